/* forcing_parts.h - what the layers above ask of core/forcing's providers. Internal: not
 * installed. */
#ifndef FLOE_FORCING_PARTS_H
#define FLOE_FORCING_PARTS_H

#include "floe_provider.h"

/* 1 when pv is one of this folder's drags (floe_drag_create: ocean_drag, wind_drag, any
 * name) or Coriolis (floe_coriolis_create): providers that act on free particles alone and
 * keep their per-particle state registered with the world (floe_world_pp_attach), so that
 * a world split over MPI ranks runs them (core/parallel/par_forcing.c) */
int floe_forcing_is_per_particle(const floe_provider *pv);

#endif
