# SPDX-License-Identifier: BSD-3-Clause
"""Analytical expectations for the Chung & Ooi (2011) tests 1-4 and the quantities measured
from the solver's outputs. Used by the test suite, the figure script and the dt sweep.
Nothing here comes from the solver: the formulas are Hertz theory (Johnson, Contact
Mechanics, 1985, section 11.1) and the rigid-body impulse limits of Chung & Ooi: while a
contact slides throughout an impact, the tangential impulse is mu times the normal impulse
m* (1 + e) v_n (doc/theory.md, section 7)."""
import csv
import math

import numpy as np

# Table 3 of the benchmark paper (Dosta et al. 2024)
TEST1 = dict(E=48e9, nu=0.2, rho=2800.0, R=0.01, v=10.0, mu=0.35)
TEST2 = dict(E=70e9, nu=0.3, rho=2699.0, R=0.1, v=0.2, mu=0.0)
TEST3 = dict(E=380e9, nu=0.23, rho=4000.0, R=2.5e-3, v=3.9, mu=0.0,
             restitutions=[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0])
TEST4 = dict(E=70e9, nu=0.33, rho=2700.0, R=2.5e-3, v=3.9, mu=0.092, e=0.98,
             angles=list(range(5, 86)))
# Chung & Ooi (2011), tests 5-8 (cases/verification/make_cases.py)
TEST5 = dict(E=2.08e11, nu=0.3, rho=7850.0, R=1e-5, v=5.0, mu=0.3, e=1.0,
             tangential=[0.1, 0.3, 0.45, 0.6, 0.9, 1.2, 1.5, 1.8, 2.25, 2.7, 3.0, 3.75, 4.5,
                         5.25, 6.0, 7.5, 9.0, 12.0, 15.0, 18.0, 21.0])
SPINS = [0.175, 0.3, 0.42, 0.6, 0.8, 1.0, 1.2, 1.5, 2.0, 2.4, 2.8, 3.0, 3.5, 4.0, 6.0, 8.0,
         10.0, 12.0, 14.0, 21.0]
TEST6 = dict(E=70e9, nu=0.33, rho=2700.0, R=0.1, v=0.2, mu=0.4, e=0.5, spins=SPINS)
TEST7 = TEST6
TEST8 = dict(TEST6, R2=0.5, rho2=2.7e6)


def sphere_mass(rho, r):
    return 4.0 / 3.0 * math.pi * r**3 * rho


def hertz(mstar, rstar, estar, v):
    """Undamped Hertz impact at relative normal speed v: maximum overlap, maximum force,
    contact duration (Johnson 1985, eqs. 11.22-11.24)."""
    dmax = (15.0 * mstar * v**2 / (16.0 * estar * math.sqrt(rstar)))**0.4
    fmax = 4.0 / 3.0 * estar * math.sqrt(rstar) * dmax**1.5
    # t_c = 2 (dmax / v) * integral_0^1 dx / sqrt(1 - x^(5/2))
    integral = math.gamma(1.4) * math.gamma(0.5) / math.gamma(0.9)
    return dmax, fmax, 2.0 * integral * dmax / v


def test1_theory():
    p = TEST1
    m = sphere_mass(p["rho"], p["R"])
    estar = p["E"] / (2.0 * (1.0 - p["nu"]**2))
    return hertz(m / 2.0, p["R"] / 2.0, estar, 2.0 * p["v"])


def test2_theory():
    p = TEST2
    m = sphere_mass(p["rho"], p["R"])
    estar = p["E"] / (1.0 - p["nu"]**2)       # rigid plane
    return hertz(m, p["R"], estar, p["v"])


def hertz_curve(mstar, rstar, estar, v, n=200):
    """Force against overlap on loading, (4/3) E* sqrt(R*) d^(3/2), up to d_max."""
    dmax, _, _ = hertz(mstar, rstar, estar, v)
    d = np.linspace(0.0, dmax, n)
    return d, 4.0 / 3.0 * estar * math.sqrt(rstar) * d**1.5


def test4_limits(theta_deg):
    """Gross-sliding limits from |F_t| <= mu F_n (Chung & Ooi 2011, eqs. 30-31): the least
    tangential restitution, the largest spin magnitude, the least rebound angle."""
    p = TEST4
    t = np.radians(np.asarray(theta_deg, dtype=float))
    mu, e, v, r = p["mu"], p["e"], p["v"], p["R"]
    et_min = 1.0 - mu * (1.0 + e) / np.tan(t)
    spin_max = 5.0 * mu * (1.0 + e) * v * np.cos(t) / (2.0 * r)
    rebound_min = np.degrees(np.arctan((np.tan(t) - 3.5 * mu * (1.0 + e)) / e))
    return et_min, spin_max, rebound_min


def sliding_threshold_deg():
    """Incident angle above which the sphere slides through the whole impact:
    tan(theta) = 3.5 mu (1 + e)."""
    p = TEST4
    return math.degrees(math.atan(3.5 * p["mu"] * (1.0 + p["e"])))


def read_csv(path):
    """Columns of a CSV file with a header line: numbers as float arrays, others as strings."""
    with open(path) as f:
        rows = list(csv.reader(f))
    header = [h.strip() for h in rows[0]]
    columns = {}
    for k, h in enumerate(header):
        values = [r[k].strip() for r in rows[1:]]
        try:
            columns[h] = np.array([float(x) for x in values])
        except ValueError:
            columns[h] = np.array(values)
    return columns


def contact_metrics(contact_csv):
    """Maximum overlap, maximum normal force and contact duration from contact.csv. The
    start and end of contact are where the signed overlap crosses zero, interpolated
    linearly between steps."""
    c = read_csv(contact_csv)
    t, d, fn = c["time"], c["overlap"], c["normal_force"]
    inside = np.nonzero(d > 0.0)[0]
    k0, k1 = inside[0], inside[-1]

    def crossing(a, b):
        return t[a] + (0.0 - d[a]) * (t[b] - t[a]) / (d[b] - d[a])

    duration = crossing(k1, k1 + 1) - crossing(k0 - 1, k0)
    return d.max(), fn.max(), duration


def restitutions(final_csv, v_in):
    """Achieved normal restitution -v_z'/v_z of every particle in final.csv."""
    f = read_csv(final_csv)
    return f["vz"] / v_in


def oblique_results(final_csv):
    """Tangential restitution, spin (positive in the sense friction produces) and rebound
    angle at the contact point, for spheres sliding along +x on a plane facing +z."""
    p = TEST4
    f = read_csv(final_csv)
    t = np.radians(np.asarray(p["angles"], dtype=float))
    vt, vn = p["v"] * np.sin(t), p["v"] * np.cos(t)
    et = f["vx"] / vt
    spin = f["wy"]
    v_contact = f["vx"] - p["R"] * spin
    rebound = np.degrees(np.arctan2(v_contact, f["vz"]))
    return et, spin, rebound, f["vz"] / vn


def tsuji_impulses(e, steps=200000):
    """The normal impulses of a Hertz contact with the damping of doc/theory.md 2.1 (Tsuji's
    form, c_n = -2 sqrt(5/6) beta), in units of m* v: the net impulse (1 + e, the restitution
    being exact for the continuous equation) and the impulse of its repulsive part, which
    exceeds it by the attractive end of the contact (2.2). In the units delta = L x,
    t = (L / v) tau, L = (m* v^2 / K)^(2/5), K = (4/3) E* sqrt(R*), the equation is
    x'' = -(x^(3/2) + D x^(1/4) x') with D = c_n sqrt(3/2), whatever m*, R*, E* and v;
    integrated here with classical Runge-Kutta from x = 0, x' = 1 until x returns to 0."""
    beta = math.log(e) / math.sqrt(math.log(e)**2 + math.pi**2)
    d = -2.0 * math.sqrt(5.0 / 6.0) * beta * math.sqrt(1.5)

    def force(x, u):
        x = max(x, 0.0)
        return x**1.5 + d * x**0.25 * u

    h = 4.0 / steps                       # the contact lasts about 2.9 units
    x, u, net, rep = 0.0, 1.0, 0.0, 0.0
    while True:
        k1x, k1u = u, -force(x, u)
        k2x, k2u = u + 0.5 * h * k1u, -force(x + 0.5 * h * k1x, u + 0.5 * h * k1u)
        k3x, k3u = u + 0.5 * h * k2u, -force(x + 0.5 * h * k2x, u + 0.5 * h * k2u)
        k4x, k4u = u + h * k3u, -force(x + h * k3x, u + h * k3u)
        f = force(x, u)
        x_new = x + h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x)
        u_new = u + h / 6.0 * (k1u + 2 * k2u + 2 * k3u + k4u)
        if x_new <= 0.0:
            frac = x / (x - x_new)        # the step's part before x crosses 0
            net += frac * h * f
            rep += frac * h * max(f, 0.0)
            return net, rep
        net += h * f                      # (left rectangles: the step is small)
        rep += h * max(f, 0.0)
        x, u = x_new, u_new


def test5_results(final_csv):
    """Test 5, per sphere: the normalised incident angle v_t / (mu v_n), the normalised spin
    R w' / (mu v_n) and rebound angle v_ct' / (mu v_n') (v_ct' = v_x' - R w_y', the contact
    point's tangential velocity), and their gross-sliding values 5 (1 + e) / 2 and
    (v_t / (mu v_n) - 3.5 (1 + e)) / e, which hold when v_t / (mu v_n) > 3.5 (1 + e)."""
    p = TEST5
    f = read_csv(final_csv)
    vt = np.asarray(p["tangential"])
    mu, e, v, r = p["mu"], p["e"], p["v"], p["R"]
    incident = vt / (mu * v)
    spin = r * f["wy"] / (mu * v)
    rebound = (f["vx"] - r * f["wy"]) / (mu * f["vz"])
    sliding = incident > 3.5 * (1.0 + e)
    spin_limit = np.full(len(vt), 2.5 * (1.0 + e))
    rebound_limit = (incident - 3.5 * (1.0 + e)) / e
    return incident, spin, spin_limit, rebound, rebound_limit, sliding


def spin_results(stem, final_csv):
    """Tests 6-8, per spinning sphere (ids 1.. in test 6; 1, 3, 5, ... in tests 7 and 8):
    the initial spin w0, the change of spin w' + w0 (friction slows it), its gross-sliding
    value 5 mu (1 + e) v_n m* / (2 R m) (m* / m = 1 against the plane; 1/2 and v_n = 2 v in
    test 7, whose spheres meet at 2 v; m2 / (m1 + m2) in test 8), that value for friction
    mu times the repulsive part of the normal force (the Coulomb-capped law: times the
    repulsive over the net normal impulse, tsuji_impulses), and whether the contact slides
    throughout: R w0 above 3.5 mu (1 + e) v (the contact point's slip, and in test 7 both
    surfaces', stops at that change)."""
    p = TEST6
    f = read_csv(final_csv)
    w0 = np.asarray(p["spins"])
    rows = slice(None) if stem == "test6_spin_wall" else slice(0, None, 2)
    change = f["wy"][rows] + w0
    ratio = 1.0
    if stem == "test8_spin_large":
        m1 = sphere_mass(p["rho"], p["R"])
        m2 = sphere_mass(TEST8["rho2"], TEST8["R2"])
        ratio = m2 / (m1 + m2)
    limit = 2.5 * p["mu"] * (1.0 + p["e"]) * p["v"] * ratio / p["R"] * np.ones(len(w0))
    sliding = p["R"] * w0 > 3.5 * p["mu"] * (1.0 + p["e"]) * p["v"]
    net, repulsive = tsuji_impulses(p["e"])
    return w0, change, limit, limit * repulsive / net, sliding


CHUNG_OOI_CASES = ("test1_sphere_sphere", "test2_sphere_wall", "test3_restitution",
                   "test4_oblique")
SLIDING_CASES = ("test5_tangential", "test6_spin_wall", "test7_spin_pair", "test8_spin_large")


def summary(stem, out):
    """The measured quantities of one test from its outputs in `out` (contact.csv or
    final.csv), as {(stem, quantity, index): value}: peak overlap and force and duration
    (tests 1-2), restitution per sphere (test 3), tangential restitution, spin, rebound angle
    and normal restitution per angle (test 4)."""
    if stem in ("test1_sphere_sphere", "test2_sphere_wall"):
        values = contact_metrics(f"{out}/contact.csv")
        return {(stem, q, 0): v for q, v in zip(("max_overlap", "max_force", "duration"), values)}
    if stem == "test3_restitution":
        e = restitutions(f"{out}/final.csv", TEST3["v"])
        return {(stem, "restitution", k): v for k, v in enumerate(e)}
    names = ("tangential_restitution", "spin", "rebound_angle", "normal_restitution")
    return {(stem, q, k): v for q, a in zip(names, oblique_results(f"{out}/final.csv"))
            for k, v in enumerate(a)}
