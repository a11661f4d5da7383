/* floe_geometry.h - particle shapes as signed distance functions (ParticLS §2.1, §5.1).
 *
 * A geometry is defined in its body frame, with the centre of mass at the origin for
 * built-in closed shapes. A "class" is a const struct of function pointers; an instance
 * starts with a pointer to its class (Chipmunk2D pattern). Only `sdf` is required: a NULL
 * optional entry means the library derives it numerically from `sdf` (SUNDIALS pattern). */
#ifndef FLOE_GEOMETRY_H
#define FLOE_GEOMETRY_H

#include "floe_base.h"

/* Built-in kinds, used for the analytic contact fast paths (Box2D-style pair table). */
typedef enum floe_geometry_kind {
    FLOE_GEOM_SPHERE = 0,
    FLOE_GEOM_BOX = 1,
    FLOE_GEOM_PLANE = 2,   /* half-space z <= 0 in the body frame: outward normal +z */
    FLOE_GEOM_USER = 3,    /* any other shape: SDF only (user callback or new class) */
    FLOE_GEOM_KIND_COUNT = 4
} floe_geometry_kind;

typedef struct floe_mass_properties {
    double volume;       /* m^3 (m^2 in 2D: area) */
    double mass;         /* kg (2D: per unit thickness, kg/m) */
    double centroid[3];  /* body frame, m */
    double inertia[3];   /* principal moments about the centroid, kg m^2, body axes */
    double quadrature_error; /* estimated relative error of numerical quadrature, 0 if analytic */
    double off_axis;         /* largest off-diagonal of the inertia tensor in the body axes over
                                its largest diagonal: 0 when the body axes are principal */
} floe_mass_properties;

typedef struct floe_geometry floe_geometry;

typedef struct floe_geometry_class {
    int version;              /* 1 */
    const char *name;
    floe_geometry_kind kind;
    double (*sdf)(const floe_geometry *g, const double X[3]);                  /* required */
    /* optional: NULL = central finite differences of sdf */
    void (*gradient)(const floe_geometry *g, const double X[3], double n[3]);
    /* optional: NULL = X - sdf(X) * grad(X) (exact for a true SDF) */
    void (*project)(const floe_geometry *g, const double X[3], double on_surface[3]);
    double (*bounding_radius)(const floe_geometry *g);                          /* required */
    /* optional: NULL = numerical quadrature of the indicator sdf <= 0 (dim 2 or 3) */
    int (*mass_properties)(const floe_geometry *g, int dim, double density, floe_mass_properties *out);
    void (*destroy)(floe_geometry *g);                                          /* optional */
} floe_geometry_class;

struct floe_geometry {
    const floe_geometry_class *klass;
};

typedef struct floe_sphere { floe_geometry base; double radius; } floe_sphere;
typedef struct floe_box { floe_geometry base; double half[3]; } floe_box;   /* half extents */
typedef struct floe_plane { floe_geometry base; } floe_plane;

/* User SDF callback shape: f(X, user) in the body frame, with a bounding radius. */
typedef double (*floe_sdf_fn)(const double X[3], void *user);
typedef struct floe_user_shape {
    floe_geometry base;
    floe_sdf_fn fn;
    void *user;
    double radius;        /* bounding radius about the body origin */
    double h;             /* finite-difference step for the gradient (default 1e-6 radius) */
    int quad_cells;       /* cells per axis of the mass quadrature (default 64) */
} floe_user_shape;

extern const floe_geometry_class floe_sphere_class;
extern const floe_geometry_class floe_box_class;
extern const floe_geometry_class floe_plane_class;
extern const floe_geometry_class floe_user_shape_class;

/* Constructors: return a heap object owned by the caller, or by the world once passed to
 * floe_world_add_geometry. NULL on invalid input (radius <= 0 etc.) or out of memory. */
floe_geometry *floe_sphere_create(double radius);
floe_geometry *floe_box_create(double lx, double ly, double lz); /* full side lengths */
floe_geometry *floe_plane_create(void);
floe_geometry *floe_user_shape_create(floe_sdf_fn fn, void *user, double bounding_radius);
void floe_geometry_destroy(floe_geometry *g);

/* Dispatch with numerical defaults. */
double floe_geometry_sdf(const floe_geometry *g, const double X[3]);
void floe_geometry_gradient(const floe_geometry *g, const double X[3], double n[3]);
void floe_geometry_project(const floe_geometry *g, const double X[3], double on_surface[3]);
double floe_geometry_bounding_radius(const floe_geometry *g);
int floe_geometry_mass_properties(const floe_geometry *g, int dim, double density, floe_mass_properties *out);
/* Numerical mass properties on a grid of n^dim cells with 2^dim-point sub-sampling on
 * boundary cells; reports its own error estimate (difference between n and n/2 grids). */
int floe_geometry_mass_numeric(const floe_geometry *g, int dim, double density, int n, floe_mass_properties *out);

#endif
