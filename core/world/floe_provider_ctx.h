/* floe_provider_ctx.h - what a force provider reads and writes in one evaluation, as a
 * stable public struct (floe_provider.h; the per-step context itself, floe_step_ctx, is
 * internal and may change).
 *
 *   static int my_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *sc,
 *                        floe_provider_out *out) {
 *       floe_provider_ctx c = floe_provider_ctx_of(sc);
 *       for (int i = 0; i < c.n; i++) if (c.motion[i] == FLOE_FREE) c.f[3 * i + 2] += ...;
 *       return FLOE_OK;
 *   }
 *
 * Arrays are indexed by particle id (the world's particle order; PD points are particles
 * too). On a world split over MPI ranks they are the rank's own particles and its ghosts,
 * by local index (floe_world_parallel_gid gives a particle's id in the scene). Forces and
 * torques are ADDED to f and t (the world zeroes them before the DEM group). In a 2D world
 * the world drops z forces and x, y torques afterwards. */
#ifndef FLOE_PROVIDER_CTX_H
#define FLOE_PROVIDER_CTX_H

struct floe_step_ctx;

typedef struct floe_provider_ctx {
    int n;                        /* particles */
    int dim;                      /* 2 or 3 */
    const double *x;              /* 3n positions of the centres of mass, m */
    const double *v;              /* 3n velocities, m/s (velocity Verlet: at mid-step) */
    const double *q;              /* 4n orientations (w, x, y, z), body -> world */
    const double *w;              /* 3n angular velocities, world frame, rad/s */
    const double *mass;           /* n masses, kg (INFINITY: a wall) */
    const double *inertia;        /* 3n principal moments of inertia, body frame, kg m^2 */
    const unsigned char *motion;  /* n floe_motion (FLOE_FREE, FLOE_FIXED, FLOE_KINEMATIC) */
    double *f;                    /* 3n forces, N: add to them */
    double *t;                    /* 3n torques, world frame, N m: add to them */
    double time;                  /* time of the evaluation, s */
    double dt;                    /* the step, s */
    int stepping;                 /* 1: the forces at the end of a step: the provider's state
                                     and its ledger (out->dissipated, work) advance by dt;
                                     0: an evaluation that advances nothing (at prepare, or
                                     a probe) */
    int probe;                    /* 1: RK2's midpoint probe: the state is restored after */
} floe_provider_ctx;

/* The evaluation's fields (cheap: pointers into the world's store). */
floe_provider_ctx floe_provider_ctx_of(const struct floe_step_ctx *ctx);

#endif
