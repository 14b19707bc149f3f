# SPDX-License-Identifier: BSD-3-Clause
"""The examples of examples/ (doc/user/examples.md), each run for a shorter time than its
namelist says (t_end rewritten; everything else as the user runs it) after a `dem --check`
without a warning, and checked against what physics says, not against the solver's own
earlier numbers:

pour     the inflow's count: the particles at each row follow floor(rate t) (at most one
         insertion behind), 3000 at the end, none removed, all of them inside the box
         (inserted = in the box + removed); at rest at the end, the walls carry the beads'
         weight; the bed's solid fraction is that of a random packing.
hopper   nothing leaves before the plug opens; particles + removed = the 3500 inserted at
         every row; the mass flow rate once it is steady lies in Beverloo's band
         W = C rho_b sqrt(g) (D - k d)^(5/2) for the constants of the literature
         (C 0.55 to 0.65, k 1.3 to 2.9), rho_b measured from the bed before the plug opens.
drum     the bed's centre of mass is on the drum's vertical through the axis before the drum
         turns and moves to the side the drum's bottom moves to (+x for -2 rad/s about y)
         after; the surface's angle (the centre of mass's angle about the axis) is a dynamic
         angle of repose (20 to 45 degrees); the bed keeps its distance from the axis; the
         torque of the beads on the drum about its axis balances gravity's torque on the bed,
         M g x_c (the bed's angular momentum is steady).
impact   the ball falls freely until it touches the bed (height and velocity of free fall); the
         kinetic plus potential energy of the particles never exceeds its value before the
         impact; the ball rebounds at most with the pair's restitution; the ball ends at rest
         inside the bed (below its surface, above the floor).
chute    from the committed steady state (the run from rest's end), 0.5 s of flow down the
         periodic chute: the mass flow rate that of the long run (8 s of steady flow) within
         5 %; the velocity profile is Bagnold's, v_b + A (h^1.5 - (h - z)^1.5), with h the
         flow's top within two diameters, no slip at the base (|v_b| under a tenth of the
         surface speed) and a residual under a third of a linear profile's; the free exponent
         fitted lies in 1.3 .. 1.9; every particle stays in the run and inside the period.
clumps   rods of three spheres poured by an inflow: 1000 rods (3000 members) at the end of
         the inflow, the count at most one insertion behind floor(rate t) members x 3;
         particles + removed = 3000 at every row after it; `removed` a multiple of 3 at every
         row (a rod leaves whole) and 0 before the plug moves; the settled bed's packing
         fraction (the union of the members in a box clear of the walls and the surface)
         between a loose packing's 0.50 and 0.72, the most any random packing of
         spherocylinders reaches; more rods lying within 30 degrees of the horizontal than
         the 0.5 of rods turned at random (0.55: three standard deviations of 1000 random
         rods); the discharge rate from 0.45 s in Beverloo's band (as the hopper's, D the
         orifice's side, d the diameter of the sphere of a rod's volume).
agglomerate  2000 bonded spheres hitting a rigid plane at 6 m/s: the bonds made are the pairs
         of the particle file within the &bond gap (counted again); the bonds broken in
         series.csv are those made that the end checkpoint no longer holds; kinetic plus
         bond energy never exceeds the kinetic energy at the start (no gravity: contacts and
         bond damping only dissipate, a bond's energy leaves with it); the damage starts at
         the impact (the broken bonds' mean height below the ball's centre); it fragments
         (the largest fragment under 0.8 of the mass: its Delta = 6 lies above the critical
         Delta of 1.5 to 3 of cases/bonds/agglomerate_impact.py); the same ball with bonds
         twice as strong at twice the speed (the same Delta of Moreno-Atanasio and Ghadiri)
         breaks a damage ratio within a factor 1.6 of this one (their collapse; the case
         study's largest spread over 24 runs is 1.86, 1.4 at this Delta).
restart  the case straight through on 1 rank, on 2 ranks, and continued on 2 ranks from the
         1-rank run's checkpoint half-way: series.csv, probes.csv, final.csv, snapshots.xmf
         identical byte for byte, and every dataset and attribute of every snapshot bit for
         bit (the HDF5 files' bytes differ between 1 and 2 ranks in HDF5's layout).
usage: test_examples.py DEM WORKDIR MPIEXEC EXAMPLE"""
import csv
import glob
import math
import os
import re
import shutil
import subprocess
import sys

import numpy as np

from regression_util import ROOT, check, finish

sys.path.insert(0, os.path.join(ROOT, "examples", "restart"))
from compare import h5_same  # noqa: E402  (the restart example's comparison)

dem, work, mpiexec, example = (sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3],
                               sys.argv[4])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
EXAMPLES = os.path.join(ROOT, "examples")
G = 9.81
RHO = 2500.0                                    # the beads' density in every example


def case(name, t_end, out):
    """The example's namelist with t_end and the output folder replaced, its files made
    absolute (the copy lives in the work folder); returns the copy's path."""
    src = os.path.join(EXAMPLES, name, name + ".nml")
    with open(src) as f:
        text = f.read()
    text, n = re.subn(r"t_end = [0-9.eE+-]+", f"t_end = {t_end}", text)
    check(n == 1, f"{name}: one t_end in {src}")
    text, n = re.subn(r"&output ", f"&output dir = '{out}', ", text)
    check(n == 1, f"{name}: one &output group")
    here = os.path.dirname(src)
    text = re.sub(r"(\b(?:mesh_)?file = ')([^']+)'",
                  lambda m: m.group(1) + os.path.normpath(os.path.join(here, m.group(2))) + "'",
                  text)
    path = os.path.join(work, f"{out}.nml")
    with open(path, "w") as f:
        f.write(text)
    # what a user runs first: dem --check, without a warning (dt within every bound)
    r = subprocess.run([dem, "--check", path], cwd=work, capture_output=True, text=True,
                       timeout=600)
    check(r.returncode == 0 and "warning" not in r.stdout + r.stderr,
          f"{name}: dem --check passes without a warning: {r.stdout[-1500:]}{r.stderr}")
    return path


def run(args, ranks=1):
    cmd = [dem, *args]
    if ranks > 1:
        cmd = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] + cmd
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=1200)
    check(r.returncode == 0, f"{' '.join(args)} on {ranks} rank(s): exit {r.returncode}\n"
          f"{r.stdout[-2000:]}{r.stderr[-2000:]}")
    return r


def table(out, name):
    return np.genfromtxt(os.path.join(work, out, name), delimiter=",", names=True)


def final(out):
    with open(os.path.join(work, out, "final.csv")) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in ("id", "radius", "x", "y", "z",
                                                              "vx", "vy", "vz")}, rows


def pour():
    run([case("pour", 0.6, "pour")])
    s, p = table("pour", "series.csv"), table("pour", "probes.csv")
    f, rows = final("pour")
    rate, end = 7500.0, 0.4
    expected = math.floor(rate * end)
    check(len(rows) == expected, f"pour: {len(rows)} particles at the end, rate x duration = "
          f"{expected}")
    check(sorted(f["id"]) == list(range(1, expected + 1)), "pour: ids 1 to 3000")
    check(s["removed"][-1] == 0 and p["box_beads"][-1] == expected,
          f"pour: inserted {expected} = in the box {p['box_beads'][-1]:g} + removed "
          f"{s['removed'][-1]:g}")
    goal = np.floor(rate * np.minimum(s["time"], end))
    # one insertion's worth behind at most: the default insert_every is the time a sphere
    # takes to move a largest diameter (3.5 mm) at 1 m/s, 3.5 ms, ~26 spheres
    lag = goal - s["particles"]
    check(np.all(lag >= 0) and np.all(lag <= rate * 0.004),
          f"pour: particles follow floor(rate t) within one insertion (lag {lag.min():g} to "
          f"{lag.max():g})")
    r = f["radius"]
    inside = ((np.abs(f["x"]) <= 0.03 - r + 1e-4) & (np.abs(f["y"]) <= 0.03 - r + 1e-4)
              & (f["z"] >= r - 1e-4))
    check(inside.all(), f"pour: every particle inside the box ({(~inside).sum()} outside)")
    weight = (RHO * 4 / 3 * math.pi * r ** 3).sum() * G
    # at rest: the kinetic energy a thousandth of what lifting the beads by a diameter takes
    check(s["kinetic_translational"][-1] < 1e-3 * weight * 0.003,
          f"pour: at rest at the end (kinetic energy {s['kinetic_translational'][-1]:.3g} J)")
    # the force of the beads on the walls is down: -fz is the load the walls carry
    check(abs(-p["walls_fz"][-1] - weight) < 0.02 * weight,
          f"pour: the walls carry the beads' weight: {-p['walls_fz'][-1]:.6g} N, weight "
          f"{weight:.6g} N")
    check(0 < -p["floor_fz"][-1] <= -p["walls_fz"][-1] + 1e-9,
          "pour: the floor carries most of it (the rest: friction on the side walls)")
    # solid fraction of the layer 2 to 10 mm above the floor
    lo, hi = 0.002, 0.010
    a, b = np.maximum(f["z"] - r, lo), np.minimum(f["z"] + r, hi)
    vol = np.where(b > a, math.pi * (r ** 2 * (b - a) - ((b - f["z"]) ** 3 -
                                                         (a - f["z"]) ** 3) / 3), 0)
    phi = vol.sum() / (0.06 * 0.06 * (hi - lo))
    check(0.50 <= phi <= 0.64, f"pour: solid fraction {phi:.3f} of a random packing "
          "(0.50 to 0.64)")
    print(f"pour: {len(rows)} particles, walls {-p['walls_fz'][-1]:.5f} N against the weight "
          f"{weight:.5f} N, solid fraction {phi:.3f}")


def hopper():
    t_end = 0.6
    run([case("hopper", t_end, "hopper")])
    s = table("hopper", "series.csv")
    n0 = 3500
    check(np.all(s["particles"] + s["removed"] == n0),
          "hopper: particles + removed = 3500 at every row")
    check(np.all(s["removed"][s["time"] <= 0.25] == 0), "hopper: none leaves before 0.25 s")
    check(s["removed"][-1] > 100, f"hopper: it discharges ({s['removed'][-1]:g} removed)")
    # bulk density of the bed on the plug: the spheres' volume in a layer 3 to 12 mm above
    # the floor, within 14 mm of the axis (clear of the wall's ordering), over the layer's
    # volume, from the last snapshot before the plug moves (0.25 s)
    import h5py
    for name in sorted(glob.glob(os.path.join(work, "hopper", "snapshots", "*.h5"))):
        with h5py.File(name) as h:
            if h["time"][()] > 0.25:
                break
            x = h["particles/position"][()]
            r = h["particles/radius"][()]
    lo, hi, rr = 0.003, 0.012, 0.014
    sel = np.hypot(x[:, 0], x[:, 1]) <= rr
    z = x[sel, 2]
    a, b = np.maximum(z - r[sel], lo), np.minimum(z + r[sel], hi)
    vol = np.where(b > a, math.pi * (r[sel] ** 2 * (b - a) - ((b - z) ** 3 -
                                                            (a - z) ** 3) / 3), 0)
    phi = vol.sum() / (math.pi * rr ** 2 * (hi - lo))
    check(0.5 <= phi <= 0.66, f"hopper: solid fraction of the bed {phi:.3f}")
    m = RHO * 4 / 3 * math.pi * 1e-3 ** 3
    steady = s["time"] >= 0.45
    w = np.polyfit(s["time"][steady], s["removed"][steady] * m, 1)[0]
    d_o, d = 0.012, 0.002
    beverloo = lambda c, k: c * phi * RHO * math.sqrt(G) * (d_o - k * d) ** 2.5
    lo_w, mid, hi_w = beverloo(0.55, 2.9), beverloo(0.58, 1.5), beverloo(0.65, 1.3)
    check(lo_w <= w <= hi_w, f"hopper: flow rate {w * 1e3:.2f} g/s in Beverloo's band "
          f"{lo_w * 1e3:.2f} to {hi_w * 1e3:.2f} g/s")
    print(f"hopper: flow rate {w * 1e3:.2f} g/s; Beverloo (C 0.58, k 1.5) {mid * 1e3:.2f} g/s, "
          f"band {lo_w * 1e3:.2f} to {hi_w * 1e3:.2f} g/s; solid fraction {phi:.3f}")


def drum():
    run([case("drum", 1.0, "drum")])
    p = table("drum", "probes.csv")
    f, rows = final("drum")
    t, x, z = p["time"], p["com_beads_x"], p["com_beads_z"]
    rest = (t >= 0.3) & (t <= 0.4)
    check(np.all(np.abs(x[rest]) < 1e-3), f"drum: at rest, the bed's centre of mass is under "
          f"the axis (x {x[rest].min():.2e} to {x[rest].max():.2e} m)")
    late = t >= 0.8
    theta = np.degrees(np.arctan2(x[late], -z[late]))
    check(np.all(x[late] > 0), "drum: turning, the centre of mass is on the side the drum's "
          "bottom moves to (+x)")
    check(20 <= theta.mean() <= 45, f"drum: the bed's angle {theta.mean():.1f} deg is a "
          "dynamic angle of repose (20 to 45)")
    d0, d = math.hypot(x[rest][-1], z[rest][-1]), np.hypot(x[late], z[late])
    check(np.all(np.abs(d - d0) < 0.1 * d0), f"drum: the bed keeps its distance from the axis "
          f"({d0 * 1e3:.1f} mm at rest, {d.min() * 1e3:.1f} to {d.max() * 1e3:.1f} turning)")
    mass = (RHO * 4 / 3 * math.pi * f["radius"] ** 3).sum()
    torque, gravity = p["drum_torque_axis"][late].mean(), mass * G * x[late].mean()
    check(abs(torque - gravity) < 0.15 * gravity, f"drum: the beads' torque on the drum "
          f"{torque:.5f} N m balances gravity's on the bed, M g x_c = {gravity:.5f} N m")
    print(f"drum: angle {theta.mean():.1f} deg, torque {torque:.5f} N m, M g x_c "
          f"{gravity:.5f} N m")


def impact():
    run([case("impact", 0.4, "impact")])
    p, s = table("impact", "probes.csv"), table("impact", "series.csv")
    f, rows = final("impact")
    z0, radius, e = 0.47, 5e-3, 0.5
    t, zb, vb = p["time"], p["ball_z"], p["ball_vz"]
    free = t <= 0.28                                 # well before the bed (about 0.3 s)
    check(np.allclose(vb[free], -G * t[free], rtol=1e-9, atol=1e-12),
          "impact: the ball's velocity is free fall's before the impact")
    check(np.allclose(zb[free], z0 - G * t[free] ** 2 / 2, rtol=0, atol=G * 0.3 * 1e-5),
          "impact: the ball's height is free fall's before the impact (within g t dt)")
    hit = int(np.argmax(np.abs(vb) < G * t - 1e-3))
    check(hit > 0, "impact: the ball touches the bed")
    v_in = -vb[hit - 1]
    check(abs(v_in - math.sqrt(2 * G * (z0 - zb[hit - 1]))) < 1e-3 * v_in,
          f"impact: speed {v_in:.4f} m/s at the bed, that of a fall from {z0} m")
    energy = s["kinetic_translational"] + s["kinetic_rotational"] + s["potential_gravity"]
    before = energy[np.argmin(np.abs(s["time"] - t[hit - 1]))]
    check(energy[s["time"] >= t[hit - 1]].max() <= before * (1 + 1e-4),
          f"impact: no energy is made after the impact (at most "
          f"{energy[s['time'] >= t[hit - 1]].max():.6g} J, {before:.6g} J before)")
    check(vb[hit:].max() <= e * v_in, f"impact: the ball rebounds at most at e v = "
          f"{e * v_in:.3f} m/s ({vb[hit:].max():.3f})")
    ke_in = 0.5 * 7800 * 4 / 3 * math.pi * radius ** 3 * v_in ** 2
    check(s["kinetic_translational"][-1] + s["kinetic_rotational"][-1] < 0.05 * ke_in,
          "impact: the particles end nearly at rest (kinetic energy < 5 % of the ball's)")
    beads = np.array([r["material"] == "beads" for r in rows])
    away = beads & (np.hypot(f["x"], f["y"]) > 0.02)
    surface = np.percentile(f["z"][away] + f["radius"][away], 95)
    check(radius <= zb[-1] < surface, f"impact: the ball ends in the bed: centre at "
          f"{zb[-1] * 1e3:.1f} mm, surface {surface * 1e3:.1f} mm, floor at 0")
    print(f"impact: {v_in:.3f} m/s at the bed, ball ends at {zb[-1] * 1e3:.1f} mm (surface "
          f"{surface * 1e3:.1f} mm), energy {before * 1e3:.2f} -> {energy[-1] * 1e3:.2f} mJ")


def chute():
    path = case("chute", 0.5, "chute")
    with open(path) as f:
        text = f.read()
    steady = os.path.join(EXAMPLES, "chute", "steady.csv")
    text, n = re.subn(r"&insert [^/]*/", f"&particle_file file = '{steady}' /", text)
    check(n == 1, "chute: one &insert group")
    with open(path, "w") as f:
        f.write(text)
    run([path])
    sys.path.insert(0, os.path.join(EXAMPLES, "chute"))
    from flow_profile import analyse          # noqa: E402  (the example's own analysis)
    d = 0.002
    r = analyse(os.path.join(work, "chute"), 0.0, 0.02, 0.0008, RHO, d)
    q_long = 0.1804                      # examples/chute/README.md: the run from rest, 4 .. 12 s
    check(abs(r["flow_rate"] - q_long) < 0.05 * q_long, f"chute: flow rate "
          f"{r['flow_rate']:.4f} kg/s, the long run's {q_long} kg/s")
    b, free, lin = r["bagnold"], r["free"], r["linear"]
    surface = r["layers"][-1][1]
    check(abs(b["h"] - r["top"]) < 2 * d, f"chute: Bagnold's depth {b['h'] * 1e3:.1f} mm is "
          f"the flow's top {r['top'] * 1e3:.1f} mm")
    check(abs(b["v_b"]) < 0.1 * surface, f"chute: no slip at the base ({b['v_b']:.4f} m/s)")
    check(b["rms"] < lin["rms"] / 3, f"chute: Bagnold's residual {b['rms']:.4f} m/s under a "
          f"third of a linear profile's {lin['rms']:.4f} m/s")
    check(1.3 <= free["p"] <= 1.9, f"chute: the fitted exponent {free['p']:.2f} is near 3/2")
    f, _ = final("chute")
    check(len(f["x"]) == 800 and np.all((f["x"] > -1e-3) & (f["x"] < 0.021) &
                                        (f["y"] > -1e-3) & (f["y"] < 0.011)),
          "chute: 800 particles, inside the period")
    print(f"chute: Q = {r['flow_rate']:.4f} kg/s (long run {q_long}), Bagnold h "
          f"{b['h'] * 1e3:.1f} mm, top {r['top'] * 1e3:.1f} mm, rms {b['rms']:.4f} m/s (linear "
          f"{lin['rms']:.4f}), exponent {free['p']:.2f}")


def clumps():
    run([case("clumps", 0.6, "clumps")])
    sys.path.insert(0, os.path.join(EXAMPLES, "clumps"))
    import clumps_numbers as ex           # noqa: E402  (the example's own analysis)
    v = ex.numbers(os.path.join(work, "clumps"))
    s, b = v["series"], v["bed"]
    t, n = s["time"], s["particles"]
    members = ex.N_RODS * ex.MEMBERS
    check(n[(t >= ex.END + 0.01) & (t <= ex.OPEN)].min() == members
          and b["rods"] == ex.N_RODS,
          f"clumps: {ex.N_RODS} rods, {members} members, once the inflow is done")
    # one insertion behind at most: every time a reach diameter (4 mm) takes at 1 m/s
    check(0 <= v["lag"] <= ex.MEMBERS * ex.RATE * 0.0041, f"clumps: the inflow at most one "
          f"insertion behind floor(rate t) x 3 ({v['lag']:g} members)")
    check(v["conserved"], "clumps: particles + removed = 3000 at every row after the inflow")
    check(v["whole"], "clumps: removed a multiple of 3 at every row (a rod leaves whole)")
    check(v["closed"], "clumps: none removed before the plug moves (0.4 s)")
    check(s["removed"][-1] > 300, f"clumps: it discharges ({s['removed'][-1]:g} removed)")
    check(0.50 <= b["phi"] <= 0.72, f"clumps: packing fraction {b['phi']:.3f} of a random "
          "packing of rods (0.50 to 0.72)")
    check(b["flat"] > 0.55, f"clumps: {b['flat']:.3f} of the rods lie within 30 degrees of "
          "the horizontal (0.5 at random)")
    w = v["rate"] * ex.MASS
    lo, hi = ex.beverloo(b["phi"], 0.55, 2.9), ex.beverloo(b["phi"], 0.65, 1.3)
    check(lo <= w <= hi, f"clumps: discharge rate {w * 1e3:.2f} g/s in Beverloo's band "
          f"{lo * 1e3:.2f} to {hi * 1e3:.2f} g/s")
    print(f"clumps: packing fraction {b['phi']:.3f}, flat {b['flat']:.3f}, top "
          f"{b['top'] * 1e3:.1f} mm, rate {v['rate']:.0f} rods/s = {w * 1e3:.2f} g/s (band "
          f"{lo * 1e3:.2f} to {hi * 1e3:.2f})")


def agglomerate():
    path = case("agglomerate", 0.002, "agglomerate")
    run([path])
    sys.path.insert(0, os.path.join(EXAMPLES, "agglomerate"))
    import fragments as ex                # noqa: E402  (the example's own analysis)
    v = ex.numbers(os.path.join(work, "agglomerate"))
    s = v["series"]
    check(v["bonds"] == v["bonds_made"], f"agglomerate: {v['bonds']} bonds made, "
          f"{v['bonds_made']} pairs within the gap")
    check(v["broken_series"] == v["broken_checkpoint"] > 0
          and v["intact_slots"] == 2 * (v["bonds_made"] - v["broken_checkpoint"]),
          f"agglomerate: broken {v['broken_series']} (series.csv) = {v['broken_checkpoint']} "
          "(bonds made, not in the end checkpoint; each intact bond in both slots)")
    e = s["kinetic_translational"] + s["kinetic_rotational"] + s["bond_energy"]
    check(e.max() <= v["kinetic0"] * (1 + 1e-9) and e[-1] < 0.5 * v["kinetic0"],
          f"agglomerate: kinetic + bond energy at most {e.max():.6g} J, at the end "
          f"{e[-1]:.6g} J, kinetic energy at the start {v['kinetic0']:.6g} J")
    check(v["broken_height"] < 0, f"agglomerate: the broken bonds' mean height "
          f"{v['broken_height']:+.3f} ball radii from the centre (the impact side)")
    f = v["fragments"]
    check(abs(v["mass"] - v["mass0"]) <= 1e-12 * v["mass0"] and f[0] < 0.8,
          f"agglomerate: it fragments (largest fragment {f[0]:.4f} of the mass)")
    # the same Delta: strengths and speed doubled
    with open(path) as fh:
        text = fh.read().replace("strength = 1e6", "strength = 2e6")
    src = os.path.join(EXAMPLES, "agglomerate", "agglomerate.csv")
    with open(src) as fh, open(os.path.join(work, "twice.csv"), "w") as g:
        g.write(fh.read().replace(",0,0,-6\n", ",0,0,-12\n"))
    text = re.sub(r"file = '[^']*agglomerate.csv'", "file = 'twice.csv'", text)
    text = re.sub(r"dir = '[^']*'", "dir = 'twice'", text)
    with open(os.path.join(work, "twice.nml"), "w") as fh:
        fh.write(text)
    run(["twice.nml"])
    t = table("twice", "series.csv")
    d2 = t["bonds_broken"][-1] / t["bonds"][0]
    check(t["bonds"][0] == v["bonds"] and max(d2, v["damage"]) / min(d2, v["damage"]) <= 1.6,
          f"agglomerate: damage ratio {v['damage']:.4f}, twice the strength at twice the "
          f"speed {d2:.4f} (the same Delta: within a factor 1.6)")
    print(f"agglomerate: {v['bonds']} bonds, damage ratio {v['damage']:.4f} (twice as strong, "
          f"twice as fast: {d2:.4f}), largest fragments {f[0]:.4f}, {f[1]:.4f}, broken bonds' "
          f"mean height {v['broken_height']:+.3f}")


def restart():
    one, two, again = (case("restart", 0.3, out) for out in ("one", "two", "again"))
    for path in (one, two, again):                   # half-way: 0.15 s
        with open(path) as f:
            text = f.read()
        with open(path, "w") as f:
            f.write(text.replace("checkpoint_interval = 0.25", "checkpoint_interval = 0.15"))
    run([one])
    run([two], ranks=2)
    shutil.copytree(os.path.join(work, "one"), os.path.join(work, "again"))
    os.remove(os.path.join(work, "again", "input.nml"))
    shutil.copy(again, os.path.join(work, "again", "input.nml"))
    point = os.path.join(work, "again", "checkpoints", "checkpoint_000000015000.h5")
    check(os.path.exists(point), "restart: a checkpoint at 0.15 s")
    run(["--restart", point, again], ranks=2)
    names = ["series.csv", "probes.csv", "final.csv", "snapshots.xmf"] + sorted(
        os.path.relpath(p, os.path.join(work, "one"))
        for p in glob.glob(os.path.join(work, "one", "snapshots", "*.h5")))
    check(len(names) == 4 + 7, f"restart: 7 snapshots ({len(names) - 4})")
    for name in names:
        for other in ("two", "again"):
            a, b = os.path.join(work, "one", name), os.path.join(work, other, name)
            if name.endswith(".h5"):
                check(h5_same(a, b), f"restart: every dataset and attribute of {name} of "
                      f"{other} is that of the 1-rank run, bit for bit")
            else:
                with open(a, "rb") as f, open(b, "rb") as g:
                    check(f.read() == g.read(), f"restart: {name} of {other} is that of the "
                          "1-rank run, byte for byte")
    print(f"restart: {len(names)} files compared, 1 rank, 2 ranks, restarted on 2 ranks")


{"pour": pour, "hopper": hopper, "drum": drum, "impact": impact, "chute": chute,
 "clumps": clumps, "agglomerate": agglomerate, "restart": restart}[example]()
finish()
