# SPDX-License-Identifier: BSD-3-Clause
"""Shared helpers of the regression tests: run the solver on a case, check expectations
and report failures with a non-zero exit code."""
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts", "post"))

failures = []
checks = 0


def check(condition, what):
    global checks
    checks += 1
    if not condition:
        failures.append(what)
        print("FAILED:", what)


def check_close(actual, expected, rtol, what):
    check(abs(actual - expected) <= rtol * abs(expected),
          f"{what}: got {actual:.9g}, expected {expected:.9g} (rtol {rtol:g})")


def run_dem(dem, case, workdir, expect_rc=0):
    """Run `dem case` in workdir; return (returncode, stdout, stderr)."""
    os.makedirs(workdir, exist_ok=True)
    r = subprocess.run([dem, os.path.abspath(case)], cwd=workdir, capture_output=True,
                       text=True, timeout=600)
    if expect_rc is not None and r.returncode != expect_rc:
        print(r.stdout, r.stderr)
        check(False, f"dem {case} exited with {r.returncode}, expected {expect_rc}")
    return r.returncode, r.stdout, r.stderr


def run_ranks(mpiexec, dem, case, ranks, workdir, *args, code=0):
    """Run `dem args case` on `ranks` MPI ranks from workdir; check the exit status."""
    cmd = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks), dem,
           *args, case]
    r = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True, timeout=900)
    check(r.returncode == code, f"{os.path.basename(case)} on {ranks} ranks: exit "
                                f"{r.returncode}, expected {code}: {r.stderr.strip()[-2000:]}")
    return r


def same_file(a, b, what):
    """Files a and b are the same byte for byte."""
    with open(a, "rb") as fa, open(b, "rb") as fb:
        check(fa.read() == fb.read(), f"{what}: {b} differs from {a}")


def same_snapshots(a, b, what):
    """The snapshot files a[k] and b[k] hold the same datasets, byte for byte, with the same
    attributes, and so do the snapshots.xmf beside them."""
    import h5py
    import numpy as np
    for pa, pb in zip(a, b):
        with h5py.File(pa, "r") as fa, h5py.File(pb, "r") as fb:
            names = []
            fa.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
            other = []
            fb.visititems(lambda n, o: other.append(n) if isinstance(o, h5py.Dataset) else None)
            check(names == other, f"{what}: {os.path.basename(pb)} has the datasets {other}")
            for n in names:
                da, db = fa[n], fb[n]
                check(da.dtype == db.dtype and da.shape == db.shape and
                      np.asarray(da[()]).tobytes() == np.asarray(db[()]).tobytes() and
                      dict(da.attrs) == dict(db.attrs),
                      f"{what}: {os.path.basename(pb)}: {n} differs")
    xmf = [os.path.join(os.path.dirname(os.path.dirname(p[0])), "snapshots.xmf") for p in (a, b)]
    same_file(xmf[0], xmf[1], f"{what}: snapshots.xmf")


def finish():
    print(f"{checks} checks, {len(failures)} failed")
    sys.exit(1 if failures else 0)
