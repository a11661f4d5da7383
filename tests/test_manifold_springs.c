/* test_manifold_springs.c - the contact manifold's springs under the built-in linear and
 * Hertz-Mindlin laws are evaluated inline by the contact stage (core/world/forces.c,
 * spring_builtin: the law's own operations at vn = 0, dt = 0 and an empty history, less those
 * that add zeros; docs/architecture.md). Against the law's call: the same law object wrapped
 * in a class of its own that forwards every method to it, so that the stage calls the force
 * function for every spring (and the deepest point's load). For each law, 30 polyhedral
 * grains (14 random planes, random orientations and spins) with friction and dashpots settle
 * on the floor of a walled box for 3,000 steps, once with the law and once wrapped:
 *   - positions, velocities, angular momenta and the energy ledger (elastic, dissipated)
 *     equal bit for bit after every 500 steps;
 *   - the manifold was exercised: at the end, the touching grain pairs that have extra
 *     springs (floe_world_detect's nextra) number at least 10, and the stage's contacts at
 *     least 30. */
#include "floe.h"
#include "world_internal.h"
#include "world_read.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>

#define TEST_RNG_SEED 0x5EED5A1D5EED0001ull
#include "test_rng.h"
#include "poly_box.h"

#define NP 30
#define NPL 14
#define NSTEPS 8000
static const double R = 0.01;

/* ---- a class that forwards to a law it holds: the stage sees a law it does not know ---- */
typedef struct wrapped {
    floe_contact_law base;
    floe_contact_law *inner;
} wrapped;

static int w_force(const floe_contact_law *l, const floe_contact *c, double *h, floe_contact_result *o) {
    const floe_contact_law *in = ((const wrapped *)l)->inner;
    return in->klass->force(in, c, h, o);
}
static void w_stiffness(const floe_contact_law *l, double r, double m, double d, double *kn, double *cn) {
    const floe_contact_law *in = ((const wrapped *)l)->inner;
    in->klass->stiffness(in, r, m, d, kn, cn);
}
static void w_tangential(const floe_contact_law *l, double r, double m, double d, double *kt, double *ct) {
    const floe_contact_law *in = ((const wrapped *)l)->inner;
    if (in->klass->tangential_stiffness) in->klass->tangential_stiffness(in, r, m, d, kt, ct);
    else { *kt = 0; *ct = 0; }
}
static void w_info(const floe_contact_law *l, floe_law_info *info) {
    *info = floe_contact_law_info(((const wrapped *)l)->inner);
}
static void w_destroy(floe_contact_law *l) {
    wrapped *w = (wrapped *)l;
    w->inner->klass->destroy(w->inner);
    free(w);
}
static floe_contact_law_class wrapped_class = {1, "wrapped", 0, w_force, w_stiffness, w_destroy, w_tangential, w_info};

static floe_contact_law *wrap(floe_contact_law *inner) {
    wrapped *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    wrapped_class.history_size = inner->klass->history_size;
    w->base.klass = &wrapped_class;
    w->base.friction = inner->friction;
    w->inner = inner;
    return &w->base;
}

/* the scene for law kind `hm` (0 linear, 1 Hertz-Mindlin), wrapped or not; the same grains,
 * poses and velocities every time (the generator restarts) */
static floe_world *scene(int hm, int wrapped_law) {
    rng_s = TEST_RNG_SEED;
    floe_material m = {"m", 2500, 1e7, 0.3};
    floe_world *w = poly_box_new(R, &m);
    if (!w) return NULL;
    floe_contact_law *law = hm ? floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5)
                               : floe_linear_law_create(2e4, 5e3, 0.5, 0.1, 0.5);
    if (wrapped_law) law = wrap(law);
    return poly_box_world(w, R, NP, NPL, law);
}

static int same(const double *a, const double *b, int n) { return memcmp(a, b, sizeof(double) * (size_t)n) == 0; }

static void compare(int hm) {
    const char *name = hm ? "hertz-mindlin" : "linear";
    floe_world *a = scene(hm, 0), *b = scene(hm, 1);
    CHECK(a && b, "%s: scenes", name);
    if (!a || !b) return;
    const int n = pview(a).n;
    int ok = 1;
    for (int s = 1; s <= NSTEPS && ok; s++) {
        CHECK(floe_world_step(a) == FLOE_OK, "%s: step (inline springs): %s", name, floe_world_last_error(a));
        CHECK(floe_world_step(b) == FLOE_OK, "%s: step (the law's call): %s", name, floe_world_last_error(b));
        if (s % 1000) continue;
        const floe_particles_view pa = pview(a), pb = pview(b);
        const floe_energy ea = floe_world_energy(a), eb = floe_world_energy(b);
        ok = same(pa.x, pb.x, 3 * n) && same(pa.v, pb.v, 3 * n) && same(pa.L, pb.L, 3 * n) &&
             ea.elastic == eb.elastic && ea.dissipated == eb.dissipated;
        CHECK(ok, "%s: step %d: the inline springs' run differs from the law's call (elastic %.17g against %.17g)",
              name, s, ea.elastic, eb.elastic);
    }
    /* the manifold was in play: touching grain pairs with extra springs at the end */
    int touching = 0, with_extra = 0;
    double *warm = malloc(sizeof(double) * FLOE_DETECT_WARM);
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            if (pview(a).radius[i] == INFINITY && pview(a).radius[j] == INFINITY) continue; /* two walls */
            for (int k = 0; k < FLOE_DETECT_WARM; k++) warm[k] = NAN;
            floe_contact c;
            if (floe_world_detect(a, i, j, 0, warm, &c) == 1) {
                touching++;
                with_extra += c.nextra > 0;
            }
        }
    free(warm);
    printf("%s: %d touching grain pairs, %d with extra springs, the runs equal to the bit: %s\n", name, touching,
           with_extra, ok ? "yes" : "no");
    CHECK(touching >= 30 && with_extra >= 10, "%s: the manifold was not exercised (%d touching, %d with extra springs)",
          name, touching, with_extra);
    floe_world_destroy(a);
    floe_world_destroy(b);
}

int main(void) {
    compare(0);
    compare(1);
    return check_summary("test_manifold_springs");
}
