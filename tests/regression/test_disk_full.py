# SPDX-License-Identifier: BSD-3-Clause
"""A text output that cannot be written stops the run with a clear error, and what was
written before is whole (issue 30, items 1-2).

1. Injected, anywhere: the output folder's histogram_h.csv is a symbolic link to /dev/full
   (every write to it fails with ENOSPC once flushed). The run must exit with status 4 (a
   file could not be written), print one `dem: error:` naming histogram_h.csv, no signal or
   backtrace, not say "done", and leave series.csv of whole rows (each with the header's
   ten columns, the file ending with a line end), no final.csv.
2. A real full disk, where a small tmpfs can be mounted (root with the right to mount;
   skipped otherwise, said so): the output folder on a 150 KiB tmpfs, a run whose
   series.csv and probes.csv outgrow it. The same expectations, for the file that filled
   it, and series.csv and probes.csv both of whole rows, none with a NUL byte.
3. HDF5 files on a full disk (the same tmpfs, where it can be mounted): 500 spheres with a
   checkpoint every 5 ms and the default snapshots, on tmpfs of 300, 500, 700 and 900 KiB
   (which made the run die with SIGSEGV inside HDF5 at most sizes: issue 30, item 1). The
   run must exit with status 4 and one `dem: error:` naming the .h5.part file it could not
   write, no crash; every checkpoint left in the folder is whole (its checksums match)
   and checkpoints/latest names one of them; with the tmpfs grown to 4 MiB, `dem --resume`
   continues from it to the end (exit 0, final.csv).
usage: test_disk_full.py DEM WORKDIR"""
import os
import shutil
import subprocess
import sys

from regression_util import check, finish
import checkpoint_util as cu

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
if os.path.exists(work):
    shutil.rmtree(work)
os.makedirs(work)

CASE = """&run dt = 1e-5, t_end = {t_end}, gravity = 0, 0, -9.81 /
&output dir = '{out}', interval = 1e-4, snapshot_interval = 0 /
&material name = 'glass', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'glass', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05 /
&insert n = 20, material = 'glass', radius_min = 1e-3, region = 'box',
        box_min = -0.01, -0.01, 0, box_max = 0.01, 0.01, 0.02, seed = 1 /
&probe name = 'all', kind = 'count', box_min = -1, -1, -1, box_max = 1, 1, 1 /
&probe name = 'h', kind = 'histogram', time = 0.005, v_min = -1, v_max = 1 /
"""


def whole(path, columns):
    """True if the CSV file is whole rows of `columns` columns, ending with a line end."""
    text = open(path, "rb").read()
    rows = text.split(b"\n")
    return (text.endswith(b"\n") and b"\0" not in text
            and all(r.count(b",") == columns - 1 for r in rows[:-1]))


def run(out, t_end, failing):
    case = os.path.join(work, os.path.basename(out) + ".nml")
    with open(case, "w") as f:
        f.write(CASE.format(out=out, t_end=t_end))
    r = subprocess.run([dem, case], cwd=work, capture_output=True, text=True, timeout=300)
    text = r.stdout + r.stderr
    errors = [line for line in text.splitlines() if line.startswith("dem: error:")]
    check(r.returncode == 4, f"{failing}: exit {r.returncode}, expected 4")
    check(len(errors) == 1 and failing in errors[0] and "cannot write" in errors[0],
          f"{failing}: the error lines: {errors}")
    check("Backtrace" not in text and "dem: done" not in text,
          f"{failing}: a backtrace or 'done' in the output: {text[-400:]}")
    check(whole(os.path.join(out, "series.csv"), 10), f"{failing}: series.csv not whole rows")
    check(not os.path.exists(os.path.join(out, "final.csv")), f"{failing}: final.csv written")
    return text


# 1. injected
out = os.path.join(work, "injected")
os.makedirs(out)
os.symlink("/dev/full", os.path.join(out, "histogram_h.csv"))
run(out, 0.02, "histogram_h.csv")

# 2. a real full disk
mnt = os.path.join(work, "tmpfs")
os.makedirs(mnt)
mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=150k", "tmpfs", mnt],
                         capture_output=True).returncode == 0
if not mounted:
    print("no tmpfs could be mounted here (not root, or no right to mount): part 2 skipped")
else:
    try:
        out = os.path.join(mnt, "out")
        text = run(out, 0.2, ".csv")
        check(whole(os.path.join(out, "probes.csv"), 3), "tmpfs: probes.csv not whole rows")
        print("tmpfs: " + [line for line in text.splitlines() if "error" in line][0])
    finally:
        subprocess.run(["umount", mnt])

# 3. HDF5 files on a full disk
H5_CASE = """&run dt = 1e-5, t_end = 0.05, gravity = 0, 0, -9.81 /
&output dir = '{out}', checkpoint_interval = 0.005 /
&material name = 'glass', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'glass', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05 /
&insert n = 500, material = 'glass', radius_min = 0.001, region = 'box',
        box_min = -0.02, -0.02, 0.001, box_max = 0.02, 0.02, 0.05, seed = 1 /
"""
for size in ("300k", "500k", "700k", "900k") if mounted else ():
    if subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", mnt],
                      capture_output=True).returncode != 0:
        check(False, f"h5 {size}: the tmpfs could not be mounted again")
        continue
    try:
        out = os.path.join(mnt, "out")
        case = os.path.join(work, f"h5_{size}.nml")
        with open(case, "w") as f:
            f.write(H5_CASE.format(out=out))
        r = subprocess.run([dem, case], cwd=work, capture_output=True, text=True, timeout=300)
        text = r.stdout + r.stderr
        errors = [line for line in text.splitlines() if line.startswith("dem: error:")]
        print(f"h5 {size}: exit {r.returncode}: {errors}")
        check(r.returncode == 4, f"h5 {size}: exit {r.returncode}, expected 4")
        check(len(errors) == 1 and ".h5.part" in errors[0] and "cannot write" in errors[0],
              f"h5 {size}: the error lines: {errors}")
        check(not cu.crash_signs(text), f"h5 {size}: signs of a crash: {cu.crash_signs(text)}")
        names = [n for n in cu.checkpoint_files(out) if n.endswith(".h5")]
        for name in names:
            check(not cu.bad_checksums(os.path.join(out, "checkpoints", name)),
                  f"h5 {size}: {name} is not whole")
        if names:
            check(cu.latest(out) == os.path.join("checkpoints", names[-1]),
                  f"h5 {size}: checkpoints/latest names {cu.latest(out)}, not {names[-1]}")
            subprocess.run(["mount", "-o", "remount,size=4m", mnt], check=True)
            r = subprocess.run([dem, "--resume", case], cwd=work, capture_output=True,
                               text=True, timeout=300)
            check(r.returncode == 0 and os.path.exists(os.path.join(out, "final.csv")),
                  f"h5 {size}: --resume exit {r.returncode}: {r.stderr.strip()[-300:]}")
    finally:
        subprocess.run(["umount", mnt])
finish()
