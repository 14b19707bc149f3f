# SPDX-License-Identifier: BSD-3-Clause
"""Inflow (&insert with a rate, doc/user/input.md; doc/theory.md section 10):

1. a mass rate of a discrete mixture by mass into an empty box above a floor: the mass
   inserted is mass_rate (end - start) to within one particle's mass (the goal of each
   insertion is met by the sphere that reaches it), ids 1, 2, ... in order; the same
   final.csv and series.csv on 1 and 2 ranks (the placement does not depend on how the
   particles are spread);
2. a particle rate of a lognormal, into a box above particles placed before the run: floor(rate
   duration) particles, ids after the largest given, radii in [radius_min, radius_max], none
   before `start` (series.csv);
3. a checkpoint written on 1 rank during the inflow, continued on 2 ranks: the same final.csv
   and series.csv as the uninterrupted run.
4. a stream through a face (region 'face', as LIGGGHTS' insert/stream): 500 spheres/s for
   0.08 s through a 4 x 2 cm rectangle turned 45 degrees about its normal -z, velocity
   (0.1, 0, -1) m/s spread by +-0.05 m/s in x and y, no gravity: floor(500 0.08) = 40
   spheres; each crossed the face's plane inside the rectangle (traced back along its
   velocity, to within the slab's thickness times the tangential speed), and they fill it
   (some reach 80 % of each half-side); vz is -1 m/s exactly where no contact changed it
   (most); vx and vy lie in their windows, with means within 4 standard errors
   (0.05/sqrt(3)/sqrt(40)); the same on 2 ranks.
5. a spread of the velocity of spheres placed before the run (velocity_spread = 0.2 m/s):
   after one step, every component within +-0.2 m/s, the mean of each within 4 standard
   errors of 0, and sum v^2 within 4 standard errors of its expectation N 3 (0.2^2 / 3).
usage: test_inflow.py DEM WORKDIR MPIEXEC"""
import csv
import math
import os
import shutil
import subprocess
import sys

from regression_util import check, finish

dem, work, mpiexec = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

HEAD = """&run dt = 1e-5, t_end = 0.08, gravity = 0, 0, -9.81 /
&output dir = '{out}', interval = 0.005{extra} /
&material name = 'glass', density = 2500.0, youngs_modulus = 5e7, poisson_ratio = 0.25 /
&material name = 'steel', density = 7800.0, youngs_modulus = 2e11, poisson_ratio = 0.3 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&pair materials = 'glass', 'steel', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'steel', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.06 /
"""
MASS = """&insert material = 'glass', radius_distribution = 'discrete', radii = 1e-3, 1.5e-3,
        fractions = 0.3, 0.7, box_min = -0.03, -0.03, 0.02, box_max = 0.03, 0.03, 0.04,
        velocity = 0, 0, -0.5, mass_rate = 0.05, start = 0.01, end = 0.05 /
"""
RATE = """&insert n = 50, material = 'glass', radius_min = 1e-3, radius_max = 1.5e-3,
        box_min = -0.03, -0.03, 0.002, box_max = 0.03, 0.03, 0.01 /
&insert material = 'glass', radius_distribution = 'lognormal', radius_mean = 1.2e-3,
        radius_sd = 2e-4, radius_min = 8e-4, radius_max = 1.6e-3, seed = 5,
        box_min = -0.03, -0.03, 0.03, box_max = 0.03, 0.03, 0.04, rate = 2000,
        start = 0.02, duration = 0.0201, insert_every = 100 /
"""


def run(name, text, ranks=1, args=()):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    cmd = [dem, *args, path]
    if ranks > 1:
        cmd = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] + cmd
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=600)
    check(r.returncode == 0, f"{name} on {ranks} ranks: exit {r.returncode}: {r.stderr[-2000:]}")


def final(out):
    with open(os.path.join(work, out, "final.csv")) as f:
        return list(csv.DictReader(f))


def same(a, b, what):
    for name in ("final.csv", "series.csv"):
        with open(os.path.join(work, a, name), "rb") as f, \
                open(os.path.join(work, b, name), "rb") as g:
            check(f.read() == g.read(), f"{what}: {name} differs ({a}, {b})")


def mass(rows):
    return sum(4 / 3 * math.pi * float(r["radius"]) ** 3 * 2500.0 for r in rows)


# 1. mass rate, 1 and 2 ranks
run("mass1", HEAD.format(out="mass1", extra="") + MASS)
run("mass2", HEAD.format(out="mass2", extra="") + MASS, ranks=2)
rows = final("mass1")
target = 0.05 * (0.05 - 0.01)
largest = 4 / 3 * math.pi * 1.5e-3 ** 3 * 2500.0
check(0 <= mass(rows) - target < largest,
      f"mass inserted {mass(rows):.6g} kg, expected {target:.6g} kg within {largest:.3g} kg")
check(sorted(int(r["id"]) for r in rows) == list(range(1, len(rows) + 1)),
      "inflow ids are 1 .. N")
same("mass1", "mass2", "1 and 2 ranks")

# 2. particle rate after particles placed before the run
run("rate", HEAD.format(out="rate", extra="") + RATE)
rows = final("rate")
new = [r for r in rows if int(r["id"]) > 50]
check(len(rows) == 50 + 40, f"{len(rows)} particles, expected 50 + floor(2000 * 0.0201) = 90")
check(sorted(int(r["id"]) for r in new) == list(range(51, 91)), "inflow ids follow 50")
check(all(8e-4 <= float(r["radius"]) <= 1.6e-3 for r in new), "inflow radii in the window")
with open(os.path.join(work, "rate", "series.csv")) as f:
    series = list(csv.DictReader(f))
check(all(int(s["particles"]) == 50 for s in series if float(s["time"]) < 0.02 - 1e-9),
      "no inflow before start")

# 3. restart during the inflow, on 2 ranks
ckpt = ", checkpoint_interval = 0.02, checkpoint_keep = 10"
run("whole", HEAD.format(out="whole", extra=ckpt) + MASS)
shutil.copytree(os.path.join(work, "whole"), os.path.join(work, "cont"))
os.remove(os.path.join(work, "cont", "final.csv"))
text = HEAD.format(out="cont", extra=ckpt) + MASS
run("cont", text, ranks=2,
    args=("--restart", os.path.join(work, "cont", "checkpoints", "checkpoint_000000002000.h5")))
same("whole", "cont", "restart during the inflow")

# 4. a stream through a face
STREAM = """&run dt = 1e-5, t_end = 0.1, gravity = 0, 0, 0 /
&output dir = '{out}', interval = 0.01 /
&material name = 'glass', density = 2500.0, youngs_modulus = 5e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&insert material = 'glass', radius_min = 1e-3, region = 'face', face_center = 0, 0, 0.1,
        face_normal = 0, 0, -1, face_axis = 1, 1, 0, face_width = 0.04, 0.02,
        velocity = 0.1, 0, -1, velocity_spread = 0.05, 0.05, 0, rate = 500, end = 0.08 /
"""
run("stream", STREAM.format(out="stream"))
run("stream2", STREAM.format(out="stream2"), ranks=2)
same("stream", "stream2", "a stream on 1 and 2 ranks")
rows = final("stream")
check(len(rows) == 40, f"{len(rows)} spheres streamed in, expected floor(500 0.08) = 40")
u = (1 / math.sqrt(2), 1 / math.sqrt(2))
w = (1 / math.sqrt(2), -1 / math.sqrt(2))      # face_normal x face_axis
slab = 3e-3                                      # max(v_n every dt, 3 r_max): 3 r_max here
reach_u = reach_w = 0.0
for r in rows:
    x, y, z = (float(r[k]) for k in ("x", "y", "z"))
    vx, vy, vz = (float(r[k]) for k in ("vx", "vy", "vz"))
    if vz >= 0:
        check(False, f"sphere {r['id']} does not move in: vz = {vz}")
        continue
    back = (0.1 - z) / vz                        # (negative) time since it crossed z = 0.1
    cx, cy = x + vx * back, y + vy * back
    tol = slab * math.hypot(vx, vy) / abs(vz) + 1e-9
    pu, pw = cx * u[0] + cy * u[1], cx * w[0] + cy * w[1]
    check(abs(pu) <= 0.02 + tol and abs(pw) <= 0.01 + tol,
          f"sphere {r['id']} crossed the face's plane outside the rectangle: {pu:.4g}, {pw:.4g}")
    reach_u, reach_w = max(reach_u, abs(pu)), max(reach_w, abs(pw))
check(reach_u > 0.8 * 0.02 and reach_w > 0.8 * 0.01,
      f"the stream fills the face: reaches {reach_u:.4g} of 0.02 m and {reach_w:.4g} of 0.01 m")
free = [r for r in rows if float(r["vz"]) == -1.0]
check(len(free) >= 30, f"{len(free)} of 40 spheres kept vz = -1 m/s exactly (no contact)")
se = 0.05 / math.sqrt(3) / math.sqrt(len(free))
for k, mean in (("vx", 0.1), ("vy", 0.0)):
    vals = [float(r[k]) for r in free]
    check(all(abs(v - mean) <= 0.05 + 1e-12 for v in vals), f"{k} within {mean} +- 0.05 m/s")
    m = sum(vals) / len(vals)
    check(abs(m - mean) < 4 * se, f"mean {k} {m:.4g} m/s, expected {mean} within {4 * se:.3g}")

# 5. a velocity spread before the run
SPREAD = """&run dt = 1e-5, t_end = 1e-5, gravity = 0, 0, 0 /
&output dir = 'spread' /
&material name = 'glass', density = 2500.0, youngs_modulus = 5e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&insert n = 300, material = 'glass', radius_min = 1e-3, box_min = 0, 0, 0,
        box_max = 0.1, 0.1, 0.1, velocity_spread = 0.2, 0.2, 0.2, seed = 9 /
"""
run("spread", SPREAD)
rows = final("spread")
vs = [[float(r[k]) for k in ("vx", "vy", "vz")] for r in rows]
check(len(vs) == 300 and all(abs(c) <= 0.2 for v in vs for c in v),
      "every component of the velocity within +-0.2 m/s")
se = 0.2 / math.sqrt(3) / math.sqrt(300)
for d in range(3):
    m = sum(v[d] for v in vs) / 300
    check(abs(m) < 4 * se, f"mean velocity component {d}: {m:.4g}, expected 0 within {4 * se:.3g}")
ssq = sum(c * c for v in vs for c in v)
expect = 900 * 0.2 ** 2 / 3                      # E u^2 = a^2 / 3
se_ssq = math.sqrt(900 * (0.2 ** 4 / 5 - 0.2 ** 4 / 9))      # Var u^2 = a^4 (1/5 - 1/9)
check(abs(ssq - expect) < 4 * se_ssq, f"sum v^2 {ssq:.4g}, expected {expect:.4g} within "
      f"{4 * se_ssq:.3g}")
finish()
