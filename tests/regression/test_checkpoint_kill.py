# SPDX-License-Identifier: BSD-3-Clause
"""A run killed (SIGKILL) in the middle of writing a checkpoint loses nothing it had saved.

The case (written here) has 200 soft spheres falling in a box onto a rising, spinning STL
floor, so the state has particle and wall contacts with tangential history and walls in
motion; it writes a checkpoint every 2500 steps. The run has checkpoint_pause.c (built by
CMake, its path the third argument) preloaded, which sleeps in the middle of every
checkpoint write (the particle data written, the file not yet closed): dem itself has no
such hook. We wait until the .part file of the second checkpoint appears and kill the
process there, which no handler can catch. Then:
1. the interrupted checkpoint is left as an incomplete <name>.part (on one rank an empty
   one: the file is built in memory and written out at its close), never under its final
   name, and a restart from it is refused; checkpoints/latest still names the first
   checkpoint, which is complete: every dataset's checksum, recomputed here from its
   definition (not by the solver), matches, and its particles, walls and run state are bit
   for bit those of the same step of an uninterrupted run of the same case (the reference:
   the same case, other output directory, every checkpoint kept);
2. `dem --resume` continues from that checkpoint to the end (exit 0), and the final
   checkpoint, final.csv, series.csv and the snapshots are bit for bit the uninterrupted
   run's: a restart repeats the same floating-point operations, so the comparison is exact;
3. at the end only the last checkpoint_keep (default 2) checkpoints remain, with no .part
   file left over.
usage: test_checkpoint_kill.py DEM WORKDIR PAUSE_LIBRARY"""
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import h5py

from regression_util import check, finish, run_dem
import checkpoint_util as cu

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
pause_library = os.path.abspath(sys.argv[3])
os.makedirs(work, exist_ok=True)

DT, T_END, EVERY = 2.0e-5, 0.2, 2500      # checkpoints at steps 2500, 5000, 7500, 10000
KEEP = 2                                  # the default checkpoint_keep
PAUSE = 2                                 # s of sleep inside each checkpoint write
out_kill = os.path.join(work, "out_kill")
out_ref = os.path.join(work, "out_ref")
for d in (out_kill, out_ref):
    if os.path.exists(d):
        shutil.rmtree(d)
common = dict(t_end=T_END, dt=DT, run=", progress_interval = 0")
case = cu.write_box_case(os.path.join(work, "kill.nml"), out_kill,
                         output=f", checkpoint_interval = {EVERY * DT}", **common)
ref = cu.write_box_case(os.path.join(work, "ref.nml"), out_ref,
                        output=f", checkpoint_interval = {EVERY * DT}, checkpoint_keep = 100",
                        **common)

t0 = time.monotonic()
run_dem(dem, ref, work)
ref_steps = [EVERY * k for k in range(1, round(T_END / DT) // EVERY + 1)]
check(cu.checkpoint_files(out_ref) == sorted([os.path.basename(cu.checkpoint_name(s))
                                              for s in ref_steps] + ["latest"]),
      f"the reference run keeps every checkpoint: {cu.checkpoint_files(out_ref)}")


# 1. kill during the second checkpoint write
def later_part():
    """The .part file of a checkpoint after the first, if there is one."""
    for name in cu.checkpoint_files(out_kill):
        m = re.fullmatch(r"checkpoint_(\d{12})\.h5\.part", name)
        if m and int(m.group(1)) > EVERY:
            return name
    return None


log = os.path.join(work, "kill")
p = cu.start([dem, case], work, log,
             env={"LD_PRELOAD": pause_library, "DEM_CHECKPOINT_PAUSE": str(PAUSE)})
found = cu.wait_for(lambda: later_part() is not None or p.poll() is not None, timeout=120)
alive = p.poll() is None
part = later_part()
check(found and alive and part is not None,
      f"no .part file of a later checkpoint appeared while the run was going "
      f"(exit status {p.poll()})")
time.sleep(0.2)                           # well inside the pause, after the particle data
p.send_signal(signal.SIGKILL)
rc = p.wait()
check(rc == -signal.SIGKILL, f"the killed run ended with {rc}, expected to be killed")
print(f"killed during the write of {part}")

ckdir = os.path.join(out_kill, "checkpoints")
first = os.path.basename(cu.checkpoint_name(EVERY))
second = os.path.basename(cu.checkpoint_name(2 * EVERY))
check(part == second + ".part", f"the interrupted write is {part}, expected {second}.part")
check(cu.checkpoint_files(out_kill) == sorted([first, second + ".part", "latest"]),
      f"after the kill the checkpoints are {cu.checkpoint_files(out_kill)}, expected "
      f"{first}, {second}.part and latest")
check(not os.path.exists(os.path.join(ckdir, second)),
      "the interrupted checkpoint is under its final name")
check(cu.latest(out_kill) == cu.checkpoint_name(EVERY),
      f"checkpoints/latest names {cu.latest(out_kill)!r}, expected "
      f"{cu.checkpoint_name(EVERY)!r} (the last complete checkpoint)")

# the .part file is incomplete: unreadable, or with datasets missing or damaged
part_path = os.path.join(ckdir, second + ".part")
complete_names = None
with h5py.File(os.path.join(out_ref, cu.checkpoint_name(2 * EVERY)), "r") as f:
    complete_names = cu.datasets(f)
try:
    with h5py.File(part_path, "r") as f:
        names = cu.datasets(f)
    incomplete = names != complete_names or len(cu.bad_checksums(part_path)) > 0
except OSError:
    incomplete = True
check(incomplete, f"{part_path} looks complete although the write was killed")
before = cu.tree_state(out_kill)
r = subprocess.run([dem, "--restart", part_path, case], cwd=work, capture_output=True,
                   text=True, timeout=120)
check(r.returncode in (2, 4) and part_path in r.stderr,
      f"a restart from the .part file: exit {r.returncode}, stderr {r.stderr.strip()!r}; "
      f"expected 2 or 4 and an error naming the file")
check(not cu.crash_signs(r.stdout + r.stderr), f"a restart from the .part file crashed: "
      f"{cu.crash_signs(r.stdout + r.stderr)}")
check(cu.tree_state(out_kill) == before, "a refused restart changed the output directory")

# the last complete checkpoint is intact and is the uninterrupted run's state
good = os.path.join(out_kill, cu.checkpoint_name(EVERY))
good_ref = os.path.join(out_ref, cu.checkpoint_name(EVERY))
try:
    with h5py.File(good, "r") as f:
        fmt, step = f["format"][()], int(f["step"][()])
    check(fmt == b"dem checkpoint 1" and step == EVERY,
          f"{good}: format {fmt!r}, step {step}")
    bad = cu.bad_checksums(good)
    check(not bad, f"{good}: datasets whose checksum does not match: {bad}")
    for group in ("particles", "walls", "state"):
        diff = cu.differing(good, good_ref, group)
        check(not diff, f"{good}: /{group} datasets differ from the uninterrupted run's: "
                        f"{diff}")
    check(cu.read_group(good, "/")["time"] == cu.read_group(good_ref, "/")["time"],
          f"{good}: /time differs from the uninterrupted run's")
except OSError as e:
    check(False, f"{good} cannot be opened: {e}")

# 2. resume to the end
r = subprocess.run([dem, "--resume", case], cwd=work, capture_output=True, text=True,
                   timeout=300)
check(r.returncode == 0, f"dem --resume exited with {r.returncode}: {r.stderr.strip()}")
check("restarting from " + os.path.join(out_kill, cu.checkpoint_name(EVERY)) in r.stdout,
      "dem --resume did not say it restarts from the last complete checkpoint")
final = os.path.join(out_kill, cu.checkpoint_name(ref_steps[-1]))
final_ref = os.path.join(out_ref, cu.checkpoint_name(ref_steps[-1]))
if os.path.exists(final):
    check(not cu.bad_checksums(final), f"{final}: checksums do not match")
    diff = cu.differing(final, final_ref, "particles")
    check(not diff, f"the resumed run's final /particles differ from the uninterrupted "
                    f"run's: {diff}")
    diff = cu.differing(final, final_ref, "state", skip=("checkpoint_step",))
    check(not diff, f"the resumed run's final /state differs from the uninterrupted run's: "
                    f"{diff}")
    kept = cu.read_group(final, "state")["checkpoint_step"].tolist()
    check(kept == ref_steps[-KEEP:], f"the final checkpoint lists the kept checkpoints "
                                     f"{kept}, expected {ref_steps[-KEEP:]}")
else:
    check(False, f"the resumed run wrote no final checkpoint {final}")
for name in ("final.csv", "series.csv", "snapshots.xmf"):
    a, b = os.path.join(out_kill, name), os.path.join(out_ref, name)
    same = os.path.exists(a) and open(a, "rb").read() == open(b, "rb").read()
    check(same, f"{name} of the resumed run differs from the uninterrupted run's")
snaps = sorted(os.listdir(os.path.join(out_ref, "snapshots")))
check(sorted(os.listdir(os.path.join(out_kill, "snapshots"))) == snaps,
      "the resumed run has other snapshot files than the uninterrupted run")
for name in snaps:
    a = os.path.join(out_kill, "snapshots", name)
    b = os.path.join(out_ref, "snapshots", name)
    if os.path.exists(a):
        diff = cu.differing(a, b, "particles")
        check(not diff, f"snapshot {name}: /particles differ from the uninterrupted run's: "
                        f"{diff}")

# 3. only the last checkpoint_keep checkpoints remain
expect = sorted([os.path.basename(cu.checkpoint_name(s)) for s in ref_steps[-KEEP:]] +
                ["latest"])
check(cu.checkpoint_files(out_kill) == expect,
      f"at the end the checkpoints are {cu.checkpoint_files(out_kill)}, expected {expect}")
check(cu.latest(out_kill) == cu.checkpoint_name(ref_steps[-1]),
      f"at the end checkpoints/latest names {cu.latest(out_kill)!r}")
print(f"{time.monotonic() - t0:.1f} s")
finish()
