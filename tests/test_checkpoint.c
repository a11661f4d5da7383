/* test_checkpoint.c - checkpoints (issue #13, floe_checkpoint.h): a run stopped at a step,
 * saved, and continued in a world freshly built from the same scene ends bit for bit where
 * the uninterrupted run ends (every particle's state compared with memcmp, the energy
 * ledger, the step count): DEM spheres with friction history (Hertz-Mindlin, walls, list
 * rebuilds on both sides of the checkpoint), polyhedra with ADMM/LP warm starts, a PD body
 * breaking under an impact, beam bonds breaking, adaptive steps, leapfrog, the staggered
 * PD-DEM scheme with a PD cycle open at the checkpoint; the same through the in-memory
 * state. Refusals: another scene, a truncated, corrupted or other-version file. And the
 * end of floe_world_run with a fixed step: exactly t_end with velocity Verlet and RK2, the
 * last whole step not past t_end with leapfrog. Tolerances: none (bitwise), except the end
 * time (4 ulp). */
#include "check.h"
#include "floe.h"
#include "floe_checkpoint.h"
#include "floe_pd.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *SPHERES =
    "name: spheres\n"
    "dimension: 3\n"
    "time: {duration: 0.02, safety: 0.5}\n"
    "gravity: [0, 0, -9.81]\n"
    "neighbor: {skin: 0.0002}\n"
    "materials:\n"
    "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
    "laws:\n"
    "  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n"
    "walls:\n"
    "  - {point: [0, 0, 0], normal: [0, 0, 1], material: glass}\n"
    "  - {point: [0, 0, 0], normal: [1, 0, 0], material: glass}\n"
    "  - {point: [0.01, 0, 0], normal: [-1, 0, 0], material: glass}\n"
    "bodies:\n"
    "  - packing: random\n"
    "    shape: {sphere: {radius: 0.001}}\n"
    "    material: glass\n"
    "    region: {min: [0, 0, 0.001], max: [0.01, 0.01, 0.01]}\n"
    "    velocity: [0.05, 0, -0.2]\n"
    "    count: 60\n"
    "    seed: 3\n";

static const char *PRISMS =
    "name: prisms\n"
    "dimension: 3\n"
    "time: {duration: 0.3, safety: 0.3}\n"
    "checks: {energy: off}  # a point law on polytopes at this step creates a little energy\n"
    "gravity: [0, 0, 0]\n"
    "materials:\n"
    "  - {name: poly, density: 1}\n"
    "laws:\n"
    "  - {materials: [poly, poly], model: viscoelastic, kn: 1.0e5, ks: 1.0e4, gn: 1.0, gs: 0.1, friction: 1.0}\n"
    "bodies:\n"
    "  - {material: poly, position: [0.0, 0.0, 0.0], velocity: [0.25, 0.25, 0.0],\n"
    "     shape: {prism: {height: 0.1, vertices: [[-0.06, -0.04], [0.05, -0.06], [0.08, 0.02], [0.01, 0.07], [-0.07, 0.03]]}}}\n"
    "  - {material: poly, position: [0.13, 0.12, 0.0],\n"
    "     shape: {prism: {height: 0.25, vertices: [[-0.07, -0.05], [0.06, -0.07], [0.07, 0.05], [-0.05, 0.06]]}}}\n"
    "  - {material: poly, position: [0.33, 0.14, 0.02],\n"
    "     shape: {prism: {height: 0.5, vertices: [[-0.08, -0.05], [0.09, -0.03], [-0.01, 0.08]]}}}\n";

static const char *PD_IMPACT =
    "name: pd-impact\n"
    "dimension: 3\n"
    "time: {duration: 12.0e-6%s}\n"
    "gravity: [0, 0, 0]\n"
    "materials:\n"
    "  - {name: steel, density: 7945, young: 2.05e11, poisson: 0.3}\n"
    "  - {name: brittle, density: 2200, young: 2.235e10, poisson: 0.25}\n"
    "laws:\n"
    "  - {materials: [steel, brittle], model: hertz_mindlin, restitution: 0.8, friction: 0.092}\n"
    "  - {materials: [brittle, brittle], model: hertz_mindlin, restitution: 0.8, friction: 0.092}\n"
    "bodies:\n"
    "  - {shape: {sphere: {radius: 0.004}}, material: steel, position: [0, 0, 0.0165], velocity: [0, 0, -300]}\n"
    "peridynamics:\n"
    "  - name: block\n"
    "    region: {box: {min: [-0.01, -0.01, 0], max: [0.01, 0.01, 0.012]}}\n"
    "    spacing: 0.002\n"
    "    horizon: 3\n"
    "    material: {model: pmb, density: 2200, bulk_modulus: 1.49e10, fracture_energy: 5}\n"
    "    contact_material: brittle\n";

static const char *BEAMS =
    "name: beams\n"
    "dimension: 2\n"
    "mass_2d: area\n"
    "time: {duration: 40%s}\n"
    "gravity: [0, 0]\n"
    "materials:\n"
    "  - {name: ice, density: 920, young: 1e8, poisson: 0.3}\n"
    "laws:\n"
    "  - {materials: [ice, ice], model: hopkins, young: 1e8, friction: 0.3, thickness_max: 1.0}\n"
    "bodies:\n"
    "  - {name: island, material: ice, motion: fixed, position: [0, 0],\n"
    "     shape: {polygon: {vertices: [[-200, -150], [150, -220], [250, 50], [0, 220]]}}}\n"
    "  - {name: floe, packing: hexagonal, shape: {sphere: {radius: 50}}, material: ice, thickness: 1.0,\n"
    "     spacing: 100, region: {min: [-300, 260], max: [300, 560]}, velocity: [0, -4]}\n"
    "bonds:\n"
    "  - {young: 1e9, poisson: 0.3, radius_factor: 1.01, timoshenko: true, thickness: 1.0,\n"
    "     tensile_strength: 2e4, tensile_sd: 4e3, shear_strength: 2e4, shear_sd: 4e3,\n"
    "     compressive_strength: 8e4, compressive_sd: 1.6e4, friction_angle: 30, seed: 7, group: 1}\n";

static floe_world *load(const char *text) {
    floe_world *w = NULL;
    char err[1024];
    int rc = floe_scene_load_ex("t.yaml", text, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "scene load: %s", rc ? err : "");
    return rc ? NULL : w;
}

static uint64_t hash_of(const char *text) { return floe_checkpoint_hash(FLOE_CHECKPOINT_HASH0, text, strlen(text)); }

/* every particle's state and the ledger of a and b identical, bit for bit */
static int same_state(const char *what, floe_world *a, floe_world *b) {
    floe_particles_view va, vb;
    floe_world_particles(a, &va);
    floe_world_particles(b, &vb);
    int ok = va.n == vb.n && floe_world_step_count(a) == floe_world_step_count(b);
    CHECK(ok, "%s: %d vs %d particles, step %ld vs %ld", what, va.n, vb.n, floe_world_step_count(a),
          floe_world_step_count(b));
    if (!ok) return 0;
    const size_t n = (size_t)va.n;
    struct { const char *name; const double *x, *y; size_t m; } arr[] = {
        {"x", va.x, vb.x, 3 * n}, {"v", va.v, vb.v, 3 * n}, {"q", va.q, vb.q, 4 * n}, {"w", va.w, vb.w, 3 * n},
        {"L", va.L, vb.L, 3 * n}, {"f", va.f, vb.f, 3 * n}, {"t", va.t, vb.t, 3 * n}};
    for (size_t k = 0; k < sizeof arr / sizeof *arr; k++) {
        int same = !memcmp(arr[k].x, arr[k].y, arr[k].m * sizeof(double));
        if (!same) {
            size_t i = 0;
            while (arr[k].x[i] == arr[k].y[i]) i++;
            CHECK(0, "%s: %s differs first at [%zu]: %.17g vs %.17g", what, arr[k].name, i, arr[k].x[i], arr[k].y[i]);
            ok = 0;
        }
    }
    floe_energy ea = floe_world_energy(a), eb = floe_world_energy(b);
    CHECK(!memcmp(&ea, &eb, sizeof ea), "%s: energy ledgers differ (dissipated %.17g vs %.17g)", what, ea.dissipated,
          eb.dissipated);
    CHECK(floe_world_time(a) == floe_world_time(b), "%s: time %.17g vs %.17g", what, floe_world_time(a),
          floe_world_time(b));
    return ok;
}

/* runs text to t1 uninterrupted, and stopped at step k, saved (file, then memory), loaded
 * into a fresh world of the same scene and run to t1; returns the file's size */
static long roundtrip(const char *what, const char *text, double t1, long k) {
    printf("%s: checkpoint at step %ld (-1: half way), run to t = %g s\n", what, k, t1);
    long fsize = 0;
    floe_world *a = load(text);
    if (!a) return 0;
    int rc = floe_world_run(a, t1, NULL, NULL);
    CHECK(rc == FLOE_OK, "%s: run A: %s", what, floe_world_last_error(a));
    {
        long broken = floe_world_beam_broken_count(a);
        for (int b = 0; b < floe_world_pd_body_count(a); b++) broken += floe_world_pd_body(a, b, NULL)->nbroken;
        printf("  uninterrupted: %ld steps, %ld bonds broken\n", floe_world_step_count(a), broken);
        if (strstr(what, "breaking") || strstr(what, "beam") || strstr(what, "PD"))
            CHECK(broken > 0, "%s: bonds break in the run (%ld)", what, broken);
    }
    if (strstr(what, "polyhedra")) {
        floe_detect_stats ds;
        floe_world_detect_stats(a, &ds);
        printf("  polytope detection: %ld evaluations, %ld pairs found apart by the separation cache\n",
               ds.evaluations, ds.sep_cached);
        /* the restart must also carry the separation cache (section SEPC) to give the same bits */
        CHECK(ds.evaluations > 50 && ds.sep_cached > 50, "%s: the polytope detection runs (%ld evaluations) and the "
              "separation cache keeps pairs apart (%ld)", what, ds.evaluations, ds.sep_cached);
    }
    if (k < 0) k = floe_world_step_count(a) / 2; /* half way */
    CHECK(floe_world_step_count(a) > k + 5, "%s: the run takes %ld steps, more than the checkpoint's %ld + 5", what,
          floe_world_step_count(a), k);
    for (int mem = 0; mem < 2; mem++) {
        floe_world *b = load(text);
        if (!b) break;
        char err[1024] = "";
        rc = FLOE_OK;
        for (long s = 0; s < k && !rc; s++) rc = floe_world_step(b);
        CHECK(rc == FLOE_OK, "%s: run B: %s", what, floe_world_last_error(b));
        void *buf = NULL;
        size_t n = 0;
        if (mem) {
            n = floe_world_state_size(b);
            buf = malloc(n);
            rc = buf ? floe_world_state_save(b, buf, n, err, sizeof err) : FLOE_ENOMEM;
        } else {
            struct timespec t0, t1s;
            clock_gettime(CLOCK_MONOTONIC, &t0);
            rc = floe_world_checkpoint_save(b, "ckpt_test.bin", hash_of(text), "t.yaml", err, sizeof err);
            clock_gettime(CLOCK_MONOTONIC, &t1s);
            printf("  save: %.3f ms\n", 1e3 * (double)(t1s.tv_sec - t0.tv_sec) + 1e-6 * (double)(t1s.tv_nsec - t0.tv_nsec));
        }
        CHECK(rc == FLOE_OK, "%s: save: %s", what, err);
        floe_world_destroy(b);
        floe_world *c = load(text);
        if (!c) { free(buf); break; }
        rc = mem ? floe_world_state_restore(c, buf, n, err, sizeof err)
                 : floe_world_checkpoint_load(c, "ckpt_test.bin", hash_of(text), "t.yaml", err, sizeof err);
        free(buf);
        CHECK(rc == FLOE_OK, "%s: load: %s", what, err);
        if (!rc) {
            rc = floe_world_run(c, t1, NULL, NULL);
            CHECK(rc == FLOE_OK, "%s: run C: %s", what, floe_world_last_error(c));
            char label[256];
            snprintf(label, sizeof label, "%s (%s)", what, mem ? "memory" : "file");
            if (same_state(label, a, c)) printf("  %s: identical after %ld steps\n", label, floe_world_step_count(c));
        }
        if (!mem) {
            FILE *f = fopen("ckpt_test.bin", "rb");
            if (f) { fseek(f, 0, SEEK_END); fsize = ftell(f); fclose(f); }
            printf("  checkpoint: %ld bytes, %d particles\n", fsize, floe_world_particle_count(c));
        }
        floe_world_destroy(c);
    }
    floe_world_destroy(a);
    return fsize;
}

/* the scene with a format argument filled in */
static char *fill(const char *fmt, const char *arg) {
    size_t n = strlen(fmt) + strlen(arg) + 1;
    char *s = malloc(n);
    snprintf(s, n, fmt, arg);
    return s;
}

/* a checkpoint file's bytes, changed by the caller, written back under another name */
static unsigned char *slurp(const char *path, long *len) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    *len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *p = malloc((size_t)*len);
    if (p && fread(p, 1, (size_t)*len, f) != (size_t)*len) { free(p); p = NULL; }
    fclose(f);
    return p;
}
static void spit(const char *path, const unsigned char *p, long len) {
    FILE *f = fopen(path, "wb");
    if (f) { fwrite(p, 1, (size_t)len, f); fclose(f); }
}

/* loading path into a fresh world of text fails with a message containing want */
static void refused(const char *what, const char *text, const char *path, uint64_t hash, const char *want) {
    floe_world *w = load(text);
    if (!w) return;
    char err[1024] = "";
    int rc = floe_world_checkpoint_load(w, path, hash, "t.yaml", err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, want), "%s: refused with \"%s\" (got %d: %s)", what, want, rc, err);
    printf("  %s: %s\n", what, err);
    floe_world_destroy(w);
}

static int noop_observe(floe_observer *o, floe_world *w) {
    (void)o;
    (void)w;
    return FLOE_OK;
}

static void test_refusals(void) {
    printf("refusals\n");
    floe_world *b = load(SPHERES);
    if (!b) return;
    for (int s = 0; s < 20; s++) floe_world_step(b);
    char err[1024];
    int rc = floe_world_checkpoint_save(b, "ckpt_ref.bin", hash_of(SPHERES), "spheres.yaml", err, sizeof err);
    CHECK(rc == FLOE_OK, "save: %s", err);
    floe_world_destroy(b);
    refused("another scene", PRISMS, "ckpt_ref.bin", hash_of(PRISMS), "another scene");
    /* the same text hash given, but another world: the sections do not fit */
    refused("another world", PRISMS, "ckpt_ref.bin", hash_of(SPHERES), "particles");
    long len = 0;
    unsigned char *p = slurp("ckpt_ref.bin", &len);
    CHECK(p && len > 100, "checkpoint read back");
    if (!p) return;
    spit("ckpt_trunc.bin", p, len / 2);
    refused("truncated", SPHERES, "ckpt_trunc.bin", hash_of(SPHERES), "truncated");
    p[len / 2] ^= 0x5a;
    spit("ckpt_bad.bin", p, len);
    refused("corrupted", SPHERES, "ckpt_bad.bin", hash_of(SPHERES), "corrupted");
    p[len / 2] ^= 0x5a;
    /* the version string follows the magic, format, byte order and its length */
    unsigned char *ver = p + 8 + 8 + 4;
    CHECK(!memcmp(ver, FLOE_VERSION_STRING, strlen(FLOE_VERSION_STRING)), "the version at its place");
    ver[0] = '9';
    spit("ckpt_ver.bin", p, len);
    refused("other version", SPHERES, "ckpt_ver.bin", hash_of(SPHERES), "written by floe 9");
    p[0] = 'X';
    spit("ckpt_magic.bin", p, len);
    refused("not a checkpoint", SPHERES, "ckpt_magic.bin", hash_of(SPHERES), "not a floe checkpoint");
    refused("missing file", SPHERES, "no_such_ckpt.bin", hash_of(SPHERES), "cannot open");
    free(p);
    /* an observer without checkpoint hooks (a class of version 1): refused, naming it */
    {
        static const floe_observer_class old_class = {.version = 1, .name = "old_style", .observe = noop_observe};
        floe_world *w2 = load(SPHERES);
        floe_observer *o = calloc(1, sizeof *o);
        if (w2 && o) {
            o->klass = &old_class;
            o->period_steps = 1;
            CHECK(floe_world_add_observer(w2, o) == FLOE_OK, "observer added");
            rc = floe_world_checkpoint_load(w2, "ckpt_ref.bin", hash_of(SPHERES), "t.yaml", err, sizeof err);
            CHECK(rc != FLOE_OK && strstr(err, "old_style") && strstr(err, "no checkpoint hooks"),
                  "an observer without hooks is refused, named: %s", err);
            printf("  observer without hooks: %s\n", err);
        }
        floe_world_destroy(w2);
    }
    /* a world that has started is refused (load into a fresh one) */
    floe_world *w = load(SPHERES);
    if (w) {
        floe_world_step(w);
        rc = floe_world_checkpoint_load(w, "ckpt_ref.bin", hash_of(SPHERES), "t.yaml", err, sizeof err);
        CHECK(rc != FLOE_OK && strstr(err, "freshly built"), "a started world is refused: %s", err);
        floe_world_destroy(w);
    }
}

/* floe_world_run's end with a fixed step */
static void test_run_end(void) {
    printf("the end of a run with a fixed step\n");
    static const char *ints[] = {"velocity_verlet", "rk2", "leapfrog"};
    for (int k = 0; k < 3; k++) {
        char *text = malloc(strlen(SPHERES) + 64);
        const char *at = strstr(SPHERES, "time: {duration: 0.02, safety: 0.5}");
        size_t pre = (size_t)(at - SPHERES);
        memcpy(text, SPHERES, pre);
        sprintf(text + pre, "time: {duration: 0.02, dt: 1.0e-5, integrator: %s}%s", ints[k],
                at + strlen("time: {duration: 0.02, safety: 0.5}"));
        floe_world *w = load(text);
        free(text);
        if (!w) continue;
        const double T = 3.3e-4 + 4.3e-6; /* 33.43 steps */
        int rc = floe_world_run(w, T, NULL, NULL);
        CHECK(rc == FLOE_OK, "%s: run: %s", ints[k], floe_world_last_error(w));
        const double t = floe_world_time(w), dt = floe_world_dt(w);
        if (k < 2) {
            CHECK(fabs(t - T) <= 4 * DBL_EPSILON * T, "%s: ends at t = %.17g, not t_end = %.17g", ints[k], t, T);
            CHECK(floe_world_step_count(w) == 34, "%s: 33 whole steps and a short one (%ld)", ints[k],
                  floe_world_step_count(w));
            CHECK(dt == 1.0e-5, "%s: the step goes back to dt after the short one (%g)", ints[k], dt);
        } else {
            CHECK(t <= T && t > T - dt && floe_world_step_count(w) == 33,
                  "leapfrog: ends on the last whole step not past t_end (t = %.17g, step %ld)", t,
                  floe_world_step_count(w));
        }
        printf("  %-16s t_end %.6g s: ends at %.17g s after %ld steps\n", ints[k], T, t, floe_world_step_count(w));
        /* a whole number of steps ends there, with no extra step */
        rc = floe_world_run(w, T + 10 * 1.0e-5, NULL, NULL);
        CHECK(rc == FLOE_OK, "%s: second run", ints[k]);
        floe_world_destroy(w);
    }
}

int main(void) {
    long sz = roundtrip("DEM spheres (Hertz-Mindlin friction, walls)", SPHERES, 0.02, 700);
    roundtrip("polyhedra (ADMM/LP warm starts)", PRISMS, 0.3, -1);
    char *s = fill(PD_IMPACT, ", safety: 0.5");
    roundtrip("PD body breaking (monolithic)", s, 12.0e-6, 40);
    free(s);
    s = fill(PD_IMPACT, ", safety: 0.2, pd_dem: {scheme: staggered, every: 3}");
    roundtrip("PD body, staggered every 3 (cycle open)", s, 12.0e-6, 41);
    free(s);
    s = fill(BEAMS, "");
    roundtrip("beam bonds breaking", s, 40, 300);
    free(s);
    s = fill(BEAMS, ", integrator: leapfrog");
    roundtrip("beam bonds, leapfrog", s, 40, 301);
    free(s);
    char *ad = malloc(strlen(SPHERES) + 64);
    const char *at = strstr(SPHERES, "safety: 0.5}");
    memcpy(ad, SPHERES, (size_t)(at - SPHERES));
    sprintf(ad + (at - SPHERES), "safety: 0.5, adaptive: true}%s", at + strlen("safety: 0.5}"));
    roundtrip("DEM spheres, adaptive steps", ad, 0.02, 300);
    free(ad);
    if (sz > 0) printf("checkpoint size: %ld bytes for 63 particles (%.0f per particle)\n", sz, sz / 63.0);
    test_refusals();
    test_run_end();
    return check_summary("test_checkpoint");
}
