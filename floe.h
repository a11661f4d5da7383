/* floe.h - umbrella header of the floe library. */
#ifndef FLOE_H
#define FLOE_H
#include "floe_base.h"
#include "floe_geometry.h"
#include "floe_contact.h"
#include "floe_world.h"
#include "floe_cell.h"
#include "floe_servo.h"
#include "floe_state.h"
#include "floe_kdtree.h"
#include "floe_observer.h"
#include "floe_scene.h"
#include "floe_world_beams.h"
#include "floe_view.h"
#include "floe_registry.h"
#include "floe_provider.h"
#include "floe_forcing.h"
#include "floe_integrator.h"
#include "floe_checkpoint.h"
#include "floe_parallel.h"
#endif
