/* world_parts.h - the helpers the world's files share (core/world: world.c, world_pd.c,
 * world_prepare.c, timestep.c, step.c, watchdog.c). Internal: not installed. */
#ifndef FLOE_WORLD_PARTS_H
#define FLOE_WORLD_PARTS_H

#include "world_internal.h"
#include "floe_pd.h"
#include "beam_set.h"
#include "floe_provider.h"

typedef struct floe_snapshot floe_snapshot; /* step.c: the adaptive controller's saved state */

#define L_from_omega floe_w_L_from_omega
#define choose_dt floe_w_choose_dt
#define contacts_wanted floe_w_contacts_wanted
#define ctx_step floe_w_ctx_step
#define estimate_dt floe_w_estimate_dt
#define grow floe_w_grow
#define observers_call floe_w_observers_call
#define providers_state_io floe_w_providers_state_io
#define providers_state_size floe_w_providers_state_size
#define shadow_term floe_w_shadow_term
#define snapshot_free floe_w_snapshot_free
#define stag_split_forces floe_w_stag_split_forces
#define step_adaptive floe_w_step_adaptive
#define step_once floe_w_step_once

void L_from_omega(const double q[4], const double I[3], const double om[3], double L[3]);
int choose_dt(floe_world *w);
int contacts_wanted(const floe_world *w);
floe_step_ctx ctx_step(floe_world *w, int record);
int estimate_dt(floe_world *w);
int grow(void **ptr, int *cap, int need, size_t sz);
int observers_call(floe_world *w, int force_all);
void providers_state_io(floe_world *w, unsigned char *buf, int save);
size_t providers_state_size(const floe_world *w);
double shadow_term(const floe_particles *p, int i, const double dv[3], const double dL[3]);
void snapshot_free(floe_snapshot *s);
int stag_split_forces(floe_world *w, const floe_step_ctx *ctx);
int step_adaptive(floe_world *w);
int step_once(floe_world *w);

#endif
