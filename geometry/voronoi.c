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
 * cell's radius, so ties (cocircular seeds of a lattice) neither loop nor split corners. */
#include "floe_voronoi.h"
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
/* seeds closer than this x the rectangle's diagonal are duplicates */
#define VOR_DUP_REL 1e-12
/* a seed cuts a corner when it is closer than s_k by more than this x the cell's radius */
#define VOR_TIE_REL 1e-12
/* corners closer than this x the cell's bounding-box diagonal are merged */
#define VOR_SHORT_EDGE_REL 1e-9
/* corners turning by less than this (sine of the angle) are dropped */
#define VOR_FLAT_SIN 1e-12

static int fail(char *err, size_t errlen, int code, const char *fmt, ...) {
    if (err && errlen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return code;
}

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
    c->cap = cap;
    return FLOE_OK;
}

static void cell_free(vor_cell *c) {
    free(c->p);
    free(c->q);
    free(c->ok);
    free(c->qok);
    free(c->used);
}

static void cell_radius(vor_cell *c) {
    double r2 = 0;
    for (int i = 0; i < c->m; i++) r2 = fmax(r2, c->p[2 * i] * c->p[2 * i] + c->p[2 * i + 1] * c->p[2 * i + 1]);
    c->r2max = r2;
}

/* clip by f(p) = p.d - |d|^2/2 <= 0 (Sutherland-Hodgman); the cell is left alone when no
 * corner is outside. Kept corners keep their checked flag; new ones are unchecked. */
static int cell_clip(vor_cell *c, const double d[2]) {
    double half = 0.5 * (d[0] * d[0] + d[1] * d[1]), fhi = -INFINITY;
    if (2 * half >= 4 * c->r2max) return FLOE_OK; /* bisector beyond every corner */
    for (int i = 0; i < c->m; i++) fhi = fmax(fhi, c->p[2 * i] * d[0] + c->p[2 * i + 1] * d[1] - half);
    if (fhi <= 0) return FLOE_OK;
    FLOE_TRY(cell_reserve(c, c->m + 1));
    int m = 0;
    for (int i = 0; i < c->m; i++) {
        int i1 = (i + 1) % c->m;
        const double *a = c->p + 2 * i, *b = c->p + 2 * i1;
        double fa = a[0] * d[0] + a[1] * d[1] - half, fb = b[0] * d[0] + b[1] * d[1] - half;
        if (fa <= 0) { c->q[2 * m] = a[0]; c->q[2 * m + 1] = a[1]; c->qok[m] = c->ok[i]; m++; }
        if ((fa <= 0) != (fb <= 0)) {
            double t = fa / (fa - fb);
            c->q[2 * m] = a[0] + t * (b[0] - a[0]);
            c->q[2 * m + 1] = a[1] + t * (b[1] - a[1]);
            c->qok[m] = 0;
            m++;
        }
    }
    double *t = c->p;
    c->p = c->q;
    c->q = t;
    unsigned char *tok = c->ok;
    c->ok = c->qok;
    c->qok = tok;
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
    int n;
    floe_kdtree *tree;
    double *pts;           /* 3n: the seeds with z = 0, for the tree */
    int nn[VOR_KNN];       /* k-NN result */
    double nd2[VOR_KNN];
    int *hit, cap_hit;     /* radius query result */
    vor_cell c;
    size_t cap_xy;         /* corners the output's xy array holds */
} vor_run;

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
        double f = p[0] * d[0] + p[1] * d[1] - 0.5 * (d[0] * d[0] + d[1] * d[1]);
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
    double rp = sqrt(p[0] * p[0] + p[1] * p[1]);
    /* the disc about v, widened for the rounding of v and of the tree's distances */
    double v[3] = {s[0] + p[0], s[1] + p[1], 0.0};
    double r = rp * (1 + 1e-9) + 1e-15 * (fabs(s[0]) + fabs(s[1]) + rp);
    int *hit = R->nn, cnt = floe_kdtree_knn(R->tree, v, VOR_KNN_CORNER, R->nn, R->nd2);
    int cut = closer_seeds(R, k, p, hit, cnt);
    if (cut == 0 && cnt == VOR_KNN_CORNER && R->nd2[cnt - 1] <= r * r) {
        while ((cnt = floe_kdtree_radius(R->tree, v, r, R->hit, R->cap_hit)) > R->cap_hit)
            FLOE_TRY(grow_int(&R->hit, &R->cap_hit, cnt));
        hit = R->hit;
        cut = closer_seeds(R, k, p, hit, cnt);
    }
    if (cut < 0) return -cut;
    if (cut == 0) { c->ok[i] = 1; return FLOE_OK; }
    for (int h = 0; h < cut; h++) {
        int j = hit[h];
        double d[2] = {R->seeds[2 * j] - s[0], R->seeds[2 * j + 1] - s[1]};
        FLOE_TRY(cell_clip(c, d));
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
        FLOE_TRY(cell_clip(c, d));
    }
    if (kn == R->n || R->nd2[kn - 1] >= 4 * c->r2max * (1 + 1e-9)) return FLOE_OK;
    for (int done = 0; !done;) FLOE_TRY(check_corner(R, k, &done));
    return FLOE_OK;
}

static double cross2(const double *a, const double *b, const double *o) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/* drop corner i of the cell */
static void cell_drop(vor_cell *c, int i) {
    memmove(c->p + 2 * i, c->p + 2 * i + 2, 2 * (size_t)(c->m - i - 1) * sizeof *c->p);
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
                cell_drop(c, i);
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
        R->cap_xy = cap;
    }
    double *xy = v->xy + 2 * at;
    for (int i = 0; i < c->m; i++)
        for (int a = 0; a < 2; a++) xy[2 * i + a] = fmin(R->hi[a], fmax(R->lo[a], s[a] + c->p[2 * i + a]));
    v->start[k + 1] = (int)(at + c->m);
    poly_moments(xy, c->m, s, v->area + k, v->centroid + 2 * k);
    return FLOE_OK;
}

/* the seeds into the k-d tree */
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

/* the Voronoi cells of the indexed seeds (v->seed) into v (xy, start, area, centroid) */
static int tessellate(vor_run *R, floe_voronoi *v, char *err, size_t errlen) {
    v->start[0] = 0;
    for (int k = 0; k < v->n; k++) {
        FLOE_TRY(cell_build(R, k));
        cell_clean(&R->c);
        if (R->c.m < 3)
            return fail(err, errlen, FLOE_EINVAL,
                        "voronoi: the cell of seed %d (%.17g, %.17g) degenerates to %d corners: seeds nearly coincide", k,
                        v->seed[2 * k], v->seed[2 * k + 1], R->c.m);
        FLOE_TRY(append_cell(R, v, k));
    }
    return FLOE_OK;
}

static int check_rect(const double lo[2], const double hi[2], char *err, size_t errlen) {
    if (!lo || !hi) return fail(err, errlen, FLOE_EINVAL, "voronoi: rectangle corners lo/hi are NULL");
    for (int a = 0; a < 2; a++) {
        if (!isfinite(lo[a]) || !isfinite(hi[a]))
            return fail(err, errlen, FLOE_EINVAL, "voronoi: rectangle lo = (%g, %g), hi = (%g, %g) is not finite", lo[0],
                        lo[1], hi[0], hi[1]);
        if (!(hi[a] > lo[a]))
            return fail(err, errlen, FLOE_EINVAL, "voronoi: rectangle has hi[%d] = %g <= lo[%d] = %g (empty)", a, hi[a], a,
                        lo[a]);
    }
    return FLOE_OK;
}

static int check_seeds(const double lo[2], const double hi[2], const double *seeds, int n, char *err, size_t errlen) {
    for (int k = 0; k < n; k++) {
        const double *s = seeds + 2 * k;
        if (!isfinite(s[0]) || !isfinite(s[1]))
            return fail(err, errlen, FLOE_EINVAL, "voronoi: seed %d = (%g, %g) is not finite", k, s[0], s[1]);
        if (s[0] < lo[0] || s[0] > hi[0] || s[1] < lo[1] || s[1] > hi[1])
            return fail(err, errlen, FLOE_EINVAL, "voronoi: seed %d = (%g, %g) is outside the rectangle [%g, %g] x [%g, %g]",
                        k, s[0], s[1], lo[0], hi[0], lo[1], hi[1]);
    }
    return FLOE_OK;
}

/* two (indexed) seeds closer than tol: the nearest other seed of each */
static int check_duplicates(vor_run *R, double tol, char *err, size_t errlen) {
    const double *s = R->seeds;
    for (int k = 0; k < R->n; k++) {
        double q[3] = {s[2 * k], s[2 * k + 1], 0.0};
        int kn = floe_kdtree_knn(R->tree, q, 2, R->nn, R->nd2);
        for (int h = 0; h < kn; h++) {
            int j = R->nn[h];
            double d = hypot(s[2 * j] - s[2 * k], s[2 * j + 1] - s[2 * k + 1]);
            if (j != k && d <= tol) {
                int a = j < k ? j : k, b = j < k ? k : j;
                return fail(err, errlen, FLOE_EINVAL,
                            "voronoi: seeds %d and %d coincide: (%.17g, %.17g) and (%.17g, %.17g) are %g apart "
                            "(at most %g = 1e-12 x the rectangle diagonal)",
                            a, b, s[2 * a], s[2 * a + 1], s[2 * b], s[2 * b + 1], d, tol);
            }
        }
    }
    return FLOE_OK;
}

static int voronoi_run(vor_run *R, const double *seeds, int n, int iters, floe_voronoi *v, char *err, size_t errlen) {
    double diag = hypot(R->hi[0] - R->lo[0], R->hi[1] - R->lo[1]);
    R->n = v->n = n;
    R->pts = malloc(3 * (size_t)n * sizeof *R->pts);
    v->start = malloc(((size_t)n + 1) * sizeof *v->start);
    v->seed = malloc(2 * (size_t)n * sizeof *v->seed);
    v->area = malloc((size_t)n * sizeof *v->area);
    v->centroid = malloc(2 * (size_t)n * sizeof *v->centroid);
    if (!R->pts || !v->start || !v->seed || !v->area || !v->centroid)
        return fail(err, errlen, FLOE_ENOMEM, "voronoi: out of memory");
    memcpy(v->seed, seeds, 2 * (size_t)n * sizeof *seeds);
    for (int it = 0;; it++) {
        int rc = index_seeds(R, v->seed);
        if (rc == FLOE_OK && it == 0) rc = check_duplicates(R, VOR_DUP_REL * diag, err, errlen);
        if (rc == FLOE_OK) rc = tessellate(R, v, err, errlen);
        if (rc == FLOE_ENOMEM) return fail(err, errlen, rc, "voronoi: out of memory");
        if (rc != FLOE_OK) return rc;
        if (it == iters) { /* shrink the corners to fit; keep the larger block if that fails */
            double *xy = realloc(v->xy, 2 * (size_t)v->start[n] * sizeof *xy);
            if (xy) v->xy = xy;
            return FLOE_OK;
        }
        memcpy(v->seed, v->centroid, 2 * (size_t)n * sizeof *v->seed);
    }
}
int floe_voronoi_rect(const double lo[2], const double hi[2], const double *seeds, int n, int lloyd_iterations,
                      floe_voronoi *out, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!out) return fail(err, errlen, FLOE_EINVAL, "voronoi: output is NULL");
    memset(out, 0, sizeof *out);
    FLOE_TRY(check_rect(lo, hi, err, errlen));
    if (n < 1 || n > VOR_MAX_SEEDS)
        return fail(err, errlen, FLOE_EINVAL, "voronoi: number of seeds n = %d is not in [1, %d]", n, VOR_MAX_SEEDS);
    if (!seeds) return fail(err, errlen, FLOE_EINVAL, "voronoi: seeds is NULL (n = %d)", n);
    if (lloyd_iterations < 0)
        return fail(err, errlen, FLOE_EINVAL, "voronoi: lloyd_iterations = %d is negative", lloyd_iterations);
    FLOE_TRY(check_seeds(lo, hi, seeds, n, err, errlen));
    vor_run R = {.lo = {lo[0], lo[1]}, .hi = {hi[0], hi[1]}};
    int rc = voronoi_run(&R, seeds, n, lloyd_iterations, out, err, errlen);
    floe_kdtree_destroy(R.tree);
    free(R.pts);
    free(R.hit);
    cell_free(&R.c);
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
        double *xy = v->xy + 2 * v->start[k];
        for (int i = 0; i < 2 * m; i++) xy[i] = c0[i & 1] + s * (xy[i] - c0[i & 1]);
        poly_moments(xy, m, c0, v->area + k, c);
    }
    return FLOE_OK;
}
