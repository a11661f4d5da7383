/* impact-plate: the validation case of 003 §4.1 (Table 1). A steel sphere (R = 0.01 m,
 * DEM) hits the centre of a simply supported steel plate 0.2 x 0.2 x 0.008 m discretised with
 * bond-based PD (PMB) points of radius 1 mm (spacing 2 mm, horizon 3 spacings) at 1 m/s.
 * E = 206 GPa, rho = 7833 kg/m^3, nu = 0.28 (PMB fixes nu = 1/4: K = E / (3 (1 - 2 nu)) of
 * the PMB body uses nu = 1/4). Contact: Hertz-Mindlin between the sphere and the plate's
 * points (hybrid PD-DEM), no damping. Simply supported: the points of the bottom layer along
 * the four edges are held (velocity 0).
 *
 *   impact_plate [SPACING_MM=2] [DURATION_US=150]
 *
 * Prints the maximum contact force, the impactor's maximum displacement, its rebound
 * velocity and the plate's maximum deflection next to the published values. */
#include "floe.h"
#include "floe_pd.h"
#include "world_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void hold(double t, double v[3], double w[3], void *user) {
    (void)t; (void)user;
    floe_v3_set(v, 0, 0, 0);
    floe_v3_set(w, 0, 0, 0);
}

int main(int argc, char **argv) {
    double dxmm = argc > 1 ? atof(argv[1]) : 2.0, dur = (argc > 2 ? atof(argv[2]) : 150.0) * 1e-6;
    const double E = 206e9, rho = 7833, nu = 0.28, L = 0.2, H = 0.008, R = 0.01, v0 = 1.0;
    double dx = dxmm * 1e-3;
    char err[512];
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    floe_v3_set(d.gravity, 0, 0, 0);
    floe_world *w = floe_world_create(&d, err, sizeof err);
    if (!w) { fprintf(stderr, "%s\n", err); return 1; }
    floe_material steel = {"steel", rho, E, nu};
    int mat = floe_world_add_material(w, &steel);
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&steel, &steel, 1.0, 0.0));

    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.horizon_factor = 3;
    floe_v3_set(r.lo, -0.5 * L, -0.5 * L, -H);
    floe_v3_set(r.hi, 0.5 * L, 0.5 * L, 0);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) { fprintf(stderr, "plate: cannot discretise\n"); return 1; }
    floe_pd_material pm = floe_pd_material_pmb(rho, E / (3 * (1 - 2 * 0.25)), 0);
    if (floe_pd_set_material(b, &pm) || floe_pd_surface_correction(b)) { fprintf(stderr, "plate: material\n"); return 1; }
    int first = 0, npts = b->n;
    if (floe_world_add_pd_body(w, b, mat, NULL, &first)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
    /* simple support: bottom-layer points within one spacing of an edge are held */
    int nheld = 0, centre = -1;
    double best = INFINITY;
    for (int i = 0; i < npts; i++) {
        const double *X = b->X + 3 * i;
        int bottom = X[2] < -H + dx, edge = fabs(X[0]) > 0.5 * L - dx || fabs(X[1]) > 0.5 * L - dx;
        if (bottom && edge) { floe_world_set_motion(w, first + i, hold, NULL); nheld++; }
        /* the bottom point nearest the centre: the plate deflection */
        double c = X[0] * X[0] + X[1] * X[1];
        if (bottom && c < best) { best = c; centre = i; }
    }
    /* the sphere just above the top points (contact radius of a point: (3V/4 pi)^(1/3)) */
    double Rp = cbrt(3 * dx * dx * dx / (4 * M_PI)), ztop = -0.5 * dx;
    int gs = floe_world_add_geometry(w, floe_sphere_create(R));
    floe_particle_def s = floe_default_particle_def();
    s.geometry = gs;
    s.material = mat;
    /* over the point nearest the centre of the top layer */
    floe_v3_set(s.x, 0, 0, ztop + Rp + R + 1e-6);
    for (int i = 0; i < npts; i++) { /* the top point nearest the axis */
        const double *X = b->X + 3 * i;
        if (X[2] > -dx && X[0] * X[0] + X[1] * X[1] <= 0.5 * dx * dx + 1e-12) { s.x[0] = X[0]; s.x[1] = X[1]; break; }
    }
    floe_v3_set(s.v, 0, 0, -v0);
    int sp = floe_world_add_particle(w, &s);
    if (sp < 0 || floe_world_prepare(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
    long steps = (long)(dur / floe_world_dt(w));
    printf("impact-plate (003 §4.1): %d PD points (spacing %.3g mm, %lld bonds), %d held, dt %.3g s, %ld steps\n", npts,
           dxmm, (long long)b->nbond, nheld, floe_world_dt(w), steps);
    double z0 = w->p.x[3 * sp + 2], zc0 = w->p.x[3 * (first + centre) + 2];
    double fmax = 0, dmax = 0, pmax = 0, vmax = -INFINITY;
    int touched = 0;
    for (long k = 0; k < steps; k++) {
        if (floe_world_step(w)) { fprintf(stderr, "step: %s\n", floe_world_last_error(w)); return 1; }
        /* contact force on the sphere: its total force (no gravity, no other load) */
        double fz = w->p.f[3 * sp + 2];
        if (fz > 0) touched = 1;
        fmax = fmax < fz ? fz : fmax;
        double dz = z0 - w->p.x[3 * sp + 2];
        if (dz > dmax) dmax = dz;
        double pz = zc0 - w->p.x[3 * (first + centre) + 2];
        if (pz > pmax) pmax = pz;
        if (touched && w->p.v[3 * sp + 2] > vmax) vmax = w->p.v[3 * sp + 2];
    }
    printf("\n%-36s %12s %12s %12s\n", "", "floe", "003 PD-DEM", "[58] / [69]");
    printf("%-36s %12.4g %12s %12s\n", "impactor max force Fn [kN]", fmax / 1e3, "1.25", "1.2335/1.25");
    printf("%-36s %12.4g %12s %12s\n", "impactor max displacement [mm]", dmax * 1e3, "0.029", "0.027/0.025");
    printf("%-36s %12.4g %12s %12s\n", "impactor rebound velocity [m/s]", vmax, "0.75", "0.75/0.75");
    printf("%-36s %12.4g %12s %12s\n", "plate max deflection [mm]", pmax * 1e3, "0.00778", "0.00781/0.0078");
    double bal = floe_world_energy_balance_error(w);
    printf("energy balance error %.2e\n", bal);
    floe_world_destroy(w);
    /* a run check for the test suite: contact happened, the sphere came back, energy closed */
    int bad = !(fmax > 0) || !(vmax > 0) || !(bal < 1e-3) || !(pmax > 0);
    if (bad) fprintf(stderr, "impact-plate: no contact, no rebound or an energy balance error above 1e-3\n");
    return bad;
}
