/* test_pd_crack.c - peridynamic pre-cracks (floe_pd_add_crack, scene `cracks:`): the bonds
 * cut are exactly those crossing the crack (against brute force in 2D and 3D), the material
 * state after cutting, contact between the faces, holes narrower than the horizon
 * (floe_pd_bonds_across and the scene warning), PD regions of polygons and compounds where
 * the scene puts them, a mode-I plate and a Kalthoff-Winkler plate. */
#include "check.h"
#include "floe_pd.h"
#include "floe_scene.h"
#include "floe.h"
#include "world_read.h"

#include <stdlib.h>
#include <string.h>

static floe_pd_body *lattice(int dim, int nx, int ny, int nz, double dx, double m) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = dim;
    r.dx = dx;
    r.horizon_factor = m;
    floe_v3_set(r.lo, 0, 0, 0);
    floe_v3_set(r.hi, nx * dx, ny * dx, dim == 3 ? nz * dx : 0);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) return NULL;
    return b;
}

/* ---- brute force: independent intersection tests ---- */

static double orient2(const double a[3], const double b[3], const double c[3]) {
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* 2D segments p-q and a-b in generic position (no point on the other's line): proper
 * crossing by the four orientation signs */
static int seg_cross(const double p[3], const double q[3], const double a[3], const double b[3]) {
    double o1 = orient2(a, b, p), o2 = orient2(a, b, q), o3 = orient2(p, q, a), o4 = orient2(p, q, b);
    return ((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0));
}

/* 3D: segment p-q against a convex polygon, by the plane through its first three vertices
 * and a fan of triangles with barycentric coordinates */
static int poly_cross(const double p[3], const double q[3], const floe_pd_crack *c) {
    double e1[3], e2[3], n[3], a[3], b[3];
    floe_v3_sub(e1, c->p[1], c->p[0]);
    floe_v3_sub(e2, c->p[2], c->p[0]);
    floe_v3_cross(n, e1, e2);
    floe_v3_sub(a, p, c->p[0]);
    floe_v3_sub(b, q, c->p[0]);
    double da = floe_v3_dot(a, n), db = floe_v3_dot(b, n);
    if ((da > 0) == (db > 0)) return 0;
    double t = da / (da - db), P[3];
    for (int d = 0; d < 3; d++) P[d] = p[d] + t * (q[d] - p[d]);
    for (int k = 1; k + 1 < c->n; k++) { /* triangle p0, pk, pk+1 */
        double u[3], v[3], w[3];
        floe_v3_sub(u, c->p[k], c->p[0]);
        floe_v3_sub(v, c->p[k + 1], c->p[0]);
        floe_v3_sub(w, P, c->p[0]);
        double uu = floe_v3_dot(u, u), uv = floe_v3_dot(u, v), vv = floe_v3_dot(v, v);
        double wu = floe_v3_dot(w, u), wv = floe_v3_dot(w, v), den = uu * vv - uv * uv;
        double s = (wu * vv - wv * uv) / den, r = (wv * uu - wu * uv) / den;
        if (s >= 0 && r >= 0 && s + r <= 1) return 1;
    }
    return 0;
}

/* cut b by c and compare with brute force over the bonds of an uncut copy */
static void compare_cut(const char *what, int dim, floe_pd_body *b, const floe_pd_crack *c) {
    int64_t nb0 = b->nbond, expect = 0, wrong_kept = 0;
    uint8_t *ex = calloc((size_t)nb0, 1);
    int32_t *pi = malloc((size_t)nb0 * sizeof *pi), *pj = malloc((size_t)nb0 * sizeof *pj);
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            const double *xi = b->X + 3 * i, *xj = b->X + 3 * b->partner[k];
            int cut = 0;
            if (dim == 2) {
                for (int s = 0; s + 1 < c->n; s++) cut |= seg_cross(xi, xj, c->p[s], c->p[s + 1]);
            } else cut = poly_cross(xi, xj, c);
            ex[k] = (uint8_t)cut;
            expect += cut;
            pi[k] = i;
            pj[k] = b->partner[k];
        }
    int64_t n = floe_pd_add_crack(b, c);
    int64_t cut_still_bonded = 0;
    for (int64_t k = 0; k < nb0; k++) {
        int bonded = floe_pd_bonded(b, pi[k], pj[k]);
        if (ex[k] && bonded) cut_still_bonded++;
        if (!ex[k] && !bonded) wrong_kept++;
    }
    printf("  %s: %lld bonds, %lld cut (brute force %lld), %lld bonds left\n", what, (long long)nb0, (long long)n,
           (long long)expect, (long long)b->nbond);
    CHECK(expect > 50, "%s: the crack crosses bonds (%lld)", what, (long long)expect);
    CHECK(n == expect, "%s: floe_pd_add_crack cut %lld bonds, brute force %lld", what, (long long)n, (long long)expect);
    CHECK(cut_still_bonded == 0 && wrong_kept == 0, "%s: %lld crossing bonds kept, %lld other bonds removed", what,
          (long long)cut_still_bonded, (long long)wrong_kept);
    CHECK(b->nbond == nb0 - expect && b->ncut == expect, "%s: nbond %lld = %lld - %lld, ncut %lld", what,
          (long long)b->nbond, (long long)nb0, (long long)expect, (long long)b->ncut);
    free(ex);
    free(pi);
    free(pj);
}

/* 1. the bonds cut are those crossing the crack (2D polyline, 3D pentagon and rectangle) */
static void test_cut_brute_force(void) {
    floe_pd_body *b = lattice(2, 40, 30, 0, 1.0, 3.0);
    floe_pd_crack c;
    memset(&c, 0, sizeof c);
    c.n = 3; /* a polyline in generic position (no lattice point on it) */
    floe_v3_set(c.p[0], 3.31, 10.27, 0);
    floe_v3_set(c.p[1], 20.71, 17.93, 0);
    floe_v3_set(c.p[2], 33.17, 9.12, 0);
    CHECK(floe_pd_crack_check(&c, 2) == FLOE_OK, "2D polyline valid");
    compare_cut("2D polyline", 2, b, &c);
    /* a second cut along the same line removes nothing more */
    CHECK(floe_pd_add_crack(b, &c) == 0, "cutting twice removes nothing more");
    double *phi = malloc((size_t)b->n * sizeof *phi), mx = 0;
    floe_pd_damage(b, phi);
    for (int i = 0; i < b->n; i++) mx = fmax(mx, phi[i]);
    CHECK(mx == 0, "cut bonds are out of the family: damage 0 everywhere at set-up (max %g)", mx);
    free(phi);
    floe_pd_body_destroy(b);

    b = lattice(3, 14, 13, 12, 1.0, 3.0);
    memset(&c, 0, sizeof c);
    c.n = 5; /* a tilted convex pentagon */
    const double cen[3] = {6.93, 6.41, 6.17}, u[3] = {0.8, 0.36, 0.48}, v[3] = {-0.45, 0.89, 0.07};
    for (int k = 0; k < 5; k++) {
        double a = 2 * M_PI * k / 5 + 0.3, r = k == 2 ? 4.1 : 5.3;
        for (int d = 0; d < 3; d++) c.p[k][d] = cen[d] + r * (cos(a) * u[d] + sin(a) * v[d]);
    }
    CHECK(floe_pd_crack_check(&c, 3) == FLOE_OK, "3D pentagon valid");
    compare_cut("3D pentagon", 3, b, &c);
    floe_pd_body_destroy(b);

    b = lattice(3, 12, 12, 12, 1.0, 3.0);
    const double o[3] = {2.13, 1.77, 5.61}, e1[3] = {7.3, 0.9, 0.2}, e2[3] = {-0.5, 6.13, 2.3}; /* no edge through a lattice line */
    c = floe_pd_crack_rectangle(o, e1, e2);
    CHECK(floe_pd_crack_check(&c, 3) == FLOE_OK, "3D rectangle valid");
    compare_cut("3D rectangle", 3, b, &c);
    floe_pd_body_destroy(b);

    /* a crack along a row of points: those points count on its + side (the left of a -> b):
     * bonded to the row above and along the row, cut from the row below */
    b = lattice(2, 20, 20, 0, 1.0, 3.0);
    const double a0[3] = {4.0, 10.5, 0}, a1[3] = {16.0, 10.5, 0}; /* the row y = 10.5 */
    c = floe_pd_crack_segment(a0, a1);
    floe_pd_add_crack(b, &c);
    int on = 10 * 20 + 10, above = 11 * 20 + 10, below = 9 * 20 + 10, along = 10 * 20 + 11;
    CHECK(fabs(b->X[3 * on + 1] - 10.5) < 1e-12, "point %d is on the crack", on);
    CHECK(floe_pd_bonded(b, on, above) && floe_pd_bonded(b, on, along) && !floe_pd_bonded(b, on, below),
          "a point on the crack: bonded above (%d) and along (%d), cut below (%d)", floe_pd_bonded(b, on, above),
          floe_pd_bonded(b, on, along), floe_pd_bonded(b, on, below));
    CHECK(!floe_pd_bonded(b, above, below), "across the crack: cut");
    floe_pd_body_destroy(b);
}

/* 2. invalid cracks */
static void test_crack_check(void) {
    floe_pd_crack c;
    memset(&c, 0, sizeof c);
    c.n = 1;
    CHECK(floe_pd_crack_check(&c, 2) == FLOE_EINVAL, "2D: one point refused");
    c.n = 2; /* two equal points */
    CHECK(floe_pd_crack_check(&c, 2) == FLOE_EINVAL, "2D: a zero-length segment refused");
    c.p[1][0] = NAN;
    CHECK(floe_pd_crack_check(&c, 2) == FLOE_EINVAL, "2D: NaN refused");
    const double sq[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    c.n = 4;
    memcpy(c.p, sq, sizeof sq);
    CHECK(floe_pd_crack_check(&c, 3) == FLOE_OK, "3D: a square");
    c.p[2][2] = 0.1;
    CHECK(floe_pd_crack_check(&c, 3) == FLOE_EINVAL, "3D: a non-planar quadrilateral refused");
    memcpy(c.p, sq, sizeof sq);
    c.p[2][0] = 0.3; c.p[2][1] = 0.3; /* reflex vertex */
    CHECK(floe_pd_crack_check(&c, 3) == FLOE_EINVAL, "3D: a non-convex quadrilateral refused");
    memcpy(c.p, sq, sizeof sq);
    double t[3];
    floe_v3_copy(t, c.p[1]); floe_v3_copy(c.p[1], c.p[2]); floe_v3_copy(c.p[2], t); /* bow tie */
    CHECK(floe_pd_crack_check(&c, 3) == FLOE_EINVAL, "3D: a self-intersecting quadrilateral refused");
    c.n = 5; /* a pentagram: every turn the same way, twice around */
    for (int k = 0; k < 5; k++) floe_v3_set(c.p[k], cos(4 * M_PI * k / 5), sin(4 * M_PI * k / 5), 0);
    CHECK(floe_pd_crack_check(&c, 3) == FLOE_EINVAL, "3D: a pentagram refused");
    c.n = 3;
    for (int k = 0; k < 3; k++) floe_v3_set(c.p[k], k, 2 * k, 0);
    CHECK(floe_pd_crack_check(&c, 3) == FLOE_EINVAL, "3D: collinear points refused");
    floe_pd_body *b = lattice(2, 5, 5, 0, 1.0, 3.0);
    c.n = 1;
    CHECK(floe_pd_add_crack(b, &c) == -FLOE_EINVAL, "floe_pd_add_crack refuses an invalid crack");
    floe_pd_body_destroy(b);
}

/* 3. cutting after set_material and the surface correction gives the state of cutting
 * before (LPS: weighted volumes, dilatation tensors; PMB: the correction factors) */
static void test_material_state(void) {
    for (int model = 0; model < 2; model++) {
        floe_pd_body *a = lattice(2, 24, 20, 0, 1e-3, 3.0), *b = lattice(2, 24, 20, 0, 1e-3, 3.0);
        floe_pd_material m = model ? floe_pd_material_lps(2000, 10e9, 6e9, 0.01, FLOE_PD_W_GAUSS)
                                   : floe_pd_material_pmb(2000, 10e9, 0.01);
        const double p0[3] = {0.0, 10.07e-3, 0}, p1[3] = {12.3e-3, 10.07e-3, 0};
        floe_pd_crack c = floe_pd_crack_segment(p0, p1);
        int64_t n1 = floe_pd_add_crack(a, &c);
        floe_pd_set_material(a, &m);
        floe_pd_surface_correction(a);
        floe_pd_set_material(b, &m);
        floe_pd_surface_correction(b);
        int64_t n2 = floe_pd_add_crack(b, &c);
        CHECK(n1 == n2 && n1 > 0, "%s: the same bonds cut before and after the material (%lld, %lld)", m.model == FLOE_PD_LPS ? "lps" : "pmb",
              (long long)n1, (long long)n2);
        CHECK((model ? b->dten != NULL : b->scorr != NULL), "the surface correction is recomputed");
        int n = a->n;
        double *x = malloc(3 * (size_t)n * sizeof *x), *fa = calloc(3 * (size_t)n, sizeof *fa),
               *fb = calloc(3 * (size_t)n, sizeof *fb);
        for (int i = 0; i < n; i++) { /* a smooth deformation with an opening at the crack */
            const double *X = a->X + 3 * i;
            x[3 * i] = X[0] * (1 + 1e-3) + 2e-4 * X[1];
            x[3 * i + 1] = X[1] * (1 - 5e-4) + (X[1] > 10.07e-3 && X[0] < 12.3e-3 ? 2e-6 : 0);
            x[3 * i + 2] = 0;
        }
        double ea = floe_pd_forces_nobreak(a, x, fa), eb = floe_pd_forces_nobreak(b, x, fb), df = 0, fm = 0;
        for (int i = 0; i < 3 * n; i++) {
            df = fmax(df, fabs(fa[i] - fb[i]));
            fm = fmax(fm, fabs(fa[i]));
        }
        CHECK(fabs(ea - eb) <= 1e-12 * fabs(ea) && df <= 1e-12 * fm, "%s: forces and energy agree (energy %.6g vs %.6g, "
              "force diff %.2g of %.2g)", m.model == FLOE_PD_LPS ? "lps" : "pmb", ea, eb, df, fm);
        free(x); free(fa); free(fb);
        floe_pd_body_destroy(a);
        floe_pd_body_destroy(b);
    }
}

/* ---- holes narrower than the horizon ---- */

typedef struct hole { double c[3], h[3]; double r; } hole; /* a box (r = 0) or a disc */
static double hole_sdf(const double X[3], void *user) {
    const hole *o = user;
    if (o->r > 0) return hypot(X[0] - o->c[0], X[1] - o->c[1]) - o->r;
    double q[2], out = 0, in = -INFINITY;
    for (int d = 0; d < 2; d++) {
        q[d] = fabs(X[d] - o->c[d]) - o->h[d];
        out += q[d] > 0 ? q[d] * q[d] : 0;
        in = fmax(in, q[d]);
    }
    return out > 0 ? sqrt(out) : in;
}
typedef struct cutout { const hole *h; } cutout;
static double keep_sdf(const double X[3], void *user) { return -hole_sdf(X, (void *)((const cutout *)user)->h); }

/* a 2D plate 40 x 30 (dx = 1, horizon 3) with the hole o left out */
static floe_pd_body *plate_with(const hole *o) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 2;
    r.dx = 1.0;
    r.horizon_factor = 3;
    floe_v3_set(r.hi, 40, 30, 0);
    cutout cu = {o};
    r.sdf = keep_sdf;
    r.sdf_user = &cu;
    floe_pd_body *b = NULL;
    floe_pd_body_create(&b, &r);
    return b;
}

/* 4. floe_pd_bonds_across: a one-row notch is bridged, a notch wider than the horizon and a
 * large hole are not (chords that clip a wide hole do not count), a small pore is; cutting
 * the notch along its centre line leaves no bridge */
static void test_bonds_across(void) {
    const hole row = {{10, 14.5, 0}, {10.2, 0.4, 0}, 0};  /* x < 20.2: one row of points out */
    const hole wide = {{10, 15, 0}, {10.2, 3.6, 0}, 0};   /* 7 rows out: wider than the horizon */
    const hole big = {{20, 15, 0}, {0, 0, 0}, 6.3};       /* a disc of diameter 12.6 > 3 */
    const hole pore = {{20.1, 15.2, 0}, {0, 0, 0}, 1.1};  /* diameter 2.2 < 3 */
    const hole *hs[4] = {&row, &wide, &big, &pore};
    const char *names[4] = {"one-row notch", "7-row notch", "disc of diameter 4.2 horizons", "pore of diameter 0.7 horizon"};
    int64_t cnt[4];
    for (int k = 0; k < 4; k++) {
        floe_pd_body *b = plate_with(hs[k]);
        double at[3] = {0, 0, 0};
        cnt[k] = floe_pd_bonds_across(b, hole_sdf, (void *)hs[k], at);
        printf("  %s: %d points, %lld bonds bridge it (e.g. at %.2f, %.2f)\n", names[k], b->n, (long long)cnt[k], at[0],
               at[1]);
        if (k == 0) {
            CHECK(cnt[0] > 100 && at[0] < 20.5 && fabs(at[1] - 14.5) < 1.01, "%s: %lld bonds bridge it, one at (%g, %g)",
                  names[0], (long long)cnt[0], at[0], at[1]);
            const double p0[3] = {-1, 14.5, 0}, p1[3] = {20.2, 14.5, 0};
            floe_pd_crack c = floe_pd_crack_segment(p0, p1);
            int64_t ncut = floe_pd_add_crack(b, &c);
            int64_t after = floe_pd_bonds_across(b, hole_sdf, (void *)hs[k], NULL);
            CHECK(ncut == cnt[0] && after == 0, "a crack along the notch cuts those %lld bonds (%lld) and leaves %lld",
                  (long long)cnt[0], (long long)ncut, (long long)after);
        }
        floe_pd_body_destroy(b);
    }
    CHECK(cnt[1] == 0, "%s: no bond bridges it (%lld)", names[1], (long long)cnt[1]);
    CHECK(cnt[2] == 0, "%s: the chords that clip it do not count (%lld)", names[2], (long long)cnt[2]);
    CHECK(cnt[3] > 0, "%s: bridged (%lld)", names[3], (long long)cnt[3]);
}

/* ---- scenes ---- */

static floe_world *load(const char *text, floe_scene_info *info, char *err, size_t errlen) {
    floe_world *w = NULL;
    int rc = floe_scene_load_ex("crack.yaml", text, NULL, 0, &w, info, err, errlen);
    return rc == FLOE_OK ? w : NULL;
}

static const char *scene_head =
    "dimension: 2\n"
    "time: {duration: 1e-3}\n"
    "gravity: [0, 0, 0]\n"
    "materials:\n"
    "  - {name: steel, density: 8000, young: 190e9, poisson: 0.25}\n"
    "laws:\n"
    "  - {materials: [steel, steel], model: hertz_mindlin, restitution: 0.9}\n"
    "peridynamics:\n";

/* 5. scene cracks (the count equals the API's), the warning for a one-row region.remove,
 * and the errors */
static void test_scene_cracks(void) {
    static char text[8192];
    char err[1024];
    floe_scene_info info;
    snprintf(text, sizeof text,
             "%s  - region: {box: {min: [0, 0], max: [0.04, 0.03]}, remove: [{shape: {box: {size: [0.02, 0.0008, 1]}}, "
             "position: [0.01, 0.0145, 0]}]}\n"
             "    spacing: 0.001\n"
             "    material: {model: pmb, density: 8000, young: 190e9, critical_stretch: 0.01}\n"
             "    contact_material: steel\n%s",
             scene_head, "");
    floe_world *w = load(text, &info, err, sizeof err);
    CHECK(w != NULL, "one-row notch scene loads: %s", err);
    if (w) {
        const floe_pd_body *b = floe_world_pd_body(w, 0, NULL);
        printf("  one-row notch: %lld bridging bonds; summary:\n%.*s\n", (long long)b->nbridge, 600, info.summary);
        CHECK(b->nbridge > 100, "the one-row notch is bridged (%lld)", (long long)b->nbridge);
        CHECK(strstr(info.summary, "WARNING: ") && strstr(info.summary, "bridge a removed region") &&
              strstr(info.summary, "cracks"), "the summary warns and suggests cracks");
        floe_world_destroy(w);
    }
    /* the same notch with a crack along it: no warning, the crack's cut count */
    snprintf(text, sizeof text,
             "%s  - region: {box: {min: [0, 0], max: [0.04, 0.03]}, remove: [{shape: {box: {size: [0.02, 0.0008, 1]}}, "
             "position: [0.01, 0.0145, 0]}]}\n"
             "    spacing: 0.001\n"
             "    material: {model: pmb, density: 8000, young: 190e9, critical_stretch: 0.01}\n"
             "    contact_material: steel\n"
             "    cracks:\n      - {points: [[-0.001, 0.0145], [0.0202, 0.0145]], name: notch}\n",
             scene_head);
    w = load(text, &info, err, sizeof err);
    CHECK(w != NULL, "notch + crack scene loads: %s", err);
    if (w) {
        const floe_pd_body *b = floe_world_pd_body(w, 0, NULL);
        CHECK(b->nbridge == 0 && b->ncut > 100 && !strstr(info.summary, "WARNING: ") && strstr(info.summary, "cracks cut"),
              "with the crack: no warning (%lld bridging), %lld bonds cut", (long long)b->nbridge, (long long)b->ncut);
        floe_world_destroy(w);
    }
    /* 3D: a rectangle given by its centre cuts what floe_pd_add_crack cuts */
    snprintf(text, sizeof text,
             "dimension: 3\ntime: {duration: 1e-3}\ngravity: [0, 0, 0]\nmaterials:\n"
             "  - {name: steel, density: 8000, young: 190e9, poisson: 0.25}\n"
             "laws:\n  - {materials: [steel, steel], model: hertz_mindlin, restitution: 0.9}\n"
             "peridynamics:\n"
             "  - region: {box: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}}\n"
             "    spacing: 0.001\n"
             "    material: {model: pmb, density: 8000, bulk_modulus: 160e9, critical_stretch: 0.01}\n"
             "    contact_material: steel\n"
             "    cracks:\n      - {rectangle: {center: [0.0031, 0.005, 0.0052], edges: [[0.006, 0, 0], [0, 0.0071, 0.001]]}}\n");
    w = load(text, &info, err, sizeof err);
    CHECK(w != NULL, "3D rectangle scene loads: %s", err);
    if (w) {
        const floe_pd_body *b = floe_world_pd_body(w, 0, NULL);
        floe_pd_body *r = lattice(3, 10, 10, 10, 0.001, 3.0);
        const double o[3] = {0.0031 - 0.003, 0.005 - 0.00355, 0.0052 - 0.0005}, e1[3] = {0.006, 0, 0}, e2[3] = {0, 0.0071, 0.001};
        floe_pd_crack c = floe_pd_crack_rectangle(o, e1, e2);
        int64_t n = floe_pd_add_crack(r, &c);
        CHECK(b->ncut == n && n > 100, "scene rectangle cut %lld bonds, the API %lld", (long long)b->ncut, (long long)n);
        floe_pd_body_destroy(r);
        floe_world_destroy(w);
    }
    /* errors */
    const char *bad[][2] = {
        {"    cracks:\n      - {points: [[0, 0.01]]}\n", "give 2 to"},
        {"    cracks:\n      - {rectangle: {corner: [0, 0, 0], edges: [[1, 0, 0], [0, 1, 0]]}}\n", "a rectangle is a 3D crack"},
        {"    cracks:\n      - {points: [[0, 0.01], [0, 0.01]]}\n", "consecutive points distinct"},
        {"    cracks: {points: [[0, 0.01], [0.01, 0.01]]}\n", "must be a list"},
        {"    cracks:\n      - {point: [[0, 0.01], [0.01, 0.01]]}\n", "points"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        snprintf(text, sizeof text,
                 "%s  - region: {box: {min: [0, 0], max: [0.02, 0.02]}}\n    spacing: 0.001\n"
                 "    material: {model: pmb, density: 8000, young: 190e9, critical_stretch: 0.01}\n"
                 "    contact_material: steel\n%s",
                 scene_head, bad[k][0]);
        err[0] = 0;
        w = load(text, &info, err, sizeof err);
        CHECK(w == NULL && strstr(err, bad[k][1]) && strstr(err, "crack.yaml:"), "bad crack %zu refused with '%s': %s", k,
              bad[k][1], err);
        floe_world_destroy(w);
    }
}

/* 6. a polygon (skewed triangle) and a compound (an L) as PD regions and as holes: the
 * points fill the shape as written, its centre of mass at position (as for bodies) */
static int in_tri(const double t[3][2], double x, double y, double tol) {
    double s = 0;
    for (int k = 0; k < 3; k++) {
        const double *a = t[k], *b = t[(k + 1) % 3];
        double c = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
        double L = hypot(b[0] - a[0], b[1] - a[1]);
        if (c / L < tol) return 0;
        s += c;
    }
    return s > 0;
}
static void test_polygon_region(void) {
    static char text[8192];
    char err[1024];
    floe_scene_info info;
    const double dx = 0.001;
    /* the triangle as written, counter-clockwise; centroid (0.02067, 0.01567) */
    const double tw[3][2] = {{0, 0}, {0.05, 0.01}, {0.012, 0.037}};
    const double cx = (0 + 0.05 + 0.012) / 3, cy = (0 + 0.01 + 0.037) / 3, px = 0.3, py = 0.2;
    double t[3][2];
    for (int k = 0; k < 3; k++) { t[k][0] = tw[k][0] - cx + px; t[k][1] = tw[k][1] - cy + py; }
    snprintf(text, sizeof text,
             "%s  - region: {shape: {polygon: {vertices: [[0, 0], [0.05, 0.01], [0.012, 0.037]]}}, position: [%.17g, %.17g, 0]}\n"
             "    spacing: %g\n"
             "    material: {model: pmb, density: 8000, young: 190e9, critical_stretch: 0.01}\n"
             "    contact_material: steel\n",
             scene_head, px, py, dx);
    floe_world *w = load(text, &info, err, sizeof err);
    CHECK(w != NULL, "triangle region loads: %s", err);
    if (w) {
        const floe_pd_body *b = floe_world_pd_body(w, 0, NULL);
        int outside = 0;
        for (int i = 0; i < b->n; i++)
            if (!in_tri(t, b->X[3 * i], b->X[3 * i + 1], -1e-9)) outside++;
        double area = 0.5 * fabs((tw[1][0] - tw[0][0]) * (tw[2][1] - tw[0][1]) - (tw[2][0] - tw[0][0]) * (tw[1][1] - tw[0][1]));
        double perim = 0;
        for (int k = 0; k < 3; k++) perim += hypot(tw[(k + 1) % 3][0] - tw[k][0], tw[(k + 1) % 3][1] - tw[k][1]);
        double expect = area / (dx * dx), tol = 0.5 * perim / dx;
        printf("  triangle region: %d points, %d outside the written triangle; area / dx^2 = %.1f (+- %.1f)\n", b->n,
               outside, expect, tol);
        CHECK(outside == 0, "every point inside the triangle as written (%d outside)", outside);
        CHECK(fabs(b->n - expect) <= tol, "points %d = area/dx^2 %.1f within half the perimeter/dx %.1f", b->n, expect, tol);
        floe_world_destroy(w);
    }
    /* an L (compound of two boxes, symmetric: its principal axes are at 45 degrees) with the
     * triangle removed from its corner region as a hole */
    const double lx = (0.02 * 4 + 0.005 * 3) / 7, ly = lx; /* centroid of the L as written */
    const double qx = 0.1, qy = -0.05;
    snprintf(text, sizeof text,
             "%s  - region:\n"
             "      shape: {compound: {pieces: [{shape: {box: {size: [0.04, 0.01, 0.001]}}, position: [0.02, 0.005, 0]},\n"
             "                                  {shape: {box: {size: [0.01, 0.03, 0.001]}}, position: [0.005, 0.025, 0]}]}}\n"
             "      position: [%.17g, %.17g, 0]\n"
             "      remove: [{shape: {polygon: {vertices: [[0, 0], [0.006, 0], [0, 0.006]]}}, position: [%.17g, %.17g, 0]}]\n"
             "    spacing: %g\n"
             "    material: {model: pmb, density: 8000, young: 190e9, critical_stretch: 0.01}\n"
             "    contact_material: steel\n",
             scene_head, qx, qy, qx - lx + 0.002, qy - ly + 0.002, dx);
    w = load(text, &info, err, sizeof err);
    CHECK(w != NULL, "L region loads: %s", err);
    if (w) {
        const floe_pd_body *b = floe_world_pd_body(w, 0, NULL);
        /* the L as written, moved by (q - centroid); the hole: triangle (0,0) (6,0) (0,6) mm */
        int outside = 0, in_hole = 0;
        for (int i = 0; i < b->n; i++) {
            double x = b->X[3 * i] - qx + lx, y = b->X[3 * i + 1] - qy + ly, e = 1e-9;
            int inL = (x >= -e && x <= 0.04 + e && y >= -e && y <= 0.01 + e) || (x >= -e && x <= 0.01 + e && y >= -e && y <= 0.04 + e);
            if (!inL) outside++;
            const double th[3][2] = {{0, 0}, {0.006, 0}, {0, 0.006}};
            if (in_tri(th, x, y, 1e-9)) in_hole++;
        }
        double expect = 7e-4 / (dx * dx) - 18e-6 / (dx * dx), tol = 0.5 * (0.16 + 0.0205) / dx;
        printf("  L region with a triangular hole: %d points, %d outside the L, %d in the hole; expected %.1f +- %.1f\n", b->n,
               outside, in_hole, expect, tol);
        CHECK(outside == 0 && in_hole == 0, "the L as written: %d points outside it, %d in the hole", outside, in_hole);
        CHECK(fabs(b->n - expect) <= tol, "points %d = area/dx^2 %.1f within %.1f", b->n, expect, tol);
        floe_world_destroy(w);
    }
}

/* 7. contact between the faces: a plate cut through by a crack stays at rest (the pairs
 * that overlap in the reference across the crack get no contact), and its halves pushed
 * together meet by contact instead of passing through each other */
static void test_faces_contact(void) {
    static char text[8192];
    char err[1024];
    floe_scene_info info;
    snprintf(text, sizeof text,
             "%s  - region: {box: {min: [0, 0], max: [0.02, 0.02]}}\n    spacing: 0.001\n"
             "    material: {model: pmb, density: 8000, young: 190e9}\n"
             "    contact_material: steel\n"
             "    cracks: [{points: [[-0.001, 0.01], [0.021, 0.01]]}]\n",
             scene_head);
    floe_world *w = load(text, &info, err, sizeof err);
    CHECK(w != NULL, "split plate loads: %s", err);
    if (!w) return;
    int f0;
    const floe_pd_body *b = floe_world_pd_body(w, 0, &f0);
    int maxc = 0;
    for (int s = 0; s < 20; s++) {
        floe_world_step(w);
        maxc = maxc > floe_world_contact_count(w) ? maxc : floe_world_contact_count(w);
    }
    double vmax = 0;
    for (int i = 0; i < b->n; i++) vmax = fmax(vmax, floe_v3_norm(pview(w).v + 3 * (f0 + i)));
    printf("  split plate at rest: %d contacts, max speed %g m/s after 20 steps\n", maxc, vmax);
    CHECK(maxc == 0 && vmax == 0, "at rest: no contact across the crack (%d) and no motion (%g m/s)", maxc, vmax);
    /* push the halves together: the upper half moves down at 20 m/s (1.2 dx in 1500 steps
     * without contact; the faces touch after 0.48 dx, where the diagonal pairs at sqrt 2 dx
     * reach R_i + R_j = 1.13 dx) */
    printf("  dt %.3g s\n", floe_world_dt(w));
    for (int i = 0; i < b->n; i++)
        if (b->X[3 * i + 1] > 0.01) set_vel(w, f0 + i, 1, -20.0);
    double gap_min = INFINITY;
    maxc = 0;
    for (int s = 0; s < 1500; s++) {
        floe_world_step(w);
        maxc = maxc > floe_world_contact_count(w) ? maxc : floe_world_contact_count(w);
        /* the lowest upper-half point stays above the highest lower-half point in each column */
        for (int i = 0; i < b->n; i++) {
            if (fabs(b->X[3 * i + 1] - 0.0105) > 1e-9) continue;
            int j = i - 20; /* the point below across the crack (20 per row) */
            double g = pview(w).x[3 * (f0 + i) + 1] - pview(w).x[3 * (f0 + j) + 1];
            gap_min = fmin(gap_min, g);
        }
    }
    printf("  halves pushed together at 20 m/s: %d contacts (max), smallest row distance across the crack %.3g dx\n", maxc,
           gap_min / 0.001);
    CHECK(maxc > 10, "the faces meet by contact (%d contacts)", maxc);
    CHECK(gap_min > 0.3 * 0.001, "the faces do not pass through each other (row distance %.3g dx > 0.3)", gap_min / 0.001);
    floe_world_destroy(w);
}


/* run a loaded scene for nsteps; returns its world (NULL on failure) */
static floe_world *run_scene(const char *text, int nsteps, const char *what) {
    char err[1024] = "";
    floe_scene_info info;
    floe_world *w = load(text, &info, err, sizeof err);
    CHECK(w != NULL, "%s loads: %s", what, err);
    if (!w) return NULL;
    int rc = 0;
    for (int s = 0; s < nsteps && !rc; s++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "%s runs: %s", what, floe_world_last_error(w));
    return w;
}

/* 8. mode I: a 40 x 40 mm plate (dx = 1 mm) pulled apart by its top and bottom strips to a
 * far-field strain of about 0.5 s_c over 100 us (12 wave crossings, quasi-static). With a
 * central pre-crack of 12 mm the bonds break at the crack tips and the crack grows along
 * its line; its faces open. The same plate without the crack breaks nothing. */
static const char *tension_scene =
    "  - region: {box: {min: [0, 0], max: [0.04, 0.04]}}\n"
    "    spacing: 0.001\n"
    "    material: {model: pmb, density: 8000, young: 190e9, critical_stretch: 0.002}\n"
    "    contact_material: steel\n"
    "    boundary:\n"
    "      - {region: {box: {min: [-1, -1], max: [1, 0.003]}}, displacement: [0, -1.7e-5], ramp: {linear: 1e-4}}\n"
    "      - {region: {box: {min: [-1, 0.037], max: [1, 1]}}, displacement: [0, 1.7e-5], ramp: {linear: 1e-4}}\n";
static void test_mode_one(void) {
    static char text[8192];
    double res[2][4]; /* broken bonds, max damage beyond the tips, max damage off the crack line, opening */
    for (int cracked = 0; cracked < 2; cracked++) {
        snprintf(text, sizeof text, "%s%s%s", scene_head, tension_scene,
                 cracked ? "    cracks: [{points: [[0.014, 0.02], [0.026, 0.02]]}]\n" : "");
        const char *what = cracked ? "pre-cracked plate" : "plate without crack";
        floe_world *w = run_scene(text, 2750, what); /* dt 4e-8 s: 110 us */
        if (!w) return;
        int f0;
        const floe_pd_body *b = floe_world_pd_body(w, 0, &f0);
        double *phi = malloc((size_t)b->n * sizeof *phi);
        floe_pd_damage(b, phi);
        double tips = 0, off = 0, up = 0, dn = 0;
        for (int i = 0; i < b->n; i++) {
            const double *X = b->X + 3 * i;
            double ey = fabs(X[1] - 0.02), ex = fabs(X[0] - 0.02);
            if (ey < 0.003 && ex > 0.006) tips = fmax(tips, phi[i]);
            if (ey > 0.004) off = fmax(off, phi[i]);
            if (ex < 0.001 && fabs(X[1] - 0.0205) < 1e-9) up = pview(w).x[3 * (f0 + i) + 1] - X[1];
            if (ex < 0.001 && fabs(X[1] - 0.0195) < 1e-9) dn = pview(w).x[3 * (f0 + i) + 1] - X[1];
        }
        res[cracked][0] = (double)b->nbroken;
        res[cracked][1] = tips;
        res[cracked][2] = off;
        res[cracked][3] = up - dn;
        printf("  %s at t = %.3g s: %lld bonds broken, damage beyond the tips %.3f, off the crack line %.3f, "
               "opening at the centre %.3g um\n", what, floe_world_time(w), (long long)b->nbroken, tips, off, (up - dn) * 1e6);
        free(phi);
        floe_world_destroy(w);
    }
    CHECK(res[0][0] == 0, "without the crack nothing breaks (%g bonds)", res[0][0]);
    CHECK(res[1][0] > 50 && res[1][1] > 0.3, "with it the crack grows from its tips (%g bonds, damage %.2f > 0.3 beyond "
          "the tips)", res[1][0], res[1][1]);
    CHECK(res[1][2] < 0.1, "only along the crack line (damage %.3f < 0.1 elsewhere)", res[1][2]);
    CHECK(res[1][3] > 5 * res[0][3] && res[1][3] > 0, "the crack faces open (%.3g um, uncracked %.3g um)", res[1][3] * 1e6,
          res[0][3] * 1e6);
}

/* 9. Kalthoff-Winkler (Kalthoff & Winkler 1988; PD: Silling 2003): a 100 x 200 mm maraging
 * steel plate with two 50 mm edge notches 50 mm apart, the strip between them struck at
 * 16.5 m/s (half the 32 m/s projectile speed, the usual velocity condition); the cracks
 * leave the notch tips at about 70 degrees to the notch in the experiment. Here at dx = 2 mm
 * (5,000 points, 90 us). The notches as cracks (between two rows of points) give a crack at
 * more than 50 degrees (measured 55.8); the notches as one row of points removed
 * (region.remove: bonds bridge them) give a shallow one (measured 36.0; the issue's 27 at its
 * resolution). Angle: the median over the points with damage > 0.35 at 12-45 mm from the
 * notch tip on the far side of the notch, of their direction from the tip (reference
 * positions), both notches mirrored onto one. */
static const char *kw_scene =
    "  - region:\n"
    "      box: {min: [0, -0.1], max: [0.1, 0.1]}\n"
    "%s"
    "    spacing: 0.002\n"
    "    material: {model: pmb, density: 8000, young: 190e9, fracture_energy: 22170}\n"
    "    contact_material: steel\n"
    "%s"
    "    boundary:\n"
    "      - {region: {box: {min: [-1, -0.024], max: [0.006, 0.024]}}, velocity: [16.5, 0]}\n";
static double kw_angle(int cracks, double *maxd) {
    static char text[8192];
    snprintf(text, sizeof text, "%s", scene_head);
    size_t L = strlen(text);
    if (cracks)
        snprintf(text + L, sizeof text - L, kw_scene, "",
                 "    cracks:\n      - {points: [[0, 0.024], [0.05, 0.024]]}\n      - {points: [[0, -0.024], [0.05, -0.024]]}\n");
    else
        snprintf(text + L, sizeof text - L, kw_scene,
                 "      remove:\n"
                 "        - {shape: {box: {size: [0.05, 0.001, 1]}}, position: [0.025, 0.025, 0]}\n"
                 "        - {shape: {box: {size: [0.05, 0.001, 1]}}, position: [0.025, -0.025, 0]}\n",
                 "");
    floe_world *w = run_scene(text, 1126, cracks ? "Kalthoff-Winkler, notches as cracks" : "Kalthoff-Winkler, notches removed");
    if (!w) return NAN;
    const floe_pd_body *b = floe_world_pd_body(w, 0, NULL);
    double *phi = malloc((size_t)b->n * sizeof *phi), ang[2000];
    floe_pd_damage(b, phi);
    int na = 0;
    *maxd = 0;
    for (int i = 0; i < b->n; i++) {
        const double *X = b->X + 3 * i;
        double y = fabs(X[1]), dxt = X[0] - 0.05, dyt = y - 0.025, r = hypot(dxt, dyt);
        *maxd = fmax(*maxd, phi[i]);
        if (phi[i] > 0.35 && dyt > 0 && r > 0.012 && r < 0.045 && na < 2000) ang[na++] = atan2(dyt, dxt) * 180 / M_PI;
    }
    for (int i = 1; i < na; i++) /* insertion sort for the median */
        for (int j = i; j > 0 && ang[j] < ang[j - 1]; j--) { double t = ang[j]; ang[j] = ang[j - 1]; ang[j - 1] = t; }
    double med = na ? ang[na / 2] : NAN;
    printf("  Kalthoff-Winkler, notches %s: t = %.3g s, %lld bonds cut at set-up, %lld broken, %lld bridging the notches; "
           "%d damaged points 12-45 mm from the tips, median angle %.1f deg\n",
           cracks ? "as cracks" : "as one removed row", floe_world_time(w), (long long)b->ncut, (long long)b->nbroken,
           (long long)b->nbridge, na, med);
    CHECK(na >= 10, "a crack runs from the notch tips (%d damaged points)", na);
    CHECK(cracks ? b->nbridge == 0 : b->nbridge > 0, "bridging bonds: %lld", (long long)b->nbridge);
    free(phi);
    floe_world_destroy(w);
    return med;
}
static void test_kalthoff_winkler(void) {
    double m1, m0;
    double a1 = kw_angle(1, &m1), a0 = kw_angle(0, &m0);
    CHECK(a1 > 50 && a1 < 80, "notches as cracks: crack angle %.1f deg in (50, 80) (experiment: about 70)", a1);
    CHECK(a0 < 45, "notches as one removed row: %.1f deg < 45 (the bonds across the notch make it no notch)", a0);
    CHECK(a1 - a0 > 15, "the cracks turn %.1f deg more", a1 - a0);
}

int main(void) {
    test_cut_brute_force();
    test_crack_check();
    test_material_state();
    test_bonds_across();
    test_scene_cracks();
    test_polygon_region();
    test_faces_contact();
    test_mode_one();
    test_kalthoff_winkler();
    return check_summary("test_pd_crack");
}
