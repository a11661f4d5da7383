/* test_pd_user.c - a user PD material (floe_pd.h FLOE_PD_USER, floe_pd_material.ops) with
 * state of its own (b->mstate) in a world with adaptive steps:
 *  - its forces are the PMB forces of the same constants (the same body under the built-in
 *    pmb and the user material gives the same forces to 1e-12 relative);
 *  - its state (a count of force evaluations) is saved and restored by the world around
 *    rejected trial steps through ops->state_size/save/restore: after the run the count
 *    equals the evaluations of the prepare plus one per accepted step, exactly;
 *  - set_material refuses a user material without ops or forces; destroy frees the state
 *    (ops->release; checked under ASan). */
#include "check.h"
#include "floe.h"
#include "floe_pd.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int user_init(floe_pd_body *b) {
    b->mstate = calloc(1, sizeof(long));
    return b->mstate ? floe_pd_pmb_ops.init(b) : FLOE_ENOMEM;
}
static double user_forces(floe_pd_body *b, const double *x, double *f) {
    ++*(long *)b->mstate;
    return floe_pd_pmb_ops.forces(b, x, f);
}
static double user_c(const floe_pd_body *b) { return b->c; }
static size_t user_size(const floe_pd_body *b) { (void)b; return sizeof(long); }
static void user_save(const floe_pd_body *b, unsigned char *buf) { memcpy(buf, b->mstate, sizeof(long)); }
static void user_restore(floe_pd_body *b, const unsigned char *buf) { memcpy(b->mstate, buf, sizeof(long)); }
static void user_release(floe_pd_body *b) {
    free(b->mstate);
    b->mstate = NULL;
}
static const floe_pd_material_ops user_ops = {.name = "counted_pmb", .init = user_init, .forces = user_forces,
                                              .bond_micromodulus = user_c, .state_size = user_size,
                                              .save = user_save, .restore = user_restore, .release = user_release};

static floe_pd_body *cube(double x0, double z0) {
    floe_pd_region r;
    memset(&r, 0, sizeof r);
    r.dim = 3;
    r.dx = 0.001;
    r.horizon_factor = 3;
    double lo[3] = {x0, 0, z0}, hi[3] = {x0 + 0.004, 0.004, z0 + 0.004};
    memcpy(r.lo, lo, sizeof lo);
    memcpy(r.hi, hi, sizeof hi);
    floe_pd_body *b = NULL;
    floe_pd_body_create(&b, &r);
    return b;
}

int main(void) {
    floe_pd_material pmb = floe_pd_material_pmb(2200, 1e9, 0);
    floe_pd_material user = pmb;
    user.model = FLOE_PD_USER;
    user.ops = &user_ops;
    /* same forces as the built-in on a stretched body */
    floe_pd_body *a = cube(0, 0), *b = cube(0, 0);
    CHECK(floe_pd_set_material(a, &pmb) == FLOE_OK && floe_pd_set_material(b, &user) == FLOE_OK, "materials");
    size_t n = (size_t)a->n;
    double *x = malloc(3 * n * sizeof *x), *fa = calloc(3 * n, sizeof *fa), *fb = calloc(3 * n, sizeof *fb);
    for (size_t i = 0; i < 3 * n; i++) x[i] = a->X[i] * (1 + 1e-3 * (double)(i % 3 + 1));
    double ea = floe_pd_forces(a, x, fa), eb = floe_pd_forces(b, x, fb), worst = 0, fbig = 0;
    for (size_t i = 0; i < 3 * n; i++) { worst = fmax(worst, fabs(fa[i] - fb[i])); fbig = fmax(fbig, fabs(fa[i])); }
    CHECK(worst <= 1e-12 * fbig && fabs(ea - eb) <= 1e-12 * ea, "user material = pmb: force diff %.3g of %.3g, "
          "energy %.9g vs %.9g", worst, fbig, eb, ea);
    CHECK(*(long *)b->mstate == 1, "one evaluation counted");
    floe_pd_material bad = user;
    bad.ops = NULL;
    CHECK(floe_pd_set_material(a, &bad) == FLOE_EINVAL && a->mat.model == FLOE_PD_PMB, "no ops refused, pmb kept");
    CHECK(floe_pd_surface_correction(b) == FLOE_ENOTSUP, "no surface correction hook: FLOE_ENOTSUP");
    free(x); free(fa); free(fb);
    floe_pd_body_destroy(a);
    floe_pd_body_destroy(b);

    /* adaptive steps: the PD cube thrown onto a wall (its contact rejects a trial) */
    floe_world_def d = floe_default_world_def();
    d.adaptive = 1;
    d.gravity[2] = -9.81;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 2200, 1e8, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.9, 0.3));
    const double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1}, v0[3] = {0, 0, -0.5};
    floe_world_add_wall(w, o, nz, 0, FLOE_FIXED);
    floe_pd_body *c = cube(0, 0.0008);
    CHECK(floe_pd_set_material(c, &user) == FLOE_OK, "user material set");
    int first;
    CHECK(floe_world_add_pd_body(w, c, 0, v0, &first) == FLOE_OK, "add: %s", floe_world_last_error(w));
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    const floe_pd_body *cb = floe_world_pd_body(w, 0, NULL);
    long c0 = *(long *)cb->mstate;
    CHECK(floe_world_run(w, 0.01, NULL, NULL) == FLOE_OK, "run: %s", floe_world_last_error(w));
    floe_step_stats st;
    floe_world_step_stats(w, &st);
    long cnt = *(long *)cb->mstate - c0;
    CHECK(st.rejected > 0 && cnt == st.accepted, "a user material's state is restored after rejected trials: %ld "
          "evaluations kept for %ld accepted steps (%ld rejected)", cnt, st.accepted, st.rejected);
    printf("  counted_pmb: %ld accepted, %ld rejected, %ld evaluations kept\n", st.accepted, st.rejected, cnt);
    floe_world_destroy(w);
    return check_summary("test_pd_user");
}
