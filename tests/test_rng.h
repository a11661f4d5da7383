/* test_rng.h - deterministic random numbers for tests (xorshift64*): uniform in [0, 1) and
 * [a, b), a uniform unit vector and a uniform rotation. Define TEST_RNG_SEED (a nonzero
 * 64-bit constant) before including it; each test has its own stream. */
#ifndef FLOE_TEST_RNG_H
#define FLOE_TEST_RNG_H
#include "floe_base.h"
#include <math.h>

#ifndef TEST_RNG_SEED
#error "define TEST_RNG_SEED before including test_rng.h"
#endif

static unsigned long long rng_s = TEST_RNG_SEED;
static double urand(void) {
    rng_s ^= rng_s >> 12; rng_s ^= rng_s << 25; rng_s ^= rng_s >> 27;
    return (double)((rng_s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}
static double uni(double a, double b) { return a + (b - a) * urand(); }
static void rand_unit(double u[3]) {
    double z = 2 * urand() - 1, ph = 2 * M_PI * urand(), s = sqrt(1 - z * z);
    floe_v3_set(u, s * cos(ph), s * sin(ph), z);
}
static void rand_quat(double q[4]) {
    double u1 = urand(), u2 = urand(), u3 = urand();
    q[0] = sqrt(1 - u1) * sin(2 * M_PI * u2); q[1] = sqrt(1 - u1) * cos(2 * M_PI * u2);
    q[2] = sqrt(u1) * sin(2 * M_PI * u3); q[3] = sqrt(u1) * cos(2 * M_PI * u3);
}

#endif
