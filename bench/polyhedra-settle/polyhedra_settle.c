/* polyhedra_settle.c - bench/polyhedra-settle: the cost of polyhedral contacts against
 * spheres of the same size. N = 5,000 (default) particles on a jittered lattice in a walled
 * box settle under gravity, linear viscoelastic contact, one thread, in two runs:
 *   polyhedra: 8 random convex grains, each the intersection of 14 half-spaces tangent to
 *              a sphere of radius r = 1 mm (random normals, offsets r (1 +- 0.15)), random
 *              orientations; exact polytope deepest-point LP detection;
 *   spheres:   the volume-equivalent sphere of each grain (same masses), same sites.
 * The sites are 2.05 bounding radii apart (the grains almost touch), so a bed forms within
 * the first ~1,000 steps. Linear viscoelastic law kn = 5000 N/m, ks = 1000 N/m,
 * gn = 0.02, gs = 0.005 N s/m, mu = 0.5; skin 0.3 mm for both. Both use the same dt (0.5 x
 * the smaller automatic critical estimate, which is conservative) and the same steps.
 * Prints per run: loop time, particle-steps/s, candidate pair evaluations (neighbour-list
 * entries visited per step, summed), contacts (touching pairs, summed over steps), and
 * ns per step divided by either (whole-step cost attributed to pairs); then the ratios.
 * WARMUP steps (default 0) run first, untimed: WARMUP = 40000 times a settled bed (the
 * grains fall for about 0.1 s of the 0.4 s; contacts_end and ke_end show it).
 * With FLOE_BENCH_CKPT=path the warmed-up worlds are saved to path.N.WARMUP.spheres and
 * .polyhedra on the first run and loaded on the next: A/B runs of a settled bed skip the
 * warm-up (the checkpoint holds the state, not the code: rebuild it when the physics changes).
 * ONLY = "poly" skips the sphere run (for profiles of the polyhedra alone; no ratios).
 * The polyhedra line ends with the LP's halves over the timed steps: how many, how many
 * kept the previous step's basis without a pivot (the resting-contact fast path), how many
 * started cold (docs/models.md, "Polytope pairs").
 *   polyhedra_settle [NSTEPS] [N] [WARMUP] [ONLY] */
#include "floe.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define NSHAPES 8
#define NPLANES 14

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static unsigned long long rng_state = 0x9E3779B97F4A7C15ull;
static double urand(void) { /* splitmix64 -> [0, 1) */
    unsigned long long z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (z >> 11) * (1.0 / 9007199254740992.0);
}

static void unit_vec(double n[3]) {
    double z = 2 * urand() - 1, a = 2 * M_PI * urand(), s = sqrt(1 - z * z);
    n[0] = s * cos(a); n[1] = s * sin(a); n[2] = z;
}

typedef struct { double n, steps, loop, pairs, contacts, lp, halves, kept, cold, sep, sepc, mfc; int ncont_end; double ke; } result;

static const double R = 0.001, RHO = 2500;

/* build the world: poly = 1 polyhedra, 0 spheres; dt = 0 automatic */
static double RB = 0; /* largest bounding radius of the grains */

/* ck: a checkpoint of the warmed-up world to load instead of preparing it (when the file
 * exists; *loaded set), else NULL */
static floe_world *build(int poly, int n, double dt, floe_geometry **shapes, double *req, const char *ck, int *loaded) {
    floe_world_def def = floe_default_world_def();
    def.dt = dt;
    def.dt_safety = 0.5;
    def.skin = 0.0003;
    def.gravity[2] = -9.81;
    char err[256];
    floe_world *w = floe_world_create(&def, err, sizeof err);
    if (!w) { fprintf(stderr, "%s\n", err); exit(1); }
    floe_material m = {"grain", RHO, 1e7, 0.3};
    floe_world_add_material(w, &m);
    /* kn: overlap ~4 % of r at 0.2 m/s (the fall from one site); restitution ~0.8 */
    floe_world_set_law(w, 0, 0, floe_linear_law_create(5000, 1000, 0.02, 0.005, 0.5));
    int g[NSHAPES];
    for (int s = 0; s < NSHAPES; s++) {
        floe_geometry *gs = poly ? shapes[s] : floe_sphere_create(req[s]);
        g[s] = floe_world_add_geometry(w, gs);
    }
    int nx = 25, ny = 25, nz = (n + nx * ny - 1) / (nx * ny);
    double sp = 2.05 * RB;
    double L[3] = {nx * sp, ny * sp, nz * sp * 1.2};
    for (int a = 0; a < 3; a++) {
        double p0[3] = {0, 0, 0}, p1[3] = {0, 0, 0}, n0[3] = {0, 0, 0}, n1[3] = {0, 0, 0};
        p1[a] = L[a]; n0[a] = 1; n1[a] = -1;
        floe_world_add_wall(w, p0, n0, 0, FLOE_FIXED);
        if (a < 2) floe_world_add_wall(w, p1, n1, 0, FLOE_FIXED);
    }
    rng_state = 12345;
    for (int i = 0; i < n; i++) {
        int ix = i % nx, iy = (i / nx) % ny, iz = i / (nx * ny);
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g[i % NSHAPES];
        double j[3] = {urand() - 0.5, urand() - 0.5, urand() - 0.5};
        floe_v3_set(p.x, (ix + 0.5) * sp + 0.1 * R * j[0], (iy + 0.5) * sp + 0.1 * R * j[1],
                    (iz + 0.5) * sp + 0.1 * R * j[2]);
        floe_v3_set(p.v, 0.1 * (urand() - 0.5), 0.1 * (urand() - 0.5), 0.1 * (urand() - 0.5));
        double ax[3], ang = 2 * M_PI * urand();
        unit_vec(ax);
        p.q[0] = cos(ang / 2);
        for (int a = 0; a < 3; a++) p.q[1 + a] = sin(ang / 2) * ax[a];
        if (floe_world_add_particle(w, &p) < 0) { fprintf(stderr, "%s\n", floe_world_last_error(w)); exit(1); }
    }
    FILE *f = ck ? fopen(ck, "rb") : NULL;
    if (loaded) *loaded = f != NULL;
    if (f) {
        fclose(f);
        if (floe_world_checkpoint_load(w, ck, 0, poly ? "polyhedra" : "spheres", err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", ck, err);
            exit(1);
        }
        return w;
    }
    if (floe_world_prepare(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); exit(1); }
    return w;
}

/* warmup untimed steps (then saved to ck, if given), nsteps timed */
static result run(floe_world *w, int n, long nsteps, long warmup, const char *ck, const char *name) {
    for (long s = 0; s < warmup; s++) /* untimed: the bed forms */
        if (floe_world_step(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); exit(1); }
    char err[256];
    if (ck && warmup > 0 && floe_world_checkpoint_save(w, ck, 0, name, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", ck, err);
        exit(1);
    }
    result r = {0};
    r.n = n; r.steps = nsteps;
    floe_detect_stats ds;
    floe_neighbor_stats ns;
    floe_world_detect_stats(w, &ds);
    long lp0 = ds.evaluations, h0 = ds.lp_halves, k0 = ds.lp_kept, c0 = ds.lp_cold, s0 = ds.separated,
         sc0 = ds.sep_cached, mc0 = ds.manifold_cached;
    double t0 = now();
    for (long s = 0; s < nsteps; s++) {
        if (floe_world_step(w)) { fprintf(stderr, "%s\n", floe_world_last_error(w)); exit(1); }
        floe_world_neighbor_stats(w, &ns);
        r.pairs += ns.pairs;
        r.contacts += floe_world_contact_count(w);
    }
    r.loop = now() - t0;
    floe_world_detect_stats(w, &ds);
    r.lp = (double)(ds.evaluations - lp0);
    r.halves = (double)(ds.lp_halves - h0);
    r.kept = (double)(ds.lp_kept - k0);
    r.cold = (double)(ds.lp_cold - c0);
    r.sep = (double)(ds.separated - s0);
    r.sepc = (double)(ds.sep_cached - sc0);
    r.mfc = (double)(ds.manifold_cached - mc0);
    r.ncont_end = floe_world_contact_count(w);
    floe_energy e = floe_world_energy(w);
    r.ke = e.kinetic_trans + e.kinetic_rot;
    return r;
}

static void print(const char *name, const result *r, double dt) {
    printf("%-9s N=%.0f steps=%.0f dt=%.3e loop_s=%.3f particle_steps_per_s=%.3e pair_evals=%.3e "
           "contacts=%.3e contacts_end=%d convex_evals=%.3e ns_per_pair_eval=%.1f ns_per_contact=%.1f "
           "ns_per_convex_eval=%.1f ke_end=%.3e\n",
           name, r->n, r->steps, dt, r->loop, r->n * r->steps / r->loop, r->pairs, r->contacts, r->ncont_end,
           r->lp, 1e9 * r->loop / r->pairs, 1e9 * r->loop / r->contacts, r->lp > 0 ? 1e9 * r->loop / r->lp : 0.0, r->ke);
}

/* the NSHAPES grain shapes, the same on every call (the stream restarts at 777): 0, or 1
 * with a message */
static int make_grains(floe_geometry *shapes[NSHAPES]) {
    rng_state = 777;
    for (int s = 0; s < NSHAPES; s++) {
        double pl[4 * NPLANES];
        /* six axis planes keep the grain bounded; eight random ones cut it */
        for (int k = 0; k < NPLANES; k++) {
            double *q = pl + 4 * k;
            if (k < 6) { q[0] = q[1] = q[2] = 0; q[k / 2] = k % 2 ? -1 : 1; }
            else unit_vec(q);
            q[3] = R * (1 + 0.15 * (2 * urand() - 1));
        }
        char err[256];
        shapes[s] = floe_polyhedron_from_planes(pl, NPLANES, err, sizeof err);
        if (!shapes[s]) { fprintf(stderr, "shape %d: %s\n", s, err); return 1; }
    }
    return 0;
}

int main(int argc, char **argv) {
    long nsteps = argc > 1 ? atol(argv[1]) : 20000;
    int n = argc > 2 ? atoi(argv[2]) : 5000;
    long warmup = argc > 3 ? atol(argv[3]) : 0;
    const int only_poly = argc > 4 && !strcmp(argv[4], "poly");
    setvbuf(stdout, NULL, _IOLBF, 0); /* each run's line as it ends */
    floe_geometry *shapes[NSHAPES];
    double req[NSHAPES];
    if (make_grains(shapes)) return 1;
    for (int s = 0; s < NSHAPES; s++) {
        floe_mass_properties mp;
        floe_geometry_mass_properties(shapes[s], 3, 1.0, &mp);
        req[s] = cbrt(3 * mp.mass / (4 * M_PI));
        RB = fmax(RB, floe_geometry_bounding_radius(shapes[s]));
    }
    printf("grains: %d shapes from %d planes, largest bounding radius %.3e m, volume-equivalent radii %.3e..%.3e m\n",
           NSHAPES, NPLANES, RB, req[0], req[NSHAPES - 1]);
    /* the same dt for both: 0.2 x the smaller automatic estimate */
    floe_world *wp = build(1, n, 0, shapes, req, NULL, NULL);
    double dtp = floe_world_dt(wp);
    floe_world_destroy(wp); /* owns the shapes: rebuild them below */
    if (make_grains(shapes)) return 1;
    floe_world *ws = build(0, n, 0, NULL, req, NULL, NULL);
    double dt = fmin(dtp, floe_world_dt(ws));
    floe_world_destroy(ws);

    /* FLOE_BENCH_CKPT=path with WARMUP > 0: the warmed-up worlds in path.spheres and
     * path.polyhedra, written by the first run and loaded by the next (same N and WARMUP) */
    const char *ckb = getenv("FLOE_BENCH_CKPT");
    char cks[1024], ckp[1024];
    snprintf(cks, sizeof cks, "%s.%d.%ld.spheres", ckb ? ckb : "", n, warmup);
    snprintf(ckp, sizeof ckp, "%s.%d.%ld.polyhedra", ckb ? ckb : "", n, warmup);
    const int use_ck = ckb && *ckb && warmup > 0;
    int loaded = 0;
    result rs = {0};
    if (!only_poly) {
        ws = build(0, n, dt, NULL, req, use_ck ? cks : NULL, &loaded);
        rs = run(ws, n, nsteps, loaded ? 0 : warmup, use_ck && !loaded ? cks : NULL, "spheres");
        print("spheres", &rs, dt);
        floe_world_destroy(ws);
    }
    wp = build(1, n, dt, shapes, req, use_ck ? ckp : NULL, &loaded);
    result rp = run(wp, n, nsteps, loaded ? 0 : warmup, use_ck && !loaded ? ckp : NULL, "polyhedra");
    print("polyhedra", &rp, dt);
    printf("lp_halves=%.3e lp_kept=%.3e lp_cold=%.3e separated=%.3e sep_cached=%.3e manifold_cached=%.3e\n", rp.halves,
           rp.kept, rp.cold, rp.sep, rp.sepc, rp.mfc);
    floe_world_destroy(wp);
    if (only_poly) return 0;
    printf("ratio polyhedra/spheres: time per step %.2f, ns per pair evaluation %.2f, ns per contact %.2f\n",
           rp.loop / rs.loop, (rp.loop / rp.pairs) / (rs.loop / rs.pairs),
           (rp.loop / rp.contacts) / (rs.loop / rs.contacts));
    return 0;
}
