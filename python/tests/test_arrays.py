# SPDX-License-Identifier: BSD-3-Clause
"""The particles as NumPy arrays: views over the solver's memory (no copy) that agree with
the copies; the deposit of a cloud of spheres onto a grid that holds them all keeps their
volume and momentum (every kernel), and onto one cell gives their volume over the cell's."""
import ctypes
import math

import numpy as np
import pytest

import dem
from conftest import GLASS, write_case


def cloud(folder, n=27):
    """n spheres of radius 0.5 mm on a 3 x 3 x 3 lattice of 2 mm, each with its own
    velocity, falling freely."""
    lines = ["&run dt = 1e-5, t_end = 1.0, gravity = 0, 0, -9.81 /",
             f"&output dir = '{folder}/out', interval = 1e-3 /", GLASS,
             "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /"]
    for k in range(n):
        i, j, l = k % 3, (k // 3) % 3, k // 9
        lines.append(f"&particle id = {k + 1}, material = 'glass', radius = 5e-4, "
                     f"position = {2e-3 * i}, {2e-3 * j}, {2e-3 * l}, "
                     f"velocity = {0.01 * i}, {-0.02 * j}, {0.005 * k} /")
    return write_case(folder, "cloud.nml", lines)


def test_views_are_the_solvers_memory(work):
    with dem.Run(cloud(work)) as run:
        run.advance(1e-3)
        views, copies = run.views(), run.particles()
        for name in ("gid", "radius", "x", "v", "w"):
            a, b = getattr(views, name), getattr(copies, name)
            assert np.array_equal(a, b), name
            assert not a.flags.writeable and not a.flags.owndata, name
        assert views.material is None and np.all(copies.material == 1)
        # the same memory as the C interface hands out: no copy was made
        x = ctypes.c_void_p()
        null = ctypes.c_void_p()
        run._lib.dem_coupling_views(run._handle, ctypes.byref(null), ctypes.byref(null),
                                    ctypes.byref(x), ctypes.byref(null), ctypes.byref(null))
        assert views.x.ctypes.data == x.value
        assert np.shares_memory(views.x, run.views().x)
        run.advance(1e-3)
        assert np.array_equal(run.views().x, run.particles().x)


@pytest.mark.parametrize("kernel", ["cell", "trilinear", "dpvm"])
def test_deposit_keeps_volume_and_momentum(work, kernel):
    with dem.Run(cloud(work)) as run:
        run.advance(1e-3)
        p = run.particles()
        volume = (4.0 / 3.0 * math.pi * p.radius**3).sum()
        momentum = (2500.0 * 4.0 / 3.0 * math.pi * p.radius[:, None]**3 * p.v).sum(axis=0)
        h = np.array([1e-3, 1.25e-3, 1.5e-3])
        n = (8, 7, 6)                                    # cells of different sizes per axis
        origin = np.array([-2e-3, -2.5e-3, -3e-3])
        d = run.deposit(origin, h, n, kernel)
        assert d.eps.shape == n and d.momentum.shape == n + (3,)
        assert abs(d.eps.sum() * h.prod() - volume) < 1e-12 * volume
        assert np.allclose(d.momentum.sum(axis=(0, 1, 2)), momentum, rtol=1e-12, atol=1e-18)
        assert np.all(d.beta_sum == 0.0)                  # no drag set
        # eps[i, j, k] is the cell at origin + (i, j, k) h: the particle nearest the
        # origin's corner lies in cell (2, 2, 2) (cell kernel)
        if kernel == "cell":
            c = tuple(int(k) for k in np.floor((p.x[np.argmin(p.gid)] - origin) / h))
            assert d.eps[c] > 0


def test_deposit_cells(work):
    with dem.Run(cloud(work)) as run:
        p = run.particles()
        volume = (4.0 / 3.0 * math.pi * p.radius**3).sum()
        d = run.deposit_cells([[2e-3, 2e-3, 2e-3], [1.0, 1.0, 1.0]], [1e-6, 1.0])
        assert abs(d.eps[0] - volume / 1e-6) < 1e-12 * volume / 1e-6
        assert d.eps[1] == 0.0


def test_errors_name_the_cause(work):
    with pytest.raises(dem.DemError) as e:
        dem.Run(f"{work}/no_such_case.nml")
    assert "no_such_case.nml" in str(e.value) and e.value.status != 0
    with dem.Run(cloud(work)) as run:
        with pytest.raises(dem.DemError) as e:
            run.advance(-1.0)
        assert e.value.status == 2 and "dt" in e.value.message
        with pytest.raises(dem.DemError):
            run.set_force_by_id([999], [0.0, 0.0, 1.0])    # no such particle
        with pytest.raises(ValueError):
            run.set_force(np.zeros((2, 3)))                 # 27 particles
    assert run.closed
    with pytest.raises(dem.DemError):
        run.advance(1e-3)


def test_open_run_closed_at_exit(work):
    """A script that never closes its run: the run is closed at the interpreter's exit
    (final.csv written), before MPI is finalised (exit status 0)."""
    import os
    import subprocess
    import sys
    case = cloud(work)
    package = os.path.dirname(os.path.dirname(dem.__file__))
    script = f"import dem\nrun = dem.Run({case!r})\nrun.advance(1e-3)\n"
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=package), timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    assert os.path.exists(os.path.join(work, "out", "final.csv"))
