/* poly_box.h - tests' random polyhedral grains and a walled box of them (test_lp_resting,
 * test_manifold_springs, test_manifold_cache). Include after test_rng.h and check.h.
 *   poly_grain(R, npl): a convex grain, the intersection of npl half-spaces (the first six
 *     axis-aligned, the rest random normals), offsets R (1 +- 0.15);
 *   poly_box_fill(w, np, g, ng, R): five fixed walls (a floor and four sides, 4 x 3.6 R wide)
 *     and np grains of the ng geometries g (in turn) on a jittered lattice 3.6 R apart, with
 *     random orientations, velocities up to 0.1 m/s and spins up to 20 rad/s;
 *   poly_box_new(R, m): a world under gravity (safety 0.5, skin 0.3 R) with the one material
 *     m (NULL when it cannot be made);
 *   poly_box_world(w, R, np, npl, law): on such a world, the contact law, 3 grain shapes of
 *     npl planes, the box of np grains, prepared; w, or NULL after a failed check. */
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

static inline floe_world *poly_box_new(double R, const floe_material *m) {
    floe_world_def def = floe_default_world_def();
    def.gravity[2] = -9.81;
    def.dt_safety = 0.5;
    def.skin = 0.3 * R;
    floe_world *w = floe_world_create(&def, NULL, 0);
    if (w) floe_world_add_material(w, m);
    return w;
}

static inline floe_world *poly_box_world(floe_world *w, double R, int np, int npl, floe_contact_law *law) {
    CHECK(law && floe_world_set_law(w, 0, 0, law) == FLOE_OK, "set law: %s", floe_world_last_error(w));
    int g[3];
    for (int s = 0; s < 3; s++) g[s] = floe_world_add_geometry(w, poly_grain(R, npl));
    poly_box_fill(w, np, g, 3, R);
    const int ok = floe_world_prepare(w) == FLOE_OK;
    CHECK(ok, "prepare: %s", floe_world_last_error(w));
    return ok ? w : NULL;
}
#endif
