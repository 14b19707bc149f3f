# SPDX-License-Identifier: BSD-3-Clause
"""Probes (&probe) against the same quantities computed here from the snapshots written at
the same steps.

Two materials fall and collide in the box case of checkpoint_util.py (particles of 'soft'
and of a second material 'hard', onto the moving floor), with a snapshot at every output row:
1. count probes of a region and of its complement give, per material, the numbers of
   particles whose centre is inside, and their sum is the particle count of series.csv;
2. a center_of_mass probe gives the mass-weighted mean position of each material
   (m = 4/3 pi R^3 rho computed here; to 1e-12);
3. a track probe gives the tracked particle's position, velocity and angular velocity, bit
   for bit;
4. a histogram probe written once, at the first row at or after its time, holds the counts
   of the radial, angular and vertical velocity components about its vertical axis, binned
   here from that snapshot (with the rows below and above the range), and each component's
   counts add up to the particles in its region;
5. bad &probe input is refused naming the file, the group and the key.
usage: test_probes.py DEM WORKDIR"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

from regression_util import check, finish
import checkpoint_util as cu

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
RHO = {"soft": 2500.0, "hard": 3000.0}
HIST_T, AXIS = 0.15, (0.01, -0.02)
SECOND = """&material name = 'hard', density = 3000, youngs_modulus = 2e7, poisson_ratio = 0.25 /
&pair materials = 'hard', 'hard', restitution = 0.5, friction = 0.4 /
&pair materials = 'soft', 'hard', restitution = 0.4, friction = 0.2 /
&pair materials = 'hard', 'wall', restitution = 0.4, friction = 0.2 /
&insert n = 100, material = 'hard', radius_min = 0.003, radius_max = 0.0035, region = 'box',
        box_min = -0.045, -0.045, 0.16, box_max = 0.045, 0.045, 0.25, seed = 3 /
"""
PROBES = f"""&probe name = 'upper', kind = 'count', region = 'box', box_min = -1e30, -1e30, 0.05,
        box_max = 1e30, 1e30, 1e30 /
&probe name = 'lower', kind = 'count', region = 'box', box_min = -1e30, -1e30, -1e30,
        box_max = 1e30, 1e30, 0.05 /
&probe name = 'com', kind = 'center_of_mass' /
&probe name = 'p5', kind = 'track', id = 5 /
&probe name = 'vel', kind = 'histogram', time = {HIST_T}, bins = 8, v_min = -1.0, v_max = 0.6,
        axis_point = {AXIS[0]}, {AXIS[1]}, 0, region = 'box', box_min = -1, -1, 0.02,
        box_max = 1, 1, 1 /
"""
case = cu.write_box_case(os.path.join(work, "probes.nml"), os.path.join(work, "out"), 0.2,
                         interval=0.01, output=", snapshot_interval = 0.01",
                         extra=SECOND + PROBES)
r = subprocess.run([dem, case], cwd=work, capture_output=True, text=True, timeout=300)
check(r.returncode == 0, f"dem exited with {r.returncode}: {r.stderr}")
out = os.path.join(work, "out")
rows = np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)
series = np.genfromtxt(os.path.join(out, "series.csv"), delimiter=",", names=True)
check(len(rows) == len(series) == 21, f"a probes.csv row per series.csv row ({len(rows)})")


def snapshot(step):
    with h5py.File(os.path.join(out, "snapshots", f"snapshot_{step:012d}.h5")) as f:
        names = [m.decode().strip() for m in f["materials/name"][()]]
        p = {k: f["particles"][k][()] for k in f["particles"]}
    p["name"] = np.array([names[k - 1] for k in p["material"]])
    return p


for row, srow in zip(rows, series):
    step = int(row["step"])
    p = snapshot(step)
    z = p["position"][:, 2]
    for mat in ("soft", "hard"):
        sel = p["name"] == mat
        check(row[f"upper_{mat}"] == np.count_nonzero(sel & (z >= 0.05)) and
              row[f"lower_{mat}"] == np.count_nonzero(sel & (z <= 0.05)),
              f"step {step}: counts of {mat} above and below z = 0.05")
        m = 4.0 / 3.0 * np.pi * p["radius"][sel] ** 3 * RHO[mat]
        com = (m[:, None] * p["position"][sel]).sum(axis=0) / m.sum()
        got = np.array([row[f"com_{mat}_{k}"] for k in "xyz"])
        check(np.allclose(got, com, rtol=1e-12, atol=1e-15),
              f"step {step}: centre of mass of {mat}: {got} vs {com}")
    check(row["upper_soft"] + row["upper_hard"] + row["lower_soft"] + row["lower_hard"]
          - np.count_nonzero(z == 0.05) == srow["particles"], f"step {step}: counts add up")
    i = np.flatnonzero(p["id"] == 5)[0]
    got = np.array([row[f"p5_{k}"] for k in ("x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz")])
    want = np.concatenate([p["position"][i], p["velocity"][i], p["angular_velocity"][i]])
    check(cu.same_bits(got, want), f"step {step}: the tracked particle")
check(rows["upper_hard"][0] == 100 and rows["lower_hard"][-1] > 0,
      "the second material starts above z = 0.05 and falls below it")

# the histogram, from the snapshot of the first row at or after its time
path = os.path.join(out, "histogram_vel.csv")
check(os.path.exists(path), "histogram_vel.csv is written")
if os.path.exists(path):
    h = np.genfromtxt(path, delimiter=",", names=True)
    step = int(rows["step"][np.flatnonzero(rows["time"] >= HIST_T - 1e-12)[0]])
    p = snapshot(step)
    x, v = p["position"], p["velocity"]
    inside = x[:, 2] >= 0.02
    rel = x[inside, :2] - AXIS
    er = rel / np.linalg.norm(rel, axis=1)[:, None]
    comps = {"radial": (er * v[inside, :2]).sum(axis=1),
             "angular": -er[:, 1] * v[inside, 0] + er[:, 0] * v[inside, 1],
             "vertical": v[inside, 2]}
    edges = np.concatenate([[-np.inf], -1.0 + np.arange(9) * 0.2, [np.inf]])
    check(np.allclose(h["bin_lo"], edges[:-1]) and np.allclose(h["bin_hi"], edges[1:]),
          "histogram bins: below, 8 of 0.2 m/s from -1 to 0.6, above")
    for name, c in comps.items():
        k = np.where(c < -1.0, 0, np.where(c >= 0.6, 9,
                     np.minimum(8, 1 + np.floor((c + 1.0) / 0.2).astype(int))))
        want = np.bincount(k, minlength=10)
        check(np.array_equal(h[name].astype(int), want),
              f"histogram {name}: {h[name].astype(int)} vs {want}")
        check(h[name].sum() == inside.sum(), f"histogram {name}: counts add up to the region")
    check(np.count_nonzero(h["vertical"][1:-1]) > 2, "the vertical velocities spread over bins")

# bad input
bad = {"kind = 'speed'": "key 'kind'", "kind = 'track', id = 99999": "key 'id'",
       "kind = 'histogram', time = 0.1, v_min = 1, v_max = 0": "key 'v_max'",
       "kind = 'count', region = 'box', box_min = 0, 0, 0, box_max = 1, -1, 1": "key 'box_max'",
       "kind = 'count', name = 'a b'": "key 'name'"}
for n, (keys, expect) in enumerate(bad.items()):
    text = f"&probe name = 'q', {keys} /\n".replace("name = 'q', kind = 'count', name", "name")
    case = cu.write_box_case(os.path.join(work, f"bad{n}.nml"), os.path.join(work, f"bad{n}"),
                             0.01, extra=text)
    r = subprocess.run([dem, "--check", case], cwd=work, capture_output=True, text=True)
    check(r.returncode == 2 and f"bad{n}.nml:" in r.stderr and "&probe" in r.stderr and
          expect in r.stderr, f"bad &probe ({keys}): exit {r.returncode}, {r.stderr.strip()}")
finish()
