# SPDX-License-Identifier: BSD-3-Clause
"""Wall primitives (&wall_primitive) against analytical rest positions and &wall_plane.

1. A sphere of radius r inside a cylinder of radius R made of n = 12 facets, gravity sideways
   towards the middle of a facet: it comes to rest against the facet, its centre at
   R cos(pi/n) - r from the axis plus the Hertz overlap under its weight (the facet sag
   R (1 - cos(pi/n)) is the whole difference from a true cylinder); a wall_load probe on the
   named cylinder reads the sphere's weight.
2. A sphere bouncing and sliding on a tilted &wall_plane and on a &wall_primitive rectangle
   of the same plane, turned 30 degrees about its normal and of other sides: the same
   trajectory (the contact force depends on the plane only).
3. A sphere in a box (side 'inner'), frictionless, gravity along -(1, 1, 1): it rests in the
   corner, r less the Hertz overlap under m g / sqrt(3) from each face.
4. On an annulus in z = 0: a sphere over the ring rests at z = r less the overlap under its
   weight, one over the hole falls through.
5. A sphere in a cone of half-angle 45 degrees, apex down, n = 6 facets: it rests on the
   axis at the height r / sin(a') of the inscribed pyramid's half-angle a',
   tan a' = tan(45 deg) cos(pi/n) (8 % above the true cone's r / sin(45 deg)).
6. Motion: a closed cylinder (side 'outer') moving at V along its axis into a sphere at rest,
   without gravity: elastic and frictionless, the sphere leaves at 2 V, as from a &wall_mesh.
usage: test_wall_primitives.py DEM WORKDIR"""
import csv
import math
import os
import shutil
import sys

from regression_util import check, finish, run_dem
import chung_ooi as co

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

r, rho, E, nu, g = 1.0e-3, 2500.0, 1.0e8, 0.2, 9.81
HEAD = f"""&material name = 'bead', density = {rho}, youngs_modulus = {E}, poisson_ratio = {nu} /
&material name = 'rigid', rigid = .true. /
&pair materials = 'bead', 'bead', restitution = 0.3, friction = 0.3 /
&pair materials = 'bead', 'rigid', restitution = 0.3, friction = 0.3 /
"""


def run(name, text, head=HEAD):
    with open(os.path.join(work, name + ".nml"), "w") as f:
        f.write(head + text)
    run_dem(dem, os.path.join(work, name + ".nml"), work)
    return co.read_csv(os.path.join(work, "output", name, "final.csv"))


# 1. rest inside a cylinder
R, n = 0.01, 12
phi = math.pi / n   # the middle of the first facet
gx, gy = g * math.cos(phi), g * math.sin(phi)
final = run("cylinder", f"""&run dt = 2.0e-6, t_end = 0.3, gravity = {gx}, {gy}, 0 /
&particle id = 1, material = 'bead', radius = {r}, position = 0, 0, 0 /
&output interval = 0.01 /
&wall_primitive shape = 'cylinder', material = 'rigid', point = 0, 0, -0.01,
                axis = 0, 0, 0.02, radius = {R}, resolution = {n}, name = 'tube' /
&probe name = 'tube', kind = 'wall_load', wall = 'tube' /
""")
estar = E / (1 - nu**2)
weight = co.sphere_mass(rho, r) * g
overlap = (3 * weight / (4 * estar * math.sqrt(r)))**(2 / 3)
d = math.hypot(final["x"][0], final["y"][0])
expected = R * math.cos(phi) - r + overlap
check(abs(d - expected) <= 0.05 * overlap,
      f"cylinder: rest at {d:.9g} m from the axis, expected R cos(pi/n) - r + overlap = "
      f"{expected:.9g} (sag {R * (1 - math.cos(phi)):.3g} m, overlap {overlap:.3g} m)")
check(abs(math.atan2(final["y"][0], final["x"][0]) - phi) < 1e-6, "cylinder: rests on the facet")
check(math.hypot(final["vx"][0], final["vy"][0]) < 1e-5, "cylinder: at rest")
with open(os.path.join(work, "output", "cylinder", "probes.csv")) as f:
    rows = list(csv.DictReader(f))
for k, gk in (("x", gx), ("y", gy)):
    load = float(rows[-1]["tube_f" + k])
    check(abs(load - weight / g * gk) <= 1e-3 * weight,
          f"cylinder: wall load {k} {load:.9g} N, the weight's {weight / g * gk:.9g} N")

# 2. rectangle turned 30 degrees against the plane it lies in
normal = (0.0, math.sin(0.3), math.cos(0.3))
start = "&particle id = 1, material = 'bead', radius = 1e-3, position = 0, 0, 0.002, " \
        "velocity = 0.05, 0.02, -0.1 /\n"
RUN = "&run dt = 2.0e-6, t_end = 0.05, gravity = 0, 0, -9.81 /\n"
plane = run("plane", RUN + start + "&wall_plane material = 'rigid', point = 0, 0, 0, normal = "
            f"{normal[0]}, {normal[1]}, {normal[2]}, half_width = 0.05 /\n")
a = (math.cos(math.pi / 6), 0.0, 0.0)
b = (0.0, math.sin(math.pi / 6) * normal[2], -math.sin(math.pi / 6) * normal[1])
direction = tuple(ai + bi for ai, bi in zip(a, b))
rect = run("rectangle", RUN + start + "&wall_primitive shape = 'rectangle', material = "
           f"'rigid', point = 0, 0, 0, normal = {normal[0]}, {normal[1]}, {normal[2]}, "
           f"direction = {direction[0]}, {direction[1]}, {direction[2]}, "
           "half_sizes = 0.04, 0.06, resolution = 3 /\n")
moved = math.dist([plane[k][0] for k in "xyz"], [0.0, 0.0, 0.002])
check(moved > 0.002, f"rectangle: the sphere slid {moved:.3g} m on the plane")
for k in ("x", "y", "z", "vx", "vy", "vz"):
    check(abs(rect[k][0] - plane[k][0]) <= 1e-9 * max(1.0, abs(plane[k][0])) + 1e-12,
          f"rectangle: {k} = {rect[k][0]!r}, the &wall_plane's {plane[k][0]!r}")
# 3. the corner of a box, frictionless (with friction the three forces are indeterminate)
final = run("box", f"""&run dt = 2.0e-6, t_end = 0.3, gravity = {-g / math.sqrt(3)}, {-g / math.sqrt(3)}, {-g / math.sqrt(3)} /
&particle id = 1, material = 'bead', radius = {r}, position = 0.005, 0.005, 0.005 /
&wall_primitive shape = 'box', material = 'rigid', box_min = 0, 0, 0, box_max = 0.01, 0.01, 0.01 /
""", HEAD.replace("friction = 0.3", "friction = 0.0"))
face = (3 * weight / math.sqrt(3) / (4 * estar * math.sqrt(r)))**(2 / 3)
for k in "xyz":
    check(abs(final[k][0] - (r - face)) <= 0.05 * face,
          f"box: {k} = {final[k][0]:.9g}, expected r - overlap = {r - face:.9g}")

# 4. an annulus: a ring and a hole
final = run("annulus", f"""&run dt = 2.0e-6, t_end = 0.2, gravity = 0, 0, {-g}, max_energy = 1 /
&particle id = 1, material = 'bead', radius = {r}, position = 0.006, 0, 0.002 /
&particle id = 2, material = 'bead', radius = {r}, position = -0.0001, 0, 0.002 /
&wall_primitive shape = 'disc', material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1,
                radius = 0.01, inner_radius = 0.003 /
""")
rows = {int(i): j for j, i in enumerate(final["id"])}
check(abs(final["z"][rows[1]] - (r - overlap)) <= 0.05 * overlap,
      f"annulus: z = {final['z'][rows[1]]:.9g} on the ring, expected {r - overlap:.9g}")
check(final["z"][rows[2]] < -0.05, f"annulus: z = {final['z'][rows[2]]:.3g} through the hole")

# 5. a cone, apex down, of 6 facets (a sphere at the apex touches each: at most 8 wall contacts)
n = 6
half = math.atan(math.cos(math.pi / n))
final = run("cone", f"""&run dt = 2.0e-6, t_end = 0.2, gravity = 0, 0, {-g} /
&particle id = 1, material = 'bead', radius = {r}, position = 0, 0, 0.004 /
&wall_primitive shape = 'cone', material = 'rigid', point = 0, 0, 0, axis = 0, 0, 0.01,
                radius = 0, radius_top = 0.01, resolution = {n} /
""")
expected = r / math.sin(half)
check(abs(final["z"][0] - expected) <= 1e-4 * r,
      f"cone: z = {final['z'][0]:.9g}, expected r / sin(a') = {expected:.9g} "
      f"(true cone: {r / math.sin(math.pi / 4):.9g})")
check(math.hypot(final["x"][0], final["y"][0]) < 1e-9, "cone: on the axis")

# 6. a moving closed cylinder pushes a sphere with its end
V = 0.5
final = run("moving", f"""&run dt = 2.0e-6, t_end = 0.02, gravity = 0, 0, 0 /
&particle id = 1, material = 'bead', radius = {r}, position = 0, 0, {r + 1e-5} /
&wall_primitive shape = 'cylinder', material = 'rigid', point = 0, 0, -0.01, axis = 0, 0, 0.01,
                radius = 0.005, side = 'outer', closed = .true., velocity = 0, 0, {V} /
""", HEAD.replace("restitution = 0.3, friction = 0.3", "restitution = 1.0, friction = 0.0"))
check(abs(final["vz"][0] - 2 * V) <= 2e-3 * 2 * V,
      f"moving cylinder: sphere leaves at {final['vz'][0]:.9g} m/s, expected 2 V = {2 * V}")
finish()
