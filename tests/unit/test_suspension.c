// SPDX-License-Identifier: BSD-3-Clause
/* A toy one-dimensional fluid solver coupled two-way to dem through the C interface: a
 * settling suspension (doc/user/coupling.md walks through it). Run on 1 and 2 ranks.
 *
 * 400 glass spheres (R = 0.5 mm) spread through a closed 10 x 10 mm column of viscous fluid
 * (mu = 0.1 Pa s, rho_f = 1000 kg/m^3) settle. The fluid lives on 8 cells along z. At each
 * fluid step it takes from dem the solids fraction eps_s and the solids volume flux of each
 * cell (momentum / rho_p, divided-particle-volume kernel), and, the column being closed, flows
 * up where the solids flow down: u_f = -eps_s u_s / (1 - eps_s) (zero net volume flux). It
 * gives each sphere buoyancy rho_f V g and the drag beta = 6 pi mu R (1 - eps_s)^-(n - 1),
 * n = 4.65, towards u_f of its cell.
 *
 * In a uniform suspension this model settles at v = v_t eps_f^n (Richardson & Zaki's law),
 * v_t = 2 (rho_p - rho_f) g R^2 / (9 mu): the drag alone would give v_t eps_f^(n - 1); the
 * last factor eps_f is the fluid's counterflow, so it checks the two-way coupling. After 10
 * relaxation times the mean velocity of the spheres in the middle of the column equals the
 * mean of v_t eps_f^n over them within 2 %, and differs from the one-way value by more. */
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

#include "dem_coupling.h"

#define NZ 8           /* fluid cells along z */
#define N 400          /* spheres */
#define RZ_N 4.65      /* Richardson-Zaki exponent */

static int failures = 0;

static void check(int ok, const char *what, double got, double expected)
{
    if (!ok) {
        failures++;
        fprintf(stderr, "FAILED: %s (got %.6g, expected %.6g)\n", what, got, expected);
    }
}

int main(int argc, char **argv)
{
    const double pi = acos(-1.0), g = 9.81, R = 5e-4, rho_p = 2500.0, rho_f = 1000.0,
                 mu = 0.1, dt_fluid = 1e-3;
    const double origin[3] = {-0.005, -0.005, 0.0}, h[3] = {0.01, 0.01, 0.005};
    const int cells[3] = {1, 1, NZ};
    const double vp = 4.0 / 3.0 * pi * R * R * R, beta0 = 6.0 * pi * mu * R;
    const double v_t = 2.0 * (rho_p - rho_f) * g * R * R / (9.0 * mu);
    const double tau = rho_p * vp / beta0;
    double eps[NZ], mom[3 * NZ], bsum[NZ], bv[3 * NZ], eps_f[NZ], u_f[NZ];
    static double x[3 * N], v[3 * N], w[3 * N], r[N], beta[N], uf[3 * N], f[3 * N], t[3 * N];
    static int64_t gid[N];
    static int mat[N];
    char msg[512];
    int rank, size, st;
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);

    char file[64];
    snprintf(file, sizeof file, "suspension_%d.nml", size);
    if (rank == 0) {
        FILE *c = fopen(file, "w");
        fprintf(c, "&run dt = 1e-5, t_end = 1.0, gravity = 0, 0, -9.81 /\n");
        fprintf(c, "&output dir = 'suspension_out_%d', interval = 0.01 /\n", size);
        fprintf(c, "&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, "
                   "poisson_ratio = 0.25 /\n");
        fprintf(c, "&material name = 'wall', density = 7800.0, youngs_modulus = 1e8, "
                   "poisson_ratio = 0.3 /\n");
        fprintf(c, "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /\n");
        fprintf(c, "&pair materials = 'glass', 'wall', restitution = 0.5, friction = 0.0 /\n");
        fprintf(c, "&insert n = %d, material = 'glass', radius_min = 5e-4, radius_max = 5e-4, "
                   "region = 'box', box_min = -0.0045, -0.0045, 0.0055, "
                   "box_max = 0.0045, 0.0045, 0.0345, seed = 11 /\n", N);
        const char *walls[5][2] = {{"0, 0, 0", "0, 0, 1"}, {"-0.005, 0, 0.02", "1, 0, 0"},
                                   {"0.005, 0, 0.02", "-1, 0, 0"}, {"0, -0.005, 0.02", "0, 1, 0"},
                                   {"0, 0.005, 0.02", "0, -1, 0"}};
        for (int k = 0; k < 5; k++)
            fprintf(c, "&wall_plane material = 'wall', point = %s, normal = %s, "
                       "half_width = 0.03 /\n", walls[k][0], walls[k][1]);
        fclose(c);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    dem_coupling *run;
    st = dem_coupling_init(&run, file, MPI_Comm_c2f(MPI_COMM_WORLD), msg, (int)sizeof msg);
    if (st != 0) {
        fprintf(stderr, "init: %s\n", msg);
        MPI_Abort(MPI_COMM_WORLD, 1);
    }

    int steps = (int)ceil(10.0 * tau / dt_fluid);
    double mean_v = 0.0, mean_rz = 0.0, mean_one_way = 0.0;
    for (int step = 0; step <= steps; step++) {
        /* the fluid: solids fraction and volume flux per cell, counterflow */
        st = dem_coupling_deposit(run, origin, h, cells, 3, eps, mom, bsum, bv, msg,
                                  (int)sizeof msg);
        check(st == 0, "deposit", st, 0);
        for (int c = 0; c < NZ; c++) {
            eps_f[c] = 1.0 - eps[c];
            double solids_flux = mom[3 * c + 2] / (rho_p * h[0] * h[1] * h[2]);  /* eps_s u_s */
            u_f[c] = -solids_flux / eps_f[c];
        }
        /* ... gives the particles buoyancy and drag towards the fluid of their cell */
        int n = dem_coupling_count(run);
        dem_coupling_get(run, gid, mat, r, x, v, w);
        double sums[4] = {0.0, 0.0, 0.0, 0.0}, all[4];
        for (int i = 0; i < n; i++) {
            int c = (int)floor((x[3 * i + 2] - origin[2]) / h[2]);
            c = c < 0 ? 0 : (c >= NZ ? NZ - 1 : c);
            beta[i] = beta0 * pow(eps_f[c], -(RZ_N - 1.0));
            uf[3 * i] = uf[3 * i + 1] = 0.0;
            uf[3 * i + 2] = u_f[c];
            f[3 * i] = f[3 * i + 1] = t[3 * i] = t[3 * i + 1] = t[3 * i + 2] = 0.0;
            f[3 * i + 2] = rho_f * vp * g;
            if (c >= 2 && c <= 4) {           /* the middle of the suspension */
                sums[0] += v[3 * i + 2];
                sums[1] += -v_t * pow(eps_f[c], RZ_N);
                sums[2] += -v_t * pow(eps_f[c], RZ_N - 1.0);
                sums[3] += 1.0;
            }
        }
        MPI_Allreduce(sums, all, 4, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
        mean_v = all[0] / all[3];
        mean_rz = all[1] / all[3];
        mean_one_way = all[2] / all[3];
        if (step == steps) break;
        dem_coupling_set_force(run, f, t);
        dem_coupling_set_drag(run, beta, uf);
        st = dem_coupling_advance(run, dt_fluid, msg, (int)sizeof msg);
        check(st == 0, "advance", st, 0);
    }
    if (rank == 0)
        printf("test_suspension: after %d fluid steps: mean v_z %.5g m/s, Richardson-Zaki "
               "%.5g, one-way %.5g, v_t %.5g\n", steps, mean_v, mean_rz, mean_one_way, -v_t);
    check(fabs(mean_v - mean_rz) <= 0.02 * fabs(mean_rz), "settling velocity = v_t eps_f^n",
          mean_v, mean_rz);
    check(fabs(mean_v - mean_one_way) > 0.04 * fabs(mean_rz),
          "distinct from the one-way coupled v_t eps_f^(n-1)", mean_v, mean_one_way);
    st = dem_coupling_finalize(&run, msg, (int)sizeof msg);
    check(st == 0, "finalize", st, 0);
    MPI_Finalize();
    if (failures == 0 && rank == 0) printf("test_suspension: all checks passed\n");
    return failures == 0 ? 0 : 1;
}
