/* test_providers.c - user force providers (floe_provider.h floe_world_add_provider,
 * floe_provider_ctx.h) and the registered provider `linear_drag` (core/world/user_providers.c,
 * docs/scene-format.md "Forces"), through public headers only:
 *  - a free sphere under F = -c m v, T = -c_r I w: v(t) = v0 exp(-c t) and w(t) = w0
 *    exp(-c_r t) (tolerance 1e-3 relative at c t = 2, c_r t = 3: velocity Verlet's error is
 *    O(c dt) per unit c t, 1e-4 here);
 *  - a box tumbling about a non-principal axis: the angular momentum decays as L0 exp(-c_r t)
 *    in every component and the rotational energy as E0 exp(-2 c_r t) (1e-3);
 *  - the ledger: the drag's work is booked as dissipated, the energy balance closes to 1e-3;
 *  - with adaptive steps (rejected trials with contacts) a user provider's state is restored
 *    with every other provider's (a counter of stepping evaluations equals the accepted
 *    steps exactly), and a sphere falling with drag follows g/c + (v0 - g/c) exp(-c t) (1e-3);
 *  - the add convention: NULL, a class without forces, after prepare are refused with a
 *    message (the caller keeps the provider), a prepared world lists the provider;
 *  - scenes: `forces: [{type: linear_drag, c, c_r}]` gives the same decay; a misspelt type,
 *    an unknown key and a negative rate are refused at their line and column. */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static floe_provider *drag_make(double c, double c_r) {
    const floe_registry_entry *e = floe_registry_find(FLOE_KIND_PROVIDER, "linear_drag");
    if (!e) return NULL;
    void *p = calloc(1, e->params_size);
    floe_params_defaults(e, p);
    memcpy((char *)p + e->params[floe_schema_index(e, "c")].offset, &c, sizeof c);
    memcpy((char *)p + e->params[floe_schema_index(e, "c_r")].offset, &c_r, sizeof c_r);
    char err[256] = "";
    floe_provider *pv = ((floe_provider_create_fn)e->create)(p, NULL, err, sizeof err);
    free(p);
    return pv;
}

static double vnorm(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

static void test_decay(void) {
    floe_world_def d = floe_default_world_def();
    d.dt = 5e-5;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 1000, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 1.0, 0.0));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_sphere_create(0.01));
    const double v0[3] = {1.0, 0.5, -0.2}, w0[3] = {0, 3.0, 10.0};
    memcpy(p.v, v0, sizeof v0);
    memcpy(p.w, w0, sizeof w0);
    floe_world_add_particle(w, &p);
    /* a box far away, tumbling about a non-principal axis */
    floe_particle_def b = floe_default_particle_def();
    b.geometry = floe_world_add_geometry(w, floe_box_create(0.01, 0.02, 0.04));
    b.x[0] = 10;
    b.w[0] = 4;
    b.w[1] = 1;
    b.w[2] = 7;
    floe_world_add_particle(w, &b);
    const double c = 2.0, c_r = 3.0, T = 1.0;
    floe_provider *pv = drag_make(c, c_r);
    CHECK(pv != NULL, "linear_drag from the registry");
    CHECK(floe_world_add_provider(w, pv) == FLOE_OK, "add: %s", floe_world_last_error(w));
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    int found = 0;
    for (int k = 0; k < floe_world_provider_count(w); k++)
        found += !strcmp(floe_world_provider(w, k)->klass->name, "linear_drag");
    CHECK(found == 1, "the prepared world lists linear_drag once among its %d providers", floe_world_provider_count(w));
    floe_particles_view v;
    floe_world_particles(w, &v);
    double L0[3], E0 = 0;
    memcpy(L0, v.L + 3, sizeof L0);
    for (int a = 0; a < 3; a++) E0 += 0.5 * v.L[3 + a] * v.w[3 + a];
    floe_energy e0 = floe_world_energy(w);
    CHECK(floe_world_run(w, T, NULL, NULL) == FLOE_OK, "run: %s", floe_world_last_error(w));
    floe_world_particles(w, &v);
    CHECK_NEAR(vnorm(v.v), vnorm(v0) * exp(-c * T), 1e-3, "sphere |v| = |v0| exp(-c t) (tol 1e-3)");
    CHECK_NEAR(v.v[1] / v.v[0], v0[1] / v0[0], 1e-9, "sphere velocity keeps its direction (tol 1e-9)");
    CHECK_NEAR(vnorm(v.w), vnorm(w0) * exp(-c_r * T), 1e-3, "sphere |w| = |w0| exp(-c_r t) (tol 1e-3)");
    for (int a = 0; a < 3; a++) {
        char what[80];
        snprintf(what, sizeof what, "box L[%d] = L0 exp(-c_r t) (tol 1e-3)", a);
        CHECK_NEAR(v.L[3 + a], L0[a] * exp(-c_r * T), 1e-3, what);
    }
    double E = 0;
    for (int a = 0; a < 3; a++) E += 0.5 * v.L[3 + a] * v.w[3 + a];
    CHECK_NEAR(E, E0 * exp(-2 * c_r * T), 1e-3, "box rotational energy = E0 exp(-2 c_r t) (tol 1e-3)");
    floe_energy e1 = floe_world_energy(w);
    double k0 = e0.kinetic_trans + e0.kinetic_rot, k1 = e1.kinetic_trans + e1.kinetic_rot;
    CHECK_NEAR(k1 + e1.dissipated, k0, 1e-3, "drag work booked as dissipated: K(t) + D(t) = K(0) (tol 1e-3)");
    floe_world_destroy(w);
}

/* A provider with state: it counts the evaluations that end a step (ctx.stepping). Its
 * state is the count, so a rejected adaptive trial is undone: the count equals the
 * accepted steps exactly. */
typedef struct counter { floe_provider base; long n; } counter;
static int count_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *sc, floe_provider_out *o) {
    (void)w; (void)o;
    floe_provider_ctx c = floe_provider_ctx_of(sc);
    ((counter *)pv)->n += c.stepping;
    return FLOE_OK;
}
static size_t count_size(const floe_provider *pv, const floe_world *w) { (void)pv; (void)w; return sizeof(long); }
static void count_save(const floe_provider *pv, const floe_world *w, unsigned char *buf) {
    (void)w;
    memcpy(buf, &((const counter *)pv)->n, sizeof(long));
}
static void count_restore(floe_provider *pv, floe_world *w, const unsigned char *buf) {
    (void)w;
    memcpy(&((counter *)pv)->n, buf, sizeof(long));
}
static const floe_provider_class counter_class = {.version = 1, .name = "counter", .group = FLOE_GROUP_DEM,
    .forces = count_forces, .state_size = count_size, .save = count_save, .restore = count_restore};

/* spheres bouncing on a wall under gravity with drag, adaptive steps (rejected trials):
 * a lone sphere far away still decays as exp(-c t), and the providers' state is restored */
static void test_adaptive(void) {
    floe_world_def d = floe_default_world_def();
    d.adaptive = 1;
    d.gravity[2] = -9.81;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 2500, 1e8, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.9, 0.3));
    const double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
    int g = floe_world_add_geometry(w, floe_sphere_create(0.005));
    for (int k = 0; k < 4; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        p.x[0] = 0.02 * k;
        p.x[2] = 0.01 + 0.005 * k;
        p.v[0] = 0.1;
        p.w[1] = 5;
        if (k == 3) { p.x[2] = 100; p.v[2] = 1; p.motion = FLOE_FREE; } /* far away: falls freely */
        floe_world_add_particle(w, &p);
    }
    const double c = 1.5, T = 0.2, gz = -9.81;
    floe_world_add_provider(w, drag_make(c, c));
    counter *cnt = calloc(1, sizeof *cnt);
    cnt->base.klass = &counter_class;
    floe_world_add_provider(w, &cnt->base);
    CHECK(floe_world_prepare(w) == FLOE_OK, "adaptive prepare: %s", floe_world_last_error(w));
    long n0 = cnt->n;
    CHECK(floe_world_run(w, T, NULL, NULL) == FLOE_OK, "adaptive run: %s", floe_world_last_error(w));
    floe_step_stats st;
    floe_world_step_stats(w, &st);
    CHECK(st.rejected > 0, "adaptive steps rejected some trials (%ld of %ld)", st.rejected, st.accepted);
    CHECK(cnt->n - n0 == st.accepted, "a provider's state is restored after rejected trials: %ld stepping "
          "evaluations kept for %ld accepted steps (%ld rejected)", cnt->n - n0, st.accepted, st.rejected);
    floe_particles_view v;
    floe_world_particles(w, &v);
    /* dv/dt = g - c v: v = g/c + (v0 - g/c) exp(-c t) */
    CHECK_NEAR(v.v[3 * 4 + 2], gz / c + (1 - gz / c) * exp(-c * T), 1e-3,
               "adaptive: falling sphere v_z = g/c + (v0 - g/c) exp(-c t) (tol 1e-3)");
    CHECK_NEAR(v.v[3 * 4 + 0], 0.1 * exp(-c * T), 1e-3, "adaptive: v_x = v0 exp(-c t) (tol 1e-3)");
    floe_energy e = floe_world_energy(w);
    CHECK(e.dissipated > 0, "adaptive + drag: dissipated %.3g J > 0", e.dissipated);
    printf("  adaptive + drag: %ld accepted, %ld rejected\n", st.accepted, st.rejected);
    floe_world_destroy(w);
}

static int noop_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *c, floe_provider_out *o) {
    (void)pv; (void)w; (void)c; (void)o;
    return FLOE_OK;
}

static void test_add_convention(void) {
    floe_world_def d = floe_default_world_def();
    d.dt = 1e-4;
    floe_world *w = floe_world_create(&d, NULL, 0);
    CHECK(floe_world_add_provider(w, NULL) == FLOE_EINVAL && strstr(floe_world_last_error(w), "NULL"),
          "NULL refused: %s", floe_world_last_error(w));
    static const floe_provider_class no_forces = {.version = 1, .name = "bad", .group = FLOE_GROUP_DEM};
    floe_provider bad = {&no_forces};
    CHECK(floe_world_add_provider(w, &bad) == FLOE_EINVAL && strstr(floe_world_last_error(w), "forces"),
          "a class without forces refused: %s", floe_world_last_error(w));
    static const floe_provider_class ok = {.version = 1, .name = "noop", .group = FLOE_GROUP_DEM, .forces = noop_forces};
    floe_provider *pv = malloc(sizeof *pv);
    pv->klass = &ok;
    CHECK(floe_world_add_provider(w, pv) == FLOE_OK, "a minimal provider added (the world frees it)");
    CHECK(floe_world_add_provider(w, pv) == FLOE_EINVAL, "the same provider twice refused");
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    floe_provider *late = drag_make(1, 0);
    CHECK(floe_world_add_provider(w, late) == FLOE_EINVAL && strstr(floe_world_last_error(w), "prepared"),
          "added after prepare refused: %s", floe_world_last_error(w));
    late->klass->destroy(late); /* refused: still the caller's */
    floe_world_destroy(w);
}

/* a user's provider is taken to read orientations whatever its name: one named like the
 * world's contact stage ("contacts") still has a spinning sphere's orientation integrated
 * (core/world/world.c orientation_refresh; before, such a name was taken for the stage and
 * the sphere's q was left unread and unchanged) */
static void test_user_name_orientation(void) {
    floe_world_def d = floe_default_world_def();
    d.dt = 5e-5;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 1000, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.0));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_sphere_create(0.01));
    p.w[2] = 10; /* rad/s about z */
    floe_world_add_particle(w, &p);
    static const floe_provider_class named = {.version = 1, .name = "contacts", .group = FLOE_GROUP_DEM,
                                              .forces = noop_forces};
    floe_provider *pv = malloc(sizeof *pv);
    pv->klass = &named;
    CHECK(floe_world_add_provider(w, pv) == FLOE_OK, "a user provider named contacts added");
    int rc = floe_world_prepare(w);
    for (int k = 0; k < 200 && !rc; k++) rc = floe_world_step(w);
    floe_particles_view v;
    floe_world_particles(w, &v);
    /* 200 steps of 5e-5 s at 10 rad/s: a turn of 0.1 rad, q = (cos 0.05, 0, 0, sin 0.05) */
    CHECK(rc == FLOE_OK && fabs(v.q[3] - sin(0.05)) < 1e-9 && fabs(v.q[0] - cos(0.05)) < 1e-9,
          "the sphere's orientation integrated under a user provider named contacts: q = (%.9g, %.3g, %.3g, %.9g), "
          "want (%.9g, 0, 0, %.9g) (rc %d: %s)", v.q[0], v.q[1], v.q[2], v.q[3], cos(0.05), sin(0.05), rc,
          rc ? floe_world_last_error(w) : "");
    floe_world_destroy(w);
}

static const char *scene =
    "dimension: 3\n"
    "time: {duration: 0.5, dt: 5.0e-5}\n"
    "materials: [{name: m, density: 1000, young: 1.0e7, poisson: 0.3}]\n"
    "laws: [{materials: [m, m], model: hertz_mindlin, restitution: 0.5}]\n"
    "bodies:\n"
    "  - {shape: {sphere: {radius: 0.01}}, material: m, position: [0, 0, 0], velocity: [2, 0, 0],\n"
    "     angular_velocity: [0, 0, 4]}\n"
    "forces:\n"
    "  - {type: linear_drag, c: 3, c_r: 1.5}\n";

static void expect_scene_error(const char *from, const char *to, const char *at, const char *word) {
    char text[2048], err[1024] = "";
    const char *p = strstr(scene, from);
    snprintf(text, sizeof text, "%.*s%s%s", (int)(p - scene), scene, to, p + strlen(from));
    floe_world *w = NULL;
    int rc = floe_scene_load_ex("t.yaml", text, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc != FLOE_OK && strstr(err, at) && strstr(err, word), "'%s': %s (want %s and %s)", to, err, at, word);
    floe_world_destroy(w);
}

static void test_scene(void) {
    floe_world *w = NULL;
    floe_scene_info info;
    char err[1024];
    int rc = floe_scene_load_ex("t.yaml", scene, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "scene with forces: %s", rc ? err : "");
    if (rc == FLOE_OK) {
        CHECK(floe_world_run(w, info.duration, NULL, NULL) == FLOE_OK, "scene run");
        floe_particles_view v;
        floe_world_particles(w, &v);
        CHECK_NEAR(v.v[0], 2 * exp(-3 * 0.5), 1e-3, "scene: v = v0 exp(-c t) (tol 1e-3)");
        CHECK_NEAR(v.w[2], 4 * exp(-1.5 * 0.5), 1e-3, "scene: w = w0 exp(-c_r t) (tol 1e-3)");
        floe_world_destroy(w);
    }
    expect_scene_error("type: linear_drag", "type: linear_dag", "t.yaml:9:12:", "did you mean 'linear_drag'");
    expect_scene_error("c: 3,", "cc: 3,", "t.yaml:9:25:", "unknown key 'cc'");
    expect_scene_error("c: 3,", "c: -3,", "t.yaml:9:28:", "must be >= 0");
    expect_scene_error("  - {type: linear_drag, c: 3, c_r: 1.5}", "  - {type: linear_drag}", "t.yaml:9:5:",
                       "forces[0].c is required");
}

/* a provider's critical_dt enters the step estimate (kind "provider"): a stiff tether of
 * stiffness k on a sphere of mass m limits the step to 2 sqrt(m/k), and the automatic step
 * is the safety factor times it; a provider that reports 0 is refused by name */
typedef struct tether { floe_provider base; double k, dt; } tether;
static int tether_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *sc, floe_provider_out *o) {
    (void)w; (void)o;
    floe_provider_ctx c = floe_provider_ctx_of(sc);
    for (int i = 0; i < c.n; i++)
        if (c.motion[i] == FLOE_FREE)
            for (int a = 0; a < 3; a++) c.f[3 * i + a] -= ((tether *)pv)->k * c.x[3 * i + a];
    return FLOE_OK;
}
static double tether_dt(floe_provider *pv, floe_world *w) { (void)w; return ((tether *)pv)->dt; }
static const floe_provider_class tether_class = {.version = 1, .name = "tether", .group = FLOE_GROUP_DEM,
    .forces = tether_forces, .critical_dt = tether_dt};

static floe_world *tether_world(double k, double dtp, double *mass) {
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 1000, 1e6, 0.3};
    floe_world_add_material(w, &m);
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_sphere_create(0.01));
    p.x[0] = 0.001;
    floe_world_add_particle(w, &p);
    *mass = 1000 * 4.0 / 3.0 * M_PI * 1e-6;
    tether *t = calloc(1, sizeof *t);
    t->base.klass = &tether_class;
    t->k = k;
    t->dt = dtp;
    CHECK(floe_world_add_provider(w, &t->base) == FLOE_OK, "tether added");
    return w;
}

static void test_critical(void) {
    double m;
    const double k = 1e4;
    floe_world *w = tether_world(k, 2 * sqrt(4.18879e-3 / k), &m);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    floe_dt_estimates e;
    CHECK(floe_world_dt_estimates(w, &e) == FLOE_OK, "estimates");
    double want = 2 * sqrt(4.18879e-3 / k);
    CHECK(e.limiting == FLOE_DT_PROVIDER && e.critical == want, "critical %g s by kind %s (want %g by provider)",
          e.critical, floe_dt_kind_name(e.limiting), want);
    CHECK_NEAR(floe_world_dt(w), 0.2 * want, 1e-12, "automatic dt = 0.2 x the provider's critical_dt");
    /* stable at that step: the tethered sphere oscillates with amplitude 1 mm for 2000 steps */
    double xmax = 0;
    for (int s = 0; s < 2000; s++) {
        if (floe_world_step(w)) break;
        floe_particles_view v;
        floe_world_particles(w, &v);
        xmax = fmax(xmax, fabs(v.x[0]));
    }
    CHECK(xmax < 1.001e-3, "tethered sphere bounded: |x| up to %g m", xmax);
    floe_world_destroy(w);
    w = tether_world(k, 0.0, &m);
    int rc = floe_world_prepare(w);
    CHECK(rc != FLOE_OK && strstr(floe_world_last_error(w), "tether"), "critical_dt 0 refused: %s",
          floe_world_last_error(w));
    floe_world_destroy(w);
}

int main(void) {
    char err[256];
    CHECK(floe_register_builtins(err, sizeof err) == FLOE_OK, "builtins: %s", err);
    test_decay();
    test_adaptive();
    test_add_convention();
    test_user_name_orientation();
    test_scene();
    test_critical();
    return check_summary("test_providers");
}
