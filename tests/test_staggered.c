/* test_staggered.c - the staggered multi-scale PD-DEM scheme (000 §3.2-3.3, Algorithm 2;
 * core/world/world.c step_staggered):
 *   1. a PD block on a fixed wall pressed by four kinematic DEM spheres (a small 000 §4.2):
 *      the wall force of staggered m = 1 equals the monolithic one to rounding, and the
 *      multi-scale m = 2 (PD sub-cycled) and k = 2 (PD every other step) runs agree with
 *      the monolithic run within 2 % (RMS over the run, relative to the RMS force);
 *   2. body forces of hybrid points are counted once: a PD body falling under gravity
 *      keeps the exact parabola with m = 3 and k = 3;
 *   3. order of convergence: PD bonds (fast) plus a soft spring body force (slow) on a PD
 *      bar, error against a fine monolithic reference falls 4x when dt halves;
 *   4. stability of the sub-cycle: a two-point PD body (one bond, exact limit 2/w from the
 *      linearised bond force) with the DEM step 4 x 0.9 (2/w) and m = 4 runs, 4 x 1.1 stops;
 *   5. the energy ledger: monolithic and m = 1 close to 1e-6; the multi-scale runs book
 *      the integration error of multiple time stepping (the contact forces act as two
 *      impulses around the PD sub-steps; here they are not much slower than the bonds),
 *      measured 2e-3 (m = 2) and 5e-4 (k = 2), bounded at 5e-3. */
#include "check.h"
#include "floe_pd.h"
#include "world_internal.h" /* internal: unit test of the staggered integrator: poisons its scratch (w->ibuf) */
#include "world_read.h"

#include <stdlib.h>
#include <string.h>

static floe_pd_body *block(int nx, int ny, int nz, double dx, double z0, int lps) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.horizon_factor = 2; /* 000 Table 1: delta = 2 dx */
    floe_v3_set(r.lo, -0.5 * nx * dx, -0.5 * ny * dx, z0);
    floe_v3_set(r.hi, 0.5 * nx * dx, 0.5 * ny * dx, z0 + nz * dx);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) return NULL;
    const double E = 1e8, nu = 0.25, K = E / (3 * (1 - 2 * nu)), G = E / (2 * (1 + nu));
    floe_pd_material m = lps ? floe_pd_material_lps(1100, K, G, 0, FLOE_PD_W_ONE) : floe_pd_material_pmb(1100, K, 0);
    if (floe_pd_set_material(b, &m)) { floe_pd_body_destroy(b); return NULL; }
    return b;
}

typedef struct press_result {
    int n;
    double *f;  /* wall force at each sample */
    double balance, cpu_evals;
    long steps;
} press_result;

/* the PD block (6 x 6 x 3 points, dx 2 cm, LPS, E 1e8 Pa, rho 1100, 000 Table 1) on a wall
 * at z = 0, four spheres R = 2 cm pressing at 5 cm/s; wall force sampled every 1e-4 s */
static press_result press(int scheme, int sub, int every, double dt, double t_end) {
    press_result res = {0, NULL, 0, 0, 0};
    const double dx = 0.02, R = 0.02, E = 1e8, nu = 0.25;
    floe_world_def d = floe_default_world_def();
    d.dt = dt;
    d.pd_dem = scheme;
    d.pd_substeps = sub;
    d.pd_every = every;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rubber", 1100, E, nu};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&m, &m, 1.0, 0.0));
    floe_pd_body *b = block(6, 6, 3, dx, 0, 1);
    const double Rpd = cbrt(3.0 * dx * dx * dx / (4 * M_PI));
    /* the bottom points touch the wall: shift the block up by Rpd - dx/2 */
    for (int i = 0; i < b->n; i++) b->X[3 * i + 2] += Rpd - 0.5 * dx;
    int f0 = 0;
    floe_world_add_pd_body(w, b, mat, NULL, &f0);
    double ztop = 0;
    for (int i = 0; i < b->n; i++) ztop = fmax(ztop, b->X[3 * i + 2]);
    int gs = floe_world_add_geometry(w, floe_sphere_create(R));
    for (int a = 0; a < 4; a++) {
        floe_particle_def s = floe_default_particle_def();
        s.geometry = gs;
        s.material = mat;
        s.motion = FLOE_KINEMATIC;
        floe_v3_set(s.x, (a & 1 ? 1 : -1) * 0.03, (a & 2 ? 1 : -1) * 0.03, ztop + Rpd + R);
        floe_v3_set(s.v, 0, 0, -0.05);
        floe_world_add_particle(w, &s);
    }
    double p0[3] = {0, 0, 0}, n0[3] = {0, 0, 1};
    int wall = floe_world_add_wall(w, p0, n0, mat, FLOE_FIXED);
    int rc = floe_world_prepare(w);
    CHECK(rc == FLOE_OK, "press prepare: %s", floe_world_last_error(w));
    const double sample = 1e-4;
    int ns = (int)(t_end / sample + 0.5);
    res.f = calloc((size_t)ns + 1, sizeof *res.f);
    double next = sample;
    while (!rc && floe_world_time(w) < t_end - 1e-12) {
        rc = floe_world_step(w);
        if (floe_world_time(w) >= next - 1e-12 && res.n < ns) {
            res.f[res.n++] = pview(w).f[3 * wall + 2];
            next += sample;
        }
    }
    CHECK(rc == FLOE_OK, "press run (scheme %d, m %d, k %d): %s", scheme, sub, every, floe_world_last_error(w));
    res.balance = floe_world_energy_balance_error(w);
    floe_step_stats st;
    floe_world_step_stats(w, &st);
    res.steps = st.accepted;
    res.cpu_evals = (double)st.pd_evaluations;
    floe_world_destroy(w);
    return res;
}

static double rms_diff(const press_result *a, const press_result *b, double *rms) {
    double s = 0, r = 0;
    int n = a->n < b->n ? a->n : b->n;
    for (int k = 0; k < n; k++) {
        s += (a->f[k] - b->f[k]) * (a->f[k] - b->f[k]);
        r += b->f[k] * b->f[k];
    }
    *rms = sqrt(r / n);
    return sqrt(s / n) / *rms;
}

static void test_press(void) {
    const double dt = 2e-5, T = 0.02;
    press_result mono = press(FLOE_PD_DEM_MONOLITHIC, 1, 1, dt, T);
    press_result s1 = press(FLOE_PD_DEM_STAGGERED, 1, 1, dt, T);
    press_result m2 = press(FLOE_PD_DEM_STAGGERED, 2, 1, 2 * dt, T);
    press_result k2 = press(FLOE_PD_DEM_STAGGERED, 1, 2, 0.5 * dt, T);
    double rms, d1 = rms_diff(&s1, &mono, &rms), d2 = rms_diff(&m2, &mono, &rms), dk = rms_diff(&k2, &mono, &rms);
    printf("  press: monolithic dt %.1e s: final wall force %.4g N (RMS %.4g N), %ld steps, balance %.2e\n", dt,
           mono.f[mono.n - 1], rms, mono.steps, mono.balance);
    printf("  staggered m = 1: RMS difference %.2e, balance %.2e\n", d1, s1.balance);
    printf("  staggered m = 2 (DEM %.1e s, PD %.1e s): RMS difference %.2e, final %.4g N, %ld steps, %.0f PD evaluations, "
           "balance %.2e\n", 2 * dt, dt, d2, m2.f[m2.n - 1], m2.steps, m2.cpu_evals, m2.balance);
    printf("  staggered k = 2 (DEM %.1e s, PD %.1e s): RMS difference %.2e, final %.4g N, balance %.2e\n", 0.5 * dt, dt,
           dk, k2.f[k2.n - 1], k2.balance);
    CHECK(mono.f[mono.n - 1] < -10, "the spheres push the wall down (%.3g N)", mono.f[mono.n - 1]);
    CHECK(d1 < 1e-9, "staggered m = 1 is the monolithic scheme to rounding (%.2e)", d1);
    CHECK(d2 < 0.02, "staggered m = 2 wall force within 2 %% RMS of monolithic (%.2e)", d2);
    CHECK(dk < 0.02, "staggered k = 2 wall force within 2 %% RMS of monolithic (%.2e)", dk);
    CHECK(m2.cpu_evals == 2 * m2.steps, "m = 2: two PD evaluations per step (%.0f for %ld)", m2.cpu_evals, m2.steps);
    CHECK(mono.balance < 1e-6 && s1.balance < 1e-6, "energy ledgers close: monolithic %.1e, m = 1 %.1e", mono.balance,
          s1.balance);
    CHECK(m2.balance < 5e-3 && k2.balance < 5e-3, "multi-scale energy error bounded: m = 2 %.1e, k = 2 %.1e", m2.balance,
          k2.balance);
    free(mono.f);
    free(s1.f);
    free(m2.f);
    free(k2.f);
}

/* gravity on a free-falling PD body is counted once: v_cm(t) = -g t exactly (counted
 * twice it would be -2 g t) */
static void test_gravity_once(void) {
    for (int mode = 0; mode < 2; mode++) {
        floe_world_def d = floe_default_world_def();
        d.pd_dem = FLOE_PD_DEM_STAGGERED;
        d.pd_substeps = mode ? 1 : 3;
        d.pd_every = mode ? 3 : 1;
        d.dt = 1e-6;
        floe_v3_set(d.gravity, 0, 0, -9.81);
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"rubber", 1100, 1e8, 0.25};
        floe_world_add_material(w, &m);
        floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 1.0, 0.0));
        floe_pd_body *b = block(4, 4, 2, 0.02, 1.0, 0);
        floe_world_add_pd_body(w, b, 0, NULL, NULL);
        int rc = floe_world_prepare(w);
        for (int s = 0; s < 300 && !rc; s++) rc = floe_world_step(w);
        double v = 0, t = floe_world_time(w);
        for (int i = 0; i < pview(w).n; i++) v += pview(w).v[3 * i + 2] / pview(w).n;
        printf("  free fall, staggered %s 3: v_cm %.12e m/s, -g t = %.12e m/s\n", mode ? "k =" : "m =", v, -9.81 * t);
        CHECK(rc == FLOE_OK, "free fall: %s", floe_world_last_error(w));
        CHECK(fabs(v + 9.81 * t) < 1e-12 * 9.81 * t, "gravity counted once (%s 3): rel. error %.2e", mode ? "k" : "m",
              fabs(v + 9.81 * t) / (9.81 * t));
        floe_world_destroy(w);
    }
}

/* PD bar (8 x 3 x 3 points, PMB) with a soft spring -ks (x - X) on every point as the slow
 * force and an initial velocity field; positions at t = T against a fine monolithic run */
typedef struct spring { double ks; const double *X; int f0; } spring;
static void spring_force(const floe_world *w, int i, double t, double f[3], double torque[3], void *user) {
    const spring *s = user;
    (void)t;
    (void)torque;
    for (int a = 0; a < 3; a++) f[a] = -s->ks * (pview(w).x[3 * i + a] - s->X[3 * (i - s->f0) + a]);
}

static void bar_run(int scheme, int sub, double dt, double T, double *xout, int *n) {
    floe_world_def d = floe_default_world_def();
    d.pd_dem = scheme;
    d.pd_substeps = sub;
    d.dt = dt;
    d.allow_unstable_dt = 1;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rubber", 1100, 1e8, 0.25};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 1.0, 0.0));
    floe_pd_body *b = block(8, 3, 3, 0.02, 0, 0);
    double *X = malloc(3 * (size_t)b->n * sizeof *X);
    memcpy(X, b->X, 3 * (size_t)b->n * sizeof *X);
    int f0 = 0;
    floe_world_add_pd_body(w, b, 0, NULL, &f0);
    spring sp = {0, X, f0};
    /* slow spring: period 40x the fast PD period scale */
    double mass = 1100 * 0.02 * 0.02 * 0.02;
    sp.ks = mass * pow(2 * M_PI / (40 * 6e-5), 2);
    floe_world_set_body_force(w, spring_force, &sp);
    for (int i = 0; i < pview(w).n; i++) { /* a smooth velocity field */
        double xr = X[3 * i] / 0.16;
        floe_world_set_velocity(w, i, (const double[3]){0.05 * sin(M_PI * xr), 0, 0.05 * cos(M_PI * xr)}, NULL);
    }
    int rc = floe_world_prepare(w);
    long steps = (long)(T / dt + 0.5);
    for (long s = 0; s < steps && !rc; s++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "bar run: %s", floe_world_last_error(w));
    memcpy(xout, pview(w).x, 3 * (size_t)pview(w).n * sizeof *xout);
    *n = pview(w).n;
    floe_world_destroy(w);
    free(X);
}

static void test_order(void) {
    const double T = 2.4e-3;
    int n = 0;
    double *ref = malloc(3 * 72 * sizeof *ref), *x = malloc(3 * 72 * sizeof *x);
    bar_run(FLOE_PD_DEM_MONOLITHIC, 1, 1e-7, T, ref, &n);
    double err[3];
    const double dts[3] = {8e-6, 4e-6, 2e-6};
    for (int r = 0; r < 3; r++) {
        bar_run(FLOE_PD_DEM_STAGGERED, 2, dts[r], T, x, &n);
        err[r] = 0;
        for (int k = 0; k < 3 * n; k++) err[r] = fmax(err[r], fabs(x[k] - ref[k]));
    }
    double p1 = log2(err[0] / err[1]), p2 = log2(err[1] / err[2]);
    printf("  staggered m = 2 on a PD bar with a slow spring: max position error %.3e %.3e %.3e m (order %.3f %.3f)\n",
           err[0], err[1], err[2], p1, p2);
    CHECK(fabs(p2 - 2) < 0.15, "staggered multi-scale is second order (%.3f; want 2 +- 0.15)", p2);
    free(ref);
    free(x);
}

/* two PD points, one bond: the sub-cycle is stable below 2/w and detected above */
static void test_substep_stability(void) {
    const double dx = 0.02, X[6] = {0, 0, 0, dx, 0, 0}, V[2] = {dx * dx * dx, dx * dx * dx};
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create_points(&b, 3, 2, X, V, 2 * dx, 0, 0) == FLOE_OK, "two-point body");
    floe_pd_material pm = floe_pd_material_pmb(1100, 6.67e7, 0);
    floe_pd_set_material(b, &pm);
    /* the bond stiffness by a finite difference of the bond force */
    double x[6], f[6] = {0};
    memcpy(x, X, sizeof x);
    const double h = 1e-9;
    x[3] += h;
    floe_pd_forces_nobreak(b, x, f);
    double k = -f[3] / h, m = 1100 * V[0], wmax = sqrt(2 * k / m), crit = 2 / wmax;
    printf("  two-point PD body: bond stiffness %.4g N/m, exact limit 2/w = %.4g s, nodal estimate %.4g s\n", k, crit,
           floe_pd_dt_nodal(b));
    floe_pd_body_destroy(b);
    for (int pass = 0; pass < 2; pass++) {
        double fac = pass ? 1.1 : 0.9;
        floe_pd_body_create_points(&b, 3, 2, X, V, 2 * dx, 0, 0);
        floe_pd_set_material(b, &pm);
        floe_world_def d = floe_default_world_def();
        d.pd_dem = FLOE_PD_DEM_STAGGERED;
        d.pd_substeps = 4;
        d.dt = 4 * fac * crit;
        d.allow_unstable_dt = 1;
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material mt = {"rubber", 1100, 1e8, 0.25};
        floe_world_add_material(w, &mt);
        floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&mt, &mt, 1.0, 0.0));
        floe_world_add_pd_body(w, b, 0, NULL, NULL);
        set_vel(w, 0, 0, -1e-4); /* stretch the bond */
        set_vel(w, 1, 0, 1e-4);
        int rc = floe_world_prepare(w);
        for (int s = 0; s < 3000 && !rc; s++) rc = floe_world_step(w);
        if (!pass)
            CHECK(rc == FLOE_OK && fabs(pview(w).x[3] - pview(w).x[0] - dx) < 1e-3 * dx,
                  "PD sub-step 0.9 x 2/w (m = 4, DEM step 3.6 x 2/w) runs bounded: %s", floe_world_last_error(w));
        else {
            printf("  PD sub-step 1.1 x 2/w: %s\n", floe_world_last_error(w));
            CHECK(rc == FLOE_EUNSTABLE && strstr(floe_world_last_error(w), "particle") && isfinite(pview(w).x[0]),
                  "PD sub-step 1.1 x 2/w detected (rc %d)", rc);
        }
        floe_world_destroy(w);
    }
}

/* a sphere touching FIXED points of a PD body: staggered m = 1 must equal monolithic (the
 * fixed points' positions at the step start were once left unset, giving them a garbage
 * velocity in the contact evaluation; the scratch buffer is poisoned to expose that) */
static double fixed_touch(int scheme) {
    const double dx = 0.02;
    floe_world_def d = floe_default_world_def();
    d.dt = 2e-6;
    d.pd_dem = scheme;
    d.pd_substeps = 1;
    d.pd_every = 1;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rubber", 1100, 1e8, 0.25};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&m, &m, 0.3, 0.0));
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.horizon_factor = 2;
    floe_v3_set(r.lo, -0.06, -0.06, 0);
    floe_v3_set(r.hi, 0.06, 0.06, 0.06);
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create(&b, &r) == FLOE_OK, "fixed-touch body");
    floe_pd_material pm = floe_pd_material_pmb(1100, 1e8 / 1.5, 0);
    floe_pd_set_material(b, &pm);
    int f0 = 0;
    floe_world_add_pd_body(w, b, mat, NULL, &f0);
    floe_pd_bc bc = floe_default_pd_bc();
    bc.kind = FLOE_PD_BC_FIXED;
    floe_v3_set(bc.lo, -1, -1, 0.04);
    floe_v3_set(bc.hi, 1, 1, 1);
    CHECK(floe_world_pd_region(w, 0, &bc) > 0, "fixed top layer");
    double ztop = 0;
    for (int i = 0; i < b->n; i++) ztop = fmax(ztop, b->X[3 * i + 2]);
    const double Rpd = cbrt(3.0 * dx * dx * dx / (4 * M_PI));
    int gs = floe_world_add_geometry(w, floe_sphere_create(0.02));
    floe_particle_def s = floe_default_particle_def();
    s.geometry = gs;
    s.material = mat;
    floe_v3_set(s.x, 0.01, 0.01, ztop + Rpd + 0.02 - 1e-4);
    floe_v3_set(s.v, 0, 0, -0.5);
    int si = floe_world_add_particle(w, &s);
    int rc = floe_world_prepare(w);
    CHECK(rc == FLOE_OK, "fixed-touch prepare: %s", floe_world_last_error(w));
    if (w->ibuf) /* the step-start positions and mean velocities (not the carried forces) */
        for (size_t k = 9 * (size_t)pview(w).n; k < w->ibuf_cap; k++) w->ibuf[k] = 1e3;
    rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "fixed-touch step: %s", floe_world_last_error(w));
    double fz = pview(w).f[3 * si + 2];
    floe_world_destroy(w);
    return fz;
}

static void test_fixed_points(void) {
    double fm = fixed_touch(FLOE_PD_DEM_MONOLITHIC), fs = fixed_touch(FLOE_PD_DEM_STAGGERED);
    printf("  sphere on fixed PD points, force after one step: monolithic %.6g N, staggered m = 1 %.6g N\n", fm, fs);
    CHECK(fm > 1 && fabs(fs - fm) <= 1e-9 * fabs(fm), "staggered m = 1 = monolithic with fixed PD points touched");
}

int main(void) {
    test_fixed_points();
    test_press();
    test_gravity_once();
    test_order();
    test_substep_stability();
    return check_summary("test_staggered");
}
