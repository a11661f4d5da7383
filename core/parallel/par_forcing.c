/* par_forcing.c - the force stages other than contacts and bonds in a world split over MPI
 * ranks (docs/parallel.md, "Forcing providers and servo walls").
 *
 * Per-particle providers (linear_drag, ocean_drag, wind_drag, coriolis, the body-force
 * callback, a user's provider whose class declares FLOE_PROVIDER_PER_PARTICLE) act on free
 * particles only, and ghosts are stored FLOE_FIXED, so each acts on the
 * owned particles of each rank: nothing of theirs reaches a ghost or travels back with the
 * reverse sum. What they keep per particle (their last force, for the trapezoid work of the
 * ledger and for a drag held between its evaluations) is registered with the world
 * (floe_world_pp_attach, world_internal.h pps) and moves with its particle here: permuted at
 * the split, routed to the new owner at every decomposition (as a record gid + the rows of
 * every array), gathered by global id into rank 0's unsplit world at a checkpoint.
 *
 * Servo walls: a wall's force on a rank is only that rank's part, and the controller's
 * speed is not linear in it. After every force evaluation (and at the split) each rank's
 * measures of every servo wall (f.n and the particles that reach it) are gathered on every
 * rank (MPI_Allgather) and summed in rank order, so the sum is the same to the bit
 * everywhere and every rank moves the wall alike; the controllers read the sums
 * (floe_servo_set_totals). The wall's own force stays each rank's part, so that the
 * boundary work summed over the ranks is the wall's work once.
 *
 * Kinematic bounded particles: their force at the step start (kin_old, written at the drift
 * and read at the step's end, a decomposition between them) is one of these rows
 * (world_prepare.c prepare_state registers it). */
#include "par_hooks.h"
#include "par_internal.h"
#include "world_parts.h"
#include "forcing_parts.h"

#include <stdlib.h>
#include <string.h>

#ifdef FLOE_HAVE_MPI

int floe_par_provider_supported(const floe_world *w, const floe_provider *pv) {
    if (floe_servo_is_provider(pv) || floe_linear_drag_is(pv) || floe_forcing_is_per_particle(pv)) return 1;
    /* any other user provider (whatever its name): when its class declares per-particle
     * forces (floe_provider.h, version 2); the world's own stages by their names */
    if (floe_provider_is_user(w, pv)) return floe_provider_splits(pv) == FLOE_PROVIDER_PER_PARTICLE;
    const char *nm = pv->klass->name;
    return !strcmp(nm, "body_forces") || !strcmp(nm, "contacts") || !strcmp(nm, "beam_bonds") || !strcmp(nm, "pd_bonds");
}

/* doubles per particle of every registered array */
static int pp_width(const floe_world *w) {
    int m = 0;
    for (int k = 0; k < w->npps; k++) m += w->pps[k].m;
    return m;
}

/* row i of every array into r (zeros beyond an array's rows) */
static void pp_get(const floe_world *w, int i, double *r) {
    for (int k = 0; k < w->npps; k++) {
        const struct floe_pp_state *s = &w->pps[k];
        if (i < *s->n && *s->arr) memcpy(r, *s->arr + (size_t)i * s->m, (size_t)s->m * sizeof *r);
        else memset(r, 0, (size_t)s->m * sizeof *r);
        r += s->m;
    }
}

/* fresh zeroed arrays of n rows (all or none) */
static int pp_alloc(const floe_world *w, int n, double **fresh) {
    for (int k = 0; k < w->npps; k++) {
        fresh[k] = calloc((size_t)(n ? n : 1) * w->pps[k].m, sizeof **fresh);
        if (!fresh[k]) {
            for (int j = 0; j < k; j++) free(fresh[j]);
            return FLOE_ENOMEM;
        }
    }
    return FLOE_OK;
}

static void pp_put(double **fresh, const floe_world *w, int i, const double *r) {
    for (int k = 0; k < w->npps; k++) {
        memcpy(fresh[k] + (size_t)i * w->pps[k].m, r, (size_t)w->pps[k].m * sizeof *r);
        r += w->pps[k].m;
    }
}

static void pp_install(floe_world *w, double **fresh, int n) {
    for (int k = 0; k < w->npps; k++) {
        free(*w->pps[k].arr);
        *w->pps[k].arr = fresh[k];
        *w->pps[k].n = n;
    }
}

int floe_par_pp_split_alloc(const floe_world *w, int nnew, double ***fresh) {
    *fresh = NULL;
    if (!w->npps) return FLOE_OK;
    double **f = malloc((size_t)w->npps * sizeof *f);
    if (!f || pp_alloc(w, nnew, f)) { free(f); return FLOE_ENOMEM; }
    *fresh = f;
    return FLOE_OK;
}

void floe_par_pp_split(floe_world *w, double **fresh, const int *newidx, int nold, int nnew, int keep) {
    if (!fresh) return;
    if (keep) {
        for (int k = 0; k < w->npps; k++) {
            const struct floe_pp_state *s = &w->pps[k];
            for (int i = 0; i < nold && i < *s->n; i++)
                if (newidx[i] >= 0)
                    memcpy(fresh[k] + (size_t)newidx[i] * s->m, *s->arr + (size_t)i * s->m, (size_t)s->m * sizeof **fresh);
        }
        pp_install(w, fresh, nnew);
    } else
        for (int k = 0; k < w->npps; k++) free(fresh[k]);
    free(fresh);
}

/* after RCB, before the migration: every owned particle's rows to its new owner */
int floe_par_pp_out(floe_world *w, floe_par *P, const int *dest) {
    free(P->ppin);
    P->ppin = NULL;
    P->nppin = 0;
    if (!w->npps) return FLOE_OK;
    const int m = 1 + pp_width(w), lo = P->nrep, no = P->nown;
    double *recs = malloc((size_t)(no ? no : 1) * m * sizeof *recs);
    int rc = recs ? FLOE_OK : FLOE_ENOMEM, n = recs ? no : 0;
    for (int k = 0; k < n; k++) {
        double *r = recs + (size_t)k * m;
        r[0] = (double)P->gid[lo + k];
        pp_get(w, lo + k, r + 1);
    }
    int r2 = floe_par_route(P, FLOE_COMM_MIGRATE, recs, dest, n, m, &P->ppin, &P->nppin);
    free(recs);
    int mine = rc ? rc : r2, all = mine;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof mine);
    return all;
}

/* after the ghosts: the arrays rebuilt for the new store (p->n rows; ghosts' rows zero, never
 * read: ghosts are not free) from the rows received, the walls' rows kept */
int floe_par_pp_in(floe_world *w, floe_par *P) {
    if (!w->npps) return FLOE_OK;
    const int m = 1 + pp_width(w), own_hi = P->nrep + P->nown;
    double **fresh = malloc((size_t)(w->npps > 0 ? w->npps : 1) * sizeof *fresh);
    floe_par_index ix = {0};
    int rc = !fresh || pp_alloc(w, w->p.n, fresh) ? FLOE_ENOMEM : FLOE_OK, lost = 0;
    if (!rc && floe_par_index_build(P, w->p.n, &ix)) {
        for (int k = 0; k < w->npps; k++) free(fresh[k]);
        rc = FLOE_ENOMEM;
    }
    if (!rc) {
        /* the walls keep their local indices [0, nrep) on every rank: their rows stay */
        for (int k = 0; k < w->npps; k++) {
            const struct floe_pp_state *st = &w->pps[k];
            const int nw = P->nrep < *st->n ? P->nrep : *st->n;
            if (nw > 0 && *st->arr) memcpy(fresh[k], *st->arr, (size_t)nw * st->m * sizeof **fresh);
        }
        for (int k = 0; k < P->nppin; k++) {
            const double *r = P->ppin + (size_t)k * m;
            const int i = floe_par_index_find(&ix, (long long)r[0]);
            if (i < P->nrep || i >= own_hi) { lost++; continue; }
            pp_put(fresh, w, i, r + 1);
        }
        pp_install(w, fresh, w->p.n);
    }
    floe_par_index_free(&ix);
    free(fresh);
    free(P->ppin);
    P->ppin = NULL;
    P->nppin = 0;
    int mine[2] = {rc, lost}, all[2];
    MPI_Allreduce(mine, all, 2, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof mine);
    if (all[1])
        return floe_world_error(w, FLOE_EINVAL, "MPI decomposition: internal: a force stage's per-particle state reached a "
                                "rank that does not own its particle");
    return all[0] ? floe_world_error(w, all[0], "MPI decomposition: out of memory") : FLOE_OK;
}

int floe_par_pp_collect(floe_world *w, floe_par *P, floe_world *full) {
    if (!w->npps) return FLOE_OK;
    const int m = 1 + pp_width(w), lo = P->nrep, no = P->nown;
    int bad = 0;
    if (P->rank == 0) {
        if (!full || full->npps != w->npps) bad = 1;
        for (int k = 0; !bad && k < w->npps; k++)
            if (full->pps[k].m != w->pps[k].m) bad = 1;
    }
    double *sb = malloc((size_t)(no ? no : 1) * m * sizeof *sb), *rb = NULL;
    int *cnt = P->rank == 0 ? malloc((size_t)2 * P->size * sizeof *cnt) : NULL;
    if (!bad && (!sb || (P->rank == 0 && !cnt))) bad = 2;
    int any = bad;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, P->comm);
    floe_par_count_allreduce(P, FLOE_COMM_OUTPUT, sizeof bad);
    if (any) {
        free(sb); free(cnt);
        return any == 2 ? floe_world_error(w, FLOE_ENOMEM, "MPI checkpoint: out of memory")
                        : floe_world_error(w, FLOE_EINVAL, "MPI checkpoint: rank 0's unsplit world has other force stages");
    }
    for (int k = 0; k < no; k++) {
        double *r = sb + (size_t)k * m;
        r[0] = (double)P->gid[lo + k];
        pp_get(w, lo + k, r + 1);
    }
    const int mine = no * m;
    MPI_Gather(&mine, 1, MPI_INT, cnt, 1, MPI_INT, 0, P->comm);
    floe_par_count_to_root(P, FLOE_COMM_OUTPUT, sizeof mine);
    int tot = 0, nomem = 0;
    if (P->rank == 0) {
        for (int r = 0; r < P->size; r++) { cnt[P->size + r] = tot; tot += cnt[r]; }
        rb = malloc((size_t)(tot ? tot : 1) * sizeof *rb);
        nomem = !rb;
    }
    MPI_Bcast(&nomem, 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof nomem);
    if (!nomem) {
        MPI_Gatherv(sb, mine, MPI_DOUBLE, rb, cnt, cnt ? cnt + P->size : NULL, MPI_DOUBLE, 0, P->comm);
        floe_par_count_to_root(P, FLOE_COMM_OUTPUT, (long long)mine * sizeof *sb);
    }
    if (!nomem && P->rank == 0) {
        /* the full world's arrays: one row per particle of the unsplit store */
        double **fresh = malloc((size_t)(w->npps > 0 ? w->npps : 1) * sizeof *fresh);
        if (!fresh || pp_alloc(full, full->p.n, fresh)) nomem = 1;
        else {
            for (int k = 0; k < tot / m; k++) {
                const double *r = rb + (size_t)k * m;
                const long long g = (long long)r[0];
                if (g >= 0 && g < full->p.n) pp_put(fresh, full, (int)g, r + 1);
            }
            pp_install(full, fresh, full->p.n);
        }
        free(fresh);
    }
    free(sb); free(cnt); free(rb);
    MPI_Bcast(&nomem, 1, MPI_INT, 0, P->comm);
    floe_par_count_bcast(P, FLOE_COMM_OUTPUT, sizeof nomem);
    return nomem ? floe_world_error(w, FLOE_ENOMEM, "MPI checkpoint: out of memory on rank 0") : FLOE_OK;
}

int floe_par_servo_totals(floe_world *w) {
    floe_par *P = w->par;
    const int ns = floe_servo_count(w);
    if (!P || !ns) return FLOE_OK;
    const int m = 2 * ns;
    const size_t need = (size_t)m * (1 + P->size);
    if (P->servo_cap < need) {
        /* the first call (the servo walls are the same on every rank: every rank is here):
         * the buffer kept in P, its allocation agreed */
        double *b = realloc(P->servo_buf, need * sizeof *b);
        if (b) { P->servo_buf = b; P->servo_cap = need; }
        int bad = !b, any = bad;
        MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_LOR, P->comm);
        floe_par_count_allreduce(P, FLOE_COMM_REDUCE, sizeof bad);
        if (any) { /* every rank the same: the next call agrees again */
            free(P->servo_buf);
            P->servo_buf = NULL;
            P->servo_cap = 0;
            w->err_agreed = 2; /* (out of memory, as par_world.c error_from) */
            return floe_world_error(w, FLOE_ENOMEM, "MPI servo walls: out of memory");
        }
    }
    double *v = P->servo_buf, *all = v + m;
    floe_servo_partials(w, v);
    MPI_Allgather(v, m, MPI_DOUBLE, all, m, MPI_DOUBLE, P->comm);
    floe_par_count_all(P, FLOE_COMM_REDUCE, (long long)m * sizeof *v);
    /* in rank order: the same sum, to the bit, on every rank */
    for (int k = 0; k < m; k++) {
        double s = 0;
        for (int r = 0; r < P->size; r++) s += all[(size_t)r * m + k];
        v[k] = s;
    }
    floe_servo_set_totals(w, v);
    return FLOE_OK;
}

#else /* serial build */

int floe_par_servo_totals(floe_world *w) {
    (void)w;
    return FLOE_OK;
}

#endif
