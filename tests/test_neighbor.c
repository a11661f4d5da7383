/* test_neighbor.c - the Verlet neighbour list: every pair whose bounding spheres are
 * closer than the skin is listed (versus brute force) for mixed sizes, tiny (1e-6 m) and
 * huge (1e3 m, offset 1e6 m) domains; the shear history of touching pairs survives a
 * rebuild, and a settling pile's positions do not depend on how often the list is rebuilt;
 * a moving wall does work that the energy ledger books; the history's stride (8 or 10
 * doubles per entry) follows the world's shapes and laws, kept bit for bit across a restride. */
#include "floe.h"
#include "world_internal.h" /* internal: unit test of the neighbour list (core/world/neighbor.c: floe_nl_*, the Verlet skin) */
#include "check.h"
#include <stdlib.h>
#include <string.h>

static double rnd(unsigned *s) { *s = *s * 1664525u + 1013904223u; return (*s >> 8) / 16777216.0; }

/* a pile of side^3 spheres (r = 1 mm, Hertz-Mindlin with friction) above a floor, leaning
 * on a side wall (gravity tilted: contacts slide on it), skin as given (0: the default);
 * box: a box shape registered too, which no particle has. Not prepared */
static floe_world *leaning_pile(int side, double skin, unsigned seed, int box) {
    floe_world_def d = floe_default_world_def();
    d.gravity[2] = -9.81;
    d.gravity[0] = -2.0;
    d.dt = 2e-6;
    d.skin = skin;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"g", 2500, 5e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5));
    int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    if (box) floe_world_add_geometry(w, floe_box_create(0.001, 0.001, 0.001));
    double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1}, nx[3] = {1, 0, 0};
    floe_world_add_wall(w, o, nz, 0, FLOE_FIXED);
    floe_world_add_wall(w, o, nx, 0, FLOE_FIXED);
    for (int k = 0; k < side; k++)
        for (int j = 0; j < side; j++)
            for (int i = 0; i < side; i++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g;
                floe_v3_set(p.x, 0.0012 + 0.002005 * i + 2e-5 * rnd(&seed), 0.0012 + 0.002005 * j + 2e-5 * rnd(&seed),
                            0.0012 + 0.002005 * k);
                floe_world_add_particle(w, &p);
            }
    return w;
}

static void check_pairs(const char *what, double scale, double offset, int n) {
    floe_particles p;
    memset(&p, 0, sizeof p);
    p.n = n;
    p.x = malloc(3 * n * sizeof(double));
    p.q = calloc(4 * n, sizeof(double));
    p.radius = malloc(n * sizeof(double));
    p.motion = calloc(n, 1);
    unsigned s = 3;
    for (int i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) p.x[3 * i + k] = offset + scale * rnd(&s);
        p.radius[i] = scale * (i % 7 == 0 ? 0.03 : 0.006) * (0.5 + rnd(&s)); /* mixed sizes */
        if (i == 5) p.radius[i] = 0.25 * scale; /* and one boulder 40x the median size */
        p.q[4 * i] = 1;
    }
    floe_neighbor_list nl;
    floe_nl_init(&nl);
    nl.skin = 0.001 * scale;
    CHECK(floe_nl_build(&nl, &p, 3, 16) == FLOE_OK, "build");
    long expect = 0, missing = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            double d[3];
            floe_v3_sub(d, p.x + 3 * j, p.x + 3 * i);
            double lim = p.radius[i] + p.radius[j] + nl.skin;
            if (floe_v3_dot(d, d) > lim * lim) continue;
            expect++;
            int found = 0;
            for (int k = 0; k < nl.npairs && !found; k++) found = nl.pi[k] == i && nl.pj[k] == j;
            missing += !found;
        }
    char msg[128];
    snprintf(msg, sizeof msg, "%s: %d listed pairs equal the %ld brute-force pairs", what, nl.npairs, expect);
    CHECK(missing == 0 && nl.npairs == expect, "%s (missing %ld)", msg, missing);
    printf("  %s\n", msg);
    floe_nl_free(&nl);
    free(p.x); free(p.q); free(p.radius); free(p.motion);
}

int main(void) {
    check_pairs("unit domain", 1.0, 0.0, 2000);
    check_pairs("tiny domain (1e-6 m)", 1e-6, 0.0, 2000);
    check_pairs("huge domain (1e3 m at 1e6 m)", 1e3, 1e6, 2000);

    /* history survives rebuilds: a sphere held against a wall with a sticking tangential
     * spring; rebuild the list by hand every step and compare with a run without */
    double fx[2];
    for (int forced = 0; forced < 2; forced++) {
        floe_world_def d = floe_default_world_def();
        d.gravity[2] = -9.81; d.gravity[0] = 2.0; /* tilt: friction holds it (mu = 0.5) */
        d.dt = 1e-5;
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"g", 2500, 1e7, 0.3};
        floe_world_add_material(w, &m);
        floe_world_set_law(w, 0, 0, floe_linear_law_create(1e4, 5e3, 5.0, 2.0, 0.5));
        int g = floe_world_add_geometry(w, floe_box_create(0.01, 0.01, 0.01));
        double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
        floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        floe_v3_set(p.x, 0, 0, 0.005);
        int i = floe_world_add_particle(w, &p);
        floe_world_record_contacts(w, 1);
        floe_world_prepare(w);
        for (int s = 0; s < 20000; s++) {
            if (forced) floe_nl_build(&w->nl, &w->p, 3, 16);
            floe_world_step(w);
        }
        fx[forced] = w->ncontacts ? w->contacts[0].force[0] : 0;
        CHECK_NEAR(fabs(fx[forced]), w->p.mass[i] * 2.0, 1e-6, "friction force held by the shear spring = m g_x (tol 1e-6)");
        printf("  tangential equilibrium: net x force %.3e N, x = %.3e m, rebuilds %ld\n", w->p.f[3 * i], w->p.x[3 * i],
               w->nl.rebuilds);
        CHECK(fabs(w->p.x[3 * i]) < 1e-4, "the block must stick (x = %g)", w->p.x[3 * i]);
        floe_world_destroy(w);
    }
    CHECK(fabs(fx[0] - fx[1]) < 1e-12, "rebuilding every step must not change the result (%g vs %g)", fx[0], fx[1]);

    /* a settling pile (Hertz-Mindlin with friction, a floor and a side wall): the list is
     * rebuilt at nearly every step with a tiny skin and a few times with a wide one; the
     * touching pairs and their histories carry over (the rows matched, the histories moved
     * in place as entries come and go), and a pair's force is added in the list's order of
     * the touching entries either way, so every position must agree to the last bit */
    {
        double *xs[2] = {NULL, NULL};
        long reb[2] = {0, 0};
        int np = 0, nc[2] = {0, 0};
        for (int run = 0; run < 2; run++) {
            floe_world *w = leaning_pile(8, run == 0 ? 1e-7 : 8e-4, 11, 0);
            CHECK(floe_world_prepare(w) == FLOE_OK, "prepare the pile");
            for (int s = 0; s < 15000; s++)
                if (floe_world_step(w) != FLOE_OK) {
                    CHECK(0, "step %d of the pile: %s", s, floe_world_last_error(w));
                    break;
                }
            floe_neighbor_stats ns;
            floe_world_neighbor_stats(w, &ns);
            reb[run] = ns.rebuilds;
            nc[run] = floe_world_contact_count(w);
            np = w->p.n;
            xs[run] = malloc(3 * (size_t)np * sizeof(double));
            memcpy(xs[run], w->p.x, 3 * (size_t)np * sizeof(double));
            floe_world_destroy(w);
        }
        printf("  settling pile: rebuilds %ld (skin 1e-7 m) and %ld (skin 8e-4 m), contacts %d and %d\n", reb[0], reb[1],
               nc[0], nc[1]);
        CHECK(reb[0] > 20 * reb[1] && reb[0] > 500, "the tiny skin must rebuild far more often (%ld vs %ld)", reb[0], reb[1]);
        CHECK(nc[0] > 300 && nc[0] == nc[1], "the pile must settle into the same contacts (%d vs %d)", nc[0], nc[1]);
        CHECK(memcmp(xs[0], xs[1], 3 * (size_t)np * sizeof(double)) == 0,
              "positions must be the same bits whatever the rebuild frequency");
        free(xs[0]);
        free(xs[1]);
    }

    /* the history's stride (floe_contact.h): a world of spheres and planes under
     * Hertz-Mindlin keeps 8 doubles per entry, one with a box shape 10; a shape added in the
     * middle of a run restrides the entries, keeping every slot: the run then goes on to the
     * same bits as one that had the box from the start (the pile above, leaning on the side
     * wall, so its springs are loaded) */
    {
        double *xs[2] = {NULL, NULL};
        int np = 0, hs_mid[2] = {0, 0}, hs_end[2] = {0, 0}, kept = 1, touching = 0;
        for (int run = 0; run < 2; run++) {
            floe_world *w = leaning_pile(5, 0, 5, run == 1); /* run 1: a box shape no particle has */
            CHECK(floe_world_prepare(w) == FLOE_OK, "prepare the stride pile");
            for (int s = 0; s < 8000 && floe_world_step(w) == FLOE_OK; s++) continue;
            hs_mid[run] = w->nl.hs;
            if (run == 0) { /* the box shape now: 8 -> 10 doubles per entry, the slots kept */
                const int n8 = w->nl.npairs;
                double *h8 = malloc((size_t)(n8 ? n8 : 1) * 8 * sizeof *h8);
                memcpy(h8, w->nl.hist, (size_t)n8 * 8 * sizeof *h8);
                floe_world_add_geometry(w, floe_box_create(0.001, 0.001, 0.001));
                CHECK(floe_world_hist_layout(w) == FLOE_OK, "restride: %s", floe_world_last_error(w));
                for (int k = 0; k < n8; k++) {
                    touching += w->nl.touching[k];
                    kept &= memcmp(w->nl.hist + 10 * (size_t)k, h8 + 8 * (size_t)k, 8 * sizeof *h8) == 0 &&
                            w->nl.hist[10 * (size_t)k + 8] == 0 && w->nl.hist[10 * (size_t)k + 9] == 0;
                }
                free(h8);
            }
            for (int s = 0; s < 4000 && floe_world_step(w) == FLOE_OK; s++) continue;
            hs_end[run] = w->nl.hs;
            np = w->p.n;
            xs[run] = malloc(3 * (size_t)np * sizeof(double));
            memcpy(xs[run], w->p.x, 3 * (size_t)np * sizeof(double));
            floe_world_destroy(w);
        }
        printf("  history stride: %d doubles (spheres, planes), %d with a box shape; %d touching entries restrided\n",
               hs_mid[0], hs_mid[1], touching);
        CHECK(hs_mid[0] == FLOE_HIST_COMPACT && hs_mid[1] == FLOE_MAX_HISTORY && hs_end[0] == FLOE_MAX_HISTORY &&
              hs_end[1] == FLOE_MAX_HISTORY, "strides %d, %d, then %d, %d", hs_mid[0], hs_mid[1], hs_end[0], hs_end[1]);
        CHECK(kept && touching > 50, "the restride must keep every entry's 8 slots and zero the new ones (%d touching)",
              touching);
        CHECK(memcmp(xs[0], xs[1], 3 * (size_t)np * sizeof(double)) == 0,
              "a run restrided in its middle must go on to the bits of one at 10 doubles throughout");
        free(xs[0]);
        free(xs[1]);

        /* a law that asks for more history than an entry holds is refused */
        floe_world_def d = floe_default_world_def();
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"g", 2500, 5e7, 0.3};
        floe_world_add_material(w, &m);
        static floe_contact_law_class big;
        big = floe_hertz_mindlin_law_class;
        big.name = "big_history";
        big.history_size = FLOE_LAW_HISTORY + 1;
        floe_contact_law *law = floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5);
        law->klass = &big;
        const int rc = floe_world_set_law(w, 0, 0, law);
        printf("  a law keeping %d doubles: %s\n", big.history_size, floe_world_last_error(w));
        CHECK(rc == FLOE_EINVAL && strstr(floe_world_last_error(w), "big_history keeps 5 doubles"),
              "set_law must refuse history_size 5 by name (rc %d)", rc);
        floe_world_destroy(w);
    }

    /* a piston (kinematic wall) compresses a sphere onto the floor: its work is booked */
    {
        floe_world_def d = floe_default_world_def();
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"g", 2500, 1e7, 0.3};
        floe_world_add_material(w, &m);
        floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.9, 0.0));
        int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
        double o[3] = {0, 0, 0}, n[3] = {0, 0, 1}, top[3] = {0, 0, 0.002}, down[3] = {0, 0, -1};
        floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
        int piston = floe_world_add_wall(w, top, down, 0, FLOE_KINEMATIC);
        w->p.v[3 * piston + 2] = -0.001; /* constant prescribed velocity */
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g;
        floe_v3_set(p.x, 0, 0, 0.001);
        floe_world_add_particle(w, &p);
        CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
        floe_world_run(w, 0.02, NULL, NULL); /* 20 um of travel */
        floe_energy e = floe_world_energy(w);
        printf("  piston: work %.4e J, elastic %.4e J, kinetic %.2e J, dissipated %.2e J\n", e.work_boundary, e.elastic,
               e.kinetic_trans, e.dissipated);
        CHECK(e.work_boundary > 0, "the piston must do positive work");
        CHECK_NEAR(e.elastic + e.kinetic_trans + e.dissipated, e.work_boundary, 1e-9, "piston work = stored + kinetic + dissipated (tol 1e-9)");
        floe_world_destroy(w);
    }
    return check_summary("test_neighbor");
}
