# SPDX-License-Identifier: BSD-3-Clause
"""Running LIGGGHTS 3.8.0 from the comparison scripts (chung-ooi-liggghts, bed-reference,
../compare-liggghts): one rank, output kept in the run directory, and the last snapshot of
a custom dump."""
import os
import subprocess
import sys

import numpy as np


def run(deck, work, variables=()):
    """Run `liggghts -in deck` (a file in work) in work with -var NAME VALUE for each pair of
    `variables`; stop with LIGGGHTS's last lines if it fails (screen.txt holds them all)."""
    cmd = ["mpirun", "--allow-run-as-root", "-np", "1", "stdbuf", "-oL", "liggghts", "-in",
           deck]
    for name, value in variables:
        cmd += ["-var", name, str(value)]
    with open(os.path.join(work, "screen.txt"), "w") as out:
        r = subprocess.run(cmd, cwd=work, stdout=out, stderr=subprocess.STDOUT)
    text = open(os.path.join(work, "screen.txt")).read()
    if r.returncode != 0 or "ERROR" in text:
        sys.exit(f"LIGGGHTS failed in {work}:\n{text[-2000:]}")


def last_dump(path):
    """The rows of the last snapshot of a custom dump, as an array."""
    lines = open(path).read().splitlines()
    k = max(i for i, s in enumerate(lines) if s.startswith("ITEM: ATOMS"))
    return np.array([[float(x) for x in s.split()] for s in lines[k + 1:] if s.strip()])
