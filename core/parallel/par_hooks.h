/* par_hooks.h - where the step (core/integrators) calls the MPI decomposition. Internal.
 * Called only for a world split by floe_world_parallel_init (w->par set); without
 * FLOE_HAVE_MPI they do nothing. */
#ifndef FLOE_PAR_HOOKS_H
#define FLOE_PAR_HOOKS_H

#include "world_internal.h"

/* after the drift: every rank decides whether its list needs a rebuild (maxd2, have_xb as
 * in step.c's rebuild_if_needed), all rebuild when one does (RCB, migration, ghosts,
 * history by global ids, floe_nl_build); otherwise the ghosts are refreshed from their
 * owners */
/* carry (NULL: none; RK2's closing values): *n rows of m doubles a particle that travel with
 * their particles through this call's decomposition (registered for the call only; every
 * rank passes the same m). dash >= 0: columns [dash, dash + 3) of the rows hold the RK2
 * midpoint's kept dashpot accelerations (forces.c), put back into w->dash_a and sent to the
 * new ghosts after a decomposition. A rank that could not make its rows passes the failure
 * as rc (below) */
typedef struct floe_par_carry {
    double **rows;
    int *n;
    int m, dash;
} floe_par_carry;
/* rc: this rank's failure since the step's last agreement (its message set; FLOE_OK: none),
 * told to every rank with the need: every rank then returns that error (an out-of-memory
 * one first, else the lowest failing rank's; w->err_agreed) and *told is set (the step puts
 * its clock back: one process returns such a failure before the clock moves). flag (or
 * NULL): in, this rank's flag (velocity Verlet: a particle failed the drift's quick checks);
 * out, whether any rank's was set, in the same reduction. Without MPI or a split: rc */
int floe_par_refresh(floe_world *w, double maxd2, int have_xb, const floe_par_carry *carry, int rc, int *flag,
                     int *told);
/* the ghosts' positions, velocities (and orientations, forces where the laws read them)
 * from their owners, without a rebuild (RK2's midpoint) */
int floe_par_ghost_update(floe_world *w);
/* a clock for the force evaluations' time (seconds; 0 without MPI), and the seconds one took
 * on this rank (the load balance's measure, floe_world_parallel_set_balance) */
double floe_par_clock(void);
void floe_par_force_time(floe_world *w, double seconds);
/* after a force evaluation: the forces and torques on ghosts added to their owners */
int floe_par_reverse(floe_world *w);
/* after a force evaluation's reverse sum (and at the split): the servo walls' measures
 * summed over the ranks for their controllers, the same on every rank (par_forcing.c);
 * nothing without servo walls */
int floe_par_servo_totals(floe_world *w);
/* a periodic cell with a stress-controlled component (the servo), before the step's velocity
 * gradient: the cell's stress (the contacts' virial, the free particles' kinetic part) summed
 * over the ranks into sigma, the servo's stiffness sums into the cell's kdiag, the same on
 * every rank; *given 0 (sigma untouched) when nothing needs it */
int floe_par_cell_stress(floe_world *w, double sigma[9], int *given);
/* after a step (force_all: every observer, the end): when the mirror's observers are due
 * (rank 0 decides, all follow), the state gathered into the mirror and its observers
 * called; nothing without a mirror */
int floe_par_observe(floe_world *w, int force_all);
/* the energy watchdog's inputs summed over the ranks (the most negative pair dissipation:
 * the minimum; pdd: the PD bodies' npd dissipations, in place), in one MPI_Allreduce (a
 * second one with more than 8 PD bodies). close_rc (or NULL): this rank's outcome of the
 * step's close, agreed in the same reduction as floe_par_agree_error agrees it (the failing
 * rank's code and message every rank's, returned; w->err_agreed set): the step's close
 * then needs no reduction of its own (core/integrators/watchdog.c floe_world_step).
 * Collective; without MPI or a split, *close_rc (or FLOE_OK) */
int floe_par_watchdog_values(floe_world *w, floe_energy *e, double *shadow, double *shadow0, double *pair_min,
                             double *pdd, int npd, const int *close_rc);

/* the words of the rank whose key is the largest (the lowest such rank; NaN counts as
 * -infinity), a (alen bytes) and b (blen), made every rank's; returns that key. The energy
 * watchdog names its culprit so: each rank its own candidate. Collective; without MPI or a
 * split: key, a and b as they are */
double floe_par_pick(floe_world *w, double key, char *a, int alen, char *b, int blen);

/* an outcome made every rank's (docs/parallel.md, "Errors inside a step"): rc is this rank's;
 * when a rank failed, the lowest failing rank's code and message are every rank's (its
 * message in last_error, naming particles by their global ids as one process does;
 * w->err_agreed set) and returned on every rank.
 * Called by every rank at the same point of the step: after a force evaluation (before its
 * reverse sum) and after the step's closing checks. One MPI_Allreduce of an int when no rank
 * failed; rc itself without MPI or a split */
int floe_par_agree_error(floe_world *w, int rc);

/* the adaptive step (core/integrators/adaptive.c) on a split world: v[0 .. n) replaced by
 * their largest values over the ranks, the same on every rank (untouched without MPI or a
 * split) */
void floe_par_max(floe_world *w, double *v, int n);

#endif
