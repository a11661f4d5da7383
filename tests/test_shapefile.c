/* test_shapefile.c - floes, coastlines and islands from an ESRI shapefile (`bodies:
 * [{polygons_file: F.shp, ...}]`, core/scene/scene_shapefile.c through the checks and bodies
 * of core/scene/scene_geojson.c); the shapefiles are written here with shapelib's writer API
 * (SHPCreate, SHPCreateObject, SHPWriteObject; DBFCreate, DBFAddField, DBFWrite*Attribute):
 *  - two floes (a convex quadrilateral with thickness 1.2 and fixed F in the .dbf, a
 *    non-convex C with empty attributes) and a coast of two parts (a non-convex L and a
 *    triangular island, fixed T), rings clockwise as the format says: 4 bodies whose
 *    masses, inertias and centroids equal those of the same polygons given through GeoJSON
 *    (counter-clockwise there) to 1e-12, their areas the rings' (1e-12), thickness and
 *    fixed read from the .dbf (an empty value: the entry's);
 *  - a multi-part shape whose parts all run counter-clockwise (a writer that ignores the
 *    rule) is read as outer rings; upper-case .SHP/.SHX names are read; integer fields
 *    (fixed 0/1, thickness), field names in any case;
 *  - refused, naming the file and the shape: a self-intersecting ring, a hole, overlapping
 *    shapes, a bad thickness, point shapes, a .prj in longitude/latitude, a missing file.
 * Built without FLOE_WITH_SHAPELIB it checks that a .shp is refused with a message naming
 * the option, prints "skipped: built without FLOE_WITH_SHAPELIB" and exits with 77 (ctest
 * reports it skipped). */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[64];

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

#ifndef FLOE_HAVE_SHAPELIB

int main(void) {
    char err[1024];
    floe_register_builtins(err, sizeof err);
    snprintf(dir, sizeof dir, "/tmp/floe_shp_XXXXXX");
    if (!mkdtemp(dir)) return 1;
    char path[128];
    snprintf(path, sizeof path, "%s/floes.shp", dir);
    FILE *f = fopen(path, "w");
    if (f) fclose(f);
    floe_world *w;
    int rc = load("  - {polygons_file: floes.shp, material: ice, thickness: 0.5}\n", &w, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, "FLOE_WITH_SHAPELIB") && strstr(err, "bodies[0].polygons_file: floes.shp"),
          "a .shp is refused naming the option: %s", err);
    floe_world_destroy(w);
    remove(path);
    rmdir(dir);
    printf("  refused: %s\n", err);
    printf("skipped: built without FLOE_WITH_SHAPELIB (a .shp scene is refused naming the option: %s)\n",
           check_fail_ ? "FAILED" : "checked");
    check_summary("test_shapefile");
    return check_fail_ ? 1 : 77;
}

#else

#include <shapefil.h>

/* the polygons, counter-clockwise, not closed */
static const double Q[] = {1500, 0, 2500, 100, 2400, 900, 1600, 700};
static const double C[] = {3000, 0, 4000, 0, 4000, 1000, 3000, 1000, 3000, 700, 3600, 700, 3600, 300, 3000, 300};
static const double L[] = {-2000, 2000, 2000, 2000, 6000, 2000, 6000, 3000, -1000, 3000, -1000, 6000, -2000, 6000};
static const double ISLAND[] = {-500, -2000, 500, -2000, 0, -1200};

/* one part of a shape: n points, written clockwise (cw = 1) or counter-clockwise, closed */
typedef struct part { const double *xy; int n, cw; } part;
typedef struct shape { part p[3]; int np; double h; char fixed; } shape; /* h 0, fixed 0: empty */

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

static char written[64][160];
static int nwritten;

static const char *tmp(const char *name) {
    static char p[160];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    if (nwritten < 64) snprintf(written[nwritten++], sizeof written[0], "%s", p);
    return p;
}

/* base.shp, .shx and (attrs) .dbf of the shapes, of shapelib type `type` */
static int write_shapefile(const char *base, int type, const shape *s, int ns, int attrs) {
    char name[96];
    snprintf(name, sizeof name, "%s.shx", base);
    tmp(name);
    snprintf(name, sizeof name, "%s.shp", base);
    SHPHandle h = SHPCreate(tmp(name), type);
    CHECK(h != NULL, "SHPCreate %s", name);
    if (!h) return 0;
    for (int k = 0; k < ns; k++) {
        double x[256], y[256];
        int start[3], nv = 0;
        for (int j = 0; j < s[k].np; j++) {
            const part *p = s[k].p + j;
            start[j] = nv;
            for (int i = 0; i <= p->n; i++) { /* closed: the first point again */
                int m = p->cw ? (p->n - i) % p->n : i % p->n;
                x[nv] = p->xy[2 * m];
                y[nv++] = p->xy[2 * m + 1];
            }
        }
        SHPObject *o = type == SHPT_POINT ? SHPCreateSimpleObject(type, 1, x, y, NULL)
                                          : SHPCreateObject(type, -1, s[k].np, start, NULL, nv, x, y, NULL, NULL);
        CHECK(SHPWriteObject(h, -1, o) == k, "SHPWriteObject shape %d", k);
        SHPDestroyObject(o);
    }
    SHPClose(h);
    if (!attrs) return 1;
    snprintf(name, sizeof name, "%s.dbf", base);
    DBFHandle d = DBFCreate(tmp(name));
    CHECK(d != NULL, "DBFCreate %s", name);
    if (!d) return 0;
    int ih = DBFAddField(d, "thickness", FTDouble, 12, 4), ifx = DBFAddField(d, "fixed", FTLogical, 1, 0);
    int in = DBFAddField(d, "name", FTString, 16, 0);
    CHECK(ih == 0 && ifx == 1 && in == 2, "DBFAddField");
    for (int k = 0; k < ns; k++) {
        int ok = s[k].h != 0 ? DBFWriteDoubleAttribute(d, k, ih, s[k].h) : DBFWriteNULLAttribute(d, k, ih);
        ok = ok && (s[k].fixed ? DBFWriteLogicalAttribute(d, k, ifx, s[k].fixed) : DBFWriteNULLAttribute(d, k, ifx));
        ok = ok && DBFWriteStringAttribute(d, k, in, "floe");
        CHECK(ok, "DBFWrite* shape %d", k);
    }
    DBFClose(d);
    return 1;
}

static void write_text(const char *name, const char *text) {
    FILE *f = fopen(tmp(name), "w");
    CHECK(f != NULL, "cannot write %s", name);
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

/* a ring as GeoJSON coordinates [[x, y], ...] (closed, counter-clockwise) */
static size_t ring_json(char *buf, size_t len, const double *xy, int n) {
    size_t at = (size_t)snprintf(buf, len, "[");
    for (int i = 0; i <= n && at < len; i++)
        at += (size_t)snprintf(buf + at, len - at, "%s[%.17g, %.17g]", i ? ", " : "", xy[2 * (i % n)],
                               xy[2 * (i % n) + 1]);
    if (at < len) at += (size_t)snprintf(buf + at, len - at, "]");
    return at;
}

static const char *entry_shp = "  - {polygons_file: floes.shp, material: ice, thickness: 0.5, velocity: [0.1, 0]}\n";

static void test_floes(void) {
    const shape shapes[] = {
        {{{Q, 4, 1}}, 1, 1.2, 'F'},
        {{{C, 8, 1}}, 1, 0, 0},
        {{{L, 7, 1}, {ISLAND, 3, 1}}, 2, 0, 'T'},
    };
    if (!write_shapefile("floes", SHPT_POLYGON, shapes, 3, 1)) return;
    /* the same polygons through GeoJSON */
    char text[8192], rq[1024], rc_[1024], rl[1024], ri[512];
    ring_json(rq, sizeof rq, Q, 4);
    ring_json(rc_, sizeof rc_, C, 8);
    ring_json(rl, sizeof rl, L, 7);
    ring_json(ri, sizeof ri, ISLAND, 3);
    snprintf(text, sizeof text,
             "{\"type\": \"FeatureCollection\", \"features\": [\n"
             " {\"type\": \"Feature\", \"properties\": {\"thickness\": 1.2, \"fixed\": false}, \"geometry\": "
             "{\"type\": \"Polygon\", \"coordinates\": [%s]}},\n"
             " {\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [%s]}},\n"
             " {\"type\": \"Feature\", \"properties\": {\"fixed\": true}, \"geometry\": {\"type\": \"MultiPolygon\", "
             "\"coordinates\": [[%s], [%s]]}}]}\n",
             rq, rc_, rl, ri);
    write_text("floes.geojson", text);
    char err[1024];
    floe_world *a, *b;
    int rc = load(entry_shp, &a, err, sizeof err);
    CHECK(rc == FLOE_OK, "the shapefile loads: %s", err);
    int rc2 = load("  - {polygons_file: floes.geojson, material: ice, thickness: 0.5, velocity: [0.1, 0]}\n", &b, err,
                   sizeof err);
    CHECK(rc2 == FLOE_OK, "the GeoJSON loads: %s", err);
    if (rc || rc2) {
        floe_world_destroy(a);
        floe_world_destroy(b);
        return;
    }
    floe_particles_view va, vb;
    floe_world_particles(a, &va);
    floe_world_particles(b, &vb);
    CHECK(va.n == 4 && vb.n == 4, "4 bodies from each (%d, %d)", va.n, vb.n);
    if (va.n != 4 || vb.n != 4 || !va.thickness) {
        floe_world_destroy(a);
        floe_world_destroy(b);
        return;
    }
    const double *rings[] = {Q, C, L, ISLAND};
    const int sizes[] = {4, 8, 7, 3};
    const double h[] = {1.2, 0.5, 0.5, 0.5};
    const char *names[] = {"quadrilateral", "C", "coast L", "island"};
    double worst = 0;
    for (int k = 0; k < 4; k++) {
        char what[96];
        double c[2], A = ring_area(rings[k], sizes[k], c);
        snprintf(what, sizeof what, "%s: mass = the GeoJSON's", names[k]);
        CHECK_NEAR(va.mass[k], vb.mass[k], 1e-12, what);
        snprintf(what, sizeof what, "%s: inertia = the GeoJSON's", names[k]);
        CHECK_NEAR(va.inertia[3 * k + 2], vb.inertia[3 * k + 2], 1e-12, what);
        snprintf(what, sizeof what, "%s: area (mass / 920 h) = the ring's", names[k]);
        CHECK_NEAR(va.mass[k] / (920 * h[k]), A, 1e-12, what);
        double dx = fmax(fabs(va.x[3 * k] - vb.x[3 * k]), fabs(va.x[3 * k + 1] - vb.x[3 * k + 1]));
        double dc = fmax(fabs(va.x[3 * k] - c[0]), fabs(va.x[3 * k + 1] - c[1]));
        CHECK(dx <= 1e-12 * 6000 && dc <= 1e-12 * 6000, "%s: at the GeoJSON body's position (%.3g m) and the ring's "
              "centroid (%.3g m)", names[k], dx, dc);
        worst = fmax(worst, fabs(va.mass[k] - vb.mass[k]) / vb.mass[k]);
        CHECK(va.thickness[k] == h[k], "%s: thickness %g from the .dbf (%g)", names[k], h[k], va.thickness[k]);
        CHECK(va.motion[k] == vb.motion[k], "%s: the same motion as from GeoJSON", names[k]);
    }
    printf("  shapefile vs GeoJSON: largest relative mass difference %.3g\n", worst);
    CHECK(va.motion[0] == FLOE_FREE && va.v[0] == 0.1, "the quadrilateral (fixed F) is free at the entry's velocity");
    CHECK(va.motion[1] == FLOE_FREE && va.v[3] == 0.1, "the C (fixed empty) takes the entry's motion and velocity");
    CHECK(va.motion[2] == FLOE_FIXED && va.motion[3] == FLOE_FIXED && va.v[6] == 0 && va.v[9] == 0,
          "both parts of the coast (fixed T) are fixed and still");
    CHECK(va.pieces[1] >= 2 && va.pieces[2] >= 2 && va.pieces[0] == 1,
          "the C and the L are compounds (%d, %d pieces), the quadrilateral a polygon", va.pieces[1], va.pieces[2]);
    floe_world_destroy(a);
    floe_world_destroy(b);
}

/* parts all counter-clockwise: outer rings; upper-case extensions */
static void test_lenient(void) {
    const shape s[] = {{{{Q, 4, 0}, {C, 8, 0}}, 2, 0, 0}};
    if (!write_shapefile("ccw", SHPT_POLYGONZ, s, 1, 0)) return;
    char err[1024];
    floe_world *w;
    int rc = load("  - {polygons_file: ccw.shp, material: ice, thickness: 2}\n", &w, err, sizeof err);
    CHECK(rc == FLOE_OK, "a PolygonZ shape of two counter-clockwise parts, without .dbf, loads: %s", err);
    if (!rc) {
        floe_particles_view v;
        floe_world_particles(w, &v);
        CHECK(v.n == 2, "two bodies (%d)", v.n);
        if (v.n == 2) {
            CHECK_NEAR(v.mass[0], 920 * 2 * ring_area(Q, 4, NULL), 1e-12, "part 0: 920 h A");
            CHECK_NEAR(v.mass[1], 920 * 2 * ring_area(C, 8, NULL), 1e-12, "part 1: 920 h A");
        }
    }
    floe_world_destroy(w);
    const shape t[] = {{{{Q, 4, 1}}, 1, 0.7, 'T'}};
    if (!write_shapefile("upper", SHPT_POLYGON, t, 1, 1)) return;
    const char *ext[][2] = {{"shp", "SHP"}, {"shx", "SHX"}, {"dbf", "DBF"}};
    for (int k = 0; k < 3; k++) {
        char from[160], to[160];
        snprintf(from, sizeof from, "%s/upper.%s", dir, ext[k][0]);
        snprintf(to, sizeof to, "%s/UPPER.%s", dir, ext[k][1]);
        CHECK(rename(from, to) == 0, "rename %s", from);
        tmp(strrchr(to, '/') + 1);
    }
    rc = load("  - {polygons_file: UPPER.SHP, material: ice, thickness: 2}\n", &w, err, sizeof err);
    CHECK(rc == FLOE_OK, "UPPER.SHP (with .SHX and .DBF) loads: %s", err);
    if (!rc) {
        floe_particles_view v;
        floe_world_particles(w, &v);
        CHECK(v.n == 1 && v.thickness && v.thickness[0] == 0.7 && v.motion[0] == FLOE_FIXED,
              "UPPER.SHP: thickness 0.7 and fixed from UPPER.DBF");
    }
    floe_world_destroy(w);
    /* integer fields, named in other cases: FIXED 1 and 2, Thickness 3 */
    const shape u[] = {{{{Q, 4, 1}}, 1, 0, 0}, {{{C, 8, 1}}, 1, 0, 0}};
    if (!write_shapefile("ints", SHPT_POLYGON, u, 2, 0)) return;
    for (int bad = 0; bad < 2; bad++) {
        DBFHandle d = DBFCreate(tmp("ints.dbf"));
        CHECK(d != NULL, "DBFCreate ints.dbf");
        if (!d) return;
        int ifx = DBFAddField(d, "FIXED", FTInteger, 4, 0), ih = DBFAddField(d, "Thickness", FTInteger, 4, 0);
        for (int k = 0; k < 2; k++) {
            DBFWriteIntegerAttribute(d, k, ifx, bad && k == 1 ? 2 : 1 - k);
            DBFWriteIntegerAttribute(d, k, ih, 3);
        }
        DBFClose(d);
        rc = load("  - {polygons_file: ints.shp, material: ice, thickness: 2}\n", &w, err, sizeof err);
        if (!bad) {
            floe_particles_view v;
            if (!rc) floe_world_particles(w, &v);
            CHECK(!rc && v.n == 2 && v.thickness[0] == 3 && v.thickness[1] == 3 && v.motion[0] == FLOE_FIXED &&
                      v.motion[1] == FLOE_FREE,
                  "integer fields FIXED 1, 0 and Thickness 3 are read: %s", err);
        } else {
            CHECK(rc != FLOE_OK && strstr(err, "shape 1: the attribute fixed must be 0 or 1"), "FIXED 2 refused: %s",
                  err);
            printf("  refused: %s\n", err);
        }
        floe_world_destroy(w);
    }
}

static void test_errors(void) {
    static const double sq[] = {0, 0, 100, 0, 100, 100, 0, 100};
    static const double bow[] = {1000, 0, 1100, 100, 1100, 0, 1000, 100};
    static const double outer[] = {1000, 0, 1300, 0, 1300, 300, 1000, 300};
    static const double inner[] = {1100, 100, 1200, 100, 1200, 200};
    static const double over[] = {50, 50, 150, 50, 150, 150, 50, 150};
    static const double tri[] = {1000, 0, 1100, 0, 1000, 100};
    struct {
        shape s[2];
        int type;
        const char *prj;
        const char *words[2];
    } cases[] = {
        {{{{{sq, 4, 1}}, 1, 0, 0}, {{{bow, 4, 1}}, 1, 0, 0}}, SHPT_POLYGON, NULL, {"shape 1", "self-intersecting"}},
        {{{{{sq, 4, 1}}, 1, 0, 0}, {{{outer, 4, 1}, {inner, 3, 0}}, 2, 0, 0}}, SHPT_POLYGON, NULL,
         {"shape 1", "holes are not supported: part 1"}},
        {{{{{sq, 4, 1}}, 1, 0, 0}, {{{over, 4, 1}}, 1, 0, 0}}, SHPT_POLYGON, NULL, {"shape 0 and shape 1 overlap", ""}},
        {{{{{sq, 4, 1}}, 1, 0, 0}, {{{tri, 3, 1}}, 1, -1, 0}}, SHPT_POLYGON, NULL, {"shape 1", "thickness must be > 0"}},
        {{{{{sq, 4, 1}}, 1, 0, 0}, {{{tri, 3, 1}}, 1, 0, 0}}, SHPT_POINT, NULL, {"Point", "expected polygons"}},
        {{{{{sq, 4, 1}}, 1, 0, 0}, {{{tri, 3, 1}}, 1, 0, 0}}, SHPT_POLYGON,
         "GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\",SPHEROID[\"WGS_1984\",6378137,298.257223563]]]",
         {"longitude and latitude", "project"}},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char base[32], name[48];
        snprintf(base, sizeof base, "bad%zu", k);
        if (!write_shapefile(base, cases[k].type, cases[k].s, 2, 1)) continue;
        if (cases[k].prj) {
            snprintf(name, sizeof name, "%s.prj", base);
            write_text(name, cases[k].prj);
        }
        char bodies[256], err[1024], head[96];
        snprintf(bodies, sizeof bodies, "  - {polygons_file: %s.shp, material: ice, thickness: 0.5}\n", base);
        snprintf(head, sizeof head, "bodies[0].polygons_file: %s.shp: ", base);
        floe_world *w;
        int rc = load(bodies, &w, err, sizeof err);
        CHECK(rc != FLOE_OK && strstr(err, "s.yaml:8:") && strstr(err, head) && strstr(err, cases[k].words[0]) &&
                  strstr(err, cases[k].words[1]),
              "case %zu refused with '%s' and '%s': %s", k, cases[k].words[0], cases[k].words[1], err);
        printf("  refused: %s\n", err);
        floe_world_destroy(w);
    }
    char err[1024];
    floe_world *w;
    int rc = load("  - {polygons_file: nowhere.shp, material: ice}\n", &w, err, sizeof err);
    CHECK(rc == FLOE_EIO && strstr(err, "nowhere.shp") && strstr(err, "cannot read"), "a missing file: %s", err);
    printf("  refused: %s\n", err);
    floe_world_destroy(w);
    /* a .shp without its .shx */
    write_text("lonely.shp", "not a shapefile");
    rc = load("  - {polygons_file: lonely.shp, material: ice}\n", &w, err, sizeof err);
    CHECK(rc == FLOE_EIO && strstr(err, "lonely.shp") && strstr(err, "as a shapefile"), "a .shp alone: %s", err);
    printf("  refused: %s\n", err);
    floe_world_destroy(w);
}

int main(void) {
    char err[256];
    floe_register_builtins(err, sizeof err);
    snprintf(dir, sizeof dir, "/tmp/floe_shp_XXXXXX");
    if (!mkdtemp(dir)) {
        fprintf(stderr, "test_shapefile: cannot make a temporary directory\n");
        return 1;
    }
    test_floes();
    test_lenient();
    test_errors();
    for (int k = 0; k < nwritten; k++) remove(written[k]);
    rmdir(dir);
    return check_summary("test_shapefile");
}

#endif
