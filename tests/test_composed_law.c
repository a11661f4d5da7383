/* test_composed_law.c - contact laws composed of a normal and a tangential part
 * (contact/laws/composed_law.c, MercuryDPM style) against the fused built-in laws:
 *  1. hertz + mindlin = hertz_mindlin and hooke + coulomb = viscoelastic (also with
 *     tension) over a loaded, sliding, rotating contact of 400 steps: force, energy,
 *     dissipation and history equal to 1e-12 relative (the same kernels, law_parts.h);
 *  2. a normal part alone is frictionless (zero tangential force while sliding);
 *  3. two worlds of colliding spheres, one with each form: the same critical step (the
 *     law's info is forwarded) and the same trajectory to 1e-12 after the collision;
 *  4. a scene composes parts by name, and a misspelled part gets the closest name. */
#include "check.h"
#include "floe.h"
#include <string.h>

/* a contact state that loads, slides and turns: depth up then down, a tangential velocity
 * that reverses, a normal that rotates slowly about z */
static void state(floe_contact *c, int k, double R, double m, double dt) {
    memset(c, 0, sizeof *c);
    double th = 0.002 * k, ph = 6.283185307179586 * k / 400.0;
    floe_v3_set(c->n, cos(th), sin(th), 0);
    c->depth = R * (0.002 + 0.01 * sin(0.5 * ph) * sin(0.5 * ph));
    c->vn = 0.3 * cos(0.5 * ph);
    double t[3] = {-sin(th), cos(th), 0}, b[3] = {0, 0, 1};
    for (int a = 0; a < 3; a++) c->vt[a] = 0.05 * cos(1.7 * ph) * t[a] + 0.02 * sin(ph) * b[a];
    for (int a = 0; a < 3; a++) c->vr[a] = c->vt[a] + c->vn * c->n[a];
    c->r_eff = R;
    c->m_eff = m;
    c->dt = dt;
    c->gscale = 1.0;
    c->fn_extra = k % 50 == 0 ? 0.1 : 0.0;
}

static double relerr(double a, double b) { return fabs(a - b) / fmax(fabs(b), 1e-300); }

static void compare(const char *what, floe_contact_law *fused, floe_contact_law *comp, double R, double m,
                    double dt) {
    double h1[FLOE_MAX_HISTORY] = {0}, h2[FLOE_MAX_HISTORY] = {0};
    double worst = 0, fscale = 0, slips = 0;
    int rc = 0;
    for (int k = 0; k < 400; k++) {
        floe_contact c;
        state(&c, k, R, m, dt);
        floe_contact_result a, b;
        rc |= fused->klass->force(fused, &c, h1, &a);
        rc |= comp->klass->force(comp, &c, h2, &b);
        fscale = fmax(fscale, floe_v3_norm(a.force));
        for (int q = 0; q < 3; q++) {
            worst = fmax(worst, fabs(a.force[q] - b.force[q]) / fmax(floe_v3_norm(a.force), 1e-300));
            worst = fmax(worst, fabs(h1[q] - h2[q]) / fmax(floe_v3_norm(h1), 1e-300));
        }
        worst = fmax(worst, relerr(b.energy, a.energy));
        worst = fmax(worst, fabs(b.dissipation - a.dissipation) / fmax(a.energy, 1e-300));
        worst = fmax(worst, relerr(b.fn, a.fn));
        worst = fmax(worst, fabs(h1[3] - h2[3]));
        double ft[3];
        for (int q = 0; q < 3; q++) ft[q] = a.force[q] + a.fn * c.n[q];
        if (floe_v3_norm(ft) > 0.999 * 0.4 * a.fn && a.fn > 0) slips++;
    }
    CHECK(rc == 0, "%s: a law failed", what);
    CHECK(slips > 10, "%s: the path should slip (Coulomb limit reached %g times)", what, slips);
    printf("  %-40s worst relative difference %.2e over 400 steps (max |F| %.3g N, %g slipping)\n", what, worst,
           fscale, slips);
    CHECK(worst <= 1e-12, "%s: composed and fused differ by %.3g (tol 1e-12)", what, worst);
    floe_contact_law_destroy(fused);
    floe_contact_law_destroy(comp);
}

/* two spheres colliding obliquely with spin; returns the world after nsteps */
static floe_world *collide(floe_contact_law *law, const floe_material *mt, int nsteps) {
    floe_world_def def = floe_default_world_def();
    char err[256];
    floe_world *w = floe_world_create(&def, err, sizeof err);
    floe_world_add_material(w, mt);
    floe_world_set_law(w, 0, 0, law);
    int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = g;
    floe_v3_set(p.v, 0.2, 0.0, 0.0);
    floe_v3_set(p.w, 0, 0, 30);
    floe_world_add_particle(w, &p);
    floe_v3_set(p.x, 0.00205, 0.0008, 0);
    floe_v3_set(p.v, -0.1, 0, 0);
    floe_v3_set(p.w, 0, 0, 0);
    floe_world_add_particle(w, &p);
    if (floe_world_prepare(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return w; }
    for (int s = 0; s < nsteps; s++)
        if (floe_world_step(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); break; }
    return w;
}

int main(void) {
    floe_material glass = {"glass", 2500, 1e7, 0.3}, steel = {"steel", 7800, 2e11, 0.28};
    const double R = 0.001, m = 1e-5;
    double dt = 1e-6;
    printf("1. composed = fused, step by step\n");
    compare("hertz + mindlin = hertz_mindlin", floe_hertz_mindlin_law_create(&glass, &steel, 0.5, 0.4),
            floe_composed_law_create(floe_hertz_part_create(&glass, &steel, 0.5),
                                     floe_mindlin_part_create(&glass, &steel, 0.4)),
            R, m, dt);
    const double kn = 2e4, gn = 0.3 * 2 * sqrt(kn * m), ks = 1e4, gs = 0.1;
    compare("hooke + coulomb = viscoelastic", floe_linear_law_create(kn, ks, gn, gs, 0.4),
            floe_composed_law_create(floe_hooke_part_create(kn, gn, 0), floe_coulomb_part_create(0.4, ks, gs)), R, m,
            1e-5);
    floe_contact_law *lt = floe_linear_law_create(kn, ks, gn, gs, 0.4);
    ((floe_linear_law *)lt)->tension = 1;
    compare("hooke(tension) + coulomb = linear(tension)", lt,
            floe_composed_law_create(floe_hooke_part_create(kn, gn, 1), floe_coulomb_part_create(0.4, ks, gs)), R, m,
            1e-5);

    printf("2. a normal part alone is frictionless\n");
    floe_contact_law *nf = floe_composed_law_create(floe_hertz_part_create(&glass, &glass, 0.9), NULL);
    double h[FLOE_MAX_HISTORY] = {0}, worst_t = 0;
    for (int k = 0; k < 100; k++) {
        floe_contact c;
        state(&c, k, R, m, dt);
        floe_contact_result r;
        nf->klass->force(nf, &c, h, &r);
        for (int q = 0; q < 3; q++) worst_t = fmax(worst_t, fabs(r.force[q] + r.fn * c.n[q]));
    }
    CHECK(worst_t == 0.0, "frictionless: tangential force %g N", worst_t);
    CHECK(nf->friction == 0.0, "frictionless: law friction %g", nf->friction);
    floe_contact_law_destroy(nf);
    CHECK(floe_hooke_part_create(-1, 0, 0) == NULL, "hooke with kn < 0 refused");
    CHECK(floe_composed_law_create(NULL, floe_coulomb_part_create(0.3, 1, 0)) == NULL, "no normal part refused");

    printf("3. worlds: the same critical step and trajectory\n");
    floe_world *wa = collide(floe_hertz_mindlin_law_create(&glass, &glass, 0.6, 0.5), &glass, 3000);
    floe_world *wb = collide(floe_composed_law_create(floe_hertz_part_create(&glass, &glass, 0.6),
                                                      floe_mindlin_part_create(&glass, &glass, 0.5)),
                             &glass, 3000);
    CHECK(floe_world_dt(wa) == floe_world_dt(wb), "dt %.17g vs %.17g", floe_world_dt(wa), floe_world_dt(wb));
    floe_particles_view va, vb;
    floe_world_particles(wa, &va);
    floe_world_particles(wb, &vb);
    double dx = 0, dw = 0, wmax = 0;
    for (int i = 0; i < va.n; i++)
        for (int q = 0; q < 3; q++) {
            dx = fmax(dx, fabs(va.x[3 * i + q] - vb.x[3 * i + q]));
            dw = fmax(dw, fabs(va.w[3 * i + q] - vb.w[3 * i + q]));
            wmax = fmax(wmax, fabs(va.w[3 * i + q]));
        }
    printf("  after 3000 steps: |dx| %.2e m, |dw| %.2e rad/s (|w| up to %.3g), dt %.4g s\n", dx, dw, wmax,
           floe_world_dt(wa));
    CHECK(dx <= 1e-12 * 0.001, "positions differ by %g m", dx);
    CHECK(dw <= 1e-12 * fmax(wmax, 1), "spins differ by %g rad/s", dw);
    CHECK(floe_v3_norm(va.v + 3) > 0, "the spheres collided");
    floe_world_destroy(wa);
    floe_world_destroy(wb);

    printf("4. scenes\n");
    const char *scene =
        "dimension: 3\ntime: {duration: 0.001}\ngravity: [0, 0, 0]\n"
        "materials:\n  - {name: glass, density: 2500, young: 1e7, poisson: 0.3}\n"
        "laws:\n  - materials: [glass, glass]\n    normal: {model: hooke, stiffness: 2e4, damping: 0.01}\n"
        "    tangential: {model: coulomb, friction: 0.3, stiffness: 1e4}\n"
        "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, position: [0, 0, 0]}\n";
    floe_world *w = NULL;
    char err[512] = "";
    int rc = floe_scene_load_string(scene, "composed.yaml", NULL, &w, NULL, err, sizeof err);
    CHECK(rc == 0 && w, "composed scene loads: %s", err);
    floe_world_destroy(w);
    char bad[2048];
    snprintf(bad, sizeof bad, "%s", scene);
    char *at = strstr(bad, "model: coulomb");
    memcpy(at, "model: colomb ", 14);
    rc = floe_scene_load_string(bad, "composed.yaml", NULL, &w, NULL, err, sizeof err);
    CHECK(rc != 0 && strstr(err, "composed.yaml:9:") && strstr(err, "did you mean 'coulomb'"),
          "misspelled part: %s", err);
    printf("  error: %s\n", err);
    return check_summary("test_composed_law");
}
