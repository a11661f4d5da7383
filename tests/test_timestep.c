/* test_timestep.c - critical time-step estimates (floe_world_dt_estimates) against their
 * closed forms and against a measured collision, the refusal of a fixed step above the
 * critical one, adaptive steps (003 §4.3: the stated criterion holds on every accepted
 * step, rejected steps are undone exactly, restitution as with a fixed small step, the run
 * ends at t_end, an unstable dt_max is rescued by rejection) and the scene keys. */
#include "check.h"
#include "floe_scene.h"
#include "floe_pd.h"
#include "floe.h"
#include "world_read.h"

#include <string.h>

/* the adaptive step's bounds in use: 0 lower, 1 upper */
static double adapt_bound(const floe_world *w, int upper) {
    double lo = 0, hi = 0;
    floe_world_adaptive_bounds(w, &lo, &hi);
    return upper ? hi : lo;
}

static floe_world *linear_pair(double kn, double ks, double r1, double r2, int *small) {
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(kn, ks, 0, 0, 0.5));
    floe_particle_def a = floe_default_particle_def(), b = floe_default_particle_def();
    a.geometry = floe_world_add_geometry(w, floe_sphere_create(r1));
    b.geometry = floe_world_add_geometry(w, floe_sphere_create(r2));
    b.x[0] = 1.0; /* far apart */
    floe_world_add_particle(w, &a);
    *small = floe_world_add_particle(w, &b);
    return w;
}

static void test_closed_forms(void) {
    const double kn = 1e3, r1 = 2e-3, r2 = 1e-3;
    int small;
    floe_world *w = linear_pair(kn, 0, r1, r2, &small);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    floe_dt_estimates e;
    floe_world_dt_estimates(w, &e);
    double m = 2500 * 4.0 / 3.0 * M_PI * r2 * r2 * r2;
    /* caged particle: w^2 = 8 kn / m (C = 2 n_c / d = 8 in 3D), dt = 2 / w */
    CHECK_NEAR(e.dt[FLOE_DT_CONTACT_PACKING], 2 / sqrt(8 * kn / m), 1e-12, "packing estimate = 2 / sqrt(8 kn / m)");
    /* one contact: C = 2 */
    CHECK_NEAR(e.dt[FLOE_DT_CONTACT_IMPACT], 2 / sqrt(2 * kn / m), 1e-12, "impact estimate = 2 / sqrt(2 kn / m)");
    /* 000 eq 43 with the 12 contacts of a close packing */
    CHECK_NEAR(e.dt[FLOE_DT_DEM_SQRT_MK], sqrt(m / (12 * kn)), 1e-12, "000 eq 43: sqrt(m / (12 kn))");
    CHECK(e.limiting == FLOE_DT_CONTACT_PACKING && e.limiting_particle == small,
          "the smaller particle's packing limits (kind %d, particle %d)", e.limiting, e.limiting_particle);
    CHECK(e.critical == floe_world_critical_dt(w), "critical = floe_world_critical_dt");
    /* per particle: m ~ R^3, so the estimate scales as R^(3/2) */
    CHECK_NEAR(floe_world_particle_critical_dt(w, 0) / floe_world_particle_critical_dt(w, small), pow(2.0, 1.5), 1e-12,
               "per-particle estimates scale as R^(3/2)");
    CHECK(!isfinite(e.dt[FLOE_DT_RAYLEIGH]) && !isfinite(e.dt[FLOE_DT_PD_NODAL]) && !isfinite(e.dt[FLOE_DT_MOTION]),
          "no Rayleigh (no Hertz law), PD or motion estimate here");
    CHECK(e.limits[FLOE_DT_CONTACT_PACKING] && !e.limits[FLOE_DT_RAYLEIGH] && !e.limits[FLOE_DT_DEM_SQRT_MK],
          "which kinds limit");
    floe_world_destroy(w);
    /* the tangential spring acts on the reduced mass m / (1 + m R^2 / I) = m / 3.5 */
    w = linear_pair(kn, kn, r1, r2, &small);
    floe_world_prepare(w);
    floe_world_dt_estimates(w, &e);
    CHECK_NEAR(e.dt[FLOE_DT_CONTACT_PACKING], 2 / sqrt(8 * 3.5 * kn / m), 1e-12, "packing with ks: 2 / sqrt(8 x 3.5 ks / m)");
    floe_world_destroy(w);
}

/* polytopes: the contact manifold's corner springs (docs/models.md, "Contact manifold"):
 * the stiffness multiplier against closed forms, and the impact estimate of a thin plate */
static void test_manifold_factor(void) {
    const double a = 1.0, h = 0.01, m = 1.0;
    double Icube[3] = {m * a * a / 6, m * a * a / 6, m * a * a / 6};
    double Iplate[3] = {m * (a * a + h * h) / 12, m * (a * a + h * h) / 12, m * a * a / 6};
    floe_geometry *cube = floe_box_create(a, a, a), *plate = floe_box_create(a, a, h), *rect = floe_box_create(a, h, h);
    /* cube: 4 corners at (+-a/2, +-a/2): rocking sum (a/2)^2 x 4 = a^2 over m a^2/6 */
    CHECK_NEAR(floe_polytope_manifold_factor(cube, 3, Icube, m), 6.0, 1e-12, "cube: manifold factor 6");
    CHECK_NEAR(floe_polytope_manifold_factor(plate, 3, Iplate, m), 12.0 / (1 + h * h / (a * a)), 1e-12,
               "thin plate: 12 a^2 / (a^2 + h^2)");
    /* 2D: a square's edge, two corners at +-a/2 about z: (a^2/2) / (m a^2/6) = 3; a thin
     * rectangle's long edge: (a^2/2) / (m (a^2 + h^2)/12) */
    double Isq[3] = {0, 0, m * a * a / 6}, Irect[3] = {0, 0, m * (a * a + h * h) / 12};
    CHECK_NEAR(floe_polytope_manifold_factor(cube, 2, Isq, m), 3.0, 1e-12, "2D square: manifold factor 3");
    CHECK_NEAR(floe_polytope_manifold_factor(rect, 2, Irect, m), 6.0 / (1 + h * h / (a * a)), 1e-12,
               "2D thin rectangle: 6 a^2 / (a^2 + h^2)");
    floe_geometry *sph = floe_sphere_create(1.0);
    CHECK(floe_polytope_manifold_factor(sph, 3, Icube, m) == 0.0, "a sphere has no manifold");
    floe_geometry_destroy(cube); floe_geometry_destroy(rect); floe_geometry_destroy(sph);
    /* through the world: a free thin plate over a wall, linear law (no tangential spring):
     * impact estimate 2 / sqrt(2 kn r / m), r = the plate's factor (the bounding-radius
     * estimate 1 + m R^2 / I_min = 7 is lower) */
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material mat = {"m", 1000, 1e7, 0.3};
    floe_world_add_material(w, &mat);
    const double kn = 1e4;
    floe_world_set_law(w, 0, 0, floe_linear_law_create(kn, 0, 0, 0, 0.5));
    double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
    floe_world_add_wall(w, o, nz, 0, FLOE_FIXED);
    floe_particle_def pd = floe_default_particle_def();
    pd.geometry = floe_world_add_geometry(w, plate);
    pd.x[2] = 1.0;
    int i = floe_world_add_particle(w, &pd);
    CHECK(floe_world_prepare(w) == FLOE_OK, "plate prepare: %s", floe_world_last_error(w));
    floe_dt_estimates e;
    floe_world_dt_estimates(w, &e);
    const double mp = pview(w).mass[i], r = 12.0 / (1 + h * h / (a * a));
    CHECK_NEAR(e.dt[FLOE_DT_CONTACT_IMPACT], 2 / sqrt(2 * kn * r / mp), 1e-9,
               "thin plate: impact estimate 2 / sqrt(2 kn x 12 / m)");
    floe_world_destroy(w);
}

/* Hertz: the Rayleigh step from its formula and the Hertz contact duration against a
 * measured undamped head-on collision at the expected relative speed */
static void test_hertz(void) {
    const double R = 0.01, E = 1e7, nu = 0.3, rho = 2500, v = 1.0;
    floe_world_def d = floe_default_world_def();
    d.dt_safety = 0.02;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", rho, E, nu};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 1.0, 0.0));
    int g = floe_world_add_geometry(w, floe_sphere_create(R));
    floe_particle_def a = floe_default_particle_def(), b = floe_default_particle_def();
    a.geometry = b.geometry = g;
    a.v[0] = v;
    b.v[0] = -v;
    b.x[0] = 2 * R; /* touching: the collision starts at once at relative speed 2 v */
    floe_world_add_particle(w, &a);
    floe_world_add_particle(w, &b);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    floe_dt_estimates e;
    floe_world_dt_estimates(w, &e);
    double G = E / (2 * (1 + nu));
    CHECK_NEAR(e.dt[FLOE_DT_RAYLEIGH], M_PI * R * sqrt(rho / G) / (0.1631 * nu + 0.8766), 1e-12, "Rayleigh step formula");
    CHECK_NEAR(e.v_expected, 2 * v, 1e-12, "expected relative speed = 2 x the fastest particle");
    long steps = 0, in = 0;
    int rc = FLOE_OK;
    while (rc == FLOE_OK && steps < 1000000) {
        rc = floe_world_step(w);
        steps++;
        if (floe_world_contact_count(w)) in++;
        else if (in) break;
    }
    CHECK(rc == FLOE_OK, "collision: %s", floe_world_last_error(w));
    double tc = in * floe_world_dt(w);
    printf("  Hertz collision at %g m/s: %ld steps in contact, duration %.5g s, estimate 2.87 (m*^2/(R* E*^2 v))^(1/5) "
           "= %.5g s, Rayleigh %.4g s, critical %.4g s\n", 2 * v, in, tc, e.dt[FLOE_DT_HERTZ], e.dt[FLOE_DT_RAYLEIGH],
           e.critical);
    CHECK_NEAR(tc, e.dt[FLOE_DT_HERTZ], 0.01, "measured Hertz contact duration vs 2.87 (...)^(1/5) (tol 1 %)");
    floe_world_destroy(w);
}

static void test_pd_estimates(void) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = 1e-3;
    r.horizon_factor = 3;
    floe_v3_set(r.hi, 6e-3, 5e-3, 4e-3);
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create(&b, &r) == FLOE_OK, "PD body");
    floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
    floe_pd_set_material(b, &pm);
    double nodal = floe_pd_dt_nodal(b), cfl = floe_pd_dt_cfl(b);
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rock", 2200, 1e5, 0.25}; /* soft contact: the PD nodal step limits */
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.3));
    floe_world_add_pd_body(w, b, 0, NULL, NULL);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    floe_dt_estimates e;
    floe_world_dt_estimates(w, &e);
    CHECK_NEAR(e.dt[FLOE_DT_PD_NODAL], nodal, 1e-12, "PD nodal estimate = floe_pd_dt_nodal");
    CHECK_NEAR(e.dt[FLOE_DT_PD_CFL], cfl, 1e-12, "PD CFL estimate = floe_pd_dt_cfl (000 eqs 41-42)");
    CHECK_NEAR(e.critical_pd, nodal, 1e-12, "critical_pd");
    printf("  PD block: nodal %.4g s, CFL %.4g s, contact %.4g s, limiting %s\n", nodal, cfl, e.critical_contact,
           floe_dt_kind_name(e.limiting));
    /* interior points have the full family: the corner point the smallest sum, the largest step */
    int first = -1, corner = -1, mid = -1;
    const floe_pd_body *pb = floe_world_pd_body(w, 0, &first);
    double dc = INFINITY, dm = INFINITY;
    for (int i = 0; i < pb->n; i++) {
        const double *X = pb->X + 3 * (size_t)i;
        double c2 = X[0] * X[0] + X[1] * X[1] + X[2] * X[2];
        double m2 = (X[0] - 3e-3) * (X[0] - 3e-3) + (X[1] - 2.5e-3) * (X[1] - 2.5e-3) + (X[2] - 2e-3) * (X[2] - 2e-3);
        if (c2 < dc) { dc = c2; corner = i; }
        if (m2 < dm) { dm = m2; mid = i; }
    }
    double t_corner = floe_world_particle_critical_dt(w, first + corner);
    double t_mid = floe_world_particle_critical_dt(w, first + mid);
    double t_global = e.critical_pd < e.critical_contact ? e.critical_pd : e.critical_contact;
    printf("  per-point critical dt: corner %.4g s, interior %.4g s, global %.4g s\n", t_corner, t_mid, t_global);
    CHECK(t_corner >= t_mid, "the corner point (fewest bonds) has a step >= an interior point's");
    CHECK(t_mid >= t_global * (1 - 1e-12), "per-point estimates are >= the global one");
    floe_world_destroy(w);
}

static void test_refusal(void) {
    int small;
    floe_world *w = linear_pair(1e3, 0, 1e-3, 1e-3, &small);
    floe_world_prepare(w);
    double crit = floe_world_critical_dt(w);
    floe_world_destroy(w);
    for (int allow = 0; allow < 2; allow++) {
        w = linear_pair(1e3, 0, 1e-3, 1e-3, &small);
        floe_world_set_dt(w, 1.01 * crit, allow);
        int rc = floe_world_prepare(w);
        if (!allow) {
            printf("  refused: %s\n", floe_world_last_error(w));
            CHECK(rc == FLOE_EUNSTABLE && strstr(floe_world_last_error(w), "above the critical estimate") &&
                      strstr(floe_world_last_error(w), "contact_packing"),
                  "dt 1.01 x critical refused with the limiting kind named (rc %d)", rc);
        } else CHECK(rc == FLOE_OK && floe_world_dt(w) == 1.01 * crit, "allowed with allow_unstable_dt");
        floe_world_destroy(w);
    }
}

/* two Hertz spheres approaching from 4 mm apart at +-1 m/s (e = 0.5), then flying apart */
static floe_world *collision(int adaptive, double safety) {
    floe_world_def d = floe_default_world_def();
    d.adaptive = adaptive;
    d.dt_safety = safety;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.0));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.01));
    floe_particle_def a = floe_default_particle_def(), b = floe_default_particle_def();
    a.geometry = b.geometry = g;
    a.v[0] = 1;
    b.v[0] = -1;
    b.x[0] = 0.024;
    floe_world_add_particle(w, &a);
    floe_world_add_particle(w, &b);
    return w;
}

static void test_adaptive(void) {
    /* fixed small step: the reference */
    floe_world *w = collision(0, 0.05);
    CHECK(floe_world_run(w, 0.006, NULL, NULL) == FLOE_OK, "fixed run: %s", floe_world_last_error(w));
    double e_fixed = (pview(w).v[3] - pview(w).v[0]) / 2;
    long n_fixed = floe_world_step_count(w);
    floe_world_destroy(w);
    /* adaptive, stepped by hand to check the criterion on every accepted step */
    w = collision(1, 0.2);
    int rc = floe_world_prepare(w);
    const double tv = floe_world_definition(w)->adapt_velocity_tol;
    double worst = 0, dtmin = INFINITY, dtmax = 0;
    int violations = 0;
    double dt_lo = 0;
    floe_world_adaptive_bounds(w, &dt_lo, NULL);
    while (!rc && floe_world_time(w) < 0.006) {
        double v0[6];
        memcpy(v0, pview(w).v, sizeof v0);
        rc = floe_world_step(w);
        double dt = floe_world_dt(w);
        for (int i = 0; i < 2; i++) {
            double dv[3];
            floe_v3_sub(dv, pview(w).v + 3 * i, v0 + 3 * i);
            double eta = floe_v3_norm(dv) * dt / 0.01;
            if (eta > worst) worst = eta;
            if (eta > tv && dt > dt_lo * (1 + 1e-9)) violations++;
        }
        dtmin = fmin(dtmin, dt);
        dtmax = fmax(dtmax, dt);
    }
    CHECK(rc == FLOE_OK, "adaptive run: %s", floe_world_last_error(w));
    floe_step_stats st;
    floe_world_step_stats(w, &st);
    double e_ad = (pview(w).v[3] - pview(w).v[0]) / 2, bal = floe_world_energy_balance_error(w);
    printf("  adaptive collision: %ld accepted, %ld rejected, dt %.3g .. %.3g s (critical %.3g s); restitution %.4f "
           "(fixed 0.05 x critical, %ld steps: %.4f); worst |dv| dt / R %.2e (tol %.0e); balance error %.2e\n",
           st.accepted, st.rejected, dtmin, dtmax, floe_world_critical_dt(w), e_ad, n_fixed, e_fixed, worst, tv, bal);
    CHECK(violations == 0, "every accepted step meets the velocity criterion (%d violations)", violations);
    CHECK(st.rejected > 0 && st.accepted > 0, "steps were rejected and accepted");
    CHECK(dtmax > 20 * dtmin, "the step varied (%.3g .. %.3g)", dtmin, dtmax);
    CHECK(st.accepted < n_fixed, "fewer steps than the fixed 0.05 x critical run (%ld vs %ld)", st.accepted, n_fixed);
    CHECK_NEAR(e_ad, 0.5, 0.02, "adaptive restitution (tol 2 %)");
    CHECK_NEAR(e_fixed, 0.5, 0.02, "fixed-step restitution (tol 2 %)");
    /* a rejected step is undone: the ledger still closes (a step booked twice would not) */
    CHECK(bal < 1e-3, "energy balance with rejected steps %.2e < 1e-3", bal);
    floe_world_destroy(w);
    /* floe_world_run ends at t_end exactly */
    w = collision(1, 0.2);
    CHECK(floe_world_run(w, 0.0061234, NULL, NULL) == FLOE_OK, "adaptive floe_world_run: %s", floe_world_last_error(w));
    CHECK(fabs(floe_world_time(w) - 0.0061234) < 1e-15, "the run ends at t_end (%.17g)", floe_world_time(w));
    floe_world_destroy(w);
}

/* dt_max 3x above the critical step (allowed): the unstable trials are rejected */
static void test_adaptive_rescue(void) {
    const double kn = 1e4, R = 0.01, m = 0.01;
    for (int adaptive = 0; adaptive < 2; adaptive++) {
        floe_world_def d = floe_default_world_def();
        d.adaptive = adaptive;
        d.dt = 3 * 2 / sqrt(kn / m);
        d.dt_max = d.dt;
        d.allow_unstable_dt = 1;
        floe_v3_set(d.gravity, 0, 0, -9.81);
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material mt = {"m", 1000, 1e7, 0.3};
        floe_world_add_material(w, &mt);
        floe_world_set_law(w, 0, 0, floe_linear_law_create(kn, 0, 0, 0, 0));
        int g = floe_world_add_geometry(w, floe_sphere_create(R));
        floe_particle_def a = floe_default_particle_def(), b = floe_default_particle_def();
        a.geometry = b.geometry = g;
        a.mass = b.mass = m;
        a.motion = FLOE_FIXED;
        b.x[2] = 2 * R + 0.002; /* falls onto the fixed sphere */
        floe_world_add_particle(w, &a);
        floe_world_add_particle(w, &b);
        int rc = floe_world_run(w, 0.2, NULL, NULL);
        floe_step_stats st;
        floe_world_step_stats(w, &st);
        printf("  dt_max = 3 x 2/w, %s: %s (%ld accepted, %ld rejected, dt %.3g .. %.3g s), rest height %.4g m\n",
               adaptive ? "adaptive" : "fixed", rc ? floe_world_last_error(w) : "ran", st.accepted, st.rejected,
               st.dt_min_used, st.dt_max_used, pview(w).x[5]);
        if (!adaptive) CHECK(rc == FLOE_EUNSTABLE, "fixed 3x above the critical step fails (rc %d)", rc);
        else {
            CHECK(rc == FLOE_OK && st.rejected > 0, "adaptive: rejections rescue the run: %s", floe_world_last_error(w));
            CHECK(fabs(pview(w).x[5] - 2 * R) < 0.002, "the sphere ends on the fixed one (z %.4g)", pview(w).x[5]);
        }
        floe_world_destroy(w);
    }
}

static int scene(const char *time, char *err, size_t len, floe_world **out) {
    char text[2048];
    snprintf(text, sizeof text,
             "time: %s\n"
             "materials: [{name: g, density: 2500, young: 1.0e7, poisson: 0.3}]\n"
             "laws: [{materials: [g, g], model: hertz_mindlin, restitution: 0.5, friction: 0.5}]\n"
             "bodies:\n"
             "  - {shape: {sphere: {radius: 0.01}}, material: g, position: [0, 0, 0], velocity: [1, 0, 0]}\n"
             "  - {shape: {sphere: {radius: 0.01}}, material: g, position: [0.03, 0, 0]}\n",
             time);
    floe_scene_info info;
    floe_world *w = NULL;
    int rc = floe_scene_load_ex("t.yaml", text, NULL, 0, &w, &info, err, len);
    if (out) *out = w;
    else floe_world_destroy(w);
    return rc;
}

static void test_scene_keys(void) {
    char err[1024];
    floe_world *w = NULL;
    int rc = scene("{duration: 0.01, integrator: leapfrog}", err, sizeof err, &w);
    CHECK(rc == FLOE_OK && w && floe_world_definition(w)->integrator == FLOE_LEAPFROG, "integrator: leapfrog (%s)", rc ? err : "");
    floe_world_destroy(w);
    rc = scene("{duration: 0.01, integrator: rk2, adaptive: {dt_min: 1e-8, dt_max: 1e-6, velocity_tolerance: 1e-4, "
               "penetration_tolerance: 0.01}}", err, sizeof err, &w);
    CHECK(rc == FLOE_OK && w && floe_world_definition(w)->integrator == FLOE_RK2 && floe_world_definition(w)->adaptive && adapt_bound(w, 0) == 1e-8 &&
              adapt_bound(w, 1) == 1e-6 && floe_world_definition(w)->adapt_velocity_tol == 1e-4 && floe_world_definition(w)->adapt_depth_tol == 0.01,
          "adaptive mapping (%s)", rc ? err : "");
    if (w) {
        rc = floe_world_run(w, 1e-4, NULL, NULL);
        CHECK(rc == FLOE_OK && fabs(floe_world_time(w) - 1e-4) < 1e-15, "scene adaptive run: %s", floe_world_last_error(w));
    }
    floe_world_destroy(w);
    rc = scene("{duration: 0.01, adaptive: true}", err, sizeof err, &w);
    CHECK(rc == FLOE_OK && w && floe_world_definition(w)->adaptive && adapt_bound(w, 1) == floe_world_critical_dt(w), "adaptive: true (%s)",
          rc ? err : "");
    floe_world_destroy(w);
    rc = scene("{duration: 0.01, integrator: verlet}", err, sizeof err, NULL);
    printf("  bad integrator: %s\n", err);
    CHECK(rc != FLOE_OK && strstr(err, "t.yaml:1:") && strstr(err, "velocity_verlet"), "unknown integrator named with a suggestion");
    rc = scene("{duration: 0.01, integrator: leapfrog, adaptive: true}", err, sizeof err, NULL);
    printf("  leapfrog + adaptive: %s\n", err);
    CHECK(rc == FLOE_EINVAL && strstr(err, "adaptive"), "leapfrog with adaptive refused");
    rc = scene("{duration: 0.01, adaptive: {dt_min: 1e-5, dt_max: 1e-6}}", err, sizeof err, NULL);
    CHECK(rc != FLOE_OK && strstr(err, "dt_min"), "dt_min above dt_max refused: %s", err);
    rc = scene("{duration: 0.01, adaptive: {dt_max: 1.0}}", err, sizeof err, NULL);
    printf("  dt_max above critical: %s\n", err);
    CHECK(rc == FLOE_EUNSTABLE && strstr(err, "dt_max"), "dt_max above the critical step refused");
    rc = scene("{duration: 0.01, pd_dem: {scheme: staggered, substeps: 2, every: 2}}", err, sizeof err, NULL);
    CHECK(rc != FLOE_OK && strstr(err, "not both"), "substeps and every together refused: %s", err);
    rc = scene("{duration: 0.01, pd_dem: {substeps: 2}}", err, sizeof err, NULL);
    CHECK(rc != FLOE_OK && strstr(err, "scheme: staggered"), "substeps without staggered refused: %s", err);
    rc = scene("{duration: 0.01, pd_dem: {scheme: staggered, substeps: auto}}", err, sizeof err, &w);
    CHECK(rc == FLOE_OK && w && floe_world_definition(w)->pd_dem == FLOE_PD_DEM_STAGGERED && floe_world_definition(w)->pd_substeps == 0,
          "pd_dem staggered, substeps auto (no PD body: monolithic) (%s)", rc ? err : "");
    floe_world_destroy(w);
}

int main(void) {
    test_manifold_factor();
    test_closed_forms();
    test_hertz();
    test_pd_estimates();
    test_refusal();
    test_adaptive();
    test_adaptive_rescue();
    test_scene_keys();
    return check_summary("test_timestep");
}
