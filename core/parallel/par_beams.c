/* par_beams.c - beam bonds of a world split over MPI ranks (docs/parallel.md, "Beam bonds").
 *
 * A bond joins two bounded particles i < j by global id (the set stores them so). It is
 * evaluated, and its whole record kept, on the rank that owns its anchor i, the end of lower
 * global id: the rule of contact pairs, so the rank that would list the pair holds the
 * bond that excludes it. The other end j is there, owned or a ghost: the ghost halo reaches
 * at least the longest intact bond (P->bond_reach, floe_par_ghosts). The force and torques
 * on a ghost end go back to its owner with the contacts' (floe_par_reverse_comm).
 *
 * At every decomposition each rank exports its bonds as records (gid_i, gid_j, the bond's
 * bytes: section, reference frame, strengths, last forces and energy, broken flag and
 * break), routed to the new owner of the anchor, and rebuilds its set from those it
 * receives, in (gid_i, gid_j) order (the serial set's order), ends renumbered to the new
 * local indices. A broken bond whose other end is not here any more is parked (kept as a
 * record, routed with the anchor at every decomposition, counted); an intact one is an
 * error (the halo did not reach it: never a silent loss). */
#include "floe_parallel.h"
#include "par_internal.h"
#include "world_parts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef FLOE_HAVE_MPI

/* doubles per record: gid_i, gid_j, then the bond's bytes */
static int brec_len(void) { return 2 + (int)((floe_beam_set_rec_size() + sizeof(double) - 1) / sizeof(double)); }

/* the set's bonds (ends by gid(k)) whose anchor is mine, and the parked records, as records
 * into a fresh array; *reach: the longest intact bond among them (positions of this store) */
static int beams_export(const floe_world *w, const long long *gid, const unsigned char *mine_by_gid, const double *park,
                        int npark, double **out, int *nout, double *reach) {
    const floe_beam_set *s = w->beams;
    const floe_particles *p = &w->p;
    const int m = brec_len(), nb = floe_beam_set_count(s);
    double *r = calloc((size_t)(nb + npark ? nb + npark : 1) * m, sizeof *r);
    if (!r) return FLOE_ENOMEM;
    int cnt = 0;
    double L = 0;
    for (int k = 0; k < nb; k++) {
        double *e = r + (size_t)cnt * m;
        int i, j, broken;
        floe_beam_set_rec_get(s, k, e + 2, &i, &j, &broken);
        const long long gi = gid ? gid[i] : i, gj = gid ? gid[j] : j;
        if (mine_by_gid && !mine_by_gid[gi]) continue;
        e[0] = (double)gi;
        e[1] = (double)gj;
        if (!broken) {
            double d[3];
            floe_v3_sub(d, p->x + 3 * j, p->x + 3 * i);
            L = fmax(L, floe_v3_norm(d));
        }
        cnt++;
    }
    if (npark) memcpy(r + (size_t)cnt * m, park, (size_t)npark * m * sizeof *r);
    *out = r;
    *nout = cnt + npark;
    *reach = L;
    return FLOE_OK;
}

int floe_par_beams_split(floe_world *w, floe_par *P, const unsigned char *mine) {
    if (!w->beams) return FLOE_OK;
    free(P->bout);
    P->bout = NULL;
    return beams_export(w, NULL, mine, NULL, 0, &P->bout, &P->nbout, &P->bout_reach);
}

int floe_par_beams_out(floe_world *w, floe_par *P, const int *dest) {
    if (!w->beams) return FLOE_OK;
    const int m = brec_len(), lo = P->nrep, hi = P->nrep + P->nown;
    double *recs = P->bout, reach = P->bout_reach;
    int n = P->nbout, rc = FLOE_OK;
    P->bout = NULL;
    P->nbout = 0;
    if (!recs) {
        /* the ghosts at their present state: the bonds' lengths now (one more refresh per
         * decomposition, only in a world with bonds) */
        rc = floe_par_forward_comm(w, P, 1);
        if (!rc) rc = beams_export(w, P->gid, NULL, P->bpark, P->npark, &recs, &n, &reach);
        if (rc) n = 0; /* the collectives below still run: every rank meets them */
    }
    free(P->bpark);
    P->bpark = NULL;
    P->npark = 0;
    /* the halo: the longest intact bond over all ranks */
    MPI_Allreduce(&reach, &P->bond_reach, 1, MPI_DOUBLE, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof reach);
    int *hd = malloc((size_t)(n ? n : 1) * sizeof *hd);
    if (!hd) { rc = FLOE_ENOMEM; n = 0; }
    int lost = 0;
    for (int k = 0; k < n; k++) { /* each bond to its anchor's new owner (owned here, in gid order) */
        const long long g = (long long)recs[(size_t)k * m];
        int a = lo, b = hi;
        while (a < b) {
            int c = (a + b) / 2;
            if (P->gid[c] < g) a = c + 1;
            else b = c;
        }
        if (a < hi && P->gid[a] == g) hd[k] = dest[a - lo];
        else { hd[k] = P->rank; lost++; }
    }
    free(P->bin);
    P->bin = NULL;
    P->nbin = 0;
    int r2 = floe_par_route(P, FLOE_COMM_MIGRATE, recs, hd, n, m, &P->bin, &P->nbin);
    free(recs);
    free(hd);
    P->blost = lost; /* reported by floe_par_beams_in, on every rank */
    /* agreed: a rank that failed alone would skip the decomposition's collectives */
    int mine = rc ? rc : r2, all = mine;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof mine);
    return all;
}

static int cmp_gid2(const void *a, const void *b) {
    const double *x = a, *y = b;
    if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
    return (x[1] > y[1]) - (x[1] < y[1]);
}

int floe_par_beams_in(floe_world *w, floe_par *P) {
    if (!w->beams) return FLOE_OK;
    const int m = brec_len(), n = P->nbin, own_hi = P->nrep + P->nown;
    double *in = P->bin;
    int rc = FLOE_OK, bad = P->blost ? 1 : 0;
    floe_par_index ix = {0};
    int *ii = malloc((size_t)(n ? n : 1) * sizeof *ii), *jj = malloc((size_t)(n ? n : 1) * sizeof *jj);
    double *keep = malloc((size_t)(n ? n : 1) * m * sizeof *keep);
    double *park = malloc((size_t)(n ? n : 1) * m * sizeof *park);
    if (!ii || !jj || !keep || !park || floe_par_index_build(P, w->p.n, &ix)) rc = FLOE_ENOMEM;
    int nk = 0, np = 0;
    if (!rc) {
        qsort(in, (size_t)n, (size_t)m * sizeof *in, cmp_gid2); /* the serial set's order */
        for (int k = 0; k < n; k++) {
            const double *e = in + (size_t)k * m;
            const int i = floe_par_index_find(&ix, (long long)e[0]), j = floe_par_index_find(&ix, (long long)e[1]);
            if (i < P->nrep || i >= own_hi) { bad = 1; continue; } /* the anchor is owned here */
            if (j >= 0) {
                ii[nk] = i;
                jj[nk] = j;
                memcpy(keep + (size_t)nk++ * m, e, (size_t)m * sizeof *e);
            } else if (floe_beam_rec_broken(e + 2))
                memcpy(park + (size_t)np++ * m, e, (size_t)m * sizeof *e);
            else
                bad = 2; /* an intact bond beyond the halo */
        }
    }
    if (!rc && !bad) rc = floe_beam_set_rec_replace(w->beams, (const unsigned char *)(keep + 2), (size_t)m * sizeof *keep, ii, jj, nk);
    if (!rc && !bad) rc = floe_beam_set_index(w->beams, w->p.n);
    floe_par_index_free(&ix);
    free(ii); free(jj); free(keep);
    free(P->bin);
    P->bin = NULL;
    P->nbin = 0;
    if (!rc && !bad) {
        P->bpark = park;
        P->npark = np;
    } else
        free(park);
    int mine[2] = {rc, bad}, all[2];
    MPI_Allreduce(mine, all, 2, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof mine);
    if (all[1])
        return floe_world_error(w, FLOE_EINVAL, "MPI decomposition: internal: a beam bond's %s is not on the rank that "
                                "evaluates it (docs/parallel.md)", all[1] == 1 ? "anchor" : "partner");
    return all[0] ? floe_world_error(w, all[0], "MPI decomposition: beam bonds failed (out of memory)") : FLOE_OK;
}

int floe_par_beams_gather(floe_world *w, floe_par *P, floe_world *M) {
    if (!w->beams) return FLOE_OK;
    const int m = brec_len();
    double *recs = NULL, reach;
    int n = 0, rc = beams_export(w, P->gid, NULL, P->bpark, P->npark, &recs, &n, &reach);
    if (rc) n = 0;
    int bad = rc != 0, anybad;
    MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_LOR, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (anybad) { free(recs); return floe_world_error(w, FLOE_ENOMEM, "MPI: gathering the beam bonds: out of memory"); }
    double *rb;
    int tot;
    if (floe_par_gather_root(P, FLOE_COMM_OUTPUT, recs, n * m, &rb, &tot)) {
        free(recs);
        return floe_world_error(w, FLOE_ENOMEM, "MPI: gathering the beam bonds: out of memory on rank 0");
    }
    int miss = 0;
    if (P->rank == 0 && M && M->beams) {
        if (!rb || tot / m != floe_beam_set_count(M->beams)) miss = 1;
        for (int k = 0; k < tot / m; k++) {
            const double *e = rb + (size_t)k * m;
            const int b = floe_beam_set_find(M->beams, (int)e[0], (int)e[1]);
            if (b < 0 || floe_beam_set_rec_put(M->beams, b, e + 2)) miss = 1;
        }
    }
    free(recs); free(rb);
    return miss ? floe_world_error(w, FLOE_EINVAL, "MPI outputs: the beam bonds gathered do not match the mirror's "
                                   "(another scene?)")
                : FLOE_OK;
}

int floe_world_parallel_beam_counts(const floe_world *w, long long *bonds, long long *broken) {
    const floe_par *P = w->par;
    if (!P) {
        *bonds = floe_beam_set_count(w->beams);
        *broken = floe_beam_set_broken(w->beams);
        return FLOE_OK;
    }
    double v[2] = {floe_beam_set_count(w->beams) + P->npark, floe_beam_set_broken(w->beams) + P->npark};
    MPI_Allreduce(MPI_IN_PLACE, v, 2, MPI_DOUBLE, MPI_SUM, P->comm);
    floe_par_count_allreduce(w->par, FLOE_COMM_REDUCE, sizeof v);
    *bonds = (long long)v[0];
    *broken = (long long)v[1];
    return FLOE_OK;
}

#else /* serial build */

int floe_world_parallel_beam_counts(const floe_world *w, long long *bonds, long long *broken) {
    *bonds = floe_beam_set_count(w->beams);
    *broken = floe_beam_set_broken(w->beams);
    return FLOE_OK;
}

#endif
