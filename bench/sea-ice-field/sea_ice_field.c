/* bench/sea-ice-field: a field of N Voronoi polygon floes (issue #12: 10,000 floes at >= 1e6
 * floe-steps/s on one core), stepped in three configurations of the same field so that the
 * differences give the breakdown:
 *   move      the floes and the neighbour list only (law none, no forcing);
 *   forcing   + ocean drag (a uniform current), wind drag (a vortex, pushing the floes
 *             together) and Coriolis with the geostrophic tilt;
 *   forcing10 the same with the drags integrated every 10th step (SubZero's coupling);
 *   contacts  forcing + Hopkins' ridging law between floes (detection: the polygons' overlap);
 *   contacts10 the same with the drags every 10th step (SubZero's coupling).
 * Prints floe-steps/s per configuration, ns per floe-step of forcing and of contacts, the
 * contacts and pair evaluations per step, and the heap bytes per floe (glibc mallinfo2:
 * everything the world holds, the floes' own polygons and the drag's quadrature included).
 * usage: bench_sea_ice_field [N=10000] [steps=500] [warm=200] [configuration: all] */
#include "floe.h"

#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static const char *const law_of[] = {"none", "none", "none", "hopkins, young: 1e7, thickness_max: 1.5",
                                     "hopkins, young: 1e7, thickness_max: 1.5"};

static int run(int cfg, int n, long steps, long warm, double *rate, double *contacts, double *evals, double *bytes) {
    /* floes of about 5 km: a square region of side 5 km x sqrt(n); a convergent vortex and
     * wind push them together */
    const double L = 5000.0 * sqrt((double)n);
    char scene[4096], err[1024];
    char forces[1024] = "";
    const int every = cfg == 2 || cfg == 4 ? 10 : 1;
    if (cfg >= 1)
        snprintf(forces, sizeof forces,
                 "forces:\n"
                 "  - {type: ocean_drag, velocity: [0.1, 0.05], every: %d}\n"
                 "  - {type: wind_drag, field: vortex, speed: 15, length: %g, center: [%g, %g], every: %d}\n"
                 "  - {type: coriolis, tilt: geostrophic, velocity: [0.1, 0.05]}\n",
                 every, 0.3 * L, 0.5 * L, 0.5 * L, every);
    snprintf(scene, sizeof scene,
             "dimension: 2\nmass_2d: area\ntime: {duration: 1e9, dt: 1.0, allow_unstable_dt: true}\ngravity: [0, 0]\n"
             "materials: [{name: ice, density: 920, young: 1e7, poisson: 0.3}]\n"
             "laws: [{materials: [ice, ice], model: %s}]\n"
             "bodies:\n"
             "  - floe_field: {region: {min: [0, 0], max: [%g, %g]}, count: %d, lloyd: 3, concentration: 1.0, "
             "seed: 5, thickness: 1.0, thickness_spread: 0.5}\n"
             "    material: ice\n%s",
             law_of[cfg], L, L, n, forces);
    struct mallinfo2 m0 = mallinfo2();
    floe_world *w = NULL;
    if (floe_scene_load_ex("bench.yaml", scene, NULL, 0, &w, NULL, err, sizeof err)) {
        fprintf(stderr, "scene: %s\n", err);
        return 1;
    }
    for (long s = 0; s < warm; s++)
        if (floe_world_step(w)) {
            fprintf(stderr, "step: %s\n", floe_world_last_error(w));
            return 1;
        }
    floe_detect_stats d0, d1;
    floe_world_detect_stats(w, &d0);
    double c = 0, t0 = now();
    for (long s = 0; s < steps; s++) {
        if (floe_world_step(w)) {
            fprintf(stderr, "step: %s\n", floe_world_last_error(w));
            return 1;
        }
        c += floe_world_contact_count(w);
    }
    double t = now() - t0;
    floe_world_detect_stats(w, &d1);
    struct mallinfo2 m1 = mallinfo2();
    *rate = (double)n * (double)steps / t;
    *contacts = c / (double)steps;
    *evals = (double)(d1.evaluations - d0.evaluations) / (double)steps;
    *bytes = ((double)m1.uordblks - (double)m0.uordblks) / n;
    floe_world_destroy(w);
    return 0;
}

int main(int argc, char **argv) {
    int n = argc > 1 ? atoi(argv[1]) : 10000;
    long steps = argc > 2 ? atol(argv[2]) : 500, warm = argc > 3 ? atol(argv[3]) : 200;
    char err[256];
    floe_register_builtins(err, sizeof err);
    static const char *const name[] = {"move", "forcing", "forcing10", "contacts", "contacts10"};
    double r[5], c[5], e[5], b[5];
    const char *only = argc > 4 ? argv[4] : NULL;
    for (int k = 0; k < 5; k++) {
        if (only && strcmp(only, name[k])) {
            r[k] = 1; c[k] = e[k] = b[k] = 0;
            continue;
        }
        if (run(k, n, steps, warm, r + k, c + k, e + k, b + k)) return 1;
        printf("%-8s N=%d steps=%ld floe_steps_per_s=%.4e contacts=%.1f pair_evals_per_step=%.1f bytes_per_floe=%.0f\n",
               name[k], n, steps, r[k], c[k], e[k], b[k]);
    }
    if (only) return 0;
    printf("breakdown: move %.1f ns, forcing %.1f ns (every 10th step: %.1f ns), contacts %.1f ns per floe-step "
           "(%.1f ns per contact)\n",
           1e9 / r[0], 1e9 / r[1] - 1e9 / r[0], 1e9 / r[2] - 1e9 / r[0], 1e9 / r[3] - 1e9 / r[1],
           c[3] > 0 ? (1e9 / r[3] - 1e9 / r[1]) * n / c[3] : 0.0);
    return 0;
}
