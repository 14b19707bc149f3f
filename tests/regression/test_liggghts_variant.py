# SPDX-License-Identifier: BSD-3-Clause
"""The LIGGGHTS variant of the contact law (&contact_model variant = 'liggghts' /) against
LIGGGHTS 3.8.0's own results, committed as references (LIGGGHTS is not needed to run this):

- the small bed of cases/liggghts_bed (294 spheres and a steel sphere thrown in, 2.5 ms):
  every particle's final position and velocity against reference.csv, made by
  `scripts/bench/liggghts/bed-reference tests/regression/cases/liggghts_bed`;
- the Chung & Ooi tests 1-4 (cases/verification, the variant added): peak overlap and force
  and duration (tests 1-2), restitution (test 3), tangential restitution, spin and rebound
  angle (test 4) against reference/liggghts_chung_ooi.csv, made by
  `scripts/bench/liggghts/chung-ooi-liggghts OUT --summary tests/regression/reference/liggghts_chung_ooi.csv`,
  to 1e-6 relative (issue 29).

The default law is run on the same inputs too: it must differ from LIGGGHTS by far more than
the tolerances (it keeps the history's length, uses the radius as lever and resets a
pair's history when the contact ends), so that the comparison can fail.
usage: test_liggghts_variant.py DEM WORKDIR"""
import csv
import os
import subprocess
import sys

import numpy as np

from regression_util import HERE, ROOT, check, finish, run_dem
import chung_ooi as co

dem, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
VARIANT = "&contact_model variant = 'liggghts' /\n"
BED = os.path.join(HERE, "cases", "liggghts_bed")
POS_TOL, VEL_TOL = 1.0e-9, 1.0e-5     # [m], [m/s]: 1e-6 R, 1e-5 of the impact speed
RTOL = 1.0e-6


def final_state(out):
    f = co.read_csv(os.path.join(out, "final.csv"))
    order = np.argsort(f["id"])
    return f["id"][order], np.array([f[c][order] for c in ("x", "y", "z", "vx", "vy", "vz")]).T


def bed(text, name):
    path = os.path.join(work, name + ".nml")
    text = text.replace("file = 'particles.csv'", f"file = '{os.path.join(BED, 'particles.csv')}'")
    with open(path, "w") as f:
        f.write(text.replace("&output interval", f"&output dir = 'output/{name}', interval"))
    run_dem(dem, path, work)
    return final_state(os.path.join(work, "output", name))


# the small bed: the variant within the tolerances of LIGGGHTS's final state, the default
# law far outside them
ref = np.loadtxt(os.path.join(BED, "reference.csv"), delimiter=",", skiprows=1)
text = open(os.path.join(BED, "case.nml")).read()
check(VARIANT in text, "the bed case uses the LIGGGHTS variant")
for name, body, within in (("bed_liggghts", text, True),
                           ("bed_default", text.replace(VARIANT, ""), False)):
    ids, state = bed(body, name)
    check(np.array_equal(ids, ref[:, 0]), f"{name}: the reference's particles")
    dx = np.abs(state[:, :3] - ref[:, 1:4]).max()
    dv = np.abs(state[:, 3:] - ref[:, 4:7]).max()
    print(f"{name}: largest differences from LIGGGHTS {dx:.3g} m, {dv:.3g} m/s")
    if within:
        check(dx <= POS_TOL and dv <= VEL_TOL,
              f"{name}: within {POS_TOL:g} m and {VEL_TOL:g} m/s of LIGGGHTS ({dx:.3g}, {dv:.3g})")
    else:
        check(dx > 1e3 * POS_TOL and dv > 1e3 * VEL_TOL,
              f"{name}: the default law is far from LIGGGHTS ({dx:.3g} m, {dv:.3g} m/s)")

# dem --check names the law and the integrator the variant takes
r = subprocess.run([dem, "--check", os.path.join(work, "bed_liggghts.nml")], capture_output=True,
                   text=True)
check("contact law          Hertz-Mindlin, variant liggghts (&contact_model), velocity Verlet"
      in r.stdout, f"dem --check names the variant and its integrator:\n{r.stdout}")

# Chung & Ooi tests 1-4 with the variant against LIGGGHTS's quantities
reference = {}
with open(os.path.join(HERE, "reference", "liggghts_chung_ooi.csv")) as f:
    for r in csv.DictReader(f):
        reference[(r["test"], r["quantity"], int(r["index"]))] = float(r["value"])
cases = os.path.join(ROOT, "cases", "verification")
for law, extra in (("liggghts", VARIANT), ("default", "")):
    path = os.path.join(work, "chung_ooi_" + law)
    os.makedirs(path, exist_ok=True)
    got = {}
    for stem in co.CHUNG_OOI_CASES:
        case = os.path.join(path, stem + ".nml")
        with open(case, "w") as f:
            f.write(open(os.path.join(cases, stem + ".nml")).read() + extra)
        run_dem(dem, case, path)
        got.update(co.summary(stem, os.path.join(path, "output", stem)))
    worst = max(abs(got[k] - v) / abs(v) for k, v in reference.items() if v != 0.0)
    print(f"Chung & Ooi, {law} law: largest relative difference from LIGGGHTS {worst:.3g} "
          f"over {len(reference)} quantities")
    check(set(got) == set(reference), f"{law}: the reference's quantities")
    if law == "liggghts":
        for k, v in reference.items():
            check(abs(got[k] - v) <= RTOL * abs(v) + 1e-300,
                  f"Chung & Ooi {k}: {got[k]:.12g} against LIGGGHTS {v:.12g}")
    else:
        check(worst > 1e2 * RTOL, f"the default law differs from LIGGGHTS ({worst:.3g})")
finish()
