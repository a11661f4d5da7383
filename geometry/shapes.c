/* shapes.c - built-in shapes: sphere (ParticLS eq 25), box (eq 26), half-space plane and
 * the user SDF callback shape. Mass properties are analytic for the built-ins. */
#include "floe_geometry.h"
#include "geometry_internal.h"
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
const floe_geometry_class floe_sphere_class = {
    .version = 1, .name = "sphere", .kind = FLOE_GEOM_SPHERE, .sdf = sphere_sdf, .gradient = sphere_grad,
    .project = sphere_project, .bounding_radius = sphere_radius, .mass_properties = sphere_mass,
    .support = sphere_support};

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
/* a convex polytope (floe_geometry_class.polytope): in 2D its four x and y faces only (its z
 * faces would cap the depth at the half thickness with a zero in-plane normal) and the
 * corners of its z = 0 section */
static void box_polytope(const floe_geometry *g, int dim, floe_polytope_view *out) {
    const floe_box *b = (const floe_box *)g;
    out->plane = b->plane;
    out->np = dim == 2 ? 4 : 6;
    out->v = dim == 2 ? b->vert2 : b->vert;
    out->nv = dim == 2 ? 4 : 8;
}
const floe_geometry_class floe_box_class = {
    .version = 1, .name = "box", .kind = FLOE_GEOM_BOX, .sdf = box_sdf, .gradient = box_grad,
    .project = box_project, .bounding_radius = box_radius, .mass_properties = box_mass,
    .support = box_support, .vertices = box_vertices, .polytope = box_polytope};

floe_geometry *floe_box_create(double lx, double ly, double lz) {
    if (!(lx > 0 && ly > 0 && lz > 0) || !isfinite(lx + ly + lz)) return NULL;
    floe_box *b = malloc(sizeof *b);
    if (!b) return NULL;
    b->base.klass = &floe_box_class;
    floe_v3_set(b->half, 0.5 * lx, 0.5 * ly, 0.5 * lz);
    for (int v = 0; v < 8; v++)
        for (int k = 0; k < 3; k++) b->vert[3 * v + k] = (v >> k & 1 ? 1 : -1) * b->half[k];
    for (int a = 0; a < 3; a++)
        for (int s = 0; s < 2; s++) {
            double *P = b->plane + 4 * (2 * a + s);
            P[0] = P[1] = P[2] = 0;
            P[a] = s ? 1.0 : -1.0;
            P[3] = b->half[a];
        }
    for (int v = 0; v < 4; v++) { /* the z = -h corners, in the plane z = 0 */
        b->vert2[3 * v] = b->vert[3 * v];
        b->vert2[3 * v + 1] = b->vert[3 * v + 1];
        b->vert2[3 * v + 2] = 0.0;
    }
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
const floe_geometry_class floe_plane_class = {
    .version = 1, .name = "plane", .kind = FLOE_GEOM_PLANE, .sdf = plane_sdf, .gradient = plane_grad,
    .project = plane_project, .bounding_radius = plane_radius, .mass_properties = plane_mass};

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
static double user_fd_step(const floe_geometry *g) { return ((const floe_user_shape *)g)->h; }
/* numerical quadrature on its own grid */
static int user_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const floe_user_shape *u = (const floe_user_shape *)g;
    return floe_geometry_mass_numeric(g, dim, rho, u->quad_cells > 0 ? u->quad_cells : 64, o);
}
/* the Lipschitz constant measured at creation, under the shape's own name */
static int user_check(const floe_geometry *g, char *err, size_t errlen) {
    const floe_user_shape *u = (const floe_user_shape *)g;
    return floe_lipschitz_verdict(u->name, u->lipschitz, u->lip_a, u->lip_b, err, errlen);
}
const floe_geometry_class floe_user_shape_class = {
    .version = 1, .name = "user_sdf", .kind = FLOE_GEOM_USER, .sdf = user_sdf,
    .bounding_radius = user_radius, .mass_properties = user_mass, .fd_step = user_fd_step, .check = user_check};

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
