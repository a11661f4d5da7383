/* test_integrator_class.c - integrators as classes (floe_integrator.h, issue #11 item 6):
 * a class registered from outside the library (as a plugin would) is found by value and by
 * the scene's time.integrator, its critical-step factor sets the automatic step, the
 * adaptive controller wraps it because it declares FLOE_INTEGRATOR_RESTORES, and a class
 * without that flag is refused with its own reason. The user class delegates its step to
 * velocity Verlet, so its trajectory must equal velocity Verlet's bit for bit.
 * Checks (tolerances stated): the built-in classes' factors are 1 and their flags as
 * documented; dt(auto) with factor 0.5 is exactly 0.5 x velocity Verlet's (exact: a
 * multiplication by 0.5); positions after 300 steps equal velocity Verlet's exactly; the
 * adaptive run with the user class ends at t_end to 1e-12 relative with accepted steps; the
 * class without RESTORES is refused with FLOE_EINVAL naming its reason. */
#include "check.h"
#include "floe.h"

#include <string.h>

enum { MY_ID = 42, MY_ID_NORESTORE = 43 };

static int my_step(floe_world *w) { return floe_integrator_class_of(FLOE_VELOCITY_VERLET)->step(w); }

static const floe_integrator_class my_class = {
    .version = 1, .name = "half_verlet", .id = MY_ID,
    .flags = FLOE_INTEGRATOR_RESTORES | FLOE_INTEGRATOR_HALF_KICK, .step = my_step,
    .why_not_kick_drift = "test class", .why_not_bonds = "test class", .dt_factor = 0.5};
static const floe_integrator_class my_noundo = {
    .version = 1, .name = "no_undo", .id = MY_ID_NORESTORE, .flags = FLOE_INTEGRATOR_HALF_KICK, .step = my_step,
    .why_not_restores = "the test class keeps no copy", .why_not_kick_drift = "test class",
    .why_not_bonds = "test class", .dt_factor = 1.0};
static const floe_integrator_class *get_my(void) { return &my_class; }
static const floe_integrator_class *get_noundo(void) { return &my_noundo; }

typedef struct { floe_params_head head; } no_params;

/* a sphere dropped on a wall with a linear law (the law gives the critical estimate) */
static floe_world *drop_world(int integ, double dt, int adaptive) {
    floe_world_def d = floe_default_world_def();
    d.integrator = integ;
    d.dt = dt;
    d.adaptive = adaptive;
    d.gravity[2] = -9.81;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 1000, 1e7, 0.3};
    int mi = floe_world_add_material(w, &m);
    floe_world_set_law(w, mi, mi, floe_linear_law_create(1e4, 5e3, 0.5, 0.5, 0.3));
    const double pt[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, pt, n, mi, FLOE_FIXED);
    int g = floe_world_add_geometry(w, floe_sphere_create(0.01));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = g;
    p.material = mi;
    p.x[2] = 0.0105;
    p.w[0] = 3.0;
    floe_world_add_particle(w, &p);
    return w;
}

int main(void) {
    char err[256];
    CHECK(floe_register_builtins(err, sizeof err) == FLOE_OK, "builtins: %s", err);
    /* the built-in classes */
    const int ids[3] = {FLOE_VELOCITY_VERLET, FLOE_LEAPFROG, FLOE_RK2};
    const unsigned flags[3] = {
        FLOE_INTEGRATOR_RESTORES | FLOE_INTEGRATOR_KICK_DRIFT | FLOE_INTEGRATOR_UNDAMPED_BONDS | FLOE_INTEGRATOR_HALF_KICK,
        FLOE_INTEGRATOR_UNDAMPED_BONDS | FLOE_INTEGRATOR_HALF_KICK, FLOE_INTEGRATOR_RESTORES};
    for (int k = 0; k < 3; k++) {
        const floe_integrator_class *c = floe_integrator_class_of(ids[k]);
        CHECK(c && c->dt_factor == 1.0 && c->flags == flags[k] && c->step, "class %d: factor 1, flags %u", ids[k],
              flags[k]);
        const floe_registry_entry *e = c ? floe_registry_find(FLOE_KIND_INTEGRATOR, c->name) : NULL;
        CHECK(e && ((floe_integrator_class_fn)e->create)() == c && e->source && e->doc,
              "class %d is registered with its doc and source", ids[k]);
    }
    const floe_registry_entry *nm = floe_registry_find(FLOE_KIND_INTEGRATOR, "newmark_implicit");
    CHECK(nm && !((floe_integrator_class_fn)nm->create)()->step && isinf(((floe_integrator_class_fn)nm->create)()->dt_factor) &&
              floe_schema_index(nm, "beta") >= 0,
          "newmark_implicit: documented (beta in its schema), no world step, unconditionally stable");
    CHECK(floe_integrator_class_of(MY_ID) == NULL, "an unregistered id has no class");

    /* register the user classes as a plugin would */
    const floe_registry_entry mine = {.kind = FLOE_KIND_INTEGRATOR, .name = "half_verlet", .title = "test",
                                      .doc = "velocity Verlet at half the step", .params_size = sizeof(no_params),
                                      .create = (floe_fn)get_my};
    const floe_registry_entry noundo = {.kind = FLOE_KIND_INTEGRATOR, .name = "no_undo", .title = "test",
                                        .doc = "cannot undo", .params_size = sizeof(no_params),
                                        .create = (floe_fn)get_noundo};
    CHECK(floe_register(&mine, err, sizeof err) == FLOE_OK && floe_register(&noundo, err, sizeof err) == FLOE_OK,
          "register the test classes: %s", err);
    CHECK(floe_integrator_class_of(MY_ID) == &my_class && !strcmp(floe_integrator_name(MY_ID), "half_verlet"),
          "a registered class is found by value and named");

    /* the critical-step factor: dt auto = safety x factor x estimate */
    floe_world *a = drop_world(FLOE_VELOCITY_VERLET, 0, 0), *b = drop_world(MY_ID, 0, 0);
    CHECK(floe_world_prepare(a) == FLOE_OK && floe_world_prepare(b) == FLOE_OK, "prepare: %s %s",
          floe_world_last_error(a), floe_world_last_error(b));
    printf("  dt auto: velocity_verlet %.17g, half_verlet %.17g\n", floe_world_dt(a), floe_world_dt(b));
    CHECK(floe_world_dt(b) == 0.5 * floe_world_dt(a) && floe_world_dt(a) > 0,
          "factor 0.5 halves the automatic step exactly (%.17g vs %.17g)", floe_world_dt(b), floe_world_dt(a));
    floe_world_destroy(a);
    floe_world_destroy(b);

    /* the same given step: the delegating class follows velocity Verlet bit for bit */
    a = drop_world(FLOE_VELOCITY_VERLET, 1e-4, 0);
    b = drop_world(MY_ID, 1e-4, 0);
    int rc = FLOE_OK;
    for (int s = 0; s < 300 && !rc; s++) rc = floe_world_step(a) | floe_world_step(b);
    floe_particle_state pa, pb;
    floe_world_get_particle(a, 1, &pa);
    floe_world_get_particle(b, 1, &pb);
    CHECK(rc == FLOE_OK && !memcmp(pa.x, pb.x, sizeof pa.x) && !memcmp(pa.q, pb.q, sizeof pa.q) &&
              !memcmp(pa.v, pb.v, sizeof pa.v),
          "300 steps: the user class's trajectory equals velocity Verlet's exactly (z %.17g vs %.17g)", pb.x[2], pa.x[2]);
    printf("  after 300 steps: z %.17g (velocity_verlet) %.17g (half_verlet)\n", pa.x[2], pb.x[2]);
    floe_world_destroy(a);
    floe_world_destroy(b);

    /* the adaptive controller wraps the user class (it restores) */
    b = drop_world(MY_ID, 0, 1);
    rc = floe_world_run(b, 0.02, NULL, NULL);
    floe_step_stats st;
    floe_world_step_stats(b, &st);
    CHECK(rc == FLOE_OK && fabs(floe_world_time(b) - 0.02) <= 1e-12 * 0.02 && st.accepted > 0,
          "adaptive run with the user class reaches t_end (rc %d, t %.17g, %ld accepted, %ld rejected): %s", rc,
          floe_world_time(b), st.accepted, st.rejected, floe_world_last_error(b));
    printf("  adaptive half_verlet: %ld accepted, %ld rejected, dt in [%g, %g]\n", st.accepted, st.rejected,
           st.dt_min_used, st.dt_max_used);
    floe_world_destroy(b);
    /* ... and refuses the class that cannot undo a trial step, with its reason */
    b = drop_world(MY_ID_NORESTORE, 0, 1);
    rc = floe_world_prepare(b);
    CHECK(rc == FLOE_EINVAL && strstr(floe_world_last_error(b), "the test class keeps no copy") &&
              strstr(floe_world_last_error(b), "adaptive steps need an integrator whose trial step can be undone"),
          "adaptive + a class without RESTORES refused with its reason (rc %d): %s", rc, floe_world_last_error(b));
    floe_world_destroy(b);

    /* the scene's time.integrator is looked up in the registry */
    const char *scene = "dimension: 3\ntime: {duration: 0.001, integrator: half_verlet}\n"
                        "materials:\n  - {name: g, density: 1000, young: 1.0e7, poisson: 0.3}\n"
                        "laws:\n  - {materials: [g, g], model: linear, kn: 1.0e4, ks: 5.0e3, friction: 0.3}\n"
                        "bodies:\n  - {shape: {sphere: {radius: 0.01}}, material: g, position: [0, 0, 0]}\n"
                        "  - {shape: {sphere: {radius: 0.01}}, material: g, position: [0.021, 0, 0]}\n";
    floe_world *w = NULL;
    floe_scene_info info;
    rc = floe_scene_load_ex("<test>", scene, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && w && floe_world_definition(w)->integrator == MY_ID,
          "time.integrator: half_verlet names the registered class (rc %d): %s", rc, err);
    floe_world_destroy(w);
    return check_summary("test_integrator_class");
}
