# SPDX-License-Identifier: BSD-3-Clause
"""Bonded particles in whole runs (doc/theory.md, section 18): spheres of R = 1 mm in a line
along x, 2R apart, joined by parallel bonds of radius R (E = 1e8 Pa, k_n / k_s = 1) between
neighbours, the contact law off while bonded, dt = 1 us.

1. A cantilever of 21 spheres, sphere 0 fixed, under gravity with a tip sphere ten times as
   dense (an end load) and bond damping: its tip comes to rest where the same chain of
   springs solved as a linear system puts it (lumped masses, shear springs at the bonds'
   centres, bending springs on the relative rotations: brute force, 0.2 %), and where
   Euler-Bernoulli theory puts a beam of bending stiffness E I under the spheres' weights
   (the sum of the point loads' deflections, within 2 %).
2. The same cantilever, undamped, with a tip sphere of half the density (lumped masses of a
   uniform beam), set free straight under gravity: its tip vibrates at the chain's first
   natural frequency (its eigenvalue, 0.5 %) and at Euler-Bernoulli's
   f_1 = 1.8751^2 / (2 pi) sqrt(E I / (mu l^4)) (2 %).
3. A bar of 5 spheres, the first fixed, the last driven at 1 mm/s along the bar: no bond
   breaks while the force is below the tensile strength times the bond's area, sigma_c A
   (the bonds' stored energy at most 4 (sigma_c A)^2 / (2 k_n A)), and the first breaks when
   the bar has stretched by 4 sigma_c L / E (quasi-static; within 1 %).
4. A pair, the first fixed, the second driven across the bond at 1 mm/s without turning:
   the bond breaks in shear when k_s A v t reaches tau_c A, at t = tau_c / (k_s v) (within a
   step), and not before.
5. A compression wave along a free chain of 101 spheres whose first is driven at 1 mm/s: its
   front (where the spheres have half the driver's speed) travels at L sqrt(k_n A / m) (the
   long-wave speed of a chain of masses m and springs k_n A, L apart; within 3 %).
6. An agglomerate (a ball of spheres on a face-centred cubic lattice, each bonded to its
   touching neighbours, Weibull strengths, the contact law on) hitting a rigid plane at
   2 m/s and breaking: the same bits (final.csv, series.csv with its bond columns) on 1, 2, 3
   and 4 ranks, and from a checkpoint written on 2 ranks halfway and continued on 3.
7. A vertical bonded chain falling through an outlet: the bonds of the spheres that leave go
   with them, and the rest of the chain falls freely on (its top sphere where symplectic
   Euler puts a free fall, to 1e-12), the same bits on 1 and 2 ranks.
8. A clump (two spheres) hanging by a bond from a fixed sphere comes to rest with the bond
   stretched by its weight over k_n A (within 1 %).
9. A bonded pair, stretched and spinning, across a periodic boundary (the partner its nearest
   image) holds the energy of the same pair away from the boundary, row by row (1e-6).
usage: test_bonds.py DEM WORKDIR MPIEXEC"""
import math
import os
import shutil
import subprocess
import sys

import numpy as np

from regression_util import check, check_close, finish

dem, work, mpiexec = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

R, RHO, E, G, DT = 1.0e-3, 2500.0, 1.0e8, 9.81, 1.0e-6
L = 2.0 * R
M = RHO * 4.0 / 3.0 * math.pi * R**3
A, I = math.pi * R**2, math.pi * R**4 / 4.0
KN = E / L * A                    # the bond's normal and shear stiffness [N/m]
KB = E / L * I                    # its bending stiffness [N m/rad]


def run(name, text):
    with open(os.path.join(work, name + ".nml"), "w") as f:
        f.write(text.replace("out_NAME", "out_" + name))
    r = subprocess.run([dem, name + ".nml"], cwd=work, capture_output=True, text=True,
                       timeout=600)
    if r.returncode != 0:
        print(r.stdout, r.stderr)
    check(r.returncode == 0, f"{name}: exit {r.returncode}")
    return os.path.join(work, "out_" + name)


def line(n, first_fixed=True, extra=None, tip=""):
    """&particle groups of n spheres along x (sphere 0 fixed), the last of material `tip`
    if given, extra[k] appended to sphere k's group."""
    extra = extra or {}
    rows = []
    for k in range(n):
        mat = tip if (tip and k == n - 1) else "m"
        fixed = ", fixed = .true." if (k == 0 and first_fixed) else ""
        rows.append(f"&particle id = {k + 1}, material = '{mat}', radius = {R}, "
                    f"position = {k * L!r}, 0, 0{fixed}{extra.get(k, '')} /")
    return "\n".join(rows)


def material(name, density):
    """A second material and its pairs."""
    return (f"&material name = '{name}', density = {density}, youngs_modulus = {E}, "
            f"poisson_ratio = 0.3 /\n" + "\n".join(
                f"&pair materials = '{a}', '{name}', restitution = 0.5, friction = 0.0 /"
                for a in ("m", name)))


def case(t_end, interval, particles, bond="", extra_materials="", output=""):
    return f"""&run dt = {DT}, t_end = {t_end}, gravity = 0, 0, -{G} /
&output dir = 'out_NAME', interval = {interval}, snapshot_interval = 0{output} /
&material name = 'm', density = {RHO}, youngs_modulus = {E}, poisson_ratio = 0.3 /
{extra_materials}
&pair materials = 'm', 'm', restitution = 0.5, friction = 0.0 /
{particles}
&bond modulus = {E}, contact = .false.{bond} /
"""


def chain_matrices(n, masses):
    """Stiffness and mass matrices of the in-plane (z, rotation about y) motion of the
    chain of n spheres with sphere 0 clamped: the bond of spheres k and k + 1 has a shear
    spring KN on w_{k+1} - w_k + R (theta_k + theta_{k+1}) (the relative velocity at the
    bond's centre) and a bending spring KB on theta_{k+1} - theta_k."""
    size = 2 * (n - 1)
    K = np.zeros((size, size))

    def idx(k):
        return (None, None) if k == 0 else (2 * (k - 1), 2 * (k - 1) + 1)

    for k in range(n - 1):
        (w1, r1), (w2, r2) = idx(k), idx(k + 1)
        for coef, terms in ((KN, ((w2, 1.0), (w1, -1.0), (r1, R), (r2, R))),
                            (KB, ((r2, 1.0), (r1, -1.0)))):
            for a, ca in terms:
                for b, cb in terms:
                    if a is not None and b is not None:
                        K[a, b] += coef * ca * cb
    Mm = np.diag(sum(([mk, 0.4 * mk * R**2] for mk in masses), []))
    return K, Mm


def tip_track(out):
    return np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)


N = 21
ELL = L * (N - 1)
probe = f"&probe name = 'tip', kind = 'track', id = {N} /"

# 1. the end-loaded cantilever at rest
masses = [M] * (N - 2) + [10.0 * M]
out = run("static", case(0.6, 1.0e-3, line(N, tip="tip") + "\n" + probe, "",
                         material("tip", 10 * RHO)).replace(" /\n&output",
                                                           ", local_damping = 0.7 /\n&output"))
p = tip_track(out)
z_end = p["tip_z"][-1]
check(abs(p["tip_z"][-1] - p["tip_z"][-50]) < 1e-4 * abs(z_end), "static: the tip is at rest: "
      f"z {p['tip_z'][-50]:.9g} then {z_end:.9g}")
K, _ = chain_matrices(N, masses)
f = np.zeros(K.shape[0])
f[0::2] = -np.array(masses) * G
chain_w = np.linalg.solve(K, f)[-2]
check_close(z_end, chain_w, 2e-3, "static: tip deflection against the linear chain")
xs = L * np.arange(1, N)          # point loads m_k g at x_k on a beam clamped at x = 0
eb = -sum(mk * G * xk**2 * (3 * ELL - xk) / (6 * E * I) for mk, xk in zip(masses, xs))
check_close(z_end, eb, 0.02, "static: tip deflection against Euler-Bernoulli")
print(f"static tip deflection {z_end:.6e} m, chain {chain_w:.6e}, Euler-Bernoulli {eb:.6e}")

# 2. the free vibration
masses = [M] * (N - 2) + [0.5 * M]
out = run("vibration", case(0.12, 2.0e-5, line(N, tip="half") + "\n" + probe, "",
                            material("half", RHO / 2)))
p = tip_track(out)
t, z = p["time"], p["tip_z"] - np.mean(p["tip_z"])
up = np.nonzero((z[:-1] < 0) & (z[1:] >= 0))[0]
t_up = t[up] - z[up] * (t[up + 1] - t[up]) / (z[up + 1] - z[up])
freq = (len(t_up) - 1) / (t_up[-1] - t_up[0])
K, Mm = chain_matrices(N, masses)
d = 1.0 / np.sqrt(np.diag(Mm))
f_chain = math.sqrt(np.linalg.eigvalsh(K * d[:, None] * d[None, :])[0]) / (2 * math.pi)
f_eb = 1.8751**2 / (2 * math.pi) * math.sqrt(E * I / (M / L * ELL**4))
check(len(t_up) >= 4, f"vibration: {len(t_up)} periods seen")
check_close(freq, f_chain, 5e-3, "vibration: first frequency against the chain's")
check_close(freq, f_eb, 0.02, "vibration: first frequency against Euler-Bernoulli")
print(f"first frequency {freq:.6f} Hz, chain {f_chain:.6f}, Euler-Bernoulli {f_eb:.6f}")

# 3. tension: the bar pulled apart
SIGMA, V = 1.0e5, 1.0e-3
out = run("tension", case(0.0095, 2.0e-5, line(5, extra={4: f", velocity = {V}, 0, 0, "
                                                          "fixed = .true."}),
                          f", tensile_strength = {SIGMA}").replace("-9.81", "0"))
s = np.genfromtxt(os.path.join(out, "series.csv"), delimiter=",", names=True)
t_b = 4 * SIGMA * L / (E * V)
first = np.nonzero(s["bonds_broken"] > 0)[0][0]
e_cap = 4 * (SIGMA * A)**2 / (2 * KN)
check(s["bonds_broken"][-1] >= 1 and s["bonds"][0] == 4, "tension: 4 bonds, one breaks")
check(np.all(s["bond_energy"][:first] <= e_cap * (1 + 1e-9)), "tension: no break before "
      f"the bonds hold {e_cap:.6e} J (force sigma_c A): most held "
      f"{s['bond_energy'][:first].max():.6e} J")
check(s["bond_energy"][first - 1] > 0.98 * e_cap, "tension: the bonds held "
      f"{s['bond_energy'][first - 1]:.6e} J at the last row before the break, near "
      f"{e_cap:.6e} J")
check_close(s["time"][first], t_b, 0.01, "tension: time of the first break")
print(f"tension: first break by t = {s['time'][first]:.6e} s, quasi-static {t_b:.6e} s")

# 4. shear: the pair sheared apart
TAU = 1.0e5
out = run("shear", case(0.0025, 1.0e-6, line(2, extra={1: f", velocity = 0, 0, {V}, "
                                                        "fixed = .true."}),
                        f", shear_strength = {TAU}").replace("-9.81", "0"))
s = np.genfromtxt(os.path.join(out, "series.csv"), delimiter=",", names=True)
first = np.nonzero(s["bonds_broken"] > 0)[0][0]
t_s = TAU / (E / L * V)
check(abs(s["time"][first] - t_s) <= 1.5 * DT, f"shear: broke at t = {s['time'][first]:.9e} "
      f"s, expected {t_s:.9e} s (within a step)")

# 5. the compression wave
NW, VW = 101, 1.0e-3
out = run("wave", case(8.0e-4, 1.0e-6, line(NW, first_fixed=False,
                                            extra={0: f", velocity = {VW}, 0, 0, "
                                                      "fixed = .true."}) + "\n"
                       + "\n".join(f"&probe name = 's{k}', kind = 'track', id = {k + 1} /"
                                   for k in (20, 80)), "").replace("-9.81", "0"))
p = np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)
arrive = [p["time"][np.argmax(p[f"s{k}_vx"] > 0.5 * VW)] for k in (20, 80)]
c_wave = 60 * L / (arrive[1] - arrive[0])
check_close(c_wave, L * math.sqrt(KN / M), 0.03, "wave: speed of the front")
print(f"wave speed {c_wave:.6f} m/s, L sqrt(k/m) = {L * math.sqrt(KN / M):.6f} m/s")

# 6. the agglomerate on 1-4 ranks, and restarted
a = math.sqrt(2.0) * R                      # FCC: nearest neighbours 2R apart
RB = 6.0 * R
pts = [(i * a, j * a, k * a) for i in range(-6, 7) for j in range(-6, 7) for k in range(-6, 7)
       if (i + j + k) % 2 == 0 and math.sqrt(i * i + j * j + k * k) * a <= RB]
z0 = RB + 1.5 * R
agg = "\n".join(f"&particle id = {n + 1}, material = 'm', radius = {R}, position = {x!r}, "
                 f"{y!r}, {z + z0!r}, velocity = 0, 0, -2.0 /" for n, (x, y, z) in enumerate(pts))
T_AGG = 2.0e-3


def agglomerate(name, t_end):
    text = case(t_end, 1.0e-4, agg, ", tensile_strength = 2.0e5, shear_strength = 2.0e5, "
                "strength_distribution = 'weibull', strength_spread = 5, seed = 7",
                "&material name = 'rigid', rigid = .true. /\n&pair materials = 'm', 'rigid', "
                "restitution = 0.5, friction = 0.3 /\n&wall_plane material = 'rigid', "
                "point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05 /",
                f", checkpoint_interval = {T_AGG / 2!r}")
    text = text.replace("contact = .false.", "contact = .true., damping = 0.1")
    with open(os.path.join(work, name + ".nml"), "w") as f:
        f.write(text.replace("out_NAME", "out_" + name))
    return name + ".nml"


def on(ranks, *args):
    r = subprocess.run([mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks),
                        dem, *args], cwd=work, capture_output=True, text=True, timeout=900)
    if r.returncode != 0:
        print(r.stdout, r.stderr)
    check(r.returncode == 0, f"{' '.join(args)} on {ranks} ranks: exit {r.returncode}")


def same(a, b, what):
    with open(os.path.join(work, a), "rb") as fa, open(os.path.join(work, b), "rb") as fb:
        check(fa.read() == fb.read(), f"{what}: {b} is {a}")


for ranks in (1, 2, 3, 4):
    on(ranks, agglomerate(f"agg{ranks}", T_AGG))
s = np.genfromtxt(os.path.join(work, "out_agg1", "series.csv"), delimiter=",", names=True)
check(s["bonds"][0] > 4 * len(pts) and 0 < s["bonds_broken"][-1] < s["bonds"][0],
      f"agglomerate: {len(pts)} spheres, {s['bonds'][0]:.0f} bonds, "
      f"{s['bonds_broken'][-1]:.0f} broken")
print(f"agglomerate: {len(pts)} spheres, {s['bonds'][0]:.0f} bonds, "
      f"{s['bonds_broken'][-1]:.0f} broken")
for ranks in (2, 3, 4):
    for out in ("final.csv", "series.csv"):
        same(f"out_agg1/{out}", f"out_agg{ranks}/{out}", f"{ranks} ranks")
on(2, agglomerate("aggr", T_AGG / 2))
agglomerate("aggr", T_AGG)
half = int(round(T_AGG / 2 / DT))
on(3, "--restart", os.path.join("out_aggr", "checkpoints", f"checkpoint_{half:012d}.h5"),
   "aggr.nml")
for out in ("final.csv", "series.csv"):
    same(f"out_agg1/{out}", f"out_aggr/{out}", "restarted on 3 ranks from 2")

# 7. the chain through an outlet
NC, Z0, T_FALL = 10, 0.005, 0.04
chain = "\n".join(f"&particle id = {k + 1}, material = 'm', radius = {R}, position = 0, 0, "
                   f"{Z0 + k * L!r} /" for k in range(NC))
for ranks in (1, 2):
    with open(os.path.join(work, f"fall{ranks}.nml"), "w") as f:
        f.write(case(T_FALL, 1.0e-3, chain + f"\n&probe name = 'top', kind = 'track', "
                     f"id = {NC} /\n&outlet region = 'plane', point = 0, 0, 0, "
                     "normal = 0, 0, -1 /").replace("out_NAME", f"out_fall{ranks}"))
    on(ranks, f"fall{ranks}.nml")
s = np.genfromtxt(os.path.join(work, "out_fall1", "series.csv"), delimiter=",", names=True)
p = np.genfromtxt(os.path.join(work, "out_fall1", "probes.csv"), delimiter=",", names=True)
n_steps = int(round(T_FALL / DT))
z_top = Z0 + (NC - 1) * L - G * DT**2 * n_steps * (n_steps + 1) / 2     # symplectic Euler
check(s["particles"][-1] < NC and s["bonds"][-1] == s["particles"][-1] - 1,
      f"fall: {s['particles'][-1]:.0f} spheres left, {s['bonds'][-1]:.0f} bonds")
check(abs(p["top_z"][-1] - z_top) <= 1e-12 * abs(z_top) + 1e-15, f"fall: the top sphere at "
      f"{p['top_z'][-1]!r}, free fall {z_top!r}")
for out in ("final.csv", "series.csv"):
    same(f"out_fall1/{out}", f"out_fall2/{out}", "fall on 2 ranks")

# 8. the hanging clump
out = run("hang", case(0.05, 1.0e-3, line(1) + f"""
&clump_template name = 'd', material = 'm', members = 0, 0, 0, {R},  0, 0, {-L}, {R} /
&clump template = 'd', position = 0, 0, {-L} /
&probe name = 'c', kind = 'track', id = 2 /""", ", damping = 1.0"))
p = tip_track(out)
stretch = -(p["c_z"][-1] + L)               # the bonded member, L below sphere 0 unstretched
check_close(stretch, 2 * M * G / KN, 0.01, "hang: the bond's stretch under the clump")

# 9. the pair across a periodic boundary
energies = []
for name, x0, periodic in (("flat", 0.0045, ""),
                           ("periodic", 0.0095, "&periodic axis = 'x', low = 0.0, high = 0.0105 /")):
    pair = (f"&particle id = 1, material = 'm', radius = {R}, position = {x0!r}, 0, 0, "
            "velocity = 0.01, 0.002, 0, angular_velocity = 0, 0, 5 /\n"
            f"&particle id = 2, material = 'm', radius = {R}, position = {x0 + L!r}, 0, 0, "
            f"velocity = 0.01, -0.002, 0 /\n{periodic}")
    out = run(name, case(0.02, 1.0e-3, pair, ", gap = 1.0e-4").replace("-9.81", "0"))
    energies.append(np.genfromtxt(os.path.join(out, "series.csv"), delimiter=",",
                                  names=True)["bond_energy"])
check(energies[0][1:].min() > 0 and np.allclose(energies[1], energies[0], rtol=1e-6, atol=0),
      f"periodic: the bond's energy {energies[1][-3:]} against {energies[0][-3:]}")
finish()
