/* test_coast_load.c - the coast_load output (observers/coast_load.c, docs/sea-ice.md
 * "Outputs"): a 1 km square floe (h = 1 m) held against the 1 km east face of a fixed
 * 2 km square coast by a uniform westward current (ocean drag, no turning angle, no
 * Coriolis) under Hopkins' law with damping: once still, the floe feels the drag of a floe
 * at rest, F = rho_w C_d |U| U A, and the coast carries it. The last row gives the contact
 * force F (1e-6), no y force, one contact, the contact length of the flat patch 1000 m
 * and F / 1000 N/m (1e-3: the overlap detector's energy integral of a 0.9 mm deep patch
 * is 8e-5 above L d^2 / 2, measured); a second output with `length: 2000` gives F / 2000; only the
 * coast is reported; a negative length is refused naming the key. */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *scene_fmt =
    "dimension: 2\nmass_2d: area\ntime: {duration: 900}\ngravity: [0, 0]\n"
    "materials: [{name: ice, density: 920, young: 1e8, poisson: 0.3}]\n"
    "laws: [{materials: [ice, ice], model: hopkins, young: 1e8, damping: 0.5, thickness_max: 1}]\n"
    "bodies:\n"
    "  - {material: ice, motion: fixed, position: [0, 0], thickness: 1, shape: {polygon: {vertices: "
    "[[-1000, -1000], [1000, -1000], [1000, 1000], [-1000, 1000]]}}}\n"
    "  - {material: ice, position: [1500, 0], thickness: 1, shape: {polygon: {vertices: "
    "[[-500, -500], [500, -500], [500, 500], [-500, 500]]}}}\n"
    "forces:\n"
    "  - {type: ocean_drag, velocity: [-0.1, 0], turning_angle: 0}\n"
    "outputs:\n"
    "  - {type: coast_load, interval: 100, file: coast.csv}\n"
    "  - {type: coast_load, interval: 100, file: coast2.csv, body: 0, %s}\n";

typedef struct cl_row {
    double t, contacts, fx, fy, f, length, per;
    int body;
    int nrows;
} cl_row;

/* the last row of a coast_load CSV and the number of rows of other bodies than 0 */
static int last_row(const char *path, cl_row *r, int *other) {
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    char line[512];
    int ok = fgets(line, sizeof line, f) && !strncmp(line, "t [s],body,contacts,fx [N]", 26);
    *other = 0;
    r->nrows = 0;
    while (ok && fgets(line, sizeof line, f)) {
        cl_row x;
        if (sscanf(line, "%lf,%d,%lf,%lf,%lf,%lf,%lf,%lf", &x.t, &x.body, &x.contacts, &x.fx, &x.fy, &x.f, &x.length,
                   &x.per) != 8) {
            ok = 0;
            break;
        }
        if (x.body != 0) (*other)++;
        x.nrows = r->nrows + 1;
        *r = x;
    }
    fclose(f);
    return ok && r->nrows > 0;
}

static void test_steady_load(void) {
    char dir[] = "/tmp/floe_coast_XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return;
    }
    char text[4096], err[1024] = "";
    snprintf(text, sizeof text, scene_fmt, "length: 2000");
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_ex("c.yaml", text, dir, 1, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "coast scene: %s", err);
    if (rc == FLOE_OK) {
        CHECK(floe_world_run(w, info.duration, NULL, NULL) == FLOE_OK, "run: %s", floe_world_last_error(w));
        floe_world_finish(w);
    }
    floe_world_destroy(w);
    const double F = 1027 * 3e-3 * 0.1 * 0.1 * 1e6; /* rho_w C_d |U| U A, defaults of ocean_drag */
    char path[256];
    cl_row r;
    int other = 0;
    snprintf(path, sizeof path, "%s/coast.csv", dir);
    CHECK(last_row(path, &r, &other), "coast.csv written and readable");
    if (r.nrows > 0) {
        CHECK(other == 0, "only the fixed coast is reported (%d rows of other bodies)", other);
        CHECK(r.contacts == 1, "one contact (%g)", r.contacts);
        CHECK_NEAR(-r.fx, F, 1e-6, "steady contact force on the coast = drag of the still floe (N)");
        CHECK(fabs(r.fy) <= 1e-6 * F, "no y force on the coast (%g N)", r.fy);
        CHECK_NEAR(r.length, 1000.0, 1e-3, "contact length: the floe's 1 km edge on the coast (m)");
        CHECK_NEAR(r.per, F / 1000.0, 1e-3, "force per length (N/m)");
        printf("  steady state at t = %.0f s: %.6g N on the coast (drag %.6g N), length %.6g m, %.6g N/m\n", r.t,
               -r.fx, F, r.length, r.per);
    }
    snprintf(path, sizeof path, "%s/coast2.csv", dir);
    CHECK(last_row(path, &r, &other), "coast2.csv written and readable");
    if (r.nrows > 0) {
        CHECK_NEAR(r.length, 2000.0, 0, "given length");
        CHECK_NEAR(r.per, F / 2000.0, 1e-6, "force per given length (N/m)");
    }
    remove(path);
    snprintf(path, sizeof path, "%s/coast.csv", dir);
    remove(path);
    rmdir(dir);
}

static void test_errors(void) {
    char text[4096], err[1024] = "";
    snprintf(text, sizeof text, scene_fmt, "length: -1");
    floe_world *w = NULL;
    int rc = floe_scene_load_ex("c.yaml", text, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, "length") && strstr(err, "c.yaml:14:"), "negative length refused: %s", err);
    printf("  length: -1 -> %s\n", err);
    floe_world_destroy(w);
}

int main(void) {
    test_steady_load();
    test_errors();
    return check_summary("test_coast_load");
}
