/* world_read.h - short reads of a world through the public view (floe_view.h) for the
 * tests: pview(w).x[3 * i] is particle i's x. A view is taken at each call, so it is never
 * stale (a view's pointers are valid only until the next add, prepare or step). */
#ifndef FLOE_TEST_WORLD_READ_H
#define FLOE_TEST_WORLD_READ_H

#include "floe.h"

static inline floe_particles_view pview(const floe_world *w) {
    floe_particles_view v;
    floe_world_particles(w, &v);
    return v;
}

static inline floe_neighbor_stats nstats(const floe_world *w) {
    floe_neighbor_stats s;
    floe_world_neighbor_stats(w, &s);
    return s;
}

static inline floe_detect_stats dstats(const floe_world *w) {
    floe_detect_stats s;
    floe_world_detect_stats(w, &s);
    return s;
}

/* set particle i's velocity component k (the others kept) */
static inline int set_vel(floe_world *w, int i, int k, double value) {
    double v[3];
    const double *cur = pview(w).v + 3 * i;
    for (int a = 0; a < 3; a++) v[a] = cur[a];
    v[k] = value;
    return floe_world_set_velocity(w, i, v, NULL);
}

#endif
