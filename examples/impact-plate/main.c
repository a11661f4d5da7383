/* impact-plate: the validation case of 003 §4.1 (Table 1). A steel sphere (R = 0.01 m,
 * DEM) hits the centre of a simply supported steel plate 0.2 x 0.2 x 0.008 m discretised with
 * bond-based PD (PMB) points at 1 m/s. E = 206 GPa, rho = 7833 kg/m^3, nu = 0.28.
 *
 * The paper's discretisation: "PD particles of radius r = 0.001 m", "the horizon is three
 * times the size of PD particles": particles of radius 1 mm touching on a cubic lattice
 * (spacing 2 mm, 100 x 100 x 4 points), delta = 3 x 2 mm = 6 mm. The impactor is projected
 * at the centre of the plate, which for 100 points a side lies between the four central
 * points. PMB fixes nu = 1/4 (K = E / (3 (1 - 2 nu)) with nu = 1/4); the paper's nu = 0.28
 * enters the Hertz-Mindlin contact (E* of steel on steel = E / (2 (1 - nu^2)) = 111.8 GPa
 * for two deformable spheres). Simply supported: the points of the bottom layer along the
 * four edges are held (velocity 0).
 *
 *   impact_plate [SPACING_MM=2] [DURATION_US=150] [key=value ...]
 *     radius=paper|volume   contact radius of a point: 1/2 spacing (the paper's "radius",
 *                           default) or (3V/4 pi)^(1/3) = 0.62 spacing (floe's default)
 *     aim=centre|point      impact at the plate centre (default) or over the top point
 *                           nearest it
 *     law=hm|sr|both        Hertz-Mindlin (hybrid PD-DEM, default), Silling's short-range
 *                           force (PD-SRRFM, contact/laws/short_range.c), or both one after the
 *                           other with the difference printed as 003 Table 1 does
 *     nu=0.28               Poisson ratio of the contact material (the PMB body keeps 1/4)
 *     horizon=3             delta in spacings
 *     support=edge|none     held bottom edge rows, or nothing held (free plate)
 *     correction=1|0        PD surface correction of the plate (default on)
 *     model=pmb|lps         plate material: bond-based PMB (the paper's, nu = 1/4) or LPS
 *                           (state-based, nu = 0.28)
 *
 * Prints the maximum contact force, the impactor's maximum displacement, its rebound
 * velocity and the plate's maximum deflection next to the published values; exit status 1
 * when there was no contact, no rebound or the energy balance is off by more than 1e-3. */
#include "floe.h"
#include "floe_pd.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void hold(double t, double v[3], double w[3], void *user) {
    (void)t; (void)user;
    floe_v3_set(v, 0, 0, 0);
    floe_v3_set(w, 0, 0, 0);
}

typedef struct {
    double dxmm, dur, nu_c, horizon;
    int radius_paper, aim_centre, support, correction, lps;
} options;

typedef struct {
    double fmax, dmax, vreb, pmax, bal;
    double t_contact;   /* duration of the first contact, s */
    double t_pmax;      /* time of the plate's largest deflection, s */
    double p_release;   /* plate deflection when the sphere leaves, m */
    int npts, nheld;
    long long nbond;
    double dt;
    long steps;
} figures;

static const double E = 206e9, RHO = 7833, L = 0.2, H = 0.008, R = 0.01, V0 = 1.0;

/* one run; law_sr: 0 Hertz-Mindlin, 1 short-range */
static int run(const options *o, int law_sr, figures *fg) {
    double dx = o->dxmm * 1e-3;
    char err[512];
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    floe_v3_set(d.gravity, 0, 0, 0);
    floe_world *w = floe_world_create(&d, err, sizeof err);
    if (!w) { fprintf(stderr, "%s\n", err); return 1; }
    floe_material steel = {"steel", RHO, E, o->nu_c};
    int mat = floe_world_add_material(w, &steel);

    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.horizon_factor = o->horizon;
    floe_v3_set(r.lo, -0.5 * L, -0.5 * L, -H);
    floe_v3_set(r.hi, 0.5 * L, 0.5 * L, 0);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) { fprintf(stderr, "plate: cannot discretise\n"); return 1; }
    /* PMB: nu = 1/4 fixed; LPS (option): the paper's nu = 0.28 */
    const double nu_b = o->lps ? 0.28 : 0.25;
    floe_pd_material pm = o->lps ? floe_pd_material_lps(RHO, E / (3 * (1 - 2 * nu_b)), E / (2 * (1 + nu_b)), 0,
                                                        FLOE_PD_W_ONE)
                                 : floe_pd_material_pmb(RHO, E / (3 * (1 - 2 * nu_b)), 0);
    if (floe_pd_set_material(b, &pm) || (o->correction && floe_pd_surface_correction(b))) {
        fprintf(stderr, "plate: material\n");
        return 1;
    }
    const double c_pmb = b->c, delta = b->delta, V = b->V[0]; /* LPS: the equivalent PMB c */
    floe_contact_law *law = law_sr ? floe_short_range_law_create_pd(c_pmb, delta, V, V, 15)
                                   : floe_hertz_mindlin_law_create(&steel, &steel, 1.0, 0.0);
    floe_world_set_law(w, mat, mat, law);
    int first = 0, npts = b->n;
    fg->nbond = (long long)b->nbond;
    if (floe_world_add_pd_body(w, b, mat, NULL, &first)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
    b = floe_world_pd_body(w, 0, NULL);
    /* the paper's point radius: half the spacing (touching spheres), instead of the world's
     * (3V/4 pi)^(1/3); the points keep their mass rho V */
    double Rp = cbrt(3 * V / (4 * M_PI));
    if (o->radius_paper) {
        Rp = 0.5 * dx;
        int g = floe_world_add_geometry(w, floe_sphere_create(Rp));
        for (int i = 0; i < npts; i++)
            if (floe_world_set_particle_geometry(w, first + i, g)) {
                fprintf(stderr, "%s\n", floe_world_last_error(w));
                return 1;
            }
    }
    /* simple support: bottom-layer points within one spacing of an edge are held */
    int nheld = 0, centre = -1;
    double best = INFINITY;
    for (int i = 0; i < npts; i++) {
        const double *X = b->X + 3 * i;
        int bottom = X[2] < -H + dx, edge = fabs(X[0]) > 0.5 * L - dx || fabs(X[1]) > 0.5 * L - dx;
        if (o->support && bottom && edge) { floe_world_set_motion(w, first + i, hold, NULL); nheld++; }
        /* the bottom point nearest the centre: the plate deflection */
        double c = X[0] * X[0] + X[1] * X[1];
        if (bottom && c < best) { best = c; centre = i; }
    }
    /* the sphere just above the top points: over the plate centre, or over the top point
     * nearest it; 1 um before first contact */
    int top = -1;
    best = INFINITY;
    for (int i = 0; i < npts; i++) {
        const double *X = b->X + 3 * i;
        double c = X[0] * X[0] + X[1] * X[1];
        if (X[2] > -dx && c < best) { best = c; top = i; }
    }
    const double *Xt = b->X + 3 * top;
    int gs = floe_world_add_geometry(w, floe_sphere_create(R));
    floe_particle_def s = floe_default_particle_def();
    s.geometry = gs;
    s.material = mat;
    if (o->aim_centre) {
        double h2 = (R + Rp) * (R + Rp) - Xt[0] * Xt[0] - Xt[1] * Xt[1];
        floe_v3_set(s.x, 0, 0, Xt[2] + sqrt(h2) + 1e-6);
    } else {
        floe_v3_set(s.x, Xt[0], Xt[1], Xt[2] + R + Rp + 1e-6);
    }
    floe_v3_set(s.v, 0, 0, -V0);
    int sp = floe_world_add_particle(w, &s);
    if (sp < 0 || floe_world_prepare(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); return 1; }
    long steps = (long)(o->dur / floe_world_dt(w));
    floe_particles_view pv; /* the particle arrays: valid until the next step */
    floe_world_particles(w, &pv);
    double z0 = pv.x[3 * sp + 2], zc0 = pv.x[3 * (first + centre) + 2];
    double fmax = 0, dmax = 0, pmax = 0, vmax = -INFINITY, t_in = -1, t_out = -1, t_pmax = 0, p_rel = NAN;
    int touched = 0;
    for (long k = 0; k < steps; k++) {
        if (floe_world_step(w)) { fprintf(stderr, "step: %s\n", floe_world_last_error(w)); return 1; }
        floe_world_particles(w, &pv);
        /* contact force on the sphere: its total force (no gravity, no other load) */
        double fz = pv.f[3 * sp + 2];
        if (fz > 0 && !touched) { touched = 1; t_in = floe_world_time(w); }
        if (touched && fz <= 0 && t_out < 0) {
            t_out = floe_world_time(w);
            p_rel = zc0 - pv.x[3 * (first + centre) + 2];
        }
        fmax = fmax < fz ? fz : fmax;
        double dz = z0 - pv.x[3 * sp + 2];
        if (dz > dmax) dmax = dz;
        double pz = zc0 - pv.x[3 * (first + centre) + 2];
        if (pz > pmax) { pmax = pz; t_pmax = floe_world_time(w); }
        if (touched && pv.v[3 * sp + 2] > vmax) vmax = pv.v[3 * sp + 2];
    }
    fg->fmax = fmax;
    fg->dmax = dmax;
    fg->vreb = vmax;
    fg->pmax = pmax;
    fg->bal = floe_world_energy_balance_error(w);
    fg->t_contact = t_out > 0 ? t_out - t_in : NAN;
    fg->t_pmax = t_pmax;
    fg->p_release = p_rel;
    fg->npts = npts;
    fg->nheld = nheld;
    fg->dt = floe_world_dt(w);
    fg->steps = steps;
    floe_world_destroy(w);
    return 0;
}

static void table(const char *head, const figures *f) {
    printf("\n%-36s %12s %12s %12s\n", head, "floe", "003 PD-DEM", "[58] / [69]");
    printf("%-36s %12.4g %12s %12s\n", "impactor max force Fn [kN]", f->fmax / 1e3, "1.25", "1.2335/1.25");
    printf("%-36s %12.4g %12s %12s\n", "impactor max displacement [mm]", f->dmax * 1e3, "0.029", "0.027/0.025");
    printf("%-36s %12.4g %12s %12s\n", "impactor rebound velocity [m/s]", f->vreb, "0.75", "0.75/0.75");
    printf("%-36s %12.4g %12s %12s\n", "plate max deflection [mm]", f->pmax * 1e3, "0.00778", "0.00781/0.0078");
    printf("%-36s %12.4g\n", "first contact duration [us]", f->t_contact * 1e6);
    printf("%-36s %12.4g  (largest at t = %.4g us)\n", "plate deflection at release [mm]", f->p_release * 1e3,
           f->t_pmax * 1e6);
    printf("energy balance error %.2e\n", f->bal);
}

static int bad(const char *what, const figures *f) {
    int b = !(f->fmax > 0) || !(f->vreb > 0) || !(f->bal < 1e-3) || !(f->pmax > 0);
    if (b) fprintf(stderr, "impact-plate (%s): no contact, no rebound or an energy balance error above 1e-3\n", what);
    return b;
}

int main(int argc, char **argv) {
    options o = {2.0, 150e-6, 0.28, 3.0, 1, 1, 1, 1, 0};
    int law = 0; /* 0 hm, 1 sr, 2 both */
    int pos = 0;
    for (int a = 1; a < argc; a++) {
        const char *s = argv[a], *eq = strchr(s, '=');
        if (!eq) {
            if (pos == 0) o.dxmm = atof(s);
            else if (pos == 1) o.dur = atof(s) * 1e-6;
            pos++;
            continue;
        }
        const char *v = eq + 1;
        if (!strncmp(s, "radius=", 7)) o.radius_paper = strcmp(v, "volume") != 0;
        else if (!strncmp(s, "aim=", 4)) o.aim_centre = strcmp(v, "point") != 0;
        else if (!strncmp(s, "law=", 4)) law = !strcmp(v, "sr") ? 1 : !strcmp(v, "both") ? 2 : 0;
        else if (!strncmp(s, "nu=", 3)) o.nu_c = atof(v);
        else if (!strncmp(s, "horizon=", 8)) o.horizon = atof(v);
        else if (!strncmp(s, "support=", 8)) o.support = strcmp(v, "none") != 0;
        else if (!strncmp(s, "correction=", 11)) o.correction = atoi(v) != 0;
        else if (!strncmp(s, "model=", 6)) o.lps = !strcmp(v, "lps");
        else { fprintf(stderr, "impact_plate: unknown option '%s'\n", s); return 2; }
    }
    if (!(o.dxmm > 0) || !(o.dur > 0) || !(o.horizon >= 1) || !(o.nu_c > -1 && o.nu_c < 0.5)) {
        fprintf(stderr, "impact_plate: bad spacing, duration, horizon or nu\n");
        return 2;
    }
    figures hm, sr;
    int rc = 0;
    printf("impact-plate (003 §4.1): %s plate, spacing %.3g mm, horizon %g spacings, point contact radius %s, aim %s, "
           "contact nu %g, %s%s\n", o.lps ? "LPS" : "PMB", o.dxmm, o.horizon,
           o.radius_paper ? "spacing/2 (paper)" : "(3V/4pi)^(1/3)", o.aim_centre ? "plate centre" : "top point", o.nu_c,
           o.support ? "bottom edge rows held" : "free plate", o.correction ? "" : ", no surface correction");
    if (law != 1) {
        if (run(&o, 0, &hm)) return 1;
        printf("%d PD points (%lld bonds), %d held, dt %.3g s, %ld steps\n", hm.npts, hm.nbond, hm.nheld, hm.dt, hm.steps);
        table("hybrid PD-DEM (Hertz-Mindlin)", &hm);
        rc |= bad("Hertz-Mindlin", &hm);
    }
    if (law != 0) {
        if (run(&o, 1, &sr)) return 1;
        table("PD short-range force (PD-SRRFM)", &sr);
        rc |= bad("short-range", &sr);
    }
    if (law == 2) {
        printf("\n%-36s %12s %12s %12s %12s\n", "PD-SRRFM vs hybrid PD-DEM", "floe SRRFM", "floe PD-DEM", "003 SRRFM",
               "003 PD-DEM");
        printf("%-36s %12.4g %12.4g %12s %12s\n", "impactor max force Fn [kN]", sr.fmax / 1e3, hm.fmax / 1e3, "5.6", "1.25");
        printf("%-36s %12.4g %12.4g %12s %12s\n", "impactor max displacement [mm]", sr.dmax * 1e3, hm.dmax * 1e3, "7.5",
               "0.029");
        printf("%-36s %12.4g %12.4g %12s %12s\n", "impactor rebound velocity [m/s]", sr.vreb, hm.vreb, "3.3", "0.75");
        printf("%-36s %12.4g %12.4g %12s %12s\n", "plate max deflection [mm]", sr.pmax * 1e3, hm.pmax * 1e3, "0.016",
               "0.00778");
    }
    return rc;
}
