/* scene_geojson.c - a body entry `{polygons_file: PATH, material, thickness, motion, velocity,
 * name}`: 2D floes, coastlines and islands read from a GeoJSON file (RFC 7946) of polygons,
 * parsed with json-c, or from an ESRI shapefile when PATH ends in .shp (scene_shapefile.c)
 * (docs/sea-ice.md, "Floes from GeoJSON" and "Floes from shapefiles"; docs/scene-format.md).
 * Both readers hand their rings to scene_polygons.c, which checks them and builds the bodies.
 *
 * Every Polygon, and every polygon of a MultiPolygon, of the FeatureCollection, Feature or
 * bare geometry is one ring handed over. A Feature's properties may set `thickness` (m) and
 * `fixed` (a coastline or island). Refused here, naming the file and the feature: an
 * unreadable file, invalid JSON (json-c's message at its line and column), other GeoJSON
 * types, malformed positions, holes (interior rings), bad properties. */
#include "scene_read.h"

#include <json.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* the largest file read (json-c keeps every number as an object of its own) */
#ifdef FLOE_SCENE_MEMORY_CAP
#define GJ_MAX_BYTES ((long)16 << 20)
#else
#define GJ_MAX_BYTES ((long)256 << 20)
#endif

typedef struct sc_polys gj;
#define gj_fail sc_polys_fail

/* ------------------------------------------------------------------------------------ */
/* GeoJSON objects                                                                       */

static const char *gj_type(struct json_object *o)
{
    struct json_object *t;
    if (!json_object_is_type(o, json_type_object) || !json_object_object_get_ex(o, "type", &t) ||
        !json_object_is_type(t, json_type_string))
        return NULL;
    return json_object_get_string(t);
}

/* One Polygon's coordinates (an array of rings): ring 0's positions handed to sc_polys_ring. */
static int gj_polygon(gj *g, struct json_object *rings, int feature, int part, double h, int fixed)
{
    char where[64];
    if (part < 0) snprintf(where, sizeof where, "feature %d", feature);
    else snprintf(where, sizeof where, "feature %d polygon %d", feature, part);
    if (!json_object_is_type(rings, json_type_array) || json_object_array_length(rings) < 1)
        return gj_fail(g, FLOE_EINVAL, "%s: a Polygon's coordinates must be an array of rings (arrays of [x, y])",
                       where);
    if (json_object_array_length(rings) > 1)
        return gj_fail(g, FLOE_EINVAL, "%s: holes are not supported: ring 1 is an interior ring (a floe with a hole "
                       "is not modelled yet)", where);
    struct json_object *ring = json_object_array_get_idx(rings, 0);
    if (!json_object_is_type(ring, json_type_array))
        return gj_fail(g, FLOE_EINVAL, "%s: ring 0 must be an array of [x, y] positions", where);
    size_t cnt = json_object_array_length(ring);
    double *raw = malloc((cnt + 1) * 2 * sizeof *raw);
    if (!raw) return gj_fail(g, FLOE_ENOMEM, "out of memory");
    for (size_t k = 0; k < cnt; k++) {
        struct json_object *pt = json_object_array_get_idx(ring, k);
        int ok = json_object_is_type(pt, json_type_array) && json_object_array_length(pt) >= 2;
        for (int a = 0; a < 2 && ok; a++) {
            struct json_object *v = json_object_array_get_idx(pt, (size_t)a);
            ok = json_object_is_type(v, json_type_double) || json_object_is_type(v, json_type_int);
            if (ok) raw[2 * k + a] = json_object_get_double(v);
        }
        if (!ok) {
            free(raw);
            return gj_fail(g, FLOE_EINVAL, "%s: ring 0 point %zu must be a position [x, y] of numbers (projected "
                           "metres)", where, k);
        }
    }
    int rc = sc_polys_ring(g, feature, part, raw, (long)cnt, h, fixed);
    free(raw);
    return rc;
}

/* A geometry: a Polygon or a MultiPolygon */
static int gj_geometry(gj *g, struct json_object *geom, int feature, double h, int fixed)
{
    const char *t = gj_type(geom);
    struct json_object *c;
    if (!json_object_is_type(geom, json_type_object))
        return gj_fail(g, FLOE_EINVAL, "feature %d: geometry must be a Polygon or MultiPolygon object, got %s", feature,
                       json_type_to_name(json_object_get_type(geom)));
    if (!t || (strcmp(t, "Polygon") && strcmp(t, "MultiPolygon")))
        return gj_fail(g, FLOE_EINVAL, "feature %d: geometry of type %s%s%s: expected a Polygon or MultiPolygon",
                       feature, t ? "\"" : "", t ? t : "(none)", t ? "\"" : "");
    if (!json_object_object_get_ex(geom, "coordinates", &c))
        return gj_fail(g, FLOE_EINVAL, "feature %d: the %s has no coordinates", feature, t);
    if (t[0] == 'P') return gj_polygon(g, c, feature, -1, h, fixed);
    if (!json_object_is_type(c, json_type_array))
        return gj_fail(g, FLOE_EINVAL, "feature %d: a MultiPolygon's coordinates must be an array of polygons",
                       feature);
    size_t np = json_object_array_length(c);
    if (np == 0) return gj_fail(g, FLOE_EINVAL, "feature %d: the MultiPolygon is empty", feature);
    for (size_t k = 0; k < np; k++)
        FLOE_TRY(gj_polygon(g, json_object_array_get_idx(c, k), feature, (int)k, h, fixed));
    return FLOE_OK;
}

/* A Feature: its properties (thickness, fixed) and its geometry */
static int gj_feature(gj *g, struct json_object *f, int k)
{
    const char *t = gj_type(f);
    if (!t || strcmp(t, "Feature"))
        return gj_fail(g, FLOE_EINVAL, "feature %d: expected an object of type \"Feature\", got %s%s%s", k,
                       t ? "\"" : "", t ? t : json_type_to_name(json_object_get_type(f)), t ? "\"" : "");
    double h = sc_polys_thickness(g);
    int fixed = -1;
    struct json_object *pr, *v, *geom;
    if (json_object_object_get_ex(f, "properties", &pr) && pr) {
        if (!json_object_is_type(pr, json_type_object))
            return gj_fail(g, FLOE_EINVAL, "feature %d: properties must be an object or null", k);
        if (json_object_object_get_ex(pr, "thickness", &v)) {
            if (!json_object_is_type(v, json_type_double) && !json_object_is_type(v, json_type_int))
                return gj_fail(g, FLOE_EINVAL, "feature %d: properties.thickness must be a number (m), got %s", k,
                               json_type_to_name(json_object_get_type(v)));
            h = json_object_get_double(v);
            if (!(h > 0) || !isfinite(h))
                return gj_fail(g, FLOE_EINVAL, "feature %d: properties.thickness must be > 0 and finite (m), got %g", k,
                               h);
        }
        if (json_object_object_get_ex(pr, "fixed", &v)) {
            if (!json_object_is_type(v, json_type_boolean))
                return gj_fail(g, FLOE_EINVAL, "feature %d: properties.fixed must be true or false, got %s", k,
                               json_type_to_name(json_object_get_type(v)));
            fixed = json_object_get_boolean(v) ? 1 : 0;
        }
    }
    if (!json_object_object_get_ex(f, "geometry", &geom) || !geom)
        return gj_fail(g, FLOE_EINVAL, "feature %d has no geometry (null): a floe needs a Polygon or MultiPolygon", k);
    return gj_geometry(g, geom, k, h, fixed);
}

/* line and column (1-based) of a byte offset */
static void gj_line_col(const char *text, long off, int *line, int *col)
{
    *line = 1;
    long bol = 0;
    for (long i = 0; i < off; i++)
        if (text[i] == '\n') {
            (*line)++;
            bol = i + 1;
        }
    *col = (int)(off - bol) + 1;
}

/* Read and parse the file (strict JSON, UTF-8), then every polygon of it. */
static int gj_read(gj *g, const char *path)
{
    struct stat st;
    FILE *fp = NULL;
    if (stat(path, &st) != 0 || !(fp = fopen(path, "rb")))
        return gj_fail(g, FLOE_EIO, "cannot read %s: %s", path, strerror(errno));
    if (!S_ISREG(st.st_mode)) {
        fclose(fp);
        return gj_fail(g, FLOE_EIO, "cannot read %s: not a regular file", path);
    }
    if (st.st_size > GJ_MAX_BYTES) {
        fclose(fp);
        return gj_fail(g, FLOE_EINVAL, "the file is %.3g MB, more than %ld MB", (double)st.st_size / 1e6,
                       GJ_MAX_BYTES >> 20);
    }
    char *text = malloc((size_t)st.st_size + 1);
    size_t len = text ? fread(text, 1, (size_t)st.st_size, fp) : 0;
    int bad = !text || ferror(fp);
    fclose(fp);
    if (bad) {
        free(text);
        return text ? gj_fail(g, FLOE_EIO, "cannot read %s: read error", path) : gj_fail(g, FLOE_ENOMEM, "out of memory");
    }
    text[len] = 0;
    struct json_tokener *tok = json_tokener_new();
    if (!tok) {
        free(text);
        return gj_fail(g, FLOE_ENOMEM, "out of memory");
    }
    json_tokener_set_flags(tok, JSON_TOKENER_STRICT | JSON_TOKENER_VALIDATE_UTF8);
    struct json_object *root = json_tokener_parse_ex(tok, text, (int)len);
    enum json_tokener_error je = json_tokener_get_error(tok);
    int rc = FLOE_OK;
    if (!root) {
        long off = je == json_tokener_continue ? (long)len : (long)json_tokener_get_parse_end(tok);
        int line, col;
        gj_line_col(text, off, &line, &col);
        /* the message names the file itself: sc_fail's position is the scene's */
        rc = sc_polys_fail_at(g, FLOE_EPARSE, line, col, "invalid JSON: %s",
                              je == json_tokener_continue ? "unexpected end of data" : json_tokener_error_desc(je));
    }
    json_tokener_free(tok);
    free(text);
    if (rc) return rc;
    const char *t = gj_type(root);
    if (t && !strcmp(t, "FeatureCollection")) {
        struct json_object *fs;
        if (!json_object_object_get_ex(root, "features", &fs) || !json_object_is_type(fs, json_type_array))
            rc = gj_fail(g, FLOE_EINVAL, "the FeatureCollection has no \"features\" array");
        size_t nf = rc ? 0 : json_object_array_length(fs);
        if (!rc && nf == 0) rc = gj_fail(g, FLOE_EINVAL, "the FeatureCollection has no features");
        for (size_t k = 0; k < nf && !rc; k++) rc = gj_feature(g, json_object_array_get_idx(fs, k), (int)k);
    } else if (t && !strcmp(t, "Feature")) {
        rc = gj_feature(g, root, 0);
    } else if (t && (!strcmp(t, "Polygon") || !strcmp(t, "MultiPolygon"))) {
        rc = gj_geometry(g, root, 0, sc_polys_thickness(g), -1);
    } else {
        rc = gj_fail(g, FLOE_EINVAL, "feature 0: the top level is %s%s%s: expected a GeoJSON FeatureCollection, "
                     "Feature, Polygon or MultiPolygon", t ? "a \"" : "", t ? t : "not a GeoJSON object",
                     t ? "\"" : "");
    }
    json_object_put(root);
    return rc;
}

int sc_polygons_file(sc *s, struct fy_node *e, int entry, const char *what)
{
    static const char *const keys[] = {"polygons_file", "material", "thickness", "velocity", "motion", "name", NULL};
    sc_map m;
    FLOE_TRY(sc_map_open(s, e, e, what, keys, &m));
    const char *file;
    struct fy_node *fat;
    FLOE_TRY(sc_str(s, &m, "polygons_file", 1, NULL, &file, &fat));
    if (s->dim != 2)
        return sc_fail(s, FLOE_EINVAL, fat, "%s.polygons_file: polygons are 2D floes (dimension: 2)", what);
    double h = 0;
    if (sc_has(&m, "thickness")) {
        FLOE_TRY(sc_num(s, &m, "thickness", 1, 0, &h));
        if (!(h > 0)) return sc_range(s, &m, "thickness", "> 0 (m)", h);
    }
    int mat, mo;
    double v[3];
    FLOE_TRY(sc_floe_entry(s, &m, entry, what, &mat, v, &mo));
    /* relative paths are relative to the scene file (as a mesh's file) */
    char path[1024], fwhat[160];
    const char *slash = s->path ? strrchr(s->path, '/') : NULL;
    if (file[0] != '/' && slash) snprintf(path, sizeof path, "%.*s/%s", (int)(slash - s->path), s->path, file);
    else snprintf(path, sizeof path, "%s", file);
    snprintf(fwhat, sizeof fwhat, "%s.polygons_file", what);
    gj *g = sc_polys_create(s, fat, fwhat, file, h);
    if (!g) return sc_fail(s, FLOE_ENOMEM, fat, "%s: out of memory", fwhat);
    size_t len = strlen(path);
    int shp = len > 4 && !strcasecmp(path + len - 4, ".shp");
    int rc = shp ? sc_shapefile_read(g, path) : gj_read(g, path);
    if (!rc) rc = sc_polys_build(g, mat, v, mo, entry);
    sc_polys_destroy(g);
    return rc;
}
