/* scene_shapefile.c - floes, coastlines and islands of a polygons_file entry read from an ESRI
 * shapefile (PATH ending in .shp; docs/sea-ice.md, "Floes from shapefiles") through
 * shapelib (Debian libshp-dev) when floe is built with FLOE_WITH_SHAPELIB. The reader only
 * hands rings over: scene_geojson.c checks them and builds the bodies, as for GeoJSON.
 *
 * ESRI Shapefile Technical Description (ESRI White Paper, July 1998): a Polygon (shape type 5,
 * PolygonZ 15, PolygonM 25; Z and M are ignored) is a set of parts, each a closed ring; "the
 * order of vertices ... defines which side of a polygon is the inside": outer rings run
 * clockwise, holes counter-clockwise. A shape whose parts all run the same way is read as
 * that many outer rings (writers that ignore the rule); when both ways are there, the
 * counter-clockwise parts are holes, which are refused (not modelled yet). The attribute
 * table (the .dbf, dBASE) may carry `thickness` (a number, m) and `fixed` (a logical, or an
 * integer 0/1) per shape, as a GeoJSON Feature's properties; an empty value is as absent.
 * Shape k (0-based, as GeoJSON features) is named "shape k", its part j "shape k part j". */
#include "scene_read.h"

#ifdef FLOE_HAVE_SHAPELIB

#include <ctype.h>
#include <math.h>
#include <shapefil.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* shapelib reports errors through its hooks' Error: kept here for the message */
static _Thread_local char shp_error[512];

static void shp_hook_error(const char *message)
{
    snprintf(shp_error, sizeof shp_error, "%s", message);
    char *gdal = strstr(shp_error, " Set SHAPE_RESTORE_SHX"); /* a GDAL option, not floe's */
    if (gdal) *gdal = 0;
}

static void shp_hooks(SAHooks *h)
{
    SASetupDefaultHooks(h);
    h->Error = shp_hook_error;
    shp_error[0] = 0;
}

/* path with its 3-letter extension replaced by ext (".dbf") */
static void shp_sibling(char *buf, size_t len, const char *path, const char *ext)
{
    snprintf(buf, len, "%.*s%s", (int)(strlen(path) - 4), path, ext);
}

static int shp_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* A .prj (the coordinate system, OGC WKT) that says GEOGCS: longitude and latitude in
 * degrees, which floe does not project. */
static int shp_geographic(const char *path)
{
    char prj[1100];
    int geo = 0;
    for (int k = 0; k < 2 && !geo; k++) {
        shp_sibling(prj, sizeof prj, path, k ? ".PRJ" : ".prj");
        FILE *f = fopen(prj, "rb");
        if (!f) continue;
        char head[32] = "";
        size_t n = fread(head, 1, sizeof head - 1, f);
        fclose(f);
        head[n] = 0;
        const char *h = head;
        while (isspace((unsigned char)*h)) h++;
        geo = !strncasecmp(h, "GEOGCS", 6);
    }
    return geo;
}

/* the attributes of a shape: thickness (m; the entry's when absent or empty) and fixed */
typedef struct shp_fields {
    DBFHandle dbf;
    int ih, ifx;          /* field indices (-1: none) */
    DBFFieldType th, tf;  /* their types */
} shp_fields;

static int shp_open_fields(sc_polys *g, const char *path, int nshape, shp_fields *f)
{
    f->dbf = NULL;
    f->ih = f->ifx = -1;
    char dbf[1100], DBF[1100];
    shp_sibling(dbf, sizeof dbf, path, ".dbf");
    shp_sibling(DBF, sizeof DBF, path, ".DBF");
    if (!shp_exists(dbf) && !shp_exists(DBF)) return FLOE_OK; /* no attributes */
    SAHooks h;
    shp_hooks(&h);
    f->dbf = DBFOpenLL(path, "rb", &h);
    if (!f->dbf)
        return sc_polys_fail(g, FLOE_EIO, "cannot read its attribute table %s: %s", shp_exists(dbf) ? dbf : DBF,
                             shp_error[0] ? shp_error : "not a dBASE file");
    int nrec = DBFGetRecordCount(f->dbf);
    if (nrec != nshape)
        return sc_polys_fail(g, FLOE_EINVAL, "the attribute table has %d records for %d shapes", nrec, nshape);
    f->ih = DBFGetFieldIndex(f->dbf, "thickness");
    f->ifx = DBFGetFieldIndex(f->dbf, "fixed");
    int w, d;
    char name[XBASE_FLDNAME_LEN_READ + 1];
    if (f->ih >= 0) {
        f->th = DBFGetFieldInfo(f->dbf, f->ih, name, &w, &d);
        if (f->th != FTDouble && f->th != FTInteger)
            return sc_polys_fail(g, FLOE_EINVAL, "the attribute thickness must be a number field (dBASE N or F), "
                                 "it is of type '%c'", DBFGetNativeFieldType(f->dbf, f->ih));
    }
    if (f->ifx >= 0) {
        f->tf = DBFGetFieldInfo(f->dbf, f->ifx, name, &w, &d);
        if (f->tf != FTLogical && f->tf != FTInteger)
            return sc_polys_fail(g, FLOE_EINVAL, "the attribute fixed must be a logical field (dBASE L: T or F) or an "
                                 "integer 0 or 1, it is of type '%c'", DBFGetNativeFieldType(f->dbf, f->ifx));
    }
    return FLOE_OK;
}

static int shp_attributes(sc_polys *g, const shp_fields *f, int k, double *h, int *fixed)
{
    *h = sc_polys_thickness(g);
    *fixed = -1;
    if (f->ih >= 0 && !DBFIsAttributeNULL(f->dbf, k, f->ih)) {
        *h = DBFReadDoubleAttribute(f->dbf, k, f->ih);
        if (!(*h > 0) || !isfinite(*h))
            return sc_polys_fail(g, FLOE_EINVAL, "shape %d: the attribute thickness must be > 0 and finite (m), got %g",
                                 k, *h);
    }
    if (f->ifx >= 0 && !DBFIsAttributeNULL(f->dbf, k, f->ifx)) {
        if (f->tf == FTLogical) {
            const char *v = DBFReadLogicalAttribute(f->dbf, k, f->ifx);
            char c = v ? (char)toupper((unsigned char)v[0]) : '?';
            *fixed = c == 'T' || c == 'Y' ? 1 : c == 'F' || c == 'N' ? 0 : -2;
            if (*fixed == -2)
                return sc_polys_fail(g, FLOE_EINVAL, "shape %d: the attribute fixed must be T or F, got '%s'", k,
                                     v ? v : "");
        } else {
            double x = DBFReadDoubleAttribute(f->dbf, k, f->ifx);
            const char *v = DBFReadStringAttribute(f->dbf, k, f->ifx);
            if (x != 0 && x != 1)
                return sc_polys_fail(g, FLOE_EINVAL, "shape %d: the attribute fixed must be 0 or 1 (or a logical T "
                                     "or F), got %s", k, v ? v : "?");
            *fixed = (int)x;
        }
    }
    return FLOE_OK;
}

/* twice the signed area of points [a, b) of a shape (> 0 counter-clockwise) */
static double shp_area2(const SHPObject *o, int a, int b)
{
    double s = 0;
    for (int i = a + 1; i + 1 < b; i++)
        s += (o->padfX[i] - o->padfX[a]) * (o->padfY[i + 1] - o->padfY[a]) -
             (o->padfY[i] - o->padfY[a]) * (o->padfX[i + 1] - o->padfX[a]);
    return s;
}

/* the parts of shape k: outer rings to sc_polys_ring, holes refused */
static int shp_shape(sc_polys *g, const SHPObject *o, int k, double h, int fixed)
{
    if (o->nSHPType == SHPT_NULL || o->nVertices == 0 || o->nParts == 0)
        return sc_polys_fail(g, FLOE_EINVAL, "shape %d is a null shape (no geometry): a floe needs a polygon", k);
    int np = o->nParts, cw = 0, ccw = 0;
    for (int j = 0; j < np; j++) {
        int a = o->panPartStart[j], b = j + 1 < np ? o->panPartStart[j + 1] : o->nVertices;
        double s = a >= 0 && b <= o->nVertices && a < b ? shp_area2(o, a, b) : 0;
        cw += s < 0;
        ccw += s > 0;
    }
    double *xy = malloc((size_t)o->nVertices * 2 * sizeof *xy);
    if (!xy) return sc_polys_fail(g, FLOE_ENOMEM, "out of memory");
    int rc = FLOE_OK;
    for (int j = 0; j < np && !rc; j++) {
        int a = o->panPartStart[j], b = j + 1 < np ? o->panPartStart[j + 1] : o->nVertices;
        if (a < 0 || b > o->nVertices || a > b) {
            rc = sc_polys_fail(g, FLOE_EINVAL, "shape %d: part %d has a bad start (%d of %d points)", k, j, a,
                               o->nVertices);
            break;
        }
        if (cw && ccw && shp_area2(o, a, b) > 0) {
            rc = sc_polys_fail(g, FLOE_EINVAL, "shape %d: holes are not supported: part %d runs counter-clockwise, "
                               "an interior ring in a shapefile (a floe with a hole is not modelled yet)", k, j);
            break;
        }
        for (int i = a; i < b; i++) {
            xy[2 * (i - a)] = o->padfX[i];
            xy[2 * (i - a) + 1] = o->padfY[i];
        }
        rc = sc_polys_ring(g, k, np > 1 ? j : -1, xy, b - a, h, fixed);
    }
    free(xy);
    return rc;
}

int sc_shapefile_read(sc_polys *g, const char *path)
{
    sc_polys_names(g, "shape", "part", "the ring");
    struct stat st;
    if (stat(path, &st) != 0) return sc_polys_fail(g, FLOE_EIO, "cannot read %s: %s", path, strerror(errno));
    if (!S_ISREG(st.st_mode)) return sc_polys_fail(g, FLOE_EIO, "cannot read %s: not a regular file", path);
    if (shp_geographic(path))
        return sc_polys_fail(g, FLOE_EINVAL, "its .prj gives longitude and latitude (GEOGCS): floe reads projected "
                             "metres (x east, y north): project the shapefile first");
    SAHooks hk;
    shp_hooks(&hk);
    SHPHandle shp = SHPOpenLL(path, "rb", &hk);
    if (!shp)
        return sc_polys_fail(g, FLOE_EIO, "cannot read %s as a shapefile (it needs its .shx index beside it): %s",
                             path, shp_error[0] ? shp_error : "not a shapefile");
    int n = 0, type = 0;
    double lo[4], hi[4];
    SHPGetInfo(shp, &n, &type, lo, hi);
    shp_fields f = {0};
    int rc = FLOE_OK;
    if (type != SHPT_POLYGON && type != SHPT_POLYGONZ && type != SHPT_POLYGONM)
        rc = sc_polys_fail(g, FLOE_EINVAL, "the shapefile holds %s shapes: expected polygons (Polygon, PolygonZ or "
                           "PolygonM)", SHPTypeName(type));
    else if (n <= 0)
        rc = sc_polys_fail(g, FLOE_EINVAL, "the shapefile has no shapes");
    if (!rc) rc = shp_open_fields(g, path, n, &f);
    for (int k = 0; k < n && !rc; k++) {
        double h;
        int fixed;
        rc = shp_attributes(g, &f, k, &h, &fixed);
        if (rc) break;
        shp_error[0] = 0;
        SHPObject *o = SHPReadObject(shp, k);
        if (!o) {
            rc = sc_polys_fail(g, FLOE_EINVAL, "shape %d cannot be read: %s", k,
                               shp_error[0] ? shp_error : "a damaged file?");
            break;
        }
        rc = shp_shape(g, o, k, h, fixed);
        SHPDestroyObject(o);
    }
    if (f.dbf) DBFClose(f.dbf);
    SHPClose(shp);
    return rc;
}

#else /* without shapelib */

int sc_shapefile_read(sc_polys *g, const char *path)
{
    (void)path;
    return sc_polys_fail(g, FLOE_ENOTSUP, "reading shapefiles needs floe built with FLOE_WITH_SHAPELIB (configure with "
                         "-DFLOE_WITH_SHAPELIB=ON; Debian package libshp-dev)");
}

#endif
