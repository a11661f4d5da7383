/* test_extremes.c - head-on Hertz-Mindlin collisions at the extremes of stiffness
 * (E = 1e3 .. 1e12 Pa), speed (1e-6 .. 1e3 m/s) and mass ratio (1 .. 1e6), each with the
 * automatic time step: the run must finish with finite numbers and restitute e = 0.5
 * within 5 % (or stop with a clear error naming the particles, never NaN output). Too soft
 * for the speed (E = 1e3 Pa at 1 m/s: the spheres would pass through each other) must
 * stop with a message, not bounce backwards. */
#include "floe.h"
#include "floe.h"
#include "world_read.h"
#include "check.h"
#include "head_on.h"
#include <string.h>

static void collide(double E, double v0, double ratio) {
    int rc;
    long in_contact;
    floe_world *w = head_on_collision(floe_default_world_def(), E, v0, ratio, &rc, &in_contact);
    char what[128];
    snprintf(what, sizeof what, "E=%.0e v=%.0e mass ratio %.0e", E, v0, ratio);
    if (rc) {
        CHECK(strstr(floe_world_last_error(w), "particle") != NULL, "%s: failed without naming a particle: %s", what,
              floe_world_last_error(w));
        printf("  %s: stopped: %s\n", what, floe_world_last_error(w));
    } else {
        double va = pview(w).v[0], vb = pview(w).v[3];
        double e = (vb - va) / v0;
        CHECK(isfinite(va) && isfinite(vb), "%s: non-finite velocities", what);
        char w2[320];
        snprintf(w2, sizeof w2, "%s: restitution (tol 5%%, %ld steps in contact)", what, in_contact);
        CHECK_NEAR(e, 0.5, 0.05, w2);
    }
    floe_world_destroy(w);
}

int main(void) {
    double Es[3] = {1e3, 1e7, 1e12}, vs[3] = {1e-6, 1.0, 1e3}, ratios[3] = {1, 1e3, 1e6};
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) collide(Es[a], vs[b], 1.0);
    for (int c = 1; c < 3; c++) collide(1e7, 1.0, ratios[c]);
    return check_summary("test_extremes");
}
