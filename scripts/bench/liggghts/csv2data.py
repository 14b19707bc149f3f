#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Convert a `dem` particle file (CSV) into a LIGGGHTS data file for atom_style granular.

The CSV has a header line naming the columns (any order; others are ignored):
    id,material,radius,x,y,z[,vx,vy,vz,wx,wy,wz]
as `dem` reads and writes it (io/dem_particle_file.f90; `final.csv` of a run). Velocities
default to zero when the columns are absent. `material` is a name or an integer index:

    M1 (any case) or 1           -> atom type 1 (density 2500)
    a name containing 'steel'    -> atom type 2 (density 7200)

Other names or indices stop with an error unless mapped with --map NAME=TYPE (e.g. --map 2=2
for a `final.csv` whose material 2 is steel).

The data file (LIGGGHTS atom_style granular):
    Atoms:      atom-ID atom-type diameter density x y z
    Velocities: atom-ID vx vy vz omegax omegay omegaz
with 2 atom types and box bounds x in [-0.06, 0.06], y in [-0.04, 0.04], z in [-0.095, 0.2],
a little larger than the Case 3 container (98 x 60 mm, floor at z = -0.0902431 m), or those
given with --box.

Usage: csv2data.py BED.csv OUT.data [--map KEY=TYPE ...] [--box XLO XHI YLO YHI ZLO ZHI]
Standard library and numpy only.
"""
import argparse
import csv
import sys

import numpy as np

DENSITY = {1: 2500.0, 2: 7200.0}            # kg/m^3 per atom type (M1, steel)
BOX = ((-0.06, 0.06), (-0.04, 0.04), (-0.095, 0.2))
REQUIRED = ("id", "material", "radius", "x", "y", "z")
OPTIONAL = ("vx", "vy", "vz", "wx", "wy", "wz")


def material_type(name, extra):
    """Atom type of a material name or index."""
    key = name.strip()
    if key in extra:
        return extra[key]
    if key.upper() == "M1" or key == "1":
        return 1
    if "steel" in key.lower():
        return 2
    raise ValueError(f"material '{key}' has no atom type (use --map {key}=TYPE)")


def read_csv(path, extra):
    with open(path, newline="") as f:
        rows = csv.reader(f)
        header = [h.strip() for h in next(rows)]
        missing = [c for c in REQUIRED if c not in header]
        if missing:
            sys.exit(f"{path}:1: the header lacks column(s) {', '.join(missing)}")
        col = {c: header.index(c) for c in REQUIRED + OPTIONAL if c in header}
        ids, types, vals = [], [], []
        numeric = ("radius", "x", "y", "z") + OPTIONAL
        for lineno, r in enumerate(rows, start=2):
            if not r or all(not s.strip() for s in r):
                continue
            try:
                ids.append(int(r[col["id"]]))
                types.append(material_type(r[col["material"]], extra))
                vals.append([float(r[col[c]]) if c in col else 0.0 for c in numeric])
            except (ValueError, IndexError) as e:
                sys.exit(f"{path}:{lineno}: {e}")
    if not ids:
        sys.exit(f"{path}: no particles after the header")
    return np.array(ids, dtype=np.int64), np.array(types, dtype=np.int64), np.array(vals)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("data")
    ap.add_argument("--map", action="append", default=[], metavar="KEY=TYPE",
                    help="extra material name/index -> atom type (1 or 2)")
    ap.add_argument("--box", nargs=6, type=float, default=[x for r in BOX for x in r],
                    metavar=("XLO", "XHI", "YLO", "YHI", "ZLO", "ZHI"),
                    help="the simulation box (default: the impact case's)")
    a = ap.parse_args()
    extra = {}
    for m in a.map:
        k, _, t = m.partition("=")
        if t not in ("1", "2"):
            sys.exit(f"--map {m}: TYPE must be 1 or 2")
        extra[k.strip()] = int(t)

    ids, types, v = read_csv(a.csv, extra)
    write_data(a.data, ids, types, v, a.csv, tuple(zip(a.box[::2], a.box[1::2])))


def write_data(path, ids, types, v, source, box=BOX):
    """The data file of the particles read by read_csv, in the box ((xlo, xhi), ...); stops
    with an error naming `source` for duplicate ids, radii <= 0 or particles outside the box."""
    if len(np.unique(ids)) != len(ids) or ids.min() <= 0:
        sys.exit(f"{source}: ids must be unique and > 0")
    radius, pos, vel, omega = v[:, 0], v[:, 1:4], v[:, 4:7], v[:, 7:10]
    if np.any(radius <= 0):
        sys.exit(f"{source}: radius must be > 0")
    for k, (lo, hi) in enumerate(box):
        out = (pos[:, k] - radius < lo) | (pos[:, k] + radius > hi)
        if out.any():
            sys.exit(f"{source}: {out.sum()} particle(s) outside the box: {'xyz'[k]} in "
                     f"[{lo}, {hi}]")
    dens = np.array([DENSITY[t] for t in types])

    with open(path, "w") as f:
        f.write(f"LIGGGHTS data file (atom_style granular) from {source} by csv2data.py\n\n")
        f.write(f"{len(ids)} atoms\n2 atom types\n\n")
        for k, (lo, hi) in enumerate(box):
            d = "xyz"[k]
            f.write(f"{lo:.9g} {hi:.9g} {d}lo {d}hi\n")
        f.write("\nAtoms\n\n")
        for i in range(len(ids)):
            f.write(f"{ids[i]} {types[i]} {2 * radius[i]:.17g} {dens[i]:.17g} "
                    f"{pos[i, 0]:.17g} {pos[i, 1]:.17g} {pos[i, 2]:.17g}\n")
        f.write("\nVelocities\n\n")
        for i in range(len(ids)):
            f.write(f"{ids[i]} {vel[i, 0]:.17g} {vel[i, 1]:.17g} {vel[i, 2]:.17g} "
                    f"{omega[i, 0]:.17g} {omega[i, 1]:.17g} {omega[i, 2]:.17g}\n")
    n1, n2 = int((types == 1).sum()), int((types == 2).sum())
    print(f"csv2data: {len(ids)} particles ({n1} of type 1, {n2} of type 2) -> {path}")


if __name__ == "__main__":
    main()
