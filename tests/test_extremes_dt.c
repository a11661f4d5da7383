/* test_extremes_dt.c - the extremes of issue #5 for what tests/test_extremes.c does not
 * cover: the same head-on Hertz-Mindlin collisions (E = 1e3 .. 1e12 Pa, speeds 1e-6 .. 1e3
 * m/s, mass ratios up to 1e6) with leapfrog, RK2 and adaptive steps; PD bodies from 1e3 to
 * 1e12 Pa with the automatic step; and the outputs written at a failure. Each run either
 * restitutes e = 0.5 within 5 % (PD: keeps momentum and a finite state) or stops with a
 * message naming the particles; no state and no output line is ever NaN or infinite. */
#include "check.h"
#include "head_on.h"
#include "floe_pd.h"
#include "floe.h"
#include "world_read.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int finite_state(const floe_world *w) {
    for (int i = 0; i < 3 * pview(w).n; i++)
        if (!isfinite(pview(w).x[i]) || !isfinite(pview(w).v[i])) return 0;
    return 1;
}

static void collide(int integ, int adaptive, double E, double v0, double ratio) {
    floe_world_def d = floe_default_world_def();
    d.integrator = integ;
    d.adaptive = adaptive;
    int rc;
    long in_contact;
    floe_world *w = head_on_collision(d, E, v0, ratio, &rc, &in_contact);
    char what[160];
    snprintf(what, sizeof what, "%s%s E=%.0e v=%.0e ratio %.0e", adaptive ? "adaptive " : "", floe_integrator_name(integ),
             E, v0, ratio);
    CHECK(finite_state(w), "%s: finite state", what);
    if (rc) {
        CHECK(strstr(floe_world_last_error(w), "particle") != NULL, "%s: failed without naming a particle: %s", what,
              floe_world_last_error(w));
    } else {
        /* leapfrog's stored velocities are those of half a step back: after the contact
         * they are the outgoing ones */
        double e = (pview(w).v[3] - pview(w).v[0]) / v0;
        char w2[256];
        snprintf(w2, sizeof w2, "%s: restitution", what);
        CHECK_NEAR(e, 0.5, 0.05, w2);
    }
    floe_world_destroy(w);
}

/* a PD cube of 4 x 4 x 4 points, one face moving at 1 m/s, automatic step */
static void pd_stiffness(double K) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = 1e-3;
    r.horizon_factor = 3;
    floe_v3_set(r.hi, 4e-3, 4e-3, 4e-3);
    floe_pd_body *b = NULL;
    floe_pd_body_create(&b, &r);
    floe_pd_material pm = floe_pd_material_pmb(1000, K, 0);
    floe_pd_set_material(b, &pm);
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 1000, 3 * K * 0.5, 0.25};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.0));
    int f0;
    floe_world_add_pd_body(w, b, 0, NULL, &f0);
    double P0 = 0;
    for (int i = 0; i < b->n; i++)
        if (b->X[3 * i] < 1e-3) { set_vel(w, f0 + i, 0, 1.0); P0 += pview(w).mass[f0 + i]; }
    int rc = floe_world_prepare(w);
    for (int s = 0; s < 400 && !rc; s++) rc = floe_world_step(w);
    double P = 0;
    for (int i = 0; i < pview(w).n; i++) P += pview(w).mass[i] * pview(w).v[3 * i];
    printf("  PD K = %.0e Pa: dt %.3g s (nodal %.3g s), %s, momentum %.6g of %.6g\n", K, floe_world_dt(w),
           floe_pd_dt_nodal(b), rc ? floe_world_last_error(w) : "400 steps", P, P0 * 1.0);
    CHECK(rc == FLOE_OK && finite_state(w), "PD K = %.0e: stable with the automatic step: %s", K, floe_world_last_error(w));
    CHECK(fabs(P - P0) < 1e-9 * P0, "PD K = %.0e: momentum kept (%.3g)", K, (P - P0) / P0);
    floe_world_destroy(w);
}

/* a failing run (too soft for the speed) writes its state at the failure: no NaN in it */
static void outputs_at_failure(void) {
    char dir[] = "/tmp/floe_extremes_XXXXXX";
    CHECK(mkdtemp(dir) != NULL, "temporary directory");
    char path[256], err[256];
    snprintf(path, sizeof path, "%s/particles.csv", dir);
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 2500, 1e3, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.0));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.01));
    floe_particle_def a = floe_default_particle_def(), b = floe_default_particle_def();
    a.geometry = b.geometry = g;
    floe_v3_set(a.v, 1.0, 0, 0);
    floe_v3_set(b.x, 0.02, 0, 0);
    floe_world_add_particle(w, &a);
    floe_world_add_particle(w, &b);
    floe_observer *o = floe_csv_writer_create(path, err, sizeof err);
    CHECK(o != NULL, "csv writer: %s", err);
    if (o) { o->period_steps = 1; floe_world_add_observer(w, o); }
    int rc = floe_world_run(w, 0.1, NULL, NULL);
    CHECK(rc == FLOE_EUNSTABLE, "the soft collision stops (rc %d)", rc);
    FILE *f = fopen(path, "r");
    long lines = 0, bad = 0;
    char line[4096];
    while (f && fgets(line, sizeof line, f)) {
        lines++;
        for (char *c = line; *c; c++) *c = (char)(*c | 0x20);
        if (strstr(line, "nan") || strstr(line, "inf")) bad++;
    }
    if (f) fclose(f);
    printf("  output at failure: %ld lines, %ld with nan/inf\n", lines, bad);
    CHECK(lines > 2 && bad == 0, "the output written up to the failure has no NaN/inf (%ld of %ld lines)", bad, lines);
    floe_world_destroy(w);
    unlink(path);
    rmdir(dir);
}

int main(void) {
    const double Es[3] = {1e3, 1e7, 1e12}, vs[3] = {1e-6, 1.0, 1e3};
    const int integ[4] = {FLOE_LEAPFROG, FLOE_RK2, FLOE_VELOCITY_VERLET, FLOE_RK2}, adapt[4] = {0, 0, 1, 1};
    for (int k = 0; k < 4; k++) {
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) collide(integ[k], adapt[k], Es[a], vs[b], 1.0);
        collide(integ[k], adapt[k], 1e7, 1.0, 1e6);
    }
    const double Ks[4] = {1e3, 1e6, 1e9, 1e12};
    for (int k = 0; k < 4; k++) pd_stiffness(Ks[k]);
    outputs_at_failure();
    return check_summary("test_extremes_dt");
}
