# SPDX-License-Identifier: BSD-3-Clause
"""Bond breakage in Yade 2023.02a. Spheres of R = 1 mm (2500 kg/m^3) in a line along x,
parallel bonds of radius R (E = 1e8 Pa, kratio = 1) between neighbours, no gravity, sphere 0
held fixed. Run from the repository root:

    yade -n -x -j1 cases/bonds/yade_bar.py tension|shear [--out FILE] [--dt S] [--total]

tension: 5 spheres, sphere 4 moved at +1e-3 m/s along x; tensile strength 1e5 Pa, shear
strength unreachable. Expected: a bond breaks at F = sigma_c A = 0.314159 N, when the bar has
been stretched by 4 sigma_c L0 / E (t = 8 ms at quasi-static loading).
shear: 2 spheres, sphere 1 moved at +1e-3 m/s along z with its rotation blocked; shear
strength 1e5 Pa, tensile strength unreachable. Expected: the bond breaks at
|Fs| = tau_c A = 0.314159 N, after a shear displacement tau_c A / ks (t = 2 ms).
Prints (and writes to FILE) the time of the first break, which bond broke and its force at
the last step before (the step's force increment is below 1e-3 of it)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))  # Yade runs it by exec
import bond_cases as bc  # noqa: E402
import yade_bonds as yb  # noqa: E402
import yade.config  # noqa: E402
from yade import O  # noqa: E402
from yade.wrapper import PyRunner  # noqa: E402

HIST = {"t": None, "forces": None, "break": None}


def bond_forces(n):
    """(tension, |shear|) of each bond k-(k+1) still cohesive, None for a broken one."""
    out = []
    for k in range(n - 1):
        i = O.interactions[k, k + 1] if O.interactions.has(k, k + 1) else None
        if i is None or not i.isReal or i.phys.cohesionBroken:
            out.append(None)
        else:
            out.append((-i.phys.normalForce.dot(i.geom.normal), i.phys.shearForce.norm()))
    return out


def watch(n):
    """Runs every step after the interaction loop: keeps the last intact forces, and stops
    the run at the first broken bond."""
    forces = bond_forces(n)
    broken = [k for k, f in enumerate(forces) if f is None]
    if broken:
        HIST["break"] = {"t_break": O.time, "iter_break": O.iter, "broken_bonds": broken,
                         "t_last_intact": HIST["t"],
                         "force_last_intact": [HIST["forces"][k] for k in broken]}
        O.pause()
    else:
        HIST["t"], HIST["forces"] = O.time, forces


def main():
    case, opts = yb.parse(("tension", "shear"))
    t, n, vel, expected_f, expected_t = bc.bar_targets(case)
    yb.build_chain(n, t, (0.0, 0.0, 0.0), 0.0, opts["dt"], not opts["total"],
                   [PyRunner(iterPeriod=1, command=f"watch({n})")])
    for b in (O.bodies[0], O.bodies[n - 1]):
        b.state.blockedDOFs = "xyzXYZ"
    O.bodies[n - 1].state.vel = vel
    bond = yb.bond_phys(t)
    O.run(int(3 * expected_t / O.dt), True)
    if HIST["break"] is None:
        sys.exit("no bond broke")
    res = HIST["break"]
    f_tension, f_shear = res["force_last_intact"][0]
    got_f = f_tension if case == "tension" else f_shear
    res.update({"case": "bar_" + case, "dt": O.dt, "yade": yade.config.version,
                "moments": "total" if opts["total"] else "incremental",
                "targets": t, "bond": bond, "expected_force": expected_f,
                "expected_time_quasistatic": expected_t,
                "force_at_break": got_f,
                "rel_diff_force": got_f / expected_f - 1.0,
                "rel_diff_time": res["t_break"] / expected_t - 1.0})
    yb.report(res, opts["out"])


main()
