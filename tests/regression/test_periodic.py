# SPDX-License-Identifier: BSD-3-Clause
"""Periodic boundaries (doc/user/input.md, &periodic; doc/theory.md, section 16):

1. A granular gas periodic along x, y and z (125 spheres on a jittered lattice with random
   velocities, no walls, no gravity) and the same gas copied 2 x 2 x 2 times into a box of
   twice the period: the copies move as the original, shifted by the period (within 1e-10 m
   after 2 ms, while round-off grows by chaos from 1e-16 m; a missed contact through a face
   would part them by the spheres' speed times the time). Over 10 ms the total momentum is
   conserved to round-off (the forces of a pair that meets through a face are exact
   negatives), no two spheres overlap by more than a contact's depth (minimum image), and
   every sphere is inside the period to half the skin.
2. The gas on 1, 2, 3 and 4 ranks: final.csv and series.csv identical byte for byte.
3. The chute example (periodic along x and y, a rough base of wall triangles) for 0.05 s on
   1, 2 and 3 ranks: the same files byte for byte, and the same checkpoint datasets (each
   pair of the history once, also on one rank, where a pair through a face is held from
   both sides); a checkpoint written on 3 ranks,
   restarted on 2, ends as the uninterrupted run on 1.
4. Insertion through a face: spheres inserted (before the run, and by an inflow during it) in
   a region along the low face, with given spheres reaching across the high face: no two
   overlap through the face (minimum image), and none ever touches (at rest without gravity,
   the kinetic energy stays 0), on 1 and 2 ranks alike.
5. Bad &periodic groups: a period shorter than 2 (2 R + skin), an axis given twice, an
   unknown axis, high <= low; each error names the file, the group and the key.
usage: test_periodic.py DEM WORKDIR MPIEXEC"""
import os
import re
import shutil
import sys

import h5py
import numpy as np

from regression_util import ROOT, check, finish, run_ranks, same_file

dem, work, mpiexec = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
L, R, SKIN = 0.0075, 0.0005, 0.0002          # the gas: period, radius, skin (0.4 R) [m]

GAS = """&run dt = 1e-6, t_end = {t_end}, gravity = 0, 0, 0, progress_interval = 0 /
&output dir = '{out}', interval = 0.001 /
&material name = 'glass', density = 2500.0, youngs_modulus = 1.0e8, poisson_ratio = 0.3 /
&pair materials = 'glass', 'glass', restitution = 0.9, friction = 0.3 /
&periodic axis = 'x', low = 0.0, high = {L} /
&periodic axis = 'y', low = 0.0, high = {L} /
&periodic axis = 'z', low = 0.0, high = {L} /
&particle_file file = '{csv}' /
"""


def run(case, ranks=1, *args, code=0):
    return run_ranks(mpiexec, dem, case, ranks, work, *args, code=code)


def write_gas(path, x, v):
    with open(path, "w") as f:
        f.write("id,material,radius,x,y,z,vx,vy,vz\n")
        for k, (p, u) in enumerate(zip(x, v)):
            f.write(f"{k + 1},glass,{R!r},{p[0]!r},{p[1]!r},{p[2]!r},{u[0]!r},{u[1]!r},"
                    f"{u[2]!r}\n")


def gas_case(name, t_end, period, csv):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(GAS.format(t_end=t_end, out=os.path.join(work, name), L=period, csv=csv))
    return path


def final(name):
    a = np.genfromtxt(os.path.join(work, name, "final.csv"), delimiter=",", names=True)
    return a, np.c_[a["x"], a["y"], a["z"]], np.c_[a["vx"], a["vy"], a["vz"]]


def same_state(a, b):
    """Every dataset of /particles and /state of the first checkpoint of runs a and b is the
    same (the /case group names the run's own folder)."""
    name = sorted(c for c in os.listdir(os.path.join(a, "checkpoints")) if c.endswith(".h5"))[0]
    with h5py.File(os.path.join(a, "checkpoints", name)) as fa, \
            h5py.File(os.path.join(b, "checkpoints", name)) as fb:
        keys = [f"{g}/{k}" for g in ("particles", "state") for k in fa[g]]
        return (keys == [f"{g}/{k}" for g in ("particles", "state") for k in fb[g]] and
                all(np.array_equal(fa[k][()], fb[k][()]) for k in keys))


# 1. the gas, and its 2 x 2 x 2 copy in twice the period
rng = np.random.default_rng(5)
g = (np.arange(5) + 0.5) * (L / 5)
x0 = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T
x0 += rng.uniform(-0.2e-3, 0.2e-3, x0.shape)
v0 = rng.normal(0.0, 1.0, x0.shape)
v0 -= v0.mean(axis=0)
write_gas(os.path.join(work, "gas.csv"), x0, v0)
shifts = np.array([[i, j, k] for i in range(2) for j in range(2) for k in range(2)]) * L
write_gas(os.path.join(work, "gas8.csv"), np.vstack([x0 + s for s in shifts]),
          np.vstack([v0] * 8))
run(gas_case("copy1", 0.002, L, "gas.csv"))
run(gas_case("copy8", 0.002, 2 * L, "gas8.csv"))
_, xa, _ = final("copy1")
_, xb, _ = final("copy8")
n = len(xa)
apart = 0.0
for c in range(8):
    d = xb[c * n:(c + 1) * n] - xa
    d -= L * np.round(d / L)
    apart = max(apart, np.abs(d).max())
moved = np.abs(np.genfromtxt(os.path.join(work, "copy1", "final.csv"), delimiter=",",
                             names=True)["x"] - x0[:, 0]).max()
check(apart < 1e-10, f"the 8 copies in twice the period follow the gas: {apart:.3g} m apart")
check(moved > 1e-4, f"the gas moved ({moved:.3g} m)")

gas = gas_case("gas_1", 0.01, L, "gas.csv")
run(gas)
a, x, v = final("gas_1")
p0, p1 = v0.sum(axis=0), v.sum(axis=0)               # equal masses: momentum / m
check(np.abs(p1 - p0).max() < 1e-12 * np.abs(v0).sum(),
      f"momentum conserved: {p0} -> {p1} (m/s, sum over the spheres)")
d = x[:, None, :] - x[None, :, :]
through = np.abs(np.round(d / L)).max(axis=-1) > 0
d -= L * np.round(d / L)
dist = np.sqrt((d**2).sum(axis=-1))
np.fill_diagonal(dist, 1.0)
check((2 * R - dist).max() < 0.05 * R, f"no deep overlap: {(2 * R - dist).max():.3g} m")
check(np.all(x > -SKIN / 2) and np.all(x < L + SKIN / 2),
      f"inside the period to half the skin: {x.min():.3g} .. {x.max():.3g} m")
print(f"gas: copies {apart:.2g} m apart after 2 ms; momentum drift "
      f"{np.abs(p1 - p0).max():.2g} m/s; {int((through & (dist < 2 * R + SKIN)).sum() // 2)} "
      f"pairs within reach through a face at 10 ms")

# 2. the gas on 2, 3, 4 ranks
for ranks in (2, 3, 4):
    name = f"gas_{ranks}"
    with open(gas) as f:
        text = f.read().replace(os.path.join(work, "gas_1"), os.path.join(work, name))
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    run(path, ranks)
    for f in ("final.csv", "series.csv"):
        same_file(os.path.join(work, "gas_1", f), os.path.join(work, name, f),
                  f"gas on {ranks} ranks")

# 3. the chute example for 0.05 s on 1..3 ranks, and a restart from 3 ranks on 2
with open(os.path.join(ROOT, "examples", "chute", "chute.nml")) as f:
    chute = f.read()
chute = chute.replace("'base.stl'", repr(os.path.join(ROOT, "examples", "chute", "base.stl")))
chute = re.sub(r"t_end = [0-9.eE+-]+", "t_end = 0.05", chute)
chute = re.sub(r"&output [^/]*/", "&output dir = '@OUT@', interval = 0.01, "
               "checkpoint_interval = 0.02 /", chute)
for ranks in (1, 2, 3):
    path = os.path.join(work, f"chute_{ranks}.nml")
    with open(path, "w") as f:
        f.write(chute.replace("@OUT@", os.path.join(work, f"chute_{ranks}")))
    run(path, ranks)
    if ranks > 1:
        for f in ("final.csv", "series.csv"):
            same_file(os.path.join(work, "chute_1", f), os.path.join(work, f"chute_{ranks}", f),
                      f"chute on {ranks} ranks")
        check(same_state(os.path.join(work, "chute_1"), os.path.join(work, f"chute_{ranks}")),
              f"chute on {ranks} ranks: the checkpoints' particles and state (pairs once each)")
d = os.path.join(work, "chute_restart")
shutil.copytree(os.path.join(work, "chute_3"), d)
ck = sorted(c for c in os.listdir(os.path.join(d, "checkpoints")) if c.endswith(".h5"))[0]
path = os.path.join(work, "chute_restart.nml")
with open(path, "w") as f:
    f.write(chute.replace("@OUT@", d))
run(path, 2, "--restart", os.path.join(d, "checkpoints", ck))
for f in ("final.csv", "series.csv"):
    same_file(os.path.join(work, "chute_1", f), os.path.join(d, f),
              "chute: checkpoint on 3 ranks, restarted on 2")

# 4. insertion clear of the images: a layer of spheres across the high x face (centres half a
# radius inside it), spheres inserted, and an inflow, in the five radii along the low face
layer = "".join(f"&particle id = {k + 1}, material = 'glass', radius = {R}, position = "
                f"{L - R / 2}, {0.4e-3 + 1.1e-3 * (k % 6)}, {0.4e-3 + 1.1e-3 * (k // 6)} /\n"
                for k in range(36))
INSERTED = GAS.replace("&particle_file file = '{csv}' /\n", layer +
                       "&insert n = 20, material = 'glass', radius_min = {R}, radius_max = {R}, "
                       "region = 'box', box_min = 0, 0, 0, box_max = 2.5e-3, {L}, {L}, seed = 3 /\n"
                       "&insert material = 'glass', radius_min = {R}, radius_max = {R}, "
                       "rate = 2e5, start = 0, end = 1e-4, insert_every = 10, region = 'box', box_min = 0, 0, 0, "
                       "box_max = 2.5e-3, {L}, {L}, seed = 4 /\n")
for ranks in (1, 2):
    name = f"inserted_{ranks}"
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(INSERTED.format(t_end=2e-4, out=os.path.join(work, name), L=L, R=R)
                .replace("interval = 0.001", "interval = 1e-5"))
    run(path, ranks)
    a, x, _ = final(name)
    d = x[:, None, :] - x[None, :, :]
    d -= L * np.round(d / L)
    dist = np.sqrt((d**2).sum(axis=-1))
    np.fill_diagonal(dist, 1.0)
    check(len(a) == 36 + 20 + 20, f"inserted on {ranks} ranks: 76 spheres ({len(a)})")
    check(dist.min() >= 2 * R * (1 - 1e-9), f"inserted on {ranks} ranks: no two overlap "
          f"through the face (closest {dist.min() / (2 * R):.6f} diameters)")
    series = np.genfromtxt(os.path.join(work, name, "series.csv"), delimiter=",", names=True)
    check(np.all(series["kinetic_translational"] == 0.0), f"inserted on {ranks} ranks: "
          "nothing ever touched (the kinetic energy is 0 in every row: all at rest, no gravity)")
same_file(os.path.join(work, "inserted_1", "final.csv"),
          os.path.join(work, "inserted_2", "final.csv"), "inserted on 2 ranks")

# 5. bad &periodic groups
BAD = [
    ("&periodic axis = 'x', low = 0.0, high = 0.002 /", r"&periodic: key 'high': the period "
     r"along x, 2\.000E-03 m, is shorter than 2 \(2 R \+ skin\) = 2\.400E-03 m"),
    ("&periodic axis = 'x', low = 0.0, high = 0.01 /\n&periodic axis = 'x', low = 0, "
     "high = 0.02 /", r"&periodic: key 'axis': axis x is periodic in an earlier"),
    ("&periodic axis = 'w', low = 0.0, high = 0.01 /", r"&periodic: key 'axis': 'w' is not "
     r"known \(accepted: x, y, z\)"),
    ("&periodic axis = 'y', low = 0.01, high = 0.01 /", r"&periodic: key 'high': must exceed "
     r"low"),
    ("&periodic axis = 'z', high = 0.01 /", r"&periodic: key 'low' is required"),
]
for k, (group, message) in enumerate(BAD):
    with open(gas) as f:
        text = re.sub(r"&periodic[^/]*/\n", "", f.read())
    path = os.path.join(work, f"bad_{k}.nml")
    with open(path, "w") as f:
        f.write(text.replace("&particle_file", group + "\n&particle_file"))
    r = run(path, 1, code=2)
    check(re.search(re.escape(path) + r":\d+: " + message, r.stderr) is not None and
          "(doc/user/input.md, &periodic)" in r.stderr,
          f"bad &periodic {k}: the error names the file, group and key: {r.stderr.strip()}")

finish()
