/* test_sphere_path.c - the contact stage's lean body for sphere pairs (core/world/forces.c,
 * sphere_pair) and its inline sphere-wall kernel against the general path: the same
 * operations in the same order, so the same bits (docs/architecture.md, "The pair loop").
 *  1. 300 Hertz-Mindlin spheres of mixed sizes (friction, damping, gravity) poured into a
 *     box of six walls, one of them tilted and one added after the spheres (walls on both
 *     sides of the spheres' indices: every sphere-wall entry has the sphere as i all the
 *     same, checked in 2), for 8,000 steps; the same scene with one fixed
 *     compound body far above them sends every list entry through the general body
 *     (contact_pair): positions, velocities, angular velocities, forces, torques and the
 *     energy ledger equal bit for bit;
 *     the same for the linear law with dashpots (the fused kernels of both laws), and for
 *     two materials whose spheres alternate, under three laws (Hertz-Mindlin for each
 *     material with itself, two different objects, the linear law between them): the
 *     fused path's batches of entries (sph_flush_lanes) end at every change of law, and the
 *     sums still come in list order; Hertz-Mindlin under adaptive steps (the stage
 *     measures each contact's overlap change: the batches' lanes too); and the linear law
 *     with tension among fast spheres (up to 5 m/s a component: a grazing contact's frame
 *     turns by several hundredths of a radian a step). Each case counts the batches that took a rare case's full form (a
 *     turned spring, a linear contact's first evaluation, a slip; w->st_lanes) and checks
 *     that both copies of each ran where the scene has them;
 *  2. every sphere-wall contact the stage recorded (the inline kernel, seen from i) against
 *     detection's own answer for the pair (floe_world_probe_contact): normal, depth and
 *     point equal bit for bit, for walls declared before the spheres and after them, the
 *     sphere i of every such pair;
 *  3. a periodic cell (tilted, sheared at a rate, its diagonal held by the stress servo):
 *     216 spheres of three sizes colliding through the faces, the lanes against the general
 *     body (world_internal.h lanes_off), Hertz-Mindlin and the linear law: particles, the
 *     ledger (the cell's work in work_boundary), the cell's vectors (the servo reads the
 *     contacts' virial and stiffness sums) and the records (image branch vectors) equal bit
 *     for bit. */
#include "check.h"
#include "floe.h"
#include "world_internal.h"
#include "sheared_cell.h"
#include <math.h>
#include <string.h>

#define NS 300

static unsigned long long rng_state = 12345;
static double urand(void) {
    rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

/* the box: walls 0..4 first (floor tilted), spheres 5..5+NS-1, then the last wall; with a
 * compound, a fixed body of two spheres near the ceiling, above it for the fast spheres
 * (index 6 + NS) */
static floe_world *scene(int with_compound, int linear) {
    floe_world_def def = floe_default_world_def();
    def.dt = 5e-6;
    def.gravity[2] = -9.81;
    def.skin = 0.0004;
    if (linear == 3) { /* adaptive steps: the stage measures every contact's overlap change */
        def.adaptive = 1;
        def.dt_min = 1e-7;
        def.dt_max = 8e-6;
    }
    char err[256];
    floe_world *w = floe_world_create(&def, err, sizeof err);
    if (!w) return NULL;
    floe_material m = {"glass", 2500, 1e7, 0.3}, m2 = {"rubber", 1200, 5e6, 0.4};
    floe_world_add_material(w, &m);
    /* Hertz-Mindlin, or the linear law with dashpots (its an_ext from the accelerations);
     * linear = 2: two materials under three laws */
    floe_contact_law *law0 = linear == 5   ? floe_linear_law_create(2e4, 1e4, 0.02, 0.01, 0.5)
                             : linear == 1 || linear == 4 ? floe_linear_law_create(200, 100, 0.02, 0.01, 0.5)
                                                         : floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5);
    if (linear == 5 && law0) ((floe_linear_law *)law0)->tension = 1;
    floe_world_set_law(w, 0, 0, law0);
    if (linear == 2) {
        floe_world_add_material(w, &m2);
        floe_world_set_law(w, 1, 1, floe_hertz_mindlin_law_create(&m2, &m2, 0.7, 0.3));
        floe_world_set_law(w, 0, 1, floe_linear_law_create(150, 80, 0.02, 0.01, 0.4));
    }
    const double L = 0.02, H = 0.06;
    double nf[3] = {0.08, -0.05, 1.0}, p0[3] = {0, 0, 0};
    floe_world_add_wall(w, p0, nf, 0, FLOE_FIXED); /* tilted floor */
    double px[3] = {L, 0, 0}, nx[3] = {-1, 0, 0}, ny0[3] = {0, 1, 0}, py[3] = {0, 0.0176, 0}, ny1[3] = {0, -1, 0};
    double nx0[3] = {1, 0, 0}, ph[3] = {0, 0, H}, nh[3] = {0, 0, -1};
    floe_world_add_wall(w, p0, nx0, 0, FLOE_FIXED);
    floe_world_add_wall(w, px, nx, 0, FLOE_FIXED);
    floe_world_add_wall(w, p0, ny0, 0, FLOE_FIXED);
    floe_world_add_wall(w, ph, nh, 0, FLOE_FIXED);
    rng_state = 12345;
    int g[3] = {floe_world_add_geometry(w, floe_sphere_create(0.0008)), floe_world_add_geometry(w, floe_sphere_create(0.001)),
                floe_world_add_geometry(w, floe_sphere_create(0.0012))};
    int glat = -1;
    for (int k = 0; k < NS; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g[k % 3];
        if (linear == 2) p.material = k % 2;
        int a = k % 7, b = (k / 7) % 7, c = k / 49;
        if (linear == 4) {
            /* an HCP lattice of touching spheres at rest (the scene loader's packing formula,
             * core/scene/scene_bodies.c): dist = r_i + r_j up to rounding, and for some
             * neighbours d2 < (r_i + r_j)^2 while rs - sqrt(d2) = 0 */
            const double d = 0.0019, ox = (c % 2) ? 0.5 * d : 0.0, oy = (c % 2) ? d * sqrt(3.0) / 6.0 : 0.0;
            if (glat < 0) glat = floe_world_add_geometry(w, floe_sphere_create(0.5 * d));
            p.geometry = glat;
            floe_v3_set(p.x, 0.0015 + ox + ((b % 2) ? 0.5 * d : 0.0) + a * d, 0.0015 + oy + b * (d * sqrt(3.0) / 2.0),
                        0.0012 + c * (d * sqrt(2.0 / 3.0)));
            floe_world_add_particle(w, &p);
            continue;
        }
        floe_v3_set(p.x, 0.0022 + 0.0023 * a + 0.00005 * urand(), 0.0022 + 0.0023 * b + 0.00005 * urand(),
                    0.0025 + 0.0023 * c + 0.00005 * urand());
        floe_v3_set(p.v, 0.1 * (urand() - 0.5), 0.1 * (urand() - 0.5), -0.3 - 0.2 * urand());
        if (linear == 5) /* fast: a grazing contact's frame turns by several hundredths of a radian a step */
            floe_v3_set(p.v, 10 * (urand() - 0.5), 10 * (urand() - 0.5), 10 * (urand() - 0.5));
        floe_v3_set(p.w, 20 * (urand() - 0.5), 20 * (urand() - 0.5), 20 * (urand() - 0.5));
        floe_world_add_particle(w, &p);
    }
    floe_world_add_wall(w, py, ny1, 0, FLOE_FIXED); /* after the spheres: pairs (sphere, wall) */
    if (with_compound) {
        floe_geometry *pieces[2] = {floe_sphere_create(0.001), floe_sphere_create(0.001)};
        double xs[6] = {-0.001, 0, 0, 0.001, 0, 0}, qs[8] = {1, 0, 0, 0, 1, 0, 0, 0};
        floe_geometry *cg = floe_compound_create(pieces, xs, qs, 2, 3, err, sizeof err);
        floe_particle_def p = floe_default_particle_def();
        p.geometry = floe_world_add_geometry(w, cg);
        p.motion = FLOE_FIXED;
        /* the fast spheres reach the ceiling: theirs above it, out of their way */
        floe_v3_set(p.x, 0.5 * L, 0.5 * L, linear == 5 ? H + 0.004 : H - 0.004);
        floe_world_add_particle(w, &p);
    }
    return w;
}

static int same(const double *a, const double *b, int n) { return memcmp(a, b, (size_t)n * sizeof(double)) == 0; }

/* one step more of both worlds, their contacts recorded: the same records, bit for bit */
static void same_records_step(floe_world *a, floe_world *b, const char *law) {
    floe_world_record_contacts(a, 1);
    floe_world_record_contacts(b, 1);
    int rc = floe_world_step(a);
    if (!rc) rc = floe_world_step(b);
    const floe_contact_info *ca = NULL, *cb = NULL;
    const int na = floe_world_contacts(a, &ca), nb = floe_world_contacts(b, &cb);
    int rdiff = na == nb ? 0 : -1;
    for (int k = 0; k < na && k < nb; k++) rdiff += memcmp(ca + k, cb + k, sizeof *ca) != 0;
    printf("  %s: recorded contacts %d and %d, differing %d\n", law, na, nb, rdiff);
    CHECK(rc == 0 && na > 0 && rdiff == 0, "%s: the records of the lanes and the general body differ (%d of %d, %d)",
          law, rdiff, na, nb);
}

/* 1. the same bits, sphere by sphere, from the lean (fused) and the general body; returns
 * world a (spheres only) stepped, for part 2 */
static floe_world *compare_paths(int linear) {
    const char *law = linear == 5 ? "linear with tension, fast spheres" : linear == 4 ? "linear, a lattice of touching spheres" : linear == 3 ? "hertz_mindlin, adaptive steps" : linear == 2 ? "three laws" : linear ? "linear" : "hertz_mindlin";
    floe_world *a = scene(0, linear), *b = scene(1, linear);
    CHECK(a && b, "%s: worlds created", law);
    if (!a || !b) return NULL;
    int rc = floe_world_prepare(a);
    CHECK(rc == 0, "%s: prepare (spheres only): %s", law, floe_world_last_error(a));
    rc = floe_world_prepare(b);
    CHECK(rc == 0, "%s: prepare (with a compound): %s", law, floe_world_last_error(b));
    for (int s = 0; s < 8000 && !rc; s++) {
        rc = floe_world_step(a);
        if (!rc) rc = floe_world_step(b);
    }
    CHECK(rc == 0, "%s: 8,000 steps: %s", law, rc ? floe_world_last_error(a) : "");
    int diff = 0, moving = 0;
    for (int i = 5; i < 5 + NS; i++) {
        floe_particle_state pa, pb;
        floe_world_get_particle(a, i, &pa);
        floe_world_get_particle(b, i, &pb);
        if (!(same(pa.x, pb.x, 3) && same(pa.v, pb.v, 3) && same(pa.w, pb.w, 3) && same(pa.f, pb.f, 3) &&
              same(pa.torque, pb.torque, 3) && same(pa.q, pb.q, 4)))
            diff++;
        moving += floe_v3_norm(pa.v) > 1e-6;
    }
    int contacts = floe_world_contact_count(a);
    printf("  %s: spheres differing between the lean and the general body: %d of %d (contacts %d, moving %d)\n", law,
           diff, NS, contacts, moving);
    CHECK(diff == 0, "%s: %d spheres differ between sphere_pair and contact_pair", law, diff);
    /* the lattice falls as a block onto the tilted floor and breaks up: few contacts at the end */
    if (linear != 5) /* the fast spheres make no pile */
        CHECK(contacts > (linear == 4 ? 0 : linear == 3 ? NS / 4 : NS / 2), "%s: the pile is in contact (%d contacts)",
              law, contacts);
    /* the batches' rare cases (sph_flush_lanes: the full form only where a live lane needs
     * it) taken and left, so that both copies of each met the general body above */
    const long *st = a->st_lanes;
    printf("  %s: batches %ld, with a turned spring %ld, a first linear evaluation %ld, a slip %ld\n", law, st[0], st[1],
           st[2], st[3]);
    CHECK(st[0] > 0 && st[3] > 0 && st[3] < st[0], "%s: batches with and without a slip (%ld of %ld)", law, st[3], st[0]);
    if (linear == 1 || linear == 5)
        CHECK(st[2] > 0 && st[2] < st[0], "%s: batches with and without a first evaluation (%ld of %ld)", law, st[2],
              st[0]);
    if (linear == 5)
        CHECK(st[1] > 0 && st[1] < st[0], "%s: batches with and without a turned spring (%ld of %ld)", law, st[1], st[0]);
    floe_energy ea = floe_world_energy(a), eb = floe_world_energy(b);
    CHECK(ea.kinetic_trans == eb.kinetic_trans && ea.kinetic_rot == eb.kinetic_rot && ea.elastic == eb.elastic &&
              ea.dissipated == eb.dissipated && ea.work_body == eb.work_body,
          "%s: energy ledger differs: K %.17g vs %.17g, elastic %.17g vs %.17g, dissipated %.17g vs %.17g", law,
          ea.kinetic_trans, eb.kinetic_trans, ea.elastic, eb.elastic, ea.dissipated, eb.dissipated);
    CHECK(ea.dissipated > 0, "%s: the dashpots and friction dissipate (%g J)", law, ea.dissipated);
    /* one step more, recorded: the lanes' records (sphere_fused_book) against contact_pair's */
    same_records_step(a, b, law);
    floe_world_record_contacts(a, 0);
    floe_world_destroy(b);
    return a;
}

/* 3. a periodic cell: 6 x 6 x 6 spheres on a cubic lattice with gaps (spacing 2.6 mm, radii
 * 0.8, 1.0 and 1.2 mm), random velocities; the cell tiles the lattice, tilted in xy, sheared
 * at 2 /s (xy), its diagonal held at -5 Pa by the servo (at most 10 /s: it is not clamped once
 * contacts form, so the lanes' stiffness sums steer it) */
static floe_world *cell_scene(int linear, int lanes_off) {
    floe_world_def def = floe_default_world_def();
    def.dt = 5e-6;
    def.skin = 0.0002;
    char err[256];
    floe_world *w = floe_world_create(&def, err, sizeof err);
    if (!w) return NULL;
    floe_material m = {"glass", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, linear ? floe_linear_law_create(200, 100, 0.02, 0.01, 0.5)
                                       : floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5));
    sheared_cell_set(w, 6, 0.0026);
    rng_state = 777;
    int g[3] = {floe_world_add_geometry(w, floe_sphere_create(0.0008)), floe_world_add_geometry(w, floe_sphere_create(0.001)),
                floe_world_add_geometry(w, floe_sphere_create(0.0012))};
    for (int k = 0; k < 216; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g[k % 3];
        sheared_cell_site(k, 6, 0.0026, p.x);
        floe_v3_set(p.v, 0.2 * (urand() - 0.5), 0.2 * (urand() - 0.5), 0.2 * (urand() - 0.5));
        floe_v3_set(p.w, 20 * (urand() - 0.5), 20 * (urand() - 0.5), 20 * (urand() - 0.5));
        floe_world_add_particle(w, &p);
    }
    w->lanes_off = lanes_off;
    return w;
}

static void compare_cell(int linear) {
    const char *law = linear ? "periodic cell, linear" : "periodic cell, hertz_mindlin";
    floe_world *a = cell_scene(linear, 0), *b = cell_scene(linear, 1);
    CHECK(a && b, "%s: worlds created", law);
    if (!a || !b) { floe_world_destroy(a); floe_world_destroy(b); return; }
    int rc = floe_world_prepare(a);
    if (!rc) rc = floe_world_prepare(b);
    CHECK(rc == 0, "%s: prepare: %s", law, floe_world_last_error(a));
    long contacts = 0, images = 0;
    for (int s = 0; s < 4000 && !rc; s++) {
        rc = floe_world_step(a);
        if (!rc) rc = floe_world_step(b);
        if (!rc && s % 100 == 0) {
            contacts += floe_world_contact_count(a);
            for (int k = 0; k < a->nl.npairs; k++) images += a->nl.touching[k] && a->nl.img && a->nl.img[k];
        }
    }
    CHECK(rc == 0, "%s: 4,000 steps: %s", law, rc ? floe_world_last_error(a) : "");
    int diff = 0;
    for (int i = 0; i < 216; i++) {
        floe_particle_state pa, pb;
        floe_world_get_particle(a, i, &pa);
        floe_world_get_particle(b, i, &pb);
        diff += !(same(pa.x, pb.x, 3) && same(pa.v, pb.v, 3) && same(pa.w, pb.w, 3) && same(pa.f, pb.f, 3) &&
                  same(pa.torque, pb.torque, 3));
    }
    double Ha[9], Hb[9];
    floe_world_cell(a, NULL, Ha);
    floe_world_cell(b, NULL, Hb);
    floe_energy ea = floe_world_energy(a), eb = floe_world_energy(b);
    printf("  %s: spheres differing between the lanes and the general body: %d of 216 (contacts summed over 40 "
           "samples %ld, through the faces %ld; H_zz %.6g of %.6g; work of the cell %.3g J)\n",
           law, diff, contacts, images, Ha[8], 6 * 0.0026, ea.work_boundary);
    CHECK(diff == 0, "%s: %d spheres differ between the lanes and the general body", law, diff);
    CHECK(contacts > 200 && images > 20, "%s: contacts, some through the faces (%ld, %ld)", law, contacts, images);
    CHECK(same(Ha, Hb, 9) && Ha[8] != 6 * 0.0026, "%s: the servo moved the cell, the same in both (H_zz %.17g, %.17g)",
          law, Ha[8], Hb[8]);
    CHECK(ea.kinetic_trans == eb.kinetic_trans && ea.elastic == eb.elastic && ea.dissipated == eb.dissipated &&
              ea.work_boundary == eb.work_boundary && ea.work_boundary != 0,
          "%s: ledger differs: elastic %.17g vs %.17g, dissipated %.17g vs %.17g, cell's work %.17g vs %.17g", law,
          ea.elastic, eb.elastic, ea.dissipated, eb.dissipated, ea.work_boundary, eb.work_boundary);
    same_records_step(a, b, law);
    floe_world_destroy(a);
    floe_world_destroy(b);
}

int main(void) {
    compare_cell(0);
    compare_cell(1);
    floe_world *lin = compare_paths(1);
    floe_world_destroy(lin);
    /* the lattice: pairs at depth 0 (or -1 ulp) by rounding, with d2 < (r_i + r_j)^2, take the
     * linear law's lanes (the law has no branch on the depth); some must occur */
    floe_world_destroy(compare_paths(4));
    floe_world *lat = scene(0, 4); /* its first step, recorded */
    if (lat && floe_world_prepare(lat) == 0) {
        floe_world_record_contacts(lat, 1);
        int rc = floe_world_step(lat), edge = 0;
        const floe_contact_info *ci = NULL;
        const int nc = floe_world_contacts(lat, &ci);
        for (int k = 0; k < nc; k++) edge += ci[k].depth <= 0;
        printf("  lattice, first step: %d of %d contacts at depth <= 0 by rounding\n", edge, nc);
        CHECK(rc == 0 && edge > 0, "the lattice has contacts at depth <= 0 (%d of %d)", edge, nc);
    }
    floe_world_destroy(lat);
    floe_world_destroy(compare_paths(5));
    floe_world *mix = compare_paths(2);
    floe_world_destroy(mix);
    floe_world *ad = compare_paths(3);
    if (ad) {
        const double t = floe_world_time(ad), dtn = 8000 * 5e-6; /* the steps taken were not all dt */
        CHECK(!(t == dtn), "adaptive steps: the time %.17g differs from 8,000 fixed steps", t);
    }
    floe_world_destroy(ad);
    floe_world *a = compare_paths(0);
    if (!a) return check_summary("test_sphere_path");
    int rc;
    /* 2. the stage's sphere-wall contacts against detection's answer */
    floe_world_record_contacts(a, 1);
    rc = floe_world_step(a);
    const floe_contact_info *ci = NULL;
    int nc = floe_world_contacts(a, &ci);
    CHECK(rc == 0 && nc > 0, "recorded contacts (%d)", nc);
    int wall_first = 0, wall_last = 0, bad = 0, low = 0, high = 0; /* walls 0-4 and 5 + NS */
    for (int k = 0; k < nc; k++) {
        const int i = ci[k].i, j = ci[k].j;
        const int wi = i < 5 || i == 5 + NS, wj = j < 5 || j == 5 + NS;
        if (!(wi || wj)) continue;
        floe_contact c;
        int r = floe_world_probe_contact(a, i, j, 0, &c);
        if (r != 1 || !same(c.n, ci[k].n, 3) || !same(c.point, ci[k].point, 3) || c.depth != ci[k].depth) bad++;
        if (wi) wall_first++;
        else wall_last++;
        low += j < 5;
        high += j == 5 + NS;
    }
    printf("  sphere-wall contacts: %d with the wall first, %d with the sphere first; differing from detection: %d\n",
           wall_first, wall_last, bad);
    CHECK(wall_first == 0 && low > 0 && high > 0, "every sphere-wall pair has the sphere as i, walls declared before "
          "the spheres (%d) and after (%d): %d with the wall first", low, high, wall_first);
    CHECK(bad == 0, "%d sphere-wall contacts differ from floe_world_probe_contact", bad);
    floe_world_destroy(a);
    return check_summary("test_sphere_path");
}
