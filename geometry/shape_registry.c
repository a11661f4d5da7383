/* shape_registry.c - the built-in shapes as registered components (floe_registry.h): a
 * parameter struct, schema and constructor each. Shapes whose parameters are point lists
 * or nested shapes (polyhedron, polygon, prism, rounded, compound, mesh) are read by the
 * scene loader itself (FLOE_ENTRY_LOADER_PARSES); their schemas document the keys. A new
 * shape is one file with its class and entry, plus one line in `builtin` below (or a
 * plugin calling floe_register). */
#include "floe_geometry.h"

#include <stddef.h>
#include <stdio.h>

#define POS(k, u, d, st, fld) {.key = k, .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, \
                               .unit = u, .min = 0, .max = INFINITY, .doc = d, .offset = offsetof(st, fld)}
#define COUNT(a) ((int)(sizeof a / sizeof *a))

static floe_geometry *made(floe_geometry *g, char *err, size_t errlen) {
    if (!g) snprintf(err, errlen, "could not create the shape (out of memory)");
    return g;
}

/* sphere */
typedef struct { floe_params_head head; double radius; } sphere_params;
static const floe_param sphere_schema[] = {POS("radius", "m", "radius", sphere_params, radius)};
static floe_geometry *sphere_make(const void *p, int dim, char *err, size_t errlen) {
    (void)dim;
    return made(floe_sphere_create(((const sphere_params *)p)->radius), err, errlen);
}

/* box */
typedef struct { floe_params_head head; double size[3]; } box_params;
static const floe_param box_schema[] = {
    {.key = "size", .type = FLOE_PARAM_VEC3, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN | FLOE_PARAM_XYZ,
     .unit = "m", .min = 0, .max = INFINITY, .doc = "full side lengths [lx, ly, lz] (also in 2D)",
     .offset = offsetof(box_params, size)}};
static floe_geometry *box_make(const void *p, int dim, char *err, size_t errlen) {
    (void)dim;
    const double *s = ((const box_params *)p)->size;
    return made(floe_box_create(s[0], s[1], s[2]), err, errlen);
}

/* ellipsoid */
typedef struct { floe_params_head head; double a[3]; } ellipsoid_params;
static const floe_param ellipsoid_schema[] = {
    {.key = "semi_axes", .type = FLOE_PARAM_VEC3, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN | FLOE_PARAM_XYZ,
     .unit = "m", .min = 0, .max = INFINITY, .doc = "semi-axes [a, b, c] along the body axes",
     .offset = offsetof(ellipsoid_params, a)}};
static floe_geometry *ellipsoid_make(const void *p, int dim, char *err, size_t errlen) {
    (void)dim;
    const double *a = ((const ellipsoid_params *)p)->a;
    return made(floe_ellipsoid_create(a[0], a[1], a[2]), err, errlen);
}

/* cylinder and cone */
typedef struct { floe_params_head head; double radius, height; } rh_params;
static const floe_param rh_schema[] = {POS("radius", "m", "radius of the base", rh_params, radius),
                                       POS("height", "m", "height along the body z axis", rh_params, height)};
static floe_geometry *cylinder_make(const void *p, int dim, char *err, size_t errlen) {
    (void)dim;
    const rh_params *q = p;
    return made(floe_cylinder_create(q->radius, q->height), err, errlen);
}
static floe_geometry *cone_make(const void *p, int dim, char *err, size_t errlen) {
    (void)dim;
    const rh_params *q = p;
    return made(floe_cone_create(q->radius, q->height), err, errlen);
}

/* capsule */
typedef struct { floe_params_head head; double radius, length; } capsule_params;
static const floe_param capsule_schema[] = {
    POS("radius", "m", "radius of the hemispherical caps and the shaft", capsule_params, radius),
    {.key = "length", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED, .unit = "m", .min = 0, .max = INFINITY,
     .doc = "length of the straight part along the body z axis", .offset = offsetof(capsule_params, length)}};
static floe_geometry *capsule_make(const void *p, int dim, char *err, size_t errlen) {
    (void)dim;
    const capsule_params *q = p;
    return made(floe_capsule_create(q->radius, q->length), err, errlen);
}

/* shapes the loader reads itself: schemas for the documentation */
static floe_geometry *loader_parses(const void *p, int dim, char *err, size_t errlen) {
    (void)p;
    (void)dim;
    snprintf(err, errlen, "this shape is built by the scene loader");
    return NULL;
}
#define DOC(k, t, d) {.key = k, .type = t, .flags = FLOE_PARAM_REQUIRED, .unit = "", .doc = d}
static const floe_param polyhedron_schema[] = {
    {.key = "vertices", .type = FLOE_PARAM_POINTS, .unit = "m", .doc = "the vertices (the body is their convex hull); "
     "give vertices or planes"},
    {.key = "planes", .type = FLOE_PARAM_POINTS, .unit = "", .doc = "face planes [nx, ny, nz, d], n.x <= d inside"}};
static const floe_param polygon_schema[] = {DOC("vertices", FLOE_PARAM_POINTS, "the vertices [x, y] (convex hull)")};
static const floe_param prism_schema[] = {DOC("vertices", FLOE_PARAM_POINTS, "the base polygon's vertices [x, y]"),
                                          {.key = "height", .type = FLOE_PARAM_REAL,
                                           .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "m", .min = 0,
                                           .max = INFINITY, .doc = "extent along z"}};
static const floe_param rounded_schema[] = {
    {.key = "radius", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "m",
     .min = 0, .max = INFINITY, .doc = "rounding radius (the inner shape grown by it)"},
    DOC("shape", FLOE_PARAM_NODE, "the inner convex shape ({kind: {...}})")};
static const floe_param compound_schema[] = {
    DOC("pieces", FLOE_PARAM_NODE, "list of {shape, position, orientation}: convex pieces in the body frame")};
static const floe_param mesh_schema[] = {
    DOC("file", FLOE_PARAM_STRING, "triangle mesh (any format assimp reads), relative to the scene file"),
    {.key = "mode", .type = FLOE_PARAM_CHOICE, .unit = "", .choices = "hull|decompose", .doc = "convex hull, or a "
     "convex decomposition into a compound (CGAL)"},
    {.key = "scale", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "", .min = 0, .max = INFINITY,
     .def = 1, .doc = "factor applied to the mesh coordinates"}};

#define ENTRY(n, t, d, src, sch, st, fn) {.kind = FLOE_KIND_SHAPE, .name = n, .title = t, .doc = d, .source = src, \
    .params = sch, .nparams = COUNT(sch), .params_size = sizeof(st), .create = (floe_fn)fn}
#define LOADER(n, t, d, src, sch) {.kind = FLOE_KIND_SHAPE, .name = n, .title = t, .doc = d, .source = src, \
    .params = sch, .nparams = COUNT(sch), .params_size = sizeof(floe_params_head), .create = (floe_fn)loader_parses, \
    .flags = FLOE_ENTRY_LOADER_PARSES}

static const floe_registry_entry builtin[] = {
    ENTRY("sphere", "sphere", "A sphere (a disc in 2D): analytic contact with spheres and walls.", "docs/scene-format.md",
          sphere_schema, sphere_params, sphere_make),
    ENTRY("box", "box", "A rectangular box centred on the body origin (a rectangle in 2D).", "docs/scene-format.md",
          box_schema, box_params, box_make),
    LOADER("polyhedron", "convex polyhedron", "A convex polyhedron from vertices (hull) or face planes.",
           "docs/scene-format.md", polyhedron_schema),
    LOADER("polygon", "convex polygon", "A convex polygon in the xy plane (2D scenes).", "docs/scene-format.md",
           polygon_schema),
    LOADER("prism", "prism", "A convex polygon extruded along z.", "docs/scene-format.md", prism_schema),
    ENTRY("ellipsoid", "ellipsoid", "An ellipsoid (exact SDF by projection; contact by ADMM).",
          "docs/scene-format.md", ellipsoid_schema, ellipsoid_params, ellipsoid_make),
    ENTRY("cylinder", "cylinder", "A circular cylinder along the body z axis.", "docs/scene-format.md", rh_schema,
          rh_params, cylinder_make),
    ENTRY("capsule", "capsule", "A cylinder with hemispherical caps along the body z axis.", "docs/scene-format.md",
          capsule_schema, capsule_params, capsule_make),
    ENTRY("cone", "cone", "A circular cone along the body z axis, apex up.", "docs/scene-format.md", rh_schema,
          rh_params, cone_make),
    LOADER("rounded", "rounded shape", "A convex shape grown by a radius (Minkowski sum with a sphere).",
           "docs/scene-format.md", rounded_schema),
    LOADER("compound", "compound", "A non-convex body made of convex pieces (one contact per piece pair).",
           "docs/scene-format.md", compound_schema),
    LOADER("mesh", "mesh", "A triangle mesh file: its convex hull or a convex decomposition.",
           "docs/scene-format.md, examples/mesh-grains", mesh_schema),
};

int floe_register_builtin_shapes(char *err, size_t errlen) {
    for (int k = 0; k < COUNT(builtin); k++) {
        if (floe_registry_find(builtin[k].kind, builtin[k].name)) continue;
        FLOE_TRY(floe_register(&builtin[k], err, errlen));
    }
    return FLOE_OK;
}
