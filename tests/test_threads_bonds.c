/* test_threads_bonds.c - the bond forces give the same bits on 1, 2, 3 and 4 threads (issue
 * 14, docs/parallel.md "The same bits"): peridynamic bonds (peridynamics/pd_materials.c, the
 * rows in parallel and a per-point gather in the serial order) and beam bonds
 * (contact/bonds/beam_bond.c, the bonds in parallel and a per-particle gather). Each world is
 * built and stepped with 1-4 threads at the default loop grain (2,048 items: every bond loop
 * here is above it, and the PD ledger's loop over points in A, F and G), and the particles'
 * positions, velocities, forces (and for beams orientations, angular velocities, torques),
 * the energy ledger, the broken counts and flags, the PD per-point state (s0, theta, q) and
 * the correspondence stress output (F, sigma, von Mises) must equal one thread's to the last
 * bit (memcmp). Bonds break during every run (checked: some broken halfway, more at the end):
 *   A. a 2D PMB plate of 5,200 points (70,000 bonds) with an edge notch, stretched: the crack
 *      runs from the notch;
 *   B. a plate of 1,920 points (25,000 bonds) with LAMMPS' per-point critical stretch
 *      (alpha: the s0 maxima), and the same plate for C-E;
 *   C. LPS with the position-aware surface correction and the Gaussian influence (theta and q
 *      gathered), and plain LPS;
 *   D. elastic-plastic PMB (yield in tension);
 *   E. PMB under the RK2 integrator (the midpoint probe: the no-breakage evaluation);
 *   F. a 3D PMB block (2,304 points, 102,000 bonds);
 *   G. PMB and LPS plates of 2,304 points filling a periodic cell (bonds through its faces:
 *      the images path), two crossed shear waves;
 *   H. 3,600 discs with 7,080 damped beam bonds (2D) and a 3D lattice of 3,240 spheres with
 *      9,036 bonds, pulled apart: bonds break, some broken pairs meet by contact.
 * Built without OpenMP, the test checks that 2 threads are refused and skips. */
#include "check.h"
#include "floe.h"
#include "floe_pd.h"
#include "beam_set.h"
#include "pd_par.h"
#include "world_internal.h"

#include <stdlib.h>
#include <string.h>

enum { PMB, ALPHA, LPS_SC, LPS_PLAIN, PLASTIC, PMB_RK2, PMB_3D, PMB_CELL, LPS_CELL, BEAM_2D, BEAM_3D };
static const char *names[] = {"PMB plate",   "PMB alpha plate", "LPS plate (surface correction, Gaussian)",
                              "LPS plate (plain)", "plastic PMB plate", "PMB plate, RK2",
                              "PMB 3D block", "PMB in a periodic cell", "LPS in a periodic cell",
                              "beam-bonded discs (2D)", "beam-bonded spheres (3D)"};

static floe_world *new_world(int dim, int integrator) {
    floe_world_def d = floe_default_world_def();
    d.dim = dim;
    floe_v3_set(d.gravity, 0, 0, 0);
    d.integrator = integrator;
    floe_world *w = floe_world_create(&d, NULL, 0);
    if (!w) return NULL;
    floe_material m = {"rock", 2200, 22.35e9, 0.25};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.3));
    return w;
}

/* a PD plate (2D: 100 x 52 points for A, 60 x 32 for the others) or block (3D, 24 x 12 x 8),
 * dx 1 mm, horizon 3 dx, with an edge notch across the middle (its bonds removed:
 * pd_crack.c), stretched along x: the crack starts at the notch after some 80 steps and
 * runs. G: a 48 x 48 plate filling a periodic cell. */
static floe_world *pd_world(int kind) {
    const int dim = kind == PMB_3D ? 3 : 2, cell = kind == PMB_CELL || kind == LPS_CELL;
    floe_world *w = new_world(dim, kind == PMB_RK2 ? FLOE_RK2 : FLOE_VELOCITY_VERLET);
    if (!w) return NULL;
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = dim;
    r.dx = 1e-3;
    r.horizon_factor = 3;
    r.thickness = 1e-3;
    const double Lc = 48e-3; /* the periodic cell's side */
    if (cell) floe_v3_set(r.hi, Lc, Lc, 1e-3);
    else if (kind == PMB) floe_v3_set(r.hi, 100e-3, 52e-3, 1e-3);
    else if (dim == 2) floe_v3_set(r.hi, 60e-3, 32e-3, 1e-3);
    else floe_v3_set(r.hi, 24e-3, 12e-3, 8e-3);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) { floe_world_destroy(w); return NULL; }
    floe_pd_material m;
    if (kind == LPS_SC || kind == LPS_PLAIN || kind == LPS_CELL)
        m = floe_pd_material_lps(2200, 14.9e9, 8.9e9, 2e-3, kind == LPS_SC ? FLOE_PD_W_GAUSS : FLOE_PD_W_ONE);
    else {
        m = floe_pd_material_pmb(2200, 14.9e9, 2e-3);
        m.E = 22.35e9;
        if (kind == ALPHA) m.alpha = 0.25;
        if (kind == PLASTIC) { m.yield_tension = 1e-3; m.s_c = 4e-3; }
    }
    /* a notch across the middle from the edge y = 0, 15 mm (2D) or 5 mm (3D) deep */
    const double xm = 0.5 * r.hi[0], depth = 0.3 * r.hi[1], a0[3] = {xm, -1e-3, -1e-3};
    const double e1[3] = {0, depth + 1e-3, 0}, e2[3] = {0, 0, r.hi[2] + 2e-3}, a1[3] = {xm, depth, 0};
    const floe_pd_crack cr = dim == 2 ? floe_pd_crack_segment(a0, a1) : floe_pd_crack_rectangle(a0, e1, e2);
    const double o[3] = {0, 0, 0}, H[9] = {Lc, 0, 0, 0, Lc, 0, 0, 0, 1};
    if (floe_pd_set_material(b, &m) || (!cell && floe_pd_add_crack(b, &cr) <= 0) ||
        (kind == LPS_SC && floe_pd_surface_correction(b)) || (cell && floe_world_set_cell(w, o, H)) ||
        floe_world_add_pd_body(w, b, 0, NULL, NULL)) {
        floe_world_destroy(w);
        return NULL;
    }
    if (cell) { /* an infinite plate (bonds through the faces): two crossed shear waves */
        for (int i = 0; i < b->n; i++) {
            const double *X = b->X + 3 * i, k = 2 * M_PI / Lc;
            double vi[3] = {12.0 * sin(k * X[1]), 9.0 * sin(k * X[0] + 0.5), 0};
            floe_world_set_velocity(w, i, vi, NULL);
        }
        return w;
    }
    /* a uniform extension along x (v at the ends), and a little shear */
    const double v = (dim == 2 ? 200.0 : 280.0) * xm; /* a strain rate of 200 /s (3D 280 /s) */
    for (int i = 0; i < b->n; i++) {
        double vi[3] = {v * (b->X[3 * i] - xm) / xm, 0.1 * v * (b->X[3 * i + 1] / r.hi[1] - 0.5), 0};
        floe_world_set_velocity(w, i, vi, NULL);
    }
    return w;
}

/* discs (2D, 60 x 60) or spheres (3D, 18 x 18 x 10) on a square lattice of spacing 1 cm,
 * nearest-neighbour beam bonds with strengths N(mean, sd), damping; the halves pulled apart */
static floe_world *beam_world(int kind) {
    const int dim = kind == BEAM_3D ? 3 : 2;
    floe_world *w = new_world(dim, FLOE_VELOCITY_VERLET);
    if (!w) return NULL;
    const int nx = dim == 2 ? 60 : 18, ny = nx, nz = dim == 2 ? 1 : 10;
    const double s = 0.01;
    int g = floe_world_add_geometry(w, floe_sphere_create(0.5 * s));
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g;
                floe_v3_set(p.x, s * i, s * j, s * k);
                const double v = i < nx / 2 ? -1.0 : 1.0;
                floe_v3_set(p.v, v * (1.0 + 0.2 * (double)j / ny), 0.1 * v, 0);
                p.w[2] = 0.5 * (double)((i * 7 + j * 3) % 5 - 2);
                if (floe_world_add_particle(w, &p) < 0) { floe_world_destroy(w); return NULL; }
            }
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 1e9;
    bp.tensile_strength = 1.0e6;
    bp.tensile_sd = 0.3e6;
    bp.shear_strength = 3.0e6;
    bp.shear_sd = 0.5e6;
    bp.damping_ratio = 0.05;
    bp.thickness = s; /* 2D: sections s wide */
    bp.seed = 7;
    if (floe_world_add_beam_bonds(w, 1.01, &bp) <= 0) { floe_world_destroy(w); return NULL; }
    return w;
}

typedef struct run_out {
    double *state; size_t nstate;
    unsigned char *flags; size_t nflags;
    floe_energy e;
    long long nbroken, nbroken_early;
    int ncontacts, nbonds, threaded, images, border, npts;
} run_out;

static int run(int kind, int threads, int steps, run_out *o) {
    const int beams = kind == BEAM_2D || kind == BEAM_3D;
    floe_world *w = beams ? beam_world(kind) : pd_world(kind);
    if (!w) return 1;
    /* threads < 0: 2, 4, 1 and 3 threads by quarters of the run (the parts cut again) */
    const int seq[4] = {2, 4, 1, 3};
    if (floe_world_set_threads(w, threads < 0 ? seq[0] : threads) || floe_world_prepare(w)) {
        fprintf(stderr, "%s\n", floe_world_last_error(w));
        floe_world_destroy(w);
        return 1;
    }
    for (int s = 0; s < steps; s++) {
        if (threads < 0 && s % (steps / 4) == 0 && s / (steps / 4) < 4) floe_world_set_threads(w, seq[s / (steps / 4)]);
        if (floe_world_step(w)) {
            fprintf(stderr, "step %d: %s\n", s, floe_world_last_error(w));
            floe_world_destroy(w);
            return 1;
        }
        if (s == steps / 2)
            o->nbroken_early = beams ? floe_world_beam_broken_count(w) : (long long)w->pd[0]->nbroken;
    }
    const floe_particles *p = &w->p;
    const size_t n = (size_t)p->n;
    const floe_pd_body *b = beams ? NULL : w->pd[0];
    const size_t nextra = b ? (b->s0 ? 2 * (size_t)b->n : 0) + (b->theta ? (size_t)b->n : 0) +
                                  (b->dten ? 11 * (size_t)b->n : 0)
                            : 0;
    o->nstate = n * (beams ? 22 : 9) + nextra + (b ? 19 * (size_t)b->n + 1 : 0);
    o->state = malloc(o->nstate * sizeof(double));
    double *d = o->state;
    memcpy(d, p->x, 3 * n * sizeof(double)); d += 3 * n;
    memcpy(d, p->v, 3 * n * sizeof(double)); d += 3 * n;
    memcpy(d, p->f, 3 * n * sizeof(double)); d += 3 * n;
    if (beams) {
        memcpy(d, p->q, 4 * n * sizeof(double)); d += 4 * n;
        memcpy(d, p->L, 3 * n * sizeof(double)); d += 3 * n;
        memcpy(d, p->w, 3 * n * sizeof(double)); d += 3 * n;
        memcpy(d, p->t, 3 * n * sizeof(double)); d += 3 * n;
        o->nflags = (size_t)floe_world_beam_bond_count(w);
        o->flags = malloc(o->nflags ? o->nflags : 1);
        for (size_t k = 0; k < o->nflags; k++) {
            floe_beam_bond_info info;
            floe_world_beam_bond(w, (int)k, &info);
            o->flags[k] = (unsigned char)info.broken;
        }
        o->nbroken = floe_world_beam_broken_count(w);
        o->nbonds = floe_world_beam_bond_count(w);
        o->threaded = floe_beam_set_threaded(w->beams);
    } else {
        if (b->s0) { memcpy(d, b->s0, 2 * (size_t)b->n * sizeof(double)); d += 2 * (size_t)b->n; }
        if (b->theta) { memcpy(d, b->theta, (size_t)b->n * sizeof(double)); d += b->n; }
        if (b->dten) { memcpy(d, b->dten, 11 * (size_t)b->n * sizeof(double)); d += 11 * (size_t)b->n; }
        /* the correspondence stress of the output (pd_correspondence.c), threaded as well */
        int sing = 0;
        const size_t m = (size_t)b->n;
        if (floe_pd_correspondence(b, p->x, 8.9e9, 9e9, d, NULL, d + 9 * m, d + 18 * m, &sing)) {
            floe_world_destroy(w);
            return 1;
        }
        d += 19 * m;
        *d++ = sing;
        o->nflags = (size_t)b->nbond;
        o->flags = malloc(o->nflags ? o->nflags : 1);
        memcpy(o->flags, b->broken, o->nflags);
        o->nbroken = b->nbroken;
        o->nbonds = (int)b->nbond;
        o->threaded = b->par != NULL;
        o->images = b->img != NULL;
        o->npts = b->n;
        if (b->par && b->par->own) /* the points on the parts' borders: through the gather */
            for (int q = 0; q < b->n; q++) o->border += !b->par->own[q];
    }
    o->e = floe_world_energy(w);
    o->ncontacts = floe_world_contact_count(w);
    floe_world_destroy(w);
    return 0;
}

#ifdef _OPENMP
static void compare(int kind, int steps) {
    const char *what = names[kind];
    const int beams = kind == BEAM_2D || kind == BEAM_3D;
    run_out ref, o;
    memset(&ref, 0, sizeof ref);
    CHECK(run(kind, 1, steps, &ref) == 0, "%s: one thread runs", what);
    CHECK(!ref.threaded, "%s: one thread keeps the serial path", what);
    if (kind == PMB_CELL || kind == LPS_CELL) CHECK(ref.images, "%s: bonds through the cell's faces", what);
    CHECK(ref.nbroken_early > 0 && ref.nbroken > ref.nbroken_early,
          "%s: bonds break during the run (%lld after %d steps, %lld at the end)", what, ref.nbroken_early, steps / 2,
          ref.nbroken);
    for (int t = 2; t <= 4; t++) {
        memset(&o, 0, sizeof o);
        CHECK(run(kind, t, steps, &o) == 0, "%s: %d threads run", what, t);
        CHECK(o.threaded, "%s: %d threads took the threaded path", what, t);
        if (!beams) /* both ways of adding a bond's share: direct (owned points) and gathered */
            CHECK(o.border > 0 && o.border < o.npts, "%s: %d threads: %d of %d points on the parts' borders", what, t,
                  o.border, o.npts);
        CHECK(o.nstate == ref.nstate && !memcmp(o.state, ref.state, ref.nstate * sizeof(double)),
              "%s: %d threads: positions, velocities, forces (and state) bit-identical", what, t);
        CHECK(!memcmp(&o.e, &ref.e, sizeof o.e),
              "%s: %d threads: energy ledger bit-identical (elastic %.17g vs %.17g, dissipated %.17g vs %.17g)", what, t,
              o.e.elastic, ref.e.elastic, o.e.dissipated, ref.e.dissipated);
        CHECK(o.nbroken == ref.nbroken && o.nflags == ref.nflags && !memcmp(o.flags, ref.flags, ref.nflags),
              "%s: %d threads: the same bonds broken (%lld vs %lld)", what, t, o.nbroken, ref.nbroken);
        CHECK(o.ncontacts == ref.ncontacts, "%s: %d threads: contacts %d vs %d", what, t, o.ncontacts, ref.ncontacts);
        free(o.state);
        free(o.flags);
    }
    if (!beams) { /* the thread count changed during the run */
        memset(&o, 0, sizeof o);
        CHECK(run(kind, -1, steps, &o) == 0, "%s: 2, 4, 1, 3 threads in turn run", what);
        CHECK(o.nstate == ref.nstate && !memcmp(o.state, ref.state, ref.nstate * sizeof(double)) &&
                  !memcmp(&o.e, &ref.e, sizeof o.e) && o.nbroken == ref.nbroken,
              "%s: 2, 4, 1, 3 threads in turn: the same bits as one", what);
        free(o.state);
        free(o.flags);
    }
    printf("%s: %d bonds, %lld broken after %d steps, %d contacts, elastic %.6e J, dissipated %.6e J: same bits "
           "for 1-4 threads\n", what, ref.nbonds, ref.nbroken, steps, ref.ncontacts, ref.e.elastic, ref.e.dissipated);
    free(ref.state);
    free(ref.flags);
}
#endif

/* the PD rows' parts (pd_materials.c pd_par_get): on 3 and 4 threads each part a run of
 * whole blocks, at least one, cut at the block border nearest to an equal share of the bonds
 * (within one block's bonds of it). The 3D block's rows hold fewer bonds toward its end (a
 * row holds its bonds to higher indices): equal rows would not give equal bonds. */
static __attribute__((unused)) void check_cut(void) {
    for (int nt = 3; nt <= 4; nt++) {
        floe_world *w = pd_world(PMB_3D);
        int ok = w && !floe_world_set_threads(w, nt) && !floe_world_prepare(w) && !floe_world_step(w);
        const floe_pd_body *b = ok ? w->pd[0] : NULL;
        const floe_pd_par *P = b ? b->par : NULL;
        CHECK(ok && P && P->nparts == nt, "PD parts: %d threads cut %d parts", nt, P ? P->nparts : -1);
        if (!P || P->nparts != nt) { floe_world_destroy(w); continue; }
        const int B = FLOE_PD_ROW_BLOCK, nblk = (b->n + B - 1) / B;
        int64_t blkmax = 0;
        for (int c = 0; c < nblk; c++) {
            const int64_t bb = b->off[(c + 1) * B < b->n ? (c + 1) * B : b->n] - b->off[c * B];
            if (bb > blkmax) blkmax = bb;
        }
        int whole = P->cut[0] == 0 && P->cut[nt] == nblk, near = 1, nearest = 1;
        double worst = 0;
        for (int t = 0; t < nt; t++) {
            whole &= P->cut[t + 1] >= P->cut[t] + 1;
            if (t > 0) { /* no border one block up or down (within the clamps) is nearer the share */
                const int64_t aim = b->nbond * t;
                int64_t d[3];
                for (int e = -1; e <= 1; e++) {
                    const int64_t r = (int64_t)(P->cut[t] + e) * B;
                    d[e + 1] = llabs(b->off[r < 0 ? 0 : r < b->n ? r : b->n] * nt - aim);
                }
                nearest &= (P->cut[t] - 1 <= P->cut[t - 1] || d[1] <= d[0]) && (P->cut[t] + 1 >= P->cut[t + 1] || d[1] <= d[2]);
            }
            const int r0 = P->cut[t] * B, r1 = P->cut[t + 1] * B < b->n ? P->cut[t + 1] * B : b->n;
            const double dev = fabs((double)(b->off[r1] - b->off[r0]) - (double)b->nbond / nt);
            near &= dev <= (double)blkmax;
            if (dev > worst) worst = dev;
        }
        const double even = fabs((double)b->off[nblk / 2 * B] - (double)b->nbond / 2);
        CHECK(whole && near && nearest, "PD parts on %d threads: runs of whole blocks, each within one block's bonds "
              "(%lld) of an equal share (worst %.0f of %lld bonds), each border the block border nearest its share",
              nt, (long long)blkmax, worst, (long long)b->nbond);
        if (nt == 3) printf("PD parts: %lld bonds, %d blocks; on 3 threads at most %.0f bonds from an equal share (half "
                            "the rows hold %.0f more or less than half the bonds)\n", (long long)b->nbond, nblk, worst, even);
        floe_world_destroy(w);
    }
}

int main(void) {
#ifndef _OPENMP
    floe_world *w = pd_world(PMB);
    CHECK(w && floe_world_set_threads(w, 2) == FLOE_ENOTSUP, "without OpenMP 2 threads are refused");
    floe_world_destroy(w);
    (void)run;
    (void)names;
    printf("built without OpenMP: skipped\n");
    return check_fail_ ? 1 : 77;
#else
    compare(PMB, 240);
    compare(ALPHA, 240);
    compare(LPS_SC, 240);
    compare(LPS_PLAIN, 240);
    compare(PLASTIC, 240);
    compare(PMB_RK2, 240);
    compare(PMB_3D, 160);
    check_cut();
    compare(PMB_CELL, 240);
    compare(LPS_CELL, 240);
    compare(BEAM_2D, 400);
    compare(BEAM_3D, 300);
    return check_summary("test_threads_bonds");
#endif
}
