/* test_quick_checks.c - a velocity-Verlet step stops on a particle that is not finite or
 * moves too far, naming it (core/integrators/step.c: the drift's quick checks, the messages
 * after the forces). A row of 300 free spheres (3 blocks of the threads' loops) in free
 * flight; particle K is corrupted through the store (as a caller writing the arrays of
 * floe_particles_view would, or an overflow), then one step:
 *  - its position NaN, or +infinity: "non-finite position", particle K;
 *  - its velocity NaN: "non-finite" (position: the drift carried it), particle K;
 *  - its velocity so large that it moves 10 of its radii in the step: "moved", particle K;
 *  - the same with a second bad particle after it: the first one is named;
 *  - a clean world steps on (the negative control);
 * each with 1 and 2 threads (the same message). Without the drift's position check the two
 * position cases step on silently (tried). */
#include "check.h"
#include "floe.h"
#include "world_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

enum { N = 300, K = 137 };
static const double R = 1e-3;

static floe_world *row(int threads) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.dt = 1e-6;
    d.gravity[2] = -9.81;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"glass", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5));
    int gs = floe_world_add_geometry(w, floe_sphere_create(R));
    for (int k = 0; k < N; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = gs;
        p.x[0] = 3 * R * k;
        p.v[1] = 0.01 * k;
        floe_world_add_particle(w, &p);
    }
    floe_world_set_threads(w, threads);
    for (int s = 0; s < 5; s++) floe_world_step(w);
    return w;
}

/* one step after bad(w); the error names particle `who` and says `what` */
static void expect(int threads, const char *label, void (*bad)(floe_world *), int who, const char *what) {
    floe_world *w = row(threads);
    if (bad) bad(w);
    const int rc = floe_world_step(w);
    const char *e = floe_world_last_error(w);
    if (!what) {
        CHECK(rc == FLOE_OK, "%d thread(s), %s: the step goes on (%s)", threads, label, e);
    } else {
        char name[32];
        snprintf(name, sizeof name, "particle %d ", who);
        CHECK(rc == FLOE_EUNSTABLE && strstr(e, name) && strstr(e, what),
              "%d thread(s), %s: stops naming %s(%s): rc %d, \"%s\"", threads, label, name, what, rc, e);
    }
    floe_world_destroy(w);
}

static void x_nan(floe_world *w) { w->p.x[3 * K + 1] = NAN; }
static void x_inf(floe_world *w) { w->p.x[3 * K + 2] = INFINITY; }
static void v_nan(floe_world *w) { w->p.v[3 * K] = NAN; }
static void v_fast(floe_world *w) { w->p.v[3 * K + 2] = 10 * R / w->dt; }
static void two_bad(floe_world *w) {
    w->p.v[3 * (K + 100)] = NAN;
    w->p.v[3 * K + 2] = -10 * R / w->dt;
}

int main(void) {
    for (int t = 1; t <= 2; t++) {
        expect(t, "clean", NULL, -1, NULL);
        expect(t, "position NaN", x_nan, K, "non-finite position");
        expect(t, "position infinite", x_inf, K, "non-finite position");
        expect(t, "velocity NaN", v_nan, K, "non-finite"); /* the drift made its position NaN too */
        expect(t, "10 radii in a step", v_fast, K, "moved");
        expect(t, "two bad particles", two_bad, K, "moved");
    }
    return check_summary("test_quick_checks");
}
