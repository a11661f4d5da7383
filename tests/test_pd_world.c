/* test_pd_world.c - peridynamic bodies inside the world (floe_world_add_pd_body): bond
 * forces on the particle machinery, no contact between family members, contact with DEM
 * particles, the energy ledger across bond breakage, momentum. */
#include "check.h"
#include "floe_pd.h"
#include "floe.h"
#include "world_read.h"

#include <stdlib.h>
#include <string.h>

static floe_pd_body *bar(int nx, int ny, int nz, double dx, double s_c) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.horizon_factor = 3;
    floe_v3_set(r.lo, 0, 0, 0);
    floe_v3_set(r.hi, nx * dx, ny * dx, nz * dx);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) return NULL;
    floe_pd_material m = floe_pd_material_pmb(2200, 14.9e9, s_c); /* E = 22.35 GPa, nu = 1/4 */
    if (floe_pd_set_material(b, &m)) { floe_pd_body_destroy(b); return NULL; }
    return b;
}

static void momentum(const floe_world *w, double P[3]) {
    floe_v3_set(P, 0, 0, 0);
    for (int i = 0; i < pview(w).n; i++)
        if (pview(w).motion[i] == FLOE_FREE) floe_v3_axpy(P, pview(w).mass[i], pview(w).v + 3 * i);
}

static floe_world *new_world(int *mat) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    floe_v3_set(d.gravity, 0, 0, 0);
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rock", 2200, 22.35e9, 0.25};
    *mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, *mat, *mat, floe_hertz_mindlin_law_create(&m, &m, 0.8, 0.3));
    return w;
}

/* 1. an elastic pulse in a free bar: no contacts (all neighbours within reach are bonded),
 * momentum and energy conserved */
static void test_pulse(void) {
    int mat;
    floe_world *w = new_world(&mat);
    floe_pd_body *b = bar(30, 4, 4, 1e-3, 0);
    CHECK(b != NULL, "bar created");
    int first = -1;
    CHECK(floe_world_add_pd_body(w, b, mat, NULL, &first) == FLOE_OK, "add PD body: %s", floe_world_last_error(w));
    for (int i = 0; i < b->n; i++) /* the first three layers move at 0.1 m/s */
        if (b->X[3 * i] < 3e-3) set_vel(w, first + i, 0, 0.1);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    double P0[3], P1[3];
    momentum(w, P0);
    double dtn = floe_pd_dt_nodal(b);
    printf("  pulse: %d points, %lld bonds, dt %.3g s (nodal estimate %.3g s)\n", b->n, (long long)b->nbond,
           floe_world_dt(w), dtn);
    int maxc = 0, rc = 0;
    for (int s = 0; s < 1500 && !rc; s++) {
        rc = floe_world_step(w);
        if (floe_world_contact_count(w) > maxc) maxc = floe_world_contact_count(w);
    }
    CHECK(rc == FLOE_OK, "pulse run: %s", floe_world_last_error(w));
    momentum(w, P1);
    double err = floe_world_energy_balance_error(w);
    floe_energy e = floe_world_energy(w);
    printf("  pulse after 1500 steps: contacts (max) %d, momentum x %.6e -> %.6e, elastic %.3e J, kinetic %.3e J, "
           "balance error %.2e\n", maxc, P0[0], P1[0], e.elastic, e.kinetic_trans, err);
    CHECK(maxc == 0, "no contact force between bonded points (max contacts %d)", maxc);
    CHECK(fabs(P1[0] - P0[0]) <= 1e-12 * fabs(P0[0]) && fabs(P1[1]) + fabs(P1[2]) <= 1e-12 * fabs(P0[0]),
          "momentum conserved to 1e-12");
    CHECK(e.elastic > 0.05 * e.initial, "the pulse loads the bonds (elastic %.3g of initial %.3g)", e.elastic, e.initial);
    /* what is left is velocity Verlet's own energy error, second order in dt: 5.5e-4, 1.4e-4
     * and 3.5e-5 at safety 0.2, 0.1 and 0.05 (the trapezoid work equals the change of the
     * quadratic bond energy exactly, so the ledger books no dissipation) */
    CHECK(err < 1e-3, "energy balance of the PD bar %.2e < 1e-3 (Verlet, second order)", err);
    CHECK(fabs(e.dissipated) < 1e-9 * e.initial, "no dissipation booked without breakage (%.2e J)", e.dissipated);
    floe_world_destroy(w);
}

/* 2. a DEM sphere hits a free PD plate: contact through the sphere-sphere path with the
 * points' contact radius, momentum conserved, the sphere slowed */
static void test_impact(void) {
    int mat;
    floe_world *w = new_world(&mat);
    floe_pd_body *b = bar(16, 16, 4, 1e-3, 0);
    int first = -1;
    CHECK(b && floe_world_add_pd_body(w, b, mat, NULL, &first) == FLOE_OK, "add plate");
    int gs = floe_world_add_geometry(w, floe_sphere_create(3e-3));
    floe_particle_def s = floe_default_particle_def();
    s.geometry = gs;
    s.material = mat;
    /* top points at z = 3.5 mm, contact radius 0.62 mm: 20 um of gap */
    floe_v3_set(s.x, 7.5e-3, 7.5e-3, 3.5e-3 + 0.6204e-3 + 3e-3 + 0.02e-3); /* over a point */
    floe_v3_set(s.v, 0, 0, -1.0);
    int sp = floe_world_add_particle(w, &s);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    double P0[3], P1[3];
    momentum(w, P0);
    int maxc = 0, rc = 0;
    long steps = (long)(60e-6 / floe_world_dt(w));
    for (long k = 0; k < steps && !rc; k++) {
        rc = floe_world_step(w);
        if (floe_world_contact_count(w) > maxc) maxc = floe_world_contact_count(w);
    }
    CHECK(rc == FLOE_OK, "impact run: %s", floe_world_last_error(w));
    momentum(w, P1);
    double vz = pview(w).v[3 * sp + 2], err = floe_world_energy_balance_error(w);
    printf("  impact: %ld steps of %.3g s, sphere vz -1 -> %.4f m/s, max contacts %d, momentum z %.6e -> %.6e, "
           "balance error %.2e\n", steps, floe_world_dt(w), vz, maxc, P0[2], P1[2], err);
    CHECK(maxc > 0, "the sphere touches the plate's points");
    CHECK(vz > -0.9, "the plate slows the sphere (vz %.3f)", vz);
    CHECK(fabs(P1[2] - P0[2]) <= 1e-9 * fabs(P0[2]), "momentum conserved (%.3g)", fabs(P1[2] - P0[2]) / fabs(P0[2]));
    CHECK(err < 1e-3, "energy balance with contact and bonds %.2e < 1e-3", err);
    floe_world_destroy(w);
}

/* 3. a bar pulled apart at its ends breaks; the bond energy released at breakage is booked
 * as dissipated, so the balance still closes; fragments then move apart */
static void test_fracture(void) {
    int mat;
    floe_world *w = new_world(&mat);
    floe_pd_body *b = bar(30, 3, 3, 1e-3, 2e-3);
    int first = -1;
    CHECK(b && floe_world_add_pd_body(w, b, mat, NULL, &first) == FLOE_OK, "add bar");
    for (int i = 0; i < b->n; i++) set_vel(w, first + i, 0, b->X[3 * i] < 15e-3 ? -20.0 : 20.0);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    int rc = 0;
    long steps = (long)(20e-6 / floe_world_dt(w));
    for (long k = 0; k < steps && !rc; k++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "fracture run: %s", floe_world_last_error(w));
    double *phi = malloc(sizeof(double) * b->n), dmax = 0;
    CHECK(phi && floe_pd_damage(b, phi) == FLOE_OK, "damage");
    for (int i = 0; i < b->n; i++) dmax = fmax(dmax, phi[i]);
    free(phi);
    double gap = 0; /* mean velocity of the two halves */
    double vl = 0, vr = 0;
    int nl = 0, nr = 0;
    for (int i = 0; i < b->n; i++) {
        if (b->X[3 * i] < 15e-3) { vl += pview(w).v[3 * (first + i)]; nl++; }
        else { vr += pview(w).v[3 * (first + i)]; nr++; }
    }
    gap = vr / nr - vl / nl;
    floe_energy e = floe_world_energy(w);
    double err = floe_world_energy_balance_error(w);
    printf("  fracture: %lld of %lld bonds broken, max damage %.2f, halves separate at %.2f m/s, dissipated %.3e J "
           "(%.1f %% of the initial), balance error %.2e\n", (long long)b->nbroken, (long long)b->nbond, dmax, gap,
           e.dissipated, 100 * e.dissipated / e.initial, err);
    CHECK(b->nbroken > 0 && dmax > 0.3, "bonds break (%lld), damage %.2f", (long long)b->nbroken, dmax);
    CHECK(gap > 1.0, "the fragments move apart (%.2f m/s)", gap);
    CHECK(e.dissipated > 0, "breakage dissipates energy");
    CHECK(err < 1e-3, "energy balance across breakage %.2e < 1e-3", err);
    floe_world_destroy(w);
}

/* 4. correspondence output (000 eqs 26-30): for an affine motion x = F0 X the non-local
 * deformation gradient is F0 at every point (surface points too), E = (F0^T F0 - 1)/2, a
 * rigid rotation has no stress, and a uniaxial stretch gives the Neo-Hookean stress */
static void test_correspondence(void) {
    floe_pd_body *b = bar(6, 5, 4, 1e-3, 0);
    CHECK(b != NULL, "body");
    if (!b) return;
    int n = b->n;
    double *x = malloc(sizeof(double) * 3 * n), *F = malloc(sizeof(double) * 9 * n), *E = malloc(sizeof(double) * 9 * n);
    double *sg = malloc(sizeof(double) * 9 * n), *vm = malloc(sizeof(double) * n);
    const double F0[9] = {1.01, 0.02, -0.005, 0.003, 0.995, 0.01, -0.004, 0.006, 1.002};
    for (int i = 0; i < n; i++)
        for (int r = 0; r < 3; r++)
            x[3 * i + r] = 0.1 + F0[3 * r] * b->X[3 * i] + F0[3 * r + 1] * b->X[3 * i + 1] + F0[3 * r + 2] * b->X[3 * i + 2];
    int sing = -1;
    double G = 8e9, lam = 12e9;
    CHECK(floe_pd_correspondence(b, x, G, lam, F, E, sg, vm, &sing) == FLOE_OK, "correspondence");
    double eF = 0, eE = 0;
    for (int i = 0; i < n; i++)
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) {
                eF = fmax(eF, fabs(F[9 * i + 3 * r + c] - F0[3 * r + c]));
                double C = F0[r] * F0[c] + F0[3 + r] * F0[3 + c] + F0[6 + r] * F0[6 + c];
                eE = fmax(eE, fabs(E[9 * i + 3 * r + c] - 0.5 * (C - (r == c))));
            }
    printf("  correspondence, affine F0 on %d points (%d singular): max |F - F0| %.2e, max |E - E0| %.2e\n", n, sing, eF, eE);
    CHECK(sing == 0 && eF < 1e-12 && eE < 1e-12, "F and E exact for an affine motion");
    /* rigid rotation: no stress */
    double th = 0.3, cs = cos(th), sn = sin(th);
    for (int i = 0; i < n; i++) {
        const double *X = b->X + 3 * i;
        x[3 * i] = cs * X[0] - sn * X[1];
        x[3 * i + 1] = sn * X[0] + cs * X[1];
        x[3 * i + 2] = X[2];
    }
    floe_pd_correspondence(b, x, G, lam, NULL, NULL, NULL, vm, NULL);
    double vmax = 0;
    for (int i = 0; i < n; i++) vmax = fmax(vmax, vm[i]);
    CHECK(vmax < 1e-6 * G, "a rigid rotation has no von Mises stress (%.2e Pa)", vmax);
    /* uniaxial stretch l along x: C = diag(l^2, 1, 1), J = l, S_xx = G (1 - 1/l^2) + lam/2 (l^2 - 1)/l^2,
     * sigma_xx = l S_xx, sigma_yy = S_yy / l = (lam/2 (l^2 - 1)) / l */
    double l = 1.002;
    for (int i = 0; i < n; i++) {
        x[3 * i] = l * b->X[3 * i];
        x[3 * i + 1] = b->X[3 * i + 1];
        x[3 * i + 2] = b->X[3 * i + 2];
    }
    floe_pd_correspondence(b, x, G, lam, NULL, NULL, sg, vm, NULL);
    double sxx = l * (G * (1 - 1 / (l * l)) + 0.5 * lam * (l * l - 1) / (l * l)), syy = 0.5 * lam * (l * l - 1) / l;
    double es = 0;
    for (int i = 0; i < n; i++) es = fmax(es, fmax(fabs(sg[9 * i] - sxx), fabs(sg[9 * i + 4] - syy)) / sxx);
    printf("  uniaxial stretch 0.2 %%: sigma_xx %.6e Pa (Neo-Hookean %.6e), sigma_yy %.6e (%.6e), max rel error %.1e\n",
           sg[0], sxx, sg[4], syy, es);
    CHECK(es < 1e-10, "Neo-Hookean Cauchy stress of a uniaxial stretch (rel %.1e)", es);
    free(x); free(F); free(E); free(sg); free(vm);
    floe_pd_body_destroy(b);
}

int main(void) {
    test_pulse();
    test_impact();
    test_fracture();
    test_correspondence();
    return check_summary("test_pd_world");
}
