/* line_packing.c - a packing in one file: `count` particles evenly spaced on the segment
 * from `from` to `to` (ends included). A scene names it as
 *   bodies: [{packing: line, from: [0, 0, 0], to: [1, 0, 0], count: 5, shape: ..., material: ...}]
 * Build:  cc -shared -fPIC -o line_packing.so line_packing.c $(pkg-config --cflags floe) */
#include "floe.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct line_params { floe_params_head head; double from[3], to[3]; int count; } line_params;

static const floe_param line_schema[] = {
    {.key = "from", .type = FLOE_PARAM_VEC3, .flags = FLOE_PARAM_REQUIRED, .unit = "m", .doc = "first centre",
     .offset = offsetof(line_params, from)},
    {.key = "to", .type = FLOE_PARAM_VEC3, .flags = FLOE_PARAM_REQUIRED, .unit = "m", .doc = "last centre",
     .offset = offsetof(line_params, to)},
    {.key = "count", .type = FLOE_PARAM_INT, .flags = FLOE_PARAM_REQUIRED, .unit = "", .min = 2, .max = 1e6,
     .doc = "particles", .offset = offsetof(line_params, count)},
};

static int line_create(const void *params, int dim, double rb, double **x, long *n, char *err, size_t errlen) {
    const line_params *p = params;
    (void)dim;
    double len = 0;
    for (int a = 0; a < 3; a++) len += (p->to[a] - p->from[a]) * (p->to[a] - p->from[a]);
    if (sqrt(len) / (p->count - 1) < 2 * rb) {
        snprintf(err, errlen, "the particles would overlap (spacing %g < diameter %g)", sqrt(len) / (p->count - 1),
                 2 * rb);
        return FLOE_EINVAL;
    }
    *x = malloc(3 * (size_t)p->count * sizeof **x);
    if (!*x) return FLOE_ENOMEM;
    for (int i = 0; i < p->count; i++)
        for (int a = 0; a < 3; a++) (*x)[3 * i + a] = p->from[a] + (p->to[a] - p->from[a]) * i / (p->count - 1);
    *n = p->count;
    return FLOE_OK;
}

static const floe_registry_entry line_entry = {
    .kind = FLOE_KIND_PACKING, .name = "line", .title = "particles on a segment",
    .doc = "count particles evenly spaced from `from` to `to`.", .params = line_schema, .nparams = 3,
    .params_size = sizeof(line_params), .create = (floe_fn)line_create};

int floe_plugin_init(char *err, size_t errlen) { return floe_register(&line_entry, err, errlen); }
