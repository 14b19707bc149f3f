#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The agglomerate example's numbers and picture. The bonds made are counted again from the
particle file (the pairs less than the &bond gap apart); the fragments are the connected
sets of spheres over the bonds left in the run's end checkpoint (/particles/bonds: a slot's
first value is the partner's id, 0 when empty; doc/user/output.md), their masses from the
radii; the broken bonds are the pairs made that the checkpoint no longer holds.

usage: .venv/bin/python examples/agglomerate/fragments.py [RUN] [--png FILE]   (RUN: output/agglomerate)"""
import argparse
import glob
import math
import os

import h5py
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

HERE = os.path.dirname(os.path.abspath(__file__))
GAP, RHO, E, SIGMA = 1e-4, 2500.0, 1e8, 1e6        # agglomerate.nml


def start(path=os.path.join(HERE, "agglomerate.csv")):
    a = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding=None)
    x = np.c_[a["x"], a["y"], a["z"]]
    return a["id"], x, a["radius"], -a["vz"][0]


def pairs_within_gap(x, r, gap):
    """The pairs (index arrays) whose surfaces are at most `gap` apart (&bond's rule)."""
    i, j = cKDTree(x).query_pairs(2 * r.max() + gap, output_type="ndarray").T
    d = np.linalg.norm(x[j] - x[i], axis=1)
    keep = d <= (r[i] + r[j]) * (1 + 1e-9) + gap
    return i[keep], j[keep]


def numbers(run):
    ids, x0, r0, speed = start()
    bi, bj = pairs_within_gap(x0, r0, GAP)
    s = np.genfromtxt(os.path.join(run, "series.csv"), delimiter=",", names=True)
    with h5py.File(sorted(glob.glob(os.path.join(run, "checkpoints", "*.h5")))[-1]) as f:
        pid = f["particles/id"][()]
        x = f["particles/position"][()]
        v = f["particles/velocity"][()]
        r = f["particles/radius"][()]
        slots = f["particles/bonds"][()]
    order = np.argsort(pid)
    pid, x, v, r, slots = pid[order], x[order], v[order], r[order], slots[order]
    partner = slots[:, 0::16].astype(np.int64)
    i, k = np.nonzero(partner > 0)
    j = np.searchsorted(pid, partner[i, k])
    n = len(pid)
    count, label = connected_components(coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n)),
                                        directed=False)
    mass = RHO * 4 / 3 * math.pi * r**3
    frag = np.bincount(label, weights=mass)
    rank = np.argsort(frag)[::-1]                     # fragment labels, largest first
    intact = set(zip(np.minimum(i, j), np.maximum(i, j)))
    broken = np.array([(a, b) not in intact for a, b in zip(bi, bj)])
    mid = 0.5 * (x0[bi] + x0[bj])
    centre = np.average(x0, axis=0, weights=r0**3)
    m0 = RHO * 4 / 3 * math.pi * r0**3
    return {"series": s, "speed": speed, "bonds_made": len(bi), "bonds": int(s["bonds"][0]),
            "broken_series": int(s["bonds_broken"][-1]), "broken_checkpoint": int(broken.sum()),
            "intact_slots": len(i), "damage": broken.sum() / len(bi),
            "delta": 2 / 3 * RHO * E * speed**2 / SIGMA**2,
            "fragments": frag[rank] / frag.sum(), "label": label, "rank": rank,
            "x0": x0, "x": x, "r": r, "mass0": m0.sum(), "mass": mass.sum(),
            "vz_centre": np.sum(mass * v[:, 2]) / mass.sum(),
            "kinetic0": 0.5 * m0.sum() * speed**2,
            "broken_height": np.mean(mid[broken, 2] - centre[2]) / np.max(r0 + np.linalg.norm(
                x0 - centre, axis=1)),
            "centre0": centre}


def picture(v, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle
    big = 8                                   # the largest fragments get a colour each
    colour_of = {lab: plt.cm.tab10(n) for n, lab in enumerate(v["rank"][:big])}
    grey = (0.75, 0.75, 0.75, 1.0)
    colours = [colour_of.get(lab, grey) for lab in v["label"]]
    fig, ax = plt.subplots(1, 3, figsize=(13, 4.8))
    views = ((ax[0], v["x0"], 2, -v["x0"][:, 1], "at the start, from the side: where each "
              "fragment\ncomes from (x, z)"),
             (ax[1], v["x"], 2, -v["x"][:, 1], "at t = 2 ms, from the side (x, z)"),
             (ax[2], v["x"], 1, v["x"][:, 2], "at t = 2 ms, from above (x, y)"))
    for a, pos, up, depth, title in views:
        back = np.argsort(depth)               # the farthest drawn first
        a.add_collection(PatchCollection([Circle((pos[k, 0], pos[k, up]), v["r"][k])
                                          for k in back],
                                         facecolors=[colours[k] for k in back],
                                         edgecolors="k", linewidths=0.2))
        a.set_aspect("equal")
        a.set_xlim(-0.025, 0.025)
        a.set_ylim(-0.002, 0.034) if up == 2 else a.set_ylim(-0.025, 0.025)
        if up == 2:
            a.axhline(0, color="k", lw=2)
        a.set_xlabel("x [m]")
        a.set_ylabel("z [m]" if up == 2 else "y [m]")
        a.set_title(title, fontsize=10)
    f = v["fragments"]
    text = ", ".join(f"{100 * q:.1f}" for q in f[:5])
    fig.suptitle(f"2000 bonded spheres on a rigid plane at {v['speed']:g} m/s: "
                 f"{100 * v['damage']:.1f} % of the bonds broken,\nthe largest fragments "
                 f"{text} % of the mass (coloured; the rest grey)", fontsize=10)
    fig.tight_layout()
    fig.savefig(png, dpi=100)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run", nargs="?", default="output/agglomerate")
    ap.add_argument("--png", default=os.path.join(HERE, "fragments.png"))
    o = ap.parse_args()
    v = numbers(o.run)
    s, f = v["series"], v["fragments"]
    print(f"bonds made {v['bonds']} (pairs within the gap in the particle file: "
          f"{v['bonds_made']})")
    print(f"broken {v['broken_series']} (series.csv), {v['broken_checkpoint']} (made, not in "
          f"the end checkpoint): damage ratio {v['damage']:.4f} at Delta = {v['delta']:.2f}")
    print(f"fragments: {len(f)}, of at least 10 spheres {np.sum(f * 2000 >= 10)}, the largest "
          + ", ".join(f"{q:.4f}" for q in f[:5]) + " of the mass")
    e = s["kinetic_translational"] + s["kinetic_rotational"] + s["bond_energy"]
    print(f"kinetic energy at the start {v['kinetic0'] * 1e3:.3f} mJ; kinetic + bond energy at "
          f"most {e.max() * 1e3:.3f} mJ, at the end {e[-1] * 1e3:.3f} mJ")
    print(f"centre of mass's vertical velocity at the end {v['vz_centre']:.4f} m/s (-"
          f"{v['speed']:g} before); broken bonds' mean height {v['broken_height']:+.3f} ball "
          "radii from the centre")
    picture(v, o.png)


if __name__ == "__main__":
    main()
