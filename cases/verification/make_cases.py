#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the namelists of the Chung & Ooi (2011) verification tests 1-4 with the
parameters of Table 3 of the benchmark paper (Dosta et al. 2024), and of their tests 5-8
with the parameters of Chung & Ooi's paper. Run it again after editing; the .nml files it
writes are the cases.

  test1_sphere_sphere.nml   elastic normal impact of two identical glass spheres, +-10 m/s
  test2_sphere_wall.nml     elastic normal impact of an Al alloy sphere on a rigid plane
  test3_restitution.nml     normal impacts on a rigid plane, restitution 0.1 ... 1.0
  test4_oblique.nml         oblique impacts on a rigid plane, incident angle 5 ... 85 deg
  test5_tangential.nml      steel spheres on a rigid plane, normal 5 m/s, tangential 0.1 ... 21
  test6_spin_wall.nml       spinning Al alloy spheres on a rigid plane, normal 0.2 m/s
  test7_spin_pair.nml       pairs of spinning identical Al alloy spheres, +-0.2 m/s
  test8_spin_large.nml      a spinning Al alloy sphere onto a five times larger one at rest

Tests 6-8 spin each sphere about -y, so that its contact point slides along +x at R w0;
in test 7 both spheres of a pair spin so, and their surfaces slide past each other at
2 R w0.
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def material(name, rho=None, e=None, nu=None, rigid=False):
    if rigid:
        return f"&material name = '{name}', rigid = .true. /\n"
    return (f"&material name = '{name}', density = {rho}, youngs_modulus = {e}, "
            f"poisson_ratio = {nu} /\n")


def pair(a, b, e, mu):
    return f"&pair materials = '{a}', '{b}', restitution = {e}, friction = {mu} /\n"


def particle(pid, mat, r, pos, vel, spin=None):
    p = ", ".join(f"{c:.17g}" for c in pos)
    v = ", ".join(f"{c:.17g}" for c in vel)
    w = "" if spin is None else ", angular_velocity = " + ", ".join(f"{c:.17g}" for c in spin)
    return (f"&particle id = {pid}, material = '{mat}', radius = {r}, position = {p}, "
            f"velocity = {v}{w} /\n")


def wall(mat, point, half_width, divisions):
    p = ", ".join(f"{c:.17g}" for c in point)
    return (f"&wall_plane material = '{mat}', point = {p}, normal = 0, 0, 1, "
            f"half_width = {half_width}, divisions = {divisions} /\n")


def write(name, text):
    with open(os.path.join(HERE, name), "w") as f:
        f.write(text)


def run(dt, t_end, interval, trace=0):
    s = (f"&run dt = {dt}, t_end = {t_end}, gravity = 0, 0, 0 /\n"
         f"&output interval = {interval}")
    if trace:
        s += f", trace_id = {trace}"
    return s + " /\n"


# Test 1: glass, E = 48 GPa, nu = 0.2, rho = 2800, R = 10 mm, +-10 m/s, mu = 0.35, e = 1.
R1, gap1 = 0.01, 5.0e-5
write("test1_sphere_sphere.nml",
      "! Chung & Ooi test 1: elastic normal impact of two identical spheres (Table 3).\n"
      + run(1.0e-8, 6.0e-5, 1.0e-6, trace=1)
      + material("glass", 2800.0, 48.0e9, 0.2)
      + pair("glass", "glass", 1.0, 0.35)
      + particle(1, "glass", R1, (-(R1 + gap1), 0, 0), (10.0, 0, 0))
      + particle(2, "glass", R1, (R1 + gap1, 0, 0), (-10.0, 0, 0)))

# Test 2: Al alloy, E = 70 GPa, nu = 0.3, rho = 2699, R = 0.1 m, 0.2 m/s onto a rigid
# plane, mu = 0, e = 1. The plane is 4 x 4 squares of two triangles; the sphere lands on a
# vertex shared by six of them.
R2, gap2 = 0.1, 1.0e-5
write("test2_sphere_wall.nml",
      "! Chung & Ooi test 2: elastic normal impact of a sphere on a rigid plane (Table 3).\n"
      + run(1.0e-7, 1.0e-3, 1.0e-5, trace=1)
      + material("al_alloy", 2699.0, 70.0e9, 0.3)
      + material("rigid", rigid=True)
      + pair("al_alloy", "al_alloy", 1.0, 0.0)
      + pair("al_alloy", "rigid", 1.0, 0.0)
      + particle(1, "al_alloy", R2, (0, 0, R2 + gap2), (0, 0, -0.2))
      + wall("rigid", (0, 0, 0), 0.5, 4))

# Test 3: Al oxide, E = 380 GPa, nu = 0.23, rho = 4000, R = 2.5 mm, 3.9 m/s, mu = 0.
# One sphere per restitution coefficient, each above its own rigid patch, 10 mm apart.
R3, gap3 = 2.5e-3, 2.0e-6
restitutions = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
text = ("! Chung & Ooi test 3: normal impacts with restitution 0.1 ... 1.0 (Table 3).\n"
        "! Sphere k falls on patch k, whose material pair with the sphere has e_k.\n"
        + run(1.0e-8, 2.0e-5, 1.0e-6)
        + material("al_oxide", 4000.0, 380.0e9, 0.23)
        + pair("al_oxide", "al_oxide", 1.0, 0.0))
for k, e in enumerate(restitutions, start=1):
    text += material(f"rigid_e{e:.1f}", rigid=True) + pair("al_oxide", f"rigid_e{e:.1f}", e, 0.0)
for k, e in enumerate(restitutions, start=1):
    x = 0.01 * (k - 1)
    text += particle(k, "al_oxide", R3, (x, 0, R3 + gap3), (0, 0, -3.9))
    text += wall(f"rigid_e{e:.1f}", (x, 0, 0), 0.004, 1)
write("test3_restitution.nml", text)

# Test 4: Al alloy, E = 70 GPa, nu = 0.33, rho = 2700, R = 2.5 mm, |V| = 3.9 m/s at
# incident angles 5 ... 85 deg (from the normal) in 1 deg steps, e = 0.98, mu = 0.092.
# The spheres move along +x and sit 10 mm apart along y.
R4, gap4, V = 2.5e-3, 2.0e-6, 3.9
angles = list(range(5, 86))
text = ("! Chung & Ooi test 4: oblique impacts on a rigid plane, 5 ... 85 deg (Table 3).\n"
        "! Sphere k has incident angle 4 + k degrees from the normal.\n"
        + run(1.0e-8, 5.0e-5, 1.0e-6)
        + material("al_alloy", 2700.0, 70.0e9, 0.33)
        + material("rigid", rigid=True)
        + pair("al_alloy", "al_alloy", 0.98, 0.092)
        + pair("al_alloy", "rigid", 0.98, 0.092))
for k, theta in enumerate(angles, start=1):
    t = math.radians(theta)
    y = 0.01 * (k - 1) - 0.4
    text += particle(k, "al_alloy", R4, (0, y, R4 + gap4), (V * math.sin(t), 0, -V * math.cos(t)))
text += wall("rigid", (0, 0, 0), 0.5, 8)
write("test4_oblique.nml", text)

# Test 5: steel, E = 208 GPa, nu = 0.3, rho = 7850, R = 10 um, normal 5 m/s onto a rigid plane,
# tangential 0.1 ... 21 m/s, no spin, e = 1, mu = 0.3. The spheres sit 0.1 mm apart along y.
R5, gap5 = 1.0e-5, 1.0e-8
TANGENTIAL5 = [0.1, 0.3, 0.45, 0.6, 0.9, 1.2, 1.5, 1.8, 2.25, 2.7, 3.0, 3.75, 4.5, 5.25, 6.0,
               7.5, 9.0, 12.0, 15.0, 18.0, 21.0]
text = ("! Chung & Ooi test 5: normal 5 m/s, tangential 0.1 ... 21 m/s onto a rigid plane.\n"
        "! Sphere k has the k-th tangential velocity (along +x).\n"
        + run(1.0e-10, 1.0e-7, 1.0e-8)
        + material("steel", 7850.0, 2.08e11, 0.3)
        + material("rigid", rigid=True)
        + pair("steel", "steel", 1.0, 0.3)
        + pair("steel", "rigid", 1.0, 0.3))
for k, vt in enumerate(TANGENTIAL5, start=1):
    text += particle(k, "steel", R5, (0, 1.0e-4 * (k - 1), R5 + gap5), (vt, 0, -5.0))
text += wall("rigid", (0, 0, 0), 0.01, 1)
write("test5_tangential.nml", text)

# Tests 6-8: Al alloy, E = 70 GPa, nu = 0.33, rho = 2700, R = 0.1 m, normal 0.2 m/s,
# initial spin w0 = 0.175 ... 21 rad/s, e = 0.5, mu = 0.4.
R6, gap6, V6 = 0.1, 1.0e-5, 0.2
SPINS = [0.175, 0.3, 0.42, 0.6, 0.8, 1.0, 1.2, 1.5, 2.0, 2.4, 2.8, 3.0, 3.5, 4.0, 6.0, 8.0,
         10.0, 12.0, 14.0, 21.0]
AL = material("al_alloy", 2700.0, 70.0e9, 0.33)

# Test 6: one sphere per spin above a rigid plane, 0.3 m apart along y.
text = ("! Chung & Ooi test 6: spheres spinning at w0 = 0.175 ... 21 rad/s onto a rigid plane.\n"
        "! Sphere k has the k-th spin, about -y.\n"
        + run(1.0e-7, 1.2e-3, 1.0e-4) + AL + material("rigid", rigid=True)
        + pair("al_alloy", "al_alloy", 0.5, 0.4) + pair("al_alloy", "rigid", 0.5, 0.4))
for k, w0 in enumerate(SPINS, start=1):
    text += particle(k, "al_alloy", R6, (0, 0.3 * (k - 1), R6 + gap6), (0, 0, -V6), (0, -w0, 0))
text += wall("rigid", (0, 3.0, 0), 4.0, 1)
write("test6_spin_wall.nml", text)

# Test 7: pairs of identical spheres at +-0.2 m/s along z, both spinning about -y; pair k
# (ids 2k - 1 above, 2k below) has the k-th spin, pairs 0.3 m apart along y.
text = ("! Chung & Ooi test 7: pairs of identical spheres spinning at w0 = 0.175 ... 21 rad/s.\n"
        "! Pair k: spheres 2k - 1 (above) and 2k (below), both spinning about -y.\n"
        + run(1.0e-7, 1.2e-3, 1.0e-4) + AL + pair("al_alloy", "al_alloy", 0.5, 0.4))
for k, w0 in enumerate(SPINS, start=1):
    y = 0.3 * (k - 1)
    text += particle(2 * k - 1, "al_alloy", R6, (0, y, R6 + gap6), (0, 0, -V6), (0, -w0, 0))
    text += particle(2 * k, "al_alloy", R6, (0, y, -R6 - gap6), (0, 0, V6), (0, -w0, 0))
write("test7_spin_pair.nml", text)

# Test 8: a spinning sphere (R = 0.1 m) at 0.2 m/s onto a sphere five times larger, of the
# same elastic properties and 1000 times the density, at rest (Chung & Ooi's case B); pair
# k (ids 2k - 1 small, 2k large) has the k-th spin, pairs 1.2 m apart along y.
R8 = 0.5
text = ("! Chung & Ooi test 8: a sphere spinning at w0 = 0.175 ... 21 rad/s onto a larger one.\n"
        "! Pair k: sphere 2k - 1 (R = 0.1 m, spinning about -y) onto 2k (R = 0.5 m, at rest).\n"
        + run(1.0e-7, 1.2e-3, 1.0e-4) + AL
        + material("al_alloy_heavy", 2700.0e3, 70.0e9, 0.33)
        + pair("al_alloy", "al_alloy", 0.5, 0.4)
        + pair("al_alloy", "al_alloy_heavy", 0.5, 0.4)
        + pair("al_alloy_heavy", "al_alloy_heavy", 0.5, 0.4))
for k, w0 in enumerate(SPINS, start=1):
    y = 1.2 * (k - 1)
    text += particle(2 * k - 1, "al_alloy", R6, (0, y, R6 + gap6), (0, 0, -V6), (0, -w0, 0))
    text += particle(2 * k, "al_alloy_heavy", R8, (0, y, -R8), (0, 0, 0))
write("test8_spin_large.nml", text)
