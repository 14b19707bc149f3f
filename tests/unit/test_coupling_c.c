// SPDX-License-Identifier: BSD-3-Clause
/* dem_coupling from C (src/api/dem_coupling.h), as a C fluid code calls it, on 1 and 2 ranks:
 * a sphere in a fluid moving sideways at u with drag beta (no buoyancy). Across the flow
 * (x) symplectic Euler gives v_n = u (1 - (1 - h beta / m)^n) after n sub-steps of h, to
 * round-off; the impulses the interface reports sum to the particle's x momentum; the
 * particle's id, material and radius come back as the case sets them, and the views show
 * what the copies hold; deposited with each kernel, the grid holds its volume, momentum and
 * beta; errors come back as a status and a message (truncated to the caller's buffer),
 * never as a stop.
 * A second handle in the same process runs a second sphere (its own id, case dt, drag and
 * fluid velocity), advanced in turn with the first: each follows its own discrete
 * solution, and once the second is finalised (its handle NULL) the first goes on alone. */
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <string.h>

#include "dem_coupling.h"

static int failures = 0;

static void check(int ok, const char *what, const char *detail)
{
    if (!ok) {
        failures++;
        fprintf(stderr, "FAILED: %s %s\n", what, detail ? detail : "");
    }
}

/* A case of one glass sphere (id, radius 1 mm) at rest at the origin, time step dt,
 * written by rank 0; its outputs go to folder `out`. */
static void write_case(const char *file, int id, const char *dt, const char *out, int rank)
{
    if (rank == 0) {
        FILE *f = fopen(file, "w");
        fprintf(f, "&run dt = %s, t_end = 1.0, gravity = 0, 0, -9.81 /\n", dt);
        fprintf(f, "&output dir = '%s', interval = 0.005 /\n", out);
        fprintf(f, "&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, "
                   "poisson_ratio = 0.25 /\n");
        fprintf(f, "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /\n");
        fprintf(f, "&particle id = %d, material = 'glass', radius = 1e-3, position = 0, 0, 0 /\n",
                id);
        fclose(f);
    }
    MPI_Barrier(MPI_COMM_WORLD);
}

/* Set the drag of `run`'s sphere (on the rank that owns it), advance by dt, and return its
 * x velocity and x impulse, summed over the ranks (each rank owns it or not). */
static void drag_step(dem_coupling *run, double beta, double u, double dt, double *vx,
                      double *jx)
{
    char msg[512];
    int n = dem_coupling_count(run);
    double b[1] = {beta}, uf[3] = {u, 0.0, 0.0}, mine[3] = {0.0, 0.0, 0.0}, all[3];
    check(n <= 1, "at most one particle per rank", NULL);
    if (n == 1) dem_coupling_set_drag(run, b, uf);
    int st = dem_coupling_advance(run, dt, msg, (int)sizeof msg);
    check(st == 0, "advance:", msg);
    if (dem_coupling_count(run) == 1) {
        int64_t gid[1];
        int mat[1];
        double r[1], x[3], v[3], w[3], j[3];
        dem_coupling_get(run, gid, mat, r, x, v, w);
        dem_coupling_impulse(run, j);
        mine[0] = v[0];
        mine[1] = j[0];
        mine[2] = 1.0;
    }
    MPI_Allreduce(mine, all, 3, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    check(all[2] == 1.0, "one rank owns the sphere", NULL);
    *vx = all[0];
    *jx = all[1];
}

int main(int argc, char **argv)
{
    const double pi = acos(-1.0), radius = 1e-3, rho = 2500.0, beta = 0.02, u = 0.002;
    const double beta2 = 0.03, u2 = -0.001;  /* the second sphere's drag and fluid */
    const double dt_fluid = 1e-4;  /* the case's dt is 3e-5: 4 sub-steps of 2.5e-5 */
    char msg[512], file[64], file2[64], out[64];
    int rank, size, fc, st, k;
    dem_coupling *run, *second;
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    fc = MPI_Comm_c2f(MPI_COMM_WORLD);

    st = dem_coupling_init(&run, "missing_case.nml", fc, msg, (int)sizeof msg);
    check(st == 2 && strstr(msg, "missing_case.nml") != NULL, "missing case file:", msg);
    check(run == NULL, "a failed init gives no handle", NULL);
    st = dem_coupling_advance(run, dt_fluid, msg, 8);
    check(st == 3 && strlen(msg) == 7, "advance on no handle, message cut to 8 bytes:", msg);
    check(dem_coupling_count(run) == 0 && dem_coupling_time(run) == 0.0, "no handle: no run",
          NULL);

    snprintf(file, sizeof file, "coupling_c_%d.nml", size);
    snprintf(out, sizeof out, "coupling_c_out_%d", size);
    write_case(file, 7, "3e-5", out, rank);
    st = dem_coupling_init(&run, file, fc, msg, (int)sizeof msg);
    check(st == 0 && run != NULL, "init:", msg);
    snprintf(file2, sizeof file2, "coupling_c_second_%d.nml", size);
    snprintf(out, sizeof out, "coupling_c_second_out_%d", size);
    write_case(file2, 9, "2e-5", out, rank);  /* 5 sub-steps of 2e-5 per advance */
    st = dem_coupling_init(&second, file2, fc, msg, (int)sizeof msg);
    check(st == 0 && second != NULL && second != run, "init of a second handle:", msg);

    const double m = rho * 4.0 / 3.0 * pi * pow(radius, 3), h = dt_fluid / 4, h2 = dt_fluid / 5;
    double impulse_x = 0.0, vx = 0.0, jx, impulse2 = 0.0, v2 = 0.0;
    for (k = 1; k <= 50; k++) {
        drag_step(run, beta, u, dt_fluid, &vx, &jx);
        impulse_x += jx;
        check(fabs(dem_coupling_time(run) - k * dt_fluid) < 1e-15, "time after the advance",
              NULL);
        double expected = u * (1.0 - pow(1.0 - h * beta / m, 4 * k));
        check(fabs(vx - expected) <= 1e-9 * fabs(expected), "v_x = the discrete solution", NULL);
        if (dem_coupling_count(run) == 1) {
            int64_t gid[1];
            int mat[1];
            double r[1], x[3], v[3], w[3];
            dem_coupling_get(run, gid, mat, r, x, v, w);
            const int64_t *gid_view;
            const double *r_view, *x_view, *v_view, *w_view, *xd, *vd, *wd;
            dem_coupling_views(run, &gid_view, &r_view, &x_view, &v_view, &w_view);
            dem_coupling_device_views(run, &xd, &vd, &wd);
            check(gid_view[0] == gid[0] && r_view[0] == r[0] && x_view[2] == x[2] &&
                  v_view[0] == v[0] && w_view[1] == w[1], "views = copies", NULL);
            check(xd != NULL && vd != NULL && wd != NULL, "device views", NULL);
            check(gid[0] == 7 && mat[0] == 1 && r[0] == radius, "id, material, radius", NULL);
        }
        if (k <= 25) {            /* the second run, in turn with the first */
            drag_step(second, beta2, u2, dt_fluid, &v2, &jx);
            impulse2 += jx;
            double expected2 = u2 * (1.0 - pow(1.0 - h2 * beta2 / m, 5 * k));
            check(fabs(v2 - expected2) <= 1e-9 * fabs(expected2),
                  "second handle: v_x = its own discrete solution", NULL);
            if (dem_coupling_count(second) == 1) {
                const int64_t *gid_view;
                const double *r_view, *x_view, *v_view, *w_view;
                dem_coupling_views(second, &gid_view, &r_view, &x_view, &v_view, &w_view);
                check(gid_view[0] == 9, "second handle: its own particle", NULL);
            }
        }
        if (k == 25) {
            check(fabs(m * v2 - impulse2) <= 1e-9 * fabs(m * v2),
                  "second handle: momentum = the impulses", NULL);
            st = dem_coupling_finalize(&second, msg, (int)sizeof msg);
            check(st == 0 && second == NULL, "finalize of the second handle:", msg);
        }
    }
    check(fabs(m * vx - impulse_x) <= 1e-9 * fabs(m * vx), "momentum: the impulses", NULL);

    /* deposit onto 4 x 4 x 4 cells of 1 mm around the sphere, each kernel: every rank gets
     * the sphere's volume and its x momentum in the whole grid */
    {
        const double origin[3] = {-0.002, -0.002, -0.003}, h[3] = {1e-3, 1e-3, 1e-3};
        const int n[3] = {4, 4, 4};
        double eps[64], mom[192], bsum[64], bv[192];
        for (int kernel = 1; kernel <= 3; kernel++) {
            st = dem_coupling_deposit(run, origin, h, n, kernel, eps, mom, bsum, bv, msg,
                                      (int)sizeof msg);
            check(st == 0 && msg[0] == '\0', "deposit:", msg);
            double volume = 0.0, px = 0.0, b = 0.0;
            for (int c = 0; c < 64; c++) {
                volume += eps[c] * 1e-9;
                px += mom[3 * c];
                b += bsum[c];
            }
            check(fabs(volume - 4.0 / 3.0 * pi * pow(radius, 3)) <= 1e-12 * volume,
                  "deposit: the sphere's volume", NULL);
            check(fabs(px - m * vx) <= 1e-12 * fabs(m * vx), "deposit: its momentum", NULL);
            check(fabs(b - beta) <= 1e-12 * beta, "deposit: its beta", NULL);
        }
        st = dem_coupling_deposit(run, origin, h, n, 4, eps, mom, bsum, bv, msg,
                                  (int)sizeof msg);
        check(st == 2, "deposit with kernel 4:", msg);
        st = dem_coupling_deposit(second, origin, h, n, 1, eps, mom, bsum, bv, msg,
                                  (int)sizeof msg);
        check(st == 3, "deposit on a finalised handle:", msg);
    }
    st = dem_coupling_finalize(&run, msg, (int)sizeof msg);
    check(st == 0 && run == NULL, "finalize:", msg);
    st = dem_coupling_advance(run, dt_fluid, msg, (int)sizeof msg);
    check(st == 3, "advance after finalize:", msg);
    st = dem_coupling_finalize(&run, msg, (int)sizeof msg);
    check(st == 3, "finalize after finalize:", msg);
    MPI_Finalize();
    if (failures == 0 && rank == 0) printf("test_coupling_c: all checks passed\n");
    return failures == 0 ? 0 : 1;
}
