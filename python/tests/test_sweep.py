# SPDX-License-Identifier: BSD-3-Clause
"""A friction sweep (dem.sweep): a sphere launched sliding along a floor without spin slows
under the friction mu m g until it rolls, at 5/7 of its speed whatever mu (the torque of
friction spins it up to v = w R), after t_r = 2 v0 / (7 mu g) and the distance
12 v0^2 / (49 mu g). The namelist editing it rests on is checked on its own."""
import os

import f90nml
import pytest

import dem
from conftest import GLASS, write_case

V0, R, G, T = 0.1, 1e-3, 9.81, 0.08


def sliding(folder):
    """A glass sphere resting on a rigid floor (its static overlap), launched at V0 along
    x; its friction with the floor is the sweep's key."""
    overlap = 3.5e-7
    return write_case(folder, "sliding.nml", [
        "&run dt = 1e-6, t_end = 1.0, gravity = 0, 0, -9.81 /",
        "&output interval = 1e-3 /", GLASS,
        "&material name = 'rigid', rigid = .true. /",
        "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /",
        "! the key the sweep changes: friction, in both pairs",
        "&pair materials = 'glass', 'rigid', restitution = 0.5, friction = 0.3 /",
        "&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, "
        "half_width = 0.05, divisions = 2 /",
        f"&particle id = 1, material = 'glass', radius = {R}, "
        f"position = 0, 0, {R - overlap}, velocity = {V0}, 0, 0 /"])


def test_friction_sweep(work):
    def measure(run):
        p = run.particles()
        return p.x[0, 0], p.v[0, 0], p.w[0, 1]
    frictions = [0.1, 0.2, 0.4]
    results = dem.sweep(sliding(work), "pair.friction", frictions, measure,
                        work_dir=os.path.join(work, "sweep"), until=T)
    assert [mu for mu, _ in results] == frictions
    for mu, (x, v, w) in results:
        t_r = 2.0 * V0 / (7.0 * mu * G)
        assert t_r < T
        assert abs(v - 5.0 / 7.0 * V0) < 0.01 * V0, (mu, v)        # rolls at 5/7 v0
        assert abs(w * R - v) < 0.01 * V0, (mu, w * R, v)           # without slip
        x_expected = 12.0 * V0**2 / (49.0 * mu * G) + 5.0 / 7.0 * V0 * (T - t_r)
        assert abs(x - x_expected) < 0.01 * x_expected, (mu, x, x_expected)
    # each run wrote its case and outputs in a folder of its own
    for k in range(len(frictions)):
        text = open(os.path.join(work, "sweep", str(k), "sliding.nml")).read()
        assert f"friction = {frictions[k]!r}" in text
        assert os.path.exists(os.path.join(work, "sweep", str(k), "output", "final.csv"))


def test_set_values():
    text = ("! a comment with &pair friction = 1 /\n"
            "&run dt = 1e-5, t_end = 1.0 /\n"
            "&pair materials = 'a', 'b', restitution = 0.5,\n"
            "      friction = 0.3 / ! after\n"
            "&pair materials = 'a/c', 'b', friction = 0.3, restitution = 0.5 /\n"
            "&wall_mesh file = 'x.stl' /\n")
    out = dem.set_values(text, {"pair.friction": 0.25, "run.t_end": 2.0,
                                "output.dir": "o/p", "run.gravity": (0, 0, -1)})
    assert out.count("friction = 0.25") == 2 and "friction = 0.3" not in out
    assert out.startswith("! a comment with &pair friction = 1 /\n")    # the comment
    assert "/ ! after\n" in out and "&wall_mesh file = 'x.stl' /\n" in out  # kept as is
    assert "t_end = 2.0" in out and "gravity = 0, 0, -1" in out
    assert "'a/c'" in out and "restitution = 0.5 /" in out
    # read back by f90nml: the values set, the others as they were, a group added
    nml = f90nml.reads(out)
    assert nml["run"]["dt"] == 1e-5 and nml["run"]["t_end"] == 2.0
    assert nml["run"]["gravity"] == [0, 0, -1]
    assert [g["friction"] for g in nml["pair"]] == [0.25, 0.25]
    assert [g["materials"] for g in nml["pair"]] == [["a", "b"], ["a/c", "b"]]
    assert [g["restitution"] for g in nml["pair"]] == [0.5, 0.5]
    assert nml["wall_mesh"]["file"] == "x.stl" and nml["output"]["dir"] == "o/p"
    assert list(dict.fromkeys(nml)) == ["run", "pair", "wall_mesh", "output"]  # added last


def test_set_values_refuses_what_it_cannot_read():
    with pytest.raises(ValueError, match="pair.friction|group.key"):
        dem.set_values("&run dt = 1 /\n", {"friction": 0.1})
    with pytest.raises(ValueError, match="&pair"):
        dem.set_values("&pair friction = 0.3\n", {"pair.friction": 0.1})


def test_write_case_makes_file_names_absolute(work):
    case = write_case(os.path.join(work, "a"), "c.nml",
                      ["&wall_mesh file = 'w.stl', material = 'rigid' /",
                       "&output interval = 1e-3 /"])
    path = dem.write_case(case, {}, os.path.join(work, "c.nml"), output_dir="out")
    text = open(path).read()
    assert f"file = '{os.path.join(work, 'a', 'w.stl')}'" in text
    assert f"dir = '{os.path.abspath('out')}'" in text and "overwrite = .true." in text
