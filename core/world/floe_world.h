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
    /* time integration (docs/integrators.md) */
    int integrator;           /* floe_integrator (FLOE_VELOCITY_VERLET) */
    int adaptive;             /* 1: adaptive step between dt_min and dt_max (003 §4.3), driven
                                 by the two tolerances below (velocity Verlet or RK2) */
    double dt_min, dt_max;    /* s; 0 = automatic: dt_max = the critical estimate, dt_min =
                                 1e-3 dt_max; dt (or safety x critical) is the first step */
    double adapt_velocity_tol; /* a step is accepted when max_i |v_i' - v_i| dt / R_i <= this
                                  (the velocity change over the step relative to the size, 1e-3) */
    double adapt_depth_tol;   /* ... and the overlap of every contact changed by at most this
                                 fraction of the smaller radius (1e-3) */
    int pd_dem;               /* floe_pd_dem_scheme (FLOE_PD_DEM_MONOLITHIC) */
    int pd_substeps;          /* staggered: PD sub-steps per step (dt_PD = dt / m), >= 1;
                                 0 = automatic (the integer ratio of the critical steps) */
    int pd_every;             /* staggered: PD updated every k-th step (dt_PD = k dt), >= 1 */
    /* energy watchdog (floe_world_set_energy_check below) */
    int energy_check;         /* floe_energy_check_mode (FLOE_CHECK_STOP) */
    double energy_check_tol;  /* fraction of the energy scale that may be created (0 = 0.05) */
    /* accuracy target (issue 10 C): relative error of the coefficient of restitution of a
     * collision; > 0 caps the automatic step so that the error model of the contact laws
     * (floe_dt_estimates.predicted_error) stays below it; 0 = off */
    double accuracy;
} floe_world_def;

/* What the energy watchdog does when energy is created beyond the tolerance: a contact or
 * a PD body whose dissipation since it began is negative by more than tol x the energy
 * scale, the ledger's total dissipation below -tol x scale, or the balance error (current
 * + dissipated - initial - work) above +tol x scale, checked after every step; the scale is
 * the largest kinetic + elastic + |work_body| + |work_boundary| seen so far.
 * STOP: floe_world_step fails with FLOE_EUNSTABLE and a message naming the step, the pair
 * or PD body and the likely cause (floe_world_run flushes the observers first); WARN: the
 * message goes to stderr once and the run goes on; OFF: nothing is checked. */
typedef enum floe_energy_check_mode {
    FLOE_CHECK_STOP = 0,
    FLOE_CHECK_WARN = 1,
    FLOE_CHECK_OFF = 2
} floe_energy_check_mode;
/* "stop", "warn", "off" (NULL out of range) */
const char *floe_energy_check_name(int mode);

/* Time integrators for the particles (docs/integrators.md). All are explicit and second
 * order; state objects always use RK2. */
typedef enum floe_integrator {
    FLOE_VELOCITY_VERLET = 0, /* kick-drift-kick, ParticLS eq 22 (symplectic) */
    FLOE_LEAPFROG = 1,        /* 000 eq 44: velocities live at half steps t - dt/2 */
    FLOE_RK2 = 2              /* explicit midpoint, ParticLS eq 21 applied to the particles:
                                 two force evaluations per step, not symplectic */
} floe_integrator;
/* "velocity_verlet", "leapfrog", "rk2" (NULL out of range) */
const char *floe_integrator_name(int integrator);

/* Coupling of PD bond forces with the contact and body forces (000 §3.2-3.3). */
typedef enum floe_pd_dem_scheme {
    FLOE_PD_DEM_MONOLITHIC = 0, /* all forces every step */
    FLOE_PD_DEM_STAGGERED = 1   /* the two force groups integrated with their own steps (multiple
                                   time stepping, r-RESPA form): pd_substeps / pd_every */
} floe_pd_dem_scheme;

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
    double thickness;         /* 2D floes (sea ice, docs/sea-ice.md): thickness h, m; the mass
                                 from density is then density x area x h and the inertia
                                 density x h x the polar moment of the area (kg, kg m^2: forces
                                 in N); laws and forcing that read thickness use it. 0 = none
                                 (2D masses per metre of thickness, read as h = 1 m) */
} floe_particle_def;

floe_particle_def floe_default_particle_def(void);
/* Add a particle; returns its index >= 0, or -error (message in last_error).
 * A world split over MPI ranks (floe_world_parallel_init) is prepared once, before the split:
 * this call and the others that would prepare it again (add_wall, set_particle_geometry,
 * set_motion, set_body_force(_threaded), set_dt, set_cell, the beam bonds, PD bodies and regions)
 * return FLOE_ENOTSUP on it (-FLOE_ENOTSUP where an index is returned), changing nothing. */
int floe_world_add_particle(floe_world *w, const floe_particle_def *d);
/* Infinite wall: plane through point p with outward normal n (pointing into the domain). */
int floe_world_add_wall(floe_world *w, const double p[3], const double n[3], int material,
                        floe_motion motion);
/* A prescribed motion for a particle (it becomes kinematic). Set before a world is split
 * over MPI ranks (floe_world_parallel_init): refused after (FLOE_ENOTSUP). */
int floe_world_set_motion(floe_world *w, int particle, floe_motion_fn fn, void *user);
/* The body force, called once per free particle and evaluation, on one thread, in index
 * order. The _threaded form declares fn safe to call from several threads at once: with
 * threads on (from the loop grain's 2,048 particles) the world calls it from its threads, a
 * block of 512 particles each; its work is summed per block, on any thread count
 * (docs/api.md). */
int floe_world_set_body_force(floe_world *w, floe_body_force_fn fn, void *user);
int floe_world_set_body_force_threaded(floe_world *w, floe_body_force_fn fn, void *user);

/* State objects evolved by RK2 (ParticLS eq 21), see floe_state.h. World takes ownership. */
typedef struct floe_state floe_state;
int floe_world_add_state(floe_world *w, floe_state *s);
/* Observers (floe_observer_base.h, built-ins in floe_observer.h). World takes ownership. */
int floe_world_add_observer(floe_world *w, floe_observer *o);

/* Prepare: masses, neighbour structures, time step (dt = 0 -> automatic). Called by
 * step/run if needed. Fails on a pair of materials with no law, on no detector for a
 * geometry pair in the scene, or dt above critical unless allowed. */
int floe_world_prepare(floe_world *w);
double floe_world_critical_dt(floe_world *w);   /* estimate, s (after prepare) */

/* Critical time-step estimates (docs/models.md, "Critical time step"). Each kind is the
 * smallest over the particles it applies to, with the particle that attains it; the kinds
 * marked `limits` are stability limits of the explicit integrators and `critical` is their
 * minimum (the step refused above, and scaled by dt_safety for the automatic step); the
 * others are reported for comparison with the literature. INFINITY: not applicable. */
typedef enum floe_dt_kind {
    FLOE_DT_CONTACT_PACKING = 0, /* limits: a particle caged by a close packing of contacts
                                    (2 % overlap): (2/w)(sqrt(1+z^2)-z), w^2 = C k/m */
    FLOE_DT_CONTACT_IMPACT,      /* limits: one contact at the overlap of an impact at the
                                    expected relative speed */
    FLOE_DT_MOTION,              /* limits: R / (2 v_expected), no move over half a radius */
    FLOE_DT_PD_NODAL,            /* limits: sqrt(2 rho / sum_j V_j c/|xi|) per PD point */
    FLOE_DT_PD_CFL,              /* 000 eqs 41-42: dx / sqrt(K/rho) (LPS: P-wave speed) */
    FLOE_DT_DEM_SQRT_MK,         /* 000 eq 43: sqrt(m_i / k_i), k_i the sum of the particle's
                                    contact stiffnesses (004 eq 28 is twice this) */
    FLOE_DT_RAYLEIGH,            /* Hertz-Mindlin materials: pi R sqrt(rho/G)/(0.1631 nu + 0.8766) */
    FLOE_DT_HERTZ,               /* Hertz contact duration 2.87 (m*^2/(R* E*^2 v))^(1/5) at the
                                    expected speed */
    FLOE_DT_BEAM,                /* limits: beam bonds, 2/sqrt(lambda_max) of the bonded
                                    particles' stiffness (block Gershgorin, contact/bonds/beam_bond.c) */
    FLOE_DT_PROVIDER,            /* limits: the smallest critical_dt of the user force providers
                                    (floe_provider.h; the particle is -1) */
    FLOE_DT_NKINDS
} floe_dt_kind;
typedef struct floe_dt_estimates {
    double critical;              /* min over the kinds that limit, s */
    int limiting;                 /* the floe_dt_kind that gives it (-1: none) */
    int limiting_particle;        /* the particle (-1: none) */
    double dt[FLOE_DT_NKINDS];    /* each estimate, s */
    int particle[FLOE_DT_NKINDS]; /* the particle that attains it (-1: none) */
    int limits[FLOE_DT_NKINDS];   /* 1: a stability limit (enters critical) */
    double critical_contact;      /* contact + motion kinds: the DEM step of a staggered scheme */
    double critical_pd;           /* PD nodal: the PD step of a staggered scheme */
    double v_expected;            /* relative speed used by the impact, motion and Hertz kinds, m/s */
    /* restitution error model (docs/models.md, "Accuracy target"): the relative error of e
     * of a collision is at most A(e) / N^2 for the linear laws (N = damped collision time /
     * dt) and A(e) / N for Hertz-Mindlin (N = Hertz time / dt); over every law and particle
     * the worst is predicted_error(dt) = max(err1 dt, err2 dt^2) */
    double err1, err2;            /* 1/s and 1/s^2 (0: no damped law) */
    double accuracy_dt;           /* the largest step that meets def.accuracy (INFINITY: none) */
    double predicted_error;       /* at the chosen step */
} floe_dt_estimates;
/* Fill *out (prepares the world if needed). */
int floe_world_dt_estimates(floe_world *w, floe_dt_estimates *out);
/* "contact_packing", "contact_impact", "motion", "pd_nodal", "pd_cfl", "dem_sqrt_m_k",
 * "rayleigh", "hertz" (NULL out of range) */
const char *floe_dt_kind_name(int kind);
/* Critical estimate of particle i (the smallest of its limiting kinds; INFINITY for fixed,
 * kinematic and unconstrained particles), after prepare; -1 when i is out of range. */
double floe_world_particle_critical_dt(const floe_world *w, int i);

/* Step statistics since prepare: accepted and rejected (redone with a smaller step)
 * steps of the adaptive scheme, the smallest and largest step taken, the PD force
 * evaluations and the PD sub-steps of a staggered scheme. */
typedef struct floe_step_stats {
    long accepted, rejected;
    double dt_min_used, dt_max_used;   /* s (0 before the first step) */
    long force_evaluations;            /* contact + body force evaluations */
    long pd_evaluations;               /* PD bond force evaluations */
    int pd_substeps, pd_every;         /* of the staggered scheme (1, 1 otherwise) */
} floe_step_stats;
int floe_world_step_stats(const floe_world *w, floe_step_stats *out);
double floe_world_dt(const floe_world *w);
double floe_world_time(const floe_world *w);
long floe_world_step_count(const floe_world *w);
int floe_world_particle_count(const floe_world *w);

/* Advance one step (the integrator of the definition, RK2 for state objects, observers).
 * With adaptive stepping, one accepted step (rejected trials are redone inside). */
int floe_world_step(floe_world *w);
/* Progress callback: return non-zero to stop. */
typedef int (*floe_progress_fn)(const floe_world *w, long step, long nsteps, void *user);
/* Run until time t_end. Observers are flushed (end) also when the run fails. A fixed step
 * ends exactly at t_end when the integrator can shorten its last step (velocity Verlet, RK2:
 * the last step is t_end minus the last whole step's end, then the step goes back to dt);
 * leapfrog and the staggered scheme with a PD cycle (every > 1) end on the last whole step
 * not past t_end (up to one step before it). Adaptive steps end at t_end. */
int floe_world_run(floe_world *w, double t_end, floe_progress_fn progress, void *user);
/* Finish: call end() of every observer (idempotent). */
int floe_world_finish(floe_world *w);

/* State of one particle (copies, world frame). */
typedef struct floe_particle_state {
    double x[3], v[3], q[4], w[3], f[3], torque[3];
    double mass, radius;     /* radius: bounding radius */
    int material, group;
    floe_motion motion;
    double thickness;        /* 2D floes: h, m; 0 for a particle without one */
} floe_particle_state;
int floe_world_get_particle(const floe_world *w, int i, floe_particle_state *out);

/* Set the velocity v (m/s) and/or the angular velocity omega (rad/s, world frame) of
 * particle i; either may be NULL (kept). For a free particle, or a kinematic one without a
 * motion callback (whose prescribed velocity this is; with a callback the callback's
 * velocity wins at the next step). Before the world is prepared this is the initial
 * condition. After, it is an impulse at the present time: the angular momentum follows
 * omega, the time step is kept, and the change of kinetic energy is booked as external work
 * (energy.work_body) so the energy balance still closes. FLOE_EINVAL (message in
 * last_error) for an index out of range, a fixed particle, a non-finite value, or in 2D a
 * velocity off the plane (v_z, omega_x, omega_y not 0). */
int floe_world_set_velocity(floe_world *w, int i, const double v[3], const double omega[3]);

/* Move particle i to the pose (x: centre of mass, m; q: orientation body -> world, made a
 * unit quaternion; either may be NULL: kept), e.g. to place bodies or probe detection at
 * nearby poses (floe_world_probe_contact). Its velocities are kept; forces are those of the
 * last evaluation until the next step; the neighbour list is rebuilt when the move needs
 * it. After prepare the energy ledger does not book the move. FLOE_EINVAL (message in
 * last_error) for an index out of range, a wall, a non-finite value, a zero quaternion, or
 * in 2D a pose off the plane (x_z, or a rotation about another axis than z). */
int floe_world_set_pose(floe_world *w, int i, const double x[3], const double q[4]);

/* Give particle i another geometry (an index from floe_world_add_geometry, bounded: not a
 * wall's plane), e.g. a contact sphere of another radius for the points of a PD body. The
 * bounding radius follows; the mass is kept (given, or computed at the last prepare) and
 * the inertia follows the new shape at the next prepare, which the next step does.
 * FLOE_EINVAL (message in last_error) for an index out of range, a wall, or an unbounded
 * geometry. */
int floe_world_set_particle_geometry(floe_world *w, int i, int geometry);

/* Set the time step of the definition (dt > 0 fixed, 0 = automatic: dt_safety x critical)
 * and whether a step above the critical estimate is allowed (allow_unstable_dt); the world
 * is prepared again before its next step (the step chosen and checked then). FLOE_EINVAL
 * for dt negative or not finite; FLOE_ENOTSUP on a world split over MPI ranks. */
int floe_world_set_dt(floe_world *w, double dt, int allow_unstable);

/* The orientation of round particles (a sphere in 3D, a disc in 2D: geometry kind
 * FLOE_GEOM_SPHERE) changes nothing in their motion; integrating it costs about a sixth of
 * a sphere's step. FLOE_ORIENT_AUTO (the default): it is integrated only when something
 * reads it: an observer that reads orientations (floe_observer_class.reads_orientation, and
 * every observer of class version < 3), beam bonds (their bending reads it), an output of
 * an MPI run that reads them; otherwise a free round particle keeps its orientation (its
 * angular velocity and momentum are integrated as always). FLOE_ORIENT_ALWAYS: always (for
 * a caller that reads floe_particles_view.q of spheres itself). Other particles' orientations
 * are always integrated. Takes effect at once (also on a prepared world). */
typedef enum floe_orientation_mode { FLOE_ORIENT_AUTO = 0, FLOE_ORIENT_ALWAYS = 1 } floe_orientation_mode;
int floe_world_set_orientation(floe_world *w, int mode);

/* Keep a record of every contact of the last step (point, normal, force), as stress
 * observers need; switched on automatically when such an observer is added. */
int floe_world_record_contacts(floe_world *w, int on);
/* Number of contacts (penetrating pairs) at the last force evaluation. */
int floe_world_contact_count(const floe_world *w);

/* Peridynamic body (peridynamics/floe_pd.h, its material set): its points become particles
 * of the world (spheres of the contact radius R = (3V/4 pi)^(1/3) in 3D, (V/(pi h))^(1/2) in
 * 2D, mass rho V, contact material `material`), all moving at v0, and their bond forces are
 * added every step. Family members never get a contact force (they are bonded); other
 * points of the same body (fragments after fracture, the faces of a pre-crack: except pairs
 * whose contact spheres overlap in the reference configuration) and every other particle do. The
 * world takes ownership of body (also on failure). *first receives the index of the first
 * point (points keep the body's order). */
struct floe_pd_body;
int floe_world_add_pd_body(floe_world *w, struct floe_pd_body *body, int material, const double v0[3], int *first);
/* Number of PD bodies and body k (NULL if out of range). */
int floe_world_pd_body_count(const floe_world *w);
struct floe_pd_body *floe_world_pd_body(const floe_world *w, int k, int *first);
/* The index in PD body k of particle i (its point), or -1 when i is not one of its points;
 * and the body's point positions, contiguous (3 n; under MPI, floe_parallel.h, the points on
 * this rank gathered at the last force evaluation: an absent point's entry is stale). Both
 * work split or not (a split world's particle indices are not the body's order). */
int floe_world_pd_point(const floe_world *w, int k, int i);
const double *floe_world_pd_positions(const floe_world *w, int k);

/* Boundary regions of a PD body (issue #4; ParticLS §5.4 eq 37). The points of PD body
 * `body` whose REFERENCE position X lies in the region (sdf(X, sdf_user) <= 0, or, when sdf
 * is NULL, lo <= X <= hi componentwise) become:
 *   FLOE_PD_BC_FIXED         fixed particles of the world (never move);
 *   FLOE_PD_BC_VELOCITY      kinematic particles moving at value * ramp(t) (m/s);
 *   FLOE_PD_BC_DISPLACEMENT  kinematic particles displaced by value * ramp(t) (m) from where
 *                            they are at t = 0 (velocity value * ramp'(t); needs a ramp);
 *   FLOE_PD_BC_BODY_FORCE    free particles that get the external force b V every step, with
 *                            the force density b = value * ramp(t) (N/m^3), or b = fn(t, X)
 *                            when force_fn is set; its work goes to energy.work_body (the
 *                            trapezoid rule, as for the body-force callback). Fixed or
 *                            kinematic points of the region get none (as for gravity).
 * ramp(t) = 1 (FLOE_PD_RAMP_NONE), min(t/T, 1) (LINEAR), 1 - exp(-t/T) (EXP; ParticLS eq 37
 * is value = (+-3, 0, 0) with EXP, T = 0.1 s), with T = ramp_time and t the world time.
 * A point may belong to one fixed/velocity/displacement region only; body-force regions
 * add up. Returns the number of points selected (> 0), or -error: FLOE_EINVAL (message in
 * last_error) for bad fields, a body index out of range, a region that selects no point or
 * a point already held by another fixed/velocity/displacement region. */
enum { FLOE_PD_BC_FIXED = 1, FLOE_PD_BC_VELOCITY = 2, FLOE_PD_BC_DISPLACEMENT = 3, FLOE_PD_BC_BODY_FORCE = 4 };
enum { FLOE_PD_RAMP_NONE = 0, FLOE_PD_RAMP_LINEAR = 1, FLOE_PD_RAMP_EXP = 2 };
typedef void (*floe_pd_force_fn)(double t, const double X[3], double b[3], void *user);
typedef struct floe_pd_bc {
    int kind;                 /* FLOE_PD_BC_* */
    double lo[3], hi[3];      /* box in reference coordinates (used when sdf is NULL), m */
    double (*sdf)(const double X[3], void *user); /* region: sdf <= 0 inside (read once) */
    void *sdf_user;
    double value[3];          /* velocity (m/s), displacement (m) or force density (N/m^3) */
    int ramp;                 /* FLOE_PD_RAMP_* */
    double ramp_time;         /* T > 0 for LINEAR and EXP, s */
    floe_pd_force_fn force_fn; /* BODY_FORCE: b = force_fn(t, X, b, user) instead of value */
    void *force_user;
} floe_pd_bc;
floe_pd_bc floe_default_pd_bc(void);   /* kind 0 (set it), everything else 0 / NULL */
int floe_world_pd_region(floe_world *w, int body, const floe_pd_bc *bc);
/* Number of PD boundary regions, and the number of points of region r (-1 out of range). */
int floe_world_pd_region_count(const floe_world *w);
int floe_world_pd_region_points(const floe_world *w, int r);

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
    long lp_halves;          /* polytope LP solves (a pair needs one or two halves) */
    long lp_kept;            /* of which the previous step's basis was still optimal: no
                                pivot (the resting-contact path, docs/models.md) */
    long lp_cold;            /* of which started from the deepest vertex (no usable basis);
                                the three are this process's counts since the start (not
                                kept in checkpoints, not summed over MPI ranks) */
    long separated;          /* candidate pairs of convex shapes found apart before LP/ADMM
                                (bounding spheres overlap, shapes do not): by the support
                                test, or by the separation cache */
    long sep_cached;         /* of which by the separation cache: a gap found by the support
                                test or the LP that the bodies' motion since cannot have
                                closed (docs/models.md; this process's count, like lp_halves) */
    long manifold_cached;    /* polytope contact manifolds that tested only the corners their
                                corner cache kept (docs/models.md; this process's count) */
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

/* Threads (OpenMP; docs/parallel.md): the number of threads the world's loops use (0: the
 * OpenMP default, OMP_NUM_THREADS or every core; 1: serial). Results are the same to the last
 * bit for any number (contact laws, geometries and motion callbacks must then be safe to call
 * from several threads at once: the built-in ones are). Built without OpenMP
 * (FLOE_WITH_OPENMP=OFF) a request above 1 is FLOE_ENOTSUP. floe_world_threads: the number
 * in use. */
int floe_world_set_threads(floe_world *w, int nthreads);
int floe_world_threads(const floe_world *w);

/* Energy watchdog (floe_energy_check_mode above): set the mode and tolerance (tol 0 = the
 * default 0.05; FLOE_EINVAL for a mode out of range or tol not in [0, 1)), and its state. */
int floe_world_set_energy_check(floe_world *w, int mode, double tol);
typedef struct floe_energy_check_state {
    int mode;                 /* floe_energy_check_mode */
    double tolerance;         /* fraction of the scale */
    double scale;             /* the energy scale, J */
    double created;           /* largest fraction of the scale found created so far (>= 0) */
    long tripped_step;        /* the step at which the tolerance was first passed (-1: never) */
    const char *message;      /* the diagnosis at that step ("" when none) */
} floe_energy_check_state;
int floe_world_energy_check(const floe_world *w, floe_energy_check_state *out);

#endif
