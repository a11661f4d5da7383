/* world.c - the simulation world: particle store, registration of materials, laws,
 * geometries, particles, walls, states and observers; preparation (mass properties,
 * time-step estimate) and the time step: velocity Verlet for rigid bodies (ParticLS
 * eqs 22-23), RK2 for generic state objects (eq 21), observers at their periods. */
#include "world_internal.h"
#include "floe_pd.h"
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
    return d;
}

floe_particle_def floe_default_particle_def(void) {
    floe_particle_def d;
    memset(&d, 0, sizeof d);
    d.q[0] = 1;
    d.motion = FLOE_FREE;
    return d;
}

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
    for (int k = 0; k < w->npd; k++) floe_pd_body_destroy(w->pd[k]);
    free(w->pd); free(w->pd_first); free(w->pd_of); free(w->pd_fold); free(w->pd_fnew); free(w->pd_eold);
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

static int pd_exclude(const void *ctx, int i, int j) {
    const floe_world *w = ctx;
    int bi = w->pd_of[i];
    if (bi < 0 || bi != w->pd_of[j]) return 0;
    int f = w->pd_first[bi];
    return floe_pd_bonded(w->pd[bi], i - f, j - f);
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
    if (w->npd == w->pd_cap) {
        int nc = w->pd_cap ? 2 * w->pd_cap : 4;
        struct floe_pd_body **a = realloc(w->pd, (size_t)nc * sizeof *a);
        if (a) w->pd = a;
        int *b = a ? realloc(w->pd_first, (size_t)nc * sizeof *b) : NULL;
        if (b) w->pd_first = b;
        if (!a || !b) { floe_pd_body_destroy(body); return floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
        w->pd_cap = nc;
    }
    /* one sphere geometry per point volume (lattice bodies: one) */
    double V = body->V[0];
    double R = body->dim == 3 ? cbrt(3.0 * V / (4.0 * M_PI)) : sqrt(V / (M_PI * body->thickness));
    floe_geometry *g = floe_sphere_create(R);
    if (!g) { floe_pd_body_destroy(body); return floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
    int gi = floe_world_add_geometry(w, g);
    if (gi < 0) { floe_geometry_destroy(g); floe_pd_body_destroy(body); return -gi; }
    int f0 = w->p.n;
    for (int i = 0; i < body->n; i++) {
        floe_particle_def d = floe_default_particle_def();
        if (body->V[i] != V) { /* another volume: its own sphere */
            double Ri = body->dim == 3 ? cbrt(3.0 * body->V[i] / (4.0 * M_PI)) : sqrt(body->V[i] / (M_PI * body->thickness));
            floe_geometry *gx = floe_sphere_create(Ri);
            int gx_i = gx ? floe_world_add_geometry(w, gx) : -FLOE_ENOMEM;
            if (gx_i < 0 && gx) floe_geometry_destroy(gx);
            if (gx_i < 0) { floe_pd_body_destroy(body); return floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
            d.geometry = gx_i;
        } else d.geometry = gi;
        d.material = material;
        floe_v3_copy(d.x, body->X + 3 * i);
        if (v0) floe_v3_copy(d.v, v0);
        d.mass = body->mat.rho * body->V[i];
        d.group = -2 - w->npd; /* PD body k writes body = -2 - k in outputs */
        int r = floe_world_add_particle(w, &d);
        if (r < 0) { floe_pd_body_destroy(body); return -r; }
    }
    /* body index of every particle (allocated with the first PD body) */
    int *po = realloc(w->pd_of, (size_t)(w->p.cap > 0 ? w->p.cap : 1) * sizeof *po);
    if (!po) { floe_pd_body_destroy(body); return floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
    for (int i = w->npd ? w->pd_npts_alloc : 0; i < w->p.n; i++) po[i] = -1;
    w->pd_of = po;
    for (int i = f0; i < w->p.n; i++) po[i] = w->npd;
    w->pd_npts_alloc = w->p.n;
    w->pd[w->npd] = body;
    w->pd_first[w->npd] = f0;
    w->npd++;
    w->pd_npts += body->n;
    w->nl.exclude = pd_exclude;
    w->nl.exclude_ctx = w;
    if (first) *first = f0;
    w->prepared = 0;
    return FLOE_OK;
}

int floe_world_pd_body_count(const floe_world *w) { return w->npd; }
struct floe_pd_body *floe_world_pd_body(const floe_world *w, int k, int *first) {
    if (k < 0 || k >= w->npd) return NULL;
    if (first) *first = w->pd_first[k];
    return w->pd[k];
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
static void pair_estimate(const floe_contact_law *law, double r_eff, double m_eff, double m, double rot, double C,
                          double v, double *dt) {
    double kn = 0, cn = 0, depth = rep_depth(law, r_eff, m_eff, v);
    law->klass->stiffness(law, r_eff, m_eff, depth, &kn, &cn);
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

static int estimate_dt(floe_world *w) {
    floe_particles *p = &w->p;
    double C = w->def.dim == 3 ? 8.0 : 6.0;
    double dt = INFINITY;
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
    w->v_expected = vrel;
    /* per material: smallest free particle (mass, radius) */
    for (int m = 0; m < w->nmats; m++) {
        double mmin = INFINITY, rmin = INFINITY, rot = 1;
        for (int i = 0; i < p->n; i++)
            if (p->material[i] == m && p->motion[i] == FLOE_FREE) {
                if (p->mass[i] < mmin) mmin = p->mass[i];
                if (p->radius[i] < rmin) rmin = p->radius[i];
                /* 1 + m R^2 / I: 3.5 for a sphere (the largest over the material) */
                const double *I = p->inertia + 3 * i;
                double imin = w->def.dim == 2 ? I[2] : fmin(I[0], fmin(I[1], I[2]));
                double rr = 1 + p->mass[i] * p->radius[i] * p->radius[i] / imin;
                if (imin > 0 && rr > rot) rot = rr;
            }
        if (!isfinite(mmin)) continue;
        for (int m2 = 0; m2 < w->nmats; m2++) {
            const floe_contact_law *law = w->laws[m * w->nmats + m2];
            if (!law) continue;
            /* partner of the same size (m* = m/2, R* = R/2) and a wall (m* = m, R* = R) */
            /* a packing (all contacts of a close packing at a 2 % overlap) and an impact at
             * the expected speed (one contact, C = 2, at the overlap of the collision) */
            pair_estimate(law, 0.5 * rmin, 0.5 * mmin, mmin, rot, C, 0, &dt);
            pair_estimate(law, rmin, mmin, mmin, rot, C, 0, &dt);
            pair_estimate(law, 0.5 * rmin, 0.5 * mmin, mmin, rot, 2.0, vrel, &dt);
            pair_estimate(law, rmin, mmin, mmin, rot, 2.0, vrel, &dt);
        }
    }
    /* motion: no particle may move more than half its radius in a step (the stability
     * check of the step stops the run past that) */
    if (vrel > 0)
        for (int i = 0; i < p->n; i++)
            if (p->motion[i] == FLOE_FREE && isfinite(p->radius[i]) && 0.5 * p->radius[i] / vrel < dt)
                dt = 0.5 * p->radius[i] / vrel;
    /* peridynamic bodies: the nodal estimate sqrt(2 rho / sum_j V_j c/|xi|) (Silling and
     * Askari 2005; measured limits 2.1x (PMB) and 1.8x (LPS) of it, tests/test_pd.c) */
    for (int k = 0; k < w->npd; k++) {
        double d = floe_pd_dt_nodal(w->pd[k]);
        if (d > 0 && d < dt) dt = d;
    }
    w->dt_crit = dt;
    return FLOE_OK;
}

static int observers_call(floe_world *w, int force_all);

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
        memset(w->pd_fold, 0, (size_t)3 * w->pd_npts * sizeof *fo);
    }
    FLOE_TRY(estimate_dt(w));
    if (w->def.dt > 0) {
        w->dt = w->def.dt;
        if (isfinite(w->dt_crit) && w->dt > w->dt_crit && !w->def.allow_unstable_dt)
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "time step %g s is above the critical estimate %g s; use a smaller dt, dt: auto "
                                    "(automatic), or allow_unstable_dt: true",
                                    w->dt, w->dt_crit);
    } else {
        if (!isfinite(w->dt_crit))
            return floe_world_error(w, FLOE_EINVAL, "automatic time step: no contact law to estimate it from; give dt");
        w->dt = w->def.dt_safety * w->dt_crit;
    }
    int rc = floe_nl_build(&w->nl, p, w->def.dim, w->def.leaf_size);
    if (rc) return floe_world_error(w, rc, "neighbour list build failed (out of memory)");
    {
        double *ko = realloc(w->kin_old, (size_t)(p->n ? p->n : 1) * 6 * sizeof(double));
        if (!ko) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        w->kin_old = ko;
    }
    w->prepared = 1;
    w->t0 = w->time;
    w->step0 = w->step;
    w->record_now = w->record_contacts || w->obs_need_contacts;
    rc = floe_compute_forces(w);
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
    for (int k = 0; k < w->nobs; k++) {
        floe_observer *o = w->obs[k];
        if (o->ended) continue;
        o->ended = 1;
        if (o->klass->end) {
            int r = o->klass->end(o, w);
            if (r && !rc) rc = r;
        }
    }
    w->finished = 1;
    return rc;
}

/* ---- the step ---- */

static void kinematic_velocity(floe_world *w, int i, double t) {
    for (int k = 0; k < w->nmotions; k++)
        if (w->motions[k].particle == i) {
            w->motions[k].fn(t, w->p.v + 3 * i, w->p.w + 3 * i, w->motions[k].user);
            if (w->def.dim == 2) { w->p.v[3 * i + 2] = 0; w->p.w[3 * i] = w->p.w[3 * i + 1] = 0; }
            return;
        }
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

int floe_world_step(floe_world *w) {
    if (!w->prepared) FLOE_TRY(floe_world_prepare(w));
    floe_particles *p = &w->p;
    const double dt = w->dt, h = 0.5 * dt;
    const int n = p->n;
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
            if (have_xb) {
                double dx = x[0] - xb[3 * i], dy = x[1] - xb[3 * i + 1], dz = x[2] - xb[3 * i + 2];
                double d2 = dx * dx + dy * dy + dz * dz;
                if (d2 > maxd2) maxd2 = d2;
            }
            double qn[4];
            q_advance(qn, q, p->w + 3 * i, dt);
            memcpy(q, qn, sizeof qn);
            continue;
        }
        double im = p->inv_mass[i];
        for (int k = 0; k < 3; k++) v[k] += h * im * p->f[3 * i + k];
        for (int k = 0; k < 3; k++) x[k] += dt * v[k];
        if (have_xb) {
            double dx = x[0] - xb[3 * i], dy = x[1] - xb[3 * i + 1], dz = x[2] - xb[3 * i + 2];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 > maxd2) maxd2 = d2;
        }
        /* body-force work over the step uses the drift displacement (exact for gravity
         * when the second half adds the same force) */
        double *L = p->L + 3 * i, *om = p->w + 3 * i;
        const double *I = p->inertia + 3 * i;
        floe_v3_axpy(L, h, p->t + 3 * i);
        if (p->iso[i]) {
            /* isotropic body (sphere): omega = L / I is frame-independent; the orientation
             * follows by q <- exp(dt omega / 2) q, here to third order without trig */
            double inv = 1.0 / I[0];
            for (int k = 0; k < 3; k++) om[k] = L[k] * inv;
            double th[3] = {h * om[0], h * om[1], h * om[2]}, t2 = floe_v3_dot(th, th);
            if (t2 > 0) {
                double c = 1 - 0.5 * t2, dq[4] = {c, th[0], th[1], th[2]}, qn[4];
                floe_q_mul(qn, dq, q);
                /* renormalise by one Newton step for 1/sqrt (|qn|^2 = 1 + O(t2^2)) */
                double s2 = qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3];
                double sc = 1.5 - 0.5 * s2;
                for (int k = 0; k < 4; k++) q[k] = qn[k] * sc;
            }
        } else if (floe_v3_dot(L, L) > 0) {
            double qm[4], omm[3];
            omega_from_L(q, I, L, omm);
            q_advance(qm, q, omm, h);
            for (int it = 0; it < 2; it++) {
                omega_from_L(qm, I, L, omm);
                q_advance(qm, q, omm, h);
            }
            omega_from_L(qm, I, L, omm);
            double qn[4];
            q_advance(qn, q, omm, dt);
            memcpy(q, qn, sizeof qn);
            omega_from_L(q, I, L, om);
        }
        wb += dt * (p->mass[i] * floe_v3_dot(w->def.gravity, v));
    }
    /* 2. state objects, RK2 midpoint (eq 21) */
    for (int s = 0; s < w->nstates; s++) {
        floe_state *st = w->states[s];
        size_t m = st->klass->size(st);
        double buf[64];
        double *y0 = m <= 16 ? buf : malloc(4 * m * sizeof(double));
        if (!y0) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        double *k1 = y0 + m, *ym = y0 + 2 * m, *k2 = y0 + 3 * m;
        st->klass->get(st, y0);
        int rc = st->klass->rhs(st, w, w->time, y0, k1);
        for (size_t a = 0; a < m && !rc; a++) ym[a] = y0[a] + h * k1[a];
        if (!rc) rc = st->klass->rhs(st, w, w->time + h, ym, k2);
        for (size_t a = 0; a < m && !rc; a++) ym[a] = y0[a] + dt * k2[a];
        if (!rc) rc = st->klass->set(st, w, ym);
        if (y0 != buf) free(y0);
        if (rc) return floe_world_error(w, rc, "state object %s failed at step %ld", st->klass->name, w->step);
    }
    w->step++;
    w->time = w->t0 + (double)(w->step - w->step0) * dt; /* no drift from repeated sums */
    /* 3. neighbours and forces at t + dt */
    if (floe_nl_needs_rebuild_after_drift(&w->nl, p, maxd2, !have_xb || w->nstates > 0)) {
        int rc = floe_nl_build(&w->nl, p, w->def.dim, w->def.leaf_size);
        if (rc) return floe_world_error(w, rc, "neighbour list rebuild failed (out of memory)");
    }
    w->advancing = 1;
    w->record_now = contacts_wanted(w);
    int frc = floe_compute_forces(w);
    w->advancing = 0;
    if (frc) return frc;
    /* 4. second half kick */
    double kt = 0, kr = 0, wbound = 0;
    for (int i = 0; i < n; i++) {
        if (p->motion[i] != FLOE_FREE) {
            if (p->motion[i] == FLOE_KINEMATIC) {
                /* work done on the others over the step: -(F_old + F_new)/2 . v_half dt (the
                 * trapezoid rule of velocity Verlet, as for the contacts) */
                const double *fo = w->kin_old + 6 * i;
                for (int k = 0; k < 3; k++)
                    wbound -= h * ((fo[k] + p->f[3 * i + k]) * p->v[3 * i + k] + (fo[3 + k] + p->t[3 * i + k]) * p->w[3 * i + k]);
                kinematic_velocity(w, i, w->time);
            }
            continue;
        }
        double *v = p->v + 3 * i, *L = p->L + 3 * i;
        double im = p->inv_mass[i];
        /* the drift of this step was dt * v_half: a particle that moved more than half its
         * radius, or whose state is not finite (NaN fails every comparison), is unstable */
        double d2 = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt * dt, lim = 0.5 * p->radius[i];
        for (int k = 0; k < 3; k++) v[k] += h * im * p->f[3 * i + k];
        floe_v3_axpy(L, h, p->t + 3 * i);
        if (p->iso[i]) {
            double inv = 1.0 / p->inertia[3 * i];
            for (int k = 0; k < 3; k++) p->w[3 * i + k] = L[k] * inv;
        } else omega_from_L(p->q + 4 * i, p->inertia + 3 * i, L, p->w + 3 * i);
        double ke = 0.5 * p->mass[i] * floe_v3_dot(v, v), kre = 0.5 * floe_v3_dot(L, p->w + 3 * i);
        kt += ke;
        kr += kre;
        if (!(d2 <= lim * lim) || !(ke + kre < INFINITY) || !(fabs(p->x[3 * i]) + fabs(p->x[3 * i + 1]) + fabs(p->x[3 * i + 2]) < INFINITY)) {
            double xold[3];
            for (int k = 0; k < 3; k++) xold[k] = p->x[3 * i + k] - dt * (v[k] - h * im * p->f[3 * i + k]);
            int rc = check_particle(w, i, xold);
            if (rc) return rc;
        }
    }
    w->energy.kinetic_trans = kt;
    w->energy.kinetic_rot = kr;
    w->energy.work_body += wb;
    w->energy.work_boundary += wbound;
    return observers_call(w, 0);
}

int floe_world_run(floe_world *w, double t_end, floe_progress_fn progress, void *user) {
    int rc = floe_world_prepare(w);
    if (rc) { floe_world_finish(w); return rc; }
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
    if (rc && rc != FLOE_ESTOP) {
        /* flush the state at failure so the outputs show what happened */
        char keep[sizeof w->err];
        memcpy(keep, w->err, sizeof keep);
        observers_call(w, 1);
        memcpy(w->err, keep, sizeof keep);
    }
    int rc2 = floe_world_finish(w);
    return rc ? rc : rc2;
}
