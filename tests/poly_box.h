/* poly_box.h - tests' random polyhedral grains and a walled box of them (test_lp_resting,
 * test_manifold_springs). Include after test_rng.h and check.h.
 *   poly_grain(R, npl): a convex grain, the intersection of npl half-spaces (the first six
 *     axis-aligned, the rest random normals), offsets R (1 +- 0.15);
 *   poly_box_fill(w, np, g, ng, R): five fixed walls (a floor and four sides, 4 x 3.6 R wide)
 *     and np grains of the ng geometries g (in turn) on a jittered lattice 3.6 R apart, with
 *     random orientations, velocities up to 0.1 m/s and spins up to 20 rad/s. */
#ifndef FLOE_TEST_POLY_BOX_H
#define FLOE_TEST_POLY_BOX_H
#include "floe.h"

static floe_geometry *poly_grain(double R, int npl) {
    double pl[4 * 64];
    if (npl > 64) npl = 64;
    for (;;) {
        for (int k = 0; k < npl; k++) {
            double *q = pl + 4 * k;
            if (k < 6) { q[0] = q[1] = q[2] = 0; q[k / 2] = k % 2 ? -1 : 1; }
            else rand_unit(q);
            q[3] = R * uni(0.85, 1.15);
        }
        floe_geometry *g = floe_polyhedron_from_planes(pl, npl, NULL, 0);
        if (g) return g;
    }
}

static void poly_box_fill(floe_world *w, int np, const int *g, int ng, double R) {
    const double sp = 3.6 * R, L = 4 * sp;
    for (int a = 0; a < 3; a++) {
        double p0[3] = {0, 0, 0}, p1[3] = {0, 0, 0}, n0[3] = {0, 0, 0}, n1[3] = {0, 0, 0};
        p1[a] = L; n0[a] = 1; n1[a] = -1;
        floe_world_add_wall(w, p0, n0, 0, FLOE_FIXED);
        if (a < 2) floe_world_add_wall(w, p1, n1, 0, FLOE_FIXED);
    }
    for (int i = 0; i < np; i++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g[i % ng];
        floe_v3_set(p.x, (i % 4 + 0.5) * sp + uni(-0.1, 0.1) * R, ((i / 4) % 4 + 0.5) * sp + uni(-0.1, 0.1) * R,
                    (i / 16 + 0.5) * sp);
        rand_quat(p.q);
        for (int k = 0; k < 3; k++) { p.v[k] = uni(-0.1, 0.1); p.w[k] = uni(-20, 20); }
        CHECK(floe_world_add_particle(w, &p) >= 0, "add particle: %s", floe_world_last_error(w));
    }
}
#endif
