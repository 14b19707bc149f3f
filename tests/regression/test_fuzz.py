# SPDX-License-Identifier: BSD-3-Clause
"""Fuzzed inputs (scripts/dev/fuzz-inputs, its fixed seed): 200 mutants of a small case's
namelist, particle file and STL wall, and of one of its checkpoints. Each runs through
`dem --check` and `dem`; none may crash or hang, `--check` must accept exactly the mutants
whose run does not fail at its start, a run that ends with exit 0 must leave whole, finite
series.csv and final.csv, and a run refused at its start no output directory (the checks
are scripts/dev/fuzz-inputs's; every failing mutant is printed with what was changed).
usage: test_fuzz.py DEM WORKDIR"""
import os
import subprocess
import sys

from regression_util import ROOT, check, finish

dem, work = sys.argv[1], sys.argv[2]
r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "dev", "fuzz-inputs"), dem, work,
                    "--count", "200", "--jobs", "8"], capture_output=True, text=True,
                   timeout=1200)
print(r.stdout[-20000:], r.stderr[-5000:])
check(r.returncode == 0 and "200 mutants" in r.stdout and ": 0 failed" in r.stdout,
      f"fuzz-inputs: exit {r.returncode}, {r.stdout.strip().splitlines()[-1:]}")
finish()
