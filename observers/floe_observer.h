/* floe_observer.h - observers (ParticLS §4.3): called every `period_steps` steps or every
 * `period_time` seconds of simulated time, and once at the start and at the end (also
 * when a run stops on an error, so that what was computed is written). */
#ifndef FLOE_OBSERVER_H
#define FLOE_OBSERVER_H

#include "floe_observer_base.h"
#include <stdio.h>

/* All writers take an output path; the directory must exist. Returns NULL and writes a
 * message to err on failure. */

/* CSV of chosen particles: t, id, x, y, z, vx, vy, vz, wx, wy, wz, q0..q3, fx, fy, fz. */
floe_observer *floe_particle_tracker_create(const char *path, const int *ids, int n,
                                            char *err, size_t errlen);
/* Homogenised Cauchy stress (ParticLS eq 24) of a group (-1 = all free particles):
 * CSV t, sxx, syy, szz, sxy, sxz, syz (Pa, tension positive), coordination number,
 * contacts, volume. volume <= 0: the axis-aligned bounding box of the collection. */
floe_observer *floe_collection_tracker_create(const char *path, int group, double volume,
                                              char *err, size_t errlen);
/* Energy CSV: t, kinetic_trans, kinetic_rot, elastic, work_body, work_boundary,
 * dissipated, balance_error. */
floe_observer *floe_energy_tracker_create(const char *path, char *err, size_t errlen);
/* VTK: one .vtu per frame (prefix_NNNNNN.vtu) and prefix.pvd listing them. Point data:
 * id, radius, velocity, angular_velocity, force, body, material. */
floe_observer *floe_vtk_writer_create(const char *dir, const char *prefix, char *err, size_t errlen);
/* The VTK writer of rank `rank` of `size` (size >= 1) in an MPI run (docs/parallel.md): it is
 * called with that rank's split world (floe_world_parallel_add_output, at the same steps on
 * every rank: its observe and end are collective) and writes the rank's piece of each frame,
 * prefix_NNNNNN_R.vtu, with the particles the rank owns (id: the global particle id; walls and
 * ghosts left out); rank 0 then writes prefix_NNNNNN.pvtu naming the size pieces and
 * prefix.pvd listing the .pvtu files. With an unsplit world and size 1 it writes the one
 * piece of every particle. floe_vtk_writer_set_ascii applies. */
floe_observer *floe_vtk_writer_create_piece(const char *dir, const char *prefix, int rank, int size, char *err,
                                            size_t errlen);
/* CSV snapshot of all particles per frame (one file, "t,id,..." rows). */
floe_observer *floe_csv_writer_create(const char *path, char *err, size_t errlen);
/* 2D outlines (observers/outline_writer.c): one .vtu per frame (prefix_NNNNNN.vtu, default
 * prefix "outlines") and prefix.pvd listing them, with one VTK_POLYGON cell per particle with
 * a bounded radius (one per piece of a compound), counter-clockwise in world coordinates;
 * cell data id, body, material, velocity, angular_velocity, area. segments (>= 3): the points
 * of a curved shape's outline (rays from its origin); ascii: 1 = ASCII, 0 = raw binary
 * appended data. dim must be 2: otherwise NULL and "outlines is a 2D output (dimension: 2);
 * use vtk in 3D" in err. */
floe_observer *floe_outline_writer_create(const char *dir, const char *prefix, int dim, int segments, int ascii,
                                          char *err, size_t errlen);
/* The floe size distribution (floe_sizes.c): one CSV row per floe (a connected set of free
 * particles joined by intact beam bonds) per observation; 2D only (NULL with a message). */
floe_observer *floe_sizes_create(const char *path, int dim, char *err, size_t errlen);
/* The area flux through the gate segment a -> b (gate_flux.c): per observation the net
 * crossings and floe area since the start (positive to the right of a -> b) and the rate;
 * 2D only (NULL with a message). */
floe_observer *floe_gate_flux_create(const char *path, int dim, const double a[2], const double b[2], char *err,
                                     size_t errlen);
/* The breaks of beam bonds (fracture_events.c): one CSV row per bond break, written at the
 * first observation after it (t, step, i, j, mode, midpoint, stress, strength). */
floe_observer *floe_fracture_events_create(const char *path, char *err, size_t errlen);
/* The contacts (contact_writer.c): every contact at each observation as a CSV row (t, i, j,
 * point, normal, fn, ft, force on i, depth, energy); and force chains, a VTK series of lines
 * between the centres of contacting bounded bodies with cell data fn, ft, force, depth
 * (DIR/PREFIX_NNNNNN.vtu, DIR/PREFIX.pvd). Both make the world record the contacts. */
floe_observer *floe_contact_csv_create(const char *path, char *err, size_t errlen);
floe_observer *floe_force_chains_create(const char *dir, const char *prefix, char *err, size_t errlen);
/* The ice load on fixed and kinematic bodies (coast_load.c): per observation and body the
 * contact force, the number of contacts, the length in contact (or `length` when > 0) and
 * the force per length; body (a particle id) and group (a body entry) choose them (-1: any).
 * 2D only (NULL with a message). */
floe_observer *floe_coast_load_create(const char *path, int dim, int body, int group, double length, char *err,
                                      size_t errlen);
/* Concentration, mean velocity and thickness of the ice per cell of an nx x ny grid over
 * [lo, hi], sampled at samples^2 points per cell (ice_grid.c): a VTK series DIR/PREFIX_*.vtu
 * and DIR/PREFIX.pvd; 2D only (NULL with a message). */
floe_observer *floe_ice_grid_create(const char *dir, const char *prefix, int dim, const double lo[2],
                                    const double hi[2], int nx, int ny, int samples, char *err, size_t errlen);

/* ---- additions: stress evaluation, accessors, VTK options ---- */

/* Result of one homogenised-stress evaluation (see observers/collection_tracker.c for the
 * formula and the sign convention: tension positive, compression negative). */
typedef struct floe_collection_stats {
    double time;          /* s */
    double sigma[6];      /* Pa: xx, yy, zz, xy, xz, yz (symmetric part) */
    double coordination;  /* 2 x contacts / particles */
    int particles;        /* members of the collection */
    int contacts;         /* contacts between two members */
    int wall_contacts;    /* contacts between a member and a non-member (wall, fixed, ...) */
    double volume;        /* m^3 (2D: bounding area x 1 m) */
} floe_collection_stats;

/* Evaluate the homogenised stress of a group of the world now (no observer needed).
 * group -1 = every free particle with a bounded radius; volume <= 0 = bounding box.
 * FLOE_EINVAL when the contacts were not recorded; FLOE_ENOTSUP on a world split over MPI
 * ranks (floe_world_collection_sums gives a rank's share). */
int floe_collection_stress(const floe_world *w, int group, double volume,
                           floe_collection_stats *out);
/* Last values computed by a collection tracker: sigma (xx, yy, zz, xy, xz, yz, Pa) and
 * coordination number (either pointer may be NULL). FLOE_EINVAL if o is not a collection
 * tracker or has not observed yet. */
int floe_collection_tracker_last(const floe_observer *o, double sigma[6], double *coord);

/* VTK writer output encoding: 0 (default) = raw binary appended data, 1 = ASCII (larger and
 * slower, human-readable). Returns FLOE_EINVAL if o is not a VTK writer. */
int floe_vtk_writer_set_ascii(floe_observer *o, int ascii);

/* Registers the built-in outputs (vtk, csv, energy, stress, tracker; the scene loader builds
 * them itself, the entries document them) and outlines (read by its schema); idempotent. */
int floe_register_builtin_outputs(char *err, size_t errlen);

#endif
