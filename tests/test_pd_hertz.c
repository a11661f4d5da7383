/* test_pd_hertz.c - Hertz contact on a peridynamic half-space through the hybrid PD-DEM
 * contact (000 §4.1, Fig. 6, Table 1): a rigid sphere R = 5 cm pressed quasi-statically
 * into a 45 x 45 x 22.5 cm PD block (dx = 1.5 cm: 30 x 30 x 15 points, E = 1e8 Pa,
 * nu = 0.25, rho = 1100, delta = 2 dx) to a penetration of 1 cm, PMB and LPS; the force on
 * the sphere against the Hertz solution F = 4/3 E* sqrt(R) d^(3/2), E* = E/(1 - nu^2)
 * (rigid sphere on an elastic half-space).
 *
 * Set-up. The sphere is a kinematic particle above the centre of the block (between the
 * four central top points) moving down at v = 0.5 m/s (v/c_P = 1.5e-3); its contact with
 * the points is Hertz-Mindlin with the DEM parameters of Table 1 (E_c = 1e8 Pa, nu_c = 0.25
 * for both, no friction). The bottom layer of points is held; the sides are free.
 * Quasi-static: mass-proportional damping f = -2 omega_1 m v on the PD points
 * (omega_1 = pi c_P / (2 H), the lowest axial mode of the block held at the bottom: critically
 * damped); ten times slower (0.05 m/s, dt 0.2 x critical instead of 0.6 x) changes the
 * fitted exponent by 0.005 and the force at 1 cm by 0.5 % (PMB) and 0.8 % (LPS). The penetration d is
 * the sphere's travel since it first touched the contact spheres of the top points
 * (R_PD = (3V/4 pi)^(1/3) = 0.93 cm); as in 000 the force is sampled every 0.05 cm to 1 cm.
 *
 * Checks: the exponent of a least-squares fit of log F against log d over the 20 samples
 * is 1.5 +- 0.2 for both materials (the target); the ratio F/F_Hertz is printed at
 * each depth and asserted in [0.4, 1.0] at 1 cm: 000 reports (Fig. 6; no numbers in the
 * text) that both PD materials fall BELOW the analytic curve without calibration of the
 * contact parameters; the lower bound rejects a contact more than 60 % too soft. Measured
 * (dx 1.5 cm): exponent 1.50 (PMB) and 1.50 (LPS), ratio 0.62 and 0.61 at 1 cm. Both
 * materials give nearly the same curve: the compliance is mostly in the point contacts
 * (Hertz-Mindlin with E_c = E between the sphere and a point of radius 0.93 cm), not in
 * the PD body.
 *
 *   test_pd_hertz [DX_CM=1.5 [V=0.5 [DT_SAFETY=0.6 [CENTRED=1]]]]
 *   (CENTRED=0: the sphere above the central top point instead; the lattice then enters
 *   contact by rings and the fitted exponent is 2.1)
 */
#include "check.h"
#include "floe.h"
#include "floe_pd.h"
#include "floe.h"
#include "world_read.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double E = 1e8, NU = 0.25, RHO = 1100, RS = 0.05, LX = 0.45, LZ = 0.225;
static double VZ = 0.5, SAFETY = 0.6;
static int CENTRED = 1;

static void hold(double t, double v[3], double w[3], void *user)
{
    (void)t; (void)user;
    floe_v3_set(v, 0, 0, 0);
    floe_v3_set(w, 0, 0, 0);
}

typedef struct { int first, n; double c; } damping;

static void damp(const floe_world *w, int i, double t, double f[3], double torque[3], void *user)
{
    (void)t; (void)torque;
    const damping *d = user;
    if (i < d->first || i >= d->first + d->n) return;
    for (int a = 0; a < 3; a++) f[a] -= d->c * pview(w).mass[i] * pview(w).v[3 * i + a];
}

/* runs one material; returns the fitted exponent, *ratio1 = F/F_Hertz at 1 cm */
static double run(int model, double dx, double *ratio1)
{
    char err[256];
    floe_world_def def = floe_default_world_def();
    floe_v3_set(def.gravity, 0, 0, 0);
    def.dt_safety = SAFETY;
    floe_world *w = floe_world_create(&def, err, sizeof err);
    floe_material mc = {"pd", RHO, E, NU};
    int mat = floe_world_add_material(w, &mc);
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&mc, &mc, 0.9, 0.0));

    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.horizon_factor = 2;
    floe_v3_set(r.lo, -0.5 * LX, -0.5 * LX, -LZ);
    floe_v3_set(r.hi, 0.5 * LX, 0.5 * LX, 0);
    floe_pd_body *b = NULL;
    CHECK(floe_pd_body_create(&b, &r) == FLOE_OK, "discretise");
    const double K = E / (3 * (1 - 2 * NU)), G = E / (2 * (1 + NU));
    floe_pd_material pm = model == FLOE_PD_PMB ? floe_pd_material_pmb(RHO, K, 0)
                                               : floe_pd_material_lps(RHO, K, G, 0, FLOE_PD_W_ONE);
    CHECK(floe_pd_set_material(b, &pm) == FLOE_OK && floe_pd_surface_correction(b) == FLOE_OK, "material");
    int first = 0, n = b->n;
    double zmax = -INFINITY, zmin = INFINITY;
    for (int i = 0; i < n; i++) {
        zmax = fmax(zmax, b->X[3 * i + 2]);
        zmin = fmin(zmin, b->X[3 * i + 2]);
    }
    /* the top point nearest the centre */
    int top = -1;
    double best = INFINITY;
    for (int i = 0; i < n; i++) {
        const double *X = b->X + 3 * i;
        double c = X[0] * X[0] + X[1] * X[1];
        if (X[2] > zmax - 0.5 * dx && c < best) { best = c; top = i; }
    }
    double Xtop[3];
    memcpy(Xtop, b->X + 3 * top, sizeof Xtop);
    const double Rp = cbrt(3.0 * b->V[top] / (4.0 * M_PI));
    CHECK(floe_world_add_pd_body(w, b, mat, NULL, &first) == FLOE_OK, "add body: %s", floe_world_last_error(w));
    int nheld = 0;
    for (int i = 0; i < n; i++)
        if (floe_world_pd_body(w, 0, NULL)->X[3 * i + 2] < zmin + 0.5 * dx) { floe_world_set_motion(w, first + i, hold, NULL); nheld++; }
    /* the sphere, 0.2 mm above first contact, over the centre (CENTRED) or the top point */
    const double gap = 2e-4;
    int gs = floe_world_add_geometry(w, floe_sphere_create(RS));
    floe_particle_def s = floe_default_particle_def();
    s.geometry = gs;
    s.material = mat;
    s.motion = FLOE_KINEMATIC;
    floe_v3_set(s.x, Xtop[0], Xtop[1], Xtop[2] + Rp + RS + gap);
    if (CENTRED) { /* touching the four central top points at once */
        double h2 = (Rp + RS) * (Rp + RS) - Xtop[0] * Xtop[0] - Xtop[1] * Xtop[1];
        floe_v3_set(s.x, 0, 0, Xtop[2] + sqrt(h2) + gap);
    }
    floe_v3_set(s.v, 0, 0, -VZ);
    int sp = floe_world_add_particle(w, &s);
    /* critical mass-proportional damping of the lowest axial mode */
    const double cP = sqrt((model == FLOE_PD_PMB ? K : K + 4.0 / 3.0 * G) / RHO);
    damping dm = {first, n, 2.0 * M_PI * cP / (2.0 * LZ)};
    floe_world_set_body_force(w, damp, &dm);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    const double dt = floe_world_dt(w), z0 = s.x[2] - gap;
    const double dmax = 0.0101;
    long steps = (long)((gap + dmax) / VZ / dt) + 1;
    /* samples at d = 0.05, 0.10, ... 1.00 cm */
    enum { NS = 20 };
    double Fs[NS], ds[NS];
    int ns = 0;
    for (long k = 0; k < steps && ns < NS; k++) {
        if (floe_world_step(w) != FLOE_OK) { CHECK(0, "step: %s", floe_world_last_error(w)); break; }
        double d = z0 - pview(w).x[3 * sp + 2];
        if (d >= 0.0005 * (ns + 1) - 1e-12) {
            ds[ns] = d;
            Fs[ns] = pview(w).f[3 * sp + 2]; /* the contact force on the sphere (no other load) */
            ns++;
        }
    }
    const double Estar = E / (1 - NU * NU);
    printf("%s: %d points (dx %.3g cm, %lld bonds), %d held, dt %.3g s, %ld steps, damping %.0f 1/s\n",
           model == FLOE_PD_PMB ? "PMB" : "LPS", n, dx * 100, (long long)floe_world_pd_body(w, 0, NULL)->nbond, nheld, dt, steps, dm.c);
    printf("  %8s %12s %12s %8s\n", "d [cm]", "F [N]", "F_Hertz [N]", "ratio");
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int nf = 0;
    *ratio1 = NAN;
    for (int k = 0; k < ns; k++) {
        double Fh = 4.0 / 3.0 * Estar * sqrt(RS) * pow(ds[k], 1.5);
        printf("  %8.3f %12.4g %12.4g %8.3f\n", ds[k] * 100, Fs[k], Fh, Fs[k] / Fh);
        if (Fs[k] > 0) {
            double x = log(ds[k]), y = log(Fs[k]);
            sx += x; sy += y; sxx += x * x; sxy += x * y;
            nf++;
        }
        if (k == ns - 1) *ratio1 = Fs[k] / Fh;
    }
    double slope = nf > 1 ? (nf * sxy - sx * sy) / (nf * sxx - sx * sx) : NAN;
    printf("  fitted exponent (d in [0.05, 1] cm, %d samples): %.3f; F/F_Hertz at %.2f cm: %.3f\n", nf, slope,
           ns ? ds[ns - 1] * 100 : 0, *ratio1);
    CHECK(ns == NS, "reached 1 cm (%d samples)", ns);
    floe_world_destroy(w);
    return slope;
}

int main(int argc, char **argv)
{
    double dx = (argc > 1 ? atof(argv[1]) : 1.5) * 0.01;
    if (argc > 2) VZ = atof(argv[2]);
    if (argc > 3) SAFETY = atof(argv[3]);
    if (argc > 4) CENTRED = atoi(argv[4]);
    for (int m = FLOE_PD_PMB; m <= FLOE_PD_LPS; m++) {
        double ratio;
        double p = run(m, dx, &ratio);
        const char *name = m == FLOE_PD_PMB ? "PMB" : "LPS";
        char what[64];
        snprintf(what, sizeof what, "%s Hertz exponent (1.5 +- 0.2)", name);
        CHECK_NEAR(p, 1.5, 0.2 / 1.5, what);
        CHECK(ratio >= 0.4 && ratio <= 1.0, "%s: F/F_Hertz at 1 cm = %.3f outside [0.4, 1.0]", name, ratio);
    }
    return check_summary("test_pd_hertz");
}
