#!/usr/bin/env python3
"""Writes the walls of the hopper example as binary STL files beside this script:

  hopper.stl  a flat-bottomed cylinder (a 64-gon) of radius 0.018 m, 0.1 m high, open at the
              top, whose floor (z = 0) is an annulus around a circular orifice of radius
              0.006 m (diameter 12 mm) at the centre: 64 x 2 triangles of wall, 64 x 2 of floor.
  plug.stl    a square of side 0.02 m at z = 0 (two triangles, facing up) that closes the
              orifice while the hopper fills; the case moves it down to open it.

usage: python3 examples/hopper/make_hopper.py"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
R, H, R_O, SIDES = 0.018, 0.1, 0.006, 64


def normal(t):
    a = [t[1][k] - t[0][k] for k in range(3)]
    b = [t[2][k] - t[0][k] for k in range(3)]
    n = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    s = math.sqrt(sum(c * c for c in n)) or 1.0
    return [c / s for c in n]


def write_stl(path, tris, name):
    with open(path, "wb") as f:
        f.write(name.encode().ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<12fH", *normal(t), *t[0], *t[1], *t[2], 0))


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
