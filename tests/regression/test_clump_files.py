# SPDX-License-Identifier: BSD-3-Clause
"""Clumps from files (&clump_template file, &clump_file; doc/user/input.md).

1. A template's members from a file (header, commas and blanks) are the members given
   inline: `dem --check` prints the same mass properties, and a pour of clumps of the
   template ends with the same final.csv and series.csv, byte for byte.
2. A template of 100 separate spheres (more than a group's 64), from a file: `dem --check`
   prints the mass and principal moments of the spheres' sum (the parallel-axis theorem,
   computed here; the spheres do not overlap), to its 6 printed digits.
3. Clumps placed by two &clump_file groups (one headerless, blank separated, 8 columns; one
   with a header and velocities, 14 columns) beside &clump groups: the same final.csv and
   series.csv as the same clumps all given as &clump groups (those of the groups first,
   then the files' in order), on 1 and 2 ranks.
usage: test_clump_files.py DEM WORKDIR MPIEXEC"""
import math
import os
import random
import re
import shutil
import subprocess
import sys

import numpy as np

from regression_util import check, check_close, finish, run_ranks, same_file

dem, work, mpiexec = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

RHO = 2500.0
HEAD = """&run dt = 2e-6, t_end = 0.03, gravity = 0, 0, -9.81 /
&output dir = '{name}', interval = 0.005 /
&material name = 'glass', density = 2500, youngs_modulus = 5e6, poisson_ratio = 0.25 /
&material name = 'steel', rigid = .true. /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&pair materials = 'glass', 'steel', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'steel', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.1 /
"""
# an asymmetric template: three overlapping spheres of different radii, off its origin
TRI = [(0.0002, -0.0001, 0.0003, 0.001), (0.0013, 0.0001, 0.0002, 0.0008),
       (0.0001, 0.0011, -0.0002, 0.0007)]


def write(name, text):
    path = os.path.join(work, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def dem_check(case):
    r = subprocess.run([dem, "--check", case], cwd=work, capture_output=True, text=True,
                       timeout=300)
    check(r.returncode == 0, f"dem --check {case}: {r.stderr.strip()}")
    return r.stdout


def template_line(out, name):
    m = re.search(rf"^\s*{name}: .*$", out, re.M)
    check(m is not None, f"dem --check prints template {name}: {out}")
    return m.group(0) if m else ""


def quaternion(rng):
    a = rng.uniform(0, math.pi)
    u = [rng.gauss(0, 1) for _ in range(3)]
    n = math.sqrt(sum(c * c for c in u))
    return [math.cos(a / 2)] + [math.sin(a / 2) * c / n for c in u]


rng = random.Random(5)
clumps = []          # (x, y, z, q, v, w), repr-exact numbers
for i in range(5):
    for j in range(5):
        for k in range(2):
            clumps.append(([-0.01 + 0.005 * i, -0.01 + 0.005 * j, 0.004 + 0.005 * k],
                           quaternion(rng), [rng.uniform(-0.3, 0.3), 0.0, -0.4 * k],
                           [0.0, rng.uniform(-20, 20), 0.0]))


def group(c):
    x, q, v, w = c
    return ("&clump template = 'tri', position = {}, orientation = {}, velocity = {}, "
            "angular_velocity = {} /\n").format(*(", ".join(repr(a) for a in b)
                                                  for b in (x, q, v, w)))


# 1. the template inline and from a file
inline = ("&clump_template name = 'tri', material = 'glass', members = "
          + ",  ".join(", ".join(repr(a) for a in m) for m in TRI) + " /\n")
write("tri.csv", "x,y,z,radius\n" + "".join(
    f"{m[0]!r}, {m[1]!r}  {m[2]!r},{m[3]!r}\n" if n % 2 else
    f"\n{m[0]!r} {m[1]!r} {m[2]!r} {m[3]!r}\n" for n, m in enumerate(TRI)))
from_file = "&clump_template name = 'tri', material = 'glass', file = 'tri.csv' /\n"
groups = "".join(group(c) for c in clumps)
for name, tpl in (("inline", inline), ("file", from_file)):
    case = write(name + ".nml", HEAD.format(name=name) + tpl + groups)
    out = dem_check(case)
    if name == "inline":
        line = template_line(out, "tri")
    else:
        check(template_line(out, "tri") == line,
              f"the template from a file prints as inline: {template_line(out, 'tri')} "
              f"against {line}")
    run_ranks(mpiexec, dem, case, 1, work)
for f in ("final.csv", "series.csv"):
    same_file(os.path.join(work, "inline", f), os.path.join(work, "file", f),
              "the template from a file")

# 2. 100 separate spheres from a file, against the parallel-axis theorem
spheres = []
for n in range(100):
    t = 0.4 * n
    spheres.append((0.01 * math.cos(t), 0.006 * math.sin(t), 0.0025 * n,
                    0.0005 + 0.0004 * ((n * 7) % 10) / 10))
write("many.csv", "".join(f"{x!r},{y!r},{z!r},{r!r}\n" for x, y, z, r in spheres))
for a in range(100):                       # (the spheres are apart)
    for b in range(a):
        d = math.dist(spheres[a][:3], spheres[b][:3])
        assert d > spheres[a][3] + spheres[b][3], (a, b)
mass = np.array([RHO * 4 / 3 * math.pi * r**3 for *_, r in spheres])
pos = np.array([s[:3] for s in spheres])
com = (mass[:, None] * pos).sum(0) / mass.sum()
inertia = np.zeros((3, 3))
for m, p, (*_, r) in zip(mass, pos - com, spheres):
    inertia += 0.4 * m * r**2 * np.eye(3) + m * (p @ p * np.eye(3) - np.outer(p, p))
moments = np.sort(np.linalg.eigvalsh(inertia))
case = write("many.nml", HEAD.format(name="many") +
             "&clump_template name = 'many', material = 'glass', file = 'many.csv' /\n"
             "&clump template = 'many', position = 0, 0, 0.1 /\n")
line = template_line(dem_check(case), "many")
got = re.search(r"1 clumps of (\d+) spheres, mass\s+(\S+) kg, principal moments\s+(\S+)\s+(\S+)"
                r"\s+(\S+) kg", line)
check(got is not None, f"the 100-sphere template: {line}")
if got:
    check(int(got.group(1)) == 100, f"the 100-sphere template has 100 members: {line}")
    check_close(float(got.group(2)), mass.sum(), 1e-5, "the 100-sphere template's mass")
    for k in range(3):
        check_close(float(got.group(3 + k)), moments[k], 1e-5,
                    f"the 100-sphere template's principal moment {k + 1}")

# 3. clumps from &clump_file groups beside &clump groups, against &clump groups only
first, plain, moving = clumps[:10], clumps[10:30], clumps[30:]
write("plain.txt", "".join("tri  {}  {}\n".format(" ".join(repr(a) for a in x),
                                                  " ".join(repr(a) for a in q))
                           for x, q, v, w in plain))
for x, q, v, w in plain:                 # (the headerless file has no velocities)
    v[:] = [0.0, 0.0, 0.0]
    w[:] = [0.0, 0.0, 0.0]
write("moving.csv", "template,x,y,z,q0,q1,q2,q3,vx,vy,vz,wx,wy,wz\n" +
      "".join("tri," + ",".join(repr(a) for a in x + q + v + w) + "\n"
              for x, q, v, w in moving))
reference = write("groups.nml", HEAD.format(name="groups") + inline +
                  "".join(group(c) for c in first + plain + moving))
files = (HEAD + inline + "&clump_file file = 'plain.txt' /\n"
         + "&clump_file file = 'moving.csv' /\n" + "".join(group(c) for c in first))
run_ranks(mpiexec, dem, reference, 1, work)
for ranks in (1, 2):
    name = f"files_{ranks}"
    run_ranks(mpiexec, dem, write(name + ".nml", files.format(name=name)), ranks, work)
    for f in ("final.csv", "series.csv"):
        same_file(os.path.join(work, "groups", f), os.path.join(work, name, f),
                  f"the clumps from &clump_file on {ranks} ranks")
series = np.genfromtxt(os.path.join(work, "groups", "series.csv"), delimiter=",", names=True)
check(series["particles"][-1] == 3 * len(clumps) and max(series["contacts_pp"]) > 0,
      f"the runs hold the {len(clumps)} clumps, which meet: {series['contacts_pp']}")
finish()
