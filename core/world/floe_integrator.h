/* floe_integrator.h - time integrators as classes (issue #11): a step function, capability
 * flags, and the reason a capability is missing. Compatibility with the adaptive
 * controller, the staggered PD-DEM scheme and beam bonds follows from the flags (no
 * if-chain over names). The classes live beside the world for now (core/world/step.c); the
 * driver that runs them moves to core/integrators with the next step of the redesign. */
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
    FLOE_INTEGRATOR_UNDAMPED_BONDS = 4
};

typedef struct floe_integrator_class {
    int version;              /* 1 */
    const char *name;         /* the scene's time.integrator */
    int id;                   /* floe_integrator (floe_world_def.integrator) */
    unsigned flags;           /* FLOE_INTEGRATOR_* */
    int (*step)(floe_world *w);
    /* why each missing capability is missing (for the message that refuses a scene) */
    const char *why_not_restores, *why_not_kick_drift, *why_not_bonds;
} floe_integrator_class;

/* The class of a floe_integrator value, or NULL. */
const floe_integrator_class *floe_integrator_class_of(int integrator);

#endif
