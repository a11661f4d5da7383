/* test_lp_resting.c - the polytope LP's resting-contact path (docs/models.md, "Polytope
 * pairs: the resting-contact path"): a pair's previous basis is kept when it is still
 * feasible and optimal, and then the contact must be the one the full LP gives.
 *  1. A settling run of 40 random polyhedra (14 planes each) with spins, in a walled box:
 *     after every step, every pair whose bounding spheres overlap is detected twice at the
 *     same poses, once warm (a basis per pair kept from the last step, as the world keeps
 *     it) and once cold (no basis: the full LP from the deepest vertex). Both must agree on
 *     touching or not; depth, point and every manifold vertex within 1e-10 x the grain size,
 *     the normals and gscale within 1e-10. The warm calls must mostly keep their basis
 *     (> 80 % of the LP halves without a pivot), or the path is not what was tested. The
 *     world's own contacts of each step (its contact stage, with the separation cache) must
 *     be exactly the pairs the cold detection finds touching, and the cache must have found
 *     most of the pairs apart.
 *  2. Negative control: a pair solved once, then one body turned by 0.3 .. 1 rad: the old
 *     basis must not be kept (a pivot, or a cold start when its point is infeasible), both
 *     cases must occur, and the result must be the cold solve's; unmoved, it is kept.
 *     2b. The same turned pairs with the pivots in closed form capped (none, one): the LU
 *     path takes over from the given basis (floe_lp_result.taken_over) and still gives the
 *     cold solve's result.
 *  3. The lazy problem (floe_lp_problem.b_body: p''s planes in its own frame and the map, as
 *     detect.c gives it, with the planes by coordinate at odd poses and without at even ones)
 *     against the same planes mapped first (by the library's own map, a cold lazy solve's
 *     buffer): at 400 poses, warm (kept, or needing a pivot or a cold start) and cold, the
 *     same basis, point, value, normal and multipliers to the bit.
 *  4. The separation cache against moves by the API that the list does not see (a turn, a
 *     move, a new shape): the next step finds the contact (sep_cache_moves). */
#include "floe.h"
#include "world_internal.h"
#include "floe_polytope_lp.h"
#include "world_read.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>
#define TEST_RNG_SEED 0x5EEDC0FFEE123457ull
#include "test_rng.h"
#include "poly_box.h"

#define NP 40
#define NPL 14
static const double R = 0.01;

static floe_geometry *grain(void) { return poly_grain(R, NPL); }

static double dist3(const double a[3], const double b[3]) {
    double d[3];
    floe_v3_sub(d, a, b);
    return floe_v3_norm(d);
}

static void settling_run(void) {
    floe_material m = {"m", 2500, 1e7, 0.3};
    floe_world *w = poly_box_new(R, &m);
    CHECK(w != NULL, "world");
    if (!w) return;
    /* mass ~ 2500 x (2R)^3 = 0.02 kg; kn: about 1 % overlap at rest under a few grains */
    floe_world_set_law(w, 0, 0, floe_linear_law_create(2e4, 5e3, 0.5, 0.1, 0.5));
    int g[4];
    for (int s = 0; s < 4; s++) g[s] = floe_world_add_geometry(w, grain());
    poly_box_fill(w, NP, g, 4, R);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    floe_world_record_contacts(w, 1);
    const int n = pview(w).n; /* the walls first, then the grains */
    unsigned char *inw = malloc((size_t)(n * n)); /* the world's own contacts of the step */
    long mism_world = 0, sep = 0, sepc = 0; /* the world's steps' pairs found apart, by the cache */
    double *warm = malloc(sizeof(double) * (size_t)(n * n * FLOE_DETECT_WARM));
    for (int k = 0; k < n * n * FLOE_DETECT_WARM; k++) warm[k] = NAN;
    long walls = 0;
    long compared = 0, touching = 0, mism_touch = 0, mism_val = 0, halves = 0, kept = 0, cold = 0, extras = 0;
    double worst_x = 0, worst_n = 0, turned = 0;
    floe_contact cf, cc;
    const int nsteps = 8000;
    for (int s = 0; s < nsteps; s++) {
        const floe_detect_stats sa = dstats(w);
        CHECK(floe_world_step(w) == FLOE_OK, "step: %s", floe_world_last_error(w));
        const floe_detect_stats sb = dstats(w);
        sep += sb.separated - sa.separated;
        sepc += sb.sep_cached - sa.sep_cached;
        floe_particles_view v = pview(w);
        for (int i = n - NP; i < n; i++) turned += floe_v3_norm(v.w + 3 * i) * floe_world_dt(w) / NP;
        memset(inw, 0, (size_t)(n * n));
        for (int c = 0; c < w->ncontacts; c++) {
            const int a = w->contacts[c].i < w->contacts[c].j ? w->contacts[c].i : w->contacts[c].j;
            const int b = w->contacts[c].i ^ w->contacts[c].j ^ a;
            inw[a * n + b] = 1;
        }
        for (int i = 0; i < n; i++)
            for (int j = i + 1; j < n; j++) {
                double *wm = warm + (size_t)(i * n + j) * FLOE_DETECT_WARM;
                const double ri = v.radius[i], rj = v.radius[j];
                if (isinf(ri) && isinf(rj)) continue; /* two walls */
                if (dist3(v.x + 3 * i, v.x + 3 * j) >= ri + rj) { /* apart: the next approach starts cold */
                    wm[0] = NAN;
                    mism_world += inw[i * n + j];
                    continue;
                }
                floe_detect_stats d0 = dstats(w);
                memset(&cf, 0, sizeof cf);
                memset(&cc, 0, sizeof cc);
                cf.gscale = cc.gscale = 1.0;
                int rf = floe_world_detect(w, i, j, 0, wm, &cf);
                floe_detect_stats d1 = dstats(w);
                halves += d1.lp_halves - d0.lp_halves;
                kept += d1.lp_kept - d0.lp_kept;
                cold += d1.lp_cold - d0.lp_cold;
                int rc = floe_world_detect(w, i, j, 0, NULL, &cc);
                compared++;
                /* the world's step (its contact stage, with the separation cache) found the
                 * same pairs touching as the cold detection at the same poses */
                if ((rc == 1) != inw[i * n + j] && mism_world++ < 5)
                    printf("  step %d pair %d-%d: the world's step says %d, cold detection %d\n", s, i, j,
                           inw[i * n + j], rc);
                if (rf != rc) {
                    if (mism_touch++ < 5)
                        printf("  step %d pair %d-%d: warm says %d, cold says %d (depths %.3e %.3e)\n", s, i, j, rf, rc,
                               cf.depth, cc.depth);
                    continue;
                }
                if (rf != 1) continue;
                touching++;
                walls += isinf(ri) || isinf(rj);
                double ex = fmax(fabs(cf.depth - cc.depth), dist3(cf.point, cc.point)), en = dist3(cf.n, cc.n);
                en = fmax(en, fabs(cf.gscale - cc.gscale));
                int bad = cf.nextra != cc.nextra;
                for (int e = 0; !bad && e < cf.nextra; e++) {
                    ex = fmax(ex, fmax(fabs(cf.extra_depth[e] - cc.extra_depth[e]), dist3(cf.extra_point[e], cc.extra_point[e])));
                    en = fmax(en, dist3(cf.extra_n[e], cc.extra_n[e]));
                    extras++;
                }
                worst_x = fmax(worst_x, ex);
                worst_n = fmax(worst_n, en);
                if (bad || ex > 1e-10 * R || en > 1e-10) {
                    if (mism_val++ < 5)
                        printf("  step %d pair %d-%d: warm and cold differ: depth %.17g vs %.17g, point by %.3e, "
                               "normal by %.3e, extras %d vs %d\n", s, i, j, cf.depth, cc.depth,
                               dist3(cf.point, cc.point), dist3(cf.n, cc.n), cf.nextra, cc.nextra);
                }
            }
    }
    const double ke = floe_world_energy(w).kinetic_trans + floe_world_energy(w).kinetic_rot;
    printf("  settling run: the world's contacts against cold detection: %ld differ; pairs found apart "
           "before the LP %ld, by the separation cache %ld (%.1f %%)\n", mism_world, sep, sepc,
           sep ? 100.0 * sepc / sep : 0.0);
    CHECK(mism_world == 0, "the world's step and cold detection agree on the touching pairs: %ld differ", mism_world);
    CHECK(sep > 10000 && sepc > sep / 2, "the separation cache is used: %ld of %ld pairs found apart (bound half)",
          sepc, sep);
    free(inw);
    printf("  settling run, %d polyhedra, %d steps (mean turn %.1f rad, kinetic energy at the end %.2e J, %d "
           "contacts): %ld pair detections compared warm against cold, %ld touching (%ld of them grain-wall, %ld "
           "manifold vertices); "
           "warm LP halves %ld, basis kept without a pivot %ld (%.1f %%), cold %ld; differ: touching %ld, values "
           "%ld; worst point/depth difference %.2e x R, normal %.2e\n",
           NP, nsteps, turned, ke, floe_world_contact_count(w), compared, touching, walls, extras, halves, kept,
           halves ? 100.0 * kept / halves : 0.0, cold, mism_touch, mism_val, worst_x / R, worst_n);
    CHECK(touching - walls > 20000, "settling run: enough touching pairs compared (%ld, bound 20000)", touching);
    CHECK(turned > 1.0, "settling run: the grains turn (mean %.2f rad, bound 1)", turned);
    CHECK(mism_touch == 0, "warm and full LP agree on touching: %ld differ", mism_touch);
    CHECK(mism_val == 0, "warm and full LP contacts within 1e-10 R and 1e-10: %ld differ (worst %.2e R, %.2e)", mism_val,
          worst_x / R, worst_n);
    CHECK(halves > 0 && kept > 0.8 * halves, "resting path used: %ld of %ld warm halves kept their basis (bound 80 %%)",
          kept, halves);
    free(warm);
    floe_world_destroy(w);
}

/* the LP of a's point deepest in b, b's planes in a's frame (as detect.c) */
static int solve_half_cap(const floe_geometry *ga, const floe_geometry *gb, const double xb[3], const double qb[4],
                          int basis[4], floe_lp_result *r, int cap) {
    floe_polytope_view A, B;
    CHECK(floe_geometry_polytope(ga, 3, &A) && floe_geometry_polytope(gb, 3, &B), "polytope views");
    double *tb = malloc(sizeof(double) * 4 * (size_t)B.np);
    for (int k = 0; k < B.np; k++) { /* a sits at the origin, unrotated */
        floe_q_rotate(tb + 4 * k, qb, B.plane + 4 * k);
        tb[4 * k + 3] = B.plane[4 * k + 3] + floe_v3_dot(tb + 4 * k, xb);
    }
    floe_lp_problem P = {.dim = 3, .a = A.plane, .na = A.np, .b = tb, .nb = B.np, .va = A.v, .nva = A.nv, .scale = R,
                         .pivots3_cap = cap};
    int rc = floe_lp_deepest(&P, basis, r);
    free(tb);
    return rc;
}
static int solve_half(const floe_geometry *ga, const floe_geometry *gb, const double xb[3], const double qb[4],
                      int basis[4], floe_lp_result *r) {
    return solve_half_cap(ga, gb, xb, qb, basis, r, 0);
}

static void negative_control(void) {
    int kept_same = 0, pivoted = 0, recold = 0, kept_moved = 0, agree = 0, trials = 200;
    double worst = 0;
    for (int t = 0; t < trials; t++) {
        floe_geometry *ga = grain(), *gb = grain();
        double u[3], xb[3], qb[4];
        rand_unit(u);
        for (int k = 0; k < 3; k++) xb[k] = 1.7 * R * u[k];
        rand_quat(qb);
        int basis[4] = {-1, -1, -1, -1}, b2[4];
        floe_lp_result r0, r1, r2;
        CHECK(solve_half(ga, gb, xb, qb, basis, &r0) == FLOE_OK, "cold solve");
        memcpy(b2, basis, sizeof b2);
        CHECK(solve_half(ga, gb, xb, qb, b2, &r1) == FLOE_OK, "warm solve, unmoved");
        kept_same += r1.warm && r1.pivots == 0 && fabs(r1.s - r0.s) <= 1e-12 * R;
        /* turn b by 0.3 .. 1 rad about a random axis */
        double th[3], dq[4], q2[4];
        rand_unit(th);
        floe_v3_scale(th, uni(0.3, 1.0));
        floe_q_from_rotvec(dq, th);
        floe_q_mul(q2, dq, qb);
        floe_q_normalize(q2);
        memcpy(b2, basis, sizeof b2);
        CHECK(solve_half(ga, gb, xb, q2, b2, &r1) == FLOE_OK, "warm solve, turned");
        int c[4] = {-1, -1, -1, -1};
        CHECK(solve_half(ga, gb, xb, q2, c, &r2) == FLOE_OK, "cold solve, turned");
        if (r1.warm && r1.pivots == 0) kept_moved++;
        else if (r1.warm) pivoted++;
        else recold++;
        double e = fmax(fabs(r1.s - r2.s), dist3(r1.x, r2.x));
        worst = fmax(worst, e);
        agree += e <= 1e-10 * R;
        floe_geometry_destroy(ga);
        floe_geometry_destroy(gb);
    }
    printf("  negative control, %d pairs: unmoved, basis kept %d; turned 0.3-1 rad: kept %d (still optimal), pivoted "
           "from it %d, started cold (infeasible) %d; results equal to the cold solve %d (worst %.2e R)\n",
           trials, kept_same, kept_moved, pivoted, recold, agree, worst / R);
    CHECK(kept_same == trials, "unmoved pairs keep their basis: %d of %d", kept_same, trials);
    CHECK(pivoted > trials / 10 && recold > trials / 10,
          "a turned pair's old basis is given up, by pivots (%d) and by a cold start (%d), both > 10 %%", pivoted, recold);
    CHECK(agree == trials, "after the basis changed the result is the cold LP's within 1e-10 R: %d of %d", agree, trials);
}

/* 2b. The LU path taking over from the pivots in closed form (polytope_lp.c lp_pivot3 gives
 * up: a singular basis, an unbounded edge, an optimum outside a row, or more pivots than its
 * cap): from the given basis, after the closed form has moved its own copy of the point and
 * multipliers. With the cap at none (every pivoting half taken over at once) and at one
 * pivot (the halves that need more taken over after one), each turned pair's result is the
 * cold solve's, and the take-overs happen. */
static void pivots_taken_over(void) {
    const int trials = 200, caps[3] = {-1, 1, 0};
    int over[3] = {0, 0, 0}, agree[3] = {0, 0, 0}, multi = 0, over_cold = 0;
    double worst = 0;
    for (int t = 0; t < trials; t++) {
        floe_geometry *ga = grain(), *gb = grain();
        double u[3], xb[3], qb[4], th[3], dq[4], q2[4];
        rand_unit(u);
        for (int k = 0; k < 3; k++) xb[k] = 1.7 * R * u[k];
        rand_quat(qb);
        rand_unit(th);
        floe_v3_scale(th, uni(0.3, 1.0));
        floe_q_from_rotvec(dq, th);
        floe_q_mul(q2, dq, qb);
        floe_q_normalize(q2);
        int basis[4] = {-1, -1, -1, -1}, c[4] = {-1, -1, -1, -1};
        floe_lp_result r0, rc;
        CHECK(solve_half(ga, gb, xb, qb, basis, &r0) == FLOE_OK, "cold solve");
        CHECK(solve_half(ga, gb, xb, q2, c, &rc) == FLOE_OK, "cold solve, turned");
        for (int m = 0; m < 3; m++) {
            int b2[4];
            floe_lp_result r;
            memcpy(b2, basis, sizeof b2);
            CHECK(solve_half_cap(ga, gb, xb, q2, b2, &r, caps[m]) == FLOE_OK, "warm solve, turned, cap %d", caps[m]);
            over[m] += r.taken_over;
            over_cold += r.taken_over && !r.warm;
            if (m == 2) multi += r.warm && !r.taken_over && r.pivots > 1;
            const double e = fmax(fabs(r.s - rc.s), dist3(r.x, rc.x));
            worst = fmax(worst, e);
            agree[m] += e <= 1e-10 * R;
        }
        floe_geometry_destroy(ga);
        floe_geometry_destroy(gb);
    }
    printf("  the LU path taking over, %d turned pairs: taken over with no closed-form pivot %d, after one %d, by "
           "default %d (%d solved in closed form with more than one pivot); equal to the cold solve %d, %d, %d "
           "(worst %.2e R)\n",
           trials, over[0], over[1], over[2], multi, agree[0], agree[1], agree[2], worst / R);
    CHECK(over[0] > trials / 10, "with no closed-form pivot the LU path takes over: %d of %d", over[0], trials);
    CHECK(over_cold == 0, "the LU path goes on from the given (feasible) basis, not cold: %d cold", over_cold);
    CHECK(over[1] > 0 && over[1] < over[0], "after one closed-form pivot: some halves taken over (%d, fewer than %d)",
          over[1], over[0]);
    for (int m = 0; m < 3; m++)
        CHECK(agree[m] == trials, "cap %d: the result is the cold LP's within 1e-10 R: %d of %d", caps[m], agree[m],
              trials);
}

static void lazy_equals_full(void) {
    int poses = 400, same = 0, lazy_kept = 0, lazy_full = 0, with_soa = 0;
    for (int t = 0; t < poses; t++) {
        floe_geometry *ga = grain(), *gb = grain();
        floe_polytope_view A, B;
        CHECK(floe_geometry_polytope(ga, 3, &A) && floe_geometry_polytope(gb, 3, &B), "polytope views");
        double *tb = malloc(sizeof(double) * 4 * (size_t)B.np), *buf = malloc(sizeof(double) * 4 * (size_t)B.np);
        int basis0[4] = {-1, -1, -1, -1};
        for (int pass = 0; pass < 3; pass++) {
            /* b at 1.7 R in a random direction, turned; pass 1: the same pose (the basis
             * kept), pass 2: another pose from pass 1's basis (pivots or a cold start) */
            static double map[12];
            if (pass != 1) {
                double u[3], q[4], Rb[3][3];
                rand_unit(u);
                rand_quat(q);
                for (int c = 0; c < 3; c++) {
                    double e[3] = {0, 0, 0}, col[3];
                    e[c] = 1;
                    floe_q_rotate(col, q, e);
                    for (int r = 0; r < 3; r++) Rb[r][c] = col[r];
                }
                /* Xb = Rb^T (x - xb), xb = 1.7 R u (a at the origin, unrotated) */
                for (int i = 0; i < 3; i++) {
                    map[9 + i] = 0;
                    for (int j = 0; j < 3; j++) {
                        map[3 * i + j] = Rb[j][i];
                        map[9 + i] -= Rb[j][i] * 1.7 * R * u[j];
                    }
                }
            }
            floe_lp_problem F = {.dim = 3, .a = A.plane, .na = A.np, .b = tb, .nb = B.np, .va = A.v, .nva = A.nv,
                                 .scale = R};
            /* the lazy problem with the planes by coordinate, as detect.c gives it (odd poses)
             * and without them (even): both the same bits as the mapped planes' */
            const int soa = t % 2 && A.plane_soa && B.plane_soa;
            floe_lp_problem L = {.dim = 3, .a = A.plane, .na = A.np, .nb = B.np, .va = A.v, .nva = A.nv, .scale = R,
                                 .b_body = B.plane, .map = map, .b_buf = buf, .a_soa = soa ? A.plane_soa : NULL,
                                 .na_soa = A.np_soa, .b_soa = soa ? B.plane_soa : NULL, .nb_soa = B.np_soa};
            with_soa += soa;
            {   /* the mapped planes as the library maps them: a cold lazy solve maps them all
                 * into its buffer (one formula, one compilation: the comparison is of the
                 * paths, not of two compilations of the map) */
                int bc[4] = {-1, -1, -1, -1};
                floe_lp_result rc0;
                CHECK(floe_lp_deepest(&L, bc, &rc0) == FLOE_OK, "cold lazy solve");
                memcpy(tb, buf, sizeof(double) * 4 * (size_t)B.np);
            }
            int bf[4], bl[4];
            memcpy(bf, basis0, sizeof bf);
            memcpy(bl, basis0, sizeof bl);
            floe_lp_result rf, rl;
            const int rcf = floe_lp_deepest(&F, bf, &rf), rcl = floe_lp_deepest(&L, bl, &rl);
            const int eq = rcf == rcl && !memcmp(bf, bl, sizeof bf) && rf.warm == rl.warm && rf.pivots == rl.pivots &&
                           rf.taken_over == rl.taken_over &&
                           !memcmp(rf.x, rl.x, sizeof rf.x) && !memcmp(&rf.s, &rl.s, sizeof rf.s) &&
                           !memcmp(rf.normal, rl.normal, sizeof rf.normal) && !memcmp(&rf.gnorm, &rl.gnorm, sizeof rf.gnorm) &&
                           !memcmp(rf.lambda, rl.lambda, sizeof rf.lambda);
            same += eq;
            lazy_kept += rl.warm && rl.pivots == 0;
            lazy_full += !(rl.warm && rl.pivots == 0);
            memcpy(basis0, bf, sizeof bf);
        }
        free(tb);
        free(buf);
        floe_geometry_destroy(ga);
        floe_geometry_destroy(gb);
    }
    printf("  lazy problem, %d solves (%d with the planes by coordinate): the same bits as the mapped planes' in %d; basis "
           "kept %d, full problem %d\n",
           3 * poses, with_soa, same, lazy_kept, lazy_full);
    CHECK(same == 3 * poses, "lazy and mapped problems give the same bits: %d of %d", same, 3 * poses);
    CHECK(with_soa == 3 * poses / 2, "the lazy problem with the planes by coordinate in half the solves: %d", with_soa);
    CHECK(lazy_kept > poses / 2 && lazy_full > poses, "both lazy paths taken: kept %d, full %d", lazy_kept, lazy_full);
}

/* 4. The separation cache against moves the list does not see: two bars 1 x 0.1 x 0.1 side
 * by side, 0.2 apart (their bounding spheres overlap), no gravity. Steps with the pair apart
 * must keep it in the cache; then bar B is turned about z (its end dips 0.002 into A), or
 * moved 0.205 towards A, or given a box 0.51 wide (mode 2: 0.005 into A) by the API, within the list's
 * skin (no rebuild). The next step must find the contact: the cache's bound covers turns,
 * moves and new shapes (a bound without its turn term keeps the pair apart in mode 0, one
 * without |dx| in mode 1; a new shape also rebuilds the list, which empties the cache). */
static void sep_cache_moves(void) {
    static const char *what[3] = {"turned", "moved", "new shape"};
    for (int mode = 0; mode < 3; mode++) {
        floe_world_def def = floe_default_world_def();
        def.dt = 1e-5;
        def.skin = 1.0;
        floe_world *w = floe_world_create(&def, NULL, 0);
        floe_material m = {"m", 1000, 1e6, 0.3};
        floe_world_add_material(w, &m);
        floe_world_set_law(w, 0, 0, floe_linear_law_create(1e3, 0, 0.5, 0.0, 0.5));
        const int g = floe_world_add_geometry(w, floe_box_create(1.0, 0.1, 0.1));
        const int g2 = floe_world_add_geometry(w, floe_box_create(1.0, 0.51, 0.1));
        floe_particle_def a = floe_default_particle_def(), b = floe_default_particle_def();
        a.geometry = b.geometry = g;
        floe_v3_set(b.x, 0, 0.3, 0);
        CHECK(floe_world_add_particle(w, &a) == 0 && floe_world_add_particle(w, &b) == 1, "sep cache: add bars");
        CHECK(floe_world_prepare(w) == FLOE_OK, "sep cache: prepare: %s", floe_world_last_error(w));
        const floe_detect_stats d0 = dstats(w);
        for (int s = 0; s < 5; s++) CHECK(floe_world_step(w) == FLOE_OK, "sep cache: step: %s", floe_world_last_error(w));
        const floe_detect_stats d1 = dstats(w);
        CHECK(floe_world_contact_count(w) == 0 && d1.sep_cached - d0.sep_cached >= 4,
              "sep cache (%s): apart, and kept in the cache (%ld of %ld steps)", what[mode],
              d1.sep_cached - d0.sep_cached, d1.separated - d0.separated);
        floe_particles_view v = pview(w);
        double x[3] = {v.x[3], v.x[4], v.x[5]};
        if (mode == 0) {
            /* turn by alpha: B's lower corner (-0.5, -0.05) goes to y = 0.3 - 0.5 sin a - 0.05 cos a,
             * 0.002 below A's top face y = 0.05 */
            double lo = 0.1, hi = 0.7;
            for (int it = 0; it < 60; it++) {
                const double al = 0.5 * (lo + hi), y = 0.3 - 0.5 * sin(al) - 0.05 * cos(al);
                if (y > 0.048) lo = al; else hi = al;
            }
            const double al = 0.5 * (lo + hi), q[4] = {cos(0.5 * al), 0, 0, sin(0.5 * al)};
            CHECK(floe_world_set_pose(w, 1, NULL, q) == FLOE_OK, "sep cache: turn: %s", floe_world_last_error(w));
        } else if (mode == 1) {
            x[1] -= 0.205;
            CHECK(floe_world_set_pose(w, 1, x, NULL) == FLOE_OK, "sep cache: move: %s", floe_world_last_error(w));
        } else {
            CHECK(floe_world_set_particle_geometry(w, 1, g2) == FLOE_OK, "sep cache: shape: %s", floe_world_last_error(w));
        }
        const long rb = w->nl.rebuilds;
        CHECK(floe_world_step(w) == FLOE_OK, "sep cache: step after the change: %s", floe_world_last_error(w));
        printf("  separation cache, bar %s (list rebuilt: %s): %d contact(s) at the next step\n", what[mode],
               w->nl.rebuilds != rb ? "yes" : "no", floe_world_contact_count(w));
        CHECK(floe_world_contact_count(w) == 1, "sep cache: the bar %s touches at the next step (%d contacts)",
              what[mode], floe_world_contact_count(w));
        floe_world_destroy(w);
    }
}

int main(void) {
    setvbuf(stdout, NULL, _IOLBF, 0);
    negative_control();
    pivots_taken_over();
    lazy_equals_full();
    sep_cache_moves();
    settling_run();
    return check_summary("test_lp_resting");
}
