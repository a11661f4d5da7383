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
    o->L = p->L;
    o->f = p->f;
    o->t = p->t;
    o->mass = p->mass;
    o->inertia = p->inertia;
    o->radius = p->radius;
    o->geometry = p->geom;
    o->material = p->material;
    o->group = p->group;
    o->motion = p->motion;
    o->pieces = p->pieces;
    o->thickness = p->thick;
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

double floe_world_solid_volume(const floe_world *w) {
    if (!w) return 0.0;
    const floe_particles *p = &w->p;
    double v = 0;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        floe_mass_properties mp;
        if (floe_geometry_mass_properties(w->geoms[p->geom[i]], w->def.dim, 1.0, &mp) == FLOE_OK) v += mp.volume;
    }
    return v;
}

const floe_world_def *floe_world_definition(const floe_world *w) { return w ? &w->def : NULL; }

int floe_world_dim(const floe_world *w) { return w ? w->def.dim : 0; }

int floe_world_pd_body_of(const floe_world *w, int i) {
    if (!w || !w->pd_of || i < 0 || i >= w->pd_npts_alloc) return -1;
    return w->pd_of[i];
}

int floe_world_neighbor_pairs(const floe_world *w, const int **pi, const int **pj) {
    if (!w) return -FLOE_EINVAL;
    if (pi) *pi = w->nl.pi;
    if (pj) *pj = w->nl.pj;
    return w->nl.npairs;
}

int floe_world_is_prepared(const floe_world *w) { return w && w->prepared; }

int floe_world_material_count(const floe_world *w) { return w ? w->nmats : 0; }

const floe_material *floe_world_material_at(const floe_world *w, int k) {
    return w && k >= 0 && k < w->nmats ? &w->mats[k] : NULL;
}

const floe_contact_law *floe_world_law(const floe_world *w, int a, int b) {
    if (!w || !w->laws || a < 0 || b < 0 || a >= w->nmats || b >= w->nmats) return NULL;
    return w->laws[a * w->nmats + b];
}

int floe_world_admm_options(const floe_world *w, floe_admm_options *o) {
    if (!w || !o) return FLOE_EINVAL;
    *o = w->det.admm;
    return FLOE_OK;
}

int floe_world_memory(const floe_world *w, floe_memory_stats *o) {
    if (!w || !o) return FLOE_EINVAL;
    const floe_particles *p = &w->p;
    const floe_neighbor_list *nl = &w->nl;
    /* per particle: x v w L f t inertia (3 doubles each), q (4), mass inv_mass inv_iso radius
     * rdot, geom material group pieces (int), motion kind iso (byte); the store's block adds
     * under a page per array (world.c particles_reserve) */
    const size_t per_particle = (7 * 3 + 4 + 5) * sizeof(double) + 4 * sizeof(int) + 3;
    /* per pair: pi pj sub, history, touching, warm starts when in use */
    const size_t per_pair = 3 * sizeof(int) + (size_t)nl->hs * sizeof(double) + 1 +
                            (nl->use_warm ? FLOE_DETECT_WARM * sizeof(double) : 0);
    o->particle_capacity = p->cap;
    o->pair_capacity = nl->cap;
    o->contact_capacity = w->contacts_cap;
    o->particles = (size_t)p->cap * per_particle + (p->block ? 20 * 4096 : 0) +
                   (p->thick ? (size_t)p->cap * sizeof(double) : 0);
    o->neighbor_list = (size_t)nl->cap * per_pair + (size_t)nl->n_build * 4 * sizeof(double) +
                       (size_t)nl->nwalls * (sizeof(int) + 4 * sizeof(double));
    /* threads: the contact stage's per-entry forces, flags and the particles' entry lists
     * (forces.c par_prepare), once the list is large enough to be threaded */
    if (floe_world_loop_threads(w, nl->cap) > 1)
        o->neighbor_list += (size_t)nl->cap * (9 * sizeof(double) + 1 + sizeof(int)) +
                            (size_t)p->cap * (2 * sizeof(int) + 1);
    o->contacts = (size_t)w->contacts_cap * sizeof(floe_contact_info);
    if (w->sep_d) /* the separation cache */
        o->neighbor_list += (size_t)w->sep_n * (9 * sizeof(double) + sizeof(int)) + (size_t)w->sep_np * 2 * sizeof(double);
    return FLOE_OK;
}

static int probe_ok(const floe_world *w, int i, int j, const floe_contact *c) {
    return w && c && i >= 0 && j >= 0 && i < w->p.n && j < w->p.n && i != j;
}

int floe_world_probe_contact(floe_world *w, int i, int j, int sub, floe_contact *c) {
    if (!probe_ok(w, i, j, c)) return -FLOE_EINVAL;
    return floe_world_detect(w, i, j, sub, NULL, c);
}

int floe_world_probe_overlap(floe_world *w, int i, int j, int sub, floe_contact *c) {
    if (!probe_ok(w, i, j, c)) return -FLOE_EINVAL;
    return floe_world_detect_overlap(w, i, j, sub, c);
}

int floe_world_adaptive_bounds(const floe_world *w, double *lo, double *hi) {
    if (!w) return FLOE_EINVAL;
    const int on = w->def.adaptive;
    if (lo) *lo = on ? w->dt_lo : 0;
    if (hi) *hi = on ? w->dt_hi : 0;
    return FLOE_OK;
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
