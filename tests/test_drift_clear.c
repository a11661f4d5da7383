/* test_drift_clear.c - velocity Verlet's and leapfrog's drift clears the free particles'
 * forces as it reads them (core/integrators/step.c, w->drift_cleared): the force evaluation
 * then clears only the fixed and kinematic particles (core/world/forces.c forces_clear). A
 * world with a state object (a no-op one here) keeps the full clearing pass, so two worlds
 * that differ by that state alone must step to the same bits:
 *   a bed of 300 particles pressed together on a fixed floor under gravity (spheres, a few
 *   boxes among them), beside a fixed sphere and a kinematic sphere driven through the bed,
 *   the floor declared before or after them; the spheres' orientations left alone (the
 *   drift's lanes without them) or integrated (FLOE_ORIENT_ALWAYS: the lanes with them);
 *   Hertz-Mindlin (no dashpot accelerations) and a linear viscoelastic law (the drift also
 *   copies f / m for the dashpot, floe_contact.an_ext); velocity Verlet and leapfrog; one
 *   thread and two (the drift's and the contact stage's threaded loops).
 * Every 25 steps of 300: positions, velocities, angular velocities, forces and torques of
 * every particle (the fixed and kinematic ones included) the same bytes, and the energy
 * ledger's terms equal; the first world's drift took the clearing at every step, the
 * second's at none. */
#include "check.h"
#include "floe.h"
#include "world_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* a state object that changes nothing (its presence turns the drift's clearing off) */
static size_t noop_size(const floe_state *s) { (void)s; return 1; }
static void noop_get(const floe_state *s, double *y) { (void)s; y[0] = 0.0; }
static int noop_set(floe_state *s, floe_world *w, const double *y) { (void)s; (void)w; (void)y; return FLOE_OK; }
static int noop_rhs(const floe_state *s, const floe_world *w, double t, const double *y, double *dydt) {
    (void)s; (void)w; (void)t; (void)y;
    dydt[0] = 0.0;
    return FLOE_OK;
}
static void noop_destroy(floe_state *s) { free(s); }
static const floe_state_class noop_class = {1, "noop", noop_size, noop_get, noop_set, noop_rhs, noop_destroy, NULL};

static void drive(double t, double v[3], double om[3], void *user) {
    (void)user;
    v[0] = 0.05 * cos(40 * t);
    v[1] = 0.02;
    v[2] = 0.0;
    om[0] = om[1] = 0.0;
    om[2] = 3.0;
}

static double urand(unsigned *s) {
    *s = *s * 1103515245u + 12345u;
    return ((*s >> 8) & 0xffffff) / (double)0x1000000;
}

static floe_world *build(int law, int integrator, int state, int floor_first, int orient, int nt) {
    const double R = 1e-3;
    floe_world_def d = floe_default_world_def();
    d.integrator = integrator;
    floe_v3_set(d.gravity, 0, 0, -9.81);
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material mat = {"soft", 2500, 1e6, 0.3};
    const int mi = floe_world_add_material(w, &mat);
    const double m = 2500 * 4.0 / 3.0 * M_PI * R * R * R, kn = 200;
    floe_world_set_law(w, mi, mi, law ? floe_linear_law_create(kn, 0.5 * kn, 2 * 0.3 * sqrt(kn * m), 0.0, 0.4)
                                      : floe_hertz_mindlin_law_create(&mat, &mat, 0.5, 0.4));
    const double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
    if (floor_first) floe_world_add_wall(w, o, nz, mi, FLOE_FIXED);
    const int geo = floe_world_add_geometry(w, floe_sphere_create(R));
    const int box = floe_world_add_geometry(w, floe_box_create(1.4 * R, 1.2 * R, 1.0 * R));
    unsigned seed = 7;
    for (int k = 0; k < 300; k++) {
        floe_particle_def p = floe_default_particle_def();
        p.geometry = k % 37 == 5 ? box : geo; /* boxes: the drift's scalar path, turning bodies */
        p.material = mi;
        /* a lattice pressed together (overlaps of about 1 % of the radius) on the floor */
        floe_v3_set(p.x, 1.98 * R * (k % 10) + 0.01 * R * urand(&seed), 1.98 * R * ((k / 10) % 10) + 0.01 * R * urand(&seed),
                    0.99 * R + 1.98 * R * (k / 100) + 0.01 * R * urand(&seed));
        for (int a = 0; a < 3; a++) p.v[a] = 0.2 * (urand(&seed) - 0.5);
        if (k == 55) p.motion = FLOE_FIXED;
        const int id = floe_world_add_particle(w, &p);
        if (k == 144) floe_world_set_motion(w, id, drive, NULL);
    }
    if (!floor_first) floe_world_add_wall(w, o, nz, mi, FLOE_FIXED);
    if (state) {
        floe_state *s = malloc(sizeof *s);
        s->klass = &noop_class;
        floe_world_add_state(w, s);
    }
    if (orient) floe_world_set_orientation(w, FLOE_ORIENT_ALWAYS);
    w->par_grain = 64; /* threads for 300 particles */
    if (floe_world_set_threads(w, nt) != FLOE_OK) floe_world_set_threads(w, 1);
    floe_world_set_dt(w, 2e-6, 0);
    return w;
}

static int same(const double *a, const double *b, int n) { return memcmp(a, b, (size_t)n * sizeof *a) == 0; }

static void compare(int law, int integrator, int floor_first, int orient, int nt) {
    floe_world *A = build(law, integrator, 0, floor_first, orient, nt),
               *B = build(law, integrator, 1, floor_first, orient, nt);
    nt = floe_world_threads(A);
    CHECK(floe_world_prepare(A) == FLOE_OK && floe_world_prepare(B) == FLOE_OK, "prepare: %s / %s",
          floe_world_last_error(A), floe_world_last_error(B));
    const char *name = integrator == FLOE_LEAPFROG ? "leapfrog" : "velocity Verlet";
    int ok = 1, steps = 0, contacts = 0;
    double fwall = 0;
    for (int s = 1; s <= 300 && ok; s++) {
        const int ra = floe_world_step(A), rb = floe_world_step(B);
        ok = ra == FLOE_OK && rb == FLOE_OK;
        CHECK(ok, "%s step %d: %s / %s", name, s, floe_world_last_error(A), floe_world_last_error(B));
        if (!ok || s % 25) continue;
        floe_particles_view a, b;
        floe_world_particles(A, &a);
        floe_world_particles(B, &b);
        const int n = a.n;
        const int eq = same(a.x, b.x, 3 * n) && same(a.v, b.v, 3 * n) && same(a.w, b.w, 3 * n) &&
                       same(a.f, b.f, 3 * n) && same(a.t, b.t, 3 * n);
        const floe_energy ea = floe_world_energy(A), eb = floe_world_energy(B);
        const int le = ea.kinetic_trans == eb.kinetic_trans && ea.kinetic_rot == eb.kinetic_rot &&
                       ea.elastic == eb.elastic && ea.work_body == eb.work_body &&
                       ea.work_boundary == eb.work_boundary && ea.dissipated == eb.dissipated;
        CHECK(eq && le, "law %d, %s, floor %s, orientations %d, %d thread(s): the same bits at step %d (state %d, "
              "ledger %d)", law, name, floor_first ? "first" : "last", orient, nt, s, eq, le);
        ok = eq && le;
        steps = s;
        contacts = floe_world_contact_count(A);
        const int fl = floor_first ? 0 : n - 1;
        fwall = a.f[3 * fl + 2];
    }
    /* the comparison means something: contacts, and the floor carries part of the bed */
    CHECK(contacts > 300 && fabs(fwall) > 0, "law %d, %s: %d contacts, floor force %.3e N at step %d", law, name, contacts,
          fwall, steps);
    CHECK(A->st_drift_clears == steps && B->st_drift_clears == 0, "law %d, %s: the drift cleared the forces at %ld "
          "of %d steps (with a state object: %ld)", law, name, A->st_drift_clears, steps, B->st_drift_clears);
    printf("  law %d, %s, floor %s, orientations %d, %d thread(s): %d steps the same bits, %d contacts, floor force "
           "%.3e N\n", law, name, floor_first ? "first" : "last", orient, nt, steps, contacts, fwall);
    floe_world_destroy(A);
    floe_world_destroy(B);
}

int main(void) {
    for (int law = 0; law < 2; law++)
        for (int lf = 0; lf < 2; lf++)
            for (int ff = 0; ff < 2; ff++)
                for (int nt = 1; nt <= 2; nt++) compare(law, lf ? FLOE_LEAPFROG : FLOE_VELOCITY_VERLET, ff, ff, nt);
    return check_summary("test_drift_clear");
}
