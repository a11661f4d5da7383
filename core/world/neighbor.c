/* neighbor.c - candidate pairs from the k-d tree over bounding spheres, with a Verlet
 * skin: the list holds every pair whose bounding spheres are closer than the skin, and
 * is rebuilt only when some particle has moved (or grown) by more than skin/2 since the
 * last build. Walls (unbounded planes) are paired with every particle within reach.
 * Per-pair history (shear springs) survives rebuilds through a hash of the pair. */
#include "world_internal.h"
#include "floe_par.h"
#include "alloc_util.h"
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int floe_nl_init(floe_neighbor_list *nl) {
    memset(nl, 0, sizeof *nl);
    nl->hs = FLOE_MAX_HISTORY;
    return FLOE_OK;
}

int floe_nl_set_stride(floe_neighbor_list *nl, int hs) {
    if (hs == nl->hs) return FLOE_OK;
    if (nl->hist) {
        /* every entry's slots kept where both layouts have them (floe_contact.h: the same
         * places), the new ones zero */
        const size_t np = nl->npairs > 0 ? (size_t)nl->npairs : 1;
        const int c = hs < nl->hs ? hs : nl->hs;
        double *h = malloc(np * (size_t)hs * sizeof *h);
        if (!h) return FLOE_ENOMEM;
        for (size_t k = 0; k < np; k++) {
            double *d = h + k * (size_t)hs;
            if (k < (size_t)nl->npairs) memcpy(d, nl->hist + k * (size_t)nl->hs, (size_t)c * sizeof *d);
            else memset(d, 0, (size_t)c * sizeof *d);
            if (hs > c) memset(d + c, 0, (size_t)(hs - c) * sizeof *d);
        }
        free(nl->hist);
        nl->hist = h;
    }
    nl->hs = hs;
    return FLOE_OK;
}

/* one search thread's entries found, (i, j, sub, img) each, and its tree-query scratch;
 * 128 bytes apart from the next thread's: its count is written at every entry found, and two
 * threads' in one cache line moved it between the cores at each (the array is 16-byte
 * aligned: 128 keeps each one's fields off the next's lines) */
struct floe_nl_found {
    int *e; size_t n, cap;
    int *scr; int scap;
    int rc;
    char pad[128 - 2 * sizeof(int *) - 2 * sizeof(size_t) - 2 * sizeof(int)];
};
_Static_assert(sizeof(struct floe_nl_found) == 128, "floe_nl_found: one per 128 bytes");

void floe_nl_free(floe_neighbor_list *nl) {
    for (int t = 0; t < nl->nfound; t++) { free(nl->found[t].e); free(nl->found[t].scr); }
    free(nl->found);
    floe_kdtree_destroy(nl->tree);
    free(nl->pi); free(nl->pj); free(nl->sub); free(nl->img); free(nl->warm); free(nl->hist); free(nl->touching);
    free(nl->x_build); free(nl->walls); free(nl->r_build); free(nl->q_walls);
    memset(nl, 0, sizeof *nl);
}

void floe_nl_drop_entries(floe_neighbor_list *nl) {
    free(nl->pi); free(nl->pj); free(nl->sub); free(nl->img); free(nl->warm); free(nl->hist); free(nl->touching);
    nl->pi = nl->pj = nl->sub = nl->img = NULL;
    nl->warm = nl->hist = NULL;
    nl->touching = NULL;
    nl->npairs = nl->cap = 0;
    nl->gen++;
}

int floe_nl_needs_rebuild_after_drift(const floe_neighbor_list *nl, const floe_particles *p, double maxd2,
                                      int growth) {
    if (!nl->x_build || nl->n_build != p->n) return 1;
    if (growth) return floe_nl_needs_rebuild(nl, p);
    double lim = 0.5 * nl->skin;
    if (maxd2 > lim * lim) return 1;
    for (int a = 0; a < nl->nwalls; a++) {
        int wi = nl->walls[a];
        if (memcmp(p->q + 4 * wi, nl->q_walls + 4 * a, 4 * sizeof(double))) return 1;
    }
    return 0;
}

int floe_nl_needs_rebuild(const floe_neighbor_list *nl, const floe_particles *p) {
    if (!nl->x_build || nl->n_build != p->n) return 1;
    double lim = 0.5 * nl->skin, lim2 = lim * lim;
    /* MPI: the walls and owned particles; a ghost's test is its owner's, which every rank's
     * verdict joins (docs/parallel.md, "Ghosts a step refreshes") */
    const int n = nl->gid ? nl->own_hi : p->n;
    for (int i = 0; i < n; i++) {
        const double *a = p->x + 3 * i, *b = nl->x_build + 3 * i;
        double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
        double grow = p->radius[i] - nl->r_build[i]; /* NaN for walls (inf - inf): not > 0 */
        if (grow > 0) {
            if (sqrt(dx * dx + dy * dy + dz * dz) + grow > lim) return 1;
        } else if (dx * dx + dy * dy + dz * dz > lim2) return 1;
    }
    /* a wall that turned (kinematic rotation) moves far from its pivot: re-pair it */
    for (int a = 0; a < nl->nwalls; a++) {
        int wi = nl->walls[a];
        if (memcmp(p->q + 4 * wi, nl->q_walls + 4 * a, 4 * sizeof(double))) return 1;
    }
    return 0;
}

static uint64_t pair_key(int i, int j) { return ((uint64_t)(uint32_t)i << 32) | (uint32_t)j; }
static uint64_t mix(uint64_t k) {
    k ^= k >> 33; k *= 0xff51afd7ed558ccdULL; k ^= k >> 33; k *= 0xc4ceb9fe1a85ec53ULL; k ^= k >> 33;
    return k;
}

static int push_one(struct floe_nl_found *fd, int i, int j, int sub, int img) {
    if (fd->n + 4 > fd->cap && floe_reserve((void **)&fd->e, &fd->cap, fd->cap ? 2 * fd->cap : 4096, sizeof(int)))
        return FLOE_ENOMEM;
    int *e = fd->e + fd->n;
    e[0] = i; e[1] = j; e[2] = sub; e[3] = img;
    fd->n += 4;
    return FLOE_OK;
}

/* one entry per piece pair: compound bodies turn with respect to their centre of mass
 * without a rebuild, so all their piece pairs are listed and culled in the force loop */
static int push_pair(struct floe_nl_found *fd, const floe_neighbor_list *nl, const floe_particles *p, int i, int j,
                     const int n[3]) {
    int img = 0;
    /* A bounded particle and an unbounded one (a wall): the bounded one is i, the entry in its
     * row whatever the indices (session 36): a wall's entries then lie in its neighbours'
     * rows, not all in the walls' rows at the list's start when walls are declared first,
     * so that the threads' parts share those neighbours no more than others
     * (docs/parallel.md). Else the pair in index order; MPI: in global-id order, as in the
     * serial world (a history's sign convention follows its order). */
    const int ui = !isfinite(p->radius[i]), uj = !isfinite(p->radius[j]);
    if (ui != uj ? ui : nl->gid ? nl->gid[i] > nl->gid[j] : i > j) {
        int t = i; i = j; j = t;
        if (n) img = floe_img_encode(-n[0], -n[1], -n[2]);
    } else if (n) img = floe_img_encode(n[0], n[1], n[2]);
    int na = p->pieces ? p->pieces[i] : 1, nb = p->pieces ? p->pieces[j] : 1;
    if (na == 1 && nb == 1) return push_one(fd, i, j, 0, img);
    for (int a = 0; a < na; a++)
        for (int b = 0; b < nb; b++) FLOE_TRY(push_one(fd, i, j, FLOE_SUB(a, b), img));
    return FLOE_OK;
}

/* the order of a row's entries: (j, piece pair, image) */
static inline int entry_less(const int *x, const int *y) {
    if (x[0] != y[0]) return x[0] < y[0];
    if (x[1] != y[1]) return x[1] < y[1];
    return x[2] < y[2];
}
static int cmp_entry(const void *a, const void *b) {
    const int *x = a, *y = b;
    return entry_less(x, y) ? -1 : entry_less(y, x);
}

/* the search of bounded particle a (index into bidx) over the tree, from each copy of it in
 * the neighbouring cells of a periodic cell: its entries into fd */
typedef struct nl_search {
    const floe_neighbor_list *nl;
    const floe_particles *p;
    const floe_cell_state *cell;
    const int *bidx, *bsh;
    const double *bx;
    double skin, wd[3];
    int dim;
} nl_search;

static int search_one(const nl_search *S, struct floe_nl_found *fd, int a) {
    const floe_neighbor_list *nl = S->nl;
    const floe_particles *p = S->p;
    const floe_cell_state *cell = S->cell;
    const int *bidx = S->bidx, *bsh = S->bsh, dim = S->dim;
    const double *bx = S->bx;
    const int mr = cell ? 1 : 0, mz = cell && dim == 3 ? 1 : 0;
    const int i = bidx[a];
    /* the law "none" (world.c inert_materials): a particle that touches nothing present
     * searches for nothing; the others skip the pairs under it, before the exclusions (a PD
     * bond's lookup) */
    if (nl->inert && nl->inert[p->material[i]]) return FLOE_OK;
    const unsigned char *none_i = nl->none ? nl->none + (size_t)p->material[i] * nl->nmat : NULL;
    const double reach = 2 * p->radius[i] + S->skin;
    for (int m0 = -mr; m0 <= mr; m0++)
      for (int m1 = -mr; m1 <= mr; m1++)
      for (int m2 = -mz; m2 <= mz; m2++) {
        const double *qx = p->x + 3 * i;
        double qy[3];
        const int m[3] = {m0, m1, m2};
        if (cell) {
            double d[3], sf[3];
            floe_v3_sub(d, bx + 3 * a, cell->o);
            int skip = 0;
            for (int r = 0; r < 3; r++) {
                sf[r] = cell->Hinv[3 * r] * d[0] + cell->Hinv[3 * r + 1] * d[1] + cell->Hinv[3 * r + 2] * d[2] + m[r];
                if (r < dim && (sf[r] * S->wd[r] < -reach || (sf[r] - 1) * S->wd[r] > reach)) skip = 1;
            }
            if (skip) continue;
            for (int r = 0; r < 3; r++)
                qy[r] = bx[3 * a + r] + cell->H[3 * r] * m0 + cell->H[3 * r + 1] * m1 + cell->H[3 * r + 2] * m2;
            qx = qy;
        }
        int cnt;
        for (;;) {
            cnt = floe_kdtree_radius(nl->tree, qx, reach, fd->scr, fd->scap);
            if (cnt <= fd->scap) break;
            int nc = cnt + cnt / 2 + 64;
            int *sc = realloc(fd->scr, nc * sizeof(int));
            if (!sc) return FLOE_ENOMEM;
            fd->scr = sc;
            fd->scap = nc;
        }
        for (int k = 0; k < cnt; k++) {
            const int b = fd->scr[k], j = bidx[b];
            if (p->radius[j] > p->radius[i] || (p->radius[j] == p->radius[i] && j <= i)) continue;
            if (none_i && none_i[p->material[j]]) continue;
            /* two particles that do not move under forces are never paired; a ghost (MPI) is
             * stored FLOE_FIXED, its true motion is free when its mass is not infinite */
            if (p->motion[i] != FLOE_FREE && p->motion[j] != FLOE_FREE &&
                !(nl->gid && ((i >= nl->own_hi && p->inv_mass[i] > 0) || (j >= nl->own_hi && p->inv_mass[j] > 0))))
                continue;
            /* MPI (core/parallel): a pair with a ghost is this rank's when its owned particle
             * has the lower global id; two ghosts are never paired */
            if (nl->gid && (i >= nl->own_hi || j >= nl->own_hi)) {
                const int g = i >= nl->own_hi ? i : j, o = g == i ? j : i;
                if (o >= nl->own_hi || nl->gid[g] < nl->gid[o]) continue;
            }
            int n[3] = {0, 0, 0};
            double d[3];
            floe_v3_sub(d, p->x + 3 * j, p->x + 3 * i);
            if (cell) {
                /* x_j + H sh_j = y_j ~ y_i + H m = x_i + H (sh_i + m): j's image x_j + H n near x_i */
                for (int r = 0; r < 3; r++) n[r] = bsh[3 * b + r] - bsh[3 * a + r] - m[r];
                for (int r = 0; r < 3; r++) d[r] += cell->H[3 * r] * n[0] + cell->H[3 * r + 1] * n[1] + cell->H[3 * r + 2] * n[2];
            }
            /* bonded pairs (PD families, beams) are excluded as their direct pair, PD bonds across
             * the cell's faces through their image too (exclude_image) */
            if (!(n[0] | n[1] | n[2]) ? nl->exclude && nl->exclude(nl->exclude_ctx, i, j)
                                      : nl->exclude_image && nl->exclude_image(nl->exclude_ctx, i, j, n))
                continue;
            double lim = p->radius[i] + p->radius[j] + S->skin;
            if (floe_v3_dot(d, d) <= lim * lim) FLOE_TRY(push_pair(fd, nl, p, i, j, cell ? n : NULL));
        }
    }
    return FLOE_OK;
}

/* the list's arrays for cap entries (contents not kept) */
static int nl_reserve(floe_neighbor_list *nl, size_t need) {
    if (need <= (size_t)nl->cap && (!nl->cell || nl->img)) return FLOE_OK;
    if (need > INT32_MAX) return FLOE_ENOMEM;
    size_t nc = need > (size_t)nl->cap ? need + need / 4 + 1024 : (size_t)nl->cap;
    if (nc > INT32_MAX) nc = need;
    if (floe_resize((void **)&nl->pi, nc, sizeof(int)) || floe_resize((void **)&nl->pj, nc, sizeof(int)) ||
        floe_resize((void **)&nl->sub, nc, sizeof(int)) || (nl->cell && floe_resize((void **)&nl->img, nc, sizeof(int))))
        return FLOE_ENOMEM;
    nl->cap = (int)nc;
    return FLOE_OK;
}

int floe_nl_trim(floe_neighbor_list *nl) {
    const size_t fit = (size_t)nl->npairs + (size_t)nl->npairs / 4 + 1024;
    if ((size_t)nl->cap <= fit + fit / 2) return 0;
    /* shrinking keeps the contents (realloc); an array whose shrink fails keeps its larger
     * size, so every one holds at least fit entries either way */
    (void)floe_resize((void **)&nl->pi, fit, sizeof(int));
    (void)floe_resize((void **)&nl->pj, fit, sizeof(int));
    (void)floe_resize((void **)&nl->sub, fit, sizeof(int));
    if (nl->img) (void)floe_resize((void **)&nl->img, fit, sizeof(int));
    nl->cap = (int)fit;
    return 1;
}

/* rows [i0, i1) each in order by (j, piece pair, image): insertion sort (a sphere's row is
 * a few entries), qsort for the long rows of compound bodies */
static int nl_sort_rows(floe_neighbor_list *nl, const int *row, int i0, int i1) {
    int *pj = nl->pj, *sub = nl->sub, *img = nl->cell ? nl->img : NULL;
    int *tmp = NULL;
    size_t tcap = 0;
    for (int i = i0; i < i1; i++) {
        const int k0 = row[i], m = row[i + 1] - k0;
        if (m < 2) continue;
        if (m <= 24) {
            for (int a = 1; a < m; a++) {
                int key[3] = {pj[k0 + a], sub[k0 + a], img ? img[k0 + a] : 0}, b = a - 1;
                while (b >= 0) {
                    const int cur[3] = {pj[k0 + b], sub[k0 + b], img ? img[k0 + b] : 0};
                    if (!entry_less(key, cur)) break;
                    pj[k0 + b + 1] = cur[0]; sub[k0 + b + 1] = cur[1];
                    if (img) img[k0 + b + 1] = cur[2];
                    b--;
                }
                pj[k0 + b + 1] = key[0]; sub[k0 + b + 1] = key[1];
                if (img) img[k0 + b + 1] = key[2];
            }
        } else {
            if ((size_t)m * 3 > tcap) {
                int *t2 = realloc(tmp, (size_t)m * 3 * sizeof *t2);
                if (!t2) { free(tmp); return FLOE_ENOMEM; }
                tmp = t2;
                tcap = (size_t)m * 3;
            }
            for (int a = 0; a < m; a++) {
                tmp[3 * a] = pj[k0 + a]; tmp[3 * a + 1] = sub[k0 + a]; tmp[3 * a + 2] = img ? img[k0 + a] : 0;
            }
            qsort(tmp, m, 3 * sizeof(int), cmp_entry);
            for (int a = 0; a < m; a++) {
                pj[k0 + a] = tmp[3 * a]; sub[k0 + a] = tmp[3 * a + 1];
                if (img) img[k0 + a] = tmp[3 * a + 2];
            }
        }
    }
    free(tmp);
    return FLOE_OK;
}

/* thread t's run of rows [*i0, *i1) of nt, about the same number of the tot entries each:
 * from the first row that starts at or after t / nt of them */
static void row_run(const int *row, int n, long tot, int t, int nt, int *i0, int *i1) {
    /* (the first particle whose row starts at or after that entry) */
    *i0 = t == 0 ? 0 : floe_int_lower(row, n, (int)(tot * t / nt));
    *i1 = t == nt - 1 ? n : floe_int_lower(row, n, (int)(tot * (t + 1) / nt));
}

/* found entry e (i, j, piece pair, image) into slot k of the list */
static inline void put_entry(int *pi, int *pj, int *sub, int *img, int k, const int *e) {
    pi[k] = e[0];
    pj[k] = e[1];
    sub[k] = e[2];
    if (img) img[k] = e[3];
}

/* The found entries of every thread into the list, sorted by (i, j, piece pair, image): a
 * counting sort by i, then each row by the rest (the order does not depend on which thread
 * found what, nor in which order). *rowp: the rows' offsets, n + 1 (the caller frees). */
static int nl_collect(floe_neighbor_list *nl, int n, int nt, int **rowp) {
    size_t tot = 0;
    for (int t = 0; t < nt; t++) tot += nl->found[t].n / 4;
    FLOE_TRY(nl_reserve(nl, tot ? tot : 1));
    int *row = calloc((size_t)n + 1, sizeof *row);
    if (!row) return FLOE_ENOMEM;
    int *pj = nl->pj, *sub = nl->sub, *img = nl->cell ? nl->img : NULL, *pi = nl->pi;
    /* threads (a few): each counts and scatters its own buffer through its own offsets per
     * row (nt counts per particle); the rows' sort then gives the order of one thread */
    int *cnt = nt > 1 && nt <= 8 && tot >= 4096 ? calloc((size_t)nt * ((size_t)n + 1), sizeof *cnt) : NULL;
    if (cnt) {
        FLOE_OMP(omp parallel for schedule(static, 1) num_threads(nt))
        for (int t = 0; t < nt; t++) {
            int *c = cnt + (size_t)t * ((size_t)n + 1);
            const int *e = nl->found[t].e;
            for (size_t q = 0; q < nl->found[t].n; q += 4) c[e[q]]++;
        }
        int acc = 0;
        for (int i = 0; i < n; i++) {
            row[i] = acc;
            for (int t = 0; t < nt; t++) { /* thread t's first slot in row i */
                int *c = cnt + (size_t)t * ((size_t)n + 1) + i;
                const int m = *c;
                *c = acc;
                acc += m;
            }
        }
        row[n] = acc;
        FLOE_OMP(omp parallel for schedule(static, 1) num_threads(nt))
        for (int t = 0; t < nt; t++) {
            int *c = cnt + (size_t)t * ((size_t)n + 1);
            const int *e = nl->found[t].e;
            for (size_t q = 0; q < nl->found[t].n; q += 4) put_entry(pi, pj, sub, img, c[e[q]]++, e + q);
        }
        free(cnt);
    } else {
        for (int t = 0; t < nt; t++) {
            const int *e = nl->found[t].e;
            for (size_t q = 0; q < nl->found[t].n; q += 4) row[e[q] + 1]++;
        }
        for (int i = 0; i < n; i++) row[i + 1] += row[i];
        /* scatter (row[i] advances to the row's end, then is moved back) */
        for (int t = 0; t < nt; t++) {
            const int *e = nl->found[t].e;
            for (size_t q = 0; q < nl->found[t].n; q += 4) put_entry(pi, pj, sub, img, row[e[q]]++, e + q);
        }
        for (int i = n; i > 0; i--) row[i] = row[i - 1];
        row[0] = 0;
    }
    nl->npairs = (int)tot;
    int rc = FLOE_OK;
    if (nt > 1 && tot >= 4096) {
        /* rows in nt runs of about the same number of entries */
        FLOE_OMP(omp parallel for schedule(static, 1) num_threads(nt) reduction(|: rc))
        for (int t = 0; t < nt; t++) {
            int i0, i1;
            row_run(row, n, (long)tot, t, nt, &i0, &i1);
            rc |= nl_sort_rows(nl, row, i0, i1);
        }
    } else
        rc = nl_sort_rows(nl, row, 0, n);
    if (rc) {
        free(row);
        return FLOE_ENOMEM;
    }
    *rowp = row;
    return FLOE_OK;
}

/* an entry is (i, j, piece pair, image): the history follows all four */
static uint64_t entry_hash(uint64_t key, int sub, int img) {
    return mix(key ^ ((uint64_t)(uint32_t)sub * 0x9E3779B97F4A7C15ULL) ^ ((uint64_t)(uint32_t)img << 17));
}

/* the list's entries strictly in order (i, j, piece pair, image), as nl_collect leaves them
 * (nt threads: each a run of the entries, every one compared with the one before it) */
static int nl_sorted(const floe_neighbor_list *nl, int nt) {
    const int *pi = nl->pi, *pj = nl->pj, *sub = nl->sub, *img = nl->img;
    int ok = 1;
    FLOE_OMP(omp parallel for schedule(static) num_threads(nt) reduction(&: ok) if (nt > 1))
    for (int k = 1; k < nl->npairs; k++) {
        if (pi[k - 1] != pi[k]) {
            ok &= pi[k - 1] < pi[k];
            continue;
        }
        const int a[3] = {pj[k - 1], sub[k - 1], img ? img[k - 1] : 0}, b[3] = {pj[k], sub[k], img ? img[k] : 0};
        ok &= entry_less(a, b);
    }
    return ok && (nl->npairs == 0 || pi[0] >= 0);
}

/* Rows by a counting sort on i, each row by insertion on (j, piece pair, image), entry_less
 * (a row holds a few entries); equal entries (none expected) keep their order, and the next
 * build then takes the hash path (nl_sorted). */
int floe_nl_sort(floe_neighbor_list *nl, int n) {
    const int np = nl->npairs, H = nl->hs, W = FLOE_DETECT_WARM, use_warm = nl->use_warm && nl->warm;
    if (np < 2) return FLOE_OK;
    for (int k = 0; k < np; k++)
        if (nl->pi[k] < 0 || nl->pi[k] >= n) return FLOE_OK; /* cannot happen: left unsorted */
    int *start = calloc((size_t)n + 1, sizeof *start), *ord = malloc((size_t)np * sizeof *ord);
    int *pi = malloc((size_t)np * sizeof *pi), *pj = malloc((size_t)np * sizeof *pj);
    int *sub = malloc((size_t)np * sizeof *sub), *img = nl->img ? malloc((size_t)np * sizeof *img) : NULL;
    unsigned char *t = malloc((size_t)np);
    double *h = malloc((size_t)np * H * sizeof *h), *wm = use_warm ? malloc((size_t)np * W * sizeof *wm) : NULL;
    int rc = start && ord && pi && pj && sub && (!nl->img || img) && t && h && (!use_warm || wm) ? FLOE_OK : FLOE_ENOMEM;
    if (!rc) {
        for (int k = 0; k < np; k++) start[nl->pi[k] + 1]++;
        for (int i = 0; i < n; i++) start[i + 1] += start[i];
        for (int k = 0; k < np; k++) ord[start[nl->pi[k]]++] = k;
        for (int i = n; i > 0; i--) start[i] = start[i - 1]; /* back to the rows' starts */
        start[0] = 0;
        for (int i = 0; i < n; i++)
            for (int a = start[i] + 1; a < start[i + 1]; a++) {
                const int k = ord[a], key[3] = {nl->pj[k], nl->sub[k], nl->img ? nl->img[k] : 0};
                int b = a;
                while (b > start[i]) {
                    const int c = ord[b - 1], cur[3] = {nl->pj[c], nl->sub[c], nl->img ? nl->img[c] : 0};
                    if (!entry_less(key, cur)) break;
                    ord[b] = c;
                    b--;
                }
                ord[b] = k;
            }
        for (int a = 0; a < np; a++) {
            const int k = ord[a];
            pi[a] = nl->pi[k];
            pj[a] = nl->pj[k];
            sub[a] = nl->sub[k];
            if (img) img[a] = nl->img[k];
            t[a] = nl->touching[k];
            memcpy(h + (size_t)a * H, nl->hist + (size_t)k * H, H * sizeof *h);
            if (use_warm) memcpy(wm + (size_t)a * W, nl->warm + (size_t)k * W, W * sizeof *wm);
        }
        free(nl->pi); free(nl->pj); free(nl->sub); free(nl->touching); free(nl->hist);
        nl->pi = pi; nl->pj = pj; nl->sub = sub; nl->touching = t; nl->hist = h;
        if (img) { free(nl->img); nl->img = img; }
        nl->cap = np;
        if (use_warm) { free(nl->warm); nl->warm = wm; }
        pi = pj = sub = img = NULL; t = NULL; h = wm = NULL;
    }
    free(start); free(ord); free(pi); free(pj); free(sub); free(img); free(t); free(h); free(wm);
    return rc;
}

/* the last build's entries (i, j, piece pair, image), taken from the list while the next is
 * built; their history stays in the list's arrays and moves in place to the new entries */
typedef struct nl_old {
    int *pi, *pj, *sub, *img, npairs;
} nl_old;

/* src[k] for the new entries of particles [i0, i1) (rows row[]): the old entry (rows orow[])
 * with the same (j, piece pair, image) whose history is kept (touching, or a warm start; the
 * list's arrays still hold the old history), -1 for none. Both lists in order: src increases. */
static void nl_match_rows(const floe_neighbor_list *nl, const nl_old *o, const int *row, const int *orow, int i0,
                          int i1, int use_warm, int *src) {
    const int W = FLOE_DETECT_WARM;
    for (int i = i0; i < i1; i++) {
        int a = orow[i];
        const int ae = orow[i + 1];
        for (int k = row[i]; k < row[i + 1]; k++) {
            const int key[3] = {nl->pj[k], nl->sub[k], nl->img && nl->cell ? nl->img[k] : 0};
            int s = -1;
            for (; a < ae; a++) {
                const int cur[3] = {o->pj[a], o->sub[a], o->img ? o->img[a] : 0};
                if (!entry_less(cur, key)) {
                    if (!entry_less(key, cur) && (nl->touching[a] || (use_warm && isfinite(nl->warm[(size_t)a * W]))))
                        s = a;
                    break;
                }
            }
            src[k] = s;
        }
    }
}

/* entry s's history, touching flag and warm start (warm: the list keeps them) to entry k */
static inline void nl_move_one(floe_neighbor_list *nl, int k, int s, int warm) {
    const int W = FLOE_DETECT_WARM, H = nl->hs;
    memcpy(nl->hist + (size_t)k * H, nl->hist + (size_t)s * H, H * sizeof(double));
    nl->touching[k] = nl->touching[s];
    if (warm) memcpy(nl->warm + (size_t)k * W, nl->warm + (size_t)s * W, W * sizeof(double));
}

/* the kept histories to their new entries, in place (the arrays hold max(old, new) entries):
 * src increases, so an entry that moves down (src[k] > k) never reads a place another moving
 * down has written when they go in increasing k, nor one moving up (src[k] < k) in decreasing
 * k, and neither kind reads what the other writes; the new entries without history last.
 * warm_old: the old warm starts are kept (else every new one is NaN) */
static void nl_move_history(floe_neighbor_list *nl, const int *src, int np, int warm_old, int nt) {
    const int W = FLOE_DETECT_WARM, H = nl->hs;
    for (int k = 0; k < np; k++)
        if (src[k] > k) nl_move_one(nl, k, src[k], warm_old);
    for (int k = np - 1; k >= 0; k--)
        if (src[k] >= 0 && src[k] < k) nl_move_one(nl, k, src[k], warm_old);
    /* every move done: each new entry's slot is its own (threads: runs of entries) */
    double *hist = nl->hist, *warm = nl->warm;
    unsigned char *touching = nl->touching;
    const int uw = nl->use_warm;
    FLOE_OMP(omp parallel for schedule(static) num_threads(nt) if (nt > 1))
    for (int k = 0; k < np; k++) {
        if (src[k] < 0) {
            for (int q = 0; q < H; q++) hist[(size_t)k * H + q] = 0.0;
            touching[k] = 0;
        }
        if (uw && (src[k] < 0 || !warm_old))
            for (int q = 0; q < W; q++) warm[(size_t)k * W + q] = NAN;
    }
}

/* the old entries back in place of new ones that failed (the caller empties the list) */
static void nl_old_restore(floe_neighbor_list *nl, nl_old *o, int ocap) {
    if (!o->pi) return;
    free(nl->pi); free(nl->pj); free(nl->sub); free(nl->img);
    nl->pi = o->pi; nl->pj = o->pj; nl->sub = o->sub; nl->img = o->img;
    nl->cap = ocap;
    memset(o, 0, sizeof *o);
}

static void nl_old_free(nl_old *o) {
    free(o->pi); free(o->pj); free(o->sub); free(o->img);
    memset(o, 0, sizeof *o);
}

int floe_nl_build(floe_neighbor_list *nl, const floe_particles *p, int dim, int leaf_size) {
    int n = p->n;
    nl->gen++;
    /* keep the history of touching pairs: the entries of a list in order (every build's) are
     * set aside, matched row by row with the new ones afterwards, and their history moved in
     * place (no second copy of it); a list in another order (MPI's imported history,
     * core/parallel hist_import) goes through a hash of its entries */
    nl_old old = {0};
    const int ocap = nl->cap;
    /* the old list's order check on the world's threads (nl->threads) when it is long, each
     * thread a run of its entries; the rows' offsets and the history's clearing below take the
     * search's (nt) */
    const int ntl = nl->threads > 1 && nl->npairs >= 4096 ? nl->threads : 1;
    const int merge = nl->npairs > 0 && nl->hist && nl->touching && nl_sorted(nl, ntl);
    const int W = FLOE_DETECT_WARM, use_warm = nl->use_warm && nl->warm;
    const size_t HS = (size_t)nl->hs; /* doubles of history per entry */
    if (merge) {
        old = (nl_old){nl->pi, nl->pj, nl->sub, nl->img, nl->npairs};
        nl->pi = nl->pj = nl->sub = nl->img = NULL;
        nl->cap = 0;
        nl->npairs = 0;
    }
    int nold = 0;
    uint64_t *okeys = NULL;
    double *ohist = NULL, *owarm = NULL;
    int *osub = NULL, *oimg = NULL;
    const floe_cell_state *cell = nl->cell;
    const int *img_old = nl->img && nl->npairs ? nl->img : NULL;
    unsigned char *otouch = NULL;
    int hcap = 0;
    /* kept: touching pairs (shear history) and pairs with a warm start */
#define KEEP(k) (nl->touching[k] || (use_warm && isfinite(nl->warm[(size_t)(k) * W])))
    for (int k = 0; k < nl->npairs; k++) nold += KEEP(k) != 0;
    if (nold) {
        hcap = 1;
        while (hcap < 2 * nold) hcap <<= 1;
        okeys = malloc(hcap * sizeof *okeys);
        osub = malloc(hcap * sizeof *osub);
        oimg = malloc(hcap * sizeof *oimg);
        otouch = malloc(hcap);
        ohist = malloc((size_t)hcap * HS * sizeof *ohist);
        owarm = use_warm ? malloc((size_t)hcap * W * sizeof *owarm) : NULL;
        if (!okeys || !osub || !oimg || !otouch || !ohist || (use_warm && !owarm)) {
            free(okeys); free(osub); free(oimg); free(otouch); free(ohist); free(owarm);
            return FLOE_ENOMEM;
        }
        for (int k = 0; k < hcap; k++) okeys[k] = UINT64_MAX;
        for (int k = 0; k < nl->npairs; k++) {
            if (!KEEP(k)) continue;
            uint64_t key = pair_key(nl->pi[k], nl->pj[k]);
            const int im = img_old ? img_old[k] : 0;
            size_t h = entry_hash(key, nl->sub[k], im) & (hcap - 1);
            while (okeys[h] != UINT64_MAX) h = (h + 1) & (hcap - 1);
            okeys[h] = key;
            osub[h] = nl->sub[k];
            oimg[h] = im;
            otouch[h] = nl->touching[k];
            memcpy(ohist + h * HS, nl->hist + (size_t)k * HS, HS * sizeof(double));
            if (use_warm) memcpy(owarm + h * W, nl->warm + (size_t)k * W, W * sizeof(double));
        }
    }
#undef KEEP

    nl->npairs = 0;
    free(nl->walls);
    nl->walls = NULL;
    nl->nwalls = 0;
    /* bounded particles go into the tree */
    int nb = 0, nw = 0;
    for (int i = 0; i < n; i++) {
        if (isfinite(p->radius[i])) nb++;
        else nw++;
    }
    /* the search's threads (the world sets nl->threads for a list this long), their buffers */
    int nt = nl->threads > 1 && nb > 1 ? nl->threads : 1;
    if (nt > nl->nfound) {
        struct floe_nl_found *f = realloc(nl->found, (size_t)nt * sizeof *f);
        if (f) {
            memset(f + nl->nfound, 0, (size_t)(nt - nl->nfound) * sizeof *f);
            nl->found = f;
            nl->nfound = nt;
        }
    }
    int *bidx = malloc((nb ? nb : 1) * sizeof(int));
    double *bx = malloc((nb ? nb : 1) * 3 * sizeof(double));
    /* periodic cell: the tree holds the positions wrapped into the cell, x + H sh */
    int *bsh = cell ? malloc((nb ? nb : 1) * 3 * sizeof(int)) : NULL;
    nl->walls = malloc((nw ? nw : 1) * sizeof(int));
    if (!bidx || !bx || !nl->walls || (cell && !bsh) || nt > nl->nfound) {
        free(bidx); free(bx); free(bsh); free(okeys); free(ohist); free(osub); free(oimg); free(otouch); free(owarm);
        nl_old_restore(nl, &old, ocap);
        return FLOE_ENOMEM;
    }
    for (int t = 0; t < nt; t++) {
        nl->found[t].n = 0;
        nl->found[t].rc = FLOE_OK;
    }
    double rmin = INFINITY;
    nb = 0;
    for (int i = 0; i < n; i++) {
        if (isfinite(p->radius[i])) {
            memcpy(bx + 3 * nb, p->x + 3 * i, 3 * sizeof(double));
            if (cell) {
                double d[3], sf[3];
                floe_v3_sub(d, p->x + 3 * i, cell->o);
                for (int r = 0; r < 3; r++) sf[r] = cell->Hinv[3 * r] * d[0] + cell->Hinv[3 * r + 1] * d[1] + cell->Hinv[3 * r + 2] * d[2];
                for (int r = 0; r < 3; r++) {
                    double fl = r < dim ? floor(sf[r]) : 0.0;
                    bsh[3 * nb + r] = -(int)fl;
                }
                for (int r = 0; r < 3; r++)
                    bx[3 * nb + r] += cell->H[3 * r] * bsh[3 * nb] + cell->H[3 * r + 1] * bsh[3 * nb + 1] +
                                      cell->H[3 * r + 2] * bsh[3 * nb + 2];
            }
            bidx[nb++] = i;
            if (p->radius[i] < rmin) rmin = p->radius[i];
        } else {
            nl->walls[nl->nwalls++] = i;
        }
    }
    if (nl->skin <= 0) nl->skin = isfinite(rmin) ? 0.1 * rmin : 0;
    double skin = nl->skin;
    int rc = FLOE_OK;
    floe_kdtree_destroy(nl->tree);
    nl->tree = nb ? floe_kdtree_build_threads(bx, nb, dim, leaf_size, nt) : NULL;
    if (nb && !nl->tree) rc = FLOE_ENOMEM;
    /* mixed sizes: each pair is found from its larger particle (ties: the lower index),
     * whose query radius 2 r_i + skin covers every partner no larger than itself, so a few
     * big particles do not inflate the search of all the small ones */
    /* periodic cell: each particle also looks for the images of the others through the
     * neighbouring cells' copies of itself, y + H m, m in {-1, 0, 1}^dim (the cell is wider than
     * a reach: floe_cell_prepare), skipping the copies whose ball misses the cell */
    nl_search S = {nl, p, cell, bidx, bsh, bx, skin, {INFINITY, INFINITY, INFINITY}, dim};
    if (cell)
        for (int r = 0; r < dim; r++) {
            const double *h = cell->Hinv + 3 * r;
            S.wd[r] = 1.0 / sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        }
    /* walls: plane through x with normal q*(0,0,1); each bounded particle within its radius
     * and the skin of one is paired with it, in the search's loop (its threads) */
    double *wnrm = rc == FLOE_OK && nl->nwalls ? malloc((size_t)nl->nwalls * 3 * sizeof(double)) : NULL;
    if (rc == FLOE_OK && nl->nwalls && !wnrm) rc = FLOE_ENOMEM;
    for (int a = 0; a < nl->nwalls && rc == FLOE_OK; a++) {
        const double ez[3] = {0, 0, 1};
        floe_q_rotate(wnrm + 3 * a, p->q + 4 * nl->walls[a], ez);
    }
    if (rc == FLOE_OK) {
        /* threads: each searches chunks of particles into its own buffer (nl_collect sorts) */
        FLOE_OMP(omp parallel for schedule(dynamic, 256) num_threads(nt) if (nt > 1))
        for (int a = 0; a < nb; a++) {
            struct floe_nl_found *fd = &nl->found[floe_par_thread()];
            if (fd->rc == FLOE_OK) fd->rc = search_one(&S, fd, a);
            const int i = bidx[a];
            for (int c = 0; c < nl->nwalls && fd->rc == FLOE_OK; c++) {
                const int wi = nl->walls[c];
                if (p->motion[i] != FLOE_FREE && p->motion[wi] != FLOE_FREE) continue;
                double d[3];
                floe_v3_sub(d, p->x + 3 * i, p->x + 3 * wi);
                if (floe_v3_dot(d, wnrm + 3 * c) <= p->radius[i] + skin) fd->rc = push_pair(fd, nl, p, i, wi, NULL);
            }
        }
        for (int t = 0; t < nt && rc == FLOE_OK; t++) rc = nl->found[t].rc;
    }
    free(wnrm);
    /* the tree serves this search only: not kept between builds (28 B a particle and its nodes) */
    floe_kdtree_destroy(nl->tree);
    nl->tree = NULL;
    if (rc == FLOE_OK) {
        double *qw = realloc(nl->q_walls, (size_t)(nl->nwalls ? nl->nwalls : 1) * 4 * sizeof(double));
        if (!qw) rc = FLOE_ENOMEM;
        else {
            nl->q_walls = qw;
            for (int a = 0; a < nl->nwalls; a++) memcpy(qw + 4 * a, p->q + 4 * nl->walls[a], 4 * sizeof(double));
        }
    }
    free(bx);
    free(bidx);
    free(bsh);
    /* deterministic order, cache friendly: sorted by (i, j, piece pair, image) */
    int *row = NULL;
    if (rc == FLOE_OK) rc = nl_collect(nl, n, nt, &row);
    for (int t = 0; t < nt; t++) { /* 16 bytes per entry: not kept between builds */
        free(nl->found[t].e);
        nl->found[t].e = NULL;
        nl->found[t].cap = nl->found[t].n = 0;
    }
    /* the history's arrays for the new entries (merge: for the old ones too until they moved) */
    const size_t np_old = merge ? (size_t)old.npairs : 0;
    if (rc == FLOE_OK) {
        size_t np = nl->npairs ? nl->npairs : 1;
        if (np < np_old) np = np_old;
        double *h = realloc(nl->hist, np * HS * sizeof(double));
        unsigned char *t = h ? realloc(nl->touching, np) : NULL;
        if (h) nl->hist = h;
        if (t) nl->touching = t;
        if (!h || !t) rc = FLOE_ENOMEM;
        if (rc == FLOE_OK && nl->use_warm) {
            double *wm = realloc(nl->warm, np * FLOE_DETECT_WARM * sizeof(double));
            if (!wm) rc = FLOE_ENOMEM;
            else nl->warm = wm;
        }
    }
    int *orow = rc == FLOE_OK && merge ? malloc((size_t)(n + 1) * sizeof *orow) : NULL;
    int *src = orow ? malloc((size_t)(nl->npairs ? nl->npairs : 1) * sizeof *src) : NULL;
    if (merge && rc == FLOE_OK && !src) rc = FLOE_ENOMEM;
    if (rc == FLOE_OK && merge) {
        /* the old rows of particles [0, n] (an old row of a particle since removed: none);
         * threads: runs of particles */
        FLOE_OMP(omp parallel for schedule(static, 1) num_threads(nt) if (nt > 1))
        for (int t = 0; t < nt; t++)
            floe_list_rows(old.pi, old.npairs, (int)((long long)(n + 1) * t / nt), (int)((long long)(n + 1) * (t + 1) / nt),
                           orow);
        if (nt > 1) {
            /* rows in nt runs of about the same number of entries */
            FLOE_OMP(omp parallel for schedule(static, 1) num_threads(nt))
            for (int t = 0; t < nt; t++) {
                int i0, i1;
                row_run(row, n, nl->npairs, t, nt, &i0, &i1);
                nl_match_rows(nl, &old, row, orow, i0, i1, use_warm, src);
            }
        } else
            nl_match_rows(nl, &old, row, orow, 0, n, use_warm, src);
        nl_move_history(nl, src, nl->npairs, use_warm, nt);
        if ((size_t)nl->npairs < np_old) { /* fewer entries: the arrays shrink (a smaller block keeps its start) */
            const size_t np = nl->npairs ? nl->npairs : 1;
            double *h = realloc(nl->hist, np * HS * sizeof(double));
            unsigned char *t = realloc(nl->touching, np);
            if (h) nl->hist = h;
            if (t) nl->touching = t;
            if (nl->use_warm) {
                double *wm = realloc(nl->warm, np * FLOE_DETECT_WARM * sizeof(double));
                if (wm) nl->warm = wm;
            }
        }
    } else if (rc == FLOE_OK) {
        memset(nl->hist, 0, (size_t)nl->npairs * HS * sizeof(double));
        memset(nl->touching, 0, nl->npairs);
        if (nl->use_warm)
            for (size_t k = 0; k < (size_t)nl->npairs * FLOE_DETECT_WARM; k++) nl->warm[k] = NAN;
        if (nold) {
            FLOE_OMP(omp parallel for schedule(static) num_threads(nt) if (nt > 1))
            for (int k = 0; k < nl->npairs; k++) {
                uint64_t key = pair_key(nl->pi[k], nl->pj[k]);
                const int im = cell ? nl->img[k] : 0;
                size_t h = entry_hash(key, nl->sub[k], im) & (hcap - 1);
                while (okeys[h] != UINT64_MAX && (okeys[h] != key || osub[h] != nl->sub[k] || oimg[h] != im))
                    h = (h + 1) & (hcap - 1);
                if (okeys[h] == key) {
                    memcpy(nl->hist + (size_t)k * HS, ohist + h * HS, HS * sizeof(double));
                    nl->touching[k] = otouch[h];
                    if (owarm && nl->use_warm)
                        memcpy(nl->warm + (size_t)k * FLOE_DETECT_WARM, owarm + h * FLOE_DETECT_WARM,
                               FLOE_DETECT_WARM * sizeof(double));
                }
            }
        }
    }
    free(row);
    free(orow);
    free(src);
    if (rc == FLOE_OK) {
        double *xb = nl->n_build == n && nl->x_build ? nl->x_build : realloc(nl->x_build, (size_t)(n ? n : 1) * 3 * sizeof(double));
        double *rb = xb ? realloc(nl->r_build, (size_t)(n ? n : 1) * sizeof(double)) : NULL;
        if (xb) nl->x_build = xb;
        if (rb) nl->r_build = rb;
        if (!xb || !rb) rc = FLOE_ENOMEM;
        else {
            if (n > 0) {
                memcpy(nl->x_build, p->x, (size_t)n * 3 * sizeof(double));
                memcpy(nl->r_build, p->radius, (size_t)n * sizeof(double));
            }
            nl->n_build = n;
            nl->rebuilds++;
            if (cell) {
                memcpy(nl->Hb, cell->H, sizeof nl->Hb);
                double rm = 0;
                for (int i = 0; i < n; i++)
                    if (isfinite(p->radius[i]) && p->radius[i] > rm) rm = p->radius[i];
                nl->rmax_b = rm;
            }
        }
    }
    free(okeys);
    free(ohist);
    free(osub);
    free(oimg);
    free(otouch);
    free(owarm);
    if (rc) { /* leave a consistent (empty) list: the caller reports the error */
        nl_old_restore(nl, &old, ocap);
        nl->npairs = 0;
        nl->n_build = 0;
    }
    nl_old_free(&old);
    return rc;
}
