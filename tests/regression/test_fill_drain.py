# SPDX-License-Identifier: BSD-3-Clause
"""Filling a box by random insertion, settling it, restarting from the settled particle file,
and draining it through an outlet.

1. &insert places 100 spheres in a box region without overlaps, reproducibly from a seed
   (the same seed gives the same file bit for bit, another seed another packing); the run
   stops by itself once the kinetic energy is below stop_kinetic_energy, with every sphere
   inside the container and no overlap above 2 % of the radius (Hertz: a sphere under the
   weight of a 10-sphere column overlaps less than that).
2. The settled final.csv starts a new case (&particle_file): the state at t = 0 is the file's,
   exactly (the gravitational energy of series.csv's first row equals the file's, computed
   here).
3. Without its floor, the bed drains through an outlet plane: every sphere is removed, and
   particles + removed = 100 in every row of series.csv; the run stops when the last one
   leaves, before t_end. The timing line's particles per step
   (their mean over the steps) lies between the means of series.csv's counts taken at the
   start and at the end of each output interval (the count never rises), the end count (0)
   is beside it, and its ns per particle-step is its time over steps x that mean. The memory
   line's bytes per particle are the peak over the most particles held (the 100 at the start).
4. Bad particle files are reported with the file, the line and the column.
5. &insert into the inside of a closed mesh (a cube turned 45 degrees about z, so that its
   bounding box is twice its volume): every sphere lies inside the cube, at least its radius
   from every face.
usage: test_fill_drain.py DEM WORKDIR"""
import os
import re
import shutil
import subprocess
import sys

import numpy as np

from regression_util import check, check_close, finish, run_dem
import chung_ooi as co

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

R, RHO, E, NU, G = 5.0e-3, 2500.0, 1.0e7, 0.2, 9.81
MATERIALS = f"""&material name = 'soft', density = {RHO}, youngs_modulus = {E}, poisson_ratio = {NU} /
&material name = 'wall', rigid = .true. /
&pair materials = 'soft', 'soft', restitution = 0.3, friction = 0.3 /
&pair materials = 'soft', 'wall', restitution = 0.3, friction = 0.3 /
"""
SIDES = """&wall_plane material = 'wall', point = -0.05, 0, 0.1, normal = 1, 0, 0, half_width = 0.1 /
&wall_plane material = 'wall', point = 0.05, 0, 0.1, normal = -1, 0, 0, half_width = 0.1 /
&wall_plane material = 'wall', point = 0, -0.05, 0.1, normal = 0, 1, 0, half_width = 0.1 /
&wall_plane material = 'wall', point = 0, 0.05, 0.1, normal = 0, -1, 0, half_width = 0.1 /
"""
FLOOR = "&wall_plane material = 'wall', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.06 /\n"


def case(name, body):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(body)
    return path


def fill(name, seed):
    return case(name, f"""&run dt = 5.0e-5, t_end = 2.0, stop_kinetic_energy = 1.0e-6 /
&output interval = 0.01 /
{MATERIALS}{SIDES}{FLOOR}&insert n = 100, material = 'soft', radius_min = {R}, seed = {seed},
        box_min = -0.05, -0.05, 0.0, box_max = 0.05, 0.05, 0.15 /
""")


# 1. fill and settle, twice with one seed and once with another
for name, seed in (("fill_a", 7), ("fill_b", 7), ("fill_c", 8)):
    run_dem(dem, fill(name, seed), work)
out = os.path.join(work, "output")
a = open(os.path.join(out, "fill_a", "final.csv")).read()
check(a == open(os.path.join(out, "fill_b", "final.csv")).read(), "same seed, same packing")
check(a != open(os.path.join(out, "fill_c", "final.csv")).read(), "other seed, other packing")
f = co.read_csv(os.path.join(out, "fill_a", "final.csv"))
s = co.read_csv(os.path.join(out, "fill_a", "series.csv"))
check(len(f["id"]) == 100 and sorted(f["id"]) == list(range(1, 101)), "ids 1 to 100")
check(s["time"][-1] < 2.0 - 1e-9, f"the run stopped once settled (t = {s['time'][-1]})")
check(s["kinetic_translational"][-1] + s["kinetic_rotational"][-1] < 1e-6, "settled")
x = np.stack([f["x"], f["y"], f["z"]], axis=1)
check(np.all(np.abs(x[:, :2]) < 0.05) and np.all(x[:, 2] > 0), "all inside the box")
d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2) + np.eye(100)
check((2 * R - d).max() < 0.02 * R, f"largest overlap {(2 * R - d).max() / R:.3%} of R")

# 2. restart from the settled file
settled = os.path.join(out, "fill_a", "final.csv")
path = case("restart", f"""&run dt = 5.0e-5, t_end = 1.0e-3 /
{MATERIALS}{SIDES}{FLOOR}&particle_file file = '{settled}' /
""")
run_dem(dem, path, work)
r0 = co.read_csv(os.path.join(out, "restart", "series.csv"))
m = co.sphere_mass(RHO, R)
check_close(r0["potential_gravity"][0], m * G * f["z"].sum(), 1e-13,
            "restart: gravitational energy of the file")
check(r0["particles"][0] == 100, "restart: 100 particles")

# 3. drain: no floor, an outlet 5 cm below
path = case("drain", f"""&run dt = 5.0e-5, t_end = 0.4 /
&output interval = 0.005 /
{MATERIALS}{SIDES}&particle_file file = '{settled}' /
&outlet region = 'plane', point = 0, 0, -0.05, normal = 0, 0, -1 /
""")
_, stdout, _ = run_dem(dem, path, work)
dr = co.read_csv(os.path.join(out, "drain", "series.csv"))
check(np.all(dr["particles"] + dr["removed"] == 100), "particles + removed = 100 in every row")
check(dr["removed"][-1] == 100 and dr["particles"][-1] == 0, "all drained")
check(np.all(np.diff(dr["removed"]) >= 0), "removed never decreases")
m = re.search(r"^timing: (\d+) steps of (\d+) particles in +(\S+) s, +(\S+) ns per "
              r"particle-step \(particles on the mean over the steps; 0 at the end\)", stdout, re.M)
check(m is not None, f"drain: timing line with the mean and the end count: {stdout[-400:]}")
if m:
    steps, mean, seconds, ns = int(m[1]), int(m[2]), float(m[3]), float(m[4])
    counts = np.asarray(dr["particles"], float)
    gaps = np.diff(np.asarray(dr["step"], float))        # (the last row is where it emptied)
    check(steps == dr["step"][-1] and dr["time"][-1] < 0.4,
          f"drain: {steps} steps, up to the last sphere's leaving ({dr['time'][-1]:.4f} s)")
    lo, hi = (gaps * counts[1:]).sum() / gaps.sum(), (gaps * counts[:-1]).sum() / gaps.sum()
    check(lo - 0.5 <= mean <= hi + 0.5, f"drain: mean {mean} particles per step within the "
          f"series' bounds {lo:.1f}-{hi:.1f}")
    # the mean is printed rounded to a particle, the time to 5 digits, the ns to 0.1
    check(1e9 * seconds / (steps * (mean + 0.5)) * (1 - 1e-4) - 0.05 <= ns
          <= 1e9 * seconds / (steps * (mean - 0.5)) * (1 + 1e-4) + 0.05,
          f"drain: {ns} ns per particle-step is {seconds} s over {steps} x {mean}")
# the memory line divides the peak by the most particles held (100 at the start), not by the 0 left
m = re.search(r"^memory: peak resident +(\S+) MiB, +(\S+) bytes per particle \(of the most "
              r"held\)", stdout, re.M)
check(m is not None, f"drain: memory line per the most particles held: {stdout[-300:]}")
if m:
    check(abs(float(m[2]) - float(m[1]) * 2**20 / 100) <= 0.05 * 2**20 / 100 + 0.1,
          f"drain: {m[2]} bytes per particle is {m[1]} MiB over 100 particles")

# 4. bad particle files
for name, text, words in (
        ("no_column", "id,material,radius,x,y\n1,soft,0.005,0,0\n", [":1:", "'z'"]),
        ("bad_number", "id,material,radius,x,y,z\n1,soft,0.005,0,0,0.1\n2,soft,0.005,0,zero,0.2\n",
         [":3:", "'y'", "zero"]),
        ("bad_material", "id,material,radius,x,y,z\n1,gold,0.005,0,0,0.1\n", [":2:", "gold"])):
    csv = os.path.join(work, name + ".csv")
    with open(csv, "w") as fh:
        fh.write(text)
    path = case(name, f"&run dt = 5.0e-5, t_end = 1.0e-3 /\n{MATERIALS}&particle_file file = "
                f"'{csv}' /\n")
    r = subprocess.run([dem, "--check", path], capture_output=True, text=True, cwd=work)
    check(r.returncode == 2, f"{name}: exit code {r.returncode}")
    for w in [path, "&particle_file", "'file'", csv] + words:
        check(w in r.stderr, f"{name}: message lacks {w!r}: {r.stderr.strip()}")
# 5. inside a closed mesh: a 40 mm cube turned 45 degrees about z, centred at the origin
c, h = np.cos(np.pi / 4), 0.02
corners = np.array([[sx * h, sy * h, sz * h] for sz in (-1, 1) for sy in (-1, 1)
                    for sx in (-1, 1)])
corners = corners @ np.array([[c, c, 0], [-c, c, 0], [0, 0, 1]])
faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
with open(os.path.join(work, "cube.stl"), "w") as fh:
    fh.write("solid cube\n")
    for a_, b_, c_, d_ in faces:
        for tri in ((a_, b_, c_), (a_, c_, d_)):
            fh.write(" facet normal 0 0 0\n  outer loop\n")
            for v in tri:
                fh.write("   vertex %.17g %.17g %.17g\n" % tuple(corners[v]))
            fh.write("  endloop\n endfacet\n")
    fh.write("endsolid cube\n")
path = case("in_mesh", f"""&run dt = 5.0e-5, t_end = 1.0e-4, gravity = 0, 0, 0 /
{MATERIALS}&insert n = 60, material = 'soft', radius_min = 2.0e-3, region = 'mesh',
        mesh_file = 'cube.stl', seed = 3 /
""")
run_dem(dem, path, work)
cube = co.read_csv(os.path.join(out, "in_mesh", "final.csv"))
p = np.stack([cube["x"], cube["y"], cube["z"]], axis=1)
local = p @ np.array([[c, c, 0], [-c, c, 0], [0, 0, 1]]).T    # back into the cube's axes
check(len(cube["id"]) == 60, "60 spheres in the mesh")
check(np.all(np.abs(local) <= h - 2.0e-3 + 1e-12), "every sphere inside the turned cube")
check(np.any(np.abs(p[:, 0]) + np.abs(p[:, 1]) > 0.0), "spheres spread over the cube")
finish()
