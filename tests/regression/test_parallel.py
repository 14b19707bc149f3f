# SPDX-License-Identifier: BSD-3-Clause
"""The same answer on any number of MPI ranks (doc/user/parallel.md): a case run on 1, 2, 3 (and
4) ranks gives bit-identical results: final.csv, series.csv (energies summed in id order,
contact counts), probes.csv, snapshots (with forces and contact counts), and the
checkpoints' particles and contact history, for

1. a settling bed with contacts and a moving, spinning STL floor (the box case of the
   checkpoint tests), on 1, 2, 3 and 4 ranks;
2. a short discharge of the reduced small silo (particles removed by the outlet: count plus
   removed conserved in every row, and equal to the one-rank run's; the run stops when the
   outlet takes the last particle out, at the same step on every rank count);
3. the impact case at reduced size (a steel sphere into a settled bed), and on 2 ranks with
   the halo handed to MPI by device address (gpu_aware_mpi); its bed has no contact history,
   and the first rebuild that knows the contacts partitions again, weighing them;
4. a checkpoint written on 3 ranks, restarted on 2: the same final state as the
   uninterrupted run on one rank; and a checkpoint written on 1 rank restarted on 3;
5. a run that goes unstable: the last good state it writes (kept by each rank for its own
   particles, gathered when written) is the same checkpoint on 1 and 2 ranks;
6. bad particles in a particle file, which the ranks read in shares (an id given twice, two
   spheres far deeper into each other than a contact, each pair in rows that different
   ranks hold): on 1, 2 and 3 ranks, a run and --check stop with the same input error
   naming the file and the ids (the smallest pair when several), and leave no output;
7. a case started from a CSV particle file and from the HDF5 snapshot of its first step (each
   rank reading its block of the file) on 1, 2 and 3 ranks: the same final.csv; and a case
   whose materials lack the snapshot's stops on every rank count with the same message;
8. a polydisperse bed with sJKR cohesion (radii 1 to 2 mm) on 1, 2 and 3 ranks, with the
   Hertz-Mindlin law and with the linear law and the Coulomb-capped tangential law.

The runs are independent: each rank count decomposes space differently (METIS on blocks),
so equality means that the forces do not depend on the decomposition, that particles
migrate with all their state and history, and that outputs gather in id order. In the
impact case on 3 ranks a rank's particle store (its capacity, which follows its share and
grows and shrinks as particles migrate) holds less than 0.55 of the particles: its third,
its ghosts and a quarter's margin (about 5/4 (1/3 + 0.04) = 0.46), not the whole case.
usage: test_parallel.py DEM WORKDIR MPIEXEC"""
import os
import re
import shutil
import sys

import h5py
import numpy as np

from regression_util import ROOT, check, finish, run_ranks, same_file
import checkpoint_util as cu

sys.path.insert(0, os.path.join(ROOT, "cases"))
import make_cases as mc     # noqa: E402

dem, work, mpiexec = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def run(case, ranks, *args, code=0):
    """Run dem on `ranks` ranks from `work`; check the exit status."""
    return run_ranks(mpiexec, dem, case, ranks, work, *args, code=code)




def same_state(a, b, what):
    """The particles and contact history of two checkpoints, bit for bit."""
    with h5py.File(a) as fa, h5py.File(b) as fb:
        for name in ("particles/id", "particles/position", "particles/velocity",
                     "particles/angular_velocity", "particles/force", "particles/torque",
                     "state/pair", "state/pair_history", "state/wall_contact_triangle",
                     "state/wall_contact_history", "state/removed"):
            check(np.array_equal(fa[name][()], fb[name][()]), f"{what}: {name} differs")


stdout = {}     # (case, ranks): what the run printed


def compare(name, ranks_list, files=("final.csv", "series.csv"), store_below=None):
    """Run case `name`.nml (in work, outputs in work/<name>_<ranks>) on each rank count and
    compare the outputs with the one-rank run's; with `store_below`, the largest particle
    store of a rank on 3 ranks, over the particles, must be below it."""
    outs = {}
    for ranks in ranks_list:
        with open(os.path.join(work, name + ".nml")) as f:
            text = f.read()
        case = os.path.join(work, f"{name}_{ranks}.nml")
        with open(case, "w") as f:
            f.write(text.replace("@OUT@", os.path.join(work, f"{name}_{ranks}")))
        r = run(case, ranks)
        stdout[name, ranks] = r.stdout
        outs[ranks] = os.path.join(work, f"{name}_{ranks}")
        if store_below and ranks == 3:
            m = re.search(r"largest store +(\S+) of the particles", r.stdout)
            check(m is not None and float(m.group(1)) < store_below,
                  f"{name} on 3 ranks: largest store {m and m.group(1)} of the particles, "
                  f"not below {store_below}")
    checkpoints = [c for c in sorted(os.listdir(os.path.join(outs[1], "checkpoints")))
                   if c.endswith(".h5")]
    check(len(checkpoints) >= 2, f"{name}: checkpoints {checkpoints}")
    for ranks in ranks_list[1:]:
        for f in files:
            same_file(os.path.join(outs[1], f), os.path.join(outs[ranks], f),
                      f"{name} on {ranks} ranks")
        for ck in checkpoints:
            same_state(os.path.join(outs[1], "checkpoints", ck),
                       os.path.join(outs[ranks], "checkpoints", ck), f"{name} on {ranks} ranks")
    return outs


# 1. settling bed, moving floor
cu.write_box_case(os.path.join(work, "box.nml"), "@OUT@", t_end=0.1, n=200,
                  output=", snapshot_interval = 0.05, snapshot_force = .true., "
                         "snapshot_contacts = .true., checkpoint_interval = 0.05")
with open(os.path.join(work, "box.nml")) as f:
    text = f.read()
with open(os.path.join(work, "box.nml"), "w") as f:
    f.write(text.replace(os.path.abspath("@OUT@"), "@OUT@"))
outs = compare("box", [1, 2, 3, 4], ("final.csv", "series.csv", "snapshots.xmf"))
for ranks in (2, 3, 4):
    for snap in sorted(os.listdir(os.path.join(outs[1], "snapshots"))):
        with h5py.File(os.path.join(outs[1], "snapshots", snap)) as fa, \
                h5py.File(os.path.join(outs[ranks], "snapshots", snap)) as fb:
            for name in fa["particles"]:
                check(np.array_equal(fa["particles"][name][()], fb["particles"][name][()]),
                      f"box on {ranks} ranks: {snap}: particles/{name} differs")
s = np.genfromtxt(os.path.join(outs[1], "series.csv"), delimiter=",", names=True)
check(s["contacts_pp"][-1] > 10 and s["contacts_pw"][-1] > 10,
      f"box: the bed has contacts ({s['contacts_pp'][-1]:.0f}, {s['contacts_pw'][-1]:.0f})")

# 2. silo discharge (reduced: 400 spheres, stiffness x 1e-3)
SCALE = 1e-3
for folder, walls in (("silo", "silo_small.stl"), ("impact", "impact_box.stl")):
    shutil.copy(os.path.join(ROOT, "cases", folder, walls), work)
prep = mc.prepare_silo("M1", "small", n=400, scale=SCALE, t_end=0.4)
prep = prep.replace(f"'{mc.OUT}/prepare_silo_M1_small_400'", f"'{work}/prepare_silo'")
with open(os.path.join(work, "prepare_silo.nml"), "w") as f:
    f.write(prep)
run(os.path.join(work, "prepare_silo.nml"), 2)
silo = mc.silo("M1", "small", n=400, scale=SCALE, t_end=0.3, interval=0.02, histogram_time=0.1,
               snapshots=0.0)
silo = silo.replace(f"'{mc.OUT}/silo_M1_small_400'", "'@OUT@'").replace(
    f"{mc.FROM_HERE}/prepare_silo_M1_small_400/final.csv", f"{work}/prepare_silo/final.csv")
silo = silo.replace("snapshot_interval = 0 /",
                    "snapshot_interval = 0, checkpoint_interval = 0.1 /")
with open(os.path.join(work, "silo.nml"), "w") as f:
    f.write(silo)
outs = compare("silo", [1, 2, 3], ("final.csv", "series.csv", "probes.csv",
                                   "histogram_velocity.csv"))
s = np.genfromtxt(os.path.join(outs[1], "series.csv"), delimiter=",", names=True)
check(np.all(s["particles"] + s["removed"] == 400) and s["removed"][-1] > 20,
      f"silo: particles + removed = 400 in every row, {s['removed'][-1]:.0f} removed")
check(s["particles"][-1] > 0 or s["time"][-1] < 0.3,
      "silo: a run whose outlet takes the last particle out stops then, before t_end")

# 3. impact, reduced
prep = mc.prepare_impact(1500, scale=SCALE, t_end=0.15).replace(
    f"'{mc.OUT}/prepare_impact_1500'", f"'{work}/prepare_impact'")
with open(os.path.join(work, "prepare_impact.nml"), "w") as f:
    f.write(prep)
run(os.path.join(work, "prepare_impact.nml"), 3)
impact = mc.impact(1500, scale=SCALE, t_end=0.02, interval=1e-3).replace(
    f"'{mc.OUT}/impact_1500'", "'@OUT@'").replace(
    f"{mc.FROM_HERE}/prepare_impact_1500/final.csv", f"{work}/prepare_impact/final.csv")
impact = impact.replace("snapshot_interval = 0.01", "snapshot_interval = 0, "
                        "checkpoint_interval = 0.01")
with open(os.path.join(work, "impact.nml"), "w") as f:
    f.write(impact)
outs = compare("impact", [1, 2, 3], ("final.csv", "series.csv", "probes.csv"),
               store_below=0.55)
# the bed's file has no contact history: the first partition weighs particles alone, and the
# first rebuild that knows the contacts partitions again, weighing them (doc/theory.md, 13)
for ranks in (2, 3):
    m = re.search(r"(\d+) partitions", stdout["impact", ranks])
    check(m is not None and int(m.group(1)) >= 2,
          f"impact on {ranks} ranks: partitions {m and m.group(1)}, not at least 2 (the "
          "second weighing the contacts)")
# the halo buffers handed to MPI by their device addresses (gpu_aware_mpi; on the host, and
# in the OpenACC build's host fallback, the same memory): the same answer
d = os.path.join(work, "impact_gpu_aware_2")
with open(os.path.join(work, "impact.nml")) as f:
    text = f.read().replace("@OUT@", d).replace("&run ", "&run gpu_aware_mpi = .true., ", 1)
with open(d + ".nml", "w") as f:
    f.write(text)
run(d + ".nml", 2)
for f in ("final.csv", "series.csv", "probes.csv"):
    same_file(os.path.join(outs[1], f), os.path.join(d, f), "impact with gpu_aware_mpi")

# 4. checkpoint on 3 ranks, restart on 2 (and on 1 rank, restart on 3): the run's directory
# copied, restarted from its first checkpoint (series.csv is cut back to it and continued)
for first, then in ((3, 2), (1, 3)):
    name = f"restart_{first}_{then}"
    d = os.path.join(work, name)
    shutil.copytree(os.path.join(work, f"box_{first}"), d)
    ck = sorted(c for c in os.listdir(os.path.join(d, "checkpoints")) if c.endswith(".h5"))[0]
    with open(os.path.join(work, f"box_{first}.nml")) as f:
        text = f.read()
    case = os.path.join(work, name + ".nml")
    with open(case, "w") as f:
        f.write(text.replace(os.path.join(work, f"box_{first}"), d))
    run(case, then, "--restart", os.path.join(d, "checkpoints", ck))
    for f in ("final.csv", "series.csv"):
        same_file(os.path.join(work, "box_1", f), os.path.join(d, f),
                  f"checkpoint on {first} ranks, restarted on {then}")
# 5. an unstable run (stiff spheres, dt far above the Rayleigh time): on 1 and 2 ranks it
# stops at the same step, and the last good state it writes (each rank keeps its own
# particles of it; they are gathered only to be written) is the same checkpoint
unstable = {}
for ranks in (1, 2):
    d = os.path.join(work, f"unstable_{ranks}")
    case = cu.write_box_case(d + ".nml", d, 0.2, 2.0e-5, interval=0.001, E="1e11",
                             run=", allow_unstable = .true.")
    r = run(case, ranks, code=3)
    m = re.search(r"the last good state, at t = \S+ s, is in (\S+)", r.stderr)
    check(m is not None, f"unstable run on {ranks} ranks: {r.stderr.strip()[-500:]}")
    unstable[ranks] = m.group(1) if m else None
if all(unstable.values()):
    check(os.path.basename(unstable[1]) == os.path.basename(unstable[2]),
          f"unstable run: last good states {unstable}")
    same_state(unstable[1], unstable[2], "the last good state of an unstable run on 2 ranks")
    with h5py.File(unstable[2]) as f:
        check(f["particles/id"].shape[0] == 200, "unstable run on 2 ranks: the last good "
              f"state holds {f['particles/id'].shape[0]} particles, not 200")

# 6. bad particles in a particle file: the same error on any number of ranks
rows = ["id,material,radius,x,y,z"] + [f"{k},M1,0.002,{0.01 * (k % 10)},{0.01 * (k // 10)},0.1"
                                       for k in range(1, 41)]
moved = {"twice": {38: "7,M1,0.002,0.08,0.03,0.1"},                # a second id 7
         "deep": {22: "22,M1,0.002,0.02,0.0,0.1011",                 # onto 2, and 33
                  33: "33,M1,0.002,0.02,0.01,0.1003"}}               # onto 12
expected = {"twice": "particle id 7 is given twice",
            "deep": "particles 2 and 22 overlap by more than half the smaller radius"}
for name in ("twice", "deep"):
    d = os.path.join(work, "bad_" + name)
    os.makedirs(d)
    bad_rows = [moved[name].get(k, row) for k, row in enumerate(rows)]
    with open(os.path.join(d, "particles.csv"), "w") as f:
        f.write("\n".join(bad_rows) + "\n")
    case = os.path.join(d, "case.nml")
    with open(case, "w") as f:
        f.write(f"""&run dt = 1e-7, t_end = 1e-6 /
&output dir = '{d}/out', interval = 1e-7 /
&material name = 'M1', density = 2500.0, youngs_modulus = 5e6, poisson_ratio = 0.3 /
&pair materials = 'M1', 'M1', restitution = 0.5, friction = 0.3 /
&particle_file file = 'particles.csv' /
""")
    for ranks in (1, 2, 3):
        for args in ((), ("--check",)):
            r = run(case, ranks, *args, code=2)
            check(case in r.stderr and expected[name] in r.stderr,
                  f"bad_{name} on {ranks} ranks {args}: {r.stderr.strip()[-500:]}")
            check(not os.path.exists(os.path.join(d, "out")),
                  f"bad_{name} on {ranks} ranks {args}: left output behind")

# 7. the same start from a CSV file and from an HDF5 snapshot, read in shares
d = os.path.join(work, "shares")
os.makedirs(d)
with open(os.path.join(d, "particles.csv"), "w") as f:
    f.write("\n".join(rows) + "\n")
CASE7 = """&run dt = 1e-6, t_end = 1e-4 /
&output dir = '{out}', interval = 5e-5, snapshot_interval = {snap} /
&material name = '{mat}', density = 2500.0, youngs_modulus = 5e6, poisson_ratio = 0.3 /
&pair materials = '{mat}', '{mat}', restitution = 0.5, friction = 0.3 /
&particle_file file = '{file}' /
"""
with open(os.path.join(d, "csv.nml"), "w") as f:
    f.write(CASE7.format(out=f"{d}/csv", snap="1e-4", mat="M1", file="particles.csv"))
run(os.path.join(d, "csv.nml"), 1)
snapshot = os.path.join(d, "csv", "snapshots", "snapshot_000000000000.h5")
for ranks in (1, 2, 3):
    case = os.path.join(d, f"h5_{ranks}.nml")
    with open(case, "w") as f:
        f.write(CASE7.format(out=f"{d}/h5_{ranks}", snap="0", mat="M1", file=snapshot))
    run(case, ranks)
    same_file(os.path.join(d, "csv", "final.csv"), os.path.join(d, f"h5_{ranks}", "final.csv"),
              f"started from the snapshot on {ranks} ranks")
    case = os.path.join(d, f"h5_bad_{ranks}.nml")
    with open(case, "w") as f:
        f.write(CASE7.format(out=f"{d}/h5_bad_{ranks}", snap="0", mat="M3", file=snapshot))
    r = run(case, ranks, code=2)
    check("particle 1 is of material 'M1', which the case does not define" in r.stderr,
          f"snapshot of undefined materials on {ranks} ranks: {r.stderr.strip()[-500:]}")

# 8. a polydisperse cohesive bed (radii 1 to 2 mm, sJKR between the particles and with the
# walls): a pair split between two ranks is evaluated from both sides, so its contact area
# must not depend on which radius comes first
COHESIVE = ("&insert n = 300, material = 'soft', radius_min = 0.001, radius_max = 0.002, "
            "region = 'box', box_min = -0.045, -0.045, 0.005, box_max = 0.045, 0.045, 0.06, "
            "seed = 11, velocity = 0.1, 0, -0.2 /\n")
cu.write_box_case(os.path.join(work, "cohesive.nml"), "@OUT@", t_end=0.08, n=300,
                  particles=COHESIVE, output=", checkpoint_interval = 0.04")
with open(os.path.join(work, "cohesive.nml")) as f:
    text = f.read().replace(os.path.abspath("@OUT@"), "@OUT@").replace(
        "restitution = 0.3, friction = 0.3 /",
        "restitution = 0.3, friction = 0.3, cohesion_energy_density = 2e5 /")
with open(os.path.join(work, "cohesive.nml"), "w") as f:
    f.write(text)
outs = compare("cohesive", [1, 2, 3], ("final.csv", "series.csv"))
s = np.genfromtxt(os.path.join(outs[1], "series.csv"), delimiter=",", names=True)
check(s["contacts_pp"][-1] > 50, f"cohesive: the bed has {s['contacts_pp'][-1]:.0f} contacts")
# and with the linear normal law and the Coulomb-capped tangential law
with open(os.path.join(work, "cohesive_linear.nml"), "w") as f:
    f.write(text.replace("cohesion_energy_density = 2e5 /",
                         "cohesion_energy_density = 2e5, stiffness = 2e3 /")
            + "&contact_model normal_model = 'hooke', tangential_model = 'coulomb' /\n")
outs = compare("cohesive_linear", [1, 2, 3], ("final.csv", "series.csv"))
s = np.genfromtxt(os.path.join(outs[1], "series.csv"), delimiter=",", names=True)
check(s["contacts_pp"].max() >= 5 and s["contacts_pw"][-1] > 100,
      f"cohesive, linear law: at most {s['contacts_pp'].max():.0f} pair contacts, "
      f"{s['contacts_pw'][-1]:.0f} on the walls at the end")

# tracing is for one rank: on two, --check and the run both refuse it as bad input (exit 2,
# naming &output's trace_id), where the run used to stop at its start with exit 3
case = os.path.join(work, "trace_2.nml")
with open(case, "w") as f:
    f.write("""&run dt = 1e-5, t_end = 1e-4, gravity = 0, 0, -9.81 /
&output dir = 'trace_2', trace_id = 1 /
&material name = 'glass', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&particle id = 1, material = 'glass', radius = 1e-3, position = 0, 0, 0.01 /
""")
for args in (["--check"], []):
    r = run(case, 2, *args, code=2)
    check("&output" in r.stderr and "key 'trace_id': tracing runs on one MPI rank"
          in r.stderr, f"trace_id on 2 ranks {args}: {r.stderr.strip()[-500:]}")
finish()
