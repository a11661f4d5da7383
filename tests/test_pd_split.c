/* test_pd_split.c - a PMB body split over ranks (floe_pd_body.split, the bond loop that an
 * MPI decomposition runs, core/parallel/par_pd.c), simulated in one process: R copies of
 * the body, each with its points marked owned (a slab along x), ghost (bonded to an owned
 * point) or absent. Between evaluations the ghosts' s0 (alpha) comes from their owners, as
 * the ranks' exchange does. Over 12 evaluations of a bar pulled apart (bonds break in the
 * neck, alpha on and off, R = 2 and 3):
 *   - every owned point's force is the unsplit loop's to the bit (its bonds in the same order);
 *   - every bond with an owned end has the unsplit loop's broken flag;
 *   - the ranks' energies and broken counts add up to the unsplit ones (energy: the sum's
 *     order differs, rel. 1e-12; counts exactly);
 *   - an owned point's s0 is the unsplit one to the bit.
 * Plastic PMB bonds (yield in compression and tension): every bond with an owned end has the
 * unsplit plastic stretch. LPS (plain and with the surface correction) the same way, the ghosts' theta and q given
 * between the passes (split_sync) as the ranks' exchange gives them; an owned point's theta
 * and q are the unsplit ones to the bit. Each case with one thread a rank and with two (the
 * threaded loops: a left-out bond's slot says "no share"). */
#include "check.h"
#include "floe_pd.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NX 12
#define NY 4
#define NZ 4

static floe_pd_body *bar(double alpha, int lps, int corr, double yield)
{
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = 1e-3;
    r.horizon_factor = 3.015;
    r.lo[0] = r.lo[1] = r.lo[2] = 0;
    r.hi[0] = NX * 1e-3; r.hi[1] = NY * 1e-3; r.hi[2] = NZ * 1e-3;
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create(&b, &r) == FLOE_OK, "create");
    floe_pd_material m = lps ? floe_pd_material_lps(2200, 1.49e10, 8.9e9, 2e-3, FLOE_PD_W_GAUSS)
                             : floe_pd_material_pmb(2200, 1.49e10, 2e-3);
    m.alpha = alpha;
    m.yield_compression = m.yield_tension = yield; /* plastic bonds (PMB, not with alpha) */
    CHECK(floe_pd_set_material(b, &m) == FLOE_OK, "material");
    if (corr) CHECK(floe_pd_surface_correction(b) == FLOE_OK, "surface correction");
    return b;
}

/* the ranks' exchange between the LPS passes (floe_pd_body.split_sync): a ghost's theta and
 * q as its owner has them after its dilatation pass. The ranks run one after the other
 * here, so the values come from the unsplit body, evaluated first at the same positions;
 * that the owners' own values are those is checked after each evaluation (bits) */
typedef struct sim { floe_pd_body **part; const floe_pd_body *full; uint8_t **mask; int n, R; } sim;
static void sync_ghosts(floe_pd_body *b, void *ctx)
{
    const sim *S = ctx;
    int r = 0;
    while (S->part[r] != b) r++;
    for (int i = 0; i < S->n; i++)
        if (S->mask[r][i] == FLOE_PD_GHOST) {
            b->theta[i] = S->full->theta[i];
            if (b->dten) b->dten[9 * (size_t)S->n + i] = S->full->dten[9 * (size_t)S->n + i];
        }
}

/* the positions of evaluation e: the bar stretched along x, more in its neck (x near the
 * middle), with a small shear wobble so that bonds differ */
static void place(const floe_pd_body *b, int e, double *x)
{
    const double L = NX * 1e-3;
    for (int i = 0; i < b->n; i++) {
        const double *X = b->X + 3 * i;
        const double u = X[0] / L - 0.5, neck = exp(-40 * u * u);
        x[3 * i] = X[0] * (1 + 4e-4 * e) + (u > 0 ? 1 : -1) * 6e-6 * e * neck * (1 + 0.3 * sin(7 * X[1] / 1e-3));
        x[3 * i + 1] = X[1] + 2e-7 * e * sin(3 * X[0] / 1e-3);
        x[3 * i + 2] = X[2] - 1e-7 * e * cos(5 * X[1] / 1e-3);
    }
}

/* rank r's points: its owned ones, and as ghosts every point bonded to one of them by a bond
 * that acts (intact, or broken but pushing back in compression: PMB's broken_tension_only),
 * as the halo promises (docs/parallel.md); the others absent (their positions NaN below), so
 * that a bond whose other point is absent is left out as on a rank */
static void build_masks(const floe_pd_body *full, const int *owner, int R, uint8_t **mask)
{
    const int keep_broken = full->mat.model == FLOE_PD_PMB && full->mat.broken_tension_only;
    for (int r = 0; r < R; r++) {
        for (int i = 0; i < full->n; i++) mask[r][i] = owner[i] == r ? FLOE_PD_OWNED : 0;
        for (int i = 0; i < full->n; i++)
            for (int64_t k = full->off[i]; k < full->off[i + 1]; k++) {
                const int j = full->partner[k];
                if (full->broken[k] && !keep_broken) continue;
                if (mask[r][i] == FLOE_PD_OWNED && !mask[r][j]) mask[r][j] = FLOE_PD_GHOST;
                if (mask[r][j] == FLOE_PD_OWNED && !mask[r][i]) mask[r][i] = FLOE_PD_GHOST;
            }
    }
}

static void run(int R, double alpha, int lps, int corr, double yield, int threads, int tension_only)
{
    floe_pd_body *full = bar(alpha, lps, corr, yield), *part[3];
    const int n = full->n;
    int *owner = malloc(n * sizeof *owner);
    uint8_t *mask[3];
    for (int i = 0; i < n; i++) {
        int o = (int)(full->X[3 * i] / (NX * 1e-3) * R);
        owner[i] = o < R ? o : R - 1;
    }
    full->mat.broken_tension_only = tension_only;
    for (int r = 0; r < R; r++) {
        part[r] = bar(alpha, lps, corr, yield);
        part[r]->mat.broken_tension_only = tension_only;
        mask[r] = calloc(n, 1);
        part[r]->split = mask[r];
        part[r]->nthreads = threads; /* the split bond loops on threads (OpenMP builds) */
    }
    sim sm = {part, full, mask, n, R};
    for (int r = 0; r < R && lps; r++) {
        part[r]->split_sync = sync_ghosts;
        part[r]->split_ctx = &sm;
    }
    double *x = malloc(3 * n * sizeof *x), *f = malloc(3 * n * sizeof *f), *g = malloc(3 * n * sizeof *g);
    int fbits = 1, flags = 1, s0bits = 1, ghosts = 0;
    int64_t broke = 0;
    double erel = 0;
    build_masks(full, owner, R, mask);
    for (int i = 0; i < n; i++) ghosts += mask[0][i] == FLOE_PD_GHOST;
    int absent = 0; /* partners of owned points left out, summed over the evaluations */
    for (int e = 0; e < 12; e++) {
        build_masks(full, owner, R, mask); /* before this evaluation's breaks */
        for (int r = 0; r < R; r++)
            for (int i = 0; i < n; i++)
                for (int64_t k = full->off[i]; k < full->off[i + 1]; k++)
                    absent += (mask[r][i] == FLOE_PD_OWNED && !mask[r][full->partner[k]]) ||
                              (mask[r][full->partner[k]] == FLOE_PD_OWNED && !mask[r][i]);
        place(full, e, x);
        memset(f, 0, 3 * n * sizeof *f);
        const double ef = floe_pd_forces(full, x, f);
        double es = 0;
        int64_t nb = 0;
        /* a ghost's position is its owner's; an absent point's is never read */
        double *xr[3];
        for (int r = 0; r < R; r++) {
            xr[r] = malloc(3 * n * sizeof *xr[r]);
            for (int i = 0; i < n; i++)
                for (int a = 0; a < 3; a++) xr[r][3 * i + a] = mask[r][i] ? x[3 * i + a] : NAN;
        }
        for (int r = 0; r < R; r++) {
            memset(g, 0, 3 * n * sizeof *g);
            es += floe_pd_forces(part[r], xr[r], g);
            free(xr[r]);
            nb += part[r]->nbroken;
            for (int i = 0; i < n; i++)
                if (mask[r][i] == FLOE_PD_OWNED) {
                    fbits &= memcmp(g + 3 * i, f + 3 * i, 3 * sizeof *g) == 0;
                    if (alpha > 0) s0bits &= part[r]->s0[i] == full->s0[i];
                    if (lps) s0bits &= part[r]->theta[i] == full->theta[i] &&
                                       (!full->dten || part[r]->dten[9 * n + i] == full->dten[9 * n + i]);
                }
            for (int i = 0; i < n; i++)
                for (int64_t k = full->off[i]; k < full->off[i + 1]; k++)
                    if (mask[r][i] == FLOE_PD_OWNED || mask[r][full->partner[k]] == FLOE_PD_OWNED) {
                        flags &= part[r]->broken[k] == full->broken[k];
                        if (yield > 0) flags &= part[r]->splast[k] == full->splast[k];
                    }
        }
        /* the ghosts' s0 from their owners (the ranks' exchange) */
        if (alpha > 0)
            for (int r = 0; r < R; r++)
                for (int i = 0; i < n; i++)
                    if (mask[r][i] == FLOE_PD_GHOST) part[r]->s0[i] = part[owner[i]]->s0[i];
        CHECK(nb == full->nbroken, "R %d alpha %g evaluation %d: broken bonds summed over the ranks %lld, unsplit %lld",
              R, alpha, e, (long long)nb, (long long)full->nbroken);
        const double rel = fabs(es - ef) / fabs(ef);
        if (rel > erel) erel = rel;
        broke = full->nbroken;
    }
    printf("%s%s%s%s R %d alpha %g, %d thread%s a rank: %d points, %d ghosts on rank 0 at the start, %lld bonds, %lld broken after "
           "12 evaluations, %d bonds of owned points to absent points left out, energy rel. err %.2e\n",
           tension_only || lps ? "" : "(broken bonds inert) ", lps ? "LPS" : "PMB", corr ? " corrected" : "", yield > 0 ? " plastic" : "", R, alpha, threads, threads > 1 ? "s" : "", n, ghosts,
           (long long)full->nbond, (long long)broke, absent, erel);
    if (lps || !tension_only) CHECK(absent > 100, "broken bonds' partners leave the halo (%d left out)", absent);
    CHECK(broke > 20 && broke < full->nbond / 2, "some bonds break in the neck (%lld)", (long long)broke);
    CHECK(fbits, "R %d alpha %g: every owned point's force is the unsplit one to the bit", R, alpha);
    CHECK(flags, "R %d alpha %g: every bond with an owned end has the unsplit broken flag (and plastic stretch)", R, alpha);
    if (yield > 0) {
        int64_t yielded = 0;
        for (int64_t k = 0; k < full->nbond; k++) yielded += full->splast[k] != 0.0f;
        printf("  plastic: %lld bonds yielded\n", (long long)yielded);
        CHECK(yielded > 50, "plastic: bonds yield (%lld)", (long long)yielded);
    }
    CHECK(s0bits, "R %d alpha %g: every owned point's s0 (PMB alpha) or theta and q (LPS) is the unsplit one to the bit",
          R, alpha);
    CHECK(erel <= 1e-12, "R %d alpha %g: the ranks' energies add up to the unsplit energy (rel. %.2e)", R, alpha, erel);
    for (int r = 0; r < R; r++) {
        floe_pd_body_destroy(part[r]);
        free(mask[r]);
    }
    floe_pd_body_destroy(full);
    free(owner); free(x); free(f); free(g);
}

int main(void)
{
    for (int t = 1; t <= 2; t++) { /* one thread a rank, then two (the threaded loops' parts) */
        run(2, 0.0, 0, 0, 0, t, 1);
        run(3, 0.0, 0, 0, 0, t, 1);
        run(2, 0.25, 0, 0, 0, t, 1);
        run(3, 0.25, 0, 1, 0, t, 1);
        run(2, 0.0, 0, 0, 5e-4, t, 1);
        run(2, 0.25, 0, 0, 0, t, 0); /* broken bonds inert: their partners leave the halo */
        run(2, 0.0, 0, 0, 5e-4, t, 0);
        run(2, 0.0, 1, 0, 0, t, 1);
        run(3, 0.0, 1, 1, 0, t, 1);
    }
    return check_summary("test_pd_split");
}
