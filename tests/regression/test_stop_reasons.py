# SPDX-License-Identifier: BSD-3-Clause
"""Every run ends with one line that says why it stopped, and settling is judged only once
the particles have had the time to move.

1. The trap of issue 33: 400 spheres inserted at rest in a box 5-10 cm above a floor, with
   stop_kinetic_energy, t_end = 0.03 s and a row of series.csv every step. The first rows
   are nearly at rest, below the threshold; a run that stopped there would be wrong.
   Settling is judged from the time of a free fall across the scene, sqrt(2 h / g) (h =
   10 cm, the walls' extent along gravity, from the floor to the side walls' top: 0.143 s),
   so the run goes on to t_end and says "reached t_end"; series.csv ends at 0.03 s.
2. The same case to t_end = 2 s: the spheres fall (the kinetic energy rises far above the
   threshold), settle, and the run stops at an output row after 0.143 s and before 2 s,
   saying "settled at t = T s (kinetic energy E J ...)" with T and E those of series.csv's
   last row (E below the threshold).
3. Ten spheres dropped from rest through an outlet plane 5 cm below them (no floor): the
   run stops when the last one leaves, saying "the outlets took the last particle out at
   t = T s", with T within one step of the time a free fall takes to bring the lowest
   sphere's centre to the plane, sqrt(2 d / g), and series.csv's last row holds 0
   particles and 10 removed; exit status 0.
4. An inflow of 200 spheres/s from t = 0 to 0.2 s (40 spheres) at rest 5-7 cm above such an
   outlet: the first sphere leaves (a fall of 5 cm: 0.101 s) long before the inflow ends,
   and the run must go on (the outlets have not taken the last particle while more are to
   come); it stops when the last one leaves: at least a fall of 5 cm after the inflow's end,
   at most a fall of 7 cm after its last insertion (within an insertion interval of the end:
   by default the time of a fall of one diameter from rest), with 40 inserted and 40 removed.
5. Settling with an inflow: the box of case 1, empty, and 100 spheres poured in from
   t = 0.2 s to 0.25 s (the box is "at rest" until then), with stop_kinetic_energy = 1e-5 J
   (a layer of spheres without rolling resistance rolls long below 1e-6 J): the run
   may not stop as settled before the last insertion and a fall across the scene (0.143 s)
   after it; it settles before t_end = 2 s with the 100 spheres in the box.
6. The drain of part 3 with a checkpoint every step and a row every 0.01 s: a sphere taken
   out at a step between rows is written out of the checkpoint of that step, and the energy
   guard that checks the state first must not see it either (it was taken out with no
   inertia: 0/0 in the rotational energy, a floating-point trap in the Debug build and a
   NaN otherwise). The run drains as in part 3, and no floating-point exception is
   signalled.
7. The inflow of part 4 with clumps: 200 dimers/s (two spheres of radius 2 mm, centres 2 mm
   apart) for 0.2 s, 40 dimers of 80 members. `removed` counts members while the inflow
   counts clumps: the run must not stop when 40 members have left, but when the last dimer
   leaves, at least a fall of 5 cm after the inflow's end, with 0 particles and 80 removed.
usage: test_stop_reasons.py DEM WORKDIR"""
import math
import os
import re
import shutil
import sys

import numpy as np

from regression_util import check, finish, run_dem

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

G, DT, THRESHOLD = 9.81, 5.0e-5, 1.0e-6
MATERIALS = """\
&material name = 'soft', density = 2500.0, youngs_modulus = 1.0e7, poisson_ratio = 0.2 /
&material name = 'wall', rigid = .true. /
&pair materials = 'soft', 'soft', restitution = 0.3, friction = 0.3 /
&pair materials = 'soft', 'wall', restitution = 0.3, friction = 0.3 /
"""
BOX = """&wall_plane material = 'wall', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.06 /
&wall_plane material = 'wall', point = -0.05, 0, 0.05, normal = 1, 0, 0, half_width = 0.05 /
&wall_plane material = 'wall', point = 0.05, 0, 0.05, normal = -1, 0, 0, half_width = 0.05 /
&wall_plane material = 'wall', point = 0, -0.05, 0.05, normal = 0, 1, 0, half_width = 0.05 /
&wall_plane material = 'wall', point = 0, 0.05, 0.05, normal = 0, -1, 0, half_width = 0.05 /
"""


def case(name, body):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(body)
    return path


def series(name):
    return np.loadtxt(os.path.join(work, "output", name, "series.csv"), delimiter=",",
                      skiprows=1, ndmin=2)


def last_line(out):
    lines = [line for line in out.splitlines() if line.startswith("dem: ")]
    return lines[-1] if lines else ""


def pour(name, t_end, interval):
    return case(name, f"""&run dt = {DT}, t_end = {t_end}, stop_kinetic_energy = {THRESHOLD} /
&output dir = 'output/{name}', interval = {interval} /
{MATERIALS}&insert n = 400, material = 'soft', radius_min = 0.002, region = 'box',
    box_min = -0.045, -0.045, 0.05, box_max = 0.045, 0.045, 0.1, seed = 3 /
{BOX}""")


# 1. at rest at the first row, t_end before the settling time: the run goes to t_end
rc, out, err = run_dem(dem, pour("trap", 0.03, DT), work)
s = series("trap")
line = last_line(out)
check(re.search(r"dem: done: reached t_end = 3\.00000E-02 s; outputs in output/trap", line),
      f"the trap: the last line says t_end was reached: {line!r}")
check(abs(s[-1, 0] - 0.03) < 1e-12 and s[1, 6] + s[1, 7] < THRESHOLD,
      f"the trap: below the threshold after a step ({s[1, 6]:.3g} J), series.csv ends at "
      f"t_end ({s[-1, 0]:.6g} s)")

# 2. the same case to 1 s: settles after the fall time and says so
t_settle = math.sqrt(2.0 * 0.1 / G)
rc, out, err = run_dem(dem, pour("settle", 2.0, 0.01), work)
s = series("settle")
line = last_line(out)
m = re.search(r"dem: done: settled at t = (\S+) s \(kinetic energy (\S+) J, below "
              r"stop_kinetic_energy = (\S+) J\)", line)
check(m is not None, f"settling: the last line says the run settled: {line!r}")
if m:
    t, e = float(m.group(1)), float(m.group(2))
    check(t_settle <= t < 2.0, f"settled at {t} s, after the fall time {t_settle:.4f} s and "
          "before t_end")
    check(abs(t - s[-1, 0]) < 1e-9 and abs(e - (s[-1, 6] + s[-1, 7])) <= 1e-5 * e + 1e-15
          and e < THRESHOLD, f"the line's time and energy are series.csv's last row "
          f"({s[-1, 0]:.6g} s, {s[-1, 6] + s[-1, 7]:.5g} J)")
    check(s[:, 6].max() > 1e3 * THRESHOLD, "the spheres moved before they settled")

# 3. dropped through an outlet: stops when the last sphere leaves
D = 0.05
spheres = "".join(f"&particle material = 'soft', radius = 0.002, position = {0.005 * k - 0.0225}, "
                  f"0, {0.1 + 0.001 * k} /\n" for k in range(10))
path = case("drain", f"""&run dt = {DT}, t_end = 1.0, expected_speed = 1.5 /
&output dir = 'output/drain', interval = 0.01 /
{MATERIALS}{spheres}&outlet region = 'plane', point = 0, 0, {0.1 + 0.009 - D}, normal = 0, 0, -1 /
""")
rc, out, err = run_dem(dem, path, work)
s = series("drain")
line = last_line(out)
m = re.search(r"dem: done: the outlets took the last particle out at t = (\S+) s", line)
check(rc == 0 and m is not None, f"drained: exit 0 and the last line says so: {rc}, {line!r}")
if m:
    t = float(m.group(1))
    t_fall = math.sqrt(2.0 * D / G)      # the highest sphere (last to leave) falls D
    check(abs(t - t_fall) <= 2 * DT, f"the last sphere left at {t} s, a free fall of {D} m "
          f"takes {t_fall:.6f} s")
    check(s[-1, 2] == 0 and s[-1, 3] == 10 and abs(s[-1, 0] - t) < 1e-9,
          f"series.csv's last row: 0 particles, 10 removed, at that time: {s[-1, :4]}")

# 6. the same with a checkpoint at every step (the guard before it: no sphere taken out)
path = case("drain_checkpoints", f"""&run dt = {DT}, t_end = 1.0, expected_speed = 1.5 /
&output dir = 'output/drain_checkpoints', interval = 0.01, checkpoint_interval = {DT} /
{MATERIALS}{spheres}&outlet region = 'plane', point = 0, 0, {0.1 + 0.009 - D}, normal = 0, 0, -1 /
""")
rc, out, err = run_dem(dem, path, work)
line = last_line(out)
check(rc == 0 and "the outlets took the last particle out" in line and "IEEE" not in out + err,
      f"drained with a checkpoint every step: exit 0, the last line says so, no "
      f"floating-point exception: {rc}, {line!r}, {err[-300:]!r}")

# 4. an inflow through an outlet: not emptied while spheres are to come
path = case("inflow", f"""&run dt = {DT}, t_end = 1.0, expected_speed = 1.5 /
&output dir = 'output/inflow', interval = 0.001 /
{MATERIALS}&insert material = 'soft', radius_min = 0.002, region = 'box', rate = 200, start = 0,
    end = 0.2, box_min = -0.02, -0.02, 0.05, box_max = 0.02, 0.02, 0.07, seed = 5 /
&outlet region = 'plane', point = 0, 0, 0, normal = 0, 0, -1 /
""")
rc, out, err = run_dem(dem, path, work)
s = series("inflow")
line = last_line(out)
m = re.search(r"dem: done: the outlets took the last particle out at t = (\S+) s", line)
check(rc == 0 and m is not None, f"inflow drained: exit 0 and the last line says so: {rc}, "
      f"{line!r}, {err[-300:]!r}")
if m:
    t = float(m.group(1))
    t_first = math.sqrt(2.0 * 0.05 / G)
    t_every = math.sqrt(2.0 * 0.004 / G)
    t_last = 0.2 + t_every + math.sqrt(2.0 * 0.07 / G)
    check(s[:, 3].max() > 0 and s[s[:, 3] > 0, 0].min() < 0.2,
          f"a sphere left before the inflow ended (a fall of 5 cm takes {t_first:.4f} s)")
    check(0.2 + t_first <= t <= t_last + 2 * DT, f"the last sphere left at {t} s: a fall of "
          f"5 cm after the inflow's end and before {t_last:.4f} s")
    check(s[-1, 2] == 0 and s[-1, 3] == 40, f"series.csv's last row: 0 particles, 40 removed: "
          f"{s[-1, :4]}")
# 7. an inflow of clumps through an outlet: emptied when the last clump's members leave
path = case("inflow_clumps", f"""&run dt = {DT}, t_end = 1.0, expected_speed = 1.5 /
&output dir = 'output/inflow_clumps', interval = 0.001 /
{MATERIALS}&clump_template name = 'dimer', material = 'soft',
    members = -0.001, 0, 0, 0.002,   0.001, 0, 0, 0.002 /
&insert template = 'dimer', region = 'box', rate = 200, start = 0, end = 0.2,
    box_min = -0.02, -0.02, 0.05, box_max = 0.02, 0.02, 0.07, seed = 5 /
&outlet region = 'plane', point = 0, 0, 0, normal = 0, 0, -1 /
""")
rc, out, err = run_dem(dem, path, work)
s = series("inflow_clumps")
line = last_line(out)
m = re.search(r"dem: done: the outlets took the last particle out at t = (\S+) s", line)
check(rc == 0 and m is not None, f"clump inflow drained: exit 0 and the last line says so: "
      f"{rc}, {line!r}, {err[-300:]!r}")
if m:
    t = float(m.group(1))
    check(t >= 0.2 + math.sqrt(2.0 * 0.05 / G), f"the last dimer left at {t} s, a fall of "
          "5 cm after the inflow's end or later")
    check(s[-1, 2] == 0 and s[-1, 3] == 80, f"series.csv's last row: 0 particles, 80 members "
          f"removed: {s[-1, :4]}")
# 5. settling with an inflow: not before its last insertion and a fall after it
path = case("inflow_settle", f"""&run dt = {DT}, t_end = 2.0, stop_kinetic_energy = 1e-5 /
&output dir = 'output/inflow_settle', interval = 0.01 /
{MATERIALS}&insert material = 'soft', radius_min = 0.002, region = 'box', rate = 2000,
    start = 0.2, end = 0.25, box_min = -0.045, -0.045, 0.05, box_max = 0.045, 0.045, 0.1,
    seed = 7 /
{BOX}""")
rc, out, err = run_dem(dem, path, work)
s = series("inflow_settle")
line = last_line(out)
m = re.search(r"dem: done: settled at t = (\S+) s", line)
check(rc == 0 and m is not None, f"inflow settled: the last line says so: {rc}, {line!r}")
if m:
    t = float(m.group(1))
    check(0.25 + t_settle <= t < 2.0 and s[-1, 2] == 100,
          f"settled at {t} s (not before {0.25 + t_settle:.4f} s) with 100 spheres: {s[-1, :4]}")
finish()
