/* test_sdf_bound.c - user SDFs that are not exact: a Lipschitz-1 bound of the distance
 * (|grad phi| <= 1, the usual SDFs of superellipsoids and smooth unions).
 *
 *  1. Walls: superellipsoids (exponents 2.5, 4, 10; phi = m (N(x) - 1), N the anisotropic
 *     p-norm, m the smallest semi-axis) and a smooth union of two spheres (polynomial smooth
 *     min), 1 cm grains at 0.1 mm overlap with a plane in 32 orientations: every contact
 *     found, depth within 1e-5 of the overlap (1e-9 m) of the exact depth (the dual norm
 *     for superellipsoids; ray bisection and a pattern search for the union).
 *  2. Spheres: a sphere 0.1 mm into each shape at 32 surface points: depth within 1e-5 of
 *     the overlap (the sphere contact once took r - phi(centre), an overestimate for a bound).
 *  3. Grain-grain collisions, frictionless and undamped (linear law), oblique and spinning:
 *     kinetic energy after equals before within 1e-3 (relative). The same for built-in
 *     ellipsoids and cylinders through ADMM: with the force at the midpoint of the two
 *     halves' points the cylinders (flat caps) lost 1.6e-2 and 2.1e-3; at the deeper
 *     half's point 1.3e-6 and 1.8e-6.
 *  4. A user SDF with Lipschitz constant 2 is refused by floe_world_add_geometry with
 *     FLOE_EINVAL and a message that names the shape; so is a custom class without
 *     `project` whose SDF has constant 3; the exact and bound shapes above pass.
 *  5. Cost: SDF evaluations per contact evaluation (a counting SDF wrapper), median and p99
 *     printed for walls, spheres and grain pairs (docs/models.md quotes them); p99 bounded. */
#include "check.h"
#include "floe.h"
#include "floe.h"
#include "world_read.h"
#include <stdlib.h>
#include <string.h>

typedef struct shape {
    int kind;        /* 0 superellipsoid, 1 smooth union of two spheres, 2 Lipschitz-2 sphere,
                        3 rounded box (exact SDF, for the cost comparison) */
    double a[3], p;  /* superellipsoid semi-axes and exponent */
    double r, s, k;  /* union: sphere radius, centres at +-s along x, blend width k; rounded
                        box: half extents a, rounding r */
    long evals;      /* SDF evaluations (the counting wrapper) */
} shape;

static double se_norm(const shape *S, const double X[3]) {
    double t = 0;
    for (int i = 0; i < 3; i++) t += pow(fabs(X[i]) / S->a[i], S->p);
    return pow(t, 1.0 / S->p);
}
static double smin(double a, double b, double k) { /* polynomial smooth min (Quilez) */
    double h = fmax(k - fabs(a - b), 0.0) / k;
    return fmin(a, b) - h * h * k * 0.25;
}
static double shape_sdf(const double X[3], void *user) {
    shape *S = user;
    S->evals++;
    if (S->kind == 0) return fmin(S->a[0], fmin(S->a[1], S->a[2])) * (se_norm(S, X) - 1);
    if (S->kind == 1) {
        double d1 = sqrt((X[0] - S->s) * (X[0] - S->s) + X[1] * X[1] + X[2] * X[2]) - S->r;
        double d2 = sqrt((X[0] + S->s) * (X[0] + S->s) + X[1] * X[1] + X[2] * X[2]) - S->r;
        return smin(d1, d2, S->k);
    }
    if (S->kind == 3) {
        double q[3], out = 0, in = -INFINITY;
        for (int k = 0; k < 3; k++) {
            q[k] = fabs(X[k]) - S->a[k];
            if (q[k] > 0) out += q[k] * q[k];
            if (q[k] > in) in = q[k];
        }
        return sqrt(out) + fmin(in, 0.0) - S->r;
    }
    return 2 * (floe_v3_norm(X) - S->r);
}

/* ---- independent references ---- */
/* surface point along the ray from the origin in direction u (star-shaped), by bisection */
static void ray_point(shape *S, const double u[3], double y[3]) {
    double lo = 0, hi = 0.05;
    for (int it = 0; it < 64; it++) {
        double m = 0.5 * (lo + hi), X[3] = {m * u[0], m * u[1], m * u[2]};
        if (shape_sdf(X, S) > 0) hi = m;
        else lo = m;
    }
    for (int k = 0; k < 3; k++) y[k] = lo * u[k];
}
static void dir_of(double th, double ph, double u[3]) {
    floe_v3_set(u, sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
}
/* support value h(d) = max over the shape of d.x: exact dual norm for a superellipsoid;
 * dense ray sampling then a pattern search in (theta, phi) for the union */
static double support_ref(shape *S, const double d[3]) {
    if (S->kind == 0) {
        double q = S->p / (S->p - 1), t = 0;
        for (int i = 0; i < 3; i++) t += pow(fabs(S->a[i] * d[i]), q);
        return pow(t, 1.0 / q);
    }
    if (S->kind == 3) return S->a[0] * fabs(d[0]) + S->a[1] * fabs(d[1]) + S->a[2] * fabs(d[2]) + S->r;
    double best = -INFINITY, bt = 0, bp = 0, u[3], y[3];
    for (int i = 0; i <= 60; i++)
        for (int j = 0; j < 120; j++) {
            double th = M_PI * i / 60, ph = 2 * M_PI * j / 120;
            dir_of(th, ph, u);
            ray_point(S, u, y);
            double f = floe_v3_dot(y, d);
            if (f > best) { best = f; bt = th; bp = ph; }
        }
    for (double st = 0.05; st > 1e-10; st *= 0.5)
        for (int moved = 1; moved;) {
            moved = 0;
            const double dt[4][2] = {{st, 0}, {-st, 0}, {0, st}, {0, -st}};
            for (int m = 0; m < 4; m++) {
                dir_of(bt + dt[m][0], bp + dt[m][1], u);
                ray_point(S, u, y);
                double f = floe_v3_dot(y, d);
                if (f > best + 1e-16) { best = f; bt += dt[m][0]; bp += dt[m][1]; moved = 1; }
            }
        }
    return best;
}
/* outward unit normal at a surface point: the analytic gradient of the SDF, normalised */
static void normal_ref(shape *S, const double y[3], double n[3]) {
    if (S->kind == 0) {
        double N = se_norm(S, y);
        for (int i = 0; i < 3; i++)
            n[i] = copysign(pow(fabs(y[i]) / S->a[i] / N, S->p - 1) / S->a[i], y[i]);
    } else if (S->kind == 3) { /* from the nearest point of the inner box */
        for (int i = 0; i < 3; i++) n[i] = y[i] - fmin(fmax(y[i], -S->a[i]), S->a[i]);
    } else {
        double c1[3] = {y[0] - S->s, y[1], y[2]}, c2[3] = {y[0] + S->s, y[1], y[2]};
        double d1 = floe_v3_norm(c1) - S->r, d2 = floe_v3_norm(c2) - S->r;
        double h = fmax(S->k - fabs(d1 - d2), 0.0) / S->k;
        /* d smin / d d1 = w, d / d d2 = 1 - w */
        double w = d1 < d2 ? 1 - 0.5 * h : 0.5 * h;
        double n1 = floe_v3_norm(c1), n2 = floe_v3_norm(c2);
        for (int i = 0; i < 3; i++) n[i] = w * c1[i] / n1 + (1 - w) * c2[i] / n2;
    }
    floe_v3_scale(n, 1.0 / floe_v3_norm(n));
}

static void random_q(double q[4], unsigned *seed) {
    double th[3];
    for (int k = 0; k < 3; k++) th[k] = 3.0 * ((double)rand_r(seed) / RAND_MAX - 0.5);
    floe_q_from_rotvec(q, th);
}

static int cmp_long(const void *a, const void *b) {
    long x = *(const long *)a, y = *(const long *)b;
    return (x > y) - (x < y);
}
static void report_cost(const char *what, long *v, int n, long *p99_out) {
    qsort(v, (size_t)n, sizeof *v, cmp_long);
    long med = n ? v[n / 2] : 0, p99 = n ? v[(int)(0.99 * (n - 1))] : 0;
    printf("  cost %-48s %5d contacts: SDF evaluations median %ld, p99 %ld, max %ld\n", what, n, med, p99,
           n ? v[n - 1] : 0);
    *p99_out = p99;
}

#define NSHAPE 5
#define NBOUND 4 /* the first four are bounds, the last exact */
static shape shapes[NSHAPE];
static const char *names[NSHAPE] = {"superellipsoid p=2.5", "superellipsoid p=4", "superellipsoid p=10",
                                    "smooth union of two spheres", "rounded box (exact)"};
static void make_shapes(void) {
    const double ps[3] = {2.5, 4, 10};
    for (int k = 0; k < 3; k++) {
        memset(&shapes[k], 0, sizeof shapes[k]);
        shapes[k].kind = 0;
        floe_v3_set(shapes[k].a, 0.005, 0.004, 0.0035);
        shapes[k].p = ps[k];
    }
    memset(&shapes[3], 0, sizeof shapes[3]);
    shapes[3].kind = 1;
    shapes[3].r = 0.004; shapes[3].s = 0.0015; shapes[3].k = 0.003;
    memset(&shapes[4], 0, sizeof shapes[4]);
    shapes[4].kind = 3;
    floe_v3_set(shapes[4].a, 0.004, 0.003, 0.0025);
    shapes[4].r = 0.001;
}
static double bound_radius(const shape *S) {
    return S->kind == 0 ? floe_v3_norm(S->a) : S->kind == 3 ? floe_v3_norm(S->a) + S->r : S->s + S->r;
}

/* ---- 1. walls and 2. spheres ---- */

/* detects the contact of i and j: the SDF evaluations it cost go to cost[(*n)++], a miss
 * to *missed, its depth error against the exact overlap to *worst */
static void depth_sample(floe_world *w, shape *S, int i, int j, double overlap, long *cost, int *n, int *missed,
                         double *worst) {
    floe_contact c;
    long e0 = S->evals;
    int r = floe_world_probe_contact(w, i, j, 0, &c);
    cost[(*n)++] = S->evals - e0;
    if (r != 1) (*missed)++;
    else *worst = fmax(*worst, fabs(c.depth - overlap));
}

static void test_walls_spheres(long *cost_wall[2], int nw[2], long *cost_sphere[2], int ns[2]) {
    const double overlap = 1e-4, tol = 1e-5 * overlap;
    for (int si = 0; si < NSHAPE; si++) {
        shape *S = &shapes[si];
        floe_world_def d = floe_default_world_def();
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"m", 1000, 1e7, 0.3};
        floe_world_add_material(w, &m);
        double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
        int wall = floe_world_add_wall(w, o, nz, 0, FLOE_FIXED);
        int g = floe_world_add_geometry(w, floe_user_shape_create_named(shape_sdf, S, bound_radius(S), names[si]));
        int gs = floe_world_add_geometry(w, floe_sphere_create(0.002));
        CHECK(g >= 0 && gs >= 0, "%s: geometry refused: %s", names[si], floe_world_last_error(w));
        if (g < 0) { floe_world_destroy(w); continue; }
        unsigned seed = 1234u + (unsigned)si;
        int missed = 0;
        double worst = 0;
        for (int t = 0; t < 32; t++) {
            floe_particle_def p = floe_default_particle_def();
            p.geometry = g;
            random_q(p.q, &seed);
            /* exact depth: support of the body in -z (body frame) minus the centre height */
            double down[3] = {0, 0, -1}, db[3];
            floe_q_rotate_inv(db, p.q, down);
            double h = support_ref(S, db);
            floe_v3_set(p.x, 0.01 * t, 0, h - overlap);
            int i = floe_world_add_particle(w, &p);
            int grp = si >= NBOUND;
            depth_sample(w, S, i, wall, overlap, cost_wall[grp], &nw[grp], &missed, &worst);
        }
        CHECK(missed == 0, "%s against a wall: %d of 32 orientations missed at 0.1 mm overlap", names[si], missed);
        CHECK(worst <= tol, "%s against a wall: depth error %.3g m > %.3g m", names[si], worst, tol);
        printf("  %-28s wall, 32 orientations at 0.1 mm: missed %d, max |depth - exact| %.2e m (tol %.0e)\n",
               names[si], missed, worst, tol);
        /* spheres 0.1 mm into the shape at 32 surface points (along the outward normal) */
        missed = 0;
        worst = 0;
        for (int t = 0; t < 32; t++) {
            double u[3], y[3], n[3];
            dir_of(acos(1 - 2 * (t + 0.5) / 32), 2.39996 * t, u); /* Fibonacci sphere */
            ray_point(S, u, y);
            normal_ref(S, y, n);
            floe_particle_def p = floe_default_particle_def();
            p.geometry = gs;
            for (int k = 0; k < 3; k++) p.x[k] = (k == 0 ? 0.5 : 0.0) + y[k] + (0.002 - overlap) * n[k];
            int sp = floe_world_add_particle(w, &p);
            floe_particle_def q = floe_default_particle_def();
            q.geometry = g;
            floe_v3_set(q.x, 0.5, 0, 0);
            int gi = floe_world_add_particle(w, &q);
            int grp = si >= NBOUND;
            depth_sample(w, S, sp, gi, overlap, cost_sphere[grp], &ns[grp], &missed, &worst);
        }
        CHECK(missed == 0, "%s against spheres: %d of 32 missed", names[si], missed);
        CHECK(worst <= tol, "%s against spheres: depth error %.3g m > %.3g m", names[si], worst, tol);
        printf("  %-28s sphere, 32 surface points at 0.1 mm: missed %d, max |depth - exact| %.2e m (tol %.0e)\n",
               names[si], missed, worst, tol);
        floe_world_destroy(w);
    }
}

/* ---- 3. frictionless undamped grain-grain collisions ---- */
static void test_collisions(long *cost[2], int nc[2], int cap) {
    for (int si = 0; si < NSHAPE; si++) {
        shape *S = &shapes[si];
        for (int trial = 0; trial < 2; trial++) {
            floe_world_def d = floe_default_world_def();
            d.dt = 1e-6;
            floe_world *w = floe_world_create(&d, NULL, 0);
            floe_material m = {"m", 1000, 1e7, 0.3};
            int mat = floe_world_add_material(w, &m);
            floe_world_set_law(w, mat, mat, floe_linear_law_create(1e4, 0, 0, 0, 0));
            int g = floe_world_add_geometry(w, floe_user_shape_create_named(shape_sdf, S, bound_radius(S), names[si]));
            unsigned seed = 77u + 13u * (unsigned)si + 1000u * (unsigned)trial;
            floe_particle_def p = floe_default_particle_def();
            p.geometry = g; p.material = mat;
            double R = bound_radius(S);
            /* head-on along x (trial 0) or oblique with an offset in y (trial 1), both
             * grains spinning; they start 0.2 mm apart along x (the extents along x from
             * the reference support function) */
            double q0[4], q1[4], ex[3] = {1, 0, 0}, mx[3] = {-1, 0, 0}, d0[3], d1[3];
            random_q(q0, &seed);
            random_q(q1, &seed);
            floe_q_rotate_inv(d0, q0, ex);
            floe_q_rotate_inv(d1, q1, mx);
            double gap = 2e-4, x0 = -support_ref(S, d0) - 0.5 * gap, x1 = support_ref(S, d1) + 0.5 * gap;
            (void)R;
            memcpy(p.q, q0, sizeof q0);
            floe_v3_set(p.x, x0, trial ? -0.25 * R : 0, 0);
            floe_v3_set(p.v, 0.4, 0, 0);
            floe_v3_set(p.w, 3, -5, 8);
            floe_world_add_particle(w, &p);
            memcpy(p.q, q1, sizeof q1);
            floe_v3_set(p.x, x1, trial ? 0.25 * R : 0, 0);
            floe_v3_set(p.v, -0.4, 0, 0);
            floe_v3_set(p.w, -6, 2, 4);
            floe_world_add_particle(w, &p);
            int rc = floe_world_prepare(w);
            CHECK(rc == 0, "%s collision: prepare failed: %s", names[si], floe_world_last_error(w));
            if (rc) { floe_world_destroy(w); continue; }
            floe_energy e0 = floe_world_energy(w);
            double k0 = e0.kinetic_trans + e0.kinetic_rot;
            int contact_steps = 0, after = 0;
            for (int step = 0; step < 200000 && after < 200; step++) {
                long ev = S->evals;
                floe_world_step(w);
                int nct = floe_world_contact_count(w);
                int grp = si >= NBOUND;
                if (nct > 0 && nc[grp] < cap) cost[grp][nc[grp]++] = S->evals - ev;
                if (nct > 0) contact_steps++;
                else if (contact_steps > 0) after++;
            }
            floe_energy e1 = floe_world_energy(w);
            double k1 = e1.kinetic_trans + e1.kinetic_rot;
            floe_detect_stats st;
            floe_world_detect_stats(w, &st);
            double rel = fabs(k1 - k0) / k0;
            printf("  %-28s %s collision: %d contact steps, KE %.6g -> %.6g J (rel %.2e, tol 1e-3), "
                   "iterations median %d p99 %d, not converged %ld\n",
                   names[si], trial ? "oblique" : "head-on", contact_steps, k0, k1, rel, st.iterations_median,
                   st.iterations_p99, st.nonconverged);
            CHECK(contact_steps > 20, "%s %s collision: the grains never met (%d contact steps)", names[si],
                  trial ? "oblique" : "head-on", contact_steps);
            CHECK(rel <= 1e-3, "%s %s collision: kinetic energy %.6g -> %.6g (rel %.3g > 1e-3)", names[si],
                  trial ? "oblique" : "head-on", k0, k1, rel);
            floe_world_destroy(w);
        }
    }
}

/* ---- 3b. the same collision for two built-in ellipsoids (ADMM, exact SDFs): the force
 * acts at the deeper half's point, not at the midpoint of the two halves' points ---- */
static void test_admm_collision(void) {
    for (int trial = 0; trial < 4; trial++) {
        const char *gname = trial < 2 ? "ellipsoids" : "cylinders";
        floe_world_def d = floe_default_world_def();
        d.dt = 1e-6;
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_material m = {"m", 1000, 1e7, 0.3};
        int mat = floe_world_add_material(w, &m);
        floe_world_set_law(w, mat, mat, floe_linear_law_create(1e4, 0, 0, 0, 0));
        int g = floe_world_add_geometry(w, trial < 2 ? floe_ellipsoid_create(0.005, 0.003, 0.002)
                                                     : floe_cylinder_create(0.004, 0.004));
        unsigned seed = 4242u + 7u * (unsigned)trial;
        floe_particle_def p = floe_default_particle_def();
        p.geometry = g; p.material = mat;
        random_q(p.q, &seed);
        floe_v3_set(p.x, -0.0052, trial % 2 ? -0.002 : 0, 0);
        floe_v3_set(p.v, 0.4, 0, 0);
        floe_v3_set(p.w, 30, -50, 80);
        floe_world_add_particle(w, &p);
        random_q(p.q, &seed);
        floe_v3_set(p.x, 0.0052, trial % 2 ? 0.002 : 0, 0);
        floe_v3_set(p.v, -0.4, 0, 0);
        floe_v3_set(p.w, -60, 20, 40);
        floe_world_add_particle(w, &p);
        int rc = floe_world_prepare(w);
        CHECK(rc == 0, "ellipsoid collision: prepare failed: %s", floe_world_last_error(w));
        if (rc) { floe_world_destroy(w); continue; }
        floe_energy e0 = floe_world_energy(w);
        double k0 = e0.kinetic_trans + e0.kinetic_rot;
        int contact_steps = 0, after = 0;
        for (int step = 0; step < 100000 && after < 200; step++) {
            floe_world_step(w);
            if (floe_world_contact_count(w) > 0) contact_steps++;
            else if (contact_steps > 0) after++;
        }
        floe_energy e1 = floe_world_energy(w);
        double k1 = e1.kinetic_trans + e1.kinetic_rot, rel = fabs(k1 - k0) / k0;
        printf("  %-10s (ADMM), %s, spinning: %d contact steps, KE %.6g -> %.6g J (rel %.2e, tol 1e-3)\n", gname,
               trial % 2 ? "oblique" : "head-on", contact_steps, k0, k1, rel);
        CHECK(contact_steps > 20, "%s collision: the grains never met", gname);
        CHECK(rel <= 1e-3, "%s collision: kinetic energy %.6g -> %.6g (rel %.3g > 1e-3)", gname, k0, k1, rel);
        floe_world_destroy(w);
    }
}

/* a custom class with only sdf and bounding_radius (no project): sampled when added */
static double steep_sdf(const floe_geometry *g, const double X[3]) { (void)g; return 3 * (floe_v3_norm(X) - 0.004); }
static double steep_radius(const floe_geometry *g) { (void)g; return 0.005; }
static const floe_geometry_class steep_class = {
    .version = 1, .name = "steep_custom", .kind = FLOE_GEOM_USER, .sdf = steep_sdf,
    .bounding_radius = steep_radius};

/* ---- 4. the Lipschitz check ---- */
static void test_lipschitz(void) {
    shape bad = {2, {0, 0, 0}, 0, 0.005, 0, 0, 0};
    floe_world_def d = floe_default_world_def();
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_geometry *dbl = floe_user_shape_create_named(shape_sdf, &bad, 0.006, "doubled_sphere");
    int g = floe_world_add_geometry(w, dbl);
    const char *msg = floe_world_last_error(w);
    CHECK(g == -FLOE_EINVAL, "an SDF with Lipschitz constant 2 must be refused (got %d)", g);
    CHECK(strstr(msg, "doubled_sphere") && strstr(msg, "Lipschitz"), "the message must name the shape: %s", msg);
    printf("  refused: %s\n", msg);
    floe_geometry *u = floe_user_shape_create(shape_sdf, &bad, 0.006);
    CHECK(u && fabs(((floe_user_shape *)u)->lipschitz - 2) < 0.02, "measured Lipschitz constant %.4g, expected 2",
          u ? ((floe_user_shape *)u)->lipschitz : NAN);
    g = floe_world_add_geometry(w, u); /* unnamed: the default name */
    CHECK(g < 0 && strstr(floe_world_last_error(w), "user_sdf"), "unnamed shape: %s", floe_world_last_error(w));
    floe_geometry_destroy(dbl); /* refused geometries stay the caller's */
    floe_geometry *steep = malloc(sizeof *steep);
    steep->klass = &steep_class;
    g = floe_world_add_geometry(w, steep);
    CHECK(g == -FLOE_EINVAL && strstr(floe_world_last_error(w), "steep_custom"),
          "a custom class without project and Lipschitz constant 3 must be refused: %d %s", g, floe_world_last_error(w));
    floe_geometry_destroy(steep);
    floe_geometry_destroy(u);
    for (int si = 0; si < NSHAPE; si++) {
        floe_geometry *s = floe_user_shape_create_named(shape_sdf, &shapes[si], bound_radius(&shapes[si]), names[si]);
        double L = ((floe_user_shape *)s)->lipschitz;
        printf("  %-28s measured Lipschitz constant %.4f\n", names[si], L);
        CHECK(L <= 1.0 + 1e-6 && L > 0.5, "%s: Lipschitz constant %.4g should be <= 1", names[si], L);
        floe_geometry_destroy(s);
    }
    floe_world_destroy(w);
}

int main(void) {
    make_shapes();
    enum { CAP = 400000 };
    long *cw[2], *cs[2], *cc[2];
    int nw[2] = {0, 0}, ns[2] = {0, 0}, nc[2] = {0, 0};
    for (int k = 0; k < 2; k++) {
        cw[k] = malloc(sizeof(long) * 256);
        cs[k] = malloc(sizeof(long) * 256);
        cc[k] = malloc(sizeof(long) * CAP);
    }
    test_lipschitz();
    test_walls_spheres(cw, nw, cs, ns);
    test_collisions(cc, nc, CAP);
    test_admm_collision();
    long p99[2][3];
    for (int k = 0; k < 2; k++) {
        const char *kind = k ? "exact" : "bound";
        char what[96];
        snprintf(what, sizeof what, "%s SDFs, wall (support climb)", kind);
        report_cost(what, cw[k], nw[k], &p99[k][0]);
        snprintf(what, sizeof what, "%s SDFs, sphere (true distance)", kind);
        report_cost(what, cs[k], ns[k], &p99[k][1]);
        snprintf(what, sizeof what, "%s SDFs, grain pair per step in contact", kind);
        report_cost(what, cc[k], nc[k], &p99[k][2]);
    }
    /* regression bounds, about 4x the measured p99 of the bound SDFs (docs/models.md:
     * 1088, 245, 6554) */
    for (int k = 0; k < 2; k++)
        CHECK(p99[k][0] < 5000 && p99[k][1] < 1000 && p99[k][2] < 30000,
              "SDF evaluations per contact: p99 wall %ld, sphere %ld, pair %ld", p99[k][0], p99[k][1], p99[k][2]);
    for (int k = 0; k < 2; k++) { free(cw[k]); free(cs[k]); free(cc[k]); }
    return check_summary("test_sdf_bound");
}
