// SPDX-License-Identifier: BSD-3-Clause
/* The C interface of dem's CFD coupling (src/api/dem_coupling.f90, doc/user/coupling.md).
 *
 * A coupled run is an opaque handle, dem_coupling *, that dem_coupling_init sets up and
 * dem_coupling_finalize ends; every other call takes it first. A process can hold several
 * handles: their runs are independent (each its own case, particles, outputs and duplicate
 * communicator). A handle is a number, never an address, and is never read through: a NULL
 * handle, a finalised one (or a copy of it) and any value dem_coupling_init did not return
 * hold no run. On them every call that returns a status returns 3 ("not initialised"),
 * dem_coupling_time and the counts give 0, and the views NULL.
 *
 * Every call is collective on the communicator given to dem_coupling_init (a handle that
 * holds no run is answered on its own rank, without communication). Every call but the
 * time, the counts and the version returns a status: 0 on success, else
 *   2: refused arguments (nothing was done, nothing written, the run is as it was): a NULL
 *      pointer where data is needed, a length < 0, a value that is not finite or out of its
 *      range (each call says which); refused on any rank, refused on every rank;
 *   3: the run cannot go on: no run (above), or an advance failed (the guard found it
 *      unstable, a wall-time or signal stop): every later advance, setter and deposit
 *      returns 3 again with the failure's message, and dem_coupling_finalize returns it
 *      (no final.csv is written: the last good state is the checkpoint the message names);
 *   4: an output could not be written (the failure is kept as for 3).
 * The calls with a `message` argument write a null-terminated message there (at most
 * message_len bytes with the terminator; nothing when message is NULL or message_len < 1);
 * dem_coupling_status gives the message of a run that failed. dem_coupling_init keeps
 * that form and hands the new run back through its first argument, so that a failure still
 * says which kind it is. No call stops the process or reads outside what it is given.
 * SI units. Arrays are of the particles this rank owns, n = dem_coupling_count(run), in
 * local order: vectors are 3 doubles per particle (x0 y0 z0 x1 y1 z1 ...); they may be
 * NULL when n is 0. The local order may change at every advance: match particles by their
 * global ids. The calls are not thread-safe. */
#ifndef DEM_COUPLING_H
#define DEM_COUPLING_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A coupled run (a Fortran coupling_t). */
typedef struct dem_coupling dem_coupling;

/* Read the case file (a null-terminated path) and set up its run on a duplicate of the
 * communicator whose Fortran handle is comm_f (MPI_Comm_c2f(comm)); MPI must be initialised.
 * On success *run is the new run; on failure it is NULL. Status 2: run or file NULL, the
 * case refused, or comm_f no intracommunicator of this process (MPI_COMM_NULL, freed, an
 * intercommunicator, a number MPI_Comm_c2f did not give: found without an abort, MPI's
 * error handlers as they were). */
int dem_coupling_init(dem_coupling **run, const char *file, int comm_f, char *message,
                      int message_len);

/* The version of the solver (src/base/dem_version.f90), a null-terminated string the
 * library keeps (do not free it). */
const char *dem_coupling_version(void);

/* The Fortran handle of MPI_COMM_WORLD, initialising MPI if nobody has (for a caller with
 * no MPI of its own: the Python package without mpi4py); dem_coupling_mpi_finalize
 * finalises MPI if dem_coupling_mpi_world initialised it, and does nothing otherwise. */
int dem_coupling_mpi_world(void);
void dem_coupling_mpi_finalize(void);

/* Write the run's final outputs, release it and end the handle: *run becomes NULL (also
 * when the outputs fail, status 4, and for a failed run, which writes no final outputs and
 * returns its failure, 3 or 4). Status 2: run is NULL (not the handle: its address). */
int dem_coupling_finalize(dem_coupling **run, char *message, int message_len);

/* Advance from t to t + dt in ceiling(dt / case dt) equal sub-steps, ending exactly at
 * t + dt; forces, torques and drag act on every sub-step. Status 2 (nothing changes, the
 * time included): dt not finite and > 0, more than 2^52 sub-steps, or t + dt after the
 * case's t_end. */
int dem_coupling_advance(dem_coupling *run, double dt, char *message, int message_len);

/* 0 while the run can go on; else 3 and the message of its failure (or of no run). */
int dem_coupling_status(const dem_coupling *run, char *message, int message_len);

double dem_coupling_time(const dem_coupling *run);   /* the DEM's time [s] */
int dem_coupling_count(const dem_coupling *run);     /* particles owned by this rank */

/* Copies of the owned particles: global ids, material indices (the case's &material
 * groups in order, from 1), radii [m], positions [m], velocities [m/s], angular
 * velocities [rad/s] (also after a failure: the state it stopped in). Status 2: an array
 * NULL. */
int dem_coupling_get(const dem_coupling *run, int64_t *gid, int *material, double *radius,
                     double *x, double *v, double *w);

/* The clumps (rigid bodies of member spheres, doc/user/input.md) this rank owns: a body is
 * owned where its members are (all on the rank of its centre of mass); the particles above
 * are its members, each with its own id. 0 in a case without clumps. */
int dem_coupling_body_count(const dem_coupling *run);

/* Copies of the owned bodies, nb = dem_coupling_body_count(run), in increasing order of their
 * ids (a body's id is that of its first member): ids, masses [kg], centres of mass [m], their
 * velocities [m/s], orientations (4 doubles per body: the unit quaternion q0 q1 q2 q3 that
 * turns the body's principal frame into the lab's) and angular velocities (lab frame)
 * [rad/s] (also after a failure: the state it stopped in). A member's velocity is
 * v + w x (x_member - x). The arrays may be NULL when nb is 0. Status 2: an array NULL. */
int dem_coupling_bodies(const dem_coupling *run, int64_t *id, double *mass, double *x,
                        double *v, double *q, double *w);

/* Read-only views (no copy) of the owned particles' ids, radii, positions, velocities and
 * angular velocities: the first dem_coupling_count(run) entries (vectors: 3 doubles each),
 * valid until the run's next advance or its finalize (NULL, status 3, for no run). Do not
 * write through them. Status 2: an output address NULL. */
int dem_coupling_views(const dem_coupling *run, const int64_t **gid, const double **radius,
                       const double **x, const double **v, const double **w);

/* The device addresses of the positions, velocities and angular velocities in an OpenACC
 * build that runs on a GPU (for the fluid code's own OpenACC or CUDA kernels: the state on
 * the device at the end of the last advance); the host views otherwise. Valid as long as
 * the views. */
int dem_coupling_device_views(const dem_coupling *run, const double **x, const double **v,
                              const double **w);

/* External force [N] and torque [N m] per owned particle, until set again. Status 2
 * (nothing set): an array NULL, a value not finite. */
int dem_coupling_set_force(dem_coupling *run, const double *force, const double *torque);

/* Drag coefficient beta [kg/s] and fluid velocity [m/s] per owned particle: the drag
 * beta (u_f - v) is evaluated at every sub-step. Status 2 (nothing set): an array NULL, a
 * value not finite, a beta < 0. */
int dem_coupling_set_drag(dem_coupling *run, const double *beta, const double *fluid_velocity);

/* The same for n particles given by global id, on any rank (each id once over all ranks):
 * the values go to the owners. Ids that are no particle of the run, or come twice, fail;
 * so do n < 0, an array NULL with n > 0, and the values refused above (nothing set). */
int dem_coupling_set_force_by_id(dem_coupling *run, int n, const int64_t *ids,
                                 const double *force, const double *torque, char *message,
                                 int message_len);
int dem_coupling_set_drag_by_id(dem_coupling *run, int n, const int64_t *ids,
                                const double *beta, const double *fluid_velocity,
                                char *message, int message_len);

/* The impulse [N s] force and drag gave each owned particle over the last advance. */
int dem_coupling_impulse(const dem_coupling *run, double *impulse);

/* The particles the outlets removed from this rank during the last advance: how many, and
 * their global ids (over all ranks, each removed particle once). */
int dem_coupling_removed_count(const dem_coupling *run);
int dem_coupling_removed(const dem_coupling *run, int64_t *ids);

/* Deposit the particles of all ranks onto the Cartesian grid of n[0] x n[1] x n[2] cells of
 * size h from origin (cell c = i + n[0] (j + n[1] k), x fastest), with kernel 1 (cell),
 * 2 (trilinear) or 3 (divided particle volume): the solids volume fraction eps, and per
 * cell the sums of the particle momentum [kg m/s], of beta [kg/s] and of beta v [N]. Every
 * rank gets the whole grid, the same bit for bit on any number of ranks. Status 2 (nothing
 * written): a pointer NULL, an unknown kernel, origin or h not finite, h <= 0 or below 2/7
 * of the largest particle diameter on an axis, a cell volume below the smallest normal
 * double, n[k] < 1 or more than 2^30 cells, or |origin| + n h > 2^40 h on an axis. */
int dem_coupling_deposit(const dem_coupling *run, const double origin[3], const double h[3],
                         const int n[3], int kernel, double *eps, double *momentum,
                         double *beta_sum, double *beta_v, char *message, int message_len);

/* The same onto a list of n_cells cells given by their centres (3 doubles each) and volumes
 * (an unstructured mesh): each particle goes whole to the cell of the nearest centre.
 * Status 2 (nothing written): n_cells < 1, a pointer NULL, a centre not finite, centres
 * spread beyond the largest double, a volume not finite or below
 * max(smallest normal double, (2/7 of the largest particle diameter)^3). */
int dem_coupling_deposit_cells(const dem_coupling *run, int n_cells, const double *centres,
                               const double *volumes, double *eps, double *momentum,
                               double *beta_sum, double *beta_v, char *message,
                               int message_len);

#ifdef __cplusplus
}
#endif
#endif
