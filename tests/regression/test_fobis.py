# SPDX-License-Identifier: BSD-3-Clause
"""The FoBiS.py build (the fobos at the source root, mode gnu) against the CMake one: the same
version, and the same results on Chung & Ooi test 1 (contact.csv and final.csv).
Builds into WORKDIR/build-fobis, so the source tree is left as it is.
usage: test_fobis.py DEM WORKDIR   (DEM: the CMake-built dem)

The files must be identical when the CMake build is a Release build without DEM_OPENACC,
whatever its DEM_SIMD: mode gnu is -O3 for any x86-64 processor, and the instruction sets of
DEM_SIMD (-march=x86-64-v3, x86-64-v4, with -ffp-contract=off) must not change a bit of the
results (doc/theory.md, section 13). With other flags (a Debug build, say) they are compared as numbers,
to a relative tolerance of 1e-12, and the test says so."""
import os
import shutil
import subprocess
import sys

from regression_util import ROOT, check, finish, run_dem

MODE = "gnu"
RTOL = 1e-12
STEM = "test1_sphere_sphere"

if len(sys.argv) != 3:
    sys.exit("usage: test_fobis.py DEM WORKDIR")
dem_cmake = os.path.abspath(sys.argv[1])
root, work = ROOT, os.path.abspath(sys.argv[2])


def fail(what):
    """A failure after which nothing else can be checked."""
    check(False, what)
    finish()


def find_fobis():
    """FoBiS.py next to this Python (a virtual environment's bin/), else on PATH."""
    for name in ("FoBiS.py", "fobis"):
        path = os.path.join(os.path.dirname(sys.executable), name)
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    for name in ("FoBiS.py", "fobis"):
        path = shutil.which(name)
        if path:
            return path
    return None


def cmake_flags_match(dem):
    """(True if the CMake build of `dem` must write mode gnu's bits, a description of its flags),
    from the CMakeCache.txt of its build directory."""
    cache = os.path.join(os.path.dirname(os.path.realpath(dem)), "CMakeCache.txt")
    if not os.path.isfile(cache):
        return False, "unknown (no CMakeCache.txt next to the CMake dem)"
    entries = {}
    with open(cache) as f:
        for line in f:
            if "=" in line and ":" in line.split("=", 1)[0] and not line.startswith(("#", "//")):
                key, value = line.rstrip("\n").split("=", 1)
                entries[key.split(":", 1)[0]] = value
    build_type = entries.get("CMAKE_BUILD_TYPE", "")
    openacc = entries.get("DEM_OPENACC", "OFF").upper() in ("ON", "TRUE", "1", "YES")
    description = (f"CMAKE_BUILD_TYPE={build_type or '(none)'}, "
                   f"DEM_SIMD={entries.get('DEM_SIMD', '(unset)')}"
                   + (", DEM_OPENACC=ON" if openacc else ""))
    return build_type == "Release" and not openacc, description


def version(dem):
    r = subprocess.run([dem, "--version"], capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        print(r.stdout, r.stderr)
        check(False, f"{dem} --version exited with {r.returncode}")
    return r.stdout.strip()


def read_rows(path):
    with open(path) as f:
        return [line.rstrip("\n").split(",") for line in f]


def compare_numbers(a_path, b_path, what):
    """Same header, shape and non-numeric fields; numbers within RTOL of each other, relative
    to the value or, for values near zero, to a thousandth of the largest in their column."""
    a, b = read_rows(a_path), read_rows(b_path)
    same_length = len(a) == len(b) and len(a) > 0
    check(same_length, f"{what}: {len(a)} lines from CMake, {len(b)} from FoBiS")
    if not same_length:
        return
    check(a[0] == b[0], f"{what}: headers differ: {a[0]} vs {b[0]}")
    values = []  # per row, per field: float or the text
    for rows in (a[1:], b[1:]):
        parsed = []
        for row in rows:
            fields = []
            for field in row:
                try:
                    fields.append(float(field))
                except ValueError:
                    fields.append(field.strip())
            parsed.append(fields)
        values.append(parsed)
    colmax = {}
    for rows in values:
        for row in rows:
            for j, v in enumerate(row):
                if isinstance(v, float):
                    colmax[j] = max(colmax.get(j, 0.0), abs(v))
    worst, bad = 0.0, []
    for i, (ra, rb) in enumerate(zip(*values), start=2):
        if len(ra) != len(rb):
            bad.append(f"line {i}: {len(ra)} fields vs {len(rb)}")
            continue
        for j, (va, vb) in enumerate(zip(ra, rb)):
            if isinstance(va, float) and isinstance(vb, float):
                scale = max(abs(va), abs(vb), colmax[j] * 1e-3)
                err = abs(va - vb) / scale if scale > 0 else 0.0
                worst = max(worst, err)
                if err > RTOL:
                    bad.append(f"line {i}, {a[0][j] if j < len(a[0]) else j}: {va!r} vs {vb!r}")
            elif va != vb:
                bad.append(f"line {i}, field {j + 1}: {va!r} vs {vb!r}")
    for line in bad[:5]:
        print("   ", line)
    check(not bad, f"{what}: {len(bad)} values differ by more than rtol {RTOL:g} "
          f"(largest relative difference {worst:.3g})")
    if not bad:
        print(f"{what}: equal within rtol {RTOL:g} (largest relative difference {worst:.3g})")


def show_differences(a_path, b_path, what, most=5):
    """Print the first lines that differ between two text files."""
    with open(a_path) as fa, open(b_path) as fb:
        a, b = fa.read().splitlines(), fb.read().splitlines()
    if len(a) != len(b):
        print(f"    {what}: {len(a)} lines from CMake, {len(b)} from FoBiS")
    shown = 0
    for i, (la, lb) in enumerate(zip(a, b), start=1):
        if la != lb and shown < most:
            print(f"    line {i}, CMake: {la[:100]}")
            print(f"    line {i}, FoBiS: {lb[:100]}")
            shown += 1


# --- build with FoBiS into the work directory --------------------------------------------------
fobis = find_fobis()
if fobis is None:
    fail("FoBiS.py not found next to the Python running this test "
         f"({os.path.dirname(sys.executable)}) nor on PATH: pip install FoBiS.py")
build_dir = os.path.join(work, "build-fobis")
dem_fobis = os.path.join(build_dir, "dem")
if os.path.exists(dem_fobis):
    os.remove(dem_fobis)  # so an old executable cannot pass for this build's
command = [fobis, "build", "-f", os.path.join(root, "fobos"), "-mode", MODE,
           "--build-dir", build_dir, "-q", "-j", str(min(os.cpu_count() or 1, 8))]
print("building:", " ".join(command))
# fobos paths (src, include) are relative to the source root: FoBiS runs there
r = subprocess.run(command, cwd=root, capture_output=True, text=True, timeout=1800)
if r.returncode != 0 or not os.path.isfile(dem_fobis):
    print(r.stdout[-6000:], r.stderr[-6000:])
    fail(f"FoBiS.py build -mode {MODE} failed (exit status {r.returncode}, "
         f"{dem_fobis} {'exists' if os.path.isfile(dem_fobis) else 'missing'})")

# --- the same version -------------------------------------------------------------------------
v_cmake, v_fobis = version(dem_cmake), version(dem_fobis)
check(v_cmake.startswith("dem "), f"CMake dem --version printed {v_cmake!r}")
check(v_fobis == v_cmake, f"dem --version: FoBiS build {v_fobis!r}, CMake build {v_cmake!r}")

# --- the same results on Chung & Ooi test 1 ---------------------------------------------------
case = os.path.join(root, "cases", "verification", STEM + ".nml")
outputs = {}
for name, dem in (("cmake", dem_cmake), ("fobis", dem_fobis)):
    rundir = os.path.join(work, "run-" + name)
    outdir = os.path.join(rundir, "output", STEM)
    shutil.rmtree(outdir, ignore_errors=True)  # no earlier run's files
    run_dem(dem, case, rundir)
    outputs[name] = outdir

strict, cmake_flags = cmake_flags_match(dem_cmake)
if strict:
    print(f"CMake build: {cmake_flags}: the outputs must be identical to mode {MODE}'s")
else:
    print(f"NOTE: CMake build: {cmake_flags}, not the flags of mode {MODE} (Release): "
          f"the outputs are compared as numbers, rtol {RTOL:g}")
for fname in ("contact.csv", "final.csv"):
    a = os.path.join(outputs["cmake"], fname)
    b = os.path.join(outputs["fobis"], fname)
    present = os.path.isfile(a) and os.path.isfile(b)
    check(present, f"{STEM}/{fname}: missing from the CMake run ({a}) or the FoBiS run ({b})")
    if not present:
        continue
    with open(a, "rb") as fa, open(b, "rb") as fb:
        identical = fa.read() == fb.read()
    if strict:
        if not identical:
            show_differences(a, b, f"{STEM}/{fname}")
        check(identical, f"{STEM}/{fname}: the FoBiS and CMake builds (same flags) wrote "
              "different files")
    elif identical:
        print(f"{STEM}/{fname}: identical")
    else:
        compare_numbers(a, b, f"{STEM}/{fname}")
finish()
