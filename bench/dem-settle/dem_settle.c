/* dem_settle.c - floe side of bench/dem-settle: reads the LIGGGHTS data file made by
 * gen_data.py and runs the same physics (Hertz-Mindlin, E = 1e7 Pa, nu = 0.3, e = 0.5,
 * mu = 0.5, gravity, six walls, dt = 1e-5 s) for NSTEPS steps, one thread. Prints the loop
 * time, particle-steps/s, contacts, neighbour rebuilds and memory per particle.
 *   dem_settle settle.data [NSTEPS [WARMUP]]
 * WARMUP steps (default 0) run before the timed NSTEPS, untimed: to time (or profile) the
 * settled bed alone. With FLOE_BENCH_CKPT=path the warmed-up state is saved there, and
 * loaded from there on later runs (same data file and WARMUP), skipping the warm-up. */
#include "floe.h"
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static size_t rss_bytes(void) {
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0, res = 0;
    if (f) { if (fscanf(f, "%ld %ld", &pages, &res) != 2) res = 0; fclose(f); }
    return (size_t)res * 4096;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: dem_settle settle.data [NSTEPS]\n"); return 2; }
    long nsteps = argc > 2 ? atol(argv[2]) : 5000, warmup = argc > 3 ? atol(argv[3]) : 0;
    FILE *f = fopen(argv[1], "r");
    if (!f) { perror(argv[1]); return 1; }
    size_t rss0 = rss_bytes();
    floe_world_def def = floe_default_world_def();
    def.dt = 1e-5;
    def.gravity[2] = -9.81;
    def.skin = 0.0005;   /* LIGGGHTS: neighbor 0.0005 bin */
    char err[256];
    floe_world *w = floe_world_create(&def, err, sizeof err);
    floe_material m = {"glass", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    double L[3] = {0.062, 0.062, 0.1};
    for (int a = 0; a < 3; a++) {
        double p0[3] = {0, 0, 0}, p1[3] = {0, 0, 0}, n0[3] = {0, 0, 0}, n1[3] = {0, 0, 0};
        p1[a] = L[a]; n0[a] = 1; n1[a] = -1;
        floe_world_add_wall(w, p0, n0, 0, FLOE_FIXED);
        floe_world_add_wall(w, p1, n1, 0, FLOE_FIXED);
    }
    char line[512];
    int mode = 0, n = 0;
    double (*vel)[3] = NULL;
    int nat = 0;
    while (fgets(line, sizeof line, f)) {
        if (strstr(line, "atoms") && !nat) nat = atoi(line);
        if (!strncmp(line, "Atoms", 5)) { mode = 1; vel = calloc(nat, sizeof *vel); continue; }
        if (!strncmp(line, "Velocities", 10)) { mode = 2; continue; }
        int id, type;
        double d, rho, x, y, z;
        if (mode == 1 && sscanf(line, "%d %d %lf %lf %lf %lf %lf", &id, &type, &d, &rho, &x, &y, &z) == 7) {
            floe_particle_def p = floe_default_particle_def();
            p.geometry = g;
            floe_v3_set(p.x, x, y, z);
            floe_world_add_particle(w, &p);
            n++;
        } else if (mode == 2 && sscanf(line, "%d %lf %lf %lf", &id, &x, &y, &z) == 4 && id >= 1 && id <= nat) {
            floe_v3_set(vel[id - 1], x, y, z);
        }
    }
    fclose(f);
    for (int i = 0; i < n; i++) floe_world_set_velocity(w, i + 6, vel[i], NULL);
    free(vel);
    const char *ckpt = getenv("FLOE_BENCH_CKPT");
    FILE *ck = ckpt && warmup > 0 ? fopen(ckpt, "rb") : NULL;
    if (ck) {
        fclose(ck);
        if (floe_world_checkpoint_load(w, ckpt, (uint64_t)warmup, "dem-settle", err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", ckpt, err);
            return 1;
        }
    } else {
        if (floe_world_prepare(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
        for (long s = 0; s < warmup; s++)
            if (floe_world_step(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
        if (ckpt && warmup > 0 && floe_world_checkpoint_save(w, ckpt, (uint64_t)warmup, "dem-settle", err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", ckpt, err);
            return 1;
        }
    }
    if (warmup > 0) fprintf(stderr, "warm-up of %ld steps done\n", warmup);
    double t0 = now();
    for (long s = 0; s < nsteps; s++)
        if (floe_world_step(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
    double loop = now() - t0;
    size_t rss1 = rss_bytes();
    floe_energy e = floe_world_energy(w);
    floe_neighbor_stats ns;
    floe_world_neighbor_stats(w, &ns);
    printf("floe dem-settle: N=%d warmup=%ld steps=%ld dt=%g loop_s=%.3f particle_steps_per_s=%.3e contacts=%d "
           "pairs=%d rebuilds=%ld ke=%.4e rss_per_particle=%.0f B\n",
           n, warmup, nsteps, floe_world_dt(w), loop, (double)n * nsteps / loop, floe_world_contact_count(w), ns.pairs, ns.rebuilds,
           e.kinetic_trans, (double)(rss1 - rss0) / n);
    floe_world_destroy(w);
    return 0;
}
