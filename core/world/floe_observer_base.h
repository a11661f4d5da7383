/* floe_observer_base.h - the observer class (ParticLS §4.3), as the world calls it: every
 * `period_steps` steps or every `period_time` seconds of simulated time, once at the start
 * and once at the end (also when a run stops on an error, so that what was computed is
 * written). The built-in observers are in observers/floe_observer.h. */
#ifndef FLOE_OBSERVER_BASE_H
#define FLOE_OBSERVER_BASE_H

#include "floe_world.h"

typedef struct floe_observer_class {
    int version; /* 1 */
    const char *name;
    int (*begin)(floe_observer *o, floe_world *w);      /* optional */
    int (*observe)(floe_observer *o, floe_world *w);    /* required */
    int (*end)(floe_observer *o, floe_world *w);        /* optional: flush, close */
    void (*destroy)(floe_observer *o);                  /* optional */
    int needs_contacts;   /* 1: reads floe_world_contacts, so the world records every contact */
} floe_observer_class;

struct floe_observer {
    const floe_observer_class *klass;
    long period_steps;      /* > 0: every n steps */
    double period_time;     /* > 0: every this many seconds (used when period_steps = 0) */
    double next_time;       /* bookkeeping of the world */
    int ended;
    int begun;
};

/* Destroys an observer the world does not own (the world destroys those added to it). */
void floe_observer_destroy(floe_observer *o);

#endif
