# SPDX-License-Identifier: BSD-3-Clause
"""Two equal glass spheres meeting head-on without gravity: the total momentum is conserved
to round-off; an elastic collision (restitution 1) exchanges their velocities and keeps the
kinetic energy; with restitution 0.5 the relative velocity after the contact is -0.5 times
the one before (within the 1 % the contact law's damping holds, test_chung_ooi) and the
kinetic energy lost is (1 - e^2) of the relative motion's."""
import math

import numpy as np
import pytest

import dem
from conftest import GLASS, write_case

R, RHO, V0 = 1e-3, 2500.0, 0.1


def head_on(folder, restitution):
    """Spheres 1 and 2 on the x axis, 0.2 mm apart, at +-V0 towards each other."""
    return write_case(folder, "head_on.nml", [
        "&run dt = 1e-6, t_end = 1.0, gravity = 0, 0, 0 /",
        f"&output dir = '{folder}/out', interval = 1e-4 /",
        GLASS,
        f"&pair materials = 'glass', 'glass', restitution = {restitution}, friction = 0.3 /",
        f"&particle id = 1, material = 'glass', radius = {R}, position = -1.1e-3, 0, 0, "
        f"velocity = {V0}, 0, 0 /",
        f"&particle id = 2, material = 'glass', radius = {R}, position = 1.1e-3, 0, 0, "
        f"velocity = {-V0}, 0, 0 /"])


def by_id(p):
    """Velocities and angular velocities of particles 1 and 2, in that order."""
    order = np.argsort(p.gid)
    return p.v[order], p.w[order]


@pytest.mark.parametrize("e", [1.0, 0.5])
def test_head_on(work, e):
    mass = RHO * 4.0 / 3.0 * math.pi * R**3
    with dem.Run(head_on(work, e)) as run:
        v, _ = by_id(run.particles())
        p_before = mass * v.sum(axis=0)
        ke_before = 0.5 * mass * (v**2).sum()
        rel_before = v[1, 0] - v[0, 0]
        touched = False
        for _ in range(40):                          # 4 ms: the gap closes at 1 ms, the
            run.advance(1e-4)                        # contact lasts about 0.3 ms
            v, w = by_id(run.particles())
            assert np.allclose(mass * v.sum(axis=0), p_before, rtol=0,
                               atol=1e-14 * mass * V0)
            touched = touched or v[0, 0] < V0 * (1 - 1e-9)
        assert touched
        assert np.all(np.abs(w) < 1e-12)             # head-on: no rotation
        rel_after = v[1, 0] - v[0, 0]
        assert rel_after > 0                          # apart
        assert abs(rel_after / -rel_before - e) < 0.01 * e
        ke_after = 0.5 * mass * (v**2).sum()
        if e == 1.0:
            assert np.allclose(v[:, 0], [-V0, V0], rtol=1e-3)      # exchanged
            assert abs(ke_after - ke_before) < 1e-4 * ke_before
        else:
            ke_rel = 0.25 * mass * rel_before**2                  # reduced mass m/2
            lost = ke_before - ke_after
            assert abs(lost - (1 - e**2) * ke_rel) < 0.02 * ke_rel
