#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The chute's steady flow from its snapshots (examples/chute/README.md): the mean velocity
along the slope in layers of height, the Bagnold profile fitted to it, and the mass flow
rate through a cross-section.

  v(z) = v_b + A (h^p - (h - z)^p)      z above the base's mid-height, h the flow's depth

is fitted for p = 3/2 (Bagnold: stress ~ (dv/dz)^2 and ~ depth, so dv/dz ~ (h - z)^(1/2)) and
with p free (by least squares over a grid of h and p, A and v_b linear); the layers are those
under the free surface's loose top (centres below h - 2 d). The flow rate is
Q = sum(m v_x) / L_x [kg/s], the mass that crosses a section x = const per second.

usage: flow_profile.py OUTPUT_DIR [--from T] [--period-x L] [--base Z] [--json] [--png FILE]"""
import argparse
import glob
import json
import os

import h5py
import numpy as np


def load(folder, t_from):
    snaps = []
    for path in sorted(glob.glob(os.path.join(folder, "snapshots", "snapshot_*.h5"))):
        with h5py.File(path, "r") as f:
            if float(f["time"][()]) < t_from:
                continue
            snaps.append((np.array(f["particles/position"]), np.array(f["particles/velocity"]),
                          np.array(f["particles/radius"])))
    return snaps


def fit(z, v, w, h_grid, p_grid):
    """Least squares of v_b + A (h^p - (h - z)^p) over h in h_grid, p in p_grid (weights w):
    (residual, h, p, A, v_b) of the best."""
    best = None
    for h in h_grid:
        if h <= z.max():
            continue
        for p in p_grid:
            m = np.c_[np.ones_like(z), h**p - (h - z)**p]
            coef, *_ = np.linalg.lstsq(m * np.sqrt(w)[:, None], v * np.sqrt(w), rcond=None)
            res = np.sqrt(np.sum(w * (m @ coef - v)**2) / np.sum(w))
            if best is None or res < best[0]:
                best = (res, h, p, coef[1], coef[0])
    return best


def analyse(folder, t_from, length_x, base, density, d):
    snaps = load(folder, t_from)
    if not snaps:
        raise SystemExit(f"no snapshots from t = {t_from} s in {folder}")
    zs, vs, ms = [], [], []
    flow = []
    for x, v, r in snaps:
        m = density * 4.0 / 3.0 * np.pi * r**3
        zs.append(x[:, 2] - base)
        vs.append(v[:, 0])
        ms.append(m)
        flow.append(np.sum(m * v[:, 0]) / length_x)
    z, vx, m = np.concatenate(zs), np.concatenate(vs), np.concatenate(ms)
    top = np.quantile(z, 0.99)                       # the free surface's loose top
    edges = np.arange(0.0, top + d / 2, d / 2)
    k = np.digitize(z, edges) - 1
    layers = []
    for b in range(len(edges) - 1):
        sel = k == b
        if sel.sum() < 10:
            continue
        layers.append((0.5 * (edges[b] + edges[b + 1]), np.sum(m[sel] * vx[sel]) / np.sum(m[sel]),
                       sel.sum()))
    zl, vl, nl = (np.array(c) for c in zip(*layers))
    body = (zl > 0.5 * d) & (zl < top - 2 * d)        # above the base's pockets, below the top
    h_grid = np.linspace(zl[body].max() + 0.1 * d, zl[body].max() + 4 * d, 80)
    bag = fit(zl[body], vl[body], nl[body], h_grid, [1.5])
    free = fit(zl[body], vl[body], nl[body], h_grid, np.linspace(0.8, 2.5, 69))
    lin = fit(zl[body], vl[body], nl[body], h_grid, [1.0])
    return dict(snapshots=len(snaps), flow_rate=float(np.mean(flow)),
                flow_rate_sd=float(np.std(flow)), top=float(top),
                layers=[[float(a), float(b), int(c)] for a, b, c in zip(zl, vl, nl)],
                bagnold=dict(rms=bag[0], h=bag[1], A=bag[3], v_b=bag[4]),
                free=dict(rms=free[0], h=free[1], p=free[2], A=free[3], v_b=free[4]),
                linear=dict(rms=lin[0], h=lin[1], A=lin[3], v_b=lin[4]),
                speed=float(np.sum(m * vx) / np.sum(m)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("output", nargs="?", default="output/chute", help="the run's folder")
    ap.add_argument("--from", dest="t_from", type=float, default=4.0,
                    help="first snapshot time averaged [s] (the flow from rest is steady by 4 s)")
    ap.add_argument("--period-x", type=float, default=0.02, help="period along x [m]")
    ap.add_argument("--base", type=float, default=0.0008, help="mean height of the base [m]")
    ap.add_argument("--density", type=float, default=2500.0, help="[kg/m^3]")
    ap.add_argument("--diameter", type=float, default=0.002, help="mean diameter [m]")
    ap.add_argument("--json", action="store_true", help="print the numbers as JSON")
    ap.add_argument("--png", help="plot the profile and the fits into this file")
    a = ap.parse_args()
    res = analyse(a.output, a.t_from, a.period_x, a.base, a.density, a.diameter)
    if a.json:
        print(json.dumps(res, indent=1))
        return
    print(f"{res['snapshots']} snapshots from t = {a.t_from} s")
    print(f"flow rate Q = {res['flow_rate']:.5g} kg/s (sd over snapshots {res['flow_rate_sd']:.2g})"
          f", mean speed {res['speed']:.4g} m/s, top of the flow {res['top'] * 1e3:.3g} mm")
    print("  z [mm]   v_x [m/s]   particles")
    for zl, vl, nl in res["layers"]:
        print(f"  {zl * 1e3:6.2f}   {vl:8.4f}   {nl:6d}")
    b, f, l = res["bagnold"], res["free"], res["linear"]
    print(f"Bagnold p = 3/2: h = {b['h'] * 1e3:.3g} mm, A = {b['A']:.4g}, v_b = {b['v_b']:.4g} m/s,"
          f" rms {b['rms']:.3g} m/s")
    print(f"best p = {f['p']:.3g}: h = {f['h'] * 1e3:.3g} mm, rms {f['rms']:.3g} m/s")
    print(f"linear (p = 1): rms {l['rms']:.3g} m/s")
    if a.png:
        plot(res, a.png)


def plot(res, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    z, v = (np.array(c) for c in list(zip(*res["layers"]))[:2])
    b, l = res["bagnold"], res["linear"]
    zz = np.linspace(0.0, b["h"], 200)
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.plot(v, z * 1e3, "o", ms=4, label="layers of d/2 (mean over the snapshots)")
    ax.plot(b["v_b"] + b["A"] * (b["h"]**1.5 - (b["h"] - zz)**1.5), zz * 1e3, "-",
            label=f"Bagnold, h = {b['h'] * 1e3:.1f} mm (rms {b['rms'] * 1e3:.1f} mm/s)")
    zl = np.linspace(0.0, l["h"], 200)
    ax.plot(l["v_b"] + l["A"] * zl, zl * 1e3, "--",
            label=f"linear (rms {l['rms'] * 1e3:.1f} mm/s)")
    ax.set_xlabel("mean velocity along the slope v_x [m/s]")
    ax.set_ylabel("height above the base z [mm]")
    ax.set_title(f"chute at 24 deg: Q = {res['flow_rate'] * 1e3:.0f} g/s per 10 mm width")
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
