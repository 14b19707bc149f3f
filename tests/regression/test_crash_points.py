# SPDX-License-Identifier: BSD-3-Clause
"""A run killed at any rename, unlink or ftruncate leaves a folder that `dem --resume`
continues exactly, or refuses with a message.

The case (60 spheres falling into a box, a probe, 21 rows of series.csv and probes.csv,
snapshots and checkpoints every 0.0025 s to 0.01 s, checkpoint_keep 2) is run once
straight through: the reference. Then for three ways of starting a run,
  fresh:   `dem CASE` into an empty folder,
  over:    `dem CASE` over the finished run of the same case (the folder is cleared first),
  restart: `dem --restart` from the older of the two checkpoints the finished run kept,
each file operation that publishes or removes something is counted (strace -f -c: the
calls of rename, unlink and ftruncate, the lock's included), and for every K and each of
the three calls the run is started again under `strace -f -e inject=CALL:signal=KILL:when=K`,
which kills it (SIGKILL, no handler runs) as it enters its K-th such call. `dem --resume
CASE` must then either end with exit 0 and series.csv, probes.csv, final.csv and
snapshots.xmf byte for byte the reference's, every snapshot listed there, and the same
checkpoints as the reference (no checkpoint beyond checkpoint_keep left for good), or be
refused with exit status 2 and a message (`dem: error: ...`); never a crash, never "done"
with an output missing. Skipped, with a message, where strace is not installed
(scripts/install/install-deps installs it).
usage: test_crash_points.py DEM WORKDIR"""
import os
import re
import shutil
import subprocess
import sys
import time

from regression_util import check, finish
import checkpoint_util as cu

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
strace = shutil.which("strace")
if strace is None:
    print("skipped: strace is not installed (Debian package strace; "
          "scripts/install/install-deps installs it)")
    sys.exit(0)
if os.path.exists(work):
    shutil.rmtree(work)
os.makedirs(work)
out = os.path.join(work, "output", "box")
ref = os.path.join(work, "reference")
CALLS = ("rename", "unlink", "ftruncate")
OUTPUTS = ("series.csv", "probes.csv", "final.csv", "snapshots.xmf")

case = os.path.join(work, "box.nml")
with open(case, "w") as f:
    f.write("""&run dt = 1e-5, t_end = 0.01, gravity = 0, 0, -9.81, progress_interval = 0 /
&output dir = 'output/box', interval = 0.0005, snapshot_interval = 0.0025,
        checkpoint_interval = 0.0025, checkpoint_keep = 2 /
&material name = 'glass', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'glass', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05 /
&wall_plane material = 'glass', point = -0.01, 0, 0, normal = 1, 0, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0.01, 0, 0, normal = -1, 0, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0, -0.01, 0, normal = 0, 1, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0, 0.01, 0, normal = 0, -1, 0, half_width = 0.05 /
&insert n = 60, material = 'glass', radius_min = 1e-3, region = 'box',
        box_min = -0.01, -0.01, 0, box_max = 0.01, 0.01, 0.02, seed = 1 /
&probe name = 'com', kind = 'center_of_mass' /
""")


def run(args, prefix=()):
    return subprocess.run([*prefix, dem, *args], cwd=work, capture_output=True, text=True,
                          timeout=300)


def snapshot_of(folder):
    """{output: bytes}, the listed snapshots that are missing, and the checkpoint files."""
    files = {}
    for name in OUTPUTS:
        p = os.path.join(folder, name)
        files[name] = open(p, "rb").read() if os.path.exists(p) else None
    listed = re.findall(r"snapshots/snapshot_\d+\.h5", (files["snapshots.xmf"] or b"").decode())
    missing = [s for s in listed if not os.path.exists(os.path.join(folder, s))]
    return files, missing, cu.checkpoint_files(folder)


t0 = time.monotonic()
r = run([case])
check(r.returncode == 0, f"the reference run: exit {r.returncode}: {r.stderr[-300:]}")
shutil.copytree(out, ref)
expected, missing, checkpoints = snapshot_of(ref)
check(not missing and len(checkpoints) == 3, f"the reference: snapshots missing {missing}, "
      f"checkpoints {checkpoints}")
older = os.path.join("output", "box", "checkpoints", checkpoints[0])   # the older one kept

SCENARIOS = {"fresh": (lambda: None, [case]),
             "over": (lambda: shutil.copytree(ref, out), [case]),
             "restart": (lambda: shutil.copytree(ref, out), ["--restart", older, case])}


def counts(prepare, args):
    """{call: how many times the run makes it}."""
    shutil.rmtree(out, ignore_errors=True)
    prepare()
    r = run(args, [strace, "-f", "-c", "-e", "trace=" + ",".join(CALLS)])
    check(r.returncode == 0, f"dem {' '.join(args)} under strace: exit {r.returncode}")
    n = {c: 0 for c in CALLS}
    for line in r.stderr.splitlines():
        f = line.split()
        if len(f) >= 5 and f[-1] in n and f[3].isdigit():
            n[f[-1]] = int(f[3])
    return n


tried = refused = 0
for name, (prepare, args) in SCENARIOS.items():
    n = counts(prepare, args)
    print(f"{name}: {n}")
    check(n["rename"] > 5 and n["unlink"] > 0, f"{name}: too few calls counted: {n}")
    for call in CALLS:
        for k in range(1, n[call] + 1):
            shutil.rmtree(out, ignore_errors=True)
            prepare()
            where = f"{name}, killed at {call} {k} of {n[call]}"
            killed = run(args, [strace, "-f", "-o", os.devnull, "-e", "trace=" + call,
                                "-e", f"inject={call}:signal=KILL:when={k}"])
            r = run(["--resume", case])
            tried += 1
            text = r.stdout + r.stderr
            check(not cu.crash_signs(text), f"{where}: --resume crashed: {text[-400:]}")
            if r.returncode == 2 and "dem: error: " in r.stderr:
                refused += 1
                print(f"{where}: refused: {r.stderr.strip()[-200:]}")
                continue
            check(r.returncode == 0, f"{where} (the run: exit {killed.returncode}): --resume "
                  f"exit {r.returncode}: {r.stderr.strip()[-300:]}")
            files, missing, ckpts = snapshot_of(out)
            differ = [f for f in OUTPUTS if files[f] != expected[f]]
            check(not differ and not missing and ckpts == checkpoints,
                  f"{where}: after --resume, differ from the reference: {differ}, snapshots "
                  f"listed but missing: {missing}, checkpoints {ckpts} (expected "
                  f"{checkpoints})")
print(f"{tried} kills, {refused} refused by --resume, {time.monotonic() - t0:.1f} s")
finish()
