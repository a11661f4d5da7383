/* test_pd_periodic.c - PD bodies across the faces of a periodic cell (docs/periodic.md): a
 * cubic lattice of N^3 points whose spacing tiles the cell bonds through the images, so it is
 * an infinite body: under a homogeneous strain of the cell every point's force is zero to
 * round-off (the same body without a cell feels its free surfaces), the cell's stress is the
 * bonds' virial and equals the lattice sum of the full family (PMB) and the exact LPS stress
 * of an isotropic stretch; every point has the full family; a critical stretch breaks the
 * bonds across the faces as the interior ones; a run continues bit for bit from a state. */
#include "check.h"
#include "floe.h"
#include "floe_checkpoint.h"
#include "floe_pd.h"
#include "world_read.h"

#include <stdlib.h>
#include <string.h>

enum { N = 8 };            /* points per side; the cell is N dx, the horizon 3 dx */
static const double DX = 1e-3, RHO = 2000, KB = 1e9, GB = 0.6e9;

static floe_pd_body *cube(int model, double s_c, int corr) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = DX;
    r.horizon_factor = 3;
    floe_v3_set(r.lo, 0, 0, 0);
    floe_v3_set(r.hi, N * DX, N * DX, N * DX);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) return NULL;
    floe_pd_material m = model == FLOE_PD_LPS ? floe_pd_material_lps(RHO, KB, GB, s_c, FLOE_PD_W_ONE)
                                              : floe_pd_material_pmb(RHO, KB, s_c);
    if (floe_pd_set_material(b, &m) || (corr && floe_pd_surface_correction(b))) {
        floe_pd_body_destroy(b);
        return NULL;
    }
    return b;
}

/* a world with the body in the cell [0, N dx)^3; cell_first: the cell set before the body */
static floe_world *world_with(floe_pd_body *b, int cell_first) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    floe_v3_set(d.gravity, 0, 0, 0);
    d.dt = 0.5 * floe_pd_dt_nodal(b);
    d.skin = 0.05 * DX;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {.name = "m", .density = RHO, .young = 1e9, .poisson = 0.25};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_linear_law_create(1e4, 0, 0, 0, 0));
    double H[9] = {N * DX, 0, 0, 0, N * DX, 0, 0, 0, N * DX}, o[3] = {0, 0, 0};
    if (cell_first) CHECK(floe_world_set_cell(w, o, H) == FLOE_OK, "set_cell: %s", floe_world_last_error(w));
    CHECK(floe_world_add_pd_body(w, b, mat, NULL, NULL) == FLOE_OK, "add PD body: %s", floe_world_last_error(w));
    if (!cell_first) CHECK(floe_world_set_cell(w, o, H) == FLOE_OK, "set_cell: %s", floe_world_last_error(w));
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    return w;
}

/* the lattice offsets o (integers) of the full family, |o| dx <= delta + 1e-9 dx */
static int family(int off[][3], int cap) {
    int n = 0;
    for (int a = -3; a <= 3; a++)
        for (int b = -3; b <= 3; b++)
            for (int c = -3; c <= 3; c++) {
                if ((!a && !b && !c) || sqrt((double)(a * a + b * b + c * c)) * DX > 3 * DX + 1e-9 * DX) continue;
                if (n < cap) { off[n][0] = a; off[n][1] = b; off[n][2] = c; }
                n++;
            }
    return n;
}

/* the partial-volume factor of pd.c (stored as a float) */
static double beta_of(double L) {
    double d = 3 * DX, be = L > d - 0.5 * DX ? (d + 0.5 * DX - L) / DX : 1.0;
    return (double)(float)fmin(1.0, fmax(0.0, be));
}

/* PMB: the stress of the infinite lattice under x = F X, from the lattice offsets alone:
 * sigma = 1/(2 V_i det F) sum_o l (x) f, l = F xi, f = c s beta V_i^2 l/|l| */
static void pmb_lattice_stress(double c, const double F[9], double sig[9]) {
    int off[200][3], nf = family(off, 200);
    double V = DX * DX * DX, det = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                                   F[2] * (F[3] * F[7] - F[4] * F[6]);
    memset(sig, 0, 9 * sizeof(double));
    for (int q = 0; q < nf; q++) {
        double xi[3] = {off[q][0] * DX, off[q][1] * DX, off[q][2] * DX}, l[3];
        for (int a = 0; a < 3; a++) l[a] = F[3 * a] * xi[0] + F[3 * a + 1] * xi[1] + F[3 * a + 2] * xi[2];
        double L = floe_v3_norm(xi), r = floe_v3_norm(l), s = (r - L) / L;
        double fm = c * s * beta_of(L) * V * V / r;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) sig[3 * a + b] += l[a] * fm * l[b] / (2 * V * det);
    }
}

/* the largest |force| of the body's points at the world's positions (no breakage) */
static double max_point_force(floe_pd_body *b, const double *x) {
    double *f = calloc(3 * (size_t)b->n, sizeof *f), m = 0;
    floe_pd_forces_nobreak(b, x, f);
    for (int i = 0; i < 3 * b->n; i++) m = fmax(m, fabs(f[i]));
    free(f);
    return m;
}

/* the cell's deformation gradient H H0^-1 (H0 = N dx I) */
static void cell_F(const floe_world *w, double F[9]) {
    double H[9];
    floe_world_cell(w, NULL, H);
    for (int k = 0; k < 9; k++) F[k] = H[k] / (N * DX);
}

/* (a) PMB: uniaxial strain of the cell; zero point forces, stress = lattice sum; with the
 * surface correction the continuum C_11 = 1.8 K */
static void test_pmb_infinite(int corr) {
    floe_pd_body *b = cube(FLOE_PD_PMB, 0, corr);
    CHECK(b != NULL, "body");
    floe_world *w = world_with(b, 1);
    const double eps = 1e-6;
    double de[9] = {eps, 0, 0, 0, 0, 0, 0, 0, 0};
    long steps = 0;
    CHECK(floe_world_cell_strain(w, de, eps / (10 * floe_world_dt(w)), NULL, &steps) == FLOE_OK, "strain: %s",
          floe_world_last_error(w));
    double F[9], sig[9], ref[9];
    cell_F(w, F);
    const double *x = pview(w).x; /* the body is the world's only particles */
    double fcell = max_point_force(b, x);
    /* the same body without a cell, under the same x = F X */
    floe_pd_body *free_b = cube(FLOE_PD_PMB, 0, corr);
    double *xf = malloc(3 * (size_t)b->n * sizeof *xf);
    for (int i = 0; i < b->n; i++)
        for (int a = 0; a < 3; a++)
            xf[3 * i + a] = F[3 * a] * b->X[3 * i] + F[3 * a + 1] * b->X[3 * i + 1] + F[3 * a + 2] * b->X[3 * i + 2];
    double fmax_free = max_point_force(free_b, xf);
    printf("  PMB%s, eps_xx %.0e in %ld steps: %d points, %lld bonds; max |f| %.3e N in the cell, %.3e N "
           "without it (free surfaces)\n", corr ? " (surface correction)" : "", eps, steps, b->n, (long long)b->nbond,
           fcell, fmax_free);
    /* round-off: positions of ~8e-3 m carry 1.7e-18 m ulps, 1e-9 of the bonds' stretch (1e-9 m) */
    CHECK(fcell < 1e-7 * fmax_free, "no surface effect in the cell: max |f| %.3e vs %.3e without the cell", fcell,
          fmax_free);
    CHECK(floe_world_cell_stress(w, sig, NULL) == FLOE_OK, "cell stress");
    if (!corr) {
        pmb_lattice_stress(b->c, F, ref);
        CHECK_NEAR(sig[0], ref[0], 1e-7, "PMB sigma_xx = the lattice sum");
        CHECK_NEAR(sig[4], ref[4], 1e-7, "PMB sigma_yy = the lattice sum");
        CHECK_NEAR(sig[8], ref[8], 1e-7, "PMB sigma_zz = the lattice sum");
        double off = fmax(fabs(sig[1]), fmax(fabs(sig[2]), fabs(sig[5])));
        CHECK(off < 1e-9 * sig[0], "no shear stress (%.3e of sigma_xx)", off / sig[0]);
        printf("  lattice sum vs continuum: sigma_xx / (1.8 K eps) = %.5f, sigma_yy / (0.6 K eps) = %.5f\n",
               sig[0] / (1.8 * KB * eps), sig[4] / (0.6 * KB * eps));
        /* the lattice sum of a 3 dx family with linear partial volumes is below the continuum
         * (the discretisation error the surface correction calibrates away, below) */
        CHECK(sig[0] < 1.8 * KB * eps && sig[0] > 0.8 * 1.8 * KB * eps, "the lattice sum within 20 %% below the "
              "continuum C_11");
    } else {
        /* the correction calibrates the uniaxial energy of every point to the continuum: C_11
         * exactly, up to the float factors (6e-8) and the stretch's nonlinearity (eps/2) */
        CHECK_NEAR(sig[0], 1.8 * KB * eps, 1e-5, "PMB corrected sigma_xx = 1.8 K eps");
        printf("  corrected: sigma_yy / (0.6 K eps) = %.5f (the cubic lattice's anisotropy)\n", sig[4] / (0.6 * KB * eps));
    }
    /* the energy ledger: the cell's work on the bonds is booked */
    double eb = floe_world_energy_balance_error(w);
    floe_energy e = floe_world_energy(w);
    printf("  elastic %.4e J, cell work %.4e J, balance error %.2e\n", e.elastic, e.work_boundary, eb);
    CHECK(fabs(eb) < 1e-6, "energy balance with the cell's work on the bonds (%.2e)", eb);
    CHECK(fabs(e.work_boundary - e.elastic) < 1e-3 * e.elastic, "the cell's work is the stored energy");
    free(xf);
    floe_pd_body_destroy(free_b);
    floe_world_destroy(w);
}

/* (a) LPS: isotropic stretch (1 + eps); theta = 3 eps exactly, sigma = 3 K eps / (1 + eps)^2 */
static void test_lps_isotropic(void) {
    floe_pd_body *b = cube(FLOE_PD_LPS, 0, 0);
    CHECK(b != NULL, "LPS body");
    floe_world *w = world_with(b, 0); /* this time the cell after the body */
    const double eps = 1e-6;
    double de[9] = {eps, 0, 0, 0, eps, 0, 0, 0, eps};
    long steps = 0;
    CHECK(floe_world_cell_strain(w, de, eps / (10 * floe_world_dt(w)), NULL, &steps) == FLOE_OK, "strain: %s",
          floe_world_last_error(w));
    double F[9], sig[9];
    cell_F(w, F);
    double fcell = max_point_force(b, pview(w).x);
    double bond = KB * eps * DX * DX; /* a point's force scale: K eps on a face dx^2 */
    printf("  LPS isotropic eps %.0e in %ld steps: max |f| %.3e N (K eps dx^2 = %.3e N)\n", eps, steps, fcell, bond);
    CHECK(fcell < 1e-7 * bond, "no surface effect in the cell (LPS)");
    CHECK(floe_world_cell_stress(w, sig, NULL) == FLOE_OK, "cell stress");
    double lam = F[0], ex = 3 * KB * (lam - 1) / (lam * lam);
    CHECK_NEAR(sig[0], ex, 1e-7, "LPS sigma_xx = 3 K eps / (1 + eps)^2");
    CHECK_NEAR(sig[4], ex, 1e-7, "LPS sigma_yy");
    CHECK_NEAR(sig[8], ex, 1e-7, "LPS sigma_zz");
    floe_world_destroy(w);
}

/* (b) the full family at every point with the cell, fewer at the faces without */
static void test_families(void) {
    int off[200][3], nf = family(off, 200);
    floe_pd_body *b0 = cube(FLOE_PD_PMB, 0, 0), *b = cube(FLOE_PD_PMB, 0, 0);
    CHECK(b0 && b, "bodies");
    int *c0 = malloc((size_t)b->n * sizeof *c0), *c1 = malloc((size_t)b->n * sizeof *c1);
    floe_pd_family_sizes(b0, c0);
    floe_world *w = world_with(b, 1);
    floe_pd_family_sizes(b, c1);
    int mn0 = nf, mx0 = 0, mn1 = nf, mx1 = 0;
    for (int i = 0; i < b->n; i++) {
        mn0 = c0[i] < mn0 ? c0[i] : mn0; mx0 = c0[i] > mx0 ? c0[i] : mx0;
        mn1 = c1[i] < mn1 ? c1[i] : mn1; mx1 = c1[i] > mx1 ? c1[i] : mx1;
    }
    long long across = 0;
    for (int64_t k = 0; k < b->nbond; k++) across += b->img && b->img[k];
    printf("  families: full %d; with the cell %d..%d (%lld bonds, %lld across the faces), without %d..%d (%lld bonds)\n",
           nf, mn1, mx1, (long long)b->nbond, across, mn0, mx0, (long long)b0->nbond);
    CHECK(mn1 == nf && mx1 == nf, "every point has the full family in the cell (%d..%d of %d)", mn1, mx1, nf);
    CHECK(b->nbond == (int64_t)b->n * nf / 2, "bonds = n x family / 2");
    CHECK(mx0 == nf && mn0 < nf, "without the cell the face points have fewer (%d < %d)", mn0, nf);
    CHECK(across == b->nbond - b0->nbond, "the bonds added are the ones across the faces (%lld)", across);
    free(c0); free(c1);
    floe_pd_body_destroy(b0);
    floe_world_destroy(w);
}

/* (c) damage across the faces: s_c = 1e-3, uniaxial eps_xx = 2.5e-3 in one step breaks the
 * bonds with n_x^2 > ~0.4 (between the offsets' 1/3 and 4/9), the same at every point. (In
 * one step: over a ramp the first bonds to break do so where round-off puts them over s_c
 * first, and the damage localises - the instability of a softening solid.) */
static void test_damage(void) {
    const double s_c = 1e-3, eps = 2.5e-3;
    floe_pd_body *b = cube(FLOE_PD_PMB, s_c, 0);
    CHECK(b != NULL, "body");
    floe_world *w = world_with(b, 1);
    double de[9] = {eps, 0, 0, 0, 0, 0, 0, 0, 0};
    long steps = 0;
    CHECK(floe_world_cell_strain(w, de, 2 * eps / floe_world_dt(w), NULL, &steps) == FLOE_OK && steps == 1,
          "strain in one step: %s", floe_world_last_error(w));
    /* the offsets whose stretch at the end exceeds s_c */
    int off[200][3], nf = family(off, 200), nbrk = 0;
    for (int q = 0; q < nf; q++) {
        double L = DX * sqrt((double)(off[q][0] * off[q][0] + off[q][1] * off[q][1] + off[q][2] * off[q][2]));
        double lx = (1 + eps) * off[q][0] * DX, r = sqrt(lx * lx + (off[q][1] * off[q][1] + off[q][2] * off[q][2]) * DX * DX);
        nbrk += (r - L) / L > s_c;
    }
    long long brk_in = 0, brk_across = 0, across = 0;
    for (int64_t k = 0; k < b->nbond; k++) {
        int im = b->img && b->img[k];
        across += im;
        if (b->broken[k]) { if (im) brk_across++; else brk_in++; }
    }
    double *phi = malloc((size_t)b->n * sizeof *phi), pmn = 1, pmx = 0;
    floe_pd_damage(b, phi);
    for (int i = 0; i < b->n; i++) { pmn = fmin(pmn, phi[i]); pmx = fmax(pmx, phi[i]); }
    printf("  damage: %d of %d offsets over s_c; broken %lld interior + %lld across the faces (of %lld) = %lld, "
           "expected %lld; damage %.6f..%.6f\n", nbrk, nf, brk_in, brk_across, across, brk_in + brk_across,
           (long long)b->n * nbrk / 2, pmn, pmx);
    CHECK(brk_in + brk_across == (long long)b->n * nbrk / 2, "every bond over s_c broken, and no other");
    CHECK(brk_across > 0 && brk_in > 0, "bonds across the faces break as the interior ones");
    CHECK(pmx - pmn < 1e-12 && pmn > 0, "the same damage at every point (%.3g..%.3g)", pmn, pmx);
    free(phi);
    floe_world_destroy(w);
}

/* a periodic PD run under a strain rate with a velocity perturbation continues bit for bit
 * from a saved state in a fresh world (its families rebuilt in the cell) */
static floe_world *perturbed(void) {
    floe_pd_body *b = cube(FLOE_PD_LPS, 0, 0);
    floe_world *w = world_with(b, 1);
    for (int i = 0; i < b->n; i++) set_vel(w, i, i % 3, 1e-3 * sin(1.0 + i));
    floe_cell_control c = floe_default_cell_control();
    c.rate[0] = 20.0;
    c.rate[1] = 5.0; /* xy shear */
    CHECK(floe_world_cell_set_control(w, &c) == FLOE_OK, "control: %s", floe_world_last_error(w));
    return w;
}
static void test_restart(void) {
    floe_world *w = perturbed();
    int rc = 0;
    for (int s = 0; s < 20 && !rc; s++) rc = floe_world_step(w);
    size_t n = floe_world_state_size(w);
    unsigned char *buf = malloc(n);
    char err[256];
    CHECK(rc == FLOE_OK && floe_world_state_save(w, buf, n, err, sizeof err) == FLOE_OK, "save: %s", err);
    for (int s = 0; s < 30 && !rc; s++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "run: %s", floe_world_last_error(w));
    int np = pview(w).n;
    double *xa = malloc(3 * (size_t)np * sizeof *xa), sa[9], sb[9];
    memcpy(xa, pview(w).x, 3 * (size_t)np * sizeof *xa);
    floe_world_cell_stress(w, sa, NULL);
    floe_world *w2 = perturbed();
    CHECK(floe_world_state_restore(w2, buf, n, err, sizeof err) == FLOE_OK, "restore: %s", err);
    for (int s = 0; s < 30 && !rc; s++) rc = floe_world_step(w2);
    CHECK(rc == FLOE_OK, "run after restore: %s", floe_world_last_error(w2));
    floe_world_cell_stress(w2, sb, NULL);
    int same = !memcmp(xa, pview(w2).x, 3 * (size_t)np * sizeof *xa) && !memcmp(sa, sb, sizeof sa);
    printf("  restart: 20 + 30 steps, sigma_xx %.6e Pa, bit for bit: %s\n", sa[0], same ? "yes" : "no");
    CHECK(same, "a periodic PD run continues bit for bit from a state");
    CHECK(sa[0] != 0, "the run stressed the body");
    free(xa); free(buf);
    floe_world_destroy(w);
    floe_world_destroy(w2);
}

/* the stress servo on a PD body: sigma_xx held at 1 kPa through the bonds' virial, with the
 * bonds' axial stiffness in the servo's D_xxxx (exact for PMB: a first-order relaxation of
 * time tau = 50 steps, so 10 tau leave e^-10 of the error) */
static void test_servo(void) {
    floe_pd_body *b = cube(FLOE_PD_PMB, 0, 0);
    floe_world *w = world_with(b, 1);
    floe_cell_control c = floe_default_cell_control();
    c.mode[0] = FLOE_CELL_STRESS;
    c.stress[0] = 1e3;
    c.max_rate = 1.0;
    CHECK(floe_world_cell_set_control(w, &c) == FLOE_OK, "control: %s", floe_world_last_error(w));
    int rc = 0;
    for (int s = 0; s < 500 && !rc; s++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "servo run: %s", floe_world_last_error(w));
    double sig[9];
    floe_world_cell_stress(w, sig, NULL);
    printf("  servo: sigma_xx %.6f Pa after 500 steps (target 1000), balance error %.2e\n", sig[0],
           floe_world_energy_balance_error(w));
    CHECK_NEAR(sig[0], 1e3, 1e-4, "servo holds sigma_xx on a PD body (measured 7.4e-6)");
    CHECK(fabs(floe_world_energy_balance_error(w)) < 1e-6, "energy balance with the servo's work (%.2e)",
          floe_world_energy_balance_error(w));
    floe_world_destroy(w);
}

/* refused: a cell narrower than two horizons */
static void test_refused(void) {
    floe_pd_body *b = cube(FLOE_PD_PMB, 0, 0);
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.dt = 1e-8;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {.name = "m", .density = RHO, .young = 1e9, .poisson = 0.25};
    int mat = floe_world_add_material(w, &m);
    double H[9] = {5 * DX, 0, 0, 0, N * DX, 0, 0, 0, N * DX}, o[3] = {0, 0, 0};
    CHECK(floe_world_set_cell(w, o, H) == FLOE_OK, "set_cell");
    int rc = floe_world_add_pd_body(w, b, mat, NULL, NULL);
    printf("  refused: %s\n", floe_world_last_error(w));
    CHECK(rc == FLOE_EINVAL && strstr(floe_world_last_error(w), "two horizons"), "a cell of 5 dx < 2 delta refused");
    floe_world_destroy(w);
}

/* points on both of two opposite faces lie on one spot through the images: refused (they
 * would bond at zero length) */
static void test_coincident(void) {
    int n = 0;
    double X[3 * 2 * N * N], V[2 * N * N];
    for (int a = 0; a < N; a++)
        for (int c = 0; c < N; c++)
            for (int side = 0; side < 2; side++) {
                floe_v3_set(X + 3 * n, side ? N * DX : 0.0, (a + 0.5) * DX, (c + 0.5) * DX);
                V[n++] = DX * DX * DX;
            }
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create_points(&b, 3, n, X, V, 3 * DX, DX, 0) == FLOE_OK, "points body");
    floe_pd_material m = floe_pd_material_pmb(RHO, KB, 0);
    CHECK(b && floe_pd_set_material(b, &m) == FLOE_OK, "material");
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.dt = 1e-8;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material mm = {.name = "m", .density = RHO, .young = 1e9, .poisson = 0.25};
    int mat = floe_world_add_material(w, &mm);
    double H[9] = {N * DX, 0, 0, 0, N * DX, 0, 0, 0, N * DX}, o[3] = {0, 0, 0};
    CHECK(floe_world_set_cell(w, o, H) == FLOE_OK, "set_cell");
    int rc = floe_world_add_pd_body(w, b, mat, NULL, NULL);
    printf("  refused: %s\n", floe_world_last_error(w));
    CHECK(rc == FLOE_EINVAL && strstr(floe_world_last_error(w), "one spot"),
          "points on opposite faces (one spot through the images) refused");
    floe_world_destroy(w);
}

/* a crack cut along a cell face after the families were found through the images: the
 * faces it leaves (1 dx apart through the image, their contact spheres overlapping in the
 * reference configuration) are kept out of the contact list like a fresh crack's inside the
 * body, so the body at rest feels no force */
static void test_crack_across_face(void) {
    floe_pd_body *b = cube(FLOE_PD_PMB, 0, 0);
    CHECK(b != NULL, "body");
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    floe_v3_set(d.gravity, 0, 0, 0);
    d.dt = 0.5 * floe_pd_dt_nodal(b);
    d.skin = 0.05 * DX;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {.name = "m", .density = RHO, .young = 1e9, .poisson = 0.25};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_linear_law_create(1e4, 0, 0, 0, 0));
    double H[9] = {N * DX, 0, 0, 0, N * DX, 0, 0, 0, N * DX}, o[3] = {0, 0, 0};
    CHECK(floe_world_set_cell(w, o, H) == FLOE_OK, "set_cell: %s", floe_world_last_error(w));
    CHECK(floe_world_add_pd_body(w, b, mat, NULL, NULL) == FLOE_OK, "add PD body: %s", floe_world_last_error(w));
    /* the families go through the images now; cut along the face x = 0 before the first prepare */
    double corner[3] = {0, -DX, -DX}, e1[3] = {0, (N + 2) * DX, 0}, e2[3] = {0, 0, (N + 2) * DX};
    floe_pd_crack c = floe_pd_crack_rectangle(corner, e1, e2);
    int64_t cut = floe_pd_add_crack(b, &c);
    CHECK(cut > 0, "the crack at x = 0 cuts the bonds across that face (%lld)", (long long)cut);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    CHECK(floe_world_step(w) == FLOE_OK, "step: %s", floe_world_last_error(w));
    floe_particles_view v;
    floe_world_particles(w, &v);
    double fmax = 0;
    for (int i = 0; i < v.n; i++) fmax = fmax > floe_v3_norm(v.f + 3 * i) ? fmax : floe_v3_norm(v.f + 3 * i);
    printf("  crack along a face: %lld bonds cut, largest force at rest %.3e N\n", (long long)cut, fmax);
    CHECK(fmax < 1e-9, "no contact across the crack's faces through the image (largest force %.3e N)", fmax);
    floe_world_destroy(w);
}

int main(void) {
    test_families();
    test_pmb_infinite(0);
    test_pmb_infinite(1);
    test_lps_isotropic();
    test_damage();
    test_restart();
    test_servo();
    test_refused();
    test_coincident();
    test_crack_across_face();
    return check_summary("test_pd_periodic");
}
