# SPDX-License-Identifier: BSD-3-Clause
"""Bonded particles side by side with Yade 2023.02a (doc/results/bonds.md), without Yade:
cases/bonds/dem_bonds.py runs dem on the cantilever (at rest under gravity with local
damping, and vibrating undamped) and on the bar broken in tension and in shear, and each
result must match the same run of Yade committed in doc/results/bonds_yade.json within the
tolerances of doc/results/bonds.md (0.5 %): the tip's deflection, the first frequency by
zero crossings and by the FFT, the break time and the force at the break. Also: the static
tip has come to rest as Yade's did (it moved less than 1e-13 m over the last 20 000 steps),
the bond that breaks in tension is the one next to the driven sphere, as in Yade, and the
bonds' forces dem_bonds.py reads from the tracked spheres hold the bond energy dem writes
(to 1e-6).
usage: test_bonds_yade.py DEM WORKDIR"""
import json
import os
import shutil
import sys

from regression_util import ROOT, check, check_close, finish

sys.path.insert(0, os.path.join(ROOT, "cases", "bonds"))
import dem_bonds  # noqa: E402

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
with open(os.path.join(ROOT, "doc", "results", "bonds_yade.json")) as f:
    yade = json.load(f)["runs"]

for case in dem_bonds.CASES:
    res = dem_bonds.run_case(dem, work, case)
    for key, tol in dem_bonds.TOLERANCES[case].items():
        check_close(res[key], yade[case][key], tol, f"{case}: {key} against Yade's")
        print(f"{case} {key}: dem {res[key]:.9g}, Yade {yade[case][key]:.9g}")
    if case == "beam_static":
        check(res["tip_change_last_rows"] < 1e-13, "static: the tip moved "
              f"{res['tip_change_last_rows']:.3g} m over the last {res['rest_steps']} steps")
    if case.startswith("bar_"):
        check(res["broken_bonds"] == yade[case]["broken_bonds"],
              f"{case}: bond {res['broken_bonds']} broke, Yade's {yade[case]['broken_bonds']}")
        check(abs(res["energy_check"]) < 1e-6, f"{case}: the tracked bond forces hold the "
              f"bond energy of series.csv to {res['energy_check']:.3g}")
finish()
