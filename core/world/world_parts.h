/* world_parts.h - the helpers the world's files share (core/world: world.c, world_pd.c,
 * world_beams.c, forces.c, timestep.c, world_prepare.c), and that the driver above
 * (core/integrators) calls. Internal: not installed. */
#ifndef FLOE_WORLD_PARTS_H
#define FLOE_WORLD_PARTS_H

#include "world_internal.h"
#include "floe_pd.h"
#include "beam_set.h"
#include "floe_provider.h"
#include "rigid_body.h"

#define L_from_omega floe_L_from_omega
#define contacts_wanted floe_w_contacts_wanted
#define orientation_refresh floe_w_orientation_refresh
#define observer_reads_orientation floe_w_observer_reads_orientation
#define observer_orientation_claim floe_w_observer_orientation_claim
#define ctx_step floe_w_ctx_step
#define estimate_dt floe_w_estimate_dt
#define grow floe_w_grow
#define observers_call floe_w_observers_call
#define prepare_store floe_w_prepare_store
#define prepare_state floe_w_prepare_state
#define prepare_ledger floe_w_prepare_ledger
#define prepare_observers floe_w_prepare_observers
#define providers_state_io floe_w_providers_state_io
#define providers_state_size floe_w_providers_state_size

/* world.c */
int grow(void **ptr, int *cap, int need, size_t sz);
/* servo_walls.c, for the MPI decomposition (core/parallel/par_forcing.c): the number of
 * servo walls; their measures on this rank's particles (2 doubles a wall, in the servos'
 * order: the normal force f.n on the wall, the free particles whose bounding sphere reaches
 * it); the totals over the ranks, which the controllers then read in place of this rank's
 * parts; the walls' indices renumbered at the split (newidx[old] = new, walls kept) */
int floe_servo_count(const floe_world *w);
/* servo_walls.c, user_providers.c: 1 when pv is the world's servo-wall provider, the
 * built-in linear_drag (core/parallel/par_forcing.c runs them split over MPI ranks) */
int floe_servo_is_provider(const floe_provider *pv);
int floe_linear_drag_is(const floe_provider *pv);
void floe_servo_partials(const floe_world *w, double *v);
void floe_servo_set_totals(floe_world *w, const double *v);
void floe_servo_renumber(floe_world *w, const int *newidx);
/* timestep.c: every critical-step estimate into w->dte, w->dt_part, w->dt_crit */
int estimate_dt(floe_world *w);
/* world_prepare.c: the store's part of floe_world_prepare (core/integrators/driver.c runs
 * them in this order around the integrator's choice of the step and first forces):
 * prepare_store: the providers, masses and inertia, the laws and detectors every pair
 * needs, the PD bookkeeping, the critical-step estimates; prepare_state (after the step is
 * chosen): the neighbour list, the scratch, the watchdog's floor, the clock (prepared = 1);
 * prepare_ledger (after the first forces): the energy at the start, the watchdog's
 * conserved form from shadow (the closing half kick's energy); prepare_observers: begin
 * every observer and let each observe the start */
int prepare_store(floe_world *w);
int prepare_state(floe_world *w);
void prepare_ledger(floe_world *w, double shadow);
int prepare_observers(floe_world *w);
int contacts_wanted(const floe_world *w);
void orientation_refresh(floe_world *w);
int observer_orientation_claim(const floe_observer *o);
int observer_reads_orientation(const floe_observer *o, const floe_world *w);
floe_step_ctx ctx_step(floe_world *w, int record);
int observers_call(floe_world *w, int force_all);
void providers_state_io(floe_world *w, unsigned char *buf, int save);
size_t providers_state_size(const floe_world *w);

#endif
