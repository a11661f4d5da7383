/* test_newmark.c - Newmark-beta for bonded systems (core/integrators/floe_newmark.h, 004 §3-4):
 * conformance on a harmonic oscillator for the explicit (beta 0) and implicit average
 * acceleration (beta 1/4) schemes (second order, energy, stability at 0.9x and detection
 * at 1.1x the critical step omega dt = 2), the static deflection of a cantilever recovered
 * by the implicit solver (and from a world with beam bonds), the energy balance with
 * damping, breakage with and without the line search of eqs 29-30, bad input. */
#include "check.h"
#include "floe_newmark.h"
#include "floe.h"
#include "world_read.h"

#include <stdlib.h>
#include <string.h>

/* ---- harmonic oscillator: a node of mass m on an axial bond (k = EA/l) to a support ---- */

static const double OSC_K = 400.0, OSC_M = 1.0, OSC_U0 = 1e-3;

static floe_newmark *oscillator(double beta, double dt, int allow) {
    floe_newmark_def d = floe_newmark_default_def();
    d.beta = beta;
    d.dt = dt;
    d.allow_unstable_dt = allow;
    char err[256];
    floe_newmark *s = floe_newmark_create(&d, err, sizeof err);
    if (!s) { printf("  create: %s\n", err); return NULL; }
    double x0[3] = {0, 0, 0}, x1[3] = {0.5, 0, 0};
    floe_newmark_add_node(s, x0, 1.0, 1.0);
    floe_newmark_add_node(s, x1, OSC_M, 1.0);
    floe_beam_section sec = {0};
    sec.E = OSC_K * 0.5 / 1e-2;
    sec.A = 1e-2;
    sec.I = 1e-20; /* no bending: the shear and rotation components are supported anyway */
    sec.W = 1;
    floe_newmark_add_bond(s, 0, 1, &sec, INFINITY, INFINITY);
    floe_newmark_fix(s, 0, FLOE_NM_ALL);
    floe_newmark_fix(s, 1, FLOE_NM_ALL & ~FLOE_NM_UX);
    double u[3] = {OSC_U0, 0, 0};
    floe_newmark_set_initial(s, 1, u, NULL, NULL, NULL);
    return s;
}

/* |u(t_end) - u0 cos(omega t_end)| / u0 */
static double osc_error(double beta, double dt, double t_end) {
    floe_newmark *s = oscillator(beta, dt, 0);
    if (!s) return NAN;
    int rc = floe_newmark_run(s, t_end);
    CHECK(rc == FLOE_OK, "oscillator run: %s", floe_newmark_last_error(s));
    double u[3];
    floe_newmark_get(s, 1, u, NULL, NULL, NULL);
    double om = sqrt(OSC_K / OSC_M), e = fabs(u[0] - OSC_U0 * cos(om * floe_newmark_time(s))) / OSC_U0;
    floe_newmark_destroy(s);
    return e;
}

static void test_oscillator(void) {
    const double om = sqrt(OSC_K / OSC_M), T = 2 * M_PI / om;
    const char *names[2] = {"explicit (beta 0)", "implicit (beta 1/4)"};
    for (int m = 0; m < 2; m++) {
        double beta = m ? 0.25 : 0.0, prev = 0;
        /* at t = 3.25 T, where cos crosses zero, the error is linear in the phase error */
        printf("  %s: error at t = 3.25 T against u0 cos(omega t)\n", names[m]);
        for (int k = 0; k < 4; k++) {
            double dt = T / (20 << k);
            double e = osc_error(beta, dt, 3.25 * T);
            printf("    dt = T/%-4d error %.4e", 20 << k, e);
            if (k) {
                printf("  ratio %.3f", prev / e);
                CHECK(fabs(prev / e - 4) < 0.2, "%s: second order (ratio %.3f when dt halves)", names[m], prev / e);
            }
            printf("\n");
            prev = e;
        }
    }
    /* implicit average acceleration: the energy of a linear undamped system is conserved
     * (to round-off), at any step */
    for (int k = 0; k < 2; k++) {
        double omdt = k ? 10.0 : 1.0;
        floe_newmark *s = oscillator(0.25, omdt / om, 0);
        floe_newmark_stats st;
        floe_newmark_prepare(s);
        floe_newmark_get_stats(s, &st);
        double e0 = st.energy_kinetic + st.energy_elastic, dev = 0;
        for (int n = 0; n < 1000; n++) {
            CHECK(floe_newmark_step(s) == FLOE_OK, "implicit step");
            floe_newmark_get_stats(s, &st);
            dev = fmax(dev, fabs(st.energy_kinetic + st.energy_elastic - e0) / e0);
        }
        /* the energy from the state itself: m v^2 / 2 + k u^2 / 2 */
        double u[3], v[3];
        floe_newmark_get(s, 1, u, NULL, v, NULL);
        double es = 0.5 * OSC_M * v[0] * v[0] + 0.5 * OSC_K * u[0] * u[0];
        printf("  implicit, omega dt = %g: energy over 1000 steps, largest relative change %.2e (from the state: %.2e)\n",
               omdt, dev, fabs(es - e0) / e0);
        CHECK(dev < 1e-12 && fabs(es - e0) < 1e-12 * e0, "average acceleration conserves energy to round-off");
        floe_newmark_destroy(s);
    }
    /* explicit: the critical step is omega dt = 2; 0.9x runs, 1.1x is detected */
    floe_newmark *s = oscillator(0.0, 1e-3, 0);
    double dtc = floe_newmark_critical_dt(s), dtd = floe_newmark_critical_dt_diag(s);
    printf("  explicit critical step %.9g s (2/omega = %.9g s; eq 28 %.9g s)\n", dtc, 2 / om, dtd);
    CHECK(fabs(dtc - 2 / om) < 1e-12 * dtc, "critical step = 2/omega for the oscillator");
    floe_newmark_destroy(s);
    s = oscillator(0.0, 0.9 * 2 / om, 0);
    int rc = 0;
    double umax = 0, u[3];
    for (int n = 0; n < 20000 && !rc; n++) {
        rc = floe_newmark_step(s);
        floe_newmark_get(s, 1, u, NULL, NULL, NULL);
        umax = fmax(umax, fabs(u[0]));
    }
    printf("  explicit at 0.9 x critical: 20000 steps, rc %d, max |u| / u0 = %.3f\n", rc, umax / OSC_U0);
    CHECK(rc == FLOE_OK && umax < 3 * OSC_U0, "explicit stable at 0.9x the critical step");
    floe_newmark_destroy(s);
    s = oscillator(0.0, 1.1 * 2 / om, 0);
    rc = floe_newmark_prepare(s);
    CHECK(rc == FLOE_EUNSTABLE && strstr(floe_newmark_last_error(s), "critical"), "1.1x refused at prepare: %s",
          floe_newmark_last_error(s));
    floe_newmark_destroy(s);
    s = oscillator(0.0, 1.1 * 2 / om, 1);
    rc = 0;
    int n = 0;
    for (; n < 1000 && !rc; n++) rc = floe_newmark_step(s);
    floe_newmark_get(s, 1, u, NULL, NULL, NULL);
    printf("  explicit at 1.1 x critical (allowed): stopped after %d steps: %s\n", n, floe_newmark_last_error(s));
    CHECK(rc == FLOE_EUNSTABLE && n < 50 && isfinite(u[0]), "1.1x detected as unstable within 50 steps, no NaN");
    floe_newmark_destroy(s);
}

/* ---- static cantilever by the implicit solver ---- */

static void test_static_cantilever(void) {
    const int n = 11;
    const double L = 1, M = 1, a = 1, r = 0.01, E = 1e10;
    floe_beam_section sec = {0};
    sec.E = E;
    sec.G = E / 2.5;
    sec.A = M_PI * r * r;
    sec.I = 0.25 * M_PI * r * r * r * r;
    sec.J = 2 * sec.I;
    sec.W = sec.I / r;
    const double l = L / (n - 1), m = M / (n - 1), om1 = 3.516 * sqrt(E * sec.I / (M / L * L * L * L));
    floe_newmark_def d = floe_newmark_default_def();
    d.dt = 2 * M_PI / om1 / 20; /* 20 steps per period of the first mode */
    d.mass_damping = 2 * om1;   /* critical for the first mode */
    floe_newmark *s = floe_newmark_create(&d, NULL, 0);
    for (int k = 0; k < n; k++) {
        double x[3] = {k * l, 0, 0}, mk = k == 0 || k == n - 1 ? 0.5 * m : m;
        floe_newmark_add_node(s, x, mk, 0.4 * mk * 0.25 * l * l);
        double f[3] = {0, -mk * a, 0};
        floe_newmark_set_load(s, k, f, NULL);
        if (k) floe_newmark_add_bond(s, k - 1, k, &sec, INFINITY, INFINITY);
    }
    floe_newmark_fix(s, 0, FLOE_NM_ALL);
    /* 32 periods: average acceleration does not damp the high modes the sudden load
     * excites (mass damping reaches them weakly), so the last 1e-6 take that long */
    const double t_end = 32 * 2 * M_PI / om1;
    int rc = floe_newmark_run(s, t_end);
    CHECK(rc == FLOE_OK, "implicit cantilever: %s", floe_newmark_last_error(s));
    double u[3];
    floe_newmark_get(s, n - 1, u, NULL, NULL, NULL);
    double d_ref = M * a * L * L * L / (8 * E * sec.I), d_fe = d_ref * (1 + l * l / (3 * L * L));
    floe_newmark_stats st;
    floe_newmark_get_stats(s, &st);
    printf("  implicit static cantilever (11 points): %ld steps, %ld factorizations, tip %.8e m; eq 38 %.8e m "
           "(%.3f %%), lumped-load exact %.8e m\n", st.steps, st.factorizations, -u[1], d_ref,
           100 * (-u[1] - d_ref) / d_ref, d_fe);
    CHECK(fabs(-u[1] - d_ref) < 0.02 * d_ref, "within 2 %% of M a L^3 / (8 E I)");
    CHECK(fabs(-u[1] - d_fe) < 1e-5 * d_fe, "the discrete static solution to 1e-5 (%.2e)", fabs(-u[1] - d_fe) / d_fe);
    CHECK(st.factorizations == 1, "factored once (%ld)", st.factorizations);
    /* energy balance with damping: kinetic + elastic + dissipated = initial + work */
    double bal = st.energy_kinetic + st.energy_elastic + st.dissipated - st.energy_initial - st.work_external;
    printf("  energy: work %.6e J, elastic %.6e J (= work/2 at rest), dissipated %.6e J, balance %.2e\n",
           st.work_external, st.energy_elastic, st.dissipated, bal / st.work_external);
    CHECK(fabs(bal) < 1e-10 * st.work_external, "average acceleration: the energy balance closes to round-off");
    CHECK(fabs(st.energy_elastic - 0.5 * st.work_external) < 1e-4 * st.work_external, "at rest, elastic = work / 2");
    floe_newmark_destroy(s);

    /* the same cantilever as a world with beam bonds, solved by the implicit solver */
    floe_world_def wd = floe_default_world_def();
    wd.dim = 2;
    wd.gravity[1] = -a;
    floe_world *w = floe_world_create(&wd, NULL, 0);
    floe_material mt = {"rod", 1000, E, 0.25};
    int mat = floe_world_add_material(w, &mt);
    floe_world_set_law(w, mat, mat, floe_linear_law_create(1e3, 0, 0, 0, 0));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.5 * l));
    for (int k = 0; k < n; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        p.material = mat;
        p.x[0] = k * l;
        p.mass = k == 0 || k == n - 1 ? 0.5 * m : m;
        p.motion = k == 0 ? FLOE_FIXED : FLOE_FREE;
        floe_world_add_particle(w, &p);
    }
    floe_beam_params bp = floe_default_beam_params();
    bp.young = E;
    bp.area = sec.A;
    bp.inertia = sec.I;
    floe_world_add_beam_bonds(w, 1.01, &bp);
    char err[256];
    s = floe_newmark_from_world(w, &d, err, sizeof err);
    CHECK(s != NULL, "from world: %s", err);
    if (s) {
        rc = floe_newmark_run(s, t_end);
        floe_newmark_get(s, n - 1, u, NULL, NULL, NULL);
        printf("  from a world (particles + beam bonds + gravity): tip %.8e m\n", -u[1]);
        CHECK(rc == FLOE_OK && fabs(-u[1] - d_fe) < 1e-5 * d_fe, "world -> implicit Newmark: same static deflection");
        floe_newmark_destroy(s);
    }
    floe_world_destroy(w);
}

/* ---- breakage and the line search ---- */

static double ramp(double t, void *user) { return t / *(double *)user; }

/* a bar under a force ramping to 2 x its breaking force over T: implicit with big steps,
 * with or without the line search; returns sigma / sigma_lim at the break */
static double bar_break(double beta, double dt, double eps, long *cuts, double *t_break) {
    floe_newmark_def d = floe_newmark_default_def();
    d.beta = beta;
    d.dt = dt;
    d.line_search_eps = eps;
    d.damping_ratio = beta == 0 ? 1.0 : 0.0;
    floe_newmark *s = floe_newmark_create(&d, NULL, 0);
    double x0[3] = {0, 0, 0}, x1[3] = {0.1, 0, 0};
    floe_newmark_add_node(s, x0, 1, 1);
    floe_newmark_add_node(s, x1, 1, 1);
    floe_beam_section sec = {0};
    sec.E = 1e9;
    sec.A = 1e-4;
    sec.I = 1e-9;
    sec.W = 1e-6;
    const double slim = 5e6, Fb = slim * sec.A;
    floe_newmark_add_bond(s, 0, 1, &sec, slim, INFINITY);
    floe_newmark_fix(s, 0, FLOE_NM_ALL);
    floe_newmark_fix(s, 1, FLOE_NM_ALL & ~FLOE_NM_UX);
    double T = 1.0, f[3] = {2 * Fb, 0, 0};
    floe_newmark_set_load(s, 1, f, NULL);
    floe_newmark_set_load_factor(s, ramp, &T);
    int rc = 0, broken = 0;
    while (!rc && !broken && floe_newmark_time(s) < T) {
        rc = floe_newmark_step(s);
        floe_newmark_bond_state(s, 0, &broken, t_break, NULL, NULL);
    }
    CHECK(rc == FLOE_OK && broken, "bar breaks: %s", floe_newmark_last_error(s));
    double sig;
    floe_newmark_bond_state(s, 0, NULL, NULL, &sig, NULL);
    floe_newmark_stats st;
    floe_newmark_get_stats(s, &st);
    *cuts = st.cuts;
    floe_newmark_destroy(s);
    return sig / slim;
}

static void test_breakage(void) {
    long cuts;
    double tb;
    /* the bar's period is 2 pi sqrt(m l / (E A)) = 6.3e-3 s; the load ramps over 1 s */
    double r_ls = bar_break(0.25, 0.07, 0.01, &cuts, &tb);
    printf("  implicit, dt 0.07 s, line search eps 0.01: breaks at sigma = %.5f sigma_lim, t = %.5f s, %ld cuts\n",
           r_ls, tb, cuts);
    CHECK(r_ls >= 1 && r_ls <= 1.01, "line search lands the break within eps of the strength (%.5f)", r_ls);
    CHECK(cuts > 0 && fabs(tb - 0.5) < 0.02, "steps were cut (%ld) and the break is at t = 0.5 s (%.4f)", cuts, tb);
    double r_no = bar_break(0.25, 0.07, -1, &cuts, &tb);
    printf("  implicit, dt 0.07 s, no line search: breaks at sigma = %.5f sigma_lim, t = %.5f s\n", r_no, tb);
    CHECK(r_no > r_ls && cuts == 0, "without the line search the stress overshoots (%.4f)", r_no);
    double r_ex = bar_break(0.0, 2e-4, 0.01, &cuts, &tb);
    printf("  explicit, dt 2e-4 s: breaks at sigma = %.5f sigma_lim, t = %.5f s\n", r_ex, tb);
    CHECK(r_ex >= 1 && r_ex < 1.01 && fabs(tb - 0.5) < 0.01, "explicit break at the strength");
}

/* a small lattice beam (21 x 4 nodes, end sections held vertically) under a sudden load
 * that cracks it: the implicit run with downdates equals the one that refactors */
static floe_newmark *lattice_beam_n(int refactor, double beta, double dt, int nx, int ny, double strength) {
    floe_newmark_def d = floe_newmark_default_def();
    d.beta = beta;
    d.dt = dt;
    d.refactor_on_break = refactor;
    d.damping_ratio = 0.05;
    floe_newmark *s = floe_newmark_create(&d, NULL, 0);
    const double h = 0.05, E = 30e9, rho = 2400;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            double x[3] = {i * h, (j + 0.5) * h, 0}, m = rho * h * h;
            floe_newmark_add_node(s, x, m, m * h * h / 6);
        }
    floe_beam_section sec = {0};
    sec.E = E;
    sec.G = E / 2.5;
    sec.A = h;
    sec.I = h * h * h / 12;
    sec.W = h * h / 6;
    sec.J = sec.I;
    sec.phi = 12 * E * sec.I / (5.0 / 6.0 * sec.G * sec.A * h * h);
    unsigned long long rng = 7;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            int a = j * nx + i;
            if (i + 1 < nx) floe_newmark_add_bond(s, a, a + 1, &sec, strength + 0.05e6 * floe_beam_normal(&rng), INFINITY);
            if (j + 1 < ny) floe_newmark_add_bond(s, a, a + nx, &sec, strength + 0.05e6 * floe_beam_normal(&rng), INFINITY);
        }
    for (int j = 0; j < ny; j++) {
        floe_newmark_fix(s, j * nx, FLOE_NM_UY | (j == 0 ? FLOE_NM_UX : 0));
        floe_newmark_fix(s, j * nx + nx - 1, FLOE_NM_UY);
    }
    for (int i = 0; i < nx; i++) {
        double f[3] = {0, -200e3 * h, 0};
        floe_newmark_set_load(s, (ny - 1) * nx + i, f, NULL);
    }
    return s;
}

static floe_newmark *lattice_beam(int refactor, double beta, double dt) { return lattice_beam_n(refactor, beta, dt, 21, 4, 3e6); }

/* the threaded solver (floe_newmark_set_threads) gives the same bits for 1, 2 and 3 threads:
 * a beam of 2,289 bonds and 3,630 dofs (above the loops' grain) cracking under its load,
 * explicit (the accepting bond pass, the node loops, the breaks) and implicit (K a_n, the
 * trial and the accepting passes, the step cuts) */
static void test_threads(void) {
    floe_newmark *probe = lattice_beam_n(0, 0.0, 0.5, 121, 10, 1e6);
    double dtc = floe_newmark_critical_dt(probe);
    floe_newmark_destroy(probe);
    const double betas[2] = {0.0, 0.25}, dts[2] = {0.5 * dtc, 2e-4};
    const long steps[2] = {3000, 60};
    for (int m = 0; m < 2; m++) {
        floe_newmark *s[3] = {NULL, NULL, NULL};
        int rc[3], nth[3] = {1, 2, 3}, refused = 0;
        for (int t = 0; t < 3; t++) {
            s[t] = lattice_beam_n(0, betas[m], dts[m], 121, 10, 1e6);
            int r = floe_newmark_set_threads(s[t], nth[t]);
            if (r == FLOE_ENOTSUP) {
                CHECK(strstr(floe_newmark_last_error(s[t]), "FLOE_WITH_OPENMP") != NULL, "the refusal names the option: %s",
                      floe_newmark_last_error(s[t]));
                refused = 1;
                break;
            }
            rc[t] = FLOE_OK;
            for (long k = 0; k < steps[m] && rc[t] == FLOE_OK; k++) rc[t] = floe_newmark_step(s[t]);
        }
        if (refused) {
            printf("  threads: OpenMP not built in, the comparison skipped\n");
            for (int t = 0; t < 3; t++) floe_newmark_destroy(s[t]);
            return;
        }
        floe_newmark_stats st[3];
        int same = 1, nb = floe_newmark_bond_count(s[0]);
        for (int t = 0; t < 3; t++) {
            CHECK(rc[t] == FLOE_OK, "%s beam on %d threads: %s", m ? "implicit" : "explicit", nth[t], floe_newmark_last_error(s[t]));
            floe_newmark_get_stats(s[t], &st[t]);
        }
        for (int t = 1; t < 3; t++) {
            for (int i = 0; i < floe_newmark_node_count(s[0]); i++) {
                double a[4][3], b[4][3];
                floe_newmark_get(s[0], i, a[0], a[1], a[2], a[3]);
                floe_newmark_get(s[t], i, b[0], b[1], b[2], b[3]);
                same &= !memcmp(a, b, sizeof a);
            }
            for (int k = 0; k < nb; k++) {
                int x, y;
                double ta, tb, sa, sb, ua, ub;
                floe_newmark_bond_state(s[0], k, &x, &ta, &sa, &ua);
                floe_newmark_bond_state(s[t], k, &y, &tb, &sb, &ub);
                same &= x == y && !memcmp(&ta, &tb, sizeof ta) && !memcmp(&sa, &sb, sizeof sa) && !memcmp(&ua, &ub, sizeof ua);
            }
            same &= st[t].broken == st[0].broken && st[t].steps == st[0].steps && st[t].cuts == st[0].cuts &&
                    !memcmp(&st[t].energy_elastic, &st[0].energy_elastic, sizeof(double)) &&
                    !memcmp(&st[t].energy_kinetic, &st[0].energy_kinetic, sizeof(double)) &&
                    !memcmp(&st[t].work_external, &st[0].work_external, sizeof(double)) &&
                    !memcmp(&st[t].dissipated, &st[0].dissipated, sizeof(double));
        }
        printf("  threads, %s lattice beam (%d bonds, %ld steps, %ld cuts): %d bonds broken on 1 thread\n",
               m ? "implicit" : "explicit", nb, st[0].steps, st[0].cuts, st[0].broken);
        CHECK(st[0].broken >= 2, "the %s beam cracks (%d bonds), so the breaks run threaded too", m ? "implicit" : "explicit",
              st[0].broken);
        CHECK(same, "%s: 1, 2 and 3 threads give the same bits (nodes, bonds, energies)", m ? "implicit" : "explicit");
        for (int t = 0; t < 3; t++) floe_newmark_destroy(s[t]);
    }
}

/* a system prepared, changed (a node added) and prepared again before its first step starts
 * over: the bonds' forces from an initial displacement, not twice */
static void test_prepare_again(void) {
    floe_newmark *s[2];
    floe_newmark_stats st[2];
    double sig[2];
    for (int t = 0; t < 2; t++) {
        s[t] = lattice_beam(0, 0.25, 2e-4);
        const double u[3] = {0, -1e-5, 0}, r[3] = {0, 0, 0};
        floe_newmark_set_initial(s[t], 30, u, r, r, r);
        if (t == 1) CHECK(floe_newmark_prepare(s[t]) == FLOE_OK, "first prepare: %s", floe_newmark_last_error(s[t]));
        const double x[3] = {5, 5, 0};
        floe_newmark_add_node(s[t], x, 1.0, 1.0);
        CHECK(floe_newmark_prepare(s[t]) == FLOE_OK, "prepare: %s", floe_newmark_last_error(s[t]));
        floe_newmark_get_stats(s[t], &st[t]);
        sig[t] = 0; /* the largest bond stress */
        for (int k = 0; k < floe_newmark_bond_count(s[t]); k++) {
            double sg;
            floe_newmark_bond_state(s[t], k, NULL, NULL, &sg, NULL);
            sig[t] = fmax(sig[t], sg);
        }
    }
    CHECK(st[0].energy_initial > 0 && sig[0] > 0 && st[1].energy_initial == st[0].energy_initial && sig[1] == sig[0],
          "prepared twice = prepared once (energy %.6e / %.6e J, largest bond stress %.6e / %.6e Pa)", st[1].energy_initial,
          st[0].energy_initial, sig[1], sig[0]);
    for (int t = 0; t < 2; t++) floe_newmark_destroy(s[t]);
}

static void test_downdate(void) {
    floe_newmark *a = lattice_beam(0, 0.25, 2e-4), *b = lattice_beam(1, 0.25, 2e-4);
    int ra = floe_newmark_run(a, 0.01), rb = floe_newmark_run(b, 0.01);
    CHECK(ra == FLOE_OK && rb == FLOE_OK, "lattice beams: %s / %s", floe_newmark_last_error(a), floe_newmark_last_error(b));
    floe_newmark_stats sa, sb;
    floe_newmark_get_stats(a, &sa);
    floe_newmark_get_stats(b, &sb);
    double dmax = 0, umax = 0;
    for (int i = 0; i < floe_newmark_node_count(a); i++) {
        double ua[3], ub[3];
        floe_newmark_get(a, i, ua, NULL, NULL, NULL);
        floe_newmark_get(b, i, ub, NULL, NULL, NULL);
        for (int k = 0; k < 2; k++) {
            dmax = fmax(dmax, fabs(ua[k] - ub[k]));
            umax = fmax(umax, fabs(ub[k]));
        }
    }
    int same = 1;
    for (int k = 0; k < floe_newmark_bond_count(a); k++) {
        int x, y;
        floe_newmark_bond_state(a, k, &x, NULL, NULL, NULL);
        floe_newmark_bond_state(b, k, &y, NULL, NULL, NULL);
        same &= x == y;
    }
    printf("  lattice beam cracking (implicit): %d bonds broken, %ld steps, %ld cuts; downdates %ld + %ld factorizations "
           "vs %ld factorizations; largest displacement difference %.2e of %.2e m\n", sa.broken, sa.steps, sa.cuts,
           sa.downdates, sa.factorizations, sb.factorizations, dmax, umax);
    CHECK(sa.broken >= 3 && same, "the beam cracks, the same bonds break with downdates and with refactoring");
    CHECK(sa.downdates >= sa.broken && sa.factorizations < sb.factorizations, "breaks handled by downdates");
    CHECK(dmax < 1e-8 * umax, "downdated factor = refactored factor (difference %.2e relative)", dmax / umax);
    floe_newmark_destroy(a);
    floe_newmark_destroy(b);
}

static void test_errors(void) {
    char err[256];
    floe_newmark_def d = floe_newmark_default_def();
    d.dt = 1e-3;
    d.beta = 0.6;
    CHECK(floe_newmark_create(&d, err, sizeof err) == NULL && strstr(err, "beta"), "beta 0.6 refused: %s", err);
    d.beta = 0.25;
    d.dt = 0;
    CHECK(floe_newmark_create(&d, err, sizeof err) == NULL && strstr(err, "dt"), "dt 0 refused: %s", err);
    d.dt = 1e-3;
    floe_newmark *s = floe_newmark_create(&d, err, sizeof err);
    double x[3] = {0, 0, 0};
    CHECK(floe_newmark_add_node(s, x, -1, 1) == -FLOE_EINVAL, "negative mass refused");
    floe_newmark_add_node(s, x, 1, 1);
    floe_newmark_add_node(s, x, 1, 1);
    floe_beam_section sec = {0};
    sec.E = 1;
    sec.A = sec.I = sec.W = 1;
    CHECK(floe_newmark_add_bond(s, 0, 1, &sec, 1, 1) == -FLOE_EINVAL &&
              strstr(floe_newmark_last_error(s), "same place"), "bond of coincident nodes refused");
    CHECK(floe_newmark_add_bond(s, 0, 5, &sec, 1, 1) == -FLOE_EINVAL, "node out of range refused");
    floe_newmark_destroy(s);
}

int main(void) {
    /* a build without CHOLMOD (FLOE_WITH_CHOLMOD=OFF) refuses the implicit scheme with a
     * message naming the option: then only the explicit parts run */
    floe_newmark_def d = floe_newmark_default_def();
    d.dt = 1e-3;
    char err[256] = "";
    floe_newmark *probe = floe_newmark_create(&d, err, sizeof err);
    if (!probe) {
        printf("  implicit Newmark unavailable: %s\n", err);
        CHECK(strstr(err, "FLOE_WITH_CHOLMOD") != NULL, "the refusal names the build option");
        long cuts;
        double tb, r = bar_break(0.0, 2e-4, 0.01, &cuts, &tb);
        CHECK(r >= 1 && r < 1.01, "explicit break at the strength");
        return check_summary("test_newmark (explicit only)");
    }
    floe_newmark_destroy(probe);
    test_oscillator();
    test_static_cantilever();
    test_breakage();
    test_downdate();
    test_threads();
    test_prepare_again();
    test_errors();
    return check_summary("test_newmark");
}
