# SPDX-License-Identifier: BSD-3-Clause
"""Stokes settling: a glass sphere released in a viscous fluid, with the drag
beta (u_f - v), beta = 6 pi mu R, set through the package and buoyancy as an external force,
reaches the analytical terminal velocity 2 (rho_p - rho_f) g R^2 / (9 mu); the impulses of
force and drag plus gravity's m g t equal its momentum."""
import math

import numpy as np

import dem
from conftest import GLASS, write_case

MU, RHO_F, RHO_P, R, G = 1.0, 1000.0, 2500.0, 1e-3, 9.81


def settling_case(folder):
    """One glass sphere at rest at the origin, gravity along -z, no walls."""
    return write_case(folder, "stokes.nml", [
        "&run dt = 3e-5, t_end = 1.0, gravity = 0, 0, -9.81 /",
        f"&output dir = '{folder}/out', interval = 0.005 /",
        GLASS,
        "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /",
        "&particle id = 1, material = 'glass', radius = 1e-3, position = 0, 0, 0 /"])


def test_terminal_velocity(work):
    volume = 4.0 / 3.0 * math.pi * R**3
    mass = RHO_P * volume
    beta = 6.0 * math.pi * MU * R
    v_t = 2.0 * (RHO_P - RHO_F) * G * R**2 / (9.0 * MU)
    tau = mass / beta
    dt_fluid = 1e-4
    with dem.Run(settling_case(work)) as run:
        assert run.count == 1
        run.set_drag(beta, [0.0, 0.0, 0.0])
        run.set_force([0.0, 0.0, RHO_F * volume * G])          # buoyancy
        impulse = np.zeros(3)
        steps = int(round(18 * tau / dt_fluid))
        for _ in range(steps):
            run.advance(dt_fluid)
            impulse += run.impulse()[0]
        t = run.time
        assert abs(t - steps * dt_fluid) < 1e-12
        p = run.particles()
        v = p.v[0]
        # the terminal velocity, analytically (18 relaxation times: e^-18 ~ 1.5e-8)
        assert abs(v[2] + v_t) < 1e-4 * v_t, (v[2], -v_t)
        assert abs(v[0]) < 1e-15 and abs(v[1]) < 1e-15
        # the momentum is the impulses of the force and drag plus gravity's
        momentum = mass * v
        expected = impulse + np.array([0.0, 0.0, -mass * G * t])
        assert np.allclose(momentum, expected, rtol=0, atol=1e-9 * mass * v_t)
        # the distance fallen: the continuous solution to the scheme's O(h / tau)
        z = -v_t * (t - tau * (1.0 - math.exp(-t / tau)))
        assert abs(p.x[0, 2] - z) < 0.02 * abs(z)


def test_two_runs_at_once(work):
    """Two handles in one process, advanced in turn: the one with drag settles at the
    terminal velocity, the other, without, falls freely (v = -g t, exact for a constant
    acceleration); neither sees the other's forces."""
    volume = 4.0 / 3.0 * math.pi * R**3
    beta = 6.0 * math.pi * MU * R
    v_t = 2.0 * (RHO_P - RHO_F) * G * R**2 / (9.0 * MU)
    with dem.Run(settling_case(f"{work}/a")) as fluid, \
            dem.Run(settling_case(f"{work}/b")) as vacuum:
        fluid.set_drag(beta, [0.0, 0.0, 0.0])
        fluid.set_force([0.0, 0.0, RHO_F * volume * G])
        for _ in range(100):
            fluid.advance(1e-4)
            vacuum.advance(1e-4)
        assert abs(fluid.particles().v[0, 2] + v_t) < 1e-4 * v_t
        assert abs(vacuum.particles().v[0, 2] + G * vacuum.time) < 1e-12
        assert np.all(vacuum.impulse() == 0.0)
