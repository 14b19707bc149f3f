# SPDX-License-Identifier: BSD-3-Clause
"""The package on several MPI ranks with mpi4py (CTest runs it on 2: mpirun -np 2 python3 -m
pytest test_mpi.py): a run on all ranks gives the same particles as the same case run on
rank 0 alone (COMM_SELF), bit for bit, and the same deposit; forces set by id from rank 0
reach the owners; a bed with two clumps gives the same bodies, consistent with their members,
and deposits each body's momentum once; the Stokes settling reaches the terminal velocity on whichever rank owns
the sphere; a friction sweep runs on all ranks. On one rank the same checks hold trivially."""
import math
import os

import numpy as np
import pytest

import dem
from conftest import GLASS, write_case

if os.environ.get("DEM_TEST_REQUIRE_MPI4PY"):          # the 2-rank CTest: no silent skip
    from mpi4py import MPI
else:
    MPI = pytest.importorskip("mpi4py.MPI")
WORLD = MPI.COMM_WORLD


@pytest.fixture
def shared(tmp_path):
    """A folder every rank uses: rank 0's."""
    return WORLD.bcast(str(tmp_path), root=0)


def bed(folder, name, extra=()):
    """125 spheres falling into a box (floor and four walls), and the groups `extra`,
    written by rank 0."""
    if WORLD.rank == 0:
        lines = ["&run dt = 1e-5, t_end = 1.0, gravity = 0, 0, -9.81 /",
                 f"&output dir = '{folder}/out_{name}', interval = 1e-3 /", GLASS,
                 "&material name = 'rigid', rigid = .true. /",
                 "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /",
                 "&pair materials = 'glass', 'rigid', restitution = 0.5, friction = 0.3 /",
                 "&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, "
                 "half_width = 0.02, divisions = 2 /"]
        for k in range(125):
            i, j, l = k % 5, (k // 5) % 5, k // 25
            lines.append(f"&particle id = {k + 1}, material = 'glass', radius = 1e-3, "
                         f"position = {2.2e-3 * i + 1e-5 * l}, {2.2e-3 * j}, "
                         f"{1.2e-3 + 2.2e-3 * l}, velocity = {0.01 * (j - 2)}, 0, 0 /")
        lines += extra
        write_case(folder, name + ".nml", lines)
    WORLD.Barrier()
    return os.path.join(folder, name + ".nml")


def gathered(run, comm):
    """Every rank's particles on rank 0 of comm, sorted by id: id, x, v, w columns."""
    p = run.particles()
    mine = np.column_stack([p.gid, p.x, p.v, p.w])
    parts = comm.gather(mine, root=0)
    if comm.rank != 0:
        return None
    a = np.concatenate(parts)
    return a[np.argsort(a[:, 0])]


def test_ranks_agree(shared):
    grid = ([-2e-3, -2e-3, -1e-3], [2e-3, 2e-3, 2e-3], (6, 6, 8))
    with dem.Run(bed(shared, "world"), comm=WORLD) as run:
        ids = np.arange(1, 126) if WORLD.rank == 0 else np.zeros(0, np.int64)
        push = np.tile([0.0, 0.0, 2e-5], (ids.size, 1))     # up, on every sphere, by id
        run.set_force_by_id(ids, push)
        for _ in range(5):
            run.advance(2e-3)
        counts = WORLD.allgather(run.count)
        assert run.body_count == 0 and run.bodies().id.size == 0      # no clumps
        world = gathered(run, WORLD)
        eps_world = run.deposit(*grid, kernel="trilinear").eps
    self_case = bed(shared, "self")                       # (collective: rank 0 writes)
    if WORLD.size > 1:
        assert min(counts) > 0, counts                    # both ranks own particles
    assert sum(counts) == 125
    if WORLD.rank == 0:
        with dem.Run(self_case, comm=MPI.COMM_SELF) as alone:
            alone.set_force_by_id(np.arange(1, 126), np.tile([0.0, 0.0, 2e-5], (125, 1)))
            for _ in range(5):
                alone.advance(2e-3)
            one = gathered(alone, MPI.COMM_SELF)
            eps_one = alone.deposit(*grid, kernel="trilinear").eps
        assert np.array_equal(world, one)                 # bit for bit
        assert np.array_equal(eps_world, eps_one)
    WORLD.Barrier()


R_MEMBER, RHO = 1e-3, 2500.0                     # the clumps' spheres, GLASS's density
# two clumps of equal spheres that do not overlap: a dimer (touching) and a triangle
CLUMPS = ["&clump_template name = 'dimer', material = 'glass', "
          "members = -1e-3, 0, 0, 1e-3,  1e-3, 0, 0, 1e-3 /",
          "&clump_template name = 'triangle', material = 'glass', "
          "members = 0, 0, 0, 1e-3,  2.4e-3, 0, 0, 1e-3,  1.2e-3, 2.2e-3, 0, 1e-3 /",
          "&clump template = 'dimer', position = -5e-3, -5e-3, 2.5e-3, "
          "orientation = 0.9238795325112867, 0, 0.3826834323650898, 0, "
          "velocity = 0.05, 0, -0.2, angular_velocity = 30, -20, 50 /",
          "&clump template = 'triangle', position = 12e-3, 12e-3, 2.5e-3, "
          "velocity = -0.05, 0.02, -0.2, angular_velocity = -40, 10, 25 /"]


def gathered_bodies(run, comm):
    """Every rank's bodies on rank 0 of comm, sorted by id: id, mass, x, v, q, w columns."""
    b = run.bodies()
    assert np.all(np.diff(b.id) > 0)                      # in increasing order of ids
    parts = comm.gather(np.column_stack([b.id, b.mass, b.x, b.v, b.q, b.w]), root=0)
    if comm.rank != 0:
        return None
    a = np.concatenate(parts)
    return a[np.argsort(a[:, 0])]


def test_bodies(shared):
    """Two clumps (ids after the 125 spheres', a body's that of its first member: 126 and 128)
    in the falling bed, hitting the floor while they spin: after the advances each body is
    owned once over the ranks, with its template's mass (n rho 4/3 pi r^3: its spheres do not
    overlap), its centre at its members' centroid (equal spheres), its members moving with it
    (v_m = V + w x (x_m - X), w_m = w) and a unit quaternion; the same bits as on rank 0 alone;
    and a deposit holds every sphere's m v and every body's M V once."""
    sphere = 4.0 / 3.0 * math.pi * R_MEMBER**3
    members = {126: [126, 127], 128: [128, 129, 130]}
    grid = ([-12e-3, -12e-3, -2e-3], [2e-3, 2e-3, 2e-3], (16, 16, 10))
    with dem.Run(bed(shared, "clumps_world", CLUMPS), comm=WORLD) as run:
        for _ in range(5):
            run.advance(2e-3)
        p, b = run.particles(), run.bodies()
        for k, i in enumerate(b.id):                      # the owner holds all the members
            at = [int(np.flatnonzero(p.gid == m)[0]) for m in members[int(i)]]
            assert b.mass[k] == pytest.approx(len(at) * RHO * sphere, rel=1e-12)
            assert b.x[k, 2] < 2.5e-3 - 5e-4                 # fallen from 2.5 mm
            assert np.allclose(b.x[k], p.x[at].mean(axis=0), rtol=0, atol=1e-12)
            assert abs(np.linalg.norm(b.q[k]) - 1.0) < 1e-12
            speed = np.linalg.norm(b.v[k]) + np.linalg.norm(b.w[k]) * 2.4e-3
            for i_m in at:
                rigid = b.v[k] + np.cross(b.w[k], p.x[i_m] - b.x[k])
                assert np.allclose(p.v[i_m], rigid, rtol=0, atol=1e-12 * speed)
                assert np.array_equal(p.w[i_m], b.w[k])
        if b.id.size:                                     # NULL arrays refused
            assert run._lib.dem_coupling_bodies(run._handle, *[None] * 6) == 2
        world = gathered_bodies(run, WORLD)
        dep = run.deposit(*grid)
        spheres = p.gid <= 125
        total = WORLD.allreduce(RHO * sphere * p.v[spheres].sum(axis=0)
                                + (b.mass[:, None] * b.v).sum(axis=0))
        volume = WORLD.allreduce(sphere * p.gid.size)
        counts = WORLD.allgather(run.body_count)
    assert sum(counts) == 2
    assert np.allclose(dep.momentum.sum(axis=(0, 1, 2)), total, rtol=1e-9,
                       atol=1e-12 * np.abs(total).max())
    assert dep.eps.sum() * 8e-9 == pytest.approx(volume, rel=1e-12)   # each member a sphere
    self_case = bed(shared, "clumps_self", CLUMPS)
    if WORLD.rank == 0:
        assert list(world[:, 0]) == [126, 128]
        with dem.Run(self_case, comm=MPI.COMM_SELF) as alone:
            for _ in range(5):
                alone.advance(2e-3)
            one = gathered_bodies(alone, MPI.COMM_SELF)
        assert np.array_equal(world, one)                 # bit for bit
    WORLD.Barrier()


def test_stokes_on_the_owner(shared):
    from test_stokes import G, MU, R, RHO_F, RHO_P, settling_case
    case = settling_case(shared) if WORLD.rank == 0 else None
    case = WORLD.bcast(case, root=0)
    volume = 4.0 / 3.0 * math.pi * R**3
    beta = 6.0 * math.pi * MU * R
    v_t = 2.0 * (RHO_P - RHO_F) * G * R**2 / (9.0 * MU)
    with dem.Run(case, comm=WORLD) as run:
        assert WORLD.allreduce(run.count) == 1
        for _ in range(100):
            run.set_drag(beta, [0.0, 0.0, 0.0])           # n = 0 on the other rank
            run.set_force([0.0, 0.0, RHO_F * volume * G])
            run.advance(1e-4)
        vz = [p[2] for p in run.particles().v]
        vz = WORLD.allreduce(vz)
    assert abs(vz[0] + v_t) < 1e-4 * v_t


def test_sweep_on_all_ranks(shared):
    """dem.sweep on every rank: rank 0 writes the cases, every rank runs them; the sphere's
    rolling speed is 5/7 v0 for each friction, on whichever rank owns it."""
    from test_sweep import V0, sliding
    case = sliding(shared) if WORLD.rank == 0 else None
    case = WORLD.bcast(case, root=0)

    def measure(run):
        return WORLD.allreduce([p[0] for p in run.particles().v])

    results = dem.sweep(case, "pair.friction", [0.2, 0.4], measure,
                        work_dir=os.path.join(shared, "sweep"), until=0.05, comm=WORLD)
    for mu, v in results:
        assert len(v) == 1 and abs(v[0] - 5.0 / 7.0 * V0) < 0.01 * V0, (mu, v)
