/* test_dynamics.c - rigid-body dynamics through the world: torque-free asymmetric body,
 * restitution of head-on collisions, energy conservation and balance, incline stick/slip,
 * sliding-to-rolling, Hertz static overlap, 2D versus 3D, instability detection, RK2
 * state convergence. Every check states its tolerance. */
#include "floe.h"
#include "floe.h"
#include "world_read.h"
#include "check.h"
#include <string.h>

static floe_material glass(void) {
    floe_material m;
    memset(&m, 0, sizeof m);
    strcpy(m.name, "glass");
    m.density = 2500; m.young = 1e7; m.poisson = 0.3;
    return m;
}

static floe_world *mkworld(int dim, double dt, const double g[3]) {
    floe_world_def d = floe_default_world_def();
    d.dim = dim; d.dt = dt;
    if (g) memcpy(d.gravity, g, sizeof d.gravity);
    return floe_world_create(&d, NULL, 0);
}

static int add_sphere(floe_world *w, int geom, double x, double y, double z, double vx, double vy, double vz) {
    floe_particle_def p = floe_default_particle_def();
    p.geometry = geom; p.material = 0;
    floe_v3_set(p.x, x, y, z); floe_v3_set(p.v, vx, vy, vz);
    return floe_world_add_particle(w, &p);
}

/* ---- torque-free asymmetric body ---- */
static void test_free_rotation(void) {
    floe_world *w = mkworld(3, 1e-4, NULL);
    floe_material m = glass();
    floe_world_add_material(w, &m);
    int g = floe_world_add_geometry(w, floe_box_create(0.1, 0.2, 0.35));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = g;
    floe_v3_set(p.w, 3.0, 0.4, 1.5);   /* near the unstable middle axis: a hard case */
    int i = floe_world_add_particle(w, &p);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    double L0[3], E0 = floe_world_energy(w).kinetic_rot;
    memcpy(L0, pview(w).L + 3 * i, sizeof L0);
    double wmin = 1e9, wmax = -1e9;
    for (int s = 0; s < 20000; s++) {
        floe_world_step(w);
        double wx = pview(w).w[3 * i];
        if (wx < wmin) wmin = wx;
        if (wx > wmax) wmax = wx;
    }
    double L[3], om[3];
    /* angular momentum recomputed from omega and the rotated inertia (not the stored L) */
    double ob[3];
    memcpy(om, pview(w).w + 3 * i, sizeof om);
    floe_q_rotate_inv(ob, pview(w).q + 4 * i, om);
    for (int k = 0; k < 3; k++) ob[k] *= pview(w).inertia[3 * i + k];
    floe_q_rotate(L, pview(w).q + 4 * i, ob);
    double dL[3];
    floe_v3_sub(dL, L, L0);
    double E = floe_world_energy(w).kinetic_rot;
    printf("  free rotation: omega_x ranged %.3f..%.3f over 2 s (tumbling)\n", wmin, wmax);
    CHECK(wmax - wmin > 0.1, "the body should tumble (omega_x varies), got range %g", wmax - wmin);
    CHECK_NEAR(floe_v3_norm(dL) / floe_v3_norm(L0) + 1.0, 1.0, 1e-10, "|L - L0|/|L0| (tol 1e-10), 20k steps");
    CHECK_NEAR(E, E0, 1e-5, "rotational KE drift (tol 1e-5), 20k steps");
    floe_world_destroy(w);
}

/* ---- many torque-free bodies: the step's orientation update is the midpoint rule of
 * ParticLS eq 23 (omega at the midpoint orientation by two fixed-point passes, q advanced by
 * exp(h omega / 2) to fourth order in the turn, renormalised; a large turn, |h omega|^2 >=
 * 1e-4, exactly), for each body alike whether the drift takes it with others in lanes or
 * alone: 21 boxes (a run of 16 and 5 more; two spin fast enough for the large-turn path),
 * their orientations and angular velocities after 300 velocity Verlet steps against this
 * test's own scalar loop ---- */
static void ref_omega(const double q[4], const double inv[3], const double L[3], double om[3]) {
    double b[3];
    floe_q_rotate_inv(b, q, L);
    for (int k = 0; k < 3; k++) b[k] *= inv[k];
    floe_q_rotate(om, q, b);
}
static void ref_advance(double out[4], const double q[4], const double om[3], double h) {
    double th[3] = {h * om[0], h * om[1], h * om[2]}, a2 = floe_v3_dot(th, th);
    if (!(a2 < 1e-4)) { /* a large turn: the exact rotation */
        double dq[4];
        floe_q_from_rotvec(dq, th);
        floe_q_mul(out, dq, q);
        floe_q_normalize(out);
        return;
    }
    /* cos(a/2) and sin(a/2)/a to a^4, and one Newton step back to |q| = 1 (step.c's forms) */
    double c = 1.0 - a2 * (0.125 - a2 * (1.0 / 384.0)), s = 0.5 - a2 * (1.0 / 48.0 - a2 * (1.0 / 3840.0));
    double dq[4] = {c, s * th[0], s * th[1], s * th[2]};
    floe_q_mul(out, dq, q);
    double sc = 1.5 - 0.5 * (out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3]);
    for (int k = 0; k < 4; k++) out[k] *= sc;
}
static void test_many_rotations(void) {
    const double dt = 2e-4;
    floe_world *w = mkworld(3, dt, NULL);
    floe_material m = glass();
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(1e3, 0, 0, 0, 0)); /* the boxes never meet */
    enum { NB = 21 };
    unsigned long long rng = 12345;
    for (int b = 0; b < NB; b++) {
        double e[3];
        for (int k = 0; k < 3; k++) {
            rng = rng * 6364136223846793005ull + 1442695040888963407ull;
            e[k] = 0.05 + 0.3 * (double)(rng >> 11) / 9007199254740992.0;
        }
        int g = floe_world_add_geometry(w, floe_box_create(e[0], e[1], e[2]));
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        floe_v3_set(p.x, 2.0 * b, 0, 0);
        floe_v3_set(p.w, 3.0 - 0.1 * b, 0.4 + 0.05 * b, 1.5 - 0.07 * b);
        if (b == 7 || b == 18) floe_v3_scale(p.w, 500.0); /* |dt omega| about 0.3: the large-turn path */
        floe_q_from_rotvec(p.q, (double[3]){0.1 * b, -0.05 * b, 0.2});
        floe_world_add_particle(w, &p);
    }
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    double q[NB][4], L[NB][3], inv[NB][3];
    for (int b = 0; b < NB; b++) {
        memcpy(q[b], pview(w).q + 4 * b, sizeof q[b]);
        memcpy(L[b], pview(w).L + 3 * b, sizeof L[b]);
        for (int k = 0; k < 3; k++) inv[b][k] = 1.0 / pview(w).inertia[3 * b + k];
    }
    const int steps = 300;
    for (int s = 0; s < steps; s++) floe_world_step(w);
    double worst = 0, worst0 = 0, worstw = 0;
    for (int b = 0; b < NB; b++) {
        double qq[4], q1[4];
        memcpy(qq, q[b], sizeof qq);
        memcpy(q1, q[b], sizeof q1);
        for (int s = 0; s < steps; s++) {
            double om[3], qm[4], qn[4];
            ref_omega(qq, inv[b], L[b], om);
            ref_advance(qm, qq, om, 0.5 * dt);
            for (int it = 0; it < 2; it++) {
                ref_omega(qm, inv[b], L[b], om);
                ref_advance(qm, qq, om, 0.5 * dt);
            }
            ref_omega(qm, inv[b], L[b], om);
            ref_advance(qn, qq, om, dt);
            memcpy(qq, qn, sizeof qq);
            /* the same with one fixed-point pass: how far a scheme a pass short lands */
            ref_omega(q1, inv[b], L[b], om);
            ref_advance(qm, q1, om, 0.5 * dt);
            ref_omega(qm, inv[b], L[b], om);
            ref_advance(qm, q1, om, 0.5 * dt);
            ref_omega(qm, inv[b], L[b], om);
            ref_advance(qn, q1, om, dt);
            memcpy(q1, qn, sizeof q1);
        }
        const double *qw = pview(w).q + 4 * b;
        double sg = qq[0] * qw[0] + qq[1] * qw[1] + qq[2] * qw[2] + qq[3] * qw[3] < 0 ? -1 : 1;
        for (int k = 0; k < 4; k++) {
            worst = fmax(worst, fabs(sg * qw[k] - qq[k]));
            worst0 = fmax(worst0, fabs(q1[k] - qq[k]));
        }
        double om[3]; /* omega at the new orientation, relative to its size */
        ref_omega(qq, inv[b], L[b], om);
        for (int k = 0; k < 3; k++) worstw = fmax(worstw, fabs(pview(w).w[3 * b + k] - om[k]) / floe_v3_norm(om));
    }
    printf("  %d torque-free boxes, %d steps: orientation within %.2e of the midpoint rule (with one fixed-point pass "
           "instead of two: %.2e); omega within %.2e\n", NB, steps, worst, worst0, worstw);
    CHECK(worst0 > 1e-13, "the check can tell one pass from two (%.2e)", worst0);
    CHECK(worst < 2e-14, "every body follows the midpoint rule of eq 23 (%.2e, tol 2e-14)", worst);
    CHECK(worstw < 1e-13, "and its angular velocity is that of its orientation (%.2e relative, tol 1e-13)", worstw);
    floe_world_destroy(w);
}

/* ---- head-on collision restitution through the world ---- */
static double collide_safety(floe_contact_law *law, double v0, double safety) {
    floe_world_def d = floe_default_world_def();
    d.dt_safety = safety;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = glass();
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, law);
    int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    add_sphere(w, g, 0, 0, 0, v0, 0, 0);
    add_sphere(w, g, 0.00201, 0, 0, -v0, 0, 0);
    if (floe_world_prepare(w)) { printf("%s\n", floe_world_last_error(w)); floe_world_destroy(w); return -1; }
    for (int s = 0; s < 200000; s++) {
        floe_world_step(w);
        if (pview(w).v[0] < 0 && floe_world_contact_count(w) == 0 && pview(w).x[3] - pview(w).x[0] > 0.00201) break;
    }
    double e = (pview(w).v[3] - pview(w).v[0]) / (2 * v0);
    floe_world_destroy(w);
    return e;
}
/* dt = 0.05 x critical: the restitution test at a fine step */
static double collide(floe_contact_law *law, double v0) { return collide_safety(law, v0, 0.05); }

static void test_restitution(void) {
    floe_material m = glass();
    double es[3] = {0.3, 0.5, 0.9};
    for (int k = 0; k < 3; k++) {
        for (double v0 = 0.01; v0 <= 1.0; v0 *= 10) {
            double e = collide(floe_hertz_mindlin_law_create(&m, &m, es[k], 0.0), v0);
            char what[96];
            snprintf(what, sizeof what, "Hertz-Mindlin restitution e=%.1f v=%.2f m/s (tol 1%%)", es[k], v0);
            CHECK_NEAR(e, es[k], 0.01, what);
        }
    }
    /* the default safety 0.2 is within 1 % too */
    for (int k = 0; k < 3; k++) {
        double e = collide_safety(floe_hertz_mindlin_law_create(&m, &m, es[k], 0.0), 0.1, 0.2);
        char what[96];
        snprintf(what, sizeof what, "Hertz-Mindlin e=%.1f at the default dt (0.2 x critical, tol 1%%)", es[k]);
        CHECK_NEAR(e, es[k], 0.01, what);
    }
    /* viscoelastic: expected from the analytic spring-dashpot formula */
    double mass = 2500 * 4.0 / 3.0 * M_PI * 1e-9, kn = 100, gn = 0.002;
    floe_linear_law *ll = (floe_linear_law *)floe_linear_law_create(kn, kn / 2, gn, 0, 0);
    ll->tension = 1;
    double e = collide(&ll->base, 0.05);
    CHECK_NEAR(e, floe_linear_restitution(kn, gn, mass / 2), 0.01, "viscoelastic restitution vs exp(-pi z/sqrt(1-z^2)) (tol 1%)");
}

/* ---- energy: elastic spheres in a box, velocity Verlet, 1e5 steps ---- */
static floe_world *box_of_spheres(int n_side, double e, double mu, const double grav[3], double dt) {
    floe_world *w = mkworld(3, dt, grav);
    floe_material m = glass();
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, e, mu));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    double Lb = n_side * 0.003 + 0.001;
    double pts[6][3] = {{0, 0, 0}, {Lb, 0, 0}, {0, 0, 0}, {0, Lb, 0}, {0, 0, 0}, {0, 0, Lb}};
    double nrm[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int k = 0; k < 6; k++) floe_world_add_wall(w, pts[k], nrm[k], 0, FLOE_FIXED);
    unsigned s = 12345;
    for (int a = 0; a < n_side; a++)
        for (int b = 0; b < n_side; b++)
            for (int c = 0; c < n_side; c++) {
                double v[3];
                for (int k = 0; k < 3; k++) { s = s * 1103515245u + 12345u; v[k] = ((s >> 8) / 16777216.0 - 0.5) * 0.4; }
                add_sphere(w, g, 0.002 + a * 0.003, 0.002 + b * 0.003, 0.002 + c * 0.003, v[0], v[1], v[2]);
            }
    return w;
}

static void test_energy(void) {
    floe_world *w = box_of_spheres(4, 1.0, 0.0, NULL, 2e-6);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    double E0 = floe_world_energy(w).initial, maxdev = 0;
    long contacts = 0;
    for (int s = 0; s < 100000; s++) {
        if (floe_world_step(w)) { CHECK(0, "step failed: %s", floe_world_last_error(w)); break; }
        floe_energy e = floe_world_energy(w);
        double E = e.kinetic_trans + e.kinetic_rot + e.elastic;
        if (fabs(E - E0) > maxdev) maxdev = fabs(E - E0);
        contacts += floe_world_contact_count(w);
    }
    printf("  elastic box: %ld contact-steps in 1e5 steps, dt = %g\n", contacts, floe_world_dt(w));
    CHECK(contacts > 1000, "the elastic test must actually collide (%ld contact-steps)", contacts);
    CHECK_NEAR(E0 + maxdev, E0, 1e-3, "max |E - E0|/E0 over 1e5 Verlet steps, elastic Hertz (tol 1e-3)");
    floe_world_destroy(w);

    /* friction + damping + gravity: the balance initial + work = now + dissipated closes */
    double g[3] = {0, 0, -9.81};
    w = box_of_spheres(4, 0.5, 0.5, g, 2e-6);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    for (int s = 0; s < 50000; s++)
        if (floe_world_step(w)) { CHECK(0, "step failed: %s", floe_world_last_error(w)); break; }
    floe_energy e = floe_world_energy(w);
    printf("  dissipative box: KE %.3e elastic %.3e work_g %.3e dissipated %.3e\n", e.kinetic_trans + e.kinetic_rot,
           e.elastic, e.work_body, e.dissipated);
    CHECK(e.dissipated > 0.3 * (e.initial + e.work_body), "most energy should be dissipated by now");
    CHECK_NEAR(1.0 + floe_world_energy_balance_error(w), 1.0, 5e-3, "energy balance error with friction (tol 0.5%)");
    floe_world_destroy(w);
}

/* ---- block on an incline (gravity tilted by theta), Coulomb mu = 0.5 ---- */
static double incline(double theta_deg, double *accel) {
    double th = theta_deg * M_PI / 180, g = 9.81;
    double grav[3] = {g * sin(th), 0, -g * cos(th)};
    floe_world *w = mkworld(3, 1e-5, grav);
    floe_material m = glass();
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(1e5, 5e4, 20, 10, 0.5));
    int gb = floe_world_add_geometry(w, floe_box_create(0.04, 0.04, 0.01));
    double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
    floe_particle_def p = floe_default_particle_def();
    p.geometry = gb;
    floe_v3_set(p.x, 0, 0, 0.005);
    int i = floe_world_add_particle(w, &p);
    floe_world_prepare(w);
    /* settle 0.2 s, then measure over 0.3 s */
    for (int s = 0; s < 20000; s++) floe_world_step(w);
    double x0 = pview(w).x[3 * i], v0 = pview(w).v[3 * i];
    for (int s = 0; s < 30000; s++) floe_world_step(w);
    double T = 0.3, x1 = pview(w).x[3 * i];
    *accel = 2 * (x1 - x0 - v0 * T) / (T * T);
    floe_world_destroy(w);
    return x1 - x0;
}

static void test_incline(void) {
    double a, g = 9.81, mu = 0.5;
    double d = incline(20.0, &a); /* tan 20 = 0.364 < 0.5: sticks */
    printf("  incline 20 deg: moved %.3e m in 0.3 s\n", d);
    CHECK(fabs(d) < 1e-5, "block should stick at tan(theta) = 0.364 < mu = 0.5 (moved %g m)", d);
    d = incline(35.0, &a); /* tan 35 = 0.700 > 0.5: slides with a = g (sin - mu cos) */
    double th = 35.0 * M_PI / 180;
    CHECK_NEAR(a, g * (sin(th) - mu * cos(th)), 0.02, "sliding acceleration at 35 deg vs g(sin - mu cos) (tol 2%)");
}

/* ---- sliding sphere reaches rolling at 5/7 v0 ---- */
static void test_rolling(void) {
    double grav[3] = {0, 0, -9.81};
    floe_world *w = mkworld(3, 0, grav);
    floe_material m = glass();
    m.young = 1e8;
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.3));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.005));
    double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
    /* resting overlap first, then launch */
    int i = add_sphere(w, g, 0, 0, 0.005, 0, 0, 0);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    for (int s = 0; s < 20000; s++) floe_world_step(w);
    set_vel(w, i, 0, 1.0);
    for (int s = 0; s < 400000; s++) floe_world_step(w);
    double v = pview(w).v[3 * i], om = pview(w).w[3 * i + 1];
    printf("  rolling: v = %.5f m/s, omega*R = %.5f m/s after %.2f s\n", v, om * 0.005, floe_world_time(w));
    CHECK_NEAR(v, 5.0 / 7.0, 0.01, "final velocity of a launched sliding sphere vs 5/7 v0 (tol 1%)");
    CHECK_NEAR(om * 0.005, v, 0.01, "rolling without slip: omega R = v (tol 1%)");
    floe_world_destroy(w);
}

/* ---- Hertz static overlap of a sphere resting on a plane ---- */
static void test_hertz_rest(void) {
    double grav[3] = {0, 0, -9.81};
    floe_world *w = mkworld(3, 0, grav);
    floe_material m = glass();
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.3, 0.5));
    double R = 0.002;
    int g = floe_world_add_geometry(w, floe_sphere_create(R));
    double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
    int i = add_sphere(w, g, 0, 0, R, 0, 0, 0);
    floe_world_prepare(w);
    for (int s = 0; s < 100000; s++) floe_world_step(w);
    double mass = pview(w).mass[i];
    double Es = 1.0 / (2 * (1 - 0.09) / 1e7);
    double d = pow(3 * mass * 9.81 / (4 * Es * sqrt(R)), 2.0 / 3.0);
    CHECK_NEAR(R - pview(w).x[3 * i + 2], d, 0.01, "sphere on plane: overlap vs (3mg/(4E* sqrt R))^(2/3) (tol 1%)");
    floe_world_destroy(w);
}

/* ---- 2D scene equals the 3D scene restricted to the plane ---- */
static void test_2d_vs_3d(void) {
    double pos[2][5][3];
    for (int dim = 2; dim <= 3; dim++) {
        double grav[3] = {0, -9.81, 0};
        floe_world *w = mkworld(dim, 2e-6, grav);
        floe_material m = glass();
        floe_world_add_material(w, &m);
        floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.4));
        int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
        double o[3] = {0, 0, 0}, n[3] = {0, 1, 0}, o2[3] = {0.01, 0, 0}, n2[3] = {-1, 0, 0};
        floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
        floe_world_add_wall(w, o2, n2, 0, FLOE_FIXED);
        for (int k = 0; k < 5; k++) add_sphere(w, g, 0.002 + 0.0015 * k, 0.002 + 0.0023 * k, 0, 0.3 - 0.1 * k, 0.05 * k, 0);
        floe_world_prepare(w);
        for (int s = 0; s < 20000; s++) floe_world_step(w);
        for (int k = 0; k < 5; k++) memcpy(pos[dim - 2][k], pview(w).x + 3 * (k + 2), 3 * sizeof(double));
        floe_world_destroy(w);
    }
    double maxd = 0;
    for (int k = 0; k < 5; k++)
        for (int a = 0; a < 3; a++) maxd = fmax(maxd, fabs(pos[0][k][a] - pos[1][k][a]));
    printf("  2D vs 3D: max position difference %.3e m after 20k steps\n", maxd);
    CHECK(maxd < 1e-12, "2D and planar 3D trajectories must agree to 1e-12 m (got %g)", maxd);
}

/* ---- instability: dt above critical is refused; forced, the run stops with an id ---- */
static void test_unstable(void) {
    floe_world *w = box_of_spheres(2, 0.5, 0.5, NULL, 1e-3);
    int rc = floe_world_prepare(w);
    CHECK(rc == FLOE_EUNSTABLE && strstr(floe_world_last_error(w), "critical"),
          "dt far above critical must be refused (rc %d: %s)", rc, floe_world_last_error(w));
    floe_world_destroy(w);
    w = box_of_spheres(2, 0.5, 0.5, NULL, 1e-3);
    floe_world_set_dt(w, 1e-3, 1);
    rc = floe_world_run(w, 1.0, NULL, NULL);
    CHECK(rc == FLOE_EUNSTABLE && strstr(floe_world_last_error(w), "particle"),
          "a forced unstable run stops naming the particle (rc %d: %s)", rc, floe_world_last_error(w));
    printf("  message: %s\n", floe_world_last_error(w));
    floe_world_destroy(w);
}

/* ---- RK2 state object: second order ---- */
static double rhs_fn(double t, double y, void *u) { (void)u; return cos(t) * y; }
static double rk2_error(double dt) {
    floe_world *w = mkworld(3, dt, NULL);
    floe_state *s = floe_scalar_state_create(1.0, rhs_fn, NULL);
    floe_world_add_state(w, s);
    floe_world_prepare(w);
    floe_world_run(w, 1.0, NULL, NULL);
    double err = fabs(floe_scalar_state_value(s) - exp(sin(floe_world_time(w))));
    floe_world_destroy(w);
    return err;
}
static void test_rk2(void) {
    double e1 = rk2_error(0.01), e2 = rk2_error(0.005), e3 = rk2_error(0.0025);
    printf("  RK2 errors: %.3e %.3e %.3e; ratios %.3f %.3f\n", e1, e2, e3, e1 / e2, e2 / e3);
    CHECK_NEAR(e1 / e2, 4.0, 0.1, "RK2 error ratio when halving dt (tol 10%)");
    CHECK_NEAR(e2 / e3, 4.0, 0.1, "RK2 error ratio when halving dt again (tol 10%)");
}

/* ---- user body-force callback: a spring to the origin (harmonic oscillator) ---- */
static void spring_force(const floe_world *w, int i, double t, double f[3], double torque[3], void *user) {
    (void)t; (void)torque;
    floe_particle_state st;
    floe_world_get_particle(w, i, &st);
    double k = *(double *)user;
    for (int a = 0; a < 3; a++) f[a] = -k * st.x[a];
}
static void test_body_force(void) {
    double k = 2.0;
    floe_world *w = mkworld(3, 1e-4, NULL);
    floe_material m = glass();
    floe_world_add_material(w, &m);
    int g = floe_world_add_geometry(w, floe_sphere_create(0.01));
    int i = add_sphere(w, g, 0.001, 0, 0, 0, 0, 0);
    floe_world_set_body_force(w, spring_force, &k);
    floe_world_prepare(w);
    double mass = pview(w).mass[i], T = 2 * M_PI * sqrt(mass / k), om = sqrt(k / mass);
    floe_particle_state st;
    /* a quarter period: the spring's energy has become kinetic, booked as body-force work */
    floe_world_run(w, 0.25 * T, NULL, NULL);
    floe_world_get_particle(w, i, &st);
    floe_energy e = floe_world_energy(w);
    double pe = 0.5 * k * (0.001 * 0.001 - st.x[0] * st.x[0]);
    CHECK_NEAR(e.work_body, pe, 1e-3, "work of the callback force = -(change of spring energy) (tol 0.1%)");
    CHECK_NEAR(e.kinetic_trans, pe, 1e-3, "kinetic energy = work of the callback force (tol 0.1%)");
    floe_world_run(w, T, NULL, NULL);
    floe_world_get_particle(w, i, &st);
    CHECK_NEAR(st.x[0], 0.001 * cos(om * floe_world_time(w)), 1e-5,
               "body-force callback: spring oscillator after one period (tol 1e-5)");
    floe_world_destroy(w);
}

/* ---- critical time step: a disc caged by six fixed discs with ks = kn, whose fastest
 * mode is the rotation (omega^2 = 6 ks R^2 / I = 15 ks/m); 0.9 x the estimate must run ---- */
static floe_world *caged(double dt) {
    floe_world_def d = floe_default_world_def();
    d.dim = 2; d.dt = dt;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = glass();
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_linear_law_create(1e4, 1e4, 0, 0, 1e6));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.1));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = g; p.w[2] = 0.01;
    floe_world_add_particle(w, &p);
    for (int k = 0; k < 6; k++) {
        floe_particle_def q = floe_default_particle_def();
        q.geometry = g; q.motion = FLOE_FIXED;
        floe_v3_set(q.x, 0.199 * cos(k * M_PI / 3), 0.199 * sin(k * M_PI / 3), 0);
        floe_world_add_particle(w, &q);
    }
    return w;
}
static void test_critical_rotation(void) {
    floe_world *w = caged(0);
    floe_world_prepare(w);
    double dc = floe_world_critical_dt(w);
    floe_world_destroy(w);
    int rc = 0;
    w = caged(0.9 * dc);
    for (int s = 0; s < 2000 && !rc; s++) rc = floe_world_step(w);
    double om = pview(w).w[2];
    CHECK(rc == FLOE_OK && fabs(om) < 0.1, "caged disc at 0.9 x critical must stay stable (rc %d, omega %g: %s)", rc, om,
          floe_world_last_error(w));
    floe_world_destroy(w);
    printf("  caged disc: critical estimate %.4g s, stable at 0.9x\n", dc);
}

int main(void) {
    printf("critical dt with rotation\n"); test_critical_rotation();
    printf("body force\n"); test_body_force();
    printf("free rotation\n"); test_free_rotation();
    printf("many rotations\n"); test_many_rotations();
    printf("restitution\n"); test_restitution();
    printf("energy\n"); test_energy();
    printf("incline\n"); test_incline();
    printf("rolling\n"); test_rolling();
    printf("hertz at rest\n"); test_hertz_rest();
    printf("2d vs 3d\n"); test_2d_vs_3d();
    printf("unstable\n"); test_unstable();
    printf("rk2\n"); test_rk2();
    return check_summary("test_dynamics");
}
