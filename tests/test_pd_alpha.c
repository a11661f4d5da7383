/* test_pd_alpha.c - PMB with the per-point critical stretch of LAMMPS pair peri/pmb
 * (floe_pd_material.alpha, peridynamics/pd_materials.c): s0_i = s00 - alpha min_j s_ij over
 * i's intact bonds at the previous evaluation, a bond breaks when s > min(s0_i, s0_j), s0
 * starts at DBL_MAX, a breaking bond carries its force in the evaluation where it breaks
 * (LAMMPS' order). Four points on a line, bonds to the nearest neighbours only, stretches
 * imposed by the positions; checked against the rule evaluation by evaluation. */
#include "check.h"
#include "floe_pd.h"
#include "floe_scene.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static floe_pd_body *line4(double alpha, double s00)
{
    double X[12] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0}, V[4] = {1, 1, 1, 1};
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create_points(&b, 3, 4, X, V, 1.5, 0, 0) == FLOE_OK, "create");
    floe_pd_material m = floe_pd_material_pmb(1000, 0, s00);
    m.c = 1.0;
    m.alpha = alpha;
    CHECK(floe_pd_set_material(b, &m) == FLOE_OK, "material");
    CHECK(b->nbond == 3, "3 bonds (got %lld)", (long long)b->nbond);
    return b;
}

/* positions giving stretches s01, s12, s23 */
static void place(double *x, double s01, double s12, double s23)
{
    memset(x, 0, 12 * sizeof *x);
    x[3] = 1 + s01;
    x[6] = x[3] + 1 + s12;
    x[9] = x[6] + 1 + s23;
}

int main(void)
{
    const double s00 = 0.01, alpha = 0.25;
    double x[12], f[12];

    /* bond 1-2 stretched to 0.012 > s00 between two compressed bonds (-0.04): the compressed
     * ends raise s0 to s00 + alpha 0.04 = 0.02 and the bond survives; with alpha = 0 it
     * breaks at once */
    floe_pd_body *b = line4(alpha, s00);
    CHECK(b->s0 != NULL && b->s0[0] == DBL_MAX, "s0 starts at DBL_MAX");
    place(x, -0.04, 0.012, -0.04);
    memset(f, 0, sizeof f);
    floe_pd_forces(b, x, f);
    CHECK(b->nbroken == 0, "first evaluation: nothing breaks (s0 = DBL_MAX)");
    CHECK_NEAR(b->s0[0], s00 + alpha * 0.04, 1e-12, "s0_0 = s00 - alpha s_01");
    CHECK_NEAR(b->s0[1], s00 + alpha * 0.04, 1e-12, "s0_1 = s00 - alpha min(s_01, s_12)");
    floe_pd_forces(b, x, f);
    CHECK(b->nbroken == 0, "alpha: 0.012 < min(s0_1, s0_2) = 0.02, intact");
    floe_pd_body_destroy(b);
    b = line4(0, s00);
    CHECK(b->s0 == NULL, "alpha = 0: no per-point state");
    floe_pd_forces(b, x, f);
    CHECK(b->nbroken == 1 && b->broken[1], "alpha = 0: 0.012 > s_c breaks at once");
    floe_pd_body_destroy(b);

    /* all bonds in tension 0.02, 0.0079, 0.0079: s0 = s00 - alpha s_min = 0.01 - 0.25 x 0.0079
     * = 0.008025 at points 1, 2, 3 and 0.005 at point 0, so the second evaluation breaks 0-1
     * (0.02 > 0.005) and keeps 1-2, 2-3 (0.0079 < 0.008025); a third one breaks nothing
     * more: point 1's s0 is now from 1-2 only (0.008025) */
    b = line4(alpha, s00);
    place(x, 0.02, 0.0079, 0.0079);
    floe_pd_forces(b, x, f);
    CHECK_NEAR(b->s0[0], s00 - alpha * 0.02, 1e-12, "s0_0 = 0.005");
    CHECK_NEAR(b->s0[1], s00 - alpha * 0.0079, 1e-12, "s0_1 = 0.008025");
    /* floe_pd_forces_nobreak leaves s0 alone */
    place(x, -0.5, -0.5, -0.5);
    floe_pd_forces_nobreak(b, x, f);
    CHECK_NEAR(b->s0[1], s00 - alpha * 0.0079, 1e-12, "nobreak keeps s0");
    place(x, 0.02, 0.0079, 0.0079);
    memset(f, 0, sizeof f);
    floe_pd_forces(b, x, f);
    CHECK(b->nbroken == 1 && b->broken[0] && !b->broken[1] && !b->broken[2], "second evaluation breaks 0-1 only");
    /* LAMMPS' order: the breaking bond still pulls point 0 in this evaluation (c s V V) */
    CHECK_NEAR(f[0], 0.02, 1e-9, "breaking bond's force applied in its last evaluation");
    /* the bond that broke in this evaluation still set s0_0 (LAMMPS); the next evaluation
     * finds no intact bond at point 0: s0 = DBL_MAX */
    CHECK_NEAR(b->s0[0], s00 - alpha * 0.02, 1e-12, "s0_0 from the bond breaking now");
    memset(f, 0, sizeof f);
    floe_pd_forces(b, x, f);
    CHECK(b->nbroken == 1, "third evaluation: nothing more");
    CHECK(f[0] == 0, "broken bond in tension carries nothing (%g)", f[0]);
    CHECK(b->s0[0] == DBL_MAX, "no intact bond: s0 = DBL_MAX");
    size_t bytes = floe_pd_body_bytes(b);
    floe_pd_body_destroy(b);

    /* invalid: negative alpha, alpha with LPS */
    b = line4(0, s00);
    floe_pd_material m = floe_pd_material_pmb(1000, 0, s00);
    m.c = 1;
    m.alpha = -0.1;
    CHECK(floe_pd_set_material(b, &m) == FLOE_EINVAL, "negative alpha refused");
    floe_pd_material l = floe_pd_material_lps(1000, 1e9, 1e9, s00, FLOE_PD_W_ONE);
    l.alpha = 0.25;
    CHECK(floe_pd_set_material(b, &l) == FLOE_EINVAL, "alpha with LPS refused");
    CHECK(floe_pd_body_bytes(b) + 8 * sizeof(double) == bytes, "s0 counted in the body's bytes (2n doubles)");
    floe_pd_body_destroy(b);

    /* scene key: peridynamics[].material.alpha */
    static const char *scene =
        "dimension: 3\n"
        "time: {duration: 1.0e-6}\n"
        "materials:\n"
        "  - {name: pd, density: 2200}\n"
        "laws:\n"
        "  - {materials: [pd, pd], model: none}\n"
        "peridynamics:\n"
        "  - {region: {box: {min: [0, 0, 0], max: [0.004, 0.004, 0.004]}}, spacing: 0.001, contact_material: pd,\n"
        "     material: {model: pmb, density: 2200, bulk_modulus: 1.0e10, critical_stretch: 0.0005, alpha: 0.25}}\n";
    floe_world *w = NULL;
    floe_scene_info info;
    char err[1024];
    int rc = floe_scene_load_ex("t.yaml", scene, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "scene: %s", err);
    if (rc == FLOE_OK) {
        floe_pd_body *pb = floe_world_pd_body(w, 0, NULL);
        CHECK(pb && pb->mat.alpha == 0.25 && pb->s0 != NULL && pb->s_c == 0.0005, "scene: alpha 0.25 set, s00 = 0.0005");
        /* prepare evaluated the forces once: s0 = s00 at rest */
        CHECK(pb && fabs(pb->s0[0] - 0.0005) < 1e-12, "s0 = s00 after the first evaluation at rest (%g)", pb ? pb->s0[0] : 0);
        floe_world_destroy(w);
    }
    char bad[2048];
    snprintf(bad, sizeof bad, "%s", scene);
    char *q = strstr(bad, "model: pmb");
    memcpy(q, "model: lps", 10);
    rc = floe_scene_load_ex("t.yaml", bad, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, "alpha is a pmb option"), "alpha with lps refused: %s", err);
    return check_summary("test_pd_alpha");
}
