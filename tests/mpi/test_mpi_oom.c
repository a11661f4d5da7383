/* test_mpi_oom.c - out of memory on one rank of a split world, in the split, inside a
 * decomposition and inside a step (docs/parallel.md, "Errors inside a step"): every rank
 * returns, all with an error or all without, and an error is agreed
 * (floe_world_parallel_error_agreed, the same value on every rank: 2 on a split world, out
 * of memory leaving it not whole; 1 after a split that failed before its decomposition,
 * which leaves the world whole, and after the measured balance's scratch failed on a split
 * world, variant 0) with the same code and message on every rank. Before, a
 * rank that failed alone left the others waiting in the next collective: the run never ended.
 *
 * This executable wraps floe's allocations (-Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,
 * tests/CMakeLists.txt; libfloe is static, so its calls go through the wrappers; MPI's,
 * Zoltan's and libc's own do not). Six worlds: 216 spheres settling in a walled box
 * (Hertz-Mindlin, velocity Verlet, one thread); the same with every third one an ellipsoid
 * under RK2; the spheres with beam bonds between neighbours; the spheres and a PD block under
 * the staggered PD-DEM scheme, with PD sub-steps, and with PD every 2nd step and a growing
 * radius; the spheres under adaptive steps (session 27). For each world, each rank v and
 * k = 0, 1, 2, ...: every rank builds and prepares the world; then on rank v the k-th
 * allocation of floe from a point on fails (once), while every rank splits the world, takes
 * WARM steps, decomposes again (floe_world_parallel_rebuild: the sequence of a step's
 * decomposition) and takes NSTEP steps (their forces, exchanges and closes). The point is
 * after the WARM steps (warm: the buffers of a step sized), then before the split (cold: the
 * split and the first steps, which size them). The sweep over k ends when the k-th
 * allocation is never reached. An alarm of 60 s stops a rank that waits forever (the test
 * then fails). Under one rank: the same sweeps without a split (a step of velocity Verlet in
 * a steady state allocates nothing, RK2 twice). */
#include "floe.h"
#include "floe_pd.h"
#include "../check.h"
#include "mpi_common.h"
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void *__real_malloc(size_t n);
void *__real_calloc(size_t a, size_t b);
void *__real_realloc(void *p, size_t n);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t a, size_t b);
void *__wrap_realloc(void *p, size_t n);

static long armed = -1; /* allocations left before the one that fails; -1: none fails */
static int fired;
static int fail_now(void) {
    if (armed < 0) return 0;
    if (armed-- > 0) return 0;
    fired = 1;
    return 1;
}
void *__wrap_malloc(size_t n) { return fail_now() ? NULL : __real_malloc(n); }
void *__wrap_calloc(size_t a, size_t b) { return fail_now() ? NULL : __real_calloc(a, b); }
void *__wrap_realloc(void *p, size_t n) { return fail_now() ? NULL : __real_realloc(p, n); }

enum { NX = 6, NY = 6, NZ = 6, WARM = 20, NSTEP = 3 };
static const double R = 0.001, SP = 0.0022, DT = 2.5e-6;

/* variant 0: spheres, velocity Verlet; 1: every third one an ellipsoid, RK2 (its rows travel
 * through the decomposition); 2: spheres with beam bonds between neighbours, velocity Verlet;
 * 3: the spheres and a PD block above them under the staggered scheme (2 PD sub-steps a
 * step; its rows travel too); 4: the same with the PD forces every 2nd step and a growing
 * radius (a state object: the states' agreement, the growth's masses); 5: the spheres under
 * adaptive steps (the snapshot's allocations: reached from the split, sized before the warm
 * sweep; no trial is redone in these few steps) */
enum { NVARIANT = 6 };
static floe_world *build(int variant) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = DT;
    d.gravity[2] = -9.81;
    if (variant == 1) d.integrator = FLOE_RK2;
    if (variant == 5) {
        d.adaptive = 1;
        d.dt_max = DT;
    }
    if (variant == 3 || variant == 4) {
        d.pd_dem = FLOE_PD_DEM_STAGGERED;
        d.pd_substeps = variant == 3 ? 2 : 1;
        d.pd_every = variant == 3 ? 1 : 2;
    }
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    const int g = floe_world_add_geometry(w, floe_sphere_create(R));
    const int ge = floe_world_add_geometry(w, floe_ellipsoid_create(R, 0.8 * R, 0.7 * R));
    int cnt = 0;
    mpi_test_box_walls(w, NX * SP + 0.0008, NY * SP + 0.0008, 0.03, 0, 6);
    unsigned s = 99;
    for (int c = 0; c < NZ; c++)
        for (int b = 0; b < NY; b++)
            for (int a = 0; a < NX; a++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = variant == 1 && cnt++ % 3 == 2 ? ge : g;
                double j[5];
                for (int k = 0; k < 5; k++) { s = s * 1103515245u + 12345u; j[k] = (s >> 8) / 16777216.0 - 0.5; }
                floe_v3_set(p.x, 0.0004 + (a + 0.5) * SP + 0.1 * j[0] * (SP - 2 * R),
                            0.0004 + (b + 0.5) * SP + 0.1 * j[1] * (SP - 2 * R), 0.0012 + (c + 0.5) * SP);
                floe_v3_set(p.v, 0.3 * j[2], 0.3 * j[3], 0.3 * j[4]);
                floe_world_add_particle(w, &p);
            }
    if (variant == 2) {
        floe_beam_params bp = floe_default_beam_params();
        bp.young = 1e7;
        bp.max_distance = 2.3 * R;
        floe_world_add_beam_bonds(w, 1.2, &bp);
    }
    if (variant == 3 || variant == 4) { /* 4 x 4 x 2 points 2 mm apart, soft (PD step 1e-4 s), above the spheres */
        floe_pd_region reg;
        memset(&reg, 0, sizeof reg);
        reg.dim = 3;
        reg.dx = 0.002;
        reg.horizon_factor = 2;
        floe_v3_set(reg.lo, 0.003, 0.003, 0.018);
        floe_v3_set(reg.hi, 0.011, 0.011, 0.022);
        floe_pd_body *b = NULL;
        const double E = 1e6, nu = 0.25;
        floe_pd_material pm = floe_pd_material_pmb(2500, E / (3 * (1 - 2 * nu)), 0);
        int rc = floe_pd_body_create(&b, &reg);
        if (!rc) rc = floe_pd_set_material(b, &pm);
        if (!rc) rc = floe_world_add_pd_body(w, b, 0, NULL, NULL);
        CHECK(rc == FLOE_OK, "the PD block: %s", floe_world_last_error(w));
    }
    if (variant == 4) {
        floe_state *st = floe_growing_radius_create(w, 7, 0.01, 1);
        CHECK(st && floe_world_add_state(w, st) == FLOE_OK, "the growing radius: %s", floe_world_last_error(w));
    }
    floe_world_set_threads(w, 1); /* the wrappers count on one thread */
    return w;
}

static int cur_v;
static long cur_k;
static void on_alarm(int sig) {
    (void)sig;
    char msg[160];
    int n = snprintf(msg, sizeof msg, "test_mpi_oom: rank %d waited 60 s after allocation %ld of rank %d failed: "
                     "the ranks did not agree on the failure\n", rank_, cur_k, cur_v);
    ssize_t r = write(2, msg, n > 0 ? (size_t)n : 0);
    (void)r;
    _exit(3);
}

/* one armed sequence: k-th allocation on rank v fails. Returns 1 when it was reached
 * somewhere (the sweep goes on), 0 when no rank reached it */
static int balance_failures; /* trials whose failure was the balance's scratch */
static int trial(int variant, int warm, int v, long k, int *errors) {
    floe_world *w = build(variant);
    const int n_all = floe_world_particle_count(w);
    int rc = floe_world_prepare(w);
    CHECK(rc == FLOE_OK, "rank %d: the set-up failed: %s", rank_, floe_world_last_error(w));
    if (rc) { floe_world_destroy(w); return 0; }
    fired = 0;
    cur_v = v;
    cur_k = k;
    alarm(60);
    if (!warm) armed = rank_ == v ? k : -1; /* cold: from the split on */
    if (size_ > 1) rc = floe_world_parallel_init(w, NULL);
    /* the balance's scratch (agreed: an out-of-memory there leaves every rank in its mode,
     * the world whole; the weights' mode keeps the cuts independent of timings) */
    int rb = 0;
    if (!rc && size_ > 1 && variant == 0) rc = rb = floe_world_parallel_set_balance(w, FLOE_BALANCE_WEIGHTS);
    if (rb) balance_failures++;
    for (int s = 0; !rc && s < warm; s++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK || !warm, "rank %d: the set-up failed: %s", rank_, floe_world_last_error(w));
    if (warm) armed = rank_ == v ? k : -1;
    if (!rc) rc = floe_world_parallel_rebuild(w);
    for (int s = 0; !rc && s < NSTEP; s++) rc = floe_world_step(w);
    armed = -1;
    alarm(0);
    /* every rank here: all failed or none, an error agreed with a message */
    const int bad = rc != FLOE_OK;
    int lo = bad, hi = bad, any_fired = fired;
    MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &any_fired, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    CHECK(lo == hi, "rank %d: allocation %ld of rank %d failed: this rank returned %d (%s), another %s", rank_, k, v,
          rc, bad ? floe_world_last_error(w) : "", bad ? "none" : "an error");
    /* (every rank reduces: the ranks may disagree on bad) the agreement's value, the code and
     * a checksum of the message, each the same on every rank */
    const int ag = bad ? floe_world_parallel_error_agreed(w) : 0;
    unsigned long sum = 5381;
    for (const char *c = bad ? floe_world_last_error(w) : ""; *c; c++) sum = sum * 33 + (unsigned char)*c;
    long v3[3] = {ag, rc, (long)(sum & 0x7fffffffL)}, v3lo[3], v3hi[3];
    MPI_Allreduce(v3, v3lo, 3, MPI_LONG, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(v3, v3hi, 3, MPI_LONG, MPI_MAX, MPI_COMM_WORLD);
    const long ag_lo = v3lo[0], ag_hi = v3hi[0];
    CHECK(v3lo[1] == v3hi[1] && v3lo[2] == v3hi[2], "rank %d: allocation %ld of rank %d: the ranks returned "
          "different errors (codes %ld to %ld; this one: %s)", rank_, k, v, v3lo[1], v3hi[1],
          bad ? floe_world_last_error(w) : "none");
    if (bad) {
        /* every failure here is out of memory: on a split world the state is not whole (2); a
         * split that failed before its decomposition leaves the world unsplit and whole (1) */
        int wr, ws;
        floe_world_parallel_rank(w, &wr, &ws);
        CHECK(ag == (ws > 1 && !rb ? 2 : 1) && (ws > 1 || floe_world_particle_count(w) == n_all),
              "rank %d: allocation %ld of rank %d: agreed %d on a world of %d rank(s) and %d particles (%d whole): %s",
              rank_, k, v, ag, ws, floe_world_particle_count(w), n_all, floe_world_last_error(w));
        CHECK(ag && ag_lo == ag_hi, "rank %d: allocation %ld of rank %d: error not agreed (%d; %ld to %ld over the "
              "ranks): %s", rank_, k, v, ag, ag_lo, ag_hi, floe_world_last_error(w));
        CHECK(floe_world_last_error(w)[0] != 0, "rank %d: allocation %ld of rank %d: an error without a message",
              rank_, k, v);
        ++*errors;
    }
    CHECK(any_fired || !bad, "rank %d: an error without a failed allocation: %s", rank_, floe_world_last_error(w));
    floe_world_destroy(w);
    return any_fired;
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    signal(SIGALRM, on_alarm);
    for (int cold = 0; cold < 2; cold++)
    for (int variant = 0; variant < NVARIANT; variant++)
        for (int v = 0; v < size_; v++) {
            int errors = 0;
            long k = 0;
            while (trial(variant, cold ? 0 : WARM, v, k, &errors) && k < 5000) k++;
            if (rank_ == 0)
                printf("world %d, %s: rank %d out of memory at each of its %ld allocations: %d errors, every one on "
                       "every rank\n", variant, cold ? "from the split" : "warm", v, k, errors);
            if (size_ > 1) {
                CHECK(k > 10 && k < 5000, "world %d, rank %d: %ld allocations in the armed sequence", variant, v, k);
                CHECK(errors > 0, "world %d, rank %d: no allocation failure gave an error", variant, v);
            }
        }
    /* the balance's scratch failed on each rank in turn (world 0, from the split: three
     * allocations each), every time agreed */
    if (size_ > 1) CHECK(balance_failures >= size_, "the balance's scratch failed in %d trials (expected %d or more)",
                         balance_failures, size_);
    if (rank_ == 0) printf("the balance's scratch failed in %d trials, each agreed\n", balance_failures);
    const int fails = mpi_test_failed("test_mpi_oom");
    MPI_Finalize();
    return fails ? 1 : 0;
}
