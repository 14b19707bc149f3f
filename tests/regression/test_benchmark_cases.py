# SPDX-License-Identifier: BSD-3-Clause
"""Reduced versions of the benchmark cases (cases/make_cases.py: the same
namelists, with fewer particles and Young's moduli scaled down so that dt grows with the
square root of the scale), prepared and run as the full ones are, checked for what must
hold whatever the size:

1. silo: filling and settling, then discharge: particles + removed is the initial count in
   every row; particles are only removed below the outlet plane, 0.02 m under the orifice;
   the count above the orifice plane never exceeds the particles left and falls; the
   velocity histogram adds up to the particles above the orifice at its time. With MPIEXEC,
   the discharge again on 2 ranks: every file the same byte for byte (the silo empties, and
   particles parked by the outlet on both ranks at once must not meet as ghosts: they did,
   at one point, when their parking place came from their position in a rank's store).
2. drum: two layers settled, then 0.4 s of rotation at omega = (0, -2, 0): no particle
   leaves the closed drum (in every snapshot and the final state its centre is at most
   0.1 - R + 1e-4 from the axis and |y| <= 0.03 - R + 1e-4), none is removed, the zone
   counts never exceed the particles of their material, and the bed climbs on the rising
   side x > 0 (the centre of mass of all particles moves to x > 0); the same bed in the
   drum made of two wall files (turning cylinder, frictionless end discs): no particle lost
   or outside, through the discs' edges where the two walls meet included.
3. impact: a bed of 4000 settled in the box, the steel impactor dropped on it: particle
   count conserved; while the impactor ploughs through the bed (from the first sample at
   which the bed's push exceeds its weight) its downward speed falls at every sample
   (0.1 ms), until it is 2 mm from the floor; it does not pass the floor (its
   lowest point stays within 2 mm of it: the soft floor contact overlaps that much).
4. the analysis of doc/results/benchmarks.md: scripts/post/plot-benchmarks draws the figures
   of these outputs; its flow-rate fit recovers the slope of an exact line, and its Beverloo
   k for the paper's flow-rate ratio of 3.10 is the paper's 1.26; it finds the reduced silos' fillings
   by their names (the soft ones apart) and takes the rates of those that ran to the case's
   end; the drum's oscillation amplitude, of a cosine whose amplitude halves every second,
   is twice that amplitude in each whole second; the flow rate by second, of a count whose
   rate steps, is each second's; two drum runs set apart by known amounts
   from a known time are found that far apart after it and not before; the mean distance
   of each material from the bed's centre, of spheres set at known distances, is those; a
   preparation's end state (energies, centre of mass, spin by eighths of height) is read
   from files made for it.
5. the namelists in cases/silo, cases/drum and cases/impact are make_cases.py's: each it
   writes is there, with the same text, and there is no other (one edited by hand, or one it
   no longer writes, fails); none of them is a variant. Every variant, written into a folder
   under output/ as scripts/bench/prepare-benchmark writes it, finds its walls and names the
   particle file of its preparation in output/benchmark/; a filling of another seed differs
   from its case only in the seed, its outputs' folder and the particle file it reads.
usage: test_benchmark_cases.py DEM WORKDIR [MPIEXEC]"""
import math
import os
import re
import shutil
import subprocess
import sys
from importlib.machinery import SourceFileLoader

import h5py
import numpy as np

from regression_util import ROOT, check, finish

sys.path.insert(0, os.path.join(ROOT, "cases"))
import make_cases as mc     # noqa: E402
import make_geometry as mg  # noqa: E402

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
mpiexec = sys.argv[3] if len(sys.argv) > 3 else None
shutil.rmtree(work, ignore_errors=True)
for folder in mc.FOLDERS:            # the case folders' walls, for the cases run here
    shutil.copytree(os.path.join(ROOT, "cases", folder), os.path.join(work, "cases", folder),
                    ignore=shutil.ignore_patterns("*.nml", "*.md"))
SCALE = 1e-3

# 5. (first: it needs no run) the committed namelists against their generator; the variants
written = mc.files()
here = {os.path.join(f, n) for f in mc.FOLDERS for n in os.listdir(os.path.join(ROOT, "cases", f))
        if n.endswith(".nml")}
check(here == set(written), "cases: namelists not written by make_cases.py: "
      f"{sorted(here - set(written))}; missing: {sorted(set(written) - here)}")
for name in sorted(here & set(written)):
    with open(os.path.join(ROOT, "cases", name)) as f:
        check(f.read() == written[name], f"cases/{name} differs from what make_cases.py "
              "writes (run it)")
variants = sorted(n for n in mc.cases() if mc.is_variant(n))
check(len(variants) > 50 and not any(mc.is_variant(n) for n in written),
      f"{len(variants)} variants, none of them committed")
elsewhere = os.path.join(work, "output", "cases")
for name in variants:
    with open(mc.write(name, elsewhere)) as f:
        files = re.findall(r"file = '([^']+)'", f.read())
    walls = [os.path.join(elsewhere, p) for p in files if p.endswith(".stl")]
    check(walls and all(os.path.samefile(p, os.path.join(ROOT, "cases", mc.folder(name),
                                                         os.path.basename(p)))
                        for p in walls), f"{name} written elsewhere: its walls {walls}")
    prepared = [os.path.normpath(os.path.join(elsewhere, p)) for p in files
                if p.endswith("final.csv")]
    check(all(p.startswith(os.path.join(ROOT, mc.OUT, "prepare_")) for p in prepared),
          f"{name} written elsewhere: its particle files {prepared}")
for name in (n for n in variants if "_seed" in n):
    base = re.sub(r"_seed\d+", "", name)
    a, b = (mc.cases()[n].splitlines() for n in (name, base))
    keys = {re.sub(r"^&(\w+).*", r"\1", x) for x, y in zip(a, b) if x != y}
    check(len(a) == len(b) and keys <= {"insert", "output", "particle_file"}
          and all(re.sub(r"_seed\d+|seed = \d+", "", x) == re.sub(r"seed = \d+", "", y)
                  for x, y in zip(a, b)),
          f"{name} differs from {base} in more than its seed, outputs and particle file")


def run(name, text, ranks=1):
    path = os.path.join(work, "cases", mc.folder(name), name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    cmd = [dem, path]
    if ranks > 1:
        cmd = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] + cmd
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=600)
    check(r.returncode == 0, f"{name}: exit {r.returncode}: {r.stderr.strip()[-2000:]}")
    return os.path.join(work, mc.OUT, name)


def table(out, name):
    return np.genfromtxt(os.path.join(out, name), delimiter=",", names=True)


def snapshots(out):
    folder = os.path.join(out, "snapshots")
    for name in sorted(os.listdir(folder)):
        with h5py.File(os.path.join(folder, name)) as f:
            yield {k: f["particles"][k][()] for k in f["particles"]}


# 1. silo
N_SILO = 800
z_o = mc.SILO["small"]["z_o"]
run("prepare_silo_M1_small_800", mc.prepare_silo("M1", "small", n=N_SILO, scale=SCALE,
                                                 t_end=0.4))
silo = mc.silo("M1", "small", n=N_SILO, scale=SCALE, t_end=0.5, interval=0.02, histogram_time=0.1)
out = run("silo_M1_small_800", silo)
s, p = table(out, "series.csv"), table(out, "probes.csv")
check(np.all(s["particles"] + s["removed"] == N_SILO), "silo: particles + removed = 800")
check(s["removed"][-1] > 0, f"silo: particles leave ({s['removed'][-1]:.0f} removed)")
check(np.all(p["silo_M1"] <= s["particles"]), "silo: count above the orifice <= particles")
check(p["silo_M1"][-1] < p["silo_M1"][0], "silo: the count above the orifice falls")
lowest = min(snap["position"][:, 2].min(initial=np.inf) for snap in snapshots(out))
check(lowest >= z_o - 0.02 - 0.01, f"silo: no particle far below the outlet plane ({lowest})")
h = table(out, "histogram_velocity.csv")
k = np.flatnonzero(p["time"] >= 0.1 - 1e-12)[0]
check(all(h[c].sum() == p["silo_M1"][k] for c in ("radial", "angular", "vertical")),
      "silo: the histograms add up to the particles above the orifice")
if mpiexec:
    out2 = run("silo_M1_small_800_2", silo.replace("/silo_M1_small_800'", "/silo_M1_small_800_2'"),
               ranks=2)
    for name in ("series.csv", "probes.csv", "histogram_velocity.csv", "final.csv"):
        with open(os.path.join(out, name), "rb") as a, open(os.path.join(out2, name), "rb") as b:
            check(a.read() == b.read(), f"silo on 2 ranks: {name} as on 1 rank")

# 2. drum
N2, N1 = 150, 500
run("prepare_drum_1", mc.prepare_drum(1, n_m2=N2, scale=SCALE, t_end=0.3))
run("prepare_drum_2", mc.prepare_drum(2, n_m2=N2, n_m1=N1, scale=SCALE, t_end=0.3))
out = run("drum", mc.drum(scale=SCALE, t_end=0.4, interval=0.02))
s, p = table(out, "series.csv"), table(out, "probes.csv")
check(np.all(s["particles"] == N1 + N2) and np.all(s["removed"] == 0), "drum: no loss")
for m, n in (("M1", N1), ("M2", N2)):
    check(np.all(p[f"zone1_{m}"] + p[f"zone2_{m}"] <= n), f"drum: zone counts of {m} <= {n}")


def outside_drum(out):
    """Particle positions, over the snapshots and final.csv, not inside the drum."""
    f = table(out, "final.csv")
    states = [*snapshots(out), {"position": np.column_stack([f["x"], f["y"], f["z"]]),
                                "radius": f["radius"]}]
    outside = 0
    for state in states:
        x, r = state["position"], state["radius"]
        outside += np.count_nonzero(np.hypot(x[:, 0], x[:, 2]) > 0.1 - r + 1e-4)
        outside += np.count_nonzero(np.abs(x[:, 1]) > 0.03 - r + 1e-4)
    return outside


check(outside_drum(out) == 0, f"drum: {outside_drum(out)} particle positions outside the drum")
com_x = [np.nanmean([row["com_M1_x"], row["com_M2_x"]]) for row in p]
check(com_x[0] < 0.002 and com_x[-1] > 0.005,
      f"drum: the bed climbs on the rising side (centre x {com_x[0]:.4f} -> {com_x[-1]:.4f})")
# the same bed in the drum of two wall files, the turning cylinder and frictionless end discs
out = run("drum_smooth", mc.drum(scale=SCALE, t_end=0.4, interval=0.02, smooth_ends=True))
s = table(out, "series.csv")
check(np.all(s["particles"] == N1 + N2), "drum with smooth ends: no loss")
check(outside_drum(out) == 0,
      f"drum with smooth ends: {outside_drum(out)} particle positions outside the drum")

# 3. impact
N_BED = 4000
# (the impact at a tenth of the stiffness: at a hundredth the impactor presses the spheres
# under it deeper than 0.9 of their radius, at a thousandth through one another, which the
# overlap guard stops)
SCALE_IMPACT = 1e-1
run("prepare_impact_4000", mc.prepare_impact(N_BED, scale=SCALE_IMPACT, t_end=0.2))
with open(os.path.join(work, mc.OUT, "prepare_impact_4000", "final.csv")) as f:
    top = max(float(line.split(",")[5]) for line in f.readlines()[1:]) + 0.001
# (the impactor set 1 mm above the bed, at the speed of its fall from the case's start, and
# the run from there: the free fall before it takes two thirds of the case's first 40 ms)
z0 = top + 0.011
v0 = math.sqrt(5.0**2 + 2 * 9.81 * (0.06 - z0))
out = run("impact_4000", mc.impact(N_BED, scale=SCALE_IMPACT, t_end=0.015, interval=1e-4)
          .replace("position = 0, 0, 0.06, velocity = 0, 0, -5 /",
                   f"position = 0, 0, {z0!r}, velocity = 0, 0, {-v0!r} /"))
s, p = table(out, "series.csv"), table(out, "probes.csv")
check(np.all(s["particles"] == N_BED + 1), "impact: particle count conserved")
z, vz = p["impactor_z"], p["impactor_vz"]
inside = (z - 0.01 < top) & (z - 0.01 > mc.FLOOR + 0.002) & (np.cumsum(vz > 0) == 0)
speed = -vz[inside]
speed = speed[np.argmax(speed):]      # from when the bed's push exceeds the weight
check(len(speed) >= 5, f"impact: {len(speed)} samples in the bed")
check(np.all(np.diff(speed) < 0), f"impact: the impactor slows in the bed ({speed})")
check(z.min() - 0.01 > mc.FLOOR - 0.002, f"impact: the impactor stays above the floor "
                                         f"(lowest {z.min() - 0.01 - mc.FLOOR:.4f} m above)")

# 4. analysis
plot = os.path.join(ROOT, "scripts", "post", "plot-benchmarks")
# the figures of another output folder go into that folder, not doc/figures/
docs = os.path.join(ROOT, "doc", "figures")
def stamps():
    return {f: os.stat(os.path.join(docs, f)).st_mtime_ns for f in os.listdir(docs)}


before = stamps()
r = subprocess.run([sys.executable, plot, "--output-dir", os.path.join(work, mc.OUT)],
                   capture_output=True, text=True)
check(r.returncode == 0, f"plot-benchmarks: exit {r.returncode}: {r.stderr.strip()}")
for png in ("silo", "silo_histogram", "silo_section", "drum"):
    check(os.path.exists(os.path.join(work, mc.OUT, f"benchmark_{png}.png")),
          f"benchmark_{png}.png beside the outputs")
check(stamps() == before, "plot-benchmarks on another output folder left doc/figures/ as it was")
pb = SourceFileLoader("plot_benchmarks", plot).load_module()
t = np.linspace(0.0, 1.0, 101)
line = np.zeros(101, dtype=[("time", float), ("silo_M1", float)])
line["time"], line["silo_M1"] = t, 20000.0 - 7000.0 * t
w, dev, keep = pb.flow_rate(line, "M1")
check(abs(w - 7000.0) < 1e-6 and dev < 1e-6 and keep.sum() == 91, f"flow rate of a line {w}")
# rows every 0.1 s at dt = 75 us: every 1333 steps, 0.099975 s apart; the row a fraction of
# a step before 0.1 s starts the fit
line = np.zeros(51, dtype=[("time", float), ("silo_M1", float)])
line["time"] = np.arange(51) * 1333 * 7.5e-5
line["silo_M1"] = 100000.0 - 8000.0 * line["time"]
w, dev, keep = pb.flow_rate(line, "M1")
check(keep.sum() == 50 and keep[1] and abs(w - 8000.0) < 1e-6,
      f"flow rate of a line on 75 us steps {w}, from row {np.argmax(keep)}")
# by second: a count whose rate steps from 8000 to 6000 particles/s at 1.5 s, rows every 0.1 s
line = np.zeros(31, dtype=[("time", float), ("silo_M1", float)])
line["time"] = np.arange(31) * 0.1
line["silo_M1"] = 100000.0 - 8000.0 * np.minimum(line["time"], 1.5) - 6000.0 * np.maximum(
    line["time"] - 1.5, 0.0)
by = pb.rates_by_second(line, "M1", line["time"] >= 0.1 - 1e-4)
check(len(by) == 3 and abs(by[0] - 8000.0) < 1e-6 and abs(by[2] - 6000.0) < 1e-6
      and abs(by[1] - 7000.0) < 1e-6, f"rates by second {by}")   # the step mid-second
check(abs(pb.beverloo_k(3.10) - 1.26) < 0.005, f"Beverloo k for 3.10: {pb.beverloo_k(3.10)}")
# the drum's oscillation amplitude, second by second: a cosine of period 0.5 s (its extremes
# on the samples, every 0.01 s) of amplitude 1000, 500, 250 in the first three seconds, and
# the start of a fourth (not whole, so not counted): ranges 2000, 1000, 500
t = np.arange(351) * 0.01
wave = np.zeros(351, dtype=[("time", float), ("zone2_M1", float)])
wave["time"] = t
wave["zone2_M1"] = 3000.0 + 1000.0 * 0.5 ** np.floor(t + 1e-9) * np.cos(4 * np.pi * t)
expected = [2000, 1000, 500]
got = pb.oscillation(wave)
check(got == expected, f"oscillation ranges {got} (expected {expected})")
# two drum runs apart by 7 M1 in Zone 2 and 3 mm of M1's centre of mass from t = 2 s on, the
# second sampled twice as often: apart by that much over the whole run, by nothing to 1 s
fields = [f"{z}_{m}" for z in ("zone1", "zone2") for m in ("M1", "M2")] + [
    f"com_{m}_{c}" for m in ("M1", "M2") for c in "xyz"]
runs = []
for every in (0.1, 0.05):
    r = np.zeros(int(round(3.0 / every)) + 1,
                 dtype=[("time", float)] + [(f, float) for f in fields])
    r["time"] = np.arange(len(r)) * every
    r["zone2_M1"], r["com_M2_z"] = 1000.0, -0.05
    runs.append(r)
late = runs[1]["time"] >= 2.0 - 1e-9
runs[1]["zone2_M1"][late] += 7
runs[1]["com_M1_x"][late] += 0.003
apart = pb.drum_difference(*runs)
whole, first = apart.split("; ")[0], apart.split("; ")[1]
check("'zone2_M1': 7," in whole and "3.0 mm (M1), 0.0 mm (M2)" in whole
      and first.startswith("to 1.00 s") and "'zone2_M1': 0," in first
      and "0.0 mm (M1)" in first, f"drum runs apart: {apart}")
# radial sorting: M1 and M2 spheres set symmetrically about a point, 20 and 50 mm from it,
# in a snapshot of the case's layout: the bed's centre is that point
import h5py  # noqa: E402
d = os.path.join(work, "sorting", "snapshots")
os.makedirs(d)
square = np.array([[1, 0], [-1, 0], [0, 1], [0, -1]], float)
xz = np.r_[0.02 * square, 0.05 * square] + [0.01, -0.04]
with h5py.File(os.path.join(d, "snapshot_000000000000.h5"), "w") as f:
    f["materials/name"] = np.array([b"M1", b"M2", b"steel"])
    f["particles/material"] = np.r_[np.full(4, 1), np.full(4, 2)]
    f["particles/position"] = np.c_[xz[:, 0], np.linspace(-0.01, 0.01, 8), xz[:, 1]]
    f["particles/velocity"] = np.zeros((8, 3))
    f["particles/radius"] = np.r_[np.full(4, 0.001), np.full(4, 0.002)]
    f["time"] = 1.0
sorting = pb.radial_sorting(os.path.dirname(d))
check(sorting.endswith("1.0 s 20.0/50.0"), f"radial sorting: {sorting}")
# a preparation's state at its end: spheres at heights 0-7 mm, one to an eighth of the bed's
# height, spinning at 0-7 rad/s about x, y or z in turn
d = os.path.join(work, "rest", "prepare_bed")
os.makedirs(d)
with open(os.path.join(d, "series.csv"), "w") as f:
    f.write("time,kinetic_translational,kinetic_rotational\n0,1,1\n0.5,2e-06,3e-07\n")
with open(os.path.join(d, "final.csv"), "w") as f:
    f.write("id,material,radius,x,y,z,vx,vy,vz,wx,wy,wz\n")
    for k in range(8):
        w = [0.0, 0.0, 0.0]
        w[k % 3] = float(k)
        f.write(f"{k + 1},M1,0.001,0,0,{k * 1e-3},0,0,0,{w[0]},{w[1]},{w[2]}\n")
rest = pb.preparations(os.path.dirname(d), work)
check("prepare_bed: t = 0.50 s, kinetic 2e-06 J (translation), 3e-07 J (rotation); centre of "
      "mass z = 3.5 mm; mean spin by eighths of height 0 1 2 3 4 5 6 7 rad/s" in rest,
      f"a preparation at its end: {rest}")
# the fillings' rates: exact lines, in folders named as make_cases.py names the reduced silos;
# a discharge stopped before the case's end, and a folder of another name, left out
fake = os.path.join(work, "fillings")
exact = {1: 7000.0, 2: 7100.0, 3: 6900.0, 4: 7300.0}
for seed, w in exact.items():
    d = os.path.join(fake, mc.silo_name("M1", "small", mc.SILO_REDUCED, seed))
    os.makedirs(d)
    t = np.linspace(0.0, mc.SILO_REDUCED_T_END if seed < 4 else 0.3, 51)
    np.savetxt(os.path.join(d, "probes.csv"), np.c_[t, 20000.0 - w * t], delimiter=",",
               header="time,silo_M1", comments="")
shutil.copytree(d, os.path.join(fake, mc.silo_name("M1", "small", mc.SILO_REDUCED) + "_copy"))
soft = os.path.join(fake, mc.silo_name("M1", "large", mc.SILO_REDUCED, 2, soft=True))
shutil.copytree(d, soft)
found = pb.silo_outputs(fake)
check(list(found) == [("M1", "small", mc.SILO_REDUCED)] and sorted(found[list(found)[0]])
      == [1, 2, 3, 4], f"the fillings' folders: {found}")
found_soft = pb.silo_outputs(fake, soft=True)
check(found_soft == {("M1", "large", mc.SILO_REDUCED): {2: soft}},
      f"the soft fillings' folders: {found_soft}")
rates = pb.filling_rates(found, "M1")
check(list(rates) == ["small"] and sorted(rates["small"]) == [1, 2, 3]
      and all(abs(rates["small"][k] - exact[k]) < 1e-6 for k in (1, 2, 3)),
      f"the fillings' flow rates: {rates}")
finish()
