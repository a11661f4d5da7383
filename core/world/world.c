/* world.c - the simulation world: the particle store, registration of materials, laws,
 * geometries, particles, walls, states and observers, and the accessors. Its other parts:
 * world_pd.c (PD bodies and regions), world_beams.c (beam bonds), forces.c (the staged force
 * providers), timestep.c (critical-step estimates), world_prepare.c (the store's part of
 * prepare, observers, finish), neighbor.c (Verlet list). This file is the bottom of the
 * folder: it calls none of them. The driver (prepare, step, run, the integrators, the
 * energy watchdog) is the layer above: core/integrators (docs/architecture.md). */
#include "world_internal.h"
#include "alloc_util.h"
#include "floe_par.h"
#include "floe_pd.h"
#include "beam_set.h"
#include "floe_provider.h"
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <string.h>
#include "world_parts.h"
#include "error_text.h"

/* a threaded stage's per-thread error buffer (floe_world_error_to) */
static _Thread_local char *err_to;
static _Thread_local size_t err_to_len;
void floe_world_error_to(char *buf, size_t len) {
    err_to = buf;
    err_to_len = buf ? len : 0;
}

int floe_world_error(floe_world *w, int code, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    if (err_to) floe_error_vset(err_to, err_to_len, code, fmt, ap);
    else floe_error_vset(w->err, sizeof w->err, code, fmt, ap);
    va_end(ap);
    return code;
}

/* the names of the energy watchdog's modes (the watchdog: core/integrators/watchdog.c) */
const char *floe_energy_check_name(int mode) {
    static const char *const names[] = {"stop", "warn", "off"};
    return mode >= FLOE_CHECK_STOP && mode <= FLOE_CHECK_OFF ? names[mode] : NULL;
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


/* grow an array of n elements of size sz to hold at least need */
int grow(void **ptr, int *cap, int need, size_t sz) {
    if (need <= *cap) return FLOE_OK;
    int nc = *cap ? *cap : 8;
    while (nc < need) nc *= 2;
    void *np = realloc(*ptr, (size_t)nc * sz);
    if (!np) return FLOE_ENOMEM;
    *ptr = np;
    *cap = nc;
    return FLOE_OK;
}

int floe_world_pp_attach(floe_world *w, double **arr, int *n, int m) {
    for (int k = 0; k < w->npps; k++)
        if (w->pps[k].arr == arr) return FLOE_OK;
    if (grow((void **)&w->pps, &w->pps_cap, w->npps + 1, sizeof *w->pps)) return FLOE_ENOMEM;
    w->pps[w->npps++] = (struct floe_pp_state){arr, n, m};
    return FLOE_OK;
}

int floe_world_pp_attach_first(floe_world *w, double **arr, int *n, int m) {
    FLOE_TRY(floe_world_pp_attach(w, arr, n, m));
    int k = 0;
    while (w->pps[k].arr != arr) k++;
    const struct floe_pp_state s = w->pps[k];
    memmove(w->pps + 1, w->pps, (size_t)k * sizeof *w->pps);
    w->pps[0] = s;
    return FLOE_OK;
}

void floe_world_pp_detach(floe_world *w, double **arr) {
    for (int k = 0; k < w->npps; k++)
        if (w->pps[k].arr == arr) {
            memmove(w->pps + k, w->pps + k + 1, (size_t)(w->npps - k - 1) * sizeof *w->pps);
            w->npps--;
            return;
        }
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
    w->par_grain = 2048;
    return w;
}

int floe_world_set_threads(floe_world *w, int nthreads) {
    int code;
    const char *why = floe_par_threads_refused(nthreads, &code);
    if (why) return floe_world_error(w, code, "threads: %d %s", nthreads, why);
    w->nthreads = nthreads;
    return FLOE_OK;
}

int floe_world_threads(const floe_world *w) { return w->nthreads > 0 ? w->nthreads : floe_par_max_threads(); }

void floe_par_scratch_free(floe_par_scratch *ps) {
    if (!ps) return;
    free(ps->pf); free(ps->act); free(ps->gl); free(ps->gc); free(ps->adj); free(ps->adj_off); free(ps->row); free(ps->lead); free(ps->bpart); free(ps->brange); free(ps->pb); free(ps->blk); free(ps->bs); free(ps->bt); free(ps->bf);
    for (int t = 0; t < ps->ndet; t++) free(ps->det[t].scratch);
    for (int t = 0; t < ps->nrs; t++) free(ps->rs[t].r);
    free(ps->rs);
    free(ps->det); free(ps->err); free(ps->fail_b); free(ps->fail_rc);
    free(ps);
}

double *floe_world_reduce_buf(floe_world *w, size_t n) {
    if (n > w->red_cap) {
        double *t = realloc(w->red, n * sizeof *t);
        if (!t) return NULL;
        w->red = t;
        w->red_cap = n;
    }
    return w->red;
}

const int *floe_loop_split_cuts(floe_world *w, int nt, int nb) {
    floe_loop_split *s = &w->ls;
    if (nt < 1) return NULL;
    if (nt > s->cap) {
        if (floe_resize((void **)&s->cut, (size_t)nt + 1, sizeof *s->cut) ||
            floe_resize((void **)&s->spb, (size_t)nt, sizeof *s->spb) ||
            floe_resize((void **)&s->sec, (size_t)nt, sizeof *s->sec))
            return NULL;
        s->cap = nt;
        s->nt = 0; /* cut anew */
    }
    if (s->nt != nt || s->nb != nb) { /* evenly, as schedule(static) */
        for (int t = 0; t <= nt; t++) s->cut[t] = (int)((long long)nb * t / nt);
        for (int t = 0; t < nt; t++) s->spb[t] = s->sec[t] = 0.0;
        s->nt = nt;
        s->nb = nb;
    }
    return s->cut;
}

void floe_loop_split_update(floe_world *w) {
    floe_loop_split *s = &w->ls;
    const int nt = s->nt;
    if (nt < 2 || s->nb < nt) return;
    double tot_speed = 0, worst = 0, mean = 0;
    int ok = 1;
    for (int t = 0; t < nt; t++) {
        const int nbt = s->cut[t + 1] - s->cut[t];
        if (nbt > 0 && s->sec[t] > 0) {
            const double m = s->sec[t] / nbt;
            s->spb[t] = s->spb[t] > 0 ? 0.75 * s->spb[t] + 0.25 * m : m;
        }
        s->sec[t] = 0.0;
        ok &= s->spb[t] > 0;
        if (!ok) continue;
        tot_speed += 1.0 / s->spb[t];
        const double T = nbt * s->spb[t];
        mean += T / nt;
        if (T > worst) worst = T;
    }
    if (!ok || !(worst > 1.05 * mean)) return;
    /* cut again: part t gets its speed's share of the blocks (at least one each) */
    double acc = 0;
    s->cut[0] = 0;
    for (int t = 0; t < nt; t++) {
        acc += (1.0 / s->spb[t]) / tot_speed;
        int c = t == nt - 1 ? s->nb : (int)(acc * s->nb + 0.5);
        if (c < s->cut[t] + 1) c = s->cut[t] + 1;
        if (c > s->nb - (nt - 1 - t)) c = s->nb - (nt - 1 - t);
        s->cut[t + 1] = c;
    }
}

int floe_world_loop_threads(const floe_world *w, long items) {
    if (items < w->par_grain) return 1;
    return floe_world_threads(w);
}

int floe_world_blocks(floe_world *w, int n, int nsum, floe_block_fn fn, void *ctx, double *sum) {
    const int B = FLOE_PAR_BLOCK, nb = n > 0 ? (n + B - 1) / B : 0, m = nsum > 0 ? nsum : 1;
    for (int k = 0; k < nsum; k++) sum[k] = 0.0;
    if (nb == 0) return FLOE_OK;
    double *red = floe_world_reduce_buf(w, (size_t)nb * m);
    if (!red) return FLOE_ENOMEM;
    const int nt = floe_world_loop_threads(w, n);
    if (nt > 1) {
        FLOE_OMP(omp parallel for num_threads(nt) schedule(static))
        for (int b = 0; b < nb; b++) fn(ctx, b * B, b + 1 == nb ? n : (b + 1) * B, red + (size_t)b * m);
    } else
        for (int b = 0; b < nb; b++) fn(ctx, b * B, b + 1 == nb ? n : (b + 1) * B, red + (size_t)b * m);
    for (int b = 0; b < nb; b++)
        for (int k = 0; k < nsum; k++) sum[k] += red[(size_t)b * m + k];
    return FLOE_OK;
}

/* a copy of src (NULL: zeros) into dst on the world's threads, one chunk a thread (below 2
 * grains on one thread) */
static void world_fill(const floe_world *w, void *dst, const void *src, size_t bytes, size_t grain) {
    const int nt = bytes >= 2 * grain ? floe_world_threads(w) : 1;
    if (nt <= 1) {
        if (src) memcpy(dst, src, bytes);
        else memset(dst, 0, bytes);
        return;
    }
    const size_t chunk = ((bytes + (size_t)nt - 1) / (size_t)nt + 63) & ~(size_t)63;
    FLOE_OMP(omp parallel for num_threads(nt) schedule(static))
    for (int t = 0; t < nt; t++) {
        const size_t a = (size_t)t * chunk, b = a + chunk < bytes ? a + chunk : bytes;
        if (a < b && src) memcpy((char *)dst + a, (const char *)src + a, b - a);
        else if (a < b) memset((char *)dst + a, 0, b - a);
    }
}

void floe_world_copy(const floe_world *w, void *dst, const void *src, size_t bytes) {
    world_fill(w, dst, src, bytes, (size_t)1 << 20);
}

/* zeros: a parallel region (a few microseconds) is worth it from 512 KiB */
void floe_world_zero(const floe_world *w, void *dst, size_t bytes) { world_fill(w, dst, NULL, bytes, (size_t)1 << 18); }

/* the list's view of the law "none" (floe_neighbor_list.none, .inert): the pairs of
 * materials under it, and the materials whose particles touch nothing in the store (the law
 * "none" with every material present, walls included); both NULL when no law is "none" */
static void inert_materials(floe_world *w) {
    const int nm = w->nmats, n = w->p.n;
    w->nl.none = w->nl.inert = NULL;
    w->nl.nmat = nm;
    int any_none = 0;
    for (int k = 0; k < nm * nm && !any_none; k++) any_none = floe_contact_law_no_contact(w->laws[k]);
    if (!any_none) return;
    if (nm * nm + 2 * nm > w->inert_cap) {
        unsigned char *t = realloc(w->inert, (size_t)(nm * nm + 2 * nm));
        if (!t) return; /* the search then pairs them, and the stage skips their pairs */
        w->inert = t;
        w->inert_cap = nm * nm + 2 * nm;
    }
    unsigned char *inert = w->inert, *present = inert + nm, *none = present + nm;
    for (int k = 0; k < nm * nm; k++) none[k] = (unsigned char)floe_contact_law_no_contact(w->laws[k]);
    memset(present, 0, (size_t)nm);
    for (int i = 0; i < n; i++) {
        const int m = w->p.material[i];
        if (m >= 0 && m < nm) present[m] = 1;
    }
    for (int a = 0; a < nm; a++) {
        inert[a] = 1;
        for (int b = 0; b < nm && inert[a]; b++)
            if (present[b] && !none[a * nm + b]) inert[a] = 0;
    }
    w->nl.none = none;
    w->nl.inert = inert;
}

int floe_world_hist_layout(floe_world *w) {
    if (!w->hs_need || w->hs_law_gen != w->law_gen || w->hs_ngeoms != w->ngeoms) {
        const int nm2 = w->nmats * w->nmats;
        int need = FLOE_HIST_COMPACT;
        for (int k = 0; k < nm2 && need < FLOE_MAX_HISTORY; k++)
            if (w->laws[k] && w->laws[k]->klass->history_size > FLOE_HIST_COMPACT - FLOE_LAW_SLOT) need = FLOE_MAX_HISTORY;
        for (int g = 0; g < w->ngeoms && need < FLOE_MAX_HISTORY; g++) {
            const floe_geometry_kind kd = w->geoms[g]->klass->kind;
            if (kd != FLOE_GEOM_SPHERE && kd != FLOE_GEOM_PLANE) need = FLOE_MAX_HISTORY; /* a manifold's twist */
        }
        w->hs_need = need;
        w->hs_law_gen = w->law_gen;
        w->hs_ngeoms = w->ngeoms;
    }
    const int rc = floe_nl_set_stride(&w->nl, w->hs_need);
    return rc ? floe_world_error(w, rc, "out of memory (contact history)") : FLOE_OK;
}

int floe_world_nl_build(floe_world *w) {
    FLOE_TRY(floe_world_hist_layout(w));
    int nt = floe_world_loop_threads(w, w->p.n);
    inert_materials(w);
    w->nl_law_gen = w->law_gen;
    /* the search calls the providers' excludes from every thread: a user's on one thread
     * (floe_provider.h does not ask it to be thread-safe) */
    for (int k = 0; k < w->nprov && nt > 1; k++)
        if (w->prov[k]->klass->excludes && floe_provider_is_user(w, w->prov[k])) nt = 1;
    w->nl.threads = nt;
    return floe_nl_build(&w->nl, &w->p, w->def.dim, w->def.leaf_size);
}

static void particles_free(floe_particles *p) {
    free(p->block);
    p->block = NULL;
    free(p->thick);
    p->thick = NULL;
}

/* the providers the world owns (built at prepare, and users' from floe_world_add_provider,
 * user_providers.c): the store frees them */
int floe_provider_is_user(const floe_world *w, const floe_provider *pv) {
    for (int k = 0; k < w->nuprov; k++)
        if (w->uprov[k] == pv) return 1;
    return 0;
}

void floe_world_providers_free(floe_world *w) {
    for (int k = 0; k < w->nprov; k++)
        if (!floe_provider_is_user(w, w->prov[k])) free(w->prov[k]);
    free(w->prov);
    w->prov = NULL;
    w->nprov = w->prov_cap = 0;
    for (int k = 0; k < w->nuprov; k++) {
        floe_provider *pv = w->uprov[k];
        if (pv->klass->destroy) pv->klass->destroy(pv);
        else free(pv);
    }
    free(w->uprov);
    w->uprov = NULL;
    w->nuprov = w->uprov_cap = 0;
}

void floe_world_destroy(floe_world *w) {
    if (!w) return;
    floe_par_scratch_free(w->thr);
    free(w->red);
    free(w->ls.cut); free(w->ls.spb); free(w->ls.sec);
    particles_free(&w->p);
    for (int i = 0; i < w->ngeoms; i++) floe_geometry_destroy(w->geoms[i]);
    free(w->geoms);
    free(w->mats);
    for (int i = 0; i < w->nlaws_owned; i++) floe_contact_law_destroy(w->law_owned[i]);
    free(w->law_owned);
    free(w->laws);
    free(w->inert);
    free(w->motions);
    free(w->motion_idx);
    free(w->fb_old);
    free(w->kin_old);
    free(w->kinb);
    free(w->pps);
    free(w->sep_d);
    free(w->sep_pose);
    free(w->sep_pair);
    free(w->sep_geom);
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
    free(w->rk2);
    free(w->stag);
    free(w->dash_a);
    if (w->snap && w->snap_free) w->snap_free(w->snap); /* the adaptive controller's (core/integrators) */
    if (w->par && w->par_free) w->par_free(w->par);     /* the decomposition's (core/parallel) */
    for (int k = 0; k < w->npd; k++) floe_pd_body_destroy(w->pd[k]);
    free(w->pd); free(w->pd_first); free(w->pd_of); free(w->pd_fold); free(w->pd_fnew); free(w->pd_eold); free(w->pd_diss); free(w->pd_diss_sum);
    for (int k = 0; k < w->npd_bc; k++) { free(w->pd_bc[k]->pts); free(w->pd_bc[k]->fold); free(w->pd_bc[k]); }
    free(w->pd_bc); free(w->pd_nbroken_seen);
    floe_beam_set_destroy(w->beams);
    floe_world_providers_free(w); /* built-in and user providers */
    free(w->pbuf);
    free(w->cell);
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
    if (law->klass->history_size < 0 || law->klass->history_size > FLOE_LAW_HISTORY) {
        const int hsz = law->klass->history_size;
        const char *nm = law->klass->name;
        floe_contact_law_destroy(law);
        return floe_world_error(w, FLOE_EINVAL, "set_law: the law %s keeps %d doubles of history per contact "
                                "(floe_contact_law_class.history_size: 0 to %d)", nm ? nm : "?", hsz, FLOE_LAW_HISTORY);
    }
    if (grow((void **)&w->law_owned, &w->law_owned_cap, w->nlaws_owned + 1, sizeof *w->law_owned)) {
        floe_contact_law_destroy(law);
        return FLOE_ENOMEM;
    }
    w->law_owned[w->nlaws_owned++] = law;
    w->laws[a * w->nmats + b] = law;
    w->laws[b * w->nmats + a] = law;
    w->law_gen++;
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

/* The arrays of the store in one allocation, each starting at its own offset within a
 * 4 KiB page (a multiple of 320 bytes, i.e. 5 cache lines, apart). Allocated one by one,
 * every array above the allocator's mmap threshold started 16 bytes into a page, so x[i],
 * v[i], f[i], L[i], ... of one particle had the same low 12 address bits: the integration
 * loops, which stream a dozen of them, paid the loads' false dependence on earlier stores
 * to another array (4K aliasing) and competed for one L1 set (bench/RESULTS.md,
 * "The store in one block"). */
static int particles_layout(floe_particles *p, int nc);

/* the store's arrays in the block, with the doubles or items per particle of each (thick,
 * outside the block, apart). core/parallel/decomp.c's record (floe_par_pack) carries the
 * same fields: a field added here must be added there */
#define STORE_FIELDS(X) X(x, 3); X(v, 3); X(q, 4); X(w, 3); X(L, 3); X(f, 3); X(t, 3); X(mass, 1); X(inv_mass, 1); \
    X(inertia, 3); X(inv_iso, 1); X(radius, 1); X(rdot, 1); X(geom, 1); X(material, 1); X(group, 1); X(pieces, 1);  \
    X(motion, 1); X(kind, 1); X(iso, 1)

void floe_world_move_particles(floe_world *w, int dst, int src, int n) {
    floe_particles *p = &w->p;
    if (n <= 0 || dst == src) return;
#define SHIFT(field, k) memmove(p->field + (size_t)dst * (k), p->field + (size_t)src * (k), (size_t)n * (k) * sizeof *p->field)
    STORE_FIELDS(SHIFT);
    if (p->thick) SHIFT(thick, 1);
#undef SHIFT
}

static int particles_reserve(floe_particles *p, int need) {
    if (need <= p->cap) return FLOE_OK;
    int nc = p->cap ? p->cap : 64;
    while (nc < need) nc *= 2;
    return particles_layout(p, nc);
}

/* the store's block at capacity nc (>= p->n), the particles moved into it */
static int particles_layout(floe_particles *p, int nc) {
    enum { PAGE = 4096, STAGGER = 320 };
    size_t off[20], total = 0;
    int nf = 0;
#define LAY(field, k) do { \
        size_t base_ = (total + PAGE - 1) / PAGE * PAGE; \
        off[nf] = base_ + (size_t)((nf + 1) * STAGGER) % PAGE; \
        total = off[nf] + (size_t)nc * (k) * sizeof *p->field; \
        nf++; } while (0)
    STORE_FIELDS(LAY);
    char *b = malloc(total);
    if (!b) return FLOE_ENOMEM;
    if (p->thick) { /* floes' thickness: its own allocation, present only when used (before
                     * the move: a failure leaves the store as it was) */
        double *t = realloc(p->thick, (size_t)nc * sizeof *t);
        if (!t) {
            free(b);
            return FLOE_ENOMEM;
        }
        p->thick = t;
    }
    nf = 0;
#define MOVE(field, k) do { \
        void *dst_ = b + off[nf++]; \
        if (p->n > 0) memcpy(dst_, p->field, (size_t)p->n * (k) * sizeof *p->field); \
        p->field = dst_; } while (0)
    STORE_FIELDS(MOVE);
#undef MOVE
#undef LAY
    free(p->block);
    p->block = b;
    p->cap = nc;
    return FLOE_OK;
}

int floe_world_reserve_particles(floe_world *w, int need) { return particles_reserve(&w->p, need); }

int floe_world_local_of(const floe_world *w, long long id, int ghosts) {
    const floe_neighbor_list *nl = &w->nl;
    if (!nl->gid) return id >= 0 && id < w->p.n ? (int)id : -1;
    const int ranges[2][2] = {{0, nl->rep_hi}, {nl->rep_hi, nl->own_hi}}; /* walls, owned */
    for (int r = 0; r < 2; r++) {
        int lo = ranges[r][0], hi = ranges[r][1];
        while (lo < hi) {
            const int mid = lo + (hi - lo) / 2;
            if (nl->gid[mid] < id) lo = mid + 1;
            else hi = mid;
        }
        if (lo < ranges[r][1] && nl->gid[lo] == id) return lo;
    }
    for (int i = nl->own_hi; ghosts && i < w->p.n; i++)
        if (nl->gid[i] == id) return i;
    return -1;
}

void floe_world_trim(floe_world *w, int released) {
    floe_particles *p = &w->p;
    const int fit = p->n + p->n / 4 + 64;
    /* out of memory: the larger block is kept */
    if (p->cap > fit + fit / 2 && particles_layout(p, fit) == FLOE_OK) released = 1;
    if (floe_nl_trim(&w->nl)) released = 1;
#ifdef __GLIBC__
    if (released) malloc_trim(0); /* the freed pages back to the system (glibc keeps some in its heap) */
#else
    (void)released;
#endif
}

int floe_world_add_particle(floe_world *w, const floe_particle_def *d) {
    if (floe_world_refuse_split(w, "add_particle")) return -FLOE_ENOTSUP;
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
    if (d->thickness < 0 || !isfinite(d->thickness))
        return -floe_world_error(w, FLOE_EINVAL, "particle: thickness must be >= 0 and finite (0 = none), got %g", d->thickness);
    if (d->thickness > 0 && w->def.dim != 2)
        return -floe_world_error(w, FLOE_EINVAL, "particle: a thickness is for 2D floes (dimension: 2)");
    floe_particles *p = &w->p;
    if (particles_reserve(p, p->n + 1)) return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    if (d->thickness > 0 && !p->thick) { /* the first floe: none for every particle so far */
        p->thick = calloc((size_t)p->cap, sizeof *p->thick);
        if (!p->thick) return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
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
    p->inv_iso[i] = 0;
    p->rdot[i] = 0;
    p->pieces[i] = floe_piece_count(g);
    p->radius[i] = floe_geometry_bounding_radius(g);
    p->mass[i] = d->mass; /* resolved at prepare */
    if (p->thick) p->thick[i] = d->thickness;
    w->prepared = 0;
    return i;
}

int floe_world_add_wall(floe_world *w, const double pt[3], const double n[3], int material, floe_motion motion) {
    double nn = floe_v3_norm(n);
    if (!(nn > 0) || !isfinite(nn)) return -floe_world_error(w, FLOE_EINVAL, "wall: normal must be non-zero");
    if (motion == FLOE_FREE) return -floe_world_error(w, FLOE_EINVAL, "wall: motion must be fixed or kinematic");
    if (floe_world_refuse_split(w, "add_wall")) return -FLOE_ENOTSUP;
    floe_geometry *pg = floe_plane_create();
    int g = floe_world_add_geometry(w, pg);
    if (g < 0) { /* not taken: still ours */
        floe_geometry_destroy(pg);
        return g;
    }
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

int floe_world_refuse_split(floe_world *w, const char *what) {
    if (!w->par) return 0;
    return floe_world_error(w, FLOE_ENOTSUP, "%s: the world is split over MPI ranks; make this change before "
                            "floe_world_parallel_init (it would prepare each rank's part again, and the ranks "
                            "would have to agree on the result)", what);
}

int floe_world_set_motion(floe_world *w, int i, floe_motion_fn fn, void *user) {
    /* a motion makes the world prepare again (its ranks would disagree on kin_old's row) */
    FLOE_TRY(floe_world_refuse_split(w, "set_motion"));
    if (i < 0 || i >= w->p.n) return floe_world_error(w, FLOE_EINVAL, "set_motion: particle %d out of range", i);
    if (!fn) return floe_world_error(w, FLOE_EINVAL, "set_motion: the motion function is NULL");
    if (grow((void **)&w->motions, &w->motions_cap, w->nmotions + 1, sizeof *w->motions)) return FLOE_ENOMEM;
    w->motions[w->nmotions++] = (floe_motion_cb){i, fn, user, i};
    w->p.motion[i] = FLOE_KINEMATIC;
    w->p.inv_mass[i] = 0;   /* no longer moved by forces (also when called after prepare) */
    w->prepared = 0;
    return FLOE_OK;
}

static int set_body_force(floe_world *w, floe_body_force_fn fn, void *user, int threaded, const char *what) {
    FLOE_TRY(floe_world_refuse_split(w, what));
    w->body_force = fn;
    w->body_force_user = user;
    w->body_force_threaded = threaded;
    w->prepared = 0;   /* prepare sizes the per-particle callback force (adaptive snapshots) */
    return FLOE_OK;
}

int floe_world_set_body_force(floe_world *w, floe_body_force_fn fn, void *user) {
    return set_body_force(w, fn, user, 0, "set_body_force");
}

int floe_world_set_body_force_threaded(floe_world *w, floe_body_force_fn fn, void *user) {
    return set_body_force(w, fn, user, 1, "set_body_force_threaded");
}

int floe_world_add_state(floe_world *w, floe_state *s) {
    if (!s) return floe_world_error(w, FLOE_EINVAL, "state object is NULL");
    const floe_state_class *k = s->klass;
    if (!k || (k->version != 1 && k->version != 2) || !k->size || !k->get || !k->set || !k->rhs)
        return floe_world_error(w, FLOE_EINVAL, "state object class %s: version %d unknown (1, or 2 with probe) or a "
                                "member missing (size, get, set and rhs are required)",
                                k && k->name ? k->name : "(unnamed)", k ? k->version : -1);
    if (grow((void **)&w->states, &w->states_cap, w->nstates + 1, sizeof *w->states)) return FLOE_ENOMEM;
    w->states[w->nstates++] = s;
    return FLOE_OK;
}

int floe_world_record_contacts(floe_world *w, int on) {
    w->record_contacts = on != 0;
    return FLOE_OK;
}

int floe_world_contact_count(const floe_world *w) { return w->ncontacts; }

/* whether round particles' orientations are integrated (floe_world_set_orientation): iso[i]
 * is 2 for an isotropic free sphere (disc) whose orientation nothing reads (the integrators
 * then leave its q), 1 for the other isotropic bodies, 0 otherwise */
/* what o's class says it reads: 0 no orientation, 1 every one (also a class before version
 * 3, which has no such field), FLOE_OBSERVER_READS_LISTED those it lists */
int observer_orientation_claim(const floe_observer *o) {
    const floe_observer_class *c = o->klass;
    if (c->version < 3) return 1;
    return c->reads_orientation == FLOE_OBSERVER_READS_LISTED ? FLOE_OBSERVER_READS_LISTED : c->reads_orientation != 0;
}

/* whether observer o reads the orientation of a round particle of w (one it lists, for a
 * FLOE_OBSERVER_READS_LISTED class) */
int observer_reads_orientation(const floe_observer *o, const floe_world *w) {
    const int claim = observer_orientation_claim(o);
    if (claim != FLOE_OBSERVER_READS_LISTED) return claim;
    const floe_particles *p = &w->p;
    for (int k = 0; k < o->norient_ids; k++) {
        int i = o->orient_ids[k];
        if (i >= 0 && i < p->n && p->iso[i] && p->kind[i] == FLOE_GEOM_SPHERE) return 1;
    }
    return 0;
}

void orientation_refresh(floe_world *w) {
    int need = w->orient_mode != FLOE_ORIENT_AUTO || w->orient_extra || (w->beams && floe_beam_set_count(w->beams) > 0);
    for (int k = 0; k < w->nobs && !need; k++) need = observer_orientation_claim(w->obs[k]) == 1;
    /* force providers other than these built-ins may read orientations (the ocean and wind
     * drag place a floe's quadrature points with it, linear_drag takes L through it, a user
     * provider reads floe_provider_ctx.q), and so may a body-force callback */
    if (w->body_force) need = 1;
    for (int k = 0; k < w->nprov + w->nuprov && !need; k++) {
        const floe_provider *pv = k < w->nprov ? w->prov[k] : w->uprov[k - w->nprov];
        const char *nm = pv->klass->name;
        /* a user's provider whatever its name (the servo walls, added as one, known by their
         * pointer); the world's own stages by name */
        if (floe_provider_is_user(w, pv)) need = pv != w->servo_pv;
        else need = strcmp(nm, "body_forces") && strcmp(nm, "contacts") && strcmp(nm, "beam_bonds") && strcmp(nm, "pd_bonds");
    }
    floe_particles *p = &w->p;
    for (int i = 0; i < p->n; i++)
        if (p->iso[i]) p->iso[i] = !need && p->kind[i] == FLOE_GEOM_SPHERE ? 2 : 1;
    /* an observer that reads the orientations of the particles it lists (a tracker) */
    for (int k = 0; k < w->nobs && !need; k++) {
        const floe_observer *o = w->obs[k];
        if (observer_orientation_claim(o) != FLOE_OBSERVER_READS_LISTED) continue;
        for (int l = 0; l < o->norient_ids; l++) {
            int i = o->orient_ids[l];
            if (i >= 0 && i < p->n && p->iso[i]) p->iso[i] = 1;
        }
    }
}

int floe_world_add_observer(floe_world *w, floe_observer *o) {
    if (!o) return floe_world_error(w, FLOE_EINVAL, "observer is NULL");
    if (o->klass->needs_contacts) w->obs_need_contacts = 1;
    if (grow((void **)&w->obs, &w->obs_cap, w->nobs + 1, sizeof *w->obs)) return FLOE_ENOMEM;
    w->obs[w->nobs++] = o;
    if (w->prepared) orientation_refresh(w);
    return FLOE_OK;
}

int floe_world_set_orientation(floe_world *w, int mode) {
    if (!w) return FLOE_EINVAL;
    if (mode != FLOE_ORIENT_AUTO && mode != FLOE_ORIENT_ALWAYS)
        return floe_world_error(w, FLOE_EINVAL, "orientation mode %d: FLOE_ORIENT_AUTO (0) or FLOE_ORIENT_ALWAYS (1)", mode);
    w->orient_mode = mode;
    if (w->prepared) orientation_refresh(w);
    return FLOE_OK;
}

double floe_world_dt(const floe_world *w) { return w->dt; }

int floe_world_detect_stats(const floe_world *w, floe_detect_stats *o) {
    const floe_detect_state *d = &w->det;
    memset(o, 0, sizeof *o);
    o->evaluations = d->calls;
    o->lp = d->lp_calls;
    o->admm = d->admm_calls;
    o->lp_halves = d->lp_halves;
    o->lp_kept = d->lp_kept;
    o->lp_cold = d->lp_cold;
    o->separated = d->separated;
    o->sep_cached = d->sep_cached;
    o->manifold_cached = d->mf_cached;
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
    o->thickness = p->thick ? p->thick[i] : 0;
    return FLOE_OK;
}


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
    FLOE_TRY(floe_world_refuse_split(w, "set_particle_geometry"));
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
    FLOE_TRY(floe_world_refuse_split(w, "set_dt"));
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

/* ---- estimate queries (floe_world_dt_estimates: core/integrators/driver.c, it prepares) ---- */

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
