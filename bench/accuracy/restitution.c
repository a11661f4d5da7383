/* restitution.c - accuracy versus speed of the time step: a head-on Hertz-Mindlin
 * collision of two glass beads (R = 1 mm, E = 1e7 Pa, v = 0.1 m/s each) for e = 0.3, 0.5,
 * 0.9 at dt = safety x critical; prints the steps per collision and the restitution error
 * for each safety factor (the cost of a run is proportional to 1/safety). */
#include "floe.h"
#include <stdio.h>

/* particle i's velocity (public view; read after each step) */
static const double *vel_of(const floe_world *w, int i) {
    floe_particles_view pv;
    floe_world_particles(w, &pv);
    return pv.v + 3 * i;
}

static double run(double e_in, double safety, long *steps_in_contact) {
    floe_world_def d = floe_default_world_def();
    d.dt_safety = safety;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"glass", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, e_in, 0.0));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    for (int k = 0; k < 2; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        floe_v3_set(p.x, k * 0.00201, 0, 0);
        floe_v3_set(p.v, k ? -0.1 : 0.1, 0, 0);
        floe_world_add_particle(w, &p);
    }
    floe_world_prepare(w);
    long in = 0;
    for (int s = 0; s < 1000000; s++) {
        floe_world_step(w);
        in += floe_world_contact_count(w) > 0;
        if (vel_of(w, 0)[0] < 0 && floe_world_contact_count(w) == 0) break;
    }
    double e = (vel_of(w, 1)[0] - vel_of(w, 0)[0]) / 0.2;
    *steps_in_contact = in;
    floe_world_destroy(w);
    return e;
}

int main(void) {
    double es[3] = {0.3, 0.5, 0.9}, safety[6] = {0.8, 0.4, 0.2, 0.1, 0.05, 0.025};
    printf("%-8s %-6s %-18s %-14s\n", "safety", "e", "steps/collision", "rel. error");
    for (int a = 0; a < 6; a++)
        for (int k = 0; k < 3; k++) {
            long n;
            double e = run(es[k], safety[a], &n);
            printf("%-8.3f %-6.1f %-18ld %-14.2e\n", safety[a], es[k], n, fabs(e - es[k]) / es[k]);
        }
    return 0;
}
