# SPDX-License-Identifier: BSD-3-Clause
"""HDF5 snapshots and their XDMF index, read as ParaView and h5py users read them.

1. snapshots.xmf is well-formed XML whose time series has one step per snapshot; every
   DataItem points at an existing file and dataset whose shape, number type and precision
   are the ones it declares; topology sizes agree with the datasets; each step's time is
   the snapshot's /time; the domain's Information element names the materials of
   /materials/name ("1 soft; 2 wall"); the walls carry the cell attributes wall and material.
2. The particle fields are consistent with each other and with series.csv: ids unique and
   ordered, radii within the inserted range, material names; the contact counts add up to
   2 x contacts_pp + contacts_pw of the series row of the same step (velocity Verlet, so
   that both are counted at the same positions); a particle without contacts carries
   exactly its weight m g (m = 4/3 pi R^3 rho computed here).
3. The walls are stored in their pose at the snapshot's time: the floor's corners equal the
   rigid motion of the STL (rise 0.01 m/s from 0.05 s to 0.15 s, spin 5 rad/s about z from
   0.1 s) computed here; the side planes do not move.
4. A snapshot seeds a new case as a particle file: that case's first snapshot holds the same
   ids, materials, positions, velocities and angular velocities, bit for bit.
usage: test_snapshots.py DEM WORKDIR"""
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

from regression_util import check, finish
import checkpoint_util as cu

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
RHO, G = 2500.0, 9.81


def write_case(name, t_end, output, integrator="symplectic_euler", particles=None):
    cu.write_box_case(os.path.join(work, name + ".nml"), os.path.join(work, f"out_{name}"),
                      t_end, interval=0.01, integrator=integrator, output=output,
                      particles=particles)


def run(case):
    r = subprocess.run([dem, case], cwd=work, capture_output=True, text=True, timeout=300)
    check(r.returncode == 0, f"dem {case}: exit {r.returncode}\n{r.stdout}{r.stderr}")


write_case("snap", t_end=0.12, integrator="velocity_verlet",
           output=", snapshot_interval = 0.02, snapshot_force = .true., "
                  "snapshot_contacts = .true.")
run("snap.nml")
out = os.path.join(work, "out_snap")
series = np.genfromtxt(os.path.join(out, "series.csv"), delimiter=",", names=True)

# 1. the XDMF index
root = ET.parse(os.path.join(out, "snapshots.xmf")).getroot()
info = root.find("Domain").findall("Information")
check(len(info) == 1 and info[0].get("Name") == "materials",
      "snapshots.xmf: one Information element, the material table")
table = info[0].get("Value") if info else None
steps = root.find("Domain").find("Grid").findall("Grid")
check(len(steps) == 7, f"7 time steps in snapshots.xmf (found {len(steps)})")
kinds = {"Float": "f", "Int": "i"}
snapshots = []
for grid in steps:
    time = float(grid.find("Time").get("Value"))
    files = set()
    for item in grid.iter("DataItem"):
        name, dataset = item.text.split(":")
        files.add(name)
        path = os.path.join(out, name)
        if not os.path.exists(path):
            check(False, f"{name} does not exist")
            continue
        with h5py.File(path) as f:
            if dataset not in f:
                check(False, f"{name}: no dataset {dataset}")
                continue
            d = f[dataset]
            dims = tuple(int(k) for k in item.get("Dimensions").split())
            check(d.shape == dims, f"{name}:{dataset}: shape {d.shape}, XDMF says {dims}")
            check(d.dtype.kind == kinds[item.get("NumberType")] and
                  d.dtype.itemsize == int(item.get("Precision")),
                  f"{name}:{dataset}: type {d.dtype}, XDMF says {item.get('NumberType')} "
                  f"{item.get('Precision')}")
    check(len(files) == 1, f"one snapshot file per step ({files})")
    walls = [g for g in grid.findall("Grid") if g.get("Name") == "walls"]
    check(len(walls) == 1 and [a.get("Name") for a in walls[0].findall("Attribute")] ==
          ["wall", "material"], "the walls carry the cell attributes wall and material")
    name = files.pop()
    snapshots.append(name)
    with h5py.File(os.path.join(out, name)) as f:
        check(f["time"][()] == time, f"{name}: XDMF time {time} is the snapshot's")
        n, n_tri = f["particles/id"].shape[0], f["walls/wall"].shape[0]
    for sub in grid.findall("Grid"):
        top = sub.find("Topology")
        expected = n if sub.get("Name") == "particles" else n_tri
        check(int(top.get("NumberOfElements")) == expected,
              f"{name}: {sub.get('Name')} topology of {expected} elements")
        for att in sub.findall("Attribute"):
            first = int(att.find("DataItem").get("Dimensions").split()[0])
            check(first == (n if att.get("Center") == "Node" else n_tri),
                  f"{name}: attribute {att.get('Name')} has one value per "
                  f"{att.get('Center').lower()}")

# 2. particle fields, 3. wall pose
contacts_seen = 0
for name in snapshots:
    with h5py.File(os.path.join(out, name)) as f:
        p = {k: f["particles"][k][()] for k in f["particles"]}
        step, time = int(f["step"][()]), float(f["time"][()])
        mats = [m.decode().strip() for m in f["materials/name"][()]]
        verts, wall = f["walls/vertices"][()], f["walls/wall"][()]
    check(np.all(np.diff(p["id"]) > 0), f"{name}: ids unique and ordered")
    check(np.all((p["radius"] >= 0.004) & (p["radius"] <= 0.005)), f"{name}: radii")
    check(mats == ["soft", "wall"] and np.all(p["material"] == 1), f"{name}: materials")
    check(table == "; ".join(f"{k} {m}" for k, m in enumerate(mats, 1)),
          f"{name}: the index's material table '{table}' names /materials/name")
    row = series[series["step"] == step]
    check(len(row) == 1 and p["contacts"].sum() == 2 * row["contacts_pp"][0] +
          row["contacts_pw"][0], f"{name}: contact counts add up to series.csv's")
    contacts_seen += p["contacts"].sum()
    free = p["contacts"] == 0
    weight = 4.0 / 3.0 * np.pi * p["radius"][free] ** 3 * RHO * np.array([0, 0, -G])[:, None]
    check(free.any() and np.allclose(p["force"][free], weight.T, rtol=1e-14, atol=0),
          f"{name}: the force on a particle without contacts is its weight")
    lift = 0.01 * (min(max(time, 0.05), 0.15) - 0.05)
    angle = 5.0 * max(time - 0.1, 0.0)
    rot = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0],
                    [0, 0, 1]])
    floor = np.array(cu.FLOOR).reshape(-1, 3) @ rot.T + [0, 0, lift]
    tris = np.repeat(wall, 3)
    check(np.allclose(verts[tris == wall.max()], floor, rtol=0, atol=1e-12),
          f"{name}: the floor in its pose at t = {time}")
    if name == snapshots[0]:
        sides = verts[tris != wall.max()]
    check(np.array_equal(verts[tris != wall.max()], sides), f"{name}: the side walls rest")

check(contacts_seen > 100, f"the snapshots hold contacts ({contacts_seen})")

# 4. a snapshot as a particle file
seed = os.path.join(out, snapshots[-1])
write_case("seeded", t_end=0.001, particles=f"&particle_file file = '{seed}' /\n",
           output=", snapshot_interval = 0.001")
run("seeded.nml")
with h5py.File(seed) as a, h5py.File(os.path.join(work, "out_seeded", "snapshots",
                                                  "snapshot_000000000000.h5")) as b:
    for k in ("id", "material", "radius", "position", "velocity", "angular_velocity"):
        check(cu.same_bits(a["particles"][k][()], b["particles"][k][()]),
              f"seeded from a snapshot: {k} bit for bit")
finish()
