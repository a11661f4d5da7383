/* floe_admm.h - contact detection between two convex SDF shapes by ADMM (Douglas-Rachford
 * splitting), ParticLS §3 eq 14: x1 = argmin over p of phi'(x) and x2 = argmin over p' of
 * phi(x), each half the convex problem  min phi'(x) s.t. phi(x) <= 0, solved by
 *
 *     x <- prox_{t phi'}(z - u)      z <- Pi_{phi <= 0}(x + u)      u <- u + x - z
 *
 * with the step t = 1/rho relative to the particle size. Only `sdf` is needed; the
 * gradient, projection and prox of the geometry vtable are used when a shape has them.
 * Half 1 runs in p's body frame and half 2 in p''s, so the warm start (z, u) moves rigidly
 * with the bodies and a persisting contact converges in one or two iterations. */
#ifndef FLOE_ADMM_H
#define FLOE_ADMM_H

#include "floe_geometry.h"

/* a geometry placed in the world: X_world = R(q) X_body + x */
typedef struct floe_pose {
    const floe_geometry *g;
    double x[3];
    double q[4];
} floe_pose;

typedef struct floe_admm_options {
    double tol;       /* stop when the primal and dual residuals are below tol x size, where size
                         is the smaller bounding radius (default 1e-5: on 200 random ellipsoid pairs
                         the warm depth is then within 2.4e-9 of the converged one) */
    int max_iter;     /* per half (default 200) */
    double step;      /* t = 1/rho as a fraction of size (default 1); adapted by residual
                         balancing when adapt = 1 */
    int adapt;        /* default 1 */
    double relax;     /* over-relaxation alpha in [1, 2) of warm starts (default 1.6) */
    int predict;      /* support-point predictor passes on a warm start of a curved shape
                         (default 1) */
} floe_admm_options;

#define FLOE_ADMM_WARM 16 /* doubles of warm-start state per pair: (z, s) and its dual per half */

typedef struct floe_admm_result {
    int penetrating;     /* both minima negative */
    double x1[3], x2[3]; /* world: p's point deepest in p', p''s point deepest in p */
    double phi1, phi2;   /* phi'(x1), phi(x2) (negative when penetrating) */
    double n[3];         /* unit normal from p to p' */
    double depth;        /* max(-phi1, -phi2) */
    int iters;           /* iterations of both halves */
    int converged;       /* 0: max_iter reached (result still finite) */
} floe_admm_result;

void floe_admm_default_options(floe_admm_options *o);

/* One pair. warm: FLOE_ADMM_WARM doubles kept by the caller between steps (set warm[0] to
 * NAN for a cold start), or NULL. Returns FLOE_OK; the result is always finite. */
int floe_admm_contact(const floe_pose *a, const floe_pose *b, const floe_admm_options *o, double *warm,
                      floe_admm_result *r);

/* One half: the point of a deepest inside b (body frame of a in and out), with warm8[8]
 * ((z, s), u in a's frame; warm8[0] NaN = cold). Returns the iterations (negative: not converged);
 * *phi = b's SDF at the point. */
int floe_admm_half(const floe_pose *a, const floe_pose *b, const floe_admm_options *o, double *warm8,
                   double x_body[3], double *phi);

/* One half for shapes that only give an SDF (no class `project`: user SDFs, exact or a
 * Lipschitz-1 bound): the point of a deepest inside b by projected gradient ascent of
 * -dist_b over a,  y <- Pi_a(y + alpha n),  with dist_b the true signed distance
 * (floe_geometry_distance: b's SDF if b is exact, measured by projection if it is a bound),
 * n = -grad dist_b, Pi_a the Euclidean projection onto a (floe_geometry_project), alpha
 * doubled after an ascent and halved otherwise. The depth it maximises is a true distance
 * (|grad| = 1), so a force k(d) along b's normal at the point is the gradient of the
 * stored energy whatever the SDF is inside. warm4[4]: y in a's frame and alpha / size
 * (warm4[0] NaN = cold: y = Pi_a(centre of b)). Returns the iterations (negative: not
 * converged); x_body: the point (a's frame), *dist: its signed distance to b (negative
 * inside), nw: b's outward unit normal there (world). */
int floe_sdf_half(const floe_pose *a, const floe_pose *b, const floe_admm_options *o, double *warm4,
                  double x_body[3], double *dist, double nw[3]);

#endif
