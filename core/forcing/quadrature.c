/* quadrature.c - area quadrature of a 2D shape in its body frame (floe_forcing.h): the
 * points over which the drag on a floe is integrated (force and torque).
 *   polygons: a fan of triangles from the centroid, each cut into level^2 similar triangles
 *             (upright and inverted ones), each by the 3-point rule exact for quadratics:
 *             3 level^2 points per edge, fourth order in the cell size for smooth integrands;
 *   unions of polygons (compound bodies whose pieces tile the shape): the same per piece;
 *   discs:    Gauss-Legendre in r (level nodes, weight r dr) x 8 level equal angles;
 *   any other bounded shape: the cells of a (8 level)^2 grid of its bounding square whose
 *             centre is inside (sdf < 0), weights scaled to its area. */
#include "floe_forcing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void floe_area_quadrature_free(floe_area_quadrature *q) {
    if (!q) return;
    free(q->x);
    free(q->w);
    memset(q, 0, sizeof *q);
}

static int qpush(floe_area_quadrature *q, int *cap, double x, double y, double w) {
    if (q->n == *cap) {
        int nc = *cap ? 2 * *cap : 64;
        double *nx = realloc(q->x, (size_t)nc * 3 * sizeof *nx);
        if (!nx) return FLOE_ENOMEM;
        q->x = nx;
        double *nw = realloc(q->w, (size_t)nc * sizeof *nw);
        if (!nw) return FLOE_ENOMEM;
        q->w = nw;
        *cap = nc;
    }
    q->x[3 * q->n] = x;
    q->x[3 * q->n + 1] = y;
    q->x[3 * q->n + 2] = 0;
    q->w[q->n++] = w;
    return FLOE_OK;
}

/* triangle (a, b, c) cut into m^2 similar triangles: the lattice a + (i u + j v)/m, u = b - a,
 * v = c - a; upright cells (i, j), (i+1, j), (i, j+1) and inverted ones (i+1, j), (i+1, j+1),
 * (i, j+1), all of area A / m^2; each by the 3-point rule exact for quadratics (barycentric
 * (2/3, 1/6, 1/6) and its permutations, weight 1/3 each: Strang & Fix 1973, table 4.1) */
static int tri_points(floe_area_quadrature *q, int *cap, const double *a, const double *b, const double *c, int m,
                      const double off[2], double cs, double sn) {
    double u[2] = {(b[0] - a[0]) / m, (b[1] - a[1]) / m}, v[2] = {(c[0] - a[0]) / m, (c[1] - a[1]) / m};
    double A = 0.5 * fabs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
    double w = A / ((double)m * m) / 3;
    /* the three points of a cell in lattice units, relative to its first corner */
    static const double up[3][2] = {{1.0 / 6, 1.0 / 6}, {2.0 / 3, 1.0 / 6}, {1.0 / 6, 2.0 / 3}};
    for (int i = 0; i < m; i++)
        for (int j = 0; i + j < m; j++) {
            for (int inv = 0; inv < 2; inv++) {
                if (inv && i + j + 1 >= m) continue;
                for (int k = 0; k < 3; k++) {
                    /* inverted cell: the upright one reflected through (i + 1/2, j + 1/2) */
                    double s = inv ? i + 1 - up[k][0] : i + up[k][0], t = inv ? j + 1 - up[k][1] : j + up[k][1];
                    double x = a[0] + s * u[0] + t * v[0], y = a[1] + s * u[1] + t * v[1];
                    /* into the body frame of the compound (piece pose: rotation cs, sn and offset) */
                    double X = off[0] + cs * x - sn * y, Y = off[1] + sn * x + cs * y;
                    FLOE_TRY(qpush(q, cap, X, Y, w));
                }
            }
        }
    return FLOE_OK;
}

/* a convex polygon (its 2D polytope view) in a frame rotated by (cs, sn) and offset */
static int polygon_points(floe_area_quadrature *q, int *cap, const floe_polytope_view *pv, int m, const double off[2],
                          double cs, double sn) {
    int nv = pv->nv;
    double cx = 0, cy = 0, A2 = 0; /* area centroid of the corners' polygon */
    for (int k = 0; k < nv; k++) {
        const double *p0 = pv->v + 3 * k, *p1 = pv->v + 3 * ((k + 1) % nv);
        double cr = p0[0] * p1[1] - p1[0] * p0[1];
        A2 += cr;
        cx += (p0[0] + p1[0]) * cr;
        cy += (p0[1] + p1[1]) * cr;
    }
    if (!(fabs(A2) > 0)) return FLOE_EINVAL;
    double c[2] = {cx / (3 * A2), cy / (3 * A2)};
    for (int k = 0; k < nv; k++) {
        const double *p0 = pv->v + 3 * k, *p1 = pv->v + 3 * ((k + 1) % nv);
        FLOE_TRY(tri_points(q, cap, c, p0, p1, m, off, cs, sn));
    }
    return FLOE_OK;
}

/* Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n from the Chebyshev guesses) */
static void gauss_legendre(int n, double *x, double *w) {
    for (int i = 0; i < n; i++) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1;
        for (int it = 0; it < 100; it++) {
            double p0 = 1, p1 = z;
            for (int k = 2; k <= n; k++) {
                double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            double pn = n == 1 ? z : p1, pm = n == 1 ? 1 : p0;
            dp = n * (z * pn - pm) / (z * z - 1);
            double dz = pn / dp;
            z -= dz;
            if (fabs(dz) < 1e-16) break;
        }
        x[i] = z;
        w[i] = 2 / ((1 - z * z) * dp * dp);
    }
}

static int disc_points(floe_area_quadrature *q, int *cap, double R, int level) {
    int nr = level + 1, na = 8 * level;
    double xg[65], wg[65];

    gauss_legendre(nr, xg, wg);
    for (int i = 0; i < nr; i++) {
        double r = 0.5 * R * (xg[i] + 1), wr = 0.5 * R * wg[i] * r; /* int_0^R g(r) r dr */
        for (int k = 0; k < na; k++) {
            double a = 2 * M_PI * (k + 0.5) / na;
            FLOE_TRY(qpush(q, cap, r * cos(a), r * sin(a), wr * 2 * M_PI / na));
        }
    }
    return FLOE_OK;
}

static int grid_points(floe_area_quadrature *q, int *cap, const floe_geometry *g, int level, double area) {
    double R = floe_geometry_bounding_radius(g);
    int m = 8 * level;
    double h = 2 * R / m, sum = 0;
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++) {
            double X[3] = {-R + (i + 0.5) * h, -R + (j + 0.5) * h, 0};
            if (floe_geometry_sdf(g, X) < 0) {
                FLOE_TRY(qpush(q, cap, X[0], X[1], h * h));
                sum += h * h;
            }
        }
    if (!(sum > 0)) return FLOE_EINVAL;
    for (int k = 0; k < q->n; k++) q->w[k] *= area / sum;
    return FLOE_OK;
}

int floe_area_quadrature_build(const floe_geometry *g, int level, floe_area_quadrature *q, char *err, size_t errlen) {
    memset(q, 0, sizeof *q);
    if (!g || level < 1 || level > 64) {
        snprintf(err, errlen, "area quadrature: %s", !g ? "no shape" : "the level must be in [1, 64]");
        return FLOE_EINVAL;
    }
    double R = floe_geometry_bounding_radius(g);
    if (!(R > 0) || !isfinite(R)) {
        snprintf(err, errlen, "area quadrature: the %s shape is unbounded", g->klass->name);
        return FLOE_EINVAL;
    }
    floe_mass_properties mp;
    int rc = floe_geometry_mass_properties(g, 2, 1.0, &mp);
    if (rc || !(mp.volume > 0)) {
        snprintf(err, errlen, "area quadrature: the %s shape has no area in the plane z = 0", g->klass->name);
        return rc ? rc : FLOE_EINVAL;
    }
    int cap = 0;
    const double zero[2] = {0, 0};
    floe_polytope_view pv;
    int np = floe_geometry_piece_count(g);
    if (floe_geometry_polytope(g, 2, &pv) && pv.nv >= 3) rc = polygon_points(q, &cap, &pv, level, zero, 1, 0);
    else if (g->klass->kind == FLOE_GEOM_SPHERE) rc = disc_points(q, &cap, ((const floe_sphere *)g)->radius, level);
    else if (np > 1 && g->klass->piece) {
        /* pieces that are polygons and tile the body (their areas add up to its area) */
        double asum = 0;
        int ok = 1;
        for (int k = 0; k < np && ok; k++) {
            double x[3], qq[4], r;
            const floe_geometry *pc = g->klass->piece(g, k, x, qq, &r);
            floe_mass_properties pm;
            ok = pc && floe_geometry_polytope(pc, 2, &pv) && pv.nv >= 3 && !floe_geometry_mass_properties(pc, 2, 1.0, &pm);
            if (!ok) break;
            asum += pm.volume;
            /* the piece's rotation about z: q = (cos a/2, 0, 0, sin a/2) */
            double a = 2 * atan2(qq[3], qq[0]);
            rc = polygon_points(q, &cap, &pv, level, x, cos(a), sin(a));
            if (rc) break;
        }
        if (rc == FLOE_OK && (!ok || fabs(asum - mp.volume) > 1e-9 * mp.volume)) {
            floe_area_quadrature_free(q);
            cap = 0;
            rc = grid_points(q, &cap, g, level, mp.volume);
        }
    } else rc = grid_points(q, &cap, g, level, mp.volume);
    if (rc) {
        floe_area_quadrature_free(q);
        snprintf(err, errlen, "area quadrature of the %s shape failed (%s)", g->klass->name,
                 rc == FLOE_ENOMEM ? "out of memory" : "no point inside it");
        return rc;
    }
    double sum = 0;
    for (int k = 0; k < q->n; k++) sum += q->w[k];
    q->area = sum;
    /* to its size: a field of floes keeps one per floe */
    double *nx = realloc(q->x, (size_t)q->n * 3 * sizeof *nx), *nw = nx ? realloc(q->w, (size_t)q->n * sizeof *nw) : NULL;
    if (nx) q->x = nx;
    if (nw) q->w = nw;
    return FLOE_OK;
}
