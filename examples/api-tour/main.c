/* api-tour: the C API in one program (docs/api.md walks through it): a world, two
 * materials with three laws (Hertz-Mindlin, linear, and a new law written here through
 * the contact-law vtable), a wall, ten beads, an energy observer, a run, the result. */
#include "floe.h"
#include <stdio.h>
#include <stdlib.h>

/* a new contact law: a linear spring without friction or damping */
typedef struct { floe_contact_law base; double k; } spring_law;

static int spring_force(const floe_contact_law *law, const floe_contact *c, double *history,
                        floe_contact_result *out) {
    (void)history;
    double k = ((const spring_law *)law)->k;
    for (int a = 0; a < 3; a++) {
        out->force[a] = -k * c->depth * c->n[a];   /* on i, pushing it away from j */
        out->torque_i[a] = out->torque_j[a] = 0;
    }
    out->energy = 0.5 * k * c->depth * c->depth;
    out->dissipation = 0;
    out->fn = k * c->depth;
    return FLOE_OK;
}
static void spring_stiffness(const floe_contact_law *law, double r_eff, double m_eff, double depth,
                             double *kn, double *cn) {
    (void)r_eff; (void)m_eff; (void)depth;
    *kn = ((const spring_law *)law)->k;
    *cn = 0;
}
static const floe_contact_law_class spring_class = {1, "spring", 0, spring_force, spring_stiffness, NULL, NULL, NULL};

int main(void) {
    char err[256];
    floe_world_def def = floe_default_world_def();      /* dim 3, dt 0 = automatic */
    def.gravity[2] = -9.81;
    floe_world *w = floe_world_create(&def, err, sizeof err);
    if (!w) { fprintf(stderr, "%s\n", err); return 1; }

    floe_material glass = {"glass", 2500, 1e7, 0.3};     /* name, density, E, nu */
    int mat = floe_world_add_material(w, &glass);
    if (mat < 0) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&glass, &glass, 0.5, 0.5));

    floe_material rubber = {"rubber", 1100, 1e6, 0.45};
    int mat2 = floe_world_add_material(w, &rubber);
    spring_law *sl = calloc(1, sizeof *sl); /* zeroed: base.friction = 0 */
    sl->base.klass = &spring_class;
    sl->k = 500;
    floe_world_set_law(w, mat2, mat2, &sl->base);           /* the world frees it (free()) */
    floe_world_set_law(w, mat, mat2, floe_linear_law_create(500, 250, 0.01, 0.005, 0.4));

    int bead = floe_world_add_geometry(w, floe_sphere_create(0.001));
    double o[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    floe_world_add_wall(w, o, up, mat, FLOE_FIXED);
    for (int k = 0; k < 10; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = bead;
        p.material = k % 2 ? mat : mat2;
        p.x[0] = 0.0001 * k; p.x[2] = 0.002 + 0.0025 * k;
        floe_world_add_particle(w, &p);
    }
    floe_observer *energy = floe_energy_tracker_create("energy.csv", err, sizeof err);
    energy->period_steps = 100;
    floe_world_add_observer(w, energy);

    int rc = floe_world_run(w, 0.2, NULL, NULL);          /* prepares, runs, flushes observers */
    if (rc) fprintf(stderr, "run failed (%s): %s\n", floe_strerror(rc), floe_world_last_error(w));
    floe_particle_state s;
    floe_world_get_particle(w, 1, &s);
    printf("t = %.3f s, dt = %.3g s, particle 1 at z = %.5f m, balance error %.1e\n", floe_world_time(w),
           floe_world_dt(w), s.x[2], floe_world_energy_balance_error(w));
    floe_world_destroy(w);
    return rc ? 1 : 0;
}
