/* test_mpi_beams.c - beam bonds in a world split over MPI ranks (core/parallel/par_beams.c,
 * docs/parallel.md "Beam bonds") against the same world on one process. Run under mpirun
 * with 1, 2 and 4 ranks (tests/CMakeLists.txt). Rank 0 first runs the unsplit world alone;
 * then every rank builds the same world, splits it and steps it.
 *   chain: 80 spheres in a line along x, 3 R apart (a bond is longer than the contact
 *     reach: the ghost halo must follow the bonds), bonded (Timoshenko, damped), set bending
 *     in two planes and twisting by a velocity and spin profile, no contact, no gravity: the
 *     subdomain cuts run across the chain, so bonds span the cut and their ghost ends carry
 *     force AND torque back to their owners.
 *   block: 6 x 6 x 6 bonded spheres (Hertz-Mindlin contacts, strengths drawn per bond)
 *     spinning about z and falling onto a floor at 3 m/s: bonds break at the impact, the
 *     broken pairs then meet by contact, and particles migrate between ranks with their
 *     bonds (the spin carries them across the cuts).
 *   stretch: two chains pulled apart while passing each other: broken bonds whose ends end
 *     up on different ranks are parked, follow their anchor, rejoin a set.
 * Checks against the unsplit run after a short horizon: every particle's position within
 * xtol of the scene's size, velocity and angular velocity within vtol of the largest,
 * orientation within qtol, the number of broken bonds equal, the bond count conserved (each
 * bond held by one rank), the energy ledger (elastic, dissipated) within 1e-8 of its scale.
 * The sums of forces on a particle are taken in another order (contacts and bonds of owned
 * ends, then what ghosts send back), so the runs agree to round-off, not to the bit.
 * These checks can fail: with the ghosts' torques dropped from the reverse sum (the ghost end
 * of a bond across the cut gets its force but not its torque; tried by hand at 2 ranks) the
 * chain's angular velocities differ by 1.1e-2 of the largest and positions by 2.6e-5 of its
 * size, the block breaks 127 bonds instead of 124 and its positions differ by 6.5e-2 of its
 * size; with a halo that ignores the bonds the chain stops at the split with "a beam bond's
 * partner is not on the rank that evaluates it".
 * Threads: the split block run again with 2 threads a rank (the bond loop threaded: the
 * grain set to 64 bonds) gives the same bits as with one. */
#include "floe.h"
#include "world_internal.h"
#include "beam_set.h"
#include "par_internal.h"
#include "../check.h"
#include "mpi_common.h"
#include <stdlib.h>
#include <string.h>

static const double R = 0.001;

static floe_world *new_world(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.dt_safety = 0.3;
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e8);
    return w;
}

static void add_sphere(floe_world *w, int g, const double x[3], const double v[3], const double om[3]) {
    floe_particle_def p = floe_default_particle_def();
    p.geometry = g;
    p.material = 0;
    floe_v3_copy(p.x, x);
    floe_v3_copy(p.v, v);
    floe_v3_copy(p.w, om);
    floe_world_add_particle(w, &p);
}

enum { NCHAIN = 80, NB = 6 };

static floe_world *build_chain(void) {
    floe_world *w = new_world();
    const int g = floe_world_add_geometry(w, floe_sphere_create(R));
    /* spheres 3 R apart (a gap of R): a bond is longer than the contact reach, so the ghost
     * halo must follow the bonds (the largest bounding radii and the skin fall short) */
    const double Lc = (NCHAIN - 1) * 3 * R;
    for (int k = 0; k < NCHAIN; k++) {
        const double s = k * 3 * R / Lc, x[3] = {k * 3 * R, 0, 0};
        const double v[3] = {0, 0.4 * sin(M_PI * s), 0.25 * sin(2 * M_PI * s)};
        const double om[3] = {80 * sin(M_PI * s), 0, 30 * cos(3 * M_PI * s)};
        add_sphere(w, g, x, v, om);
    }
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 1e8;
    bp.timoshenko = 1;
    bp.radius_ratio = 0.8;
    bp.damping_ratio = 0.02;
    bp.max_distance = 3.05 * R;
    floe_world_add_beam_bonds(w, 1.01, &bp);
    return w;
}

/* two chains of 60 touching spheres, 5 mm apart, each pulled apart (velocities from -20 to
 * 20 m/s along it) and both passing each other at 40 m/s (the first to +x, the second to
 * -x): bonds break in tension (weak ones where the 2- and 4-rank cuts fall at the start),
 * the pieces fly apart beyond the halo, so the broken bonds whose other end left the
 * anchor's rank are parked; as the chains pass, the bisection's cuts move along them and
 * the anchors of parked bonds migrate, the records with them */
enum { NS = 60 };
static floe_world *build_stretch(void) {
    floe_world *w = new_world();
    const int g = floe_world_add_geometry(w, floe_sphere_create(R));
    for (int c = 0; c < 2; c++)
        for (int k = 0; k < NS; k++) {
            const double s = (double)k / (NS - 1), x[3] = {k * 2 * R, c * 0.005, 0};
            const double v[3] = {40 * (s - 0.5) + (c ? -40 : 40), 0.5 * sin(5 * s), 0}, om[3] = {0, 0, 20 * cos(7 * s)};
            add_sphere(w, g, x, v, om);
        }
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 1e8;
    bp.radius_ratio = 0.6;
    bp.tensile_strength = 0.5e6;
    for (int c = 0; c < 2; c++)
        for (int q = 1; q < 4; q++) floe_world_add_beam_bond(w, c * NS + q * NS / 4 - 1, c * NS + q * NS / 4, &bp);
    bp.tensile_strength = 2.0e6;
    bp.tensile_sd = 0.6e6;
    bp.seed = 11;
    floe_world_add_beam_bonds(w, 1.01, &bp);
    return w;
}

static floe_world *build_block(void) {
    floe_world *w = new_world();
    w->def.gravity[2] = -9.81;
    const int g = floe_world_add_geometry(w, floe_sphere_create(R));
    const double floor_p[3] = {0, 0, 0}, floor_n[3] = {0, 0, 1};
    floe_world_add_wall(w, floor_p, floor_n, 0, FLOE_FIXED);
    const double c = (NB - 1) * R, om[3] = {0, 0, 250};
    for (int a = 0; a < NB; a++)
        for (int b = 0; b < NB; b++)
            for (int k = 0; k < NB; k++) {
                const double x[3] = {a * 2 * R - c, b * 2 * R - c, R + 0.0003 + k * 2 * R};
                /* rigid spin about the block's vertical axis, falling */
                const double v[3] = {-om[2] * x[1], om[2] * x[0], -3.0};
                add_sphere(w, g, x, v, om);
            }
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 1e8;
    bp.timoshenko = 1;
    bp.radius_ratio = 0.6;
    bp.damping_ratio = 0.05;
    bp.tensile_strength = 2.0e6;
    bp.tensile_sd = 0.6e6;
    bp.shear_strength = 2.0e6;
    bp.shear_sd = 0.6e6;
    bp.seed = 7;
    floe_world_add_beam_bonds(w, 1.01, &bp);
    return w;
}

/* per global id: x v w (3 each) and q (4); a split world's owned particles summed over the
 * ranks (every id owned once, walls on every rank: taken from rank 0 only) */
enum { SN = 13 };
static void snapshot(floe_world *w, int N, double *s) {
    memset(s, 0, (size_t)N * SN * sizeof *s);
    int rk = 0, sz = 1;
    floe_world_parallel_rank(w, &rk, &sz);
    for (int i = 0; i < w->p.n; i++) {
        const long long g = floe_world_parallel_gid(w, i);
        if (!floe_world_parallel_is_owned(w, i) || (!isfinite(w->p.radius[i]) && rk != 0)) continue;
        double *e = s + (size_t)g * SN;
        memcpy(e, w->p.x + 3 * i, 3 * sizeof *e);
        memcpy(e + 3, w->p.v + 3 * i, 3 * sizeof *e);
        memcpy(e + 6, w->p.w + 3 * i, 3 * sizeof *e);
        memcpy(e + 9, w->p.q + 4 * i, 4 * sizeof *e);
    }
    if (w->par) floe_world_parallel_sum(w, s, N * SN);
}

typedef struct result {
    double ledger[3];         /* elastic, dissipated, scale (initial + |work_body|) */
    long long bonds, broken;
    long long cross;          /* largest count over the steps of bonds with a ghost end */
    long long migrated;
    long long parked;         /* broken bonds held as records (an end not on the anchor's rank) */
    long long parked_moved;   /* parked bonds whose anchor changed rank */
    long long parked_ever;    /* anchors that had a bond parked at some check */
} result;

/* parked bonds (split world): the rank + 1 that first held each anchor's parked record
 * (first, by global id), and whether another rank held it later (moved) */
static void parked_track(floe_world *w, int N, int *first, unsigned char *moved) {
    int *loc = calloc((size_t)N, sizeof *loc), *cur = calloc((size_t)N, sizeof *cur);
    const int m = 2 + (int)((floe_beam_set_rec_size() + 7) / 8);
    for (int k = 0; k < w->par->npark; k++) loc[(long long)w->par->bpark[(size_t)k * m]] = rank_ + 1;
    MPI_Allreduce(loc, cur, N, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    for (int g = 0; g < N; g++) {
        if (cur[g] && !first[g]) first[g] = cur[g];
        else if (cur[g] && cur[g] != first[g]) moved[g] = 1;
    }
    free(loc);
    free(cur);
}

static int run(floe_world *w, long n, result *r) {
    r->cross = 0;
    const int N = w->par ? (int)w->par->ntotal : 0;
    int *first = calloc((size_t)(N ? N : 1), sizeof *first);
    unsigned char *moved = calloc((size_t)(N ? N : 1), 1);
    for (long s = 0; s < n; s++) {
        if (floe_world_step(w)) {
            fprintf(stderr, "rank %d: step %ld: %s\n", rank_, s, floe_world_last_error(w));
            free(first);
            free(moved);
            return 1;
        }
        if (w->par && s % 50 == 0) { /* bonds whose other end is a ghost: they span a cut */
            double c = 0;
            for (int k = 0; k < floe_world_beam_bond_count(w); k++) {
                floe_beam_bond_info b;
                floe_world_beam_bond(w, k, &b);
                c += !b.broken && !floe_world_parallel_is_owned(w, b.j);
            }
            floe_world_parallel_sum(w, &c, 1);
            if (c > r->cross) r->cross = (long long)c;
            parked_track(w, N, first, moved);
        }
    }
    r->parked_moved = r->parked_ever = 0;
    for (int g = 0; g < N; g++) { r->parked_moved += moved[g]; r->parked_ever += first[g] != 0; }
    free(first);
    free(moved);
    floe_energy e;
    floe_world_parallel_energy(w, &e);
    r->ledger[0] = e.elastic;
    r->ledger[1] = e.dissipated;
    r->ledger[2] = e.initial + fabs(e.work_body) + fabs(e.work_boundary);
    floe_world_parallel_beam_counts(w, &r->bonds, &r->broken);
    double mg[2] = {w->par ? (double)w->par->migrated : 0, w->par ? (double)w->par->npark : 0};
    floe_world_parallel_sum(w, mg, 2);
    r->migrated = (long long)mg[0];
    r->parked = (long long)mg[1];
    return 0;
}

static floe_world *split(floe_world *(*build)(void), int threads) {
    floe_world *w = build();
    floe_world_set_threads(w, threads);
    w->par_grain = 64;
    int rc = floe_world_prepare(w);
    if (rc == 0) rc = floe_world_parallel_init(w, NULL);
    CHECK(rc == 0, "split: %s", rc ? floe_world_last_error(w) : "");
    if (rc) MPI_Abort(MPI_COMM_WORLD, 1);
    return w;
}

static void compare(const char *tag, floe_world *(*build)(void), long nsteps, double xtol, double vtol, double qtol,
                    int threads_too) {
    floe_world *w = build();
    const int N = w->p.n;
    floe_world_destroy(w);
    double *ss = calloc((size_t)N * SN, sizeof *ss), *sp = calloc((size_t)N * SN, sizeof *sp);
    result rs = {{0}, 0, 0, 0, 0, 0, 0, 0}, rp = rs;
    int bad = 0;
    if (rank_ == 0) {
        floe_world *ws = build();
        int rc = floe_world_prepare(ws);
        CHECK(rc == 0, "%s: prepare: %s", tag, rc ? floe_world_last_error(ws) : "");
        bad |= rc || run(ws, nsteps, &rs);
        snapshot(ws, N, ss);
        floe_world_destroy(ws);
    }
    w = split(build, 1);
    { /* bonds are made before the split */
        floe_beam_params bp = floe_default_beam_params();
        bp.young = 1e8;
        const int r1 = floe_world_add_beam_bond(w, 0, 1, &bp), r2 = floe_world_add_beam_bonds(w, 1.01, &bp);
        CHECK(r1 == -FLOE_ENOTSUP && r2 == -FLOE_ENOTSUP && strstr(floe_world_last_error(w), "before floe_world_parallel_init"),
              "%s: bonds added to a split world are refused (%d, %d: %s)", tag, r1, r2, floe_world_last_error(w));
    }
    bad |= run(w, nsteps, &rp);
    snapshot(w, N, sp);
    floe_world_destroy(w);
    if (threads_too) { /* the same split run with the bond loop on 2 threads: the same bits */
        double *st = calloc((size_t)N * SN, sizeof *st);
        result rt;
        w = split(build, 2);
        bad |= run(w, nsteps, &rt);
        const int threaded = floe_beam_set_threaded(w->beams), nthr = floe_world_threads(w);
        snapshot(w, N, st);
        floe_world_destroy(w);
        int thr = threaded, anythr;
        MPI_Allreduce(&thr, &anythr, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
        if (rank_ == 0) {
            printf("  %s: 2 threads a rank (bond loop threaded on some rank: %d): %lld broken\n", tag, anythr, rt.broken);
            if (nthr > 1) CHECK(anythr, "%s: the threaded bond loop ran", tag);
            CHECK(!memcmp(st, sp, (size_t)N * SN * sizeof *st) && rt.broken == rp.broken,
                  "%s: 1 and 2 threads a rank give the same bits", tag);
        }
        free(st);
    }
    int allbad;
    MPI_Allreduce(&bad, &allbad, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    CHECK(!allbad, "%s: the runs stepped without error", tag);
    if (rank_ == 0) {
        double dx = 0, dv = 0, dw = 0, dq = 0, xmin = INFINITY, xmax = -INFINITY, vmax = 0, wmax = 0;
        for (int i = 0; i < N; i++) {
            const double *a = ss + (size_t)i * SN, *b = sp + (size_t)i * SN;
            for (int k = 0; k < 3; k++) {
                dx = fmax(dx, fabs(a[k] - b[k]));
                dv = fmax(dv, fabs(a[3 + k] - b[3 + k]));
                dw = fmax(dw, fabs(a[6 + k] - b[6 + k]));
                xmin = fmin(xmin, a[k]);
                xmax = fmax(xmax, a[k]);
                vmax = fmax(vmax, fabs(a[3 + k]));
                wmax = fmax(wmax, fabs(a[6 + k]));
            }
            /* q and -q are the same rotation */
            double dp = 0, dm = 0;
            for (int k = 0; k < 4; k++) { dp = fmax(dp, fabs(a[9 + k] - b[9 + k])); dm = fmax(dm, fabs(a[9 + k] + b[9 + k])); }
            dq = fmax(dq, fmin(dp, dm));
        }
        const double size = xmax - xmin;
        printf("  %s, %d ranks, %ld steps: max |dx| %.2e of the size %.3g m, |dv| %.2e of %.3g m/s, |dw| %.2e of "
               "%.3g rad/s, |dq| %.2e\n", tag, size_, nsteps, dx / size, size, dv / vmax, vmax, dw / wmax, wmax, dq);
        printf("  %s: bonds %lld (serial %lld), broken %lld (serial %lld), largest bonds across a cut %lld, "
               "migrations %lld, broken bonds parked %lld at the end, %lld at some time (%lld moved with their anchor)\n", tag,
               rp.bonds, rs.bonds, rp.broken, rs.broken, rp.cross, rp.migrated, rp.parked, rp.parked_ever, rp.parked_moved);
        printf("  %s: ledger elastic %.9e (serial %.9e), dissipated %.9e (serial %.9e)\n", tag, rp.ledger[0], rs.ledger[0],
               rp.ledger[1], rs.ledger[1]);
        CHECK(dx <= xtol * size, "%s: positions within %.0e of the size (got %.2e)", tag, xtol, dx / size);
        CHECK(dv <= vtol * vmax, "%s: velocities within %.0e of the largest (got %.2e)", tag, vtol, dv / vmax);
        CHECK(dw <= vtol * wmax, "%s: angular velocities within %.0e of the largest (got %.2e)", tag, vtol, dw / wmax);
        CHECK(dq <= qtol, "%s: orientations within %.0e (got %.2e)", tag, qtol, dq);
        CHECK(rp.bonds == rs.bonds, "%s: every bond held by one rank (%lld, serial %lld)", tag, rp.bonds, rs.bonds);
        CHECK(rp.broken == rs.broken, "%s: broken bonds %lld, serial %lld", tag, rp.broken, rs.broken);
        for (int k = 0; k < 2; k++)
            CHECK(fabs(rp.ledger[k] - rs.ledger[k]) <= 1e-8 * rs.ledger[2], "%s: ledger entry %d within 1e-8 of %.3g J "
                  "(got %.2e)", tag, k, rs.ledger[2], fabs(rp.ledger[k] - rs.ledger[k]) / rs.ledger[2]);
        if (size_ > 1) CHECK(rp.cross > 0, "%s: bonds span the subdomain cut (%lld)", tag, rp.cross);
    }
    MPI_Bcast(&rs, sizeof rs, MPI_BYTE, 0, MPI_COMM_WORLD);
    if (!strcmp(tag, "stretch") && rank_ == 0) {
        CHECK(rs.broken > 5, "%s: bonds broke (%lld of %lld)", tag, rs.broken, rs.bonds);
        if (size_ > 1)
            CHECK(rp.parked_ever > 0 && rp.parked_moved + rp.parked_ever - rp.parked > 0 && rp.migrated > 0,
                  "%s: broken bonds parked (%lld), moved with their anchor (%lld) or back in a set (%lld)", tag,
                  rp.parked_ever, rp.parked_moved, rp.parked_ever - rp.parked);
    }
    if (!strcmp(tag, "block") && rank_ == 0) {
        CHECK(rs.broken > 20 && rs.broken < rs.bonds / 2, "%s: some bonds broke (%lld of %lld)", tag, rs.broken, rs.bonds);
        if (size_ > 1) CHECK(rp.migrated > 0, "%s: particles with bonds migrated (%lld)", tag, rp.migrated);
    }
    free(ss); free(sp);
}

/* owner rank of every global id (walls and unknown: -1) */
static int *owners(floe_world *w, int N) {
    int *o = malloc((size_t)N * sizeof *o);
    for (int g = 0; g < N; g++) o[g] = -1;
    for (int i = 0; i < w->p.n; i++)
        if (isfinite(w->p.radius[i]) && floe_world_parallel_is_owned(w, i)) o[floe_world_parallel_gid(w, i)] = rank_;
    MPI_Allreduce(MPI_IN_PLACE, o, N, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return o;
}

/* the traffic of a decomposition with bonds, exactly (docs/parallel.md, "Traffic
 * accounting"): the gapped chain shifted along itself by 0.3 of its period (x + 24 spacings
 * modulo 80: the last 24 go to the start; the order along x changes, so particles and
 * bonds change owner; no contact, so no history), then a rebuild. Expected on every rank:
 * migrate = 312 B a particle that leaves + 408 B a bond whose anchor leaves + 3 routes x
 * 4 B (counts) to every other rank; ghost = fb B a ghost sent by the refresh before the
 * bonds are measured (x v w q: 104 B; + f, 24 B, under a linear dashpot: floe_par_fwd_doubles)
 + 312 B a new ghost + (64 + 4) B to every other rank; reduce = 8 B
 * (the longest bond) + 4 B (the bonds' hand-over agreed) + 8 B (the bonds' check) + 8 x 4 B
 * (the decomposition's agreements: before and after the bisection, in the 3 routes, before
 * the ghosts' exchange, after the history's import and after the list); nothing else. */
static void traffic(void) {
    floe_world *w = split(build_chain, 1);
    floe_par *P = w->par;
    const int N = (int)P->ntotal, S = size_;
    const double period = NCHAIN * 3 * R;
    int *before = owners(w, N);
    long long *anchors = malloc((size_t)(floe_world_beam_bond_count(w) + 1) * sizeof *anchors);
    int na = 0;
    for (int k = 0; k < floe_world_beam_bond_count(w); k++) {
        floe_beam_bond_info b;
        floe_world_beam_bond(w, k, &b);
        anchors[na++] = floe_world_parallel_gid(w, b.i);
    }
    for (int i = 0; i < w->p.n; i++) w->p.x[3 * i] = fmod(w->p.x[3 * i] + 0.3 * period, period);
    const long long nsend0 = P->nsend;
    floe_world_parallel_comm_reset(w);
    int rc = floe_world_parallel_rebuild(w);
    CHECK(rc == 0, "traffic: rebuild: %s", rc ? floe_world_last_error(w) : "");
    int *after = owners(w, N);
    long long left = 0, bleft = 0;
    for (int g = 0; g < N; g++) left += before[g] == rank_ && after[g] != rank_;
    for (int k = 0; k < na; k++) bleft += after[anchors[k]] != rank_;
    floe_comm_stats c;
    floe_world_parallel_comm(w, &c);
    const long long others = S - 1, nsend1 = P->nsend;
    const long long mig = S > 1 ? 312 * left + 408 * bleft + 3 * 4 * others : 0;
    const long long fb = 8LL * floe_par_fwd_doubles(w, P);
    CHECK(fb == 104, "traffic: a ghost refresh carries x v w q with beam bonds (%lld B, expected 104)", fb);
    const long long gh = S > 1 ? fb * nsend0 + 312 * nsend1 + 68 * others : 0, red = S > 1 ? 20 + 8 * 4 + 16 * S + 8 : 0; /* + the bisection's balance */
    CHECK(c.bytes[FLOE_COMM_MIGRATE] == mig, "rank %d: migration %lld B, expected %lld (%lld particles x 312, %lld bonds x "
          "408)", rank_, c.bytes[FLOE_COMM_MIGRATE], mig, left, bleft);
    CHECK(c.bytes[FLOE_COMM_GHOST] == gh, "rank %d: ghosts %lld B, expected %lld (%lld refreshed x %lld, %lld new x 312)",
          rank_, c.bytes[FLOE_COMM_GHOST], gh, nsend0, fb, nsend1);
    CHECK(c.bytes[FLOE_COMM_REDUCE] == red && c.bytes[FLOE_COMM_REVERSE] == 0 && c.bytes[FLOE_COMM_OUTPUT] == 0,
          "rank %d: reductions %lld B (expected %lld), nothing else", rank_, c.bytes[FLOE_COMM_REDUCE], red);
    long long tot[2] = {left, bleft};
    MPI_Allreduce(MPI_IN_PLACE, tot, 2, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
    if (S > 1) CHECK(tot[0] > 0 && tot[1] > 0, "traffic: particles (%lld) and bonds (%lld) changed owner", tot[0], tot[1]);
    if (rank_ == 0) printf("  traffic of a rebuild: %lld particles and %lld bonds changed owner\n", tot[0], tot[1]);
    long long nb, nbr;
    floe_world_parallel_beam_counts(w, &nb, &nbr);
    CHECK(nb == NCHAIN - 1 && nbr == 0, "traffic: the bonds after the move (%lld, %lld broken)", nb, nbr);
    free(before); free(after); free(anchors);
    floe_world_destroy(w);
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    const long nchain = argc > 1 ? atol(argv[1]) : 2000, nblock = argc > 2 ? atol(argv[2]) : 2000;
    compare("chain", build_chain, nchain, 1e-10, 1e-8, 1e-9, 0);
    compare("block", build_block, nblock, 1e-10, 1e-8, 1e-9, 1);
    compare("stretch", build_stretch, nchain, 1e-10, 1e-8, 1e-9, 0);
    traffic();
    int all = mpi_test_failed("test_mpi_beams");
    MPI_Finalize();
    return all ? 1 : 0;
}
