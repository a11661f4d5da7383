/* test_pd.c - the peridynamics core (peridynamics/floe_pd.h) on its own: families against
 * brute force, a single bond breaking exactly at s_c, forces against the finite-difference
 * gradient of the energy, energy conservation under velocity Verlet, the time-step
 * estimates against the observed stability limit, the elastic wave speed in a bar and the
 * quasi-static uniaxial tension of LPS / PMB blocks (E and nu recovered in the interior).
 * Every dynamic loop is a small velocity-Verlet integrator written here. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "floe_pd.h"

static uint64_t rng_state = 0x2545f4914f6cdd1dull;
static double urand(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static floe_pd_body *make_box(int dim, double dx, double m, int nx, int ny, int nz)
{
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = dim;
    r.dx = dx;
    r.horizon_factor = m;
    r.thickness = dx;
    r.hi[0] = nx * dx;
    r.hi[1] = ny * dx;
    r.hi[2] = nz * dx;
    floe_pd_body *b = NULL;
    int rc = floe_pd_body_create(&b, &r);
    CHECK(rc == FLOE_OK && b, "body create: %s", floe_strerror(rc));
    return b;
}

static double sphere_sdf(const double X[3], void *user)
{
    const double *c = user; /* centre, radius */
    double d[3] = {X[0] - c[0], X[1] - c[1], X[2] - c[2]};
    return floe_v3_norm(d) - c[3];
}

/* ------------------------------------------------------------ families ---- */
static void test_families(void)
{
    printf("families\n");
    const double dx = 0.5e-3;
    /* a sphere (SDF region) on a simple cubic lattice, delta = 3 dx */
    double sph[4] = {2.6e-3, 2.4e-3, 2.5e-3, 2.3e-3};
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.hi[0] = r.hi[1] = r.hi[2] = 5e-3;
    r.sdf = sphere_sdf;
    r.sdf_user = sph;
    floe_pd_body *b = NULL;
    int rc = floe_pd_body_create(&b, &r);
    CHECK(rc == FLOE_OK && b, "sdf body: %s", floe_strerror(rc));
    if (!b) return;
    /* brute-force point count of the SDF region */
    int nbf = 0;
    for (int k = 0; k < 10; k++)
        for (int j = 0; j < 10; j++)
            for (int i = 0; i < 10; i++) {
                double p[3] = {(i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx};
                if (sphere_sdf(p, sph) <= 0) nbf++;
            }
    CHECK(b->n == nbf && b->n > 100, "sdf points %d, brute force %d", b->n, nbf);
    CHECK(fabs(b->delta - 3 * dx) < 1e-15, "delta = 3 dx by default: %g", b->delta);
    CHECK(fabs(b->V[0] - dx * dx * dx) < 1e-20, "V = dx^3");
    /* family sizes and bonds against brute force (|xi| <= delta + 1e-9 dx) */
    int n = b->n;
    int *cnt = malloc((size_t)n * sizeof *cnt);
    floe_pd_family_sizes(b, cnt);
    double r2 = (b->delta + 1e-9 * dx) * (b->delta + 1e-9 * dx);
    int bad = 0, badb = 0, sorted = 1, maxc = 0;
    int64_t pairs = 0;
    for (int i = 0; i < n; i++) {
        int c = 0;
        for (int j = 0; j < n; j++) {
            if (j == i) continue;
            double d[3];
            floe_v3_sub(d, b->X + 3 * j, b->X + 3 * i);
            int in = floe_v3_dot(d, d) <= r2;
            c += in;
            if (j > i) pairs += in;
            if (floe_pd_bonded(b, i, j) != in) badb++;
        }
        if (c != cnt[i]) bad++;
        if (cnt[i] > maxc) maxc = cnt[i];
        for (int64_t k = b->off[i] + 1; k < b->off[i + 1]; k++)
            if (b->partner[k] <= b->partner[k - 1]) sorted = 0;
    }
    CHECK(bad == 0, "%d points with family size != brute force", bad);
    CHECK(badb == 0, "%d pairs where floe_pd_bonded != brute force", badb);
    CHECK(pairs == b->nbond, "bonds stored once: %lld vs %lld pairs", (long long)b->nbond,
          (long long)pairs);
    CHECK(sorted, "partners sorted in each row");
    CHECK(maxc == 122, "interior point of the simple cubic lattice, delta = 3 dx: %d "
          "neighbours (LAMMPS: 122)", maxc);
    int vbad = 0, nhalf = 0;
    for (int64_t k = 0; k < b->nbond; k++) {
        double L = b->len[k], want = L <= b->delta - 0.5 * dx ? 1.0 : (b->delta + 0.5 * dx - L) / dx;
        if (!(b->vfac[k] >= 0 && b->vfac[k] <= 1) || fabs(b->vfac[k] - want) > 1e-6) vbad++;
        if (fabs(L - 3 * dx) < 1e-12) nhalf += fabs(b->vfac[k] - 0.5) < 1e-6;
    }
    CHECK(vbad == 0 && nhalf > 0, "partial-volume factors in [0,1] and linear (%d bad); "
          "|xi| = delta bonds get 1/2 (%d)", vbad, nhalf);
    printf("  sphere: %d points, %lld bonds (stored once), max family %d\n", n,
           (long long)b->nbond, maxc);
    {
        floe_pd_material pm = floe_pd_material_pmb(2200, 14.9e9, 0);
        floe_pd_set_material(b, &pm);
        printf("  memory: %zu bytes per bond in the bond arrays (int32 partner, double |xi|, float "
               "factor, byte flag; each bond once); whole PMB body %.1f bytes per bond "
               "(%.1f per bond end)\n", floe_pd_bytes_per_bond(),
               (double)floe_pd_body_bytes(b) / (double)b->nbond,
               (double)floe_pd_body_bytes(b) / (2.0 * (double)b->nbond));
    }
    free(cnt);
    floe_pd_body_destroy(b);

    /* 2D square lattice: interior family of delta = 3 dx is 28 points */
    b = make_box(2, dx, 3, 12, 12, 1);
    if (b) {
        int *c2 = malloc((size_t)b->n * sizeof *c2);
        floe_pd_family_sizes(b, c2);
        int mx = 0;
        for (int i = 0; i < b->n; i++) mx = c2[i] > mx ? c2[i] : mx;
        CHECK(b->n == 144 && mx == 28, "2D: %d points, max family %d (want 144, 28)", b->n, mx);
        CHECK(fabs(b->V[0] - dx * dx * dx) < 1e-20, "2D volume dx^2 * thickness");
        floe_pd_material l2 = floe_pd_material_lps(1000, 1e9, 1e9, 0, FLOE_PD_W_ONE);
        CHECK(floe_pd_set_material(b, &l2) == FLOE_OK && b->ops == &floe_pd_lps_ops,
              "2D LPS accepted (tests/test_pd_lps.c)");
        l2.plane = 7;
        CHECK(floe_pd_set_material(b, &l2) == FLOE_EINVAL && b->mat.plane != 7,
              "2D LPS with a bad plane refused, material unchanged");
        floe_pd_material bad = floe_pd_material_pmb(-1, 1e9, 0);
        CHECK(floe_pd_set_material(b, &bad) == FLOE_EINVAL, "negative density refused");
        free(c2);
        floe_pd_body_destroy(b);
    }
    /* errors */
    floe_pd_region bad_r;
    memset(&bad_r, 0, sizeof bad_r);
    bad_r.dim = 4;
    bad_r.dx = 1;
    bad_r.hi[0] = bad_r.hi[1] = bad_r.hi[2] = 3;
    floe_pd_body *nb = (floe_pd_body *)&bad_r;
    CHECK(floe_pd_body_create(&nb, &bad_r) == FLOE_EINVAL && nb == NULL, "dim 4 refused");
    bad_r.dim = 3;
    bad_r.dx = 0;
    CHECK(floe_pd_body_create(&nb, &bad_r) == FLOE_EINVAL, "dx 0 refused");
}


/* ---------------------------------------------------------- single bond ---- */
static void test_single_bond(int model)
{
    printf("single bond (%s)\n", model == FLOE_PD_PMB ? "PMB" : "LPS");
    const double L = 1e-3, V = 1e-9, s_c = 1e-3;
    double X[6] = {0, 0, 0, L, 0, 0}, Vv[2] = {V, V};
    floe_pd_body *b = NULL;
    int rc = floe_pd_body_create_points(&b, 3, 2, X, Vv, 1.5 * L, 0, 0);
    CHECK(rc == FLOE_OK && b && b->nbond == 1, "two-point body");
    if (!b) return;
    floe_pd_material m = model == FLOE_PD_PMB ? floe_pd_material_pmb(2200, 14.9e9, s_c)
                                              : floe_pd_material_lps(2200, 14.9e9, 9e9, s_c, FLOE_PD_W_ONE);
    CHECK(floe_pd_set_material(b, &m) == FLOE_OK, "set material");
    double x[6], f[6];
    /* stretch s: positions along a skew direction so that all components matter */
    double dir[3] = {0.6, 0.48, 0.64};
    double steps[] = {s_c * (1 - 1e-9), s_c * (1 + 1e-9), 0.5 * s_c, -0.5 * s_c, s_c * 0.999};
    double fprev = 0;
    for (int t = 0; t < 5; t++) {
        double s = steps[t];
        memset(x, 0, sizeof x);
        for (int d = 0; d < 3; d++) x[3 + d] = dir[d] * L * (1 + s);
        memset(f, 0, sizeof f);
        double e = floe_pd_forces(b, x, f);
        double fn = floe_v3_dot(f, dir); /* force on point 0 along the bond (towards 1) */
        double sum = fabs(f[0] + f[3]) + fabs(f[1] + f[4]) + fabs(f[2] + f[5]);
        double want = 0;
        if (model == FLOE_PD_PMB) want = b->c * s * V * V;               /* c s V_i V_j */
        else want = 2 * (3 * m.K * (3 * s * L / L) / (L * L * V)) * L * V * V; /* (t_ij + t_ji) V V */
        if (t == 0) {
            CHECK(!b->broken[0] && fabs(fn - want) <= 1e-9 * fabs(want) && fn > 0,
                  "just below s_c: intact, force %.6g (want %.6g)", fn, want);
            CHECK(e > 0, "energy > 0 below s_c");
            fprev = fn;
        } else if (t == 1) {
            CHECK(b->broken[0] && fn == 0 && b->nbroken == 1,
                  "just above s_c: broken (%d), force %.3g (was %.6g)", b->broken[0], fn, fprev);
        } else if (t == 2 || t == 4) {
            CHECK(b->broken[0] && fn == 0, "stretch %.3g s_c after breaking: stays broken, force %g",
                  s / s_c, fn);
        } else if (t == 3) {
            if (model == FLOE_PD_PMB)
                CHECK(b->broken[0] && fn < 0 && fabs(fn - want) <= 1e-9 * fabs(want),
                      "compressed broken bond pushes (003 eq 2, mu = 1 for s <= 0): %g vs %g", fn, want);
            else
                CHECK(b->broken[0] && fn == 0, "LPS: a broken bond carries nothing: %g", fn);
        }
        CHECK(sum <= 1e-12 * (fabs(fn) + 1e-30) || sum == 0, "momentum: forces sum to %g", sum);
    }
    double phi[2];
    floe_pd_damage(b, phi);
    CHECK(phi[0] == 1 && phi[1] == 1, "damage 1 with the only bond broken: %g %g", phi[0], phi[1]);
    if (model == FLOE_PD_PMB) {
        /* broken_tension_only = 0: nothing in compression either */
        m.broken_tension_only = 0;
        floe_pd_set_material(b, &m);
        for (int d = 0; d < 3; d++) x[3 + d] = dir[d] * L * 0.99;
        memset(f, 0, sizeof f);
        floe_pd_forces(b, x, f);
        CHECK(f[0] == 0 && f[1] == 0 && f[2] == 0, "broken_tension_only = 0: no force");
        /* s_c from G_c (003 eq 5) */
        floe_pd_material g = floe_pd_material_pmb(2200, 14.9e9, 0);
        g.G_c = 38.0;
        floe_pd_set_material(b, &g);
        double want = sqrt(10 * g.G_c / (M_PI * b->c * pow(b->delta, 5)));
        CHECK_NEAR(b->s_c, want, 1e-14, "s_c from G_c (003 eq 5)");
    }
    floe_pd_body_destroy(b);
}

/* -------------------------------------------- forces = -grad energy (FD) ---- */
static double total_energy(floe_pd_body *b, const double *x, double *scratch)
{
    memset(scratch, 0, 3 * (size_t)b->n * sizeof *scratch);
    return floe_pd_forces_nobreak(b, x, scratch);
}

static void perturb(const floe_pd_body *b, double *x, double amp)
{
    for (int i = 0; i < 3 * b->n; i++) x[i] = b->X[i] + amp * (2 * urand() - 1);
}

static void test_gradient(const floe_pd_material *m, int corr, const char *what)
{
    floe_pd_body *b = make_box(3, 1e-3, 3, 5, 4, 4);
    if (!b) return;
    floe_pd_set_material(b, m);
    if (corr) CHECK(floe_pd_surface_correction(b) == FLOE_OK, "correction");
    int n3 = 3 * b->n;
    double *x = malloc(n3 * sizeof *x), *f = calloc(n3, sizeof *f), *s = malloc(n3 * sizeof *s);
    perturb(b, x, 2e-6);
    floe_pd_forces_nobreak(b, x, f);
    double fmax = 0, errmax = 0;
    for (int i = 0; i < n3; i++) fmax = fmax > fabs(f[i]) ? fmax : fabs(f[i]);
    for (int t = 0; t < 30; t++) {
        int k = (int)(urand() * n3);
        double h = 1e-9, x0 = x[k];
        x[k] = x0 + h;
        double ep = total_energy(b, x, s);
        x[k] = x0 - h;
        double em = total_energy(b, x, s);
        x[k] = x0;
        double fd = -(ep - em) / (2 * h);
        double err = fabs(fd - f[k]);
        errmax = err > errmax ? err : errmax;
    }
    char buf[96];
    snprintf(buf, sizeof buf, "%s: max |f + dE/dx| / max|f| (30 dofs)", what);
    CHECK(errmax <= 1e-5 * fmax, "%s: %.3g", buf, errmax / fmax);
    printf("  %-52s %.2e (tol 1e-5)\n", buf, errmax / fmax);
    free(x); free(f); free(s);
    floe_pd_body_destroy(b);
}

/* ---------------------------------------------------- velocity Verlet ---- */
typedef struct vv {
    floe_pd_body *b;
    double *x, *v, *f, *mass;
    double epot;
} vv;

static void vv_init(vv *s, floe_pd_body *b)
{
    s->b = b;
    size_t n3 = 3 * (size_t)b->n;
    s->x = malloc(n3 * sizeof *s->x);
    s->v = calloc(n3, sizeof *s->v);
    s->f = calloc(n3, sizeof *s->f);
    s->mass = malloc((size_t)b->n * sizeof *s->mass);
    memcpy(s->x, b->X, n3 * sizeof *s->x);
    for (int i = 0; i < b->n; i++) s->mass[i] = b->mat.rho * b->V[i];
}
static void vv_free(vv *s) { free(s->x); free(s->v); free(s->f); free(s->mass); }
static void vv_force(vv *s)
{
    memset(s->f, 0, 3 * (size_t)s->b->n * sizeof *s->f);
    s->epot = floe_pd_forces(s->b, s->x, s->f);
}
static double vv_kinetic(const vv *s)
{
    double k = 0;
    for (int i = 0; i < s->b->n; i++)
        k += 0.5 * s->mass[i] * floe_v3_dot(s->v + 3 * i, s->v + 3 * i);
    return k;
}
/* one step; fixed[i] != 0 pins dof i (velocity kept as given) */
static void vv_step(vv *s, double dt, const unsigned char *fixed)
{
    int n3 = 3 * s->b->n;
    for (int i = 0; i < n3; i++) {
        if (!fixed || !fixed[i]) s->v[i] += 0.5 * dt * s->f[i] / s->mass[i / 3];
        s->x[i] += dt * s->v[i];
    }
    vv_force(s);
    for (int i = 0; i < n3; i++)
        if (!fixed || !fixed[i]) s->v[i] += 0.5 * dt * s->f[i] / s->mass[i / 3];
}

/* --------------------------------------------------- energy conservation ---- */
static void test_energy(const floe_pd_material *m, const char *what)
{
    floe_pd_body *b = make_box(3, 1e-3, 3, 6, 6, 6);
    if (!b) return;
    floe_pd_set_material(b, m);
    vv s;
    vv_init(&s, b);
    perturb(b, s.x, 1e-7);
    vv_force(&s);
    double dt = 0.5 * floe_pd_dt_nodal(b);
    const int nsteps = 2000, win = 500;
    double e0 = s.epot + vv_kinetic(&s), first = 0, last = 0, emin = e0, emax = e0;
    for (int t = 0; t < nsteps; t++) {
        vv_step(&s, dt, NULL);
        double e = s.epot + vv_kinetic(&s);
        if (t < win) first += e / win;
        if (t >= nsteps - win) last += e / win;
        emin = e < emin ? e : emin;
        emax = e > emax ? e : emax;
    }
    double drift = fabs(last - first) / e0;
    char buf[96];
    snprintf(buf, sizeof buf, "%s: energy drift (mean of last vs first %d steps)", what, win);
    CHECK(drift < 1e-4 && b->nbroken == 0, "%s: %.3g", buf, drift);
    printf("  %-52s %.2e (tol 1e-4); fluctuation %.2e, dt = 0.5 dt_nodal\n", buf, drift,
           (emax - emin) / e0);
    vv_free(&s);
    floe_pd_body_destroy(b);
}

/* ----------------------------------------------------------- time step ---- */
/* largest eigenvalue of M^-1 K by power iteration on the linearised forces at the
 * reference configuration (forces vanish there): K v ~ -f(X + h v)/h */
static double omega_max(floe_pd_body *b)
{
    int n3 = 3 * b->n;
    double *v = malloc(n3 * sizeof *v), *x = malloc(n3 * sizeof *x), *f = malloc(n3 * sizeof *f);
    for (int i = 0; i < n3; i++) v[i] = 2 * urand() - 1;
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

/* run at dt, return max |u| / initial max |u| after nsteps */
static double growth(floe_pd_body *b, double dt, int nsteps)
{
    vv s;
    vv_init(&s, b);
    rng_state = 12345;
    perturb(b, s.x, 1e-9);
    double u0 = 0, u1 = 0;
    for (int i = 0; i < 3 * b->n; i++) u0 = fmax(u0, fabs(s.x[i] - b->X[i]));
    vv_force(&s);
    for (int t = 0; t < nsteps && u1 < 1e6 * u0; t++) {
        vv_step(&s, dt, NULL);
        if (t % 50 == 0)
            for (int i = 0; i < 3 * b->n; i++) u1 = fmax(u1, fabs(s.x[i] - b->X[i]));
    }
    u1 = 0;
    for (int i = 0; i < 3 * b->n; i++) u1 = fmax(u1, fabs(s.x[i] - b->X[i]));
    vv_free(&s);
    return u1 / u0;
}

static void test_timestep(const floe_pd_material *m, const char *what)
{
    printf("time step (%s)\n", what);
    floe_pd_body *b = make_box(3, 1e-3, 3, 7, 7, 7);
    if (!b) return;
    floe_pd_set_material(b, m);
    double dtn = floe_pd_dt_nodal(b), dtc = floe_pd_dt_cfl(b);
    double w = omega_max(b), dt_true = 2.0 / w; /* velocity Verlet: stable iff w dt < 2 */
    printf("  dt_nodal %.4g s, dt_cfl %.4g s, 2/omega_max %.4g s = %.2f dt_nodal = %.2f dt_cfl\n",
           dtn, dtc, dt_true, dt_true / dtn, dt_true / dtc);
    double g09 = growth(b, 0.9 * dtn, 2000);
    CHECK(g09 < 10, "0.9 dt_nodal bounded: growth %.3g", g09);
    double gl = growth(b, 0.97 * dt_true, 2000), gh = growth(b, 1.05 * dt_true, 2000);
    CHECK(gl < 10 && gh > 1e3, "observed limit at 2/omega_max: growth %.3g at 0.97x, %.3g at 1.05x",
          gl, gh);
    double g2 = growth(b, 2 * dtn, 2000);
    printf("  growth at 0.9 dt_nodal %.3g, at 2 dt_nodal %.3g, at 0.97 / 1.05 of 2/omega_max %.3g / %.3g\n",
           g09, g2, gl, gh);
    CHECK(dt_true >= dtn, "nodal estimate conservative: limit %.3g x estimate", dt_true / dtn);
    if (dt_true < 2 * dtn) CHECK(g2 > 1e3, "2 dt_nodal blows up: growth %.3g", g2);
    floe_pd_body_destroy(b);
}

/* ------------------------------------------------------------ wave speed ---- */
/* A bar along x (ny x ny points in 3D, ny in 2D plane stress) whose first three layers are
 * driven at a constant velocity v0 from t = 0: a velocity step runs down the bar. The
 * front (the layer-averaged v_x crossing v0/2, interpolated) is located at two times and
 * its speed compared with the bar speed sqrt(E/rho): 3D PMB has nu = 1/4, E = 3K(1 - 2nu)
 * = 1.5 K; 2D plane-stress PMB has nu = 1/3 and E given. The PMB surface correction is on
 * (without it a bar a few horizons thick is 17-30 % slow: its surface points miss bonds). */
static double wave_ratio(int dim, int ny, int nx, double *cmeas)
{
    const double dx = 1e-3, rho = 2000, K = 1e9, v0 = 1e-3;
    floe_pd_body *b = make_box(dim, dx, 3, nx, ny, dim == 3 ? ny : 1);
    if (!b) return 0;
    floe_pd_material mat = floe_pd_material_pmb(rho, K, 0);
    floe_pd_set_material(b, &mat);
    CHECK(floe_pd_surface_correction(b) == FLOE_OK, "surface correction");
    double cb = sqrt(mat.E / rho);
    vv s;
    vv_init(&s, b);
    unsigned char *fix = calloc(3 * (size_t)b->n, 1);
    for (int i = 0; i < b->n; i++)
        if (b->X[3 * i] < 3 * dx) { fix[3 * i] = fix[3 * i + 1] = fix[3 * i + 2] = 1; s.v[3 * i] = v0; }
    double *lay = calloc((size_t)nx + 1, sizeof *lay);
    int *cnt = calloc((size_t)nx + 1, sizeof *cnt);
    for (int i = 0; i < b->n; i++) cnt[(int)(b->X[3 * i] / dx)]++;
    double dt = 0.5 * floe_pd_dt_nodal(b), t = 0;
    double tm[2] = {0.25 * nx * dx / cb, 0.6 * nx * dx / cb}, pos[2] = {0, 0};
    vv_force(&s);
    for (int k = 0; k < 2;) {
        vv_step(&s, dt, fix);
        t += dt;
        if (t < tm[k]) continue;
        memset(lay, 0, ((size_t)nx + 1) * sizeof *lay);
        for (int i = 0; i < b->n; i++) {
            int l = (int)(b->X[3 * i] / dx);
            lay[l] += s.v[3 * i] / cnt[l];
        }
        int l = nx - 1;
        while (l > 0 && lay[l] < 0.5 * v0) l--;
        pos[k] = (l + 0.5) * dx + dx * (lay[l] - 0.5 * v0) / (lay[l] - lay[l + 1]);
        tm[k] = t;
        k++;
    }
    double c = (pos[1] - pos[0]) / (tm[1] - tm[0]);
    *cmeas = c;
    free(fix); free(lay); free(cnt);
    vv_free(&s);
    floe_pd_body_destroy(b);
    return c / cb;
}

static void test_wave(void)
{
    printf("wave speed in a bar (PMB, surface correction, delta = 3 dx)\n");
    double c;
    double r2 = wave_ratio(2, 10, 480, &c);
    CHECK_NEAR(r2, 1.0, 0.03, "2D plane stress strip 480 x 10: c / sqrt(E/rho)");
    double r3 = wave_ratio(3, 6, 240, &c);
    CHECK_NEAR(r3, 1.0, 0.03, "3D bar 240 x 6 x 6: c / sqrt(E/rho), E = 1.5 K");
}

/* ------------------------------------------------ quasi-static tension ---- */
/* A block nx x ny x ny (delta = m dx): the x displacement of the end slabs (three layers
 * each, X < 3 dx and X > (nx - 3) dx) is prescribed, u_x = eps (X - x_c); every other dof is
 * free. Static equilibrium by conjugate gradients on the linearised stiffness (matrix-free:
 * K v = -f(X + a v)/a at a tiny amplitude a, the forces vanish at X). In the interior core
 * (at least delta from the lateral faces, middle half in x) eps_x and eps_y, eps_z are
 * least-squares slopes of the displacements, nu = -eps_lat/eps_x; sigma_xx is the bond-force
 * flux through the mid plane x = x_c over the core patch (each bond crossing the patch,
 * half weight on its edge), so E = sigma_xx/eps_x measures the interior alone. */
typedef struct tens_ctx {
    floe_pd_body *b;
    double *x, *f;
} tens_ctx;

static void kmul(tens_ctx *c, const double *v, double *out, const unsigned char *fix)
{
    floe_pd_body *b = c->b;
    int n3 = 3 * b->n;
    double mx = 0;
    for (int i = 0; i < n3; i++) mx = fmax(mx, fabs(v[i]));
    if (mx == 0) { memset(out, 0, n3 * sizeof *out); return; }
    double a = 1e-7 * b->dx / mx;
    for (int i = 0; i < n3; i++) c->x[i] = b->X[i] + a * v[i];
    memset(c->f, 0, n3 * sizeof *c->f);
    floe_pd_forces_nobreak(b, c->x, c->f);
    for (int i = 0; i < n3; i++) out[i] = fix[i] ? 0 : -c->f[i] / a;
}

typedef struct flux_ctx {
    const floe_pd_body *b;
    double xm, lo, hi, tol, sum;
} flux_ctx;

static void flux_visit(int i, int j, int64_t k, const double f[3], void *user)
{
    (void)k;
    flux_ctx *F = user;
    const double *Xi = F->b->X + 3 * i, *Xj = F->b->X + 3 * j;
    if ((Xi[0] - F->xm) * (Xj[0] - F->xm) >= 0) return;
    double t = (F->xm - Xi[0]) / (Xj[0] - Xi[0]), w = 1;
    for (int d = 1; d < 3; d++) {
        double c = Xi[d] + t * (Xj[d] - Xi[d]);
        if (c < F->lo - F->tol || c > F->hi + F->tol) return;
        if (fabs(c - F->lo) < F->tol || fabs(c - F->hi) < F->tol) w *= 0.5;
    }
    /* force on the point right of the plane from the one left of it (f acts on i) */
    F->sum += w * (Xj[0] > F->xm ? -f[0] : f[0]);
}

static void tension(const floe_pd_material *m, double mh, int corr, int nx, int ny,
                    double *E_ratio, double *nu_out, double *resid)
{
    const double dx = 1e-3, eps = 1e-4;
    floe_pd_body *b = make_box(3, dx, mh, nx, ny, ny);
    if (!b) return;
    floe_pd_set_material(b, m);
    if (corr) CHECK(floe_pd_surface_correction(b) == FLOE_OK, "correction");
    int n3 = 3 * b->n;
    tens_ctx c = {b, malloc(n3 * sizeof(double)), malloc(n3 * sizeof(double))};
    unsigned char *fix = calloc(n3, 1);
    double *u = calloc(n3, sizeof *u), *r = malloc(n3 * sizeof *r), *p = malloc(n3 * sizeof *p),
           *Ap = malloc(n3 * sizeof *Ap);
    double xc = 0.5 * nx * dx;
    for (int i = 0; i < b->n; i++) {
        double X = b->X[3 * i];
        if (X < 3 * dx || X > (nx - 3) * dx) { fix[3 * i] = 1; u[3 * i] = eps * (X - xc); }
    }
    kmul(&c, u, r, fix); /* r = b - K u_free = -K u_prescribed on the free dofs */
    for (int i = 0; i < n3; i++) r[i] = fix[i] ? 0 : -r[i];
    memcpy(p, r, n3 * sizeof *p);
    double rs = 0;
    for (int i = 0; i < n3; i++) rs += r[i] * r[i];
    double rs0 = rs;
    int it;
    for (it = 0; it < 2000 && rs > 1e-20 * rs0; it++) {
        kmul(&c, p, Ap, fix);
        double pAp = 0, rn = 0;
        for (int i = 0; i < n3; i++) pAp += p[i] * Ap[i];
        double al = rs / pAp;
        for (int i = 0; i < n3; i++) {
            if (!fix[i]) u[i] += al * p[i];
            r[i] -= al * Ap[i];
            rn += r[i] * r[i];
        }
        for (int i = 0; i < n3; i++) p[i] = r[i] + rn / rs * p[i];
        rs = rn;
    }
    /* true (nonlinear) residual of the free dofs against the prescribed load */
    for (int i = 0; i < n3; i++) c.x[i] = b->X[i] + (fix[i] ? u[i] : 0);
    memset(c.f, 0, n3 * sizeof *c.f);
    floe_pd_forces_nobreak(b, c.x, c.f);
    double f0 = 0, f1 = 0;
    for (int i = 0; i < n3; i++) if (!fix[i]) f0 += c.f[i] * c.f[i];
    for (int i = 0; i < n3; i++) c.x[i] = b->X[i] + u[i];
    memset(c.f, 0, n3 * sizeof *c.f);
    floe_pd_forces_nobreak(b, c.x, c.f);
    for (int i = 0; i < n3; i++) if (!fix[i]) f1 += c.f[i] * c.f[i];
    *resid = sqrt(f1 / f0);
    /* interior fits */
    double yc = 0.5 * ny * dx, core = 0.5 * ny * dx - b->delta;
    double sx = 0, sxx = 0, sux = 0, su = 0, sy = 0, syy = 0, suy = 0, sv = 0;
    int cn = 0;
    for (int i = 0; i < b->n; i++) {
        const double *X = b->X + 3 * i;
        if (fabs(X[0] - xc) > 0.25 * nx * dx || fabs(X[1] - yc) > core || fabs(X[2] - yc) > core) continue;
        cn++;
        double ax = X[0] - xc;
        sx += ax; sxx += ax * ax; sux += ax * u[3 * i]; su += u[3 * i];
        for (int d = 1; d < 3; d++) {
            double ay = X[d] - yc;
            sy += ay; syy += ay * ay; suy += ay * u[3 * i + d]; sv += u[3 * i + d];
        }
    }
    double ex = (sux - sx * su / cn) / (sxx - sx * sx / cn);
    double ey = (suy - sy * sv / (2 * cn)) / (syy - sy * sy / (2 * cn));
    flux_ctx F = {b, xc, yc - core - 0.5 * dx, yc + core + 0.5 * dx, 1e-9 * dx, 0};
    floe_pd_bond_forces(b, c.x, flux_visit, &F);
    double sig = -F.sum / ((F.hi - F.lo) * (F.hi - F.lo)); /* tension > 0 */
    *E_ratio = sig / ex / m->E;
    *nu_out = -ey / ex;
    printf("  CG %d it, residual %.1e, core %d points, eps_x %.4g (applied %.4g between slabs)\n",
           it, *resid, cn, ex, eps);
    free(c.x); free(c.f); free(fix); free(u); free(r); free(p); free(Ap);
    floe_pd_body_destroy(b);
}

static void test_tension(void)
{
    printf("quasi-static uniaxial tension, interior E and nu (block 24 x 12 x 12, delta = 3 dx)\n");
    const double E = 1e9;
    double Er, nu, res;
    for (int t = 0; t < 2; t++) {
        double nu0 = t == 0 ? 0.3 : 0.45;
        int infl = t == 0 ? FLOE_PD_W_ONE : FLOE_PD_W_GAUSS;
        floe_pd_material m = floe_pd_material_lps(1000, E / (3 * (1 - 2 * nu0)), E / (2 * (1 + nu0)), 0, infl);
        char what[96];
        tension(&m, 3, 1, 24, 12, &Er, &nu, &res);
        CHECK(res < 1e-3, "equilibrium residual %.3g (nonlinear forces at strain 1e-4)", res);
        snprintf(what, sizeof what, "LPS nu=%.2f %s, alpha calibrated: E_int / E", nu0, infl ? "gauss" : "w=1");
        CHECK_NEAR(Er, 1.0, 0.05, what);
        snprintf(what, sizeof what, "LPS nu=%.2f %s, alpha calibrated: nu_int", nu0, infl ? "gauss" : "w=1");
        CHECK_NEAR(nu, nu0, 0.05, what);
        /* without the calibration (alpha = 15 G/m of 000 eq 25): the lattice error, shown */
        tension(&m, 3, 0, 24, 12, &Er, &nu, &res);
        printf("  LPS nu=%.2f %s, alpha = 15G/m (no calibration): E_int/E %.4f, nu_int %.4f "
               "(%+.1f %%)\n", nu0, infl ? "gauss" : "w=1", Er, nu, 100 * (nu / nu0 - 1));
    }
    floe_pd_material pm = floe_pd_material_pmb(1000, E / 1.5, 0);
    tension(&pm, 3, 1, 24, 12, &Er, &nu, &res);
    CHECK(res < 1e-3, "equilibrium residual %.3g (nonlinear forces at strain 1e-4)", res);
    CHECK_NEAR(Er, 1.0, 0.05, "PMB delta = 3 dx, surface corrected: E_int / E");
    /* bond-based PD on a cubic lattice is cubic, not isotropic (central forces): nu along
     * [100] is 0.269 at delta = 3 dx and tends to 1/4 as delta/dx grows */
    CHECK_NEAR(nu, 0.25, 0.10, "PMB delta = 3 dx: nu_int (cubic lattice, tol 10 %)");
    tension(&pm, 4, 1, 24, 12, &Er, &nu, &res);
    CHECK_NEAR(nu, 0.25, 0.03, "PMB delta = 4 dx: nu_int");
    CHECK_NEAR(Er, 1.0, 0.05, "PMB delta = 4 dx: E_int / E");
}

/* --------------------------------------------------------------- damage ---- */
/* A 2D plate cut by moving its right half away: exactly the bonds crossing the cut break,
 * points far from it keep phi = 0, points at the cut get 0 < phi < 1. */
static void test_damage(void)
{
    printf("damage across a cut (2D PMB)\n");
    const double dx = 1e-3;
    floe_pd_body *b = make_box(2, dx, 3, 20, 10, 1);
    if (!b) return;
    floe_pd_material m = floe_pd_material_pmb(1000, 1e9, 1e-3);
    floe_pd_set_material(b, &m);
    double xc = 10 * dx;
    int64_t crossing = 0;
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++)
            crossing += (b->X[3 * i] < xc) != (b->X[3 * b->partner[k]] < xc);
    double *x = malloc(3 * (size_t)b->n * sizeof *x), *f = calloc(3 * (size_t)b->n, sizeof *f);
    double *phi = malloc((size_t)b->n * sizeof *phi);
    for (int i = 0; i < 3 * b->n; i++) x[i] = b->X[i] + (i % 3 == 0 && b->X[i - i % 3] > xc ? 0.1 * dx : 0);
    floe_pd_forces(b, x, f);
    CHECK(b->nbroken == crossing && crossing > 0, "broken %lld, crossing the cut %lld",
          (long long)b->nbroken, (long long)crossing);
    CHECK(floe_pd_damage(b, phi) == FLOE_OK, "damage");
    int bad = 0;
    double mx = 0;
    for (int i = 0; i < b->n; i++) {
        double d = fabs(b->X[3 * i] - xc);
        if (d > b->delta && phi[i] != 0) bad++;
        if (d < dx && !(phi[i] > 0 && phi[i] < 1)) bad++;
        mx = fmax(mx, phi[i]);
    }
    CHECK(bad == 0, "%d points with damage out of place", bad);
    /* put the halves back: bonds stay broken, the halves do not attract */
    memset(f, 0, 3 * (size_t)b->n * sizeof *f);
    for (int i = 0; i < 3 * b->n; i++) x[i] = b->X[i] + (i % 3 == 0 && b->X[i - i % 3] > xc ? 1e-4 * dx : 0);
    floe_pd_forces(b, x, f);
    double fl = 0;
    for (int i = 0; i < b->n; i++) if (b->X[3 * i] < xc) fl += f[3 * i];
    CHECK(fl == 0 && b->nbroken == crossing, "no force across the healed-looking cut: %g", fl);
    printf("  %lld bonds broken across the cut, max damage %.3f\n", (long long)crossing, mx);
    free(x); free(f); free(phi);
    floe_pd_body_destroy(b);
}

int main(void)
{
    double t0 = now_s();
    test_families();
    test_single_bond(FLOE_PD_PMB);
    test_single_bond(FLOE_PD_LPS);
    test_damage();
    printf("forces against the energy gradient\n");
    floe_pd_material pmb = floe_pd_material_pmb(2200, 14.9e9, 0);
    floe_pd_material lps1 = floe_pd_material_lps(2200, 14.9e9, 6.0e9, 0, FLOE_PD_W_ONE);
    floe_pd_material lpsg = floe_pd_material_lps(2200, 14.9e9, 6.0e9, 0, FLOE_PD_W_GAUSS);
    test_gradient(&pmb, 0, "PMB");
    test_gradient(&pmb, 1, "PMB surface corrected");
    test_gradient(&lps1, 0, "LPS w=1");
    test_gradient(&lpsg, 0, "LPS w=gauss");
    test_gradient(&lpsg, 1, "LPS w=gauss, alpha calibrated");
    printf("energy conservation\n");
    test_energy(&pmb, "PMB");
    test_energy(&lpsg, "LPS w=gauss");
    test_timestep(&pmb, "PMB");
    test_timestep(&lps1, "LPS w=1");
    test_wave();
    test_tension();
    printf("total %.2f s\n", now_s() - t0);
    return check_summary("test_pd");
}
