/* test_beam.c - beam bonds in the world (contact/bonds/floe_beam.h; ParticLS §5.5, 004 §2):
 * the linearised bond law against the matrix of 004 eq 7 (2D and 3D), rigid motions give
 * no force, the 2D cantilever of ParticLS eq 38 (11 points within 2 %, convergence table),
 * Timoshenko shear deflection, 3D cantilevers with nearest-neighbour and fixed-radius bonds,
 * breakage at the strength and contact afterwards, strengths drawn from N(mean, sd),
 * the contact exclusion chained with a peridynamic body's, the energy ledger, bad input. */
#include "check.h"
#include "floe_beam.h"
#include "floe_scene.h"
#include "floe_pd.h"
#include "world_internal.h" /* internal: unit test of the beam-bond forces: floe_compute_forces at displaced poses, the exclusion list */

#include <stdlib.h>
#include <string.h>

static floe_world *new_world(int dim, double gx, double gy, double gz, int *mat) {
    floe_world_def d = floe_default_world_def();
    d.dim = dim;
    floe_v3_set(d.gravity, gx, gy, gz);
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"steel", 7800, 2e11, 0.3};
    *mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, *mat, *mat, floe_linear_law_create(1e3, 0, 0, 0, 0));
    return w;
}

static int add_sphere(floe_world *w, int mat, double r, const double x[3], double mass, floe_motion motion) {
    int g = floe_world_add_geometry(w, floe_sphere_create(r));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = g;
    p.material = mat;
    floe_v3_copy(p.x, x);
    p.mass = mass;
    p.motion = motion;
    return floe_world_add_particle(w, &p);
}

/* ---- 1. linearisation = 004 eq 7; rigid motions give no force ---- */

/* rows of R: local axes (e, y', z' = e x y') */
static void local_frame(int dim, const double e[3], double R[3][3]) {
    floe_v3_copy(R[0], e);
    if (dim == 2) floe_v3_set(R[1], -e[1], e[0], 0);
    else {
        double a[3] = {0.3, -0.7, 0.2}, t[3];
        floe_v3_cross(t, e, a);
        floe_v3_scale(t, 1.0 / floe_v3_norm(t));
        floe_v3_copy(R[1], t);
    }
    floe_v3_cross(R[2], R[0], R[1]);
}

static void rotate_by(double q[4], const double th[3]) {
    double dq[4], r[4];
    floe_q_from_rotvec(dq, th);
    floe_q_mul(r, dq, q);
    memcpy(q, r, sizeof r);
}

static void test_linearisation(int dim, int timoshenko) {
    int mat;
    floe_world *w = new_world(dim, 0, 0, 0, &mat);
    double xa[3] = {0.1, 0.2, 0}, xb[3] = {0.1 + 0.08, 0.2 + 0.05, dim == 3 ? 0.03 : 0};
    int a = add_sphere(w, mat, 0.05, xa, 1.0, FLOE_FREE), b = add_sphere(w, mat, 0.05, xb, 1.5, FLOE_FREE);
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 3e10;
    bp.poisson = 0.2;
    bp.timoshenko = timoshenko;
    bp.radius_ratio = 0.8;
    CHECK(floe_world_add_beam_bond(w, a, b, &bp) == 0, "one bond: %s", floe_world_last_error(w));
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    floe_beam_bond_info info;
    floe_world_beam_bond(w, 0, &info);
    const int nd = dim == 2 ? 3 : 6, n = 2 * nd;
    double K[144];
    floe_beam_local_stiffness(&info.section, dim, K);
    double e[3], R[3][3];
    floe_v3_sub(e, xb, xa);
    floe_v3_scale(e, 1.0 / floe_v3_norm(e));
    local_frame(dim, e, R);
    /* small displacements and rotations of both ends, in global components */
    const double h = 1e-7 * info.section.l;
    double du[2][3] = {{0.3 * h, -0.8 * h, 0.5 * h}, {-0.6 * h, 0.4 * h, 0.9 * h}};
    double dth[2][3] = {{0.7e-7, -0.4e-7, 0.9e-7}, {-0.5e-7, 0.8e-7, 0.6e-7}};
    if (dim == 2)
        for (int k = 0; k < 2; k++) du[k][2] = dth[k][0] = dth[k][1] = 0;
    floe_particles *p = &w->p;
    for (int k = 0; k < 2; k++) {
        floe_v3_add(p->x + 3 * k, p->x + 3 * k, du[k]);
        rotate_by(p->q + 4 * k, dth[k]);
    }
    CHECK(floe_compute_forces(w) == FLOE_OK, "forces");
    /* local displacement vector, then f = -T K T^T u */
    double ul[12], fl[12];
    for (int k = 0; k < 2; k++)
        for (int r = 0; r < 3; r++) {
            double ut = floe_v3_dot(R[r], du[k]), ur = floe_v3_dot(R[r], dth[k]);
            if (dim == 2) {
                if (r < 2) ul[3 * k + r] = ut;
                else ul[3 * k + 2] = ur;
            } else {
                ul[6 * k + r] = ut;
                ul[6 * k + 3 + r] = ur;
            }
        }
    for (int r = 0; r < n; r++) {
        fl[r] = 0;
        for (int c = 0; c < n; c++) fl[r] -= K[r * n + c] * ul[c];
    }
    double err = 0, scale = 0;
    for (int k = 0; k < 2; k++) {
        double Fg[3] = {0, 0, 0}, Tg[3] = {0, 0, 0};
        for (int r = 0; r < 3; r++) { /* back to global: sum over local components */
            double ft = dim == 2 ? (r < 2 ? fl[3 * k + r] : 0) : fl[6 * k + r];
            double fr = dim == 2 ? (r == 2 ? fl[3 * k + 2] : 0) : fl[6 * k + 3 + r];
            floe_v3_axpy(Fg, ft, R[r]);
            floe_v3_axpy(Tg, fr, R[r]);
        }
        for (int a2 = 0; a2 < 3; a2++) {
            double l = info.section.l;
            err = fmax(err, fabs(p->f[3 * k + a2] - Fg[a2]) * l);
            err = fmax(err, fabs(p->t[3 * k + a2] - Tg[a2]));
            scale = fmax(scale, fmax(fabs(Fg[a2]) * l, fabs(Tg[a2])));
        }
    }
    printf("  %dD %s: bond force and torque vs -K u of 004 eq 7 (phi %.3f): max difference %.2e of %.2e\n", dim,
           timoshenko ? "Timoshenko" : "Euler-Bernoulli", info.section.phi, err, scale);
    CHECK(scale > 0 && err < 1e-5 * scale, "%dD linearised bond law = eq 7 (rel. %.2e)", dim, err / scale);

    /* a rigid motion of the pair (1 rad turn about an oblique axis + a shift) */
    double th[3] = {dim == 3 ? 0.5 : 0, dim == 3 ? -0.6 : 0, 0.7}, qr[4], c[3];
    floe_q_from_rotvec(qr, th);
    for (int k = 0; k < 2; k++) {
        double x0[3], rel[3];
        floe_v3_copy(x0, k ? xb : xa);
        floe_v3_sub(rel, x0, xa);
        floe_q_rotate(c, qr, rel);
        floe_v3_set(p->x + 3 * k, xa[0] + c[0] + 0.3, xa[1] + c[1] - 0.2, dim == 3 ? xa[2] + c[2] + 0.1 : 0);
        floe_q_identity(p->q + 4 * k);
        rotate_by(p->q + 4 * k, th);
    }
    CHECK(floe_compute_forces(w) == FLOE_OK, "forces");
    double fmaxr = 0;
    for (int k = 0; k < 6; k++) fmaxr = fmax(fmaxr, fmax(fabs(p->f[k]) * info.section.l, fabs(p->t[k])));
    double ref = info.section.E * info.section.A * info.section.l; /* force at 100 % strain, times l */
    printf("  %dD rigid turn of 1 rad + shift: largest force x l or torque %.2e (E A l = %.2e)\n", dim, fmaxr, ref);
    CHECK(fmaxr < 1e-12 * ref, "rigid motion gives no bond force (%.2e)", fmaxr / ref);
    floe_world_destroy(w);
}

/* ---- 2. cantilevers ---- */

typedef struct { double c; } damp_ctx;
/* mass-proportional damping f = -c m v, torque = -c J w (drives the cantilever to rest) */
static void damping(const floe_world *w, int i, double t, double f[3], double tq[3], void *user) {
    (void)t;
    const damp_ctx *d = user;
    const floe_particles *p = &w->p;
    double J = fmin(p->inertia[3 * i], fmin(p->inertia[3 * i + 1], p->inertia[3 * i + 2]));
    for (int a = 0; a < 3; a++) {
        f[a] = -d->c * p->mass[i] * p->v[3 * i + a];
        tq[a] = -d->c * J * p->w[3 * i + a];
    }
}

/* 2D cantilever of length L with n points (the first clamped), total mass M lumped (tip
 * half), load by the acceleration a; returns the tip deflection (positive down) */
static double cantilever_2d(int n, double L, double M, double a, double E, double A, double I, int timo,
                            double nu, double *t_run) {
    int mat;
    floe_world *w = new_world(2, 0, -a, 0, &mat);
    w->def.dt_safety = 0.5;
    double l = L / (n - 1), m = M / (n - 1);
    for (int k = 0; k < n; k++) {
        double x[3] = {k * l, 0, 0};
        add_sphere(w, mat, 0.5 * l, x, k == n - 1 || k == 0 ? 0.5 * m : m, k == 0 ? FLOE_FIXED : FLOE_FREE);
    }
    floe_beam_params bp = floe_default_beam_params();
    bp.young = E;
    bp.poisson = nu;
    bp.area = A;
    bp.inertia = I;
    bp.timoshenko = timo;
    int nb = floe_world_add_beam_bonds(w, 1.01, &bp);
    CHECK(nb == n - 1, "cantilever: %d nearest-neighbour bonds (got %d: %s)", n - 1, nb, floe_world_last_error(w));
    /* first bending mode omega_1 = 3.516 sqrt(EI / (mu L^4)): critical mass damping */
    damp_ctx dc = {2.0 * 3.516 * sqrt(E * I / (M / L * L * L * L))};
    floe_world_set_body_force(w, damping, &dc);
    double t_end = 16.0 / (0.5 * dc.c);
    int rc = floe_world_run(w, t_end, NULL, NULL);
    CHECK(rc == FLOE_OK, "cantilever run: %s", floe_world_last_error(w));
    *t_run = t_end;
    double d = -w->p.x[3 * (n - 1) + 1];
    floe_world_destroy(w);
    return d;
}

static void test_cantilever_2d(void) {
    /* ParticLS Fig. 10 parameters: M = 1 kg, L = 1 m, I = 7.85e-9 m^4 (a rod of radius 1 cm);
     * E = 1e10 Pa and a = 1 m/s^2 keep the deflection at 0.16 % of L (linear range) */
    const double L = 1, M = 1, a = 1, r = 0.01, A = M_PI * r * r, I = 0.25 * M_PI * r * r * r * r, E = 1e10;
    const double d_ref = M * a * L * L * L / (8 * E * I);
    printf("  2D cantilever, d = M a L^3 / (8 E I) = %.6e m (ParticLS eq 38)\n", d_ref);
    printf("  %6s %14s %12s %14s\n", "points", "tip d [m]", "rel. error", "(l/L)^2/3");
    int ns[4] = {6, 11, 21, 41};
    double errs[4];
    for (int k = 0; k < 4; k++) {
        double tr;
        double d = cantilever_2d(ns[k], L, M, a, E, A, I, 0, 0.25, &tr);
        double l = L / (ns[k] - 1);
        errs[k] = (d - d_ref) / d_ref;
        printf("  %6d %14.8e %12.3e %14.3e\n", ns[k], d, errs[k], l * l / 3);
        if (ns[k] == 11) CHECK(fabs(errs[k]) < 0.02, "11 points within 2 %% (%.3g %%)", 100 * errs[k]);
    }
    for (int k = 1; k < 4; k++)
        CHECK(fabs(errs[k]) < 0.3 * fabs(errs[k - 1]), "error falls as points increase (%.3g -> %.3g)", errs[k - 1],
              errs[k]);
    /* the lumped load gives the trapezoid rule's error (l/L)^2 / 3 exactly (the beam elements
     * are exact for nodal loads): the rest is the settling and the co-rotational geometry */
    CHECK(fabs(errs[1] - 0.01 / 3) < 2e-4, "11 points: error %.4g = (l/L)^2/3 = %.4g within 2e-4", errs[1], 0.01 / 3);

    /* Timoshenko: a stubby beam (L/h = 4), d = w L^4/(8EI) + w L^2/(2 kappa G A) */
    const double b = 0.25, hgt = 0.25, At = b * hgt, It = b * hgt * hgt * hgt / 12, nu = 0.25, G = E / (2 * (1 + nu));
    double tr;
    double dT = cantilever_2d(21, L, M, a, E, At, It, 1, nu, &tr);
    double wl = M * a / L;
    double dT_ref = wl * L * L * L * L / (8 * E * It) + wl * L * L / (2 * (5.0 / 6.0) * G * At);
    double dEB = cantilever_2d(21, L, M, a, E, At, It, 0, nu, &tr);
    printf("  Timoshenko cantilever (L/h = 4, 21 points): d = %.6e m vs %.6e m (shear part %.1f %%), Euler-Bernoulli bonds "
           "%.6e m\n", dT, dT_ref, 100 * (dT_ref - wl / (8 * E * It)) / dT_ref, dEB);
    CHECK_NEAR(dT, dT_ref, 0.01, "Timoshenko tip deflection");
    CHECK(dEB < 0.99 * dT, "Euler-Bernoulli bonds are stiffer than Timoshenko ones");
}

/* 3D: nx x 3 x 3 spheres on a cubic lattice (spacing s), the first layer clamped; bonds to
 * the nearest neighbours (section s x s) or within a fixed radius 1.5 s (diagonals too);
 * returns the tip deflection (mean over the last layer) */
static double cantilever_3d(int nx, double s, double E, double rho, double a, int fixed_radius, int *nbonds) {
    int mat;
    floe_world *w = new_world(3, 0, 0, -a, &mat);
    w->def.dt_safety = 0.5;
    double m = rho * s * s * s;
    for (int k = 0; k < nx; k++)
        for (int j = 0; j < 3; j++)
            for (int i = 0; i < 3; i++) {
                double x[3] = {k * s, (j - 1) * s, (i - 1) * s};
                add_sphere(w, mat, 0.5 * s, x, k == nx - 1 ? 0.5 * m : m, k == 0 ? FLOE_FIXED : FLOE_FREE);
            }
    floe_beam_params bp = floe_default_beam_params();
    bp.young = E;
    bp.poisson = 0.25;
    bp.area = s * s;
    bp.inertia = s * s * s * s / 12;
    bp.polar = 0.1406 * s * s * s * s;
    bp.section_modulus = s * s * s / 6;
    if (fixed_radius) bp.max_distance = 1.5 * s;
    *nbonds = floe_world_add_beam_bonds(w, 1.01, &bp);
    double H = 3 * s, L = (nx - 1) * s, mu = rho * H * H;
    damp_ctx dc = {2.0 * 3.516 * sqrt(E * H * H * H * H / 12 / (mu * L * L * L * L))};
    floe_world_set_body_force(w, damping, &dc);
    int rc = floe_world_run(w, 16.0 / (0.5 * dc.c), NULL, NULL);
    CHECK(rc == FLOE_OK, "3D cantilever run: %s", floe_world_last_error(w));
    double d = 0;
    for (int q = 0; q < 9; q++) d -= w->p.x[3 * (9 * (nx - 1) + q) + 2] / 9;
    floe_world_destroy(w);
    return d;
}

static void test_cantilever_3d(void) {
    const double s = 0.02, E = 1e9, rho = 1000, a = 1;
    printf("  3D cantilever, 3 x 3 spheres across (section 0.06 x 0.06 m), d_EB = w L^4 / (8 E I):\n");
    printf("  %6s %10s %8s %14s %14s %10s\n", "layers", "bonds", "L/H", "d_EB [m]", "d [m]", "d / d_EB");
    double ratio_nn[2] = {0, 0}, ratio_fr = 0;
    int layers[2] = {11, 21};
    for (int k = 0; k < 2; k++) {
        int nx = layers[k], nb;
        double L = (nx - 1) * s, H = 3 * s, I = H * H * H * H / 12, wl = rho * H * H * a;
        double dref = wl * L * L * L * L / (8 * E * I);
        double d = cantilever_3d(nx, s, E, rho, a, 0, &nb);
        ratio_nn[k] = d / dref;
        printf("  %6d %10d %8.1f %14.6e %14.6e %10.4f  nearest neighbours\n", nx, nb, L / H, dref, d, d / dref);
        if (k == 1) {
            double df = cantilever_3d(nx, s, E, rho, a, 1, &nb);
            ratio_fr = df / dref;
            printf("  %6d %10d %8.1f %14.6e %14.6e %10.4f  fixed radius 1.5 s\n", nx, nb, L / H, dref, df, df / dref);
        }
    }
    /* the lattice's bending stiffness equals the section's (sum of A y^2 + I over the 9
     * chains = (3s)^4/12), and the frame's shear flexibility fades as the beam gets slender */
    CHECK(fabs(ratio_nn[1] - 1) < 0.1, "3D nearest neighbours, L/H = 6.7: within 10 %% of Euler-Bernoulli (%.4f)",
          ratio_nn[1]);
    CHECK(fabs(ratio_nn[1] - 1) < fabs(ratio_nn[0] - 1), "3D: closer to Euler-Bernoulli as the beam gets slender");
    CHECK(ratio_fr < ratio_nn[1], "fixed-radius bonds stiffen the beam (ParticLS Fig. 11): %.4f < %.4f", ratio_fr,
          ratio_nn[1]);
}

/* ---- 3. breakage, contact afterwards, strengths ---- */

typedef struct { double rate, push; int idx; } pull_ctx;
/* a force ramping up until the bond breaks, then a push back */
static void pull(const floe_world *w, int i, double t, double f[3], double tq[3], void *user) {
    (void)tq;
    const pull_ctx *c = user;
    if (i != c->idx) return;
    f[0] = floe_world_beam_broken_count(w) == 0 ? c->rate * t : -c->push;
}

static void test_breakage(void) {
    int mat;
    floe_world *w = new_world(3, 0, 0, 0, &mat);
    floe_world_set_law(w, mat, mat, floe_linear_law_create(1e6, 0, 50, 0, 0));
    double x0[3] = {0, 0, 0}, x1[3] = {0.02, 0, 0};
    add_sphere(w, mat, 0.01, x0, 0.01, FLOE_FIXED);
    int b = add_sphere(w, mat, 0.01, x1, 0.01, FLOE_FREE);
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 1e8;
    bp.radius_ratio = 0.5;
    bp.tensile_strength = 2e6;
    bp.damping_ratio = 0.5;
    CHECK(floe_world_add_beam_bonds(w, 1.01, &bp) == 1, "one bond");
    floe_beam_bond_info info;
    floe_world_beam_bond(w, 0, &info);
    double A = info.section.A, F_break = 2e6 * A;
    /* the force ramps to 2 F_break over 0.2 s (quasi-static: the bond's period is ~1e-4 s) */
    pull_ctx pc = {2 * F_break / 0.2, 0.1 * F_break, b};
    floe_world_set_body_force(w, pull, &pc);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    double t_break = -1, F_at = 0;
    int rc = 0, contacts = 0;
    double min_gap = INFINITY;
    while (floe_world_time(w) < 0.3 && !rc) {
        rc = floe_world_step(w);
        if (t_break < 0 && floe_world_beam_broken_count(w) == 1) {
            floe_world_beam_bond(w, 0, &info);
            t_break = info.t_broken;
            F_at = pc.rate * t_break;
        }
        if (t_break >= 0) {
            if (floe_world_contact_count(w) > 0) contacts++;
            min_gap = fmin(min_gap, w->p.x[3 * b] - w->p.x[0] - 0.02);
        }
    }
    CHECK(rc == FLOE_OK, "breakage run: %s", floe_world_last_error(w));
    printf("  tension bar: breaks at F = %.6g N vs sigma_lim A = %.6g N (t = %.4f s); afterwards in contact for %d "
           "steps, smallest gap %.3g m (radius 0.01)\n", F_at, F_break, t_break, contacts, min_gap);
    CHECK_NEAR(F_at, F_break, 0.01, "breaking force = tensile strength x area (eq 11)");
    CHECK(contacts > 0 && min_gap > -0.005, "after breaking, the pair meets by contact and does not pass through");
    floe_world_destroy(w);

    /* strengths: a lattice of 2,000+ bonds with N(6 MPa, 0.05 MPa), reproducible by seed */
    w = new_world(2, 0, 0, 0, &mat);
    for (int j = 0; j < 30; j++)
        for (int i = 0; i < 40; i++) {
            double x[3] = {0.01 * i, 0.01 * j, 0};
            add_sphere(w, mat, 0.005, x, 0.1, FLOE_FREE);
        }
    bp = floe_default_beam_params();
    bp.young = 3e10;
    bp.tensile_strength = 6e6;
    bp.tensile_sd = 0.05e6;
    bp.seed = 42;
    int nb = floe_world_add_beam_bonds(w, 1.01, &bp);
    double s1 = 0, s2 = 0;
    for (int k = 0; k < nb; k++) {
        floe_world_beam_bond(w, k, &info);
        s1 += info.sigma_lim;
        s2 += info.sigma_lim * info.sigma_lim;
    }
    double mean = s1 / nb, sd = sqrt(s2 / nb - mean * mean);
    printf("  %d bonds: strength mean %.6g Pa, sd %.6g Pa (N(6e6, 5e4))\n", nb, mean, sd);
    CHECK(nb == 40 * 29 + 30 * 39, "square lattice: %d nearest-neighbour bonds", nb);
    CHECK(fabs(mean - 6e6) < 4 * 5e4 / sqrt(nb), "strength mean within 4 standard errors");
    CHECK(fabs(sd - 5e4) < 0.1 * 5e4, "strength sd within 10 %%");
    floe_world_destroy(w);
}

/* ---- 4. exclusion chained with a PD body's ---- */

/* a 6 x 4 x 4 mm PMB block (dx 1 mm, horizon 3 dx) */
static floe_pd_body *pd_block(void) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = 1e-3;
    r.horizon_factor = 3;
    floe_v3_set(r.hi, 6e-3, 4e-3, 4e-3);
    floe_pd_body *pb = NULL;
    floe_pd_body_create(&pb, &r);
    floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
    floe_pd_set_material(pb, &pm);
    return pb;
}

static void test_exclusion_with_pd(void) {
    int mat;
    floe_world *w = new_world(3, 0, 0, 0, &mat);
    /* a PD block, then a bonded chain of spheres beside it (bonds first, PD second and the
     * other way round must both keep both exclusions) */
    for (int order = 0; order < 2; order++) {
        if (order == 1) { floe_world_destroy(w); w = new_world(3, 0, 0, 0, &mat); }
        floe_pd_body *pb = pd_block();
        int first = -1, nchain = 8;
        if (order == 1) CHECK(floe_world_add_pd_body(w, pb, mat, NULL, &first) == FLOE_OK, "PD body");
        int c0 = w->p.n;
        for (int k = 0; k < nchain; k++) {
            double x[3] = {0.02 + k * 0.002, 0, 0};
            int i = add_sphere(w, mat, 0.001, x, 1e-5, FLOE_FREE);
            w->p.group[i] = 7;
        }
        double xs[3] = {0.02 + nchain * 0.002 - 1e-5, 0, 0}; /* unbonded, touching the chain's end */
        add_sphere(w, mat, 0.001, xs, 1e-5, FLOE_FREE);
        floe_beam_params bp = floe_default_beam_params();
        bp.young = 1e9;
        bp.group = 7; /* the chain only (not the PD points, nor the loose sphere) */
        CHECK(floe_world_add_beam_bonds(w, 1.01, &bp) == nchain - 1, "chain bonds: %s", floe_world_last_error(w));
        if (order == 0) CHECK(floe_world_add_pd_body(w, pb, mat, NULL, &first) == FLOE_OK, "PD body");
        CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
        CHECK(floe_compute_forces(w) == FLOE_OK, "forces");
        int bonded_listed = 0, family_listed = 0;
        for (int k = 0; k < w->nl.npairs; k++) {
            int i = w->nl.pi[k], j = w->nl.pj[k];
            if (i >= c0 && i < c0 + nchain && j >= c0 && j < c0 + nchain && abs(i - j) == 1) bonded_listed++;
            if (w->pd_of && i < w->pd_npts_alloc && j < w->pd_npts_alloc && w->pd_of[i] >= 0 && w->pd_of[i] == w->pd_of[j])
                family_listed++;
        }
        printf("  exclusion (%s first): %d list pairs, bonded pairs listed %d, PD family pairs listed %d\n",
               order ? "PD" : "bonds", w->nl.npairs, bonded_listed, family_listed);
        CHECK(bonded_listed == 0, "beam-bonded pairs are not contact candidates");
        CHECK(family_listed == 0, "PD family pairs are not contact candidates");
        CHECK(floe_world_contact_count(w) == 1, "one contact: the loose sphere (got %d)", floe_world_contact_count(w));
    }
    floe_world_destroy(w);
}

/* ---- 5. energy ledger, stability, bad input ---- */

static void test_ledger_and_errors(void) {
    int mat;
    for (int damped = 0; damped < 2; damped++) {
        floe_world *w = new_world(3, 0, 0, 0, &mat);
        for (int k = 0; k < 6; k++) {
            double x[3] = {0.02 * k, 0, 0};
            int i = add_sphere(w, mat, 0.01, x, 0.01, k == 0 ? FLOE_FIXED : FLOE_FREE);
            if (k == 5) { w->p.v[3 * i + 1] = 0.05; w->p.v[3 * i + 2] = -0.03; w->p.w[3 * i] = 2.0; }
        }
        floe_beam_params bp = floe_default_beam_params();
        bp.young = 1e8;
        bp.radius_ratio = 0.5;
        bp.damping_ratio = damped ? 1.0 : 0;
        floe_world_add_beam_bonds(w, 1.01, &bp);
        int rc = floe_world_prepare(w);
        double dtc = floe_world_critical_dt(w);
        for (int s = 0; s < 5000 && !rc; s++) rc = floe_world_step(w);
        CHECK(rc == FLOE_OK, "chain run: %s", floe_world_last_error(w));
        floe_energy e = floe_world_energy(w);
        double err = floe_world_energy_balance_error(w);
        printf("  vibrating chain (%s): dt %.3g s (critical %.3g s), kinetic %.3e, elastic %.3e, dissipated %.3e of "
               "%.3e J, balance error %.2e\n", damped ? "damped" : "undamped", floe_world_dt(w), dtc,
               e.kinetic_trans + e.kinetic_rot, e.elastic, e.dissipated, e.initial, err);
        CHECK(err < 2e-3, "energy balance closes (%.2e)", err);
        /* stiffness-proportional damping: the axial and torsional modes lose most of their
         * energy, the slow bending modes little (damping ratio xi omega / omega_a) */
        if (damped) CHECK(e.dissipated > 0.3 * e.initial, "damping dissipates (%.2f of the energy)", e.dissipated / e.initial);
        else CHECK(fabs(e.dissipated) < 2e-3 * e.initial, "undamped: nothing dissipated beyond integration error");
        floe_world_destroy(w);
    }
    /* the critical step is a bound: 0.95 x it is stable (no damping, 20,000 steps) */
    {
        floe_world *w = new_world(2, 0, 0, 0, &mat);
        w->def.dt_safety = 0.95;
        for (int k = 0; k < 12; k++) {
            double x[3] = {0.02 * k, 0, 0};
            int i = add_sphere(w, mat, 0.01, x, 0.01, k == 0 ? FLOE_FIXED : FLOE_FREE);
            w->p.v[3 * i] = 1e-3 * sin(k);
            w->p.v[3 * i + 1] = 1e-3 * cos(3 * k);
        }
        floe_beam_params bp = floe_default_beam_params();
        bp.young = 1e9;
        floe_world_add_beam_bonds(w, 1.01, &bp);
        int rc = 0;
        for (int s = 0; s < 20000 && !rc; s++) rc = floe_world_step(w);
        floe_energy e = floe_world_energy(w);
        CHECK(rc == FLOE_OK && e.kinetic_trans + e.kinetic_rot + e.elastic < 2 * e.initial,
              "0.95 x the bond critical step is stable: %s", floe_world_last_error(w));
        floe_world_destroy(w);
    }
    floe_world *w = new_world(3, 0, 0, 0, &mat);
    double x0[3] = {0, 0, 0}, x1[3] = {0.02, 0, 0};
    add_sphere(w, mat, 0.01, x0, 0.01, FLOE_FREE);
    add_sphere(w, mat, 0.01, x1, 0.01, FLOE_FREE);
    floe_beam_params bp = floe_default_beam_params();
    int r1 = floe_world_add_beam_bonds(w, 1.01, &bp); /* young missing */
    CHECK(r1 == -FLOE_EINVAL && strstr(floe_world_last_error(w), "young"), "missing young refused: %s",
          floe_world_last_error(w));
    bp.young = 1e9;
    bp.poisson = 0.7;
    r1 = floe_world_add_beam_bonds(w, 1.01, &bp);
    CHECK(r1 == -FLOE_EINVAL && strstr(floe_world_last_error(w), "poisson"), "bad poisson refused: %s",
          floe_world_last_error(w));
    bp.poisson = 0.25;
    CHECK(floe_world_add_beam_bonds(w, -1, &bp) == -FLOE_EINVAL, "negative radius factor refused");
    CHECK(floe_world_add_beam_bond(w, 0, 0, &bp) == -FLOE_EINVAL, "self bond refused");
    CHECK(floe_world_add_beam_bond(w, 0, 1, &bp) == 0, "bond 0-1");
    CHECK(floe_world_add_beam_bond(w, 1, 0, &bp) == -FLOE_EINVAL, "duplicate bond refused");
    CHECK(floe_world_add_beam_bonds(w, 1.01, &bp) == 0, "existing bonds skipped");
    floe_world_destroy(w);
}

/* ---- 6. the `bonds:` scene section ---- */

static void test_scene(void) {
    const char *text =
        "dimension: 2\n"
        "time: {duration: 0.002}\n"
        "gravity: [0, -1, 0]\n"
        "materials:\n"
        "  - {name: rod, density: 1000, young: 1.0e9, poisson: 0.25}\n"
        "laws:\n"
        "  - {materials: [rod, rod], model: linear, kn: 1000, ks: 0}\n"
        "bodies:\n"
        "  - {shape: {sphere: {radius: 0.01}}, material: rod, position: [0, 0], motion: fixed}\n"
        "  - {packing: lattice, shape: {sphere: {radius: 0.01}}, material: rod, origin: [0.02, 0],\n"
        "     counts: [9, 1, 1], spacing: 0.02}\n"
        "bonds:\n"
        "  - {young: 1.0e9, poisson: 0.25, radius_factor: 1.01, timoshenko: true, radius_ratio: 0.5,\n"
        "     tensile_strength: 6.0e6, tensile_sd: 5.0e4, seed: 3}\n";
    floe_world *w = NULL;
    floe_scene_info info;
    char err[1024];
    int rc = floe_scene_load_string(text, "bonds.yaml", "/tmp", &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "scene with bonds: %s", err);
    if (rc == FLOE_OK) {
        floe_beam_bond_info bi;
        floe_world_beam_bond(w, 0, &bi);
        printf("  scene: %d particles, %d bonds, phi %.3f, strength %.6g Pa\n", w->p.n, floe_world_beam_bond_count(w),
               bi.section.phi, bi.sigma_lim);
        CHECK(floe_world_beam_bond_count(w) == 9 && bi.section.phi > 0, "scene: 9 Timoshenko bonds along the rod");
        CHECK(floe_world_run(w, info.duration, NULL, NULL) == FLOE_OK, "scene runs: %s", floe_world_last_error(w));
        floe_world_destroy(w);
    }
    const char *bad = "dimension: 2\ntime: {duration: 0.002}\nmaterials:\n  - {name: rod, density: 1000}\n"
                      "laws:\n  - {materials: [rod, rod], model: linear, kn: 1000, ks: 0}\n"
                      "bodies:\n  - {shape: {sphere: {radius: 0.01}}, material: rod, position: [0, 0]}\n"
                      "bonds:\n  - {young: 1.0e9, radius_factr: 1.01}\n";
    rc = floe_scene_load_string(bad, "bad.yaml", "/tmp", &w, &info, err, sizeof err);
    printf("  bad key: %s\n", err);
    CHECK(rc != FLOE_OK && strstr(err, "bad.yaml:10") && strstr(err, "radius_factor"), "misspelt key named with line");
    const char *lonely = "dimension: 2\ntime: {duration: 0.002}\nmaterials:\n  - {name: rod, density: 1000}\n"
                         "laws:\n  - {materials: [rod, rod], model: linear, kn: 1000, ks: 0}\n"
                         "bodies:\n  - {shape: {sphere: {radius: 0.01}}, material: rod, position: [0, 0]}\n"
                         "bonds:\n  - {young: 1.0e9}\n";
    rc = floe_scene_load_string(lonely, "lonely.yaml", "/tmp", &w, &info, err, sizeof err);
    printf("  no pair: %s\n", err);
    CHECK(rc != FLOE_OK && strstr(err, "no pair"), "a bond set that bonds nothing is an error");
}

/* review findings: PD points are not beam-bonded unless their group is named; rk2 with
 * bonds is refused; single bonds draw different strengths from one seeded stream */
static void test_defaults_and_refusals(void) {
    int mat;
    floe_world *w = new_world(3, 0, 0, 0, &mat);
    floe_pd_body *pb = pd_block();
    CHECK(floe_world_add_pd_body(w, pb, mat, NULL, NULL) == FLOE_OK, "PD body");
    for (int k = 0; k < 4; k++) {
        double x[3] = {0.02 + k * 0.002, 0, 0};
        add_sphere(w, mat, 0.001, x, 1e-5, FLOE_FREE);
    }
    floe_beam_params bp = floe_default_beam_params();
    bp.young = 1e9;
    int nb = floe_world_add_beam_bonds(w, 1.01, &bp);
    CHECK(nb == 3, "bonds with group left out skip the PD points: %d bonds (want the chain's 3)", nb);
    w->def.integrator = FLOE_RK2;
    int rc = floe_world_prepare(w);
    CHECK(rc == FLOE_EINVAL && strstr(floe_world_last_error(w), "rk2"), "rk2 with beam bonds refused: %s",
          floe_world_last_error(w));
    floe_world_destroy(w);

    w = new_world(3, 0, 0, 0, &mat);
    for (int k = 0; k < 5; k++) {
        double x[3] = {k * 0.002, 0, 0};
        add_sphere(w, mat, 0.001, x, 1e-5, FLOE_FREE);
    }
    bp.tensile_strength = 6e6;
    bp.tensile_sd = 1e6;
    for (int k = 0; k < 4; k++) CHECK(floe_world_add_beam_bond(w, k, k + 1, &bp) == k, "single bond %d", k);
    floe_beam_bond_info a, b;
    floe_world_beam_bond(w, 0, &a);
    floe_world_beam_bond(w, 3, &b);
    printf("  single bonds' tensile strengths: %.6g, %.6g Pa\n", a.sigma_lim, b.sigma_lim);
    CHECK(a.sigma_lim != b.sigma_lim, "single bonds draw different strengths (%g, %g)", a.sigma_lim, b.sigma_lim);
    floe_world_destroy(w);
}

int main(void) {
    test_defaults_and_refusals();
    test_linearisation(2, 0);
    test_linearisation(2, 1);
    test_linearisation(3, 0);
    test_linearisation(3, 1);
    test_cantilever_2d();
    test_cantilever_3d();
    test_breakage();
    test_exclusion_with_pd();
    test_ledger_and_errors();
    test_scene();
    return check_summary("test_beam");
}
