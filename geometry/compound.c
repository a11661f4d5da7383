/* compound.c - a non-convex rigid body as a union of convex pieces, each placed at piece_x
 * with orientation piece_q in the compound body frame. SDF = min over the pieces (exact
 * outside the union; inside, where pieces overlap, it is the deepest single-piece value's
 * minimum, i.e. a lower bound of the true depth in the overlap).
 *
 * Mass properties sum the pieces' (rotated and shifted by the parallel-axis theorem), so
 * the volume of overlapping pieces is counted twice: model a compound with pieces that only
 * touch, or accept the excess mass. The constructor moves the body frame to the combined
 * centroid and principal axes (only about z for dim 2) and records the placement in
 * frame_x/frame_q (X_input = R(frame_q) X_body + frame_x). */
#include "geometry_internal.h"
#include "floe_geometry.h"
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


static double piece_sdf(const floe_compound *c, int i, const double X[3], double Y[3]) {
    double d[3];
    floe_v3_sub(d, X, c->piece_x + 3 * i);
    floe_q_rotate_inv(Y, c->piece_q + 4 * i, d);
    return floe_geometry_sdf(c->piece[i], Y);
}
/* the piece with the smallest SDF (pieces whose bounding sphere is farther than the best
 * value so far cannot win: sdf >= |X - x_i| - r_i) */
static int nearest_piece(const floe_compound *c, const double X[3], double *phi, double Yb[3]) {
    double best = INFINITY, Y[3];
    int ib = 0;
    for (int i = 0; i < c->n; i++) {
        double d[3];
        floe_v3_sub(d, X, c->piece_x + 3 * i);
        if (floe_v3_norm(d) - c->piece_r[i] >= best) continue;
        double s = piece_sdf(c, i, X, Y);
        if (s < best) { best = s; ib = i; floe_v3_copy(Yb, Y); }
    }
    if (!(best < INFINITY)) { best = piece_sdf(c, 0, X, Y); ib = 0; floe_v3_copy(Yb, Y); }
    *phi = best;
    return ib;
}
static double comp_sdf(const floe_geometry *g, const double X[3]) {
    double phi, Y[3];
    nearest_piece((const floe_compound *)g, X, &phi, Y);
    return phi;
}
static void comp_grad(const floe_geometry *g, const double X[3], double n[3]) {
    const floe_compound *c = (const floe_compound *)g;
    double phi, Y[3], m[3];
    int i = nearest_piece(c, X, &phi, Y);
    floe_geometry_gradient(c->piece[i], Y, m);
    floe_q_rotate(n, c->piece_q + 4 * i, m);
}
/* nearest point on the surface of the piece with the smallest SDF (on the union's surface
 * unless it lies inside another, overlapping piece) */
static void comp_project(const floe_geometry *g, const double X[3], double o[3]) {
    const floe_compound *c = (const floe_compound *)g;
    double phi, Y[3], m[3];
    int i = nearest_piece(c, X, &phi, Y);
    floe_geometry_project(c->piece[i], Y, m);
    floe_q_rotate(o, c->piece_q + 4 * i, m);
    floe_v3_add(o, o, c->piece_x + 3 * i);
}
static double comp_radius(const floe_geometry *g) { return ((const floe_compound *)g)->radius; }
static void piece_support(const floe_geometry *p, const double d[3], double o[3]) {
    if (p->klass->support) { p->klass->support(p, d, o); return; }
    /* no support function: the nearest point to a far point along d (error ~ R / 1e8) */
    double far[3] = {d[0], d[1], d[2]};
    floe_v3_scale(far, 1e8 * floe_geometry_bounding_radius(p));
    floe_geometry_project(p, far, o);
}
static void comp_support(const floe_geometry *g, const double d[3], double o[3]) {
    const floe_compound *c = (const floe_compound *)g;
    double best = -INFINITY;
    for (int i = 0; i < c->n; i++) {
        double dl[3], s[3], w[3];
        floe_q_rotate_inv(dl, c->piece_q + 4 * i, d);
        piece_support(c->piece[i], dl, s);
        floe_q_rotate(w, c->piece_q + 4 * i, s);
        floe_v3_add(w, w, c->piece_x + 3 * i);
        double v = floe_v3_dot(w, d);
        if (v > best) { best = v; floe_v3_copy(o, w); }
    }
}

/* combined volume, centroid and inertia tensor about the centroid, at density rho */
static int combine(floe_geometry *const *piece, const double *px, const double *pq, int n, int dim, double rho,
                   double *V, double c[3], double I[3][3], int *bad) {
    double M = 0, S[3] = {0, 0, 0}, J[3][3] = {{0}};
    floe_mass_properties *mp = malloc((size_t)n * sizeof *mp);
    double *pc = malloc((size_t)n * 3 * sizeof *pc);
    if (!mp || !pc) { free(mp); free(pc); return FLOE_ENOMEM; }
    *V = 0;
    for (int i = 0; i < n; i++) {
        int rc = floe_geometry_mass_properties(piece[i], dim, rho, &mp[i]);
        if (rc != FLOE_OK || !(mp[i].volume > 0) || !isfinite(mp[i].mass) || mp[i].off_axis > 1e-6) {
            *bad = i; free(mp); free(pc);
            return rc != FLOE_OK ? rc : FLOE_EINVAL;
        }
        floe_q_rotate(pc + 3 * i, pq + 4 * i, mp[i].centroid);
        floe_v3_add(pc + 3 * i, pc + 3 * i, px + 3 * i);
        *V += mp[i].volume; M += mp[i].mass;
        floe_v3_axpy(S, mp[i].mass, pc + 3 * i);
    }
    for (int k = 0; k < 3; k++) c[k] = M > 0 ? S[k] / M : 0;
    for (int i = 0; i < n; i++) {
        /* R diag(I) R^T + m (|r|^2 1 - r r^T) */
        double R[3][3], e[3], r[3];
        for (int k = 0; k < 3; k++) {
            floe_v3_set(e, k == 0, k == 1, k == 2);
            floe_q_rotate(r, pq + 4 * i, e); /* column k */
            for (int j = 0; j < 3; j++) R[j][k] = r[j];
        }
        floe_v3_sub(r, pc + 3 * i, c);
        double r2 = floe_v3_dot(r, r);
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) {
                double s = 0;
                for (int k = 0; k < 3; k++) s += R[a][k] * mp[i].inertia[k] * R[b][k];
                J[a][b] += s + mp[i].mass * ((a == b ? r2 : 0) - r[a] * r[b]);
            }
    }
    memcpy(I, J, sizeof J);
    free(mp); free(pc);
    return FLOE_OK;
}

static int comp_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const floe_compound *c = (const floe_compound *)g;
    double V, ce[3], I[3][3];
    int bad = 0;
    FLOE_TRY(combine(c->piece, c->piece_x, c->piece_q, c->n, dim, rho, &V, ce, I, &bad));
    o->volume = V; o->mass = rho * V;
    floe_v3_copy(o->centroid, ce);
    for (int k = 0; k < 3; k++) o->inertia[k] = I[k][k];
    double dm = fmax(I[0][0], fmax(I[1][1], I[2][2]));
    o->off_axis = dm > 0 ? fmax(fabs(I[0][1]), fmax(fabs(I[0][2]), fabs(I[1][2]))) / dm : 0;
    o->quadrature_error = 0;
    for (int i = 0; i < c->n; i++) { /* the largest error of a piece */
        floe_mass_properties m;
        if (floe_geometry_mass_properties(c->piece[i], dim, rho, &m) == FLOE_OK)
            o->quadrature_error = fmax(o->quadrature_error, m.quadrature_error);
    }
    return FLOE_OK;
}

static void comp_destroy(floe_geometry *g) {
    floe_compound *c = (floe_compound *)g;
    for (int i = 0; i < c->n; i++) floe_geometry_destroy(c->piece[i]);
    free(c->piece); free(c->piece_x); free(c->piece_q); free(c->piece_r);
    free(c);
}

static int comp_piece_count(const floe_geometry *g) { return ((const floe_compound *)g)->n; }
static const floe_geometry *comp_piece(const floe_geometry *g, int k, double x[3], double q[4], double *r) {
    const floe_compound *c = (const floe_compound *)g;
    floe_v3_copy(x, c->piece_x + 3 * k);
    memcpy(q, c->piece_q + 4 * k, 4 * sizeof(double));
    *r = c->piece_r[k];
    return c->piece[k];
}

/* planar when a piece is (polygons: 2D worlds only), solid when a piece is, else either */
static int comp_dimension(const floe_geometry *g) {
    const floe_compound *c = (const floe_compound *)g;
    int d = 0;
    for (int k = 0; k < c->n; k++) {
        int dk = floe_geometry_dimension(c->piece[k]);
        if (dk == 2) return 2;
        if (dk == 3) d = 3;
    }
    return d;
}

const floe_geometry_class floe_compound_class = {
    .version = 1, .name = "compound", .kind = FLOE_GEOM_COMPOUND, .sdf = comp_sdf, .gradient = comp_grad,
    .project = comp_project, .bounding_radius = comp_radius, .mass_properties = comp_mass,
    .destroy = comp_destroy, .support = comp_support, .piece_count = comp_piece_count, .piece = comp_piece,
    .dimension = comp_dimension};

floe_geometry *floe_compound_create(floe_geometry **pieces, const double *x, const double *q, int n, int dim,
                                    char *err, size_t errlen) {
    floe_compound *c = NULL;
    if (!pieces || n < 1) { floe_set_err(err, errlen, "compound: need at least one piece"); return NULL; }
    const char *msg = NULL;
    int bad = -1;
    if (dim != 2 && dim != 3) msg = "dimension must be 2 or 3";
    for (int i = 0; i < n && !msg; i++) {
        bad = i;
        if (!pieces[i]) msg = "piece is NULL";
        else if (x && !isfinite(x[3 * i] + x[3 * i + 1] + x[3 * i + 2])) msg = "position is not finite";
        else if (q && (!isfinite(q[4 * i] + q[4 * i + 1] + q[4 * i + 2] + q[4 * i + 3]) ||
                       !(q[4 * i] * q[4 * i] + q[4 * i + 1] * q[4 * i + 1] + q[4 * i + 2] * q[4 * i + 2] +
                         q[4 * i + 3] * q[4 * i + 3] > 0)))
            msg = "orientation is not a finite non-zero quaternion";
        else if (!(floe_geometry_bounding_radius(pieces[i]) < INFINITY)) msg = "piece is unbounded";
    }
    if (msg && dim != 2 && dim != 3) bad = -1;
    if (msg) goto fail;
    c = calloc(1, sizeof *c);
    if (c) {
        c->piece = malloc((size_t)n * sizeof *c->piece);
        c->piece_x = malloc((size_t)n * 3 * sizeof(double));
        c->piece_q = malloc((size_t)n * 4 * sizeof(double));
        c->piece_r = malloc((size_t)n * sizeof(double));
    }
    if (!c || !c->piece || !c->piece_x || !c->piece_q || !c->piece_r) { msg = "out of memory"; bad = -1; goto fail; }
    c->base.klass = &floe_compound_class;
    c->dim = dim;
    for (int i = 0; i < n; i++) {
        c->piece[i] = pieces[i];
        c->n = i + 1; /* owned from here */
        if (x) floe_v3_copy(c->piece_x + 3 * i, x + 3 * i);
        else floe_v3_set(c->piece_x + 3 * i, 0, 0, 0);
        if (q) { memcpy(c->piece_q + 4 * i, q + 4 * i, 4 * sizeof(double)); floe_q_normalize(c->piece_q + 4 * i); }
        else floe_q_identity(c->piece_q + 4 * i);
        c->piece_r[i] = floe_geometry_bounding_radius(pieces[i]);
    }
    double V, ce[3], I[3][3], l[3], R[3][3];
    int rc = combine(c->piece, c->piece_x, c->piece_q, n, dim, 1.0, &V, ce, I, &bad);
    if (rc != FLOE_OK) {
        msg = rc == FLOE_ENOMEM ? "out of memory"
              : rc == FLOE_ENOTSUP ? "no mass properties for this dimension"
                                   : "mass properties not usable (zero volume, or inertia not diagonal in the piece's body axes)";
        if (rc == FLOE_ENOMEM) bad = -1;
        goto fail;
    }
    if (dim == 2) { /* turn about z only: body x along the largest in-plane spread */
        double th = 0.5 * atan2(-2 * I[0][1], I[1][1] - I[0][0]), cs = cos(th), sn = sin(th);
        double Rz[3][3] = {{cs, -sn, 0}, {sn, cs, 0}, {0, 0, 1}};
        memcpy(R, Rz, sizeof R);
        ce[2] = 0;
    } else {
        floe_sym3_eigen(I, l, R);
    }
    double qR[4], qc[4];
    floe_q_from_matrix(qR, R);
    qc[0] = qR[0]; qc[1] = -qR[1]; qc[2] = -qR[2]; qc[3] = -qR[3];
    c->radius = 0;
    for (int i = 0; i < n; i++) {
        double d[3], qn[4];
        floe_v3_sub(d, c->piece_x + 3 * i, ce);
        floe_q_rotate_inv(c->piece_x + 3 * i, qR, d);
        floe_q_mul(qn, qc, c->piece_q + 4 * i);
        floe_q_normalize(qn);
        memcpy(c->piece_q + 4 * i, qn, sizeof qn);
        c->radius = fmax(c->radius, floe_v3_norm(c->piece_x + 3 * i) + c->piece_r[i]);
    }
    floe_v3_copy(c->frame_x, ce);
    memcpy(c->frame_q, qR, sizeof qR);
    return &c->base;
fail:
    if (bad >= 0) floe_set_err(err, errlen, "compound: piece %d: %s", bad, msg);
    else floe_set_err(err, errlen, "compound: %s", msg);
    /* ownership is taken on failure too: c destroys the pieces it holds, the rest here */
    int owned = c && c->piece ? c->n : 0;
    if (c && c->piece) comp_destroy(&c->base);
    else if (c) { free(c->piece_x); free(c->piece_q); free(c->piece_r); free(c); }
    for (int i = owned; i < n; i++)
        if (pieces[i]) floe_geometry_destroy(pieces[i]);
    return NULL;
}
