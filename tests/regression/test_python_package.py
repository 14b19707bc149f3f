# SPDX-License-Identifier: BSD-3-Clause
"""The Python package as a user installs it: `pip install ./python` into a fresh virtual
environment builds libdem.so with the project's CMake (scikit-build-core) and puts it in
the package; imported from outside the source tree, with no DEM_LIBRARY, the installed copy
and its own library are the ones used, of the solver's version; a sphere dropped through it
falls at v = -g t and z = z0 - g t^2 / 2 (velocity Verlet is exact for a constant
acceleration); the worked example of doc/user/python.md (python/examples/settling.py) runs
with no variable to the analytical terminal velocity; DEM_LIBRARY still overrides.

Nothing is downloaded: the environment sees the system's packages (numpy) and those of the
interpreter running this test (the project's .venv: scikit-build-core, f90nml, as
scripts/install/install-deps installs them), and pip builds without build isolation and
without the package index. Without scikit-build-core there, pip takes it from the index.
usage: test_python_package.py DEM WORKDIR LIBDEM"""
import os
import re
import shutil
import subprocess
import sys
import sysconfig

from regression_util import ROOT, check, check_close, finish

dem, work, libdem = (os.path.abspath(a) for a in sys.argv[1:4])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
venv = os.path.join(work, "venv")
python = os.path.join(venv, "bin", "python")
env = {k: v for k, v in os.environ.items()
       if k not in ("DEM_LIBRARY", "PYTHONPATH", "LD_LIBRARY_PATH")}


def step(what, cmd, extra_env=None, expect=0):
    """Run cmd in WORKDIR; check its exit status; return its standard output."""
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=900,
                       env=dict(env, **(extra_env or {})))
    check(r.returncode == expect, f"{what}: exit {r.returncode}, expected {expect}: "
          f"{(r.stdout + r.stderr)[-3000:]}")
    if r.returncode != expect:
        finish()
    return r.stdout


def python_out(what, code, extra_env=None):
    """The lines printed by `code` run by the environment's Python in WORKDIR."""
    return step(what, [python, "-c", code], extra_env).split("\n")


step("make the virtual environment",
     [sys.executable, "-m", "venv", "--system-site-packages", venv])
site = subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()"
                       "['purelib'])"], capture_output=True, text=True).stdout.strip()
with open(os.path.join(site, "project_packages.pth"), "w") as f:
    f.write(sysconfig.get_paths()["purelib"] + "\n")
try:
    import scikit_build_core                                  # noqa: F401
    offline = ["--no-build-isolation", "--no-index"]
except ImportError:
    offline = []
    print("(no scikit-build-core beside this Python: pip builds it from the package index)")
out = step("pip install ./python", [python, "-m", "pip", "install", *offline,
                                    os.path.join(ROOT, "python")])
check("Successfully installed dem-granular" in out,
      f"pip says it installed dem-granular: {out[-500:]}")

package = os.path.join(site, "dem")
lines = python_out("import the installed package",
                   "import dem\nprint(dem.__file__)\nprint(dem.library_path())\n"
                   "print(dem.library_version())")
check(lines[0] == os.path.join(package, "__init__.py"), f"the installed copy: {lines[0]}")
check(lines[1] == os.path.join(package, "libdem.so"), f"the package's library: {lines[1]}")
with open(os.path.join(ROOT, "src", "base", "dem_version.f90")) as f:
    version = re.search(r"dem_version_string = '([^']+)'", f.read()).group(1)
check(lines[2] == version, f"its version {lines[2]} is {version}")

# a sphere in free fall for T through the installed package
g, dt, t, z0 = 9.81, 5e-5, 0.1, 1.0
with open(os.path.join(work, "fall.nml"), "w") as f:
    f.write(f"""&run dt = {dt}, t_end = 1.0, gravity = 0, 0, {-g},
     integrator = 'velocity_verlet' /
&output dir = '{work}/fall', interval = 0.05, overwrite = .true. /
&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&particle id = 1, material = 'glass', radius = 1e-3, position = 0, 0, {z0} /
""")
lines = python_out("a free fall", f"""import dem
with dem.Run('fall.nml') as run:
    run.advance({t})
    p = run.particles()
    print(repr(run.time), repr(p.v[0, 2]), repr(p.x[0, 2]))""")
time, v, z = (float(x) for x in lines[0].split())
check_close(time, t, 1e-12, "the time after the advance")
check_close(v, -g * t, 1e-9, "free fall: v = -g t")
check_close(z, z0 - 0.5 * g * t**2, 1e-9, "free fall: z = z0 - g t^2 / 2")
check(os.path.exists(os.path.join(work, "fall", "final.csv")), "the run wrote final.csv")

example = os.path.join(ROOT, "python", "examples", "settling.py")
out = step("the worked example, no variable", [python, example, "settling"])
m = re.search(r"simulated ([\d.]+) mm/s, analytical ([\d.]+) mm/s", out)
check(m is not None, f"the example prints its result: {out[-1000:]}")
if m:
    v_t = 2 * (2500.0 - 1000.0) * 9.81 * 1e-3**2 / (9 * 1.0) * 1e3     # mm/s
    check_close(float(m.group(2)), v_t, 1e-9, "analytical 2 (rho_p - rho_f) g R^2 / (9 mu)")
    check_close(float(m.group(1)), v_t, 1e-4, "the terminal velocity")

lines = python_out("DEM_LIBRARY overrides", "import dem\nprint(dem.library_path())",
                   {"DEM_LIBRARY": libdem})
check(lines[0] == libdem, f"DEM_LIBRARY's library is loaded: {lines[0]}")
finish()
