/* kdtree_bench.c - floe_kdtree build + fixed-radius search for every point; the floe side
 * of the kdtree-nanoflann peer benchmark (nanoflann_bench.cpp is the same program over
 * nanoflann 1.4.3). Single thread.
 * Usage: kdtree_bench N LEAF [REPS] [TARGET_MEAN]
 *   N uniformly random points in [0,1)^3 (splitmix64, seed 42: the same points as
 *   nanoflann_bench), radius calibrated (untimed) so that the mean neighbour count, self
 *   included, is ~TARGET_MEAN (default 30). Timed: build (median of REPS), a radius query
 *   for all N points in generation (random) order and in tree (leaf) order (median of REPS
 *   each). The index sum of the results is a checksum. Memory: bytes allocated by the build
 *   (glibc mallinfo2), per point; floe's tree holds its own copy of the coordinates. */
#define _GNU_SOURCE
#include <malloc.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "floe_kdtree.h"

static uint64_t rng_state;
static uint64_t splitmix64(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}
static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

#define CAP 4096

int main(int argc, char **argv)
{
    if (argc < 3) { fprintf(stderr, "usage: %s N LEAF [REPS] [TARGET_MEAN]\n", argv[0]); return 2; }
    const int N = atoi(argv[1]);
    const int leaf = atoi(argv[2]);
    const int reps = argc > 3 ? atoi(argv[3]) : 3;
    const double target = argc > 4 ? atof(argv[4]) : 30.0;
    if (N < 1 || leaf < 1 || reps < 1 || reps > 100) { fprintf(stderr, "bad arguments\n"); return 2; }

    double *p = malloc((size_t)3 * (size_t)N * sizeof *p);
    int *res = malloc(CAP * sizeof *res);
    if (!p || !res) { fprintf(stderr, "out of memory\n"); return 1; }
    rng_state = 42;
    for (size_t i = 0; i < 3 * (size_t)N; i++) p[i] = (double)(splitmix64() >> 11) * 0x1.0p-53;

    /* radius for the target mean count: bulk estimate, then calibrate on a sample */
    double r = cbrt(3.0 * target / (4.0 * M_PI * (double)N));
    {
        floe_kdtree *t = floe_kdtree_build(p, N, 3, leaf);
        if (!t) { fprintf(stderr, "build failed\n"); return 1; }
        for (int it = 0; it < 3; it++) {
            int S = N < 20000 ? N : 20000;
            size_t tot = 0;
            for (int i = 0; i < S; i++)
                tot += (size_t)floe_kdtree_radius(t, &p[3 * (size_t)i * (size_t)(N / S)], r, res, CAP);
            double m = (double)tot / (double)S;
            r *= cbrt(target / m);
        }
        floe_kdtree_destroy(t);
    }

    double tb[100], tq[100], tqs[100], mem_per_pt = 0, checksum = 0;
    size_t total = 0;
    for (int rep = 0; rep < reps; rep++) {
        struct mallinfo2 m0 = mallinfo2();
        double t0 = now();
        floe_kdtree *t = floe_kdtree_build(p, N, 3, leaf);
        double t1 = now();
        if (!t) { fprintf(stderr, "build failed\n"); return 1; }
        struct mallinfo2 m1 = mallinfo2();
        mem_per_pt = ((double)(m1.uordblks + m1.hblkhd) - (double)(m0.uordblks + m0.hblkhd)) / (double)N;
        tb[rep] = t1 - t0;

        size_t tot = 0;
        double cs = 0;
        t0 = now();
        for (int i = 0; i < N; i++) {
            int k = floe_kdtree_radius(t, &p[3 * (size_t)i], r, res, CAP);
            if (k > CAP) { fprintf(stderr, "ERROR: buffer too small (%d)\n", k); return 1; }
            tot += (size_t)k;
            for (int j = 0; j < k; j++) cs += res[j];
        }
        t1 = now();
        tq[rep] = t1 - t0;
        total = tot;
        checksum = cs;

        /* queries in tree (leaf) order: spatially coherent, as in a DEM/PD neighbour build */
        const int *order = floe_kdtree_order(t);
        size_t tot2 = 0;
        t0 = now();
        for (int k2 = 0; k2 < N; k2++) {
            int k = floe_kdtree_radius(t, &p[3 * (size_t)order[k2]], r, res, CAP);
            tot2 += (size_t)k;
            for (int j = 0; j < k; j++) cs += res[j];
        }
        t1 = now();
        tqs[rep] = t1 - t0;
        if (tot2 != tot) { fprintf(stderr, "ERROR: order-dependent count %zu vs %zu\n", tot, tot2); return 1; }

        if (rep == 0) { /* brute-force check of 200 queries (floe keeps dist <= r) */
            for (int q = 0; q < 200; q++) {
                size_t i = ((size_t)q * 7919) % (size_t)N, bf = 0;
                for (size_t j = 0; j < (size_t)N; j++) {
                    double dx = p[3 * i] - p[3 * j], dy = p[3 * i + 1] - p[3 * j + 1], dz = p[3 * i + 2] - p[3 * j + 2];
                    if (dx * dx + dy * dy + dz * dz <= r * r) ++bf;
                }
                size_t k = (size_t)floe_kdtree_radius(t, &p[3 * i], r, res, CAP);
                if (k != bf) { fprintf(stderr, "ERROR: query %zu: kd-tree %zu vs brute force %zu\n", i, k, bf); return 1; }
            }
        }
        floe_kdtree_destroy(t);
    }
    double b = median(tb, reps), q = median(tq, reps), qs = median(tqs, reps);
    printf("floe_kdtree N=%d leaf=%d reps=%d radius=%.6g mean_neighbours=%.2f build_s=%.4f query_s=%.4f "
           "queries_per_s=%.3e query_sorted_s=%.4f queries_sorted_per_s=%.3e neighbours_per_s=%.3e "
           "mem_bytes_per_point=%.1f checksum=%.0f\n",
           N, leaf, reps, r, (double)total / (double)N, b, q, (double)N / q, qs, (double)N / qs,
           (double)total / q, mem_per_pt, checksum);
    free(p);
    free(res);
    return 0;
}
