# SPDX-License-Identifier: BSD-3-Clause
"""Bonded cantilever in Yade 2023.02a: 21 spheres (R = 1 mm, 2500 kg/m^3) in a line along x,
parallel bonds of radius R (E = 1e8 Pa, kratio = 1) between neighbours, sphere 0 clamped,
gravity -9.81 m/s^2 along z. Run from the repository root:

    yade -n -x -j1 cases/bonds/yade_beam.py static|vibration [--out FILE] [--dt S] [--total]

static: Cundall's local damping 0.4 until the tip is at rest; the tip's deflection.
vibration: no damping, gravity on at t = 0 from the straight beam; the tip's z(t) over 0.2 s
(about 8 periods) and its frequency (upward zero crossings of z - mean, and the FFT peak),
with the wall time of the run and the nanoseconds per bond-step.
--total uses Yade's default total formulation of the bending and twisting moments; without
it, the incremental one (as a parallel bond). Both report the Euler-Bernoulli values and those
of the same discrete chain solved as a linear system (lumped masses m and 2/5 m R^2, shear
springs at the contact points, bending springs between the rotations)."""
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))  # Yade runs it by exec
import yade_bonds as yb  # noqa: E402
import yade.config  # noqa: E402
from yade import O, utils  # noqa: E402
from yade.wrapper import PyRunner  # noqa: E402

N = 21
G = 9.81
T_VIBRATION = 0.2     # [s]
SAMPLE = 10           # steps between two records of the tip's z


def chain_matrices(t, m):
    """Stiffness and mass matrices of the clamped chain's in-plane (z, rotation about y)
    motion: the bond between spheres k and k+1 has a shear spring t['ks'] on
    w_{k+1} - w_k + R (theta_k + theta_{k+1}) and a bending spring t['kr'] on
    theta_{k+1} - theta_k. Unknowns (w_k, theta_k) for k = 1..N-1."""
    n = 2 * (N - 1)
    K = np.zeros((n, n))

    def idx(k):  # sphere k's w and theta, None for the clamped sphere 0
        return (None, None) if k == 0 else (2 * (k - 1), 2 * (k - 1) + 1)

    for k in range(N - 1):
        (w1, r1), (w2, r2) = idx(k), idx(k + 1)
        for coef, terms in ((t["ks"], ((w2, 1.0), (w1, -1.0), (r1, yb.R), (r2, yb.R))),
                            (t["kr"], ((r2, 1.0), (r1, -1.0)))):
            for a, ca in terms:
                for b, cb in terms:
                    if a is not None and b is not None:
                        K[a, b] += coef * ca * cb
    M = np.diag([m, 0.4 * m * yb.R**2] * (N - 1))
    return K, M


def expectations(t, m):
    EI = yb.YOUNG * t["I"]
    length = 2.0 * yb.R * (N - 1)
    mu = m / (2.0 * yb.R)
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


def setup(t, opts, damping, extra=()):
    yb.build_chain(N, t, (0.0, 0.0, -G), damping, opts["dt"], not opts["total"], extra)
    O.bodies[0].state.blockedDOFs = "xyzXYZ"


def run_static():
    last = None
    while True:
        O.run(20000, True)
        z = O.bodies[N - 1].state.pos[2]
        if last is not None and abs(z - last) < 1e-13 and utils.unbalancedForce() < 1e-6:
            break
        if O.iter > 10_000_000:
            sys.exit("the beam did not come to rest")
        last = z
    return {"tip_deflection": -z, "steps": O.iter, "time": O.time,
            "unbalanced_force": utils.unbalancedForce(),
            "kinetic_energy": utils.kineticEnergy()}


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


REC_T, REC_Z = [], []


def record_tip():
    """Runs after the integrator: the tip's position is that of time O.time + O.dt."""
    REC_T.append(O.time + O.dt)
    REC_Z.append(O.bodies[N - 1].state.pos[2])


def run_vibration():
    O.engines = O.engines + [PyRunner(iterPeriod=SAMPLE, initRun=True, command="record_tip()")]
    steps = int(round(T_VIBRATION / O.dt))
    start = time.perf_counter()
    O.run(steps, True)
    wall = time.perf_counter() - start
    ts, zs = np.array(REC_T), np.array(REC_Z)
    f_cross, f_fft, ncross = frequency(ts, zs)
    nbonds = sum(1 for i in O.interactions if i.isReal)
    return {"f1_zero_crossings": f_cross, "f1_fft": f_fft, "upward_crossings": ncross,
            "tip_mean_deflection": -zs.mean(), "tip_min_z": zs.min(), "tip_max_z": zs.max(),
            "steps": O.iter, "time": O.time, "bonds": nbonds, "wall_s": wall,
            "ns_per_bond_step": wall / (O.iter * nbonds) * 1e9,
            "sample_steps": SAMPLE, "threads": O.numThreads}


def main():
    case, opts = yb.parse(("static", "vibration"))
    t = yb.bond_targets(yb.R, 1.0, yb.YOUNG, 1.0, yb.HUGE, yb.HUGE)
    m = yb.mass()
    setup(t, opts, 0.4 if case == "static" else 0.0)
    result = {"case": "beam_" + case, "dt": O.dt, "moments": "total" if opts["total"]
              else "incremental", "targets": t, "mass": m, "expected": expectations(t, m),
              "yade": yade.config.version}
    if case == "static":
        result.update(run_static())
        got, keys = result["tip_deflection"], ("EB_tip_deflection", "chain_tip_deflection")
    else:
        result.update(run_vibration())
        got, keys = result["f1_zero_crossings"], ("EB_f1", "chain_f1")
    result["bond"] = yb.bond_phys(t)
    result["rel_diff"] = {k: got / result["expected"][k] - 1.0 for k in keys}
    yb.report(result, opts["out"])


main()
