/* test_prepare.c - a scene's `prepare` block (core/scene/scene_prepare.c, docs/granular.md):
 * isotropic compaction in a box of six walls to a target porosity (reached within 1 %,
 * walls then still) or a target pressure (every wall within 1 % at the end of the
 * preparation, 2 % once the run's first forces are taken), friction switched on through
 * the law setter, the run's clock back at 0; `floe check` (with_outputs 0) does not run it;
 * a target not reached in max_time is an error at the block's line saying how far it got;
 * the same two targets in a periodic cell through the cell's control. */
#include "check.h"
#include "floe.h"
#include "floe_servo.h"
#include "world_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* 100 frictionless spheres (r in [4, 6] mm, shear spring ks > 0 for the friction to come) in
 * a 5.5 cm box of fixed walls (the preparation makes them servo walls) */
static char scene[8192];
static void make_scene(const char *prepare) {
    snprintf(scene, sizeof scene,
             "dimension: 3\n"
             "time: {duration: 0.01, safety: 0.2}\n"
             "gravity: [0, 0, 0]\n"
             "materials: [{name: g, density: 2500}]\n"
             "laws: [{materials: [g, g], model: viscoelastic, kn: 1.0e4, gn: 1.5, ks: 5.0e3, gs: 0.5, friction: 0}]\n"
             "forces: [{type: linear_drag, c: 100}]\n"
             "walls:\n"
             "  - {point: [0, 0, 0], normal: [1, 0, 0], material: g}\n"
             "  - {point: [0.055, 0, 0], normal: [-1, 0, 0], material: g}\n"
             "  - {point: [0, 0, 0], normal: [0, 1, 0], material: g}\n"
             "  - {point: [0, 0.055, 0], normal: [0, -1, 0], material: g}\n"
             "  - {point: [0, 0, 0], normal: [0, 0, 1], material: g}\n"
             "  - {point: [0, 0, 0.055], normal: [0, 0, -1], material: g}\n"
             "bodies:\n"
             "  - packing: random\n"
             "    material: g\n"
             "    region: {min: [0, 0, 0], max: [0.055, 0.055, 0.055]}\n"
             "    count: 100\n"
             "    seed: 3\n"
             "    radius_distribution: {uniform: [0.004, 0.006]}\n"
             "prepare:\n%s",
             prepare);
}

static int W[6];
static floe_world *load(int run, char *err, size_t errlen, floe_scene_info *info) {
    floe_world *w = NULL;
    if (floe_scene_load_ex("prep.yaml", scene, "/tmp", run, &w, info, err, errlen)) {
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

static double porosity(floe_world *w) {
    double vs = 0, L[3];
    for (int i = 0; i < floe_world_particle_count(w); i++) {
        floe_particle_state ps;
        floe_world_get_particle(w, i, &ps);
        if (!isinf(ps.radius)) vs += 4.0 / 3.0 * M_PI * ps.radius * ps.radius * ps.radius;
    }
    for (int a = 0; a < 3; a++) {
        floe_particle_state lo, hi;
        floe_world_get_particle(w, W[2 * a], &lo);
        floe_world_get_particle(w, W[2 * a + 1], &hi);
        L[a] = hi.x[a] - lo.x[a];
    }
    return 1 - vs / (L[0] * L[1] * L[2]);
}

static void test_porosity(void) {
    char err[2048];
    floe_scene_info info;
    make_scene("  compact: {porosity: 0.42}\n  then: {friction: 0.4}\n  max_time: 1\n  hold: 200\n");
    floe_world *w = load(1, err, sizeof err, &info);
    CHECK(w != NULL, "porosity scene: %s", err);
    if (!w) return;
    double n = porosity(w);
    CHECK_NEAR(n, 0.42, 0.01, "porosity reached");
    CHECK(w->laws[0]->friction == 0.4 && ((floe_linear_law *)w->laws[0])->mu == 0.4,
          "friction switched on: %g", w->laws[0]->friction);
    CHECK(floe_world_time(w) == 0 && floe_world_step_count(w) == 0, "the run's clock at 0 (t = %g, step %ld)",
          floe_world_time(w), floe_world_step_count(w));
    CHECK(strstr(info.summary, "prepared: compacted to the porosity") != NULL, "summary says it: %s", info.summary);
    printf("  porosity: %.5f (target 0.42); %s", n, strstr(info.summary, "prepared:"));
    /* the walls stay where the preparation left them */
    floe_particle_state a, b;
    floe_world_get_particle(w, W[1], &a);
    for (int s = 0; s < 100; s++) floe_world_step(w);
    floe_world_get_particle(w, W[1], &b);
    CHECK(a.x[0] == b.x[0], "wall held after the preparation (%.9g -> %.9g)", a.x[0], b.x[0]);
    floe_world_destroy(w);
}

static void test_pressure(void) {
    char err[2048];
    floe_scene_info info;
    make_scene("  compact: {pressure: 2000}\n  then: {friction: 0.3}\n  max_time: 1\n  max_speed: 0.5\n  hold: 300\n");
    floe_world *w = load(1, err, sizeof err, &info);
    CHECK(w != NULL, "pressure scene: %s", err);
    if (!w) return;
    for (int k = 0; k < 6; k++) {
        char what[64];
        snprintf(what, sizeof what, "wall %d pressure after the preparation", k);
        CHECK_NEAR(floe_world_wall_pressure(w, W[k]), 2000, 0.02, what);
    }
    printf("  pressure: %s", strstr(info.summary, "prepared:"));
    /* at the preparation's last step (the summary): every wall within 1 % */
    const char *q = strstr(info.summary, "wall pressures ");
    double lo = 0, hi = 0;
    CHECK(q && sscanf(q, "wall pressures %lf to %lf", &lo, &hi) == 2, "summary gives the pressures");
    CHECK(fabs(lo - 2000) <= 20 && fabs(hi - 2000) <= 20, "end of the preparation: pressures %g to %g within 1 %%", lo,
          hi);
    printf("  porosity at 2 kPa: %.4f\n", porosity(w));
    floe_world_destroy(w);
}

/* the same preparation in a periodic cell (no walls): the cell's control compacts to the
 * porosity (within 1 %, the cell then fixed) and to the pressure (the cell's normal stresses
 * within 1 % at the end of the preparation) */
static void test_cell(void) {
    static const char *const cases[2] = {"  compact: {porosity: 0.42}\n  then: {friction: 0.4}\n  max_time: 2\n  hold: 200\n",
                                         "  compact: {pressure: 2000}\n  max_time: 2\n  hold: 300\n"};
    for (int c = 0; c < 2; c++) {
        char text[8192], err[2048];
        snprintf(text, sizeof text,
                 "dimension: 3\n"
                 "time: {duration: 0.01, safety: 0.2}\n"
                 "gravity: [0, 0, 0]\n"
                 "materials: [{name: g, density: 2500}]\n"
                 "laws: [{materials: [g, g], model: viscoelastic, kn: 1.0e4, gn: 1.5, ks: 5.0e3, gs: 0.5, friction: 0}]\n"
                 "forces: [{type: linear_drag, c: 100}]\n"
                 "cell: {size: [0.055, 0.055, 0.055]}\n"
                 "bodies:\n"
                 "  - {packing: random, material: g, region: {min: [0, 0, 0], max: [0.055, 0.055, 0.055]}, count: 100,\n"
                 "     seed: 3, radius_distribution: {uniform: [0.004, 0.006]}}\n"
                 "prepare:\n%s", cases[c]);
        floe_world *w = NULL;
        floe_scene_info info;
        int rc = floe_scene_load_ex("prep_cell.yaml", text, "/tmp", 1, &w, &info, err, sizeof err);
        CHECK(rc == FLOE_OK, "periodic prepare %d: %s", c, err);
        if (rc) continue;
        floe_rve_measures m;
        floe_world_refresh_forces(w);
        floe_world_cell_measures(w, &m);
        if (c == 0) {
            CHECK_NEAR(m.porosity, 0.42, 0.01, "periodic: porosity reached");
            CHECK(((floe_linear_law *)w->laws[0])->mu == 0.4, "periodic: friction switched on");
        } else {
            const char *q = strstr(info.summary, "normal stresses -");
            double lo = 0, hi = 0;
            CHECK(q && sscanf(q, "normal stresses -%lf to -%lf", &lo, &hi) == 2, "summary gives the stresses");
            CHECK(fabs(lo - 2000) <= 20 && fabs(hi - 2000) <= 20, "periodic: stresses %g to %g Pa within 1 %%", lo, hi);
        }
        printf("  %s", strstr(info.summary, "prepared:"));
        CHECK(floe_world_time(w) == 0, "periodic: the run's clock at 0");
        floe_world_destroy(w);
    }
}

static void test_check_and_errors(void) {
    char err[2048];
    floe_scene_info info;
    /* check mode: read, not run */
    make_scene("  compact: {pressure: 2000}\n  max_time: 1\n");
    floe_world *w = load(0, err, sizeof err, &info);
    CHECK(w != NULL, "check-mode scene: %s", err);
    if (w) {
        floe_particle_state ps;
        floe_world_get_particle(w, W[1], &ps);
        CHECK(ps.x[0] == 0.055 && floe_world_step_count(w) == 0, "check mode: no preparation run");
        floe_world_destroy(w);
    }
    /* not reached in max_time: at the block (line 21), saying how far it got */
    make_scene("  compact: {pressure: 2000}\n  max_time: 0.001\n");
    w = load(1, err, sizeof err, &info);
    CHECK(!w && strstr(err, "prep.yaml:21:") && strstr(err, "not reached within max_time") &&
              strstr(err, "porosity"), "max_time too short: %s", err);
    floe_world_destroy(w);
    make_scene("  compact: {porosity: 0.42, pressure: 3}\n  max_time: 1\n");
    w = load(0, err, sizeof err, &info);
    CHECK(!w && strstr(err, "either pressure") != NULL, "both targets refused: %s", err);
    floe_world_destroy(w);
    make_scene("  compact: {porosity: 1.5}\n  max_time: 1\n");
    w = load(0, err, sizeof err, &info);
    CHECK(!w && strstr(err, "prep.yaml:22:") && strstr(err, "(0, 1)"), "porosity out of range refused: %s", err);
    floe_world_destroy(w);
}

int main(void) {
    test_cell();
    test_check_and_errors();
    test_porosity();
    test_pressure();
    return check_summary("test_prepare");
}
