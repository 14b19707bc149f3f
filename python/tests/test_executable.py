# SPDX-License-Identifier: BSD-3-Clause
"""The same case run by the dem program and from Python to the same end time: the same
particles (ids, materials, radii) at the same positions and velocities, in the program's
final.csv, in Python's arrays, and in the final.csv that closing the Python run writes."""
import os
import subprocess

import numpy as np
import pytest

import dem
from conftest import GLASS, ROOT, dem_exe, write_case

T_END = 0.02


def pour(folder, out):
    """64 spheres falling onto a floor and bouncing, with friction: contacts between
    spheres and with the wall."""
    lines = [f"&run dt = 1e-5, t_end = {T_END}, gravity = 0, 0, -9.81 /",
             f"&output dir = '{out}', interval = 2e-3 /", GLASS,
             "&material name = 'rigid', rigid = .true. /",
             "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /",
             "&pair materials = 'glass', 'rigid', restitution = 0.5, friction = 0.3 /",
             "&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, "
             "half_width = 0.02, divisions = 2 /"]
    rng = np.random.default_rng(4)
    for k in range(64):
        i, j, l = k % 4, (k // 4) % 4, k // 16
        x = np.array([2.1e-3 * i, 2.1e-3 * j, 1.2e-3 + 2.1e-3 * l])
        x[:2] += rng.uniform(-1e-4, 1e-4, 2)
        lines.append(f"&particle id = {k + 1}, material = 'glass', radius = 1e-3, "
                     f"position = {x[0]!r}, {x[1]!r}, {x[2]!r} /")
    return write_case(folder, "pour.nml", lines)


def read_final(path, materials=("glass", "rigid")):
    """final.csv as an array sorted by id (id, material index from 1, radius, x, v, w
    columns; the file names the material)."""
    rows = []
    with open(path) as f:
        next(f)
        for line in f:
            fields = line.strip().split(",")
            fields[1] = materials.index(fields[1].strip().strip("'\"")) + 1
            rows.append([float(v) for v in fields])
    a = np.array(rows)
    return a[np.argsort(a[:, 0])]


def test_same_as_the_program(work):
    exe = dem_exe()
    if not os.path.exists(exe):
        pytest.skip(f"no dem program at {exe}")
    out_exe = os.path.join(work, "out_exe")
    case = pour(os.path.join(work, "exe"), out_exe)
    r = subprocess.run([exe, case], cwd=work, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    program = read_final(os.path.join(out_exe, "final.csv"))

    out_py = os.path.join(work, "out_py")
    with dem.Run(pour(os.path.join(work, "py"), out_py)) as run:
        run.advance(T_END)                               # one advance, the case's sub-steps
        p = run.particles()
    o = np.argsort(p.gid)
    python = np.column_stack([p.gid, p.material, p.radius, p.x, p.v, p.w])[o]
    written = read_final(os.path.join(out_py, "final.csv"))
    assert python.shape == program.shape == (64, 12)
    assert np.array_equal(python[:, :3], program[:, :3])            # ids, materials, radii
    # positions and velocities: the same steps (the advance's sub-step is t_end / steps,
    # the program's dt: equal to the last bits, not necessarily in them)
    assert np.allclose(python[:, 3:6], program[:, 3:6], rtol=0, atol=1e-9)
    assert np.allclose(python[:, 6:], program[:, 6:], rtol=0, atol=1e-6)
    assert np.allclose(written, python, rtol=1e-9, atol=1e-12)
    assert program[:, 5].min() < 1.2e-3                 # they fell: the test is not trivial
