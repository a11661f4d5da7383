/* floe_view.h - a read-only view of a world, for observers, examples, benches and users:
 * the particle arrays (zero-copy), the contacts of the last force evaluation with their
 * points, normals and forces, the geometries, peridynamic bodies, neighbour-list and
 * detection counters, and the definition in use. Nothing here changes the world (the
 * detection probes only count in the detection statistics); the setters are in
 * floe_world.h (floe_world_set_velocity, _set_pose, _set_particle_geometry, _set_dt).
 *
 * Pointers in a view stay valid until the next call that adds to the world (add_*, set_*),
 * prepares or steps it; take a new view after those (docs/api.md, "Reading a world").
 * Arrays are indexed by particle id (walls included: a wall is a particle with an unbounded
 * geometry, radius INFINITY). */
#ifndef FLOE_VIEW_H
#define FLOE_VIEW_H

#include "floe_world.h"
#include "floe_admm.h"

typedef struct floe_particles_view {
    int n;                          /* particles, walls included */
    int dim;                        /* 2 or 3 */
    const double *x, *v;            /* 3n: centre of mass (m), velocity (m/s) */
    const double *q;                /* 4n: orientation body -> world (w, x, y, z) */
    const double *w;                /* 3n: angular velocity, world frame (rad/s) */
    const double *L;                /* 3n: angular momentum, world frame (kg m^2/s; the
                                       integrated variable, set from w at prepare) */
    const double *f, *t;            /* 3n: force (N) and torque (N m) of the last evaluation */
    const double *mass;             /* n: kg (walls: their nominal mass) */
    const double *inertia;          /* 3n: principal moments, body frame (kg m^2) */
    const double *radius;           /* n: bounding radius (m), INFINITY for walls */
    const int *geometry;            /* n: index into floe_world_geometry_at */
    const int *material, *group;    /* n */
    const unsigned char *motion;    /* n: floe_motion */
    const int *pieces;              /* n: convex pieces of the geometry (compounds > 1, else 1) */
    const double *thickness;        /* n: 2D floes' thickness (m; 0: none), NULL when no particle
                                       of the world has one (floe_particle_def.thickness) */
} floe_particles_view;

/* Fills out; FLOE_EINVAL when w or out is NULL. */
int floe_world_particles(const floe_world *w, floe_particles_view *out);

/* One contact of the last force evaluation. force acts on i (-force on j); n points from i
 * to j; depth is the documented deepest-point depth (m); fn the normal force magnitude (N);
 * energy the stored elastic energy of the contact (J). */
typedef struct floe_contact_info {
    int i, j;
    double point[3], n[3], depth;
    double force[3];
    double fn;
    double energy;
    double branch[3];        /* from i's centre to j's (j's periodic image in a cell), m */
    double r_eff, m_eff;     /* the contact's effective radius (m) and mass (kg) */
} floe_contact_info;

/* The contacts of the last force evaluation: sets *out and returns their number (>= 0), or
 * -FLOE_EINVAL when they were not recorded at that evaluation (call
 * floe_world_record_contacts(w, 1) before stepping; observers that need contacts switch it
 * on when they are due). The count alone is floe_world_contact_count. */
int floe_world_contacts(const floe_world *w, const floe_contact_info **out);

/* The sums behind a collection's homogenised stress (observers/collection_tracker.c has the
 * formula, ParticLS eq 24 as the Love-Weber average): the members are the particles of group
 * g >= 0, or every free particle (group -1), walls never; the contacts those of the last force
 * evaluation. s[3 a + b] (a, b = 0..2) = sum of l_a f_b over the contacts that touch a member
 * (the branch vector between two members, the member's centre to the contact point
 * otherwise); s[9] the members, s[10] the member-member contacts, s[11] the others touching a
 * member; s[12..14] the members' bounding box low corner, s[15..17] its high corner (each
 * member inflated by its bounding radius; +-infinity when there is none). On a world split
 * over MPI ranks (floe_parallel.h) these are this rank's share: its own particles and the
 * contacts it evaluated (each pair is evaluated by one rank), so the sums over the ranks (the
 * minimum and maximum for the box) are the whole world's. FLOE_EINVAL when the contacts were
 * not recorded (floe_world_contacts), FLOE_ENOMEM. */
enum { FLOE_COLLECTION_SUMS = 18 };
int floe_world_collection_sums(const floe_world *w, int group, double s[FLOE_COLLECTION_SUMS]);

/* The world's geometries: how many, and geometry k (NULL out of range). A particle's is
 * floe_world_geometry_at(w, view.geometry[i]); floe_world_particle_geometry does both. */
int floe_world_geometry_count(const floe_world *w);
const floe_geometry *floe_world_geometry_at(const floe_world *w, int k);
const floe_geometry *floe_world_particle_geometry(const floe_world *w, int i);

/* The solid volume of the free particles (m^3): each one's shape volume (2D: its area times
 * 1 m, whatever its mass was taken from; a floe's thickness does not enter), for porosities
 * and void ratios (the periodic cell's measures, the `prepare` block). 0 for NULL. */
double floe_world_solid_volume(const floe_world *w);

/* The definition in use (after floe_world_create's defaults; read-only). */
const floe_world_def *floe_world_definition(const floe_world *w);
int floe_world_dim(const floe_world *w);

/* The peridynamic body of particle i (-1 for none) */
int floe_world_pd_body_of(const floe_world *w, int i);

/* 1 when the world is prepared (masses, time step, neighbour list in place), 0 when the next
 * step or run prepares it again (after an add_*, set_motion, set_dt ... or before the first). */
int floe_world_is_prepared(const floe_world *w);

/* Materials: how many, and material k (NULL out of range). The contact law of the material
 * pair (a, b) (symmetric; NULL when none was set or an index is out of range). */
int floe_world_material_count(const floe_world *w);
const floe_material *floe_world_material_at(const floe_world *w, int k);
const floe_contact_law *floe_world_law(const floe_world *w, int a, int b);

/* The ADMM options of convex-pair detection in use (floe_admm.h; the scene's
 * contact_detection block). FLOE_EINVAL when w or out is NULL. */
int floe_world_admm_options(const floe_world *w, floe_admm_options *out);

/* The bounds of the adaptive step in use (def.dt_min and dt_max, or their defaults:
 * dt_max = the critical estimate, dt_min = 1e-3 dt_max), s, as the last prepare set them
 * (0 before the first, and without adaptive steps). FLOE_EINVAL when w is NULL. */
int floe_world_adaptive_bounds(const floe_world *w, double *dt_min, double *dt_max);

/* Contact detection of the pair (i, j) at the particles' present poses, as a step does it
 * (piece pair sub = FLOE_SUB(a, b) of compound bodies, floe_detect.h, 0 otherwise; no warm
 * start): fills *c (floe_contact.h) and returns 1 in contact, 0 apart, or -error
 * (-FLOE_EINVAL for an index out of range). A diagnostic: nothing changes but the detection
 * statistics (floe_world_detect_stats). floe_world_probe_overlap does the same with the
 * overlap-area/volume detector of the overlap laws. */
int floe_world_probe_contact(floe_world *w, int i, int j, int sub, floe_contact *c);
int floe_world_probe_overlap(floe_world *w, int i, int j, int sub, floe_contact *c);

/* Memory held by the world's main arrays, in bytes (allocated capacity, not only what is in
 * use): the particle store, the neighbour list with its per-pair history and warm starts,
 * the contact records; and the capacities behind them. */
typedef struct floe_memory_stats {
    size_t particles, neighbor_list, contacts;   /* bytes */
    int particle_capacity, pair_capacity, contact_capacity;
} floe_memory_stats;
int floe_world_memory(const floe_world *w, floe_memory_stats *out);

/* The candidate pairs of the neighbour list (i < j, walls included, except that a pair of a bounded particle and a
 * wall has the bounded particle as i, so i > j where the wall's index is lower; pairs excluded by bonds,
 * PD families and beam bonds, are never listed): sets *pi and *pj to arrays of the returned
 * count (either may be NULL). Valid until the next step or prepare. -FLOE_EINVAL for w NULL.
 * Their number and the rebuilds: floe_world_neighbor_stats below. */
int floe_world_neighbor_pairs(const floe_world *w, const int **pi, const int **pj);

/* Neighbour-list counters: candidate pairs now and rebuilds so far. */
typedef struct floe_neighbor_stats {
    int pairs;
    long rebuilds;
    double skin;                    /* m */
} floe_neighbor_stats;
int floe_world_neighbor_stats(const floe_world *w, floe_neighbor_stats *out);

/* observers (wt-obs) */
/* The geometry kind of particle i (floe_geometry_kind; -1 out of range). */
int floe_world_particle_kind(const floe_world *w, int i);
/* Sets the world's last error (floe_world_last_error) to the formatted message and returns
 * code: how an observer (or other code outside the world) reports a failure,
 * `return floe_world_report_error(w, FLOE_EIO, "...: %s", strerror(errno));`. The one
 * call of this header that writes to the world: its error message only. */
int floe_world_report_error(floe_world *w, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#endif
