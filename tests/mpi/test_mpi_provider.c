/* test_mpi_provider.c - a user's force provider in a world split over MPI ranks
 * (floe_provider.h, version 2: .splits = FLOE_PROVIDER_PER_PARTICLE; docs/parallel.md
 * "Forcing providers and servo walls"). Run under mpirun with 1, 2 and 4 ranks.
 *
 *  1. The provider: a tether F = -k m (x - c) towards the box's centre on every free sphere,
 *     its stored energy k m |x - c|^2 / 2 booked as elastic, and a torque about z on spheres
 *     moving in +x (a force that reads the particle's own velocity; its work tau w_z dt at
 *     the evaluation's spin booked as work_boundary: the energy watchdog stops the run
 *     without it). 125 spheres in a walled box, no gravity, 2,000 steps of velocity Verlet,
 *     1,000 of RK2 (its midpoint probe calls the provider too), 2,000 of leapfrog and 1,000
 *     accepted adaptive steps of velocity Verlet (the trials agreed over the ranks) with
 *     contacts and migrations. Rank 0 first runs the unsplit world alone; then every rank builds the same world, splits it and steps it: positions
 *     within 1e-10 of the box side, velocities within 1e-8 of the largest speed, the stored
 *     energy summed over the ranks within 1e-9 of the unsplit one (the tether's share of it
 *     is more than half: the provider matters), the torque's work summed over the ranks
 *     within 1e-9, the rotational kinetic energy within 1e-8 (more than twice that of the
 *     same run without the torque: the torque matters).
 *     The same provider in FLOE_GROUP_PD on the points of a PMB block (216 points, free in
 *     space, the tether's centre at a corner so that the bonds work), 500 steps of velocity
 *     Verlet and of the staggered PD-DEM scheme (two PD sub-steps a step: the provider runs
 *     at the PD rate): positions within 1e-10 of the block, velocities within 1e-8, the
 *     stored energy within 1e-9.
 *  2. The same provider declaring nothing (version 1, and version 2 with splits 0): the
 *     split is refused on every rank (FLOE_ENOTSUP), the message naming the provider and
 *     the declaration it lacks.
 *  3. floe_world_add_provider refuses a version-2 class with splits other than 0 or
 *     FLOE_PROVIDER_PER_PARTICLE, and a per-particle one that keeps a state or excludes
 *     pairs (FLOE_EINVAL, the world unchanged: the caller keeps the provider). */
#include "floe.h"
#include "floe_pd.h"
#include "../check.h"
#include "mpi_common.h"
#include <math.h>
#include <stdlib.h>

enum { NS = 5, STEPS = 2000 };
static const double R = 0.001, SP = 0.0024, DT = 2.5e-6, L = NS * 0.0024 + 0.001, K = 2e3;

typedef struct tether { floe_provider base; double c[3], k; } tether;
static double torque_ = 1e-6; /* N m, about z, on a sphere moving in +x (0: the reference run) */

static int tether_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *sc, floe_provider_out *out) {
    (void)w;
    const tether *t = (const tether *)pv;
    floe_provider_ctx c = floe_provider_ctx_of(sc);
    for (int i = 0; i < c.n; i++) {
        if (c.motion[i] != FLOE_FREE) continue;
        for (int d = 0; d < 3; d++) {
            const double u = c.x[3 * i + d] - t->c[d];
            c.f[3 * i + d] -= t->k * c.mass[i] * u;
            out->elastic += 0.5 * t->k * c.mass[i] * u * u;
        }
        if (c.v[3 * i] > 0) { /* its own velocity decides; its work tau w_z dt booked as the boundary's */
            c.t[3 * i + 2] += torque_;
            if (c.stepping) out->work_boundary += torque_ * c.w[3 * i + 2] * c.dt;
        }
    }
    return FLOE_OK;
}
static size_t no_state(const floe_provider *pv, const floe_world *w) { (void)pv; (void)w; return 0; }
static void no_save(const floe_provider *pv, const floe_world *w, unsigned char *b) { (void)pv; (void)w; (void)b; }
static void no_restore(floe_provider *pv, floe_world *w, const unsigned char *b) { (void)pv; (void)w; (void)b; }
static int no_pairs(const floe_provider *pv, const floe_world *w, int i, int j) { (void)pv; (void)w; (void)i; (void)j; return 0; }

static const floe_provider_class split_class = {.version = 2, .name = "tether", .group = FLOE_GROUP_DEM,
                                                .forces = tether_forces, .splits = FLOE_PROVIDER_PER_PARTICLE};
static const floe_provider_class v1_class = {.version = 1, .name = "tether_v1", .group = FLOE_GROUP_DEM,
                                             .forces = tether_forces};
static const floe_provider_class v2_none_class = {.version = 2, .name = "tether_v2_none", .group = FLOE_GROUP_DEM,
                                                  .forces = tether_forces, .splits = 0};
static const floe_provider_class bad_splits_class = {.version = 2, .name = "tether_bad", .group = FLOE_GROUP_DEM,
                                                     .forces = tether_forces, .splits = 7};
static const floe_provider_class stateful_class = {
    .version = 2, .name = "tether_state", .group = FLOE_GROUP_DEM, .forces = tether_forces, .state_size = no_state,
    .save = no_save, .restore = no_restore, .splits = FLOE_PROVIDER_PER_PARTICLE};
static const floe_provider_class excluding_class = {.version = 2, .name = "tether_excl", .group = FLOE_GROUP_DEM,
                                                    .forces = tether_forces, .excludes = no_pairs,
                                                    .splits = FLOE_PROVIDER_PER_PARTICLE};

static tether *new_tether(const floe_provider_class *k) {
    tether *t = calloc(1, sizeof *t);
    t->base.klass = k;
    for (int d = 0; d < 3; d++) t->c[d] = 0.5 * L;
    t->k = K;
    return t;
}

static int adaptive_ = 0; /* 1: adaptive steps (floe_world_def.adaptive) */

static floe_world *build(const floe_provider_class *k, floe_integrator integ) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = DT; d.integrator = integ; d.adaptive = adaptive_;
    floe_world *w = mpi_test_sphere_box(d, NS, R, SP, L);
    if (k) {
        tether *t = new_tether(k);
        if (floe_world_add_provider(w, &t->base)) { free(t); CHECK(0, "add_provider: %s", floe_world_last_error(w)); }
    }
    return w;
}

/* part 1: the split run against the unsplit one */
static void split_matches(floe_integrator integ, int steps, const char *tag) {
    double *x0 = NULL, *v0 = NULL;
    int N = 0;
    floe_energy e0 = {0}, ep = {0}, er = {0};
    if (rank_ == 0) { /* the unsplit run, the same without the torque, and without the provider */
        torque_ = 0;
        floe_world *w = build(&split_class, integ);
        for (int s = 0; s < steps; s++)
            if (floe_world_step(w)) { CHECK(0, "%s serial without the torque: %s", tag, floe_world_last_error(w)); break; }
        er = floe_world_energy(w);
        floe_world_destroy(w);
        torque_ = 1e-6;
        w = build(&split_class, integ);
        const int src = mpi_test_serial_run(w, steps, &N, &x0, &v0, &e0);
        CHECK(src == 0, "%s serial: %s", tag, src ? floe_world_last_error(w) : "");
        if (adaptive_) { /* the steps did adapt: not all of them DT */
            floe_step_stats st;
            floe_world_step_stats(w, &st);
            CHECK(st.dt_max_used > 1.01 * st.dt_min_used && fabs(floe_world_time(w) - steps * DT) > 0.01 * steps * DT,
                  "%s: the steps adapted (dt %.3g .. %.3g s, t %.6g s against %d x %.3g s)", tag, st.dt_min_used,
                  st.dt_max_used, floe_world_time(w), steps, DT);
            printf("  %s: dt from %.3g to %.3g s, %ld trials redone\n", tag, st.dt_min_used, st.dt_max_used, st.rejected);
        }
        floe_world_destroy(w);
        w = build(NULL, FLOE_VELOCITY_VERLET);
        floe_world_prepare(w);
        ep = floe_world_energy(w);
        floe_world_destroy(w);
    }
    floe_world *w = build(&split_class, integ);
    const int n = 6 + NS * NS * NS;
    double *xp, *vp;
    floe_energy e;
    const int rc = mpi_test_split_run(w, steps, n, &xp, &vp, &e);
    CHECK(rc == 0, "%s split run: %s", tag, rc ? floe_world_last_error(w) : "");
    if (rank_ == 0 && rc == 0) {
        double dx, dv, vmax;
        mpi_test_max_diffs(xp, x0, vp, v0, 3 * 6, 3 * n, &dx, &dv, &vmax); /* the spheres (the walls are 0 .. 5) */
        CHECK(N == n, "particle count %d (%d)", N, n);
        CHECK(dx <= 1e-10 * L, "positions: %.3g of the side (tol 1e-10)", dx / L);
        CHECK(dv <= 1e-8 * vmax, "velocities: %.3g of the largest speed (tol 1e-8)", dv / vmax);
        const double del = fabs(e.elastic - e0.elastic), dr = fabs(e.kinetic_rot - e0.kinetic_rot);
        CHECK(del <= 1e-9 * e0.elastic, "stored energy %.17g vs %.17g (%.3g of it, tol 1e-9)", e.elastic, e0.elastic,
              del / e0.elastic);
        CHECK(dr <= 1e-8 * e0.kinetic_rot, "rotational kinetic energy %.17g vs %.17g (%.3g of it, tol 1e-8)",
              e.kinetic_rot, e0.kinetic_rot, dr / e0.kinetic_rot);
        /* the tether's own share of the initial stored energy: the sum k m |x - c|^2 / 2 over
         * the spheres at their start is what the provider books (the scene without it
         * stores only the contacts') */
        CHECK(e0.initial > 0 && e0.initial - ep.initial > 0.5 * e0.initial, "the tether's energy %.3g J is more than "
              "half of the initial %.3g J", e0.initial - ep.initial, e0.initial);
        const double dwb = fabs(e.work_boundary - e0.work_boundary);
        CHECK(e0.work_boundary > 0 && dwb <= 1e-9 * e0.work_boundary, "%s: the torque's work summed over the ranks %.17g "
              "vs %.17g (tol 1e-9 of it)", tag, e.work_boundary, e0.work_boundary);
        CHECK(e0.kinetic_rot > 2 * er.kinetic_rot, "%s: the torque matters: rotational energy %.3g J, %.3g J without it",
              tag, e0.kinetic_rot, er.kinetic_rot);
        printf("  %s: positions %.2e of the side, velocities %.2e of the largest speed, stored energy %.2e of it "
               "(%.3g J), rotation %.2e of it (%.3g J; %.3g J without the torque)\n", tag, dx / L, dv / vmax,
               del / e0.elastic, e0.elastic, dr / e0.kinetic_rot, e0.kinetic_rot, er.kinetic_rot);
    }
    free(xp); free(vp); free(x0); free(v0);
    floe_world_destroy(w);
}

/* part 1b: a FLOE_GROUP_PD provider on the points of a PMB block (6 x 6 x 6 points, soft,
 * free in space), the tether's centre at a corner of the block so that the points pull apart
 * unevenly and the bonds work; velocity Verlet, then the staggered PD-DEM scheme with two PD
 * sub-steps a step (the provider runs at the PD rate). The split run against the unsplit
 * one: positions within 1e-10 of the block's size, velocities within 1e-8 of the largest
 * speed, the stored energy (bonds and tether) within 1e-9. */
static const floe_provider_class pd_class = {.version = 2, .name = "tether_pd", .group = FLOE_GROUP_PD,
                                             .forces = tether_forces, .splits = FLOE_PROVIDER_PER_PARTICLE};
enum { NPD = 6 };
static const double PDX = 0.02;

static floe_world *build_pd(int staggered) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = 1e-3;
    if (staggered) { d.pd_dem = FLOE_PD_DEM_STAGGERED; d.pd_substeps = 2; }
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(1e3, 0, 0, 0, 0)); /* soft: the points' own pairs */
    floe_pd_region reg;
    memset(&reg, 0, sizeof reg);
    reg.dim = 3;
    reg.dx = PDX;
    reg.horizon_factor = 2;
    floe_v3_set(reg.hi, NPD * PDX, NPD * PDX, NPD * PDX);
    floe_pd_body *b = NULL;
    const double E = 100, nu = 0.25;
    floe_pd_material pm = floe_pd_material_pmb(1100, E / (3 * (1 - 2 * nu)), 0);
    int rc = floe_pd_body_create(&b, &reg);
    if (!rc) rc = floe_pd_set_material(b, &pm);
    const double v0[3] = {0.01, -0.02, 0.005};
    if (!rc) rc = floe_world_add_pd_body(w, b, 0, v0, NULL);
    CHECK(rc == FLOE_OK, "the PD block (%s)", floe_world_last_error(w));
    tether *t = new_tether(&pd_class);
    for (int k = 0; k < 3; k++) t->c[k] = 0; /* a corner of the block */
    t->k = 4;
    if (floe_world_add_provider(w, &t->base)) { free(t); CHECK(0, "add_provider: %s", floe_world_last_error(w)); }
    return w;
}

static void pd_split_matches(int staggered, int steps) {
    const char *tag = staggered ? "PD group, staggered (2 PD sub-steps)" : "PD group, velocity Verlet";
    const int n = NPD * NPD * NPD;
    double *x0 = NULL, *v0 = NULL;
    int N = 0;
    floe_energy e0 = {0};
    const double tq = torque_;
    torque_ = 0; /* the points do not turn */
    if (rank_ == 0) {
        floe_world *w = build_pd(staggered);
        const int src = mpi_test_serial_run(w, steps, &N, &x0, &v0, &e0);
        CHECK(src == 0, "%s serial: %s", tag, src ? floe_world_last_error(w) : "");
        floe_world_destroy(w);
    }
    floe_world *w = build_pd(staggered);
    double *xp, *vp;
    floe_energy e;
    const int rc = mpi_test_split_run(w, steps, n, &xp, &vp, &e);
    CHECK(rc == 0, "%s split run: %s", tag, rc ? floe_world_last_error(w) : "");
    if (rank_ == 0 && rc == 0 && x0) {
        double dx, dv, vmax;
        mpi_test_max_diffs(xp, x0, vp, v0, 0, 3 * n, &dx, &dv, &vmax);
        CHECK(N == n, "%s: point count %d (%d)", tag, N, n);
        CHECK(dx <= 1e-10 * NPD * PDX, "%s: positions %.3g of the block (tol 1e-10)", tag, dx / (NPD * PDX));
        CHECK(dv <= 1e-8 * vmax, "%s: velocities %.3g of the largest speed (tol 1e-8)", tag, dv / vmax);
        const double del = fabs(e.elastic - e0.elastic);
        CHECK(e0.elastic > 0 && del <= 1e-9 * e0.elastic, "%s: stored energy %.17g vs %.17g (tol 1e-9 of it)", tag,
              e.elastic, e0.elastic);
        printf("  %s: positions %.2e of the block, velocities %.2e of the largest speed, stored energy %.2e of it "
               "(%.3g J)\n", tag, dx / (NPD * PDX), dv / vmax, del / e0.elastic, e0.elastic);
    }
    torque_ = tq;
    free(xp); free(vp); free(x0); free(v0);
    floe_world_destroy(w);
}

/* part 2: providers that declare nothing: refused on every rank, named */
static void undeclared_refused(void) {
    const floe_provider_class *ks[2] = {&v1_class, &v2_none_class};
    for (int q = 0; q < 2; q++) {
        floe_world *w = build(ks[q], FLOE_VELOCITY_VERLET);
        int rc = floe_world_prepare(w);
        CHECK(rc == 0, "%s: prepare (%s)", ks[q]->name, rc ? floe_world_last_error(w) : "");
        rc = floe_world_parallel_init(w, NULL);
        const char *msg = floe_world_last_error(w);
        CHECK(rc == FLOE_ENOTSUP && strstr(msg, ks[q]->name) && strstr(msg, "FLOE_PROVIDER_PER_PARTICLE"),
              "%s: refused naming it and the declaration (rc %d: %s)", ks[q]->name, rc, msg);
        if (rank_ == 0 && q == 0) printf("  refused: %s\n", msg);
        floe_world_destroy(w);
    }
}

/* part 3: the classes floe_world_add_provider refuses */
static void bad_classes(void) {
    const floe_provider_class *ks[3] = {&bad_splits_class, &stateful_class, &excluding_class};
    const char *want[3] = {"splits must be", "a state", "excludes"};
    for (int q = 0; q < 3; q++) {
        floe_world *w = build(NULL, FLOE_VELOCITY_VERLET);
        tether *t = new_tether(ks[q]);
        const int rc = floe_world_add_provider(w, &t->base);
        const char *msg = floe_world_last_error(w);
        CHECK(rc == FLOE_EINVAL && strstr(msg, ks[q]->name) && strstr(msg, want[q]), "%s: refused (rc %d: %s)",
              ks[q]->name, rc, msg);
        CHECK(floe_world_prepare(w) == 0, "%s: the world prepares without it", ks[q]->name);
        free(t); /* refused: the caller keeps it */
        floe_world_destroy(w);
    }
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    split_matches(FLOE_VELOCITY_VERLET, STEPS, "velocity Verlet");
    split_matches(FLOE_RK2, STEPS / 2, "RK2");
    split_matches(FLOE_LEAPFROG, STEPS, "leapfrog");
    adaptive_ = 1; /* each rank's trials agreed: the accepted steps are the unsplit run's */
    split_matches(FLOE_VELOCITY_VERLET, STEPS / 2, "adaptive velocity Verlet");
    adaptive_ = 0;
    pd_split_matches(0, 500);
    pd_split_matches(1, 500);
    undeclared_refused();
    bad_classes();
    const int fails = mpi_test_failed("test_mpi_provider");
    MPI_Finalize();
    return fails ? 1 : 0;
}
