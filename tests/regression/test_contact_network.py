# SPDX-License-Identifier: BSD-3-Clause
"""The contact network and the wall stress of snapshots (doc/user/output.md), on spheres at
rest on a floor under gravity: a tetrahedral pile of 4 (ids 3, 1, 6 on the floor, 2 on top)
and a column of 2 (id 5 on the floor, 4 on it), R = 5 mm, friction 0.5, velocity Verlet with
local damping, a floor of 8 triangles ('floor') and a side wall nothing touches ('side'), a
wall_load probe on the floor. Snapshots at 0, 0.1 and 0.2 s with `snapshot_contact_network`
and `snapshot_wall_stress`. Checked on the last snapshot (at rest: speeds below 1e-9 m/s):
1. /contacts/pairs: the pairs that overlap, brute force over the positions (the kernel's
   test), once each, lower row first, in increasing order.
2. Newton: each sphere's weight m g plus the forces of its lines (/contacts/force on the first
   particle, its opposite on the second) plus the floor's force on it sums to zero, so the
   spheres off the floor (ids 2 and 4) take m g from their lines (rtol 1e-6), and the floor's
   force on each sphere on it, -(m g + its lines), is upward and within Coulomb's cone
   (|F_t| <= 0.5 F_n); the column's contact carries fn = m g.
3. Each contact: force = -fn n + F_t, n the unit vector from the first centre to the second,
   F_t perpendicular to n.
4. /walls/force summed over the triangles is the floor's wall_load probe of the same step
   (rtol 1e-12) and the weight of the 6 spheres (rtol 1e-6); each triangle's pressure x area
   is its force's normal component, its shear x area the rest (rtol 1e-9); the side wall's
   triangles carry nothing.
5. The snapshots' datasets and attributes and snapshots.xmf are the same bits on 1 and 2
   ranks, and when the run is continued on 1 rank from a checkpoint written on 2 at 0.1 s.
6. snapshots.xmf (xml.etree): each step with contacts has a `contacts` grid of Polyline
   topology over /contacts/pairs on the particles' positions with the cell attributes
   normal_force, force, tangential_force; the walls grid carries force, pressure, shear; an
   Information element names the walls. Where VTK's Python is there, vtkXdmfReader reads the
   contacts as the lines between the right particles.
7. scripts/post/to-vtu: meshio reads its VTU files back with the snapshot's points, lines,
   triangles and data.
8. A case without the two keys: no /contacts, no /walls/force, no contacts grid, and no walls
   Information element where no wall is named.
usage: test_contact_network.py DEM WORKDIR MPIEXEC"""
import math
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

from regression_util import ROOT, check, check_close, finish, run_ranks, same_snapshots

dem, work, mpiexec = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]), sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

R, RHO, G, MU = 5.0e-3, 2500.0, 9.81, 0.5
M = RHO * 4.0 / 3.0 * math.pi * R**3
STEPS = [0, 5000, 10000]
pos = {}
for i, a in zip((3, 1, 6), (90.0, 210.0, 330.0)):
    a = math.radians(a)
    pos[i] = (2 * R / math.sqrt(3) * math.cos(a), 2 * R / math.sqrt(3) * math.sin(a), R)
pos[2] = (0.0, 0.0, R + 2 * R * math.sqrt(2.0 / 3.0))
pos[5], pos[4] = (0.025, 0.02, R), (0.025, 0.02, 3 * R)


def case(name, t_end, network=True, named=True, checkpoint=0.0):
    rows = "\n".join(f"&particle id = {i}, material = 'bead', radius = {R}, position = "
                     f"{x!r}, {y!r}, {z!r} /" for i, (x, y, z) in sorted(pos.items()))
    keys = "snapshot_contact_network = .true., snapshot_wall_stress = .true.," if network else ""
    floor, side = (", name = 'floor'", ", name = 'side'") if named else ("", "")
    probe = "&probe name = 'floor', kind = 'wall_load', wall = 'floor' /" if named else ""
    text = f"""&run dt = 2e-5, t_end = {t_end}, gravity = 0, 0, {-G},
     integrator = 'velocity_verlet', local_damping = 0.3 /
&output dir = 'out_{name}', interval = 0.1, snapshot_interval = 0.1, {keys}
        checkpoint_interval = {checkpoint} /
&material name = 'bead', density = {RHO}, youngs_modulus = 1e7, poisson_ratio = 0.3 /
&material name = 'steel', density = 7800, youngs_modulus = 1e7, poisson_ratio = 0.3 /
&pair materials = 'bead', 'bead', restitution = 0.3, friction = {MU} /
&pair materials = 'bead', 'steel', restitution = 0.3, friction = {MU} /
&wall_plane material = 'steel', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05,
            divisions = 2{floor} /
&wall_plane material = 'steel', point = 0.045, 0, 0.02, normal = -1, 0, 0,
            half_width = 0.02{side} /
{probe}
{rows}
"""
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    return path


def snapshots(name):
    return [os.path.join(work, f"out_{name}", "snapshots", f"snapshot_{s:012d}.h5")
            for s in STEPS]


for ranks in (1, 2):
    run_ranks(mpiexec, dem, case(f"r{ranks}", 0.2), ranks, work)

with h5py.File(snapshots("r1")[-1], "r") as f:
    ids, x, v = f["particles/id"][()], f["particles/position"][()], f["particles/velocity"][()]
    radius = f["particles/radius"][()]
    pairs = [tuple(int(a) for a in p) for p in f["contacts/pairs"][()]]
    fn, force = f["contacts/normal_force"][()], f["contacts/force"][()]
    ft = f["contacts/tangential_force"][()]
    wall_force, pressure = f["walls/force"][()], f["walls/pressure"][()]
    shear, vert = f["walls/shear"][()], f["walls/vertices"][()]
    tri, wall = f["walls/triangles"][()], f["walls/wall"][()]
    wall_names = [n.decode().strip() for n in f["walls/name"][()]]
row = {int(i): k for k, i in enumerate(ids)}
check(np.abs(v).max() < 1e-9, f"at rest: the largest speed {np.abs(v).max():.3g} m/s")

# 1. the pairs, brute force
expected = []
for a in range(len(ids)):
    for b in range(a + 1, len(ids)):
        d = x[b] - x[a]
        if d[0]**2 + d[1]**2 + d[2]**2 < (radius[a] + radius[b])**2:
            expected.append((a, b))
check(pairs == expected, f"/contacts/pairs {pairs}, expected {expected}")
check(len(pairs) == 7, f"{len(pairs)} contacts: the pile's 6 and the column's 1")

# 2. Newton on each sphere
weight = np.array([0.0, 0.0, -M * G])
lines = np.zeros((len(ids), 3))
for (a, b), fc in zip(pairs, force):
    lines[a] += fc
    lines[b] -= fc
for i in (2, 4):                                     # off the floor
    k = row[i]
    check(np.linalg.norm(lines[k] + weight) <= 1e-6 * M * G,
          f"id {i}: its lines {lines[k]} balance its weight {M * G:.9g} N")
for i in (3, 1, 6, 5):                               # on the floor
    floor = -(lines[row[i]] + weight)
    check(floor[2] > 0 and math.hypot(floor[0], floor[1]) <= MU * floor[2],
          f"id {i}: the floor's force on it {floor} upward, within Coulomb's cone")
column = pairs.index(tuple(sorted((row[4], row[5]))))
check_close(fn[column], M * G, 1e-6, "the column's contact: fn = m g")

# 3. each contact's force
for (a, b), n_force, f_c, t_c in zip(pairs, fn, force, ft):
    n = (x[b] - x[a]) / np.linalg.norm(x[b] - x[a])
    check(np.linalg.norm(f_c - (-n_force * n + t_c)) <= 1e-9 * abs(n_force) and
          abs(np.dot(t_c, n)) <= 1e-6 * max(np.linalg.norm(t_c), 1e-300) + 1e-18,
          f"pair {a}-{b}: force = -fn n + F_t, F_t perpendicular to n")

# 4. the walls' triangles
with open(os.path.join(work, "out_r1", "probes.csv")) as f:
    head, *table = [line.strip().split(",") for line in f]
last = dict(zip(head, (float(c) for c in table[-1])))
total = wall_force.sum(axis=0)
probe = np.array([last["floor_fx"], last["floor_fy"], last["floor_fz"]])
check(np.linalg.norm(total - probe) <= 1e-12 * np.linalg.norm(probe),
      f"/walls/force summed {total}, the wall_load probe {probe}")
check_close(-total[2], 6 * M * G, 1e-6, "/walls/force summed: the weight of the 6 spheres")
for k, t in enumerate(tri):
    c = vert[t]
    nrm = np.cross(c[1] - c[0], c[2] - c[0])
    area = 0.5 * np.linalg.norm(nrm)
    nrm /= np.linalg.norm(nrm)
    normal = abs(np.dot(wall_force[k], nrm))
    tangential = np.linalg.norm(wall_force[k] - np.dot(wall_force[k], nrm) * nrm)
    check(abs(pressure[k] * area - normal) <= 1e-9 * M * G and
          abs(shear[k] * area - tangential) <= 1e-9 * M * G,
          f"triangle {k}: pressure {pressure[k]:.9g} and shear {shear[k]:.9g} Pa")
side = wall == wall_names.index("side") + 1
check(wall_names == ["floor", "side"] and side.sum() == 2 and
      not wall_force[side].any() and not pressure[side].any(),
      f"the side wall ({wall_names}) carries nothing")


# 5. the same bits on 1 and 2 ranks, and continued from a checkpoint
same_snapshots(snapshots("r1"), snapshots("r2"), "2 ranks")
run_ranks(mpiexec, dem, case("c", 0.1, checkpoint=0.1), 2, work)
with h5py.File(os.path.join(work, "out_c", "checkpoints", "checkpoint_000000005000.h5")) as f:
    counts = list(f["state/snapshot_contacts"][()])
with h5py.File(snapshots("r1")[1], "r") as f:
    check(counts[-1] == len(f["contacts/pairs"]), f"checkpoint: /state/snapshot_contacts "
          f"{counts}")
run_ranks(mpiexec, dem, case("c", 0.2), 1, work, "--restart",
          os.path.join("out_c", "checkpoints", "checkpoint_000000005000.h5"))
same_snapshots(snapshots("r1"), snapshots("c"), "continued on 1 rank from 2")

# 6. the XDMF index
xmf = os.path.join(work, "out_r1", "snapshots.xmf")
domain = ET.parse(xmf).getroot().find("Domain")
info = {i.get("Name"): i.get("Value") for i in domain.findall("Information")}
check(info.get("walls") == "1 floor; 2 side" and info.get("materials") == "1 bead; 2 steel",
      f"snapshots.xmf: the name tables {info}")
steps = domain.find("Grid").findall("Grid")
check(len(steps) == len(STEPS), f"snapshots.xmf: {len(steps)} steps")
for step, path, grid in zip(STEPS, snapshots("r1"), steps):
    with h5py.File(path, "r") as f:
        nc = len(f["contacts/pairs"])
    h5 = os.path.relpath(path, os.path.join(work, "out_r1"))
    grids = {g.get("Name"): g for g in grid.findall("Grid")}
    check(sorted(grids) == (["contacts", "particles", "walls"] if nc else ["particles", "walls"]),
          f"step {step}: grids {sorted(grids)}")
    attrs = {a.get("Name"): a for a in grids["walls"].findall("Attribute")}
    check(all(attrs.get(k) is not None and attrs[k].get("Center") == "Cell" and
              attrs[k].find("DataItem").text == f"{h5}:/walls/{k}"
              for k in ("force", "pressure", "shear")), f"step {step}: the walls' loads")
    if "contacts" not in grids:
        continue
    contacts = grids["contacts"]
    topo = contacts.find("Topology")
    check(topo.get("TopologyType") == "Polyline" and topo.get("NodesPerElement") == "2" and
          topo.get("NumberOfElements") == str(nc) and
          topo.find("DataItem").text == f"{h5}:/contacts/pairs" and
          topo.find("DataItem").get("Dimensions") == f"{nc} 2",
          f"step {step}: the contacts' topology {ET.tostring(topo).decode()}")
    check(ET.tostring(contacts.find("Geometry")) ==
          ET.tostring(grids["particles"].find("Geometry")),
          f"step {step}: the contacts' points are the particles'")
    attrs = {a.get("Name"): a for a in contacts.findall("Attribute")}
    check(all(attrs.get(k) is not None and attrs[k].get("Center") == "Cell" and
              attrs[k].find("DataItem").text == f"{h5}:/contacts/{k}"
              for k in ("normal_force", "force", "tangential_force")),
          f"step {step}: the contacts' attributes")
try:
    import vtk
except ImportError:
    vtk = None
    print("(VTK's Python not found: the index not read with vtkXdmfReader)")
if vtk is not None:
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(xmf)
    reader.UpdateTimeStep(0.2)
    blocks = reader.GetOutputDataObject(0)
    lines, names = None, []
    for k in range(blocks.GetNumberOfBlocks()):
        names.append(blocks.GetMetaData(k).Get(vtk.vtkCompositeDataSet.NAME()))
        if names[-1].startswith("contacts"):
            grid = blocks.GetBlock(k)
            lines = [tuple(grid.GetCell(c).GetPointId(j) for j in range(2))
                     for c in range(grid.GetNumberOfCells())]
            fns = [grid.GetCellData().GetArray("normal_force").GetValue(c)
                   for c in range(grid.GetNumberOfCells())]
            check(np.array_equal(fns, fn), "vtkXdmfReader: the contacts' normal_force")
    check(lines == pairs, f"vtkXdmfReader: the contacts at 0.2 s are the lines {lines} "
                          f"(blocks {names})")

# 7. scripts/post/to-vtu, read back with meshio
try:
    import meshio
except ImportError:
    meshio = None
    check(False, "meshio not found (scripts/install/install-deps installs it into .venv)")
if meshio is not None:
    out = os.path.join(work, "vtu")
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "post", "to-vtu"),
                        os.path.join(work, "out_r1"), "--out", out],
                       capture_output=True, text=True)
    print(r.stdout, r.stderr)
    check(r.returncode == 0, f"to-vtu: exit {r.returncode}")
    step = f"{STEPS[-1]:012d}"
    p = meshio.read(os.path.join(out, f"particles_{step}.vtu"))
    check(np.array_equal(p.points, x) and np.array_equal(p.point_data["radius"], radius) and
          np.array_equal(p.point_data["id"], ids), "to-vtu: the particles")
    c = meshio.read(os.path.join(out, f"contacts_{step}.vtu"))
    check(np.array_equal(c.points, x) and
          [tuple(e) for e in c.cells_dict["line"]] == pairs and
          np.array_equal(c.cell_data["normal_force"][0], fn) and
          np.array_equal(c.cell_data["force"][0], force) and
          np.array_equal(c.cell_data["tangential_force"][0], ft), "to-vtu: the contacts")
    w = meshio.read(os.path.join(out, f"walls_{step}.vtu"))
    check(np.array_equal(w.points, vert) and np.array_equal(w.cells_dict["triangle"], tri) and
          np.array_equal(w.cell_data["force"][0], wall_force) and
          np.array_equal(w.cell_data["pressure"][0], pressure), "to-vtu: the walls")
    with open(os.path.join(out, "contacts.pvd")) as f:
        check(f.read().count("<DataSet ") == sum(
            1 for s in STEPS if os.path.exists(os.path.join(out, f"contacts_{s:012d}.vtu"))),
            "to-vtu: contacts.pvd lists every contacts file")

# 8. without the keys
run_ranks(mpiexec, dem, case("plain", 0.1, network=False, named=False), 1, work)
with h5py.File(snapshots("plain")[1], "r") as f:
    check("contacts" not in f and "force" not in f["walls"] and "name" not in f["walls"],
          "plain: no /contacts, /walls/force, /walls/name")
with open(os.path.join(work, "out_plain", "snapshots.xmf")) as f:
    text = f.read()
check('Name="contacts"' not in text and 'Name="pressure"' not in text and
      'Name="walls" Value' not in text, "plain: no contacts grid, wall loads or wall names")
finish()
