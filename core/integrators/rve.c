/* rve.c - driving a periodic cell as a representative volume element (floe_cell.h,
 * docs/periodic.md): strain increments and the perturbation tangent. They step the world, so
 * they sit in the driver's layer above the cell (core/world/cell.c). */
#include "world_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int floe_world_cell_strain(floe_world *w, const double de[9], double max_rate, const int *stress_mask, long *steps) {
    if (steps) *steps = 0;
    if (!w->cell) return floe_world_error(w, FLOE_EINVAL, "strain increment: the world has no periodic cell");
    if (!w->prepared) FLOE_TRY(floe_world_prepare(w));
    long n = 0;
    FLOE_TRY(floe_cell_path_begin(w, de, max_rate, stress_mask, &n));
    int rc = FLOE_OK;
    for (long s = 0; s < n && rc == FLOE_OK; s++) {
        rc = floe_world_step(w);
        if (rc == FLOE_OK && steps) (*steps)++;
    }
    floe_cell_path_end(w);
    return rc;
}
