/* pump_law.h - a contact law that creates energy, for the energy watchdog's tests
 * (tests/test_watchdog.c, tests/mpi/test_mpi_watchdog.c): a linear spring with a dashpot of
 * negative coefficient, F = (k d + c v_n) n towards i; with c < 0 the dashpot pushes along
 * the motion and feeds the collision. Include after "floe.h". */
#ifndef PUMP_LAW_H
#define PUMP_LAW_H
#include <math.h>
#include <stdlib.h>

typedef struct pump_law { floe_contact_law base; double k, c; } pump_law;

static int pump_force(const floe_contact_law *law, const floe_contact *c, double *h, floe_contact_result *out) {
    (void)h;
    const pump_law *l = (const pump_law *)law;
    double fn = l->k * c->depth + l->c * c->vn;
    for (int a = 0; a < 3; a++) out->force[a] = -fn * c->n[a];
    out->energy = 0.5 * l->k * c->depth * c->depth;
    out->fn = fabs(fn);
    return FLOE_OK;
}
static void pump_stiffness(const floe_contact_law *law, double r, double m, double d, double *kn, double *cn) {
    (void)r; (void)m; (void)d;
    *kn = ((const pump_law *)law)->k;
    *cn = 0;
}
static void pump_destroy(floe_contact_law *law) { free(law); }
static const floe_contact_law_class pump_class = {1, "pump (test)", 0, pump_force, pump_stiffness, pump_destroy, NULL, NULL};

/* the law for a body of mass `mass` at stiffness k, its dashpot -zeta of critical */
static inline floe_contact_law *pump_create(double mass, double k, double zeta) {
    pump_law *l = calloc(1, sizeof *l);
    l->base.klass = &pump_class;
    l->k = k;
    l->c = -2 * zeta * sqrt(k * mass);
    return &l->base;
}
#endif
