/* scene_polygons.c - the polygons of a body entry `{polygons_file: PATH, ...}` (the entry:
 * scene_geojson.c), whichever file they come from: a reader (GeoJSON in scene_geojson.c, ESRI
 * shapefiles in scene_shapefile.c) hands over each outer ring as the file writes it
 * (sc_polys_ring); this file checks it, cuts it into convex pieces, checks that no two
 * polygons overlap and makes the bodies (docs/sea-ice.md, "Floes from GeoJSON" and "Floes
 * from shapefiles").
 *
 * Every ring becomes one body: a convex ring a `polygon` geometry placed at its centroid
 * frame (as a scene `polygon` body written at its centroid), a non-convex one a compound of
 * convex pieces: an ear-clipping triangulation (Meisters' two-ears theorem) merged into
 * convex polygons by Hertel and Mehlhorn's rule (drop a diagonal when both its ends stay
 * convex; at most four times the fewest pieces). Coordinates are projected metres (x, y).
 *
 * Refused, naming the file and the polygon ("feature 2", "shape 3 part 1"): rings with
 * fewer than 3 distinct points, non-finite coordinates, self-intersecting rings (a sweep
 * over the edges' boxes, then every pair of non-adjacent edges that may meet), rings of zero
 * area, and polygons that overlap each other (boxes first, then the separating-axis test
 * between their convex pieces: floes that only touch are accepted). */
#include "scene_read.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* the most points in one ring (the ear clipping is quadratic in the worst case) */
#define PL_MAX_RING 200000
/* collinear and zero-area tests: |cross| <= PL_FLAT L^2, L the ring's box diagonal (as
 * floe_polygon_create); overlaps shallower than PL_TOUCH x the larger polygon are touches */
#define PL_FLAT 1e-12
#define PL_TOUCH 1e-9

typedef struct pl_poly {
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
} pl_poly;

/* the polygons of one entry, whichever reader found them (scene_read.h) */
struct sc_polys {
    sc *s;
    struct fy_node *at;  /* the polygons_file value: every message is reported there */
    char what[160];      /* "bodies[2].polygons_file" */
    const char *file;    /* the file as the scene names it */
    double h;            /* the entry's thickness (0: none) */
    const char *unit, *sub, *ring; /* "feature", "polygon", "ring 0" (sc_polys_names) */
    pl_poly *p;
    int n, cap;
};
typedef struct sc_polys pl;

static int pl_vfail(pl *g, int code, const char *fmt, va_list ap)
{
    char msg[768];
    vsnprintf(msg, sizeof msg, fmt, ap);
    return sc_fail(g->s, code, g->at, "%s: %s: %s", g->what, g->file, msg);
}

int sc_polys_fail(pl *g, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = pl_vfail(g, code, fmt, ap);
    va_end(ap);
    return rc;
}
#define pl_fail sc_polys_fail

int sc_polys_fail_at(pl *g, int code, int line, int col, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return sc_fail(g->s, code, g->at, "%s: %s:%d:%d: %s", g->what, g->file, line, col, msg);
}

void sc_polys_names(pl *g, const char *unit, const char *part, const char *ring)
{
    g->unit = unit;
    g->sub = part;
    g->ring = ring;
}

double sc_polys_thickness(const pl *g) { return g->h; }

/* "feature 3" or "feature 3 polygon 1" ("shape 3 part 1") */
static const char *pl_name(const pl *g, char *buf, size_t len, int feature, int part)
{
    if (part < 0) snprintf(buf, len, "%s %d", g->unit, feature);
    else snprintf(buf, len, "%s %d %s %d", g->unit, feature, g->sub, part);
    return buf;
}

pl *sc_polys_create(sc *s, struct fy_node *at, const char *what, const char *file, double h)
{
    pl *g = calloc(1, sizeof *g);
    if (!g) return NULL;
    g->s = s;
    g->at = at;
    snprintf(g->what, sizeof g->what, "%s", what);
    g->file = file;
    g->h = h;
    sc_polys_names(g, "feature", "polygon", "ring 0");
    return g;
}

void sc_polys_destroy(pl *g)
{
    if (!g) return;
    for (int i = 0; i < g->n; i++) {
        free(g->p[i].xy);
        free(g->p[i].start);
        free(g->p[i].pxy);
    }
    free(g->p);
    free(g);
}

/* ------------------------------------------------------------------------------------ */
/* Planar predicates                                                                     */

/* twice the signed area of (a, b, c): > 0 counter-clockwise */
static double pl_orient(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* p on the segment ab, given that the three are collinear */
static int pl_within(const double *a, const double *b, const double *p)
{
    return p[0] >= fmin(a[0], b[0]) && p[0] <= fmax(a[0], b[0]) && p[1] >= fmin(a[1], b[1]) &&
           p[1] <= fmax(a[1], b[1]);
}

/* the closed segments ab and cd share a point */
static int pl_segments_meet(const double *a, const double *b, const double *c, const double *d)
{
    double d1 = pl_orient(c, d, a), d2 = pl_orient(c, d, b), d3 = pl_orient(a, b, c), d4 = pl_orient(a, b, d);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 1;
    return (d1 == 0 && pl_within(c, d, a)) || (d2 == 0 && pl_within(c, d, b)) || (d3 == 0 && pl_within(a, b, c)) ||
           (d4 == 0 && pl_within(a, b, d));
}

/* twice the signed area of a ring (about its first point, for accuracy) */
static double pl_area2(const double *xy, int n)
{
    double a = 0;
    for (int i = 1; i + 1 < n; i++) a += pl_orient(xy, xy + 2 * i, xy + 2 * (i + 1));
    return a;
}

/* ------------------------------------------------------------------------------------ */
/* Rings                                                                                 */

typedef struct pl_edge { double xmin, xmax; int i; } pl_edge;

static int pl_edge_cmp(const void *a, const void *b)
{
    const pl_edge *x = a, *y = b;
    return x->xmin < y->xmin ? -1 : x->xmin > y->xmin ? 1 : x->i - y->i;
}

/* Two non-adjacent edges that meet, by a sweep along x over the edges' boxes: 0 when
 * none, else 1 with the edges in *ea < *eb. */
static int pl_self_crossing(const double *xy, int n, int *ea, int *eb, int *oom)
{
    pl_edge *e = malloc((size_t)n * sizeof *e);
    *oom = !e;
    if (!e) return 0;
    for (int i = 0; i < n; i++) {
        const double *a = xy + 2 * i, *b = xy + 2 * ((i + 1) % n);
        e[i] = (pl_edge){fmin(a[0], b[0]), fmax(a[0], b[0]), i};
    }
    qsort(e, (size_t)n, sizeof *e, pl_edge_cmp);
    int found = 0;
    for (int k = 0; k < n && !found; k++) {
        int i = e[k].i;
        const double *a = xy + 2 * i, *b = xy + 2 * ((i + 1) % n);
        for (int m = k + 1; m < n && e[m].xmin <= e[k].xmax; m++) {
            int j = e[m].i;
            if (abs(i - j) == 1 || abs(i - j) == n - 1) continue; /* adjacent: they share a point */
            const double *c = xy + 2 * j, *d = xy + 2 * ((j + 1) % n);
            if (fmax(c[1], d[1]) < fmin(a[1], b[1]) || fmin(c[1], d[1]) > fmax(a[1], b[1])) continue;
            if (pl_segments_meet(a, b, c, d)) {
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

/* The points of a ring as written (x, y of each; point k of the file is k here) into xy
 * without the closing point and repeats, the index in the file of each kept point into orig. */
static int pl_filter_ring(pl *g, const char *where, const double *raw, long cnt, double **xy, int **orig, int *n)
{
    *xy = NULL;
    *orig = NULL;
    *n = 0;
    if (cnt > PL_MAX_RING)
        return pl_fail(g, FLOE_EINVAL, "%s: %s has %ld points, more than %d", where, g->ring, cnt, PL_MAX_RING);
    double *x = malloc(((size_t)cnt + 1) * 2 * sizeof *x);
    int *o = malloc(((size_t)cnt + 1) * sizeof *o);
    if (!x || !o) {
        free(x);
        free(o);
        return pl_fail(g, FLOE_ENOMEM, "out of memory");
    }
    int m = 0;
    for (long k = 0; k < cnt; k++) {
        const double *c = raw + 2 * k;
        if (!isfinite(c[0]) || !isfinite(c[1])) {
            free(x);
            free(o);
            return pl_fail(g, FLOE_EINVAL, "%s: %s point %ld is not finite (%g, %g)", where, g->ring, k, c[0], c[1]);
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
        return pl_fail(g, FLOE_EINVAL, "%s: %s has %d distinct points (a polygon needs at least 3)", where, g->ring,
                       m);
    }
    *xy = x;
    *orig = o;
    *n = m;
    return FLOE_OK;
}

/* A simple ring of non-zero area: no two non-adjacent edges meet, no adjacent ones fold
 * back on each other. */
static int pl_check_ring(pl *g, const char *where, const double *xy, const int *orig, int n, double L)
{
    int ea, eb, oom;
    if (pl_self_crossing(xy, n, &ea, &eb, &oom))
        return pl_fail(g, FLOE_EINVAL, "%s: %s is self-intersecting: the edge from point %d to point %d "
                       "meets the edge from point %d to point %d, near (%.17g, %.17g)", where, g->ring, orig[ea],
                       orig[(ea + 1) % n], orig[eb], orig[(eb + 1) % n], xy[2 * eb], xy[2 * eb + 1]);
    if (oom) return pl_fail(g, FLOE_ENOMEM, "out of memory");
    if (!(fabs(pl_area2(xy, n)) > 2 * PL_FLAT * L * L))
        return pl_fail(g, FLOE_EINVAL, "%s: %s has zero area (its %d points are collinear)", where, g->ring, n);
    for (int i = 0; i < n; i++) {
        const double *a = xy + 2 * ((i + n - 1) % n), *v = xy + 2 * i, *b = xy + 2 * ((i + 1) % n);
        double dot = (v[0] - a[0]) * (b[0] - v[0]) + (v[1] - a[1]) * (b[1] - v[1]);
        if (fabs(pl_orient(a, v, b)) <= PL_FLAT * L * L && dot < 0)
            return pl_fail(g, FLOE_EINVAL, "%s: %s is self-intersecting: it turns back on itself at point %d "
                           "(its two edges there overlap)", where, g->ring, orig[i]);
    }
    return FLOE_OK;
}

/* ------------------------------------------------------------------------------------ */
/* Convex decomposition of a simple counter-clockwise polygon                            */

/* The points that start reflex, bucketed on a grid over the ring's box: an ear test looks
 * only in the cells its triangle's box covers. Clipping ears only makes reflex points
 * convex (the interior angles at the clipped ear's neighbours shrink), never the reverse,
 * so the grid is built once and stale entries are skipped by the reflex flag. */
typedef struct pl_grid {
    int g;               /* g x g cells */
    double lo[2], inv[2];
    int *first, *item;   /* cell c holds item[first[c] .. first[c + 1]) */
} pl_grid;

static int pl_cell(const pl_grid *gr, double x, int a)
{
    double c = (x - gr->lo[a]) * gr->inv[a];
    return c <= 0 ? 0 : c >= gr->g - 1 ? gr->g - 1 : (int)c;
}

static int pl_grid_build(pl_grid *gr, const double *xy, int n, const char *reflex)
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
        if (reflex[i]) gr->first[pl_cell(gr, xy[2 * i + 1], 1) * gr->g + pl_cell(gr, xy[2 * i], 0) + 1]++;
    for (int c = 0; c < gr->g * gr->g; c++) gr->first[c + 1] += gr->first[c];
    int *fill = malloc((size_t)gr->g * gr->g * sizeof *fill);
    if (!fill) return -2;
    memcpy(fill, gr->first, (size_t)gr->g * gr->g * sizeof *fill);
    for (int i = 0; i < n; i++)
        if (reflex[i]) gr->item[fill[pl_cell(gr, xy[2 * i + 1], 1) * gr->g + pl_cell(gr, xy[2 * i], 0)]++] = i;
    free(fill);
    return 0;
}

/* a reflex point other than a, v, b in the closed triangle (a, v, b) */
static int pl_ear_blocked(const pl_grid *gr, const double *xy, const char *reflex, int a, int v, int b)
{
    const double *A = xy + 2 * a, *V = xy + 2 * v, *B = xy + 2 * b;
    int c0 = pl_cell(gr, fmin(A[0], fmin(V[0], B[0])), 0), c1 = pl_cell(gr, fmax(A[0], fmax(V[0], B[0])), 0);
    int r0 = pl_cell(gr, fmin(A[1], fmin(V[1], B[1])), 1), r1 = pl_cell(gr, fmax(A[1], fmax(V[1], B[1])), 1);
    for (int row = r0; row <= r1; row++)
        for (int col = c0; col <= c1; col++) {
            int c = row * gr->g + col;
            for (int q = gr->first[c]; q < gr->first[c + 1]; q++) {
                int k = gr->item[q];
                if (!reflex[k] || k == a || k == v || k == b) continue;
                const double *P = xy + 2 * k;
                if (pl_orient(A, V, P) >= 0 && pl_orient(V, B, P) >= 0 && pl_orient(B, A, P) >= 0) return 1;
            }
        }
    return 0;
}

/* Ear clipping: n - 2 triangles (3 point indices each, counter-clockwise) into tri; 0, -1
 * when no ear is found (a ring that is not simple to round-off), -2 out of memory.
 * Collinear points must have been removed. Only reflex points can lie in an ear. */
static int pl_ear_clip(const double *xy, int n, int *tri)
{
    int *prev = malloc((size_t)n * sizeof *prev), *next = malloc((size_t)n * sizeof *next);
    char *reflex = malloc((size_t)n);
    pl_grid gr = {0};
    int rc = prev && next && reflex ? 0 : -2;
    for (int i = 0; i < n && !rc; i++) {
        prev[i] = (i + n - 1) % n;
        next[i] = (i + 1) % n;
        reflex[i] = pl_orient(xy + 2 * prev[i], xy + 2 * i, xy + 2 * next[i]) <= 0;
    }
    if (!rc) rc = pl_grid_build(&gr, xy, n, reflex);
    int left = n, nt = 0, v = 0, tries = 0;
    while (!rc && left > 3) {
        int a = prev[v], b = next[v];
        if (reflex[v] || pl_ear_blocked(&gr, xy, reflex, a, v, b)) {
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
        reflex[a] = reflex[a] && pl_orient(xy + 2 * prev[a], xy + 2 * a, xy + 2 * b) <= 0;
        reflex[b] = reflex[b] && pl_orient(xy + 2 * a, xy + 2 * b, xy + 2 * next[b]) <= 0;
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

typedef struct pl_diag { int lo, hi, t; } pl_diag; /* a triangle's edge lo-hi (lo < hi) */

static int pl_diag_cmp(const void *a, const void *b)
{
    const pl_diag *x = a, *y = b;
    return x->lo != y->lo ? x->lo - y->lo : x->hi != y->hi ? x->hi - y->hi : x->t - y->t;
}

static int pl_find_root(int *up, int t)
{
    while (up[t] != t) t = up[t] = up[up[t]];
    return t;
}

/* Hertel-Mehlhorn: the triangles merged across their diagonals while both ends of a
 * diagonal stay convex. Pieces as point cycles: piece k is cyc[k][0 .. len[k]). */
static int pl_merge(const double *xy, int n, const int *tri, int ***cyc_out, int **len_out, int *np_out)
{
    int nt = n - 2, rc = FLOE_ENOMEM;
    int **cyc = calloc((size_t)nt, sizeof *cyc), *len = calloc((size_t)nt, sizeof *len);
    int *up = malloc((size_t)nt * sizeof *up);
    pl_diag *d = malloc((size_t)nt * 3 * sizeof *d);
    if (!cyc || !len || !up || !d) goto done;
    for (int t = 0; t < nt; t++) {
        if (!(cyc[t] = malloc(3 * sizeof **cyc))) goto done;
        memcpy(cyc[t], tri + 3 * t, 3 * sizeof **cyc);
        len[t] = 3;
        up[t] = t;
        for (int k = 0; k < 3; k++) {
            int p = tri[3 * t + k], q = tri[3 * t + (k + 1) % 3];
            d[3 * t + k] = (pl_diag){p < q ? p : q, p < q ? q : p, t};
        }
    }
    qsort(d, (size_t)nt * 3, sizeof *d, pl_diag_cmp);
    for (int k = 0; k + 1 < 3 * nt; k++) {
        if (d[k].lo != d[k + 1].lo || d[k].hi != d[k + 1].hi) continue; /* a side of the polygon */
        int P = pl_find_root(up, d[k].t), Q = pl_find_root(up, d[k + 1].t);
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
        if (pl_orient(xy + 2 * pu, xy + 2 * u, xy + 2 * qn) < 0 || pl_orient(xy + 2 * qp, xy + 2 * w, xy + 2 * nw) < 0)
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
static int pl_pieces(pl *g, const char *where, pl_poly *p, double *ccw)
{
    int n = p->n;
    double L2 = p->size * p->size;
    p->convex = 1;
    for (int i = 0; i < n && p->convex; i++)
        if (pl_orient(ccw + 2 * ((i + n - 1) % n), ccw + 2 * i, ccw + 2 * ((i + 1) % n)) < -PL_FLAT * L2) p->convex = 0;
    if (p->convex) {
        p->npiece = 1;
        p->pxy = ccw;
        p->start = malloc(2 * sizeof *p->start);
        if (!p->start) return pl_fail(g, FLOE_ENOMEM, "out of memory");
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
            if (fabs(pl_orient(a, ccw + 2 * i, b)) <= PL_FLAT * L2) continue;
            ccw[2 * m] = ccw[2 * i];
            ccw[2 * m + 1] = ccw[2 * i + 1];
            m++;
        }
    }
    int *tri = malloc((size_t)(m > 3 ? m - 2 : 1) * 3 * sizeof *tri);
    if (!tri) {
        free(ccw);
        return pl_fail(g, FLOE_ENOMEM, "out of memory");
    }
    int rc = m >= 3 ? pl_ear_clip(ccw, m, tri) : -1;
    int **cyc = NULL, *len = NULL, np = 0;
    if (!rc) rc = pl_merge(ccw, m, tri, &cyc, &len, &np) ? -2 : 0;
    free(tri);
    if (rc) {
        free(ccw);
        return rc == -2 ? pl_fail(g, FLOE_ENOMEM, "out of memory")
                        : pl_fail(g, FLOE_EINVAL, "%s: %s could not be cut into triangles (not simple to "
                                  "round-off?)", where, g->ring);
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
    if (!p->start || !p->pxy) return pl_fail(g, FLOE_ENOMEM, "out of memory");
    return FLOE_OK;
}

/* ------------------------------------------------------------------------------------ */
/* Polygons, whatever their file                                                        */

int sc_polys_ring(pl *g, int feature, int part, const double *raw, long cnt, double h, int fixed)
{
    char where[64];
    pl_name(g, where, sizeof where, feature, part);
    if (g->n == g->cap) {
        int cap = g->cap ? 2 * g->cap : 16;
        pl_poly *q = realloc(g->p, (size_t)cap * sizeof *q);
        if (!q) return pl_fail(g, FLOE_ENOMEM, "out of memory");
        g->p = q;
        g->cap = cap;
    }
    pl_poly *p = g->p + g->n;
    memset(p, 0, sizeof *p);
    int *orig;
    FLOE_TRY(pl_filter_ring(g, where, raw, cnt, &p->xy, &orig, &p->n));
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
    int rc = pl_check_ring(g, where, p->xy, orig, p->n, p->size);
    free(orig);
    FLOE_TRY(rc);
    double *ccw = malloc((size_t)p->n * 2 * sizeof *ccw);
    if (!ccw) return pl_fail(g, FLOE_ENOMEM, "out of memory");
    int rev = pl_area2(p->xy, p->n) < 0;
    for (int i = 0; i < p->n; i++) {
        int k = rev ? p->n - 1 - i : i;
        ccw[2 * i] = p->xy[2 * k];
        ccw[2 * i + 1] = p->xy[2 * k + 1];
    }
    return pl_pieces(g, where, p, ccw); /* takes ccw */
}

/* ------------------------------------------------------------------------------------ */
/* Overlaps                                                                              */

/* extent of the convex polygon v (n points) along the axis (nx, ny) */
static void pl_extent(const double *v, int n, double nx, double ny, double *lo, double *hi)
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
static int pl_convex_overlap(const double *a, int na, const double *b, int nb, double tol)
{
    for (int s = 0; s < 2; s++) {
        const double *v = s ? b : a;
        int n = s ? nb : na;
        for (int i = 0; i < n; i++) {
            const double *p = v + 2 * i, *q = v + 2 * ((i + 1) % n);
            double ex = q[0] - p[0], ey = q[1] - p[1], el = hypot(ex, ey);
            if (!(el > 0)) continue;
            double alo, ahi, blo, bhi;
            pl_extent(a, na, ey / el, -ex / el, &alo, &ahi);
            pl_extent(b, nb, ey / el, -ex / el, &blo, &bhi);
            if (ahi <= blo + tol || bhi <= alo + tol) return 0;
        }
    }
    return 1;
}

static int pl_boxes_meet(const double *alo, const double *ahi, const double *blo, const double *bhi, double tol)
{
    return alo[0] < bhi[0] - tol && blo[0] < ahi[0] - tol && alo[1] < bhi[1] - tol && blo[1] < ahi[1] - tol;
}

static int pl_polys_overlap(const pl_poly *A, const pl_poly *B)
{
    double tol = PL_TOUCH * fmax(A->size, B->size);
    if (!pl_boxes_meet(A->lo, A->hi, B->lo, B->hi, tol)) return 0;
    for (int i = 0; i < A->npiece; i++) {
        const double *a = A->pxy + 2 * A->start[i];
        int na = A->start[i + 1] - A->start[i];
        double alo[2], ahi[2], blo[2], bhi[2];
        pl_extent(a, na, 1, 0, alo, ahi);
        pl_extent(a, na, 0, 1, alo + 1, ahi + 1);
        for (int j = 0; j < B->npiece; j++) {
            const double *b = B->pxy + 2 * B->start[j];
            int nb = B->start[j + 1] - B->start[j];
            pl_extent(b, nb, 1, 0, blo, bhi);
            pl_extent(b, nb, 0, 1, blo + 1, bhi + 1);
            if (pl_boxes_meet(alo, ahi, blo, bhi, tol) && pl_convex_overlap(a, na, b, nb, tol)) return 1;
        }
    }
    return 0;
}

static int pl_lo_cmp(const void *a, const void *b)
{
    const pl_poly *x = *(const pl_poly *const *)a, *y = *(const pl_poly *const *)b;
    if (x->lo[0] != y->lo[0]) return x->lo[0] < y->lo[0] ? -1 : 1;
    return x < y ? -1 : x > y;
}

/* The first pair of polygons that overlap (a sweep along x over their boxes). */
static int pl_check_overlaps(pl *g)
{
    const pl_poly **o = malloc((size_t)g->n * sizeof *o);
    if (!o) return pl_fail(g, FLOE_ENOMEM, "out of memory");
    for (int i = 0; i < g->n; i++) o[i] = g->p + i;
    qsort(o, (size_t)g->n, sizeof *o, pl_lo_cmp);
    const pl_poly *A = NULL, *B = NULL;
    for (int i = 0; i < g->n && !A; i++)
        for (int j = i + 1; j < g->n && o[j]->lo[0] < o[i]->hi[0]; j++)
            if (pl_polys_overlap(o[i], o[j])) {
                A = o[i] < o[j] ? o[i] : o[j];
                B = o[i] < o[j] ? o[j] : o[i];
                break;
            }
    free(o);
    if (!A) return FLOE_OK;
    char a[64], b[64];
    pl_name(g, a, sizeof a, A->feature, A->part);
    pl_name(g, b, sizeof b, B->feature, B->part);
    return pl_fail(g, FLOE_EINVAL, "%s and %s overlap (floes must not start overlapping; touching is fine)", a, b);
}

/* ------------------------------------------------------------------------------------ */
/* Bodies                                                                                */

/* the body: a polygon (convex) or a compound of its pieces, in the file's coordinates */
static floe_geometry *pl_shape(const pl_poly *p, char *err, size_t errlen)
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

static int pl_add_bodies(pl *g, int mat, const double v[3], int motion, int entry)
{
    static const double zero[3] = {0, 0, 0};
    sc *s = g->s;
    for (int i = 0; i < g->n; i++) {
        const pl_poly *p = g->p + i;
        char where[64], err[512] = "";
        pl_name(g, where, sizeof where, p->feature, p->part);
        floe_geometry *geo = pl_shape(p, err, sizeof err);
        if (!geo) return pl_fail(g, FLOE_EINVAL, "%s: %s", where, err);
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
            return pl_fail(g, -gi, "%s: %s", where, floe_world_last_error(s->w));
        }
        d.geometry = gi;
        d.material = mat;
        d.motion = p->fixed == 1 ? FLOE_FIXED : p->fixed == 0 ? FLOE_FREE : (floe_motion)motion;
        floe_v3_copy(d.v, p->fixed == 1 ? zero : v);
        d.group = entry;
        d.thickness = p->h;
        int r = floe_world_add_particle(s->w, &d);
        if (r < 0) return pl_fail(g, -r, "%s: %s", where, floe_world_last_error(s->w));
        s->mats[mat].nbody++;
        if (d.motion == FLOE_FREE) s->mats[mat].nfree = 1;
        s->nparticles++;
        s->nboxes++;
    }
    return FLOE_OK;
}

int sc_polys_build(pl *g, int mat, const double v[3], int motion, int entry)
{
    FLOE_TRY(pl_check_overlaps(g));
    FLOE_TRY(sc_check_memory(g->s, g->at, g->what, (double)g->n));
    return pl_add_bodies(g, mat, v, motion, entry);
}
