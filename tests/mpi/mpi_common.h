/* mpi_common.h - what the MPI C tests (tests/mpi/test_mpi_*.c) share: the rank and the rank
 * count, MPI's start, the failed checks summed over the ranks, and the pieces of their scenes
 * (the glass material with its Hertz-Mindlin law, the six walls of a box). Include after
 * "../check.h". */
#ifndef MPI_COMMON_H
#define MPI_COMMON_H
#include "floe.h"
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
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

/* A world of def d: glass (Young's modulus 1e7), the six walls of the cube [0, side]^3 (the
 * particles 0 .. 5), then n^3 spheres of radius r at 0.0005 + (a + 1/2) sp along each axis,
 * each with velocity components in [-0.15, 0.15) m/s from one fixed sequence (the same
 * world on every rank and every call): the scene of test_mpi_bodyforce and test_mpi_provider */
static inline floe_world *mpi_test_sphere_box(floe_world_def d, int n, double r, double sp, double side)
{
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    const int g = floe_world_add_geometry(w, floe_sphere_create(r));
    mpi_test_box_walls(w, side, side, side, 0, 6);
    unsigned s = 99;
    for (int c = 0; c < n; c++)
        for (int b = 0; b < n; b++)
            for (int a = 0; a < n; a++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g;
                double j[3];
                for (int k = 0; k < 3; k++) { s = s * 1103515245u + 12345u; j[k] = (s >> 8) / 16777216.0 - 0.5; }
                floe_v3_set(p.x, 0.0005 + (a + 0.5) * sp, 0.0005 + (b + 0.5) * sp, 0.0005 + (c + 0.5) * sp);
                floe_v3_set(p.v, 0.3 * j[0], 0.3 * j[1], 0.3 * j[2]);
                floe_world_add_particle(w, &p);
            }
    return w;
}

/* w (not split) run for steps steps on this rank alone, then its particles' count in *n, their
 * positions and velocities in *x0, *v0 (3n each, allocated) and its energy in *e: FLOE_OK,
 * or the first error (the message in floe_world_last_error; nothing allocated) */
static inline int mpi_test_serial_run(floe_world *w, int steps, int *n, double **x0, double **v0, floe_energy *e)
{
    for (int s = 0; s < steps; s++) {
        const int rc = floe_world_step(w);
        if (rc) return rc;
    }
    *n = floe_world_particle_count(w);
    *x0 = calloc((size_t)*n * 3, sizeof **x0);
    *v0 = calloc((size_t)*n * 3, sizeof **v0);
    floe_world_parallel_gather(w, *x0, *v0, *n);
    *e = floe_world_energy(w);
    return FLOE_OK;
}

/* w prepared, split over the ranks and run for steps steps, then its n particles' positions and
 * velocities gathered into *xp, *vp (3n each, allocated; rank 0's hold the whole state) and
 * its energy summed over the ranks into *e: FLOE_OK, or the first error (the message in
 * floe_world_last_error; *xp, *vp allocated all the same) */
static inline int mpi_test_split_run(floe_world *w, int steps, int n, double **xp, double **vp, floe_energy *e)
{
    int rc = floe_world_prepare(w);
    if (!rc) rc = floe_world_parallel_init(w, NULL);
    for (int s = 0; !rc && s < steps; s++) rc = floe_world_step(w);
    *xp = calloc((size_t)n * 3, sizeof **xp);
    *vp = calloc((size_t)n * 3, sizeof **vp);
    if (!rc) {
        floe_world_parallel_gather(w, *xp, *vp, n);
        floe_world_parallel_energy(w, e);
    }
    return rc;
}

/* the largest differences of positions (dx) and velocities (dv) between two gathered states
 * over the doubles k0 .. k1-1, and the largest speed component of the reference (vmax) */
static inline void mpi_test_max_diffs(const double *x, const double *x0, const double *v, const double *v0, int k0,
                                      int k1, double *dx, double *dv, double *vmax)
{
    *dx = *dv = *vmax = 0;
    for (int k = k0; k < k1; k++) {
        *dx = fmax(*dx, fabs(x[k] - x0[k]));
        *dv = fmax(*dv, fabs(v[k] - v0[k]));
        *vmax = fmax(*vmax, fabs(v0[k]));
    }
}
#endif
