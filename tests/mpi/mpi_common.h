/* mpi_common.h - what the MPI C tests (tests/mpi/test_mpi_*.c) share: the rank and the rank
 * count, MPI's start, the failed checks summed over the ranks, and the pieces of their scenes
 * (the glass material with its Hertz-Mindlin law, the six walls of a box). Include after
 * "../check.h". */
#ifndef MPI_COMMON_H
#define MPI_COMMON_H
#include "floe.h"
#include <mpi.h>
#include <stdio.h>
#include <string.h>

static int rank_, size_;

/* MPI_Init, then rank_ and size_ */
static inline void mpi_test_init(int *argc, char ***argv)
{
    MPI_Init(argc, argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

/* the failed checks summed over the ranks, printed by rank 0 as "NAME (S ranks): N failed
 * checks over all ranks" */
static inline int mpi_test_failed(const char *name)
{
    int fails = check_fail_, all;
    MPI_Allreduce(&fails, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    if (rank_ == 0) printf("%s (%d ranks): %d failed checks over all ranks\n", name, size_, all);
    return all;
}

/* glass: density 2500, Young's modulus `young`, Poisson 0.3 */
static inline floe_material mpi_test_glass(double young)
{
    floe_material m;
    memset(&m, 0, sizeof m);
    strcpy(m.name, "glass");
    m.density = 2500; m.young = young; m.poisson = 0.3;
    return m;
}

/* material 0 of w: glass (mpi_test_glass), with the Hertz-Mindlin law (e = 0.5, mu = 0.3) */
static inline void mpi_test_add_glass(floe_world *w, double young)
{
    floe_material m = mpi_test_glass(young);
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.3));
}

/* walls k0..k1-1 of the box [0, lx] x [0, ly] x [0, lz], fixed, inward normals, in the order
 * x = 0, x = lx, y = 0, y = ly, z = 0, z = lz */
static inline void mpi_test_box_walls(floe_world *w, double lx, double ly, double lz, int k0, int k1)
{
    double pts[6][3] = {{0, 0, 0}, {lx, 0, 0}, {0, 0, 0}, {0, ly, 0}, {0, 0, 0}, {0, 0, lz}};
    double nrm[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int k = k0; k < k1; k++) floe_world_add_wall(w, pts[k], nrm[k], 0, FLOE_FIXED);
}
#endif
