# SPDX-License-Identifier: BSD-3-Clause
"""The package on several MPI ranks with mpi4py (CTest runs it on 2: mpirun -np 2 python3 -m
pytest test_mpi.py): a run on all ranks gives the same particles as the same case run on
rank 0 alone (COMM_SELF), bit for bit, and the same deposit; forces set by id from rank 0
reach the owners; the Stokes settling reaches the terminal velocity on whichever rank owns
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


def bed(folder, name):
    """125 spheres falling into a box (floor and four walls), written by rank 0."""
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
