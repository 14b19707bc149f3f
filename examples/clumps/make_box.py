#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the floor and the plug of the clumps example as binary STL files beside this
script (the box's side walls are `&wall_plane` groups of clumps.nml):

  floor.stl  the box's floor, a square of side 0.03 m at z = 0 facing up, around a square
             orifice of side 0.016 m at the centre: 4 trapezoids, 8 triangles.
  plug.stl   a square of side 0.022 m at z = 0 (two triangles, facing up) that closes the
             orifice while the box fills; the case moves it down to open it.

usage: python3 examples/clumps/make_box.py"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "cases"))
from make_geometry import write_stl  # noqa: E402  (the cases' STL writer)

HALF, ORIFICE, PLUG = 0.015, 0.008, 0.011        # half sides: box, orifice, plug


def square(a):
    """The corners of a square of half side a at z = 0, counter-clockwise from above."""
    return [(-a, -a, 0.0), (a, -a, 0.0), (a, a, 0.0), (-a, a, 0.0)]


def floor():
    out, hole = square(HALF), square(ORIFICE)
    tris = []
    for k in range(4):
        o0, o1, i0, i1 = out[k], out[(k + 1) % 4], hole[k], hole[(k + 1) % 4]
        tris += [(i0, o0, o1), (i0, o1, i1)]             # counter-clockwise: facing up
    return tris


def plug():
    c = square(PLUG)
    return [(c[0], c[1], c[2]), (c[0], c[2], c[3])]


if __name__ == "__main__":
    write_stl(os.path.join(HERE, "floor.stl"), floor(), "clumps example floor")
    write_stl(os.path.join(HERE, "plug.stl"), plug(), "clumps example plug")
