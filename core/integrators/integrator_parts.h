/* integrator_parts.h - the helpers the driver's files share (core/integrators: step.c,
 * integrators.c, adaptive.c, driver.c, watchdog.c). Internal: not installed. The files
 * form a chain without circles (docs/architecture.md): step.c < integrators.c, adaptive.c
 * < driver.c < watchdog.c. */
#ifndef FLOE_INTEGRATOR_PARTS_H
#define FLOE_INTEGRATOR_PARTS_H

#include "world_parts.h"
#include "floe_integrator.h"
#include "par_hooks.h"

#define step_verlet floe_i_step_verlet
#define step_rk2 floe_i_step_rk2
#define step_staggered floe_i_step_staggered
#define stag_split_forces floe_i_stag_split_forces
#define stag_rows floe_i_stag_rows
#define shadow_term floe_i_shadow_term
#define step_once floe_i_step_once
#define step_adaptive floe_i_step_adaptive
#define choose_dt floe_i_choose_dt

/* step.c: one step of each scheme (velocity Verlet and leapfrog share step_verlet) */
int step_verlet(floe_world *w);
int step_rk2(floe_world *w);
int step_staggered(floe_world *w);
/* step.c: the staggered scheme's first forces (F_C, then F_PD, p->f = their sum) */
int stag_split_forces(floe_world *w, const floe_step_ctx *ctx);
/* step.c: the staggered scheme's row of each particle (w->stag): F_C, its torque, F_PD (kept
 * between steps), the start position of a PD point's cycle, its true velocity while the
 * contact laws read its mean one */
enum { STAG_FS = 0, STAG_TS = 3, STAG_FPD = 6, STAG_XS = 9, STAG_VT = 12, STAG_W = 15 };
/* the rows for every particle here (new rows zero), registered with the world at the first
 * call (they travel with their particles under MPI); NULL: out of memory (the error set) */
double *stag_rows(floe_world *w);
/* step.c: energy of the closing half kick of free particle i (the watchdog's conserved form) */
double shadow_term(const floe_particles *p, int i, const double dv[3], const double dL[3]);
/* integrators.c: one step of the world's scheme (the staggered PD-DEM scheme when chosen
 * and PD bodies exist, else the integrator class's step) */
int step_once(floe_world *w);
/* adaptive.c: the adaptive controller around any step that can be undone (the class has
 * FLOE_INTEGRATOR_RESTORES; choose_dt refuses the others) */
int step_adaptive(floe_world *w, int (*inner)(floe_world *w));
/* driver.c: the step, the staggered ratios and the adaptive bounds (at prepare) */
int choose_dt(floe_world *w);

/* largest squared distance of x from its position at the neighbour build, into *maxd2 */
static inline void floe_i_note_disp(const double *x, const double *xb, double *maxd2) {
    double dx = x[0] - xb[0], dy = x[1] - xb[1], dz = x[2] - xb[2];
    double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 > *maxd2) *maxd2 = d2;
}
#define note_disp floe_i_note_disp

#endif
