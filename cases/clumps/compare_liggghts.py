#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Clumps side by side with LIGGGHTS 3.8.0's multisphere (fix particletemplate/multisphere,
fix multisphere), from the same initial states and walls. Run from the repository root:

    .venv/bin/python cases/clumps/compare_liggghts.py [--dem build/dem] [--only impact|bin]
                                        [--seeds 10007,20011,30011,40009,50021] [--reuse]

(`build/dem` from `scripts/install/build plain`; `liggghts` and `mpirun` on the PATH; each
code runs on one core: about 30 minutes in all for five seeds). Outputs go to
output/clumps_liggghts/ (apart from the clumps example's output/clumps/); the numbers to
output/clumps_liggghts/summary.txt (and standard output), the figures to
doc/figures/clumps_liggghts_impact.png and doc/figures/clumps_liggghts_bin.png.

1. impact.nml / impact.liggghts: one three-sphere clump falling at an angle onto a plane.
   Both trajectories are reduced to the body's centre of mass, its velocity and its angular
   velocity (fitted to the three members' positions and velocities, the same way for both
   codes) and compared over 20 ms. dem runs it again at dt = 1 us, for its own time-step
   error, taken on the rows where no member touches the plane.
2. bin.liggghts / bin.nml: for each seed, LIGGGHTS fills the bin with 3000 clumps and
   empties it; its state at the opening (fill.txt) is converted to an &clump_file and dem
   empties the same bin from it. The discharge rate (clumps per second) is the slope of the
   count of members above the floor, over the steady window, divided by three; a fill
   whose orifice clogged (no member left over the window) is counted apart. With --reuse,
   the bin's runs whose outputs are in output/clumps_liggghts/ are not run again.

The mass properties written into the decks (the template about its centre of mass, its mass
and principal moments) are checked here against the closed form of the union of the three
spheres (doc/theory.md, section 17.1)."""
import argparse
import math
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
OUT = os.path.join(ROOT, "output", "clumps_liggghts")
FIGURES = os.path.join(ROOT, "doc", "figures")
RHO = 2500.0
WINDOW = (0.2, 0.6)    # the steady part of the discharge [s]


# ---- the template -------------------------------------------------------------------------

def vee(scale):
    """Member centres (about the union's centre of mass), radius, mass and principal moments
    (x, y, z: the template's axes are principal by its symmetry) of the vee: a middle sphere
    and two arms at 1.5 radii from it, 120 degrees apart, radius 2 mm times scale. The
    arms do not touch each other, so the union is the three spheres less two lenses, each
    lens two caps (doc/theory.md, section 17.1)."""
    r, d = 0.002 * scale, 0.003 * scale
    c = np.array([[0.0, 0.0, 0.0],
                  [d * math.sin(math.pi / 3), -d * math.cos(math.pi / 3), 0.0],
                  [-d * math.sin(math.pi / 3), -d * math.cos(math.pi / 3), 0.0]])
    vs = 4.0 / 3.0 * math.pi * r**3
    vol, first, second = 3 * vs, vs * c.sum(0), np.zeros((3, 3))
    for k in range(3):
        second += vs * np.outer(c[k], c[k]) + 4.0 / 15.0 * math.pi * r**5 * np.eye(3)
    h = d / 2   # each cap lies beyond the plane half-way between the centres
    v_cap = math.pi / 3 * (r - h)**2 * (2 * r + h)
    z1 = math.pi / 4 * (r * r - h * h)**2
    z2 = math.pi * (2 * r**5 / 15 - r * r * h**3 / 3 + h**5 / 5)
    rho2 = math.pi / 2 * (8 * r**5 / 15 - r**4 * h + 2 * r * r * h**3 / 3 - h**5 / 5)
    for k in (1, 2):
        e, mid = c[k] / d, c[k] / 2
        axial = 2 * (z2 - 2 * h * z1 + h * h * v_cap)
        lens = axial * np.outer(e, e) + rho2 * (np.eye(3) - np.outer(e, e))
        vol -= 2 * v_cap
        first -= 2 * v_cap * mid
        second -= 2 * v_cap * np.outer(mid, mid) + lens
    com = first / vol
    sc = second - vol * np.outer(com, com)
    inertia = RHO * (np.trace(sc) * np.eye(3) - sc)
    return c - com, r, RHO * vol, np.diag(inertia)


def check_decks():
    """The template written into the four decks is vee()'s, to 1e-12."""
    for scale, names in ((1.0, ("impact.nml", "impact.liggghts")),
                         (0.75, ("bin.nml", "bin.liggghts"))):
        members, r, mass, moments = vee(scale)
        want = np.hstack([members, np.full((3, 1), r)]).ravel()
        for name in names:
            text = open(os.path.join(HERE, name)).read()
            if name.endswith(".nml"):
                block = re.search(r"members\s*=\s*([^/]*)/", text).group(1)
                got = np.array([float(t) for t in block.replace(",", " ").split()])
            else:
                block = re.search(r"spheres &(.*?)type 1", text, re.S).group(1)
                got = np.array([float(t) for t in block.replace("&", " ").split()])
                m = float(re.search(r"type 1 mass (\S+)", text).group(1))
                tensor = [float(t) for t in re.search(r"inertia_tensor((?: \S+){6})",
                                                      text).group(1).split()]
                if abs(m / mass - 1) > 1e-12 or not np.allclose(
                        tensor, [moments[0], 0, 0, moments[1], 0, moments[2]], rtol=1e-12,
                        atol=0):
                    sys.exit(f"{name}: mass or inertia_tensor not the closed form's "
                             f"({mass!r}, {moments!r})")
            if got.shape != want.shape or not np.allclose(got, want, rtol=0, atol=1e-15):
                sys.exit(f"{name}: the members are not the closed form's: {want!r}")


# ---- running the codes --------------------------------------------------------------------

def run_dem(dem, case, work, log):
    start = time.time()
    with open(os.path.join(work, "dem.txt"), "w") as out:
        r = subprocess.run(["nice", "-n", "19", dem, case], cwd=work, stdout=out,
                           stderr=subprocess.STDOUT)
    if r.returncode != 0:
        sys.exit(f"dem failed on {case}: see {work}/dem.txt")
    log.append((os.path.basename(work) + " (dem)", time.time() - start))


def run_liggghts(deck, work, log, variables=()):
    start = time.time()
    cmd = ["nice", "-n", "19", "mpirun", "--allow-run-as-root", "-np", "1", "liggghts",
           "-in", os.path.join(HERE, deck)]
    for name, value in variables:
        cmd += ["-var", name, str(value)]
    with open(os.path.join(work, "screen.txt"), "w") as out:
        r = subprocess.run(cmd, cwd=work, stdout=out, stderr=subprocess.STDOUT)
    text = open(os.path.join(work, "screen.txt")).read()
    if r.returncode != 0 or "ERROR" in text:
        sys.exit(f"LIGGGHTS failed in {work}:\n{text[-2000:]}")
    log.append((os.path.basename(work) + " (LIGGGHTS)", time.time() - start))


def fresh(path):
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)
    return path


# ---- bodies from their members ------------------------------------------------------------

def fit_body(members, x, v, w):
    """Centre of mass X, rotation R (template frame to lab) and velocity V of a rigid body
    whose members, at the template's offsets `members` (about the centre of mass), are at x
    with velocities v, turning at w: R by the Kabsch fit, V = mean(v_k - w x (x_k - X))."""
    xm, bm = x.mean(0), members.mean(0)
    u, _, vt = np.linalg.svd((members - bm).T @ (x - xm))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rot = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    centre = xm - rot @ bm
    misfit = np.max(np.abs(centre + members @ rot.T - x))
    return centre, rot, (v - np.cross(w, x - centre)).mean(0), misfit


def quaternion(rot):
    """Unit quaternion (q0, q1, q2, q3) of a rotation matrix (Shepperd 1978)."""
    t = np.trace(rot)
    k = int(np.argmax([t, rot[0, 0], rot[1, 1], rot[2, 2]]))
    if k == 0:
        s = 2 * math.sqrt(1 + t)
        q = [s / 4, (rot[2, 1] - rot[1, 2]) / s, (rot[0, 2] - rot[2, 0]) / s,
             (rot[1, 0] - rot[0, 1]) / s]
    else:
        i, j, m = k - 1, k % 3, (k + 1) % 3
        s = 2 * math.sqrt(1 + 2 * rot[i, i] - t)
        q = [0.0] * 4
        q[0] = (rot[m, j] - rot[j, m]) / s
        q[1 + i] = s / 4
        q[1 + j] = (rot[j, i] + rot[i, j]) / s
        q[1 + m] = (rot[m, i] + rot[i, m]) / s
    q = np.array(q)
    return q / np.linalg.norm(q) * (1 if q[0] >= 0 else -1)


def dump_snapshots(path):
    """(step, rows sorted by id) of each snapshot of a custom dump."""
    for block in open(path).read().split("ITEM: TIMESTEP\n")[1:]:
        lines = block.splitlines()
        rows = np.array([[float(t) for t in s.split()] for s in lines[8:] if s.strip()])
        if rows.size:
            yield int(lines[0]), rows[np.argsort(rows[:, 0])]


def body_row(members, rows):
    """time-less row X, V, w of one body from its member rows (id x y z vx vy vz wx wy wz)."""
    w = rows[0, 7:10]
    centre, _, vel, misfit = fit_body(members, rows[:, 1:4], rows[:, 4:7], w)
    if misfit > 1e-9:
        sys.exit(f"the members are not the template's (misfit {misfit:.2e} m)")
    return np.concatenate([centre, vel, w])


# ---- 1. one clump hitting a plane ---------------------------------------------------------

def impact_dem(dem, name, dt, log):
    """dem's run of impact.nml at time step dt into OUT/name: the rows (t, X, V, w) of the
    body and whether a member touches the plane (its centre within its radius of it)."""
    members, radius = vee(1.0)[:2]
    work = fresh(os.path.join(OUT, name))
    case = os.path.join(work, "impact.nml")
    text = open(os.path.join(HERE, "impact.nml")).read()
    text = text.replace("'../../output/clumps_liggghts/impact'", f"'{work}'")
    open(case, "w").write(text.replace("dt = 2e-6,", f"dt = {dt!r},"))
    run_dem(dem, case, work, log)
    probes = np.genfromtxt(os.path.join(work, "probes.csv"), delimiter=",", names=True)
    bodies, touching = [], []
    for p in probes:
        rows = np.array([[k] + [p[f"m{k}_{c}"] for c in ("x", "y", "z", "vx", "vy", "vz",
                                                         "wx", "wy", "wz")]
                         for k in (1, 2, 3)])
        bodies.append(np.concatenate([[p["time"]], body_row(members, rows)]))
        touching.append(rows[:, 3].min() < radius)
    return np.array(bodies), np.array(touching)


def impact(dem, log, summary):
    members = vee(1.0)[0]
    work_l = fresh(os.path.join(OUT, "impact_liggghts"))
    ours, touching = impact_dem(dem, "impact", 2e-6, log)
    run_liggghts("impact.liggghts", work_l, log)
    theirs = np.array([np.concatenate([[step * 2e-6], body_row(members, rows)])
                       for step, rows in dump_snapshots(os.path.join(work_l,
                                                                     "trajectory.txt"))])
    if ours.shape != theirs.shape or not np.allclose(ours[:, 0], theirs[:, 0], atol=1e-9):
        sys.exit(f"the trajectories do not have the same rows: {ours.shape} {theirs.shape}")
    names = ["X", "Y", "Z", "Vx", "Vy", "Vz", "wx", "wy", "wz"]
    summary.append("1. one clump hitting a plane (impact.nml, impact.liggghts)")
    summary.append("   at t = 20 ms      dem                   LIGGGHTS              "
                   "difference")
    for k, name in enumerate(names):
        a, b = ours[-1, k + 1], theirs[-1, k + 1]
        summary.append(f"   {name:3s}  {a:21.12e} {b:21.12e} {a - b:12.3e}")
    dx = np.max(np.linalg.norm(ours[:, 1:4] - theirs[:, 1:4], axis=1))
    dv = np.max(np.linalg.norm(ours[:, 4:7] - theirs[:, 4:7], axis=1))
    dw = np.max(np.linalg.norm(ours[:, 7:10] - theirs[:, 7:10], axis=1))
    vmax = np.max(np.linalg.norm(theirs[:, 4:7], axis=1))
    wmax = np.max(np.linalg.norm(theirs[:, 7:10], axis=1))
    summary.append(f"   largest difference over 20 ms: centre of mass {dx:.3e} m, velocity "
                   f"{dv:.3e} m/s ({dv / vmax:.2e} of its largest), angular velocity "
                   f"{dw:.3e} rad/s ({dw / wmax:.2e} of its largest)")
    # dem's own time-step error: at 1 us against 2 us, on the rows where neither touches
    halved, touching_halved = impact_dem(dem, "impact_dt1", 1e-6, log)
    free = ~(touching | touching_halved)
    dv = np.max(np.linalg.norm(ours[free, 4:7] - halved[free, 4:7], axis=1))
    dw = np.max(np.linalg.norm(ours[free, 7:10] - halved[free, 7:10], axis=1))
    summary.append(f"   dem at dt = 1 us against 2 us, where no member touches the plane "
                   f"({free.sum()} of {free.size} rows): velocity {dv:.3e} m/s, angular "
                   f"velocity {dw:.3e} rad/s")
    plot_impact(ours, theirs)


def plot_impact(ours, theirs):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    t1, t2 = ours[:, 0] * 1e3, theirs[:, 0] * 1e3
    for k, (label, color) in enumerate((("X", "C0"), ("Y", "C1"), ("Z", "C2"))):
        axes[0].plot(t1, ours[:, 1 + k] * 1e3, color=color, label=f"{label} dem")
        axes[0].plot(t2, theirs[:, 1 + k] * 1e3, "o", color=color, ms=3, mfc="none",
                     markevery=4, label=f"{label} LIGGGHTS")
        axes[1].plot(t1, ours[:, 4 + k], color=color, label=f"V{label.lower()} dem")
        axes[1].plot(t2, theirs[:, 4 + k], "o", color=color, ms=3, mfc="none", markevery=4,
                     label=f"V{label.lower()} LIGGGHTS")
        axes[2].plot(t1, ours[:, 7 + k], color=color, label=f"w{label.lower()} dem")
        axes[2].plot(t2, theirs[:, 7 + k], "o", color=color, ms=3, mfc="none", markevery=4,
                     label=f"w{label.lower()} LIGGGHTS")
    for ax, ylabel in zip(axes, ("centre of mass [mm]", "velocity [m/s]",
                                 "angular velocity [rad/s]")):
        ax.set_xlabel("t [ms]")
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=7, ncol=2)
    fig.suptitle("A three-sphere clump hitting a plane: dem (lines) and LIGGGHTS 3.8 "
                 "multisphere (circles)")
    fig.tight_layout()
    fig.savefig(os.path.join(FIGURES, "clumps_liggghts_impact.png"), dpi=110)
    plt.close(fig)


# ---- 2. a bin emptied ---------------------------------------------------------------------

def clumps_from_fill(path):
    """The bodies of a LIGGGHTS fill (members of a body: consecutive ids) as the lines of an
    &clump_file (template, centre of mass, orientation, velocity, angular velocity), and
    their number."""
    members = vee(0.75)[0]
    rows = list(dump_snapshots(path))[-1][1]
    if rows.shape[0] % 3 or not np.array_equal(rows[:, 0], np.arange(1, rows.shape[0] + 1)):
        sys.exit(f"{path}: the members are not three consecutive ids a body")
    lines = ["template,x,y,z,q0,q1,q2,q3,vx,vy,vz,wx,wy,wz\n"]
    for b in range(rows.shape[0] // 3):
        member_rows = rows[3 * b:3 * b + 3]
        w = member_rows[0, 7:10]
        centre, rot, vel, misfit = fit_body(members, member_rows[:, 1:4], member_rows[:, 4:7],
                                            w)
        if misfit > 1e-9:
            sys.exit(f"{path}: body {b + 1}'s members are not the template's ({misfit:.1e} m)")
        values = np.concatenate([centre, quaternion(rot), vel, w])
        lines.append("vee," + ",".join(repr(float(t)) for t in values) + "\n")
    return "".join(lines), rows.shape[0] // 3


def bin_case(work, fill):
    """bin.nml in `work`, its output there, with the clumps of LIGGGHTS's fill (clumps.csv);
    the case's path and the number of clumps."""
    table, n_bodies = clumps_from_fill(fill)
    open(os.path.join(work, "clumps.csv"), "w").write(table)
    head = open(os.path.join(HERE, "bin.nml")).read().replace(
        "'bin_floor.stl'", f"'{os.path.join(HERE, 'bin_floor.stl')}'").replace(
        "&output interval", f"&output dir = '{work}', interval")
    case = os.path.join(work, "bin.nml")
    open(case, "w").write(head + "&clump_file file = 'clumps.csv' /\n")
    return case, n_bodies


def rate(t, members_above):
    """Clumps per second: the slope of the members above the floor over WINDOW, over 3; None
    when the orifice clogged (no member left over the window)."""
    k = (t >= WINDOW[0] - 1e-12) & (t <= WINDOW[1] + 1e-12)
    if members_above[k][0] == members_above[k][-1]:
        return None
    return -np.polyfit(t[k], members_above[k], 1)[0] / 3.0


def emptying(dem, seeds, log, summary, reuse):
    curves = {}
    rates = {"dem": [], "LIGGGHTS": []}
    for seed in seeds:
        work_l = os.path.join(OUT, f"bin_liggghts_{seed}")
        if not (reuse and os.path.exists(os.path.join(work_l, "count.txt"))):
            fresh(work_l)
            shutil.copy(os.path.join(HERE, "bin_floor.stl"), work_l)
            run_liggghts("bin.liggghts", work_l, log, (("seed", seed),))
        count = np.loadtxt(os.path.join(work_l, "count.txt"), comments="#")
        t_l, n_l = count[:, 0] * 2e-5, count[:, 1]
        work_d = os.path.join(OUT, f"bin_{seed}")
        if reuse and os.path.exists(os.path.join(work_d, "probes.csv")):
            n_bodies = clumps_from_fill(os.path.join(work_l, "fill.txt"))[1]
        else:
            fresh(work_d)
            case, n_bodies = bin_case(work_d, os.path.join(work_l, "fill.txt"))
            run_dem(dem, case, work_d, log)
        probes = np.genfromtxt(os.path.join(work_d, "probes.csv"), delimiter=",", names=True)
        t_d, n_d = probes["time"], probes["above_grain"]
        curves[seed] = (t_d, n_d, t_l, n_l)
        rates["dem"].append(rate(t_d, n_d))
        rates["LIGGGHTS"].append(rate(t_l, n_l))
        if n_d[0] != 3 * n_bodies:
            sys.exit(f"seed {seed}: not all {n_bodies} clumps above the floor at the opening")
    summary.append(f"2. a bin emptied (bin.liggghts, bin.nml; 3000 clumps; rate over "
                   f"{WINDOW[0]}-{WINDOW[1]} s, clumps per second; clogged: no clump left "
                   "over it)")
    summary.append("   seed      dem        LIGGGHTS   dem / LIGGGHTS")
    for k, seed in enumerate(seeds):
        a, b = rates["dem"][k], rates["LIGGGHTS"][k]
        shown = [f"{r:10.1f}" if r is not None else "   clogged" for r in (a, b)]
        ratio = f"{a / b:.4f}" if a is not None and b is not None else "-"
        summary.append(f"   {seed:6d} {shown[0]} {shown[1]}   {ratio}")
    means = {}
    for code in ("dem", "LIGGGHTS"):
        r = np.array([x for x in rates[code] if x is not None])
        sd = r.std(ddof=1) if r.size > 1 else float("nan")
        means[code] = r.mean()
        summary.append(f"   {code:8s} clogged {len(seeds) - r.size} of {len(seeds)}; the "
                       f"flowing fills: mean {r.mean():.1f}, standard deviation {sd:.1f} "
                       f"({sd / r.mean():.2%})")
    summary.append(f"   mean rate of the flowing fills, dem / LIGGGHTS "
                   f"{means['dem'] / means['LIGGGHTS']:.4f}")
    plot_bin(curves, seeds)


def plot_bin(curves, seeds):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for k, seed in enumerate(seeds):
        t_d, n_d, t_l, n_l = curves[seed]
        ax.plot(t_d, n_d / 3, color=f"C{k}", label=f"dem, fill {seed}")
        ax.plot(t_l, n_l / 3, "o", color=f"C{k}", ms=3, mfc="none", markevery=4,
                label=f"LIGGGHTS, fill {seed}")
    ax.axvspan(*WINDOW, color="0.9", zorder=0, label="window of the rate")
    ax.set_xlabel("time since the orifice opened [s]")
    ax.set_ylabel("clumps above the floor (members / 3)")
    ax.set_title("3000 three-sphere clumps leaving a bin: dem and LIGGGHTS 3.8", fontsize=10)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(FIGURES, "clumps_liggghts_bin.png"), dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dem", default=os.path.join(ROOT, "build", "dem"))
    parser.add_argument("--seeds", default="10007,20011,30011,40009,50021")
    parser.add_argument("--reuse", action="store_true",
                        help="the bin: keep the runs whose outputs are there (summary, figure)")
    parser.add_argument("--only", choices=("impact", "bin"))
    args = parser.parse_args()
    dem = os.path.abspath(args.dem)
    seeds = [int(s) for s in args.seeds.split(",")]
    check_decks()
    os.makedirs(OUT, exist_ok=True)
    log, summary = [], []
    if args.only in (None, "impact"):
        impact(dem, log, summary)
    if args.only in (None, "bin"):
        emptying(dem, seeds, log, summary, args.reuse)
    summary.append("wall time of each run (one core, nice 19; not a timing comparison):")
    summary += [f"   {name:32s} {seconds:8.1f} s" for name, seconds in log]
    text = "\n".join(summary) + "\n"
    open(os.path.join(OUT, "summary.txt" if args.only is None else
                      f"summary_{args.only}.txt"), "w").write(text)
    print(text, end="")


if __name__ == "__main__":
    main()
