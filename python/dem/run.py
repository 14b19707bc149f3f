# SPDX-License-Identifier: BSD-3-Clause
"""A coupled run held by a handle of the C interface (src/api/dem_coupling.h): one case,
advanced from Python, its particles read as NumPy arrays, forces and drag set per particle,
deposits onto a grid (doc/user/python.md)."""
import ctypes
import itertools
from collections import namedtuple

import numpy as np

from . import _library

_MESSAGE_LEN = 1024
_KERNELS = {"cell": 1, "trilinear": 2, "dpvm": 3}
_MAX_CELLS = 2**30          # the most cells of a deposit grid (doc/user/coupling.md)
_serials = itertools.count()

#: The owned particles: ids (int64, n), material indices (int32, n, from 1 in the order of
#: the case's &material groups; None in views), radii (n), positions, velocities and angular
#: velocities (n x 3), SI units, in the local order of the last advance.
Particles = namedtuple("Particles", "gid material radius x v w")

#: The owned clumps (rigid bodies of member spheres): ids (int64, nb; a body's id is its first
#: member's), masses (nb), centres of mass, their velocities (nb x 3), orientations (nb x 4,
#: the unit quaternions q0..q3 from the body's principal frame to the lab's) and angular
#: velocities (nb x 3, lab frame), SI units, in increasing order of the ids.
Bodies = namedtuple("Bodies", "id mass x v q w")

#: A deposit onto cells: the solids volume fraction eps, and per cell the sums of the
#: particles' momentum [kg m/s], drag coefficients beta [kg/s] and beta v [N]. On a grid,
#: eps[i, j, k] and momentum[i, j, k, :] (views of the C layout, x fastest); on a list of
#: cells, eps[c] and momentum[c, :].
Deposit = namedtuple("Deposit", "eps momentum beta_sum beta_v")


class DemError(RuntimeError):
    """A call of the C interface that failed: status 2 (bad input or arguments: nothing was
    changed), 3 (the run cannot go on: it failed, or it is closed) or 4 (an output could
    not be written), with the solver's message. Once a run has failed, every later call
    that would go on with it raises status 3 with the failure's message, and so does
    close()."""

    def __init__(self, status, message):
        super().__init__(f"{message} (status {status})")
        self.status = status
        self.message = message


def _check(status, buffer):
    """Raise DemError for a non-zero status of a call, with its message."""
    if status != 0:
        raise DemError(status, buffer.value.decode(errors="replace"))


def _vectors(values, n, name):
    """`values` as a C-contiguous float64 array of n x 3 (a single 3-vector is repeated)."""
    a = np.asarray(values, dtype=np.float64)
    if a.shape == (3,):
        a = np.broadcast_to(a, (n, 3))
    if a.shape != (n, 3):
        raise ValueError(f"{name}: shape {a.shape}, expected ({n}, 3) or (3,)")
    return np.ascontiguousarray(a)


def _scalars(values, n, name):
    """`values` as a C-contiguous float64 array of n (a single number is repeated)."""
    a = np.asarray(values, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"{name}: shape {a.shape}, expected ({n},) or a number")
    return np.ascontiguousarray(a)


class Run:
    """One case set up as a coupled run on an MPI communicator (collective on it): every
    method is collective, as the C calls are. Use it in a `with` block, or call close(),
    which writes the final outputs (final.csv) and releases the run (a run still open at
    the interpreter's exit is closed then, before MPI is finalised).

    case: the case file (a namelist, doc/user/input.md). comm: None for MPI_COMM_WORLD, an
    mpi4py communicator, or a Fortran communicator handle. library: the path of libdem.so
    (else found as doc/user/python.md says)."""

    def __init__(self, case, comm=None, library=None):
        self._lib = _library.load_library(library)
        self._handle = ctypes.c_void_p()
        self._serial = next(_serials)
        self.case = str(case)
        message = ctypes.create_string_buffer(_MESSAGE_LEN)
        comm_f = _library.comm_handle(self._lib, comm)
        status = self._lib.dem_coupling_init(ctypes.byref(self._handle), self.case.encode(),
                                             comm_f, message, _MESSAGE_LEN)
        _check(status, message)
        _library.track(self)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    @property
    def closed(self):
        """True once the run is closed (or it never opened)."""
        return not self._handle.value

    def close(self):
        """Write the final outputs and release the run (collective); closing twice does
        nothing."""
        if self.closed:
            return
        message = ctypes.create_string_buffer(_MESSAGE_LEN)
        status = self._lib.dem_coupling_finalize(ctypes.byref(self._handle), message,
                                                 _MESSAGE_LEN)
        _library.untrack(self)                 # (the handle is freed, also on a failure)
        _check(status, message)

    def _live(self):
        """The handle; an error if the run is closed."""
        if self.closed:
            raise DemError(3, "dem: the run is closed")
        return self._handle

    def _check_plain(self, status, refused):
        """Raise DemError for a non-zero status of a call without a message: status 2 with
        `refused` (what its arguments must be), status 3 with the run's failure."""
        if status == 2:
            raise DemError(2, refused)
        if status != 0:
            message = ctypes.create_string_buffer(_MESSAGE_LEN)
            self._lib.dem_coupling_status(self._handle, message, _MESSAGE_LEN)
            _check(status, message)

    @property
    def time(self):
        """The DEM's time [s]."""
        return self._lib.dem_coupling_time(self._handle)

    @property
    def count(self):
        """The particles this rank owns."""
        return self._lib.dem_coupling_count(self._handle)

    def __len__(self):
        return self.count

    def advance(self, dt):
        """Advance from t to t + dt [s] in ceiling(dt / case dt) equal sub-steps, ending
        exactly at t + dt; the forces, torques and drag set act on every sub-step. The
        particles' local order may change: match them by id."""
        message = ctypes.create_string_buffer(_MESSAGE_LEN)
        _check(self._lib.dem_coupling_advance(self._live(), float(dt), message,
                                              _MESSAGE_LEN), message)

    def particles(self):
        """Copies of the owned particles (Particles, with the material indices)."""
        n = self.count
        gid = np.empty(n, np.int64)
        material = np.empty(n, np.int32)
        radius = np.empty(n)
        x, v, w = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
        if n > 0:
            P = _library.as_pointer
            self._check_plain(self._lib.dem_coupling_get(
                self._live(), P(gid, ctypes.c_int64), P(material, ctypes.c_int), P(radius),
                P(x), P(v), P(w)), "dem_coupling_get: an array is NULL")
        return Particles(gid, material, radius, x, v, w)

    @property
    def body_count(self):
        """The clumps (rigid bodies) this rank owns: those whose members it owns (0 in a case
        without clumps)."""
        return self._lib.dem_coupling_body_count(self._handle)

    def bodies(self):
        """Copies of the owned clumps (Bodies); their members are among particles()."""
        n = self.body_count
        ids = np.empty(n, np.int64)
        mass = np.empty(n)
        x, v, q, w = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 3))
        if n > 0:
            P = _library.as_pointer
            self._check_plain(self._lib.dem_coupling_bodies(
                self._live(), P(ids, ctypes.c_int64), P(mass), P(x), P(v), P(q), P(w)),
                "dem_coupling_bodies: an array is NULL")
        return Bodies(ids, mass, x, v, q, w)

    def views(self):
        """The owned particles' ids, radii, positions, velocities and angular velocities as
        read-only arrays over the solver's own memory, without a copy (material is None: the
        C interface has no view of it). They are valid only until the next advance() or
        close(): copy what must outlive them (np.array(view))."""
        n = self.count
        addresses = [ctypes.c_void_p() for _ in range(5)]
        self._check_plain(self._lib.dem_coupling_views(self._live(),
                                                       *(ctypes.byref(a) for a in addresses)),
                          "dem_coupling_views: an address is NULL")
        gid, radius, x, v, w = (a.value for a in addresses)
        V = _library.view
        return Particles(V(gid, (n,), np.int64), None, V(radius, (n,), np.float64),
                         V(x, (n, 3), np.float64), V(v, (n, 3), np.float64),
                         V(w, (n, 3), np.float64))

    def device_views(self):
        """The device addresses (integers) of the positions, velocities and angular
        velocities in an OpenACC build on a GPU, for the caller's own device code (e.g.
        CuPy's UnownedMemory); the host addresses otherwise."""
        addresses = [ctypes.c_void_p() for _ in range(3)]
        self._check_plain(self._lib.dem_coupling_device_views(
            self._live(), *(ctypes.byref(a) for a in addresses)),
            "dem_coupling_device_views: an address is NULL")
        return tuple(a.value for a in addresses)

    def set_force(self, force, torque=None):
        """External force [N] and torque [N m] per owned particle (n x 3, or one 3-vector for
        all; torque None: zero), kept until set again. Values that are not finite raise
        DemError (status 2) and nothing is set."""
        n = self.count
        f = _vectors(force, n, "force")
        t = _vectors(np.zeros(3) if torque is None else torque, n, "torque")
        self._check_plain(self._lib.dem_coupling_set_force(
            self._live(), _library.as_pointer(f), _library.as_pointer(t)),
            "dem_coupling_set_force: a force or torque is not finite")

    def set_drag(self, beta, fluid_velocity):
        """Drag coefficient beta [kg/s] (n, or one number) and fluid velocity [m/s] (n x 3,
        or one 3-vector) per owned particle: the drag beta (u_f - v) acts at every sub-step.
        Values that are not finite, or a beta < 0, raise DemError (status 2) and nothing is
        set."""
        n = self.count
        b = _scalars(beta, n, "beta")
        u = _vectors(fluid_velocity, n, "fluid_velocity")
        self._check_plain(self._lib.dem_coupling_set_drag(
            self._live(), _library.as_pointer(b), _library.as_pointer(u)),
            "dem_coupling_set_drag: a beta or fluid velocity is not finite, or a beta < 0")

    def set_force_by_id(self, ids, force, torque=None):
        """Force and torque for particles given by global id, on any rank (each id once over
        all ranks); the values go to the owners (collective)."""
        i = np.ascontiguousarray(ids, dtype=np.int64).reshape(-1)
        f = _vectors(force, i.size, "force")
        t = _vectors(np.zeros(3) if torque is None else torque, i.size, "torque")
        message = ctypes.create_string_buffer(_MESSAGE_LEN)
        P = _library.as_pointer
        _check(self._lib.dem_coupling_set_force_by_id(self._live(), i.size,
                                                      P(i, ctypes.c_int64), P(f), P(t),
                                                      message, _MESSAGE_LEN), message)

    def set_drag_by_id(self, ids, beta, fluid_velocity):
        """Drag coefficient and fluid velocity for particles given by global id, on any rank
        (collective)."""
        i = np.ascontiguousarray(ids, dtype=np.int64).reshape(-1)
        b = _scalars(beta, i.size, "beta")
        u = _vectors(fluid_velocity, i.size, "fluid_velocity")
        message = ctypes.create_string_buffer(_MESSAGE_LEN)
        P = _library.as_pointer
        _check(self._lib.dem_coupling_set_drag_by_id(self._live(), i.size,
                                                     P(i, ctypes.c_int64), P(b), P(u),
                                                     message, _MESSAGE_LEN), message)

    def impulse(self):
        """The impulse [N s] force and drag gave each owned particle over the last advance
        (n x 3, a copy, in the order of particles())."""
        n = self.count
        j = np.zeros((n, 3))
        if n > 0:
            self._check_plain(self._lib.dem_coupling_impulse(self._live(),
                                                             _library.as_pointer(j)),
                              "dem_coupling_impulse: the array is NULL")
        return j

    def removed(self):
        """The global ids of the particles the outlets removed from this rank during the
        last advance."""
        n = self._lib.dem_coupling_removed_count(self._handle)
        ids = np.zeros(n, np.int64)
        if n > 0:
            self._check_plain(self._lib.dem_coupling_removed(
                self._live(), _library.as_pointer(ids, ctypes.c_int64)),
                "dem_coupling_removed: the array is NULL")
        return ids

    def deposit(self, origin, h, n, kernel="cell"):
        """Deposit the particles of all ranks onto the grid of n = (nx, ny, nz) cells of size
        h from origin, with kernel 'cell', 'trilinear' or 'dpvm' (divided particle volume);
        every rank gets the whole grid (collective). Returns a Deposit of arrays indexed
        [i, j, k] (vectors [i, j, k, component]). A grid the library refuses (a non-finite
        origin or h, cells smaller than 2/7 of the largest particle diameter, more than 2^30
        cells: doc/user/coupling.md) raises DemError with status 2."""
        o = np.ascontiguousarray(origin, dtype=np.float64).reshape(3)
        hh = np.ascontiguousarray(h, dtype=np.float64).reshape(3)
        n64 = np.asarray(n, dtype=np.float64).reshape(3)         # (held to int32's range)
        nn = np.ascontiguousarray(np.clip(np.nan_to_num(n64, nan=0.0), -2**31, 2**31 - 1),
                                  dtype=np.int32)
        if kernel not in _KERNELS:
            raise ValueError(f"kernel {kernel!r}: one of {', '.join(_KERNELS)}")
        cells = int(np.prod(nn.astype(np.int64)))
        if not (np.all(nn >= 1) and cells <= _MAX_CELLS):
            cells = 0                                    # refused by the library, unwritten
        eps, beta_sum = np.zeros(cells), np.zeros(cells)
        momentum, beta_v = np.zeros(3 * cells), np.zeros(3 * cells)
        message = ctypes.create_string_buffer(_MESSAGE_LEN)
        P = _library.as_pointer
        _check(self._lib.dem_coupling_deposit(self._live(), P(o), P(hh), P(nn, ctypes.c_int),
                                              _KERNELS[kernel], P(eps), P(momentum),
                                              P(beta_sum), P(beta_v), message, _MESSAGE_LEN),
               message)
        shape = tuple(int(k) for k in nn)

        def grid(a):
            return a.reshape(shape, order="F")

        def grid3(a):
            return a.reshape((3,) + shape, order="F").transpose(1, 2, 3, 0)
        return Deposit(grid(eps), grid3(momentum), grid(beta_sum), grid3(beta_v))

    def deposit_cells(self, centres, volumes):
        """Deposit the particles of all ranks onto a list of cells given by their centres
        [m] (m x 3) and volumes [m^3] (m): each particle goes whole to the cell of the
        nearest centre (collective). Returns a Deposit of arrays indexed [c]
        (vectors [c, component])."""
        c = np.ascontiguousarray(centres, dtype=np.float64).reshape(-1, 3)
        vol = np.ascontiguousarray(volumes, dtype=np.float64).reshape(-1)
        m = c.shape[0]
        if vol.size != m:
            raise ValueError(f"volumes: {vol.size} values for {m} centres")
        eps, beta_sum = np.zeros(m), np.zeros(m)
        momentum, beta_v = np.zeros((m, 3)), np.zeros((m, 3))
        message = ctypes.create_string_buffer(_MESSAGE_LEN)
        P = _library.as_pointer
        _check(self._lib.dem_coupling_deposit_cells(self._live(), m, P(c), P(vol), P(eps),
                                                    P(momentum), P(beta_sum), P(beta_v),
                                                    message, _MESSAGE_LEN), message)
        return Deposit(eps, momentum, beta_sum, beta_v)
