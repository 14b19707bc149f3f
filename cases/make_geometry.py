#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the walls of the benchmark paper's three cases (Dosta et al. 2024) as binary STL
files in the case folders silo/, drum/ and impact/, from the dimensions of the published
wall files (inner surfaces only: a particle never reaches the outer skin of those 2 mm thick
shells). z is vertical.

  silo/silo_small.stl, silo_large.stl  a 100-gon cylinder of inner radius 0.1 m, 0.3 m high,
                                   on a 45-degree cone (inner surface r = z + c) down to the
                                   orifice, r_o = 0.02 or 0.03 m at z_o; open at the top and at
                                   the orifice. The cylinder is one ring of 200 triangles, the
                                   cone 20 rings of 200 (4000 triangles, as fine as the paper's
                                   3977 and 3549), vertices on the surfaces.
  drum/drum.stl                    a 100-gon cylinder of radius 0.1 m about the y axis, depth
                                   0.06 m (y = -0.03 .. 0.03), closed by two 100-gon end discs
                                   (fans of 98 triangles): 396 triangles.
  drum/drum_slice.stl              the same drum 0.015 m deep (y = -0.0075 .. 0.0075): a quarter
                                   of it, for the reduced drum run on a workstation.
  drum/<drum>_shell.stl, <drum>_ends.stl  the cylinder and the two end discs of drum and
                                   drum_slice apart (the drums with frictionless end discs).
  impact/impact_box.stl            the open-top box x = -0.049 .. 0.049, y = -0.03 .. 0.03,
                                   floor at z = -0.0902431, rim at z = 0.107757: 10 triangles.

Every triangle's normal (the order of its corners) points into the space of the particles.
Binary STL stores single precision: corners are within 4e-9 m of these dimensions.
Run it again after editing; the .stl files it writes are what the cases read."""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
SIDES = 100

SILOS = {  # orifice radius and plane z_o, c of the cone r = z + c, top of the cylinder
    "small": dict(r_o=0.02, z_o=-0.0593008, c=0.0793008, top=0.320699),
    "large": dict(r_o=0.03, z_o=-0.0554222, c=0.0854222, top=0.314578),
}
DRUM = dict(radius=0.1, half_depth=0.03)
DRUM_SLICE = dict(radius=0.1, half_depth=0.0075)
BOX = dict(x=0.049, y=0.030, floor=-0.0902431, rim=0.107757)


def ring(r, z):
    return [(r * math.cos(2 * math.pi * k / SIDES), r * math.sin(2 * math.pi * k / SIDES), z)
            for k in range(SIDES)]


def band(lower, upper):
    """Triangles between two rings of the same number of points, normals towards the axis."""
    tris = []
    for k in range(SIDES):
        a, b = lower[k], lower[(k + 1) % SIDES]
        c, d = upper[k], upper[(k + 1) % SIDES]
        tris += [(a, c, b), (b, c, d)]
    return tris


def silo(r_o, z_o, c, top, cone_rings=20):
    z_j = 0.1 - c                                    # where the cone meets the cylinder
    rings = [ring(z + c, z) for z in (z_o + (z_j - z_o) * k / cone_rings
                                      for k in range(cone_rings + 1))]
    tris = []
    for lower, upper in zip(rings, rings[1:]):
        tris += band(lower, upper)
    return tris + band(rings[-1], ring(0.1, top))


def drum(radius, half_depth, shell=True, ends=True):
    def about_y(points):                             # the z axis turned onto the y axis
        return [(x, z, y) for x, y, z in points]
    front, back = about_y(ring(radius, -half_depth)), about_y(ring(radius, half_depth))
    tris = [(a, c, b) for a, b, c in band(front, back)] if shell else []   # the turn mirrors
    for k in range(1, SIDES - 1 if ends else 1):
        tris.append((front[0], front[k + 1], front[k]))     # disc at y = -d, normal +y
        tris.append((back[0], back[k], back[k + 1]))        # disc at y = +d, normal -y
    return tris


def box(x, y, floor, rim):
    corners = lambda z: [(-x, -y, z), (x, -y, z), (x, y, z), (-x, y, z)]
    lo, hi = corners(floor), corners(rim)
    tris = [(lo[0], lo[1], lo[2]), (lo[0], lo[2], lo[3])]     # floor, normal +z
    for k in range(4):
        a, b, c, d = lo[k], lo[(k + 1) % 4], hi[(k + 1) % 4], hi[k]
        tris += [(a, d, b), (b, d, c)]                          # sides, normals inwards
    return tris


def normal(t):
    u = [t[1][i] - t[0][i] for i in range(3)]
    v = [t[2][i] - t[0][i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    length = math.sqrt(sum(c * c for c in n))
    return [c / length for c in n]


def write_stl(path, tris, name):
    with open(path, "wb") as f:
        f.write(name.encode().ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<12fH", *normal(t), *t[0], *t[1], *t[2], 0))


def main():
    for name, dims in SILOS.items():
        write_stl(os.path.join(HERE, "silo", f"silo_{name}.stl"), silo(**dims),
                  f"silo {name} orifice")
    for name, dims in (("drum", DRUM), ("drum_slice", DRUM_SLICE)):
        label, out = name.replace("_", " "), os.path.join(HERE, "drum")
        write_stl(os.path.join(out, f"{name}.stl"), drum(**dims), label)
        write_stl(os.path.join(out, f"{name}_shell.stl"), drum(**dims, ends=False),
                  label + " shell")
        write_stl(os.path.join(out, f"{name}_ends.stl"), drum(**dims, shell=False),
                  label + " end discs")
    write_stl(os.path.join(HERE, "impact", "impact_box.stl"), box(**BOX), "impact box")


if __name__ == "__main__":
    main()
