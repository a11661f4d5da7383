/* test_mpi_bodyforce.c - the body-force callback in a world split over MPI ranks
 * (core/parallel/par_forcing.c, docs/parallel.md "Forcing providers and servo walls"). Run
 * under mpirun with 1, 2 and 4 ranks. Rank 0 first runs the unsplit world alone; then every
 * rank builds the same world, splits it and steps it. 125 spheres in a walled box, no
 * gravity; the callback pulls every sphere towards the box's centre (-k m (x - c)) and adds
 * a force and a torque that depend on the particle's global id (floe_world_parallel_gid on a
 * split world: the callback gets local indices). After 2,000 steps (contacts, migrations):
 * positions within 1e-10 of the box side, velocities within 1e-8 of the largest speed, and
 * the body-force work summed over the ranks within 1e-9 of its own size (it is more than
 * 1 % of the kinetic energy: the callback matters). */
#include "floe.h"
#include "world_internal.h"
#include "../check.h"
#include "mpi_common.h"
#include <math.h>
#include <stdlib.h>

enum { NS = 5, STEPS = 2000 };
static const double R = 0.001, SP = 0.0024, DT = 2.5e-6, L = NS * 0.0024 + 0.001;

static void pull(const floe_world *w, int i, double t, double f[3], double torque[3], void *user) {
    (void)t; (void)user;
    floe_particles_view v;
    floe_world_particles(w, &v);
    const long long g = floe_world_parallel_gid(w, i); /* i itself in one process */
    for (int k = 0; k < 3; k++) f[k] = -2e3 * v.mass[i] * (v.x[3 * i + k] - 0.5 * L);
    f[2] += 2e-4 * (double)(g % 3);
    torque[2] = 1e-9 * (double)(g % 2);
}

static floe_world *build(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = DT;
    floe_world *w = mpi_test_sphere_box(d, NS, R, SP, L);
    floe_world_set_body_force(w, pull, NULL);
    return w;
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    double *x0 = NULL, *v0 = NULL;
    int N = 0;
    floe_energy e0 = {0};
    if (rank_ == 0) { /* the unsplit run */
        floe_world *w = build();
        if (mpi_test_serial_run(w, STEPS, &N, &x0, &v0, &e0)) {
            fprintf(stderr, "serial: %s\n", floe_world_last_error(w));
            return 1;
        }
        floe_world_destroy(w);
    }
    floe_world *w = build();
    const int n = 6 + NS * NS * NS;
    double *xp, *vp;
    floe_energy e;
    const int rc = mpi_test_split_run(w, STEPS, n, &xp, &vp, &e);
    CHECK(rc == 0, "split run: %s", rc ? floe_world_last_error(w) : "");
    if (rank_ == 0 && rc == 0) {
        double dx, dv, vmax;
        mpi_test_max_diffs(xp, x0, vp, v0, 3 * 6, 3 * n, &dx, &dv, &vmax); /* the spheres (the walls are 0 .. 5) */
        CHECK(N == n, "particle count %d (%d)", N, n);
        CHECK(dx <= 1e-10 * L, "positions: %.3g of the side (tol 1e-10)", dx / L);
        CHECK(dv <= 1e-8 * vmax, "velocities: %.3g of the largest speed (tol 1e-8)", dv / vmax);
        const double dw = fabs(e.work_body - e0.work_body);
        CHECK(dw <= 1e-9 * fabs(e0.work_body), "body-force work %.17g vs %.17g (%.3g of it, tol 1e-9)", e.work_body,
              e0.work_body, dw / fabs(e0.work_body));
        CHECK(fabs(e0.work_body) > 0.01 * (e0.kinetic_trans + e0.kinetic_rot), "the callback's work %.3g J is more "
              "than 1 %% of the kinetic energy %.3g J", e0.work_body, e0.kinetic_trans + e0.kinetic_rot);
        printf("  positions %.2e of the side, velocities %.2e of the largest speed, body work %.2e of it "
               "(%.3g J; kinetic %.3g J)\n", dx / L, dv / vmax, dw / fabs(e0.work_body), e0.work_body,
               e0.kinetic_trans + e0.kinetic_rot);
    }
    free(xp); free(vp); free(x0); free(v0);
    floe_world_destroy(w);
    const int fails = mpi_test_failed("test_mpi_bodyforce");
    MPI_Finalize();
    return fails ? 1 : 0;
}
