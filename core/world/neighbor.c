/* neighbor.c - candidate pairs from the k-d tree over bounding spheres, with a Verlet
 * skin: the list holds every pair whose bounding spheres are closer than the skin, and
 * is rebuilt only when some particle has moved (or grown) by more than skin/2 since the
 * last build. Walls (unbounded planes) are paired with every particle within reach.
 * Per-pair history (shear springs) survives rebuilds through a hash of the pair. */
#include "world_internal.h"
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int floe_nl_init(floe_neighbor_list *nl) {
    memset(nl, 0, sizeof *nl);
    return FLOE_OK;
}

void floe_nl_free(floe_neighbor_list *nl) {
    floe_kdtree_destroy(nl->tree);
    free(nl->pi); free(nl->pj); free(nl->sub); free(nl->img); free(nl->warm); free(nl->hist); free(nl->touching);
    free(nl->x_build); free(nl->walls); free(nl->scratch); free(nl->r_build); free(nl->q_walls); free(nl->cand);
    memset(nl, 0, sizeof *nl);
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
    for (int i = 0; i < p->n; i++) {
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

static int push_one(floe_neighbor_list *nl, int i, int j, int sub, int img) {
    if (nl->npairs == nl->cap) {
        int nc = nl->cap ? 2 * nl->cap : 1024;
        int *a = realloc(nl->pi, nc * sizeof(int));
        if (!a) return FLOE_ENOMEM;
        nl->pi = a;
        int *b = realloc(nl->pj, nc * sizeof(int));
        if (!b) return FLOE_ENOMEM;
        nl->pj = b;
        int *c = realloc(nl->sub, nc * sizeof(int));
        if (!c) return FLOE_ENOMEM;
        nl->sub = c;
        if (nl->cell) {
            int *d = realloc(nl->img, nc * sizeof(int));
            if (!d) return FLOE_ENOMEM;
            nl->img = d;
        }
        nl->cap = nc;
    }
    nl->pi[nl->npairs] = i;
    nl->pj[nl->npairs] = j;
    nl->sub[nl->npairs] = sub;
    if (nl->cell) nl->img[nl->npairs] = img;
    nl->npairs++;
    return FLOE_OK;
}

/* one entry per piece pair: compound bodies turn with respect to their centre of mass
 * without a rebuild, so all their piece pairs are listed and culled in the force loop */
static int push_pair(floe_neighbor_list *nl, const floe_particles *p, int i, int j, const int n[3]) {
    int img = 0;
    /* MPI: the pair in global-id order, as in the serial world (a history's sign convention
     * follows its order) */
    if (nl->gid ? nl->gid[i] > nl->gid[j] : i > j) {
        int t = i; i = j; j = t;
        if (n) img = floe_img_encode(-n[0], -n[1], -n[2]);
    } else if (n) img = floe_img_encode(n[0], n[1], n[2]);
    int na = p->pieces ? p->pieces[i] : 1, nb = p->pieces ? p->pieces[j] : 1;
    if (na == 1 && nb == 1) return push_one(nl, i, j, 0, img);
    for (int a = 0; a < na; a++)
        for (int b = 0; b < nb; b++) FLOE_TRY(push_one(nl, i, j, FLOE_SUB(a, b), img));
    return FLOE_OK;
}

static int cmp_pair(const void *a, const void *b) {
    const int *x = a, *y = b;
    if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
    if (x[1] != y[1]) return x[1] < y[1] ? -1 : 1;
    if (x[2] != y[2]) return x[2] < y[2] ? -1 : 1;
    return (x[3] > y[3]) - (x[3] < y[3]);
}
/* an entry is (i, j, piece pair, image): the history follows all four */
static uint64_t entry_hash(uint64_t key, int sub, int img) {
    return mix(key ^ ((uint64_t)(uint32_t)sub * 0x9E3779B97F4A7C15ULL) ^ ((uint64_t)(uint32_t)img << 17));
}

int floe_nl_build(floe_neighbor_list *nl, const floe_particles *p, int dim, int leaf_size) {
    int n = p->n;
    nl->gen++;
    /* keep the history of touching pairs */
    int nold = 0;
    uint64_t *okeys = NULL;
    double *ohist = NULL, *owarm = NULL;
    int *osub = NULL, *oimg = NULL;
    const floe_cell_state *cell = nl->cell;
    const int *img_old = nl->img && nl->npairs ? nl->img : NULL;
    unsigned char *otouch = NULL;
    int hcap = 0;
    const int W = FLOE_DETECT_WARM, use_warm = nl->use_warm && nl->warm;
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
        ohist = malloc((size_t)hcap * FLOE_MAX_HISTORY * sizeof *ohist);
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
            memcpy(ohist + h * FLOE_MAX_HISTORY, nl->hist + (size_t)k * FLOE_MAX_HISTORY,
                   FLOE_MAX_HISTORY * sizeof(double));
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
    int *bidx = malloc((nb ? nb : 1) * sizeof(int));
    double *bx = malloc((nb ? nb : 1) * 3 * sizeof(double));
    /* periodic cell: the tree holds the positions wrapped into the cell, x + H sh */
    int *bsh = cell ? malloc((nb ? nb : 1) * 3 * sizeof(int)) : NULL;
    int *nimg = cell && !nl->img ? malloc((size_t)(nl->cap ? nl->cap : 1) * sizeof(int)) : NULL;
    if (nimg) nl->img = nimg;
    nl->walls = malloc((nw ? nw : 1) * sizeof(int));
    if (!bidx || !bx || !nl->walls || (cell && (!bsh || !nl->img))) {
        free(bidx); free(bx); free(bsh); free(okeys); free(ohist); free(osub); free(oimg); free(otouch); free(owarm);
        return FLOE_ENOMEM;
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
    nl->tree = nb ? floe_kdtree_build(bx, nb, dim, leaf_size) : NULL;
    if (nb && !nl->tree) rc = FLOE_ENOMEM;
    /* mixed sizes: each pair is found from its larger particle (ties: the lower index),
     * whose query radius 2 r_i + skin covers every partner no larger than itself, so a few
     * big particles do not inflate the search of all the small ones */
    /* periodic cell: each particle also looks for the images of the others through the
     * neighbouring cells' copies of itself, y + H m, m in {-1, 0, 1}^dim (the cell is wider than
     * a reach: floe_cell_prepare), skipping the copies whose ball misses the cell */
    double wd[3] = {INFINITY, INFINITY, INFINITY};
    if (cell)
        for (int r = 0; r < dim; r++) {
            const double *h = cell->Hinv + 3 * r;
            wd[r] = 1.0 / sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        }
    const int mr = cell ? 1 : 0, mz = cell && dim == 3 ? 1 : 0;
    for (int a = 0; a < nb && rc == FLOE_OK; a++)
      for (int m0 = -mr; m0 <= mr && rc == FLOE_OK; m0++)
      for (int m1 = -mr; m1 <= mr && rc == FLOE_OK; m1++)
      for (int m2 = -mz; m2 <= mz && rc == FLOE_OK; m2++) {
        int i = bidx[a];
        double reach = 2 * p->radius[i] + skin;
        const double *qx = p->x + 3 * i;
        double qy[3];
        const int m[3] = {m0, m1, m2};
        if (cell) {
            double d[3], sf[3];
            floe_v3_sub(d, bx + 3 * a, cell->o);
            int skip = 0;
            for (int r = 0; r < 3; r++) {
                sf[r] = cell->Hinv[3 * r] * d[0] + cell->Hinv[3 * r + 1] * d[1] + cell->Hinv[3 * r + 2] * d[2] + m[r];
                if (r < dim && (sf[r] * wd[r] < -reach || (sf[r] - 1) * wd[r] > reach)) skip = 1;
            }
            if (skip) continue;
            for (int r = 0; r < 3; r++)
                qy[r] = bx[3 * a + r] + cell->H[3 * r] * m0 + cell->H[3 * r + 1] * m1 + cell->H[3 * r + 2] * m2;
            qx = qy;
        }
        int cnt;
        for (;;) {
            cnt = floe_kdtree_radius(nl->tree, qx, reach, nl->scratch, nl->scratch_cap);
            if (cnt <= nl->scratch_cap) break;
            int nc = cnt + cnt / 2 + 64;
            int *s = realloc(nl->scratch, nc * sizeof(int));
            if (!s) { rc = FLOE_ENOMEM; break; }
            nl->scratch = s;
            nl->scratch_cap = nc;
        }
        if (rc) break;
        for (int k = 0; k < cnt; k++) {
            const int b = nl->scratch[k], j = bidx[b];
            if (p->radius[j] > p->radius[i] || (p->radius[j] == p->radius[i] && j <= i)) continue;
            if (p->motion[i] != FLOE_FREE && p->motion[j] != FLOE_FREE) continue;
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
            double lim = p->radius[i] + p->radius[j] + skin;
            if (floe_v3_dot(d, d) <= lim * lim) rc = push_pair(nl, p, i, j, cell ? n : NULL);
        }
    }
    if (rc == FLOE_OK) {
        double *qw = realloc(nl->q_walls, (size_t)(nl->nwalls ? nl->nwalls : 1) * 4 * sizeof(double));
        if (!qw) rc = FLOE_ENOMEM;
        else {
            nl->q_walls = qw;
            for (int a = 0; a < nl->nwalls; a++) memcpy(qw + 4 * a, p->q + 4 * nl->walls[a], 4 * sizeof(double));
        }
    }
    /* walls: plane through x with normal q*(0,0,1) */
    for (int a = 0; a < nl->nwalls && rc == FLOE_OK; a++) {
        int wi = nl->walls[a];
        double nw[3];
        const double ez[3] = {0, 0, 1};
        floe_q_rotate(nw, p->q + 4 * wi, ez);
        for (int b = 0; b < nb && rc == FLOE_OK; b++) {
            int i = bidx[b];
            if (p->motion[i] != FLOE_FREE && p->motion[wi] != FLOE_FREE) continue;
            double d[3];
            floe_v3_sub(d, p->x + 3 * i, p->x + 3 * wi);
            if (floe_v3_dot(d, nw) <= p->radius[i] + skin) rc = push_pair(nl, p, i, wi, NULL);
        }
    }
    free(bx);
    free(bidx);
    free(bsh);
    if (rc == FLOE_OK) {
        /* deterministic order, cache friendly: sort by (i, j) */
        int *tmp = malloc((size_t)(nl->npairs ? nl->npairs : 1) * 4 * sizeof(int));
        if (!tmp) rc = FLOE_ENOMEM;
        else {
            for (int k = 0; k < nl->npairs; k++) {
                tmp[4 * k] = nl->pi[k]; tmp[4 * k + 1] = nl->pj[k]; tmp[4 * k + 2] = nl->sub[k];
                tmp[4 * k + 3] = cell ? nl->img[k] : 0;
            }
            qsort(tmp, nl->npairs, 4 * sizeof(int), cmp_pair);
            for (int k = 0; k < nl->npairs; k++) {
                nl->pi[k] = tmp[4 * k]; nl->pj[k] = tmp[4 * k + 1]; nl->sub[k] = tmp[4 * k + 2];
                if (cell) nl->img[k] = tmp[4 * k + 3];
            }
            free(tmp);
        }
    }
    if (rc == FLOE_OK) {
        size_t np = nl->npairs ? nl->npairs : 1;
        double *h = realloc(nl->hist, np * FLOE_MAX_HISTORY * sizeof(double));
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
    if (rc == FLOE_OK) {
        memset(nl->hist, 0, (size_t)nl->npairs * FLOE_MAX_HISTORY * sizeof(double));
        memset(nl->touching, 0, nl->npairs);
        if (nl->use_warm)
            for (size_t k = 0; k < (size_t)nl->npairs * FLOE_DETECT_WARM; k++) nl->warm[k] = NAN;
        if (nold) {
            for (int k = 0; k < nl->npairs; k++) {
                uint64_t key = pair_key(nl->pi[k], nl->pj[k]);
                const int im = cell ? nl->img[k] : 0;
                size_t h = entry_hash(key, nl->sub[k], im) & (hcap - 1);
                while (okeys[h] != UINT64_MAX && (okeys[h] != key || osub[h] != nl->sub[k] || oimg[h] != im))
                    h = (h + 1) & (hcap - 1);
                if (okeys[h] == key) {
                    memcpy(nl->hist + (size_t)k * FLOE_MAX_HISTORY, ohist + h * FLOE_MAX_HISTORY,
                           FLOE_MAX_HISTORY * sizeof(double));
                    nl->touching[k] = otouch[h];
                    if (owarm && nl->use_warm)
                        memcpy(nl->warm + (size_t)k * FLOE_DETECT_WARM, owarm + h * FLOE_DETECT_WARM,
                               FLOE_DETECT_WARM * sizeof(double));
                }
            }
        }
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
        nl->npairs = 0;
        nl->n_build = 0;
    }
    return rc;
}
