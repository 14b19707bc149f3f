# SPDX-License-Identifier: BSD-3-Clause
"""Coarse-grained fields (&coarse_grain; doc/theory.md, section 19):

1. A column of ten spheres (radius r = 1 mm) at rest on a floor, the fields averaged over x
   and y on a box of area A = 4 r^2 and resolved along z (Gaussian w = r; Lucy c = 3 r): in
   the bulk (one cut-off from the floor and the top) the vertical stress is the weight of
   the material above per unit area, sigma_zz(z) = -(m g / (A d)) (H - z) (d the spacing of
   the centres, H the top of the column, both from final.csv), to 1 % of m g / A; the
   kinetic stress is nil (below 1e-6 m g / A).
2. There the momentum balance of a bed at rest holds: d sigma_zz / dz - rho g = 0 (central
   differences over the nodes), to 1 % of rho g.
3. The files' fields are the same bit for bit on 1, 2 and 3 ranks.
4. A single sphere's density integrates to its mass, sum rho dV = m: a 3D Lucy kernel
   (spacing c / 10) and a Gaussian along z (spacing w / 50), to 1e-3.
usage: test_coarse_grain.py DEM WORKDIR MPIEXEC"""
import math
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

from regression_util import check, finish, run_dem

dem, work, mpiexec = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

G = 9.81
R = 1e-3
N = 10
M = 2500.0 * 4.0 / 3.0 * math.pi * R**3
A = (2 * R)**2
HEAD = """&material name = 'glass', density = 2500.0, youngs_modulus = 5.0e7, poisson_ratio = 0.25 /
&material name = 'rigid', rigid = .true. /
&pair materials = 'glass', 'glass', restitution = 0.3, friction = 0.3 /
&pair materials = 'glass', 'rigid', restitution = 0.3, friction = 0.3 /
"""
column = ("""&run dt = 5e-6, t_end = 0.2, gravity = 0, 0, -9.81, integrator = 'velocity_verlet' /
&output interval = 0.05 /
""" + HEAD + "".join(f"&particle id = {k + 1}, material = 'glass', radius = {R}, "
                     f"position = 0, 0, {R + 2 * R * k:.17g} /\n" for k in range(N)) + """
&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.01 /
&coarse_grain name = 'gauss', box_min = -1e-3, -1e-3, 0, box_max = 1e-3, 1e-3, 0.02,
  cells = 1, 1, 80, width = 1e-3, t_start = 0.15, every = 100 /
&coarse_grain name = 'lucy', kernel = 'lucy', box_min = -1e-3, -1e-3, 0,
  box_max = 1e-3, 1e-3, 0.02, cells = 1, 1, 80, width = 3e-3, t_start = 0.15, every = 100 /
&coarse_grain name = 'grid', box_min = -4e-3, -4e-3, 0, box_max = 4e-3, 4e-3, 0.024,
  cells = 4, 4, 12, width = 1.5e-3, t_start = 0.15, every = 500 /
""")


def write_case(name, text):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    return path


def fields(case, name):
    with h5py.File(os.path.join(work, "output", case, f"fields_{name}.h5"), "r") as f:
        return {k: f[k][()] for k in ["samples", "grid/x", "grid/y", "grid/z",
                                      "fields/density", "fields/velocity",
                                      "fields/kinetic_stress", "fields/contact_stress",
                                      "fields/stress"]}


# 1, 2: the column at rest
run_dem(dem, write_case("column", column), work)
final = np.genfromtxt(os.path.join(work, "output", "column", "final.csv"), delimiter=",",
                      names=True)
zc = np.sort(final["z"])
d = (zc[-1] - zc[0]) / (N - 1)
H = zc[-1] + R
unit = M * G / A
for name, cut in [("gauss", 3e-3), ("lucy", 3e-3)]:
    f = fields("column", name)
    z = f["grid/z"]
    szz = f["fields/stress"][:, 0, 0, 8]
    rho = f["fields/density"][:, 0, 0]
    bulk = (z > cut + 2 * R) & (z < H - cut - R)
    check(f["samples"] == 101, f"{name}: 101 samples ({f['samples']})")
    expected = -(M * G / (A * d)) * (H - z)
    err = np.max(np.abs(szz - expected)[bulk]) / unit
    print(f"{name}: sigma_zz against the weight above: largest difference {err:.2e} m g / A")
    check(err < 1e-2, f"{name}: sigma_zz is the weight above per unit area ({err:.2e})")
    kin = np.max(np.abs(f["fields/kinetic_stress"])) / unit
    check(kin < 1e-6, f"{name}: no kinetic stress at rest ({kin:.2e})")
    dz = z[1] - z[0]
    div = (szz[2:] - szz[:-2]) / (2 * dz)
    res = np.abs(div - rho[1:-1] * G)[bulk[1:-1]] / (rho[1:-1][bulk[1:-1]] * G)
    print(f"{name}: momentum balance: largest residual {res.max():.2e} rho g")
    check(res.max() < 1e-2, f"{name}: d sigma_zz / dz = rho g ({res.max():.2e})")

# 3: the same bits on 2 and 3 ranks
for ranks in (2, 3):
    case = f"column{ranks}"
    write_case(case, column)
    r = subprocess.run([mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks),
                        dem, os.path.join(work, case + ".nml")], cwd=work, capture_output=True,
                       text=True, timeout=600)
    check(r.returncode == 0, f"column on {ranks} ranks: exit {r.returncode}: {r.stderr[-2000:]}")
    for name in ("gauss", "lucy", "grid"):
        one, many = fields("column", name), fields(case, name)
        same = all(one[k].tobytes() == many[k].tobytes() for k in one)
        check(same, f"{name}: the same bits on 1 and {ranks} ranks")

# 4: one sphere's mass
sphere = """&run dt = 1e-5, t_end = 1e-4, gravity = 0, 0, 0 /
""" + HEAD + """&particle id = 1, material = 'glass', radius = 1e-3, position = 1.3e-4, -2.1e-4, 3.7e-4,
  velocity = 0.01, 0, 0 /
&coarse_grain name = 'lucy', kernel = 'lucy', box_min = -4e-3, -4e-3, -4e-3,
  box_max = 4e-3, 4e-3, 4e-3, cells = 27, 27, 27, width = 3e-3 /
&coarse_grain name = 'gauss', box_min = -1e-2, -1e-2, -4e-3, box_max = 1e-2, 1e-2, 4e-3,
  cells = 1, 1, 200, width = 1e-3 /
"""
run_dem(dem, write_case("sphere", sphere), work)
for name in ("lucy", "gauss"):
    f = fields("sphere", name)
    cell = np.prod([(f[k][-1] - f[k][0]) / (len(f[k]) - 1) if len(f[k]) > 1 else 0.02
                    for k in ("grid/x", "grid/y", "grid/z")])
    mass = f["fields/density"].sum() * cell
    print(f"{name}: sum rho dV = {mass / M:.8f} m")
    check(abs(mass / M - 1) < 1e-3, f"{name}: the density integrates to the mass ({mass / M})")
finish()
