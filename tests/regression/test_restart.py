# SPDX-License-Identifier: BSD-3-Clause
"""Checkpoint and restart continue a run bit for bit.

1. For both integrators, a run of 2N steps straight and a run of N steps, then --restart from
   its final checkpoint with t_end doubled, end in the same state to the last bit: every
   particle's position, velocity, angular velocity, force and torque, the particle-particle
   and particle-wall contact history, the wall pose, and series.csv, probes.csv, final.csv
   and the snapshots. The restart happens while the particles press on each other and on
   the floor, and while the floor moves (checkpoint_util.py), so history and wall motion
   both matter.
2. --resume without a checkpoint starts the case from t = 0 (same final.csv as a plain run).
3. A restart with another dt counts time on from the checkpoint's: the series rows after it
   are at t_checkpoint + k dt_new, and the run ends at t_end.
4. A restart from the older of two kept checkpoints abandons the continuation that wrote the
   newer one: once the new run has written its own, that one is gone and checkpoint_keep
   (2) checkpoints remain, the restart's and the new run's.
5. The LIGGGHTS variant, whose parted pairs keep their history until the next list build
   (reset_pair_history false), so that its results depend on when the lists are built: the
   regression bed (a ball into 294 spheres) restarted from a checkpoint between two builds
   ends as the run straight through, final.csv byte for byte (its checkpoint holds the
   positions of the last build, which the restart's first build replays).
usage: test_restart.py DEM WORKDIR"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

from regression_util import check, check_close, finish
import checkpoint_util as cu

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
DT, N = 2e-5, 6000
SNAP = ", snapshot_interval = 0.04"


PROBES = """&probe name = 'low', kind = 'count', region = 'box', box_min = -1, -1, -1,
        box_max = 1, 1, 0.03 /
&probe name = 'com', kind = 'center_of_mass' /
&probe name = 'p9', kind = 'track', id = 9 /
"""


def write_case(name, t_end, dt=DT, integrator="symplectic_euler", output=""):
    cu.write_box_case(os.path.join(work, name + ".nml"), os.path.join(work, f"out_{name}"),
                      t_end, dt=dt, interval=0.01, integrator=integrator, output=output,
                      extra=PROBES)


def run(*args, expect=0):
    r = subprocess.run([dem, *args], cwd=work, capture_output=True, text=True, timeout=300)
    if r.returncode != expect:
        print(r.stdout, r.stderr)
    check(r.returncode == expect, f"dem {' '.join(args)}: exit {r.returncode}, expected {expect}")
    return r


def ckpt(name, step):
    return os.path.join(work, f"out_{name}", "checkpoints", f"checkpoint_{step:012d}.h5")


def read(path):
    with open(path, "rb") as f:
        return f.read()


for integrator in ("symplectic_euler", "velocity_verlet"):
    straight = f"straight_{integrator}"
    split = f"split_{integrator}"
    write_case(straight, t_end=2 * N * DT, integrator=integrator, output=SNAP)
    write_case(split, t_end=N * DT, integrator=integrator, output=SNAP)
    run(straight + ".nml")
    run(split + ".nml")
    with h5py.File(ckpt(split, N)) as f:
        pairs = f["state/pair"].shape[0]
        walls = int((f["state/wall_contact_triangle"][()] > 0).sum())
        check(pairs > 30 and walls > 30, f"{integrator}: contacts at the restart "
              f"({pairs} pairs with history, {walls} wall contacts)")
    write_case(split, t_end=2 * N * DT, integrator=integrator, output=SNAP)
    r = run("--restart", ckpt(split, N), split + ".nml")
    check("restarting from" in r.stdout, f"{integrator}: the restart is announced")

    with h5py.File(ckpt(straight, 2 * N)) as a, h5py.File(ckpt(split, 2 * N)) as b:
        names = [n for n in cu.datasets(a) if n not in ("case/input", "state/checkpoint_step")]
        check(sorted(names + ["case/input", "state/checkpoint_step"]) == sorted(cu.datasets(b)),
              f"{integrator}: same datasets")
        differ = [n for n in names if not cu.same_bits(a[n][()], b[n][()])]
        check(not differ, f"{integrator}: datasets that differ after the restart: {differ}")
    for out in ("series.csv", "probes.csv", "final.csv", "snapshots.xmf"):
        check(read(os.path.join(work, f"out_{straight}", out)) ==
              read(os.path.join(work, f"out_{split}", out)), f"{integrator}: {out} differs")
    snaps = sorted(os.listdir(os.path.join(work, f"out_{straight}", "snapshots")))
    check(snaps == sorted(os.listdir(os.path.join(work, f"out_{split}", "snapshots"))),
          f"{integrator}: same snapshot files")
    for s in snaps:
        with h5py.File(os.path.join(work, f"out_{straight}", "snapshots", s)) as a, \
             h5py.File(os.path.join(work, f"out_{split}", "snapshots", s)) as b:
            check(all(cu.same_bits(a[n][()], b[n][()]) for n in cu.datasets(a)),
                  f"{integrator}: snapshot {s} differs")

# 2. --resume with nothing to resume from
write_case("fresh", t_end=200 * DT)
write_case("resumed", t_end=200 * DT)
run("fresh.nml")
r = run("--resume", "resumed.nml")
check("restarting" not in r.stdout, "--resume without a checkpoint starts from t = 0")
check(read(os.path.join(work, "out_fresh", "final.csv")) ==
      read(os.path.join(work, "out_resumed", "final.csv")), "--resume from nothing: final.csv")

# 3. another dt after the restart
name = "split_symplectic_euler"
write_case(name, t_end=2 * N * DT, dt=DT / 2)
shutil.rmtree(os.path.join(work, f"out_{name}", "snapshots"))
run("--restart", ckpt(name, N), name + ".nml")
rows = np.genfromtxt(os.path.join(work, f"out_{name}", "series.csv"), delimiter=",", names=True)
after = rows[rows["step"] > N]
expected = N * DT + (after["step"] - N) * DT / 2
check(len(after) == 12 and np.allclose(after["time"], expected, rtol=0, atol=1e-12),
      f"dt halved at the restart: rows after it at t_checkpoint + k dt ({after['time']})")
check_close(rows["time"][-1], 2 * N * DT, 1e-12, "the run with the new dt ends at t_end")

# 4. restart from the older checkpoint
name = "split_velocity_verlet"
folder = os.path.join(work, f"out_{name}", "checkpoints")
before = sorted(os.listdir(folder))
write_case(name, t_end=1.5 * N * DT, integrator="velocity_verlet", output=SNAP)
run("--restart", ckpt(name, N), name + ".nml")
after = sorted(os.listdir(folder))
names = [os.path.basename(ckpt(name, k)) for k in (N, 3 * N // 2)] + ["latest"]
check(after == names, f"restart from the older checkpoint: {before} became {after}, "
                      f"expected {names}")

# 5. the LIGGGHTS variant (history kept until a list build)
bed = os.path.join(os.path.dirname(os.path.abspath(__file__)), "cases", "liggghts_bed")
with open(os.path.join(bed, "case.nml")) as f:
    text = f.read().replace("'particles.csv'", repr(os.path.join(bed, "particles.csv")))
for name in ("bed_straight", "bed_restarted"):
    with open(os.path.join(work, name + ".nml"), "w") as f:
        f.write(text.replace("&output interval = 0.001 /", f"&output dir = 'out_{name}', "
                             "interval = 0.0005, checkpoint_interval = 0.0011 /"))
run("bed_straight.nml")
shutil.copytree(os.path.join(work, "out_bed_straight"), os.path.join(work, "out_bed_restarted"))
os.remove(os.path.join(work, "out_bed_restarted", "input.nml"))
run("--restart", ckpt("bed_restarted", 4400), "bed_restarted.nml")
check(read(os.path.join(work, "out_bed_straight", "final.csv")) ==
      read(os.path.join(work, "out_bed_restarted", "final.csv")),
      "the LIGGGHTS variant restarted between two list builds: final.csv byte for byte")
finish()
