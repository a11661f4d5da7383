/* test_orientation.c - the orientation of round particles only when something reads it
 * (floe_world_set_orientation, docs/api.md):
 *  - four spheres spinning and bouncing on a floor with friction, and a cube (isotropic
 *    inertia, not round), 3,000 velocity-Verlet steps: under FLOE_ORIENT_AUTO without
 *    observers the spheres keep their orientation exactly, while positions, velocities,
 *    angular velocities and momenta are the same bits as under FLOE_ORIENT_ALWAYS (a sphere's
 *    orientation changes nothing in its motion); the cube's orientation is integrated in both;
 *  - under ALWAYS a free sphere spinning at omega (no contact) turns by |omega| t: its
 *    quaternion is exp(t omega / 2) within 1e-6 (the integrator's error);
 *  - AUTO with an observer of class version 2 (taken to read them): the same bits as ALWAYS,
 *    q included; an observer that does not read them (energy) leaves them; a particle
 *    tracker reads the orientations of the particles it tracks only: tracking sphere 1, its
 *    q is the bits of ALWAYS and sphere 2 keeps its orientation; tracking the floor and the
 *    cube, every sphere keeps its orientation;
 *  - the mode switched on a prepared world takes effect at the next step; a bad mode is
 *    refused with FLOE_EINVAL. */
#include "check.h"
#include "floe.h"
#include "floe_observer.h"
#include "floe_observer_base.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double R = 1e-3;
enum { NS = 4, STEPS = 3000 };

/* a floor (particle 0), NS spheres (1..NS) dropping with spin, a cube (NS + 1), and a free
 * sphere far away spinning (NS + 2) */
static floe_world *scene(int mode) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    d.dt = 2e-6;
    d.gravity[2] = -9.81;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"glass", 2500, 1e7, 0.3};
    floe_world_add_material(w, &m);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.5, 0.5));
    double o[3] = {0, 0, 0}, n[3] = {0, 0, 1};
    floe_world_add_wall(w, o, n, 0, FLOE_FIXED);
    int gs = floe_world_add_geometry(w, floe_sphere_create(R));
    int gb = floe_world_add_geometry(w, floe_box_create(1.6 * R, 1.6 * R, 1.6 * R));
    for (int k = 0; k < NS + 2; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = k == NS ? gb : gs;
        p.x[0] = k * 2.5 * R + (k == NS + 1 ? 0.1 : 0);
        p.x[2] = (k == NS ? 0.8 : 1.0) * R - 1e-6 * k + (k == NS + 1 ? 0.1 : 0);
        p.v[0] = 0.05 * (k % 2 ? 1 : -1);
        p.v[2] = -0.01;
        p.w[0] = 30.0 + k;
        p.w[1] = -20.0 * k;
        p.w[2] = 50.0;
        floe_world_add_particle(w, &p);
    }
    if (mode >= 0) floe_world_set_orientation(w, mode);
    return w;
}

static int run(floe_world *w, int steps) {
    for (int s = 0; s < steps; s++)
        if (floe_world_step(w) != FLOE_OK) return 1;
    return 0;
}

/* the bits of x, v, omega, L (and q when with_q) of every particle: equal */
static int same_bits(const floe_world *a, const floe_world *b, int with_q) {
    floe_particles_view pa, pb;
    floe_world_particles(a, &pa);
    floe_world_particles(b, &pb);
    if (pa.n != pb.n) return 0;
    const size_t n3 = 3 * (size_t)pa.n * sizeof(double);
    return !memcmp(pa.x, pb.x, n3) && !memcmp(pa.v, pb.v, n3) && !memcmp(pa.w, pb.w, n3) && !memcmp(pa.L, pb.L, n3) &&
           (!with_q || !memcmp(pa.q, pb.q, 4 * (size_t)pa.n * sizeof(double)));
}

static int q_is_identity(const floe_world *w, int i) {
    floe_particles_view p;
    floe_world_particles(w, &p);
    const double *q = p.q + 4 * i;
    return q[0] == 1 && q[1] == 0 && q[2] == 0 && q[3] == 0;
}

/* an observer of class version 2 (before reads_orientation): taken to read orientations */
static int v2_observe(floe_observer *o, floe_world *w) {
    (void)o; (void)w;
    return FLOE_OK;
}
static void v2_destroy(floe_observer *o) { free(o); }
static const floe_observer_class v2_class = {.version = 2, .name = "old", .observe = v2_observe, .destroy = v2_destroy};
static floe_observer *v2_create(void) {
    floe_observer *o = calloc(1, sizeof *o);
    o->klass = &v2_class;
    o->period_steps = 1000;
    return o;
}

int main(void) {
    floe_world *aut = scene(-1), *all = scene(FLOE_ORIENT_ALWAYS);
    CHECK(run(aut, STEPS) == 0 && run(all, STEPS) == 0, "runs: %s / %s", floe_world_last_error(aut), floe_world_last_error(all));
    CHECK(floe_world_contact_count(all) > 0, "the spheres touch the floor (%d contacts)", floe_world_contact_count(all));
    CHECK(same_bits(aut, all, 0), "AUTO vs ALWAYS: x, v, omega, L the same bits");
    int kept = 1;
    for (int i = 1; i <= NS; i++) kept &= q_is_identity(aut, i);
    CHECK(kept, "AUTO without observers: the spheres keep their orientation");
    CHECK(!q_is_identity(aut, NS + 1) && !q_is_identity(all, 1), "the cube turns under AUTO, a sphere under ALWAYS");
    {
        floe_particles_view a, b;
        floe_world_particles(aut, &a);
        floe_world_particles(all, &b);
        CHECK(!memcmp(a.q + 4 * (NS + 1), b.q + 4 * (NS + 1), 4 * sizeof(double)), "the cube's orientation: the same bits");
        /* the free sphere: q = (cos(|w| t / 2), sin(|w| t / 2) w / |w|) */
        const double *om = b.w + 3 * (NS + 2), *q = b.q + 4 * (NS + 2);
        const double wn = sqrt(om[0] * om[0] + om[1] * om[1] + om[2] * om[2]), t = floe_world_time(all);
        const double ha = 0.5 * wn * t, qa[4] = {cos(ha), sin(ha) * om[0] / wn, sin(ha) * om[1] / wn, sin(ha) * om[2] / wn};
        double err = 0;
        for (int k = 0; k < 4; k++) err = fmax(err, fabs(q[k] - qa[k]));
        CHECK(err < 1e-6 && ha > 0.1, "ALWAYS: the free sphere turned by %.3g rad as exp(t omega/2) (error %.2e, tol 1e-6)",
              2 * ha, err);
    }

    /* observers: the tracker reads orientations, the energy tracker does not, version 2 is
     * taken to */
    char err[256];
    floe_world *trk = scene(-1), *eng = scene(-1), *old = scene(-1), *trw = scene(-1);
    const int ids[1] = {1}, ids_w[2] = {0, NS + 1};
    CHECK(floe_world_add_observer(trk, floe_particle_tracker_create("orientation_track.csv", ids, 1, err, sizeof err)) ==
              FLOE_OK,
          "tracker");
    CHECK(floe_world_add_observer(trw, floe_particle_tracker_create("orientation_track_w.csv", ids_w, 2, err, sizeof err)) ==
              FLOE_OK,
          "tracker of the floor and the cube");
    CHECK(floe_world_add_observer(eng, floe_energy_tracker_create("orientation_energy.csv", err, sizeof err)) == FLOE_OK,
          "energy tracker");
    CHECK(floe_world_add_observer(old, v2_create()) == FLOE_OK, "a version-2 observer");
    CHECK(run(trk, STEPS) == 0 && run(eng, STEPS) == 0 && run(old, STEPS) == 0 && run(trw, STEPS) == 0,
          "runs with observers");
    {
        floe_particles_view a, b;
        floe_world_particles(trk, &a);
        floe_world_particles(all, &b);
        CHECK(same_bits(trk, all, 0) && !memcmp(a.q + 4, b.q + 4, 4 * sizeof(double)) && q_is_identity(trk, 2),
              "AUTO with a tracker of sphere 1: its orientation the bits of ALWAYS, sphere 2's left");
    }
    CHECK(same_bits(trw, aut, 1), "AUTO with a tracker of the floor and the cube: every sphere's orientation left");
    CHECK(same_bits(old, all, 1), "AUTO with a version-2 observer: the bits of ALWAYS, orientations included");
    CHECK(same_bits(eng, aut, 1) && q_is_identity(eng, 1), "AUTO with an energy tracker: orientations left");

    /* switched on a prepared world: from the next step on */
    floe_world *sw = scene(-1);
    CHECK(run(sw, 10) == 0 && q_is_identity(sw, 1), "10 steps under AUTO");
    CHECK(floe_world_set_orientation(sw, FLOE_ORIENT_ALWAYS) == FLOE_OK && run(sw, 10) == 0 && !q_is_identity(sw, 1),
          "ALWAYS set on a prepared world: the sphere turns");
    CHECK(floe_world_set_orientation(sw, 7) == FLOE_EINVAL, "mode 7 refused");

    floe_world_destroy(aut);
    floe_world_destroy(all);
    floe_world_destroy(trk);
    floe_world_destroy(eng);
    floe_world_destroy(old);
    floe_world_destroy(trw);
    floe_world_destroy(sw);
    remove("orientation_track.csv");
    remove("orientation_energy.csv");
    remove("orientation_track_w.csv");
    return check_summary("test_orientation");
}
