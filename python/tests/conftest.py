# SPDX-License-Identifier: BSD-3-Clause
"""Shared set-up of the Python package's tests: the package from this source tree (unless
an installed one is asked for), the solver's library and program from the environment
(DEM_LIBRARY, DEM_EXE: CTest sets them) or the repository's build/, cases written as text."""
import os
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
if not os.environ.get("DEM_TEST_INSTALLED"):
    sys.path.insert(0, os.path.dirname(HERE))             # python/: the package's sources


def dem_exe():
    """The dem program to compare with (DEM_EXE, else build/dem)."""
    return os.environ.get("DEM_EXE", os.path.join(ROOT, "build", "dem"))


def write_case(folder, name, lines):
    """Write the case `name` in `folder` from its namelist lines; return its path."""
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return path


GLASS = ("&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, "
         "poisson_ratio = 0.25 /")


@pytest.fixture
def work(tmp_path):
    """A fresh folder for a test's cases and outputs."""
    return str(tmp_path)
