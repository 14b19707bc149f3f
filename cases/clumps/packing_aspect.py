#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The poured packing fraction of rods against their aspect ratio. Run from the repository
root, under nice (one dem run at a time):

    nice -n 19 .venv/bin/python cases/clumps/packing_aspect.py [--dem build/dem]
        [--friction 0.5,0.1] [--spheres 1,2,3,4,5,7] [--seeds 1,2]

Each rod is a rigid clump of n spheres of radius r = 1 mm, their centres r apart along a line:
length L = (n + 1) r, aspect ratio L / (2 r) = (n + 1) / 2 (1, 1.5, 2, 2.5, 3, 4 for n = 1,
2, 3, 4, 5, 7); n = 1 is the sphere. For each friction coefficient (grain-grain and
grain-wall; restitution 0.5, E = 10 MPa, 2500 kg/m^3 as in examples/) and each n, rods
of 16 cm^3 of solid in all are poured by an inflow over 0.5 s (turned at random, thrown
down at 1 m/s from a region 28 mm square, 30 to 70 mm above the floor) into a box 36 mm
square and left to settle (until the kinetic energy is below 1e-7 J, or t = 1.2 s), once
for each seed of the inflow.
The packing fraction is that of the union of the members (overlaps counted once) in a box
clear of the walls and of the free surface: within 12 mm of the axis (6 mm, more than half
the longest rod, from the side walls), from 4 mm above the floor to 4 mm below the bed's top
(the median of 5 x 5 columns of the highest member's top), measured on a grid of 0.1 mm
cubes (examples/clumps/clumps_numbers.py, union_fraction). A rod's volume, from which the
number of rods follows, is n V_s - (n - 1) V_lens (neighbours overlap, the others at most
touch), checked against the mass `dem --check` prints.

Writes output/clumps_packing/mu<friction>/n<n>_s<seed>/ (the runs),
output/clumps_packing/packing.csv (a row a run) and doc/figures/clumps_packing_aspect.png
(the mean over the seeds, and each run)."""
import argparse
import csv
import math
import os
import re
import subprocess
import sys

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "examples", "clumps"))
from clumps_numbers import union_fraction  # noqa: E402  (the example's measurement)

R, RHO, SOLID = 1e-3, 2500.0, 16000e-9        # member radius, density, solid volume poured
HALF, INNER, MARGIN = 0.018, 0.012, 0.004     # box, measurement box half sides, margins
OUT = os.path.join(ROOT, "output", "clumps_packing")


def rod_volume(n):
    """The union of n spheres of radius R, centres R apart on a line (only neighbours
    overlap: a lens of two spheres at the distance d = R, pi (4R + d)(2R - d)^2 / 12)."""
    sphere = 4 / 3 * math.pi * R ** 3
    lens = math.pi * (4 * R + R) * (2 * R - R) ** 2 / 12
    return n * sphere - (n - 1) * lens


def case(n, friction, seed, rods):
    members = ",   ".join(f"{(k - (n - 1) / 2) * R:.6g}, 0, 0, {R:g}" for k in range(n))
    rate = rods / 0.5
    return f"""! a packing of rods of {n} spheres (cases/clumps/packing_aspect.py)
&run dt = 1e-5, t_end = 1.2, stop_kinetic_energy = 1e-7 /
&output interval = 0.01, snapshot_interval = 0, overwrite = .true. /
&material name = 'beads', density = {RHO}, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&material name = 'steel', density = 7800.0, youngs_modulus = 2e11, poisson_ratio = 0.3 /
&pair materials = 'beads', 'beads', restitution = 0.5, friction = {friction} /
&pair materials = 'beads', 'steel', restitution = 0.5, friction = {friction} /
&clump_template name = 'rod', material = 'beads', members = {members} /
&wall_plane material = 'steel', point = 0, 0, 0, normal = 0, 0, 1, half_width = {HALF} /
&wall_plane material = 'steel', point = {-HALF}, 0, 0.04, normal = 1, 0, 0, half_width = 0.04 /
&wall_plane material = 'steel', point = {HALF}, 0, 0.04, normal = -1, 0, 0, half_width = 0.04 /
&wall_plane material = 'steel', point = 0, {-HALF}, 0.04, normal = 0, 1, 0, half_width = 0.04 /
&wall_plane material = 'steel', point = 0, {HALF}, 0.04, normal = 0, -1, 0, half_width = 0.04 /
&insert template = 'rod', n = {rods}, rate = {rate:.6g}, start = 0, end = 0.5, seed = {seed},
        box_min = -0.014, -0.014, 0.03, box_max = 0.014, 0.014, 0.07, velocity = 0, 0, -1 /
"""


def check_mass(dem, path, n):
    r = subprocess.run([dem, "--check", path], capture_output=True, text=True, check=True)
    m = re.search(r"rod: .* mass\s+(\S+) kg", r.stdout)
    mass = float(m.group(1))
    exact = RHO * rod_volume(n)
    assert abs(mass - exact) < 1e-5 * exact, f"n = {n}: dem --check {mass}, exact {exact}"
    return mass


def measure(run):
    with open(os.path.join(run, "final.csv")) as f:
        rows = list(csv.DictReader(f))
    x = np.array([[float(r[k]) for k in ("x", "y", "z")] for r in rows])
    rad = np.array([float(r["radius"]) for r in rows])
    ids = np.array([int(r["id"]) for r in rows])
    body = np.array([int(r["body"]) for r in rows])
    order = np.argsort(ids)
    x, rad, body = x[order], rad[order], body[order]
    col = np.floor((x[:, :2] + HALF) / (2 * HALF / 5)).clip(0, 4).astype(int)
    key = col[:, 0] * 5 + col[:, 1]
    top = np.median([(x[key == k, 2] + rad[key == k]).max() for k in np.unique(key)])
    lo, hi = (-INNER, -INNER, MARGIN), (INNER, INNER, top - MARGIN)
    phi = union_fraction(x, rad, lo, hi)
    _, first, count = np.unique(body, return_index=True, return_counts=True)
    axis = x[first + count - 1] - x[first]
    long = count > 1
    cz = np.abs(axis[long, 2]) / np.linalg.norm(axis[long], axis=1)
    flat = float(np.mean(cz < 0.5)) if long.any() else float("nan")
    return phi, top, flat, len(first)


def one(dem, mu, n, seed):
    """One pour: its case written, checked and run; its row of the table."""
    run = os.path.join(OUT, f"mu{mu}", f"n{n}_s{seed}")
    os.makedirs(run, exist_ok=True)
    rods = int(round(SOLID / rod_volume(n)))
    path = os.path.join(run, "case.nml")
    with open(path, "w") as f:
        f.write(case(n, mu, seed, rods).replace("&output ", f"&output dir = '{run}', "))
    check_mass(dem, path, n)
    r = subprocess.run([dem, path], capture_output=True, text=True)
    last = r.stdout.strip().splitlines()[-1] if r.stdout.strip() else ""
    if r.returncode != 0:
        sys.exit(f"{path}: exit {r.returncode}: {last} {r.stderr[-500:]}")
    phi, top, flat, count = measure(run)
    if count != rods:
        sys.exit(f"{path}: {count} rods inserted of {rods}")
    settled = re.search(r"settled at t = (\S+) s", last)
    return {"friction": float(mu), "spheres": n, "aspect": (n + 1) / 2, "seed": seed,
            "rods": count, "phi": round(phi, 4), "top_mm": round(top * 1e3, 2),
            "flat": round(flat, 3),
            "settled_s": float(settled.group(1)) if settled else float("nan")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dem", default=os.path.join(ROOT, "build", "dem"))
    ap.add_argument("--friction", default="0.5,0.1")
    ap.add_argument("--spheres", default="1,2,3,4,5,7")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--plot-only", action="store_true", help="redraw from packing.csv")
    a = ap.parse_args()
    table = os.path.join(OUT, "packing.csv")
    rows = []
    if not a.plot_only:
        for mu in a.friction.split(","):
            for n in map(int, a.spheres.split(",")):
                for seed in map(int, a.seeds.split(",")):
                    rows.append(one(a.dem, mu, n, seed))
                    print(rows[-1], flush=True)
        with open(table, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    with open(table) as f:
        rows = list(csv.DictReader(f))
    text = summary(rows)
    print(text)
    with open(os.path.join(OUT, "summary.md"), "w") as f:
        f.write(text)
    plot(rows, os.path.join(ROOT, "doc", "figures", "clumps_packing_aspect.png"))


def summary(rows):
    """The table of doc/results/clumps.md: for each aspect ratio and friction, the mean
    packing fraction over the seeds with half their range, and the mean share lying flat."""
    mus = sorted({r["friction"] for r in rows}, key=float, reverse=True)
    head = ["aspect ratio", "spheres"] + [f"{k}, friction {float(m):g}" for m in mus
                                          for k in ("packing fraction", "lying flat")]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for n in sorted({int(r["spheres"]) for r in rows}):
        cells = [f"{(n + 1) / 2:g}", str(n)]
        for m in mus:
            sel = [r for r in rows if r["friction"] == m and int(r["spheres"]) == n]
            phi = np.array([float(r["phi"]) for r in sel])
            flat = np.array([float(r["flat"]) for r in sel])
            cells.append(f"{phi.mean():.4f} ± {(phi.max() - phi.min()) / 2:.4f}")
            cells.append("" if np.isnan(flat).all() else f"{flat.mean():.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot(rows, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for mu in sorted({r["friction"] for r in rows}, key=float, reverse=True):
        sel = [r for r in rows if r["friction"] == mu]
        a = np.array([float(r["aspect"]) for r in sel])
        phi = np.array([float(r["phi"]) for r in sel])
        xs = np.unique(a)
        line, = ax.plot(xs, [phi[a == x].mean() for x in xs], "o-",
                        label=f"dem: rods of overlapping spheres poured, friction {float(mu):g}")
        ax.plot(a, phi, ".", color=line.get_color(), alpha=0.5)
    ax.plot([1.0], [0.64], "ks", label="random close packing of spheres, 0.64")
    ax.plot([1.45], [0.721], "k^", label="densest random packing of spherocylinders,\n"
            "0.721 at aspect 1.45 (Imaz González et al. 2023)")
    ax.set_xlabel("aspect ratio L / d")
    ax.set_ylabel("packing fraction")
    ax.legend(fontsize=7, loc="lower left")
    ax.set_title("Poured rods: packing fraction against aspect ratio", fontsize=10)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


if __name__ == "__main__":
    main()
