/* view.c - the read-only view of a world (floe_view.h). */
#include "world_internal.h"

int floe_world_particles(const floe_world *w, floe_particles_view *o) {
    if (!w || !o) return FLOE_EINVAL;
    const floe_particles *p = &w->p;
    o->n = p->n;
    o->dim = w->def.dim;
    o->x = p->x;
    o->v = p->v;
    o->q = p->q;
    o->w = p->w;
    o->f = p->f;
    o->t = p->t;
    o->mass = p->mass;
    o->inertia = p->inertia;
    o->radius = p->radius;
    o->geometry = p->geom;
    o->material = p->material;
    o->group = p->group;
    o->motion = p->motion;
    return FLOE_OK;
}

int floe_world_contacts(const floe_world *w, const floe_contact_info **out) {
    if (!w) return -FLOE_EINVAL;
    if (!w->contacts_valid) {
        if (out) *out = NULL;
        return -FLOE_EINVAL;
    }
    if (out) *out = w->contacts;
    return w->ncontacts;
}

int floe_world_geometry_count(const floe_world *w) { return w ? w->ngeoms : 0; }

const floe_geometry *floe_world_geometry_at(const floe_world *w, int k) {
    return w && k >= 0 && k < w->ngeoms ? w->geoms[k] : NULL;
}

const floe_geometry *floe_world_particle_geometry(const floe_world *w, int i) {
    return w && i >= 0 && i < w->p.n ? w->geoms[w->p.geom[i]] : NULL;
}

const floe_world_def *floe_world_definition(const floe_world *w) { return w ? &w->def : NULL; }

int floe_world_dim(const floe_world *w) { return w ? w->def.dim : 0; }

int floe_world_pd_body_of(const floe_world *w, int i) {
    if (!w || !w->pd_of || i < 0 || i >= w->pd_npts_alloc) return -1;
    return w->pd_of[i];
}

int floe_world_neighbor_stats(const floe_world *w, floe_neighbor_stats *o) {
    if (!w || !o) return FLOE_EINVAL;
    o->pairs = w->nl.npairs;
    o->rebuilds = w->nl.rebuilds;
    o->skin = w->nl.skin;
    return FLOE_OK;
}

/* observers (wt-obs) */
#include <stdarg.h>
#include <stdio.h>

int floe_world_particle_kind(const floe_world *w, int i) {
    if (!w || i < 0 || i >= w->p.n) return -1;
    if (w->p.kind) return w->p.kind[i];
    const floe_geometry *g = w->geoms && w->p.geom ? w->geoms[w->p.geom[i]] : NULL;
    return g && g->klass ? (int)g->klass->kind : -1;
}

int floe_world_report_error(floe_world *w, int code, const char *fmt, ...) {
    if (!w) return code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(w->err, sizeof w->err, fmt, ap);
    va_end(ap);
    return code;
}
