/* test_detect.c - analytic detectors against exact answers: a cube given only as a user
 * SDF, tilted by 1e-1 .. 1e-5 rad about y and pushed 1e-4 m into a wall (the exact depth
 * of its lowest corner) must be detected with the depth within 1 %. A user shape whose
 * centre of mass is off the body origin is refused with a message. A tumbling box
 * bouncing on a floor through the lumped box-wall contact (linear law, no damping or
 * friction) keeps its mechanical energy within 1 % between impacts. */
#include "floe.h"
#include "floe.h"
#include "world_read.h"
#include "check.h"
#include <string.h>

static double cube_sdf(const double X[3], void *u) {
    double h = *(double *)u, q[3], o = 0, in = -INFINITY;
    for (int k = 0; k < 3; k++) {
        q[k] = fabs(X[k]) - h;
        if (q[k] > 0) o += q[k] * q[k];
        if (q[k] > in) in = q[k];
    }
    return o > 0 ? sqrt(o) : in;
}

static double offset_sphere(const double X[3], void *u) {
    (void)u;
    double d[3] = {X[0] - 0.05, X[1], X[2]};
    return floe_v3_norm(d) - 0.1;
}

int main(void) {
    /* a user shape whose centre of mass is not the body origin is refused, not integrated
     * about the wrong point */
    {
        floe_world_def d = floe_default_world_def();
        d.dt = 1e-3;
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"m", 1000, 1e7, 0.3};
        floe_world_add_material(w, &m);
        int g = floe_world_add_geometry(w, floe_user_shape_create(offset_sphere, NULL, 0.16));
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        floe_world_add_particle(w, &p);
        int rc = floe_world_prepare(w);
        CHECK(rc == FLOE_EINVAL && strstr(floe_world_last_error(w), "centre of mass"),
              "off-centre user shape must be refused (rc %d: %s)", rc, floe_world_last_error(w));
        printf("  %s\n", floe_world_last_error(w));
        floe_world_destroy(w);
    }
    static double h = 0.1;
    for (double tilt = 1e-1; tilt >= 1e-5; tilt /= 10) {
        floe_world_def d = floe_default_world_def();
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"m", 1000, 1e7, 0.3};
        floe_world_add_material(w, &m);
        double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
        int wall = floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
        int g = floe_world_add_geometry(w, floe_user_shape_create(cube_sdf, &h, sqrt(3.0) * h));
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        double th[3] = {0, tilt, 0};
        floe_q_from_rotvec(p.q, th);
        /* lowest corner height relative to the centre: -h (cos t + sin t) */
        double low = h * (cos(tilt) + sin(tilt));
        floe_v3_set(p.x, 0, 0, low - 1e-4);
        int i = floe_world_add_particle(w, &p);
        floe_contact c;
        int r = floe_world_probe_contact(w, i, wall, 0, &c);
        char what[96];
        snprintf(what, sizeof what, "user cube tilted %.0e rad: depth vs exact 1e-4 m (tol 1%%)", tilt);
        CHECK(r == 1, "%s: not detected", what);
        if (r == 1) CHECK_NEAR(c.depth, 1e-4, 0.01, what);
        floe_world_destroy(w);
    }
    /* the lumped box-wall contact is conservative for a linear law: a tumbling box bouncing
     * on a floor without damping or friction keeps its mechanical energy */
    {
        floe_world_def d = floe_default_world_def();
        d.gravity[2] = -9.81;
        d.dt = 2e-5;
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"m", 1000, 1e7, 0.3};
        floe_world_add_material(w, &m);
        floe_world_set_law(w, 0, 0, floe_linear_law_create(1e5, 0, 0, 0, 0));
        double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
        floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
        int g = floe_world_add_geometry(w, floe_box_create(0.1, 0.2, 0.3));
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        floe_v3_set(p.x, 0, 0, 0.3);
        floe_v3_set(p.w, 3, 20, 7);
        int i = floe_world_add_particle(w, &p);
        CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
        double g9 = 9.81, E0 = 0, maxdev = 0;
        long contact_steps = 0;
        for (int s = 0; s <= 50000; s++) {
            floe_energy e = floe_world_energy(w);
            double E = e.kinetic_trans + e.kinetic_rot + e.elastic + pview(w).mass[i] * g9 * pview(w).x[3 * i + 2];
            if (s == 0) E0 = E;
            /* compared in flight: in contact the law's elastic energy (k (sum d)^2 / 2) is
             * not the per-vertex springs' potential (sum k d^2 / 2), the forces are */
            if (floe_world_contact_count(w) == 0) maxdev = fmax(maxdev, fabs(E - E0));
            if (floe_world_step(w)) { CHECK(0, "step: %s", floe_world_last_error(w)); break; }
            contact_steps += floe_world_contact_count(w) > 0;
        }
        printf("  tumbling box on a floor: %ld contact steps, max |dE|/E0 = %.2e\n", contact_steps, maxdev / E0);
        CHECK(contact_steps > 1000, "the box must hit the floor (%ld contact steps)", contact_steps);
        CHECK(maxdev / E0 < 1e-2, "lumped box-wall contact must conserve energy (max |dE|/E0 = %g)", maxdev / E0);
        floe_world_destroy(w);
    }
    return check_summary("test_detect");
}
