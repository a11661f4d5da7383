/* test_watchdog.c - the energy watchdog (core/world/world.c energy_watchdog, issue 10 A):
 *   1. staggered PD-DEM that blows up: a rigid sphere at 1 m/s into an LPS block with
 *      pd_dem {scheme: staggered, substeps: m}, the PD step held at 0.5 x the PD nodal
 *      estimate and the DEM step m times that (as bench/multiscale does); with checks off
 *      the total energy peaks above 2x the impact energy for m = 5, 6, 8 and the run still
 *      finishes; with the default (stop) floe_world_run fails with FLOE_EUNSTABLE naming
 *      PD body 0 and suggesting fewer substeps, after the observers flushed (the energy
 *      CSV's last row is the stopping step); m = 2 runs to the end without tripping;
 *   2. a contact law that creates energy (a spring with negative damping, tests/pump_law.h):
 *      stop names the pair and the law; warn prints once and the run goes on; off checks
 *      nothing;
 *   3. legit runs never trip it: an elastic bouncing sphere at the default step, and a
 *      two-particle linear spring at 0.95 x its stability limit (the measured K + U
 *      oscillates by up to 10x there; the watchdog compares velocity Verlet's conserved
 *      form, shadow_term);
 *   4. the scene key checks: {energy: stop | warn | off, energy_tolerance} and the C API
 *      (floe_world_def.energy_check, floe_world_set_energy_check) refuse bad values. */
#include "check.h"
#include "floe.h"
#include "floe_pd.h"
#include "floe_scene.h"
#include "floe.h"
#include "world_read.h"
#include "pump_law.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- 1. staggered PD-DEM ---- */

static const char *stag_scene =
    "name: stag-impact\n"
    "dimension: 3\n"
    "time: {duration: 0.02, dt: %g, allow_unstable_dt: true, pd_dem: {scheme: staggered, substeps: %d}}\n"
    "gravity: [0, 0, 0]\n"
    "%s"
    "materials:\n"
    "  - {name: rigid, density: 2650, young: 1.0e10, poisson: 0.25}\n"
    "  - {name: rubber, density: 1100, young: 1.0e10, poisson: 0.25}\n"
    "laws:\n"
    "  - {materials: [rigid, rubber], model: hertz_mindlin, restitution: 0.5}\n"
    "  - {materials: [rubber, rubber], model: hertz_mindlin, restitution: 0.5}\n"
    "bodies:\n"
    "  - {name: ball, shape: {sphere: {radius: 0.05}}, material: rigid, position: [0, 0, 0.141], velocity: [0, 0, -1]}\n"
    "peridynamics:\n"
    "  - name: block\n"
    "    region: {box: {min: [-0.105, -0.105, -0.075], max: [0.105, 0.105, 0.075]}}\n"
    "    spacing: 0.03\n"
    "    horizon: 2\n"
    "    material: {model: lps, density: 1100, bulk_modulus: 6.667e7, shear_modulus: 4.0e7}\n"
    "    contact_material: rubber\n"
    "outputs:\n"
    "  - {type: energy, every: 1000000, file: energy.csv}\n";

static floe_world *stag_world(int m, const char *checks, const char *outdir) {
    /* the PD nodal estimate of this block, from a first load with m = 1 */
    static double nodal = 0;
    char text[4096], err[1024];
    floe_scene_info info;
    floe_world *w = NULL;
    if (nodal == 0) {
        snprintf(text, sizeof text, stag_scene, 1e-6, 1, "");
        int rc = floe_scene_load_string(text, "<stag>", outdir, &w, &info, err, sizeof err);
        CHECK(rc == FLOE_OK, "staggered scene: %s", err);
        if (rc) return NULL;
        floe_dt_estimates e;
        floe_world_dt_estimates(w, &e);
        nodal = e.dt[FLOE_DT_PD_NODAL];
        floe_world_destroy(w);
        w = NULL;
    }
    snprintf(text, sizeof text, stag_scene, m * 0.5 * nodal, m, checks);
    int rc = floe_scene_load_string(text, "<stag>", outdir, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "staggered scene m = %d: %s", m, err);
    return rc ? NULL : w;
}

/* last time in an energy CSV (-1 if none) */
static double csv_last_time(const char *path) {
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char line[1024];
    double t = -1;
    while (fgets(line, sizeof line, f))
        if (line[0] >= '0' && line[0] <= '9') t = atof(line);
    fclose(f);
    return t;
}

static void test_staggered_blowup(void) {
    const char *dir = "out_watchdog";
    const int ms[3] = {5, 6, 8};
    for (int k = 0; k < 3; k++) {
        const int m = ms[k];
        /* checks off: the scheme blows up and the run still "finishes" */
        floe_world *w = stag_world(m, "checks: {energy: off}\n", dir);
        if (!w) return;
        floe_energy e = floe_world_energy(w);
        const double e0 = e.initial;
        double peak = e0;
        int rc = 0;
        while (!rc && floe_world_time(w) < 0.02) {
            rc = floe_world_step(w);
            e = floe_world_energy(w);
            peak = fmax(peak, e.kinetic_trans + e.kinetic_rot + e.elastic);
        }
        printf("  staggered m = %d, checks off: total energy peaks at %.1fx the impact energy (rc %d)\n", m, peak / e0,
               rc);
        CHECK(peak > 2 * e0, "m = %d blows up without the watchdog (peak %.2fx)", m, peak / e0);
        floe_world_destroy(w);
        /* the default: stopped, naming the PD body and the remedy, observers flushed */
        w = stag_world(m, "", dir);
        if (!w) return;
        rc = floe_world_run(w, 0.02, NULL, NULL);
        const char *msg = floe_world_last_error(w);
        printf("  staggered m = %d, default checks: %s\n", m, msg);
        CHECK(rc == FLOE_EUNSTABLE, "m = %d stopped (rc %d)", m, rc);
        CHECK(strstr(msg, "energy watchdog") && strstr(msg, "PD body 0") && strstr(msg, "fewer substeps") &&
                  strstr(msg, "step"), "m = %d: the message names the step, the PD body and fewer substeps", m);
        floe_energy_check_state st;
        floe_world_energy_check(w, &st);
        CHECK(st.tripped_step == floe_world_step_count(w) && st.created > 0.05,
              "m = %d: tripped at the last step (%ld of %ld), created %.3g", m, st.tripped_step,
              floe_world_step_count(w), st.created);
        double tl = csv_last_time("out_watchdog/energy.csv");
        CHECK(fabs(tl - floe_world_time(w)) <= 1e-9 * floe_world_time(w),
              "m = %d: the energy observer flushed the stopping step (last row t = %.9g, stop t = %.9g)", m, tl,
              floe_world_time(w));
        CHECK(floe_world_time(w) < 0.015, "m = %d stopped before the end (t = %g s)", m, floe_world_time(w));
        floe_world_destroy(w);
    }
    /* m = 2 with the same PD step: stable, no trip */
    floe_world *w = stag_world(2, "", dir);
    if (!w) return;
    int rc = floe_world_run(w, 0.02, NULL, NULL);
    floe_energy_check_state st;
    floe_world_energy_check(w, &st);
    printf("  staggered m = 2: %s, largest creation %.2e of the scale\n", rc ? floe_world_last_error(w) : "ran", st.created);
    CHECK(rc == FLOE_OK && st.tripped_step < 0 && st.created < 0.01, "m = 2 runs to the end (created %.2e)", st.created);
    floe_world_destroy(w);
}

/* ---- 2. a contact law that creates energy (pump_law.h) ---- */

/* a sphere (R 0.1 m, steel-like) dropped at 1 m/s onto a wall with law l; returns rc */
static int bounce(floe_contact_law *law, int mode, floe_world **out) {
    floe_world_def d = floe_default_world_def();
    d.energy_check = mode;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material mt = {"m", 7800, 2e11, 0.3};
    int mat = floe_world_add_material(w, &mt);
    floe_world_set_law(w, mat, mat, law);
    int g = floe_world_add_geometry(w, floe_sphere_create(0.1));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = g;
    p.material = mat;
    floe_v3_set(p.x, 0, 0, 0.1005);
    floe_v3_set(p.v, 0, 0, -1);
    floe_world_add_particle(w, &p);
    double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, mat, FLOE_FIXED);
    int rc = floe_world_run(w, 0.02, NULL, NULL);
    *out = w;
    return rc;
}

static void test_creating_law(void) {
    const double mass = 7800 * 4.0 / 3.0 * M_PI * 1e-3, k = 1e7;
    floe_world *w;
    /* stop (the default) */
    int rc = bounce(pump_create(mass, k, 0.1), FLOE_CHECK_STOP, &w);
    const char *msg = floe_world_last_error(w);
    printf("  negative damping, stop: %s\n", msg);
    CHECK(rc == FLOE_EUNSTABLE && strstr(msg, "particles 0 and 1") && strstr(msg, "pump (test)") &&
              strstr(msg, "contact law creates energy"),
          "a creating law stops the run naming the pair and the law (rc %d)", rc);
    floe_particle_state ps;
    floe_world_get_particle(w, 0, &ps);
    CHECK(floe_world_contact_count(w) == 1, "stopped during the first contact (the law pulls at onset: v_z %.3g m/s)",
          ps.v[2]);
    floe_world_destroy(w);
    /* warn: one message on stderr, the run finishes */
    fflush(stderr);
    FILE *tmp = tmpfile();
    int saved = dup(fileno(stderr));
    dup2(fileno(tmp), fileno(stderr));
    rc = bounce(pump_create(mass, k, 0.1), FLOE_CHECK_WARN, &w);
    fflush(stderr);
    dup2(saved, fileno(stderr));
    close(saved);
    rewind(tmp);
    char buf[8192];
    size_t nr = fread(buf, 1, sizeof buf - 1, tmp);
    buf[nr] = 0;
    fclose(tmp);
    int count = 0;
    for (const char *q = buf; (q = strstr(q, "energy watchdog")); q++) count++;
    floe_energy_check_state st;
    floe_world_energy_check(w, &st);
    floe_world_get_particle(w, 0, &ps);
    printf("  negative damping, warn: rc %d, %d message(s), tripped at step %ld, created %.2f of the scale, "
           "rebound %.3g m/s\n", rc, count, st.tripped_step, st.created, ps.v[2]);
    CHECK(rc == FLOE_OK && count == 1 && st.tripped_step > 0 && strstr(st.message, "particles 0 and 1"),
          "warn prints once and goes on (rc %d, %d messages)", rc, count);
    CHECK(ps.v[2] > 1.0, "the law really creates energy: rebound %.3g m/s > 1 m/s", ps.v[2]);
    floe_world_destroy(w);
    /* off */
    rc = bounce(pump_create(mass, k, 0.1), FLOE_CHECK_OFF, &w);
    floe_world_energy_check(w, &st);
    CHECK(rc == FLOE_OK && st.tripped_step < 0 && st.created == 0, "off checks nothing (rc %d)", rc);
    floe_world_destroy(w);
    /* the same law with positive damping: dissipates, no trip */
    rc = bounce(pump_create(mass, k, -0.1), FLOE_CHECK_STOP, &w);
    floe_world_energy_check(w, &st);
    printf("  positive damping: rc %d, largest creation %.2e of the scale\n", rc, st.created);
    CHECK(rc == FLOE_OK && st.created < 1e-3, "a dissipating law does not trip (%.2e)", st.created);
    floe_world_destroy(w);
}

/* ---- 3. legit runs ---- */

static void spring_force(const floe_world *w, int i, double t, double f[3], double tq[3], void *user) {
    (void)t;
    (void)tq;
    f[0] = -*(const double *)user * pview(w).x[3 * i];
}

static void test_legit(void) {
    /* Hertz-Mindlin e = 1 bounce at the automatic step */
    floe_world *w;
    floe_material mt = {"m", 7800, 2e11, 0.3};
    int rc = bounce(floe_hertz_mindlin_law_create(&mt, &mt, 1.0, 0.3), FLOE_CHECK_STOP, &w);
    floe_energy_check_state st;
    floe_world_energy_check(w, &st);
    printf("  elastic Hertz bounce: rc %d, largest creation %.2e\n", rc, st.created);
    CHECK(rc == FLOE_OK && st.created < 1e-3, "elastic bounce does not trip (%.2e)", st.created);
    floe_world_destroy(w);
    /* a particle on a linear spring (a body-force callback, F = -k x) at 0.95 x its limit
     * 2/w: K + U as measured oscillates by up to 1/(1 - 0.95^2) = 10x; the form velocity
     * Verlet conserves stays put */
    floe_world_def d = floe_default_world_def();
    static double k = 1e6;
    const double m = 1.0, R = 0.1;
    d.dt = 0.95 * 2 / sqrt(k / m);
    w = floe_world_create(&d, NULL, 0);
    floe_material mm = {"m", m / (4.0 / 3.0 * M_PI * R * R * R), 1e9, 0.3};
    int mat = floe_world_add_material(w, &mm);
    int g = floe_world_add_geometry(w, floe_sphere_create(R));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = g;
    p.material = mat;
    floe_v3_set(p.v, 0.3, 0, 0);
    floe_world_add_particle(w, &p);
    floe_world_set_body_force(w, spring_force, &k);
    rc = floe_world_prepare(w);
    double e0 = floe_world_energy(w).initial, emax = 0;
    for (int s = 0; s < 2000 && !rc; s++) {
        rc = floe_world_step(w);
        floe_energy e = floe_world_energy(w);
        emax = fmax(emax, e.kinetic_trans + 0.5 * k * pview(w).x[0] * pview(w).x[0]);
    }
    floe_world_energy_check(w, &st);
    printf("  spring at 0.95 x 2/w: measured K + U up to %.2fx the initial, rc %d, largest creation %.2e\n", emax / e0,
           rc, st.created);
    CHECK(emax > 3 * e0, "the measured energy does oscillate (%.2fx)", emax / e0);
    CHECK(rc == FLOE_OK && st.created < 1e-9, "a stable step near the limit does not trip (%.2e)", st.created);
    floe_world_destroy(w);
}

/* ---- 4. scene key and API ---- */

static void test_keys(void) {
    static const char *base = "time: {duration: 0.001}\n"
                              "materials: [{name: m, density: 1000, young: 1e7, poisson: 0.3}]\n"
                              "laws: [{materials: [m, m], model: linear, kn: 1e5, ks: 0}]\n"
                              "bodies: [{shape: {sphere: {radius: 0.1}}, material: m, position: [0, 0, 0]}]\n"
                              "%s";
    const char *keys[5] = {"", "checks: {energy: warn}\n", "checks: {energy: off}\n",
                           "checks: {energy: stop, energy_tolerance: 0.02}\n", "checks: {energy: maybe}\n"};
    const int modes[4] = {FLOE_CHECK_STOP, FLOE_CHECK_WARN, FLOE_CHECK_OFF, FLOE_CHECK_STOP};
    const double tols[4] = {0.05, 0.05, 0.05, 0.02};
    for (int k = 0; k < 5; k++) {
        char text[1024], err[512];
        snprintf(text, sizeof text, base, keys[k]);
        floe_world *w = NULL;
        floe_scene_info info;
        int rc = floe_scene_load_ex("<checks>", text, NULL, 0, &w, &info, err, sizeof err);
        if (k < 4) {
            CHECK(rc == FLOE_OK, "checks scene %d: %s", k, err);
            if (rc) continue;
            floe_energy_check_state st;
            floe_world_energy_check(w, &st);
            CHECK(st.mode == modes[k] && st.tolerance == tols[k], "'%s': mode %s, tolerance %g", keys[k],
                  floe_energy_check_name(st.mode), st.tolerance);
            floe_world_destroy(w);
        } else {
            printf("  %s", err);
            printf("\n");
            CHECK(rc != FLOE_OK && strstr(err, ":5:") && strstr(err, "stop, warn, off"),
                  "a bad checks.energy is refused with its line and the valid values: %s", err);
        }
    }
    floe_world_def d = floe_default_world_def();
    CHECK(d.energy_check == FLOE_CHECK_STOP && d.energy_check_tol == 0.05, "default: stop at 5 %%");
    d.energy_check = 7;
    char err[256];
    CHECK(floe_world_create(&d, err, sizeof err) == NULL && strstr(err, "energy_check"), "bad mode refused");
    d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    CHECK(floe_world_set_energy_check(w, FLOE_CHECK_WARN, 0.1) == FLOE_OK, "setter");
    CHECK(floe_world_set_energy_check(w, 3, 0.1) == FLOE_EINVAL, "setter refuses a bad mode");
    CHECK(floe_world_set_energy_check(w, FLOE_CHECK_OFF, 1.5) == FLOE_EINVAL, "setter refuses a bad tolerance");
    floe_energy_check_state st;
    floe_world_energy_check(w, &st);
    CHECK(st.mode == FLOE_CHECK_WARN && st.tolerance == 0.1 && st.tripped_step == -1, "setter kept warn, 0.1");
    floe_world_destroy(w);
}

int main(void) {
    test_keys();
    test_legit();
    test_creating_law();
    test_staggered_blowup();
    return check_summary("test_watchdog");
}
