#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The hopper example's numbers and figure: the mass discharged (series.csv, `removed`,
times the mass of a sphere) against time, its slope once the flow is steady, and Beverloo's
correlation for a flat-bottomed silo with a circular orifice,
    W = C rho_b sqrt(g) (D - k d)^(5/2),
with rho_b the bulk density of the bed (measured: the solid fraction of the bed on the plug,
from the last snapshot before the plug moves, times the beads' density), D = 12 mm the
orifice, d = 2 mm the spheres, C = 0.58 and k = 1.5 (and the band the literature's constants
give, C 0.55 to 0.65, k 1.3 to 2.9).

usage: .venv/bin/python examples/hopper/flow_rate.py [RUN] [--png FILE]   (RUN: output/hopper)"""
import argparse
import glob
import math

import h5py
import numpy as np

RHO, G, D_O, D = 2500.0, 9.81, 0.012, 0.002          # hopper.nml
N0, OPEN, STEADY = 3500, 0.25, 0.45                 # spheres, plug moves, flow steady from
MASS = RHO * 4 / 3 * math.pi * (D / 2) ** 3


def solid_fraction(run):
    """Of the layer 3 to 12 mm above the floor within 14 mm of the axis."""
    for name in sorted(glob.glob(f"{run}/snapshots/*.h5")):
        with h5py.File(name) as h:
            if h["time"][()] > OPEN:
                break
            x, r = h["particles/position"][()], h["particles/radius"][()]
    lo, hi, rr = 0.003, 0.012, 0.014
    sel = np.hypot(x[:, 0], x[:, 1]) <= rr
    z, r = x[sel, 2], r[sel]
    a, b = np.maximum(z - r, lo), np.minimum(z + r, hi)
    vol = np.where(b > a, math.pi * (r ** 2 * (b - a) - ((b - z) ** 3 - (a - z) ** 3) / 3), 0)
    return vol.sum() / (math.pi * rr ** 2 * (hi - lo))


def beverloo(phi, c=0.58, k=1.5):
    return c * phi * RHO * math.sqrt(G) * (D_O - k * D) ** 2.5


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run", nargs="?", default="output/hopper")
    ap.add_argument("--png")
    a = ap.parse_args()
    s = np.genfromtxt(f"{a.run}/series.csv", delimiter=",", names=True)
    t, out = s["time"], s["removed"] * MASS
    steady = t >= STEADY
    w, w0 = np.polyfit(t[steady], out[steady], 1)
    phi = solid_fraction(a.run)
    wb, lo, hi = beverloo(phi), beverloo(phi, 0.55, 2.9), beverloo(phi, 0.65, 1.3)
    print(f"particles + removed = {N0} at every row: "
          f"{bool(np.all(s['particles'] + s['removed'] == N0))}")
    print(f"solid fraction of the bed {phi:.3f}, bulk density {phi * RHO:.0f} kg/m3")
    print(f"flow rate from t = {STEADY} s: {w * 1e3:.2f} g/s ({w / MASS:.0f} spheres/s); "
          f"Beverloo (C = 0.58, k = 1.5): {wb * 1e3:.2f} g/s, ratio {w / wb:.2f}; band "
          f"{lo * 1e3:.2f} to {hi * 1e3:.2f} g/s")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
        ax[0].plot(t, out * 1e3, label="discharged (series.csv removed x sphere mass)")
        ax[0].plot(t[steady], (w * t[steady] + w0) * 1e3, "k--",
                   label=f"fit from {STEADY} s: {w * 1e3:.1f} g/s")
        ax[0].axvline(OPEN, color="0.6", ls=":", label="the plug starts moving down")
        ax[0].set_xlabel("time [s]")
        ax[0].set_ylabel("mass discharged [g]")
        ax[0].legend(fontsize=8)
        mid = (t[1:] + t[:-1]) / 2
        rate = np.diff(out) / np.diff(t)
        k = 5
        smooth = np.convolve(rate, np.ones(k) / k, mode="valid")
        ax[1].plot(mid[k // 2:len(mid) - k // 2], smooth * 1e3, label="flow rate (5-row mean)")
        ax[1].axhline(wb * 1e3, color="k", ls="--", label=f"Beverloo: {wb * 1e3:.1f} g/s")
        ax[1].axhspan(lo * 1e3, hi * 1e3, color="0.85", label="Beverloo, constants' range")
        ax[1].axvline(OPEN, color="0.6", ls=":")
        ax[1].set_xlabel("time [s]")
        ax[1].set_ylabel("flow rate [g/s]")
        ax[1].legend(fontsize=8, loc="lower right")
        fig.suptitle("examples/hopper: 3500 spheres of 2 mm through an orifice of 12 mm")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
