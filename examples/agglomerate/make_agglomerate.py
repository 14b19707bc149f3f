# SPDX-License-Identifier: BSD-3-Clause
"""A dense random packing of spheres in a ball, for a bonded agglomerate: radii uniform in
[0.8, 1.2] mean radii, centres drawn at random in the ball, then overlaps relaxed (each
overlapping pair pushed apart by its overlap, shared, the centres kept in the ball: the
force-biased scheme of Mościński, Bargieł, Rycerz and Jacobs 1989) until none exceeds
1e-6 of the mean radius; the radii then shrink by the largest overlap left, so no two
spheres overlap. Writes a particle file (doc/user/input.md, &particle_file), the ball's
centre at the origin, or with --lift its lowest point that far above z = 0 and every sphere
moving down at --speed.

    python3 make_agglomerate.py N PHI OUT.csv [--radius R] [--seed S] [--lift H --speed V]

The example's file: python3 make_agglomerate.py 2000 0.58 agglomerate.csv --lift 1e-4
--speed 4"""
import argparse

import numpy as np
from scipy.spatial import cKDTree


def packing(n, phi, radius, seed, tol=1e-6, max_iter=20000):
    """Centres (n, 3) and radii (n,) of n spheres of mean radius `radius` filling a ball
    about the origin to the solid fraction `phi`; returns them and the ball's radius."""
    rng = np.random.default_rng(seed)
    r = radius * rng.uniform(0.8, 1.2, n)
    rb = (np.sum(r**3) / phi) ** (1.0 / 3.0)
    u = rng.normal(size=(n, 3))
    x = u / np.linalg.norm(u, axis=1)[:, None] * (rb * rng.uniform(0, 1, n) ** (1 / 3))[:, None]
    for _ in range(max_iter):
        i, j = cKDTree(x).query_pairs(2.4 * radius, output_type="ndarray").T
        d = x[j] - x[i]
        dist = np.linalg.norm(d, axis=1)
        ov = r[i] + r[j] - dist
        keep = ov > 0
        i, j, d, dist, ov = i[keep], j[keep], d[keep], dist[keep], ov[keep]
        push = (0.5 * ov / dist)[:, None] * d
        np.add.at(x, i, -push)
        np.add.at(x, j, push)
        rad = np.linalg.norm(x, axis=1)
        out = rad > rb - r
        x[out] *= ((rb - r[out]) / rad[out])[:, None]
        if ov.size == 0 or ov.max() < tol * radius:
            break
    i, j = cKDTree(x).query_pairs(2.4 * radius, output_type="ndarray").T
    ratio = np.linalg.norm(x[j] - x[i], axis=1) / (r[i] + r[j])
    return x, r * min(1.0, ratio.min()), rb


def write(path, x, r, material="grain", lift=None, speed=0.0):
    """The particle file (10 digits); with `lift`, the ball raised so that its lowest point
    is `lift` above z = 0, every sphere moving at `speed` down."""
    x = x.copy()
    head = "id,material,radius,x,y,z"
    if lift is not None:
        x[:, 2] += lift - np.min(x[:, 2] - r)
        head += ",vx,vy,vz"
    with open(path, "w") as f:
        f.write(head + "\n")
        for k in range(len(r)):
            row = f"{k + 1},{material},{r[k]:.10g},{x[k, 0]:.10g},{x[k, 1]:.10g},{x[k, 2]:.10g}"
            f.write(row + (f",0,0,{-speed:g}\n" if lift is not None else "\n"))


if __name__ == "__main__":
    a = argparse.ArgumentParser()
    a.add_argument("n", type=int)
    a.add_argument("phi", type=float)
    a.add_argument("out")
    a.add_argument("--radius", type=float, default=1e-3)
    a.add_argument("--seed", type=int, default=1)
    a.add_argument("--lift", type=float, help="the gap under the ball [m]")
    a.add_argument("--speed", type=float, default=0.0, help="downward speed [m/s]")
    o = a.parse_args()
    x, r, rb = packing(o.n, o.phi, o.radius, o.seed)
    write(o.out, x, r, lift=o.lift, speed=o.speed)
    print(f"{o.n} spheres in a ball of radius {rb:.6g} m, solid fraction "
          f"{np.sum(r**3) / rb**3:.4f}")
