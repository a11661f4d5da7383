/* packings.c - the built-in packings as registered components (floe_registry.h, kind
 * FLOE_KIND_PACKING): lattice, hexagonal and random. Their generators are in
 * scene_bodies.c (they report errors at the scene's positions, so the loader reads their
 * keys itself: FLOE_ENTRY_LOADER_PARSES); the schemas below document those keys for
 * `floe help packing NAME` and docs/reference.md. A packing of your own is generic
 * (floe_packing_create_fn, floe_scene.h). */
#include "floe_scene.h"
#include "floe_registry.h"

#include <math.h>
#include <stdio.h>

typedef struct packing_doc { floe_params_head head; } packing_doc;

/* the loader reads these entries itself: their constructor is never called */
static int loader_reads(const void *params, int dim, double rb, double **x, long *n, char *err, size_t errlen) {
    (void)params; (void)dim; (void)rb; (void)x; (void)n;
    snprintf(err, errlen, "this packing is read by the scene loader");
    return FLOE_ENOTSUP;
}

static const floe_param lattice_schema[] = {
    {.key = "spacing", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "m",
     .min = 0, .max = INFINITY, .doc = "distance between neighbouring sites (>= a sphere's diameter)"},
    {.key = "counts", .type = FLOE_PARAM_NODE, .unit = "", .doc = "[nx, ny(, nz)]: sites along each axis, integers "
     ">= 1 (with origin; or region)"},
    {.key = "origin", .type = FLOE_PARAM_NODE, .unit = "m", .doc = "[x, y(, z)]: the first site (with counts)"},
    {.key = "region", .type = FLOE_PARAM_NODE, .unit = "m", .doc = "{min, max}: fill this box from min (instead of "
     "counts)"},
    {.key = "jitter", .type = FLOE_PARAM_REAL, .unit = "m", .min = 0, .max = INFINITY, .def = 0,
     .doc = "random displacement of each site, up to this along each axis"},
    {.key = "seed", .type = FLOE_PARAM_INT, .unit = "", .min = -INFINITY, .max = INFINITY, .def = 1,
     .doc = "seed of the jitter"},
};

static const floe_param random_schema[] = {
    {.key = "region", .type = FLOE_PARAM_NODE, .flags = FLOE_PARAM_REQUIRED, .unit = "m",
     .doc = "{min, max}: the box every particle lies inside"},
    {.key = "count", .type = FLOE_PARAM_INT, .flags = FLOE_PARAM_REQUIRED, .unit = "", .min = 1, .max = 1e8,
     .doc = "particles to place"},
    {.key = "seed", .type = FLOE_PARAM_INT, .unit = "", .min = -INFINITY, .max = INFINITY, .def = 1,
     .doc = "seed of the placement"},
    {.key = "max_tries", .type = FLOE_PARAM_INT, .unit = "", .min = 1, .max = 1e9, .def = 100000,
     .doc = "placement attempts at most (raised to count)"},
    {.key = "radius_distribution", .type = FLOE_PARAM_NODE, .unit = "m",
     .doc = "spheres (discs) of drawn radii instead of a shape: {uniform: [rmin, rmax]}, {lognormal: {median or "
            "mean, sigma, min, max}} or {given: [[r, fraction], ...], by: volume (default) or number}, with seed "
            "(docs/granular.md); placed largest first"},
};

const floe_registry_entry floe_packing_entry_lattice = {
    .kind = FLOE_KIND_PACKING, .name = "lattice", .title = "simple cubic lattice",
    .doc = "Particles on a simple cubic (2D: square) lattice: counts from an origin, or every site of a region.",
    .source = "docs/scene-format.md, \"bodies\"",
    .params = lattice_schema, .nparams = 6, .params_size = sizeof(packing_doc), .create = (floe_fn)loader_reads,
    .flags = FLOE_ENTRY_LOADER_PARSES};
const floe_registry_entry floe_packing_entry_hexagonal = {
    .kind = FLOE_KIND_PACKING, .name = "hexagonal", .title = "hexagonal close packing",
    .doc = "Particles on a 2D triangular lattice or a 3D HCP (ABAB layers): counts from an origin, or every site of a "
           "region; spacing is the nearest-neighbour distance.",
    .source = "docs/scene-format.md, \"bodies\"",
    .params = lattice_schema, .nparams = 6, .params_size = sizeof(packing_doc), .create = (floe_fn)loader_reads,
    .flags = FLOE_ENTRY_LOADER_PARSES};
const floe_registry_entry floe_packing_entry_random = {
    .kind = FLOE_KIND_PACKING, .name = "random", .title = "random sequential placement",
    .doc = "count particles placed at random inside the region without overlap of their bounding spheres (random "
           "sequential addition; fails with a message when the region is jammed), numbered in Morton order of their centres "
           "(neighbours in space get nearby indices).",
    .source = "docs/scene-format.md, \"bodies\"",
    .params = random_schema, .nparams = 5, .params_size = sizeof(packing_doc), .create = (floe_fn)loader_reads,
    .flags = FLOE_ENTRY_LOADER_PARSES};

static const floe_registry_entry *const builtin[] = {&floe_packing_entry_lattice, &floe_packing_entry_hexagonal,
                                                     &floe_packing_entry_random};

int floe_register_builtin_packings(char *err, size_t errlen) {
    return floe_register_list(builtin, sizeof builtin / sizeof *builtin, err, errlen);
}
