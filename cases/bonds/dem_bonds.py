# SPDX-License-Identifier: BSD-3-Clause
"""The dem side of the bonded-particle cases: the same four cases as yade_beam.py and
yade_bar.py (bond_cases.py holds what they share), written as dem case files, run with a
given dem executable, and their results in the keys of Yade's JSON. From the repository root:

    .venv/bin/python cases/bonds/dem_bonds.py --dem build/dem [--work DIR] [--out FILE]
        [--case beam_static|beam_vibration|bar_tension|bar_shear ...] [--check YADE_JSON]

beam_static: 21 spheres, sphere 0 fixed, gravity, Cundall's local damping 0.4 (&run
local_damping), 0.6 s; the tip's deflection and its change over the last 20 000 steps.
beam_vibration: undamped, gravity on at t = 0 from the straight beam; the tip's z every 10
steps over 0.2 s, its frequency by upward zero crossings and by the FFT peak (as Yade's).
bar_tension, bar_shear: the first step with a broken bond (the time of its force
evaluation, as Yade reports it), which bond broke and its force at the step before.
dem writes no force per bond: the script takes it from the tracked spheres (the bond's
incremental force is k A times the sum of the rates of the steps' force evaluations) and
checks it against series.csv's bond energy (`energy_check`: 1e-9 in tension, the positions'
rounding; 7e-7 in shear, where the pair turns by 1e-3 rad and the shear force is taken from
the energy instead).

--check compares each result with the same run of a Yade JSON (doc/results/bonds_yade.json)
within the tolerances of doc/results/bonds.md and exits 1 if one is missed."""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bond_cases as bc  # noqa: E402

CASES = ("beam_static", "beam_vibration", "bar_tension", "bar_shear")
T_STATIC = 0.6          # [s], as long as Yade's static run took to come to rest
REST_STEPS = 20000      # the static tip's change is measured over this many steps
# the largest relative difference to Yade that --check accepts (doc/results/bonds.md)
TOLERANCES = {"beam_static": {"tip_deflection": 5e-3},
              "beam_vibration": {"f1_zero_crossings": 5e-3, "f1_fft": 5e-3},
              "bar_tension": {"force_at_break": 5e-3, "t_break": 5e-3},
              "bar_shear": {"force_at_break": 5e-3, "t_break": 5e-3}}


def case_text(name, t_end, interval, particles, probes, gravity, bond="", damping=0.0):
    """A dem case file: spheres of one material, the contact law off while bonded (the
    material's own elastic constants act only after a break), touching pairs bonded."""
    run_extra = f", local_damping = {damping}" if damping > 0.0 else ""
    return f"""&run dt = {bc.DT!r}, t_end = {t_end!r}, gravity = 0, 0, {-gravity!r},
     progress_interval = 0{run_extra} /
&output dir = 'out_{name}', interval = {interval!r}, snapshot_interval = 0, overwrite = .true. /
&material name = 'm', density = {bc.DENSITY!r}, youngs_modulus = {bc.YOUNG!r},
          poisson_ratio = 0.3 /
&pair materials = 'm', 'm', restitution = 0.5, friction = 0.0 /
{particles}
{probes}
&bond modulus = {bc.YOUNG!r}, stiffness_ratio = 1, radius_ratio = 1, contact = .false.{bond} /
"""


def chain(n, driven=None):
    """n spheres 2R apart along x, ids 1..n, sphere 0 fixed; `driven` the last sphere's
    velocity (then it is fixed too)."""
    rows = []
    for k in range(n):
        extra = ""
        if k == 0:
            extra = ", fixed = .true."
        elif k == n - 1 and driven is not None:
            extra = ", velocity = {!r}, {!r}, {!r}, fixed = .true.".format(*driven)
        rows.append(f"&particle id = {k + 1}, material = 'm', radius = {bc.R!r}, "
                    f"position = {2.0 * bc.R * k!r}, 0, 0{extra} /")
    return "\n".join(rows)


def track(ids):
    return "\n".join(f"&probe name = 's{i}', kind = 'track', id = {i} /" for i in ids)


def run_dem(dem, work, name, text):
    """Write `name`.nml in work, run dem on it; the output folder and the wall time [s]."""
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    start = time.perf_counter()
    r = subprocess.run([dem, name + ".nml"], cwd=work, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if r.returncode != 0:
        sys.exit(f"dem {path}: exit {r.returncode}\n{r.stdout}\n{r.stderr}")
    return os.path.join(work, "out_" + name), wall


def csv(out, name):
    return np.genfromtxt(os.path.join(out, name), delimiter=",", names=True)


def beam_static(dem, work):
    t, m = bc.beam_targets(), bc.mass()
    tip = bc.N_BEAM
    text = case_text("beam_static", T_STATIC, REST_STEPS * bc.DT, chain(bc.N_BEAM),
                     track([tip]), bc.G, damping=bc.DAMPING_STATIC)
    out, _ = run_dem(dem, work, "beam_static", text)
    p = csv(out, "probes.csv")
    z = p[f"s{tip}_z"]
    v = np.array([p[f"s{tip}_v{c}"][-1] for c in "xyz"])
    return {"tip_deflection": -z[-1], "tip_change_last_rows": abs(z[-1] - z[-2]),
            "rest_steps": REST_STEPS, "steps": int(round(p["time"][-1] / bc.DT)),
            "time": p["time"][-1], "tip_speed": float(np.linalg.norm(v)),
            "mass": m, "targets": t}


def beam_vibration(dem, work):
    t, m = bc.beam_targets(), bc.mass()
    tip = bc.N_BEAM
    text = case_text("beam_vibration", bc.T_VIBRATION, bc.SAMPLE * bc.DT, chain(bc.N_BEAM),
                     track([tip]), bc.G)
    out, wall = run_dem(dem, work, "beam_vibration", text)
    p = csv(out, "probes.csv")
    ts, zs = p["time"], p[f"s{tip}_z"]
    f_cross, f_fft, ncross = bc.frequency(ts, zs)
    s = csv(out, "series.csv")
    nbonds = int(s["bonds"][-1])
    steps = int(round(bc.T_VIBRATION / bc.DT))
    return {"f1_zero_crossings": f_cross, "f1_fft": f_fft, "upward_crossings": ncross,
            "tip_mean_deflection": -zs.mean(), "tip_min_z": zs.min(), "tip_max_z": zs.max(),
            "steps": steps, "time": ts[-1], "bonds": nbonds, "wall_s": wall,
            "ns_per_bond_step": wall / (steps * nbonds) * 1e9, "sample_steps": bc.SAMPLE,
            "threads": 1, "mass": m, "targets": t}


def bond_forces_from_tracks(p, n, t, rows):
    """The force of each bond k-(k+1) [tension, |shear|] held at the given rows of
    probes.csv (row 0 the start, row j after step j): after step j the incremental force is
    k A dt times the sum of the rates u(0) .. u(j-1) of the rows its force evaluations saw,
    and row j has moved by dt (u(1) + .. + u(j)) (symplectic Euler), so the force is
    k A (d(j) - d(0) - (u(j) - u(0)) dt) with d the bond's stretch or shear offset (the
    spheres do not turn: no lever terms; first order in the pair's rotation)."""
    def col(i, c):
        return p[f"s{i + 1}_{c}"]
    res = [[] for _ in rows]
    for k in range(n - 1):
        dx = np.stack([col(k + 1, c) - col(k, c) for c in "xyz"], axis=1)
        dv = np.stack([col(k + 1, "v" + c) - col(k, "v" + c) for c in "xyz"], axis=1)
        for out, r in zip(res, rows):
            nrm = dx[r] / np.linalg.norm(dx[r])
            # stretch along the pair, and offset across it
            fn = np.linalg.norm(dx[r]) - np.linalg.norm(dx[0]) - \
                (np.dot(dv[r], nrm) - np.dot(dv[0], nrm)) * bc.DT
            shift = dx[r] - dx[0] - (dv[r] - dv[0]) * bc.DT
            fs = np.linalg.norm(shift - np.dot(shift, nrm) * nrm)
            out.append((t["kn"] * fn, t["ks"] * fs))
    return res


def bar(dem, work, case):
    t, n, vel, expected_f, expected_t = bc.bar_targets(case)
    name = "bar_" + case
    strength = (f", tensile_strength = {bc.STRENGTH!r}" if case == "tension"
                else f", shear_strength = {bc.STRENGTH!r}")
    text = case_text(name, 1.5 * expected_t, bc.DT, chain(n, vel), track(range(1, n + 1)),
                     0.0, strength)
    out, _ = run_dem(dem, work, name, text)
    s, p = csv(out, "series.csv"), csv(out, "probes.csv")
    if not np.array_equal(s["time"], p["time"]):
        sys.exit(f"{out}: series.csv and probes.csv have different rows")
    broken_rows = np.nonzero(s["bonds_broken"] > 0)[0]
    if len(broken_rows) == 0:
        sys.exit(f"{name}: no bond broke by t = {s['time'][-1]}")
    first = broken_rows[0]
    if first < 1:
        sys.exit(f"{name}: a bond broke at the first step")
    # the rows before and after the step that broke: the bonds whose force at that step
    # (the row after it) reached the strength are those that broke
    before, after = bond_forces_from_tracks(p, n, t, [first - 1, first])
    axis = 0 if case == "tension" else 1
    broken = [k for k, f in enumerate(after) if f[axis] > expected_f]
    if not broken:
        sys.exit(f"{name}: no bond's force reached the strength at the break")
    energy = s["bond_energy"][first - 1]
    tracked = sum(fn**2 / (2.0 * t["kn"]) + fs**2 / (2.0 * t["ks"]) for fn, fs in before)
    if case == "shear":
        # the pair turns by 1e-3 rad: |F_s| from the one bond's energy less its normal
        # force's share, exact where the tracks' small-angle estimate is not (to 7e-7)
        fn = before[0][0]
        before[0] = (fn, math.sqrt(2.0 * t["ks"] * (energy - fn**2 / (2.0 * t["kn"]))))
    got_f = before[broken[0]][axis]
    # a row is written after its step: the step that broke evaluated its forces one dt
    # before the row's time
    t_break = s["time"][first] - bc.DT
    return {"t_break": t_break, "iter_break": int(round(t_break / bc.DT)),
            "broken_bonds": broken, "bonds_broken_count": int(s["bonds_broken"][first]),
            "t_last_intact": t_break - bc.DT,
            "force_last_intact": [list(before[k]) for k in broken],
            "force_at_break": got_f, "expected_force": expected_f,
            "expected_time_quasistatic": expected_t,
            "rel_diff_force": got_f / expected_f - 1.0,
            "rel_diff_time": t_break / expected_t - 1.0,
            "energy_check": tracked / energy - 1.0,
            "targets": t}


def run_case(dem, work, case):
    if case == "beam_static":
        res = beam_static(dem, work)
        got, keys = res["tip_deflection"], ("EB_tip_deflection", "chain_tip_deflection")
    elif case == "beam_vibration":
        res = beam_vibration(dem, work)
        got, keys = res["f1_zero_crossings"], ("EB_f1", "chain_f1")
    else:
        return bar(dem, work, case.split("_")[1])
    res["expected"] = bc.expectations(res["targets"], res["mass"])
    res["rel_diff"] = {k: got / res["expected"][k] - 1.0 for k in keys}
    return res


def check(results, yade_json):
    """Each result against the same run of Yade within TOLERANCES; the failures."""
    with open(yade_json) as f:
        yade = json.load(f)["runs"]
    failed = []
    for case, res in results.items():
        for key, tol in TOLERANCES[case].items():
            ref = yade[case][key]
            rel = res[key] / ref - 1.0
            ok = abs(rel) <= tol
            print(f"{case} {key}: dem {res[key]:.9g}, Yade {ref:.9g}, {rel:+.2e} "
                  f"({'within' if ok else 'OUTSIDE'} {tol:g})")
            if not ok:
                failed.append(f"{case} {key}")
    return failed


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dem", required=True, help="the dem executable")
    ap.add_argument("--work", default="output/bonds/dem", help="folder of the runs")
    ap.add_argument("--out", help="write the results here (JSON)")
    ap.add_argument("--case", action="append", choices=CASES, help="(default: all)")
    ap.add_argument("--check", metavar="YADE_JSON", help="compare with Yade's results")
    a = ap.parse_args()
    dem = os.path.abspath(a.dem)
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    results = {}
    for case in a.case or CASES:
        res = run_case(dem, a.work, case)
        res.update({"case": case, "dt": bc.DT, "moments": "incremental"})
        results[case] = res
        print(json.dumps({case: {k: v for k, v in res.items()
                                 if k not in ("targets", "expected")}}, sort_keys=True),
              flush=True)
    doc = {"code": "dem (this repository), one MPI rank", "runs": results,
           "command": " ".join(["cases/bonds/dem_bonds.py"] + sys.argv[1:])}
    if a.out:
        with open(a.out, "w") as f:
            f.write(json.dumps(doc, indent=1, sort_keys=True) + "\n")
    if a.check and check(results, a.check):
        sys.exit(1)


if __name__ == "__main__":
    main()
