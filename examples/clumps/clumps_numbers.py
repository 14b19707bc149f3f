#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The clumps example's numbers and figure: the rods inserted by the inflow, conservation
(particles + removed = 3 x 1000 members once the inflow is done, and `removed` a multiple of 3:
a rod leaves whole), the settled bed before the plug moves (its packing fraction: the volume
of the union of the members inside a box clear of the walls and of the surface, over the
box's; its top; the fraction of rods lying within 30 degrees of the horizontal, 0.5 for
rods turned at random), and the discharge rate (the slope of `removed` / 3) against
Beverloo's correlation for a flat-bottomed silo,
    W = C rho_b sqrt(g) (D - k d)^(5/2),  C = 0.58, k = 1.5,
with D the orifice's side (the hydraulic diameter 4 A / P of a square), d the diameter of
the sphere of a rod's volume and rho_b the bed's bulk density (and the band of the
literature's constants, C 0.55 to 0.65, k 1.3 to 2.9).
The figure: the members of the rods (drawn to scale), coloured by rod, at rest before the plug moves and
during the discharge (the rods whose centre is within 1.5 mm of y = 0, seen along y), and the rods discharged against
time.

usage: .venv/bin/python examples/clumps/clumps_numbers.py [RUN] [--png FILE]   (RUN: output/clumps)"""
import argparse
import glob
import math

import h5py
import numpy as np

RATE, END, N_RODS, MEMBERS = 5000.0, 0.2, 1000, 3      # clumps.nml, &insert
RHO, G, SIDE, HALF = 2500.0, 9.81, 0.016, 0.015        # density, gravity, orifice, box
MASS = 2.48709e-05                # a rod's mass (dem --check): its volume 9.948e-9 m^3
D_V = (6 * MASS / RHO / math.pi) ** (1 / 3)            # equal-volume sphere: 2.67 mm
OPEN, STEADY = 0.4, (0.45, 0.7)   # the plug moves; the window of the discharge rate
BOX_LO, BOX_HI = (-0.010, -0.010, 0.003), (0.010, 0.010, 0.013)    # packing measured in


def union_fraction(x, r, lo, hi, h=1e-4):
    """The volume fraction of the box lo..hi that the union of the spheres (centres x,
    radii r) fills: the share of the centres of a grid of cubes of side h inside a sphere."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    n = np.round((hi - lo) / h).astype(int)
    axes = [lo[k] + (np.arange(n[k]) + 0.5) * h for k in range(3)]
    full = np.zeros(n, bool)
    for c, rad in zip(x, r):
        a = np.clip(np.floor((c - rad - lo) / h).astype(int), 0, n)
        b = np.clip(np.ceil((c + rad - lo) / h).astype(int), 0, n)
        if np.any(b <= a):
            continue
        dx, dy, dz = (axes[k][a[k]:b[k]] - c[k] for k in range(3))
        inside = dx[:, None, None] ** 2 + dy[None, :, None] ** 2 + dz[None, None, :] ** 2
        full[a[0]:b[0], a[1]:b[1], a[2]:b[2]] |= inside <= rad * rad
    return full.mean()


def snapshot(run, at):
    """The last snapshot at or before time `at`: the members' positions, radii and bodies,
    in the order of their ids, and its time."""
    out = None
    for name in sorted(glob.glob(f"{run}/snapshots/*.h5")):
        with h5py.File(name) as h:
            if h["time"][()] > at + 1e-9:
                break
            p = h["particles"]
            order = np.argsort(p["id"][()])
            out = (p["position"][()][order], p["radius"][()][order], p["body"][()][order],
                   h["time"][()])
    return out


def rod_axes(x, body):
    """Each rod's axis: the unit vector from its first member to its last (ids in order)."""
    _, first, count = np.unique(body, return_index=True, return_counts=True)
    axis = x[first + count - 1] - x[first]
    return axis / np.linalg.norm(axis, axis=1)[:, None]


def bed(run):
    x, r, body, t = snapshot(run, OPEN)
    phi = union_fraction(x, r, BOX_LO, BOX_HI)
    axes = rod_axes(x, body)
    flat = np.mean(np.abs(axes[:, 2]) < math.sin(math.radians(30)))
    # the top: the median over 5 x 5 columns of the box of the highest member's top
    col = np.floor((x[:, :2] + HALF) / (2 * HALF / 5)).clip(0, 4).astype(int)
    key = col[:, 0] * 5 + col[:, 1]
    top = np.median([(x[key == k, 2] + r[key == k]).max() for k in np.unique(key)])
    return {"phi": phi, "flat": flat, "top": top, "rods": len(axes), "time": t}


def beverloo(phi, c=0.58, k=1.5):
    return c * phi * RHO * math.sqrt(G) * (SIDE - k * D_V) ** 2.5


def numbers(run):
    s = np.genfromtxt(f"{run}/series.csv", delimiter=",", names=True)
    t, n, out = s["time"], s["particles"], s["removed"]
    done = t >= END + 0.01
    win = (t >= STEADY[0]) & (t <= STEADY[1])
    w = np.polyfit(t[win], out[win] / MEMBERS, 1)[0]
    return {"series": s, "bed": bed(run), "rate": w,
            "conserved": bool(np.all(n[done] + out[done] == N_RODS * MEMBERS)),
            "whole": bool(np.all(out % MEMBERS == 0)),
            "closed": bool(np.all(out[t <= OPEN] == 0)),
            "lag": float((np.floor(RATE * np.minimum(t, END)) * MEMBERS - n)[~done].max())}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run", nargs="?", default="output/clumps")
    ap.add_argument("--png")
    a = ap.parse_args()
    v = numbers(a.run)
    b, s = v["bed"], v["series"]
    w = v["rate"] * MASS
    wb, lo, hi = beverloo(b["phi"]), beverloo(b["phi"], 0.55, 2.9), beverloo(b["phi"], 0.65, 1.3)
    print(f"rods inserted: {b['rods']} ({int(s['particles'][s['time'] <= OPEN][-1])} members);"
          f" inflow at most {v['lag']:.0f} members behind floor(rate t) x 3")
    print(f"particles + removed = {N_RODS * MEMBERS} once the inflow is done: {v['conserved']};"
          f" removed a multiple of 3 at every row: {v['whole']}; none before {OPEN} s: "
          f"{v['closed']}")
    print(f"bed at t = {b['time']:.2f} s: packing fraction {b['phi']:.3f} (bulk density "
          f"{b['phi'] * RHO:.0f} kg/m3), top {b['top'] * 1e3:.1f} mm, lying flat (within 30 deg)"
          f" {b['flat']:.3f} (0.5 at random)")
    print(f"discharge rate {STEADY[0]} to {STEADY[1]} s: {v['rate']:.0f} rods/s = "
          f"{w * 1e3:.1f} g/s; Beverloo (C 0.58, k 1.5, d = {D_V * 1e3:.2f} mm): "
          f"{wb * 1e3:.1f} g/s, ratio {w / wb:.2f}; band {lo * 1e3:.1f} to {hi * 1e3:.1f} g/s")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.collections import PatchCollection
        from matplotlib.patches import Circle
        fig, ax = plt.subplots(1, 3, figsize=(13, 4.2),
                               gridspec_kw={"width_ratios": [1, 1, 1.3]})
        for k, at in enumerate((OPEN, 0.6)):
            x, r, body, tt = snapshot(a.run, at)
            _, inv = np.unique(body, return_inverse=True)     # the rods whose centre
            ybar = np.bincount(inv, x[:, 1]) / np.bincount(inv)  # is within 1.5 mm of y = 0
            sl = np.abs(ybar[inv]) < 0.0015
            order = np.argsort(x[sl, 1])                 # the nearer drawn last
            colours = plt.get_cmap("tab20")((body[sl][order] * 0.6180339887) % 1.0)
            ax[k].add_collection(PatchCollection(
                [Circle((cx * 1e3, cz * 1e3), cr * 1e3) for cx, cz, cr in
                 zip(x[sl, 0][order], x[sl, 2][order], r[sl][order])],
                facecolors=colours, edgecolors="k", linewidths=0.2))
            ax[k].plot([-15, -8], [0, 0], "k", [8, 15], [0, 0], "k", lw=2)
            ax[k].plot([-15, -15], [0, 30], "k", [15, 15], [0, 30], "k", lw=1)
            ax[k].set_xlim(-16, 16)
            ax[k].set_ylim(-6, 30)
            ax[k].set_aspect("equal")
            ax[k].set_xlabel("x [mm]")
            ax[k].set_ylabel("z [mm]")
            ax[k].set_title(f"t = {tt:.1f} s: the rods centred within 1.5 mm of y = 0",
                            fontsize=8)
        t = s["time"]
        ax[2].plot(t, s["removed"] / MEMBERS, label="rods discharged (removed / 3)")
        ax[2].plot(t, s["particles"] / MEMBERS, label="rods in the run (particles / 3)")
        win = (t >= STEADY[0]) & (t <= STEADY[1])
        fit = np.polyfit(t[win], s["removed"][win] / MEMBERS, 1)
        ax[2].plot(t[win], np.polyval(fit, t[win]), "k--",
                   label=f"fit {STEADY[0]} to {STEADY[1]} s: {fit[0]:.0f} rods/s")
        ax[2].axvline(OPEN, color="0.6", ls=":", label="the plug starts moving down")
        ax[2].set_xlabel("time [s]")
        ax[2].set_ylabel("rods")
        ax[2].legend(fontsize=8)
        fig.suptitle("examples/clumps: 1000 rods of three spheres poured into a box and "
                     "discharged through a 16 mm orifice")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
