/* scene_geojson.c - a body entry `{polygons_file: PATH, material, thickness, motion, velocity,
 * name}`: 2D floes, coastlines and islands read from a GeoJSON file (RFC 7946) of polygons,
 * parsed with json-c (docs/sea-ice.md, "Floes from GeoJSON"; docs/scene-format.md).
 *
 * Every Polygon, and every polygon of a MultiPolygon, of the FeatureCollection, Feature or
 * bare geometry becomes one body: a convex ring a `polygon` geometry placed at its centroid
 * frame (as a scene `polygon` body written at its centroid), a non-convex one a compound of
 * convex pieces: an ear-clipping triangulation (Meisters' two-ears theorem) merged into
 * convex polygons by Hertel and Mehlhorn's rule (drop a diagonal when both its ends stay
 * convex; at most four times the fewest pieces). Coordinates are projected metres (x, y).
 * A Feature's properties may set `thickness` (m) and `fixed` (a coastline or island).
 *
 * Refused, naming the file and the feature: an unreadable file, invalid JSON (json-c's
 * message at its line and column), other GeoJSON types, rings with fewer than 3 distinct
 * points, non-finite coordinates, self-intersecting rings (a sweep over the edges' boxes,
 * then every pair of non-adjacent edges that may meet), rings of zero area, holes, and
 * polygons that overlap each other (boxes first, then the separating-axis test between
 * their convex pieces: floes that only touch are accepted). */
#include "scene_internal.h"

#include <json.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* the largest file read (json-c keeps every number as an object of its own) */
#ifdef FLOE_SCENE_MEMORY_CAP
#define GJ_MAX_BYTES ((long)16 << 20)
#else
#define GJ_MAX_BYTES ((long)256 << 20)
#endif
/* the most points in one ring (the ear clipping is quadratic in the worst case) */
#define GJ_MAX_RING 200000
/* collinear and zero-area tests: |cross| <= GJ_FLAT L^2, L the ring's box diagonal (as
 * floe_polygon_create); overlaps shallower than GJ_TOUCH x the larger polygon are touches */
#define GJ_FLAT 1e-12
#define GJ_TOUCH 1e-9

typedef struct gj_poly {
    int feature, part;   /* feature index; index in its MultiPolygon (-1: a Polygon) */
    int n;               /* points as written, the closing point and repeats dropped */
    double *xy;          /* 2 n */
    double h;            /* thickness (0: none) */
    int fixed;           /* the `fixed` property: -1 none, 0 false, 1 true */
    int convex;
    double lo[2], hi[2], size; /* bounding box and its diagonal */
    int npiece;          /* convex pieces (counter-clockwise): piece k is points */
    int *start;          /* start[k] .. start[k + 1] - 1 of pxy */
    double *pxy;
} gj_poly;

typedef struct gj {
    sc *s;
    struct fy_node *at;  /* the polygons_file value: every message is reported there */
    char what[160];      /* "bodies[2].polygons_file" */
    const char *file;    /* the file as the scene names it */
    double h;            /* the entry's thickness (0: none) */
    gj_poly *p;
    int n, cap;
} gj;

static int gj_fail(gj *g, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static int gj_fail(gj *g, int code, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return sc_fail(g->s, code, g->at, "%s: %s: %s", g->what, g->file, msg);
}

/* "feature 3" or "feature 3 polygon 1" */
static const char *gj_name(char *buf, size_t len, int feature, int part)
{
    if (part < 0) snprintf(buf, len, "feature %d", feature);
    else snprintf(buf, len, "feature %d polygon %d", feature, part);
    return buf;
}

static void gj_free(gj *g)
{
    for (int i = 0; i < g->n; i++) {
        free(g->p[i].xy);
        free(g->p[i].start);
        free(g->p[i].pxy);
    }
    free(g->p);
}

/* ------------------------------------------------------------------------------------ */
/* Planar predicates                                                                     */

/* twice the signed area of (a, b, c): > 0 counter-clockwise */
static double gj_orient(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* p on the segment ab, given that the three are collinear */
static int gj_within(const double *a, const double *b, const double *p)
{
    return p[0] >= fmin(a[0], b[0]) && p[0] <= fmax(a[0], b[0]) && p[1] >= fmin(a[1], b[1]) &&
           p[1] <= fmax(a[1], b[1]);
}

/* the closed segments ab and cd share a point */
static int gj_segments_meet(const double *a, const double *b, const double *c, const double *d)
{
    double d1 = gj_orient(c, d, a), d2 = gj_orient(c, d, b), d3 = gj_orient(a, b, c), d4 = gj_orient(a, b, d);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 1;
    return (d1 == 0 && gj_within(c, d, a)) || (d2 == 0 && gj_within(c, d, b)) || (d3 == 0 && gj_within(a, b, c)) ||
           (d4 == 0 && gj_within(a, b, d));
}

/* twice the signed area of a ring (about its first point, for accuracy) */
static double gj_area2(const double *xy, int n)
{
    double a = 0;
    for (int i = 1; i + 1 < n; i++) a += gj_orient(xy, xy + 2 * i, xy + 2 * (i + 1));
    return a;
}

/* ------------------------------------------------------------------------------------ */
/* Rings                                                                                 */

typedef struct gj_edge { double xmin, xmax; int i; } gj_edge;

static int gj_edge_cmp(const void *a, const void *b)
{
    const gj_edge *x = a, *y = b;
    return x->xmin < y->xmin ? -1 : x->xmin > y->xmin ? 1 : x->i - y->i;
}

/* Two non-adjacent edges that meet, by a sweep along x over the edges' boxes: 0 when
 * none, else 1 with the edges in *ea < *eb. */
static int gj_self_crossing(const double *xy, int n, int *ea, int *eb, int *oom)
{
    gj_edge *e = malloc((size_t)n * sizeof *e);
    *oom = !e;
    if (!e) return 0;
    for (int i = 0; i < n; i++) {
        const double *a = xy + 2 * i, *b = xy + 2 * ((i + 1) % n);
        e[i] = (gj_edge){fmin(a[0], b[0]), fmax(a[0], b[0]), i};
    }
    qsort(e, (size_t)n, sizeof *e, gj_edge_cmp);
    int found = 0;
    for (int k = 0; k < n && !found; k++) {
        int i = e[k].i;
        const double *a = xy + 2 * i, *b = xy + 2 * ((i + 1) % n);
        for (int m = k + 1; m < n && e[m].xmin <= e[k].xmax; m++) {
            int j = e[m].i;
            if (abs(i - j) == 1 || abs(i - j) == n - 1) continue; /* adjacent: they share a point */
            const double *c = xy + 2 * j, *d = xy + 2 * ((j + 1) % n);
            if (fmax(c[1], d[1]) < fmin(a[1], b[1]) || fmin(c[1], d[1]) > fmax(a[1], b[1])) continue;
            if (gj_segments_meet(a, b, c, d)) {
                *ea = i < j ? i : j;
                *eb = i < j ? j : i;
                found = 1;
                break;
            }
        }
    }
    free(e);
    return found;
}

/* Ring 0 of a polygon: its points (x, y of each position; the closing point and repeats
 * dropped) into *xy, the index in the file of each kept point into *orig. */
static int gj_read_ring(gj *g, struct json_object *ring, const char *where, double **xy, int **orig, int *n)
{
    *xy = NULL;
    *orig = NULL;
    *n = 0;
    if (!json_object_is_type(ring, json_type_array))
        return gj_fail(g, FLOE_EINVAL, "%s: ring 0 must be an array of [x, y] positions", where);
    size_t cnt = json_object_array_length(ring);
    if (cnt > GJ_MAX_RING)
        return gj_fail(g, FLOE_EINVAL, "%s: ring 0 has %zu points, more than %d", where, cnt, GJ_MAX_RING);
    double *x = malloc((cnt + 1) * 2 * sizeof *x);
    int *o = malloc((cnt + 1) * sizeof *o);
    if (!x || !o) {
        free(x);
        free(o);
        return gj_fail(g, FLOE_ENOMEM, "out of memory");
    }
    int m = 0;
    for (size_t k = 0; k < cnt; k++) {
        struct json_object *pt = json_object_array_get_idx(ring, k);
        double c[2];
        int ok = json_object_is_type(pt, json_type_array) && json_object_array_length(pt) >= 2;
        for (int a = 0; a < 2 && ok; a++) {
            struct json_object *v = json_object_array_get_idx(pt, (size_t)a);
            ok = json_object_is_type(v, json_type_double) || json_object_is_type(v, json_type_int);
            if (ok) c[a] = json_object_get_double(v);
        }
        int rc = FLOE_OK;
        if (!ok)
            rc = gj_fail(g, FLOE_EINVAL, "%s: ring 0 point %zu must be a position [x, y] of numbers (projected "
                         "metres)", where, k);
        else if (!isfinite(c[0]) || !isfinite(c[1]))
            rc = gj_fail(g, FLOE_EINVAL, "%s: ring 0 point %zu is not finite (%g, %g)", where, k, c[0], c[1]);
        if (rc) {
            free(x);
            free(o);
            return rc;
        }
        if (m > 0 && c[0] == x[2 * m - 2] && c[1] == x[2 * m - 1]) continue; /* a repeat */
        x[2 * m] = c[0];
        x[2 * m + 1] = c[1];
        o[m++] = (int)k;
    }
    if (m > 1 && x[0] == x[2 * m - 2] && x[1] == x[2 * m - 1]) m--; /* the closing point */
    if (m < 3) {
        free(x);
        free(o);
        return gj_fail(g, FLOE_EINVAL, "%s: ring 0 has %d distinct points (a polygon needs at least 3)", where, m);
    }
    *xy = x;
    *orig = o;
    *n = m;
    return FLOE_OK;
}

/* A simple ring of non-zero area: no two non-adjacent edges meet, no adjacent ones fold
 * back on each other. */
static int gj_check_ring(gj *g, const char *where, const double *xy, const int *orig, int n, double L)
{
    int ea, eb, oom;
    if (gj_self_crossing(xy, n, &ea, &eb, &oom))
        return gj_fail(g, FLOE_EINVAL, "%s: ring 0 is self-intersecting: the edge from point %d to point %d "
                       "meets the edge from point %d to point %d, near (%.17g, %.17g)", where, orig[ea],
                       orig[(ea + 1) % n], orig[eb], orig[(eb + 1) % n], xy[2 * eb], xy[2 * eb + 1]);
    if (oom) return gj_fail(g, FLOE_ENOMEM, "out of memory");
    if (!(fabs(gj_area2(xy, n)) > 2 * GJ_FLAT * L * L))
        return gj_fail(g, FLOE_EINVAL, "%s: ring 0 has zero area (its %d points are collinear)", where, n);
    for (int i = 0; i < n; i++) {
        const double *a = xy + 2 * ((i + n - 1) % n), *v = xy + 2 * i, *b = xy + 2 * ((i + 1) % n);
        double dot = (v[0] - a[0]) * (b[0] - v[0]) + (v[1] - a[1]) * (b[1] - v[1]);
        if (fabs(gj_orient(a, v, b)) <= GJ_FLAT * L * L && dot < 0)
            return gj_fail(g, FLOE_EINVAL, "%s: ring 0 is self-intersecting: it turns back on itself at point %d "
                           "(its two edges there overlap)", where, orig[i]);
    }
    return FLOE_OK;
}

/* ------------------------------------------------------------------------------------ */
/* Convex decomposition of a simple counter-clockwise polygon                            */

/* The points that start reflex, bucketed on a grid over the ring's box: an ear test looks
 * only in the cells its triangle's box covers. Clipping ears only makes reflex points
 * convex (the interior angles at the clipped ear's neighbours shrink), never the reverse,
 * so the grid is built once and stale entries are skipped by the reflex flag. */
typedef struct gj_grid {
    int g;               /* g x g cells */
    double lo[2], inv[2];
    int *first, *item;   /* cell c holds item[first[c] .. first[c + 1]) */
} gj_grid;

static int gj_cell(const gj_grid *gr, double x, int a)
{
    double c = (x - gr->lo[a]) * gr->inv[a];
    return c <= 0 ? 0 : c >= gr->g - 1 ? gr->g - 1 : (int)c;
}

static int gj_grid_build(gj_grid *gr, const double *xy, int n, const char *reflex)
{
    int r = 0;
    gr->lo[0] = gr->lo[1] = INFINITY;
    double hi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < n; i++) {
        r += reflex[i];
        for (int a = 0; a < 2; a++) {
            gr->lo[a] = fmin(gr->lo[a], xy[2 * i + a]);
            hi[a] = fmax(hi[a], xy[2 * i + a]);
        }
    }
    gr->g = (int)fmin(1024, fmax(1, ceil(sqrt((double)r))));
    for (int a = 0; a < 2; a++) gr->inv[a] = hi[a] > gr->lo[a] ? gr->g / (hi[a] - gr->lo[a]) : 0;
    gr->first = calloc((size_t)gr->g * gr->g + 1, sizeof *gr->first);
    gr->item = malloc((size_t)(r > 0 ? r : 1) * sizeof *gr->item);
    if (!gr->first || !gr->item) return -2;
    for (int i = 0; i < n; i++)
        if (reflex[i]) gr->first[gj_cell(gr, xy[2 * i + 1], 1) * gr->g + gj_cell(gr, xy[2 * i], 0) + 1]++;
    for (int c = 0; c < gr->g * gr->g; c++) gr->first[c + 1] += gr->first[c];
    int *fill = malloc((size_t)gr->g * gr->g * sizeof *fill);
    if (!fill) return -2;
    memcpy(fill, gr->first, (size_t)gr->g * gr->g * sizeof *fill);
    for (int i = 0; i < n; i++)
        if (reflex[i]) gr->item[fill[gj_cell(gr, xy[2 * i + 1], 1) * gr->g + gj_cell(gr, xy[2 * i], 0)]++] = i;
    free(fill);
    return 0;
}

/* a reflex point other than a, v, b in the closed triangle (a, v, b) */
static int gj_ear_blocked(const gj_grid *gr, const double *xy, const char *reflex, int a, int v, int b)
{
    const double *A = xy + 2 * a, *V = xy + 2 * v, *B = xy + 2 * b;
    int c0 = gj_cell(gr, fmin(A[0], fmin(V[0], B[0])), 0), c1 = gj_cell(gr, fmax(A[0], fmax(V[0], B[0])), 0);
    int r0 = gj_cell(gr, fmin(A[1], fmin(V[1], B[1])), 1), r1 = gj_cell(gr, fmax(A[1], fmax(V[1], B[1])), 1);
    for (int row = r0; row <= r1; row++)
        for (int col = c0; col <= c1; col++) {
            int c = row * gr->g + col;
            for (int q = gr->first[c]; q < gr->first[c + 1]; q++) {
                int k = gr->item[q];
                if (!reflex[k] || k == a || k == v || k == b) continue;
                const double *P = xy + 2 * k;
                if (gj_orient(A, V, P) >= 0 && gj_orient(V, B, P) >= 0 && gj_orient(B, A, P) >= 0) return 1;
            }
        }
    return 0;
}

/* Ear clipping: n - 2 triangles (3 point indices each, counter-clockwise) into tri; 0, -1
 * when no ear is found (a ring that is not simple to round-off), -2 out of memory.
 * Collinear points must have been removed. Only reflex points can lie in an ear. */
static int gj_ear_clip(const double *xy, int n, int *tri)
{
    int *prev = malloc((size_t)n * sizeof *prev), *next = malloc((size_t)n * sizeof *next);
    char *reflex = malloc((size_t)n);
    gj_grid gr = {0};
    int rc = prev && next && reflex ? 0 : -2;
    for (int i = 0; i < n && !rc; i++) {
        prev[i] = (i + n - 1) % n;
        next[i] = (i + 1) % n;
        reflex[i] = gj_orient(xy + 2 * prev[i], xy + 2 * i, xy + 2 * next[i]) <= 0;
    }
    if (!rc) rc = gj_grid_build(&gr, xy, n, reflex);
    int left = n, nt = 0, v = 0, tries = 0;
    while (!rc && left > 3) {
        int a = prev[v], b = next[v];
        if (reflex[v] || gj_ear_blocked(&gr, xy, reflex, a, v, b)) {
            v = b;
            if (++tries > left) rc = -1;
            continue;
        }
        tri[3 * nt] = a;
        tri[3 * nt + 1] = v;
        tri[3 * nt + 2] = b;
        nt++;
        next[a] = b;
        prev[b] = a;
        left--;
        reflex[a] = reflex[a] && gj_orient(xy + 2 * prev[a], xy + 2 * a, xy + 2 * b) <= 0;
        reflex[b] = reflex[b] && gj_orient(xy + 2 * a, xy + 2 * b, xy + 2 * next[b]) <= 0;
        v = a;
        tries = 0;
    }
    if (!rc) {
        tri[3 * nt] = prev[v];
        tri[3 * nt + 1] = v;
        tri[3 * nt + 2] = next[v];
    }
    free(prev);
    free(next);
    free(reflex);
    free(gr.first);
    free(gr.item);
    return rc;
}

typedef struct gj_diag { int lo, hi, t; } gj_diag; /* a triangle's edge lo-hi (lo < hi) */

static int gj_diag_cmp(const void *a, const void *b)
{
    const gj_diag *x = a, *y = b;
    return x->lo != y->lo ? x->lo - y->lo : x->hi != y->hi ? x->hi - y->hi : x->t - y->t;
}

static int gj_find_root(int *up, int t)
{
    while (up[t] != t) t = up[t] = up[up[t]];
    return t;
}

/* Hertel-Mehlhorn: the triangles merged across their diagonals while both ends of a
 * diagonal stay convex. Pieces as point cycles: piece k is cyc[k][0 .. len[k]). */
static int gj_merge(const double *xy, int n, const int *tri, int ***cyc_out, int **len_out, int *np_out)
{
    int nt = n - 2, rc = FLOE_ENOMEM;
    int **cyc = calloc((size_t)nt, sizeof *cyc), *len = calloc((size_t)nt, sizeof *len);
    int *up = malloc((size_t)nt * sizeof *up);
    gj_diag *d = malloc((size_t)nt * 3 * sizeof *d);
    if (!cyc || !len || !up || !d) goto done;
    for (int t = 0; t < nt; t++) {
        if (!(cyc[t] = malloc(3 * sizeof **cyc))) goto done;
        memcpy(cyc[t], tri + 3 * t, 3 * sizeof **cyc);
        len[t] = 3;
        up[t] = t;
        for (int k = 0; k < 3; k++) {
            int p = tri[3 * t + k], q = tri[3 * t + (k + 1) % 3];
            d[3 * t + k] = (gj_diag){p < q ? p : q, p < q ? q : p, t};
        }
    }
    qsort(d, (size_t)nt * 3, sizeof *d, gj_diag_cmp);
    for (int k = 0; k + 1 < 3 * nt; k++) {
        if (d[k].lo != d[k + 1].lo || d[k].hi != d[k + 1].hi) continue; /* a side of the polygon */
        int P = gj_find_root(up, d[k].t), Q = gj_find_root(up, d[k + 1].t);
        if (P == Q) continue;
        /* P runs u -> w along the diagonal, Q runs w -> u */
        int i = 0, j = 0, lp = len[P], lq = len[Q];
        while (i < lp && !((cyc[P][i] == d[k].lo || cyc[P][i] == d[k].hi) &&
                           (cyc[P][(i + 1) % lp] == d[k].lo || cyc[P][(i + 1) % lp] == d[k].hi)))
            i++;
        int u = cyc[P][i], w = cyc[P][(i + 1) % lp];
        while (j < lq && cyc[Q][j] != w) j++;
        if (i == lp || j == lq || cyc[Q][(j + 1) % lq] != u) continue; /* cannot happen */
        /* merged: P from w round to u, then Q after u round to before w */
        int pu = cyc[P][(i + lp - 1) % lp], nw = cyc[P][(i + 2) % lp];
        int qn = cyc[Q][(j + 2) % lq], qp = cyc[Q][(j + lq - 1) % lq];
        if (gj_orient(xy + 2 * pu, xy + 2 * u, xy + 2 * qn) < 0 || gj_orient(xy + 2 * qp, xy + 2 * w, xy + 2 * nw) < 0)
            continue; /* a reflex corner: keep the diagonal */
        int *m = malloc((size_t)(lp + lq - 2) * sizeof *m);
        if (!m) goto done;
        int L = 0;
        for (int a = 0; a < lp; a++) m[L++] = cyc[P][(i + 1 + a) % lp];
        for (int a = 2; a < lq; a++) m[L++] = cyc[Q][(j + a) % lq];
        free(cyc[P]);
        free(cyc[Q]);
        cyc[P] = m;
        cyc[Q] = NULL;
        len[P] = L;
        len[Q] = 0;
        up[Q] = P;
    }
    int np = 0;
    for (int t = 0; t < nt; t++)
        if (cyc[t]) {
            cyc[np] = cyc[t];
            len[np++] = len[t];
        }
    *cyc_out = cyc;
    *len_out = len;
    *np_out = np;
    cyc = NULL;
    len = NULL;
    rc = FLOE_OK;
done:
    if (cyc)
        for (int t = 0; t < nt; t++) free(cyc[t]);
    free(cyc);
    free(len);
    free(up);
    free(d);
    return rc;
}

/* The convex pieces of a polygon (counter-clockwise copy ccw of its points): itself when
 * convex, else its Hertel-Mehlhorn pieces. */
static int gj_pieces(gj *g, const char *where, gj_poly *p, double *ccw)
{
    int n = p->n;
    double L2 = p->size * p->size;
    p->convex = 1;
    for (int i = 0; i < n && p->convex; i++)
        if (gj_orient(ccw + 2 * ((i + n - 1) % n), ccw + 2 * i, ccw + 2 * ((i + 1) % n)) < -GJ_FLAT * L2) p->convex = 0;
    if (p->convex) {
        p->npiece = 1;
        p->pxy = ccw;
        p->start = malloc(2 * sizeof *p->start);
        if (!p->start) return gj_fail(g, FLOE_ENOMEM, "out of memory");
        p->start[0] = 0;
        p->start[1] = n;
        return FLOE_OK;
    }
    /* drop the points on a straight run (until none is left), then clip ears and merge */
    int m = n;
    for (int was = 0; was != m && m >= 3;) {
        was = m;
        m = 0;
        for (int i = 0; i < was; i++) {
            const double *a = m ? ccw + 2 * (m - 1) : ccw + 2 * (was - 1), *b = ccw + 2 * ((i + 1) % was);
            if (fabs(gj_orient(a, ccw + 2 * i, b)) <= GJ_FLAT * L2) continue;
            ccw[2 * m] = ccw[2 * i];
            ccw[2 * m + 1] = ccw[2 * i + 1];
            m++;
        }
    }
    int *tri = malloc((size_t)(m > 3 ? m - 2 : 1) * 3 * sizeof *tri);
    if (!tri) {
        free(ccw);
        return gj_fail(g, FLOE_ENOMEM, "out of memory");
    }
    int rc = m >= 3 ? gj_ear_clip(ccw, m, tri) : -1;
    int **cyc = NULL, *len = NULL, np = 0;
    if (!rc) rc = gj_merge(ccw, m, tri, &cyc, &len, &np) ? -2 : 0;
    free(tri);
    if (rc) {
        free(ccw);
        return rc == -2 ? gj_fail(g, FLOE_ENOMEM, "out of memory")
                        : gj_fail(g, FLOE_EINVAL, "%s: ring 0 could not be cut into triangles (not simple to "
                                  "round-off?)", where);
    }
    int tot = 0;
    for (int k = 0; k < np; k++) tot += len[k];
    p->npiece = np;
    p->start = malloc((size_t)(np + 1) * sizeof *p->start);
    p->pxy = malloc((size_t)tot * 2 * sizeof *p->pxy);
    if (p->start && p->pxy) {
        p->start[0] = 0;
        for (int k = 0; k < np; k++) {
            for (int a = 0; a < len[k]; a++) {
                p->pxy[2 * (p->start[k] + a)] = ccw[2 * cyc[k][a]];
                p->pxy[2 * (p->start[k] + a) + 1] = ccw[2 * cyc[k][a] + 1];
            }
            p->start[k + 1] = p->start[k] + len[k];
        }
    }
    for (int k = 0; k < np; k++) free(cyc[k]);
    free(cyc);
    free(len);
    free(ccw);
    if (!p->start || !p->pxy) return gj_fail(g, FLOE_ENOMEM, "out of memory");
    return FLOE_OK;
}

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

/* One Polygon's coordinates (an array of rings): checked, its pieces found, appended. */
static int gj_polygon(gj *g, struct json_object *rings, int feature, int part, double h, int fixed)
{
    char where[64];
    gj_name(where, sizeof where, feature, part);
    if (!json_object_is_type(rings, json_type_array) || json_object_array_length(rings) < 1)
        return gj_fail(g, FLOE_EINVAL, "%s: a Polygon's coordinates must be an array of rings (arrays of [x, y])",
                       where);
    if (json_object_array_length(rings) > 1)
        return gj_fail(g, FLOE_EINVAL, "%s: holes are not supported: ring 1 is an interior ring (a floe with a hole "
                       "is not modelled yet)", where);
    if (g->n == g->cap) {
        int cap = g->cap ? 2 * g->cap : 16;
        gj_poly *q = realloc(g->p, (size_t)cap * sizeof *q);
        if (!q) return gj_fail(g, FLOE_ENOMEM, "out of memory");
        g->p = q;
        g->cap = cap;
    }
    gj_poly *p = g->p + g->n;
    memset(p, 0, sizeof *p);
    int *orig;
    FLOE_TRY(gj_read_ring(g, json_object_array_get_idx(rings, 0), where, &p->xy, &orig, &p->n));
    g->n++; /* owned by g from here */
    p->feature = feature;
    p->part = part;
    p->h = h;
    p->fixed = fixed;
    p->lo[0] = p->lo[1] = INFINITY;
    p->hi[0] = p->hi[1] = -INFINITY;
    for (int i = 0; i < 2 * p->n; i++) {
        p->lo[i % 2] = fmin(p->lo[i % 2], p->xy[i]);
        p->hi[i % 2] = fmax(p->hi[i % 2], p->xy[i]);
    }
    p->size = hypot(p->hi[0] - p->lo[0], p->hi[1] - p->lo[1]);
    int rc = gj_check_ring(g, where, p->xy, orig, p->n, p->size);
    free(orig);
    FLOE_TRY(rc);
    double *ccw = malloc((size_t)p->n * 2 * sizeof *ccw);
    if (!ccw) return gj_fail(g, FLOE_ENOMEM, "out of memory");
    int rev = gj_area2(p->xy, p->n) < 0;
    for (int i = 0; i < p->n; i++) {
        int k = rev ? p->n - 1 - i : i;
        ccw[2 * i] = p->xy[2 * k];
        ccw[2 * i + 1] = p->xy[2 * k + 1];
    }
    return gj_pieces(g, where, p, ccw); /* takes ccw */
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
    double h = g->h;
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
        rc = sc_fail(g->s, FLOE_EPARSE, g->at, "%s: %s:%d:%d: invalid JSON: %s", g->what, g->file, line, col,
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
        rc = gj_geometry(g, root, 0, g->h, -1);
    } else {
        rc = gj_fail(g, FLOE_EINVAL, "feature 0: the top level is %s%s%s: expected a GeoJSON FeatureCollection, "
                     "Feature, Polygon or MultiPolygon", t ? "a \"" : "", t ? t : "not a GeoJSON object",
                     t ? "\"" : "");
    }
    json_object_put(root);
    return rc;
}

/* ------------------------------------------------------------------------------------ */
/* Overlaps                                                                              */

/* extent of the convex polygon v (n points) along the axis (nx, ny) */
static void gj_extent(const double *v, int n, double nx, double ny, double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (int i = 0; i < n; i++) {
        double s = nx * v[2 * i] + ny * v[2 * i + 1];
        *lo = fmin(*lo, s);
        *hi = fmax(*hi, s);
    }
}

/* Two convex polygons overlap deeper than tol along every edge normal of both (separating
 * axis theorem: else they are apart or only touch). */
static int gj_convex_overlap(const double *a, int na, const double *b, int nb, double tol)
{
    for (int s = 0; s < 2; s++) {
        const double *v = s ? b : a;
        int n = s ? nb : na;
        for (int i = 0; i < n; i++) {
            const double *p = v + 2 * i, *q = v + 2 * ((i + 1) % n);
            double ex = q[0] - p[0], ey = q[1] - p[1], el = hypot(ex, ey);
            if (!(el > 0)) continue;
            double alo, ahi, blo, bhi;
            gj_extent(a, na, ey / el, -ex / el, &alo, &ahi);
            gj_extent(b, nb, ey / el, -ex / el, &blo, &bhi);
            if (ahi <= blo + tol || bhi <= alo + tol) return 0;
        }
    }
    return 1;
}

static int gj_boxes_meet(const double *alo, const double *ahi, const double *blo, const double *bhi, double tol)
{
    return alo[0] < bhi[0] - tol && blo[0] < ahi[0] - tol && alo[1] < bhi[1] - tol && blo[1] < ahi[1] - tol;
}

static int gj_polys_overlap(const gj_poly *A, const gj_poly *B)
{
    double tol = GJ_TOUCH * fmax(A->size, B->size);
    if (!gj_boxes_meet(A->lo, A->hi, B->lo, B->hi, tol)) return 0;
    for (int i = 0; i < A->npiece; i++) {
        const double *a = A->pxy + 2 * A->start[i];
        int na = A->start[i + 1] - A->start[i];
        double alo[2], ahi[2], blo[2], bhi[2];
        gj_extent(a, na, 1, 0, alo, ahi);
        gj_extent(a, na, 0, 1, alo + 1, ahi + 1);
        for (int j = 0; j < B->npiece; j++) {
            const double *b = B->pxy + 2 * B->start[j];
            int nb = B->start[j + 1] - B->start[j];
            gj_extent(b, nb, 1, 0, blo, bhi);
            gj_extent(b, nb, 0, 1, blo + 1, bhi + 1);
            if (gj_boxes_meet(alo, ahi, blo, bhi, tol) && gj_convex_overlap(a, na, b, nb, tol)) return 1;
        }
    }
    return 0;
}

static int gj_lo_cmp(const void *a, const void *b)
{
    const gj_poly *x = *(const gj_poly *const *)a, *y = *(const gj_poly *const *)b;
    if (x->lo[0] != y->lo[0]) return x->lo[0] < y->lo[0] ? -1 : 1;
    return x < y ? -1 : x > y;
}

/* The first pair of polygons that overlap (a sweep along x over their boxes). */
static int gj_check_overlaps(gj *g)
{
    const gj_poly **o = malloc((size_t)g->n * sizeof *o);
    if (!o) return gj_fail(g, FLOE_ENOMEM, "out of memory");
    for (int i = 0; i < g->n; i++) o[i] = g->p + i;
    qsort(o, (size_t)g->n, sizeof *o, gj_lo_cmp);
    const gj_poly *A = NULL, *B = NULL;
    for (int i = 0; i < g->n && !A; i++)
        for (int j = i + 1; j < g->n && o[j]->lo[0] < o[i]->hi[0]; j++)
            if (gj_polys_overlap(o[i], o[j])) {
                A = o[i] < o[j] ? o[i] : o[j];
                B = o[i] < o[j] ? o[j] : o[i];
                break;
            }
    free(o);
    if (!A) return FLOE_OK;
    char a[64], b[64];
    gj_name(a, sizeof a, A->feature, A->part);
    gj_name(b, sizeof b, B->feature, B->part);
    return gj_fail(g, FLOE_EINVAL, "%s and %s overlap (floes must not start overlapping; touching is fine)", a, b);
}

/* ------------------------------------------------------------------------------------ */
/* Bodies                                                                                */

/* the body: a polygon (convex) or a compound of its pieces, in the file's coordinates */
static floe_geometry *gj_shape(const gj_poly *p, char *err, size_t errlen)
{
    if (p->convex) return floe_polygon_create(p->xy, p->n, err, errlen);
    floe_geometry **pc = calloc((size_t)p->npiece, sizeof *pc);
    double *px = malloc((size_t)p->npiece * 3 * sizeof *px), *pq = malloc((size_t)p->npiece * 4 * sizeof *pq);
    int ok = pc && px && pq;
    if (!ok) snprintf(err, errlen, "out of memory");
    for (int k = 0; k < p->npiece && ok; k++) {
        pc[k] = floe_polygon_create(p->pxy + 2 * p->start[k], p->start[k + 1] - p->start[k], err, errlen);
        if (!pc[k]) {
            ok = 0;
            break;
        }
        const floe_polytope *pg = (const floe_polytope *)pc[k];
        floe_v3_copy(px + 3 * k, pg->frame_x);
        memcpy(pq + 4 * k, pg->frame_q, 4 * sizeof *pq);
    }
    floe_geometry *g = NULL;
    if (ok) g = floe_compound_create(pc, px, pq, p->npiece, 2, err, errlen); /* owns the pieces */
    else if (pc)
        for (int k = 0; k < p->npiece; k++) floe_geometry_destroy(pc[k]);
    free(pc);
    free(px);
    free(pq);
    return g;
}

static int gj_add_bodies(gj *g, int mat, const double v[3], int motion, int entry)
{
    static const double zero[3] = {0, 0, 0};
    sc *s = g->s;
    for (int i = 0; i < g->n; i++) {
        const gj_poly *p = g->p + i;
        char where[64], err[512] = "";
        gj_name(where, sizeof where, p->feature, p->part);
        floe_geometry *geo = gj_shape(p, err, sizeof err);
        if (!geo) return gj_fail(g, FLOE_EINVAL, "%s: %s", where, err);
        const double *fx, *fq;
        if (geo->klass == &floe_compound_class) {
            fx = ((const floe_compound *)geo)->frame_x;
            fq = ((const floe_compound *)geo)->frame_q;
        } else {
            fx = ((const floe_polytope *)geo)->frame_x;
            fq = ((const floe_polytope *)geo)->frame_q;
        }
        /* placed as a scene body written at its centroid: orientation identity x frame */
        floe_particle_def d = floe_default_particle_def();
        double id[4];
        floe_q_identity(id);
        floe_v3_copy(d.x, fx);
        floe_q_mul(d.q, id, fq);
        floe_q_normalize(d.q);
        int gi = floe_world_add_geometry(s->w, geo);
        if (gi < 0) {
            floe_geometry_destroy(geo);
            return gj_fail(g, -gi, "%s: %s", where, floe_world_last_error(s->w));
        }
        d.geometry = gi;
        d.material = mat;
        d.motion = p->fixed == 1 ? FLOE_FIXED : p->fixed == 0 ? FLOE_FREE : (floe_motion)motion;
        floe_v3_copy(d.v, p->fixed == 1 ? zero : v);
        d.group = entry;
        d.thickness = p->h;
        int r = floe_world_add_particle(s->w, &d);
        if (r < 0) return gj_fail(g, -r, "%s: %s", where, floe_world_last_error(s->w));
        s->mats[mat].nbody++;
        if (d.motion == FLOE_FREE) s->mats[mat].nfree = 1;
        s->nparticles++;
        s->nboxes++;
    }
    return FLOE_OK;
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
    gj g;
    memset(&g, 0, sizeof g);
    g.s = s;
    g.at = fat;
    snprintf(g.what, sizeof g.what, "%s.polygons_file", what);
    g.file = file;
    if (sc_has(&m, "thickness")) {
        FLOE_TRY(sc_num(s, &m, "thickness", 1, 0, &g.h));
        if (!(g.h > 0)) return sc_range(s, &m, "thickness", "> 0 (m)", g.h);
    }
    int mat, mo;
    double v[3];
    FLOE_TRY(sc_floe_entry(s, &m, entry, what, &mat, v, &mo));
    /* relative paths are relative to the scene file (as a mesh's file) */
    char path[1024];
    const char *slash = s->path ? strrchr(s->path, '/') : NULL;
    if (file[0] != '/' && slash) snprintf(path, sizeof path, "%.*s/%s", (int)(slash - s->path), s->path, file);
    else snprintf(path, sizeof path, "%s", file);
    int rc = gj_read(&g, path);
    if (!rc) rc = gj_check_overlaps(&g);
    if (!rc) rc = sc_check_memory(s, fat, what, (double)g.n);
    if (!rc) rc = gj_add_bodies(&g, mat, v, mo, entry);
    gj_free(&g);
    return rc;
}
