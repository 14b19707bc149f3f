# SPDX-License-Identifier: BSD-3-Clause
"""An output folder is held by one run at a time, and what --resume finds there is checked.

A case of 60 spheres falling into a box (series.csv rows every 0.002 s, snapshots and
checkpoints every 0.04 s, to 0.2 s) is started in the background. While it runs (stopped
with SIGSTOP while the others try, then continued):
1. a second `dem CASE` and a `dem --resume CASE` on the same folder are refused with exit
   status 2 and a message that names the holder: the first run's process id and host; the
   first run then ends with exit 0 and complete outputs (series.csv has its 101 rows,
   final.csv its 60 particles, snapshots.xmf lists the 6 snapshots, all there), and leaves
   the lock file empty (released).
2. A lock file left by a process that is gone (the process id of a program that has
   ended, this host): the next run takes it over, says so naming that process, and runs.
3. A snapshot listed in snapshots.xmf removed: `dem --resume` refuses it (exit 2, the
   message names the file), whether the run had ended or not.
4. `dem --resume` of the ended run on a read-only file system (a read-only bind mount,
   where the system allows one; skipped with a message otherwise): exit 0, nothing to do.
5. SIGTERM during a long start-up (3 million spheres inserted, in `dem --check`): dem stops
   with exit status 75 and says so, within 10 s (the insertion looks every 65 536 spheres,
   the later steps of the start at their end).
usage: test_folder_lock.py DEM WORKDIR"""
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time

from regression_util import check, finish
import checkpoint_util as cu

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
if os.path.exists(work):
    shutil.rmtree(work)
os.makedirs(work)
out = os.path.join(work, "output", "box")
lock = os.path.join(out, "lock")

CASE = """&run dt = 1e-5, t_end = 0.2, gravity = 0, 0, -9.81, progress_interval = 0 /
&output dir = 'output/box', interval = 0.002, snapshot_interval = 0.04,
        checkpoint_interval = 0.04 /
&material name = 'glass', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'glass', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05 /
&wall_plane material = 'glass', point = -0.01, 0, 0, normal = 1, 0, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0.01, 0, 0, normal = -1, 0, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0, -0.01, 0, normal = 0, 1, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0, 0.01, 0, normal = 0, -1, 0, half_width = 0.05 /
&insert n = 60, material = 'glass', radius_min = 1e-3, region = 'box',
        box_min = -0.01, -0.01, 0, box_max = 0.01, 0.01, 0.02, seed = 1 /
"""
case = os.path.join(work, "box.nml")
with open(case, "w") as f:
    f.write(CASE)


def run(*args):
    return subprocess.run([dem, *args], cwd=work, capture_output=True, text=True, timeout=300)


def listed():
    return sorted(set(re.findall(r"snapshots/snapshot_\d+\.h5",
                                 open(os.path.join(out, "snapshots.xmf")).read())))


# 1. two runs at once
host = socket.gethostname()
log = os.path.join(work, "first")
p = cu.start([dem, case], work, log)
held = cu.wait_for(lambda: os.path.exists(lock) and os.path.getsize(lock) > 0
                   and os.path.exists(os.path.join(out, "series.csv")), timeout=60)
check(held and p.poll() is None, "the first run did not take the lock while running")
p.send_signal(signal.SIGSTOP)        # (held still, however fast the machine)
for args in ([case], ["--resume", case]):
    r = run(*args)
    says = f"held by another run (process {p.pid} on host {host}"
    check(r.returncode == 2 and says in r.stderr, f"dem {' '.join(args)} beside a running "
          f"one: exit {r.returncode}, expected 2 and {says!r}: {r.stderr.strip()[-300:]}")
p.send_signal(signal.SIGCONT)
check(cu.finish_process(p, 300) == 0, "the first run did not end with exit status 0")
first_out, _ = cu.read_log(log)
check("dem: done" in first_out, "the first run did not say done")
check(cu.lines_of(os.path.join(out, "series.csv")) == 1 + 101, "series.csv: "
      f"{cu.lines_of(os.path.join(out, 'series.csv'))} lines, expected 102")
check(cu.lines_of(os.path.join(out, "final.csv")) == 1 + 60, "final.csv: not 60 particles")
check(len(listed()) == 6 and all(os.path.exists(os.path.join(out, s)) for s in listed()),
      f"snapshots.xmf lists {listed()}")
check(open(lock).read() == "", "the lock file is not empty after the run")
series = open(os.path.join(out, "series.csv"), "rb").read()

# 2. a stale lock: a process that has ended
gone = subprocess.Popen(["true"])
gone.wait()
with open(lock, "w") as f:
    f.write(f"{host} {gone.pid} 12345\n")
r = run(case)
says = f"lock: taken over from process {gone.pid} on host {host}, which ended"
check(r.returncode == 0 and says in r.stdout, f"stale lock: exit {r.returncode}, expected 0 "
      f"and {says!r}: {(r.stdout + r.stderr).strip()[-400:]}")
check(open(os.path.join(out, "series.csv"), "rb").read() == series,
      "after taking over a stale lock, series.csv differs from the first run's")

# 3. a listed snapshot removed
for cut in (None, "checkpoint_000000012000.h5"):
    run(case)
    if cut:                          # a run not ended: its latest an older checkpoint
        with open(os.path.join(out, "checkpoints", "latest"), "w") as f:
            f.write("checkpoints/" + cut + "\n")
        shutil.copy(os.path.join(out, "checkpoints", "checkpoint_000000016000.h5"),
                    os.path.join(out, "checkpoints", cut))
    gone_snap = os.path.join(out, "snapshots", "snapshot_000000008000.h5")
    os.remove(gone_snap)
    r = run("--resume", case)
    check(r.returncode == 2 and "snapshot_000000008000.h5: listed in snapshots.xmf" in r.stderr,
          f"a removed snapshot ({cut or 'ended run'}): exit {r.returncode}, expected 2 naming "
          f"it: {r.stderr.strip()[-300:]}")

# 4. --resume of an ended run on a read-only file system
run(case)
ro = os.path.join(work, "read_only")
os.makedirs(ro)
mounted = subprocess.run(["mount", "--bind", work, ro], capture_output=True).returncode == 0
if mounted:
    mounted = subprocess.run(["mount", "-o", "remount,ro,bind", ro],
                             capture_output=True).returncode == 0
    if mounted:
        r = subprocess.run([dem, "--resume", os.path.join(ro, "box.nml")], cwd=ro,
                           capture_output=True, text=True, timeout=120)
        check(r.returncode == 0 and "nothing to do" in r.stdout, f"--resume of an ended run "
              f"on a read-only file system: exit {r.returncode}: {r.stderr.strip()[-300:]}")
    subprocess.run(["umount", ro])
if not mounted:
    print("skipped: --resume on a read-only file system (no read-only bind mount here)")

# 5. SIGTERM during a long insertion
big = os.path.join(work, "big.nml")
with open(big, "w") as f:
    walled = CASE.replace("n = 60", "n = 3000000").replace("box_max = 0.01, 0.01, 0.02",
                                                           "box_max = 1, 1, 1")
    f.write("".join(line for line in walled.splitlines(True)    # (the box reaches past them)
                    if not line.startswith("&wall_plane")))
p = subprocess.Popen([dem, "--check", big], cwd=work, stdout=subprocess.PIPE,
                     stderr=subprocess.PIPE, text=True)
time.sleep(2.0)
p.send_signal(signal.SIGTERM)
sent = time.monotonic()
try:
    _, err = p.communicate(timeout=60)
except subprocess.TimeoutExpired:
    p.kill()
    _, err = p.communicate()
waited = time.monotonic() - sent
check(p.returncode == 75 and "SIGTERM received while" in err and waited < 10.0,
      f"SIGTERM during the start-up: exit {p.returncode} after {waited:.2f} s, expected 75 "
      f"within 10 s: {err.strip()[-300:]}")
finish()
