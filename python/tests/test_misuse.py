# SPDX-License-Identifier: BSD-3-Clause
"""Misuse of a Run never takes the interpreter down: every bad argument (NaN, Inf, a grid
the doubles cannot resolve, cells too small for the particles) raises dem.DemError with
status 2 and leaves the run as it was; a run that failed (status 3) refuses every later
call that would go on with it, with the same message, and close() raises it, with no
final.csv written. Each case runs in a subprocess with a time limit, so that a crash or a
hang fails its test instead of killing pytest."""
import math
import os
import subprocess
import sys
import textwrap

import pytest

from conftest import GLASS, HERE, write_case

PAIR = "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /"


def one_sphere(folder):
    """A glass sphere of radius 1 mm at rest at the origin, falling (case dt 1e-5 s)."""
    return write_case(folder, "one.nml", [
        "&run dt = 1e-5, t_end = 1.0, gravity = 0, 0, -9.81 /",
        f"&output dir = '{folder}/out', interval = 1e-3 /", GLASS, PAIR,
        "&particle id = 1, material = 'glass', radius = 1e-3, position = 0, 0, 0 /"])


def head_on(folder):
    """Two glass spheres of R = 10 mm meeting head-on at +-100 m/s with dt twice the
    stability bound (allowed with allow_unstable): the run fails, unstable, when they
    meet (about t = 5e-5 s)."""
    return write_case(folder, "head_on.nml", [
        "&run dt = 1.5e-5, t_end = 4e-4, gravity = 0, 0, 0, expected_speed = 100, "
        "allow_unstable = .true. /",
        f"&output dir = '{folder}/out', interval = 1e-5 /",
        "&material name = 'glass', density = 2800.0, youngs_modulus = 48.0e9, "
        "poisson_ratio = 0.2 /",
        "&pair materials = 'glass', 'glass', restitution = 1.0, friction = 0.35 /",
        "&particle id = 1, material = 'glass', radius = 0.01, position = -0.0105, 0, 0, "
        "velocity = 100, 0, 0 /",
        "&particle id = 2, material = 'glass', radius = 0.01, position = 0.0105, 0, 0, "
        "velocity = -100, 0, 0 /"])


def run_script(body, case, timeout=60):
    """Run `body` in a fresh interpreter with `run` an open dem.Run of `case` and
    `raises(status, call, *args)` asserting that the call raises DemError of that status
    (it returns the message); the script's exit status and output."""
    script = textwrap.dedent("""\
        import math, sys
        import numpy as np
        import dem

        def raises(status, call, *args, **kwargs):
            try:
                call(*args, **kwargs)
            except dem.DemError as e:
                assert e.status == status, (e.status, e.message)
                return e.message
            raise AssertionError(f"no DemError from {call.__name__}{args}")

        run = dem.Run(sys.argv[1])
        """) + textwrap.dedent(body) + "\nprint('script done')\n"
    env = dict(os.environ)
    if not env.get("DEM_TEST_INSTALLED"):
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [os.path.dirname(HERE),
                                                          env.get("PYTHONPATH")]))
    done = subprocess.run([sys.executable, "-c", script, case], env=env, timeout=timeout,
                          capture_output=True, text=True)
    assert done.returncode == 0 and "script done" in done.stdout, \
        f"exit {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done.stdout


def test_deposit_refuses_origins_and_spacings_it_cannot_grid(work):
    """A NaN or infinite origin, an origin so far that the cells' faces are not distinct
    doubles (1e300 m with 1 mm cells), h = 1e-300 (the cell volume underflows) or cells
    smaller than 2/7 of the largest diameter (where the divided-volume kernel would need
    more than 8 cells per axis): status 2, naming the argument; then a good deposit still
    holds the sphere's volume."""
    run_script("""
        h, n = [1e-3] * 3, (4, 4, 4)
        for origin in ([math.nan, 0, 0], [0, math.inf, 0], [1e300, 1e300, 1e300],
                       [-1e300, 0, 0]):
            for kernel in ("cell", "trilinear", "dpvm"):
                assert "origin" in raises(2, run.deposit, origin, h, n, kernel)
        for bad_h in ([1e-300] * 3, [math.nan, 1e-3, 1e-3], [math.inf] * 3, [1e-3, 0, 1e-3],
                      [1e-3, 1e-3, 2e-4]):
            assert "h" in raises(2, run.deposit, [-2e-3] * 3, bad_h, n, "dpvm")
        assert "cells" in raises(2, run.deposit, [0] * 3, h, (2**11, 2**10, 2**10))
        raises(2, run.deposit, [0] * 3, h, (0, 4, 4))
        d = run.deposit([-2e-3] * 3, h, n, "dpvm")
        assert abs(d.eps.sum() * 1e-9 - 4 / 3 * math.pi * 1e-9) < 1e-12 * 4e-9
        assert np.all(np.isfinite(d.eps))
        run.close()
        """, one_sphere(work))


def test_deposit_far_from_the_particles(work):
    """A good grid far from the sphere (1e9 m, 1e10 cells away) leaves it out (status 0,
    eps 0 everywhere) instead of reading outside the grid."""
    run_script("""
        d = run.deposit([1e6, 1e6, 1e6], [1e-3] * 3, (4, 4, 4), "dpvm")
        assert np.all(d.eps == 0.0)
        d = run.deposit([-1e6, -1e6, -1e6], [1e-3] * 3, (4, 4, 4), "cell")
        assert np.all(d.eps == 0.0)
        run.close()
        """, one_sphere(work))


def test_deposit_cells_refuses_bad_centres_and_volumes(work):
    """NaN or infinite centres (which hung the bucket search), centres whose spread
    overflows, and volumes that are not finite or too small for the particles: status 2."""
    run_script("""
        good = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
        for centres in ([[math.nan, 0, 0], [1, 1, 1]], [[0, 0, 0], [math.inf, 1, 1]],
                        [[-1.7e308, 0, 0], [1.7e308, 0, 0]]):
            assert "centre" in raises(2, run.deposit_cells, centres, [1.0, 1.0])
        for volumes in ([math.nan, 1.0], [1.0, math.inf], [1e-300, 1.0], [0.0, 1.0]):
            assert "volume" in raises(2, run.deposit_cells, good, volumes)
        d = run.deposit_cells(good, [1e-6, 1.0])
        assert abs(d.eps[0] - 4 / 3 * math.pi * 1e-9 / 1e-6) < 1e-12 * 4.2e-3
        run.close()
        """, one_sphere(work))


def test_refused_advance_changes_nothing(work):
    """advance(inf), advance(nan), advance(1e300) and advance(-1) are refused (status 2)
    before anything changes: the time is as it was, and the run goes on exactly as one
    that was never given them."""
    out = run_script("""
        run.advance(1e-3)
        t = run.time
        for dt in (math.inf, math.nan, 1e300, -1.0, 0.0, 2.0):
            raises(2, run.advance, dt)
            assert run.time == t, run.time
        run.advance(1e-3)
        print(repr(run.time), repr(run.particles().x[0, 2]))
        run.close()
        """, one_sphere(work))
    other = run_script("""
        run.advance(1e-3)
        run.advance(1e-3)
        print(repr(run.time), repr(run.particles().x[0, 2]))
        run.close()
        """, one_sphere(os.path.join(work, "other")))
    assert out == other


def test_failed_run_stays_failed(work):
    """After advance raises status 3 (unstable), every later advance, deposit and setter
    raises status 3 with the same message; close() raises it too, writes no final.csv
    (the last good state is the checkpoint the message names, if any), and the run is
    closed."""
    case = head_on(work)
    run_script("""
        first = raises(3, run.advance, 1.5e-5)
        assert "unstable" in first
        t = run.time
        assert raises(3, run.advance, 1e-5) == first
        assert raises(3, run.advance, 1e-5) == first
        assert run.time == t
        assert raises(3, run.deposit, [-0.1] * 3, [0.1] * 3, (2, 2, 2)) == first
        assert raises(3, run.deposit_cells, [[0, 0, 0]], [1.0]) == first
        assert raises(3, run.set_force, [0.0, 0.0, 1.0]) == first
        assert raises(3, run.set_force_by_id, [1], [0.0, 0.0, 1.0]) == first
        assert raises(3, run.close) == first
        assert run.closed
        run.close()                                     # closing twice does nothing
        """, case)
    assert not os.path.exists(os.path.join(work, "out", "final.csv"))


def test_non_finite_forces_and_drag_are_refused(work):
    """A NaN force, an infinite torque, a NaN drag coefficient or fluid velocity, or a
    negative drag coefficient: status 2, and the run goes on unharmed."""
    run_script("""
        for call, args in ((run.set_force, ([math.nan, 0, 0],)),
                           (run.set_force, ([0, 0, 0], [0, math.inf, 0])),
                           (run.set_drag, (math.nan, [0, 0, 0])),
                           (run.set_drag, (-1.0, [0, 0, 0])),
                           (run.set_drag, (1e-3, [0, math.nan, 0])),
                           (run.set_force_by_id, ([1], [math.nan, 0, 0])),
                           (run.set_drag_by_id, ([1], math.inf, [0, 0, 0]))):
            raises(2, call, *args)
        run.advance(1e-3)
        assert np.all(np.isfinite(run.particles().x))
        run.close()
        """, one_sphere(work))
    with open(os.path.join(work, "out", "final.csv")) as f:
        assert "nan" not in f.read().lower()
