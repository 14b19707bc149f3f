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
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))  # Yade runs it by exec
import bond_cases as bc  # noqa: E402
import yade_bonds as yb  # noqa: E402
import yade.config  # noqa: E402
from yade import O, utils  # noqa: E402
from yade.wrapper import PyRunner  # noqa: E402


def setup(t, opts, damping, extra=()):
    yb.build_chain(bc.N_BEAM, t, (0.0, 0.0, -bc.G), damping, opts["dt"], not opts["total"],
                   extra)
    O.bodies[0].state.blockedDOFs = "xyzXYZ"


def run_static():
    last = None
    while True:
        O.run(20000, True)
        z = O.bodies[bc.N_BEAM - 1].state.pos[2]
        if last is not None and abs(z - last) < 1e-13 and utils.unbalancedForce() < 1e-6:
            break
        if O.iter > 10_000_000:
            sys.exit("the beam did not come to rest")
        last = z
    return {"tip_deflection": -z, "steps": O.iter, "time": O.time,
            "unbalanced_force": utils.unbalancedForce(),
            "kinetic_energy": utils.kineticEnergy()}


REC_T, REC_Z = [], []


def record_tip():
    """Runs after the integrator: the tip's position is that of time O.time + O.dt."""
    REC_T.append(O.time + O.dt)
    REC_Z.append(O.bodies[bc.N_BEAM - 1].state.pos[2])


def run_vibration():
    O.engines = O.engines + [PyRunner(iterPeriod=bc.SAMPLE, initRun=True,
                                      command="record_tip()")]
    steps = int(round(bc.T_VIBRATION / O.dt))
    start = time.perf_counter()
    O.run(steps, True)
    wall = time.perf_counter() - start
    ts, zs = np.array(REC_T), np.array(REC_Z)
    f_cross, f_fft, ncross = bc.frequency(ts, zs)
    nbonds = sum(1 for i in O.interactions if i.isReal)
    return {"f1_zero_crossings": f_cross, "f1_fft": f_fft, "upward_crossings": ncross,
            "tip_mean_deflection": -zs.mean(), "tip_min_z": zs.min(), "tip_max_z": zs.max(),
            "steps": O.iter, "time": O.time, "bonds": nbonds, "wall_s": wall,
            "ns_per_bond_step": wall / (O.iter * nbonds) * 1e9,
            "sample_steps": bc.SAMPLE, "threads": O.numThreads}


def main():
    case, opts = yb.parse(("static", "vibration"))
    t = bc.beam_targets()
    m = bc.mass()
    setup(t, opts, bc.DAMPING_STATIC if case == "static" else 0.0)
    result = {"case": "beam_" + case, "dt": O.dt, "moments": "total" if opts["total"]
              else "incremental", "targets": t, "mass": m,
              "expected": bc.expectations(t, m),
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
