/* shapes.c - built-in shapes: sphere (ParticLS eq 25), box (eq 26), half-space plane and
 * the user SDF callback shape. Mass properties are analytic for the built-ins. */
#include "floe_geometry.h"
#include <stdio.h>
#include <stdlib.h>

/* ---- sphere, eq 25: phi = |X| - R ---- */
static double sphere_sdf(const floe_geometry *g, const double X[3]) {
    return floe_v3_norm(X) - ((const floe_sphere *)g)->radius;
}
static void sphere_grad(const floe_geometry *g, const double X[3], double n[3]) {
    (void)g;
    double r = floe_v3_norm(X);
    if (r > 0) { n[0] = X[0] / r; n[1] = X[1] / r; n[2] = X[2] / r; }
    else floe_v3_set(n, 0, 0, 1);
}
static void sphere_project(const floe_geometry *g, const double X[3], double o[3]) {
    double n[3];
    sphere_grad(g, X, n);
    double R = ((const floe_sphere *)g)->radius;
    o[0] = R * n[0]; o[1] = R * n[1]; o[2] = R * n[2];
}
static double sphere_radius(const floe_geometry *g) { return ((const floe_sphere *)g)->radius; }
static int sphere_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    double R = ((const floe_sphere *)g)->radius;
    floe_v3_set(o->centroid, 0, 0, 0);
    o->quadrature_error = 0;
    o->off_axis = 0;
    if (dim == 2) { /* disc per unit thickness */
        o->volume = M_PI * R * R; o->mass = rho * o->volume;
        double I = 0.5 * o->mass * R * R;
        floe_v3_set(o->inertia, 0.5 * I, 0.5 * I, I);
    } else {
        o->volume = 4.0 / 3.0 * M_PI * R * R * R; o->mass = rho * o->volume;
        double I = 0.4 * o->mass * R * R;
        floe_v3_set(o->inertia, I, I, I);
    }
    return FLOE_OK;
}
static void sphere_support(const floe_geometry *g, const double d[3], double o[3]) {
    double R = ((const floe_sphere *)g)->radius;
    o[0] = R * d[0]; o[1] = R * d[1]; o[2] = R * d[2];
}
const floe_geometry_class floe_sphere_class = {1, "sphere", FLOE_GEOM_SPHERE, sphere_sdf, sphere_grad,
                                               sphere_project, sphere_radius, sphere_mass, NULL,
                                               sphere_support, NULL, NULL};

floe_geometry *floe_sphere_create(double radius) {
    if (!(radius > 0) || !isfinite(radius)) return NULL;
    floe_sphere *s = malloc(sizeof *s);
    if (!s) return NULL;
    s->base.klass = &floe_sphere_class;
    s->radius = radius;
    return &s->base;
}

/* ---- box, eq 26 (exact SDF: outside |max(|X|-h, 0)|, inside max_k(|X_k| - h_k)) ---- */
static double box_sdf(const floe_geometry *g, const double X[3]) {
    const double *h = ((const floe_box *)g)->half;
    double q[3], out2 = 0, inside = -INFINITY;
    for (int k = 0; k < 3; k++) {
        q[k] = fabs(X[k]) - h[k];
        if (q[k] > 0) out2 += q[k] * q[k];
        if (q[k] > inside) inside = q[k];
    }
    return out2 > 0 ? sqrt(out2) : inside;
}
static void box_grad(const floe_geometry *g, const double X[3], double n[3]) {
    const double *h = ((const floe_box *)g)->half;
    double q[3], out2 = 0;
    int kmax = 0;
    for (int k = 0; k < 3; k++) {
        q[k] = fabs(X[k]) - h[k];
        if (q[k] > 0) out2 += q[k] * q[k];
        if (q[k] > q[kmax]) kmax = k;
    }
    if (out2 > 0) {
        double r = sqrt(out2);
        for (int k = 0; k < 3; k++) n[k] = q[k] > 0 ? copysign(q[k] / r, X[k]) : 0;
    } else {
        floe_v3_set(n, 0, 0, 0);
        n[kmax] = X[kmax] >= 0 ? 1 : -1;
    }
}
static void box_project(const floe_geometry *g, const double X[3], double o[3]) {
    const double *h = ((const floe_box *)g)->half;
    double d = box_sdf(g, X);
    if (d > 0) {
        for (int k = 0; k < 3; k++) o[k] = fmin(fmax(X[k], -h[k]), h[k]);
    } else {
        double n[3];
        box_grad(g, X, n);
        floe_v3_copy(o, X);
        floe_v3_axpy(o, -d, n);
    }
}
static double box_radius(const floe_geometry *g) { return floe_v3_norm(((const floe_box *)g)->half); }
static int box_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const double *h = ((const floe_box *)g)->half;
    double a = 2 * h[0], b = 2 * h[1], c = 2 * h[2];
    floe_v3_set(o->centroid, 0, 0, 0);
    o->quadrature_error = 0;
    o->off_axis = 0;
    if (dim == 2) {
        o->volume = a * b; o->mass = rho * o->volume;
        floe_v3_set(o->inertia, o->mass * b * b / 12, o->mass * a * a / 12, o->mass * (a * a + b * b) / 12);
    } else {
        o->volume = a * b * c; o->mass = rho * o->volume;
        floe_v3_set(o->inertia, o->mass * (b * b + c * c) / 12, o->mass * (a * a + c * c) / 12,
                    o->mass * (a * a + b * b) / 12);
    }
    return FLOE_OK;
}
static void box_support(const floe_geometry *g, const double d[3], double o[3]) {
    const double *h = ((const floe_box *)g)->half;
    for (int k = 0; k < 3; k++) o[k] = d[k] >= 0 ? h[k] : -h[k];
}
static const double *box_vertices(const floe_geometry *g, int *count) {
    *count = 8;
    return ((const floe_box *)g)->vert;
}
const floe_geometry_class floe_box_class = {1, "box", FLOE_GEOM_BOX, box_sdf, box_grad, box_project,
                                            box_radius, box_mass, NULL, box_support, box_vertices, NULL};

floe_geometry *floe_box_create(double lx, double ly, double lz) {
    if (!(lx > 0 && ly > 0 && lz > 0) || !isfinite(lx + ly + lz)) return NULL;
    floe_box *b = malloc(sizeof *b);
    if (!b) return NULL;
    b->base.klass = &floe_box_class;
    floe_v3_set(b->half, 0.5 * lx, 0.5 * ly, 0.5 * lz);
    for (int v = 0; v < 8; v++)
        for (int k = 0; k < 3; k++) b->vert[3 * v + k] = (v >> k & 1 ? 1 : -1) * b->half[k];
    return &b->base;
}

/* ---- half-space: phi = X_z (outward normal +z in the body frame) ---- */
static double plane_sdf(const floe_geometry *g, const double X[3]) { (void)g; return X[2]; }
static void plane_grad(const floe_geometry *g, const double X[3], double n[3]) {
    (void)g; (void)X;
    floe_v3_set(n, 0, 0, 1);
}
static void plane_project(const floe_geometry *g, const double X[3], double o[3]) {
    (void)g;
    floe_v3_set(o, X[0], X[1], 0);
}
static double plane_radius(const floe_geometry *g) { (void)g; return INFINITY; }
static int plane_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    (void)g; (void)dim; (void)rho;
    o->volume = INFINITY; o->mass = INFINITY;
    floe_v3_set(o->centroid, 0, 0, 0);
    floe_v3_set(o->inertia, INFINITY, INFINITY, INFINITY);
    o->quadrature_error = 0;
    o->off_axis = 0;
    return FLOE_OK;
}
const floe_geometry_class floe_plane_class = {1, "plane", FLOE_GEOM_PLANE, plane_sdf, plane_grad,
                                              plane_project, plane_radius, plane_mass, NULL, NULL, NULL, NULL};

floe_geometry *floe_plane_create(void) {
    floe_plane *p = malloc(sizeof *p);
    if (!p) return NULL;
    p->base.klass = &floe_plane_class;
    return &p->base;
}

/* ---- user SDF callback ---- */
static double user_sdf(const floe_geometry *g, const double X[3]) {
    const floe_user_shape *u = (const floe_user_shape *)g;
    return u->fn(X, u->user);
}
static double user_radius(const floe_geometry *g) { return ((const floe_user_shape *)g)->radius; }
const floe_geometry_class floe_user_shape_class = {1, "user_sdf", FLOE_GEOM_USER, user_sdf, NULL, NULL,
                                                   user_radius, NULL, NULL, NULL, NULL, NULL};

floe_geometry *floe_user_shape_create_named(floe_sdf_fn fn, void *user, double bounding_radius, const char *name) {
    if (!fn || !(bounding_radius > 0) || !isfinite(bounding_radius)) return NULL;
    floe_user_shape *u = malloc(sizeof *u);
    if (!u) return NULL;
    u->base.klass = &floe_user_shape_class;
    u->fn = fn; u->user = user; u->radius = bounding_radius;
    u->h = 1e-6 * bounding_radius;
    u->quad_cells = 64;
    snprintf(u->name, sizeof u->name, "%s", name ? name : "user_sdf");
    /* the contract |grad| <= 1, measured now (refused when added to a world) */
    u->lipschitz = floe_geometry_lipschitz(&u->base, FLOE_SDF_LIPSCHITZ_PAIRS, u->lip_a, u->lip_b);
    return &u->base;
}

floe_geometry *floe_user_shape_create(floe_sdf_fn fn, void *user, double bounding_radius) {
    return floe_user_shape_create_named(fn, user, bounding_radius, NULL);
}
