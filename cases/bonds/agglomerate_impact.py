# SPDX-License-Identifier: BSD-3-Clause
"""An agglomerate of 2000 bonded spheres hitting a rigid plane at increasing speed, for three
mean bond strengths: the damage ratio (broken bonds over the bonds made) and the largest
fragment's mass fraction against the energy group of Moreno-Atanasio and Ghadiri (2006),

    Delta = (m V^2 / 2) / U_b = (2/3) rho E V^2 / sigma^2,

a primary sphere's kinetic energy over the elastic energy a bond of mean radius R, length 2R
holds when it breaks in tension (U_b = sigma^2 A L0 / (2 E)). doc/results/bonds.md,
"Agglomerate impact against the literature".

The packing: examples/agglomerate/make_agglomerate.py (2000 spheres, radii uniform in
0.8 .. 1.2 mm, solid fraction 0.58 in a ball of 15.3 mm). Bonds: every pair within 0.1 mm
(&bond gap), E = 1e8 Pa, bond radius the smaller sphere's, Weibull strengths (modulus 5),
tensile = shear strength, bond damping 0.1 of critical, the Hertz-Mindlin contact law in
parallel (restitution 0.5, friction 0.3). The ball starts 0.1 mm above the plane; 2 ms
(the breakage stops after about 1.4 ms). Fragments: the connected sets of spheres over the
bonds left in the end checkpoint (/particles/bonds, doc/user/output.md).

    .venv/bin/python cases/bonds/agglomerate_impact.py [--dem build/dem] [--out DIR]
        [--jobs 2] [--png doc/figures/bonds_impact.png]

About 24 runs of 10 to 30 s on one core each. Writes DIR/impact.csv and DIR/impact.json."""
import argparse
import concurrent.futures
import csv
import glob
import json
import math
import os
import subprocess
import sys

import h5py
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "examples", "agglomerate"))
from make_agglomerate import packing, write  # noqa: E402

N, PHI, R, SEED = 2000, 0.58, 1.0e-3, 1
RHO, E, GAP = 2500.0, 1.0e8, 1.0e-4
STRENGTHS = (0.5e6, 1.0e6, 2.0e6)                  # mean bond strengths [Pa]
FACTORS = (0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0)  # V [m/s] = factor x sigma / 1 MPa
DT, T_END = 4.0e-7, 2.0e-3


def delta(v, sigma):
    """Moreno-Atanasio and Ghadiri's group for a parallel bond of mean length 2R."""
    return 2.0 / 3.0 * RHO * E * v**2 / sigma**2


CASE = """&run dt = {dt}, t_end = {t_end}, gravity = 0, 0, 0 /
&output dir = 'out', interval = 2e-5, snapshot_interval = 0 /
&material name = 'grain', density = {rho}, youngs_modulus = {e}, poisson_ratio = 0.3 /
&material name = 'rigid', rigid = .true. /
&pair materials = 'grain', 'grain', restitution = 0.5, friction = 0.3 /
&pair materials = 'grain', 'rigid', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.3 /
&particle_file file = 'ball.csv' /
&bond gap = {gap}, modulus = {e}, tensile_strength = {s}, shear_strength = {s},
      strength_distribution = 'weibull', strength_spread = 5, seed = 7, damping = 0.1 /
"""


def fragments(h5):
    """Mass fractions of the fragments (connected sets over the intact bonds), largest
    first, from a checkpoint."""
    with h5py.File(h5) as f:
        ids = f["particles/id"][()]
        r = f["particles/radius"][()]
        slots = f["particles/bonds"][()]
    index = np.full(ids.max() + 1, -1)
    index[ids] = np.arange(len(ids))
    partner = slots[:, 0::16].astype(np.int64)
    i, k = np.nonzero(partner > 0)
    j = index[partner[i, k]]
    n = len(ids)
    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
    count, label = connected_components(graph, directed=False)
    mass = np.bincount(label, weights=r**3)
    return np.sort(mass)[::-1] / mass.sum(), label


def run_one(dem, work, ball, sigma, factor):
    v = factor * sigma / 1.0e6
    name = f"s{sigma / 1e6:g}MPa_v{v:g}"
    d = os.path.join(work, name)
    os.makedirs(d, exist_ok=True)
    x, r = ball
    z0 = np.max(np.linalg.norm(x, axis=1) + r) + 1.0e-4
    with open(os.path.join(d, "ball.csv"), "w") as f:
        f.write("id,material,radius,x,y,z,vx,vy,vz\n")
        for k in range(len(r)):
            f.write(f"{k + 1},grain,{r[k]!r},{x[k, 0]!r},{x[k, 1]!r},{x[k, 2] + z0!r},"
                    f"0,0,{-v!r}\n")
    with open(os.path.join(d, "case.nml"), "w") as f:
        f.write(CASE.format(dt=DT, t_end=T_END, rho=RHO, e=E, gap=GAP, s=sigma))
    out = os.path.join(d, "out")
    if not os.path.exists(os.path.join(out, "final.csv")):
        p = subprocess.run([dem, "case.nml"], cwd=d, capture_output=True, text=True)
        if p.returncode != 0:
            raise RuntimeError(f"{name}: exit {p.returncode}\n{p.stdout[-2000:]}{p.stderr}")
    s = np.genfromtxt(os.path.join(out, "series.csv"), delimiter=",", names=True)
    late = s["time"] >= T_END - 0.5e-3 - 1e-12
    frac, _ = fragments(sorted(glob.glob(os.path.join(out, "checkpoints", "*.h5")))[-1])
    return {"strength": sigma, "speed": v, "delta": delta(v, sigma),
            "bonds": int(s["bonds"][0]), "broken": int(s["bonds_broken"][-1]),
            "damage": s["bonds_broken"][-1] / s["bonds"][0],
            "broken_last_0.5ms": int(s["bonds_broken"][-1] - s["bonds_broken"][late][0]),
            "largest": frac[0], "second": frac[1] if len(frac) > 1 else 0.0,
            "fragments_10": int(np.sum(frac * N >= 10 * (1.0 - 1e-9)))}


def plot(rows, fit, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(14, 4.3))
    for sigma, mark in zip(STRENGTHS, "os^"):
        sel = [q for q in rows if q["strength"] == sigma]
        lab = f"mean bond strength {sigma / 1e6:g} MPa"
        ax[0].loglog([q["speed"] for q in sel], [q["damage"] for q in sel], mark + "-",
                     label=lab)
        ax[1].loglog([q["delta"] for q in sel], [q["damage"] for q in sel], mark + "-",
                     label=lab)
        ax[2].semilogx([q["delta"] for q in sel], [q["largest"] for q in sel], mark + "-",
                       label=lab)
    xs = np.array([min(q["delta"] for q in rows), max(q["delta"] for q in rows)])
    ax[1].loglog(xs, fit["c"] * xs ** fit["n"], "k:",
                 label=f"D = {fit['c']:.3f} $\\Delta^{{{fit['n']:.2f}}}$ (least squares)")
    ax[0].set_xlabel("impact speed V [m/s]")
    for a in ax[1:]:
        a.set_xlabel(r"$\Delta = \frac{2}{3}\rho E V^2/\bar\sigma^2$ "
                     "(a sphere's kinetic energy / a bond's)")
    for a in ax:
        a.grid(alpha=0.3, which="both")
    ax[0].set_ylabel("damage ratio D (broken / initial bonds)")
    ax[1].set_ylabel("damage ratio D")
    ax[2].set_ylabel("largest fragment / agglomerate mass")
    ax[0].legend(fontsize=8)
    ax[1].legend(fontsize=8)
    ax[0].set_title("2000 bonded spheres on a rigid plane", fontsize=10)
    ax[1].set_title("against Moreno-Atanasio and Ghadiri's group", fontsize=10)
    ax[2].set_title("fragmentation above a critical $\\Delta$", fontsize=10)
    fig.tight_layout()
    fig.savefig(png, dpi=100)


def spread(rows, key):
    """The largest ratio max / min of the damage ratios of runs with the same `key`."""
    groups = {}
    for q in rows:
        groups.setdefault(round(q[key], 9), []).append(q["damage"])
    return max(max(d) / min(d) for d in groups.values() if len(d) > 1)


def main():
    a = argparse.ArgumentParser()
    a.add_argument("--dem", default=os.path.join(ROOT, "build", "dem"))
    a.add_argument("--out", default=os.path.join(ROOT, "output", "agglomerate_impact"))
    a.add_argument("--jobs", type=int, default=2)
    a.add_argument("--png", default=os.path.join(ROOT, "doc", "figures", "bonds_impact.png"))
    o = a.parse_args()
    os.makedirs(o.out, exist_ok=True)
    x, r, rb = packing(N, PHI, R, SEED)
    write(os.path.join(o.out, "packing.csv"), x, r)
    with concurrent.futures.ThreadPoolExecutor(o.jobs) as pool:
        jobs = [pool.submit(run_one, os.path.abspath(o.dem), o.out, (x, r), s, f)
                for s in STRENGTHS for f in FACTORS]
        rows = [j.result() for j in jobs]
    # D = c Delta^n, least squares on the logarithms, all runs
    n, lc = np.polyfit(np.log([q["delta"] for q in rows]), np.log([q["damage"] for q in rows]),
                       1)
    res = np.log([q["damage"] for q in rows]) - (lc + n * np.log([q["delta"] for q in rows]))
    fit = {"c": math.exp(lc), "n": n, "max_log_residual": float(np.abs(res).max())}
    collapse = {"same_delta": spread(rows, "delta"), "same_speed": spread(rows, "speed")}
    with open(os.path.join(o.out, "impact.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    summary = {"rows": rows, "fit": fit, "damage_max_over_min": collapse,
               "packing_ball_radius": rb, "spheres": N}
    with open(os.path.join(o.out, "impact.json"), "w") as f:
        json.dump(summary, f, indent=1)
    for q in rows:
        print(f"sigma {q['strength'] / 1e6:4g} MPa  V {q['speed']:5g} m/s  Delta "
              f"{q['delta']:7.3f}  damage {q['damage']:.4f}  largest {q['largest']:.4f}  "
              f"second {q['second']:.4f}  fragments>=10 {q['fragments_10']:3d}  broken in "
              f"the last 0.5 ms {q['broken_last_0.5ms']}")
    print(f"D = {fit['c']:.4f} Delta^{n:.3f}, largest residual of log D "
          f"{fit['max_log_residual']:.3f}; damage max / min at the same Delta "
          f"{collapse['same_delta']:.2f}, at the same speed {collapse['same_speed']:.2f}")
    plot(rows, fit, o.png)


if __name__ == "__main__":
    main()
