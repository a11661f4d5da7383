/* test_mpi_comm.c - the traffic accounting of a split world (floe_world_parallel_comm,
 * core/parallel, docs/parallel.md) against what the decomposition implies, exactly (tolerance
 * 0: the counts are integers). Run under mpirun with 1, 2 and 4 ranks (tests/CMakeLists.txt).
 * Every rank builds the same world of spheres of two sizes in a walled box (and an unsplit
 * copy), splits it, and the test works out from the unsplit copy, the owners of every global
 * id and the ranks' boxes of owned centres (its own MPI calls, not counted) how many ghosts
 * each rank must send to each other rank, M[o][r]; then
 *   - ghost refresh (spheres under Hertz-Mindlin: x3 v3 w3, 72 B a ghost; orientations only
 *     with other shapes or beam bonds, forces only under a linear dashpot): K refreshes send
 *     exactly K x 72 x sum_r M[me][r] bytes in K x #{r: M[me][r] > 0} messages, nothing else;
 *   - reverse sum (f3 t3, 48 B a ghost): K x 48 x sum_o M[o][me] bytes, to #{o: M[o][me] > 0}
 *     ranks;
 *   - (after the steps below) a rebuild after a shift move (many particles change owner, a third of the list's pairs
 *     marked touching so that history travels): migration = 312 B per particle that left this
 *     rank + the history records of the touching pairs whose anchor left (4 +
 *     8 or 10 doubles each) + two count exchanges (4 B to each other rank); ghosts =
 *     312 B per new ghost sent (M after the move) + the box (64 B: its corners, the largest
 *     radius, a failure flag) and a count (4 B) to each other rank; reductions = the
 *     decomposition's 7 agreements (4 B each: a failure on one rank is every rank's);
 *   - 200 steps of a gas of fast spheres (a few rebuilds on the way): each step's reverse
 *     traffic is 48 B x this rank's ghosts at the step's end, the ghost traffic summed over
 *     the ranks 72 B (312 B at a rebuild, + 68 B x (ranks - 1) per rank) x the ghosts of all
 *     ranks, the reductions three a step (seven more at a rebuild): 12 B (whether to rebuild,
 *     whether a rank failed, whether a drift check failed) + 4 B (the forces' outcome agreed)
 *     + 152 B (the watchdog's ledger, its minimum and the step's close agreed, one element
 *     of 19 doubles) or, in the last 50 steps with the watchdog off, 4 B for the close alone;
 *     + 28 B at a rebuild; no output word without outputs; the step count and the mean loads;
 *   - the watchdog's reduction itself (floe_par_watchdog_values): the sums and the minimum
 *     over the ranks exact, the PD bodies' dissipations in the same reduction up to 8 and in
 *     a second one beyond, the step's close agreed in it (a failure on one rank returned by
 *     every rank with that rank's message, an out-of-memory one first, err_agreed 1 or 2);
 *   - the end of a run with a mirror (rank 0): the gathered state 184 B per owned particle
 *     and 48 B per wall on every other rank, + the ledger (56 B), the words (4 B each).
 * With one rank every count is 0. */
#include "floe.h"
#include "world_internal.h"
#include "par_internal.h"
#include "par_hooks.h"
#include "../check.h"
#include "mpi_common.h"
#include <stdlib.h>
#include <string.h>

static const double L = 0.02; /* box side, m */
enum { NSIDE = 9 };           /* 729 spheres */

static floe_world *build(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = 1e-6;
    d.gravity[2] = -9.81;
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    int g[2] = {floe_world_add_geometry(w, floe_sphere_create(0.0004)), floe_world_add_geometry(w, floe_sphere_create(0.0006))};
    mpi_test_box_walls(w, L, L, L, 0, 6);
    unsigned s = 31337;
    const double h = L / NSIDE;
    int cnt = 0;
    for (int a = 0; a < NSIDE; a++)
        for (int b = 0; b < NSIDE; b++)
            for (int c = 0; c < NSIDE; c++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g[cnt++ % 2];
                double j[6];
                for (int k = 0; k < 6; k++) { s = s * 1103515245u + 12345u; j[k] = (s >> 8) / 16777216.0 - 0.5; }
                floe_v3_set(p.x, (a + 0.5 + 0.15 * j[0]) * h, (b + 0.5 + 0.15 * j[1]) * h, (c + 0.5 + 0.15 * j[2]) * h);
                floe_v3_set(p.v, 6 * j[3], 6 * j[4], 6 * j[5]); /* fast: rebuilds within 200 steps */
                floe_world_add_particle(w, &p);
            }
    w->nl.skin = 0.0004;
    if (floe_world_prepare(w)) { fprintf(stderr, "prepare: %s\n", floe_world_last_error(w)); exit(2); }
    return w;
}

/* owner[g] of every global id (-1: a wall), from every rank's owned particles */
static int *owners(const floe_world *w) {
    const floe_par *P = w->par;
    const int N = P->ntotal;
    int *o = malloc((size_t)N * sizeof *o);
    for (int g = 0; g < N; g++) o[g] = -1;
    for (int i = P->nrep; i < P->nrep + P->nown; i++) o[P->gid[i]] = rank_;
    MPI_Allreduce(MPI_IN_PLACE, o, N, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return o;
}

/* every particle's position by global id on every rank (walls: 0) */
static double *positions(const floe_world *w) {
    const floe_par *P = w->par;
    double *x = calloc((size_t)3 * P->ntotal, sizeof *x);
    for (int i = P->nrep; i < P->nrep + P->nown; i++) memcpy(x + 3 * P->gid[i], w->p.x + 3 * i, 3 * sizeof *x);
    MPI_Allreduce(MPI_IN_PLACE, x, 3 * P->ntotal, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    return x;
}

/* M[o * S + r]: particles of rank o that rank r must hold as ghosts: those whose bounding
 * sphere, grown by the largest radius r owns and the skin, reaches the box of r's owned
 * centres. Positions x by global id, radii from the unsplit world q. */
static long long *ghost_matrix(const double *x, const floe_particles *q, const int *own, double skin) {
    const int S = size_, N = q->n;
    double *box = malloc((size_t)S * 7 * sizeof *box);
    for (int r = 0; r < S; r++) {
        double *b = box + 7 * r;
        for (int a = 0; a < 3; a++) { b[a] = INFINITY; b[3 + a] = -INFINITY; }
        b[6] = 0;
    }
    for (int g = 0; g < N; g++) {
        if (own[g] < 0) continue;
        double *b = box + 7 * own[g];
        for (int a = 0; a < 3; a++) { b[a] = fmin(b[a], x[3 * g + a]); b[3 + a] = fmax(b[3 + a], x[3 * g + a]); }
        b[6] = fmax(b[6], q->radius[g]);
    }
    long long *M = calloc((size_t)S * S, sizeof *M);
    for (int g = 0; g < N; g++) {
        if (own[g] < 0) continue;
        for (int r = 0; r < S; r++) {
            const double *b = box + 7 * r;
            if (r == own[g] || !(b[0] <= b[3])) continue;
            double d2 = 0;
            for (int a = 0; a < 3; a++) {
                const double y = x[3 * g + a], e = y < b[a] ? b[a] - y : y > b[3 + a] ? y - b[3 + a] : 0;
                d2 += e * e;
            }
            M[own[g] * S + r] += sqrt(d2) <= q->radius[g] + b[6] + skin;
        }
    }
    free(box);
    return M;
}

/* R[o * S + r]: ghosts of rank o that rank r's neighbour list reads (an end of one of its
 * pairs): the ghosts a step refreshes (docs/parallel.md, "Ghosts a step refreshes"); every
 * rank the whole matrix. *held: those this rank reads, or -1 - that when the subset the rank
 * keeps (P->frecv) is not exactly that set */
static long long *read_matrix(const floe_world *w, const int *own, long long *held) {
    const floe_par *P = w->par;
    const floe_neighbor_list *nl = &w->nl;
    const int S = size_, g0 = nl->own_hi, n = w->p.n;
    unsigned char *rd = calloc((size_t)(n - g0 + 1), 1);
    for (int k = 0; k < nl->npairs; k++) {
        if (nl->pi[k] >= g0) rd[nl->pi[k] - g0] = 1;
        if (nl->pj[k] >= g0) rd[nl->pj[k] - g0] = 1;
    }
    long long *R = calloc((size_t)S * S, sizeof *R);
    *held = 0;
    for (int i = g0; i < n; i++)
        if (rd[i - g0]) {
            R[own[P->gid[i]] * S + rank_]++;
            ++*held;
        }
    MPI_Allreduce(MPI_IN_PLACE, R, S * S, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
    /* the subset kept (P->frecv) is that set: as many, each one read, none twice */
    int same = P->fgen == nl->gen && P->nfrecv == *held;
    for (int k = 0; same && k < P->nfrecv; k++) {
        const int i = P->frecv[k];
        same = i >= g0 && i < n && rd[i - g0] == 1;
        if (same) rd[i - g0] = 2;
    }
    if (!same) *held = -1 - *held; /* (told to the caller: the kept subset is another) */
    free(rd);
    return R;
}

static floe_comm_stats stats(const floe_world *w) {
    floe_comm_stats c;
    floe_world_parallel_comm(w, &c);
    return c;
}

/* every kind but `keep` (a bit set) is zero */
static int others_zero(const floe_comm_stats *c, unsigned keep) {
    for (int k = 0; k < FLOE_COMM_KINDS; k++)
        if (!(keep >> k & 1u) && (c->bytes[k] || c->messages[k])) return 0;
    return 1;
}

static void check_refresh(floe_world *w, const floe_world *ref) {
    floe_par *P = w->par;
    const int S = size_, me = rank_, K = 3;
    int *own = owners(w);
    double *x = positions(w);
    long long *M = ghost_matrix(x, &ref->p, own, w->nl.skin);
    long long send = 0, recv = 0, smsg = 0, rmsg = 0;
    for (int r = 0; r < S; r++) {
        send += M[me * S + r]; smsg += M[me * S + r] > 0;
        recv += M[r * S + me]; rmsg += M[r * S + me] > 0;
    }
    CHECK(recv == P->nghost, "rank %d: the ghosts the decomposition implies (%lld) are those held (%d)", me, recv, P->nghost);
    /* the refreshed ghosts: those the list reads, of each owner (fsend, frecv) */
    long long held;
    long long *R = read_matrix(w, own, &held);
    CHECK(held >= 0, "rank %d: the ghosts it keeps refreshed are those its list reads (%lld)", me, -1 - held);
    if (held < 0) held = -1 - held;
    long long fsend = 0, fsmsg = 0, frmsg = 0;
    for (int r = 0; r < S; r++) {
        fsend += R[me * S + r]; fsmsg += R[me * S + r] > 0;
        frmsg += R[r * S + me] > 0;
    }
    CHECK(P->nfsend == fsend, "rank %d: it sends its ghosts the others' lists read: %d (%lld)", me, P->nfsend, fsend);
    floe_world_parallel_comm_reset(w);
    for (int k = 0; k < K; k++) floe_par_forward_comm(w, P, 0);
    floe_comm_stats c = stats(w);
    CHECK(floe_par_fwd_doubles(w, P) == 9, "rank %d: a refresh of spheres without a linear dashpot carries x v w (%d doubles)",
          me, floe_par_fwd_doubles(w, P));
    CHECK(c.bytes[FLOE_COMM_GHOST] == K * 72LL * fsend && c.messages[FLOE_COMM_GHOST] == K * fsmsg,
          "rank %d: %d refreshes: ghost traffic %lld B in %lld messages, expected %lld B (%lld ghosts x 72 B) in %lld",
          me, K, c.bytes[FLOE_COMM_GHOST], c.messages[FLOE_COMM_GHOST], K * 72LL * fsend, fsend, K * fsmsg);
    CHECK(others_zero(&c, 1u << FLOE_COMM_GHOST), "rank %d: a refresh sends nothing else", me);
    /* every ghost (a decomposition's own refreshes) */
    floe_world_parallel_comm_reset(w);
    floe_par_forward_comm(w, P, 1);
    c = stats(w);
    CHECK(c.bytes[FLOE_COMM_GHOST] == 72LL * send && c.messages[FLOE_COMM_GHOST] == smsg,
          "rank %d: a refresh of every ghost: %lld B in %lld messages, expected %lld B (%lld ghosts x 72 B) in %lld", me,
          c.bytes[FLOE_COMM_GHOST], c.messages[FLOE_COMM_GHOST], 72LL * send, send, smsg);
    floe_world_parallel_comm_reset(w);
    for (int k = 0; k < K; k++) floe_par_reverse_comm(w, P);
    c = stats(w);
    CHECK(c.bytes[FLOE_COMM_REVERSE] == K * 48LL * held && c.messages[FLOE_COMM_REVERSE] == K * frmsg,
          "rank %d: %d reverse sums: %lld B in %lld messages, expected %lld B (%lld ghosts x 48 B) in %lld", me, K,
          c.bytes[FLOE_COMM_REVERSE], c.messages[FLOE_COMM_REVERSE], K * 48LL * held, held, K * frmsg);
    CHECK(others_zero(&c, 1u << FLOE_COMM_REVERSE), "rank %d: a reverse sum sends nothing else", me);
    long long tot[2] = {held, recv};
    MPI_Allreduce(MPI_IN_PLACE, tot, 2, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
    CHECK(tot[0] <= tot[1], "the ghosts read are among those held (%lld of %lld)", tot[0], tot[1]);
    if (me == 0)
        printf("  refresh: rank 0 sends %lld of its %lld ghosts (%lld B a refresh) to %lld ranks, holds %lld of %lld; "
               "all ranks: %lld of %lld ghosts refreshed\n", fsend, send, 72 * fsend, fsmsg, held, recv, tot[0], tot[1]);
    free(own); free(M); free(x); free(R);
}

/* the shift move of test_mpi_decomp, a third of the pairs marked touching, a rebuild (the
 * world overlaps after it: the last check before the end) */
static void check_rebuild(floe_world *w, const floe_world *ref) {
    floe_par *P = w->par;
    const int S = size_, me = rank_, N = P->ntotal;
    for (int i = 0; i < w->p.n; i++)
        if (isfinite(w->p.radius[i])) {
            double *x = w->p.x + 3 * i;
            const int a = (int)(floe_world_parallel_gid(w, i) % 3);
            x[a] = fmod(x[a] + 0.5 * L, L);
        }
    floe_neighbor_list *nl = &w->nl;
    for (int k = 0; k < nl->npairs; k++) nl->touching[k] = k % 3 == 0;
    const int hl = 4 + nl->hs + (nl->use_warm && nl->warm ? FLOE_DETECT_WARM : 0);
    int *before = owners(w);
    /* the kept entries (touching, or a warm start) whose anchor (lower gid of two bounded
     * particles, else the bounded one) this rank owns, by anchor gid */
    long long *anchors = malloc((size_t)(nl->npairs ? nl->npairs : 1) * sizeof *anchors);
    int na = 0;
    for (int k = 0; k < nl->npairs; k++) {
        const int use_warm = nl->use_warm && nl->warm;
        if (!(nl->touching[k] || (use_warm && isfinite(nl->warm[(size_t)k * FLOE_DETECT_WARM])))) continue;
        const int i = nl->pi[k], j = nl->pj[k];
        const long long gi = P->gid[i], gj = P->gid[j];
        const int bi = isfinite(w->p.radius[i]), bj = isfinite(w->p.radius[j]);
        const long long a = bi && bj ? (gi < gj ? gi : gj) : bi ? gi : gj;
        if (before[a] == me) anchors[na++] = a;
    }
    floe_world_parallel_comm_reset(w);
    int rc = floe_world_parallel_rebuild(w);
    CHECK(rc == 0, "rebuild: %s", rc ? floe_world_last_error(w) : "");
    int *after = owners(w);
    long long left = 0, hleft = 0;
    unsigned char *pdest = calloc((size_t)S, 1), *hdest = calloc((size_t)S, 1);
    for (int g = 0; g < N; g++)
        if (before[g] == me && after[g] != me) { left++; pdest[after[g]] = 1; }
    for (int k = 0; k < na; k++)
        if (after[anchors[k]] != me) { hleft++; hdest[after[anchors[k]]] = 1; }
    long long pm = 0, hm = 0;
    for (int r = 0; r < S; r++) { pm += pdest[r]; hm += hdest[r]; }
    double *x = positions(w);
    long long *M = ghost_matrix(x, &ref->p, after, w->nl.skin);
    long long send = 0, smsg = 0, recv = 0, rmsg = 0;
    for (int r = 0; r < S; r++) {
        send += M[me * S + r]; smsg += M[me * S + r] > 0;
        recv += M[r * S + me]; rmsg += M[r * S + me] > 0;
    }
    const floe_comm_stats c = stats(w);
    const long long others = S - 1;
    const long long mig_b = 312 * left + 8LL * hl * hleft + 2 * 4 * others, mig_m = pm + hm + 2 * others;
    /* + a byte per ghost held back to its owner: whether this rank's list reads it */
    const long long gh_b = 312 * send + (64 + 4) * others + recv, gh_m = smsg + 2 * others + rmsg;
    CHECK(c.bytes[FLOE_COMM_MIGRATE] == mig_b && c.messages[FLOE_COMM_MIGRATE] == mig_m,
          "rank %d: migration %lld B in %lld messages, expected %lld B (%lld particles x 312 B, %lld history records x %d B) "
          "in %lld", me, c.bytes[FLOE_COMM_MIGRATE], c.messages[FLOE_COMM_MIGRATE], mig_b, left, hleft, 8 * hl, mig_m);
    CHECK(c.bytes[FLOE_COMM_GHOST] == gh_b && c.messages[FLOE_COMM_GHOST] == gh_m,
          "rank %d: new ghosts %lld B in %lld messages, expected %lld B (%lld ghosts x 312 B, %lld read flags) in %lld", me,
          c.bytes[FLOE_COMM_GHOST], c.messages[FLOE_COMM_GHOST], gh_b, send, recv, gh_m);
    /* the decomposition's agreements: before and after the bisection, in the two routes
     * (particles, history), before the ghosts' exchange, after the history's import and after
     * the list (par_rebuild: a failure on one rank is every rank's); and the bisection's
     * balance (decomp.c rcb_imbalance: each part's two sums and a failure flag, 8-byte integers) */
    CHECK(c.bytes[FLOE_COMM_REDUCE] == (S > 1 ? 7 * 4 + 16 * S + 8 : 0), "rank %d: a rebuild's reductions %lld B, expected %d",
          me, c.bytes[FLOE_COMM_REDUCE], S > 1 ? 7 * 4 + 16 * S + 8 : 0);
    CHECK(others_zero(&c, 1u << FLOE_COMM_GHOST | 1u << FLOE_COMM_MIGRATE | 1u << FLOE_COMM_REDUCE),
          "rank %d: a rebuild sends nothing else", me);
    CHECK(c.rebuilds == 1 && c.steps == 0, "rank %d: one rebuild, no step counted (%ld, %ld)", me, c.rebuilds, c.steps);
    long long tot[2] = {left, hleft};
    MPI_Allreduce(MPI_IN_PLACE, tot, 2, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
    if (S > 1) CHECK(tot[0] > N / 8 && tot[1] > 0, "the shift move migrates particles (%lld) and history (%lld)", tot[0], tot[1]);
    if (me == 0) printf("  rebuild: %lld particles and %lld history records migrated in all\n", tot[0], tot[1]);
    free(before); free(after); free(anchors); free(pdest); free(hdest); free(M); free(x);
}

static void check_steps(floe_world *w) {
    const int S = size_, me = rank_, NSTEP = 200;
    const long long others = S - 1;
    const int check0 = w->def.energy_check;
    CHECK(check0 != FLOE_CHECK_OFF, "the energy watchdog is on (the default)");
    floe_world_parallel_comm_reset(w);
    floe_comm_stats c0 = stats(w);
    int ok_rev = 1, ok_red = 1, ok_out = 1, ok_gh = 1, ok_read = 1, nreb = 0;
    double gsum = 0, osum = 0, fsum = 0;
    for (int s = 0; s < NSTEP; s++) {
        if (s == NSTEP - 50) w->def.energy_check = FLOE_CHECK_OFF; /* the close agreed alone */
        const int wd = w->def.energy_check != FLOE_CHECK_OFF;
        int rc = floe_world_step(w);
        if (rc) { CHECK(0, "step %d: %s", s, floe_world_last_error(w)); break; }
        floe_comm_stats c = stats(w);
        int own, gh;
        floe_world_parallel_counts(w, &own, &gh);
        gsum += gh; osum += own;
        /* the ghosts this step refreshed: those its list reads */
        int *owner = owners(w);
        long long held;
        long long *R = read_matrix(w, owner, &held);
        free(owner); free(R);
        ok_read &= held >= 0;
        if (held < 0) held = -1 - held;
        fsum += (double)held;
        const int reb = c.rebuilds > c0.rebuilds;
        nreb += reb;
        long long d[FLOE_COMM_KINDS], dm[FLOE_COMM_KINDS];
        for (int k = 0; k < FLOE_COMM_KINDS; k++) {
            d[k] = c.bytes[k] - c0.bytes[k];
            dm[k] = c.messages[k] - c0.messages[k];
        }
        if (S > 1) {
            ok_rev &= d[FLOE_COMM_REVERSE] == 48LL * held;
            /* whether to rebuild with whether a rank failed and whether a drift check failed (3
             * ints), the forces' outcome, the
             * step's close (4 B; with the watchdog on, the watchdog's 9 sums, its minimum and
             * the close's word, 19 doubles, in one reduction); a rebuild's agreements. Three
             * reductions a step (+ eight at a rebuild: seven agreements and the bisection's
             * balance, the parts' two sums and a failure flag as 8-byte integers) */
            ok_red &= d[FLOE_COMM_REDUCE] == 12 + 4 + (reb ? 7 * 4 + 16 * S + 8 : 0) + (wd ? 152 : 4);
            ok_red &= dm[FLOE_COMM_REDUCE] == 3 + (reb ? 8 : 0);
            ok_out &= d[FLOE_COMM_OUTPUT] == 0 && dm[FLOE_COMM_OUTPUT] == 0;
            ok_red &= reb || d[FLOE_COMM_MIGRATE] == 0;
        } else {
            for (int k = 0; k < FLOE_COMM_KINDS; k++) ok_rev &= d[k] == 0;
        }
        /* over the ranks: every ghost held was sent once by its owner at a rebuild (312 B, and
         * a byte back: whether it is read), every ghost read at the other steps (72 B) */
        long long v[2] = {d[FLOE_COMM_GHOST] - (reb ? 68 * others : 0), reb ? gh : held};
        MPI_Allreduce(MPI_IN_PLACE, v, 2, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
        ok_gh &= v[0] == (reb ? 313 : 72) * v[1];
        c0 = c;
    }
    w->def.energy_check = check0;
    CHECK(ok_read, "rank %d: every step refreshes the ghosts its list reads", me);
    CHECK(ok_rev, "rank %d: every step's reverse traffic is 48 B x the ghosts its list reads", me);
    CHECK(ok_red, "rank %d: every step's reductions are three: 16 B (+ 36 + 16 x ranks B and eight more at a rebuild), the "
          "close's 4 B, carried by the watchdog's 152 B when it is on", me);
    CHECK(ok_out, "rank %d: without outputs a step sends no output word", me);
    CHECK(ok_gh, "every step's ghost traffic over the ranks is 72 B x the ghosts read (313 B x all ghosts held at a "
          "rebuild)");
    floe_comm_stats c = stats(w);
    CHECK(c.steps == NSTEP && c.rebuilds == nreb, "rank %d: %ld steps counted (%d), %ld rebuilds (%d)", me, c.steps, NSTEP,
          c.rebuilds, nreb);
    CHECK(c.ghost_steps == gsum && c.owned_steps == osum && c.refreshed_steps == fsum,
          "rank %d: the mean loads: ghosts %g (%g), refreshed %g (%g), owned %g (%g)", me, c.ghost_steps, gsum,
          c.refreshed_steps, fsum, c.owned_steps, osum);
    int any = nreb;
    MPI_Allreduce(MPI_IN_PLACE, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    CHECK(any > 0, "the gas rebuilds within %d steps (%d)", NSTEP, any);
    double ld[2] = {fsum, gsum};
    MPI_Allreduce(MPI_IN_PLACE, ld, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    if (S > 1) CHECK(ld[0] > 0 && ld[0] < ld[1], "the steps refresh some ghosts, not all (%g of %g ghost-steps)", ld[0], ld[1]);
    if (me == 0) printf("  %d steps: %g of %g ghost-steps refreshed (all ranks)\n", NSTEP, ld[0], ld[1]);
    if (me == 0) {
        printf("  %d steps, %d rebuilds: rank 0 sent per step (B):", NSTEP, nreb);
        for (int k = 0; k < FLOE_COMM_KINDS; k++)
            printf(" %s %.1f", floe_comm_kind_name((floe_comm_kind)k), (double)c.bytes[k] / c.steps);
        printf("\n");
    }
}

/* outputs reduced over the ranks (docs/parallel.md): a mirror whose observers are a
 * collection's stress (every step), the energy (every step) and a tracker of a wall and two
 * spheres (every 2 steps) gathers nothing: each step's output traffic is the words (rank 0:
 * whether it is due, which observers are; whether it holds a mirror is told once, at
 * floe_world_parallel_outputs), the ledger, three
 * checks and the reduced sums (13 + 6 doubles for the stress, 22 a tracked particle), whatever
 * the number of particles */
static void check_reduced(void) {
    const int me = rank_, NSTEP = 6;
    floe_world *M = NULL, *w = build();
    if (floe_world_parallel_init(w, NULL)) {
        CHECK(0, "split: %s", floe_world_last_error(w));
        floe_world_destroy(w);
        return;
    }
    char path[3][96];
    const char *names[3] = {"stress", "energy", "track"};
    for (int k = 0; k < 3; k++) snprintf(path[k], sizeof path[k], "/tmp/floe_test_mpi_comm_%d_%s.csv", size_, names[k]);
    if (me == 0) {
        M = build();
        const int ids[3] = {0, 100, 700}; /* a wall (the walls come first), two spheres */
        char err[256];
        floe_observer *o[3] = {floe_collection_tracker_create(path[0], -1, 0, err, sizeof err),
                               floe_energy_tracker_create(path[1], err, sizeof err),
                               floe_particle_tracker_create(path[2], ids, 3, err, sizeof err)};
        for (int k = 0; k < 3; k++) {
            CHECK(o[k] != NULL, "output %s: %s", names[k], err);
            if (!o[k]) continue;
            o[k]->period_steps = k == 2 ? 2 : 1;
            floe_world_add_observer(M, o[k]);
        }
    }
    int rc = floe_world_parallel_outputs(w, M);
    CHECK(rc == 0, "outputs: %s", rc ? floe_world_last_error(w) : "");
    floe_world_parallel_comm_reset(w);
    long long got = 0, want = 0;
    for (int s = 0; s < NSTEP && rc == 0; s++) {
        rc = floe_world_step(w);
        CHECK(rc == 0, "step %d: %s", s, rc ? floe_world_last_error(w) : "");
        if (size_ == 1) continue;
        const long step = floe_world_step_count(w);
        want += me == 0 ? 4 + 3 * 4 + 56 + 3 * 4 : 56 + 3 * 4 + 8 * (13 + 6) + (step % 2 == 0 ? 8 * 22 * 3 : 0);
    }
    const floe_comm_stats c = stats(w);
    got = c.bytes[FLOE_COMM_OUTPUT];
    CHECK(got == want, "rank %d: reduced outputs sent %lld B over %d steps, expected %lld B (nothing gathered)", me,
          got, NSTEP, want);
    /* an observer added to the mirror after floe_world_parallel_outputs: gathered for */
    char late[96];
    snprintf(late, sizeof late, "/tmp/floe_test_mpi_comm_%d_late.csv", size_);
    if (me == 0) {
        char err[256];
        floe_observer *o = floe_energy_tracker_create(late, err, sizeof err);
        CHECK(o != NULL, "late output: %s", err);
        if (o) {
            o->period_steps = 1;
            floe_world_add_observer(M, o);
        }
    }
    for (int s = 0; s < 2 && rc == 0; s++) {
        rc = floe_world_step(w);
        CHECK(rc == 0, "late step %d: %s", s, rc ? floe_world_last_error(w) : "");
    }
    /* detach the mirror (its files closed with it) */
    rc = floe_world_parallel_outputs(w, NULL);
    CHECK(rc == 0, "outputs detached: %s", rc ? floe_world_last_error(w) : "");
    if (me == 0) {
        floe_world_finish(M);
        floe_world_destroy(M);
        const int rows[3] = {NSTEP, NSTEP, 3 * NSTEP / 2}; /* data rows (the tracker: 3 a row block) */
        for (int k = 0; k < 3; k++) {
            FILE *f = fopen(path[k], "r");
            int n = -1, ch; /* the header is not a row */
            while (f && (ch = fgetc(f)) != EOF) n += ch == '\n';
            if (f) fclose(f);
            CHECK(n >= rows[k], "%s: %d rows after %d steps (at least %d)", names[k], n, NSTEP, rows[k]);
            remove(path[k]);
        }
        FILE *f = fopen(late, "r");
        int n = -1, ch;
        while (f && (ch = fgetc(f)) != EOF) n += ch == '\n';
        if (f) fclose(f);
        CHECK(n == 2, "the output added late wrote %d rows over 2 steps (2)", n);
        remove(late);
    }
    floe_world_destroy(w);
}

/* the end of a run with rank 0's mirror (no observers): the state gathered once */
static void check_finish(floe_world *w, floe_world *ref) {
    const int me = rank_;
    int rc = floe_world_parallel_outputs(w, me == 0 ? ref : NULL);
    CHECK(rc == 0, "outputs: %s", rc ? floe_world_last_error(w) : "");
    floe_world_parallel_comm_reset(w);
    rc = floe_world_parallel_finish(w);
    CHECK(rc == 0, "finish: %s", rc ? floe_world_last_error(w) : "");
    const floe_par *P = w->par;
    const floe_comm_stats c = stats(w);
    long long want = 0, msgs = 0;
    if (size_ > 1) {
        /* the word (root), the ledger (7 doubles), the allocation check, the result (all);
         * rank 0's word that it holds the gathered state (root) */
        want = (me == 0 ? 8 : 0) + 56 + 4 + 4;
        msgs = (me == 0 ? 2 : 0) + 3;
        if (me != 0) { /* the walls' forces, the count, the owned particles' state */
            want += 48LL * P->nrep + 4 + 184LL * P->nown;
            msgs += (P->nrep > 0) + 1 + (P->nown > 0);
        }
    }
    CHECK(c.bytes[FLOE_COMM_OUTPUT] == want && c.messages[FLOE_COMM_OUTPUT] == msgs,
          "rank %d: the mirror's gather %lld B in %lld messages, expected %lld B (%d particles x 184 B, %d walls x 48 B) in %lld",
          me, c.bytes[FLOE_COMM_OUTPUT], c.messages[FLOE_COMM_OUTPUT], want, P->nown, P->nrep, msgs);
    CHECK(others_zero(&c, 1u << FLOE_COMM_OUTPUT), "rank %d: the gather sends nothing else", me);
}

/* floe_par_watchdog_values on the split world w: rank r's values are known functions of r,
 * so the sums over the ranks are exact (small integers) */
static void check_watchdog_sums(floe_world *w) {
    const int S = size_, me = rank_;
    for (int npd = 0; npd <= 10; npd += 5) { /* 0, 5 (with the rest), 10 (a second sum) */
        floe_energy e;
        memset(&e, 0, sizeof e);
        e.kinetic_trans = 1 + me; e.kinetic_rot = 2 * (1 + me); e.elastic = 3; e.work_body = -me;
        e.work_boundary = 0.5; e.dissipated = 4 * me; e.initial = 7;
        double shadow = 10 + me, shadow0 = 20, pair_min = -1.0 - me, pdd[10];
        for (int k = 0; k < npd; k++) pdd[k] = (k + 1) * (me + 1);
        const floe_comm_stats c0 = stats(w);
        const int rc = floe_par_watchdog_values(w, &e, &shadow, &shadow0, &pair_min, pdd, npd, NULL);
        const floe_comm_stats c1 = stats(w);
        const double s1 = S * (S + 1) / 2.0, s0 = S * (S - 1) / 2.0; /* sum of (1 + r), of r */
        int ok = rc == FLOE_OK && e.kinetic_trans == s1 && e.kinetic_rot == 2 * s1 && e.elastic == 3 * S &&
                 e.work_body == -s0 && e.work_boundary == 0.5 * S && e.dissipated == 4 * s0 && e.initial == 7 * S &&
                 shadow == 10 * S + s0 && shadow0 == 20 * S && pair_min == -(double)S;
        for (int k = 0; k < npd; k++) ok &= pdd[k] == (k + 1) * s1;
        CHECK(ok, "rank %d: the watchdog's sums over %d ranks with %d PD bodies (%g %g, min %g)", me, S, npd,
              e.kinetic_trans, shadow, pair_min);
        const long long nred = c1.messages[FLOE_COMM_REDUCE] - c0.messages[FLOE_COMM_REDUCE];
        if (S > 1)
            CHECK(nred == (npd > 8 ? 2 : 1), "rank %d: %lld reductions with %d PD bodies (%d)", me, nred, npd,
                  npd > 8 ? 2 : 1);
    }
    /* the close agreed in the same reduction: the last rank fails (its message), then rank 0
     * runs out of memory while the last rank fails otherwise (out of memory first) */
    for (int round = 0; round < 2; round++) {
        floe_energy e;
        memset(&e, 0, sizeof e);
        double shadow = 0, shadow0 = 0, pair_min = 0, pdd[10] = {0};
        int mine = FLOE_OK;
        if (me == S - 1) mine = floe_world_error(w, FLOE_EUNSTABLE, "close failed on rank %d", me);
        if (round == 1 && me == 0) mine = floe_world_error(w, FLOE_ENOMEM, "rank %d out of memory", me);
        w->err_agreed = 0;
        const int rc = floe_par_watchdog_values(w, &e, &shadow, &shadow0, &pair_min, pdd, 10, &mine);
        char want[64];
        if (round == 0) snprintf(want, sizeof want, "close failed on rank %d", S - 1);
        else snprintf(want, sizeof want, "rank 0 out of memory");
        const int code = round == 0 ? FLOE_EUNSTABLE : FLOE_ENOMEM;
        CHECK(rc == code && strstr(floe_world_last_error(w), want) && w->err_agreed == (round == 0 ? 1 : 2),
              "rank %d: the close agreed in the watchdog's reduction, round %d: %d '%s' agreed %d (want %d '%s')", me,
              round, rc, floe_world_last_error(w), w->err_agreed, code, want);
    }
    w->err_agreed = 0;
    w->err[0] = 0;
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    floe_world *w = build(), *ref = build();
    CHECK(strcmp(floe_comm_kind_name(FLOE_COMM_MIGRATE), "migrate") == 0, "kind names");
    int rc = floe_world_parallel_init(w, NULL);
    CHECK(rc == 0, "split: %s", rc ? floe_world_last_error(w) : "");
    if (rc == 0) {
        floe_comm_stats c = stats(w);
        CHECK(c.rebuilds == 1 && c.steps == 0, "the split: one decomposition, no step (%ld, %ld)", c.rebuilds, c.steps);
        if (size_ > 1) CHECK(c.bytes[FLOE_COMM_GHOST] > 0 && c.bytes[FLOE_COMM_REDUCE] > 0, "the split's traffic counted");
        else CHECK(others_zero(&c, 0), "one rank sends nothing");
        check_refresh(w, ref);
        check_steps(w);
        check_watchdog_sums(w);
        check_rebuild(w, ref);
        check_finish(w, ref);
        check_reduced();
    }
    int all = mpi_test_failed("test_mpi_comm");
    floe_world_destroy(w);
    floe_world_destroy(ref);
    MPI_Finalize();
    return all ? 1 : 0;
}
