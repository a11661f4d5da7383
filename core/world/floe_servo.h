/* floe_servo.h - servo walls: a plane wall that moves along its normal to hold the normal
 * pressure of the particles on it at a target (docs/granular.md, "Servo walls"), and the
 * friction setter a preparation switches friction on with.
 *
 * The controller is a velocity servo on the measured pressure p = -F.n / A (F the force of
 * the particles on the wall at the last evaluation, n its normal into the domain, A its
 * area; 2D: F per unit length of the wall, A a length and P in N/m):
 *     v_n = clamp(g (p - P), -v_max, v_max)      (v_n > 0: the wall moves back, outwards)
 * i.e. the wall advances into the sample while p < P and backs off while p > P. The default
 * gain follows the wall's stiffness, so that one step corrects a fraction beta =
 * FLOE_SERVO_BETA of the pressure error and the wall never moves more than beta times the
 * target overlap in a step near the target:
 *     g = beta A / (K_w dt),   K_w = n_c f_s / delta_s,
 * n_c the free particles touching the wall, delta_s the law's overlap at the contact force
 * f_s = P A_c of the target, A_c = (2 r)^2 (3D) or 2 r (2D) the wall area per contact of
 * particles of mean radius r (so near the target n_c ~ A / A_c and each step moves the wall
 * by beta delta_s (1 - p/P)); without contacts the wall moves at v_max. The loop gain per
 * step is beta (linear law; up to 1.5 beta for Hertz), well inside the discrete stability
 * limit 2. The default v_max is beta delta_s / dt; a larger one speeds the approach of a
 * loose sample up (the gain still holds near the target). The wall is a kinematic particle:
 * its work on the particles is booked as boundary work by the integrator. */
#ifndef FLOE_SERVO_H
#define FLOE_SERVO_H

#include "floe_world.h"

#define FLOE_SERVO_BETA 0.05

typedef struct floe_servo_def {
    double pressure;   /* target P, Pa (2D: N/m), > 0 */
    double max_speed;  /* v_max, m/s; 0 = automatic (beta delta_s / dt) */
    double gain;       /* g, m/(s Pa), fixed; 0 = automatic (the rule above) */
    double area;       /* A, m^2 (2D: m); 0 = automatic: the product of the separations of the
                          other walls of an axis-aligned box (2 x dim walls) */
} floe_servo_def;

/* pressure 0 (set it), everything else automatic */
floe_servo_def floe_default_servo_def(void);

/* Make wall `wall` (a particle index from floe_world_add_wall, fixed or kinematic without a
 * motion of its own) a servo wall. Before or after prepare (the world prepares again).
 * FLOE_EINVAL (message in last_error) for an index that is not a wall, a wall that already
 * has a motion or a servo, or a bad field; FLOE_ENOMEM. area 0 (automatic) is resolved at
 * prepare, which fails when the other walls do not make an axis-aligned box. */
int floe_world_add_servo_wall(floe_world *w, int wall, const floe_servo_def *def);

/* The controller's small interface (a preparation drives it, docs/granular.md): set the
 * target pressure (P > 0; pressure mode), or a prescribed normal speed (m/s, > 0 outwards,
 * < 0 into the sample; speed mode); and what it measures: the wall's pressure -F.n / A at
 * the last evaluation (Pa; 2D N/m), its area A (m^2; 2D m) and its position along its normal
 * (m). FLOE_EINVAL / NAN for a particle that is not a servo wall. */
int floe_world_servo_set_pressure(floe_world *w, int wall, double pressure);
int floe_world_servo_set_speed(floe_world *w, int wall, double speed);
/* back to the definition given to floe_world_add_servo_wall */
int floe_world_servo_reset(floe_world *w, int wall);
double floe_world_wall_pressure(const floe_world *w, int wall);
double floe_world_servo_area(const floe_world *w, int wall);
/* Resolve the automatic area of servo wall `wall` now (prepare does it too): FLOE_EINVAL
 * (message in last_error) when the other walls do not make an axis-aligned box. */
int floe_world_servo_check(floe_world *w, int wall);
/* 1 when wall is a servo wall, else 0 */
int floe_world_is_servo_wall(const floe_world *w, int wall);

/* Set the Coulomb friction coefficient (mu >= 0) of the contact law of the material pair
 * (a, b), or of every pair when a < 0: through floe_contact_law_set_friction. FLOE_ENOTSUP
 * (message in last_error) for a law that cannot change it (a frictionless composed law, a
 * user law), FLOE_EINVAL for a pair out of range, no law, or mu out of range. Changing mu
 * between steps keeps every contact's history (the shear springs are limited by the new
 * mu at the next step). */
int floe_world_set_law_friction(floe_world *w, int mat_a, int mat_b, double mu);

#endif
