/* geometry.c - dispatch of the geometry vtable with numerical defaults (SUNDIALS-style
 * optional operations), and numerical mass properties for shapes that only give an SDF. */
#include "floe_geometry.h"
#include "geometry_internal.h"
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double floe_geometry_sdf(const floe_geometry *g, const double X[3]) { return g->klass->sdf(g, X); }

double floe_geometry_bounding_radius(const floe_geometry *g) { return g->klass->bounding_radius(g); }

void floe_geometry_gradient(const floe_geometry *g, const double X[3], double n[3]) {
    if (g->klass->gradient) { g->klass->gradient(g, X, n); return; }
    /* central differences with a step relative to the shape size */
    double r = g->klass->bounding_radius(g);
    double h = (isfinite(r) && r > 0 ? r : 1.0) * 1e-6;
    if (g->klass == &floe_user_shape_class) {
        const floe_user_shape *u = (const floe_user_shape *)g;
        if (u->h > 0) h = u->h;
    }
    for (int k = 0; k < 3; k++) {
        double a[3] = {X[0], X[1], X[2]}, b[3] = {X[0], X[1], X[2]};
        a[k] += h; b[k] -= h;
        n[k] = (g->klass->sdf(g, a) - g->klass->sdf(g, b)) / (2 * h);
    }
    double m = floe_v3_norm(n);
    if (m > 0) floe_v3_scale(n, 1.0 / m);
    else floe_v3_set(n, 0, 0, 1);
}

void floe_geometry_project(const floe_geometry *g, const double X[3], double out[3]) {
    if (g->klass->project) { g->klass->project(g, X, out); return; }
    /* exact for a true SDF: step back along the gradient by the distance; two
     * corrections make it robust to mild non-exactness */
    floe_v3_copy(out, X);
    for (int it = 0; it < 3; it++) {
        double n[3];
        double d = g->klass->sdf(g, out);
        floe_geometry_gradient(g, out, n);
        floe_v3_axpy(out, -d, n);
    }
}

int floe_geometry_mass_properties(const floe_geometry *g, int dim, double density,
                                  floe_mass_properties *out) {
    if (g->klass->mass_properties) return g->klass->mass_properties(g, dim, density, out);
    int n = 64;
    if (g->klass == &floe_user_shape_class) {
        const floe_user_shape *u = (const floe_user_shape *)g;
        if (u->quad_cells > 0) n = u->quad_cells;
    }
    return floe_geometry_mass_numeric(g, dim, density, n, out);
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
