/* test_stress.c - homogenised Cauchy stress (ParticLS eq 24) of a static confined packing
 * versus the wall force per wall area. A 5 x 5 x 5 jittered packing of two sphere sizes
 * (1 and 0.99 mm) is squeezed by six walls (box 3 % smaller than the free lattice) and
 * damped to rest, with friction between grains and frictionless walls (wall friction would
 * add shear tractions whose moments enter sigma_ii). Then sigma_xx, sigma_yy, sigma_zz must
 * equal -(force on the walls normal to the axis)/(wall area) within 2 %, with V = the box
 * volume (contact points sit inside the walls by half the overlap: about 0.5 % offset). */
#include "floe.h"
#include "floe.h"
#include "world_read.h"
#include "check.h"
#include <string.h>

int main(void) {
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"grain", 2000, 5e6, 0.25};
    floe_world_add_material(w, &m);
    floe_material steel = {"steel", 7800, 5e6, 0.25};
    floe_world_add_material(w, &steel);
    floe_world_set_law(w, 0, 0, floe_hertz_mindlin_law_create(&m, &m, 0.2, 0.3));
    /* frictionless walls: with wall friction the boundary tractions also carry shear whose
     * moments enter sigma_ii, and wall force / area is no longer the reference */
    floe_world_set_law(w, 0, 1, floe_hertz_mindlin_law_create(&m, &steel, 0.2, 0.0));
    int g1 = floe_world_add_geometry(w, floe_sphere_create(0.001));
    int g2 = floe_world_add_geometry(w, floe_sphere_create(0.00099));
    const int n = 5;
    const double a = 0.002, L = n * a * 0.97;
    int walls[6];
    for (int k = 0; k < 3; k++) {
        double p0[3] = {0, 0, 0}, p1[3] = {0, 0, 0}, n0[3] = {0, 0, 0}, n1[3] = {0, 0, 0};
        p1[k] = L; n0[k] = 1; n1[k] = -1;
        walls[2 * k] = floe_world_add_wall(w, p0, n0, 1, FLOE_FIXED);
        walls[2 * k + 1] = floe_world_add_wall(w, p1, n1, 1, FLOE_FIXED);
    }
    unsigned s = 99;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            for (int k = 0; k < n; k++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = (i + j + k) % 3 ? g1 : g2;
                double jit[3];
                for (int c = 0; c < 3; c++) { s = s * 1664525u + 1013904223u; jit[c] = ((s >> 8) / 16777216.0 - 0.5) * 1e-4; }
                floe_v3_set(p.x, (i + 0.5) * L / n + jit[0], (j + 0.5) * L / n + jit[1], (k + 0.5) * L / n + jit[2]);
                floe_world_add_particle(w, &p);
            }
    floe_world_record_contacts(w, 1);
    CHECK(floe_world_prepare(w) == FLOE_OK, "prepare: %s", floe_world_last_error(w));
    printf("  dt = %.3g s\n", floe_world_dt(w));
    for (int st = 0; st < 100000; st++)
        if (floe_world_step(w)) { CHECK(0, "step: %s", floe_world_last_error(w)); break; }
    floe_energy e = floe_world_energy(w);
    printf("  kinetic energy at the end %.3e J (elastic %.3e J)\n", e.kinetic_trans + e.kinetic_rot, e.elastic);
    CHECK(e.kinetic_trans + e.kinetic_rot < 1e-3 * e.elastic, "the packing must be at rest");
    floe_collection_stats cs;
    CHECK(floe_collection_stress(w, -1, L * L * L, &cs) == FLOE_OK, "collection stress");
    for (int k = 0; k < 3; k++) {
        /* total force the particles exert on the two walls normal to axis k */
        double f0 = -pview(w).f[3 * walls[2 * k] + k], f1 = pview(w).f[3 * walls[2 * k + 1] + k];
        double wall = 0.5 * (f0 + f1) / (L * L);
        char what[80];
        snprintf(what, sizeof what, "sigma_%c%c vs -(wall force)/(wall area) (tol 2%%)", "xyz"[k], "xyz"[k]);
        CHECK_NEAR(cs.sigma[k], -wall, 0.02, what);
    }
    printf("  coordination number %.2f, %d contacts, %d wall contacts\n", cs.coordination, cs.contacts, cs.wall_contacts);
    CHECK(cs.coordination > 3 && cs.coordination < 12, "coordination number %g out of range", cs.coordination);
    floe_world_destroy(w);
    return check_summary("test_stress");
}
