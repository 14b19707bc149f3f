# SPDX-License-Identifier: BSD-3-Clause
"""The chute's coarse-grained fields (fields.nml: &coarse_grain averaged over x and y) against
z: velocity, density, and the shear and normal stress beside those of the momentum balance of
a steady uniform flow, sigma_xz(z) = g_x int_z^inf rho dz', sigma_zz(z) = g_z int_z^inf rho dz'.
usage: fields_plot.py OUTPUT_DIR [--png PICTURE]   (default: fields.png beside this script)"""
import argparse
import os

import h5py
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

G = np.array([3.990, 0.0, -8.962])      # fields.nml's gravity [m/s^2]

ap = argparse.ArgumentParser(description="the chute's coarse-grained fields against z")
ap.add_argument("output", help="the output folder of fields.nml")
ap.add_argument("--png", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                              "fields.png"))
args = ap.parse_args()
out, picture = args.output, args.png
with h5py.File(os.path.join(out, "fields_chute.h5"), "r") as f:
    z = f["grid/z"][()]
    rho = f["fields/density"][:, 0, 0]
    vx = np.where(rho > 10.0, f["fields/velocity"][:, 0, 0, 0], np.nan)   # (no flow: none)
    s = f["fields/stress"][:, 0, 0, :]
dz = z[1] - z[0]
above = np.cumsum(rho[::-1])[::-1] * dz - 0.5 * rho * dz     # int_z^inf rho dz'
fig, ax = plt.subplots(1, 3, figsize=(10, 4), sharey=True)
ax[0].plot(vx, z * 1e3)
ax[0].set_xlabel("V_x [m/s]")
ax[0].set_ylabel("z [mm]")
ax[1].plot(rho, z * 1e3)
ax[1].set_xlabel("density [kg/m³]")
ax[2].plot(s[:, 2], z * 1e3, label="σ_xz")
ax[2].plot(-s[:, 8], z * 1e3, label="-σ_zz")
ax[2].plot(G[0] * above, z * 1e3, "k--", lw=0.8, label="momentum balance")
ax[2].plot(-G[2] * above, z * 1e3, "k--", lw=0.8)
ax[2].set_xlabel("stress [Pa]")
ax[2].legend()
fig.suptitle("chute: coarse-grained fields (Gaussian, w = 1 mm), averaged over 0.5 s")
fig.tight_layout()
fig.savefig(picture, dpi=100)
bulk = (z > 0.004) & (z < 0.015)
print("sigma_xz / -sigma_zz in the bulk:", np.mean(s[bulk, 2] / -s[bulk, 8]),
      "(tan of the incline:", G[0] / -G[2], ")")
