# SPDX-License-Identifier: BSD-3-Clause
"""Walls read from STL files, at rest and in rigid motion, against impulse balances.

1. A square wall (two triangles, from an ASCII STL in millimetres, scale 1e-3) moving at
   V = 0.5 m/s into a sphere at rest, without gravity: a wall of infinite mass sends an
   elastic sphere off at 2 V, and one with restitution e at (1 + e) V; the largest overlap
   is Hertz's at impact speed V.
2. A wall rotating about the z axis at omega sweeps into a sphere at distance y0 from the
   axis: the wall's velocity at the contact point is omega y0, so the sphere leaves at
   2 omega y0 (elastic, frictionless), within the small turn of the wall during the contact.
3. Input errors of &wall_mesh: a missing STL file and a malformed one are reported with the
   case file, the group and the key.
usage: test_moving_walls.py DEM WORKDIR"""
import math
import os
import shutil
import subprocess
import sys

from regression_util import check, check_close, finish, run_dem
import chung_ooi as co

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def write_stl(name, triangles):
    with open(os.path.join(work, name), "w") as f:
        f.write("solid wall\n")
        for tri in triangles:
            f.write("  facet normal 0 0 0\n    outer loop\n")
            for v in tri:
                f.write("      vertex %.17g %.17g %.17g\n" % v)
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid wall\n")


def square(a, b, c, d):
    return [(a, b, c), (a, c, d)]


R, rho, E, nu = 1.0e-3, 2800.0, 48.0e9, 0.2
m = co.sphere_mass(rho, R)
estar = E / (1 - nu**2)

# 1. translating wall, in mm
write_stl("floor_mm.stl", square((-10, -10, 0), (10, -10, 0), (10, 10, 0), (-10, 10, 0)))
V = 0.5
for e in (1.0, 0.5):
    name = f"push_{e}"
    with open(os.path.join(work, name + ".nml"), "w") as f:
        f.write(f"""&run dt = 2.0e-8, t_end = 1.0e-4, gravity = 0, 0, 0 /
&output interval = 1.0e-6, trace_id = 1 /
&material name = 'glass', density = {rho}, youngs_modulus = {E}, poisson_ratio = {nu} /
&material name = 'rigid', rigid = .true. /
&pair materials = 'glass', 'glass', restitution = 1.0, friction = 0.0 /
&pair materials = 'glass', 'rigid', restitution = {e}, friction = 0.0 /
&particle id = 1, material = 'glass', radius = {R}, position = 0, 0, {R + 1e-5} /
&wall_mesh file = 'floor_mm.stl', scale = 1.0e-3, material = 'rigid', velocity = 0, 0, {V} /
""")
    run_dem(dem, os.path.join(work, name + ".nml"), work)
    final = co.read_csv(os.path.join(work, "output", name, "final.csv"))
    check_close(final["vz"][0], (1 + e) * V, 2e-3, f"moving wall, e = {e}: sphere speed after")
    if e == 1.0:
        contact = co.read_csv(os.path.join(work, "output", name, "contact.csv"))
        check_close(contact["overlap"].max(), co.hertz(m, R, estar, V)[0], 5e-3,
                    "moving wall: largest overlap")

# 2. rotating wall: the plane x = 0 (y from 0 to 20 mm), turning about z at omega < 0,
# so that its points move towards +x; the sphere sits at y0 = 10 mm
write_stl("paddle.stl", square((0, 0, -5e-3), (0, 20e-3, -5e-3), (0, 20e-3, 5e-3),
                               (0, 0, 5e-3)))
omega, y0 = -10.0, 0.01
with open(os.path.join(work, "paddle.nml"), "w") as f:
    f.write(f"""&run dt = 2.0e-8, t_end = 1.2e-4, gravity = 0, 0, 0 /
&material name = 'glass', density = {rho}, youngs_modulus = {E}, poisson_ratio = {nu} /
&material name = 'rigid', rigid = .true. /
&pair materials = 'glass', 'glass', restitution = 1.0, friction = 0.0 /
&pair materials = 'glass', 'rigid', restitution = 1.0, friction = 0.0 /
&particle id = 1, material = 'glass', radius = {R}, position = {R + 1e-6}, {y0}, 0 /
&wall_mesh file = 'paddle.stl', material = 'rigid', rotation_axis = 0, 0, 1,
           rotation_point = 0, 0, 0, angular_velocity = {omega} /
""")
run_dem(dem, os.path.join(work, "paddle.nml"), work)
final = co.read_csv(os.path.join(work, "output", "paddle", "final.csv"))
speed = math.hypot(final["vx"][0], final["vy"][0])
check_close(speed, 2 * abs(omega) * y0, 5e-3, "rotating wall: sphere speed after")

# 3. errors
for name, text, words in (
        ("missing_stl", "&wall_mesh file = 'nowhere.stl', material = 'rigid' /", ["nowhere.stl"]),
        ("bad_stl", "&wall_mesh file = 'bad.stl', material = 'rigid' /", ["bad.stl", "bad.stl:4:", "vertex"])):
    with open(os.path.join(work, "bad.stl"), "w") as f:
        f.write("solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 zero\n")
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(open(os.path.join(work, "paddle.nml")).read().split("&wall_mesh")[0] + text + "\n")
    r = subprocess.run([dem, "--check", path], capture_output=True, text=True, cwd=work)
    check(r.returncode == 2, f"{name}: exit code {r.returncode}")
    for w in [path, "&wall_mesh", "'file'"] + words:
        check(w in r.stderr, f"{name}: message lacks {w!r}: {r.stderr.strip()}")
finish()
