# SPDX-License-Identifier: BSD-3-Clause
"""Rolling resistance and cohesion in whole runs (doc/theory.md, section 15).

1. A sphere rolling on a rigid plane (v0 = 0.1 m/s, w0 = v0 / R) with the constant
   directional torque (CDT) of rolling_friction mu_r: it decelerates at a = 5/7 mu_r g
   (torque mu_r R m g against the translational and rotational inertia, I = 2/5 m R^2) and
   stops after s = 7 v0^2 / (10 mu_r g); afterwards it stays where it stopped.
2. The same with EPSD2: while it rolls, the spring torque is at its limit mu_r R |F_n|, so
   the deceleration is the same (not more: the limit holds) and so is the distance, to the
   spring's small elastic roll-back; it then stays at rest, held by the spring.
3. A restart in the middle of an EPSD2 roll (the rolling spring in the checkpoint's wall
   history, after the slots' tangential springs) ends bit for bit where the straight run
   ends; and the box bed of the checkpoint tests with EPSD2 rolling resistance and sJKR
   cohesion between the particles and with the walls (pair and wall springs, cohesive
   forces) gives the same final state and checkpoint on 1 and 2 ranks, and restarted
   mid-run.
usage: test_rolling.py DEM WORKDIR MPIEXEC"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

from regression_util import check, check_close, finish
import checkpoint_util as cu

dem, work, mpiexec = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

R, RHO, E, NU, G = 0.005, 2500.0, 1.0e7, 0.2, 9.81
MUR, V0, DT = 0.05, 0.1, 2.0e-5
m = RHO * 4.0 / 3.0 * np.pi * R**3
estar = E / (1 - NU**2)                     # against a rigid plane
d0 = (m * G / (4.0 / 3.0 * estar * np.sqrt(R)))**(2.0 / 3.0)    # resting Hertz overlap
A = 5.0 / 7.0 * MUR * G
S = V0**2 / (2 * A)                          # = 7 v0^2 / (10 mu_r g)
T_STOP = V0 / A


def run(*args, ranks=1, expect=0):
    cmd = [dem, *args]
    if ranks > 1:
        cmd = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] + cmd
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=600)
    if r.returncode != expect:
        print(r.stdout, r.stderr)
    check(r.returncode == expect, f"dem {' '.join(args)} on {ranks}: exit {r.returncode}")
    return r


def roll_case(name, model, t_end, output=""):
    with open(os.path.join(work, name + ".nml"), "w") as f:
        f.write(f"""&run dt = {DT}, t_end = {t_end}, gravity = 0, 0, -{G} /
&output dir = 'out_{name}', interval = 1.0e-3{output} /
&material name = 'ball', density = {RHO}, youngs_modulus = {E}, poisson_ratio = {NU} /
&material name = 'rigid', rigid = .true. /
&pair materials = 'ball', 'ball', restitution = 0.5, friction = 0.5 /
&pair materials = 'ball', 'rigid', restitution = 0.5, friction = 0.5,
      rolling_friction = {MUR}, rolling_model = '{model}' /
&particle id = 1, material = 'ball', radius = {R}, position = 0, 0, {R - d0!r},
          velocity = {V0}, 0, 0, angular_velocity = 0, {V0 / R!r}, 0 /
&wall_plane material = 'rigid', point = 0.05, 0, 0, normal = 0, 0, 1, half_width = 0.1 /
&probe name = 'p', kind = 'track', id = 1 /
""")
    return name + ".nml"


def track(name):
    return np.genfromtxt(os.path.join(work, f"out_{name}", "probes.csv"), delimiter=",",
                         names=True)


# 1, 2: the distance, the deceleration, at rest afterwards
for model, rtol in (("cdt", 0.002), ("epsd2", 0.002)):
    run(roll_case(model, model, 1.6 * T_STOP))
    p = track(model)
    t, x, vx = p["time"], p["p_x"], p["p_vx"]
    rolling = (t > 0.1 * T_STOP) & (t < 0.8 * T_STOP)
    slope = np.polyfit(t[rolling], vx[rolling], 1)[0]
    check_close(-slope, A, rtol, f"{model}: deceleration 5/7 mu_r g while rolling")
    check_close(x[-1], S, rtol, f"{model}: stopping distance 7 v0^2 / (10 mu_r g)")
    after = t > 1.2 * T_STOP
    check(np.ptp(x[after]) < 1e-6 * S / 0.01, f"{model}: at rest after stopping "
          f"(moves {np.ptp(x[after]):.3g} m)")
    check(np.all(np.abs(p["p_wy"][after]) < 1e-2), f"{model}: no rotation after stopping")

# 3. restart mid-roll, exact
N = 50 * int(round(0.5 * T_STOP / DT / 50))      # a row of the series at the restart
CK = ", checkpoint_interval = %r" % (N * DT)
run(roll_case("straight", "epsd2", 2 * N * DT, CK))
run(roll_case("split", "epsd2", N * DT, CK))
ckpt = os.path.join(work, "out_split", "checkpoints", f"checkpoint_{N:012d}.h5")
with h5py.File(ckpt) as f:
    h = f["state/wall_contact_history"][()]
    # (particle, column, 3): the 8 slots' displacements, then their rolling springs
    check(h.shape[1] == 16 and np.any(h[:, 8:, :] != 0),
          f"the checkpoint holds the rolling spring ({h.shape})")
roll_case("split", "epsd2", 2 * N * DT, CK)
run("--restart", ckpt, "split.nml")
for out in ("final.csv", "probes.csv", "series.csv"):
    with open(os.path.join(work, "out_straight", out), "rb") as a, \
         open(os.path.join(work, "out_split", out), "rb") as b:
        check(a.read() == b.read(), f"restart mid-roll: {out} the same")

# the box bed with EPSD2 and cohesion: 1 and 2 ranks, and a restart
PAIR = "restitution = 0.3, friction = 0.3 /"
MORE = ("restitution = 0.3, friction = 0.3, rolling_friction = 0.2, rolling_model = 'epsd2', "
        "cohesion_energy_density = 2.0e4 /")
NB, DTB = 1500, 2.0e-5


def box(name, t_end):
    path = os.path.join(work, name + ".nml")
    cu.write_box_case(path, os.path.join(work, f"out_{name}"), t_end, dt=DTB, n=150,
                      interval=NB * DTB / 10,
                      output=", checkpoint_interval = %r" % (NB * DTB))
    with open(path) as f:
        text = f.read().replace(PAIR, MORE)
    with open(path, "w") as f:
        f.write(text)
    return name + ".nml"


run(box("box1", 2 * NB * DTB))
run(box("box2", 2 * NB * DTB), ranks=2)
run(box("boxr", NB * DTB))
box("boxr", 2 * NB * DTB)
run("--restart", os.path.join(work, "out_boxr", "checkpoints", f"checkpoint_{NB:012d}.h5"),
    "boxr.nml")
last = f"checkpoint_{2 * NB:012d}.h5"
with h5py.File(os.path.join(work, "out_box1", "checkpoints", last)) as a:
    pairs = a["state/pair_history"][()]
    check(pairs.shape[-1] == 6 and np.any(pairs[:, 3:] != 0) if pairs.ndim == 2 else False,
          f"box: pair history with rolling springs ({pairs.shape})")
    names = [n for n in cu.datasets(a) if n not in ("case/input", "state/checkpoint_step")
             and not n.startswith("state/snapshot_")]      # (no snapshots: bookkeeping)
    for other in ("box2", "boxr"):
        with h5py.File(os.path.join(work, f"out_{other}", "checkpoints", last)) as b:
            differ = [n for n in names if n in b and not cu.same_bits(a[n][()], b[n][()])]
            check(not differ, f"box, {other}: checkpoint datasets that differ: {differ}")
for other in ("box2", "boxr"):
    with open(os.path.join(work, "out_box1", "final.csv"), "rb") as a, \
         open(os.path.join(work, f"out_{other}", "final.csv"), "rb") as b:
        check(a.read() == b.read(), f"box, {other}: final.csv the same as on 1 rank")
finish()
