# SPDX-License-Identifier: BSD-3-Clause
"""An output folder is held by one run at a time: a second `dem.Run` of the same case, in
the same process, raises and names the holder (this process), and the folder is free again
once the first is closed; the program is refused while a `dem.Run` holds the folder."""
import os
import subprocess

import pytest

import dem
from conftest import GLASS, dem_exe, write_case


def case(folder):
    return write_case(folder, "one.nml", [
        "&run dt = 1e-5, t_end = 1e-3 /", f"&output dir = '{folder}/out', interval = 1e-4 /",
        GLASS, "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /",
        "&particle id = 1, material = 'glass', radius = 5e-4, position = 0, 0, 0 /"])


def test_second_run_of_a_folder_raises(work):
    path = case(work)
    with dem.Run(path) as first:
        with pytest.raises(dem.DemError) as e:
            dem.Run(path)
        assert e.value.status == 2
        assert f"process {os.getpid()} on host {os.uname().nodename}" in e.value.message
        assert "held by another run" in e.value.message
        r = subprocess.run([dem_exe(), path], cwd=work, capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 2 and f"process {os.getpid()}" in r.stderr, r.stderr
        first.advance(1e-4)
    with dem.Run(path) as again:            # released by the close
        again.advance(1e-4)
    assert open(os.path.join(work, "out", "lock")).read() == ""
