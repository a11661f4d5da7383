/* test_kdtree.c - floe_kdtree against brute force. Radius results must equal the
 * brute-force set {j : dx*dx + dy*dy + dz*dz <= r*r} exactly; k-NN results must have
 * exactly the brute-force k smallest squared distances (ties may pick any index).
 * Data: uniform 3D, gaussian clusters of very different scales, 2D (z ignored),
 * duplicates, all-identical points, 1e-12 .. 1e12 coordinate scales, n = 0 and 1, and a
 * geometric sequence whose tree is deeper than the search stack. */
#include <math.h>
#include <time.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "floe_kdtree.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;

static uint64_t splitmix64(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static double urand(void) { return (double)(splitmix64() >> 11) * 0x1.0p-53; }
static double grand(void)
{
    double u = urand(), v = urand();
    return sqrt(-2.0 * log(u > 0 ? u : 1e-300)) * cos(6.283185307179586 * v);
}

static double dist2(const double *p, const double *q, int dim)
{
    double dx = p[0] - q[0], dy = p[1] - q[1], dz = dim == 3 ? p[2] - q[2] : 0.0;
    return dx * dx + dy * dy + dz * dz;
}

static int cmp_int(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

/* scratch shared by the checks */
static int *g_out, *g_bf, *g_vis, g_nvis, g_viscap, *g_kidx, *g_bidx;
static double *g_kd2, *g_bd2;

static void visit_collect(int index, double d2, void *user)
{
    const double *r2 = user;
    if (d2 > *r2) g_nvis = -1000000000; /* reported a point outside the radius */
    if (g_nvis >= 0 && g_nvis < g_viscap) g_vis[g_nvis] = index;
    g_nvis++;
}

/* radius query vs brute force; returns 1 when everything matched */
static int check_radius(const floe_kdtree *t, const double *pts, int n, int dim,
                        const double q[3], double r)
{
    double r2 = r * r;
    int nb = 0;
    for (int j = 0; j < n; j++)
        if (dist2(pts + 3 * (size_t)j, q, dim) <= r2) g_bf[nb++] = j;
    int cnt = floe_kdtree_radius(t, q, r, g_out, n + 1);
    int ok = cnt == nb;
    if (ok) {
        qsort(g_out, (size_t)cnt, sizeof(int), cmp_int);
        ok = memcmp(g_out, g_bf, (size_t)cnt * sizeof(int)) == 0;
    }
    /* a short buffer: same total, and what was written are distinct true hits */
    if (ok && nb > 2) {
        int cap = nb / 2;
        int c2 = floe_kdtree_radius(t, q, r, g_out, cap);
        ok = c2 == nb;
        qsort(g_out, (size_t)cap, sizeof(int), cmp_int);
        for (int i = 0; ok && i < cap; i++) {
            ok = (i == 0 || g_out[i] != g_out[i - 1]) &&
                 bsearch(&g_out[i], g_bf, (size_t)nb, sizeof(int), cmp_int) != NULL;
        }
    }
    /* count only */
    if (ok) ok = floe_kdtree_radius(t, q, r, NULL, 0) == nb;
    /* callback form */
    if (ok) {
        double ref[1] = {r2};
        g_nvis = 0;
        g_viscap = n + 1;
        floe_kdtree_radius_visit(t, q, r, visit_collect, ref);
        ok = g_nvis == nb;
        if (ok) {
            qsort(g_vis, (size_t)nb, sizeof(int), cmp_int);
            ok = memcmp(g_vis, g_bf, (size_t)nb * sizeof(int)) == 0;
        }
    }
    return ok;
}

/* k-NN vs brute force (k smallest squared distances by insertion) */
static int check_knn(const floe_kdtree *t, const double *pts, int n, int dim,
                     const double q[3], int k)
{
    int nb = 0;
    for (int j = 0; j < n; j++) {
        double d = dist2(pts + 3 * (size_t)j, q, dim);
        if (nb < k || d < g_bd2[nb - 1]) {
            int i = nb < k ? nb++ : k - 1;
            while (i > 0 && g_bd2[i - 1] > d) { g_bd2[i] = g_bd2[i - 1]; g_bidx[i] = g_bidx[i - 1]; i--; }
            g_bd2[i] = d;
            g_bidx[i] = j;
        }
    }
    int cnt = floe_kdtree_knn(t, q, k, g_kidx, g_kd2);
    if (cnt != nb) return 0;
    for (int i = 0; i < cnt; i++) {
        if (g_kd2[i] != g_bd2[i]) return 0;
        if (g_kidx[i] < 0 || g_kidx[i] >= n) return 0;
        if (dist2(pts + 3 * (size_t)g_kidx[i], q, dim) != g_kd2[i]) return 0;
    }
    memcpy(g_out, g_kidx, (size_t)cnt * sizeof(int));
    qsort(g_out, (size_t)cnt, sizeof(int), cmp_int);
    for (int i = 1; i < cnt; i++)
        if (g_out[i] == g_out[i - 1]) return 0;
    return 1;
}

static int check_order(const floe_kdtree *t, int n)
{
    const int *ord = floe_kdtree_order(t);
    if (n == 0) return 1;
    if (!ord) return 0;
    memcpy(g_out, ord, (size_t)n * sizeof(int));
    qsort(g_out, (size_t)n, sizeof(int), cmp_int);
    for (int i = 0; i < n; i++)
        if (g_out[i] != i) return 0;
    return 1;
}

static void alloc_scratch(int n)
{
    size_t m = (size_t)n + 8;
    g_out = malloc(m * sizeof(int));
    g_bf = malloc(m * sizeof(int));
    g_vis = malloc(m * sizeof(int));
    g_kidx = malloc(m * sizeof(int));
    g_bidx = malloc(m * sizeof(int));
    g_kd2 = malloc(m * sizeof(double));
    g_bd2 = malloc(m * sizeof(double));
}

static void free_scratch(void)
{
    free(g_out); free(g_bf); free(g_vis); free(g_kidx); free(g_bidx); free(g_kd2); free(g_bd2);
}

/* Runs radius and k-NN checks on one data set. scale: typical neighbour distance used to
 * pick radii; nq: number of queries of each kind; full: add whole-cloud queries. */
static void run_case(const char *name, const double *pts, int n, int dim, int leaf,
                     double scale, int nq, int full)
{
    clock_t c0 = clock();
    floe_kdtree *t = floe_kdtree_build(pts, n, dim, leaf);
    CHECK(t != NULL, "%s: build failed", name);
    if (!t) return;
    CHECK(floe_kdtree_size(t) == n, "%s: size %d != %d", name, floe_kdtree_size(t), n);
    alloc_scratch(n);
    CHECK(check_order(t, n), "%s: order is not a permutation", name);
    int bad_r = 0, bad_k = 0, nr = 0, nk = 0;
    static const double rmul[] = {0.0, 0.5, 1.0, 2.0, 4.0};
    static const int ks[] = {1, 2, 7, 33};
    for (int iq = 0; iq < nq; iq++) {
        double q[3];
        if (n > 0 && iq % 3 != 2) { /* data point, possibly nudged */
            const double *p = pts + 3 * (size_t)(splitmix64() % (uint64_t)n);
            double nudge = iq % 3 == 1 ? scale : 0.0;
            for (int d = 0; d < 3; d++) q[d] = p[d] + nudge * (urand() - 0.5);
        } else { /* anywhere, also outside the cloud */
            for (int d = 0; d < 3; d++) q[d] = (n > 0 ? pts[d] : 0.0) + 20 * scale * (urand() - 0.5);
        }
        if (dim == 2) q[2] = 1e300 * (urand() - 0.5); /* must be ignored */
        double r = rmul[iq % 5] * scale;
        if (iq % 7 == 3 && n > 0) /* radius exactly at a point's distance (boundary) */
            r = sqrt(dist2(pts + 3 * (size_t)(splitmix64() % (uint64_t)n), q, dim));
        bad_r += !check_radius(t, pts, n, dim, q, r);
        nr++;
        int k = ks[iq % 4];
        bad_k += !check_knn(t, pts, n, dim, q, k);
        nk++;
    }
    /* k larger than n, and a radius covering everything */
    if (n > 0 && full) {
        double q[3] = {pts[0], pts[1], pts[2]};
        bad_k += !check_knn(t, pts, n, dim, q, n + 3);
        nk++;
        double ext = 0;
        for (int j = 0; j < n; j++) ext = fmax(ext, dist2(pts + 3 * (size_t)j, q, dim));
        bad_r += !check_radius(t, pts, n, dim, q, sqrt(ext));
        bad_r += !check_radius(t, pts, n, dim, q, INFINITY);
        nr += 2;
    }
    CHECK(bad_r == 0, "%s (leaf %d): %d of %d radius queries differ from brute force", name, leaf, bad_r, nr);
    CHECK(bad_k == 0, "%s (leaf %d): %d of %d k-NN queries differ from brute force", name, leaf, bad_k, nk);
    printf("  %-34s n=%-6d dim=%d leaf=%-3d radius %d/%d  knn %d/%d %s %.3f s\n", name, n, dim, leaf,
           nr - bad_r, nr, nk - bad_k, nk, bad_r + bad_k ? "FAILED" : "ok", (double)(clock() - c0) / CLOCKS_PER_SEC);
    free_scratch();
    floe_kdtree_destroy(t);
}

static double *gen_uniform(int n, double lo, double width)
{
    double *p = malloc((size_t)(3 * n + 1) * sizeof(double));
    for (int i = 0; i < 3 * n; i++) p[i] = lo + width * urand();
    return p;
}

/* A build by 2, 4 or 64 threads is the one-thread build: the same permutation, and the same
 * radius and k-NN answers in the same order (the order of a radius query's points is the
 * order the nodes are visited in: their splits, bounds and layout). Without OpenMP all are
 * one thread's. */
static void check_threaded(const char *name, const double *p, int n, int dim, int leaf, double r)
{
    int bad = 0, failed = 0;
    floe_kdtree *t1 = floe_kdtree_build_threads(p, n, dim, leaf, 1);
    int *a = malloc((size_t)n * sizeof *a), *b = malloc((size_t)n * sizeof *b);
    double da[8], db[8];
    static const int nts[3] = {2, 4, 64}; /* 64: fewer are taken (each with 4 subtrees of 256 points) */
    for (int q = 0; q < 3; q++) {
        const int nt = nts[q];
        floe_kdtree *tn = floe_kdtree_build_threads(p, n, dim, leaf, nt);
        CHECK(t1 && tn, "%s: the build on %d threads failed", name, nt);
        if (!t1 || !tn) {
            failed = 1;
            floe_kdtree_destroy(tn);
            continue;
        }
        CHECK(!memcmp(floe_kdtree_order(t1), floe_kdtree_order(tn), (size_t)n * sizeof(int)),
              "%s: the order of the build on %d threads differs", name, nt);
        int badn = 0;
        for (int iq = 0; iq < 50; iq++) {
            const double *c = p + 3 * (size_t)((iq * 7919) % n);
            const double q[3] = {c[0] + 0.3 * r * grand(), c[1] + 0.3 * r * grand(), c[2] + 0.3 * r * grand()};
            const double rq = r * (1 + iq % 3);
            const int na = floe_kdtree_radius(t1, q, rq, a, n), nb = floe_kdtree_radius(tn, q, rq, b, n);
            badn += na != nb || memcmp(a, b, (size_t)(na < n ? na : n) * sizeof *a);
            const int ka = floe_kdtree_knn(t1, q, 8, a, da), kb = floe_kdtree_knn(tn, q, 8, b, db);
            badn += ka != kb || memcmp(a, b, (size_t)ka * sizeof *a) || memcmp(da, db, (size_t)ka * sizeof *da);
        }
        CHECK(badn == 0, "%s: %d of 100 queries differ on the build of %d threads", name, badn, nt);
        bad += badn;
        floe_kdtree_destroy(tn);
    }
    printf("  %-34s n=%-6d builds on 2, 4 and 64 threads %s\n", name, n, bad || failed ? "FAILED" : "the same");
    free(a);
    free(b);
    floe_kdtree_destroy(t1);
}

int main(void)
{
    /* uniform 3D, 20k points, mean spacing ~ n^(-1/3) */
    {
        int n = 20000;
        double *p = gen_uniform(n, 0.0, 1.0);
        double s = 0.05;
        run_case("uniform 3D", p, n, 3, 10, s, 240, 1);
        run_case("uniform 3D", p, n, 3, 1, s, 60, 0);
        run_case("uniform 3D", p, n, 3, 0, s, 60, 0);
        run_case("uniform 3D", p, n, 3, 200, s, 60, 0);
        check_threaded("uniform 3D", p, n, 3, 10, s);
        check_threaded("uniform 3D, leaf 1", p, n, 3, 1, s);
        free(p);
    }
    /* gaussian clusters with scales from 1e-6 to 1e2 */
    {
        int n = 12000, nc = 6;
        static const double sig[] = {1e-6, 1e-3, 1e-1, 1.0, 10.0, 100.0};
        double *p = malloc((size_t)3 * n * sizeof(double));
        for (int i = 0; i < n; i++) {
            int c = i % nc;
            for (int d = 0; d < 3; d++) p[3 * i + d] = 1000.0 * c + (d == 0 ? 3.0 * c : 0.0) + sig[c] * grand();
        }
        run_case("clusters 1e-6..1e2", p, n, 3, 10, 1e-3, 120, 1);
        run_case("clusters 1e-6..1e2", p, n, 3, 10, 1.0, 60, 0);
        run_case("clusters 1e-6..1e2", p, n, 3, 10, 1e-6, 60, 0);
        check_threaded("clusters 1e-6..1e2", p, n, 3, 10, 1e-3);
        free(p);
    }
    /* 2D: z holds garbage and must be ignored */
    {
        int n = 15000;
        double *p = gen_uniform(n, -1.0, 2.0);
        for (int i = 0; i < n; i++) p[3 * i + 2] = 1e6 * grand();
        run_case("2D (z ignored)", p, n, 2, 10, 0.05, 150, 1);
        run_case("2D (z ignored)", p, n, 2, 3, 0.02, 60, 0);
        check_threaded("2D (z ignored)", p, n, 2, 10, 0.05);
        free(p);
    }
    /* duplicates: 6000 points on 40 distinct positions, and all identical */
    {
        int n = 6000, m = 40;
        double *base = gen_uniform(m, 0.0, 1.0);
        double *p = malloc((size_t)3 * n * sizeof(double));
        for (int i = 0; i < n; i++) {
            int c = (int)(splitmix64() % (uint64_t)m);
            memcpy(p + 3 * i, base + 3 * c, 3 * sizeof(double));
        }
        run_case("duplicates (40 sites)", p, n, 3, 10, 0.1, 80, 1);
        run_case("duplicates 2D", p, n, 2, 4, 0.1, 40, 1);
        check_threaded("duplicates (40 sites)", p, n, 3, 10, 0.1);
        for (int i = 0; i < n; i++) { p[3 * i] = 0.25; p[3 * i + 1] = -7.5; p[3 * i + 2] = 1e3; }
        run_case("all identical", p, n, 3, 10, 1.0, 40, 1);
        run_case("all identical", p, 1000, 3, 1, 1.0, 20, 0);
        check_threaded("all identical", p, n, 3, 10, 1.0);
        free(base);
        free(p);
    }
    /* coordinate scales: tiny and huge, also offset far from the origin */
    {
        int n = 8000;
        static const double scales[] = {1e-12, 1e-9, 1e9, 1e12};
        for (int s = 0; s < 4; s++) {
            double *p = gen_uniform(n, 0.0, scales[s]);
            char name[64];
            snprintf(name, sizeof name, "uniform scale %.0e", scales[s]);
            run_case(name, p, n, 3, 10, 0.06 * scales[s], 60, 1);
            free(p);
        }
        double *p = gen_uniform(n, 1e12, 1e4);
        run_case("offset 1e12, width 1e4", p, n, 3, 10, 600.0, 60, 1);
        free(p);
    }
    /* n = 0 and n = 1 */
    {
        double one[3] = {0.5, -0.25, 2.0};
        run_case("n=1", one, 1, 3, 10, 1.0, 30, 1);
        run_case("n=1 2D", one, 1, 2, 10, 1.0, 30, 1);
        floe_kdtree *t = floe_kdtree_build(NULL, 0, 3, 10);
        CHECK(t != NULL, "n=0: build returned NULL");
        double q[3] = {0, 0, 0};
        int idx[2];
        double d2[2];
        CHECK(floe_kdtree_size(t) == 0, "n=0: size");
        CHECK(floe_kdtree_radius(t, q, 1e300, idx, 2) == 0, "n=0: radius found points");
        CHECK(floe_kdtree_knn(t, q, 2, idx, d2) == 0, "n=0: knn found points");
        floe_kdtree_destroy(t);
        floe_kdtree_destroy(NULL);
    }
    /* invalid arguments */
    {
        double p[3] = {0, 0, 0};
        CHECK(floe_kdtree_build(p, 1, 4, 10) == NULL, "dim 4 accepted");
        CHECK(floe_kdtree_build(p, -1, 3, 10) == NULL, "n < 0 accepted");
        CHECK(floe_kdtree_build(NULL, 5, 3, 10) == NULL, "NULL points accepted");
    }
    /* NaN and infinite coordinates: the build must terminate, and radius queries still
     * equal brute force (a NaN distance is never within r) */
    {
        int n = 3000;
        double *p = gen_uniform(n, 0.0, 1.0);
        for (int i = 0; i < n; i += 7) p[3 * i + (i % 3)] = NAN;
        for (int i = 3; i < n; i += 101) p[3 * i + 1] = (i % 2) ? INFINITY : -INFINITY;
        for (int i = 0; i < 10; i++) p[3 * i] = p[3 * i + 1] = p[3 * i + 2] = NAN;
        floe_kdtree *t = floe_kdtree_build(p, n, 3, 8);
        CHECK(t != NULL, "NaN points: build failed");
        double *p2 = malloc((size_t)3 * 3 * n * sizeof *p2); /* the same, three times over: a threaded build */
        for (int c = 0; c < 3; c++) memcpy(p2 + 3 * (size_t)n * c, p, 3 * (size_t)n * sizeof *p2);
        check_threaded("NaN/inf points", p2, 3 * n, 3, 8, 0.05);
        free(p2);
        if (t) {
            alloc_scratch(n);
            CHECK(check_order(t, n), "NaN points: order is not a permutation");
            int bad = 0;
            for (int iq = 0; iq < 40; iq++) {
                double q[3] = {urand(), urand(), urand()};
                bad += !check_radius(t, p, n, 3, q, 0.02 * (iq % 10));
            }
            CHECK(bad == 0, "NaN points: %d of 40 radius queries differ from brute force", bad);
            printf("  %-34s n=%-6d radius %d/40 %s\n", "NaN/inf points", n, 40 - bad, bad ? "FAILED" : "ok");
            free_scratch();
            floe_kdtree_destroy(t);
        }
        free(p);
    }
    /* geometric sequence: each midpoint split peels one point off, so the tree is much
     * deeper than the search stack and the overflow path is exercised */
    {
        int n = 1200;
        double *p = malloc((size_t)3 * n * sizeof(double));
        for (int i = 0; i < n; i++) {
            p[3 * i] = ldexp(1.0, -(i % 600));
            p[3 * i + 1] = i < 600 ? 0.0 : 1.0;
            p[3 * i + 2] = 0.0;
        }
        run_case("geometric sequence (deep tree)", p, n, 3, 1, 1e-3, 60, 1);
        run_case("geometric sequence (deep tree)", p, n, 3, 1, 1.0, 20, 0);
        free(p);
        n = 6000; /* deep below the threads' top levels */
        p = malloc((size_t)3 * n * sizeof(double));
        for (int i = 0; i < n; i++) {
            p[3 * i] = ldexp(1.0, -(i % 900));
            p[3 * i + 1] = (double)(i / 900);
            p[3 * i + 2] = 0.0;
        }
        check_threaded("geometric sequence (deep tree)", p, n, 3, 1, 1e-3);
        free(p);
    }
    return check_summary("test_kdtree");
}
