/* geometry.c - dispatch of the geometry vtable with numerical defaults (SUNDIALS-style
 * optional operations), and numerical mass properties for shapes that only give an SDF. */
#include "floe_geometry.h"
#include "floe_rng.h"
#include "geometry_internal.h"
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double floe_geometry_sdf(const floe_geometry *g, const double X[3]) { return g->klass->sdf(g, X); }

double floe_geometry_bounding_radius(const floe_geometry *g) { return g->klass->bounding_radius(g); }

static double fd_step(const floe_geometry *g) {
    double r = g->klass->bounding_radius(g);
    double h = (isfinite(r) && r > 0 ? r : 1.0) * 1e-6;
    if (g->klass->fd_step) {
        double hc = g->klass->fd_step(g);
        if (hc > 0) h = hc;
    }
    return h;
}

static double size_of(const floe_geometry *g) {
    double r = g->klass->bounding_radius(g);
    return isfinite(r) && r > 0 ? r : 1.0;
}

/* the gradient as it is: the class's, or central differences (not normalised: a bound
 * SDF has |grad| < 1 outside, and the Newton step below needs the true magnitude) */
static void grad_raw(const floe_geometry *g, const double X[3], double n[3]) {
    if (g->klass->gradient) { g->klass->gradient(g, X, n); return; }
    double h = fd_step(g);
    for (int k = 0; k < 3; k++) {
        double a[3] = {X[0], X[1], X[2]}, b[3] = {X[0], X[1], X[2]};
        a[k] += h; b[k] -= h;
        n[k] = (g->klass->sdf(g, a) - g->klass->sdf(g, b)) / (2 * h);
    }
}

void floe_geometry_gradient(const floe_geometry *g, const double X[3], double n[3]) {
    if (g->klass->gradient) { g->klass->gradient(g, X, n); return; }
    grad_raw(g, X, n); /* central differences, normalised (a unit normal) */
    double m = floe_v3_norm(n);
    if (m > 0) floe_v3_scale(n, 1.0 / m);
    else floe_v3_set(n, 0, 0, 1);
}

/* Newton's method on phi along its gradient, y <- y - phi grad / |grad|^2: onto the zero
 * level set of any SDF whose gradient does not vanish near it. One step for an exact SDF
 * (|grad| = 1); for a Lipschitz-1 bound outside (|grad| < 1) a plain step of phi along the
 * unit normal falls short by the factor |grad|, Newton does not. Steps are capped at the
 * shape size (a bound can be flat far away). */
static int newton_surface(const floe_geometry *g, const double X[3], double R, double y[3]) {
    const double tol = 1e-12 * R;
    floe_v3_copy(y, X);
    for (int it = 0; it < 60; it++) {
        double phi = g->klass->sdf(g, y), gr[3];
        if (fabs(phi) <= tol) return 1;
        if (!isfinite(phi)) return 0;
        grad_raw(g, y, gr);
        double gg = floe_v3_dot(gr, gr);
        if (!(gg > 1e-24)) return 0;
        double s = phi / gg, len = fabs(s) * sqrt(gg);
        if (len > R) s *= R / len;
        floe_v3_axpy(y, -s, gr);
    }
    return fabs(g->klass->sdf(g, y)) <= 1e-9 * R;
}

/* Euclidean projection onto the zero level set from the SDF alone: the Newton foot point,
 * then the closest point by descent of |X - y| along the surface (tangential part of
 * X - y, pulled back onto the surface by Newton, halved until the distance falls). Exact
 * for any SDF with the right zero set; for an exact SDF the first Newton step is already
 * the answer and the loop costs one gradient. */
static void project_numeric(const floe_geometry *g, const double X[3], double out[3]) {
    double R = size_of(g), y[3], yt[3], r[3], n[3];
    if (!newton_surface(g, X, R, y)) {
        /* far away (Newton steps are capped at R) or a flat spot of a bound: start again
         * from X pulled to 2R from the body origin; the descent below does the rest */
        double Xs[3], m = floe_v3_norm(X);
        floe_v3_copy(Xs, X);
        if (m > 2 * R) floe_v3_scale(Xs, 2 * R / m);
        if (!newton_surface(g, Xs, R, y)) floe_v3_set(y, 0, 0, 0), newton_surface(g, y, R, y);
    }
    floe_v3_sub(r, X, y);
    double dy = floe_v3_norm(r), alpha = 1.0, sprev[3] = {0, 0, 0}, tprev[3] = {0, 0, 0};
    for (int it = 0; it < 100; it++) {
        floe_geometry_gradient(g, y, n);
        floe_v3_sub(r, X, y);
        double rn = floe_v3_dot(r, n), rt[3];
        for (int k = 0; k < 3; k++) rt[k] = r[k] - rn * n[k];
        double nt = floe_v3_norm(rt);
        if (nt <= 1e-10 * R) break;
        if (it > 0) { /* Barzilai-Borwein length (the tangent step is exact on a flat face: 1) */
            double dr[3];
            floe_v3_sub(dr, rt, tprev);
            double sy = -floe_v3_dot(sprev, dr);
            if (sy > 0) alpha = floe_v3_dot(sprev, sprev) / sy;
            else alpha = fmin(1.0, 2 * alpha);
        }
        alpha = fmin(alpha, 2 * R / nt);
        int ok = 0;
        for (int k = 0; k < 40 && !ok; k++) {
            double p[3], e[3];
            floe_v3_copy(p, y);
            floe_v3_axpy(p, alpha, rt);
            int on = newton_surface(g, p, R, yt);
            floe_v3_sub(e, X, yt);
            double dt = floe_v3_norm(e);
            if (on && dt < dy) { ok = 1; dy = dt; }
            else alpha *= 0.5;
        }
        if (!ok) break;
        floe_v3_sub(sprev, yt, y);
        floe_v3_copy(tprev, rt);
        floe_v3_copy(y, yt);
    }
    floe_v3_copy(out, y);
}

void floe_geometry_project(const floe_geometry *g, const double X[3], double out[3]) {
    if (g->klass->project) { g->klass->project(g, X, out); return; }
    project_numeric(g, X, out);
}

double floe_geometry_distance(const floe_geometry *g, const double X[3], double n[3]) {
    double phi = g->klass->sdf(g, X);
    if (g->klass->project) { /* a class with its own projection gives an exact SDF */
        floe_geometry_gradient(g, X, n);
        return phi;
    }
    double y[3], v[3];
    project_numeric(g, X, y);
    floe_v3_sub(v, X, y);
    double d = floe_v3_norm(v);
    if (d > 1e-9 * size_of(g)) {
        floe_v3_scale(v, (phi < 0 ? -1.0 : 1.0) / d);
        floe_v3_copy(n, v);
    } else floe_geometry_gradient(g, y, n);
    return phi < 0 ? -d : d;
}

/* The point of the shape farthest along the unit direction d from the SDF alone: start at
 * the Newton foot of 2R d, then climb d.y along the surface: a step along the tangential
 * part t of d, pulled back onto the surface by Newton, of the Barzilai-Borwein length
 * |s|^2 / -(s . (t' - t)) (s the last move; it follows the curvature, so long thin ridges
 * such as the rounded edges of a p = 10 superellipsoid do not zig-zag), halved until d.y
 * rises; stops when the normal is d to 1e-9 rad or no step rises. */
static void support_numeric(const floe_geometry *g, const double d[3], double out[3]) {
    double R = size_of(g), y[3], yt[3], p[3], n[3], tprev[3] = {0, 0, 0}, sprev[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) p[k] = 2 * R * d[k];
    newton_surface(g, p, R, y);
    double alpha = R, fy = floe_v3_dot(d, y);
    for (int it = 0; it < 300; it++) {
        floe_geometry_gradient(g, y, n);
        double dn = floe_v3_dot(d, n), dt[3];
        for (int k = 0; k < 3; k++) dt[k] = d[k] - dn * n[k];
        double nd = floe_v3_norm(dt);
        if (nd < 1e-9) break;
        if (it > 0) {
            double dy[3], ss = floe_v3_dot(sprev, sprev), sy;
            floe_v3_sub(dy, dt, tprev);
            sy = -floe_v3_dot(sprev, dy);
            if (sy > 0) alpha = ss / sy;
            else alpha *= 2;
        }
        alpha = fmin(alpha, 2 * R / nd); /* no step longer than the diameter */
        int ok = 0;
        while (!ok && alpha * nd > 1e-13 * R) {
            floe_v3_copy(p, y);
            floe_v3_axpy(p, alpha, dt);
            int on = newton_surface(g, p, R, yt);
            double ft = floe_v3_dot(d, yt);
            if (on && ft > fy) { ok = 1; fy = ft; }
            else alpha *= 0.5;
        }
        if (!ok) break;
        floe_v3_sub(sprev, yt, y);
        floe_v3_copy(tprev, dt);
        floe_v3_copy(y, yt);
    }
    floe_v3_copy(out, y);
}

void floe_geometry_support(const floe_geometry *g, const double d[3], double out[3]) {
    if (g->klass->support) { g->klass->support(g, d, out); return; }
    support_numeric(g, d, out);
}

/* the sampling of the Lipschitz check is the same at every run (floe_rng.h) */
static double rand_unit(unsigned long long *s) { return floe_rng_uniform(s); }

double floe_geometry_lipschitz(const floe_geometry *g, int pairs, double a_out[3], double b_out[3]) {
    double R = size_of(g), worst = 0;
    unsigned long long s = 0x9E3779B97F4A7C15ULL;
    if (a_out) floe_v3_set(a_out, 0, 0, 0);
    if (b_out) floe_v3_set(b_out, 0, 0, 0);
    for (int k = 0; k < pairs; k++) {
        /* a in the cube of side 3R about the body origin; b at a distance log-uniform in
         * [1e-4 R, R] (short pairs see the local gradient, long ones the bound) */
        double a[3], b[3], u[3], len = R * pow(10.0, -4.0 + 4.0 * rand_unit(&s));
        for (int i = 0; i < 3; i++) a[i] = R * (3 * rand_unit(&s) - 1.5);
        double un;
        do {
            for (int i = 0; i < 3; i++) u[i] = 2 * rand_unit(&s) - 1;
            un = floe_v3_norm(u);
        } while (!(un > 0.1 && un <= 1));
        for (int i = 0; i < 3; i++) b[i] = a[i] + len * u[i] / un;
        double fa = g->klass->sdf(g, a), fb = g->klass->sdf(g, b), d[3];
        floe_v3_sub(d, a, b);
        double L = fabs(fa - fb) / floe_v3_norm(d);
        if (!isfinite(fa) || !isfinite(fb)) L = INFINITY;
        if (L > worst) {
            worst = L;
            if (a_out) floe_v3_copy(a_out, a);
            if (b_out) floe_v3_copy(b_out, b);
        }
        if (!isfinite(L)) break;
    }
    return worst;
}

int floe_geometry_check(const floe_geometry *g, char *err, size_t errlen) {
    if (g->klass->polytope) {
        /* the exact paths read the face planes as the SDF (the largest plane distance) and
         * as bounds of distance (docs/models.md, the separation cache): unit normals */
        const int dim = g->klass->dimension && g->klass->dimension(g) == 2 ? 2 : 3;
        floe_polytope_view pv = {0};
        g->klass->polytope(g, dim, &pv);
        for (int k = 0; pv.plane && k < pv.np; k++) {
            const double *n = pv.plane + 4 * k, len = floe_v3_norm(n);
            if (!(fabs(len - 1.0) <= 1e-9) || !isfinite(n[3])) {
                floe_set_err(err, errlen, "shape '%s': face plane %d of its polytope has a normal of length %.17g "
                             "(offset %g): the planes must be unit outward normals n and offsets d, inside "
                             "n.x <= d (floe_polytope_view)", g->klass->name ? g->klass->name : "custom", k, len, n[3]);
                return FLOE_EINVAL;
            }
        }
    }
    if (g->klass->check) return g->klass->check(g, err, errlen);
    if (g->klass->project) return FLOE_OK; /* its own projection: the SDF is the class's business */
    double a[3], b[3], L = floe_geometry_lipschitz(g, FLOE_SDF_LIPSCHITZ_PAIRS, a, b);
    return floe_lipschitz_verdict(g->klass->name ? g->klass->name : "custom", L, a, b, err, errlen);
}

int floe_lipschitz_verdict(const char *name, double L, const double a[3], const double b[3], char *err,
                           size_t errlen) {
    if (L <= FLOE_SDF_LIPSCHITZ_MAX) return FLOE_OK;
    floe_set_err(err, errlen,
                 "shape '%s': its SDF changes by %.3g x the distance between (%.3g, %.3g, %.3g) and "
                 "(%.3g, %.3g, %.3g) (Lipschitz constant above %.2f): a user SDF must never overestimate the "
                 "distance to its surface, |grad phi| <= 1 (exact, or a lower bound) (docs/models.md, \"What a user SDF must satisfy\")",
                 name, L, a[0], a[1], a[2], b[0], b[1], b[2], FLOE_SDF_LIPSCHITZ_MAX);
    return FLOE_EINVAL;
}

int floe_geometry_mass_properties(const floe_geometry *g, int dim, double density,
                                  floe_mass_properties *out) {
    if (g->klass->mass_properties) return g->klass->mass_properties(g, dim, density, out);
    return floe_geometry_mass_numeric(g, dim, density, 64, out);
}

/* Midpoint quadrature of the indicator (sdf <= 0) over the bounding cube, with cells that
 * the surface crosses (|sdf| < half-diagonal) subdivided 4x per axis. Moments about the
 * origin, then shifted to the centroid; principal moments are the eigenvalues of the
 * inertia tensor (Jacobi). */
static void sym3_eig(double A[3][3], double ev[3]) {
    for (int sweep = 0; sweep < 50; sweep++) {
        double off = fabs(A[0][1]) + fabs(A[0][2]) + fabs(A[1][2]);
        if (off < 1e-300) break;
        for (int p = 0; p < 2; p++)
            for (int q = p + 1; q < 3; q++) {
                if (fabs(A[p][q]) < 1e-300) continue;
                double th = 0.5 * (A[q][q] - A[p][p]) / A[p][q];
                double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; k++) {
                    double akp = A[k][p], akq = A[k][q];
                    A[k][p] = c * akp - s * akq; A[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) {
                    double apk = A[p][k], aqk = A[q][k];
                    A[p][k] = c * apk - s * aqk; A[q][k] = s * apk + c * aqk;
                }
            }
    }
    ev[0] = A[0][0]; ev[1] = A[1][1]; ev[2] = A[2][2];
}

static void quad_grid(const floe_geometry *g, int dim, int n, double R, double m[10]) {
    /* m: volume, first moments (3), second moments xx yy zz xy xz yz */
    memset(m, 0, 10 * sizeof(double));
    double h = 2 * R / n;
    int nz = dim == 3 ? n : 1;
    int sub = 4;
    double hd = 0.5 * h * sqrt((double)dim);
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double c[3] = {-R + (i + 0.5) * h, -R + (j + 0.5) * h, dim == 3 ? -R + (k + 0.5) * h : 0};
                double d = g->klass->sdf(g, c);
                int ns = fabs(d) < hd ? sub : 1;
                double hs = h / ns;
                int nsz = dim == 3 ? ns : 1;
                double cv = dim == 3 ? hs * hs * hs : hs * hs;
                for (int c2 = 0; c2 < nsz; c2++)
                    for (int b = 0; b < ns; b++)
                        for (int a = 0; a < ns; a++) {
                            double X[3] = {c[0] - 0.5 * h + (a + 0.5) * hs, c[1] - 0.5 * h + (b + 0.5) * hs,
                                           dim == 3 ? c[2] - 0.5 * h + (c2 + 0.5) * hs : 0};
                            if (ns > 1 ? g->klass->sdf(g, X) > 0 : d > 0) continue;
                            m[0] += cv;
                            m[1] += cv * X[0]; m[2] += cv * X[1]; m[3] += cv * X[2];
                            m[4] += cv * X[0] * X[0]; m[5] += cv * X[1] * X[1]; m[6] += cv * X[2] * X[2];
                            m[7] += cv * X[0] * X[1]; m[8] += cv * X[0] * X[2]; m[9] += cv * X[1] * X[2];
                        }
            }
}

static void moments_to_props(const double m[10], int dim, double density, floe_mass_properties *out) {
    double V = m[0];
    out->volume = V;
    out->mass = density * V;
    double c[3] = {m[1] / V, m[2] / V, m[3] / V};
    floe_v3_copy(out->centroid, c);
    /* second moments about the centroid */
    double xx = m[4] / V - c[0] * c[0], yy = m[5] / V - c[1] * c[1], zz = m[6] / V - c[2] * c[2];
    double xy = m[7] / V - c[0] * c[1], xz = m[8] / V - c[0] * c[2], yz = m[9] / V - c[1] * c[2];
    double M = out->mass;
    out->off_axis = 0;
    if (dim == 2) { /* planar: only rotation about z matters; polar moment */
        out->inertia[0] = M * yy; out->inertia[1] = M * xx; out->inertia[2] = M * (xx + yy);
        return;
    }
    double I[3][3] = {{M * (yy + zz), -M * xy, -M * xz}, {-M * xy, M * (xx + zz), -M * yz}, {-M * xz, -M * yz, M * (xx + yy)}};
    double dmax = fmax(I[0][0], fmax(I[1][1], I[2][2]));
    out->off_axis = dmax > 0 ? fmax(fabs(I[0][1]), fmax(fabs(I[0][2]), fabs(I[1][2]))) / dmax : 0;
    sym3_eig(I, out->inertia);
}

int floe_geometry_mass_numeric(const floe_geometry *g, int dim, double density, int n,
                               floe_mass_properties *out) {
    double R = g->klass->bounding_radius(g);
    if (!(R > 0) || !isfinite(R) || n < 4 || (dim != 2 && dim != 3)) return FLOE_EINVAL;
    double m1[10], m2[10];
    quad_grid(g, dim, n, R, m1);
    if (!(m1[0] > 0)) return FLOE_EINVAL;
    quad_grid(g, dim, n / 2, R, m2);
    moments_to_props(m1, dim, density, out);
    floe_mass_properties coarse;
    moments_to_props(m2, dim, density, &coarse);
    /* error estimate: change between the n/2 and n grids (first-order convergence of the
     * boundary term: the error of the fine grid is about that of the coarse one halved) */
    double e = fabs(coarse.volume - out->volume) / out->volume;
    for (int k = 0; k < 3; k++)
        if (out->inertia[k] > 0) {
            double ek = fabs(coarse.inertia[k] - out->inertia[k]) / out->inertia[k];
            if (ek > e) e = ek;
        }
    out->quadrature_error = e;
    return FLOE_OK;
}

void floe_geometry_destroy(floe_geometry *g) {
    if (!g) return;
    if (g->klass->destroy) g->klass->destroy(g);
    else free(g);
}

void floe_set_err(char *err, size_t errlen, const char *fmt, ...) {
    if (!err || errlen == 0) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

int floe_geometry_polytope(const floe_geometry *g, int dim, floe_polytope_view *out) {
    if (!g->klass->polytope) return 0;
    out->ccw = 0; /* the optional fields a class may leave */
    out->plane_soa = NULL;
    out->np_soa = 0;
    g->klass->polytope(g, dim, out);
    if (dim != 3 || out->np_soa < out->np) { /* the planes by coordinate: 3D, all of them */
        out->plane_soa = NULL;
        out->np_soa = 0;
    }
    return 1;
}

int floe_geometry_piece_count(const floe_geometry *g) {
    return g->klass->piece_count ? g->klass->piece_count(g) : 1;
}

int floe_geometry_dimension(const floe_geometry *g) {
    return g->klass->dimension ? g->klass->dimension(g) : 0;
}

/* floe_polytope_manifold_factor (floe_geometry.h): one face's corners V (nc of them), its
 * outward normal n */
static double face_factor(const double *V, int nc, const double n[3], int dim, const double I[3], double m) {
    const int K = dim == 2 ? 2 : 4;
    const double w = nc > K ? (double)K / nc : 1.0;
    double c[3] = {0, 0, 0}, best = nc < K ? nc : K;
    for (int k = 0; k < nc; k++) floe_v3_axpy(c, 1.0 / nc, V + 3 * k);
    /* rocking axes e in the face's plane (2D: z only) */
    double t1[3], t2[3], z[3] = {0, 0, 1};
    floe_v3_cross(t1, n, z);
    if (floe_v3_dot(t1, t1) < 1e-12) { double x[3] = {1, 0, 0}; floe_v3_cross(t1, n, x); }
    floe_v3_scale(t1, 1.0 / floe_v3_norm(t1));
    floe_v3_cross(t2, n, t1);
    const int na = dim == 2 ? 1 : 36;
    for (int a = 0; a < na; a++) {
        double e[3], ep[3];
        if (dim == 2) floe_v3_copy(e, z);
        else {
            const double th = M_PI * a / na;
            for (int k = 0; k < 3; k++) e[k] = cos(th) * t1[k] + sin(th) * t2[k];
        }
        floe_v3_cross(ep, n, e);
        double S = 0, Ie = I[0] * e[0] * e[0] + I[1] * e[1] * e[1] + I[2] * e[2] * e[2];
        for (int k = 0; k < nc; k++) {
            double r[3];
            floe_v3_sub(r, V + 3 * k, c);
            double s = floe_v3_dot(r, ep);
            S += w * s * s;
        }
        if (Ie > 0 && m * S / Ie > best) best = m * S / Ie;
    }
    return best;
}

double floe_polytope_manifold_factor(const floe_geometry *g, int dim, const double inertia[3], double mass) {
    double Vf[3 * 64];
    floe_polytope_view pv;
    if (!floe_geometry_polytope(g, dim, &pv)) return 0.0;
    const double *V = pv.v, *P = pv.plane;
    const int nv = pv.nv, np = pv.np;
    const double R = g->klass->bounding_radius(g), tol = 1e-9 * R;
    double best = 0.0;
    for (int f = 0; f < np; f++) {
        int nc = 0;
        for (int k = 0; k < nv && nc < 64; k++)
            if (fabs(floe_v3_dot(P + 4 * f, V + 3 * k) - P[4 * f + 3]) <= tol) {
                floe_v3_copy(Vf + 3 * nc, V + 3 * k);
                if (dim == 2) Vf[3 * nc + 2] = 0.0;
                nc++;
            }
        if (nc < 1) continue;
        double r = face_factor(Vf, nc, P + 4 * f, dim, inertia, mass);
        if (r > best) best = r;
    }
    return best;
}
