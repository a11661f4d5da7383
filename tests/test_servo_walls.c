/* test_servo_walls.c - servo walls (core/world/servo_walls.c, floe_servo.h): an isotropic
 * compaction of a few hundred frictionless spheres in a box of six servo walls reaches the
 * target pressure on every wall within 1 % (mean over the last steps, and the largest
 * deviation of the instantaneous pressure within 2 %), the energy watchdog stays quiet
 * (STOP mode: a trip fails the step), the box area is the product of the other walls'
 * separations; one servo wall against five fixed ones; the friction setter; refusals. */
#include "check.h"
#include "floe.h"
#include "floe_servo.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double P = 2000.0; /* Pa */

/* 200 spheres (r in [4, 6] mm), soft viscoelastic contacts (kn 1e4 N/m, gn 1.5 N s/m),
 * frictionless, a linear drag, in a 0.07 m box of six walls; servo: the walls with `servo` */
static char scene[8192];
static void make_scene(const char *servo_x0, const char *servo_others) {
    snprintf(scene, sizeof scene,
             "dimension: 3\n"
             "time: {duration: 1, safety: 0.2}\n"
             "gravity: [0, 0, 0]\n"
             "materials: [{name: g, density: 2500}]\n"
             "laws: [{materials: [g, g], model: viscoelastic, kn: 1.0e4, gn: 1.5, ks: 0, gs: 0, friction: 0}]\n"
             "forces: [{type: linear_drag, c: 100}]\n"
             "walls:\n"
             "  - {point: [0, 0, 0], normal: [1, 0, 0], material: g%s}\n"
             "  - {point: [0.07, 0, 0], normal: [-1, 0, 0], material: g%s}\n"
             "  - {point: [0, 0, 0], normal: [0, 1, 0], material: g%s}\n"
             "  - {point: [0, 0.07, 0], normal: [0, -1, 0], material: g%s}\n"
             "  - {point: [0, 0, 0], normal: [0, 0, 1], material: g%s}\n"
             "  - {point: [0, 0, 0.07], normal: [0, 0, -1], material: g%s}\n"
             "bodies:\n"
             "  - packing: random\n"
             "    material: g\n"
             "    region: {min: [0, 0, 0], max: [0.07, 0.07, 0.07]}\n"
             "    count: 200\n"
             "    seed: 2\n"
             "    radius_distribution: {uniform: [0.004, 0.006]}\n",
             servo_x0, servo_others, servo_others, servo_others, servo_others, servo_others);
}

static int W[6]; /* the particle indices of the walls, in the scene's order */
static floe_world *load(const char *text, char *err, size_t errlen) {
    floe_world *w = NULL;
    floe_scene_info info;
    if (floe_scene_load_string(text, "servo.yaml", "/tmp", &w, &info, err, errlen)) {
        floe_world_destroy(w);
        return NULL;
    }
    int k = 0;
    for (int i = 0; i < floe_world_particle_count(w) && k < 6; i++) {
        floe_particle_state ps;
        floe_world_get_particle(w, i, &ps);
        if (isinf(ps.radius)) W[k++] = i;
    }
    return w;
}

static double wall_x(floe_world *w, int i, int axis) {
    floe_particle_state ps;
    floe_world_get_particle(w, i, &ps);
    return ps.x[axis];
}

/* steps until every servo wall's pressure stays within tol of P for `hold` steps in a row
 * (or max steps); then `avg` more steps: the mean and the largest deviation of each */
static long run_to_steady(floe_world *w, const int *walls, int nw, long max, long hold, double tol, int *rc) {
    long in = 0, s = 0;
    for (; s < max && in < hold; s++) {
        if ((*rc = floe_world_step(w))) return s;
        int ok = 1;
        for (int k = 0; k < nw; k++) ok &= fabs(floe_world_wall_pressure(w, walls[k]) - P) <= tol * P;
        in = ok ? in + 1 : 0;
        if (getenv("SERVO_TRACE") && s % 500 == 0) {
            printf("    step %6ld", s);
            for (int k = 0; k < nw; k++) printf(" %8.1f", floe_world_wall_pressure(w, walls[k]));
            printf("\n");
        }
    }
    return s;
}

static void test_isotropic(void) {
    char err[2048];
    const char *sv = ", servo: {pressure: 2000, area: auto, max_speed: 0.5}";
    make_scene(sv, sv);
    floe_world *w = load(scene, err, sizeof err);
    CHECK(w != NULL, "isotropic scene: %s", err);
    if (!w) return;
    int *walls = W, rc = 0;
    for (int k = 0; k < 6; k++) CHECK(floe_world_is_servo_wall(w, walls[k]), "wall %d is a servo wall", k);
    long steps = run_to_steady(w, walls, 6, 60000, 500, 0.01, &rc);
    CHECK(rc == 0, "isotropic compaction stepped without error: %s", rc ? floe_world_last_error(w) : "");
    CHECK(steps < 60000, "every wall within 1 %% of P for 500 steps after %ld steps", steps);
    /* steady state: mean over 1,000 more steps within 1 %, every sample within 2 % */
    double mean[6] = {0}, dev[6] = {0};
    const int navg = 1000;
    for (int s = 0; s < navg && !rc; s++) {
        rc = floe_world_step(w);
        for (int k = 0; k < 6; k++) {
            double p = floe_world_wall_pressure(w, W[k]);
            mean[k] += p / navg;
            dev[k] = fmax(dev[k], fabs(p - P) / P);
        }
    }
    CHECK(rc == 0, "steady state stepped: %s", rc ? floe_world_last_error(w) : "");
    for (int k = 0; k < 6; k++) {
        char what[64];
        snprintf(what, sizeof what, "wall %d mean pressure at steady state", k);
        CHECK_NEAR(mean[k], P, 0.01, what);
        CHECK(dev[k] <= 0.02, "wall %d: largest deviation %.3g %% > 2 %%", k, 100 * dev[k]);
    }
    /* the area of wall 0 (normal +x): the y and z separations */
    double ly = wall_x(w, W[3], 1) - wall_x(w, W[2], 1), lz = wall_x(w, W[5], 2) - wall_x(w, W[4], 2);
    CHECK_NEAR(floe_world_servo_area(w, W[0]), ly * lz, 1e-12, "area auto = ly lz");
    double lx = wall_x(w, W[1], 0) - wall_x(w, W[0], 0);
    /* solid fraction reached: the box shrank from 0.07 m */
    double vs = 0;
    for (int i = 0; i < floe_world_particle_count(w); i++) {
        floe_particle_state ps;
        floe_world_get_particle(w, i, &ps);
        if (!isinf(ps.radius)) vs += 4.0 / 3.0 * M_PI * ps.radius * ps.radius * ps.radius;
    }
    printf("  isotropic: %ld steps to 1 %% (dt %.3g s), box %.4f x %.4f x %.4f m, solid fraction %.3f\n", steps,
           floe_world_dt(w), lx, ly, lz, vs / (lx * ly * lz));
    CHECK(vs / (lx * ly * lz) > 0.5, "compacted: solid fraction %.3f > 0.5", vs / (lx * ly * lz));
    floe_energy_check_state ec;
    floe_world_energy_check(w, &ec);
    CHECK(ec.tripped_step < 0, "energy watchdog quiet (created %.3g of the scale)", ec.created);
    floe_energy e = floe_world_energy(w);
    CHECK(e.work_boundary > 0, "the walls did work on the sample (%g J)", e.work_boundary);
    floe_world_destroy(w);
}

/* wall 0 alone is a servo wall (area given); the others are fixed */
static void test_one_wall(void) {
    char err[2048];
    make_scene(", servo: {pressure: 2000, area: 0.0049, max_speed: 0.5}", "");
    floe_world *w = load(scene, err, sizeof err);
    CHECK(w != NULL, "one-wall scene: %s", err);
    if (!w) return;
    int walls[1] = {W[0]}, rc = 0;
    CHECK(!floe_world_is_servo_wall(w, W[1]), "wall 1 is fixed");
    long steps = run_to_steady(w, walls, 1, 80000, 500, 0.01, &rc);
    CHECK(rc == 0, "one-wall compaction stepped: %s", rc ? floe_world_last_error(w) : "");
    CHECK(steps < 80000, "wall 0 within 1 %% of P for 500 steps after %ld steps", steps);
    double mean = 0;
    for (int s = 0; s < 1000 && !rc; s++) {
        rc = floe_world_step(w);
        mean += floe_world_wall_pressure(w, W[0]) / 1000;
    }
    CHECK_NEAR(mean, P, 0.01, "one servo wall: mean pressure");
    /* the fixed opposite wall carries the same force (static equilibrium, no body force):
     * its pressure over the same area */
    floe_particle_state ps;
    floe_world_get_particle(w, W[1], &ps);
    CHECK_NEAR(ps.f[0] / 0.0049, P, 0.05, "opposite fixed wall: F / A");
    CHECK_NEAR(wall_x(w, W[1], 0), 0.07, 1e-15, "wall 1 did not move");
    printf("  one wall: %ld steps, wall 0 at x = %.4f m\n", steps, wall_x(w, W[0], 0));
    floe_world_destroy(w);
}

static void test_friction_setter(void) {
    floe_contact_law *l = floe_linear_law_create(1e4, 5e3, 0, 0, 0);
    CHECK(floe_contact_law_set_friction(l, 0.5) == FLOE_OK && ((floe_linear_law *)l)->mu == 0.5 && l->friction == 0.5,
          "linear law: friction set");
    CHECK(floe_contact_law_set_friction(l, -1) == FLOE_EINVAL, "negative friction refused");
    floe_contact_law_destroy(l);
    floe_material m = {"a", 1000, 1e7, 0.3};
    l = floe_hertz_mindlin_law_create(&m, &m, 0.5, 0);
    CHECK(floe_contact_law_set_friction(l, 0.3) == FLOE_OK && ((floe_hertz_mindlin_law *)l)->mu == 0.3,
          "hertz_mindlin: friction set");
    floe_contact_law_destroy(l);
    /* through the world: every pair */
    char err[2048];
    make_scene("", "");
    floe_world *w = load(scene, err, sizeof err);
    CHECK(w != NULL, "friction scene: %s", err);
    if (!w) return;
    CHECK(floe_world_set_law_friction(w, -1, -1, 0.4) == FLOE_OK, "world: friction of every law");
    CHECK(floe_world_set_law_friction(w, 0, 5, 0.4) == FLOE_EINVAL, "world: pair out of range refused");
    floe_world_destroy(w);
}

static void test_refusals(void) {
    char err[2048];
    /* area auto without the box's y walls: refused at prepare */
    const char *t =
        "dimension: 3\n"
        "time: {duration: 0.01}\n"
        "materials: [{name: g, density: 2500}]\n"
        "laws: [{materials: [g, g], model: viscoelastic, kn: 1.0e4, ks: 0, gn: 0, gs: 0, friction: 0}]\n"
        "walls:\n"
        "  - {point: [0, 0, 0], normal: [1, 0, 0], material: g, servo: {pressure: 100}}\n"
        "  - {point: [0.1, 0, 0], normal: [-1, 0, 0], material: g, velocity: [0.1, 0, 0], servo: {pressure: 100}}\n"
        "bodies: [{shape: {sphere: {radius: 0.01}}, material: g, position: [0.05, 0.05, 0.05]}]\n";
    floe_world *w = load(t, err, sizeof err);
    CHECK(!w && strstr(err, "servo.yaml:7:") && strstr(err, "either velocity or servo"),
          "velocity + servo refused at its line: %s", err);
    floe_world_destroy(w);
    const char *t2 =
        "dimension: 3\n"
        "time: {duration: 0.01}\n"
        "materials: [{name: g, density: 2500}]\n"
        "laws: [{materials: [g, g], model: viscoelastic, kn: 1.0e4, ks: 0, gn: 0, gs: 0, friction: 0}]\n"
        "walls:\n"
        "  - {point: [0, 0, 0], normal: [1, 0, 0], material: g, servo: {pressure: 100}}\n"
        "bodies: [{shape: {sphere: {radius: 0.01}}, material: g, position: [0.05, 0.05, 0.05]}]\n";
    w = load(t2, err, sizeof err);
    CHECK(!w && strstr(err, "servo.yaml:6:") && strstr(err, "no wall with normal"),
          "area auto without a box refused at its line: %s", err);
    floe_world_destroy(w);
    const char *t3 =
        "dimension: 3\n"
        "time: {duration: 0.01}\n"
        "materials: [{name: g, density: 2500}]\n"
        "laws: [{materials: [g, g], model: viscoelastic, kn: 1.0e4, ks: 0, gn: 0, gs: 0, friction: 0}]\n"
        "walls:\n"
        "  - {point: [0, 0, 0], normal: [1, 0, 0], material: g, servo: {pressure: -1}}\n"
        "bodies: [{shape: {sphere: {radius: 0.01}}, material: g, position: [0.05, 0.05, 0.05]}]\n";
    w = load(t3, err, sizeof err);
    CHECK(!w && strstr(err, "servo.yaml:6:") && strstr(err, "pressure"), "negative pressure refused: %s", err);
    floe_world_destroy(w);
}

int main(void) {
    test_friction_setter();
    test_refusals();
    test_isotropic();
    test_one_wall();
    return check_summary("test_servo_walls");
}
