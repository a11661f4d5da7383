/* user_providers.c - user force providers (floe_provider.h floe_world_add_provider), the
 * public view of an evaluation (floe_provider_ctx.h) and the built-in registered provider
 * `linear_drag` (kind FLOE_KIND_PROVIDER, named in a scene's `forces:`). */
#include "world_parts.h"
#include "floe_registry.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

floe_provider_ctx floe_provider_ctx_of(const struct floe_step_ctx *ctx) {
    floe_provider_ctx c;
    memset(&c, 0, sizeof c);
    if (!ctx) return c;
    const floe_particles *p = ctx->p;
    c.n = p->n;
    c.dim = ctx->dim;
    c.x = p->x;
    c.v = p->v;
    c.q = p->q;
    c.w = p->w;
    c.mass = p->mass;
    c.inertia = p->inertia;
    c.motion = p->motion;
    c.f = p->f;
    c.t = p->t;
    c.time = ctx->time;
    c.dt = ctx->dt;
    c.stepping = ctx->stepping;
    c.probe = ctx->probe;
    return c;
}

int floe_provider_splits(const floe_provider *pv) {
    return pv && pv->klass && pv->klass->version >= 2 ? pv->klass->splits : 0; /* (version 1 has no such field) */
}

int floe_world_add_provider(floe_world *w, floe_provider *pv) {
    if (!w) return FLOE_EINVAL;
    if (!pv || !pv->klass) return floe_world_error(w, FLOE_EINVAL, "provider is NULL or has no class");
    const floe_provider_class *k = pv->klass;
    if ((k->version != 1 && k->version != 2) || !k->name || !k->name[0] || !k->forces)
        return floe_world_error(w, FLOE_EINVAL, "provider class %s: version 1 or 2, a name and forces() are required",
                                k->name ? k->name : "(unnamed)");
    if (k->version == 2 && k->splits != 0 && k->splits != FLOE_PROVIDER_PER_PARTICLE)
        return floe_world_error(w, FLOE_EINVAL, "provider %s: splits must be 0 or FLOE_PROVIDER_PER_PARTICLE (got %d)",
                                k->name, k->splits);
    if (floe_provider_splits(pv) == FLOE_PROVIDER_PER_PARTICLE && (k->state_size || k->excludes))
        return floe_world_error(w, FLOE_EINVAL, "provider %s: declares per-particle forces (splits) but keeps %s: a "
                                "per-particle provider keeps no state and excludes no pairs", k->name,
                                k->state_size ? "a state (state_size)" : "pairs out of the list (excludes)");
    if (k->group != FLOE_GROUP_DEM && k->group != FLOE_GROUP_PD)
        return floe_world_error(w, FLOE_EINVAL, "provider %s: group must be FLOE_GROUP_DEM or FLOE_GROUP_PD", k->name);
    if (k->state_size && (!k->save || !k->restore))
        return floe_world_error(w, FLOE_EINVAL, "provider %s: state_size needs save and restore", k->name);
    if (w->prepared)
        return floe_world_error(w, FLOE_EINVAL, "provider %s: add providers before the world is prepared (its first "
                                "step)", k->name);
    if (floe_provider_is_user(w, pv)) return floe_world_error(w, FLOE_EINVAL, "provider %s was added twice", k->name);
    if (grow((void **)&w->uprov, &w->uprov_cap, w->nuprov + 1, sizeof *w->uprov))
        return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    w->uprov[w->nuprov++] = pv;
    return FLOE_OK;
}

/* ---- linear_drag: F = -c m v, T = -c_r L (L = I w, the angular momentum) ---- */

typedef struct drag_params {
    floe_params_head head;
    double c, c_r;
} drag_params;

typedef struct drag {
    floe_provider base;
    double c, c_r;
    double *old; /* 6n: the force and torque of the last evaluation (trapezoid work) */
    int n;
} drag;

/* one block of particles [i0, i1): their drag, its work over the step in sums[0] */
typedef struct drag_job {
    const drag *d;
    floe_provider_ctx c;
} drag_job;
static void drag_block(void *ctx, int i0, int i1, double *sums) {
    const drag_job *jb = ctx;
    const drag *d = jb->d;
    const floe_provider_ctx *c = &jb->c;
    double work = 0;
    for (int i = i0; i < i1; i++) {
        if (c->motion[i] != FLOE_FREE) continue;
        const double *v = c->v + 3 * (size_t)i, *om = c->w + 3 * (size_t)i, *q = c->q + 4 * (size_t)i;
        const double *I = c->inertia + 3 * (size_t)i;
        double f[3], t[3], wb[3], Lb[3], L[3];
        floe_q_rotate_inv(wb, q, om); /* the angular momentum I w, through the body frame */
        for (int a = 0; a < 3; a++) Lb[a] = I[a] * wb[a];
        floe_q_rotate(L, q, Lb);
        for (int a = 0; a < 3; a++) {
            f[a] = -d->c * c->mass[i] * v[a];
            t[a] = -d->c_r * L[a];
            c->f[3 * (size_t)i + a] += f[a];
            c->t[3 * (size_t)i + a] += t[a];
        }
        if (c->probe) continue;
        double *old = d->old + 6 * (size_t)i;
        for (int a = 0; a < 3; a++) work += 0.5 * c->dt * ((f[a] + old[a]) * v[a] + (t[a] + old[3 + a]) * om[a]);
        memcpy(old, f, sizeof f);
        memcpy(old + 3, t, sizeof t);
    }
    sums[0] = work;
}

static int drag_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *sc, floe_provider_out *out) {
    drag *d = (drag *)pv;
    floe_provider_ctx c = floe_provider_ctx_of(sc);
    if (d->n < c.n) {
        double *o = realloc(d->old, (size_t)c.n * 6 * sizeof *o);
        if (!o) return floe_world_error(w, FLOE_ENOMEM, "linear_drag: out of memory");
        memset(o + 6 * (size_t)d->n, 0, (size_t)(c.n - d->n) * 6 * sizeof *o);
        d->old = o;
        d->n = c.n;
    }
    /* its rows move with their particles under MPI */
    if (floe_world_pp_attach(w, &d->old, &d->n, 6)) return floe_world_error(w, FLOE_ENOMEM, "linear_drag: out of memory");
    /* the particles in blocks on the world's threads (the same bits for any number) */
    drag_job jb = {d, c};
    double work;
    if (floe_world_blocks(w, c.n, 1, drag_block, &jb, &work))
        return floe_world_error(w, FLOE_ENOMEM, "linear_drag: out of memory");
    if (c.stepping) out->dissipated -= work; /* the drag's work is negative: dissipated */
    return FLOE_OK;
}

/* its state: the last forces (the ledger's trapezoid), restored with a rejected step */
static size_t drag_state_size(const floe_provider *pv, const floe_world *w) {
    (void)w;
    return 6 * (size_t)((const drag *)pv)->n * sizeof(double);
}
static void drag_save(const floe_provider *pv, const floe_world *w, unsigned char *buf) {
    const drag *d = (const drag *)pv;
    (void)w;
    if (d->n) memcpy(buf, d->old, 6 * (size_t)d->n * sizeof(double));
}
static void drag_restore(floe_provider *pv, floe_world *w, const unsigned char *buf) {
    drag *d = (drag *)pv;
    (void)w;
    if (d->n) memcpy(d->old, buf, 6 * (size_t)d->n * sizeof(double));
}
static double drag_critical(floe_provider *pv, floe_world *w) {
    const drag *d = (const drag *)pv;
    (void)w;
    double c = fmax(d->c, d->c_r); /* explicit stability of dv/dt = -c v: c dt < 2 */
    return c > 0 ? 2.0 / c : INFINITY;
}
static void drag_destroy(floe_provider *pv) {
    drag *d = (drag *)pv;
    free(d->old);
    free(d);
}

static const floe_provider_class drag_class = {
    .version = 1, .name = "linear_drag", .group = FLOE_GROUP_DEM, .forces = drag_forces,
    .critical_dt = drag_critical, .state_size = drag_state_size, .save = drag_save, .restore = drag_restore,
    .destroy = drag_destroy};

int floe_linear_drag_is(const floe_provider *pv) { return pv && pv->klass == &drag_class; }

static floe_provider *drag_create(const void *params, const floe_world *w, char *err, size_t errlen) {
    const drag_params *p = params;
    (void)w;
    drag *d = calloc(1, sizeof *d);
    if (!d) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    d->base.klass = &drag_class;
    d->c = p->c;
    d->c_r = p->c_r;
    return &d->base;
}

static const floe_param drag_schema[] = {
    {.key = "c", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED, .unit = "1/s", .min = 0, .max = INFINITY,
     .doc = "drag rate: F = -c m v on every free particle", .offset = offsetof(drag_params, c)},
    {.key = "c_r", .type = FLOE_PARAM_REAL, .unit = "1/s", .min = 0, .max = INFINITY, .def = 0,
     .doc = "rotational drag rate: torque -c_r I w (I w the angular momentum)", .offset = offsetof(drag_params, c_r)},
};

const floe_registry_entry floe_provider_entry_linear_drag = {
    .kind = FLOE_KIND_PROVIDER, .name = "linear_drag", .title = "linear drag",
    .doc = "A linear (Stokes-like) drag on every free particle: F = -c m v and T = -c_r I w, so a lone particle's "
           "velocity decays as v0 exp(-c t) and its angular momentum as L0 exp(-c_r t). The work it does is booked "
           "as dissipated energy.",
    .source = "docs/scene-format.md, \"forces\"",
    .params = drag_schema, .nparams = 2, .params_size = sizeof(drag_params), .create = (floe_fn)drag_create};

static const floe_registry_entry *const builtin[] = {&floe_provider_entry_linear_drag};

int floe_register_builtin_providers(char *err, size_t errlen) {
    return floe_register_list(builtin, sizeof builtin / sizeof *builtin, err, errlen);
}
