/* floe_rng.h - the one random-number generator of floe: splitmix64 (Steele, Lea & Flood
 * 2014), deterministic per seed and the same on every platform. Used for random packings
 * (scene), beam-bond strengths and the sampling of the SDF Lipschitz check. The state is one
 * 64-bit word; a seed is any value. */
#ifndef FLOE_RNG_H
#define FLOE_RNG_H

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* the next 64 random bits */
static inline unsigned long long floe_rng_next(unsigned long long *s) {
    unsigned long long z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

/* uniform in [0, 1), 53 bits */
static inline double floe_rng_uniform(unsigned long long *s) { return (double)(floe_rng_next(s) >> 11) * 0x1.0p-53; }

/* uniform in (0, 1] (a logarithm's argument) */
static inline double floe_rng_uniform_pos(unsigned long long *s) {
    return ((double)(floe_rng_next(s) >> 11) + 1.0) * 0x1.0p-53;
}

/* a standard normal deviate (Box-Muller; two uniforms per deviate, one deviate used) */
static inline double floe_rng_normal(unsigned long long *s) {
    double u0 = floe_rng_uniform_pos(s), u1 = floe_rng_uniform_pos(s);
    return sqrt(-2.0 * log(u0)) * cos(2.0 * M_PI * u1);
}

#endif
