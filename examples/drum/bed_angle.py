#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The drum example's numbers and figure: the bed's centre of mass (probes.csv, probe `com`)
turns about the drum's axis when the drum turns; the angle it turns by is the angle of the
bed's surface (a bed that fills a circular segment has its centre of mass on the segment's
axis of symmetry, which is normal to the surface), the dynamic angle of repose. Also the
power the drum draws, -angular_velocity x the torque of the beads on it about its axis.

usage: .venv/bin/python examples/drum/bed_angle.py [RUN] [--png FILE]   (RUN: output/drum)"""
import argparse
import math

import numpy as np

OMEGA, START = -2.0, 0.4          # drum.nml: angular_velocity, rotation_start


def angles(run):
    p = np.genfromtxt(f"{run}/probes.csv", delimiter=",", names=True)
    theta = np.degrees(np.arctan2(p["com_beads_x"], -p["com_beads_z"]))
    return p, theta


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run", nargs="?", default="output/drum")
    ap.add_argument("--png")
    a = ap.parse_args()
    p, theta = angles(a.run)
    t = p["time"]
    rest = t <= START
    turning = t >= START + 0.5 * (t[-1] - START)
    d0 = math.hypot(p["com_beads_x"][rest][-1], p["com_beads_z"][rest][-1])
    power = -OMEGA * p["drum_torque_axis"]
    print(f"at rest (t = {t[rest][-1]:.2f} s): centre of mass {d0 * 1e3:.1f} mm below the axis,"
          f" angle {theta[rest][-1]:.1f} deg")
    print(f"turning (t = {t[turning][0]:.2f} to {t[-1]:.2f} s): angle {theta[turning].mean():.1f}"
          f" +- {theta[turning].std():.1f} deg, centre of mass x = "
          f"{p['com_beads_x'][turning].mean() * 1e3:.1f} mm, power {power[turning].mean():.4f} W")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
        ax[0].plot(t, p["com_beads_x"] * 1e3, label="x (towards the rising side)")
        ax[0].plot(t, p["com_beads_z"] * 1e3, label="z")
        ax[0].axvline(START, color="0.6", ls=":", label="the drum starts turning")
        ax[0].set_xlabel("time [s]")
        ax[0].set_ylabel("centre of mass of the beads [mm]")
        ax[0].legend(fontsize=8)
        late = t >= 0.2                    # once the beads have fallen to the bottom
        ax[1].plot(t[late], theta[late], label="atan(x / -z): angle of the bed's surface")
        ax[1].axhline(theta[turning].mean(), color="k", ls="--",
                      label=f"mean over the second half: {theta[turning].mean():.1f} deg")
        ax[1].axvline(START, color="0.6", ls=":")
        ax[1].set_xlabel("time [s]")
        ax[1].set_ylabel("angle [deg]")
        ax[1].legend(fontsize=8)
        fig.suptitle("examples/drum: 1200 beads in a drum of radius 5 cm turning at 2 rad/s")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
