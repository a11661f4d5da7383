/* test_observers.c - observers on a hand-filled world (no stepping): homogenised stress
 * against hand calculations (sign: tension positive), coordination, volumes, and the CSV /
 * VTK writers' files. */
#include "check.h"
#include "test_files.h"
#include "floe_observer.h"
#include "file_writer.h" /* internal: unit test of the observers' file writer */
#include "world_internal.h" /* internal: unit test of the observers on a hand-made world (its contacts, time and particles set directly) */

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define OUTDIR "test_observers_out"
#define MAXP 8
#define MAXC 8

/* A world filled by hand: up to MAXP particles, MAXC contacts. */
typedef struct hand_world {
    floe_world w;
    double x[3 * MAXP], v[3 * MAXP], q[4 * MAXP], om[3 * MAXP], L[3 * MAXP], f[3 * MAXP],
        t[3 * MAXP], mass[MAXP], inv_mass[MAXP], inertia[3 * MAXP], radius[MAXP];
    int geom[MAXP], material[MAXP], group[MAXP];
    unsigned char motion[MAXP], kind[MAXP];
    floe_contact_rec contacts[MAXC];
} hand_world;

static hand_world *hand_world_new(int dim) {
    hand_world *h = calloc(1, sizeof *h);
    if (!h) { fprintf(stderr, "out of memory\n"); exit(2); }
    floe_world *w = &h->w;
    w->def.dim = dim;
    floe_particles *p = &w->p;
    p->x = h->x; p->v = h->v; p->q = h->q; p->w = h->om; p->L = h->L; p->f = h->f; p->t = h->t;
    p->mass = h->mass; p->inv_mass = h->inv_mass; p->inertia = h->inertia; p->radius = h->radius;
    p->geom = h->geom; p->material = h->material; p->group = h->group; p->motion = h->motion;
    p->kind = h->kind;
    p->cap = MAXP;
    w->contacts = h->contacts;
    w->contacts_cap = MAXC;
    w->record_contacts = 1;
    w->contacts_valid = 1;
    return h;
}

static int add_sphere(hand_world *h, double x, double y, double z, double r) {
    floe_particles *p = &h->w.p;
    int i = p->n++;
    floe_v3_set(p->x + 3 * i, x, y, z);
    floe_q_identity(p->q + 4 * i);
    p->radius[i] = r;
    p->mass[i] = 1.0;
    p->inv_mass[i] = 1.0;
    p->kind[i] = FLOE_GEOM_SPHERE;
    p->motion[i] = FLOE_FREE;
    return i;
}

static int add_wall(hand_world *h, double x, double y, double z) {
    floe_particles *p = &h->w.p;
    int i = p->n++;
    floe_v3_set(p->x + 3 * i, x, y, z);
    floe_q_identity(p->q + 4 * i);
    p->radius[i] = INFINITY;
    p->kind[i] = FLOE_GEOM_PLANE;
    p->motion[i] = FLOE_FIXED;
    return i;
}

static void add_contact(hand_world *h, int i, int j, const double point[3], const double force_on_i[3]) {
    floe_contact_rec *c = &h->contacts[h->w.ncontacts++];
    memset(c, 0, sizeof *c);
    c->i = i;
    c->j = j;
    floe_v3_copy(c->point, point);
    floe_v3_copy(c->force, force_on_i);
    c->fn = floe_v3_norm(force_on_i);
}

static int count_lines(const char *s) {
    int n = 0;
    for (; s && *s; s++) n += *s == '\n';
    return n;
}

static int count_substr(const char *s, const char *sub) {
    int n = 0;
    size_t L = strlen(sub);
    for (const char *p = s ? strstr(s, sub) : NULL; p; p = strstr(p + L, sub)) n++;
    return n;
}

/* Values of data line `line` (0 = first after the header) as doubles; returns the count. */
static int csv_row(const char *s, int line, double *vals, int maxv) {
    const char *p = strchr(s, '\n');
    for (int k = 0; p && k < line; k++) p = strchr(p + 1, '\n');
    if (!p) return 0;
    p++;
    int n = 0;
    while (*p && *p != '\n' && n < maxv) {
        char *end;
        vals[n++] = strtod(p, &end);
        p = end;
        if (*p == ',') p++;
        else break;
    }
    return n;
}

/* Two spheres and a floor (the 3-particle, 2-contact case computed by hand):
 *   sphere 0 at (0, 0, 0.5), sphere 1 at (1, 0, 0.5), radius 0.5; wall 2 (plane z = 0).
 *   contact (0, 1) at (0.5, 0, 0.5), force on 0 = (-10, 2, 0) N (repulsive + tangential)
 *   contact (2, 0) at (0, 0, 0), force on the wall (i = 2) = (0, 0, -20) N, so on 0 (0, 0, 20)
 * Branch terms (l (x) f):
 *   pair:  l = x1 - x0 = (1, 0, 0), f = (-10, 2, 0): s_xx = -10, s_xy = 2
 *   wall:  l = point - x0 = (0, 0, -0.5), f = (0, 0, 20): s_zz = -10
 * Bounding box: [-0.5, 1.5] x [-0.5, 0.5] x [0, 1] -> V = 2 m^3.
 * sigma = (-5, 0, -5, 0.5 (symmetrised), 0, 0) Pa, Z = 2 * 1 / 2 = 1. */
static hand_world *three_particle_world(void) {
    hand_world *h = hand_world_new(3);
    add_sphere(h, 0, 0, 0.5, 0.5);
    add_sphere(h, 1, 0, 0.5, 0.5);
    add_wall(h, 0, 0, 0);
    double p01[3] = {0.5, 0, 0.5}, f01[3] = {-10, 2, 0};
    double p20[3] = {0, 0, 0}, f20[3] = {0, 0, -20};
    add_contact(h, 0, 1, p01, f01);
    add_contact(h, 2, 0, p20, f20);
    h->w.time = 0.25;
    h->w.step = 5;
    return h;
}

static void test_stress_hand(void) {
    printf("stress: 2 spheres + wall, 2 contacts (hand calculation)\n");
    hand_world *h = three_particle_world();
    floe_collection_stats st;
    CHECK(floe_collection_stress(&h->w, -1, 0, &st) == FLOE_OK, "floe_collection_stress failed");
    const double expect[6] = {-5, 0, -5, 0.5, 0, 0};
    const char *names[6] = {"sxx", "syy", "szz", "sxy", "sxz", "syz"};
    for (int k = 0; k < 6; k++) {
        char what[64];
        snprintf(what, sizeof what, "%s (Pa, tension positive)", names[k]);
        CHECK_NEAR(st.sigma[k], expect[k], 1e-12, what);
    }
    CHECK_NEAR(st.volume, 2.0, 1e-12, "bounding-box volume (m^3)");
    CHECK_NEAR(st.coordination, 1.0, 1e-12, "coordination 2*1/2");
    CHECK(st.contacts == 1 && st.wall_contacts == 1 && st.particles == 2,
          "counts: contacts %d wall %d particles %d", st.contacts, st.wall_contacts, st.particles);

    /* same contact with i and j swapped (force on i flips): identical stress */
    hand_world *g = three_particle_world();
    g->contacts[0].i = 1; g->contacts[0].j = 0;
    floe_v3_scale(g->contacts[0].force, -1.0);
    g->contacts[1].i = 0; g->contacts[1].j = 2;
    floe_v3_scale(g->contacts[1].force, -1.0);
    floe_collection_stats st2;
    floe_collection_stress(&g->w, -1, 0, &st2);
    for (int k = 0; k < 6; k++) CHECK_NEAR(st2.sigma[k], expect[k], 1e-12, "swapped i/j: same sigma");

    /* given volume */
    floe_collection_stress(&h->w, -1, 4.0, &st);
    CHECK_NEAR(st.sigma[0], -2.5, 1e-12, "sxx with V = 4 m^3");
    CHECK_NEAR(st.volume, 4.0, 1e-12, "given volume reported");

    /* groups: sphere 1 in group 1 -> for group 0 it is a boundary: only the half of 0 counts
     * (l = point - x0 = (0.5, 0, 0), f = (-10, 2, 0) -> s_xx = -5, s_xy = 1);
     * box of sphere 0 alone: 1 x 1 x 1 */
    h->group[1] = 1;
    floe_collection_stress(&h->w, 0, 0, &st);
    CHECK_NEAR(st.volume, 1.0, 1e-12, "group 0 box volume");
    CHECK_NEAR(st.sigma[0], -5.0, 1e-12, "group 0 sxx (half of the pair)");
    CHECK_NEAR(st.sigma[3], 0.5, 1e-12, "group 0 sxy (symmetrised)");
    CHECK_NEAR(st.sigma[2], -10.0, 1e-12, "group 0 szz (wall half)");
    CHECK(st.contacts == 0 && st.wall_contacts == 2 && st.particles == 1,
          "group 0 counts: %d %d %d", st.contacts, st.wall_contacts, st.particles);
    CHECK_NEAR(st.coordination, 0.0, 0, "group 0 coordination");
    h->group[1] = 0;

    /* a fixed sphere is not in group -1 */
    h->motion[1] = FLOE_FIXED;
    floe_collection_stress(&h->w, -1, 0, &st);
    CHECK(st.particles == 1 && st.wall_contacts == 2, "fixed sphere is a boundary of group -1");
    free(h);
    free(g);
}

/* Column of two spheres (radius R) squeezed between a floor (z = 0) and a lid (z = 4R) by a
 * force F: the Love-Weber stress is sigma_zz = -F/A over V = A * 4R (compression negative). */
static void test_stress_column(void) {
    printf("stress: column between two walls under a load F\n");
    const double R = 0.01, F = 3.0, A = 2e-4;
    hand_world *h = hand_world_new(3);
    int a = add_sphere(h, 0, 0, R, R), b = add_sphere(h, 0, 0, 3 * R, R);
    int floor_ = add_wall(h, 0, 0, 0), lid = add_wall(h, 0, 0, 4 * R);
    double pf[3] = {0, 0, 0}, fa[3] = {0, 0, F};          /* floor pushes a up */
    double pab[3] = {0, 0, 2 * R}, fab[3] = {0, 0, -F};    /* b pushes a down */
    double pl[3] = {0, 0, 4 * R}, fl[3] = {0, 0, F};       /* on the lid (i), b on j */
    add_contact(h, a, floor_, pf, fa);
    add_contact(h, a, b, pab, fab);
    add_contact(h, lid, b, pl, fl);
    floe_collection_stats st;
    floe_collection_stress(&h->w, -1, A * 4 * R, &st);
    CHECK_NEAR(st.sigma[2], -F / A, 1e-12, "szz = -F/A (Pa)");
    CHECK_NEAR(st.sigma[0], 0.0, 0, "sxx = 0");
    CHECK(st.sigma[2] < 0, "compression is negative");
    /* reversed load (adhesive contacts pulling): tension positive */
    for (int c = 0; c < 3; c++) floe_v3_scale(h->contacts[c].force, -1.0);
    floe_collection_stress(&h->w, -1, A * 4 * R, &st);
    CHECK_NEAR(st.sigma[2], F / A, 1e-12, "tension is positive");
    free(h);
}

static void test_stress_2d(void) {
    printf("stress: 2D bounding area x 1 m\n");
    hand_world *h = hand_world_new(2);
    add_sphere(h, 0, 0, 0, 0.5);
    add_sphere(h, 1, 0, 0, 0.5);
    double p[3] = {0.5, 0, 0}, f[3] = {-4, 0, 0};
    add_contact(h, 0, 1, p, f);
    floe_collection_stats st;
    floe_collection_stress(&h->w, -1, 0, &st);
    CHECK_NEAR(st.volume, 2.0, 1e-12, "2D volume = 2 x 1 m^2 x 1 m");
    CHECK_NEAR(st.sigma[0], -2.0, 1e-12, "2D sxx");
    CHECK_NEAR(st.sigma[2], 0.0, 0, "2D szz");
    /* empty collection: zeros, no division by zero */
    h->w.p.motion[0] = h->w.p.motion[1] = FLOE_FIXED;
    floe_collection_stress(&h->w, -1, 0, &st);
    CHECK(st.particles == 0 && st.volume == 0 && st.sigma[0] == 0 && st.coordination == 0,
          "empty collection gives zeros");
    free(h);
}

static void test_collection_tracker(void) {
    printf("collection tracker: CSV and accessor\n");
    hand_world *h = three_particle_world();
    char err[256];
    floe_observer *o = floe_collection_tracker_create(OUTDIR "/stress.csv", -1, 0, err, sizeof err);
    CHECK(o != NULL, "create: %s", err);
    if (!o) { free(h); return; }
    double sig[6], z = -1;
    CHECK(floe_collection_tracker_last(o, sig, &z) == FLOE_EINVAL, "no value before observe");
    if (o->klass->begin) CHECK(o->klass->begin(o, &h->w) == FLOE_OK, "begin");
    CHECK(o->klass->observe(o, &h->w) == FLOE_OK, "observe");
    CHECK(o->klass->observe(o, &h->w) == FLOE_OK, "observe twice at one step (no duplicate)");
    CHECK(floe_collection_tracker_last(o, sig, &z) == FLOE_OK, "accessor");
    CHECK_NEAR(sig[0], -5.0, 1e-12, "accessor sxx");
    CHECK_NEAR(z, 1.0, 1e-12, "accessor coordination");
    h->w.step = 6;
    h->w.time = 0.3;
    CHECK(o->klass->end(o, &h->w) == FLOE_OK, "end (writes the final step)");
    CHECK(floe_collection_tracker_last(NULL, sig, &z) == FLOE_EINVAL, "accessor on NULL");
    floe_observer_destroy(o);

    char *s = slurp(OUTDIR "/stress.csv");
    CHECK(s != NULL, "stress.csv exists");
    if (s) {
        CHECK(strncmp(s, "t [s],sxx [Pa],syy [Pa],szz [Pa],sxy [Pa],sxz [Pa],syz [Pa],coordination,"
                         "contacts,wall_contacts,volume [m^3]\n", strlen("t [s],sxx [Pa],syy [Pa],szz [Pa],sxy [Pa],sxz [Pa],syz [Pa],coordination,contacts,wall_contacts,volume [m^3]\n")) == 0,
              "stress.csv header");
        CHECK(count_lines(s) == 3, "header + 2 rows, got %d lines", count_lines(s));
        double r[16];
        int nv = csv_row(s, 0, r, 16);
        CHECK(nv == 11, "11 columns, got %d", nv);
        CHECK_NEAR(r[0], 0.25, 1e-15, "row t");
        CHECK_NEAR(r[1], -5.0, 1e-12, "row sxx");
        CHECK_NEAR(r[3], -5.0, 1e-12, "row szz");
        CHECK_NEAR(r[4], 0.5, 1e-12, "row sxy");
        CHECK_NEAR(r[7], 1.0, 1e-12, "row coordination");
        CHECK(r[8] == 1 && r[9] == 1, "row contacts / wall_contacts");
        CHECK_NEAR(r[10], 2.0, 1e-12, "row volume");
        nv = csv_row(s, 1, r, 16);
        CHECK(nv == 11 && r[0] == 0.3, "final row at end()");
        free(s);
    }
    free(h);
}

static void test_particle_tracker(void) {
    printf("particle tracker\n");
    hand_world *h = three_particle_world();
    h->v[3 * 1 + 2] = -0.75;
    h->f[3 * 1 + 0] = 10;
    char err[256];
    int ids[2] = {1, 0};
    floe_observer *o = floe_particle_tracker_create(OUTDIR "/track.csv", ids, 2, err, sizeof err);
    CHECK(o != NULL, "create: %s", err);
    if (!o) { free(h); return; }
    CHECK(!o->klass->begin || o->klass->begin(o, &h->w) == FLOE_OK, "begin");
    CHECK(o->klass->observe(o, &h->w) == FLOE_OK, "observe");
    CHECK(o->klass->end(o, &h->w) == FLOE_OK, "end");
    /* continuing after end appends */
    h->w.step = 7;
    h->w.time = 0.5;
    CHECK(o->klass->observe(o, &h->w) == FLOE_OK, "observe after end (append)");
    CHECK(o->klass->end(o, &h->w) == FLOE_OK, "end again");
    floe_observer_destroy(o);
    char *s = slurp(OUTDIR "/track.csv");
    CHECK(s && strncmp(s, "t [s],id,x [m],y [m],z [m],vx [m/s]", 35) == 0, "track header");
    if (s) {
        CHECK(count_lines(s) == 5, "header + 4 rows, got %d", count_lines(s));
        double r[32];
        int nv = csv_row(s, 0, r, 32);
        CHECK(nv == 18, "18 columns, got %d", nv);
        CHECK(r[1] == 1 && r[2] == 1 && r[3] == 0 && r[4] == 0.5, "row id 1 position");
        CHECK(r[7] == -0.75 && r[15] == 10 && r[11] == 1, "row velocity, force, q0");
        nv = csv_row(s, 3, r, 32);
        CHECK(nv == 18 && r[0] == 0.5 && r[1] == 0, "appended row");
        free(s);
    }
    /* id out of range: begin fails with FLOE_EINVAL, no exit */
    int bad[1] = {17};
    o = floe_particle_tracker_create(OUTDIR "/track_bad.csv", bad, 1, err, sizeof err);
    CHECK(o && o->klass->begin && o->klass->begin(o, &h->w) == FLOE_EINVAL, "out-of-range id");
    CHECK(strstr(floe_world_last_error(&h->w), "particle id 17 out of range (3 particles)") != NULL,
          "reported through floe_world_report_error: %s", floe_world_last_error(&h->w));
    CHECK(floe_world_particle_kind(&h->w, 2) == FLOE_GEOM_PLANE &&
              floe_world_particle_kind(&h->w, 0) == FLOE_GEOM_SPHERE &&
              floe_world_particle_kind(&h->w, 3) == -1 && floe_world_particle_kind(&h->w, -1) == -1,
          "floe_world_particle_kind: wall, sphere, out of range");
    floe_observer_destroy(o);
    CHECK(floe_particle_tracker_create(OUTDIR "/no/such/dir/x.csv", ids, 2, err, sizeof err) == NULL &&
              err[0] != '\0', "missing directory -> NULL + message");
    free(h);
}

static void test_energy_and_csv(void) {
    printf("energy tracker and csv writer\n");
    hand_world *h = three_particle_world();
    h->v[0] = 2.0; /* sphere 0, mass 1: 2 J */
    h->w.energy.kinetic_trans = 2.0;
    h->w.energy.initial = 2.0;
    char err[256];
    floe_observer *e = floe_energy_tracker_create(OUTDIR "/energy.csv", err, sizeof err);
    floe_observer *c = floe_csv_writer_create(OUTDIR "/particles.csv", err, sizeof err);
    CHECK(e && c, "create: %s", err);
    if (!e || !c) { floe_observer_destroy(e); floe_observer_destroy(c); free(h); return; }
    CHECK(e->klass->observe(e, &h->w) == FLOE_OK, "energy observe");
    CHECK(e->klass->end(e, &h->w) == FLOE_OK, "energy end");
    CHECK(c->klass->observe(c, &h->w) == FLOE_OK, "csv observe");
    h->w.step++;
    h->w.time += 0.1;
    CHECK(c->klass->end(c, &h->w) == FLOE_OK, "csv end");
    floe_observer_destroy(e);
    floe_observer_destroy(c);
    char *s = slurp(OUTDIR "/energy.csv");
    CHECK(s && strncmp(s, "t [s],kinetic_trans [J],kinetic_rot [J],elastic [J]", 51) == 0, "energy header");
    if (s) {
        double r[16];
        int nv = csv_row(s, 0, r, 16);
        CHECK(nv == 9, "energy: 9 columns, got %d", nv);
        CHECK_NEAR(r[1], 2.0, 1e-12, "energy kinetic_trans");
        CHECK(count_lines(s) == 2, "energy: one row (end at the same step adds none)");
        free(s);
    }
    s = slurp(OUTDIR "/particles.csv");
    CHECK(s && strncmp(s, "t [s],id,body,material,x [m]", 28) == 0, "particles header");
    if (s) {
        CHECK(count_lines(s) == 7, "header + 2 frames x 3 rows, got %d", count_lines(s));
        double r[32];
        int nv = csv_row(s, 2, r, 32);
        CHECK(nv == 17, "17 columns, got %d", nv);
        CHECK(r[1] == 2 && r[16] == 0, "wall row written with radius 0");
        nv = csv_row(s, 0, r, 32);
        CHECK(r[16] == 0.5 && r[7] == 2.0, "sphere row radius and vx");
        free(s);
    }
    free(h);
}

static void test_vtk(int ascii) {
    printf("vtk writer (%s)\n", ascii ? "ascii" : "binary");
    hand_world *h = three_particle_world();
    char err[256];
    const char *prefix = ascii ? "asc" : "bin";
    floe_observer *o = floe_vtk_writer_create(OUTDIR, prefix, err, sizeof err);
    CHECK(o != NULL, "create: %s", err);
    if (!o) { free(h); return; }
    CHECK(floe_vtk_writer_set_ascii(o, ascii) == FLOE_OK, "set_ascii");
    char path[256];
    snprintf(path, sizeof path, OUTDIR "/%s.pvd", prefix);
    char *s = slurp(path);
    CHECK(s && count_substr(s, "<DataSet") == 0 && strstr(s, "</VTKFile>"), "empty pvd at create");
    free(s);
    CHECK(o->klass->observe(o, &h->w) == FLOE_OK, "frame 0");
    CHECK(o->klass->observe(o, &h->w) == FLOE_OK, "same step again: no new frame");
    h->w.step = 9;
    h->w.time = 0.5;
    h->x[0] = 0.125;
    s = slurp(path);
    CHECK(s && count_substr(s, "<DataSet") == 1, "pvd after frame 0 lists 1 frame");
    free(s);
    CHECK(o->klass->end(o, &h->w) == FLOE_OK, "end writes the final frame");
    floe_observer_destroy(o);
    s = slurp(path);
    CHECK(s && count_substr(s, "<DataSet") == 2, "pvd lists 2 frames");
    CHECK(s && strstr(s, "timestep=\"0.25\"") && strstr(s, "timestep=\"0.5\""), "pvd timesteps");
    snprintf(path, sizeof path, "file=\"%s_000001.vtu\"", prefix);
    CHECK(s && strstr(s, path), "pvd names frame 1 relative to the pvd");
    free(s);
    snprintf(path, sizeof path, OUTDIR "/%s_000001.vtu", prefix);
    s = slurp(path);
    CHECK(s != NULL, "%s exists", path);
    if (s) {
        CHECK(strstr(s, "NumberOfPoints=\"2\"") && strstr(s, "NumberOfCells=\"2\""), "2 points (wall left out)");
        const char *names[] = {"\"id\"", "\"radius\"", "\"velocity\"", "\"angular_velocity\"", "\"force\"",
                               "\"body\"", "\"material\"", "\"orientation\"", "\"connectivity\"", "\"types\""};
        for (size_t k = 0; k < sizeof names / sizeof *names; k++)
            CHECK(strstr(s, names[k]), "array %s present", names[k]);
        CHECK(strstr(s, "Name=\"TimeValue\"") != NULL, "TimeValue field data");
        if (ascii) CHECK(strstr(s, "0.125 0 0.5") != NULL, "ascii point of particle 0 at the final state");
        else CHECK(strstr(s, "encoding=\"raw\"") != NULL, "raw appended data");
        free(s);
    }
    CHECK(floe_vtk_writer_create(OUTDIR "/no/such/dir", "x", err, sizeof err) == NULL && err[0],
          "missing directory -> NULL + message");
    free(h);
}

/* The file writer (observers/file_writer.c): many frames of the CSV writer cross many page
 * boundaries of the file, written in pieces that stay inside a page; the file must be
 * exactly the header and every row, each formatted as the writer formats it (%.17g time,
 * %.16g values), with nothing lost or doubled at a boundary. */
static void test_file_writer_pages(void) {
    printf("file writer: rows across page boundaries, byte-exact\n");
    hand_world *h = three_particle_world();
    char err[256];
    floe_observer *c = floe_csv_writer_create(OUTDIR "/pages.csv", err, sizeof err);
    CHECK(c != NULL, "create: %s", err);
    if (!c) { free(h); return; }
    static const char header[] = "t [s],id,body,material,x [m],y [m],z [m],vx [m/s],vy [m/s],vz [m/s],"
                                 "wx [rad/s],wy [rad/s],wz [rad/s],fx [N],fy [N],fz [N],radius [m]\n";
    size_t cap = 1 << 20, len = 0;
    char *want = malloc(cap);
    if (!want) { floe_observer_destroy(c); free(h); return; }
    len += (size_t)snprintf(want, cap, "%s", header);
    int ok = 1;
    for (int k = 0; k < 400 && ok; k++) {
        h->w.step = k;
        h->w.time = 1e-5 * k + (k % 7) * 1e-9;           /* varying row lengths */
        h->x[0] = 0.1 * k / 3.0;
        h->v[4] = -1.0 / (k + 1);
        h->f[8] = k % 3 ? 1e-300 * k : 12345.678;
        ok = c->klass->observe(c, &h->w) == FLOE_OK;
        for (int i = 0; i < h->w.p.n && len + 1024 < cap; i++) {
            const double *x = h->x + 3 * i, *v = h->v + 3 * i, *om = h->om + 3 * i, *f = h->f + 3 * i;
            double r = isfinite(h->radius[i]) ? h->radius[i] : 0.0;
            len += (size_t)snprintf(want + len, cap - len,
                                    "%.17g,%d,%d,%d,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,"
                                    "%.16g,%.16g,%.16g,%.16g\n",
                                    h->w.time, i, h->group[i], h->material[i], x[0], x[1], x[2], v[0], v[1],
                                    v[2], om[0], om[1], om[2], f[0], f[1], f[2], r);
        }
    }
    CHECK(ok, "400 frames observed");
    CHECK(c->klass->end(c, &h->w) == FLOE_OK, "end");
    floe_observer_destroy(c);
    char *s = slurp(OUTDIR "/pages.csv");
    CHECK(len > 20 * 4096, "the file spans %zu bytes, more than 20 pages", len);
    CHECK(s && strlen(s) == len && memcmp(s, want, len) == 0, "pages.csv is byte-exact (%zu bytes, expected %zu)",
          s ? strlen(s) : 0, len);
    free(s);
    free(want);
    free(h);
}

/* The pieces the file writer cuts pending rows into: each stays inside one 4096-byte page
 * of the file and ends at a row end, or is exactly one row (one that crosses a page
 * boundary); together they are the rows. Rows of 1 to 700 bytes from offsets near page
 * boundaries. */
static void test_file_writer_pieces(void) {
    printf("file writer: pieces inside pages\n");
    char buf[20000];
    unsigned seed = 12345;
    int bad = 0, pieces = 0, crossing = 0;
    for (int trial = 0; trial < 200; trial++) {
        size_t n = 0;
        while (n < sizeof buf - 800) {
            seed = seed * 1103515245u + 12345u;
            size_t len = 1 + (seed >> 16) % 700;
            memset(buf + n, 'x', len - 1);
            buf[n + len - 1] = '\n';
            n += len;
        }
        seed = seed * 1103515245u + 12345u;
        long long off = 4096LL * (trial % 5) + (trial % 3 == 0 ? 0 : (long long)((seed >> 16) % 4096));
        size_t done = 0;
        while (done < n) {
            size_t k = floe_fw_next_write(buf + done, n - done, off);
            pieces++;
            int ends_row = k > 0 && buf[done + k - 1] == '\n';
            int in_page = off / 4096 == (off + (long long)k - 1) / 4096;
            const char *nl = memchr(buf + done, '\n', n - done);
            int one_row = nl && (size_t)(nl - (buf + done)) + 1 == k;
            if (!ends_row || !(in_page || one_row) || k > n - done) bad++;
            crossing += !in_page;
            done += k ? k : n - done;
            off += (long long)k;
        }
    }
    CHECK(bad == 0, "%d of %d pieces cross a page boundary with more than one row or end inside a row", bad, pieces);
    CHECK(crossing > 100, "the trials include rows that cross a page boundary (%d)", crossing);
}

/* Open errors name the path and the errno text; no temporary file is left by the VTK writer. */
static void test_file_writer_errors(void) {
    printf("file writer: errors and temporary files\n");
    char err[256];
    CHECK(floe_energy_tracker_create(OUTDIR "/no/such/dir/e.csv", err, sizeof err) == NULL, "missing directory");
    CHECK(strstr(err, "energy tracker: cannot open " OUTDIR "/no/such/dir/e.csv: ") && strstr(err, strerror(ENOENT)),
          "message names the path and the errno text: %s", err);
    if (access("/dev/full", W_OK) == 0) {
        CHECK(floe_csv_writer_create("/dev/full", err, sizeof err) == NULL, "/dev/full refused");
        CHECK(strstr(err, "csv writer: cannot write /dev/full: ") && strstr(err, strerror(ENOSPC)),
              "header write error names the path and ENOSPC: %s", err);
    }
    CHECK(access(OUTDIR "/bin.pvd", F_OK) == 0 && access(OUTDIR "/bin.pvd.tmp", F_OK) != 0 &&
              access(OUTDIR "/bin_000001.vtu.tmp", F_OK) != 0 && access(OUTDIR "/asc_000000.vtu.tmp", F_OK) != 0,
          "the VTK writer left its collection and no temporary file");
}

int main(void) {
    if (mkdir(OUTDIR, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "cannot create %s\n", OUTDIR);
        return 2;
    }
    test_stress_hand();
    test_stress_column();
    test_stress_2d();
    test_collection_tracker();
    test_particle_tracker();
    test_energy_and_csv();
    test_vtk(1);
    test_vtk(0);
    test_file_writer_pages();
    test_file_writer_pieces();
    test_file_writer_errors();
    return check_summary("test_observers");
}
