/* pd_materials.c - PD material vtables: PMB bond-based (000 eqs 9-12, 003 eqs 2-5) and the
 * linear peridynamic solid (000 eqs 15-25, ParticLS eqs 30-35; 2D: Le, Silling & Bobaru 2014)
 * with its position-aware surface correction (floe_pd.h). One pass per bond (each bond
 * is stored once, i < j); forces are applied to both ends. With threads (b->nthreads) the
 * rows run in parallel and each point gathers its bonds' forces in the serial order: the
 * same bits for any thread count ("threads" below, docs/parallel.md). */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "floe_pd.h"
#include "floe_par.h"
#include "pd_par.h"

/* ---------------------------------------------------------------- PMB ---- */

static void free_lps(floe_pd_body *b)
{
    free(b->m);
    free(b->theta);
    free(b->wbond);
    free(b->dten); /* the LPS surface correction goes with the material */
    b->m = b->theta = b->wbond = b->dten = NULL;
}

/* Micromodulus: 3D c = 18K/(pi delta^4) (000 eq 10; equals 003 eq 3 at nu = 1/4);
 * 2D plane stress c = 9E/(pi h delta^3) (nu = 1/3), plane strain c = 48E/(5 pi h delta^3)
 * (nu = 1/4) (Bobaru et al. 2009; Ha & Bobaru 2010), h the thickness. 000 gives only the 3D
 * constant. */
static int pmb_init(floe_pd_body *b)
{
    const floe_pd_material *m = &b->mat;
    double c = m->c;
    if (!(c >= 0) || !(m->alpha >= 0) || !isfinite(m->alpha)) return FLOE_EINVAL;
    if (c == 0) {
        double d = b->delta;
        if (b->dim == 3) {
            if (!(m->K > 0)) return FLOE_EINVAL;
            c = 18.0 * m->K / (M_PI * d * d * d * d);
        } else {
            if (!(m->E > 0)) return FLOE_EINVAL;
            double h = b->thickness;
            c = m->plane == FLOE_PD_PLANE_STRAIN ? 48.0 * m->E / (5.0 * M_PI * h * d * d * d)
                                                 : 9.0 * m->E / (M_PI * h * d * d * d);
        }
    }
    /* per-point critical stretch (alpha > 0): s0 starts at DBL_MAX, as in LAMMPS, so no bond
     * breaks before the first evaluation has measured the stretches */
    if (m->alpha > 0) {
        if (!b->s0) {
            b->s0 = malloc(2 * (size_t)(b->n > 0 ? b->n : 1) * sizeof *b->s0);
            if (!b->s0) return FLOE_ENOMEM;
        }
        for (int i = 0; i < b->n; i++) b->s0[i] = DBL_MAX;
    } else {
        free(b->s0);
        b->s0 = NULL;
    }
    /* elastic-perfectly-plastic bonds (003 eq 6): one plastic stretch per bond */
    if (!(m->yield_compression >= 0) || !(m->yield_tension >= 0) || !isfinite(m->yield_compression) ||
        !isfinite(m->yield_tension))
        return FLOE_EINVAL;
    if (m->yield_compression > 0 || m->yield_tension > 0) {
        if (m->alpha > 0) return FLOE_EINVAL; /* one extension at a time */
        if (!b->splast) {
            b->splast = calloc((size_t)(b->nbond > 0 ? b->nbond : 1), sizeof *b->splast);
            if (!b->splast) return FLOE_ENOMEM;
        }
    } else {
        free(b->splast);
        b->splast = NULL;
    }
    b->c = c;
    free_lps(b);
    return FLOE_OK;
}

static double pmb_c(const floe_pd_body *b) { return b->c; }

/* ------------------------------------------------------------ threads ---- */

/* The bond loops below run over the rows i (each bond k = (i, j) once, j > i) and add a
 * bond's force to j when they meet it and i's row sum at the end of row i. Threaded
 * (b->nthreads > 1, pd_par.h), the rows are computed in parallel, one part of consecutive
 * blocks per thread: a point whose every row lies in one part (P->own) gets its shares where
 * the serial loop adds them, from that part's thread; for the others (the parts' borders)
 * each bond's share of j goes into P->g and each row's sums into P->row, and the point then
 * gathers them in the order of the serial loop (pd_gather): the same additions, the same
 * bits. A bond that adds nothing stores +0 for a subtraction (x - +0 = x) and -0 for an addition (x + -0 = x), for every x.
 * Energies and broken counts are summed per block of FLOE_PD_ROW_BLOCK rows and the blocks in
 * order, on one thread too. */

void floe_pd_par_free(floe_pd_body *b)
{
    if (!b || !b->par) return;
    floe_pd_par *P = b->par;
    free(P->roff); free(P->rk); free(P->cut); free(P->g); free(P->row); free(P->blk); free(P->blkn); free(P->own); free(P->border);
    free(P->gslot); free(P->bslot); free(P->bsplit);
    free(P);
    b->par = NULL;
}

/* the threads of this evaluation: b->nthreads, at most one per block of rows */
static int pd_threads(const floe_pd_body *b)
{
#ifdef _OPENMP
    const int nblk = (b->n + FLOE_PD_ROW_BLOCK - 1) / FLOE_PD_ROW_BLOCK;
    const int nt = b->nthreads < nblk ? b->nthreads : nblk;
    return nt > 1 ? nt : 1;
#else
    (void)b;
    return 1;
#endif
}

static int pd_grow(void **ptr, size_t need, size_t *cap, size_t size)
{
    if (need <= *cap) return 0;
    void *t = realloc(*ptr, need * size);
    if (!t) return -1;
    *ptr = t;
    *cap = need;
    return 0;
}

/* the row whose bonds hold bond k (b->off ascending) */
static int pd_row_of(const floe_pd_body *b, int64_t k)
{
    int lo = 0, hi = b->n - 1;
    while (lo < hi) {
        const int mid = lo + (hi - lo + 1) / 2;
        if (b->off[mid] <= k) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

/* the bonds of the rows in blocks [0, c) */
static int64_t pd_bonds_below(const floe_pd_body *b, int c)
{
    const int64_t r = (int64_t)c * FLOE_PD_ROW_BLOCK;
    return b->off[r < b->n ? r : b->n];
}

/* the part that holds row r (parts cut[t] <= r's block < cut[t + 1]) */
static int pd_part_of(const int *cut, int nt, int r)
{
    const int c = r / FLOE_PD_ROW_BLOCK;
    int lo = 0, hi = nt - 1;
    while (lo < hi) {
        const int mid = lo + (hi - lo + 1) / 2;
        if (cut[mid] <= c) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

/* The buffers of a threaded evaluation on nt threads: the parts, the owned and border
 * points, gs doubles per border bond and rs per point (cut again when the bonds or the
 * thread count changed); NULL when out of memory: the caller then runs the serial loop,
 * which gives the same bits. */
static floe_pd_par *pd_par_get(floe_pd_body *b, int gs, int rs, int nt)
{
    if (!b->par && !(b->par = calloc(1, sizeof *b->par))) return NULL;
    floe_pd_par *P = b->par;
    const int n = b->n;
    const int64_t nb = b->nbond;
    const int nblk = (n + FLOE_PD_ROW_BLOCK - 1) / FLOE_PD_ROW_BLOCK;
    /* one part per thread, the same thread's at every evaluation (schedule(static) below):
     * its points' cache lines stay in that core's caches from one step to the next. The
     * border points (those a row of another part adds to) are few when the points are
     * numbered layer by layer (a body's lattice). Until session 7 there were two parts per
     * thread handed out dynamically (on bench/pd-impact 1.15-1.25x faster than one part per
     * thread on the dynamic schedule, a breaking region unbalancing them); the fixed parts ran
     * pd-impact's 2-thread steps 1.0-1.25x faster than those (bench/RESULTS.md, "Issue 14,
     * session 7"): moving a part between the cores cost more than the imbalance. The parts
     * are cut at equal bonds, not equal rows (session 36): a row holds its bonds to higher
     * indices, so the last rows of a body numbered layer by layer hold fewer (pd-impact's
     * first half of the rows held 6 % more bonds than its second). */
    /* the reverse index (kept only while the parts are cut: its bond list is freed after) */
    if (!P->roff || P->n != n || P->nbond != nb || (P->nparts != nt && !P->rk)) {
        free(P->roff); /* a failure below leaves the index unbuilt */
        free(P->rk);
        P->roff = P->rk = NULL;
        int64_t *roff = calloc((size_t)n + 1, sizeof *roff), *rk = malloc((size_t)(nb > 0 ? nb : 1) * sizeof *rk);
        if (!roff || !rk) { free(roff); free(rk); return NULL; }
        for (int64_t k = 0; k < nb; k++) roff[b->partner[k] + 1]++;
        for (int p = 0; p < n; p++) roff[p + 1] += roff[p];
        for (int64_t k = 0; k < nb; k++) rk[roff[b->partner[k]]++] = k; /* ascending k per partner */
        for (int p = n; p > 0; p--) roff[p] = roff[p - 1];
        roff[0] = 0;
        P->roff = roff;
        P->rk = rk;
        P->n = n;
        P->nbond = nb;
        P->nparts = 0; /* own[] below */
    }
    if (P->nparts != nt) {
        P->nparts = 0; /* until all of it is built */
        if (nb > INT32_MAX) return NULL; /* slots are int32: the serial loop then */
        int *cut = realloc(P->cut, (size_t)(nt + 1) * sizeof *cut);
        if (!cut) return NULL;
        P->cut = cut;
        /* part t: blocks [cut[t], cut[t + 1]), cut at the block border nearest to where the
         * bonds below reach t / nt of all, a block at least each (nt <= nblk: pd_threads) */
        cut[0] = 0;
        for (int t = 1, c = 0; t < nt; t++) {
            const int64_t aim = nb * t; /* bonds below the border, times nt */
            /* (the bonds below nblk are all: c stops below it) */
            while (pd_bonds_below(b, c + 1) * nt < aim) c++;
            int k = pd_bonds_below(b, c + 1) * nt - aim < aim - pd_bonds_below(b, c) * nt ? c + 1 : c;
            if (k < cut[t - 1] + 1) k = cut[t - 1] + 1;
            if (k > nblk - (nt - t)) k = nblk - (nt - t);
            cut[t] = k;
        }
        cut[nt] = nblk;
        uint8_t *own = realloc(P->own, (size_t)(n > 0 ? n : 1));
        if (own) P->own = own;
        int *bd = own ? realloc(P->border, (size_t)(n > 0 ? n : 1) * sizeof *bd) : NULL;
        if (bd) P->border = bd;
        int32_t *gslot = bd ? realloc(P->gslot, (size_t)(nb > 0 ? nb : 1) * sizeof *gslot) : NULL;
        if (gslot) P->gslot = gslot;
        int64_t *bslot = gslot ? realloc(P->bslot, (size_t)(n + 1) * sizeof *bslot) : NULL;
        if (bslot) P->bslot = bslot;
        int64_t *bsplit = bslot ? realloc(P->bsplit, (size_t)(n > 0 ? n : 1) * sizeof *bsplit) : NULL;
        if (!bsplit) return NULL;
        P->bsplit = bsplit;
        P->nborder = 0;
        const int64_t *roff = P->roff, *rk = P->rk;
        for (int q = 0; q < n; q++) { /* the rows that add to q: its own and rows below it, the
                                         * lowest that of its first bond as partner (the parts
                                         * are runs of rows: the rows between lie in them too) */
            const int64_t e0 = roff[q], e1 = roff[q + 1];
            own[q] = e0 == e1 || pd_part_of(cut, nt, pd_row_of(b, rk[e0])) == pd_part_of(cut, nt, q);
            if (!own[q]) bd[P->nborder++] = q;
        }
        /* the border points' bonds in slots, point by point in the gather's order */
        for (int64_t k = 0; k < nb; k++) gslot[k] = -1;
        int64_t ns = 0;
        for (int e = 0; e < P->nborder; e++) {
            const int q = bd[e];
            bslot[e] = ns;
            bsplit[e] = -1;
            for (int64_t r = roff[q]; r < roff[q + 1]; r++) {
                if (bsplit[e] < 0 && rk[r] >= b->off[q]) bsplit[e] = ns;
                gslot[rk[r]] = (int32_t)ns++;
            }
            if (bsplit[e] < 0) bsplit[e] = ns;
        }
        bslot[P->nborder] = ns;
        P->nslot = ns;
        P->nparts = nt;
        free(P->rk); /* 8 B a bond: the slots took its place */
        P->rk = NULL;
    }
    size_t bc = (size_t)P->blk_cap;
    if (pd_grow((void **)&P->g, (size_t)gs * (size_t)(P->nslot > 0 ? P->nslot : 1), &P->g_cap, sizeof(double)) ||
        pd_grow((void **)&P->row, (size_t)rs * (size_t)(n > 0 ? n : 1), &P->row_cap, sizeof(double)))
        return NULL;
    if ((size_t)nblk > bc) {
        double *e = realloc(P->blk, (size_t)nblk * sizeof *e);
        if (!e) return NULL;
        P->blk = e;
        int64_t *c = realloc(P->blkn, (size_t)nblk * sizeof *c);
        if (!c) return NULL;
        P->blkn = c;
        P->blk_cap = nblk;
    }
    return P;
}

/* The bond vector from i (at xi0, xi1, xi2) to its partner j; a bond across
 * the periodic cell's faces (img[k] != 0) goes to j's image. */
static inline __attribute__((always_inline)) void pd_bond_vec(const double *x, int j, double xi0, double xi1,
                                                              double xi2, int per, const int32_t *img,
                                                              const double *H, int64_t k, double *d0, double *d1,
                                                              double *d2)
{
    const double *xj = x + 3 * (size_t)j;
    *d0 = xj[0] - xi0; *d1 = xj[1] - xi1; *d2 = xj[2] - xi2;
    if (per && img[k]) {
        double sh[3];
        floe_img_shift(H, img[k], sh);
        *d0 += sh[0]; *d1 += sh[1]; *d2 += sh[2];
    }
}

/* Border point q = P->border[eb]'s sums in the serial loop's order: v[0 .. gs) (from v's
 * values: f, or 0) gets the shares of the bonds whose partner q is (its slots), in
 * increasing k, added (sub = 0) or subtracted
 * (sub = 1), and q's own row sums row[0 .. gs) where the serial loop adds them: after the
 * bonds of the rows below q, before those of rows above (none: every partner is above its
 * row). With mx (PMB alpha) the shares' and the row's slot gs is a maximum (first of equal
 * values, as the serial loop keeps it), into *mx from -INFINITY. */
static inline __attribute__((always_inline)) void pd_gather(const floe_pd_par *P, int eb, double *v, const int gs,
                                                            const int st, const int sub, double *mx)
{
    const int q = P->border[eb];
    const int64_t split = P->bsplit[eb], e1 = P->bslot[eb + 1];
    const double *row = P->row + (size_t)st * (size_t)q;
    double m = -INFINITY;
    int64_t e = P->bslot[eb];
    for (; e < split; e++) {
        const double *g = P->g + (size_t)st * (size_t)e;
        for (int c = 0; c < gs; c++) v[c] = sub ? v[c] - g[c] : v[c] + g[c];
        if (mx && g[gs] > m) m = g[gs];
    }
    for (int c = 0; c < gs; c++) v[c] += row[c];
    if (mx && row[gs] > m) m = row[gs];
    for (; e < e1; e++) {
        const double *g = P->g + (size_t)st * (size_t)e;
        for (int c = 0; c < gs; c++) v[c] = sub ? v[c] - g[c] : v[c] + g[c];
        if (mx && g[gs] > m) m = g[gs];
    }
    if (mx) *mx = m;
}

/* f[q] after a threaded force loop: f minus the bonds' shares, plus the row sum */
static inline __attribute__((always_inline)) void pd_gather_f(const floe_pd_par *P, int eb, double *f, const int st,
                                                              double *mx)
{
    const int q = P->border[eb];
    double v[3] = {f[3 * (size_t)q], f[3 * (size_t)q + 1], f[3 * (size_t)q + 2]};
    pd_gather(P, eb, v, 3, st, 1, mx);
    f[3 * (size_t)q] = v[0];
    f[3 * (size_t)q + 1] = v[1];
    f[3 * (size_t)q + 2] = v[2];
}
/* 000 eqs 9-12 / 003 eq 2: pair force c s mu beta V_i V_j along the deformed bond, with
 * s = (|y| - |xi|)/|xi| (003 eq 4). A bond breaks when s > s_c and stays broken; a broken
 * bond still pushes in compression when broken_tension_only is set (003: mu = 1 for s <= 0).
 * Energy per bond: 1/2 c s^2 |xi| beta V_i V_j, whose gradient is the force above.
 *
 * With alpha > 0 (LAMMPS pair peri/pmb, Parks et al. 2008) the critical stretch of bond
 * (i, j) is min(s0_i, s0_j) with s0 from the previous evaluation, and this evaluation builds
 * s0_i = s00 - alpha min_j s_ij = max_j (s00 - alpha s_ij) over i's bonds intact at its start
 * (a bond breaking now still counts, as in LAMMPS; a point without intact bonds gets
 * DBL_MAX), s00 = s_c. Also as in LAMMPS, a bond that breaks in this evaluation still
 * carries its force (and energy) in it; the constant-s_c rule drops it at once. (Measured on
 * the pd-impact benchmark: with this order floe's damage follows LAMMPS' within 2.4 % at
 * every 100 steps; without it 8-11 % off.) Without breakage (s_c = 0,
 * floe_pd_forces_nobreak) s0 is left as is.
 * `alpha_on` is a constant at both call sites, so the compiler drops the branch from the
 * constant-s_c loop.
 *
 * Row i: its energy returned, bonds broken counted in *nbroken. Serial (gb NULL): the forces
 * added to f and s0n[j] raised as the loop meets them. Threaded: each bond's force on i (and
 * with alpha its candidate s00 - alpha s for both ends' s0, -INFINITY for none) into gb, the
 * row's force sum (and its own s0 candidate) into rb, stride 4 with alpha, else 3. */
static inline __attribute__((always_inline)) double pmb_row(floe_pd_body *b, const double *x, double *f, int i,
                                                            double *s0n, double *gb, double *rb, const uint8_t *own,
                                                            const int32_t *gslot, int64_t *nbroken, const int alpha_on,
                                                            const int per, const uint8_t *sm)
{
    const int32_t *img = per ? b->img : NULL;
    const double *H = per ? b->cellH : NULL;
    const double c = b->c, s_c = b->s_c, alpha = b->mat.alpha;
    const int comp = b->mat.broken_tension_only, st = alpha_on ? 4 : 3;
    const double *V = b->V;
    const int32_t *part = b->partner;
    const double *len = b->len;
    const float *vfac = b->vfac, *scorr = b->scorr;
    uint8_t *brk = b->broken;
    const double *s0 = alpha_on ? b->s0 : NULL;
    const double xi0 = x[3 * (size_t)i], xi1 = x[3 * (size_t)i + 1], xi2 = x[3 * (size_t)i + 2];
    const double Vi = V[i];
    const double s0i = alpha_on ? s0[i] : 0.0;
    const int owni = !gb || own[i];
    double s0ni = alpha_on ? (owni ? s0n[i] : -INFINITY) : 0.0;
    double fi0 = 0, fi1 = 0, fi2 = 0, ei = 0;
    /* a body split over MPI ranks (sm): the bonds with an owned end, both ends here (the serial
     * loop calls no row of an absent point; the threaded one calls every row, and a bond left
     * out writes "no share" into its slot, so that a border point's gather adds nothing for
     * it, as the serial loop does) */
    const int smi = sm ? sm[i] : FLOE_PD_OWNED;
    for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
        const int j = part[k], ownj = !gb || own[j];
        if (sm && (!smi || !sm[j] || (smi != FLOE_PD_OWNED && sm[j] != FLOE_PD_OWNED))) {
            if (!ownj) { /* threaded: the slot says "no share" (0, and -inf for the max) */
                double *q = gb + (size_t)st * (size_t)gslot[k];
                q[0] = q[1] = q[2] = 0.0;
                if (alpha_on) q[3] = -INFINITY;
            }
            continue;
        }
        double d0, d1, d2;
        pd_bond_vec(x, j, xi0, xi1, xi2, per, img, H, k, &d0, &d1, &d2);
        double r = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
        double L = len[k];
        double s = (r - L) / L;
        double g0 = 0, g1 = 0, g2 = 0, t = -INFINITY;
        int on = 1; /* the bond carries a force in this evaluation */
        if (brk[k]) {
            on = comp && !(s >= 0);
        } else {
            double sck = s_c;
            if (alpha_on) {
                t = s_c - alpha * s;
                /* selects, not branches: once a wave runs through the body the comparisons
                 * go either way and a branch on them mispredicts (pd-impact 1.2x faster) */
                s0ni = t > s0ni ? t : s0ni;
                if (ownj) s0n[j] = t > s0n[j] ? t : s0n[j];
                sck = s0i < s0[j] ? s0i : s0[j];
            }
            if (s_c > 0 && s > sck) {
                brk[k] = 1;
                *nbroken += smi == FLOE_PD_OWNED; /* split: counted by the rank of its row */
                /* LAMMPS' order with alpha: the bond's force of this evaluation is applied,
                 * then it breaks */
                if ((!comp || s >= 0) && !alpha_on) on = 0;
            }
        }
        if (on && r > 0) {
            double w = (double)vfac[k] * (scorr ? (double)scorr[k] : 1.0) * Vi * V[j];
            double fm = c * s * w / r;
            if (smi == FLOE_PD_OWNED) ei += 0.5 * c * s * s * L * w; /* split: on the row's rank */
            g0 = fm * d0; g1 = fm * d1; g2 = fm * d2;
            fi0 += g0; fi1 += g1; fi2 += g2;
            if (ownj) {
                double *fj = f + 3 * (size_t)j;
                fj[0] -= g0; fj[1] -= g1; fj[2] -= g2;
            }
        }
        if (!ownj) {
            double *q = gb + (size_t)st * (size_t)gslot[k];
            q[0] = g0; q[1] = g1; q[2] = g2;
            if (alpha_on) q[3] = t;
        }
    }
    if (!owni) {
        double *q = rb + (size_t)st * (size_t)i;
        q[0] = fi0; q[1] = fi1; q[2] = fi2;
        if (alpha_on) q[3] = s0ni;
    } else {
        if (alpha_on) s0n[i] = s0ni;
        f[3 * (size_t)i] += fi0;
        f[3 * (size_t)i + 1] += fi1;
        f[3 * (size_t)i + 2] += fi2;
    }
    return ei;
}

static inline double pmb_forces_impl(floe_pd_body *b, const double *x, double *f, const int alpha_on, const int per)
{
    const int n = b->n, B = FLOE_PD_ROW_BLOCK, nblk = (n + B - 1) / B, st = alpha_on ? 4 : 3;
    const uint8_t *sm = b->split;
    const int nt = pd_threads(b);
    floe_pd_par *P = nt > 1 ? pd_par_get(b, st, st, nt) : NULL;
    double *s0n = alpha_on ? b->s0 + n : NULL;
    double energy = 0.0;
    int64_t nbroken = 0;
    if (!P) {
        if (alpha_on)
            for (int i = 0; i < n; i++) s0n[i] = -INFINITY;
        for (int c = 0; c < nblk; c++) {
            const int i1 = (c + 1) * B < n ? (c + 1) * B : n;
            double eb = 0.0;
            if (sm)
                for (int i = c * B; i < i1; i++) {
                    if (sm[i]) eb += pmb_row(b, x, f, i, s0n, NULL, NULL, NULL, NULL, &nbroken, alpha_on, per, sm);
                }
            else
                for (int i = c * B; i < i1; i++)
                    eb += pmb_row(b, x, f, i, s0n, NULL, NULL, NULL, NULL, &nbroken, alpha_on, per, NULL);
            energy += eb;
        }
        if (alpha_on) /* split: the owned points' (a ghost's comes from its owner) */
            for (int i = 0; i < n; i++)
                if (!sm || sm[i] == FLOE_PD_OWNED) b->s0[i] = s0n[i] == -INFINITY ? DBL_MAX : s0n[i];
    } else {
        const uint8_t *own = P->own;
        FLOE_OMP(omp parallel num_threads(nt))
        {
            if (alpha_on) {
                FLOE_OMP(omp for schedule(static))
                for (int q = 0; q < n; q++)
                    if (own[q]) s0n[q] = -INFINITY;
            }
            FLOE_OMP(omp for schedule(static))
            for (int pt = 0; pt < P->nparts; pt++)
                for (int c = P->cut[pt]; c < P->cut[pt + 1]; c++) {
                    const int i1 = (c + 1) * B < n ? (c + 1) * B : n;
                    double eb = 0.0;
                    int64_t nbk = 0;
                    for (int i = c * B; i < i1; i++)
                        eb += pmb_row(b, x, f, i, s0n, P->g, P->row, own, P->gslot, &nbk, alpha_on, per, sm);
                    P->blk[c] = eb;
                    P->blkn[c] = nbk;
                }
            FLOE_OMP(omp for schedule(static))
            for (int e = 0; e < P->nborder; e++) {
                double m;
                pd_gather_f(P, e, f, st, alpha_on ? &m : NULL);
                if (alpha_on) s0n[P->border[e]] = m;
            }
            /* the old s0 is read by the rows above and written below, after their barrier */
            if (alpha_on) { /* split: the owned points' (a ghost's comes from its owner) */
                FLOE_OMP(omp for schedule(static))
                for (int q = 0; q < n; q++)
                    if (!sm || sm[q] == FLOE_PD_OWNED) b->s0[q] = s0n[q] == -INFINITY ? DBL_MAX : s0n[q];
            }
        }
        for (int c = 0; c < nblk; c++) {
            energy += P->blk[c];
            nbroken += P->blkn[c];
        }
    }
    b->nbroken += nbroken;
    return energy;
}

/* Elastic-perfectly-plastic PMB bond (003 eq 6, Fig 2): the force follows the elastic
 * stretch s_e = s - s_p, capped at -s_yc in compression (and +s_yt in tension when given);
 * beyond the cap the plastic stretch s_p moves so that s_e stays on it, and the bond unloads
 * elastically with the residual s_p. Breakage by s_c acts on the total stretch s, a broken
 * bond pushes back in compression (broken_tension_only) with the capped elastic law. The
 * returned energy is the stored elastic energy 1/2 c s_e^2 |xi| w; the plastic work is what
 * the world's ledger books as dissipated (it books -work - dE). Row i as pmb_row (stride 3). */
static inline __attribute__((always_inline)) double plastic_row(floe_pd_body *b, const double *x, double *f, int i,
                                                                double *gb, double *rb, const uint8_t *own,
                                                                const int32_t *gslot, int64_t *nbroken,
                                                                const uint8_t *sm)
{
    const double c = b->c, s_c = b->s_c;
    const double syc = b->mat.yield_compression, syt = b->mat.yield_tension;
    const int comp = b->mat.broken_tension_only;
    float *sp = b->splast;
    double fi[3] = {0, 0, 0}, ei = 0;
    const int smi = sm ? sm[i] : FLOE_PD_OWNED; /* split: as pmb_row */
    for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
        const int j = b->partner[k], ownj = !gb || own[j];
        double d[3], g[3] = {0, 0, 0};
        if (sm && (!smi || !sm[j] || (smi != FLOE_PD_OWNED && sm[j] != FLOE_PD_OWNED))) {
            if (!ownj) memcpy(gb + 3 * (size_t)gslot[k], g, sizeof g); /* threaded: no share */
            continue;
        }
        floe_pd_bond_vec(b, x, b->cellH, i, j, k, d);
        double r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double L = b->len[k], s = (r - L) / L;
        int on = 1;
        if (b->broken[k]) {
            on = comp && !(s >= 0);
        } else if (s_c > 0 && s > s_c) {
            b->broken[k] = 1;
            *nbroken += smi == FLOE_PD_OWNED; /* split: counted by the rank of its row */
            on = comp && !(s >= 0);
        }
        if (on) {
            double se = s - (double)sp[k];
            if (syc > 0 && se < -syc) { sp[k] = (float)(s + syc); se = s - (double)sp[k]; }
            if (syt > 0 && se > syt) { sp[k] = (float)(s - syt); se = s - (double)sp[k]; }
            if (r > 0) {
                double w = (double)b->vfac[k] * (b->scorr ? (double)b->scorr[k] : 1.0) * b->V[i] * b->V[j];
                double fm = c * se * w / r;
                if (smi == FLOE_PD_OWNED) ei += 0.5 * c * se * se * L * w; /* split: on the row's rank */
                for (int a = 0; a < 3; a++) {
                    g[a] = fm * d[a];
                    fi[a] += g[a];
                    if (ownj) f[3 * (size_t)j + a] -= g[a];
                }
            }
        }
        if (!ownj) memcpy(gb + 3 * (size_t)gslot[k], g, sizeof g);
    }
    if (gb && !own[i]) memcpy(rb + 3 * (size_t)i, fi, sizeof fi);
    else
        for (int a = 0; a < 3; a++) f[3 * (size_t)i + a] += fi[a];
    return ei;
}

static double pmb_forces_plastic(floe_pd_body *b, const double *x, double *f)
{
    const int n = b->n, B = FLOE_PD_ROW_BLOCK, nblk = (n + B - 1) / B;
    const uint8_t *sm = b->split;
    const int nt = pd_threads(b);
    floe_pd_par *P = nt > 1 ? pd_par_get(b, 3, 3, nt) : NULL;
    double energy = 0.0;
    int64_t nbroken = 0;
    if (!P) {
        for (int c = 0; c < nblk; c++) {
            const int i1 = (c + 1) * B < n ? (c + 1) * B : n;
            double eb = 0.0;
            if (sm) {
                for (int i = c * B; i < i1; i++)
                    if (sm[i]) eb += plastic_row(b, x, f, i, NULL, NULL, NULL, NULL, &nbroken, sm);
            } else
                for (int i = c * B; i < i1; i++) eb += plastic_row(b, x, f, i, NULL, NULL, NULL, NULL, &nbroken, NULL);
            energy += eb;
        }
    } else {
        const uint8_t *own = P->own;
        FLOE_OMP(omp parallel num_threads(nt))
        {
            FLOE_OMP(omp for schedule(static))
            for (int pt = 0; pt < P->nparts; pt++)
                for (int c = P->cut[pt]; c < P->cut[pt + 1]; c++) {
                    const int i1 = (c + 1) * B < n ? (c + 1) * B : n;
                    double eb = 0.0;
                    int64_t nbk = 0;
                    for (int i = c * B; i < i1; i++) eb += plastic_row(b, x, f, i, P->g, P->row, own, P->gslot, &nbk, sm);
                    P->blk[c] = eb;
                    P->blkn[c] = nbk;
                }
            FLOE_OMP(omp for schedule(static))
            for (int e = 0; e < P->nborder; e++) pd_gather_f(P, e, f, 3, NULL);
        }
        for (int c = 0; c < nblk; c++) {
            energy += P->blk[c];
            nbroken += P->blkn[c];
        }
    }
    b->nbroken += nbroken;
    return energy;
}

static double pmb_forces(floe_pd_body *b, const double *x, double *f)
{
    if (b->splast) return pmb_forces_plastic(b, x, f);
    if (b->img) return b->s0 && b->s_c > 0 ? pmb_forces_impl(b, x, f, 1, 1) : pmb_forces_impl(b, x, f, 0, 1);
    if (b->s0 && b->s_c > 0) return pmb_forces_impl(b, x, f, 1, 0);
    return pmb_forces_impl(b, x, f, 0, 0);
}

const floe_pd_material_ops floe_pd_pmb_ops = {.name = "pmb", .init = pmb_init, .forces = pmb_forces, .bond_micromodulus = pmb_c};

/* ---------------------------------------------------------------- LPS ---- */

/* Weighted volume m_i = sum_j w |xi|^2 beta V_j (000 eq 19, ParticLS eq 31), fixed in the
 * reference configuration (broken bonds keep counting in m, as in Peridigm). Influence
 * w = 1 or exp(-|xi|^2/delta^2) (ParticLS eq 33). 3D, or 2D plane stress / plane strain
 * (Le, Silling & Bobaru 2014; docs/models.md). */
static int lps_init(floe_pd_body *b)
{
    const floe_pd_material *m = &b->mat;
    if (b->dim != 3 && b->dim != 2) return FLOE_ENOTSUP;
    if (!(m->K > 0) || !(m->G > 0) || m->alpha != 0) return FLOE_EINVAL;
    if (m->influence != FLOE_PD_W_ONE && m->influence != FLOE_PD_W_GAUSS) return FLOE_EINVAL;
    if (b->dim == 2 && m->plane != FLOE_PD_PLANE_STRESS && m->plane != FLOE_PD_PLANE_STRAIN) return FLOE_EINVAL;
    size_t n = (size_t)(b->n > 0 ? b->n : 1), nb = (size_t)(b->nbond > 0 ? b->nbond : 1);
    double *mm = calloc(n, sizeof *mm), *th = calloc(n, sizeof *th), *w = NULL;
    if (m->influence == FLOE_PD_W_GAUSS) w = malloc(nb * sizeof *w);
    if (!mm || !th || (m->influence == FLOE_PD_W_GAUSS && !w)) {
        free(mm); free(th); free(w);
        return FLOE_ENOMEM;
    }
    double d2 = b->delta * b->delta;
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            double L = b->len[k];
            double wk = 1.0;
            if (w) wk = w[k] = exp(-L * L / d2);
            double a = wk * L * L * b->vfac[k];
            mm[i] += a * b->V[j];
            mm[j] += a * b->V[i];
        }
    free_lps(b);
    free(b->s0); /* PMB alpha state */
    b->s0 = NULL;
    b->m = mm;
    b->theta = th;
    b->wbond = w;
    /* the equivalent PMB c (for s_c from G_c and the time step): the PMB of the same P-wave
     * modulus M = K + 4G/3 (3D: nu = 1/4, K_pmb = M/1.8; 2D plane strain PMB: E = M/1.2) */
    double Mp = m->K + 4.0 / 3.0 * m->G;
    double d = b->delta;
    if (b->dim == 3) b->c = 18.0 * (Mp / 1.8) / (M_PI * d * d * d * d);
    else b->c = 48.0 * (Mp / 1.2) / (5.0 * M_PI * b->thickness * d * d * d);
    return FLOE_OK;
}

static double lps_c(const floe_pd_body *b) { return b->c; }

/* The modulus of the dilatation term, W = k theta^2/2 + ...: 3D K; 2D the in-plane bulk
 * modulus, plane strain lambda + G = K + G/3, plane stress E/(2(1 - nu)) = 9KG/(3K + 4G). */
static double lps_kdil(const floe_pd_body *b)
{
    const double K = b->mat.K, G = b->mat.G;
    if (b->dim == 3) return K;
    return b->mat.plane == FLOE_PD_PLANE_STRAIN ? K + G / 3.0 : 9.0 * K * G / (3.0 * K + 4.0 * G);
}

/* alpha_i = a G/m_i: a = 15 in 3D (000 eq 25), 8 in 2D (Le et al. 2014), times the
 * calibration factor acorr_i when the surface correction is on. */
static double lps_alpha(const floe_pd_body *b, int i)
{
    double mi = b->m[i] > 0 ? b->m[i] : 1.0;
    return (b->dim == 3 ? 15.0 : 8.0) * b->mat.G / mi * (b->acorr ? b->acorr[i] : 1.0);
}

/* n^T A n for the symmetric tensor A stored as (xx, yy, zz, xy, xz, yz) and the unit n */
static inline double lps_quad(const double *A, const double n[3])
{
    return A[0] * n[0] * n[0] + A[1] * n[1] * n[1] + A[2] * n[2] * n[2] +
           2.0 * (A[3] * n[0] * n[1] + A[4] * n[0] * n[2] + A[5] * n[1] * n[2]);
}

/* Weights of bond k = (i, j) at both ends: the dilatation weight omega/w and alpha. With
 * the surface correction omega = n^T A n and alpha = n^T B n (n the reference direction,
 * A and B of each end), else dim/m and a G/m (lps_alpha). */
static inline void lps_weights(const floe_pd_body *b, int i, int j, int64_t k, double *oi, double *oj,
                               double *ai, double *aj)
{
    if (b->dten) {
        const size_t n6 = 6 * (size_t)b->n;
        double n[3];
        floe_pd_ref_vec(b, i, j, k, n);
        floe_v3_scale(n, 1.0 / b->len[k]);
        *oi = lps_quad(b->dten + 6 * (size_t)i, n);
        *oj = lps_quad(b->dten + 6 * (size_t)j, n);
        const double *Bi = b->dten + n6 + 3 * (size_t)i, *Bj = b->dten + n6 + 3 * (size_t)j;
        double n0 = n[0] * n[0], n1 = n[1] * n[1], n2 = n[2] * n[2];
        *ai = Bi[0] * n0 + Bi[1] * n1 + Bi[2] * n2;
        *aj = Bj[0] * n0 + Bj[1] * n1 + Bj[2] * n2;
    } else {
        *oi = b->m[i] > 0 ? b->dim / b->m[i] : 0.0;
        *oj = b->m[j] > 0 ? b->dim / b->m[j] : 0.0;
        *ai = lps_alpha(b, i);
        *aj = lps_alpha(b, j);
    }
}

/* Dilatation pass: theta_i = sum_j omega_ij |xi| e beta V_j over intact bonds (omega = w
 * dim/m_i without the surface correction: 000 eq 18, ParticLS eq 32); with it also
 * q_i = sum_j alpha_ij w |xi| e^d_ij beta V_j (into dten + 9n; zero for the plain form and an intact
 * family, so the plain form leaves it out). Breaks bonds with e > s_c |xi| when s_c > 0;
 * returns the number broken.
 * Row i (the number broken returned): serial (gb NULL) j's shares of theta (and of the sums
 * p, mi of q) added as the loop meets them and i's row sums at its end; threaded the shares
 * into gb and the row sums into rb, stride 3 with the surface correction, else 1. */
static inline __attribute__((always_inline)) int64_t lps_dil_row(floe_pd_body *b, const double *x, int i, double *gb,
                                                                 double *rb, const uint8_t *own, const int32_t *gslot,
                                                                 const int per, const uint8_t *sm)
{
    const int32_t *img = per ? b->img : NULL;
    const double *H = per ? b->cellH : NULL;
    const int n = b->n;
    const double s_c = b->s_c;
    const double *V = b->V, *len = b->len, *wb = b->wbond;
    const float *vfac = b->vfac;
    const int32_t *part = b->partner;
    uint8_t *brk = b->broken;
    double *th = b->theta;
    double *p = b->dten ? b->dten + 9 * (size_t)n : NULL, *mi = p ? p + n : NULL;
    const int st = p ? 3 : 1;
    int64_t nbroken = 0;
    const double *xi = x + 3 * (size_t)i;
    double ti = 0, pi = 0, mii = 0;
    const int smi = sm ? sm[i] : FLOE_PD_OWNED; /* split: as pmb_row */
    for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
        double cj[3] = {-0.0, -0.0, -0.0}; /* j's shares (-0: none) */
        const int j = part[k], ownj = !gb || own[j];
        if (sm && (!smi || !sm[j] || (smi != FLOE_PD_OWNED && sm[j] != FLOE_PD_OWNED))) {
            if (!ownj) /* threaded: no share */
                for (int c = 0; c < st; c++) gb[(size_t)st * (size_t)gslot[k] + c] = cj[c];
            continue;
        }
        if (!brk[k]) {
            double d0, d1, d2;
            pd_bond_vec(x, j, xi[0], xi[1], xi[2], per, img, H, k, &d0, &d1, &d2);
            double L = len[k];
            double e = sqrt(d0 * d0 + d1 * d1 + d2 * d2) - L;
            if (s_c > 0 && e > s_c * L) {
                brk[k] = 1;
                nbroken += smi == FLOE_PD_OWNED; /* split: counted by the rank of its row */
            } else {
                double a = (wb ? wb[k] : 1.0) * L * (double)vfac[k];
                if (p) {
                    double oi, oj, ai, aj;
                    lps_weights(b, i, j, k, &oi, &oj, &ai, &aj);
                    ti += a * oi * e * V[j];
                    cj[0] = a * oj * e * V[i];
                    pi += ai * a * e * V[j];
                    cj[1] = aj * a * e * V[i];
                    mii += ai * a * L * V[j];
                    cj[2] = aj * a * L * V[i];
                    if (ownj) { th[j] += cj[0]; p[j] += cj[1]; mi[j] += cj[2]; }
                } else {
                    ti += a * e * V[j];
                    cj[0] = a * e * V[i];
                    if (ownj) th[j] += cj[0];
                }
            }
        }
        if (!ownj)
            for (int c = 0; c < st; c++) gb[(size_t)st * (size_t)gslot[k] + c] = cj[c];
    }
    if (gb && !own[i]) {
        double *r = rb + (size_t)st * (size_t)i;
        r[0] = ti;
        if (p) { r[1] = pi; r[2] = mii; }
    } else {
        th[i] += ti;
        if (p) { p[i] += pi; mi[i] += mii; }
    }
    return nbroken;
}

/* point i once its sums are complete: q_i, or the plain theta_i = dim sum / m_i */
static inline void lps_dil_final(floe_pd_body *b, int i)
{
    const int n = b->n, dim = b->dim;
    double *th = b->theta;
    if (b->dten) {
        double *p = b->dten + 9 * (size_t)n, *mi = p + n;
        p[i] -= th[i] * mi[i] / dim; /* q_i */
    } else
        th[i] = b->m[i] > 0 ? dim * th[i] / b->m[i] : 0.0;
}

static inline int64_t lps_dilatation_impl(floe_pd_body *b, const double *x, const int per)
{
    const int n = b->n, B = FLOE_PD_ROW_BLOCK, nblk = (n + B - 1) / B;
    double *th = b->theta;
    double *p = b->dten ? b->dten + 9 * (size_t)n : NULL, *mi = p ? p + n : NULL;
    const int st = p ? 3 : 1;
    const uint8_t *sm = b->split;
    const int nt = pd_threads(b);
    floe_pd_par *P = nt > 1 ? pd_par_get(b, 3, 3, nt) : NULL;
    int64_t nbroken = 0;
    if (!P) {
        for (int i = 0; i < n; i++) th[i] = 0;
        if (p)
            for (int i = 0; i < n; i++) p[i] = mi[i] = 0;
        if (sm) {
            for (int i = 0; i < n; i++)
                if (sm[i]) nbroken += lps_dil_row(b, x, i, NULL, NULL, NULL, NULL, per, sm);
        } else
            for (int i = 0; i < n; i++) nbroken += lps_dil_row(b, x, i, NULL, NULL, NULL, NULL, per, NULL);
        for (int i = 0; i < n; i++) lps_dil_final(b, i);
        /* split: the ghosts' sums lack the bonds this rank does not hold: their owners' */
        if (sm && b->split_sync) b->split_sync(b, b->split_ctx);
        return nbroken;
    }
    const uint8_t *own = P->own;
    FLOE_OMP(omp parallel num_threads(nt))
    {
        FLOE_OMP(omp for schedule(static))
        for (int q = 0; q < n; q++)
            if (own[q]) {
                th[q] = 0;
                if (p) p[q] = mi[q] = 0;
            }
        FLOE_OMP(omp for schedule(static))
        for (int pt = 0; pt < P->nparts; pt++)
            for (int c = P->cut[pt]; c < P->cut[pt + 1]; c++) {
                const int i1 = (c + 1) * B < n ? (c + 1) * B : n;
                int64_t nbk = 0;
                for (int i = c * B; i < i1; i++) nbk += lps_dil_row(b, x, i, P->g, P->row, own, P->gslot, per, sm);
                P->blkn[c] = nbk;
            }
        FLOE_OMP(omp for schedule(static))
        for (int e = 0; e < P->nborder; e++) {
            const int q = P->border[e];
            double v[3] = {0, 0, 0};
            pd_gather(P, e, v, st, st, 0, NULL);
            th[q] = v[0];
            if (p) { p[q] = v[1]; mi[q] = v[2]; }
        }
        FLOE_OMP(omp for schedule(static))
        for (int q = 0; q < n; q++) lps_dil_final(b, q);
    }
    for (int c = 0; c < nblk; c++) nbroken += P->blkn[c];
    /* split: the ghosts' sums from their owners (collective: outside the threads) */
    if (sm && b->split_sync) b->split_sync(b, b->split_ctx);
    return nbroken;
}

static int64_t lps_dilatation(floe_pd_body *b, const double *x)
{
    return b->img ? lps_dilatation_impl(b, x, 1) : lps_dilatation_impl(b, x, 0);
}

/* Scalar force states of bond k at both ends (per unit beta V_i V_j), from the energy
 * W_i = k theta_i^2/2 + 1/2 sum_j alpha_ij w (e^d_ij)^2 beta V_j, e^d = e - theta_i |xi|/dim:
 *   t_ij = (k theta_i - q_i/dim) omega_ij |xi| + alpha_ij w e^d_ij
 * (000 eq 22 / ParticLS eq 34 with omega = 3w/m_i and alpha_ij = 15G/m_i, where q_i = 0). Adds the deviatoric
 * energy of the bond (both ends, per unit beta V_i V_j) to *en. */
static inline void lps_bond_t(const floe_pd_body *b, double kd, int i, int j, int64_t k, double e,
                              double *tij, double *tji, double *en)
{
    const double L = b->len[k], w = b->wbond ? b->wbond[k] : 1.0, dim = b->dim;
    const double *th = b->theta;
    double oi, oj, ai, aj;
    lps_weights(b, i, j, k, &oi, &oj, &ai, &aj);
    double edi = e - th[i] * L / dim, edj = e - th[j] * L / dim;
    double qi = 0, qj = 0;
    if (b->dten) {
        qi = b->dten[9 * (size_t)b->n + i];
        qj = b->dten[9 * (size_t)b->n + j];
    }
    *tij = (kd * th[i] - qi / dim) * w * oi * L + ai * w * edi;
    *tji = (kd * th[j] - qj / dim) * w * oj * L + aj * w * edj;
    *en += 0.5 * w * (ai * edi * edi + aj * edj * edj);
}

/* 000 eqs 18-25 / ParticLS eqs 30-35 (3D), Le et al. 2014 (2D):
 *   e = |y| - |xi|, theta_i as above, force on i: sum_j (t_ij + t_ji) beta V_i V_j M
 * (000 eq 14); energy sum_i V_i W_i (000 eq 24). Broken bonds (stretch e/|xi| > s_c,
 * checked in the dilatation pass) drop out of theta and t. Row i as pmb_row (stride 3). */
static inline __attribute__((always_inline)) double lps_row(const floe_pd_body *b, const double *x, double *f, int i,
                                                            double kd, double *gb, double *rb, const uint8_t *own,
                                                            const int32_t *gslot, const int per, const uint8_t *sm)
{
    const int32_t *img = per ? b->img : NULL;
    const double *H = per ? b->cellH : NULL;
    const double *V = b->V, *len = b->len;
    const float *vfac = b->vfac;
    const int32_t *part = b->partner;
    const uint8_t *brk = b->broken;
    const double *th = b->theta;
    const double xi0 = x[3 * (size_t)i], xi1 = x[3 * (size_t)i + 1], xi2 = x[3 * (size_t)i + 2];
    const double Vi = V[i];
    double fi0 = 0, fi1 = 0, fi2 = 0, ei = 0.5 * kd * th[i] * th[i] * Vi;
    const int smi = sm ? sm[i] : FLOE_PD_OWNED; /* split: as pmb_row */
    for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
        double g0 = 0, g1 = 0, g2 = 0;
        const int j = part[k], ownj = !gb || own[j];
        if (sm && (!smi || !sm[j] || (smi != FLOE_PD_OWNED && sm[j] != FLOE_PD_OWNED))) {
            if (!ownj) { /* threaded: no share */
                double *q = gb + 3 * (size_t)gslot[k];
                q[0] = q[1] = q[2] = 0.0;
            }
            continue;
        }
        if (!brk[k]) {
            double d0, d1, d2;
            pd_bond_vec(x, j, xi0, xi1, xi2, per, img, H, k, &d0, &d1, &d2);
            double r = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
            double tij, tji, eb = 0;
            lps_bond_t(b, kd, i, j, k, r - len[k], &tij, &tji, &eb);
            double bv = (double)vfac[k] * Vi * V[j];
            ei += eb * bv;
            if (r > 0) {
                double fm = (tij + tji) * bv / r;
                g0 = fm * d0; g1 = fm * d1; g2 = fm * d2;
                fi0 += g0; fi1 += g1; fi2 += g2;
                if (ownj) {
                    double *fj = f + 3 * (size_t)j;
                    fj[0] -= g0; fj[1] -= g1; fj[2] -= g2;
                }
            }
        }
        if (!ownj) {
            double *q = gb + 3 * (size_t)gslot[k];
            q[0] = g0; q[1] = g1; q[2] = g2;
        }
    }
    if (gb && !own[i]) {
        double *q = rb + 3 * (size_t)i;
        q[0] = fi0; q[1] = fi1; q[2] = fi2;
    } else {
        f[3 * (size_t)i] += fi0;
        f[3 * (size_t)i + 1] += fi1;
        f[3 * (size_t)i + 2] += fi2;
    }
    /* theta_j's k theta^2/2 V_j term is added when the loop reaches j; split: the energy of
     * the row's rank */
    return smi == FLOE_PD_OWNED ? ei : 0.0;
}

static inline double lps_forces_impl(floe_pd_body *b, const double *x, double *f, const int per)
{
    const int n = b->n, B = FLOE_PD_ROW_BLOCK, nblk = (n + B - 1) / B;
    const double kd = lps_kdil(b);
    b->nbroken += lps_dilatation(b, x);
    const uint8_t *sm = b->split;
    const int nt = pd_threads(b);
    floe_pd_par *P = nt > 1 ? pd_par_get(b, 3, 3, nt) : NULL;
    double energy = 0.0;
    if (!P) {
        for (int c = 0; c < nblk; c++) {
            const int i1 = (c + 1) * B < n ? (c + 1) * B : n;
            double eb = 0.0;
            if (sm) {
                for (int i = c * B; i < i1; i++)
                    if (sm[i]) eb += lps_row(b, x, f, i, kd, NULL, NULL, NULL, NULL, per, sm);
            } else
                for (int i = c * B; i < i1; i++) eb += lps_row(b, x, f, i, kd, NULL, NULL, NULL, NULL, per, NULL);
            energy += eb;
        }
        return energy;
    }
    const uint8_t *own = P->own;
    FLOE_OMP(omp parallel num_threads(nt))
    {
        FLOE_OMP(omp for schedule(static))
        for (int pt = 0; pt < P->nparts; pt++)
            for (int c = P->cut[pt]; c < P->cut[pt + 1]; c++) {
                const int i1 = (c + 1) * B < n ? (c + 1) * B : n;
                double eb = 0.0;
                for (int i = c * B; i < i1; i++) eb += lps_row(b, x, f, i, kd, P->g, P->row, own, P->gslot, per, sm);
                P->blk[c] = eb;
            }
        FLOE_OMP(omp for schedule(static))
        for (int e = 0; e < P->nborder; e++) pd_gather_f(P, e, f, 3, NULL);
    }
    for (int c = 0; c < nblk; c++) energy += P->blk[c];
    return energy;
}

static double lps_forces(floe_pd_body *b, const double *x, double *f)
{
    return b->img ? lps_forces_impl(b, x, f, 1) : lps_forces_impl(b, x, f, 0);
}

const floe_pd_material_ops floe_pd_lps_ops = {.name = "lps", .init = lps_init, .forces = lps_forces, .bond_micromodulus = lps_c};

/* Solve the dense system M y = r (size s <= 6) by Gaussian elimination with partial
 * pivoting; 0 on success, -1 when a pivot is below tol times the largest |M| entry. */
static int lps_solve(int s, double M[6][6], double *r)
{
    double mx = 0;
    for (int a = 0; a < s; a++)
        for (int c = 0; c < s; c++) mx = fmax(mx, fabs(M[a][c]));
    if (!(mx > 0)) return -1;
    for (int c = 0; c < s; c++) {
        int p = c;
        for (int a = c + 1; a < s; a++)
            if (fabs(M[a][c]) > fabs(M[p][c])) p = a;
        if (!(fabs(M[p][c]) > 1e-10 * mx)) return -1;
        if (p != c) {
            for (int t = 0; t < s; t++) { double u = M[c][t]; M[c][t] = M[p][t]; M[p][t] = u; }
            double u = r[c]; r[c] = r[p]; r[p] = u;
        }
        for (int a = c + 1; a < s; a++) {
            double g = M[a][c] / M[c][c];
            for (int t = c; t < s; t++) M[a][t] -= g * M[c][t];
            r[a] -= g * r[c];
        }
    }
    for (int c = s - 1; c >= 0; c--) {
        double u = r[c];
        for (int t = c + 1; t < s; t++) u -= M[c][t] * r[t];
        r[c] = u / M[c][c];
    }
    return 0;
}

/* LPS surface correction (floe_pd.h). Components of a symmetric tensor: (xx, yy, zz, xy, xz,
 * yz) in 3D, (xx, yy, xy) in 2D. */
int floe_pd_lps_surface_correction(floe_pd_body *b)
{
    if (!b || !b->ops || b->mat.model != FLOE_PD_LPS || !b->m) return FLOE_EINVAL;
    const int dim = b->dim, s = dim == 3 ? 6 : 3;
    static const int ia3[6] = {0, 1, 2, 0, 0, 1}, ib3[6] = {0, 1, 2, 1, 2, 2};
    static const int ia2[3] = {0, 1, 0}, ib2[3] = {0, 1, 1};
    static const int slot2[3] = {0, 1, 3}; /* 2D component -> storage slot */
    const int *ia = dim == 3 ? ia3 : ia2, *ib = dim == 3 ? ib3 : ib2;
    size_t n = (size_t)(b->n > 0 ? b->n : 1);
    /* the 15 distinct components of a fully symmetric 4th-order tensor: n_x^ex n_y^ey n_z^ez,
     * ex + ey + ez = 4, slot mi[ex][ey] */
    int mi[5][5], nm = 0;
    for (int ex = 0; ex <= 4; ex++)
        for (int ey = 0; ey <= 4 - ex; ey++) mi[ex][ey] = nm++;
    double *C = calloc(n * 15, sizeof *C), *A = calloc(11 * n, sizeof *A);
    if (!C || !A) { free(C); free(A); return FLOE_ENOMEM; }
    /* 1. per point the fourth moment C_abcd = sum_j w |xi|^2 beta V_j n_a n_b n_c n_d */
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            double L = b->len[k], nv[3];
            floe_pd_ref_vec(b, i, j, k, nv);
            floe_v3_scale(nv, 1.0 / L);
            double wl = (b->wbond ? b->wbond[k] : 1.0) * L * L * b->vfac[k];
            double px[5] = {1, nv[0], nv[0] * nv[0], nv[0] * nv[0] * nv[0], 0}, py[5], pz[5];
            px[4] = px[2] * px[2];
            py[0] = pz[0] = 1;
            for (int t = 1; t < 5; t++) { py[t] = py[t - 1] * nv[1]; pz[t] = pz[t - 1] * nv[2]; }
            for (int ex = 0; ex <= 4; ex++)
                for (int ey = 0; ey <= 4 - ex; ey++) {
                    double t = wl * px[ex] * py[ey] * pz[4 - ex - ey];
                    C[15 * (size_t)i + mi[ex][ey]] += t * b->V[j];
                    C[15 * (size_t)j + mi[ex][ey]] += t * b->V[i];
                }
        }
    /* 2. A_i from C : A = I (the dilatation exact for every uniform strain), as the linear
     * system on the independent components of A; a point whose family does not span the
     * space keeps the plain dim/m_i I */
    for (int i = 0; i < b->n; i++) {
        double M[6][6], r[6];
        for (int p = 0; p < s; p++) {
            for (int q = 0; q < s; q++) {
                int e[3] = {0, 0, 0};
                e[ia[p]]++; e[ib[p]]++; e[ia[q]]++; e[ib[q]]++;
                M[p][q] = C[15 * (size_t)i + mi[e[0]][e[1]]] * (ia[q] == ib[q] ? 1.0 : 2.0);
            }
            r[p] = ia[p] == ib[p] ? 1.0 : 0.0;
        }
        double *Ai = A + 6 * (size_t)i;
        if (lps_solve(s, M, r) == 0) {
            for (int p = 0; p < s; p++) Ai[dim == 3 ? p : slot2[p]] = r[p];
        } else {
            double a = b->m[i] > 0 ? dim / b->m[i] : 0.0;
            for (int d = 0; d < dim; d++) Ai[d] = a;
        }
    }
    free(C);
    /* 3. alpha_ij = n^T B_i n with B_i = diag(c_1 .. c_dim): for the uniform uniaxial strain
     * eps along each axis d the deviatoric energy 1/2 sum_j alpha_ij w (e^d_ij)^2 beta V_j =
     * eps^2/2 sum_e c_e M_de, M_de = sum_j w |xi|^2 beta V_j n_e^2 (n_d^2 - thetahat_i^d/dim)^2,
     * thetahat_i^d = sum_j omega_ij |xi|^2 n_d^2 beta V_j (= 1 when A_i was solved), equals
     * the continuum G (1 - 1/dim) eps^2 for every d at once: M c = 2G(1 - 1/dim). Where that
     * has no positive solution, c_e = mean_d 2G(1 - 1/dim)/sum_e M_de (a scalar alpha_i). */
    double *TH = calloc(3 * n, sizeof *TH), *MM = calloc(9 * n, sizeof *MM);
    if (!TH || !MM) { free(TH); free(MM); free(A); return FLOE_ENOMEM; }
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < b->n; i++)
            for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
                int j = b->partner[k];
                double L = b->len[k], nv[3];
                floe_pd_ref_vec(b, i, j, k, nv);
                floe_v3_scale(nv, 1.0 / L);
                double w = b->wbond ? b->wbond[k] : 1.0, wl = w * L * L * b->vfac[k];
                double oi = w * lps_quad(A + 6 * (size_t)i, nv), oj = w * lps_quad(A + 6 * (size_t)j, nv);
                for (int a = 0; a < dim; a++) {
                    double na2 = nv[a] * nv[a];
                    size_t ix = 3 * (size_t)i + a, jx = 3 * (size_t)j + a;
                    if (pass == 0) {
                        TH[ix] += oi * L * L * b->vfac[k] * na2 * b->V[j];
                        TH[jx] += oj * L * L * b->vfac[k] * na2 * b->V[i];
                    } else {
                        double qi = na2 - TH[ix] / dim, qj = na2 - TH[jx] / dim;
                        for (int c = 0; c < dim; c++) {
                            double nc2 = nv[c] * nv[c];
                            MM[9 * (size_t)i + 3 * a + c] += wl * nc2 * qi * qi * b->V[j];
                            MM[9 * (size_t)j + 3 * a + c] += wl * nc2 * qj * qj * b->V[i];
                        }
                    }
                }
            }
    free(TH);
    const double G = b->mat.G, rhs = 2.0 * G * (1.0 - 1.0 / dim);
    for (int i = 0; i < b->n; i++) {
        double M[6][6], c[6];
        const double *Mi = MM + 9 * (size_t)i;
        for (int a = 0; a < dim; a++) {
            for (int t = 0; t < dim; t++) M[a][t] = Mi[3 * a + t];
            c[a] = rhs;
        }
        int ok = lps_solve(dim, M, c) == 0;
        for (int a = 0; ok && a < dim; a++) ok = c[a] > 0 && isfinite(c[a]);
        if (!ok) {
            double sum = 0;
            int cnt = 0;
            for (int a = 0; a < dim; a++) {
                double Da = 0;
                for (int t = 0; t < dim; t++) Da += Mi[3 * a + t];
                if (Da > 0) { sum += rhs / Da; cnt++; }
            }
            double al = cnt > 0 ? sum / cnt : lps_alpha(b, i);
            for (int a = 0; a < dim; a++) c[a] = al;
        }
        double *Bi = A + 6 * n + 3 * (size_t)i;
        Bi[0] = Bi[1] = Bi[2] = 0;
        for (int a = 0; a < dim; a++) Bi[a] = c[a];
    }
    free(MM);
    free(b->acorr); /* alpha is in B_i */
    b->acorr = NULL;
    free(b->dten);
    b->dten = A;
    return FLOE_OK;
}

/* ------------------------------------------------------- bond visitor ---- */
int floe_pd_bond_forces(floe_pd_body *b, const double *x, floe_pd_bond_visit_fn fn, void *user)
{
    if (!b || !b->ops || !x || !fn) return FLOE_EINVAL;
    if (b->mat.model == FLOE_PD_USER) return FLOE_ENOTSUP; /* its bond forces are its own */
    /* split over MPI ranks: the bonds of the rows whose point this rank owns, their partner
     * here (every bond of the body once over the ranks); LPS's dilatation pass below calls
     * the split's exchange: every rank calls this for every body */
    const uint8_t *sm = b->split;
    const int lps = b->mat.model == FLOE_PD_LPS;
    const double kd = lps ? lps_kdil(b) : 0.0;
    if (lps) { /* a fresh dilatation pass, without breaking bonds */
        double s_c = b->s_c;
        b->s_c = 0;
        lps_dilatation(b, x);
        b->s_c = s_c;
    }
    for (int i = 0; i < b->n; i++) {
        if (sm && sm[i] != FLOE_PD_OWNED) continue;
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            if (sm && !sm[j]) continue; /* (an intact bond's partner is always here: par_pd.c) */
            double d[3];
            floe_pd_bond_vec(b, x, b->cellH, i, j, k, d);
            double r = floe_v3_norm(d), L = b->len[k], s = (r - L) / L;
            if (b->broken[k] && (lps || !b->mat.broken_tension_only || s >= 0)) continue;
            if (!(r > 0)) continue;
            double bv = (double)b->vfac[k] * b->V[i] * b->V[j], fm;
            if (!lps) {
                double se = b->splast ? s - (double)b->splast[k] : s; /* plastic bonds: elastic part */
                fm = b->c * se * bv * (b->scorr ? (double)b->scorr[k] : 1.0);
            } else {
                double tij, tji, en = 0;
                lps_bond_t(b, kd, i, j, k, r - L, &tij, &tji, &en);
                fm = (tij + tji) * bv;
            }
            double f[3] = {fm * d[0] / r, fm * d[1] / r, fm * d[2] / r};
            fn(i, j, k, f, user);
        }
    }
    return FLOE_OK;
}
