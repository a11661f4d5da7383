/* decomp.c - the pieces of the MPI domain decomposition (docs/parallel.md): particles packed
 * for travel, routing between ranks, recursive coordinate bisection by Zoltan, migration of
 * owned particles, ghosts by bounding radius and their forward and reverse refresh. The
 * world-level sequence (par_world.c) calls these, never the reverse. */
#include "par_internal.h"
#include "alloc_util.h"
#include "floe_observer_base.h"

#ifdef FLOE_HAVE_MPI
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zoltan.h>

int floe_par_gather_root(floe_par *P, int k, const double *sb, int n, double **out, int *tot) {
    *out = NULL;
    *tot = 0;
    int *cnt = P->rank == 0 ? P->gcnt : NULL;
    MPI_Gather(&n, 1, MPI_INT, cnt, 1, MPI_INT, 0, P->comm);
    floe_par_count_to_root(P, k, sizeof n);
    int nomem = 0;
    double *rb = NULL;
    if (P->rank == 0) {
        long long t = 0;
        for (int r = 0; r < P->size; r++) { cnt[P->size + r] = (int)t; t += cnt[r]; }
        nomem = t > 0x7fffffff; /* MPI counts are ints */
        if (!nomem) *tot = (int)t;
        rb = nomem ? NULL : malloc((size_t)(*tot ? *tot : 1) * sizeof *rb);
        nomem = !rb;
    }
    MPI_Bcast(&nomem, 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, k, sizeof nomem);
    if (nomem) {
        *tot = 0;
        return FLOE_ENOMEM;
    }
    MPI_Gatherv(sb, n, MPI_DOUBLE, rb, cnt, cnt ? cnt + P->size : NULL, MPI_DOUBLE, 0, P->comm);
    floe_par_count_to_root(P, k, (long long)n * sizeof *sb);
    *out = rb;
    return FLOE_OK;
}

int floe_par_reserve(double **buf, size_t *cap, size_t n) {
    if (n <= *cap && *buf) return FLOE_OK;
    size_t nc = n ? n : 1;
    double *b = realloc(*buf, nc * sizeof *b);
    if (!b) return FLOE_ENOMEM;
    *buf = b;
    *cap = nc;
    return FLOE_OK;
}

void floe_par_pack_state(const floe_particles *p, int i, double *r) {
    memcpy(r, p->x + 3 * i, 3 * sizeof *r);
    memcpy(r + 3, p->v + 3 * i, 3 * sizeof *r);
    memcpy(r + 6, p->q + 4 * i, 4 * sizeof *r);
    memcpy(r + 10, p->w + 3 * i, 3 * sizeof *r);
    memcpy(r + 13, p->L + 3 * i, 3 * sizeof *r);
    memcpy(r + 16, p->f + 3 * i, 3 * sizeof *r);
    memcpy(r + 19, p->t + 3 * i, 3 * sizeof *r);
}

void floe_par_unpack_state(floe_particles *p, int i, const double *r) {
    memcpy(p->x + 3 * i, r, 3 * sizeof *r);
    memcpy(p->v + 3 * i, r + 3, 3 * sizeof *r);
    memcpy(p->q + 4 * i, r + 6, 4 * sizeof *r);
    memcpy(p->w + 3 * i, r + 10, 3 * sizeof *r);
    memcpy(p->L + 3 * i, r + 13, 3 * sizeof *r);
    memcpy(p->f + 3 * i, r + 16, 3 * sizeof *r);
    memcpy(p->t + 3 * i, r + 19, 3 * sizeof *r);
}

/* the record: gid, the state (x3 v3 q4 w3 L3 f3 t3), mass inv_mass inertia3 radius, geom
 * material group motion kind iso, inv_iso rdot pieces thick = 39 doubles: every array of the
 * store (a migration moves the stayers with floe_world_move_particles, world.c's list of
 * them: a field added to one must be added to the other) */
void floe_par_pack(const floe_particles *p, int i, long long gid, double *r) {
    int k = 0;
    r[k++] = (double)gid;
    floe_par_pack_state(p, i, r + k);
    k += FLOE_PAR_FWD;
    r[k++] = p->mass[i];
    r[k++] = p->inv_mass[i];
    for (int a = 0; a < 3; a++) r[k++] = p->inertia[3 * i + a];
    r[k++] = p->radius[i];
    r[k++] = p->geom[i];
    r[k++] = p->material[i];
    r[k++] = p->group[i];
    r[k++] = p->motion[i];
    r[k++] = p->kind[i];
    r[k++] = p->iso[i];
    r[k++] = p->inv_iso[i];
    r[k++] = p->rdot[i];
    r[k++] = p->pieces[i];
    r[k++] = p->thick ? p->thick[i] : 0.0;
}

void floe_par_unpack(floe_particles *p, int i, const double *r, long long *gid) {
    int k = 0;
    *gid = (long long)r[k++];
    floe_par_unpack_state(p, i, r + k);
    k += FLOE_PAR_FWD;
    p->mass[i] = r[k++];
    p->inv_mass[i] = r[k++];
    for (int a = 0; a < 3; a++) p->inertia[3 * i + a] = r[k++];
    p->radius[i] = r[k++];
    p->geom[i] = (int)r[k++];
    p->material[i] = (int)r[k++];
    p->group[i] = (int)r[k++];
    p->motion[i] = (unsigned char)r[k++];
    p->kind[i] = (unsigned char)r[k++];
    p->iso[i] = (unsigned char)r[k++];
    p->inv_iso[i] = r[k++];
    p->rdot[i] = r[k++];
    p->pieces[i] = (int)r[k++];
    double th = r[k++];
    if (p->thick) p->thick[i] = th;
}

void floe_par_count(floe_par *P, int k, long long bytes, long long msgs) {
    if (P->size < 2 || bytes <= 0) return;
    P->traffic.bytes[k] += bytes;
    P->traffic.messages[k] += msgs;
}

void floe_par_count_v(floe_par *P, int k, const int *count, long long item_bytes) {
    for (int r = 0; r < P->size; r++)
        if (r != P->rank && count[r] > 0) floe_par_count(P, k, count[r] * item_bytes, 1);
}

void floe_par_count_allreduce(floe_par *P, int k, long long bytes) { floe_par_count(P, k, bytes, 1); }
void floe_par_count_bcast(floe_par *P, int k, long long bytes) {
    if (P->rank == 0) floe_par_count(P, k, bytes, 1);
}
void floe_par_count_to_root(floe_par *P, int k, long long bytes) {
    if (P->rank != 0) floe_par_count(P, k, bytes, 1);
}
void floe_par_count_all(floe_par *P, int k, long long bytes) {
    floe_par_count(P, k, bytes * (P->size - 1), P->size - 1);
}

int floe_par_agree(floe_par *P, int rc) {
    int all = rc;
    MPI_Allreduce(&rc, &all, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof rc);
    return all;
}

int floe_par_route(floe_par *P, int kind, const double *items, const int *dest, int nitems, int m, double **out, int *nout) {
    const int S = P->size;
    int *sc = P->rt, *sd = sc + S, *rc = sc + 2 * S, *rd = sc + 3 * S, *pos = sc + 4 * S;
    *out = NULL;
    *nout = 0;
    /* the counts (-1 to every rank: this rank failed before; every rank then returns) */
    for (int r = 0; r < S; r++) sc[r] = nitems < 0 ? -1 : 0;
    for (int k = 0; k < nitems; k++) sc[dest[k]]++;
    MPI_Alltoall(sc, 1, MPI_INT, rc, 1, MPI_INT, P->comm);
    floe_par_count_all(P, kind, sizeof(int));
    int failed = nitems < 0;
    for (int r = 0; r < S; r++) failed |= rc[r] < 0;
    if (failed) return FLOE_ENOMEM;
    floe_par_count_v(P, kind, sc, (long long)m * sizeof(double));
    int ns = 0, nr = 0;
    for (int r = 0; r < S; r++) { sd[r] = ns; ns += sc[r]; rd[r] = nr; nr += rc[r]; }
    double *sb = malloc((size_t)(ns ? ns : 1) * m * sizeof *sb);
    double *rb = malloc((size_t)(nr ? nr : 1) * m * sizeof *rb);
    if (floe_par_agree(P, !sb || !rb ? FLOE_ENOMEM : FLOE_OK)) { free(sb); free(rb); return FLOE_ENOMEM; }
    memcpy(pos, sd, (size_t)S * sizeof *pos);
    for (int k = 0; k < nitems; k++) memcpy(sb + (size_t)pos[dest[k]]++ * m, items + (size_t)k * m, (size_t)m * sizeof *sb);
    for (int r = 0; r < S; r++) { sc[r] *= m; sd[r] *= m; rc[r] *= m; rd[r] *= m; }
    MPI_Alltoallv(sb, sc, sd, MPI_DOUBLE, rb, rc, rd, MPI_DOUBLE, P->comm);
    free(sb);
    *out = rb;
    *nout = nr;
    return FLOE_OK;
}

/* ---- Zoltan's callbacks: the owned particles, their centres ---- */
typedef struct zctx { floe_world *w; floe_par *P; const float *wts; } zctx;

static int z_num_obj(void *data, int *ierr) {
    *ierr = ZOLTAN_OK;
    return ((zctx *)data)->P->nown;
}
static void z_obj_list(void *data, int ngid, int nlid, ZOLTAN_ID_PTR gids, ZOLTAN_ID_PTR lids, int wdim, float *wts,
                       int *ierr) {
    (void)ngid; (void)nlid;
    const zctx *z = data;
    for (int k = 0; k < z->P->nown; k++) {
        gids[k] = (ZOLTAN_ID_TYPE)z->P->gid[z->P->nrep + k];
        lids[k] = (ZOLTAN_ID_TYPE)k;
        for (int c = 0; c < wdim; c++) wts[(size_t)k * wdim + c] = z->wts ? z->wts[2 * k + c] : 1.0f;
    }
    *ierr = ZOLTAN_OK;
}
static int z_num_geom(void *data, int *ierr) {
    *ierr = ZOLTAN_OK;
    return ((zctx *)data)->w->def.dim;
}
static void z_geom_multi(void *data, int ngid, int nlid, int nobj, ZOLTAN_ID_PTR gids, ZOLTAN_ID_PTR lids, int ndim,
                         double *geom, int *ierr) {
    (void)ngid; (void)nlid; (void)gids;
    const zctx *z = data;
    for (int k = 0; k < nobj; k++) {
        const int i = z->P->nrep + (int)lids[k];
        double y[3];
        /* a periodic cell: the centre wrapped into it (positions are never wrapped) */
        if (z->w->cell) floe_world_cell_wrap(z->w, z->w->p.x + 3 * i, y);
        else memcpy(y, z->w->p.x + 3 * i, sizeof y);
        for (int a = 0; a < ndim; a++) geom[(size_t)k * ndim + a] = y[a];
    }
    *ierr = ZOLTAN_OK;
}

/* The work of owned particle k, for the bisection, as two criteria (units of a free
 * particle's integration, ~50 ns a step on the development VM), from the list of the last
 * decomposition:
 *   [2k]     the particles' phases: 1 (its integration) + 0.1 per list entry it is in (the
 *            entry's screening and the list's build);
 *   [2k + 1] all of its work: that + 1.2 more per entry in contact at the last step (the pair's
 *            evaluation).
 * NULL before a list exists (every particle 1 and 1). The two are balanced each on its own
 * (Zoltan's multicriteria bisection places each cut where the worse criterion is the most
 * even, and chooses among directions as floe_par_rcb says), so the contacts' phase is
 * balanced too: the step's phases each
 * end at a collective (the forces at the ghosts' sums, the drift and the list at the ghosts'
 * positions), and a rank that holds the contacts of a settled bed and one that holds the
 * falling particles above it waited for each other twice a step with their total work equal:
 * one weight, the total, cut a settling bed (bench/dem-settle under mpirun -np 2) across its
 * height (bench/RESULTS.md, issue 14 sessions 28 and 32). The second criterion is the total
 * and not the contacts alone, which are few and scattered in a gas: normalised to the same
 * sum as the first, they moved the cut at every rebuild. */
static float *rcb_weights(const floe_world *w, const floe_par *P) {
    const floe_neighbor_list *nl = &w->nl;
    const int lo = P->nrep, hi = P->nrep + P->nown;
    if (nl->n_build != w->p.n || nl->npairs <= 0 || !nl->touching) return NULL;
    float *wt = malloc(2 * (size_t)(P->nown ? P->nown : 1) * sizeof *wt);
    if (!wt) return NULL; /* count alone */
    for (int k = 0; k < 2 * P->nown; k++) wt[k] = 1.0f;
    for (int k = 0; k < nl->npairs; k++) {
        const float c = nl->touching[k] ? 1.3f : 0.1f;
        const int i = nl->pi[k], j = nl->pj[k];
        if (i >= lo && i < hi) {
            wt[2 * (i - lo)] += 0.1f;
            wt[2 * (i - lo) + 1] += c;
        }
        if (j >= lo && j < hi) {
            wt[2 * (j - lo)] += 0.1f;
            wt[2 * (j - lo) + 1] += c;
        }
    }
    return wt;
}

/* the parts' target sizes (P->bal_sz, both criteria) given to zz, those given before cleared
 * (Zoltan appends each call's to its list) */
static void set_part_sizes(floe_par *P, struct Zoltan_Struct *zz) {
    if (!P->bal_sz || !zz) return;
    Zoltan_LB_Set_Part_Sizes(zz, 1, -1, NULL, NULL, NULL);
    Zoltan_LB_Set_Part_Sizes(zz, 1, 2 * P->size, P->bal_ids, P->bal_ids + 2 * P->size, P->bal_sz);
}

/* the balance's mode; its scratch at the first call, agreed (collective): a rank out of
 * memory there is every rank's and no rank changes its mode (the ranks would otherwise
 * decompose in different modes, and their collectives part); back to even shares when the
 * weights take over again */
int floe_par_set_balance(floe_par *P, int mode) {
    const int S = P->size;
    const int first = !P->cost;
    if (first) {
        P->cost = calloc(2 * (size_t)S, sizeof *P->cost);
        P->bal_ids = malloc(4 * (size_t)S * sizeof *P->bal_ids);
        P->bal_sz = malloc(2 * (size_t)S * sizeof *P->bal_sz);
    }
    /* (first is every rank's: the scratch is kept, or freed on every rank below) */
    const int bad = !P->cost || !P->bal_ids || !P->bal_sz;
    if (first && floe_par_agree(P, bad ? FLOE_ENOMEM : FLOE_OK)) { /* as before the call, on every rank */
        free(P->cost); free(P->bal_ids); free(P->bal_sz);
        P->cost = NULL; P->bal_ids = NULL; P->bal_sz = NULL;
        return FLOE_ENOMEM;
    }
    if (first) {
        for (int r = 0; r < S; r++) { /* each part's size for both criteria (rcb_weights) */
            P->bal_ids[r] = P->bal_ids[S + r] = r;
            P->bal_ids[2 * S + r] = 0;
            P->bal_ids[3 * S + r] = 1;
            P->bal_sz[r] = P->bal_sz[S + r] = 1.0f / (float)S;
        }
    }
    if (mode == FLOE_BALANCE_WEIGHTS && P->balance != mode && P->zz) { /* back to even shares */
        for (int r = 0; r < S; r++) { P->bal_sz[r] = P->bal_sz[S + r] = 1.0f / (float)S; P->cost[r] = 0; }
        set_part_sizes(P, P->zz);
    }
    P->balance = mode;
    return FLOE_OK;
}

/* FLOE_BALANCE_TIME: each rank's seconds per unit of weight since the last cut (the seconds
 * of its own work, P->busy: force evaluations and outputs, over the sum of its total
 * criterion (rcb_weights; the same list, the same touching flags), averaged with the previous measure (half each: a single
 * noisy interval moves the cut by half as much), gathered; the parts' target sizes are the
 * ranks' speeds (1 / cost) over their sum, kept within [1/4, 4] of the even share, the same on
 * every rank. Before any measure, or if a rank has none (no weights, no time), the sizes stay
 * as they were. */
static void time_shares(floe_par *P, const float *wts) {
    const int S = P->size;
    double ws = 0, *all = P->cost + S;
    if (wts) /* the total criterion: the rank's work */
        for (int k = 0; k < P->nown; k++) ws += wts[2 * k + 1];
    else
        ws = P->nown;
    const double mine = ws > 0 && P->busy > 0 ? P->busy / ws : 0.0;
    MPI_Allgather(&mine, 1, MPI_DOUBLE, all, 1, MPI_DOUBLE, P->comm);
    floe_par_count(P, FLOE_COMM_REDUCE, (long long)(S - 1) * (long long)sizeof mine, S - 1);
    for (int r = 0; r < S; r++)
        if (!(all[r] > 0 && all[r] < INFINITY)) return;
    double sum = 0, tot = 0;
    for (int r = 0; r < S; r++) {
        P->cost[r] = P->cost[r] > 0 ? 0.5 * (P->cost[r] + all[r]) : all[r];
        sum += 1.0 / P->cost[r];
    }
    for (int r = 0; r < S; r++) {
        const double even = 1.0 / S, share = (1.0 / P->cost[r]) / sum;
        all[r] = fmin(fmax(share, 0.25 * even), 4.0 * even);
        tot += all[r];
    }
    for (int r = 0; r < S; r++) P->bal_sz[r] = P->bal_sz[S + r] = (float)(all[r] / tot);
    set_part_sizes(P, P->zz);
}

/* a Zoltan object for RCB under both criteria (rcb_weights) with its directions locked after
 * its first partition (which tries every direction whose extent is at least 1/aspect of the
 * part's longest); the parts' sizes as set (NULL: out of memory or Zoltan) */
static struct Zoltan_Struct *rcb_new(floe_par *P, const char *aspect) {
    struct Zoltan_Struct *zz = Zoltan_Create(P->comm);
    if (!zz) return NULL;
    Zoltan_Set_Param(zz, "DEBUG_LEVEL", "0");
    Zoltan_Set_Param(zz, "LB_METHOD", "RCB");
    Zoltan_Set_Param(zz, "NUM_GID_ENTRIES", "1");
    Zoltan_Set_Param(zz, "NUM_LID_ENTRIES", "1");
    Zoltan_Set_Param(zz, "OBJ_WEIGHT_DIM", "2");
    Zoltan_Set_Param(zz, "RCB_MULTICRITERIA_NORM", "3"); /* the worse criterion's imbalance */
    Zoltan_Set_Param(zz, "RCB_LOCK_DIRECTIONS", "1");
    /* the directions tried: those at least 1/aspect of the part's longest extent */
    Zoltan_Set_Param(zz, "RCB_MAX_ASPECT_RATIO", aspect);
    Zoltan_Set_Param(zz, "RETURN_LISTS", "EXPORT");
    Zoltan_Set_Param(zz, "RCB_REUSE", "1");
    Zoltan_Set_Param(zz, "KEEP_CUTS", "1");
    set_part_sizes(P, zz);
    return zz;
}

/* zz's partition of the owned particles into dest (the rank each goes to) */
static int rcb_run(struct Zoltan_Struct *zz, zctx *z, int *dest) {
    const floe_par *P = z->P;
    for (int k = 0; k < P->nown; k++) dest[k] = P->rank;
    Zoltan_Set_Num_Obj_Fn(zz, z_num_obj, z);
    Zoltan_Set_Obj_List_Fn(zz, z_obj_list, z);
    Zoltan_Set_Num_Geom_Fn(zz, z_num_geom, z);
    Zoltan_Set_Geom_Multi_Fn(zz, z_geom_multi, z);
    int changes, ngid, nlid, nimp, nexp;
    ZOLTAN_ID_PTR igid = NULL, ilid = NULL, egid = NULL, elid = NULL;
    int *iproc = NULL, *ipart = NULL, *eproc = NULL, *epart = NULL;
    int zr = Zoltan_LB_Partition(zz, &changes, &ngid, &nlid, &nimp, &igid, &ilid, &iproc, &ipart, &nexp, &egid,
                                 &elid, &eproc, &epart);
    if (zr == ZOLTAN_OK || zr == ZOLTAN_WARN)
        for (int k = 0; k < nexp; k++) dest[elid[k]] = eproc[k];
    Zoltan_LB_Free_Part(&igid, &ilid, &iproc, &ipart);
    Zoltan_LB_Free_Part(&egid, &elid, &eproc, &epart);
    return zr == ZOLTAN_OK || zr == ZOLTAN_WARN ? FLOE_OK : FLOE_EINVAL;
}

/* the parts' imbalance under dest: over both criteria and every part, the largest of a part's
 * weight over its target share (1: even). The weights are summed as integers (tenths: 1 +
 * 0.1 per entry + 1.2 per contact are whole tenths), so the sums, and the decisions taken on
 * them, are the same on every rank whatever the reduction's order. *rc: this rank's outcome
 * so far, carried in the same reduction (every rank calls this, failed or not: a rank whose
 * bisection failed must not skip the collective); on return, when any rank failed, a
 * failure on every rank (this rank's own, else FLOE_EINVAL) and INFINITY */
static double rcb_imbalance(floe_par *P, const float *wts, const int *dest, int *rc) {
    const int S = P->size, m = 2 * S + 1;
    long long *loc = P->rcb_sum, *tot = loc + m;
    memset(loc, 0, (size_t)m * sizeof *loc);
    for (int k = 0; !*rc && k < P->nown; k++)
        for (int c = 0; c < 2; c++) loc[2 * dest[k] + c] += wts ? llroundf(10.0f * wts[2 * k + c]) : 10;
    loc[2 * S] = *rc != FLOE_OK;
    MPI_Allreduce(loc, tot, m, MPI_LONG_LONG, MPI_SUM, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, m * (long long)sizeof *tot);
    if (tot[2 * S]) {
        if (!*rc) *rc = FLOE_EINVAL; /* another rank's bisection failed */
        return INFINITY;
    }
    double worst = 0;
    for (int c = 0; c < 2; c++) {
        long long sum = 0;
        for (int r = 0; r < S; r++) sum += tot[2 * r + c];
        for (int r = 0; r < S; r++) {
            const double share = P->bal_sz ? (double)P->bal_sz[r] : 1.0 / S; /* (even: no balance mode set) */
            const double b = sum > 0 ? (double)tot[2 * r + c] / (share * (double)sum) : 1.0;
            if (b > worst) worst = b;
        }
    }
    return worst;
}

/* The decomposition: recursive coordinate bisection under both criteria (rcb_weights), each
 * cut placed where the worse of the two is the most even. The first decomposition tries the
 * directions at least 2/3 of a part's longest extent (with the two criteria alike, as at the
 * split, Zoltan's choice among all three made slabs of a box at 4 ranks: 14 % more ghosts).
 * The directions are then kept from one decomposition to the next, with only the cuts'
 * places moved: where two directions balance about as well (a uniform box, a gas), a free
 * choice turned from one to the other at successive rebuilds, and half the particles
 * migrated each time. They are chosen again (a fresh partition that tries every direction
 * down to a tenth of the longest extent, about 1.5 ms for 20,000 particles on two ranks)
 * when the kept ones leave a part more than 5 % above its share, and taken when that is at
 * least 3 % (of a share) better; after a fresh choice that did no better, not before the
 * kept ones are 5 % worse again. A bed settling under a cut across its height changes it for
 * one along it (bench/dem-settle, tests/mpi/test_mpi_balance.c). */
int floe_par_rcb(floe_world *w, floe_par *P, int *dest) {
    for (int k = 0; k < P->nown; k++) dest[k] = P->rank;
    if (P->size == 1) return FLOE_OK;
    int rc = FLOE_OK;
    if (!P->zz) { /* (a failure here joins the collectives below all the same, and is agreed there) */
        float zver;
        if (Zoltan_Initialize(0, NULL, &zver) != ZOLTAN_OK) rc = FLOE_EINVAL;
        else if (!(P->zz = rcb_new(P, "1.5"))) rc = FLOE_ENOMEM;
    }
    float *wts = rcb_weights(w, P);
    if (P->balance == FLOE_BALANCE_TIME) time_shares(P, wts);
    P->busy = 0; /* the measure starts again with the new cut */
    zctx z = {w, P, wts};
    if (!rc) rc = rcb_run(P->zz, &z, dest);
    const double kept = rcb_imbalance(P, wts, dest, &rc); /* (rc: now every rank's) */
    if (!rc && kept > 1.05 && kept > P->rcb_tried + 0.05) {
        int *alt = malloc((size_t)(P->nown ? P->nown : 1) * sizeof *alt);
        struct Zoltan_Struct *zn = rcb_new(P, "10");
        int ok = floe_par_agree(P, alt && zn ? FLOE_OK : FLOE_ENOMEM) == FLOE_OK;
        ok = ok && floe_par_agree(P, rcb_run(zn, &z, alt)) == FLOE_OK;
        int frc = FLOE_OK;
        const double fresh = ok ? rcb_imbalance(P, wts, alt, &frc) : INFINITY; /* (ok: agreed) */
        if (ok && !frc && fresh < kept - 0.03) { /* the new directions: zn's cuts are kept from now on */
            memcpy(dest, alt, (size_t)P->nown * sizeof *dest);
            struct Zoltan_Struct *old = P->zz;
            P->zz = zn;
            zn = old;
            P->rcb_tried = 0;
        } else
            P->rcb_tried = kept; /* not again until the kept ones are 5 % worse still */
        if (zn) Zoltan_Destroy(&zn);
        free(alt);
    }
    free(wts);
    return rc;
}

static int cmp_rec(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* room for the gid table and the store */
static int par_room(floe_world *w, floe_par *P, int need) {
    if (floe_world_reserve_particles(w, need)) return FLOE_ENOMEM;
    if (need > P->gid_cap) {
        long long *g = realloc(P->gid, (size_t)need * sizeof *g);
        if (!g) return FLOE_ENOMEM;
        if (w->nl.gid == P->gid) w->nl.gid = g; /* (the messages read it: floe_world_pid) */
        P->gid = g;
        P->gid_cap = need;
    }
    /* the kinematic particles' forces at the step start (6 per particle; walls only under
     * MPI, but the integrators index it by particle) */
    double *ko = realloc(w->kin_old, (size_t)(need ? need : 1) * 6 * sizeof *ko);
    if (!ko) return FLOE_ENOMEM;
    w->kin_old = ko;
    w->kin_old_n = need; /* registered (world_prepare.c) where kinematic particles are: then floe_par_pp_in
                            sets the new rows */
    return FLOE_OK;
}

/* The owned particles stay sorted by global id (floe_world_local_of searches them so). The
 * stayers keep their order: they are closed up over the leavers' rows, then the arrivals,
 * sorted, are merged in from the back, each run of stayers above an arrival moved up at once
 * (floe_world_move_particles, array by array). A decomposition moves a few particles of
 * thousands: packing, sorting and unpacking every owned particle's record cost 1.5 % of a
 * rank's step on dem-settle (bench/RESULTS.md, issue 14 session 33). */
int floe_par_migrate(floe_world *w, floe_par *P, const int *dest) {
    floe_particles *p = &w->p;
    const int m = FLOE_PAR_REC, lo = P->nrep;
    int nleave = 0;
    for (int k = 0; k < P->nown; k++) nleave += dest[k] != P->rank;
    double *out = malloc((size_t)(nleave ? nleave : 1) * m * sizeof *out);
    int *od = malloc((size_t)(nleave ? nleave : 1) * sizeof *od);
    int a = 0;
    for (int k = 0; out && od && k < P->nown; k++)
        if (dest[k] != P->rank) {
            floe_par_pack(p, lo + k, P->gid[lo + k], out + (size_t)a * m);
            od[a++] = dest[k];
        }
    double *in = NULL;
    int nin = 0;
    /* (out of memory here: the route tells every rank) */
    int rc = floe_par_route(P, FLOE_COMM_MIGRATE, out, od, out && od ? nleave : -1, m, &in, &nin);
    free(out); free(od);
    if (rc) return rc;
    P->migrated += nleave;
    const int nkeep = P->nown - nleave, nnew = nkeep + nin;
    rc = par_room(w, P, lo + nnew); /* (the stayers' rows are within the present count) */
    if (rc) { free(in); return rc; }
    int c = lo; /* the stayers closed up over the leavers */
    for (int k = 0; k < P->nown;) {
        int e = k;
        while (e < P->nown && dest[e] == P->rank) e++;
        if (c != lo + k) {
            floe_world_move_particles(w, c, lo + k, e - k);
            memmove(P->gid + c, P->gid + lo + k, (size_t)(e - k) * sizeof *P->gid);
        }
        c += e - k;
        k = e + 1; /* (past the leaver at e) */
    }
    qsort(in, nin, (size_t)m * sizeof *in, cmp_rec);
    for (int s = nkeep, r = nin; r > 0; r--) { /* arrival r - 1 to s0 + r - 1: after stayers [0, s0) and arrivals [0, r - 1) */
        const double *rec = in + (size_t)(r - 1) * m;
        int s0 = 0, s1 = s;
        while (s0 < s1) { /* the first stayer with a larger id */
            const int mid = s0 + (s1 - s0) / 2;
            if ((double)P->gid[lo + mid] < rec[0]) s0 = mid + 1;
            else s1 = mid;
        }
        floe_world_move_particles(w, lo + s0 + r, lo + s0, s - s0);
        memmove(P->gid + lo + s0 + r, P->gid + lo + s0, (size_t)(s - s0) * sizeof *P->gid);
        floe_par_unpack(p, lo + s0 + r - 1, rec, P->gid + lo + s0 + r - 1);
        s = s0;
    }
    free(in);
    P->nown = nnew;
    P->nghost = 0;
    p->n = lo + nnew;
    return FLOE_OK;
}

/* distance from x to the box [lo, hi] (0 inside) */
static double box_dist(const double *x, const double *lo, const double *hi, int dim) {
    double d2 = 0;
    for (int a = 0; a < dim; a++) {
        double e = x[a] < lo[a] ? lo[a] - x[a] : x[a] > hi[a] ? x[a] - hi[a] : 0.0;
        d2 += e * e;
    }
    return sqrt(d2);
}

/* a periodic cell: the copies y + H m (m in {-1, 0, 1}^dim) of a centre y wrapped into the
 * cell (fractional coordinates s) that come within reach of the cell, at most 27; the first
 * is y itself */
static int cell_copies(const floe_cell_state *c, int dim, const double *y, const double wd[3], double reach,
                       double (*out)[3]) {
    double d[3], s[3];
    for (int r = 0; r < 3; r++) d[r] = y[r] - c->o[r];
    for (int r = 0; r < 3; r++) s[r] = c->Hinv[3 * r] * d[0] + c->Hinv[3 * r + 1] * d[1] + c->Hinv[3 * r + 2] * d[2];
    memcpy(out[0], y, 3 * sizeof *y);
    int n = 1;
    const int mz = dim == 3 ? 1 : 0;
    for (int m0 = -1; m0 <= 1; m0++)
        for (int m1 = -1; m1 <= 1; m1++)
            for (int m2 = -mz; m2 <= mz; m2++) {
                const int m[3] = {m0, m1, m2};
                if (!(m0 | m1 | m2)) continue;
                int far = 0;
                for (int r = 0; r < dim && !far; r++) {
                    const double f = s[r] + m[r];
                    far = f * wd[r] < -reach || (f - 1) * wd[r] > reach;
                }
                if (far) continue;
                for (int r = 0; r < 3; r++)
                    out[n][r] = y[r] + c->H[3 * r] * m0 + c->H[3 * r + 1] * m1 + c->H[3 * r + 2] * m2;
                n++;
            }
    return n;
}

int floe_par_ghosts(floe_world *w, floe_par *P, double skin, int bad) {
    floe_particles *p = &w->p;
    const int S = P->size, dim = w->def.dim, lo = P->nrep, hi = P->nrep + P->nown;
    const floe_cell_state *cell = w->cell;
    /* a periodic cell: the owned centres wrapped into it (the bisection cut the wrapped
     * centres), their copies across the faces tested below; otherwise the centres */
    double *y = NULL;
    if (cell && !bad) {
        y = malloc((size_t)(hi > lo ? hi - lo : 1) * 3 * sizeof *y);
        if (!y) bad = 1;
        for (int i = lo; y && i < hi; i++) floe_world_cell_wrap(w, p->x + 3 * i, y + 3 * (i - lo));
    }
#define CENTRE(i) (cell ? y + 3 * ((i) - lo) : p->x + 3 * (i))
    /* each rank's box of owned centres, its largest bounding radius and whether it failed
     * (since the decomposition's last agreement: every rank then returns); an empty rank an
     * empty box (lo > hi: nothing reaches it) */
    double mine[8] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY, 0, bad ? 1.0 : 0.0};
    for (int i = lo; !bad && i < hi; i++) {
        const double *x = CENTRE(i);
        for (int a = 0; a < 3; a++) {
            if (x[a] < mine[a]) mine[a] = x[a];
            if (x[a] > mine[3 + a]) mine[3 + a] = x[a];
        }
        if (p->radius[i] > mine[6]) mine[6] = p->radius[i];
    }
    double *boxes = P->boxes;
    MPI_Allgather(mine, 8, MPI_DOUBLE, boxes, 8, MPI_DOUBLE, P->comm);
    floe_par_count_all(P, FLOE_COMM_GHOST, 8 * sizeof(double));
    for (int r = 0; r < S; r++)
        if (boxes[8 * r + 7] != 0) { free(y); return FLOE_ENOMEM; }
    /* a periodic cell: the widest reach of any pair (the copies that can matter) and the
     * cell's widths */
    double wd[3] = {INFINITY, INFINITY, INFINITY}, reach = 0;
    if (cell) {
        floe_world_cell_widths(w, wd);
        double rmax = 0, rall = 0;
        for (int i = lo; i < hi; i++) rmax = fmax(rmax, p->radius[i]);
        for (int r = 0; r < S; r++) rall = fmax(rall, boxes[8 * r + 6]);
        reach = fmax(rmax + rall, fmax(P->bond_reach, P->pd_reach)) + skin;
    }
    /* a periodic cell: each owned centre's copies (cell_copies), once for every destination:
     * those of particle i at cpx[cpat[i - lo] .. cpat[i - lo + 1]) */
    double (*cpx)[3] = NULL;
    int *cpat = NULL;
    if (cell) {
        cpat = malloc((size_t)(hi - lo + 1) * sizeof *cpat);
        int cap = 2 * (hi - lo) + 27, n = 0;
        cpx = malloc((size_t)cap * sizeof *cpx);
        for (int i = lo; cpat && cpx && i < hi; i++) {
            if (n + 27 > cap) {
                cap *= 2;
                double (*t)[3] = realloc(cpx, (size_t)cap * sizeof *t);
                if (!t) { free(cpx); cpx = NULL; break; }
                cpx = t;
            }
            cpat[i - lo] = n;
            n += cell_copies(cell, dim, CENTRE(i), wd, reach, cpx + n);
        }
        if (!cpat || !cpx) bad = 1;
        else cpat[hi - lo] = n;
    }
    /* the send lists, grouped by destination (the refreshed subsets are chosen again after
     * the list: floe_par_choose_refreshed) */
    P->fgen = -1;
    P->nsend = 0;
    for (int r = 0; r < S; r++) {
        P->sdispl[r] = P->nsend;
        P->scount[r] = 0;
        const double *b = boxes + 8 * r;
        if (bad || r == P->rank || !(b[0] <= b[3])) continue;
        for (int i = lo; !bad && i < hi; i++) {
            /* beam bonds and PD bonds: the partner of a bond evaluated on r is within the
             * bond's length of one of r's centres (bond_reach, pd_reach: the longest,
             * par_beams.c and par_pd.c) */
            const double lim = fmax(p->radius[i] + b[6], fmax(P->bond_reach, P->pd_reach)) + skin;
            int near = 0;
            if (cell) { /* sent once, whichever copy comes near: r's list finds each image */
                for (int c = cpat[i - lo]; c < cpat[i - lo + 1] && !near; c++) near = box_dist(cpx[c], b, b + 3, dim) <= lim;
            } else
                near = box_dist(p->x + 3 * i, b, b + 3, dim) <= lim;
            if (!near) continue;
            if (P->nsend == P->send_cap) {
                int nc = P->send_cap ? 2 * P->send_cap : 256;
                int *t = realloc(P->send_idx, (size_t)nc * sizeof *t);
                if (!t) { bad = 1; break; }
                P->send_idx = t;
                P->send_cap = nc;
            }
            P->send_idx[P->nsend++] = i;
            P->scount[r]++;
        }
    }
#undef CENTRE
    free(y);
    free(cpat);
    free(cpx);
    const int m = FLOE_PAR_REC;
    /* the counts (-1 to every rank: this rank failed; every rank then returns); the room for
     * the refreshed subset of the sent ones */
    if (!bad && floe_par_reserve(&P->sbuf, &P->sbuf_cap, (size_t)P->nsend * m)) bad = 1;
    if (!bad && floe_reserve((void **)&P->fsend, &P->fsend_cap, (size_t)P->nsend, sizeof *P->fsend)) bad = 1;
    for (int r = 0; bad && r < S; r++) P->scount[r] = -1;
    MPI_Alltoall(P->scount, 1, MPI_INT, P->rcount, 1, MPI_INT, P->comm);
    floe_par_count_all(P, FLOE_COMM_GHOST, sizeof(int));
    for (int r = 0; r < S; r++) bad |= P->rcount[r] < 0;
    if (bad) {
        P->nsend = 0;
        for (int r = 0; r < S; r++) P->scount[r] = P->sdispl[r] = P->rcount[r] = P->rdispl[r] = 0;
        return FLOE_ENOMEM;
    }
    int nr = 0;
    for (int r = 0; r < S; r++) { P->rdispl[r] = nr; nr += P->rcount[r]; }
    /* the room for what arrives, agreed before the exchange */
    int nomem = floe_par_reserve(&P->rbuf, &P->rbuf_cap, (size_t)nr * m) || par_room(w, P, hi + nr);
    if (!nomem && nr > P->gmotion_cap) {
        unsigned char *g = realloc(P->gmotion, (size_t)nr);
        if (g) {
            P->gmotion = g;
            P->gmotion_cap = nr;
            w->gmotion = g;
        } else nomem = 1;
    }
    if (!nomem && floe_reserve((void **)&P->frecv, &P->frecv_cap, (size_t)nr, sizeof *P->frecv)) nomem = 1;
    if (floe_par_agree(P, nomem ? FLOE_ENOMEM : FLOE_OK)) return FLOE_ENOMEM;
    for (int k = 0; k < P->nsend; k++) floe_par_pack(p, P->send_idx[k], P->gid[P->send_idx[k]], P->sbuf + (size_t)k * m);
    int *sc = P->gc;
    for (int r = 0; r < S; r++) {
        sc[r] = P->scount[r] * m; sc[S + r] = P->sdispl[r] * m;
        sc[2 * S + r] = P->rcount[r] * m; sc[3 * S + r] = P->rdispl[r] * m;
    }
    MPI_Alltoallv(P->sbuf, sc, sc + S, MPI_DOUBLE, P->rbuf, sc + 2 * S, sc + 3 * S, MPI_DOUBLE, P->comm);
    floe_par_count_v(P, FLOE_COMM_GHOST, P->scount, (long long)m * sizeof(double));
    w->gmotion = P->gmotion;
    for (int k = 0; k < nr; k++) {
        floe_par_unpack(p, hi + k, P->rbuf + (size_t)k * m, P->gid + hi + k);
        P->gmotion[k] = p->motion[hi + k];
        p->motion[hi + k] = FLOE_FIXED; /* a copy: the owner integrates it */
    }
    P->nghost = nr;
    p->n = hi + nr;
    return FLOE_OK;
}

/* The lists of a ghost exchange: every ghost received at the decomposition (the send
 * lists, and the ghosts [g0, n) in the order received) or the refreshed subset of both sides
 * (floe_par_choose_refreshed: fsend, frecv) */
typedef struct ghost_lists {
    const int *sidx;  /* local indices sent, grouped by destination */
    const int *ridx;  /* the ghosts filled, grouped by source (NULL: g0, g0 + 1, ...) */
    const int *cnt;   /* 4 size: send counts, displacements, receive counts, displacements */
    int ns, nr, g0;
} ghost_lists;

static ghost_lists every_ghost(const floe_par *P) {
    return (ghost_lists){P->send_idx, NULL, P->scount, P->nsend, P->nghost, P->nrep + P->nown};
}

/* every = 0: the subset while the list is the one it was chosen for. A list built since on
 * one rank alone cannot happen where a subset was chosen (refresh_all; forces.c refuses a
 * user's provider's rebuild under MPI): were it to, the ranks' counts would differ and MPI
 * would fail loudly (MPI_ERR_TRUNCATE) rather than a rank read stale ghosts */
static ghost_lists lists_of(const floe_world *w, const floe_par *P, int every) {
    if (!every && P->fgen == w->nl.gen)
        return (ghost_lists){P->fsend, P->frecv, P->fcnt, P->nfsend, P->nfrecv, P->nrep + P->nown};
    return every_ghost(P);
}

int floe_par_nrefreshed(const floe_world *w, const floe_par *P) { return lists_of(w, P, 0).nr; }

/* the local index of the k-th ghost an exchange fills */
static inline int ghost_at(const ghost_lists *L, int k) { return L->ridx ? L->ridx[k] : L->g0 + k; }

/* counts and displacements of the ghost exchange in doubles, m per particle (P->gc: the
 * exchanges of a step allocate nothing) */
static int *ghost_counts(const floe_par *P, const ghost_lists *L, int m) {
    const int S = P->size;
    const int *sc = L->cnt;
    int *c = P->gc;
    for (int r = 0; r < S; r++) {
        c[r] = sc[r] * m; c[S + r] = sc[S + r] * m;
        c[2 * S + r] = sc[2 * S + r] * m; c[3 * S + r] = sc[3 * S + r] * m;
    }
    return c;
}

/* what a ghost refresh carries (floe_par_forward_comm): the same on every rank (the laws
 * and any_nonround are; a rank's own beam count is not: any_nonround says whether the world
 * had bonds at the split) */
int floe_par_laws_dashpot(const floe_world *w) {
    int f = 0;
    for (int k = 0; k < w->nmats * w->nmats && !f; k++) f = w->laws[k] && floe_contact_law_info(w->laws[k]).linear_gn > 0;
    return f;
}

static void fwd_what(const floe_world *w, const floe_par *P, int *with_q, int *with_f) {
    *with_q = P->any_nonround;
    *with_f = floe_par_laws_dashpot(w);
}

static int fwd_len(int with_q, int with_f) { return 9 + 4 * with_q + 3 * with_f; }

int floe_par_fwd_doubles(const floe_world *w, const floe_par *P) {
    int wq, wf;
    fwd_what(w, P, &wq, &wf);
    return fwd_len(wq, wf);
}

void floe_par_choose_refreshed(floe_world *w, floe_par *P) {
    const floe_neighbor_list *nl = &w->nl;
    const int S = P->size, g0 = P->nrep + P->nown, ng = P->nghost;
    if (P->refresh_all) return; /* every ghost, at every step (the same on every rank) */
    /* a byte per ghost held (in the order received) and per particle sent (in send_idx's
     * order): the exchange buffers hold FLOE_PAR_REC doubles each (floe_par_ghosts) */
    unsigned char *read = (unsigned char *)P->rbuf, *wanted = (unsigned char *)P->sbuf;
    memset(read, 0, (size_t)ng);
    for (int k = 0; k < nl->npairs; k++) { /* a pair's ends (ghost pairs are never listed) */
        if (nl->pi[k] >= g0) read[nl->pi[k] - g0] = 1;
        if (nl->pj[k] >= g0) read[nl->pj[k] - g0] = 1;
    }
    /* each ghost's byte to its owner: back along the decomposition's exchange */
    int *c = P->gc;
    for (int r = 0; r < S; r++) {
        c[r] = P->rcount[r]; c[S + r] = P->rdispl[r];
        c[2 * S + r] = P->scount[r]; c[3 * S + r] = P->sdispl[r];
    }
    MPI_Alltoallv(read, c, c + S, MPI_UNSIGNED_CHAR, wanted, c + 2 * S, c + 3 * S, MPI_UNSIGNED_CHAR, P->comm);
    floe_par_count_v(P, FLOE_COMM_GHOST, P->rcount, 1);
    int *fc = P->fcnt, ns = 0, nr = 0;
    for (int r = 0; r < S; r++) {
        fc[S + r] = ns;
        for (int k = P->sdispl[r]; k < P->sdispl[r] + P->scount[r]; k++)
            if (wanted[k]) P->fsend[ns++] = P->send_idx[k];
        fc[r] = ns - fc[S + r];
        fc[3 * S + r] = nr;
        for (int k = P->rdispl[r]; k < P->rdispl[r] + P->rcount[r]; k++)
            if (read[k]) P->frecv[nr++] = g0 + k;
        fc[2 * S + r] = nr - fc[3 * S + r];
    }
    P->nfsend = ns;
    P->nfrecv = nr;
    P->fgen = nl->gen;
}

int floe_par_forward_comm(floe_world *w, floe_par *P, int every) {
    floe_particles *p = &w->p;
    int wq, wf;
    fwd_what(w, P, &wq, &wf);
    const int m = fwd_len(wq, wf), S = P->size;
    const ghost_lists L = lists_of(w, P, every);
    /* (the ghosts' choice left FLOE_PAR_REC doubles a ghost both ways: a step's exchanges
     * allocate nothing, and cannot fail on one rank alone) */
    if (floe_par_reserve(&P->sbuf, &P->sbuf_cap, (size_t)L.ns * m) ||
        floe_par_reserve(&P->rbuf, &P->rbuf_cap, (size_t)L.nr * m))
        return FLOE_ENOMEM;
    for (int k = 0; k < L.ns; k++) {
        const int i = L.sidx[k];
        double *r = P->sbuf + (size_t)k * m;
        memcpy(r, p->x + 3 * i, 3 * sizeof *r);
        memcpy(r + 3, p->v + 3 * i, 3 * sizeof *r);
        memcpy(r + 6, p->w + 3 * i, 3 * sizeof *r);
        if (wq) memcpy(r + 9, p->q + 4 * i, 4 * sizeof *r);
        if (wf) memcpy(r + 9 + 4 * wq, p->f + 3 * i, 3 * sizeof *r);
    }
    const int *c = ghost_counts(P, &L, m);
    MPI_Alltoallv(P->sbuf, c, c + S, MPI_DOUBLE, P->rbuf, c + 2 * S, c + 3 * S, MPI_DOUBLE, P->comm);
    floe_par_count_v(P, FLOE_COMM_GHOST, L.cnt, (long long)m * sizeof(double));
    for (int k = 0; k < L.nr; k++) {
        const int i = ghost_at(&L, k);
        const double *r = P->rbuf + (size_t)k * m;
        memcpy(p->x + 3 * i, r, 3 * sizeof *r);
        memcpy(p->v + 3 * i, r + 3, 3 * sizeof *r);
        memcpy(p->w + 3 * i, r + 6, 3 * sizeof *r);
        if (wq) memcpy(p->q + 4 * i, r + 9, 4 * sizeof *r);
        if (wf) memcpy(p->f + 3 * i, r + 9 + 4 * wq, 3 * sizeof *r);
    }
    return FLOE_OK;
}

int floe_par_forward_rows(floe_par *P, double *a, int m) {
    const int S = P->size;
    const ghost_lists L = every_ghost(P);
    if (floe_par_reserve(&P->sbuf, &P->sbuf_cap, (size_t)L.ns * m)) return FLOE_ENOMEM;
    for (int k = 0; k < L.ns; k++) memcpy(P->sbuf + (size_t)k * m, a + (size_t)L.sidx[k] * m, (size_t)m * sizeof *a);
    const int *c = ghost_counts(P, &L, m);
    MPI_Alltoallv(P->sbuf, c, c + S, MPI_DOUBLE, a ? a + (size_t)L.g0 * m : NULL, c + 2 * S, c + 3 * S, MPI_DOUBLE, P->comm);
    floe_par_count_v(P, FLOE_COMM_GHOST, L.cnt, (long long)m * sizeof(double));
    return FLOE_OK;
}

int floe_par_reverse_comm(floe_world *w, floe_par *P) {
    floe_particles *p = &w->p;
    const int m = 6, S = P->size;
    const ghost_lists L = lists_of(w, P, 0);
    /* the reverse of the forward exchange: ghosts send, owners receive */
    if (floe_par_reserve(&P->rbuf, &P->rbuf_cap, (size_t)L.nr * m) ||
        floe_par_reserve(&P->sbuf, &P->sbuf_cap, (size_t)L.ns * m))
        return FLOE_ENOMEM;
    for (int k = 0; k < L.nr; k++) {
        const int i = ghost_at(&L, k);
        memcpy(P->rbuf + (size_t)k * m, p->f + 3 * i, 3 * sizeof(double));
        memcpy(P->rbuf + (size_t)k * m + 3, p->t + 3 * i, 3 * sizeof(double));
    }
    const int *c = ghost_counts(P, &L, m);
    MPI_Alltoallv(P->rbuf, c + 2 * S, c + 3 * S, MPI_DOUBLE, P->sbuf, c, c + S, MPI_DOUBLE, P->comm);
    floe_par_count_v(P, FLOE_COMM_REVERSE, L.cnt + 2 * S, (long long)m * sizeof(double));
    for (int k = 0; k < L.ns; k++) {
        const int i = L.sidx[k];
        const double *r = P->sbuf + (size_t)k * m;
        for (int a = 0; a < 3; a++) {
            p->f[3 * i + a] += r[a];
            p->t[3 * i + a] += r[3 + a];
        }
    }
    return FLOE_OK;
}

/* the slot where id g starts its probe (Fibonacci hashing: ids are dense and ordered, the
 * multiplier spreads neighbours apart) */
static inline int index_slot(long long g, int mask) {
    return (int)(((unsigned long long)g * 0x9E3779B97F4A7C15ull) >> 32) & mask;
}

int floe_par_index_build(const floe_par *P, int n, floe_par_index *ix) {
    ix->key = NULL; ix->loc = NULL; ix->n = 0;
    if (n > (1 << 29)) return FLOE_ENOMEM; /* the table's slots are ints */
    int cap = 16;
    while (cap < 2 * n) cap *= 2;
    ix->key = malloc((size_t)cap * sizeof *ix->key);
    ix->loc = malloc((size_t)cap * sizeof *ix->loc);
    if (!ix->key || !ix->loc) { floe_par_index_free(ix); return FLOE_ENOMEM; }
    ix->n = n;
    ix->mask = cap - 1;
    for (int s = 0; s < cap; s++) ix->key[s] = -1;
    for (int i = 0; i < n; i++) {
        const long long g = P->gid[i];
        if (g < 0) continue;
        int s = index_slot(g, ix->mask);
        while (ix->key[s] >= 0 && ix->key[s] != g) s = (s + 1) & ix->mask;
        if (ix->key[s] < 0) { ix->key[s] = g; ix->loc[s] = i; }
    }
    return FLOE_OK;
}

int floe_par_index_find(const floe_par_index *ix, long long g) {
    if (!ix->n || g < 0) return -1;
    int s = index_slot(g, ix->mask);
    while (ix->key[s] >= 0) {
        if (ix->key[s] == g) return ix->loc[s];
        s = (s + 1) & ix->mask;
    }
    return -1;
}

void floe_par_index_free(floe_par_index *ix) {
    free(ix->key); free(ix->loc);
    ix->key = NULL; ix->loc = NULL; ix->n = 0;
}

void floe_par_free(floe_par *P) {
    if (!P) return;
    if (P->zz) Zoltan_Destroy(&P->zz);
    for (int k = 0; k < P->nouts; k++) floe_observer_destroy(P->outs[k]);
    free(P->outs);
    free(P->bout); free(P->bin); free(P->bpark); free(P->ppin); free(P->servo_buf);
    free(P->gid); free(P->send_idx); free(P->fsend); free(P->frecv); free(P->scount); free(P->boxes); free(P->rcb_sum); free(P->sbuf); free(P->rbuf);
    free(P->cost); free(P->bal_ids); free(P->bal_sz);
    floe_pd_split_free(P->pd_split); /* PD bodies' split (par_pd.c) */
    free(P->pd_counts);
    free(P->gmotion); free(P->mkind); free(P->mgroup); free(P->mids_at); free(P->mids); free(P->mdue); free(P->red_buf);
    if (P->have_sum_min) {
        MPI_Op_free(&P->sum_min);
        MPI_Type_free(&P->wd_type);
    }
    MPI_Comm_free(&P->comm);
    free(P);
}

#else
typedef int floe_par_decomp_unused; /* ISO C: a translation unit is not empty */
#endif
