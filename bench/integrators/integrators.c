/* integrators.c - accuracy against cost of the integrators (docs/integrators.md): for a DEM
 * scene and a PD scene, each integrator (velocity Verlet, leapfrog, RK2, adaptive velocity
 * Verlet and RK2) at several time-step factors (fraction of the critical estimate) is run
 * to t_end and compared with a reference of the same scene at 0.001 x critical (velocity
 * Verlet); the error is the largest position difference over all particles, relative to
 * the particle radius. Fixed steps are t_end / N (every run ends exactly at t_end), N the
 * smallest with dt <= factor x critical. CPU time of the process (the machine may be
 * shared), the fastest of REPEATS runs.
 *
 *   DEM: 25 chains (5 x 5, 3 mm apart) of 12 Hertz-Mindlin glass spheres (R 1 mm, E 1e7 Pa,
 *        e 0.8, friction 0.3) at 0.1 mm gaps, each hit by a 13th at 1 m/s with a slight
 *        offset (so the contacts also slide and roll), 2 ms.
 *   PD:  a PMB bar 30 x 4 x 4 points (dx 1 mm, 22 GPa), its first three layers moving at
 *        0.1 m/s, a pulse running along it, 4 us.
 *
 *   bench_integrators [REPEATS]   prints csv,scene,integrator,factor,steps,cpu_s,error */
#include "floe.h"
#include "floe_pd.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double cpu(void) {
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static floe_world *dem_scene(const floe_world_def *d0) {
    floe_world_def d = *d0;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"glass", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.3));
    int g = floe_world_add_geometry(w, floe_sphere_create(1e-3));
    for (int c = 0; c < 25; c++)
        for (int i = 0; i < 13; i++) {
            floe_particle_def p = floe_default_particle_def();
            p.geometry = g;
            floe_v3_set(p.x, i * 2.1e-3, (c % 5) * 3e-3, (c / 5) * 3e-3);
            if (i == 0) {
                p.v[0] = 1.0;
                p.x[1] += 2e-4 * (1 + c % 3); /* off-centre: oblique contacts, friction, rotation */
            }
            floe_world_add_particle(w, &p);
        }
    return w;
}

static floe_world *pd_scene(const floe_world_def *d0) {
    floe_world_def d = *d0;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rock", 2200, 22.35e9, 0.25};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.3));
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = 1e-3;
    r.horizon_factor = 3;
    floe_v3_set(r.hi, 30e-3, 4e-3, 4e-3);
    floe_pd_body *b = NULL;
    floe_pd_body_create(&b, &r);
    floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
    floe_pd_set_material(b, &pm);
    int f0;
    floe_world_add_pd_body(w, b, 0, NULL, &f0);
    for (int i = 0; i < b->n; i++)
        if (b->X[3 * i] < 3e-3) floe_world_set_velocity(w, f0 + i, (const double[3]){0.1, 0, 0}, NULL);
    return w;
}

typedef floe_world *(*scene_fn)(const floe_world_def *);

/* run to t_end; positions into x (3n); returns the CPU time, *steps */
static double run(scene_fn sc, int integ, int adaptive, double factor, double t_end, double *x, int *n, long *steps,
                  int *rc_out) {
    floe_world_def d = floe_default_world_def();
    d.integrator = integ;
    d.adaptive = adaptive;
    d.dt_safety = factor;
    floe_world *w = sc(&d);
    if (!adaptive) { /* dt = t_end / N <= factor x critical */
        floe_world_prepare(w);
        double crit = floe_world_critical_dt(w);
        floe_world_destroy(w);
        d.dt = t_end / ceil(t_end / (factor * crit) - 1e-9);
        w = sc(&d);
    }
    double t0 = cpu();
    int rc = floe_world_run(w, t_end, NULL, NULL);
    double c = cpu() - t0;
    floe_step_stats st;
    floe_world_step_stats(w, &st);
    *steps = st.accepted;
    floe_particles_view pv;
    floe_world_particles(w, &pv);
    *n = pv.n;
    memcpy(x, pv.x, 3 * (size_t)pv.n * sizeof *x);
    *rc_out = rc;
    floe_world_destroy(w);
    return c;
}

int main(int argc, char **argv) {
    int reps = argc > 1 ? atoi(argv[1]) : 3;
    const char *names[2] = {"dem_chain", "pd_bar"};
    scene_fn scenes[2] = {dem_scene, pd_scene};
    const double t_end[2] = {2e-3, 4e-6}, radius[2] = {1e-3, 0.62e-3};
    const double factors[] = {0.025, 0.05, 0.1, 0.2, 0.4, 0.7, 1.0};
    const int nf = (int)(sizeof factors / sizeof *factors);
    struct { const char *name; int integ, adaptive; } ints[] = {
        {"velocity_verlet", FLOE_VELOCITY_VERLET, 0}, {"leapfrog", FLOE_LEAPFROG, 0}, {"rk2", FLOE_RK2, 0},
        {"adaptive_verlet", FLOE_VELOCITY_VERLET, 1}, {"adaptive_rk2", FLOE_RK2, 1}};
    for (int s = 0; s < 2; s++) {
        double *ref = malloc(3 * 8000 * sizeof *ref), *x = malloc(3 * 8000 * sizeof *x);
        int n, rc;
        long steps;
        run(scenes[s], FLOE_VELOCITY_VERLET, 0, 0.001, t_end[s], ref, &n, &steps, &rc);
        fprintf(stderr, "%s: reference %ld steps (%s)\n", names[s], steps, rc ? "failed" : "ok");
        for (int k = 0; k < 5; k++)
            for (int f = 0; f < nf; f++) {
                if (ints[k].adaptive && f > 0) continue; /* adaptive: its own steps (one run) */
                double best = INFINITY, err = 0;
                for (int r = 0; r < reps; r++) {
                    double c = run(scenes[s], ints[k].integ, ints[k].adaptive, factors[f], t_end[s], x, &n, &steps, &rc);
                    if (c < best) best = c;
                }
                for (int a = 0; a < 3 * n; a++) err = fmax(err, fabs(x[a] - ref[a]));
                printf("csv,%s,%s,%g,%ld,%.6f,%.4e,%d\n", names[s], ints[k].name, ints[k].adaptive ? 0.0 : factors[f],
                       steps, best, rc ? NAN : err / radius[s], rc);
                fflush(stdout);
            }
        free(ref);
        free(x);
    }
    return 0;
}
