#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The impact example's numbers and figure: the ball's height and vertical velocity
(probes.csv, probe `ball`) beside free fall from 0.47 m, and the mechanical energy of all
particles (kinetic, translational and rotational, plus potential: series.csv), which the
impact dissipates.

usage: .venv/bin/python examples/impact/impact_numbers.py [RUN] [--png FILE]   (RUN: output/impact)"""
import argparse
import csv
import math

import numpy as np

Z0, R, RHO, G = 0.47, 5e-3, 7800.0, 9.81     # impact.nml: the ball's start, radius, density
M = RHO * 4 / 3 * math.pi * R ** 3


def numbers(run):
    p = np.genfromtxt(f"{run}/probes.csv", delimiter=",", names=True)
    s = np.genfromtxt(f"{run}/series.csv", delimiter=",", names=True)
    with open(f"{run}/final.csv") as f:
        beads = [r for r in csv.DictReader(f) if r["material"] == "beads"]
    e = s["kinetic_translational"] + s["kinetic_rotational"] + s["potential_gravity"]
    # the first row at which the ball is slower than free fall: it has touched the bed
    free = np.sqrt(2 * G * np.clip(Z0 - p["ball_z"], 0, None))
    hit = int(np.argmax(np.abs(p["ball_vz"]) < free - 1e-3))
    before = hit - 1
    return {"p": p, "s": s, "energy": e, "hit": hit, "before": before,
            "v_impact": -p["ball_vz"][before], "z_impact": p["ball_z"][before],
            "z_end": p["ball_z"][-1], "v_end": math.sqrt(p["ball_vx"][-1] ** 2 +
                                                        p["ball_vy"][-1] ** 2 +
                                                        p["ball_vz"][-1] ** 2),
            "bed_top": np.percentile([float(r["z"]) + float(r["radius"]) for r in beads
                                      if math.hypot(float(r["x"]), float(r["y"])) > 0.02],
                                     99)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run", nargs="?", default="output/impact")
    ap.add_argument("--png")
    a = ap.parse_args()
    n = numbers(a.run)
    p, s, e = n["p"], n["s"], n["energy"]
    b = n["before"]
    ke = 0.5 * M * n["v_impact"] ** 2
    print(f"last row before the impact: t = {p['time'][b]:.3f} s, ball at z = "
          f"{n['z_impact'] * 1e3:.1f} mm moving down at {n['v_impact']:.3f} m/s "
          f"(free fall: {math.sqrt(2 * G * (Z0 - n['z_impact'])):.3f} m/s), kinetic energy "
          f"{ke * 1e3:.2f} mJ")
    print(f"end (t = {p['time'][-1]:.2f} s): ball at z = {n['z_end'] * 1e3:.1f} mm (its bottom "
          f"{(n['z_end'] - R) * 1e3:.1f} mm above the floor; the bed's surface away from the "
          f"crater at {n['bed_top'] * 1e3:.1f} mm), speed {n['v_end']:.2e} m/s")
    print(f"mechanical energy of the particles: {e[b] * 1e3:.2f} mJ before the impact, "
          f"{e[-1] * 1e3:.2f} mJ at the end, at most {e[b:].max() * 1e3:.2f} mJ after it")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 3, figsize=(13, 3.8))
        t = p["time"]
        late = t >= 0.2
        ax[0].plot(t[late], p["ball_z"][late] * 1e3, label="ball (probe ball)")
        ax[0].plot(t[late], (Z0 - G * t[late] ** 2 / 2) * 1e3, ":", label="free fall")
        ax[0].axhline(n["bed_top"] * 1e3 + R * 1e3, color="0.6", ls="--",
                      label="touching the bed's surface")
        ax[0].set_ylim(0, 150)
        ax[0].set_xlabel("time [s]")
        ax[0].set_ylabel("height of the ball's centre [mm]")
        ax[0].legend(fontsize=8)
        ax[1].plot(t[late], p["ball_vz"][late], label="ball")
        ax[1].plot(t[late], -G * t[late], ":", label="free fall")
        ax[1].set_xlabel("time [s]")
        ax[1].set_ylabel("vertical velocity [m/s]")
        ax[1].legend(fontsize=8)
        ax[2].plot(s["time"], e * 1e3)
        ax[2].set_xlabel("time [s]")
        ax[2].set_ylabel("kinetic + potential energy [mJ]")
        fig.suptitle("examples/impact: a 10 mm ball (7800 kg/m3) dropped from 0.47 m into "
                     "4000 beads of 3 mm")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
