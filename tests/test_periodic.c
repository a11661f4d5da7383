/* test_periodic: the periodic cell (floe_cell.h, core/world/cell.c).
 *   1. A simple cubic lattice of frictionless spheres (linear springs kn, touching) in a
 *      periodic cell: a strain increment of -1e-7 gives sigma = C : eps with the lattice's
 *      elastic tensor C_aaaa = kn / s (every other component 0), and eq 29's tangent equals C,
 *      both within 1e-6 relative; a finite increment with shear gives the exact lattice
 *      stress (each bond's overlap from the deformed bond vector) within 1e-9.
 *   2. The same in 2D (square lattice, V = area x 1 m).
 *   3. A random packing: the contacts found through the images are exactly those of a
 *      brute-force search over every pair and every image; the stress servo holds an
 *      isotropic target within 1 %; the energy balance closes (the cell's work booked).
 *   4. Refused: a cell narrower than two diameters, a strain increment that inverts the
 *      cell, a wall in a cell. */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* n^dim spheres of radius r on a lattice of spacing s filling a cell of n s */
static floe_world *lattice(int dim, int n, double r, double s, double kn, double ks) {
    floe_world_def d = floe_default_world_def();
    d.dim = dim;
    d.dt = 1e-4;
    d.skin = 0.05 * r;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {.name = "m", .density = 1000, .young = 1e7, .poisson = 0.3};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_linear_law_create(kn, ks, 0, 0, 0));
    int g = floe_world_add_geometry(w, floe_sphere_create(r));
    int nz = dim == 3 ? n : 1;
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++)
            for (int c = 0; c < nz; c++) {
                floe_particle_def pd = floe_default_particle_def();
                pd.geometry = g;
                pd.material = mat;
                floe_v3_set(pd.x, (a + 0.5) * s, (b + 0.5) * s, dim == 3 ? (c + 0.5) * s : 0);
                floe_world_add_particle(w, &pd);
            }
    double H[9] = {n * s, 0, 0, 0, n * s, 0, 0, 0, dim == 3 ? n * s : 1};
    double o[3] = {0, 0, 0};
    CHECK(floe_world_set_cell(w, o, H) == FLOE_OK, "set_cell: %s", floe_world_last_error(w));
    floe_world_record_contacts(w, 1);
    return w;
}

/* the exact stress of the deformed lattice: per particle one bond along each cell vector,
 * l = F s e_a, overlap 2r - |l|, force on i -kn overlap l/|l| */
static void lattice_stress(int dim, int n, double r, double s, double kn, const double F[9], double sig[9]) {
    /* V = det(F) (n s)^dim (2D: times 1 m) */
    double V, det = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) + F[2] * (F[3] * F[7] - F[4] * F[6]);
    V = det * pow(n * s, dim);
    memset(sig, 0, 9 * sizeof(double));
    double np = pow(n, dim);
    for (int a = 0; a < dim; a++) {
        double l[3] = {F[a] * s, F[3 + a] * s, F[6 + a] * s};
        double len = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]), ov = 2 * r - len;
        if (ov <= 0) continue;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) sig[3 * i + j] += np * l[i] * (-kn * ov * l[j] / len) / V;
    }
}

static double max_abs(const double *a, int n) {
    double m = 0;
    for (int k = 0; k < n; k++) m = fmax(m, fabs(a[k]));
    return m;
}

static void lattice_case(int dim) {
    const int n = 4;
    const double r = 0.5, s = 1.0, kn = 1e4;
    floe_world *w = lattice(dim, n, r, s, kn, 0);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    /* 1a. small strain: linear elasticity of the lattice */
    const double e = -1e-7;
    double de[9] = {0};
    de[0] = e; de[4] = 0.5 * e; de[8] = dim == 3 ? 0.25 * e : 0;
    long steps = 0;
    CHECK(floe_world_cell_strain(w, de, 1e-3, NULL, &steps) == FLOE_OK, "strain: %s", floe_world_last_error(w));
    CHECK(steps == 1, "%dD: one step for |de| / max_rate below dt (got %ld)", dim, steps);
    double sig[9], D[81];
    CHECK(floe_world_cell_stress(w, sig, NULL) == FLOE_OK, "stress");
    char what[128];
    for (int a = 0; a < dim; a++) {
        snprintf(what, sizeof what, "%dD lattice sigma_%d%d = (kn/s) eps", dim, a, a);
        CHECK_NEAR(sig[4 * a], kn / s * de[4 * a], 1e-6, what);
    }
    CHECK(fabs(sig[1]) + fabs(sig[2]) + fabs(sig[5]) <= 1e-6 * fabs(sig[0]), "%dD: no shear stress", dim);
    CHECK(floe_world_tangent_contact(w, 0, D) == FLOE_OK, "tangent");
    double C[81] = {0};
    for (int a = 0; a < dim; a++) C[27 * a + 9 * a + 3 * a + a] = kn / s;
    double err = 0;
    for (int k = 0; k < 81; k++) err = fmax(err, fabs(D[k] - C[k]));
    snprintf(what, sizeof what, "%dD lattice: max |D_eq29 - C| / (kn/s)", dim);
    CHECK_NEAR(err / (kn / s) + 1, 1, 1e-6, what);
    double Vo[36];
    floe_tangent_to_voigt(D, Vo);
    CHECK_NEAR(Vo[0], kn / s, 1e-6, "Voigt D_11");
    /* the perturbation tangent (probes of 1e-9, one step each, no relaxation) is the lattice's
     * tangent too; the state is put back */
    {
        double Dp[81], sb[9], sa[9];
        long ps = 0, step0 = floe_world_step_count(w);
        floe_world_cell_stress(w, sb, NULL);
        CHECK(floe_world_tangent_perturb(w, 1e-9, 1e-3, 0, Dp, NULL, &ps) == FLOE_OK, "perturb: %s",
              floe_world_last_error(w));
        double ep = 0;
        for (int k = 0; k < 81; k++) ep = fmax(ep, fabs(Dp[k] - C[k]));
        snprintf(what, sizeof what, "%dD lattice: max |D_perturb - C| / (kn/s)", dim);
        CHECK_NEAR(ep / (kn / s) + 1, 1, 1e-5, what);
        CHECK(ps == (dim == 3 ? 7 : 4), "%dD: one step per probe and the reference (%ld)", dim, ps);
        floe_world_cell_stress(w, sa, NULL);
        CHECK(floe_world_step_count(w) == step0 && !memcmp(sa, sb, sizeof sa), "%dD: state restored after the probes",
              dim);
    }
    /* the RVE's measures: Z = 2 dim, fabric I / dim, porosity 1 - (sphere / cube) */
    floe_rve_measures me;
    CHECK(floe_world_cell_measures(w, &me) == FLOE_OK, "measures");
    snprintf(what, sizeof what, "%dD lattice coordination", dim);
    CHECK_NEAR(me.coordination, 2.0 * dim, 1e-12, what);
    snprintf(what, sizeof what, "%dD lattice fabric F_00", dim);
    CHECK_NEAR(me.fabric[0], 1.0 / dim, 1e-12, what);
    const double solid = dim == 3 ? 4.0 / 3.0 * M_PI * r * r * r / (s * s * s) : M_PI * r * r / (s * s);
    double vdef = (1 + de[0]) * (1 + de[4]) * (1 + de[8]);
    snprintf(what, sizeof what, "%dD lattice porosity", dim);
    CHECK_NEAR(me.porosity, 1 - solid / vdef, 1e-12, what);
    CHECK_NEAR(me.void_ratio, me.porosity / (1 - me.porosity), 1e-12, "void ratio = n / (1 - n)");
    /* 1b. a finite increment with shear: the exact lattice stress */
    double de2[9] = {0};
    de2[0] = -2e-3; de2[4] = -1e-3; de2[1] = 4e-4; de2[3] = 1e-4;
    if (dim == 3) { de2[8] = -1.5e-3; de2[2] = 2e-4; de2[7] = -3e-4; }
    CHECK(floe_world_cell_strain(w, de2, 0.5, NULL, &steps) == FLOE_OK, "strain 2: %s", floe_world_last_error(w));
    printf("  %dD finite increment in %ld steps\n", dim, steps);
    double H[9], o[3], F[9];
    floe_world_cell(w, o, H);
    for (int k = 0; k < 9; k++) F[k] = H[k] / (n * s);
    if (dim == 2) F[8] = 1;
    double ref[9];
    lattice_stress(dim, n, r, s, kn, F, ref);
    floe_world_cell_stress(w, sig, NULL);
    double sc = max_abs(ref, 9), e2 = 0;
    for (int k = 0; k < 9; k++) e2 = fmax(e2, fabs(0.5 * (sig[k] + sig[3 * (k % 3) + k / 3]) - 0.5 * (ref[k] + ref[3 * (k % 3) + k / 3])));
    snprintf(what, sizeof what, "%dD lattice with shear: max |sigma - exact| / |sigma|", dim);
    CHECK_NEAR(e2 / sc + 1, 1, 1e-9, what);
    /* the cell went exactly to (I + de) H0 */
    double Hx = (1 + de[0]) * (1 + de2[0]) * n * s;
    CHECK(fabs(H[0] - Hx) < 1e-9 * Hx, "%dD: H_xx = %.15g, expected ~%.15g", dim, H[0], Hx);
    floe_world_destroy(w);
}

/* a random packing of spheres in a cubic cell (seeded LCG) */
static double rnd(unsigned long long *s) {
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* global damping F = -c m v (a body force): the packing settles to rest */
static void drag(const floe_world *w, int i, double t, double f[3], double torque[3], void *user) {
    (void)t;
    floe_particle_state ps;
    floe_world_get_particle(w, i, &ps);
    const double c = *(const double *)user;
    for (int a = 0; a < 3; a++) {
        f[a] = -c * ps.mass * ps.v[a];
        torque[a] = 0;
    }
}

static void random_case(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.dt = 2e-4;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {.name = "m", .density = 1000, .young = 1e7, .poisson = 0.3};
    int mat = floe_world_add_material(w, &m);
    const double kn = 2e3;
    floe_world_set_law(w, mat, mat, floe_linear_law_create(kn, 0, 5.0, 0, 0));
    static double cdrag = 2.0;
    floe_world_set_body_force(w, drag, &cdrag);
    const double Lc = 6.0;
    unsigned long long seed = 7;
    int np = 0;
    double xs[3 * 400], rs[400];
    for (int t = 0; t < 200000 && np < 260; t++) {
        double r = 0.35 + 0.15 * rnd(&seed), x[3] = {Lc * rnd(&seed), Lc * rnd(&seed), Lc * rnd(&seed)};
        int ok = 1;
        for (int q = 0; q < np && ok; q++) {
            double dd[3];
            for (int a = 0; a < 3; a++) {
                dd[a] = x[a] - xs[3 * q + a];
                dd[a] -= Lc * round(dd[a] / Lc);
            }
            if (floe_v3_dot(dd, dd) < (r + rs[q]) * (r + rs[q]) * 0.9) ok = 0; /* slight overlaps allowed */
        }
        if (!ok) continue;
        memcpy(xs + 3 * np, x, sizeof x);
        rs[np++] = r;
    }
    for (int q = 0; q < np; q++) {
        floe_particle_def pd = floe_default_particle_def();
        pd.geometry = floe_world_add_geometry(w, floe_sphere_create(rs[q]));
        pd.material = mat;
        memcpy(pd.x, xs + 3 * q, sizeof pd.x);
        floe_world_add_particle(w, &pd);
    }
    double H[9] = {Lc, 0, 0, 0.3, Lc, 0, 0, 0, Lc}; /* a sheared cell */
    H[1] = 0.4;
    double o[3] = {0, 0, 0};
    CHECK(floe_world_set_cell(w, o, H) == FLOE_OK, "set_cell");
    floe_world_record_contacts(w, 1);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare random: %s", floe_world_last_error(w));
    /* servo: isotropic -200 Pa */
    floe_cell_control c = floe_default_cell_control();
    const double target = -200;
    for (int a = 0; a < 3; a++) {
        c.mode[4 * a] = FLOE_CELL_STRESS;
        c.stress[4 * a] = target;
    }
    c.max_rate = 0.5;
    CHECK(floe_world_cell_set_control(w, &c) == FLOE_OK, "control: %s", floe_world_last_error(w));
    int rc = FLOE_OK;
    for (int s = 0; s < 6000 && rc == FLOE_OK; s++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "servo run: %s", floe_world_last_error(w));
    double sig[9], avg[3] = {0, 0, 0};
    for (int s = 0; s < 500 && rc == FLOE_OK; s++) {
        rc = floe_world_step(w);
        floe_world_cell_stress(w, sig, NULL);
        for (int a = 0; a < 3; a++) avg[a] += sig[4 * a] / 500;
    }
    char what[96];
    for (int a = 0; a < 3; a++) {
        snprintf(what, sizeof what, "servo: mean sigma_%d%d over 500 steps", a, a);
        CHECK_NEAR(avg[a], target, 0.01, what);
    }
    /* contacts through the images = brute force over every pair and image */
    floe_world_cell(w, o, H);
    floe_particles_view v;
    floe_world_particles(w, &v);
    int brute = 0;
    for (int i = 0; i < v.n; i++)
        for (int j = i + 1; j < v.n; j++)
            for (int a = -2; a <= 2; a++)
                for (int b = -2; b <= 2; b++)
                    for (int e = -2; e <= 2; e++) {
                        double dd[3];
                        for (int r = 0; r < 3; r++)
                            dd[r] = v.x[3 * j + r] + H[3 * r] * a + H[3 * r + 1] * b + H[3 * r + 2] * e - v.x[3 * i + r];
                        double rr = v.radius[i] + v.radius[j];
                        brute += floe_v3_dot(dd, dd) < rr * rr;
                    }
    printf("  %d particles, %d contacts (brute force %d)\n", v.n, floe_world_contact_count(w), brute);
    CHECK(brute > v.n, "a packed sample (contacts %d)", brute);
    CHECK(floe_world_contact_count(w) == brute, "contacts through images %d = brute force %d",
          floe_world_contact_count(w), brute);
    /* eq 29 against the perturbation tangent on the random frictionless packing: probes of
     * 1e-6 in one step each, then one step with the cell fixed (the probe's dashpot forces
     * gone); what eq 29 leaves out (the contact forces turning with the branch, the particles'
     * non-affine motion over the two steps) is what separates them */
    {
        double De[81], Dp[81], Ve[36], Vp[36];
        floe_world_refresh_forces(w);
        CHECK(floe_world_tangent_contact(w, 0, De) == FLOE_OK, "eq 29 on the packing");
        long ps = 0;
        CHECK(floe_world_tangent_perturb(w, 1e-6, 1e-6 / d.dt, 1, Dp, NULL, &ps) == FLOE_OK, "perturb packing: %s",
              floe_world_last_error(w));
        /* the affine response of central linear springs, exactly to first order: with E the
         * probe's strain, l -> l + E l, f = kn (r_i + r_j - |l|), F_i = -f n, V -> V (1 + tr E):
         * d(l (x) F) = -f |l| (E n) (x) n + kn |l|^2 (n.E n) n (x) n - f |l| n (x) (E n - n (n.E n)),
         * d sigma = sym(sum d(l (x) F)) / V - sigma tr E. eq 29 keeps only the kn term. */
        const floe_contact_info *cs;
        int ncs = floe_world_contacts(w, &cs);
        double Vc = floe_world_cell_volume(w), s0[9], Va[36] = {0};
        floe_world_cell_stress(w, s0, NULL);
        static const int vi[6] = {0, 1, 2, 1, 0, 0}, vj[6] = {0, 1, 2, 2, 2, 1};
        for (int J = 0; J < 6; J++) {
            double E[9] = {0};
            if (vi[J] == vj[J]) E[4 * vi[J]] = 1;
            else E[3 * vi[J] + vj[J]] = E[3 * vj[J] + vi[J]] = 0.5;
            double dT[9] = {0};
            for (int q = 0; q < ncs; q++) {
                const double *nn = cs[q].n, *l = cs[q].branch, ll = sqrt(floe_v3_dot(l, l)), f = cs[q].fn;
                double En[3], nEn = 0;
                for (int a = 0; a < 3; a++) En[a] = E[3 * a] * nn[0] + E[3 * a + 1] * nn[1] + E[3 * a + 2] * nn[2];
                nEn = floe_v3_dot(nn, En);
                for (int a = 0; a < 3; a++)
                    for (int b = 0; b < 3; b++)
                        dT[3 * a + b] += -f * ll * En[a] * nn[b] + kn * ll * ll * nEn * nn[a] * nn[b] -
                                         f * ll * nn[a] * (En[b] - nn[b] * nEn);
            }
            const double trE = E[0] + E[4] + E[8];
            for (int I = 0; I < 6; I++) {
                int a = vi[I], b = vj[I];
                Va[6 * I + J] = 0.5 * (dT[3 * a + b] + dT[3 * b + a]) / Vc - s0[3 * a + b] * trE;
            }
        }
        floe_tangent_to_voigt(De, Ve);
        floe_tangent_to_voigt(Dp, Vp);
        double num = 0, den = 0, na = 0, da = 0;
        for (int k = 0; k < 36; k++) {
            num += (Vp[k] - Ve[k]) * (Vp[k] - Ve[k]);
            den += Ve[k] * Ve[k];
            na += (Vp[k] - Va[k]) * (Vp[k] - Va[k]);
            da += Va[k] * Va[k];
        }
        printf("  random packing (p = %.4g Pa): D_11 eq29 %.5g, perturbation %.5g, affine %.5g; D_44 %.5g, %.5g, %.5g\n",
               -(s0[0] + s0[4] + s0[8]) / 3, Ve[0], Vp[0], Va[0], Ve[21], Vp[21], Va[21]);
        printf("  |D_pert - D_eq29| / |D_eq29| = %.3g, |D_pert - D_affine| / |D_affine| = %.3g (%ld steps)\n",
               sqrt(num / den), sqrt(na / da), ps);
        CHECK(sqrt(na / da) < 1e-2, "frictionless packing: the perturbation tangent is the affine response within 1e-2 "
              "(Frobenius; measured 3.3e-3): %.3g", sqrt(na / da));
        /* eq 29 leaves out the terms of the order of the stress: -f|l| ... above (here p / D_11 ~ 0.13) */
        CHECK(sqrt(num / den) < 0.3, "frictionless packing: perturbation and eq 29 within 30 %% (Frobenius): %.3g",
              sqrt(num / den));
    }
    double be = floe_world_energy_balance_error(w);
    printf("  energy balance error %.3g\n", be);
    CHECK(be < 1e-3, "energy balance error %g < 1e-3 (the cell's work booked)", be);
    floe_world_destroy(w);
}

static void refusals(void) {
    /* a cell of 1.5 diameters */
    floe_world *w = lattice(3, 1, 0.5, 1.5, 1e3, 0);
    CHECK(floe_world_prepare(w) == FLOE_EINVAL && strstr(floe_world_last_error(w), "two particle diameters"),
          "narrow cell refused: %s", floe_world_last_error(w));
    floe_world_destroy(w);
    w = lattice(3, 4, 0.5, 1.0, 1e3, 0);
    double de[9] = {-1.5, 0, 0, 0, 0, 0, 0, 0, 0};
    CHECK(floe_world_cell_strain(w, de, 1, NULL, NULL) == FLOE_EINVAL && strstr(floe_world_last_error(w), "invert"),
          "inverting increment refused: %s", floe_world_last_error(w));
    double de2[9] = {-0.6, 0, 0, 0, 0, 0, 0, 0, 0};
    CHECK(floe_world_cell_strain(w, de2, 1, NULL, NULL) == FLOE_EINVAL &&
              strstr(floe_world_last_error(w), "two particle diameters"),
          "over-compressing increment refused: %s", floe_world_last_error(w));
    CHECK(floe_world_step_count(w) == 0, "nothing moved");
    double p[3] = {0, 0, 0}, nrm[3] = {0, 0, 1};
    floe_world_add_wall(w, p, nrm, 0, FLOE_FIXED);
    CHECK(floe_world_prepare(w) == FLOE_ENOTSUP && strstr(floe_world_last_error(w), "wall"),
          "wall in a cell refused: %s", floe_world_last_error(w));
    floe_world_destroy(w);
}

/* a checkpoint of a periodic world under the stress servo continues bit for bit */
static floe_world *servo_world(void) {
    floe_world *w = lattice(3, 4, 0.5, 0.97, 1e4, 5e3);
    floe_cell_control c = floe_default_cell_control();
    for (int a = 0; a < 3; a++) {
        c.mode[4 * a] = FLOE_CELL_STRESS;
        c.stress[4 * a] = -50.0 * (a + 1);
    }
    c.mode[1] = FLOE_CELL_RATE;
    c.rate[1] = 0.02; /* and a shear rate */
    c.max_rate = 0.1;
    floe_world_cell_set_control(w, &c);
    return w;
}
static void checkpoint_case(void) {
    const char *path = "/tmp/floe_test_periodic.ckpt";
    floe_world *a = servo_world(), *b = servo_world();
    int rc = FLOE_OK;
    for (int k = 0; k < 300 && rc == FLOE_OK; k++) rc = floe_world_step(a);
    for (int k = 0; k < 120 && rc == FLOE_OK; k++) rc = floe_world_step(b);
    char err[512] = "";
    CHECK(rc == FLOE_OK && floe_world_checkpoint_save(b, path, 42, "periodic", err, sizeof err) == FLOE_OK,
          "periodic checkpoint save: %s %s", err, floe_world_last_error(b));
    floe_world_destroy(b);
    b = servo_world();
    CHECK(floe_world_checkpoint_load(b, path, 42, "periodic", err, sizeof err) == FLOE_OK, "load: %s", err);
    for (int k = 120; k < 300 && rc == FLOE_OK; k++) rc = floe_world_step(b);
    CHECK(rc == FLOE_OK, "continued run: %s", floe_world_last_error(b));
    floe_particles_view va, vb;
    floe_world_particles(a, &va);
    floe_world_particles(b, &vb);
    double Ha[9], Hb[9];
    floe_world_cell(a, NULL, Ha);
    floe_world_cell(b, NULL, Hb);
    CHECK(!memcmp(va.x, vb.x, 3 * sizeof(double) * va.n) && !memcmp(va.v, vb.v, 3 * sizeof(double) * va.n) &&
              !memcmp(Ha, Hb, sizeof Ha),
          "periodic restart: positions, velocities and cell equal bit for bit");
    printf("  periodic restart after 120 of 300 steps: H_xx %.17g, H_xy %.17g (both runs)\n", Hb[0], Hb[1]);
    floe_world_destroy(a);
    floe_world_destroy(b);
    remove(path);
}

int main(void) {
    lattice_case(3);
    lattice_case(2);
    random_case();
    refusals();
    checkpoint_case();
    return check_summary("test_periodic");
}
