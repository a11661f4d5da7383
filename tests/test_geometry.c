/* test_geometry.c - conformance of every geometry (GSL-style: the same checks for each
 * class): gradient versus finite differences, sdf(project(X)) = 0, mass properties of the
 * built-ins versus the numerical quadrature, and convergence of that quadrature for a
 * user SDF shape with its own error estimate. */
#include "floe.h"
#include "check.h"
#include <stdlib.h>

static double rnd(unsigned *s) { *s = *s * 1664525u + 1013904223u; return (*s >> 8) / 16777216.0; }

/* a user shape: sphere of radius 0.3 (exact SDF) */
static double user_sphere(const double X[3], void *u) { return floe_v3_norm(X) - *(double *)u; }
/* capsule: segment from -a to a on z, radius r (exact SDF) */
typedef struct { double a, r; } capsule;
static double user_capsule(const double X[3], void *u) {
    const capsule *c = u;
    double z = fmax(-c->a, fmin(c->a, X[2]));
    double d[3] = {X[0], X[1], X[2] - z};
    return floe_v3_norm(d) - c->r;
}

static void conformance(const char *name, const floe_geometry *g, double scale) {
    unsigned s = 7;
    double worst_grad = 0, worst_proj = 0;
    for (int k = 0; k < 500; k++) {
        double X[3] = {(rnd(&s) - 0.5) * 3 * scale, (rnd(&s) - 0.5) * 3 * scale, (rnd(&s) - 0.5) * 3 * scale};
        double n[3], fd[3], h = 1e-6 * scale, P[3];
        floe_geometry_gradient(g, X, n);
        for (int a = 0; a < 3; a++) {
            double p[3] = {X[0], X[1], X[2]}, m[3] = {X[0], X[1], X[2]};
            p[a] += h; m[a] -= h;
            fd[a] = (floe_geometry_sdf(g, p) - floe_geometry_sdf(g, m)) / (2 * h);
        }
        /* skip points within 1e-4 of a gradient discontinuity (box medial axis) */
        double diff[3];
        floe_v3_sub(diff, n, fd);
        if (fabs(floe_v3_norm(fd) - 1) < 1e-6) worst_grad = fmax(worst_grad, floe_v3_norm(diff));
        floe_geometry_project(g, X, P);
        worst_proj = fmax(worst_proj, fabs(floe_geometry_sdf(g, P)) / scale);
    }
    char what[128];
    snprintf(what, sizeof what, "%s: max |grad - finite diff| (tol 1e-5)", name);
    CHECK(worst_grad < 1e-5, "%s = %g", what, worst_grad);
    printf("  %-52s %.2e\n", what, worst_grad);
    snprintf(what, sizeof what, "%s: max |sdf(project(X))|/size (tol 1e-9)", name);
    CHECK(worst_proj < 1e-9, "%s = %g", what, worst_proj);
    printf("  %-52s %.2e\n", what, worst_proj);
}

int main(void) {
    floe_geometry *sph = floe_sphere_create(0.3), *box = floe_box_create(0.2, 0.5, 0.8), *pl = floe_plane_create();
    double r = 0.3;
    capsule cap = {0.2, 0.1};
    floe_geometry *us = floe_user_shape_create(user_sphere, &r, 0.31);
    floe_geometry *uc = floe_user_shape_create(user_capsule, &cap, 0.31);
    CHECK(floe_sphere_create(-1) == NULL && floe_box_create(1, 0, 1) == NULL && floe_user_shape_create(user_sphere, &r, 0) == NULL,
          "invalid shape parameters must be refused");
    conformance("sphere", sph, 0.3);
    conformance("box", box, 0.5);
    conformance("plane", pl, 1.0);
    conformance("user sphere", us, 0.3);
    conformance("user capsule", uc, 0.3);

    /* analytic mass properties vs the numerical quadrature */
    floe_mass_properties a, b;
    floe_geometry_mass_properties(box, 3, 1000, &a);
    floe_geometry_mass_numeric(box, 3, 1000, 96, &b);
    CHECK_NEAR(b.mass, a.mass, 2e-2, "box mass: quadrature vs analytic (tol 2%)");
    for (int k = 0; k < 3; k++) CHECK_NEAR(b.inertia[k], a.inertia[k], 3e-2, "box principal inertia: quadrature vs analytic (tol 3%)");

    /* convergence of the user-shape quadrature (sphere: exact 4/3 pi r^3, 2/5 m r^2);
     * its error estimate must bound the true error and shrink */
    double prev = INFINITY;
    for (int n = 16; n <= 128; n *= 2) {
        floe_user_shape *u = (floe_user_shape *)us;
        u->quad_cells = n;
        floe_mass_properties m;
        CHECK(floe_geometry_mass_properties(us, 3, 1000, &m) == FLOE_OK, "quadrature failed");
        double V = 4.0 / 3.0 * M_PI * r * r * r, I = 0.4 * 1000 * V * r * r;
        double err = fmax(fabs(m.volume - V) / V, fabs(m.inertia[0] - I) / I);
        printf("  user sphere quadrature n=%3d: true error %.2e, estimate %.2e\n", n, err, m.quadrature_error);
        CHECK(err <= 2 * m.quadrature_error + 1e-12, "error estimate %g must bound the true error %g", m.quadrature_error, err);
        CHECK(err < prev, "quadrature error must decrease with n (%g -> %g)", prev, err);
        prev = err;
    }
    CHECK(prev < 2e-3, "n=128 quadrature within 0.2%% (got %g)", prev);
    /* capsule: V = pi r^2 (2a) + 4/3 pi r^3 */
    floe_mass_properties mc;
    ((floe_user_shape *)uc)->quad_cells = 128;
    floe_geometry_mass_properties(uc, 3, 1, &mc);
    CHECK_NEAR(mc.volume, M_PI * 0.01 * 0.4 + 4.0 / 3.0 * M_PI * 1e-3, 5e-3, "capsule volume by quadrature (tol 0.5%)");
    /* 2D: disc area and polar moment */
    floe_geometry_mass_properties(sph, 2, 1, &a);
    CHECK_NEAR(a.volume, M_PI * 0.09, 1e-14, "2D sphere = disc area");
    floe_geometry_mass_numeric(sph, 2, 1, 128, &b);
    CHECK_NEAR(b.inertia[2], a.inertia[2], 1e-2, "2D disc polar moment: quadrature vs analytic (tol 1%)");

    floe_geometry_destroy(sph); floe_geometry_destroy(box); floe_geometry_destroy(pl);
    floe_geometry_destroy(us); floe_geometry_destroy(uc);
    return check_summary("test_geometry");
}
