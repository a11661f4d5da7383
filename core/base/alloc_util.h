/* alloc_util.h - arrays that grow (internal to the library): one copy of the realloc
 * pattern the world, the checkpoints and the MPI layer share. */
#ifndef FLOE_ALLOC_H
#define FLOE_ALLOC_H

#include <stdint.h>
#include <stdlib.h>

#include "floe_base.h"

/* *ptr resized to n items of size bytes (at least one item, so a success never returns
 * NULL): FLOE_OK, or FLOE_ENOMEM with *ptr untouched (overflow included). */
static inline int floe_resize(void **ptr, size_t n, size_t size) {
    if (!n) n = 1;
    if (size && n > SIZE_MAX / size) return FLOE_ENOMEM;
    void *t = realloc(*ptr, n * size);
    if (!t) return FLOE_ENOMEM;
    *ptr = t;
    return FLOE_OK;
}

/* *ptr holds at least n items of size bytes, *cap items now (contents kept): grows to
 * exactly n when short. FLOE_OK or FLOE_ENOMEM (*ptr and *cap untouched). */
static inline int floe_reserve(void **ptr, size_t *cap, size_t n, size_t size) {
    if (n <= *cap && *ptr) return FLOE_OK;
    int rc = floe_resize(ptr, n, size);
    if (rc == FLOE_OK) *cap = n ? n : 1;
    return rc;
}

#endif
