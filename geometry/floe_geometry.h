/* floe_geometry.h - particle shapes as signed distance functions (ParticLS §2.1, §5.1).
 *
 * A geometry is defined in its body frame, with the centre of mass at the origin for
 * built-in closed shapes. A "class" is a const struct of function pointers; an instance
 * starts with a pointer to its class (Chipmunk2D pattern). Only `sdf` is required: a NULL
 * optional entry means the library derives it numerically from `sdf` (SUNDIALS pattern). */
#ifndef FLOE_GEOMETRY_H
#define FLOE_GEOMETRY_H

#include "floe_base.h"
#include "floe_registry.h"
#include "floe_linalg.h"

/* Built-in kinds, used for the analytic contact fast paths (Box2D-style pair table). */
typedef enum floe_geometry_kind {
    FLOE_GEOM_SPHERE = 0,
    FLOE_GEOM_BOX = 1,
    FLOE_GEOM_PLANE = 2,   /* half-space z <= 0 in the body frame: outward normal +z */
    FLOE_GEOM_USER = 3,    /* any other convex shape with an SDF (user callback, polyhedron,
                              ellipsoid, ...): the exact LP when both shapes are polytopes
                              (class `polytope`), else ADMM (contact/detect/admm.c) */
    FLOE_GEOM_COMPOUND = 4,/* union of convex pieces (one rigid body): one contact per piece pair
                              (detection reads the class's piece_count and piece, not the kind) */
    FLOE_GEOM_KIND_COUNT = 5
} floe_geometry_kind;
#define FLOE_GEOM_CONVEX FLOE_GEOM_USER

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

/* A convex polytope as the exact contact paths read it (a class's `polytope` entry): arrays
 * the geometry owns, valid while it lives, in the body frame. */
typedef struct floe_polytope_view {
    const double *plane;  /* np face planes (n, d): unit outward normal n, inside n.X <= d */
    int np;
    const double *v;      /* nv corners, 3 doubles each */
    int nv;
    int ccw;              /* optional, 2D: 1 when the corners are in counter-clockwise order
                             (0, the default: detection sorts them) */
    /* optional, 3D (NULL, the default: none): the same planes as four rows of np_soa doubles
     * each (the normals' x, y, z, then d), np_soa >= np a multiple of 8, the rows past np
     * padded with (0, 0, 0, +inf), which every point satisfies: the polytope LP's tests of
     * all planes read them in vector lanes (contact/detect/polytope_lp.c) */
    const double *plane_soa;
    int np_soa;
} floe_polytope_view;

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
    /* optional: the point of the shape farthest along the unit direction d (body frame);
     * used by the plane fast path and by support-function libraries (libccd) */
    void (*support)(const floe_geometry *g, const double d[3], double out[3]);
    /* optional: a polytope's vertices (body frame, 3 doubles each), for the per-vertex
     * plane contact; NULL for curved shapes */
    const double *(*vertices)(const floe_geometry *g, int *count);
    /* optional: proximal operator argmin_x phi(x) + |x - v|^2 / (2 t), t > 0 (NULL: derived
     * from sdf and gradient, exact for exact SDFs away from edges and corners) */
    void (*prox)(const floe_geometry *g, const double v[3], double t, double out[3]);
    /* ---- optional capabilities: the library asks the class, never its identity, so a class
     * of a user or a plugin that gives one takes the same paths as the built-ins (a class
     * written before these entries leaves them NULL: C zero-fills a shorter initializer) ---- */
    /* a convex polytope: its face planes and corners for a world of dimension dim (2: the
     * edges, normals in the xy plane, and the corners of the section z = 0, with z = 0).
     * A class that gives it takes the exact paths (docs/extending.md, "A shape"): the
     * deepest-point LP against any other polytope, the contact manifold, the per-vertex
     * plane contact, the overlap-area law and the manifold's time-step factor. */
    void (*polytope)(const floe_geometry *g, int dim, floe_polytope_view *out);
    /* a union of convex pieces (one rigid body): how many, and piece k (0 <= k < count) with
     * its pose in the body frame (x, unit quaternion q) and its bounding radius r; detection
     * gives each piece pair its own contact. Pieces are not themselves unions. */
    int (*piece_count)(const floe_geometry *g);
    const floe_geometry *(*piece)(const floe_geometry *g, int k, double x[3], double q[4], double *r);
    /* the dimension of the shape: 2 (planar, in the xy plane: 2D worlds only, mass per unit
     * thickness), 3 (a solid: 3D worlds only); NULL or 0: either */
    int (*dimension)(const floe_geometry *g);
    /* the step of the central differences where the library derives the gradient from the
     * SDF (NULL: 1e-6 x the bounding radius) */
    double (*fd_step)(const floe_geometry *g);
    /* the check when the shape is added to a world: FLOE_OK or an error with a message (NULL:
     * floe_geometry_check measures the Lipschitz constant of a shape without `project`) */
    int (*check)(const floe_geometry *g, char *err, size_t errlen);
} floe_geometry_class;

/* Capabilities, asked through the class (NULL entries answered here). */
/* 1 and *out filled when g is a convex polytope (its class gives `polytope`), else 0 */
int floe_geometry_polytope(const floe_geometry *g, int dim, floe_polytope_view *out);
/* the number of convex pieces: the class's piece_count, 1 for a convex shape */
int floe_geometry_piece_count(const floe_geometry *g);
/* 2, 3 or 0 (either): the class's `dimension` */
int floe_geometry_dimension(const floe_geometry *g);

struct floe_geometry {
    const floe_geometry_class *klass;
};

typedef struct floe_sphere { floe_geometry base; double radius; } floe_sphere;
/* half extents, corners (bit k of corner v: the sign along axis k), face planes (-x, +x, -y,
 * +y, -z, +z: the first four are its 2D edges) and the corners of its z = 0 section (2D) */
typedef struct floe_box { floe_geometry base; double half[3]; double vert[24]; double plane[24]; double vert2[12]; } floe_box;
typedef struct floe_plane { floe_geometry base; } floe_plane;

/* User SDF callback shape: f(X, user) in the body frame, with a bounding radius.
 * Contract (docs/models.md, "What a user SDF must satisfy"): f < 0 inside, 0 on the surface,
 * and f never overestimates the distance to the surface: |f(a) - f(b)| <= |a - b| (an exact
 * SDF, or one exact inside and a lower bound outside, as most SDFs in the literature are).
 * The constructor measures the Lipschitz constant on FLOE_SDF_LIPSCHITZ_PAIRS random pairs
 * of points in and around the bounding cube; floe_world_add_geometry refuses the shape,
 * naming it, when the constant is above FLOE_SDF_LIPSCHITZ_MAX. */
typedef double (*floe_sdf_fn)(const double X[3], void *user);
typedef struct floe_user_shape {
    floe_geometry base;
    floe_sdf_fn fn;
    void *user;
    double radius;        /* bounding radius about the body origin */
    double h;             /* finite-difference step for the gradient (default 1e-6 radius) */
    int quad_cells;       /* cells per axis of the mass quadrature (default 64) */
    char name[64];        /* for messages (default "user_sdf") */
    double lipschitz;     /* measured at creation: largest |f(a) - f(b)| / |a - b| */
    double lip_a[3], lip_b[3]; /* the pair that gave it */
} floe_user_shape;
#define FLOE_SDF_LIPSCHITZ_MAX 1.05
#define FLOE_SDF_LIPSCHITZ_PAIRS 2000

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
/* the same with a name for messages (NULL: "user_sdf"; at most 63 characters kept) */
floe_geometry *floe_user_shape_create_named(floe_sdf_fn fn, void *user, double bounding_radius, const char *name);
void floe_geometry_destroy(floe_geometry *g);

/* Dispatch with numerical defaults. */
double floe_geometry_sdf(const floe_geometry *g, const double X[3]);
void floe_geometry_gradient(const floe_geometry *g, const double X[3], double n[3]);
/* the closest point of the surface (Euclidean); without a class `project`, Newton steps on
 * phi / |grad phi| onto the zero level set, then descent of the distance along the surface:
 * exact for any SDF with the right zero set and |grad| <= 1, not only exact ones */
void floe_geometry_project(const floe_geometry *g, const double X[3], double on_surface[3]);
/* exact signed distance and unit outward normal n: the SDF and its gradient for a class with
 * its own `project`, else measured through floe_geometry_project (so a bound SDF gives the
 * true distance) */
double floe_geometry_distance(const floe_geometry *g, const double X[3], double n[3]);
/* the point farthest along the unit direction d: the class's `support`, else a climb of d.y
 * along the zero level set (normal equal to d within 1e-9 rad) */
void floe_geometry_support(const floe_geometry *g, const double d[3], double out[3]);
/* largest |phi(a) - phi(b)| / |a - b| over `pairs` pseudo-random pairs (fixed seed) in and
 * around the bounding cube; a_out/b_out (optional) get the worst pair */
double floe_geometry_lipschitz(const floe_geometry *g, int pairs, double a_out[3], double b_out[3]);
/* FLOE_OK, or FLOE_EINVAL with a message naming the shape when a shape whose projection the
 * library derives (no class `project`: user SDFs) has a Lipschitz constant above
 * FLOE_SDF_LIPSCHITZ_MAX (user shapes: the constant measured at creation) */
int floe_geometry_check(const floe_geometry *g, char *err, size_t errlen);
double floe_geometry_bounding_radius(const floe_geometry *g);
int floe_geometry_mass_properties(const floe_geometry *g, int dim, double density, floe_mass_properties *out);
/* Numerical mass properties on a grid of n^dim cells with 2^dim-point sub-sampling on
 * boundary cells; reports its own error estimate (difference between n and n/2 grids). */
int floe_geometry_mass_numeric(const floe_geometry *g, int dim, double density, int n, floe_mass_properties *out);

/* ---- convex polytopes (geometry/polytope.c), ParticLS eq 27 and Figs 3-5 ----
 * Exact signed distance: inside, the largest face-plane distance; outside, the distance to
 * the nearest face, edge or vertex. The constructors move the body frame to the centroid
 * and turn it into the principal frame of inertia; `frame_x`/`frame_q` give the input
 * coordinates of the body frame: X_input = R(frame_q) X_body + frame_x, so a scene can place
 * the shape where its vertices were written. A polygon (dim 2) lies in the xy plane and
 * its SDF ignores z (a prism of infinite height): it is a shape for 2D worlds. */
typedef struct floe_polytope {
    floe_geometry base;
    int dim;              /* 3: polyhedron, 2: polygon */
    int nv;               /* vertices */
    double *v;            /* 3 nv, body frame */
    int np;               /* distinct face planes (3D) or edges (2D) */
    double *plane;        /* 4 np: unit outward normal n and offset d; inside: n.X <= d */
    int nt;               /* boundary triangles (3D; 0 in 2D) */
    int *tri;             /* 3 nt vertex indices, counter-clockwise seen from outside */
    double radius;        /* bounding radius about the centroid */
    double frame_x[3];    /* centroid in the input coordinates */
    double frame_q[4];    /* principal axes in the input coordinates (body -> input) */
} floe_polytope;
extern const floe_geometry_class floe_polytope_class;

/* Convex polygon (2D) from points: the convex hull of the points (Andrew's monotone chain;
 * interior and collinear points are dropped). NULL, with a message in err (if given), when
 * fewer than 3 non-collinear points or the input is not finite. */
floe_geometry *floe_polygon_create(const double *xy, int n, char *err, size_t errlen);
/* Convex polyhedron from half-spaces n.X <= d (4 doubles each; n need not be unit): the
 * vertices are enumerated; NULL with a message when the region is empty, unbounded or
 * flat (zero volume). */
floe_geometry *floe_polyhedron_from_planes(const double *planes, int np, char *err, size_t errlen);
/* Convex polyhedron from a closed convex triangle mesh (e.g. a convex hull): coplanar
 * triangles are merged into one face plane. NULL with a message when the mesh is not
 * closed, not convex (to a relative tolerance of 1e-9), or has zero volume. */
floe_geometry *floe_polyhedron_from_mesh(const double *v, int nv, const int *tri, int nt, char *err,
                                         size_t errlen);
/* Prism: the convex hull of a polygon (xy points) extruded from z = -h/2 to h/2. */
floe_geometry *floe_prism_create(const double *xy, int n, double height, char *err, size_t errlen);

/* ---- curved primitives (geometry/primitives.c), axes along the body z axis, centroid at
 * the origin; analytic mass properties ---- */
typedef struct floe_ellipsoid { floe_geometry base; double a[3]; } floe_ellipsoid;  /* semi-axes */
typedef struct floe_cylinder { floe_geometry base; double radius, half_height; } floe_cylinder;
typedef struct floe_capsule { floe_geometry base; double radius, half_length; } floe_capsule; /* segment +-half_length */
typedef struct floe_cone { floe_geometry base; double radius, height; } floe_cone; /* base at z = -h/4, apex at z = 3h/4 */
/* "rounded" modifier: phi(X) - r, any convex shape with its edges and corners rounded. */
typedef struct floe_rounded { floe_geometry base; floe_geometry *inner; double r; } floe_rounded;
extern const floe_geometry_class floe_ellipsoid_class, floe_cylinder_class, floe_capsule_class,
    floe_cone_class, floe_rounded_class;
floe_geometry *floe_ellipsoid_create(double a, double b, double c);
floe_geometry *floe_cylinder_create(double radius, double height);
floe_geometry *floe_capsule_create(double radius, double length); /* length of the straight part */
floe_geometry *floe_cone_create(double radius, double height);
/* takes ownership of inner (destroyed with the rounded shape, also on failure) */
floe_geometry *floe_rounded_create(floe_geometry *inner, double r);

/* ---- compound (geometry/compound.c): a non-convex body as a union of convex pieces ----
 * Each piece is a geometry placed at piece_x with orientation piece_q in the compound's
 * body frame. The constructor moves the body frame to the combined centroid and turns it
 * into the principal frame (frame_x/frame_q as for polytopes). SDF = min over the pieces. */
typedef struct floe_compound {
    floe_geometry base;
    int n;
    floe_geometry **piece;    /* owned */
    double *piece_x;          /* 3 n, body frame */
    double *piece_q;          /* 4 n, body frame */
    double *piece_r;          /* n bounding radii of the pieces */
    double radius;
    double frame_x[3], frame_q[4];
    int dim;                  /* mass properties computed for this dimension */
} floe_compound;
extern const floe_geometry_class floe_compound_class;
/* takes ownership of the pieces (destroyed on failure too); density ratios per piece are
 * not supported (one material per body). */
floe_geometry *floe_compound_create(floe_geometry **pieces, const double *x, const double *q, int n, int dim,
                                    char *err, size_t errlen);

/* Stiffness multiplier of a polytope's contact manifold (docs/models.md, "Contact
 * manifold"): resting on any one face with K = 2 (2D) or 4 (3D) springs of stiffness k at
 * that face's corners (all of them, scaled by K/corners, if it has more), the body's highest
 * frequency is about sqrt(r k / m) with r = the largest over faces of max(K, max over
 * rocking axes e of m sum (rho . (n x e))^2 / I_e) (translation and rocking taken apart;
 * rho from the face's centre, I_e from the principal moments `inertia` of a body of mass
 * `mass`). For any shape whose class gives `polytope`; 0 for any other shape. A thin square plate: 12, a cube:
 * 6 (one spring at the bounding radius: 1 + m R^2 / I_min = 7 and 5.5). */
double floe_polytope_manifold_factor(const floe_geometry *g, int dim, const double inertia[3], double mass);

/* floe_sym3_eigen, floe_q_from_matrix: core/base/floe_linalg.h */

/* ---- shapes as registered components (floe_registry.h, kind FLOE_KIND_SHAPE) ----
 * A registered shape gives a parameter schema and this constructor: params is its parameter
 * struct (filled from the scene by the schema), dim the scene's dimension. It returns the
 * geometry (the world owns it once added) or NULL with a message in err. A scene names it
 * as `shape: {<name>: {<its parameters>}}`. */
typedef floe_geometry *(*floe_shape_create_fn)(const void *params, int dim, char *err, size_t errlen);
/* Registers the built-in shapes (idempotent); FLOE_OK or the registry's error. */
int floe_register_builtin_shapes(char *err, size_t errlen);

#endif
