/* world.c - the simulation world: particle store, registration of materials, laws,
 * geometries, particles, walls, states and observers; preparation (mass properties,
 * time-step estimate) and the time step: velocity Verlet for rigid bodies (ParticLS
 * eqs 22-23), RK2 for generic state objects (eq 21), observers at their periods. */
#include "world_internal.h"
#include "floe_pd.h"
#include "beam_set.h"
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *floe_strerror(int code) {
    switch (code) {
    case FLOE_OK: return "FLOE_OK";
    case FLOE_EINVAL: return "FLOE_EINVAL";
    case FLOE_ENOMEM: return "FLOE_ENOMEM";
    case FLOE_EIO: return "FLOE_EIO";
    case FLOE_EPARSE: return "FLOE_EPARSE";
    case FLOE_EUNSTABLE: return "FLOE_EUNSTABLE";
    case FLOE_ENOTSUP: return "FLOE_ENOTSUP";
    case FLOE_ESTOP: return "FLOE_ESTOP";
    default: return "FLOE_E?";
    }
}

int floe_world_error(floe_world *w, int code, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(w->err, sizeof w->err, fmt, ap);
    va_end(ap);
    return code;
}

const char *floe_world_last_error(const floe_world *w) { return w->err; }

floe_world_def floe_default_world_def(void) {
    floe_world_def d;
    memset(&d, 0, sizeof d);
    d.dim = 3;
    d.dt = 0;
    d.dt_safety = 0.2;
    d.leaf_size = 16;
    d.integrator = FLOE_VELOCITY_VERLET;
    d.adapt_velocity_tol = 1e-3;
    d.adapt_depth_tol = 1e-3;
    d.pd_dem = FLOE_PD_DEM_MONOLITHIC;
    d.pd_substeps = 1;
    d.pd_every = 1;
    d.energy_check = FLOE_CHECK_STOP;
    d.energy_check_tol = 0.05;
    return d;
}

floe_particle_def floe_default_particle_def(void) {
    floe_particle_def d;
    memset(&d, 0, sizeof d);
    d.q[0] = 1;
    d.motion = FLOE_FREE;
    return d;
}

typedef struct floe_snapshot floe_snapshot;
static void snapshot_free(floe_snapshot *s);

/* grow an array of n elements of size sz to hold at least need */
static int grow(void **ptr, int *cap, int need, size_t sz) {
    if (need <= *cap) return FLOE_OK;
    int nc = *cap ? *cap : 8;
    while (nc < need) nc *= 2;
    void *np = realloc(*ptr, (size_t)nc * sz);
    if (!np) return FLOE_ENOMEM;
    *ptr = np;
    *cap = nc;
    return FLOE_OK;
}

floe_world *floe_world_create(const floe_world_def *def, char *err, size_t errlen) {
    const char *bad = NULL;
    if (def->dim != 2 && def->dim != 3) bad = "dim must be 2 or 3";
    else if (!(def->dt >= 0) || !isfinite(def->dt)) bad = "dt must be >= 0 (0 = automatic)";
    else if (!(def->dt_safety > 0 && def->dt_safety <= 1)) bad = "dt_safety must be in (0, 1]";
    else if (!(def->skin >= 0) || !isfinite(def->skin)) bad = "skin must be >= 0";
    else if (!isfinite(def->gravity[0] + def->gravity[1] + def->gravity[2])) bad = "gravity must be finite";
    else if (!floe_energy_check_name(def->energy_check)) bad = "energy_check must be stop, warn or off";
    else if (!(def->energy_check_tol >= 0 && def->energy_check_tol < 1)) bad = "energy_check_tol must be in [0, 1)";
    else if (!(def->accuracy >= 0 && def->accuracy < 1)) bad = "accuracy must be in [0, 1) (0 = off)";
    if (bad) {
        if (err && errlen) snprintf(err, errlen, "invalid world definition: %s", bad);
        return NULL;
    }
    floe_world *w = calloc(1, sizeof *w);
    if (!w) {
        if (err && errlen) snprintf(err, errlen, "out of memory");
        return NULL;
    }
    w->def = *def;
    if (w->def.leaf_size <= 0) w->def.leaf_size = 16;
    floe_nl_init(&w->nl);
    w->nl.skin = def->skin;
    floe_admm_default_options(&w->det.admm);
    w->dt_cap = INFINITY;
    if (!(w->def.energy_check_tol > 0)) w->def.energy_check_tol = 0.05;
    w->wd_step = -1;
    return w;
}

static void particles_free(floe_particles *p) {
    free(p->x); free(p->v); free(p->q); free(p->w); free(p->L); free(p->f); free(p->t);
    free(p->mass); free(p->inv_mass); free(p->inertia); free(p->radius); free(p->geom);
    free(p->material); free(p->group); free(p->motion); free(p->kind); free(p->iso); free(p->rdot);
    free(p->pieces);
}

void floe_world_destroy(floe_world *w) {
    if (!w) return;
    particles_free(&w->p);
    for (int i = 0; i < w->ngeoms; i++) floe_geometry_destroy(w->geoms[i]);
    free(w->geoms);
    free(w->mats);
    for (int i = 0; i < w->nlaws_owned; i++) floe_contact_law_destroy(w->law_owned[i]);
    free(w->law_owned);
    free(w->laws);
    free(w->motions);
    free(w->motion_idx);
    free(w->fb_old);
    free(w->kin_old);
    for (int i = 0; i < w->nstates; i++) {
        if (w->states[i]->klass->destroy) w->states[i]->klass->destroy(w->states[i]);
        else free(w->states[i]);
    }
    free(w->states);
    for (int i = 0; i < w->nobs; i++) floe_observer_destroy(w->obs[i]);
    free(w->obs);
    floe_nl_free(&w->nl);
    free(w->contacts);
    free(w->det.scratch);
    free(w->dt_part);
    free(w->ibuf);
    snapshot_free(w->snap);
    for (int k = 0; k < w->npd; k++) floe_pd_body_destroy(w->pd[k]);
    free(w->pd); free(w->pd_first); free(w->pd_of); free(w->pd_fold); free(w->pd_fnew); free(w->pd_eold); free(w->pd_diss);
    for (int k = 0; k < w->npd_bc; k++) { free(w->pd_bc[k]->pts); free(w->pd_bc[k]->fold); free(w->pd_bc[k]); }
    free(w->pd_bc); free(w->pd_nbroken_seen);
    floe_beam_set_destroy(w->beams);
    free(w);
}

int floe_world_add_material(floe_world *w, const floe_material *m) {
    if (!(m->density > 0) || !isfinite(m->density))
        return -floe_world_error(w, FLOE_EINVAL, "material '%s': density must be > 0 (got %g)", m->name, m->density);
    if (!(m->young > 0) || !isfinite(m->young))
        return -floe_world_error(w, FLOE_EINVAL, "material '%s': young must be > 0 (got %g)", m->name, m->young);
    if (!(m->poisson > -1 && m->poisson < 0.5))
        return -floe_world_error(w, FLOE_EINVAL, "material '%s': poisson must be in (-1, 0.5) (got %g)", m->name, m->poisson);
    int old = w->nmats;
    if (grow((void **)&w->mats, &w->mats_cap, old + 1, sizeof *w->mats)) return -FLOE_ENOMEM;
    floe_contact_law **nl = calloc((size_t)(old + 1) * (old + 1), sizeof *nl);
    if (!nl) return -FLOE_ENOMEM;
    for (int a = 0; a < old; a++)
        for (int b = 0; b < old; b++) nl[a * (old + 1) + b] = w->laws[a * old + b];
    free(w->laws);
    w->laws = nl;
    w->mats[old] = *m;
    w->nmats = old + 1;
    return old;
}

int floe_world_set_law(floe_world *w, int a, int b, floe_contact_law *law) {
    if (!law) return floe_world_error(w, FLOE_EINVAL, "contact law is NULL (invalid parameters?)");
    if (a < 0 || b < 0 || a >= w->nmats || b >= w->nmats) {
        floe_contact_law_destroy(law);
        return floe_world_error(w, FLOE_EINVAL, "set_law: material index out of range");
    }
    if (grow((void **)&w->law_owned, &w->law_owned_cap, w->nlaws_owned + 1, sizeof *w->law_owned)) {
        floe_contact_law_destroy(law);
        return FLOE_ENOMEM;
    }
    w->law_owned[w->nlaws_owned++] = law;
    w->laws[a * w->nmats + b] = law;
    w->laws[b * w->nmats + a] = law;
    return FLOE_OK;
}

int floe_world_add_geometry(floe_world *w, floe_geometry *g) {
    if (!g) return -floe_world_error(w, FLOE_EINVAL, "geometry is NULL (invalid shape parameters?)");
    if (!g->klass || !g->klass->sdf || !g->klass->bounding_radius)
        return -floe_world_error(w, FLOE_EINVAL, "geometry class must provide sdf and bounding_radius");
    char gerr[400] = "";
    int grc = floe_geometry_check(g, gerr, sizeof gerr); /* a user SDF's Lipschitz bound */
    if (grc) return -floe_world_error(w, grc, "%s", gerr); /* the caller keeps g, as on every failure */
    if (grow((void **)&w->geoms, &w->geoms_cap, w->ngeoms + 1, sizeof *w->geoms)) return -FLOE_ENOMEM;
    w->geoms[w->ngeoms] = g;
    return w->ngeoms++;
}

static int particles_reserve(floe_particles *p, int need) {
    if (need <= p->cap) return FLOE_OK;
    int nc = p->cap ? p->cap : 64;
    while (nc < need) nc *= 2;
#define RE(field, k) do { void *t_ = realloc(p->field, (size_t)nc * (k) * sizeof *p->field); if (!t_) return FLOE_ENOMEM; p->field = t_; } while (0)
    RE(x, 3); RE(v, 3); RE(q, 4); RE(w, 3); RE(L, 3); RE(f, 3); RE(t, 3);
    RE(mass, 1); RE(inv_mass, 1); RE(inertia, 3); RE(radius, 1); RE(geom, 1);
    RE(material, 1); RE(group, 1); RE(motion, 1); RE(kind, 1); RE(iso, 1); RE(rdot, 1); RE(pieces, 1);
#undef RE
    p->cap = nc;
    return FLOE_OK;
}

int floe_world_add_particle(floe_world *w, const floe_particle_def *d) {
    if (d->geometry < 0 || d->geometry >= w->ngeoms)
        return -floe_world_error(w, FLOE_EINVAL, "particle: geometry index %d out of range", d->geometry);
    if (d->material < 0 || d->material >= w->nmats)
        return -floe_world_error(w, FLOE_EINVAL, "particle: material index %d out of range", d->material);
    for (int k = 0; k < 3; k++)
        if (!isfinite(d->x[k]) || !isfinite(d->v[k]) || !isfinite(d->w[k]))
            return -floe_world_error(w, FLOE_EINVAL, "particle: position, velocity and angular velocity must be finite");
    double qn = sqrt(d->q[0] * d->q[0] + d->q[1] * d->q[1] + d->q[2] * d->q[2] + d->q[3] * d->q[3]);
    if (!(qn > 0) || !isfinite(qn)) return -floe_world_error(w, FLOE_EINVAL, "particle: orientation quaternion must be non-zero");
    if (d->mass < 0 || !isfinite(d->mass)) return -floe_world_error(w, FLOE_EINVAL, "particle: mass must be >= 0 (0 = from density)");
    floe_particles *p = &w->p;
    if (particles_reserve(p, p->n + 1)) return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    int i = p->n++;
    const floe_geometry *g = w->geoms[d->geometry];
    memcpy(p->x + 3 * i, d->x, sizeof d->x);
    memcpy(p->v + 3 * i, d->v, sizeof d->v);
    memcpy(p->w + 3 * i, d->w, sizeof d->w);
    for (int k = 0; k < 4; k++) p->q[4 * i + k] = d->q[k] / qn;
    if (w->def.dim == 2) { p->x[3 * i + 2] = 0; p->v[3 * i + 2] = 0; p->w[3 * i] = p->w[3 * i + 1] = 0; }
    memset(p->L + 3 * i, 0, 3 * sizeof(double));
    memset(p->f + 3 * i, 0, 3 * sizeof(double));
    memset(p->t + 3 * i, 0, 3 * sizeof(double));
    p->geom[i] = d->geometry;
    p->material[i] = d->material;
    p->group[i] = d->group;
    p->motion[i] = (unsigned char)d->motion;
    p->kind[i] = (unsigned char)g->klass->kind;
    p->iso[i] = 0;
    p->rdot[i] = 0;
    p->pieces[i] = floe_piece_count(g);
    p->radius[i] = floe_geometry_bounding_radius(g);
    p->mass[i] = d->mass; /* resolved at prepare */
    w->prepared = 0;
    return i;
}

int floe_world_add_wall(floe_world *w, const double pt[3], const double n[3], int material, floe_motion motion) {
    double nn = floe_v3_norm(n);
    if (!(nn > 0) || !isfinite(nn)) return -floe_world_error(w, FLOE_EINVAL, "wall: normal must be non-zero");
    if (motion == FLOE_FREE) return -floe_world_error(w, FLOE_EINVAL, "wall: motion must be fixed or kinematic");
    int g = floe_world_add_geometry(w, floe_plane_create());
    if (g < 0) return g;
    floe_particle_def d = floe_default_particle_def();
    d.geometry = g;
    d.material = material;
    d.motion = motion;
    d.group = -1;
    memcpy(d.x, pt, sizeof d.x);
    /* quaternion rotating +z onto n */
    double u[3] = {n[0] / nn, n[1] / nn, n[2] / nn};
    double c = u[2];
    if (c < -1 + 1e-15) { d.q[0] = 0; d.q[1] = 1; d.q[2] = 0; d.q[3] = 0; }
    else {
        double ax[3] = {-u[1], u[0], 0}; /* z x u */
        d.q[0] = 1 + c; d.q[1] = ax[0]; d.q[2] = ax[1]; d.q[3] = ax[2];
    }
    int i = floe_world_add_particle(w, &d);
    if (i >= 0 && w->def.dim == 2) w->p.x[3 * i + 2] = pt[2];
    return i;
}

int floe_world_set_motion(floe_world *w, int i, floe_motion_fn fn, void *user) {
    if (i < 0 || i >= w->p.n) return floe_world_error(w, FLOE_EINVAL, "set_motion: particle %d out of range", i);
    if (!fn) return floe_world_error(w, FLOE_EINVAL, "set_motion: the motion function is NULL");
    if (grow((void **)&w->motions, &w->motions_cap, w->nmotions + 1, sizeof *w->motions)) return FLOE_ENOMEM;
    w->motions[w->nmotions++] = (floe_motion_cb){i, fn, user};
    w->p.motion[i] = FLOE_KINEMATIC;
    w->p.inv_mass[i] = 0;   /* no longer moved by forces (also when called after prepare) */
    w->prepared = 0;
    return FLOE_OK;
}

int floe_world_set_body_force(floe_world *w, floe_body_force_fn fn, void *user) {
    w->body_force = fn;
    w->body_force_user = user;
    w->prepared = 0;   /* prepare sizes the per-particle callback force (adaptive snapshots) */
    return FLOE_OK;
}

int floe_world_add_state(floe_world *w, floe_state *s) {
    if (!s) return floe_world_error(w, FLOE_EINVAL, "state object is NULL");
    if (grow((void **)&w->states, &w->states_cap, w->nstates + 1, sizeof *w->states)) return FLOE_ENOMEM;
    w->states[w->nstates++] = s;
    return FLOE_OK;
}

int floe_world_record_contacts(floe_world *w, int on) {
    w->record_contacts = on != 0;
    return FLOE_OK;
}

int floe_world_contact_count(const floe_world *w) { return w->ncontacts; }

int floe_world_add_observer(floe_world *w, floe_observer *o) {
    if (!o) return floe_world_error(w, FLOE_EINVAL, "observer is NULL");
    if (o->klass->needs_contacts) w->obs_need_contacts = 1;
    if (grow((void **)&w->obs, &w->obs_cap, w->nobs + 1, sizeof *w->obs)) return FLOE_ENOMEM;
    w->obs[w->nobs++] = o;
    return FLOE_OK;
}

/* ---- peridynamic bodies ---- */

/* Contact exclusion of two points of the same PD body. An unbonded pair (beyond the
 * horizon, or across a pre-crack: floe_pd_add_crack removes those bonds) meets by contact
 * unless its contact spheres overlap in the reference configuration, as a broken pair
 * below (only a pre-crack makes such pairs on a lattice). A bonded pair gets no contact while
 * its bond is intact (the bond is the interaction), nor when it is broken but still acts
 * (a PMB bond with broken_tension_only pushes in compression, 003 eq 2 mu = 1). Other broken
 * pairs meet by contact, except those whose contact spheres already overlap in the
 * reference configuration (|xi| < R_i + R_j: the nearest lattice neighbours at 1 dx, with
 * R = 0.62 dx): a contact there would push the faces of a fresh crack apart at once with
 * the force of a 0.24 dx overlap. Across a crack the next pairs (sqrt 2 dx) are in contact
 * range, so closing cracks still resist. */
static int pd_exclude(const void *ctx, int i, int j) {
    const floe_world *w = ctx;
    int bi = w->pd_of[i];
    if (bi < 0 || bi != w->pd_of[j]) return 0;
    int f = w->pd_first[bi];
    const floe_pd_body *b = w->pd[bi];
    int64_t k = floe_pd_bond_index(b, i - f, j - f);
    if (k < 0) { /* not bonded (a pre-crack's faces, floe_pd_add_crack): as a broken pair */
        double d[3];
        floe_v3_sub(d, b->X + 3 * (size_t)(j - f), b->X + 3 * (size_t)(i - f));
        return floe_v3_norm(d) < w->p.radius[i] + w->p.radius[j];
    }
    if (!b->broken[k]) return 1;
    if (b->mat.model == FLOE_PD_PMB && b->mat.broken_tension_only) return 1;
    return b->len[k] < w->p.radius[i] + w->p.radius[j];
}

/* the pairs that never enter the contact list: bonded PD family members (pd_exclude) and
 * particles held by an intact beam bond */
static int world_exclude(const void *ctx, int i, int j) {
    const floe_world *w = ctx;
    if (w->npd && pd_exclude(w, i, j)) return 1;
    return w->beams && floe_beam_set_excludes(w->beams, i, j);
}

void floe_world_install_exclusion(floe_world *w) {
    w->nl.exclude = world_exclude;
    w->nl.exclude_ctx = w;
}

/* 1 when broken pairs of body b can meet by contact (pd_exclude) */
static int pd_broken_pairs_touch(const floe_pd_body *b) {
    return !(b->mat.model == FLOE_PD_PMB && b->mat.broken_tension_only);
}

/* 1 when the neighbour list holds the pair (i, j), i < j (sorted by (i, j): a binary
 * search; if the list were not sorted this only ever answers 0, i.e. rebuild) */
static int nl_has_pair(const floe_neighbor_list *nl, int i, int j) {
    int lo = 0, hi = nl->npairs;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (nl->pi[mid] < i || (nl->pi[mid] == i && nl->pj[mid] < j)) lo = mid + 1;
        else hi = mid;
    }
    return lo < nl->npairs && nl->pi[lo] == i && nl->pj[lo] == j;
}

int floe_pd_after_forces(floe_world *w) {
    /* bonds broke this evaluation: a broken pair that may now touch (pd_exclude) and is
     * within reach (R_i + R_j + skin) must be in the list before it can touch; the Verlet
     * criterion does not see it (nothing moved), so rebuild now. Only bodies whose broken
     * pairs can touch are scanned, and only at evaluations where their count changed. */
    int rebuild = 0;
    const floe_particles *p = &w->p;
    for (int b = 0; b < w->npd; b++) {
        floe_pd_body *pb = w->pd[b];
        if ((long long)pb->nbroken == w->pd_nbroken_seen[b]) continue;
        w->pd_nbroken_seen[b] = (long long)pb->nbroken;
        if (rebuild || !pd_broken_pairs_touch(pb)) continue;
        int f0 = w->pd_first[b];
        double skin = w->nl.skin;
        for (int i = 0; i < pb->n && !rebuild; i++)
            for (int64_t k = pb->off[i]; k < pb->off[i + 1]; k++) {
                if (!pb->broken[k]) continue;
                int a = f0 + i, c = f0 + pb->partner[k];
                double rr = p->radius[a] + p->radius[c];
                if (pb->len[k] < rr) continue; /* excluded (overlap in the reference) */
                if (p->motion[a] != FLOE_FREE && p->motion[c] != FLOE_FREE) continue;
                double d[3];
                floe_v3_sub(d, p->x + 3 * c, p->x + 3 * a);
                if (floe_v3_dot(d, d) > (rr + skin) * (rr + skin)) continue;
                if (!nl_has_pair(&w->nl, a, c)) { rebuild = 1; break; }
            }
    }
    if (!rebuild) return FLOE_OK;
    int rc = floe_nl_build(&w->nl, p, w->def.dim, w->def.leaf_size);
    return rc ? floe_world_error(w, rc, "neighbour list rebuild after bond breakage failed (out of memory)") : FLOE_OK;
}

/* the contact radius of a point of volume V */
static double pd_contact_radius(const floe_pd_body *b, double V) {
    return b->dim == 3 ? cbrt(3.0 * V / (4.0 * M_PI)) : sqrt(V / (M_PI * b->thickness));
}

int floe_world_add_pd_body(floe_world *w, struct floe_pd_body *body, int material, const double v0[3], int *first) {
    if (!body) return floe_world_error(w, FLOE_EINVAL, "PD body: NULL");
    if (material < 0 || material >= w->nmats) {
        floe_pd_body_destroy(body);
        return floe_world_error(w, FLOE_EINVAL, "PD body: contact material index %d out of range", material);
    }
    if (!body->ops || body->n < 1 || body->dim != w->def.dim) {
        int bd = body->dim;
        floe_pd_body_destroy(body);
        return floe_world_error(w, FLOE_EINVAL, "PD body: %s", bd != w->def.dim ? "its dimension differs from the world's"
                                                                                 : "no points or no material set");
    }
    if (v0 && !(isfinite(v0[0]) && isfinite(v0[1]) && isfinite(v0[2]))) {
        floe_pd_body_destroy(body);
        return floe_world_error(w, FLOE_EINVAL, "PD body: the initial velocity must be finite");
    }
    if (w->npd == w->pd_cap) {
        int nc = w->pd_cap ? 2 * w->pd_cap : 4;
        struct floe_pd_body **a = realloc(w->pd, (size_t)nc * sizeof *a);
        if (a) w->pd = a;
        int *b = a ? realloc(w->pd_first, (size_t)nc * sizeof *b) : NULL;
        if (b) w->pd_first = b;
        long long *s = b ? realloc(w->pd_nbroken_seen, (size_t)nc * sizeof *s) : NULL;
        if (s) w->pd_nbroken_seen = s;
        if (!a || !b || !s) { floe_pd_body_destroy(body); return floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
        w->pd_cap = nc;
    }
    /* on any failure below, the particles and geometries added so far are removed again:
     * a failed add leaves the world as it was */
    const int ng0 = w->ngeoms, n0 = w->p.n, prepared0 = w->prepared;
    int rc = FLOE_OK, r;
    /* one sphere geometry per point volume (lattice bodies: one) */
    double Vg = 0;
    int gi = -1;
    for (int i = 0; i < body->n && rc == FLOE_OK; i++) {
        if (gi < 0 || body->V[i] != Vg) {
            Vg = body->V[i];
            double R = pd_contact_radius(body, Vg);
            floe_geometry *g = floe_sphere_create(R);
            gi = g ? floe_world_add_geometry(w, g) : -FLOE_ENOMEM;
            if (gi < 0) {
                floe_geometry_destroy(g);
                if (isfinite(R) && R > 0) rc = floe_world_error(w, FLOE_ENOMEM, "out of memory");
                else rc = floe_world_error(w, FLOE_EINVAL, "PD body: point %d: volume %g gives no contact radius", i, Vg);
                break;
            }
        }
        floe_particle_def d = floe_default_particle_def();
        d.geometry = gi;
        d.material = material;
        floe_v3_copy(d.x, body->X + 3 * i);
        if (v0) floe_v3_copy(d.v, v0);
        d.mass = body->mat.rho * body->V[i];
        d.group = -2 - w->npd; /* PD body k writes body = -2 - k in outputs */
        if ((r = floe_world_add_particle(w, &d)) < 0) {
            char why[sizeof w->err];
            memcpy(why, w->err, sizeof why);
            rc = floe_world_error(w, -r, "PD body: point %d: %s", i, why);
        }
    }
    /* body index of every particle (allocated with the first PD body) */
    int *po = NULL;
    if (rc == FLOE_OK) {
        po = realloc(w->pd_of, (size_t)(w->p.cap > 0 ? w->p.cap : 1) * sizeof *po);
        if (po) w->pd_of = po;
        else rc = floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    if (rc != FLOE_OK) {
        for (int g = ng0; g < w->ngeoms; g++) floe_geometry_destroy(w->geoms[g]);
        w->ngeoms = ng0;
        w->p.n = n0;
        w->prepared = prepared0;
        floe_pd_body_destroy(body);
        return rc;
    }
    for (int i = w->npd ? w->pd_npts_alloc : 0; i < n0; i++) po[i] = -1;
    for (int i = n0; i < w->p.n; i++) po[i] = w->npd;
    w->pd_npts_alloc = w->p.n;
    w->pd[w->npd] = body;
    w->pd_first[w->npd] = n0;
    w->pd_nbroken_seen[w->npd] = (long long)body->nbroken;
    w->npd++;
    w->pd_npts += body->n;
    floe_world_install_exclusion(w);
    if (first) *first = n0;
    w->prepared = 0;
    return FLOE_OK;
}

int floe_world_pd_body_count(const floe_world *w) { return w->npd; }
struct floe_pd_body *floe_world_pd_body(const floe_world *w, int k, int *first) {
    if (k < 0 || k >= w->npd) return NULL;
    if (first) *first = w->pd_first[k];
    return w->pd[k];
}

/* ---- PD boundary regions (ParticLS eq 37) ---- */

floe_pd_bc floe_default_pd_bc(void) {
    floe_pd_bc bc;
    memset(&bc, 0, sizeof bc);
    return bc;
}

int floe_world_pd_region_count(const floe_world *w) { return w->npd_bc; }
int floe_world_pd_region_points(const floe_world *w, int r) {
    return r >= 0 && r < w->npd_bc ? w->pd_bc[r]->n : -1;
}

/* ramp(t) and its derivative */
static double pd_ramp(const floe_pd_bc *bc, double t, double *deriv) {
    double T = bc->ramp_time;
    if (t < 0) t = 0;
    switch (bc->ramp) {
    case FLOE_PD_RAMP_LINEAR:
        if (deriv) *deriv = t < T ? 1.0 / T : 0.0;
        return t < T ? t / T : 1.0;
    case FLOE_PD_RAMP_EXP:
        if (deriv) *deriv = exp(-t / T) / T;
        return -expm1(-t / T);
    default:
        if (deriv) *deriv = 0.0;
        return 1.0;
    }
}

/* kinematic region points with a time-dependent velocity (floe_world_set_motion) */
static void pd_bc_motion(double t, double v[3], double om[3], void *user) {
    const floe_pd_bc_rec *r = user;
    double dr, s = pd_ramp(&r->def, t, &dr);
    double f = r->def.kind == FLOE_PD_BC_DISPLACEMENT ? dr : s;
    for (int k = 0; k < 3; k++) { v[k] = f * r->def.value[k]; om[k] = 0; }
}

static void pd_bc_free(floe_pd_bc_rec *r) {
    if (!r) return;
    free(r->pts);
    free(r->fold);
    free(r);
}

int floe_world_pd_region(floe_world *w, int body, const floe_pd_bc *bc) {
    if (!bc) return -floe_world_error(w, FLOE_EINVAL, "PD region: NULL definition");
    if (body < 0 || body >= w->npd)
        return -floe_world_error(w, FLOE_EINVAL, "PD region: body %d out of range (%d PD bodies)", body, w->npd);
    const char *bad = NULL;
    int kind = bc->kind;
    if (kind < FLOE_PD_BC_FIXED || kind > FLOE_PD_BC_BODY_FORCE) bad = "kind must be fixed, velocity, displacement or body force";
    else if (bc->ramp < FLOE_PD_RAMP_NONE || bc->ramp > FLOE_PD_RAMP_EXP) bad = "unknown ramp";
    else if (bc->ramp != FLOE_PD_RAMP_NONE && !(bc->ramp_time > 0 && isfinite(bc->ramp_time)))
        bad = "a ramp needs ramp_time > 0";
    else if (kind == FLOE_PD_BC_DISPLACEMENT && bc->ramp == FLOE_PD_RAMP_NONE)
        bad = "a prescribed displacement needs a ramp (linear or exp) over which it is applied";
    else if (!isfinite(bc->value[0]) || !isfinite(bc->value[1]) || !isfinite(bc->value[2])) bad = "value must be finite";
    else if (!bc->sdf)
        for (int k = 0; k < 3 && !bad; k++)
            if (!(bc->lo[k] <= bc->hi[k])) bad = "the box needs lo <= hi on every axis";
    if (bad) return -floe_world_error(w, FLOE_EINVAL, "PD region %d: %s", w->npd_bc, bad);
    const floe_pd_body *pb = w->pd[body];
    const int f0 = w->pd_first[body];
    floe_pd_bc_rec *r = calloc(1, sizeof *r);
    if (!r) return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    r->def = *bc;
    r->def.sdf = NULL; /* read here only: the caller's data need not outlive this call */
    r->def.sdf_user = NULL;
    r->body = body;
    for (int pass = 0; pass < 2; pass++) {
        int n = 0;
        for (int i = 0; i < pb->n; i++) {
            const double *X = pb->X + 3 * (size_t)i;
            int in = bc->sdf ? bc->sdf(X, bc->sdf_user) <= 0
                             : X[0] >= bc->lo[0] && X[0] <= bc->hi[0] && X[1] >= bc->lo[1] && X[1] <= bc->hi[1] &&
                                   (w->def.dim == 2 || (X[2] >= bc->lo[2] && X[2] <= bc->hi[2]));
            if (!in) continue;
            if (pass == 1) r->pts[n] = f0 + i;
            n++;
        }
        if (pass == 0) {
            if (n == 0) {
                pd_bc_free(r);
                return -floe_world_error(w, FLOE_EINVAL, "PD region %d selects no point of PD body %d (%d points)",
                                         w->npd_bc, body, pb->n);
            }
            r->n = n;
            r->pts = malloc((size_t)n * sizeof *r->pts);
            if (!r->pts) { pd_bc_free(r); return -floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
        }
    }
    const int moving = kind != FLOE_PD_BC_BODY_FORCE;
    if (moving) /* one fixed/velocity/displacement region per point */
        for (int q = 0; q < w->npd_bc; q++) {
            const floe_pd_bc_rec *o = w->pd_bc[q];
            if (o->body != body || o->def.kind == FLOE_PD_BC_BODY_FORCE) continue;
            int shared = 0;
            for (int a = 0, c = 0; a < r->n && c < o->n;) { /* both lists ascending */
                if (r->pts[a] == o->pts[c]) { shared++; a++; c++; }
                else if (r->pts[a] < o->pts[c]) a++;
                else c++;
            }
            if (shared) {
                pd_bc_free(r);
                return -floe_world_error(w, FLOE_EINVAL, "PD region %d shares %d points with region %d: a point "
                                         "may be in one fixed, velocity or displacement region only", w->npd_bc, shared, q);
            }
        }
    if (kind == FLOE_PD_BC_BODY_FORCE) {
        r->fold = calloc(3 * (size_t)r->n, sizeof *r->fold);
        if (!r->fold) { pd_bc_free(r); return -floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
    }
    if (grow((void **)&w->pd_bc, &w->pd_bc_cap, w->npd_bc + 1, sizeof *w->pd_bc)) {
        pd_bc_free(r);
        return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    /* the motion of the points: fixed, constant velocity (kinematic without a callback keeps
     * its velocity), or a time-dependent velocity through a motion callback */
    int timed = moving && kind != FLOE_PD_BC_FIXED && bc->ramp != FLOE_PD_RAMP_NONE;
    if (timed && grow((void **)&w->motions, &w->motions_cap, w->nmotions + r->n, sizeof *w->motions)) {
        pd_bc_free(r);
        return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    w->pd_bc[w->npd_bc++] = r;
    if (moving) {
        floe_particles *p = &w->p;
        double v[3], om[3];
        pd_bc_motion(w->time, v, om, r);
        for (int a = 0; a < r->n; a++) {
            int i = r->pts[a];
            p->motion[i] = kind == FLOE_PD_BC_FIXED ? FLOE_FIXED : FLOE_KINEMATIC;
            p->inv_mass[i] = 0;
            floe_v3_set(p->w + 3 * i, 0, 0, 0);
            if (kind == FLOE_PD_BC_FIXED) floe_v3_set(p->v + 3 * i, 0, 0, 0);
            else floe_v3_copy(p->v + 3 * i, v);
            if (w->def.dim == 2) p->v[3 * i + 2] = 0;
            if (timed) w->motions[w->nmotions++] = (floe_motion_cb){i, pd_bc_motion, r};
        }
        w->prepared = 0;
    }
    return r->n;
}

double floe_pd_bc_forces(floe_world *w) {
    floe_particles *p = &w->p;
    const double t = w->time, dt = w->dt;
    double work = 0;
    for (int q = 0; q < w->npd_bc; q++) {
        floe_pd_bc_rec *r = w->pd_bc[q];
        if (r->def.kind != FLOE_PD_BC_BODY_FORCE) continue;
        const floe_pd_body *pb = w->pd[r->body];
        const int f0 = w->pd_first[r->body];
        double b[3], s = pd_ramp(&r->def, t, NULL);
        for (int k = 0; k < 3; k++) b[k] = s * r->def.value[k];
        for (int a = 0; a < r->n; a++) {
            int i = r->pts[a];
            double *old = r->fold + 3 * a;
            if (p->motion[i] != FLOE_FREE) { floe_v3_set(old, 0, 0, 0); continue; }
            double V = pb->V[i - f0], f[3];
            double bi[3] = {b[0], b[1], b[2]}; /* each point's callback gets the ramped value */
            if (r->def.force_fn) r->def.force_fn(t, pb->X + 3 * (size_t)(i - f0), bi, r->def.force_user);
            for (int k = 0; k < 3; k++) f[k] = bi[k] * V;
            if (w->def.dim == 2) f[2] = 0;
            floe_v3_add(p->f + 3 * i, p->f + 3 * i, f);
            /* velocities are at mid-step here (dx = v dt): work = (F_old + F_new)/2 . dx */
            for (int k = 0; k < 3; k++) work += 0.5 * dt * (f[k] + old[k]) * p->v[3 * i + k];
            floe_v3_copy(old, f);
        }
    }
    return work;
}

double floe_world_dt(const floe_world *w) { return w->dt; }

int floe_world_detect_stats(const floe_world *w, floe_detect_stats *o) {
    const floe_detect_state *d = &w->det;
    memset(o, 0, sizeof *o);
    o->evaluations = d->calls;
    o->lp = d->lp_calls;
    o->admm = d->admm_calls;
    o->nonconverged = d->nonconverged;
    o->first_bad_i = d->first_bad_i;
    o->first_bad_j = d->first_bad_j;
    o->first_bad_step = d->first_bad_step;
    if (d->calls > 0) {
        o->iterations_mean = (double)d->iterations / (double)d->calls;
        long acc = 0, half = (d->calls + 1) / 2, p99 = (long)ceil(0.99 * (double)d->calls);
        o->iterations_median = o->iterations_p99 = -1;
        for (int k = 0; k < FLOE_DETECT_HIST; k++) {
            acc += d->hist[k];
            if (o->iterations_median < 0 && acc >= half) o->iterations_median = k;
            if (o->iterations_p99 < 0 && acc >= p99) o->iterations_p99 = k;
        }
    }
    return FLOE_OK;
}
double floe_world_time(const floe_world *w) { return w->time; }
long floe_world_step_count(const floe_world *w) { return w->step; }
int floe_world_particle_count(const floe_world *w) { return w->p.n; }
double floe_world_critical_dt(floe_world *w) { return w->dt_crit; }
floe_energy floe_world_energy(const floe_world *w) { return w->energy; }

int floe_world_get_particle(const floe_world *w, int i, floe_particle_state *o) {
    if (i < 0 || i >= w->p.n) return FLOE_EINVAL;
    const floe_particles *p = &w->p;
    memcpy(o->x, p->x + 3 * i, sizeof o->x);
    memcpy(o->v, p->v + 3 * i, sizeof o->v);
    memcpy(o->q, p->q + 4 * i, sizeof o->q);
    memcpy(o->w, p->w + 3 * i, sizeof o->w);
    memcpy(o->f, p->f + 3 * i, sizeof o->f);
    memcpy(o->torque, p->t + 3 * i, sizeof o->torque);
    o->mass = p->mass[i];
    o->radius = p->radius[i];
    o->material = p->material[i];
    o->group = p->group[i];
    o->motion = (floe_motion)p->motion[i];
    return FLOE_OK;
}

static void L_from_omega(const double q[4], const double I[3], const double om[3], double L[3]);

int floe_world_set_velocity(floe_world *w, int i, const double v[3], const double omega[3]) {
    floe_particles *p = &w->p;
    if (i < 0 || i >= p->n) return floe_world_error(w, FLOE_EINVAL, "set_velocity: particle %d out of range", i);
    if (p->motion[i] == FLOE_FIXED)
        return floe_world_error(w, FLOE_EINVAL, "set_velocity: particle %d is fixed (it never moves)", i);
    for (int k = 0; k < 3; k++)
        if ((v && !isfinite(v[k])) || (omega && !isfinite(omega[k])))
            return floe_world_error(w, FLOE_EINVAL, "set_velocity: particle %d: the velocities must be finite", i);
    if (w->def.dim == 2 && ((v && v[2] != 0) || (omega && (omega[0] != 0 || omega[1] != 0))))
        return floe_world_error(w, FLOE_EINVAL, "set_velocity: particle %d: in 2D v_z, omega_x and omega_y must be 0", i);
    const int book = w->prepared && p->motion[i] == FLOE_FREE;
    double *vi = p->v + 3 * i, *wi = p->w + 3 * i, *Li = p->L + 3 * i;
    const double kt0 = 0.5 * p->mass[i] * floe_v3_dot(vi, vi), kr0 = 0.5 * floe_v3_dot(Li, wi);
    if (v) memcpy(vi, v, 3 * sizeof *vi);
    if (omega) {
        memcpy(wi, omega, 3 * sizeof *wi);
        /* the angular momentum is the integrated variable (set from omega at prepare) */
        if (w->prepared && p->motion[i] == FLOE_FREE) L_from_omega(p->q + 4 * i, p->inertia + 3 * i, wi, Li);
    }
    if (book) {
        const double dkt = 0.5 * p->mass[i] * floe_v3_dot(vi, vi) - kt0, dkr = 0.5 * floe_v3_dot(Li, wi) - kr0;
        w->energy.kinetic_trans += dkt;
        w->energy.kinetic_rot += dkr;
        w->energy.work_body += dkt + dkr;
    }
    return FLOE_OK;
}

int floe_world_set_pose(floe_world *w, int i, const double x[3], const double q[4]) {
    floe_particles *p = &w->p;
    if (i < 0 || i >= p->n) return floe_world_error(w, FLOE_EINVAL, "set_pose: particle %d out of range", i);
    if (!isfinite(p->radius[i])) return floe_world_error(w, FLOE_EINVAL, "set_pose: particle %d is a wall", i);
    double qn = 1;
    if (x && !(isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2])))
        return floe_world_error(w, FLOE_EINVAL, "set_pose: particle %d: the position must be finite", i);
    if (q) {
        qn = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(qn > 0) || !isfinite(qn))
            return floe_world_error(w, FLOE_EINVAL, "set_pose: particle %d: the quaternion must be non-zero and finite", i);
        if (fabs(qn - 1) <= 1e-12) qn = 1; /* a unit quaternion is kept as given */
    }
    if (w->def.dim == 2 && ((x && x[2] != 0) || (q && (q[1] != 0 || q[2] != 0))))
        return floe_world_error(w, FLOE_EINVAL, "set_pose: particle %d: in 2D z and rotations off the z axis must be 0", i);
    if (x) memcpy(p->x + 3 * i, x, 3 * sizeof *x);
    if (q)
        for (int k = 0; k < 4; k++) p->q[4 * i + k] = q[k] / qn;
    /* the angular velocity is kept: the angular momentum follows the new orientation */
    if (q && w->prepared && p->motion[i] == FLOE_FREE) L_from_omega(p->q + 4 * i, p->inertia + 3 * i, p->w + 3 * i, p->L + 3 * i);
    return FLOE_OK;
}

int floe_world_set_particle_geometry(floe_world *w, int i, int geometry) {
    floe_particles *p = &w->p;
    if (i < 0 || i >= p->n) return floe_world_error(w, FLOE_EINVAL, "set_particle_geometry: particle %d out of range", i);
    if (geometry < 0 || geometry >= w->ngeoms)
        return floe_world_error(w, FLOE_EINVAL, "set_particle_geometry: geometry index %d out of range", geometry);
    if (!isfinite(p->radius[i]))
        return floe_world_error(w, FLOE_EINVAL, "set_particle_geometry: particle %d is a wall", i);
    const floe_geometry *g = w->geoms[geometry];
    double r = floe_geometry_bounding_radius(g);
    if (!(r > 0) || !isfinite(r))
        return floe_world_error(w, FLOE_EINVAL, "set_particle_geometry: geometry %d is not bounded (a wall's plane)",
                                geometry);
    p->geom[i] = geometry;
    p->kind[i] = (unsigned char)g->klass->kind;
    p->pieces[i] = floe_piece_count(g);
    p->radius[i] = r;
    w->prepared = 0;
    return FLOE_OK;
}

int floe_world_set_dt(floe_world *w, double dt, int allow_unstable) {
    if (!(dt >= 0) || !isfinite(dt))
        return floe_world_error(w, FLOE_EINVAL, "set_dt: the time step must be >= 0 and finite (0 = automatic), got %g", dt);
    w->def.dt = dt;
    w->def.allow_unstable_dt = allow_unstable != 0;
    w->prepared = 0;
    return FLOE_OK;
}

double floe_world_energy_balance_error(const floe_world *w) {
    const floe_energy *e = &w->energy;
    double in = e->initial + e->work_body + e->work_boundary;
    double out = e->kinetic_trans + e->kinetic_rot + e->elastic + e->dissipated;
    double scale = fmax(fabs(e->initial) + fabs(e->work_body) + fabs(e->work_boundary), fabs(out));
    if (!(scale > 0)) return 0;
    return fabs(in - out) / scale;
}

/* ---- rotation helpers ---- */

/* omega = R I^-1 R^T L (world frame) */
static void omega_from_L(const double q[4], const double I[3], const double L[3], double om[3]) {
    double Lb[3];
    floe_q_rotate_inv(Lb, q, L);
    for (int k = 0; k < 3; k++) Lb[k] = I[k] > 0 && isfinite(I[k]) ? Lb[k] / I[k] : 0;
    floe_q_rotate(om, q, Lb);
}
static void L_from_omega(const double q[4], const double I[3], const double om[3], double L[3]) {
    double ob[3];
    floe_q_rotate_inv(ob, q, om);
    for (int k = 0; k < 3; k++) ob[k] *= I[k];
    floe_q_rotate(L, q, ob);
}
/* q <- exp(h omega / 2) q, i.e. rotate by the vector h*omega */
static void q_advance(double out[4], const double q[4], const double om[3], double h) {
    double th[3] = {h * om[0], h * om[1], h * om[2]}, dq[4];
    double a2 = floe_v3_dot(th, th);
    if (a2 < 1e-4) {
        /* small turn (every stable step): the series of cos(a/2) and sin(a/2)/a to a^4,
         * truncation below 1e-16 here, no trigonometry (profile of 5,000 polyhedra: sincos
         * was 3 % and this function 6 % of the run) */
        double c = 1.0 - a2 * (0.125 - a2 * (1.0 / 384.0)), s = 0.5 - a2 * (1.0 / 48.0 - a2 * (1.0 / 3840.0));
        dq[0] = c; dq[1] = s * th[0]; dq[2] = s * th[1]; dq[3] = s * th[2];
        floe_q_mul(out, dq, q);
        /* |out| = 1 + O(round-off): one Newton step for 1/sqrt keeps it unit */
        double n2 = out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3];
        double sc = 1.5 - 0.5 * n2;
        for (int k = 0; k < 4; k++) out[k] *= sc;
        return;
    }
    floe_q_from_rotvec(dq, th);
    floe_q_mul(out, dq, q);
    floe_q_normalize(out);
}

/* ---- preparation ---- */

/* Representative overlap: the larger of 2 % of R* and the overlap at which a collision
 * at relative speed v stores its kinetic energy (energy ~ (4/15) k_tangent d^2, exact for
 * Hertz; conservative for linear springs), found by bisection on the law's stiffness. */
static double rep_depth(const floe_contact_law *law, double r_eff, double m_eff, double v) {
    double lo = 0.02 * r_eff, hi = r_eff, kn, cn;
    double target = 0.5 * m_eff * v * v;
    law->klass->stiffness(law, r_eff, m_eff, lo, &kn, &cn);
    if (4.0 / 15.0 * kn * lo * lo >= target) return lo;
    law->klass->stiffness(law, r_eff, m_eff, hi, &kn, &cn);
    if (4.0 / 15.0 * kn * hi * hi <= target) return hi;
    for (int it = 0; it < 60; it++) {
        double mid = 0.5 * (lo + hi);
        law->klass->stiffness(law, r_eff, m_eff, mid, &kn, &cn);
        if (4.0 / 15.0 * kn * mid * mid < target) lo = mid;
        else hi = mid;
    }
    return hi;
}

/* Explicit stability of one particle of mass m held by springs k and dashpots c of a law
 * at a representative contact (r_eff, m_eff): a particle with contacts n_c has the
 * stiffness matrix sum_c k n n^T, and by Gershgorin its highest mode is at most twice that
 * sum's largest eigenvalue: omega^2 <= C k / m with C = 2 n_c / d (8 for the 12 contacts
 * of a close packing in 3D, 6 for the 6 of a hexagonal packing in 2D); the dashpots add up
 * the same way (the peers' "8 gamma / m"). Spring-dashpot limit:
 * dt < (2/omega)(sqrt(1 + zeta^2) - zeta). */
static void pair_estimate(const floe_contact_law *law, double r_eff, double m_eff, double m, double rot, double rotn,
                          double C, double v, double *dt) {
    double kn = 0, cn = 0, depth = rep_depth(law, r_eff, m_eff, v);
    law->klass->stiffness(law, r_eff, m_eff, depth, &kn, &cn);
    /* the normal force on a non-spherical body need not pass through its centre (a corner
     * of a polygon hit sideways): its contact point then moves as a mass m / rotn, which
     * shortens the contact period by sqrt(rotn) (spheres: rotn = 1) */
    kn *= rotn;
    cn *= rotn;
    /* polytopes under a point law touch through a contact manifold (rotn includes its
     * factor, floe_dt_estimates); the overlap law spreads its load instead (its own
     * stiffness counts the contact length) */
    if (law->klass == &floe_overlap_law_class && rotn > rot) {
        kn *= rot / rotn;
        cn *= rot / rotn;
    }
    if (law->klass->tangential_stiffness) {
        /* tangential springs act at the surface: the contact point of a particle of mass m,
         * radius R and inertia I moves as a mass 1/(1/m + R^2/I) = m/rot */
        double kt = 0, ct = 0;
        law->klass->tangential_stiffness(law, r_eff, m_eff, depth, &kt, &ct);
        if (kt * rot > kn) kn = kt * rot;
        if (ct * rot > cn) cn = ct * rot;
    }
    if (!(kn > 0)) return;
    double k = C * kn, c = C * cn;
    double om = sqrt(k / m), zeta = c / (2 * sqrt(k * m));
    double d = 2.0 / om * (sqrt(1 + zeta * zeta) - zeta);
    if (d < *dt) *dt = d;
}

/* Per-particle estimates of one (material, mass, radius, rotation factor), cached: most
 * scenes have few distinct particles */
typedef struct dt_cache_entry {
    int mat;
    double m, r, rot;
    double rotn;    /* rot for non-spherical bodies (normal forces off the centre), else 1 */
    double packing, impact, sqrt_mk, hertz;
    double err1, err2;        /* restitution error model (floe_dt_estimates) */
} dt_cache_entry;
#define DT_CACHE 1024

static void particle_contact_estimates(const floe_world *w, dt_cache_entry *e, double vrel) {
    const double C = w->def.dim == 3 ? 8.0 : 6.0, nc = w->def.dim == 3 ? 12.0 : 6.0;
    const double m = e->m, R = e->r, rot = e->rot, rotn = e->rotn;
    e->packing = e->impact = e->sqrt_mk = e->hertz = INFINITY;
    e->err1 = e->err2 = 0;
    for (int m2 = 0; m2 < w->nmats; m2++) {
        const floe_contact_law *law = w->laws[e->mat * w->nmats + m2];
        if (!law) continue;
        /* partner of the same size (m* = m/2, R* = R/2) and a wall (m* = m, R* = R) */
        /* a packing (all contacts of a close packing at a 2 % overlap) and an impact at
         * the expected speed (one contact, C = 2, at the overlap of the collision) */
        pair_estimate(law, 0.5 * R, 0.5 * m, m, rot, rotn, C, 0, &e->packing);
        pair_estimate(law, R, m, m, rot, rotn, C, 0, &e->packing);
        pair_estimate(law, 0.5 * R, 0.5 * m, m, rot, rotn, 2.0, vrel, &e->impact);
        pair_estimate(law, R, m, m, rot, rotn, 2.0, vrel, &e->impact);
        /* 000 eq 43: sqrt(m / k_bar), k_bar = the normal stiffnesses of the n_c contacts of
         * a close packing at 2 % overlap (004 eq 28 takes 2 sqrt(m_ii / k_ii) of the same) */
        for (int s = 0; s < 2; s++) {
            double re = s ? R : 0.5 * R, me = s ? m : 0.5 * m, kn = 0, cn = 0;
            law->klass->stiffness(law, re, me, 0.02 * re, &kn, &cn);
            if (kn > 0 && sqrt(m / (nc * kn)) < e->sqrt_mk) e->sqrt_mk = sqrt(m / (nc * kn));
            /* Hertz contact duration at the expected speed, 2.87 (m*^2 / (R* E*^2 v))^(1/5)
             * (E* of the law: the force is 4/3 E* sqrt(R*) d^(3/2)) */
            if (law->klass == &floe_hertz_mindlin_law_class && vrel > 0) {
                double es = ((const floe_hertz_mindlin_law *)law)->e_star;
                double th = 2.87 * pow(me * me / (re * es * es * vrel), 0.2);
                if (th < e->hertz) e->hertz = th;
                /* restitution error ~ A(e) / N, N = th / dt (first order: the damping grows
                 * as d^(1/4) from the onset; tests/test_restitution_onset.c) */
                double er = ((const floe_hertz_mindlin_law *)law)->restitution;
                double A = 3.5 * pow(1 - er, 1.5) + 0.02;
                if (A / th > e->err1) e->err1 = A / th;
            }
            if (law->klass == &floe_linear_law_class) {
                /* ~ A(e) / N^2, N = pi / w_d / dt (the dashpot's onset and release treated in
                 * contact/laws/linear_law.c) */
                const floe_linear_law *ll = (const floe_linear_law *)law;
                double kk = ll->kn, z = ll->gn / (2 * sqrt(kk * me));
                if (kk > 0 && z < 1) {
                    double tc = M_PI / (sqrt(kk / me) * sqrt(1 - z * z));
                    double er = floe_linear_restitution(kk, ll->gn, me), A = 3 + 12 * (1 - er) * (1 - er);
                    if (A / (tc * tc) > e->err2) e->err2 = A / (tc * tc);
                }
            }
        }
    }
}

/* record dt for kind k at particle i when it is the smallest so far */
static void dt_note(floe_dt_estimates *d, int k, double dt, int i) {
    if (dt < d->dt[k]) { d->dt[k] = dt; d->particle[k] = i; }
}

const char *floe_dt_kind_name(int kind) {
    static const char *const names[FLOE_DT_NKINDS] = {"contact_packing", "contact_impact", "motion", "pd_nodal",
                                                      "pd_cfl", "dem_sqrt_m_k", "rayleigh", "hertz", "beam_bond"};
    return kind >= 0 && kind < FLOE_DT_NKINDS ? names[kind] : NULL;
}

/* Every estimate of floe_dt_estimates, per particle (w->dt_part: the smallest limiting
 * kind of each particle) and global (w->dte, w->dt_crit). */
static int estimate_dt(floe_world *w) {
    floe_particles *p = &w->p;
    floe_dt_estimates *d = &w->dte;
    memset(d, 0, sizeof *d);
    for (int k = 0; k < FLOE_DT_NKINDS; k++) { d->dt[k] = INFINITY; d->particle[k] = -1; }
    d->limits[FLOE_DT_CONTACT_PACKING] = d->limits[FLOE_DT_CONTACT_IMPACT] = 1;
    d->limits[FLOE_DT_MOTION] = d->limits[FLOE_DT_PD_NODAL] = 1;
    double *dp = realloc(w->dt_part, (size_t)(p->n ? p->n : 1) * sizeof *dp);
    if (!dp) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    w->dt_part = dp;
    /* largest relative speed to expect: twice the fastest particle plus the free fall
     * over the extent of the scene along gravity */
    double vmax = 0, gmag = floe_v3_norm(w->def.gravity), lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] == FLOE_FIXED) continue;
        double s = floe_v3_norm(p->v + 3 * i);
        if (s > vmax) vmax = s;
        if (gmag > 0 && isfinite(p->radius[i])) {
            double h = floe_v3_dot(p->x + 3 * i, w->def.gravity) / gmag;
            if (h < lo) lo = h;
            if (h > hi) hi = h;
        }
    }
    double vrel = 2 * vmax + (hi > lo ? sqrt(2 * gmag * (hi - lo)) : 0);
    w->v_expected = d->v_expected = vrel;
    /* materials in a Hertz-Mindlin law: the Rayleigh step of their particles */
    unsigned char *hertz_mat = calloc((size_t)(w->nmats ? w->nmats : 1), 1);
    dt_cache_entry *cache = calloc(DT_CACHE, sizeof *cache);
    if (!hertz_mat || !cache) {
        free(hertz_mat);
        free(cache);
        return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    for (int a = 0; a < w->nmats; a++)
        for (int b = 0; b < w->nmats; b++) {
            const floe_contact_law *law = w->laws[a * w->nmats + b];
            if (law && law->klass == &floe_hertz_mindlin_law_class) hertz_mat[a] = hertz_mat[b] = 1;
        }
    for (int k = 0; k < DT_CACHE; k++) cache[k].mat = -1;
    double *mfac = malloc((size_t)(w->ngeoms > 0 ? w->ngeoms : 1) * sizeof *mfac); /* NULL: computed each time */
    if (mfac)
        for (int k = 0; k < w->ngeoms; k++) mfac[k] = -1.0;
    for (int i = 0; i < p->n; i++) {
        dp[i] = INFINITY;
        if (p->motion[i] != FLOE_FREE || !isfinite(p->radius[i])) continue;
        /* 1 + m R^2 / I: 3.5 for a sphere */
        const double *I = p->inertia + 3 * i;
        double imin = w->def.dim == 2 ? I[2] : fmin(I[0], fmin(I[1], I[2]));
        double rot = imin > 0 ? fmax(1.0, 1 + p->mass[i] * p->radius[i] * p->radius[i] / imin) : 1.0;
        double rotn = p->kind[i] == FLOE_GEOM_SPHERE ? 1.0 : rot;
        /* polytopes touch through a contact manifold (up to 2 corner springs in 2D, 4 in 3D),
         * which can be stiffer in rocking than one point at the bounding radius (a thin
         * square plate flat on a face: 12 k/m against 1 + m R^2/I_min = 7): the larger */
        if (p->kind[i] != FLOE_GEOM_SPHERE && mfac) { /* per shape (it depends on I/m only) */
            double *f = mfac + p->geom[i];
            if (*f < 0) *f = floe_polytope_manifold_factor(w->geoms[p->geom[i]], w->def.dim, I, p->mass[i]);
            rotn = fmax(rotn, *f);
        } else if (p->kind[i] != FLOE_GEOM_SPHERE) {
            rotn = fmax(rotn, floe_polytope_manifold_factor(w->geoms[p->geom[i]], w->def.dim, I, p->mass[i]));
        }
        dt_cache_entry key = {p->material[i], p->mass[i], p->radius[i], rot, rotn, 0, 0, 0, 0, 0, 0};
        unsigned long long hsh = (unsigned long long)key.mat * 0x9E3779B97F4A7C15ull;
        const double vals[4] = {key.m, key.r, key.rot, key.rotn};
        for (int k = 0; k < 4; k++) {
            unsigned long long bits;
            memcpy(&bits, &vals[k], sizeof bits);
            hsh = (hsh ^ bits) * 0x100000001B3ull;
        }
        dt_cache_entry *e = &cache[(hsh >> 20) % DT_CACHE];
        if (!(e->mat == key.mat && e->m == key.m && e->r == key.r && e->rot == key.rot && e->rotn == key.rotn)) {
            *e = key;
            particle_contact_estimates(w, e, vrel);
        }
        dt_note(d, FLOE_DT_CONTACT_PACKING, e->packing, i);
        dt_note(d, FLOE_DT_CONTACT_IMPACT, e->impact, i);
        dt_note(d, FLOE_DT_DEM_SQRT_MK, e->sqrt_mk, i);
        dt_note(d, FLOE_DT_HERTZ, e->hertz, i);
        if (e->err1 > d->err1) d->err1 = e->err1;
        if (e->err2 > d->err2) d->err2 = e->err2;
        double mine = fmin(e->packing, e->impact);
        /* motion: no particle may move more than half its radius in a step (the stability
         * check of the step stops the run past that) */
        if (vrel > 0) {
            double dm = 0.5 * p->radius[i] / vrel;
            dt_note(d, FLOE_DT_MOTION, dm, i);
            if (dm < mine) mine = dm;
        }
        if (hertz_mat[p->material[i]]) {
            /* Rayleigh wave crossing the particle: pi R sqrt(rho / G) / (0.1631 nu + 0.8766) */
            const floe_material *mt = &w->mats[p->material[i]];
            double G = mt->young / (2 * (1 + mt->poisson));
            double dr = M_PI * p->radius[i] * sqrt(mt->density / G) / (0.1631 * mt->poisson + 0.8766);
            dt_note(d, FLOE_DT_RAYLEIGH, dr, i);
        }
        dp[i] = mine;
    }
    free(hertz_mat);
    free(cache);
    free(mfac);
    /* peridynamic bodies: the nodal estimate sqrt(2 rho / sum_j V_j c/|xi|) per point
     * (Silling and Askari 2005; measured limits 2.1x (PMB) and 1.8x (LPS) of it,
     * tests/test_pd.c), as floe_pd_dt_nodal; and the CFL step of 000 eqs 41-42 per body */
    for (int k = 0; k < w->npd; k++) {
        const floe_pd_body *b = w->pd[k];
        const int f0 = w->pd_first[k];
        double *sum = calloc((size_t)b->n, sizeof *sum);
        if (!sum) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        double c = b->ops->bond_micromodulus(b);
        for (int i = 0; i < b->n; i++)
            for (int64_t q = b->off[i]; q < b->off[i + 1]; q++) {
                int j = b->partner[q];
                double s = b->vfac[q] * (b->scorr ? b->scorr[q] : 1.0f) * c / b->len[q];
                sum[i] += s * b->V[j];
                sum[j] += s * b->V[i];
            }
        for (int i = 0; i < b->n; i++) {
            if (!(sum[i] > 0) || p->motion[f0 + i] != FLOE_FREE) continue;
            double dn = sqrt(2.0 * b->mat.rho / sum[i]);
            dt_note(d, FLOE_DT_PD_NODAL, dn, f0 + i);
            if (dn < dp[f0 + i]) dp[f0 + i] = dn;
        }
        free(sum);
        double dc = floe_pd_dt_cfl(b);
        if (dc > 0) dt_note(d, FLOE_DT_PD_CFL, dc, f0);
    }
    if (w->beams) { /* beam bonds */
        d->limits[FLOE_DT_BEAM] = 1;
        d->dt[FLOE_DT_BEAM] = floe_world_beam_critical_dt(w);
    }
    d->critical = INFINITY;
    d->limiting = d->limiting_particle = -1;
    for (int k = 0; k < FLOE_DT_NKINDS; k++)
        if (d->limits[k] && d->dt[k] < d->critical) {
            d->critical = d->dt[k];
            d->limiting = k;
            d->limiting_particle = d->particle[k];
        }
    d->critical_contact = fmin(d->dt[FLOE_DT_CONTACT_PACKING], fmin(d->dt[FLOE_DT_CONTACT_IMPACT], d->dt[FLOE_DT_MOTION]));
    d->critical_pd = d->dt[FLOE_DT_PD_NODAL];
    d->accuracy_dt = INFINITY;
    if (w->def.accuracy > 0) {
        const double a = w->def.accuracy;
        if (d->err1 > 0) d->accuracy_dt = a / d->err1;
        if (d->err2 > 0) d->accuracy_dt = fmin(d->accuracy_dt, sqrt(a / d->err2));
    }
    w->dt_crit = d->critical;
    return FLOE_OK;
}

/* The step, the staggered ratios and the adaptive bounds, from the definition and the
 * estimates. A given dt above the critical estimate is refused unless allowed; so is a PD
 * step of the staggered scheme above the PD estimate. */
static int choose_dt(floe_world *w) {
    const floe_world_def *d = &w->def;
    const floe_dt_estimates *e = &w->dte;
    if (d->integrator < FLOE_VELOCITY_VERLET || d->integrator > FLOE_RK2)
        return floe_world_error(w, FLOE_EINVAL, "integrator %d unknown (velocity_verlet, leapfrog or rk2)", d->integrator);
    if (d->pd_dem != FLOE_PD_DEM_MONOLITHIC && d->pd_dem != FLOE_PD_DEM_STAGGERED)
        return floe_world_error(w, FLOE_EINVAL, "pd_dem scheme %d unknown (monolithic or staggered)", d->pd_dem);
    const int stag = d->pd_dem == FLOE_PD_DEM_STAGGERED;
    if (stag && d->integrator != FLOE_VELOCITY_VERLET)
        return floe_world_error(w, FLOE_EINVAL, "the staggered PD-DEM scheme kicks and drifts as velocity Verlet does "
                                "(r-RESPA); use integrator velocity_verlet with it");
    if (d->adaptive && d->integrator == FLOE_LEAPFROG)
        return floe_world_error(w, FLOE_EINVAL, "adaptive steps need velocity_verlet or rk2 (leapfrog keeps half-step "
                                "velocities, which a rejected step could not restore consistently)");
    if (d->adaptive && stag)
        return floe_world_error(w, FLOE_EINVAL, "adaptive steps and the staggered PD-DEM scheme cannot be combined yet");
    if (d->integrator == FLOE_RK2 && w->beams)
        return floe_world_error(w, FLOE_EINVAL, "the rk2 integrator and beam bonds cannot be combined: RK2 has no stable "
                                "step for undamped bonds (energy grows by 1 + (w dt)^4/4 per step) and its midpoint "
                                "evaluation would book the bonds' energy twice; use velocity_verlet or leapfrog");
    if (d->adaptive && w->beams)
        return floe_world_error(w, FLOE_EINVAL, "adaptive steps and beam bonds cannot be combined yet (a bond broken in "
                                "a rejected trial step would stay broken); use a fixed or automatic step");
    if (d->pd_substeps < 0 || d->pd_every < 0 || (d->pd_substeps > 1 && d->pd_every > 1))
        return floe_world_error(w, FLOE_EINVAL, "staggered PD-DEM: substeps (%d) and every (%d) must be >= 1 (substeps 0: "
                                "automatic), and only one of them above 1", d->pd_substeps, d->pd_every);
    if (d->adaptive) {
        const char *bad = NULL;
        if (!(d->adapt_velocity_tol > 0) || !isfinite(d->adapt_velocity_tol)) bad = "velocity tolerance must be > 0";
        else if (!(d->adapt_depth_tol > 0) || !isfinite(d->adapt_depth_tol)) bad = "penetration tolerance must be > 0";
        else if (!(d->dt_min >= 0) || !isfinite(d->dt_min)) bad = "dt_min must be >= 0 (0 = automatic)";
        else if (!(d->dt_max >= 0) || !isfinite(d->dt_max)) bad = "dt_max must be >= 0 (0 = automatic)";
        if (bad) return floe_world_error(w, FLOE_EINVAL, "adaptive steps: %s", bad);
    }
    const int st = stag && w->npd > 0;
    double crit = st && isfinite(e->critical_contact) ? e->critical_contact : e->critical;
    const char *what = st && isfinite(e->critical_contact) ? "the contact critical estimate" : "the critical estimate";
    int lk = st && isfinite(e->critical_contact) ? (e->dt[FLOE_DT_CONTACT_PACKING] == crit ? FLOE_DT_CONTACT_PACKING
                                                    : e->dt[FLOE_DT_CONTACT_IMPACT] == crit ? FLOE_DT_CONTACT_IMPACT
                                                                                              : FLOE_DT_MOTION)
                                                 : e->limiting;
    if (d->dt > 0) {
        w->dt = d->dt;
        if (isfinite(crit) && w->dt > crit && !d->allow_unstable_dt)
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "time step %g s is above %s %g s (%s, particle %d); use a smaller dt, dt: auto "
                                    "(automatic), or allow_unstable_dt: true",
                                    w->dt, what, crit, lk >= 0 ? floe_dt_kind_name(lk) : "?",
                                    lk >= 0 ? e->particle[lk] : -1);
    } else {
        if (!isfinite(crit))
            return floe_world_error(w, FLOE_EINVAL, "automatic time step: no contact law to estimate it from; give dt");
        w->dt = d->dt_safety * crit;
        if (d->accuracy > 0 && e->accuracy_dt < w->dt) w->dt = e->accuracy_dt; /* time.accuracy */
    }
    w->dte.predicted_error = fmax(e->err1 * w->dt, e->err2 * w->dt * w->dt);
    w->pd_sub = w->pd_every = 1;
    if (st) {
        const double pdc = e->critical_pd;
        int sub = d->pd_substeps, every = d->pd_every > 0 ? d->pd_every : 1;
        if (sub == 0) { /* automatic: the integer ratio of the two critical steps */
            sub = 1;
            if (isfinite(pdc) && every == 1) {
                if (w->dt > d->dt_safety * pdc) sub = (int)ceil(w->dt / (d->dt_safety * pdc) - 1e-9);
                else every = (int)fmax(1.0, floor(d->dt_safety * pdc / w->dt + 1e-9));
            }
        }
        if (sub > 100000 || every > 100000)
            return floe_world_error(w, FLOE_EINVAL, "staggered PD-DEM: ratio %d out of range (at most 100000)", sub > every ? sub : every);
        double dpd = every > 1 ? every * w->dt : w->dt / sub;
        if (isfinite(pdc) && dpd > pdc && !d->allow_unstable_dt)
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "staggered PD-DEM: the PD step %g s (dt %g s %s %d) is above the PD critical estimate "
                                    "%g s (pd_nodal, particle %d); raise substeps, lower every or dt, or allow_unstable_dt: true",
                                    dpd, w->dt, every > 1 ? "x" : "/", every > 1 ? every : sub, pdc,
                                    e->particle[FLOE_DT_PD_NODAL]);
        w->pd_sub = sub;
        w->pd_every = every;
    }
    w->st.pd_substeps = w->pd_sub;
    w->st.pd_every = w->pd_every;
    if (d->adaptive) {
        w->dt_hi = d->dt_max > 0 ? d->dt_max : crit;
        if (!isfinite(w->dt_hi))
            return floe_world_error(w, FLOE_EINVAL, "adaptive steps: no critical estimate to bound the step; give dt_max");
        if (d->dt_max > 0 && isfinite(crit) && d->dt_max > crit && !d->allow_unstable_dt)
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "adaptive steps: dt_max %g s is above the critical estimate %g s; lower it, or "
                                    "allow_unstable_dt: true", d->dt_max, crit);
        w->dt_lo = d->dt_min > 0 ? d->dt_min : 1e-3 * w->dt_hi;
        if (w->dt_lo > w->dt_hi)
            return floe_world_error(w, FLOE_EINVAL, "adaptive steps: dt_min %g s is above dt_max %g s", w->dt_lo, w->dt_hi);
        w->dt = fmin(w->dt_hi, fmax(w->dt_lo, w->dt));
        w->dt_next = w->dt;
    }
    return FLOE_OK;
}

static int observers_call(floe_world *w, int force_all);
static int contacts_wanted(const floe_world *w);
static int stag_split_forces(floe_world *w);
static double shadow_energy(const floe_world *w, const double *fs, const double *ts, const double *fpd);

int floe_world_prepare(floe_world *w) {
    if (w->prepared) return FLOE_OK;
    floe_particles *p = &w->p;
    w->err[0] = 0;
    /* masses and inertia */
    for (int i = 0; i < p->n; i++) {
        const floe_geometry *g = w->geoms[p->geom[i]];
        if (!isfinite(p->radius[i])) {
            p->mass[i] = INFINITY;
            p->inv_mass[i] = 0;
            floe_v3_set(p->inertia + 3 * i, INFINITY, INFINITY, INFINITY);
            continue;
        }
        if (!(p->radius[i] > 0)) return floe_world_error(w, FLOE_EINVAL, "particle %d: bounding radius must be > 0", i);
        floe_mass_properties mp;
        int mdim = (w->def.dim == 2 && w->def.mass_2d_area) ? 2 : 3;
        int polygon = g->klass == &floe_polytope_class && ((const floe_polytope *)g)->dim == 2;
        if (polygon && w->def.dim == 3)
            return floe_world_error(w, FLOE_EINVAL,
                                    "particle %d: a polygon is a 2D shape (dim: 2); in 3D use a prism or polyhedron", i);
        if (polygon) mdim = 2; /* a polygon has no 3D body: mass per metre of thickness */
        if (w->def.dim == 2 && g->klass == &floe_polytope_class && !polygon)
            return floe_world_error(w, FLOE_EINVAL,
                                    "particle %d: a polyhedron (or prism, mesh) is a 3D shape; in 2D use a polygon", i);
        int rc = floe_geometry_mass_properties(g, mdim, w->mats[p->material[i]].density, &mp);
        if (rc) return floe_world_error(w, rc, "particle %d: mass properties of its %s failed", i, g->klass->name);
        /* the body frame must be the principal frame at the centre of mass: the integrator
         * rotates about the origin with the inertia diagonal in the body axes */
        double off = floe_v3_norm(mp.centroid);
        if (off > 1e-2 * p->radius[i] || mp.off_axis > 1e-2)
            return floe_world_error(w, FLOE_EINVAL,
                                    "particle %d: its %s shape has its centre of mass at (%g, %g, %g) and "
                                    "off-diagonal inertia %.2g (relative): define the SDF about the centre "
                                    "of mass with the principal axes along x, y, z",
                                    i, g->klass->name, mp.centroid[0], mp.centroid[1], mp.centroid[2], mp.off_axis);
        if (p->mass[i] > 0) { /* user mass: scale inertia */
            double s = p->mass[i] / mp.mass;
            for (int k = 0; k < 3; k++) mp.inertia[k] *= s;
        } else p->mass[i] = mp.mass;
        if (!(p->mass[i] > 0) || !isfinite(p->mass[i]))
            return floe_world_error(w, FLOE_EINVAL, "particle %d: mass must be > 0 and finite (got %g)", i, p->mass[i]);
        memcpy(p->inertia + 3 * i, mp.inertia, sizeof mp.inertia);
        {
            const double *I = mp.inertia;
            double imax = fmax(I[0], fmax(I[1], I[2])), imin = fmin(I[0], fmin(I[1], I[2]));
            /* 2D rotates about z only, so only I_zz matters: treat as isotropic with I_zz */
            p->iso[i] = w->def.dim == 2 || imax - imin <= 1e-12 * imax;
            if (w->def.dim == 2) p->inertia[3 * i] = p->inertia[3 * i + 1] = I[2];
        }
        p->inv_mass[i] = p->motion[i] == FLOE_FREE ? 1.0 / p->mass[i] : 0;
        L_from_omega(p->q + 4 * i, p->inertia + 3 * i, p->w + 3 * i, p->L + 3 * i);
    }
    /* every material pair that can meet needs a law; every geometry pair a detector */
    for (int a = 0; a < w->nmats; a++)
        for (int b = a; b < w->nmats; b++) {
            if (w->laws[a * w->nmats + b]) continue;
            int used_a = 0, used_b = 0, free_a = 0, free_b = 0;
            for (int i = 0; i < p->n; i++) {
                if (p->material[i] == a) { used_a++; free_a |= p->motion[i] == FLOE_FREE; }
                if (p->material[i] == b) { used_b++; free_b |= p->motion[i] == FLOE_FREE; }
            }
            /* a pair can meet if both are present (two particles when a == b) and one is free */
            int meet = a == b ? used_a >= 2 && free_a : used_a && used_b && (free_a || free_b);
            if (meet)
                return floe_world_error(w, FLOE_EINVAL, "no contact law for the material pair (%s, %s)",
                                        w->mats[a].name, w->mats[b].name);
        }
    {
        /* geometry pairs present among (free, any) particles */
        int ng = w->ngeoms;
        int *seen = calloc((size_t)ng * 2, sizeof(int));
        if (!seen) return FLOE_ENOMEM;
        for (int i = 0; i < p->n; i++) seen[2 * p->geom[i] + (p->motion[i] == FLOE_FREE)]++;
        int rc = FLOE_OK;
        for (int a = 0; a < ng && !rc; a++) {
            if (!seen[2 * a + 1]) continue;
            for (int b = 0; b < ng && !rc; b++) {
                int nb = seen[2 * b] + seen[2 * b + 1];
                if (nb < (a == b ? 2 : 1)) continue;
                if (!floe_detect_supported(w->geoms[a], w->geoms[b]))
                    rc = floe_world_error(w, FLOE_ENOTSUP, "no contact detector for the pair %s-%s",
                                          w->geoms[a]->klass->name, w->geoms[b]->klass->name);
                else if (floe_detect_needs_warm(w->geoms[a], w->geoms[b]))
                    w->nl.use_warm = 1; /* ADMM / LP pairs: keep warm starts */
            }
        }
        free(seen);
        if (rc) return rc;
    }
    if (w->npd) {
        /* PD bookkeeping: the body index of particles added after the bodies, last forces */
        if (w->pd_npts_alloc < p->n) {
            int *po = realloc(w->pd_of, (size_t)p->n * sizeof *po);
            if (!po) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            for (int i = w->pd_npts_alloc; i < p->n; i++) po[i] = -1;
            w->pd_of = po;
            w->pd_npts_alloc = p->n;
        }
        double *fo = realloc(w->pd_fold, (size_t)3 * w->pd_npts * sizeof *fo);
        if (fo) w->pd_fold = fo;
        double *fn = fo ? realloc(w->pd_fnew, (size_t)3 * w->pd_npts * sizeof *fn) : NULL;
        if (fn) w->pd_fnew = fn;
        double *eo = fn ? realloc(w->pd_eold, (size_t)w->npd * sizeof *eo) : NULL;
        if (eo) w->pd_eold = eo;
        if (!fo || !fn || !eo) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        if (w->pd_diss_n < w->npd) { /* the watchdog's per-body dissipation, kept across re-prepares */
            double *pdd = realloc(w->pd_diss, (size_t)w->npd * sizeof *pdd);
            if (!pdd) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            for (int k = w->pd_diss_n; k < w->npd; k++) pdd[k] = 0;
            w->pd_diss = pdd;
            w->pd_diss_n = w->npd;
        }
        memset(w->pd_fold, 0, (size_t)3 * w->pd_npts * sizeof *fo);
    }
    FLOE_TRY(estimate_dt(w));
    FLOE_TRY(choose_dt(w));
    if (w->step == 0) w->lf_dt_prev = 0; /* leapfrog: the velocities given are synchronised */
    int rc = floe_nl_build(&w->nl, p, w->def.dim, w->def.leaf_size);
    if (rc) return floe_world_error(w, rc, "neighbour list build failed (out of memory)");
    {
        double *ko = realloc(w->kin_old, (size_t)(p->n ? p->n : 1) * 6 * sizeof(double));
        if (!ko) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        w->kin_old = ko;
    }
    /* the watchdog's floor on the energy scale: every free particle lifted by its size
     * against gravity (a resting pile has little kinetic energy, yet that is the energy
     * its contacts are measured against) */
    {
        double g = floe_v3_norm(w->def.gravity), gs = 0;
        for (int i = 0; i < p->n; i++)
            if (p->motion[i] == FLOE_FREE && isfinite(p->radius[i])) gs += p->mass[i] * g * p->radius[i];
        w->wd_gscale = gs;
    }
    w->prepared = 1;
    w->t0 = w->time;
    w->step0 = w->step;
    w->record_now = w->record_contacts || w->obs_need_contacts;
    rc = w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd ? stag_split_forces(w) : floe_compute_forces(w);
    if (rc) return rc;
    /* energy at start */
    floe_energy *e = &w->energy;
    double kt = 0, kr = 0;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        kt += 0.5 * p->mass[i] * floe_v3_dot(p->v + 3 * i, p->v + 3 * i);
        kr += 0.5 * floe_v3_dot(p->L + 3 * i, p->w + 3 * i);
    }
    e->kinetic_trans = kt;
    e->kinetic_rot = kr;
    {
        const int stag = w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd;
        const size_t n3 = 3 * (size_t)p->n;
        w->wd_shadow = stag ? shadow_energy(w, w->ibuf, w->ibuf + n3, w->ibuf + 2 * n3) : shadow_energy(w, p->f, p->t, NULL);
        w->wd_shadow0 = w->wd_shadow; /* the watchdog's balance restarts with the ledger */
    }
    if (w->step == 0) {
        e->initial = kt + kr + e->elastic;
        e->work_body = e->work_boundary = e->dissipated = 0;
    } else {
        /* re-prepared mid-run (particles added, motion changed): the ledger goes on from
         * the present state, so the balance error restarts from 0 here */
        e->initial = kt + kr + e->elastic + e->dissipated - e->work_body - e->work_boundary;
    }
    for (int k = 0; k < w->nobs; k++) {
        floe_observer *o = w->obs[k];
        if (o->begun) continue; /* re-prepared mid-run: already writing */
        o->begun = 1;
        o->next_time = w->time;
        if (o->klass->begin) {
            rc = o->klass->begin(o, w);
            if (rc) return floe_world_error(w, rc, "observer %s failed to start: %s", o->klass->name,
                                            w->err[0] ? w->err : "(no message)");
        }
    }
    return observers_call(w, 1);
}

static int observer_due(const floe_world *w, const floe_observer *o) {
    if (o->period_steps > 0) return w->step % o->period_steps == 0;
    if (o->period_time > 0) return w->time >= o->next_time - 1e-9 * w->dt;
    return 1;
}

/* contact records are kept only at force evaluations that an observer will read */
static int contacts_wanted(const floe_world *w) {
    if (w->record_contacts) return 1;
    if (!w->obs_need_contacts) return 0;
    if (w->last_step_of_run) return 1; /* observers write the final state at the end */
    for (int k = 0; k < w->nobs; k++)
        if (w->obs[k]->klass->needs_contacts && observer_due(w, w->obs[k])) return 1;
    return 0;
}

static int observers_call(floe_world *w, int force_all) {
    for (int k = 0; k < w->nobs; k++) {
        floe_observer *o = w->obs[k];
        int due = force_all || observer_due(w, o);
        if (!due) continue;
        if (o->period_time > 0 && o->period_steps <= 0)
            while (o->next_time <= w->time + 1e-9 * w->dt) o->next_time += o->period_time;
        w->err[0] = 0;
        int rc = o->klass->observe(o, w);
        if (rc) {
            char why[sizeof w->err];
            memcpy(why, w->err, sizeof why);
            return floe_world_error(w, rc, "observer %s failed at step %ld: %s", o->klass->name, w->step,
                                    why[0] ? why : floe_strerror(rc));
        }
    }
    return FLOE_OK;
}

int floe_world_finish(floe_world *w) {
    int rc = FLOE_OK;
    char first[sizeof w->err]; /* the first failure's message is the one reported (a full disk
                                  fails every writer: the first names the cause) */
    first[0] = 0;
    for (int k = 0; k < w->nobs; k++) {
        floe_observer *o = w->obs[k];
        if (o->ended) continue;
        o->ended = 1;
        if (o->klass->end) {
            int r = o->klass->end(o, w);
            if (r && !rc) { rc = r; memcpy(first, w->err, sizeof first); }
        }
    }
    if (rc) memcpy(w->err, first, sizeof first);
    w->finished = 1;
    return rc;
}

/* Energy of the closing half kick of free particle i (velocity change dv, angular momentum
 * change dL): 1/2 m |dv|^2 + 1/2 dL . I^-1 dL. Velocity Verlet conserves exactly (linear
 * forces) K + U minus this term (1/2 m v_{n+1/2} . v_{n-1/2} + U), not K + U, whose
 * measured value oscillates by up to (w dt/2)^2 / (1 - (w dt/2)^2) near the stability
 * limit; the energy watchdog compares that conserved form (w->wd_shadow). */
static double shadow_term(const floe_particles *p, int i, const double dv[3], const double dL[3]) {
    double e = 0.5 * p->mass[i] * floe_v3_dot(dv, dv);
    const double *I = p->inertia + 3 * i;
    if (p->iso[i]) {
        if (I[0] > 0 && isfinite(I[0])) e += 0.5 * floe_v3_dot(dL, dL) / I[0];
    } else {
        double b[3];
        floe_q_rotate_inv(b, p->q + 4 * i, dL);
        for (int k = 0; k < 3; k++)
            if (I[k] > 0 && isfinite(I[k])) e += 0.5 * b[k] * b[k] / I[k];
    }
    return e;
}

/* the same over every free particle from the forces in p->f, p->t (velocity Verlet and
 * leapfrog: the half kick h F / m) or the staggered groups fs, ts, fpd; 0 for RK2 */
static double shadow_energy(const floe_world *w, const double *fs, const double *ts, const double *fpd) {
    const floe_particles *p = &w->p;
    if (w->def.integrator == FLOE_RK2 && !fpd) return 0;
    const double h = 0.5 * w->dt, hp = fpd ? 0.5 * w->dt / (w->pd_sub > 0 ? w->pd_sub : 1) : 0;
    double e = 0;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        double dv[3], dL[3];
        for (int k = 0; k < 3; k++) {
            dv[k] = h * p->inv_mass[i] * fs[3 * i + k];
            if (fpd && w->pd_every == 1 && w->pd_of && w->pd_of[i] >= 0) dv[k] += hp * p->inv_mass[i] * fpd[3 * i + k];
            dL[k] = h * ts[3 * i + k];
        }
        e += shadow_term(p, i, dv, dL);
    }
    return e;
}

/* ---- the step ---- */

/* motion callback of particle i: an index particle -> callback, rebuilt when callbacks or
 * particles were added (a linear scan per particle would cost O(k^2) per step for k
 * ramped PD boundary points); the first callback set for a particle wins */
static int motion_of(floe_world *w, int i) {
    if (w->motion_idx_n != w->p.n || w->motion_idx_cnt != w->nmotions) {
        int *t = realloc(w->motion_idx, (size_t)(w->p.n > 0 ? w->p.n : 1) * sizeof *t);
        if (!t) { /* out of memory: fall back to the scan */
            for (int k = 0; k < w->nmotions; k++)
                if (w->motions[k].particle == i) return k;
            return -1;
        }
        w->motion_idx = t;
        for (int k = 0; k < w->p.n; k++) t[k] = -1;
        for (int k = w->nmotions - 1; k >= 0; k--) {
            int pi = w->motions[k].particle;
            if (pi >= 0 && pi < w->p.n) t[pi] = k;
        }
        w->motion_idx_n = w->p.n;
        w->motion_idx_cnt = w->nmotions;
    }
    return w->motion_idx[i];
}

static void kinematic_velocity(floe_world *w, int i, double t) {
    int k = motion_of(w, i);
    if (k < 0) return;
    w->motions[k].fn(t, w->p.v + 3 * i, w->p.w + 3 * i, w->motions[k].user);
    if (w->def.dim == 2) { w->p.v[3 * i + 2] = 0; w->p.w[3 * i] = w->p.w[3 * i + 1] = 0; }
}

/* End of a step for kinematic particle i: the work it did on the others over the step,
 * -(F_old + F_new)/2 . v_half dt (the trapezoid rule of velocity Verlet, as for the
 * contacts; h = dt/2), then its prescribed velocity at the new time. */
static double kinematic_close(floe_world *w, int i, double h) {
    const floe_particles *p = &w->p;
    const double *fo = w->kin_old + 6 * i;
    double wb = 0;
    for (int k = 0; k < 3; k++)
        wb -= h * ((fo[k] + p->f[3 * i + k]) * p->v[3 * i + k] + (fo[3 + k] + p->t[3 * i + k]) * p->w[3 * i + k]);
    kinematic_velocity(w, i, w->time);
    return wb;
}

/* forces at the end of a step, with the history and the ledger advancing */
static int forces_advancing(floe_world *w) {
    w->advancing = 1;
    w->record_now = contacts_wanted(w);
    int rc = floe_compute_forces(w);
    w->advancing = 0;
    return rc;
}

static int check_particle(floe_world *w, int i, const double xold[3]) {
    floe_particles *p = &w->p;
    const double *x = p->x + 3 * i, *v = p->v + 3 * i, *om = p->w + 3 * i;
    for (int k = 0; k < 3; k++)
        if (!isfinite(x[k]) || !isfinite(v[k]) || !isfinite(om[k]))
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "unstable: particle %d (body %d) has a non-finite %s at step %ld, t = %g s "
                                    "(force %g %g %g N)",
                                    i, p->group[i], !isfinite(x[k]) ? "position" : !isfinite(v[k]) ? "velocity" : "angular velocity",
                                    w->step, w->time, p->f[3 * i], p->f[3 * i + 1], p->f[3 * i + 2]);
    double d[3];
    floe_v3_sub(d, x, xold);
    double moved = floe_v3_norm(d);
    if (moved > 0.5 * p->radius[i])
        return floe_world_error(w, FLOE_EUNSTABLE,
                                "unstable: particle %d (body %d) moved %.3g of its radius in one step at step %ld, "
                                "t = %g s (speed %g m/s): the time step %g s is too large for the contact stiffness "
                                "or the velocities",
                                i, p->group[i], moved / p->radius[i], w->step, w->time, floe_v3_norm(v), w->dt);
    return FLOE_OK;
}

/* largest squared distance of x from its position at the neighbour build, into *maxd2 */
static inline void note_disp(const double *x, const double *xb, double *maxd2) {
    double dx = x[0] - xb[0], dy = x[1] - xb[1], dz = x[2] - xb[2];
    double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 > *maxd2) *maxd2 = d2;
}

/* omega of free particle i from its angular momentum */
static inline void omega_update(floe_particles *p, int i) {
    if (p->iso[i]) {
        double inv = 1.0 / p->inertia[3 * i];
        for (int k = 0; k < 3; k++) p->w[3 * i + k] = p->L[3 * i + k] * inv;
    } else omega_from_L(p->q + 4 * i, p->inertia + 3 * i, p->L + 3 * i, p->w + 3 * i);
}

/* the orientation of free particle i over dt with its angular momentum L (eq 23 as the
 * midpoint rule of step_verlet: the isotropic fast path, or two fixed-point passes) */
static void rotate_drift(floe_particles *p, int i, double dt) {
    double *q = p->q + 4 * i, *L = p->L + 3 * i, *om = p->w + 3 * i;
    const double *I = p->inertia + 3 * i, h = 0.5 * dt;
    if (p->iso[i]) {
        double inv = 1.0 / I[0];
        for (int k = 0; k < 3; k++) om[k] = L[k] * inv;
        double th[3] = {h * om[0], h * om[1], h * om[2]}, t2 = floe_v3_dot(th, th);
        if (t2 > 0) {
            double c = 1 - 0.5 * t2, dq[4] = {c, th[0], th[1], th[2]}, qn[4];
            floe_q_mul(qn, dq, q);
            double s2 = qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3];
            double sc = 1.5 - 0.5 * s2;
            for (int k = 0; k < 4; k++) q[k] = qn[k] * sc;
        }
    } else if (floe_v3_dot(L, L) > 0) {
        double qm[4], omm[3], qn[4];
        omega_from_L(q, I, L, omm);
        q_advance(qm, q, omm, h);
        for (int it = 0; it < 2; it++) {
            omega_from_L(qm, I, L, omm);
            q_advance(qm, q, omm, h);
        }
        omega_from_L(qm, I, L, omm);
        q_advance(qn, q, omm, dt);
        memcpy(q, qn, sizeof qn);
        omega_from_L(q, I, L, om);
    }
}

/* state objects over the step, RK2 midpoint (eq 21) */
static int advance_states(floe_world *w, double dt) {
    const double h = 0.5 * dt;
    for (int s = 0; s < w->nstates; s++) {
        floe_state *st = w->states[s];
        size_t m = st->klass->size(st);
        double buf[64];
        double *y0 = m <= 16 ? buf : malloc(4 * m * sizeof(double));
        if (!y0) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        double *k1 = y0 + m, *ym = y0 + 2 * m, *k2 = y0 + 3 * m;
        w->err[0] = 0;
        st->klass->get(st, y0);
        int rc = st->klass->rhs(st, w, w->time, y0, k1);
        for (size_t a = 0; a < m && !rc; a++) ym[a] = y0[a] + h * k1[a];
        if (!rc) rc = st->klass->rhs(st, w, w->time + h, ym, k2);
        for (size_t a = 0; a < m && !rc; a++) ym[a] = y0[a] + dt * k2[a];
        if (!rc) rc = st->klass->set(st, w, ym);
        if (y0 != buf) free(y0);
        if (rc) { /* keep the state's own reason */
            char why[sizeof w->err];
            memcpy(why, w->err, sizeof why);
            return floe_world_error(w, rc, "state object %s failed at step %ld: %s", st->klass->name, w->step,
                                    why[0] ? why : floe_strerror(rc));
        }
    }
    return FLOE_OK;
}

/* the integrators' scratch: at least nd doubles (contents kept when it grows) */
static double *ibuf_reserve(floe_world *w, size_t nd) {
    if (nd <= w->ibuf_cap) return w->ibuf;
    double *b = realloc(w->ibuf, nd * sizeof *b);
    if (!b) return NULL;
    w->ibuf = b;
    w->ibuf_cap = nd;
    return b;
}

/* step counter and time after a step (no drift from repeated sums) */
static void advance_clock(floe_world *w) {
    w->step++;
    w->time = w->t0 + (double)(w->step - w->step0) * w->dt;
}

static int rebuild_if_needed(floe_world *w, double maxd2, int have_xb) {
    if (floe_nl_needs_rebuild_after_drift(&w->nl, &w->p, maxd2, !have_xb || w->nstates > 0)) {
        int rc = floe_nl_build(&w->nl, &w->p, w->def.dim, w->def.leaf_size);
        if (rc) return floe_world_error(w, rc, "neighbour list rebuild failed (out of memory)");
    }
    return FLOE_OK;
}

/* Velocity Verlet (ParticLS eq 22) and leapfrog (000 eq 44). Leapfrog keeps v_{n-1/2}:
 * its one kick per step v_{n+1/2} = v_{n-1/2} + dt a_n is velocity Verlet's two half kicks
 * merged, so both follow the same trajectory (to rounding); they differ in the velocity
 * they store (leapfrog: half a step behind the positions, as in the paper). */
static int step_verlet(floe_world *w) {
    floe_particles *p = &w->p;
    const double dt = w->dt, h = 0.5 * dt;
    const int n = p->n, leap = w->def.integrator == FLOE_LEAPFROG;
    /* leapfrog: the kick spans the two half steps around t_n; the first step after the
     * velocities were synchronised (start) spans half a step */
    const double k1 = leap ? 0.5 * (w->lf_dt_prev + dt) : h, k2 = leap ? 0.0 : h;
    double wb = 0;    /* body-force work this step */
    double maxd2 = 0; /* largest squared displacement since the neighbour build */
    const double *xb = w->nl.x_build;
    const int have_xb = xb && w->nl.n_build == n;
    /* 1. first half kick + drift (eq 22), rotation by the midpoint rule (eq 23) */
    for (int i = 0; i < n; i++) {
        double *x = p->x + 3 * i, *v = p->v + 3 * i, *q = p->q + 4 * i;
        if (p->motion[i] == FLOE_FIXED) continue;
        if (p->motion[i] == FLOE_KINEMATIC) {
            /* keep the force of the step's start for the trapezoid work of the boundary */
            memcpy(w->kin_old + 6 * i, p->f + 3 * i, 3 * sizeof(double));
            memcpy(w->kin_old + 6 * i + 3, p->t + 3 * i, 3 * sizeof(double));
            kinematic_velocity(w, i, w->time + h);
            floe_v3_axpy(x, dt, v);
            if (have_xb) note_disp(x, xb + 3 * i, &maxd2);
            double qn[4];
            q_advance(qn, q, p->w + 3 * i, dt);
            memcpy(q, qn, sizeof qn);
            continue;
        }
        double im = p->inv_mass[i];
        for (int k = 0; k < 3; k++) v[k] += k1 * im * p->f[3 * i + k];
        for (int k = 0; k < 3; k++) x[k] += dt * v[k];
        if (have_xb) note_disp(x, xb + 3 * i, &maxd2);
        /* body-force work over the step uses the drift displacement (exact for gravity
         * when the second half adds the same force) */
        /* rotation: L by the half kick, then the orientation over dt (rotate_drift: the
         * isotropic fast path q <- exp(dt omega / 2) q without trig, or the midpoint rule) */
        floe_v3_axpy(p->L + 3 * i, k1, p->t + 3 * i);
        rotate_drift(p, i, dt);
        wb += dt * (p->mass[i] * floe_v3_dot(w->def.gravity, v));
    }
    /* 2. state objects, RK2 midpoint (eq 21) */
    FLOE_TRY(advance_states(w, dt));
    advance_clock(w);
    /* 3. neighbours and forces at t + dt */
    FLOE_TRY(rebuild_if_needed(w, maxd2, have_xb));
    FLOE_TRY(forces_advancing(w));
    /* 4. second half kick (leapfrog: none; its kinetic energy is that of the synchronised
     * velocity v_{n+1/2} + dt/2 a_{n+1}) */
    double kt = 0, kr = 0, wbound = 0, sh = 0;
    const int shadow = w->def.energy_check != FLOE_CHECK_OFF;
    for (int i = 0; i < n; i++) {
        if (p->motion[i] != FLOE_FREE) {
            if (p->motion[i] == FLOE_KINEMATIC) wbound += kinematic_close(w, i, h);
            continue;
        }
        double *v = p->v + 3 * i, *L = p->L + 3 * i;
        double im = p->inv_mass[i];
        if (shadow) {
            double dv[3], dL[3];
            for (int k = 0; k < 3; k++) { dv[k] = h * im * p->f[3 * i + k]; dL[k] = h * p->t[3 * i + k]; }
            sh += shadow_term(p, i, dv, dL);
        }
        /* the drift of this step was dt * v_half: a particle that moved more than half its
         * radius, or whose state is not finite (NaN fails every comparison), is unstable */
        double d2 = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt * dt, lim = 0.5 * p->radius[i];
        double ke, kre;
        if (!leap) {
            for (int k = 0; k < 3; k++) v[k] += h * im * p->f[3 * i + k];
            floe_v3_axpy(L, h, p->t + 3 * i);
            if (p->iso[i]) {
                double inv = 1.0 / p->inertia[3 * i];
                for (int k = 0; k < 3; k++) p->w[3 * i + k] = L[k] * inv;
            } else omega_from_L(p->q + 4 * i, p->inertia + 3 * i, L, p->w + 3 * i);
            ke = 0.5 * p->mass[i] * floe_v3_dot(v, v);
            kre = 0.5 * floe_v3_dot(L, p->w + 3 * i);
        } else {
            double vs[3], Ls[3], ws[3];
            for (int k = 0; k < 3; k++) {
                vs[k] = v[k] + h * im * p->f[3 * i + k];
                Ls[k] = L[k] + h * p->t[3 * i + k];
            }
            if (p->iso[i]) {
                double inv = 1.0 / p->inertia[3 * i];
                for (int k = 0; k < 3; k++) ws[k] = Ls[k] * inv;
            } else omega_from_L(p->q + 4 * i, p->inertia + 3 * i, Ls, ws);
            ke = 0.5 * p->mass[i] * floe_v3_dot(vs, vs);
            kre = 0.5 * floe_v3_dot(Ls, ws);
        }
        kt += ke;
        kr += kre;
        if (!(d2 <= lim * lim) || !(ke + kre < INFINITY) || !(fabs(p->x[3 * i]) + fabs(p->x[3 * i + 1]) + fabs(p->x[3 * i + 2]) < INFINITY)) {
            double xold[3];
            for (int k = 0; k < 3; k++) xold[k] = p->x[3 * i + k] - dt * (v[k] - k2 * im * p->f[3 * i + k]);
            int rc = check_particle(w, i, xold);
            if (rc) return rc;
        }
    }
    if (leap) w->lf_dt_prev = dt;
    w->wd_shadow = sh;
    w->energy.kinetic_trans = kt;
    w->energy.kinetic_rot = kr;
    w->energy.work_body += wb;
    w->energy.work_boundary += wbound;
    return FLOE_OK;
}

/* Forces at the RK2 midpoint: the contact history is advanced by dt/2 from the step's
 * start (its midpoint value) and put back afterwards, the body-force and external-force
 * memories of the energy ledger too; nothing is booked in the ledger, no contact recorded,
 * and PD bonds do not break (their forces come from floe_pd_forces_nobreak). */
static int rk2_midpoint_forces(floe_world *w, double h) {
    floe_particles *p = &w->p;
    floe_neighbor_list *nl = &w->nl;
    const size_t np = (size_t)nl->npairs, nh = np * FLOE_MAX_HISTORY, nt = (np + 7) / 8;
    const size_t nfb = w->body_force && w->fb_old ? 6 * (size_t)w->fb_n : 0;
    size_t nbc = 0;
    for (int q = 0; q < w->npd_bc; q++)
        if (w->pd_bc[q]->fold) nbc += 3 * (size_t)w->pd_bc[q]->n;
    /* after the RK2 state (16 n doubles) */
    const size_t off = 16 * (size_t)p->n;
    double *b = ibuf_reserve(w, off + nh + nt + nfb + nbc);
    if (!b) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    double *hs = b + off, *fbs = hs + nh + nt, *bcs = fbs + nfb;
    unsigned char *ts = (unsigned char *)(hs + nh);
    if (np) {
        memcpy(hs, nl->hist, nh * sizeof *hs);
        memcpy(ts, nl->touching, np);
    }
    if (nfb) memcpy(fbs, w->fb_old, nfb * sizeof *fbs);
    for (int q = 0, o = 0; q < w->npd_bc; q++)
        if (w->pd_bc[q]->fold) {
            memcpy(bcs + o, w->pd_bc[q]->fold, 3 * (size_t)w->pd_bc[q]->n * sizeof *bcs);
            o += 3 * w->pd_bc[q]->n;
        }
    const int npd = w->npd;
    const double ec = w->elastic_contact;
    w->npd = 0; /* the bond forces below, without breakage */
    w->peek_dt = h;
    w->advancing = 0;
    w->record_now = 0;
    long rb = nl->rebuilds;
    int rc = floe_compute_forces_part(w, FLOE_FORCES_CONTACT);
    w->peek_dt = 0;
    w->npd = npd;
    w->elastic_contact = ec;
    w->st.force_evaluations++;
    if (rc) return rc;
    if (nl->rebuilds != rb) return floe_world_error(w, FLOE_EINVAL, "internal: neighbour list rebuilt at the RK2 midpoint");
    if (np) {
        memcpy(nl->hist, hs, nh * sizeof *hs);
        memcpy(nl->touching, ts, np);
    }
    if (nfb) memcpy(w->fb_old, fbs, nfb * sizeof *fbs);
    for (int q = 0, o = 0; q < w->npd_bc; q++)
        if (w->pd_bc[q]->fold) {
            memcpy(w->pd_bc[q]->fold, bcs + o, 3 * (size_t)w->pd_bc[q]->n * sizeof *bcs);
            o += 3 * w->pd_bc[q]->n;
        }
    for (int k = 0; k < npd; k++) {
        int f0 = w->pd_first[k];
        floe_pd_forces_nobreak(w->pd[k], p->x + 3 * (size_t)f0, p->f + 3 * (size_t)f0);
        if (w->def.dim == 2)
            for (int i = 0; i < w->pd[k]->n; i++) p->f[3 * (size_t)(f0 + i) + 2] = 0;
    }
    return FLOE_OK;
}

/* Explicit midpoint RK2 for the particles (ParticLS eq 21 with y = (x, v, q, L)):
 *   y_mid = y_n + dt/2 f(y_n);  y_{n+1} = y_n + dt f(y_mid).
 * The force at the end of the step, f(y_{n+1}), is evaluated with the midpoint velocities
 * (the velocities of the drift x_{n+1} - x_n = dt v_mid), like velocity Verlet's forces:
 * the contact history then grows by the tangential displacement of the step and the
 * energy ledger's trapezoid work is that of the actual displacement; that force only
 * enters the next step's midpoint, where an O(dt) error costs O(dt^3) locally. */
static int step_rk2(floe_world *w) {
    floe_particles *p = &w->p;
    const int n = p->n;
    const double dt = w->dt, h = 0.5 * dt, t_n = w->time;
    double *b = ibuf_reserve(w, 16 * (size_t)(n ? n : 1));
    if (!b) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    double *x0 = b, *v0 = b + 3 * (size_t)n, *L0 = b + 6 * (size_t)n, *q0 = b + 9 * (size_t)n;
    memcpy(x0, p->x, 3 * (size_t)n * sizeof *x0);
    memcpy(v0, p->v, 3 * (size_t)n * sizeof *v0);
    memcpy(L0, p->L, 3 * (size_t)n * sizeof *L0);
    memcpy(q0, p->q, 4 * (size_t)n * sizeof *q0);
    /* 1. the midpoint state */
    for (int i = 0; i < n; i++) {
        double *x = p->x + 3 * i, *v = p->v + 3 * i, *q = p->q + 4 * i;
        if (p->motion[i] == FLOE_FIXED) continue;
        if (p->motion[i] == FLOE_KINEMATIC) {
            memcpy(w->kin_old + 6 * i, p->f + 3 * i, 3 * sizeof(double));
            memcpy(w->kin_old + 6 * i + 3, p->t + 3 * i, 3 * sizeof(double));
            kinematic_velocity(w, i, t_n + h);
            floe_v3_axpy(x, h, v);
        } else {
            double im = p->inv_mass[i];
            floe_v3_axpy(x, h, v);
            for (int k = 0; k < 3; k++) v[k] += h * im * p->f[3 * i + k];
            floe_v3_axpy(p->L + 3 * i, h, p->t + 3 * i);
        }
        double qn[4];
        q_advance(qn, q, p->w + 3 * i, h);
        memcpy(q, qn, sizeof qn);
        if (p->motion[i] == FLOE_FREE) omega_update(p, i);
    }
    /* 2. forces at the midpoint */
    w->time = t_n + h;
    int rc = rk2_midpoint_forces(w, h);
    w->time = t_n;
    if (rc) return rc;
    b = w->ibuf; /* the midpoint's scratch may have moved it */
    x0 = b; v0 = b + 3 * (size_t)n; L0 = b + 6 * (size_t)n; q0 = b + 9 * (size_t)n;
    double *fm = b + 13 * (size_t)n; /* F_mid */
    memcpy(fm, p->f, 3 * (size_t)n * sizeof *fm);
    /* 3. x_{n+1} = x_n + dt v_mid, q_{n+1} = exp(dt w_mid) q_n; v, w stay at the midpoint
     * values for the forces at the end; v_{n+1}, L_{n+1} from the midpoint forces */
    double wb = 0, maxd2 = 0;
    const double *xb = w->nl.x_build;
    const int have_xb = xb && w->nl.n_build == n;
    for (int i = 0; i < n; i++) {
        if (p->motion[i] == FLOE_FIXED) continue;
        double *x = p->x + 3 * i;
        for (int k = 0; k < 3; k++) x[k] = x0[3 * i + k] + dt * p->v[3 * i + k];
        q_advance(p->q + 4 * i, q0 + 4 * i, p->w + 3 * i, dt);
        if (have_xb) note_disp(x, xb + 3 * i, &maxd2);
        if (p->motion[i] == FLOE_FREE) {
            wb += dt * (p->mass[i] * floe_v3_dot(w->def.gravity, p->v + 3 * i));
            for (int k = 0; k < 3; k++) L0[3 * i + k] += dt * p->t[3 * i + k]; /* L_{n+1} */
        }
    }
    FLOE_TRY(advance_states(w, dt));
    advance_clock(w);
    FLOE_TRY(rebuild_if_needed(w, maxd2, have_xb));
    FLOE_TRY(forces_advancing(w));
    /* 4. v_{n+1} = v_n + dt F_mid / m, L_{n+1} = L_n + dt T_mid */
    double kt = 0, kr = 0, wbound = 0;
    for (int i = 0; i < n; i++) {
        if (p->motion[i] != FLOE_FREE) {
            if (p->motion[i] == FLOE_KINEMATIC) wbound += kinematic_close(w, i, h);
            continue;
        }
        double *v = p->v + 3 * i, *L = p->L + 3 * i, im = p->inv_mass[i];
        double d2 = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt * dt, lim = 0.5 * p->radius[i];
        for (int k = 0; k < 3; k++) {
            v[k] = v0[3 * i + k] + dt * im * fm[3 * i + k];
            L[k] = L0[3 * i + k];
        }
        omega_update(p, i);
        double ke = 0.5 * p->mass[i] * floe_v3_dot(v, v), kre = 0.5 * floe_v3_dot(L, p->w + 3 * i);
        kt += ke;
        kr += kre;
        if (!(d2 <= lim * lim) || !(ke + kre < INFINITY) || !(fabs(p->x[3 * i]) + fabs(p->x[3 * i + 1]) + fabs(p->x[3 * i + 2]) < INFINITY)) {
            int rc2 = check_particle(w, i, x0 + 3 * i);
            if (rc2) return rc2;
        }
    }
    w->energy.kinetic_trans = kt;
    w->energy.kinetic_rot = kr;
    w->energy.work_body += wb;
    w->energy.work_boundary += wbound;
    return FLOE_OK;
}

/* ---- staggered PD-DEM (000 §3.2-3.3, Algorithm 2) ----
 * Two force groups: the contact and body forces F_C (DEM and coupling forces, gravity and
 * external forces, counted once as the paper requires) and the PD bond forces F_PD. With
 * dt_PD = dt / m the PD points sub-cycle m velocity Verlet steps with F_PD inside each
 * step, between two half kicks with F_C; with dt_PD = k dt, F_PD is applied as two half
 * kicks of k dt / 2 around every k steps of velocity Verlet with F_C. This is the
 * impulse form of multiple time stepping (r-RESPA, Tuckerman, Berne and Martyna 1992):
 * symmetric, second order and symplectic, and with m = k = 1 it is velocity Verlet (the
 * monolithic scheme) with the two groups evaluated separately. The scratch w->ibuf holds
 * F_C, its torques and F_PD between steps (3n each), then the start positions and the
 * true velocities of the PD points (3n each). */

static void stag_zero_pd_forces(floe_world *w) {
    for (int k = 0; k < w->npd; k++)
        memset(w->p.f + 3 * (size_t)w->pd_first[k], 0, 3 * (size_t)w->pd[k]->n * sizeof(double));
}

/* evaluate F_C then F_PD at the present state (prepare), p->f = their sum */
static int stag_split_forces(floe_world *w) {
    floe_particles *p = &w->p;
    const size_t n3 = 3 * (size_t)p->n;
    double *b = ibuf_reserve(w, 5 * (n3 ? n3 : 3));
    if (!b) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    double *fs = b, *ts = b + n3, *fpd = b + 2 * n3;
    FLOE_TRY(floe_compute_forces_part(w, FLOE_FORCES_CONTACT));
    memcpy(fs, p->f, n3 * sizeof *fs);
    memcpy(ts, p->t, n3 * sizeof *ts);
    memset(p->f, 0, n3 * sizeof *p->f);
    FLOE_TRY(floe_compute_forces_part(w, FLOE_FORCES_PD));
    memcpy(fpd, p->f, n3 * sizeof *fpd);
    for (size_t a = 0; a < n3; a++) p->f[a] = fs[a] + fpd[a];
    memcpy(p->t, ts, n3 * sizeof *ts);
    return FLOE_OK;
}

/* PD bond forces at the present positions into fpd, with the PD points moving at their
 * mean velocity (x - xs) / span for the ledger's trapezoid work over that span */
static int stag_pd_forces(floe_world *w, double span, const double *xs, double *vt, double *fpd, int mean_velocity) {
    floe_particles *p = &w->p;
    const double dt = w->dt;
    for (int k = 0; k < w->npd; k++)
        for (int i = w->pd_first[k]; i < w->pd_first[k] + w->pd[k]->n; i++)
            if (mean_velocity) {
                memcpy(vt + 3 * i, p->v + 3 * i, 3 * sizeof(double));
                for (int a = 0; a < 3; a++) p->v[3 * i + a] = (p->x[3 * i + a] - xs[3 * i + a]) / span;
            }
    stag_zero_pd_forces(w);
    w->dt = span;
    w->advancing = 1;
    int rc = floe_compute_forces_part(w, FLOE_FORCES_PD);
    w->advancing = 0;
    w->dt = dt;
    for (int k = 0; k < w->npd; k++) {
        size_t f0 = 3 * (size_t)w->pd_first[k], m = 3 * (size_t)w->pd[k]->n;
        memcpy(fpd + f0, p->f + f0, m * sizeof *fpd);
        if (mean_velocity) memcpy(p->v + f0, vt + f0, m * sizeof *vt);
    }
    return rc;
}

static int step_staggered(floe_world *w) {
    floe_particles *p = &w->p;
    const int n = p->n, m = w->pd_sub, ke = w->pd_every;
    const size_t n3 = 3 * (size_t)n;
    const double dt = w->dt, h = 0.5 * dt, K = ke * dt;
    double *b = ibuf_reserve(w, 5 * (n3 ? n3 : 3));
    if (!b) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    double *fs = b, *ts = b + n3, *fpd = b + 2 * n3, *xs = b + 3 * n3, *vt = b + 4 * n3;
    const long cyc = ke > 1 ? w->pd_cycle % ke : 0;
    const int pd_start = ke > 1 && cyc % ke == 0, pd_end = ke > 1 && (cyc + 1) % ke == 0;
    const int *pd_of = w->pd_of;
    double wb = 0, maxd2 = 0;
    /* PD every k-th step: the opening half kick of a PD cycle */
    if (pd_start)
        for (int k = 0; k < w->npd; k++)
            for (int i = w->pd_first[k]; i < w->pd_first[k] + w->pd[k]->n; i++) {
                memcpy(xs + 3 * i, p->x + 3 * i, 3 * sizeof(double));
                if (p->motion[i] == FLOE_FREE) floe_v3_axpy(p->v + 3 * i, 0.5 * K * p->inv_mass[i], fpd + 3 * i);
            }
    /* 1. half kick with F_C; drift of everything except the PD points that sub-cycle */
    for (int i = 0; i < n; i++) {
        double *x = p->x + 3 * i, *v = p->v + 3 * i;
        const int sub = ke == 1 && pd_of[i] >= 0;
        if (sub) memcpy(xs + 3 * i, x, 3 * sizeof(double)); /* fixed points too: step 3 reads it */
        if (p->motion[i] == FLOE_FIXED) continue;
        if (p->motion[i] == FLOE_KINEMATIC) {
            memcpy(w->kin_old + 6 * i, p->f + 3 * i, 3 * sizeof(double));
            memcpy(w->kin_old + 6 * i + 3, p->t + 3 * i, 3 * sizeof(double));
            kinematic_velocity(w, i, w->time + h);
            if (!sub) floe_v3_axpy(x, dt, v);
            double qn[4];
            q_advance(qn, p->q + 4 * i, p->w + 3 * i, dt);
            memcpy(p->q + 4 * i, qn, sizeof qn);
            continue;
        }
        floe_v3_axpy(v, h * p->inv_mass[i], fs + 3 * i);
        floe_v3_axpy(p->L + 3 * i, h, ts + 3 * i);
        rotate_drift(p, i, dt);
        if (!sub) {
            floe_v3_axpy(x, dt, v);
            wb += dt * (p->mass[i] * floe_v3_dot(w->def.gravity, v));
        }
    }
    /* 2. dt_PD = dt / m: m velocity Verlet sub-steps of the PD points with F_PD */
    if (ke == 1) {
        const double d = dt / m, hd = 0.5 * d;
        for (int s = 0; s < m; s++) {
            for (int k = 0; k < w->npd; k++)
                for (int i = w->pd_first[k]; i < w->pd_first[k] + w->pd[k]->n; i++) {
                    double *v = p->v + 3 * i;
                    if (p->motion[i] == FLOE_FIXED) continue;
                    if (p->motion[i] == FLOE_FREE) floe_v3_axpy(v, hd * p->inv_mass[i], fpd + 3 * i);
                    floe_v3_axpy(p->x + 3 * i, d, v);
                    if (p->motion[i] == FLOE_FREE) wb += d * (p->mass[i] * floe_v3_dot(w->def.gravity, v));
                }
            FLOE_TRY(stag_pd_forces(w, d, xs, vt, fpd, 0));
            if (s == m - 1) break; /* the last sub-step closes with the final kick below */
            for (int k = 0; k < w->npd; k++)
                for (int i = w->pd_first[k]; i < w->pd_first[k] + w->pd[k]->n; i++)
                    if (p->motion[i] == FLOE_FREE) floe_v3_axpy(p->v + 3 * i, hd * p->inv_mass[i], fpd + 3 * i);
        }
    }
    FLOE_TRY(advance_states(w, dt));
    advance_clock(w);
    w->pd_cycle++;
    const double *xb = w->nl.x_build;
    const int have_xb = xb && w->nl.n_build == n;
    if (have_xb)
        for (int i = 0; i < n; i++)
            if (p->motion[i] != FLOE_FIXED) note_disp(p->x + 3 * i, xb + 3 * i, &maxd2);
    FLOE_TRY(rebuild_if_needed(w, maxd2, have_xb));
    /* 3. F_C at the new positions; sub-cycled PD points move at their mean velocity over
     * the step for the contact laws (the tangential spring grows by the displacement) and
     * the ledger */
    if (ke == 1)
        for (int k = 0; k < w->npd; k++)
            for (int i = w->pd_first[k]; i < w->pd_first[k] + w->pd[k]->n; i++) {
                memcpy(vt + 3 * i, p->v + 3 * i, 3 * sizeof(double));
                for (int a = 0; a < 3; a++) p->v[3 * i + a] = (p->x[3 * i + a] - xs[3 * i + a]) / dt;
            }
    w->advancing = 1;
    w->record_now = contacts_wanted(w);
    int rc = floe_compute_forces_part(w, FLOE_FORCES_CONTACT);
    w->advancing = 0;
    if (ke == 1)
        for (int k = 0; k < w->npd; k++)
            memcpy(p->v + 3 * (size_t)w->pd_first[k], vt + 3 * (size_t)w->pd_first[k], 3 * (size_t)w->pd[k]->n * sizeof *vt);
    if (rc) return rc;
    memcpy(fs, p->f, n3 * sizeof *fs);
    memcpy(ts, p->t, n3 * sizeof *ts);
    /* PD every k-th step: the closing evaluation and half kick of the cycle */
    if (pd_end) {
        FLOE_TRY(stag_pd_forces(w, K, xs, vt, fpd, 1));
        for (int k = 0; k < w->npd; k++)
            for (int i = w->pd_first[k]; i < w->pd_first[k] + w->pd[k]->n; i++)
                if (p->motion[i] == FLOE_FREE) floe_v3_axpy(p->v + 3 * i, 0.5 * K * p->inv_mass[i], fpd + 3 * i);
    }
    /* 4. closing half kick with F_C; p->f = F_C + F_PD for the observers */
    for (size_t a = 0; a < n3; a++) p->f[a] = fs[a] + fpd[a];
    double kt = 0, kr = 0, wbound = 0, sh = 0;
    const int shadow = w->def.energy_check != FLOE_CHECK_OFF;
    for (int i = 0; i < n; i++) {
        if (p->motion[i] != FLOE_FREE) {
            if (p->motion[i] == FLOE_KINEMATIC) wbound += kinematic_close(w, i, h);
            continue;
        }
        double *v = p->v + 3 * i, *L = p->L + 3 * i, im = p->inv_mass[i];
        if (shadow) { /* the closing kicks: the last PD sub-step's and F_C's */
            double dv[3], dL[3];
            for (int k = 0; k < 3; k++) {
                dv[k] = h * im * fs[3 * i + k] + (ke == 1 && pd_of[i] >= 0 ? 0.5 * dt / m * im * fpd[3 * i + k] : 0);
                dL[k] = h * ts[3 * i + k];
            }
            sh += shadow_term(p, i, dv, dL);
        }
        double xold[3], d2;
        if (ke == 1 && pd_of[i] >= 0) memcpy(xold, xs + 3 * i, sizeof xold);
        else for (int k = 0; k < 3; k++) xold[k] = p->x[3 * i + k] - dt * v[k];
        d2 = (p->x[3 * i] - xold[0]) * (p->x[3 * i] - xold[0]) + (p->x[3 * i + 1] - xold[1]) * (p->x[3 * i + 1] - xold[1]) +
             (p->x[3 * i + 2] - xold[2]) * (p->x[3 * i + 2] - xold[2]);
        if (ke == 1 && pd_of[i] >= 0) floe_v3_axpy(v, 0.5 * dt / m * im, fpd + 3 * i); /* last PD sub-step */
        floe_v3_axpy(v, h * im, fs + 3 * i);
        floe_v3_axpy(L, h, ts + 3 * i);
        omega_update(p, i);
        double kin = 0.5 * p->mass[i] * floe_v3_dot(v, v), kre = 0.5 * floe_v3_dot(L, p->w + 3 * i);
        kt += kin;
        kr += kre;
        double lim = 0.5 * p->radius[i];
        if (!(d2 <= lim * lim) || !(kin + kre < INFINITY)) {
            int rc2 = check_particle(w, i, xold);
            if (rc2) return rc2;
        }
    }
    w->wd_shadow = sh;
    w->energy.kinetic_trans = kt;
    w->energy.kinetic_rot = kr;
    w->energy.work_body += wb;
    w->energy.work_boundary += wbound;
    return FLOE_OK;
}

/* ---- adaptive steps (003 §4.3) ----
 * A trial step is taken from a saved state; it is accepted when
 *   eta_v = max_i |v_i(t+dt) - v_i(t)| dt / R_i <= adapt_velocity_tol  and
 *   eta_d = max_contacts |v_n| dt / min(R_i, R_j) <= adapt_depth_tol
 * (the velocity change and the overlap change over the step relative to the particle
 * size), else the state is restored and the step redone with a smaller dt (also when the
 * trial went unstable); the next step grows by the same criterion, at most 2x, within
 * [dt_min, dt_max]. A trial that rebuilt the neighbour list (the contact history changes
 * its layout) cannot be undone and is accepted: the list is rebuilt before a trial whose
 * drift could pass the skin. */

typedef struct floe_snapshot {
    double *d; size_t dcap;
    unsigned char *c; size_t ccap;
    floe_energy energy;
    double elastic_contact, elastic_pd, time, t0;
    double wd_shadow, wd_shadow0;
    long step, step0;
} floe_snapshot;

static void snapshot_free(floe_snapshot *s) {
    if (!s) return;
    free(s->d);
    free(s->c);
    free(s);
}

/* sizes of what a step changes: particle state (22 n), pair history, ledger memories,
 * PD forces and broken flags, state objects */
static void snapshot_sizes(const floe_world *w, size_t *nd, size_t *nc) {
    size_t d = 22 * (size_t)w->p.n + FLOE_MAX_HISTORY * (size_t)w->nl.npairs, c = (size_t)w->nl.npairs;
    if (w->body_force && w->fb_old) d += 6 * (size_t)w->fb_n;
    for (int q = 0; q < w->npd_bc; q++)
        if (w->pd_bc[q]->fold) d += 3 * (size_t)w->pd_bc[q]->n;
    if (w->npd) d += 3 * (size_t)w->pd_npts + 4 * (size_t)w->npd;
    for (int k = 0; k < w->npd; k++) {
        c += (size_t)w->pd[k]->nbond;
        if (w->pd[k]->s0) d += 2 * (size_t)w->pd[k]->n; /* PMB alpha: per-point critical stretch */
        if (w->pd[k]->splast) d += ((size_t)w->pd[k]->nbond * sizeof(float) + sizeof(double) - 1) / sizeof(double);
    }
    for (int s = 0; s < w->nstates; s++) d += w->states[s]->klass->size(w->states[s]);
    *nd = d;
    *nc = c;
}

#define SNAP_COPY(save, a, b, nbytes) \
    do { if ((nbytes) > 0) { if (save) memcpy((a), (b), (nbytes)); else memcpy((b), (a), (nbytes)); } } while (0)

static int snapshot_io(floe_world *w, int save) {
    floe_snapshot *s = w->snap;
    floe_particles *p = &w->p;
    if (save) {
        size_t nd, nc;
        snapshot_sizes(w, &nd, &nc);
        if (nd > s->dcap) {
            double *d = realloc(s->d, nd * sizeof *d);
            if (!d) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            s->d = d;
            s->dcap = nd;
        }
        if (nc > s->ccap) {
            unsigned char *c = realloc(s->c, nc ? nc : 1);
            if (!c) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            s->c = c;
            s->ccap = nc;
        }
        s->energy = w->energy;
        s->elastic_contact = w->elastic_contact;
        s->elastic_pd = w->elastic_pd;
        s->wd_shadow = w->wd_shadow;
        s->wd_shadow0 = w->wd_shadow0;
        s->time = w->time;
        s->t0 = w->t0;
        s->step = w->step;
        s->step0 = w->step0;
    }
    double *d = s->d;
    unsigned char *c = s->c;
    const size_t n = (size_t)p->n;
    /* state objects first: set() may rescale a particle's mass, inertia and momentum,
     * which are restored after */
    for (int k = 0; k < w->nstates; k++) {
        floe_state *st = w->states[k];
        size_t m = st->klass->size(st);
        if (save) st->klass->get(st, d);
        else {
            int rc = st->klass->set(st, w, d);
            if (rc) return floe_world_error(w, rc, "state object %s could not be restored", st->klass->name);
        }
        d += m;
    }
    SNAP_COPY(save, d, p->x, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->v, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->q, 4 * n * sizeof *d); d += 4 * n;
    SNAP_COPY(save, d, p->L, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->w, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->f, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->t, 3 * n * sizeof *d); d += 3 * n;
    size_t np = (size_t)w->nl.npairs;
    SNAP_COPY(save, d, w->nl.hist, FLOE_MAX_HISTORY * np * sizeof *d); d += FLOE_MAX_HISTORY * np;
    SNAP_COPY(save, c, w->nl.touching, np); c += np;
    if (w->body_force && w->fb_old) { SNAP_COPY(save, d, w->fb_old, 6 * (size_t)w->fb_n * sizeof *d); d += 6 * (size_t)w->fb_n; }
    for (int q = 0; q < w->npd_bc; q++)
        if (w->pd_bc[q]->fold) {
            size_t m = 3 * (size_t)w->pd_bc[q]->n;
            SNAP_COPY(save, d, w->pd_bc[q]->fold, m * sizeof *d);
            d += m;
        }
    if (w->npd) {
        SNAP_COPY(save, d, w->pd_fold, 3 * (size_t)w->pd_npts * sizeof *d); d += 3 * (size_t)w->pd_npts;
        for (int k = 0; k < w->npd; k++) {
            floe_pd_body *b = w->pd[k];
            if (save) {
                d[0] = w->pd_eold[k]; d[1] = (double)b->nbroken; d[2] = (double)w->pd_nbroken_seen[k];
                d[3] = k < w->pd_diss_n ? w->pd_diss[k] : 0;
            } else {
                w->pd_eold[k] = d[0]; b->nbroken = (int64_t)d[1]; w->pd_nbroken_seen[k] = (long long)d[2];
                if (k < w->pd_diss_n) w->pd_diss[k] = d[3];
            }
            d += 4;
            SNAP_COPY(save, c, b->broken, (size_t)b->nbond);
            c += b->nbond;
            if (b->s0) {
                SNAP_COPY(save, d, b->s0, 2 * (size_t)b->n * sizeof *d);
                d += 2 * (size_t)b->n;
            }
            if (b->splast) { /* PMB plastic stretches (floats, packed into the double store) */
                SNAP_COPY(save, d, b->splast, (size_t)b->nbond * sizeof(float));
                d += ((size_t)b->nbond * sizeof(float) + sizeof(double) - 1) / sizeof(double);
            }
        }
    }
    if (!save) {
        w->energy = s->energy;
        w->elastic_contact = s->elastic_contact;
        w->elastic_pd = s->elastic_pd;
        w->wd_shadow = s->wd_shadow;
        w->wd_shadow0 = s->wd_shadow0;
        w->time = s->time;
        w->t0 = s->t0;
        w->step = s->step;
        w->step0 = s->step0;
    }
    return FLOE_OK;
}

static int step_once(floe_world *w) {
    if (w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd) return step_staggered(w);
    if (w->def.integrator == FLOE_RK2) return step_rk2(w);
    return step_verlet(w);
}

/* the largest displacement from the neighbour build that the next drift of dt can reach
 * (velocity Verlet and RK2 both move by dt (v + dt/2 F/m)) */
static double predicted_disp2(const floe_world *w, double dt) {
    const floe_particles *p = &w->p;
    const double *xb = w->nl.x_build;
    if (!xb || w->nl.n_build != p->n) return INFINITY;
    double m2 = 0;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] == FLOE_FIXED) continue;
        double y[3];
        for (int k = 0; k < 3; k++)
            y[k] = p->x[3 * i + k] + dt * (p->v[3 * i + k] + 0.5 * dt * p->inv_mass[i] * p->f[3 * i + k]);
        note_disp(y, xb + 3 * i, &m2);
    }
    return m2;
}

static int step_adaptive(floe_world *w) {
    floe_particles *p = &w->p;
    const double tv = w->def.adapt_velocity_tol, td = w->def.adapt_depth_tol;
    if (!w->snap) {
        w->snap = calloc(1, sizeof *w->snap);
        if (!w->snap) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    for (;;) {
        double dt = fmin(w->dt_next, w->dt_cap);
        if (dt != w->dt) { /* the clock restarts from here at the new step */
            w->t0 = w->time;
            w->step0 = w->step;
            /* the watchdog's conserved form at the new step (the half kick grows as dt):
             * the same state, so its balance goes on continuously */
            double r2 = (dt / w->dt) * (dt / w->dt);
            w->wd_shadow0 += w->wd_shadow * (r2 - 1);
            w->wd_shadow *= r2;
            w->dt = dt;
        }
        double lim = 0.5 * w->nl.skin;
        if (predicted_disp2(w, dt) > lim * lim) {
            int rc = floe_nl_build(&w->nl, p, w->def.dim, w->def.leaf_size);
            if (rc) return floe_world_error(w, rc, "neighbour list rebuild failed (out of memory)");
        }
        FLOE_TRY(snapshot_io(w, 1));
        const long rb = w->nl.rebuilds;
        w->track_depth = 1;
        int rc = step_once(w);
        w->track_depth = 0;
        const int undoable = w->nl.rebuilds == rb;
        double eta_v = 0, eta_d = w->eta_depth;
        if (!rc) {
            const double *v0 = w->snap->d + 3 * (size_t)p->n; /* after x (states first) */
            size_t so = 0;
            for (int s = 0; s < w->nstates; s++) so += w->states[s]->klass->size(w->states[s]);
            v0 += so;
            for (int i = 0; i < p->n; i++) {
                if (p->motion[i] != FLOE_FREE || !isfinite(p->radius[i])) continue;
                double dv[3];
                floe_v3_sub(dv, p->v + 3 * i, v0 + 3 * i);
                double e = floe_v3_norm(dv) * dt / p->radius[i];
                if (e > eta_v) eta_v = e;
            }
        }
        /* step factor from the criterion: eta_v grows as dt^2 (a dt^2), eta_d as dt */
        double fv = eta_v > 0 ? sqrt(tv / eta_v) : INFINITY, fd = eta_d > 0 ? td / eta_d : INFINITY;
        double f = 0.9 * fmin(fv, fd);
        const int at_min = dt <= w->dt_lo * (1 + 1e-9);
        if ((rc == FLOE_EUNSTABLE || (rc == FLOE_OK && (eta_v > tv || eta_d > td))) && undoable && !at_min) {
            FLOE_TRY(snapshot_io(w, 0));
            w->st.rejected++;
            f = rc ? 0.25 : fmax(0.1, fmin(0.9, f));
            w->dt_next = fmax(w->dt_lo, dt * f);
            w->err[0] = 0;
            continue;
        }
        if (rc) return rc;
        f = fmax(0.1, fmin(2.0, f));
        if (!(dt < w->dt_next) || f < 1) w->dt_next = fmin(w->dt_hi, fmax(w->dt_lo, dt * f));
        return FLOE_OK;
    }
}

/* ---- energy watchdog ----
 * After every accepted step: energy created beyond tol x the energy scale (the largest
 * K + elastic + |work_body| + |work_boundary| seen, at least sum m |g| R over the free
 * particles) stops the run (or warns once). Four
 * measures, each O(1) or O(PD bodies) per step: the contact with the most negative
 * dissipation over its life (forces.c keeps it in the pair's history), each PD body's bond
 * dissipation, the ledger's total dissipation, and the balance error (energy that appeared
 * outside the ledger: the integration). The diagnosis below runs only when one trips. */

const char *floe_energy_check_name(int mode) {
    static const char *const names[] = {"stop", "warn", "off"};
    return mode >= FLOE_CHECK_STOP && mode <= FLOE_CHECK_OFF ? names[mode] : NULL;
}

int floe_world_set_energy_check(floe_world *w, int mode, double tol) {
    if (!floe_energy_check_name(mode) || !(tol >= 0 && tol < 1))
        return floe_world_error(w, FLOE_EINVAL, "energy check: mode %d (stop, warn or off) or tolerance %g (in [0, 1)) "
                                "invalid", mode, tol);
    w->def.energy_check = mode;
    w->def.energy_check_tol = tol > 0 ? tol : 0.05;
    return FLOE_OK;
}

int floe_world_energy_check(const floe_world *w, floe_energy_check_state *out) {
    out->mode = w->def.energy_check;
    out->tolerance = w->def.energy_check_tol;
    out->scale = w->wd_scale;
    out->created = w->wd_created;
    out->tripped_step = w->wd_step;
    out->message = w->wd_msg;
    return FLOE_OK;
}

/* kinetic + elastic energy of PD body k (J) */
static double pd_body_energy(const floe_world *w, int k) {
    const floe_particles *p = &w->p;
    double e = w->pd_eold ? w->pd_eold[k] : 0;
    for (int i = w->pd_first[k]; i < w->pd_first[k] + w->pd[k]->n; i++)
        if (p->motion[i] == FLOE_FREE) e += 0.5 * p->mass[i] * floe_v3_dot(p->v + 3 * i, p->v + 3 * i);
    return e;
}

/* "PD body k (particles a..b)" into buf */
static void pd_body_name(const floe_world *w, int k, char *buf, size_t len) {
    snprintf(buf, len, "PD body %d (particles %d..%d)", k, w->pd_first[k], w->pd_first[k] + w->pd[k]->n - 1);
}

/* the likely cause when PD bodies run staggered with several rates (else "") */
static const char *stag_cause(const floe_world *w, char *buf, size_t len) {
    buf[0] = 0;
    if (w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd && (w->pd_sub > 1 || w->pd_every > 1))
        snprintf(buf, len, "staggered PD-DEM with %s %d: the contact impulses on the PD points resonate with the "
                 "body's modes (the step %g s is too long for them); use fewer substeps (or scheme: monolithic) "
                 "or a smaller dt", w->pd_every > 1 ? "every" : "substeps", w->pd_every > 1 ? w->pd_every : w->pd_sub,
                 w->dt);
    return buf;
}

static int energy_watchdog(floe_world *w) {
    if (w->def.energy_check == FLOE_CHECK_OFF) return FLOE_OK;
    const floe_energy *e = &w->energy;
    const double cur = e->kinetic_trans + e->kinetic_rot + e->elastic;
    double sc = fmax(fmax(cur + fabs(e->work_body) + fabs(e->work_boundary), fabs(e->initial)), w->wd_gscale);
    if (sc > w->wd_scale) w->wd_scale = sc;
    const double S = w->wd_scale, tol = w->def.energy_check_tol;
    if (!(S > 0)) return FLOE_OK;
    double c_pair = -w->wd_pair_min / S, c_pd = 0, c_led = -(e->dissipated + e->elastic) / S;
    /* the balance in the form velocity Verlet conserves (shadow_term) */
    double c_bal = (cur - w->wd_shadow + e->dissipated - (e->initial - w->wd_shadow0) - e->work_body - e->work_boundary) / S;
    int kb = -1;
    for (int k = 0; k < w->npd && k < w->pd_diss_n; k++)
        if (-w->pd_diss[k] / S > c_pd) { c_pd = -w->pd_diss[k] / S; kb = k; }
    /* above half the critical step the measured energy of forces that are not linear (or
     * not exactly the gradient of the reported energy, as beam bonds) oscillates by tens of
     * per cent at a stable step (26 % at 0.95 x the bond limit, tests/test_beam.c): there
     * the balance trips only when half the scale appeared (an instability passes that in a
     * few steps) */
    const double tol_bal = w->dt > 0.5 * w->dt_crit ? fmax(tol, 0.5) : tol;
    double created = fmax(fmax(c_pair, c_pd), fmax(c_led, c_bal));
    if (created > w->wd_created) w->wd_created = created;
    /* (NaN passes no test: the particle checks report it) */
    if (!(c_pair > tol || c_pd > tol || c_led > tol || c_bal > tol_bal)) return FLOE_OK;
    if (w->wd_step >= 0 && w->def.energy_check == FLOE_CHECK_WARN) return FLOE_OK; /* warned once */
    char what[256], cause[512], name[96];
    const floe_particles *p = &w->p;
    stag_cause(w, cause, sizeof cause);
    if (c_pair > tol || (c_led > tol && c_pd <= tol && w->wd_worst < 0)) {
        /* a contact: this step's worst, or the run's worst when the ledger as a whole went negative */
        int i = c_pair > tol ? w->wd_pair_i : w->wd_worst_i, j = c_pair > tol ? w->wd_pair_j : w->wd_worst_j;
        double d = c_pair > tol ? w->wd_pair_min : w->wd_worst;
        const floe_contact_law *law = w->laws[p->material[i] * w->nmats + p->material[j]];
        const int pdk = w->pd_of ? (w->pd_of[i] >= 0 ? w->pd_of[i] : w->pd_of[j]) : -1;
        name[0] = 0;
        if (pdk >= 0) {
            char pn[80];
            pd_body_name(w, pdk, pn, sizeof pn);
            snprintf(name, sizeof name, ", a point of %s", pn);
        }
        snprintf(what, sizeof what, "the contact of particles %d and %d (bodies %d, %d%s; law %s) gave back %.3g J "
                 "more than it received since it began", i, j, p->group[i], p->group[j], name,
                 law ? law->klass->name : "?", -d);
        if (!cause[0] || pdk < 0)
            snprintf(cause, sizeof cause, "the contact law creates energy (negative damping, or unloading stiffer "
                     "than loading), or the step %g s is too large for its stiffness", w->dt);
    } else if (c_pd > tol || (c_led > tol && kb >= 0)) {
        pd_body_name(w, kb, name, sizeof name);
        snprintf(what, sizeof what, "the bonds of %s gave back %.3g J more than they took", name, -w->pd_diss[kb]);
        if (!cause[0])
            snprintf(cause, sizeof cause, "the bond forces' integration is unstable: the step %g s is too large "
                     "for the bond stiffness", w->dt);
    } else {
        /* energy appeared outside the ledger: name the PD body or particle that holds most */
        double best = -1;
        int bi = -1;
        kb = -1;
        for (int k = 0; k < w->npd; k++) {
            double eb = pd_body_energy(w, k);
            if (eb > best) { best = eb; kb = k; }
        }
        if (kb >= 0) pd_body_name(w, kb, name, sizeof name);
        if (!cause[0] || kb < 0) {
            best = -1;
            for (int i = 0; i < p->n; i++)
                if (p->motion[i] == FLOE_FREE && (!w->pd_of || w->pd_of[i] < 0 || !cause[0])) {
                    double ek = 0.5 * p->mass[i] * floe_v3_dot(p->v + 3 * i, p->v + 3 * i);
                    if (ek > best) { best = ek; bi = i; }
                }
            if (bi >= 0 && (!cause[0] || kb < 0)) {
                if (w->pd_of && w->pd_of[bi] >= 0) pd_body_name(w, w->pd_of[bi], name, sizeof name);
                else snprintf(name, sizeof name, "particle %d (body %d)", bi, p->group[bi]);
            }
            if (!cause[0]) {
                const floe_geometry_class *gk = bi >= 0 ? w->geoms[p->geom[bi]]->klass : NULL;
                const int poly = gk == &floe_box_class || gk == &floe_polytope_class || gk == &floe_compound_class;
                snprintf(cause, sizeof cause, "the integration created it: the step %g s is too large for the "
                         "stiffness, or a force is not conservative (a body-force callback)%s; lower dt or safety",
                         w->dt, poly ? ", or a polytope contact under a point law (linear, Hertz) crossed a kink of "
                         "the deepest-point depth (an edge lying on a face: docs/models.md, \"Contact manifold\"; "
                         "model: overlap_area has none)" : "");
            }
        }
        snprintf(what, sizeof what, "the energy grew %.3g J beyond the ledger (balance error), most of it in %s",
                 c_bal * S, bi >= 0 || kb >= 0 ? name : "?");
    }
    snprintf(w->wd_msg, sizeof w->wd_msg,
             "energy watchdog: %.1f %% of the energy scale %.3g J created by step %ld (t = %g s): %s; likely cause: %s",
             100 * created, S, w->step, w->time, what, cause);
    if (w->wd_step < 0) w->wd_step = w->step;
    if (w->def.energy_check == FLOE_CHECK_WARN) {
        fprintf(stderr, "floe: warning: %s (checks: energy: warn, the run goes on)\n", w->wd_msg);
        return FLOE_OK;
    }
    return floe_world_error(w, FLOE_EUNSTABLE, "%s", w->wd_msg);
}

int floe_world_step(floe_world *w) {
    if (!w->prepared) FLOE_TRY(floe_world_prepare(w));
    int rc = w->def.adaptive ? step_adaptive(w) : step_once(w);
    if (rc) return rc;
    floe_step_stats *s = &w->st;
    s->accepted++;
    if (s->dt_min_used == 0 || w->dt < s->dt_min_used) s->dt_min_used = w->dt;
    if (w->dt > s->dt_max_used) s->dt_max_used = w->dt;
    FLOE_TRY(energy_watchdog(w));
    return observers_call(w, 0);
}

int floe_world_run(floe_world *w, double t_end, floe_progress_fn progress, void *user) {
    int rc = floe_world_prepare(w);
    if (rc) { floe_world_finish(w); return rc; }
    if (!w->def.adaptive) {
        long nsteps = (long)ceil((t_end - w->time) / w->dt - 1e-9);
        if (nsteps < 0) nsteps = 0;
        for (long s = 0; s < nsteps; s++) {
            w->last_step_of_run = s == nsteps - 1;
            rc = floe_world_step(w);
            w->last_step_of_run = 0;
            if (rc) break;
            if (progress && progress(w, s + 1, nsteps, user)) {
                rc = floe_world_error(w, FLOE_ESTOP, "stopped by the progress callback at step %ld", w->step);
                break;
            }
        }
    } else {
        /* adaptive: steps until t_end, the last one cut to end there */
        const double eps = 1e-9 * w->dt_lo;
        for (long s = 0; w->time < t_end - eps; s++) {
            w->dt_cap = t_end - w->time;
            w->last_step_of_run = w->dt_next >= w->dt_cap - eps;
            rc = floe_world_step(w);
            w->last_step_of_run = 0;
            w->dt_cap = INFINITY;
            if (rc) break;
            long left = (long)ceil((t_end - w->time) / w->dt_next - 1e-9);
            if (progress && progress(w, s + 1, s + 1 + (left > 0 ? left : 0), user)) {
                rc = floe_world_error(w, FLOE_ESTOP, "stopped by the progress callback at step %ld", w->step);
                break;
            }
        }
    }
    if (rc && rc != FLOE_ESTOP) {
        /* flush the state at failure so the outputs show what happened */
        char keep[sizeof w->err];
        memcpy(keep, w->err, sizeof keep);
        observers_call(w, 1);
        memcpy(w->err, keep, sizeof keep);
    }
    char keep[sizeof w->err];
    memcpy(keep, w->err, sizeof keep);
    int rc2 = floe_world_finish(w);
    if (rc) memcpy(w->err, keep, sizeof keep); /* the run's first error, not a writer's at the end */
    return rc ? rc : rc2;
}

/* ---- integrator and estimate queries ---- */

const char *floe_integrator_name(int integrator) {
    static const char *const names[] = {"velocity_verlet", "leapfrog", "rk2"};
    return integrator >= 0 && integrator <= FLOE_RK2 ? names[integrator] : NULL;
}

int floe_world_dt_estimates(floe_world *w, floe_dt_estimates *out) {
    if (!w->prepared) FLOE_TRY(floe_world_prepare(w));
    *out = w->dte;
    return FLOE_OK;
}

double floe_world_particle_critical_dt(const floe_world *w, int i) {
    if (i < 0 || i >= w->p.n) return -1;
    return w->prepared && w->dt_part ? w->dt_part[i] : INFINITY;
}

int floe_world_step_stats(const floe_world *w, floe_step_stats *out) {
    *out = w->st;
    if (out->pd_substeps < 1) out->pd_substeps = 1;
    if (out->pd_every < 1) out->pd_every = 1;
    return FLOE_OK;
}
