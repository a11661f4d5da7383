/* multiscale.c - 000 §4.2 (Fig. 8, Table 2): a PD body of 40 x 40 x 10 cm (20 x 20 x 5 =
 * 2,000 points, dx = 2 cm, LPS with delta = 2 dx, E = 1e8 Pa, nu = 0.25, rho = 1,100 kg/m^3,
 * 000 Table 1) on a static wall, 9 x 9 = 81 DEM spheres of R = 2 cm on top pushed down at
 * 1 cm/s until the spheres moved 0.2 cm; Hertz-Mindlin contact with the Table 1 values, no
 * friction and no damping (fully dynamic). Writes the normal force on the wall against the
 * displacement u of the spheres as CSV and prints the cost.
 *
 *   bench_multiscale SCHEME M DT_PD [OUT.csv] [T_END]
 *     SCHEME mono: monolithic, dt = DT_PD (M ignored)
 *            stag: staggered, PD step DT_PD, DEM step M x DT_PD (PD sub-cycled M times)
 *            every: staggered, DEM step DT_PD / M, PD every M-th DEM step
 *
 * Departure from the paper: the bottom points are not constrained in x-y (floe has no
 * per-direction constraint yet); the loading is symmetric and frictionless, so they stay
 * put to within the lateral Poisson expansion. */
#include "floe.h"
#include "floe_pd.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* CPU time of the process: on a shared machine the wall clock also counts the time the
 * process waited for a core */
/* the z force on particle i at the last evaluation */
static double wall_fz(const floe_world *w, int i) {
    floe_particle_state st;
    return floe_world_get_particle(w, i, &st) == FLOE_OK ? st.f[2] : NAN;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc < 4) {
        fprintf(stderr, "usage: %s mono|stag|every M DT_PD [OUT.csv] [T_END]\n", argv[0]);
        return 2;
    }
    const char *scheme = argv[1];
    int M = atoi(argv[2]);
    double dtpd = atof(argv[3]);
    const char *out = argc > 4 ? argv[4] : NULL;
    const double v = 0.01, u_end = 0.002, t_end = argc > 5 ? atof(argv[5]) : u_end / v;
    if (M < 1 || !(dtpd > 0)) {
        fprintf(stderr, "M >= 1 and DT_PD > 0\n");
        return 2;
    }
    const double dx = 0.02, R = 0.02, E = 1e8, nu = 0.25, rho = 1100;
    floe_world_def d = floe_default_world_def();
    d.allow_unstable_dt = 1; /* the paper's steps, reported against the estimates below */
    if (!strcmp(scheme, "mono")) {
        d.dt = dtpd;
    } else if (!strcmp(scheme, "stag")) {
        d.pd_dem = FLOE_PD_DEM_STAGGERED;
        d.pd_substeps = M;
        d.dt = M * dtpd;
    } else if (!strcmp(scheme, "every")) {
        d.pd_dem = FLOE_PD_DEM_STAGGERED;
        d.pd_every = M;
        d.dt = dtpd / M;
    } else {
        fprintf(stderr, "unknown scheme %s\n", scheme);
        return 2;
    }
    /* the bench measures the staggered schemes' error and cost, including the substep ratios
     * that resonate (m >= 4): the energy watchdog would stop those runs (issue 10) */
    d.energy_check = FLOE_CHECK_OFF;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"rubber", rho, E, nu};
    int mat = floe_world_add_material(w, &m);
    floe_world_set_law(w, mat, mat, floe_hertz_mindlin_law_create(&m, &m, 1.0, 0.0));
    /* the PD body: bottom points touching the wall at z = 0 */
    const double Rpd = cbrt(3.0 * dx * dx * dx / (4 * M_PI));
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = dx;
    r.horizon_factor = 2;
    floe_v3_set(r.lo, -0.2, -0.2, Rpd - 0.5 * dx);
    floe_v3_set(r.hi, 0.2, 0.2, Rpd - 0.5 * dx + 0.1);
    floe_pd_body *b = NULL;
    if (floe_pd_body_create(&b, &r)) return 1;
    const double K = E / (3 * (1 - 2 * nu)), G = E / (2 * (1 + nu));
    floe_pd_material pm = floe_pd_material_lps(rho, K, G, 0, FLOE_PD_W_ONE);
    if (floe_pd_set_material(b, &pm) || floe_pd_surface_correction(b)) return 1;
    int np = b->n, f0;
    if (floe_world_add_pd_body(w, b, mat, NULL, &f0)) {
        fprintf(stderr, "%s\n", floe_world_last_error(w));
        return 1;
    }
    double ztop = 0;
    floe_particles_view pv;
    floe_world_particles(w, &pv);
    for (int i = 0; i < np; i++) ztop = fmax(ztop, pv.x[3 * (f0 + i) + 2]);
    /* 9 x 9 spheres at a 4.4 cm pitch, touching the top layer, moving down at 1 cm/s */
    int gs = floe_world_add_geometry(w, floe_sphere_create(R));
    for (int a = 0; a < 9; a++)
        for (int c = 0; c < 9; c++) {
            floe_particle_def s = floe_default_particle_def();
            s.geometry = gs;
            s.material = mat;
            s.motion = FLOE_KINEMATIC;
            floe_v3_set(s.x, (a - 4) * 0.044, (c - 4) * 0.044, ztop + Rpd + R);
            floe_v3_set(s.v, 0, 0, -v);
            floe_world_add_particle(w, &s);
        }
    double p0[3] = {0, 0, 0}, n0[3] = {0, 0, 1};
    int wall = floe_world_add_wall(w, p0, n0, mat, FLOE_FIXED);
    if (floe_world_prepare(w)) {
        fprintf(stderr, "prepare: %s\n", floe_world_last_error(w));
        return 1;
    }
    floe_dt_estimates e;
    floe_world_dt_estimates(w, &e);
    FILE *f = out ? fopen(out, "w") : NULL;
    if (f) fprintf(f, "t [s],u [m],wall_force [N]\n");
    const double sample = 1e-3;
    double next = 0, t0 = now();
    int rc = FLOE_OK;
    while (rc == FLOE_OK && floe_world_time(w) < t_end - 1e-12) {
        rc = floe_world_step(w);
        if (f && floe_world_time(w) >= next - 1e-12) {
            fprintf(f, "%.6g,%.6g,%.6g\n", floe_world_time(w), v * floe_world_time(w), -wall_fz(w, wall));
            next += sample;
        }
    }
    double wall_s = now() - t0;
    if (f) fclose(f);
    floe_step_stats st;
    floe_world_step_stats(w, &st);
    printf("scheme %s M %d dt %.3g s PD step %.3g s: %s; %ld steps, %ld contact and %ld PD evaluations, CPU %.3f s, "
           "final wall force %.4g N, balance %.2e; estimates: contact %.3g s, PD nodal %.3g s, PD CFL %.3g s; %d points\n",
           scheme, M, floe_world_dt(w), !strcmp(scheme, "mono") ? d.dt : !strcmp(scheme, "stag") ? dtpd : dtpd,
           rc ? floe_world_last_error(w) : "ok", st.accepted, st.force_evaluations, st.pd_evaluations, wall_s,
           -wall_fz(w, wall), floe_world_energy_balance_error(w), e.critical_contact, e.critical_pd,
           e.dt[FLOE_DT_PD_CFL], np);
    printf("csv,%s,%d,%.6g,%.6f,%d\n", scheme, M, dtpd, wall_s, rc);
    floe_world_destroy(w);
    return rc ? 1 : 0;
}
