# SPDX-License-Identifier: BSD-3-Clause
"""Shared helpers of the checkpoint and run-control regression tests: a small case with
contacts and moving walls written on the fly, the checksum of a checkpoint's datasets
recomputed independently of the solver, exact comparison of HDF5 datasets, and running the
solver in the background.

The checksum is recomputed here from its definition (doc/theory.md, section 11): the
exclusive or, over the bytes b_k (k = 1, 2, ...) of a dataset in storage order, of
SplitMix64's finaliser applied to k + 2^56 b_k. Fixed-length strings are stored padded with
blanks."""
import os
import signal
import subprocess
import time

import h5py
import numpy as np

# The floor: two triangles of a square at z = 0, 0.16 m wide, so that it covers the box
# however it turns (written as ASCII STL).
FLOOR = [((-0.08, -0.08, 0.0), (0.08, -0.08, 0.0), (0.08, 0.08, 0.0)),
         ((-0.08, -0.08, 0.0), (0.08, 0.08, 0.0), (-0.08, 0.08, 0.0))]
FLOOR_STL = "solid floor\n" + "".join(
    " facet normal 0 0 1\n  outer loop\n"
    + "".join("   vertex %r %r %r\n" % v for v in tri) + "  endloop\n endfacet\n"
    for tri in FLOOR) + "endsolid floor\n"

# Soft spheres falling in a box of four planes onto an STL floor that rises, then spins:
# particle-particle and particle-wall contacts with tangential history, and walls in motion.
BOX_CASE = """&run dt = {dt}, t_end = {t_end}, integrator = '{integrator}'{run} /
&output dir = '{dir}', interval = {interval}{output} /
&material name = '{soft}', density = 2500, youngs_modulus = {E}, poisson_ratio = 0.2 /
&material name = 'wall', rigid = .true. /
&pair materials = '{soft}', '{soft}', restitution = 0.3, friction = 0.3 /
&pair materials = '{soft}', 'wall', restitution = 0.3, friction = 0.3 /
{particles}&wall_plane material = 'wall', point = {x0}, 0, 0.1, normal = 1, 0, 0, half_width = 0.1 /
&wall_plane material = 'wall', point = 0.05, 0, 0.1, normal = -1, 0, 0, half_width = 0.1 /
&wall_plane material = 'wall', point = 0, -0.05, 0.1, normal = 0, 1, 0, half_width = 0.1 /
{last_plane}&wall_mesh file = '{stl}', material = 'wall', velocity = 0, 0, 0.01, velocity_start = {floor_start}, velocity_end = 0.15, rotation_axis = 0, 0, 1, rotation_point = 0, 0, 0, angular_velocity = 5, rotation_start = 0.1 /
{extra}"""
INSERT = ("&insert n = {n}, material = '{soft}', radius_min = 0.004, radius_max = 0.005, "
          "region = 'box', box_min = -0.045, -0.045, 0.005, box_max = 0.045, 0.045, 0.15, "
          "seed = 7, velocity = 0.1, 0, -0.2 /\n")
LAST_PLANE = ("&wall_plane material = 'wall', point = 0, 0.05, 0.1, normal = 0, -1, 0, "
              "half_width = 0.1 /\n")


def write_box_case(path, out_dir, t_end, dt=2.0e-5, interval=None, run="", output="",
                   integrator="symplectic_euler", n=200, E="1e7", soft="soft", x0="-0.05",
                   four_planes=True, floor_start="0.05", extra="", particles=None):
    """Write the box case (and floor.stl beside it) to `path`; `run` and `output` are extra
    keys of &run and &output (", key = value, ..."), `extra` extra groups; the other
    arguments change the case: particle count, Young's modulus and name of the particles'
    material, the position of the first wall plane, the fourth wall plane or none, and when
    the floor starts to rise [s]; `particles` replaces the random insertion."""
    stl = os.path.join(os.path.dirname(os.path.abspath(path)), "floor.stl")
    with open(stl, "w") as f:
        f.write(FLOOR_STL)
    text = BOX_CASE.format(dt=dt, t_end=t_end, integrator=integrator, run=run,
                           dir=os.path.abspath(out_dir),
                           interval=interval if interval is not None else t_end / 100.0,
                           output=output, soft=soft, E=E, n=n, x0=x0, stl="floor.stl",
                           last_plane=LAST_PLANE if four_planes else "",
                           floor_start=floor_start, extra=extra,
                           particles=particles if particles is not None
                           else INSERT.format(n=n, soft=soft))
    with open(path, "w") as f:
        f.write(text)
    return path


# ---------------------------------------------------------------- checksums

_M1 = np.uint64(-4658895280553007687 & 0xFFFFFFFFFFFFFFFF)
_M2 = np.uint64(-7723592293110705685 & 0xFFFFFFFFFFFFFFFF)


def _mix(z):
    with np.errstate(over="ignore"):
        z = z ^ (z >> np.uint64(30))
        z = z * _M1
        z = z ^ (z >> np.uint64(27))
        z = z * _M2
        z = z ^ (z >> np.uint64(31))
    return z


def checksum(buf):
    """The checksum of a dataset's bytes (signed 64-bit, as stored)."""
    b = np.frombuffer(buf, dtype=np.uint8).astype(np.uint64)
    if b.size == 0:
        return 0
    k = np.arange(1, b.size + 1, dtype=np.uint64)
    return int(np.bitwise_xor.reduce(_mix(k | (b << np.uint64(56)))).astype(np.int64))


def dataset_bytes(d):
    """The bytes of a dataset as the solver checksums them."""
    a = d[()]
    if d.dtype.kind == "S":
        width = d.dtype.itemsize
        if isinstance(a, bytes):
            return a.ljust(width)
        return b"".join(x.ljust(width) for x in np.asarray(a).ravel())
    return np.ascontiguousarray(a).tobytes()


def datasets(f):
    """The names of all datasets of an open file, sorted."""
    names = []
    f.visititems(lambda name, obj: names.append(name) if isinstance(obj, h5py.Dataset)
                 else None)
    return sorted(names)


def bad_checksums(path):
    """The datasets of a file whose stored checksum is missing or does not match."""
    bad = []
    with h5py.File(path, "r") as f:
        for name in datasets(f):
            d = f[name]
            if "checksum" not in d.attrs or int(d.attrs["checksum"]) != checksum(
                    dataset_bytes(d)):
                bad.append(name)
    return bad


def read_group(path, group):
    """{dataset name: value} of the datasets of one group of a file."""
    with h5py.File(path, "r") as f:
        return {k: f[group][k][()] for k in f[group] if isinstance(f[group][k], h5py.Dataset)}


def same_bits(a, b):
    """Exact equality, bit for bit (so that -0.0 /= 0.0 and NaN == NaN of the same bits)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def differing(path_a, path_b, group, skip=()):
    """Names of the datasets of `group` that differ between two files (or exist in one)."""
    a, b = read_group(path_a, group), read_group(path_b, group)
    names = sorted(set(a) | set(b))
    return [k for k in names if k not in skip and (k not in a or k not in b or
                                                   not same_bits(a[k], b[k]))]


def checkpoint_files(out_dir):
    """Sorted names of the entries of <out_dir>/checkpoints."""
    d = os.path.join(out_dir, "checkpoints")
    return sorted(os.listdir(d)) if os.path.isdir(d) else []


def latest(out_dir):
    """The name held by <out_dir>/checkpoints/latest, or None."""
    p = os.path.join(out_dir, "checkpoints", "latest")
    if not os.path.exists(p):
        return None
    with open(p) as f:
        return f.read().strip()


def checkpoint_name(step):
    return f"checkpoints/checkpoint_{step:012d}.h5"


# ---------------------------------------------------------------- processes

def start(args, workdir, log, env=None):
    """Start the solver in the background, its stdout and stderr into log.out and log.err;
    returns the Popen object."""
    os.makedirs(workdir, exist_ok=True)
    full_env = dict(os.environ)
    if env:
        full_env.update(env)
    out = open(log + ".out", "w")
    err = open(log + ".err", "w")
    p = subprocess.Popen(args, cwd=workdir, stdout=out, stderr=err, env=full_env)
    out.close()
    err.close()
    return p


def wait_for(condition, timeout, poll=0.005):
    """Poll until condition() is true; returns whether it became true within timeout s."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(poll)
    return condition()


def finish_process(p, timeout):
    """Wait for a process; kill it (and return None) if it takes longer than timeout s."""
    try:
        return p.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.send_signal(signal.SIGKILL)
        p.wait()
        return None


def read_log(log):
    with open(log + ".out") as f:
        out = f.read()
    with open(log + ".err") as f:
        err = f.read()
    return out, err


def lines_of(path):
    """Number of lines of a text file (0 if it does not exist)."""
    try:
        with open(path, "rb") as f:
            return f.read().count(b"\n")
    except OSError:
        return 0


def crash_signs(text):
    """Signs of a crash rather than a clean error in a program's output."""
    signs = ("Backtrace", "Program received signal", "Error termination", "HDF5-DIAG",
             "Traceback", "Segmentation fault", "Fortran runtime error", "At line ",
             "MPI_ABORT", "#0 ", "core dumped")
    return [s for s in signs if s in text]


def tree_state(path):
    """{relative path: (size, mtime_ns, bytes)} of every file under path (empty if none),
    but the folder's lock file, which every run takes and releases."""
    state = {}
    if not os.path.exists(path):
        return state
    for root, dirs, files in os.walk(path):
        for name in dirs + files:
            full = os.path.join(root, name)
            rel = os.path.relpath(full, path)
            if rel == "lock":
                continue
            if os.path.isdir(full):
                state[rel + "/"] = None
            else:
                st = os.stat(full)
                with open(full, "rb") as f:
                    state[rel] = (st.st_size, st.st_mtime_ns, f.read())
    return state
