# SPDX-License-Identifier: BSD-3-Clause
"""Run control: signals, the wall-time limit, the progress line and the instability guard.

The cases are written here: 200 soft spheres falling in a box of four planes onto a rising,
spinning STL floor (contacts with tangential history, walls in motion), for 2 s of
simulated time (100 000 steps, a few seconds of wall clock); and a single sphere.
(a) SIGTERM, and SIGUSR1, sent to a running case (we wait until series.csv has grown, so the
    time loop is running): the run stops with exit status 75, the last line of its output
    names the checkpoint it wrote at the step where it stopped, that checkpoint holds that
    step (and time), is intact (checksums recomputed here) and is named by
    checkpoints/latest; `dem --resume` continues it to the end (exit 0), and the final state
    (final checkpoint's particles and run state, final.csv, series.csv) is bit for bit that
    of an uninterrupted run: a restart repeats the same floating-point operations, at any
    step.
(b) &run wall_time_limit = 2 on the same case made 10 times longer: it stops with exit 75
    before 2 s of wall clock (the limit counts from the start of the program; we allow
    0.05 s for starting the process), but not long before (it ran at least 1.5 s), with a
    checkpoint at the step where it stopped.
(c) &run progress_interval = 0.5 (on the uninterrupted run of (a)): progress lines arrive
    about every 0.5 s of wall clock (by the clock of this script), in the documented format;
    the step increases, the time is step * dt, the percentage is 100 step / steps and lies
    in 0..100, the particle count is the case's.
(d) The instability guard. The box case with spheres 10^4 times stiffer (Rayleigh time
    3.4e-6 s) run with dt = 2e-5 s (allow_unstable): the run stops with exit status 3; the
    message names a particle of the case, the time, dt as a fraction of the Rayleigh time
    (which we compute from its formula, doc/theory.md), says "reduce dt" and names the
    last good state's checkpoint: it exists, is intact, its time is the one named and is
    before the failure, its values are finite and every speed (|v| and |w| R) is below the
    bound, whose default is max(0.1 x smallest radius / dt, 10 x the expected speed that
    dem --check prints). And a sphere that starts faster
    than an explicit &run max_speed stops the run at the first step (t = dt).
(e) SIGUSR1 sent 0.1 s after the start (while MPI starts and the case is read) stops the
    run at its first step with a checkpoint (exit 75); a 2-step case with a 1 ms wall-time
    limit stops after step 1 (75), and its --resume, which reaches t_end, ends as finished
    (0).
usage: test_run_control.py DEM WORKDIR"""
import math
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import time

import h5py
import numpy as np

from regression_util import check, check_close, finish
import checkpoint_util as cu

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
if os.path.exists(work):
    shutil.rmtree(work)
os.makedirs(work)
t_start = time.monotonic()

DT, T_END, N = 2.0e-5, 2.0, 200
N_END = round(T_END / DT)
STOP = re.compile(r"dem: (.+); stopped at t = (\S+) s after writing (\S+); "
                  r"continue with dem --resume (\S+)$")


def case_for(name, t_end=T_END, run=""):
    return cu.write_box_case(os.path.join(work, name + ".nml"), os.path.join(work, name),
                             t_end, DT, interval=0.01, run=run)


def stopped_checkpoint(what, out_dir, log, reason, case):
    """Checks of a run stopped early; returns (step, time) of its checkpoint or None."""
    out, err = cu.read_log(log)
    lines = out.strip().splitlines()
    last = lines[-1] if lines else ""
    m = STOP.match(last)
    check(m is not None, f"{what}: the last line of the output is {last!r}, expected "
                         f"'dem: ...; stopped at t = T s after writing CHECKPOINT; "
                         f"continue with dem --resume CASE'")
    check(not cu.crash_signs(out + err), f"{what}: signs of a crash: "
                                         f"{cu.crash_signs(out + err)}")
    if m is None:
        return None
    check(reason in m.group(1), f"{what}: the reason is {m.group(1)!r}, expected {reason!r}")
    check(m.group(4) == case, f"{what}: it says to resume {m.group(4)}, not {case}")
    path = m.group(3)
    name = re.fullmatch(re.escape(out_dir) + r"/checkpoints/checkpoint_(\d{12})\.h5", path)
    check(name is not None, f"{what}: the checkpoint named is {path}")
    if name is None or not os.path.exists(path):
        check(False, f"{what}: the checkpoint {path} does not exist")
        return None
    step = int(name.group(1))
    with h5py.File(path, "r") as f:
        f_step, f_time = int(f["step"][()]), float(f["time"][()])
    check(f_step == step, f"{what}: {path} holds step {f_step}")
    check_close(f_time, float(m.group(2)), 1e-4, f"{what}: the time of the checkpoint")
    check_close(f_time, step * DT, 1e-9, f"{what}: the time of the checkpoint's step")
    check(not cu.bad_checksums(path), f"{what}: {path}: checksums do not match")
    check(cu.latest(out_dir) == cu.checkpoint_name(step),
          f"{what}: checkpoints/latest names {cu.latest(out_dir)!r}, not the stop's checkpoint")
    return step, f_time


# (a) + (c): the uninterrupted run, with progress lines timed as they arrive
ref = case_for("ref", run=", progress_interval = 0.5")
p = subprocess.Popen([dem, ref], cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                     text=True, bufsize=1)
t0 = time.monotonic()
arrivals = []
for line in p.stdout:
    if line.startswith("progress:"):
        arrivals.append((time.monotonic() - t0, line.rstrip("\n")))
ref_err = p.stderr.read()
rc = p.wait()
ref_seconds = time.monotonic() - t0
check(rc == 0, f"the uninterrupted run exited with {rc}: {ref_err.strip()}")
print(f"uninterrupted run: {ref_seconds:.1f} s, {len(arrivals)} progress lines")
ref_out = os.path.join(work, "ref")
ref_final = os.path.join(ref_out, cu.checkpoint_name(N_END))

PROGRESS = re.compile(r"progress: step (\d+) +t = +(\S+) s +(\S+) % +particles (\d+) +"
                      r"contacts (\d+) +(\S+) particle-steps/s +left (\d+):(\d\d):(\d\d)$")
check(len(arrivals) >= max(2, int(ref_seconds / 0.5) - 3),
      f"(c) {len(arrivals)} progress lines in a run of {ref_seconds:.1f} s with "
      f"progress_interval = 0.5")
steps, percents = [], []
for when, line in arrivals:
    m = PROGRESS.match(line)
    check(m is not None, f"(c) a progress line not in the documented format: {line!r}")
    if m is None:
        continue
    step, t, pct = int(m.group(1)), float(m.group(2)), float(m.group(3))
    steps.append(step)
    percents.append(pct)
    check(abs(t - step * DT) <= 1e-4 * step * DT, f"(c) t = {t} at step {step}: not step * dt")
    check(0.0 <= pct <= 100.0, f"(c) percentage {pct} out of 0..100")
    check(abs(pct - 100.0 * step / N_END) <= 0.05 + 1e-9,
          f"(c) percentage {pct} at step {step} of {N_END}")
    check(int(m.group(4)) == N, f"(c) particles {m.group(4)}, expected {N}")
    check(float(m.group(6)) > 0.0, f"(c) particle-steps/s {m.group(6)} not positive")
    check(int(m.group(8)) < 60 and int(m.group(9)) < 60, f"(c) time left {m.group(7)}:"
                                                         f"{m.group(8)}:{m.group(9)}")
check(all(b > a for a, b in zip(steps, steps[1:])), f"(c) the steps do not increase: {steps}")
check(all(b >= a for a, b in zip(percents, percents[1:])), "(c) the percentage decreases")
gaps = [b[0] - a[0] for a, b in zip(arrivals, arrivals[1:])]
if gaps:
    print(f"(c) progress lines every {min(gaps):.3f} .. {max(gaps):.3f} s, "
          f"median {statistics.median(gaps):.3f} s")
    check(min(gaps) >= 0.4, f"(c) progress lines {min(gaps):.3f} s apart (interval 0.5 s)")
    check(0.45 <= statistics.median(gaps) <= 0.75,
          f"(c) progress lines a median {statistics.median(gaps):.3f} s apart (interval 0.5 s)")
    check(max(gaps) <= 3.0, f"(c) progress lines up to {max(gaps):.3f} s apart")

# (a) SIGTERM and SIGUSR1
for sig, rows in ((signal.SIGTERM, 20), (signal.SIGUSR1, 60)):
    name = sig.name.lower()
    case = case_for(name)
    out_dir = os.path.join(work, name)
    series = os.path.join(out_dir, "series.csv")
    log = os.path.join(work, name + "_log")
    p = cu.start([dem, case], work, log)
    running = cu.wait_for(lambda: cu.lines_of(series) > rows or p.poll() is not None, 120)
    alive = p.poll() is None
    check(running and alive, f"(a) {sig.name}: the run was not going when the signal was due "
                             f"(exit status {p.poll()})")
    last_row_step = (cu.lines_of(series) - 2) * 500    # a header, then a row every 500 steps
    p.send_signal(sig)
    rc = cu.finish_process(p, 120)
    check(rc == 75, f"(a) {sig.name}: exit status {rc}, expected 75")
    stop = stopped_checkpoint(f"(a) {sig.name}", out_dir, log, f"{sig.name} received", case)
    if stop is None:
        continue
    step, t = stop
    print(f"(a) {sig.name} after series.csv reached step {last_row_step}: stopped at step "
          f"{step}")
    check(last_row_step <= step < N_END,
          f"(a) {sig.name}: stopped at step {step}, before the signal or at the end")
    r = subprocess.run([dem, "--resume", case], cwd=work, capture_output=True, text=True,
                       timeout=300)
    check(r.returncode == 0, f"(a) {sig.name}: dem --resume exited with {r.returncode}: "
                             f"{r.stderr.strip()}")
    check("restarting from " + os.path.join(out_dir, cu.checkpoint_name(step)) in r.stdout,
          f"(a) {sig.name}: dem --resume did not restart from the stop's checkpoint")
    final = os.path.join(out_dir, cu.checkpoint_name(N_END))
    if not os.path.exists(final):
        check(False, f"(a) {sig.name}: the resumed run left no final checkpoint {final}")
        continue
    diff = cu.differing(final, ref_final, "particles")
    check(not diff, f"(a) {sig.name}: the final /particles differ from the uninterrupted "
                    f"run's: {diff}")
    diff = cu.differing(final, ref_final, "state", skip=("checkpoint_step",))
    check(not diff, f"(a) {sig.name}: the final /state differs from the uninterrupted run's: "
                    f"{diff}")
    for csv in ("final.csv", "series.csv"):
        a, b = os.path.join(out_dir, csv), os.path.join(ref_out, csv)
        check(os.path.exists(a) and open(a, "rb").read() == open(b, "rb").read(),
              f"(a) {sig.name}: {csv} differs from the uninterrupted run's")

# (b) the wall-time limit
LIMIT = 2.0
case = case_for("wall_time", t_end=10 * T_END, run=f", wall_time_limit = {LIMIT}")
log = os.path.join(work, "wall_time_log")
t0, t0_wall = time.monotonic(), time.time()
p = cu.start([dem, case], work, log)
rc = cu.finish_process(p, 120)
elapsed = time.monotonic() - t0
print(f"(b) wall_time_limit = {LIMIT} s: exit {rc} after {elapsed:.2f} s")
check(rc == 75, f"(b) exit status {rc}, expected 75")
check(elapsed <= LIMIT + 0.05, f"(b) the run ended {elapsed:.2f} s after its start, after "
                               f"its wall_time_limit of {LIMIT} s")
check(elapsed >= LIMIT - 0.5, f"(b) the run stopped after {elapsed:.2f} s, long before the "
                              f"limit of {LIMIT} s")
stop = stopped_checkpoint("(b)", os.path.join(work, "wall_time"), log, "wall-time limit", case)
if stop is not None:
    check(0 < stop[0] < 10 * N_END, f"(b) stopped at step {stop[0]}")
    # the checkpoint was complete (last written) before the limit, start-up allowed for
    written = os.stat(os.path.join(work, "wall_time", cu.checkpoint_name(stop[0]))).st_mtime
    print(f"(b) checkpoint written {written - t0_wall:.3f} s after the start")
    check(written - t0_wall <= LIMIT + 0.1, f"(b) the checkpoint was written "
                                            f"{written - t0_wall:.3f} s after the start, "
                                            f"after the limit of {LIMIT} s")

# (d) instability: stiff spheres, dt 6 Rayleigh times
E, NU, RHO = 1.0e11, 0.2, 2500.0
case = cu.write_box_case(os.path.join(work, "unstable.nml"), os.path.join(work, "unstable"),
                         0.2, DT, interval=0.001, E="1e11", run=", allow_unstable = .true.")
check_out = subprocess.run([dem, "--check", case], cwd=work, capture_output=True, text=True,
                           timeout=300).stdout
v0 = float(re.search(r"at the largest expected speed, +(\S+) m/s", check_out).group(1))
r = subprocess.run([dem, case], cwd=work, capture_output=True, text=True, timeout=300)
message = r.stderr.strip()
print(f"(d) exit {r.returncode}: {message}")
check(r.returncode == 3, f"(d) exit status {r.returncode}, expected 3")
check(not cu.crash_signs(r.stdout + r.stderr), f"(d) signs of a crash")
UNSTABLE = re.compile(r"dem: error: unstable: particle (\d+) (.*) at t = (\S+) s; dt is (\S+) "
                      r"of the Rayleigh time \((\S+) s\): reduce dt; the last good state, at "
                      r"t = (\S+) s, is in (\S+)$")
m = UNSTABLE.match(message)
check(m is not None, f"(d) the message is not in the documented form: {message!r}")
if m is not None:
    pid, t_fail, t_good, path = int(m.group(1)), float(m.group(3)), float(m.group(6)), \
        m.group(7)
    check(0.0 < t_fail <= 0.2, f"(d) failure time {t_fail} out of the run")
    out_dir = os.path.join(work, "unstable")
    check(os.path.dirname(os.path.dirname(path)) == out_dir and os.path.exists(path),
          f"(d) the last good state {path} does not exist in {out_dir}/checkpoints")
    if os.path.exists(path):
        check(not cu.bad_checksums(path), f"(d) {path}: checksums do not match")
        with h5py.File(path, "r") as f:
            time_good = float(f["time"][()])
            par = {k: f["particles"][k][()] for k in f["particles"]}
        check(pid in par["id"].tolist(), f"(d) particle {pid} is not in the case")
        check_close(time_good, t_good, 1e-4, "(d) the time of the last good state")
        check(time_good < t_fail, f"(d) the last good state (t = {time_good}) is not before "
                                  f"the failure (t = {t_fail})")
        finite = all(np.all(np.isfinite(v)) for v in par.values() if v.dtype.kind == "f")
        check(finite, "(d) the last good state has non-finite values")
        radius = par["radius"]
        bound = max(0.1 * radius.min() / DT, 10.0 * v0)
        speed = np.maximum(np.linalg.norm(par["velocity"], axis=1),
                           np.linalg.norm(par["angular_velocity"], axis=1) * radius)
        check(speed.max() < bound, f"(d) the last good state has a speed {speed.max():.4g} "
                                   f"m/s, above the bound {bound:.4g} m/s")
        check(cu.latest(out_dir) == os.path.relpath(path, out_dir),
              f"(d) checkpoints/latest names {cu.latest(out_dir)!r}, not {path}")
        bm = re.search(r"above the bound (\S+) m/s", message)
        if bm:
            check_close(float(bm.group(1)), bound, 1e-4, "(d) the default bound max_speed")
        # Rayleigh time of the smallest sphere: pi R sqrt(rho / G) / (0.1631 nu + 0.8766)
        g = E / (2.0 * (1.0 + NU))
        t_r = math.pi * radius.min() * math.sqrt(RHO / g) / (0.1631 * NU + 0.8766)
        check_close(float(m.group(5)), t_r, 1e-3, "(d) the Rayleigh time in the message")
        check_close(float(m.group(4)), DT / t_r, 1e-3, "(d) dt / Rayleigh time in the message")

# (d) a sphere faster than &run max_speed from the start
one = os.path.join(work, "fast.nml")
with open(one, "w") as f:
    f.write(f"""&run dt = 1e-5, t_end = 0.01, gravity = 0, 0, 0, max_speed = 1.0 /
&output dir = '{os.path.join(work, "fast")}' /
&material name = 'soft', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.2 /
&pair materials = 'soft', 'soft', restitution = 0.5, friction = 0.3 /
&particle id = 7, material = 'soft', radius = 0.005, position = 0, 0, 0, velocity = 2, 0, 0 /
""")
r = subprocess.run([dem, one], cwd=work, capture_output=True, text=True, timeout=120)
message = r.stderr.strip()
print(f"(d) fast sphere: exit {r.returncode}: {message}")
check(r.returncode == 3, f"(d) fast sphere: exit status {r.returncode}, expected 3")
m = UNSTABLE.match(message)
check(m is not None and m.group(1) == "7" and "max_speed" in m.group(2),
      f"(d) fast sphere: the message does not name particle 7 and max_speed: {message!r}")
if m is not None:
    check_close(float(m.group(3)), 1e-5, 1e-4, "(d) fast sphere: the time it stopped (the "
                                               "first step)")
    check(os.path.exists(m.group(7)), f"(d) fast sphere: {m.group(7)} does not exist")
    check(float(m.group(6)) == 0.0, f"(d) fast sphere: the last good state is at t = "
                                    f"{m.group(6)}, expected 0")
rows = cu.lines_of(os.path.join(work, "fast", "series.csv")) - 1
check(rows == 1, f"(d) fast sphere: {rows} rows in series.csv, expected the one at t = 0")

# (e) a signal during start-up (before the time loop: starting MPI, reading the case,
#     inserting 800 spheres) is kept and honoured at the first step; a stop that falls on
#     the last step is no stop: the run ends as finished (exit 0, final.csv)
case = cu.write_box_case(os.path.join(work, "early.nml"), os.path.join(work, "early"), T_END,
                         DT, interval=0.01, n=800)
p = cu.start([dem, case], work, os.path.join(work, "early_log"))
time.sleep(0.1)
p.send_signal(signal.SIGUSR1)
rc = cu.finish_process(p, 120)
check(rc == 75, f"(e) SIGUSR1 during start-up: exit status {rc}, expected 75")
stop = stopped_checkpoint("(e)", os.path.join(work, "early"), os.path.join(work, "early_log"),
                          "SIGUSR1", case)
check(stop is not None and stop[0] == 1, f"(e) stopped at the first step ({stop})")
case = cu.write_box_case(os.path.join(work, "last.nml"), os.path.join(work, "last"), 2 * DT,
                         DT, interval=DT, run=", wall_time_limit = 0.001")
runs = [subprocess.run([dem, "--resume", case], cwd=work, capture_output=True, text=True,
                       timeout=120).returncode for _ in range(2)]
check(runs == [75, 0], f"(e) a 2-step case with a 1 ms wall-time limit: exit statuses "
                       f"{runs}, expected [75, 0] (the second run ends at t_end)")
check(os.path.exists(os.path.join(work, "last", "final.csv")),
      "(e) final.csv of the 2-step case")

print(f"{time.monotonic() - t_start:.1f} s")
finish()
