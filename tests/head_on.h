/* head_on.h - the head-on Hertz-Mindlin collision of tests/test_extremes.c and
 * tests/test_extremes_dt.c: two spheres of 1 cm radius (Young's modulus E, Poisson 0.3,
 * densities 2500 and 2500 x ratio kg/m^3, restitution 0.5, no friction), touching, the
 * light one moving at v0 towards the heavy one; run with d (its dt_safety set to 0.1) until
 * they separate, at most 2e6 steps. Returns the world (the caller destroys it); *rc is the
 * last step's code and *in_contact the number of steps in contact. */
#ifndef FLOE_TEST_HEAD_ON_H
#define FLOE_TEST_HEAD_ON_H
#include "floe.h"
#include "floe.h"
#include "world_read.h"

static floe_world *head_on_collision(floe_world_def d, double E, double v0, double ratio, int *rc, long *in_contact) {
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
    *rc = floe_world_prepare(w);
    long steps = 0;
    *in_contact = 0;
    while (*rc == FLOE_OK && steps < 2000000) {
        *rc = floe_world_step(w);
        steps++;
        if (floe_world_contact_count(w)) (*in_contact)++;
        if (*in_contact && !floe_world_contact_count(w)) break;
    }
    return w;
}

#endif
