/* voronoi.c - 2D Voronoi tessellation of a rectangle by half-plane clipping, with Lloyd
 * relaxation (floe_voronoi.h).
 *
 * Cell k starts as the rectangle and is clipped (Sutherland-Hodgman, one convex polygon
 * against one half-plane) by the bisector of s_k and each nearby seed s_j:
 *   keep p = x - s_k with  f(p) = p.d - |d|^2/2 <= 0,  d = s_j - s_k,
 * f being |d| times the signed distance of x beyond the bisector. Coordinates are relative
 * to s_k so the bisector tests do not lose digits to large offsets.
 *
 * Which seeds: the seeds are held in a k-d tree (core/base/floe_kdtree.h).
 *  1. Clip by the VOR_KNN nearest seeds, nearest first. If the farthest of them is at
 *     least 2 R from s_k (R = the largest corner distance |p|), no other seed can cut: its
 *     bisector is at least R from s_k (the security radius criterion). This ends most cells
 *     of an even field.
 *  2. Otherwise check each corner v: a seed j cuts the (convex) cell only if some corner is
 *     strictly closer to s_j than to s_k, and then the seed nearest to v is such a seed. So
 *     ask the tree for the few seeds nearest to v, clip by those strictly closer than s_k
 *     and check the new corners, until no corner has a seed closer than s_k (the empty
 *     circles of the Voronoi vertices). Corners kept by a clip stay checked. A far corner
 *     (left by step 1 in a cell at the rectangle's edge) moves in with each clip, and its
 *     nearest seeds are found in O(log n) however many seeds its disc holds. When all the
 *     nearest seeds of v tie with s_k (cocircular seeds, a lattice), the whole disc of
 *     radius |v - s_k| is searched instead.
 * So clustered seeds, seeds on a line (long strips) and long rectangles cost about as much
 * per cell as an even field (50,000 cells in under a second in each of these cases).
 * A seed is counted as closer to a corner only when it is so by more than 1e-12 x the
 * cell's radius, so ties (cocircular seeds of a lattice) neither loop nor split corners.
 *
 * Power cells (weights w): the same clipping by the power bisectors
 *   p.d <= (|d|^2 + w_k - w_j)/2,
 * step 1 with the nearest seeds in the plane, step 2 for every corner (no security radius)
 * with the seeds lifted to sqrt(W - w_j) above the plane, where the nearest lifted seeds of
 * a corner are those of least power distance. Each edge keeps the seed whose bisector it
 * lies on, for the Newton method on the weights (floe_voronoi_areas, below). */
#include "floe_voronoi.h"
#include "error_text.h"
#include "floe_base.h"
#include "floe_kdtree.h"
#include "floe_rng.h"
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define VOR_MAX_SEEDS 100000000
/* nearest seeds clipped by before the corner checks */
#define VOR_KNN 16
/* nearest seeds of a corner asked first in its check */
#define VOR_KNN_CORNER 6
#define VOR_KNN_POWER 4
/* seeds closer than this x the rectangle's diagonal are duplicates */
#define VOR_DUP_REL 1e-12
/* a seed cuts a corner when it is closer than s_k by more than this x the cell's radius */
#define VOR_TIE_REL 1e-12
/* corners closer than this x the cell's bounding-box diagonal are merged */
#define VOR_SHORT_EDGE_REL 1e-9
/* corners turning by less than this (sine of the angle) are dropped */
#define VOR_FLAT_SIN 1e-12

static int grow_int(int **a, int *cap, int need) {
    if (need <= *cap) return FLOE_OK;
    int c = 2 * need;
    int *b = realloc(*a, (size_t)c * sizeof *b);
    if (!b) return FLOE_ENOMEM;
    *a = b;
    *cap = c;
    return FLOE_OK;
}

/* ---- one cell: a convex polygon, corners relative to the seed, in p[0 .. 2m); ok[i]
 * says corner i has been checked (step 2) ---- */
typedef struct vor_cell {
    double *p, *q;          /* the polygon and the clip's output, swapped after a clip */
    unsigned char *ok, *qok;
    int *lab, *qlab;        /* the seed whose bisector holds edge i -> i+1 (-1: the rectangle) */
    int m, cap;
    double r2max;           /* max |corner|^2 */
    int *used, nused, cap_used; /* seeds clipped by (or ruled out) */
} vor_cell;

static int cell_reserve(vor_cell *c, int need) {
    if (need <= c->cap) return FLOE_OK;
    int cap = 2 * need;
    double *p = realloc(c->p, 2 * (size_t)cap * sizeof *p);
    if (!p) return FLOE_ENOMEM;
    c->p = p;
    double *q = realloc(c->q, 2 * (size_t)cap * sizeof *q);
    if (!q) return FLOE_ENOMEM;
    c->q = q;
    unsigned char *ok = realloc(c->ok, (size_t)cap);
    if (!ok) return FLOE_ENOMEM;
    c->ok = ok;
    unsigned char *qok = realloc(c->qok, (size_t)cap);
    if (!qok) return FLOE_ENOMEM;
    c->qok = qok;
    int *lab = realloc(c->lab, (size_t)cap * sizeof *lab);
    if (!lab) return FLOE_ENOMEM;
    c->lab = lab;
    int *qlab = realloc(c->qlab, (size_t)cap * sizeof *qlab);
    if (!qlab) return FLOE_ENOMEM;
    c->qlab = qlab;
    c->cap = cap;
    return FLOE_OK;
}

static void cell_free(vor_cell *c) {
    free(c->p);
    free(c->q);
    free(c->ok);
    free(c->qok);
    free(c->lab);
    free(c->qlab);
    free(c->used);
}

static void cell_radius(vor_cell *c) {
    double r2 = 0;
    for (int i = 0; i < c->m; i++) r2 = fmax(r2, c->p[2 * i] * c->p[2 * i] + c->p[2 * i + 1] * c->p[2 * i + 1]);
    c->r2max = r2;
}

/* clip by seed j: f(p) = p.d - (|d|^2 + dw)/2 <= 0, dw = w_k - w_j (0 for Voronoi cells;
 * the power bisector otherwise), Sutherland-Hodgman; the cell is left alone when no corner
 * is outside. Kept corners keep their checked flag and their edge's label; new ones are
 * unchecked, and the edge along the new line is labelled j. */
static int cell_clip(vor_cell *c, const double d[2], double dw, int j) {
    double dd = d[0] * d[0] + d[1] * d[1], half = 0.5 * (dd + dw), fhi = -INFINITY;
    if (dw == 0 ? 2 * half >= 4 * c->r2max : half >= 0 && half * half >= c->r2max * dd)
        return FLOE_OK; /* bisector beyond every corner */
    for (int i = 0; i < c->m; i++) fhi = fmax(fhi, c->p[2 * i] * d[0] + c->p[2 * i + 1] * d[1] - half);
    if (fhi <= 0) return FLOE_OK;
    FLOE_TRY(cell_reserve(c, c->m + 1));
    int m = 0;
    for (int i = 0; i < c->m; i++) {
        int i1 = (i + 1) % c->m;
        const double *a = c->p + 2 * i, *b = c->p + 2 * i1;
        double fa = a[0] * d[0] + a[1] * d[1] - half, fb = b[0] * d[0] + b[1] * d[1] - half;
        if (fa <= 0) { c->q[2 * m] = a[0]; c->q[2 * m + 1] = a[1]; c->qok[m] = c->ok[i]; c->qlab[m] = c->lab[i]; m++; }
        if ((fa <= 0) != (fb <= 0)) {
            double t = fa / (fa - fb);
            c->q[2 * m] = a[0] + t * (b[0] - a[0]);
            c->q[2 * m + 1] = a[1] + t * (b[1] - a[1]);
            c->qok[m] = 0;
            c->qlab[m] = fa <= 0 ? j : c->lab[i];
            m++;
        }
    }
    double *t = c->p;
    c->p = c->q;
    c->q = t;
    unsigned char *tok = c->ok;
    c->ok = c->qok;
    c->qok = tok;
    int *tlab = c->lab;
    c->lab = c->qlab;
    c->qlab = tlab;
    c->m = m;
    cell_radius(c);
    return FLOE_OK;
}

static int cell_used(const vor_cell *c, int j) {
    for (int i = 0; i < c->nused; i++)
        if (c->used[i] == j) return 1;
    return 0;
}

/* ---- the tessellation's working state ---- */
typedef struct vor_run {
    double lo[2], hi[2];
    const double *seeds;   /* the current seeds (2n) */
    const double *w;       /* their weights (n), NULL for a Voronoi tessellation */
    int n;
    floe_kdtree *tree;     /* the seeds in the plane */
    floe_kdtree *lift;     /* power cells: the seeds lifted (index_weights) */
    double *pts;           /* 3n: the seeds with z = 0, then lifted (power cells), for the trees */
    int nn[VOR_KNN];       /* k-NN result */
    double nd2[VOR_KNN];
    int *hit, cap_hit;     /* radius query result */
    vor_cell c;
    size_t cap_xy;         /* corners the output's xy array holds */
    int *elab;             /* the label of each output edge (cap_xy), as vor_cell.lab */
    int nempty;            /* empty power cells in the last tessellation */
    int moved;             /* the seeds moved since they were indexed */
} vor_run;

/* w_k - w_j: the shift of the bisector of s_k and s_j in a power tessellation */
static double dweight(const vor_run *R, int k, int j) { return R->w ? R->w[k] - R->w[j] : 0.0; }

/* seeds among hit[0 .. cnt) that are closer to corner p than s_k by more than the tie
 * tolerance and not yet clipped by: moved to the front of hit, marked used; returns how
 * many (or -FLOE_ENOMEM) */
static int closer_seeds(vor_run *R, int k, const double p[2], int *hit, int cnt) {
    vor_cell *c = &R->c;
    const double *s = R->seeds + 2 * k;
    double tie = VOR_TIE_REL * sqrt(c->r2max);
    int cut = 0;
    for (int h = 0; h < cnt; h++) {
        int j = hit[h];
        if (j == k || cell_used(c, j)) continue;
        double d[2] = {R->seeds[2 * j] - s[0], R->seeds[2 * j + 1] - s[1]};
        double f = p[0] * d[0] + p[1] * d[1] - 0.5 * (d[0] * d[0] + d[1] * d[1] + dweight(R, k, j));
        if (f <= tie * sqrt(d[0] * d[0] + d[1] * d[1])) continue;
        if (grow_int(&c->used, &c->cap_used, c->nused + 1) != FLOE_OK) return -FLOE_ENOMEM;
        c->used[c->nused++] = j;
        hit[cut++] = j;
    }
    return cut;
}

/* step 2 for the first unchecked corner v = s_k + p: clip by the seeds strictly closer to
 * v than s_k, or mark it checked. The nearest seeds of v are asked first (a far corner's
 * disc may hold many seeds, its nearest ones are enough: each clip moves the corner in);
 * only when all VOR_KNN_CORNER of them tie with s_k (cocircular seeds) is the whole disc
 * searched. *done = 1 when no unchecked corner is left. */
static int check_corner(vor_run *R, int k, int *done) {
    vor_cell *c = &R->c;
    const double *s = R->seeds + 2 * k;
    int i = 0;
    while (i < c->m && c->ok[i]) i++;
    *done = i == c->m;
    if (*done) return FLOE_OK;
    const double p[2] = {c->p[2 * i], c->p[2 * i + 1]};
    /* the lifted distance of s_k from (v, 0): power cells (index_weights) */
    double rp = R->w ? hypot(hypot(p[0], p[1]), R->pts[3 * k + 2]) : sqrt(p[0] * p[0] + p[1] * p[1]);
    /* the disc about v, widened for the rounding of v and of the tree's distances */
    double v[3] = {s[0] + p[0], s[1] + p[1], 0.0};
    double r = rp * (1 + 1e-9) + 1e-15 * (fabs(s[0]) + fabs(s[1]) + rp);
    const floe_kdtree *t = R->w ? R->lift : R->tree;
    int kc = R->w ? VOR_KNN_POWER : VOR_KNN_CORNER;
    int *hit = R->nn, cnt = floe_kdtree_knn(t, v, kc, R->nn, R->nd2);
    int cut = closer_seeds(R, k, p, hit, cnt);
    if (cut == 0 && cnt == kc && R->nd2[cnt - 1] <= r * r) {
        while ((cnt = floe_kdtree_radius(t, v, r, R->hit, R->cap_hit)) > R->cap_hit)
            FLOE_TRY(grow_int(&R->hit, &R->cap_hit, cnt));
        hit = R->hit;
        cut = closer_seeds(R, k, p, hit, cnt);
    }
    if (cut < 0) return -cut;
    if (cut == 0) { c->ok[i] = 1; return FLOE_OK; }
    for (int h = 0; h < cut; h++) {
        int j = hit[h];
        double d[2] = {R->seeds[2 * j] - s[0], R->seeds[2 * j + 1] - s[1]};
        FLOE_TRY(cell_clip(c, d, dweight(R, k, j), j));
    }
    return FLOE_OK;
}

/* cell k in the rectangle, relative to s_k (file comment, steps 1 and 2) */
static int cell_build(vor_run *R, int k) {
    vor_cell *c = &R->c;
    const double *s = R->seeds + 2 * k;
    FLOE_TRY(cell_reserve(c, 8));
    double x0 = R->lo[0] - s[0], x1 = R->hi[0] - s[0], y0 = R->lo[1] - s[1], y1 = R->hi[1] - s[1];
    double rect[8] = {x0, y0, x1, y0, x1, y1, x0, y1};
    memcpy(c->p, rect, sizeof rect);
    memset(c->ok, 0, 4);
    for (int i = 0; i < 4; i++) c->lab[i] = -1;
    c->m = 4;
    c->nused = 0;
    cell_radius(c);
    double q[3] = {s[0], s[1], 0.0};
    int kn = floe_kdtree_knn(R->tree, q, VOR_KNN, R->nn, R->nd2);
    FLOE_TRY(grow_int(&c->used, &c->cap_used, kn));
    for (int h = 0; h < kn; h++) {
        int j = R->nn[h];
        if (j == k) continue;
        c->used[c->nused++] = j;
        double d[2] = {R->seeds[2 * j] - s[0], R->seeds[2 * j + 1] - s[1]};
        FLOE_TRY(cell_clip(c, d, dweight(R, k, j), j));
    }
    /* the security radius holds for Voronoi cells only; power cells check every corner */
    if (kn == R->n || (!R->w && R->nd2[kn - 1] >= 4 * c->r2max * (1 + 1e-9))) return FLOE_OK;
    for (int done = 0; !done;) FLOE_TRY(check_corner(R, k, &done));
    return FLOE_OK;
}

static double cross2(const double *a, const double *b, const double *o) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/* drop corner i of the cell: the edges before and after it become one, labelled as the
 * longer of the two (next: the edge after it is the longer) */
static void cell_drop(vor_cell *c, int i, int next) {
    if (next) c->lab[(i + c->m - 1) % c->m] = c->lab[i];
    memmove(c->p + 2 * i, c->p + 2 * i + 2, 2 * (size_t)(c->m - i - 1) * sizeof *c->p);
    memmove(c->lab + i, c->lab + i + 1, (size_t)(c->m - i - 1) * sizeof *c->lab);
    c->m--;
}

/* merge corners closer than VOR_SHORT_EDGE_REL x the bounding-box diagonal and drop
 * corners that turn by less than VOR_FLAT_SIN (or turn the wrong way, from rounding) */
static void cell_clean(vor_cell *c) {
    double bl[2] = {INFINITY, INFINITY}, bh[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < c->m; i++)
        for (int a = 0; a < 2; a++) { bl[a] = fmin(bl[a], c->p[2 * i + a]); bh[a] = fmax(bh[a], c->p[2 * i + a]); }
    double tol = VOR_SHORT_EDGE_REL * hypot(bh[0] - bl[0], bh[1] - bl[1]);
    for (int changed = 1; changed && c->m >= 3;) {
        changed = 0;
        for (int i = 0; i < c->m && c->m >= 3; i++) {
            const double *a = c->p + 2 * ((i + c->m - 1) % c->m), *v = c->p + 2 * i, *b = c->p + 2 * ((i + 1) % c->m);
            double la = hypot(v[0] - a[0], v[1] - a[1]), lb = hypot(b[0] - v[0], b[1] - v[1]);
            if (la < tol || cross2(v, b, a) <= VOR_FLAT_SIN * la * lb) {
                cell_drop(c, i, lb > la);
                changed = 1;
                i--;
            }
        }
    }
}

/* area and centroid of the polygon xy (m corners), the sums taken relative to o */
static void poly_moments(const double *xy, int m, const double o[2], double *area, double c[2]) {
    double A2 = 0, cx = 0, cy = 0;
    for (int i = 0; i < m; i++) {
        const double *p = xy + 2 * i, *q = xy + 2 * ((i + 1) % m);
        double px = p[0] - o[0], py = p[1] - o[1], qx = q[0] - o[0], qy = q[1] - o[1], w = px * qy - py * qx;
        A2 += w;
        cx += (px + qx) * w;
        cy += (py + qy) * w;
    }
    *area = 0.5 * A2;
    c[0] = o[0] + cx / (3 * A2);
    c[1] = o[1] + cy / (3 * A2);
}

/* ---- the whole tessellation ---- */
static int append_cell(vor_run *R, floe_voronoi *v, int k) {
    const double *s = v->seed + 2 * k;
    vor_cell *c = &R->c;
    size_t at = (size_t)v->start[k];
    if (at + c->m > R->cap_xy) {
        size_t cap = 2 * (at + c->m);
        double *xy = realloc(v->xy, 2 * cap * sizeof *xy);
        if (!xy) return FLOE_ENOMEM;
        v->xy = xy;
        int *el = realloc(R->elab, cap * sizeof *el);
        if (!el) return FLOE_ENOMEM;
        R->elab = el;
        R->cap_xy = cap;
    }
    double *xy = v->xy + 2 * at;
    for (int i = 0; i < c->m; i++)
        for (int a = 0; a < 2; a++) xy[2 * i + a] = fmin(R->hi[a], fmax(R->lo[a], s[a] + c->p[2 * i + a]));
    memcpy(R->elab + at, c->lab, (size_t)c->m * sizeof *c->lab);
    v->start[k + 1] = (int)(at + c->m);
    poly_moments(xy, c->m, s, v->area + k, v->centroid + 2 * k);
    return FLOE_OK;
}

/* the seeds into the k-d tree of the plane */
static int index_seeds(vor_run *R, const double *seeds) {
    for (int k = 0; k < R->n; k++) {
        R->pts[3 * k] = seeds[2 * k];
        R->pts[3 * k + 1] = seeds[2 * k + 1];
        R->pts[3 * k + 2] = 0.0;
    }
    floe_kdtree_destroy(R->tree);
    R->tree = floe_kdtree_build(R->pts, R->n, 2, 0);
    R->seeds = seeds;
    return R->tree ? FLOE_OK : FLOE_ENOMEM;
}

/* power cells (R->w): the indexed seeds lifted into the tree R->lift, seed j to the height
 * z_j = sqrt(W - w_j), W = max w, so that the squared distance from (x, 0) to the lifted
 * seed is |x - s_j|^2 - w_j + W: the seeds that beat s_k at x are those of the lifted ball
 * about (x, 0) through s_k's lifted point (Aurenhammer 1987, power diagrams as a
 * projection) */
static int index_weights(vor_run *R) {
    double W = -INFINITY;
    for (int k = 0; k < R->n; k++) W = fmax(W, R->w[k]);
    for (int k = 0; k < R->n; k++) R->pts[3 * k + 2] = sqrt(W - R->w[k]);
    floe_kdtree_destroy(R->lift);
    R->lift = floe_kdtree_build(R->pts, R->n, 3, 0);
    return R->lift ? FLOE_OK : FLOE_ENOMEM;
}

/* the cells of the indexed seeds (v->seed) into v (xy, start, area, centroid). A Voronoi
 * cell of fewer than 3 corners is an error; a power cell may be empty (R->nempty counts
 * them: no corners, area 0, centroid at the seed). */
static int tessellate(vor_run *R, floe_voronoi *v, char *err, size_t errlen) {
    v->start[0] = 0;
    R->nempty = 0;
    for (int k = 0; k < v->n; k++) {
        FLOE_TRY(cell_build(R, k));
        cell_clean(&R->c);
        if (R->c.m < 3 && R->w) {
            R->nempty++;
            v->start[k + 1] = v->start[k];
            v->area[k] = 0;
            memcpy(v->centroid + 2 * k, v->seed + 2 * k, 2 * sizeof *v->seed);
            continue;
        }
        if (R->c.m < 3)
            return floe_error_set(err, errlen, FLOE_EINVAL,
                        "voronoi: the cell of seed %d (%.17g, %.17g) degenerates to %d corners: seeds nearly coincide", k,
                        v->seed[2 * k], v->seed[2 * k + 1], R->c.m);
        FLOE_TRY(append_cell(R, v, k));
    }
    return FLOE_OK;
}

static int check_rect(const double lo[2], const double hi[2], char *err, size_t errlen) {
    if (!lo || !hi) return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: rectangle corners lo/hi are NULL");
    for (int a = 0; a < 2; a++) {
        if (!isfinite(lo[a]) || !isfinite(hi[a]))
            return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: rectangle lo = (%g, %g), hi = (%g, %g) is not finite", lo[0],
                        lo[1], hi[0], hi[1]);
        if (!(hi[a] > lo[a]))
            return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: rectangle has hi[%d] = %g <= lo[%d] = %g (empty)", a, hi[a], a,
                        lo[a]);
    }
    return FLOE_OK;
}

static int check_seeds(const double lo[2], const double hi[2], const double *seeds, int n, char *err, size_t errlen) {
    for (int k = 0; k < n; k++) {
        const double *s = seeds + 2 * k;
        if (!isfinite(s[0]) || !isfinite(s[1]))
            return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: seed %d = (%g, %g) is not finite", k, s[0], s[1]);
        if (s[0] < lo[0] || s[0] > hi[0] || s[1] < lo[1] || s[1] > hi[1])
            return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: seed %d = (%g, %g) is outside the rectangle [%g, %g] x [%g, %g]",
                        k, s[0], s[1], lo[0], hi[0], lo[1], hi[1]);
    }
    return FLOE_OK;
}

/* the common checks of the three entry points */
static int check_input(const double lo[2], const double hi[2], const double *seeds, int n, floe_voronoi *out, char *err,
                       size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!out) return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: output is NULL");
    memset(out, 0, sizeof *out);
    FLOE_TRY(check_rect(lo, hi, err, errlen));
    if (n < 1 || n > VOR_MAX_SEEDS)
        return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: number of seeds n = %d is not in [1, %d]", n, VOR_MAX_SEEDS);
    if (!seeds) return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: seeds is NULL (n = %d)", n);
    return check_seeds(lo, hi, seeds, n, err, errlen);
}

/* two (indexed, unweighted) seeds closer than 1e-12 x the rectangle's diagonal: the
 * nearest other seed of each */
static int check_duplicates(vor_run *R, char *err, size_t errlen) {
    const double *s = R->seeds;
    double tol = VOR_DUP_REL * hypot(R->hi[0] - R->lo[0], R->hi[1] - R->lo[1]);
    for (int k = 0; k < R->n; k++) {
        double q[3] = {s[2 * k], s[2 * k + 1], 0.0};
        int kn = floe_kdtree_knn(R->tree, q, 2, R->nn, R->nd2);
        for (int h = 0; h < kn; h++) {
            int j = R->nn[h];
            double d = hypot(s[2 * j] - s[2 * k], s[2 * j + 1] - s[2 * k + 1]);
            if (j != k && d <= tol) {
                int a = j < k ? j : k, b = j < k ? k : j;
                return floe_error_set(err, errlen, FLOE_EINVAL,
                            "voronoi: seeds %d and %d coincide: (%.17g, %.17g) and (%.17g, %.17g) are %g apart "
                            "(at most %g = 1e-12 x the rectangle diagonal)",
                            a, b, s[2 * a], s[2 * a + 1], s[2 * b], s[2 * b + 1], d, tol);
            }
        }
    }
    return FLOE_OK;
}

/* the output's arrays for n cells (weights too when weighted), the seeds copied, and the
 * run's point buffer; the duplicate check on the seeds */
static int run_start(vor_run *R, const double *seeds, int n, int weighted, floe_voronoi *v, char *err, size_t errlen) {
    R->n = v->n = n;
    R->pts = malloc(3 * (size_t)n * sizeof *R->pts);
    v->start = malloc(((size_t)n + 1) * sizeof *v->start);
    v->seed = malloc(2 * (size_t)n * sizeof *v->seed);
    v->area = malloc((size_t)n * sizeof *v->area);
    v->centroid = malloc(2 * (size_t)n * sizeof *v->centroid);
    if (weighted) v->weight = calloc((size_t)n, sizeof *v->weight);
    if (!R->pts || !v->start || !v->seed || !v->area || !v->centroid || (weighted && !v->weight))
        return floe_error_set(err, errlen, FLOE_ENOMEM, "voronoi: out of memory");
    memcpy(v->seed, seeds, 2 * (size_t)n * sizeof *seeds);
    int rc = index_seeds(R, v->seed);
    if (rc == FLOE_ENOMEM) return floe_error_set(err, errlen, rc, "voronoi: out of memory");
    return check_duplicates(R, err, errlen);
}

/* index the seeds (when they moved), the weights R->w (power cells), and tessellate */
static int run_tessellate(vor_run *R, floe_voronoi *v, char *err, size_t errlen) {
    int rc = R->seeds == v->seed && !R->moved ? FLOE_OK : index_seeds(R, v->seed);
    R->moved = 0;
    if (rc == FLOE_OK && R->w) rc = index_weights(R);
    if (rc == FLOE_OK) rc = tessellate(R, v, err, errlen);
    if (rc == FLOE_ENOMEM) return floe_error_set(err, errlen, rc, "voronoi: out of memory");
    return rc;
}

/* shrink the corners to fit (keep the larger block if that fails) */
static void run_trim(floe_voronoi *v) {
    if (v->start[v->n] == 0) return;
    double *xy = realloc(v->xy, 2 * (size_t)v->start[v->n] * sizeof *xy);
    if (xy) v->xy = xy;
}

static void run_free(vor_run *R) {
    floe_kdtree_destroy(R->tree);
    floe_kdtree_destroy(R->lift);
    free(R->pts);
    free(R->hit);
    free(R->elab);
    cell_free(&R->c);
}

static int voronoi_run(vor_run *R, const double *seeds, int n, int iters, floe_voronoi *v, char *err, size_t errlen) {
    FLOE_TRY(run_start(R, seeds, n, 0, v, err, errlen));
    for (int it = 0;; it++) {
        FLOE_TRY(run_tessellate(R, v, err, errlen));
        if (it == iters) {
            run_trim(v);
            return FLOE_OK;
        }
        memcpy(v->seed, v->centroid, 2 * (size_t)n * sizeof *v->seed);
        R->moved = 1;
    }
}

int floe_voronoi_rect(const double lo[2], const double hi[2], const double *seeds, int n, int lloyd_iterations,
                      floe_voronoi *out, char *err, size_t errlen) {
    FLOE_TRY(check_input(lo, hi, seeds, n, out, err, errlen));
    if (lloyd_iterations < 0)
        return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: lloyd_iterations = %d is negative", lloyd_iterations);
    vor_run R = {.lo = {lo[0], lo[1]}, .hi = {hi[0], hi[1]}};
    int rc = voronoi_run(&R, seeds, n, lloyd_iterations, out, err, errlen);
    run_free(&R);
    if (rc != FLOE_OK) floe_voronoi_free(out);
    return rc;
}

int floe_voronoi_power_rect(const double lo[2], const double hi[2], const double *seeds, const double *weights, int n,
                            floe_voronoi *out, char *err, size_t errlen) {
    FLOE_TRY(check_input(lo, hi, seeds, n, out, err, errlen));
    if (!weights) return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: weights is NULL (n = %d)", n);
    for (int k = 0; k < n; k++)
        if (!isfinite(weights[k])) return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: weight %d = %g is not finite", k, weights[k]);
    vor_run R = {.lo = {lo[0], lo[1]}, .hi = {hi[0], hi[1]}};
    int rc = run_start(&R, seeds, n, 1, out, err, errlen);
    if (rc == FLOE_OK) {
        memcpy(out->weight, weights, (size_t)n * sizeof *weights);
        R.w = out->weight;
        rc = run_tessellate(&R, out, err, errlen);
    }
    if (rc == FLOE_OK) run_trim(out);
    run_free(&R);
    if (rc != FLOE_OK) floe_voronoi_free(out);
    return rc;
}

/* ---- power cells of prescribed areas: a damped Newton method on the weights ----
 *
 * The areas A_k(w) of the power cells are the gradient of a concave function of the
 * weights (Aurenhammer, Hoffmann & Aronov 1998), so the weights that give the areas a_k
 * maximise sum_k (a_k w_k) - that function; its Hessian dA/dw is the graph Laplacian of the
 * cells' adjacency with the entries
 *     dA_k/dw_j = -L_kj / (2 |s_k - s_j|)   (j != k, L_kj the length of the shared edge),
 *     dA_k/dw_k = sum_j L_kj / (2 |s_k - s_j|)
 * (moving the bisector of s_k and s_j by dw/(2|d|) sweeps L dw/(2|d|) of area). Each step
 * solves (dA/dw) dw = a - A by conjugate gradients (Jacobi-preconditioned, mean-free) and
 * takes w + tau dw with the largest tau = 2^-l that keeps every cell above
 * eps = min(min a, min A(w_0))/2 and lowers |A - a| by the factor 1 - tau/2: the damped
 * Newton method of Kitagawa, Merigot & Thibert (2019, J. Eur. Math. Soc. 21, 2603-2651),
 * which converges from any weights with nonempty cells, and quadratically near the
 * solution. Power cells of given areas with the seeds moved to the centroids between
 * solves are the capacity-constrained centroidal power diagrams of Balzer, Schloemer &
 * Deussen (2009) and de Goes et al. (2012). */

#define VOR_NEWTON_MAX 200
/* the conjugate gradients' relative residual: at most, and when a step fails */
#define VOR_CG_INEXACT 1e-3
#define VOR_CG_TOL 1e-9
/* the smallest step fraction of the line search */
#define VOR_TAU_MIN 1e-10

typedef struct vor_newton {
    int n, ne;
    double *b, *dw, *wt, *r, *z, *p, *q, *diag; /* n each */
    int *ek, *ej;
    double *ec;   /* ne entries of the Laplacian: (k, j, c) adds c to (k,k), (j,j), -c to (k,j), (j,k) */
    size_t cap_e;
} vor_newton;

static void newton_free(vor_newton *N) {
    double *d[] = {N->b, N->dw, N->wt, N->r, N->z, N->p, N->q, N->diag, N->ec};
    for (size_t i = 0; i < sizeof d / sizeof *d; i++) free(d[i]);
    free(N->ek);
    free(N->ej);
}

static int newton_alloc(vor_newton *N, int n) {
    N->n = n;
    double **d[] = {&N->b, &N->dw, &N->wt, &N->r, &N->z, &N->p, &N->q, &N->diag};
    for (size_t i = 0; i < sizeof d / sizeof *d; i++)
        if (!(*d[i] = malloc((size_t)n * sizeof **d[i]))) return FLOE_ENOMEM;
    return FLOE_OK;
}

/* dA/dw of the tessellation v: one entry per labelled edge, half its coefficient (each
 * shared edge is seen from both cells: the two halves average their lengths) */
static int newton_hessian(vor_newton *N, const vor_run *R, const floe_voronoi *v) {
    size_t need = (size_t)v->start[v->n];
    if (need > N->cap_e) {
        int *ek = realloc(N->ek, need * sizeof *ek), *ej = ek ? realloc(N->ej, need * sizeof *ej) : NULL;
        if (ek) N->ek = ek;
        if (ej) N->ej = ej;
        double *ec = ej ? realloc(N->ec, need * sizeof *ec) : NULL;
        if (!ec) return FLOE_ENOMEM;
        N->ec = ec;
        N->cap_e = need;
    }
    N->ne = 0;
    memset(N->diag, 0, (size_t)N->n * sizeof *N->diag);
    for (int k = 0; k < v->n; k++) {
        int a = v->start[k], m = v->start[k + 1] - a;
        for (int i = 0; i < m; i++) {
            int j = R->elab[a + i];
            if (j < 0) continue;
            const double *x0 = v->xy + 2 * (a + i), *x1 = v->xy + 2 * (a + (i + 1) % m);
            double L = hypot(x1[0] - x0[0], x1[1] - x0[1]);
            double d = hypot(v->seed[2 * j] - v->seed[2 * k], v->seed[2 * j + 1] - v->seed[2 * k + 1]);
            double c = 0.25 * L / d;
            N->ek[N->ne] = k;
            N->ej[N->ne] = j;
            N->ec[N->ne++] = c;
            N->diag[k] += c;
            N->diag[j] += c;
        }
    }
    return FLOE_OK;
}

/* q = (dA/dw + reg) x */
static void newton_apply(const vor_newton *N, double reg, const double *x, double *q) {
    for (int k = 0; k < N->n; k++) q[k] = reg * x[k];
    for (int e = 0; e < N->ne; e++) {
        int k = N->ek[e], j = N->ej[e];
        double t = N->ec[e] * (x[k] - x[j]);
        q[k] += t;
        q[j] -= t;
    }
}

static double dot(const double *a, const double *b, int n) {
    double s = 0;
    for (int k = 0; k < n; k++) s += a[k] * b[k];
    return s;
}

/* dw from (dA/dw) dw = b by preconditioned conjugate gradients, to the residual rtol |b|;
 * the Laplacian's null space (a constant added to every weight changes nothing) is held off
 * by a regularisation of 1e-12 x its largest diagonal, and b sums to zero */
static void newton_direction(vor_newton *N, double rtol) {
    int n = N->n;
    double reg = 0, bb = sqrt(dot(N->b, N->b, n));
    for (int k = 0; k < n; k++) reg = fmax(reg, N->diag[k]);
    reg *= 1e-12;
    memset(N->dw, 0, (size_t)n * sizeof *N->dw);
    memcpy(N->r, N->b, (size_t)n * sizeof *N->r);
    for (int k = 0; k < n; k++) N->p[k] = N->z[k] = N->r[k] / (N->diag[k] + reg);
    double rz = dot(N->r, N->z, n);
    int itmax = 200 + (int)(20 * sqrt((double)n));
    for (int it = 0; it < itmax && sqrt(dot(N->r, N->r, n)) > rtol * bb; it++) {
        newton_apply(N, reg, N->p, N->q);
        double pq = dot(N->p, N->q, n);
        if (!(pq > 0)) break;
        double al = rz / pq;
        for (int k = 0; k < n; k++) {
            N->dw[k] += al * N->p[k];
            N->r[k] -= al * N->q[k];
            N->z[k] = N->r[k] / (N->diag[k] + reg);
        }
        double rz1 = dot(N->r, N->z, n), be = rz1 / rz;
        rz = rz1;
        for (int k = 0; k < n; k++) N->p[k] = N->z[k] + be * N->p[k];
    }
}

/* |A - a| (2-norm), the worst relative error of an area, the smallest area */
static double area_misfit(const double *A, const double *a, int n, double *worst, double *amin) {
    double e2 = 0;
    *worst = 0;
    *amin = INFINITY;
    for (int k = 0; k < n; k++) {
        e2 += (A[k] - a[k]) * (A[k] - a[k]);
        *worst = fmax(*worst, fabs(A[k] - a[k]) / a[k]);
        *amin = fmin(*amin, A[k]);
    }
    return sqrt(e2);
}

/* the weights v->weight (a start with no empty cell) that give the cells the areas a to the
 * relative tolerance tol; v holds the last tessellation */
static int solve_areas(vor_run *R, floe_voronoi *v, const double *a, double tol, vor_newton *N, char *err,
                       size_t errlen) {
    int n = v->n;
    R->w = v->weight;
    FLOE_TRY(run_tessellate(R, v, err, errlen));
    if (R->nempty) { /* a warm start that lost a cell: start from the Voronoi cells */
        memset(v->weight, 0, (size_t)n * sizeof *v->weight);
        FLOE_TRY(run_tessellate(R, v, err, errlen));
        if (R->nempty) return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: %d cells are empty: seeds nearly coincide", R->nempty);
    }
    double worst, amin, amin_t = INFINITY;
    for (int k = 0; k < n; k++) amin_t = fmin(amin_t, a[k]);
    double res = area_misfit(v->area, a, n, &worst, &amin), eps = 0.5 * fmin(amin_t, amin);
    for (int it = 0; worst > tol; it++) {
        if (it == VOR_NEWTON_MAX)
            return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: the cell areas missed their targets by %.3g (relative) after %d Newton steps",
                        worst, it);
        if (newton_hessian(N, R, v) != FLOE_OK) return floe_error_set(err, errlen, FLOE_ENOMEM, "voronoi: out of memory");
        for (int k = 0; k < n; k++) N->b[k] = a[k] - v->area[k];
        /* an inexact Newton step (the linear residual below the area error, at most 1e-3);
         * should its line search fail, the same step solved to VOR_CG_TOL */
        double rtol = fmax(VOR_CG_TOL, fmin(VOR_CG_INEXACT, worst)), tau = 1, res_t = INFINITY, worst_t = 0;
        newton_direction(N, rtol);
        R->w = N->wt;
        for (;; tau *= 0.5) {
            if (tau < VOR_TAU_MIN && rtol > VOR_CG_TOL) {
                newton_direction(N, rtol = VOR_CG_TOL);
                tau = 1;
            } else if (tau < VOR_TAU_MIN)
                return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: the Newton step on the weights found no descent (area error %.3g)", worst);
            for (int k = 0; k < n; k++) N->wt[k] = v->weight[k] + tau * N->dw[k];
            FLOE_TRY(run_tessellate(R, v, err, errlen));
            res_t = area_misfit(v->area, a, n, &worst_t, &amin);
            if (!R->nempty && amin >= eps && res_t <= (1 - 0.5 * tau) * res) break;
        }
        memcpy(v->weight, N->wt, (size_t)n * sizeof *v->weight);
        R->w = v->weight;
        res = res_t;
        worst = worst_t;
    }
    return FLOE_OK;
}

static int areas_run(vor_run *R, const double *seeds, const double *areas, int n, int iters, double tol, floe_voronoi *v,
                     char *err, size_t errlen) {
    FLOE_TRY(run_start(R, seeds, n, 1, v, err, errlen));
    vor_newton N = {0};
    double *a = malloc((size_t)n * sizeof *a), sum = 0;
    int rc = a && newton_alloc(&N, n) == FLOE_OK ? FLOE_OK : floe_error_set(err, errlen, FLOE_ENOMEM, "voronoi: out of memory");
    if (rc == FLOE_OK) {
        for (int k = 0; k < n; k++) sum += areas[k];
        double scale = (R->hi[0] - R->lo[0]) * (R->hi[1] - R->lo[1]) / sum;
        for (int k = 0; k < n; k++) a[k] = areas[k] * scale;
    }
    for (int it = 0; rc == FLOE_OK; it++) {
        rc = solve_areas(R, v, a, tol, &N, err, errlen);
        if (rc != FLOE_OK || it == iters) break;
        memcpy(v->seed, v->centroid, 2 * (size_t)n * sizeof *v->seed);
        R->moved = 1;
    }
    if (rc == FLOE_OK) run_trim(v);
    newton_free(&N);
    free(a);
    return rc;
}

int floe_voronoi_areas(const double lo[2], const double hi[2], const double *seeds, const double *areas, int n,
                       int lloyd_iterations, double tol, floe_voronoi *out, char *err, size_t errlen) {
    FLOE_TRY(check_input(lo, hi, seeds, n, out, err, errlen));
    if (lloyd_iterations < 0)
        return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: lloyd_iterations = %d is negative", lloyd_iterations);
    if (!(tol > 0 && tol <= 0.5)) return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: tolerance %g is not in (0, 0.5]", tol);
    if (!areas) return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: areas is NULL (n = %d)", n);
    for (int k = 0; k < n; k++)
        if (!(isfinite(areas[k]) && areas[k] > 0))
            return floe_error_set(err, errlen, FLOE_EINVAL, "voronoi: area %d = %g is not a positive number", k, areas[k]);
    vor_run R = {.lo = {lo[0], lo[1]}, .hi = {hi[0], hi[1]}};
    int rc = areas_run(&R, seeds, areas, n, lloyd_iterations, tol, out, err, errlen);
    run_free(&R);
    if (rc != FLOE_OK) floe_voronoi_free(out);
    return rc;
}

void floe_voronoi_free(floe_voronoi *v) {
    if (!v) return;
    free(v->xy);
    free(v->start);
    free(v->seed);
    free(v->area);
    free(v->centroid);
    free(v->weight);
    memset(v, 0, sizeof *v);
}

int floe_voronoi_random_seeds(const double lo[2], const double hi[2], int n, unsigned long long seed, double *out) {
    if (check_rect(lo, hi, NULL, 0) != FLOE_OK || n < 1 || !out) return FLOE_EINVAL;
    for (int k = 0; k < n; k++)
        for (int a = 0; a < 2; a++) out[2 * k + a] = fmin(hi[a], lo[a] + (hi[a] - lo[a]) * floe_rng_uniform(&seed));
    return FLOE_OK;
}

int floe_voronoi_scale_cells(floe_voronoi *v, double s) {
    if (!v || !(s > 0 && s <= 1)) return FLOE_EINVAL;
    for (int k = 0; k < v->n; k++) {
        double *c = v->centroid + 2 * k, c0[2] = {c[0], c[1]};
        int m = v->start[k + 1] - v->start[k];
        if (m < 3) continue; /* an empty power cell */
        double *xy = v->xy + 2 * v->start[k];
        for (int i = 0; i < 2 * m; i++) xy[i] = c0[i & 1] + s * (xy[i] - c0[i & 1]);
        poly_moments(xy, m, c0, v->area + k, c);
    }
    return FLOE_OK;
}
