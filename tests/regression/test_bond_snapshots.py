# SPDX-License-Identifier: BSD-3-Clause
"""The bonds and fragments of snapshots (doc/user/output.md), on a case whose bonds are known by
construction: spheres of R = 1 mm, E = 1e8 Pa, bonded where they touch, no gravity:
- a bar of 6 spheres along x (ids 2, 4, ..., 12), the first fixed, the last driven at
  V = 1 mm/s along the bar; its middle bond (ids 6-8, made by a first &bond group over a box
  around it) of tensile strength sigma_w = 1e5 Pa, the others unbreakable;
- a chain of 5 spheres at rest (ids 1, 3, 5, 7, 11), a triangle of 3 touching spheres at rest
  (ids 13, 14, 15) and a lone sphere (id 9).
Snapshots every 4 ms to t = 12 ms, with `snapshot_fragments`. Checked:
1. /bonds/pairs of each snapshot: every pair of touching spheres of the first snapshot
   (brute force over the positions), as rows of the id order, once each, lower row first,
   in increasing order; from the last snapshot on without the middle bond of the bar, which
   breaks when the bar has stretched by 5 sigma_w L / E (at 10 ms, quasi-static).
2. /bonds/stress_ratio: the weak bond's is sigma / sigma_w = E V t / (5 L sigma_w) (each of
   the 5 bonds carries the same force, quasi-static: within 2 %) at 4 and 8 ms; the resting
   bonds' 0; the unbreakable ones' below 1e-200.
3. /particles/fragment: the smallest id of each particle's component of the bonds (breadth-
   first search over the expected bonds): 3 fragments and the lone sphere before the break,
   the bar in two (ids 2-6 and 8-12) after it.
4. The snapshots' datasets and attributes and snapshots.xmf are the same bits on 1 and 3 ranks,
   and when the run is continued on 3 ranks from a checkpoint written on 2 at 8 ms (the index
   keeps the bond counts of the snapshots before it).
5. snapshots.xmf (xml.etree): each step has a `bonds` grid of Polyline topology, 2 nodes per
   element, as many as the snapshot's bonds, on the particles' positions, with the cell
   attribute stress_ratio; the particles carry `fragment`. Where VTK's Python is there,
   vtkXdmfReader reads the bonds as lines between the right particles.
6. scripts/post/fragments on the output folder: the fragments, their sizes and masses
   (N 4/3 pi R^3 rho) largest first, the largest's mass fraction 5/15; it refuses (exit 1) a
   snapshot whose /particles/fragment disagrees with its bonds.
7. A case without bonds: no /bonds, no bonds grid; with snapshot_fragments, fragment = id.
usage: test_bond_snapshots.py DEM WORKDIR MPIEXEC"""
import math
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from collections import deque

import h5py
import numpy as np

from regression_util import ROOT, check, check_close, finish, run_ranks, same_snapshots

dem, work, mpiexec = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

R, RHO, E, V, SIGMA_W, DT = 1.0e-3, 2500.0, 1.0e8, 1.0e-3, 1.0e5, 1.0e-6
L = 2.0 * R
M = RHO * 4.0 / 3.0 * math.pi * R**3
STEPS = [0, 4000, 8000, 12000]
T_BREAK = 5 * SIGMA_W * L / (E * V)                  # 10 ms

spheres = []                                         # (id, x, y, z, extra)
for k, i in enumerate([2, 4, 6, 8, 10, 12]):
    extra = {0: ", fixed = .true.", 5: f", velocity = {V}, 0, 0, fixed = .true."}.get(k, "")
    spheres.append((i, k * L, 0.0, 0.0, extra))
for k, i in enumerate([1, 3, 5, 7, 11]):
    spheres.append((i, k * L, 0.01, 0.0, ""))
spheres += [(13, 0.0, -0.01, 0.0, ""), (14, L, -0.01, 0.0, ""),
            (15, R, -0.01, math.sqrt(3.0) * R, ""), (9, 0.0, 0.0, 0.01, "")]


def case(name, t_end, bonds=True, fragments=True, checkpoint=0.0):
    rows = "\n".join(f"&particle id = {i}, material = 'm', radius = {R}, position = {x!r}, "
                     f"{y!r}, {z!r}{extra} /" for i, x, y, z, extra in spheres)
    text = f"""&run dt = {DT}, t_end = {t_end}, gravity = 0, 0, 0 /
&output dir = 'out_{name}', interval = 1e-3, snapshot_interval = 0.004,
        snapshot_fragments = {'.true.' if fragments else '.false.'},
        checkpoint_interval = {checkpoint} /
&material name = 'm', density = {RHO}, youngs_modulus = {E}, poisson_ratio = 0.3 /
&pair materials = 'm', 'm', restitution = 0.5, friction = 0.0 /
{rows}
"""
    if bonds:
        text += (f"&bond modulus = {E}, contact = .false., tensile_strength = {SIGMA_W}, "
                 f"region_min = {1.9 * L}, {-R}, {-R}, region_max = {3.1 * L}, {R}, {R} /\n"
                 f"&bond modulus = {E}, contact = .false. /\n")
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    return path


def snapshots(name):
    return [os.path.join(work, f"out_{name}", "snapshots", f"snapshot_{s:012d}.h5")
            for s in STEPS]


def components(n, pairs):
    """Breadth-first search: each row's component, named by its smallest row."""
    nbr = [[] for _ in range(n)]
    for a, b in pairs:
        nbr[a].append(b)
        nbr[b].append(a)
    comp = [-1] * n
    for start in range(n):
        if comp[start] >= 0:
            continue
        seen, todo = [start], deque([start])
        comp[start] = start
        while todo:
            for b in nbr[todo.popleft()]:
                if comp[b] < 0:
                    comp[b] = start
                    seen.append(b)
                    todo.append(b)
        for a in seen:
            comp[a] = min(seen)
    return np.array(comp)


for ranks in (1, 3):
    run_ranks(mpiexec, dem, case(f"r{ranks}", 0.012), ranks, work)

# 1. the bonds, brute force from the first snapshot's positions
with h5py.File(snapshots("r1")[0], "r") as f:
    ids, x0 = f["particles/id"][()], f["particles/position"][()]
row = {int(i): k for k, i in enumerate(ids)}
check(list(ids) == sorted(i for i, *_ in spheres), f"the particles by id: {list(ids)}")
touching = [(a, b) for a in range(len(ids)) for b in range(a + 1, len(ids))
            if np.linalg.norm(x0[a] - x0[b]) <= 2 * R * (1 + 1e-9)]
check(len(touching) == 5 + 4 + 3, f"{len(touching)} touching pairs, 12 by construction")
weak = (row[6], row[8])
rest = [(row[a], row[b]) for a, b in ((1, 3), (3, 5), (5, 7), (7, 11), (13, 14), (13, 15),
                                      (14, 15))]
for step, path in zip(STEPS, snapshots("r1")):
    with h5py.File(path, "r") as f:
        pairs = [tuple(p) for p in f["bonds/pairs"][()]]
        ratio = f["bonds/stress_ratio"][()]
        fragment = f["particles/fragment"][()]
        t = float(f["time"][()])
    expected = [p for p in touching if t < T_BREAK or p != weak]
    check(pairs == expected, f"step {step}: /bonds/pairs {pairs}, expected {expected}")
    if pairs != expected:
        continue
    # 2. the stress ratios
    by_pair = dict(zip(pairs, ratio))
    check(all(by_pair[p] == 0.0 for p in rest), f"step {step}: the resting bonds' ratio 0")
    strong = [p for p in pairs if p != weak and p not in rest]
    check(all(0.0 <= by_pair[p] < 1e-200 for p in strong),
          f"step {step}: the unbreakable bonds' ratios {[by_pair[p] for p in strong]}")
    if 0 < t < T_BREAK:
        check_close(by_pair[weak], E * V * t / (5 * L * SIGMA_W), 0.02,
                    f"step {step}: the weak bond's stress ratio")
    # 3. the fragments
    comp = components(len(ids), expected)
    check(np.array_equal(fragment, ids[comp]), f"step {step}: /particles/fragment "
          f"{list(fragment)}, expected {list(ids[comp])}")
    groups = sorted(np.unique(ids[comp], return_counts=True)[1].tolist())
    check(groups == ([1, 3, 3, 3, 5] if t > T_BREAK else [1, 3, 5, 6]),
          f"step {step}: fragment sizes {groups}")


# 4. the same bits on 1 and 3 ranks, and continued from a checkpoint
same_snapshots(snapshots("r1"), snapshots("r3"), "3 ranks")
run_ranks(mpiexec, dem, case("c", 0.008, checkpoint=0.008), 2, work)
with h5py.File(os.path.join(work, "out_c", "checkpoints", "checkpoint_000000008000.h5")) as f:
    check(list(f["state/snapshot_bonds"][()]) == [12, 12, 12],
          f"checkpoint: /state/snapshot_bonds {list(f['state/snapshot_bonds'][()])}")
run_ranks(mpiexec, dem, case("c", 0.012), 3, work, "--restart",
          os.path.join("out_c", "checkpoints", "checkpoint_000000008000.h5"))
same_snapshots(snapshots("r1"), snapshots("c"), "continued on 3 ranks from 2")

# 5. the XDMF index
xmf = os.path.join(work, "out_r1", "snapshots.xmf")
steps = ET.parse(xmf).getroot().find("Domain").find("Grid").findall("Grid")
check(len(steps) == len(STEPS), f"snapshots.xmf: {len(steps)} steps")
for step, path, grid in zip(STEPS, snapshots("r1"), steps):
    with h5py.File(path, "r") as f:
        nb = len(f["bonds/pairs"])
    h5 = os.path.relpath(path, os.path.join(work, "out_r1"))
    grids = {g.get("Name"): g for g in grid.findall("Grid")}
    check(sorted(grids) == ["bonds", "particles"], f"step {step}: grids {sorted(grids)}")
    if sorted(grids) != ["bonds", "particles"]:
        continue
    bonds, particles = grids["bonds"], grids["particles"]
    topo = bonds.find("Topology")
    check(topo.get("TopologyType") == "Polyline" and topo.get("NodesPerElement") == "2" and
          topo.get("NumberOfElements") == str(nb) and
          topo.find("DataItem").text == f"{h5}:/bonds/pairs" and
          topo.find("DataItem").get("Dimensions") == f"{nb} 2",
          f"step {step}: the bonds' topology {ET.tostring(topo).decode()}")
    check(ET.tostring(bonds.find("Geometry")) == ET.tostring(particles.find("Geometry")),
          f"step {step}: the bonds' points are the particles'")
    attrs = {a.get("Name"): a for a in bonds.findall("Attribute")}
    check("stress_ratio" in attrs and attrs["stress_ratio"].get("Center") == "Cell" and
          attrs["stress_ratio"].find("DataItem").text == f"{h5}:/bonds/stress_ratio",
          f"step {step}: the bonds' stress_ratio")
    check(any(a.get("Name") == "fragment" and a.find("DataItem").text ==
              f"{h5}:/particles/fragment" for a in particles.findall("Attribute")),
          f"step {step}: the particles' fragment")
try:
    import vtk
except ImportError:
    vtk = None
    print("(VTK's Python not found: the index not read with vtkXdmfReader)")
if vtk is not None:
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(xmf)
    reader.UpdateTimeStep(0.012)
    blocks = reader.GetOutputDataObject(0)
    lines = None
    for k in range(blocks.GetNumberOfBlocks()):
        if blocks.GetMetaData(k).Get(vtk.vtkCompositeDataSet.NAME()).startswith("bonds"):
            grid = blocks.GetBlock(k)
            lines = [tuple(grid.GetCell(c).GetPointId(j) for j in range(2))
                     for c in range(grid.GetNumberOfCells())
                     if grid.GetCell(c).GetNumberOfPoints() == 2]
    expected = [p for p in touching if p != weak]
    check(lines == expected, f"vtkXdmfReader: the bonds at 12 ms are the lines {lines}")

# 6. scripts/post/fragments
script = os.path.join(ROOT, "scripts", "post", "fragments")
table = os.path.join(work, "fragments.csv")
r = subprocess.run([sys.executable, script, os.path.join(work, "out_r1"), "--csv", table,
                    "--plot", os.path.join(work, "fragments.png")],
                   capture_output=True, text=True)
print(r.stdout, r.stderr)
check(r.returncode == 0, f"fragments: exit {r.returncode}")
got = np.genfromtxt(table, delimiter=",", names=True, dtype=None)
check([(int(a), int(b)) for a, b in zip(got["fragment"], got["spheres"])] ==
      [(1, 5), (2, 3), (8, 3), (13, 3), (9, 1)], f"fragments: {got}")
check(np.allclose(got["mass"], got["spheres"] * M, rtol=1e-12, atol=0),
      f"fragments: masses {got['mass']}, expected spheres x {M:.9g} kg")
check(f"mass fraction {5 / 15:.6f}" in r.stdout, "fragments: the largest's mass fraction")
check(os.path.getsize(os.path.join(work, "fragments.png")) > 0, "fragments: the plot")
bad = os.path.join(work, "bad.h5")
shutil.copy(snapshots("r1")[-1], bad)
with h5py.File(bad, "r+") as f:
    f["particles/fragment"][0] = 2                    # id 1 put in the bar's fragment
r = subprocess.run([sys.executable, script, bad, "--density", f"m={RHO}"],
                   capture_output=True, text=True)
check(r.returncode == 1 and "disagrees" in r.stderr, f"fragments: a wrong "
      f"/particles/fragment refused: exit {r.returncode}, {r.stderr.strip()}")

# 7. without bonds
for name, fragments in (("plain", False), ("plain_fragments", True)):
    run_ranks(mpiexec, dem, case(name, 0.004, bonds=False, fragments=fragments), 2, work)
    with h5py.File(snapshots(name)[1], "r") as f:
        check("bonds" not in f, f"{name}: no /bonds")
        check(("fragment" in f["particles"]) == fragments, f"{name}: /particles/fragment "
              f"{'written' if fragments else 'not written'}")
        if fragments:
            check(np.array_equal(f["particles/fragment"][()], f["particles/id"][()]),
                  f"{name}: each particle its own fragment")
    with open(os.path.join(work, f"out_{name}", "snapshots.xmf")) as f:
        check('Name="bonds"' not in f.read(), f"{name}: no bonds grid")
finish()
