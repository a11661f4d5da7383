/* primitives.c - curved convex primitives with exact signed distances and analytic mass
 * properties: ellipsoid, cylinder, capsule and cone (axes along the body z axis, centroid at
 * the origin), and the "rounded" modifier phi_inner - r. */
#include "floe_geometry.h"
#include <stdlib.h>

/* ---- ellipsoid: exact distance by D. Eberly, "Distance from a Point to an Ellipse, an
 * Ellipsoid, or a Hyperellipsoid" (Geometric Tools, 2013): with the semi-axes sorted
 * e0 >= e1 >= e2 and the point in the first octant, the closest point is
 * x_i = r_i y_i / (s + r_i) (r_i = e_i^2 / e2^2) where s is the root of
 * sum (r_i z_i / (s + r_i))^2 = 1 (z = y / e), bracketed and found by bisection (robust
 * inside and outside; the zero components are handled as lower-dimensional cases). ---- */
static double robust_len(const double *v, int n) {
    double m = 0;
    for (int i = 0; i < n; i++) m = fmax(m, fabs(v[i]));
    if (m == 0) return 0;
    double s = 0;
    for (int i = 0; i < n; i++) s += (v[i] / m) * (v[i] / m);
    return m * sqrt(s);
}
/* root of sum_{i<n} (num_i / (s + r_i))^2 - 1 = 0 with r_{n-1} = 1, num_i = r_i z_i */
static double ell_root(int n, const double *r, const double *z, double g) {
    double num[3];
    for (int i = 0; i < n; i++) num[i] = r[i] * z[i];
    double s0 = z[n - 1] - 1, s1 = g < 0 ? 0 : robust_len(num, n) - 1, s = 0;
    for (int it = 0; it < 1100; it++) {
        s = 0.5 * (s0 + s1);
        if (s == s0 || s == s1) break;
        double f = -1;
        for (int i = 0; i < n; i++) { double q = num[i] / (s + r[i]); f += q * q; }
        if (f > 0) s0 = s;
        else if (f < 0) s1 = s;
        else break;
    }
    return s;
}
/* e sorted descending, y >= 0 componentwise, n = 2: ellipse; returns the distance */
static double ell_dist2(const double e[2], const double y[2], double x[2]) {
    if (y[1] > 0) {
        if (y[0] > 0) {
            double z[2] = {y[0] / e[0], y[1] / e[1]}, g = z[0] * z[0] + z[1] * z[1] - 1;
            if (g != 0) {
                double r[2] = {(e[0] / e[1]) * (e[0] / e[1]), 1};
                double s = ell_root(2, r, z, g);
                x[0] = r[0] * y[0] / (s + r[0]); x[1] = y[1] / (s + 1);
            } else { x[0] = y[0]; x[1] = y[1]; }
        } else { x[0] = 0; x[1] = e[1]; }
    } else {
        double num = e[0] * y[0], den = e[0] * e[0] - e[1] * e[1];
        if (num < den) {
            double t = num / den;
            x[0] = e[0] * t; x[1] = e[1] * sqrt(fmax(1 - t * t, 0));
        } else { x[0] = e[0]; x[1] = 0; }
    }
    return hypot(x[0] - y[0], x[1] - y[1]);
}
static void ell_dist3(const double e[3], const double y[3], double x[3]) {
    if (y[2] > 0) {
        if (y[1] > 0) {
            if (y[0] > 0) {
                double z[3] = {y[0] / e[0], y[1] / e[1], y[2] / e[2]};
                double g = z[0] * z[0] + z[1] * z[1] + z[2] * z[2] - 1;
                if (g != 0) {
                    double r[3] = {(e[0] / e[2]) * (e[0] / e[2]), (e[1] / e[2]) * (e[1] / e[2]), 1};
                    double s = ell_root(3, r, z, g);
                    for (int i = 0; i < 3; i++) x[i] = r[i] * y[i] / (s + r[i]);
                } else { x[0] = y[0]; x[1] = y[1]; x[2] = y[2]; }
            } else {
                double ee[2] = {e[1], e[2]}, yy[2] = {y[1], y[2]}, xx[2];
                ell_dist2(ee, yy, xx);
                x[0] = 0; x[1] = xx[0]; x[2] = xx[1];
            }
        } else {
            if (y[0] > 0) {
                double ee[2] = {e[0], e[2]}, yy[2] = {y[0], y[2]}, xx[2];
                ell_dist2(ee, yy, xx);
                x[0] = xx[0]; x[1] = 0; x[2] = xx[1];
            } else { x[0] = 0; x[1] = 0; x[2] = e[2]; }
        }
    } else {
        double d0 = e[0] * e[0] - e[2] * e[2], d1 = e[1] * e[1] - e[2] * e[2];
        double n0 = e[0] * y[0], n1 = e[1] * y[1];
        if (n0 < d0 && n1 < d1) {
            double t0 = n0 / d0, t1 = n1 / d1, disc = 1 - t0 * t0 - t1 * t1;
            if (disc > 0) { x[0] = e[0] * t0; x[1] = e[1] * t1; x[2] = e[2] * sqrt(disc); return; }
        }
        double ee[2] = {e[0], e[1]}, yy[2] = {y[0], y[1]}, xx[2];
        ell_dist2(ee, yy, xx);
        x[0] = xx[0]; x[1] = xx[1]; x[2] = 0;
    }
}
/* closest surface point P, signed distance, outward unit normal at P */
static double ell_eval(const floe_geometry *g, const double X[3], double P[3], double n[3]) {
    const double *a = ((const floe_ellipsoid *)g)->a;
    int o[3] = {0, 1, 2}; /* axes by decreasing semi-axis */
    for (int i = 0; i < 2; i++)
        for (int j = i + 1; j < 3; j++)
            if (a[o[j]] > a[o[i]]) { int t = o[i]; o[i] = o[j]; o[j] = t; }
    double e[3], y[3], x[3];
    for (int i = 0; i < 3; i++) { e[i] = a[o[i]]; y[i] = fabs(X[o[i]]); }
    ell_dist3(e, y, x);
    double p[3], d2 = 0, q = 0;
    for (int i = 0; i < 3; i++) {
        p[o[i]] = copysign(x[i], X[o[i]]);
        d2 += (x[i] - y[i]) * (x[i] - y[i]);
        q += (y[i] / e[i]) * (y[i] / e[i]);
    }
    if (P) floe_v3_copy(P, p);
    if (n) {
        for (int i = 0; i < 3; i++) n[i] = p[i] / (a[i] * a[i]);
        floe_v3_scale(n, 1 / floe_v3_norm(n));
    }
    double d = sqrt(d2);
    return q < 1 ? -d : d;
}
static double ell_sdf(const floe_geometry *g, const double X[3]) { return ell_eval(g, X, NULL, NULL); }
static void ell_grad(const floe_geometry *g, const double X[3], double n[3]) { ell_eval(g, X, NULL, n); }
static void ell_project(const floe_geometry *g, const double X[3], double o[3]) { ell_eval(g, X, o, NULL); }
static double ell_radius(const floe_geometry *g) {
    const double *a = ((const floe_ellipsoid *)g)->a;
    return fmax(a[0], fmax(a[1], a[2]));
}
static void ell_support(const floe_geometry *g, const double d[3], double o[3]) {
    const double *a = ((const floe_ellipsoid *)g)->a;
    double ad[3] = {a[0] * d[0], a[1] * d[1], a[2] * d[2]}, m = floe_v3_norm(ad);
    for (int k = 0; k < 3; k++) o[k] = m > 0 ? a[k] * ad[k] / m : 0;
}
static int ell_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const double *a = ((const floe_ellipsoid *)g)->a;
    floe_v3_set(o->centroid, 0, 0, 0);
    o->quadrature_error = 0;
    o->off_axis = 0;
    if (dim == 2) { /* the ellipse a, b (section z = 0) per unit thickness */
        o->volume = M_PI * a[0] * a[1]; o->mass = rho * o->volume;
        floe_v3_set(o->inertia, o->mass * a[1] * a[1] / 4, o->mass * a[0] * a[0] / 4,
                    o->mass * (a[0] * a[0] + a[1] * a[1]) / 4);
    } else {
        o->volume = 4.0 / 3.0 * M_PI * a[0] * a[1] * a[2]; o->mass = rho * o->volume;
        floe_v3_set(o->inertia, o->mass * (a[1] * a[1] + a[2] * a[2]) / 5, o->mass * (a[0] * a[0] + a[2] * a[2]) / 5,
                    o->mass * (a[0] * a[0] + a[1] * a[1]) / 5);
    }
    return FLOE_OK;
}
const floe_geometry_class floe_ellipsoid_class = {
    .version = 1, .name = "ellipsoid", .kind = FLOE_GEOM_USER, .sdf = ell_sdf, .gradient = ell_grad,
    .project = ell_project, .bounding_radius = ell_radius, .mass_properties = ell_mass,
    .support = ell_support};

static int pos(double x) { return x > 0 && isfinite(x); }

floe_geometry *floe_ellipsoid_create(double a, double b, double c) {
    if (!pos(a) || !pos(b) || !pos(c)) return NULL;
    floe_ellipsoid *e = malloc(sizeof *e);
    if (!e) return NULL;
    e->base.klass = &floe_ellipsoid_class;
    floe_v3_set(e->a, a, b, c);
    return &e->base;
}

/* ---- solids of revolution about z: the distance to the 3D solid is the 2D distance from
 * (rho, z) to the meridian section, since the nearest point lies in the same half-plane.
 * Helpers map a 2D (rho, z) result back to 3D. ---- */
static double radial(const double X[3], double u[2]) {
    double r = hypot(X[0], X[1]);
    if (r > 0) { u[0] = X[0] / r; u[1] = X[1] / r; }
    else { u[0] = 1; u[1] = 0; } /* on the axis: any radial direction */
    return r;
}
static void lift(const double u[2], double rr, double z, double o[3]) { o[0] = rr * u[0]; o[1] = rr * u[1]; o[2] = z; }
/* nearest point of the segment a-b (2D) to p */
static double seg2(const double p[2], const double a[2], const double b[2], double o[2]) {
    double ex = b[0] - a[0], ey = b[1] - a[1], L2 = ex * ex + ey * ey;
    double t = L2 > 0 ? ((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / L2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    o[0] = a[0] + t * ex; o[1] = a[1] + t * ey;
    return hypot(p[0] - o[0], p[1] - o[1]);
}

/* ---- cylinder: radius R, |z| <= h ---- */
static double cyl_eval(const floe_geometry *g, const double X[3], double P[3], double n[3]) {
    const floe_cylinder *c = (const floe_cylinder *)g;
    double u[2], r = radial(X, u), R = c->radius, h = c->half_height;
    double dr = r - R, dz = fabs(X[2]) - h, sz = X[2] >= 0 ? 1 : -1, phi;
    if (dr > 0 || dz > 0) {
        double a = fmax(dr, 0), b = fmax(dz, 0);
        phi = hypot(a, b);
        if (P) lift(u, fmin(r, R), fmax(-h, fmin(h, X[2])), P);
        if (n) { lift(u, a / phi, sz * b / phi, n); }
    } else if (dr > dz) {
        phi = dr;
        if (P) lift(u, R, X[2], P);
        if (n) lift(u, 1, 0, n);
    } else {
        phi = dz;
        if (P) lift(u, r, sz * h, P);
        if (n) floe_v3_set(n, 0, 0, sz);
    }
    return phi;
}
static double cyl_sdf(const floe_geometry *g, const double X[3]) { return cyl_eval(g, X, NULL, NULL); }
static void cyl_grad(const floe_geometry *g, const double X[3], double n[3]) { cyl_eval(g, X, NULL, n); }
static void cyl_project(const floe_geometry *g, const double X[3], double o[3]) { cyl_eval(g, X, o, NULL); }
static double cyl_radius(const floe_geometry *g) {
    const floe_cylinder *c = (const floe_cylinder *)g;
    return hypot(c->radius, c->half_height);
}
static void cyl_support(const floe_geometry *g, const double d[3], double o[3]) {
    const floe_cylinder *c = (const floe_cylinder *)g;
    double m = hypot(d[0], d[1]);
    o[0] = m > 0 ? c->radius * d[0] / m : 0; o[1] = m > 0 ? c->radius * d[1] / m : 0;
    o[2] = d[2] >= 0 ? c->half_height : -c->half_height;
}
static int cyl_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const floe_cylinder *c = (const floe_cylinder *)g;
    if (dim != 3) return FLOE_ENOTSUP;
    double R = c->radius, H = 2 * c->half_height;
    o->volume = M_PI * R * R * H; o->mass = rho * o->volume;
    double Ix = o->mass * (3 * R * R + H * H) / 12;
    floe_v3_set(o->inertia, Ix, Ix, 0.5 * o->mass * R * R);
    floe_v3_set(o->centroid, 0, 0, 0);
    o->quadrature_error = 0; o->off_axis = 0;
    return FLOE_OK;
}
const floe_geometry_class floe_cylinder_class = {
    .version = 1, .name = "cylinder", .kind = FLOE_GEOM_USER, .sdf = cyl_sdf, .gradient = cyl_grad,
    .project = cyl_project, .bounding_radius = cyl_radius, .mass_properties = cyl_mass,
    .support = cyl_support};
floe_geometry *floe_cylinder_create(double radius, double height) {
    if (!pos(radius) || !pos(height)) return NULL;
    floe_cylinder *c = malloc(sizeof *c);
    if (!c) return NULL;
    c->base.klass = &floe_cylinder_class;
    c->radius = radius; c->half_height = 0.5 * height;
    return &c->base;
}

/* ---- capsule: points within R of the segment |z| <= h on the axis ---- */
static double cap_eval(const floe_geometry *g, const double X[3], double P[3], double n[3]) {
    const floe_capsule *c = (const floe_capsule *)g;
    double z = fmax(-c->half_length, fmin(c->half_length, X[2]));
    double e[3] = {X[0], X[1], X[2] - z}, m = floe_v3_norm(e);
    if (m > 0) floe_v3_scale(e, 1 / m);
    else floe_v3_set(e, 1, 0, 0); /* on the segment: any perpendicular direction */
    if (n) floe_v3_copy(n, e);
    if (P) { floe_v3_set(P, 0, 0, z); floe_v3_axpy(P, c->radius, e); }
    return m - c->radius;
}
static double cap_sdf(const floe_geometry *g, const double X[3]) { return cap_eval(g, X, NULL, NULL); }
static void cap_grad(const floe_geometry *g, const double X[3], double n[3]) { cap_eval(g, X, NULL, n); }
static void cap_project(const floe_geometry *g, const double X[3], double o[3]) { cap_eval(g, X, o, NULL); }
static double cap_radius(const floe_geometry *g) {
    const floe_capsule *c = (const floe_capsule *)g;
    return c->radius + c->half_length;
}
static void cap_support(const floe_geometry *g, const double d[3], double o[3]) {
    const floe_capsule *c = (const floe_capsule *)g;
    floe_v3_set(o, 0, 0, d[2] >= 0 ? c->half_length : -c->half_length);
    floe_v3_axpy(o, c->radius, d);
}
static int cap_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const floe_capsule *c = (const floe_capsule *)g;
    if (dim != 3) return FLOE_ENOTSUP;
    double R = c->radius, h = c->half_length, L = 2 * h;
    double vc = M_PI * R * R * L, vs = 4.0 / 3.0 * M_PI * R * R * R, mc = rho * vc, ms = rho * vs;
    o->volume = vc + vs; o->mass = rho * o->volume;
    /* cylinder + two hemispheres, each with its centroid 3R/8 from its flat face:
     * transverse moment of the pair about the centre = ms (2/5 R^2 + h^2 + 3/4 h R) */
    double Ix = mc * (3 * R * R + L * L) / 12 + ms * (0.4 * R * R + h * h + 0.75 * h * R);
    floe_v3_set(o->inertia, Ix, Ix, 0.5 * mc * R * R + 0.4 * ms * R * R);
    floe_v3_set(o->centroid, 0, 0, 0);
    o->quadrature_error = 0; o->off_axis = 0;
    return FLOE_OK;
}
const floe_geometry_class floe_capsule_class = {
    .version = 1, .name = "capsule", .kind = FLOE_GEOM_USER, .sdf = cap_sdf, .gradient = cap_grad,
    .project = cap_project, .bounding_radius = cap_radius, .mass_properties = cap_mass,
    .support = cap_support};
floe_geometry *floe_capsule_create(double radius, double length) {
    if (!pos(radius) || !(length >= 0) || !isfinite(length)) return NULL;
    floe_capsule *c = malloc(sizeof *c);
    if (!c) return NULL;
    c->base.klass = &floe_capsule_class;
    c->radius = radius; c->half_length = 0.5 * length;
    return &c->base;
}

/* ---- cone: base disc of radius R at z = -H/4, apex at z = 3H/4 (centroid at the origin).
 * Meridian section (rho >= 0): the triangle (0, zb), (R, zb), (0, za); its boundary for
 * rho >= 0 is the base segment and the slant segment. ---- */
static double cone_eval(const floe_geometry *g, const double X[3], double P[3], double n[3]) {
    const floe_cone *c = (const floe_cone *)g;
    double R = c->radius, H = c->height, zb = -0.25 * H, za = 0.75 * H;
    double u[2], r = radial(X, u), p[2] = {r, X[2]};
    double sl = hypot(H, R), ns[2] = {H / sl, R / sl}; /* outward normal of the slant */
    double db = zb - X[2], ds = ns[0] * (r - R) + ns[1] * (X[2] - zb);
    double q[2], gn[2], phi;
    if (db <= 0 && ds <= 0) { /* inside: the nearer of the two planes */
        if (db >= ds) { phi = db; q[0] = r; q[1] = zb; gn[0] = 0; gn[1] = -1; }
        else { phi = ds; q[0] = r - ds * ns[0]; q[1] = X[2] - ds * ns[1]; gn[0] = ns[0]; gn[1] = ns[1]; }
    } else {
        double A[2] = {0, zb}, B[2] = {R, zb}, C[2] = {0, za}, q1[2], q2[2];
        double d1 = seg2(p, A, B, q1), d2 = seg2(p, B, C, q2);
        if (d1 <= d2) { phi = d1; q[0] = q1[0]; q[1] = q1[1]; }
        else { phi = d2; q[0] = q2[0]; q[1] = q2[1]; }
        if (phi > 0) { gn[0] = (p[0] - q[0]) / phi; gn[1] = (p[1] - q[1]) / phi; }
        else if (db >= ds) { gn[0] = 0; gn[1] = -1; }
        else { gn[0] = ns[0]; gn[1] = ns[1]; }
    }
    if (P) lift(u, q[0], q[1], P);
    if (n) lift(u, gn[0], gn[1], n);
    return phi;
}
static double cone_sdf(const floe_geometry *g, const double X[3]) { return cone_eval(g, X, NULL, NULL); }
static void cone_grad(const floe_geometry *g, const double X[3], double n[3]) { cone_eval(g, X, NULL, n); }
static void cone_project(const floe_geometry *g, const double X[3], double o[3]) { cone_eval(g, X, o, NULL); }
static double cone_radius(const floe_geometry *g) {
    const floe_cone *c = (const floe_cone *)g;
    return fmax(0.75 * c->height, hypot(c->radius, 0.25 * c->height));
}
static void cone_support(const floe_geometry *g, const double d[3], double o[3]) {
    const floe_cone *c = (const floe_cone *)g;
    double m = hypot(d[0], d[1]), rim[3];
    rim[0] = m > 0 ? c->radius * d[0] / m : 0; rim[1] = m > 0 ? c->radius * d[1] / m : 0; rim[2] = -0.25 * c->height;
    double apex[3] = {0, 0, 0.75 * c->height};
    floe_v3_copy(o, floe_v3_dot(apex, d) > floe_v3_dot(rim, d) ? apex : rim);
}
static int cone_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const floe_cone *c = (const floe_cone *)g;
    if (dim != 3) return FLOE_ENOTSUP;
    double R = c->radius, H = c->height;
    o->volume = M_PI * R * R * H / 3; o->mass = rho * o->volume;
    double Ix = o->mass * (3.0 / 20.0 * R * R + 3.0 / 80.0 * H * H);
    floe_v3_set(o->inertia, Ix, Ix, 0.3 * o->mass * R * R);
    floe_v3_set(o->centroid, 0, 0, 0);
    o->quadrature_error = 0; o->off_axis = 0;
    return FLOE_OK;
}
const floe_geometry_class floe_cone_class = {
    .version = 1, .name = "cone", .kind = FLOE_GEOM_USER, .sdf = cone_sdf, .gradient = cone_grad,
    .project = cone_project, .bounding_radius = cone_radius, .mass_properties = cone_mass,
    .support = cone_support};
floe_geometry *floe_cone_create(double radius, double height) {
    if (!pos(radius) || !pos(height)) return NULL;
    floe_cone *c = malloc(sizeof *c);
    if (!c) return NULL;
    c->base.klass = &floe_cone_class;
    c->radius = radius; c->height = height;
    return &c->base;
}

/* ---- rounded: phi_inner - r. Exact when the inner SDF is exact and the inner shape convex:
 * the rounded surface is the offset of the inner one by r along its normals. ---- */
static double rnd_sdf(const floe_geometry *g, const double X[3]) {
    const floe_rounded *s = (const floe_rounded *)g;
    return floe_geometry_sdf(s->inner, X) - s->r;
}
static void rnd_grad(const floe_geometry *g, const double X[3], double n[3]) {
    floe_geometry_gradient(((const floe_rounded *)g)->inner, X, n);
}
/* nearest point: the inner nearest point moved out by r along the inner gradient at X (for
 * X outside the inner shape that gradient is the direction from the inner nearest point to
 * X; inside it is the normal of the nearest inner face) */
static void rnd_project(const floe_geometry *g, const double X[3], double o[3]) {
    const floe_rounded *s = (const floe_rounded *)g;
    double n[3];
    floe_geometry_project(s->inner, X, o);
    floe_geometry_gradient(s->inner, X, n);
    floe_v3_axpy(o, s->r, n);
}
static double rnd_radius(const floe_geometry *g) {
    const floe_rounded *s = (const floe_rounded *)g;
    return floe_geometry_bounding_radius(s->inner) + s->r;
}
static void rnd_support(const floe_geometry *g, const double d[3], double o[3]) {
    const floe_rounded *s = (const floe_rounded *)g;
    if (s->inner->klass->support) s->inner->klass->support(s->inner, d, o);
    else { /* no inner support: the nearest point to a far point along d (error ~ R / 1e8) */
        double far[3] = {d[0], d[1], d[2]};
        floe_v3_scale(far, 1e8 * floe_geometry_bounding_radius(s->inner));
        floe_geometry_project(s->inner, far, o);
    }
    floe_v3_axpy(o, s->r, d);
}
/* mass: numerical quadrature (floe_geometry_mass_numeric, 96 cells per axis; its own error
 * estimate is reported in quadrature_error) - the exact value would need the inner shape's
 * surface area and mean curvature integrals (Steiner formula), not available generically */
static int rnd_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    return floe_geometry_mass_numeric(g, dim, rho, 96, o);
}
static void rnd_destroy(floe_geometry *g) {
    floe_rounded *s = (floe_rounded *)g;
    floe_geometry_destroy(s->inner);
    free(s);
}
const floe_geometry_class floe_rounded_class = {
    .version = 1, .name = "rounded", .kind = FLOE_GEOM_USER, .sdf = rnd_sdf, .gradient = rnd_grad,
    .project = rnd_project, .bounding_radius = rnd_radius, .mass_properties = rnd_mass,
    .destroy = rnd_destroy, .support = rnd_support};
floe_geometry *floe_rounded_create(floe_geometry *inner, double r) {
    if (!inner) return NULL;
    if (!pos(r)) { floe_geometry_destroy(inner); return NULL; }
    floe_rounded *s = malloc(sizeof *s);
    if (!s) { floe_geometry_destroy(inner); return NULL; }
    s->base.klass = &floe_rounded_class;
    s->inner = inner; s->r = r;
    return &s->base;
}
