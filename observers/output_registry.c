/* output_registry.c - the built-in outputs in the registry (floe_registry.h). The scene
 * loader reads the keys of vtk, csv, energy, stress and tracker itself (group: 'all' or an
 * index; particle and wall lists), so their entries document them; outlines, like a plugin's
 * output, is read by its schema alone and built by its constructor here. */
#include "floe_observer.h"

#include <stddef.h>
#include <stdio.h>

static floe_observer *loader_builds(const void *p, const floe_output_ctx *ctx, char *err, size_t errlen) {
    (void)p;
    (void)ctx;
    snprintf(err, errlen, "this output is built by the scene loader");
    return NULL;
}

#define COUNT(a) ((int)(sizeof a / sizeof *a))
#define FILE_KEY(d) {.key = "file", .type = FLOE_PARAM_STRING, .unit = "", .def_text = d, \
                     .doc = "CSV file, relative to the output directory (or absolute)"}

static const floe_param vtk_schema[] = {
    {.key = "prefix", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "frame",
     .doc = "files prefix_NNNNNN.vtu and prefix.pvd in the output directory"},
    {.key = "ascii", .type = FLOE_PARAM_BOOL, .unit = "", .doc = "ASCII instead of raw binary appended data"}};
static const floe_param csv_schema[] = {FILE_KEY("particles.csv")};
static const floe_param energy_schema[] = {FILE_KEY("energy.csv")};
static const floe_param stress_schema[] = {
    FILE_KEY("stress.csv"),
    {.key = "group", .type = FLOE_PARAM_NODE, .unit = "", .doc = "'all' (default) or a body entry index"},
    {.key = "volume", .type = FLOE_PARAM_REAL, .unit = "m^3", .min = 0, .max = INFINITY,
     .doc = "the sample volume (0: the bounding box of the collection)"}};
static const floe_param tracker_schema[] = {
    FILE_KEY("track.csv"),
    {.key = "particles", .type = FLOE_PARAM_NODE, .unit = "", .doc = "list of particle ids"},
    {.key = "walls", .type = FLOE_PARAM_NODE, .unit = "", .doc = "list of wall indices"}};

/* outlines: 2D particles as VTK polygons (outline_writer.c) */
typedef struct outlines_params {
    floe_params_head head;
    char prefix[FLOE_PARAM_STRING_MAX];
    int segments;
    int ascii;
} outlines_params;
static const floe_param outlines_schema[] = {
    {.key = "prefix", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "outlines",
     .doc = "files prefix_NNNNNN.vtu and prefix.pvd in the output directory",
     .offset = offsetof(outlines_params, prefix)},
    {.key = "segments", .type = FLOE_PARAM_INT, .unit = "", .min = 3, .max = 1e6, .def = 48,
     .doc = "points of a curved outline (disc, ellipse, user SDF): one on each ray from the body origin",
     .offset = offsetof(outlines_params, segments)},
    {.key = "ascii", .type = FLOE_PARAM_BOOL, .unit = "", .doc = "ASCII instead of raw binary appended data",
     .offset = offsetof(outlines_params, ascii)}};

static floe_observer *outlines_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    const outlines_params *p = params;
    return floe_outline_writer_create(ctx->outdir, p->prefix, ctx->dim, p->segments, p->ascii, err, errlen);
}

/* floe_sizes: the floe size distribution (floe_sizes.c) */
typedef struct fsd_params {
    floe_params_head head;
    char file[FLOE_PARAM_STRING_MAX];
} fsd_params;
static const floe_param fsd_schema[] = {
    {.key = "file", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "floe_sizes.csv",
     .doc = "CSV file in the output directory", .offset = offsetof(fsd_params, file)}};

static floe_observer *fsd_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    (void)params;
    return floe_sizes_create(ctx->path, ctx->dim, err, errlen);
}

/* gate_flux: the floe area through a gate line (gate_flux.c) */
typedef struct gate_params {
    floe_params_head head;
    char file[FLOE_PARAM_STRING_MAX];
    double from[3], to[3];
} gate_params;
static const floe_param gate_schema[] = {
    {.key = "file", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "gate_flux.csv",
     .doc = "CSV file in the output directory", .offset = offsetof(gate_params, file)},
    {.key = "from", .type = FLOE_PARAM_VEC3, .flags = FLOE_PARAM_REQUIRED, .unit = "m",
     .doc = "the gate's first end A", .offset = offsetof(gate_params, from)},
    {.key = "to", .type = FLOE_PARAM_VEC3, .flags = FLOE_PARAM_REQUIRED, .unit = "m",
     .doc = "its second end B: crossings to the right of A -> B count positive", .offset = offsetof(gate_params, to)}};

static floe_observer *gate_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    const gate_params *p = params;
    return floe_gate_flux_create(ctx->path, ctx->dim, p->from, p->to, err, errlen);
}

/* ice_grid: concentration, velocity and thickness on a grid (ice_grid.c) */
typedef struct grid_params {
    floe_params_head head;
    char prefix[FLOE_PARAM_STRING_MAX];
    double min[3], max[3];
    int nx, ny, samples;
} grid_params;
static const floe_param grid_schema[] = {
    {.key = "prefix", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "ice_grid",
     .doc = "files prefix_NNNNNN.vtu and prefix.pvd in the output directory", .offset = offsetof(grid_params, prefix)},
    {.key = "min", .type = FLOE_PARAM_VEC3, .flags = FLOE_PARAM_REQUIRED, .unit = "m",
     .doc = "the grid's lower-left corner", .offset = offsetof(grid_params, min)},
    {.key = "max", .type = FLOE_PARAM_VEC3, .flags = FLOE_PARAM_REQUIRED, .unit = "m",
     .doc = "its upper-right corner", .offset = offsetof(grid_params, max)},
    {.key = "nx", .type = FLOE_PARAM_INT, .flags = FLOE_PARAM_REQUIRED, .unit = "", .min = 1, .max = 1e6,
     .doc = "cells along x", .offset = offsetof(grid_params, nx)},
    {.key = "ny", .type = FLOE_PARAM_INT, .flags = FLOE_PARAM_REQUIRED, .unit = "", .min = 1, .max = 1e6,
     .doc = "cells along y", .offset = offsetof(grid_params, ny)},
    {.key = "samples", .type = FLOE_PARAM_INT, .unit = "", .min = 1, .max = 1000, .def = 4,
     .doc = "sample points per cell and axis (concentration error O(1/samples) at a slanted edge)",
     .offset = offsetof(grid_params, samples)}};

static floe_observer *grid_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    const grid_params *p = params;
    return floe_ice_grid_create(ctx->outdir, p->prefix, ctx->dim, p->min, p->max, p->nx, p->ny, p->samples, err,
                                errlen);
}

/* fracture_events: the breaks of beam bonds (fracture_events.c) */
typedef struct fracture_params {
    floe_params_head head;
    char file[FLOE_PARAM_STRING_MAX];
} fracture_params;
static const floe_param fracture_schema[] = {
    {.key = "file", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "fracture_events.csv",
     .doc = "CSV file in the output directory", .offset = offsetof(fracture_params, file)}};

static floe_observer *fracture_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    (void)params;
    return floe_fracture_events_create(ctx->path, err, errlen);
}

/* coast_load: the ice load on coasts (coast_load.c) */
typedef struct coast_params {
    floe_params_head head;
    char file[FLOE_PARAM_STRING_MAX];
    int body, group;
    double length;
} coast_params;
static const floe_param coast_schema[] = {
    {.key = "file", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "coast_load.csv",
     .doc = "CSV file in the output directory", .offset = offsetof(coast_params, file)},
    {.key = "body", .type = FLOE_PARAM_INT, .unit = "", .min = -1, .max = 2e9, .def = -1,
     .doc = "the one body (particle id) reported; -1: every fixed or kinematic body", .offset = offsetof(coast_params, body)},
    {.key = "group", .type = FLOE_PARAM_INT, .unit = "", .min = -1, .max = 2e9, .def = -1,
     .doc = "only the fixed or kinematic bodies of this body entry (bodies[group]); -1: any",
     .offset = offsetof(coast_params, group)},
    {.key = "length", .type = FLOE_PARAM_REAL, .unit = "m", .min = 0, .max = INFINITY, .def = 0,
     .doc = "divide the force by this length; 0: by the length in contact (the contact patches' lengths)",
     .offset = offsetof(coast_params, length)}};

static floe_observer *coast_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    const coast_params *p = params;
    return floe_coast_load_create(ctx->path, ctx->dim, p->body, p->group, p->length, err, errlen);
}

/* contacts and force_chains: the contacts (contact_writer.c) */
typedef struct contacts_params {
    floe_params_head head;
    char file[FLOE_PARAM_STRING_MAX];
} contacts_params;
static const floe_param contacts_schema[] = {
    {.key = "file", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "contacts.csv",
     .doc = "CSV file in the output directory", .offset = offsetof(contacts_params, file)}};

static floe_observer *contacts_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    (void)params;
    return floe_contact_csv_create(ctx->path, err, errlen);
}

typedef struct chains_params {
    floe_params_head head;
    char prefix[FLOE_PARAM_STRING_MAX];
} chains_params;
static const floe_param chains_schema[] = {
    {.key = "prefix", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "force_chains",
     .doc = "files prefix_NNNNNN.vtu and prefix.pvd in the output directory", .offset = offsetof(chains_params, prefix)}};

static floe_observer *chains_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    const chains_params *p = params;
    return floe_force_chains_create(ctx->outdir, p->prefix, err, errlen);
}

#define OUT(n, t, d, src, sch) {.kind = FLOE_KIND_OBSERVER, .name = n, .title = t, .doc = d, .source = src, \
    .params = sch, .nparams = COUNT(sch), .params_size = sizeof(floe_params_head), .create = (floe_fn)loader_builds, \
    .flags = FLOE_ENTRY_LOADER_PARSES}

static const floe_registry_entry builtin[] = {
    OUT("vtk", "VTK frames", "ParaView frames: one .vtu per frame and a .pvd series (particles, walls, PD fields).",
        "docs/scene-format.md", vtk_schema),
    OUT("csv", "particle CSV", "Every particle's state per frame in one CSV file.", "docs/scene-format.md", csv_schema),
    OUT("energy", "energy ledger", "Kinetic, elastic, work and dissipated energy and the balance error.",
        "docs/models.md, \"Energy ledger\"", energy_schema),
    OUT("stress", "homogenised stress", "Homogenised Cauchy stress of a collection, coordination number, contacts.",
        "ParticLS eq 24", stress_schema),
    OUT("tracker", "particle tracker", "The state of chosen particles and walls over time.", "ParticLS §4.3",
        tracker_schema),
    {.kind = FLOE_KIND_OBSERVER, .name = "outlines", .title = "2D outlines",
     .doc = "2D worlds: every particle's outline as a VTK polygon (one per piece of a compound), one .vtu per "
            "frame and a .pvd series, for ParaView; cell data id, body, material, velocity, angular_velocity, "
            "area. Polygons by their corners, curved shapes by `segments` points. Refused in 3D.",
     .source = "docs/scene-format.md", .params = outlines_schema, .nparams = COUNT(outlines_schema),
     .params_size = sizeof(outlines_params), .create = (floe_fn)outlines_create},
    {.kind = FLOE_KIND_OBSERVER, .name = "floe_sizes", .title = "floe size distribution",
     .doc = "2D sea ice: one CSV row per floe per frame (t, floe, particles, area, centroid), a floe being a "
            "connected set of free particles joined by intact beam bonds: a bonded floe breaking shows its "
            "fragments. Refused in 3D.",
     .source = "docs/sea-ice.md, \"Outputs\"", .params = fsd_schema, .nparams = COUNT(fsd_schema),
     .params_size = sizeof(fsd_params), .create = (floe_fn)fsd_create},
    {.kind = FLOE_KIND_OBSERVER, .name = "gate_flux", .title = "gate flux",
     .doc = "2D sea ice: the net number and area of floes whose centres crossed the segment from -> to "
            "(positive to its right), and the area rate, one CSV row per frame. Observe often enough that no "
            "floe crosses and returns between two rows.",
     .source = "docs/sea-ice.md, \"Outputs\"", .params = gate_schema, .nparams = COUNT(gate_schema),
     .params_size = sizeof(gate_params), .create = (floe_fn)gate_create},
    {.kind = FLOE_KIND_OBSERVER, .name = "ice_grid", .title = "ice on a grid",
     .doc = "2D sea ice: per cell of an nx x ny grid, the ice concentration (fraction of samples inside floes), the "
            "mean ice velocity and thickness over the ice; a VTK series of quads (.vtu, .pvd) for ParaView.",
     .source = "docs/sea-ice.md, \"Outputs\"", .params = grid_schema, .nparams = COUNT(grid_schema),
     .params_size = sizeof(grid_params), .create = (floe_fn)grid_create},
    {.kind = FLOE_KIND_OBSERVER, .name = "fracture_events", .title = "fracture events",
     .doc = "Beam bonds: one CSV row per bond break (t, step, i, j, mode tension | shear | compression, the "
            "midpoint x y z of the centres, the stress that broke it and its strength), each break once, written "
            "at the first observation after it.",
     .source = "docs/sea-ice.md, \"Outputs\"", .params = fracture_schema, .nparams = COUNT(fracture_schema),
     .params_size = sizeof(fracture_params), .create = (floe_fn)fracture_create},
    {.kind = FLOE_KIND_OBSERVER, .name = "coast_load", .title = "ice load on coasts",
     .doc = "2D sea ice: per fixed or kinematic body (a coast, an island) and observation, the contact force on it "
            "(fx, fy, |F|), the number of contacts, the length in contact (polygon pairs: A^2/(2I) of each overlap; "
            "others: the chord at the contact's depth) or the length given, and the force per length (N/m).",
     .source = "docs/sea-ice.md, \"Outputs\"", .params = coast_schema, .nparams = COUNT(coast_schema),
     .params_size = sizeof(coast_params), .create = (floe_fn)coast_create},
    {.kind = FLOE_KIND_OBSERVER, .name = "contacts", .title = "contact list",
     .doc = "Every contact at each observation, one CSV row each: t, i, j, the point, the unit normal from i to j, "
            "the normal and tangential force magnitudes, the force on i, the overlap depth and the stored energy.",
     .source = "docs/scene-format.md", .params = contacts_schema, .nparams = COUNT(contacts_schema),
     .params_size = sizeof(contacts_params), .create = (floe_fn)contacts_create},
    {.kind = FLOE_KIND_OBSERVER, .name = "force_chains", .title = "force chains",
     .doc = "A VTK series of lines (.vtu, .pvd) from centre to centre of every contact between two bounded bodies "
            "(walls left out), with cell data fn, ft, force and depth: force chains in ParaView.",
     .source = "docs/scene-format.md", .params = chains_schema, .nparams = COUNT(chains_schema),
     .params_size = sizeof(chains_params), .create = (floe_fn)chains_create},
};

int floe_register_builtin_outputs(char *err, size_t errlen) {
    for (int k = 0; k < COUNT(builtin); k++) {
        if (floe_registry_find(builtin[k].kind, builtin[k].name)) continue;
        FLOE_TRY(floe_register(&builtin[k], err, errlen));
    }
    return FLOE_OK;
}
