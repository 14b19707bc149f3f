#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the rough base of the chute example as a binary STL file beside this script:

  base.stl  a height field over x = -2D .. 12D, y = -2D .. 7D (D = 2 mm, one particle
            diameter) on a square grid of pitch D/2, each node at a random height between 0
            and 0.8 D (uniform; seed 1), two triangles per square, facing up. The heights
            repeat with the chute's period (x = 0 .. 10D, y = 0 .. 5D), and the field reaches
            two diameters beyond each periodic face, so that a particle near a face meets the
            base as it continues across that face (walls are not imaged: a wall that spans
            the period and its reach repeats by itself). A disordered base, like the fixed
            random spheres of Silbert et al. (2001): a regular one lets the first layers
            order and slide.

usage: .venv/bin/python examples/chute/make_base.py"""
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "cases"))
from make_geometry import write_stl  # noqa: E402  (the cases' STL writer)

D = 0.002
H = D / 2                       # grid pitch
NX, NY = 20, 10                 # nodes per period (10 D x 5 D)
BEYOND = 4                      # nodes beyond each face (2 D)


def main():
    rng = random.Random(1)
    height = [[rng.uniform(0.0, 0.8 * D) for _ in range(NY)] for _ in range(NX)]

    def node(i, j):
        return (i * H, j * H, height[i % NX][j % NY])

    tris = []
    for i in range(-BEYOND, NX + BEYOND):
        for j in range(-BEYOND, NY + BEYOND):
            a, b, c, d = node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)
            tris += [(a, b, c), (a, c, d)]          # counter-clockwise from above
    write_stl(os.path.join(HERE, "base.stl"), tris, "chute base")


if __name__ == "__main__":
    main()
