/* test_mpi_balance.c - the load balance by measured time (floe_world_parallel_set_balance,
 * core/parallel/decomp.c time_shares, docs/parallel.md "Load balance"), run under mpirun with
 * 1, 2 and 4 ranks (tests/CMakeLists.txt). A loose lattice of equal spheres (no contacts:
 * every particle weighs about the same, so a rank's share of the weights is its share of the
 * particles):
 *   - the modes: an unknown one refused (FLOE_EINVAL, with a message);
 *   - a rank that measures twice the others' seconds per unit of weight (its force time set
 *     by hand before a decomposition: timings of a real run are not repeatable) gets the
 *     share its speed gives, 1/2 / (1/2 + S - 1) of the particles (1/3 with 2 ranks), within
 *     Zoltan's bisection tolerance; the others share the rest evenly; every particle is owned
 *     by exactly one rank;
 *   - the next measure (equal costs) is averaged with the last: the slow rank's share moves
 *     half way back (cost 1.5: 2/3 / (2/3 + S - 1));
 *   - back to FLOE_BALANCE_WEIGHTS: even shares again;
 *   - a bed under a cloud: both the particles and the contacts balanced (build_bed_cloud);
 *   - an imbalance no cut can mend (three spheres far apart: the fullest part holds ceil(3 / S)
 *     of them against a share of 3 / S, 4/3 of it at 2 and 4 ranks): the fresh choice of directions does no better and is rejected, its imbalance
 *     kept; the next decompositions do not try again (the kept cuts are no worse), and with
 *     that memory cleared one does, at the cost of its three reductions, and rejects it
 *     again (check_rejected_fresh);
 *   - a run of 300 steps under the time balance (the real timings, cuts at every rebuild)
 *     ends with the same kinetic energy as under the weights within 1e-9 (the decompositions
 *     differ: only round-off may), and the force time it measured is positive. */
#include "floe.h"
#include "world_internal.h"
#include "par_internal.h"
#include "../check.h"
#include "mpi_common.h"
#include <math.h>
#include <stdlib.h>

static const double L = 0.03;
enum { NS = 12 }; /* 1728 spheres */

static floe_world *build(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = 1e-6;
    d.gravity[2] = -9.81;
    d.energy_check = FLOE_CHECK_OFF;
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    const int g = floe_world_add_geometry(w, floe_sphere_create(0.0004));
    mpi_test_box_walls(w, L, L, L, 0, 6);
    const double h = L / NS;
    unsigned s = 4242;
    for (int a = 0; a < NS; a++)
        for (int b = 0; b < NS; b++)
            for (int c = 0; c < NS; c++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g;
                p.material = 0;
                double j[3];
                for (int k = 0; k < 3; k++) { s = s * 1103515245u + 12345u; j[k] = (s >> 8) / 16777216.0 - 0.5; }
                floe_v3_set(p.x, (a + 0.5) * h, (b + 0.5) * h, (c + 0.5) * h);
                floe_v3_set(p.v, 0.2 * j[0], 0.2 * j[1], 0.2 * j[2]);
                floe_world_add_particle(w, &p);
            }
    if (floe_world_prepare(w)) { fprintf(stderr, "prepare: %s\n", floe_world_last_error(w)); exit(2); }
    return w;
}

/* this rank's owned count after a decomposition with its force time set to `cost` seconds per
 * owned particle (every rank the same time per particle times its factor) */
static int decompose_with_cost(floe_world *w, double cost) {
    w->par->busy = cost * w->par->nown;
    const int rc = floe_world_parallel_rebuild(w);
    CHECK(rc == 0, "rebuild: %s", rc ? floe_world_last_error(w) : "");
    int own, gh;
    floe_world_parallel_counts(w, &own, &gh);
    return own;
}

/* the owned counts of every rank gathered; every particle owned once */
static void gather_owned(int own, int *all) {
    MPI_Allgather(&own, 1, MPI_INT, all, 1, MPI_INT, MPI_COMM_WORLD);
    long tot = 0;
    for (int r = 0; r < size_; r++) tot += all[r];
    CHECK(tot == NS * NS * NS, "owned in all: %ld of %d", tot, NS * NS * NS);
}

/* rank 0's share and the others' against the speeds' shares, within 10 % (Zoltan's default
 * imbalance tolerance; the lattice's cuts come out exact) */
static void check_shares(const int *all, double slow, const char *when) {
    const double N = NS * NS * NS, s0 = (1.0 / slow) / (1.0 / slow + (size_ - 1));
    const double want0 = size_ == 1 ? N : s0 * N, want = size_ == 1 ? N : (1 - s0) * N / (size_ - 1);
    if (rank_ == 0) {
        printf("  %s: owned", when);
        for (int r = 0; r < size_; r++) printf(" %d", all[r]);
        printf(" (want %.0f, then %.0f each)\n", want0, want);
    }
    CHECK(fabs(all[0] - want0) <= 0.1 * want0, "%s: rank 0 owns %d, want %.0f", when, all[0], want0);
    for (int r = 1; r < size_; r++)
        CHECK(fabs(all[r] - want) <= 0.1 * want, "%s: rank %d owns %d, want %.0f", when, r, all[r], want);
}

/* A bed under a cloud (docs/parallel.md "Subdomains"): a bed of touching spheres (25 x 25 x 3,
 * spacing 0.79 mm for radius 0.4 mm: every lattice neighbour in contact) at the bottom of a
 * box 20 x 20 x 40 mm, and as many loose spheres (11 x 11 x 16, spacing 1.8 mm) above it, no
 * gravity. The split cuts across the height (the only direction within 2/3 of the longest
 * extent): one rank the bed, the other the cloud. After a step (the contacts known) a
 * decomposition must balance both the particles (their integration and list) and the contacts:
 * each rank's owned count and its count of owned particles in contact within 15 % of the
 * mean. One weight (the work's sum) cut the bed across its height: at 2 ranks 0.53 of the bed
 * on one rank, the rest with the whole cloud on the other (owned 1,000 and 2,800) */
static floe_world *build_bed_cloud(int *nbed) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = 1e-6;
    d.energy_check = FLOE_CHECK_OFF;
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    const double r = 0.0004, Lb = 0.02;
    const int g = floe_world_add_geometry(w, floe_sphere_create(r));
    mpi_test_box_walls(w, Lb, Lb, 2 * Lb, 0, 6);
    *nbed = 0;
    for (int c = 0; c < 3; c++)
        for (int b = 0; b < 25; b++)
            for (int a = 0; a < 25; a++, ++*nbed) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g;
                floe_v3_set(p.x, r + a * 0.00079, r + b * 0.00079, r + c * 0.00079);
                floe_world_add_particle(w, &p);
            }
    for (int c = 0; c < 16; c++)
        for (int b = 0; b < 11; b++)
            for (int a = 0; a < 11; a++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g;
                floe_v3_set(p.x, 0.001 + a * 0.0018, 0.001 + b * 0.0018, 0.005 + c * 0.0018);
                floe_world_add_particle(w, &p);
            }
    if (floe_world_prepare(w)) { fprintf(stderr, "prepare: %s\n", floe_world_last_error(w)); exit(2); }
    return w;
}

static void check_bed_cloud(void) {
    int nbed = 0;
    floe_world *w = build_bed_cloud(&nbed);
    const int ntot = nbed + 11 * 11 * 16;
    int rc = floe_world_parallel_init(w, NULL);
    if (!rc) rc = floe_world_step(w); /* the contacts known */
    if (!rc) rc = floe_world_parallel_rebuild(w);
    if (!rc) rc = floe_world_step(w);
    CHECK(rc == 0, "bed and cloud: %s", rc ? floe_world_last_error(w) : "");
    if (!rc) {
        /* this rank's owned particles, and those of them in contact with another sphere */
        const floe_particles *p = &w->p;
        const floe_neighbor_list *nl = &w->nl;
        const int lo = w->par->nrep, hi = lo + w->par->nown;
        unsigned char *t = calloc((size_t)p->n + 1, 1);
        for (int k = 0; k < nl->npairs; k++)
            if (nl->touching[k] && p->kind[nl->pi[k]] == FLOE_GEOM_SPHERE && p->kind[nl->pj[k]] == FLOE_GEOM_SPHERE)
                t[nl->pi[k]] = t[nl->pj[k]] = 1;
        int mine[2] = {w->par->nown, 0}, all[2 * 64];
        for (int i = lo; i < hi; i++) mine[1] += t[i];
        free(t);
        if (size_ <= 64) {
            MPI_Allgather(mine, 2, MPI_INT, all, 2, MPI_INT, MPI_COMM_WORLD);
            long tot[2] = {0, 0};
            for (int q = 0; q < size_; q++) { tot[0] += all[2 * q]; tot[1] += all[2 * q + 1]; }
            if (rank_ == 0) {
                printf("  bed and cloud (%d + %d spheres), owned / in contact:", nbed, ntot - nbed);
                for (int q = 0; q < size_; q++) printf(" %d / %d", all[2 * q], all[2 * q + 1]);
                printf("\n");
            }
            CHECK(tot[0] == ntot && tot[1] >= nbed * 9 / 10, "bed and cloud: %ld owned (of %d), %ld in contact", tot[0], ntot,
                  tot[1]);
            for (int q = 0; q < size_; q++)
                for (int c = 0; c < 2; c++)
                    CHECK(fabs(all[2 * q + c] - (double)tot[c] / size_) <= 0.15 * tot[c] / size_,
                          "bed and cloud: rank %d %s %d, the mean %.0f", q, c ? "in contact" : "owns", all[2 * q + c],
                          (double)tot[c] / size_);
        }
    }
    floe_world_destroy(w);
}

/* the reductions (FLOE_COMM_REDUCE messages) of one decomposition */
static long long rebuild_reductions(floe_world *w) {
    floe_world_parallel_comm_reset(w);
    const int rc = floe_world_parallel_rebuild(w);
    CHECK(rc == 0, "rebuild: %s", rc ? floe_world_last_error(w) : "");
    floe_comm_stats cs;
    floe_world_parallel_comm(w, &cs);
    return cs.messages[FLOE_COMM_REDUCE];
}

static void check_rejected_fresh(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = 1e-6;
    d.energy_check = FLOE_CHECK_OFF;
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    const int g = floe_world_add_geometry(w, floe_sphere_create(0.0004));
    for (int k = 0; k < 3; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        floe_v3_set(p.x, 0.01 * k, 0.001 * k, 0);
        floe_world_add_particle(w, &p);
    }
    if (floe_world_prepare(w)) { fprintf(stderr, "prepare: %s\n", floe_world_last_error(w)); exit(2); }
    int rc = floe_world_parallel_init(w, NULL);
    CHECK(rc == 0, "three spheres: split: %s", rc ? floe_world_last_error(w) : "");
    const double worst = ceil(3.0 / size_) / (3.0 / size_); /* the fullest part over its share */
    if (rc == 0 && worst > 1.05) { /* (2 and 4 ranks: 4/3; one rank or three: balanced) */
        floe_par *P = w->par;
        const void *zz = P->zz;
        CHECK(fabs(P->rcb_tried - worst) < 1e-12, "three spheres: the fresh choice rejected at the split, the kept "
              "imbalance %.4f remembered (%.4f)", P->rcb_tried, worst);
        const long long r1 = rebuild_reductions(w), r2 = rebuild_reductions(w);
        CHECK(r1 == r2 && fabs(P->rcb_tried - worst) < 1e-12 && P->zz == zz,
              "three spheres: no fresh choice while the kept cuts are no worse (%lld, %lld reductions; %.4f)", r1, r2,
              P->rcb_tried);
        P->rcb_tried = 0; /* forgotten: the next decomposition tries again */
        const long long r3 = rebuild_reductions(w);
        CHECK(r3 == r1 + 3 && fabs(P->rcb_tried - worst) < 1e-12 && P->zz == zz,
              "three spheres: a fresh choice tried again (%lld reductions against %lld: + 2 agreements and its "
              "imbalance), rejected, the kept directions' object kept (%.4f)", r3, r1, P->rcb_tried);
        if (rank_ == 0) printf("  three spheres: fresh choice rejected, imbalance %.4f kept; %lld reductions a "
                               "decomposition, %lld with a fresh try\n", P->rcb_tried, r1, r3);
    }
    floe_world_destroy(w);
}

static double kinetic_after(floe_balance mode, int steps, double *force_s) {
    floe_world *w = build();
    int rc = floe_world_parallel_init(w, NULL);
    if (!rc) rc = floe_world_parallel_set_balance(w, mode);
    for (int k = 0; !rc && k < steps; k++) rc = floe_world_step(w);
    CHECK(rc == 0, "run: %s", rc ? floe_world_last_error(w) : "");
    floe_energy e;
    floe_world_parallel_energy(w, &e);
    floe_comm_stats cs;
    floe_world_parallel_comm(w, &cs);
    *force_s = cs.force_seconds;
    floe_world_destroy(w);
    return e.kinetic_trans + e.kinetic_rot;
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    floe_world *w = build();
    int rc = floe_world_parallel_init(w, NULL);
    CHECK(rc == 0, "split: %s", rc ? floe_world_last_error(w) : "");
    CHECK(floe_world_parallel_set_balance(w, (floe_balance)7) == FLOE_EINVAL, "an unknown mode is refused");
    CHECK(strstr(floe_world_last_error(w), "balance mode") != NULL, "its message: %s", floe_world_last_error(w));
    if (rc == 0) {
        int all[64];
        rc = floe_world_parallel_set_balance(w, FLOE_BALANCE_TIME);
        CHECK(rc == 0, "time balance: %s", rc ? floe_world_last_error(w) : "");
        if (size_ <= 64 && rc == 0) {
            /* rank 0 twice as slow per unit of weight */
            gather_owned(decompose_with_cost(w, rank_ == 0 ? 2e-6 : 1e-6), all);
            check_shares(all, 2.0, "rank 0 at twice the cost");
            /* equal costs now: the smoothed cost of rank 0 is 1.5 */
            gather_owned(decompose_with_cost(w, 1e-6), all);
            check_shares(all, 1.5, "then equal costs (averaged)");
            /* the weights again: even shares */
            rc = floe_world_parallel_set_balance(w, FLOE_BALANCE_WEIGHTS);
            CHECK(rc == 0, "weights balance: %s", rc ? floe_world_last_error(w) : "");
            gather_owned(decompose_with_cost(w, rank_ == 0 ? 5e-6 : 1e-6), all);
            check_shares(all, 1.0, "weights (the time ignored)");
        }
    }
    floe_world_destroy(w);
    check_bed_cloud();
    check_rejected_fresh();
    /* a run under each mode: the same physics within round-off */
    double fw, ft;
    const double kw = kinetic_after(FLOE_BALANCE_WEIGHTS, 300, &fw), kt = kinetic_after(FLOE_BALANCE_TIME, 300, &ft);
    if (rank_ == 0) printf("  300 steps: kinetic energy %.17g (weights) %.17g (time)\n", kw, kt);
    CHECK(kw > 0 && fabs(kt - kw) <= 1e-9 * kw, "kinetic energy: %.17g under time, %.17g under weights", kt, kw);
    CHECK(ft > 0 && fw > 0, "force time measured: %g, %g s", ft, fw);
    int fails = mpi_test_failed("test_mpi_balance");
    MPI_Finalize();
    return fails ? 1 : 0;
}
