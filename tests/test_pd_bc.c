/* test_pd_bc.c - boundary regions of peridynamic bodies (floe_world_pd_region: fixed,
 * prescribed velocity or displacement, body force density with a ramp, ParticLS eq 37),
 * contact between the points of broken bonds, and floe_world_add_pd_body's rollback.
 *
 * 1. A bar clamped at one end (a fixed region of 3 layers = the horizon) with a body force
 *    density on its last 3 layers, ramped linearly over two fundamental periods (which
 *    leaves no free vibration in a 1D bar: the ramp is a whole number of periods of every
 *    mode of a clamped-free bar) and held: the strain between two interior cross-sections,
 *    averaged over one period, equals the static sigma/E = F/(A E) within 5 % (F = b V N
 *    over the loaded layers, A the lattice cross-section). The lattice's own error in E
 *    is 1-3 % (peridynamics/README.md), the averaging leaves < 1 %.
 * 2. A velocity region moves at exactly its velocity (to round-off), a fixed region does
 *    not move, a displacement region reaches its displacement at the end of its ramp.
 * 3. A region that selects no point, and overlapping kinematic regions, are refused.
 * 4. The energy ledger closes with a body-force region (work_body); a callback b(t, X) and
 *    a ramp give the force density expected, fixed points none.
 * 5. Broken bonds (broken_tension_only = 0, and LPS): the pairs meet by contact; two halves
 *    of a body with their connecting bonds broken bounce off each other instead of passing
 *    through; a bond broken mid-run brings its pair into the contact list at once.
 * 6. A failed floe_world_add_pd_body leaves the world unchanged.
 * 7. The scene keys: boundary entries, and an empty region is refused with file:line. */
#include "check.h"
#include "floe_pd.h"
#include "floe_scene.h"
#include "floe.h"
#include "world_read.h"

#include <stdlib.h>
#include <string.h>

static floe_pd_body *box_body(int nx, int ny, int nz, double dx, const floe_pd_material *m) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.horizon_factor = 3;
    floe_v3_set(r.hi, nx * dx, ny * dx, nz * dx);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) return NULL;
    if (floe_pd_set_material(b, m)) { floe_pd_body_destroy(b); return NULL; }
    return b;
}

static floe_world *new_world(int *mat, double safety) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.dt_safety = safety;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rock", 2200, 22.35e9, 0.25};
    *mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, *mat, *mat, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.3));
    return w;
}

static floe_pd_bc box_bc(int kind, double x0, double x1) {
    floe_pd_bc bc = floe_default_pd_bc();
    bc.kind = kind;
    floe_v3_set(bc.lo, x0, -1, -1);
    floe_v3_set(bc.hi, x1, 1, 1);
    return bc;
}

/* mean x displacement of the points of body b (first f0) whose reference x is within dx/4 of xc */
static double section_u(const floe_world *w, const floe_pd_body *b, int f0, double xc) {
    double s = 0;
    int n = 0;
    for (int i = 0; i < b->n; i++)
        if (fabs(b->X[3 * i] - xc) < 0.25 * b->dx) {
            s += pview(w).x[3 * (f0 + i)] - b->X[3 * i];
            n++;
        }
    return n ? s / n : NAN;
}

/* 1. static elongation of a clamped bar under an end body force */
static void test_bar_static(void) {
    const int model = FLOE_PD_PMB;
    const int nx = 40, ny = 8, nz = 8;
    const double dx = 1e-3, rho = 2200, E = 22.35e9, nu = 0.25;
    const double K = E / (3 * (1 - 2 * nu)), G = E / (2 * (1 + nu));
    floe_pd_material pm = model == FLOE_PD_PMB ? floe_pd_material_pmb(rho, K, 0)
                                               : floe_pd_material_lps(rho, K, G, 0, FLOE_PD_W_ONE);
    int mat;
    floe_world *w = new_world(&mat, 0.5);
    floe_pd_body *b = box_body(nx, ny, nz, dx, &pm);
    CHECK(b && floe_pd_surface_correction(b) == FLOE_OK, "bar body");
    int f0 = -1;
    CHECK(floe_world_add_pd_body(w, b, mat, NULL, &f0) == FLOE_OK, "add bar: %s", floe_world_last_error(w));
    const double L = nx * dx, c = sqrt(E / rho), T1 = 4 * L / c; /* clamped-free fundamental period */
    const double bx = 2e9;                                       /* N/m^3 */
    floe_pd_bc clamp = box_bc(FLOE_PD_BC_FIXED, -1, 3 * dx);
    floe_pd_bc load = box_bc(FLOE_PD_BC_BODY_FORCE, L - 3 * dx, 1);
    load.value[0] = bx;
    load.ramp = FLOE_PD_RAMP_LINEAR;
    load.ramp_time = 2 * T1;
    int nc = floe_world_pd_region(w, 0, &clamp), nl = floe_world_pd_region(w, 0, &load);
    CHECK(nc == 3 * ny * nz && nl == 3 * ny * nz, "regions select 3 layers each (%d, %d)", nc, nl);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    const double F = bx * nl * dx * dx * dx, A = ny * nz * dx * dx, eps = F / (A * E);
    /* gauge: cross-sections 4 dx past the clamp and 4 dx before the load */
    const double xa = 3 * dx + 4.5 * dx, xb = L - 3 * dx - 4.5 * dx;
    long nramp = (long)ceil(2 * T1 / floe_world_dt(w)), nper = (long)ceil(T1 / floe_world_dt(w));
    int rc = 0;
    for (long s = 0; s < nramp && !rc; s++) rc = floe_world_step(w);
    double sum = 0, lo = INFINITY, hi = -INFINITY;
    for (long s = 0; s < nper && !rc; s++) {
        rc = floe_world_step(w);
        double e = (section_u(w, b, f0, xb) - section_u(w, b, f0, xa)) / (xb - xa);
        sum += e;
        lo = fmin(lo, e);
        hi = fmax(hi, e);
    }
    CHECK(rc == FLOE_OK, "bar run: %s", floe_world_last_error(w));
    double mean = sum / nper;
    printf("  %s bar %dx%dx%d: %ld + %ld steps of %.3g s, strain %.5g (min %.5g, max %.5g) vs F/(AE) %.5g, "
           "balance error %.2e\n", model == FLOE_PD_PMB ? "PMB" : "LPS", nx, ny, nz, nramp, nper, floe_world_dt(w),
           mean, lo, hi, eps, floe_world_energy_balance_error(w));
    CHECK_NEAR(mean, eps, 0.05, model == FLOE_PD_PMB ? "PMB bar static strain vs F/(A E)" : "LPS bar static strain vs F/(A E)");
    CHECK(floe_world_energy_balance_error(w) < 1e-3, "energy ledger closes with the body force (%.2e)",
          floe_world_energy_balance_error(w));
    CHECK(floe_world_energy(w).work_body > 0, "the body force did work (%.3g J)", floe_world_energy(w).work_body);
    floe_world_destroy(w);
}

/* 2. fixed, velocity and displacement regions move exactly as prescribed */
static void test_kinematic(void) {
    const double dx = 1e-3, dt = 5e-8;
    floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
    floe_world_def d = floe_default_world_def();
    d.dt = dt;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rock", 2200, 22.35e9, 0.25};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.3));
    floe_pd_body *b = box_body(10, 4, 4, dx, &pm);
    int f0 = -1;
    CHECK(b && floe_world_add_pd_body(w, b, mat, NULL, &f0) == FLOE_OK, "add body: %s", floe_world_last_error(w));
    const double v[3] = {0.05, -0.02, 0.01}, u[3] = {0, 2e-6, -1e-6};
    const long nramp = 50, nsteps = 200;
    floe_pd_bc vel = box_bc(FLOE_PD_BC_VELOCITY, -1, 2 * dx);
    floe_v3_copy(vel.value, v);
    floe_pd_bc fix = box_bc(FLOE_PD_BC_FIXED, 8 * dx, 1);
    floe_pd_bc dis = box_bc(FLOE_PD_BC_DISPLACEMENT, 4 * dx, 5 * dx);
    floe_v3_copy(dis.value, u);
    dis.ramp = FLOE_PD_RAMP_LINEAR;
    dis.ramp_time = nramp * dt;
    int nv = floe_world_pd_region(w, 0, &vel), nf = floe_world_pd_region(w, 0, &fix), nd = floe_world_pd_region(w, 0, &dis);
    CHECK(nv == 32 && nf == 32 && nd == 16, "regions of 2, 2 and 1 layers (%d, %d, %d)", nv, nf, nd);
    CHECK(floe_world_pd_region_count(w) == 3 && floe_world_pd_region_points(w, 2) == 16 &&
              floe_world_pd_region_points(w, 3) == -1, "region accessors");
    int rc = floe_world_prepare(w);
    CHECK(rc == FLOE_OK && floe_world_dt(w) == dt, "prepare: %s", floe_world_last_error(w));
    for (long s = 0; s < nsteps && !rc; s++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "run: %s", floe_world_last_error(w));
    double t = floe_world_time(w), ev = 0, evel = 0, ef = 0, ed = 0, emid = 0;
    for (int i = 0; i < b->n; i++) {
        const double *X = b->X + 3 * i, *x = pview(w).x + 3 * (f0 + i), *vi = pview(w).v + 3 * (f0 + i);
        for (int k = 0; k < 3; k++) {
            if (X[0] < 2 * dx) {
                ev = fmax(ev, fabs(x[k] - (X[k] + v[k] * t)));
                evel = fmax(evel, fabs(vi[k] - v[k]));
            } else if (X[0] > 8 * dx) ef = fmax(ef, fabs(x[k] - X[k]) + fabs(vi[k]));
            else if (X[0] > 4 * dx && X[0] < 5 * dx) ed = fmax(ed, fabs(x[k] - (X[k] + u[k])));
            else emid = fmax(emid, fabs(x[k] - X[k]));
        }
    }
    printf("  kinematic regions after %ld steps: velocity region off by %.2g m (v by %.2g m/s), fixed moved %.2g, "
           "displacement region off by %.2g m (u = %.1g m), free points moved up to %.2g m\n",
           nsteps, ev, evel, ef, ed, floe_v3_norm(u), emid);
    CHECK(ev < 1e-15 && evel == 0, "the velocity region moves at exactly its velocity (%.2g m, %.2g m/s)", ev, evel);
    CHECK(ef == 0, "the fixed region does not move (%.2g)", ef);
    CHECK(ed < 1e-15, "the displacement region reaches its displacement at the end of the ramp (%.2g m)", ed);
    CHECK(emid > 1e-7, "the free points between follow (%.2g m)", emid);
    CHECK(floe_world_energy_balance_error(w) < 1e-3, "energy ledger with kinematic regions (%.2e)",
          floe_world_energy_balance_error(w));
    floe_world_destroy(w);
}

/* 3. bad regions are refused with a message */
static void test_refused(void) {
    int mat;
    floe_world *w = new_world(&mat, 0.2);
    floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
    floe_pd_body *b = box_body(6, 3, 3, 1e-3, &pm);
    CHECK(b && floe_world_add_pd_body(w, b, mat, NULL, NULL) == FLOE_OK, "add body");
    floe_pd_bc none = box_bc(FLOE_PD_BC_FIXED, 0.5, 0.6); /* beyond the body */
    int r = floe_world_pd_region(w, 0, &none);
    CHECK(r == -FLOE_EINVAL && strstr(floe_world_last_error(w), "selects no point"), "empty region refused: %d '%s'", r,
          floe_world_last_error(w));
    CHECK(floe_world_pd_region(w, 1, &none) == -FLOE_EINVAL && strstr(floe_world_last_error(w), "out of range"),
          "body index out of range refused");
    floe_pd_bc a = box_bc(FLOE_PD_BC_FIXED, -1, 2e-3), c = box_bc(FLOE_PD_BC_VELOCITY, 1e-3, 3e-3);
    CHECK(floe_world_pd_region(w, 0, &a) == 18, "fixed region of 2 layers");
    r = floe_world_pd_region(w, 0, &c);
    CHECK(r == -FLOE_EINVAL && strstr(floe_world_last_error(w), "shares 9 points"), "overlapping kinematic regions "
          "refused: '%s'", floe_world_last_error(w));
    floe_pd_bc f = box_bc(FLOE_PD_BC_BODY_FORCE, 1e-3, 3e-3);
    CHECK(floe_world_pd_region(w, 0, &f) == 18, "a body-force region may overlap a fixed one");
    floe_pd_bc dnr = box_bc(FLOE_PD_BC_DISPLACEMENT, 4e-3, 1);
    CHECK(floe_world_pd_region(w, 0, &dnr) == -FLOE_EINVAL && strstr(floe_world_last_error(w), "needs a ramp"),
          "displacement without a ramp refused");
    floe_pd_bc bad = box_bc(FLOE_PD_BC_BODY_FORCE, 4e-3, 1);
    bad.ramp = FLOE_PD_RAMP_EXP;
    CHECK(floe_world_pd_region(w, 0, &bad) == -FLOE_EINVAL && strstr(floe_world_last_error(w), "ramp_time"),
          "a ramp without ramp_time refused");
    bad.kind = 9;
    CHECK(floe_world_pd_region(w, 0, &bad) == -FLOE_EINVAL, "unknown kind refused");
    CHECK(floe_world_pd_region_count(w) == 2, "refused regions leave nothing behind (%d)", floe_world_pd_region_count(w));
    floe_world_destroy(w);
}

/* 4b. body-force values: a callback b(t, X), a ramp at t = 0, fixed points get none */
static void force_fn(double t, const double X[3], double b[3], void *user) {
    (void)t;
    const double *s = user;
    floe_v3_set(b, s[0] * X[0], s[1], 0);
}

static void test_body_force_values(void) {
    int mat;
    floe_world *w = new_world(&mat, 0.2);
    floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
    floe_pd_body *b = box_body(6, 3, 3, 1e-3, &pm);
    int f0;
    CHECK(b && floe_world_add_pd_body(w, b, mat, NULL, &f0) == FLOE_OK, "add body");
    double scale[2] = {1e12, 2e8};
    floe_pd_bc cb = box_bc(FLOE_PD_BC_BODY_FORCE, -1, 3e-3);
    cb.force_fn = force_fn;
    cb.force_user = scale;
    floe_pd_bc ramped = box_bc(FLOE_PD_BC_BODY_FORCE, 3e-3, 1);
    ramped.value[2] = 1e9;
    ramped.ramp = FLOE_PD_RAMP_LINEAR;
    ramped.ramp_time = 1e-6;
    floe_pd_bc fix = box_bc(FLOE_PD_BC_FIXED, -1, 1e-3);
    CHECK(floe_world_pd_region(w, 0, &cb) == 27 && floe_world_pd_region(w, 0, &ramped) == 27 &&
              floe_world_pd_region(w, 0, &fix) == 9, "three regions");
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare");
    /* at rest in the reference configuration the bond forces vanish: f is the body force */
    double err = 0, big = 0;
    for (int i = 0; i < b->n; i++) {
        const double *X = b->X + 3 * i, *f = pview(w).f + 3 * (f0 + i);
        double want[3] = {0, 0, 0};
        if (X[0] > 1e-3 && X[0] < 3e-3) floe_v3_set(want, scale[0] * X[0] * b->V[i], scale[1] * b->V[i], 0);
        for (int k = 0; k < 3; k++) {
            err = fmax(err, fabs(f[k] - want[k]));
            big = fmax(big, fabs(want[k]));
        }
    }
    CHECK(big > 0 && err <= 1e-12 * big, "callback force density b(X) V on the free points of its region, none on "
          "fixed ones, the ramp at 0 at t = 0 (error %.2g of %.2g N)", err, big);
    floe_world_destroy(w);
}

/* a body of two 4x4x4 blocks, gap between their facing planes g dx (bonds across: g < 3) */
static floe_pd_body *two_blocks(double dx, double g, const floe_pd_material *pm) {
    double X[3 * 128], V[128];
    int n = 0;
    for (int h = 0; h < 2; h++)
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                for (int k = 0; k < 4; k++) {
                    floe_v3_set(X + 3 * n, (i + h * (3 + g)) * dx, j * dx, k * dx);
                    V[n++] = dx * dx * dx;
                }
    floe_pd_body *b = NULL;
    if (floe_pd_body_create_points(&b, 3, n, X, V, 3 * dx, dx, 0)) return NULL;
    if (floe_pd_set_material(b, pm)) { floe_pd_body_destroy(b); return NULL; }
    return b;
}

/* 5a. two halves whose connecting bonds are broken meet by contact (broken_tension_only = 0) */
static void test_broken_contact(void) {
    const double dx = 1e-3, vx = 5.0;
    for (int variant = 0; variant < 2; variant++) {
        int mat;
        floe_world *w = new_world(&mat, 0.2);
        floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
        pm.broken_tension_only = 0;
        floe_pd_body *b = two_blocks(dx, 2.0, &pm);
        CHECK(b != NULL, "two blocks");
        if (!b) { floe_world_destroy(w); return; }
        int across = 0;
        for (int i = 0; i < b->n; i++)
            for (int64_t k = b->off[i]; k < b->off[i + 1]; k++)
                if ((i < 64) != (b->partner[k] < 64)) {
                    across++;
                    if (variant == 1) { b->broken[k] = 1; b->nbroken++; }
                }
        int f0;
        CHECK(floe_world_add_pd_body(w, b, mat, NULL, &f0) == FLOE_OK, "add: %s", floe_world_last_error(w));
        for (int i = 0; i < b->n; i++) set_vel(w, f0 + i, 0, i < 64 ? vx : -vx);
        int rc = floe_world_prepare(w), maxc = 0;
        double gap_min = INFINITY, va = 0;
        long steps = (long)(4 * dx / vx / floe_world_dt(w));
        for (long s = 0; s < steps && !rc; s++) {
            rc = floe_world_step(w);
            if (floe_world_contact_count(w) > maxc) maxc = floe_world_contact_count(w);
            double xa = -INFINITY, xb = INFINITY; /* facing planes: mean x of the inner layers */
            for (int i = 0; i < b->n; i++) {
                if (i < 64 && b->X[3 * i] > 2.5 * dx) xa = fmax(xa, pview(w).x[3 * (f0 + i)]);
                if (i >= 64 && b->X[3 * i] < 5.5 * dx) xb = fmin(xb, pview(w).x[3 * (f0 + i)]);
            }
            gap_min = fmin(gap_min, xb - xa);
        }
        CHECK(rc == FLOE_OK, "run: %s", floe_world_last_error(w));
        va = 0;
        for (int i = 0; i < 64; i++) va += pview(w).v[3 * (f0 + i)] / 64;
        printf("  %s (%d bonds across): %ld steps, max contacts %d, closest approach of the faces %.3g dx, "
               "half A ends at vx %.3g m/s (started %.3g)\n", variant ? "connecting bonds broken" : "intact body",
               across, steps, maxc, gap_min / dx, va, vx);
        if (variant == 1) {
            CHECK(maxc > 0, "the broken pairs meet by contact (max contacts %d)", maxc);
            CHECK(va < -0.5 * vx, "the halves bounce off each other (vx of half A %.3g m/s)", va);
            CHECK(gap_min > 0.5 * dx, "the faces never pass through each other (closest %.3g dx)", gap_min / dx);
        } else {
            CHECK(maxc == 0, "intact bonds: no contact between family members (%d)", maxc);
        }
        floe_world_destroy(w);
    }
}

/* 5b. a bond broken mid-run brings its pair into the contact list at the next evaluation */
static void test_broken_joins_list(void) {
    const double dx = 1e-3;
    for (int tension_only = 0; tension_only < 2; tension_only++) {
        floe_world_def d = floe_default_world_def();
        d.skin = 0.5 * dx; /* reach 2R + skin = 1.74 dx covers the sqrt(2) dx diagonals */
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"rock", 2200, 22.35e9, 0.25};
        int mat = floe_world_add_material(w, &m);
        floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.3));
        floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
        pm.broken_tension_only = tension_only;
        floe_pd_body *b = box_body(4, 4, 4, dx, &pm);
        int f0;
        CHECK(b && floe_world_add_pd_body(w, b, mat, NULL, &f0) == FLOE_OK, "add");
        CHECK(floe_world_prepare(w) == FLOE_OK && floe_world_step(w) == FLOE_OK, "first step");
        /* point 0 at (0.5, 0.5, 0.5) dx and point 5 at (1.5, 1.5, 0.5) dx: a diagonal bond */
        int64_t k = floe_pd_bond_index(b, 0, 5), k1 = floe_pd_bond_index(b, 0, 1);
        CHECK(k >= 0 && fabs(b->len[k] - sqrt(2) * dx) < 1e-12 && k1 >= 0, "diagonal bond found");
        int listed0 = 0, listed1 = 0, near0 = 0, near1 = 0;
        const int *pi, *pj;
        for (int q = 0, np = floe_world_neighbor_pairs(w, &pi, &pj); q < np; q++) {
            listed0 |= pi[q] == f0 && pj[q] == f0 + 5;
            near0 |= pi[q] == f0 && pj[q] == f0 + 1;
        }
        b->broken[k] = 1; /* as the material would break them */
        b->broken[k1] = 1;
        b->nbroken += 2;
        long rb = nstats(w).rebuilds;
        CHECK(floe_world_step(w) == FLOE_OK, "step after the breakage");
        for (int q = 0, np = floe_world_neighbor_pairs(w, &pi, &pj); q < np; q++) {
            listed1 |= pi[q] == f0 && pj[q] == f0 + 5;
            near1 |= pi[q] == f0 && pj[q] == f0 + 1;
        }
        printf("  broken_tension_only %d: diagonal pair listed %d -> %d, nearest pair %d -> %d, rebuilds +%ld\n",
               tension_only, listed0, listed1, near0, near1, nstats(w).rebuilds - rb);
        CHECK(!listed0 && !near0, "bonded pairs are not in the contact list");
        if (!tension_only) {
            CHECK(listed1 && nstats(w).rebuilds == rb + 1, "the broken diagonal pair enters the list at once");
            CHECK(!near1, "the broken nearest pair (overlapping in the reference) stays out");
        } else {
            CHECK(!listed1 && nstats(w).rebuilds == rb, "a broken PMB bond that still pushes keeps its pair out, no rebuild");
        }
        floe_world_destroy(w);
    }
}

/* 6. a failed add leaves the world unchanged */
static void test_rollback(void) {
    int mat;
    floe_world *w = new_world(&mat, 0.2);
    floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
    floe_pd_body *b = box_body(4, 4, 4, 1e-3, &pm);
    CHECK(b && floe_world_add_pd_body(w, b, mat, NULL, NULL) == FLOE_OK, "first body");
    CHECK(floe_world_prepare(w) == FLOE_OK && floe_world_step(w) == FLOE_OK, "runs");
    int n0 = floe_world_particle_count(w), g0 = floe_world_geometry_count(w), pd0 = floe_world_pd_body_count(w), prep0 = floe_world_is_prepared(w);
    /* a body whose point 5 has an infinite volume: points 0-4 are added, then it fails */
    double X[3 * 8], V[8];
    for (int i = 0; i < 8; i++) {
        floe_v3_set(X + 3 * i, 0.01 + 1e-3 * i, 0, 0);
        V[i] = i == 5 ? INFINITY : 1e-9;
    }
    floe_pd_body *bad = NULL;
    CHECK(floe_pd_body_create_points(&bad, 3, 8, X, V, 3e-3, 1e-3, 0) == FLOE_OK && floe_pd_set_material(bad, &pm) == FLOE_OK,
          "bad body");
    int rc = floe_world_add_pd_body(w, bad, mat, NULL, NULL);
    printf("  failed add: '%s'\n", floe_world_last_error(w));
    CHECK(rc == FLOE_EINVAL && strstr(floe_world_last_error(w), "point 5"), "the add fails at point 5 (%d)", rc);
    CHECK(floe_world_particle_count(w) == n0 && floe_world_geometry_count(w) == g0 && floe_world_pd_body_count(w) == pd0 && floe_world_is_prepared(w) == prep0,
          "the world is unchanged (particles %d/%d, geometries %d/%d, bodies %d/%d)", floe_world_particle_count(w), n0,
          floe_world_geometry_count(w), g0, floe_world_pd_body_count(w), pd0);
    CHECK(floe_world_step(w) == FLOE_OK, "and still runs: %s", floe_world_last_error(w));
    floe_pd_body *bad2 = box_body(2, 2, 2, 1e-3, &pm);
    double vnan[3] = {NAN, 0, 0};
    CHECK(floe_world_add_pd_body(w, bad2, mat, vnan, NULL) == FLOE_EINVAL && floe_world_particle_count(w) == n0,
          "a non-finite velocity is refused before anything is added");
    floe_world_destroy(w);
}

/* 7. scene keys */
static const char *scene_fmt =
    "dimension: 3\n"
    "time: {duration: 2.0e-6}\n"
    "materials:\n"
    "  - {name: rock, density: 2200, young: 2.235e10, poisson: 0.25}\n"
    "laws:\n"
    "  - {materials: [rock, rock], model: hertz_mindlin, restitution: 0.8}\n"
    "peridynamics:\n"
    "  - region: {box: {min: [0, 0, 0], max: [0.01, 0.003, 0.003]}}\n"
    "    spacing: 0.001\n"
    "    material: {model: pmb, density: 2200, bulk_modulus: 1.49e10}\n"
    "    contact_material: rock\n"
    "    boundary:\n"
    "      - {region: {box: {min: [0, 0, 0], max: [0.002, 1, 1]}}, fixed: true}\n"
    "      - {region: {shape: {sphere: {radius: 0.0015}}, position: [0.01, 0.0015, 0.0015]}, body_force: [1.0e9, 0, 0],\n"
    "         ramp: {exp: 1.0e-6}}\n"
    "      - {region: {box: {min: [%s, 0, 0], max: [%s, 1, 1]}}, velocity: [0.1, 0, 0]}\n";

static void test_scene(void) {
    char text[2048], err[1024];
    floe_world *w = NULL;
    snprintf(text, sizeof text, scene_fmt, "0.005", "0.006");
    int rc = floe_scene_load_ex("bc.yaml", text, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "scene with boundary regions: %s", err);
    if (w) {
        CHECK(floe_world_pd_region_count(w) == 3 && floe_world_pd_region_points(w, 0) == 18 &&
                  floe_world_pd_region_points(w, 2) == 9,
              "three regions (%d points fixed, %d pushed, %d moving)", floe_world_pd_region_points(w, 0),
              floe_world_pd_region_points(w, 1), floe_world_pd_region_points(w, 2));
        CHECK(floe_world_run(w, 2e-6, NULL, NULL) == FLOE_OK, "runs: %s", floe_world_last_error(w));
        CHECK(floe_world_energy(w).work_body > 0, "the body force works (%.3g J)", floe_world_energy(w).work_body);
        floe_world_destroy(w);
        w = NULL;
    }
    snprintf(text, sizeof text, scene_fmt, "0.02", "0.03"); /* beyond the body */
    rc = floe_scene_load_ex("bc.yaml", text, NULL, 0, &w, NULL, err, sizeof err);
    printf("  empty region: %s\n", err);
    CHECK(rc == FLOE_EINVAL && strstr(err, "bc.yaml:16:") && strstr(err, "peridynamics[0].boundary[2]") &&
              strstr(err, "selects no point"),
          "an empty boundary region is refused at its line: %s", err);
    floe_world_destroy(w);
}

int main(void) {
    test_bar_static();
    test_kinematic();
    test_refused();
    test_body_force_values();
    test_broken_contact();
    test_broken_joins_list();
    test_rollback();
    test_scene();
    return check_summary("test_pd_bc");
}
