# SPDX-License-Identifier: BSD-3-Clause
"""Shared part of the Yade side of the bonded-particle cases (imported by yade_beam.py and
yade_bar.py, which run under Yade 2023.02a: `yade -n -x -j1 SCRIPT ARGS`).

A chain of equal spheres (radius R, centres 2R apart along x) joined by Yade's cohesive
contacts (CohFrictMat, Ip2_CohFrictMat_CohFrictMat_CohFrictPhys,
Law2_ScGeom6D_CohFrictPhys_CohesionMoment) whose stiffnesses and strengths are chosen to be
those of a parallel bond of radius lambda*R (see README.md, "Matching the parameters")."""
import json
import sys

from bond_cases import DENSITY, DT, R
from yade import O, utils
from yade.wrapper import (Bo1_Sphere_Aabb, CohFrictMat, ForceResetter,
                          Ig2_Sphere_Sphere_ScGeom6D, InsertionSortCollider,
                          InteractionLoop, Ip2_CohFrictMat_CohFrictMat_CohFrictPhys,
                          Law2_ScGeom6D_CohFrictPhys_CohesionMoment, NewtonIntegrator)


def yade_material(radius, t):
    """CohFrictMat values that give the pair stiffnesses and adhesions in `t` (from
    bond_cases.bond_targets) for two equal spheres of `radius`. Yade 2023.02a, equal radii and one
    material: kn = young*R, ks = poisson*kn, kr = alphaKr*ks*R^2, ktw = alphaKtw*ks*R^2,
    normalAdhesion = normalCohesion*R^2, shearAdhesion = shearCohesion*R^2."""
    young = t["kn"] / radius
    poisson = t["ks"] / t["kn"]
    ks = poisson * young * radius
    return CohFrictMat(young=young, poisson=poisson, density=DENSITY, frictionAngle=0.0,
                       alphaKr=t["kr"] / (ks * radius**2),
                       alphaKtw=t["ktw"] / (ks * radius**2),
                       normalCohesion=t["Fn_break"] / radius**2,
                       shearCohesion=t["Fs_break"] / radius**2,
                       momentRotationLaw=True, isCohesive=True, fragile=True,
                       etaRoll=-1.0, etaTwist=-1.0, label="bond")


def build_chain(n, t, gravity, damping, dt, incremental, extra_engines=()):
    """n spheres at x = 2Rk, bonds between consecutive ones only (created explicitly, so no
    other pair is ever bonded), and the engine list. `extra_engines` run after the
    interaction loop (they see this step's bond forces) and before the integrator."""
    O.reset()
    mat = O.materials.append(yade_material(R, t))
    for k in range(n):
        O.bodies.append(utils.sphere((2.0 * R * k, 0.0, 0.0), R, material=mat))
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb()]),
        InteractionLoop([Ig2_Sphere_Sphere_ScGeom6D()],
                        [Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionNow=True)],
                        [Law2_ScGeom6D_CohFrictPhys_CohesionMoment(
                            useIncrementalForm=incremental, label="law")]),
        *extra_engines,
        NewtonIntegrator(gravity=gravity, damping=damping, label="newton"),
    ]
    O.dt = dt
    for k in range(n - 1):
        utils.createInteraction(k, k + 1)
    return mat


def bond_phys(t):
    """The first bond's stiffnesses and adhesions as Yade computed them, with their ratio
    to the targets (1 when the mapping is right)."""
    i = O.interactions[0, 1]
    p = i.phys
    got = {"kn": p.kn, "ks": p.ks, "kr": p.kr, "ktw": p.ktw,
           "normalAdhesion": p.normalAdhesion, "shearAdhesion": p.shearAdhesion}
    want = {"kn": t["kn"], "ks": t["ks"], "kr": t["kr"], "ktw": t["ktw"],
            "normalAdhesion": t["Fn_break"], "shearAdhesion": t["Fs_break"]}
    return {"yade": got, "ratio_to_target": {k: got[k] / want[k] for k in got}}


def parse(choices):
    """`SCRIPT CASE [--out FILE] [--dt DT] [--total]` from sys.argv (as Yade passes them)."""
    args = sys.argv[1:]
    opts = {"out": None, "dt": DT, "total": False}
    if not args or args[0] not in choices:
        sys.exit(f"usage: yade -n -x -j1 {sys.argv[0]} {'|'.join(choices)} "
                 "[--out FILE] [--dt SECONDS] [--total]")
    case = args.pop(0)
    while args:
        a = args.pop(0)
        if a == "--out":
            opts["out"] = args.pop(0)
        elif a == "--dt":
            opts["dt"] = float(args.pop(0))
        elif a == "--total":
            opts["total"] = True
        else:
            sys.exit(f"unknown argument {a}")
    return case, opts


def report(result, out):
    """One JSON line on standard output, and the same into `out` when given."""
    line = json.dumps(result, sort_keys=True)
    print(line, flush=True)
    if out:
        with open(out, "w") as f:
            f.write(json.dumps(result, indent=1, sort_keys=True) + "\n")
