#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The pour example's numbers and figure: the particles against time beside the inflow's
schedule floor(rate t) up to rate x (end - start) = 3000, the force of the beads on the walls
against their weight, and the bed's solid fraction at the end.

usage: .venv/bin/python examples/pour/pour_numbers.py [RUN] [--png FILE]   (RUN: output/pour)"""
import argparse
import csv
import math

import numpy as np

RATE, START, END = 7500.0, 0.0, 0.4          # pour.nml, &insert
RHO, G, SIDE = 2500.0, 9.81, 0.06            # density, gravity, the box's side


def numbers(run):
    s = np.genfromtxt(f"{run}/series.csv", delimiter=",", names=True)
    p = np.genfromtxt(f"{run}/probes.csv", delimiter=",", names=True)
    with open(f"{run}/final.csv") as f:
        rows = list(csv.DictReader(f))
    r = np.array([float(x["radius"]) for x in rows])
    z = np.array([float(x["z"]) for x in rows])
    mass = RHO * 4 / 3 * math.pi * r ** 3
    # solid fraction of the layer 2 to 10 mm above the floor (clear of the floor's ordering and
    # of the heap's slopes): the volume of the spheres' parts inside it over its volume
    lo, hi = 0.002, 0.010
    h = np.clip(np.minimum(z + r, hi) - np.maximum(z - r, lo), 0, None)
    # a sphere's slice between two planes: pi (r^2 dz - ((b-z)^3 - (a-z)^3) / 3)
    a, b = np.maximum(z - r, lo), np.minimum(z + r, hi)
    vol = np.where(h > 0, math.pi * (r ** 2 * (b - a) - ((b - z) ** 3 - (a - z) ** 3) / 3), 0)
    return {"series": s, "probes": p, "n": len(rows), "mass": mass.sum(),
            "expected": math.floor(RATE * (END - START)),
            "fraction": vol.sum() / (SIDE * SIDE * (hi - lo)),
            "top": (z + r).max()}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run", nargs="?", default="output/pour")
    ap.add_argument("--png")
    a = ap.parse_args()
    n = numbers(a.run)
    s, p = n["series"], n["probes"]
    weight = n["mass"] * G
    print(f"particles at the end: {n['n']} (inflow: rate x duration = {n['expected']}), "
          f"removed {int(s['removed'][-1])}, in the box {int(p['box_beads'][-1])}")
    print(f"load on the walls at the end (-fz of the beads on them): {-p['walls_fz'][-1]:.5f} N"
          f" (the beads' weight {weight:.5f} N), on the floor {-p['floor_fz'][-1]:.5f} N")
    print(f"solid fraction 2 to 10 mm above the floor: {n['fraction']:.3f}; top of the heap "
          f"{n['top'] * 1e3:.1f} mm; kinetic energy at the end "
          f"{s['kinetic_translational'][-1]:.2e} J")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
        t = s["time"]
        ax[0].plot(t, s["particles"], label="particles (series.csv)")
        ax[0].plot(t, np.floor(RATE * np.clip(t, START, END)), "--",
                   label="floor(rate t), rate = 7500/s until 0.4 s")
        ax[0].set_xlabel("time [s]")
        ax[0].set_ylabel("particles")
        ax[0].legend(fontsize=8)
        ax[1].plot(p["time"], -p["walls_fz"], label="on all walls (probe walls, -fz)")
        ax[1].plot(p["time"], -p["floor_fz"], label="on the floor (probe floor, -fz)")
        ax[1].plot(t, RHO * 4 / 3 * math.pi * 3.469e-9 * s["particles"] * G, ":",
                   label="weight of the particles inserted (mean radius cubed)")
        ax[1].set_xlabel("time [s]")
        ax[1].set_ylabel("load of the beads on the walls [N]")
        ax[1].legend(fontsize=8)
        fig.suptitle("examples/pour: 3000 beads poured into a box 6 cm wide")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
