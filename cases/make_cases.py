#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the namelists of the benchmark paper's three case studies (Dosta et al. 2024) with
the definitions of its Tables 4-5 and of the published drivers (materials M1, M2, steel;
g = 9.81 m/s^2; spheres; no rolling resistance; the default contact law, the LIGGGHTS/MUSEN
form of Hertz-Mindlin). Run the cases from the repository root: their outputs go to
output/benchmark/<case>/, and a preparation's final.csv there is the particle file of the
case of the same name. File names in a namelist are relative to the namelist's folder.

  cases/make_cases.py            writes the committed cases into silo/, drum/ and impact/
  cases/make_cases.py NAME...    writes the named cases (file names without .nml, variants
                                 or committed ones) into output/cases/ (--dir DIR: into DIR)

The committed cases (each folder's README.md says how to prepare and run them):

  silo/prepare_silo_<M1|M2>_<small|large>.nml  fill the silo (orifice closed by a plane)
                                          with 100 000 spheres of 4 mm and let them settle
  silo/silo_<M1|M2>_<small|large>.nml     discharge for 5 s; probes: particles above the
                                          orifice plane, velocity histograms at 2 s
  silo/[prepare_]silo_<M>_<orifice>_20000.nml  the same with 20 000 spheres, run here
  drum/prepare_drum_1.nml, prepare_drum_2.nml  8 000 M2 of 4 mm settled in the drum, then
                                          30 000 M1 of 2 mm settled on top
  drum/drum.nml                           5 s at 2 rad/s about y, omega = (0, -2, 0) as in
                                          MercuryDPM; probes: zone counts, centres of mass,
                                          the torque on the walls (drive)
  drum/prepare_drum_slice_<1|2>.nml, drum_slice.nml  the same in a quarter of the drum's
                                          depth (0.015 m, 2 000 M2 and 7 500 M1), run here
  impact/prepare_impact_<N>.nml           N = 25 000, 50 000, 100 000 M1 of 2 mm settled in
                                          the box
  impact/impact_<N>.nml                   the steel impactor (R = 10 mm) from z = 0.06 m at
                                          5 m/s for 0.1 s; probe: its state every 1 ms

The variants, written on demand (scripts/bench/prepare-benchmark writes those it prepares):

  [prepare_]silo_M1_<orifice>_20000_seed<k>  the reduced M1 silos from fillings of seeds
                                          k = 2-6
  [prepare_]silo_<M>_<orifice>[_20000]_soft[_seed<k>]  the silos with the soft drum's
                                          materials (below), at dt = 50 us (reduced: M1
                                          three fillings, M2 one)
  resettle_silo_<M>_small_soft_dt<us>     the full soft small silo's filling run on for
                                          0.06 s, orifice closed, at 50, 75 (and M2: 100)
                                          us: does the resting bed stay at rest?
  drum_slice_smooth                       the slice with frictionless end discs
  [prepare_]drum[_slice]_soft[_<1|2>]     MercuryDPM's -soft drum (E of M1 and M2 2e-3
                                          times as large, output every 0.01 s; dt 5e-5 s,
                                          half its 1e-4 s, within our stability bound),
                                          full and in the slice; drum_slice_soft_dt25us:
                                          the slice at dt 25 us (the error of dt 50 us);
                                          [prepare_]drum_slice_soft_seed2[_<1|2>]: a slice
                                          of other seeds
  [prepare_]impact_25000_seed<k>          the 25 000 bed of seeds k = 2-10 (the ensemble)

The functions take the particle count and a stiffness scale, so that
tests/regression/test_benchmark_cases.py can make reduced versions of the same cases."""
import argparse
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = "output/benchmark"                 # outputs, relative to the repository root
FROM_HERE = "../../" + OUT               # the same, relative to a case folder
FOLDERS = ("silo", "drum", "impact")     # the case folders, beside this file
VARIANT_MARKS = ("_seed", "_soft", "_smooth", "resettle_")   # in the names of the variants

MATERIALS = {"M1": (2500.0, 1.0e9), "M2": (2000.0, 0.5e9), "steel": (7200.0, 210.0e9)}
PAIRS = [("M1", "M1", 0.5, 0.3), ("M1", "M2", 0.45, 0.2), ("M1", "steel", 0.4, 0.2),
         ("M2", "M2", 0.4, 0.4), ("M2", "steel", 0.4, 0.2), ("steel", "steel", 0.6, 0.5)]
SILO = {"small": dict(r_o=0.02, z_o=-0.0593008, top=0.320699),
        "large": dict(r_o=0.03, z_o=-0.0554222, top=0.314578)}
SILO_DT = {"M1": 1.5e-6, "M2": 2.0e-6}
SILO_PREPARE_DT = {"M1": 4.0e-6, "M2": 5.0e-6}     # about 0.24 Rayleigh times of the 4 mm spheres
SILO_REDUCED = 20000                               # particles in the reduced silos run here
SILO_FILLINGS = 6                                  # reduced M1 silos: fillings of seeds 1-6
SILO_REDUCED_T_END = 0.5                           # reduced silos' discharge [s]
SILO_REDUCED_INTERVAL = 0.01                       # ... and the time between their counts [s]
SILO_SOFT_DT = 5.0e-5                              # soft silos [s]: 0.10 and 0.13 Rayleigh times
                                                   # of the 4 mm M2 and M1 spheres; 75 and 100
                                                   # us (0.2 of M1's, M2's) let full beds rattle
                                                   # (doc/results/benchmarks.md)
SILO_SOFT_CHECKPOINT = 0.1                         # full soft silos: checkpoint interval [s]
SILO_SOFT_FILLINGS = 3                             # reduced soft M1 silos: seeds 1-3
SOFT = 2.0e-3                            # MercuryDPM's -soft drum: E of M1, M2 times this
DRUM_SOFT_DT = 5.0e-5                    # the soft drums' dt [s] (MercuryDPM's 1e-4 is above
                                         # the bound, 5.34e-5, of our default contact law)
DRUM_SOFT_INTERVAL = 0.01                # ... and their output interval, MercuryDPM's [s]
FLOOR = -0.0902431                        # impact box floor [m]
IMPACTOR_ID = 1000000000
BIG = "1e30"


def materials(scale=1.0, steel_scale=None):
    """&material and &pair groups; Young's moduli of M1 and M2 times `scale`, steel's times
    `steel_scale` (default `scale`: the reduced test versions; 1 for the soft cases)."""
    factor = {"M1": scale, "M2": scale, "steel": scale if steel_scale is None else steel_scale}
    text = "".join(f"&material name = '{m}', density = {rho}, "
                   f"youngs_modulus = {e * factor[m]:g}, poisson_ratio = 0.2 /\n"
                   for m, (rho, e) in MATERIALS.items())
    return text + "".join(f"&pair materials = '{a}', '{b}', restitution = {e}, "
                          f"friction = {mu} /\n" for a, b, e, mu in PAIRS)


def case_materials(scale, soft):
    """A case's &material and &pair groups: `soft` is MercuryDPM's -soft variant (M1 and M2
    2e-3 times as stiff, steel as it is), else `materials(scale)`."""
    return materials(SOFT, 1.0) if soft else materials(scale)


def run(dt, t_end, extra=""):
    return f"&run dt = {dt:g}, t_end = {t_end:g}, gravity = 0, 0, -9.81{extra} /\n"


def output(name, interval, snapshots, extra=""):
    return (f"&output dir = '{OUT}/{name}', interval = {interval:g}, "
            f"snapshot_interval = {snapshots:g}{extra} /\n")


def soft_checkpoints(n, soft):
    """The full soft silos' checkpoints (&output keys), so that a run stopped by the end of a
    session loses little (dem --resume continues it); none for the others."""
    return (f", checkpoint_interval = {SILO_SOFT_CHECKPOINT:g}, checkpoint_keep = 2"
            if soft and n == 100000 else "")


def silo_walls(orifice):
    return (f"&wall_mesh file = 'silo_{orifice}.stl', material = 'steel' /\n")


def orifice_closed(orifice):
    """The plane that closes the orifice while a filling settles."""
    return (f"&wall_plane material = 'steel', point = 0, 0, {SILO[orifice]['z_o']}, "
            f"normal = 0, 0, 1, half_width = 0.035 /\n")


def silo_name(material, orifice, n=100000, seed=1, soft=False):
    return (f"silo_{material}_{orifice}" + (f"_{n}" if n != 100000 else "")
            + ("_soft" if soft else "") + (f"_seed{seed}" if seed > 1 else ""))


def prepare_silo(material, orifice, n=100000, scale=1.0, t_end=2.0, seed=1, soft=False):
    """Spheres of 4 mm dropped into the silo from a cylinder above the cone (0.9 m high, so
    that random insertion has room), onto a plane that closes the orifice; settled, at a
    larger dt than the discharge (the packing's settling is not measured); `soft`: with the
    soft drum's materials, at the soft discharge's dt."""
    s = SILO[orifice]
    z_j = 0.1 - (s["r_o"] - s["z_o"])                # where cone and cylinder meet
    height = min(0.9, 0.9 * n / 100000.0 + 0.05)
    name = "prepare_" + silo_name(material, orifice, n, seed, soft)
    dt = SILO_SOFT_DT if soft else SILO_PREPARE_DT[material] / scale ** 0.5
    return (run(dt, t_end,
                f", stop_kinetic_energy = {n * 1e-10:g}")
            + output(name, 0.01, 0.0, soft_checkpoints(n, soft)) + case_materials(scale, soft)
            + f"&insert n = {n}, material = '{material}', radius_min = 0.002, "
              f"radius_max = 0.002, region = 'cylinder', cylinder_base = 0, 0, {z_j:.7g}, "
              f"cylinder_radius = 0.096, cylinder_height = {height:g}, seed = {seed} /\n"
            + silo_walls(orifice) + orifice_closed(orifice))


def silo(material, orifice, n=100000, scale=1.0, t_end=5.0, interval=0.1, histogram_time=2.0,
         snapshots=0.5, dt=None, integrator="symplectic_euler", name=None, seed=1, soft=False):
    """Discharge: the settled packing without the plane; particles removed 0.02 m below the
    orifice plane (MercuryDPM's deletion boundary); remaining particles counted above it
    (dt, integrator and output name other than the case's for the speed-against-error study;
    `soft`: the soft drum's materials, from the soft filling, at SILO_SOFT_DT)."""
    s = SILO[orifice]
    bed = silo_name(material, orifice, n, seed, soft)
    if soft:
        scale, dt = 1.0, dt or SILO_SOFT_DT
    name = name or bed
    above = (f"region = 'box', box_min = -{BIG}, -{BIG}, {s['z_o']}, "
             f"box_max = {BIG}, {BIG}, {BIG}")
    extra = "" if integrator == "symplectic_euler" else f", integrator = '{integrator}'"
    return (run((dt or SILO_DT[material]) / scale ** 0.5, t_end, extra)
            + output(name, interval, snapshots, soft_checkpoints(n, soft))
            + case_materials(scale, soft)
            + f"&particle_file file = '{FROM_HERE}/prepare_{bed}/final.csv' /\n"
            + silo_walls(orifice)
            + f"&outlet region = 'plane', point = 0, 0, {s['z_o'] - 0.02:.7g}, "
              f"normal = 0, 0, -1 /\n"
            + f"&probe name = 'silo', kind = 'count', {above} /\n"
            + f"&probe name = 'velocity', kind = 'histogram', time = {histogram_time:g}, "
              f"bins = 40, v_min = -1.5, v_max = 0.5, {above} /\n")


def resettle_silo(material, dt, orifice="small", t_end=0.06):
    """The full soft silo's settled filling, the orifice still closed, run on at another dt:
    at too large a step the resting bed's contacts go unstable (its spheres spin up, from the
    bottom, to a level friction caps) instead of staying at rest."""
    bed = silo_name(material, orifice, soft=True)
    return (run(dt, t_end) + output(f"resettle_{bed}_dt{dt * 1e6:.0f}us", 0.005, 0.0)
            + case_materials(1.0, True)
            + f"&particle_file file = '{FROM_HERE}/prepare_{bed}/final.csv' /\n"
            + silo_walls(orifice) + orifice_closed(orifice))


def drum_walls(rotating, drum="drum"):
    spin = (", rotation_axis = 0, 1, 0, rotation_point = 0, 0, 0, angular_velocity = -2"
            if rotating else "")
    return f"&wall_mesh file = '{drum}.stl', material = 'steel'{spin} /\n"


def drum_name(drum, soft, seed=1):
    return drum + ("_soft" if soft else "") + (f"_seed{seed}" if seed > 1 else "")


def prepare_drum(stage, n_m2=8000, n_m1=30000, scale=1.0, t_end=1.0, drum="drum",
                 half_depth=0.03, soft=False, seed=1):
    """Stage 1: M2 (4 mm) inserted in the whole drum, settled; stage 2: M1 (2 mm) inserted
    in a box above that bed, settled on it (`drum`: the wall file and, with `soft` and
    `seed`, the cases' name; the insertions' seeds are 2 seed - 1 and 2 seed). dt is the
    case's 0.8 us scaled with the Rayleigh time (the square root of the stiffness), for the
    soft drums too: the falling spheres' impacts need it."""
    name = drum_name(drum, soft, seed)
    if soft:
        scale = SOFT
    dt = 8e-7 / scale ** 0.5
    if stage == 1:
        body = (f"&insert n = {n_m2}, material = 'M2', radius_min = 0.002, radius_max = 0.002, "
                f"region = 'mesh', mesh_file = '{drum}.stl', seed = {2 * seed - 1} /\n")
        n = n_m2
    else:
        y = half_depth - 0.002
        body = (f"&particle_file file = '{FROM_HERE}/prepare_{name}_1/final.csv' /\n"
                f"&insert n = {n_m1}, material = 'M1', radius_min = 0.001, radius_max = 0.001, "
                f"region = 'box', box_min = -0.07, -{y:g}, -0.03, "
                f"box_max = 0.07, {y:g}, 0.068, seed = {2 * seed} /\n")
        n = n_m2 + n_m1
    return (run(dt, t_end, f", stop_kinetic_energy = {n * 1e-11:g}")
            + output(f"prepare_{name}_{stage}", 0.01, 0.0) + case_materials(scale, soft) + body
            + drum_walls(False, drum))


def drum(scale=1.0, t_end=5.0, interval=0.1, drum="drum", smooth_ends=False, soft=False,
         dt=None, name=None, seed=1):
    """Zone 1: x > 0 and z > 0 (the upper quadrant on the rising side for omega = (0,-2,0));
    Zone 2: x < 0 and z < 0 (MercuryDPM's definitions). `smooth_ends`: the end discs, apart
    from the turning cylinder, of a steel without friction (a stand-in for a periodic depth:
    they hold the bed in y without dragging it round). `soft`: MercuryDPM's -soft variant,
    from the soft preparation, at its dt and output interval unless given (`dt`, `name`: a
    run of another dt, for the check of its error); `seed`: from that preparation. The probe
    `drive` is the torque of the particles on the walls about the axis: the power draw is
    -omega times drive_torque_axis."""
    bed = drum_name(drum, soft, seed)
    walls, name = drum_walls(True, drum), name or bed
    if soft:
        dt, interval = dt or DRUM_SOFT_DT, DRUM_SOFT_INTERVAL
    dt = dt or 8e-7 / scale ** 0.5
    if smooth_ends:
        name += "_smooth"
        walls = (drum_walls(True, drum + "_shell")
                 + f"&wall_mesh file = '{drum}_ends.stl', material = 'smooth' /\n"
                 + "&material name = 'smooth', density = 7200.0, "
                   f"youngs_modulus = {210e9 * scale:g}, poisson_ratio = 0.2 /\n"
                 + "".join(f"&pair materials = '{m}', 'smooth', restitution = 0.4, "
                           "friction = 0 /\n" for m in ("M1", "M2")))
    return (run(dt, t_end) + output(name, interval, 1.0) + case_materials(scale, soft)
            + f"&particle_file file = '{FROM_HERE}/prepare_{bed}_2/final.csv' /\n"
            + walls
            + f"&probe name = 'zone1', kind = 'count', region = 'box', box_min = 0, -{BIG}, 0, "
              f"box_max = {BIG}, {BIG}, {BIG} /\n"
            + f"&probe name = 'zone2', kind = 'count', region = 'box', "
              f"box_min = -{BIG}, -{BIG}, -{BIG}, box_max = 0, {BIG}, 0 /\n"
            + "&probe name = 'com', kind = 'center_of_mass' /\n"
            + "&probe name = 'drive', kind = 'wall_load', axis = 0, 1, 0, axis_point = 0, 0, 0 /\n")


def impact_name(n, seed):
    return f"impact_{n}" + (f"_seed{seed}" if seed > 1 else "")


def prepare_impact(n, seed=1, scale=1.0, t_end=1.0):
    """M1 spheres of 2 mm inserted in the box (a column five times the spheres' volume, so
    that random insertion has room), settled."""
    height = n * 4.19e-9 / 0.2 / (0.096 * 0.058)     # a fifth of the column is spheres
    return (run(2e-6 / scale ** 0.5, t_end, f", stop_kinetic_energy = {n * 1e-11:g}")
            + output("prepare_" + impact_name(n, seed), 0.01, 0.0) + materials(scale)
            + f"&insert n = {n}, material = 'M1', radius_min = 0.001, radius_max = 0.001, "
              f"region = 'box', box_min = -0.048, -0.029, {FLOOR + 0.001:.7g}, "
              f"box_max = 0.048, 0.029, {FLOOR + 0.001 + height:.5g}, seed = {seed} /\n"
            + "&wall_mesh file = 'impact_box.stl', material = 'steel' /\n")


def impact(n, seed=1, scale=1.0, t_end=0.1, interval=1e-3, dt=5e-7,
           integrator="symplectic_euler", name=None, allow_unstable=False):
    """The steel impactor, R = 10 mm, centre at (0, 0, 0.06), 5 m/s down, into the bed (dt,
    integrator and output name other than the case's for the speed-against-error study)."""
    bed = impact_name(n, seed)
    name = name or bed
    extra = "" if integrator == "symplectic_euler" else f", integrator = '{integrator}'"
    if allow_unstable:
        extra += ", allow_unstable = .true."
    return (run(dt / scale ** 0.5, t_end, extra) + output(name, interval, 0.01)
            + materials(scale)
            + f"&particle_file file = '{FROM_HERE}/prepare_{bed}/final.csv' /\n"
            + f"&particle id = {IMPACTOR_ID}, material = 'steel', radius = 0.01, "
              f"position = 0, 0, 0.06, velocity = 0, 0, -5 /\n"
            + "&wall_mesh file = 'impact_box.stl', material = 'steel' /\n"
            + f"&probe name = 'impactor', kind = 'track', id = {IMPACTOR_ID} /\n")


def cases():
    """{name: text} of every case, committed or variant."""
    out = {}
    for m in ("M1", "M2"):
        for o in ("small", "large"):
            out[f"prepare_silo_{m}_{o}"] = prepare_silo(m, o)
            out[f"silo_{m}_{o}"] = silo(m, o)
            n = SILO_REDUCED                   # run here; M1 from fillings of several seeds
            for seed in range(1, SILO_FILLINGS + 1) if m == "M1" else (1,):
                name = silo_name(m, o, n, seed)
                out[f"prepare_{name}"] = prepare_silo(m, o, n, t_end=1.0, seed=seed)
                out[f"{name}"] = silo(m, o, n, t_end=SILO_REDUCED_T_END,
                                          interval=SILO_REDUCED_INTERVAL,
                                          histogram_time=0.3, snapshots=0.1, seed=seed)
            name = silo_name(m, o, soft=True)            # the full silos, soft
            out[f"prepare_{name}"] = prepare_silo(m, o, soft=True)
            out[f"{name}"] = silo(m, o, soft=True)
            for seed in range(1, SILO_SOFT_FILLINGS + 1) if m == "M1" else (1,):
                name = silo_name(m, o, n, seed, soft=True)
                out[f"prepare_{name}"] = prepare_silo(m, o, n, t_end=1.0, seed=seed, soft=True)
                out[f"{name}"] = silo(m, o, n, t_end=SILO_REDUCED_T_END,
                                          interval=SILO_REDUCED_INTERVAL, histogram_time=0.3,
                                          snapshots=0.1, seed=seed, soft=True)
    for m, steps in (("M1", (5.0e-5, 7.5e-5)), ("M2", (5.0e-5, 7.5e-5, 1.0e-4))):
        for dt in steps:
            out[f"resettle_silo_{m}_small_soft_dt{dt * 1e6:.0f}us"] = resettle_silo(m, dt)
    out["prepare_drum_1"] = prepare_drum(1)
    out["prepare_drum_2"] = prepare_drum(2)
    out["drum"] = drum()
    slice_ = dict(n_m2=2000, n_m1=7500, drum="drum_slice", half_depth=0.0075)
    out["prepare_drum_slice_1"] = prepare_drum(1, **slice_)
    out["prepare_drum_slice_2"] = prepare_drum(2, **slice_)
    out["drum_slice"] = drum(drum="drum_slice")
    out["drum_slice_smooth"] = drum(drum="drum_slice", smooth_ends=True)
    for size in (dict(drum="drum"), slice_):
        soft = drum_name(size["drum"], True)
        out[f"prepare_{soft}_1"] = prepare_drum(1, soft=True, **size)
        out[f"prepare_{soft}_2"] = prepare_drum(2, soft=True, **size)
        out[f"{soft}"] = drum(drum=size["drum"], soft=True)
    out["drum_slice_soft_dt25us"] = drum(drum="drum_slice", soft=True, dt=2.5e-5,
                                             name="drum_slice_soft_dt25us")
    for stage in (1, 2):
        out[f"prepare_drum_slice_soft_seed2_{stage}"] = prepare_drum(stage, soft=True,
                                                                         seed=2, **slice_)
    out["drum_slice_soft_seed2"] = drum(drum="drum_slice", soft=True, seed=2)
    for n in (25000, 50000, 100000):
        out[f"prepare_{impact_name(n, 1)}"] = prepare_impact(n)
        out[f"{impact_name(n, 1)}"] = impact(n)
    for seed in range(2, 11):
        out[f"prepare_{impact_name(25000, seed)}"] = prepare_impact(25000, seed)
        out[f"{impact_name(25000, seed)}"] = impact(25000, seed)
    return out


def folder(name):
    """The case folder of a case (committed or variant): the one of its walls."""
    return next(f for f in FOLDERS if f in name)


def is_variant(name):
    return any(mark in name for mark in VARIANT_MARKS)


def relocated(text, home, target=None):
    """`text`, a namelist of the folder `home` (silo, drum, impact), with its relative file
    names made relative to the folder `target` instead, or absolute without one."""
    def move(m):
        path = os.path.normpath(os.path.join(HERE, home, m.group(2)))
        return m.group(1) + (os.path.relpath(path, target) if target else path) + "'"
    return re.sub(r"(file = ')([^'/][^']*)'", move, text)


def header(name):
    return f"! {name}.nml: written by cases/make_cases.py (Dosta et al. 2024 benchmark)\n"


def files():
    """{path in cases/: text} of the committed cases."""
    return {os.path.join(folder(name), name + ".nml"): header(name) + text
            for name, text in cases().items() if not is_variant(name)}


def write(name, target):
    """Write the case `name` into the folder `target`, its file names relative to it;
    return its path."""
    os.makedirs(target, exist_ok=True)
    path = os.path.join(target, name + ".nml")
    with open(path, "w") as f:
        f.write(header(name) + relocated(cases()[name], folder(name), os.path.abspath(target)))
    return path


def main():
    ap = argparse.ArgumentParser(description="Writes the benchmark cases' namelists.")
    ap.add_argument("names", nargs="*", help="cases to write into --dir (default: write the "
                                             "committed cases into their folders)")
    ap.add_argument("--dir", default=os.path.join(ROOT, "output", "cases"))
    a = ap.parse_args()
    known = cases()
    for name in a.names:
        if name not in known:
            sys.exit(f"make_cases.py: no case {name}; the cases: {' '.join(sorted(known))}")
        print(write(name, a.dir))
    if not a.names:
        for path, text in files().items():
            with open(os.path.join(HERE, path), "w") as f:
                f.write(text)


if __name__ == "__main__":
    main()
