/* test_dashpot_static.c - the linear dashpot carries no static error (contact/laws/
 * linear_law.c: the dashpot sees the end-of-step velocity v_mid + dt/2 (a_ext - Fn/m*), the
 * other forces' part a_ext from the last evaluation, core/world/forces.c).
 *   1. The law alone: a contact at rest with a_ext = kn d / m* (held by others) gives
 *      Fn = kn d within 1e-12; with a_ext = 0 (two bodies alone) the binary-collision form
 *      (kn d + gn vn) / (1 + gn dt / 2m*), within 1e-12.
 *   2. A column of 5 spheres at rest on a wall under gravity, viscoelastic (zeta 0.5 of the
 *      sphere-wall pair), each overlap at its static value (N - k) m g / kn, at the default
 *      step: over 200 steps every contact's force is kn d within 1e-9 relative, for velocity
 *      Verlet, leapfrog and RK2 (with a_ext = 0, the binary form alone, they were too low by
 *      x / (1 + x), x = gn dt / (2 m*): 2.2 % at the wall, 4.3 % between spheres, printed).
 *   3. A periodic 2D rectangular lattice of discs compressed unequally in x and y (at rest
 *      by symmetry), viscoelastic: over 100 steps every contact's force is kn d within 1e-9,
 *      and the stress after floe_world_refresh_forces equals the stress of the last step
 *      within 1e-9 relative (with the binary form alone both were off by 4.0 %). */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <string.h>

/* 1. the law alone */
static void law_alone(void) {
    const double kn = 1e4, gn = 2.0, m = 1e-3, dt = 1e-5, d = 1e-4;
    floe_contact_law *law = floe_linear_law_create(kn, 0, gn, 0, 0);
    double hist[FLOE_MAX_HISTORY] = {0};
    floe_contact c;
    memset(&c, 0, sizeof c);
    c.n[0] = 1;
    c.depth = d;
    c.r_eff = 1e-3;
    c.m_eff = m;
    c.dt = dt;
    c.gscale = 1;
    floe_contact_result r;
    law->klass->force(law, &c, hist, &r); /* the first evaluation (the onset's factor) */
    c.an_ext = kn * d / m;                /* held at rest by the other contacts */
    law->klass->force(law, &c, hist, &r);
    CHECK_NEAR(r.fn, kn * d, 1e-12, "at rest, held by others: Fn = kn d");
    const double hm = 0.5 * dt / m, vn = 0.01;
    c.an_ext = 0;
    c.vn = vn;
    law->klass->force(law, &c, hist, &r);
    CHECK_NEAR(r.fn, (kn * d + gn * vn) / (1 + gn * hm), 1e-12, "two bodies alone: the binary-collision form");
    floe_contact_law_destroy(law);
}

/* the worst |fn / (kn d) - 1| over the recorded contacts of the last evaluation */
static double worst_static(const floe_world *w, double kn, int *count) {
    const floe_contact_info *ci;
    int nc = floe_world_contacts(w, &ci);
    double e = 0;
    for (int k = 0; k < nc; k++) e = fmax(e, fabs(ci[k].fn / (kn * ci[k].depth) - 1));
    *count = nc;
    return nc > 0 ? e : INFINITY;
}

/* 2. a column of spheres on a wall at its static overlaps */
static void column(int integrator) {
    const int N = 5;
    const double R = 1e-3, rho = 2500, g = 9.81, kn = 100;
    const double m = rho * 4.0 / 3.0 * M_PI * R * R * R, gn = 2 * 0.5 * sqrt(kn * m);
    floe_world_def d = floe_default_world_def();
    d.integrator = integrator;
    floe_v3_set(d.gravity, 0, 0, -g);
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material mat = {"glass", rho, 6.3e10, 0.23};
    int mi = floe_world_add_material(w, &mat);
    floe_world_set_law(w, mi, mi, floe_linear_law_create(kn, 0, gn, 0, 0));
    int geo = floe_world_add_geometry(w, floe_sphere_create(R));
    double z = 0;
    for (int k = 0; k < N; k++) {
        const double dk = (N - k) * m * g / kn; /* the load of the spheres above and this one */
        z += k == 0 ? R - dk : 2 * R - dk;
        floe_particle_def p = floe_default_particle_def();
        p.geometry = geo;
        p.material = mi;
        floe_v3_set(p.x, 0, 0, z);
        floe_world_add_particle(w, &p);
    }
    double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, mi, FLOE_FIXED);
    floe_world_record_contacts(w, 1);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    const double dt = floe_world_dt(w), hm = 0.5 * dt / m; /* the wall pair: m* = m */
    double worst = 0;
    int nc = 0, bad = 0;
    for (int s = 0; s < 200; s++) {
        bad |= floe_world_step(w) != FLOE_OK;
        worst = fmax(worst, worst_static(w, kn, &nc));
        bad |= nc != N;
    }
    const char *name = integrator == FLOE_LEAPFROG ? "leapfrog" : integrator == FLOE_RK2 ? "rk2" : "velocity Verlet";
    printf("  column, %s: dt %.3g s, worst |Fn / (kn d) - 1| over 200 steps %.2e (the binary form's static "
           "error: %.2e at the wall, %.2e between spheres)\n", name, dt, worst, gn * hm / (1 + gn * hm),
           2 * gn * hm / (1 + 2 * gn * hm));
    CHECK(!bad, "%s: 200 steps with %d contacts", name, N);
    CHECK(worst <= 1e-9, "%s column at rest: every Fn = kn d within 1e-9 (worst %.2e)", name, worst);
    floe_world_destroy(w);
}

/* 3. a periodic rectangular lattice of discs, at rest by symmetry */
static void lattice(void) {
    const int n = 4;
    const double r = 1e-3, sx = 2 * r * (1 - 2e-3), sy = 2 * r * (1 - 1e-3), kn = 5e4, rho = 1000;
    const double m = rho * 4.0 / 3.0 * M_PI * r * r * r, gn = 2 * 0.3 * sqrt(kn * 0.5 * m); /* discs: a sphere's mass */
    floe_world_def d = floe_default_world_def();
    d.dim = 2;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material mat = {"m", rho, 1e6, 0.3};
    int mi = floe_world_add_material(w, &mat);
    floe_world_set_law(w, mi, mi, floe_linear_law_create(kn, 0, gn, 0, 0));
    int geo = floe_world_add_geometry(w, floe_sphere_create(r));
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) {
            floe_particle_def p = floe_default_particle_def();
            p.geometry = geo;
            p.material = mi;
            floe_v3_set(p.x, (a + 0.5) * sx, (b + 0.5) * sy, 0);
            floe_world_add_particle(w, &p);
        }
    double H[9] = {n * sx, 0, 0, 0, n * sy, 0, 0, 0, 1}, o[3] = {0, 0, 0};
    CHECK(floe_world_set_cell(w, o, H) == FLOE_OK, "set_cell: %s", floe_world_last_error(w));
    floe_world_record_contacts(w, 1);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    double worst = 0, sig[9], sref[9];
    int nc = 0, bad = 0;
    for (int s = 0; s < 100; s++) {
        bad |= floe_world_step(w) != FLOE_OK;
        worst = fmax(worst, worst_static(w, kn, &nc));
        bad |= nc != 2 * n * n;
    }
    CHECK(!bad, "lattice: 100 steps with %d contacts", 2 * n * n);
    CHECK(floe_world_cell_stress(w, sig, NULL) == FLOE_OK, "stress of the step");
    CHECK(floe_world_refresh_forces(w) == FLOE_OK, "refresh: %s", floe_world_last_error(w));
    CHECK(floe_world_cell_stress(w, sref, NULL) == FLOE_OK, "stress of the refresh");
    floe_particles_view pv;
    floe_world_particles(w, &pv);
    const double hm = 0.5 * floe_world_dt(w) / (0.5 * pv.mass[0]);
    printf("  periodic lattice: m %.3g kg, dt %.3g s, worst |Fn / (kn d) - 1| over 100 steps %.2e (the binary form's: %.2e); "
           "sigma_xx %.6e Pa (step) %.6e Pa (refresh), sigma_yy %.6e / %.6e, differences %.1e %.1e\n",
           pv.mass[0], floe_world_dt(w), worst, gn * hm / (1 + gn * hm), sig[0], sref[0], sig[4], sref[4],
           fabs(sig[0] / sref[0] - 1), fabs(sig[4] / sref[4] - 1));
    CHECK(worst <= 1e-9, "lattice at rest: every Fn = kn d within 1e-9 (worst %.2e)", worst);
    CHECK(fabs(sig[0] / sref[0] - 1) <= 1e-9 && fabs(sig[4] / sref[4] - 1) <= 1e-9,
          "lattice: the refresh's stress = the step's within 1e-9 (xx %.2e, yy %.2e)", fabs(sig[0] / sref[0] - 1),
          fabs(sig[4] / sref[4] - 1));
    floe_world_destroy(w);
}

int main(void) {
    law_alone();
    column(FLOE_VELOCITY_VERLET);
    column(FLOE_LEAPFROG);
    column(FLOE_RK2);
    lattice();
    return check_summary("test_dashpot_static");
}
