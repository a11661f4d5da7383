/* torus_plugin.c - a floe plugin: a shape, a contact law and an output that a scene names
 * without rebuilding floe (docs/extending.md).
 *
 *   shape  `torus`   {major: R, minor: r}: a ring about the body z axis, exact SDF
 *   law    `hooke`   {k: N/m}: F = k d along the normal, nothing else (energy-conserving)
 *   output `contact_count` a CSV of t, contacts, kinetic energy, every `every` steps
 *
 * Build against an installed floe (no library to link: the floe CLI exports its symbols):
 *   cc -O2 -shared -fPIC -o torus_plugin.so torus_plugin.c $(pkg-config --cflags floe)
 * and run:  floe run scene.yaml   (the scene lists it under plugins:), or
 *           floe run --plugin ./torus_plugin.so my_scene.yaml */
#include "floe.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

/* ---- shape: torus ---- */

typedef struct torus {
    floe_geometry base;
    double R, r;
} torus;

static double torus_sdf(const floe_geometry *g, const double X[3]) {
    const torus *t = (const torus *)g;
    double q = sqrt(X[0] * X[0] + X[1] * X[1]) - t->R;
    return sqrt(q * q + X[2] * X[2]) - t->r;
}

static double torus_radius(const floe_geometry *g) {
    const torus *t = (const torus *)g;
    return t->R + t->r;
}

/* the nearest point of the centre circle (on the axis, where every point of the circle is
 * nearest, the one on +x) */
static void centre_point(const torus *t, const double X[3], double c[3]) {
    double h = sqrt(X[0] * X[0] + X[1] * X[1]);
    c[0] = h > 0 ? t->R * X[0] / h : t->R;
    c[1] = h > 0 ? t->R * X[1] / h : 0;
    c[2] = 0;
}

/* exact gradient and projection (floe would derive both from the SDF by finite differences,
 * which are not unit length on the axis, where the SDF has a ridge) */
static void torus_gradient(const floe_geometry *g, const double X[3], double n[3]) {
    double c[3];
    centre_point((const torus *)g, X, c);
    double d[3] = {X[0] - c[0], X[1] - c[1], X[2] - c[2]}, l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int a = 0; a < 3; a++) n[a] = l > 0 ? d[a] / l : (a == 2);
}

static void torus_project(const floe_geometry *g, const double X[3], double out[3]) {
    const torus *t = (const torus *)g;
    double c[3], n[3];
    centre_point(t, X, c);
    torus_gradient(g, X, n);
    for (int a = 0; a < 3; a++) out[a] = c[a] + t->r * n[a];
}

/* the farthest point along d: on the rim circle in d's azimuth, then r along d */
static void torus_support(const floe_geometry *g, const double d[3], double out[3]) {
    const torus *t = (const torus *)g;
    double h = sqrt(d[0] * d[0] + d[1] * d[1]);
    double cx = h > 0 ? t->R * d[0] / h : t->R, cy = h > 0 ? t->R * d[1] / h : 0;
    out[0] = cx + t->r * d[0];
    out[1] = cy + t->r * d[1];
    out[2] = t->r * d[2];
}

static const floe_geometry_class torus_class = {
    .version = 1, .name = "torus", .kind = FLOE_GEOM_USER, .sdf = torus_sdf, .gradient = torus_gradient,
    .project = torus_project, .bounding_radius = torus_radius, .support = torus_support,
    /* mass properties: derived by floe (quadrature of sdf <= 0) */
};

typedef struct torus_params {
    floe_params_head head;
    double major, minor;
} torus_params;

static const floe_param torus_schema[] = {
    {.key = "major", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "m",
     .min = 0, .max = INFINITY, .doc = "radius of the ring's centre line", .offset = offsetof(torus_params, major)},
    {.key = "minor", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "m",
     .min = 0, .max = INFINITY, .doc = "radius of the tube", .offset = offsetof(torus_params, minor)},
};

static floe_geometry *torus_create(const void *params, int dim, char *err, size_t errlen) {
    const torus_params *p = params;
    if (dim != 3) {
        snprintf(err, errlen, "a torus is a 3D shape");
        return NULL;
    }
    if (!(p->minor < p->major)) {
        snprintf(err, errlen, "minor (%g m) must be below major (%g m): the ring would have no hole", p->minor,
                 p->major);
        return NULL;
    }
    torus *t = calloc(1, sizeof *t); /* floe frees it (no destroy: plain free) */
    if (!t) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    t->base.klass = &torus_class;
    t->R = p->major;
    t->r = p->minor;
    return &t->base;
}

/* ---- law: hooke ---- */

typedef struct hooke {
    floe_contact_law base;
    double k;
} hooke;

static int hooke_force(const floe_contact_law *law, const floe_contact *c, double *history,
                       floe_contact_result *out) {
    (void)history;
    const double k = ((const hooke *)law)->k, f = k * c->depth;
    for (int a = 0; a < 3; a++) out->force[a] = -f * c->n[a]; /* n points from i to j: push i back */
    out->fn = f;
    out->energy = 0.5 * k * c->depth * c->depth;
    return FLOE_OK;
}

static void hooke_stiffness(const floe_contact_law *law, double r_eff, double m_eff, double depth, double *kn,
                            double *cn) {
    (void)r_eff;
    (void)m_eff;
    (void)depth;
    *kn = ((const hooke *)law)->k;
    *cn = 0;
}

static const floe_contact_law_class hooke_class = {
    .version = 1, .name = "hooke", .history_size = 0, .force = hooke_force, .stiffness = hooke_stiffness,
};

typedef struct hooke_params {
    floe_params_head head;
    double k;
} hooke_params;

static const floe_param hooke_schema[] = {
    {.key = "k", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "N/m",
     .min = 0, .max = INFINITY, .doc = "spring stiffness", .offset = offsetof(hooke_params, k)},
};

static floe_contact_law *hooke_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                      size_t errlen) {
    (void)a;
    (void)b;
    hooke *h = calloc(1, sizeof *h); /* laws are calloc'd: fields the world reads start at 0 */
    if (!h) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    h->base.klass = &hooke_class;
    h->k = ((const hooke_params *)params)->k;
    return &h->base;
}

/* ---- output: contact_count ---- */

typedef struct contacts_out {
    floe_observer base;
    FILE *f;
    int energy;
} contacts_out;

static int contacts_observe(floe_observer *o, floe_world *w) {
    contacts_out *c = (contacts_out *)o;
    fprintf(c->f, "%.9g,%d", floe_world_time(w), floe_world_contact_count(w));
    if (c->energy) {
        floe_energy e = floe_world_energy(w);
        fprintf(c->f, ",%.9g", e.kinetic_trans + e.kinetic_rot);
    }
    fprintf(c->f, "\n");
    return fflush(c->f) ? FLOE_EIO : FLOE_OK;
}

static void contacts_destroy(floe_observer *o) {
    contacts_out *c = (contacts_out *)o;
    if (c->f) fclose(c->f);
    free(c);
}

static const floe_observer_class contacts_class = {
    .version = 1, .name = "contact_count", .observe = contacts_observe, .destroy = contacts_destroy,
};

typedef struct contacts_params {
    floe_params_head head;
    int energy;
} contacts_params;

static const floe_param contacts_schema[] = {
    {.key = "energy", .type = FLOE_PARAM_BOOL, .unit = "", .def = 1, .doc = "add the kinetic energy column",
     .offset = offsetof(contacts_params, energy)},
};

static floe_observer *contacts_create(const void *params, const floe_output_ctx *ctx, char *err, size_t errlen) {
    contacts_out *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    c->f = fopen(ctx->path, "w");
    if (!c->f) {
        snprintf(err, errlen, "cannot write %s", ctx->path);
        free(c);
        return NULL;
    }
    c->base.klass = &contacts_class;
    c->energy = ((const contacts_params *)params)->energy;
    fprintf(c->f, "t [s],contacts%s\n", c->energy ? ",kinetic [J]" : "");
    return &c->base;
}

/* ---- registration ---- */

#define COUNT(a) ((int)(sizeof a / sizeof *a))

static const floe_registry_entry entries[] = {
    {.kind = FLOE_KIND_SHAPE, .name = "torus", .title = "torus (plugin)", .doc = "A ring about the body z axis.",
     .source = "examples/plugin", .params = torus_schema, .nparams = COUNT(torus_schema),
     .params_size = sizeof(torus_params), .create = (floe_fn)torus_create},
    {.kind = FLOE_KIND_LAW, .name = "hooke", .title = "Hooke spring (plugin)",
     .doc = "A linear spring on the depth along the normal; no damping, no friction.", .source = "examples/plugin",
     .params = hooke_schema, .nparams = COUNT(hooke_schema), .params_size = sizeof(hooke_params),
     .create = (floe_fn)hooke_create},
    {.kind = FLOE_KIND_OBSERVER, .name = "contact_count", .title = "contact count (plugin)",
     .doc = "CSV of t, the number of contacts and the kinetic energy.", .source = "examples/plugin",
     .params = contacts_schema, .nparams = COUNT(contacts_schema), .params_size = sizeof(contacts_params),
     .create = (floe_fn)contacts_create},
};

int floe_plugin_init(char *err, size_t errlen);
int floe_plugin_init(char *err, size_t errlen) {
    for (int k = 0; k < COUNT(entries); k++) {
        int rc = floe_register(&entries[k], err, errlen);
        if (rc != FLOE_OK) return rc;
    }
    return FLOE_OK;
}
