/* test_public_api.c - the public read-only view (floe_view.h) and the state setters of
 * floe_world.h (issue 11, "A public API"), through public headers only:
 *  - the particle view reads the arrays (walls at radius INFINITY, L = I w after prepare);
 *  - contacts are refused unless recorded, then match the count;
 *  - floe_world_set_velocity validates, is the initial condition before prepare and, after,
 *    an impulse booked as external work: the energy balance stays closed (1e-12);
 *  - floe_world_set_pose, floe_world_set_particle_geometry, floe_world_set_dt validate and
 *    take effect (the step re-prepares where documented);
 *  - materials, laws, ADMM options, memory, adaptive bounds, neighbour pairs and the
 *    detection probes read what the world holds. */
#include "check.h"
#include "floe.h"
#include "floe_detect.h"

#include <math.h>
#include <string.h>

static const double R = 1e-3, RHO = 2500;

/* a wall (particle 0) and two spheres of radius R at x = 0 and x = gap (particles 1, 2) */
static floe_world *two_spheres(int dim, double gap, int *mat) {
    floe_world_def d = floe_default_world_def();
    d.dim = dim;
    d.dt = 1e-6;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"glass", RHO, 1e7, 0.3};
    *mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 1.0, 0.0));
    double o[3] = {0, -0.1, 0}, n[3] = {0, 1, 0};
    floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
    int g = floe_world_add_geometry(w, floe_sphere_create(R));
    for (int k = 0; k < 2; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        p.x[0] = k * gap;
        floe_world_add_particle(w, &p);
    }
    return w;
}

static double sphere_mass(int dim) { return dim == 3 ? RHO * 4.0 / 3.0 * M_PI * R * R * R : RHO * M_PI * R * R; }

static void test_view(void) {
    int mat;
    floe_world *w = two_spheres(3, 0.0019, &mat);
    const double om[3] = {0, 0, 2.0};
    CHECK(floe_world_set_velocity(w, 1, NULL, om) == FLOE_OK, "omega before prepare");
    CHECK(!floe_world_is_prepared(w), "not prepared before the first prepare");
    const floe_contact_info *c = NULL;
    CHECK(floe_world_contacts(w, &c) == -FLOE_EINVAL && c == NULL, "contacts refused before any evaluation");
    floe_world_record_contacts(w, 1);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    CHECK(floe_world_is_prepared(w), "prepared");
    floe_particles_view pv;
    CHECK(floe_world_particles(w, &pv) == FLOE_OK && floe_world_particles(NULL, &pv) == FLOE_EINVAL, "view");
    CHECK(pv.n == 3 && pv.dim == 3 && isinf(pv.radius[0]) && pv.radius[1] == R, "n %d, wall radius %g", pv.n,
          pv.radius[0]);
    CHECK(pv.pieces[1] == 1 && pv.motion[0] == FLOE_FIXED && pv.material[2] == mat, "pieces, motion, material");
    CHECK(floe_world_particle_geometry(w, 1) == floe_world_geometry_at(w, pv.geometry[1]) &&
              floe_world_geometry_at(w, floe_world_geometry_count(w)) == NULL,
          "geometries");
    const double m = sphere_mass(3), I = 0.4 * m * R * R;
    CHECK_NEAR(pv.mass[1], m, 1e-12, "view mass = rho 4/3 pi R^3 (tol 1e-12)");
    CHECK_NEAR(pv.L[3 * 1 + 2], I * om[2], 1e-12, "view L_z = (2/5) m R^2 omega_z after prepare (tol 1e-12)");
    int nc = floe_world_contacts(w, &c);
    CHECK(nc == 1 && nc == floe_world_contact_count(w) && c && c[0].i == 1 && c[0].j == 2, "one recorded contact (%d)",
          nc);
    if (nc == 1) CHECK_NEAR(c[0].depth, 2 * R - 0.0019, 1e-9, "recorded depth = 2R - distance (tol 1e-9)");

    /* materials and laws */
    CHECK(floe_world_material_count(w) == 1 && floe_world_material_at(w, 0)->density == RHO &&
              floe_world_material_at(w, 1) == NULL,
          "materials");
    CHECK(floe_world_law(w, 0, 0) != NULL && floe_world_law(w, 0, 1) == NULL && floe_world_law(w, -1, 0) == NULL,
          "laws of material pairs");
    floe_admm_options ao, def;
    floe_admm_default_options(&def);
    CHECK(floe_world_admm_options(w, &ao) == FLOE_OK && ao.tol == def.tol && ao.max_iter == def.max_iter,
          "ADMM options: the defaults");
    floe_memory_stats ms;
    floe_neighbor_stats ns;
    CHECK(floe_world_memory(w, &ms) == FLOE_OK && floe_world_neighbor_stats(w, &ns) == FLOE_OK, "memory, stats");
    CHECK(ms.particle_capacity >= 3 && ms.particles >= (size_t)ms.particle_capacity * 29 * sizeof(double) &&
              ms.pair_capacity >= ns.pairs && ms.contact_capacity >= 1 &&
              ms.contacts >= sizeof(floe_contact_info),
          "memory: %zu B particles (capacity %d), %zu B list, %zu B contacts", ms.particles, ms.particle_capacity,
          ms.neighbor_list, ms.contacts);
    const int *pi = NULL, *pj = NULL;
    int np = floe_world_neighbor_pairs(w, &pi, &pj), has12 = 0;
    for (int k = 0; k < np; k++) has12 |= pi[k] == 1 && pj[k] == 2;
    CHECK(np == ns.pairs && np >= 1 && has12, "neighbour pairs: %d, the touching pair listed", np);
    double lo = -1, hi = -1;
    CHECK(floe_world_adaptive_bounds(w, &lo, &hi) == FLOE_OK && lo == 0 && hi == 0, "no adaptive bounds without adaptive");

    /* the detection probe */
    floe_contact pc;
    memset(&pc, 0, sizeof pc);
    CHECK(floe_world_probe_contact(w, 1, 2, 0, &pc) == 1, "probe: in contact");
    CHECK_NEAR(pc.depth, 2 * R - 0.0019, 1e-9, "probe depth = 2R - distance (tol 1e-9)");
    CHECK(floe_world_probe_contact(w, 1, 3, 0, &pc) == -FLOE_EINVAL && floe_world_probe_contact(w, 1, 1, 0, &pc) == -FLOE_EINVAL &&
              floe_world_probe_overlap(w, -1, 2, 0, &pc) == -FLOE_EINVAL,
          "probe: bad indices refused");
    floe_world_destroy(w);
}

/* set_velocity: validation; before prepare it is the initial state; after, an impulse whose
 * kinetic energy is booked as work, so the balance stays closed */
static void test_set_velocity(void) {
    int mat;
    floe_world *w = two_spheres(3, 0.01, &mat); /* apart: free flight, no gravity */
    const double v1[3] = {1, 0, 0}, bad[3] = {NAN, 0, 0};
    CHECK(floe_world_set_velocity(w, 3, v1, NULL) == FLOE_EINVAL, "index out of range refused");
    CHECK(floe_world_set_velocity(w, 0, v1, NULL) == FLOE_EINVAL && strstr(floe_world_last_error(w), "fixed"),
          "fixed wall refused: %s", floe_world_last_error(w));
    CHECK(floe_world_set_velocity(w, 1, bad, NULL) == FLOE_EINVAL, "NaN refused");
    CHECK(floe_world_set_velocity(w, 1, v1, NULL) == FLOE_OK, "set before prepare");
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    const double m = sphere_mass(3);
    CHECK_NEAR(floe_world_energy(w).initial, 0.5 * m, 1e-12, "initial energy = 1/2 m v^2 of the set velocity (tol 1e-12)");
    for (int s = 0; s < 10; s++) floe_world_step(w);
    const double v2[3] = {2, 0, 0}, om[3] = {0, 3, 0};
    CHECK(floe_world_set_velocity(w, 1, v2, om) == FLOE_OK, "impulse after 10 steps");
    floe_energy e = floe_world_energy(w);
    const double I = 0.4 * m * R * R;
    CHECK_NEAR(e.kinetic_trans, 0.5 * m * 4, 1e-12, "kinetic energy follows the impulse at once (tol 1e-12)");
    CHECK_NEAR(e.work_body, 0.5 * m * 3 + 0.5 * I * 9, 1e-12, "impulse booked as work: 1/2 m (4 - 1) + 1/2 I w^2 (tol 1e-12)");
    for (int s = 0; s < 10; s++) floe_world_step(w);
    floe_particles_view pv;
    floe_world_particles(w, &pv);
    CHECK(pv.v[3] == 2 && pv.w[4] == 3, "velocities kept in free flight (v %g, w %g)", pv.v[3], pv.w[4]);
    CHECK_NEAR(pv.L[4], I * 3, 1e-12, "angular momentum follows omega (tol 1e-12)");
    double err = floe_world_energy_balance_error(w);
    printf("  balance error after the impulse: %.2e\n", err);
    CHECK(err < 1e-12, "energy balance closed after an impulse (%.3g, tol 1e-12)", err);
    CHECK_NEAR(floe_world_dt(w), 1e-6, 1e-15, "the step is kept (tol 1e-15)");
    floe_world_destroy(w);
    /* 2D: velocities off the plane refused */
    w = two_spheres(2, 0.01, &mat);
    const double vz[3] = {0, 0, 1}, wx[3] = {1, 0, 0}, wz[3] = {0, 0, 1};
    CHECK(floe_world_set_velocity(w, 1, vz, NULL) == FLOE_EINVAL && floe_world_set_velocity(w, 1, NULL, wx) == FLOE_EINVAL,
          "2D: v_z and omega_x refused");
    CHECK(floe_world_set_velocity(w, 1, v1, wz) == FLOE_OK, "2D: in-plane velocity accepted");
    floe_world_destroy(w);
}

static void test_setters(void) {
    int mat;
    floe_world *w = two_spheres(3, 0.01, &mat);
    /* pose */
    const double x[3] = {0.003, 0.001, 0}, q2[4] = {2, 0, 0, 0}, q0[4] = {0, 0, 0, 0};
    CHECK(floe_world_set_pose(w, 0, x, NULL) == FLOE_EINVAL, "pose: wall refused");
    CHECK(floe_world_set_pose(w, 1, NULL, q0) == FLOE_EINVAL, "pose: zero quaternion refused");
    CHECK(floe_world_set_pose(w, 1, x, q2) == FLOE_OK, "pose set");
    floe_particles_view pv;
    floe_world_particles(w, &pv);
    CHECK(pv.x[3] == x[0] && pv.x[4] == x[1] && pv.q[4] == 1.0 && pv.q[5] == 0, "pose read back, quaternion made unit");
    /* geometry */
    int g2 = floe_world_add_geometry(w, floe_sphere_create(2 * R));
    int gp = floe_world_add_geometry(w, floe_plane_create());
    CHECK(floe_world_set_particle_geometry(w, 0, g2) == FLOE_EINVAL, "geometry: wall refused");
    CHECK(floe_world_set_particle_geometry(w, 1, gp) == FLOE_EINVAL, "geometry: unbounded plane refused");
    CHECK(floe_world_set_particle_geometry(w, 1, 99) == FLOE_EINVAL, "geometry: index out of range refused");
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare");
    CHECK(floe_world_set_particle_geometry(w, 2, g2) == FLOE_OK && !floe_world_is_prepared(w),
          "geometry set; the world prepares again");
    floe_world_particles(w, &pv);
    CHECK(pv.radius[2] == 2 * R && pv.geometry[2] == g2, "new bounding radius %g", pv.radius[2]);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare again");
    floe_world_particles(w, &pv);
    const double m = sphere_mass(3);
    CHECK_NEAR(pv.mass[2], m, 1e-12, "mass kept (tol 1e-12)");
    CHECK_NEAR(pv.inertia[3 * 2], 0.4 * m * 4 * R * R, 1e-12, "inertia follows the new shape (tol 1e-12)");
    /* dt */
    CHECK(floe_world_set_dt(w, -1, 0) == FLOE_EINVAL && floe_world_set_dt(w, NAN, 0) == FLOE_EINVAL,
          "dt: negative and NaN refused");
    CHECK(floe_world_set_dt(w, 2e-6, 0) == FLOE_OK && !floe_world_is_prepared(w) &&
              floe_world_definition(w)->dt == 2e-6,
          "dt set in the definition; the world prepares again");
    CHECK(floe_world_step(w) == FLOE_OK && floe_world_dt(w) == 2e-6, "the next step uses it (%g s)", floe_world_dt(w));
    floe_world_destroy(w);
    /* adaptive bounds: the defaults dt_max = critical, dt_min = 1e-3 dt_max */
    floe_world_def d = floe_default_world_def();
    d.adaptive = 1;
    w = floe_world_create(&d, NULL, 0);
    floe_material mt = {"glass", RHO, 1e7, 0.3};
    floe_world_add_material(w, &mt);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&mt, &mt, 1.0, 0.0));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_sphere_create(R));
    floe_world_add_particle(w, &p);
    p.x[0] = 0.0019;
    floe_world_add_particle(w, &p);
    CHECK(floe_world_prepare(w) == FLOE_OK, "adaptive prepare: %s", floe_world_last_error(w));
    double lo, hi;
    floe_world_adaptive_bounds(w, &lo, &hi);
    CHECK(hi == floe_world_critical_dt(w) && fabs(lo - 1e-3 * hi) <= 1e-15 * hi, "adaptive bounds %g .. %g s", lo, hi);
    floe_world_destroy(w);
}

int main(void) {
    printf("view\n");
    test_view();
    printf("set_velocity\n");
    test_set_velocity();
    printf("set_pose, set_particle_geometry, set_dt, adaptive bounds\n");
    test_setters();
    return check_summary("test_public_api");
}
