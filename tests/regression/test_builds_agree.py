# SPDX-License-Identifier: BSD-3-Clause
"""An OpenACC build gives the same results as the plain build: the same cases, run with both
executables, write identical files (every digit of every number; the HDF5 snapshots and
checkpoints byte for byte, as they carry no time stamps). scripts/install/build makes the
OpenACC build for any x86-64 and the plain one for the machine's vector instructions
(DEM_SIMD), so this also checks that these give the same bits.
usage: test_builds_agree.py DEM WORKDIR REFERENCE_DEM"""
import filecmp
import os
import sys

from regression_util import HERE, ROOT, check, finish, run_dem

dem, work, reference = sys.argv[1], sys.argv[2], sys.argv[3]


def files(top):
    """The files under a directory, as sorted relative paths."""
    return sorted(os.path.relpath(os.path.join(d, f), top)
                  for d, _, names in os.walk(top) for f in names)


cases = [os.path.join(ROOT, "cases", "verification", name + ".nml")
         for name in ("test1_sphere_sphere", "test2_sphere_wall", "test3_restitution",
                      "test4_oblique")]
cases.append(os.path.join(HERE, "cases", "head_on_100.nml"))
for case in cases:
    stem = os.path.splitext(os.path.basename(case))[0]
    outputs = []
    for label, exe in (("tested", dem), ("reference", reference)):
        run_dem(exe, case, os.path.join(work, label))
        outputs.append(os.path.join(work, label, "output", stem))
    names = files(outputs[1])
    check(names == files(outputs[0]), f"{stem}: different output files")
    for name in names:
        same = filecmp.cmp(os.path.join(outputs[0], name), os.path.join(outputs[1], name),
                           shallow=False)
        check(same, f"{stem}/{name}: differs between {dem} and {reference}")
finish()
