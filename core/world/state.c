/* state.c - built-in state objects (ParticLS §4.1, §5.2): the growing sphere radius,
 * dR/dt = rate, and a generic scalar ODE. Both are advanced by the world's RK2 (eq 21). */
#include "world_internal.h"
#include <stdlib.h>

typedef struct growing_radius {
    floe_state base;
    int particle; /* the world's index at creation: the global id on a split world */
    int geom;     /* its own sphere (the same index on every rank of a split world) */
    double rate;
    int update_mass;
    double R0;
    /* the local index of the particle on a split world, found again after each rebuild */
    long cached_rebuilds;
    const long long *cached_gid;
    int cached_local;
    /* what gr_probe changed and puts back: the sphere's radius, the particle's local index
     * (-1: none on this rank), its radius, mass and inverse mass */
    double probe_saved[4];
    int probe_local;
} growing_radius;

static size_t gr_size(const floe_state *s) { (void)s; return 1; }
static void gr_get_w(const floe_state *s, const floe_world *w, double *y);

static floe_sphere *gr_sphere(const floe_world *w, int i) {
    return (floe_sphere *)w->geoms[w->p.geom[i]];
}

/* The particle's local index: itself in one process; on a world split over MPI ranks
 * (docs/parallel.md: every rank keeps every state object and advances it alike) the wall,
 * owned or ghost copy of it on this rank, -1 where the rank holds none. The local indices
 * change only at a rebuild: the search (binary over the owned range, sorted by global id;
 * linear over the ghosts) runs once after each. */
static int gr_local(growing_radius *g, const floe_world *w) {
    const floe_neighbor_list *nl = &w->nl;
    if (!nl->gid) return floe_world_local_of(w, g->particle, 0);
    if (g->cached_gid == nl->gid && g->cached_rebuilds == nl->rebuilds) return g->cached_local;
    g->cached_gid = nl->gid;
    g->cached_rebuilds = nl->rebuilds;
    g->cached_local = floe_world_local_of(w, g->particle, 1);
    return g->cached_local;
}

/* The radius lives in the particle's own sphere geometry; get() needs the world, so the
 * state keeps a pointer to it in a wrapper. */
typedef struct growing_radius_w {
    growing_radius g;
    floe_world *w;
} growing_radius_w;

static void gr_get_w(const floe_state *s, const floe_world *w, double *y) {
    const growing_radius *g = (const growing_radius *)s;
    y[0] = ((const floe_sphere *)w->geoms[g->geom])->radius;
}

static void gr_get_real(const floe_state *s, double *y) {
    const growing_radius_w *g = (const growing_radius_w *)s;
    gr_get_w(s, g->w, y);
}

static int gr_set(floe_state *s, floe_world *w, const double *y) {
    growing_radius *g = (growing_radius *)s;
    if (!(y[0] > 0) || !isfinite(y[0]))
        return floe_world_error(w, FLOE_EUNSTABLE, "growing radius of particle %d became %g", g->particle, y[0]);
    floe_sphere *sp = (floe_sphere *)w->geoms[g->geom];
    double r_old = sp->radius;
    sp->radius = y[0];
    const int i = gr_local(g, w);
    if (i < 0) return FLOE_OK; /* a split world: not on this rank (its geometry is) */
    w->p.radius[i] = y[0];
    w->p.rdot[i] = g->rate; /* for the energy ledger: growth does work */
    if (g->update_mass && w->prepared) {
        double r = y[0] / r_old, s = w->def.dim == 2 && w->def.mass_2d_area ? r * r : r * r * r;
        double m = w->p.mass[i] * s;
        double scale = s * r * r; /* inertia ~ m R^2 */
        /* the grown particle keeps its velocity and angular velocity (the added mass moves
         * with it): momentum and angular momentum grow with the mass, and the kinetic
         * energy this adds is booked as boundary work so that the ledger still closes */
        const double *v = w->p.v + 3 * i, *om = w->p.w + 3 * i;
        double *L = w->p.L + 3 * i;
        double ke_t = 0.5 * (m - w->p.mass[i]) * floe_v3_dot(v, v);
        double ke_r = 0.5 * (scale - 1) * floe_v3_dot(L, om);
        w->p.mass[i] = m;
        /* a ghost (split world) is FLOE_FIXED here: its owner's motion decides */
        const int own = !w->nl.gid || i < w->nl.own_hi;
        const int free_ = (own ? w->p.motion[i] : w->gmotion[i - w->nl.own_hi]) == FLOE_FREE;
        if (free_) w->p.inv_mass[i] = 1.0 / m;
        for (int k = 0; k < 3; k++) {
            w->p.inertia[3 * i + k] *= scale;
            L[k] *= scale;
        }
        floe_particle_inv_iso_update(&w->p, i);
        if (free_ && own) w->energy.work_boundary += ke_t + ke_r; /* the owner books the work */
    }
    return FLOE_OK;
}

/* The RK2 midpoint's radius (and, with update_mass, mass) for its force evaluation: the
 * contact sees the sphere it touches then (floe_state_class.probe) */
static int gr_probe(floe_state *s, floe_world *w, const double *y) {
    growing_radius *g = (growing_radius *)s;
    floe_sphere *sp = (floe_sphere *)w->geoms[g->geom];
    floe_particles *p = &w->p;
    if (!y) { /* put back */
        sp->radius = g->probe_saved[0];
        const int i = g->probe_local;
        if (i >= 0) {
            p->radius[i] = g->probe_saved[1];
            p->mass[i] = g->probe_saved[2];
            p->inv_mass[i] = g->probe_saved[3];
        }
        return FLOE_OK;
    }
    if (!(y[0] > 0) || !isfinite(y[0]))
        return floe_world_error(w, FLOE_EUNSTABLE, "growing radius of particle %d became %g", g->particle, y[0]);
    const int i = gr_local(g, w);
    g->probe_saved[0] = sp->radius;
    g->probe_local = i;
    const double r = y[0] / sp->radius;
    sp->radius = y[0];
    if (i < 0) return FLOE_OK;
    g->probe_saved[1] = p->radius[i];
    g->probe_saved[2] = p->mass[i];
    g->probe_saved[3] = p->inv_mass[i];
    p->radius[i] = y[0];
    if (g->update_mass && w->prepared) {
        const double m = p->mass[i] * (w->def.dim == 2 && w->def.mass_2d_area ? r * r : r * r * r);
        p->mass[i] = m;
        if (p->inv_mass[i] > 0) p->inv_mass[i] = 1.0 / m; /* a free particle or its ghost (as gr_set) */
    }
    return FLOE_OK;
}

static int gr_rhs(const floe_state *s, const floe_world *w, double t, const double *y, double *dydt) {
    (void)w; (void)t; (void)y;
    dydt[0] = ((const growing_radius *)s)->rate;
    return FLOE_OK;
}

static const floe_state_class growing_radius_class = {2, "growing_radius", gr_size, gr_get_real, gr_set, gr_rhs, NULL,
                                                      gr_probe};

floe_state *floe_growing_radius_create(floe_world *w, int particle, double rate, int update_mass) {
    if (particle < 0 || particle >= w->p.n || !isfinite(rate)) return NULL;
    if (w->geoms[w->p.geom[particle]]->klass != &floe_sphere_class) {
        floe_world_error(w, FLOE_EINVAL, "growing radius: particle %d is not a sphere", particle);
        return NULL;
    }
    /* give the particle its own sphere so that the others sharing the geometry keep theirs */
    floe_geometry *own = floe_sphere_create(gr_sphere(w, particle)->radius);
    int gi = floe_world_add_geometry(w, own);
    if (gi < 0) { floe_geometry_destroy(own); return NULL; }
    w->p.geom[particle] = gi;
    growing_radius_w *g = calloc(1, sizeof *g);
    if (!g) return NULL;
    g->g.base.klass = &growing_radius_class;
    g->g.particle = particle;
    g->g.geom = gi;
    g->g.cached_local = -1;
    g->g.rate = rate;
    g->g.update_mass = update_mass;
    g->g.R0 = ((floe_sphere *)own)->radius;
    g->w = w;
    return &g->g.base;
}

/* ---- generic scalar ODE ---- */
typedef struct scalar_state {
    floe_state base;
    double y;
    floe_scalar_rhs_fn f;
    void *user;
} scalar_state;

static size_t sc_size(const floe_state *s) { (void)s; return 1; }
static void sc_get(const floe_state *s, double *y) { y[0] = ((const scalar_state *)s)->y; }
static int sc_set(floe_state *s, floe_world *w, const double *y) {
    (void)w;
    ((scalar_state *)s)->y = y[0];
    return FLOE_OK;
}
static int sc_rhs(const floe_state *s, const floe_world *w, double t, const double *y, double *dydt) {
    (void)w;
    const scalar_state *c = (const scalar_state *)s;
    dydt[0] = c->f(t, y[0], c->user);
    return isfinite(dydt[0]) ? FLOE_OK : FLOE_EUNSTABLE;
}
static const floe_state_class scalar_state_class = {1, "scalar", sc_size, sc_get, sc_set, sc_rhs, NULL, NULL};

floe_state *floe_scalar_state_create(double y0, floe_scalar_rhs_fn f, void *user) {
    if (!f) return NULL;
    scalar_state *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->base.klass = &scalar_state_class;
    s->y = y0; s->f = f; s->user = user;
    return &s->base;
}

double floe_scalar_state_value(const floe_state *s) { return ((const scalar_state *)s)->y; }

int floe_state_splits(const floe_state *s) {
    return s->klass == &growing_radius_class || s->klass == &scalar_state_class;
}
