# SPDX-License-Identifier: BSD-3-Clause
"""The cost per bond in Yade 2023.02a: a long cantilever, N spheres (R = 1 mm, 2500 kg/m^3)
along x bonded to their neighbours as in yade_beam.py (incremental moments), sphere 0
clamped, gravity, no damping, STEPS steps on one thread. From the repository root:

    yade -n -x -j1 cases/bonds/yade_chain.py N STEPS [--out FILE]

Prints (and writes to FILE) the wall time of the steps (O.run, set-up excluded) and the
nanoseconds per bond-step, wall / (STEPS x bonds). bench_bonds.py runs it beside dem."""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))  # Yade runs it by exec
import bond_cases as bc  # noqa: E402
import yade_bonds as yb  # noqa: E402
import yade.config  # noqa: E402
from yade import O  # noqa: E402


def main():
    args = sys.argv[1:]
    out = None
    if "--out" in args:
        i = args.index("--out")
        out = args[i + 1]
        del args[i:i + 2]
    if len(args) != 2:
        sys.exit(f"usage: yade -n -x -j1 {sys.argv[0]} N STEPS [--out FILE]")
    n, steps = int(args[0]), int(args[1])
    t = bc.beam_targets()
    yb.build_chain(n, t, (0.0, 0.0, -bc.G), 0.0, bc.DT, True)
    O.bodies[0].state.blockedDOFs = "xyzXYZ"
    start = time.perf_counter()
    O.run(steps, True)
    wall = time.perf_counter() - start
    bonds = sum(1 for i in O.interactions if i.isReal and not i.phys.cohesionBroken)
    yb.report({"case": "chain", "spheres": n, "bonds": bonds, "steps": O.iter,
               "wall_s": wall, "ns_per_bond_step": wall / (O.iter * bonds) * 1e9,
               "tip_z": O.bodies[n - 1].state.pos[2], "threads": O.numThreads,
               "yade": yade.config.version}, out)


main()
