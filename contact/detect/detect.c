/* detect.c - contact detection, producing the contact summary of ParticLS eq 15.
 *
 * Dispatch is a table over geometry kinds (Box2D style), applied to convex pieces (a
 * body whose class gives piece_count/piece, such as a compound, contributes one piece per
 * list entry, so non-convex bodies get one contact per piece pair). Within a kind, the paths
 * follow what the class gives, never which class it is (floe_geometry.h, capabilities):
 *   sphere-sphere, sphere-plane, sphere-anything (the other shape's SDF and gradient at
 *   the sphere centre: exact for exact SDFs; spheres never enter ADMM);
 *   polytope-plane (the deepest vertex and a manifold of the next ones), convex-plane (support
 *   point: the shape's `support` or iterated projection);
 *   polytope-polytope (any two shapes whose classes give `polytope`: boxes, polyhedra,
 *   polygons, a user's polytope): the exact deepest-point LP (contact/detect/polytope_lp.c),
 *   warm-started from the previous basis;
 *   any other convex pair: ADMM on the two SDFs (contact/detect/admm.c), warm-started.
 * Warm-start state lives in the neighbour list (FLOE_DETECT_WARM doubles per entry) and is
 * allocated only when a scene has such pairs. */
#include "floe_detect.h"
#include "floe_admm.h"
#include "floe_polytope_lp.h"
#include "floe_overlap.h"
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct shape_ref {
    const floe_geometry *g;
    double x[3], q[4];
    double r;   /* bounding radius (a sphere's current radius) */
    int kind;
} shape_ref;

static void make_ref(const floe_body_ref *body, int piece, shape_ref *s);

typedef int (*pair_fn)(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c);

static void finish(floe_contact *c) {
    for (int k = 0; k < 3; k++) c->point[k] = 0.5 * (c->x1[k] + c->x2[k]);
}

/* contact point = the deepest point x itself: with d = max over x in A of -phi_B(x), the
 * envelope theorem makes the force k(d) along B's normal at x, applied at x, the gradient
 * of the stored energy; at the midpoint of the two halves' points the lever arm is off by
 * half the depth along the normal and a spinning pair gains energy */
static void finish_at(floe_contact *c, const double x[3]) { floe_v3_copy(c->point, x); }

static void to_body(const shape_ref *s, const double x[3], double X[3]) {
    double d[3];
    floe_v3_sub(d, x, s->x);
    floe_q_rotate_inv(X, s->q, d);
}

static int sphere_sphere(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    (void)w; (void)warm;
    double d[3];
    floe_v3_sub(d, b->x, a->x);
    double dist2 = floe_v3_dot(d, d), rs = a->r + b->r;
    if (dist2 >= rs * rs) return 0;
    double dist = sqrt(dist2);
    if (dist > 0) floe_v3_set(c->n, d[0] / dist, d[1] / dist, d[2] / dist);
    else floe_v3_set(c->n, 1, 0, 0); /* coincident centres: any direction, finite */
    c->depth = rs - dist;
    for (int k = 0; k < 3; k++) {
        c->x1[k] = a->x[k] + a->r * c->n[k];
        c->x2[k] = b->x[k] - b->r * c->n[k];
    }
    c->r_eff = a->r * b->r / rs;
    finish(c);
    return 1;
}

/* the rotation matrix of a unit quaternion (body -> world) */
static void q_matrix(double R[3][3], const double q[4]) {
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    R[0][0] = 1 - 2 * (y * y + z * z); R[0][1] = 2 * (x * y - z * w); R[0][2] = 2 * (x * z + y * w);
    R[1][0] = 2 * (x * y + z * w); R[1][1] = 1 - 2 * (x * x + z * z); R[1][2] = 2 * (y * z - x * w);
    R[2][0] = 2 * (x * z - y * w); R[2][1] = 2 * (y * z + x * w); R[2][2] = 1 - 2 * (x * x + y * y);
}

/* the map from a's body frame to b's, Xb = M Xa + m (one matrix per pair half instead of
 * two quaternion rotations per plane or corner) */
typedef struct rel_map { double M[3][3], m[3]; } rel_map;

static void rel_make(rel_map *f, const shape_ref *a, const shape_ref *b, double Ra[3][3]) {
    double Rb[3][3], d[3];
    q_matrix(Ra, a->q);
    q_matrix(Rb, b->q);
    floe_v3_sub(d, a->x, b->x);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) f->M[i][j] = Rb[0][i] * Ra[0][j] + Rb[1][i] * Ra[1][j] + Rb[2][i] * Ra[2][j];
        f->m[i] = Rb[0][i] * d[0] + Rb[1][i] * d[1] + Rb[2][i] * d[2];
    }
}

/* the map back, from b's frame to a's (f from rel_make(f, a, b, Ra)): M^T and Ra^T (xb - xa),
 * the same operations as rel_make(g, b, a) (the products commute, the sums keep their
 * order, xb - xa is -(xa - xb) exactly): the same bits without the two rotation matrices */
static void rel_back(rel_map *g, const rel_map *f, const double Ra[3][3], const shape_ref *a, const shape_ref *b) {
    double d[3];
    floe_v3_sub(d, b->x, a->x);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) g->M[i][j] = f->M[j][i];
        g->m[i] = Ra[0][i] * d[0] + Ra[1][i] * d[1] + Ra[2][i] * d[2];
    }
}

static void rel_apply(const rel_map *f, const double X[3], double Y[3]) {
    for (int i = 0; i < 3; i++) Y[i] = f->M[i][0] * X[0] + f->M[i][1] * X[1] + f->M[i][2] * X[2] + f->m[i];
}

static void plane_normal(const shape_ref *s, double nw[3]) {
    const double ez[3] = {0, 0, 1};
    floe_q_rotate(nw, s->q, ez);
}

static int sphere_plane(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    (void)w; (void)warm;
    return floe_sphere_plane_contact(a->x, a->r, b->x, b->q, c);
}

/* sphere a against any shape b with an SDF: distance of the sphere centre. The SDF never
 * overestimates the distance (|grad| <= 1, docs/models.md), so phi >= r means apart; below,
 * the true distance and unit normal (floe_geometry_distance: measured by projection for a
 * shape that only gives an SDF, whose value outside may be a bound) */
static int sphere_sdf(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    (void)w; (void)warm;
    double X[3], g[3], gw[3];
    to_body(b, a->x, X);
    double phi = floe_geometry_sdf(b->g, X);
    if (phi >= a->r) return 0;
    phi = floe_geometry_distance(b->g, X, g);
    if (phi >= a->r) return 0;
    floe_q_rotate(gw, b->q, g);
    floe_v3_set(c->n, -gw[0], -gw[1], -gw[2]);
    c->depth = a->r - phi;
    for (int k = 0; k < 3; k++) {
        c->x1[k] = a->x[k] - a->r * gw[k];
        c->x2[k] = a->x[k] - phi * gw[k];
    }
    c->r_eff = a->r;
    finish(c);
    return 1;
}

/* polytope a (vertices known) against plane b: the penetrating vertices lumped into one
 * contact with depth = sum of the vertex depths, at their depth-weighted mean. For a linear
 * law this is exactly the resultant of one spring per penetrating vertex (force k sum d_v,
 * moment sum d_v x_v), so the contact is conservative and a face resting on the plane gets
 * a central point and rests without rocking. For Hertz it is an approximation (a flat face
 * has no Hertz radius; R* = the bounding radius). */
/* the contact manifold's vertices (detect.c manifold): the K deepest, deepest first */
typedef struct mf_vertex { double d, x[3], n[3]; } mf_vertex;

static void mf_insert(mf_vertex *best, int *nb, int cap, const mf_vertex *v) {
    int k;
    if (*nb < cap) k = (*nb)++;
    else if (v->d > best[cap - 1].d) k = cap - 1;
    else return;
    while (k > 0 && best[k - 1].d < v->d) { best[k] = best[k - 1]; k--; }
    best[k] = *v;
}

/* the 2nd .. nb-th of them as the contact's extra springs (the deepest is the contact point) */
static void mf_set_extras(floe_contact *c, const mf_vertex *best, int nb) {
    c->nextra = 0;
    for (int k = 1; k < nb; k++) {
        int e = c->nextra++;
        c->extra_depth[e] = best[k].d;
        floe_v3_copy(c->extra_point[e], best[k].x);
        floe_v3_copy(c->extra_n[e], best[k].n);
    }
}


/* polytope a against plane b: the contact manifold of the vertices below the plane (as for
 * polytope pairs, detect.c manifold): the deepest vertex is the contact point, the 2nd ..
 * K-th deepest (K = 2 in 2D, 4 in 3D) carry elastic springs of the same law, so the stored
 * energy is the sum of the law's energy over those vertices and the force its gradient */
static int vertices_plane(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    (void)warm;
    int nv = 0;
    const double *V;
    floe_polytope_view pv; /* a polytope's corners for this dimension (2D: its z = 0 section) */
    if (floe_geometry_polytope(a->g, w->dim, &pv)) {
        V = pv.v;
        nv = pv.nv;
    } else V = a->g->klass->vertices(a->g, &nv);
    double nw[3], rel[3], nb_[3];
    plane_normal(b, nw);
    floe_v3_sub(rel, a->x, b->x);
    const double h0 = floe_v3_dot(rel, nw); /* the centre's height above the plane */
    if (h0 >= a->r) return 0;
    /* a corner's height h0 + (R X).n = h0 + X.(R^T n): the wall's normal in a's frame once,
     * the world corner only for those below */
    floe_q_rotate_inv(nb_, a->q, nw);
    const int K = w->dim == 2 ? 2 : 4;
    mf_vertex best[4];
    int nb = 0, below[64];
    /* the corners below, a chunk at a time without a branch per corner (which are below is
     * data: a branch per corner was mispredicted), then each of them in order */
    for (int v0 = 0; v0 < nv; v0 += 64) {
        const int v1 = v0 + 64 < nv ? v0 + 64 : nv;
        int n = 0;
        for (int v = v0; v < v1; v++) {
            const double *X = V + 3 * v;
            below[n] = v;
            n += h0 + (X[0] * nb_[0] + X[1] * nb_[1] + X[2] * nb_[2]) < 0;
        }
        for (int q = 0; q < n; q++) {
            double xw[3];
            floe_q_rotate(xw, a->q, V + 3 * below[q]);
            floe_v3_add(xw, xw, a->x);
            floe_v3_sub(rel, xw, b->x);
            const double s = floe_v3_dot(rel, nw);
            if (s < 0) {
                mf_vertex m = {-s, {xw[0], xw[1], xw[2]}, {-nw[0], -nw[1], -nw[2]}};
                mf_insert(best, &nb, K, &m);
            }
        }
    }
    if (nb == 0) return 0;
    floe_v3_set(c->n, -nw[0], -nw[1], -nw[2]);
    c->depth = best[0].d;
    for (int k = 0; k < 3; k++) {
        c->x1[k] = best[0].x[k];
        c->x2[k] = best[0].x[k] + c->depth * nw[k];
    }
    c->r_eff = a->r;
    finish_at(c, c->x1); /* the force acts at the vertex: the gradient of its energy */
    mf_set_extras(c, best, nb);
    return 1;
}

/* convex shape a against plane b: a polytope's corners (vertices_plane), else the support
 * point in direction -n (the shape's own `support`, or floe_geometry_support's climb along
 * the zero level set, which needs only the SDF, exact or a bound: test_sdf_bound). */
static int convex_plane(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    (void)w; (void)warm;
    const floe_geometry *g = a->g;
    if (g->klass->polytope || g->klass->vertices) return vertices_plane(w, a, b, warm, c);
    double nw[3], nb[3], X[3] = {0, 0, 0}, rel[3];
    plane_normal(b, nw);
    floe_v3_sub(rel, a->x, b->x);
    double R = a->r;
    if (floe_v3_dot(rel, nw) >= R) return 0;
    floe_q_rotate_inv(nb, a->q, nw);
    double d[3] = {-nb[0], -nb[1], -nb[2]};
    floe_geometry_support(g, d, X);
    double xw[3];
    floe_q_rotate(xw, a->q, X);
    floe_v3_add(xw, xw, a->x);
    floe_v3_sub(rel, xw, b->x);
    double s = floe_v3_dot(rel, nw);
    if (s >= 0) return 0;
    floe_v3_set(c->n, -nw[0], -nw[1], -nw[2]);
    c->depth = -s;
    floe_v3_copy(c->x1, xw);
    for (int k = 0; k < 3; k++) c->x2[k] = xw[k] - s * nw[k];
    c->r_eff = R;
    finish_at(c, c->x1); /* the force acts at the support point (it is the gradient of the
                            stored energy, d = -min n.x over the shape) */
    return 1;
}

/* ---- polytope-polytope: exact LP ---- */

/* a convex polytope: its class gives its planes and corners (floe_geometry_class.polytope) */
static int is_polytope(const floe_geometry *g) { return g->klass->polytope != NULL; }

/* planes and vertices of b expressed in a's body frame (scratch owned by the world) */
static int lp_scratch(floe_detect_ctx *w, int need) {
    if (w->det->scratch_cap >= need) return FLOE_OK;
    double *s = realloc(w->det->scratch, (size_t)need * sizeof(double));
    if (!s) return FLOE_ENOMEM;
    w->det->scratch = s;
    w->det->scratch_cap = need;
    return FLOE_OK;
}

/* one half: a's point deepest in b, in world coordinates (f: the map from a's frame to b's),
 * and b's outward normal there in a's frame (the caller turns the deeper half's alone) */
static int lp_half(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, const floe_polytope_view *pva,
                   const floe_polytope_view *pvb, const rel_map *f, double *warm4, double x[3], double *s, double n[3],
                   double *gnorm, int *pivots, int *face) {
    const floe_polytope_view A = *pva, B = *pvb; /* a's and b's planes and corners */
    const double *pa = A.plane, *pb = B.plane, *va = A.v;
    const int na = A.np, nb = B.np, nva = A.nv;
    if (lp_scratch(w, 4 * nb)) return FLOE_ENOMEM;
    double *tb = w->det->scratch;
    /* b's planes in a's frame (n_a = M^T n_b, d_a = d_b - n_b . m with Xb = M Xa + m): the LP
     * maps them into tb when it needs them all (a warm basis that stays optimal in 3D reads
     * its own rows only) */
    floe_lp_problem P = {.dim = w->dim, .a = pa, .na = na, .nb = nb, .va = va, .nva = nva,
                         .scale = a->r < b->r ? a->r : b->r, .b_body = pb, .map = &f->M[0][0], .b_buf = tb,
                         .a_soa = A.plane_soa, .na_soa = A.np_soa, .b_soa = B.plane_soa, .nb_soa = B.np_soa};
    int basis[4];
    const int have = warm4 && isfinite(warm4[0]);
    for (int k = 0; k < 4; k++) basis[k] = have && isfinite(warm4[k]) ? (int)warm4[k] : -1;
    floe_lp_result r;
    int rc = floe_lp_deepest(&P, basis, &r);
    w->det->lp_halves++;
    w->det->lp_kept += r.warm && r.pivots == 0;
    w->det->lp_cold += !r.warm;
    if (rc) {
        if (warm4) warm4[0] = NAN;
        return rc;
    }
    if (warm4)
        for (int k = 0; k < 4; k++) warm4[k] = k <= w->dim ? basis[k] : NAN;
    floe_q_rotate(x, a->q, r.x);
    floe_v3_add(x, x, a->x);
    floe_v3_copy(n, r.normal); /* outward normal of b at x, in a's frame */
    *s = r.s;
    *gnorm = r.gnorm;
    *pivots = r.pivots + 1;
    /* b's face of the largest multiplier: the face a presses on */
    *face = 0;
    double lb = -INFINITY;
    for (int k = 0; k <= w->dim; k++)
        if (basis[k] >= na && r.lambda[k] > lb) { lb = r.lambda[k]; *face = basis[k] - na; }
    return FLOE_OK;
}

/* ---- overlap integrals (the overlap-area law, contact/detect/overlap.c): world-frame inputs ---- */
#define OV_MAX FLOE_OVERLAP_MAX

/* 2D: a body's corners (its z = 0 section) and lines n.x <= h, relative to the point o (the
 * first body's centre: local coordinates keep the overlap's digits when floes sit hundreds
 * of km from the origin), corners counter-clockwise. A body in the plane turns about z only:
 * its rotation is (c, -s; s, c) with c, s from the quaternion. */
static void ov_rot2(const shape_ref *s, double *c, double *sn) {
    const double *q = s->q; /* (w, x, y, z) */
    *c = 1 - 2 * (q[2] * q[2] + q[3] * q[3]);
    *sn = 2 * (q[0] * q[3] + q[1] * q[2]);
}

static int ov_polygon(const shape_ref *s, const double o[2], double (*P)[2]) {
    floe_polytope_view pv;
    floe_geometry_polytope(s->g, 2, &pv);
    const double *V = pv.v;
    const int k = pv.nv < OV_MAX ? pv.nv : OV_MAX;
    double c, sn, tx = s->x[0] - o[0], ty = s->x[1] - o[1], cx = 0, cy = 0;
    ov_rot2(s, &c, &sn);
    for (int v = 0; v < k; v++) {
        P[v][0] = c * V[3 * v] - sn * V[3 * v + 1] + tx;
        P[v][1] = sn * V[3 * v] + c * V[3 * v + 1] + ty;
        cx += P[v][0];
        cy += P[v][1];
    }
    /* polygons keep their corners in order (counter-clockwise: every turn to the left; the
     * class says so, or each turn is looked at); other sections are sorted about the centre */
    int ordered = 1;
    if (pv.ccw) return k;
    for (int a = 0; a < k && ordered; a++) {
        const double *p0 = P[a], *p1 = P[(a + 1) % k], *p2 = P[(a + 2) % k];
        ordered = (p1[0] - p0[0]) * (p2[1] - p1[1]) - (p1[1] - p0[1]) * (p2[0] - p1[0]) > 0;
    }
    if (ordered) return k;
    double ang[OV_MAX];
    cx /= k; cy /= k;
    for (int a = 0; a < k; a++) ang[a] = atan2(P[a][1] - cy, P[a][0] - cx);
    for (int a = 1; a < k; a++) /* counter-clockwise */
        for (int b = a; b > 0 && ang[b] < ang[b - 1]; b--) {
            double t = ang[b], px = P[b][0], py = P[b][1];
            ang[b] = ang[b - 1]; P[b][0] = P[b - 1][0]; P[b][1] = P[b - 1][1];
            ang[b - 1] = t; P[b - 1][0] = px; P[b - 1][1] = py;
        }
    return k;
}

/* line k of a body (its face k), relative to o */
static void ov_line1(const shape_ref *s, const double o[2], const double *pl, double L[3]) {
    double c, sn;
    ov_rot2(s, &c, &sn);
    const double nx = c * pl[0] - sn * pl[1], ny = sn * pl[0] + c * pl[1];
    L[0] = nx;
    L[1] = ny;
    L[2] = pl[3] + nx * (s->x[0] - o[0]) + ny * (s->x[1] - o[1]);
}

static int ov_lines(const shape_ref *s, const double o[2], double (*Lh)[3]) {
    floe_polytope_view pv;
    floe_geometry_polytope(s->g, 2, &pv);
    const int np = pv.np < OV_MAX ? pv.np : OV_MAX;
    for (int k = 0; k < np; k++) ov_line1(s, o, pv.plane + 4 * k, Lh[k]);
    return np;
}

/* world-frame planes (n, h) and corners of a polytope */
static int ov_planes3(const shape_ref *s, double *pl, double *V, int *nv) {
    floe_polytope_view pv;
    floe_geometry_polytope(s->g, 3, &pv);
    const double *bp = pv.plane, *bv = pv.v;
    const int np = pv.np, n = pv.nv;
    if (np > FLOE_POLY3_FACES || n > 4 * FLOE_POLY3_FACES * FLOE_POLY3_CORNERS) return -1;
    for (int k = 0; k < np; k++) {
        floe_q_rotate(pl + 4 * k, s->q, bp + 4 * k);
        pl[4 * k + 3] = bp[4 * k + 3] + floe_v3_dot(pl + 4 * k, s->x);
    }
    for (int v = 0; v < n; v++) {
        floe_q_rotate(V + 3 * v, s->q, bv + 3 * v);
        floe_v3_add(V + 3 * v, V + 3 * v, s->x);
    }
    *nv = n;
    return np;
}

static int overlap3(const shape_ref *a, const shape_ref *b, double F[3], double M[3], double *meas, double *I,
                    double cen[3], double *patch) {
    enum { NV = 4 * FLOE_POLY3_FACES * FLOE_POLY3_CORNERS };
    double pa[4 * FLOE_POLY3_FACES], pb[4 * FLOE_POLY3_FACES];
    double *Va = malloc(sizeof(double) * 3 * NV * 2);
    floe_poly3 *X = malloc(sizeof *X * 2);
    if (!Va || !X) { free(Va); free(X); return -FLOE_ENOMEM; }
    double *Vb = Va + 3 * NV;
    int nva = 0, nvb = 0, npa = ov_planes3(a, pa, Va, &nva), npb = ov_planes3(b, pb, Vb, &nvb);
    double tol = 1e-9 * fmin(a->r, b->r);
    int rc = FLOE_OK;
    if (npa < 0 || npb < 0 || floe_poly3_from_planes(pa, npa, Va, nva, tol, &X[0]) ||
        floe_poly3_from_planes(pb, npb, Vb, nvb, tol, &X[1]))
        rc = -FLOE_ENOTSUP;
    else {
        double f1[3], f2[3], m1[3], m2[3], v1, v2, c1[3], c2[3], s1, s2;
        double I1 = floe_overlap_term3(&X[0], pb, npb, tol, f1, m1, &v1, c1, &s1);
        double I2 = floe_overlap_term3(&X[1], pa, npa, tol, f2, m2, &v2, c2, &s2);
        for (int k = 0; k < 3; k++) {
            F[k] = 0.5 * (f1[k] - f2[k]);
            M[k] = 0.5 * (m1[k] - m2[k]);
        }
        *meas = 0.5 * (v1 + v2);
        *I = 0.5 * (I1 + I2);
        floe_v3_copy(cen, c1);
        *patch = 0.5 * (s1 + s2);
    }
    free(Va);
    free(X);
    return rc;
}

int floe_detect_overlap(const floe_detect_ctx *w, const floe_body_ref *bi, const floe_body_ref *bj, int sub,
                        double *warm, floe_contact *c) {
    shape_ref a, b;
    make_ref(bi, FLOE_SUB_A(sub), &a);
    make_ref(bj, FLOE_SUB_B(sub), &b);
    if (!is_polytope(a.g) || !is_polytope(b.g)) return -FLOE_ENOTSUP;
    c->nextra = 0; /* the overlap law has its own patch */
    double F[3] = {0, 0, 0}, M[3] = {0, 0, 0}, cen[3], meas, I, l2, org[3] = {0, 0, 0};
    if (w->dim == 2) {
        const double o[2] = {a.x[0], a.x[1]};
        floe_overlap2 ov;
        memset(&ov, 0, sizeof ov);
        w->det->calls++;
        /* a line that kept them apart last time (warm[0]: its number, k + 1 for A's face k,
         * np_A + k + 1 for B's; 0 none, NaN after the bounding circles parted) is tried first,
         * with only that line and the other body's corners: most neighbours in a packed
         * field touch along an edge and stay so */
        const double tol = 1e-10 * (a.r + b.r);
        const int axis = warm && warm[0] >= 1 ? (int)warm[0] : 0;
        int apart = 0;
        if (axis) {
            floe_polytope_view va, vb;
            floe_geometry_polytope(a.g, 2, &va);
            floe_geometry_polytope(b.g, 2, &vb);
            double P[OV_MAX][2], L[3];
            if (axis <= va.np && axis <= OV_MAX) {
                ov_line1(&a, o, va.plane + 4 * (axis - 1), L);
                apart = floe_overlap_pen2(P, ov_polygon(&b, o, P), L) <= tol;
            } else if (axis - va.np <= vb.np && axis - va.np <= OV_MAX) {
                ov_line1(&b, o, vb.plane + 4 * (axis - va.np - 1), L);
                apart = floe_overlap_pen2(P, ov_polygon(&a, o, P), L) <= tol;
            }
        }
        if (apart)
            w->det->separated++;
        else {
            double PA[OV_MAX][2], PB[OV_MAX][2], LA[OV_MAX][3], LB[OV_MAX][3];
            const int na = ov_polygon(&a, o, PA), nb = ov_polygon(&b, o, PB);
            const int la = ov_lines(&a, o, LA), lb = ov_lines(&b, o, LB);
            int r = floe_overlap_pair2(PA, na, LA, la, PB, nb, LB, lb, &ov);
            if (r < 0) return -FLOE_ENOTSUP;
            if (warm) warm[0] = r ? 0 : floe_overlap_axis2(PA, na, LA, la, PB, nb, LB, lb, tol);
        }
        /* moments and points about o from here on */
        F[0] = ov.f[0];
        F[1] = ov.f[1];
        M[2] = ov.m;
        meas = ov.area;
        I = ov.I;
        cen[0] = ov.cen[0]; /* (0, 0) when apart: then F = 0 and cen is not read */
        cen[1] = ov.cen[1];
        cen[2] = 0.5 * (a.x[2] + b.x[2]);
        org[0] = o[0];
        org[1] = o[1];
        l2 = I > 0 ? meas * meas / (2 * I) : 0; /* contact length A^2 / 2I (flat: exact) */
        l2 *= l2;
    } else {
        double patch;
        int rc = overlap3(&a, &b, F, M, &meas, &I, cen, &patch);
        if (rc) return rc;
        l2 = patch; /* the mean area of each body's boundary inside the other (flat: the patch) */
    }
    double F2 = floe_v3_dot(F, F);
    floe_v3_copy(c->area_force, F);
    c->area = meas;
    c->area_energy = I;
    c->area_l2 = l2;
    floe_v3_set(c->area_couple, 0, 0, 0);
    if (!(F2 > 0)) return 0; /* touching, no overlap */
    /* the central axis of the wrench: p = F x M / |F|^2 (then M = p x F + the couple along F),
     * moved along F to the point nearest the overlap's centroid */
    double p[3], u[3], fl = sqrt(F2);
    floe_v3_cross(p, F, M);
    floe_v3_scale(p, 1.0 / F2);
    for (int k = 0; k < 3; k++) u[k] = F[k] / fl;
    double mpar = floe_v3_dot(M, u), d[3];
    for (int k = 0; k < 3; k++) c->area_couple[k] = mpar * u[k];
    floe_v3_sub(d, cen, p);
    double s = floe_v3_dot(d, u);
    for (int k = 0; k < 3; k++) c->point[k] = p[k] + s * u[k] + org[k];
    if (w->dim == 2) c->point[2] = cen[2];
    floe_v3_set(c->n, -u[0], -u[1], -u[2]); /* from i to j: the force on i pushes it back */
    c->gscale = 1.0;
    if (w->dim == 2) { /* polygons: no point detection ran, the rest of the summary from the overlap */
        c->i = bi->id;
        c->j = bj->id;
        c->depth = 2 * I / meas; /* the mean depth (a flat overlap: its depth) */
        floe_v3_copy(c->x1, c->point);
        floe_v3_copy(c->x2, c->point);
        c->r_eff = a.r * b.r / (a.r + b.r);
    }
    return 1;
}

static void count_iterations(floe_detect_ctx *w, int it) {
    w->det->calls++;
    w->det->iterations += it;
    w->det->hist[it < FLOE_DETECT_HIST - 1 ? it : FLOE_DETECT_HIST - 1]++;
}

/* corner X of a (a's frame) against b: 1 when it is inside (its depth, the least face
 * distance, positive, ties to the lowest face, and within b's bounding sphere), its depth
 * and that face in *d, *f. Without a branch (which corners are in is data: a branch per
 * corner or per face was mispredicted) */
static inline int mf_corner_in(const floe_detect_ctx *w, const rel_map *map, const double *X, const double *P, int np,
                               double rb2, double *d, int *f) {
    double Xb[3];
    rel_apply(map, X, Xb);
    const int inside_r = floe_v3_dot(Xb, Xb) < rb2;
    if (w->dim == 2) Xb[2] = 0;
    double dd = INFINITY;
    int ff = -1;
    for (int k = 0; k < np; k++) {
        const double s = P[4 * k + 3] - floe_v3_dot(P + 4 * k, Xb);
        const int take = s < dd;
        dd = take ? s : dd;
        ff = take ? k : ff;
    }
    *d = dd;
    *f = ff;
    return inside_r & (dd > 0) & (ff >= 0);
}

/* corner X of a inside b at depth d on b's face pl, into the manifold's candidates */
static inline void mf_place(const shape_ref *a, const shape_ref *b, const double *X, const double *pl, double d,
                            double sign, mf_vertex *best, int *nb, int cap) {
    double xw[3]; /* the corner in the world */
    floe_q_rotate(xw, a->q, X);
    floe_v3_add(xw, xw, a->x);
    mf_vertex m;
    m.d = d;
    floe_v3_copy(m.x, xw);
    floe_q_rotate(m.n, b->q, pl);
    floe_v3_scale(m.n, -sign);
    mf_insert(best, nb, cap, &m);
}

/* the vertices of a inside b, sign: +1 when a is particle i (the normal from i to j is then
 * minus b's outward face normal), -1 when a is j */
static void mf_vertices(const floe_detect_ctx *w, const shape_ref *a, const shape_ref *b,
                        const floe_polytope_view *pva, const floe_polytope_view *pvb, const rel_map *mp, double sign,
                        int first, mf_vertex *best, int *nb, int cap) {
    const floe_polytope_view pa = *pva, pb = *pvb; /* a's corners (2D: its z = 0 section), b's planes */
    const double *V = pa.v, *P = pb.plane;
    const int nv = pa.nv, np = pb.np;
    if (!V || !P) return;
    /* a's corners in b's frame by one matrix (rel_map); a corner outside one face of b is
     * out (its depth, the least face distance, is then <= 0) */
    const rel_map map = *mp;
    const double rb2 = b->r * b->r;
    /* 3D: the face `first` in a's frame, n.Xb <= d as na.V <= ca: a corner clearly outside it
     * (by more than round-off, eps) is out without its map into b's frame; the others take
     * the exact test below, so the corners kept are the same. A resting contact keeps a few
     * corners of the dozens: the map of each was a fifth of a settled bed's step */
    const int cull = w->dim == 3 && first >= 0 && first < np;
    double na[3] = {0, 0, 0}, ca = 0;
    if (cull) {
        const double *pf = P + 4 * first;
        for (int i = 0; i < 3; i++) na[i] = map.M[0][i] * pf[0] + map.M[1][i] * pf[1] + map.M[2][i] * pf[2];
        ca = pf[3] - (pf[0] * map.m[0] + pf[1] * map.m[1] + pf[2] * map.m[2]);
    }
    const double eps = 1e-9 * (a->r + b->r);
    /* the corners not culled, in order, a chunk at a time (the test without a branch: which
     * corners pass is data, a branch per corner was mispredicted) */
    int keep[64];
    for (int v0 = 0; v0 < nv; v0 += 64) {
        const int v1 = v0 + 64 < nv ? v0 + 64 : nv;
        int nk = 0;
        if (cull)
            for (int v = v0; v < v1; v++) {
                const double *X = V + 3 * v;
                keep[nk] = v;
                nk += !(ca - (na[0] * X[0] + na[1] * X[1] + na[2] * X[2]) < -eps);
            }
        else
            for (int v = v0; v < v1; v++) keep[nk++] = v;
        /* each corner kept: its depth, the least face distance, and that face (ties to the
         * lowest), over every face; it is in when that depth is positive and it lies in b's
         * bounding sphere. Without a branch (which corners are in is data: a branch per
         * corner or per face was mispredicted); the few in are then placed in the world */
        int in[64], fin[64];
        double din[64];
        int ni = 0;
        for (int q0 = 0; q0 < nk; q0++) {
            const int v = keep[q0];
            in[ni] = v;
            ni += mf_corner_in(w, &map, V + 3 * v, P, np, rb2, &din[ni], &fin[ni]);
        }
        for (int q = 0; q < ni; q++) mf_place(a, b, V + 3 * in[q], P + 4 * fin[q], din[q], sign, best, nb, cap);
    }
}

/* the same for the corners idx[0 .. n) of a only (ascending: the order above), when the
 * pair's corner cache says the others are out (manifold) */
static void mf_vertices_of(const floe_detect_ctx *w, const shape_ref *a, const shape_ref *b,
                           const floe_polytope_view *pva, const floe_polytope_view *pvb, const rel_map *mp, double sign,
                           const int *idx, int n, mf_vertex *best, int *nb, int cap) {
    const double *V = pva->v, *P = pvb->plane;
    const double rb2 = b->r * b->r;
    for (int q = 0; q < n; q++) {
        double d;
        int f;
        if (mf_corner_in(w, mp, V + 3 * idx[q], P, pvb->np, rb2, &d, &f))
            mf_place(a, b, V + 3 * idx[q], P + 4 * f, d, sign, best, nb, cap);
    }
}

/* The corner cache of a resting polytope pair (3D): the corners of a that may be inside b
 * until the pair has moved by more than *M: every corner whose distance from b is below
 * delta (by a lower bound: its largest face violation over that face's normal's length; a
 * corner inside counts as distance 0), into idx (ascending, at most cap), *M the least such
 * bound of the others (INFINITY: none). A corner further than M from b stays outside while
 * the two bodies' points have moved less than M in all (the separation cache's argument,
 * forces.c sep_update), so the corners in idx are the only ones the manifold needs. -1 when
 * more than cap corners are that near (or b has more than 256 faces). */
static int mf_near(const floe_polytope_view *pva, const floe_polytope_view *pvb, const rel_map *mp, double delta, int *idx,
                   int cap, double *M) {
    const double *V = pva->v, *P = pvb->plane;
    const int nv = pva->nv, np = pvb->np;
    int n = 0;
    double lo = INFINITY;
    if (!V || !P || np <= 0 || np > 256) return -1;
    double inv[256]; /* each face normal's 1 / length (0 for a zero normal) */
    for (int k = 0; k < np; k++) {
        const double nn = sqrt(floe_v3_dot(P + 4 * k, P + 4 * k));
        inv[k] = nn > 0 ? 1.0 / nn : 0.0;
    }
    for (int v = 0; v < nv; v++) {
        double Xb[3];
        rel_apply(mp, V + 3 * v, Xb);
        double g = 0.0; /* the distance's lower bound */
        for (int k = 0; k < np; k++) {
            const double viol = (floe_v3_dot(P + 4 * k, Xb) - P[4 * k + 3]) * inv[k];
            if (viol > g) g = viol;
        }
        if (g < delta) {
            if (n == cap) return -1;
            idx[n++] = v;
        } else if (g < lo)
            lo = g;
    }
    *M = lo;
    return n;
}

/* The contact manifold of a polytope pair (docs/models.md, "Contact manifold"). The stored
 * energy of a point law on two polytopes is
 *     E = e(d) + sum over the K deepest vertices v of e(d_v) - e(max_v d_v),
 * d the deepest-point depth (the LP), d_v = -phi_other(v) for each vertex of either body
 * inside the other, e the law's elastic energy, K = 2 (2D) or 4 (3D). Every term is
 * continuous (a vertex enters at d_v = 0; the sum of the K largest is continuous), and
 * where the deepest point is a vertex the kinks of d and of max_v d_v cancel: two faces
 * passing through parallel no longer move the force from one end of the patch to the
 * other, and a flat face rests on two (2D) or up to four (3D) springs. The gradient of
 * e(d_v) is the law's force at v along the nearest face's normal (exact: the vertex moves
 * with its body, the face with the other). This finds the 2nd .. K-th deepest vertices. */
/* The corner cache (3D, a pair with a warm slot and the separation cache): mf_near's corners
 * of both bodies in the pair's warm slot, from MF_SLOT on: the pair's motion bound when they
 * were found (m0, also in the separation cache's slot, whose gap is then MF_MARK: a slot
 * reset by a new list, an RK2 restore of one of the two or a pair found apart never
 * matches), the margin M, the two counts, then the indices, 4 of 13 bits in each double. While
 * the pair has moved less than M since (the separation cache's test) the manifold tests only
 * those corners: the same corners are inside, found in the same order, so the same bits. */
#define MF_SLOT 9
#define MF_MARK (-1.0)
#define MF_CAP 16          /* corners kept, both bodies */
#define MF_NEAR 2e-3       /* corners nearer than this x (r_a + r_b) are kept */

static int mf_cache_holds(const floe_detect_ctx *w, const double *warm) {
    const double *sc = w->sep, *m = warm + MF_SLOT;
    return sc && sc[0] == MF_MARK && m[0] == sc[1] && w->motion - m[0] + 1e-9 * w->motion < m[1];
}

static void mf_cache_get(const double *warm, int *idx, int *na, int *nb) {
    const double *m = warm + MF_SLOT;
    const int c = (int)m[2];
    *na = c & 31;
    *nb = c >> 5;
    for (int k = 0; k < *na + *nb; k++) idx[k] = (int)(((int64_t)m[3 + k / 4] >> (13 * (k % 4))) & 8191);
}

static void mf_cache_put(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, const floe_polytope_view *pva,
                         const floe_polytope_view *pvb, const rel_map *fab, const rel_map *fba, double *warm) {
    int idx[MF_CAP];
    double Ma, Mb;
    const double delta = MF_NEAR * (a->r + b->r);
    const int na = pva->nv < 8192 && pvb->nv < 8192 ? mf_near(pva, pvb, fab, delta, idx, MF_CAP, &Ma) : -1;
    const int nb = na >= 0 ? mf_near(pvb, pva, fba, delta, idx + na, MF_CAP - na, &Mb) : -1;
    if (nb < 0) return; /* too many near corners: no cache (the separation slot stays NaN) */
    double *m = warm + MF_SLOT;
    int64_t pk[4] = {0, 0, 0, 0};
    for (int k = 0; k < na + nb; k++) pk[k / 4] |= (int64_t)idx[k] << (13 * (k % 4));
    m[0] = w->motion;
    m[1] = fmin(Ma, Mb);
    m[2] = na + 32 * nb;
    for (int k = 0; k < 4; k++) m[3 + k] = (double)pk[k];
    w->sep[0] = MF_MARK;
    w->sep[1] = w->motion;
}

static void manifold(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, const floe_polytope_view *pva,
                     const floe_polytope_view *pvb, const rel_map *fab, const rel_map *fba, int fb, int fa,
                     double *warm, floe_contact *c) {
    const int K = w->dim == 2 ? 2 : 4;
    mf_vertex best[4];
    int nb = 0;
    const int cc = w->dim == 3 && warm && w->sep && !w->no_corner_cache;
    if (cc && mf_cache_holds(w, warm)) {
        int idx[MF_CAP], na, nbb;
        mf_cache_get(warm, idx, &na, &nbb);
        mf_vertices_of(w, a, b, pva, pvb, fab, 1.0, idx, na, best, &nb, K);
        mf_vertices_of(w, b, a, pvb, pva, fba, -1.0, idx + na, nbb, best, &nb, K);
        w->det->mf_cached++;
    } else {
        mf_vertices(w, a, b, pva, pvb, fab, 1.0, fb, best, &nb, K);
        mf_vertices(w, b, a, pvb, pva, fba, -1.0, fa, best, &nb, K);
        if (cc) mf_cache_put(w, a, b, pva, pvb, fab, fba, warm);
    }
    mf_set_extras(c, best, nb); /* the deepest vertex is the deepest point's share */
}

/* the separation cache (docs/models.md): a lower bound of the distance between a and b (not
 * positive: none), kept with the pair's motion bound now, less a margin for its round-off */
static void sep_keep(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double gap) {
    w->sep[0] = gap > 0 ? gap - 1e-9 * (a->r + b->r) : NAN;
    w->sep[1] = w->motion;
}

/* the warm slot of a polytope pair: the two halves' bases in 0..3 and 4..7, then 1 here if
 * the pair touched at the last look (NaN otherwise; ADMM's slot, unused by the LP) */
#define LP_TOUCHED 8

static int polytope_pair(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    if (warm) warm[LP_TOUCHED] = NAN;
    double x1[3], x2[3], s1, s2, n1[3], n2[3], g1 = 1, g2 = 1;
    int p1 = 0, p2 = 0;
    int fb = 0, fa = 0; /* the faces of b and of a the other presses on */
    rel_map fab, fba; /* the maps between the frames, each for its LP half and manifold pass */
    double Ra[3][3];
    rel_make(&fab, a, b, Ra);
    floe_polytope_view va, vb; /* each body's planes and corners, fetched once for the pair */
    floe_geometry_polytope(a->g, w->dim, &va);
    floe_geometry_polytope(b->g, w->dim, &vb);
    int rc = lp_half(w, a, b, &va, &vb, &fab, warm, x1, &s1, n1, &g1, &p1, &fb);
    if (rc) return -rc;
    w->det->lp_calls++;
    if (!(s1 < 0)) {
        /* apart: s1 = min over a of the largest plane distance of b, at most the distance
         * from a to b (each plane's distance bounds a point's distance from b outside it) */
        if (w->sep) sep_keep(w, a, b, s1);
        count_iterations(w, p1);
        return 0;
    }
    rel_back(&fba, &fab, Ra, a, b);
    rc = lp_half(w, b, a, &vb, &va, &fba, warm ? warm + 4 : NULL, x2, &s2, n2, &g2, &p2, &fa);
    if (rc) return -rc;
    count_iterations(w, p1 + p2);
    if (!(s2 < 0)) {
        if (w->sep) sep_keep(w, a, b, s2);
        return 0;
    }
    floe_v3_copy(c->x1, x1);
    floe_v3_copy(c->x2, x2);
    /* the deeper half sets depth, normal and the point the force acts at (the deepest
     * point itself: the force is then the gradient of the stored energy) */
    if (-s1 >= -s2) {
        double n[3];
        floe_q_rotate(n, a->q, n1); /* into the world */
        c->depth = -s1;
        floe_v3_set(c->n, -n[0], -n[1], -n[2]);
        floe_v3_copy(c->point, x1);
        c->gscale = g1;
    } else {
        c->depth = -s2;
        floe_q_rotate(c->n, b->q, n2);
        floe_v3_copy(c->point, x2);
        c->gscale = g2;
    }
    c->r_eff = a->r * b->r / (a->r + b->r);
    manifold(w, a, b, &va, &vb, &fab, &fba, fb, fa, warm, c);
    if (warm) warm[LP_TOUCHED] = 1.0;
    return 1;
}

/* the gap between a and b along the line of centres (support functions): no point of a is
 * closer to a point of b than this, so a positive gap is a cheap exact "no contact"; -1
 * without support functions or with coincident centres */
static double centre_line_gap(const shape_ref *a, const shape_ref *b) {
    if (!a->g->klass->support || !b->g->klass->support) return -1.0;
    double d[3], da[3], db[3], sa[3], sb[3];
    floe_v3_sub(d, b->x, a->x);
    double n = floe_v3_norm(d);
    if (!(n > 0)) return -1.0;
    floe_v3_scale(d, 1.0 / n);
    floe_q_rotate_inv(da, a->q, d);
    floe_v3_scale(d, -1.0);
    floe_q_rotate_inv(db, b->q, d);
    a->g->klass->support(a->g, da, sa);
    b->g->klass->support(b->g, db, sb);
    /* the extent of a towards b and of b towards a along the unit centre line, each in its
     * own frame (a rotation keeps the dot product: no rotation back to the world) */
    return n - (floe_v3_dot(sa, da) + floe_v3_dot(sb, db));
}

static void note_nonconverged(floe_detect_ctx *w) {
    w->det->nonconverged++;
    if (w->det->nonconverged == 1) {
        w->det->first_bad_i = w->det->cur_i;
        w->det->first_bad_j = w->det->cur_j;
        w->det->first_bad_step = w->step;
    }
}

/* a shape that only gives an SDF: the library derives its projection (user SDFs) */
static int sdf_only(const floe_geometry *g) { return !g->klass->project; }

/* a pair with a shape that only gives an SDF (exact, or a Lipschitz-1 bound outside):
 * projected gradient ascent on the true distance (floe_sdf_half), one half per shape the
 * other can be deepest in (a polytope partner: only its point deepest in the curved shape,
 * as for ADMM); depth = the deeper half, force along the normal of the shape it is deepest
 * in, applied at the deepest point (finish_at). */
static int sdf_pair(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    floe_pose pa = {a->g, {a->x[0], a->x[1], a->x[2]}, {a->q[0], a->q[1], a->q[2], a->q[3]}};
    floe_pose pb = {b->g, {b->x[0], b->x[1], b->x[2]}, {b->q[0], b->q[1], b->q[2], b->q[3]}};
    int half1 = !is_polytope(b->g), half2 = !is_polytope(a->g);
    double X1[3], X2[3], d1 = INFINITY, d2 = INFINITY, n1[3] = {0, 0, 1}, n2[3] = {0, 0, 1};
    int its = 0, bad = 0;
    if (half1) {
        int it = floe_sdf_half(&pa, &pb, &w->det->admm, warm, X1, &d1, n1);
        its += it < 0 ? -it : it;
        bad |= it < 0;
    }
    if (half2 && (!half1 || d1 < 0)) { /* half 1 apart: no contact, half 2 not needed */
        int it = floe_sdf_half(&pb, &pa, &w->det->admm, warm ? warm + 8 : NULL, X2, &d2, n2);
        its += it < 0 ? -it : it;
        bad |= it < 0;
    }
    count_iterations(w, its);
    w->det->admm_calls++;
    if (bad) note_nonconverged(w);
    if (!(d1 < 0 || d2 < 0) || (half1 && !(d1 < 0))) return 0;
    double x[3];
    if (d1 <= d2) { /* a's point x deepest in b; n1: b's outward normal, towards a */
        floe_q_rotate(x, a->q, X1);
        floe_v3_add(x, x, a->x);
        floe_v3_copy(c->x1, x);
        for (int k = 0; k < 3; k++) c->x2[k] = x[k] - d1 * n1[k];
        floe_v3_set(c->n, -n1[0], -n1[1], -n1[2]);
        c->depth = -d1;
    } else { /* b's point deepest in a; n2: a's outward normal, towards b */
        floe_q_rotate(x, b->q, X2);
        floe_v3_add(x, x, b->x);
        floe_v3_copy(c->x2, x);
        for (int k = 0; k < 3; k++) c->x1[k] = x[k] - d2 * n2[k];
        floe_v3_copy(c->n, n2);
        c->depth = -d2;
    }
    c->r_eff = a->r * b->r / (a->r + b->r);
    finish_at(c, x);
    return 1;
}

/* ---- any other convex pair: ADMM ---- */
static int admm_pair(floe_detect_ctx *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    const int lp = is_polytope(a->g) && is_polytope(b->g);
    /* a polytope pair that touched at the last look (LP_TOUCHED) goes to the LP at once:
     * the LP itself says "apart" exactly, and for a resting contact the support test could
     * only fail */
    if (!(lp && warm && isfinite(warm[0]) && warm[LP_TOUCHED] == 1.0)) {
        /* most list pairs of non-spherical grains: bounding spheres overlap, shapes apart.
         * The separation cache: a gap g measured at the pair's motion bound m0 stays open
         * while the bodies' points have moved less than g since (motion - m0 < g) */
        if (floe_detect_sep_holds(w)) return 0; /* the warm state as the evaluation that found it apart left it */
        const double gap = centre_line_gap(a, b);
        if (w->sep) sep_keep(w, a, b, gap);
        if (gap > 0) {
            if (warm) warm[0] = warm[8] = NAN;
            w->det->separated++;
            return 0;
        }
    }
    if (lp) return polytope_pair(w, a, b, warm, c);
    if (sdf_only(a->g) || sdf_only(b->g)) return sdf_pair(w, a, b, warm, c);
    floe_pose pa = {a->g, {a->x[0], a->x[1], a->x[2]}, {a->q[0], a->q[1], a->q[2], a->q[3]}};
    floe_pose pb = {b->g, {b->x[0], b->x[1], b->x[2]}, {b->q[0], b->q[1], b->q[2], b->q[3]}};
    floe_admm_result r;
    int pa_poly = is_polytope(a->g), pb_poly = is_polytope(b->g);
    if (pa_poly != pb_poly) {
        /* polytope against a curved shape: only the half whose objective is the curved
         * shape's SDF (the polytope's point deepest in it). The other half minimises the
         * polytope's SDF, whose ridges make the SDF-only prox stall (docs/models.md); the
         * curved half alone gives the depth and the normal of the curved surface. */
        const floe_pose *P = pa_poly ? &pa : &pb, *S = pa_poly ? &pb : &pa;
        double X[3], phi, xw[3], g[3], gw[3], Xs[3], d[3];
        int it = floe_admm_half(P, S, &w->det->admm, warm, X, &phi);
        count_iterations(w, it < 0 ? -it : it);
        w->det->admm_calls++;
        if (it < 0) note_nonconverged(w);
        if (!(phi < 0)) return 0;
        floe_q_rotate(xw, P->q, X);
        floe_v3_add(xw, xw, P->x);
        floe_v3_sub(d, xw, S->x);
        floe_q_rotate_inv(Xs, S->q, d);
        floe_geometry_gradient(S->g, Xs, g);
        floe_q_rotate(gw, S->q, g); /* outward normal of the curved shape, towards P */
        double xs[3];
        for (int k = 0; k < 3; k++) xs[k] = xw[k] - phi * gw[k]; /* on the curved surface */
        if (pa_poly) { /* normal from a (polytope) to b (curved) */
            floe_v3_copy(c->x1, xw);
            floe_v3_copy(c->x2, xs);
            floe_v3_set(c->n, -gw[0], -gw[1], -gw[2]);
        } else {
            floe_v3_copy(c->x1, xs);
            floe_v3_copy(c->x2, xw);
            floe_v3_copy(c->n, gw);
        }
        c->depth = -phi;
        c->r_eff = a->r * b->r / (a->r + b->r);
        finish_at(c, xw); /* the polytope's point deepest in S */
        return 1;
    }
    floe_admm_contact(&pa, &pb, &w->det->admm, warm, &r);
    count_iterations(w, r.iters);
    w->det->admm_calls++;
    if (!r.converged) note_nonconverged(w);
    if (!r.penetrating) return 0;
    floe_v3_copy(c->x1, r.x1);
    floe_v3_copy(c->x2, r.x2);
    floe_v3_copy(c->n, r.n);
    c->depth = r.depth;
    c->r_eff = a->r * b->r / (a->r + b->r);
    /* the deeper half's point (r.depth and r.n come from it) */
    finish_at(c, -r.phi1 >= -r.phi2 ? r.x1 : r.x2);
    return 1;
}

static const pair_fn pair_table[4][4] = {
    /*            SPHERE        BOX         PLANE         USER */
    /* SPHERE */ {sphere_sphere, sphere_sdf, sphere_plane, sphere_sdf},
    /* BOX    */ {NULL, admm_pair, convex_plane, admm_pair},
    /* PLANE  */ {NULL, NULL, NULL, NULL},
    /* USER   */ {NULL, NULL, convex_plane, admm_pair},
};

static pair_fn lookup(int ka, int kb, int *swap) {
    *swap = 0;
    if (ka > 3 || kb > 3) return NULL;
    if (pair_table[ka][kb]) return pair_table[ka][kb];
    if (pair_table[kb][ka]) { *swap = 1; return pair_table[kb][ka]; }
    return NULL;
}

static int kinds_supported(const floe_geometry *a, const floe_geometry *b) {
    int swap;
    return lookup(a->klass->kind, b->klass->kind, &swap) != NULL;
}

/* piece k of a body: its class's piece (a union of convex pieces), else the shape itself */
static const floe_geometry *piece_shape(const floe_geometry *g, int k) {
    double x[3], q[4], r;
    return g->klass->piece ? g->klass->piece(g, k, x, q, &r) : g;
}

int floe_detect_supported(const floe_geometry *a, const floe_geometry *b) {
    const int na = floe_geometry_piece_count(a), nb = floe_geometry_piece_count(b);
    for (int i = 0; i < na; i++)
        for (int j = 0; j < nb; j++)
            if (!kinds_supported(piece_shape(a, i), piece_shape(b, j))) return 0;
    return 1;
}

int floe_detect_needs_warm(const floe_geometry *a, const floe_geometry *b) {
    const int na = floe_geometry_piece_count(a), nb = floe_geometry_piece_count(b);
    for (int i = 0; i < na; i++)
        for (int j = 0; j < nb; j++) {
            int swap;
            pair_fn f = lookup(piece_shape(a, i)->klass->kind, piece_shape(b, j)->klass->kind, &swap);
            if (f == admm_pair) return 1;
        }
    return 0;
}

int floe_piece_count(const floe_geometry *g) { return floe_geometry_piece_count(g); }

static void make_ref(const floe_body_ref *body, int piece, shape_ref *s) {
    const floe_geometry *g = body->g;
    const double *x = body->x, *q = body->q;
    if (g->klass->piece) { /* a piece of a union: its pose in the body frame, then the body's */
        double px[3], pq[4], off[3];
        s->g = g->klass->piece(g, piece, px, pq, &s->r);
        floe_q_rotate(off, q, px);
        floe_v3_add(s->x, x, off);
        floe_q_mul(s->q, q, pq);
    } else {
        floe_v3_copy(s->x, x);
        memcpy(s->q, q, sizeof s->q);
        s->g = g;
        s->r = body->radius;
    }
    s->kind = s->g->klass->kind;
}

void floe_piece_centre(const floe_body_ref *body, int piece, double c[3], double *r) {
    shape_ref s;
    make_ref(body, piece, &s);
    floe_v3_copy(c, s.x);
    *r = s.r;
}

int floe_detect(floe_detect_ctx *w, const floe_body_ref *bi, const floe_body_ref *bj, int sub, double *warm,
                floe_contact *c) {
    shape_ref a, b;
    const int i = bi->id, j = bj->id;
    make_ref(bi, FLOE_SUB_A(sub), &a);
    make_ref(bj, FLOE_SUB_B(sub), &b);
    int swap;
    pair_fn fn = lookup(a.kind, b.kind, &swap);
    if (!fn) return -FLOE_ENOTSUP;
    w->det->cur_i = i;
    w->det->cur_j = j;
    c->i = i;
    c->j = j;
    if (!swap) return fn(w, &a, &b, warm, c);
    int r = fn(w, &b, &a, warm, c);
    if (r <= 0) return r;
    /* the function computed the contact seen from j: swap the roles back */
    double t[3];
    floe_v3_copy(t, c->x1); floe_v3_copy(c->x1, c->x2); floe_v3_copy(c->x2, t);
    floe_v3_scale(c->n, -1.0);
    for (int e = 0; e < c->nextra; e++) floe_v3_scale(c->extra_n[e], -1.0);
    return r;
}
