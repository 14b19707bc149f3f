# SPDX-License-Identifier: BSD-3-Clause
"""Clumps (&clump_template, &clump; doc/theory.md, section 17) in whole runs.

1. End-on impact: a dimer (two glass spheres of R = 1 mm, centres 1.4 mm apart) falling with
   its axis vertical at 0.5 m/s onto a rigid plane touches it at one point on the line
   through its centre of mass: no torque, a one-dimensional impact of the body's mass M on
   one member's Hertz contact (the law takes the body's mass, as LIGGGHTS does). Side by
   side, a single sphere of the member's radius with the density that gives it the mass M
   (the union's mass, computed here from the lens formula, pi (4R + d)(2R - d)^2 / 12 for
   the overlap) falls the same way: the dimer's rebound velocity must equal the sphere's to
   1e-9, and the restitution the pair asks for, 0.6, to 1 %. `dem --check` prints the
   template's mass, which must be the lens formula's to 1e-6.
2. An elastic, frictionless, off-centre collision of two dimers in zero gravity (e = 1): the
   kinetic energy (series.csv, translational + rotational, each body once) after the
   contact equals the energy before, to 1e-6 at dt = 1 us, with symplectic Euler and with
   velocity Verlet (the Hertz law stores and returns the energy); the state after it (the
   members' velocities and rim speeds R w) converges at second order: the slope of the log
   of its error against log dt, at dt = 2, 1, 0.5 and 0.25 us against a run at 62.5 ns, is
   above 1.8 (the integration is a symmetric splitting; a torque lever off by h v_m, taken
   after the step's drift, made it first order and its energy error 1e-4). With no force at
   the start or the end, symplectic Euler and velocity Verlet take the same positions (the
   leapfrog's, the velocities half a step apart only while forces act): their states after
   the collision agree to 1e-9 m/s. The
   momentum, sum of M (v1 + v2)/2 over the bodies (a dimer's members are symmetric about
   its centre, so their mean velocity is the body's), is kept to 1e-12 of |M v0|; and the
   bodies turn (rotational energy after the contact > 1 % of the total).
3. A pour: 216 dimers of random orientations and a sphere falling onto a plane for 50 ms:
   final.csv and series.csv byte for byte the same on 1, 2, 3 and 4 ranks; a restart from the
   checkpoint at 20 ms on 1 and on 2 ranks ends with the same final.csv; a snapshot holds
   each particle's body id and its body's orientation (unit quaternions). The probes, against
   the final checkpoint's bodies: a centre-of-mass probe weighs each clump once at its centre
   (to 1e-12 m), a count probe counts a clump's members where its centre is, and a track
   probe of a member gives that member's own position and velocity (to the bit).
4. &insert of 120 clumps of a three-sphere template (random orientations, reach from 1.5 to
   2.5 mm) among 30 spheres: the same final.csv on 1 and 2 ranks; at the start each body's
   radii and member distances are the template's times one scale, the scaled reach (that
   `dem --check` prints) within the radii asked for, and no particle overlaps another
   body's.
5. An outlet plane below 120 falling dimers: the removed and remaining counts even at every
   row of series.csv, the outflow of probes.csv the removed dimers' mass (each once), each
   dimer left whole with its centre above the plane, the same series.csv and probes.csv on
   1 and 2 ranks.
6. An oblique, elastic, frictionless impact of a dimer tilted by 45 degrees: its rebound
   velocity and spin those of rigid-body impact theory (the impulse 2 m_eff v0 at the contact
   point, 1/m_eff = 1/M + (lever)^2 / I), to 1 %.
7. A rod of four spheres dropped tilted onto a plane comes to rest flat, each member at R - d,
   d Hertz's static overlap under a quarter of the rod's weight, to 2 % of d.
8. A run with clumps is not a particle file: its final.csv and its snapshots are refused as
   &particle_file (exit 2, naming the clumps).
9. An inflow of clumps (a rate) beside an inflow of spheres (by mass): every clump whole, its
   members' ids consecutive, no more than rate x time of them; the same final.csv on 1 and 2
   ranks, and after a restart halfway.
10. Periodic along x and y: 60 dimers crossing the period about twice at 1 m/s over a
   frictionless floor, colliding: every dimer whole and rigid at the end, its centre in the
   period, the momentum along x kept to 1e-12, the same final.csv on 1, 2 and 3 ranks and
   after a restart.
usage: test_clumps.py DEM WORKDIR MPIEXEC"""
import math
import os
import random
import re
import shutil
import subprocess
import sys

import h5py
import numpy as np

from regression_util import check, check_close, finish, run_dem, run_ranks, same_file

dem, work, mpiexec = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

R, D, RHO = 1.0e-3, 1.4e-3, 2500.0
LENS = math.pi * (4 * R + D) * (2 * R - D) ** 2 / 12
MASS = RHO * (2 * 4.0 / 3.0 * math.pi * R**3 - LENS)

HEAD = """&run dt = 1e-6, t_end = {t_end}, gravity = 0, 0, {g} /
&output dir = '{name}', interval = {every}{extra} /
&material name = 'glass', density = {rho}, youngs_modulus = 5e6, poisson_ratio = 0.25 /
&material name = 'steel', rigid = .true. /
&pair materials = 'glass', 'glass', restitution = {e}, friction = {mu} /
&pair materials = 'glass', 'steel', restitution = {e}, friction = {mu} /
&clump_template name = 'dimer', material = 'glass',
    members = -{h}, 0, 0, {r},  {h}, 0, 0, {r} /
"""


def write(name, text):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    return path


def head(name, t_end, g=0.0, e=0.6, mu=0.3, every=1e-4, extra="", rho=RHO):
    return HEAD.format(name=name, t_end=t_end, g=g, e=e, mu=mu, every=every, extra=extra,
                       rho=rho, h=D / 2, r=R)


def final(name):
    return np.genfromtxt(os.path.join(work, name, "final.csv"), delimiter=",", names=True,
                         dtype=None, encoding="ascii")


# 1. end-on impact, beside a sphere of the body's mass
floor = "&wall_plane material = 'steel', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.01 /\n"
s45 = math.sqrt(0.5)
dimer = write("end_on", head("end_on", 0.004) + floor +
              f"&clump template = 'dimer', position = 0, 0, {D / 2 + R + 1e-5}, "
              f"orientation = {s45}, 0, {-s45}, 0, velocity = 0, 0, -0.5 /\n")
rho_sphere = MASS / (4.0 / 3.0 * math.pi * R**3)
sphere = write("sphere", head("sphere", 0.004) + floor +
               f"&material name = 'heavy', density = {rho_sphere!r}, youngs_modulus = 5e6, "
               "poisson_ratio = 0.25 /\n&pair materials = 'heavy', 'steel', restitution = 0.6, "
               "friction = 0.3 /\n&pair materials = 'heavy', 'heavy', restitution = 0.6, "
               f"friction = 0.3 /\n&pair materials = 'heavy', 'glass', restitution = 0.6, "
               f"friction = 0.3 /\n&particle material = 'heavy', radius = {R}, "
               f"position = 0, 0, {R + 1e-5}, velocity = 0, 0, -0.5 /\n")
r = subprocess.run([dem, "--check", dimer], cwd=work, capture_output=True, text=True)
got = re.search(r"dimer: 1 clumps of 2 spheres, mass\s+(\S+) kg", r.stdout)
check(got is not None, f"dem --check prints the template: {r.stdout} {r.stderr}")
if got:
    check_close(float(got.group(1)), MASS, 1e-5, "the dimer's mass (lens formula)")
run_dem(dem, dimer, work)
run_dem(dem, sphere, work)
fd, fs = final("end_on"), final("sphere")
if fd.size == 2 and fs.size == 1:
    vd = float(np.mean(fd["vz"]))
    vs = float(fs["vz"])
    check_close(vd, vs, 1e-9, "the end-on dimer rebounds as the sphere of its mass")
    check_close(vd / 0.5, 0.6, 0.01, "the end-on dimer's restitution")
    check(np.allclose(fd["vx"], 0, atol=1e-12) and np.allclose(fd["wy"], 0, atol=1e-9),
          f"no torque at an end-on impact: {fd}")

# 2. an elastic, frictionless, off-centre collision of two dimers, at several steps and with
# velocity Verlet
pair = ("&clump template = 'dimer', position = -0.003, 0, 0, velocity = 1, 0, 0 /\n"
        "&clump template = 'dimer', position = 0.0005, 0.0015, 0, "
        f"orientation = {s45}, 0, 0, {s45} /\n")
e0 = 0.5 * MASS * 1.0**2
gain, state = {}, {}
steps = {"collide_2": 2e-6, "collide": 1e-6, "collide_half": 5e-7, "collide_quarter": 2.5e-7,
         "collide_fine": 6.25e-8, "collide_verlet": 1e-6}
for name, dt in steps.items():
    extra = ", integrator = 'velocity_verlet'" if name == "collide_verlet" else ""
    run_dem(dem, write(name, head(name, 0.006, e=1.0, mu=0.0, every=5e-5).replace(
        "dt = 1e-6", f"dt = {dt!r}{extra}") + pair), work)
    series = np.genfromtxt(os.path.join(work, name, "series.csv"), delimiter=",", names=True)
    ek = series["kinetic_translational"] + series["kinetic_rotational"]
    check_close(ek[0], e0, 1e-12, f"{name}: the kinetic energy at the start (M v0^2 / 2)")
    check(series["contacts_pp"][-1] == 0 and max(series["contacts_pp"]) > 0,
          f"{name}: the dimers met and parted")
    check(series["kinetic_rotational"][-1] > 0.01 * e0,
          f"{name}: the off-centre collision turns them")
    gain[name] = ek[-1] / e0 - 1
    fs = final(name)
    state[name] = np.concatenate([np.ravel([fs[c] for c in ("vx", "vy", "vz")]),
                                  R * np.ravel([fs[c] for c in ("wx", "wy", "wz")])])
print("energy after the collision, relative:", gain)
check(abs(gain["collide"]) < 1e-6 and abs(gain["collide_verlet"]) < 1e-6,
      f"the kinetic energy kept by the elastic collision: {gain}")
coarse = ("collide_2", "collide", "collide_half", "collide_quarter")
error = [np.max(np.abs(state[name] - state["collide_fine"])) for name in coarse]
order = np.polyfit(np.log([steps[name] for name in coarse]), np.log(error), 1)[0]
print("the state's error against dt = 62.5 ns, at 2, 1, 0.5, 0.25 us:", error, "order", order)
check(order > 1.8, f"the state converges at second order: {order}")
check(np.max(np.abs(state["collide_verlet"] - state["collide"])) <= 1e-9,
      "velocity Verlet's state that of symplectic Euler (the same positions, as no force "
      "acts at the start or the end)")
fc = final("collide")
if fc.size == 4:
    p = np.zeros(3)
    for body in (fc[fc["id"] <= 2], fc[fc["id"] > 2]):
        p += MASS * np.array([np.mean(body[c]) for c in ("vx", "vy", "vz")])
    check(np.linalg.norm(p - [MASS * 1.0, 0, 0]) <= 1e-12 * MASS,
          f"the momentum kept: {p} against {[MASS, 0, 0]}")

# 3. a pour, on 1, 2 and 3 ranks, restarted
rng = random.Random(3)
lines = [head("pour", 0.05, g=-9.81, every=0.005, extra=", checkpoint_interval = 0.02, "
              "checkpoint_keep = 5, snapshot_interval = 0.05", rho=RHO),
         floor.replace("0.01 /", "0.1 /"),
         "&particle material = 'glass', radius = 0.0012, position = 0, 0, 0.03 /\n",
         "&probe name = 'all', kind = 'center_of_mass' /\n",
         "&probe name = 'low', kind = 'count', region = 'box', box_min = -1, -1, -1, "
         "box_max = 1, 1, 0.01 /\n",
         "&probe name = 'member', kind = 'track', id = 7 /\n"]
for i in range(6):
    for j in range(6):
        for k in range(6):
            a = rng.uniform(0, math.pi)
            u = [rng.gauss(0, 1) for _ in range(3)]
            n = math.sqrt(sum(c * c for c in u))
            q = [math.cos(a / 2)] + [math.sin(a / 2) * c / n for c in u]
            lines.append(f"&clump template = 'dimer', position = {-0.015 + 0.006 * i:.6f}, "
                         f"{-0.015 + 0.006 * j:.6f}, {0.005 + 0.005 * k:.6f}, "
                         f"orientation = {q[0]!r}, {q[1]!r}, {q[2]!r}, {q[3]!r}, "
                         f"velocity = {rng.uniform(-0.1, 0.1):.4f}, 0, 0 /\n")
text = "".join(lines)
for ranks in (1, 2, 3, 4):
    name = f"pour_{ranks}"
    case = write(name, text.replace("dir = 'pour'", f"dir = '{name}'"))
    run_ranks(mpiexec, dem, case, ranks, work)
    if ranks > 1:
        for f in ("final.csv", "series.csv"):
            same_file(os.path.join(work, "pour_1", f), os.path.join(work, name, f),
                      f"the pour on {ranks} ranks")
ckpt = os.path.join(work, "pour_1", "checkpoints", "checkpoint_000000020000.h5")
check(os.path.exists(ckpt), "the pour's checkpoint at 20 ms")
for ranks in (1, 2):
    name = f"pour_restart_{ranks}"
    case = write(name, text.replace("dir = 'pour'", f"dir = '{name}'"))
    run_ranks(mpiexec, dem, case, ranks, work, "--restart", ckpt)
    same_file(os.path.join(work, "pour_1", "final.csv"), os.path.join(work, name, "final.csv"),
              f"the pour restarted on {ranks} ranks")
# the probes against the final checkpoint's bodies: each clump once, at its centre of mass
last = sorted(f for f in os.listdir(os.path.join(work, "pour_1", "checkpoints"))
              if f.endswith(".h5"))[-1]
with h5py.File(os.path.join(work, "pour_1", "checkpoints", last), "r") as h:
    body = h["particles/body"][...]
    ids = h["particles/id"][...]
    xs = h["particles/position"][...]
    rs = h["particles/radius"][...]
    bx = h["particles/body_position"][...]
    bm = h["particles/body_mass"][...]
    vs = h["particles/velocity"][...]
if xs.shape[0] == 3:
    xs, bx, vs = xs.T, bx.T, vs.T
sphere = body == 0
lead = (body != 0) & (ids == body)
m = np.concatenate([4.0 / 3.0 * math.pi * rs[sphere] ** 3 * RHO, bm[lead]])
com = (m[:, None] * np.concatenate([xs[sphere], bx[lead]])).sum(0) / m.sum()
probes = np.genfromtxt(os.path.join(work, "pour_1", "probes.csv"), delimiter=",", names=True)
got = [float(probes[f"all_glass_{a}"][-1]) for a in "xyz"]
check(np.allclose(got, com, rtol=0, atol=1e-12),
      f"the centre-of-mass probe weighs each clump once, at its centre: {got} against {com}")
low = np.concatenate([xs[sphere][:, 2], np.repeat(bx[lead][:, 2], 2)])
check(int(probes["low_glass"][-1]) == int(np.count_nonzero(low <= 0.01)),
      "the count probe counts a clump's members where its centre of mass is")
tracked = np.flatnonzero(ids == 7)[0]
check(body[tracked] != 0 and ids[tracked] != body[tracked],
      "particle 7 is a clump's second member")
got = [float(probes[f"member_{a}"][-1]) for a in ("x", "y", "z", "vx", "vy", "vz")]
check(np.array_equal(got, np.concatenate([xs[tracked], vs[tracked]])),
      f"a track probe follows the member itself, not its body: {got}")
snaps = sorted(f for f in os.listdir(os.path.join(work, "pour_1", "snapshots"))
               if f.endswith(".h5"))
check(len(snaps) > 0, "the pour wrote snapshots")
if snaps:
    with h5py.File(os.path.join(work, "pour_1", "snapshots", snaps[-1]), "r") as h:
        body = h["particles/body"][...]
        q = h["particles/orientation"][...]
        ids = h["particles/id"][...]
    check(np.count_nonzero(body) == 432 and len(set(body[body > 0])) == 216,
          "each member's body id in the snapshot")
    check(np.allclose(np.linalg.norm(q[body > 0], axis=-1), 1, atol=1e-12),
          f"the orientations unit quaternions: shape {q.shape}")
    check(set(body[body > 0]) <= set(ids), "a body's id is one of its members' ids")

# 4. &insert of clumps: a three-sphere template at random orientations, its reach scaled
# by a uniform distribution, among spheres
tri = ("&clump_template name = 'tri', material = 'glass', members = 0, 0, 0, 0.001,  "
       "0.0012, 0, 0, 0.0009,  0, 0.0012, 0, 0.0008 /\n")
ins = (head("{name}", 0.002, g=-9.81, every=0.001) + tri + floor.replace("0.01 /", "0.1 /") +
       "&insert n = 120, template = 'tri', box_min = -0.015, -0.015, 0.002, "
       "box_max = 0.015, 0.015, 0.04, radius_min = 0.0015, radius_max = 0.0025 /\n"
       "&insert n = 30, material = 'glass', radius_min = 0.001, box_min = -0.015, -0.015, "
       "0.002, box_max = 0.015, 0.015, 0.04 /\n").replace("dt = 1e-6", "dt = 2e-6")
for ranks in (1, 2):
    name = f"insert_{ranks}"
    run_ranks(mpiexec, dem, write(name, ins.replace("{name}", name)), ranks, work)
same_file(os.path.join(work, "insert_1", "final.csv"), os.path.join(work, "insert_2",
          "final.csv"), "the inserted clumps on 2 ranks")
with h5py.File(os.path.join(work, "insert_1", "snapshots", "snapshot_000000000000.h5"),
               "r") as h:
    x = h["particles/position"][...]
    rad = h["particles/radius"][...]
    body = h["particles/body"][...]
    ids = h["particles/id"][...]
if x.shape[0] == 3:
    x = x.T
members = np.array([[0, 0, 0], [0.0012, 0, 0], [0, 0.0012, 0]])
radii = np.array([0.001, 0.0009, 0.0008])
scales = []
for b in sorted(set(body[body > 0])):
    k = np.argsort(ids[body == b])
    xb, rb = x[body == b][k], rad[body == b][k]
    s = rb[0] / radii[0]
    scales.append(s)
    check(np.allclose(rb, s * radii, rtol=1e-12), f"body {b}: its radii the template's scaled")
    d = [np.linalg.norm(xb[i] - xb[j]) for i, j in ((0, 1), (0, 2), (1, 2))]
    want = [s * np.linalg.norm(members[i] - members[j]) for i, j in ((0, 1), (0, 2), (1, 2))]
    check(np.allclose(d, want, rtol=1e-12), f"body {b}: its members where the template has them")
check(len(scales) == 120, f"120 clumps inserted: {len(scales)}")
r = subprocess.run([dem, "--check", os.path.join(work, "insert_1.nml")], cwd=work,
                   capture_output=True, text=True)
got = re.search(r"tri: 120 clumps of 3 spheres.* reach\s+(\S+) m", r.stdout)
check(got is not None, f"dem --check prints the template's reach: {r.stdout}")
if got:
    reach = float(got.group(1))
    check(0.0015 * (1 - 1e-3) <= min(scales) * reach and max(scales) * reach <= 0.0025 *
          (1 + 1e-3), f"the reach of the clumps within the radii asked for: {min(scales)}, "
          f"{max(scales)} times {reach}")
gap = np.inf
for i in range(len(x)):
    other = (body != body[i]) | (body == 0)
    other[i] = False
    dist = np.linalg.norm(x[other] - x[i], axis=1) - rad[other] - rad[i]
    gap = min(gap, dist.min())
check(gap >= 0, f"no particle overlaps another body's at the start: smallest gap {gap}")

# 5. an outlet takes clumps out whole: 120 dimers falling through a plane
out = (head("{name}", 0.04, g=-9.81, every=0.005) +
       "&insert n = 120, template = 'dimer', box_min = -0.01, -0.01, 0.012, "
       "box_max = 0.01, 0.01, 0.05 /\n"
       "&outlet region = 'plane', point = 0, 0, 0.01, normal = 0, 0, -1 /\n")
for ranks in (1, 2):
    name = f"outlet_{ranks}"
    run_ranks(mpiexec, dem, write(name, out.replace("{name}", name)), ranks, work)
same_file(os.path.join(work, "outlet_1", "series.csv"), os.path.join(work, "outlet_2",
          "series.csv"), "the outlet on 2 ranks")
series = np.genfromtxt(os.path.join(work, "outlet_1", "series.csv"), delimiter=",", names=True)
check(series["removed"][-1] > 10 and series["particles"][-1] > 10,
      f"some clumps left, some stayed: {series['removed'][-1]}, {series['particles'][-1]}")
check(np.all(series["removed"] % 2 == 0) and np.all(series["particles"] % 2 == 0),
      "the removed and the remaining particles: whole dimers at every row")
same_file(os.path.join(work, "outlet_1", "probes.csv"), os.path.join(work, "outlet_2",
          "probes.csv"), "the outflow on 2 ranks")
flow = np.genfromtxt(os.path.join(work, "outlet_1", "probes.csv"), delimiter=",", names=True)
check(np.allclose(flow["outflow_glass"], series["removed"] / 2 * MASS, rtol=1e-5, atol=0),
      "the outflow: the removed dimers' mass (lens formula), each dimer once, at every row")
fo = final("outlet_1")
left = {}
for row in np.atleast_1d(fo):
    left.setdefault(int(row["id"] - 1) // 2, []).append(row)
check(all(len(v) == 2 for v in left.values()), "every dimer left has both its members")
check(all(0.5 * (v[0]["z"] + v[1]["z"]) > 0.01 - 1e-9 for v in left.values()),
      "the dimers left have their centre above the outlet's plane")

# 6. an oblique impact against rigid-body impact theory: a dimer tilted by 45 degrees about y,
# stiff (E = 500 MPa: a contact of about 40 us, in which it turns by less than 0.01 rad),
# elastic (e = 1) and frictionless, falling at v0 = 0.5 m/s onto a plane. Its lower member
# touches at the contact point c - X = r = (h cos t, 0, -h sin t - R); the impulse J along z
# with 1/m_eff = 1/M + (h cos t)^2 / I_t (I_t the transverse principal moment, y a principal
# axis) and J = 2 m_eff v0 gives V_z = -v0 + J/M, w_y = -J h cos t / I_t, V_x = 0.
t = math.pi / 4
oblique = (head("oblique", 0.00025, e=1.0, mu=0.0, every=5e-5).replace("dt = 1e-6", "dt = 2e-8")
           .replace("youngs_modulus = 5e6", "youngs_modulus = 5e8") + floor +
           f"&clump template = 'dimer', position = 0, 0, {D / 2 * math.sin(t) + R + 1e-6}, "
           f"orientation = {math.cos(t / 2)!r}, 0, {math.sin(t / 2)!r}, 0, "
           "velocity = 0, 0, -0.5 /\n")
r = subprocess.run([dem, "--check", write("oblique", oblique)], cwd=work, capture_output=True,
                   text=True)
got = re.search(r"principal moments\s+(\S+)\s+(\S+)\s+(\S+) kg m\^2", r.stdout)
check(got is not None, f"dem --check prints the principal moments: {r.stdout}")
run_dem(dem, os.path.join(work, "oblique.nml"), work)
fob = final("oblique")
series = np.genfromtxt(os.path.join(work, "oblique", "series.csv"), delimiter=",", names=True)
check(series["contacts_pw"][-1] == 0 and max(series["contacts_pw"]) > 0,
      "the oblique dimer touched the plane and left it")
if got and fob.size == 2:
    i_t = float(got.group(2))
    lever = D / 2 * math.cos(t)
    m_eff = 1.0 / (1.0 / MASS + lever**2 / i_t)
    j = 2 * m_eff * 0.5
    vz, wy = float(np.mean(fob["vz"])), float(np.mean(fob["wy"]))
    print(f"oblique impact: V_z {vz:.6g} (theory {-0.5 + j / MASS:.6g}), w_y {wy:.6g} "
          f"(theory {-j * lever / i_t:.6g})")
    check_close(vz, -0.5 + j / MASS, 0.01, "the oblique dimer's rebound V_z (impact theory)")
    check_close(wy, -j * lever / i_t, 0.01, "its spin w_y (impact theory)")
    check(abs(float(np.mean(fob["vx"]))) < 1e-9 and abs(float(np.mean(fob["wx"]))) < 1e-9,
          "no sideways motion or other spin without friction")

# 7. a rod of four spheres resting on a plane: dropped tilted by 10 degrees, it comes to rest
# lying flat, each member carrying a quarter of the weight: its centre at R - d, d Hertz's
# static overlap under M g / 4, (3 F / (4 E* sqrt(R)))^(2/3), E* = E / (1 - nu^2) (a rigid
# plane)
rod_pos = "-0.0027, 0, 0, 0.001,  -0.0009, 0, 0, 0.001,  0.0009, 0, 0, 0.001,  0.0027, 0, 0, 0.001"
rod = (head("rod", 0.4, g=-9.81, e=0.3, mu=0.5, every=0.05) + floor +
       f"&clump_template name = 'rod', material = 'glass', members = {rod_pos} /\n"
       f"&clump template = 'rod', position = 0, 0, {0.0027 * math.sin(0.1745) + R + 5e-4}, "
       f"orientation = {math.cos(0.0873)!r}, 0, {math.sin(0.0873)!r}, 0 /\n")
r = subprocess.run([dem, "--check", write("rod", rod)], cwd=work, capture_output=True, text=True)
got = re.search(r"rod: 1 clumps of 4 spheres, mass\s+(\S+) kg", r.stdout)
check(got is not None, f"dem --check prints the rod: {r.stdout}")
run_dem(dem, os.path.join(work, "rod.nml"), work)
frod = final("rod")
if got and frod.size == 4:
    m_rod = float(got.group(1))
    e_star = 5e6 / (1 - 0.25**2)
    d = (3 * m_rod * 9.81 / 4 / (4 * e_star * math.sqrt(R))) ** (2.0 / 3.0)
    print(f"rod at rest: z {sorted(frod['z'])}, expected {R - d:.9g}")
    check(np.allclose(frod["z"], R - d, rtol=0, atol=0.02 * d),
          f"the rod lies flat, each member at R - d: {frod['z']} against {R - d}")
    check(np.max(np.abs(frod["vz"])) < 1e-4 and np.max(np.abs(frod["wy"])) < 1e-2,
          "the rod at rest")

# 8. a run with clumps is not a particle file: its final.csv (a column 'body') and its
# snapshots (/particles/body) are refused as &particle_file, with exit 2
for name, source in (("from_final", os.path.join(work, "pour_1", "final.csv")),
                     ("from_snapshot", os.path.join(work, "pour_1", "snapshots",
                                                    "snapshot_000000000000.h5"))):
    case = write(name, head(name, 0.001) + f"&particle_file file = '{source}' /\n")
    r = subprocess.run([dem, case], cwd=work, capture_output=True, text=True)
    check(r.returncode == 2 and "clumps" in r.stderr and "&particle_file" in r.stderr,
          f"{name}: refused, naming the clumps: exit {r.returncode}, {r.stderr}")

# 9. inflow of clumps during the run (a rate), among an inflow of spheres by mass: whole
# clumps only, at most rate x time of them, the same on 1 and 2 ranks, and a restart from
# the checkpoint halfway ends the same
flow = (head("{name}", 0.06, g=-9.81, every=0.01, extra=", checkpoint_interval = 0.03, "
             "checkpoint_keep = 5").replace("dt = 1e-6", "dt = 2e-6") + tri +
        floor.replace("0.01 /", "0.1 /") +
        "&insert template = 'tri', box_min = -0.01, -0.01, 0.02, box_max = 0.01, 0.01, 0.03, "
        "rate = 2000, velocity = 0, 0, -0.5 /\n"
        "&insert material = 'glass', radius_min = 0.001, box_min = -0.01, -0.01, 0.02, "
        "box_max = 0.01, 0.01, 0.03, mass_rate = 0.01 /\n")
for ranks in (1, 2):
    name = f"inflow_{ranks}"
    run_ranks(mpiexec, dem, write(name, flow.replace("{name}", name)), ranks, work)
same_file(os.path.join(work, "inflow_1", "final.csv"), os.path.join(work, "inflow_2",
          "final.csv"), "the inflow of clumps on 2 ranks")
ckpt = os.path.join(work, "inflow_1", "checkpoints", "checkpoint_000000015000.h5")
run_ranks(mpiexec, dem, write("inflow_restart", flow.replace("{name}", "inflow_restart")), 2,
          work, "--restart", ckpt)
same_file(os.path.join(work, "inflow_1", "final.csv"), os.path.join(work, "inflow_restart",
          "final.csv"), "the inflow of clumps restarted halfway on 2 ranks")
ff = final("inflow_1")
members = {}
for row in np.atleast_1d(ff):
    if row["body"] > 0:
        members.setdefault(int(row["body"]), []).append(int(row["id"]))
check(all(sorted(v) == list(range(b, b + 3)) for b, v in members.items()),
      "every clump of the inflow whole, its members' ids consecutive from the body's")
check(60 <= len(members) <= 2000 * 0.06 + 1,
      f"the clumps inserted: {len(members)}, at most rate x time = 120")
check(np.count_nonzero(ff["body"] == 0) > 10, "the spheres' inflow beside them")

# 10. periodic along x and y: 60 dimers moving at 1 m/s along x above a frictionless floor,
# crossing the period (20 mm) about twice, colliding with each other: every dimer whole at the
# end, its centre inside the period, the momentum along x kept (to 1e-12), the same final.csv
# on 1, 2 and 3 ranks and after a restart
per = (head("{name}", 0.04, g=-9.81, every=0.01, extra=", checkpoint_interval = 0.02, "
            "checkpoint_keep = 5").replace("dt = 1e-6", "dt = 2e-6")
       .replace("'glass', 'steel', restitution = 0.6, friction = 0.3",
                "'glass', 'steel', restitution = 0.6, friction = 0") +
       floor.replace("0.01 /", "0.1 /") +
       "&periodic axis = 'x', low = -0.01, high = 0.01 /\n"
       "&periodic axis = 'y', low = -0.01, high = 0.01 /\n"
       "&insert n = 60, template = 'dimer', box_min = -0.01, -0.01, 0.001, "
       "box_max = 0.01, 0.01, 0.02, velocity = 1, 0, 0, velocity_spread = 0.2, 0.2, 0 /\n")
for ranks in (1, 2, 3):
    name = f"periodic_{ranks}"
    run_ranks(mpiexec, dem, write(name, per.replace("{name}", name)), ranks, work)
    if ranks > 1:
        same_file(os.path.join(work, "periodic_1", "final.csv"),
                  os.path.join(work, name, "final.csv"), f"the periodic clumps on {ranks} ranks")
run_ranks(mpiexec, dem, write("periodic_restart", per.replace("{name}", "periodic_restart")),
          2, work, "--restart", os.path.join(work, "periodic_1", "checkpoints",
                                             "checkpoint_000000010000.h5"))
same_file(os.path.join(work, "periodic_1", "final.csv"),
          os.path.join(work, "periodic_restart", "final.csv"), "the periodic clumps restarted")
fp = final("periodic_1")
pairs = {}
for row in np.atleast_1d(fp):
    pairs.setdefault(int(row["body"]), []).append(row)
check(len(pairs) == 60 and all(len(v) == 2 for v in pairs.values()), "60 dimers, whole")
gaps = [np.linalg.norm([v[0][a] - v[1][a] for a in "xyz"]) for v in pairs.values()]
check(np.allclose(gaps, D, rtol=1e-9), f"every dimer rigid across the period: {min(gaps)}, "
      f"{max(gaps)}")
cx = np.array([0.5 * (v[0]["x"] + v[1]["x"]) for v in pairs.values()])
check(np.all((cx >= -0.01 - 1e-3) & (cx < 0.01 + 1e-3)),
      "the dimers' centres inside the period (within a step's travel of it)")
with h5py.File(os.path.join(work, "periodic_1", "snapshots", "snapshot_000000000000.h5"),
               "r") as h:
    v0 = h["particles/velocity"][...]
v0 = v0.T if v0.shape[0] == 3 else v0
p0 = MASS * v0[:, 0].sum() / 2                      # each dimer's V_x, the mean of its two
p1 = MASS * float(np.sum(fp["vx"])) / 2
check(abs(p1 - p0) <= 1e-12 * MASS * 60, f"the momentum along x kept: {p0} -> {p1}")
series = np.genfromtxt(os.path.join(work, "periodic_1", "series.csv"), delimiter=",", names=True)
check(max(series["contacts_pp"]) > 0, "the dimers collided")
r0 = subprocess.run([dem, "--check", os.path.join(work, "periodic_1.nml")], cwd=work,
                    capture_output=True, text=True)
check(r0.returncode == 0, f"--check of the periodic case: {r0.stderr}")

finish()
