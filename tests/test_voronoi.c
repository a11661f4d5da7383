/* test_voronoi.c - the Voronoi tessellation of a rectangle (geometry/voronoi.c): cell areas
 * tile the rectangle; every cell convex, CCW, holding its seed, its corners no farther from
 * its seed than from any other (brute force); a lattice gives exact squares; Lloyd lowers
 * the quantization energy at every step and evens the areas; seeds on the boundary,
 * collinear seeds, n = 1; every invalid input refused with a message; shrinking the cells
 * scales the areas by s^2. Prints (does not assert) the time of 20,000 cells, 5 Lloyd
 * iterations. */
#include "check.h"
#include "floe_base.h"
#include "floe_rng.h"
#include "floe_voronoi.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int cell_m(const floe_voronoi *v, int k) { return v->start[k + 1] - v->start[k]; }
static const double *cell_xy(const floe_voronoi *v, int k) { return v->xy + 2 * v->start[k]; }

/* shoelace area of a polygon (coordinates relative to its first corner) */
static double poly_area(const double *xy, int m) {
    double A2 = 0;
    for (int i = 1; i + 1 < m; i++) {
        const double *p = xy + 2 * i, *q = xy + 2 * (i + 1);
        A2 += (p[0] - xy[0]) * (q[1] - xy[1]) - (p[1] - xy[1]) * (q[0] - xy[0]);
    }
    return 0.5 * A2;
}

/* int_P |x - s|^2 dA, exact: fan of triangles (s, a, b), each
 * cross(a, b) / 12 (|a|^2 + a.b + |b|^2) with a, b relative to s */
static double poly_energy(const double *xy, int m, const double s[2]) {
    double E = 0;
    for (int i = 0; i < m; i++) {
        const double *p = xy + 2 * i, *q = xy + 2 * ((i + 1) % m);
        double ax = p[0] - s[0], ay = p[1] - s[1], bx = q[0] - s[0], by = q[1] - s[1];
        E += (ax * by - ay * bx) / 12 * (ax * ax + ay * ay + ax * bx + ay * by + bx * bx + by * by);
    }
    return E;
}

static double energy(const floe_voronoi *v) {
    double E = 0;
    for (int k = 0; k < v->n; k++) E += poly_energy(cell_xy(v, k), cell_m(v, k), v->seed + 2 * k);
    return E;
}

static double area_cv(const floe_voronoi *v) {
    double m = 0, m2 = 0;
    for (int k = 0; k < v->n; k++) { m += v->area[k]; m2 += v->area[k] * v->area[k]; }
    m /= v->n;
    return sqrt(fmax(0, m2 / v->n - m * m)) / m;
}

static double rect_area(const double lo[2], const double hi[2]) { return (hi[0] - lo[0]) * (hi[1] - lo[1]); }

/* worst violations over all cells, relative to the domain size D: convexity and
 * orientation (the smallest turn cross(e_i, e_i+1) / |e_i||e_i+1|, must be > 0), seed
 * inside (how far outside an edge it lies), corners outside the rectangle, and the
 * count of cells with fewer than 3 corners */
typedef struct shape_report { double min_turn, seed_out, rect_out; int few; } shape_report;

static shape_report cell_shapes(const floe_voronoi *v, const double lo[2], const double hi[2]) {
    shape_report r = {INFINITY, 0, 0, 0};
    double D = hypot(hi[0] - lo[0], hi[1] - lo[1]);
    for (int k = 0; k < v->n; k++) {
        int m = cell_m(v, k);
        const double *xy = cell_xy(v, k), *s = v->seed + 2 * k;
        if (m < 3) { r.few++; continue; }
        for (int i = 0; i < m; i++) {
            const double *a = xy + 2 * i, *b = xy + 2 * ((i + 1) % m), *c = xy + 2 * ((i + 2) % m);
            double ex = b[0] - a[0], ey = b[1] - a[1], fx = c[0] - b[0], fy = c[1] - b[1];
            r.min_turn = fmin(r.min_turn, (ex * fy - ey * fx) / (hypot(ex, ey) * hypot(fx, fy)));
            /* signed distance of the seed to the right of edge a->b (outside) */
            double out = -(ex * (s[1] - a[1]) - ey * (s[0] - a[0])) / hypot(ex, ey);
            r.seed_out = fmax(r.seed_out, out / D);
            for (int t = 0; t < 2; t++) r.rect_out = fmax(r.rect_out, fmax(lo[t] - a[t], a[t] - hi[t]) / D);
        }
    }
    return r;
}

static void check_shapes(const char *what, const floe_voronoi *v, const double lo[2], const double hi[2]) {
    shape_report r = cell_shapes(v, lo, hi);
    CHECK(r.few == 0, "%s: %d cells with fewer than 3 corners", what, r.few);
    CHECK(r.min_turn > 0, "%s: a cell is not strictly convex and CCW (smallest turn sine %g)", what, r.min_turn);
    CHECK(r.seed_out <= 1e-9, "%s: a seed lies %g x D outside its cell (tol 1e-9)", what, r.seed_out);
    CHECK(r.rect_out <= 0, "%s: a corner lies %g x D outside the rectangle", what, r.rect_out);
    printf("  %-52s turn >= %.2e, seed out %.1e, %d few\n", what, r.min_turn, r.seed_out, r.few);
}

/* sum of the areas, from v->area and from the corners, against the rectangle */
static void check_tiling(const char *what, const floe_voronoi *v, const double lo[2], const double hi[2]) {
    double sa = 0, sp = 0, worst = 0;
    for (int k = 0; k < v->n; k++) {
        double a = poly_area(cell_xy(v, k), cell_m(v, k));
        sa += v->area[k];
        sp += a;
        worst = fmax(worst, fabs(a - v->area[k]) / fabs(a));
    }
    char buf[160];
    snprintf(buf, sizeof buf, "%s: sum of areas / rectangle (tol 1e-9)", what);
    CHECK_NEAR(sa, rect_area(lo, hi), 1e-9, buf);
    snprintf(buf, sizeof buf, "%s: sum of polygon areas / rectangle (tol 1e-9)", what);
    CHECK_NEAR(sp, rect_area(lo, hi), 1e-9, buf);
    CHECK(worst <= 1e-12, "%s: area[k] differs from its polygon's by %g (tol 1e-12)", what, worst);
}

static void test_area_sums(void) {
    const double lo[2] = {-2.0, 1.0}, hi[2] = {3.0, 4.5};
    const int ns[] = {1, 2, 100, 5000};
    for (int t = 0; t < 4; t++) {
        int n = ns[t];
        double *s = malloc(2 * (size_t)n * sizeof *s);
        CHECK(floe_voronoi_random_seeds(lo, hi, n, 42 + t, s) == FLOE_OK, "random seeds");
        floe_voronoi v;
        char err[256], what[64];
        int rc = floe_voronoi_rect(lo, hi, s, n, 0, &v, err, sizeof err);
        CHECK(rc == FLOE_OK, "n = %d: %s", n, err);
        if (rc == FLOE_OK) {
            snprintf(what, sizeof what, "random n = %d", n);
            check_tiling(what, &v, lo, hi);
            check_shapes(what, &v, lo, hi);
            if (n == 1) {
                CHECK(cell_m(&v, 0) == 4, "n = 1: the cell is the rectangle (4 corners), got %d", cell_m(&v, 0));
                CHECK(fabs(v.centroid[0] - 0.5) < 1e-12 && fabs(v.centroid[1] - 2.75) < 1e-12,
                      "n = 1: centroid (%g, %g), expected (0.5, 2.75)", v.centroid[0], v.centroid[1]);
            }
        }
        floe_voronoi_free(&v);
        free(s);
    }
}

/* every corner of cell k at least as close to s_k as to any s_j (tol 1e-9 D) */
static void brute_force(const char *what, const double lo[2], const double hi[2], const double *s, int n) {
    const double D = hypot(hi[0] - lo[0], hi[1] - lo[1]);
    floe_voronoi v;
    char err[256];
    int rc = floe_voronoi_rect(lo, hi, s, n, 0, &v, err, sizeof err);
    CHECK(rc == FLOE_OK, "%s: %s", what, err);
    if (rc != FLOE_OK) return;
    double worst = 0;
    for (int k = 0; k < n; k++)
        for (int i = 0; i < cell_m(&v, k); i++) {
            const double *x = cell_xy(&v, k) + 2 * i;
            double dk = hypot(x[0] - s[2 * k], x[1] - s[2 * k + 1]);
            for (int j = 0; j < n; j++) worst = fmax(worst, (dk - hypot(x[0] - s[2 * j], x[1] - s[2 * j + 1])) / D);
        }
    CHECK(worst <= 1e-9, "%s: a corner is %g x D closer to another seed than to its own (tol 1e-9)", what, worst);
    char line[160];
    snprintf(line, sizeof line, "%s: corner nearer another seed, / D", what);
    printf("  %-52s %.2e (tol 1e-9)\n", line, worst);
    check_shapes(what, &v, lo, hi);
    check_tiling(what, &v, lo, hi);
    floe_voronoi_free(&v);
}

static void test_brute_force(void) {
    const double lo[2] = {0, 0}, hi[2] = {2.0, 1.0};
    const int n = 300;
    double s[2 * 300];
    floe_voronoi_random_seeds(lo, hi, n, 7, s);
    brute_force("n = 300 even", lo, hi, s, n);
    /* three clusters of widths 0.1, 1e-3, 1e-5 (the seeds' nearest neighbours all inside
     * their cluster: the cells at a cluster's rim reach far) */
    unsigned long long st = 9;
    for (int k = 0; k < n; k++) {
        double w = k % 3 == 0 ? 0.1 : k % 3 == 1 ? 1e-3 : 1e-5, cx = 0.3 + 0.7 * (k % 3);
        s[2 * k] = cx + w * (floe_rng_uniform(&st) - 0.5);
        s[2 * k + 1] = 0.5 + w * (floe_rng_uniform(&st) - 0.5);
    }
    brute_force("n = 300 in 3 clusters (0.1, 1e-3, 1e-5 wide)", lo, hi, s, n);
    /* nearly collinear: y = 0.5 + 1e-6 u */
    for (int k = 0; k < n; k++) {
        s[2 * k] = 2.0 * floe_rng_uniform(&st);
        s[2 * k + 1] = 0.5 + 1e-6 * floe_rng_uniform(&st);
    }
    brute_force("n = 300 on y = 0.5 + 1e-6 u", lo, hi, s, n);
}

/* a lattice of seeds at the centres of a grid of h x h squares: each cell is that square */
static void test_lattice(void) {
    const double h = 0.25, lo[2] = {-1.0, 2.0};
    const int nx = 12, ny = 7, n = nx * ny;
    const double hi[2] = {lo[0] + nx * h, lo[1] + ny * h};
    double s[2 * 12 * 7];
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            s[2 * (i + nx * j)] = lo[0] + (i + 0.5) * h;
            s[2 * (i + nx * j) + 1] = lo[1] + (j + 0.5) * h;
        }
    floe_voronoi v;
    char err[256];
    CHECK(floe_voronoi_rect(lo, hi, s, n, 0, &v, err, sizeof err) == FLOE_OK, "lattice: %s", err);
    double worst_area = 0, worst_corner = 0;
    int not4 = 0;
    for (int k = 0; k < n; k++) {
        worst_area = fmax(worst_area, fabs(v.area[k] - h * h) / (h * h));
        if (cell_m(&v, k) != 4) { not4++; continue; }
        /* each corner is s + (+-h/2, +-h/2) */
        for (int i = 0; i < 4; i++) {
            const double *x = cell_xy(&v, k) + 2 * i;
            double ex = fabs(fabs(x[0] - s[2 * k]) - 0.5 * h), ey = fabs(fabs(x[1] - s[2 * k + 1]) - 0.5 * h);
            worst_corner = fmax(worst_corner, fmax(ex, ey) / h);
        }
    }
    CHECK(not4 == 0, "lattice: %d cells are not 4-cornered", not4);
    CHECK(worst_area <= 1e-12, "lattice: cell area off by %g relative (tol 1e-12)", worst_area);
    CHECK(worst_corner <= 1e-12, "lattice: a corner is off by %g x h (tol 1e-12)", worst_corner);
    printf("  %-52s area %.1e, corners %.1e (tol 1e-12)\n", "lattice 12 x 7: squares of side 0.25", worst_area,
           worst_corner);
    /* Lloyd leaves a centroidal lattice where it is (tol 1e-12 h) */
    floe_voronoi w;
    CHECK(floe_voronoi_rect(lo, hi, s, n, 3, &w, err, sizeof err) == FLOE_OK, "lattice Lloyd: %s", err);
    double moved = 0;
    for (int i = 0; i < 2 * n; i++) moved = fmax(moved, fabs(w.seed[i] - s[i]) / h);
    CHECK(moved <= 1e-12, "lattice: Lloyd moved a seed by %g x h (tol 1e-12)", moved);
    floe_voronoi_free(&w);
    floe_voronoi_free(&v);
}

/* Lloyd: energy non-increasing (chained single steps), the 30-step call equals the chain,
 * and the area spread drops */
static void test_lloyd(void) {
    const double lo[2] = {0, 0}, hi[2] = {1.0, 1.5};
    const int n = 500, iters = 30;
    double *s = malloc(2 * n * sizeof *s);
    floe_voronoi_random_seeds(lo, hi, n, 2024, s);
    floe_voronoi v, w;
    char err[256];
    CHECK(floe_voronoi_rect(lo, hi, s, n, 0, &v, err, sizeof err) == FLOE_OK, "Lloyd: %s", err);
    double E0 = energy(&v), cv0 = area_cv(&v), Eprev = E0, worst_rise = -INFINITY;
    for (int it = 1; it <= iters; it++) {
        CHECK(floe_voronoi_rect(lo, hi, v.centroid, n, 0, &w, err, sizeof err) == FLOE_OK, "Lloyd step %d: %s", it, err);
        double E = energy(&w);
        worst_rise = fmax(worst_rise, (E - Eprev) / Eprev);
        Eprev = E;
        floe_voronoi_free(&v);
        v = w;
    }
    CHECK(worst_rise <= 1e-13, "Lloyd: the energy rose by %g relative in a step (tol 1e-13)", worst_rise);
    printf("  %-52s %.6g -> %.6g, largest step change %+.2e\n", "Lloyd energy, 30 steps", E0, Eprev, worst_rise);
    CHECK(Eprev < 0.9 * E0, "Lloyd: energy %g after 30 steps is not below 0.9 x the first %g", Eprev, E0);
    floe_voronoi u;
    CHECK(floe_voronoi_rect(lo, hi, s, n, iters, &u, err, sizeof err) == FLOE_OK, "Lloyd 30: %s", err);
    double diff = 0;
    for (int i = 0; i < 2 * n; i++) diff = fmax(diff, fabs(u.seed[i] - v.seed[i]));
    CHECK(diff == 0, "Lloyd: 30 iterations in one call differ from 30 chained calls by %g", diff);
    double cv = area_cv(&u);
    CHECK(cv < cv0, "Lloyd: area coefficient of variation %g after 30 steps is not below %g", cv, cv0);
    printf("  %-52s %.4f -> %.4f\n", "cell-area coefficient of variation", cv0, cv);
    check_tiling("Lloyd 30", &u, lo, hi);
    check_shapes("Lloyd 30", &u, lo, hi);
    floe_voronoi_free(&u);
    floe_voronoi_free(&v);
    free(s);
}

/* seeds on the boundary and corners, collinear seeds (on a line across, on an edge, on a
 * diagonal), and seeds from a narrow rectangle */
static void test_awkward(void) {
    char err[256];
    floe_voronoi v;
    const double lo[2] = {0, 0}, hi[2] = {1, 1};
    /* corners, edge midpoints and the centre: squares and half squares */
    double b[] = {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0, 1, 0.5, 0.5, 1, 0, 0.5, 0.5, 0.5, 0.25, 0};
    CHECK(floe_voronoi_rect(lo, hi, b, 9, 0, &v, err, sizeof err) == FLOE_OK, "boundary seeds: %s", err);
    check_tiling("seeds on corners, edges, centre", &v, lo, hi);
    check_shapes("seeds on corners, edges, centre", &v, lo, hi);
    CHECK_NEAR(v.area[0], 0.0625, 1e-12, "corner seed's cell [0, 1/4]^2 (tol 1e-12)");
    CHECK_NEAR(v.area[4], 0.125, 1e-12, "edge seed's cell [1/4, 3/4] x [0, 1/4] (tol 1e-12)");
    CHECK_NEAR(v.area[8], 0.25, 1e-12, "centre seed's cell [1/4, 3/4]^2 (tol 1e-12)");
    floe_voronoi_free(&v);
    CHECK(floe_voronoi_rect(lo, hi, b, 10, 0, &v, err, sizeof err) == FLOE_OK, "boundary seeds: %s", err);
    check_tiling("seeds on corners and edges", &v, lo, hi);
    check_shapes("seeds on corners and edges", &v, lo, hi);
    floe_voronoi_free(&v);
    CHECK(floe_voronoi_rect(lo, hi, b, 10, 5, &v, err, sizeof err) == FLOE_OK, "boundary seeds, Lloyd: %s", err);
    check_tiling("seeds on corners and edges, 5 Lloyd", &v, lo, hi);
    floe_voronoi_free(&v);

    /* 200 seeds on y = 0.3, on the edge y = 0, on the diagonal: strips */
    const int n = 200;
    double *s = malloc(2 * n * sizeof *s);
    const char *name[3] = {"collinear on y = 0.3", "collinear on the edge y = 0", "collinear on the diagonal"};
    for (int t = 0; t < 3; t++) {
        for (int k = 0; k < n; k++) {
            double x = (k + 0.5) / n;
            s[2 * k] = x;
            s[2 * k + 1] = t == 0 ? 0.3 : t == 1 ? 0.0 : x;
        }
        CHECK(floe_voronoi_rect(lo, hi, s, n, 0, &v, err, sizeof err) == FLOE_OK, "%s: %s", name[t], err);
        check_tiling(name[t], &v, lo, hi);
        check_shapes(name[t], &v, lo, hi);
        if (t < 2) {
            double worst = 0;
            for (int k = 0; k < n; k++) worst = fmax(worst, fabs(v.area[k] * n - 1));
            CHECK(worst <= 1e-12, "%s: a strip's area is off by %g relative (tol 1e-12)", name[t], worst);
        }
        floe_voronoi_free(&v);
    }
    free(s);

    /* a long thin rectangle (aspect 1e4) */
    const double tlo[2] = {0, 0}, thi[2] = {1e4, 1};
    double *r = malloc(2 * 1000 * sizeof *r);
    floe_voronoi_random_seeds(tlo, thi, 1000, 3, r);
    CHECK(floe_voronoi_rect(tlo, thi, r, 1000, 2, &v, err, sizeof err) == FLOE_OK, "thin rectangle: %s", err);
    check_tiling("rectangle 1e4 x 1, n = 1000", &v, tlo, thi);
    check_shapes("rectangle 1e4 x 1, n = 1000", &v, tlo, thi);
    floe_voronoi_free(&v);
    free(r);

    /* far from the origin */
    const double flo[2] = {1e6, -2e6}, fhi[2] = {1e6 + 10, -2e6 + 5};
    double f[2 * 400];
    floe_voronoi_random_seeds(flo, fhi, 400, 11, f);
    CHECK(floe_voronoi_rect(flo, fhi, f, 400, 1, &v, err, sizeof err) == FLOE_OK, "offset rectangle: %s", err);
    check_tiling("rectangle at (1e6, -2e6), n = 400", &v, flo, fhi);
    check_shapes("rectangle at (1e6, -2e6), n = 400", &v, flo, fhi);
    floe_voronoi_free(&v);
}

/* rc is FLOE_EINVAL, out zeroed, and the message holds each of the words */
static void expect_refusal(const char *what, int rc, const floe_voronoi *v, const char *err, const char *w1,
                           const char *w2) {
    CHECK(rc == FLOE_EINVAL, "%s: rc %d, expected FLOE_EINVAL", what, rc);
    CHECK(v->n == 0 && !v->xy && !v->start && !v->seed && !v->area && !v->centroid, "%s: output not zeroed", what);
    CHECK(strstr(err, w1) && (!w2 || strstr(err, w2)), "%s: message \"%s\" lacks \"%s\"%s%s", what, err, w1,
          w2 ? " / " : "", w2 ? w2 : "");
    printf("  %-40s -> %s\n", what, err);
}

static void test_errors(void) {
    const double lo[2] = {0, 0}, hi[2] = {1, 1};
    double s[] = {0.1, 0.1, 0.2, 0.7, 0.9, 0.3, 0.5, 0.5, 0.2, 0.7};
    char err[256];
    floe_voronoi v;
    expect_refusal("duplicate seeds 1 and 4", floe_voronoi_rect(lo, hi, s, 5, 0, &v, err, sizeof err), &v, err,
                   "seeds 1 and 4", "coincide");
    s[8] = 0.2 + 1e-14; /* 1e-14 apart: still a duplicate (tol 1e-12 x diagonal) */
    expect_refusal("seeds 1 and 4 1e-14 apart", floe_voronoi_rect(lo, hi, s, 5, 0, &v, err, sizeof err), &v, err,
                   "seeds 1 and 4", "coincide");
    expect_refusal("n = 0", floe_voronoi_rect(lo, hi, s, 0, 0, &v, err, sizeof err), &v, err, "n = 0", NULL);
    double h1[2] = {1, 0};
    expect_refusal("hi[1] <= lo[1]", floe_voronoi_rect(lo, h1, s, 4, 0, &v, err, sizeof err), &v, err, "hi[1]", "lo[1]");
    double h2[2] = {-1, 1};
    expect_refusal("hi[0] < lo[0]", floe_voronoi_rect(lo, h2, s, 4, 0, &v, err, sizeof err), &v, err, "hi[0]", "lo[0]");
    double sn[] = {0.1, 0.1, 0.2, NAN, 0.5, 0.5};
    expect_refusal("NaN seed", floe_voronoi_rect(lo, hi, sn, 3, 0, &v, err, sizeof err), &v, err, "seed 1",
                   "not finite");
    double ln[2] = {NAN, 0};
    expect_refusal("NaN corner", floe_voronoi_rect(ln, hi, s, 4, 0, &v, err, sizeof err), &v, err, "rectangle",
                   "not finite");
    double hinf[2] = {1, INFINITY};
    expect_refusal("infinite corner", floe_voronoi_rect(lo, hinf, s, 4, 0, &v, err, sizeof err), &v, err, "rectangle",
                   "not finite");
    double so[] = {0.1, 0.1, 1.5, 0.5};
    expect_refusal("seed outside", floe_voronoi_rect(lo, hi, so, 2, 0, &v, err, sizeof err), &v, err, "seed 1",
                   "outside");
    expect_refusal("negative Lloyd iterations", floe_voronoi_rect(lo, hi, s, 4, -1, &v, err, sizeof err), &v, err,
                   "lloyd_iterations", NULL);
    double out[4];
    CHECK(floe_voronoi_random_seeds(lo, h1, 2, 1, out) == FLOE_EINVAL && floe_voronoi_random_seeds(lo, hi, 0, 1, out) ==
              FLOE_EINVAL, "random seeds: an empty rectangle and n = 0 refused");
    floe_voronoi z = {0};
    floe_voronoi_free(&z); /* a zeroed tessellation frees */
}

static void test_scale(void) {
    const double lo[2] = {0, 0}, hi[2] = {4, 3};
    const int n = 1000;
    double *s = malloc(2 * n * sizeof *s);
    floe_voronoi_random_seeds(lo, hi, n, 5, s);
    floe_voronoi v;
    char err[256];
    CHECK(floe_voronoi_rect(lo, hi, s, n, 3, &v, err, sizeof err) == FLOE_OK, "scale: %s", err);
    double *a0 = malloc(n * sizeof *a0), *c0 = malloc(2 * n * sizeof *c0);
    memcpy(a0, v.area, n * sizeof *a0);
    memcpy(c0, v.centroid, 2 * n * sizeof *c0);
    const double conc = 0.7, sc = sqrt(conc);
    CHECK(floe_voronoi_scale_cells(&v, sc) == FLOE_OK, "scale_cells(%g) failed", sc);
    double worst = 0, worst_poly = 0, worst_c = 0, total = 0;
    for (int k = 0; k < n; k++) {
        worst = fmax(worst, fabs(v.area[k] - sc * sc * a0[k]) / (sc * sc * a0[k]));
        worst_poly = fmax(worst_poly, fabs(poly_area(cell_xy(&v, k), cell_m(&v, k)) - sc * sc * a0[k]) / (sc * sc * a0[k]));
        worst_c = fmax(worst_c, hypot(v.centroid[2 * k] - c0[2 * k], v.centroid[2 * k + 1] - c0[2 * k + 1]) / 5.0);
        total += v.area[k];
    }
    CHECK(worst <= 1e-12, "scale: area[k] / (s^2 area0) off by %g (tol 1e-12)", worst);
    CHECK(worst_poly <= 1e-12, "scale: polygon area / (s^2 area0) off by %g (tol 1e-12)", worst_poly);
    CHECK(worst_c <= 1e-12, "scale: a centroid moved by %g x D (tol 1e-12)", worst_c);
    printf("  %-52s %.1e / %.1e (tol 1e-12)\n", "scale sqrt(0.7): areas x s^2, polygons x s^2", worst, worst_poly);
    CHECK_NEAR(total / rect_area(lo, hi), conc, 1e-12, "ice concentration after scaling (tol 1e-12)");
    shape_report r = cell_shapes(&v, lo, hi);
    CHECK(r.few == 0 && r.min_turn > 0, "scale: cells no longer convex");
    CHECK(floe_voronoi_scale_cells(&v, 0) == FLOE_EINVAL && floe_voronoi_scale_cells(&v, 1.5) == FLOE_EINVAL &&
              floe_voronoi_scale_cells(&v, NAN) == FLOE_EINVAL,
          "scale: s = 0, 1.5, NaN must be refused");
    floe_voronoi_free(&v);
    free(a0);
    free(c0);
    free(s);
}

static void test_random_seeds(void) {
    const double lo[2] = {-1, 5}, hi[2] = {2, 6};
    double a[200], b[200];
    floe_voronoi_random_seeds(lo, hi, 100, 99, a);
    floe_voronoi_random_seeds(lo, hi, 100, 99, b);
    int inside = 1;
    for (int k = 0; k < 100; k++) inside &= a[2 * k] >= lo[0] && a[2 * k] <= hi[0] && a[2 * k + 1] >= lo[1] && a[2 * k + 1] <= hi[1];
    CHECK(memcmp(a, b, sizeof a) == 0, "random seeds: not deterministic per seed");
    CHECK(inside, "random seeds: a point outside the rectangle");
}

/* printed, not asserted: timing depends on the machine */
static void time_large(void) {
    const double lo[2] = {0, 0}, hi[2] = {1e5, 1e5};
    const int n = 20000;
    double *s = malloc(2 * n * sizeof *s);
    floe_voronoi_random_seeds(lo, hi, n, 1, s);
    floe_voronoi v;
    char err[256];
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    int rc = floe_voronoi_rect(lo, hi, s, n, 5, &v, err, sizeof err);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    CHECK(rc == FLOE_OK, "20,000 cells: %s", err);
    if (rc == FLOE_OK) check_tiling("20,000 cells, 5 Lloyd", &v, lo, hi);
    int corners = rc == FLOE_OK ? v.start[n] : 0;
    printf("  time: 20,000 cells, 5 Lloyd iterations (6 tessellations): %.3f s, %.2f corners per cell\n",
           (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec), (double)corners / n);
    floe_voronoi_free(&v);
    free(s);
}

int main(void) {
    test_area_sums();
    test_brute_force();
    test_lattice();
    test_lloyd();
    test_awkward();
    test_errors();
    test_scale();
    test_random_seeds();
    time_large();
    return check_summary("test_voronoi");
}
