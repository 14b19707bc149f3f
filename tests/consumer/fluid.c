// SPDX-License-Identifier: BSD-3-Clause
/* The smallest C fluid code: the DEM case given on the command line, advanced ten fluid
 * steps of 1e-4 s, with the buoyancy of a fluid of density 1000 kg/m^3 (the weight of the
 * fluid a particle displaces, upwards) set as each particle's force before every step.
 * Prints the solver's version, the time, the particles over all ranks and their mean
 * vertical velocity. Built with find_package(dem) (CMakeLists.txt). */
#include <math.h>
#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "dem_coupling.h"

enum { message_len = 512 };

/* Print a failed call's message on rank 0, release the run and return the status. */
static int stop(dem_coupling **run, int status, const char *message, int rank)
{
    char ignored[message_len];
    if (rank == 0) fprintf(stderr, "fluid: %s\n", message);
    if (*run) dem_coupling_finalize(run, ignored, message_len);
    MPI_Finalize();
    return status;
}

int main(int argc, char **argv)
{
    const double rho_fluid = 1000.0, g = 9.81, dt = 1e-4, pi = acos(-1.0);
    char message[message_len] = "";
    dem_coupling *run = NULL;
    int rank, status;
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (argc < 2) return stop(&run, 2, "usage: fluid CASE.nml", rank);
    status = dem_coupling_init(&run, argv[1], (int)MPI_Comm_c2f(MPI_COMM_WORLD), message,
                               message_len);
    if (status != 0) return stop(&run, status, message, rank);

    const int64_t *id;                     /* read-only views of the owned particles */
    const double *radius, *x, *v, *w;
    double *force = NULL, *torque = NULL;
    for (int step = 0; step < 10; step++) {
        /* the owned particles may change at every advance: read them, then set their forces */
        int n = dem_coupling_count(run);
        status = dem_coupling_views(run, &id, &radius, &x, &v, &w);
        force = realloc(force, (size_t)(3 * n + 3) * sizeof *force);
        torque = realloc(torque, (size_t)(3 * n + 3) * sizeof *torque);
        if (!force || !torque) return stop(&run, 3, "out of memory", rank);
        for (int i = 0; i < 3 * n; i++) force[i] = torque[i] = 0.0;
        for (int i = 0; i < n; i++)
            force[3 * i + 2] = rho_fluid * 4.0 / 3.0 * pi * pow(radius[i], 3) * g;
        if (status == 0) status = dem_coupling_set_force(run, force, torque);
        if (status == 0) status = dem_coupling_advance(run, dt, message, message_len);
        if (status != 0) {
            dem_coupling_status(run, message, message_len);
            return stop(&run, status, message, rank);
        }
    }
    free(force);
    free(torque);

    /* the particles after the last step, summed over the ranks */
    int n = dem_coupling_count(run);
    status = dem_coupling_views(run, &id, &radius, &x, &v, &w);
    if (status != 0) return stop(&run, status, "the views were refused", rank);
    double mine[2] = {(double)n, 0.0}, all[2];
    for (int i = 0; i < n; i++) mine[1] += v[3 * i + 2];
    MPI_Allreduce(mine, all, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    if (rank == 0)
        printf("fluid: dem %s, t = %.5e s, %d particles, mean vertical velocity %.12e m/s\n",
               dem_coupling_version(), dem_coupling_time(run), (int)all[0],
               all[0] > 0 ? all[1] / all[0] : 0.0);

    status = dem_coupling_finalize(&run, message, message_len);
    if (status != 0) return stop(&run, status, message, rank);
    MPI_Finalize();
    return 0;
}
