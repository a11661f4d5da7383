/* detect.c - contact detection, producing the contact summary of ParticLS eq 15.
 *
 * Dispatch is a table over geometry kinds (Box2D style), applied to convex pieces (a
 * compound body contributes one piece per list entry, so non-convex bodies get one contact
 * per piece pair):
 *   sphere-sphere, sphere-plane, sphere-anything (the other shape's SDF and gradient at
 *   the sphere centre: exact for exact SDFs; spheres never enter ADMM);
 *   polytope-plane (per-vertex springs lumped into one contact), convex-plane (support
 *   point: the shape's `support` or iterated projection);
 *   polytope-polytope (boxes, polyhedra, polygons): the exact deepest-point LP
 *   (contact/polytope_lp.c), warm-started from the previous basis;
 *   any other convex pair: ADMM on the two SDFs (contact/admm.c), warm-started.
 * Warm-start state lives in the neighbour list (FLOE_DETECT_WARM doubles per entry) and is
 * allocated only when a scene has such pairs. */
#include "world_internal.h"
#include "floe_admm.h"
#include "floe_polytope_lp.h"
#include <stdlib.h>
#include <string.h>

typedef struct shape_ref {
    const floe_geometry *g;
    double x[3], q[4];
    double r;   /* bounding radius (a sphere's current radius) */
    int kind;
} shape_ref;

typedef int (*pair_fn)(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c);

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

static int sphere_sphere(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
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

static void plane_normal(const shape_ref *s, double nw[3]) {
    const double ez[3] = {0, 0, 1};
    floe_q_rotate(nw, s->q, ez);
}

static int sphere_plane(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    (void)w; (void)warm;
    double nw[3], d[3];
    plane_normal(b, nw);
    floe_v3_sub(d, a->x, b->x);
    double s = floe_v3_dot(d, nw);
    if (s >= a->r) return 0;
    floe_v3_set(c->n, -nw[0], -nw[1], -nw[2]);
    c->depth = a->r - s;
    for (int k = 0; k < 3; k++) {
        c->x1[k] = a->x[k] - a->r * nw[k];
        c->x2[k] = a->x[k] - s * nw[k];
    }
    c->r_eff = a->r;
    finish(c);
    return 1;
}

/* sphere a against any shape b with an SDF: distance of the sphere centre. The SDF never
 * overestimates the distance (|grad| <= 1, docs/models.md), so phi >= r means apart; below,
 * the true distance and unit normal (floe_geometry_distance: measured by projection for a
 * shape that only gives an SDF, whose value outside may be a bound) */
static int sphere_sdf(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
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
static int vertices_plane(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    (void)warm;
    int nv = 0;
    const double *V = a->g->klass->vertices(a->g, &nv);
    double nw[3], rel[3], wsum = 0, acc[3] = {0, 0, 0};
    plane_normal(b, nw);
    floe_v3_sub(rel, a->x, b->x);
    if (floe_v3_dot(rel, nw) >= a->r) return 0;
    const int is_box = a->kind == FLOE_GEOM_BOX;
    for (int v = 0; v < nv; v++) {
        double X[3] = {V[3 * v], V[3 * v + 1], V[3 * v + 2]}, xw[3];
        if (w->def.dim == 2 && is_box) {
            if (X[2] > 0) continue; /* 2D: one face of the box (the z = -h corners) */
            X[2] = 0;
        }
        floe_q_rotate(xw, a->q, X);
        floe_v3_add(xw, xw, a->x);
        floe_v3_sub(rel, xw, b->x);
        double s = floe_v3_dot(rel, nw);
        if (s < 0) {
            wsum += -s;
            floe_v3_axpy(acc, -s, xw);
        }
    }
    if (wsum <= 0) return 0;
    double pc[3] = {acc[0] / wsum, acc[1] / wsum, acc[2] / wsum};
    floe_v3_sub(rel, pc, b->x);
    double s = floe_v3_dot(rel, nw);
    floe_v3_set(c->n, -nw[0], -nw[1], -nw[2]);
    c->depth = wsum;
    for (int k = 0; k < 3; k++) {
        c->x2[k] = pc[k] - s * nw[k];
        c->x1[k] = pc[k];
    }
    c->r_eff = a->r;
    finish(c);
    return 1;
}

/* convex shape a against plane b: the support point in direction -n (the shape's own
 * `support`, or floe_geometry_support's climb along the zero level set, which needs only
 * the SDF, exact or a bound: test_sdf_bound). */
static int convex_plane(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    (void)w; (void)warm;
    const floe_geometry *g = a->g;
    if (g->klass->vertices && g->klass->kind != FLOE_GEOM_COMPOUND) return vertices_plane(w, a, b, warm, c);
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

/* body-frame face planes of a box or polytope (NULL otherwise) */
/* dim 2: a box's z faces are left out (its motion is in the xy plane; as LP rows they
 * would cap the depth at the half thickness with a zero in-plane normal) */
static const double *body_planes(const floe_geometry *g, int dim, int *np, double buf[24]) {
    if (g->klass == &floe_box_class) {
        const double *h = ((const floe_box *)g)->half;
        for (int a = 0; a < 3; a++)
            for (int s = 0; s < 2; s++) {
                double *P = buf + 4 * (2 * a + s);
                P[0] = P[1] = P[2] = 0;
                P[a] = s ? 1.0 : -1.0;
                P[3] = h[a];
            }
        *np = dim == 2 ? 4 : 6;
        return buf;
    }
    if (g->klass == &floe_polytope_class) {
        const floe_polytope *p = (const floe_polytope *)g;
        *np = p->np;
        return p->plane;
    }
    return NULL;
}

static int is_polytope(const floe_geometry *g) {
    return g->klass == &floe_box_class || g->klass == &floe_polytope_class;
}

/* planes and vertices of b expressed in a's body frame (scratch owned by the world) */
static int lp_scratch(floe_world *w, int need) {
    if (w->det.scratch_cap >= need) return FLOE_OK;
    double *s = realloc(w->det.scratch, (size_t)need * sizeof(double));
    if (!s) return FLOE_ENOMEM;
    w->det.scratch = s;
    w->det.scratch_cap = need;
    return FLOE_OK;
}

static void plane_to_frame(const double P[4], const shape_ref *from, const shape_ref *to, double out[4]) {
    /* n_to = R_to^T R_from n; d_to = d + n_world . (x_from - x_to) */
    double nw[3], d[3];
    floe_q_rotate(nw, from->q, P);
    floe_q_rotate_inv(out, to->q, nw);
    floe_v3_sub(d, from->x, to->x);
    out[3] = P[3] + floe_v3_dot(nw, d);
}

/* one half: a's point deepest in b, in world coordinates */
static int lp_half(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm4, double x[3], double *s,
                   double n[3], int *pivots) {
    double ba[24], bb[24];
    int na = 0, nb = 0, nva = 0;
    const double *pa = body_planes(a->g, w->def.dim, &na, ba), *pb = body_planes(b->g, w->def.dim, &nb, bb);
    const double *va = a->g->klass->vertices(a->g, &nva);
    if (lp_scratch(w, 4 * nb)) return FLOE_ENOMEM;
    double *tb = w->det.scratch;
    for (int k = 0; k < nb; k++) plane_to_frame(pb + 4 * k, b, a, tb + 4 * k);
    floe_lp_problem P = {w->def.dim, pa, na, tb, nb, va, nva, fmin(a->r, b->r)};
    int basis[4];
    for (int k = 0; k < 4; k++) basis[k] = warm4 && isfinite(warm4[k]) ? (int)warm4[k] : -1;
    floe_lp_result r;
    int rc = floe_lp_deepest(&P, basis, &r);
    if (rc) {
        if (warm4) warm4[0] = NAN;
        return rc;
    }
    if (warm4)
        for (int k = 0; k < 4; k++) warm4[k] = k <= w->def.dim ? basis[k] : NAN;
    floe_q_rotate(x, a->q, r.x);
    floe_v3_add(x, x, a->x);
    floe_q_rotate(n, a->q, r.normal); /* outward normal of b at x */
    *s = r.s;
    *pivots = r.pivots + 1;
    return FLOE_OK;
}

/* Flat contacts: where faces touch, the deepest points are not unique and the LP returns
 * a vertex of the optimal set (near an edge of the face) with a normal mixed from two
 * faces, which spins bodies that meet head-on and breaks the energy ledger. Among the
 * faces tight at the two optima, take the one with the least overlap along its normal
 * (separating-axis rule); depth = that overlap, point = midpoint of the two shapes'
 * vertex sets within a small band of the supporting planes (a face centre for aligned
 * faces). */
static void extent(const shape_ref *s, const double n[3], double *lo, double *hi) {
    int nv = 0;
    const double *V = s->g->klass->vertices(s->g, &nv);
    double nb[3];
    floe_q_rotate_inv(nb, s->q, n);
    double o = floe_v3_dot(s->x, n);
    *lo = INFINITY; *hi = -INFINITY;
    for (int v = 0; v < nv; v++) {
        double d = floe_v3_dot(V + 3 * v, nb) + o;
        if (d < *lo) *lo = d;
        if (d > *hi) *hi = d;
    }
}
static void band_centroid(const shape_ref *s, const double n[3], double level, double band, double out[3]) {
    int nv = 0, cnt = 0;
    const double *V = s->g->klass->vertices(s->g, &nv);
    double nb[3], acc[3] = {0, 0, 0};
    floe_q_rotate_inv(nb, s->q, n);
    double o = floe_v3_dot(s->x, n);
    for (int v = 0; v < nv; v++)
        if (fabs(floe_v3_dot(V + 3 * v, nb) + o - level) <= band) {
            floe_v3_add(acc, acc, V + 3 * v);
            cnt++;
        }
    if (!cnt) return;
    floe_v3_scale(acc, 1.0 / cnt);
    floe_q_rotate(out, s->q, acc);
    floe_v3_add(out, out, s->x);
}
static void face_contact(const shape_ref *a, const shape_ref *b, int dim, const double *warm, floe_contact *c) {
    if (!warm) return;
    double cand[8][3];
    int nc = 0;
    for (int h = 0; h < 2; h++) { /* half 0: rows of b (normals point out of b); half 1: rows of a */
        const shape_ref *own = h ? a : b, *oth = h ? b : a;
        double buf[24];
        int np = 0, nrow_other = 0;
        const double *pl = body_planes(own->g, dim, &np, buf);
        double tmp[24];
        body_planes(oth->g, dim, &nrow_other, tmp);
        for (int k = 0; k < 4; k++) {
            double r = warm[4 * h + k];
            if (!isfinite(r)) continue;
            int row = (int)r - nrow_other; /* the rows of the "b" side come after the other's */
            if (row < 0 || row >= np) continue;
            double nw[3];
            floe_q_rotate(nw, own->q, pl + 4 * row);
            if (h == 0) floe_v3_scale(nw, -1.0); /* normal from a to b */
            if (nc < 8) floe_v3_copy(cand[nc++], nw);
        }
    }
    double best = INFINITY, bn[3] = {0, 0, 0};
    for (int k = 0; k < nc; k++) {
        double alo, ahi, blo, bhi;
        extent(a, cand[k], &alo, &ahi);
        extent(b, cand[k], &blo, &bhi);
        double ov = ahi - blo;
        if (ov < best) { best = ov; floe_v3_copy(bn, cand[k]); }
    }
    if (!(best > 0) || !isfinite(best) || best > 2 * c->depth + 1e-12) return;
    double alo, ahi, blo, bhi, pa[3], pb[3];
    extent(a, bn, &alo, &ahi);
    extent(b, bn, &blo, &bhi);
    double band = 1e-3 * fmin(a->r, b->r) + best;
    floe_v3_copy(pa, c->x1);
    floe_v3_copy(pb, c->x2);
    band_centroid(a, bn, ahi, band, pa);
    band_centroid(b, bn, blo, band, pb);
    /* the patch: between the two face centroids, each moved onto its supporting plane */
    double mid[3];
    for (int k = 0; k < 3; k++) mid[k] = 0.5 * (pa[k] + pb[k]);
    double m = floe_v3_dot(mid, bn);
    for (int k = 0; k < 3; k++) {
        c->x1[k] = mid[k] + (ahi - m) * bn[k];
        c->x2[k] = mid[k] + (blo - m) * bn[k];
    }
    floe_v3_copy(c->n, bn);
    c->depth = best;
    finish(c);
}

static void count_iterations(floe_world *w, int it) {
    w->det.calls++;
    w->det.iterations += it;
    w->det.hist[it < FLOE_DETECT_HIST - 1 ? it : FLOE_DETECT_HIST - 1]++;
}

static int polytope_pair(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    double x1[3], x2[3], s1, s2, n1[3], n2[3];
    int p1 = 0, p2 = 0;
    int rc = lp_half(w, a, b, warm, x1, &s1, n1, &p1);
    if (rc) return -rc;
    w->det.lp_calls++;
    if (!(s1 < 0)) {
        count_iterations(w, p1);
        return 0;
    }
    rc = lp_half(w, b, a, warm ? warm + 4 : NULL, x2, &s2, n2, &p2);
    if (rc) return -rc;
    count_iterations(w, p1 + p2);
    if (!(s2 < 0)) return 0;
    floe_v3_copy(c->x1, x1);
    floe_v3_copy(c->x2, x2);
    if (-s1 >= -s2) { c->depth = -s1; floe_v3_set(c->n, -n1[0], -n1[1], -n1[2]); }
    else { c->depth = -s2; floe_v3_copy(c->n, n2); }
    c->r_eff = a->r * b->r / (a->r + b->r);
    finish(c);
    face_contact(a, b, w->def.dim, warm, c);
    return 1;
}

/* separated along the line of centres (support functions): a cheap exact "no contact" */
static int separated_on_centre_line(const shape_ref *a, const shape_ref *b) {
    if (!a->g->klass->support || !b->g->klass->support) return 0;
    double d[3], da[3], db[3], sa[3], sb[3], xa[3], xb[3];
    floe_v3_sub(d, b->x, a->x);
    double n = floe_v3_norm(d);
    if (!(n > 0)) return 0;
    floe_v3_scale(d, 1.0 / n);
    floe_q_rotate_inv(da, a->q, d);
    floe_v3_scale(d, -1.0);
    floe_q_rotate_inv(db, b->q, d);
    a->g->klass->support(a->g, da, sa);
    b->g->klass->support(b->g, db, sb);
    floe_q_rotate(xa, a->q, sa);
    floe_q_rotate(xb, b->q, sb);
    /* extent of a towards b and of b towards a, along the unit centre line -d */
    return -floe_v3_dot(xa, d) + floe_v3_dot(xb, d) < n ? 1 : 0;
}

static void note_nonconverged(floe_world *w) {
    w->det.nonconverged++;
    if (w->det.nonconverged == 1) {
        w->det.first_bad_i = w->det.cur_i;
        w->det.first_bad_j = w->det.cur_j;
        w->det.first_bad_step = w->step;
    }
}

/* a shape that only gives an SDF: the library derives its projection (user SDFs) */
static int sdf_only(const floe_geometry *g) { return !g->klass->project; }

/* a pair with a shape that only gives an SDF (exact, or a Lipschitz-1 bound outside):
 * projected gradient ascent on the true distance (floe_sdf_half), one half per shape the
 * other can be deepest in (a polytope partner: only its point deepest in the curved shape,
 * as for ADMM); depth = the deeper half, force along the normal of the shape it is deepest
 * in, applied at the deepest point (finish_at). */
static int sdf_pair(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    floe_pose pa = {a->g, {a->x[0], a->x[1], a->x[2]}, {a->q[0], a->q[1], a->q[2], a->q[3]}};
    floe_pose pb = {b->g, {b->x[0], b->x[1], b->x[2]}, {b->q[0], b->q[1], b->q[2], b->q[3]}};
    int half1 = !is_polytope(b->g), half2 = !is_polytope(a->g);
    double X1[3], X2[3], d1 = INFINITY, d2 = INFINITY, n1[3] = {0, 0, 1}, n2[3] = {0, 0, 1};
    int its = 0, bad = 0;
    if (half1) {
        int it = floe_sdf_half(&pa, &pb, &w->det.admm, warm, X1, &d1, n1);
        its += it < 0 ? -it : it;
        bad |= it < 0;
    }
    if (half2 && (!half1 || d1 < 0)) { /* half 1 apart: no contact, half 2 not needed */
        int it = floe_sdf_half(&pb, &pa, &w->det.admm, warm ? warm + 8 : NULL, X2, &d2, n2);
        its += it < 0 ? -it : it;
        bad |= it < 0;
    }
    count_iterations(w, its);
    w->det.admm_calls++;
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
static int admm_pair(floe_world *w, const shape_ref *a, const shape_ref *b, double *warm, floe_contact *c) {
    if (separated_on_centre_line(a, b)) {
        /* most list pairs of non-spherical grains: bounding spheres overlap, shapes apart */
        if (warm) warm[0] = warm[8] = NAN;
        w->det.separated++;
        return 0;
    }
    if (is_polytope(a->g) && is_polytope(b->g)) return polytope_pair(w, a, b, warm, c);
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
        int it = floe_admm_half(P, S, &w->det.admm, warm, X, &phi);
        count_iterations(w, it < 0 ? -it : it);
        w->det.admm_calls++;
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
    floe_admm_contact(&pa, &pb, &w->det.admm, warm, &r);
    count_iterations(w, r.iters);
    w->det.admm_calls++;
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
    /* BOX    */ {NULL, admm_pair, vertices_plane, admm_pair},
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

int floe_detect_supported(const floe_geometry *a, const floe_geometry *b) {
    const floe_compound *ca = a->klass == &floe_compound_class ? (const floe_compound *)a : NULL;
    const floe_compound *cb = b->klass == &floe_compound_class ? (const floe_compound *)b : NULL;
    int na = ca ? ca->n : 1, nb = cb ? cb->n : 1;
    for (int i = 0; i < na; i++)
        for (int j = 0; j < nb; j++)
            if (!kinds_supported(ca ? ca->piece[i] : a, cb ? cb->piece[j] : b)) return 0;
    return 1;
}

int floe_detect_needs_warm(const floe_geometry *a, const floe_geometry *b) {
    const floe_compound *ca = a->klass == &floe_compound_class ? (const floe_compound *)a : NULL;
    const floe_compound *cb = b->klass == &floe_compound_class ? (const floe_compound *)b : NULL;
    int na = ca ? ca->n : 1, nb = cb ? cb->n : 1;
    for (int i = 0; i < na; i++)
        for (int j = 0; j < nb; j++) {
            int swap;
            pair_fn f = lookup((ca ? ca->piece[i] : a)->klass->kind, (cb ? cb->piece[j] : b)->klass->kind, &swap);
            if (f == admm_pair) return 1;
        }
    return 0;
}

int floe_piece_count(const floe_geometry *g) {
    return g->klass == &floe_compound_class ? ((const floe_compound *)g)->n : 1;
}

static void make_ref(const floe_world *w, int i, int piece, shape_ref *s) {
    const floe_particles *p = &w->p;
    const floe_geometry *g = w->geoms[p->geom[i]];
    const double *x = p->x + 3 * i, *q = p->q + 4 * i;
    if (g->klass == &floe_compound_class) {
        const floe_compound *cg = (const floe_compound *)g;
        double off[3];
        floe_q_rotate(off, q, cg->piece_x + 3 * piece);
        floe_v3_add(s->x, x, off);
        floe_q_mul(s->q, q, cg->piece_q + 4 * piece);
        s->g = cg->piece[piece];
        s->r = cg->piece_r[piece];
    } else {
        floe_v3_copy(s->x, x);
        memcpy(s->q, q, sizeof s->q);
        s->g = g;
        s->r = p->radius[i];
    }
    s->kind = s->g->klass->kind;
}

void floe_piece_centre(const floe_world *w, int i, int piece, double c[3], double *r) {
    shape_ref s;
    make_ref(w, i, piece, &s);
    floe_v3_copy(c, s.x);
    *r = s.r;
}

int floe_detect(floe_world *w, int i, int j, int sub, double *warm, floe_contact *c) {
    shape_ref a, b;
    make_ref(w, i, FLOE_SUB_A(sub), &a);
    make_ref(w, j, FLOE_SUB_B(sub), &b);
    int swap;
    pair_fn fn = lookup(a.kind, b.kind, &swap);
    if (!fn) return -FLOE_ENOTSUP;
    w->det.cur_i = i;
    w->det.cur_j = j;
    c->i = i;
    c->j = j;
    if (!swap) return fn(w, &a, &b, warm, c);
    int r = fn(w, &b, &a, warm, c);
    if (r <= 0) return r;
    /* the function computed the contact seen from j: swap the roles back */
    double t[3];
    floe_v3_copy(t, c->x1); floe_v3_copy(c->x1, c->x2); floe_v3_copy(c->x2, t);
    floe_v3_scale(c->n, -1.0);
    return r;
}
