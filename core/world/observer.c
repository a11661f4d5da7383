/* observer.c - observer lifetime helpers shared by all observer classes. */
#include "floe_observer_base.h"

#include <stdlib.h>

void floe_observer_destroy(floe_observer *o) {
    if (!o) return;
    if (o->klass && o->klass->destroy)
        o->klass->destroy(o);
    else
        free(o);
}
