/* rigid_body.h - angular momentum and angular velocity of a rigid body with principal
 * moments I (body frame) at orientation q: the store (floe_world_set_velocity, prepare) and
 * the integrators (core/integrators/step.c) convert between them. Internal: not installed.
 * Inline, so the integrators' per-particle loops keep them inlined. */
#ifndef FLOE_RIGID_BODY_H
#define FLOE_RIGID_BODY_H

#include "floe_base.h"

/* omega = R I^-1 R^T L (world frame); an infinite or zero moment gives no turn about it */
static inline void floe_omega_from_L(const double q[4], const double I[3], const double L[3], double om[3]) {
    double Lb[3];
    floe_q_rotate_inv(Lb, q, L);
    for (int k = 0; k < 3; k++) Lb[k] = I[k] > 0 && isfinite(I[k]) ? Lb[k] / I[k] : 0;
    floe_q_rotate(om, q, Lb);
}

/* L = R I R^T omega (world frame) */
static inline void floe_L_from_omega(const double q[4], const double I[3], const double om[3], double L[3]) {
    double ob[3];
    floe_q_rotate_inv(ob, q, om);
    for (int k = 0; k < 3; k++) ob[k] *= I[k];
    floe_q_rotate(L, q, ob);
}

#endif
