/* test_overlap2d: the overlap integrals of two convex polygons (contact/detect/overlap.c,
 * floe_overlap_pair2), which the overlap-area law and Hopkins' ridging law read for polygon
 * pairs, against independent computations:
 *   - area and I = (∫_O d_B + ∫_O d_A) / 2 against a fine midpoint grid over the overlap
 *     (d: the distance to the other polygon's boundary, min over its lines);
 *   - the load on A (force f, moment m) against central differences of I: f = -dI/dx_A,
 *     m = -dI/dθ_A (the integrals by regions and the divergence theorem must be the exact
 *     gradient of the energy, or edge-on-edge contacts would not conserve energy);
 *   - a flat overlap (two squares edge on edge): A = L d, I = L d^2 / 2 to round-off;
 *   - polygons apart or sharing an edge (a Voronoi field): no overlap, and a separating line;
 *   - all of this 300 km from the origin, where floes of a sea-ice field sit. */
#include "check.h"
#include "floe_overlap.h"

#include <stdlib.h>
#include <string.h>

#define MAXN 12

typedef struct poly {
    int n;
    double P[MAXN][2], L[MAXN][3];
} poly;

static double urand(unsigned *s) {
    *s = *s * 1664525u + 1013904223u;
    return (double)(*s >> 8) / 16777216.0;
}

static void set_lines(poly *p) {
    for (int k = 0; k < p->n; k++) {
        const double *a = p->P[k], *b = p->P[(k + 1) % p->n];
        double dx = b[0] - a[0], dy = b[1] - a[1], l = sqrt(dx * dx + dy * dy);
        p->L[k][0] = dy / l;
        p->L[k][1] = -dx / l;
        p->L[k][2] = p->L[k][0] * a[0] + p->L[k][1] * a[1];
    }
}

/* corners on an ellipse at sorted random angles (convex, counter-clockwise) */
static void random_poly(poly *p, int n, double cx, double cy, double r, unsigned *s) {
    double ang[MAXN];
    for (int k = 0; k < n; k++) ang[k] = 2 * M_PI * ((double)k + 0.8 * urand(s)) / n;
    const double e = 0.6 + 0.4 * urand(s), rot = 2 * M_PI * urand(s);
    p->n = n;
    for (int k = 0; k < n; k++) {
        double x = r * cos(ang[k]), y = e * r * sin(ang[k]);
        p->P[k][0] = cx + cos(rot) * x - sin(rot) * y;
        p->P[k][1] = cy + sin(rot) * x + cos(rot) * y;
    }
    set_lines(p);
}

/* p moved by (dx, dy) and turned by th about (ox, oy) */
static void moved(const poly *p, double dx, double dy, double th, double ox, double oy, poly *q) {
    q->n = p->n;
    for (int k = 0; k < p->n; k++) {
        double x = p->P[k][0] - ox, y = p->P[k][1] - oy;
        q->P[k][0] = ox + cos(th) * x - sin(th) * y + dx;
        q->P[k][1] = oy + sin(th) * x + cos(th) * y + dy;
    }
    set_lines(q);
}

/* both polygons relative to (ox, oy), as detection hands them over */
static int pair(const poly *a, const poly *b, double ox, double oy, floe_overlap2 *out) {
    poly A = *a, B = *b;
    for (int k = 0; k < A.n; k++) { A.P[k][0] -= ox; A.P[k][1] -= oy; }
    for (int k = 0; k < B.n; k++) { B.P[k][0] -= ox; B.P[k][1] -= oy; }
    set_lines(&A);
    set_lines(&B);
    return floe_overlap_pair2(A.P, A.n, A.L, A.n, B.P, B.n, B.L, B.n, out);
}

static double depth(const poly *p, double x, double y) {
    double d = INFINITY;
    for (int k = 0; k < p->n; k++) {
        double v = p->L[k][2] - p->L[k][0] * x - p->L[k][1] * y;
        d = v < d ? v : d;
    }
    return d;
}

/* midpoint grid over the common part of the two bounding boxes: area and I of the overlap */
static void grid_integrals(const poly *a, const poly *b, int m, double *area, double *I) {
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY}, lb[2] = {INFINITY, INFINITY},
           hb[2] = {-INFINITY, -INFINITY};
    for (int k = 0; k < a->n; k++)
        for (int c = 0; c < 2; c++) {
            lo[c] = fmin(lo[c], a->P[k][c]);
            hi[c] = fmax(hi[c], a->P[k][c]);
        }
    for (int k = 0; k < b->n; k++)
        for (int c = 0; c < 2; c++) {
            lb[c] = fmin(lb[c], b->P[k][c]);
            hb[c] = fmax(hb[c], b->P[k][c]);
        }
    for (int c = 0; c < 2; c++) {
        lo[c] = fmax(lo[c], lb[c]);
        hi[c] = fmin(hi[c], hb[c]);
    }
    const double hx = (hi[0] - lo[0]) / m, hy = (hi[1] - lo[1]) / m;
    double A = 0, S = 0;
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++) {
            double x = lo[0] + (i + 0.5) * hx, y = lo[1] + (j + 0.5) * hy;
            double da = depth(a, x, y), db = depth(b, x, y);
            if (da > 0 && db > 0) {
                A += 1;
                S += 0.5 * (da + db);
            }
        }
    *area = A * hx * hy;
    *I = S * hx * hy;
}

int main(void) {
    unsigned seed = 12345u;
    const double X0 = 3.0e5, Y0 = -2.0e5; /* a sea-ice field's coordinates, m */
    int tested = 0;
    double worst_area = 0, worst_I = 0, worst_f = 0, worst_m = 0;
    for (int t = 0; t < 40; t++) {
        poly a, b;
        const double r = 2000.0 + 3000.0 * urand(&seed);
        random_poly(&a, 3 + (int)(7 * urand(&seed)), X0, Y0, r, &seed);
        /* b's centre at a distance that makes them overlap partly (from a shallow edge
         * contact to a deep one) */
        const double rb = r * (0.5 + urand(&seed)), ang = 2 * M_PI * urand(&seed);
        const double dist = (0.3 + 0.5 * urand(&seed)) * (r + rb);
        random_poly(&b, 3 + (int)(7 * urand(&seed)), X0 + dist * cos(ang), Y0 + dist * sin(ang), rb, &seed);
        floe_overlap2 ov;
        if (pair(&a, &b, X0, Y0, &ov) != 1) continue;
        tested++;
        double ga, gI;
        grid_integrals(&a, &b, 1000, &ga, &gI);
        /* the grid: an error of about the cells along the boundary over all cells */
        worst_area = fmax(worst_area, fabs(ov.area - ga) / ga);
        worst_I = fmax(worst_I, fabs(ov.I - gI) / gI);
        /* the load on A against central differences of I (about A's first corner for the
         * moment: the turn is about it) */
        const double h = 1e-6 * r, th = 1e-8;
        const double ox = a.P[0][0], oy = a.P[0][1];
        floe_overlap2 p1, m1;
        poly a1;
        double fd[2], fm;
        for (int c = 0; c < 2; c++) {
            moved(&a, c == 0 ? h : 0, c == 1 ? h : 0, 0, 0, 0, &a1);
            pair(&a1, &b, X0, Y0, &p1);
            moved(&a, c == 0 ? -h : 0, c == 1 ? -h : 0, 0, 0, 0, &a1);
            pair(&a1, &b, X0, Y0, &m1);
            fd[c] = -(p1.I - m1.I) / (2 * h);
        }
        moved(&a, 0, 0, th, ox, oy, &a1);
        pair(&a1, &b, X0, Y0, &p1);
        moved(&a, 0, 0, -th, ox, oy, &a1);
        pair(&a1, &b, X0, Y0, &m1);
        fm = -(p1.I - m1.I) / (2 * th);
        /* the analytic moment about the frame's origin (X0, Y0), moved to A's corner */
        const double rx = ox - X0, ry = oy - Y0;
        const double m_o = ov.m - (rx * ov.f[1] - ry * ov.f[0]);
        const double fs = hypot(ov.f[0], ov.f[1]);
        worst_f = fmax(worst_f, hypot(ov.f[0] - fd[0], ov.f[1] - fd[1]) / fs);
        worst_m = fmax(worst_m, fabs(m_o - fm) / (fs * r));
    }
    CHECK(tested >= 30, "only %d of 40 random pairs overlapped", tested);
    printf("  %d random convex pairs (3-9 corners, 2-5 km, 300 km from the origin)\n", tested);
    CHECK_NEAR(worst_area, 0.0, 5e-4, "overlap area vs a 1000^2 grid: worst relative error");
    CHECK_NEAR(worst_I, 0.0, 5e-4, "I vs a 1000^2 grid: worst relative error");
    CHECK_NEAR(worst_f, 0.0, 1e-6, "force = -dI/dx (central differences): worst rel.");
    CHECK_NEAR(worst_m, 0.0, 1e-5, "moment = -dI/dtheta (central differences): worst rel.");

    /* flat overlap: a square A of side L and a taller rectangle B edge on edge, overlapping by
     * d: the strip d x L whose ends are A's top and bottom edges. d_B = d - u (u: depth into
     * B's left edge) gives I_AB = L d^2 / 2; d_A = min(u, v, L - v) (v along the strip) gives
     * I_BA = L d^2 / 2 - d^3 / 3 (a triangle's worth less at each end); so I = L d^2 / 2 -
     * d^3 / 6 and the force on A is -dI/dd = -(L d - d^2 / 2) along x, none across. */
    {
        const double L = 4000, d = 3.7, s = 900;
        poly a = {4, {{X0, Y0}, {X0 + L, Y0}, {X0 + L, Y0 + L}, {X0, Y0 + L}}, {{0}}};
        poly b = {4, {{X0 + L - d, Y0 - s}, {X0 + 2 * L - d, Y0 - s}, {X0 + 2 * L - d, Y0 + s + L}, {X0 + L - d, Y0 + s + L}}, {{0}}};
        set_lines(&a);
        set_lines(&b);
        floe_overlap2 ov;
        CHECK(pair(&a, &b, X0 + 0.5 * L, Y0 + 0.5 * L, &ov) == 1, "flat overlap found");
        CHECK_NEAR(ov.area, L * d, 1e-10, "flat overlap: area = L d");
        CHECK_NEAR(ov.I, L * d * d / 2 - d * d * d / 6, 1e-10, "flat overlap: I = L d^2/2 - d^3/6");
        CHECK_NEAR(ov.f[0], -(L * d - d * d / 2), 1e-10, "flat overlap: force on A = -(L d - d^2/2) along x");
        CHECK(fabs(ov.f[1]) <= 1e-10 * L * d, "flat overlap: no force across (%g)", ov.f[1]);
        /* apart by 1 m, then sharing the edge exactly (a Voronoi field's neighbours) */
        poly c = b;
        for (int k = 0; k < 4; k++) c.P[k][0] += d + 1.0;
        set_lines(&c);
        CHECK(pair(&a, &c, X0, Y0, &ov) == 0 && ov.area == 0, "apart: no overlap");
        poly A0 = a, C0 = c;
        for (int k = 0; k < 4; k++) { A0.P[k][0] -= X0; A0.P[k][1] -= Y0; C0.P[k][0] -= X0; C0.P[k][1] -= Y0; }
        set_lines(&A0);
        set_lines(&C0);
        int ax = floe_overlap_axis2(A0.P, 4, A0.L, 4, C0.P, 4, C0.L, 4, 1e-6);
        CHECK(ax == 2, "apart: the separating line is A's right edge (line 2), got %d", ax);
        CHECK(floe_overlap_pen2(C0.P, 4, A0.L[ax - 1]) <= -1.0 + 1e-9, "apart: B's corners 1 m behind it");
        for (int k = 0; k < 4; k++) c.P[k][0] -= 1.0;
        set_lines(&c);
        CHECK(pair(&a, &c, X0, Y0, &ov) == 0, "sharing an edge: touching, no overlap (area %g)", ov.area);
    }
    return check_summary("test_overlap2d");
}
