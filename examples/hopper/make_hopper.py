#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the walls of the hopper example as binary STL files beside this script:

  hopper.stl  a flat-bottomed cylinder (a 64-gon) of radius 0.018 m, 0.1 m high, open at the
              top, whose floor (z = 0) is an annulus around a circular orifice of radius
              0.006 m (diameter 12 mm) at the centre: 64 x 2 triangles of wall, 64 x 2 of floor.
  plug.stl    a square of side 0.02 m at z = 0 (two triangles, facing up) that closes the
              orifice while the hopper fills; the case moves it down to open it.

usage: python3 examples/hopper/make_hopper.py"""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "cases"))
from make_geometry import write_stl  # noqa: E402  (the cases' STL writer)

R, H, R_O, SIDES = 0.018, 0.1, 0.006, 64


def ring(r, z, k):
    a = 2 * math.pi * k / SIDES
    return (r * math.cos(a), r * math.sin(a), z)


def hopper():
    tris = []
    for k in range(SIDES):
        # the wall, facing inwards
        p0, p1 = ring(R, 0.0, k), ring(R, 0.0, k + 1)
        q0, q1 = ring(R, H, k), ring(R, H, k + 1)
        tris += [(p0, q0, p1), (p1, q0, q1)]
        # the floor, facing up
        i0, i1 = ring(R_O, 0.0, k), ring(R_O, 0.0, k + 1)
        tris += [(i0, p0, p1), (i0, p1, i1)]
    return tris


def plug():
    a = 0.01
    c = [(-a, -a, 0.0), (a, -a, 0.0), (a, a, 0.0), (-a, a, 0.0)]
    return [(c[0], c[1], c[2]), (c[0], c[2], c[3])]


if __name__ == "__main__":
    write_stl(os.path.join(HERE, "hopper.stl"), hopper(), "hopper example")
    write_stl(os.path.join(HERE, "plug.stl"), plug(), "hopper example plug")
