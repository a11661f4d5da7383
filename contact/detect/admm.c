/* admm.c - contact detection between convex SDF shapes by ADMM (see floe_admm.h).
 *
 * Prox of an SDF phi' with step t (exact for an exact SDF on a flat face or a smooth
 * surface, an approximation at edges and corners, ParticLS §3): a step of t along
 * -grad phi' that stops where the SDF stops falling at unit rate (a ridge inside, the
 * nearest vertex or edge outside). Stopping on the surface from outside, as a cruder rule
 * would, leaves a fixed point that can never go inside: measured, it stalls at r = depth.
 * The projection onto
 * {phi <= 0} is the geometry's own `project` (X - phi grad phi for an exact SDF). The step
 * t starts at `step` x size and is rebalanced (Boyd et al. 2011, §3.4.1): when the primal
 * residual dominates t shrinks, when the dual residual dominates it grows (the scaled dual u
 * is rescaled with it), so neither flat nor curved partners stall the iteration. */
#include "floe_admm.h"
#include <string.h>
#ifdef ADMM_TRACE
#include <stdio.h>
#endif

void floe_admm_default_options(floe_admm_options *o) {
    o->tol = 1e-5;
    o->max_iter = 200;
    o->step = 1.0;
    o->adapt = 1;
    o->relax = 1.6;
    o->predict = 1;
}

static void q_matrix(double R[3][3], const double q[4]) {
    double w = q[0], x = q[1], y = q[2], z = q[3];
    R[0][0] = 1 - 2 * (y * y + z * z); R[0][1] = 2 * (x * y - z * w); R[0][2] = 2 * (x * z + y * w);
    R[1][0] = 2 * (x * y + z * w); R[1][1] = 1 - 2 * (x * x + z * z); R[1][2] = 2 * (y * z - x * w);
    R[2][0] = 2 * (x * z - y * w); R[2][1] = 2 * (y * z + x * w); R[2][2] = 1 - 2 * (x * x + y * y);
}

/* frame map from a's body frame to b's: Xb = M Xa + m */
typedef struct rel_frame { double M[3][3], m[3]; } rel_frame;

static void make_rel(rel_frame *f, const floe_pose *a, const floe_pose *b) {
    double Ra[3][3], Rb[3][3], d[3];
    q_matrix(Ra, a->q);
    q_matrix(Rb, b->q);
    floe_v3_sub(d, a->x, b->x);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++)
            f->M[i][j] = Rb[0][i] * Ra[0][j] + Rb[1][i] * Ra[1][j] + Rb[2][i] * Ra[2][j];
        f->m[i] = Rb[0][i] * d[0] + Rb[1][i] * d[1] + Rb[2][i] * d[2];
    }
}
static void to_b(const rel_frame *f, const double xa[3], double xb[3]) {
    for (int i = 0; i < 3; i++) xb[i] = f->M[i][0] * xa[0] + f->M[i][1] * xa[1] + f->M[i][2] * xa[2] + f->m[i];
}
static void dir_to_a(const rel_frame *f, const double gb[3], double ga[3]) {
    for (int j = 0; j < 3; j++) ga[j] = f->M[0][j] * gb[0] + f->M[1][j] * gb[1] + f->M[2][j] * gb[2];
}
static void to_a(const rel_frame *f, const double xb[3], double xa[3]) {
    double d[3];
    floe_v3_sub(d, xb, f->m);
    dir_to_a(f, d, xa);
}

static void proj_a(const floe_geometry *ga, const double w[3], double z[3]) {
    if (floe_geometry_sdf(ga, w) <= 0) floe_v3_copy(z, w);
    else floe_geometry_project(ga, w, z);
}

static double size_of(const floe_pose *a, const floe_pose *b) {
    double ra = floe_geometry_bounding_radius(a->g), rb = floe_geometry_bounding_radius(b->g);
    double s = fmin(ra, rb);
    return s > 0 && isfinite(s) ? s : 1.0;
}

/* prox of t phi_b at v (a's frame): outside, a step of t along -grad that stops on the
 * surface; inside, a step of t deeper that stops where another face takes over (a ridge of
 * the SDF, found by bisection on the linearity phi(v - s g) = phi(v) - s). */
static void prox_b(const floe_geometry *gb, const rel_frame *f, const double v[3], double t, double size,
                   double x[3]) {
    double vb[3], xb[3];
    to_b(f, v, vb);
    if (gb->klass->prox) {
        gb->klass->prox(gb, vb, t, xb);
        to_a(f, xb, x);
        return;
    }
    double phi = floe_geometry_sdf(gb, vb), g[3];
    floe_geometry_gradient(gb, vb, g);
    /* along the gradient line an exact SDF falls at unit rate, across the surface too,
     * until the line meets a ridge (inside) or passes the nearest vertex or edge (outside):
     * the step stops there (largest s with phi(v - s g) = phi(v) - s, by bisection) */
    double s = t, tol = 1e-9 * size, p[3];
    for (int k = 0; k < 3; k++) p[k] = vb[k] - s * g[k];
    if (floe_geometry_sdf(gb, p) > phi - s + tol) {
        double lo = 0, hi = s;
        for (int it = 0; it < 40 && hi - lo > tol; it++) {
            double m = 0.5 * (lo + hi);
            for (int k = 0; k < 3; k++) p[k] = vb[k] - m * g[k];
            if (floe_geometry_sdf(gb, p) > phi - m + tol) hi = m;
            else lo = m;
        }
        s = lo;
    }
    for (int k = 0; k < 3; k++) xb[k] = vb[k] - s * g[k];
    to_a(f, xb, x);
}

int floe_admm_half(const floe_pose *a, const floe_pose *b, const floe_admm_options *o, double *warm8,
                   double x_body[3], double *phi) {
    floe_admm_options def;
    if (!o) { floe_admm_default_options(&def); o = &def; }
    rel_frame f;
    make_rel(&f, a, b);
    const floe_geometry *ga = a->g, *gb = b->g;
    double size = size_of(a, b), eps = o->tol * size;
    double t = o->step * size;
    double z[3], u[3], x[3];
    int cold = !warm8 || !isfinite(warm8[0]);
    if (!cold) {
        floe_v3_copy(z, warm8);
        floe_v3_copy(u, warm8 + 3);
        if (warm8[6] > 0 && isfinite(warm8[6])) t = warm8[6] * size;
        if (!(isfinite(z[1] + z[2] + u[0] + u[1] + u[2]))) cold = 1;
        else if (ga->klass->support && !ga->klass->vertices && !ga->klass->polytope) {
            /* predictor for a curved a: at the solution a's outward normal is opposite to
             * b's SDF gradient, so the point of a whose normal is -grad phi_b (evaluated at
             * the kept point, in the bodies' new relative pose) follows the motion */
            double zb[3], g[3], d[3], zp[3];
            floe_v3_copy(zp, z);
            for (int k = 0; k < o->predict; k++) { /* x <- support_a(-grad phi_b(x)) */
                double prev[3];
                floe_v3_copy(prev, zp);
                to_b(&f, zp, zb);
                floe_geometry_gradient(gb, zb, g);
                dir_to_a(&f, g, d);
                floe_v3_scale(d, -1.0);
                ga->klass->support(ga, d, zp);
                floe_v3_sub(prev, prev, zp);
                if (floe_v3_norm(prev) <= 0.1 * eps) break;
            }
            to_b(&f, zp, zb);
            floe_geometry_gradient(gb, zb, g);
            dir_to_a(&f, g, u);
            floe_v3_scale(u, -t);
            floe_v3_copy(z, zp);
        }
    }
    if (cold) {
        double cb[3], ob[3] = {0, 0, 0}, zb[3], g[3];
        t = o->step * size;
        to_a(&f, ob, cb);
        if (ga->klass->support && floe_v3_norm(cb) > 0) {
            /* a's farthest point towards b's centre: near the deepest point of a shallow
             * contact */
            double d[3];
            floe_v3_copy(d, cb);
            floe_v3_scale(d, 1.0 / floe_v3_norm(cb));
            ga->klass->support(ga, d, z);
        } else proj_a(ga, cb, z);
        to_b(&f, z, zb);
        floe_geometry_gradient(gb, zb, g);
        dir_to_a(&f, g, u);
        floe_v3_scale(u, -t);
    }
    /* over-relaxation speeds up the re-convergence of a warm start (two ellipsoids moved
     * by 3e-4 x size per step: 15 iterations plain, 9 with alpha = 1.6) but slows a cold
     * start (31 -> 136): cold starts use alpha = 1 */
    const double alpha = cold ? 1.0 : o->relax;
    int it, conv = 0;
    for (it = 1; it <= o->max_iter; it++) {
        double v[3], wv[3], zn[3];
        floe_v3_sub(v, z, u);
        prox_b(gb, &f, v, t, size, x);
        /* over-relaxation (Boyd et al. 2011, §3.4.3): xh = alpha x + (1 - alpha) z */
        double xh[3];
        for (int k = 0; k < 3; k++) xh[k] = alpha * x[k] + (1.0 - alpha) * z[k];
        floe_v3_add(wv, xh, u);
        proj_a(ga, wv, zn);
        double r[3], s[3];
        floe_v3_sub(r, x, zn);
        floe_v3_sub(s, zn, z);
        for (int k = 0; k < 3; k++) u[k] += xh[k] - zn[k];
        floe_v3_copy(z, zn);
        double rn = floe_v3_norm(r), sn = floe_v3_norm(s);
#ifdef ADMM_TRACE
        fprintf(stderr, "it %d t %.3g x(%.4f %.4f %.4f) z(%.4f %.4f %.4f) u(%.4f %.4f %.4f) r %.3g s %.3g\n", it, t,
                x[0], x[1], x[2], z[0], z[1], z[2], u[0], u[1], u[2], rn, sn);
#endif
        if (rn <= eps && sn <= eps) { conv = 1; break; }
        if (o->adapt && (it % 4) == 0) {
            if (rn > 10 * sn && t > 0.25 * size) { t *= 0.5; floe_v3_scale(u, 2.0); }
            else if (sn > 10 * rn && t < 8 * size) { t *= 2.0; floe_v3_scale(u, 0.5); }
        }
    }
    if (!(isfinite(z[0] + z[1] + z[2]))) { floe_v3_set(z, 0, 0, 0); conv = 0; }
    double zb[3];
    to_b(&f, z, zb);
    *phi = floe_geometry_sdf(gb, zb);
    floe_v3_copy(x_body, z);
    if (warm8) {
        floe_v3_copy(warm8, z);
        for (int k = 0; k < 3; k++) warm8[3 + k] = isfinite(u[k]) ? u[k] : 0.0;
        warm8[6] = t / size;
        warm8[7] = 0;
        if (!isfinite(z[0] + z[1] + z[2])) warm8[0] = NAN;
    }
    return conv ? it : -o->max_iter;
}

static void body_to_world(const floe_pose *p, const double X[3], double x[3]) {
    floe_q_rotate(x, p->q, X);
    floe_v3_add(x, x, p->x);
}

int floe_admm_contact(const floe_pose *a, const floe_pose *b, const floe_admm_options *o, double *warm,
                      floe_admm_result *r) {
    memset(r, 0, sizeof *r);
    double X1[3], X2[3];
    if (warm && !isfinite(warm[0])) warm[8] = NAN; /* a cold pair: both halves cold */
    int i1 = floe_admm_half(a, b, o, warm, X1, &r->phi1);
    body_to_world(a, X1, r->x1);
    r->iters = i1 < 0 ? -i1 : i1;
    r->converged = i1 > 0;
    if (!(r->phi1 < 0)) { /* no point of a inside b: apart (half 2 is not needed) */
        r->phi2 = NAN;
        floe_v3_copy(r->x2, r->x1);
        if (warm) warm[8] = NAN;
        return FLOE_OK;
    }
    int i2 = floe_admm_half(b, a, o, warm ? warm + 8 : NULL, X2, &r->phi2);
    body_to_world(b, X2, r->x2);
    r->iters += i2 < 0 ? -i2 : i2;
    r->converged = r->converged && i2 > 0;
    if (!(r->phi2 < 0)) return FLOE_OK;
    r->penetrating = 1;
    /* depth: the deeper of the two deepest points; normal: the outward normal of the shape it
     * is deepest in (for two spheres both equal eq 15; for flat faces the pair x1, x2 is not
     * unique and |x2 - x1| would overestimate the depth, docs/models.md) */
    double g[3], gw[3];
    if (-r->phi1 >= -r->phi2) {
        double Xb[3], d[3];
        floe_v3_sub(d, r->x1, b->x);
        floe_q_rotate_inv(Xb, b->q, d);
        floe_geometry_gradient(b->g, Xb, g);
        floe_q_rotate(gw, b->q, g);
        floe_v3_set(r->n, -gw[0], -gw[1], -gw[2]);
        r->depth = -r->phi1;
    } else { /* X2 is in b's frame: the gradient of a wants a's */
        double Xa[3], d[3];
        floe_v3_sub(d, r->x2, a->x);
        floe_q_rotate_inv(Xa, a->q, d);
        floe_geometry_gradient(a->g, Xa, g);
        floe_q_rotate(r->n, a->q, g);
        r->depth = -r->phi2;
    }
    return FLOE_OK;
}

/* ---- shapes that only give an SDF: projected gradient ascent (floe_admm.h) ---- */
static double dist_b(const floe_geometry *gb, const rel_frame *f, const double y[3], double grad_a[3]) {
    double yb[3], nb[3];
    to_b(f, y, yb);
    double d = floe_geometry_distance(gb, yb, nb);
    dir_to_a(f, nb, grad_a);
    return d;
}

int floe_sdf_half(const floe_pose *a, const floe_pose *b, const floe_admm_options *o, double *warm4,
                  double x_body[3], double *dist, double nw[3]) {
    floe_admm_options def;
    if (!o) { floe_admm_default_options(&def); o = &def; }
    rel_frame f;
    make_rel(&f, a, b);
    const floe_geometry *ga = a->g, *gb = b->g;
    double size = size_of(a, b), y[3], n[3], alpha = size;
    int cold = !warm4 || !isfinite(warm4[0] + warm4[1] + warm4[2]);
    if (!cold) {
        floe_v3_copy(y, warm4);
        if (warm4[3] > 0 && isfinite(warm4[3])) alpha = warm4[3] * size;
        double yp[3];
        proj_a(ga, y, yp); /* the kept point, back onto a (it is in a's frame: it moved with a) */
        floe_v3_copy(y, yp);
    } else {
        double cb[3], ob[3] = {0, 0, 0};
        to_a(&f, ob, cb);
        proj_a(ga, cb, y);
    }
    double d = dist_b(gb, &f, y, n);
    /* a step of at least size that moves less than eps: the normals match to eps / size rad
     * and the depth is off by about (eps / size)^2 size / 2 */
    const double eps = 1e-7 * size;
    int it, conv = 0, moved = 0, halved = 0;
    double sprev[3] = {0, 0, 0}, nprev[3] = {0, 0, 0};
    for (it = 1; it <= o->max_iter; it++) {
        double p[3], yt[3], nt[3], e[3];
        if (d > 0 && it % 16 == 0) {
            /* apart so far and slow (parallel faces creep): -dist_b is concave, so over a it
             * is at most -d + (-n).(s - y) with s a's support point along -n; below 0 the
             * shapes are apart and the exact closest point does not matter */
            double m[3] = {-n[0], -n[1], -n[2]}, sp[3], r[3];
            floe_geometry_support(ga, m, sp);
            floe_v3_sub(r, sp, y);
            if (-d + floe_v3_dot(m, r) < 0) { conv = 1; break; }
        }
        if (moved) { /* Barzilai-Borwein length from the last move (spectral projected gradient) */
            double dn[3], ss = floe_v3_dot(sprev, sprev), sy;
            floe_v3_sub(dn, n, nprev); /* the ascent direction is -n: its change is -(n - nprev) */
            sy = floe_v3_dot(sprev, dn);
            if (sy > 0) alpha = fmin(ss / sy, 4 * size);
            moved = 0;
        }
        floe_v3_copy(p, y);
        floe_v3_axpy(p, -alpha, n); /* ascent of -dist_b: against b's outward normal */
        proj_a(ga, p, yt);
        if (!(floe_geometry_sdf(ga, yt) <= 1e-6 * size)) { /* the projection failed: shorter step */
            halved = 1;
            alpha *= 0.5;
            if (alpha < 1e-9 * size) break;
            continue;
        }
        floe_v3_sub(e, yt, y);
        double step = floe_v3_norm(e);
        if (step <= eps) { /* a fixed point: y is the deepest point; unless the step was short */
            if (alpha >= size || halved) { conv = 1; break; }
            alpha = size;
            continue;
        }
        double dt = dist_b(gb, &f, yt, nt);
        if (dt < d) {
            /* a step of at least size gaining below 1e-12 size: flat on flat, where every
             * point is as deep */
            int flat = d - dt <= 1e-12 * size && alpha >= size;
            floe_v3_copy(sprev, e);
            floe_v3_copy(nprev, n);
            floe_v3_copy(y, yt);
            floe_v3_copy(n, nt);
            d = dt;
            moved = 1;
            halved = 0;
            alpha = fmin(2 * alpha, 4 * size);
            if (flat) { conv = 1; break; }
        } else {
            halved = 1;
            alpha *= 0.5;
            if (alpha < 1e-9 * size) { conv = 1; break; } /* no ascent left at any step */
        }
    }
    if (!isfinite(y[0] + y[1] + y[2] + d)) { floe_v3_set(y, 0, 0, 0); d = INFINITY; conv = 0; }
    floe_v3_copy(x_body, y);
    *dist = d;
    double nb[3];
    for (int k = 0; k < 3; k++) nb[k] = n[k];
    floe_q_rotate(nw, a->q, nb); /* n is in a's frame */
    double m = floe_v3_norm(nw);
    if (m > 0) floe_v3_scale(nw, 1.0 / m);
    if (warm4) {
        floe_v3_copy(warm4, y);
        warm4[3] = alpha / size;
        if (!isfinite(y[0] + y[1] + y[2])) warm4[0] = NAN;
    }
    return conv ? it : -o->max_iter;
}
