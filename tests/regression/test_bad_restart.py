# SPDX-License-Identifier: BSD-3-Clause
"""A restart from a file that is not a good checkpoint of the case is refused with a clear
error, and changes nothing.

A short run of a case (200 soft spheres in a box of four planes on an STL floor, written
here) leaves a good checkpoint. From it we make bad restart inputs, each with the way it was
damaged known here, independently of the solver:
- a truncated file (its first half);
- a corrupted file: 8 bytes flipped inside the raw float64 data of /particles/position,
  found in the file as the little-endian bytes of a particle's position read with h5py;
- checkpoints of other cases: another Young's modulus (material properties), a material
  renamed, a material more, a particle less, a wall less, a wall moved (wall geometry), the
  floor rising from t = 0.01 s instead of 0.05 s, so that at the checkpoint's time
  (0.02 s) it is elsewhere (wall motion);
- a copy of the checkpoint without the dataset /state/pair_history (made with h5py);
- a snapshot of the run instead of a checkpoint;
- a file that does not exist;
- crafted files whose checksums are valid: a particle id given twice, a negative id, a
  negative step;
- a directory, an empty file and /dev/zero given as the checkpoint (refused before HDF5
  or MPI-IO reads them);
- --restart with too few arguments (a usage error);
- a run with a probe, restarted from its first checkpoint with the probe renamed: the
  columns of its probes.csv are not those of the changed case, and neither probes.csv nor
  series.csv (which would be cut back first) may change.
Each must end with exit status 2 (bad input) or 4 (a file that cannot be read), with one
error message that names the file and what is wrong (the dataset, or what differs between
the cases), no crash (signal, backtrace, HDF5 library diagnostics), and no output written:
the output directory of the case, which holds the first run's outputs, is byte for byte
unchanged, and the output directories of the other cases are not created.
Finally the good checkpoint itself is accepted (the errors above come from the damage).
usage: test_bad_restart.py DEM WORKDIR"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

from regression_util import check, finish, run_dem
import checkpoint_util as cu

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
if os.path.exists(work):
    shutil.rmtree(work)
os.makedirs(work)

DT, T_END = 2.0e-5, 0.02                  # 1000 steps
out_a = os.path.join(work, "out_a")
case_a = cu.write_box_case(os.path.join(work, "a.nml"), out_a, T_END, DT,
                           output=", snapshot_interval = 0.01")
run_dem(dem, case_a, work)
good = os.path.join(out_a, cu.checkpoint_name(round(T_END / DT)))
snapshot = os.path.join(out_a, "snapshots", "snapshot_000000000500.h5")
check(os.path.exists(good) and os.path.exists(snapshot),
      "the first run left no checkpoint or no snapshot")
with h5py.File(good, "r") as f:
    n_particles = f["particles/id"].shape[0]
    n_tri = f["walls/triangles"].shape[0]
    position = f["particles/position"][()]

bad_dir = os.path.join(work, "bad")
os.makedirs(bad_dir)

# truncated: the first half of the file
truncated = os.path.join(bad_dir, "truncated.h5")
data = open(good, "rb").read()
with open(truncated, "wb") as f:
    f.write(data[:len(data) // 2])

# corrupted: the y coordinate of a particle's position, flipped bit for bit
corrupted = os.path.join(bad_dir, "corrupted.h5")
k = n_particles // 2
raw = position[k].astype("<f8").tobytes()         # x, y, z of particle k: 24 bytes
at = data.find(raw)
check(at > 0 and data.find(raw, at + 1) < 0,
      "the raw bytes of a particle's position are not found once in the checkpoint")
damaged = bytearray(data)
damaged[at + 8:at + 16] = bytes(b ^ 0xFF for b in damaged[at + 8:at + 16])
with open(corrupted, "wb") as f:
    f.write(damaged)

# a dataset left out
missing = os.path.join(bad_dir, "missing.h5")
with h5py.File(good, "r") as src, h5py.File(missing, "w") as dst:
    for name in src:
        if name != "state":
            src.copy(src[name], dst, name=name)
    dst.create_group("state")
    for name in src["state"]:
        if name != "pair_history":
            src.copy(src["state"][name], dst["state"], name=name)
with h5py.File(missing, "r") as f:
    check("state/pair_history" not in f and "state/pair" in f,
          "the copy without /state/pair_history is not as intended")

# crafted: whole files with valid checksums (recomputed here) whose particle ids repeat or
# are negative, or whose step is negative (issue 30, item 9)
def crafted(name, dataset, change):
    path = os.path.join(bad_dir, name + ".h5")
    shutil.copy(good, path)
    with h5py.File(path, "r+") as f:
        d = f[dataset]
        a = d[()]
        a = change(a)
        d[()] = a
        d.attrs["checksum"] = np.int64(cu.checksum(cu.dataset_bytes(d)))
    check(not cu.bad_checksums(path), f"{name}: the crafted file's checksums do not match")
    return path


def twice(a):
    a = a.copy()
    a[1] = a[0]
    return a


def negative(a):
    a = a.copy()
    a[0] = -5
    return a


crafted_files = [(crafted("duplicate_id", "/particles/id", twice), "particle ids", "repeated id"),
                 (crafted("negative_id", "/particles/id", negative), "particle ids",
                  "negative id"),
                 (crafted("negative_step", "/step", lambda a: np.int64(-3)), "run state",
                  "negative step")]
others = {
    "youngs_modulus": (dict(E="2e7"), "material properties"),
    # a material renamed: the materials (names and properties) differ; the message may
    # list the names or say "material properties"
    "renamed": (dict(soft="glass"), "material"),
    "more_materials": (dict(extra="&material name = 'steel', rigid = .true. /\n"
                                  "&pair materials = 'soft', 'steel', restitution = 0.5, "
                                  "friction = 0.1 /\n"), "materials: (soft, wall) there, "
                                                         "(soft, wall, steel) here"),
    "fewer_particles": (dict(n=n_particles - 1), f"particle count: {n_particles} there, "
                                                 f"{n_particles - 1} here"),
    "fewer_walls": (dict(four_planes=False), f"walls: {n_tri} triangles there, "
                                             f"{n_tri - 2} here"),
    "wall_moved": (dict(x0="-0.0501"), "wall geometry"),
    "wall_motion": (dict(floor_start="0.01"), "wall motion"),
}

cases = {}
for name, (change, _) in others.items():
    out = os.path.join(work, "out_" + name)
    cases[name] = cu.write_box_case(os.path.join(work, name + ".nml"), out, T_END, DT,
                                    output=", snapshot_interval = 0.01", **change)
    r = subprocess.run([dem, "--check", cases[name]], capture_output=True, text=True,
                       cwd=work, timeout=120)
    check(r.returncode == 0, f"the case {name} is not valid: {r.stderr.strip()}")


def refused(args, out_dirs, expect_codes, needles, what, accepted=False):
    """Run dem with args; it must fail cleanly with an error containing all needles and
    leave out_dirs as they were (`accepted`: the checkpoint itself is good, and said so)."""
    before = {d: cu.tree_state(d) for d in out_dirs}
    r = subprocess.run([dem] + args, capture_output=True, text=True, cwd=work, timeout=120)
    message = r.stderr.strip()
    print(f"{what}: exit {r.returncode}: {message}")
    check(r.returncode in expect_codes,
          f"{what}: exit status {r.returncode}, expected {' or '.join(map(str, expect_codes))}")
    lines = [ln for ln in message.splitlines() if ln.strip()]
    check(len(lines) == 1 and lines[0].startswith("dem: error: "),
          f"{what}: expected one line 'dem: error: ...' on stderr, got {message!r}")
    for needle in needles:
        check(needle in message, f"{what}: the error does not say {needle!r}: {message!r}")
    signs = cu.crash_signs(r.stdout + r.stderr)
    check(not signs, f"{what}: signs of a crash: {signs}")
    check("dem: done" not in r.stdout and (accepted or "restarting from" not in r.stdout),
          f"{what}: the run went on")
    for d in out_dirs:
        after = cu.tree_state(d)
        if before[d] != after:
            new = sorted(set(after) - set(before[d]))
            changed = sorted(k for k in set(after) & set(before[d]) if after[k] != before[d][k])
            gone = sorted(set(before[d]) - set(after))
            check(False, f"{what}: {d} changed: new {new}, changed {changed}, removed {gone}")
    return r


READ_ERRORS = (2, 4)        # bad input, or a file that cannot be read

refused(["--restart", truncated, case_a], [out_a], READ_ERRORS,
        [truncated, "truncated"], "truncated checkpoint")
refused(["--restart", corrupted, case_a], [out_a], READ_ERRORS,
        [corrupted, "/particles/position", "damaged"], "corrupted checkpoint")
refused(["--restart", missing, case_a], [out_a], READ_ERRORS,
        [missing, "/state/pair_history", "missing"], "checkpoint without a dataset")
refused(["--restart", snapshot, case_a], [out_a], READ_ERRORS,
        [snapshot, "not a dem checkpoint"], "snapshot given as a checkpoint")
nowhere = os.path.join(bad_dir, "no_such_checkpoint.h5")
refused(["--restart", nowhere, case_a], [out_a], READ_ERRORS,
        [nowhere, "does not exist"], "checkpoint that does not exist")
for path, says, what in crafted_files:
    refused(["--restart", path, case_a], [out_a], READ_ERRORS, [path, says, "not"],
            f"crafted checkpoint ({what})")
# not files to read: one line, no Open MPI read errors before it (issue 30, item 9), and no
# read that never ends (/dev/zero, item 8)
empty = os.path.join(bad_dir, "empty.h5")
open(empty, "w").close()
for path, why, what in ((bad_dir, "is a directory", "a directory"),
                        (empty, "is empty or not a regular file", "an empty file"),
                        ("/dev/zero", "is empty or not a regular file", "/dev/zero")):
    refused(["--restart", path, case_a], [out_a], READ_ERRORS, [path, why],
            f"{what} given as a checkpoint")

for name, (_, differs) in others.items():
    out = os.path.join(work, "out_" + name)
    refused(["--restart", good, cases[name]], [out_a, out], (2,),
                [good, "another case", cases[name], differs],
                f"checkpoint of another case ({name})")
    check(not os.path.exists(out), f"checkpoint of another case ({name}): {out} was created")

# a probe renamed between the run and its restart: probes.csv's columns differ
out_p = os.path.join(work, "out_probe")
probe = "&probe name = '{}', kind = 'center_of_mass' /\n"
output = ", checkpoint_interval = 0.01"
case_p = cu.write_box_case(os.path.join(work, "probe.nml"), out_p, T_END, DT, output=output,
                           extra=probe.format("bed"))
run_dem(dem, case_p, work)
case_q = cu.write_box_case(os.path.join(work, "probe_renamed.nml"), out_p, T_END, DT,
                           output=output, extra=probe.format("heap"))
first = os.path.join(out_p, cu.checkpoint_name(round(0.01 / DT)))
refused(["--restart", first, case_q], [out_p], (2,),
        [os.path.join(out_p, "probes.csv"), "bed_soft_x", "heap_soft_x", "columns"],
        "a restart whose probes.csv columns changed", accepted=True)

# usage errors
for args in (["--restart", case_a], ["--restart"], ["--restart", good, case_a, case_a]):
    refused(args, [out_a], (2,), ["--restart", "usage"], "dem " + " ".join(
        os.path.basename(a) for a in args))

# the good checkpoint is accepted: the case goes on from it to its end (nothing left to do)
r = subprocess.run([dem, "--restart", good, case_a], capture_output=True, text=True,
                   cwd=work, timeout=120)
check(r.returncode == 0 and "restarting from " + good in r.stdout,
      f"a restart from the good checkpoint: exit {r.returncode}: {r.stderr.strip()}")
finish()
