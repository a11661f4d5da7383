/* test_mpi_cell.c - a periodic cell split over MPI ranks through the library (docs/parallel.md,
 * "Periodic cells across ranks"). Run under mpirun with 1, 2 and 4 ranks. Rank 0 first runs
 * the unsplit world alone; then every rank builds the same world, splits it and steps it.
 * 216 spheres on a cubic lattice with gaps in a cell tilted in xy, with random velocities,
 * sheared at 2 /s (xy) while the stress servo holds the diagonal at -5 Pa (unclamped once
 * contacts form: the step sums the contacts' virial and stiffness over the ranks). After
 * 3,000 steps (contacts through the faces, particles crossing them and changing rank):
 *  - the cell H the same bits on every rank, and within 1e-12 of the unsplit run's;
 *  - every particle's (unwrapped) position within 1e-10 of the cell's size of the unsplit
 *    run's, its velocity within 1e-8 of the largest speed;
 *  - the ledger summed over the ranks within 1e-9 of the energy scale, the cell's work in
 *    it not zero;
 *  - the queries that read this rank's contacts alone refuse a split world (FLOE_ENOTSUP):
 *    floe_world_cell_stress, floe_world_cell_measures, floe_world_tangent_contact,
 *    floe_world_refresh_forces. */
#include "floe.h"
#include "../check.h"
#include "mpi_common.h"
#include "../sheared_cell.h"
#include <math.h>
#include <stdlib.h>

enum { NS = 6, STEPS = 3000 };
static const double SP = 0.0026, LC = NS * 0.0026;

static floe_world *build(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.dt = 5e-6;
    d.skin = 0.0002;
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    sheared_cell_set(w, NS, SP);
    const int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    unsigned s = 4242;
    for (int k = 0; k < NS * NS * NS; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        double j[6];
        for (int q = 0; q < 6; q++) { s = s * 1103515245u + 12345u; j[q] = (s >> 8) / 16777216.0 - 0.5; }
        sheared_cell_site(k, NS, SP, p.x);
        floe_v3_set(p.v, 0.2 * j[0], 0.2 * j[1], 0.2 * j[2]);
        floe_v3_set(p.w, 20 * j[3], 20 * j[4], 20 * j[5]);
        floe_world_add_particle(w, &p);
    }
    return w;
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    const int N = NS * NS * NS;
    double *x0 = calloc((size_t)N * 3, sizeof *x0), *v0 = calloc((size_t)N * 3, sizeof *v0), H0[9] = {0};
    floe_energy e0 = {0};
    if (rank_ == 0) { /* the unsplit run */
        floe_world *w = build();
        for (int s = 0; s < STEPS; s++)
            if (floe_world_step(w)) { fprintf(stderr, "serial: %s\n", floe_world_last_error(w)); return 1; }
        floe_world_parallel_gather(w, x0, v0, N);
        floe_world_cell(w, NULL, H0);
        e0 = floe_world_energy(w);
        floe_world_destroy(w);
    }
    floe_world *w = build();
    int rc = floe_world_prepare(w);
    if (!rc) rc = floe_world_parallel_init(w, NULL);
    CHECK(rc == 0, "split: %s", rc ? floe_world_last_error(w) : "");
    for (int s = 0; !rc && s < STEPS; s++) rc = floe_world_step(w);
    CHECK(rc == 0, "split run: %s", rc ? floe_world_last_error(w) : "");
    double x[3 * NS * NS * NS], v[3 * NS * NS * NS];
    floe_world_parallel_gather(w, x, v, N);
    /* the cell: the same bits on every rank */
    double H[9], hmax[9], hmin[9];
    floe_world_cell(w, NULL, H);
    MPI_Allreduce(H, hmax, 9, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(H, hmin, 9, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    CHECK(memcmp(hmax, hmin, sizeof hmax) == 0, "the cell differs between the ranks (H_zz %.17g .. %.17g)", hmin[8], hmax[8]);
    floe_energy e;
    floe_world_parallel_energy(w, &e);
    /* what reads this rank's contacts alone refuses */
    double sig[9], D[81];
    floe_rve_measures m;
    CHECK(floe_world_cell_stress(w, sig, NULL) == FLOE_ENOTSUP, "floe_world_cell_stress on a split world: not refused");
    CHECK(floe_world_cell_measures(w, &m) == FLOE_ENOTSUP, "floe_world_cell_measures on a split world: not refused");
    CHECK(floe_world_tangent_contact(w, 0, D) == FLOE_ENOTSUP, "floe_world_tangent_contact on a split world: not refused");
    CHECK(floe_world_refresh_forces(w) == FLOE_ENOTSUP, "floe_world_refresh_forces on a split world: not refused");
    int own, gh, any_ghosts = 0;
    floe_world_parallel_counts(w, &own, &gh);
    const int has_ghosts = gh > 0;
    MPI_Allreduce(&has_ghosts, &any_ghosts, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    if (rank_ == 0) {
        double dx = 0, dv = 0, vmax = 0, dh = 0;
        for (int k = 0; k < 3 * N; k++) {
            dx = fmax(dx, fabs(x[k] - x0[k]));
            dv = fmax(dv, fabs(v[k] - v0[k]));
            vmax = fmax(vmax, fabs(v0[k]));
        }
        for (int k = 0; k < 9; k++) dh = fmax(dh, fabs(H[k] - H0[k]));
        const double scale = fmax(fabs(e0.kinetic_trans) + fabs(e0.kinetic_rot) + fabs(e0.elastic), fabs(e0.dissipated));
        const double de = fmax(fmax(fabs(e.kinetic_trans - e0.kinetic_trans), fabs(e.dissipated - e0.dissipated)),
                               fmax(fabs(e.work_boundary - e0.work_boundary), fabs(e.elastic - e0.elastic)));
        printf("  %d ranks: positions %.2e of the cell, velocities %.2e of the largest, H %.2e of the cell, ledger %.2e "
               "of its scale; H_zz %.6g of %.6g, the cell's work %.3g J (serial %.3g J)\n",
               size_, dx / LC, dv / vmax, dh / LC, de / scale, H[8], LC, e.work_boundary, e0.work_boundary);
        CHECK(dx <= 1e-10 * LC, "positions differ from the unsplit run by %.3g of the cell", dx / LC);
        CHECK(dv <= 1e-8 * vmax, "velocities differ by %.3g of the largest speed", dv / vmax);
        CHECK(dh <= 1e-12 * LC, "the cell differs from the unsplit run's by %.3g of its size", dh / LC);
        CHECK(H[8] != LC && H0[8] != LC, "the servo moved the cell (H_zz %.17g)", H[8]);
        CHECK(de <= 1e-9 * scale && e0.work_boundary != 0, "ledger differs by %.3g of its scale (cell's work %.3g J)",
              de / scale, e0.work_boundary);
    }
    if (size_ > 1) CHECK(any_ghosts, "some rank holds ghosts");
    free(x0); free(v0);
    floe_world_destroy(w);
    const int fails = mpi_test_failed("test_mpi_cell");
    MPI_Finalize();
    return fails ? 1 : 0;
}
