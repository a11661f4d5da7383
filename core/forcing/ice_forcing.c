/* ice_forcing.c - the forcing providers of floes (floe_forcing.h, docs/sea-ice.md): ocean
 * and wind drag integrated over each floe's area, Coriolis with the sea-surface tilt, and
 * their registry entries (kind "provider", named in a scene's `forces:`; a gridded field's
 * file is read when the provider is created). */
#include "floe_forcing.h"
#include "forcing_parts.h"
#include "floe_view.h"
#include "floe_registry.h"
#include "particle_store.h"
#include "world_internal.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the trapezoid work of a force that changes over the step: the force of the last
 * evaluation per particle (force x3, torque z) */
typedef struct last_force {
    double *old; /* 4n */
    int n;
} last_force;

/* A gridded field covers every free particle's bounding box [x - r, x + r], or the provider
 * refuses: at its first evaluation (the world's prepare), and whenever a particle leaves the
 * grid during the run (the time then in the message); a grid is never extrapolated. */
static int field_covers_all(floe_world *w, const char *who, const floe_field *f, const floe_particles *p, int first,
                            double time) {
    if (f->kind != FLOE_FIELD_GRID) return FLOE_OK;
    char msg[768];
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE ||
            !floe_field_covers(f, p->x + 3 * i, p->radius[i], (int)floe_world_pid(w, i), msg, sizeof msg))
            continue;
        if (first) return floe_world_report_error(w, FLOE_EINVAL, "%s: %s", who, msg);
        return floe_world_report_error(w, FLOE_EINVAL, "%s: %s at t = %.9g s", who, msg, time);
    }
    return FLOE_OK;
}

static int last_reserve(last_force *l, int n) {
    if (l->n >= n) return FLOE_OK;
    double *o = realloc(l->old, (size_t)n * 4 * sizeof *o);
    if (!o) return FLOE_ENOMEM;
    memset(o + 4 * (size_t)l->n, 0, (size_t)(n - l->n) * 4 * sizeof *o);
    l->old = o;
    l->n = n;
    return FLOE_OK;
}

/* ======================= quadratic drag ======================= */

typedef struct drag_pv {
    floe_provider base;
    floe_provider_class klass; /* its own copy: the name is the instance's */
    char name[32];
    floe_drag_def d;
    double cs, sn;             /* cos and sin of the turning angle */
    floe_area_quadrature *quad;/* per geometry index, built at first use */
    int nquad;
    last_force last;
    int evaluated;             /* 1 after the first evaluation (prepare) */
} drag_pv;

floe_drag_def floe_ocean_drag_default(void) {
    floe_drag_def d;
    memset(&d, 0, sizeof d);
    d.rho = 1027.0;                    /* Subzero.jl Constants.ρo */
    d.cd = 3.0e-3;                     /* Constants.Cd_io */
    d.turning_angle = 15.0 * M_PI / 180; /* Constants.turnθ */
    d.quadrature = 1;
    return d;
}

floe_drag_def floe_wind_drag_default(void) {
    floe_drag_def d;
    memset(&d, 0, sizeof d);
    d.rho = 1.2;                       /* Subzero.jl Constants.ρa */
    d.cd = 1.0e-3;                     /* Constants.Cd_ia */
    d.quadrature = 1;
    return d;
}

static const floe_area_quadrature *drag_quad(drag_pv *d, floe_world *w, int g) {
    if (g >= d->nquad) {
        int nq = floe_world_geometry_count(w);
        if (nq <= g) nq = g + 1;
        floe_area_quadrature *q = realloc(d->quad, (size_t)nq * sizeof *q);
        if (!q) return NULL;
        memset(q + d->nquad, 0, (size_t)(nq - d->nquad) * sizeof *q);
        d->quad = q;
        d->nquad = nq;
    }
    floe_area_quadrature *q = d->quad + g;
    if (!q->n) {
        char err[256];
        if (floe_area_quadrature_build(floe_world_geometry_at(w, g), d->d.quadrature, q, err, sizeof err)) {
            floe_world_report_error(w, FLOE_EINVAL, "%s: %s", d->name, err);
            return NULL;
        }
    }
    return q;
}

/* the drag on floe i: force f (x, y) and torque tz about its centre */
static void drag_floe(const drag_pv *d, const floe_area_quadrature *q, const double *x, const double *v,
                      const double *om, const double *qt, double time, double out[3]) {
    /* the floe's rotation about z: cos a = w^2 - z^2, sin a = 2 w z */
    const double ca = qt[0] * qt[0] - qt[3] * qt[3], sa = 2 * qt[0] * qt[3];
    const double rc = d->d.rho * d->d.cd, cs = d->cs, sn = d->sn, wz = om[2];
    const int uniform = d->d.field.kind == FLOE_FIELD_UNIFORM;
    double U[3] = {d->d.field.U[0], d->d.field.U[1], 0};
    double fx = 0, fy = 0, tz = 0;
    for (int k = 0; k < q->n; k++) {
        const double *b = q->x + 3 * k;
        const double rx = ca * b[0] - sa * b[1], ry = sa * b[0] + ca * b[1];
        if (!uniform) {
            const double X[3] = {x[0] + rx, x[1] + ry, 0};
            floe_field_eval(&d->d.field, X, time, U);
        }
        /* fluid velocity relative to the floe's point v + w k x r */
        const double dx = U[0] - (v[0] - wz * ry), dy = U[1] - (v[1] + wz * rx);
        const double s = rc * sqrt(dx * dx + dy * dy) * q->w[k];
        const double tx = s * (cs * dx - sn * dy), ty = s * (sn * dx + cs * dy);
        fx += tx;
        fy += ty;
        tz += rx * ty - ry * tx;
    }
    out[0] = fx;
    out[1] = fy;
    out[2] = tz;
}

/* one block of particles [i0, i1): their drag (integrated, or held), its work in sums[0] */
typedef struct drag_job {
    const drag_pv *d;
    const struct floe_step_ctx *ctx;
    floe_particles *p;
    int hold;
} drag_job;
static void drag_block(void *jv, int i0, int i1, double *sums) {
    const drag_job *jb = jv;
    const drag_pv *d = jb->d;
    const struct floe_step_ctx *ctx = jb->ctx;
    floe_particles *p = jb->p;
    double work = 0;
    for (int i = i0; i < i1; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        double fr[3];
        if (jb->hold) {
            const double *o = d->last.old + 4 * (size_t)i;
            fr[0] = o[0];
            fr[1] = o[1];
            fr[2] = o[3];
        } else /* its geometry's quadrature built before the blocks (drag_forces) */
            drag_floe(d, d->quad + p->geom[i], p->x + 3 * i, p->v + 3 * i, p->w + 3 * i, p->q + 4 * i, ctx->time, fr);
        p->f[3 * i] += fr[0];
        p->f[3 * i + 1] += fr[1];
        p->t[3 * i + 2] += fr[2];
        if (ctx->probe) continue;
        double *o = d->last.old + 4 * (size_t)i;
        const double *v = p->v + 3 * i;
        work += 0.5 * ctx->dt * ((fr[0] + o[0]) * v[0] + (fr[1] + o[1]) * v[1] + (fr[2] + o[3]) * p->w[3 * i + 2]);
        o[0] = fr[0];
        o[1] = fr[1];
        o[3] = fr[2];
    }
    sums[0] = work;
}

static int drag_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *ctx, floe_provider_out *out) {
    drag_pv *d = (drag_pv *)pv;
    floe_particles *p = ctx->p;
    if (ctx->dim != 2)
        return floe_world_report_error(w, FLOE_EINVAL, "%s is for 2D floes (dimension: 2): it integrates the drag "
                                       "over each floe's area in the plane", d->name);
    const int fresh = d->last.n < p->n; /* no force held yet */
    if (last_reserve(&d->last, p->n) || floe_world_pp_attach(w, &d->last.old, &d->last.n, 4))
        return floe_world_report_error(w, FLOE_ENOMEM, "%s: out of memory", d->name);
    FLOE_TRY(field_covers_all(w, d->name, &d->d.field, p, !d->evaluated, ctx->time));
    d->evaluated = 1;
    /* every k-th step (and at prepare) the drag is integrated; in between it is held */
    const int hold = d->d.every > 1 && !fresh && ctx->stepping && floe_world_step_count(w) % d->d.every != 0;
    /* the free floes' quadratures, built here (serially) so that the blocks only read them */
    for (int i = 0; i < p->n && !hold; i++) {
        const int g = p->geom[i];
        if (p->motion[i] == FLOE_FREE && (g >= d->nquad || !d->quad[g].n) && !drag_quad(d, w, g)) return FLOE_EINVAL;
    }
    /* the floes in blocks on the world's threads (the same bits for any number) */
    drag_job jb = {d, ctx, p, hold};
    double work;
    if (floe_world_blocks(w, p->n, 1, drag_block, &jb, &work))
        return floe_world_report_error(w, FLOE_ENOMEM, "%s: out of memory", d->name);
    /* the fluid's work on the floes: external (a wind puts energy in, still water takes it) */
    if (ctx->stepping) out->work_boundary += work;
    return FLOE_OK;
}

/* explicit stability of the linearised drag dv/dt = -c v, c = 2 rho C_d |du| A / m (the
 * derivative of the quadratic law), with |du| from the fluid at the floe and its speed now */
static double drag_critical(floe_provider *pv, floe_world *w) {
    drag_pv *d = (drag_pv *)pv;
    floe_particles_view pvw;
    if (floe_world_particles(w, &pvw)) return INFINITY;
    double cmax = 0;
    for (int i = 0; i < pvw.n; i++) {
        if (pvw.motion[i] != FLOE_FREE || !(pvw.mass[i] > 0)) continue;
        const floe_geometry *g = floe_world_particle_geometry(w, i);
        floe_mass_properties mp;
        if (!g || floe_geometry_mass_properties(g, 2, 1.0, &mp)) continue;
        double U[3], R = pvw.radius[i];
        floe_field_eval(&d->d.field, pvw.x + 3 * i, 0, U);
        double du = hypot(U[0] - pvw.v[3 * i], U[1] - pvw.v[3 * i + 1]) + fabs(pvw.w[3 * i + 2]) * R;
        if (d->d.field.kind == FLOE_FIELD_SHEAR) du += fabs(d->d.field.rate) * R;
        if (d->d.field.kind == FLOE_FIELD_GRID) du += floe_field_grid_max_gradient(d->d.field.grid) * R;
        double c = 2 * d->d.rho * d->d.cd * du * mp.volume / pvw.mass[i];
        if (c > cmax) cmax = c;
    }
    return cmax > 0 ? 2.0 / cmax : INFINITY;
}

static size_t drag_state_size(const floe_provider *pv, const floe_world *w) {
    (void)w;
    return 4 * (size_t)((const drag_pv *)pv)->last.n * sizeof(double);
}
static void drag_save(const floe_provider *pv, const floe_world *w, unsigned char *buf) {
    const drag_pv *d = (const drag_pv *)pv;
    (void)w;
    if (d->last.n) memcpy(buf, d->last.old, 4 * (size_t)d->last.n * sizeof(double));
}
static void drag_restore(floe_provider *pv, floe_world *w, const unsigned char *buf) {
    drag_pv *d = (drag_pv *)pv;
    (void)w;
    if (d->last.n) memcpy(d->last.old, buf, 4 * (size_t)d->last.n * sizeof(double));
}
static void drag_destroy(floe_provider *pv) {
    drag_pv *d = (drag_pv *)pv;
    for (int k = 0; k < d->nquad; k++) floe_area_quadrature_free(d->quad + k);
    free(d->quad);
    free(d->last.old);
    floe_field_grid_release(d->d.field.grid);
    free(d);
}

floe_provider *floe_drag_create(const char *name, const floe_drag_def *def, char *err, size_t errlen) {
    if (!def || !name || !name[0]) {
        snprintf(err, errlen, "drag: a name and a definition are required");
        return NULL;
    }
    if (!(def->rho >= 0) || !isfinite(def->rho) || !(def->cd >= 0) || !isfinite(def->cd)) {
        snprintf(err, errlen, "%s: rho and cd must be >= 0 and finite", name);
        return NULL;
    }
    if (!isfinite(def->turning_angle) || fabs(def->turning_angle) > M_PI / 2) {
        snprintf(err, errlen, "%s: the turning angle must be within [-90, 90] degrees", name);
        return NULL;
    }
    if (def->every < 0) {
        snprintf(err, errlen, "%s: every must be >= 1 (steps)", name);
        return NULL;
    }
    if (def->quadrature < 0 || def->quadrature > 64) {
        snprintf(err, errlen, "%s: quadrature must be in [1, 64]", name);
        return NULL;
    }
    char ferr[200];
    if (floe_field_check(&def->field, ferr, sizeof ferr)) {
        snprintf(err, errlen, "%s: %s", name, ferr);
        return NULL;
    }
    drag_pv *d = calloc(1, sizeof *d);
    if (!d) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    snprintf(d->name, sizeof d->name, "%s", name);
    d->d = *def;
    d->d.field.grid = def->field.kind == FLOE_FIELD_GRID ? floe_field_grid_retain(def->field.grid) : NULL;
    if (!d->d.quadrature) d->d.quadrature = 1;
    if (!d->d.every) d->d.every = 1;
    d->cs = cos(def->turning_angle);
    d->sn = sin(def->turning_angle);
    d->klass = (floe_provider_class){.version = 1, .name = d->name, .group = FLOE_GROUP_DEM, .forces = drag_forces,
                                     .critical_dt = drag_critical, .state_size = drag_state_size, .save = drag_save,
                                     .restore = drag_restore, .destroy = drag_destroy};
    d->base.klass = &d->klass;
    return &d->base;
}

/* ======================= Coriolis and tilt ======================= */

static int coriolis_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *ctx, floe_provider_out *out);

int floe_forcing_is_per_particle(const floe_provider *pv) {
    return pv && pv->klass && (pv->klass->forces == drag_forces || pv->klass->forces == coriolis_forces);
}

double floe_coriolis_parameter(double latitude_deg) { return 2 * FLOE_EARTH_OMEGA * sin(latitude_deg * M_PI / 180); }

floe_coriolis_def floe_coriolis_default(void) {
    floe_coriolis_def d;
    memset(&d, 0, sizeof d);
    d.f = 1.4e-4; /* Subzero.jl Constants.f (about 73.7 N) */
    d.g = 9.81;
    return d;
}

typedef struct coriolis_pv {
    floe_provider base;
    floe_coriolis_def d;
    last_force last;
    int evaluated;             /* 1 after the first evaluation (prepare) */
} coriolis_pv;

/* one block of particles [i0, i1): their Coriolis and tilt forces, their work in sums[0] */
typedef struct coriolis_job {
    const coriolis_pv *c;
    const struct floe_step_ctx *ctx;
    floe_particles *p;
    double ph, den, gx, gy;
} coriolis_job;
static void coriolis_block(void *jv, int i0, int i1, double *sums) {
    const coriolis_job *jb = jv;
    const coriolis_pv *c = jb->c;
    const struct floe_step_ctx *ctx = jb->ctx;
    floe_particles *p = jb->p;
    const double f = c->d.f, ph = jb->ph, den = jb->den, gx = jb->gx, gy = jb->gy;
    double work = 0;
    for (int i = i0; i < i1; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        const double *v = p->v + 3 * i, m = p->mass[i];
        double ug[3] = {0, 0, 0};
        if (c->d.tilt == FLOE_TILT_GEOSTROPHIC) floe_field_eval(&c->d.field, p->x + 3 * i, ctx->time, ug);
        const double ux = v[0] - ug[0], uy = v[1] - ug[1];
        /* -i f u / (1 + i ph) = -i f u (1 - i ph) / den = f (-ph u - i u) / den; -i u = (uy, -ux) */
        const double ax = f * (uy - ph * ux) / den, ay = f * (-ux - ph * uy) / den;
        const double fx = m * (ax + gx), fy = m * (ay + gy);
        p->f[3 * i] += fx;
        p->f[3 * i + 1] += fy;
        if (ctx->probe) continue;
        double *o = c->last.old + 4 * (size_t)i;
        work += 0.5 * ctx->dt * ((fx + o[0]) * v[0] + (fy + o[1]) * v[1]);
        o[0] = fx;
        o[1] = fy;
    }
    sums[0] = work;
}

static int coriolis_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *ctx, floe_provider_out *out) {
    coriolis_pv *c = (coriolis_pv *)pv;
    floe_particles *p = ctx->p;
    if (last_reserve(&c->last, p->n) || floe_world_pp_attach(w, &c->last.old, &c->last.n, 4))
        return floe_world_report_error(w, FLOE_ENOMEM, "coriolis: out of memory");
    if (c->d.tilt == FLOE_TILT_GEOSTROPHIC)
        FLOE_TRY(field_covers_all(w, "coriolis", &c->d.field, p, !c->evaluated, ctx->time));
    c->evaluated = 1;
    const double f = c->d.f;
    /* velocity Verlet: the Cayley rotation over the step, a = -i f u / (1 + i f dt / 2) in
     * complex form (u = v - U_g), so that v_{n+3/2} = v_{n+1/2} + dt a turns u by
     * 2 atan(f dt / 2) with its length kept */
    const int cayley = floe_world_definition(w)->integrator == FLOE_VELOCITY_VERLET;
    const double ph = cayley ? 0.5 * f * ctx->dt : 0, den = 1 + ph * ph;
    const double gx = c->d.tilt == FLOE_TILT_SLOPE ? -c->d.g * c->d.slope[0] : 0;
    const double gy = c->d.tilt == FLOE_TILT_SLOPE ? -c->d.g * c->d.slope[1] : 0;
    /* the floes in blocks on the world's threads (the same bits for any number) */
    coriolis_job jb = {c, ctx, p, ph, den, gx, gy};
    double work;
    if (floe_world_blocks(w, p->n, 1, coriolis_block, &jb, &work))
        return floe_world_report_error(w, FLOE_ENOMEM, "coriolis: out of memory");
    if (ctx->stepping) out->work_boundary += work;
    return FLOE_OK;
}

/* the rotation is exact in amplitude for any step; its phase error (f dt)^2 / 12 stays
 * below 1e-4 when f dt < 0.035: the limit is the step that keeps an inertial period to
 * about 180 steps */
static double coriolis_critical(floe_provider *pv, floe_world *w) {
    (void)w;
    double f = fabs(((coriolis_pv *)pv)->d.f);
    return f > 0 ? 0.035 / f : INFINITY;
}
static size_t coriolis_state_size(const floe_provider *pv, const floe_world *w) {
    (void)w;
    return 4 * (size_t)((const coriolis_pv *)pv)->last.n * sizeof(double);
}
static void coriolis_save(const floe_provider *pv, const floe_world *w, unsigned char *buf) {
    const coriolis_pv *c = (const coriolis_pv *)pv;
    (void)w;
    if (c->last.n) memcpy(buf, c->last.old, 4 * (size_t)c->last.n * sizeof(double));
}
static void coriolis_restore(floe_provider *pv, floe_world *w, const unsigned char *buf) {
    coriolis_pv *c = (coriolis_pv *)pv;
    (void)w;
    if (c->last.n) memcpy(c->last.old, buf, 4 * (size_t)c->last.n * sizeof(double));
}
static void coriolis_destroy(floe_provider *pv) {
    coriolis_pv *c = (coriolis_pv *)pv;
    free(c->last.old);
    floe_field_grid_release(c->d.field.grid);
    free(c);
}

static const floe_provider_class coriolis_class = {
    .version = 1, .name = "coriolis", .group = FLOE_GROUP_DEM, .forces = coriolis_forces,
    .critical_dt = coriolis_critical, .state_size = coriolis_state_size, .save = coriolis_save,
    .restore = coriolis_restore, .destroy = coriolis_destroy};

floe_provider *floe_coriolis_create(const floe_coriolis_def *def, char *err, size_t errlen) {
    if (!def || !isfinite(def->f)) {
        snprintf(err, errlen, "coriolis: f must be finite");
        return NULL;
    }
    if (def->tilt < FLOE_TILT_NONE || def->tilt > FLOE_TILT_SLOPE) {
        snprintf(err, errlen, "coriolis: unknown tilt %d", (int)def->tilt);
        return NULL;
    }
    if (def->tilt == FLOE_TILT_SLOPE &&
        (!isfinite(def->slope[0]) || !isfinite(def->slope[1]) || !(def->g >= 0) || !isfinite(def->g))) {
        snprintf(err, errlen, "coriolis: the slope and g must be finite (g >= 0)");
        return NULL;
    }
    char ferr[200];
    if (def->tilt == FLOE_TILT_GEOSTROPHIC && floe_field_check(&def->field, ferr, sizeof ferr)) {
        snprintf(err, errlen, "coriolis: %s", ferr);
        return NULL;
    }
    coriolis_pv *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    c->base.klass = &coriolis_class;
    c->d = *def;
    c->d.field.grid = def->tilt == FLOE_TILT_GEOSTROPHIC && def->field.kind == FLOE_FIELD_GRID
                          ? floe_field_grid_retain(def->field.grid) : NULL;
    return &c->base;
}

/* ======================= registry ======================= */

/* the keys of a velocity field, shared by the drag and Coriolis schemas (S.fp a field_params) */
#define FIELD_PARAMS(S)                                                                                           \
    {.key = "field", .type = FLOE_PARAM_CHOICE, .choices = "uniform|shear|gyre|vortex|netcdf", .def = 0,         \
     .doc = "the fluid's velocity field (docs/sea-ice.md, \"Velocity fields\"): uniform, simple shear, one gyre, " \
            "a Rankine vortex, gridded data from a NetCDF file",                                                  \
     .offset = offsetof(S, fp.field)},                                                                            \
    {.key = "velocity", .type = FLOE_PARAM_VEC3, .unit = "m/s", .doc = "its uniform part U (every field adds it)", \
     .offset = offsetof(S, fp.velocity)},                                                                         \
    {.key = "shear_rate", .type = FLOE_PARAM_REAL, .unit = "1/s", .def = 0,                                      \
     .doc = "shear: du_x/dy about the line y = center_y", .offset = offsetof(S, fp.shear_rate)},                  \
    {.key = "speed", .type = FLOE_PARAM_REAL, .unit = "m/s", .def = 0,                                           \
     .doc = "gyre, vortex: peak speed S (> 0 counter-clockwise)", .offset = offsetof(S, fp.speed)},              \
    {.key = "length", .type = FLOE_PARAM_REAL, .unit = "m", .def = 0, .min = 0, .max = INFINITY,                 \
     .doc = "gyre: side L of its square; vortex: core radius R", .offset = offsetof(S, fp.length)},              \
    {.key = "center", .type = FLOE_PARAM_VEC3, .unit = "m",                                                       \
     .doc = "shear: a point of the line of zero shear velocity; gyre: the square's lower-left corner; vortex: "   \
            "its centre",                                                                                          \
     .offset = offsetof(S, fp.center)},                                                                           \
    {.key = "file", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "",                                        \
     .doc = "netcdf: the NetCDF file (CF; x, y in metres; a relative path from the scene file's folder)",            \
     .offset = offsetof(S, fp.file)},                                                                             \
    {.key = "u_var", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "u",                                      \
     .doc = "netcdf: the variable of the velocity's x component, (time, y, x) or (y, x)",                        \
     .offset = offsetof(S, fp.u_var)},                                                                            \
    {.key = "v_var", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "v",                                      \
     .doc = "netcdf: the variable of the velocity's y component (the same grid as u_var)",                       \
     .offset = offsetof(S, fp.v_var)},                                                                            \
    {.key = "x_var", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "x",                                      \
     .doc = "netcdf: the x coordinate (m; the longitude with a projection), strictly increasing",                \
     .offset = offsetof(S, fp.x_var)},                                                                            \
    {.key = "y_var", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "y",                                      \
     .doc = "netcdf: the y coordinate (m; the latitude with a projection), strictly increasing",                 \
     .offset = offsetof(S, fp.y_var)},                                                                            \
    {.key = "time_var", .type = FLOE_PARAM_STRING, .unit = "", .def_text = "time",                                \
     .doc = "netcdf: the time coordinate (units seconds, minutes, hours or days since DATE; the simulation time is "   \
            "the time since DATE)",                                                                                \
     .offset = offsetof(S, fp.time_var)},                                                                         \
    {.key = "scale", .type = FLOE_PARAM_REAL, .unit = "", .def = 1,                                               \
     .doc = "netcdf: multiplier of the velocities read (after the file's scale_factor and add_offset)",           \
     .offset = offsetof(S, fp.scale)},                                                                            \
    {.key = "projection", .type = FLOE_PARAM_CHOICE, .choices = "none|equirectangular|polar_stereographic",      \
     .def = 0,                                                                                                    \
     .doc = "netcdf: the scene as a map of a grid in longitude and latitude (degrees): equirectangular (sphere "  \
            "R = 6371 km) or polar stereographic (WGS84); none: a grid in metres",                                \
     .offset = offsetof(S, fp.projection)},                                                                       \
    {.key = "lon0", .type = FLOE_PARAM_REAL, .unit = "deg", .def = 0,                                            \
     .doc = "netcdf, projection: the longitude of x = 0 (equirectangular), the central meridian "                \
            "(polar_stereographic, -y from the north pole; EPSG:3413 -45)",                                       \
     .offset = offsetof(S, fp.lon0)},                                                                             \
    {.key = "lat0", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN | FLOE_PARAM_MAX_OPEN, .unit = "deg",  \
     .min = -90, .max = 90, .def = 0,                                                                             \
     .doc = "netcdf, equirectangular: the latitude of y = 0, where the scale is true",                            \
     .offset = offsetof(S, fp.lat0)},                                                                             \
    {.key = "lat_ts", .type = FLOE_PARAM_REAL, .unit = "deg", .min = -90, .max = 90, .def = 70,                  \
     .doc = "netcdf, polar_stereographic: the latitude of true scale, > 0 north pole, < 0 south (EPSG:3413 70)",  \
     .offset = offsetof(S, fp.lat_ts)}

typedef struct field_params {
    int field;
    double velocity[3], shear_rate, speed, length, center[3];
    char file[FLOE_PARAM_STRING_MAX], u_var[FLOE_PARAM_STRING_MAX], v_var[FLOE_PARAM_STRING_MAX];
    char x_var[FLOE_PARAM_STRING_MAX], y_var[FLOE_PARAM_STRING_MAX], time_var[FLOE_PARAM_STRING_MAX];
    double scale;
    int projection;
    double lon0, lat0, lat_ts;
} field_params;

/* The field of a provider's parameters (entry e, struct params): a netcdf one reads its file
 * (the grid's reference is the caller's: floe_field_grid_release after creating the
 * provider). FLOE_OK, or an error with the message in err. */
static int field_of(const floe_registry_entry *e, const void *params, const field_params *p, floe_field *f,
                    char *err, size_t errlen) {
    memset(f, 0, sizeof *f);
    f->kind = (floe_field_kind)p->field;
    memcpy(f->U, p->velocity, sizeof f->U);
    f->rate = p->shear_rate;
    f->speed = p->speed;
    f->length = p->length;
    memcpy(f->center, p->center, sizeof f->center);
    static const char *const grid_keys[] = {"file", "u_var", "v_var", "x_var", "y_var", "time_var", "scale",
                                            "projection", "lon0", "lat0", "lat_ts"};
    if (f->kind != FLOE_FIELD_GRID) {
        for (size_t k = 0; e && k < sizeof grid_keys / sizeof *grid_keys; k++)
            if (floe_params_given(e, params, grid_keys[k])) {
                snprintf(err, errlen, "%s is only read with field: netcdf", grid_keys[k]);
                return FLOE_EINVAL;
            }
        return FLOE_OK;
    }
    if (!p->file[0]) {
        snprintf(err, errlen, "field: netcdf needs file (the NetCDF file of the velocities)");
        return FLOE_EINVAL;
    }
    /* the projection's keys: each only with the projection that reads it */
    static const struct { const char *key; int for_kind; } pkeys[] = {
        {"lon0", -1}, {"lat0", FLOE_PROJECTION_EQUIRECTANGULAR}, {"lat_ts", FLOE_PROJECTION_POLAR_STEREOGRAPHIC}};
    static const char *const pnames[] = {"none", "equirectangular", "polar_stereographic"};
    for (size_t k = 0; e && k < sizeof pkeys / sizeof *pkeys; k++)
        if (floe_params_given(e, params, pkeys[k].key) &&
            (p->projection == FLOE_PROJECTION_NONE || (pkeys[k].for_kind >= 0 && pkeys[k].for_kind != p->projection))) {
            if (pkeys[k].for_kind >= 0)
                snprintf(err, errlen, "%s is only read with projection: %s (not %s)", pkeys[k].key,
                         pnames[pkeys[k].for_kind], pnames[p->projection]);
            else
                snprintf(err, errlen, "%s is only read with a projection (equirectangular or polar_stereographic)",
                         pkeys[k].key);
            return FLOE_EINVAL;
        }
    floe_field_grid_def gd = {.file = p->file, .u_var = p->u_var, .v_var = p->v_var, .x_var = p->x_var,
                              .y_var = p->y_var, .time_var = p->time_var, .scale = p->scale,
                              .projection = {.kind = (floe_projection_kind)p->projection, .lon0 = p->lon0,
                                             .lat0 = p->lat0, .lat_ts = p->lat_ts}};
    f->grid = floe_field_grid_load(&gd, err, errlen);
    return f->grid ? FLOE_OK : FLOE_EINVAL;
}

typedef struct drag_params {
    floe_params_head head;
    double rho, cd, turning_angle;
    int quadrature, every;
    field_params fp;
} drag_params;

static floe_provider *drag_build(const char *name, const void *params, char *err, size_t errlen) {
    const drag_params *p = params;
    floe_drag_def d;
    memset(&d, 0, sizeof d);
    d.rho = p->rho;
    d.cd = p->cd;
    d.turning_angle = p->turning_angle * M_PI / 180;
    d.quadrature = p->quadrature;
    d.every = p->every;
    if (field_of(floe_registry_find(FLOE_KIND_PROVIDER, name), p, &p->fp, &d.field, err, errlen)) return NULL;
    floe_provider *pv = floe_drag_create(name, &d, err, errlen);
    floe_field_grid_release(d.field.grid); /* the provider holds its own reference */
    return pv;
}
static floe_provider *ocean_create(const void *params, const floe_world *w, char *err, size_t errlen) {
    (void)w;
    return drag_build("ocean_drag", params, err, errlen);
}
static floe_provider *wind_create(const void *params, const floe_world *w, char *err, size_t errlen) {
    (void)w;
    return drag_build("wind_drag", params, err, errlen);
}

#define DRAG_SCHEMA(rho_def, cd_def, theta_def, what)                                                             \
    {{.key = "rho", .type = FLOE_PARAM_REAL, .unit = "kg/m^3", .min = 0, .max = INFINITY, .def = rho_def,        \
      .doc = "density of the " what, .offset = offsetof(drag_params, rho)},                                       \
     {.key = "cd", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY, .def = cd_def,                \
      .doc = "drag coefficient C_d of ice against the " what, .offset = offsetof(drag_params, cd)},               \
     {.key = "turning_angle", .type = FLOE_PARAM_REAL, .unit = "deg", .min = -90, .max = 90, .def = theta_def,   \
      .doc = "theta: the stress is the relative velocity turned counter-clockwise by theta (> 0 north)",          \
      .offset = offsetof(drag_params, turning_angle)},                                                             \
     {.key = "quadrature", .type = FLOE_PARAM_INT, .unit = "", .min = 1, .max = 64, .def = 1,                     \
      .doc = "subdivision level of the area quadrature (polygons: level^2 triangles of 3 points per edge's fan triangle)",    \
      .offset = offsetof(drag_params, quadrature)},                                                                \
     {.key = "every", .type = FLOE_PARAM_INT, .unit = "steps", .min = 1, .max = 1e9, .def = 1,                    \
      .doc = "integrate the drag every k-th step and hold it in between (SubZero couples every 10)",             \
      .offset = offsetof(drag_params, every)},                                                                     \
     FIELD_PARAMS(drag_params)}

static const floe_param ocean_schema[] = DRAG_SCHEMA(1027.0, 3.0e-3, 15.0, "water");
static const floe_param wind_schema[] = DRAG_SCHEMA(1.2, 1.0e-3, 0.0, "air");

const floe_registry_entry floe_provider_entry_ocean_drag = {
    .kind = FLOE_KIND_PROVIDER, .name = "ocean_drag", .title = "ocean drag",
    .doc = "Quadratic ice-ocean drag on 2D floes, tau = rho C_d |du| R(theta) du with du the current minus the "
           "floe's velocity at each point (v + w k x r), integrated over the floe's area (force and torque). "
           "Defaults as SubZero (rho 1027, C_d 3e-3, theta 15 deg); DEMSI uses C_d 5.5e-3 without turning.",
    .source = "docs/sea-ice.md; Hibler (1979) J. Phys. Oceanogr. 9; Subzero.jl coupling.jl calc_ocean_forcing!",
    .params = ocean_schema, .nparams = sizeof ocean_schema / sizeof *ocean_schema,
    .params_size = sizeof(drag_params), .create = (floe_fn)ocean_create};

const floe_registry_entry floe_provider_entry_wind_drag = {
    .kind = FLOE_KIND_PROVIDER, .name = "wind_drag", .title = "wind drag",
    .doc = "Quadratic ice-air drag on 2D floes, tau = rho C_d |du| R(theta) du with du the wind minus the floe's "
           "velocity at each point, integrated over the floe's area. Defaults as SubZero (rho 1.2, C_d 1e-3, "
           "no turning); DEMSI uses C_d 1.2e-3.",
    .source = "docs/sea-ice.md; Subzero.jl coupling.jl calc_atmosphere_forcing",
    .params = wind_schema, .nparams = sizeof wind_schema / sizeof *wind_schema,
    .params_size = sizeof(drag_params), .create = (floe_fn)wind_create};

typedef struct coriolis_params {
    floe_params_head head;
    double f, latitude;
    int tilt;
    double slope[3], g;
    field_params fp;
} coriolis_params;

static floe_provider *coriolis_make(const void *params, const floe_world *w, char *err, size_t errlen) {
    const coriolis_params *p = params;
    (void)w;
    const floe_registry_entry *e = floe_registry_find(FLOE_KIND_PROVIDER, "coriolis");
    int gf = e && floe_params_given(e, p, "f"), gl = e && floe_params_given(e, p, "latitude");
    if (gf && gl) {
        snprintf(err, errlen, "give either f or latitude, not both");
        return NULL;
    }
    floe_coriolis_def d = floe_coriolis_default();
    if (gf) d.f = p->f;
    if (gl) d.f = floe_coriolis_parameter(p->latitude);
    d.tilt = (floe_tilt_kind)p->tilt;
    memcpy(d.slope, p->slope, sizeof d.slope);
    d.g = p->g;
    int gfield = e && (floe_params_given(e, p, "field") || floe_params_given(e, p, "velocity"));
    if (d.tilt == FLOE_TILT_GEOSTROPHIC && !gfield) {
        snprintf(err, errlen, "tilt: geostrophic needs the current (field and/or velocity, as the ocean_drag's)");
        return NULL;
    }
    if (d.tilt != FLOE_TILT_GEOSTROPHIC && gfield) {
        snprintf(err, errlen, "a current (field, velocity) is only read with tilt: geostrophic");
        return NULL;
    }
    if (d.tilt != FLOE_TILT_SLOPE && e && floe_params_given(e, p, "slope")) {
        snprintf(err, errlen, "slope is only read with tilt: slope");
        return NULL;
    }
    if (field_of(e, p, &p->fp, &d.field, err, errlen)) return NULL;
    floe_provider *pv = floe_coriolis_create(&d, err, errlen);
    floe_field_grid_release(d.field.grid); /* the provider holds its own reference */
    return pv;
}

static const floe_param coriolis_schema[] = {
    {.key = "f", .type = FLOE_PARAM_REAL, .unit = "1/s", .def = 1.4e-4,
     .doc = "Coriolis parameter (> 0 north; SubZero's 1.4e-4, about 73.7 N)", .offset = offsetof(coriolis_params, f)},
    {.key = "latitude", .type = FLOE_PARAM_REAL, .unit = "deg", .min = -90, .max = 90, .def = 0,
     .doc = "instead of f: f = 2 Omega sin(latitude), Omega = 7.2921e-5 rad/s",
     .offset = offsetof(coriolis_params, latitude)},
    {.key = "tilt", .type = FLOE_PARAM_CHOICE, .choices = "none|geostrophic|slope", .def = 0,
     .doc = "sea-surface tilt: none, geostrophic (of the current given below), or a given slope",
     .offset = offsetof(coriolis_params, tilt)},
    {.key = "slope", .type = FLOE_PARAM_VEC3, .unit = "", .doc = "tilt slope: grad(eta), F = -m g grad(eta)",
     .offset = offsetof(coriolis_params, slope)},
    {.key = "g", .type = FLOE_PARAM_REAL, .unit = "m/s^2", .min = 0, .max = INFINITY, .def = 9.81,
     .doc = "tilt slope: gravity", .offset = offsetof(coriolis_params, g)},
    FIELD_PARAMS(coriolis_params)};

const floe_registry_entry floe_provider_entry_coriolis = {
    .kind = FLOE_KIND_PROVIDER, .name = "coriolis", .title = "Coriolis and sea-surface tilt",
    .doc = "Coriolis force F = -m f k x (v - U_g) on every free particle's centre (no torque), with the "
           "sea-surface tilt: none (U_g = 0), geostrophic (U_g the current: the tilt balances it, as SubZero) or a "
           "slope (adds -m g grad(eta)). Under velocity Verlet the rotation over a step is the implicit midpoint "
           "(Cayley) one: inertial oscillations keep their amplitude and their period 2 pi/f to (f dt)^2/12.",
    .source = "docs/sea-ice.md; Subzero.jl coupling.jl (Coriolis, pressure gradient); DEMSI demsi_external_force.cpp",
    .params = coriolis_schema, .nparams = sizeof coriolis_schema / sizeof *coriolis_schema,
    .params_size = sizeof(coriolis_params), .create = (floe_fn)coriolis_make};

static const floe_registry_entry *const builtin[] = {&floe_provider_entry_ocean_drag, &floe_provider_entry_wind_drag,
                                                     &floe_provider_entry_coriolis};

int floe_register_builtin_forcing(char *err, size_t errlen) {
    return floe_register_list(builtin, sizeof builtin / sizeof *builtin, err, errlen);
}
