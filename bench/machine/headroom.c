/* headroom.c - what a second core can give on this machine: a triad-like update a[i] += s b[i]
 * over N doubles (16 N bytes touched per sweep) for about 4e9 element updates, timed, printed
 * as seconds and GB/s. machine/run.sh runs one copy, then two at once (one per core): the
 * ratio of the two copies' rate to one copy's is the most any two-thread or two-rank run of a
 * loop of that kind and working-set size can gain here (2.0 on two independent cores).
 *   bench_headroom N      (N doubles per array) */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char **argv) {
    const long n = argc > 1 ? atol(argv[1]) : 400000;
    if (n < 1) { fprintf(stderr, "usage: bench_headroom N (N >= 1)\n"); return 2; }
    double *a = malloc((size_t)n * sizeof *a), *b = malloc((size_t)n * sizeof *b);
    if (!a || !b) { fprintf(stderr, "out of memory\n"); return 1; }
    for (long i = 0; i < n; i++) { a[i] = (double)i; b[i] = 1.0; }
    const long reps = 4000000000L / n > 0 ? 4000000000L / n : 1;
    const double t0 = now();
    for (long r = 0; r < reps; r++)
        for (long i = 0; i < n; i++) a[i] += 1e-9 * b[i];
    const double t = now() - t0;
    double s = 0;
    for (long i = 0; i < n; i += 4096) s += a[i]; /* the result is read: the loop stays */
    printf("headroom: n=%ld bytes=%ld seconds=%.3f gb_per_s=%.1f check=%.3g\n", n, 16 * n, t,
           24.0 * (double)reps * (double)n / 1e9 / t, s);
    free(a);
    free(b);
    return 0;
}
