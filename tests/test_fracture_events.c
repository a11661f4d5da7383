/* test_fracture_events.c - the fracture_events output (observers/fracture_events.c,
 * docs/sea-ice.md "Outputs"): one CSV row per beam-bond break.
 *  - a pair pulled apart: a fixed disc and a kinematic one moved away at u, so the axial
 *    stress grows by E u dt / l0 per step exactly; the bond breaks at the first step n with
 *    n E u dt / l0 > sigma_t: one row, mode tension, at t = n dt (to one step), its step
 *    n, the midpoint of the centres then, a stress above the strength by at most one
 *    step's increment; the output observed every 37 steps (the break between two rows);
 *  - the same pair pushed together: mode compression;
 *  - three pairs of strengths 1e5, 1.5e5, 2e5 Pa pulled together, observed every 5,000
 *    steps: all three breaks in one observation, each once, ordered by time;
 *  - the output named in a scene (`type: fracture_events`, `file`): two free bonded discs
 *    flying apart give one tension row. */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const double E = 1e9, U = 1e-4, DT = 1e-3, L0 = 2.0;

typedef struct fe_row {
    double t, x, y, z, stress, strength;
    long step;
    int i, j;
    char mode[16];
} fe_row;

/* the rows of a fracture_events CSV (header checked); returns how many, -1 if unreadable */
static int read_rows(const char *path, fe_row *rows, int cap) {
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char line[512];
    int n = 0;
    if (!fgets(line, sizeof line, f) || strncmp(line, "t [s],step,i,j,mode,", 20)) {
        fclose(f);
        return -1;
    }
    while (fgets(line, sizeof line, f)) {
        fe_row r;
        if (sscanf(line, "%lf,%ld,%d,%d,%15[a-z],%lf,%lf,%lf,%lf,%lf", &r.t, &r.step, &r.i, &r.j, r.mode, &r.x, &r.y,
                   &r.z, &r.stress, &r.strength) != 10) {
            n = -1;
            break;
        }
        if (n < cap) rows[n] = r;
        n++;
    }
    fclose(f);
    return n;
}

/* a world of npairs (fixed disc at (0, 4k), kinematic disc at (2, 4k) moving at v), one
 * bond per pair with its strength in mode (1 tension, 3 compression) */
static floe_world *pairs_world(int npairs, const double *strength, int mode, double v) {
    floe_world_def d = floe_default_world_def();
    d.dim = 2;
    d.mass_2d_area = 1;
    d.dt = DT;
    d.allow_unstable_dt = 1;
    d.gravity[0] = d.gravity[1] = d.gravity[2] = 0;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"ice", 920, E, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(1e6, 0, 0, 0, 0));
    int g = floe_world_add_geometry(w, floe_sphere_create(1.0));
    for (int k = 0; k < npairs; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        p.x[1] = 4.0 * k;
        p.motion = FLOE_FIXED;
        floe_world_add_particle(w, &p);
        p.x[0] = L0;
        p.motion = FLOE_KINEMATIC;
        p.v[0] = v;
        floe_world_add_particle(w, &p);
        floe_beam_params bp = floe_default_beam_params();
        bp.young = E;
        bp.poisson = 0.3;
        if (mode == 1) bp.tensile_strength = strength[k];
        else bp.compressive_strength = strength[k];
        CHECK(floe_world_add_beam_bond(w, 2 * k, 2 * k + 1, &bp) >= 0, "bond: %s", floe_world_last_error(w));
    }
    return w;
}

/* run nsteps with the output every `every` steps; the rows into rows */
static int run_pairs(floe_world *w, const char *path, long every, long nsteps, fe_row *rows, int cap) {
    char err[256];
    floe_observer *o = floe_fracture_events_create(path, err, sizeof err);
    CHECK(o != NULL, "fracture_events: %s", err);
    if (!o) return -1;
    o->period_steps = every;
    CHECK(floe_world_add_observer(w, o) == FLOE_OK, "add observer: %s", floe_world_last_error(w));
    for (long s = 0; s < nsteps; s++)
        if (floe_world_step(w) != FLOE_OK) {
            CHECK(0, "step %ld: %s", s, floe_world_last_error(w));
            break;
        }
    floe_world_finish(w);
    return read_rows(path, rows, cap);
}

static void test_pair(int mode) {
    const char *what = mode == 1 ? "tension" : "compression";
    const double lim = 2e5, per_step = E * U * DT / L0; /* 50 Pa a step */
    const long n = (long)floor(lim / per_step) + 1;       /* first step with n x 50 > 2e5 */
    floe_world *w = pairs_world(1, &lim, mode, mode == 1 ? U : -U);
    char path[] = "/tmp/floe_fe_XXXXXX";
    int fd = mkstemp(path);
    if (fd >= 0) close(fd);
    fe_row r[4];
    int nr = run_pairs(w, path, 37, n + 500, r, 4);
    CHECK(nr == 1, "%s: exactly one row (got %d)", what, nr);
    if (nr == 1) {
        CHECK(!strcmp(r[0].mode, what), "%s: mode %s", what, r[0].mode);
        CHECK(fabs(r[0].t - n * DT) <= DT * (1 + 1e-9), "%s: broke at t = %.6g s, expected %.6g s (one step %g)", what,
              r[0].t, n * DT, DT);
        CHECK(labs(r[0].step - n) <= 1 && fabs(r[0].step * DT - r[0].t) < 1e-9, "%s: step %ld at t = %g (expected %ld)",
              what, r[0].step, r[0].t, n);
        double u = (mode == 1 ? U : -U) * r[0].t;
        CHECK(fabs(r[0].x - 0.5 * (L0 + u)) < 1e-9 && fabs(r[0].y) < 1e-12 && r[0].i == 0 && r[0].j == 1,
              "%s: bond 0-1 at its midpoint (%g, %g), expected (%g, 0)", what, r[0].x, r[0].y, 0.5 * (L0 + u));
        CHECK(r[0].strength == lim && r[0].stress > lim && r[0].stress <= lim + per_step * (1 + 1e-6),
              "%s: stress %.8g above the strength %.8g by at most one step's %g Pa", what, r[0].stress, r[0].strength,
              per_step);
        printf("  %-12s one row: t = %.4f s (expected %.4f), step %ld, stress %.1f Pa of %.1f Pa, midpoint x %.6f m\n",
               what, r[0].t, n * DT, r[0].step, r[0].stress, r[0].strength, r[0].x);
    }
    floe_world_destroy(w);
    remove(path);
}

static void test_three_pairs(void) {
    const double lim[3] = {2e5, 1e5, 1.5e5};
    floe_world *w = pairs_world(3, lim, 1, U);
    char path[] = "/tmp/floe_fe_XXXXXX";
    int fd = mkstemp(path);
    if (fd >= 0) close(fd);
    fe_row r[8];
    int nr = run_pairs(w, path, 5000, 4600, r, 8);
    CHECK(nr == 3, "three pairs: three rows (got %d)", nr);
    if (nr == 3) {
        CHECK(r[0].i == 2 && r[1].i == 4 && r[2].i == 0, "three pairs: in the order they broke (bonds %d, %d, %d)", r[0].i,
              r[1].i, r[2].i);
        CHECK(r[0].t < r[1].t && r[1].t < r[2].t, "three pairs: times increase (%g, %g, %g)", r[0].t, r[1].t, r[2].t);
        for (int k = 0; k < 3; k++)
            CHECK(fabs(r[k].y - 4.0 * (r[k].i / 2)) < 1e-12 && r[k].j == r[k].i + 1, "three pairs: row %d at its pair", k);
        printf("  three pairs, one observation: bonds %d-%d, %d-%d, %d-%d at %.3f, %.3f, %.3f s\n", r[0].i, r[0].j, r[1].i,
               r[1].j, r[2].i, r[2].j, r[0].t, r[1].t, r[2].t);
    }
    floe_world_destroy(w);
    remove(path);
}

static void test_scene(void) {
    char dir[] = "/tmp/floe_fe_dir_XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return;
    }
    const char *text =
        "dimension: 2\nmass_2d: area\ntime: {duration: 2, dt: 1e-4}\ngravity: [0, 0]\n"
        "materials: [{name: ice, density: 920, young: 1e9, poisson: 0.3}]\n"
        "laws: [{materials: [ice, ice], model: linear, kn: 1e6, ks: 0}]\n"
        "bodies:\n"
        "  - {material: ice, position: [0, 0], velocity: [-1, 0], shape: {sphere: {radius: 1}}}\n"
        "  - {material: ice, position: [2, 0], velocity: [1, 0], shape: {sphere: {radius: 1}}}\n"
        "bonds:\n"
        "  - {young: 1e9, poisson: 0.3, radius_factor: 1.01, tensile_strength: 1e6}\n"
        "outputs:\n"
        "  - {type: fracture_events, every: 100, file: breaks.csv}\n";
    char err[1024] = "";
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_ex("t.yaml", text, dir, 1, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "fracture scene: %s", err);
    if (rc == FLOE_OK) {
        CHECK(floe_world_run(w, info.duration, NULL, NULL) == FLOE_OK, "run: %s", floe_world_last_error(w));
        floe_world_finish(w);
    }
    floe_world_destroy(w);
    char path[256];
    snprintf(path, sizeof path, "%s/breaks.csv", dir);
    fe_row r[4];
    int nr = read_rows(path, r, 4);
    CHECK(nr == 1 && !strcmp(r[0].mode, "tension") && r[0].i == 0 && r[0].j == 1,
          "scene: one tension row for bond 0-1 (got %d rows)", nr);
    if (nr == 1) printf("  scene output: bond 0-1 broke in %s at t = %.4f s, step %ld\n", r[0].mode, r[0].t, r[0].step);
    remove(path);
    rmdir(dir);
}

int main(void) {
    test_pair(1);
    test_pair(3);
    test_three_pairs();
    test_scene();
    return check_summary("test_fracture_events");
}
