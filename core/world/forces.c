/* forces.c - force and torque on every particle at the current positions: body forces
 * (gravity, user callback) and contact forces over the neighbour list (detection ->
 * contact summary, eq 15 -> contact law of the material pair -> force, torque, history,
 * energy, dissipation). In 2D the out-of-plane components are removed. */
#include "world_internal.h"
#include "floe_pd.h"
#include "beam_set.h"
#include "floe_provider.h"
#include "floe_par.h"
#include "alloc_util.h"
#include "law_kernels.h"
#include <limits.h>
#include <stdlib.h>
#include <string.h>

/* a record to the world's contacts, or (threads: sink) to its part's, which the stage
 * appends to the world's in part order, the order of one thread */
static int push_contact(floe_world *w, floe_rec_sink *sink, const floe_contact *c, const floe_contact_result *r,
                        const double l[3]) {
    floe_contact_rec **buf = sink ? &sink->r : &w->contacts;
    int *cnt = sink ? &sink->n : &w->ncontacts, *cap = sink ? &sink->cap : &w->contacts_cap;
    if (*cnt == *cap) {
        int nc = *cap ? 2 * *cap : 1024;
        floe_contact_rec *t = realloc(*buf, (size_t)nc * sizeof *t);
        if (!t) return FLOE_ENOMEM;
        *buf = t;
        *cap = nc;
    }
    floe_contact_rec *k = &(*buf)[(*cnt)++];
    k->i = c->i; k->j = c->j;
    memcpy(k->point, c->point, sizeof k->point);
    memcpy(k->n, c->n, sizeof k->n);
    k->depth = c->depth;
    memcpy(k->force, r->force, sizeof k->force);
    k->fn = r->fn;
    k->energy = r->energy;
    memcpy(k->branch, l, sizeof k->branch);
    k->r_eff = c->r_eff;
    k->m_eff = c->m_eff;
    return FLOE_OK;
}


/* A manifold spring under a built-in law without the law's call through its class: the
 * law's own normal kernel (floe_linear_normal_k, floe_hertz_normal) at the spring's contact,
 * which manifold_springs gives vn = 0 and dt = 0 (the dashpot adds zeros, no history is
 * read or advanced), the force along -n and its energy: the values of the law's force
 * function by construction (tests/test_manifold_springs checks the bits). 0 (nothing set)
 * for other laws and for inputs the law itself refuses or treats apart (Hertz-Mindlin's
 * checks, a depth not > 0): the caller calls the law then. */
static inline int spring_builtin(const floe_contact_law *law, const floe_contact *ce, floe_contact_result *re) {
    floe_normal_force nf;
    if (!(ce->depth > 0.0)) return 0;
    if (law->klass == &floe_linear_law_class) {
        const floe_linear_law *L = (const floe_linear_law *)law;
        double h[FLOE_MAX_HISTORY] = {0}; /* untouched at dt = 0 (floe_linear_dashpot_phase) */
        floe_linear_normal_k(L->kn, L->gn, L->tension, ce, h, &nf);
    } else if (law->klass == &floe_hertz_mindlin_law_class) {
        const floe_hertz_mindlin_law *H = (const floe_hertz_mindlin_law *)law;
        const double m = ce->m_eff, R = ce->r_eff; /* the law's own checks */
        if (!(m > 0.0) || !isfinite(m) || !(R > 0.0) || !isfinite(R)) return 0;
        floe_hertz_normal(H->e_star, H->damping_ratio, ce, &nf);
    } else
        return 0;
    re->fn = nf.fn;
    for (int k = 0; k < 3; k++) re->force[k] = -nf.fn * ce->n[k];
    re->energy = nf.energy;
    return 1;
}

/* The springs of a contact manifold's extra vertices (floe_contact.h): the law's elastic
 * force and energy at each vertex's depth (a call with no relative motion, no history and
 * a zero step; spring_builtin for the built-in laws), summed as a force on i (fx) with its
 * torques about the centres (tx_i, tx_j), and their energy (ex); their loads in fe and their
 * sum in c->fn_extra. Also the deepest point's elastic load f0 and the load centre of all
 * the points (centre). */
static int manifold_springs(floe_world *w, const floe_contact_law *law, floe_contact *c, const double *xa,
                            const double *xb, double *fe, double *f0, double centre[3], double fx[3], double tx_i[3],
                            double tx_j[3], double *ex) {
    double ftot = 0.0;
    floe_v3_set(centre, 0, 0, 0);
    /* one copy of the contact (the law reads it const): each spring changes its depth,
     * normal and point only (a copy per spring was a tenth of a settled bed's step) */
    floe_contact ce = *c;
    ce.vn = 0.0;
    floe_v3_set(ce.vr, 0, 0, 0);
    floe_v3_set(ce.vt, 0, 0, 0);
    floe_v3_set(ce.wr, 0, 0, 0);
    ce.nextra = 0;
    ce.fn_extra = 0.0;
    ce.dt = 0.0; /* elastic only: no implicit dashpot factor, no history advanced */
    for (int e = -1; e < c->nextra; e++) {
        double arm[3], t[3];
        if (e >= 0) {
            ce.depth = c->extra_depth[e];
            floe_v3_copy(ce.n, c->extra_n[e]);
            floe_v3_copy(ce.point, c->extra_point[e]);
        }
        floe_contact_result re;
        if (!spring_builtin(law, &ce, &re)) {
            double he[FLOE_MAX_HISTORY] = {0};
            memset(&re, 0, sizeof re);
            int rc = law->klass->force(law, &ce, he, &re);
            if (rc)
                return floe_world_error(w, rc, "contact law %s failed for particles %lld and %lld at a manifold vertex: %s",
                                        law->klass->name, floe_world_pid(w, c->i), floe_world_pid(w, c->j), floe_strerror(rc));
        }
        const double fn = fmax(re.fn, 0.0);
        ftot += fn;
        floe_v3_axpy(centre, fn, ce.point);
        if (e < 0) { /* the deepest point: its load only (the law applies its force) */
            *f0 = fn;
            continue;
        }
        floe_v3_sub(arm, ce.point, xa);
        floe_v3_add(fx, fx, re.force);
        floe_v3_cross(t, arm, re.force);
        floe_v3_add(tx_i, tx_i, t);
        floe_v3_sub(arm, ce.point, xb);
        floe_v3_cross(t, arm, re.force);
        floe_v3_sub(tx_j, tx_j, t);
        *ex += re.energy;
        fe[e] = re.fn;
        c->fn_extra += re.fn;
    }
    if (ftot > 0.0) floe_v3_scale(centre, 1.0 / ftot);
    else floe_v3_copy(centre, c->point);
    return FLOE_OK;
}

/* Couples of a contact manifold (polytope pairs and polytope-plane contacts under a point
 * law): the law's dashpot and friction act at the manifold's load centre, which resists
 * neither rocking nor twisting; over the points k (the deepest point and the extra
 * vertices, loads f_k, at rho_k from the load centre across n):
 *  - rocking: the law's normal dashpot cn_k at every point, the couple
 *    -sum cn_k ((w x rho_k) . n) (rho_k x n), w = w_i - w_j;
 *  - twist about n (3D): the law's tangential springs and dashpots give a torsion spring
 *    sum kt_k rho_k^2 and dashpot sum ct_k rho_k^2 on the relative twist angle theta
 *    (history), and Coulomb at every point caps the couple at mu sum f_k rho_k.
 * fe: the extras' loads, centre: the load centre. Adds the couples (on i, minus them on j)
 * and the torsion spring's energy to res. */
static void manifold_couples(const floe_contact_law *law, const floe_contact *c, int dim, double fn0,
                             const double *fe, const double centre[3], double *theta, floe_contact_result *res) {
    const int np = c->nextra + 1;
    double rho[FLOE_MANIFOLD_EXTRA + 1][3], f[FLOE_MANIFOLD_EXTRA + 1], d[FLOE_MANIFOLD_EXTRA + 1];
    for (int k = 0; k < np; k++) {
        floe_v3_sub(rho[k], k ? c->extra_point[k - 1] : c->point, centre);
        floe_v3_axpy(rho[k], -floe_v3_dot(rho[k], c->n), c->n);
        d[k] = k ? c->extra_depth[k - 1] : c->depth;
        f[k] = fmax(k ? fe[k - 1] : fn0, 0.0);
    }
    /* rocking */
    for (int k = 0; k < np; k++) {
        double kn = 0.0, cn = 0.0, u[3], m[3];
        law->klass->stiffness(law, c->r_eff, c->m_eff, d[k], &kn, &cn);
        if (!(cn > 0.0)) continue;
        floe_v3_cross(u, c->wr, rho[k]);
        floe_v3_cross(m, rho[k], c->n);
        const double s = -cn * floe_v3_dot(u, c->n);
        floe_v3_axpy(res->torque_i, s, m);
        floe_v3_axpy(res->torque_j, -s, m);
    }
    /* twist */
    if (dim != 3 || !law->klass->tangential_stiffness || !(law->friction > 0.0)) {
        *theta = 0.0;
        return;
    }
    double kt = 0.0, ct = 0.0, lim = 0.0;
    for (int k = 0; k < np; k++) {
        double kk = 0.0, cc = 0.0;
        const double rho2 = floe_v3_dot(rho[k], rho[k]);
        law->klass->tangential_stiffness(law, c->r_eff, c->m_eff, d[k], &kk, &cc);
        kt += kk * rho2;
        ct += cc * rho2;
        lim += law->friction * f[k] * sqrt(rho2);
    }
    const double wn = floe_v3_dot(c->wr, c->n);
    *theta += wn * c->dt;
    double m = -kt * *theta - ct * wn;
    if (fabs(m) > lim) { /* slipping: the spring keeps what Coulomb allows */
        m = m > 0 ? lim : -lim;
        *theta = kt > 0.0 ? -(m + ct * wn) / kt : 0.0;
    }
    floe_v3_axpy(res->torque_i, m, c->n);
    floe_v3_axpy(res->torque_j, -m, c->n);
    res->energy += 0.5 * kt * *theta * *theta;
}

/* the pose of particle i as detection sees it */
static inline floe_body_ref body_ref(const floe_world *w, int i) {
    const floe_particles *p = &w->p;
    floe_body_ref b = {w->geoms[p->geom[i]], p->x + 3 * i, p->q + 4 * i, p->radius[i], i};
    return b;
}

/* the same with j at xb (its periodic image, or its own centre) */
static inline floe_body_ref body_ref_at(const floe_world *w, int j, const double *xb) {
    floe_body_ref b = body_ref(w, j);
    b.x = xb;
    return b;
}

static int detect_pair(const floe_world *w, floe_detect_ctx *ctx, int i, int j, int sub, double *warm,
                       floe_contact *c) {
    floe_body_ref bi = body_ref(w, i), bj = body_ref(w, j);
    return floe_detect(ctx, &bi, &bj, sub, warm, c);
}
static int detect_pair_at(const floe_world *w, floe_detect_ctx *ctx, int i, int j, const double *xb, int sub,
                          double *warm, floe_contact *c) {
    floe_body_ref bi = body_ref(w, i), bj = body_ref_at(w, j, xb);
    return floe_detect(ctx, &bi, &bj, sub, warm, c);
}

int floe_world_detect(floe_world *w, int i, int j, int sub, double *warm, floe_contact *c) {
    floe_detect_ctx ctx = {.dim = w->def.dim, .step = w->step, .det = &w->det};
    return detect_pair(w, &ctx, i, j, sub, warm, c);
}

int floe_world_detect_overlap(floe_world *w, int i, int j, int sub, floe_contact *c) {
    floe_detect_ctx ctx = {.dim = w->def.dim, .step = w->step, .det = &w->det};
    floe_body_ref bi = body_ref(w, i), bj = body_ref(w, j);
    return floe_detect_overlap(&ctx, &bi, &bj, sub, NULL, c);
}

/* ---- provider "body": PD body-force regions, the body-force callback (with gravity, set
 * where the forces are cleared (forces_clear), the body forces m b of 000 eq 40, counted
 * once) ---- */
/* the body-force callback on particles [i0, i1): its forces added, its work over the step
 * (trapezoid, with the velocities at mid-step: dx = v dt) summed in particle order */
typedef struct {
    floe_world *w;
    floe_particles *p;
    double t, dt;
} body_cb_ctx;

static void body_cb_block(void *ctx, int i0, int i1, double *sum) {
    const body_cb_ctx *c = ctx;
    floe_world *w = c->w;
    floe_particles *p = c->p;
    double wb = 0;
    for (int i = i0; i < i1; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        double f[3] = {0, 0, 0}, t[3] = {0, 0, 0}, *old = w->fb_old + 6 * i;
        w->body_force(w, i, c->t, f, t, w->body_force_user);
        floe_v3_add(p->f + 3 * i, p->f + 3 * i, f);
        floe_v3_add(p->t + 3 * i, p->t + 3 * i, t);
        for (int a = 0; a < 3; a++)
            wb += 0.5 * c->dt * ((f[a] + old[a]) * p->v[3 * i + a] + (t[a] + old[3 + a]) * p->w[3 * i + a]);
        memcpy(old, f, sizeof f);
        memcpy(old + 3, t, sizeof t);
    }
    *sum = wb;
}

static int body_stage(floe_provider *pv, floe_world *w, const floe_step_ctx *ctx, floe_provider_out *out) {
    (void)pv;
    (void)out;
    floe_particles *p = ctx->p;
    const int n = p->n;
    const int stepping = ctx->stepping;
    /* gravity, m g on every free particle, was set where the forces were cleared (forces_clear:
     * this stage is the first) */
    /* PD boundary regions: the external force b V of body-force regions (ParticLS eq 37),
     * its work booked like the body-force callback's (core/world/world.c floe_pd_bc_forces) */
    if (w->npd_bc) {
        double wbc = floe_pd_bc_forces(w);
        if (stepping) w->energy.work_body += wbc;
    }
    if (w->body_force) {
        if (w->fb_n < n) { /* previous callback force and torque, for the trapezoid rule */
            double *fb = realloc(w->fb_old, (size_t)n * 6 * sizeof(double));
            if (!fb) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            memset(fb + 6 * w->fb_n, 0, (size_t)(n - w->fb_n) * 6 * sizeof(double));
            w->fb_old = fb;
            w->fb_n = n;
        }
        if (floe_world_pp_attach(w, &w->fb_old, &w->fb_n, 6)) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        /* a callback declared thread-safe on the world's threads, a block of particles each
         * (its work summed per block); else on this one, its work one running sum */
        body_cb_ctx bc = {w, p, ctx->time, ctx->dt};
        double wb;
        if (!w->body_force_threaded) body_cb_block(&bc, 0, n, &wb);
        else if (floe_world_blocks(w, n, 1, body_cb_block, &bc, &wb))
            return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        if (stepping) w->energy.work_body += wb;
    }
    return FLOE_OK;
}

/* its state: the callback's and the body-force regions' last forces (trapezoid work) */
static size_t body_state_size(const floe_provider *pv, const floe_world *w) {
    (void)pv;
    size_t n = w->body_force && w->fb_old ? 6 * (size_t)w->fb_n : 0;
    for (int q = 0; q < w->npd_bc; q++)
        if (w->pd_bc[q]->fold) n += 3 * (size_t)w->pd_bc[q]->n;
    return n * sizeof(double);
}

static void body_state_io(const floe_world *w, unsigned char *buf, int save) {
    size_t o = 0;
    if (w->body_force && w->fb_old) {
        size_t m = 6 * (size_t)w->fb_n * sizeof(double);
        if (save) memcpy(buf, w->fb_old, m);
        else memcpy(w->fb_old, buf, m);
        o += m;
    }
    for (int q = 0; q < w->npd_bc; q++)
        if (w->pd_bc[q]->fold) {
            size_t m = 3 * (size_t)w->pd_bc[q]->n * sizeof(double);
            if (save) memcpy(buf + o, w->pd_bc[q]->fold, m);
            else memcpy(w->pd_bc[q]->fold, buf + o, m);
            o += m;
        }
}
static void body_save(const floe_provider *pv, const floe_world *w, unsigned char *buf) {
    (void)pv;
    body_state_io(w, buf, 1);
}
static void body_restore(floe_provider *pv, floe_world *w, const unsigned char *buf) {
    (void)pv;
    body_state_io(w, (unsigned char *)buf, 0);
}

const floe_provider_class floe_body_provider_class = {
    .version = 1, .name = "body_forces", .group = FLOE_GROUP_DEM, .forces = body_stage,
    .state_size = body_state_size, .save = body_save, .restore = body_restore};

/* ---- provider "beam_bonds" (contact/bonds/beam_bond.c): force, torque, energy and
 * breakage; a broken bond's pair enters the contact list before the contact stage ---- */
static int beam_stage(floe_provider *pv, floe_world *w, const floe_step_ctx *ctx, floe_provider_out *out) {
    (void)pv;
    if (!w->beams) return FLOE_OK;
    floe_step_ctx bc = *ctx;
    bc.stepping = ctx->stepping && !ctx->probe;
    floe_beam_set_threads(w->beams, floe_world_loop_threads(w, floe_beam_set_count(w->beams)));
    int nbreak = floe_beam_set_forces(w->beams, &bc, &out->elastic, &out->dissipated);
    if (nbreak > 0) out->rebuild = 1;
    return FLOE_OK;
}
static double beam_critical(floe_provider *pv, floe_world *w) {
    (void)pv;
    return floe_world_beam_critical_dt(w);
}
static int beam_excludes(const floe_provider *pv, const floe_world *w, int i, int j) {
    (void)pv;
    return w->beams && floe_beam_set_excludes(w->beams, i, j);
}
/* the bonds' last forces and broken flags are not saved yet: adaptive steps refuse them */
static int beam_can_save(const floe_provider *pv, const floe_world *w) {
    (void)pv;
    return !w->beams;
}
const floe_provider_class floe_beam_provider_class = {
    .version = 1, .name = "beam_bonds", .group = FLOE_GROUP_DEM, .forces = beam_stage,
    .critical_dt = beam_critical, .excludes = beam_excludes, .can_save = beam_can_save};

/* ---- provider "contacts": every pair of the neighbour list through detection and the
 * law of its materials (ParticLS eqs 15-20; the manifold of polytope pairs) ---- */
/* What the pair evaluations add up (contact_stage), and what they share. */
struct stage_acc {
    double eta_d, elastic, diss, wgrow;
    double vir[9], kdiag[9]; /* periodic cell: sum l (x) F, and k_n (n_a l_b)^2 for the servo */
    /* energy watchdog: the contact (wd_i, wd_j) that received the most negative work since it
     * began (its dissipation plus its stored energy; the first such, 0 if none), for
     * core/integrators/watchdog.c */
    double wd_min; int wd_i, wd_j;
    long ncontacts;          /* contacts counted (not recorded) */
    /* threads: an entry's force on i and torque increments of i and j go to pf (9 per entry,
     * act[k]: 1 for i, 2 for j) when an end is not led by this block's part, gathered per particle
     * afterwards; NULL: added to p->f, p->t */
    double *pf;
    unsigned char *act;
    const unsigned char *lead; /* per particle: the part that adds its forces directly
                                  (floe_par_scratch.lead) */
    int part;                  /* this block's part */
    floe_rec_sink *rs;        /* threads, recording: the part's contact records (NULL: the world's) */
    int oom;                  /* a record of the lanes' books found no memory (stage_block reports it) */
};
typedef struct stage_acc stage_acc;

/* the work d a contact (i, j) received since it began (the watchdog's) */
static inline void acc_life(stage_acc *acc, int i, int j, double d) {
    if (d < acc->wd_min) { acc->wd_min = d; acc->wd_i = i; acc->wd_j = j; }
}

/* entry k's force F on i (-F on j) and torque increments ti, tj, added as a serial loop adds
 * them (threads: an end led by another part stored for the gather, which adds them after the
 * lead part's, in the same order) */
static inline __attribute__((always_inline)) void pair_apply(floe_particles *p, stage_acc *acc, int k, int i, int j,
                                                             const double F[3], const double ti[3], const double tj[3]) {
    double *fi = p->f + 3 * i, *fj = p->f + 3 * j, *Ti = p->t + 3 * i, *Tj = p->t + 3 * j;
    if (acc->pf) {
        /* an end led by this part (its first entry lies here; every entry of a particle whose
         * entries lie in one part) takes its share directly, in list order as one thread adds
         * it; an end led by an earlier part waits for the gather, which adds it after all of
         * that part's */
        const int oi = acc->lead[i] == acc->part, oj = acc->lead[j] == acc->part;
        if (oi)
            for (int a = 0; a < 3; a++) { fi[a] += F[a]; Ti[a] += ti[a]; }
        if (oj)
            for (int a = 0; a < 3; a++) { fj[a] -= F[a]; Tj[a] += tj[a]; }
        if (oi & oj) return;
        double *b = acc->pf + 9 * (size_t)k;
        for (int a = 0; a < 3; a++) { b[a] = F[a]; b[3 + a] = ti[a]; b[6 + a] = tj[a]; }
        acc->act[k] = (unsigned char)((oi ? 0 : 1) | (oj ? 0 : 2)); /* the ends the gather adds: 1 i, 2 j */
        return;
    }
    for (int a = 0; a < 3; a++) {
        fi[a] += F[a];
        fj[a] -= F[a];
        Ti[a] += ti[a];
        Tj[a] += tj[a];
    }
}
typedef struct stage_env {
    floe_particles *p;
    floe_neighbor_list *nl;
    const floe_detect_ctx *dctx;
    int stepping, track, any_growth, nm, any_none, any_pieces, any_overlap;
    int any_floe; /* a law reads the floes' thickness and radii (floe_law_info.needs_floe) */
    int overlap2d; /* 2D and a law reads the overlap: polygon pairs skip the point detection */
    const floe_cell_state *cell; /* periodic cell (NULL: none): images, affine velocities */
    const int *img;              /* the list's image codes (with a cell) */
    int fused;                   /* sphere pairs under a built-in law may take its fused kernel
                                    (sph_flush_lanes: no growth) */
    const floe_contact_law *law1; /* the one law of a world with one material (else NULL): the
                                     sphere path skips the lookup by materials */
    int record;                  /* contacts recorded at this evaluation (ctx->record) */
} stage_env;

/* periodic cell: j's image xs = x_j + H n of entry k (xs untouched and x_j returned when the
 * entry has no image) */
static inline const double *pair_image(const stage_env *env, int k, const double *xj, double xs[3]) {
    if (!env->img || !env->img[k]) return xj;
    double sh[3];
    floe_img_shift(env->cell->H, env->img[k], sh);
    floe_v3_add(xs, xj, sh);
    return xs;
}
/* periodic cell: the mean field's relative velocity of i with respect to j's image, -L l
 * (l = x_j' - x_i), subtracted from the fluctuation velocities' v_i - v_j */
static inline void pair_affine_sub(const stage_env *env, const double l[3], double vr[3]) {
    const double *L = env->cell->L;
    for (int a = 0; a < 3; a++) vr[a] -= L[3 * a] * l[0] + L[3 * a + 1] * l[1] + L[3 * a + 2] * l[2];
}

/* the pair's law reads the overlap (the overlap-area law, or prefers it: Hopkins') */
static inline int pair_wants_overlap(const floe_world *w, int i, int j, int nm) {
    const floe_contact_law *law = w->laws[w->p.material[i] * nm + w->p.material[j]];
    if (!law) return 0;
    const floe_law_info li = floe_contact_law_info(law);
    return li.needs_overlap | li.prefers_overlap;
}

/* the smaller of two radii (never NaN): fmin is a library call here (NaN rules) */
static inline double rmin(double a, double b) { return a < b ? a : b; }

/* The relative normal acceleration of i with respect to j that a linear dashpot adds to its
 * mid-step velocity (floe_contact.an_ext, contact/laws/linear_law.c): (a_i - a_j) . n from
 * the accelerations f / m of the last force evaluation (w->dash_a; 0 for fixed and kinematic
 * bodies), less this contact's own share, its last force F on i (history, scaled by gscale
 * as applied) times 1/m_i + 1/m_j; the law adds its own new force implicitly. Two bodies
 * alone: 0 (the law's binary-collision form); a pair held at rest by other contacts:
 * Fn_last / m* (the dashpot then sees the rest it is at). Translational only: the angular
 * accelerations have no normal component at the contact point of two spheres (their lever
 * arms lie along n), and the law's own term uses the translational m* as well. */
static inline double pair_an_ext(const floe_world *w, const floe_particles *p, int i, int j, const floe_contact *c,
                                 const double *hist) {
    const double *ai = w->dash_a + 3 * (size_t)i, *aj = w->dash_a + 3 * (size_t)j, *n = c->n;
    const double an = (ai[0] - aj[0]) * n[0] + (ai[1] - aj[1]) * n[1] + (ai[2] - aj[2]) * n[2];
    const double g = c->gscale > 0 ? c->gscale : 1.0;
    return an - floe_v3_dot(hist + FLOE_FORCE_SLOT, n) * (p->inv_mass[i] + p->inv_mass[j]) / g;
}

/* the errors of a pair evaluation, out of the hot path */
static __attribute__((noinline, cold)) int pair_too_deep(floe_world *w, int i, int j, double depth, int wall,
                                                         const double n[3]) {
    const floe_particles *p = &w->p;
    return floe_world_error(w, FLOE_EUNSTABLE,
                            "unstable: particles %lld and %lld (bodies %d, %d) overlap by %.3g m, more than %s "
                            "at step %ld, t = %g s: the contact is too soft for the speeds (relative "
                            "normal speed %.3g m/s) or the time step too large",
                            floe_world_pid(w, i), floe_world_pid(w, j), p->group[i], p->group[j], depth, wall ? "the diameter" : "the smaller radius",
                            w->step, w->time, floe_v3_dot(p->v + 3 * i, n) - floe_v3_dot(p->v + 3 * j, n));
}
static __attribute__((noinline, cold)) int pair_law_failed(floe_world *w, const floe_contact_law *law, int rc,
                                                           int i, int j, const floe_contact *c) {
    /* the law has no message of its own: name its inputs */
    return floe_world_error(w, rc, "contact law %s failed for particles %lld and %lld: %s (effective mass %g kg, "
                            "effective radius %g m, overlap %g m)", law->klass->name, floe_world_pid(w, i),
                            floe_world_pid(w, j), floe_strerror(rc),
                            c->m_eff, c->r_eff, c->depth);
}

/* the release of entry k (its pair no longer touches): the last force still did work over
 * half a step; the history is reset (ParticLS §3.1) */
static inline void pair_release(floe_world *w, const floe_particles *p, floe_neighbor_list *nl, int k, int i, int j,
                                int stepping, stage_acc *acc, const stage_env *env, const double *xb) {
    double *hist = nl->hist + (size_t)k * nl->hs;
    if (stepping) {
        double vr[3];
        floe_v3_sub(vr, p->v + 3 * i, p->v + 3 * j);
        if (env->cell) { /* the cell's share of the last half step's work */
            double l[3], v0[3];
            floe_v3_sub(l, xb, p->x + 3 * i);
            floe_v3_copy(v0, vr);
            pair_affine_sub(env, l, vr);
            floe_v3_sub(v0, v0, vr);
            acc->wgrow += 0.5 * floe_v3_dot(hist + FLOE_FORCE_SLOT, v0) * w->dt;
        }
        double dk = hist[FLOE_ENERGY_SLOT] - 0.5 * floe_v3_dot(hist + FLOE_FORCE_SLOT, vr) * w->dt;
        acc->diss += dk;
        acc_life(acc, i, j, hist[FLOE_DISS_SLOT] + dk);
    }
    memset(hist, 0, (size_t)nl->hs * sizeof(double));
    nl->touching[k] = 0;
}

/* the contact of two overlapping spheres i, j (radii ri, rj, centres xa, xb, xb - xa =
 * (dx, dy, dz), d2 its square): normal, depth, effective radius, surface points, point */
static inline __attribute__((always_inline)) void sphere_contact(floe_contact *c, int i, int j, const double *xa,
                                                                 const double *xb, double ri, double rj, double dx,
                                                                 double dy, double dz, double d2) {
    const double rs = ri + rj, dist = sqrt(d2), inv = dist > 0 ? 1.0 / dist : 0.0;
    if (dist > 0) floe_v3_set(c->n, dx * inv, dy * inv, dz * inv);
    else floe_v3_set(c->n, 1, 0, 0);
    c->i = i; c->j = j;
    c->depth = rs - dist;
    c->r_eff = ri * rj / rs;
    for (int a = 0; a < 3; a++) {
        c->x1[a] = xa[a] + ri * c->n[a];
        c->x2[a] = xb[a] - rj * c->n[a];
        c->point[a] = 0.5 * (c->x1[a] + c->x2[a]);
    }
}

/* the lever arms of a sphere pair's contact point (the middle of the overlap on the line of
 * centres) from i's centre and from j's, d = x_j - x_i (j's image in a periodic cell), n the
 * unit normal: ri = (r_i - depth/2) n, rj = ri - d. One body for the general path
 * (sphere_arms) and each lane of sph_flush_lanes: the same bits. From the centre line rather
 * than as point - x: the lanes need not gather the centres (issue 14 session 41) */
static inline __attribute__((always_inline)) void sphere_arms_l(double rad_i, double depth, const double n[3],
                                                                const double d[3], double ri[3], double rj[3]) {
    const double ci = rad_i - 0.5 * depth;
    for (int a = 0; a < 3; a++) {
        ri[a] = ci * n[a];
        rj[a] = ri[a] - d[a];
    }
}
static inline __attribute__((always_inline)) void sphere_arms(const floe_contact *c, double rad_i, double dx,
                                                              double dy, double dz, double ri[3], double rj[3]) {
    const double d[3] = {dx, dy, dz};
    sphere_arms_l(rad_i, c->depth, c->n, d, ri, rj);
}

/* The end of a pair evaluation, the same for both bodies: the stored energy (res.energy +
 * the manifold springs' ex), the dissipation ledger, the pair's history, and its record (with
 * the manifold's force fx) or its count. */
static inline __attribute__((always_inline)) int pair_book(floe_world *w, const floe_step_ctx *ctx,
                                                           const stage_env *env, int i, int j,
                                                           const floe_contact *c, const floe_contact_result *res,
                                                           const double fx[3], double ex, double *hist,
                                                           stage_acc *acc, const double *xb) {
    const floe_particles *p = env->p;
    acc->elastic += res->energy + ex;
    double l[3] = {0, 0, 0};
    if (env->cell || ctx->record) floe_v3_sub(l, xb, p->x + 3 * i);
    if (env->cell) {
        /* the homogenised stress's sum, and the servo's stiffness (eq 29's D_abab) */
        double ft[3];
        floe_v3_add(ft, res->force, fx);
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) acc->vir[3 * a + b] += l[a] * ft[b];
        if (env->cell->want_kdiag) {
            const floe_contact_law *law = w->laws[p->material[i] * env->nm + p->material[j]];
            double kn = 0, cn = 0;
            if (law && law->klass->stiffness) law->klass->stiffness(law, c->r_eff, c->m_eff, c->depth, &kn, &cn);
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++) acc->kdiag[3 * a + b] += kn * c->n[a] * c->n[a] * l[b] * l[b];
        }
    }
    /* dissipation ledger: work done on the contact by the relative motion over the step
     * (mid-step velocities) minus the change of its stored energy */
    if (env->stepping) {
        /* trapezoid rule: the work of velocity Verlet over a step is (F_old + F_new)/2 . dx */
        double fav[3];
        for (int a = 0; a < 3; a++) fav[a] = 0.5 * (res->force[a] + hist[FLOE_FORCE_SLOT + a]);
        double wc = -floe_v3_dot(fav, c->vr) * c->dt;
        /* couples of the law (rocking dashpots): their work over the step */
        wc -= (floe_v3_dot(res->torque_i, p->w + 3 * i) + floe_v3_dot(res->torque_j, p->w + 3 * j)) * c->dt;
        /* surfaces that grow (state objects) move towards each other at rdot_i + rdot_j:
         * that work enters the contact from outside the particle system */
        double grow = env->any_growth ? p->rdot[i] + p->rdot[j] : 0.0;
        if (grow != 0) {
            double wg = -floe_v3_dot(fav, c->n) * grow * c->dt;
            wc += wg;
            acc->wgrow += wg;
        }
        if (env->cell) { /* the work of the cell's deformation on the contact: fav . L l dt */
            const double *L = env->cell->L;
            double la[3];
            for (int a = 0; a < 3; a++) la[a] = L[3 * a] * l[0] + L[3 * a + 1] * l[1] + L[3 * a + 2] * l[2];
            acc->wgrow += floe_v3_dot(fav, la) * c->dt;
        }
        double dk = wc - (res->energy - hist[FLOE_ENERGY_SLOT]);
        acc->diss += dk;
        hist[FLOE_DISS_SLOT] += dk;
        /* the watchdog reads the work done on the contact since it began, dissipation +
         * stored energy: negative when it gave back more than it took (robust to a law
         * whose stored energy is not the potential of its force) */
        double wk = hist[FLOE_DISS_SLOT] + res->energy;
        acc_life(acc, i, j, wk);
    }
    hist[FLOE_ENERGY_SLOT] = res->energy;
    memcpy(hist + FLOE_FORCE_SLOT, res->force, 3 * sizeof(double));
    if (!ctx->record) acc->ncontacts++;
    else {
        /* one record per pair: the manifold's springs in its force (the stress observer's
         * branch vector between centres needs the total only) */
        floe_contact_result rec = *res;
        floe_v3_add(rec.force, rec.force, fx);
        rec.fn += c->fn_extra;
        rec.energy += ex;
        if (push_contact(w, acc->rs, c, &rec, l)) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    return FLOE_OK;
}

/* One entry k of the neighbour list: detection, law, forces, ledger. The stage first
 * filters the entries whose bounding spheres are apart (most of them) in a small loop, then
 * runs this over the rest: with this body inside the loop over every entry the compiler kept
 * nothing in registers and the loop took twice the instructions per entry (callgrind,
 * 2026-12-02). */
static inline int contact_pair(floe_world *w, const floe_step_ctx *ctx, const stage_env *env, int k,
                               stage_acc *acc) {
    floe_particles *p = env->p;
    floe_neighbor_list *nl = env->nl;
    const int stepping = env->stepping, track = env->track, nm = env->nm;
    const int any_none = env->any_none, any_pieces = env->any_pieces, any_overlap = env->any_overlap;
    floe_detect_ctx dctx = *env->dctx;
    int i = nl->pi[k], j = nl->pj[k], sub = any_pieces ? nl->sub[k] : 0; /* 0 unless compound */
    if (w->sep_on) { /* the separation cache: this entry's gap, the pair's motion bound */
        dctx.sep = w->sep_pair + 2 * (size_t)k;
        dctx.motion = w->sep_d[i] + w->sep_d[j];
    }
    if (any_none && floe_contact_law_no_contact(w->laws[p->material[i] * nm + p->material[j]])) return FLOE_OK;
    double *warm = nl->use_warm ? nl->warm + (size_t)k * FLOE_DETECT_WARM : NULL;
    floe_contact c;
    c.gscale = 1.0;
    c.nextra = 0;
    c.fn_extra = 0.0;
    int r = 0, ov_done = 0, spheres = 0;
    /* bounding spheres apart: no contact for any pair of shapes (most list pairs) */
    double xs[3];
    const double *xa = p->x + 3 * i, *xb = pair_image(env, k, p->x + 3 * j, xs);
    double rad_i = p->radius[i], rad_j = p->radius[j];
    double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2], rs = rad_i + rad_j;
    if (any_pieces && (p->pieces[i] > 1 || p->pieces[j] > 1)) {
        /* compound bodies: the bounding spheres of this entry's two pieces */
        double ca[3], cb[3];
        floe_body_ref bi = body_ref(w, i), bj = body_ref_at(w, j, xb);
        floe_piece_centre(&bi, FLOE_SUB_A(sub), ca, &rad_i);
        floe_piece_centre(&bj, FLOE_SUB_B(sub), cb, &rad_j);
        dx = cb[0] - ca[0]; dy = cb[1] - ca[1]; dz = cb[2] - ca[2];
        rs = rad_i + rad_j;
    }
    double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < rs * rs) {
        if (p->kind[i] == FLOE_GEOM_SPHERE && p->kind[j] == FLOE_GEOM_SPHERE) {
            /* sphere-sphere inline (the bounding test above is the exact test) */
            sphere_contact(&c, i, j, xa, xb, p->radius[i], p->radius[j], dx, dy, dz, d2);
            r = spheres = 1;
        } else if (!sub && ((p->kind[i] == FLOE_GEOM_SPHERE && p->kind[j] == FLOE_GEOM_PLANE) ||
                            (p->kind[i] == FLOE_GEOM_PLANE && p->kind[j] == FLOE_GEOM_SPHERE))) {
            /* sphere-wall inline (detection's own kernel, without the call through its
             * pair table): a settled bed has as many of these as contacts between spheres */
            const int sph = p->kind[i] == FLOE_GEOM_SPHERE ? i : j, pl = sph == i ? j : i;
            r = floe_sphere_plane_contact(p->x + 3 * sph, p->radius[sph], p->x + 3 * pl, p->q + 4 * pl, &c);
            c.i = i; c.j = j;
            if (r && sph == j) { /* seen from i, as floe_detect swaps the roles back (defensive: the
                                  * list holds no wall as i, neighbor.c push_pair) */
                double t[3];
                floe_v3_copy(t, c.x1); floe_v3_copy(c.x1, c.x2); floe_v3_copy(c.x2, t);
                floe_v3_scale(c.n, -1.0);
            }
        } else if (env->overlap2d && pair_wants_overlap(w, i, j, nm)) {
            /* two polygons under an overlap law: the overlap is the exact test (area > 0),
             * no deepest-point LP before it */
            floe_body_ref bi = body_ref(w, i), bj = body_ref_at(w, j, xb);
            r = floe_detect_overlap(&dctx, &bi, &bj, sub, warm, &c);
            if (r == -FLOE_ENOTSUP) r = detect_pair_at(w, &dctx, i, j, xb, sub, warm, &c); /* a disc, a wall */
            else ov_done = 1;
        } else if (!w->sep_on || !floe_detect_sep_holds(&dctx)) /* a gap kept: apart, no dispatch */
            r = detect_pair_at(w, &dctx, i, j, xb, sub, warm, &c);
    } else if (!(rs < INFINITY)) {
        r = detect_pair(w, &dctx, i, j, sub, warm, &c);
    } else if (warm) {
        warm[0] = NAN; /* apart: the next approach starts cold */
    }
    const floe_contact_law *law = r > 0 ? w->laws[p->material[i] * nm + p->material[j]] : NULL;
    const floe_law_info linfo = r == 1 && (any_overlap || env->any_floe) ? floe_contact_law_info(law) : (floe_law_info){0};
    if (!ov_done && (linfo.needs_overlap || linfo.prefers_overlap)) {
        floe_body_ref bi = body_ref(w, i), bj = body_ref_at(w, j, xb);
        r = floe_detect_overlap(&dctx, &bi, &bj, sub, NULL, &c);
        if (r == -FLOE_ENOTSUP && linfo.prefers_overlap) { /* not two polytopes: the deepest point */
            r = 1;
            c.area = 0;
        } else if (r == -FLOE_ENOTSUP)
            return floe_world_error(w, FLOE_ENOTSUP,
                                    "contact law %s needs two polytopes (polygons, boxes, prisms, polyhedra); particles %lld and %lld are %s-%s",
                                    law->klass->name, floe_world_pid(w, i), floe_world_pid(w, j), w->geoms[p->geom[i]]->klass->name,
                                    w->geoms[p->geom[j]]->klass->name);
    }
    if (r < 0 && r != -FLOE_ENOTSUP)
        return floe_world_error(w, -r, "contact detection failed for particles %lld and %lld (%s-%s): %s",
                                floe_world_pid(w, i), floe_world_pid(w, j),
                                w->geoms[p->geom[i]]->klass->name, w->geoms[p->geom[j]]->klass->name,
                                r == -FLOE_ENOMEM ? "out of memory" : "degenerate polytope LP");
    if (r < 0)
        return floe_world_error(w, -r, "no contact detector for particles %lld and %lld (%s-%s)", floe_world_pid(w, i),
                                floe_world_pid(w, j),
                                w->geoms[p->geom[i]]->klass->name, w->geoms[p->geom[j]]->klass->name);
    double *hist = nl->hist + (size_t)k * nl->hs;
    if (r == 0) {
        if (nl->touching[k]) pair_release(w, p, nl, k, i, j, stepping, acc, env, xb);
        return FLOE_OK;
    }
    nl->touching[k] = 1;
    /* interpenetration beyond recovery: the centre of the smaller particle inside the
     * other (for spheres the normal would flip and they would pass through), or a
     * particle through a wall */
    if (c.depth > (rs < INFINITY ? rmin(rad_i, rad_j) : 2 * rmin(rad_i, rad_j)))
        return pair_too_deep(w, i, j, c.depth, !(rs < INFINITY), c.n);
    double ri[3], rj[3], ui[3], uj[3];
    if (spheres) sphere_arms(&c, p->radius[i], dx, dy, dz, ri, rj);
    else {
        floe_v3_sub(ri, c.point, xa);
        floe_v3_sub(rj, c.point, xb);
    }
    floe_v3_cross(ui, p->w + 3 * i, ri);
    floe_v3_cross(uj, p->w + 3 * j, rj);
    for (int a = 0; a < 3; a++) c.vr[a] = (p->v[3 * i + a] + ui[a]) - (p->v[3 * j + a] + uj[a]);
    double lb[3];
    floe_v3_sub(lb, xb, xa);
    if (env->cell) pair_affine_sub(env, lb, c.vr);
    c.vn = floe_v3_dot(c.vr, c.n);
    floe_v3_sub(c.wr, p->w + 3 * i, p->w + 3 * j);
    if (track) { /* adaptive steps: overlap change over the step relative to the size */
        double e = fabs(c.vn) * w->dt / rmin(rad_i, rad_j);
        if (e > acc->eta_d) acc->eta_d = e;
    }
    for (int a = 0; a < 3; a++) c.vt[a] = c.vr[a] - c.vn * c.n[a];
    /* inverse masses are 0 for fixed and kinematic particles: m* = the free one's mass */
    c.m_eff = 1.0 / (p->inv_mass[i] + p->inv_mass[j]);
    /* prepare evaluates forces without advancing history; the RK2 midpoint advances it
     * by hist_dt and restores it (the providers' save/restore) */
    c.dt = stepping ? ctx->dt : ctx->hist_dt;
    c.an_ext = w->dash_on ? pair_an_ext(w, p, i, j, &c, hist) : 0.0;
    if (env->any_floe) {
        c.thick_i = floe_particle_thickness(p, i);
        c.thick_j = floe_particle_thickness(p, j);
        c.rad_i = p->radius[i];
        c.rad_j = p->radius[j];
        if (c.nextra > 0 && linfo.single_point) c.nextra = 0;
    }
    /* the manifold's other vertices (polytope pairs, floe_contact.h): elastic springs of
     * the same law, evaluated first so that the law's friction sees their load; the law's
     * dashpot and friction then act at the manifold's load centre */
    double fx[3] = {0, 0, 0}, tx_i[3] = {0, 0, 0}, tx_j[3] = {0, 0, 0}, ex = 0, fe[FLOE_MANIFOLD_EXTRA];
    double f0 = 0, centre[3] = {0, 0, 0}, vr_point[3] = {0, 0, 0};
    if (c.nextra > 0) {
        FLOE_TRY(manifold_springs(w, law, &c, xa, xb, fe, &f0, centre, fx, tx_i, tx_j, &ex));
        /* the law sees the relative velocity at the load centre */
        double rc_i[3], rc_j[3], uc_i[3], uc_j[3];
        floe_v3_copy(vr_point, c.vr);
        floe_v3_sub(rc_i, centre, xa);
        floe_v3_sub(rc_j, centre, xb);
        floe_v3_cross(uc_i, p->w + 3 * i, rc_i);
        floe_v3_cross(uc_j, p->w + 3 * j, rc_j);
        for (int a = 0; a < 3; a++) c.vr[a] = (p->v[3 * i + a] + uc_i[a]) - (p->v[3 * j + a] + uc_j[a]);
        if (env->cell) pair_affine_sub(env, lb, c.vr);
        c.vn = floe_v3_dot(c.vr, c.n);
        for (int a = 0; a < 3; a++) c.vt[a] = c.vr[a] - c.vn * c.n[a];
    }
    floe_contact_result res;
    memset(&res, 0, sizeof res);
    int rc = law->klass->force(law, &c, hist + FLOE_LAW_SLOT, &res);
    if (rc) return pair_law_failed(w, law, rc, i, j, &c);
    if (c.gscale != 1.0) { /* depth growing slower than along n (polytope ridges) */
        floe_v3_scale(res.force, c.gscale);
        floe_v3_scale(res.torque_i, c.gscale);
        floe_v3_scale(res.torque_j, c.gscale);
        res.fn *= c.gscale;
    }
    if (c.nextra > 0) {
        /* the deepest point keeps its elastic force; the law's dashpot and friction act
         * at the load centre: moved there by a couple */
        double rest[3], T[3];
        for (int a = 0; a < 3; a++) rest[a] = res.force[a] + f0 * c.gscale * c.n[a];
        floe_v3_sub(T, centre, c.point);
        floe_v3_cross(T, T, rest);
        floe_v3_add(res.torque_i, res.torque_i, T);
        floe_v3_sub(res.torque_j, res.torque_j, T);
        floe_v3_copy(c.vr, vr_point); /* the ledger: the work of res.force at the point */
        manifold_couples(law, &c, w->def.dim, res.fn, fe, centre, hist + FLOE_TWIST_SLOT, &res);
    } else {
        if (nl->hs > FLOE_TWIST_SLOT) hist[FLOE_TWIST_SLOT] = 0.0;
    }
    double ti[3], tj[3], F[3], Ti[3], Tj[3];
    floe_v3_cross(ti, ri, res.force);
    floe_v3_cross(tj, rj, res.force);
    for (int a = 0; a < 3; a++) {
        F[a] = res.force[a];
        Ti[a] = ti[a] + res.torque_i[a];
        Tj[a] = -tj[a] + res.torque_j[a];
    }
    if (c.nextra > 0)
        for (int a = 0; a < 3; a++) {
            /* the manifold's springs: conservative, their energy is stored, nothing
             * dissipated (their work over a step is the change of their energy up to the
             * integrator's error, which the balance shows) */
            F[a] += fx[a];
            Ti[a] += tx_i[a];
            Tj[a] += tx_j[a];
        }
    pair_apply(p, acc, k, i, j, F, Ti, Tj);
    return pair_book(w, ctx, env, i, j, &c, &res, fx, ex, hist, acc, xb);
}

/* A pair of spheres under Hertz-Mindlin or the linear law, fused (stage_env.fused):
 * sphere_pair + the law's force function (law_kernels.h) + pair_book (and its record of the
 * contact when the evaluation records them, and a periodic cell's sums) in a world without
 * growth, less what that case never reads (the relative spin, the law's result struct and its
 * dissipation sums, the couples' work: the law has none) and without the call through the
 * law's table; the same operations otherwise, so the same bits (tests/test_sphere_path.c).
 * (dx, dy, dz) = x_j - x_i, dist its length (> 0), depth <= the smaller radius, r_eff =
 * r_i r_j / (r_i + r_j), m_eff = 1 / (1/m_i + 1/m_j). The entries go in batches (sph_batch,
 * sph_flush_lanes): the forces (lever arms, the law's stages, the torques: nothing summed)
 * stage by stage over the batch in lanes, then each entry's book (sphere_fused_book: the
 * particles' sums and the ledger) in list order. */
typedef struct sph_out {
    double F[3], Ti[3], Tj[3], energy;
    /* recording (stage_env.record): the contact as contact_pair records it */
    double point[3], n[3], depth, fn, branch[3], r_eff, m_eff;
} sph_out;

/* A batch of entries for the fused kernel, all under one law (sph_flush_lanes). */
#define SPH_BATCH 16
typedef struct sph_batch {
    int n;
    const floe_contact_law *law;
    int k[SPH_BATCH], i[SPH_BATCH], j[SPH_BATCH];
    double dx[SPH_BATCH], dy[SPH_BATCH], dz[SPH_BATCH], d2[SPH_BATCH];
    /* the lanes' inputs (sph_flush_lanes), gathered as each entry joins: the radii, 1/m_i +
     * 1/m_j, the velocities and spins, a_i - a_j (w->dash_a), the history's spring, dashpot
     * phase, last force and stored energy; the centres only for a wall's entry or a stage
     * that records its contacts (sph_lane_gather's centres) */
    double ra[SPH_BATCH], rb[SPH_BATCH], im[SPH_BATCH], xa[3][SPH_BATCH], xb[3][SPH_BATCH], vi[3][SPH_BATCH],
        vj[3][SPH_BATCH], wi[3][SPH_BATCH], wj[3][SPH_BATCH], aij[3][SPH_BATCH], s[3][SPH_BATCH], h3[SPH_BATCH],
        fo[3][SPH_BATCH], eo[SPH_BATCH];
    /* sphere-wall entries (sphere_wall_pair; wall[q] = 1) among the sphere pairs, in list
     * order: their geometry as floe_sphere_plane_contact finds it, seen from i: the normal,
     * the depth, r_eff (the sphere's radius) and the contact point */
    int nwall;
    double wall[SPH_BATCH]; /* 1 or 0 (a double: the flush's loops select by it in vector lanes) */
    double wn[3][SPH_BATCH], wdep[SPH_BATCH], wreff[SPH_BATCH], wpt[3][SPH_BATCH];
} sph_batch;

/* A batch's book sums (the stage's elastic energy and dissipation, the watchdog's minimum,
 * the contact count), held in locals over the batch (sph_flush_lanes) and written back at its
 * end: added through acc one entry after the other, each was a chain of loads and stores
 * through memory (the history's and the forces' stores may alias them, so the compiler kept
 * them there). The same additions in the same order: the same bits. (The i-side of a row's
 * run of entries held the same way was slower, in sessions 37 and 39: a mispredicted branch
 * at each change of row; not kept.) */
typedef struct sph_sums {
    double elastic, diss, wd_min;
    int wd_i, wd_j;
    long ncontacts;
} sph_sums;

static inline __attribute__((always_inline)) void sph_sums_take(sph_sums *ls, const stage_acc *acc) {
    ls->elastic = acc->elastic;
    ls->diss = acc->diss;
    ls->wd_min = acc->wd_min;
    ls->wd_i = acc->wd_i;
    ls->wd_j = acc->wd_j;
    ls->ncontacts = acc->ncontacts;
}
static inline __attribute__((always_inline)) void sph_sums_put(const sph_sums *ls, stage_acc *acc) {
    acc->elastic = ls->elastic;
    acc->diss = ls->diss;
    acc->wd_min = ls->wd_min;
    acc->wd_i = ls->wd_i;
    acc->wd_j = ls->wd_j;
    acc->ncontacts = ls->ncontacts;
}

/* the book of entry k: the particles' sums and the ledger, in list order; dk the work the
 * contact did less the change of its stored energy (pair_book's ledger) */
static inline __attribute__((always_inline)) void sphere_fused_book(floe_world *w, const stage_env *env, int k,
                                                                   stage_acc *acc, sph_sums *ls,
                                                                   int i, int j, double *hist, const sph_out *o,
                                                                   double dk) {
    pair_apply(env->p, acc, k, i, j, o->F, o->Ti, o->Tj);
    const double energy = o->energy;
    ls->elastic += energy;
    if (env->stepping) { /* pair_book's ledger: dk from the lanes (sph_flush_lanes) */
        ls->diss += dk;
        hist[FLOE_DISS_SLOT] += dk;
        const double life = hist[FLOE_DISS_SLOT] + energy; /* acc_life */
        if (life < ls->wd_min) { ls->wd_min = life; ls->wd_i = i; ls->wd_j = j; }
    }
    hist[FLOE_ENERGY_SLOT] = energy;
    memcpy(hist + FLOE_FORCE_SLOT, o->F, 3 * sizeof(double));
    if (!env->record) {
        ls->ncontacts++;
        return;
    }
    /* pair_book's record: the manifold's force, fn_extra and energy (zeros) added as it adds them */
    floe_contact c;
    floe_contact_result r;
    c.i = i;
    c.j = j;
    for (int a = 0; a < 3; a++) {
        c.point[a] = o->point[a];
        c.n[a] = o->n[a];
        r.force[a] = o->F[a] + 0.0;
    }
    c.depth = o->depth;
    c.r_eff = o->r_eff;
    c.m_eff = o->m_eff;
    r.fn = o->fn + 0.0;
    r.energy = energy + 0.0;
    if (push_contact(w, acc->rs, &c, &r, o->branch)) acc->oom = 1;
}

/* entry q's inputs to the lanes (sph_flush_lanes), as it joins the batch (xb: j's centre,
 * or its image's in a periodic cell); lin: the linear law's too (the dashpot's phase and
 * a_i - a_j, the last force); centres: the two centres too (a wall's entry, or a stage that
 * records its contacts: the point; a sphere pair's lever arms come from the centre line) */
static inline __attribute__((always_inline)) void sph_lane_gather(const floe_world *w, const floe_particles *p,
                                                                 sph_batch *b, int q, int i, int j, const double *xb,
                                                                 const double *hist, double rad_i, double rad_j,
                                                                 double im, int lin, int centres) {
    b->ra[q] = rad_i;
    b->rb[q] = rad_j;
    b->im[q] = im;
    if (centres) /* a wall's lever arms, a record's point (sphere pairs' arms: sphere_arms) */
        for (int a = 0; a < 3; a++) {
            b->xa[a][q] = p->x[3 * i + a];
            b->xb[a][q] = xb[a];
        }
    for (int a = 0; a < 3; a++) {
        b->vi[a][q] = p->v[3 * i + a];
        b->vj[a][q] = p->v[3 * j + a];
        b->wi[a][q] = p->w[3 * i + a];
        b->wj[a][q] = p->w[3 * j + a];
        b->s[a][q] = hist[FLOE_LAW_SLOT + a];
        b->fo[a][q] = hist[FLOE_FORCE_SLOT + a];
    }
    b->eo[q] = hist[FLOE_ENERGY_SLOT];
    if (!lin) return;
    b->h3[q] = hist[FLOE_LAW_SLOT + 3];
    const int dash = w->dash_on;
    for (int a = 0; a < 3; a++) b->aij[a][q] = dash ? w->dash_a[3 * (size_t)i + a] - w->dash_a[3 * (size_t)j + a] : 0.0;
}

/* A batch in lanes: every stage's operations on arrays of the batch's contacts, one array
 * per quantity, so that the compiler runs each stage over 8 contacts at a time (AVX-512; 4
 * with AVX2) where the scalar stages before ran one contact after the other: the geometry
 * and velocities with the other forces' normal acceleration (pair_an_ext), the springs
 * turned with the contact frames, then the law's normal force and tangential spring
 * (floe_hertz_normal_lane, floe_mindlin_trial and floe_mindlin_slip, or floe_linear_normal_lane,
 * floe_coulomb_trial_rotated and floe_coulomb_slip: every case computed and the one that
 * applies selected, without a branch per lane) and the torques; then the books in list order.
 * A rare case's full form (a spring turned by more than 0.01 rad, a linear contact's first
 * evaluation, a slip) runs only for a batch where a live lane needs it, and the linear law's
 * last-evaluation phase only under a law with tension: one branch a batch (or a law), and
 * their divisions and square roots left out of the others (issue 14 session 39; the counts
 * in docs/architecture.md, "Session 39"). The inputs are the batch's arrays
 * (sph_lane_gather, as each entry joined; the lanes past nb hold an earlier batch's entries or
 * zeros, their results are dropped; the centres XA, XB are a wall lane's, or every lane's
 * when recording: a sphere pair's lane otherwise holds stale ones, read by no kept result). Each
 * lane does the scalar operations in their order (no contraction in ISO C): the same bits
 * as the law's own force function (tests/test_sphere_path.c, which also counts the batches
 * that took each rare case, w->st_lanes). Out of line: inlined at each flush of stage_block,
 * some copies stayed scalar (the RVE 1.5x slower). The ParticLS 5.3 RVE 14 % and dem-settle
 * 8 % faster on one thread (bench/RESULTS.md, issue 14 session 13). */
#define SL SPH_BATCH
/* lane q's results: the force -Fn n + Ft on i, the spring s, the energy, and the torques
 * about the centres from the lever arms Ri, Rj (+ the law's couples, zero, as sphere_pair
 * adds them) */
static inline __attribute__((always_inline)) void lane_out(int q, double fn, const double n[3], const double Ft[3],
                                                          const double s[3], double energy, double (*Ri)[SL],
                                                          double (*Rj)[SL], double (*S)[SL], double (*F)[SL],
                                                          double (*TI)[SL], double (*TJ)[SL], double *E) {
    double f[3], ri[3], rj[3], ti[3], tj[3];
    for (int a = 0; a < 3; a++) {
        f[a] = -fn * n[a] + Ft[a];
        S[a][q] = s[a];
        F[a][q] = f[a];
        ri[a] = Ri[a][q];
        rj[a] = Rj[a][q];
    }
    E[q] = energy;
    floe_cross3_l(ti, ri, f);
    floe_cross3_l(tj, rj, f);
    for (int a = 0; a < 3; a++) {
        TI[a][q] = ti[a] + 0.0;
        TJ[a][q] = -tj[a] + 0.0;
    }
}
static __attribute__((noinline)) void sph_flush_lanes(floe_world *w, const floe_step_ctx *ctx,
                                                                  const stage_env *env, stage_acc *acc, sph_batch *b) {
    const floe_linear_law *L = (const floe_linear_law *)b->law; /* read unless hm */
    const int hm = b->law->klass == &floe_hertz_mindlin_law_class;
    const int nb = b->n, dash = w->dash_on && !hm, tension = hm ? 0 : L->tension;
    const size_t hs = (size_t)env->nl->hs;
    const double dt = env->stepping ? ctx->dt : ctx->hist_dt;
    /* the batch's arrays (sph_lane_gather), all SL lanes: those past nb hold an earlier
     * batch's entries or zeros, their results dropped (and XA, XB stale in a sphere pair's
     * lane unless the stage records: only a wall lane's arms and the record's point read
     * them) */
    const double *RI = b->ra, *RJ = b->rb, *IM = b->im, *H3i = b->h3;
    const double *D[3] = {b->dx, b->dy, b->dz};
    double (*XA)[SL] = b->xa, (*XB)[SL] = b->xb, (*VI)[SL] = b->vi, (*VJ)[SL] = b->vj, (*WI)[SL] = b->wi,
           (*WJ)[SL] = b->wj, (*AIJ)[SL] = b->aij, (*FO)[SL] = b->fo;
    double S[3][SL], H3[SL];
    const double kn = hm ? 0 : L->kn, gn = hm ? 0 : L->gn, ks = hm ? 0 : L->ks, gs = hm ? 0 : L->gs, mu = hm ? 0 : L->mu;
    const double minus_inv_ks = ks > 0.0 ? -1.0 / ks : 0.0;
    /* dist = |x_j - x_i|, depth = r_i + r_j - dist, r_eff = r_i r_j / (r_i + r_j), m_eff =
     * 1 / (1/m_i + 1/m_j) */
    double depth[SL], reff[SL], meff[SL];
    /* r_eff: Hertz-Mindlin's, and the record's and a periodic cell's stiffness sums (a
     * division a lane: the linear law alone leaves it) */
    const int want_reff = hm || env->record || (env->cell && env->cell->want_kdiag);
    /* geometry, velocities, the other forces' normal acceleration */
    double N[3][SL], Ri[3][SL], Rj[3][SL], VR[3][SL], VT[3][SL], VN[SL], AN[SL], PT[3][SL], FN[SL];
    /* a periodic cell: the mean field's velocity of i relative to j's image, -L l with l =
     * (dx, dy, dz) (pair_affine_sub's operations; selected, so a world without a cell keeps
     * its bits) */
    static const double L0[9];
    const int cel = env->cell != NULL;
    const double *LC = cel ? env->cell->L : L0;
    /* the gradient's entries as locals: loaded inside the lanes' loop under the select below,
     * GCC made them masked loads it cannot vectorize, and the whole kinematics loop ran scalar */
    double LCl[9];
    for (int a = 0; a < 9; a++) LCl[a] = LC[a];
    /* lane q's kinematics from its normal n and lever arms ri, rj (from the centres to the
     * contact point: the relative velocity there and its parts, the overlap change,
     * pair_an_ext with gscale 1) */
#define LANE_KIN(q, n, ri, rj)                                                                                  \
    do {                                                                                                        \
        double ri_[3], rj_[3], wi_[3], wj_[3], ui_[3], uj_[3], vr_[3];                                          \
        for (int a = 0; a < 3; a++) {                                                                           \
            ri_[a] = (ri)[a];                                                                                   \
            rj_[a] = (rj)[a];                                                                                   \
            wi_[a] = WI[a][q];                                                                                  \
            wj_[a] = WJ[a][q];                                                                                  \
        }                                                                                                       \
        floe_cross3_l(ui_, wi_, ri_);                                                                           \
        floe_cross3_l(uj_, wj_, rj_);                                                                           \
        for (int a = 0; a < 3; a++) {                                                                           \
            const double v_ = (VI[a][q] + ui_[a]) - (VJ[a][q] + uj_[a]);                                       \
            const double la_ = LCl[3 * a] * D[0][q] + LCl[3 * a + 1] * D[1][q] + LCl[3 * a + 2] * D[2][q];     \
            vr_[a] = cel ? v_ - la_ : v_;                                                                       \
        }                                                                                                       \
        const double vn_ = floe_dot3_l(vr_, n);                                                                 \
        for (int a = 0; a < 3; a++) {                                                                           \
            N[a][q] = (n)[a];                                                                                   \
            Ri[a][q] = ri_[a];                                                                                  \
            Rj[a][q] = rj_[a];                                                                                  \
            VR[a][q] = vr_[a];                                                                                  \
            VT[a][q] = vr_[a] - vn_ * (n)[a];                                                                   \
        }                                                                                                       \
        VN[q] = vn_;                                                                                            \
        const double an_ = AIJ[0][q] * (n)[0] + AIJ[1][q] * (n)[1] + AIJ[2][q] * (n)[2];                        \
        const double fo_ = FO[0][q] * (n)[0] + FO[1][q] * (n)[1] + FO[2][q] * (n)[2];                           \
        AN[q] = dash ? an_ - fo_ * IM[q] : 0.0;                                                                 \
    } while (0)
    if (b->nwall) { /* sphere-wall entries among them: their geometry found as they joined */
        double dist[SL];
        for (int q = 0; q < SL; q++) {
            const double rs = RI[q] + RJ[q];
            const int wl = b->wall[q] != 0.0;
            dist[q] = sqrt(b->d2[q]);
            depth[q] = wl ? b->wdep[q] : rs - dist[q];
            meff[q] = 1.0 / IM[q];
        }
        if (want_reff)
            for (int q = 0; q < SL; q++) reff[q] = b->wall[q] != 0.0 ? b->wreff[q] : RI[q] * RJ[q] / (RI[q] + RJ[q]);
        for (int q = 0; q < SL; q++) {
            const double inv = 1.0 / dist[q];
            const int wl = b->wall[q] != 0.0;
            double n[3], ns[3], d[3], si[3], sj[3], ri[3], rj[3];
            for (int a = 0; a < 3; a++) {
                ns[a] = D[a][q] * inv;
                d[a] = D[a][q];
            }
            sphere_arms_l(RI[q], depth[q], ns, d, si, sj);
            for (int a = 0; a < 3; a++) { /* a wall's lane: from its contact point (XA, XB gathered) */
                const double pw = b->wpt[a][q];
                n[a] = wl ? b->wn[a][q] : ns[a];
                ri[a] = wl ? pw - XA[a][q] : si[a];
                rj[a] = wl ? pw - XB[a][q] : sj[a];
            }
            LANE_KIN(q, n, ri, rj);
        }
    } else {
        double dist[SL];
        for (int q = 0; q < SL; q++) {
            dist[q] = sqrt(b->d2[q]);
            depth[q] = (RI[q] + RJ[q]) - dist[q];
            meff[q] = 1.0 / IM[q];
        }
        if (want_reff)
            for (int q = 0; q < SL; q++) reff[q] = RI[q] * RJ[q] / (RI[q] + RJ[q]);
        for (int q = 0; q < SL; q++) {
            const double inv = 1.0 / dist[q];
            double n[3], d[3], ri[3], rj[3];
            for (int a = 0; a < 3; a++) {
                n[a] = D[a][q] * inv;
                d[a] = D[a][q];
            }
            sphere_arms_l(RI[q], depth[q], n, d, ri, rj);
            LANE_KIN(q, n, ri, rj);
        }
    }
#undef LANE_KIN
    if (env->record) /* the record's point: a wall's from its detector, else the middle of the two
                      * surface points (sphere_contact's; N holds a sphere lane's normal) */
        for (int q = 0; q < SL; q++)
            for (int a = 0; a < 3; a++) {
                const double x1 = XA[a][q] + RI[q] * N[a][q], x2 = XB[a][q] - RJ[q] * N[a][q];
                PT[a][q] = b->wall[q] != 0.0 ? b->wpt[a][q] : 0.5 * (x1 + x2);
            }
    /* the springs turned with the contact frames (floe_contact_rotate_history): its common
     * cases on every lane, its full form on every lane only when a live lane's frame turned by
     * more than 0.01 rad in the step (a square root and a division a lane left out otherwise) */
    double S0[3][SL];
    {
        double TURN[SL]; /* 0 or 1: doubles, as the lanes' other arrays (the loop stays vector code) */
        for (int q = 0; q < SL; q++) {
            double s[3], n[3];
            for (int a = 0; a < 3; a++) {
                s[a] = b->s[a][q];
                n[a] = N[a][q];
            }
            TURN[q] = floe_contact_rotate_history_small(s, n);
            for (int a = 0; a < 3; a++) S0[a][q] = s[a];
        }
        int turn = 0;
        for (int q = 0; q < nb; q++) turn |= TURN[q] != 0.0;
        if (!acc->pf) { /* one thread only: the counts are the tests' */
            w->st_lanes[0]++;
            w->st_lanes[1] += turn;
        }
        if (turn)
            for (int q = 0; q < SL; q++) {
                double s[3], n[3];
                for (int a = 0; a < 3; a++) {
                    s[a] = b->s[a][q];
                    n[a] = N[a][q];
                }
                floe_contact_rotate_history(s, n);
                for (int a = 0; a < 3; a++) S0[a][q] = s[a];
            }
    }
    /* the normal force and the tangential trial on every lane (S1: the spring, FT: the force,
     * LIM: the Coulomb limit, FT2: |FT|^2, EN: the normal part's stored energy), then the slip's
     * values only for a batch with a live lane that slips (the law's slip: a square root and a
     * division a lane), then the forces and torques (F, TI, TJ, E) */
    double F[3][SL], TI[3][SL], TJ[3][SL], E[SL];
    double S1[3][SL], FT[3][SL], LIM[SL], FT2[SL], EN[SL], GT[SL], HIK[SL];
    if (hm) { /* floe_hm_kernel: floe_hertz_normal, floe_mindlin_tangential (its dissipation sums, diss, unread here) */
        const floe_hertz_mindlin_law *H = (const floe_hertz_mindlin_law *)b->law;
        const double e_star = H->e_star, beta = H->damping_ratio, g_star = H->g_star, tdr = H->tangent_damping_ratio,
                     mu_h = H->mu;
        for (int q = 0; q < SL; q++) {
            double fn, fel, Sn, gnq, en, diss = 0.0, s[3], vt[3], Ft[3];
            floe_hertz_normal_lane(e_star, beta, depth[q], VN[q], reff[q], meff[q], &fn, &fel, &Sn, &gnq, &en);
            for (int a = 0; a < 3; a++) {
                s[a] = S0[a][q];
                vt[a] = VT[a][q];
            }
            floe_mindlin_trial(g_star, tdr, mu_h, dt, reff[q], depth[q], vt, gnq, fn, 0.0, s, Ft, &GT[q], &LIM[q], &FT2[q],
                               &HIK[q], &diss);
            for (int a = 0; a < 3; a++) {
                S1[a][q] = s[a];
                FT[a][q] = Ft[a];
            }
            EN[q] = en;
            FN[q] = fn;
        }
    } else {
        /* the linear law in four copies, one for each value of the law's tension switch and of
         * "a live lane's first evaluation" (history[3] == 0): without tension (the usual case)
         * the dashpot's last-evaluation phase is never taken, and without a first evaluation
         * (most batches) its onset phase neither: their divisions drop out
         * (floe_linear_phase_lane). The same operations on the lanes whose results are kept. */
        int first = 0;
        for (int q = 0; q < nb; q++) first |= H3i[q] == 0.0;
        if (!acc->pf) w->st_lanes[2] += first;
#define LIN_TRIAL(TENSION, FIRST)                                                                               \
    for (int q = 0; q < SL; q++) {                                                                             \
        double fn, fel, en, h3 = H3i[q], s[3], vt[3], Ft[3], lim, ft2;                                         \
        floe_linear_normal_lane(kn, gn, (TENSION), depth[q], VN[q], dt, meff[q], AN[q], &h3, &fn, &fel, &en,   \
                                (FIRST));                                                                      \
        H3[q] = h3;                                                                                            \
        for (int a = 0; a < 3; a++) {                                                                          \
            s[a] = S0[a][q];                                                                                   \
            vt[a] = VT[a][q];                                                                                  \
        }                                                                                                      \
        floe_coulomb_trial_rotated(vt, dt, ks, gs, mu, fabs(fn) + 0.0, s, Ft, &lim, &ft2); /* + fn_extra, 0 */ \
        for (int a = 0; a < 3; a++) {                                                                          \
            S1[a][q] = s[a];                                                                                   \
            FT[a][q] = Ft[a];                                                                                  \
        }                                                                                                      \
        LIM[q] = lim;                                                                                          \
        FT2[q] = ft2;                                                                                          \
        EN[q] = en;                                                                                            \
        FN[q] = fn;                                                                                            \
    }
        if (tension) {
            if (first) LIN_TRIAL(1, 1)
            else LIN_TRIAL(1, 0)
        } else {
            if (first) LIN_TRIAL(0, 1)
            else LIN_TRIAL(0, 0)
        }
#undef LIN_TRIAL
    }
    int slips = 0;
    for (int q = 0; q < nb; q++) slips |= FT2[q] > LIM[q] * LIM[q];
    if (!acc->pf) w->st_lanes[3] += slips;
    /* the slip's values where a lane slips (SLIPS, a constant: the copy without them for a
     * batch where none does), its stored energy, the force and torques; HM a constant too (a
     * test of hm inside the loop kept it scalar) */
#define LANES_OUT(HM, SLIPS)                                                                                     \
    for (int q = 0; q < SL; q++) {                                                                             \
        double s[3], n[3], vt[3], Ft[3];                                                                       \
        for (int a = 0; a < 3; a++) {                                                                          \
            s[a] = S1[a][q];                                                                                   \
            n[a] = N[a][q];                                                                                    \
            vt[a] = VT[a][q];                                                                                  \
            Ft[a] = FT[a][q];                                                                                  \
        }                                                                                                      \
        double en;                                                                                             \
        if (HM) {                                                                                              \
            double diss = 0.0;                                                                                 \
            if (SLIPS) floe_mindlin_slip(GT[q], vt, LIM[q], FT2[q], HIK[q], s, Ft, &diss);                     \
            en = EN[q] + floe_dot3_l(s, s) * HIK[q];                                                           \
        } else {                                                                                               \
            if (SLIPS) { /* floe_coulomb_slip's values where it slips */                                       \
                const double lim = LIM[q], ft2 = FT2[q];                                                       \
                const int slip = ft2 > lim * lim;                                                              \
                double fs[3], ss[3];                                                                           \
                floe_coulomb_slip(vt, ks, gs, minus_inv_ks, lim / sqrt(ft2), Ft, fs, ss);                      \
                for (int a = 0; a < 3; a++) {                                                                  \
                    Ft[a] = slip ? fs[a] : Ft[a];                                                              \
                    s[a] = slip ? ss[a] : s[a];                                                                \
                }                                                                                              \
            }                                                                                                  \
            en = EN[q] + 0.5 * ks * floe_dot3_l(s, s);                                                         \
        }                                                                                                      \
        lane_out(q, FN[q], n, Ft, s, en, Ri, Rj, S, F, TI, TJ, E);                                             \
    }
    if (hm) {
        if (slips) LANES_OUT(1, 1)
        else LANES_OUT(1, 0)
    } else {
        if (slips) LANES_OUT(0, 1)
        else LANES_OUT(0, 0)
    }
#undef LANES_OUT
    /* the ledger's work less the change of stored energy: (F_old + F_new)/2 . vr dt - dE */
    double DK[SL];
    for (int q = 0; q < SL; q++) {
        double fav[3], vr[3];
        for (int a = 0; a < 3; a++) {
            fav[a] = 0.5 * (F[a][q] + FO[a][q]);
            vr[a] = VR[a][q];
        }
        DK[q] = -floe_dot3_l(fav, vr) * dt - (E[q] - b->eo[q]);
    }
    if (env->track) /* the largest overlap change over the step, relative to the size (a max: any order) */
        for (int q = 0; q < nb; q++) {
            const double eta = fabs(VN[q]) * w->dt / (RI[q] < RJ[q] ? RI[q] : RJ[q]);
            if (eta > acc->eta_d) acc->eta_d = eta;
        }
    sph_sums ls;
    sph_sums_take(&ls, acc);
    for (int q = 0; q < nb; q++) {
        double *h = env->nl->hist + (size_t)b->k[q] * hs;
        for (int a = 0; a < 3; a++) h[FLOE_LAW_SLOT + a] = S[a][q];
        if (!hm) h[FLOE_LAW_SLOT + 3] = H3[q];
        if (hs > FLOE_TWIST_SLOT) h[FLOE_TWIST_SLOT] = 0.0;
        sph_out o;
        for (int a = 0; a < 3; a++) {
            o.F[a] = F[a][q];
            o.Ti[a] = TI[a][q];
            o.Tj[a] = TJ[a][q];
        }
        o.energy = E[q];
        if (cel) { /* pair_book's sums of a periodic cell, in list order */
            const double l[3] = {D[0][q], D[1][q], D[2][q]};
            double ft[3];
            for (int a = 0; a < 3; a++) ft[a] = o.F[a] + 0.0; /* + the manifold's force, 0 */
            for (int a = 0; a < 3; a++)
                for (int c = 0; c < 3; c++) acc->vir[3 * a + c] += l[a] * ft[c];
            if (env->cell->want_kdiag) {
                double kn = 0, cn = 0;
                if (b->law->klass->stiffness) b->law->klass->stiffness(b->law, reff[q], meff[q], depth[q], &kn, &cn);
                for (int a = 0; a < 3; a++)
                    for (int c = 0; c < 3; c++) acc->kdiag[3 * a + c] += kn * N[a][q] * N[a][q] * l[c] * l[c];
            }
            if (env->stepping) { /* the work of the cell's deformation on the contact: fav . L l dt */
                double fav[3], la[3];
                for (int a = 0; a < 3; a++) {
                    fav[a] = 0.5 * (F[a][q] + FO[a][q]);
                    la[a] = LC[3 * a] * l[0] + LC[3 * a + 1] * l[1] + LC[3 * a + 2] * l[2];
                }
                acc->wgrow += floe_v3_dot(fav, la) * dt;
            }
        }
        if (env->record) { /* the contact as contact_pair records it */
            for (int a = 0; a < 3; a++) {
                o.point[a] = PT[a][q];
                o.n[a] = N[a][q];
                o.branch[a] = XB[a][q] - XA[a][q];
            }
            o.depth = depth[q];
            o.fn = FN[q];
            o.r_eff = reff[q];
            o.m_eff = meff[q];
        }
        sphere_fused_book(w, env, b->k[q], acc, &ls, b->i[q], b->j[q], h, &o, DK[q]);
    }
    sph_sums_put(&ls, acc);
    b->n = 0;
    b->nwall = 0; /* the flags past the next batch's end are stale, their lanes dropped */
}
#undef SL

/* Entry k when both particles are spheres, under a law that needs no overlap area: the
 * operations of contact_pair in the same order (the same bits), without the branches of
 * other shapes (warm starts, pieces, the manifold, the ridge scale) and inlined into the
 * stage's loop; a settled bed of 20,000 spheres spends most of its step here. */
static inline __attribute__((always_inline)) int sphere_pair(floe_world *w, const floe_step_ctx *ctx,
                                                             const stage_env *env, int k, stage_acc *acc,
                                                             sph_batch *b) {
    floe_particles *p = env->p;
    floe_neighbor_list *nl = env->nl;
    const int i = nl->pi[k], j = nl->pj[k];
    double xs[3];
    const double *xa = p->x + 3 * i, *xb = pair_image(env, k, p->x + 3 * j, xs);
    const double rad_i = p->radius[i], rad_j = p->radius[j];
    const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2], rs = rad_i + rad_j;
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (!(d2 < rs * rs)) {
        if (nl->touching[k]) {
            if (b->n) sph_flush_lanes(w, ctx, env, acc, b); /* the sums in list order */
            pair_release(w, p, nl, k, i, j, env->stepping, acc, env, xb);
        }
        return FLOE_OK;
    }
    const floe_contact_law *law = env->law1 ? env->law1 : w->laws[p->material[i] * env->nm + p->material[j]];
    if (env->any_none && floe_contact_law_no_contact(law)) return FLOE_OK;
    double *hist = nl->hist + (size_t)k * nl->hs;
    nl->touching[k] = 1;
    if (env->fused && (law->klass == &floe_hertz_mindlin_law_class || law->klass == &floe_linear_law_class)) {
        const double im = p->inv_mass[i] + p->inv_mass[j], rmn = rmin(rad_i, rad_j), rmx = rs - rmn;
        /* dist = |x_j - x_i| > 0, depth = rs - dist in (0, the smaller radius]: decided from d2
         * alone when it is clearly so (margins of 1e-9, far above the rounding of the square
         * root and of rs - dist), so that the square root goes to the lanes with the rest; at
         * the edges, by the square root itself. Else the checks below and the law's own, with
         * their messages (Hertz-Mindlin at depth 0 by rounding: the law resets its spring).
         * The linear law has no branch on the depth: depth <= 0 by rounding (d2 < rs^2 with
         * dist = rs, the touching neighbours of a lattice) is for the lanes as for the law */
        const int lin = law->klass == &floe_linear_law_class;
        int in = d2 > 0 && (lin || d2 < rs * rs * (1 - 1e-9)) && d2 > rmx * rmx * (1 + 3e-9);
        if (!in) {
            const double dist = sqrt(d2), depth = rs - dist;
            in = dist > 0 && (depth > 0 || lin) && depth <= rmn;
        }
        if (in && im > 0 && im < INFINITY) {
            if (b->n && b->law != law) sph_flush_lanes(w, ctx, env, acc, b);
            const int q = b->n++;
            b->wall[q] = 0.0;
            /* the lanes' inputs now (stage_block prefetched them 8 entries ahead) */
            sph_lane_gather(w, p, b, q, i, j, xb, hist, rad_i, rad_j, im, lin, env->record);
            b->law = law;
            b->k[q] = k; b->i[q] = i; b->j[q] = j;
            b->dx[q] = dx; b->dy[q] = dy; b->dz[q] = dz; b->d2[q] = d2;
            if (b->n == SPH_BATCH) sph_flush_lanes(w, ctx, env, acc, b);
            return FLOE_OK;
        }
    }
    if (b->n) sph_flush_lanes(w, ctx, env, acc, b);
    floe_contact c;
    c.gscale = 1.0;
    c.nextra = 0;
    c.fn_extra = 0.0;
    sphere_contact(&c, i, j, xa, xb, rad_i, rad_j, dx, dy, dz, d2);
    /* the centre of the smaller sphere inside the other: the normal would flip */
    if (c.depth > rmin(rad_i, rad_j)) return pair_too_deep(w, i, j, c.depth, 0, c.n);
    const double *wi = p->w + 3 * i, *wj = p->w + 3 * j, *vi = p->v + 3 * i, *vj = p->v + 3 * j;
    double ri[3], rj[3], ui[3], uj[3];
    sphere_arms(&c, rad_i, dx, dy, dz, ri, rj);
    floe_v3_cross(ui, wi, ri);
    floe_v3_cross(uj, wj, rj);
    for (int a = 0; a < 3; a++) c.vr[a] = (vi[a] + ui[a]) - (vj[a] + uj[a]);
    if (env->cell) {
        const double l[3] = {dx, dy, dz};
        pair_affine_sub(env, l, c.vr);
    }
    c.vn = floe_v3_dot(c.vr, c.n);
    floe_v3_sub(c.wr, wi, wj);
    if (env->track) {
        double e = fabs(c.vn) * w->dt / rmin(rad_i, rad_j);
        if (e > acc->eta_d) acc->eta_d = e;
    }
    for (int a = 0; a < 3; a++) c.vt[a] = c.vr[a] - c.vn * c.n[a];
    c.m_eff = 1.0 / (p->inv_mass[i] + p->inv_mass[j]);
    c.dt = env->stepping ? ctx->dt : ctx->hist_dt;
    c.an_ext = w->dash_on ? pair_an_ext(w, p, i, j, &c, hist) : 0.0;
    floe_contact_result res;
    memset(&res, 0, sizeof res);
    int rc = law->klass->force(law, &c, hist + FLOE_LAW_SLOT, &res);
    if (rc) return pair_law_failed(w, law, rc, i, j, &c);
    if (nl->hs > FLOE_TWIST_SLOT) hist[FLOE_TWIST_SLOT] = 0.0;
    double ti[3], tj[3], Ti[3], Tj[3];
    floe_v3_cross(ti, ri, res.force);
    floe_v3_cross(tj, rj, res.force);
    for (int a = 0; a < 3; a++) {
        Ti[a] = ti[a] + res.torque_i[a];
        Tj[a] = -tj[a] + res.torque_j[a];
    }
    pair_apply(p, acc, k, i, j, res.force, Ti, Tj);
    const double zero[3] = {0, 0, 0};
    return pair_book(w, ctx, env, i, j, &c, &res, zero, 0.0, hist, acc, xb);
}

/* the warm slot and the history of the convex pair two candidates ahead of q, on their way
 * (a settled polyhedra bed: 7 % of the step waited for them; sphere scenes have no slot) */
static inline void prefetch_ahead(const floe_neighbor_list *nl, const int *cand, int q, int nc) {
    if (q + 2 >= nc || !nl->use_warm) return;
    const size_t k2 = (size_t)cand[q + 2];
    __builtin_prefetch(nl->warm + k2 * FLOE_DETECT_WARM);
    __builtin_prefetch(nl->warm + k2 * FLOE_DETECT_WARM + 8);
    __builtin_prefetch(nl->warm + k2 * FLOE_DETECT_WARM + FLOE_DETECT_WARM - 1);
    __builtin_prefetch(nl->hist + k2 * nl->hs);
}

/* Entry k of a sphere and a wall (a plane): floe_sphere_plane_contact's test and geometry,
 * seen from i as contact_pair sees it. Apart and untouched before (most wall entries: the
 * wall's bounding radius is infinite, so all of them pass the filter): nothing. Touching,
 * under a built-in law fused in lanes (stage_env.fused), with a depth the law takes (0 <
 * depth <= the sphere's diameter) and a free sphere: the entry joins the batch of sphere
 * pairs in list order (sph_flush_lanes, b->wall[q]), which runs the operations of
 * contact_pair and the law in their order (the same bits, tests/test_sphere_path.c). Anything
 * else (a release, an error with its message, another law): contact_pair. A settled bed of
 * 20,000 spheres in a box spent 7 % of its step on its walls' contacts through contact_pair
 * and the law's table. The walls' entries lie among the spheres' in the list (the ParticLS
 * 5.3 RVE: one in about 40 contacts): a batch of their own would end the spheres' at each. */
static __attribute__((noinline)) int sphere_wall_pair(floe_world *w, const floe_step_ctx *ctx,
                                                                  const stage_env *env, int k, stage_acc *acc,
                                                                  sph_batch *b) {
    floe_particles *p = env->p;
    floe_neighbor_list *nl = env->nl;
    const int i = nl->pi[k], j = nl->pj[k];
    const int sph = p->kind[i] == FLOE_GEOM_SPHERE ? i : j, pl = sph == i ? j : i;
    const double r = p->radius[sph], *xs = p->x + 3 * sph;
    floe_contact c;
    const int hit = floe_sphere_plane_contact(xs, r, p->x + 3 * pl, p->q + 4 * pl, &c);
    if (!hit && !nl->touching[k]) return FLOE_OK; /* apart, nothing to release */
    if (hit && env->fused) {
        const floe_contact_law *law = env->law1 ? env->law1 : w->laws[p->material[i] * env->nm + p->material[j]];
        if (env->any_none && floe_contact_law_no_contact(law)) return FLOE_OK;
        const double depth = c.depth, im = p->inv_mass[i] + p->inv_mass[j];
        if ((law->klass == &floe_hertz_mindlin_law_class || law->klass == &floe_linear_law_class) && depth > 0 &&
            depth <= 2 * r && im > 0 && im < INFINITY) {
            double *hist = nl->hist + (size_t)k * nl->hs;
            nl->touching[k] = 1;
            if (b->n && b->law != law) sph_flush_lanes(w, ctx, env, acc, b);
            const int q = b->n++;
            b->wall[q] = 1.0;
            b->nwall++;
            b->d2[q] = 1.0; /* the sphere pairs' geometry, computed for every lane, is dropped */
            b->dx[q] = b->dy[q] = b->dz[q] = 0.0;
            sph_lane_gather(w, p, b, q, i, j, p->x + 3 * j, hist, p->radius[i], p->radius[j], im,
                            law->klass == &floe_linear_law_class, 1);
            b->law = law;
            b->k[q] = k; b->i[q] = i; b->j[q] = j;
            /* the geometry seen from i: n from the sphere into the wall (flipped were the wall
             * i, as contact_pair swaps the roles back; defensive: the list holds no wall as i,
             * neighbor.c push_pair) */
            for (int a = 0; a < 3; a++) {
                b->wn[a][q] = sph == i ? c.n[a] : -c.n[a];
                b->wpt[a][q] = c.point[a];
            }
            b->wdep[q] = depth;
            b->wreff[q] = c.r_eff;
            if (b->n == SPH_BATCH) sph_flush_lanes(w, ctx, env, acc, b);
            return FLOE_OK;
        }
    }
    if (b->n) sph_flush_lanes(w, ctx, env, acc, b);
    return contact_pair(w, ctx, env, k, acc);
}

/* One block of entries [k0, k1): the entries whose bounding spheres may touch go to cand
 * (k1 - k0 <= FLOE_PAR_BLOCK places: the calling thread's buffer), then each through its
 * evaluation; bp: the calling thread's batch (empty; zeroed once an evaluation, not once a
 * block: 6 KiB a block, dem-settle on one thread about 4 % faster, bench/RESULTS.md session 30) */
static int stage_block(floe_world *w, const floe_step_ctx *ctx, const stage_env *env, int k0, int k1, int *cand,
                       sph_batch *bp, stage_acc *acc) {
    const floe_neighbor_list *nl = env->nl;
    const floe_particles *p = env->p;
    const int *pi = nl->pi, *pj = nl->pj;
    const unsigned char *touching = nl->touching;
    const double *x = p->x, *rad = p->radius;
    int nc = 0;
    if (env->any_pieces || (nl->use_warm && (env->img || env->any_none)))
        for (int k = k0; k < k1; k++) cand[nc++] = k;
    else if (nl->use_warm) {
        /* convex shapes (warm starts): an untouched entry whose bounding spheres are apart, or
         * whose pair's kept gap is still open (the separation cache), does nothing in
         * contact_pair but the apart one's warm[0] = NaN (its next approach starts cold) and
         * the gap's counts: done here, without a branch per entry, and the entry left out (a
         * settled polyhedra bed: two thirds of its entries, each a call of contact_pair). A
         * kept gap is a convex pair's only (sphere and wall pairs' slots stay NaN, their test
         * false; a sphere pair's warm slot, never written, is NaN already); NaN centres or
         * bounds fail both tests and go to contact_pair. (A law "none" returns before both in
         * contact_pair: such a world keeps the loop above.) The resets and counts are made for
         * the whole block first: an evaluation that fails in the block has made them for the
         * entries after it too (warm starts of apart pairs, statistics) */
        const double *sp = w->sep_on && !env->overlap2d ? w->sep_pair : NULL, *sd = w->sep_d;
        int apart_k[FLOE_PAR_BLOCK]; /* the apart entries (k1 - k0 <= FLOE_PAR_BLOCK) */
        int na = 0;
        long held = 0;
        for (int k = k0; k < k1; k++) {
            const int i = pi[k], j = pj[k];
            const double dx = x[3 * j] - x[3 * i], dy = x[3 * j + 1] - x[3 * i + 1], dz = x[3 * j + 2] - x[3 * i + 2];
            const double rs = rad[i] + rad[j], d2 = dx * dx + dy * dy + dz * dz;
            const int apart = (rs < INFINITY) & (d2 >= rs * rs);
            int hold = 0;
            if (sp) /* where contact_pair asks: d2 < rs^2 (a wall's rs is infinite) */
                hold = (d2 < rs * rs) & floe_detect_sep_open(sp + 2 * (size_t)k, sd[i] + sd[j]);
            const int skip = (apart | hold) & !touching[k];
            held += hold & !touching[k];
            apart_k[na] = k;
            na += apart & !touching[k]; /* (contact_pair resets a touching one's) */
            cand[nc] = k;
            nc += !skip;
        }
        for (int q = 0; q < na; q++) nl->warm[(size_t)apart_k[q] * FLOE_DETECT_WARM] = NAN;
        env->dctx->det->sep_cached += held;
        env->dctx->det->separated += held;
    } else if (env->img)
        for (int k = k0; k < k1; k++) {
            /* periodic cell: the same test with j's image */
            const int i = pi[k], j = pj[k];
            double xs[3];
            const double *xj = pair_image(env, k, x + 3 * j, xs);
            const double dx = xj[0] - x[3 * i], dy = xj[1] - x[3 * i + 1], dz = xj[2] - x[3 * i + 2];
            const double rs = rad[i] + rad[j];
            const int apart = (rs < INFINITY) & (dx * dx + dy * dy + dz * dz >= rs * rs) & !touching[k];
            cand[nc] = k;
            nc += !apart;
        }
    else
        for (int k = k0; k < k1; k++) {
            /* most entries of a loose packing: two bounding spheres apart, untouched before;
             * nothing to do. Without a branch: in a dense bed half the entries touch, at
             * random, and a mispredicted branch per entry cost more than the test */
            const int i = pi[k], j = pj[k];
            const double dx = x[3 * j] - x[3 * i], dy = x[3 * j + 1] - x[3 * i + 1], dz = x[3 * j + 2] - x[3 * i + 2];
            const double rs = rad[i] + rad[j];
            const int apart = (rs < INFINITY) & (dx * dx + dy * dy + dz * dz >= rs * rs) & !touching[k];
            cand[nc] = k;
            nc += !apart;
        }
    /* spheres under a point law: the lean body (sphere_pair); every other entry the general one */
    const unsigned char *kind = p->kind;
    if (!env->any_pieces && !env->any_overlap && !env->any_floe) {
        sph_batch *b = bp; /* the lanes past a batch's end read zeros or an earlier batch's entries */
        const double *dash_a = w->dash_on ? w->dash_a : NULL;
        for (int q = 0; q < nc; q++) {
            const int k = cand[q];
            if (q + 8 < nc) { /* what sph_lane_gather reads of the entry 8 ahead */
                const size_t k8 = (size_t)cand[q + 8], j8 = (size_t)pj[k8];
                const char *hk = (const char *)(nl->hist + k8 * nl->hs);
                __builtin_prefetch(hk);
                __builtin_prefetch(hk + nl->hs * sizeof(double) - 1);
                __builtin_prefetch(p->v + 3 * j8);
                __builtin_prefetch(p->w + 3 * j8);
                if (dash_a) __builtin_prefetch(dash_a + 3 * j8);
            }
            if (kind[pi[k]] == FLOE_GEOM_SPHERE && kind[pj[k]] == FLOE_GEOM_SPHERE) FLOE_TRY(sphere_pair(w, ctx, env, k, acc, b));
            else if (!env->img && ((kind[pi[k]] == FLOE_GEOM_SPHERE && kind[pj[k]] == FLOE_GEOM_PLANE) ||
                                   (kind[pi[k]] == FLOE_GEOM_PLANE && kind[pj[k]] == FLOE_GEOM_SPHERE)))
                FLOE_TRY(sphere_wall_pair(w, ctx, env, k, acc, b));
            else {
                if (b->n) sph_flush_lanes(w, ctx, env, acc, b);
                prefetch_ahead(nl, cand, q, nc);
                FLOE_TRY(contact_pair(w, ctx, env, k, acc));
            }
        }
        if (b->n) sph_flush_lanes(w, ctx, env, acc, b);
        if (acc->oom) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    } else
        for (int q = 0; q < nc; q++) {
            prefetch_ahead(nl, cand, q, nc);
            FLOE_TRY(contact_pair(w, ctx, env, cand[q], acc));
        }
    return FLOE_OK;
}

/* a block's sums into the stage's, in block order (the same for any number of threads) */
static void acc_merge(floe_world *w, stage_acc *tot, const stage_acc *a) {
    if (a->eta_d > tot->eta_d) tot->eta_d = a->eta_d;
    tot->elastic += a->elastic;
    tot->diss += a->diss;
    tot->wgrow += a->wgrow;
    if (w->cell) /* (zeros without a periodic cell) */
        for (int q = 0; q < 9; q++) {
            tot->vir[q] += a->vir[q];
            tot->kdiag[q] += a->kdiag[q];
        }
    tot->ncontacts += a->ncontacts;
    if (a->wd_min < w->wd_pair_min) { w->wd_pair_min = a->wd_min; w->wd_pair_i = a->wd_i; w->wd_pair_j = a->wd_j; }
    if (a->wd_min < w->wd_worst) { w->wd_worst = a->wd_min; w->wd_worst_i = a->wd_i; w->wd_worst_j = a->wd_j; }
}

/* the estimated work of entry k for cutting the threads' parts (par_prepare): the bounding-
 * sphere test 1, a touching pair of spheres 16 more, any other touching pair (a wall, a
 * shape's detection: contact_pair) 48 more */
static inline double part_weight(const floe_particles *p, const floe_neighbor_list *nl, int k) {
    if (!nl->touching[k]) return 1.0;
    return p->kind[nl->pi[k]] == FLOE_GEOM_SPHERE && p->kind[nl->pj[k]] == FLOE_GEOM_SPHERE ? 17.0 : 49.0;
}

/* the sum of the blocks' smoothed times (balance_parts) */
static double par_times(const floe_par_scratch *ps) {
    double tot = 0;
    for (int b = 0; b < ps->bt_nb; b++) tot += ps->bt[b];
    return tot;
}

/* particle i's blocks: from its first entry to its last (its row; adj in list order) */
static inline void par_brange(const floe_par_scratch *ps, int i) {
    const int *row = ps->row, *off = ps->adj_off;
    int lo = INT_MAX, hi = -1;
    if (row[i + 1] > row[i]) { lo = row[i]; hi = row[i + 1] - 1; }
    if (off[i + 1] > off[i]) {
        if (ps->adj[off[i]] < lo) lo = ps->adj[off[i]];
        if (ps->adj[off[i + 1] - 1] > hi) hi = ps->adj[off[i + 1] - 1];
    }
    ps->brange[2 * i] = hi >= 0 ? lo / FLOE_PAR_BLOCK : INT_MAX;
    ps->brange[2 * i + 1] = hi >= 0 ? hi / FLOE_PAR_BLOCK : -1;
}

/* the entries of particle i (as i or j) past its lead part's blocks: those the gather takes */
static inline long par_gathered(const floe_par_scratch *ps, int i) {
    const int k0 = ps->pb[ps->lead[i] + 1] * FLOE_PAR_BLOCK, *row = ps->row, *off = ps->adj_off;
    const int r0 = row[i] > k0 ? row[i] : k0, r1 = row[i + 1] > r0 ? row[i + 1] : r0;
    return (long)(r1 - r0) + (off[i + 1] - off[i]) - floe_int_lower(ps->adj + off[i], off[i + 1] - off[i], k0);
}

/* A new list's particle entries (par_prepare): its rows (row), the entries each particle is j
 * of in list order (adj_off, adj: a counting sort by j) and each particle's blocks (brange).
 * FLOE_EINVAL when the list is not sorted by i. On nt threads when nt is 2-8 and the list
 * holds 4,096 entries or more (otherwise on one): each counts the j of a run of entries, the
 * offsets per thread and j come from one pass over the particles, and each thread puts its
 * run's entries after those of the runs before (the same order as one pass) and finds the rows
 * and blocks of a run of particles; one thread took 250 us a list of 56,000 entries
 * (dem-settle), while the others waited. */
static int par_adjacency(const floe_neighbor_list *nl, int n, int nt, floe_par_scratch *ps) {
    const int npairs = nl->npairs, *pi = nl->pi, *pj = nl->pj;
    int *off = ps->adj_off, *row = ps->row, *adj = ps->adj;
    int *cnt = nt > 1 && nt <= 8 && npairs >= 4096 ? calloc((size_t)nt * ((size_t)n + 1), sizeof *cnt) : NULL;
    if (!cnt) {
        memset(off, 0, (size_t)(n + 1) * sizeof *off);
        memset(row, 0, (size_t)(n + 1) * sizeof *row);
        for (int k = 0; k < npairs; k++) {
            if (k > 0 && pi[k] < pi[k - 1]) return FLOE_EINVAL; /* not sorted by i */
            row[pi[k] + 1]++;
            off[pj[k] + 1]++;
        }
        for (int i = 0; i < n; i++) {
            row[i + 1] += row[i];
            off[i + 1] += off[i];
        }
        for (int k = 0; k < npairs; k++) adj[off[pj[k]]++] = k; /* in list order */
        for (int i = n; i > 0; i--) off[i] = off[i - 1];
        off[0] = 0;
        for (int i = 0; i < n; i++) par_brange(ps, i);
        return FLOE_OK;
    }
    int bad = 0;
    FLOE_OMP(omp parallel for schedule(static, 1) num_threads(nt) reduction(|: bad))
    for (int t = 0; t < nt; t++) {
        const int k0 = (int)((long long)npairs * t / nt), k1 = (int)((long long)npairs * (t + 1) / nt);
        int *c = cnt + (size_t)t * ((size_t)n + 1);
        for (int k = k0 > 0 ? k0 : 1; k < k1; k++) bad |= pi[k] < pi[k - 1];
        for (int k = k0; k < k1; k++) c[pj[k]]++;
    }
    if (bad) {
        free(cnt);
        return FLOE_EINVAL; /* not sorted by i */
    }
    int acc = 0;
    for (int i = 0; i < n; i++) {
        off[i] = acc;
        for (int t = 0; t < nt; t++) { /* thread t's first place among the entries of j = i */
            int *c = cnt + (size_t)t * ((size_t)n + 1) + i;
            const int m = *c;
            *c = acc;
            acc += m;
        }
    }
    off[n] = acc;
    row[n] = npairs;
    FLOE_OMP(omp parallel num_threads(nt))
    {
        const int nth = floe_par_nthreads();
        for (int t = floe_par_thread(); t < nt; t += nth) {
            const int k0 = (int)((long long)npairs * t / nt), k1 = (int)((long long)npairs * (t + 1) / nt);
            int *c = cnt + (size_t)t * ((size_t)n + 1);
            for (int k = k0; k < k1; k++) adj[c[pj[k]]++] = k;
            /* the rows of a run of particles */
            floe_list_rows(pi, npairs, (int)((long long)n * t / nt), (int)((long long)n * (t + 1) / nt), row);
        }
        FLOE_OMP(omp barrier)
        for (int t = floe_par_thread(); t < nt; t += nth) {
            const int i0 = (int)((long long)n * t / nt), i1 = (int)((long long)n * (t + 1) / nt);
            for (int i = i0; i < i1; i++) par_brange(ps, i);
        }
    }
    free(cnt);
    return FLOE_OK;
}

/* the buffers for nt threads, nb blocks, the list's entries and n particles; the particles'
 * entries rebuilt after each list build */
static int par_prepare(floe_world *w, int nt, int nb) {
    const floe_neighbor_list *nl = &w->nl;
    const int n = w->p.n, npairs = nl->npairs;
    if (!w->thr && !(w->thr = calloc(1, sizeof *w->thr))) return FLOE_ENOMEM;
    floe_par_scratch *ps = w->thr;
    /* a quarter more room than the list when it grows (a settling bed's lists grow at most
     * builds: each growth of the 72-byte records was a realloc on one thread, 2 us a step of
     * dem-settle) */
    const size_t ne = npairs ? (size_t)npairs : 1, room = ne > ps->act_cap || !ps->act ? ne + ne / 4 : ne;
    if (floe_reserve((void **)&ps->pf, &ps->pf_cap, room * 9, sizeof(double)) ||
        floe_reserve((void **)&ps->act, &ps->act_cap, room, 1))
        return FLOE_ENOMEM;
    if (nb > ps->blk_cap) {
        stage_acc *t = realloc(ps->blk, (size_t)nb * sizeof *t);
        if (!t) return FLOE_ENOMEM;
        ps->blk = t;
        ps->blk_cap = nb;
    }
    if (nb > ps->bt_cap) {
        double *bs = realloc(ps->bs, (size_t)nb * sizeof *bs);
        if (bs) ps->bs = bs;
        double *bt = bs ? realloc(ps->bt, (size_t)nb * sizeof *bt) : NULL;
        if (!bt) return FLOE_ENOMEM;
        ps->bt = bt; /* (the times of bt_nb blocks kept: the next list's first cut) */
        ps->bt_cap = nb;
    }
    if (nt > ps->ndet) {
        floe_detect_state *d = realloc(ps->det, (size_t)nt * sizeof *d);
        if (!d) return FLOE_ENOMEM;
        memset(d + ps->ndet, 0, (size_t)(nt - ps->ndet) * sizeof *d);
        ps->det = d;
        ps->ndet = nt;
    }
    if (nt > ps->nerr) {
        char(*e)[1024] = realloc(ps->err, (size_t)nt * sizeof *e);
        if (e) ps->err = e;
        int *fb = e ? realloc(ps->fail_b, (size_t)nt * sizeof *fb) : NULL;
        if (fb) ps->fail_b = fb;
        int *fr = fb ? realloc(ps->fail_rc, (size_t)nt * sizeof *fr) : NULL;
        if (!fr) return FLOE_ENOMEM;
        ps->fail_rc = fr;
        ps->nerr = nt;
    }
    if (ps->adj_gen != nl->gen || ps->adj_np != n || !ps->adj_off) {
        /* a particle's entries as i are its row of the list (sorted by i: floe_nl_build, and a
         * checkpoint's copy of such a list); those as j are indexed */
        int *off = realloc(ps->adj_off, (size_t)(n + 1) * sizeof *off);
        if (off) ps->adj_off = off;
        int *row = off ? realloc(ps->row, (size_t)(n + 1) * sizeof *row) : NULL;
        if (!row) return FLOE_ENOMEM;
        ps->row = row;
        size_t c2 = ps->adj_cap;
        if (floe_reserve((void **)&ps->adj, &c2, npairs ? (size_t)npairs : 1, sizeof(int))) return FLOE_ENOMEM;
        ps->adj_cap = c2;
        int *br = realloc(ps->brange, 2 * (size_t)(n ? n : 1) * sizeof *br);
        if (!br) return FLOE_ENOMEM;
        ps->brange = br;
        FLOE_TRY(par_adjacency(nl, n, nt, ps));
        ps->adj_gen = nl->gen;
        ps->adj_np = n;
        ps->pb_nt = 0; /* parts and lead[] below */
    }
    /* one part per thread: a run of blocks that one thread takes in order, the same thread
     * every evaluation (a schedule by hand, not dynamic), so that the particles of a part stay
     * in that core's caches from one step to the next. Handed out dynamically (a few parts per
     * thread, as before 2026-12-03), a part and its particles' cache lines moved between the
     * cores from step to step: the §5.3 RVE on two threads ran 1.16-1.21x faster with these
     * (bench/RESULTS.md, "Issue 14, session 7"). The first list is cut so that each part gets
     * the same estimated work: the rows of a run of particles, each particle 4 (its share of
     * the integrator's loops), each entry of its row by part_weight (its touching flag carried
     * over from the last build); the cut at the nearest block. A later list of as many
     * particles is cut by the last list's measured times, the same list again by its own
     * (balance_parts). A particle's lead part (that of its first entry, as i or j) is its only
     * direct writer and adds its forces in list order; the later parts' ends wait for the
     * gather (pair_apply) */
    const int same = ps->pb_nt == nt && ps->pb[nt] == nb && ps->pb_gen == nl->gen;
    if (!same || ps->recut) {
        ps->pb_nt = 0; /* (cut again at the next evaluation if anything below fails) */
        int *pb = realloc(ps->pb, (size_t)(nt + 1) * sizeof *pb);
        unsigned char *lead = pb ? realloc(ps->lead, (size_t)(n ? n : 1)) : NULL;
        if (pb) ps->pb = pb;
        if (!lead) return FLOE_ENOMEM;
        ps->lead = lead;
        if (floe_reserve((void **)&ps->bpart, &ps->bpart_cap, (size_t)(nb ? nb : 1), 1)) return FLOE_ENOMEM;
        /* the gather's particles and their shares (below) */
        if (floe_reserve((void **)&ps->gl, &ps->gl_cap, (size_t)(n ? n : 1), sizeof(int)) ||
            floe_reserve((void **)&ps->gc, &ps->gc_cap, (size_t)nt + 1, sizeof(int)))
            return FLOE_ENOMEM;
        const int *row = ps->row, B = FLOE_PAR_BLOCK;
        pb[0] = 0;
        int t = 1;
        double told = 0; /* the last list's times, summed */
        if (same && ps->bt_nb == nb) {
            /* the same list: cut again by the blocks' measured times (balance_parts) */
            double tot = 0, acc = 0;
            for (int b = 0; b < nb; b++) tot += ps->bt[b];
            for (int b = 0; b < nb && t < nt; b++) {
                acc += ps->bt[b];
                for (; t < nt && acc >= tot * t / nt; t++) {
                    const int bt = acc - tot * t / nt < 0.5 * ps->bt[b] ? b + 1 : b;
                    pb[t] = bt < pb[t - 1] ? pb[t - 1] : bt;
                }
            }
        } else if (ps->bf_nb > 0 && ps->bf_nb == ps->bt_nb && ps->bf_n == n && npairs > 0 && (told = par_times(ps)) > 0) {
            /* a new list of the same particles: cut by the last list's measured times (a
             * part's share ends at a particle, found by the last list's blocks' first particles
             * and in proportion within a block), at the block nearest that particle's place in
             * this list's rows. The estimate below was a pass over the entries on one thread
             * (150 us a dem-settle list) and cut the first evaluation of a list worse */
            const double *bt = ps->bt, tot = told;
            const int *bf = ps->bf;
            double acc = 0;
            for (int b = 0; b < ps->bt_nb && t < nt; b++) {
                const double a0 = acc;
                acc += bt[b];
                for (; t < nt && acc >= tot * t / nt; t++) {
                    const double ph = bt[b] > 0 ? (tot * t / nt - a0) / bt[b] : 0.0, P = bf[b] + ph * (bf[b + 1] - bf[b]);
                    const int i = P < 0 ? 0 : P >= n ? n - 1 : (int)P;
                    const double e = row[i] + (P - i) * (row[i + 1] - row[i]);
                    const int c = (int)((e + 0.5 * B) / B);
                    pb[t] = c > nb ? nb : c < pb[t - 1] ? pb[t - 1] : c;
                }
            }
        } else {
            double tot = 4.0 * n;
            for (int k = 0; k < npairs; k++) tot += part_weight(&w->p, nl, k);
            /* part t starts at the row of the first particle before which the work reaches t / nt
             * of the whole, rounded to the nearest block */
            double acc = 0;
            for (int i = 0; i < n && t < nt; i++) {
                acc += 4.0;
                for (int k = row[i]; k < row[i + 1]; k++) acc += part_weight(&w->p, nl, k);
                for (; t < nt && acc >= tot * t / nt; t++) {
                    const int bt = (row[i + 1] + B / 2) / B;
                    pb[t] = bt > nb ? nb : bt < pb[t - 1] ? pb[t - 1] : bt;
                }
            }
        }
        for (; t <= nt; t++) pb[t] = nb;
        ps->recut = 0;
        /* each particle's lead part: that of its first block, through the blocks' parts (a
         * particle without entries: 0); the gather's particles: those whose last block lies
         * past their lead part, weighed by their entries there (a wall's entries in every part:
         * those of its lead part are not gathered) */
        const int *br = ps->brange;
        unsigned char *bpart = ps->bpart;
        for (int q = 0; q < nt; q++)
            for (int b = pb[q]; b < pb[q + 1]; b++) bpart[b] = (unsigned char)q;
        for (int i = 0; i < n; i++) lead[i] = br[2 * i] < nb ? bpart[br[2 * i]] : 0;
        int ngl = 0;
        long ent = 0;
        for (int i = 0; i < n; i++)
            if (br[2 * i + 1] >= pb[lead[i] + 1]) { /* its last block past its lead part */
                ps->gl[ngl++] = i;
                ent += par_gathered(ps, i);
            }
        int *gc = ps->gc, s = 1;
        long acc = 0;
        gc[0] = 0;
        for (int q = 0; q < ngl && s < nt; q++) {
            acc += par_gathered(ps, ps->gl[q]);
            for (; s < nt && acc * nt >= ent * s; s++) gc[s] = q + 1;
        }
        for (; s <= nt; s++) gc[s] = ngl;
        ps->pb_nt = nt;
        ps->pb_gen = nl->gen;
    }
    for (int t = 0; t < nt; t++) { /* the detection statistics of this evaluation, per thread */
        floe_detect_state *d = &ps->det[t];
        double *sc = d->scratch;
        int scap = d->scratch_cap;
        memset(d, 0, sizeof *d);
        d->admm = w->det.admm;
        d->scratch = sc;
        d->scratch_cap = scap;
        d->cur_i = -1;
        ps->fail_b[t] = INT_MAX;
        ps->fail_rc[t] = 0;
    }
    return FLOE_OK;
}

/* The parts' balance: the estimated work of par_prepare's cut misses what it does not model
 * (a law's own cost, contacts made since the build, the caches), so each block's stage time is
 * measured and smoothed (bt; a sample at most 3x the smoothed time: a preempted thread's block
 * does not move the cut), and when the slowest part takes more than 5 % above the mean the
 * next evaluation cuts the parts again by these times (the list's blocks unchanged; a new list
 * of as many particles by the last list's, through bf). Which thread adds which force never
 * changes the bits
 * (pair_apply, the gather): a cut by measured times keeps the results those of one thread. */
static void balance_parts(floe_par_scratch *ps, const floe_neighbor_list *nl, int n, int nt, int nb) {
    /* the first particle of each block of this list (its times cut the next list's parts:
     * par_prepare) */
    if (ps->bf_gen != nl->gen || ps->bf_nb != nb) {
        ps->bf_nb = 0;
        if (!floe_reserve((void **)&ps->bf, &ps->bf_cap, (size_t)nb + 1, sizeof(int))) {
            for (int b = 0; b < nb; b++) ps->bf[b] = nl->pi[(size_t)b * FLOE_PAR_BLOCK];
            ps->bf[nb] = n;
            ps->bf_nb = nb;
            ps->bf_n = n;
            ps->bf_gen = nl->gen;
        }
    }
    if (ps->bt_nb != nb) {
        memcpy(ps->bt, ps->bs, (size_t)nb * sizeof *ps->bt);
        ps->bt_nb = nb;
    } else
        for (int b = 0; b < nb; b++) {
            const double s = ps->bs[b], cap = 3.0 * ps->bt[b];
            ps->bt[b] = 0.75 * ps->bt[b] + 0.25 * (ps->bt[b] > 0 && s > cap ? cap : s);
        }
    double tot = 0, worst = 0;
    for (int t = 0; t < nt; t++) {
        double T = 0;
        for (int b = ps->pb[t]; b < ps->pb[t + 1]; b++) T += ps->bt[b];
        tot += T;
        if (T > worst) worst = T;
    }
    ps->recut = worst > 1.05 * tot / nt;
}

/* the threads' detection statistics into the world's, as one thread would have left them */
static void par_merge_detect(floe_world *w, int nt) {
    floe_detect_state *W = &w->det;
    const long nonconv0 = W->nonconverged;
    for (int t = 0; t < nt; t++) {
        const floe_detect_state *d = &w->thr->det[t];
        W->calls += d->calls;
        W->iterations += d->iterations;
        W->admm_calls += d->admm_calls;
        W->lp_calls += d->lp_calls;
        W->separated += d->separated;
        W->sep_cached += d->sep_cached;
        W->mf_cached += d->mf_cached;
        W->lp_halves += d->lp_halves;
        W->lp_kept += d->lp_kept;
        W->lp_cold += d->lp_cold;
        W->nonconverged += d->nonconverged;
        for (int q = 0; q < FLOE_DETECT_HIST; q++) W->hist[q] += d->hist[q];
    }
    if (nonconv0 == 0) /* the first non-converged pair: of the first thread (block) that met one */
        for (int t = 0; t < nt; t++) {
            const floe_detect_state *d = &w->thr->det[t];
            if (d->nonconverged > 0) {
                W->first_bad_i = d->first_bad_i;
                W->first_bad_j = d->first_bad_j;
                W->first_bad_step = d->first_bad_step;
                break;
            }
        }
    for (int t = nt - 1; t >= 0; t--) /* the last pair detected: of the last thread that did */
        if (w->thr->det[t].cur_i >= 0) {
            W->cur_i = w->thr->det[t].cur_i;
            W->cur_j = w->thr->det[t].cur_j;
            break;
        }
}

/* The separation cache's motion bounds (floe_world.sep_*; docs/models.md, "Polytope pairs:
 * the separation cache"). Each evaluation adds to every particle's bound how far any of its
 * points can have moved since the last: |dx| + radius x (a bound of the angle it turned) +
 * |dr|. The angle between unit quaternions q and q0 is 4 asin(c / 2), c = |q -+ q0| (the
 * sign of the nearer), and asin(u) <= u / sqrt(1 - u^2): at most 2c / sqrt(1 - c^2 / 4). A
 * particle whose geometry changed gets an infinite bound (its pairs are tested). A new
 * list, a restore (sep_n = -1) or a new particle count starts every bound again at 0 with
 * no gap kept. Only scenes with boxes, convex or compound shapes, without a periodic cell
 * (images move with the cell) or MPI (ghosts change places) keep the cache. */
static int sep_update(floe_world *w) {
    const floe_particles *p = &w->p;
    const floe_neighbor_list *nl = &w->nl;
    const int n = p->n, np = nl->npairs;
    if (w->cell || w->par) {
        w->sep_on = 0;
        return FLOE_OK;
    }
    if (!floe_world_sep_seen(w)) { /* a new list: its kinds scanned once (O(n), serial) */
        int want = 0;
        for (int i = 0; i < n && !want; i++)
            want = p->kind[i] == FLOE_GEOM_BOX || p->kind[i] == FLOE_GEOM_USER || p->kind[i] == FLOE_GEOM_COMPOUND;
        w->sep_on = 0;
        w->sep_n = n;
        w->sep_gen = nl->gen;
        w->sep_np = np;
        if (!want) return FLOE_OK;
        if (floe_resize((void **)&w->sep_d, (size_t)n, sizeof(double)) ||
            floe_resize((void **)&w->sep_pose, (size_t)n, 8 * sizeof(double)) ||
            floe_resize((void **)&w->sep_geom, (size_t)n, sizeof(int)) ||
            floe_resize((void **)&w->sep_pair, (size_t)np, 2 * sizeof(double))) {
            w->sep_n = -1;
            return floe_world_error(w, FLOE_ENOMEM, "out of memory (separation cache)");
        }
        for (int i = 0; i < n; i++) {
            double *s = w->sep_pose + 8 * (size_t)i;
            w->sep_d[i] = 0.0;
            memcpy(s, p->x + 3 * (size_t)i, 3 * sizeof(double));
            memcpy(s + 3, p->q + 4 * (size_t)i, 4 * sizeof(double));
            s[7] = p->radius[i];
            w->sep_geom[i] = p->geom[i];
        }
        for (size_t k = 0; k < 2 * (size_t)np; k++) w->sep_pair[k] = NAN;
        w->sep_on = 1;
        return FLOE_OK;
    }
    if (!w->sep_on) return FLOE_OK;
    for (int i = 0; i < n; i++) {
        double *s = w->sep_pose + 8 * (size_t)i;
        const double *x = p->x + 3 * (size_t)i, *q = p->q + 4 * (size_t)i;
        const double r = p->radius[i];
        const double dx = x[0] - s[0], dy = x[1] - s[1], dz = x[2] - s[2];
        const double dot = q[0] * s[3] + q[1] * s[4] + q[2] * s[5] + q[3] * s[6], sg = dot < 0 ? -1.0 : 1.0;
        double c2 = 0;
        for (int a = 0; a < 4; a++) {
            const double e = q[a] - sg * s[3 + a];
            c2 += e * e;
        }
        const double c = sqrt(c2), den = 1.0 - 0.25 * c2;
        const double turn = den > 0.25 ? 2.0 * c / sqrt(den) : 4.0; /* c <= sqrt(2) for unit q: den >= 0.5 */
        const double rr = r > s[7] ? r : s[7];
        w->sep_d[i] += sqrt(dx * dx + dy * dy + dz * dz) + rr * turn + fabs(r - s[7]);
        if (p->geom[i] != w->sep_geom[i]) w->sep_d[i] = INFINITY;
        memcpy(s, x, 3 * sizeof(double));
        memcpy(s + 3, q, 4 * sizeof(double));
        s[7] = r;
    }
    return FLOE_OK;
}

/* particle i's forces from the entries buffered for it (pair_apply: act[k] bit 1 for i, 2 for
 * j; entries of the parts after its lead part), added in list order after the lead part's as
 * one thread adds them: the entries it is j of before its row, its row, those after it */
static inline void gather_one(const floe_par_scratch *ps, floe_particles *p, int i) {
    const int *off = ps->adj_off, *adj = ps->adj, *row = ps->row;
    const double *pf = ps->pf;
    const unsigned char *act = ps->act;
    double *f = p->f, *tq = p->t;
    double fi[3] = {f[3 * i], f[3 * i + 1], f[3 * i + 2]}, ti[3] = {tq[3 * i], tq[3 * i + 1], tq[3 * i + 2]};
    /* the lead part's entries hold nothing for i: from the first entry past them */
    const int k0 = ps->pb[ps->lead[i] + 1] * FLOE_PAR_BLOCK;
    const int r0 = row[i] > k0 ? row[i] : k0, r1 = row[i + 1], e1 = off[i + 1];
    int e = off[i] + floe_int_lower(adj + off[i], e1 - off[i], k0);
    for (; e < e1 && adj[e] < r0; e++) {
        const int k = adj[e];
        if (!(act[k] & 2)) continue;
        const double *bk = pf + 9 * (size_t)k;
        for (int a = 0; a < 3; a++) { fi[a] -= bk[a]; ti[a] += bk[6 + a]; }
    }
    for (int k = r0; k < r1; k++) {
        if (!(act[k] & 1)) continue;
        const double *bk = pf + 9 * (size_t)k;
        for (int a = 0; a < 3; a++) { fi[a] += bk[a]; ti[a] += bk[3 + a]; }
    }
    for (; e < e1; e++) {
        const int k = adj[e];
        if (!(act[k] & 2)) continue;
        const double *bk = pf + 9 * (size_t)k;
        for (int a = 0; a < 3; a++) { fi[a] -= bk[a]; ti[a] += bk[6 + a]; }
    }
    for (int a = 0; a < 3; a++) { f[3 * i + a] = fi[a]; tq[3 * i + a] = ti[a]; }
}

static int contact_stage(floe_provider *pv, floe_world *w, const floe_step_ctx *ctx, floe_provider_out *out) {
    (void)pv;
    floe_particles *p = ctx->p;
    const int stepping = ctx->stepping; /* 0 at prepare and at the RK2 probe: no work booked */
    const int track = ctx->track_depth;
    w->ncontacts = 0;
    if (stepping) w->wd_pair_min = 0; /* the watchdog's worst contact of this evaluation */
    FLOE_TRY(sep_update(w));
    const int any_growth = w->nstates > 0; /* only state objects set rdot */
    floe_neighbor_list *nl = &w->nl;
    const int nm = w->nmats;
    floe_detect_ctx dctx = {.dim = w->def.dim, .step = w->step, .det = &w->det, .no_corner_cache = w->mf_cache_off};
    /* pairs under the law "none" are skipped; most scenes have none, and then the law of a
     * pair is looked up only when it touches (a load per pair saved on the sphere path) */
    int any_none = 0;
    int any_overlap = 0; /* laws that read the overlap area (floe_law_info.needs_overlap) */
    int any_floe = 0;    /* laws that read the floes' thickness (floe_law_info.needs_floe) */
    for (int k = 0; k < nm * nm; k++) {
        any_none |= floe_contact_law_no_contact(w->laws[k]);
        if (!w->laws[k]) continue;
        const floe_law_info li = floe_contact_law_info(w->laws[k]);
        any_overlap |= li.needs_overlap | li.prefers_overlap;
        any_floe |= li.needs_floe;
    }
    /* compound bodies: their pairs are per piece (the geometries added since the last look) */
    if (w->pieces_seen > w->ngeoms) w->pieces_seen = w->any_pieces = 0; /* geometries taken back */
    for (; w->pieces_seen < w->ngeoms; w->pieces_seen++) w->any_pieces |= floe_piece_count(w->geoms[w->pieces_seen]) > 1;
    const int any_pieces = w->any_pieces;
    const stage_env env = {p,         nl,         &dctx,       stepping, track,
                           any_growth, nm,        any_none,    any_pieces, any_overlap,
                           any_floe,  w->def.dim == 2 && any_overlap, w->cell, w->cell ? nl->img : NULL,
                           !any_growth && !w->lanes_off, nm == 1 ? w->laws[0] : NULL, ctx->record};
    /* blocks of FLOE_PAR_BLOCK entries, their sums added in block order: one thread or many,
     * the same bits (floe_par.h); recorded contacts in list order (per part, then joined) */
    const int npairs = nl->npairs, B = FLOE_PAR_BLOCK, nb = (npairs + B - 1) / B;
    int nt = floe_world_loop_threads(w, npairs);
    if (nt > nb) nt = nb;
    if (nt > 255) nt = 255; /* a particle's lead part is a byte (par_prepare) */
    stage_acc tot;
    memset(&tot, 0, sizeof tot);
    if (nt <= 1) {
        int cand[FLOE_PAR_BLOCK]; /* a block's candidates (stage_block), on the stack: 2 KiB, hot */
        sph_batch batch;
        memset(&batch, 0, sizeof batch);
        for (int b = 0; b < nb; b++) {
            stage_acc a;
            memset(&a, 0, sizeof a);
            const int k0 = b * B, k1 = k0 + B < npairs ? k0 + B : npairs;
            FLOE_TRY(stage_block(w, ctx, &env, k0, k1, cand, &batch, &a));
            acc_merge(w, &tot, &a);
        }
    } else {
        const int prc = par_prepare(w, nt, nb);
        if (prc)
            return floe_world_error(w, prc, prc == FLOE_ENOMEM ? "out of memory (threads' buffers)"
                                                               : "internal: the neighbour list is not sorted by its first particle");
        floe_par_scratch *ps = w->thr;
        if (ctx->record && nt > ps->nrs) {
            floe_rec_sink *rs = realloc(ps->rs, (size_t)nt * sizeof *rs);
            if (!rs) return floe_world_error(w, FLOE_ENOMEM, "out of memory (threads' buffers)");
            memset(rs + ps->nrs, 0, (size_t)(nt - ps->nrs) * sizeof *rs);
            ps->rs = rs;
            ps->nrs = nt;
        }
        for (int t = 0; ctx->record && t < nt; t++) ps->rs[t].n = 0;
        FLOE_OMP(omp parallel num_threads(nt))
        {
            const int t = floe_par_thread();
            int cand[FLOE_PAR_BLOCK]; /* this thread's block's candidates (stage_block) */
            sph_batch batch;
            memset(&batch, 0, sizeof batch);
            stage_env te = env;
            floe_detect_ctx td = {.dim = w->def.dim, .step = w->step, .det = &ps->det[t]};
            te.dctx = &td;
            floe_world_error_to(ps->err[t], sizeof ps->err[t]);
            int failed = 0;
            /* thread t's part: its blocks in order (par_prepare); the lowest failed block of
             * all threads is the first error */
            const int nth = floe_par_nthreads();
            double t0 = floe_par_wtime(); /* a block's start: the last one's end */
            for (int part = t; part < nt; part += nth)
            for (int b = ps->pb[part]; b < ps->pb[part + 1]; b++) {
                if (failed) continue; /* this thread's first error is the one its blocks met first */
                /* the block's sums on this thread's stack (blocks side by side in ps->blk share
                 * cache lines: updated per pair, they bounced between the cores) */
                stage_acc la;
                memset(&la, 0, sizeof la);
                la.pf = ps->pf;
                la.act = ps->act;
                la.lead = ps->lead;
                la.part = part;
                la.rs = ctx->record ? &ps->rs[part] : NULL;
                const int k0 = b * B, k1 = k0 + B < npairs ? k0 + B : npairs;
                memset(ps->act + k0, 0, (size_t)(k1 - k0));
                int rc = stage_block(w, ctx, &te, k0, k1, cand, &batch, &la);
                ps->blk[b] = la;
                const double t1 = floe_par_wtime();
                ps->bs[b] = t1 - t0;
                t0 = t1;
                if (rc) {
                    failed = 1;
                    ps->fail_b[t] = b;
                    ps->fail_rc[t] = rc;
                }
            }
            floe_world_error_to(NULL, 0);
            /* every block's buffered entries written: the particles with entries past their lead
             * part take those, each in list order as one thread adds them (pair_apply), a share
             * of them by entries per thread (par_prepare); not after a failure (the blocks a
             * thread skipped left their flags of an earlier evaluation), the same choice on every
             * thread */
            FLOE_OMP(omp barrier)
            int any_failed = 0;
            for (int q = 0; q < nt; q++) any_failed |= ps->fail_rc[q] != 0;
            for (int part = t; part < nt && !any_failed; part += nth)
                for (int q = ps->gc[part]; q < ps->gc[part + 1]; q++) gather_one(ps, p, ps->gl[q]);
        }
        par_merge_detect(w, nt);
        int tf = -1; /* the error a serial run meets first: of the lowest failed block */
        for (int t = 0; t < nt; t++)
            if (ps->fail_rc[t] && (tf < 0 || ps->fail_b[t] < ps->fail_b[tf])) tf = t;
        if (tf >= 0) {
            memcpy(w->err, ps->err[tf], sizeof w->err);
            w->err[sizeof w->err - 1] = 0;
            return ps->fail_rc[tf];
        }
        for (int b = 0; b < nb; b++) acc_merge(w, &tot, &ps->blk[b]);
        balance_parts(ps, nl, p->n, nt, nb);
        if (ctx->record) { /* the parts' records joined in part order: the list's order */
            int nrec = 0;
            for (int t = 0; t < nt; t++) nrec += ps->rs[t].n;
            if (nrec > w->contacts_cap) {
                floe_contact_rec *r = realloc(w->contacts, (size_t)nrec * sizeof *r);
                if (!r) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
                w->contacts = r;
                w->contacts_cap = nrec;
            }
            for (int t = 0; t < nt; t++) {
                if (ps->rs[t].n)
                    memcpy(w->contacts + w->ncontacts, ps->rs[t].r, (size_t)ps->rs[t].n * sizeof *ps->rs[t].r);
                w->ncontacts += ps->rs[t].n;
            }
        }
    }
    w->ncontacts += (int)tot.ncontacts;
    w->eta_depth = tot.eta_d;
    if (w->cell && !ctx->probe) {
        memcpy(w->cell->virial, tot.vir, sizeof tot.vir);
        memcpy(w->cell->kdiag, tot.kdiag, sizeof tot.kdiag);
        w->cell->valid = 1;
    }
    out->elastic += tot.elastic;
    out->dissipated += tot.diss;
    out->work_boundary += tot.wgrow;
    return FLOE_OK;
}

/* its state: the pairs' history and touching flags (the list itself is the world's) */
static size_t contact_state_size(const floe_provider *pv, const floe_world *w) {
    (void)pv;
    return (size_t)w->nl.npairs * ((size_t)w->nl.hs * sizeof(double) + 1);
}
static void contact_save(const floe_provider *pv, const floe_world *w, unsigned char *buf) {
    (void)pv;
    const size_t np = (size_t)w->nl.npairs, nh = np * (size_t)w->nl.hs * sizeof(double);
    if (!np) return;
    floe_world_copy(w, buf, w->nl.hist, nh); /* RK2's probe: twice a step, the list's size */
    memcpy(buf + nh, w->nl.touching, np);
}
static void contact_restore(floe_provider *pv, floe_world *w, const unsigned char *buf) {
    (void)pv;
    const size_t np = (size_t)w->nl.npairs, nh = np * (size_t)w->nl.hs * sizeof(double);
    if (!np) return;
    floe_world_copy(w, w->nl.hist, buf, nh);
    memcpy(w->nl.touching, buf + nh, np);
}
const floe_provider_class floe_contact_provider_class = {
    .version = 1, .name = "contacts", .group = FLOE_GROUP_DEM, .forces = contact_stage,
    .state_size = contact_state_size, .save = contact_save, .restore = contact_restore};

/* ---- provider "pd_bonds": the bond forces of every PD body, with their ledger ---- */
/* periodic cell: the bonds' share of the homogenised stress, sum l (x) f (l the bond vector
 * from i to j's image, f the force on i), and of the servo's stiffness, k (n_a l_b)^2 with
 * k = c beta V_i V_j / |xi| the bond's axial stiffness (the equivalent PMB c for LPS) */
typedef struct pd_vir_ctx {
    const floe_pd_body *b;
    const double *x, *H;
    double vir[9], kdiag[9];
    int want_kdiag;
} pd_vir_ctx;
static void pd_vir_visit(int i, int j, int64_t k, const double f[3], void *user) {
    pd_vir_ctx *c = user;
    double l[3];
    floe_pd_bond_vec(c->b, c->x, c->H, i, j, k, l);
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) c->vir[3 * a + b] += l[a] * f[b];
    if (c->want_kdiag) {
        const floe_pd_body *pb = c->b;
        double r = floe_v3_norm(l), kb = pb->c * (double)pb->vfac[k] * pb->V[i] * pb->V[j] / pb->len[k];
        if (pb->scorr) kb *= (double)pb->scorr[k];
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) c->kdiag[3 * a + b] += kb * (l[a] / r) * (l[a] / r) * l[b] * l[b];
    }
}

/* points [i0, i1) of a body: their new bond forces fnew added to the particles' pf, and the
 * work of the forces over the step (trapezoid with the old ones fold, mid-step velocities v,
 * times 2/dt) returned */
static double pd_ledger_block(const double *fnew, const double *fold, double *pf, const double *v, int i0, int i1) {
    double wk = 0;
    for (int i = i0; i < i1; i++)
        for (int a = 0; a < 3; a++) {
            double fa = fnew[3 * i + a];
            pf[3 * (size_t)i + a] += fa;
            wk += (fa + fold[3 * i + a]) * v[3 * (size_t)i + a];
        }
    return wk;
}

static int pd_stage(floe_provider *pv, floe_world *w, const floe_step_ctx *ctx, floe_provider_out *out) {
    (void)pv;
    floe_particles *p = ctx->p;
    /* threads for each body's bond loops (pd_materials.c: the same bits for any count) */
    for (int k = 0; k < w->npd; k++) w->pd[k]->nthreads = floe_world_loop_threads(w, (long)w->pd[k]->nbond);
    if (ctx->probe) { /* RK2 midpoint: the bond forces without breakage, nothing booked */
        if (w->pd_split) floe_pd_split_gather(w); /* MPI: the points here, contiguous per body */
        for (int k = 0, off = 0; k < w->npd; k++) {
            const int np = w->pd[k]->n;
            if (w->pd_split) { /* MPI: the owned points' forces, as below */
                double *fnew = w->pd_fnew + 3 * (size_t)off; /* scratch until the step's evaluation */
                memset(fnew, 0, (size_t)3 * np * sizeof *fnew);
                floe_pd_forces_nobreak(w->pd[k], floe_pd_positions(w, k), fnew);
                const int *loc = w->pd_split->loc[k];
                const uint8_t *own = w->pd_split->mask[k];
                for (int q = 0; q < np; q++)
                    if (own[q] == FLOE_PD_OWNED)
                        for (int a = 0; a < 3; a++) p->f[3 * (size_t)loc[q] + a] += fnew[3 * q + a];
            } else {
                const int f0 = w->pd_first[k];
                floe_pd_forces_nobreak(w->pd[k], p->x + 3 * (size_t)f0, p->f + 3 * (size_t)f0);
            }
            off += np;
        }
        return FLOE_OK;
    }
    const int stepping = ctx->stepping;
    double elastic = out->elastic, diss = out->dissipated;
    pd_vir_ctx vc;
    memset(&vc, 0, sizeof vc);
    if (w->cell) {
        vc.H = w->cell->H;
        vc.want_kdiag = w->cell->want_kdiag;
    }
    /* Ledger: the work of the bond forces over the step (trapezoid, as for contacts) minus
     * the change of the stored energy is dissipated; for intact bonds it is the integration
     * error only, a breaking bond releases its energy there. */
    if (w->pd_split) floe_pd_split_gather(w); /* MPI: the points here, contiguous per body */
    int pd_fail = FLOE_OK;
    char pd_why[sizeof w->err];
    for (int b = 0, off = 0; b < w->npd; b++) {
        floe_pd_body *pb = w->pd[b];
        int f0 = w->pd_first[b], np = pb->n;
        double *fold = w->pd_fold + 3 * (size_t)off, *fnew = w->pd_fnew + 3 * (size_t)off;
        floe_world_zero(w, fnew, (size_t)3 * np * sizeof *fnew);
        double e = floe_pd_forces(pb, floe_pd_positions(w, b), fnew);
        /* the forces onto the particles and their work, summed per block of points in block
         * order (the same bits threaded or not) */
        const int B = FLOE_PAR_BLOCK, nblk = (np + B - 1) / B, ntl = floe_world_loop_threads(w, np);
        double *pf = w->pd_split ? NULL : p->f + 3 * (size_t)f0;
        double *red = ntl > 1 && nblk > 1 && !w->pd_split ? floe_world_reduce_buf(w, (size_t)nblk) : NULL;
        const double *vel = w->pd_split ? NULL : p->v + 3 * (size_t)f0;
        double wk = 0;
        if (w->pd_split) { /* MPI: the owned points' forces (a ghost's owner has its own) */
            const int *loc = w->pd_split->loc[b];
            const uint8_t *own = w->pd_split->mask[b];
            for (int q = 0; q < np; q++)
                if (own[q] == FLOE_PD_OWNED)
                    for (int a = 0; a < 3; a++) {
                        const size_t i = 3 * (size_t)loc[q] + a;
                        p->f[i] += fnew[3 * q + a];
                        wk += (fnew[3 * q + a] + fold[3 * q + a]) * p->v[i];
                    }
        } else if (red) {
            FLOE_OMP(omp parallel for schedule(static) num_threads(ntl))
            for (int c = 0; c < nblk; c++)
                red[c] = pd_ledger_block(fnew, fold, pf, vel, c * B, (c + 1) * B < np ? (c + 1) * B : np);
            for (int c = 0; c < nblk; c++) wk += red[c];
        } else
            for (int c = 0; c < nblk; c++)
                wk += pd_ledger_block(fnew, fold, pf, vel, c * B, (c + 1) * B < np ? (c + 1) * B : np);
        if (w->cell) { /* periodic cell: the bonds' virial (pd_vir_visit) */
            double v0[9];
            memcpy(v0, vc.vir, sizeof v0);
            vc.b = pb;
            vc.x = floe_pd_positions(w, b); /* MPI: the points here (each rank its owned rows' bonds) */
            int rc = floe_pd_bond_forces(pb, vc.x, pd_vir_visit, &vc);
            if (rc != FLOE_OK) {
                rc = floe_world_error(w, rc, "PD body %d: its bond forces for the cell's stress: %s", b, floe_strerror(rc));
                /* MPI: the later bodies' evaluations still run (an LPS body's exchange is a
                 * collective), the first failure returned after them */
                if (!w->par) return rc;
                if (!pd_fail) { pd_fail = rc; memcpy(pd_why, w->err, sizeof pd_why); }
                off += np;
                continue;
            }
            /* this body's share of the cell's work (its watchdog ledger; at the present virial) */
            double wcb = 0;
            for (int a = 0; a < 3; a++)
                for (int c = 0; c < 3; c++) wcb += (vc.vir[3 * c + a] - v0[3 * c + a]) * w->cell->L[3 * a + c];
            if (stepping && b < w->pd_diss_n) w->pd_diss[b] += wcb * ctx->dt;
        }
        if (stepping) {
            double db = -0.5 * wk * ctx->dt - (e - w->pd_eold[b]);
            diss += db;
            if (b < w->pd_diss_n) w->pd_diss[b] += db; /* per body, for the energy watchdog */
        }
        w->pd_eold[b] = e;
        elastic += e;
        off += np;
    }
    if (pd_fail) {
        memcpy(w->err, pd_why, sizeof pd_why);
        return pd_fail;
    }
    if (w->cell && w->npd) { /* the bonds' virial: the cell's stress and its work on the bonds */
        floe_cell_state *cs = w->cell;
        if (stepping) { /* the work of the cell's deformation on the bonds, (W_old + W_new)/2 : L dt */
            double wc = 0;
            for (int a = 0; a < 3; a++)
                for (int c = 0; c < 3; c++) wc += 0.5 * (cs->pd_virial[3 * c + a] + vc.vir[3 * c + a]) * cs->L[3 * a + c];
            out->work_boundary += wc * ctx->dt;
            diss += wc * ctx->dt; /* the ledger books the work done on the bonds less dE: the cell's too */
        }
        memcpy(cs->pd_virial, vc.vir, sizeof vc.vir);
        if (cs->want_kdiag)
            for (int k = 0; k < 9; k++) cs->kdiag[k] += vc.kdiag[k];
    }
    if (w->npd) { /* the new forces become the old ones */
        double *t = w->pd_fold;
        w->pd_fold = w->pd_fnew;
        w->pd_fnew = t;
        /* bonds that broke may let their pairs meet by contact: the list is rebuilt next */
        if (floe_pd_broken_pairs_reachable(w)) out->rebuild = 1;
    }
    out->elastic = elastic;
    out->dissipated = diss;
    return FLOE_OK;
}

static int pd_excludes(const floe_provider *pv, const floe_world *w, int i, int j) {
    (void)pv;
    return floe_pd_pair_excluded(w, i, j);
}

/* its state: last forces and energies, broken counts and flags, per-point critical
 * stretches (LAMMPS alpha) and plastic stretches: everything a step of the bonds changes */
static size_t pd_state_size(const floe_provider *pv, const floe_world *w) {
    (void)pv;
    size_t n = 3 * (size_t)w->pd_npts * sizeof(double) + 4 * (size_t)w->npd * sizeof(double);
    for (int k = 0; k < w->npd; k++) {
        const floe_pd_body *b = w->pd[k];
        n += (size_t)b->nbond;
        if (b->s0) n += 2 * (size_t)b->n * sizeof(double);
        if (b->splast) n += (size_t)b->nbond * sizeof(float);
        if (b->ops->state_size) n += b->ops->state_size(b); /* a user material's (floe_pd.h) */
    }
    return n;
}

static void pd_state_io(floe_world *w, unsigned char *buf, int save) {
#define IO(ptr, nbytes) do { if (save) memcpy(buf, (ptr), (nbytes)); else memcpy((ptr), buf, (nbytes)); buf += (nbytes); } while (0)
    IO(w->pd_fold, 3 * (size_t)w->pd_npts * sizeof(double));
    for (int k = 0; k < w->npd; k++) {
        floe_pd_body *b = w->pd[k];
        double d[4];
        if (save) {
            d[0] = w->pd_eold[k]; d[1] = (double)b->nbroken; d[2] = (double)w->pd_nbroken_seen[k];
            d[3] = k < w->pd_diss_n ? w->pd_diss[k] : 0;
        }
        IO(d, sizeof d);
        if (!save) {
            w->pd_eold[k] = d[0]; b->nbroken = (int64_t)d[1]; w->pd_nbroken_seen[k] = (long long)d[2];
            if (k < w->pd_diss_n) w->pd_diss[k] = d[3];
        }
        IO(b->broken, (size_t)b->nbond);
        if (b->s0) IO(b->s0, 2 * (size_t)b->n * sizeof(double));
        if (b->splast) IO(b->splast, (size_t)b->nbond * sizeof(float));
        if (b->ops->state_size) { /* a user material's state */
            size_t m = b->ops->state_size(b);
            if (save) b->ops->save(b, buf);
            else b->ops->restore(b, buf);
            buf += m;
        }
    }
#undef IO
}
static void pd_save(const floe_provider *pv, const floe_world *w, unsigned char *buf) {
    (void)pv;
    pd_state_io((floe_world *)w, buf, 1); /* reads only */
}
static void pd_restore(floe_provider *pv, floe_world *w, const unsigned char *buf) {
    (void)pv;
    pd_state_io(w, (unsigned char *)buf, 0); /* reads only from buf */
}
const floe_provider_class floe_pd_provider_class = {
    .version = 1, .name = "pd_bonds", .group = FLOE_GROUP_PD, .forces = pd_stage, .excludes = pd_excludes,
    .state_size = pd_state_size, .save = pd_save, .restore = pd_restore};

/* ---- the staged evaluation ---- */

/* The accelerations f / m of the last evaluation, for the linear dashpots' end-of-step
 * velocity (pair_an_ext), kept before p->f is cleared; only when a law has a linear dashpot
 * (floe_law_info.linear_gn > 0). p->f is part of a checkpoint, so a restart copies the same.
 * After an RK2 midpoint probe the copy of the probe is kept: the contact history (its last
 * force) was put back to the step's start, and the accelerations must be of the same
 * evaluation. */
int floe_world_dash_reserve(floe_world *w) {
    const size_t n3 = 3 * (size_t)w->p.n;
    if (n3 <= w->dash_cap) return FLOE_OK;
    double *t = realloc(w->dash_a, n3 * sizeof *t);
    if (!t) return FLOE_ENOMEM;
    w->dash_a = t;
    w->dash_cap = n3;
    return FLOE_OK;
}

/* a law with a linear dashpot asks for the accelerations (floe_contact.an_ext) */
static int dash_wanted(const floe_world *w) {
    int want = 0;
    for (int k = 0; k < w->nmats * w->nmats && !want; k++)
        want = w->laws[k] && floe_contact_law_info(w->laws[k]).linear_gn > 0;
    return want;
}

int floe_world_dash_next(const floe_world *w) { return dash_wanted(w) && !(w->dash_keep && w->dash_on); }

static int dashpot_accelerations(floe_world *w, const floe_step_ctx *ctx, int *dash) {
    const floe_particles *p = &w->p;
    *dash = 0;
    const int want = dash_wanted(w);
    const int keep = w->dash_keep && w->dash_on;
    w->dash_keep = ctx->probe;
    w->dash_on = 0;
    if (!want || p->n == 0) return FLOE_OK;
    if (floe_world_dash_reserve(w)) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    w->dash_on = 1;
    *dash = !keep; /* forces_clear computes them */
    return FLOE_OK;
}

/* The DEM group's start: the accelerations of the last evaluation into dash_a (dash: from
 * dashpot_accelerations), then the forces set to gravity, m g on the free particles and 0 on
 * the others (the body stage, always the first, assigned it here before), and the torques
 * cleared. One pass over the store, on the threads, each its even share of the particles, as
 * the integrator's loops (one thread clearing them all pulled every particle's force into its
 * core's caches, for the other thread to pull back). After velocity Verlet's drift, which did
 * this for the free particles as it read their forces (w->drift_cleared, step.c), the pass sees
 * to the others alone: a scan of the motion bytes, on one thread. */
static void forces_clear(floe_world *w, int dash) {
    floe_particles *p = &w->p;
    const int n = p->n, B = FLOE_PAR_BLOCK, nb = (n + B - 1) / B, nt = floe_world_loop_threads(w, n);
    double *f = p->f, *t = p->t, *da = w->dash_a;
    const double *im = p->inv_mass, *m = p->mass;
    const uint8_t *mo = p->motion;
    const double g0 = w->def.gravity[0], g1 = w->def.gravity[1], g2 = w->def.gravity[2];
    if (w->drift_cleared) {
        w->drift_cleared = 0;
        /* runs of 64 motion bytes, each skipped when their OR is 0 (FLOE_FREE): a loop the
         * compiler vectorises, where a test per particle cost a cycle each (7 us of a
         * dem-settle step, on one thread while the others wait) */
        _Static_assert(FLOE_FREE == 0, "the scan below ORs motion bytes");
        for (int i0 = 0; i0 < n; i0 += 64) {
            const int i1 = i0 + 64 < n ? i0 + 64 : n;
            unsigned any = 0;
            for (int i = i0; i < i1; i++) any |= mo[i];
            if (!any) continue;
            for (int i = i0; i < i1; i++) {
                if (mo[i] == FLOE_FREE) continue;
                for (int a = 0; a < 3; a++) {
                    if (dash) da[3 * i + a] = f[3 * i + a] * im[i];
                    f[3 * i + a] = t[3 * i + a] = 0.0;
                }
            }
        }
        return;
    }
    FLOE_OMP(omp parallel for schedule(static) num_threads(nt) if (nt > 1))
    for (int b = 0; b < nb; b++) {
        const int i0 = b * B, i1 = i0 + B < n ? i0 + B : n;
        if (dash)
            for (int i = i0; i < i1; i++)
                for (int a = 0; a < 3; a++) da[3 * i + a] = f[3 * i + a] * im[i];
        for (int i = i0; i < i1; i++) { /* (mi: no inf x 0 for a fixed particle's infinite mass) */
            const int fr = mo[i] == FLOE_FREE;
            const double mi = fr ? m[i] : 0.0;
            f[3 * i] = fr ? mi * g0 : 0.0;
            f[3 * i + 1] = fr ? mi * g1 : 0.0;
            f[3 * i + 2] = fr ? mi * g2 : 0.0;
        }
        memset(t + 3 * (size_t)i0, 0, (size_t)(i1 - i0) * 3 * sizeof(double));
    }
}

int floe_world_forces(floe_world *w, const floe_step_ctx *ctx, int groups) {
    floe_particles *p = &w->p;
    const int n = p->n;
    const int stepping = ctx->stepping;
    floe_provider_out od = {0, 0, 0, 0}, op = {0, 0, 0, 0};
    /* a stage's failure: returned at once; on a split world (MPI) after the later stages have
     * run, since a stage may hold a collective (an LPS body's dilatation exchange,
     * core/parallel par_pd.c) that the other ranks reach: the step then agrees on the first
     * failure (step.c forces_all). Its message is kept */
    int first = FLOE_OK;
    char why[sizeof w->err];
    if (groups & FLOE_GROUP_DEM) {
        int dash = 0;
        first = dashpot_accelerations(w, ctx, &dash);
        if (first && !w->par) return first;
        if (first) memcpy(why, w->err, sizeof why);
        if (n > 0) forces_clear(w, dash);
        w->ncontacts = 0;
    }
    for (int k = 0; k < w->nprov; k++) {
        floe_provider *pv = w->prov[k];
        if (!(pv->klass->group & groups)) continue;
        floe_provider_out *o = pv->klass->group == FLOE_GROUP_PD ? &op : &od;
        o->rebuild = 0;
        int rc = pv->klass->forces(pv, w, ctx, o);
        if (rc) {
            if (!w->par) return rc;
            if (!first) { first = rc; memcpy(why, w->err, sizeof why); }
            continue;
        }
        if (o->rebuild && !first) { /* between stages, never inside one */
            if (ctx->probe) return floe_world_error(w, FLOE_EINVAL, "internal: %s changed pairs at a probe", pv->klass->name);
            /* MPI: a user's provider runs on each rank's own particles, and a list built on
             * one rank alone would read the ghosts the decomposition chose not to refresh
             * (docs/parallel.md, "Ghosts a step refreshes"; floe_provider.h) */
            if (w->par && floe_provider_is_user(w, pv))
                rc = floe_world_error(w, FLOE_ENOTSUP, "MPI decomposition: the force provider %s asked for a "
                                      "neighbour-list rebuild, which a provider that runs split may not (floe_provider.h)",
                                      pv->klass->name);
            else if ((rc = floe_world_nl_build(w)) != FLOE_OK)
                rc = floe_world_error(w, rc, "neighbour list rebuild after %s changed pairs failed (out of memory)",
                                      pv->klass->name);
            if (rc && !w->par) return rc;
            if (rc) { first = rc; memcpy(why, w->err, sizeof why); }
        }
    }
    if (first) {
        memcpy(w->err, why, sizeof why);
        return first;
    }
    if (ctx->probe) { /* nothing booked: the caller restores the providers' state */
        if (w->def.dim == 2)
            for (int i = 0; i < n; i++) { p->f[3 * i + 2] = 0; p->t[3 * i] = p->t[3 * i + 1] = 0; }
        return FLOE_OK;
    }
    if (groups & FLOE_GROUP_DEM) {
        w->elastic_contact = od.elastic;
        w->contacts_valid = ctx->record;
        w->st.force_evaluations += stepping;
    }
    if ((groups & FLOE_GROUP_PD) && w->npd) {
        w->elastic_pd = op.elastic;
        w->st.pd_evaluations += stepping;
    }
    if (w->def.dim == 2)
        for (int i = 0; i < n; i++) { p->f[3 * i + 2] = 0; p->t[3 * i] = p->t[3 * i + 1] = 0; }
    w->energy.elastic = w->elastic_contact + w->elastic_pd;
    if (stepping) {
        w->energy.dissipated += od.dissipated + op.dissipated;
        w->energy.work_boundary += od.work_boundary + op.work_boundary; /* PD: a periodic cell's work on the bonds */
    }
    return FLOE_OK;
}

int floe_compute_forces(floe_world *w) {
    floe_step_ctx c = {&w->p, w->def.dim, 0, w->time, w->dt, 0.0, 0, w->record_contacts || w->obs_need_contacts, 0};
    return floe_world_forces(w, &c, FLOE_GROUP_ALL);
}

/* floe_cell.h: the forces again at the present state, the contacts recorded */
int floe_world_refresh_forces(floe_world *w) {
    if (!w->prepared) return floe_world_error(w, FLOE_EINVAL, "refresh: prepare the world first");
    /* MPI: an evaluation outside the step would leave the ghosts' forces unsent to their owners */
    if (w->par) return floe_world_error(w, FLOE_ENOTSUP, "refresh: not on a world split over MPI ranks (docs/periodic.md)");
    const int keep = w->record_contacts;
    w->record_contacts = 1;
    int rc = floe_compute_forces(w);
    w->record_contacts = keep;
    return rc;
}
