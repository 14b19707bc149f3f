# SPDX-License-Identifier: BSD-3-Clause
"""find_package(dem) works for a fluid code: this build is installed into WORKDIR/prefix, and
tests/consumer, copied to a temporary folder outside the source tree (so the template needs
nothing of the tree), is configured, built and run against the install on 2 ranks:
- fluid_c (C, dem::dem_shared) and fluid_c_static (C, dem::dem) advance four free spheres,
  with the buoyancy of a fluid of density rho_f set as their force, by ten fluid steps of
  1e-4 s: t = 1e-3 s, all four particles, and their vertical velocity the exact
  -g (1 - rho_f / rho_p) t of a constant acceleration (symplectic Euler integrates it without
  error), to 1e-9; the version they print is the one of src/base/dem_version.f90;
- fluid_f (Fortran, dem::dem) reaches t = 1e-3 s.
Every function dem_coupling.h declares (parsed from the installed header's prototypes: the
bind(C) functions of dem_coupling.f90) links with both dem::dem and dem::dem_shared (a
generated C program takes the address of each), every dem_coupling_* call doc/user/coupling.md names is declared there, the
CMakeLists.txt that page shows is the template's, and libdem.so exports the functions of
dem_coupling.h and nothing else.
usage: test_package.py DEM WORKDIR BUILD_DIR MPIEXEC"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

from regression_util import ROOT, check, check_close, finish

dem, work, build, mpiexec = (os.path.abspath(a) for a in sys.argv[1:5])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
prefix = os.path.join(work, "prefix")
G, RHO_P, RHO_F, T = 9.81, 2500.0, 1000.0, 1e-3     # fluid.c's g and rho_f, its ten steps


def step(what, cmd, cwd=work):
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=600)
    check(r.returncode == 0, f"{what}: exit {r.returncode}: {(r.stdout + r.stderr)[-3000:]}")
    if r.returncode != 0:
        finish()
    return r.stdout


def declared_functions(header):
    """The functions a C header declares: its prototypes, comments left out."""
    with open(header) as f:
        text = re.sub(r"/\*.*?\*/|//[^\n]*", " ", f.read(), flags=re.S)
    return set(re.findall(r"\b(dem_coupling_\w+)\s*\([^;{}]*\)\s*;", text))


step("install", ["cmake", "--install", build, "--prefix", prefix])
for f in ("lib/cmake/dem/demConfig.cmake", "include/dem/dem_coupling.mod",
          "include/dem/dem_coupling.h", "share/doc/dem/README.md", "share/doc/dem/theory.md",
          "share/doc/dem/user/input.md", "share/dem/cases/silo/README.md",
          "share/dem/examples/drum/drum.nml", "share/dem/examples/chute/base.stl"):
    check(os.path.exists(os.path.join(prefix, f)), f"installed {f}")
# relocatable: the exported targets name imported targets (found again by demConfig.cmake
# where the package is used), not absolute paths of this machine's libraries
for f in os.listdir(os.path.join(prefix, "lib", "cmake", "dem")):
    if f.startswith("demTargets"):
        with open(os.path.join(prefix, "lib", "cmake", "dem", f)) as g:
            text = g.read()
        check("/usr/" not in text and ROOT not in text and build not in text,
              f"{f} holds no absolute path of the build machine")

header = os.path.join(prefix, "include", "dem", "dem_coupling.h")
declared = declared_functions(header)
with open(os.path.join(ROOT, "src", "api", "dem_coupling.f90")) as f:
    bound = set(re.findall(r"bind\(C, name='(dem_coupling_\w+)'\)", f.read()))
check(declared == bound, f"the header declares the bind(C) functions of dem_coupling.f90: "
      f"not declared {sorted(bound - declared)}, not bound {sorted(declared - bound)}")
with open(os.path.join(ROOT, "doc", "user", "coupling.md")) as f:
    page = f.read()
documented = set(re.findall(r"\b(dem_coupling_\w+)\(", page))
# the CMakeLists.txt the page shows is the template's (without its heading comments)
block = re.search(r"## Building against it\n.*?```cmake\n(.*?)```", page, re.S)
with open(os.path.join(ROOT, "tests", "consumer", "CMakeLists.txt")) as f:
    template = re.sub(r"\A(#[^\n]*\n)+", "", f.read())
check(block is not None and block.group(1) == template,
      "coupling.md shows tests/consumer/CMakeLists.txt as it is")
check(documented <= declared, f"the calls coupling.md names are declared in dem_coupling.h: "
      f"not declared {sorted(documented - declared)}")
# the shared library: exactly the C interface (the functions the header declares)
library = os.path.join(prefix, "lib", "libdem.so")
check(os.path.exists(library), "installed lib/libdem.so")
symbols = step("the library's symbols", ["nm", "-D", "--defined-only", library])
exported = {line.split()[-1] for line in symbols.splitlines()
            if len(line.split()) == 3 and line.split()[1] in "TDBR"}
check(exported == declared, f"libdem.so exports the header's {len(declared)} functions: "
      f"missing {sorted(declared - exported)}, more {sorted(exported - declared)}")

cache = open(os.path.join(build, "CMakeCache.txt")).read().splitlines()
setting = {k.split(":")[0]: v for k, _, v in (line.partition("=") for line in cache) if ":" in k}


def cmake_project(source, binary):
    """Configure and build the CMake project `source` in `binary` against the install."""
    step(f"configure {os.path.basename(source)}",
         ["cmake", "-S", source, "-B", binary, "-G", "Ninja", f"-Ddem_DIR={prefix}/lib/cmake/dem",
          f"-DCMAKE_C_COMPILER={setting['CMAKE_C_COMPILER']}",
          f"-DCMAKE_Fortran_COMPILER={setting['CMAKE_Fortran_COMPILER']}",
          f"-DCMAKE_BUILD_TYPE={setting['CMAKE_BUILD_TYPE']}"])
    step(f"build {os.path.basename(source)}", ["cmake", "--build", binary])


with tempfile.TemporaryDirectory(prefix="dem_consumer_") as outside:
    check(not os.path.realpath(outside).startswith(os.path.realpath(ROOT) + os.sep),
          f"{outside} is outside the source tree")
    # every declared function links, with each target
    links = os.path.join(outside, "links")
    os.makedirs(links)
    names = sorted(declared)
    with open(os.path.join(links, "links.c"), "w") as f:
        f.write('#include <stdio.h>\n#include "dem_coupling.h"\n'
                "typedef void (*function)(void);\n"
                "static volatile function calls[] = {\n"
                + "".join(f"    (function){name},\n" for name in names)
                + "};\nint main(void)\n{\n    int n = 0;\n"
                "    for (size_t k = 0; k < sizeof calls / sizeof calls[0]; k++) "
                "n += calls[k] != 0;\n"
                '    printf("%d functions\\n", n);\n    return 0;\n}\n')
    with open(os.path.join(links, "CMakeLists.txt"), "w") as f:
        f.write("cmake_minimum_required(VERSION 3.20)\nproject(links LANGUAGES C Fortran)\n"
                "find_package(dem REQUIRED)\n"
                "add_executable(links_shared links.c)\n"
                "target_link_libraries(links_shared PRIVATE dem::dem_shared)\n"
                "add_executable(links_static links.c)\n"
                "target_link_libraries(links_static PRIVATE dem::dem)\n"
                "set_target_properties(links_static PROPERTIES LINKER_LANGUAGE Fortran)\n")
    cmake_project(links, os.path.join(outside, "links-build"))
    for target in ("links_shared", "links_static"):
        out = step(target, [os.path.join(outside, "links-build", target)])
        check(out.strip() == f"{len(names)} functions",
              f"{target}: the {len(names)} functions of dem_coupling.h link: {out}")

    # the template, copied out of the tree
    consumer = os.path.join(outside, "consumer")
    shutil.copytree(os.path.join(ROOT, "tests", "consumer"), consumer)
    cmake_project(consumer, os.path.join(outside, "consumer-build"))
    with open(os.path.join(ROOT, "src", "base", "dem_version.f90")) as f:
        version = re.search(r"dem_version_string = '([^']+)'", f.read()).group(1)
    mpirun = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", "2"]
    for program in ("fluid_c", "fluid_c_static", "fluid_f"):
        case = os.path.join(work, f"{program}.nml")
        with open(case, "w") as f:
            f.write(f"&run dt = 2.5e-5, t_end = 1.0, gravity = 0, 0, -{G} /\n"
                    f"&output dir = '{work}/{program}', interval = 0.5 /\n"
                    f"&material name = 'glass', density = {RHO_P}, youngs_modulus = 1e7, "
                    "poisson_ratio = 0.25 /\n"
                    "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /\n"
                    + "".join(f"&particle id = {k + 1}, material = 'glass', radius = 1e-3, "
                              f"position = {0.01 * k}, 0, 0 /\n" for k in range(4)))
        out = step(f"{program} on 2 ranks",
                   mpirun + [os.path.join(outside, "consumer-build", program), case])
        if program == "fluid_f":
            check("t =  1.00000E-03 s" in out, f"fluid_f: {out}")
            continue
        m = re.search(r"dem (\S+), t = (\S+) s, (\d+) particles, mean vertical velocity (\S+)",
                      out)
        check(m is not None, f"{program} prints its line: {out}")
        if m:
            check(m.group(1) == version, f"{program}: version {m.group(1)}, expected {version}")
            check(m.group(2) == "1.00000e-03", f"{program}: t = {m.group(2)}")
            check(m.group(3) == "4", f"{program}: {m.group(3)} particles, expected 4")
            check_close(float(m.group(4)), -G * (1.0 - RHO_F / RHO_P) * T, 1e-9,
                        f"{program}: the spheres' vertical velocity")
finish()
