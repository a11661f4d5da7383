/* test_shapes.c - polytopes, curved primitives, the rounded modifier and compounds:
 * exact SDFs versus independent brute force (point-triangle distances for polyhedra, dense
 * surface sampling with local refinement for curved shapes), projections on the surface,
 * exact mass properties versus closed forms, principal frames, compounds, degenerate input,
 * and gradients versus central differences. */
#include "floe.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>

static double rnd(unsigned *s) { *s = *s * 1664525u + 1013904223u; return (*s >> 8) / 16777216.0; }
static double rndn(unsigned *s) { /* standard normal (Box-Muller) */
    double u = rnd(s) + 1e-12, v = rnd(s);
    return sqrt(-2 * log(u)) * cos(2 * M_PI * v);
}
static void rnd_unit(unsigned *s, double d[3]) {
    floe_v3_set(d, rndn(s), rndn(s), rndn(s));
    floe_v3_scale(d, 1 / floe_v3_norm(d));
}
static void rnd_quat(unsigned *s, double q[4]) {
    q[0] = rndn(s); q[1] = rndn(s); q[2] = rndn(s); q[3] = rndn(s);
    floe_q_normalize(q);
}
static void report(const char *what, double val, double tol) {
    CHECK(val <= tol && val == val, "%s = %.3g > tol %.1g", what, val, tol);
    printf("  %-60s %.2e (tol %.0e)\n", what, val, tol);
}

/* ---- independent point-triangle distance: plane projection with barycentric inside
 * test, otherwise the nearest of the three edges ---- */
static double seg_dist(const double p[3], const double a[3], const double b[3]) {
    double ab[3], ap[3];
    floe_v3_sub(ab, b, a); floe_v3_sub(ap, p, a);
    double t = floe_v3_dot(ap, ab) / floe_v3_dot(ab, ab);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double q[3] = {a[0] + t * ab[0] - p[0], a[1] + t * ab[1] - p[1], a[2] + t * ab[2] - p[2]};
    return floe_v3_norm(q);
}
static double tri_dist(const double p[3], const double a[3], const double b[3], const double c[3]) {
    double ab[3], ac[3], n[3], ap[3];
    floe_v3_sub(ab, b, a); floe_v3_sub(ac, c, a); floe_v3_cross(n, ab, ac);
    double nn = floe_v3_norm(n);
    floe_v3_scale(n, 1 / nn);
    floe_v3_sub(ap, p, a);
    double h = floe_v3_dot(ap, n);
    double q[3] = {p[0] - h * n[0], p[1] - h * n[1], p[2] - h * n[2]};
    /* barycentric coordinates of q by sub-triangle areas */
    double w[3], qa[3], qb[3], qc[3];
    floe_v3_sub(qa, a, q); floe_v3_sub(qb, b, q); floe_v3_sub(qc, c, q);
    floe_v3_cross(w, qb, qc); double la = floe_v3_dot(w, n);
    floe_v3_cross(w, qc, qa); double lb = floe_v3_dot(w, n);
    floe_v3_cross(w, qa, qb); double lc = floe_v3_dot(w, n);
    if (la >= 0 && lb >= 0 && lc >= 0) return fabs(h);
    return fmin(seg_dist(p, a, b), fmin(seg_dist(p, b, c), seg_dist(p, c, a)));
}

static void body_to_input(const double *fx, const double *fq, const double b[3], double X[3]) {
    floe_q_rotate(X, fq, b);
    floe_v3_add(X, X, fx);
}
static void input_to_body(const double *fx, const double *fq, const double X[3], double b[3]) {
    double d[3];
    floe_v3_sub(d, X, fx);
    floe_q_rotate_inv(b, fq, d);
}

/* gradients: unit everywhere, equal to central differences where the SDF is smooth */
static void check_gradients(const char *name, const floe_geometry *g, double scale, unsigned seed) {
    unsigned s = seed;
    double worst_unit = 0, worst_fd = 0;
    int compared = 0;
    for (int k = 0; k < 600; k++) {
        double X[3] = {(rnd(&s) - 0.5) * 3 * scale, (rnd(&s) - 0.5) * 3 * scale, (rnd(&s) - 0.5) * 3 * scale};
        double n[3], fd[3], h = 1e-6 * scale;
        floe_geometry_gradient(g, X, n);
        worst_unit = fmax(worst_unit, fabs(floe_v3_norm(n) - 1));
        for (int a = 0; a < 3; a++) {
            double p[3] = {X[0], X[1], X[2]}, m[3] = {X[0], X[1], X[2]};
            p[a] += h; m[a] -= h;
            fd[a] = (floe_geometry_sdf(g, p) - floe_geometry_sdf(g, m)) / (2 * h);
        }
        if (fabs(floe_v3_norm(fd) - 1) > 1e-6) continue; /* at a kink (medial axis, edge) */
        /* also skip where one-sided differences disagree (within h of a kink) */
        double diff[3];
        floe_v3_sub(diff, n, fd);
        compared++;
        worst_fd = fmax(worst_fd, floe_v3_norm(diff));
    }
    char what[160];
    snprintf(what, sizeof what, "%s: max ||grad| - 1|", name);
    report(what, worst_unit, 1e-12);
    snprintf(what, sizeof what, "%s: max |grad - central diff| (%d pts)", name, compared);
    report(what, worst_fd, 1e-5);
    CHECK(compared > 300, "%s: too few smooth points compared (%d)", name, compared);
}

/* ---- dense surface sampling with local refinement: a surface is a set of patches
 * (u, v) in [0,1]^2 -> R^3; the distance is the minimum over a coarse grid, refined by
 * repeated zooms around the best sample of each patch. Returns the distance and the
 * final sampling step (an upper bound of the first-order sampling error). ---- */
typedef void (*patch_fn)(const void *shape, int patch, double u, double v, double out[3]);
static double sampled_distance(patch_fn f, const void *shape, int npatch, double size, const double X[3], double *step) {
    const int NC = 120, NZ = 21, LEVELS = 6;
    double best = INFINITY, hmax = 0;
    for (int p = 0; p < npatch; p++) {
        /* the 4 best coarse samples, each refined (the basin of the best one need not hold
         * the global minimum, e.g. near the degenerate apex or pole of a parametrisation) */
        double cu[4] = {0}, cv[4] = {0}, cd[4] = {INFINITY, INFINITY, INFINITY, INFINITY}, P[3], d[3];
        for (int i = 0; i <= NC; i++)
            for (int j = 0; j <= NC; j++) {
                double u = (double)i / NC, v = (double)j / NC;
                f(shape, p, u, v, P);
                floe_v3_sub(d, P, X);
                double dd = floe_v3_norm(d);
                if (dd >= cd[3] || dd == cd[0] || dd == cd[1] || dd == cd[2]) continue; /* one per degenerate point */
                int k = 3;
                while (k > 0 && cd[k - 1] > dd) { cd[k] = cd[k - 1]; cu[k] = cu[k - 1]; cv[k] = cv[k - 1]; k--; }
                cd[k] = dd; cu[k] = u; cv[k] = v;
            }
        for (int c = 0; c < 4; c++) {
            double bu = cu[c], bv = cv[c], bd = cd[c];
            double w = 2.0 / NC; /* window half-width in parameter space */
            for (int l = 0; l < LEVELS; l++) {
                double u0 = bu, v0 = bv;
                for (int i = 0; i < NZ; i++)
                    for (int j = 0; j < NZ; j++) {
                        double u = u0 - w + 2 * w * i / (NZ - 1), v = v0 - w + 2 * w * j / (NZ - 1);
                        u = u < 0 ? 0 : u > 1 ? 1 : u; /* v is the azimuth in every patch: periodic */
                        f(shape, p, u, v, P);
                        floe_v3_sub(d, P, X);
                        double dd = floe_v3_norm(d);
                        if (dd < bd) { bd = dd; bu = u; bv = v; }
                    }
                w = 2 * w / (NZ - 1) * 2;
            }
            hmax = fmax(hmax, w);
            best = fmin(best, bd);
        }
    }
    /* parameter step times the largest speed of the parametrisations (< 2 pi size) */
    *step = hmax * 2 * M_PI * size;
    return best;
}

typedef struct { double a[3]; } ell_t;
static void ell_patch(const void *sh, int p, double u, double v, double o[3]) {
    const ell_t *e = sh; (void)p;
    double th = M_PI * u, ph = 2 * M_PI * v;
    floe_v3_set(o, e->a[0] * sin(th) * cos(ph), e->a[1] * sin(th) * sin(ph), e->a[2] * cos(th));
}
typedef struct { double R, h; } rh_t;
static void cyl_patch(const void *sh, int p, double u, double v, double o[3]) {
    const rh_t *c = sh;
    double ph = 2 * M_PI * v;
    if (p == 0) floe_v3_set(o, c->R * cos(ph), c->R * sin(ph), -c->h + 2 * c->h * u);
    else floe_v3_set(o, u * c->R * cos(ph), u * c->R * sin(ph), p == 1 ? c->h : -c->h);
}
static void cap_patch(const void *sh, int p, double u, double v, double o[3]) {
    const rh_t *c = sh;
    double ph = 2 * M_PI * v;
    if (p == 0) floe_v3_set(o, c->R * cos(ph), c->R * sin(ph), -c->h + 2 * c->h * u);
    else {
        double th = 0.5 * M_PI * u; /* hemisphere polar angle from the tip */
        floe_v3_set(o, c->R * sin(th) * cos(ph), c->R * sin(th) * sin(ph), p == 1 ? c->h + c->R * cos(th) : -c->h - c->R * cos(th));
    }
}
static void cone_patch(const void *sh, int p, double u, double v, double o[3]) {
    const rh_t *c = sh; /* R, h = height */
    double ph = 2 * M_PI * v, zb = -0.25 * c->h;
    if (p == 0) floe_v3_set(o, (1 - u) * c->R * cos(ph), (1 - u) * c->R * sin(ph), zb + u * c->h);
    else floe_v3_set(o, u * c->R * cos(ph), u * c->R * sin(ph), zb);
}

/* compare a curved shape with the sampled distance; inside() gives the sign */
static void check_curved(const char *name, const floe_geometry *g, patch_fn f, const void *sh, int npatch, double size,
                         int (*inside)(const void *, const double *), int npts, unsigned seed) {
    unsigned s = seed;
    double worst = 0, worst_proj = 0, worst_near = 0, step = 0, st;
    for (int k = 0; k < npts; k++) {
        double X[3] = {(rnd(&s) - 0.5) * 3 * size, (rnd(&s) - 0.5) * 3 * size, (rnd(&s) - 0.5) * 3 * size};
        if (k % 3 == 0) floe_v3_scale(X, 0.3); /* more inside points */
        double phi = floe_geometry_sdf(g, X);
        double bf = sampled_distance(f, sh, npatch, size, X, &st);
        step = fmax(step, st);
        if (inside(sh, X)) bf = -bf;
        worst = fmax(worst, fabs(phi - bf));
        double P[3], d[3];
        floe_geometry_project(g, X, P);
        worst_proj = fmax(worst_proj, fabs(floe_geometry_sdf(g, P)));
        floe_v3_sub(d, X, P);
        worst_near = fmax(worst_near, fabs(floe_v3_norm(d) - fabs(phi)));
    }
    char what[160];
    snprintf(what, sizeof what, "%s: max |sdf - sampled| / size (sampling step %.1e)", name, step / size);
    report(what, worst / size, step / size);
    snprintf(what, sizeof what, "%s: max |sdf(project(X))| / size", name);
    report(what, worst_proj / size, 1e-12);
    snprintf(what, sizeof what, "%s: max ||X - project(X)| - |sdf|| / size", name);
    report(what, worst_near / size, 1e-12);
}
static int ell_in(const void *sh, const double *X) {
    const ell_t *e = sh;
    double q = 0;
    for (int k = 0; k < 3; k++) q += (X[k] / e->a[k]) * (X[k] / e->a[k]);
    return q < 1;
}
static int cyl_in(const void *sh, const double *X) {
    const rh_t *c = sh;
    return hypot(X[0], X[1]) < c->R && fabs(X[2]) < c->h;
}
static int cap_in(const void *sh, const double *X) {
    const rh_t *c = sh;
    double z = fmax(-c->h, fmin(c->h, X[2]));
    return hypot(hypot(X[0], X[1]), X[2] - z) < c->R;
}
static int cone_in(const void *sh, const double *X) {
    const rh_t *c = sh;
    double zb = -0.25 * c->h, r = hypot(X[0], X[1]);
    return X[2] > zb && X[2] < zb + c->h && r < c->R * (1 - (X[2] - zb) / c->h);
}

/* analytic mass vs the numerical quadrature with its own error estimate */
static void check_mass_numeric(const char *name, const floe_geometry *g) {
    floe_mass_properties a, b;
    CHECK(floe_geometry_mass_properties(g, 3, 1.0, &a) == FLOE_OK, "%s: mass failed", name);
    CHECK(floe_geometry_mass_numeric(g, 3, 1.0, 128, &b) == FLOE_OK, "%s: numeric mass failed", name);
    double e = fabs(b.volume - a.volume) / a.volume;
    for (int k = 0; k < 3; k++) e = fmax(e, fabs(b.inertia[k] - a.inertia[k]) / a.inertia[k]);
    char what[160];
    snprintf(what, sizeof what, "%s: analytic vs quadrature (n=128), tol 2x its estimate", name);
    report(what, e, 2 * b.quadrature_error);
}

/* ---- polyhedra ---- */
static void test_random_polyhedron(void) {
    printf("random convex polyhedron from planes\n");
    unsigned s = 12345;
    enum { NP = 24 };
    double planes[4 * NP], c0[3] = {0.3, -0.2, 0.5};
    for (int i = 0; i < NP; i++) {
        double n[3];
        rnd_unit(&s, n);
        double scale = 0.5 + rnd(&s); /* non-unit normals are allowed */
        for (int k = 0; k < 3; k++) planes[4 * i + k] = scale * n[k];
        planes[4 * i + 3] = scale * (floe_v3_dot(n, c0) + 0.8 + 0.4 * rnd(&s));
    }
    char err[256] = "";
    floe_geometry *g = floe_polyhedron_from_planes(planes, NP, err, sizeof err);
    CHECK(g != NULL, "random polyhedron refused: %s", err);
    if (!g) return;
    const floe_polytope *p = (const floe_polytope *)g;
    CHECK(strcmp(g->klass->name, "polyhedron") == 0 && g->klass->kind == FLOE_GEOM_USER, "class name/kind");
    printf("  %d vertices, %d faces, %d triangles, radius %.3f\n", p->nv, p->np, p->nt, p->radius);
    /* vertices: feasible, each on >= 3 input planes (input coordinates) */
    double worst_v = 0;
    int on_ok = 1;
    for (int j = 0; j < p->nv; j++) {
        double X[3];
        body_to_input(p->frame_x, p->frame_q, p->v + 3 * j, X);
        int on = 0;
        for (int i = 0; i < NP; i++) {
            double nn = floe_v3_norm(planes + 4 * i), d = (floe_v3_dot(planes + 4 * i, X) - planes[4 * i + 3]) / nn;
            worst_v = fmax(worst_v, d);
            if (fabs(d) < 1e-12) on++;
        }
        if (on < 3) on_ok = 0;
    }
    report("vertices: max violation of the input planes", worst_v, 1e-12);
    CHECK(on_ok, "every vertex lies on at least 3 input planes");
    /* sdf vs brute force in the input frame: inside max over the input planes, outside min
     * over the boundary triangles */
    double R = p->radius, worst = 0, worst_proj = 0, worst_near = 0, worst_nearest = 0;
    int nin = 0;
    for (int k = 0; k < 2000; k++) {
        double X[3], B[3];
        for (int a = 0; a < 3; a++) X[a] = c0[a] + (rnd(&s) - 0.5) * 3.2 * R;
        if (k % 4 == 0) for (int a = 0; a < 3; a++) X[a] = p->frame_x[a] + 0.5 * (X[a] - p->frame_x[a]);
        input_to_body(p->frame_x, p->frame_q, X, B);
        double phi = floe_geometry_sdf(g, B), bf = -INFINITY;
        for (int i = 0; i < NP; i++) {
            double nn = floe_v3_norm(planes + 4 * i);
            bf = fmax(bf, (floe_v3_dot(planes + 4 * i, X) - planes[4 * i + 3]) / nn);
        }
        if (bf > 0) {
            bf = INFINITY;
            for (int t = 0; t < p->nt; t++) {
                double a[3], b[3], c[3];
                body_to_input(p->frame_x, p->frame_q, p->v + 3 * p->tri[3 * t], a);
                body_to_input(p->frame_x, p->frame_q, p->v + 3 * p->tri[3 * t + 1], b);
                body_to_input(p->frame_x, p->frame_q, p->v + 3 * p->tri[3 * t + 2], c);
                bf = fmin(bf, tri_dist(X, a, b, c));
            }
        } else nin++;
        worst = fmax(worst, fabs(phi - bf) / R);
        double P[3], d[3];
        floe_geometry_project(g, B, P);
        worst_proj = fmax(worst_proj, fabs(floe_geometry_sdf(g, P)) / R);
        floe_v3_sub(d, B, P);
        worst_near = fmax(worst_near, fabs(floe_v3_norm(d) - fabs(phi)) / R);
        /* nearest: no vertex (and, by the brute force, no boundary point) is closer */
        if (phi > 0) worst_nearest = fmax(worst_nearest, (floe_v3_norm(d) - bf) / R);
    }
    printf("  %d of 2000 points inside\n", nin);
    report("polyhedron: max |sdf - brute force| / radius", worst, 1e-12);
    report("polyhedron: max |sdf(project(X))| / radius", worst_proj, 1e-12);
    report("polyhedron: max ||X - project(X)| - |sdf|| / radius", worst_near, 1e-12);
    report("polyhedron: project distance above brute-force nearest / radius", worst_nearest, 1e-12);
    /* support = max over vertices, and the surface sits inside the support plane */
    double worst_sup = 0;
    for (int k = 0; k < 200; k++) {
        double d[3], o[3], best = -INFINITY;
        rnd_unit(&s, d);
        floe_geometry_class const *kl = g->klass;
        kl->support(g, d, o);
        for (int j = 0; j < p->nv; j++) best = fmax(best, floe_v3_dot(d, p->v + 3 * j));
        worst_sup = fmax(worst_sup, fabs(floe_v3_dot(d, o) - best));
    }
    report("polyhedron: support vs max over vertices", worst_sup, 1e-15);
    int cnt = 0;
    CHECK(g->klass->vertices(g, &cnt) == p->v && cnt == p->nv, "vertices entry");
    /* mass: off-axis 0 after the principal rotation, centroid at the origin */
    floe_mass_properties m;
    CHECK(floe_geometry_mass_properties(g, 3, 2.0, &m) == FLOE_OK, "mass failed");
    report("polyhedron: off_axis after the principal rotation", m.off_axis, 1e-12);
    report("polyhedron: |centroid| / radius", floe_v3_norm(m.centroid) / R, 1e-12);
    CHECK(m.inertia[0] <= m.inertia[1] && m.inertia[1] <= m.inertia[2], "ascending principal moments");
    floe_mass_properties nm;
    floe_geometry_mass_numeric(g, 3, 2.0, 128, &nm);
    double e = fabs(nm.volume - m.volume) / m.volume;
    for (int k = 0; k < 3; k++) e = fmax(e, fabs(nm.inertia[k] - m.inertia[k]) / m.inertia[k]);
    report("polyhedron: exact mass vs quadrature (tol 2x its estimate)", e, 2 * nm.quadrature_error);
    check_gradients("polyhedron", g, R, 99);
    floe_geometry_destroy(g);
}

static void check_poly_mass(const char *name, floe_geometry *g, const char *err, double V, const double I[3]) {
    CHECK(g != NULL, "%s refused: %s", name, err);
    if (!g) return;
    floe_mass_properties m;
    CHECK(floe_geometry_mass_properties(g, 3, 1.0, &m) == FLOE_OK, "%s: mass failed", name);
    char what[160];
    snprintf(what, sizeof what, "%s volume", name);
    CHECK_NEAR(m.volume, V, 1e-12, what);
    for (int k = 0; k < 3; k++) {
        snprintf(what, sizeof what, "%s principal moment %d", name, k);
        CHECK_NEAR(m.inertia[k], I[k], 1e-12, what);
    }
    snprintf(what, sizeof what, "%s off_axis", name);
    report(what, m.off_axis, 1e-12);
    floe_geometry_destroy(g);
}

static void test_polyhedron_mass(void) {
    printf("polyhedron mass properties\n");
    char err[256] = "";
    /* box lx, ly, lz from planes, centred away from the origin */
    double lx = 0.7, ly = 1.3, lz = 2.1, c[3] = {1, -2, 3};
    double bp[24] = {1, 0, 0, c[0] + lx / 2, -1, 0, 0, -c[0] + lx / 2, 0, 1, 0, c[1] + ly / 2,
                     0, -1, 0, -c[1] + ly / 2, 0, 0, 1, c[2] + lz / 2, 0, 0, -1, -c[2] + lz / 2};
    double V = lx * ly * lz;
    double Ib[3] = {V * (lx * lx + ly * ly) / 12, V * (lx * lx + lz * lz) / 12, V * (ly * ly + lz * lz) / 12};
    check_poly_mass("box (planes)", floe_polyhedron_from_planes(bp, 6, err, sizeof err), err, V, Ib);
    /* regular tetrahedron: vertices (1,1,1), (1,-1,-1), (-1,1,-1), (-1,-1,1), edge 2 sqrt 2 */
    double tv[12] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1}, tp[16];
    for (int i = 0; i < 4; i++) {
        for (int k = 0; k < 3; k++) tp[4 * i + k] = -tv[3 * i + k];
        tp[4 * i + 3] = 1; /* -v.X <= 1: the face opposite v */
    }
    double a2 = 8, Vt = 8.0 / 3.0, It[3] = {Vt * a2 / 20, Vt * a2 / 20, Vt * a2 / 20};
    check_poly_mass("regular tetrahedron (planes)", floe_polyhedron_from_planes(tp, 4, err, sizeof err), err, Vt, It);
    int tt[12] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2}; /* orientation either way */
    check_poly_mass("regular tetrahedron (mesh)", floe_polyhedron_from_mesh(tv, 4, tt, 4, err, sizeof err), err, Vt, It);
    /* regular octahedron |x| + |y| + |z| <= 1: V = 4/3, I = m a^2 / 10 = 4/15 (a = sqrt 2) */
    double op[32];
    for (int i = 0; i < 8; i++) {
        op[4 * i] = i & 1 ? 1 : -1; op[4 * i + 1] = i & 2 ? 1 : -1; op[4 * i + 2] = i & 4 ? 1 : -1; op[4 * i + 3] = 1;
    }
    double Io[3] = {4.0 / 15, 4.0 / 15, 4.0 / 15};
    check_poly_mass("regular octahedron (planes)", floe_polyhedron_from_planes(op, 8, err, sizeof err), err, 4.0 / 3, Io);
    double ov[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    int ot[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    check_poly_mass("regular octahedron (mesh)", floe_polyhedron_from_mesh(ov, 6, ot, 8, err, sizeof err), err, 4.0 / 3, Io);
    /* cube mesh: 12 triangles, merged into 6 faces */
    double cv[24];
    for (int v = 0; v < 8; v++)
        for (int k = 0; k < 3; k++) cv[3 * v + k] = (v >> k & 1 ? 0.5 : -0.5) * (k == 0 ? lx : k == 1 ? ly : lz);
    int ct[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    floe_geometry *cm = floe_polyhedron_from_mesh(cv, 8, ct, 12, err, sizeof err);
    CHECK(cm && ((floe_polytope *)cm)->np == 6 && ((floe_polytope *)cm)->nv == 8, "cube mesh: 6 merged faces, 8 vertices (%s)", err);
    check_poly_mass("box (mesh)", cm, err, V, Ib);
    /* prism of a unit square, height 0.5 */
    double sq[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    double Ip[3] = {0.5 * (1 + 0.25) / 12, 0.5 * (1 + 0.25) / 12, 0.5 * 2.0 / 12};
    check_poly_mass("prism (square, h 0.5)", floe_prism_create(sq, 4, 0.5, err, sizeof err), err, 0.5, Ip);
    /* a flat hexagonal prism: its dim-2 mass is the hexagon's (section z = 0) */
    double hx[12];
    for (int i = 0; i < 6; i++) { hx[2 * i] = cos(M_PI / 3 * i); hx[2 * i + 1] = sin(M_PI / 3 * i); }
    floe_geometry *hp = floe_prism_create(hx, 6, 0.2, err, sizeof err), *hg = floe_polygon_create(hx, 6, err, sizeof err);
    CHECK(hp && hg, "hexagonal prism / polygon: %s", err);
    if (hp && hg) {
        floe_mass_properties m2, m3, mg;
        CHECK(floe_geometry_mass_properties(hp, 2, 1.0, &m2) == FLOE_OK && floe_geometry_mass_properties(hp, 3, 1.0, &m3) == FLOE_OK &&
              floe_geometry_mass_properties(hg, 2, 1.0, &mg) == FLOE_OK, "hexagonal prism mass");
        CHECK_NEAR(m3.volume, 0.2 * 1.5 * sqrt(3.0), 1e-12, "hexagonal prism volume");
        CHECK_NEAR(m2.volume, mg.volume, 1e-12, "hexagonal prism in 2D: section area = polygon area");
        CHECK_NEAR(m2.inertia[2], mg.inertia[2], 1e-12, "hexagonal prism in 2D: polar moment = polygon's");
    }
    floe_geometry_destroy(hp); floe_geometry_destroy(hg);
}

static void test_principal_frame(void) {
    printf("principal frame of a rotated box given as planes\n");
    unsigned s = 777;
    double q[4], x0[3] = {0.4, 1.7, -2.2}, h[3] = {0.5, 1.0, 1.5};
    rnd_quat(&s, q);
    double planes[24], corners[24];
    for (int k = 0; k < 3; k++)
        for (int sg = 0; sg < 2; sg++) {
            double e[3] = {0, 0, 0}, n[3];
            e[k] = sg ? -1 : 1;
            floe_q_rotate(n, q, e);
            double *pl = planes + 4 * (2 * k + sg);
            floe_v3_copy(pl, n);
            pl[3] = floe_v3_dot(n, x0) + h[k];
        }
    for (int v = 0; v < 8; v++) {
        double b[3];
        for (int k = 0; k < 3; k++) b[k] = (v >> k & 1 ? 1 : -1) * h[k];
        floe_q_rotate(corners + 3 * v, q, b);
        floe_v3_add(corners + 3 * v, corners + 3 * v, x0);
    }
    char err[256] = "";
    floe_geometry *g = floe_polyhedron_from_planes(planes, 6, err, sizeof err);
    CHECK(g != NULL, "rotated box refused: %s", err);
    if (!g) return;
    const floe_polytope *p = (const floe_polytope *)g;
    floe_mass_properties m;
    floe_geometry_mass_properties(g, 3, 1.0, &m);
    report("rotated box: off_axis", m.off_axis, 1e-12);
    double worst = 0;
    for (int j = 0; j < p->nv; j++) {
        double X[3], best = INFINITY;
        body_to_input(p->frame_x, p->frame_q, p->v + 3 * j, X);
        for (int v = 0; v < 8; v++) {
            double d[3];
            floe_v3_sub(d, X, corners + 3 * v);
            best = fmin(best, floe_v3_norm(d));
        }
        worst = fmax(worst, best);
    }
    CHECK(p->nv == 8, "rotated box: 8 vertices (got %d)", p->nv);
    report("rotated box: frame reproduces the input corners", worst, 1e-12);
    double dx[3];
    floe_v3_sub(dx, p->frame_x, x0);
    report("rotated box: frame_x = centre", floe_v3_norm(dx), 1e-12);
    /* body x is the longest axis (smallest moment): input axis 2 */
    double ex[3] = {1, 0, 0}, bx[3], ax[3], e2[3] = {0, 0, 1};
    floe_q_rotate(bx, p->frame_q, ex);
    floe_q_rotate(ax, q, e2);
    report("rotated box: body x along the longest side", 1 - fabs(floe_v3_dot(bx, ax)), 1e-12);
    double V = 8 * h[0] * h[1] * h[2];
    CHECK_NEAR(m.inertia[0], V * (4 * h[0] * h[0] + 4 * h[1] * h[1]) / 12, 1e-12, "rotated box smallest moment");
    floe_geometry_destroy(g);
}

static void test_polygons(void) {
    printf("polygons\n");
    char err[256] = "";
    /* regular hexagon, side s, rotated and shifted, plus interior and collinear points */
    double sd = 0.8, xy[2 * 9], off[2] = {2.0, -1.0};
    for (int i = 0; i < 6; i++) {
        double a = M_PI / 3 * i + 0.2;
        xy[2 * i] = off[0] + sd * cos(a); xy[2 * i + 1] = off[1] + sd * sin(a);
    }
    xy[12] = off[0]; xy[13] = off[1];                               /* interior */
    xy[14] = 0.5 * (xy[0] + xy[2]); xy[15] = 0.5 * (xy[1] + xy[3]); /* on an edge */
    xy[16] = off[0] + 0.1; xy[17] = off[1] - 0.2;
    floe_geometry *g = floe_polygon_create(xy, 9, err, sizeof err);
    CHECK(g != NULL, "hexagon refused: %s", err);
    if (!g) return;
    const floe_polytope *p = (const floe_polytope *)g;
    CHECK(p->nv == 6 && p->dim == 2 && g->klass == &floe_polytope_class, "hexagon: 6 hull vertices, dim 2 (got %d)", p->nv);
    floe_mass_properties m;
    CHECK(floe_geometry_mass_properties(g, 2, 1.0, &m) == FLOE_OK, "polygon mass");
    double A = 1.5 * sqrt(3.0) * sd * sd, J = 5 * sqrt(3.0) / 8 * pow(sd, 4);
    CHECK_NEAR(m.volume, A, 1e-12, "hexagon area");
    CHECK_NEAR(m.inertia[2], J, 1e-12, "hexagon polar moment");
    CHECK_NEAR(m.inertia[0], J / 2, 1e-12, "hexagon planar moment x");
    CHECK_NEAR(m.inertia[1], J / 2, 1e-12, "hexagon planar moment y");
    CHECK_NEAR(p->frame_x[0], off[0], 1e-12, "hexagon centroid x");
    CHECK_NEAR(p->frame_x[1], off[1], 1e-12, "hexagon centroid y");
    CHECK(floe_geometry_mass_properties(g, 3, 1.0, &m) == FLOE_ENOTSUP, "polygon in 3D: ENOTSUP");
    /* sdf vs brute force (2D, z ignored) */
    unsigned s = 4242;
    double worst = 0, worst_proj = 0;
    for (int k = 0; k < 2000; k++) {
        double X[3] = {(rnd(&s) - 0.5) * 3 * sd, (rnd(&s) - 0.5) * 3 * sd, (rnd(&s) - 0.5) * 5}, bf = -INFINITY;
        for (int i = 0; i < 6; i++) { /* body vertices: hexagon edges */
            const double *a = p->v + 3 * i, *b = p->v + 3 * ((i + 1) % 6);
            double ex = b[0] - a[0], ey = b[1] - a[1], L = hypot(ex, ey);
            bf = fmax(bf, (ey * (X[0] - a[0]) - ex * (X[1] - a[1])) / L);
        }
        if (bf > 0) {
            bf = INFINITY;
            for (int i = 0; i < 6; i++) {
                double a[3] = {p->v[3 * i], p->v[3 * i + 1], X[2]};
                double b[3] = {p->v[3 * ((i + 1) % 6)], p->v[3 * ((i + 1) % 6) + 1], X[2]};
                bf = fmin(bf, seg_dist(X, a, b));
            }
        }
        worst = fmax(worst, fabs(floe_geometry_sdf(g, X) - bf) / sd);
        double P[3];
        floe_geometry_project(g, X, P);
        worst_proj = fmax(worst_proj, fabs(floe_geometry_sdf(g, P)) / sd + fabs(P[2] - X[2]));
    }
    report("hexagon: max |sdf - brute force| / side", worst, 1e-12);
    report("hexagon: max |sdf(project(X))| / side", worst_proj, 1e-12);
    check_gradients("hexagon", g, sd, 5);
    floe_geometry_destroy(g);
    /* rectangle a x b rotated by 30 degrees: principal frame, moments */
    double a = 2.0, b = 0.6, th = M_PI / 6, r4[8];
    for (int i = 0; i < 4; i++) {
        double x = (i == 1 || i == 2 ? 0.5 : -0.5) * a, y = (i >= 2 ? 0.5 : -0.5) * b;
        r4[2 * i] = 1 + cos(th) * x - sin(th) * y; r4[2 * i + 1] = 3 + sin(th) * x + cos(th) * y;
    }
    g = floe_polygon_create(r4, 4, err, sizeof err);
    CHECK(g != NULL, "rectangle refused: %s", err);
    if (!g) return;
    p = (const floe_polytope *)g;
    floe_geometry_mass_properties(g, 2, 3.0, &m);
    double M = 3 * a * b;
    CHECK_NEAR(m.volume, a * b, 1e-12, "rectangle area");
    CHECK_NEAR(m.inertia[0], M * b * b / 12, 1e-12, "rectangle moment about body x");
    CHECK_NEAR(m.inertia[1], M * a * a / 12, 1e-12, "rectangle moment about body y");
    CHECK_NEAR(m.inertia[2], M * (a * a + b * b) / 12, 1e-12, "rectangle polar moment");
    report("rectangle: off_axis", m.off_axis, 1e-12);
    double worst_v = 0;
    for (int j = 0; j < p->nv; j++) {
        double X[3], best = INFINITY;
        body_to_input(p->frame_x, p->frame_q, p->v + 3 * j, X);
        for (int i = 0; i < 4; i++) best = fmin(best, hypot(X[0] - r4[2 * i], X[1] - r4[2 * i + 1]) + fabs(X[2]));
        worst_v = fmax(worst_v, best);
    }
    report("rectangle: frame reproduces the input points", worst_v, 1e-12);
    floe_geometry_destroy(g);
}

static void test_curved(void) {
    printf("curved primitives\n");
    ell_t es = {{0.9, 0.5, 0.3}};
    floe_geometry *g = floe_ellipsoid_create(es.a[0], es.a[1], es.a[2]);
    CHECK(g && strcmp(g->klass->name, "ellipsoid") == 0, "ellipsoid create");
    check_curved("ellipsoid", g, ell_patch, &es, 1, 0.9, ell_in, 300, 11);
    check_gradients("ellipsoid", g, 0.9, 12);
    check_mass_numeric("ellipsoid", g);
    {
        unsigned s = 3;
        double worst = 0;
        for (int k = 0; k < 100; k++) {
            double d[3], o[3];
            rnd_unit(&s, d);
            g->klass->support(g, d, o);
            double h = sqrt(pow(es.a[0] * d[0], 2) + pow(es.a[1] * d[1], 2) + pow(es.a[2] * d[2], 2));
            worst = fmax(worst, fabs(floe_v3_dot(o, d) - h));
        }
        report("ellipsoid: support . d vs sqrt(sum a_i^2 d_i^2)", worst, 1e-15);
        floe_mass_properties m;
        CHECK(floe_geometry_mass_properties(g, 2, 1.0, &m) == FLOE_OK, "ellipse mass");
        CHECK_NEAR(m.volume, M_PI * 0.9 * 0.5, 1e-14, "ellipsoid in 2D: ellipse area");
    }
    floe_geometry_destroy(g);
    /* a sphere-like and a prolate one: equal axes exercise the degenerate branches */
    ell_t e2 = {{0.4, 0.4, 0.7}};
    g = floe_ellipsoid_create(e2.a[0], e2.a[1], e2.a[2]);
    check_curved("spheroid", g, ell_patch, &e2, 1, 0.7, ell_in, 150, 13);
    floe_geometry_destroy(g);

    rh_t cy = {0.4, 0.6};
    g = floe_cylinder_create(0.4, 1.2);
    CHECK(g && strcmp(g->klass->name, "cylinder") == 0, "cylinder create");
    check_curved("cylinder", g, cyl_patch, &cy, 3, 0.72, cyl_in, 300, 21);
    check_gradients("cylinder", g, 0.72, 22);
    check_mass_numeric("cylinder", g);
    floe_geometry_destroy(g);

    rh_t ca = {0.3, 0.5};
    g = floe_capsule_create(0.3, 1.0);
    CHECK(g && strcmp(g->klass->name, "capsule") == 0, "capsule create");
    check_curved("capsule", g, cap_patch, &ca, 3, 0.8, cap_in, 300, 31);
    check_gradients("capsule", g, 0.8, 32);
    check_mass_numeric("capsule", g);
    floe_geometry_destroy(g);

    rh_t co = {0.5, 1.2};
    g = floe_cone_create(0.5, 1.2);
    CHECK(g && strcmp(g->klass->name, "cone") == 0, "cone create");
    check_curved("cone", g, cone_patch, &co, 2, 0.9, cone_in, 300, 41);
    check_gradients("cone", g, 0.9, 42);
    check_mass_numeric("cone", g);
    floe_geometry_destroy(g);
}

static void test_rounded(void) {
    printf("rounded box\n");
    double r = 0.05;
    floe_geometry *box = floe_box_create(0.4, 0.6, 0.8), *g = floe_rounded_create(floe_box_create(0.4, 0.6, 0.8), r);
    CHECK(g && strcmp(g->klass->name, "rounded") == 0, "rounded create");
    unsigned s = 55;
    double worst = 0, worst_proj = 0, worst_sup = 0;
    for (int k = 0; k < 2000; k++) {
        double X[3] = {(rnd(&s) - 0.5), (rnd(&s) - 0.5) * 1.2, (rnd(&s) - 0.5) * 1.4}, P[3];
        worst = fmax(worst, fabs(floe_geometry_sdf(g, X) - (floe_geometry_sdf(box, X) - r)));
        floe_geometry_project(g, X, P);
        worst_proj = fmax(worst_proj, fabs(floe_geometry_sdf(g, P)));
    }
    for (int k = 0; k < 100; k++) {
        double d[3], o[3], b[3];
        rnd_unit(&s, d);
        g->klass->support(g, d, o);
        box->klass->support(box, d, b);
        worst_sup = fmax(worst_sup, fabs(floe_v3_dot(o, d) - floe_v3_dot(b, d) - r));
    }
    report("rounded: |sdf - (box sdf - r)|", worst, 0);
    report("rounded: max |sdf(project(X))|", worst_proj, 1e-15);
    report("rounded: support . d - (box support . d + r)", worst_sup, 1e-15);
    CHECK_NEAR(floe_geometry_bounding_radius(g), floe_geometry_bounding_radius(box) + r, 1e-15, "rounded bounding radius");
    check_gradients("rounded box", g, 0.5, 56);
    /* mass by quadrature; exact: box + faces*r + quarter-cylinders on edges + sphere */
    floe_mass_properties m;
    CHECK(floe_geometry_mass_properties(g, 3, 1.0, &m) == FLOE_OK, "rounded mass");
    double a = 0.4, b = 0.6, c = 0.8;
    double V = a * b * c + 2 * r * (a * b + b * c + a * c) + M_PI * r * r * (a + b + c) + 4.0 / 3 * M_PI * r * r * r;
    printf("  rounded box volume %.8g vs exact %.8g, stated quadrature error %.1e\n", m.volume, V, m.quadrature_error);
    report("rounded: volume rel. error (tol 2x the stated estimate)", fabs(m.volume - V) / V, 2 * m.quadrature_error);
    floe_geometry_destroy(g);
    floe_geometry_destroy(box);
}

static void test_compound(void) {
    printf("compound: an L of two boxes\n");
    char err[256] = "";
    floe_geometry *pc[2] = {floe_box_create(3, 1, 1), floe_box_create(1, 2, 1)};
    double x[6] = {1.5, 0.5, 0.5, 0.5, 2.0, 0.5}, q[8] = {1, 0, 0, 0, 1, 0, 0, 0};
    floe_geometry *g = floe_compound_create(pc, x, q, 2, 3, err, sizeof err);
    CHECK(g != NULL, "compound refused: %s", err);
    if (!g) return;
    const floe_compound *c = (const floe_compound *)g;
    CHECK(g->klass->kind == FLOE_GEOM_COMPOUND && strcmp(g->klass->name, "compound") == 0, "compound kind/name");
    floe_mass_properties m;
    CHECK(floe_geometry_mass_properties(g, 3, 2.0, &m) == FLOE_OK, "compound mass");
    CHECK_NEAR(m.volume, 5, 1e-14, "L volume");
    CHECK_NEAR(m.mass, 10, 1e-14, "L mass (density 2)");
    CHECK_NEAR(c->frame_x[0], 1.1, 1e-14, "L centroid x");
    CHECK_NEAR(c->frame_x[1], 1.1, 1e-14, "L centroid y");
    CHECK_NEAR(c->frame_x[2], 0.5, 1e-14, "L centroid z");
    report("L: |centroid in the body frame|", floe_v3_norm(m.centroid), 1e-14);
    /* hand-computed tensor about the centroid: Ixx = Iyy = 121/30, Izz = 217/30, Ixy = 1.8 */
    double I[3] = {2 * (121.0 / 30 - 1.8), 2 * (121.0 / 30 + 1.8), 2 * 217.0 / 30};
    CHECK_NEAR(m.inertia[0], I[0], 1e-13, "L principal moment 0");
    CHECK_NEAR(m.inertia[1], I[1], 1e-13, "L principal moment 1");
    CHECK_NEAR(m.inertia[2], I[2], 1e-13, "L principal moment 2");
    report("L: off_axis", m.off_axis, 1e-13);
    double ex[3] = {1, 0, 0}, bx[3];
    floe_q_rotate(bx, c->frame_q, ex);
    report("L: body x along (1,-1,0)/sqrt2", 1 - fabs(bx[0] - bx[1]) / sqrt(2.0), 1e-13);
    /* sdf = min of the two box SDFs in the input coordinates */
    floe_geometry *b1 = floe_box_create(3, 1, 1), *b2 = floe_box_create(1, 2, 1);
    unsigned s = 8;
    double worst = 0, worst_proj = 0;
    for (int k = 0; k < 2000; k++) {
        double X[3] = {-1 + 5 * rnd(&s), -1 + 5 * rnd(&s), -1 + 3 * rnd(&s)}, B[3], y1[3], y2[3], P[3];
        input_to_body(c->frame_x, c->frame_q, X, B);
        floe_v3_sub(y1, X, x); floe_v3_sub(y2, X, x + 3);
        double bf = fmin(floe_geometry_sdf(b1, y1), floe_geometry_sdf(b2, y2));
        worst = fmax(worst, fabs(floe_geometry_sdf(g, B) - bf));
        floe_geometry_project(g, B, P);
        if (floe_geometry_sdf(g, B) > 0) worst_proj = fmax(worst_proj, fabs(floe_geometry_sdf(g, P)));
    }
    report("L: |sdf - min of box SDFs|", worst, 1e-14);
    report("L: max |sdf(project(X))| (outside points)", worst_proj, 1e-14);
    floe_mass_properties nm;
    floe_geometry_mass_numeric(g, 3, 2.0, 128, &nm);
    double e = fabs(nm.volume - m.volume) / m.volume;
    for (int k = 0; k < 3; k++) e = fmax(e, fabs(nm.inertia[k] - m.inertia[k]) / m.inertia[k]);
    report("L: mass vs quadrature (tol 2x its estimate)", e, 2 * nm.quadrature_error);
    double d[3] = {1, 0, 0}, o[3];
    g->klass->support(g, d, o);
    CHECK(floe_v3_dot(o, d) > 0, "compound support");
    check_gradients("L compound", g, 2.0, 9);
    floe_geometry_destroy(b1); floe_geometry_destroy(b2);
    floe_geometry_destroy(g);
    /* the same L in 2D: area 5, centroid (1.1, 1.1, 0) */
    floe_geometry *p2[2] = {floe_box_create(3, 1, 1), floe_box_create(1, 2, 1)};
    double x2[6] = {1.5, 0.5, 0, 0.5, 2.0, 0};
    g = floe_compound_create(p2, x2, NULL, 2, 2, err, sizeof err);
    CHECK(g != NULL, "2D compound refused: %s", err);
    if (g) {
        c = (const floe_compound *)g;
        floe_geometry_mass_properties(g, 2, 1.0, &m);
        CHECK_NEAR(m.volume, 5, 1e-14, "2D L area");
        CHECK(fabs(c->frame_x[0] - 1.1) < 1e-14 && fabs(c->frame_x[1] - 1.1) < 1e-14 && c->frame_x[2] == 0, "2D L centroid");
        CHECK(fabs(c->frame_q[1]) < 1e-15 && fabs(c->frame_q[2]) < 1e-15, "2D L turned about z only");
        CHECK_NEAR(m.inertia[2], 2 * 217.0 / 30 / 2, 1e-13, "2D L polar moment");
        report("2D L: off_axis", m.off_axis, 1e-13);
        floe_geometry_destroy(g);
    }
}

static void test_degenerate(void) {
    printf("degenerate input\n");
    char err[256];
#define REFUSED(expr, what, word)                                                   \
    do {                                                                            \
        err[0] = 0;                                                                 \
        floe_geometry *g_ = (expr);                                                 \
        CHECK(g_ == NULL && strstr(err, word), "%s: expected NULL and a message with '%s' (got '%s')", what, word, err); \
        printf("  %-34s -> %s\n", what, err);                                       \
        if (g_) floe_geometry_destroy(g_);                                          \
    } while (0)
    double flat[24] = {0, 0, 1, 0, 0, 0, -1, 0, 1, 0, 0, 1, -1, 0, 0, 1, 0, 1, 0, 1, 0, -1, 0, 1};
    REFUSED(floe_polyhedron_from_planes(flat, 6, err, sizeof err), "coplanar planes (zero volume)", "zero volume");
    double slab[24] = {1, 0, 0, 1, -1, 0, 0, 1, 0, 1, 0, 1, 0, -1, 0, 1, 0, 0, 1, 1, 1, 1, 0, 5};
    REFUSED(floe_polyhedron_from_planes(slab, 6, err, sizeof err), "unbounded (open below)", "unbounded");
    double prism[16] = {1, 0, 0, 1, -1, 0, 0, 1, 0, 1, 0, 1, 0, -1, 0, 1};
    REFUSED(floe_polyhedron_from_planes(prism, 4, err, sizeof err), "unbounded (normals in a plane)", "unbounded");
    double empty[24] = {1, 0, 0, -1, -1, 0, 0, -1, 0, 1, 0, 1, 0, -1, 0, 1, 0, 0, 1, 1, 0, 0, -1, 1};
    REFUSED(floe_polyhedron_from_planes(empty, 6, err, sizeof err), "empty (x <= -1 and x >= 1)", "empty");
    double two[4] = {0, 0, 1, 1};
    REFUSED(floe_polygon_create(two, 2, err, sizeof err), "polygon with 2 points", "at least 3");
    double col[8] = {0, 0, 1, 1, 2, 2, 3, 3};
    REFUSED(floe_polygon_create(col, 4, err, sizeof err), "collinear polygon points", "collinear");
    REFUSED(floe_prism_create(col, 4, 1.0, err, sizeof err), "collinear prism points", "collinear");
    double sq[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    REFUSED(floe_prism_create(sq, 4, -1.0, err, sizeof err), "prism with negative height", "height");
    double ov[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    int ot[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    REFUSED(floe_polyhedron_from_mesh(ov, 6, ot, 7, err, sizeof err), "open mesh (a triangle missing)", "not closed");
    double dent[18];
    memcpy(dent, ov, sizeof dent);
    dent[14] = -0.2; /* top apex pushed below the equator */
    REFUSED(floe_polyhedron_from_mesh(dent, 6, ot, 8, err, sizeof err), "non-convex mesh (dented)", "not convex");
    double flatm[18];
    memcpy(flatm, ov, sizeof flatm);
    flatm[14] = 0; flatm[17] = 0;
    REFUSED(floe_polyhedron_from_mesh(flatm, 6, ot, 8, err, sizeof err), "flat mesh", "zero volume");
    CHECK(floe_ellipsoid_create(1, -1, 1) == NULL && floe_ellipsoid_create(1, 1, NAN) == NULL, "ellipsoid: negative/NaN axis refused");
    CHECK(floe_cylinder_create(-0.1, 1) == NULL && floe_cylinder_create(1, 0) == NULL, "cylinder: non-positive size refused");
    CHECK(floe_capsule_create(-0.1, 1) == NULL && floe_capsule_create(0.1, -1) == NULL, "capsule: negative size refused");
    CHECK(floe_cone_create(0.5, -1) == NULL && floe_cone_create(INFINITY, 1) == NULL, "cone: negative/infinite size refused");
    CHECK(floe_rounded_create(floe_box_create(1, 1, 1), -0.1) == NULL, "rounded: negative radius refused (inner freed)");
    floe_geometry *pcs[2] = {floe_box_create(1, 1, 1), floe_plane_create()};
    REFUSED(floe_compound_create(pcs, NULL, NULL, 2, 3, err, sizeof err), "compound with a half-space piece", "unbounded");
    /* cylinder/capsule/cone in a 2D world: no mass section */
    floe_geometry *cy = floe_cylinder_create(1, 1);
    floe_mass_properties m;
    CHECK(floe_geometry_mass_properties(cy, 2, 1, &m) == FLOE_ENOTSUP, "cylinder in 2D: ENOTSUP");
    floe_geometry_destroy(cy);
}

static void test_linalg(void) {
    printf("linear algebra\n");
    unsigned s = 99;
    double worst = 0, worst_q = 0;
    for (int t = 0; t < 200; t++) {
        double q[4], R[3][3], l0[3] = {rndn(&s), rndn(&s), rndn(&s)}, A[3][3] = {{0}};
        rnd_quat(&s, q);
        for (int k = 0; k < 3; k++) {
            double e[3] = {k == 0, k == 1, k == 2}, c[3];
            floe_q_rotate(c, q, e);
            for (int j = 0; j < 3; j++) R[j][k] = c[j];
        }
        if (t % 4 == 0) l0[1] = l0[0]; /* repeated eigenvalue */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++) A[i][j] += R[i][k] * l0[k] * R[j][k];
        double l[3], V[3][3], q2[4];
        floe_sym3_eigen(A, l, V);
        double det = V[0][0] * (V[1][1] * V[2][2] - V[1][2] * V[2][1]) - V[0][1] * (V[1][0] * V[2][2] - V[1][2] * V[2][0]) +
                     V[0][2] * (V[1][0] * V[2][1] - V[1][1] * V[2][0]);
        CHECK(l[0] <= l[1] && l[1] <= l[2] && fabs(det - 1) < 1e-12, "eigen: ascending, right-handed");
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double r = 0;
                for (int k = 0; k < 3; k++) r += V[i][k] * l[k] * V[j][k];
                worst = fmax(worst, fabs(r - A[i][j]));
            }
        floe_q_from_matrix(q2, R);
        worst_q = fmax(worst_q, fmin(fabs(q2[0] - q[0]) + fabs(q2[1] - q[1]) + fabs(q2[2] - q[2]) + fabs(q2[3] - q[3]),
                                     fabs(q2[0] + q[0]) + fabs(q2[1] + q[1]) + fabs(q2[2] + q[2]) + fabs(q2[3] + q[3])));
    }
    report("sym3_eigen: max |V diag(l) V^T - A|", worst, 1e-13);
    report("q_from_matrix: max |q - q0| (up to sign)", worst_q, 1e-14);
}

int main(void) {
    test_linalg();
    test_random_polyhedron();
    test_polyhedron_mass();
    test_principal_frame();
    test_polygons();
    test_curved();
    test_rounded();
    test_compound();
    test_degenerate();
    return check_summary("test_shapes");
}
