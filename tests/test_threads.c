/* test_threads.c - threads give the same bits as one thread (issue 14, docs/parallel.md).
 * The same world is built and stepped with 1, 2, 3 and 4 threads (the grain lowered so that
 * every loop with more than 64 items runs threaded), and every particle's position, velocity,
 * orientation, angular momentum, force and torque, the energy ledger, the contact count, the
 * neighbour-list rebuilds and the detection statistics must be equal to the last bit
 * (memcmp, tolerance 0):
 *   A. 1,200 spheres of three radii and 60 boxes (the polytope LP, warm starts) settling in
 *      a walled box under gravity, Hertz-Mindlin with friction, 400 steps; in A-C and E a
 *      body-force callback declared thread-safe (a drag and a push) as well, called from several threads
 *      (checked), its work in the ledger;
 *   B. the same spheres only (the sphere path), leapfrog, 400 steps;
 *   C. A again with the particle loops' parts (floe_loop_split: the drift's and the kick's
 *      blocks per thread, cut by measured speed) moved to a random cut after every step, and
 *      the contact stage's parts cut by random block times (its list has two blocks: two
 *      parts here, more in E);
 *   D. B's lattice with 6,000 spheres (a list of several blocks) under a user law that wraps
 *      Hertz-Mindlin and fails for every contact deeper than 5 % of the deepest that a run
 *      without failures reaches in 100 steps: the step that fails, its code and its message
 *      (the first failing contact in list order, as one thread meets it) the same on 2-4
 *      threads, with failures in several threads' parts at once (the lowest block's error
 *      wins; no thread gathers the shared particles' forces after a failure). Taking the
 *      highest failed block's error instead fails it.
 *   E. A's spheres without the boxes, 6,000 of them (a dozen blocks: the contact stage in 3
 *      and 4 parts), the parts cut at random as in C (some of one block), 120 steps.
 * A body-force callback set by floe_world_set_body_force (not declared thread-safe) is called
 * on one thread, in particle order, on 2 threads too.
 * And floe_loop_split itself: even at first; a thread at twice the seconds per block gets
 * a third of the blocks; a measure within 5 % keeps the cut; a new block count cuts evenly
 * again; every part keeps at least one block.
 * Built without OpenMP, the test checks that a request for 2 threads is refused and skips. */
#include "check.h"
#include "floe.h"
#include "world_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

static double urand(unsigned long long *s) {
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* A-C's body-force callback: a drag on the velocity and the spin, and a push that depends
 * on the position (its work booked by the ledger per block of particles in block order).
 * It marks the threads that call it (the threaded path runs it on several at once). */
static unsigned cb_threads;
static void swirl_force(const floe_world *w, int i, double t, double f[3], double torque[3], void *user) {
    (void)t;
    (void)user;
    floe_particle_state s;
    floe_world_get_particle(w, i, &s);
    for (int a = 0; a < 3; a++) {
        f[a] = -0.5 * s.mass * s.v[a];
        torque[a] = -1e-9 * s.w[a];
    }
    f[0] += 2e-3 * s.mass * sin(400.0 * s.x[1]);
#ifdef _OPENMP
    const unsigned bit = 1u << (omp_get_thread_num() & 31);
    if (!(__atomic_load_n(&cb_threads, __ATOMIC_RELAXED) & bit)) __atomic_fetch_or(&cb_threads, bit, __ATOMIC_RELAXED);
#endif
}

static floe_world *build_n(int boxes, int leapfrog, int ns) {
    floe_world_def def = floe_default_world_def();
    def.gravity[2] = -9.81;
    if (leapfrog) def.integrator = FLOE_LEAPFROG;
    char err[512];
    floe_world *w = floe_world_create(&def, err, sizeof err);
    if (!w) return NULL;
    floe_material m = {"grain", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5));
    const double L = 0.0305, H = 0.08;
    const double pts[5][3] = {{0, 0, 0}, {0, 0, 0}, {L, 0, 0}, {0, 0, 0}, {0, L, 0}};
    const double nrm[5][3] = {{0, 0, 1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
    for (int k = 0; k < 5; k++) floe_world_add_wall(w, pts[k], nrm[k], 0, FLOE_FIXED);
    int gs[3], gb = floe_world_add_geometry(w, floe_box_create(0.0016, 0.0012, 0.001));
    for (int k = 0; k < 3; k++) gs[k] = floe_world_add_geometry(w, floe_sphere_create(0.0005 + 0.0001 * k));
    unsigned long long seed = 12345;
    const int nb = boxes ? 60 : 0;
    /* a loose lattice with jitter, random velocities */
    int placed = 0;
    for (int c = 0; placed < ns + nb; c++) {
        const int nx = 22, ny = 22;
        const double a = 0.00135;
        int ix = c % nx, iy = (c / nx) % ny, iz = c / (nx * ny);
        floe_particle_def p = floe_default_particle_def();
        p.geometry = placed < nb ? gb : gs[placed % 3];
        if (placed < nb) { ix = placed % 12; iy = placed / 12; iz = 0; }
        const double ab = placed < nb ? 0.0019 : a; /* boxes: 1.9 mm apart, bounding radius 1.2 mm */
        p.x[0] = 0.0012 + ab * ix + 0.0002 * urand(&seed);
        p.x[1] = 0.0012 + ab * iy + 0.0002 * urand(&seed);
        p.x[2] = 0.0012 + a * iz + (placed < nb ? 0.0 : 0.004);
        for (int k = 0; k < 3; k++) p.v[k] = 1.0 * (urand(&seed) - 0.5);
        if (placed < nb) {
            double th = 6.28 * urand(&seed);
            p.q[0] = cos(th / 2); p.q[1] = sin(th / 2) * 0.6; p.q[2] = sin(th / 2) * 0.8; p.q[3] = 0;
        }
        if (floe_world_add_particle(w, &p) < 0) { floe_world_destroy(w); return NULL; }
        placed++;
    }
    (void)H;
    w->par_grain = 64;
    return w;
}

static int run_spheres = 1200; /* the spheres of run()'s worlds (E: more) */
static floe_world *build(int boxes, int leapfrog) { return build_n(boxes, leapfrog, run_spheres); }

typedef struct run_out {
    double *state; size_t nstate;
    floe_energy e;
    int ncontacts; long rebuilds;
    floe_detect_stats ds;
    int threaded;
    int *list; int npairs; /* the neighbour list's entries (i, j, piece pair) at the end */
    int nl_threads;        /* the threads of its last build's search */
    int cb_threads;        /* the threads that called the body-force callback */
} run_out;

static int run(int boxes, int leapfrog, int threads, int steps, run_out *o, int skew) {
    floe_world *w = build(boxes, leapfrog);
    if (!w) return 1;
    cb_threads = 0;
    if (floe_world_set_body_force_threaded(w, swirl_force, NULL) || floe_world_set_threads(w, threads) ||
        floe_world_prepare(w)) {
        fprintf(stderr, "%s\n", floe_world_last_error(w));
        floe_world_destroy(w);
        return 1;
    }
    if (threads == 1) printf("dt %g s\n", floe_world_dt(w));
    unsigned long long seed = 99;
    for (int s = 0; s < steps; s++) {
        if (floe_world_step(w)) {
            fprintf(stderr, "step %d: %s\n", s, floe_world_last_error(w));
            floe_world_destroy(w);
            return 1;
        }
        floe_loop_split *ls = &w->ls;
        if (skew && ls->nt > 1 && ls->nb >= ls->nt) /* any increasing cut, a block at least each */
            for (int t = 1; t < ls->nt; t++) {
                const int lo = ls->cut[t - 1] + 1, hi = ls->nb - (ls->nt - t);
                ls->cut[t] = lo + (int)(urand(&seed) * (hi - lo + 1));
            }
        floe_par_scratch *ps = w->thr;
        if (skew && ps && ps->bt_nb > 0) {
            /* the contact stage's parts cut again at the next evaluation by random block times
             * (u^4: some parts of one block among long ones) */
            for (int b = 0; b < ps->bt_nb; b++) {
                const double u = urand(&seed);
                ps->bt[b] = 1e-6 * u * u * u * u + 1e-12;
            }
            ps->recut = 1;
        }
    }
    const floe_particles *p = &w->p;
    const size_t n = (size_t)p->n;
    o->nstate = n * (3 + 3 + 4 + 3 + 3 + 3 + 3);
    o->state = malloc(o->nstate * sizeof(double));
    double *d = o->state;
    memcpy(d, p->x, 3 * n * sizeof(double)); d += 3 * n;
    memcpy(d, p->v, 3 * n * sizeof(double)); d += 3 * n;
    memcpy(d, p->q, 4 * n * sizeof(double)); d += 4 * n;
    memcpy(d, p->L, 3 * n * sizeof(double)); d += 3 * n;
    memcpy(d, p->w, 3 * n * sizeof(double)); d += 3 * n;
    memcpy(d, p->f, 3 * n * sizeof(double)); d += 3 * n;
    memcpy(d, p->t, 3 * n * sizeof(double));
    o->e = floe_world_energy(w);
    o->ncontacts = floe_world_contact_count(w);
    floe_neighbor_stats ns;
    floe_world_neighbor_stats(w, &ns);
    o->rebuilds = ns.rebuilds;
    floe_world_detect_stats(w, &o->ds);
    o->threaded = w->thr != NULL;
    o->cb_threads = __builtin_popcount(cb_threads);
    o->npairs = w->nl.npairs;
    o->nl_threads = w->nl.threads;
    o->list = malloc((size_t)(o->npairs ? o->npairs : 1) * 3 * sizeof(int));
    for (int k = 0; k < o->npairs; k++) {
        o->list[3 * k] = w->nl.pi[k];
        o->list[3 * k + 1] = w->nl.pj[k];
        o->list[3 * k + 2] = w->nl.sub[k];
    }
    floe_world_destroy(w);
    return 0;
}

/* A callback set by floe_world_set_body_force (not declared thread-safe) on 2 threads: every
 * call outside a parallel region, each evaluation's calls in particle order (one sequence of
 * the free particles per evaluation) */
static long plain_calls, plain_par, plain_drops;
static int plain_last = -1;
static void plain_force(const floe_world *w, int i, double t, double f[3], double torque[3], void *user) {
    (void)w; (void)t; (void)torque; (void)user;
    plain_calls++;
#ifdef _OPENMP
    plain_par += omp_in_parallel() != 0;
#endif
    plain_drops += i <= plain_last;
    plain_last = i;
    f[2] -= 1e-9;
}

static __attribute__((unused)) void check_plain_body_force(void) {
    floe_world *w = build(0, 0);
    int ok = w && !floe_world_set_body_force(w, plain_force, NULL) && !floe_world_set_threads(w, 2) &&
             !floe_world_prepare(w);
    for (int s = 0; ok && s < 20; s++) ok = !floe_world_step(w);
    const long nfree = 1200; /* the spheres; the walls are fixed */
    CHECK(ok && plain_calls > 0 && plain_calls % nfree == 0 && plain_par == 0 && plain_drops == plain_calls / nfree - 1,
          "a plain body force on 2 threads: %ld calls, %ld inside a parallel region, %ld sequences of the %ld free "
          "particles in order (%ld restarts)", plain_calls, plain_par, plain_calls / nfree, nfree, plain_drops);
    floe_world_destroy(w);
}

/* floe_loop_split's cuts (unused without OpenMP) */
static __attribute__((unused)) void check_loop_split(void) {
    floe_world *w = build(0, 0);
    const int *c = floe_loop_split_cuts(w, 2, 40);
    CHECK(c && c[0] == 0 && c[1] == 20 && c[2] == 40, "loop split: even at first (%d)", c ? c[1] : -1);
    w->ls.sec[0] = 20e-6;
    w->ls.sec[1] = 40e-6; /* thread 1 at twice the seconds per block */
    floe_loop_split_update(w);
    CHECK(w->ls.cut[1] == 27, "loop split: the slower thread's part is its speed's share, 13 of 40 (cut %d)", w->ls.cut[1]);
    w->ls.sec[0] = 27e-6;
    w->ls.sec[1] = 26e-6; /* now within 5 %: kept */
    floe_loop_split_update(w);
    CHECK(w->ls.cut[1] == 27, "loop split: a balanced measure keeps the cut (%d)", w->ls.cut[1]);
    c = floe_loop_split_cuts(w, 2, 50);
    CHECK(c && c[1] == 25, "loop split: a new block count cuts evenly again (%d)", c ? c[1] : -1);
    c = floe_loop_split_cuts(w, 4, 4);
    const double sec[4] = {1e-6, 1e-6, 1e-6, 1e-4};
    memcpy(w->ls.sec, sec, sizeof sec);
    floe_loop_split_update(w);
    int ok = c && w->ls.cut[0] == 0 && w->ls.cut[4] == 4;
    for (int t = 0; t < 4; t++) ok &= w->ls.cut[t + 1] == w->ls.cut[t] + 1;
    CHECK(ok, "loop split: every part keeps a block (4 parts of 4 blocks, one part 100x slower)");
    floe_world_destroy(w);
}

/* D: a law that fails for contacts deeper than fail_depth, else Hertz-Mindlin's force; with
 * fail_depth infinite it records the deepest contact of a one-thread run (max_depth) */
static floe_contact_law *hm_inner;
static double fail_depth = INFINITY, max_depth;
static int armed; /* 0 during the prepare's evaluation (the lattice's first overlaps) */
static long fails_seen; /* failing calls (several threads: counted, not compared) */
static int failing_force(const floe_contact_law *law, const floe_contact *c, double *hist, floe_contact_result *out) {
    (void)law;
    if (armed && c->depth > fail_depth) {
        __atomic_add_fetch(&fails_seen, 1, __ATOMIC_RELAXED);
        return FLOE_EINVAL;
    }
    if (armed && isinf(fail_depth) && c->depth > max_depth) max_depth = c->depth; /* (one thread) */
    return hm_inner->klass->force(hm_inner, c, hist, out);
}
static void failing_stiffness(const floe_contact_law *law, double r, double m, double d, double *kn, double *cn) {
    (void)law;
    hm_inner->klass->stiffness(hm_inner, r, m, d, kn, cn);
}
static void failing_tstiffness(const floe_contact_law *law, double r, double m, double d, double *kt, double *ct) {
    (void)law;
    hm_inner->klass->tangential_stiffness(hm_inner, r, m, d, kt, ct);
}
static void failing_destroy(floe_contact_law *law) { free(law); }
static floe_contact_law_class failing_class = {1, "failing", 0, failing_force, failing_stiffness, failing_destroy,
                                               failing_tstiffness, NULL};

/* D's world (6,000 spheres, leapfrog) under the failing law on `threads` threads, stepped
 * until a step fails (at most `steps`): the failed step (-1: none; -2: the setup failed; -3:
 * the contact stage never ran threaded), its code and message */
static __attribute__((unused)) int run_failing(int threads, int steps, char *msg, size_t cap, int *code) {
    floe_world *w = build_n(0, 1, 6000); /* a list of several blocks from the first step */
    floe_contact_law *fl = malloc(sizeof *fl);
    fl->klass = &failing_class;
    fl->friction = hm_inner->friction;
    failing_class.history_size = hm_inner->klass->history_size;
    floe_world_set_law(w, 0, 0, fl);
    int at = -1;
    *code = 0;
    msg[0] = 0;
    armed = 0;
    if (floe_world_set_threads(w, threads) || floe_world_prepare(w)) {
        snprintf(msg, cap, "setup: %s", floe_world_last_error(w));
        *code = -1;
        floe_world_destroy(w);
        return -2;
    }
    armed = 1;
    for (int s = 0; s < steps && at < 0; s++) {
        const int rc = floe_world_step(w);
        if (rc) {
            at = s;
            *code = rc;
            snprintf(msg, cap, "%s", floe_world_last_error(w));
        }
    }
    if (threads > 1 && !w->thr) at = -3; /* the contact stage never ran threaded: the case tests nothing */
    floe_world_destroy(w);
    return at;
}

static __attribute__((unused)) void check_failure(void) {
    floe_material m = {"grain", 2500, 1e7, 0.3};
    hm_inner = floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5);
    char ref[1024], msg[1024];
    int code_ref, code;
    fail_depth = INFINITY;
    max_depth = 0;
    const int steps = 100;
    CHECK(run_failing(1, steps, ref, sizeof ref, &code_ref) == -1, "D: without a failure the %d steps run (%s)", steps, ref);
    CHECK(max_depth > 0, "D: contacts were made (deepest %.3e m)", max_depth);
    fail_depth = 0.05 * max_depth; /* many contacts go deeper at once: several parts fail */
    fails_seen = 0;
    const int at = run_failing(1, steps, ref, sizeof ref, &code_ref);
    CHECK(at >= 0 && code_ref != 0, "D: one thread: the step fails (at step %d, code %d: %s)", at, code_ref, ref);
    CHECK(fails_seen == 1, "D: one thread stops at the first failing contact (%ld failing calls)", fails_seen);
    long most = 0;
    for (int t = 2; t <= 4; t++) {
        fails_seen = 0;
        const int at_t = run_failing(t, steps, msg, sizeof msg, &code);
        if (fails_seen > most) most = fails_seen;
        CHECK(at_t == at && code == code_ref && !strcmp(msg, ref),
              "D: %d threads: fails at step %d with code %d and \"%s\" (one thread: step %d, code %d, \"%s\")", t,
              at_t, code, msg, at, code_ref, ref);
    }
    CHECK(most >= 2, "D: on some thread count more than one part met a failing contact (%ld failing calls at most)", most);
    printf("D: a failing law: step %d, \"%s\"; the same on 2-4 threads (failing calls at most %ld)\n", at, ref, most);
    floe_contact_law_destroy(hm_inner);
}

/* unused without OpenMP (main skips) */
static __attribute__((unused)) void compare(const char *what, int boxes, int leapfrog, int steps, int skew) {
    run_out ref, o;
    memset(&ref, 0, sizeof ref);
    CHECK(run(boxes, leapfrog, 1, steps, &ref, 0) == 0, "%s: one thread runs", what);
    CHECK(ref.ncontacts > 200, "%s: a dense packing (%d contacts)", what, ref.ncontacts);
    CHECK(!ref.threaded, "%s: one thread keeps the serial path", what);
    for (int t = 2; t <= 4; t++) {
        memset(&o, 0, sizeof o);
        CHECK(run(boxes, leapfrog, t, steps, &o, skew) == 0, "%s: %d threads run", what, t);
        CHECK(o.threaded, "%s: %d threads took the threaded path", what, t);
        CHECK(o.cb_threads > 1, "%s: %d threads: the body-force callback ran on %d of them", what, t, o.cb_threads);
        CHECK(o.nstate == ref.nstate && !memcmp(o.state, ref.state, ref.nstate * sizeof(double)),
              "%s: %d threads: positions, velocities, orientations, momenta, forces, torques bit-identical", what, t);
        CHECK(!memcmp(&o.e, &ref.e, sizeof o.e), "%s: %d threads: energy ledger bit-identical (dissipated %.17g vs %.17g)",
              what, t, o.e.dissipated, ref.e.dissipated);
        CHECK(o.ncontacts == ref.ncontacts && o.rebuilds == ref.rebuilds, "%s: %d threads: contacts %d/%d, rebuilds %ld/%ld",
              what, t, o.ncontacts, ref.ncontacts, o.rebuilds, ref.rebuilds);
        CHECK(!memcmp(&o.ds, &ref.ds, sizeof o.ds), "%s: %d threads: detection statistics equal (evaluations %ld/%ld)", what, t,
              o.ds.evaluations, ref.ds.evaluations);
        CHECK(o.nl_threads == t, "%s: the list searched on %d threads (%d)", what, t, o.nl_threads);
        CHECK(o.npairs == ref.npairs && !memcmp(o.list, ref.list, (size_t)ref.npairs * 3 * sizeof(int)),
              "%s: %d threads: the neighbour list entry for entry (%d/%d entries)", what, t, o.npairs, ref.npairs);
        free(o.state);
        free(o.list);
    }
    printf("%s: %d contacts after %d steps, dissipated %.6e J, body-force work %.6e J, LP evaluations %ld: same bits "
           "for 1-4 threads\n", what, ref.ncontacts, steps, ref.e.dissipated, ref.e.work_body, ref.ds.evaluations);
    free(ref.state);
    free(ref.list);
}

int main(void) {
#ifndef _OPENMP
    floe_world *w = build(0, 0);
    CHECK(w && floe_world_set_threads(w, 2) == FLOE_ENOTSUP, "without OpenMP 2 threads are refused");
    floe_world_destroy(w);
    printf("built without OpenMP: skipped\n");
    return check_fail_ ? 1 : 77;
#else
    compare("spheres and boxes, velocity Verlet", 1, 0, 400, 0);
    compare("spheres, leapfrog", 0, 1, 400, 0);
    compare("spheres and boxes, the particle loops' parts moved at every step", 1, 0, 400, 1);
    run_spheres = 6000; /* a list of a dozen blocks: 3 and 4 parts in the contact stage */
    compare("6,000 spheres, the contact stage's parts cut at random", 0, 0, 120, 1);
    run_spheres = 1200;
    check_loop_split();
    check_plain_body_force();
    check_failure();
    return check_summary("test_threads");
#endif
}
