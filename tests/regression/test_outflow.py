# SPDX-License-Identifier: BSD-3-Clause
"""The mass that leaves through the outlets (probes.csv's outflow_<material> columns) and
cylinder probe regions.

Spheres of two materials and of spread sizes (a lognormal and a discrete distribution) fall
out of a bottomless box through an outlet plane below it; the run ends while some are still
in the box.
1. In every row, outflow_<material> is the mass of the particles of that material that have
   left: those of the snapshot at t = 0 missing from the row's snapshot, their masses
   4/3 pi r^3 rho computed here (to 1e-12); the last row's, those missing from final.csv;
   it never falls, and the last row's is not zero for either material.
2. The same bits on 1 and 2 ranks (probes.csv and final.csv byte for byte), and a restart
   from a checkpoint in the middle of the discharge gives the rows after it byte for byte (the
   cumulative sums are carried exactly), on 2 ranks.
3. A cylinder probe (tilted axis, a height range) counts, in every row, the particles of each
   material whose centre lies in the cylinder, counted here from the row's snapshot.
(Bad input of the new keys: test_input_errors.py.)
usage: test_outflow.py DEM WORKDIR MPIEXEC"""
import filecmp
import math
import os
import shutil
import sys

import h5py
import numpy as np

from regression_util import check, finish, run_dem, run_ranks

dem, work, mpiexec = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
RHO = {"light": 1200.0, "heavy": 7800.0}
BASE, AXIS, RADIUS, HEIGHT = np.array([0.01, -0.005, 0.02]), np.array([0.3, 0.2, 1.0]), 0.03, 0.1
CASE = f"""&run dt = 2.5e-5, t_end = 0.2, gravity = 0, 0, -9.81 /
&output dir = '{{dir}}', interval = 0.01, snapshot_interval = 0.01,
        checkpoint_interval = 0.1 /
&material name = 'light', density = {RHO['light']}, youngs_modulus = 1e7, poisson_ratio = 0.2 /
&material name = 'heavy', density = {RHO['heavy']}, youngs_modulus = 1e7, poisson_ratio = 0.2 /
&material name = 'wall', rigid = .true. /
&pair materials = 'light', 'light', restitution = 0.3, friction = 0.3 /
&pair materials = 'heavy', 'heavy', restitution = 0.3, friction = 0.3 /
&pair materials = 'light', 'heavy', restitution = 0.3, friction = 0.3 /
&pair materials = 'light', 'wall', restitution = 0.3, friction = 0.3 /
&pair materials = 'heavy', 'wall', restitution = 0.3, friction = 0.3 /
&wall_plane material = 'wall', point = -0.05, 0, 0.1, normal = 1, 0, 0, half_width = 0.2 /
&wall_plane material = 'wall', point = 0.05, 0, 0.1, normal = -1, 0, 0, half_width = 0.2 /
&wall_plane material = 'wall', point = 0, -0.05, 0.1, normal = 0, 1, 0, half_width = 0.2 /
&wall_plane material = 'wall', point = 0, 0.05, 0.1, normal = 0, -1, 0, half_width = 0.2 /
&insert n = 120, material = 'light', radius_distribution = 'lognormal', radius_mean = 0.004,
        radius_sd = 0.001, radius_min = 0.0025, radius_max = 0.006, seed = 5,
        box_min = -0.05, -0.05, 0.0, box_max = 0.05, 0.05, 0.12 /
&insert n = 80, material = 'heavy', radius_distribution = 'discrete', radii = 0.003, 0.005,
        fractions = 0.5, 0.5, seed = 6,
        box_min = -0.05, -0.05, 0.12, box_max = 0.05, 0.05, 0.25 /
&outlet region = 'plane', point = 0, 0, -0.02, normal = 0, 0, -1 /
&probe name = 'cyl', kind = 'count', region = 'cylinder', cylinder_base = {BASE[0]}, {BASE[1]},
        {BASE[2]}, cylinder_axis = {AXIS[0]}, {AXIS[1]}, {AXIS[2]}, cylinder_radius = {RADIUS},
        cylinder_height = {HEIGHT} /
"""


def write(name, text=None):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text if text is not None else CASE.format(dir=os.path.join(work, name)))
    return path


def snapshot(name, step):
    with h5py.File(os.path.join(work, name, "snapshots", f"snapshot_{step:012d}.h5")) as f:
        names = [m.decode().strip() for m in f["materials/name"][()]]
        p = {k: f["particles"][k][()] for k in ("id", "material", "radius", "position")}
    p["name"] = np.array([names[k - 1] for k in p["material"]])
    if p["position"].shape[0] == 3 and len(p["id"]) != 3:
        p["position"] = p["position"].T
    return p


def masses(p, ids, mat):
    sel = np.isin(p["id"], ids) & (p["name"] == mat)
    return math.fsum(4.0 / 3.0 * math.pi * p["radius"][sel] ** 3 * RHO[mat])


run_dem(dem, write("one"), work)
rows = np.genfromtxt(os.path.join(work, "one", "probes.csv"), delimiter=",", names=True)
first = snapshot("one", 0)
check(len(first["id"]) == 200, f"200 particles at the start ({len(first['id'])})")
a = AXIS / np.linalg.norm(AXIS)
for row in rows:
    step = int(row["step"])
    p = snapshot("one", step)
    gone = np.setdiff1d(first["id"], p["id"])
    for mat in RHO:
        want = masses(first, gone, mat)
        check(abs(row[f"outflow_{mat}"] - want) <= 1e-12 * max(want, 1e-30),
              f"step {step}: outflow of {mat} {row[f'outflow_{mat}']!r} vs {want!r}")
        d = p["position"] - BASE
        h = d @ a
        r2 = ((d - h[:, None] * a) ** 2).sum(axis=1)
        inside = (h >= 0) & (h <= HEIGHT) & (r2 <= RADIUS ** 2) & (p["name"] == mat)
        check(row[f"cyl_{mat}"] == np.count_nonzero(inside),
              f"step {step}: cylinder count of {mat} {row[f'cyl_{mat}']} vs "
              f"{np.count_nonzero(inside)}")
final = np.genfromtxt(os.path.join(work, "one", "final.csv"), delimiter=",", names=True)
gone = np.setdiff1d(first["id"], final["id"].astype(np.int64))
for mat in RHO:
    col = rows[f"outflow_{mat}"]
    check(np.all(np.diff(col) >= 0) and col[-1] > 0, f"outflow of {mat} rises, not zero at the end")
    want = masses(first, gone, mat)
    check(abs(col[-1] - want) <= 1e-12 * want, f"final outflow of {mat}: {col[-1]!r} vs {want!r}")
check(0 < len(gone) < 200, f"some particles left, some stayed ({len(gone)} left)")
check(np.count_nonzero(rows["cyl_light"] + rows["cyl_heavy"]) > 5, "the cylinder sees particles")

# 2. the same bits on 2 ranks, and across a restart
run_ranks(mpiexec, dem, write("two"), 2, work)
for f in ("probes.csv", "final.csv"):
    check(filecmp.cmp(os.path.join(work, "one", f), os.path.join(work, "two", f), shallow=False),
          f"{f}: the same bytes on 1 and 2 ranks")
ckpt = os.path.join(work, "one", "checkpoints", "checkpoint_000000004000.h5")
check(os.path.exists(ckpt), "a checkpoint at t = 0.1 s")
with h5py.File(ckpt) as f:
    check("state/outflow" in f, "the checkpoint holds the outflow")
run_ranks(mpiexec, dem, write("again"), 2, work, "--restart", ckpt)
with open(os.path.join(work, "one", "probes.csv")) as f:
    whole = f.read().splitlines()
with open(os.path.join(work, "again", "probes.csv")) as f:
    again = f.read().splitlines()
check(len(again) > 2 and again[1:] == whole[len(whole) - len(again) + 1:],
      "probes.csv after a restart at t = 0.1 s on 2 ranks: the rows after it, byte for byte")
check(float(again[1].split(",")[-2]) > 0, "the restart's first row carries the outflow before it")

finish()
