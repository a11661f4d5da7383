/* par_pd.c - peridynamic bodies of a world split over MPI ranks (docs/parallel.md, "PD
 * bodies across ranks").
 *
 * A PD body's points are particles like any other: owned by the rank whose subdomain holds
 * them, migrated, sent as ghosts. Every rank keeps the body's bond arrays whole (it read the
 * whole scene), and its bond loop (peridynamics/pd_materials.c, floe_pd_body.split) runs
 * the bonds with an owned end whose two points are here, in the serial loop's order: an
 * owned point's force is the unsplit loop's to the bit, and a bond between two ranks is
 * evaluated on both from the same positions, so both break it at the same evaluation. Its
 * energy and breakage count on the rank that owns its row's point (the end of lower index),
 * once over the ranks. The halo reaches the longest acting bond (P->pd_reach, measured at
 * every decomposition; the skin covers the motion until the next one), so every acting bond
 * of an owned point has its other point here (checked at every decomposition: never a
 * silent loss).
 *
 * What a rank does not evaluate goes stale on it: the broken flags of bonds with no owned
 * end, the s0 and last bond forces of points it does not own, the plastic stretches of bonds
 * whose row's point it does not own. At every decomposition, before the migration, they are
 * made whole on every rank (flags OR-ed, the owners' values summed with zeros elsewhere), so that a point arriving at a new owner finds them right. With
 * alpha (LAMMPS' per-point critical stretch) the ghosts' s0 come from their owners at every
 * ghost refresh.
 *
 * LPS reads the other end's dilatation (and q): between its two passes the ghosts get their
 * owners' (lps_theta_sync, one more exchange a step and body).
 *
 * Supported: PMB (constant s_c or alpha, or plastic bonds; surface correction;
 * broken_tension_only either way) and LPS (either influence, with or without the surface
 * correction) in the monolithic and the staggered scheme (core/integrators/step.c, its rows
 * moving with their points), with boundary regions of every kind (fixed, velocity and
 * displacement regions are their points' motion; a body-force region acts on the owners).
 * In a periodic cell each rank sums the virial of the bonds whose row point it owns
 * (floe_pd_bond_forces). Refused with a message: user materials (their loops are their
 * own). The bond arrays whole on every rank and the
 * decomposition's O(bonds) reductions are this first version's limits (docs/parallel.md). */
#include "floe_parallel.h"
#include "par_internal.h"
#include "world_parts.h"
#include "floe_pd.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef FLOE_HAVE_MPI

int floe_par_pd_unsupported(const floe_world *w, char *what, size_t len) {
    if (!w->npd) return 0;
    /* fixed and constant-velocity regions are their points' motion (it travels with them;
     * a ramped one is a motion callback, which follows its point by global id); a body-force
     * region's points
     * take its force on their owners' ranks, its last forces made whole at each
     * decomposition (regions_pack) */
    for (int b = 0; b < w->npd; b++) {
        const floe_pd_body *pb = w->pd[b];
        if (pb->mat.model != FLOE_PD_PMB && pb->mat.model != FLOE_PD_LPS) {
            snprintf(what, len, "a PD body of material %s (PD bodies split over ranks: pmb, lps)",
                     pb->ops && pb->ops->name ? pb->ops->name : "?");
            return 1;
        }
        if (pb->nbond > INT_MAX || 4 * (int64_t)pb->n > INT_MAX) { /* the decompositions' reductions */
            snprintf(what, len, "a PD body of more than %d bonds or %d points", INT_MAX, INT_MAX / 4);
            return 1;
        }
    }
    return 0;
}

/* at least n doubles in *buf (capacity *cap): 0 or FLOE_ENOMEM */
static int grow_buf(double **buf, size_t *cap, size_t n) {
    if (n <= *cap) return FLOE_OK;
    double *t = realloc(*buf, n * sizeof *t);
    if (!t) return FLOE_ENOMEM;
    *buf = t;
    *cap = n;
    return FLOE_OK;
}

/* the halo's reach for body b: the longest intact bond with an owned end, from positions x
 * (3 n; own NULL: every point here and owned), and, where broken bonds push back in
 * compression (broken_tension_only), their reference length: such a bond acts only within
 * it, wherever its points are now */
static double body_reach(const floe_pd_body *b, const double *x, const uint8_t *own) {
    const int comp = b->mat.model == FLOE_PD_PMB && b->mat.broken_tension_only;
    double L = 0, L2 = 0; /* (squares compared: one root at the end, the same value) */
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            const int j = b->partner[k];
            if (own && own[i] != FLOE_PD_OWNED && own[j] != FLOE_PD_OWNED) continue;
            if (b->broken[k]) {
                if (comp && b->len[k] > L) L = b->len[k];
                continue;
            }
            double d[3]; /* intact: both points here (checked at each decomposition) */
            floe_v3_sub(d, x + 3 * (size_t)j, x + 3 * (size_t)i);
            const double r2 = floe_v3_dot(d, d);
            if (r2 > L2) L2 = r2;
        }
    return fmax(L, sqrt(L2));
}

int floe_par_pd_split_reach(floe_world *w, floe_par *P) {
    double L = 0;
    for (int b = 0; b < w->npd; b++) L = fmax(L, body_reach(w->pd[b], w->p.x + 3 * (size_t)w->pd_first[b], NULL));
    P->pd_reach = L; /* the same on every rank: each holds the whole world */
    return FLOE_OK;
}

/* m doubles a ghost from its owner: S->tx (m per entry of the send list, packed by the
 * caller) into S->rx (m per ghost, in the ghosts' order); the buffers sized at the
 * decomposition (floe_par_pd_index, m <= 2): nothing allocated, no other collective */
static void ghost_exchange(floe_par *P, floe_pd_split *S, int m) {
    const int R = P->size;
    int c[4 * FLOE_PAR_PD_SYNC_RANKS], *cc = R <= FLOE_PAR_PD_SYNC_RANKS ? c : P->pd_counts;
    for (int r = 0; r < R; r++) {
        cc[r] = m * P->scount[r]; cc[R + r] = m * P->sdispl[r];
        cc[2 * R + r] = m * P->rcount[r]; cc[3 * R + r] = m * P->rdispl[r];
    }
    MPI_Alltoallv(S->tx, cc, cc + R, MPI_DOUBLE, S->rx, cc + 2 * R, cc + 3 * R, MPI_DOUBLE, P->comm);
    floe_par_count_v(P, FLOE_COMM_GHOST, P->scount, m * (long long)sizeof(double));
}

/* LPS (floe_pd_body.split_sync, between the dilatation and force passes of body b): the
 * owners' theta, and q with the surface correction, to the ghosts. Every rank's body b
 * calls it at the same evaluation (the same scene): collective. */
static void lps_theta_sync(floe_pd_body *pb, void *ctx) {
    floe_world *w = ctx;
    floe_par *P = w->par;
    floe_pd_split *S = P->pd_split;
    int b = 0;
    while (b < w->npd && w->pd[b] != pb) b++;
    const int g0 = P->nrep + P->nown, m = pb->dten ? 2 : 1;
    const double *q = pb->dten ? pb->dten + 9 * (size_t)pb->n : NULL;
    for (int k = 0; k < P->nsend; k++) {
        const int i = P->send_idx[k], mine = w->pd_of[i] == b;
        const int l = mine ? floe_pd_local(w, b, i) : 0;
        S->tx[(size_t)m * k] = mine ? pb->theta[l] : 0.0;
        if (q) S->tx[(size_t)m * k + 1] = mine ? q[l] : 0.0;
    }
    ghost_exchange(P, S, m);
    double *qq = pb->dten ? pb->dten + 9 * (size_t)pb->n : NULL;
    for (int k = 0; k < P->nghost; k++) {
        const int i = g0 + k;
        if (w->pd_of[i] != b) continue;
        const int l = floe_pd_local(w, b, i);
        pb->theta[l] = S->rx[(size_t)m * k];
        if (qq) qq[l] = S->rx[(size_t)m * k + 1];
    }
}

int floe_par_pd_index(floe_world *w, floe_par *P) {
    if (!w->npd) return FLOE_OK;
    floe_particles *p = &w->p;
    int rc = FLOE_OK;
    if (!P->pd_split && !(P->pd_split = floe_pd_split_new(w))) rc = FLOE_ENOMEM;
    if (!rc) {
        int *po = realloc(w->pd_of, (size_t)(p->n ? p->n : 1) * sizeof *po);
        if (!po) rc = FLOE_ENOMEM;
        else {
            w->pd_of = po;
            w->pd_npts_alloc = p->n;
        }
    }
    int bad = 0;
    if (!rc) {
        floe_pd_split *S = P->pd_split;
        S->gid = P->gid;
        const int hi = P->nrep + P->nown;
        for (int b = 0; b < w->npd; b++) {
            memset(S->mask[b], 0, (size_t)w->pd[b]->n);
            for (int q = 0; q < w->pd[b]->n; q++) S->loc[b][q] = -1;
        }
        for (int i = 0; i < p->n; i++) {
            /* the body whose ids hold g: the last first id <= g (bodies take ids in order) */
            const long long g = P->gid[i];
            int lo = 0, up = w->npd;
            while (lo < up) {
                const int mid = (lo + up) / 2;
                if (w->pd_first[mid] <= g) lo = mid + 1;
                else up = mid;
            }
            const int b = lo - 1;
            w->pd_of[i] = -1;
            if (b < 0 || g >= w->pd_first[b] + w->pd[b]->n) continue;
            const int q = (int)(g - w->pd_first[b]);
            w->pd_of[i] = b;
            S->loc[b][q] = i;
            S->mask[b][q] = i >= P->nrep && i < hi ? FLOE_PD_OWNED : FLOE_PD_GHOST;
        }
        /* every acting bond with an owned end has both points here (the halo's promise) */
        for (int b = 0; b < w->npd && !bad; b++) {
            const floe_pd_body *pb = w->pd[b];
            const uint8_t *m = S->mask[b];
            for (int i = 0; i < pb->n && !bad; i++)
                for (int64_t k = pb->off[i]; k < pb->off[i + 1]; k++) {
                    const int j = pb->partner[k];
                    if ((m[i] == FLOE_PD_OWNED || m[j] == FLOE_PD_OWNED) && (!m[i] || !m[j]) && !pb->broken[k]) {
                        bad = 1;
                        break;
                    }
                }
            w->pd[b]->split = S->mask[b];
            if (pb->mat.model == FLOE_PD_LPS) {
                w->pd[b]->split_sync = lps_theta_sync;
                w->pd[b]->split_ctx = w;
            }
        }
        w->pd_split = S;
        /* the ghost exchanges' buffers (LPS, alpha), and their counts beyond FLOE_PAR_PD_SYNC_RANKS ranks */
        if (grow_buf(&S->tx, &S->tx_cap, 2 * (size_t)P->nsend) || grow_buf(&S->rx, &S->rx_cap, 2 * (size_t)P->nghost))
            rc = FLOE_ENOMEM;
        if (!rc && P->size > FLOE_PAR_PD_SYNC_RANKS && !P->pd_counts &&
            !(P->pd_counts = malloc((size_t)4 * P->size * sizeof *P->pd_counts)))
            rc = FLOE_ENOMEM;
    }
    int mine[2] = {rc, bad}, all[2];
    MPI_Allreduce(mine, all, 2, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof mine);
    if (all[0]) return floe_world_error(w, all[0], "MPI decomposition: PD bodies: out of memory");
    if (all[1])
        return floe_world_error(w, FLOE_EINVAL, "MPI decomposition: internal: an intact PD bond's point is not on the rank "
                                "that evaluates it (docs/parallel.md)");
    return FLOE_OK;
}

/* 1 when body b keeps a per-point s0 (alpha) */
static int has_s0(const floe_pd_body *b) { return b->s0 && b->s_c > 0; }

/* the plastic stretch of each bond whose row's point is owned (own NULL: every one), zeros
 * elsewhere, into sp (nbond floats): the rows' owners' values, to be summed over the ranks */
static void splast_owned(const floe_pd_body *pb, const uint8_t *own, float *sp) {
    for (int i = 0; i < pb->n; i++) {
        const int o = !own || own[i] == FLOE_PD_OWNED;
        for (int64_t k = pb->off[i]; k < pb->off[i + 1]; k++) sp[k] = o ? pb->splast[k] : 0.0f;
    }
}

/* body b's state as its owners hold it, zeros elsewhere, to be summed over the ranks (own
 * NULL: all here): per point its last bond force and s0 (alpha), 3 or 4 doubles, then with
 * plastic bonds the plastic stretch of each bond whose row's point is owned (nbond floats);
 * NULL when out of memory */
static double *owned_values(const floe_world *w, const floe_pd_body *pb, int off, const uint8_t *own) {
    const size_t n = (size_t)pb->n;
    const int ns = has_s0(pb) ? 1 : 0, mv = 3 + ns;
    double *v = malloc(n * mv * sizeof *v + (pb->splast ? (size_t)pb->nbond * sizeof(float) : 0) + 1);
    if (!v) return NULL;
    const double *fold = w->pd_fold + 3 * (size_t)off;
    for (size_t q = 0; q < n; q++) {
        const int o = !own || own[q] == FLOE_PD_OWNED;
        for (int a = 0; a < 3; a++) v[q * mv + a] = o ? fold[3 * q + a] : 0.0;
        if (ns) v[q * mv + 3] = o ? pb->s0[q] : 0.0;
    }
    if (pb->splast) splast_owned(pb, own, (float *)(v + n * mv));
    return v;
}

/* the body-force regions' last forces (the ledger's trapezoid work, world_pd.c
 * floe_pd_bc_forces): 3 doubles a region point, regions in order */
static size_t regions_len(const floe_world *w) {
    size_t n = 0;
    for (int r = 0; r < w->npd_bc; r++)
        if (w->pd_bc[r]->fold) n += 3 * (size_t)w->pd_bc[r]->n;
    return n;
}

/* ... as the points' owners hold them, zeros elsewhere (S NULL: all here), to be summed over
 * the ranks */
static void regions_pack(const floe_world *w, const floe_pd_split *S, double *v) {
    for (int r = 0; r < w->npd_bc; r++) {
        const floe_pd_bc_rec *R = w->pd_bc[r];
        if (!R->fold) continue;
        const int f0 = w->pd_first[R->body];
        for (int a = 0; a < R->n; a++, v += 3) {
            const int o = !S || S->mask[R->body][R->pts[a] - f0] == FLOE_PD_OWNED;
            for (int k = 0; k < 3; k++) v[k] = o ? R->fold[3 * a + k] : 0.0;
        }
    }
}

static void regions_unpack(floe_world *w, const double *v) {
    for (int r = 0; r < w->npd_bc; r++) {
        floe_pd_bc_rec *R = w->pd_bc[r];
        if (!R->fold) continue;
        memcpy(R->fold, v, 3 * (size_t)R->n * sizeof *v);
        v += 3 * (size_t)R->n;
    }
}

/* the regions made whole on every rank (to root only: into M on rank 0, M NULL elsewhere),
 * the same collective on every rank; FLOE_OK or FLOE_ENOMEM agreed */
static int regions_sum(floe_world *w, floe_par *P, floe_world *M, int to_root) {
    const size_t n = regions_len(w);
    if (!n) return FLOE_OK;
    double *v = malloc(n * sizeof *v);
    int bad = !v, any;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_LOR, P->comm);
    if (any) { free(v); return FLOE_ENOMEM; }
    regions_pack(w, P->pd_split, v);
    if (to_root) {
        MPI_Reduce(P->rank == 0 ? MPI_IN_PLACE : v, v, (int)n, MPI_DOUBLE, MPI_SUM, 0, P->comm);
        floe_par_count_to_root(P, FLOE_COMM_OUTPUT, (long long)(n * sizeof *v));
        if (M) regions_unpack(M, v);
    } else {
        MPI_Allreduce(MPI_IN_PLACE, v, (int)n, MPI_DOUBLE, MPI_SUM, P->comm);
        floe_par_count_allreduce(P, FLOE_COMM_MIGRATE, (long long)(n * sizeof *v));
        regions_unpack(w, v);
    }
    free(v);
    return FLOE_OK;
}

/* the bonds broken since the last decomposition, to every rank: each is reported by the rank
 * that owns its row's point (that rank evaluated it at every evaluation since: the halo's
 * promise), as a global bond id (the bodies' bonds numbered in order), gathered by every
 * rank and set there; the flags then equal the snapshot S->snap everywhere. O(breaks) on
 * the wire (the flags were an MPI_Allreduce(BOR) of every bond until session 19); the scan of
 * the owned rows is local */
static int flags_sync(floe_world *w, floe_par *P) {
    floe_pd_split *S = P->pd_split;
    const int R = P->size;
    long long nnew = 0, base = 0;
    for (int b = 0; b < w->npd; b++) {
        const floe_pd_body *pb = w->pd[b];
        const uint8_t *m = S->mask[b], *sn = S->snap[b];
        for (int i = 0; i < pb->n; i++)
            if (m[i] == FLOE_PD_OWNED)
                for (int64_t k = pb->off[i]; k < pb->off[i + 1]; k++) nnew += pb->broken[k] & !sn[k];
    }
    /* the lists' counts (-1: a rank out of memory, said to all by the gather itself) and
     * the ids, on the stack when few (a decomposition usually finds none or a few) */
    enum { FEW = 256 };
    long long few_mine[FEW], few_all[FEW];
    int cdv[2 * FLOE_PAR_PD_SYNC_RANKS], *cd = R <= FLOE_PAR_PD_SYNC_RANKS ? cdv : P->pd_counts;
    long long *mine = nnew <= FEW ? few_mine : nnew <= INT_MAX ? malloc((size_t)nnew * sizeof *mine) : NULL;
    int cnt = 0;
    for (int b = 0; mine && b < w->npd; base += w->pd[b]->nbond, b++) {
        const floe_pd_body *pb = w->pd[b];
        const uint8_t *m = S->mask[b], *sn = S->snap[b];
        for (int i = 0; i < pb->n; i++)
            if (m[i] == FLOE_PD_OWNED)
                for (int64_t k = pb->off[i]; k < pb->off[i + 1]; k++)
                    if (pb->broken[k] && !sn[k]) mine[cnt++] = base + k;
    }
    const int said = mine ? cnt : -1;
    MPI_Allgather(&said, 1, MPI_INT, cd, 1, MPI_INT, P->comm);
    floe_par_count_all(P, FLOE_COMM_MIGRATE, sizeof said);
    long long tot = 0;
    int bad = 0;
    for (int r = 0; r < R; r++) {
        bad |= cd[r] < 0;
        cd[R + r] = (int)tot;
        tot += cd[r] > 0 ? cd[r] : 0;
    }
    long long *all = NULL;
    if (!bad && tot > FEW) { /* the same tot on every rank: agree on the allocation */
        all = tot <= INT_MAX ? malloc((size_t)tot * sizeof *all) : NULL;
        int mb = !all;
        MPI_Allreduce(&mb, &bad, 1, MPI_INT, MPI_LOR, P->comm);
        floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof mb);
    } else
        all = few_all;
    if (bad) {
        if (mine != few_mine) free(mine);
        if (all != few_all) free(all);
        return FLOE_ENOMEM;
    }
    MPI_Allgatherv(mine, cnt, MPI_LONG_LONG, all, cd, cd + R, MPI_LONG_LONG, P->comm);
    floe_par_count_all(P, FLOE_COMM_MIGRATE, (long long)cnt * (long long)sizeof *mine);
    for (long long e = 0; e < tot; e++) {
        long long g = all[e];
        int b = 0;
        while (b < w->npd - 1 && g >= w->pd[b]->nbond) { g -= w->pd[b]->nbond; b++; }
        w->pd[b]->broken[g] = 1;
        S->snap[b][g] = 1;
    }
    if (mine != few_mine) free(mine);
    if (all != few_all) free(all);
    return FLOE_OK;
}

int floe_par_pd_sync(floe_world *w, floe_par *P) {
    const floe_pd_split *S = P->pd_split;
    if (!w->npd || !S) return FLOE_OK;
    double L = 0;
    /* the ghosts at their present state (the halo's reach reads them): one more refresh per
     * decomposition, only in a world with PD bodies */
    if (floe_par_forward_comm(w, P, 1)) return floe_world_error(w, FLOE_ENOMEM, "MPI decomposition: out of memory");
    floe_pd_split_gather(w);
    /* the broken flags: a bond breaks once and never heals */
    if (flags_sync(w, P)) return floe_world_error(w, FLOE_ENOMEM, "MPI decomposition: PD bodies: out of memory");
    for (int b = 0; b < w->npd; b++) {
        floe_pd_body *pb = w->pd[b];
        const uint8_t *m = S->mask[b];
        /* plastic bonds: the plastic stretches of the rows' owners, a sum with zeros
         * elsewhere (O(bonds): every yielding bond's changes at every evaluation) */
        if (pb->splast && pb->nbond > 0) {
            float *sp = malloc((size_t)pb->nbond * sizeof *sp);
            int bad = !sp, any;
            MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_LOR, P->comm);
            if (any) { free(sp); return floe_world_error(w, FLOE_ENOMEM, "MPI decomposition: PD bodies: out of memory"); }
            splast_owned(pb, m, sp);
            MPI_Allreduce(MPI_IN_PLACE, sp, (int)pb->nbond, MPI_FLOAT, MPI_SUM, P->comm);
            floe_par_count_allreduce(P, FLOE_COMM_MIGRATE, pb->nbond * (long long)sizeof(float));
            memcpy(pb->splast, sp, (size_t)pb->nbond * sizeof *sp);
            free(sp);
        }
        /* the halo's reach: the longest acting bond with an owned end, now */
        L = fmax(L, body_reach(pb, S->xb[b], m));
    }
    if (regions_sum(w, P, NULL, 0)) return floe_world_error(w, FLOE_ENOMEM, "MPI decomposition: PD regions: out of memory");
    MPI_Allreduce(&L, &P->pd_reach, 1, MPI_DOUBLE, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof L);
    return FLOE_OK;
}

/* body b's first point in w->pd_fold (the bodies' points in order) */
static size_t fold_off(const floe_world *w, int b) {
    size_t o = 0;
    for (int c = 0; c < b; c++) o += (size_t)w->pd[c]->n;
    return o;
}

/* each owned PD point leaving (dest, from the bisection) takes its last bond force (the
 * ledger's trapezoid) and its s0 (alpha) to its new owner: O(points moved). Its ghosts get
 * their s0 after the ghosts are chosen (floe_par_pd_s0_refresh) */
int floe_par_pd_out(floe_world *w, floe_par *P, const int *dest) {
    const floe_pd_split *S = P->pd_split;
    if (!w->npd || !S) return FLOE_OK; /* the first split: every rank holds the same */
    const int lo = P->nrep, hi = P->nrep + P->nown, M = 5; /* gid, fold, s0 */
    int nl = 0;
    for (int i = lo; i < hi; i++) nl += w->pd_of[i] >= 0 && dest[i - lo] != P->rank;
    double *it = malloc((size_t)(nl ? nl : 1) * M * sizeof *it);
    int *dd = malloc((size_t)(nl ? nl : 1) * sizeof *dd);
    const int nomem = !it || !dd; /* (then nothing sent; the failure agreed after the route) */
    int k = 0, any;
    for (int i = lo; i < hi && !nomem; i++) {
        const int b = w->pd_of[i];
        if (b < 0 || dest[i - lo] == P->rank) continue;
        const int q = floe_pd_local(w, b, i);
        const double *fo = w->pd_fold + 3 * ((size_t)fold_off(w, b) + q);
        double *r = it + (size_t)k * M;
        r[0] = (double)P->gid[i];
        r[1] = fo[0]; r[2] = fo[1]; r[3] = fo[2];
        r[4] = has_s0(w->pd[b]) ? w->pd[b]->s0[q] : 0.0;
        dd[k++] = dest[i - lo];
    }
    double *in = NULL;
    int nin = 0;
    int rc = floe_par_route(P, FLOE_COMM_MIGRATE, it, dd, k, M, &in, &nin);
    free(it); free(dd);
    const int bad = nomem || rc != FLOE_OK;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_LOR, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof bad);
    if (any) { free(in); return floe_world_error(w, FLOE_ENOMEM, "MPI decomposition: PD bodies: out of memory"); }
    for (int e = 0; e < nin; e++) {
        const double *r = in + (size_t)e * M;
        const long long g = (long long)r[0];
        int b = w->npd - 1; /* the body whose ids hold g: the last first id <= g */
        while (b > 0 && w->pd_first[b] > g) b--;
        const int q = (int)(g - w->pd_first[b]);
        double *fo = w->pd_fold + 3 * ((size_t)fold_off(w, b) + q);
        fo[0] = r[1]; fo[1] = r[2]; fo[2] = r[3];
        if (has_s0(w->pd[b])) w->pd[b]->s0[q] = r[4];
    }
    free(in);
    return FLOE_OK;
}

int floe_par_pd_s0_refresh(floe_world *w, floe_par *P) {
    int any = 0;
    for (int b = 0; b < w->npd; b++) any |= has_s0(w->pd[b]);
    if (!any || !P->pd_split) return FLOE_OK; /* the same on every rank: the same scene */
    floe_pd_split *S = P->pd_split;
    const int g0 = P->nrep + P->nown;
    for (int k = 0; k < P->nsend; k++) {
        const int i = P->send_idx[k], b = w->pd_of[i];
        S->tx[k] = b >= 0 && has_s0(w->pd[b]) ? w->pd[b]->s0[floe_pd_local(w, b, i)] : 0.0;
    }
    ghost_exchange(P, S, 1);
    for (int k = 0; k < P->nghost; k++) {
        const int i = g0 + k, b = w->pd_of[i];
        if (b >= 0 && has_s0(w->pd[b])) w->pd[b]->s0[floe_pd_local(w, b, i)] = S->rx[k];
    }
    return FLOE_OK;
}

int floe_par_pd_gather(floe_world *w, floe_par *P, floe_world *M) {
    if (!w->npd) return FLOE_OK;
    int miss = 0;
    if (P->rank == 0 && M && M->npd != w->npd) miss = 1;
    for (int b = 0; !miss && P->rank == 0 && M && b < w->npd; b++)
        if (M->pd[b]->n != w->pd[b]->n || M->pd[b]->nbond != w->pd[b]->nbond) miss = 1;
    if (P->rank == 0 && M && !miss && M->npd_bc != w->npd_bc) miss = 1;
    for (int r = 0; !miss && P->rank == 0 && M && r < w->npd_bc; r++)
        if (M->pd_bc[r]->n != w->pd_bc[r]->n || !M->pd_bc[r]->fold != !w->pd_bc[r]->fold) miss = 1;
    MPI_Bcast(&miss, 1, MPI_INT, 0, P->comm);
    if (miss) return floe_world_error(w, FLOE_EINVAL, "MPI: the PD bodies gathered do not match the mirror's (another scene?)");
    const floe_pd_split *S = P->pd_split;
    const int root = P->rank == 0 && M;
    /* the ledger's per-body terms: sums */
    double *e = malloc((size_t)2 * w->npd * sizeof *e);
    int bad = !e, anybad;
    MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_LOR, P->comm);
    if (anybad) { free(e); return floe_world_error(w, FLOE_ENOMEM, "MPI: gathering the PD bodies: out of memory"); }
    if (regions_sum(w, P, root ? M : NULL, 1)) {
        free(e);
        return floe_world_error(w, FLOE_ENOMEM, "MPI: gathering the PD regions: out of memory");
    }
    for (int b = 0; b < w->npd; b++) {
        e[2 * b] = w->pd_eold[b];
        e[2 * b + 1] = b < w->pd_diss_n ? w->pd_diss[b] : 0.0;
    }
    MPI_Reduce(P->rank == 0 ? MPI_IN_PLACE : e, e, 2 * w->npd, MPI_DOUBLE, MPI_SUM, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, 2LL * w->npd * sizeof *e);
    if (root)
        for (int b = 0; b < w->npd; b++) {
            M->pd_eold[b] = e[2 * b];
            if (b < M->pd_diss_n) M->pd_diss[b] = e[2 * b + 1];
        }
    free(e);
    for (int b = 0, off = 0; b < w->npd; off += w->pd[b]->n, b++) {
        floe_pd_body *pb = w->pd[b], *mb = root ? M->pd[b] : NULL;
        const size_t n = (size_t)pb->n;
        if (pb->nbond > 0) { /* (rank 0 without a world to fill: into its own, already whole there) */
            uint8_t *dst = root ? mb->broken : P->rank == 0 ? pb->broken : NULL;
            MPI_Reduce(P->rank == 0 && !root ? MPI_IN_PLACE : pb->broken, dst, (int)pb->nbond, MPI_BYTE, MPI_BOR, 0,
                       P->comm);
            floe_par_count_to_root(P, FLOE_COMM_OUTPUT, pb->nbond);
        }
        const int ns = has_s0(pb) ? 1 : 0, mv = 3 + ns;
        double *v = owned_values(w, pb, off, S ? S->mask[b] : NULL);
        bad = !v;
        MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_LOR, P->comm);
        if (anybad) { free(v); return floe_world_error(w, FLOE_ENOMEM, "MPI: gathering the PD bodies: out of memory"); }
        MPI_Reduce(P->rank == 0 ? MPI_IN_PLACE : v, v, (int)(n * mv), MPI_DOUBLE, MPI_SUM, 0, P->comm);
        floe_par_count_to_root(P, FLOE_COMM_OUTPUT, (long long)(n * mv * sizeof *v));
        float *sp = (float *)(v + n * mv);
        if (pb->splast) {
            MPI_Reduce(P->rank == 0 ? MPI_IN_PLACE : sp, sp, (int)pb->nbond, MPI_FLOAT, MPI_SUM, 0, P->comm);
            floe_par_count_to_root(P, FLOE_COMM_OUTPUT, pb->nbond * (long long)sizeof(float));
        }
        if (root) {
            double *mf = M->pd_fold + 3 * (size_t)off;
            int64_t nb = 0;
            for (size_t q = 0; q < n; q++) {
                for (int a = 0; a < 3; a++) mf[3 * q + a] = v[q * mv + a];
                if (ns && mb->s0) mb->s0[q] = v[q * mv + 3];
            }
            if (pb->splast && mb->splast) memcpy(mb->splast, sp, (size_t)pb->nbond * sizeof(float));
            for (int64_t k = 0; k < mb->nbond; k++) nb += mb->broken[k];
            mb->nbroken = nb;
            M->pd_nbroken_seen[b] = (long long)nb;
        }
        free(v);
    }
    return FLOE_OK;
}

#else
typedef int floe_par_pd_unused; /* ISO C: a translation unit is not empty */
#endif
