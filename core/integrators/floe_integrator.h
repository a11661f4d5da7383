/* floe_integrator.h - time integrators as classes (issue #11): a step function, capability
 * flags, a critical-step factor, and the reason a capability is missing. Compatibility with
 * the adaptive controller, the staggered PD-DEM scheme and beam bonds follows from the
 * flags (no if-chain over names); the adaptive controller wraps the step of any class that
 * can undo a trial step (core/integrators/adaptive.c). Each class is registered under the
 * registry kind "integrator" (floe_registry.h: name, title, doc, source, parameters), so
 * `floe help integrator rk2` documents it and the scene's time.integrator is looked up
 * there. The driver that runs them (prepare, step, run, the energy watchdog) is this layer,
 * core/integrators, above the world (docs/architecture.md). */
#ifndef FLOE_INTEGRATOR_H
#define FLOE_INTEGRATOR_H

#include "floe_world.h"

enum {
    /* a trial step can be undone (positions, velocities, momenta, providers' state): the
     * adaptive controller may wrap it */
    FLOE_INTEGRATOR_RESTORES = 1,
    /* kicks and drifts as velocity Verlet (r-RESPA): the staggered PD-DEM scheme may
     * sub-cycle it */
    FLOE_INTEGRATOR_KICK_DRIFT = 2,
    /* stable for undamped springs at the critical step: beam bonds may be integrated */
    FLOE_INTEGRATOR_UNDAMPED_BONDS = 4,
    /* closes each step with a half kick h F / m (velocity Verlet, leapfrog): the energy
     * watchdog's conserved form subtracts that kick's energy (shadow term) */
    FLOE_INTEGRATOR_HALF_KICK = 8
};

typedef struct floe_integrator_class {
    int version;              /* 1 */
    const char *name;         /* the scene's time.integrator */
    int id;                   /* floe_integrator (floe_world_def.integrator); -1: not a world
                                 integrator (the Newmark-beta solvers of floe_newmark.h) */
    unsigned flags;           /* FLOE_INTEGRATOR_* */
    int (*step)(floe_world *w); /* NULL: not a world integrator */
    /* why each missing capability is missing (for the message that refuses a scene) */
    const char *why_not_restores, *why_not_kick_drift, *why_not_bonds;
    /* the stable step as a multiple of the world's critical estimate (floe_dt_estimates):
     * the step chosen (dt: auto), the largest step accepted without allow_unstable_dt and
     * the adaptive controller's dt_max default are this factor times the estimate.
     * INFINITY: unconditionally stable (implicit Newmark on a linear system). */
    double dt_factor;
} floe_integrator_class;

/* The class of a floe_integrator value, or NULL (built-ins, then registered classes). */
const floe_integrator_class *floe_integrator_class_of(int integrator);

/* The registry's constructor of an "integrator" entry (floe_registry_entry.create, cast):
 * returns the class. */
typedef const floe_integrator_class *(*floe_integrator_class_fn)(void);

/* Registers the built-in integrators (velocity_verlet, leapfrog, rk2, and the Newmark-beta
 * solvers newmark_explicit, newmark_implicit, documented there) under the kind
 * "integrator"; a second call does nothing. */
int floe_register_builtin_integrators(char *err, size_t errlen);

#endif
