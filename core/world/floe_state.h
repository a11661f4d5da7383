/* floe_state.h - generic state objects evolved in time by RK2 (ParticLS §4.1, eq 21).
 * A state object is anything with an ODE dy/dt = rhs(t, y): a growing radius, a
 * temperature, a damage variable. GSL odeiv2-style class + instance. */
#ifndef FLOE_STATE_H
#define FLOE_STATE_H

#include "floe_world.h"

typedef struct floe_state_class {
    int version;   /* 1, or 2 with probe */
    const char *name;
    size_t (*size)(const floe_state *s);
    void (*get)(const floe_state *s, double *y);
    /* set may change the world (e.g. a particle's radius); it returns a status */
    int (*set)(floe_state *s, floe_world *w, const double *y);
    int (*rhs)(const floe_state *s, const floe_world *w, double t, const double *y, double *dydt);
    void (*destroy)(floe_state *s);
    /* version 2, optional (NULL, or version 1: an RK2 midpoint's forces see the state of the
     * step's start, which is first order in the coupling of a state and the forces; a state
     * that changes masses or radii should have one): probe(s, w, y) puts what the forces
     * read (a particle's radius and mass) at y, the state at the RK2 midpoint, for that
     * force evaluation only; probe(s, w, NULL) then puts back exactly what was there (the
     * states are put back in reverse order). A probe that fails must change nothing.
     * Between the two the world does not step, rebuild or write.
     * RK2 hands set() the particles' midpoint L and v (the state may scale them with a
     * grown inertia or mass: docs/models.md), velocity Verlet, leapfrog and the staggered
     * scheme the half step's. */
    int (*probe)(floe_state *s, floe_world *w, const double *y);
} floe_state_class;

struct floe_state {
    const floe_state_class *klass;
};

/* Radius of a sphere particle growing as dR/dt = rate (ParticLS §5.2). The particle must
 * own its sphere geometry (the state clones it on creation). Mass and inertia stay those
 * of the initial particle unless update_mass is 1. On a world split over MPI ranks every
 * rank keeps it (keyed by the particle's index at creation, its global id) and sets its
 * own copy of the particle, owned or ghost; a user's state class is refused there
 * (docs/parallel.md, "RK2 steps and state objects"). */
floe_state *floe_growing_radius_create(floe_world *w, int particle, double rate, int update_mass);
/* Generic scalar ODE dy/dt = f(t, y, user) for tests and user models. */
typedef double (*floe_scalar_rhs_fn)(double t, double y, void *user);
floe_state *floe_scalar_state_create(double y0, floe_scalar_rhs_fn f, void *user);
double floe_scalar_state_value(const floe_state *s);

#endif
