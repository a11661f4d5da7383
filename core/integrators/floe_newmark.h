/* floe_newmark.h - Newmark-beta time integration of a bonded system (004 §3-4): explicit
 * (beta = 0, gamma = 1/2, central difference) and implicit average acceleration
 * (beta = 1/4, gamma = 1/2), for nodes (particles with mass and rotational inertia) joined
 * by beam bonds (contact/bonds/floe_beam.h, 004 eq 7), with supports (eq 3), loads and bond
 * breakage (eq 11).
 *
 * This is a self-contained solver over nodes + bonds + supports + loads (a "bonded
 * system"), not the world's step: the system is linear in the small displacements u of
 * the nodes (2D: u_x, u_y, theta_z per node; 3D: three translations and three rotations),
 * the bonds keep their reference frames (T of eq 4), and the internal forces are
 * incremental (eqs 19-20): f_int(n+1) = f_int(n) + K du, per bond in its local frame
 * (eq 10), which is where the stresses of eq 11 are read. Each step solves eq 26,
 *
 *     (K beta dt^2 + C gamma dt + M) a(n+1) = f_e(n+1) - f_int(n) - K a_n - C b_n,
 *     a_n = dt v_n + dt^2/2 (1 - 2 beta) a_n,   b_n = v_n + (1 - gamma) dt a_n,
 *
 * with the supported components eliminated (eq 27), then du = a_n + beta dt^2 a(n+1),
 * v(n+1) = b_n + gamma dt a(n+1) (eqs 24-25). Implicit: K, C, M are assembled as one sparse
 * symmetric matrix (upper triangle), factored by SuiteSparse CHOLMOD once, and refactored
 * only when the step changes (a cut, eqs 29-30); a broken bond leaves the factor by a rank
 * downdate (cholmod_updown: its term beta dt^2 T^T K_b T + gamma dt C_b, split into
 * sqrt(lambda) v by its eigenvectors), or by a refactorization with refactor_on_break (the
 * symbolic analysis is kept either way: a broken bond's entries stay in the pattern as
 * zeros). Explicit: with beta = 0 the matrix is
 * M + gamma dt C, block-diagonal per node (C of eq 8 is diagonal in each bond frame), so
 * each node solves its own small block.
 *
 * Damping C (004 eq 8): per bond, 2 xi sqrt(k_kk m_r) on each translational and
 * 2 xi sqrt(k_kk J_r) on each rotational local component of both ends (k_kk the diagonal
 * of eq 7, m_r and J_r the reduced mass and inertia), plus an optional mass-proportional
 * alpha M.
 *
 * Step control (004 eqs 29-30, implicit): when a trial step takes a bond's stress beyond
 * its strength by more than a fraction eps, the fraction alpha of du at which the first
 * bond reaches its strength is found (stresses are linear in du), and the step is redone
 * with dt sqrt(alpha) (eq 30, which assumes du ~ dt^2). The steps are taken from the
 * levels dt 2^(-k/2), k = 0 .. 20 (down to 1e-3 dt), so that their factors are found
 * again (NM_SLOTS = 4 are kept, least recently used replaced, each downdated when bonds
 * break): eq 30 gives the first shorter level, then bisection between the longest level
 * known to exceed the strength and the shortest known to stay below, and between two
 * adjacent levels a log-linear interpolation of the largest stress ratio (steps off the
 * ladder, factored for that trial), up to max_cuts trials; without a landing in
 * [1, 1 + eps] (right after a break the stiff local modes pass the released load on within
 * about their period, far from du ~ dt^2) the shortest step known to exceed is taken and
 * its bonds break. Bonds at or
 * beyond their strength then break. The next step keeps the level while bonds break and
 * doubles the step after a step without breaks, back to dt (004 does not say how the
 * step returns to dt). The explicit scheme breaks bonds at the step where they exceed
 * their strength.
 *
 * Stability: the explicit step is checked against floe_newmark_critical_dt (a block
 * Gershgorin bound of the bonded system, damping included) unless allow_unstable_dt;
 * every step checks that the energy (kinetic + elastic) stays below 100 x (initial energy
 * + the work of the loads) + a tiny floor, and stops with FLOE_EUNSTABLE otherwise (never
 * NaN output).
 *
 * Not yet: unbound (contact) elements after breakage (004 eqs 5-6); broken pairs do not
 * interact. Errors: every call returns FLOE_OK or a code of floe_base.h, the message in
 * floe_newmark_last_error. */
#ifndef FLOE_NEWMARK_H
#define FLOE_NEWMARK_H

#include "floe_base.h"
#include "floe_world_beams.h"

typedef struct floe_newmark floe_newmark;

typedef struct floe_newmark_def {
    int dim;                  /* 2 or 3 */
    double beta, gamma;       /* 0, 1/2: explicit; 1/4, 1/2: implicit average acceleration
                                 (0 <= 2 beta <= 1, 0 <= gamma <= 1, eq 16; gamma >= 1/2) */
    double dt;                /* step, s (> 0) */
    double damping_ratio;     /* xi of eq 8 (>= 0) */
    double mass_damping;      /* alpha of C += alpha M, 1/s (>= 0) */
    double line_search_eps;   /* eps of eqs 29-30 (implicit): tolerated relative excess of a
                                 stress over its strength before the step is cut; < 0: never cut */
    int max_cuts;             /* trial steps redone per step (12) */
    int allow_unstable_dt;    /* 1: an explicit dt above the critical estimate is accepted */
    int refactor_on_break;    /* implicit: 1 = refactor when bonds break; 0 (default) = remove
                                 the broken bonds from the factor by a rank downdate
                                 (cholmod_updown), refactoring every 256 downdates */
} floe_newmark_def;

/* Implicit average acceleration (beta 1/4, gamma 1/2), dim 2, dt 0 (must be set), no
 * damping, eps 0.01, 12 cuts. */
floe_newmark_def floe_newmark_default_def(void);

/* Create an empty system; NULL on an invalid definition (message to err). The caller owns
 * it: floe_newmark_destroy. */
floe_newmark *floe_newmark_create(const floe_newmark_def *def, char *err, size_t errlen);
void floe_newmark_destroy(floe_newmark *s);
const char *floe_newmark_last_error(const floe_newmark *s);

/* A node at x (m) with mass m (kg) and rotational inertia J (kg m^2, about every axis);
 * returns its index or -error. */
int floe_newmark_add_node(floe_newmark *s, const double x[3], double mass, double inertia);
/* A bond between nodes i and j with the section of sec (its length l is taken from the
 * node positions) and strengths sigma_lim, tau_lim (Pa; INFINITY: unbreakable); returns
 * its index or -error. */
int floe_newmark_add_bond(floe_newmark *s, int i, int j, const floe_beam_section *sec, double sigma_lim,
                          double tau_lim);

/* Supports (eq 3): components of node i held at zero displacement. */
enum {
    FLOE_NM_UX = 1, FLOE_NM_UY = 2, FLOE_NM_UZ = 4, FLOE_NM_RX = 8, FLOE_NM_RY = 16, FLOE_NM_RZ = 32,
    FLOE_NM_ALL = 63
};
int floe_newmark_fix(floe_newmark *s, int i, unsigned mask);
/* Threads for the solver's bond and node loops (OpenMP; 0, the default: OpenMP's default,
 * OMP_NUM_THREADS). The results are the same bits for any count (docs/parallel.md). A count
 * above 1 in a build without OpenMP (FLOE_WITH_OPENMP=OFF) is refused (FLOE_ENOTSUP). */
int floe_newmark_set_threads(floe_newmark *s, int nthreads);
/* Constant external force (N) and moment (N m) on node i, times the load factor. */
int floe_newmark_set_load(floe_newmark *s, int i, const double f[3], const double moment[3]);
/* Load factor lambda(t): f_e(t) = lambda(t) F (default 1). */
typedef double (*floe_newmark_load_fn)(double t, void *user);
int floe_newmark_set_load_factor(floe_newmark *s, floe_newmark_load_fn fn, void *user);
/* Initial displacement and rotation (the bonds start loaded: f_int = K u0), and initial
 * velocity and angular velocity of node i (before the first step). */
int floe_newmark_set_initial(floe_newmark *s, int i, const double u[3], const double rot[3], const double v[3],
                             const double w[3]);

/* Build the system of a prepared world: one node per particle (walls and fixed or
 * kinematic particles are fully supported nodes), the world's intact beam bonds with their
 * sections and strengths, gravity as the load, the particles' velocities. The node index
 * is the particle index; the solver takes the world's threads (floe_world_set_threads). NULL
 * with a message in err on failure. */
floe_newmark *floe_newmark_from_world(floe_world *w, const floe_newmark_def *def, char *err, size_t errlen);

/* Assemble, factor, initial acceleration from eq 15 at t = 0 (called by step if needed).
 * Fails on a bad set-up, an explicit dt above the critical one (unless allowed), a matrix
 * CHOLMOD finds not positive definite, or FLOE_ENOTSUP for beta > 0 in a build without
 * CHOLMOD (FLOE_WITH_CHOLMOD). */
int floe_newmark_prepare(floe_newmark *s);
/* One step of dt (implicit: possibly cut, eqs 29-30). */
int floe_newmark_step(floe_newmark *s);
/* Steps until t_end (the last step shortened to land on it). */
int floe_newmark_run(floe_newmark *s, double t_end);

/* Critical step of the explicit scheme (s): block Gershgorin bound on the highest
 * frequency of the free components, with the damping; and the estimate of 004 eq 28,
 * min 2 sqrt(m_ii / k_ii) over the diagonals (not a bound: it can exceed the true limit). */
double floe_newmark_critical_dt(floe_newmark *s);
double floe_newmark_critical_dt_diag(floe_newmark *s);

double floe_newmark_time(const floe_newmark *s);
int floe_newmark_node_count(const floe_newmark *s);
int floe_newmark_bond_count(const floe_newmark *s);
/* Displacement, rotation, velocity and angular velocity of node i (NULL to skip). */
int floe_newmark_get(const floe_newmark *s, int i, double u[3], double rot[3], double v[3], double w[3]);
/* Bond k: broken flag, time of breaking (-1), last stresses (eq 11), Pa. */
int floe_newmark_bond_state(const floe_newmark *s, int k, int *broken, double *t_broken, double *sigma, double *tau);

typedef struct floe_newmark_stats {
    long steps;               /* accepted steps */
    long cuts;                /* trial steps redone with a shorter step (eqs 29-30) */
    long factorizations;      /* numeric factorizations (implicit) */
    long downdates;           /* rank downdates of the factor for broken bonds (implicit) */
    int broken;               /* bonds broken so far */
    double t_first_break;     /* time of the first break, s (-1: none) */
    double energy_kinetic, energy_elastic; /* now, J */
    double work_external;     /* work of the loads since t = 0 (trapezoid), J */
    double energy_initial;    /* kinetic + elastic at t = 0, J */
    double dissipated;        /* by damping (work of C v, trapezoid) and breaking bonds, J */
    double seconds_factor, seconds_solve, seconds_bonds; /* wall time in those parts */
} floe_newmark_stats;
int floe_newmark_get_stats(const floe_newmark *s, floe_newmark_stats *out);

/* The nodes (displaced) and intact and broken bonds as a VTK unstructured grid (.vtu,
 * lines with cell data broken and t_broken) for ParaView; and the bonds as CSV (midpoint,
 * broken, t_broken, sigma, tau). FLOE_EIO on write errors. */
int floe_newmark_write_vtu(floe_newmark *s, const char *path);
int floe_newmark_write_bonds_csv(floe_newmark *s, const char *path);

/* 1 if this build has CHOLMOD (FLOE_WITH_CHOLMOD), so implicit Newmark (beta > 0) runs. */
int floe_newmark_implicit_available(void);

#endif
