# SPDX-License-Identifier: BSD-3-Clause
"""The instability guard's bounds and messages (doc/theory.md, section 6).

1. A sphere spinning at the start: Chung & Ooi's test 6 sphere (R = 0.1 m, aluminium alloy)
   spinning at 21 rad/s (a rim speed of 2.1 m/s, ten times its 0.2 m/s fall) onto a rigid
   plane, with no &run expected_speed. Its kinetic energy at the start, computed here,
   (1/2) m v^2 + (1/2) (2/5) m R^2 w^2, must lie within the energy guard's bound that
   `dem --check` prints, and the run must end (exit 0): the bound counts the rotational
   energy at the start. The same sphere with &run max_speed = 1 m/s, below its rim speed:
   the speed guard stops it at once (exit 3), and the message calls the speed a rim speed
   and gives w R.
2. Overlaps during a run. A heavy sphere (R = 10 mm, 1000 kg/m^3) resting on a light one
   (1/100 of its density) on a rigid plane, both soft (E = 1 MPa) and started touching at
   rest (at overlaps of 0.45 R), under a gravity chosen so that Hertz's static overlap of the pair,
   F = (4/3) E* sqrt(R*) d^(3/2) with E* = E / (2 (1 - nu^2)), R* = R / 2 and F the heavy
   sphere's weight, is 0.6 R. The run ends (exit 0) with a warning on standard error that
   names the pair, and the final overlap of the pair, read from final.csv, is above half a
   radius (the warning's claim, checked independently). With the gravity that makes the
   static overlap of one sphere on the plane 0.95 R (its weight = (4/3) E/(1 - nu^2)
   sqrt(R) d^(3/2)), the run stops with exit 3 and a message naming the particle and the
   wall (at a row of series.csv, every 0.1 ms here: the sphere falls through the plane
   within 2 ms), and the checkpoint it names holds a state whose overlap is below the stop limit,
   0.9 R (the last good state).
3. The energy balance of a closed case: the elastic, frictionless glass sphere of
   test_stability.py (R = 1 mm, dropped from 0.1 mm onto a rigid plane, e = 1) at 4 times
   the stability bound that `dem --check` prints, with allow_unstable. Each bounce gains
   energy; the run must stop with exit 3 and the energy balance's message, before the
   kinetic and gravitational energy (1/2) m v^2 + m g z, computed here from series.csv, has
   risen from its start by more than a quarter of what the case can set free, and the
   checkpoint the message names holds a state whose energy (with the Hertz energy of its
   overlap, (2/5) (4/3) E/(1 - nu^2) sqrt(R) d^(5/2)) is within that rise. At twice the
   bound the same sphere runs its 0.9 s to the end: the balance guard does not stop a run
   whose energy stays (within 2 %) at or below its start (below it mid-contact, where the
   rows' kinetic and gravitational energy leaves the elastic energy out).
usage: test_guard.py DEM WORKDIR"""
import math
import os
import re
import shutil
import subprocess
import sys

import h5py
import numpy as np

from regression_util import check, check_close, finish, run_dem

dem, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def write(name, text):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    return path


# 1. a spinning sphere
R, rho, v0, w0 = 0.1, 2700.0, 0.2, 21.0
m = rho * 4.0 / 3.0 * math.pi * R**3
energy0 = 0.5 * m * v0**2 + 0.5 * 0.4 * m * R**2 * w0**2
spin = """&run dt = 1e-07, t_end = 0.0012, gravity = 0, 0, 0{extra} /
&output dir = 'output/{name}', interval = 0.0001 /
&material name = 'al_alloy', density = 2700.0, youngs_modulus = 7e10, poisson_ratio = 0.33 /
&material name = 'rigid', rigid = .true. /
&pair materials = 'al_alloy', 'al_alloy', restitution = 0.5, friction = 0.4 /
&pair materials = 'al_alloy', 'rigid', restitution = 0.5, friction = 0.4 /
&particle id = 1, material = 'al_alloy', radius = 0.1, position = 0, 0, 0.10001,
          velocity = 0, 0, -0.2, angular_velocity = 0, -21, 0 /
&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, half_width = 1.0 /
"""
case = write("spin", spin.format(extra="", name="spin"))
r = subprocess.run([dem, "--check", case], cwd=work, capture_output=True, text=True)
bound = re.search(r"energy guard\s+(\S+) J", r.stdout)
check(bound is not None, f"dem --check prints the energy guard: {r.stdout}")
if bound:
    check(float(bound.group(1)) >= energy0,
          f"the energy guard's bound {bound.group(1)} J is below the energy at the start, "
          f"{energy0:.6g} J")
run_dem(dem, case, work)

case = write("spin_guard", spin.format(extra=", max_speed = 1.0", name="spin_guard"))
rc, out, err = run_dem(dem, case, work, expect_rc=3)
said = re.search(r"spins at a rim speed \(angular speed times radius\) of (\S+) m/s", err)
check(said is not None, f"the speed guard's message names a rim speed: {err}")
if said:
    check_close(float(said.group(1)), w0 * R, 1e-3, "the rim speed the message gives")

# 2. overlaps during a run
R, E, nu, rho = 0.01, 1.0e6, 0.3, 1000.0
m = rho * 4.0 / 3.0 * math.pi * R**3
pair_force = 4.0 / 3.0 * E / (2 * (1 - nu**2)) * math.sqrt(R / 2) * (0.6 * R)**1.5
wall_force = 4.0 / 3.0 * E / (1 - nu**2) * math.sqrt(R) * (0.95 * R)**1.5
stack = """&run dt = 2e-06, t_end = {t_end}, gravity = 0, 0, {g}, max_energy = 1e30 /
&output dir = 'output/{name}', interval = {every}, checkpoint_interval = {every} /
&material name = 'heavy', density = {rho}, youngs_modulus = {E}, poisson_ratio = {nu} /
&material name = 'light', density = {rho_light}, youngs_modulus = {E}, poisson_ratio = {nu} /
&material name = 'rigid', rigid = .true. /
&pair materials = 'heavy', 'heavy', restitution = 0.1, friction = 0.3 /
&pair materials = 'heavy', 'light', restitution = 0.1, friction = 0.3 /
&pair materials = 'light', 'light', restitution = 0.1, friction = 0.3 /
&pair materials = 'heavy', 'rigid', restitution = 0.1, friction = 0.3 /
&pair materials = 'light', 'rigid', restitution = 0.1, friction = 0.3 /
{particles}
&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05 /
"""
# (started at rest at overlaps 0.45 R, within the start-up check's half radius, and the
# light sphere at its static overlap on the plane, so that they sink without overshooting)
d_wall = (pair_force / (4.0 / 3.0 * E / (1 - nu**2) * math.sqrt(R)))**(2.0 / 3.0)
z1 = R - d_wall
two = f"""&particle id = 1, material = 'light', radius = 0.01, position = 0, 0, {z1!r} /
&particle id = 2, material = 'heavy', radius = 0.01, position = 0, 0, {z1 + 1.55 * R!r} /"""
case = write("deep_pair", stack.format(t_end=0.1, every=0.002, g=-pair_force / m, rho=rho,
                                       E=E, nu=nu, rho_light=rho / 100, name="deep_pair",
                                       particles=two))
rc, out, err = run_dem(dem, case, work)
warned = r"dem: warning: particles 1 and 2 overlap by more than 0\.50 of the smaller radius"
check(re.search(warned, err) is not None, f"the run warns of the pair's overlap: {err}")
final = np.loadtxt(os.path.join(work, "output", "deep_pair", "final.csv"), delimiter=",",
                   skiprows=1, usecols=(3, 4, 5))
gap = np.linalg.norm(final[1] - final[0])
check(2 * R - gap > 0.5 * R, f"the pair's final overlap {2 * R - gap:.4g} m exceeds half a "
                             f"radius, as warned")

one = f"&particle id = 7, material = 'heavy', radius = 0.01, position = 0, 0, {0.55 * R!r} /"
case = write("deep_wall", stack.format(t_end=0.01, every=1e-4, g=-wall_force / m, rho=rho,
                                       E=E, nu=nu, rho_light=rho, name="deep_wall",
                                       particles=one))
rc, out, err = run_dem(dem, case, work, expect_rc=3)
check("unstable: particle 7 overlaps a wall by more than 0.90 of its radius" in err,
      f"the run stops naming the particle and the wall: {err}")
named = re.search(r"(checkpoints/checkpoint_\d+\.h5)", err)
check(named is not None, f"the message names the last good state's checkpoint: {err}")
if named:
    with h5py.File(os.path.join(work, "output", "deep_wall", named.group(1)), "r") as f:
        z = f["particles/position"][...].reshape(-1, 3)[0, 2] if "particles/position" in f \
            else None
    check(z is not None, "the checkpoint holds the particle's position")
    if z is not None:
        check(R - z < 0.9 * R, f"the named state's overlap {R - z:.4g} m is within the stop "
                               f"limit")
# 3. the energy balance
R, rho, E, nu, g, z0 = 1.0e-3, 2800.0, 48.0e9, 0.2, 9.81, 1.1e-3
m = rho * 4.0 / 3.0 * math.pi * R**3
bounce = """&run dt = {dt!r}, t_end = 0.9, gravity = 0, 0, -9.81, allow_unstable = .true. /
&output dir = 'output/{name}', interval = 1.0e-4 /
&material name = 'glass', density = 2800.0, youngs_modulus = 48.0e9, poisson_ratio = 0.2 /
&material name = 'rigid', rigid = .true. /
&pair materials = 'glass', 'glass', restitution = 1.0, friction = 0.0 /
&pair materials = 'glass', 'rigid', restitution = 1.0, friction = 0.0 /
&particle id = 1, material = 'glass', radius = 1.0e-3, position = 0, 0, 1.1e-3 /
&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.01 /
"""
r = subprocess.run([dem, "--check", write("bounce", bounce.format(dt=1e-7, name="bounce"))],
                   cwd=work, capture_output=True, text=True)
bound = float(re.search(r"stability bound +(\S+) s", r.stdout).group(1))
speed = float(re.search(r"Hertz contact time +\S+ s \(at the largest expected speed, +(\S+) "
                        r"m/s\)", r.stdout).group(1))
room = 0.25 * 0.5 * m * speed**2          # (the sphere starts at rest, touching nothing)


def energy(series):
    return series["kinetic_translational"] + series["potential_gravity"]


rc, out, err = run_dem(dem, write("bounce_x4", bounce.format(dt=4 * bound, name="bounce_x4")),
                       work, expect_rc=3)
check("unstable: the kinetic, elastic and gravitational energy has grown by" in err,
      f"at 4 x the bound the energy balance stops the run: {err}")
s4 = np.genfromtxt(os.path.join(work, "output", "bounce_x4", "series.csv"), delimiter=",",
                   names=True)
check(np.all(energy(s4) - energy(s4)[0] <= room * (1 + 1e-9)),
      f"at 4 x the bound the rows' energy rose by {max(energy(s4) - energy(s4)[0]):.4g} J, "
      f"more than {room:.4g} J")
named = re.search(r"(checkpoints/checkpoint_\d+\.h5)", err)
check(named is not None, f"the message names the last good state's checkpoint: {err}")
if named:
    with h5py.File(os.path.join(work, "output", "bounce_x4", named.group(1)), "r") as f:
        z = f["particles/position"][...].reshape(-1, 3)[0, 2]
        v = f["particles/velocity"][...].reshape(-1, 3)[0]
    d = max(0.0, R - z)
    e = (0.5 * m * v @ v + m * g * z
         + 0.4 * 4.0 / 3.0 * E / (1 - nu**2) * math.sqrt(R) * d**2.5)
    check(e - m * g * z0 <= room * (1 + 1e-9), f"the named state's energy rose by "
                                               f"{e - m * g * z0:.4g} J, more than {room:.4g} J")
run_dem(dem, write("bounce_x2", bounce.format(dt=2 * bound, name="bounce_x2")), work)
s2 = np.genfromtxt(os.path.join(work, "output", "bounce_x2", "series.csv"), delimiter=",",
                   names=True)
check(s2["time"][-1] > 0.9 - 1e-9 and max(energy(s2)) < 1.02 * energy(s2)[0],
      "at twice the bound the sphere bounces to the end without gaining energy")
finish()
