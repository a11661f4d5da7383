/* test_pd_lps.c - accuracy of the linear peridynamic solid (LPS) at free surfaces and in 2D
 * (peridynamics/pd_materials.c, floe_pd_lps_surface_correction; docs/models.md, "LPS
 * surface correction" and "2D LPS").
 *
 * 1. Clamped bar under an end load, static: a bar nx x ny x ny (delta = 3 dx, so nearly
 *    every point is within a horizon of a free surface), its first three layers fixed, a body
 *    force density b on its last three layers (total F). Static equilibrium by conjugate
 *    gradients on the linearised stiffness (matrix-free, K v = -f(X + a v)/a at a tiny a).
 *    The strain between the cross-sections at L/4 and 3L/4 (mean u_x of each) gives
 *    E_eff = F/(A eps), A = ny^2 dx^2, to compare with E; nu from the lateral slope. With the
 *    correction E_eff is within 5 % of E at nu = 0.3 and 0.45 (the plain LPS is 7-9 % too
 *    stiff, the previous alpha-only calibration 16-19 %; both printed).
 * 2. The same in 2D (a strip nx x ny, plane stress and plane strain): E_eff against the
 *    in-plane modulus (plane stress E, plane strain E/(1 - nu^2)) and the in-plane Poisson
 *    ratio (nu, nu/(1 - nu)), within 5 %.
 * 3. Forces = -grad energy (central differences) with the correction on, in 3D and 2D, also
 *    with some bonds broken (the q_i term of the force state).
 * 4. Energy conservation under velocity Verlet, no breakage, correction on, 3D and 2D.
 * 5. The nodal time-step estimate (floe_pd_dt_nodal, with the equivalent PMB micromodulus of
 *    the 2D LPS) is below the true stability limit 2/omega_max of velocity Verlet (power
 *    iteration on the linearised forces), with and without the correction, 3D and 2D.
 * 6. A single layer of a 3D lattice (examples/plate-with-hole): its families do not span
 *    z, so the correction keeps the plain dilatation there: finite forces, and the energy of
 *    a uniform in-plane isotropic stretch eps equals the plain LPS's (exact, the plain
 *    dilatation is exact for it) within 1e-9. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "floe_pd.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double urand(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

static floe_pd_body *make_box(int dim, double dx, int nx, int ny, int nz)
{
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = dim;
    r.dx = dx;
    r.horizon_factor = 3;
    r.thickness = dx;
    r.hi[0] = nx * dx;
    r.hi[1] = ny * dx;
    r.hi[2] = nz * dx;
    floe_pd_body *b = NULL;
    int rc = floe_pd_body_create(&b, &r);
    CHECK(rc == FLOE_OK && b, "body create: %s", floe_strerror(rc));
    return b;
}

static floe_pd_material lps_mat(double E, double nu, int infl, int plane)
{
    floe_pd_material m = floe_pd_material_lps(1000, E / (3 * (1 - 2 * nu)), E / (2 * (1 + nu)), 0, infl);
    m.plane = plane;
    return m;
}

/* K v = -f(X + a v)/a on the free dofs (the forces vanish at X) */
static void kmul(floe_pd_body *b, double *xs, double *fs, const double *v, double *out, const unsigned char *fix)
{
    int n3 = 3 * b->n;
    double mx = 0;
    for (int i = 0; i < n3; i++) mx = fmax(mx, fabs(v[i]));
    if (mx == 0) { memset(out, 0, n3 * sizeof *out); return; }
    double a = 1e-7 * b->dx / mx;
    for (int i = 0; i < n3; i++) xs[i] = b->X[i] + a * v[i];
    memset(fs, 0, n3 * sizeof *fs);
    floe_pd_forces_nobreak(b, xs, fs);
    for (int i = 0; i < n3; i++) out[i] = fix[i] ? 0 : -fs[i] / a;
}

/* 1, 2: static clamped bar (3D: ny x ny section; 2D: strip of width ny); returns E_eff/E_ref
 * and the measured Poisson ratio in *nu_out */
static double bar_static(int dim, int nx, int ny, const floe_pd_material *m, int corr, double *nu_out)
{
    const double dx = 1e-3, bx = 1e6;
    floe_pd_body *b = make_box(dim, dx, nx, ny, dim == 3 ? ny : 1);
    if (!b) return NAN;
    CHECK(floe_pd_set_material(b, m) == FLOE_OK, "set LPS material (%dD)", dim);
    if (corr) CHECK(floe_pd_surface_correction(b) == FLOE_OK, "LPS surface correction (%dD)", dim);
    int n3 = 3 * b->n;
    double *xs = malloc(n3 * sizeof *xs), *fs = malloc(n3 * sizeof *fs), *u = calloc(n3, sizeof *u);
    double *r = calloc(n3, sizeof *r), *p = malloc(n3 * sizeof *p), *Ap = malloc(n3 * sizeof *Ap);
    unsigned char *fix = calloc(n3, 1);
    const double L = nx * dx;
    double F = 0;
    for (int i = 0; i < b->n; i++) {
        double X = b->X[3 * i];
        if (X < 3 * dx) fix[3 * i] = fix[3 * i + 1] = fix[3 * i + 2] = 1;
        if (X > L - 3 * dx) { r[3 * i] = bx * b->V[i]; F += bx * b->V[i]; }
        if (dim == 2) fix[3 * i + 2] = 1;
    }
    memcpy(p, r, n3 * sizeof *p);
    double rs = 0;
    for (int i = 0; i < n3; i++) rs += r[i] * r[i];
    double rs0 = rs;
    int it;
    for (it = 0; it < 5000 && rs > 1e-20 * rs0; it++) {
        kmul(b, xs, fs, p, Ap, fix);
        double pAp = 0, rn = 0;
        for (int i = 0; i < n3; i++) pAp += p[i] * Ap[i];
        double al = rs / pAp;
        for (int i = 0; i < n3; i++) {
            u[i] += al * p[i];
            r[i] -= al * Ap[i];
            rn += r[i] * r[i];
        }
        for (int i = 0; i < n3; i++) p[i] = r[i] + rn / rs * p[i];
        rs = rn;
    }
    CHECK(rs <= 1e-20 * rs0, "CG converged (%d iterations)", it);
    /* axial strain between the sections at L/4 and 3L/4, lateral slope over the middle half */
    double xa = floor(0.25 * nx) * dx + 0.5 * dx, xb = floor(0.75 * nx) * dx + 0.5 * dx;
    double ua = 0, ub = 0, sy = 0, syy = 0, suy = 0, su = 0;
    int na = 0, nb = 0, cn = 0;
    const double yc = 0.5 * ny * dx;
    for (int i = 0; i < b->n; i++) {
        const double *X = b->X + 3 * i;
        if (fabs(X[0] - xa) < 0.25 * dx) { ua += u[3 * i]; na++; }
        if (fabs(X[0] - xb) < 0.25 * dx) { ub += u[3 * i]; nb++; }
        if (fabs(X[0] - 0.5 * L) > 0.25 * L) continue;
        for (int d = 1; d < dim; d++) {
            double ay = X[d] - yc;
            sy += ay; syy += ay * ay; suy += ay * u[3 * i + d]; su += u[3 * i + d];
            cn++;
        }
    }
    double ex = (ub / nb - ua / na) / (xb - xa);
    double ey = (suy - sy * su / cn) / (syy - sy * sy / cn);
    double A = dim == 3 ? ny * ny * dx * dx : ny * dx * b->thickness;
    /* reference in-plane moduli: 3D and plane stress E, nu; plane strain E/(1 - nu^2), nu/(1 - nu) */
    double E = m->E, nu = (3 * m->K - 2 * m->G) / (2 * (3 * m->K + m->G));
    if (dim == 2 && m->plane == FLOE_PD_PLANE_STRAIN) { E /= 1 - nu * nu; nu /= 1 - nu; }
    *nu_out = -ey / ex / nu;
    free(xs); free(fs); free(u); free(r); free(p); free(Ap); free(fix);
    floe_pd_body_destroy(b);
    return F / (A * ex) / E;
}

static void test_bar(void)
{
    printf("static clamped bar under an end load, E_eff = F/(A eps) (delta = 3 dx)\n");
    const double E = 1e9;
    for (int t = 0; t < 3; t++) {
        double nu0 = t == 0 ? 0.3 : 0.45;
        int infl = t == 2 ? FLOE_PD_W_GAUSS : FLOE_PD_W_ONE;
        floe_pd_material m = lps_mat(E, nu0, infl, 0);
        double nr, nr0;
        double er = bar_static(3, 40, 8, &m, 1, &nr), er0 = bar_static(3, 40, 8, &m, 0, &nr0);
        char what[120];
        snprintf(what, sizeof what, "3D bar 40x8x8 nu=%.2f %s, corrected: E_eff/E", nu0, infl ? "gauss" : "w=1");
        CHECK_NEAR(er, 1.0, 0.05, what);
        snprintf(what, sizeof what, "3D bar 40x8x8 nu=%.2f %s, corrected: nu_eff/nu", nu0, infl ? "gauss" : "w=1");
        CHECK_NEAR(nr, 1.0, 0.05, what);
        printf("  (plain LPS, no correction: E_eff/E %.4f, nu_eff/nu %.4f)\n", er0, nr0);
    }
}

static void test_bar_2d(void)
{
    printf("2D LPS strip under an end load, in-plane E_eff and nu (delta = 3 dx)\n");
    const double E = 1e9;
    for (int t = 0; t < 4; t++) {
        double nu0 = t % 2 == 0 ? 0.3 : 0.45;
        int plane = t < 2 ? FLOE_PD_PLANE_STRESS : FLOE_PD_PLANE_STRAIN;
        floe_pd_material m = lps_mat(E, nu0, FLOE_PD_W_ONE, plane);
        double nr, nr0;
        double er = bar_static(2, 60, 12, &m, 1, &nr), er0 = bar_static(2, 60, 12, &m, 0, &nr0);
        const char *pl = plane == FLOE_PD_PLANE_STRAIN ? "plane strain" : "plane stress";
        char what[120];
        snprintf(what, sizeof what, "2D strip 60x12 %s nu=%.2f, corrected: E_eff/E'", pl, nu0);
        CHECK_NEAR(er, 1.0, 0.05, what);
        snprintf(what, sizeof what, "2D strip 60x12 %s nu=%.2f, corrected: nu_eff/nu'", pl, nu0);
        CHECK_NEAR(nr, 1.0, 0.05, what);
        printf("  (no correction: E_eff/E' %.4f, nu_eff/nu' %.4f)\n", er0, nr0);
    }
}

/* 3. forces = -grad energy */
static double energy_at(floe_pd_body *b, const double *x, double *scratch)
{
    memset(scratch, 0, 3 * (size_t)b->n * sizeof *scratch);
    return floe_pd_forces_nobreak(b, x, scratch);
}

static void test_gradient(int dim, int plane, int broken)
{
    floe_pd_body *b = dim == 3 ? make_box(3, 1e-3, 5, 4, 4) : make_box(2, 1e-3, 8, 7, 1);
    if (!b) return;
    floe_pd_material m = lps_mat(1e9, 0.3, FLOE_PD_W_GAUSS, plane);
    floe_pd_set_material(b, &m);
    CHECK(floe_pd_surface_correction(b) == FLOE_OK, "correction");
    if (broken)
        for (int64_t k = 0; k < b->nbond; k += 7) b->broken[k] = 1;
    int n3 = 3 * b->n;
    double *x = malloc(n3 * sizeof *x), *f = calloc(n3, sizeof *f), *s = malloc(n3 * sizeof *s);
    for (int i = 0; i < n3; i++) x[i] = b->X[i] + (dim == 2 && i % 3 == 2 ? 0 : 2e-6 * (2 * urand() - 1));
    floe_pd_forces_nobreak(b, x, f);
    double fm = 0, errmax = 0;
    for (int i = 0; i < n3; i++) fm = fm > fabs(f[i]) ? fm : fabs(f[i]);
    for (int t = 0; t < 30; t++) {
        int k = (int)(urand() * n3);
        double h = 1e-9, x0 = x[k];
        x[k] = x0 + h;
        double ep = energy_at(b, x, s);
        x[k] = x0 - h;
        double em = energy_at(b, x, s);
        x[k] = x0;
        errmax = fmax(errmax, fabs(-(ep - em) / (2 * h) - f[k]));
    }
    char what[120];
    snprintf(what, sizeof what, "%dD%s corrected%s: max |f + dE/dx| / max|f|", dim,
             dim == 2 ? (plane ? " plane strain" : " plane stress") : "", broken ? ", 1/7 bonds broken" : "");
    CHECK(errmax <= 1e-5 * fm, "%s: %.3g", what, errmax / fm);
    printf("  %-66s %.2e (tol 1e-5)\n", what, errmax / fm);
    free(x); free(f); free(s);
    floe_pd_body_destroy(b);
}

/* 4. energy conservation (velocity Verlet, dt = 0.5 dt_nodal) */
static void test_energy(int dim)
{
    floe_pd_body *b = dim == 3 ? make_box(3, 1e-3, 6, 6, 6) : make_box(2, 1e-3, 12, 12, 1);
    if (!b) return;
    floe_pd_material m = lps_mat(1e9, 0.35, FLOE_PD_W_ONE, FLOE_PD_PLANE_STRESS);
    floe_pd_set_material(b, &m);
    CHECK(floe_pd_surface_correction(b) == FLOE_OK, "correction");
    int n = b->n, n3 = 3 * n;
    double *x = malloc(n3 * sizeof *x), *v = calloc(n3, sizeof *v), *f = calloc(n3, sizeof *f);
    for (int i = 0; i < n3; i++) x[i] = b->X[i] + (dim == 2 && i % 3 == 2 ? 0 : 1e-7 * (2 * urand() - 1));
    double ep = floe_pd_forces(b, x, f), dt = 0.5 * floe_pd_dt_nodal(b);
    const int nsteps = 2000, win = 500;
    double first = 0, last = 0, e0 = ep;
    for (int t = 0; t < nsteps; t++) {
        for (int i = 0; i < n3; i++) {
            double mi = m.rho * b->V[i / 3];
            v[i] += 0.5 * dt * f[i] / mi;
            x[i] += dt * v[i];
        }
        memset(f, 0, n3 * sizeof *f);
        ep = floe_pd_forces(b, x, f);
        double ek = 0;
        for (int i = 0; i < n3; i++) {
            double mi = m.rho * b->V[i / 3];
            v[i] += 0.5 * dt * f[i] / mi;
            ek += 0.5 * mi * v[i] * v[i];
        }
        if (t < win) first += (ep + ek) / win;
        if (t >= nsteps - win) last += (ep + ek) / win;
    }
    double drift = fabs(last - first) / e0;
    CHECK(drift < 1e-4 && b->nbroken == 0, "%dD LPS corrected: energy drift %.3g (tol 1e-4)", dim, drift);
    printf("  %dD LPS corrected: energy drift (mean of last vs first %d of %d steps) %.2e (tol 1e-4)\n", dim,
           win, nsteps, drift);
    free(x); free(v); free(f);
    floe_pd_body_destroy(b);
}

/* 5. largest eigenvalue of M^-1 K by power iteration (K v ~ -f(X + h v)/h) */
static double omega_max(floe_pd_body *b)
{
    int n3 = 3 * b->n;
    double *v = malloc(n3 * sizeof *v), *x = malloc(n3 * sizeof *x), *f = malloc(n3 * sizeof *f);
    for (int i = 0; i < n3; i++) v[i] = b->dim == 2 && i % 3 == 2 ? 0 : 2 * urand() - 1;
    double lam = 0, h = 1e-9 * b->dx;
    for (int it = 0; it < 300; it++) {
        double nv = 0;
        for (int i = 0; i < n3; i++) nv += v[i] * v[i];
        nv = sqrt(nv);
        for (int i = 0; i < n3; i++) { v[i] /= nv; x[i] = b->X[i] + h * v[i]; }
        memset(f, 0, n3 * sizeof *f);
        floe_pd_forces_nobreak(b, x, f);
        double num = 0;
        for (int i = 0; i < n3; i++) {
            v[i] = -f[i] / h / (b->mat.rho * b->V[i / 3]);
            num += v[i] * v[i];
        }
        lam = sqrt(num);
    }
    free(v); free(x); free(f);
    return sqrt(lam);
}

static void test_timestep(int dim, int plane, double nu, int corr)
{
    floe_pd_body *b = dim == 3 ? make_box(3, 1e-3, 7, 7, 7) : make_box(2, 1e-3, 14, 14, 1);
    if (!b) return;
    floe_pd_material m = lps_mat(1e9, nu, FLOE_PD_W_ONE, plane);
    floe_pd_set_material(b, &m);
    if (corr) CHECK(floe_pd_surface_correction(b) == FLOE_OK, "correction");
    double dtn = floe_pd_dt_nodal(b), lim = 2.0 / omega_max(b);
    char what[120];
    snprintf(what, sizeof what, "%dD%s nu=%.2f%s: stability limit / dt_nodal", dim,
             dim == 2 ? (plane ? " plane strain" : " plane stress") : "", nu, corr ? " corrected" : "");
    CHECK(lim >= dtn, "%s: %.3f (must be >= 1)", what, lim / dtn);
    printf("  %-62s %.3f (>= 1)\n", what, lim / dtn);
    floe_pd_body_destroy(b);
}

/* 6. single-layer 3D plate */
static void test_single_layer(void)
{
    floe_pd_body *b = make_box(3, 1e-3, 10, 10, 1);
    if (!b) return;
    floe_pd_material m = lps_mat(1e9, 0.3, FLOE_PD_W_ONE, 0);
    floe_pd_set_material(b, &m);
    int n3 = 3 * b->n;
    double *x = malloc(n3 * sizeof *x), *f = calloc(n3, sizeof *f);
    for (int i = 0; i < n3; i++) x[i] = b->X[i] * (i % 3 == 2 ? 1.0 : 1.0 + 1e-4);
    double e0 = floe_pd_forces_nobreak(b, x, f);
    CHECK(floe_pd_surface_correction(b) == FLOE_OK, "correction on a single layer");
    memset(f, 0, n3 * sizeof *f);
    double e1 = floe_pd_forces_nobreak(b, x, f);
    int finite = 1;
    for (int i = 0; i < n3; i++) finite &= isfinite(f[i]);
    CHECK(finite && e1 > 0 && fabs(e1 - e0) <= 1e-9 * e0,
          "single layer: finite forces, in-plane isotropic stretch energy %.6g vs plain %.6g", e1, e0);
    printf("  single-layer 3D plate 10x10x1: energy of an in-plane isotropic stretch %.6g J "
           "(plain %.6g J)\n", e1, e0);
    free(x); free(f);
    floe_pd_body_destroy(b);
}

int main(void)
{
    test_bar();
    test_bar_2d();
    printf("forces against the energy gradient\n");
    test_gradient(3, 0, 0);
    test_gradient(3, 0, 1);
    test_gradient(2, FLOE_PD_PLANE_STRESS, 0);
    test_gradient(2, FLOE_PD_PLANE_STRAIN, 1);
    printf("energy conservation\n");
    test_energy(3);
    test_energy(2);
    printf("time step: nodal estimate against the stability limit\n");
    test_timestep(3, 0, 0.45, 1);
    test_timestep(2, FLOE_PD_PLANE_STRESS, 0.3, 0);
    test_timestep(2, FLOE_PD_PLANE_STRAIN, 0.45, 0);
    test_timestep(2, FLOE_PD_PLANE_STRAIN, 0.45, 1);
    test_timestep(2, FLOE_PD_PLANE_STRESS, 0.1, 1);
    printf("single layer of a 3D lattice\n");
    test_single_layer();
    return check_summary("test_pd_lps");
}
