# SPDX-License-Identifier: BSD-3-Clause
"""Wall loads (the 'wall_load' probe) against momentum balances, and prescribed wall motions
(oscillation, velocity tables) in a run (doc/theory.md, sections 4 and 8):

1. A small bed settled in a box (1 s; at rest to 2e-11 J): the walls together carry its weight,
   F = M g, and the torque about a point a is that of the weight, M (X - a) x g (X from a
   centre-of-mass probe); the floor carries most of it and the floor's and the sides'
   probes add up to the whole. The probe's columns are bit-identical on 1 and 2 ranks.
2. A sphere resting on a floor that oscillates vertically, z_f = A (sin(w t + phi) - sin phi),
   with A w^2 = 0.5 g: it moves with the floor (its height above the floor stays the radius
   to 1e-3 A), and the floor's load is m (g - a_f), the weight less the mass times the
   floor's acceleration a_f = -A w^2 sin(w t + phi). At A w^2 = 3 g it leaves the floor.
3. A floor moved by a velocity table, v_z = 0 at t = 0.05 s, 0.2 m/s at 0.1 s, 0 at 0.15 s:
   it lifts the sphere by the table's integral, 0.01 m, and the load while the floor
   accelerates is m (g + a), a = 4 m/s^2. With tables and an oscillation together, a restart
   from a checkpoint writes the same probes.csv and final.csv as the run straight through.
4. A small drum rotating at omega about y: over its steady rotation the mean torque of the
   particles about the axis balances the torque of their weight, T_y = M g X (X the centre
   of mass's offset along x), and the drum's power draw is -omega T_y > 0.
usage: test_wall_loads.py DEM WORKDIR MPIEXEC"""
import math
import os
import shutil
import subprocess
import sys

import numpy as np

from regression_util import check, check_close, finish, run_dem

dem, work, mpiexec = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

G = 9.81
MATERIALS = """&material name = 'glass', density = 2500.0, youngs_modulus = 5.0e7, poisson_ratio = 0.25 /
&material name = 'rigid', rigid = .true. /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&pair materials = 'glass', 'rigid', restitution = 0.5, friction = 0.3 /
"""


def write_stl(name, triangles):
    with open(os.path.join(work, name), "w") as f:
        f.write("solid wall\n")
        for tri in triangles:
            f.write("  facet normal 0 0 0\n    outer loop\n")
            for v in tri:
                f.write("      vertex %.17g %.17g %.17g\n" % tuple(v))
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid wall\n")


def write_case(name, text):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    return path


def probes(name):
    return np.genfromtxt(os.path.join(work, "output", name, "probes.csv"), delimiter=",",
                         names=True)


def sphere_mass(r, rho=2500.0):
    return rho * 4.0 / 3.0 * math.pi * r**3


# 1. a bed settled in a box of five planes; the torque about a = (-0.05, 0.01, 0)
box = """&run dt = 5e-6, t_end = 1.0, gravity = 0, 0, -9.81, integrator = 'velocity_verlet' /
&output interval = 0.01 /
""" + MATERIALS + """&insert n = 40, material = 'glass', radius_min = 0.002, radius_max = 0.002,
        region = 'box', box_min = -0.008, -0.008, 0.003, box_max = 0.008, 0.008, 0.03, seed = 7 /
&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.01, name = 'floor' /
&wall_plane material = 'rigid', point = -0.01, 0, 0.01, normal = 1, 0, 0, half_width = 0.01 /
&wall_plane material = 'rigid', point = 0.01, 0, 0.01, normal = -1, 0, 0, half_width = 0.01 /
&wall_plane material = 'rigid', point = 0, -0.01, 0.01, normal = 0, 1, 0, half_width = 0.01 /
&wall_plane material = 'rigid', point = 0, 0.01, 0.01, normal = 0, -1, 0, half_width = 0.01 /
&probe name = 'all', kind = 'wall_load', axis_point = -0.05, 0.01, 0, axis = 0, 1, 0 /
&probe name = 'floor', kind = 'wall_load', wall = 'floor', axis_point = -0.05, 0.01, 0 /
&probe name = 'com', kind = 'center_of_mass' /
"""
path = write_case("box", box)
run_dem(dem, path, work)
p = probes("box")
last = p[-1]
M = 40 * sphere_mass(0.002)
series = np.genfromtxt(os.path.join(work, "output", "box", "series.csv"), delimiter=",",
                       names=True)
ke = series["kinetic_translational"][-1] + series["kinetic_rotational"][-1]
print(f"box: at t = {last['time']}, kinetic energy {ke} J, F = {last['all_fx']}, "
      f"{last['all_fy']}, {last['all_fz']} (M g = {M * G})")
check(ke < 2e-11, f"box: the bed has settled (kinetic energy {ke} J)")
check_close(last["all_fz"], -M * G, 1e-6, "box: the walls carry the weight")
check(abs(last["all_fx"]) < 1e-6 * M * G and abs(last["all_fy"]) < 1e-6 * M * G,
      "box: no net horizontal load")
X = np.array([last["com_glass_x"], last["com_glass_y"], last["com_glass_z"]])
a = np.array([-0.05, 0.01, 0.0])
torque = M * np.cross(X - a, [0.0, 0.0, -G])
for k, c in enumerate("xyz"):
    check(abs(last["all_t" + c] - torque[k]) < 1e-3 * M * G * np.linalg.norm(X - a),
          f"box: torque {c}: {last['all_t' + c]} vs the weight's {torque[k]}")
check_close(last["all_torque_axis"], last["all_ty"], 1e-15, "box: torque about the y axis")
check(-last["floor_fz"] > 0.5 * M * G and -last["floor_fz"] <= M * G * (1 + 1e-6),
      f"box: the floor carries most of the weight ({-last['floor_fz'] / (M * G)})")
check(abs(p["floor_fx"][0]) + abs(p["all_fz"][0]) == 0.0, "box: no load before contact")

# the same on 2 ranks: the probes' columns bit for bit
with open(os.path.join(work, "box2.nml"), "w") as f:
    f.write(box)
r = subprocess.run([mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", "2", dem,
                    os.path.join(work, "box2.nml")], cwd=work, capture_output=True, text=True,
                   timeout=600)
check(r.returncode == 0, f"box on 2 ranks: exit {r.returncode}: {r.stderr[-2000:]}")
one = open(os.path.join(work, "output", "box", "probes.csv")).read()
two = open(os.path.join(work, "output", "box2", "probes.csv")).read()
check(one == two, "box: probes.csv the same on 1 and 2 ranks")

# 2. a sphere on an oscillating floor (STL square at z = 0), the oscillation from 0.05 s
write_stl("floor.stl", [((-0.02, -0.02, 0), (0.02, -0.02, 0), (0.02, 0.02, 0)),
                        ((-0.02, -0.02, 0), (0.02, 0.02, 0), (-0.02, 0.02, 0))])
R, A, phi, t0 = 0.002, 1.0e-3, 0.4, 0.05
m = sphere_mass(R)
for gamma in (0.5, 3.0):
    w = math.sqrt(gamma * G / A)
    name = f"shake_{gamma}"
    run_dem(dem, write_case(name, f"""&run dt = 5e-6, t_end = 0.4, gravity = 0, 0, -9.81,
     integrator = 'velocity_verlet' /
&output interval = 0.002 /
""" + MATERIALS + f"""&particle id = 1, material = 'glass', radius = {R}, position = 0, 0, {R} /
&wall_mesh file = 'floor.stl', material = 'rigid', name = 'floor',
           oscillation_amplitude = 0, 0, {A}, oscillation_frequency = {w / (2 * math.pi)},
           oscillation_phase = {phi}, oscillation_start = {t0} /
&probe name = 'ball', kind = 'track', id = 1 /
&probe name = 'floor', kind = 'wall_load', wall = 'floor' /
"""), work)
    p = probes(name)
    t = p["time"]
    late = t > 0.1
    tau = t[late] - t0
    zf = A * (np.sin(w * tau + phi) - math.sin(phi))
    gap = p["ball_z"][late] - R - zf
    if gamma < 1:
        check(np.max(np.abs(gap)) < 1e-3 * A, f"shaken below g: the sphere follows the floor "
              f"(height above it - R within {np.max(np.abs(gap)):.3g} m)")
        af = -A * w**2 * np.sin(w * tau + phi)
        err = np.max(np.abs(p["floor_fz"][late] - (-m * (G + af))))
        check(err < 0.02 * m * G, f"shaken below g: the floor's load is m (g - a_f) "
              f"(off by {err / (m * G):.3g} m g)")
    else:
        check(np.max(gap) > 0.1 * A, f"shaken at 3 g: the sphere leaves the floor "
              f"(highest gap {np.max(gap):.3g} m)")

# 3. a floor moved by a velocity table: up by 0.01 m between 0.05 and 0.15 s
name = "lift"
run_dem(dem, write_case(name, """&run dt = 5e-6, t_end = 0.25, gravity = 0, 0, -9.81,
     integrator = 'velocity_verlet' /
&output interval = 0.002 /
""" + MATERIALS + f"""&particle id = 1, material = 'glass', radius = {R}, position = 0, 0, {R} /
&wall_mesh file = 'floor.stl', material = 'rigid', name = 'floor',
           velocity_table_time = 0.05, 0.1, 0.15, velocity_table = 0, 0, 0, 0, 0, 0.2, 0, 0, 0 /
&probe name = 'ball', kind = 'track', id = 1 /
&probe name = 'floor', kind = 'wall_load', wall = 'floor' /
"""), work)
p = probes(name)
t = p["time"]
zf = np.where(t < 0.05, 0.0, np.where(t < 0.1, 2.0 * (t - 0.05)**2,
              np.where(t < 0.15, 0.005 + 0.2 * (t - 0.1) - 2.0 * (t - 0.1)**2, 0.01)))
check(np.max(np.abs(p["ball_z"] - R - zf)[t > 0.02]) < 1e-6,
      "velocity table: the sphere rides on the floor, lifted by the integral")
acc = (t > 0.06) & (t < 0.09)
check(np.max(np.abs(p["floor_fz"][acc] + m * (G + 4.0))) < 0.02 * m * G,
      "velocity table: the load while the floor accelerates is m (g + a)")

# restarts: a run of the shaken floor that also slides on a velocity table and spins on an
# angular velocity table, split at 0.15 s and restarted from its checkpoint, writes the same
# probes.csv (the track and the wall load) and final.csv as the run straight to 0.3 s
def restart_case(name, t_end):
    return write_case(name, f"""&run dt = 5e-6, t_end = {t_end}, gravity = 0, 0, -9.81,
     integrator = 'velocity_verlet' /
&output interval = 0.002 /
""" + MATERIALS + f"""&particle id = 1, material = 'glass', radius = {R}, position = 0.003, 0, {R} /
&wall_mesh file = 'floor.stl', material = 'rigid', name = 'floor',
           oscillation_amplitude = 0, 0, {A}, oscillation_frequency = 11, oscillation_phase = 1,
           velocity_table_time = 0.1, 0.16, 0.25, velocity_table = 0, 0, 0, 0.02, 0, 0, 0, 0, 0,
           angular_velocity_table_time = 0.12, 0.2, angular_velocity_table = 0, 3 /
&probe name = 'ball', kind = 'track', id = 1 /
&probe name = 'floor', kind = 'wall_load', wall = 'floor', axis_point = 0.01, 0, 0 /
""")


run_dem(dem, restart_case("straight", 0.3), work)
run_dem(dem, restart_case("split", 0.15), work)
r = subprocess.run([dem, "--restart", os.path.join(work, "output", "split", "checkpoints",
                                                   "checkpoint_000000030000.h5"),
                    restart_case("split", 0.3)], cwd=work, capture_output=True, text=True,
                   timeout=600)
check(r.returncode == 0 and "restarting from" in r.stdout, f"restart: exit {r.returncode} "
      f"{r.stderr[-2000:]}")
for out in ("probes.csv", "final.csv"):
    check(open(os.path.join(work, "output", "straight", out)).read()
          == open(os.path.join(work, "output", "split", out)).read(), f"restart: {out} the same")
p = probes("straight")
check(np.ptp(p["floor_tz"]) > 0 and np.ptp(p["ball_x"]) > 2e-4,
      "restart: the floor slides and spins under the sphere")

# 4. a small closed drum, radius 0.03 m, 0.02 m long along y, turning at omega about y
n_seg, Rd, L = 32, 0.03, 0.02
tris = []
for k in range(n_seg):
    a0, a1 = 2 * math.pi * k / n_seg, 2 * math.pi * (k + 1) / n_seg
    p0 = (Rd * math.cos(a0), Rd * math.sin(a0))
    p1 = (Rd * math.cos(a1), Rd * math.sin(a1))
    lo0, lo1 = (p0[0], -L / 2, p0[1]), (p1[0], -L / 2, p1[1])
    hi0, hi1 = (p0[0], L / 2, p0[1]), (p1[0], L / 2, p1[1])
    tris += [(lo0, lo1, hi1), (lo0, hi1, hi0), ((0, -L / 2, 0), lo0, lo1), ((0, L / 2, 0), hi1, hi0)]
write_stl("drum.stl", tris)
omega, n_drum, rd = -3.0, 120, 0.0025
name = "drum"
run_dem(dem, write_case(name, f"""&run dt = 1e-5, t_end = 1.2, gravity = 0, 0, -9.81,
     integrator = 'velocity_verlet' /
&output interval = 0.005 /
""" + MATERIALS + f"""&insert n = {n_drum}, material = 'glass', radius_min = {rd}, radius_max = {rd},
        region = 'mesh', mesh_file = 'drum.stl', seed = 3 /
&wall_mesh file = 'drum.stl', material = 'rigid', name = 'drum', rotation_axis = 0, 1, 0,
           angular_velocity = {omega} /
&probe name = 'drum', kind = 'wall_load', wall = 'drum', axis = 0, 1, 0 /
&probe name = 'com', kind = 'center_of_mass' /
"""), work)
p = probes(name)
steady = p["time"] > 0.6
M = n_drum * sphere_mass(rd)
T = np.mean(p["drum_torque_axis"][steady])
T_weight = np.mean(M * G * p["com_glass_x"][steady])
print(f"drum: mean torque {T} N m, the weight's {T_weight} N m, power draw {-omega * T} W")
check(abs(T - T_weight) < 0.05 * abs(T_weight), "drum: the torque balances the weight's")
check(-omega * T > 0, "drum: it draws power")
check(np.max(np.abs(np.mean(p["drum_fz"][steady]) + M * G)) < 0.02 * M * G,
      "drum: it carries the weight")
finish()
