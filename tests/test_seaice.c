/* test_seaice.c - floes and their forcing (core/forcing, docs/sea-ice.md), through public
 * headers only:
 *  - thickness-scaled masses: a floe of thickness h weighs rho h A with inertia rho h J
 *    (polygon and disc, 1e-12), a particle without thickness keeps its mass per metre, a
 *    thickness in 3D or negative is refused with a message;
 *  - SubZero's coupling oracles (Subzero.jl test/test_physical_processes/test_coupling.jl,
 *    "OA Forcings", a 5 x 20 km floe, h = 0.25 m, default constants): force per area
 *    (2.9760, 0.8296) for a still floe in a 1 m/s current with the geostrophic tilt,
 *    (-0.1756, -0.1419) for a floe moving at (0.25, 0.1) in still water with Coriolis,
 *    (-0.0013, -6.708e-4) under a (-1, -0.5) m/s wind (to the 4 digits they print, and to
 *    1e-9 against the closed forms);
 *  - the drag torque of a disc spinning in still water, -cos(theta) 2 pi rho C_d w^2 R^5 / 5
 *    (Gauss-Legendre rings: 1e-12), of a spinning square, -rho C_d w^2 (8 a^5 / 5)
 *    int_0^{pi/4} sec^5 (1e-2 at the default level 1, 1e-5 at level 8, falling with the level);
 *  - free drift: one floe under wind, current, Coriolis and tilt reaches the steady
 *    solution of the momentum balance (solved by Newton to round-off) within 0.1 %, also
 *    with the drag integrated every 10th step and held in between;
 *  - the inertial oscillation: u - U_o turns clockwise with the period 2 pi / f (0.5 %;
 *    measured ~1e-5) and a kept amplitude (1e-9);
 *  - a Voronoi floe field (`floe_field:`): areas add up to concentration x region (1e-9),
 *    masses rho h A with h in thickness +- spread, reproducible from its seed; bad keys and
 *    ranges refused at their line;
 *  - Hopkins' ridging law against its formulas: elastic k_e d L, loading along the series
 *    ridging curve (1e-9), the permanent ridge, unloading and reloading elastic up to the
 *    hardened yield, the shear spring G h_eff and Coulomb sliding, the damped branch at a
 *    slow rate on the quasi-static curve (1e-3); two square floes edge on edge: elastic
 *    below the yield (kinetic energy back to 1e-3), ridging above it (energy lost, the
 *    ledger closing);
 *  - bonded cells: a beam bond breaks in tension, shear, compression and shear under
 *    compression (Mohr-Coulomb, friction angle 45 deg) at the step where that stress first
 *    passes its strength (the last stress before within 1 % below it); under the elliptical
 *    (Hibler-type) yield the same four motions break it where its yield function, computed
 *    here from the bond's stresses, first reaches 1 (the last value before within 2 %), in
 *    the mode of the larger term, compression raising the shear limit;
 *  - the gate_flux output: net crossings and area of floes through a gate line, by sign;
 *  - the ice_grid output: concentration, velocity and thickness per cell of a square floe;
 *  - scenes: the providers by name with thicknesses; errors (both f and latitude, a drag in
 *    3D, a gyre without length) refused with what is wrong. */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const double RHO_I = 920.0;

/* a 2D world with one ice material and a rectangle floe (half sides a, b) of thickness h */
static floe_world *ice_world(double dt, int integrator) {
    floe_world_def d = floe_default_world_def();
    d.dim = 2;
    d.mass_2d_area = 1;
    d.dt = dt;
    d.allow_unstable_dt = 1;
    d.integrator = integrator;
    d.gravity[0] = d.gravity[1] = d.gravity[2] = 0;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"ice", RHO_I, 6e6, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(1e3, 0, 0, 0, 0));
    return w;
}

static int add_rect(floe_world *w, double a, double b, double h, const double x[3], const double v[3]) {
    const double xy[8] = {-a, -b, a, -b, a, b, -a, b};
    char err[256];
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_polygon_create(xy, 4, err, sizeof err));
    p.thickness = h;
    if (x) memcpy(p.x, x, sizeof p.x);
    if (v) memcpy(p.v, v, sizeof p.v);
    return floe_world_add_particle(w, &p);
}

static void test_masses(void) {
    floe_world *w = ice_world(1.0, FLOE_VELOCITY_VERLET);
    const double a = 2500, b = 10000, h = 0.25, R = 3000;
    int i = add_rect(w, a, b, h, NULL, NULL);
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_sphere_create(R));
    p.thickness = 1.5;
    p.x[0] = 5e4;
    int j = floe_world_add_particle(w, &p);
    p.thickness = 0;
    p.x[0] = -5e4;
    int k = floe_world_add_particle(w, &p);
    CHECK(i >= 0 && j >= 0 && k >= 0, "floes added");
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    floe_particles_view v;
    floe_world_particles(w, &v);
    double A = 4 * a * b;
    CHECK_NEAR(v.mass[i], RHO_I * h * A, 1e-12, "rectangle floe: m = rho h A");
    CHECK_NEAR(v.inertia[3 * i + 2], RHO_I * h * A * (4 * a * a + 4 * b * b) / 12, 1e-12,
               "rectangle floe: I = rho h A (w^2 + l^2) / 12");
    CHECK_NEAR(v.mass[j], RHO_I * 1.5 * M_PI * R * R, 1e-12, "disc floe: m = rho h pi R^2");
    CHECK_NEAR(v.inertia[3 * j + 2], 0.5 * v.mass[j] * R * R, 1e-12, "disc floe: I = m R^2 / 2");
    CHECK_NEAR(v.mass[k], RHO_I * M_PI * R * R, 1e-12, "no thickness: mass per metre");
    CHECK(v.thickness && v.thickness[i] == h && v.thickness[k] == 0, "the view lists the thicknesses");
    floe_particle_state st;
    floe_world_get_particle(w, j, &st);
    CHECK(st.thickness == 1.5, "floe_world_get_particle: thickness %g", st.thickness);
    p.thickness = -1;
    CHECK(floe_world_add_particle(w, &p) < 0 && strstr(floe_world_last_error(w), "thickness"),
          "a negative thickness is refused: %s", floe_world_last_error(w));
    floe_world_destroy(w);
    floe_world_def d3 = floe_default_world_def();
    floe_world *w3 = floe_world_create(&d3, NULL, 0);
    floe_material m = {"ice", RHO_I, 6e6, 0.3};
    floe_world_add_material(w3, &m);
    floe_particle_def q = floe_default_particle_def();
    q.geometry = floe_world_add_geometry(w3, floe_sphere_create(1));
    q.thickness = 1;
    CHECK(floe_world_add_particle(w3, &q) < 0 && strstr(floe_world_last_error(w3), "2D"),
          "a thickness in 3D is refused: %s", floe_world_last_error(w3));
    floe_world_destroy(w3);
}

/* force per area on floe 0 after prepare */
static void force_per_area(floe_world *w, double A, double out[3]) {
    floe_particle_state st;
    floe_world_get_particle(w, 0, &st);
    out[0] = st.f[0] / A;
    out[1] = st.f[1] / A;
    out[2] = st.torque[2];
}

static void test_subzero_oracles(void) {
    const double a = 2500, b = 10000, h = 0.25, A = 4 * a * b, f = 1.4e-4;
    const double rc = 1027 * 3e-3, c15 = cos(15 * M_PI / 180), s15 = sin(15 * M_PI / 180);
    char err[256];
    /* 1. a still floe in a 1 m/s eastward current, with the geostrophic tilt */
    {
        floe_world *w = ice_world(1e-3, FLOE_VELOCITY_VERLET);
        add_rect(w, a, b, h, NULL, NULL);
        floe_drag_def od = floe_ocean_drag_default();
        od.field.U[0] = 1;
        floe_world_add_provider(w, floe_drag_create("ocean_drag", &od, err, sizeof err));
        floe_coriolis_def cd = floe_coriolis_default();
        cd.tilt = FLOE_TILT_GEOSTROPHIC;
        cd.field.U[0] = 1;
        floe_world_add_provider(w, floe_coriolis_create(&cd, err, sizeof err));
        CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
        double F[3];
        force_per_area(w, A, F);
        CHECK_NEAR(F[0], 2.9760, 5e-5, "SubZero oracle: still floe, current (1,0): F_x/A (2.9760)");
        CHECK_NEAR(F[1], 0.8296, 5e-5, "SubZero oracle: F_y/A (0.8296)");
        CHECK_NEAR(F[0], rc * c15, 1e-9, "closed form rho C cos(15)");
        CHECK_NEAR(F[1], rc * s15 + RHO_I * h * f, 1e-6, "closed form rho C sin(15) + rho_i h f");
        CHECK(fabs(F[2]) < 1e-9 * rc * A * b, "no torque on the still floe in a uniform current (%g)", F[2]);
        floe_world_destroy(w);
    }
    /* 2. a floe moving at (0.25, 0.1) in still water, with Coriolis (no tilt) */
    {
        floe_world *w = ice_world(1e-3, FLOE_VELOCITY_VERLET);
        const double v[3] = {0.25, 0.1, 0};
        add_rect(w, a, b, h, NULL, v);
        floe_drag_def od = floe_ocean_drag_default();
        floe_world_add_provider(w, floe_drag_create("ocean_drag", &od, err, sizeof err));
        floe_coriolis_def cd = floe_coriolis_default();
        floe_world_add_provider(w, floe_coriolis_create(&cd, err, sizeof err));
        CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
        double F[3];
        force_per_area(w, A, F);
        CHECK_NEAR(F[0], -0.1756, 3e-4, "SubZero oracle: moving floe, still water: F_x/A (-0.1756)");
        CHECK_NEAR(F[1], -0.1419, 3e-4, "SubZero oracle: F_y/A (-0.1419)");
        double dx = -0.25, dy = -0.1, s = rc * hypot(dx, dy);
        CHECK_NEAR(F[0], s * (c15 * dx - s15 * dy) + RHO_I * h * f * 0.1, 1e-6, "closed form, x");
        CHECK_NEAR(F[1], s * (s15 * dx + c15 * dy) - RHO_I * h * f * 0.25, 1e-6, "closed form, y");
        floe_world_destroy(w);
    }
    /* 3. a still floe under a (-1, -0.5) m/s wind */
    {
        floe_world *w = ice_world(1e-3, FLOE_VELOCITY_VERLET);
        add_rect(w, a, b, h, NULL, NULL);
        floe_drag_def wd = floe_wind_drag_default();
        wd.field.U[0] = -1;
        wd.field.U[1] = -0.5;
        floe_world_add_provider(w, floe_drag_create("wind_drag", &wd, err, sizeof err));
        CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
        double F[3];
        force_per_area(w, A, F);
        CHECK_NEAR(F[0], -0.0013, 4e-2, "SubZero oracle: wind (-1,-0.5): F_x/A (-0.0013)");
        CHECK_NEAR(F[1], -6.708e-4, 1e-4, "SubZero oracle: F_y/A (-6.708e-4)");
        CHECK_NEAR(F[0], -1.2e-3 * hypot(1, 0.5), 1e-9, "closed form rho_a C |U| U_x");
        floe_world_destroy(w);
    }
}

/* the drag torque on a floe spinning at w in still water (one provider, level lev) */
static double spin_torque(const double *xy, int nv, double R, double wz, double theta, int lev) {
    floe_world *w = ice_world(1e-3, FLOE_VELOCITY_VERLET);
    char err[256];
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, xy ? floe_polygon_create(xy, nv, err, sizeof err) : floe_sphere_create(R));
    p.thickness = 1;
    p.w[2] = wz;
    floe_world_add_particle(w, &p);
    floe_drag_def od = floe_ocean_drag_default();
    od.turning_angle = theta;
    od.quadrature = lev;
    floe_world_add_provider(w, floe_drag_create("ocean_drag", &od, err, sizeof err));
    double t = NAN;
    if (floe_world_prepare(w) == FLOE_OK) {
        floe_particle_state st;
        floe_world_get_particle(w, 0, &st);
        t = st.torque[2];
        CHECK(fabs(st.f[0]) + fabs(st.f[1]) < 1e-9 * fabs(t) / (R > 0 ? R : 1), "no net force on a spinning floe");
    }
    floe_world_destroy(w);
    return t;
}

static void test_torque(void) {
    const double rc = 1027 * 3e-3, wz = 2e-3, R = 1000;
    for (int k = 0; k < 2; k++) {
        double th = k ? 15 * M_PI / 180 : 0;
        double t = spin_torque(NULL, 0, R, wz, th, 3);
        CHECK_NEAR(t, -cos(th) * 2 * M_PI * rc * wz * wz * pow(R, 5) / 5, 1e-12,
                   k ? "disc spin torque, theta 15: -cos(theta) 2 pi rho C w^2 R^5 / 5" : "disc spin torque, theta 0");
    }
    /* a square of half side a: int r^3 dA = (8 a^5 / 5) int_0^{pi/4} sec^5 */
    const double a = 500, xy[8] = {-a, -a, a, -a, a, a, -a, a};
    const double sec3 = (sqrt(2.0) + log(1 + sqrt(2.0))) / 2, sec5 = 2 * sqrt(2.0) / 4 + 0.75 * sec3;
    const double exact = -rc * wz * wz * 8 * pow(a, 5) / 5 * sec5;
    double prev = INFINITY;
    for (int lev = 1; lev <= 8; lev *= 2) {
        double t = spin_torque(xy, 4, a, wz, 0, lev), e = fabs(t / exact - 1);
        printf("  square spin torque, level %d: rel. error %.3e\n", lev, e);
        CHECK(e < prev, "the square's torque error falls with the level (%g after %g)", e, prev);
        prev = e;
        if (lev == 1) CHECK(e < 1e-2, "square spin torque at the default level 1 within 1e-2 (%g)", e);
        if (lev == 8) CHECK(e < 1e-5, "square spin torque at level 8 within 1e-5 (%g)", e);
    }
}

/* steady free drift: solve rho_a Ca |Ua - u| (Ua - u) + rho_w Cw |Uo - u| R(th)(Uo - u) -
 * rho_i h f k x (u - Uo) = 0 by Newton (finite-difference Jacobian, to round-off) */
static void drift_residual(const double u[2], const double Ua[2], const double Uo[2], double th, double h, double f,
                           double r[2]) {
    double ax = Ua[0] - u[0], ay = Ua[1] - u[1], sa = 1.2 * 1e-3 * hypot(ax, ay);
    double ox = Uo[0] - u[0], oy = Uo[1] - u[1], so = 1027 * 3e-3 * hypot(ox, oy);
    double c = cos(th), s = sin(th), b = RHO_I * h * f;
    /* -b k x (u - Uo) = b k x (Uo - u) = b (-oy, ox) */
    r[0] = sa * ax + so * (c * ox - s * oy) - b * oy;
    r[1] = sa * ay + so * (s * ox + c * oy) + b * ox;
}

static void test_free_drift(void) {
    const double Ua[2] = {10, 2}, Uo[2] = {0.05, -0.08}, th = 15 * M_PI / 180, h = 1.0, f = 1.4e-4;
    double u[2] = {0.2, 0};
    for (int it = 0; it < 60; it++) {
        double r[2], J[2][2], e = 1e-7;
        drift_residual(u, Ua, Uo, th, h, f, r);
        for (int k = 0; k < 2; k++) {
            double up[2] = {u[0], u[1]}, rp[2];
            up[k] += e;
            drift_residual(up, Ua, Uo, th, h, f, rp);
            J[0][k] = (rp[0] - r[0]) / e;
            J[1][k] = (rp[1] - r[1]) / e;
        }
        double det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
        u[0] -= (J[1][1] * r[0] - J[0][1] * r[1]) / det;
        u[1] -= (-J[1][0] * r[0] + J[0][0] * r[1]) / det;
    }
    double r[2];
    drift_residual(u, Ua, Uo, th, h, f, r);
    CHECK(hypot(r[0], r[1]) < 1e-12, "the steady balance solved (residual %g)", hypot(r[0], r[1]));
    printf("  steady free drift: u = (%.6f, %.6f) m/s, %.2f%% of the wind\n", u[0], u[1],
           100 * hypot(u[0], u[1]) / hypot(Ua[0], Ua[1]));
    char err[256];
    for (int every = 1; every <= 10; every += 9) {
    floe_world *w = ice_world(5.0, FLOE_VELOCITY_VERLET);
    add_rect(w, 1500, 1000, h, NULL, NULL);
    floe_drag_def od = floe_ocean_drag_default();
    od.every = every;
    if (every > 1) { /* held: the drag of a floe starting at rest stays that of rest for 9 steps */
        floe_world *w1 = ice_world(5.0, FLOE_VELOCITY_VERLET);
        add_rect(w1, 1500, 1000, h, NULL, NULL);
        floe_drag_def oc = od;
        oc.field.U[0] = 0.3;
        floe_world_add_provider(w1, floe_drag_create("ocean_drag", &oc, err, sizeof err));
        floe_world_prepare(w1);
        floe_particle_state s0, s9, s10;
        floe_world_get_particle(w1, 0, &s0);
        for (int k = 0; k < 9; k++) floe_world_step(w1);
        floe_world_get_particle(w1, 0, &s9);
        floe_world_step(w1);
        floe_world_get_particle(w1, 0, &s10);
        CHECK(s9.f[0] == s0.f[0] && s9.f[1] == s0.f[1] && s10.f[0] != s0.f[0] && s9.v[0] != 0,
              "every 10: the drag is held for 9 steps and renewed at the 10th (%g %g %g)", s0.f[0], s9.f[0], s10.f[0]);
        floe_world_destroy(w1);
    }
    od.field.U[0] = Uo[0];
    od.field.U[1] = Uo[1];
    floe_world_add_provider(w, floe_drag_create("ocean_drag", &od, err, sizeof err));
    floe_drag_def wd = floe_wind_drag_default();
    wd.field.U[0] = Ua[0];
    wd.field.U[1] = Ua[1];
    wd.every = every;
    floe_world_add_provider(w, floe_drag_create("wind_drag", &wd, err, sizeof err));
    floe_coriolis_def cd = floe_coriolis_default();
    cd.tilt = FLOE_TILT_GEOSTROPHIC;
    cd.field = od.field;
    floe_world_add_provider(w, floe_coriolis_create(&cd, err, sizeof err));
    int rc = floe_world_run(w, 60000, NULL, NULL);
    CHECK(rc == FLOE_OK, "free drift run: %s", floe_world_last_error(w));
    floe_particle_state st;
    floe_world_get_particle(w, 0, &st);
    double e = hypot(st.v[0] - u[0], st.v[1] - u[1]) / hypot(u[0], u[1]);
    printf("  free drift after 60,000 s, drag every %d steps: (%.6f, %.6f), error %.2e of |u|\n", every, st.v[0],
           st.v[1], e);
    CHECK(e < 1e-3, "free drift within 0.1 %% of the steady solution (%g, drag every %d steps)", e, every);
    CHECK(fabs(st.w[2]) < 1e-12, "a symmetric floe in uniform fields does not turn (%g)", st.w[2]);
    CHECK(fabs(floe_world_energy_balance_error(w)) < 1e-3,
          "energy balance closes (%g)", floe_world_energy_balance_error(w));
    floe_world_destroy(w);
    }
}

static void test_inertial(void) {
    const double f = 1.4e-4, Uo[2] = {0.1, -0.03}, T = 2 * M_PI / f;
    char err[256];
    floe_world *w = ice_world(60.0, FLOE_VELOCITY_VERLET);
    const double v0[3] = {0.3, 0.1, 0};
    add_rect(w, 1000, 700, 0.8, NULL, v0);
    floe_coriolis_def cd = floe_coriolis_default();
    cd.f = f;
    cd.tilt = FLOE_TILT_GEOSTROPHIC;
    cd.field.U[0] = Uo[0];
    cd.field.U[1] = Uo[1];
    floe_world_add_provider(w, floe_coriolis_create(&cd, err, sizeof err));
    /* u - Uo = (u0 - Uo) exp(-i f t): the angle of u - Uo falls by f t; crossings of the
     * x axis from above (uy - Uoy through 0 with ux - Uox < 0 ... ) timed by interpolation */
    double amp0 = hypot(v0[0] - Uo[0], v0[1] - Uo[1]), amin = INFINITY, amax = 0;
    double prev_y = v0[1] - Uo[1], prev_t = 0, cross[8];
    int nc = 0;
    while (floe_world_time(w) < 3.2 * T && nc < 8) {
        if (floe_world_step(w) != FLOE_OK) break;
        floe_particle_state st;
        floe_world_get_particle(w, 0, &st);
        double ux = st.v[0] - Uo[0], uy = st.v[1] - Uo[1], t = floe_world_time(w), a = hypot(ux, uy);
        amin = fmin(amin, a);
        amax = fmax(amax, a);
        if (prev_y > 0 && uy <= 0 && ux > 0) cross[nc++] = prev_t + (t - prev_t) * prev_y / (prev_y - uy);
        prev_y = uy;
        prev_t = t;
    }
    CHECK(nc >= 3, "three downward crossings (%d)", nc);
    if (nc >= 3) {
        double Tm = (cross[nc - 1] - cross[0]) / (nc - 1);
        CHECK_NEAR(Tm, T, 5e-3, "inertial period 2 pi / f (tol 0.5 %)");
    }
    CHECK(amax - amin <= 1e-9 * amp0 && fabs(amax - amp0 * cos(0.5 * f * 60.0)) < 1e-3 * amp0,
          "the inertial amplitude is kept (%g .. %g of %g)", amin, amax, amp0);
    floe_world_destroy(w);
}

static const char *scene =
    "dimension: 2\n"
    "mass_2d: area\n"
    "time: {duration: 100, dt: 10}\n"
    "gravity: [0, 0]\n"
    "materials: [{name: ice, density: 920, young: 6e6, poisson: 0.3}]\n"
    "laws: [{materials: [ice, ice], model: linear, kn: 1e3, ks: 0}]\n"
    "bodies:\n"
    "  - {material: ice, position: [0, 0], thickness: 0.25, shape: {polygon: {vertices: [[-2500, -10000], [2500, -10000], [2500, 10000], [-2500, 10000]]}}}\n"
    "forces:\n"
    "  - {type: ocean_drag, velocity: [1, 0]}\n"
    "  - {type: coriolis, tilt: geostrophic, velocity: [1, 0]}\n";

static void expect_scene_error(const char *from, const char *to, const char *word) {
    char text[4096], err[1024] = "";
    const char *p = strstr(scene, from);
    if (!p) {
        CHECK(0, "scene text has no '%s'", from);
        return;
    }
    snprintf(text, sizeof text, "%.*s%s%s", (int)(p - scene), scene, to, p + strlen(from));
    floe_world *w = NULL;
    int rc = floe_scene_load_ex("t.yaml", text, NULL, 0, &w, NULL, err, sizeof err);
    if (rc == FLOE_OK) {
        rc = floe_world_prepare(w);
        snprintf(err, sizeof err, "%s", floe_world_last_error(w));
    }
    CHECK(rc != FLOE_OK && strstr(err, word), "'%s' refused with '%s': %s", to, word, err);
    floe_world_destroy(w);
}

static void test_scene(void) {
    char err[1024] = "";
    floe_world *w = NULL;
    int rc = floe_scene_load_ex("t.yaml", scene, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "sea-ice scene: %s", err);
    if (rc == FLOE_OK) {
        CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
        floe_particle_state st;
        floe_world_get_particle(w, 0, &st);
        const double A = 5000.0 * 20000.0;
        CHECK_NEAR(st.mass, RHO_I * 0.25 * A, 1e-12, "scene: thickness-scaled mass");
        CHECK_NEAR(st.f[1] / A, 0.8296, 5e-5, "scene: the SubZero oracle through the scene");
    }
    floe_world_destroy(w);
    expect_scene_error("tilt: geostrophic,", "f: 1e-4, latitude: 70, tilt: geostrophic,", "either f or latitude");
    expect_scene_error("tilt: geostrophic, velocity: [1, 0]", "tilt: none, velocity: [1, 0]", "only read with tilt");
    expect_scene_error("{type: ocean_drag, velocity: [1, 0]}", "{type: ocean_drag, field: gyre, speed: 1}",
                       "length must be > 0");
    expect_scene_error("thickness: 0.25", "thickness: -1", "thickness");
    /* Hopkins' critical step assumes thickness_max: a thicker floe is refused, naming it */
    expect_scene_error("model: linear, kn: 1e3, ks: 0}", "model: hopkins, thickness_max: 0.2}",
                       "0.25 m thick, more than thickness_max = 0.2 m");
    expect_scene_error("dimension: 2\nmass_2d: area\ntime: {duration: 100, dt: 10}\ngravity: [0, 0]\n",
                       "dimension: 3\ntime: {duration: 100, dt: 10}\ngravity: [0, 0, 0]\n", "2D");
}

static const char *field_scene =
    "dimension: 2\n"
    "mass_2d: area\n"
    "time: {duration: 100, dt: 10}\n"
    "gravity: [0, 0]\n"
    "materials: [{name: ice, density: 920, young: 6e6, poisson: 0.3}]\n"
    "laws: [{materials: [ice, ice], model: linear, kn: 1e3, ks: 0}]\n"
    "bodies:\n"
    "  - floe_field: {region: {min: [0, 0], max: [1e5, 5e4]}, count: 150, lloyd: 4, concentration: 0.7, seed: 7, "
    "thickness: 0.5, thickness_spread: 0.2}\n"
    "    material: ice\n";

/* a Voronoi floe field: the floes' areas add up to concentration x region, each floe's mass
 * is rho h A with h within thickness +- spread, the same seed gives the same field */
static void test_floe_field(void) {
    char err[1024] = "";
    floe_world *w = NULL, *w2 = NULL;
    int rc = floe_scene_load_ex("f.yaml", field_scene, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "floe field scene: %s", err);
    rc = rc ? rc : floe_scene_load_ex("f.yaml", field_scene, NULL, 0, &w2, NULL, err, sizeof err);
    if (rc == FLOE_OK && floe_world_prepare(w) == FLOE_OK && floe_world_prepare(w2) == FLOE_OK) {
        floe_particles_view v, v2;
        floe_world_particles(w, &v);
        floe_world_particles(w2, &v2);
        CHECK(v.n == 150, "150 floes (%d)", v.n);
        double area = 0, hmin = INFINITY, hmax = 0, same = 1;
        for (int i = 0; i < v.n; i++) {
            floe_mass_properties mp;
            floe_geometry_mass_properties(floe_world_particle_geometry(w, i), 2, 1.0, &mp);
            area += mp.volume;
            double h = v.thickness[i];
            hmin = fmin(hmin, h);
            hmax = fmax(hmax, h);
            if (fabs(v.mass[i] - 920 * h * mp.volume) > 1e-12 * v.mass[i]) same = 0;
            for (int a = 0; a < 2; a++) same = same && v.x[3 * i + a] == v2.x[3 * i + a];
            same = same && v.thickness[i] == v2.thickness[i];
        }
        CHECK_NEAR(area, 0.7 * 1e5 * 5e4, 1e-9, "floe field: total floe area = concentration x region");
        CHECK(hmin >= 0.3 && hmax <= 0.7 && hmax - hmin > 0.2, "thickness in 0.5 +- 0.2 ([%g, %g])", hmin, hmax);
        CHECK(same, "masses rho h A and the same field from the same seed");
    }
    floe_world_destroy(w);
    floe_world_destroy(w2);
    const char *bad[][3] = {{"concentration: 0.7", "concentration: 1.5", "concentration"},
                            {"thickness_spread: 0.2", "thickness_spread: 0.5", "thickness_spread"},
                            {"count: 150", "count: 0", "count"},
                            {"max: [1e5, 5e4]", "max: [1e5, -5e4]", "max must exceed min"},
                            {"lloyd: 4,", "lloyd: 4, size: 3,", "unknown key 'size'"}};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        char text[2048];
        const char *p = strstr(field_scene, bad[k][0]);
        snprintf(text, sizeof text, "%.*s%s%s", (int)(p - field_scene), field_scene, bad[k][1], p + strlen(bad[k][0]));
        floe_world *wb = NULL;
        err[0] = 0;
        rc = floe_scene_load_ex("f.yaml", text, NULL, 0, &wb, NULL, err, sizeof err);
        CHECK(rc != FLOE_OK && strstr(err, bad[k][2]) && strstr(err, "f.yaml:8:"), "'%s' refused at its line: %s",
              bad[k][1], err);
        floe_world_destroy(wb);
    }
}

/* Hopkins' ridging law against its formulas (docs/sea-ice.md "Ridging law"): two disc
 * floes of radius r and thickness h along x, driven through a prescribed overlap history */
typedef struct hk_run {
    const floe_contact_law *law;
    floe_contact c;
    double hist[FLOE_MAX_HISTORY];
} hk_run;

static double hk_step(hk_run *r, double depth, double rate, double vt, double dt, floe_contact_result *out) {
    r->c.depth = depth;
    r->c.vn = rate;
    r->c.vt[1] = vt;
    r->c.dt = dt;
    memset(out, 0, sizeof *out);
    CHECK(r->law->klass->force(r->law, &r->c, r->hist, out) == FLOE_OK, "hopkins force");
    return out->fn;
}

static void test_hopkins(void) {
    floe_hopkins_def d = floe_hopkins_default();
    const double E = d.young, rr = 500, h = 0.8, L = 4 * rr * rr / (2 * rr), ke = E * h / (2 * rr);
    const double kr = d.plastic_friction * h, kp = d.plastic_hardening * h * h;
    d.damping = 0;
    char err[256];
    hk_run r;
    memset(&r, 0, sizeof r);
    r.law = floe_hopkins_law_create(&d, err, sizeof err);
    CHECK(r.law != NULL, "hopkins created: %s", err);
    if (!r.law) return;
    r.c.n[0] = 1;
    r.c.thick_i = r.c.thick_j = h;
    r.c.rad_i = r.c.rad_j = rr;
    r.c.r_eff = rr / 2;
    r.c.m_eff = 920 * h * M_PI * rr * rr / 2;
    floe_contact_result o;
    /* elastic below the yield: F = k_e d L, the force on i along -n, energy k_e L d^2 / 2 */
    const double dy = kr / ke; /* the yield overlap */
    double F = hk_step(&r, 0.5 * dy, 1e-3, 0, 1.0, &o);
    CHECK_NEAR(F, ke * 0.5 * dy * L, 1e-12, "hopkins elastic: F = k_e d L");
    CHECK_NEAR(o.force[0], -F, 1e-15, "hopkins: the force pushes i away from j");
    CHECK_NEAR(o.energy, 0.5 * ke * L * 0.25 * dy * dy, 1e-12, "hopkins elastic energy k_e L d^2 / 2");
    /* loading at a steady rate: beyond the yield the series law
     * F/L = k_e (k_p d + k_r) / (k_p + k_e) (eta = 0), the ridge d_p = d - F / (k_e L) */
    const int N = 2000;
    const double dmax = 50 * dy, dt = 1.0, rate = dmax / (N * dt);
    double worst = 0;
    for (int k = 1; k <= N; k++) {
        double dk = dmax * k / N;
        F = hk_step(&r, dk, rate, 0, dt, &o);
        double ref = fmin(ke * dk, ke * (kp * dk + kr) / (kp + ke)) * L;
        worst = fmax(worst, fabs(F - ref) / ref);
    }
    CHECK(worst < 1e-9, "hopkins loading follows min(elastic, series ridging) (worst %.2e)", worst);
    const double dp = dmax - F / (ke * L);
    CHECK_NEAR(r.hist[0], dp, 1e-9, "hopkins: the plastic ridge d_p = d - F/(k_e L)");
    CHECK(dp > 0.9 * dmax, "most of the overlap is ridge (%g of %g)", dp, dmax);
    /* unloading: elastic from the ridge, no load behind it, the ridge kept */
    F = hk_step(&r, dmax - 0.5 * (dmax - dp), -rate, 0, dt, &o);
    CHECK_NEAR(F, ke * 0.5 * (dmax - dp) * L, 1e-9, "hopkins unloading: elastic from the ridge");
    F = hk_step(&r, 0.5 * dp, -rate, 0, dt, &o);
    CHECK(F == 0 && fabs(r.hist[0] - dp) < 1e-9 * dp, "hopkins: no load behind the ridge, which stays (F %g, d_p %g)", F, r.hist[0]);
    /* reloading: elastic from d_p up to the hardened yield k_r + k_p d_p */
    F = hk_step(&r, dp + 0.5 * (kr + kp * dp) / ke, rate, 0, dt, &o);
    CHECK_NEAR(F, 0.5 * (kr + kp * dp) * L, 1e-9, "hopkins reloading: elastic below the hardened yield");
    /* tangential: stick with k_t = G h_eff, then Coulomb sliding */
    const double kt = E / (2 * (1 + d.poisson)) * (h / 2), Fn = F;
    double sl = 1e-4 * Fn / kt;
    hk_step(&r, r.c.depth, 0, sl / dt, dt, &o);
    CHECK_NEAR(o.force[1], -kt * sl, 1e-9, "hopkins shear spring k_t = G h_eff");
    hk_step(&r, r.c.depth, 0, 1e4 * sl / dt, dt, &o);
    CHECK_NEAR(o.force[1], -d.friction * Fn, 1e-9, "hopkins Coulomb sliding mu F");
    /* damped ridging: at a slow rate the backward-Euler Maxwell branch tends to the
     * quasi-static series curve */
    floe_contact_law_class const *K = r.law->klass;
    K->destroy((floe_contact_law *)r.law);
    d.damping = 0.1;
    r.law = floe_hopkins_law_create(&d, err, sizeof err);
    memset(r.hist, 0, sizeof r.hist);
    const double slow = dmax / 2e6;
    for (int k = 1; k <= N; k++) F = hk_step(&r, dmax * k / N, slow, 0, dmax / N / slow, &o);
    CHECK_NEAR(F, ke * (kp * dmax + kr) / (kp + ke) * L, 1e-3, "hopkins damped, slow: the quasi-static ridging force");
    r.law->klass->destroy((floe_contact_law *)r.law);
    d.plastic_hardening = -1;
    CHECK(floe_hopkins_law_create(&d, err, sizeof err) == NULL && strstr(err, "plastic_hardening"),
          "a negative hardening is refused: %s", err);
}

/* two square floes (side 1 km, h = 1 m) meeting edge on edge under Hopkins' law without
 * damping: below the yield the collision is elastic (kinetic energy back to 1e-3, the
 * overlap-area measure keeps the force conservative where the deepest point would jump);
 * above it they ridge (energy dissipated, a permanent ridge), and the ledger closes */
static double hk_collide(double vrel, double *balance, double *ke0) {
    floe_world_def d = floe_default_world_def();
    d.dim = 2;
    d.mass_2d_area = 1;
    d.gravity[0] = d.gravity[1] = d.gravity[2] = 0;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"ice", RHO_I, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_hopkins_def hd = floe_hopkins_default();
    hd.young = 1e7;
    hd.damping = 0;
    hd.thickness_max = 1;
    char err[256];
    floe_world_set_law(w, 0, 0, floe_hopkins_law_create(&hd, err, sizeof err));
    const double xa[3] = {-505, 0, 0}, xb[3] = {505, 0, 0}, va[3] = {vrel / 2, 0, 0}, vb[3] = {-vrel / 2, 0, 0};
    add_rect(w, 500, 500, 1.0, xa, va);
    add_rect(w, 500, 500, 1.0, xb, vb);
    double t_end = 40 / (vrel > 0 ? vrel : 1) + 200;
    int rc = floe_world_run(w, t_end, NULL, NULL);
    CHECK(rc == FLOE_OK, "hopkins collision at %g m/s: %s", vrel, floe_world_last_error(w));
    floe_energy e = floe_world_energy(w);
    *balance = floe_world_energy_balance_error(w);
    *ke0 = e.initial;
    double ke = e.kinetic_trans + e.kinetic_rot;
    floe_particle_state a, b;
    floe_world_get_particle(w, 0, &a);
    floe_world_get_particle(w, 1, &b);
    CHECK(a.v[0] < 0 && b.v[0] > 0, "the floes separate (%g, %g)", a.v[0], b.v[0]);
    floe_world_destroy(w);
    return ke;
}

static void test_hopkins_polygons(void) {
    double bal, ke0;
    double ke = hk_collide(0.2, &bal, &ke0);
    CHECK_NEAR(ke, ke0, 1e-3, "hopkins, polygons edge on edge below the yield: kinetic energy back (elastic)");
    CHECK(fabs(bal) < 1e-4, "energy balance %g", bal);
    ke = hk_collide(2.0, &bal, &ke0);
    printf("  hopkins ridging collision at 2 m/s: %.1f %% of the kinetic energy left\n", 100 * ke / ke0);
    CHECK(ke < 0.9 * ke0 && ke > 0, "hopkins above the yield: the floes ridge and lose energy (%g of %g)", ke, ke0);
    CHECK(fabs(bal) < 1e-3, "energy balance with ridging %g", bal);
}

/* bonded cells (beam bonds, docs/sea-ice.md "Bonded floes"): two discs, one fixed, the
 * other moved at a constant speed (pulled, pushed, sheared, or pushed then sheared); the
 * bond breaks in the mode asked, at the step where its stress first passes the strength:
 * the last stress before the break is within 1 % below the strength */
typedef struct mc_motion {
    double t1, u;
} mc_motion;

static void mc_move(double t, double v[3], double om[3], void *user) {
    const mc_motion *m = user;
    v[0] = t < m->t1 ? -m->u : 0; /* pushed, then sheared */
    v[1] = t < m->t1 ? 0 : m->u;
    v[2] = 0;
    om[0] = om[1] = om[2] = 0;
}

static void bond_mode(int mode, double phi) {
    static const char *const what[] = {"", "tension", "shear", "compression", "shear under compression"};
    floe_world_def d = floe_default_world_def();
    d.dim = 2;
    d.mass_2d_area = 1;
    d.dt = 1e-3;
    d.allow_unstable_dt = 1;
    d.gravity[0] = d.gravity[1] = d.gravity[2] = 0;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"ice", RHO_I, 1e9, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(1e6, 0, 0, 0, 0));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_sphere_create(1.0));
    p.motion = FLOE_FIXED;
    floe_world_add_particle(w, &p);
    /* the moved cell: kinematic at a constant velocity (a strain of 5e-8 per step) */
    const double u = 1e-4;
    p.x[0] = 2.0;
    p.motion = FLOE_KINEMATIC;
    p.v[0] = mode == 1 ? u : mode == 3 ? -u : 0;
    p.v[1] = mode == 2 ? u : 0;
    floe_world_add_particle(w, &p);
    mc_motion mm = {2e-4 / u, u}; /* pushed by 0.2 mm (N/A = -1e5 Pa), then sheared */
    if (mode == 4) floe_world_set_motion(w, 1, mc_move, &mm);
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 1e9;
    bp.poisson = 0.3;
    const double lim = 2e5;
    if (mode == 1) bp.tensile_strength = lim;
    if (mode == 2 || mode == 4) bp.shear_strength = lim;
    if (mode == 3) bp.compressive_strength = lim;
    bp.friction_angle = phi;
    CHECK(floe_world_add_beam_bond(w, 0, 1, &bp) >= 0, "bond: %s", floe_world_last_error(w));
    floe_beam_bond_info prev, b;
    memset(&prev, 0, sizeof prev);
    int broke = 0;
    for (long k = 0; k < 200000 && !broke; k++) {
        if (floe_world_step(w) != FLOE_OK) break;
        floe_world_beam_bond(w, 0, &b);
        if (b.broken) broke = 1;
        else prev = b;
    }
    CHECK(broke && b.mode == (mode == 4 ? 2 : mode), "%s: the bond broke in mode %d (got %d)", what[mode],
          mode == 4 ? 2 : mode, b.mode);
    /* the stress of that mode at the last step before the break, and its limit */
    double s = mode == 1 ? prev.sigma : mode == 3 ? prev.sigma_c : prev.tau;
    double l = mode == 4 ? lim + tan(phi * M_PI / 180) * 0.5 * (prev.sigma_c - prev.sigma) : lim;
    printf("  bond breaks in %-24s at %.6g Pa (strength %.6g Pa)\n", what[mode], s, l);
    CHECK(s <= l && s >= 0.99 * l, "%s: the last stress before the break %g is within 1 %% below the strength %g",
          what[mode], s, l);
    if (mode == 4) CHECK(l > 1.4 * lim, "Mohr-Coulomb: compression raised the shear limit (%g)", l);
    floe_world_destroy(w);
}

/* the elliptical yield (FLOE_BEAM_YIELD_ELLIPSE): sigma_t = 2e5, sigma_c = 6e5, tau_s = 3e5
 * Pa; the same motions as bond_mode. Shear at N = 0 breaks at tau_s sqrt(1 - (s0/a)^2) =
 * 2.598e5 Pa; after a push to N/A = -1e5 Pa at tau_s sqrt(1 - ((-1e5 - s0)/a)^2) = 2.905e5. The yield function of the bond's last stresses before
 * the break, computed here, is in [0.98, 1); the mode is the larger term's. */
static double ellipse_f(const floe_beam_bond_info *b, double st, double sc, double ts) {
    const double s0 = 0.5 * (st - sc), a = 0.5 * (st + sc), y = (b->tau / ts) * (b->tau / ts);
    const double xp = ((b->sigma - s0) / a) * ((b->sigma - s0) / a), xm = ((-b->sigma_c - s0) / a) * ((-b->sigma_c - s0) / a);
    return (xp > xm ? xp : xm) + y;
}

static double bond_ellipse(int mode) {
    static const char *const what[] = {"", "tension", "shear", "compression", "shear under compression"};
    const double st = 2e5, sc = 6e5, ts = 3e5;
    floe_world_def d = floe_default_world_def();
    d.dim = 2;
    d.mass_2d_area = 1;
    d.dt = 1e-3;
    d.allow_unstable_dt = 1;
    d.gravity[0] = d.gravity[1] = d.gravity[2] = 0;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"ice", RHO_I, 1e9, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(1e6, 0, 0, 0, 0));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_sphere_create(1.0));
    p.motion = FLOE_FIXED;
    floe_world_add_particle(w, &p);
    const double u = 1e-4;
    p.x[0] = 2.0;
    p.motion = FLOE_KINEMATIC;
    p.v[0] = mode == 1 ? u : mode == 3 ? -u : 0;
    p.v[1] = mode == 2 ? u : 0;
    floe_world_add_particle(w, &p);
    mc_motion mm = {2e-4 / u, u}; /* pushed by 0.2 mm (N/A = -1e5 Pa), then sheared */
    if (mode == 4) floe_world_set_motion(w, 1, mc_move, &mm);
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 1e9;
    bp.poisson = 0.3;
    bp.tensile_strength = st;
    bp.compressive_strength = sc;
    bp.shear_strength = ts;
    bp.yield = FLOE_BEAM_YIELD_ELLIPSE;
    /* the section of the 2 m x 1 m rectangle (A, I) but a large section modulus: bending
     * stress small against the shear stress, so that a sideways motion breaks the bond in
     * shear (with the rectangle's W the bending fibre, twice the shear stress, breaks it in
     * tension first) */
    bp.area = 2.0;
    bp.inertia = 2.0 / 3.0;
    bp.section_modulus = 20.0;
    CHECK(floe_world_add_beam_bond(w, 0, 1, &bp) >= 0, "ellipse bond: %s", floe_world_last_error(w));
    floe_beam_bond_info prev, b;
    memset(&prev, 0, sizeof prev);
    memset(&b, 0, sizeof b);
    int broke = 0;
    for (long k = 0; k < 400000 && !broke; k++) {
        if (floe_world_step(w) != FLOE_OK) break;
        floe_world_beam_bond(w, 0, &b);
        if (b.broken) broke = 1;
        else prev = b;
    }
    const int want = mode == 4 ? 2 : mode;
    CHECK(broke && b.mode == want, "ellipse, %s: broke in mode %d (got %d)", what[mode], want, b.mode);
    const double F = ellipse_f(&prev, st, sc, ts);
    printf("  ellipse: breaks in %-24s yield function before %.5f; %.6g Pa of %.6g Pa\n", what[mode], F,
           b.stress_broken, b.strength_broken);
    CHECK(F < 1 && F >= 0.98, "ellipse, %s: the yield function before the break %g in [0.98, 1)", what[mode], F);
    CHECK(b.stress_broken >= b.strength_broken && b.stress_broken <= 1.02 * b.strength_broken,
          "ellipse, %s: the break's stress %g just past the envelope %g", what[mode], b.stress_broken,
          b.strength_broken);
    floe_world_destroy(w);
    return b.strength_broken;
}

/* the gate_flux output: two floes moving south and one north across a gate from (0, 0) to
 * (10 km, 0) (its right side is south), one floe passing beside it: 2 - 1 = 1 net crossing
 * and the net area of the southbound ones minus the northbound one */
static void test_gate_flux(void) {
    char dir[] = "/tmp/floe_gate_XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return;
    }
    const char *text =
        "dimension: 2\nmass_2d: area\ntime: {duration: 4000, dt: 10}\ngravity: [0, 0]\n"
        "materials: [{name: ice, density: 920, young: 6e6, poisson: 0.3}]\n"
        "laws: [{materials: [ice, ice], model: none}]\n"
        "bodies:\n"
        "  - {material: ice, position: [2000, 1000], velocity: [0, -1], thickness: 1, shape: {polygon: {vertices: "
        "[[-500, -500], [500, -500], [500, 500], [-500, 500]]}}}\n"
        "  - {material: ice, position: [6000, 1500], velocity: [0, -1], thickness: 1, shape: {polygon: {vertices: "
        "[[-300, -300], [300, -300], [300, 300], [-300, 300]]}}}\n"
        "  - {material: ice, position: [8000, -1000], velocity: [0, 1], thickness: 1, shape: {polygon: {vertices: "
        "[[-200, -200], [200, -200], [200, 200], [-200, 200]]}}}\n"
        "  - {material: ice, position: [15000, 1000], velocity: [0, -1], thickness: 1, shape: {polygon: {vertices: "
        "[[-400, -400], [400, -400], [400, 400], [-400, 400]]}}}\n"
        "outputs:\n"
        "  - {type: gate_flux, interval: 100, file: gate.csv, from: [0, 0], to: [10000, 0]}\n";
    char err[1024] = "";
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_ex("t.yaml", text, dir, 1, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "gate scene: %s", err);
    if (rc == FLOE_OK) {
        CHECK(floe_world_run(w, info.duration, NULL, NULL) == FLOE_OK, "gate run: %s", floe_world_last_error(w));
        floe_world_finish(w);
    }
    floe_world_destroy(w);
    char path[256], line[256], last[256] = "";
    snprintf(path, sizeof path, "%s/gate.csv", dir);
    FILE *f = fopen(path, "r");
    CHECK(f != NULL, "gate.csv written");
    while (f && fgets(line, sizeof line, f)) snprintf(last, sizeof last, "%s", line);
    if (f) fclose(f);
    double t = 0, area = 0, rate = 0;
    long n = 0;
    CHECK(sscanf(last, "%lf,%ld,%lf,%lf", &t, &n, &area, &rate) == 4, "gate row: %s", last);
    CHECK(n == 1, "gate: 2 southbound - 1 northbound = 1 net crossing (%ld)", n);
    CHECK_NEAR(area, 1000.0 * 1000 + 600 * 600 - 400 * 400, 1e-9, "gate: net area through (southbound - northbound)");
    remove(path);
    rmdir(dir);
}

/* the ice_grid output: a 2 km square floe (h = 0.5 m, moving and spinning) on the 1 km cells
 * of a 4 x 4 grid: concentration 1 in the four cells it covers and 0 elsewhere, the cells'
 * velocity v + w k x (cell centre - floe centre), thickness 0.5 */
static int read_array(const char *text, const char *name, int n, int ncomp, double *out) {
    char key[64];
    snprintf(key, sizeof key, "Name=\"%s\"", name);
    const char *p = strstr(text, key);
    if (!p || !(p = strchr(p, '>'))) return 0;
    p++;
    for (int k = 0; k < n * ncomp; k++) {
        char *end;
        out[k] = strtod(p, &end);
        if (end == p) return 0;
        p = end;
    }
    return 1;
}

static void test_ice_grid(void) {
    char dir[] = "/tmp/floe_grid_XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return;
    }
    const char *text =
        "dimension: 2\nmass_2d: area\ntime: {duration: 1e-6, dt: 1e-6}\ngravity: [0, 0]\n"
        "materials: [{name: ice, density: 920, young: 6e6, poisson: 0.3}]\n"
        "laws: [{materials: [ice, ice], model: none}]\n"
        "bodies:\n"
        "  - {material: ice, position: [1000, 1000], velocity: [0.2, -0.1], angular_velocity: [0, 0, 1e-3], "
        "thickness: 0.5, shape: {polygon: {vertices: [[-1000, -1000], [1000, -1000], [1000, 1000], [-1000, 1000]]}}}\n"
        "outputs:\n"
        "  - {type: ice_grid, every: 1, prefix: grid, min: [0, 0], max: [4000, 4000], nx: 4, ny: 4, samples: 4}\n";
    char err[1024] = "";
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_ex("t.yaml", text, dir, 1, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "ice_grid scene: %s", err);
    if (rc == FLOE_OK) {
        CHECK(floe_world_run(w, info.duration, NULL, NULL) == FLOE_OK, "run: %s", floe_world_last_error(w));
        floe_world_finish(w);
    }
    floe_world_destroy(w);
    char path[256];
    snprintf(path, sizeof path, "%s/grid_000000.vtu", dir);
    FILE *f = fopen(path, "r");
    static char buf[1 << 16];
    size_t len = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
    if (f) fclose(f);
    buf[len] = 0;
    double c[16], v[48], h[16];
    int ok = read_array(buf, "concentration", 16, 1, c) && read_array(buf, "velocity", 16, 3, v) &&
             read_array(buf, "thickness", 16, 1, h);
    CHECK(ok, "ice_grid: frame 0 read (%s)", path);
    if (ok) {
        int right = 1;
        double werr = 0;
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++) {
                const int k = j * 4 + i, in = i < 2 && j < 2;
                right = right && c[k] == (in ? 1.0 : 0.0) && h[k] == (in ? 0.5 : 0.0);
                if (in) {
                    const double rx = 500 + 1000 * i - 1000, ry = 500 + 1000 * j - 1000;
                    werr = fmax(werr, fabs(v[3 * k] - (0.2 - 1e-3 * ry)) + fabs(v[3 * k + 1] - (-0.1 + 1e-3 * rx)));
                }
            }
        CHECK(right, "ice_grid: concentration 1 and thickness 0.5 in the 4 covered cells, 0 elsewhere");
        CHECK(werr < 1e-9, "ice_grid: cell velocity v + w k x r (error %g)", werr);
    }
    char cmd[300];
    snprintf(cmd, sizeof cmd, "%s/grid.pvd", dir);
    CHECK(access(cmd, F_OK) == 0, "ice_grid: the .pvd series is written");
    for (int k = 0; k < 4; k++) {
        snprintf(cmd, sizeof cmd, "%s/grid_%06d.vtu", dir, k);
        remove(cmd);
    }
    snprintf(cmd, sizeof cmd, "%s/grid.pvd", dir);
    remove(cmd);
    rmdir(dir);
}

int main(void) {
    char err[256];
    floe_register_builtins(err, sizeof err);
    test_masses();
    test_subzero_oracles();
    test_torque();
    test_free_drift();
    test_inertial();
    test_scene();
    test_floe_field();
    test_hopkins();
    test_hopkins_polygons();
    for (int mode = 1; mode <= 4; mode++) bond_mode(mode, mode == 4 ? 45.0 : 0.0);
    {
        double lim[5] = {0};
        for (int mode = 1; mode <= 4; mode++) lim[mode] = bond_ellipse(mode);
        /* pure pull: the tensile strength; push: the compressive one (bending is nil) */
        CHECK_NEAR(lim[1], 2e5, 1e-6, "ellipse: a pull breaks at sigma_t");
        CHECK_NEAR(lim[3], 6e5, 1e-6, "ellipse: a push breaks at sigma_c");
        CHECK(lim[4] > lim[2], "ellipse: compression raises the shear limit (%g > %g)", lim[4], lim[2]);
        /* near the envelope's values at N = 0 and N/A = -1e5 Pa; the bending fibre (1/15 of tau
         * here) moves them by a few per cent */
        CHECK_NEAR(lim[2], 3e5 * sqrt(0.75), 5e-2, "ellipse: shear at N = 0");
        CHECK_NEAR(lim[4], 3e5 * sqrt(1 - 0.0625), 5e-2, "ellipse: shear after a push to -1e5 Pa");
    }
    test_gate_flux();
    test_ice_grid();
    return check_summary("test_seaice");
}
