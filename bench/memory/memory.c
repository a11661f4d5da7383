/* memory.c - bytes per particle of a sphere scene: N spheres on a simple cubic lattice
 * (touching neighbours at 1 % overlap, so every particle has contacts and history),
 * Hertz-Mindlin, prepared and stepped 10 times; prints the resident memory growth per
 * particle, its peak (VmHWM, which the store's growth while particles are added and the
 * list's build reach), and the part of it that the particle store, neighbour list and
 * contact records account for.   bench_memory [N [STEPS]]   (default 1000000, 0)
 * With STEPS > 0 it then times STEPS more steps and prints particle-steps/s: the cost per
 * particle-step against N (every particle in contact with its 6 lattice neighbours). */
#include "floe.h"
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* the peak resident size so far (VmHWM), bytes */
static size_t rss_peak(void) {
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long kb = 0;
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "VmHWM: %ld kB", &kb) == 1) break;
    if (f) fclose(f);
    return (size_t)kb * 1024;
}

static size_t rss(void) {
    FILE *f = fopen("/proc/self/statm", "r");
    long a = 0, r = 0;
    if (f) { if (fscanf(f, "%ld %ld", &a, &r) != 2) r = 0; fclose(f); }
    return (size_t)r * 4096;
}

int main(int argc, char **argv) {
    long N = argc > 1 ? atol(argv[1]) : 1000000, steps = argc > 2 ? atol(argv[2]) : 0;
    int side = (int)ceil(cbrt((double)N));
    size_t r0 = rss();
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"glass", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    long n = 0;
    for (int k = 0; k < side && n < N; k++)
        for (int j = 0; j < side && n < N; j++)
            for (int i = 0; i < side && n < N; i++, n++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g;
                floe_v3_set(p.x, i * 0.00198, j * 0.00198, k * 0.00198);
                if (floe_world_add_particle(w, &p) < 0) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
            }
    if (floe_world_prepare(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
    for (int s = 0; s < 10; s++) floe_world_step(w);
    size_t r1 = rss();
    floe_memory_stats ms;
    floe_neighbor_stats ns;
    floe_world_memory(w, &ms);
    floe_world_neighbor_stats(w, &ns);
    double store = (double)ms.particles / n, nl = (double)ms.neighbor_list / n, cont = (double)ms.contacts / n;
    printf("memory: N=%ld spheres, %d candidate pairs, %d contacts: RSS %.0f B/particle, peak %.0f "
           "(particle store %.0f, neighbour list + history %.0f, contact records %.0f)\n",
           n, ns.pairs, floe_world_contact_count(w), (double)(r1 - r0) / n, (double)(rss_peak() - r0) / n, store, nl,
           cont);
    if (steps > 0) {
        double t0 = now();
        for (long s = 0; s < steps; s++)
            if (floe_world_step(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
        double dt = now() - t0;
        printf("time: N=%ld steps=%ld loop_s=%.3f particle_steps_per_s=%.3e ns_per_particle_step=%.1f contacts=%d\n", n,
               steps, dt, (double)n * steps / dt, 1e9 * dt / ((double)n * steps), floe_world_contact_count(w));
    }
    floe_world_destroy(w);
    return 0;
}
