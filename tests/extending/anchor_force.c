/* anchor_force.c - a force provider in one file (docs/extending.md, "A force provider"): a
 * harmonic tether F = -k (x - anchor) on every free particle, its energy k |x - anchor|^2 / 2
 * booked as stored (elastic) energy. A scene names it as
 *   forces: [{type: anchor, point: [0, 0, 0], k: 4}]
 * with the plugin listed under plugins: (or floe run --plugin ./anchor_force.so).
 * Build:  cc -shared -fPIC -o anchor_force.so anchor_force.c $(pkg-config --cflags floe) */
#include "floe.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct anchor_params { floe_params_head head; double point[3], k; } anchor_params;

static const floe_param anchor_schema[] = {
    {.key = "point", .type = FLOE_PARAM_VEC3, .unit = "m", .doc = "the anchor",
     .offset = offsetof(anchor_params, point)},
    {.key = "k", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "N/m",
     .min = 0, .max = INFINITY, .doc = "tether stiffness", .offset = offsetof(anchor_params, k)},
};

typedef struct anchor { floe_provider base; double point[3], k; } anchor;

static int anchor_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *sc, floe_provider_out *out) {
    const anchor *a = (const anchor *)pv;
    floe_provider_ctx c = floe_provider_ctx_of(sc);
    (void)w;
    for (int i = 0; i < c.n; i++) {
        if (c.motion[i] != FLOE_FREE) continue;
        for (int d = 0; d < 3; d++) {
            double u = c.x[3 * i + d] - a->point[d];
            c.f[3 * i + d] -= a->k * u;
            out->elastic += 0.5 * a->k * u * u;
        }
    }
    return FLOE_OK;
}

/* version 2 with splits: the force on particle i reads i's position alone, lands on free
 * particles only, and the provider keeps no state, so `floe run` under mpirun runs it on each
 * rank's own particles (floe_provider.h) */
static const floe_provider_class anchor_class = {
    .version = 2, .name = "anchor", .group = FLOE_GROUP_DEM, .forces = anchor_forces, /* destroy NULL: free() */
    .splits = FLOE_PROVIDER_PER_PARTICLE};

static floe_provider *anchor_create(const void *params, const floe_world *w, char *err, size_t errlen) {
    const anchor_params *p = params;
    (void)w;
    anchor *a = malloc(sizeof *a);
    if (!a) { snprintf(err, errlen, "out of memory"); return NULL; }
    *a = (anchor){.base = {&anchor_class}, .point = {p->point[0], p->point[1], p->point[2]}, .k = p->k};
    return &a->base;
}

static const floe_registry_entry anchor_entry = {
    .kind = FLOE_KIND_PROVIDER, .name = "anchor", .title = "harmonic tether",
    .doc = "F = -k (x - point) on every free particle.", .params = anchor_schema, .nparams = 2,
    .params_size = sizeof(anchor_params), .create = (floe_fn)anchor_create};

int floe_plugin_init(char *err, size_t errlen) { return floe_register(&anchor_entry, err, errlen); }
