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
#include "../peridynamics/floe_pd.h"

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
    printf("  bond storage: %zu bytes per bond (partner int32, |xi| double, factor float, "
           "flag byte), bonds stored once\n", floe_pd_bytes_per_bond());
}

int main(void)
{
    double t0 = now_s();
    (void)urand;
    test_families();
    printf("total %.2f s\n", now_s() - t0);
    return check_summary("test_pd");
}
