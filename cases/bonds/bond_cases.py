# SPDX-License-Identifier: BSD-3-Clause
"""What the two sides of the bonded-particle cases share, without Yade: the geometry, the
parallel bond's targets, the expectations (Euler-Bernoulli and the discrete chain) and the
frequency estimate. Imported by yade_bonds.py and yade_beam.py (under Yade) and by
dem_bonds.py and bench_bonds.py (plain Python with numpy); see README.md."""
import math

import numpy as np

R = 1e-3             # sphere radius [m]
DENSITY = 2500.0     # [kg/m^3]
YOUNG = 1e8          # bond modulus E [Pa]
HUGE = 1e20          # a strength that is never reached [Pa]
DT = 1e-6            # time step [s]

N_BEAM = 21          # spheres of the cantilever, sphere 0 clamped
G = 9.81             # gravity, along -z [m/s^2]
DAMPING_STATIC = 0.4 # Cundall's local damping of the static beam
T_VIBRATION = 0.2    # [s]
SAMPLE = 10          # steps between two records of the tip's z

SPEED = 1e-3         # the bars' driven sphere [m/s]
STRENGTH = 1e5       # the bars' breaking strength [Pa]
N_TENSION = 5
N_SHEAR = 2


def bond_targets(radius, lam, young, kratio, sigma_c, tau_c):
    """The parallel bond between two spheres of `radius` touching (L0 = 2 radius): its area,
    moments of area and the four pair stiffnesses and two break forces that Yade must match."""
    rb = lam * radius
    area = math.pi * rb**2
    inertia = math.pi * rb**4 / 4.0
    polar = math.pi * rb**4 / 2.0
    kn_area = young / (2.0 * radius)          # normal stiffness per area, E / L0
    ks_area = kn_area / kratio
    return {"bond_radius": rb, "A": area, "I": inertia, "J": polar, "L0": 2.0 * radius,
            "kn": kn_area * area, "ks": ks_area * area,
            "kr": kn_area * inertia, "ktw": ks_area * polar,
            "Fn_break": sigma_c * area, "Fs_break": tau_c * area}


def beam_targets():
    """The beam's bonds: radius R, unbreakable."""
    return bond_targets(R, 1.0, YOUNG, 1.0, HUGE, HUGE)


def bar_targets(case):
    """The bar's bonds ('tension' or 'shear'), the sphere count, the driven sphere's
    velocity, the expected break force and the quasi-static break time."""
    if case == "tension":
        t = bond_targets(R, 1.0, YOUNG, 1.0, STRENGTH, HUGE)
        n, vel, force, stiff = N_TENSION, (SPEED, 0.0, 0.0), t["Fn_break"], t["kn"]
    else:
        t = bond_targets(R, 1.0, YOUNG, 1.0, HUGE, STRENGTH)
        n, vel, force, stiff = N_SHEAR, (0.0, 0.0, SPEED), t["Fs_break"], t["ks"]
    return t, n, vel, force, (n - 1) * force / stiff / SPEED


def mass():
    return DENSITY * 4.0 / 3.0 * math.pi * R**3


def chain_matrices(t, m, n=N_BEAM):
    """Stiffness and mass matrices of the clamped chain's in-plane (z, rotation about y)
    motion: the bond between spheres k and k+1 has a shear spring t['ks'] on
    w_{k+1} - w_k + R (theta_k + theta_{k+1}) and a bending spring t['kr'] on
    theta_{k+1} - theta_k. Unknowns (w_k, theta_k) for k = 1..n-1."""
    size = 2 * (n - 1)
    K = np.zeros((size, size))

    def idx(k):  # sphere k's w and theta, None for the clamped sphere 0
        return (None, None) if k == 0 else (2 * (k - 1), 2 * (k - 1) + 1)

    for k in range(n - 1):
        (w1, r1), (w2, r2) = idx(k), idx(k + 1)
        for coef, terms in ((t["ks"], ((w2, 1.0), (w1, -1.0), (r1, R), (r2, R))),
                            (t["kr"], ((r2, 1.0), (r1, -1.0)))):
            for a, ca in terms:
                for b, cb in terms:
                    if a is not None and b is not None:
                        K[a, b] += coef * ca * cb
    M = np.diag([m, 0.4 * m * R**2] * (n - 1))
    return K, M


def expectations(t, m):
    """The beam's tip deflection and first frequency: Euler-Bernoulli (q = m g / 2R over
    l = 2R (N - 1)) and the discrete chain solved as a linear system."""
    EI = YOUNG * t["I"]
    length = 2.0 * R * (N_BEAM - 1)
    mu = m / (2.0 * R)
    K, M = chain_matrices(t, m)
    f = np.zeros(K.shape[0])
    f[0::2] = -m * G
    static_chain = -np.linalg.solve(K, f)[-2]
    d = 1.0 / np.sqrt(np.diag(M))
    omega2 = np.linalg.eigvalsh(K * d[:, None] * d[None, :])
    return {"EB_tip_deflection": mu * G * length**4 / (8.0 * EI),
            "EB_f1": 1.8751**2 / (2.0 * math.pi) * math.sqrt(EI / (mu * length**4)),
            "chain_tip_deflection": static_chain,
            "chain_f1": math.sqrt(omega2[0]) / (2.0 * math.pi)}


def frequency(ts, zs):
    """Frequency of z(t) from its upward crossings of the mean (linear interpolation), and
    from the FFT's peak (parabolic interpolation of the log magnitude, 16x zero padding)."""
    y = zs - zs.mean()
    up = np.nonzero((y[:-1] < 0.0) & (y[1:] >= 0.0))[0]
    tc = ts[up] - y[up] * (ts[up + 1] - ts[up]) / (y[up + 1] - y[up])
    f_cross = (len(tc) - 1) / (tc[-1] - tc[0])
    nfft = 16 * len(y)
    spec = np.abs(np.fft.rfft(y * np.hanning(len(y)), nfft))
    i = int(np.argmax(spec[1:])) + 1
    a, b, c = np.log(spec[i - 1:i + 2])
    di = 0.5 * (a - c) / (a - 2.0 * b + c)
    f_fft = (i + di) / (nfft * (ts[-1] - ts[0]) / (len(ts) - 1))
    return f_cross, f_fft, len(tc)
