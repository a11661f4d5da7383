/* pingpong.c - the cost of moving a cache line between two cores on this machine: two
 * threads hand a counter back and forth through one atomic (each waits for the other's
 * increment, then adds its own), for ROUNDS hand-overs; prints the nanoseconds per one-way
 * hand-over. That is the price of every line a two-thread run shares between its threads
 * (a particle written on one core and read on the other), and on a VM it moves when the
 * host places the two vCPUs elsewhere (same L3 or not): machine/run.sh prints it with the
 * headroom, so that a sitting's two-thread figures can be read against it.
 *   bench_pingpong [ROUNDS]   (default 2000000) */
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static _Alignas(64) atomic_long ball;
static long rounds;

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* thread `side` (0 or 1) moves the ball when it is even (side 0) or odd (side 1) */
static void *player(void *arg) {
    const long side = (long)(size_t)arg;
    for (long r = 0; r < rounds; r++) {
        const long want = 2 * r + side;
        while (atomic_load_explicit(&ball, memory_order_acquire) != want) {}
        atomic_store_explicit(&ball, want + 1, memory_order_release);
    }
    return NULL;
}

int main(int argc, char **argv) {
    rounds = argc > 1 ? atol(argv[1]) : 2000000;
    if (rounds < 1) { fprintf(stderr, "usage: bench_pingpong [ROUNDS >= 1]\n"); return 2; }
    atomic_store(&ball, 0);
    pthread_t a, b;
    const double t0 = now();
    if (pthread_create(&a, NULL, player, (void *)(size_t)0) || pthread_create(&b, NULL, player, (void *)(size_t)1)) {
        fprintf(stderr, "pthread_create failed\n");
        return 1;
    }
    pthread_join(a, NULL);
    pthread_join(b, NULL);
    const double t = now() - t0;
    printf("pingpong: handovers=%ld seconds=%.3f ns_per_handover=%.1f\n", 2 * rounds, t, 1e9 * t / (2.0 * rounds));
    return 0;
}
