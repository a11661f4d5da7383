/* test_mpi_decomp.c - the MPI decomposition itself (core/parallel, docs/parallel.md), run
 * under mpirun with 1, 2 and 4 ranks (tests/CMakeLists.txt): every rank builds the same
 * world of spheres of two sizes, ellipsoids and boxes in a walled box, splits it, and checks
 *   - the partition: every bounded particle owned by exactly one rank, walls on every rank;
 *   - migration keeps every particle's data: each local particle (owned or ghost) equals,
 *     field by field and bit for bit, the particle of the same global id in an unsplit copy
 *     (a ghost's motion excepted: FLOE_FIXED by design);
 *   - the ghosts are exactly those a brute-force search finds (bounding radius + the largest
 *     bounding radius of the rank + skin from the box of the rank's owned centres), and every
 *     particle within reach (r_i + r_j + skin) of an owned one is present;
 *   - the neighbour lists of the ranks together hold every pair of the unsplit list exactly
 *     once (same global ids, walls included);
 *   - after a shift of every particle (many change owner) and a new decomposition,
 *     the same four checks, with particles migrated;
 *   - the forward refresh gives each ghost its owner's values, the reverse sum gives each
 *     owner exactly its ghosts' forces. */
#include "floe.h"
#include "world_internal.h"
#include "par_internal.h"
#include "../check.h"
#include "mpi_common.h"
#include <stdlib.h>
#include <string.h>

static const double L = 0.02; /* box side, m */

/* n_side^3 particles on a jittered lattice: spheres of 0.4 and 0.6 mm, ellipsoids, boxes;
 * 6 walls, three of them added first, three last (walls anywhere in the store) */
static floe_world *build(int n_side) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = 1e-6;
    d.gravity[2] = -9.81;
    d.energy_check = FLOE_CHECK_OFF;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = mpi_test_glass(1e7);
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.3));
    int g[4];
    g[0] = floe_world_add_geometry(w, floe_sphere_create(0.0004));
    g[1] = floe_world_add_geometry(w, floe_sphere_create(0.0006));
    g[2] = floe_world_add_geometry(w, floe_ellipsoid_create(0.0006, 0.0004, 0.0003));
    g[3] = floe_world_add_geometry(w, floe_box_create(0.0008, 0.0006, 0.0005));
    mpi_test_box_walls(w, L, L, L, 0, 3);
    unsigned s = 777;
    const double h = L / n_side;
    int cnt = 0;
    for (int a = 0; a < n_side; a++)
        for (int b = 0; b < n_side; b++)
            for (int c = 0; c < n_side; c++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g[cnt++ % 4];
                p.material = 0;
                double j[6];
                for (int k = 0; k < 6; k++) { s = s * 1103515245u + 12345u; j[k] = (s >> 8) / 16777216.0 - 0.5; }
                floe_v3_set(p.x, (a + 0.5 + 0.15 * j[0]) * h, (b + 0.5 + 0.15 * j[1]) * h, (c + 0.5 + 0.15 * j[2]) * h);
                floe_v3_set(p.v, 0.1 * j[3], 0.1 * j[4], 0.1 * j[5]);
                p.q[0] = 1; p.q[1] = j[0]; p.q[2] = j[1]; p.q[3] = j[2];
                floe_world_add_particle(w, &p);
            }
    mpi_test_box_walls(w, L, L, L, 3, 6);
    w->nl.skin = 0.0006; /* wide: many ghosts */
    if (floe_world_prepare(w)) { fprintf(stderr, "prepare: %s\n", floe_world_last_error(w)); exit(2); }
    return w;
}

static int cmp_ll(const void *a, const void *b) {
    const long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

/* the bounded-bounded and wall pairs of a list as sorted keys gid_a * N + gid_b */
static long long *pair_keys(const floe_world *w, const long long *gid, int N, int *np) {
    const floe_neighbor_list *nl = &w->nl;
    long long *k = malloc((size_t)(nl->npairs ? nl->npairs : 1) * sizeof *k);
    for (int a = 0; a < nl->npairs; a++) {
        long long gi = gid ? gid[nl->pi[a]] : nl->pi[a], gj = gid ? gid[nl->pj[a]] : nl->pj[a];
        if (gi > gj) { long long t = gi; gi = gj; gj = t; }
        k[a] = gi * N + gj;
    }
    qsort(k, nl->npairs, sizeof *k, cmp_ll);
    *np = nl->npairs;
    return k;
}

static void check_split(floe_world *w, floe_world *ref, const char *when) {
    const floe_par *P = w->par;
    const floe_particles *p = &w->p, *q = &ref->p;
    const int N = q->n;
    int nb = 0;
    for (int i = 0; i < N; i++) nb += isfinite(q->radius[i]) != 0;
    /* 1. partition */
    int *owners = calloc((size_t)(N > 0 ? N : 1), sizeof *owners);
    for (int i = P->nrep; i < P->nrep + P->nown; i++) owners[P->gid[i]]++;
    MPI_Allreduce(MPI_IN_PLACE, owners, N, MPI_INT, MPI_SUM, P->comm);
    int once = 1, walls_ok = P->nrep == N - nb;
    for (int g = 0; g < N; g++) once &= owners[g] == (isfinite(q->radius[g]) ? 1 : 0);
    for (int i = 0; i < P->nrep; i++) walls_ok &= !isfinite(p->radius[i]);
    CHECK(once, "%s: every bounded particle owned by exactly one rank", when);
    CHECK(walls_ok, "%s: the %d walls on every rank", when, N - nb);
    free(owners);
    /* 2. data, bit for bit */
    int same = 1, sorted = 1;
    double ra[FLOE_PAR_REC], rb[FLOE_PAR_REC];
    for (int i = 0; i < p->n; i++) {
        const long long g = P->gid[i];
        floe_par_pack(p, i, g, ra);
        floe_par_pack(q, (int)g, g, rb);
        if (i >= P->nrep + P->nown) ra[32] = rb[32]; /* a ghost's motion: FLOE_FIXED */
        if (memcmp(ra, rb, sizeof ra)) same = 0;
        if (i > P->nrep && i < P->nrep + P->nown && P->gid[i - 1] >= g) sorted = 0;
    }
    CHECK(same, "%s: every local particle equals its global id's particle, field by field", when);
    CHECK(sorted, "%s: owned particles in global-id order", when);
    /* 3. ghosts against a brute-force search */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, rmax = 0;
    for (int i = P->nrep; i < P->nrep + P->nown; i++) {
        for (int a = 0; a < 3; a++) { lo[a] = fmin(lo[a], p->x[3 * i + a]); hi[a] = fmax(hi[a], p->x[3 * i + a]); }
        rmax = fmax(rmax, p->radius[i]);
    }
    unsigned char *local = calloc((size_t)(N > 0 ? N : 1), 1), *own = calloc((size_t)(N > 0 ? N : 1), 1);
    for (int i = 0; i < p->n; i++) local[P->gid[i]] = i < P->nrep + P->nown ? 2 : 1;
    for (int i = P->nrep; i < P->nrep + P->nown; i++) own[P->gid[i]] = 1;
    const double skin = w->nl.skin;
    int ghosts_ok = 1, nexp = 0, reach_ok = 1;
    for (int g = 0; g < N; g++) {
        if (!isfinite(q->radius[g]) || own[g]) continue;
        double d2 = 0;
        for (int a = 0; a < 3; a++) {
            double e = q->x[3 * g + a] < lo[a] ? lo[a] - q->x[3 * g + a] : q->x[3 * g + a] > hi[a] ? q->x[3 * g + a] - hi[a] : 0;
            d2 += e * e;
        }
        const int want = P->nown > 0 && sqrt(d2) <= q->radius[g] + rmax + skin;
        nexp += want;
        if (want != (local[g] == 1)) ghosts_ok = 0;
    }
    for (int i = P->nrep; i < P->nrep + P->nown; i++) {
        const long long gi = P->gid[i];
        for (int g = 0; g < N; g++) {
            if (!isfinite(q->radius[g]) || g == gi) continue;
            double d[3];
            floe_v3_sub(d, q->x + 3 * g, q->x + 3 * gi);
            const double lim = q->radius[g] + q->radius[gi] + skin;
            if (floe_v3_dot(d, d) <= lim * lim && !local[g]) reach_ok = 0;
        }
    }
    CHECK(ghosts_ok && nexp == P->nghost, "%s: rank %d: ghosts %d, brute force %d", when, rank_, P->nghost, nexp);
    CHECK(reach_ok, "%s: rank %d: every particle within reach of an owned one is here", when, rank_);
    free(local); free(own);
    /* 4. the lists together: the unsplit list, each pair once */
    int np, nr;
    long long *mine = pair_keys(w, P->gid, N, &np), *want = pair_keys(ref, NULL, N, &nr);
    int *cnts = rank_ == 0 ? malloc((size_t)size_ * sizeof *cnts) : NULL, *dsp = rank_ == 0 ? malloc((size_t)size_ * sizeof *dsp) : NULL;
    MPI_Gather(&np, 1, MPI_INT, cnts, 1, MPI_INT, 0, P->comm);
    int tot = 0;
    if (rank_ == 0) for (int r = 0; r < size_; r++) { dsp[r] = tot; tot += cnts[r]; }
    long long *all = rank_ == 0 ? malloc((size_t)(tot ? tot : 1) * sizeof *all) : NULL;
    MPI_Gatherv(mine, np, MPI_LONG_LONG, all, cnts, dsp, MPI_LONG_LONG, 0, P->comm);
    if (rank_ == 0) {
        qsort(all, tot, sizeof *all, cmp_ll);
        int eq = tot == nr && !memcmp(all, want, (size_t)nr * sizeof *all);
        CHECK(eq, "%s: the ranks' lists hold the unsplit list's %d pairs once each (got %d)", when, nr, tot);
        printf("  %s: %d ranks, %d pairs in all (unsplit %d)\n", when, size_, tot, nr);
    }
    free(mine); free(want); free(cnts); free(dsp); free(all);
}

static void check_comm(floe_world *w) {
    floe_par *P = w->par;
    floe_particles *p = &w->p;
    const int g0 = P->nrep + P->nown, N = P->ntotal;
    double *vsave = malloc((size_t)p->n * 3 * sizeof *vsave);
    memcpy(vsave, p->v, (size_t)p->n * 3 * sizeof *vsave);
    for (int i = P->nrep; i < g0; i++) floe_v3_set(p->v + 3 * i, (double)P->gid[i], 2.0 * P->gid[i], -1.0);
    floe_par_forward_comm(w, P, 1);
    int fwd = 1;
    for (int i = g0; i < p->n; i++) fwd &= p->v[3 * i] == (double)P->gid[i] && p->v[3 * i + 1] == 2.0 * P->gid[i];
    CHECK(fwd, "rank %d: forward refresh: each of %d ghosts holds its owner's velocity", rank_, P->nghost);
    /* a step's refresh: the ghosts the list reads (an end of a listed pair) hold their owners'
     * velocities, the others keep theirs (docs/parallel.md, "Ghosts") */
    unsigned char *rd = calloc((size_t)(p->n - g0 + 1), 1);
    for (int k = 0; k < w->nl.npairs; k++) {
        if (w->nl.pi[k] >= g0) rd[w->nl.pi[k] - g0] = 1;
        if (w->nl.pj[k] >= g0) rd[w->nl.pj[k] - g0] = 1;
    }
    for (int i = P->nrep; i < g0; i++) floe_v3_set(p->v + 3 * i, (double)P->gid[i], 3.0 * P->gid[i], -2.0);
    floe_par_forward_comm(w, P, 0);
    int sub = 1;
    long long nread[2] = {0, P->nghost};
    for (int i = g0; i < p->n; i++) {
        nread[0] += rd[i - g0];
        sub &= rd[i - g0] ? p->v[3 * i + 1] == 3.0 * P->gid[i] && p->v[3 * i + 2] == -2.0
                          : p->v[3 * i + 1] == 2.0 * P->gid[i] && p->v[3 * i + 2] == -1.0;
    }
    CHECK(sub, "rank %d: a step's refresh: the %lld ghosts the list reads hold their owners' velocities, the other %lld "
          "keep theirs", rank_, nread[0], nread[1] - nread[0]);
    MPI_Allreduce(MPI_IN_PLACE, nread, 2, MPI_LONG_LONG, MPI_SUM, P->comm);
    if (size_ > 1) CHECK(nread[0] > 0 && nread[0] < nread[1], "the list reads some ghosts, not all (%lld of %lld)", nread[0],
                         nread[1]);
    if (rank_ == 0) printf("  a step's refresh: %lld of %lld ghosts (all ranks)\n", nread[0], nread[1]);
    memcpy(p->v, vsave, (size_t)p->n * 3 * sizeof *vsave);
    floe_par_forward_comm(w, P, 1);
    free(vsave);
    /* reverse: ghosts carry 1, owners 0: each owner receives its number of ghost copies that
     * an end of a listed pair is (the others exert nothing: docs/parallel.md, "Ghosts") */
    for (int i = P->nrep; i < p->n; i++) floe_v3_set(p->f + 3 * i, i >= g0 ? 1.0 : 0.0, 0, 0);
    int *copies = calloc((size_t)(N > 0 ? N : 1), sizeof *copies);
    for (int i = g0; i < p->n; i++) copies[P->gid[i]] += rd[i - g0];
    free(rd);
    MPI_Allreduce(MPI_IN_PLACE, copies, N, MPI_INT, MPI_SUM, P->comm);
    floe_par_reverse_comm(w, P);
    int rev = 1;
    for (int i = P->nrep; i < g0; i++) rev &= p->f[3 * i] == copies[P->gid[i]];
    CHECK(rev, "rank %d: reverse sum: each owner receives its ghosts' forces once", rank_);
    free(copies);
}

/* a user's provider that takes a built-in's name: refused all the same (its loops and state
 * are its own; core/parallel/par_forcing.c knows the built-ins by their classes) */
static int impostor_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *ctx, floe_provider_out *out) {
    (void)pv; (void)w; (void)ctx; (void)out;
    return FLOE_OK;
}
static const floe_provider_class impostor_class = {.version = 1, .name = "linear_drag", .group = FLOE_GROUP_DEM,
                                                   .forces = impostor_forces};

/* a user's provider that runs split (per particle) but asks for a neighbour-list rebuild: a
 * split world refuses it (a list built on one rank alone would read ghosts the decomposition
 * does not refresh: docs/parallel.md, "Ghosts a step refreshes") */
static int rebuilder_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *ctx, floe_provider_out *out) {
    (void)pv; (void)w; (void)ctx;
    out->rebuild = 1;
    return FLOE_OK;
}
static const floe_provider_class rebuilder_class = {.version = 2, .name = "user_rebuilder", .group = FLOE_GROUP_DEM,
                                                    .forces = rebuilder_forces, .splits = FLOE_PROVIDER_PER_PARTICLE};

static void spin(double t, double v[3], double om[3], void *user) {
    (void)t; (void)user;
    v[0] = v[1] = v[2] = 0;
    om[0] = om[1] = 0; om[2] = 1;
}

/* a user's state object: it may read particles by index, which the split renumbers */
static size_t us_size(const floe_state *s) { (void)s; return 1; }
static void us_get(const floe_state *s, double *y) { (void)s; y[0] = 0; }
static int us_set(floe_state *s, floe_world *w, const double *y) { (void)s; (void)w; (void)y; return FLOE_OK; }
static int us_rhs(const floe_state *s, const floe_world *w, double t, const double *y, double *dydt) {
    (void)s; (void)w; (void)t; (void)y;
    dydt[0] = 0;
    return FLOE_OK;
}
static const floe_state_class user_state_class = {1, "user_temperature", us_size, us_get, us_set, us_rhs, NULL, NULL};

/* what is not supported yet is refused with FLOE_ENOTSUP and a message, on every rank (RK2,
 * the built-in state objects and motion callbacks on bounded particles run split since
 * session 22: tests/mpi/rk2_grow.yaml, pd_pull.yaml and the first case below) */
static void check_refusals(void) {
    for (int k = 0; k < 4; k++) {
        floe_world_def d = floe_default_world_def();
        d.dt = 1e-6;
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = mpi_test_glass(1e7);
        floe_world_add_material(w, &m);
        floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.3));
        int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
        for (int i = 0; i < 4; i++) {
            floe_particle_def p = floe_default_particle_def();
            p.geometry = g;
            p.x[0] = 0.003 * i;
            const int pi = floe_world_add_particle(w, &p);
            if (k == 0 && i == 2) floe_world_set_motion(w, pi, spin, NULL);
        }
        if (k == 1) {
            floe_state *st = malloc(sizeof *st);
            st->klass = &user_state_class;
            floe_world_add_state(w, st); /* the world frees it */
        }
        if (k == 2 || k == 3) {
            floe_provider *pv = malloc(sizeof *pv);
            pv->klass = k == 2 ? &impostor_class : &rebuilder_class;
            floe_world_add_provider(w, pv); /* the world frees it */
        }
        int rc = floe_world_prepare(w);
        if (rc == 0) rc = floe_world_parallel_init(w, NULL);
        if (k == 0) {
            /* since session 22 a motion callback on a bounded particle runs split: the rank
             * that owns the sphere finds its callback by global id (step.c motion_of) */
            CHECK(rc == 0, "a motion callback on a sphere runs split (rc %d: %s)", rc, rc ? floe_world_last_error(w) : "");
            for (int s = 0; s < 3 && rc == 0; s++) rc = floe_world_step(w);
            CHECK(rc == 0, "3 steps with the callback (rc %d)", rc);
            int spun = 0, all = 0;
            for (int i = 0; i < w->p.n; i++)
                if (floe_world_parallel_is_owned(w, i) && floe_world_parallel_gid(w, i) == 2 && w->p.w[3 * i + 2] == 1) spun++;
            MPI_Allreduce(&spun, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
            CHECK(all == 1, "the callback's sphere spins on the rank that owns it (%d ranks)", all);
            floe_world_destroy(w);
            continue;
        }
        if (k == 3) { /* split, then refused at the step, on every rank */
            CHECK(rc == 0, "a provider that runs split: the split (rc %d: %s)", rc, rc ? floe_world_last_error(w) : "");
            if (rc == 0) rc = floe_world_step(w);
            CHECK(rc == FLOE_ENOTSUP && strstr(floe_world_last_error(w), "asked for a neighbour-list rebuild") &&
                      strstr(floe_world_last_error(w), "user_rebuilder"),
                  "a split provider's rebuild refused at the step (rc %d: %s)", rc, floe_world_last_error(w));
            if (rank_ == 0) printf("  refused at the step: %s\n", floe_world_last_error(w));
            floe_world_destroy(w);
            continue;
        }
        const char *why[3] = {"", "a user's state object", "a user's provider named linear_drag"};
        CHECK(rc == FLOE_ENOTSUP && strstr(floe_world_last_error(w), "not supported yet"),
              "%s refused (rc %d: %s)", why[k], rc, floe_world_last_error(w));
        if (rank_ == 0) printf("  refused: %s\n", floe_world_last_error(w));
        floe_world_destroy(w);
    }
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    check_refusals();
    const int n_side = 12; /* 1728 particles */
    floe_world *w = build(n_side), *ref = build(n_side);
    int rc = floe_world_parallel_init(w, NULL);
    CHECK(rc == 0, "split: %s", rc ? floe_world_last_error(w) : "");
    if (rc == 0) {
        check_split(w, ref, "after the split");
        /* the store and the list hold this rank's part, not the whole world's they were
         * allocated for (floe_world_trim; before it, 2,048 particles' room on every rank) */
        const int fit = w->p.n + w->p.n / 4 + 64, pfit = w->nl.npairs + w->nl.npairs / 4 + 1024;
        CHECK(w->p.cap <= fit + fit / 2 && w->nl.cap <= pfit + pfit / 2,
              "the split store trimmed: room for %d particles (%d here, %d in the world), %d entries (%d)", w->p.cap,
              w->p.n, ref->p.n, w->nl.cap, w->nl.npairs);
        /* shift the upper half of the box by L/2 along x and the lower half by L/2 along y
         * (periodically): whatever the cuts, many particles change subdomain (a shift move
         * would not do: Zoltan renumbers the parts to keep particles where they are) */
        floe_world *ws[2] = {w, ref};
        for (int k = 0; k < 2; k++)
            for (int i = 0; i < ws[k]->p.n; i++)
                if (isfinite(ws[k]->p.radius[i])) {
                    double *x = ws[k]->p.x + 3 * i;
                    const int a = (int)(floe_world_parallel_gid(ws[k], i) % 3);
                    x[a] = fmod(x[a] + 0.5 * L, L);
                }
        floe_nl_build(&ref->nl, &ref->p, 3, ref->def.leaf_size);
        long long mig0 = w->par->migrated, mig;
        rc = floe_world_parallel_rebuild(w);
        CHECK(rc == 0, "rebuild: %s", rc ? floe_world_last_error(w) : "");
        long long m1 = w->par->migrated - mig0;
        MPI_Allreduce(&m1, &mig, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
        if (rank_ == 0) printf("  shift move: %lld of %d particles migrated\n", mig, n_side * n_side * n_side);
        if (size_ > 1) CHECK(mig > n_side * n_side * n_side / 8, "particles migrated after the shift move: %lld", mig);
        check_split(w, ref, "after the shift move");
        check_comm(w);
    }
    int all = mpi_test_failed("test_mpi_decomp");
    floe_world_destroy(w);
    floe_world_destroy(ref);
    MPI_Finalize();
    return all ? 1 : 0;
}
