/* test_manifold_cache.c - the polytope manifold's corner cache (contact/detect/detect.c
 * manifold, docs/models.md "Contact manifold"): while a resting pair has moved less than the
 * margin its cache kept, the manifold tests only the corners that were near the other body.
 * It must change no bit. Two worlds of 30 polyhedral grains (14 random planes) with
 * Hertz-Mindlin contact, friction and dashpots, one with the cache and one without
 * (world_internal.h mf_cache_off), run in lockstep: they settle in a walled box for 6,000
 * steps, then every grain is kicked (a random velocity up to 0.3 m/s and spin up to 30
 * rad/s: every cache's margin is overrun and must be found stale) and they run 2,000 more.
 *   - positions, velocities, angular momenta and the energy ledger equal bit for bit every
 *     250 steps;
 *   - the cache was used: at least half of the manifolds of the cached world came from it,
 *     none of the other's; after the kick, new caches were built (the hit rate of the last
 *     2,000 steps below 100 %, and above 0). */
#include "floe.h"
#include "world_internal.h"
#include "world_read.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>

#define TEST_RNG_SEED 0x5EED5A1D5EED0019ull
#include "test_rng.h"
#include "poly_box.h"

#define NP 30
#define NPL 14
#define NSETTLE 6000
#define NAFTER 2000
static const double R = 0.01;

static floe_world *scene(int cache_off) {
    rng_s = TEST_RNG_SEED;
    floe_material m = {"m", 2500, 1e7, 0.3};
    floe_world *w = poly_box_new(R, &m);
    if (!w) return NULL;
    floe_world_set_threads(w, 1);
    w->mf_cache_off = cache_off;
    return poly_box_world(w, R, NP, NPL, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5));
}

static int same(const double *a, const double *b, int n) { return memcmp(a, b, sizeof(double) * (size_t)n) == 0; }

static long cached(const floe_world *w) {
    floe_detect_stats d;
    floe_world_detect_stats(w, &d);
    return d.manifold_cached;
}

static long manifolds(const floe_world *w) { /* the LP evaluations that found a contact */
    floe_detect_stats d;
    floe_world_detect_stats(w, &d);
    return d.lp;
}

int main(void) {
    floe_world *a = scene(0), *b = scene(1);
    CHECK(a && b, "scenes");
    if (!a || !b) return check_summary("test_manifold_cache");
    const int n = pview(a).n;
    int ok = 1, steps = 0;
    long c_settle = 0, lp_settle = 0;
    for (int s = 1; s <= NSETTLE + NAFTER && ok; s++) {
        if (s == NSETTLE + 1) { /* the kick: the same in both worlds */
            c_settle = cached(a);
            lp_settle = manifolds(a);
            rng_s = TEST_RNG_SEED ^ 0xABCDull;
            double v[3], om[3];
            for (int i = 0; i < n; i++) {
                if (pview(a).radius[i] == INFINITY) continue;
                rand_unit(v);
                rand_unit(om);
                const double sv = uni(0, 0.3), so = uni(0, 30);
                for (int k = 0; k < 3; k++) { v[k] *= sv; om[k] *= so; }
                CHECK(floe_world_set_velocity(a, i, v, om) == FLOE_OK && floe_world_set_velocity(b, i, v, om) == FLOE_OK,
                      "kick %d", i);
            }
        }
        CHECK(floe_world_step(a) == FLOE_OK, "step (cache): %s", floe_world_last_error(a));
        CHECK(floe_world_step(b) == FLOE_OK, "step (no cache): %s", floe_world_last_error(b));
        steps = s;
        if (s % 250) continue;
        const floe_particles_view pa = pview(a), pb = pview(b);
        const floe_energy ea = floe_world_energy(a), eb = floe_world_energy(b);
        ok = same(pa.x, pb.x, 3 * n) && same(pa.v, pb.v, 3 * n) && same(pa.L, pb.L, 3 * n) &&
             ea.elastic == eb.elastic && ea.dissipated == eb.dissipated;
        CHECK(ok, "step %d: the run with the corner cache differs from the one without (elastic %.17g against %.17g)", s,
              ea.elastic, eb.elastic);
    }
    const long ca = cached(a), la = manifolds(a), cb = cached(b);
    const double settle_rate = lp_settle > 0 ? (double)c_settle / (double)lp_settle : 0.0;
    const double after_rate = la > lp_settle ? (double)(ca - c_settle) / (double)(la - lp_settle) : 0.0;
    printf("%d steps, the runs equal to the bit: %s; LP evaluations %ld, manifolds from the cache %ld (settling %.1f %%, "
           "after the kick %.1f %%); without the cache %ld\n",
           steps, ok ? "yes" : "no", la, ca, 100 * settle_rate, 100 * after_rate, cb);
    CHECK(cb == 0, "the world without the cache used it (%ld)", cb);
    CHECK(ca >= la / 2, "the cache served under half of the manifolds (%ld of %ld LP evaluations)", ca, la);
    CHECK(after_rate > 0 && after_rate < 1, "after the kick the caches were rebuilt (hit rate %.3f)", after_rate);
    floe_world_destroy(a);
    floe_world_destroy(b);
    return check_summary("test_manifold_cache");
}
