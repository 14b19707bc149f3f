# SPDX-License-Identifier: BSD-3-Clause
"""An output folder belongs to one run, and a damaged `checkpoints/latest` is refused.

A case (60 spheres falling into a box, snapshots and checkpoints every 0.01 s to 0.05 s) is
run to its end. Then, each judged from the files in the folder (listed and hashed here):
1. The case edited (another friction), run afresh into the same folder: refused with exit
   status 2 and a message naming the folder and the way out; the folder byte for byte as it
   was (issue 30: the old run's checkpoint would have been resumed with the new case).
   `dem --check` of the edited case warns that a fresh run would stop so (exit 0: a
   --resume may still continue the run), and of the unchanged case does not.
2. The same with `&output overwrite = .true.` and t_end = 0.025: it runs, and the folder
   then holds this run's outputs only: its input.nml is the edited case, series.csv ends at
   0.025 s, and no snapshot or checkpoint of a step after the new run's last is left (the
   old run's would be; the snapshots listed by snapshots.xmf are exactly those on disk).
3. The unchanged case run afresh again: accepted (a rerun of the same case), and its
   series.csv equals the first run's byte for byte.
4. A folder with outputs but no input.nml (written by another program, or an older dem):
   refused, as 1.
5. `checkpoints/latest` emptied, then `dem --resume`: exit 2, the message names latest and
   says it is empty, nothing written; `latest` naming a file that is not there: the same,
   naming that file. With no `latest` at all, --resume starts from t = 0 (doc/user/running.md).
usage: test_output_folder.py DEM WORKDIR"""
import hashlib
import os
import re
import shutil
import subprocess
import sys

from regression_util import check, finish, run_dem

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
if os.path.exists(work):
    shutil.rmtree(work)
os.makedirs(work)
out = os.path.join(work, "output", "box")

CASE = """&run dt = 1e-5, t_end = {t_end}, gravity = 0, 0, -9.81 /
&output dir = 'output/box', interval = 0.005, snapshot_interval = 0.01,
        checkpoint_interval = 0.01{extra} /
&material name = 'glass', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = {mu} /
&wall_plane material = 'glass', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05 /
&wall_plane material = 'glass', point = -0.01, 0, 0, normal = 1, 0, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0.01, 0, 0, normal = -1, 0, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0, -0.01, 0, normal = 0, 1, 0, half_width = 0.05 /
&wall_plane material = 'glass', point = 0, 0.01, 0, normal = 0, -1, 0, half_width = 0.05 /
&insert n = 60, material = 'glass', radius_min = 1e-3, region = 'box',
        box_min = -0.01, -0.01, 0, box_max = 0.01, 0.01, 0.02, seed = 1 /
"""


def case(t_end=0.05, mu=0.3, extra=""):
    path = os.path.join(work, "box.nml")
    with open(path, "w") as f:
        f.write(CASE.format(t_end=t_end, mu=mu, extra=extra))
    return path


def folder():
    """{relative path: sha256} of every file under the output folder."""
    files = {}
    for root, _, names in os.walk(out):
        for n in names:
            p = os.path.join(root, n)
            files[os.path.relpath(p, out)] = hashlib.sha256(open(p, "rb").read()).hexdigest()
    return files


def steps(sub, prefix):
    d = os.path.join(out, sub)
    return sorted(int(m.group(1)) for n in os.listdir(d)
                  if (m := re.fullmatch(prefix + r"_(\d+)\.h5", n)))


def run(args, expect):
    r = subprocess.run([dem] + args, cwd=work, capture_output=True, text=True, timeout=300)
    check(r.returncode == expect, f"dem {' '.join(args)}: exit {r.returncode}, expected "
          f"{expect}: {r.stderr.strip()[:300]}")
    return r.stdout + r.stderr


run_dem(dem, case(), work)
first = folder()
series = open(os.path.join(out, "series.csv"), "rb").read()
check("input.nml" in first and len(steps("checkpoints", "checkpoint")) >= 2
      and len(steps("snapshots", "snapshot")) == 6, "the first run's outputs: " +
      ", ".join(sorted(first)))

# 1. an edited case, run afresh
text = run([case(mu=0.6)], 2)
check("output/box: holds the outputs of a run of another case" in text
      and "overwrite = .true." in text, f"edited case: the message: {text.strip()[-300:]}")
check(folder() == first, "edited case: the folder changed")
# --check says so (a warning: --resume of an edited case may still continue the run), and
# says nothing of the kind for the case whose run it is
text = run(["--check", case(mu=0.6)], 0)
check("warning: a fresh run stops at once: " in text and "holds the outputs of a run of "
      "another case" in text, f"edited case: --check does not warn: {text.strip()[-300:]}")
text = run(["--check", case()], 0)
check("warning: a fresh run stops" not in text, "the same case: --check warns")
check(folder() == first, "--check: the folder changed")

# 2. with overwrite, a shorter run
run([case(t_end=0.025, mu=0.6, extra=", overwrite = .true.")], 0)
now = folder()
last = int(round(0.025 / 1e-5))
check(open(os.path.join(out, "input.nml")).read() == open(case(t_end=0.025, mu=0.6,
      extra=", overwrite = .true.")).read(), "overwrite: input.nml is not the new case")
rows = open(os.path.join(out, "series.csv")).read().splitlines()
check(abs(float(rows[-1].split(",")[0]) - 0.025) < 1e-12, f"overwrite: series.csv ends at "
      f"{rows[-1].split(',')[0]}")
check(max(steps("snapshots", "snapshot")) <= last and max(steps("checkpoints", "checkpoint"))
      <= last, "overwrite: the old run's later snapshots or checkpoints are left: "
      + ", ".join(sorted(k for k in now if "/" in k)))
listed = sorted(set(re.findall(r"snapshots/(snapshot_\d+\.h5)",
                               open(os.path.join(out, "snapshots.xmf")).read())))
check(listed == sorted(os.listdir(os.path.join(out, "snapshots"))),
      f"overwrite: snapshots.xmf lists {listed}, the folder holds "
      f"{sorted(os.listdir(os.path.join(out, 'snapshots')))}")

# 3. the first case again: a rerun of the same case
shutil.rmtree(out)
run_dem(dem, case(), work)
run([case()], 0)
check(open(os.path.join(out, "series.csv"), "rb").read() == series,
      "rerun of the same case: series.csv differs from the first run's")

# 4. outputs without input.nml
os.remove(os.path.join(out, "input.nml"))
before = folder()
text = run([case()], 2)
check("has no input.nml" in text, f"no input.nml: the message: {text.strip()[-300:]}")
check(folder() == before, "no input.nml: the folder changed")

# 5. a damaged latest
run_dem(dem, case(extra=", overwrite = .true."), work)
latest = os.path.join(out, "checkpoints", "latest")
for content, says in (("", "empty or unreadable"),
                      ("checkpoints/checkpoint_000000999999.h5\n",
                       "names checkpoints/checkpoint_000000999999.h5, which is not there")):
    with open(latest, "w") as f:
        f.write(content)
    before = folder()
    text = run(["--resume", case(extra=", overwrite = .true.")], 2)
    check("checkpoints/latest: " + says in text, f"latest {content!r}: the message: "
          f"{text.strip()[-300:]}")
    check(folder() == before, f"latest {content!r}: the folder changed")
os.remove(latest)
text = run(["--resume", case(extra=", overwrite = .true.")], 0)
check("restarting" not in text, "no latest: --resume did not start from t = 0")
finish()
