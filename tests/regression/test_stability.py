# SPDX-License-Identifier: BSD-3-Clause
"""Numerical stability on hard cases, for both integrators.

1. An elastic, frictionless sphere bouncing on a rigid plane for about 100 bounces keeps
   its energy (kinetic + gravitational, measured in free flight). The bounds are derived in
   doc/theory.md, section 5: between contacts the integrator conserves a modified energy,
   off the true one by at most
     symplectic Euler (first order):  B = h m g v_imp
     velocity Verlet (second order):  B = h^2 (S_max v_imp^2 / 12 + F_max^2 / (24 m))
   (v_imp = sqrt(2 g h_drop); F_max, S_max = 2 E* sqrt(R d_max): Hertz peak force and
   stiffness at v_imp). The Hertz force is not smooth where contact begins and ends; there a
   step can gain or lose at most the elastic energy of one step's travel,
   U_h = (8/15) E* sqrt(R) (v_imp h)^(5/2), so each bounce changes the energy by at most
   2 U_h + 2 B, and N bounces by at most 2 N U_h + B. These per-bounce changes have no
   preferred sign (no drift): by Hoeffding's inequality their mean over N bounces stays
   within 2 U_h sqrt(2 ln(2/p) / N) with probability 1 - p; we take p = 1e-6.
2. Two spheres meeting head-on at +-100 m/s: the state stays finite, the largest overlap
   is Hertz theory's, and the motion stays exactly mirror-symmetric.
3. A loaded resting bed of soft spheres (600 of 4 mm, E = 1 MPa: the soft silos' M2, in a
   40 mm box under 87 m/s^2, whose bottom then bears about what the full soft silo's
   0.21 m bed bears under g). Settled, then run on for 0.05 s from its final state: at the
   soft silos' step, 50 us, it stays at rest (its spheres' rms spin rate
   sqrt(2 K_rot / (N I)) ends below its start and below 1 rad/s); at 100 us, which dem's
   bound for one contact (about 104 us here) admits, the same bed rattles: its spheres spin
   up to more than 10 rad/s within 5 ms and stay so (doc/results/benchmarks.md, the soft silos'
   step). The second run shows that the first check can fail. dem warns of it: 100 us is
   above the step for loaded packings (0.6 of the bound) that dem prints, 50 us below it.
4. A size ratio of 20: 3000 spheres of radius 0.25 mm settling on a plane while 6 of 5 mm
   (8000 times heavier) fall onto them, E = 5e7 Pa. The bound's contacts include each
   material's smallest sphere squeezed by its largest (doc/theory.md, section 6): a run at
   0.9 of the bound that `dem --check` prints completes, its kinetic + gravitational energy
   never above its start (the spheres start apart and at rest or falling: what the contacts
   store as elastic energy or dissipate comes from it; a blow-up adds energy). At 3.5 us,
   0.85 of the bound of the two-body contacts alone (4.11 us), the bound refuses dt, and with
   allow_unstable the instability guard stops the run (exit 3): the check above can fail.
   (At 3 us the blow-up within the run is a matter of chance: a change in the last bits of
   the contact law, issue 28's fifth step, let that run finish.)
5. The energy guard: the head-on glass spheres of part 2 at +-25 m/s, with restitution 1,
   run with allow_unstable at 2 and 5 times the stability bound that `dem --check` prints.
   Their speeds stay below the speed guard's bound (250 m/s: 10 v), but the overlap
   overshoots and the elastic energy grows past the energy guard's bound, M v^2
   (M the mass of both, v = 25 m/s, the expected speed: twice the kinetic energy at the
   start): the run stops with exit 3 and a message naming the energy guard, and names a
   checkpoint. Its state, read here, has a kinetic + elastic energy (the Hertz spring
   energy (2/5) (4/3) E* sqrt(R*) d^(5/2) from its overlap, computed here) within the
   bound; run on from it at a twentieth of the bound, the spheres rebound with that
   energy (e = 1: within 1e-3), so the state the guard names is one a smaller step can
   continue. Before the energy guard, the named state was mid-contact at an overshot
   overlap and such a continuation rebounded several times faster than it came in.
usage: test_stability.py DEM WORKDIR"""
import math
import os
import re
import shutil
import subprocess
import sys

import h5py
import numpy as np

from regression_util import HERE, check, check_close, finish, run_dem
import chung_ooi as co

dem, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)    # (an output folder of another case is refused)
os.makedirs(work)


def variant(case, integrator):
    """Copy of a case in WORKDIR with another integrator and its own output directory."""
    stem = os.path.splitext(os.path.basename(case))[0] + "_" + integrator
    text = open(case).read().replace("'symplectic_euler'", f"'{integrator}'")
    path = os.path.join(work, stem + ".nml")
    with open(path, "w") as f:
        f.write(text)
    return path, os.path.join(work, "output", stem)


# 1. elastic bouncing
R, rho, E, nu, g, drop = 1.0e-3, 2800.0, 48.0e9, 0.2, 9.81, 1.0e-4
m = co.sphere_mass(rho, R)
estar = E / (1.0 - nu**2)
v_imp = math.sqrt(2.0 * g * drop)
dmax, fmax, tc = co.hertz(m, R, estar, v_imp)
smax = 2.0 * estar * math.sqrt(R * dmax)
h = 5.0e-7
u_h = 8.0 / 15.0 * estar * math.sqrt(R) * (v_imp * h)**2.5
smooth = {"symplectic_euler": h * m * g * v_imp,
          "velocity_verlet": h**2 * (smax * v_imp**2 / 12.0 + fmax**2 / (24.0 * m))}
for integrator, b in smooth.items():
    case, outdir = variant(os.path.join(HERE, "cases", "bounce_elastic.nml"), integrator)
    run_dem(dem, case, work)
    s = co.read_csv(os.path.join(outdir, "series.csv"))
    z = s["potential_gravity"] / (m * g)
    free = z > R                       # the sphere is off the plane (at z = 0)
    energy = s["kinetic_translational"] + s["kinetic_rotational"] + s["potential_gravity"]
    # one energy per flight: the median of its samples
    edges = np.flatnonzero(np.diff(free.astype(int)))
    flights = [seg for seg in np.split(np.arange(len(free)), edges + 1) if free[seg[0]]]
    e_flight = np.array([np.median(energy[seg]) for seg in flights])
    n = len(flights) - 1
    steps = np.diff(e_flight)
    total = np.abs(energy[free] - energy[0]).max()
    drift = abs(steps.mean())
    drift_bound = 2.0 * u_h * math.sqrt(2.0 * math.log(2.0 / 1e-6) / n)
    print(f"{integrator}: {n} bounces; max |E - E0| = {total:.3e} J (bound "
          f"{2 * n * u_h + b:.3e}); largest change in a bounce {np.abs(steps).max():.3e} J "
          f"(bound {2 * u_h + 2 * b:.3e}); mean change {drift:.3e} J (bound {drift_bound:.3e})")
    check(n >= 95, f"{integrator}: only {n} bounces")
    check(total <= 2 * n * u_h + b, f"{integrator}: energy error {total:.3e} J over the run")
    check(np.abs(steps).max() <= 2 * u_h + 2 * b, f"{integrator}: energy change in one bounce")
    check(drift <= drift_bound, f"{integrator}: energy drifts by {drift:.3e} J per bounce")

# 2. head-on at 100 m/s
m1 = co.sphere_mass(2800.0, 0.01)
for integrator in ("symplectic_euler", "velocity_verlet"):
    case, outdir = variant(os.path.join(HERE, "cases", "head_on_100.nml"), integrator)
    run_dem(dem, case, work)
    f = co.read_csv(os.path.join(outdir, "final.csv"))
    c = co.read_csv(os.path.join(outdir, "contact.csv"))
    check(np.all(np.isfinite(c["overlap"])), f"{integrator}: non-finite state")
    dmax_theory = co.hertz(m1 / 2.0, 0.005, 48.0e9 / (2.0 * (1.0 - 0.2**2)), 200.0)[0]
    check_close(c["overlap"].max(), dmax_theory, 1e-2, f"{integrator}: maximum overlap")
    check(c["overlap"][-1] < 0.0, f"{integrator}: the spheres did not separate")
    for key in ("x", "vx"):
        check(f[key][0] == -f[key][1], f"{integrator}: {key} not mirror-symmetric: "
              f"{f[key][0]!r} vs {f[key][1]!r}")
    for key in ("y", "z", "vy", "vz", "wx", "wy", "wz"):
        check(np.all(f[key] == 0.0), f"{integrator}: {key} left the axis of symmetry")
    check_close(f["vx"][1], 100.0, 1e-3, f"{integrator}: elastic rebound speed")

def box_walls(side):
    """The floor z = 0 and four side walls of a square box of `side` m, of material 'wall'."""
    planes = [("0, 0, 0", "0, 0, 1"), ("0, 0, 0", "1, 0, 0"), (f"{side}, 0, 0", "-1, 0, 0"),
              ("0, 0, 0", "0, 1, 0"), (f"0, {side}, 0", "0, -1, 0")]
    return "".join(f"&wall_plane material = 'wall', point = {p}, normal = {n}, "
                   "half_width = 0.1 /\n" for p, n in planes)


# 3. a loaded resting bed of soft spheres
BED = """&material name = 'soft', density = 2000, youngs_modulus = 1e6, poisson_ratio = 0.2 /
&material name = 'wall', density = 7200, youngs_modulus = 2.1e11, poisson_ratio = 0.2 /
&pair materials = 'soft', 'soft', restitution = 0.4, friction = 0.4 /
&pair materials = 'soft', 'wall', restitution = 0.4, friction = 0.2 /
""" + box_walls(0.04)
N, R_BED = 600, 0.002
inertia = 0.4 * co.sphere_mass(2000.0, R_BED) * R_BED**2


def bed_case(name, run_line, source):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(run_line + f"&output dir = 'output/{name}', interval = 0.005 /\n" + BED + source)
    return path


run_dem(dem, bed_case("bed_fill", "&run dt = 5e-05, t_end = 0.4, gravity = 0, 0, -87, "
                      "stop_kinetic_energy = 6e-08 /\n",
                      f"&insert n = {N}, material = 'soft', radius_min = {R_BED}, radius_max = "
                      f"{R_BED}, region = 'box', box_min = 0.002, 0.002, 0.002, box_max = "
                      "0.038, 0.038, 0.098, seed = 1 /\n"), work)
fill = co.read_csv(os.path.join(work, "output", "bed_fill", "series.csv"))
check(fill["time"][-1] < 0.4 - 1e-9, f"bed: not settled by 0.4 s (t = {fill['time'][-1]})")
settled = os.path.join(work, "output", "bed_fill", "final.csv")
for dt, quiet in (("5e-05", True), ("1e-04", False)):
    rc, out, err = run_dem(dem, bed_case(f"bed_dt{dt}", f"&run dt = {dt}, t_end = 0.05, "
                                         "gravity = 0, 0, -87 /\n",
                                         f"&particle_file file = '{settled}' /\n"), work)
    warned = "warning: dt exceeds the loaded packings' step" in out
    check(warned != quiet, f"bed at dt {dt}: the loaded packings' warning "
          + ("missing" if not warned else "given at a step where the bed rests"))
    s = co.read_csv(os.path.join(work, "output", f"bed_dt{dt}", "series.csv"))
    spin = np.sqrt(2.0 * s["kinetic_rotational"] / (N * inertia))     # rms rate [rad/s]
    print(f"bed at dt {dt} (no allow_unstable): rms spin {spin[0]:.3g} rad/s at the start, "
          f"{spin[1:].min():.3g}-{spin[1:].max():.3g} after, {spin[-1]:.3g} at the end")
    if quiet:
        check(spin[-1] < spin[0] and spin[-1] < 1.0, f"bed at dt {dt}: does not stay at rest "
              f"(rms spin {spin[0]:.3g} -> {spin[-1]:.3g} rad/s)")
    else:
        check(spin[1:].min() > 10.0, f"bed at dt {dt}: did not rattle (rms spin "
              f"{spin[1:].min():.3g} rad/s): the check above cannot tell")
# 4. a size ratio of 20
RATIO = """&output dir = 'output/{name}', interval = 0.001 /
&material name = 'soft', density = 2500, youngs_modulus = 5e7, poisson_ratio = 0.25 /
&material name = 'wall', density = 7800, youngs_modulus = 2e11, poisson_ratio = 0.3 /
&pair materials = 'soft', 'soft', restitution = 0.5, friction = 0.5 /
&pair materials = 'soft', 'wall', restitution = 0.5, friction = 0.5 /
""" + box_walls(0.02) + """&insert n = 3000, material = 'soft', radius_min = 2.5e-4, region = 'box',
        box_min = 0.0003, 0.0003, 0.0003, box_max = 0.0197, 0.0197, 0.003, seed = 1 /
&insert n = 6, material = 'soft', radius_min = 5e-3, region = 'box', box_min = 0, 0, 0.005,
        box_max = 0.02, 0.02, 0.04, velocity = 0, 0, -0.3, seed = 2 /
"""


def ratio_case(name, dt, extra=""):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(f"&run dt = {dt!r}, t_end = 0.03, gravity = 0, 0, -9.81{extra} /\n"
                + RATIO.format(name=name))
    return path


r = subprocess.run([dem, "--check", ratio_case("ratio_check", 1e-6)], capture_output=True,
                   text=True)
bound = float(re.search(r"stability bound +(\S+) s", r.stdout).group(1))
print(f"size ratio 20: stability bound {bound:.4g} s")
run_dem(dem, ratio_case("ratio_stable", 0.9 * bound), work)
s = co.read_csv(os.path.join(work, "output", "ratio_stable", "series.csv"))
energy = s["kinetic_translational"] + s["kinetic_rotational"] + s["potential_gravity"]
rise = energy.max() / energy[0] - 1.0
print(f"size ratio 20 at 0.9 of the bound: energy {energy[0]:.6g} J at the start, at most "
      f"{energy.max():.6g} J, {energy[-1]:.4g} J at the end")
check(rise <= 1e-12, f"size ratio 20 at 0.9 of the bound: the energy rose above its start "
      f"by {rise:.3g} of it")
rc, out, err = run_dem(dem, ratio_case("ratio_refused", 3.5e-6), work, expect_rc=2)
check(rc == 2 and "exceeds the stability bound" in out + err,
      "size ratio 20 at 3.5 us: not refused by the bound")
rc, out, err = run_dem(dem, ratio_case("ratio_unstable", 3.5e-6, ", allow_unstable = .true."),
                       work, expect_rc=3)
check(rc == 3 and "unstable" in out + err,
      "size ratio 20 at 3.5 us with allow_unstable: the guard did not stop it")

# 5. the energy guard
HEAD_ON = """&material name = 'glass', density = 2800.0, youngs_modulus = 48.0e9, poisson_ratio = 0.2 /
&pair materials = 'glass', 'glass', restitution = 1.0, friction = 0.35 /
"""
V5, R5 = 25.0, 0.01
M5 = 2.0 * co.sphere_mass(2800.0, R5)
ESTAR5 = 48.0e9 / (2.0 * (1.0 - 0.2**2))


def head_on_case(name, dt, t_end, particles, extra=""):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(f"&run dt = {dt!r}, t_end = {t_end!r}, gravity = 0, 0, 0, expected_speed = "
                f"{V5}{extra} /\n&output dir = 'output/{name}', interval = 1e-5 /\n" + HEAD_ON
                + "".join(f"&particle id = {k + 1}, material = 'glass', radius = {R5}, "
                          f"position = {x!r}, 0, 0, velocity = {v!r}, 0, 0 /\n"
                          for k, (x, v) in enumerate(particles)))
    return path


start5 = [(-0.0105, V5), (0.0105, -V5)]
r = subprocess.run([dem, "--check", head_on_case("head_on_check", 1e-7, 2e-4, start5)],
                   capture_output=True, text=True)
bound5 = float(re.search(r"stability bound +(\S+) s", r.stdout).group(1))
guard5 = float(re.search(r"energy guard +(\S+) J", r.stdout).group(1))
check_close(guard5, M5 * V5**2, 1e-4, "energy guard: the bound M v^2 that --check prints")
for k in (2, 5):
    rc, out, err = run_dem(dem, head_on_case(f"head_on_x{k}", k * bound5, 2e-4, start5,
                                             ", allow_unstable = .true."), work, expect_rc=3)
    m = re.search(r"the kinetic and elastic energy, (\S+) J, exceeds the bound (\S+) J "
                  r"\(&run max_energy\).* is in (\S+)$", err.strip())
    check(m is not None, f"energy guard at {k} x the bound: not stopped by it: {err!r}")
    if m is None:
        continue
    check_close(float(m.group(2)), guard5, 1e-4, f"energy guard at {k} x the bound: its bound")
    with h5py.File(os.path.join(work, m.group(3)), "r") as f:
        t_good = float(f["time"][()])
        x = f["particles"]["position"][()][:, 0]
        v = f["particles"]["velocity"][()][:, 0]
    d = max(0.0, 2.0 * R5 - (x[1] - x[0]))
    e_good = 0.5 * (M5 / 2.0) * (v**2).sum() \
        + 0.4 * (4.0 / 3.0) * ESTAR5 * math.sqrt(R5 / 2.0) * d**2.5
    print(f"energy guard at {k} x the bound: stopped, the named state at t = {t_good:.4g} s "
          f"has overlap {d:.3g} m and energy {e_good:.6g} J (bound {guard5:.6g} J)")
    check(e_good <= guard5, f"energy guard at {k} x the bound: the named state's energy "
                            f"{e_good:.6g} J is above the bound {guard5:.6g} J")
    run_dem(dem, head_on_case(f"head_on_x{k}_on", bound5 / 20.0, 2e-4,
                              list(zip(x.tolist(), v.tolist()))), work)
    f = co.read_csv(os.path.join(work, "output", f"head_on_x{k}_on", "final.csv"))
    e_end = 0.5 * (M5 / 2.0) * (f["vx"]**2).sum()
    check(f["x"][1] - f["x"][0] > 2.0 * R5, f"energy guard at {k} x the bound: the "
                                             "continued spheres did not separate")
    check_close(e_end, e_good, 1e-3, f"energy guard at {k} x the bound: the energy after "
                                     "the continued rebound")
finish()
