# SPDX-License-Identifier: BSD-3-Clause
"""Finding and loading libdem.so, the C prototypes of its calls, and MPI (doc/user/python.md).

The library is looked for, in this order, at: the path given to load_library(); the file
named by the environment variable DEM_LIBRARY; the build folders of the repository this
package sits in (build/, build-debug/, when it is used from python/ of a source tree); the
package's own copy (dem/libdem.so, which pip install ./python builds and puts there); lib/
of the Python prefix (cmake --install --prefix into a virtual environment); then wherever
the dynamic loader finds libdem.so (LD_LIBRARY_PATH, ldconfig: an install under
/usr/local)."""
import atexit
import ctypes
import ctypes.util
import os
import sys

import numpy as np

_lib = None            # the loaded library (one per process)
_lib_path = None
_live_runs = {}         # the open runs by serial: closed at exit, before MPI is finalised
_exit_registered = False

_double_p = ctypes.POINTER(ctypes.c_double)
_int_p = ctypes.POINTER(ctypes.c_int)
_int64_p = ctypes.POINTER(ctypes.c_int64)
_handle = ctypes.c_void_p
_char_p = ctypes.c_char_p

# name: (result type, argument types) of every call of src/api/dem_coupling.h
_PROTOTYPES = {
    "dem_coupling_version": (ctypes.c_char_p, []),
    "dem_coupling_mpi_world": (ctypes.c_int, []),
    "dem_coupling_mpi_finalize": (None, []),
    "dem_coupling_init": (ctypes.c_int, [ctypes.POINTER(_handle), _char_p, ctypes.c_int,
                                         _char_p, ctypes.c_int]),
    "dem_coupling_finalize": (ctypes.c_int, [ctypes.POINTER(_handle), _char_p,
                                             ctypes.c_int]),
    "dem_coupling_advance": (ctypes.c_int, [_handle, ctypes.c_double, _char_p,
                                            ctypes.c_int]),
    "dem_coupling_status": (ctypes.c_int, [_handle, _char_p, ctypes.c_int]),
    "dem_coupling_time": (ctypes.c_double, [_handle]),
    "dem_coupling_count": (ctypes.c_int, [_handle]),
    "dem_coupling_get": (ctypes.c_int, [_handle, _int64_p, _int_p, _double_p, _double_p,
                                        _double_p, _double_p]),
    "dem_coupling_body_count": (ctypes.c_int, [_handle]),
    "dem_coupling_bodies": (ctypes.c_int, [_handle, _int64_p] + [_double_p] * 5),
    "dem_coupling_views": (ctypes.c_int, [_handle] + [ctypes.POINTER(ctypes.c_void_p)] * 5),
    "dem_coupling_device_views": (ctypes.c_int,
                                  [_handle] + [ctypes.POINTER(ctypes.c_void_p)] * 3),
    "dem_coupling_set_force": (ctypes.c_int, [_handle, _double_p, _double_p]),
    "dem_coupling_set_drag": (ctypes.c_int, [_handle, _double_p, _double_p]),
    "dem_coupling_set_force_by_id": (ctypes.c_int, [_handle, ctypes.c_int, _int64_p,
                                                    _double_p, _double_p, _char_p,
                                                    ctypes.c_int]),
    "dem_coupling_set_drag_by_id": (ctypes.c_int, [_handle, ctypes.c_int, _int64_p,
                                                   _double_p, _double_p, _char_p,
                                                   ctypes.c_int]),
    "dem_coupling_impulse": (ctypes.c_int, [_handle, _double_p]),
    "dem_coupling_removed_count": (ctypes.c_int, [_handle]),
    "dem_coupling_removed": (ctypes.c_int, [_handle, _int64_p]),
    "dem_coupling_deposit": (ctypes.c_int, [_handle, _double_p, _double_p, _int_p,
                                            ctypes.c_int, _double_p, _double_p, _double_p,
                                            _double_p, _char_p, ctypes.c_int]),
    "dem_coupling_deposit_cells": (ctypes.c_int, [_handle, ctypes.c_int, _double_p,
                                                  _double_p, _double_p, _double_p,
                                                  _double_p, _double_p, _char_p,
                                                  ctypes.c_int]),
}


def _candidates():
    """The paths where libdem.so is looked for when none is given, in order."""
    found = []
    if os.environ.get("DEM_LIBRARY"):
        found.append(os.environ["DEM_LIBRARY"])
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(os.path.dirname(here))       # python/dem -> the repository
    if os.path.exists(os.path.join(root, "src", "api", "dem_coupling.h")):
        for build in ("build", "build-debug", "build-acc"):
            found.append(os.path.join(root, build, "libdem.so"))
    found.append(os.path.join(here, "libdem.so"))
    for lib in ("lib", "lib64"):
        found.append(os.path.join(sys.prefix, lib, "libdem.so"))
    name = ctypes.util.find_library("dem")
    if name:
        found.append(name)
    found.append("libdem.so")                              # LD_LIBRARY_PATH
    return found


def load_library(path=None):
    """Load libdem.so (from `path`, else the first that exists of the places above) and
    return it; later calls return the library already loaded (one per process: asking for
    another path then is an error)."""
    global _lib, _lib_path
    if _lib is not None:
        if path is not None and os.path.realpath(path) != os.path.realpath(_lib_path):
            raise RuntimeError(f"dem: {_lib_path} is loaded already; cannot load {path}")
        return _lib
    tried = [path] if path is not None else _candidates()
    errors = []
    for candidate in tried:
        if os.sep in candidate and not os.path.exists(candidate):
            errors.append(f"{candidate}: no such file")
            continue
        _load_mpi()
        try:
            lib = ctypes.CDLL(candidate)
        except OSError as e:
            errors.append(str(e))
            continue
        for name, (restype, argtypes) in _PROTOTYPES.items():
            f = getattr(lib, name)
            f.restype = restype
            f.argtypes = argtypes
        _lib, _lib_path = lib, candidate
        return lib
    raise OSError("dem: cannot load libdem.so (pip install ./python builds it into the "
                  "package; or build it with scripts/install/build and set DEM_LIBRARY to its "
                  "path, or install it with cmake --install); tried:\n  "
                  + "\n  ".join(errors))


def library_path():
    """The path of the loaded library (it is loaded if it is not yet)."""
    load_library()
    return _lib_path


def library_version():
    """The version of the solver the loaded library was built from."""
    return load_library().dem_coupling_version().decode()


def _load_mpi():
    """Make the MPI library's symbols global before libdem.so (and so MPI) is loaded, as
    mpi4py does: Open MPI's components, loaded at run time, look them up there."""
    if "mpi4py.MPI" in sys.modules:
        return
    name = ctypes.util.find_library("mpi")
    if name:
        try:
            ctypes.CDLL(name, mode=ctypes.RTLD_GLOBAL)
        except OSError:
            pass


def world_handle(lib):
    """The Fortran handle of MPI_COMM_WORLD: mpi4py's when the program has imported it,
    else libdem's own (which initialises MPI, and finalises it at exit)."""
    _register_exit()
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None:
        return mpi.COMM_WORLD.py2f()
    return lib.dem_coupling_mpi_world()


def comm_handle(lib, comm):
    """The Fortran handle of `comm`: None (MPI_COMM_WORLD), an mpi4py communicator, or an
    integer that already is a Fortran handle (MPI_Comm_c2f)."""
    if comm is None:
        return world_handle(lib)
    _register_exit()
    if hasattr(comm, "py2f"):
        return comm.py2f()
    return int(comm)


def track(run):
    """Remember an open run, to close it at exit before MPI is finalised (it is kept alive
    until then, or until it is closed)."""
    _live_runs[run._serial] = run


def untrack(run):
    """Forget a closed run."""
    _live_runs.pop(run._serial, None)


def _register_exit():
    """Register, once, the exit handler: it closes the runs still open, then finalises MPI
    if libdem initialised it."""
    global _exit_registered
    if not _exit_registered:
        atexit.register(_at_exit)
        _exit_registered = True


def _at_exit():
    """Close the runs still open (in the order they were made), then finalise MPI if libdem
    started it; nothing when mpi4py has finalised MPI already."""
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_finalized():
        return
    for serial in sorted(_live_runs):
        run = _live_runs[serial]
        try:
            run.close()
        except Exception as e:                             # report, go on closing
            print(f"dem: closing a run at exit: {e}", file=sys.stderr)
    if _lib is not None:
        _lib.dem_coupling_mpi_finalize()


def as_pointer(array, ctype=ctypes.c_double):
    """A ctypes pointer to the data of a contiguous NumPy array."""
    return array.ctypes.data_as(ctypes.POINTER(ctype))


def view(address, shape, dtype):
    """A read-only NumPy array over `shape` items at `address`, without a copy (an empty
    array for a null address or no items)."""
    if not address or int(np.prod(shape)) == 0:
        array = np.zeros(shape, dtype=dtype)
    else:
        ctype = np.ctypeslib.as_ctypes_type(np.dtype(dtype))
        array = np.ctypeslib.as_array(ctypes.cast(address, ctypes.POINTER(ctype)),
                                      shape=shape)
    array.flags.writeable = False
    return array
