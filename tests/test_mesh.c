/* test_mesh.c - mesh import (assimp), convex hull and convex decomposition (CGAL):
 * meshes are written procedurally (ASCII STL, OBJ, PLY) into a temporary directory; good
 * meshes load with the right counts and volumes, the polyhedron SDF equals CGAL's exact
 * point-mesh distance, an L-shape decomposes into convex pieces of the same total volume,
 * and every bad file gives an error naming the file and the defect. Built without CGAL or
 * assimp, the functions must answer FLOE_ENOTSUP naming the CMake option. */
#include "check.h"
#include "floe_mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[64];

/* ---- small meshes ---- */

typedef struct tmesh { int nv, nt; double v[3 * 64]; int t[3 * 128]; } tmesh;

static int addv(tmesh *m, double x, double y, double z) {
    m->v[3 * m->nv] = x, m->v[3 * m->nv + 1] = y, m->v[3 * m->nv + 2] = z;
    return m->nv++;
}
static void addt(tmesh *m, int a, int b, int c) {
    m->t[3 * m->nt] = a, m->t[3 * m->nt + 1] = b, m->t[3 * m->nt + 2] = c;
    m->nt++;
}

/* closed prism: a polygon (counter-clockwise, star-shaped from vertex `fan`) from z0 to z1 */
static void extrude(tmesh *m, const double *xy, int n, int fan, double z0, double z1) {
    int b = m->nv;
    for (int i = 0; i < n; i++) addv(m, xy[2 * i], xy[2 * i + 1], z0);
    for (int i = 0; i < n; i++) addv(m, xy[2 * i], xy[2 * i + 1], z1);
    for (int k = 1; k + 1 < n; k++) {
        int i = (fan + k) % n, j = (fan + k + 1) % n;
        addt(m, b + n + fan, b + n + i, b + n + j); /* top, outward +z */
        addt(m, b + fan, b + j, b + i);             /* bottom, outward -z */
    }
    for (int i = 0; i < n; i++) {
        int j = (i + 1) % n;
        addt(m, b + i, b + j, b + n + j);
        addt(m, b + i, b + n + j, b + n + i);
    }
}

static void cube(tmesh *m, double c0, double c1, double c2, double side) {
    double h = side / 2;
    const double sq[8] = {c0 - h, c1 - h, c0 + h, c1 - h, c0 + h, c1 + h, c0 - h, c1 + h};
    extrude(m, sq, 4, 0, c2 - h, c2 + h);
}

static const double L_xy[12] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2}; /* area 3; reflex vertex 3 */
static int inside_L(const double X[3]) {
    if (X[2] <= 0 || X[2] >= 1 || X[0] <= 0 || X[1] <= 0) return 0;
    return (X[0] < 2 && X[1] < 1) || (X[0] < 1 && X[1] < 2);
}

static void tetra(tmesh *m, const double p[12]) {
    int b = m->nv;
    for (int i = 0; i < 4; i++) addv(m, p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    /* oriented outward for a positively oriented (p1-p0, p2-p0, p3-p0) */
    addt(m, b + 0, b + 2, b + 1);
    addt(m, b + 0, b + 1, b + 3);
    addt(m, b + 1, b + 2, b + 3);
    addt(m, b + 0, b + 3, b + 2);
}

static void icosahedron(tmesh *m) {
    const double f = (1 + sqrt(5.0)) / 2;
    const double v[36] = {-1, f, 0, 1, f, 0, -1, -f, 0, 1, -f, 0, 0, -1, f, 0, 1, f,
                          0, -1, -f, 0, 1, -f, f, 0, -1, f, 0, 1, -f, 0, -1, -f, 0, 1};
    const int t[60] = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                       3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int i = 0; i < 12; i++) addv(m, v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    for (int i = 0; i < 20; i++) addt(m, t[3 * i], t[3 * i + 1], t[3 * i + 2]);
}

static double volume(const double *v, const int *t, int nt) {
    double s = 0;
    for (int i = 0; i < nt; i++) {
        const double *a = v + 3 * t[3 * i], *b = v + 3 * t[3 * i + 1], *c = v + 3 * t[3 * i + 2];
        s += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
    return s / 6;
}

/* ---- writers ---- */

static const char *path_of(const char *name) {
    static char buf[8][160];
    static int k = 0;
    k = (k + 1) % 8;
    snprintf(buf[k], sizeof buf[k], "%s/%s", dir, name);
    return buf[k];
}

static const char *write_stl(const char *name, const tmesh *m) {
    const char *p = path_of(name);
    FILE *f = fopen(p, "w");
    fprintf(f, "solid test\n");
    for (int i = 0; i < m->nt; i++) {
        fprintf(f, " facet normal 0 0 0\n  outer loop\n");
        for (int k = 0; k < 3; k++) {
            const double *x = m->v + 3 * m->t[3 * i + k];
            fprintf(f, "   vertex %.17g %.17g %.17g\n", x[0], x[1], x[2]);
        }
        fprintf(f, "  endloop\n endfacet\n");
    }
    fprintf(f, "endsolid test\n");
    fclose(f);
    return p;
}

static const char *write_obj(const char *name, const tmesh *m) {
    const char *p = path_of(name);
    FILE *f = fopen(p, "w");
    fprintf(f, "# floe test mesh\n");
    for (int i = 0; i < m->nv; i++) fprintf(f, "v %.17g %.17g %.17g\n", m->v[3 * i], m->v[3 * i + 1], m->v[3 * i + 2]);
    for (int i = 0; i < m->nt; i++) fprintf(f, "f %d %d %d\n", m->t[3 * i] + 1, m->t[3 * i + 1] + 1, m->t[3 * i + 2] + 1);
    fclose(f);
    return p;
}

static const char *write_ply(const char *name, const tmesh *m) {
    const char *p = path_of(name);
    FILE *f = fopen(p, "w");
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
               "element face %d\nproperty list uchar int vertex_indices\nend_header\n",
            m->nv, m->nt);
    for (int i = 0; i < m->nv; i++) fprintf(f, "%.9g %.9g %.9g\n", m->v[3 * i], m->v[3 * i + 1], m->v[3 * i + 2]);
    for (int i = 0; i < m->nt; i++) fprintf(f, "3 %d %d %d\n", m->t[3 * i], m->t[3 * i + 1], m->t[3 * i + 2]);
    fclose(f);
    return p;
}

static const char *write_raw(const char *name, const void *data, size_t n) {
    const char *p = path_of(name);
    FILE *f = fopen(p, "wb");
    if (n) fwrite(data, 1, n, f);
    fclose(f);
    return p;
}

/* ---- helpers ---- */

/* X_body = R(q)^T (X - x): input coordinates to a shape's body frame */
static void to_body(const double x[3], const double q[4], const double X[3], double B[3]) {
    double w = q[0], a = q[1], b = q[2], c = q[3];
    double R[3][3] = {{1 - 2 * (b * b + c * c), 2 * (a * b - w * c), 2 * (a * c + w * b)},
                      {2 * (a * b + w * c), 1 - 2 * (a * a + c * c), 2 * (b * c - w * a)},
                      {2 * (a * c - w * b), 2 * (b * c + w * a), 1 - 2 * (a * a + b * b)}};
    double d[3] = {X[0] - x[0], X[1] - x[1], X[2] - x[2]};
    for (int i = 0; i < 3; i++) B[i] = R[0][i] * d[0] + R[1][i] * d[1] + R[2][i] * d[2];
}

static double poly_sdf(const floe_geometry *g, const double X[3]) {
    const floe_polytope *p = (const floe_polytope *)g;
    double B[3];
    to_body(p->frame_x, p->frame_q, X, B);
    return floe_geometry_sdf(g, B);
}

static double urand(void) { return rand() / (RAND_MAX + 1.0); }

static int has(const char *err, const char *word) { return strstr(err, word) != NULL; }

static double geom_volume(const floe_geometry *g) {
    floe_mass_properties mp;
    if (floe_geometry_mass_properties(g, 3, 1.0, &mp) != FLOE_OK) return NAN;
    return mp.volume;
}

/* ---- tests ---- */

static void test_without(int feat) {
    char err[512] = "";
    floe_mesh m;
    if (!(feat & FLOE_MESH_HAVE_ASSIMP)) {
        int rc = floe_mesh_load("whatever.stl", 1.0, &m, err, sizeof err);
        CHECK(rc == FLOE_ENOTSUP && has(err, "FLOE_WITH_ASSIMP"), "load without assimp: rc %d, '%s'", rc, err);
        printf("  without assimp: %s\n", err);
    }
    if (!(feat & FLOE_MESH_HAVE_CGAL)) {
        const double p[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
        int rc = floe_mesh_hull(p, 4, &m, err, sizeof err);
        CHECK(rc == FLOE_ENOTSUP && has(err, "FLOE_WITH_CGAL"), "hull without CGAL: rc %d, '%s'", rc, err);
        printf("  without CGAL: %s\n", err);
        floe_geometry *g = floe_polyhedron_from_points(p, 4, err, sizeof err);
        CHECK(!g && has(err, "FLOE_WITH_CGAL"), "polyhedron from points without CGAL: '%s'", err);
        g = floe_mesh_shape("x.stl", "hull", 1.0, err, sizeof err);
        CHECK(!g && has(err, "FLOE_WITH_CGAL"), "mesh shape without CGAL: '%s'", err);
        floe_mesh *pc;
        int np;
        tmesh t = {0};
        cube(&t, 0, 0, 0, 1);
        floe_mesh fm = {t.nv, t.nt, t.v, t.t};
        rc = floe_mesh_decompose(&fm, "cube", &pc, &np, err, sizeof err);
        CHECK(rc == FLOE_ENOTSUP && has(err, "FLOE_WITH_CGAL"), "decompose without CGAL: '%s'", err);
        double d = 0, X[3] = {2, 0, 0};
        rc = floe_mesh_distances(&fm, X, 1, &d);
        CHECK(rc == FLOE_ENOTSUP && isnan(d), "distances without CGAL: rc %d, %g", rc, d);
        /* the C checks still work */
        rc = floe_mesh_validate(&fm, "cube", err, sizeof err);
        CHECK(rc == FLOE_OK, "validate cube without CGAL: '%s'", err);
    }
}

static void test_load_cube(int feat) {
    tmesh t = {0};
    cube(&t, 1, 2, 3, 2);
    const char *files[3] = {write_stl("cube.stl", &t), write_obj("cube.obj", &t), write_ply("cube.ply", &t)};
    for (int f = 0; f < 3; f++) {
        char err[512] = "", what[96];
        floe_mesh m;
        int rc = floe_mesh_load(files[f], 0.5, &m, err, sizeof err);
        CHECK(rc == FLOE_OK, "load %s: %s", files[f], err);
        if (rc != FLOE_OK) continue;
        CHECK(m.nv == 8 && m.nt == 12, "%s: %d vertices %d triangles, expected 8 and 12", files[f], m.nv, m.nt);
        rc = floe_mesh_validate(&m, files[f], err, sizeof err);
        CHECK(rc == FLOE_OK, "validate %s: %s", files[f], err);
        floe_geometry *g = floe_polyhedron_from_mesh(m.v, m.nv, m.tri, m.nt, err, sizeof err);
        CHECK(g != NULL, "polyhedron from %s: %s", files[f], err);
        if (g) {
            snprintf(what, sizeof what, "cube volume from %s", strrchr(files[f], '.'));
            CHECK_NEAR(geom_volume(g), 1.0, 1e-12, what);
            const floe_polytope *p = (const floe_polytope *)g;
            double e = fabs(p->frame_x[0] - 0.5) + fabs(p->frame_x[1] - 1) + fabs(p->frame_x[2] - 1.5);
            CHECK(e < 1e-12, "cube centroid (%g %g %g), expected (0.5 1 1.5)", p->frame_x[0], p->frame_x[1],
                  p->frame_x[2]);
            floe_geometry_destroy(g);
        }
        floe_mesh_free(&m);
    }
    if (!(feat & FLOE_MESH_HAVE_CGAL)) return;
    /* an icosahedron (OBJ): 12 vertices, 20 triangles; the hull shape has the mesh's volume */
    tmesh ic = {0};
    icosahedron(&ic);
    const char *p = write_obj("icosahedron.obj", &ic);
    char err[512] = "";
    floe_mesh m;
    int rc = floe_mesh_load(p, 1.0, &m, err, sizeof err);
    CHECK(rc == FLOE_OK && m.nv == 12 && m.nt == 20, "icosahedron: rc %d, %d vertices %d triangles: %s", rc, m.nv, m.nt,
          err);
    if (rc != FLOE_OK) return;
    CHECK(floe_mesh_validate(&m, p, err, sizeof err) == FLOE_OK, "validate icosahedron: %s", err);
    floe_geometry *g = floe_mesh_shape(p, "hull", 1.0, err, sizeof err);
    CHECK(g != NULL, "icosahedron hull shape: %s", err);
    if (g) CHECK_NEAR(geom_volume(g), volume(m.v, m.tri, m.nt), 1e-12, "icosahedron hull volume vs mesh volume");
    floe_geometry_destroy(g);
    g = floe_mesh_shape(p, "decompose", 1.0, err, sizeof err);
    CHECK(g && g->klass->kind == FLOE_GEOM_COMPOUND && ((floe_compound *)g)->n == 1,
          "convex icosahedron decomposes into one piece: %s", g ? "" : err);
    if (g) CHECK_NEAR(geom_volume(g), volume(m.v, m.tri, m.nt), 1e-12, "icosahedron compound volume");
    floe_geometry_destroy(g);
    floe_mesh_free(&m);
}

static void test_hull_and_sdf(void) {
    enum { N = 300, NQ = 2000 };
    static double pts[3 * N];
    srand(12345);
    for (int i = 0; i < N; i++) { /* points in a squashed ball */
        double x, y, z;
        do {
            x = 2 * urand() - 1, y = 2 * urand() - 1, z = 2 * urand() - 1;
        } while (x * x + y * y + z * z > 1);
        pts[3 * i] = 1.5 * x + 0.3, pts[3 * i + 1] = y - 0.2, pts[3 * i + 2] = 0.6 * z + 1;
    }
    char err[512] = "";
    floe_mesh h;
    int rc = floe_mesh_hull(pts, N, &h, err, sizeof err);
    CHECK(rc == FLOE_OK, "hull of %d random points: %s", N, err);
    if (rc != FLOE_OK) return;
    int notinput = 0;
    for (int i = 0; i < h.nv; i++) {
        int found = 0;
        for (int j = 0; j < N && !found; j++) found = memcmp(h.v + 3 * i, pts + 3 * j, 3 * sizeof(double)) == 0;
        notinput += !found;
    }
    CHECK(notinput == 0, "%d hull vertices are not input points", notinput);
    printf("  hull of %d points: %d vertices, %d triangles\n", N, h.nv, h.nt);
    floe_geometry *g = floe_polyhedron_from_points(pts, N, err, sizeof err);
    CHECK(g != NULL, "polyhedron from points: %s", err);
    if (!g) {
        floe_mesh_free(&h);
        return;
    }
    CHECK_NEAR(geom_volume(g), volume(h.v, h.tri, h.nt), 1e-12, "hull polyhedron volume vs hull mesh volume");
    double worst = -INFINITY;
    for (int i = 0; i < N; i++) worst = fmax(worst, poly_sdf(g, pts + 3 * i));
    CHECK(worst <= 1e-9, "an input point lies outside the hull: sdf %g", worst);
    printf("  largest SDF of an input point: %.3g (tol 1e-9)\n", worst);

    /* polyhedron SDF vs CGAL's exact point-mesh distance */
    static double q[3 * NQ], d[NQ];
    for (int i = 0; i < NQ; i++) {
        q[3 * i] = 0.3 + 2.2 * (2 * urand() - 1);
        q[3 * i + 1] = -0.2 + 1.6 * (2 * urand() - 1);
        q[3 * i + 2] = 1 + 1.0 * (2 * urand() - 1);
    }
    rc = floe_mesh_distances(&h, q, NQ, d);
    CHECK(rc == FLOE_OK, "floe_mesh_distances rc %d", rc);
    int nin = 0, nout = 0;
    double ein = 0, eout = 0;
    for (int i = 0; i < NQ; i++) {
        double s = poly_sdf(g, q + 3 * i);
        /* relative error, against the distance (floored at 1e-3 of the size for points
         * almost on the surface, where only the absolute rounding error is meaningful) */
        double e = fabs(fabs(s) - d[i]) / fmax(d[i], 1e-3);
        if (s > 0) nout++, eout = fmax(eout, e);
        else nin++, ein = fmax(ein, e);
    }
    CHECK(nin > 100 && nout > 100, "%d points inside, %d outside", nin, nout);
    CHECK(eout <= 1e-9, "SDF outside vs CGAL distance: rel err %g", eout);
    CHECK(ein <= 1e-9, "SDF inside vs -(CGAL distance): rel err %g", ein);
    printf("  SDF vs CGAL point-mesh distance: %d outside max rel err %.2e, %d inside max rel err %.2e (tol 1e-9)\n",
           nout, eout, nin, ein);
    floe_geometry_destroy(g);
    floe_mesh_free(&h);

    /* hull errors */
    const double flat[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0.5, 0.2, 0};
    rc = floe_mesh_hull(flat, 5, &h, err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "coplanar") && has(err, "zero volume"), "coplanar hull: rc %d '%s'", rc, err);
    printf("  coplanar points: %s\n", err);
    rc = floe_mesh_hull(flat, 3, &h, err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "at least 4"), "3-point hull: rc %d '%s'", rc, err);
}

static void test_decompose_L(void) {
    tmesh t = {0};
    extrude(&t, L_xy, 6, 3, 0, 1);
    const char *p = write_obj("L.obj", &t);
    char err[512] = "";
    floe_mesh m;
    int rc = floe_mesh_load(p, 1.0, &m, err, sizeof err);
    CHECK(rc == FLOE_OK && m.nv == 12 && m.nt == 20, "L: rc %d, %d vertices %d triangles: %s", rc, m.nv, m.nt, err);
    if (rc != FLOE_OK) return;
    rc = floe_mesh_validate(&m, p, err, sizeof err);
    CHECK(rc == FLOE_OK, "validate L: %s", err);
    floe_mesh *pc = NULL;
    int np = 0;
    rc = floe_mesh_decompose(&m, p, &pc, &np, err, sizeof err);
    CHECK(rc == FLOE_OK && np >= 2, "decompose L: rc %d, %d pieces: %s", rc, np, err);
    double vsum = 0;
    for (int i = 0; i < np; i++) {
        vsum += volume(pc[i].v, pc[i].tri, pc[i].nt);
        floe_mesh_free(&pc[i]);
    }
    free(pc);
    printf("  L-shape: %d convex pieces\n", np);
    CHECK_NEAR(vsum, 3.0, 1e-9, "sum of the L's piece volumes");
    floe_mesh_free(&m);

    floe_geometry *g = floe_mesh_shape(p, "decompose", 1.0, err, sizeof err);
    CHECK(g && g->klass->kind == FLOE_GEOM_COMPOUND, "L compound: %s", g ? "" : err);
    if (!g) return;
    const floe_compound *c = (const floe_compound *)g;
    CHECK(c->n >= 2, "L compound has %d pieces", c->n);
    CHECK_NEAR(geom_volume(g), 3.0, 1e-9, "L compound volume");
    int wrong = 0, nin = 0, n = 0;
    for (int i = 0; i < 24; i++)
        for (int j = 0; j < 24; j++)
            for (int k = 0; k < 8; k++) {
                double X[3] = {-0.2 + 2.4 * (i + 0.5) / 24, -0.2 + 2.4 * (j + 0.5) / 24, -0.2 + 1.4 * (k + 0.5) / 8}, B[3];
                to_body(c->frame_x, c->frame_q, X, B);
                double s = floe_geometry_sdf(g, B);
                int in = inside_L(X);
                nin += in, n++;
                if ((in && !(s < 0)) || (!in && !(s > 0))) wrong++;
            }
    CHECK(wrong == 0, "L compound SDF has the wrong sign at %d of %d sample points", wrong, n);
    printf("  L compound SDF sign right at %d of %d points (%d inside)\n", n - wrong, n, nin);
    floe_geometry_destroy(g);
    /* hull mode: the convex hull of the L (area 3.5) */
    g = floe_mesh_shape(p, "hull", 1.0, err, sizeof err);
    CHECK(g != NULL, "L hull: %s", err);
    if (g) CHECK_NEAR(geom_volume(g), 3.5, 1e-12, "L hull volume");
    floe_geometry_destroy(g);
}

/* a bad file: floe_mesh_shape fails, naming the file and one of the defect words */
static void expect_bad(const char *file, const char *mode, const char *w1, const char *w2) {
    char err[512] = "";
    floe_geometry *g = floe_mesh_shape(file, mode, 1.0, err, sizeof err);
    const char *base = strrchr(file, '/') ? strrchr(file, '/') + 1 : file;
    CHECK(!g && has(err, base) && (has(err, w1) || (w2 && has(err, w2))), "%s (%s): expected an error with '%s': '%s'",
          base, mode, w1, err);
    printf("  %-10s %s\n", mode, err);
    floe_geometry_destroy(g);
}

static void test_bad(void) {
    tmesh t = {0};
    cube(&t, 0, 0, 0, 1);
    t.nt -= 2; /* the last side face gone */
    const char *open = write_stl("open_cube.stl", &t);
    expect_bad(open, "decompose", "open", "not closed");
    expect_bad(open, "hull", "open", "not closed"); /* hull mode refuses open meshes too (docs/scene-format.md) */

    tmesh x = {0};
    const double t1[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double t2[12] = {0.2, 0.2, 0.2, 1.2, 0.2, 0.2, 0.2, 1.2, 0.2, 0.2, 0.2, 1.2};
    tetra(&x, t1);
    tetra(&x, t2);
    const char *si = write_obj("self_intersecting.obj", &x);
    expect_bad(si, "decompose", "self-intersect", NULL);

    tmesh flat = {0}; /* a closed "pillow" of zero thickness: two squares back to back */
    int a = addv(&flat, 0, 0, 0), b = addv(&flat, 1, 0, 0), c = addv(&flat, 1, 1, 0), d = addv(&flat, 0, 1, 0);
    addt(&flat, a, b, c), addt(&flat, a, c, d), addt(&flat, b, a, d), addt(&flat, b, d, c);
    const char *fl = write_obj("flat.obj", &flat);
    expect_bad(fl, "decompose", "zero volume", "degenerate");
    expect_bad(fl, "hull", "zero volume", "coplanar");

    tmesh z = {0}; /* zero-area triangles only (collinear vertices) */
    int p0 = addv(&z, 0, 0, 0), p1 = addv(&z, 1, 0, 0), p2 = addv(&z, 2, 0, 0), p3 = addv(&z, 3, 0, 0);
    addt(&z, p0, p1, p2), addt(&z, p1, p2, p3), addt(&z, p0, p2, p3);
    const char *zf = write_obj("zero_area.obj", &z);
    expect_bad(zf, "decompose", "degenerate", "zero area");
    expect_bad(zf, "hull", "zero volume", "zero area");

    const char *empty = write_raw("empty.stl", "", 0);
    expect_bad(empty, "hull", "empty", "no triangles");
    const char *novert = write_raw("points_only.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", 24);
    expect_bad(novert, "hull", "no triangles", "cannot read");
    expect_bad(path_of("does_not_exist.stl"), "hull", "cannot read", NULL);
    unsigned char junk[300];
    for (int i = 0; i < 300; i++) junk[i] = (unsigned char)(i * 37 + 11);
    const char *gb = write_raw("garbage.stl", junk, sizeof junk);
    expect_bad(gb, "hull", "cannot read", "no triangles");
    const char *gx = write_raw("garbage.xyzq", junk, sizeof junk);
    expect_bad(gx, "hull", "cannot read", NULL);

    /* an unknown mode, a bad scale */
    tmesh cb = {0};
    cube(&cb, 0, 0, 0, 1);
    const char *cf = write_obj("cube2.obj", &cb);
    expect_bad(cf, "convex", "unknown mode", NULL);
    char err[512] = "";
    floe_mesh m;
    int rc = floe_mesh_load(cf, 0.0, &m, err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "scale"), "scale 0: rc %d '%s'", rc, err);
    rc = floe_mesh_load(cf, NAN, &m, err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "scale"), "scale NaN: rc %d '%s'", rc, err);

    /* validate directly: inside out, inconsistent orientation, a missing triangle */
    floe_mesh fm = {cb.nv, cb.nt, cb.v, cb.t};
    for (int i = 0; i < cb.nt; i++) { int s = cb.t[3 * i + 1]; cb.t[3 * i + 1] = cb.t[3 * i + 2]; cb.t[3 * i + 2] = s; }
    rc = floe_mesh_validate(&fm, "inverted", err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "inside out") && has(err, "inverted"), "inside-out cube: '%s'", err);
    printf("  validate   %s\n", err);
    /* an inside-out file is the same solid: decompose turns it outward */
    const char *inv = write_obj("inverted.obj", &cb);
    floe_geometry *g = floe_mesh_shape(inv, "decompose", 1.0, err, sizeof err);
    CHECK(g != NULL, "inside-out cube decomposes: %s", err);
    if (g) CHECK_NEAR(geom_volume(g), 1.0, 1e-12, "inside-out cube compound volume");
    floe_geometry_destroy(g);
    { int s = cb.t[1]; cb.t[1] = cb.t[2]; cb.t[2] = s; } /* one triangle back: mixed orientation */
    rc = floe_mesh_validate(&fm, "mixed", err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "oriented"), "mixed orientation: '%s'", err);
    printf("  validate   %s\n", err);
    fm.nt = 0;
    rc = floe_mesh_validate(&fm, "nothing", err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "empty"), "empty mesh: '%s'", err);
}

int main(void) {
    int feat = floe_mesh_features();
    printf("mesh features: assimp %s, CGAL %s\n", feat & FLOE_MESH_HAVE_ASSIMP ? "yes" : "no",
           feat & FLOE_MESH_HAVE_CGAL ? "yes" : "no");
    test_without(feat);
    if (feat & FLOE_MESH_HAVE_CGAL) test_hull_and_sdf();
    if (feat & FLOE_MESH_HAVE_ASSIMP) {
        snprintf(dir, sizeof dir, "/tmp/floe_test_mesh_XXXXXX");
        if (!mkdtemp(dir)) {
            perror("mkdtemp");
            return 1;
        }
        test_load_cube(feat);
        if (feat & FLOE_MESH_HAVE_CGAL) {
            test_decompose_L();
            test_bad();
        }
        char cmd[128];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
        if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
    }
    return check_summary("test_mesh");
}
