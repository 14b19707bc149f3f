# SPDX-License-Identifier: BSD-3-Clause
"""The Python package as a user installs it: `pip install ./python` into a fresh virtual
environment (with the system's site packages, as the project's .venv), no compiler, no
index; imported from outside the source tree, the installed copy is the one used; without
a library to find it says how to give one (DEM_LIBRARY); with DEM_LIBRARY it runs the worked
example of doc/user/python.md (python/examples/settling.py) to the analytical terminal
velocity; and after `cmake --install` into the environment's prefix it finds libdem.so
there with no variable set.
usage: test_python_package.py DEM WORKDIR BUILD_DIR LIBDEM"""
import os
import re
import shutil
import subprocess
import sys

from regression_util import ROOT, check, finish

dem, work, build, libdem = (os.path.abspath(a) for a in sys.argv[1:5])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
venv = os.path.join(work, "venv")
python = os.path.join(venv, "bin", "python")
env = {k: v for k, v in os.environ.items()
       if k not in ("DEM_LIBRARY", "PYTHONPATH", "LD_LIBRARY_PATH")}


def step(what, cmd, extra_env=None, expect=0):
    """Run cmd in WORKDIR; check its exit status; return its output."""
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=600,
                       env=dict(env, **(extra_env or {})))
    out = r.stdout + r.stderr
    check(r.returncode == expect, f"{what}: exit {r.returncode}, expected {expect}: "
          f"{out[-3000:]}")
    if r.returncode != expect:
        finish()
    return out


# a copy of python/: pip builds in the folder it is given (build/, dem.egg-info)
source = os.path.join(work, "python")
shutil.copytree(os.path.join(ROOT, "python"), source,
                ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
step("make the virtual environment",
     [sys.executable, "-m", "venv", "--system-site-packages", venv])
out = step("pip install ./python", [python, "-m", "pip", "install", "--no-build-isolation",
                                    "--no-deps", "--no-index", source])
check("Successfully installed dem" in out, f"pip says it installed dem: {out[-500:]}")
out = step("import the installed package", [python, "-c", "import dem; print(dem.__file__)"])
check(out.strip().startswith(venv), f"the installed copy is imported: {out.strip()}")

probe = ("import dem\ntry:\n    print(dem.library_path())\nexcept OSError as e:\n"
         "    print('ERROR', e)\n")
out = step("no library given", [python, "-c", probe])
if out.startswith("ERROR"):
    check("DEM_LIBRARY" in out and "cmake --install" in out,
          f"the error says how to give the library: {out}")
else:
    print(f"(a libdem.so is installed on this machine: {out.strip()})")

example = os.path.join(ROOT, "python", "examples", "settling.py")
out = step("the worked example with DEM_LIBRARY", [python, example, "settling"],
           {"DEM_LIBRARY": libdem})
m = re.search(r"simulated ([\d.]+) mm/s, analytical ([\d.]+) mm/s", out)
check(m is not None, f"the example prints its result: {out[-1000:]}")
if m:
    simulated, analytical = float(m.group(1)), float(m.group(2))
    check(abs(analytical - 3.27) < 1e-9, f"analytical 2 (rho_p - rho_f) g R^2 / (9 mu) = "
          f"3.27 mm/s: {analytical}")
    check(abs(simulated - analytical) < 1e-4 * analytical,
          f"terminal velocity {simulated} mm/s, analytical {analytical} mm/s")
check(os.path.exists(os.path.join(work, "settling", "output", "final.csv")),
      "the example's run wrote final.csv")

step("cmake --install into the environment", ["cmake", "--install", build, "--prefix", venv])
out = step("the library of the install prefix",
           [python, "-c", "import dem; print(dem.library_path()); print(dem.library_version())"])
lines = out.split()
check(len(lines) >= 2 and lines[0] == os.path.join(venv, "lib", "libdem.so"),
      f"found in the prefix: {out}")
with open(os.path.join(ROOT, "src", "base", "dem_version.f90")) as f:
    version = re.search(r"dem_version_string = '([^']+)'", f.read()).group(1)
check(len(lines) >= 2 and lines[1] == version, f"its version {lines[1:]} is {version}")
out = step("the worked example with the installed library", [python, example, "settling2"])
check("analytical 3.270000 mm/s" in out, f"the example runs: {out[-500:]}")
finish()
