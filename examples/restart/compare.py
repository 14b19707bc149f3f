#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The restart example's figure and verdict: the three runs of examples/restart/run-restart
(1 rank straight, 2 ranks straight, 2 ranks from the 1-rank run's checkpoint at 0.25 s) side
by side: their kinetic energy and particle count against time, and whether every output is
the same: the text files byte for byte, the snapshots dataset by dataset, bit for bit (the
bytes of an HDF5 file written on 2 ranks differ from those of one written on 1 in HDF5's own
layout of the file, not in what it holds).

usage: .venv/bin/python examples/restart/compare.py [--png FILE]   (from the repository root)"""
import argparse
import filecmp
import glob
import os

import h5py
import numpy as np

RUNS = {"output/restart_1_rank": "1 rank, straight through",
        "output/restart_2_ranks": "2 ranks, straight through",
        "output/restart": "2 ranks, from the checkpoint at 0.25 s"}


def h5_same(a, b):
    """Every dataset and attribute of HDF5 files a and b the same, bit for bit."""
    with h5py.File(a) as f, h5py.File(b) as g:
        names, other = [], []
        f.visit(names.append)
        g.visit(other.append)
        if sorted(names) != sorted(other):
            return False
        for n in names:
            if dict(f[n].attrs).keys() != dict(g[n].attrs).keys() or any(
                    np.asarray(f[n].attrs[k]).tobytes() != np.asarray(g[n].attrs[k]).tobytes()
                    for k in f[n].attrs):
                return False
            if isinstance(f[n], h5py.Dataset) and (
                    f[n].dtype != g[n].dtype or f[n].shape != g[n].shape or
                    np.asarray(f[n][()]).tobytes() != np.asarray(g[n][()]).tobytes()):
                return False
    return True


def same(a, b):
    return h5_same(a, b) if a.endswith(".h5") else filecmp.cmp(a, b, shallow=False)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--png")
    a = ap.parse_args()
    ref = "output/restart_1_rank"
    files = ["series.csv", "probes.csv", "final.csv", "snapshots.xmf"] + sorted(
        os.path.relpath(p, ref) for p in glob.glob(f"{ref}/snapshots/*.h5"))
    equal = all(same(f"{ref}/{f}", f"{run}/{f}") for run in RUNS for f in files)
    print(f"{len(files)} files of 3 runs: {'all the same' if equal else 'DIFFERENT'}")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
        for (run, label), style in zip(RUNS.items(), ["-", "--", ":"]):
            s = np.genfromtxt(f"{run}/series.csv", delimiter=",", names=True)
            ax[0].semilogy(s["time"], s["kinetic_translational"], style, lw=2, label=label)
            ax[1].plot(s["time"], s["particles"], style, lw=2, label=label)
        for x in ax:
            x.axvline(0.25, color="0.6", lw=0.8)
            x.set_xlabel("time [s]")
        ax[0].set_ylabel("kinetic energy [J]")
        ax[1].set_ylabel("particles")
        ax[1].legend(fontsize=8)
        fig.suptitle(f"examples/restart: three runs of one case; {len(files)} output files "
                     f"{'the same' if equal else 'DIFFERENT'}")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
