/* test_extremes.c - head-on Hertz-Mindlin collisions at the extremes of stiffness
 * (E = 1e3 .. 1e12 Pa), speed (1e-6 .. 1e3 m/s) and mass ratio (1 .. 1e6), each with the
 * automatic time step: the run must finish with finite numbers and restitute e = 0.5
 * within 5 % (or stop with a clear error naming the particles, never NaN output). Too soft
 * for the speed (E = 1e3 Pa at 1 m/s: the spheres would pass through each other) must
 * stop with a message, not bounce backwards. */
#include "floe.h"
#include "world_internal.h"
#include "check.h"
#include <string.h>

static void collide(double E, double v0, double ratio) {
    floe_world_def d = floe_default_world_def();
    d.dt_safety = 0.1;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 2500, E, 0.3}, heavy = {"h", 2500 * ratio, E, 0.3};
    floe_world_add_material(w, &m);
    floe_world_add_material(w, &heavy);
    floe_world_set_law(w, 0, 1, floe_hertz_mindlin_law_create(&m, &heavy, 0.5, 0.0));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.01));
    floe_particle_def a = floe_default_particle_def(), b = floe_default_particle_def();
    a.geometry = b.geometry = g;
    b.material = 1;
    floe_v3_set(a.v, v0, 0, 0);
    floe_v3_set(b.x, 0.02, 0, 0); /* touching: the collision starts at once */
    floe_world_add_particle(w, &a);
    floe_world_add_particle(w, &b);
    int rc = floe_world_prepare(w);
    long steps = 0, in_contact = 0;
    while (rc == FLOE_OK && steps < 2000000) {
        rc = floe_world_step(w);
        steps++;
        if (w->ncontacts) in_contact++;
        if (in_contact && !w->ncontacts) break;
    }
    char what[128];
    snprintf(what, sizeof what, "E=%.0e v=%.0e mass ratio %.0e", E, v0, ratio);
    if (rc) {
        CHECK(strstr(floe_world_last_error(w), "particle") != NULL, "%s: failed without naming a particle: %s", what,
              floe_world_last_error(w));
        printf("  %s: stopped: %s\n", what, floe_world_last_error(w));
    } else {
        double va = w->p.v[0], vb = w->p.v[3];
        double e = (vb - va) / v0;
        CHECK(isfinite(va) && isfinite(vb), "%s: non-finite velocities", what);
        char w2[320];
        snprintf(w2, sizeof w2, "%s: restitution (tol 5%%, %ld steps in contact)", what, in_contact);
        CHECK_NEAR(e, 0.5, 0.05, w2);
    }
    floe_world_destroy(w);
}

int main(void) {
    double Es[3] = {1e3, 1e7, 1e12}, vs[3] = {1e-6, 1.0, 1e3}, ratios[3] = {1, 1e3, 1e6};
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) collide(Es[a], vs[b], 1.0);
    for (int c = 1; c < 3; c++) collide(1e7, 1.0, ratios[c]);
    return check_summary("test_extremes");
}
