/* test_mpi_watchdog.c - the energy watchdog's message under MPI names the culprit as one
 * process does (core/integrators/watchdog.c, core/parallel floe_par_pick; docs/parallel.md,
 * "Errors inside a step"). Run under mpirun with 1, 2 and 4 ranks (tests/CMakeLists.txt).
 * Every rank builds the same world twice, runs one copy whole (one process's run, on every
 * rank) and splits the other, and compares:
 *   1. a contact law that creates energy (a spring with a negative dashpot, as
 *      tests/test_watchdog.c): twelve spheres in a row fall onto a wall from heights that
 *      differ (the last in the row, on the last rank, lowest), each touching only the wall; the run stops when the first contact has fed
 *      more than the tolerance: the split run returns FLOE_EUNSTABLE at the same step with
 *      the same message, which names that sphere and the wall by their index in the whole
 *      scene and the law (before session 28 the split run named no pair, only the measures);
 *      with more than one rank the culprit is owned by a rank other than 0 (checked).
 *      The spheres touch only the wall, so each sphere's force is one contact's, evaluated by
 *      one rank: the split run's bits are one process's and the culprit is the same pair.
 *   2. the balance case (energy from outside the ledger: the rank holding the most energetic
 *      particle names it; session 30): a user force provider (per-particle, so it runs split)
 *      pushes every free sphere along its velocity, F = c m v, without booking its work; the
 *      twelve spheres move apart along x, touching nothing, the last (on the last rank) the
 *      fastest: the split run stops at the same step with the same message, which names that
 *      sphere by its index in the whole scene. (A body force cannot reach this case: velocity
 *      Verlet books a body force's work, so the particle checks stop such runs first.) */
#include "floe.h"
#include "../check.h"
#include "mpi_common.h"
#include "../pump_law.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { NS = 12 };

/* the pump law, twelve spheres falling onto a wall */
static floe_world *build(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.gravity[2] = 0.0;
    d.dt = 1e-5;
    const double R = 0.01, rho = 2500, m = rho * 4.0 / 3.0 * M_PI * R * R * R, k = 1e5;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material mt = mpi_test_glass(1e7);
    const int mat = floe_world_add_material(w, &mt);
    floe_world_set_law(w, mat, mat, pump_create(m, k, 0.1));
    const double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, mat, FLOE_FIXED);
    const int g = floe_world_add_geometry(w, floe_sphere_create(R));
    for (int s = 0; s < NS; s++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        p.material = mat;
        /* at 1 m/s from heights 0.5 mm apart above the wall, the last (on the last rank) lowest */
        floe_v3_set(p.x, 3 * R * s, 0, R + 0.0005 * (NS - s));
        floe_v3_set(p.v, 0, 0, -1);
        floe_world_add_particle(w, &p);
    }
    floe_world_set_threads(w, 1);
    return w;
}

/* variant 2: an unbooked push along each free particle's velocity, F = c m v (per particle:
 * it runs split) */
typedef struct push { floe_provider base; double c; } push;
static int push_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *sc, floe_provider_out *out) {
    (void)w;
    (void)out; /* its work not booked: energy from outside the ledger */
    const double c = ((const push *)pv)->c;
    floe_provider_ctx x = floe_provider_ctx_of(sc);
    for (int i = 0; i < x.n; i++)
        if (x.motion[i] == FLOE_FREE)
            for (int d = 0; d < 3; d++) x.f[3 * i + d] += c * x.mass[i] * x.v[3 * i + d];
    return FLOE_OK;
}
static const floe_provider_class push_class = {.version = 2, .name = "push", .group = FLOE_GROUP_DEM,
                                               .forces = push_forces, .splits = FLOE_PROVIDER_PER_PARTICLE};

/* twelve spheres 3 R apart in a row along x above a wall they never reach, moving along x at
 * 1 + 0.1 s m/s (the last the fastest: the row spreads, no contact), under the push */
static floe_world *build_push(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.gravity[2] = 0.0;
    d.dt = 1e-5;
    const double R = 0.01;
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    const double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
    const int g = floe_world_add_geometry(w, floe_sphere_create(R));
    for (int s = 0; s < NS; s++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        floe_v3_set(p.x, 3 * R * s, 0, 5 * R);
        floe_v3_set(p.v, 1 + 0.1 * s, 0, 0);
        floe_world_add_particle(w, &p);
    }
    push *pu = calloc(1, sizeof *pu);
    pu->base.klass = &push_class;
    pu->c = 20; /* 1/s: the kinetic energy doubles in about 17 ms */
    if (floe_world_add_provider(w, &pu->base)) {
        CHECK(0, "add_provider push: %s", floe_world_last_error(w));
        free(pu);
    }
    floe_world_set_threads(w, 1);
    return w;
}

/* steps until an error (at most nmax); the step count and the message */
static int run(floe_world *w, int nmax, long *step, char *msg, size_t len) {
    int rc = FLOE_OK;
    for (int s = 0; s < nmax && !rc; s++) rc = floe_world_step(w);
    *step = floe_world_step_count(w);
    snprintf(msg, len, "%s", rc ? floe_world_last_error(w) : "");
    return rc;
}

static void compare(int variant, floe_world *(*mk)(void), const char *must) {
    floe_world *whole = mk(), *split = mk();
    int owner = -1; /* the rank that owns particle 12, the culprit */
    char m1[1024], m2[1024];
    long s1 = 0, s2 = 0;
    int rc1 = floe_world_prepare(whole), rc2 = floe_world_prepare(split);
    if (!rc2) rc2 = floe_world_parallel_init(split, NULL);
    if (!rc2) {
        for (int i = 0; i < floe_world_particle_count(split); i++)
            if (floe_world_parallel_gid(split, i) == 12 && floe_world_parallel_is_owned(split, i)) owner = rank_;
        MPI_Allreduce(MPI_IN_PLACE, &owner, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
        CHECK(size_ == 1 || owner > 0, "the culprit, particle 12, is owned by rank %d (not 0)", owner);
    }
    CHECK(rc1 == FLOE_OK && rc2 == FLOE_OK, "variant %d: set-up: %s / %s", variant, floe_world_last_error(whole),
          floe_world_last_error(split));
    if (!rc1 && !rc2) {
        rc1 = run(whole, 20000, &s1, m1, sizeof m1);
        rc2 = run(split, 20000, &s2, m2, sizeof m2);
        if (rank_ == 0) printf("  variant %d: one process: rc %d at step %ld: %s\n", variant, rc1, s1, m1);
        CHECK(rc1 == FLOE_EUNSTABLE && strstr(m1, "energy watchdog") && strstr(m1, must),
              "variant %d: one process stops on the watchdog naming '%s' (rc %d: %s)", variant, must, rc1, m1);
        CHECK(rc2 == rc1 && s2 == s1 && strcmp(m1, m2) == 0,
              "rank %d, variant %d: the split run stops as one process (rc %d at step %ld: %s)", rank_, variant, rc2, s2,
              m2);
        CHECK(floe_world_parallel_error_agreed(split) == 1, "rank %d, variant %d: the error is agreed", rank_, variant);
    }
    floe_world_destroy(whole);
    floe_world_destroy(split);
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    compare(1, build, "the contact of particles 12 and 0 (bodies 0, -1; law pump (test))"); /* a wall is j */
    compare(2, build_push, "beyond the ledger (balance error), most of it in particle 12 (body 0)");
    int all = mpi_test_failed("test_mpi_watchdog");
    MPI_Finalize();
    return all ? 1 : 0;
}
