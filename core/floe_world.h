/* floe_world.h - the simulation: particles (structure of arrays), materials, contact laws
 * per material pair, walls, body forces, state objects, neighbour search, integrator,
 * observers. The world owns everything added to it; floe_world_destroy frees it all. */
#ifndef FLOE_WORLD_H
#define FLOE_WORLD_H

#include "floe_base.h"
#include "floe_geometry.h"
#include "floe_contact.h"

typedef struct floe_world floe_world;
typedef struct floe_observer floe_observer;

typedef enum floe_motion {
    FLOE_FREE = 0,        /* integrated from forces */
    FLOE_FIXED = 1,       /* never moves */
    FLOE_KINEMATIC = 2    /* prescribed velocity / angular velocity */
} floe_motion;

/* Prescribed motion of a kinematic particle: fills v and w at time t. */
typedef void (*floe_motion_fn)(double t, double v[3], double w[3], void *user);
/* Extra body force on particle i (added to f, torque). */
typedef void (*floe_body_force_fn)(const floe_world *w, int i, double t, double f[3],
                                   double torque[3], void *user);

typedef struct floe_world_def {
    int dim;                  /* 2 or 3 */
    double dt;                /* s; 0 = automatic: safety * critical */
    double dt_safety;         /* fraction of the critical step used when dt = 0 (0.2) */
    int allow_unstable_dt;    /* 1: accept dt above the critical estimate */
    double gravity[3];        /* m/s^2 */
    double skin;              /* Verlet skin, m; 0 = 0.1 x smallest bounding radius */
    int leaf_size;            /* k-d tree bucket size (16) */
    int mass_2d_area;         /* 2D only: 1 = masses from area x density (per metre
                                 thickness); 0 (default) = 3D shapes moving in the plane */
} floe_world_def;

floe_world_def floe_default_world_def(void);

/* Create an empty world; NULL on invalid def (message to *err if non-NULL). */
floe_world *floe_world_create(const floe_world_def *def, char *err, size_t errlen);
void floe_world_destroy(floe_world *w);
const char *floe_world_last_error(const floe_world *w);

/* Materials: returns index >= 0 or -error. */
int floe_world_add_material(floe_world *w, const floe_material *m);
/* Contact law for the pair of materials (a, b), symmetric. The world takes ownership. */
int floe_world_set_law(floe_world *w, int mat_a, int mat_b, floe_contact_law *law);
/* Geometry shared by particles; the world takes ownership. Returns index or -error. */
int floe_world_add_geometry(floe_world *w, floe_geometry *g);

typedef struct floe_particle_def {
    int geometry;             /* index from floe_world_add_geometry */
    int material;
    double x[3], v[3], w[3];  /* centre of mass, velocity, angular velocity (world frame) */
    double q[4];              /* orientation body -> world (unit) */
    floe_motion motion;
    int group;                /* user tag written as "body" in outputs */
    double mass;              /* 0 = from geometry and density */
} floe_particle_def;

floe_particle_def floe_default_particle_def(void);
/* Add a particle; returns its index >= 0, or -error (message in last_error). */
int floe_world_add_particle(floe_world *w, const floe_particle_def *d);
/* Infinite wall: plane through point p with outward normal n (pointing into the domain). */
int floe_world_add_wall(floe_world *w, const double p[3], const double n[3], int material,
                        floe_motion motion);
int floe_world_set_motion(floe_world *w, int particle, floe_motion_fn fn, void *user);
int floe_world_set_body_force(floe_world *w, floe_body_force_fn fn, void *user);

/* State objects evolved by RK2 (ParticLS eq 21), see floe_state.h. World takes ownership. */
typedef struct floe_state floe_state;
int floe_world_add_state(floe_world *w, floe_state *s);
/* Observers (floe_observer.h). World takes ownership. */
int floe_world_add_observer(floe_world *w, floe_observer *o);

/* Prepare: masses, neighbour structures, time step (dt = 0 -> automatic). Called by
 * step/run if needed. Fails on a pair of materials with no law, on no detector for a
 * geometry pair in the scene, or dt above critical unless allowed. */
int floe_world_prepare(floe_world *w);
double floe_world_critical_dt(floe_world *w);   /* estimate, s (after prepare) */
double floe_world_dt(const floe_world *w);
double floe_world_time(const floe_world *w);
long floe_world_step_count(const floe_world *w);
int floe_world_particle_count(const floe_world *w);

/* Advance one step (velocity Verlet + RK2 states + observers). */
int floe_world_step(floe_world *w);
/* Progress callback: return non-zero to stop. */
typedef int (*floe_progress_fn)(const floe_world *w, long step, long nsteps, void *user);
/* Run until time t_end. Observers are flushed (end) also when the run fails. */
int floe_world_run(floe_world *w, double t_end, floe_progress_fn progress, void *user);
/* Finish: call end() of every observer (idempotent). */
int floe_world_finish(floe_world *w);

/* State of one particle (copies, world frame). */
typedef struct floe_particle_state {
    double x[3], v[3], q[4], w[3], f[3], torque[3];
    double mass, radius;     /* radius: bounding radius */
    int material, group;
    floe_motion motion;
} floe_particle_state;
int floe_world_get_particle(const floe_world *w, int i, floe_particle_state *out);

/* Keep a record of every contact of the last step (point, normal, force), as stress
 * observers need; switched on automatically when such an observer is added. */
int floe_world_record_contacts(floe_world *w, int on);
/* Number of contacts (penetrating pairs) at the last force evaluation. */
int floe_world_contact_count(const floe_world *w);

/* Peridynamic body (peridynamics/floe_pd.h, its material set): its points become particles
 * of the world (spheres of the contact radius R = (3V/4 pi)^(1/3) in 3D, (V/(pi h))^(1/2) in
 * 2D, mass rho V, contact material `material`), all moving at v0, and their bond forces are
 * added every step. Family members never get a contact force (they are bonded); other
 * points of the same body (fragments after fracture) and every other particle do. The
 * world takes ownership of body (also on failure). *first receives the index of the first
 * point (points keep the body's order). */
struct floe_pd_body;
int floe_world_add_pd_body(floe_world *w, struct floe_pd_body *body, int material, const double v0[3], int *first);
/* Number of PD bodies and body k (NULL if out of range). */
int floe_world_pd_body_count(const floe_world *w);
struct floe_pd_body *floe_world_pd_body(const floe_world *w, int k, int *first);

/* Contact detection statistics since prepare (pairs of convex shapes that go through the
 * polytope LP or ADMM; spheres and walls are analytic and not counted). */
typedef struct floe_detect_stats {
    long evaluations;        /* LP/ADMM pair evaluations */
    long lp, admm;           /* of which polytope LP, ADMM */
    double iterations_mean;  /* iterations per evaluation (LP: pivots + 1, both halves) */
    int iterations_median, iterations_p99;
    long nonconverged;       /* ADMM evaluations stopped at max_iterations (a warning: the
                                contact used the last iterate) */
    int first_bad_i, first_bad_j; /* the first such pair and its step */
    long first_bad_step;
} floe_detect_stats;
int floe_world_detect_stats(const floe_world *w, floe_detect_stats *out);

/* Energy bookkeeping (J) maintained every step. */
typedef struct floe_energy {
    double kinetic_trans, kinetic_rot, elastic;   /* current */
    double work_body;         /* work done by gravity and body-force callbacks */
    double work_boundary;     /* work done on the free particles by kinematic particles,
                                 walls and growing surfaces (state objects) */
    double dissipated;        /* damping and friction slip, accumulated */
    double initial;           /* kinetic + elastic at prepare */
} floe_energy;
floe_energy floe_world_energy(const floe_world *w);
/* Relative error of the balance initial + work = current + dissipated. */
double floe_world_energy_balance_error(const floe_world *w);

#endif
