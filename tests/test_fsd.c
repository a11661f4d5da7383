/* test_fsd.c - floe fields of a given floe size distribution (docs/sea-ice.md, "Floe size
 * distributions"):
 *  - power tessellations (geometry/voronoi.c): 300 random seeds with random weights; every
 *    corner of a cell has the least power distance |x - s_k|^2 - w_k to its own seed
 *    (brute force, 1e-9 of the squared domain size), 4,000 random points each lie in the
 *    cell of least power distance, the areas tile the rectangle (1e-9); equal weights give
 *    the Voronoi cells (areas to 1e-12);
 *  - cells of prescribed areas (floe_voronoi_areas): 600 targets spanning a factor 100,
 *    every cell within the tolerance 1e-6 asked, with and without Lloyd steps;
 *  - scenes with `size_distribution`: a power law N(>D) ~ D^-alpha, alpha = 2 and 1.5 on
 *    [100, 1000] m: the maximum-likelihood exponent of the truncated Pareto law (Aban,
 *    Meerschaert & Panorska 2006) fitted to the floes' diameters D = 2 sqrt(A / pi) within
 *    0.15 of alpha (about 4 standard errors of the estimator at these counts; the error is
 *    printed), every diameter in [min, max] (1e-3), total floe area = concentration x
 *    region (1e-9); a given table of three diameters: each floe one of them (1e-3), the
 *    number fractions within 4 binomial standard deviations;
 *  - bad input refused at its line with the key named: alpha <= 0, min >= max, fractions
 *    not summing to 1, decreasing diameters, count with a distribution, both power_law
 *    and given, a largest floe that does not fit. */
#include "check.h"
#include "floe.h"
#include "floe_base.h"
#include "floe_rng.h"
#include "floe_voronoi.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cell_m(const floe_voronoi *v, int k) { return v->start[k + 1] - v->start[k]; }
static const double *cell_xy(const floe_voronoi *v, int k) { return v->xy + 2 * v->start[k]; }

static double power_dist(const double *x, const double *s, double w) {
    return (x[0] - s[0]) * (x[0] - s[0]) + (x[1] - s[1]) * (x[1] - s[1]) - w;
}

/* x inside convex CCW polygon xy (m corners), to tol (a distance) */
static int inside(const double *xy, int m, const double *x, double tol) {
    for (int i = 0; i < m; i++) {
        const double *a = xy + 2 * i, *b = xy + 2 * ((i + 1) % m);
        double ex = b[0] - a[0], ey = b[1] - a[1];
        if ((ex * (x[1] - a[1]) - ey * (x[0] - a[0])) / hypot(ex, ey) < -tol) return 0;
    }
    return 1;
}

static void test_power_brute_force(void) {
    const double lo[2] = {0, 0}, hi[2] = {3.0, 2.0}, D2 = 13.0;
    const int n = 300;
    double s[600], w[300];
    unsigned long long st = 11;
    floe_voronoi_random_seeds(lo, hi, n, 5, s);
    for (int k = 0; k < n; k++) w[k] = 0.04 * floe_rng_uniform(&st); /* cells are ~0.02 in area */
    floe_voronoi v;
    char err[256];
    int rc = floe_voronoi_power_rect(lo, hi, s, w, n, &v, err, sizeof err);
    CHECK(rc == FLOE_OK, "power cells: %s", err);
    if (rc) return;
    double worst = 0, area = 0;
    int empty = 0;
    for (int k = 0; k < n; k++) {
        area += v.area[k];
        empty += cell_m(&v, k) == 0;
        for (int i = 0; i < cell_m(&v, k); i++) {
            const double *x = cell_xy(&v, k) + 2 * i;
            double pk = power_dist(x, s + 2 * k, w[k]);
            for (int j = 0; j < n; j++) worst = fmax(worst, (pk - power_dist(x, s + 2 * j, w[j])) / D2);
        }
    }
    CHECK(worst <= 1e-9, "power cells: a corner is %g x D^2 nearer another seed in power (tol 1e-9)", worst);
    printf("  power cells, 300 seeds: corner nearer another seed %.2e x D^2 (tol 1e-9); %d empty cells\n", worst, empty);
    CHECK_NEAR(area, 6.0, 1e-9, "power cells: sum of areas / rectangle");
    int miss = 0;
    for (int t = 0; t < 4000; t++) {
        double x[2] = {3.0 * floe_rng_uniform(&st), 2.0 * floe_rng_uniform(&st)};
        int best = 0;
        for (int j = 1; j < n; j++)
            if (power_dist(x, s + 2 * j, w[j]) < power_dist(x, s + 2 * best, w[best])) best = j;
        miss += !inside(cell_xy(&v, best), cell_m(&v, best), x, 1e-9);
    }
    CHECK(miss == 0, "power cells: %d of 4000 random points outside the cell of least power distance", miss);
    floe_voronoi_free(&v);
    /* equal weights: the Voronoi cells */
    for (int k = 0; k < n; k++) w[k] = 0.5;
    floe_voronoi u;
    rc = floe_voronoi_power_rect(lo, hi, s, w, n, &v, err, sizeof err);
    rc = rc ? rc : floe_voronoi_rect(lo, hi, s, n, 0, &u, err, sizeof err);
    CHECK(rc == FLOE_OK, "equal weights: %s", err);
    if (rc) return;
    double dev = 0;
    for (int k = 0; k < n; k++) dev = fmax(dev, fabs(v.area[k] - u.area[k]) / u.area[k]);
    CHECK(dev <= 1e-12, "equal weights: areas differ from the Voronoi cells' by %g (tol 1e-12)", dev);
    printf("  equal weights against Voronoi cells: areas to %.2e (tol 1e-12)\n", dev);
    floe_voronoi_free(&v);
    floe_voronoi_free(&u);
    w[3] = NAN;
    CHECK(floe_voronoi_power_rect(lo, hi, s, w, n, &v, err, sizeof err) == FLOE_EINVAL && strstr(err, "weight 3"),
          "a NaN weight refused: %s", err);
}

static void test_areas(void) {
    const double lo[2] = {-50, 10}, hi[2] = {150, 110};
    const int n = 600;
    double *s = malloc(2 * n * sizeof *s), *a = malloc(n * sizeof *a), sum = 0;
    unsigned long long st = 3;
    floe_voronoi_random_seeds(lo, hi, n, 17, s);
    for (int k = 0; k < n; k++) sum += a[k] = pow(10.0, 2 * floe_rng_uniform(&st)); /* a factor 100 */
    const int lloyd[2] = {0, 3};
    for (int t = 0; t < 2; t++) {
        floe_voronoi v;
        char err[256];
        int rc = floe_voronoi_areas(lo, hi, s, a, n, lloyd[t], 1e-6, &v, err, sizeof err);
        CHECK(rc == FLOE_OK, "prescribed areas, %d Lloyd: %s", lloyd[t], err);
        if (rc) continue;
        double worst = 0, tot = 0, scale = 2e4 / sum;
        int few = 0;
        for (int k = 0; k < n; k++) {
            worst = fmax(worst, fabs(v.area[k] - a[k] * scale) / (a[k] * scale));
            tot += v.area[k];
            few += cell_m(&v, k) < 3;
        }
        CHECK(worst <= 1e-6 && few == 0, "prescribed areas, %d Lloyd: worst relative error %g (tol 1e-6), %d empty",
              lloyd[t], worst, few);
        printf("  600 cells of prescribed areas (x100 range), %d Lloyd: worst area error %.2e (tol 1e-6)\n", lloyd[t],
               worst);
        CHECK_NEAR(tot, 2e4, 1e-9, "prescribed areas: sum / rectangle");
        floe_voronoi_free(&v);
    }
    floe_voronoi v;
    char err[256];
    a[7] = -1;
    CHECK(floe_voronoi_areas(lo, hi, s, a, n, 0, 1e-6, &v, err, sizeof err) == FLOE_EINVAL && strstr(err, "area 7"),
          "a negative area refused: %s", err);
    a[7] = 1;
    CHECK(floe_voronoi_areas(lo, hi, s, a, n, 0, 0, &v, err, sizeof err) == FLOE_EINVAL && strstr(err, "tolerance"),
          "a zero tolerance refused: %s", err);
    free(s);
    free(a);
}

/* the maximum-likelihood exponent of a truncated Pareto law with known bounds [L, U]
 * (Aban, Meerschaert & Panorska 2006, J. Am. Stat. Assoc. 101, eq. 5 with the bounds
 * given): 1/alpha + r^alpha ln r / (1 - r^alpha) = mean ln(D/L), r = L/U, by bisection
 * (the left side falls with alpha); *se: 1/sqrt(n I(alpha)), I the Fisher information
 * 1/alpha^2 - r^alpha ln^2 r / (1 - r^alpha)^2 */
static double pareto_mle(const double *D, int n, double L, double U, double *se) {
    double S = 0, r = L / U, lr = log(r);
    for (int i = 0; i < n; i++) S += log(D[i] / L);
    S /= n;
    double a0 = 1e-3, a1 = 20;
    for (int it = 0; it < 200; it++) {
        double am = 0.5 * (a0 + a1), ra = pow(r, am);
        if (1 / am + ra * lr / (1 - ra) > S) a0 = am;
        else a1 = am;
    }
    double al = 0.5 * (a0 + a1), ra = pow(r, al);
    *se = 1 / sqrt(n * (1 / (al * al) - ra * lr * lr / ((1 - ra) * (1 - ra))));
    return al;
}

static const char *fsd_scene_fmt =
    "dimension: 2\n"
    "mass_2d: area\n"
    "time: {duration: 100, dt: 10}\n"
    "gravity: [0, 0]\n"
    "materials: [{name: ice, density: 920, young: 6e6, poisson: 0.3}]\n"
    "laws: [{materials: [ice, ice], model: linear, kn: 1e3, ks: 0}]\n"
    "bodies:\n"
    "  - floe_field: {region: {min: [0, 0], max: [1.5e4, 1.5e4]}, lloyd: 2, concentration: 0.7, seed: 3, "
    "thickness: 0.5, %s}\n"
    "    material: ice\n";

/* load the scene with the given distribution text; the floes' diameters into D (malloc'd) */
static floe_world *load_field(const char *dist, double **D, int *n, double *area, char *err, size_t errlen) {
    char text[2048];
    snprintf(text, sizeof text, fsd_scene_fmt, dist);
    floe_world *w = NULL;
    *D = NULL;
    *n = 0;
    err[0] = 0;
    if (floe_scene_load_ex("f.yaml", text, NULL, 0, &w, NULL, err, errlen) != FLOE_OK) return w;
    floe_particles_view v;
    floe_world_particles(w, &v);
    *D = malloc((size_t)v.n * sizeof **D);
    *area = 0;
    for (int i = 0; i < v.n; i++) {
        floe_mass_properties mp;
        floe_geometry_mass_properties(floe_world_particle_geometry(w, i), 2, 1.0, &mp);
        (*D)[i] = 2 * sqrt(mp.volume / M_PI);
        *area += mp.volume;
    }
    *n = v.n;
    return w;
}

static void test_power_law_fields(void) {
    const double alphas[2] = {2.0, 1.5}, L = 100, U = 1000;
    for (int t = 0; t < 2; t++) {
        char dist[128], err[1024];
        snprintf(dist, sizeof dist, "size_distribution: {power_law: %g, min: %g, max: %g}", alphas[t], L, U);
        double *D, area;
        int n;
        floe_world *w = load_field(dist, &D, &n, &area, err, sizeof err);
        CHECK(D != NULL, "power law %g: %s", alphas[t], err);
        if (D) {
            double se, al = pareto_mle(D, n, L, U, &se), dlo = INFINITY, dhi = 0;
            for (int i = 0; i < n; i++) {
                dlo = fmin(dlo, D[i]);
                dhi = fmax(dhi, D[i]);
            }
            CHECK(fabs(al - alphas[t]) <= 0.15, "power law %g: fitted exponent %g (tol 0.15)", alphas[t], al);
            printf("  power law alpha = %g, %d floes: fitted %.4f (error %+.4f, standard error %.4f, tol 0.15)\n",
                   alphas[t], n, al, al - alphas[t], se);
            CHECK(dlo >= L * (1 - 1e-3) && dhi <= U * (1 + 1e-3), "power law %g: diameters in [%g, %g], expected [%g, %g]",
                  alphas[t], dlo, dhi, L, U);
            CHECK_NEAR(area, 0.7 * 1.5e4 * 1.5e4, 1e-9, "power-law field: total floe area = concentration x region");
        }
        free(D);
        floe_world_destroy(w);
    }
}

static void test_given_field(void) {
    const double d[3] = {200, 400, 800}, f[3] = {0.6, 0.3, 0.1};
    double *D, area;
    int n;
    char err[1024];
    floe_world *w =
        load_field("size_distribution: {given: [[200, 0.6], [400, 0.3], [800, 0.1]]}", &D, &n, &area, err, sizeof err);
    CHECK(D != NULL, "given distribution: %s", err);
    if (D) {
        int cnt[3] = {0, 0, 0}, other = 0;
        for (int i = 0; i < n; i++) {
            int c = -1;
            for (int j = 0; j < 3; j++)
                if (fabs(D[i] - d[j]) <= 1e-3 * d[j]) c = j;
            if (c < 0) other++;
            else cnt[c]++;
        }
        CHECK(other == 0, "given distribution: %d floes of none of the diameters (1e-3)", other);
        for (int j = 0; j < 3; j++) {
            double sd = sqrt(n * f[j] * (1 - f[j]));
            CHECK(fabs(cnt[j] - n * f[j]) <= 4 * sd, "given distribution: %d floes of %g m, expected %g +- %g", cnt[j], d[j],
                  n * f[j], 4 * sd);
            printf("  given distribution, %d floes: %g m: %d (expected %.1f, 4 sd %.1f)\n", n, d[j], cnt[j], n * f[j],
                   4 * sd);
        }
        CHECK_NEAR(area, 0.7 * 1.5e4 * 1.5e4, 1e-9, "given field: total floe area = concentration x region");
    }
    free(D);
    floe_world_destroy(w);
}

static void test_errors(void) {
    const char *bad[][2] = {
        {"size_distribution: {power_law: 0, min: 100, max: 1000}", "size_distribution.power_law must be in (0, 20]"},
        {"size_distribution: {power_law: -1, min: 100, max: 1000}", "size_distribution.power_law must be in (0, 20]"},
        {"size_distribution: {power_law: 2, min: 1000, max: 1000}", "size_distribution.max must exceed min"},
        {"size_distribution: {power_law: 2, min: 0, max: 1000}", "size_distribution.min must be > 0"},
        {"size_distribution: {power_law: 2, max: 1000}", "size_distribution.min is required"},
        {"size_distribution: {given: [[200, 0.6], [400, 0.3]]}", "size_distribution.given: the number fractions sum to 0.9"},
        {"size_distribution: {given: [[400, 0.6], [200, 0.4]]}", "size_distribution.given[1]: the diameters must increase"},
        {"size_distribution: {given: [[200, 0.6], [400]]}", "size_distribution.given[1]"},
        {"size_distribution: {power_law: 2, min: 100, max: 1000}, count: 50", "count and size_distribution exclude"},
        {"size_distribution: {power_law: 2, min: 100, max: 1000, given: [[200, 1]]}", "either power_law"},
        {"size_distribution: {power_law: 2, min: 100, max: 20000}", "the largest floe (20000 m) must fit"},
        {"size_distribution: {power_law: 2, min: 100, max: 1000, slope: 3}", "unknown key 'slope'"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        double *D, area;
        int n;
        char err[1024];
        floe_world *w = load_field(bad[k][0], &D, &n, &area, err, sizeof err);
        CHECK(!D && strstr(err, bad[k][1]) && strstr(err, "f.yaml:8:"), "'%s' refused at its line, naming '%s': %s",
              bad[k][0], bad[k][1], err);
        printf("  %-60.60s -> %s\n", bad[k][0], err);
        free(D);
        floe_world_destroy(w);
    }
}

int main(void) {
    test_power_brute_force();
    test_areas();
    test_power_law_fields();
    test_given_field();
    test_errors();
    return check_summary("test_fsd");
}
