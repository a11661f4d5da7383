/* spring_material.c - a PD material in one file (docs/extending.md, "A PD material"): every
 * bond a linear spring of stiffness k (N/m) between its two points, F = k (|y| - |xi|) along
 * the bond, energy k (|y| - |xi|)^2 / 2. A scene names it as
 *   peridynamics: [{..., material: {model: spring_bond, density: 1000, k: 10}}]
 * with the plugin listed under plugins: (or floe run --plugin ./spring_material.so).
 * Build:  cc -shared -fPIC -o spring_material.so spring_material.c $(pkg-config --cflags floe) */
#include "floe.h"
#include "floe_pd.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>

typedef struct spring_params { floe_params_head head; double rho, k; } spring_params;

static const floe_param spring_schema[] = {
    {.key = "density", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN,
     .unit = "kg/m^3", .min = 0, .max = INFINITY, .doc = "mass density", .offset = offsetof(spring_params, rho)},
    {.key = "k", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "N/m",
     .min = 0, .max = INFINITY, .doc = "stiffness of every bond", .offset = offsetof(spring_params, k)},
};

static int spring_init(floe_pd_body *b) { return b->mat.param[0] > 0 ? FLOE_OK : FLOE_EINVAL; }

/* forces ADDED to f for positions x; returns the elastic energy */
static double spring_forces(floe_pd_body *b, const double *x, double *f) {
    const double k = b->mat.param[0];
    double e = 0;
    for (int i = 0; i < b->n; i++)
        for (int64_t q = b->off[i]; q < b->off[i + 1]; q++) {
            int j = b->partner[q];
            if (b->broken[q]) continue;
            double d[3], r = 0;
            for (int a = 0; a < 3; a++) { d[a] = x[3 * j + a] - x[3 * i + a]; r += d[a] * d[a]; }
            r = sqrt(r);
            double s = r - b->len[q], fm = k * s / r;
            for (int a = 0; a < 3; a++) { f[3 * i + a] += fm * d[a]; f[3 * j + a] -= fm * d[a]; }
            e += 0.5 * k * s * s;
        }
    return e;
}

/* the PMB micromodulus with the same nodal stiffness (for the time-step estimate) */
static double spring_c(const floe_pd_body *b) { return b->mat.param[0] * b->dx / (b->V[0] * b->V[0]); }

static const floe_pd_material_ops spring_ops = {
    .name = "spring_bond", .init = spring_init, .forces = spring_forces, .bond_micromodulus = spring_c};

static int spring_create(const void *params, int dim, floe_pd_material *out, char *err, size_t errlen) {
    const spring_params *p = params;
    (void)dim; (void)err; (void)errlen;
    *out = (floe_pd_material){.model = FLOE_PD_USER, .ops = &spring_ops, .rho = p->rho};
    out->param[0] = p->k;
    return FLOE_OK;
}

static const floe_registry_entry spring_entry = {
    .kind = FLOE_KIND_PD_MATERIAL, .name = "spring_bond", .title = "linear spring bonds",
    .doc = "Every bond a linear spring of stiffness k.", .params = spring_schema, .nparams = 2,
    .params_size = sizeof(spring_params), .create = (floe_fn)spring_create};

int floe_plugin_init(char *err, size_t errlen) { return floe_register(&spring_entry, err, errlen); }
