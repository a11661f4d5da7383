/* test_pd_hex.c - the hexagonal PD lattice (issue #4: floe_pd_region.lattice =
 * FLOE_PD_LATTICE_HEXAGONAL, 2D triangular and 3D hexagonal close packing): nearest
 * distance and neighbour counts, volumes summing to the region volume (box, sphere, disc),
 * the interior quadrature of the horizon integrals that the PMB/LPS constants come from,
 * the bar wave speed of PMB against sqrt(E/rho), the interior E and nu of LPS in
 * quasi-static tension, and the scene key `lattice:`. The cubic lattice is run beside it
 * where the figures are compared (printed, not asserted). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "floe_pd.h"
#include "floe_scene.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static floe_pd_body *make_region(int dim, int lattice, double dx, double m, const double lo[3],
                                 const double hi[3], floe_pd_sdf_fn sdf, void *user)
{
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = dim;
    r.dx = dx;
    r.horizon_factor = m;
    r.thickness = dx;
    r.lattice = lattice;
    for (int d = 0; d < 3; d++) { r.lo[d] = lo[d]; r.hi[d] = hi[d]; }
    r.sdf = sdf;
    r.sdf_user = user;
    floe_pd_body *b = NULL;
    int rc = floe_pd_body_create(&b, &r);
    CHECK(rc == FLOE_OK && b, "body create: %s", floe_strerror(rc));
    return b;
}

/* box [0, nx dx] x [0, ny dx] x [0, nz dx] */
static floe_pd_body *make_box(int dim, int lattice, double dx, double m, double nx, double ny, double nz)
{
    double lo[3] = {0, 0, 0}, hi[3] = {nx * dx, ny * dx, nz * dx};
    return make_region(dim, lattice, dx, m, lo, hi, NULL, NULL);
}

static double sphere_sdf(const double X[3], void *user)
{
    const double *c = user; /* centre, radius; 2D: a disc (z ignored) */
    double d[3] = {X[0] - c[0], X[1] - c[1], c[4] > 0 ? X[2] - c[2] : 0};
    return floe_v3_norm(d) - c[3];
}

static double total_volume(const floe_pd_body *b)
{
    double v = 0;
    for (int i = 0; i < b->n; i++) v += b->V[i];
    return v;
}

/* the point nearest to c */
static int nearest_point(const floe_pd_body *b, const double c[3])
{
    int best = 0;
    double bd = INFINITY;
    for (int i = 0; i < b->n; i++) {
        double d[3];
        floe_v3_sub(d, b->X + 3 * i, c);
        double q = floe_v3_dot(d, d);
        if (q < bd) { bd = q; best = i; }
    }
    return best;
}

/* ------------------------------------------------------------- geometry ---- */
static void test_geometry(void)
{
    printf("hexagonal lattice geometry and volumes\n");
    const double dx = 1e-3;
    for (int dim = 2; dim <= 3; dim++) {
        /* a box whose sides are not multiples of the row / layer pitch */
        floe_pd_body *b = make_box(dim, FLOE_PD_LATTICE_HEXAGONAL, dx, 3, 20.3, 17.6, dim == 3 ? 15.2 : 1);
        if (!b) continue;
        double h = dx; /* 2D thickness */
        double Vwant = dim == 3 ? dx * dx * dx / sqrt(2.0) : 0.5 * sqrt(3.0) * dx * dx * h;
        int vbad = 0, outside = 0;
        double zmid = 0.5 * dx; /* 2D: z = (lo + hi)/2 */
        for (int i = 0; i < b->n; i++) {
            if (fabs(b->V[i] - Vwant) > 1e-12 * Vwant) vbad++;
            const double *X = b->X + 3 * i;
            double hi[3] = {20.3 * dx, 17.6 * dx, 15.2 * dx};
            for (int d = 0; d < dim; d++)
                if (X[d] < -1e-12 || X[d] > hi[d] + 1e-12) outside++;
            if (dim == 2 && fabs(X[2] - zmid) > 1e-15) outside++;
        }
        CHECK(vbad == 0, "%dD: %d points with V != %s", dim, vbad, dim == 3 ? "dx^3/sqrt(2)" : "sqrt(3)/2 dx^2 h");
        CHECK(outside == 0, "%dD: %d points outside the box", dim, outside);
        /* the lattice is centred: the gaps at the two ends of every axis are equal */
        double bhi[3] = {20.3 * dx, 17.6 * dx, 15.2 * dx};
        for (int d = 0; d < dim; d++) {
            double mn = INFINITY, mx = -INFINITY;
            for (int i = 0; i < b->n; i++) { mn = fmin(mn, b->X[3 * i + d]); mx = fmax(mx, b->X[3 * i + d]); }
            CHECK(fabs(mn - (bhi[d] - mx)) < 1e-9 * dx && mn > 0, "%dD axis %d: gaps %g and %g dx (centred)", dim, d,
                  mn / dx, (bhi[d] - mx) / dx);
        }
        /* nearest distance dx everywhere; an interior point has 6 (2D) / 12 (3D) at dx */
        double dmin = INFINITY;
        for (int64_t k = 0; k < b->nbond; k++) dmin = fmin(dmin, b->len[k]);
        CHECK_NEAR(dmin, dx, 1e-9, dim == 3 ? "3D HCP: nearest distance / dx" : "2D triangular: nearest distance");
        /* the partial-volume factor is the same linear one as on the cubic lattice */
        int vfbad = 0;
        for (int64_t k = 0; k < b->nbond; k++) {
            double L = b->len[k], want = L <= b->delta - 0.5 * dx ? 1.0 : (b->delta + 0.5 * dx - L) / dx;
            if (fabs(b->vfac[k] - want) > 1e-6) vfbad++;
        }
        CHECK(vfbad == 0, "%dD: %d bonds with a partial-volume factor off the linear rule", dim, vfbad);
        double c[3] = {10 * dx, 8.8 * dx, dim == 3 ? 7.6 * dx : zmid};
        int ic = nearest_point(b, c), nn = 0, fam = 0;
        for (int j = 0; j < b->n; j++) {
            if (j == ic) continue;
            double d[3];
            floe_v3_sub(d, b->X + 3 * j, b->X + 3 * ic);
            double L = floe_v3_norm(d);
            nn += fabs(L - dx) < 1e-9 * dx;
            fam += L <= b->delta + 1e-9 * dx;
        }
        CHECK(nn == (dim == 3 ? 12 : 6), "%dD: interior point has %d nearest neighbours (want %d)", dim, nn,
              dim == 3 ? 12 : 6);
        int *cnt = malloc((size_t)b->n * sizeof *cnt);
        floe_pd_family_sizes(b, cnt);
        CHECK(cnt[ic] == fam, "%dD: family of the interior point %d, brute force %d", dim, cnt[ic], fam);
        free(cnt);
        /* HCP: the second shell at sqrt(2) dx has 6 points (FCC would have 6 too, but HCP
         * has 2 at sqrt(8/3) dx where FCC has none: the stacking is ABAB) */
        if (dim == 3) {
            int n83 = 0;
            for (int j = 0; j < b->n; j++) {
                double d[3];
                floe_v3_sub(d, b->X + 3 * j, b->X + 3 * ic);
                n83 += fabs(floe_v3_norm(d) - sqrt(8.0 / 3.0) * dx) < 1e-9 * dx;
            }
            CHECK(n83 == 2, "3D: %d neighbours at sqrt(8/3) dx (HCP: 2, FCC: 0)", n83);
        }
        double vb = dim == 3 ? 20.3 * 17.6 * 15.2 * dx * dx * dx : 20.3 * 17.6 * dx * dx * h;
        char what[96];
        snprintf(what, sizeof what, "%dD box (%d points, family %d): sum V / box volume", dim, b->n, fam);
        CHECK_NEAR(total_volume(b) / vb, 1.0, 0.04, what);
        floe_pd_body_destroy(b);
    }
    /* a sphere (3D) and a disc (2D) as SDF regions, radius 8 dx */
    for (int dim = 2; dim <= 3; dim++) {
        const double R = 8 * dx;
        double sph[5] = {10 * dx, 10 * dx, dim == 3 ? 10 * dx : 0.5 * dx, R, dim == 3 ? 1 : 0};
        double lo[3] = {0, 0, 0}, hi[3] = {20 * dx, 20 * dx, dim == 3 ? 20 * dx : dx};
        floe_pd_body *b = make_region(dim, FLOE_PD_LATTICE_HEXAGONAL, dx, 3, lo, hi, sphere_sdf, sph);
        if (!b) continue;
        int bad = 0;
        for (int i = 0; i < b->n; i++) bad += sphere_sdf(b->X + 3 * i, sph) > 0;
        CHECK(bad == 0, "%dD: %d points outside the SDF region", dim, bad);
        double vs = dim == 3 ? 4.0 / 3.0 * M_PI * R * R * R : M_PI * R * R * dx;
        char what[96];
        snprintf(what, sizeof what, "%s r = 8 dx (%d points): sum V / volume", dim == 3 ? "3D sphere" : "2D disc",
                 b->n);
        CHECK_NEAR(total_volume(b) / vs, 1.0, 0.04, what);
        floe_pd_body_destroy(b);
        /* the cubic lattice on the same region, for comparison */
        b = make_region(dim, FLOE_PD_LATTICE_CUBIC, dx, 3, lo, hi, sphere_sdf, sph);
        if (b) printf("  (cubic lattice, same region: sum V / volume %.4f)\n", total_volume(b) / vs);
        floe_pd_body_destroy(b);
    }
    /* a bad lattice value is refused */
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.hi[0] = r.hi[1] = r.hi[2] = 5 * dx;
    r.lattice = 7;
    floe_pd_body *nb = (floe_pd_body *)&r;
    CHECK(floe_pd_body_create(&nb, &r) == FLOE_EINVAL && nb == NULL, "lattice 7 refused");
    r.lattice = FLOE_PD_LATTICE_HEXAGONAL;
    r.hi[2] = 0.5 * dx; /* less than one layer pitch */
    CHECK(floe_pd_body_create(&nb, &r) == FLOE_EINVAL && nb == NULL, "hexagonal box thinner than a layer refused");
}

/* --------------------------------------------------- horizon quadrature ---- */
/* The PMB micromodulus and the LPS weighted volume come from continuum integrals over the
 * horizon; the lattice enters only through the quadrature sum_j beta V_j (.) over the family
 * of an interior point. Compared with the integrals (delta = 3 dx):
 *   volume            sum beta V_j             = pi delta^2 h (2D) | 4/3 pi delta^3 (3D)
 *   PMB stiffness     sum beta V_j |xi| n_x^4  = pi h delta^3/4    | pi delta^4/5 (the
 *                     uniaxial energy density that c = 9E/(pi h delta^3), 18K/(pi delta^4) matches)
 *   LPS m (w = 1)     sum beta V_j |xi|^2      = pi h delta^4/2    | 4/5 pi delta^5
 * and the isotropy of the PMB stiffness (n_x^4 against n_y^4, n_z^4). */
static void quadrature(int dim, int lattice, double out[5])
{
    const double dx = 1e-3;
    floe_pd_body *b = make_box(dim, lattice, dx, 3, 16, 16, dim == 3 ? 16 : 1);
    if (!b) return;
    double c[3] = {8 * dx, 8 * dx, dim == 3 ? 8 * dx : 0.5 * dx};
    int ic = nearest_point(b, c);
    double sv = 0, s4[3] = {0, 0, 0}, sm = 0;
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            if (i != ic && j != ic) continue;
            int o = i == ic ? j : i;
            double d[3], L = b->len[k], w = b->vfac[k] * b->V[o];
            floe_v3_sub(d, b->X + 3 * o, b->X + 3 * ic);
            sv += w;
            sm += w * L * L;
            for (int a = 0; a < 3; a++) s4[a] += w * L * pow(d[a] / L, 4);
        }
    double dl = b->delta, h = b->thickness;
    out[0] = sv / (dim == 3 ? 4.0 / 3.0 * M_PI * dl * dl * dl : M_PI * dl * dl * h);
    out[1] = s4[0] / (dim == 3 ? M_PI * pow(dl, 4) / 5 : M_PI * h * pow(dl, 3) / 4);
    out[2] = sm / (dim == 3 ? 0.8 * M_PI * pow(dl, 5) : 0.5 * M_PI * h * pow(dl, 4));
    out[3] = s4[1] / s4[0];
    out[4] = dim == 3 ? s4[2] / s4[0] : 1.0;
    floe_pd_body_destroy(b);
}

static void test_quadrature(void)
{
    printf("interior horizon quadrature / continuum integral (delta = 3 dx, linear beta)\n");
    for (int dim = 2; dim <= 3; dim++) {
        double hx[5] = {0}, cu[5] = {0};
        quadrature(dim, FLOE_PD_LATTICE_HEXAGONAL, hx);
        quadrature(dim, FLOE_PD_LATTICE_CUBIC, cu);
        printf("  %dD            volume   PMB n_x^4   LPS m   y/x   z/x\n", dim);
        printf("  hexagonal   %7.4f   %7.4f   %7.4f   %.4f %.4f\n", hx[0], hx[1], hx[2], hx[3], hx[4]);
        printf("  cubic       %7.4f   %7.4f   %7.4f   %.4f %.4f\n", cu[0], cu[1], cu[2], cu[3], cu[4]);
        char what[96];
        /* The linear beta (cut at |xi| = delta) loses part of the outer shell on any
         * lattice: the cubic lattice is 9-16 % low in 3D, which the PMB surface correction
         * and the LPS calibration absorb. The hexagonal lattice must be in the same band
         * (within 20 % of the continuum and no more than 8 % below the cubic figure). */
        const char *name[3] = {"family volume", "PMB stiffness sum", "LPS weighted volume"};
        for (int q = 0; q < 3; q++) {
            snprintf(what, sizeof what, "%dD hex: %s / continuum", dim, name[q]);
            CHECK_NEAR(hx[q], 1.0, 0.20, what);
            CHECK(hx[q] > cu[q] - 0.08, "%dD %s: hexagonal %.4f, cubic %.4f", dim, name[q], hx[q], cu[q]);
        }
        /* in-plane isotropy of the triangular layers: n_y^4 sum equals the n_x^4 sum */
        snprintf(what, sizeof what, "%dD hex: stiffness y / x (in-plane isotropy)", dim);
        CHECK_NEAR(hx[3], 1.0, 0.02, what);
    }
}

/* ---------------------------------------------------- velocity Verlet ---- */
typedef struct vv {
    floe_pd_body *b;
    double *x, *v, *f, *mass;
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
    floe_pd_forces(s->b, s->x, s->f);
}
static void vv_step(vv *s, double dt, const unsigned char *fixed)
{
    int n3 = 3 * s->b->n;
    for (int i = 0; i < n3; i++) {
        if (!fixed[i]) s->v[i] += 0.5 * dt * s->f[i] / s->mass[i / 3];
        s->x[i] += dt * s->v[i];
    }
    vv_force(s);
    for (int i = 0; i < n3; i++)
        if (!fixed[i]) s->v[i] += 0.5 * dt * s->f[i] / s->mass[i / 3];
}

/* ------------------------------------------------------------ wave speed ---- */
/* As tests/test_pd.c: a bar along x whose points with X < 3 dx are driven at v0 from t = 0;
 * the front (layer-averaged v_x crossing v0/2; layers are bins of width dx in x, each holds
 * one point per row) is located at two times and its speed compared with sqrt(E/rho): 3D
 * PMB nu = 1/4, E = 1.5 K; 2D plane-stress PMB E given (nu = 1/3). Surface correction on. */
static double wave_ratio(int dim, int lattice, double ny, int nx)
{
    const double dx = 1e-3, rho = 2000, K = 1e9, v0 = 1e-3;
    floe_pd_body *b = make_box(dim, lattice, dx, 3, nx, ny, dim == 3 ? ny : 1);
    if (!b) return 0;
    floe_pd_material mat = floe_pd_material_pmb(rho, K, 0);
    CHECK(floe_pd_set_material(b, &mat) == FLOE_OK, "PMB material");
    CHECK(floe_pd_surface_correction(b) == FLOE_OK, "surface correction");
    double cb = sqrt(mat.E / rho);
    vv s;
    vv_init(&s, b);
    unsigned char *fix = calloc(3 * (size_t)b->n, 1);
    for (int i = 0; i < b->n; i++)
        if (b->X[3 * i] < 3 * dx) { fix[3 * i] = fix[3 * i + 1] = fix[3 * i + 2] = 1; s.v[3 * i] = v0; }
    double *lay = calloc((size_t)nx + 2, sizeof *lay);
    int *cnt = calloc((size_t)nx + 2, sizeof *cnt);
    for (int i = 0; i < b->n; i++) cnt[(int)(b->X[3 * i] / dx)]++;
    double dt = 0.5 * floe_pd_dt_nodal(b), t = 0;
    double tm[2] = {0.25 * nx * dx / cb, 0.6 * nx * dx / cb}, pos[2] = {0, 0};
    vv_force(&s);
    for (int k = 0; k < 2;) {
        vv_step(&s, dt, fix);
        t += dt;
        if (t < tm[k]) continue;
        memset(lay, 0, ((size_t)nx + 2) * sizeof *lay);
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
    free(fix); free(lay); free(cnt);
    vv_free(&s);
    floe_pd_body_destroy(b);
    return c / cb;
}

static void test_wave(void)
{
    printf("wave speed in a bar on the hexagonal lattice (PMB, surface correction, delta = 3 dx)\n");
    double r2 = wave_ratio(2, FLOE_PD_LATTICE_HEXAGONAL, 10, 400);
    CHECK_NEAR(r2, 1.0, 0.03, "2D triangular strip 400 x 10 dx: c / sqrt(E/rho)");
    /* measured: a 6 x 6 dx HCP bar (delta = half its width) is 2.7-3.1 % fast (cubic
     * lattice 1.4-1.7 %), an 8 x 8 dx bar 1.2 %: the surface correction of a thin bar */
    double r3 = wave_ratio(3, FLOE_PD_LATTICE_HEXAGONAL, 8, 160);
    CHECK_NEAR(r3, 1.0, 0.03, "3D HCP bar 160 x 8 x 8 dx: c / sqrt(E/rho)");
}

/* ------------------------------------------------ quasi-static tension ---- */
/* As tests/test_pd.c: a block nx x ny x ny dx, the x displacement of the end slabs
 * (X < 3 dx, X > (nx - 3) dx) prescribed u_x = eps (X - x_c), every other dof free;
 * static equilibrium by matrix-free conjugate gradients on the linearised stiffness. In the
 * core (at least delta from the lateral faces of the point cloud, middle half in x) eps_x,
 * eps_y, eps_z are least-squares slopes of the displacements, nu = -eps_lat/eps_x. The
 * stress is the bond virial of the core points, sigma_i = 1/(2 V_i) sum_j F_ij (xi_ij)_x
 * (F_ij the force on i through bond ij, floe_pd_bond_forces): for a uniform strain it is
 * exactly dW/deps (forces = -grad E), and unlike a flux through a plane patch it needs no
 * lattice-aligned patch edges. E = sigma_xx / eps_x. */
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

typedef struct virial_ctx {
    const floe_pd_body *b;
    const unsigned char *core;
    double *sxx; /* per point */
} virial_ctx;

static void virial_visit(int i, int j, int64_t k, const double f[3], void *user)
{
    (void)k;
    virial_ctx *C = user;
    const double *Xi = C->b->X + 3 * i, *Xj = C->b->X + 3 * j;
    double fx = f[0] * (Xj[0] - Xi[0]); /* F_ij (xi)_x, the same seen from j */
    if (C->core[i]) C->sxx[i] += 0.5 * fx / C->b->V[i];
    if (C->core[j]) C->sxx[j] += 0.5 * fx / C->b->V[j];
}

static void tension(const floe_pd_material *m, int lattice, double mh, int nx, int ny, double *E_ratio,
                    double *nu_y, double *nu_z, double *resid)
{
    const double dx = 1e-3, eps = 1e-4;
    floe_pd_body *b = make_box(3, lattice, dx, mh, nx, ny, ny);
    if (!b) return;
    CHECK(floe_pd_set_material(b, m) == FLOE_OK, "material");
    CHECK(floe_pd_surface_correction(b) == FLOE_OK, "correction");
    int n3 = 3 * b->n;
    tens_ctx c = {b, malloc(n3 * sizeof(double)), malloc(n3 * sizeof(double))};
    unsigned char *fix = calloc(n3, 1), *core = calloc((size_t)b->n, 1);
    double *u = calloc(n3, sizeof *u), *r = malloc(n3 * sizeof *r), *p = malloc(n3 * sizeof *p),
           *Ap = malloc(n3 * sizeof *Ap), *sxx = calloc((size_t)b->n, sizeof *sxx);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, ctr[3];
    for (int i = 0; i < b->n; i++)
        for (int d = 0; d < 3; d++) {
            lo[d] = fmin(lo[d], b->X[3 * i + d]);
            hi[d] = fmax(hi[d], b->X[3 * i + d]);
        }
    for (int d = 0; d < 3; d++) ctr[d] = 0.5 * (lo[d] + hi[d]);
    double xc = ctr[0];
    for (int i = 0; i < b->n; i++) {
        double X = b->X[3 * i];
        if (X < 3 * dx || X > (nx - 3) * dx) { fix[3 * i] = 1; u[3 * i] = eps * (X - xc); }
    }
    kmul(&c, u, r, fix);
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
    /* core: least-squares slopes */
    double sx = 0, sxx_ = 0, sux = 0, su = 0;
    double sy[2] = {0, 0}, syy[2] = {0, 0}, suy[2] = {0, 0}, sv[2] = {0, 0};
    int cn = 0;
    for (int i = 0; i < b->n; i++) {
        const double *X = b->X + 3 * i;
        if (fabs(X[0] - xc) > 0.25 * nx * dx) continue;
        int in = 1;
        for (int d = 1; d < 3; d++)
            if (X[d] < lo[d] + b->delta || X[d] > hi[d] - b->delta) in = 0;
        if (!in) continue;
        core[i] = 1;
        cn++;
        double ax = X[0] - xc;
        sx += ax; sxx_ += ax * ax; sux += ax * u[3 * i]; su += u[3 * i];
        for (int d = 1; d < 3; d++) {
            double ay = X[d] - ctr[d];
            sy[d - 1] += ay; syy[d - 1] += ay * ay; suy[d - 1] += ay * u[3 * i + d]; sv[d - 1] += u[3 * i + d];
        }
    }
    double ex = (sux - sx * su / cn) / (sxx_ - sx * sx / cn), el[2];
    for (int d = 0; d < 2; d++) el[d] = (suy[d] - sy[d] * sv[d] / cn) / (syy[d] - sy[d] * sy[d] / cn);
    virial_ctx V = {b, core, sxx};
    floe_pd_bond_forces(b, c.x, virial_visit, &V);
    double sig = 0;
    for (int i = 0; i < b->n; i++) sig += core[i] ? sxx[i] : 0;
    sig /= cn;
    *E_ratio = sig / ex / m->E;
    *nu_y = -el[0] / ex;
    *nu_z = -el[1] / ex;
    printf("  %d points, CG %d it, residual %.1e, core %d points, eps_x %.4g (applied %.4g)\n", b->n, it,
           *resid, cn, ex, eps);
    free(c.x); free(c.f); free(fix); free(core); free(u); free(r); free(p); free(Ap); free(sxx);
    floe_pd_body_destroy(b);
}

static void test_tension(void)
{
    printf("quasi-static tension on the HCP lattice: interior E and nu (block 20 x 11 x 11 dx, delta = 3 dx)\n");
    const double E = 1e9, nu0 = 0.3;
    double Er, ny, nz, res;
    for (int infl = 0; infl < 2; infl++) {
        floe_pd_material m = floe_pd_material_lps(1000, E / (3 * (1 - 2 * nu0)), E / (2 * (1 + nu0)), 0,
                                                  infl ? FLOE_PD_W_GAUSS : FLOE_PD_W_ONE);
        char what[96];
        tension(&m, FLOE_PD_LATTICE_HEXAGONAL, 3, 20, 11, &Er, &ny, &nz, &res);
        CHECK(res < 1e-3, "equilibrium residual %.3g", res);
        snprintf(what, sizeof what, "LPS nu=0.3 %s, HCP: E_int / E", infl ? "gauss" : "w=1");
        CHECK_NEAR(Er, 1.0, 0.05, what);
        snprintf(what, sizeof what, "LPS nu=0.3 %s, HCP: nu_int (in-plane y)", infl ? "gauss" : "w=1");
        CHECK_NEAR(ny, nu0, 0.05, what);
        snprintf(what, sizeof what, "LPS nu=0.3 %s, HCP: nu_int (stacking axis z)", infl ? "gauss" : "w=1");
        CHECK_NEAR(nz, nu0, 0.05, what);
    }
    /* PMB (bond-based: nu = 1/4 for an isotropic family), surface corrected */
    floe_pd_material pm = floe_pd_material_pmb(1000, E / 1.5, 0);
    tension(&pm, FLOE_PD_LATTICE_HEXAGONAL, 3, 20, 11, &Er, &ny, &nz, &res);
    CHECK(res < 1e-3, "equilibrium residual %.3g", res);
    CHECK_NEAR(Er, 1.0, 0.05, "PMB HCP delta = 3 dx, surface corrected: E_int / E");
    /* bond-based PD on HCP is transversely isotropic at a finite horizon (the family's
     * n_z^4 sum is 4.6 % above n_x^4 at delta = 3 dx): nu towards the stacking axis is
     * low, and both tend to 1/4 as delta/dx grows */
    CHECK_NEAR(ny, 0.25, 0.10, "PMB HCP delta = 3 dx: nu_int (in-plane y)");
    CHECK_NEAR(nz, 0.25, 0.12, "PMB HCP delta = 3 dx: nu_int (stacking axis z)");
    tension(&pm, FLOE_PD_LATTICE_HEXAGONAL, 4, 24, 14, &Er, &ny, &nz, &res); /* a core delta from the faces */
    CHECK_NEAR(Er, 1.0, 0.05, "PMB HCP delta = 4 dx: E_int / E");
    CHECK_NEAR(ny, 0.25, 0.05, "PMB HCP delta = 4 dx: nu_int (in-plane y)");
    CHECK_NEAR(nz, 0.25, 0.05, "PMB HCP delta = 4 dx: nu_int (stacking axis z)");
    tension(&pm, FLOE_PD_LATTICE_CUBIC, 3, 20, 11, &Er, &ny, &nz, &res);
    printf("  (cubic lattice, PMB, same block: E_int/E %.4f, nu_y %.4f, nu_z %.4f)\n", Er, ny, nz);
    /* the same measurement on the cubic lattice (printed for comparison) */
    floe_pd_material m = floe_pd_material_lps(1000, E / (3 * (1 - 2 * nu0)), E / (2 * (1 + nu0)), 0, FLOE_PD_W_ONE);
    tension(&m, FLOE_PD_LATTICE_CUBIC, 3, 20, 11, &Er, &ny, &nz, &res);
    printf("  (cubic lattice, LPS w=1, same block: E_int/E %.4f, nu_y %.4f, nu_z %.4f)\n", Er, ny, nz);
}

/* ---------------------------------------------------------------- scene ---- */
#define SCENE_HEAD                                                                     \
    "time: {duration: 0.01}\n"                                                         \
    "materials:\n"                                                                     \
    "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"                  \
    "laws:\n"                                                                          \
    "  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n" \
    "peridynamics:\n"

static void test_scene(void)
{
    printf("scene key lattice\n");
    char text[2048], err[1024];
    for (int dim = 2; dim <= 3; dim++) {
        snprintf(text, sizeof text,
                 "dimension: %d\n" SCENE_HEAD
                 "  - region: {box: {min: [0, 0, 0], max: [0.01, 0.01, 0.004]}}\n"
                 "    spacing: 0.001\n"
                 "    lattice: hexagonal\n"
                 "    material: {model: pmb, density: 2200, bulk_modulus: 14.9e9, critical_stretch: 0.001}\n"
                 "    contact_material: glass\n",
                 dim);
        floe_world *w = NULL;
        floe_scene_info info;
        int rc = floe_scene_load_ex("t.yaml", text, NULL, 0, &w, &info, err, sizeof err);
        CHECK(rc == FLOE_OK, "%dD hexagonal scene loads: %s", dim, rc ? err : "");
        if (rc != FLOE_OK) continue;
        int first = -1;
        floe_pd_body *b = floe_world_pd_body(w, 0, &first);
        CHECK(b != NULL, "the PD body is there");
        if (b) {
            double dx = 1e-3;
            double Vw = dim == 3 ? dx * dx * dx / sqrt(2.0) : 0.5 * sqrt(3.0) * dx * dx * dx;
            double vb = dim == 3 ? 0.01 * 0.01 * 0.004 : 0.01 * 0.01 * dx;
            CHECK(fabs(b->V[0] - Vw) < 1e-9 * Vw, "%dD: V = %g (want %g)", dim, b->V[0], Vw);
            printf("  %dD scene: %d points, sum V / box %.4f\n", dim, b->n, total_volume(b) / vb);
            CHECK_NEAR(total_volume(b) / vb, 1.0, 0.05, "scene body (10 x 10 dx): sum V / box volume");
        }
        floe_world_destroy(w);
    }
    /* explicit cubic keeps the old lattice; an unknown value is refused with a suggestion */
    const char *fmt = "dimension: 3\n" SCENE_HEAD
                      "  - region: {box: {min: [0, 0, 0], max: [0.01, 0.01, 0.004]}}\n"
                      "    spacing: 0.001\n"
                      "    lattice: %s\n"
                      "    material: {model: pmb, density: 2200, bulk_modulus: 14.9e9, critical_stretch: 0.001}\n"
                      "    contact_material: glass\n";
    snprintf(text, sizeof text, fmt, "cubic");
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_ex("t.yaml", text, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && w && floe_world_pd_body(w, 0, NULL) && floe_world_pd_body(w, 0, NULL)->n == 400,
          "lattice: cubic gives the 10 x 10 x 4 cubic body: %s", rc ? err : "");
    floe_world_destroy(w);
    snprintf(text, sizeof text, fmt, "hexgonal");
    w = (floe_world *)1;
    rc = floe_scene_load_ex("t.yaml", text, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc != FLOE_OK && w == NULL, "unknown lattice refused");
    printf("  %s\n", err);
    CHECK(strstr(err, "t.yaml:10:14:") == err, "message located at the value: '%s'", err);
    CHECK(strstr(err, "lattice") && strstr(err, "did you mean 'hexagonal'?"), "did-you-mean message: '%s'", err);
}

int main(void)
{
    double t0 = now_s();
    test_geometry();
    test_quadrature();
    test_scene();
    test_wave();
    test_tension();
    printf("total %.2f s\n", now_s() - t0);
    return check_summary("test_pd_hex");
}
