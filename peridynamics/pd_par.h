/* pd_par.h - the buffers of the threaded PD bond loops (pd_materials.c; docs/parallel.md,
 * "The same bits"). Internal to peridynamics/. */
#ifndef FLOE_PD_PAR_H
#define FLOE_PD_PAR_H

#include "floe_pd.h"

/* Each bond k = (i, j) is stored in row i (i < j); a serial loop over the rows adds its force
 * to j when it meets it and i's row sum at the end of row i. A threaded evaluation computes
 * the rows in parallel, each bond's share of j into g (per bond) and each row's sums into
 * row (per point), then every point gathers its shares in the serial loop's order: the bonds
 * whose partner it is in increasing k (the reverse index rk), its own row sum where the
 * serial loop adds it; a point whose every row lies in one part of the rows (floe_pd_par.own)
 * is added to directly by that part's thread, in the same order. Partial sums (energy, broken bonds) are per block of FLOE_PD_ROW_BLOCK
 * rows, added in block order, also on one thread. */

/* Rows per block: fixed (not the thread count's), and smaller than FLOE_PAR_BLOCK because a
 * row holds tens of bonds (about 14 in 2D, 60 in 3D at a horizon of 3 dx): a body of 5,000
 * points gives its threads 40 blocks to share, not 10. A thread's part is a run of them
 * (pd_materials.c pd_par_get). */
#define FLOE_PD_ROW_BLOCK 128
typedef struct floe_pd_par {
    int64_t *roff, *rk;   /* the bonds whose partner is p: rk[roff[p] .. roff[p + 1]), ascending */
    int n;                /* points and bonds the reverse index was built for */
    int64_t nbond;
    double *g; size_t g_cap;     /* per border bond: its share of the partner (stride set by the loop) */
    double *row; size_t row_cap; /* per point: its row's sums */
    double *blk; int64_t *blkn; int blk_cap; /* per block of rows: energy, broken bonds */
    /* nparts parts (one per thread), part t the blocks of rows [cut[t], cut[t + 1]), cut at
     * equal bonds, each on one thread in order (pd_materials.c pd_par_get); own[p]
     * when every row that adds to p (its own, and those of the bonds whose partner it is)
     * lies in p's part: that thread then adds to p directly, in the serial loop's order, and
     * only the points on the parts' borders go through g, row and the gather */
    uint8_t *own;
    int *border, nborder; /* the points not owned, ascending: the gather's work, split evenly */
    /* g holds the shares of the bonds whose partner is a border point only, border point e's
     * in slots [bslot[e], bslot[e + 1]) in increasing bond index, those of the rows below its
     * own before bsplit[e]; gslot[k] is bond k's slot (-1: its partner is owned) */
    int32_t *gslot; int64_t *bslot, *bsplit, nslot;
    int *cut, nparts;
} floe_pd_par;

/* frees b->par (the bond arrays changed: pd_crack.c, floe_pd_make_periodic; or the body goes) */
void floe_pd_par_free(floe_pd_body *b);

#endif
