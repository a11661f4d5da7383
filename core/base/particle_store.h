/* particle_store.h - the particle store (structure of arrays, index = particle id) and the
 * per-step context that force providers receive. Internal: the layout may change; users
 * read particles through the world's accessors (floe_world.h). It sits in the base layer
 * so that providers below the world (beam bonds) take the arrays, not the world. */
#ifndef FLOE_PARTICLE_STORE_H
#define FLOE_PARTICLE_STORE_H

#include "floe_base.h"

/* Particle store: structure of arrays, index = particle id. */
typedef struct floe_particles {
    int n, cap;
    double *x;        /* 3n centre of mass */
    double *v;        /* 3n velocity */
    double *q;        /* 4n orientation body -> world */
    double *w;        /* 3n angular velocity, world frame */
    double *L;        /* 3n angular momentum, world frame (integrated variable) */
    double *f;        /* 3n force */
    double *t;        /* 3n torque */
    double *mass;     /* n */
    double *inv_mass; /* n (0 for fixed/kinematic) */
    double *inertia;  /* 3n principal moments, body frame */
    double *radius;   /* n bounding radius (infinite for walls) */
    int *geom;        /* n geometry index */
    int *material;    /* n */
    int *group;       /* n user tag ("body" in outputs) */
    unsigned char *motion; /* n floe_motion */
    unsigned char *kind;   /* n geometry kind (cached) */
    unsigned char *iso;    /* n 1 = isotropic inertia (spheres; every body in 2D) */
    double *inv_iso;       /* n 1/I of an isotropic body (iso = 1; 0 if I is 0 or infinite), else 0:
                            * the integrators' omega = L / I without a division */
    double *rdot;          /* n outward surface speed set by state objects (growing radius), m/s */
    int *pieces;           /* n convex pieces of the geometry (compound bodies > 1) */
    double *thick;         /* n ice thickness of 2D floes, m (docs/sea-ice.md): NULL until a
                            * particle is given one (floe_particle_def.thickness); then 0 for
                            * the others (none: masses and forces per metre, read as 1 m by
                            * floe_particle_thickness). Outside the block: only scenes with
                            * floes pay for it */
    void *block;           /* the one allocation the arrays above live in (world.c
                            * particles_reserve: each array starts at its own offset in
                            * the 4 KiB page, see there); NULL for a store the caller built */
} floe_particles;

/* inv_iso of particle i from its iso flag and inertia (after either changes) */
static inline void floe_particle_inv_iso_update(floe_particles *p, int i) {
    const double I0 = p->inertia[3 * i];
    p->inv_iso[i] = p->iso[i] && I0 > 0 && I0 < INFINITY ? 1.0 / I0 : 0.0;
}

/* the thickness forces and laws use for particle i: the floe's, else 1 m (per metre) */
static inline double floe_particle_thickness(const floe_particles *p, int i) {
    return p->thick && p->thick[i] > 0 ? p->thick[i] : 1.0;
}

/* What a force provider is handed for one evaluation (core/world/floe_provider.h): the store
 * (forces f and torques t are accumulated into it), the dimension, the time at the
 * evaluation, the step, and what kind of evaluation it is:
 *   stepping = 1: the forces at the end of a step; history, breakage and the energy ledger
 *                 advance by dt;
 *   stepping = 0: an evaluation that advances nothing: at prepare (hist_dt = 0), or a
 *                 probe (probe = 1, RK2's midpoint: history advanced by hist_dt and restored
 *                 by the caller through the providers' save/restore; no breakage). */
typedef struct floe_step_ctx {
    floe_particles *p;
    int dim;
    int stepping;
    double time, dt;
    double hist_dt;   /* the step contact history advances by (dt when stepping) */
    int probe;        /* RK2 midpoint: no breakage; state restored afterwards */
    int record;       /* keep a record of every contact (observers, floe_world_contacts) */
    int track_depth;  /* adaptive steps: measure the overlap change over the step */
} floe_step_ctx;

#endif
