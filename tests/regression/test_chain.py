# SPDX-License-Identifier: BSD-3-Clause
"""Long runs as chains of short ones: scripts/jobs/run-chain and the SLURM template
scripts/jobs/dem-slurm.sbatch. A chain is only useful if continuing from a checkpoint changes
nothing, so every chain here is compared with one uninterrupted run of the same case.

The case: 200 soft spheres falling into a box onto an STL floor that moves up and then turns
(contacts, contact history and a moving mesh all cross the restarts), 30000 steps.
1. The uninterrupted reference run, timed: it takes C s of CPU time, and dem takes S s of
   wall time to start and end (`dem --version`, mostly MPI's start); the chained copy gets
   &run wall_time_limit = S + 0.25 + C / 8 (0.25 s: dem's reserve for the end of the
   program), so that each run does about an eighth of the steps whatever the machine's
   speed (more runs when the machine is busy).
2. scripts/jobs/run-chain on that copy: at least three runs, all but the last exiting with 75
   and each leaving a newer checkpoint, the last exiting with 0; one line per run; then
   the final checkpoint's /particles datasets, final.csv, series.csv and every snapshot
   are identical, bit for bit, to the reference's.
3. run-chain's own rules, with a stand-in dem (a shell script) and a stand-in mpirun on
   PATH: the mpirun command line for -n 2 with the extra arguments after --; -m stops the
   chain (exit 1); a run exiting with 75 without a newer checkpoint stops it (exit 1);
   a failure's exit status is passed on; a missing case or executable is exit 2 with a
   message. And SIGTERM sent to run-chain reaches the real dem (as SIGUSR1): it writes a
   checkpoint and run-chain stops with 75 without starting another run.
4. The SLURM template: bash -n, and it holds the --signal=B:USR1 line, the trap that
   passes SIGUSR1 on, `--resume`, the test of 75 and the resubmission guarded by
   DEM_CHAIN_MAX. Then it runs under stand-in sbatch/srun commands (on PATH; sbatch queues
   a copy of the script as SLURM does, with the submitting environment for
   --export=ALL, and srun runs the command here) with this test as the scheduler, which
   sends SIGUSR1 to the batch shell alone, as --signal=B: does, once dem is stepping:
   job 1 stops with 75 and resubmits itself once (same script copy and case, a dependency
   on itself, DEM_CHAIN_COUNT=2); job 2, signalled too, reaches DEM_CHAIN_MAX = 2 and does
   not resubmit (exit 75); submitted again by hand, job 3 finishes the case (exit 0, no
   resubmission), and the final state equals the reference's bit for bit. With the
   stand-in dem: a run that exits with 75 without a newer checkpoint is not resubmitted
   (exit 1), nor one that fails (its exit status passed on).
usage: test_chain.py DEM WORKDIR"""
import os
import re
import resource
import shutil
import signal
import stat
import subprocess
import sys
import threading
import time

import h5py
import numpy as np

from regression_util import ROOT, check, finish, run_dem

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
run_chain = os.path.join(ROOT, "scripts", "jobs", "run-chain")
template = os.path.join(ROOT, "scripts", "jobs", "dem-slurm.sbatch")
DT, T_END = 2.0e-5, 0.6
N_END = round(T_END / DT)

with open(os.path.join(work, "floor.stl"), "w") as f:
    f.write("solid floor\n")
    for tri in (((-0.06, -0.06, 0), (0.06, -0.06, 0), (0.06, 0.06, 0)),
                ((-0.06, -0.06, 0), (0.06, 0.06, 0), (-0.06, 0.06, 0))):
        f.write(" facet normal 0 0 1\n  outer loop\n")
        for v in tri:
            f.write("   vertex %g %g %g\n" % v)
        f.write("  endloop\n endfacet\n")
    f.write("endsolid floor\n")


def write_case(stem, run_extra=""):
    """The case under another name (and so output directory), with more &run keys."""
    walls = "".join(f"&wall_plane material = 'wall', point = {p}, normal = {n}, "
                    "half_width = 0.1 /\n" for p, n in (
                        ("-0.05, 0, 0.1", "1, 0, 0"), ("0.05, 0, 0.1", "-1, 0, 0"),
                        ("0, -0.05, 0.1", "0, 1, 0"), ("0, 0.05, 0.1", "0, -1, 0")))
    path = os.path.join(work, stem + ".nml")
    with open(path, "w") as f:
        f.write(f"""&run dt = {DT}, t_end = {T_END}, integrator = 'symplectic_euler',
     progress_interval = 0.05{run_extra} /
&output interval = 0.01, snapshot_interval = 0.1 /
&material name = 'soft', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.2 /
&material name = 'wall', rigid = .true. /
&pair materials = 'soft', 'soft', restitution = 0.3, friction = 0.3 /
&pair materials = 'soft', 'wall', restitution = 0.3, friction = 0.3 /
&insert n = 200, material = 'soft', radius_min = 0.004, radius_max = 0.005, region = 'box',
        box_min = -0.045, -0.045, 0.005, box_max = 0.045, 0.045, 0.15, seed = 7,
        velocity = 0.1, 0, -0.2 /
{walls}&wall_mesh file = 'floor.stl', material = 'wall', velocity = 0, 0, 0.01,
           velocity_start = 0.05, velocity_end = 0.15, rotation_axis = 0, 0, 1,
           rotation_point = 0, 0, 0, angular_velocity = 5, rotation_start = 0.1 /
""")
    return path


def out(stem, *names):
    return os.path.join(work, "output", stem, *names)


def latest(stem):
    with open(out(stem, "checkpoints", "latest")) as f:
        return f.read().strip()


def h5_datasets(path, group="/"):
    found = {}
    with h5py.File(path, "r") as f:
        f[group].visititems(lambda name, obj: found.__setitem__(name, obj[()])
                            if isinstance(obj, h5py.Dataset) else None)
    return found


def same_bytes(a, b):
    with open(a, "rb") as fa, open(b, "rb") as fb:
        return fa.read() == fb.read()


def check_same_end(stem, what):
    """The end of a chained run is the reference's, bit for bit."""
    for name in ("final.csv", "series.csv"):
        check(os.path.exists(out(stem, name)) and same_bytes(out(stem, name), out("ref", name)),
              f"{what}: {name} differs from the uninterrupted run's")
    ckpt = f"checkpoints/checkpoint_{N_END:012d}.h5"
    check(latest(stem) == ckpt, f"{what}: the latest checkpoint is {latest(stem)}, not {ckpt}")
    a, b = h5_datasets(out(stem, ckpt), "/particles"), h5_datasets(out("ref", ckpt), "/particles")
    check(sorted(a) == sorted(b) and len(a) >= 6, f"{what}: /particles datasets {sorted(a)}")
    for name in sorted(b):
        check(name in a and a[name].dtype == b[name].dtype and np.array_equal(a[name], b[name]),
              f"{what}: final checkpoint /particles/{name} differs from the uninterrupted run's")


def watchdog(proc, seconds):
    """Kill the process group of `proc` if it runs for longer than `seconds`."""
    def kill():
        if proc.poll() is None:
            print(f"FAILED: timeout, killing {proc.args}")
            os.killpg(proc.pid, signal.SIGKILL)
    t = threading.Timer(seconds, kill)
    t.daemon = True
    t.start()
    return t


def run_signalled(cmd, env, cwd, sig=None):
    """Run cmd in its own process group; once a dem progress line shows that the time loop
    runs, send `sig` to cmd's process alone. Returns (status, output)."""
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, start_new_session=True)
    timer = watchdog(p, 120)
    lines, sent = [], False
    for line in p.stdout:
        lines.append(line)
        if sig is not None and not sent and line.startswith("progress:"):
            os.kill(p.pid, sig)
            sent = True
    p.wait()
    timer.cancel()
    if sig is not None:
        check(sent, f"{cmd}: no progress line came to send {sig.name} after")
    return p.returncode, "".join(lines)


def executable(path, text):
    with open(path, "w") as f:
        f.write(text)
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)


# 1. the uninterrupted reference, and the time dem takes to start (MPI, mostly a wait)
starts = []
for _ in range(2):
    t0 = time.monotonic()
    subprocess.run([dem, "--version"], capture_output=True, check=True)
    starts.append(time.monotonic() - t0)
start = min(starts)
t0, cpu0 = time.monotonic(), resource.getrusage(resource.RUSAGE_CHILDREN)
rc, stdout, _ = run_dem(dem, write_case("ref"), work)
cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
wall = time.monotonic() - t0
cpu = cpu1.ru_utime + cpu1.ru_stime - cpu0.ru_utime - cpu0.ru_stime
m = re.search(r"^timing: (\d+) steps of \d+ particles in\s+(\S+) s", stdout, re.M)
check(m is not None and int(m.group(1)) == N_END, "reference: the timing line with all steps")
# dem stops once the time since its start plus a reserve reaches the limit; the reserve is
# two checkpoint writes and two steps (small here) and 0.25 s for the end of the program.
# CPU time rather than wall time: under load (other tests running beside this one) the
# reference is slowed down, and a limit taken from its wall time could let the chain,
# run with the machine less loaded, end in fewer runs than meant; the CPU time is about
# what the time loop takes on an idle machine, and a slower chain only makes more runs.
limit = start + 0.25 + cpu / 8.0
print(f"reference: {wall:.2f} s ({cpu:.2f} s of CPU time, the time loop "
      f"{float(m.group(2)) if m else 0:.2f} s); dem starts in {start:.2f} s; "
      f"wall_time_limit = {limit:.3f} s")
write_case("chain", f", wall_time_limit = {limit:.4f}")

# 2. run-chain
env = dict(os.environ, DEM=dem)
t0 = time.monotonic()
r = subprocess.run([run_chain, "chain.nml"], cwd=work, env=env, capture_output=True,
                   text=True, timeout=300)
if r.returncode != 0:
    print(r.stdout, r.stderr)
print(f"run-chain: {time.monotonic() - t0:.2f} s")
check(r.returncode == 0, f"run-chain: exit status {r.returncode}")
runs = re.findall(r"^run-chain: run (\d+) exit (\d+) latest (\S+)$", r.stdout, re.M)
print("\n".join(line for line in r.stdout.splitlines() if line.startswith("run-chain:")))
check(len(runs) >= 3, f"run-chain: {len(runs)} runs, expected at least 3 "
      f"(wall_time_limit {limit:.3f} s for a case of {cpu:.2f} s of CPU time)")
check([int(k) for k, _, _ in runs] == list(range(1, len(runs) + 1)), "run-chain: run numbers")
check(all(rc_ == "75" for _, rc_, _ in runs[:-1]) and runs and runs[-1][1] == "0",
      f"run-chain: exit statuses {[rc_ for _, rc_, _ in runs]}, expected 75 ... 75 0")
steps = [int(m.group(1)) if m else -1 for m in
         (re.search(r"checkpoint_(\d+)\.h5$", c) for _, _, c in runs)]
# every run that stops early leaves a newer checkpoint (the last one may only finish the
# outputs, when the one before reached t_end but stopped there with 75)
check(all(a < b for a, b in zip([0] + steps[:-1], steps[:-1])) and steps and
      steps[-1] == N_END and steps[-1] >= steps[-2],
      f"run-chain: checkpoint steps {steps} do not increase to {N_END}")
check(r.stdout.count("dem: the wall-time limit is near") == len(runs) - 1,
      "run-chain: every stop but the last is dem's wall-time stop")
# each run's CPU time: the runs together do at least the reference's time loop (its CPU
# time less dem's start and end, which every run pays again), and no run takes more CPU time
# than its wall time (one rank) and a second
times = [(float(w), float(c)) for w, c in
         re.findall(r"^run-chain: times of run \d+: wall (\d+) s, CPU ([\d.]+) s", r.stdout, re.M)]
check(len(times) == len(runs) and sum(c for _, c in times) >= 0.5 * cpu and
      all(c <= w + 1.0 for w, c in times),
      f"run-chain: CPU times {times} against the reference's {cpu:.2f} s")
check_same_end("chain", "run-chain")
snaps = sorted(os.listdir(out("ref", "snapshots")))
check(snaps == sorted(os.listdir(out("chain", "snapshots"))) and
      len(snaps) == round(T_END / 0.1) + 1, f"run-chain: snapshot files {snaps}")
for name in snaps:
    a = h5_datasets(out("chain", "snapshots", name))
    b = h5_datasets(out("ref", "snapshots", name))
    check(sorted(a) == sorted(b) and all(np.array_equal(a[k], b[k]) for k in b),
          f"run-chain: snapshot {name} differs from the uninterrupted run's")

# 3. run-chain's rules, with stand-ins
stubs = os.path.join(work, "stubs")
os.makedirs(stubs)
fake_dem = os.path.join(stubs, "fake-dem")
executable(fake_dem, """#!/usr/bin/env bash
echo "fake-dem $*" >> "$FAKE_LOG"
if [[ $1 == --check ]]; then echo "  output directory     $FAKE_OUT"; exit 0; fi
case $FAKE_MODE in
    progress) n=$(( $(cat "$FAKE_OUT/n" 2> /dev/null || echo 0) + 1 ))
              echo $n > "$FAKE_OUT/n"
              mkdir -p "$FAKE_OUT/checkpoints"
              echo "checkpoints/checkpoint_$n.h5" > "$FAKE_OUT/checkpoints/latest"
              exit 75 ;;
    stuck) exit 75 ;;
    done) exit 0 ;;
    fail) exit 3 ;;
esac
""")
executable(os.path.join(stubs, "mpirun"), """#!/usr/bin/env bash
echo "mpirun $*" >> "$FAKE_LOG"
while [[ $# -gt 0 && $1 != -np ]]; do shift; done
shift 2
exec "$@"
""")
fake_log = os.path.join(work, "fake.log")


def fake_chain(mode, *args, dem_path=fake_dem):
    fake_out = os.path.join(work, "fake_" + mode)
    shutil.rmtree(fake_out, ignore_errors=True)
    os.makedirs(fake_out)
    if os.path.exists(fake_log):
        os.remove(fake_log)
    e = dict(os.environ, DEM=dem_path, FAKE_MODE=mode, FAKE_OUT=fake_out, FAKE_LOG=fake_log,
             PATH=stubs + os.pathsep + os.environ["PATH"])
    r = subprocess.run([run_chain, *args], cwd=work, env=e, capture_output=True, text=True,
                       timeout=60)
    log = open(fake_log).read().splitlines() if os.path.exists(fake_log) else []
    return r, log


r, log = fake_chain("done", "-n", "2", "chain.nml", "--", "--extra", "two words")
check(r.returncode == 0, f"run-chain -n 2: exit status {r.returncode}: {r.stderr}")
check(f"mpirun --allow-run-as-root --oversubscribe -np 2 {fake_dem} --resume chain.nml "
      "--extra two words" in log, f"run-chain -n 2: mpirun command line {log}")
r, log = fake_chain("progress", "-m", "3", "chain.nml")
check(r.returncode == 1 and r.stdout.count("run-chain: run ") == 3 and "-m" in r.stderr,
      f"run-chain -m 3: exit {r.returncode}, {r.stdout}{r.stderr}")
check("run-chain: run 3 exit 75 latest " + os.path.join(work, "fake_progress",
                                                        "checkpoints/checkpoint_3.h5")
      in r.stdout, f"run-chain -m 3: the run line: {r.stdout}")
r, log = fake_chain("stuck", "chain.nml")
check(r.returncode == 1 and r.stdout.count("run-chain: run ") == 1 and
      "without a newer checkpoint" in r.stderr,
      f"run-chain, no progress: exit {r.returncode}, {r.stdout}{r.stderr}")
r, log = fake_chain("fail", "chain.nml")
check(r.returncode == 3 and "failed with exit status 3" in r.stderr,
      f"run-chain, a failing run: exit {r.returncode}, {r.stderr}")
r, log = fake_chain("done", "nowhere.nml")
check(r.returncode == 2 and "nowhere.nml" in r.stderr and not log,
      f"run-chain, no case file: exit {r.returncode}, {r.stderr}")
r, log = fake_chain("done", "chain.nml", dem_path=os.path.join(work, "no-dem"))
check(r.returncode == 2 and "no-dem" in r.stderr, f"run-chain, no dem: {r.returncode}, {r.stderr}")
r, log = fake_chain("done", "-n", "x", "chain.nml")
check(r.returncode == 2 and "-n" in r.stderr, f"run-chain -n x: {r.returncode}, {r.stderr}")

write_case("sigterm")
rc, text = run_signalled([run_chain, "sigterm.nml"], env, work, signal.SIGTERM)
check(rc == 75 and text.count("run-chain: run ") == 1 and "stopped by SIGTERM" in text
      and "dem: SIGUSR1 received" in text,
      f"run-chain with SIGTERM: exit {rc}, one run, dem stopped by SIGUSR1:\n{text}")
check(os.path.exists(out("sigterm", latest("sigterm"))), "run-chain with SIGTERM: checkpoint")

# 4. the SLURM template: statically, then with stand-in sbatch and srun
r = subprocess.run(["bash", "-n", template], capture_output=True, text=True)
check(r.returncode == 0, f"bash -n {template}: {r.stderr}")
r = subprocess.run(["bash", "-n", run_chain], capture_output=True, text=True)
check(r.returncode == 0, f"bash -n {run_chain}: {r.stderr}")
text = open(template).read()
sbatch_lines = [line for line in text.splitlines() if line.startswith("#SBATCH")]
check(any(re.fullmatch(r"#SBATCH --signal=B:USR1@\d+", line) for line in sbatch_lines),
      "template: no '#SBATCH --signal=B:USR1@seconds' line")
for what, pattern in (("the SIGUSR1 trap", r"trap \w+ USR1"),
                      ("passing SIGUSR1 on", r'kill -USR1 "\$child"'),
                      ("dem --resume", r'--resume "\$case_file"'),
                      ("the test of exit status 75", r"rc != 75"),
                      ("the resubmission",
                       r'sbatch --parsable .*\n?.*"\$DEM_SBATCH_SCRIPT" "\$case_file"'),
                      ("the DEM_CHAIN_MAX guard", r"count >= DEM_CHAIN_MAX"),
                      ("the chain counter passed on", r"DEM_CHAIN_COUNT=\$\(\(count \+ 1\)\)")):
    check(re.search(pattern, text) is not None, f"template: no {what} ({pattern})")

slurm = os.path.join(work, "slurm")
os.makedirs(slurm)
slurm_log = os.path.join(slurm, "calls.log")
executable(os.path.join(stubs, "sbatch"), """#!/usr/bin/env bash
# stand-in sbatch: queues a copy of the script (as SLURM spools it) with the submitting
# environment; the test runs the queue
set -euo pipefail
echo "sbatch $*" >> "$STUB_SLURM/calls.log"
parsable=0 export_opt=ALL dependency=
while [[ $# -gt 0 && $1 == -* ]]; do
    case $1 in
        --parsable) parsable=1 ;;
        --export=*) export_opt=${1#--export=} ;;
        --dependency=*) dependency=${1#--dependency=} ;;
    esac
    shift
done
id=$(( $(cat "$STUB_SLURM/last_id" 2> /dev/null || echo 100) + 1 ))
echo $id > "$STUB_SLURM/last_id"
mkdir -p "$STUB_SLURM/spool/job$id"
cp "$1" "$STUB_SLURM/spool/job$id/slurm_script"
shift
env -0 > "$STUB_SLURM/spool/job$id/environ"
printf '%s\\n' "$PWD" "$export_opt" "$dependency" "$@" > "$STUB_SLURM/spool/job$id/job"
echo $id >> "$STUB_SLURM/queue"
if (( parsable )); then echo $id; else echo "Submitted batch job $id"; fi
""")
executable(os.path.join(stubs, "srun"), """#!/usr/bin/env bash
# stand-in srun: runs the command here (exec, so that signals reach it as srun passes them)
echo "srun $*" >> "$STUB_SLURM/calls.log"
while [[ $# -gt 0 && $1 == -* ]]; do shift; done
exec "$@"
""")


def calls():
    return open(slurm_log).read().splitlines() if os.path.exists(slurm_log) else []


def queue():
    path = os.path.join(slurm, "queue")
    return open(path).read().split() if os.path.exists(path) else []


def run_job(job_id, sig=None):
    """Run a queued job as SLURM would: its spooled script, in the submission directory,
    with the environment asked for; `sig` goes to the batch shell once dem steps."""
    spool = os.path.join(slurm, "spool", "job" + job_id)
    with open(os.path.join(spool, "job")) as f:
        submit_dir, export_opt, dependency, *args = f.read().split("\n")[:-1]
    script = os.path.join(spool, "slurm_script")
    e = {}
    if export_opt.split(",")[0] == "ALL":
        raw = open(os.path.join(spool, "environ"), "rb").read().split(b"\0")
        e = dict(item.decode().split("=", 1) for item in raw if item)
    e.update(item.split("=", 1) for item in export_opt.split(",")[1:])
    ntasks = re.search(r"^#SBATCH --ntasks=(\d+)", open(script).read(), re.M).group(1)
    e.update(SLURM_JOB_ID=job_id, SLURM_SUBMIT_DIR=submit_dir, SLURM_NTASKS=ntasks)
    rc, output = run_signalled(["bash", script, *args], e, submit_dir, sig)
    with open(os.path.join(submit_dir, f"dem-{job_id}.out"), "w") as f:
        f.write(output)
    return rc, output, dependency


write_case("slurm")
user_env = dict(os.environ, DEM=dem, DEM_CHAIN_MAX="2", STUB_SLURM=slurm,
                PATH=stubs + os.pathsep + os.environ["PATH"])
r = subprocess.run(["sbatch", template, "slurm.nml"], cwd=work, env=user_env,
                   capture_output=True, text=True)
check(r.returncode == 0 and queue() == ["101"], f"stub sbatch: {r.stdout}{r.stderr}")

rc, output, _ = run_job("101", signal.SIGUSR1)
print(output)
check(rc == 0, f"job 101: exit status {rc}")
check("dem: SIGUSR1 received" in output, "job 101: dem did not get SIGUSR1 from the batch shell")
check("dem exited with 75" in output and "resubmitted as job 102" in output,
      "job 101: no resubmission after exit status 75")
script101 = os.path.join(slurm, "spool", "job101", "slurm_script")
check(calls()[-1] == f"sbatch --parsable --dependency=afterany:101 --export=ALL,"
      f"DEM_CHAIN_COUNT=2 {script101} slurm.nml",
      f"job 101: the resubmission command: {calls()[-1:]}")
check(sum(c.startswith("srun ") for c in calls()) == 2 and
      "srun --ntasks=1 " + dem + " --resume slurm.nml" in calls(),
      f"job 101: the srun commands: {calls()}")
check(queue() == ["101", "102"], f"queue after job 101: {queue()}")
step_101 = latest("slurm")

n_calls = len(calls())
rc, output, dependency = run_job("102", signal.SIGUSR1)
print(output)
check(dependency == "afterany:101", f"job 102: dependency {dependency!r}")
check("dem: restarting from output/slurm/" + step_101 in output,
      f"job 102: dem did not resume from {step_101}")
check(rc == 75 and "DEM_CHAIN_MAX = 2 jobs reached" in output,
      f"job 102: exit status {rc}, expected 75 and the DEM_CHAIN_MAX message")
check(not any(c.startswith("sbatch") for c in calls()[n_calls:]) and queue() == ["101", "102"],
      "job 102: resubmitted beyond DEM_CHAIN_MAX")
check(latest("slurm") > step_101, "job 102: no newer checkpoint")

r = subprocess.run(["sbatch", template, "slurm.nml"], cwd=work, env=user_env,
                   capture_output=True, text=True)
check(r.returncode == 0 and queue()[-1] == "103", f"stub sbatch again: {r.stdout}{r.stderr}")
n_calls = len(calls())
rc, output, _ = run_job("103")
print(output)
check(rc == 0 and "the case is finished" in output, f"job 103: exit status {rc}")
check(not any(c.startswith("sbatch") for c in calls()[n_calls:]), "job 103: resubmitted")
check_same_end("slurm", "SLURM chain")

# the template's other ends, with the stand-in dem: a run that stops without a newer
# checkpoint is not resubmitted (exit 1), nor a failed one (its status passed on)
for mode, expect, words in (("stuck", 1, "without a newer checkpoint"),
                            ("fail", 3, "dem failed with exit status 3")):
    fake_out = os.path.join(work, "fake_slurm_" + mode)
    os.makedirs(fake_out)
    e = dict(user_env, DEM=fake_dem, FAKE_MODE=mode, FAKE_OUT=fake_out, FAKE_LOG=fake_log)
    r = subprocess.run(["sbatch", template, "slurm.nml"], cwd=work, env=e,
                       capture_output=True, text=True)
    job = queue()[-1]
    n_calls = len(calls())
    rc, output, _ = run_job(job)
    check(rc == expect and words in output,
          f"job {job} with a dem that exits {mode}: exit status {rc}:\n{output}")
    check(not any(c.startswith("sbatch") for c in calls()[n_calls:]),
          f"job {job} with a dem that exits {mode}: resubmitted")
finish()
