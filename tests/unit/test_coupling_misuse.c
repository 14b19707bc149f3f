// SPDX-License-Identifier: BSD-3-Clause
/* dem_coupling from C, misused: every call answers with a status and leaves the process,
 * and the run, as they were (src/api/dem_coupling.h). On 1 and 2 ranks:
 * - NULL pointers (the handle's address, the case file, a message with a length, the data
 *   arrays, the views' addresses) give status 2, and NULL as the handle gives 3;
 * - a finalised handle, and a copy of it kept by the caller, hold no run (status 3, count
 *   0, body count 0, time 0, NULL views), as does a made-up handle; finalize(NULL) is status 2;
 * - communicators that are none (MPI_COMM_NULL, a freed one, a made-up number) give status
 *   2 and leave MPI_COMM_WORLD's error handler as it was (errors fatal);
 * - non-finite reals (dt, forces, drag, deposit origin and spacing, cell centres) give 2,
 *   and the run's time and particles are unchanged; on 2 ranks a NaN dt on one rank only
 *   is refused on both (no rank waits for the other in the advance);
 * - a run whose advance failed (two spheres meeting head-on with dt above the stability
 *   bound: the guard stops it, status 3) refuses every later advance, setter and deposit
 *   with status 3 and the same message, dem_coupling_status gives that message, and
 *   finalize returns it and writes no final.csv.
 * A regression that crashes or hangs fails the test (CTest: a signal or its time limit). */
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "dem_coupling.h"

static int failures = 0;

static void check(int ok, const char *what, const char *detail)
{
    if (!ok) {
        failures++;
        fprintf(stderr, "FAILED: %s %s\n", what, detail ? detail : "");
    }
}

/* The case `file` (written by rank 0): one glass sphere of radius 1 mm at rest at the
 * origin, or (head_on) two spheres of 10 mm meeting at +-100 m/s with dt = 1.5e-5 s, 1.16
 * Rayleigh times (allowed with allow_unstable); outputs into folder `out`. */
static void write_case(const char *file, const char *out, int head_on, int rank)
{
    if (rank == 0) {
        FILE *f = fopen(file, "w");
        if (head_on) {
            fprintf(f, "&run dt = 1.5e-5, t_end = 4e-4, gravity = 0, 0, 0, "
                       "expected_speed = 100, allow_unstable = .true. /\n");
            fprintf(f, "&output dir = '%s', interval = 1e-5, overwrite = .true. /\n", out);
            fprintf(f, "&material name = 'glass', density = 2800.0, youngs_modulus = 48.0e9, "
                       "poisson_ratio = 0.2 /\n");
            fprintf(f, "&pair materials = 'glass', 'glass', restitution = 1.0, "
                       "friction = 0.35 /\n");
            fprintf(f, "&particle id = 1, material = 'glass', radius = 0.01, "
                       "position = -0.0105, 0, 0, velocity = 100, 0, 0 /\n");
            fprintf(f, "&particle id = 2, material = 'glass', radius = 0.01, "
                       "position = 0.0105, 0, 0, velocity = -100, 0, 0 /\n");
        } else {
            fprintf(f, "&run dt = 1e-5, t_end = 1.0, gravity = 0, 0, -9.81 /\n");
            fprintf(f, "&output dir = '%s', interval = 1e-3, overwrite = .true. /\n", out);
            fprintf(f, "&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, "
                       "poisson_ratio = 0.25 /\n");
            fprintf(f, "&pair materials = 'glass', 'glass', restitution = 0.5, "
                       "friction = 0.3 /\n");
            fprintf(f, "&particle id = 1, material = 'glass', radius = 1e-3, "
                       "position = 0, 0, 0 /\n");
        }
        fclose(f);
    }
    MPI_Barrier(MPI_COMM_WORLD);
}

/* The sphere's z position summed over the ranks (one of them owns it). */
static double sphere_z(dem_coupling *run)
{
    double mine = 0.0, all;
    if (dem_coupling_count(run) == 1) {
        int64_t gid[1];
        int mat[1];
        double r[1], x[3], v[3], w[3];
        check(dem_coupling_get(run, gid, mat, r, x, v, w) == 0, "get", NULL);
        mine = x[2];
    }
    MPI_Allreduce(&mine, &all, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    return all;
}

/* Bad communicators: status 2 and no handle, MPI_COMM_WORLD's error handler unchanged. */
static void bad_communicators(const char *file)
{
    char msg[512];
    dem_coupling *run = (dem_coupling *)&msg;   /* must come back NULL */
    MPI_Comm freed;
    MPI_Comm_dup(MPI_COMM_WORLD, &freed);
    int freed_f = MPI_Comm_c2f(freed);
    MPI_Comm_free(&freed);
    const int handles[3] = {MPI_Comm_c2f(MPI_COMM_NULL), freed_f, 987654};
    for (int k = 0; k < 3; k++) {
        int st = dem_coupling_init(&run, file, handles[k], msg, (int)sizeof msg);
        check(st == 2 && run == NULL && strstr(msg, "communicator") != NULL,
              "a bad communicator: status 2, no handle:", msg);
    }
    MPI_Errhandler handler;
    MPI_Comm_get_errhandler(MPI_COMM_WORLD, &handler);
    check(handler == MPI_ERRORS_ARE_FATAL, "MPI_COMM_WORLD's error handler as it was", NULL);
    MPI_Errhandler_free(&handler);
}

/* NULL pointers and handles that hold no run. */
static void null_pointers(const char *file, int fc, int rank)
{
    char msg[512];
    int st;
    dem_coupling *run = NULL, *copy;
    st = dem_coupling_init(NULL, file, fc, msg, (int)sizeof msg);
    check(st == 2 && strstr(msg, "NULL") != NULL, "init with run NULL:", msg);
    st = dem_coupling_init(&run, NULL, fc, msg, (int)sizeof msg);
    check(st == 2 && run == NULL, "init with file NULL:", msg);
    st = dem_coupling_init(&run, "missing_case.nml", fc, NULL, 512);
    check(st == 2 && run == NULL, "init with message NULL and a length", NULL);
    st = dem_coupling_finalize(NULL, msg, (int)sizeof msg);
    check(st == 2, "finalize(NULL):", msg);

    st = dem_coupling_init(&run, file, fc, NULL, 512);
    check(st == 0 && run != NULL, "init with message NULL", NULL);
    int n = dem_coupling_count(run);
    double t0 = dem_coupling_time(run);
    st = dem_coupling_advance(run, 1e-4, NULL, 100);
    check(st == 0, "advance with message NULL", NULL);
    check(dem_coupling_get(run, NULL, NULL, NULL, NULL, NULL, NULL) == (n > 0 ? 2 : 0),
          "get into NULL arrays", NULL);
    check(dem_coupling_set_force(run, NULL, NULL) == (n > 0 ? 2 : 0), "set_force NULL", NULL);
    check(dem_coupling_set_drag(run, NULL, NULL) == (n > 0 ? 2 : 0), "set_drag NULL", NULL);
    check(dem_coupling_impulse(run, NULL) == (n > 0 ? 2 : 0), "impulse into NULL", NULL);
    check(dem_coupling_body_count(run) == 0 &&
          dem_coupling_bodies(run, NULL, NULL, NULL, NULL, NULL, NULL) == 0,
          "no clumps: no bodies, NULL arrays taken", NULL);
    check(dem_coupling_views(run, NULL, NULL, NULL, NULL, NULL) == 2, "views into NULL",
          NULL);
    check(dem_coupling_device_views(run, NULL, NULL, NULL) == 2, "device views into NULL",
          NULL);
    /* a NULL array on one rank only (rank 0's ids): refused on every rank */
    int64_t ids[1] = {1};
    double force[3] = {0.0, 0.0, 1.0}, torque[3] = {0.0, 0.0, 0.0};
    st = dem_coupling_set_force_by_id(run, rank == 0 ? 1 : 0, rank == 0 ? NULL : ids, force,
                                      torque, msg, (int)sizeof msg);
    check(st == 2, "set_force_by_id with ids NULL:", msg);
    st = dem_coupling_set_force_by_id(run, -1, ids, force, torque, msg, (int)sizeof msg);
    check(st == 2, "set_force_by_id with n < 0:", msg);
    double eps[8], mom[24], bsum[8], bv[24];
    const double origin[3] = {-1e-3, -1e-3, -1e-3}, h[3] = {1e-3, 1e-3, 1e-3};
    const int cells[3] = {2, 2, 2};
    st = dem_coupling_deposit(run, NULL, h, cells, 1, eps, mom, bsum, bv, msg, (int)sizeof msg);
    check(st == 2, "deposit with origin NULL:", msg);
    st = dem_coupling_deposit(run, origin, h, cells, 1, NULL, mom, bsum, bv, msg,
                              (int)sizeof msg);
    check(st == 2, "deposit into eps NULL:", msg);
    st = dem_coupling_deposit_cells(run, 1, NULL, NULL, eps, mom, bsum, bv, msg,
                                    (int)sizeof msg);
    check(st == 2, "deposit_cells with centres NULL:", msg);
    check(dem_coupling_time(run) > t0, "the run went on", NULL);

    /* the handle finalised, a copy kept: it holds no run */
    copy = run;
    st = dem_coupling_finalize(&run, msg, (int)sizeof msg);
    check(st == 0 && run == NULL, "finalize:", msg);
    st = dem_coupling_advance(copy, 1e-4, msg, (int)sizeof msg);
    check(st == 3, "advance on a finalised handle's copy:", msg);
    st = dem_coupling_finalize(&copy, msg, (int)sizeof msg);
    check(st == 3, "finalize of a finalised handle's copy:", msg);
    check(dem_coupling_count(copy) == 0 && dem_coupling_time(copy) == 0.0,
          "a finalised handle: count 0, time 0", NULL);
    const int64_t *gv = (const int64_t *)msg;
    const double *rv = h, *xv = h, *vv = h, *wv = h;
    st = dem_coupling_views(copy, &gv, &rv, &xv, &vv, &wv);
    check(st == 3 && gv == NULL && xv == NULL, "a finalised handle: NULL views", NULL);
    check(dem_coupling_get(copy, NULL, NULL, NULL, NULL, NULL, NULL) == 3,
          "get on a finalised handle", NULL);
    check(dem_coupling_body_count(copy) == 0 &&
          dem_coupling_bodies(copy, NULL, NULL, NULL, NULL, NULL, NULL) == 3,
          "bodies of a finalised handle: count 0, status 3", NULL);
    check(dem_coupling_set_force(copy, force, torque) == 3, "set_force on it", NULL);
    dem_coupling *made_up = (dem_coupling *)(&msg[1]);
    st = dem_coupling_advance(made_up, 1e-4, msg, (int)sizeof msg);
    check(st == 3, "advance on a made-up handle:", msg);
    check(dem_coupling_status(NULL, msg, (int)sizeof msg) == 3, "status of NULL:", msg);
}

/* Non-finite reals: status 2, nothing changed; a NaN dt on one rank only is refused on
 * all. */
static void non_finite(const char *file, int fc, int rank, int size)
{
    char msg[512];
    int st;
    dem_coupling *run;
    st = dem_coupling_init(&run, file, fc, msg, (int)sizeof msg);
    check(st == 0, "init:", msg);
    st = dem_coupling_advance(run, 1e-4, msg, (int)sizeof msg);
    double t = dem_coupling_time(run), z = sphere_z(run);
    const double bad[4] = {NAN, INFINITY, -INFINITY, 1e300};
    for (int k = 0; k < 4; k++) {
        st = dem_coupling_advance(run, bad[k], msg, (int)sizeof msg);
        check(st == 2 && strstr(msg, "dt") != NULL, "advance by a non-finite dt:", msg);
        check(dem_coupling_time(run) == t, "the time is as it was", NULL);
    }
    if (size > 1) {
        st = dem_coupling_advance(run, rank == 1 ? NAN : 1e-4, msg, (int)sizeof msg);
        check(st == 2, "a NaN dt on rank 1 only: refused on every rank:", msg);
        check(dem_coupling_time(run) == t, "the time is as it was", NULL);
    }
    int n = dem_coupling_count(run);
    double f[3] = {0.0, NAN, 0.0}, zero[3] = {0.0, 0.0, 0.0}, beta[1] = {INFINITY};
    if (n == 1) {
        check(dem_coupling_set_force(run, f, zero) == 2, "a NaN force", NULL);
        check(dem_coupling_set_force(run, zero, f) == 2, "a NaN torque", NULL);
        check(dem_coupling_set_drag(run, beta, zero) == 2, "an infinite beta", NULL);
        beta[0] = -1.0;
        check(dem_coupling_set_drag(run, beta, zero) == 2, "a negative beta", NULL);
    }
    int64_t ids[1] = {1};
    st = dem_coupling_set_force_by_id(run, rank == 0 ? 1 : 0, ids, f, zero, msg,
                                      (int)sizeof msg);
    check(st == 2, "set_force_by_id with a NaN force:", msg);
    double eps[64], mom[192], bsum[64], bv[192];
    const int cells[3] = {4, 4, 4};
    const double good_o[3] = {-2e-3, -2e-3, -2e-3}, good_h[3] = {1e-3, 1e-3, 1e-3};
    const double origins[3][3] = {{NAN, 0, 0}, {0, 0, INFINITY}, {1e300, 1e300, 1e300}};
    const double spacings[3][3] = {{1e-300, 1e-300, 1e-300}, {1e-3, NAN, 1e-3},
                                   {1e-3, 1e-3, 2e-4}};
    for (int k = 0; k < 3; k++) {
        for (int kernel = 1; kernel <= 3; kernel++) {
            st = dem_coupling_deposit(run, origins[k], good_h, cells, kernel, eps, mom, bsum,
                                      bv, msg, (int)sizeof msg);
            check(st == 2 && strstr(msg, "origin") != NULL, "deposit, bad origin:", msg);
            st = dem_coupling_deposit(run, good_o, spacings[k], cells, kernel, eps, mom, bsum,
                                      bv, msg, (int)sizeof msg);
            check(st == 2 && strstr(msg, "h =") != NULL, "deposit, bad h:", msg);
        }
    }
    const int too_many[3] = {2048, 1024, 1024};
    st = dem_coupling_deposit(run, good_o, good_h, too_many, 1, eps, mom, bsum, bv, msg,
                              (int)sizeof msg);
    check(st == 2, "deposit onto 2^31 cells:", msg);
    const double centres[6] = {0.0, 0.0, 0.0, NAN, 1.0, 1.0}, volumes[2] = {1.0, 1.0};
    st = dem_coupling_deposit_cells(run, 2, centres, volumes, eps, mom, bsum, bv, msg,
                                    (int)sizeof msg);
    check(st == 2 && strstr(msg, "centres") != NULL, "deposit_cells, NaN centre:", msg);
    st = dem_coupling_deposit(run, good_o, good_h, cells, 3, eps, mom, bsum, bv, msg,
                              (int)sizeof msg);
    double volume = 0.0;
    for (int c = 0; c < 64; c++) volume += eps[c] * 1e-9;
    check(st == 0 && fabs(volume - 4.0 / 3.0 * acos(-1.0) * 1e-9) < 1e-21,
          "a good deposit afterwards holds the sphere's volume:", msg);
    check(dem_coupling_time(run) == t && sphere_z(run) == z, "time and sphere unchanged",
          NULL);
    st = dem_coupling_advance(run, 1e-4, msg, (int)sizeof msg);
    check(st == 0 && dem_coupling_time(run) == t + 1e-4, "the run goes on:", msg);
    st = dem_coupling_finalize(&run, msg, (int)sizeof msg);
    check(st == 0, "finalize:", msg);
}

/* A failed run stays failed and its finalize reports the failure without final.csv. */
static void failed_run(const char *file, const char *out, int fc)
{
    char msg[512], first[512], final_csv[128];
    int st;
    dem_coupling *run;
    struct stat info;
    st = dem_coupling_init(&run, file, fc, msg, (int)sizeof msg);
    check(st == 0, "init of the head-on case:", msg);
    st = dem_coupling_advance(run, 1.5e-5, first, (int)sizeof first);
    check(st == 3 && strstr(first, "reduce dt") != NULL, "the advance fails, unstable:", first);
    double t = dem_coupling_time(run);
    st = dem_coupling_advance(run, 1.5e-5, msg, (int)sizeof msg);
    check(st == 3 && strcmp(msg, first) == 0, "a later advance: 3, the same message:", msg);
    check(dem_coupling_time(run) == t, "the time stays", NULL);
    check(dem_coupling_status(run, msg, (int)sizeof msg) == 3 && strcmp(msg, first) == 0,
          "dem_coupling_status: the failure", msg);
    double eps[8], mom[24], bsum[8], bv[24], zero[6] = {0};
    const double origin[3] = {-0.04, -0.04, -0.04}, h[3] = {0.04, 0.04, 0.04};
    const int cells[3] = {2, 2, 2};
    st = dem_coupling_deposit(run, origin, h, cells, 1, eps, mom, bsum, bv, msg,
                              (int)sizeof msg);
    check(st == 3 && strcmp(msg, first) == 0, "a deposit: 3, the same message:", msg);
    check(dem_coupling_set_force(run, zero, zero) == 3, "set_force: 3", NULL);
    snprintf(final_csv, sizeof final_csv, "%s/final.csv", out);
    st = dem_coupling_finalize(&run, msg, (int)sizeof msg);
    check(st == 3 && strcmp(msg, first) == 0 && run == NULL,
          "finalize reports the failure:", msg);
    check(stat(final_csv, &info) != 0, "no final.csv", final_csv);
}

int main(int argc, char **argv)
{
    char file[64], out[64], head_on[64], head_on_out[64];
    int rank, size, fc;
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    fc = MPI_Comm_c2f(MPI_COMM_WORLD);
    snprintf(file, sizeof file, "coupling_misuse_%d.nml", size);
    snprintf(out, sizeof out, "coupling_misuse_out_%d", size);
    write_case(file, out, 0, rank);
    snprintf(head_on, sizeof head_on, "coupling_misuse_head_on_%d.nml", size);
    snprintf(head_on_out, sizeof head_on_out, "coupling_misuse_head_on_out_%d", size);
    write_case(head_on, head_on_out, 1, rank);

    bad_communicators(file);
    null_pointers(file, fc, rank);
    non_finite(file, fc, rank, size);
    failed_run(head_on, head_on_out, fc);
    MPI_Finalize();
    if (failures == 0 && rank == 0) printf("test_coupling_misuse: all checks passed\n");
    return failures == 0 ? 0 : 1;
}
