/* dem_coupling from C (src/dem_coupling.h), as a C fluid code calls it, on 1 and 2 ranks:
 * a sphere in a fluid moving sideways at u with drag beta (no buoyancy). Across the flow
 * (x) symplectic Euler gives v_n = u (1 - (1 - h beta / m)^n) after n sub-steps of h, to
 * round-off; the impulses the interface reports sum to the particle's x momentum; the
 * particle's id, material and radius come back as the case sets them, and the views show
 * what the copies hold; deposited with each
 * kernel, the grid holds its volume, momentum and beta; errors come back as a status and a
 * message (truncated to the caller's buffer), never as a stop. */
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

int main(int argc, char **argv)
{
    const double pi = acos(-1.0), radius = 1e-3, rho = 2500.0, beta = 0.02, u = 0.002;
    const double dt_fluid = 1e-4;  /* the case's dt is 3e-5: 4 sub-steps of 2.5e-5 */
    char msg[512], file[64];
    int rank, size, fc, st, k;
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    fc = MPI_Comm_c2f(MPI_COMM_WORLD);

    st = dem_coupling_init("missing_case.nml", fc, msg, (int)sizeof msg);
    check(st == 2 && strstr(msg, "missing_case.nml") != NULL, "missing case file:", msg);
    st = dem_coupling_advance(dt_fluid, msg, 8);
    check(st == 3 && strlen(msg) == 7, "advance before init, message cut to 8 bytes:", msg);

    snprintf(file, sizeof file, "coupling_c_%d.nml", size);
    if (rank == 0) {
        FILE *f = fopen(file, "w");
        fprintf(f, "&run dt = 3e-5, t_end = 1.0, gravity = 0, 0, -9.81 /\n");
        fprintf(f, "&output dir = 'coupling_c_out_%d', interval = 0.005 /\n", size);
        fprintf(f, "&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, "
                   "poisson_ratio = 0.25 /\n");
        fprintf(f, "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /\n");
        fprintf(f, "&particle id = 7, material = 'glass', radius = 1e-3, position = 0, 0, 0 /\n");
        fclose(f);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    st = dem_coupling_init(file, fc, msg, (int)sizeof msg);
    check(st == 0, "init:", msg);

    const double m = rho * 4.0 / 3.0 * pi * pow(radius, 3), h = dt_fluid / 4;
    double impulse_x = 0.0, vx = 0.0;
    for (k = 1; k <= 50; k++) {
        int n = dem_coupling_count();
        double b[1] = {beta}, uf[3] = {u, 0.0, 0.0};
        check(n <= 1, "at most one particle per rank", NULL);
        if (n == 1) dem_coupling_set_drag(b, uf);
        st = dem_coupling_advance(dt_fluid, msg, (int)sizeof msg);
        check(st == 0, "advance:", msg);
        check(fabs(dem_coupling_time() - k * dt_fluid) < 1e-15, "time after the advance", NULL);
        n = dem_coupling_count();
        double mine[3] = {0.0, 0.0, 0.0}, all[3];
        if (n == 1) {
            int64_t gid[1];
            int mat[1];
            double r[1], x[3], v[3], w[3], j[3];
            dem_coupling_get(gid, mat, r, x, v, w);
            dem_coupling_impulse(j);
            const int64_t *gid_view;
            const double *r_view, *x_view, *v_view, *w_view, *xd, *vd, *wd;
            dem_coupling_views(&gid_view, &r_view, &x_view, &v_view, &w_view);
            dem_coupling_device_views(&xd, &vd, &wd);
            check(gid_view[0] == gid[0] && r_view[0] == r[0] && x_view[2] == x[2] &&
                  v_view[0] == v[0] && w_view[1] == w[1], "views = copies", NULL);
            check(xd != NULL && vd != NULL && wd != NULL, "device views", NULL);
            check(gid[0] == 7 && mat[0] == 1 && r[0] == radius, "id, material, radius", NULL);
            mine[0] = v[0];
            mine[1] = j[0];
            mine[2] = 1.0;
        }
        MPI_Allreduce(mine, all, 3, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
        check(all[2] == 1.0, "one rank owns the sphere", NULL);
        vx = all[0];
        impulse_x += all[1];
        double expected = u * (1.0 - pow(1.0 - h * beta / m, 4 * k));
        check(fabs(vx - expected) <= 1e-9 * fabs(expected), "v_x = the discrete solution", NULL);
    }
    check(fabs(m * vx - impulse_x) <= 1e-9 * fabs(m * vx), "momentum: the impulses", NULL);

    /* deposit onto 4 x 4 x 4 cells of 1 mm around the sphere, each kernel: every rank gets
     * the sphere's volume and its x momentum in the whole grid */
    {
        const double origin[3] = {-0.002, -0.002, -0.003}, h[3] = {1e-3, 1e-3, 1e-3};
        const int n[3] = {4, 4, 4};
        double eps[64], mom[192], bsum[64], bv[192];
        for (int kernel = 1; kernel <= 3; kernel++) {
            st = dem_coupling_deposit(origin, h, n, kernel, eps, mom, bsum, bv, msg,
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
        st = dem_coupling_deposit(origin, h, n, 4, eps, mom, bsum, bv, msg, (int)sizeof msg);
        check(st == 2, "deposit with kernel 4:", msg);
    }
    st = dem_coupling_finalize(msg, (int)sizeof msg);
    check(st == 0, "finalize:", msg);
    st = dem_coupling_advance(dt_fluid, msg, (int)sizeof msg);
    check(st == 3, "advance after finalize:", msg);
    MPI_Finalize();
    if (failures == 0 && rank == 0) printf("test_coupling_c: all checks passed\n");
    return failures == 0 ? 0 : 1;
}
