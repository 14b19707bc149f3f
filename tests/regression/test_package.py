# SPDX-License-Identifier: BSD-3-Clause
"""find_package(dem) works for a fluid code: this build is installed into WORKDIR/prefix, and
tests/consumer (a Fortran and a C program, built with CMake against dem::dem only) is
configured, built and run against the install: the C program's coupling checks pass on 2
ranks, and the Fortran program advances ten fluid steps to t = 1e-3 s. The shared library
libdem.so is installed and exports the functions of dem_coupling.h, and nothing else.
usage: test_package.py DEM WORKDIR BUILD_DIR MPIEXEC"""
import os
import re
import shutil
import subprocess
import sys

from regression_util import ROOT, check, finish

dem, work, build, mpiexec = (os.path.abspath(a) for a in sys.argv[1:5])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
prefix = os.path.join(work, "prefix")


def step(what, cmd, cwd=work):
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=600)
    check(r.returncode == 0, f"{what}: exit {r.returncode}: {(r.stdout + r.stderr)[-3000:]}")
    if r.returncode != 0:
        finish()
    return r.stdout


step("install", ["cmake", "--install", build, "--prefix", prefix])
for f in ("lib/cmake/dem/demConfig.cmake", "include/dem/dem_coupling.mod",
          "include/dem/dem_coupling.h", "share/doc/dem/README.md", "share/doc/dem/theory.md",
          "share/doc/dem/user/input.md", "share/dem/cases/silo/README.md",
          "share/dem/examples/drum/drum.nml", "share/dem/examples/hopper/hopper.stl"):
    check(os.path.exists(os.path.join(prefix, f)), f"installed {f}")
# relocatable: the exported targets name imported targets (found again by demConfig.cmake
# where the package is used), not absolute paths of this machine's libraries
for f in os.listdir(os.path.join(prefix, "lib", "cmake", "dem")):
    if f.startswith("demTargets"):
        with open(os.path.join(prefix, "lib", "cmake", "dem", f)) as g:
            text = g.read()
        check("/usr/" not in text and ROOT not in text and build not in text,
              f"{f} holds no absolute path of the build machine")
# the shared library: exactly the C interface (the functions the header declares)
library = os.path.join(prefix, "lib", "libdem.so")
check(os.path.exists(library), "installed lib/libdem.so")
with open(os.path.join(ROOT, "src", "api", "dem_coupling.h")) as f:
    declared = set(re.findall(r"\b(dem_coupling_\w+)\(", f.read()))
symbols = step("the library's symbols", ["nm", "-D", "--defined-only", library])
exported = {line.split()[-1] for line in symbols.splitlines()
            if len(line.split()) == 3 and line.split()[1] in "TDBR"}
check(exported == declared, f"libdem.so exports the header's {len(declared)} functions: "
      f"missing {sorted(declared - exported)}, more {sorted(exported - declared)}")
cache = open(os.path.join(build, "CMakeCache.txt")).read().splitlines()
setting = {k.split(":")[0]: v for k, _, v in (line.partition("=") for line in cache) if ":" in k}
consumer = os.path.join(work, "consumer")
step("configure the consumer", ["cmake", "-S", os.path.join(ROOT, "tests", "consumer"), "-B",
                                consumer, "-G", "Ninja", f"-Ddem_DIR={prefix}/lib/cmake/dem",
                                f"-DCMAKE_Fortran_COMPILER={setting['CMAKE_Fortran_COMPILER']}",
                                f"-DCMAKE_BUILD_TYPE={setting['CMAKE_BUILD_TYPE']}"])
step("build the consumer", ["cmake", "--build", consumer])
mpirun = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", "2"]
out = step("the C coupling checks on 2 ranks", mpirun + [os.path.join(consumer, "fluid_c")])
check("all checks passed" in out, f"fluid_c: {out}")
case = os.path.join(work, "coupling_c_2.nml")           # the case fluid_c wrote
out = step("the Fortran fluid code", mpirun + [os.path.join(consumer, "fluid_f"), case])
check("t =  1.00000E-03 s" in out, f"fluid_f: {out}")
finish()
