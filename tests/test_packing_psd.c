/* test_packing_psd.c - radius distributions of the random packing (core/scene/scene_psd.c,
 * docs/granular.md): the drawn sample's statistics against the distribution (tolerances from
 * the sample size), no overlaps, every sphere inside the region, one geometry per distinct
 * radius, the particles numbered in Morton order of their centres, and the refusals
 * (file:line messages). */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static floe_world *load(const char *text, char *err, size_t errlen) {
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_string(text, "psd.yaml", "/tmp", &w, &info, err, errlen);
    if (rc) {
        floe_world_destroy(w);
        return NULL;
    }
    return w;
}

static char scene[4000];
static void make_scene(int dim, const char *region, long count, const char *dist) {
    snprintf(scene, sizeof scene,
             "dimension: %d\n"
             "time: {duration: 0.01, dt: 1e-5}\n"
             "materials: [{name: g, density: 2500}]\n"
             "laws: [{materials: [g, g], model: viscoelastic, kn: 1e5, gn: 0, ks: 0, gs: 0, friction: 0}]\n"
             "bodies:\n"
             "  - packing: random\n"
             "    material: g\n"
             "    region: %s\n"
             "    count: %ld\n"
             "    seed: 7\n"
             "    radius_distribution: %s\n",
             dim, region, count, dist);
}

/* radii, centres; checks overlaps (O(n^2), n <= 2000) and containment in [lo, hi] */
static void check_geometry(floe_world *w, int dim, const double lo[3], const double hi[3], const char *what) {
    int n = floe_world_particle_count(w);
    double *x = malloc((size_t)n * 4 * sizeof *x);
    for (int i = 0; i < n; i++) {
        floe_particle_state ps;
        floe_world_get_particle(w, i, &ps);
        memcpy(x + 4 * i, ps.x, 3 * sizeof(double));
        x[4 * i + 3] = ps.radius;
    }
    int overlaps = 0, outside = 0;
    for (int i = 0; i < n; i++) {
        const double *a = x + 4 * i;
        for (int k = 0; k < dim; k++)
            if (a[k] - a[3] < lo[k] - 1e-12 || a[k] + a[3] > hi[k] + 1e-12) outside++;
        for (int j = i + 1; j < n; j++) {
            const double *b = x + 4 * j;
            double d2 = 0;
            for (int k = 0; k < 3; k++) d2 += (a[k] - b[k]) * (a[k] - b[k]);
            if (d2 < (a[3] + b[3]) * (a[3] + b[3]) * (1 - 1e-12)) overlaps++;
        }
    }
    CHECK(overlaps == 0, "%s: %d overlapping pairs", what, overlaps);
    CHECK(outside == 0, "%s: %d spheres reach outside the region", what, outside);
    free(x);
}

static double radius_of(floe_world *w, int i) {
    floe_particle_state ps;
    floe_world_get_particle(w, i, &ps);
    return ps.radius;
}

/* lognormal: 2,000 draws; the sample mean of ln r has standard error sigma / sqrt(n), its
 * standard deviation sigma / sqrt(2 n) (normal theory); 4 standard errors as tolerance */
static void test_lognormal(void) {
    char err[1024];
    const double med = 0.01, sig = 0.25;
    const long n = 2000;
    make_scene(3, "{min: [0, 0, 0], max: [1, 1, 1]}", n, "{lognormal: {median: 0.01, sigma: 0.25}, seed: 3}");
    floe_world *w = load(scene, err, sizeof err);
    CHECK(w != NULL, "lognormal scene: %s", err);
    if (!w) return;
    CHECK(floe_world_particle_count(w) == n, "lognormal: %d particles", floe_world_particle_count(w));
    double s1 = 0, s2 = 0;
    for (int i = 0; i < n; i++) {
        double l = log(radius_of(w, i));
        s1 += l;
        s2 += l * l;
    }
    double m = s1 / n, sd = sqrt((s2 - n * m * m) / (n - 1));
    double tol_m = 4 * sig / sqrt((double)n), tol_s = 4 * sig / sqrt(2.0 * n);
    CHECK(fabs(m - log(med)) <= tol_m, "lognormal: mean of ln r %g vs ln median %g (tol %g)", m, log(med), tol_m);
    CHECK(fabs(sd - sig) <= tol_s, "lognormal: sd of ln r %g vs sigma %g (tol %g)", sd, sig, tol_s);
    printf("  lognormal n=%ld: median %.5g (want %g, tol x%.3f), sigma %.4f (want %g +- %.4f)\n", n, exp(m), med,
           exp(tol_m), sd, sig, tol_s);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    check_geometry(w, 3, lo, hi, "lognormal");
    floe_world_destroy(w);

    /* truncation and the mean form: every radius inside [min, max]; mean of the untruncated
     * distribution -> median = mean exp(-sigma^2/2) */
    make_scene(3, "{min: [0, 0, 0], max: [1, 1, 1]}", 1000,
               "{lognormal: {mean: 0.01, sigma: 0.5, min: 0.006, max: 0.012}, seed: 5}");
    w = load(scene, err, sizeof err);
    CHECK(w != NULL, "truncated lognormal: %s", err);
    if (!w) return;
    double rmin = INFINITY, rmax = 0;
    for (int i = 0; i < 1000; i++) {
        double r = radius_of(w, i);
        rmin = fmin(rmin, r);
        rmax = fmax(rmax, r);
    }
    CHECK(rmin >= 0.006 && rmax <= 0.012, "truncated lognormal: radii in [%g, %g]", rmin, rmax);
    floe_world_destroy(w);
}

/* uniform: mean (rmin + rmax)/2, standard error (rmax - rmin)/sqrt(12 n); 4 of them */
static void test_uniform_2d(void) {
    char err[1024];
    const long n = 1500;
    make_scene(2, "{min: [0, 0], max: [1, 1]}", n, "{uniform: [0.004, 0.008]}");
    floe_world *w = load(scene, err, sizeof err);
    CHECK(w != NULL, "uniform 2D scene: %s", err);
    if (!w) return;
    double s = 0, rmin = INFINITY, rmax = 0;
    for (int i = 0; i < n; i++) {
        double r = radius_of(w, i);
        s += r;
        rmin = fmin(rmin, r);
        rmax = fmax(rmax, r);
    }
    double tol = 4 * 0.004 / sqrt(12.0 * n);
    CHECK(fabs(s / n - 0.006) <= tol, "uniform: mean %g vs 0.006 (tol %g)", s / n, tol);
    CHECK(rmin >= 0.004 && rmax <= 0.008, "uniform: radii in [%g, %g]", rmin, rmax);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 0};
    check_geometry(w, 2, lo, hi, "uniform 2D");
    floe_world_destroy(w);
}

/* given fractions by volume and by number: the counts against the expected counts by a
 * chi-square bound (k - 1 degrees of freedom; 3 radii: the 99.9 % point of chi2(2) is 13.8) */
static void test_given(const char *by, int by_volume) {
    char err[1024], dist[256];
    const long n = 2000;
    const double r[3] = {0.004, 0.006, 0.008}, f[3] = {0.2, 0.3, 0.5};
    snprintf(dist, sizeof dist, "{given: [[0.004, 0.2], [0.006, 0.3], [0.008, 0.5]], by: %s}", by);
    make_scene(3, "{min: [0, 0, 0], max: [0.5, 0.5, 0.5]}", n, dist);
    floe_world *w = load(scene, err, sizeof err);
    CHECK(w != NULL, "given (%s) scene: %s", by, err);
    if (!w) return;
    double p[3], ps = 0;
    for (int k = 0; k < 3; k++) ps += p[k] = by_volume ? f[k] / (r[k] * r[k] * r[k]) : f[k];
    long cnt[3] = {0, 0, 0}, other = 0;
    for (int i = 0; i < n; i++) {
        double ri = radius_of(w, i);
        int k = 0;
        while (k < 3 && ri != r[k]) k++;
        if (k == 3) other++;
        else cnt[k]++;
    }
    CHECK(other == 0, "given (%s): %ld radii not in the list", by, other);
    double chi2 = 0, vol[3], vt = 0;
    for (int k = 0; k < 3; k++) {
        double e = n * p[k] / ps;
        chi2 += (cnt[k] - e) * (cnt[k] - e) / e;
        vt += vol[k] = cnt[k] * r[k] * r[k] * r[k];
    }
    CHECK(chi2 < 13.8, "given (%s): chi2 %g of the counts %ld %ld %ld exceeds 13.8 (chi2(2) at 99.9 %%)", by, chi2,
          cnt[0], cnt[1], cnt[2]);
    printf("  given by %s: counts %ld %ld %ld chi2 %.2f; volume fractions %.3f %.3f %.3f\n", by, cnt[0], cnt[1],
           cnt[2], chi2, vol[0] / vt, vol[1] / vt, vol[2] / vt);
    const double lo[3] = {0, 0, 0}, hi[3] = {0.5, 0.5, 0.5};
    check_geometry(w, 3, lo, hi, by);
    floe_world_destroy(w);
}

/* the Morton key of x in [lo, hi] (every axis scaled by the longest side), written out bit by
 * bit (the loader's spreads the bits by masks) */
static unsigned long long morton_naive(const double *x, int dim, const double *lo, const double *hi) {
    unsigned long long key = 0, q[3] = {0, 0, 0};
    double side = 0;
    for (int a = 0; a < dim; a++) side = fmax(side, hi[a] - lo[a]);
    for (int a = 0; a < dim; a++) {
        double u = (x[a] - lo[a]) / side;
        u = u < 0 ? 0 : u > 1 ? 1 : u;
        q[a] = (unsigned long long)(u * 2097151.0);
    }
    for (int b = 0; b < 21; b++)
        for (int a = 0; a < dim; a++) key |= ((q[a] >> b) & 1ull) << (dim * b + a);
    return key;
}

static int cmp_long(const void *a, const void *b) {
    long x = *(const long *)a, y = *(const long *)b;
    return (x > y) - (x < y);
}

/* A random packing's particles are numbered in Morton order of their centres (the keys
 * never decrease with the index), so near neighbours get near indices: the median index
 * gap of the pairs within 4 radii must be below n / 20 (in placement order, a random
 * order, it is about n / 3: 910 of 3,000 and 594 of 2,000, checked by hand). One geometry per distinct
 * radius, whatever the order. */
static void test_spatial_order(int dim, const char *region, const double *lo, const double *hi, long n,
                               const char *dist, int ngeom) {
    char err[1024];
    make_scene(dim, region, n, dist);
    floe_world *w = load(scene, err, sizeof err);
    CHECK(w != NULL, "order (%dD, %s): %s", dim, dist, err);
    if (!w) return;
    double *x = malloc((size_t)n * 3 * sizeof *x), rmax = 0;
    int decreasing = 0;
    unsigned long long prev = 0;
    for (int i = 0; i < n; i++) {
        floe_particle_state ps;
        floe_world_get_particle(w, i, &ps);
        memcpy(x + 3 * i, ps.x, sizeof ps.x);
        rmax = fmax(rmax, ps.radius);
        unsigned long long key = morton_naive(ps.x, dim, lo, hi);
        if (i > 0 && key < prev) decreasing++;
        prev = key;
    }
    CHECK(decreasing == 0, "order (%dD): the Morton key decreases %d times along the indices", dim, decreasing);
    long *gap = malloc((size_t)n * 64 * sizeof *gap), ng = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n && ng < n * 64; j++) {
            double d2 = 0;
            for (int a = 0; a < 3; a++) d2 += (x[3 * i + a] - x[3 * j + a]) * (x[3 * i + a] - x[3 * j + a]);
            if (d2 < 16 * rmax * rmax) gap[ng++] = j - i;
        }
    qsort(gap, (size_t)ng, sizeof *gap, cmp_long);
    long med = ng ? gap[ng / 2] : n;
    CHECK(ng > n && med < n / 20, "order (%dD): median index gap %ld of %ld near pairs (want < %ld)", dim, med, ng,
          n / 20);
    CHECK(floe_world_geometry_count(w) == ngeom, "order (%dD): %d geometries (want %d, one per radius)", dim,
          floe_world_geometry_count(w), ngeom);
    printf("  order %dD, n=%ld: the key decreases %d times, median index gap %ld of %ld near pairs, %d geometries\n", dim,
           n, decreasing, med, ng, floe_world_geometry_count(w));
    free(gap);
    free(x);
    floe_world_destroy(w);
}

/* grow.index names a random packing's particle in its final (Morton) numbering: particle I
 * of the entry, and no other, gets its own geometry */
static void test_grow_index(void) {
    char err[1024], text[1200];
    snprintf(text, sizeof text,
             "dimension: 3\n"
             "time: {duration: 0.01, dt: 1e-5}\n"
             "materials: [{name: g, density: 2500}]\n"
             "laws: [{materials: [g, g], model: viscoelastic, kn: 1e5, gn: 0, ks: 0, gs: 0, friction: 0}]\n"
             "bodies:\n"
             "  - {packing: lattice, shape: {sphere: {radius: 0.01}}, material: g, spacing: 0.03, counts: [2, 1, 1],\n"
             "     origin: [0.5, 0.5, 0.5]}\n"
             "  - {packing: random, shape: {sphere: {radius: 0.01}}, material: g, count: 40, seed: 9,\n"
             "     region: {min: [0, 0, 0], max: [0.3, 0.3, 0.3]}, grow: {index: 7, rate: 0.001}}\n");
    floe_world *w = load(text, err, sizeof err);
    CHECK(w != NULL, "grow on a random packing: %s", err);
    if (!w) return;
    const floe_geometry *shared = floe_world_particle_geometry(w, 2);
    int own = 0, which = -1;
    for (int i = 2; i < 42; i++)
        if (floe_world_particle_geometry(w, i) != shared) {
            own++;
            which = i;
        }
    CHECK(own == 1 && which == 2 + 7, "grow.index 7 of the second entry: %d particles with their own geometry, "
          "the last %d (want particle 9 alone)", own, which);
    floe_world_destroy(w);
}

static void test_refusals(void) {
    char err[1024];
    /* far too many for the region: refused before placement, at the count's line */
    make_scene(3, "{min: [0, 0, 0], max: [0.1, 0.1, 0.1]}", 5000, "{uniform: [0.004, 0.008]}");
    floe_world *w = load(scene, err, sizeof err);
    CHECK(!w && strstr(err, "psd.yaml:9:") && strstr(err, "random close packing"),
          "overfull region refused at count (line 9): %s", err);
    floe_world_destroy(w);
    /* shape and distribution together */
    char two[4200];
    make_scene(3, "{min: [0, 0, 0], max: [1, 1, 1]}", 10, "{uniform: [0.004, 0.008]}");
    snprintf(two, sizeof two, "%s    shape: {sphere: {radius: 0.01}}\n", scene);
    w = load(two, err, sizeof err);
    CHECK(!w && strstr(err, "either shape or radius_distribution"), "shape + distribution refused: %s", err);
    floe_world_destroy(w);
    /* a bad lognormal */
    make_scene(3, "{min: [0, 0, 0], max: [1, 1, 1]}", 10, "{lognormal: {median: 0.01}}");
    w = load(scene, err, sizeof err);
    CHECK(!w && strstr(err, "sigma"), "lognormal without sigma refused: %s", err);
    floe_world_destroy(w);
    make_scene(3, "{min: [0, 0, 0], max: [1, 1, 1]}", 10, "{uniform: [0.008, 0.004]}");
    w = load(scene, err, sizeof err);
    CHECK(!w && strstr(err, "rmin <= rmax"), "uniform rmin > rmax refused: %s", err);
    floe_world_destroy(w);
    /* jammed: within the close-packing bound but beyond what random placement reaches */
    make_scene(2, "{min: [0, 0], max: [0.2, 0.2]}", 400, "{given: [[0.005, 1]]}");
    w = load(scene, err, sizeof err);
    CHECK(!w && strstr(err, "could only place"), "jammed region refused: %s", err);
    floe_world_destroy(w);
}

int main(void) {
    test_lognormal();
    test_uniform_2d();
    test_given("volume", 1);
    test_given("number", 0);
    const double lo[3] = {0, 0, 0}, hi3[3] = {0.5, 0.5, 0.5}, hi2[3] = {1, 0.5, 0};
    test_spatial_order(3, "{min: [0, 0, 0], max: [0.5, 0.5, 0.5]}", lo, hi3, 3000,
                       "{given: [[0.004, 0.2], [0.006, 0.3], [0.008, 0.5]], by: number}", 3);
    test_spatial_order(2, "{min: [0, 0], max: [1, 0.5]}", lo, hi2, 2000, "{given: [[0.004, 1], [0.006, 1]]}", 2);
    test_grow_index();
    test_refusals();
    return check_summary("test_packing_psd");
}
