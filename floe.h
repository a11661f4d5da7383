/* floe.h - umbrella header of the floe library. */
#ifndef FLOE_H
#define FLOE_H
#include "core/floe_base.h"
#include "geometry/floe_geometry.h"
#include "contact/floe_contact.h"
#include "core/floe_world.h"
#include "core/floe_state.h"
#include "core/floe_kdtree.h"
#include "observers/floe_observer.h"
#include "core/floe_scene.h"
#endif
