/* test_user_polytope.c - a shape class written by a user (here, not floe_polytope) reaches the
 * exact contact paths of the built-in polytopes by what its class gives (floe_geometry.h,
 * "capabilities"; docs/extending.md, "A shape"), never by which class it is:
 *  1. a triangular prism (3D) / triangle (2D) defined by its own face planes, corners and SDF,
 *     giving `polytope` and `dimension`, against a built-in box and polytope: the deepest-point
 *     LP (the world's detection counters: LP evaluations, no ADMM), the contact manifold,
 *     the per-vertex wall contact and the overlap-area law give the same depth, normal,
 *     point, manifold springs, overlap integrals and contact force as the built-in prism
 *     (floe_prism_create) / polygon of the same shape placed at the same pose, to 1e-12
 *     relative (the two differ only by the rounding of the built-in's principal frame;
 *     lengths, areas and forces relative to their value or to that of a contact 1e-3 of the
 *     size deep, whichever is larger: a sliver's integrals are all cancellation). Placements
 *     are random; point-law contacts shallow (a deep overlap meets several faces at once,
 *     where the normal is any of their subgradients and depends on the order of the faces);
 *  2. a user union of two boxes giving `piece_count` and `piece` gets one contact per piece
 *     pair, each equal to the built-in compound's (floe_compound_create) to 1e-12;
 *  3. `dimension`: the planar user triangle is refused in a 3D world as a polygon is.
 * Without the capabilities the user prism took the SDF path (projected ascent: depths to
 * ~1e-9, no LP) and the union one contact for the whole body. */
#include "floe.h"
#include "floe_detect.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>

#define TEST_RNG_SEED 0x5DEECE66DULL
#include "test_rng.h"

#define TOL 1e-12

/* ---- a user's convex polytope: the triangle (-a, -b), (a, -b), (0, 2b) (centroid at the
 * origin, symmetric about x = 0: the body axes are principal), in 3D extruded over
 * z in [-h/2, h/2] ---- */
typedef struct tri_prism {
    floe_geometry base;
    int dim;                /* 3: prism, 2: triangle in the xy plane */
    double a, b, h;
    double plane[4 * 5];    /* the three sides, then -z and +z */
    double v[3 * 6];        /* corners (3D) */
    double v2[3 * 3];       /* corners of the section z = 0 */
} tri_prism;

static void tri_corners(double a, double b, double xy[6]) {
    xy[0] = -a; xy[1] = -b; xy[2] = a; xy[3] = -b; xy[4] = 0; xy[5] = 2 * b;
}

static double tp_sdf(const floe_geometry *g, const double X[3]) {
    const tri_prism *t = (const tri_prism *)g;
    double s = -INFINITY;
    for (int k = 0; k < (t->dim == 3 ? 5 : 3); k++) s = fmax(s, floe_v3_dot(t->plane + 4 * k, X) - t->plane[4 * k + 3]);
    return s; /* exact inside, a lower bound outside (Lipschitz 1) */
}
static double tp_radius(const floe_geometry *g) {
    const tri_prism *t = (const tri_prism *)g;
    double r = 0;
    for (int k = 0; k < (t->dim == 3 ? 6 : 3); k++) r = fmax(r, floe_v3_norm((t->dim == 3 ? t->v : t->v2) + 3 * k));
    return r;
}
static void tp_support(const floe_geometry *g, const double d[3], double o[3]) {
    const tri_prism *t = (const tri_prism *)g;
    const double *V = t->dim == 3 ? t->v : t->v2;
    int best = 0, n = t->dim == 3 ? 6 : 3;
    for (int k = 1; k < n; k++)
        if (floe_v3_dot(V + 3 * k, d) > floe_v3_dot(V + 3 * best, d)) best = k;
    floe_v3_copy(o, V + 3 * best);
}
/* analytic: for a triangle with its centroid at the origin, int x x^T dA = A/12 sum p p^T */
static int tp_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const tri_prism *t = (const tri_prism *)g;
    const double A = 3 * t->a * t->b, sxx = t->a * t->a / 6, syy = t->b * t->b / 2, szz = t->h * t->h / 12;
    memset(o, 0, sizeof *o);
    if (dim == 2) {
        o->volume = A;
        o->mass = rho * A;
        floe_v3_set(o->inertia, o->mass * syy, o->mass * sxx, o->mass * (sxx + syy));
    } else {
        o->volume = A * t->h;
        o->mass = rho * o->volume;
        floe_v3_set(o->inertia, o->mass * (syy + szz), o->mass * (sxx + szz), o->mass * (sxx + syy));
    }
    return FLOE_OK;
}
static void tp_polytope(const floe_geometry *g, int dim, floe_polytope_view *out) {
    const tri_prism *t = (const tri_prism *)g;
    out->plane = t->plane;
    out->np = dim == 2 ? 3 : 5;
    out->v = dim == 2 ? t->v2 : t->v;
    out->nv = dim == 2 ? 3 : 6;
}
static int tp_dimension(const floe_geometry *g) { return ((const tri_prism *)g)->dim; }

static const floe_geometry_class tri_prism_class = {
    .version = 1, .name = "user_tri_prism", .kind = FLOE_GEOM_USER, .sdf = tp_sdf, .bounding_radius = tp_radius,
    .mass_properties = tp_mass, .support = tp_support, .polytope = tp_polytope, .dimension = tp_dimension};

static floe_geometry *tri_prism_create(int dim, double a, double b, double h) {
    tri_prism *t = calloc(1, sizeof *t);
    t->base.klass = &tri_prism_class;
    t->dim = dim; t->a = a; t->b = b; t->h = h;
    double xy[6];
    tri_corners(a, b, xy);
    for (int k = 0; k < 3; k++) { /* side k -> k+1, counter-clockwise: outward normal (dy, -dx) */
        const double *p = xy + 2 * k, *q = xy + 2 * ((k + 1) % 3);
        double n[3] = {q[1] - p[1], p[0] - q[0], 0}, l = floe_v3_norm(n);
        floe_v3_scale(n, 1.0 / l);
        floe_v3_copy(t->plane + 4 * k, n);
        t->plane[4 * k + 3] = n[0] * p[0] + n[1] * p[1];
        floe_v3_set(t->v2 + 3 * k, p[0], p[1], 0);
        floe_v3_set(t->v + 3 * k, p[0], p[1], -h / 2);
        floe_v3_set(t->v + 3 * (k + 3), p[0], p[1], h / 2);
    }
    double zl[4] = {0, 0, -1, h / 2}, zh[4] = {0, 0, 1, h / 2};
    memcpy(t->plane + 12, zl, sizeof zl);
    memcpy(t->plane + 16, zh, sizeof zh);
    return &t->base;
}

/* the built-in of the same shape; *fx, *fq: where its body frame lies in the user's */
static floe_geometry *builtin_prism(int dim, double a, double b, double h, double fx[3], double fq[4]) {
    double xy[6];
    char err[256];
    tri_corners(a, b, xy);
    floe_geometry *g = dim == 2 ? floe_polygon_create(xy, 3, err, sizeof err) : floe_prism_create(xy, 3, h, err, sizeof err);
    const floe_polytope *p = (const floe_polytope *)g;
    floe_v3_copy(fx, p->frame_x);
    memcpy(fq, p->frame_q, 4 * sizeof(double));
    return g;
}

/* ---- a user's union of convex pieces: two equal boxes at (-d, 0, 0) and (d, 0, 0) ---- */
typedef struct box_pair {
    floe_geometry base;
    floe_geometry *piece[2];
    double s[3], d;
} box_pair;

static double bp_sdf(const floe_geometry *g, const double X[3]) {
    const box_pair *u = (const box_pair *)g;
    double s = INFINITY;
    for (int k = 0; k < 2; k++) {
        double Y[3] = {X[0] - (k ? u->d : -u->d), X[1], X[2]};
        s = fmin(s, floe_geometry_sdf(u->piece[k], Y));
    }
    return s;
}
static double bp_radius(const floe_geometry *g) {
    const box_pair *u = (const box_pair *)g;
    return u->d + floe_geometry_bounding_radius(u->piece[0]);
}
static int bp_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const box_pair *u = (const box_pair *)g;
    const double *s = u->s, d = u->d;
    memset(o, 0, sizeof *o);
    if (dim == 2) {
        double mb = rho * s[0] * s[1];
        o->volume = 2 * s[0] * s[1];
        o->mass = 2 * mb;
        floe_v3_set(o->inertia, 2 * mb * s[1] * s[1] / 12, 2 * (mb * s[0] * s[0] / 12 + mb * d * d),
                    2 * (mb * (s[0] * s[0] + s[1] * s[1]) / 12 + mb * d * d));
    } else {
        double mb = rho * s[0] * s[1] * s[2];
        o->volume = 2 * s[0] * s[1] * s[2];
        o->mass = 2 * mb;
        floe_v3_set(o->inertia, 2 * mb * (s[1] * s[1] + s[2] * s[2]) / 12,
                    2 * (mb * (s[0] * s[0] + s[2] * s[2]) / 12 + mb * d * d),
                    2 * (mb * (s[0] * s[0] + s[1] * s[1]) / 12 + mb * d * d));
    }
    return FLOE_OK;
}
static void bp_destroy(floe_geometry *g) {
    box_pair *u = (box_pair *)g;
    floe_geometry_destroy(u->piece[0]);
    floe_geometry_destroy(u->piece[1]);
    free(u);
}
static void bp_support(const floe_geometry *g, const double dir[3], double o[3]) {
    const box_pair *u = (const box_pair *)g;
    double best = -INFINITY, X[3];
    for (int k = 0; k < 2; k++) {
        floe_geometry_support(u->piece[k], dir, X);
        X[0] += k ? u->d : -u->d;
        if (floe_v3_dot(X, dir) > best) { best = floe_v3_dot(X, dir); floe_v3_copy(o, X); }
    }
}
static int bp_count(const floe_geometry *g) { (void)g; return 2; }
static const floe_geometry *bp_piece(const floe_geometry *g, int k, double x[3], double q[4], double *r) {
    const box_pair *u = (const box_pair *)g;
    floe_v3_set(x, k ? u->d : -u->d, 0, 0);
    floe_q_identity(q);
    *r = floe_geometry_bounding_radius(u->piece[k]);
    return u->piece[k];
}
static const floe_geometry_class box_pair_class = {
    .version = 1, .name = "user_box_pair", .kind = FLOE_GEOM_COMPOUND, .sdf = bp_sdf, .bounding_radius = bp_radius,
    .mass_properties = bp_mass, .destroy = bp_destroy, .support = bp_support, .piece_count = bp_count, .piece = bp_piece};

static floe_geometry *box_pair_create(const double s[3], double d) {
    box_pair *u = calloc(1, sizeof *u);
    u->base.klass = &box_pair_class;
    floe_v3_copy(u->s, s);
    u->d = d;
    for (int k = 0; k < 2; k++) u->piece[k] = floe_box_create(s[0], s[1], s[2]);
    return &u->base;
}
static floe_geometry *builtin_box_pair(int dim, const double s[3], double d, double fx[3], double fq[4]) {
    floe_geometry *pieces[2] = {floe_box_create(s[0], s[1], s[2]), floe_box_create(s[0], s[1], s[2])};
    double x[6] = {-d, 0, 0, d, 0, 0};
    char err[256];
    floe_geometry *g = floe_compound_create(pieces, x, NULL, 2, dim, err, sizeof err);
    const floe_compound *c = (const floe_compound *)g;
    floe_v3_copy(fx, c->frame_x);
    memcpy(fq, c->frame_q, 4 * sizeof(double));
    return g;
}

/* ---- twin worlds: the user's shape or the built-in at the same pose, and a partner ---- */
typedef struct twin {
    floe_world *w;
    int wall;   /* the wall's particle index, or -1 */
} twin;

static twin make_twin(int dim, int overlap, floe_geometry *g, const double fx[3], const double fq[4], const double x[3],
                      const double q[4], floe_geometry *partner, const double xp[3], const double qp[4], int wall) {
    floe_world_def d = floe_default_world_def();
    d.dim = dim;
    d.mass_2d_area = dim == 2;
    d.dt = 1e-5;
    twin t = {floe_world_create(&d, NULL, 0), -1};
    floe_material m = {"m", 1000, 1e9, 0.3};
    int mat = floe_world_add_material(t.w, &m);
    /* elastic and frictionless: the force is the law's function of the detected contact only */
    floe_world_set_law(t.w, mat, mat, overlap ? floe_overlap_law_create(dim == 2 ? 1e6 : 1e7, 0, 0, 0, 0)
                                              : floe_linear_law_create(1e5, 0, 0, 0, 0));
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(t.w, g);
    p.material = mat;
    /* the body frame of g lies at fx, fq in the user's: x + R(q) fx, q fq */
    double off[3];
    floe_q_rotate(off, q, fx);
    floe_v3_add(p.x, x, off);
    floe_q_mul(p.q, q, fq);
    int rc = floe_world_add_particle(t.w, &p);
    CHECK(rc == 0, "add the shape: %s", floe_world_last_error(t.w));
    if (partner) {
        p = floe_default_particle_def();
        p.geometry = floe_world_add_geometry(t.w, partner);
        p.material = mat;
        floe_v3_copy(p.x, xp);
        memcpy(p.q, qp, sizeof p.q);
        floe_world_add_particle(t.w, &p);
    }
    if (wall) {
        double o[3] = {0, 0, 0}, n[3] = {0, 0, 0};
        n[dim - 1] = 1;
        t.wall = floe_world_add_wall(t.w, o, n, mat, FLOE_FIXED);
    }
    floe_world_record_contacts(t.w, 1);
    rc = floe_world_prepare(t.w);
    CHECK(rc == 0, "prepare: %s", floe_world_last_error(t.w));
    return t;
}

static double vdiff(const double a[3], const double b[3]) {
    double d[3];
    floe_v3_sub(d, a, b);
    return floe_v3_norm(d);
}

static double worst_rel = 0; /* the largest relative difference seen in all comparisons */
static void near(double got, double ref, double scale, const char *what, int k) {
    double e = fabs(got - ref) / scale;
    worst_rel = fmax(worst_rel, e);
    CHECK(e <= TOL, "%s (case %d): user %.17g built-in %.17g (rel %.3g > %.0e)", what, k, got, ref, e, TOL);
}
static void near3(const double got[3], const double ref[3], double scale, const char *what, int k) {
    double e = vdiff(got, ref) / scale;
    worst_rel = fmax(worst_rel, e);
    CHECK(e <= TOL, "%s (case %d): differ by %.3g relative (> %.0e)", what, k, e, TOL);
}

/* the point-law contact (probe: depth, normal, point, manifold) and the force of the first
 * step of user and built-in twins; size: the length scale of the relative tolerance */
static int compare_contact(twin *u, twin *r, int i, int j, int sub, double size, int k) {
    floe_contact cu, cr;
    memset(&cu, 0, sizeof cu); /* a probe fills what its detector sets (a wall contact: no gscale) */
    memset(&cr, 0, sizeof cr);
    int hu = floe_world_probe_contact(u->w, i, j, sub, &cu), hr = floe_world_probe_contact(r->w, i, j, sub, &cr);
    CHECK(hu == hr, "case %d: user contact %d, built-in %d", k, hu, hr);
    if (hu != 1 || hr != 1) return 0;
    near(cu.depth, cr.depth, fmax(cr.depth, 1e-3 * size), "depth", k);
    near3(cu.n, cr.n, 1.0, "normal", k);
    near3(cu.point, cr.point, size, "contact point", k);
    near(cu.gscale, cr.gscale, 1.0, "gscale", k);
    CHECK(cu.nextra == cr.nextra, "case %d: manifold springs %d vs %d", k, cu.nextra, cr.nextra);
    for (int e = 0; e < cu.nextra && e < cr.nextra; e++) {
        near(cu.extra_depth[e], cr.extra_depth[e], fmax(cr.depth, 1e-3 * size), "manifold spring depth", k);
        near3(cu.extra_n[e], cr.extra_n[e], 1.0, "manifold spring normal", k);
        near3(cu.extra_point[e], cr.extra_point[e], size, "manifold spring point", k);
    }
    return 1;
}

/* the first step's contact forces (elastic, frictionless: the law of the contact alone) */
#define F0 10.0 /* N: kn 1e5 N/m x 1e-4 m; ka x 1e-3 size^dim (1e7 N/m^3 x 1e-6 m^3, 2D 1e6 x 1e-5) */
static void compare_forces(twin *u, twin *r, int k) {
    CHECK(floe_world_step(u->w) == 0 && floe_world_step(r->w) == 0, "case %d: step", k);
    const floe_contact_info *cu = NULL, *cr = NULL;
    int nu = floe_world_contacts(u->w, &cu), nr = floe_world_contacts(r->w, &cr);
    CHECK(nu == nr && nu > 0, "case %d: %d contacts (user) vs %d (built-in)", k, nu, nr);
    for (int c = 0; c < nu && c < nr; c++) {
        /* relative to the force, or to the force at a depth of 1e-3 size (F0, both laws) */
        double F = fmax(floe_v3_norm(cr[c].force), F0);
        near3(cu[c].force, cr[c].force, F, "contact force", k);
        near(cu[c].depth, cr[c].depth, fmax(cr[c].depth, 1e-4), "recorded depth", k);
    }
}

/* the extent of g at pose q along the world direction u: max over the shape of u.(X - x) */
static double extent(const floe_geometry *g, const double q[4], const double u[3]) {
    double d[3], X[3], xw[3];
    floe_q_rotate_inv(d, q, u);
    floe_geometry_support(g, d, X);
    floe_q_rotate(xw, q, X);
    return floe_v3_dot(xw, u);
}

/* the partner's centre along u from the shape's (at x, q) such that their support planes
 * normal to u overlap by delta: a shallow contact with a well-defined deepest point (deep
 * ones meet several faces at once, where the normal is any of their subgradients) */
static void place_partner(const floe_geometry *g, const double x[3], const double q[4], const floe_geometry *p,
                          const double qp[4], const double u[3], double delta, double xp[3]) {
    double mu[3] = {-u[0], -u[1], -u[2]};
    double dist = extent(g, q, u) + extent(p, qp, mu) - delta;
    for (int c = 0; c < 3; c++) xp[c] = x[c] + dist * u[c];
}

static void random_dir(int dim, double u[3]) {
    if (dim == 2) {
        double th = uni(0, 2 * M_PI);
        floe_v3_set(u, cos(th), sin(th), 0);
    } else rand_unit(u);
}

static void random_pose(int dim, double q[4]) {
    if (dim == 2) {
        double th = uni(0, 2 * M_PI);
        q[0] = cos(th / 2); q[1] = q[2] = 0; q[3] = sin(th / 2);
    } else rand_quat(q);
}

/* ---- 1. the user polytope against a built-in partner, point law and overlap law ---- */
static void test_polytope(int dim, int partner_kind, int overlap) {
    const double a = 0.05, b = 0.03, h = 0.07, size = 0.1;
    int contacts = 0;
    long lp = 0, admm = 0;
    for (int k = 0; k < 60; k++) {
        double q[4], qp[4], x[3] = {0, 0, 0}, xp[3], u3[3], fx[3], fq[4], id_x[3] = {0, 0, 0}, id_q[4] = {1, 0, 0, 0};
        random_pose(dim, q);
        random_pose(dim, qp);
        random_dir(dim, u3);
        floe_geometry *pu, *pr;
        if (partner_kind == 0) {
            pu = floe_box_create(0.08, 0.05, 0.06);
            pr = floe_box_create(0.08, 0.05, 0.06);
        } else { /* a built-in polygon / tetrahedron */
            char err[128];
            double xy[8] = {-0.04, -0.03, 0.05, -0.02, 0.03, 0.04, -0.03, 0.03};
            double pl[16] = {1, 1, 1, 0.02, 1, -1, -1, 0.02, -1, 1, -1, 0.02, -1, -1, 1, 0.02};
            pu = dim == 2 ? floe_polygon_create(xy, 4, err, sizeof err) : floe_polyhedron_from_planes(pl, 4, err, sizeof err);
            pr = dim == 2 ? floe_polygon_create(xy, 4, err, sizeof err) : floe_polyhedron_from_planes(pl, 4, err, sizeof err);
        }
        floe_geometry *gu = tri_prism_create(dim, a, b, h);
        /* shallow for the point law, where a deep overlap meets several faces at once; deeper
         * for the overlap law, whose integrals of a sliver are all cancellation */
        place_partner(gu, x, q, pu, qp, u3, overlap ? uni(0.01, 0.03) : uni(0.003, 0.015), xp);
        twin U = make_twin(dim, overlap, gu, id_x, id_q, x, q, pu, xp, qp, 0);
        twin R = make_twin(dim, overlap, builtin_prism(dim, a, b, h, fx, fq), fx, fq, x, q, pr, xp, qp, 0);
        if (!overlap) contacts += compare_contact(&U, &R, 0, 1, 0, size, k);
        else {
            floe_contact cu, cr;
            memset(&cu, 0, sizeof cu);
            memset(&cr, 0, sizeof cr);
            int hu = floe_world_probe_overlap(U.w, 0, 1, 0, &cu), hr = floe_world_probe_overlap(R.w, 0, 1, 0, &cr);
            CHECK(hu == hr && hu >= 0, "case %d: overlap %d (user) vs %d (built-in)", k, hu, hr);
            if (hu == 1 && hr == 1) {
                contacts++;
                /* relative to the value, or to that of an overlap 1e-3 size deep (slivers) */
                const double A0 = 1e-3 * pow(size, dim), I0 = 1e-3 * pow(size, dim + 1);
                near(cu.area, cr.area, fmax(cr.area, A0), "overlap area/volume", k);
                near(cu.area_energy, cr.area_energy, fmax(cr.area_energy, I0), "overlap energy", k);
                near3(cu.area_force, cr.area_force, fmax(floe_v3_norm(cr.area_force), A0), "overlap force", k);
                near3(cu.point, cr.point, size, "overlap point", k);
            }
        }
        floe_contact tmp;
        if (floe_world_probe_contact(R.w, 0, 1, 0, &tmp) == 1) compare_forces(&U, &R, k);
        floe_detect_stats s;
        floe_world_detect_stats(U.w, &s);
        lp += s.lp;
        admm += s.admm;
        floe_world_destroy(U.w);
        floe_world_destroy(R.w);
    }
    printf("  %dD user prism vs built-in %s (%s law): %d contacts compared; user LP evaluations %ld, ADMM %ld\n",
           dim, partner_kind ? "polytope" : "box", overlap ? "overlap-area" : "linear", contacts, lp, admm);
    CHECK(contacts >= 20, "%dD: at least 20 of 60 random placements in contact (got %d)", dim, contacts);
    if (!overlap) CHECK(lp > 0 && admm == 0, "%dD: the user polytope takes the exact LP (LP %ld, ADMM %ld)", dim, lp, admm);
}

/* ---- 1b. the user polytope on a wall: the per-vertex plane contact and its manifold ---- */
static void test_wall(int dim) {
    const double a = 0.05, b = 0.03, h = 0.07;
    int contacts = 0;
    for (int k = 0; k < 20; k++) {
        double q[4], x[3] = {0, 0, 0}, fx[3], fq[4], id_x[3] = {0, 0, 0}, id_q[4] = {1, 0, 0, 0};
        random_pose(dim, q);
        x[dim - 1] = uni(0.0, 0.04);
        twin U = make_twin(dim, 0, tri_prism_create(dim, a, b, h), id_x, id_q, x, q, NULL, NULL, NULL, 1);
        twin R = make_twin(dim, 0, builtin_prism(dim, a, b, h, fx, fq), fx, fq, x, q, NULL, NULL, NULL, 1);
        contacts += compare_contact(&U, &R, 0, U.wall, 0, 0.1, k);
        floe_world_destroy(U.w);
        floe_world_destroy(R.w);
    }
    printf("  %dD user prism on a wall: %d contacts compared\n", dim, contacts);
    CHECK(contacts >= 10, "%dD wall: at least 10 of 20 placements in contact (got %d)", dim, contacts);
}

/* ---- 2. a user union of pieces: one contact per piece pair, as the built-in compound's ---- */
static void test_union(int dim) {
    const double s[3] = {0.04, 0.02, 0.03}, d = 0.03;
    int contacts = 0, pairs_both = 0;
    for (int k = 0; k < 30; k++) {
        double q[4], qp[4], x[3] = {0, 0, 0}, xp[3], u3[3], fx[3], fq[4], id_x[3] = {0, 0, 0}, id_q[4] = {1, 0, 0, 0};
        random_pose(dim, q);
        const int under = k % 2; /* odd: a long box under both pieces, tilted a little */
        double pl[3] = {0.05, 0.03, 0.04}, pw[3] = {0.14, 0.03, 0.1};
        const double *ps = under ? pw : pl;
        if (under) {
            double tilt[3] = {dim == 3 ? uni(-0.03, 0.03) : 0, 0, uni(-0.03, 0.03)}, qt[4], down[3] = {0, -1, 0};
            floe_q_from_rotvec(qt, tilt);
            floe_q_mul(qp, q, qt);
            floe_q_rotate(u3, q, down);
        } else {
            random_pose(dim, qp);
            random_dir(dim, u3);
        }
        floe_geometry *gu = box_pair_create(s, d), *pu = floe_box_create(ps[0], ps[1], ps[2]);
        place_partner(gu, x, q, pu, qp, u3, uni(0.004, 0.01), xp);
        twin U = make_twin(dim, 0, gu, id_x, id_q, x, q, pu, xp, qp, 0);
        twin R = make_twin(dim, 0, builtin_box_pair(dim, s, d, fx, fq), fx, fq, x, q, floe_box_create(ps[0], ps[1], ps[2]),
                           xp, qp, 0);
        floe_particles_view vu, vr;
        floe_world_particles(U.w, &vu);
        floe_world_particles(R.w, &vr);
        CHECK(vu.pieces[0] == 2 && vr.pieces[0] == 2, "case %d: two pieces (user %d, built-in %d)", k, vu.pieces[0],
              vr.pieces[0]);
        int hit = 0;
        for (int piece = 0; piece < 2; piece++) hit += compare_contact(&U, &R, 0, 1, FLOE_SUB(piece, 0), 0.1, k);
        contacts += hit;
        pairs_both += hit == 2;
        floe_contact tmp;
        if (floe_world_probe_contact(R.w, 0, 1, FLOE_SUB(0, 0), &tmp) == 1 ||
            floe_world_probe_contact(R.w, 0, 1, FLOE_SUB(1, 0), &tmp) == 1)
            compare_forces(&U, &R, k);
        floe_world_destroy(U.w);
        floe_world_destroy(R.w);
    }
    printf("  %dD user union of two boxes vs a box: %d piece contacts compared (%d placements with both)\n", dim,
           contacts, pairs_both);
    CHECK(contacts >= 30 && pairs_both >= 10, "%dD union: piece contacts %d (>= 30), both pieces %d (>= 10)", dim,
          contacts, pairs_both);
}

/* ---- 3. `dimension`: a planar shape has no place in a 3D world ---- */
static void test_dimension(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"m", 1000, 1e9, 0.3};
    floe_world_add_material(w, &m);
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, tri_prism_create(2, 0.05, 0.03, 0.07));
    floe_world_add_particle(w, &p);
    int rc = floe_world_prepare(w);
    CHECK(rc == FLOE_EINVAL && strstr(floe_world_last_error(w), "2D shape"),
          "a user shape of dimension 2 is refused in 3D (rc %d: %s)", rc, floe_world_last_error(w));
    floe_world_destroy(w);
}

/* face planes that are not unit normals are refused when the shape is added (the LP reads
 * them as distances: the SDF, and the separation cache's gaps) */
static void test_plane_norms(void) {
    for (int dim = 2; dim <= 3; dim++) {
        floe_world_def d = floe_default_world_def();
        d.dim = dim;
        floe_world *w = floe_world_create(&d, NULL, 0);
        floe_geometry *g = tri_prism_create(dim, 0.05, 0.03, 0.07);
        tri_prism *t = (tri_prism *)g;
        for (int k = 0; k < 4; k++) t->plane[4 * 1 + k] *= 1.5; /* one side: a normal of length 1.5 */
        const int gi = floe_world_add_geometry(w, g);
        CHECK(gi < 0 && strstr(floe_world_last_error(w), "face plane 1") && strstr(floe_world_last_error(w), "unit"),
              "%dD: a user polytope with a face normal of length 1.5 is refused (%d: %s)", dim, gi,
              floe_world_last_error(w));
        if (gi < 0) floe_geometry_destroy(g); /* not taken */
        floe_world_destroy(w);
    }
}

int main(void) {
    test_plane_norms();
    for (int dim = 2; dim <= 3; dim++) {
        test_polytope(dim, 0, 0);
        test_polytope(dim, 1, 0);
        test_polytope(dim, 0, 1);
        test_polytope(dim, 1, 1);
        test_wall(dim);
        test_union(dim);
    }
    test_dimension();
    printf("  largest relative difference user vs built-in: %.3g (tolerance %.0e)\n", worst_rel, TOL);
    return check_summary("test_user_polytope");
}
