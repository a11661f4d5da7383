/* test_geojson.c - floes, coastlines and islands from a GeoJSON file of polygons
 * (`bodies: [{polygons_file: PATH, ...}]`, core/scene/scene_geojson.c), through public headers:
 *  - a FeatureCollection of 3 convex floes (one clockwise, one with its own thickness) and a
 *    non-convex L-shaped coastline with `fixed: true`: 4 bodies, each floe's mass 920 h A
 *    (1e-12) with the feature's thickness over the entry's, its position the centroid
 *    (1e-12), the coast fixed and still, a compound whose area and centroid are the L's
 *    (1e-12);
 *  - the convex decomposition of non-convex rings (a comb, a 300-point random star): the
 *    pieces' areas add up to the ring's (1e-12), which they would not if a piece were not
 *    convex (its hull is taken), if two overlapped or if one were missing;
 *  - a Feature with a MultiPolygon (two bodies, the feature's thickness), a bare Polygon
 *    (a position's third number, an altitude, ignored);
 *  - touching floes (a shared edge, a corner, a square in the L's notch) are accepted;
 *  - every defect refused with the file's name, the feature and a word saying what:
 *    unreadable, invalid JSON (at its line), other GeoJSON types, < 3 distinct points,
 *    non-finite coordinates, a self-intersecting ring, zero area, a hole, two overlapping
 *    polygons (convex and concave), bad properties, a 3D scene;
 *  - the same floes written as `polygon` bodies at their centroids give bit-identical
 *    positions, orientations and masses. */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[64];

static void write_file(const char *name, const char *text) {
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    CHECK(f != NULL, "cannot write %s", path);
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

static const char *scene_head =
    "dimension: 2\n"
    "mass_2d: area\n"
    "time: {duration: 100, dt: 10}\n"
    "gravity: [0, 0]\n"
    "materials: [{name: ice, density: 920, young: 6e6, poisson: 0.3}]\n"
    "laws: [{materials: [ice, ice], model: linear, kn: 1e3, ks: 0}]\n"
    "bodies:\n";

/* load a scene whose bodies section is `bodies` (the scene file sits in dir) */
static int load(const char *bodies, floe_world **w, char *err, size_t errlen) {
    char text[8192], path[128];
    snprintf(text, sizeof text, "%s%s", scene_head, bodies);
    snprintf(path, sizeof path, "%s/s.yaml", dir);
    *w = NULL;
    err[0] = 0;
    return floe_scene_load_ex(path, text, NULL, 0, w, NULL, err, errlen);
}

/* twice the signed area and the centroid of a ring */
static double ring_area(const double *xy, int n, double c[2]) {
    double a = 0, cx = 0, cy = 0;
    for (int i = 0; i < n; i++) {
        const double *p = xy + 2 * i, *q = xy + 2 * ((i + 1) % n);
        double cr = p[0] * q[1] - q[0] * p[1];
        a += cr;
        cx += (p[0] + q[0]) * cr;
        cy += (p[1] + q[1]) * cr;
    }
    if (c) {
        c[0] = cx / (3 * a);
        c[1] = cy / (3 * a);
    }
    return a / 2;
}

/* the three floes and the coast of test 1 (the closing point is not repeated here) */
static const double F0[] = {0, 0, 1000, 0, 400, 800};
static const double F1[] = {1500, 0, 2500, 100, 2400, 900, 1600, 700};
static const double F2[] = {3000, 0, 3200, 900, 3800, 1000, 4100, 400, 3600, -200}; /* clockwise */
static const double COAST[] = {-2000, 2000, 2000, 2000, 6000, 2000, 6000, 3000, -1000, 3000, -1000, 6000, -2000, 6000};

static const char *collection =
    "{\"type\": \"FeatureCollection\",\n"
    " \"features\": [\n"
    "  {\"type\": \"Feature\", \"properties\": {\"thickness\": 1.2, \"name\": \"a\"},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[0, 0], [1000, 0], [400, 800], [0, 0]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": null,\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[1500, 0], [2500, 100], [2400, 900], [1600, 700], "
    "[1500, 0]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"thickness\": 0.8},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[3000, 0], [3200, 900], [3800, 1000], [4100, 400], "
    "[3600, -200], [3000, 0]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"fixed\": true, \"name\": \"coast\"},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[-2000, 2000], [2000, 2000], [6000, 2000], "
    "[6000, 3000], [-1000, 3000], [-1000, 6000], [-2000, 6000], [-2000, 2000]]]}}\n"
    " ]}\n";

static const char *entry = "  - {polygons_file: floes.geojson, material: ice, thickness: 0.5, velocity: [0.1, 0]}\n";

static void test_collection(void) {
    write_file("floes.geojson", collection);
    char err[1024];
    floe_world *w;
    int rc = load(entry, &w, err, sizeof err);
    CHECK(rc == FLOE_OK, "the FeatureCollection loads: %s", err);
    if (rc) return;
    floe_particles_view v;
    floe_world_particles(w, &v);
    CHECK(v.n == 4, "4 bodies (%d)", v.n);
    if (v.n != 4 || !v.thickness) {
        floe_world_destroy(w);
        return;
    }
    const double *rings[] = {F0, F1, F2};
    const int sizes[] = {3, 4, 5};
    const double h[] = {1.2, 0.5, 0.8};
    for (int k = 0; k < 3; k++) {
        double c[2], A = fabs(ring_area(rings[k], sizes[k], c));
        char what[96];
        snprintf(what, sizeof what, "floe %d: mass = 920 h A (h = %g)", k, h[k]);
        CHECK_NEAR(v.mass[k], 920 * h[k] * A, 1e-12, what);
        CHECK(v.thickness[k] == h[k], "floe %d: thickness %g (%g)", k, h[k], v.thickness[k]);
        CHECK(fabs(v.x[3 * k] - c[0]) <= 1e-12 * 5000 && fabs(v.x[3 * k + 1] - c[1]) <= 1e-12 * 5000,
              "floe %d at its centroid (%.17g, %.17g) vs (%.17g, %.17g)", k, v.x[3 * k], v.x[3 * k + 1], c[0], c[1]);
        CHECK(v.motion[k] == FLOE_FREE && v.v[3 * k] == 0.1, "floe %d free at the entry's velocity", k);
    }
    CHECK(v.motion[3] == FLOE_FIXED && v.v[9] == 0 && v.v[10] == 0, "the coast (fixed: true) is fixed and still");
    CHECK(v.thickness[3] == 0.5, "the coast takes the entry's thickness (%g)", v.thickness[3]);
    const floe_geometry *g = floe_world_particle_geometry(w, 3);
    CHECK(g->klass == &floe_compound_class && v.pieces[3] >= 2, "the L is a compound of %d convex pieces", v.pieces[3]);
    floe_mass_properties mp;
    floe_geometry_mass_properties(g, 2, 1.0, &mp);
    CHECK_NEAR(mp.volume, 8000.0 * 1000 + 1000.0 * 3000, 1e-12, "the L's area (two rectangles)");
    CHECK(ring_area(COAST, 7, NULL) == 1.1e7, "the L ring's shoelace area is exact");
    /* centroid of the two rectangles [-2000, 6000] x [2000, 3000] and [-2000, -1000] x [3000, 6000] */
    double cx = (8e6 * 2000 + 3e6 * -1500) / 1.1e7, cy = (8e6 * 2500 + 3e6 * 4500) / 1.1e7;
    CHECK_NEAR(v.x[9], cx, 1e-12, "the L's centroid x");
    CHECK_NEAR(v.x[10], cy, 1e-12, "the L's centroid y");
    floe_world_destroy(w);
}

/* a ring as GeoJSON coordinates text [[[x, y], ...]] (closed) */
static void ring_json(char *buf, size_t len, const double *xy, int n) {
    size_t L = (size_t)snprintf(buf, len, "[[");
    for (int i = 0; i <= n && L < len; i++)
        L += (size_t)snprintf(buf + L, len - L, "%s[%.17g, %.17g]", i ? ", " : "", xy[2 * (i % n)], xy[2 * (i % n) + 1]);
    if (L < len) snprintf(buf + L, len - L, "]]");
}

/* non-convex rings: the pieces partition the ring (their areas add up to its area) */
static void test_decomposition(void) {
    enum { NS = 300 };
    static double star[2 * NS];
    unsigned long long r = 12345;
    for (int i = 0; i < NS; i++) { /* a random star, counter-clockwise */
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        double rad = 500 + 1500 * (double)(r >> 11) / 9007199254740992.0, th = 2 * M_PI * i / NS;
        star[2 * i] = 1e5 + rad * cos(th);
        star[2 * i + 1] = -3e4 + rad * sin(th);
    }
    /* a comb, clockwise: 6 teeth 100 m wide, 250 m high, 100 m apart, on a bar 50 m high */
    double comb[2 * 64];
    int nc = 0;
    comb[nc++] = 0;
    comb[nc++] = 0;
    for (int t = 0; t < 6; t++) {
        double x0 = 200.0 * t;
        if (t > 0) {
            comb[nc++] = x0;
            comb[nc++] = 50;
        }
        comb[nc++] = x0;
        comb[nc++] = 300;
        comb[nc++] = x0 + 100;
        comb[nc++] = 300;
        comb[nc++] = x0 + 100;
        comb[nc++] = t < 5 ? 50 : 0;
    }
    int ncomb = nc / 2;
    static char text[65536], rs[32768], rc_[4096];
    ring_json(rs, sizeof rs, star, NS);
    ring_json(rc_, sizeof rc_, comb, ncomb);
    snprintf(text, sizeof text,
             "{\"type\": \"FeatureCollection\", \"features\": [\n"
             " {\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"Polygon\", \"coordinates\": %s}},\n"
             " {\"type\": \"Feature\", \"geometry\": {\"type\": \"Polygon\", \"coordinates\": %s}, \"properties\": {}}]}\n",
             rs, rc_);
    write_file("shapes.geojson", text);
    char err[1024];
    floe_world *w;
    int rc = load("  - {polygons_file: shapes.geojson, material: ice, thickness: 1}\n", &w, err, sizeof err);
    CHECK(rc == FLOE_OK, "a star and a comb load: %s", err);
    if (rc) return;
    floe_particles_view v;
    floe_world_particles(w, &v);
    CHECK(v.n == 2, "2 bodies (%d)", v.n);
    const double *rings[] = {star, comb};
    const int n[] = {NS, ncomb};
    for (int k = 0; k < 2 && k < v.n; k++) {
        floe_mass_properties mp;
        floe_geometry_mass_properties(floe_world_particle_geometry(w, k), 2, 1.0, &mp);
        double c[2], A = fabs(ring_area(rings[k], n[k], c));
        char what[96];
        snprintf(what, sizeof what, "%s: the %d pieces' area = the ring's", k ? "comb" : "star", v.pieces[k]);
        CHECK_NEAR(mp.volume, A, 1e-12, what);
        CHECK(fabs(v.x[3 * k] - c[0]) <= 1e-12 * 1e5 && fabs(v.x[3 * k + 1] - c[1]) <= 1e-12 * 1e5,
              "%s at its centroid", k ? "comb" : "star");
        /* Hertel-Mehlhorn keeps at most two diagonals per reflex point: pieces <= 2 r + 1 */
        int reflex = 0, ccw = ring_area(rings[k], n[k], NULL) > 0;
        for (int i = 0; i < n[k]; i++) {
            const double *a = rings[k] + 2 * ((i + n[k] - 1) % n[k]), *p = rings[k] + 2 * i,
                         *q = rings[k] + 2 * ((i + 1) % n[k]);
            double cr = (p[0] - a[0]) * (q[1] - p[1]) - (p[1] - a[1]) * (q[0] - p[0]);
            reflex += ccw ? cr < 0 : cr > 0;
        }
        CHECK(v.pieces[k] > 1 && v.pieces[k] <= 2 * reflex + 1, "%s: %d pieces for %d reflex points (<= 2 r + 1)",
              k ? "comb" : "star", v.pieces[k], reflex);
        printf("  %s: %d points, %d reflex, %d convex pieces\n", k ? "comb" : "star", n[k], reflex, v.pieces[k]);
    }
    floe_world_destroy(w);
}

static void test_multipolygon(void) {
    write_file("multi.geojson",
               "{\"type\": \"Feature\", \"properties\": {\"thickness\": 0.3},\n"
               " \"geometry\": {\"type\": \"MultiPolygon\", \"coordinates\": [\n"
               "   [[[0, 0], [100, 0], [100, 100], [0, 100], [0, 0]]],\n"
               "   [[[200, 0], [400, 0], [400, 200], [300, 200], [300, 100], [200, 100], [200, 0]]]]}}\n");
    write_file("bare.geojson", "{\"type\": \"Polygon\", \"coordinates\": [[[0, 0, 7], [10, 0, 7], [0, 10, 7]]]}");
    char err[1024];
    floe_world *w;
    int rc = load("  - {polygons_file: multi.geojson, material: ice, thickness: 0.5}\n"
                  "  - {polygons_file: bare.geojson, material: ice, thickness: 2, motion: fixed}\n",
                  &w, err, sizeof err);
    CHECK(rc == FLOE_OK, "a MultiPolygon Feature and a bare Polygon load: %s", err);
    if (rc) return;
    floe_particles_view v;
    floe_world_particles(w, &v);
    CHECK(v.n == 3, "3 bodies (%d)", v.n);
    if (v.n == 3 && v.thickness) {
        CHECK_NEAR(v.mass[0], 920 * 0.3 * 1e4, 1e-12, "MultiPolygon square: 920 x 0.3 x 100^2");
        CHECK_NEAR(v.mass[1], 920 * 0.3 * 3e4, 1e-12, "MultiPolygon L: 920 x 0.3 x 30,000");
        CHECK(v.group[0] == 0 && v.group[1] == 0 && v.group[2] == 1, "the entries' bodies carry their index");
        CHECK(v.motion[2] == FLOE_FIXED && v.thickness[2] == 2, "the bare polygon: the entry's motion and thickness");
        CHECK_NEAR(v.mass[2], 920 * 2 * 50.0, 1e-12, "the bare polygon (altitudes ignored): 920 x 2 x 50");
    }
    floe_world_destroy(w);
    /* touching is not overlapping: a shared edge, a corner, a square in the L's notch */
    write_file("touch.geojson",
               "{\"type\": \"MultiPolygon\", \"coordinates\": [\n"
               "  [[[0, 0], [100, 0], [100, 100], [0, 100]]],\n"
               "  [[[100, 0], [200, 0], [200, 100], [100, 100]]],\n"
               "  [[[200, 100], [300, 100], [300, 200], [200, 200]]],\n"
               "  [[[400, 0], [600, 0], [600, 200], [500, 200], [500, 100], [400, 100]]],\n"
               "  [[[400, 100], [500, 100], [500, 200], [400, 200]]]]}\n");
    rc = load("  - {polygons_file: touch.geojson, material: ice, thickness: 0.5}\n", &w, err, sizeof err);
    CHECK(rc == FLOE_OK, "touching polygons are accepted: %s", err);
    floe_world_destroy(w);
}

/* every defect, refused naming the file, the feature and what is wrong */
static void test_errors(void) {
    static const char *sq = "[[[0, 0], [100, 0], [100, 100], [0, 100], [0, 0]]]";
    static const char *sq2 = "[[[500, 0], [600, 0], [600, 100], [500, 100], [500, 0]]]";
    struct {
        const char *geometry;  /* feature 2's geometry (NULL: the whole file is `raw`) */
        const char *raw;
        const char *words[2];
    } cases[] = {
        {NULL, "{\"type\": \"FeatureCollection\",\n \"features\": [{\"type\": \"Feature\",, }]}",
         {"invalid JSON", "bad.geojson:2:"}},
        {NULL, "{\"type\": \"FeatureCollection\", \"features\": [", {"invalid JSON", "end of data"}},
        {NULL, "{\"type\": \"GeometryCollection\", \"geometries\": []}", {"feature 0", "GeometryCollection"}},
        {"{\"type\": \"Point\", \"coordinates\": [1, 2]}", NULL, {"feature 2", "Point"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1100, 0], [1100, 0], [1000, 0]]]}", NULL,
         {"feature 2", "distinct points"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1e999, 0], [1100, 100], [1000, 0]]]}", NULL,
         {"feature 2", "not finite"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1100, 0], [1100, NaN], [1000, 0]]]}", NULL,
         {"feature 2", "not finite"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1100, 100], [1100, 0], [1000, 100], [1000, 0]]]}",
         NULL, {"feature 2", "self-intersecting"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1200, 0], [1100, 0], [1100, 100], [1000, 0]]]}",
         NULL, {"feature 2", "self-intersecting"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1100, 0], [1200, 0], [1000, 0]]]}", NULL,
         {"feature 2", "zero area"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1300, 0], [1300, 300], [1000, 300], [1000, 0]], "
         "[[1100, 100], [1200, 100], [1200, 200], [1100, 100]]]}",
         NULL, {"feature 2", "holes are not supported"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[50, 50], [150, 50], [150, 150], [50, 150], [50, 50]]]}", NULL,
         {"feature 0 and feature 2 overlap", "overlap"}},
        /* an L around feature 1's square: boxes meet, the L's arm runs into it */
        {"{\"type\": \"MultiPolygon\", \"coordinates\": [[[[1000, 0], [1100, 0], [1100, 100], [1000, 100]]], "
         "[[[300, -100], [700, -100], [700, 300], [300, 300], [300, 200], [550, 200], [550, 50], [300, 50]]]]}",
         NULL, {"feature 1 and feature 2 polygon 1 overlap", "overlap"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1100, 0], [1000, 100]]]}, \"properties\": "
         "{\"thickness\": -1}",
         NULL, {"feature 2", "properties.thickness"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1100, 0], [1000, 100]]]}, \"properties\": "
         "{\"fixed\": \"yes\"}",
         NULL, {"feature 2", "properties.fixed"}},
        {"{\"type\": \"Polygon\", \"coordinates\": [[[1000, 0], [1100, 0], [\"a\", 100]]]}", NULL,
         {"feature 2", "point 2"}},
        {"null", NULL, {"feature 2", "no geometry"}},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char text[2048];
        if (cases[k].raw) snprintf(text, sizeof text, "%s", cases[k].raw);
        else
            snprintf(text, sizeof text,
                     "{\"type\": \"FeatureCollection\", \"features\": [\n"
                     " {\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"Polygon\", \"coordinates\": %s}},\n"
                     " {\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"Polygon\", \"coordinates\": %s}},\n"
                     " {\"type\": \"Feature\", \"geometry\": %s}]}\n",
                     sq, sq2, cases[k].geometry);
        write_file("bad.geojson", text);
        char err[1024];
        floe_world *w;
        int rc = load("  - {polygons_file: bad.geojson, material: ice, thickness: 0.5}\n", &w, err, sizeof err);
        CHECK(rc != FLOE_OK && strstr(err, "s.yaml:8:") && strstr(err, "bodies[0].polygons_file: bad.geojson") &&
                  strstr(err, cases[k].words[0]) && strstr(err, cases[k].words[1]),
              "case %zu refused with '%s' and '%s': %s", k, cases[k].words[0], cases[k].words[1], err);
        printf("  refused: %s\n", err);
        floe_world_destroy(w);
    }
    char err[1024];
    floe_world *w;
    int rc = load("  - {polygons_file: nowhere.geojson, material: ice}\n", &w, err, sizeof err);
    CHECK(rc == FLOE_EIO && strstr(err, "nowhere.geojson") && strstr(err, "cannot read"), "a missing file: %s", err);
    floe_world_destroy(w);
    rc = load("  - {polygons_file: floes.geojson, material: ice, thikness: 1}\n", &w, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, "unknown key 'thikness'") && strstr(err, "thickness"), "a bad key: %s", err);
    floe_world_destroy(w);
    rc = load("  - {polygons_file: floes.geojson, material: ice, thickness: -1}\n", &w, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, "thickness must be > 0"), "a negative thickness: %s", err);
    floe_world_destroy(w);
    char text[1024], path[128];
    snprintf(text, sizeof text, "time: {duration: 1, dt: 1e-3}\nmaterials: [{name: ice, density: 920, young: 6e6, "
             "poisson: 0.3}]\nbodies:\n  - {polygons_file: floes.geojson, material: ice}\n");
    snprintf(path, sizeof path, "%s/s.yaml", dir);
    rc = floe_scene_load_ex(path, text, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, "2D"), "polygons in a 3D scene are refused: %s", err);
    floe_world_destroy(w);
}

/* the floes of test 1 written as polygon bodies at their centroids: the same bits */
static void test_same_as_polygons(void) {
    char bodies[4096], err[1024];
    size_t L = 0;
    const double *rings[] = {F0, F1, F2};
    const int sizes[] = {3, 4, 5};
    const double h[] = {1.2, 0.5, 0.8};
    for (int k = 0; k < 3; k++) {
        floe_geometry *g = floe_polygon_create(rings[k], sizes[k], err, sizeof err);
        CHECK(g != NULL, "polygon %d: %s", k, err);
        if (!g) return;
        const floe_polytope *p = (const floe_polytope *)g;
        L += (size_t)snprintf(bodies + L, sizeof bodies - L,
                              "  - {material: ice, thickness: %.17g, velocity: [0.1, 0], position: [%.17g, %.17g],\n"
                              "     shape: {polygon: {vertices: [", h[k], p->frame_x[0], p->frame_x[1]);
        for (int i = 0; i < sizes[k]; i++)
            L += (size_t)snprintf(bodies + L, sizeof bodies - L, "%s[%.17g, %.17g]", i ? ", " : "", rings[k][2 * i],
                                  rings[k][2 * i + 1]);
        L += (size_t)snprintf(bodies + L, sizeof bodies - L, "]}}}\n");
        floe_geometry_destroy(g);
    }
    /* the coast as two rectangles of a compound, at the L's centroid */
    L += (size_t)snprintf(bodies + L, sizeof bodies - L,
                          "  - {material: ice, thickness: 0.5, motion: fixed, position: [%.17g, %.17g], shape: {compound: "
                          "{pieces: [{shape: {polygon: {vertices: [[-2000, 2000], [6000, 2000], [6000, 3000], [-2000, 3000]]}}},"
                          " {shape: {polygon: {vertices: [[-2000, 3000], [-1000, 3000], [-1000, 6000], [-2000, 6000]]}}}]}}}\n",
                          (8e6 * 2000 + 3e6 * -1500) / 1.1e7, (8e6 * 2500 + 3e6 * 4500) / 1.1e7);
    floe_world *a, *b;
    int rc = load(entry, &a, err, sizeof err);
    CHECK(rc == FLOE_OK, "GeoJSON scene: %s", err);
    int rc2 = load(bodies, &b, err, sizeof err);
    CHECK(rc2 == FLOE_OK, "polygon scene: %s", err);
    if (!rc && !rc2) {
        floe_particles_view va, vb;
        floe_world_particles(a, &va);
        floe_world_particles(b, &vb);
        CHECK(va.n == 4 && vb.n == 4, "4 bodies each (%d, %d)", va.n, vb.n);
        for (int k = 0; k < 3 && va.n == 4 && vb.n == 4; k++) {
            CHECK(memcmp(va.x + 3 * k, vb.x + 3 * k, 3 * sizeof(double)) == 0 &&
                      memcmp(va.q + 4 * k, vb.q + 4 * k, 4 * sizeof(double)) == 0 && va.mass[k] == vb.mass[k] &&
                      va.inertia[3 * k + 2] == vb.inertia[3 * k + 2],
                  "floe %d: bit-identical position, orientation, mass and inertia (%.17g vs %.17g)", k, va.mass[k],
                  vb.mass[k]);
        }
        if (va.n == 4 && vb.n == 4) {
            CHECK_NEAR(va.mass[3], vb.mass[3], 1e-12, "coast: mass as the compound of two rectangles");
            CHECK_NEAR(va.inertia[11], vb.inertia[11], 1e-12, "coast: inertia as the compound of two rectangles");
            CHECK(fabs(va.x[9] - vb.x[9]) <= 1e-12 * 6000 && fabs(va.x[10] - vb.x[10]) <= 1e-12 * 6000,
                  "coast: the same centroid");
        }
    }
    floe_world_destroy(a);
    floe_world_destroy(b);
}

int main(void) {
    char err[256];
    floe_register_builtins(err, sizeof err);
    snprintf(dir, sizeof dir, "/tmp/floe_geojson_XXXXXX");
    if (!mkdtemp(dir)) {
        fprintf(stderr, "test_geojson: cannot make a temporary directory\n");
        return 1;
    }
    test_collection();
    test_decomposition();
    test_multipolygon();
    test_errors();
    test_same_as_polygons();
    const char *names[] = {"floes.geojson", "shapes.geojson", "multi.geojson", "bare.geojson", "touch.geojson",
                           "bad.geojson"};
    for (size_t k = 0; k < sizeof names / sizeof *names; k++) {
        char path[128];
        snprintf(path, sizeof path, "%s/%s", dir, names[k]);
        remove(path);
    }
    rmdir(dir);
    return check_summary("test_geojson");
}
