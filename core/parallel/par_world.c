/* par_world.c - a world split over MPI ranks (floe_parallel.h, docs/parallel.md): the split,
 * the rebuild sequence (RCB, migration, ghosts, contact history by global ids, the
 * neighbour list), the step's hooks (par_hooks.h) and the reductions. */
#include "alloc_util.h"
#include "floe_parallel.h"
#include "floe_observer_base.h"
#include "par_hooks.h"
#include "par_internal.h"
#include "world_parts.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int floe_world_parallel_error_agreed(const floe_world *w) { return !w || !w->par ? 1 : w->err_agreed; }

const char *floe_comm_kind_name(floe_comm_kind k) {
    static const char *const names[FLOE_COMM_KINDS] = {"ghost", "reverse", "migrate", "reduce", "output"};
    return (int)k >= 0 && k < FLOE_COMM_KINDS ? names[k] : "?";
}

/* floe_world_parallel_set_balance's mode, in both builds */
static int balance_check(floe_world *w, floe_balance mode) {
    if (mode == FLOE_BALANCE_WEIGHTS || mode == FLOE_BALANCE_TIME) return FLOE_OK;
    return floe_world_error(w, FLOE_EINVAL, "MPI decomposition: unknown balance mode %d", (int)mode);
}

#ifdef FLOE_HAVE_MPI

int floe_parallel_available(void) { return 1; }

/* a local index (of this rank's world) as a global id, -1 kept */
static int gid_or(const floe_par *P, int i) { return i >= 0 && i < P->nrep + P->nown + P->nghost ? (int)P->gid[i] : -1; }

/* the particle indices the run keeps for its messages (the watchdog's worst contacts, the
 * detector's first non-converged pair) through a decomposition: global ids before the store
 * changes (diag_save), local indices after (diag_load; -1 when the particle is no longer on
 * this rank, and the messages then name no particle) */
enum { NDIAG = 6 };
static void diag_ptrs(floe_world *w, int *ix[NDIAG]) {
    ix[0] = &w->wd_pair_i; ix[1] = &w->wd_pair_j; ix[2] = &w->wd_worst_i; ix[3] = &w->wd_worst_j;
    ix[4] = &w->det.first_bad_i; ix[5] = &w->det.first_bad_j;
}
static void diag_save(floe_world *w, const floe_par *P, long long g[NDIAG]) {
    int *ix[NDIAG];
    diag_ptrs(w, ix);
    for (int k = 0; k < NDIAG; k++) g[k] = gid_or(P, *ix[k]);
}
static void diag_load(floe_world *w, const floe_par *P, const long long g[NDIAG]) {
    int *ix[NDIAG];
    diag_ptrs(w, ix);
    for (int k = 0; k < NDIAG; k++) *ix[k] = -1;
    const int n = P->nrep + P->nown + P->nghost;
    for (int i = 0; i < n; i++)
        for (int k = 0; k < NDIAG; k++)
            if (g[k] >= 0 && P->gid[i] == g[k]) *ix[k] = i;
}

/* ---- contact history by global ids ----
 * A pair is evaluated on the rank that owns its anchor: the bounded particle of the pair
 * with the lower global id (a wall is never the anchor: walls are on every rank). Its
 * history travels with the anchor. Record: gid_a gid_b (list order) sub touching [image]
 * hist[nl.hs] warm[FLOE_DETECT_WARM] (the image code of j with a periodic cell: positions are
 * never wrapped, so a pair's image is the same on every rank; warm only when the list keeps
 * warm starts). */
static int hist_head(const floe_world *w) { return w->cell ? 5 : 4; }
static int hist_len(const floe_world *w) {
    return hist_head(w) + w->nl.hs + (w->nl.use_warm && w->nl.warm ? FLOE_DETECT_WARM : 0);
}

static long long anchor_of(const floe_particles *p, const long long *gid, int i, int j) {
    const int bi = isfinite(p->radius[i]), bj = isfinite(p->radius[j]);
    if (bi && bj) return gid[i] < gid[j] ? gid[i] : gid[j];
    return bi ? gid[i] : gid[j];
}

/* the kept entries (touching, or a warm start) of the list whose anchor is owned: is_mine(gid) */
static int hist_export(const floe_world *w, const long long *gid, const unsigned char *mine_by_gid, int lo, int hi,
                       double **out, int *nout) {
    const floe_neighbor_list *nl = &w->nl;
    const floe_particles *p = &w->p;
    const int m = hist_len(w), h0 = hist_head(w), use_warm = nl->use_warm && nl->warm;
    int cnt = 0;
    double *r = malloc((size_t)(nl->npairs ? nl->npairs : 1) * m * sizeof *r);
    if (!r) return FLOE_ENOMEM;
    for (int k = 0; k < nl->npairs; k++) {
        if (!(nl->touching[k] || (use_warm && isfinite(nl->warm[(size_t)k * FLOE_DETECT_WARM])))) continue;
        const int i = nl->pi[k], j = nl->pj[k];
        const long long a = anchor_of(p, gid, i, j);
        if (mine_by_gid ? !mine_by_gid[a] : 0) continue;
        if (!mine_by_gid) { /* owned: the anchor's local index in [lo, hi) */
            const int ia = gid[i] == a ? i : j;
            if (ia < lo || ia >= hi) continue;
        }
        double *e = r + (size_t)cnt++ * m;
        e[0] = (double)gid[i];
        e[1] = (double)gid[j];
        e[2] = nl->sub[k];
        e[3] = nl->touching[k];
        if (h0 > 4) e[4] = nl->img ? nl->img[k] : 0;
        memcpy(e + h0, nl->hist + (size_t)k * nl->hs, (size_t)nl->hs * sizeof *e);
        if (use_warm) memcpy(e + h0 + nl->hs, nl->warm + (size_t)k * FLOE_DETECT_WARM, FLOE_DETECT_WARM * sizeof *e);
    }
    *out = r;
    *nout = cnt;
    return FLOE_OK;
}

static int grow_int(int **a, int n) {
    int *t = realloc(*a, (size_t)(n ? n : 1) * sizeof *t);
    if (!t) return FLOE_ENOMEM;
    *a = t;
    return FLOE_OK;
}

/* the received history entries written as the list's previous pairs in the new local
 * indices, so that floe_nl_build keeps them as it keeps the history across any rebuild */
static int hist_import(floe_world *w, floe_par *P, const double *in, int nin) {
    floe_neighbor_list *nl = &w->nl;
    const int m = hist_len(w), h0 = hist_head(w), use_warm = nl->use_warm && nl->warm;
    floe_par_index ix;
    if (floe_par_index_build(P, w->p.n, &ix)) return FLOE_ENOMEM;
    if (nin > nl->cap) {
        if (grow_int(&nl->pi, nin) || grow_int(&nl->pj, nin) || grow_int(&nl->sub, nin)) {
            floe_par_index_free(&ix);
            return FLOE_ENOMEM;
        }
        nl->cap = nin;
    }
    /* a periodic cell: the images, as long as the list's other arrays (neighbor.c) */
    if (w->cell && grow_int(&nl->img, nl->cap)) {
        floe_par_index_free(&ix);
        return FLOE_ENOMEM;
    }
    double *h = realloc(nl->hist, (size_t)(nin ? nin : 1) * nl->hs * sizeof *h);
    unsigned char *t = h ? realloc(nl->touching, (size_t)(nin ? nin : 1)) : NULL;
    if (h) nl->hist = h;
    if (t) nl->touching = t;
    double *wm = NULL;
    if (h && t && use_warm) {
        wm = realloc(nl->warm, (size_t)(nin ? nin : 1) * FLOE_DETECT_WARM * sizeof *wm);
        if (wm) nl->warm = wm;
    }
    if (!h || !t || (use_warm && !wm)) { floe_par_index_free(&ix); return FLOE_ENOMEM; }
    int cnt = 0;
    for (int k = 0; k < nin; k++) {
        const double *e = in + (size_t)k * m;
        const int i = floe_par_index_find(&ix, (long long)e[0]), j = floe_par_index_find(&ix, (long long)e[1]);
        if (i < 0 || j < 0) continue; /* cannot happen for a touching pair: its partner is a ghost here */
        nl->pi[cnt] = i;
        nl->pj[cnt] = j;
        nl->sub[cnt] = (int)e[2];
        nl->touching[cnt] = (unsigned char)e[3];
        if (w->cell) nl->img[cnt] = (int)e[4];
        memcpy(nl->hist + (size_t)cnt * nl->hs, e + h0, (size_t)nl->hs * sizeof *e);
        if (use_warm) memcpy(nl->warm + (size_t)cnt * FLOE_DETECT_WARM, e + h0 + nl->hs, FLOE_DETECT_WARM * sizeof *e);
        cnt++;
    }
    floe_par_index_free(&ix);
    if (!w->cell) {
        free(nl->img);
        nl->img = NULL;
    }
    nl->npairs = cnt;
    nl->gen++; /* a new list: the threads' per-particle index is rebuilt (forces.c) */
    /* in the order a build leaves its list: the next build carries the history by its row
     * merge, not through a hash of every entry */
    return floe_nl_sort(nl, w->p.n);
}

/* the decomposition again: RCB of the owned centres, the history of the pairs whose anchor
 * leaves routed to its new owner (pend: entries exported before, at the split), migration,
 * ghosts, the neighbour list */
static int par_rebuild(floe_world *w, floe_par *P, double *pend, int npend) {
    /* Every failure is every rank's (w->err_agreed): a stage's own failure on one rank is told
     * to the others before the next collective, by an agreement (floe_par_agree) or inside the
     * collective itself (a route's counts, the ghosts' boxes), so that no rank waits for one
     * that has left (docs/parallel.md, "Errors inside a step") */
    const int m = hist_len(w), lo = P->nrep, hi = P->nrep + P->nown;
    double *recs = pend;
    int nrec = npend, rc = FLOE_OK;
    if (!recs) rc = hist_export(w, P->gid, NULL, lo, hi, &recs, &nrec);
    int *dest = malloc((size_t)(P->nown ? P->nown : 1) * sizeof *dest);
    int *hd = malloc((size_t)(nrec ? nrec : 1) * sizeof *hd);
    double *in = NULL;
    int nin = 0;
    if (!dest || !hd) rc = FLOE_ENOMEM;
    rc = floe_par_agree(P, rc);
    /* PD bodies: made whole before the migration (its own message, agreed by every rank) */
    if (!rc && (rc = floe_par_pd_sync(w, P)) != FLOE_OK) {
        free(dest); free(hd); free(recs);
        w->err_agreed = 2;
        return rc;
    }
    floe_par_index ix = {0};
    if (!rc) {
        rc = floe_par_rcb(w, P, dest);
        if (!rc) rc = floe_par_index_build(P, hi, &ix);
        if (!rc) /* each entry to its anchor's new owner: the owned particle of the pair with the
                  * lower id (walls and ghosts are not among the owned [lo, hi)) */
            for (int k = 0; k < nrec; k++) {
                const double *e = recs + (size_t)k * m;
                int f[2];
                for (int s = 0; s < 2; s++) {
                    const int a = floe_par_index_find(&ix, (long long)e[s]);
                    f[s] = a >= lo && a < hi ? a : -1;
                }
                const int an = f[0] >= 0 && f[1] >= 0 ? (P->gid[f[0]] < P->gid[f[1]] ? f[0] : f[1]) : f[0] >= 0 ? f[0] : f[1];
                hd[k] = an >= 0 ? dest[an - lo] : P->rank;
            }
        floe_par_index_free(&ix);
        rc = floe_par_agree(P, rc);
    }
    long long diag[NDIAG];
    diag_save(w, P, diag);
    if (!rc && (rc = floe_par_pd_out(w, P, dest)) != FLOE_OK) {
        free(dest); free(hd); free(recs);
        w->err_agreed = 2;
        return rc;
    }
    if (!rc) rc = floe_par_beams_out(w, P, dest); /* beam bonds (par_beams.c; agreed) */
    if (!rc) rc = floe_par_pp_out(w, P, dest);    /* the force stages' rows (par_forcing.c; agreed) */
    if (!rc) rc = floe_par_ghosts(w, P, w->nl.skin, floe_par_migrate(w, P, dest)); /* agreed */
    if (!rc) diag_load(w, P, diag);
    if (!rc) rc = floe_par_route(P, FLOE_COMM_MIGRATE, recs, hd, nrec, m, &in, &nin);
    if (!rc) rc = floe_par_agree(P, hist_import(w, P, in, nin));
    free(in); free(dest); free(hd); free(recs);
    /* a failed decomposition (out of memory; the store may be half rebuilt): every rank
     * returns it, the state is not written (w->err_agreed 2); from here on too */
    w->err_agreed = 2;
    if (rc) return floe_world_error(w, rc, "MPI decomposition failed (out of memory or Zoltan)");
    FLOE_TRY(floe_par_beams_in(w, P)); /* its own message, agreed by every rank */
    FLOE_TRY(floe_par_pp_in(w, P));    /* the same */
    FLOE_TRY(floe_par_pd_index(w, P)); /* PD bodies: their points here (before the list's exclusions) */
    if (floe_par_pd_s0_refresh(w, P)) return floe_world_error(w, FLOE_ENOMEM, "out of memory"); /* alpha: the new ghosts' s0 */
    w->nl.gid = P->gid;
    w->nl.own_hi = P->nrep + P->nown;
    w->nl.rep_hi = P->nrep;
    rc = floe_par_agree(P, floe_world_nl_build(w));
    if (rc) return floe_world_error(w, rc, "neighbour list rebuild failed (out of memory)");
    floe_par_choose_refreshed(w, P); /* the ghosts a step refreshes: those this list reads */
    w->err_agreed = 0;
    P->nl_rebuilds = w->nl.rebuilds;
    w->motion_idx_n = -1; /* the motion callbacks' particles found again (step.c motion_of) */
    /* the arrays of the whole world (at the split) or of a larger share, shrunk to this
     * rank's part (docs/parallel.md, "Memory per rank") */
    floe_world_trim(w, 0);
    P->rebuilds++;
    P->traffic.rebuilds++;
    return FLOE_OK;
}

static int refuse(floe_world *w, const char *what) {
    return floe_world_error(w, FLOE_ENOTSUP, "MPI decomposition: %s is not supported yet (docs/parallel.md)", what);
}

/* The energy watchdog's reduction (floe_par_watchdog_values): one element of the type
 * floe_par.wd_type, WD_LEN doubles: WD_SUMS summed (the ledger's 7, the conserved form's 2,
 * up to 8 PD bodies' dissipations, zeros past them), then two minima (the most negative pair
 * dissipation, the step close's agreement word). The operation takes whole elements: MPI may
 * hand it any number of them, never a piece of one (a buffer of plain doubles would let a
 * segmented algorithm split it, and the entries' roles with it) */
#define FLOE_PAR_WD_PD 8
enum { WD_SUMS = 9 + FLOE_PAR_WD_PD, WD_LEN = WD_SUMS + 2 };
static void sum_then_min(void *in, void *inout, int *len, MPI_Datatype *type) {
    (void)type;
    const double *a = in;
    double *b = inout;
    for (int e = 0; e < *len; e++, a += WD_LEN, b += WD_LEN) {
        for (int k = 0; k < WD_SUMS; k++) b[k] = a[k] + b[k];
        for (int k = WD_SUMS; k < WD_LEN; k++) b[k] = fmin(a[k], b[k]); /* (commutative, NaN too) */
    }
}

int floe_world_parallel_init(floe_world *w, const void *comm) {
    int inited = 0;
    MPI_Initialized(&inited);
    if (!inited) return floe_world_error(w, FLOE_EINVAL, "MPI decomposition: MPI_Init has not been called");
    if (w->par) return floe_world_error(w, FLOE_EINVAL, "MPI decomposition: the world is split already");
    /* prepared by the caller (floe_world_prepare lives in core/integrators, a layer above) */
    if (!w->prepared)
        return floe_world_error(w, FLOE_EINVAL, "MPI decomposition: prepare the world first (floe_world_prepare)");
    floe_particles *p = &w->p;
    char pdwhy[160];
    if (floe_par_pd_unsupported(w, pdwhy, sizeof pdwhy)) return refuse(w, pdwhy);
    for (int k = 0; k < w->nstates; k++)
        if (!floe_state_splits(w->states[k])) {
            char what[96];
            snprintf(what, sizeof what, "the user state object %s", w->states[k]->klass->name);
            return refuse(w, what);
        }
    if (w->nobs) return refuse(w, "an observer (outputs)");
    if (w->def.integrator != FLOE_VELOCITY_VERLET && w->def.integrator != FLOE_LEAPFROG && w->def.integrator != FLOE_RK2)
        return refuse(w, "a user integrator");
    /* the providers that run split (par_forcing.c): a user's only when its class declares
     * per-particle forces (its loops and state are otherwise its own) */
    for (int k = 0; k < w->nprov + w->nuprov; k++) {
        const floe_provider *pv = k < w->nprov ? w->prov[k] : w->uprov[k - w->nprov];
        if (!floe_par_provider_supported(w, pv)) {
            char what[224];
            if (floe_provider_is_user(w, pv))
                snprintf(what, sizeof what, "the force provider %s (a user's provider runs split when its class, "
                         "version 2, declares .splits = FLOE_PROVIDER_PER_PARTICLE: floe_provider.h)", pv->klass->name);
            else
                snprintf(what, sizeof what, "the force provider %s", pv->klass->name);
            return refuse(w, what);
        }
    }
    /* the communicator first (collective), then the memory agreed on it: a rank that failed
     * alone would leave the others waiting */
    MPI_Comm dup;
    MPI_Comm_dup(comm ? *(const MPI_Comm *)comm : MPI_COMM_WORLD, &dup);
    floe_par *P = calloc(1, sizeof *P);
    int nomem = !P, any_nomem = nomem;
    MPI_Allreduce(&nomem, &any_nomem, 1, MPI_INT, MPI_MAX, dup);
    if (any_nomem) {
        free(P);
        MPI_Comm_free(&dup);
        return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    P->comm = dup;
    MPI_Op_create(sum_then_min, 1, &P->sum_min); /* local calls */
    MPI_Type_contiguous(WD_LEN, MPI_DOUBLE, &P->wd_type);
    MPI_Type_commit(&P->wd_type);
    P->have_sum_min = 1;
    MPI_Comm_rank(P->comm, &P->rank);
    MPI_Comm_size(P->comm, &P->size);
    const int S = P->size, n = p->n;
    P->scount = malloc((size_t)19 * S * sizeof *P->scount);
    P->boxes = malloc((size_t)8 * S * sizeof *P->boxes);
    P->rcb_sum = malloc(((size_t)4 * S + 2) * sizeof *P->rcb_sum);
    if (P->scount) {
        P->sdispl = P->scount + S; P->rcount = P->scount + 2 * S; P->rdispl = P->scount + 3 * S;
        P->gcnt = P->scount + 4 * S;
        P->gc = P->scount + 6 * S;
        P->rt = P->scount + 10 * S;
        P->fcnt = P->scount + 15 * S;
    }
    P->fgen = -1;
    /* the same world on every rank? (count and a checksum of the positions) */
    double chk[2] = {n, 0}, chk0[2];
    for (int i = 0; i < n; i++)
        if (isfinite(p->radius[i])) chk[1] += p->x[3 * i] + 2 * p->x[3 * i + 1] + 3 * p->x[3 * i + 2] + p->radius[i];
    memcpy(chk0, chk, sizeof chk);
    MPI_Bcast(chk0, 2, MPI_DOUBLE, 0, P->comm);
    int same = chk0[0] == chk[0] && chk0[1] == chk[1], all_same;
    MPI_Allreduce(&same, &all_same, 1, MPI_INT, MPI_LAND, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_REDUCE, sizeof chk0);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof same);
    if (!all_same) {
        floe_par_free(P);
        return floe_world_error(w, FLOE_EINVAL, "MPI decomposition: the ranks do not hold the same world");
    }
    /* global ids = index; walls first, then this rank's block of the bounded particles */
    int nw = 0, nb = 0;
    for (int i = 0; i < n; i++) nw += !isfinite(p->radius[i]);
    P->any_nonround = 0; /* the ranks hold the same world: the same answer everywhere */
    for (int i = 0; i < n; i++) P->any_nonround |= isfinite(p->radius[i]) && p->kind[i] != FLOE_GEOM_SPHERE;
    const int bonds = w->beams && floe_beam_set_count(w->beams) > 0;
    if (bonds) P->any_nonround = 1;
    P->refresh_all = bonds || w->npd > 0; /* (a user's provider may not rebuild the list: forces.c) */
    nb = n - nw;
    const int k0 = (int)((long long)nb * P->rank / S), k1 = (int)((long long)nb * (P->rank + 1) / S);
    unsigned char *mine = calloc((size_t)(n ? n : 1), 1);
    int *newidx = malloc((size_t)(n ? n : 1) * sizeof *newidx);
    long long *gid0 = malloc((size_t)(n ? n : 1) * sizeof *gid0);
    double *recs = NULL, *buf = malloc((size_t)(n ? n : 1) * FLOE_PAR_REC * sizeof *buf);
    P->gid = malloc((size_t)(n ? n : 1) * sizeof *P->gid);
    P->gid_cap = n;
    double **fresh = NULL; /* the force stages' per-particle rows, this rank's part (par_forcing.c) */
    int nrec = 0, rc = !P->scount || !P->boxes || !P->rcb_sum || !mine || !newidx || !gid0 || !buf || !P->gid ? FLOE_ENOMEM : FLOE_OK;
    if (!rc) {
        int kb = 0;
        for (int i = 0; i < n; i++) {
            gid0[i] = i;
            if (isfinite(p->radius[i])) { mine[i] = kb >= k0 && kb < k1; kb++; }
        }
        rc = hist_export(w, gid0, mine, 0, 0, &recs, &nrec);
        if (!rc) rc = floe_par_beams_split(w, P, mine); /* beam bonds: those anchored here */
        if (!rc) rc = floe_par_pd_split_reach(w, P);    /* PD bonds: the halo's reach */
    }
    int a = 0;
    if (!rc) {
        for (int i = 0; i < n; i++) newidx[i] = -1;
        for (int i = 0; i < n; i++)
            if (!isfinite(p->radius[i])) { newidx[i] = a; floe_par_pack(p, i, i, buf + (size_t)a++ * FLOE_PAR_REC); }
        for (int i = 0; i < n; i++)
            if (mine[i]) { newidx[i] = a; floe_par_pack(p, i, i, buf + (size_t)a++ * FLOE_PAR_REC); }
        rc = floe_par_pp_split_alloc(w, a, &fresh);
    }
    /* every rank, before the store changes and before the decomposition's collectives: a
     * failed split leaves the world as it was */
    rc = floe_par_agree(P, rc);
    floe_par_pp_split(w, fresh, newidx, n, a, !rc);
    if (!rc) {
        P->ntotal = n;
        P->nrep = nw;
        P->nown = k1 - k0;
        for (int k = 0; k < a; k++) floe_par_unpack(p, k, buf + (size_t)k * FLOE_PAR_REC, P->gid + k);
        p->n = a;
        floe_servo_renumber(w, newidx);
        for (int k = 0; k < w->nmotions; k++) {
            const int i = w->motions[k].particle;
            if (i >= 0 && i < n) w->motions[k].particle = newidx[i];
        }
        w->motion_idx_n = -1;
    }
    free(mine); free(newidx); free(gid0); free(buf);
    if (rc) {
        free(recs);
        floe_par_free(P);
        return floe_world_error(w, rc, "out of memory");
    }
    w->par = P;
    w->par_free = floe_par_free;
    FLOE_TRY(par_rebuild(w, P, recs, nrec));
    /* the ledger: the values at prepare (the whole world) stay on rank 0; the others start
     * from nothing but their own kinetic energy */
    if (P->rank != 0) {
        memset(&w->energy, 0, sizeof w->energy);
        w->wd_shadow = w->wd_shadow0 = 0;
        w->elastic_contact = w->elastic_pd = 0;
        /* the PD bodies' ledger terms: each rank books its share of the bonds from here */
        for (int b = 0; b < w->npd; b++) {
            w->pd_eold[b] = 0;
            if (b < w->pd_diss_n) w->pd_diss[b] = 0;
        }
        /* a wall's force is the sum of the ranks' parts (the boundary work of a kinematic
         * wall uses it at the next step): the whole of it stays on rank 0 */
        for (int i = 0; i < P->nrep; i++) {
            memset(w->p.f + 3 * i, 0, 3 * sizeof(double));
            memset(w->p.t + 3 * i, 0, 3 * sizeof(double));
        }
        /* a periodic cell's sums over the contacts (the whole world's at prepare): the servo's
         * first step sums them over the ranks (floe_par_cell_stress) */
        if (w->cell) {
            memset(w->cell->virial, 0, sizeof w->cell->virial);
            memset(w->cell->pd_virial, 0, sizeof w->cell->pd_virial);
            memset(w->cell->kdiag, 0, sizeof w->cell->kdiag);
        }
    }
    return floe_par_servo_totals(w); /* the servos' measures of the whole world, as at prepare */
}

/* v[0 .. n) reduced in place over the ranks by op (a split world; counted as reduce traffic) */
static void reduce_in_place(const floe_world *w, double *v, int n, MPI_Op op) {
    if (!w->par || n <= 0) return;
    MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, op, w->par->comm);
    floe_par_count_allreduce(w->par, FLOE_COMM_REDUCE, (long long)n * sizeof *v);
}

void floe_par_max(floe_world *w, double *v, int n) { reduce_in_place(w, v, n, MPI_MAX); }

int floe_world_parallel_rebuild(floe_world *w) {
    if (!w->par) return FLOE_OK;
    return par_rebuild(w, w->par, NULL, 0);
}

/* this rank's word in an agreement (agree_error_kind): the size when it did not fail, its
 * rank less the size for out of memory (first), else its rank */
static int agree_word(const floe_par *P, int rc) { return !rc ? P->size : rc == FLOE_ENOMEM ? P->rank - P->size : P->rank; }

/* every rank, after a reduction found that rank `first` (the lowest) failed with rc there:
 * that rank's code and message (particles named by their global ids, as one process names
 * them: floe_world_pid) become every rank's, w->err_agreed set; returns the code */
static int error_from(floe_world *w, floe_par *P, int first, int rc, int kind) {
    struct { int code; char msg[sizeof w->err]; } m;
    if (P->rank == first) {
        m.code = rc;
        snprintf(m.msg, sizeof m.msg, "%s", w->err);
    }
    MPI_Bcast(&m, (int)sizeof m, MPI_BYTE, first, P->comm);
    if (P->rank == first) floe_par_count(P, kind, sizeof m, 1); /* (as floe_par_count_bcast) */
    floe_world_error(w, m.code, "%s", m.msg);
    /* out of memory: the failing rank may have stopped short of the others (a step's work
     * skipped on its way to the agreement): the state is not written */
    w->err_agreed = m.code == FLOE_ENOMEM ? 2 : 1;
    return m.code;
}

int floe_par_refresh(floe_world *w, double maxd2, int have_xb, const floe_par_carry *carry, int rc, int *flag,
                     int *told) {
    floe_par *P = w->par;
    *told = 0;
    /* a periodic cell: the test that discounts the cell's affine map (step.c rebuild_if_needed) */
    int need = w->cell ? floe_nl_needs_rebuild_cell(&w->nl, &w->p)
                       : floe_nl_needs_rebuild_after_drift(&w->nl, &w->p, maxd2, !have_xb || w->nstates > 0);
    /* a bond broke and the list was rebuilt in the force stage (forces.c): the ghosts were
     * chosen for the list of the last decomposition, so decompose again */
    if (w->beams && w->nl.rebuilds != P->nl_rebuilds) need = 1;
    if (w->law_gen != w->nl_law_gen) need = 1; /* a law set since the build (step.c rebuild_if_needed) */
    /* rows that travel with their particles: registered for this decomposition only (every
     * rank is here with the same width), their memory agreed with the need */
    double **rows = carry ? carry->rows : NULL;
    const int m = carry ? carry->m : 0;
    if (!rc && carry && floe_world_pp_attach(w, rows, carry->n, m))
        rc = floe_world_error(w, FLOE_ENOMEM, "out of memory");
    /* the need, and this rank's failure since the last agreement, in one reduction: the
     * failing rank whose error is every rank's, an out-of-memory one first (S - rank + S),
     * else the lowest (S - rank) */
    const int S = P->size;
    int mine[3] = {need, !rc ? 0 : rc == FLOE_ENOMEM ? 2 * S - P->rank : S - P->rank, flag && *flag}, all[3];
    MPI_Allreduce(mine, all, 3, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof mine);
    if (flag) *flag = all[2];
    if (all[1]) {
        if (carry) floe_world_pp_detach(w, rows);
        *told = 1;
        return error_from(w, P, all[1] > S ? 2 * S - all[1] : S - all[1], rc, FLOE_COMM_REDUCE);
    }
    if (!carry) return all[0] ? par_rebuild(w, P, NULL, 0) : floe_par_ghost_update(w);
    rc = all[0] ? par_rebuild(w, P, NULL, 0) : floe_par_ghost_update(w);
    floe_world_pp_detach(w, rows);
    if (rc || !all[0]) return rc;
    /* an RK2 step's end keeps its midpoint probe's accelerations for the linear dashpots
     * (forces.c dashpot_accelerations): the owned particles' from the rows they brought, the
     * new ghosts' from their owners. Decided from what every rank holds alike (dash_on is 0
     * on a rank without particles) */
    if (carry->dash >= 0 && w->dash_keep && floe_par_laws_dashpot(w)) {
        const int n = w->p.n, own_hi = w->nl.own_hi, d = carry->dash;
        /* the forward below is collective: the memory agreed first */
        int bad = floe_world_dash_reserve(w) ? 1 : 0, any_bad = 0;
        MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_MAX, P->comm);
        floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof bad);
        if (any_bad) {
            w->err_agreed = 2; /* (out of memory, as error_from) */
            return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        }
        for (int i = 0; i < own_hi; i++) memcpy(w->dash_a + 3 * (size_t)i, *rows + (size_t)i * m + d, 3 * sizeof(double));
        if (floe_par_forward_rows(P, w->dash_a, 3)) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        w->dash_on = n > 0;
    }
    return FLOE_OK;
}

int floe_par_ghost_update(floe_world *w) {
    floe_par *P = w->par;
    int rc = floe_par_forward_comm(w, P, 0);
    if (!rc) rc = floe_par_pd_s0_refresh(w, P); /* PD with alpha: the ghosts' s0 */
    return rc ? floe_world_error(w, rc, "out of memory") : FLOE_OK;
}

/* floe_par_agree_error, its reduction counted as kind */
static int agree_error_kind(floe_world *w, int rc, int kind) {
    floe_par *P = w->par;
    if (!P) return rc;
    /* the failing rank whose error is every rank's: an out-of-memory one first (rank - S < 0:
     * a rank that stopped short of the others; the state is not whole), else the lowest */
    const int S = P->size;
    int mine = agree_word(P, rc), first = mine;
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, P->comm);
    floe_par_count_allreduce(P, kind, sizeof mine);
    return first == S ? FLOE_OK : error_from(w, P, first < 0 ? first + S : first, rc, kind);
}

int floe_par_agree_error(floe_world *w, int rc) { return agree_error_kind(w, rc, FLOE_COMM_REDUCE); }

double floe_par_clock(void) { return MPI_Wtime(); }
void floe_par_force_time(floe_world *w, double seconds) {
    w->par->busy += seconds;
    w->par->traffic.force_seconds += seconds;
}

int floe_world_parallel_set_balance(floe_world *w, floe_balance mode) {
    const int rc = balance_check(w, mode);
    if (rc || !w->par) return rc;
    if (!floe_par_set_balance(w->par, mode)) return FLOE_OK;
    w->err_agreed = 1; /* every rank's (the world is as it was) */
    return floe_world_error(w, FLOE_ENOMEM, "out of memory");
}

int floe_par_reverse(floe_world *w) {
    int rc = floe_par_reverse_comm(w, w->par);
    return rc ? floe_world_error(w, rc, "out of memory") : FLOE_OK;
}

int floe_par_cell_stress(floe_world *w, double sigma[9], int *given) {
    floe_cell_state *c = w->cell;
    floe_par *P = w->par;
    *given = 0;
    if (!c || !c->want_kdiag) return FLOE_OK; /* only the servo reads it at each step */
    /* this rank's contacts' virial (the contacts it evaluates), its owned free particles'
     * sum of m v (x) v (ghosts are stored fixed), the servo's stiffness sums, whether its
     * last evaluation set them */
    double v[37], s[37];
    memcpy(v, c->virial, 9 * sizeof *v);
    memcpy(v + 9, c->pd_virial, 9 * sizeof *v);
    memcpy(v + 18, c->kdiag, 9 * sizeof *v);
    memset(v + 27, 0, 9 * sizeof *v);
    floe_cell_mvv(&w->p, P->nrep, P->nrep + P->nown, v + 27);
    v[36] = c->valid ? 0 : 1;
    MPI_Allreduce(v, s, 37, MPI_DOUBLE, MPI_SUM, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof v);
    memcpy(c->kdiag, s + 18, sizeof c->kdiag); /* the servo's stiffness: the whole cell's */
    /* floe_world_cell_stress's: an evaluation missing on some rank gives 0, as there */
    if (s[36] > 0) memset(sigma, 0, 9 * sizeof *sigma);
    else floe_cell_stress_of(s, s + 9, s + 27, floe_world_cell_volume(w), sigma);
    *given = 1;
    return FLOE_OK;
}


static void energy_pack(const floe_energy *e, double *v) {
    v[0] = e->kinetic_trans; v[1] = e->kinetic_rot; v[2] = e->elastic; v[3] = e->work_body;
    v[4] = e->work_boundary; v[5] = e->dissipated; v[6] = e->initial;
}
static void energy_unpack(floe_energy *e, const double *v) {
    e->kinetic_trans = v[0]; e->kinetic_rot = v[1]; e->elastic = v[2]; e->work_body = v[3];
    e->work_boundary = v[4]; e->dissipated = v[5]; e->initial = v[6];
}


int floe_par_watchdog_values(floe_world *w, floe_energy *e, double *shadow, double *shadow0, double *pair_min,
                             double *pdd, int npd, const int *close_rc) {
    floe_par *P = w->par;
    double v[WD_LEN] = {0}, s[WD_LEN];
    energy_pack(e, v);
    v[7] = *shadow;
    v[8] = *shadow0;
    /* the PD bodies' dissipation with the rest (a scene with more bodies: a second sum) */
    const int nin = npd <= FLOE_PAR_WD_PD ? npd : 0, n = WD_LEN;
    for (int k = 0; k < nin; k++) v[9 + k] = pdd[k];
    /* the minima last: the pair dissipation, the close's word (an int, exact as a double) */
    v[n - 2] = *pair_min;
    v[n - 1] = close_rc ? agree_word(P, *close_rc) : P->size;
    MPI_Allreduce(v, s, 1, P->wd_type, P->sum_min, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, n * (long long)sizeof(double));
    energy_unpack(e, s);
    *shadow = s[7];
    *shadow0 = s[8];
    for (int k = 0; k < nin; k++) pdd[k] = s[9 + k];
    *pair_min = s[n - 2];
    const int first = (int)s[n - 1];
    if (first != P->size) /* the close failed on some rank: its error, every rank's */
        return error_from(w, P, first < 0 ? first + P->size : first, close_rc ? *close_rc : FLOE_OK, FLOE_COMM_REDUCE);
    if (npd > nin) {
        MPI_Allreduce(MPI_IN_PLACE, pdd, npd, MPI_DOUBLE, MPI_SUM, P->comm);
        floe_par_count_allreduce(P, FLOE_COMM_REDUCE, npd * (long long)sizeof(double));
    }
    return FLOE_OK;
}

double floe_par_pick(floe_world *w, double key, char *a, int alen, char *b, int blen) {
    floe_par *P = w->par;
    if (!P) return key;
    struct { double v; int r; } mine = {key == key ? key : -INFINITY, P->rank}, top;
    MPI_Allreduce(&mine, &top, 1, MPI_DOUBLE_INT, MPI_MAXLOC, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof mine);
    a[alen - 1] = 0;
    b[blen - 1] = 0;
    MPI_Bcast(a, alen, MPI_CHAR, top.r, P->comm);
    MPI_Bcast(b, blen, MPI_CHAR, top.r, P->comm);
    if (P->rank == top.r) floe_par_count(P, FLOE_COMM_REDUCE, (long long)alen + blen, 2); /* (as floe_par_count_bcast) */
    return top.v;
}

/* the ledger summed over the ranks, counted as kind */
static void energy_sum(const floe_world *w, floe_energy *out, int kind) {
    *out = w->energy;
    if (!w->par) return;
    double v[7], s[7];
    energy_pack(&w->energy, v);
    MPI_Allreduce(v, s, 7, MPI_DOUBLE, MPI_SUM, w->par->comm);
    floe_par_count_allreduce(w->par, kind, sizeof v);
    energy_unpack(out, s);
}

int floe_world_parallel_energy(const floe_world *w, floe_energy *out) {
    energy_sum(w, out, FLOE_COMM_REDUCE);
    return FLOE_OK;
}

int floe_world_parallel_sum(const floe_world *w, double *v, int n) {
    reduce_in_place(w, v, n, MPI_SUM);
    return FLOE_OK;
}

int floe_world_parallel_gather(const floe_world *w, double *x, double *v, int N) {
    floe_par *P = w->par;
    if (!P) {
        for (int i = 0; i < w->p.n && i < N; i++) {
            if (x) memcpy(x + 3 * i, w->p.x + 3 * i, 3 * sizeof *x);
            if (v) memcpy(v + 3 * i, w->p.v + 3 * i, 3 * sizeof *v);
        }
        return FLOE_OK;
    }
    const int m = 7, lo = P->nrep, no = P->nown;
    double *sb = malloc((size_t)(no ? no : 1) * m * sizeof *sb);
    int bad = !sb, anybad;
    MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_LOR, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (anybad) { free(sb); return FLOE_ENOMEM; }
    for (int k = 0; k < no; k++) {
        double *r = sb + (size_t)k * m;
        r[0] = (double)P->gid[lo + k];
        memcpy(r + 1, w->p.x + 3 * (lo + k), 3 * sizeof *r);
        memcpy(r + 4, w->p.v + 3 * (lo + k), 3 * sizeof *r);
    }
    double *rb;
    int tot;
    const int rc = floe_par_gather_root(P, FLOE_COMM_OUTPUT, sb, no * m, &rb, &tot);
    if (P->rank == 0 && rb)
        for (int k = 0; k < tot / m; k++) {
            const double *r = rb + (size_t)k * m;
            const long long g = (long long)r[0];
            if (g < 0 || g >= N) continue;
            if (x) memcpy(x + 3 * g, r + 1, 3 * sizeof *x);
            if (v) memcpy(v + 3 * g, r + 4, 3 * sizeof *v);
        }
    free(sb); free(rb);
    return rc;
}

int floe_world_parallel_comm(const floe_world *w, floe_comm_stats *out) {
    if (w->par) *out = w->par->traffic;
    else memset(out, 0, sizeof *out);
    return FLOE_OK;
}

int floe_world_parallel_comm_reset(floe_world *w) {
    if (w->par) memset(&w->par->traffic, 0, sizeof w->par->traffic);
    return FLOE_OK;
}

int floe_world_parallel_rank(const floe_world *w, int *rank, int *size) {
    *rank = w->par ? w->par->rank : 0;
    *size = w->par ? w->par->size : 1;
    return FLOE_OK;
}

int floe_world_parallel_counts(const floe_world *w, int *owned, int *ghosts) {
    if (!w->par) {
        int nb = 0;
        for (int i = 0; i < w->p.n; i++) nb += isfinite(w->p.radius[i]) != 0;
        *owned = nb;
        *ghosts = 0;
        return FLOE_OK;
    }
    *owned = w->par->nown;
    *ghosts = w->par->nghost;
    return FLOE_OK;
}

long long floe_world_parallel_gid(const floe_world *w, int i) {
    if (i < 0 || i >= w->p.n) return -1;
    return w->par ? w->par->gid[i] : i;
}

int floe_world_parallel_is_owned(const floe_world *w, int i) {
    return !w->par || i < w->par->nrep + w->par->nown;
}

/* ---- outputs through the mirror (rank 0) ---- */


static int mirror_reads_contacts(const floe_world *M) {
    for (int k = 0; k < M->nobs; k++)
        if (M->obs[k]->klass->needs_contacts) return 1;
    return 0;
}

/* an output of M that reads contacts is due after the next step (the clock of step.c's
 * advance_clock) */
static int contacts_due_next(const floe_world *w, const floe_world *M) {
    const long step = w->step + 1;
    /* adaptive steps: the next step is at most dt_next (the end of the run, a rejection shorten
     * it), so an output this time does not reach is not due */
    const double time = w->def.adaptive ? w->time + w->dt_next : w->t0 + (double)(step - w->step0) * w->dt;
    for (int k = 0; k < M->nobs; k++) {
        const floe_observer *o = M->obs[k];
        if (!o->klass->needs_contacts) continue;
        if (o->period_steps > 0) {
            if (step % o->period_steps == 0) return 1;
        } else if (o->period_time > 0) {
            /* its next time after this step's observation (called after this, it advances
             * next_time when due now, as observers_call does) */
            double nt = o->next_time;
            if (w->time >= nt - 1e-9 * w->dt)
                while (nt <= w->time + 1e-9 * w->dt) nt += o->period_time;
            if (time >= nt - 1e-9 * w->dt) return 1;
        } else return 1;
    }
    return 0;
}

static int split_requests(floe_world *w, floe_par *P);

int floe_world_parallel_outputs(floe_world *w, floe_world *mirror) {
    floe_par *P = w->par;
    if (!P) return floe_world_error(w, FLOE_EINVAL, "MPI outputs: the world is not split");
    int bad = 0;
    if (P->rank == 0 && mirror) {
        if (mirror->p.n != P->ntotal) bad = 1;
        if (!bad && !mirror->prepared) bad = 3;
    }
    int any;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (any == 1) return floe_world_error(w, FLOE_EINVAL, "MPI outputs: the mirror does not hold the split world's particles");
    if (any == 3) return floe_world_error(w, FLOE_EINVAL, "MPI outputs: prepare the mirror first (floe_world_prepare)");
    P->mirror = P->rank == 0 ? mirror : NULL;
    /* the mirror is never stepped: its list's entries and their history (the whole world's,
     * built at its prepare, stale from the first step on) are dropped; a checkpoint's collect
     * fills them whole
     * (floe_world_parallel_collect), the outputs read the gathered contacts */
    if (P->mirror && !P->mirror->par) {
        floe_nl_drop_entries(&P->mirror->nl);
        floe_world_trim(P->mirror, 1);
    }
    /* rank 0's word: whether it has a mirror (bit 0), whether the mirror has outputs that read
     * contacts (bit 1) and whether one is due at the next step (bit 2): every rank then
     * records its contacts at the steps they are read (contacts_wanted) */
    int word = 0;
    if (P->mirror) word = 1 | (mirror_reads_contacts(P->mirror) ? 2 : 0);
    if (word & 2 && contacts_due_next(w, P->mirror)) word |= 4;
    for (int k = 0; P->mirror && k < P->mirror->nobs; k++)
        if (observer_reads_orientation(P->mirror->obs[k], P->mirror)) word |= 8; /* the split world integrates them */
    MPI_Bcast(&word, 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof word);
    if (!(word & 1)) P->mirror = NULL;
    P->has_mirror = word & 1; /* every rank knows it from now on (floe_par_observe) */
    w->par_contacts = (word & 2 ? 1 : 0) | (word & 4 ? 2 : 0);
    if (word & 8) {
        w->orient_extra = 1;
        orientation_refresh(w);
    }
    return split_requests(w, P);
}

/* the contacts of the ranks' last evaluation, by global ids, into the mirror M (rank 0) in
 * the order of the serial list (pairs by (gid_i, gid_j), the records of a pair in the
 * evaluating rank's order: each pair is evaluated by one rank); M's contacts are marked
 * unrecorded when a rank has none (not recorded at this evaluation, as a serial world's) */
enum { CREC = 20 }; /* gid_i gid_j seq point3 n3 depth force3 fn energy branch3 r_eff m_eff */

typedef struct { double g[3]; } crec_key; /* a record's first three doubles: its sort key */

static int crec_cmp(const void *a, const void *b) {
    const double *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k]) return x[k] < y[k] ? -1 : 1;
    return 0;
}

static int contacts_gather(floe_world *w, floe_par *P) {
    const int nc = w->contacts_valid ? w->ncontacts : 0;
    /* a rank's records above INT_MAX doubles cannot be sent (MPI counts): out of memory */
    double *sb = (long long)nc * CREC > 0x7fffffff ? NULL : malloc((size_t)(nc ? nc : 1) * CREC * sizeof *sb);
    crec_key *key = sb ? malloc((size_t)(nc ? nc : 1) * sizeof *key) : NULL;
    int flags[2] = {!key, !w->contacts_valid}, any[2];
    MPI_Allreduce(flags, any, 2, MPI_INT, MPI_LOR, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof flags);
    floe_world *M = P->mirror;
    if (M) M->contacts_valid = 0;
    if (any[0] || any[1]) { free(sb); free(key); return any[0] ? FLOE_ENOMEM : FLOE_OK; }
    /* each rank's records in the serial order (their keys sorted here, in parallel), so that
     * rank 0 merges the ranks' runs instead of sorting every record (20 doubles each) */
    for (int k = 0; k < nc; k++) {
        key[k].g[0] = (double)gid_or(P, w->contacts[k].i);
        key[k].g[1] = (double)gid_or(P, w->contacts[k].j);
        key[k].g[2] = k;
    }
    qsort(key, (size_t)nc, sizeof *key, crec_cmp);
    for (int q = 0; q < nc; q++) {
        const int k = (int)key[q].g[2];
        const floe_contact_rec *c = &w->contacts[k];
        double *r = sb + (size_t)q * CREC;
        memcpy(r, key[q].g, 3 * sizeof *r);
        memcpy(r + 3, c->point, 3 * sizeof *r);
        memcpy(r + 6, c->n, 3 * sizeof *r);
        r[9] = c->depth;
        memcpy(r + 10, c->force, 3 * sizeof *r);
        r[13] = c->fn;
        r[14] = c->energy;
        memcpy(r + 15, c->branch, 3 * sizeof *r);
        r[18] = c->r_eff;
        r[19] = c->m_eff;
    }
    free(key);
    double *rb;
    int tot;
    int rc = floe_par_gather_root(P, FLOE_COMM_OUTPUT, sb, nc * CREC, &rb, &tot);
    const int n = tot / CREC;
    if (P->rank == 0 && rb && M) {
        if (n > M->contacts_cap) {
            floe_contact_rec *nb = realloc(M->contacts, (size_t)n * sizeof *nb);
            if (!nb) rc = FLOE_ENOMEM;
            else { M->contacts = nb; M->contacts_cap = n; }
        }
        /* the ranks' runs merged: the smallest head taken each time (a scan of the heads;
         * many ranks: the runs concatenated and sorted whole) */
        const int S = P->size, scan = S <= 16;
        int head[16], end[16];
        for (int r = 0; scan && r < S; r++) {
            head[r] = P->gcnt[S + r] / CREC;
            end[r] = head[r] + P->gcnt[r] / CREC;
        }
        if (!rc && !scan) qsort(rb, (size_t)n, CREC * sizeof *rb, crec_cmp);
        if (!rc) {
            for (int k = 0; k < n; k++) {
                int at = k;
                if (scan) {
                    int best = -1;
                    for (int r = 0; r < S; r++)
                        if (head[r] < end[r] &&
                            (best < 0 || crec_cmp(rb + (size_t)head[r] * CREC, rb + (size_t)head[best] * CREC) < 0))
                            best = r;
                    at = head[best]++;
                }
                const double *r = rb + (size_t)at * CREC;
                floe_contact_rec *c = &M->contacts[k];
                c->i = (int)r[0];
                c->j = (int)r[1];
                memcpy(c->point, r + 3, 3 * sizeof *r);
                memcpy(c->n, r + 6, 3 * sizeof *r);
                c->depth = r[9];
                memcpy(c->force, r + 10, 3 * sizeof *r);
                c->fn = r[13];
                c->energy = r[14];
                memcpy(c->branch, r + 15, 3 * sizeof *r);
                c->r_eff = r[18];
                c->m_eff = r[19];
            }
            M->ncontacts = n;
            M->contacts_valid = 1;
        }
    }
    free(sb); free(rb);
    /* rank 0 alone may have failed (its copy): every rank returns the same */
    int all;
    MPI_Allreduce(&rc, &all, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof rc);
    return all;
}

/* the mirror's clock and cell (rank 0) */
static void mirror_clock(const floe_world *w, floe_world *M) {
    M->time = w->time;
    M->step = w->step;
    M->dt = w->dt;
    if (w->cell && M->cell) *M->cell = *w->cell; /* its vectors (the outputs' volume, the wrap) */
}

/* the state objects' values into the unsplit world M (rank 0: the mirror, or the world a
 * checkpoint collects into), before the particles' state is unpacked there: every rank keeps
 * and advances every state object alike (state.c), so rank 0's are the run's. A growing
 * radius sets M's geometry, radius and growth rate (and with its mass scales M's mass, which
 * the split world scaled step by step: the same within round-off); M's ledger is kept */
static int mirror_states(const floe_world *w, floe_world *M) {
    const int ns = w->nstates < M->nstates ? w->nstates : M->nstates;
    const floe_energy ledger = M->energy; /* a set books work (a grown mass): the run's is booked */
    for (int k = 0; k < ns; k++) {
        floe_state *s = w->states[k], *t = M->states[k];
        const size_t m = s->klass->size(s);
        if (t->klass != s->klass || t->klass->size(t) != m) continue;
        double buf[16], *y = m <= 16 ? buf : malloc(m * sizeof *y);
        if (!y) return FLOE_ENOMEM;
        s->klass->get(s, y);
        const int rc = t->klass->set(t, M, y);
        if (y != buf) free(y);
        if (rc) return rc;
    }
    M->energy = ledger;
    return FLOE_OK;
}

/* the owned particles' state by global id into the mirror (rank 0), the walls' forces summed */
static int mirror_gather(floe_world *w, floe_par *P, int contacts) {
    const int m = 1 + FLOE_PAR_FWD, lo = P->nrep, no = P->nown;
    double *sb = malloc((size_t)(no ? no : 1) * m * sizeof *sb);
    double *wf = malloc((size_t)(P->nrep ? P->nrep : 1) * 6 * sizeof *wf);
    int bad = !sb || !wf, anybad;
    MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_LOR, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (anybad) { free(sb); free(wf); return FLOE_ENOMEM; }
    const floe_particles *p = &w->p;
    for (int k = 0; k < no; k++) {
        const int i = lo + k;
        double *r = sb + (size_t)k * m;
        r[0] = (double)P->gid[i];
        floe_par_pack_state(p, i, r + 1);
    }
    for (int i = 0; i < P->nrep; i++) {
        memcpy(wf + 6 * i, p->f + 3 * i, 3 * sizeof *wf);
        memcpy(wf + 6 * i + 3, p->t + 3 * i, 3 * sizeof *wf);
    }
    if (P->nrep) MPI_Reduce(P->rank == 0 ? MPI_IN_PLACE : wf, wf, 6 * P->nrep, MPI_DOUBLE, MPI_SUM, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, 6LL * P->nrep * sizeof *wf);
    double *rb;
    int tot;
    const int grc = floe_par_gather_root(P, FLOE_COMM_OUTPUT, sb, no * m, &rb, &tot);
    floe_world *M = P->mirror;
    int src = 0;
    if (P->rank == 0 && rb && M) {
        src = mirror_states(w, M);
        floe_particles *q = &M->p;
        for (int k = 0; k < tot / m; k++) {
            const double *r = rb + (size_t)k * m;
            const long long g = (long long)r[0];
            if (g < 0 || g >= q->n) continue;
            floe_par_unpack_state(q, (int)g, r + 1);
        }
        for (int i = 0; i < P->nrep; i++) {
            const long long g = P->gid[i];
            memcpy(q->x + 3 * g, p->x + 3 * i, 3 * sizeof(double)); /* a kinematic wall moves */
            memcpy(q->v + 3 * g, p->v + 3 * i, 3 * sizeof(double));
            memcpy(q->q + 4 * g, p->q + 4 * i, 4 * sizeof(double));
            memcpy(q->f + 3 * g, wf + 6 * i, 3 * sizeof(double));
            memcpy(q->t + 3 * g, wf + 6 * i + 3, 3 * sizeof(double));
        }
        mirror_clock(w, M);
    }
    free(sb); free(wf); free(rb);
    if (grc) return grc;
    /* the contacts, when the mirror has outputs that read them (stress, contacts, force
     * chains, coast load) */
    if (contacts && w->par_contacts & 1) FLOE_TRY(contacts_gather(w, P));
    /* the beam bonds' state (broken flags, stresses: fracture_events, floe_sizes) */
    FLOE_TRY(floe_par_beams_gather(w, P, P->rank == 0 ? P->mirror : NULL));
    /* the PD bodies' (broken flags: damage, fracture events) */
    FLOE_TRY(floe_par_pd_gather(w, P, P->rank == 0 ? P->mirror : NULL));
    /* a state object that could not be set on the mirror (rank 0 only): after the
     * collectives above, which every rank reaches alike */
    return src ? floe_world_error(w, src, "MPI outputs: a state object could not be set on the mirror") : FLOE_OK;
}

/* ---- outputs reduced over the ranks (docs/parallel.md, "Outputs reduced over the ranks") ---- */

/* o's split kind (floe_observer_class.split_request; 0: gathered) */
static int split_kind(const floe_observer *o, floe_split_request *rq) {
    memset(rq, 0, sizeof *rq);
    if (o->klass->version < 4 || !o->klass->split_request || o->klass->split_request(o, rq) != FLOE_OK) return 0;
    switch (rq->kind) {
    case FLOE_SPLIT_CLOCK: return rq->kind;
    case FLOE_SPLIT_PARTICLES: return rq->nids >= 0 && (rq->ids || !rq->nids) ? rq->kind : 0;
    case FLOE_SPLIT_COLLECTION: /* its sums read the ranks' contacts: recorded only for a class that needs them */
        return o->klass->observe_sums && o->klass->needs_contacts && rq->group >= -1 ? rq->kind : 0;
    }
    return 0;
}

/* rank 0's mirror observers' split requests, to every rank */
static int split_requests(floe_world *w, floe_par *P) {
    floe_world *M = P->mirror;
    free(P->mkind); free(P->mgroup); free(P->mids_at); free(P->mids); free(P->mdue);
    P->mkind = P->mgroup = P->mids_at = P->mdue = NULL;
    P->mids = NULL;
    P->nmobs = 0;
    int head[2] = {0, 0}; /* observers, ids */
    if (M) {
        head[0] = M->nobs;
        for (int k = 0; k < M->nobs; k++) {
            floe_split_request rq;
            if (split_kind(M->obs[k], &rq) == FLOE_SPLIT_PARTICLES) head[1] += rq.nids;
        }
    }
    MPI_Bcast(head, 2, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof head);
    const int n = head[0];
    int *ib = malloc((size_t)(3 * n + 1) * sizeof *ib);
    P->mids = malloc((size_t)(head[1] ? head[1] : 1) * sizeof *P->mids);
    P->mkind = malloc((size_t)(n ? n : 1) * sizeof *P->mkind);
    P->mgroup = malloc((size_t)(n ? n : 1) * sizeof *P->mgroup);
    P->mids_at = malloc((size_t)(n + 1) * sizeof *P->mids_at);
    P->mdue = malloc((size_t)(n ? n : 1) * sizeof *P->mdue);
    int bad = !ib || !P->mids || !P->mkind || !P->mgroup || !P->mids_at || !P->mdue, any;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_LOR, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (any) { free(ib); return floe_world_error(w, FLOE_ENOMEM, "MPI outputs: out of memory"); }
    if (M) { /* kind, group, first id of each; the ids */
        int at = 0;
        for (int k = 0; k < n; k++) {
            floe_split_request rq;
            int kind = split_kind(M->obs[k], &rq);
            if (kind == FLOE_SPLIT_PARTICLES && at + rq.nids > head[1]) kind = 0; /* its list changed since: gathered */
            ib[3 * k] = kind;
            ib[3 * k + 1] = rq.group;
            ib[3 * k + 2] = at;
            if (kind == FLOE_SPLIT_PARTICLES)
                for (int q = 0; q < rq.nids; q++) P->mids[at++] = rq.ids[q];
        }
        ib[3 * n] = at;
    }
    MPI_Bcast(ib, 3 * n + 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, (long long)(3 * n + 1) * sizeof *ib);
    if (head[1]) MPI_Bcast(P->mids, head[1], MPI_LONG_LONG, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, (long long)head[1] * sizeof *P->mids);
    for (int k = 0; k < n; k++) {
        P->mkind[k] = ib[3 * k];
        P->mgroup[k] = ib[3 * k + 1];
        P->mids_at[k] = ib[3 * k + 2];
    }
    P->mids_at[n] = ib[3 * n];
    P->nmobs = n;
    free(ib);
    return FLOE_OK;
}

/* a listed particle's state as floe_par_pack_state writes it (x v q w L f t), its force and
 * torque from SPLIT_FT on */
enum { SPLIT_PSTATE = FLOE_PAR_FWD, SPLIT_FT = 16 };


/* the due reduced outputs (due[k] for the mirror's observer k): every rank's share summed
 * (the boxes by minimum) on rank 0, which writes the collections' rows (observe_sums) and the
 * listed particles' state into the mirror (their outputs then observe it as usual).
 * Collective; the same return on every rank */
static int split_outputs(floe_world *w, floe_par *P, const int *due) {
    enum { CS = FLOE_COLLECTION_SUMS };
    long long nsum = 0, nmin = 0;
    for (int k = 0; k < P->nmobs; k++) {
        if (!due[k]) continue;
        if (P->mkind[k] == FLOE_SPLIT_COLLECTION) { nsum += 13; nmin += 6; } /* 12 sums + "not recorded" */
        if (P->mkind[k] == FLOE_SPLIT_PARTICLES) {
            nsum += (long long)SPLIT_PSTATE * (P->mids_at[k + 1] - P->mids_at[k]);
        }
    }
    if (!nsum && !nmin) return FLOE_OK; /* the same on every rank */
    int bad = nsum + nmin > 0x7fffffff || floe_par_reserve(&P->red_buf, &P->red_cap, (size_t)(nsum + nmin));
    double *sb = P->red_buf, *mb = sb + nsum;
    const floe_particles *p = &w->p;
    long long at = 0, am = 0;
    for (int k = 0; !bad && k < P->nmobs; k++) {
        if (!due[k]) continue;
        if (P->mkind[k] == FLOE_SPLIT_COLLECTION) {
            double cs[CS];
            const int rc = floe_world_collection_sums(w, P->mgroup[k], cs);
            if (rc == FLOE_ENOMEM) bad = 1;
            if (rc) { /* not recorded here: flagged, nothing added */
                for (int q = 0; q < 12; q++) cs[q] = 0;
                for (int a = 0; a < 3; a++) { cs[12 + a] = INFINITY; cs[15 + a] = -INFINITY; }
            }
            memcpy(sb + at, cs, 12 * sizeof *sb);
            sb[at + 12] = rc != FLOE_OK;
            for (int a = 0; a < 3; a++) { mb[am + a] = cs[12 + a]; mb[am + 3 + a] = -cs[15 + a]; }
            at += 13;
            am += 6;
        } else if (P->mkind[k] == FLOE_SPLIT_PARTICLES) {
            for (int q = P->mids_at[k]; q < P->mids_at[k + 1]; q++, at += SPLIT_PSTATE) {
                /* -0.0, the sum's identity: the owner's values come through the sum unchanged,
                 * -0.0 included */
                double *r = sb + at;
                for (int c = 0; c < SPLIT_PSTATE; c++) r[c] = -0.0;
                const int i = floe_world_local_of(w, P->mids[q], 0); /* a wall or owned here */
                if (i < 0) continue; /* owned elsewhere */
                floe_par_pack_state(p, i, r);
                /* a wall's force and torque are every rank's share, the rest rank 0's */
                if (i < P->nrep && P->rank != 0)
                    for (int c = 0; c < SPLIT_FT; c++) r[c] = -0.0;
            }
        }
    }
    int any;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_LOR, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (any) return floe_world_error(w, FLOE_ENOMEM, "MPI outputs: out of memory");
    const int root = P->rank == 0;
    if (nsum) MPI_Reduce(root ? MPI_IN_PLACE : sb, sb, (int)nsum, MPI_DOUBLE, MPI_SUM, 0, P->comm);
    if (nmin) MPI_Reduce(root ? MPI_IN_PLACE : mb, mb, (int)nmin, MPI_DOUBLE, MPI_MIN, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, (nsum + nmin) * (long long)sizeof *sb);
    floe_world *M = P->mirror;
    int rc = FLOE_OK;
    if (root && M) {
        const double t0 = MPI_Wtime(); /* rank 0's own work (the load balance's measure) */
        mirror_clock(w, M);
        floe_particles *q = &M->p;
        at = am = 0;
        for (int k = 0; !rc && k < P->nmobs; k++) {
            if (!due[k]) continue;
            if (P->mkind[k] == FLOE_SPLIT_COLLECTION) {
                double cs[CS];
                memcpy(cs, sb + at, 12 * sizeof *cs);
                for (int a = 0; a < 3; a++) { cs[12 + a] = mb[am + a]; cs[15 + a] = -mb[am + 3 + a]; }
                floe_observer *o = M->obs[k];
                if (sb[at + 12] != 0) M->contacts_valid = 0; /* some rank did not record: no row */
                else { /* every rank recorded its contacts */
                    M->err[0] = 0;
                    rc = o->klass->observe_sums(o, M, cs);
                    if (rc) floe_world_error(w, rc, "output %s failed at step %ld: %s", o->klass->name, w->step,
                                             M->err[0] ? M->err : floe_strerror(rc));
                }
                at += 13;
                am += 6;
            } else if (P->mkind[k] == FLOE_SPLIT_PARTICLES) {
                for (int j = P->mids_at[k]; j < P->mids_at[k + 1]; j++, at += SPLIT_PSTATE) {
                    const long long g = P->mids[j];
                    if (g < 0 || g >= q->n) continue;
                    floe_par_unpack_state(q, (int)g, sb + at);
                }
            }
        }
        P->busy += MPI_Wtime() - t0;
    }
    return agree_error_kind(w, rc, FLOE_COMM_OUTPUT); /* the failing rank's message everywhere */
}

static int output_due(const floe_world *w, const floe_observer *o) {
    return o->period_steps > 0 ? w->step % o->period_steps == 0
                               : o->period_time > 0 ? w->time >= o->next_time - 1e-9 * w->dt : 1;
}

/* one call of an output's observe (end: its end), its message prefixed with its name */
static int output_call(floe_world *w, floe_observer *o, int end) {
    w->err[0] = 0;
    int rc = end ? (o->klass->end ? o->klass->end(o, w) : FLOE_OK) : o->klass->observe(o, w);
    if (!rc) return FLOE_OK;
    char why[sizeof w->err];
    memcpy(why, w->err, sizeof why);
    return end ? floe_world_error(w, rc, "output %s failed at its end: %s", o->klass->name, why[0] ? why : floe_strerror(rc))
               : floe_world_error(w, rc, "output %s failed at step %ld: %s", o->klass->name, w->step,
                                  why[0] ? why : floe_strerror(rc));
}

/* every rank's own outputs (floe_world_parallel_add_output) that are due, as the world calls
 * its observers; the same on every rank, so their collective calls meet */
/* the due outputs of this rank, every one called (an output may hold a collective: the vtk
 * pieces' agreement), the first failure returned after them and agreed by every rank when
 * any was due (the same on every rank: their periods are) */
static int outputs_call(floe_world *w, floe_par *P, int force_all) {
    int first = FLOE_OK, called = 0;
    char why[sizeof w->err];
    for (int k = 0; k < P->nouts; k++) {
        floe_observer *o = P->outs[k];
        if (!force_all && !output_due(w, o)) continue;
        if (o->period_time > 0 && o->period_steps <= 0)
            while (o->next_time <= w->time + 1e-9 * w->dt) o->next_time += o->period_time;
        called = 1;
        const int rc = output_call(w, o, 0);
        if (rc && !first) { first = rc; memcpy(why, w->err, sizeof why); }
    }
    if (first) memcpy(w->err, why, sizeof why);
    return called ? floe_par_agree_error(w, first) : first;
}

int floe_world_parallel_add_output(floe_world *w, floe_observer *o) {
    floe_par *P = w->par;
    if (!o) return floe_world_error(w, FLOE_EINVAL, "MPI outputs: no output");
    if (!P) {
        floe_observer_destroy(o);
        return floe_world_error(w, FLOE_EINVAL, "MPI outputs: the world is not split");
    }
    int bad = o->klass->needs_contacts, any;
    floe_observer **no = bad ? NULL : realloc(P->outs, (size_t)(P->nouts + 1) * sizeof *no);
    if (!bad && !no) bad = 2;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (no) P->outs = no;
    if (any) {
        floe_observer_destroy(o);
        return any == 1 ? refuse(w, "an output that reads contacts") : floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    P->outs[P->nouts++] = o;
    /* every rank adds the same outputs: the class decides (one that lists particles reads
     * local indices that differ by rank: taken to read) */
    if (observer_orientation_claim(o)) {
        w->orient_extra = 1;
        orientation_refresh(w);
    }
    /* restored from a checkpoint (floe_world_checkpoint_restore_split_outputs): it goes on
     * from its state, its next time, as a restarted world's observers do (nothing written now) */
    if (o->begun) return FLOE_OK;
    o->begun = 1;
    w->err[0] = 0;
    int rc = o->klass->begin ? o->klass->begin(o, w) : FLOE_OK;
    if (rc) {
        char why[sizeof w->err];
        memcpy(why, w->err, sizeof why);
        return floe_world_error(w, rc, "output %s failed to start: %s", o->klass->name, why[0] ? why : "(no message)");
    }
    /* the state at the split (a prepared world's observers write theirs) */
    o->next_time = w->time;
    if (o->period_time > 0 && o->period_steps <= 0)
        while (o->next_time <= w->time + 1e-9 * w->dt) o->next_time += o->period_time;
    return output_call(w, o, 0);
}

int floe_world_parallel_own_outputs(const floe_world *w, floe_observer *const **outs) {
    *outs = w && w->par ? w->par->outs : NULL;
    return w && w->par ? w->par->nouts : 0;
}

/* the mirror's due observers (due[k]; more: an observer added to the mirror after
 * floe_world_parallel_outputs is due, gathered for; end: their ends, every one): the ledger
 * summed, the reduced outputs' shares (split_outputs), then the state gathered when an
 * observer without a split kind is due (the contacts with it when one of those reads them),
 * and rank 0's observers called. Collective; the same return on every rank */
static int mirror_observe(floe_world *w, floe_par *P, const int *due, int more, int force_all, int end) {
    floe_energy e;
    energy_sum(w, &e, FLOE_COMM_OUTPUT);
    if (P->mirror) P->mirror->energy = e;
    int gather = end || more, contacts = end;
    for (int k = 0; P->mirror && k < P->mirror->nobs; k++) /* rank 0: the late ones too */
        if (k >= P->nmobs ? more && (force_all || output_due(w, P->mirror->obs[k])) : due[k] && !P->mkind[k])
            contacts |= P->mirror->obs[k]->klass->needs_contacts;
    for (int k = 0; k < P->nmobs; k++) gather |= due[k] && !P->mkind[k];
    if (gather && !end) { /* only rank 0 holds the observers */
        MPI_Bcast(&contacts, 1, MPI_INT, 0, P->comm);
        floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof contacts);
    }
    int rc = split_outputs(w, P, due);
    if (!rc && gather) rc = mirror_gather(w, P, contacts);
    if (P->rank == 0 && !rc) {
        const double t0 = MPI_Wtime();
        mirror_clock(w, P->mirror); /* gathered or not, the observers' clock */
        if (end) {
            P->mirror->last_step_of_run = 1;
            rc = floe_world_finish(P->mirror);
        } else {
            rc = observers_call(P->mirror, force_all);
        }
        if (rc) floe_world_error(w, rc, "%s", floe_world_last_error(P->mirror));
        P->busy += MPI_Wtime() - t0;
    }
    return agree_error_kind(w, rc, FLOE_COMM_OUTPUT); /* the failing rank's message everywhere */
}

int floe_par_observe(floe_world *w, int force_all) {
    floe_par *P = w->par;
    /* the step's end: the traffic's step count and the mean loads */
    P->traffic.steps++;
    P->traffic.owned_steps += P->nown;
    P->traffic.ghost_steps += P->nghost;
    P->traffic.refreshed_steps += floe_par_nrefreshed(w, P);
    /* the outputs' own work (this rank's pieces; rank 0's observers on the mirror below) is
     * work the other ranks wait for: it counts in the load balance's measure (P->busy) */
    double t0 = MPI_Wtime();
    FLOE_TRY(outputs_call(w, P, force_all)); /* agreed */
    P->busy += MPI_Wtime() - t0;
    if (!P->has_mirror) return FLOE_OK; /* rank 0 has no mirror: told at floe_world_parallel_outputs */
    /* rank 0's word: the mirror is due now (bit 0), an output that reads contacts is due at
     * the next step (bit 1: every rank records its contacts then); when due, which of the
     * mirror's observers are (due[k]) */
    const int n = P->nmobs;
    int word = 0, *due = P->mdue;
    if (P->rank == 0) {
        for (int k = 0; k < n; k++) {
            due[k] = force_all || output_due(w, P->mirror->obs[k]);
            word |= due[k];
        }
        /* observers added after floe_world_parallel_outputs: gathered for (bit 2) */
        for (int k = n; k < P->mirror->nobs; k++)
            if (force_all || output_due(w, P->mirror->obs[k])) word |= 1 | 4;
        if (w->par_contacts & 1 && contacts_due_next(w, P->mirror)) word |= 2;
    }
    MPI_Bcast(&word, 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof word);
    w->par_contacts = (w->par_contacts & 1) | (word & 2);
    if (!(word & 1)) return FLOE_OK;
    MPI_Bcast(due, n, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, (long long)n * sizeof *due);
    return mirror_observe(w, P, due, word & 4, force_all, 0);
}

int floe_world_parallel_finish(floe_world *w) {
    floe_par *P = w->par;
    if (!P) return FLOE_OK;
    /* every rank's outputs: their end (collective; an error is the same on every rank when the
     * output agrees on it, as the vtk pieces do) */
    int orc = FLOE_OK;
    for (int k = 0; k < P->nouts; k++) {
        floe_observer *o = P->outs[k];
        if (o->ended) continue;
        o->ended = 1;
        int r = output_call(w, o, 1);
        if (r && !orc) orc = r;
    }
    int has = P->mirror != NULL;
    MPI_Bcast(&has, 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof has);
    if (!has) return orc;
    /* every reduced output called (each writes the final state unless it has at this step),
     * then the whole state gathered for the others' ends */
    int *due = P->mdue;
    for (int k = 0; k < P->nmobs; k++) due[k] = P->mkind[k] != 0;
    const int all = mirror_observe(w, P, due, 0, 0, 1);
    return orc ? orc : all;
}

/* ---- the whole state on rank 0 (checkpoints: floe_world_parallel_collect) ---- */

/* entries sorted by (gid_i, gid_j, piece pair, image): the serial list's order (its rows by
 * i, each row by (j, piece pair, image)); a wall pair is ordered by index as any other */
static int pair_cmp(const void *a, const void *b) {
    const double *x = a, *y = b;
    for (int k = 0; k < 4; k++)
        if (x[k] != y[k]) return x[k] < y[k] ? -1 : 1;
    return 0;
}

int floe_world_parallel_collect(const floe_world *w, floe_world *full) {
    floe_par *P = w->par;
    if (!P) return FLOE_OK;
    const floe_neighbor_list *nl = &w->nl;
    const int lo = P->nrep, no = P->nown, use_warm = nl->use_warm && nl->warm != NULL;
    const int mp = 1 + FLOE_PAR_FWD + 4;                                 /* gid, state, x_build, r_build */
    const int me = 5 + nl->hs + (use_warm ? FLOE_DETECT_WARM : 0); /* gid_i gid_j sub image touching hist warm */
    /* the full world must be an unsplit, prepared copy of this world's scene (rank 0) */
    int bad = 0;
    if (P->rank == 0) {
        if (!full || full->par || !full->prepared) bad = 1;
        else if (full->p.n != P->ntotal || (full->nl.use_warm != 0) != (nl->use_warm != 0)) bad = 2;
    }
    double *sp = malloc((size_t)(no ? no : 1) * mp * sizeof *sp);
    double *se = malloc((size_t)(nl->npairs ? nl->npairs : 1) * me * sizeof *se);
    double *wf = malloc((size_t)(P->nrep ? P->nrep : 1) * 6 * sizeof *wf);
    if (!bad && (!sp || !se || !wf)) bad = 3;
    int any;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (any) {
        free(sp); free(se); free(wf);
        return any == 3 ? floe_world_error((floe_world *)w, FLOE_ENOMEM, "MPI checkpoint: out of memory")
               : any == 1 ? floe_world_error((floe_world *)w, FLOE_EINVAL, "MPI checkpoint: rank 0 needs an unsplit, prepared "
                                            "world of the same scene to collect the state into")
                          : floe_world_error((floe_world *)w, FLOE_EINVAL, "MPI checkpoint: rank 0's unsplit world is not "
                                            "this world's scene (%d particles, %d here before the split)",
                                            full ? full->p.n : -1, P->ntotal);
    }
    const floe_particles *p = &w->p;
    for (int k = 0; k < no; k++) {
        const int i = lo + k;
        double *r = sp + (size_t)k * mp;
        r[0] = (double)P->gid[i];
        floe_par_pack_state(p, i, r + 1);
        const int built = i < nl->n_build;
        for (int a = 0; a < 3; a++) r[1 + FLOE_PAR_FWD + a] = built ? nl->x_build[3 * i + a] : p->x[3 * i + a];
        r[1 + FLOE_PAR_FWD + 3] = built ? nl->r_build[i] : p->radius[i];
    }
    /* every entry of this rank's list: each pair is listed on exactly one rank */
    for (int k = 0; k < nl->npairs; k++) {
        double *e = se + (size_t)k * me;
        e[0] = (double)P->gid[nl->pi[k]];
        e[1] = (double)P->gid[nl->pj[k]];
        e[2] = nl->sub[k];
        e[3] = w->cell && nl->img ? nl->img[k] : 0;
        e[4] = nl->touching[k];
        memcpy(e + 5, nl->hist + (size_t)k * nl->hs, (size_t)nl->hs * sizeof *e);
        if (use_warm) memcpy(e + 5 + nl->hs, nl->warm + (size_t)k * FLOE_DETECT_WARM, FLOE_DETECT_WARM * sizeof *e);
    }
    for (int i = 0; i < P->nrep; i++) {
        memcpy(wf + 6 * i, p->f + 3 * i, 3 * sizeof *wf);
        memcpy(wf + 6 * i + 3, p->t + 3 * i, 3 * sizeof *wf);
    }
    if (P->nrep) MPI_Reduce(P->rank == 0 ? MPI_IN_PLACE : wf, wf, 6 * P->nrep, MPI_DOUBLE, MPI_SUM, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, 6LL * P->nrep * sizeof *wf);
    /* the ledger and the watchdog's per-rank terms: sums (the pair dissipation's minimum, the
     * largest depth rate); the detection counters summed */
    double sv[11], ss[11], mn[3], mx[3];
    energy_pack(&w->energy, sv);
    sv[7] = w->elastic_contact; sv[8] = w->elastic_pd; sv[9] = w->wd_shadow; sv[10] = w->wd_shadow0;
    MPI_Reduce(sv, ss, 11, MPI_DOUBLE, MPI_SUM, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, sizeof sv);
    /* a periodic cell's sums over the contacts (its servo's first step after a restart) */
    double cv[27], cs[27];
    if (w->cell) {
        memcpy(cv, w->cell->virial, 9 * sizeof *cv);
        memcpy(cv + 9, w->cell->pd_virial, 9 * sizeof *cv);
        memcpy(cv + 18, w->cell->kdiag, 9 * sizeof *cv);
        MPI_Reduce(cv, cs, 27, MPI_DOUBLE, MPI_SUM, 0, P->comm);
        floe_par_count_to_root(P, FLOE_COMM_OUTPUT, sizeof cv);
    }
    mn[0] = w->wd_pair_min; mn[1] = -w->eta_depth; mn[2] = -nl->rmax_b; /* the largest radius at the builds */
    MPI_Reduce(mn, mx, 3, MPI_DOUBLE, MPI_MIN, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, sizeof mn);
    /* the watchdog's worst contacts (this step's, the run's): the rank that holds the
     * smallest, and the pair's global ids from every rank (rank 0 keeps that rank's) */
    struct { double v; int r; } wl[2] = {{w->wd_pair_min, P->rank}, {w->wd_worst, P->rank}}, wg[2];
    MPI_Reduce(wl, wg, 2, MPI_DOUBLE_INT, MPI_MINLOC, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, sizeof wl);
    int wid[4] = {gid_or(P, w->wd_pair_i), gid_or(P, w->wd_pair_j), gid_or(P, w->wd_worst_i), gid_or(P, w->wd_worst_j)};
    int *wids = P->rank == 0 ? malloc((size_t)4 * P->size * sizeof *wids) : NULL;
    int wok = P->rank != 0 || wids != NULL;
    MPI_Bcast(&wok, 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof wok);
    if (wok) {
        MPI_Gather(wid, 4, MPI_INT, wids, 4, MPI_INT, 0, P->comm);
        floe_par_count_to_root(P, FLOE_COMM_OUTPUT, sizeof wid);
    }
    long dl[6 + FLOE_DETECT_HIST], ds[6 + FLOE_DETECT_HIST];
    const floe_detect_state *d = &w->det;
    dl[0] = d->calls; dl[1] = d->iterations; dl[2] = d->admm_calls; dl[3] = d->lp_calls; dl[4] = d->separated;
    dl[5] = d->nonconverged;
    memcpy(dl + 6, d->hist, sizeof d->hist);
    MPI_Reduce(dl, ds, 6 + FLOE_DETECT_HIST, MPI_LONG, MPI_SUM, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, sizeof dl);
    /* the particles and the entries to rank 0 */
    int mine[2] = {no * mp, nl->npairs * me}, tot[2] = {0, 0};
    double *rb[2] = {NULL, NULL};
    const double *sb[2] = {sp, se};
    int rc = FLOE_OK;
    for (int s = 0; s < 2 && !rc; s++) rc = floe_par_gather_root(P, FLOE_COMM_OUTPUT, sb[s], mine[s], &rb[s], &tot[s]);
    free(sp); free(se);
    if (!rc && P->rank == 0) {
        floe_particles *q = &full->p;
        floe_neighbor_list *fl = &full->nl;
        const int N = q->n, ne = tot[1] / me;
        /* the list of the whole world, in the serial order */
        qsort(rb[1], (size_t)ne, (size_t)me * sizeof(double), pair_cmp);
        int nwl = nl->nwalls;
        int r2 = floe_resize((void **)&fl->pi, (size_t)ne * sizeof(int), 1);
        if (!r2) r2 = floe_resize((void **)&fl->pj, (size_t)ne * sizeof(int), 1);
        if (!r2) r2 = floe_resize((void **)&fl->sub, (size_t)ne * sizeof(int), 1);
        if (!r2) r2 = floe_resize((void **)&fl->hist, (size_t)ne * nl->hs * sizeof(double), 1);
        if (!r2) r2 = floe_resize((void **)&fl->touching, (size_t)ne, 1);
        if (!r2 && w->cell) r2 = floe_resize((void **)&fl->img, (size_t)ne * sizeof(int), 1);
        if (!r2 && fl->use_warm) r2 = floe_resize((void **)&fl->warm, (size_t)ne * FLOE_DETECT_WARM * sizeof(double), 1);
        if (!r2) r2 = floe_resize((void **)&fl->x_build, 3 * (size_t)N * sizeof(double), 1);
        if (!r2) r2 = floe_resize((void **)&fl->r_build, (size_t)N * sizeof(double), 1);
        if (!r2) r2 = floe_resize((void **)&fl->walls, (size_t)nwl * sizeof(int), 1);
        if (!r2) r2 = floe_resize((void **)&fl->q_walls, 4 * (size_t)nwl * sizeof(double), 1);
        if (r2) rc = FLOE_ENOMEM;
        else {
            for (int k = 0; k < ne; k++) {
                const double *e = rb[1] + (size_t)k * me;
                fl->pi[k] = (int)e[0];
                fl->pj[k] = (int)e[1];
                fl->sub[k] = (int)e[2];
                if (w->cell) fl->img[k] = (int)e[3];
                fl->touching[k] = (unsigned char)e[4];
                memcpy(fl->hist + (size_t)k * nl->hs, e + 5, (size_t)nl->hs * sizeof *e);
                if (fl->use_warm) {
                    if (use_warm) memcpy(fl->warm + (size_t)k * FLOE_DETECT_WARM, e + 5 + nl->hs, FLOE_DETECT_WARM * sizeof *e);
                    else for (int a = 0; a < FLOE_DETECT_WARM; a++) fl->warm[(size_t)k * FLOE_DETECT_WARM + a] = NAN;
                }
            }
            fl->npairs = fl->cap = ne;
            fl->hs = nl->hs; /* the same scene's stride */
            fl->gen++;
            if (!w->cell) {
                free(fl->img);
                fl->img = NULL;
            }
            fl->n_build = N;
            fl->skin = nl->skin;
            fl->rebuilds = nl->rebuilds;
            /* the state objects (a growing radius: the geometry and the radius), then the
             * particles: the owners' state and build positions by global id */
            const int srs = mirror_states(w, full);
            if (srs) rc = srs;
            for (int k = 0; k < tot[0] / mp; k++) {
                const double *r = rb[0] + (size_t)k * mp;
                const long long g = (long long)r[0];
                if (g < 0 || g >= N) continue;
                floe_par_unpack_state(q, (int)g, r + 1);
                memcpy(fl->x_build + 3 * g, r + 1 + FLOE_PAR_FWD, 3 * sizeof(double));
                fl->r_build[g] = r[1 + FLOE_PAR_FWD + 3];
            }
            /* the walls: rank 0's (the same on every rank), their forces summed */
            for (int i = 0; i < P->nrep; i++) {
                const long long g = P->gid[i];
                double st[FLOE_PAR_FWD];
                floe_par_pack_state(p, i, st);
                floe_par_unpack_state(q, (int)g, st);
                memcpy(q->f + 3 * g, wf + 6 * i, 3 * sizeof(double));
                memcpy(q->t + 3 * g, wf + 6 * i + 3, 3 * sizeof(double));
                const int built = i < nl->n_build;
                for (int a = 0; a < 3; a++) fl->x_build[3 * g + a] = built ? nl->x_build[3 * i + a] : p->x[3 * i + a];
                fl->r_build[g] = built ? nl->r_build[i] : p->radius[i];
            }
            fl->nwalls = nwl;
            for (int a = 0; a < nwl; a++) fl->walls[a] = (int)P->gid[nl->walls[a]];
            /* a periodic cell: the same on every rank, its sums over the contacts the ranks' */
            if (w->cell && full->cell) {
                *full->cell = *w->cell;
                memcpy(full->cell->virial, cs, 9 * sizeof *cs);
                memcpy(full->cell->pd_virial, cs + 9, 9 * sizeof *cs);
                memcpy(full->cell->kdiag, cs + 18, 9 * sizeof *cs);
                memcpy(fl->Hb, nl->Hb, sizeof fl->Hb);
                fl->rmax_b = -mx[2];
                fl->cell = full->cell;
            }
            memcpy(fl->q_walls, nl->q_walls, 4 * (size_t)nwl * sizeof(double));
            /* the clock and the integrator's memory: the same on every rank */
            full->time = w->time; full->dt = w->dt; full->t0 = w->t0; full->dt_crit = w->dt_crit;
            full->lf_dt_prev = w->lf_dt_prev; full->dt_next = w->dt_next; full->dt_lo = w->dt_lo; full->dt_hi = w->dt_hi;
            full->dt_cap = w->dt_cap; full->step = w->step; full->step0 = w->step0; full->pd_cycle = w->pd_cycle;
            /* the ledger */
            energy_unpack(&full->energy, ss);
            full->elastic_contact = ss[7]; full->elastic_pd = ss[8]; full->wd_shadow = ss[9]; full->wd_shadow0 = ss[10];
            full->wd_pair_min = mx[0]; full->eta_depth = -mx[1];
            full->wd_worst = wg[1].v; full->wd_scale = w->wd_scale; full->wd_created = w->wd_created;
            full->wd_gscale = w->wd_gscale; full->wd_step = w->wd_step;
            if (wids) {
                const int *a = wids + 4 * wg[0].r, *b = wids + 4 * wg[1].r;
                full->wd_pair_i = a[0]; full->wd_pair_j = a[1];
                full->wd_worst_i = b[2]; full->wd_worst_j = b[3];
            } else full->wd_pair_i = full->wd_pair_j = full->wd_worst_i = full->wd_worst_j = -1;
            memcpy(full->wd_msg, w->wd_msg, sizeof full->wd_msg);
            /* the statistics: the steps are every rank's; the detector's counts summed */
            full->st = w->st;
            floe_detect_state *fd = &full->det;
            fd->calls = ds[0]; fd->iterations = ds[1]; fd->admm_calls = ds[2]; fd->lp_calls = ds[3]; fd->separated = ds[4];
            fd->nonconverged = ds[5];
            memcpy(fd->hist, ds + 6, sizeof fd->hist);
            fd->cur_i = gid_or(P, d->cur_i); fd->cur_j = gid_or(P, d->cur_j);
            fd->first_bad_i = gid_or(P, d->first_bad_i); fd->first_bad_j = gid_or(P, d->first_bad_j);
            fd->first_bad_step = d->first_bad_step;
            full->ncontacts = 0;
            full->contacts_valid = 0;
        }
    }
    free(rb[0]); free(rb[1]); free(wf); free(wids);
    MPI_Bcast(&rc, 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof rc);
    if (rc) return floe_world_error((floe_world *)w, rc, rc == FLOE_ENOMEM ? "MPI checkpoint: out of memory on rank 0"
                                                                           : "MPI checkpoint: a state object could not be set");
    FLOE_TRY(floe_par_pp_collect((floe_world *)w, P, P->rank == 0 ? full : NULL)); /* par_forcing.c */
    FLOE_TRY(floe_par_pd_gather((floe_world *)w, P, P->rank == 0 ? full : NULL));  /* par_pd.c */
    /* the beam bonds' state (broken flags, stresses), held by the ranks that anchor them */
    if (!w->beams) return FLOE_OK;
    rc = floe_par_beams_gather((floe_world *)w, P, P->rank == 0 ? full : NULL);
    int all = rc; /* a mismatch is found on rank 0 only: every rank's error */
    MPI_Allreduce(&rc, &all, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof rc);
    if (rc) return rc; /* its message is set */
    return all ? floe_world_error((floe_world *)w, all, "MPI checkpoint: gathering the beam bonds failed on rank 0")
               : FLOE_OK;
}

int floe_parallel_agree(const void *comm, int rc) {
    int inited = 0, all = rc;
    MPI_Initialized(&inited);
    if (!inited) return rc;
    MPI_Allreduce(&rc, &all, 1, MPI_INT, MPI_MAX, comm ? *(const MPI_Comm *)comm : MPI_COMM_WORLD);
    return all;
}

#else /* serial build: a world is never split */

int floe_parallel_available(void) { return 0; }
int floe_world_parallel_collect(const floe_world *w, floe_world *full) { (void)w; (void)full; return FLOE_OK; }
int floe_parallel_agree(const void *comm, int rc) { (void)comm; return rc; }
int floe_world_parallel_init(floe_world *w, const void *comm) {
    (void)comm;
    return floe_world_error(w, FLOE_ENOTSUP, "MPI decomposition: floe was built without MPI (configure with "
                            "-DFLOE_WITH_MPI=ON)");
}
int floe_world_parallel_rebuild(floe_world *w) { (void)w; return FLOE_OK; }
int floe_par_refresh(floe_world *w, double maxd2, int have_xb, const floe_par_carry *carry, int rc, int *flag,
                     int *told) {
    (void)flag;
    (void)w; (void)maxd2; (void)have_xb; (void)carry;
    *told = 0;
    return rc;
}
int floe_par_ghost_update(floe_world *w) { (void)w; return FLOE_OK; }
int floe_par_reverse(floe_world *w) { (void)w; return FLOE_OK; }
int floe_par_agree_error(floe_world *w, int rc) { (void)w; return rc; }
void floe_par_max(floe_world *w, double *v, int n) { (void)w; (void)v; (void)n; }
int floe_par_cell_stress(floe_world *w, double sigma[9], int *given) {
    (void)w; (void)sigma;
    *given = 0;
    return FLOE_OK;
}
double floe_par_clock(void) { return 0.0; }
void floe_par_force_time(floe_world *w, double seconds) { (void)w; (void)seconds; }
int floe_world_parallel_set_balance(floe_world *w, floe_balance mode) {
    return balance_check(w, mode);
}
int floe_par_observe(floe_world *w, int force_all) { (void)w; (void)force_all; return FLOE_OK; }
int floe_world_parallel_outputs(floe_world *w, floe_world *mirror) {
    (void)mirror;
    return floe_world_error(w, FLOE_ENOTSUP, "MPI outputs: floe was built without MPI");
}
int floe_world_parallel_finish(floe_world *w) { (void)w; return FLOE_OK; }
int floe_world_parallel_own_outputs(const floe_world *w, floe_observer *const **outs) {
    (void)w;
    *outs = NULL;
    return 0;
}
int floe_world_parallel_add_output(floe_world *w, floe_observer *o) {
    floe_observer_destroy(o);
    return floe_world_error(w, FLOE_ENOTSUP, "MPI outputs: floe was built without MPI");
}
int floe_par_watchdog_values(floe_world *w, floe_energy *e, double *shadow, double *shadow0, double *pair_min,
                             double *pdd, int npd, const int *close_rc) {
    (void)w; (void)e; (void)shadow; (void)shadow0; (void)pair_min; (void)pdd; (void)npd;
    return close_rc ? *close_rc : FLOE_OK;
}
double floe_par_pick(floe_world *w, double key, char *a, int alen, char *b, int blen) {
    (void)w; (void)a; (void)alen; (void)b; (void)blen;
    return key;
}
int floe_world_parallel_energy(const floe_world *w, floe_energy *out) { *out = w->energy; return FLOE_OK; }
int floe_world_parallel_sum(const floe_world *w, double *v, int n) { (void)w; (void)v; (void)n; return FLOE_OK; }
int floe_world_parallel_gather(const floe_world *w, double *x, double *v, int N) {
    for (int i = 0; i < w->p.n && i < N; i++) {
        if (x) memcpy(x + 3 * i, w->p.x + 3 * i, 3 * sizeof *x);
        if (v) memcpy(v + 3 * i, w->p.v + 3 * i, 3 * sizeof *v);
    }
    return FLOE_OK;
}
int floe_world_parallel_rank(const floe_world *w, int *rank, int *size) { (void)w; *rank = 0; *size = 1; return FLOE_OK; }
int floe_world_parallel_comm(const floe_world *w, floe_comm_stats *out) {
    (void)w;
    memset(out, 0, sizeof *out);
    return FLOE_OK;
}
int floe_world_parallel_comm_reset(floe_world *w) { (void)w; return FLOE_OK; }
int floe_world_parallel_counts(const floe_world *w, int *owned, int *ghosts) {
    int nb = 0;
    for (int i = 0; i < w->p.n; i++) nb += isfinite(w->p.radius[i]) != 0;
    *owned = nb;
    *ghosts = 0;
    return FLOE_OK;
}
long long floe_world_parallel_gid(const floe_world *w, int i) { return i >= 0 && i < w->p.n ? i : -1; }
int floe_world_parallel_is_owned(const floe_world *w, int i) { (void)w; (void)i; return 1; }

#endif
