# SPDX-License-Identifier: BSD-3-Clause
"""dem from Python: a ctypes layer over the C interface of the solver's shared library
libdem.so (src/api/dem_coupling.h; doc/user/python.md).

    import dem
    with dem.Run("case.nml") as run:          # MPI_COMM_WORLD, or comm=an mpi4py communicator
        run.set_drag(beta, fluid_velocity)    # per owned particle
        run.advance(1e-3)                     # sub-steps of the case's dt
        p = run.views()                       # NumPy arrays over the solver's memory
"""
from ._library import library_path, library_version, load_library
from .run import Bodies, Deposit, DemError, Particles, Run
from .sweep import set_values, sweep, write_case

__version__ = "0.1.0"   # the solver's (src/base/dem_version.f90)
__all__ = ["Run", "Particles", "Bodies", "Deposit", "DemError", "load_library", "library_path",
           "library_version",
           "sweep", "set_values", "write_case"]
