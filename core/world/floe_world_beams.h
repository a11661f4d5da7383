/* floe_world_beams.h - beam bonds of a world (ParticLS §5.5; 004 §2): the world API over
 * the bond kernels of contact/bonds/floe_beam.h. */
#ifndef FLOE_WORLD_BEAMS_H
#define FLOE_WORLD_BEAMS_H

#include "floe_beam.h"
#include "floe_world.h"

/* Bond every pair of particles (walls excluded, not both fixed/kinematic) whose centres are
 * within radius_factor (R_i + R_j) (R the bounding radii; 1.01 on a touching lattice gives
 * the nearest neighbours), or within par->max_distance when that is > 0. Pairs already
 * bonded are skipped. The bond frame is taken from the present positions and orientations.
 * Returns the number of new bonds (>= 0) or -error (FLOE_EINVAL with a message naming the
 * field, FLOE_ENOMEM). Call before the run; the world owns the bonds. */
int floe_world_add_beam_bonds(floe_world *w, double radius_factor, const floe_beam_params *par);
/* One bond between particles i and j; returns its index or -error. */
int floe_world_add_beam_bond(floe_world *w, int i, int j, const floe_beam_params *par);

/* Bonds and broken bonds so far. In a world split over MPI ranks (floe_parallel.h) these and
 * floe_world_beam_bond cover this rank's bonds only, with local indices;
 * floe_world_parallel_beam_counts sums over the ranks. */
int floe_world_beam_bond_count(const floe_world *w);
int floe_world_beam_broken_count(const floe_world *w);

/* Bond k (0 <= k < count); FLOE_EINVAL out of range. */
int floe_world_beam_bond(const floe_world *w, int k, floe_beam_bond_info *out);

/* The bonds as CSV (crack pattern): i, j, midpoint x y z, broken, t_broken, sigma, tau,
 * sigma_lim. FLOE_EIO with a message if the file cannot be written. */
int floe_world_write_beam_bonds_csv(floe_world *w, const char *path);

/* Critical time step of the world's bonds (s, INFINITY without bonds), as the time-step
 * estimate of floe_world_prepare computes it (floe_beam_set_critical_dt). */
double floe_world_beam_critical_dt(floe_world *w);

#endif
