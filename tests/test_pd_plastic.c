/* test_pd_plastic.c - elastic-perfectly-plastic PMB bonds (003 eq 6, Fig 2).
 * 1. One bond through a compression - unloading - tension path: the force follows
 *    c s_e w with s_e = s - s_p capped at -s_yc (and +s_yt), the bond unloads elastically
 *    with the residual plastic stretch, and the stored energy is 1/2 c s_e^2 L w; the
 *    plastic work of a monotone compression to -3 s_yc is 2 c w L s_yc^2 (exact).
 * 2. In a world: a PMB block squeezed by a prescribed-velocity end region dissipates
 *    energy only when its bonds yield, and the energy ledger closes.
 * 3. Scene keys and their refusals. */
#include "check.h"
#include "floe_pd.h"
#include "floe_scene.h"
#include "floe.h"
#include "world_read.h"

#include <stdlib.h>
#include <string.h>

static void test_single_bond(void) {
    const double dx = 1e-3, V = dx * dx * dx, X[6] = {0, 0, 0, dx, 0, 0}, Vs[2] = {V, V};
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create_points(&b, 3, 2, X, Vs, 2 * dx, 0, 0) == FLOE_OK, "two-point body");
    floe_pd_material pm = floe_pd_material_pmb(7800, 1.6e11, 0);
    const double syc = 1e-3, syt = 4e-3;
    pm.yield_compression = syc;
    pm.yield_tension = syt;
    CHECK(floe_pd_set_material(b, &pm) == FLOE_OK && b->splast, "plastic PMB material");
    const double c = b->c, w = V * V, L = dx;
    /* path of stretches and the expected elastic stretch after each */
    const double path[] = {-0.5 * syc, -3 * syc, -1.5 * syc, 0.0, 3 * syc, 6 * syc, 0.0};
    const double se_expected[] = {-0.5 * syc, -syc, 0.5 * syc, 2 * syc, syt, syt, -syc};
    /* s_p after: 0, -2 syc, -2 syc, -2 syc, -syc, 2 syc, syc (each jump is one monotone
     * segment, which the rate-independent law resolves in one evaluation) */
    double maxerr = 0, eerr = 0;
    for (size_t k = 0; k < sizeof path / sizeof path[0]; k++) {
        double x[6] = {0, 0, 0, dx * (1 + path[k]), 0, 0}, f[6] = {0};
        double e = floe_pd_forces(b, x, f);
        double fj = f[3], want = -c * w * se_expected[k];
        double err = fabs(fj - want) / (c * w * syc);
        if (err > maxerr) maxerr = err;
        double ew = 0.5 * c * se_expected[k] * se_expected[k] * L * w;
        double er = fabs(e - ew) / (0.5 * c * syc * syc * L * w);
        if (er > eerr) eerr = er;
        printf("  s = %+.4f: force on j %+.6g N (expected %+.6g), s_p %+.3e, energy %.6g J (expected %.6g)\n", path[k],
               fj, want, (double)b->splast[0], e, ew);
    }
    /* float storage of s_p: 1e-7 relative of the stretch, i.e. ~1e-6 of s_yc here */
    CHECK(maxerr < 1e-5, "bond force on the elastic-perfectly-plastic path (max err %.2e x c w s_yc)", maxerr);
    CHECK(eerr < 1e-5, "stored energy 1/2 c s_e^2 L w on the path (max err %.2e)", eerr);
    floe_pd_body_destroy(b);

    /* plastic work of a monotone compression to -3 s_yc in 3000 increments (trapezoid) */
    b = NULL;
    floe_pd_body_create_points(&b, 3, 2, X, Vs, 2 * dx, 0, 0);
    pm.yield_tension = 0;
    floe_pd_set_material(b, &pm);
    double work = 0, fprev = 0, e = 0;
    const int nstep = 3000;
    for (int k = 1; k <= nstep; k++) {
        double s = -3 * syc * k / nstep, x[6] = {0, 0, 0, dx * (1 + s), 0, 0}, f[6] = {0};
        e = floe_pd_forces(b, x, f);
        /* work done on the bond by the external agent moving j by ds L against f_j */
        work += -0.5 * (f[3] + fprev) * (-3 * syc / nstep) * L;
        fprev = f[3];
    }
    double dissipated = work - e, exact = 2 * c * w * L * syc * syc;
    CHECK_NEAR(dissipated, exact, 1e-3, "plastic work of compression to -3 s_yc = 2 c w L s_yc^2");
    floe_pd_body_destroy(b);
}

/* a 10 x 4 x 4 PMB block (dx 1 mm, steel-like), left layer fixed, right layer moving in at
 * v; returns the dissipated energy and the ledger error */
static void squeeze(double ycomp, double *diss, double *balance, double *emax) {
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"steel", 7800, 2e11, 0.25};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&m, &m, 1.0, 0.0));
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = 1e-3;
    r.horizon_factor = 3;
    floe_v3_set(r.hi, 10e-3, 4e-3, 4e-3);
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create(&b, &r) == FLOE_OK, "block");
    floe_pd_material pm = floe_pd_material_pmb(7800, 2e11 / 1.5, 0);
    pm.yield_compression = ycomp;
    CHECK(floe_pd_set_material(b, &pm) == FLOE_OK, "block material");
    floe_pd_surface_correction(b);
    int f0 = 0;
    CHECK(floe_world_add_pd_body(w, b, mat, NULL, &f0) == FLOE_OK, "add block: %s", floe_world_last_error(w));
    floe_pd_bc fix = floe_default_pd_bc(), mov = floe_default_pd_bc();
    fix.kind = FLOE_PD_BC_FIXED;
    floe_v3_set(fix.lo, -1, -1, -1);
    floe_v3_set(fix.hi, 1e-3, 1, 1);
    mov.kind = FLOE_PD_BC_VELOCITY;
    floe_v3_set(mov.lo, 9e-3, -1, -1);
    floe_v3_set(mov.hi, 1, 1, 1);
    floe_v3_set(mov.value, -2.0, 0, 0);
    CHECK(floe_world_pd_region(w, 0, &fix) > 0 && floe_world_pd_region(w, 0, &mov) > 0, "regions");
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    /* 2 m/s for 5 us: 1e-5 m on 9e-3 m, a mean strain of 1.1e-3 */
    int rc = floe_world_run(w, 5e-6, NULL, NULL);
    CHECK(rc == FLOE_OK, "squeeze run: %s", floe_world_last_error(w));
    floe_energy e = floe_world_energy(w);
    *diss = e.dissipated;
    *balance = floe_world_energy_balance_error(w);
    *emax = e.work_boundary;
    floe_world_destroy(w);
}

static void test_world(void) {
    double de, be, we, dp, bp, wp;
    squeeze(0, &de, &be, &we);
    squeeze(2e-4, &dp, &bp, &wp);
    printf("  squeeze: elastic dissipated %.3g J of work %.3g J (balance %.2e); plastic (s_yc 2e-4) dissipated "
           "%.3g J of work %.3g J (balance %.2e)\n", de, we, be, dp, wp, bp);
    CHECK(fabs(de) < 1e-6 * we, "elastic bonds dissipate nothing (%.2e of the work)", de / we);
    CHECK(dp > 0.1 * wp, "yielding bonds dissipate a good part of the work (%.2f)", dp / wp);
    CHECK(be < 1e-4 && bp < 1e-4, "energy ledger closes (elastic %.2e, plastic %.2e)", be, bp);
}

static void test_scene(void) {
    const char *base =
        "dimension: 3\ntime: {duration: 1.0e-6}\n"
        "materials:\n  - {name: steel, density: 7800, young: 2.0e11, poisson: 0.25}\n"
        "laws:\n  - {materials: [steel, steel], model: hertz_mindlin, restitution: 0.9}\n"
        "peridynamics:\n  - {region: {box: {min: [0, 0, 0], max: [0.004, 0.004, 0.004]}}, spacing: 0.001,\n"
        "     contact_material: steel, material: {model: %s, density: 7800, bulk_modulus: 1.3e11, %s}}\n";
    char text[2048];
    floe_world *w = NULL;
    char err[512];
    snprintf(text, sizeof text, base, "pmb", "yield_compression: 2.0e-4");
    int rc = floe_scene_load_string(text, "p.yaml", NULL, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK && w && floe_world_pd_body(w, 0, NULL)->splast, "scene yield_compression: %s", rc ? err : "ok");
    floe_world_destroy(w);
    w = NULL;
    snprintf(text, sizeof text, base, "lps", "shear_modulus: 8.0e10, yield_compression: 2.0e-4");
    rc = floe_scene_load_string(text, "p.yaml", NULL, &w, NULL, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, "pmb options"), "lps + yield refused: %s", err);
    printf("  %s\n", err);
    floe_world_destroy(w);
    w = NULL;
    snprintf(text, sizeof text, base, "pmb", "yield_compression: -1");
    rc = floe_scene_load_string(text, "p.yaml", NULL, &w, NULL, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, "yield_compression") && strstr(err, "p.yaml:"), "negative yield refused: %s", err);
    printf("  %s\n", err);
    floe_world_destroy(w);
}

int main(void) {
    test_single_bond();
    test_world();
    test_scene();
    return check_summary("test_pd_plastic");
}
