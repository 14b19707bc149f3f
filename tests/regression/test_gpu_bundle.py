# SPDX-License-Identifier: BSD-3-Clause
"""The GPU bundle (scripts/install/gpu-bundle, doc/user/gpu.md) is self-contained: packed from
this OpenACC build without the beds, it runs a short case (the settling box with a moving STL
floor, a snapshot and a checkpoint: particle and wall contacts, parallel HDF5) on 1 and 2 ranks
with nothing from the environment but what its own env.sh sets (env -i), on the host fallback,
and writes the same files, byte for byte, as the plain build (REFERENCE_DEM, with the system's
mpiexec on 2 ranks). Every shared object the runs load (the dynamic loader's LD_DEBUG=libs log
of mpirun and of every rank) comes from the bundle, but the C library's, and libgomp's nvptx
plugin is among them. The bundle's size without beds is under 60 MiB. Then the bundle's
gpu-check runs dry (--host, a bed of 300 spheres, 10 steps, on 1 and 2 ranks) and finds the
trajectories equal to its host reference's, and no traffic between host and device per step
on one rank (acc_data's counts), the halo's on two.

With --chroot DIR (scripts/dev/check-gpu-bundle), the bundle's runs are made inside that root
(a minimal Debian: debootstrap --variant=minbase, none of the bundle's libraries installed),
with /proc, /sys and /dev bound into it.

usage: test_gpu_bundle.py DEM WORKDIR REFERENCE_DEM MPIEXEC [--chroot DIR]"""
import filecmp
import glob
import os
import re
import shutil
import subprocess
import sys
import time

from regression_util import ROOT, check, finish
import checkpoint_util as cu

dem, work, reference, mpiexec = sys.argv[1:5]
dem, reference = os.path.abspath(dem), os.path.abspath(reference)
chroot = sys.argv[sys.argv.index("--chroot") + 1] if "--chroot" in sys.argv else None
work = os.path.abspath(work)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
GLIBC = re.compile(r"^(ld-linux[-a-z0-9_]*\.so\.\d+|libc\.so\.6|libm\.so\.6|libmvec\.so\.1|"
                   r"libpthread\.so\.0|libdl\.so\.2|librt\.so\.1|libresolv\.so\.2|"
                   r"libutil\.so\.1|libnss_\w+\.so\.\d+)$")

# the bundle is of a build with nvptx offload (gcc-offload-nvptx, which install-deps installs)
mkoffload = subprocess.run(["gfortran", "-print-prog-name=accel/nvptx-none/mkoffload"],
                           capture_output=True, text=True).stdout.strip()
if not os.path.exists(mkoffload):
    print("test_gpu_bundle: skipped: gcc-offload-nvptx is not installed (no nvptx offload)")
    sys.exit(0)

# 1. the bundle, without beds
t0 = time.time()
top = work
if chroot:                       # the bundle and the cases inside the root, same paths there
    top = os.path.join(chroot, "gpu-bundle-check")
    shutil.rmtree(top, ignore_errors=True)
    os.makedirs(top)
bundle = os.path.join(top, "bundle")
r = subprocess.run([os.path.join(ROOT, "scripts", "install", "gpu-bundle"), "--exe", dem,
                    "--exe-sm80", "", "--out", bundle, "--no-beds"], capture_output=True, text=True)
print(r.stdout, r.stderr)
check(r.returncode == 0, f"gpu-bundle failed: {r.stderr[-2000:]}")
size = sum(os.path.getsize(p) for p in glob.glob(bundle + "/**", recursive=True)
           if os.path.isfile(p) and not os.path.islink(p))
print(f"bundle: {size / 2**20:.1f} MiB without beds, packed in {time.time() - t0:.1f} s")
check(size < 60 * 2**20, f"the bundle is {size / 2**20:.1f} MiB, not under 60")


def inside(path):
    """A path of this machine as the bundle's runs see it."""
    return "/" + os.path.relpath(path, chroot) if chroot else path


# 2. the case: the settling box, short, with a snapshot and a checkpoint
def case(folder):
    os.makedirs(folder)
    path = os.path.join(folder, "box.nml")
    cu.write_box_case(path, os.path.join(folder, "output"), t_end=0.02, n=200, interval=0.002,
                      output=", snapshot_interval = 0.01, checkpoint_interval = 0.01")
    with open(path) as f:                     # the output folder relative to the run's folder
        text = f.read().replace(os.path.join(folder, "output"), "output")
    with open(path, "w") as f:
        f.write(text)
    return path


def run(cmd, cwd, env=None):
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=300, env=env)
    check(r.returncode == 0, f"{' '.join(cmd)} in {cwd}: exit {r.returncode}: "
                             f"{(r.stdout + r.stderr)[-3000:]}")
    return r


def bundle_run(ranks, folder):
    """The bundle's dem on `ranks` ranks in `folder`, the environment emptied (env -i), the
    loader's log of every process in folder/ld.*."""
    exe = [inside(os.path.join(bundle, "bin", "dem")), "box.nml"]
    if ranks > 1:
        exe = [inside(os.path.join(bundle, "bin", "mpirun")), "-np", str(ranks)] + exe
    env = ["env", "-i", "PATH=/usr/bin:/bin", "LD_DEBUG=libs",
           f"LD_DEBUG_OUTPUT={inside(folder)}/ld"]
    if chroot:
        cmd = ["chroot", chroot, "/bin/sh", "-c",
               f"cd {inside(folder)} && exec " + " ".join(env + exe)]
        return run(cmd, "/")
    return run(env + exe, folder)


def loaded(folder):
    """The shared objects the loader initialised for the bundle's programs (dem, orterun,
    orted; not the shell and the tools of the wrappers bin/dem and bin/mpirun), from its
    LD_DEBUG logs in folder: a log holds the images a process went through (exec), each
    from its 'initialize program:' line."""
    objects, programs = set(), set()
    for log in glob.glob(os.path.join(folder, "ld.*")):
        with open(log, errors="replace") as f:
            text = f.read()
        for image in re.split(r"\n\s*\d+:\s+initialize program: ", text)[1:]:
            program = os.path.basename(image.split("\n", 1)[0].strip())
            if program in ("dem", "orterun", "orted", "mpirun"):
                programs.add(program)
                objects |= set(re.findall(r"calling init: (\S+)", image))
        os.remove(log)
    return objects, programs


def outputs(top_dir):
    return sorted(os.path.relpath(os.path.join(d, f), top_dir)
                  for d, _, names in os.walk(top_dir) for f in names)


mounts = []
if chroot:
    for m in ("proc", "sys", "dev", "dev/shm"):
        target = os.path.join(chroot, m)
        os.makedirs(target, exist_ok=True)
        if subprocess.run(["mount", "--bind", "/" + m, target]).returncode == 0:
            mounts.append(target)
try:
    for ranks in (1, 2):
        ref = case(os.path.join(work, f"plain_{ranks}"))
        cmd = [reference, "box.nml"] if ranks == 1 else \
            [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", "2", reference, "box.nml"]
        run(cmd, os.path.dirname(ref))
        folder = os.path.dirname(case(os.path.join(top, f"bundle_{ranks}")))
        t1 = time.time()
        r = bundle_run(ranks, folder)
        print(f"bundle on {ranks} rank(s): {time.time() - t1:.1f} s")
        objects, programs = loaded(folder)
        check("dem" in programs and ("orted" in programs or "orterun" in programs),
              f"{ranks} rank(s): the loader's logs name the programs {sorted(programs)}")
        root_in = inside(bundle) + "/"
        foreign = sorted(o for o in objects if not o.startswith(root_in)
                         and not GLIBC.match(os.path.basename(o)))
        check(not foreign, f"{ranks} rank(s): loaded from outside the bundle: {foreign}")
        check(any(o.endswith("libgomp-plugin-nvptx.so.1") for o in objects),
              f"{ranks} rank(s): libgomp's nvptx plugin was not loaded")
        check(any("openmpi3/mca_" in o for o in objects),
              f"{ranks} rank(s): no Open MPI component was loaded")
        print(f"{ranks} rank(s): {len(objects)} shared objects loaded, "
              f"{len(objects) - len(foreign)} of them the bundle's or the C library's")
        a, b = os.path.join(os.path.dirname(ref), "output"), os.path.join(folder, "output")
        names = outputs(a)
        check(names == outputs(b), f"{ranks} rank(s): other files: {names} / {outputs(b)}")
        check("final.csv" in names and any(n.startswith("checkpoints/") for n in names),
              f"{ranks} rank(s): outputs {names}")
        same = [name for name in names if os.path.exists(os.path.join(b, name))
                and filecmp.cmp(os.path.join(a, name), os.path.join(b, name), shallow=False)]
        check(same == names, f"{ranks} rank(s): {sorted(set(names) - set(same))} differ "
                             f"between the bundle and {reference}")
        print(f"{ranks} rank(s): {len(same)} of {len(names)} files byte for byte the plain "
              f"build's")
finally:
    for target in reversed(mounts):
        subprocess.run(["umount", target])

# 3. gpu-check's dry run (--host: everything on the host fallback) on a small bed of 300
# spheres on a lattice in the impact box, made an HDF5 particle file by the bundle's dem (its
# snapshot at t = 0), as gpu-bundle makes the beds: every run ends, and each trajectory is
# the reference's, byte for byte
if not chroot:
    beds = os.path.join(work, "beds")
    os.makedirs(beds)
    with open(os.path.join(beds, "lattice.csv"), "w") as f:
        f.write("id,material,radius,x,y,z\n")
        for k in range(300):
            layer, j = divmod(k, 20 * 10)
            f.write(f"{k + 1},M1,0.001,{-0.0205 + 0.0021 * (j // 10)!r},"
                    f"{-0.0095 + 0.0021 * (j % 10)!r},{-0.08914 + 0.0021 * layer!r}\n")
    with open(os.path.join(beds, "bed.nml"), "w") as f:
        f.write("&run dt = 5e-07, t_end = 5e-07 /\n"
                "&output dir = 'out', interval = 1, snapshot_interval = 1 /\n"
                "&material name = 'M1', density = 2500.0, youngs_modulus = 1e+09, "
                "poisson_ratio = 0.2 /\n&pair materials = 'M1', 'M1', restitution = 0.5, "
                "friction = 0.3 /\n&particle_file file = 'lattice.csv' /\n")
    run([os.path.join(bundle, "bin", "dem"), "bed.nml"], beds)
    shutil.copy(os.path.join(beds, "out", "snapshots", "snapshot_000000000000.h5"),
                os.path.join(beds, "bed_300.h5"))
    t1 = time.time()
    out = os.path.join(work, "gpu-check")
    r = subprocess.run([sys.executable, os.path.join(bundle, "gpu-check"), "--host",
                        "--sizes", "300", "--steps", "10", "--beds", beds, "--out", out],
                       capture_output=True, text=True, timeout=300)
    print(r.stdout[-3000:], r.stderr[-2000:])
    check(r.returncode == 0, f"gpu-check --host: exit {r.returncode}")
    rows = open(os.path.join(out, "results.csv")).read() if r.returncode == 0 else ""
    check(rows.count("final.csv identical; probes.csv identical") == 2,
          f"gpu-check --host: the runs on 1 and 2 ranks are not the reference's: {rows}")
    check(all(os.path.exists(os.path.join(out, f)) for f in ("gpu-check.log", "runs.tar.gz")),
          "gpu-check --host: its log and runs.tar.gz")
    # on one rank a step moves nothing between host and device (acc_data's counts, the same
    # on the host fallback as on a GPU: doc/user/gpu.md); on two, the halo through the host
    import csv
    table = {row["run"]: row for row in csv.DictReader(open(os.path.join(out, "results.csv")))} \
        if r.returncode == 0 else {}
    one, two = table.get("host_300_1rank", {}), table.get("host_300_2rank", {})
    check(one.get("h2d_bytes_per_step") == "0" and one.get("d2h_bytes_per_step") == "0",
          f"gpu-check --host: traffic per step on one rank: {one}")
    check(int(two.get("h2d_bytes_per_step") or 0) > 0,
          f"gpu-check --host: no halo traffic per step on two ranks: {two}")
    print(f"gpu-check --host: {time.time() - t1:.1f} s")
print(f"test_gpu_bundle: {time.time() - t0:.1f} s in all")
finish()
