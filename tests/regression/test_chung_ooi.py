# SPDX-License-Identifier: BSD-3-Clause
"""Chung & Ooi verification tests 1-4 (cases/verification) against Hertz theory and the
Coulomb limits, computed in scripts/post/chung_ooi.py independently of the solver; and tests
5-8 (a sphere sliding on a plane or on another sphere by its tangential velocity or its spin)
with the Coulomb-capped tangential law: where the contact slides throughout the impact, the
spin (and in test 5 the rebound angle) meet the rigid-body limits for a tangential impulse
of mu times the repulsive normal impulse within 0.1 % (the repulsive impulse exceeds the net
one by the attractive end of a damped contact: 3.4 % at e = 0.5, computed independently in
chung_ooi.tsuji_impulses), and nowhere does the spin change exceed them.
usage: test_chung_ooi.py DEM WORKDIR"""
import os
import shutil
import sys

import numpy as np

from regression_util import ROOT, check, check_close, finish, run_dem
import chung_ooi as co

dem, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)    # (an output folder of another case is refused)
cases = os.path.join(ROOT, "cases", "verification")


def out(stem, name):
    return os.path.join(work, "output", stem, name)


# Tests 1 and 2: maximum overlap, maximum force, contact duration within 0.5 %
for stem, theory in (("test1_sphere_sphere", co.test1_theory()),
                     ("test2_sphere_wall", co.test2_theory())):
    run_dem(dem, os.path.join(cases, stem + ".nml"), work)
    dmax, fmax, tc = co.contact_metrics(out(stem, "contact.csv"))
    check_close(dmax, theory[0], 5e-3, f"{stem}: maximum overlap")
    check_close(fmax, theory[1], 5e-3, f"{stem}: maximum normal force")
    check_close(tc, theory[2], 5e-3, f"{stem}: contact duration")

# Test 3: achieved restitution within 1 % of the input, for every value
stem = "test3_restitution"
run_dem(dem, os.path.join(cases, stem + ".nml"), work)
achieved = co.restitutions(out(stem, "final.csv"), co.TEST3["v"])
check(len(achieved) == len(co.TEST3["restitutions"]), "test 3: one sphere per restitution")
for e_in, e_out in zip(co.TEST3["restitutions"], achieved):
    check_close(e_out, e_in, 1e-2, f"test 3: restitution {e_in}")

# Test 3 with the linear law (normal_model = 'hooke', k_n = 1e8 N/m for every pair: contacts
# of about 5 us): its restitution is exact for the continuous equation (doc/theory.md, 2.4),
# within 1 % at this step
with open(os.path.join(cases, stem + ".nml")) as f:
    text = f.read().replace("friction = 0.0 /", "friction = 0.0, stiffness = 1e8 /")
with open(os.path.join(work, stem + "_hooke.nml"), "w") as f:
    f.write(text + "&contact_model normal_model = 'hooke' /\n")
run_dem(dem, os.path.join(work, stem + "_hooke.nml"), work)
achieved = co.restitutions(out(stem + "_hooke", "final.csv"), co.TEST3["v"])
for e_in, e_out in zip(co.TEST3["restitutions"], achieved):
    check_close(e_out, e_in, 1e-2, f"test 3, linear law: restitution {e_in}")

# Test 4: the Coulomb limits hold at every angle; above the sliding threshold the sphere
# slides throughout and meets them; well below it, it does not.
stem = "test4_oblique"
run_dem(dem, os.path.join(cases, stem + ".nml"), work)
et, spin, rebound, en = co.oblique_results(out(stem, "final.csv"))
angles = np.array(co.TEST4["angles"], dtype=float)
et_min, spin_max, rebound_min = co.test4_limits(angles)
threshold = co.sliding_threshold_deg()
for k, a in enumerate(angles):
    # |F_t| <= mu |F_n| at every step bounds the tangential impulse; the 1e-3 allows for
    # the brief attractive normal force at the end of a damped contact (theory.md, 2.2)
    check(spin[k] <= spin_max[k] * (1 + 1e-3), f"test 4, {a} deg: spin {spin[k]:.2f} "
          f"above the limit {spin_max[k]:.2f}")
    check(et[k] >= et_min[k] - 1e-3, f"test 4, {a} deg: tangential restitution {et[k]:.4f} "
          f"below the limit {et_min[k]:.4f}")
    check(rebound[k] >= rebound_min[k] - 0.05, f"test 4, {a} deg: rebound angle "
          f"{rebound[k]:.3f} below the limit {rebound_min[k]:.3f}")
    check_close(en[k], co.TEST4["e"], 1e-2, f"test 4, {a} deg: normal restitution")
    if a >= threshold + 0.5:
        check_close(spin[k], spin_max[k], 1e-3, f"test 4, {a} deg: gross sliding spin")
        check(abs(rebound[k] - rebound_min[k]) < 0.05, f"test 4, {a} deg: gross sliding "
              f"rebound angle {rebound[k]:.3f} vs {rebound_min[k]:.3f}")
    if a <= threshold - 7.5:
        check(spin[k] < 0.95 * spin_max[k], f"test 4, {a} deg: sticks or micro-slips, "
              f"spin {spin[k]:.2f} should stay below the sliding value {spin_max[k]:.2f}")
# where the spin first reaches the gross-sliding value (within 0.1 %)
first = angles[np.argmax(spin >= 0.999 * spin_max)]
check(abs(first - threshold) <= 3.0, f"test 4: sliding starts at {first} deg, theory "
      f"{threshold:.2f} deg")


def coulomb_case(stem):
    """Case `stem` with the Coulomb-capped tangential law, written into work; its outputs
    go to output/<stem>_coulomb."""
    path = os.path.join(work, stem + "_coulomb.nml")
    with open(os.path.join(cases, stem + ".nml")) as f:
        text = f.read()
    with open(path, "w") as f:
        f.write(text + "&contact_model tangential_model = 'coulomb' /\n")
    return path


# Tests 5-8 with the Coulomb-capped tangential law: the limits where the contact slides
# throughout; below them, the spin changes less (friction acts on the repulsive part of the
# normal force only, so the tangential impulse is at most mu times the repulsive impulse)
stem = "test5_tangential"
run_dem(dem, coulomb_case(stem), work)
incident, spin, spin_limit, rebound, rebound_limit, sliding = co.test5_results(
    out(stem + "_coulomb", "final.csv"))
check(np.count_nonzero(sliding) >= 3, "test 5: some impacts slide throughout")
for k in range(len(incident)):
    check(spin[k] <= spin_limit[k] * (1 + 1e-3), f"test 5, v_t/(mu v_n) = {incident[k]:.2f}: "
          f"spin {spin[k]:.4f} above its limit {spin_limit[k]:.4f}")
    if sliding[k]:
        check_close(spin[k], spin_limit[k], 1e-3, f"test 5, {incident[k]:.2f}: spin")
        check_close(rebound[k], rebound_limit[k], 1e-3, f"test 5, {incident[k]:.2f}: rebound")
for stem in ("test6_spin_wall", "test7_spin_pair", "test8_spin_large"):
    run_dem(dem, coulomb_case(stem), work)
    w0, change, _, limit, sliding = co.spin_results(stem, out(stem + "_coulomb",
                                                                 "final.csv"))
    check(np.count_nonzero(sliding) >= 3, f"{stem}: some impacts slide throughout")
    for k in range(len(w0)):
        check(change[k] <= limit[k] * (1 + 1e-3), f"{stem}, w0 = {w0[k]}: spin change "
              f"{change[k]:.4f} above its limit {limit[k]:.4f}")
        if sliding[k]:
            check_close(change[k], limit[k], 1e-3, f"{stem}, w0 = {w0[k]}: spin change")
finish()
