# SPDX-License-Identifier: BSD-3-Clause
"""A force or a drag set on one member of a clump moves and turns the whole body: a dimer of
two glass spheres (radius 1 mm, centres 3 mm apart, along x), at rest and without gravity, one
step of h after a force F = (0, F, 0) on its member at +x, or a drag beta (u - v) with v = 0
on its member at -x. Rigid-body mechanics (doc/theory.md, section 17): V = F h / M and
L = h (r x F), r = (+-1.5 mm, 0, 0) from the centre of mass; the dimer's moment about a
transverse axis is I = 2 (2/5 m r^2 + m d^2), d = 1.5 mm, so w = L / I about z (to the
frame's turn within the step, w h ~ 1e-8)."""
import math

import numpy as np
import pytest

import dem
from conftest import GLASS, write_case

R, D, RHO, H = 1e-3, 1.5e-3, 2500.0, 1e-6
M_SPHERE = RHO * 4.0 / 3.0 * math.pi * R**3
I_PERP = 2.0 * (0.4 * M_SPHERE * R**2 + M_SPHERE * D**2)


def dimer(folder):
    """The dimer alone, at rest, in free space; its members have ids 1 (at -x) and 2."""
    return write_case(folder, "dimer.nml", [
        f"&run dt = {H}, t_end = 1.0, gravity = 0, 0, 0 /",
        f"&output dir = '{folder}/out', interval = 1e-3 /", GLASS,
        "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /",
        "&clump_template name = 'dimer', material = 'glass', "
        "members = -1.5e-3, 0, 0, 1e-3,  1.5e-3, 0, 0, 1e-3 /",
        "&clump template = 'dimer', position = 0, 0, 0.05 /"])


@pytest.mark.parametrize("how", ["force", "drag"])
def test_a_member_turns_its_body(work, how):
    push = 1e-3                                     # N: F, or beta u
    with dem.Run(dimer(work)) as run:
        if how == "force":
            run.set_force_by_id([2], [[0.0, push, 0.0]])
            lever = D
        else:
            run.set_drag_by_id([1], [1e-2], [[0.0, push / 1e-2, 0.0]])
            lever = -D
        run.advance(H)
        b = run.bodies()
    assert b.id.tolist() == [1]
    assert b.mass[0] == pytest.approx(2.0 * M_SPHERE, rel=1e-12)
    assert np.allclose(b.v[0], [0.0, push * H / (2.0 * M_SPHERE), 0.0], rtol=1e-12,
                       atol=1e-15)
    w_z = lever * push * H / I_PERP
    assert b.w[0, 2] == pytest.approx(w_z, rel=1e-6)
    assert np.abs(b.w[0, :2]).max() <= 1e-6 * abs(w_z)
