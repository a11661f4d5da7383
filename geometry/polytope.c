/* polytope.c - convex polygons (2D) and polyhedra (3D) as exact signed distance functions
 * (ParticLS eq 27, Figs 3-5).
 *
 * phi(X): inside (all plane distances <= 0) the largest face-plane distance, which for a
 * convex body is minus the distance to the boundary; outside the distance to the nearest
 * boundary point, which lies on a face whose plane distance is positive (a face with
 * n.X <= d cannot be seen from X), found as the exact closest point on that face's triangles
 * (2D: on that edge). Mass properties are exact (divergence theorem: signed tetrahedra /
 * shoelace triangles from a reference point). The constructors put the body origin at the
 * centroid and the body axes along the principal axes of inertia (ascending moments; a
 * polygon is only turned about z), and record the input placement in frame_x/frame_q. */
#include "geometry_internal.h"
#include "floe_geometry.h"
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* private extension: triangles grouped by face */
typedef struct poly_priv {
    floe_polytope p;
    int *face_start; /* np + 1 (3D): triangles of face f are face_start[f] .. face_start[f+1]-1 */
    double *plane_soa; /* 3D: the planes by coordinate, np_soa each (floe_polytope_view) */
    int np_soa;
} poly_priv;


/* ---- exact closest points ---- */

/* closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5) */
static void closest_on_triangle(const double p[3], const double a[3], const double b[3], const double c[3],
                                double o[3]) {
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    floe_v3_sub(ab, b, a); floe_v3_sub(ac, c, a); floe_v3_sub(ap, p, a);
    double d1 = floe_v3_dot(ab, ap), d2 = floe_v3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) { floe_v3_copy(o, a); return; }
    floe_v3_sub(bp, p, b);
    double d3 = floe_v3_dot(ab, bp), d4 = floe_v3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) { floe_v3_copy(o, b); return; }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        floe_v3_copy(o, a); floe_v3_axpy(o, v, ab); return;
    }
    floe_v3_sub(cp, p, c);
    double d5 = floe_v3_dot(ab, cp), d6 = floe_v3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) { floe_v3_copy(o, c); return; }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        floe_v3_copy(o, a); floe_v3_axpy(o, w, ac); return;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6)), bc[3];
        floe_v3_sub(bc, c, b);
        floe_v3_copy(o, b); floe_v3_axpy(o, w, bc); return;
    }
    double den = 1 / (va + vb + vc), v = vb * den, w = vc * den;
    floe_v3_copy(o, a); floe_v3_axpy(o, v, ab); floe_v3_axpy(o, w, ac);
}

/* closest point of segment ab to p in the xy plane (z of the result = p z) */
static void closest_on_segment_xy(const double p[3], const double a[3], const double b[3], double o[3]) {
    double ex = b[0] - a[0], ey = b[1] - a[1];
    double L2 = ex * ex + ey * ey;
    double t = L2 > 0 ? ((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / L2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    o[0] = a[0] + t * ex; o[1] = a[1] + t * ey; o[2] = p[2];
}

/* Shared core: the signed distance, the nearest boundary point and the unit gradient. */
static double poly_eval(const floe_geometry *g, const double X[3], double P[3], double n[3]) {
    const poly_priv *pp = (const poly_priv *)g;
    const floe_polytope *p = &pp->p;
    double dmax = -INFINITY;
    int imax = 0;
    for (int i = 0; i < p->np; i++) {
        const double *pl = p->plane + 4 * i;
        double d = pl[0] * X[0] + pl[1] * X[1] + pl[2] * X[2] - pl[3];
        if (d > dmax) { dmax = d; imax = i; }
    }
    if (dmax <= 0) { /* inside: nearest face plane */
        const double *pl = p->plane + 4 * imax;
        if (n) floe_v3_copy(n, pl);
        if (P) { floe_v3_copy(P, X); floe_v3_axpy(P, -dmax, pl); }
        return dmax;
    }
    double best2 = INFINITY, bp[3] = {0, 0, 0};
    for (int i = 0; i < p->np; i++) {
        const double *pl = p->plane + 4 * i;
        double d = pl[0] * X[0] + pl[1] * X[1] + pl[2] * X[2] - pl[3];
        if (!(d > 0) || d * d >= best2) continue; /* the face is at least d away */
        if (p->dim == 2) {
            double o[3], e[3];
            closest_on_segment_xy(X, p->v + 3 * i, p->v + 3 * ((i + 1) % p->nv), o);
            floe_v3_sub(e, X, o);
            double e2 = e[0] * e[0] + e[1] * e[1];
            if (e2 < best2) { best2 = e2; floe_v3_copy(bp, o); }
        } else {
            for (int t = pp->face_start[i]; t < pp->face_start[i + 1]; t++) {
                const int *tr = p->tri + 3 * t;
                double o[3], e[3];
                closest_on_triangle(X, p->v + 3 * tr[0], p->v + 3 * tr[1], p->v + 3 * tr[2], o);
                floe_v3_sub(e, X, o);
                double e2 = floe_v3_dot(e, e);
                if (e2 < best2) { best2 = e2; floe_v3_copy(bp, o); }
            }
        }
    }
    double dist = sqrt(best2);
    if (dist < dmax) dist = dmax; /* rounding only: the distance is at least the plane distance */
    if (P) floe_v3_copy(P, bp);
    if (n) {
        double e[3];
        floe_v3_sub(e, X, bp);
        if (p->dim == 2) e[2] = 0;
        double m = floe_v3_norm(e);
        if (m > 0 && m >= 1e-3 * dmax) { floe_v3_scale(e, 1 / m); floe_v3_copy(n, e); }
        else floe_v3_copy(n, p->plane + 4 * imax); /* on the surface to rounding */
    }
    return dist;
}

static double poly_sdf(const floe_geometry *g, const double X[3]) { return poly_eval(g, X, NULL, NULL); }
static void poly_grad(const floe_geometry *g, const double X[3], double n[3]) { poly_eval(g, X, NULL, n); }
static void poly_project(const floe_geometry *g, const double X[3], double o[3]) { poly_eval(g, X, o, NULL); }
static double poly_radius(const floe_geometry *g) { return ((const floe_polytope *)g)->radius; }

static void poly_support(const floe_geometry *g, const double d[3], double o[3]) {
    const floe_polytope *p = (const floe_polytope *)g;
    int best = 0;
    double bv = -INFINITY;
    for (int i = 0; i < p->nv; i++) {
        double s = floe_v3_dot(p->v + 3 * i, d);
        if (s > bv) { bv = s; best = i; }
    }
    floe_v3_copy(o, p->v + 3 * best);
}
static const double *poly_vertices(const floe_geometry *g, int *count) {
    const floe_polytope *p = (const floe_polytope *)g;
    *count = p->nv;
    return p->v;
}

/* ---- exact moments ----
 * m[10]: volume (area), first moments x y z, second moments xx yy zz xy xz yz about the
 * origin of the coordinates given. */
static void poly3_moments(const double *v, const int *tri, int nt, double m[10]) {
    memset(m, 0, 10 * sizeof(double));
    for (int t = 0; t < nt; t++) {
        const double *a = v + 3 * tri[3 * t], *b = v + 3 * tri[3 * t + 1], *c = v + 3 * tri[3 * t + 2];
        double bc[3];
        floe_v3_cross(bc, b, c);
        double V = floe_v3_dot(a, bc) / 6; /* signed tetrahedron (0, a, b, c) */
        double s[3] = {a[0] + b[0] + c[0], a[1] + b[1] + c[1], a[2] + b[2] + c[2]};
        m[0] += V;
        for (int k = 0; k < 3; k++) m[1 + k] += V * s[k] / 4;
        /* int x_i x_j over the tetrahedron = V/20 (sum_k v_k,i v_k,j + s_i s_j) */
        static const int I[6] = {0, 1, 2, 0, 0, 1}, J[6] = {0, 1, 2, 1, 2, 2};
        for (int q = 0; q < 6; q++) {
            int i = I[q], j = J[q];
            m[4 + q] += V / 20 * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j]);
        }
    }
}
static void poly2_moments(const double *v, int nv, double m[10]) {
    memset(m, 0, 10 * sizeof(double));
    for (int i = 0; i < nv; i++) {
        const double *a = v + 3 * i, *b = v + 3 * ((i + 1) % nv);
        double cr = a[0] * b[1] - b[0] * a[1];
        m[0] += cr / 2;
        m[1] += cr * (a[0] + b[0]) / 6;
        m[2] += cr * (a[1] + b[1]) / 6;
        m[4] += cr * (a[0] * a[0] + a[0] * b[0] + b[0] * b[0]) / 12;
        m[5] += cr * (a[1] * a[1] + a[1] * b[1] + b[1] * b[1]) / 12;
        m[7] += cr * (a[0] * b[1] + 2 * a[0] * a[1] + 2 * b[0] * b[1] + b[0] * a[1]) / 24;
    }
}
/* centroid and the covariance C_ij = int (x - c)_i (x - c)_j at unit density */
static void moments_central(const double m[10], double c[3], double C[3][3]) {
    double V = m[0];
    for (int k = 0; k < 3; k++) c[k] = m[1 + k] / V;
    C[0][0] = m[4] - V * c[0] * c[0]; C[1][1] = m[5] - V * c[1] * c[1]; C[2][2] = m[6] - V * c[2] * c[2];
    C[0][1] = C[1][0] = m[7] - V * c[0] * c[1];
    C[0][2] = C[2][0] = m[8] - V * c[0] * c[2];
    C[1][2] = C[2][1] = m[9] - V * c[1] * c[2];
}
static void inertia_from_cov(const double C[3][3], double rho, double I[3][3]) {
    double tr = C[0][0] + C[1][1] + C[2][2];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) I[i][j] = rho * ((i == j ? tr : 0) - C[i][j]);
}

static int hull2d(const double *pts, int n, double tol, int *out);

/* dim 2 for a polyhedron: its section by the body plane z = 0, per unit thickness (as the
 * box gives its rectangle); the vertices of the section polygon are the crossings of the
 * edges with z = 0 */
static int section_moments(const floe_polytope *p, double m[10]) {
    int n = 0, nmax = 3 * p->nt;
    double *pts = malloc((size_t)nmax * 2 * sizeof *pts), *v = malloc((size_t)(nmax + 1) * 3 * sizeof *v);
    int *h = malloc((size_t)(nmax + 1) * sizeof *h);
    if (!pts || !v || !h) { free(pts); free(v); free(h); return FLOE_ENOMEM; }
    double tol = 1e-12 * p->radius;
    for (int t = 0; t < p->nt; t++)
        for (int k = 0; k < 3; k++) {
            const double *a = p->v + 3 * p->tri[3 * t + k], *b = p->v + 3 * p->tri[3 * t + (k + 1) % 3];
            if (fabs(a[2]) <= tol) { pts[2 * n] = a[0]; pts[2 * n + 1] = a[1]; n++; }
            else if ((a[2] < 0 && b[2] > tol) || (a[2] > 0 && b[2] < -tol)) {
                double s = a[2] / (a[2] - b[2]);
                pts[2 * n] = a[0] + s * (b[0] - a[0]); pts[2 * n + 1] = a[1] + s * (b[1] - a[1]); n++;
            }
        }
    int nh = n >= 3 ? hull2d(pts, n, 1e-12 * p->radius * p->radius, h) : 0;
    for (int i = 0; i < nh; i++) floe_v3_set(v + 3 * i, pts[2 * h[i]], pts[2 * h[i] + 1], 0);
    if (nh >= 3) poly2_moments(v, nh, m);
    free(pts); free(v); free(h);
    return nh < 0 ? FLOE_ENOMEM : nh < 3 ? FLOE_EINVAL : FLOE_OK;
}

/* dim 3 for a polygon (an infinite prism) is not supported: FLOE_ENOTSUP */
static int poly_mass(const floe_geometry *g, int dim, double rho, floe_mass_properties *o) {
    const floe_polytope *p = (const floe_polytope *)g;
    if (dim != 2 && dim != 3) return FLOE_EINVAL;
    if (p->dim == 2 && dim == 3) return FLOE_ENOTSUP;
    double m[10], c[3], C[3][3], I[3][3];
    if (dim == 3) poly3_moments(p->v, p->tri, p->nt, m);
    else if (p->dim == 2) poly2_moments(p->v, p->nv, m);
    else FLOE_TRY(section_moments(p, m));
    moments_central(m, c, C);
    if (dim == 2) { C[0][2] = C[2][0] = C[1][2] = C[2][1] = C[2][2] = 0; }
    inertia_from_cov(C, rho, I);
    o->volume = m[0];
    o->mass = rho * m[0];
    floe_v3_copy(o->centroid, c);
    for (int k = 0; k < 3; k++) o->inertia[k] = I[k][k];
    o->quadrature_error = 0;
    double dm = fmax(I[0][0], fmax(I[1][1], I[2][2]));
    o->off_axis = dm > 0 ? fmax(fabs(I[0][1]), fmax(fabs(I[0][2]), fabs(I[1][2]))) / dm : 0;
    return FLOE_OK;
}

static void poly_destroy(floe_geometry *g) {
    poly_priv *pp = (poly_priv *)g;
    if (!pp) return;
    free(pp->p.v); free(pp->p.plane); free(pp->p.tri); free(pp->face_start); free(pp->plane_soa);
    free(pp);
}

/* its planes and corners as they are (a polygon's lie in the plane z = 0) */
static void poly_polytope(const floe_geometry *g, int dim, floe_polytope_view *out) {
    const floe_polytope *p = (const floe_polytope *)g;
    (void)dim;
    out->plane = p->plane;
    out->np = p->np;
    out->v = p->v;
    out->nv = p->nv;
    out->ccw = p->dim == 2; /* a polygon's hull, counter-clockwise */
    out->plane_soa = ((const poly_priv *)g)->plane_soa;
    out->np_soa = ((const poly_priv *)g)->np_soa;
}

/* the planes by coordinate (floe_polytope_view.plane_soa), padded to a multiple of 8 with
 * (0, 0, 0, +inf); FLOE_ENOMEM */
static int poly_planes_soa(poly_priv *pp) {
    const floe_polytope *p = &pp->p;
    const int m = (p->np + 7) / 8 * 8;
    double *s = malloc((size_t)(4 * m) * sizeof *s);
    if (!s) return FLOE_ENOMEM;
    for (int k = 0; k < m; k++)
        for (int c = 0; c < 4; c++) s[c * m + k] = k < p->np ? p->plane[4 * k + c] : c == 3 ? INFINITY : 0.0;
    pp->plane_soa = s;
    pp->np_soa = m;
    return FLOE_OK;
}
static int poly_dimension(const floe_geometry *g) { return ((const floe_polytope *)g)->dim; }

/* one class for both dimensions (`dimension` tells a polygon from a polyhedron): the name is
 * "polyhedron" for polygons too */
const floe_geometry_class floe_polytope_class = {
    .version = 1, .name = "polyhedron", .kind = FLOE_GEOM_USER, .sdf = poly_sdf, .gradient = poly_grad,
    .project = poly_project, .bounding_radius = poly_radius, .mass_properties = poly_mass,
    .destroy = poly_destroy, .support = poly_support, .vertices = poly_vertices, .polytope = poly_polytope,
    .dimension = poly_dimension};
/* ---- 2D convex hull (Andrew's monotone chain) on points pts (2 each); writes the hull
 * indices counter-clockwise into out (size >= n + 1), returns their count. Collinear and
 * duplicate points (|cross| <= tol) are dropped. ---- */
static const double *hull_pts_;
static int hull_cmp(const void *a, const void *b) {
    const double *p = hull_pts_ + 2 * *(const int *)a, *q = hull_pts_ + 2 * *(const int *)b;
    if (p[0] != q[0]) return p[0] < q[0] ? -1 : 1;
    if (p[1] != q[1]) return p[1] < q[1] ? -1 : 1;
    return 0;
}
static double cross2(const double *o, const double *a, const double *b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}
static int hull2d(const double *pts, int n, double tol, int *out) {
    int *idx = malloc((size_t)n * sizeof *idx);
    if (!idx) return -1;
    for (int i = 0; i < n; i++) idx[i] = i;
    hull_pts_ = pts; /* qsort has no context argument in C11; single-threaded constructors */
    qsort(idx, (size_t)n, sizeof *idx, hull_cmp);
    int k = 0;
    for (int i = 0; i < n; i++) { /* lower */
        while (k >= 2 && cross2(pts + 2 * out[k - 2], pts + 2 * out[k - 1], pts + 2 * idx[i]) <= tol) k--;
        out[k++] = idx[i];
    }
    for (int i = n - 2, lo = k + 1; i >= 0; i--) { /* upper */
        while (k >= lo && cross2(pts + 2 * out[k - 2], pts + 2 * out[k - 1], pts + 2 * idx[i]) <= tol) k--;
        out[k++] = idx[i];
    }
    free(idx);
    return k > 1 ? k - 1 : k; /* the last point repeats the first */
}

/* ---- polygon ---- */
floe_geometry *floe_polygon_create(const double *xy, int n, char *err, size_t errlen) {
    if (!xy || n < 3) { floe_set_err(err, errlen, "polygon: need at least 3 points (got %d)", xy ? n : 0); return NULL; }
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < 2 * n; i++) {
        if (!isfinite(xy[i])) { floe_set_err(err, errlen, "polygon: point %d is not finite", i / 2); return NULL; }
        lo[i % 2] = fmin(lo[i % 2], xy[i]); hi[i % 2] = fmax(hi[i % 2], xy[i]);
    }
    double L = hypot(hi[0] - lo[0], hi[1] - lo[1]);
    int *h = malloc((size_t)(n + 1) * sizeof *h);
    if (!h) { floe_set_err(err, errlen, "polygon: out of memory"); return NULL; }
    int m = L > 0 ? hull2d(xy, n, 1e-12 * L * L, h) : 0;
    if (m < 3) {
        free(h);
        floe_set_err(err, errlen, m < 0 ? "polygon: out of memory" : "polygon: the points are collinear (zero area)");
        return NULL;
    }
    poly_priv *pp = calloc(1, sizeof *pp);
    floe_polytope *p = pp ? &pp->p : NULL;
    if (p) { p->v = malloc((size_t)m * 3 * sizeof(double)); p->plane = malloc((size_t)m * 4 * sizeof(double)); }
    if (!p || !p->v || !p->plane) {
        free(h);
        if (pp) poly_destroy(&pp->p.base);
        floe_set_err(err, errlen, "polygon: out of memory");
        return NULL;
    }
    p->base.klass = &floe_polytope_class;
    p->dim = 2; p->nv = m; p->np = m; p->nt = 0;
    for (int i = 0; i < m; i++) floe_v3_set(p->v + 3 * i, xy[2 * h[i]], xy[2 * h[i] + 1], 0);
    free(h);
    /* centroid and principal angle, from a reference vertex for accuracy */
    double ref[3] = {p->v[0], p->v[1], 0}, mm[10], c[3], C[3][3];
    for (int i = 0; i < m; i++) { p->v[3 * i] -= ref[0]; p->v[3 * i + 1] -= ref[1]; }
    poly2_moments(p->v, m, mm);
    if (!(mm[0] > 1e-12 * L * L)) {
        poly_destroy(&pp->p.base);
        floe_set_err(err, errlen, "polygon: zero area");
        return NULL;
    }
    moments_central(mm, c, C);
    double th = 0.5 * atan2(2 * C[0][1], C[0][0] - C[1][1]); /* body x along the largest spread */
    double cs = cos(th), sn = sin(th);
    for (int i = 0; i < m; i++) {
        double x = p->v[3 * i] - c[0], y = p->v[3 * i + 1] - c[1];
        p->v[3 * i] = cs * x + sn * y;
        p->v[3 * i + 1] = -sn * x + cs * y;
    }
    p->radius = 0;
    for (int i = 0; i < m; i++) {
        const double *a = p->v + 3 * i, *b = p->v + 3 * ((i + 1) % m);
        double ex = b[0] - a[0], ey = b[1] - a[1], el = hypot(ex, ey);
        double *pl = p->plane + 4 * i;
        pl[0] = ey / el; pl[1] = -ex / el; pl[2] = 0;
        pl[3] = pl[0] * a[0] + pl[1] * a[1];
        p->radius = fmax(p->radius, hypot(a[0], a[1]));
    }
    floe_v3_set(p->frame_x, ref[0] + c[0], ref[1] + c[1], 0);
    p->frame_q[0] = cos(0.5 * th); p->frame_q[1] = 0; p->frame_q[2] = 0; p->frame_q[3] = sin(0.5 * th);
    return &p->base;
}

/* ---- polyhedron core ---- */

static int edge_cmp(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}
/* every directed edge (a, b) once, and (b, a) once: a closed, consistently oriented surface */
static int check_closed(const int *tri, int nt, int nv) {
    size_t ne = 3 * (size_t)nt;
    uint64_t *e = malloc(ne * sizeof *e);
    if (!e) return -1;
    for (int t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint64_t a = (uint64_t)tri[3 * t + k], b = (uint64_t)tri[3 * t + (k + 1) % 3];
            e[3 * (size_t)t + k] = a * (uint64_t)nv + b;
        }
    qsort(e, ne, sizeof *e, edge_cmp);
    int ok = 1;
    for (size_t i = 0; i < ne && ok; i++) {
        if (i + 1 < ne && e[i + 1] == e[i]) ok = 0;
        uint64_t a = e[i] / (uint64_t)nv, b = e[i] % (uint64_t)nv, r = b * (uint64_t)nv + a;
        if (a == b || !bsearch(&r, e, ne, sizeof *e, edge_cmp)) ok = 0;
    }
    free(e);
    return ok;
}

/* Assemble from vertices V0 (nv, welded), unit outward face planes P (nf) and the face
 * vertex lists fv[fn[f] .. fn[f+1]) (counter-clockwise seen from outside): the used vertices
 * renumbered, the faces fan-triangulated, the closedness check, the exact mass and the move
 * to the principal frame. Linear in the size (the check sorts the edges). Takes nothing over;
 * L is the size for the zero-volume test. */
static floe_geometry *assemble_polyhedron(const double *V0, int nv, const double *P, int nf, const int *fv, const int *fn,
                                          double L, const char *what, const char *open_msg, char *err, size_t errlen) {
    floe_geometry *result = NULL;
    double *V = NULL;
    int *used = NULL, *tri = NULL, *fstart = NULL;
    poly_priv *pp = NULL;
    int nfv = fn[nf];
    /* keep the vertices used by faces, renumbered */
    used = malloc((size_t)nv * sizeof *used);
    if (!used) goto oom;
    for (int j = 0; j < nv; j++) used[j] = -1;
    int nu = 0;
    for (int k = 0; k < nfv; k++)
        if (used[fv[k]] < 0) used[fv[k]] = nu++;
    int nt = nfv - 2 * nf;
    tri = malloc((size_t)nt * 3 * sizeof *tri);
    fstart = malloc(((size_t)nf + 1) * sizeof *fstart);
    if (!tri || !fstart) goto oom;
    int t = 0;
    for (int f = 0; f < nf; f++) {
        fstart[f] = t;
        const int *F = fv + fn[f];
        for (int k = 1; k + 1 < fn[f + 1] - fn[f]; k++, t++) {
            tri[3 * t] = used[F[0]]; tri[3 * t + 1] = used[F[k]]; tri[3 * t + 2] = used[F[k + 1]];
        }
    }
    fstart[nf] = t;
    V = malloc((size_t)nu * 3 * sizeof *V);
    if (!V) goto oom;
    for (int j = 0; j < nv; j++)
        if (used[j] >= 0) floe_v3_copy(V + 3 * used[j], V0 + 3 * j);
    int closed = check_closed(tri, nt, nu);
    if (closed < 0) goto oom;
    if (!closed) { floe_set_err(err, errlen, "%s: %s", what, open_msg); goto fail; }
    /* mass from a reference point (the vertex mean) for accuracy */
    double ref[3] = {0, 0, 0}, m[10], c[3], C[3][3], I[3][3], l[3], R[3][3];
    for (int j = 0; j < nu; j++) floe_v3_axpy(ref, 1.0 / nu, V + 3 * j);
    for (int j = 0; j < nu; j++) floe_v3_sub(V + 3 * j, V + 3 * j, ref);
    poly3_moments(V, tri, nt, m);
    if (!(m[0] > 1e-12 * L * L * L)) { floe_set_err(err, errlen, "%s: zero volume (%.3g)", what, m[0]); goto fail; }
    moments_central(m, c, C);
    inertia_from_cov(C, 1.0, I);
    floe_sym3_eigen(I, l, R);
    /* X_input = R X_body + (ref + c) */
    pp = calloc(1, sizeof *pp);
    if (!pp) goto oom;
    floe_polytope *p = &pp->p;
    p->base.klass = &floe_polytope_class;
    p->dim = 3; p->nv = nu; p->np = nf; p->nt = nt;
    p->v = V; p->tri = tri; pp->face_start = fstart;
    V = NULL; tri = NULL; fstart = NULL;
    p->plane = malloc((size_t)nf * 4 * sizeof(double));
    if (!p->plane) goto oom;
    p->radius = 0;
    for (int j = 0; j < nu; j++) {
        double x[3], y[3];
        floe_v3_sub(x, p->v + 3 * j, c);
        for (int k = 0; k < 3; k++) y[k] = R[0][k] * x[0] + R[1][k] * x[1] + R[2][k] * x[2];
        floe_v3_copy(p->v + 3 * j, y);
        p->radius = fmax(p->radius, floe_v3_norm(y));
    }
    double cx[3];
    floe_v3_add(cx, ref, c);
    for (int f = 0; f < nf; f++) {
        const double *q = P + 4 * f;
        double *o = p->plane + 4 * f;
        for (int k = 0; k < 3; k++) o[k] = R[0][k] * q[0] + R[1][k] * q[1] + R[2][k] * q[2];
        /* the offset from the face vertices (consistent with the stored vertices) */
        const int *F = fv + fn[f];
        double s = 0;
        int cnt = fn[f + 1] - fn[f];
        for (int k = 0; k < cnt; k++) s += floe_v3_dot(o, p->v + 3 * used[F[k]]);
        o[3] = s / cnt;
    }
    if (poly_planes_soa(pp)) goto oom;
    floe_v3_copy(p->frame_x, cx);
    floe_q_from_matrix(p->frame_q, R);
    result = &p->base;
    pp = NULL;
    goto done;
oom:
    floe_set_err(err, errlen, "%s: out of memory", what);
fail:
done:
    if (pp) poly_destroy(&pp->p.base);
    free(V); free(used); free(tri); free(fstart);
    return result;
}

/* Build from candidate vertices (all on the boundary of the convex region or inside it) and
 * unit outward planes: each plane's vertices (within tol) form a face, ordered as their 2D
 * convex hull in the plane; planes with fewer than 3 non-collinear vertices are redundant and
 * dropped, as are repeated planes. Then the checks (closed, volume), the exact mass, and the
 * move to the principal frame. `what` prefixes the messages. */
static floe_geometry *build_polyhedron(const double *cand, int nc, const double *pl, int npl, const char *what,
                                       const char *open_msg, char *err, size_t errlen) {
    floe_geometry *result = NULL;
    double *V = NULL, *P = NULL, *uv = NULL;
    int *vid = NULL, *fv = NULL, *fn = NULL, *hidx = NULL;
    if (nc < 4) { floe_set_err(err, errlen, "%s: %s", what, nc == 0 ? open_msg : "zero volume (fewer than 4 vertices)"); return NULL; }
    /* weld the candidates */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < nc; i++)
        for (int k = 0; k < 3; k++) { lo[k] = fmin(lo[k], cand[3 * i + k]); hi[k] = fmax(hi[k], cand[3 * i + k]); }
    double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    double L = floe_v3_norm(ext);
    if (!(L > 0) || !isfinite(L)) { floe_set_err(err, errlen, "%s: zero volume (all vertices coincide)", what); return NULL; }
    double tol_dup = 1e-10 * L, tol_on = 1e-9 * L;
    V = malloc((size_t)nc * 3 * sizeof *V);
    if (!V) goto oom;
    int nv = 0;
    for (int i = 0; i < nc; i++) {
        const double *x = cand + 3 * i;
        int dup = 0;
        for (int j = 0; j < nv && !dup; j++) {
            double d[3];
            floe_v3_sub(d, x, V + 3 * j);
            if (floe_v3_norm(d) <= tol_dup) dup = 1;
        }
        if (!dup) { floe_v3_copy(V + 3 * nv, x); nv++; }
    }
    /* flatness: four affinely independent vertices */
    {
        int i1 = 0, i2 = 0;
        double best = -1, d[3], e[3], nrm[3];
        for (int i = 1; i < nv; i++) { floe_v3_sub(d, V + 3 * i, V); if (floe_v3_norm(d) > best) { best = floe_v3_norm(d); i1 = i; } }
        floe_v3_sub(d, V + 3 * i1, V);
        double dl = floe_v3_norm(d);
        best = -1;
        for (int i = 1; i < nv; i++) {
            floe_v3_sub(e, V + 3 * i, V); floe_v3_cross(nrm, d, e);
            if (floe_v3_norm(nrm) / dl > best) { best = floe_v3_norm(nrm) / dl; i2 = i; }
        }
        if (!(best > tol_on)) { floe_set_err(err, errlen, "%s: zero volume (the vertices are collinear)", what); goto fail; }
        floe_v3_sub(e, V + 3 * i2, V); floe_v3_cross(nrm, d, e); floe_v3_scale(nrm, 1 / floe_v3_norm(nrm));
        best = 0;
        for (int i = 1; i < nv; i++) { floe_v3_sub(e, V + 3 * i, V); best = fmax(best, fabs(floe_v3_dot(e, nrm))); }
        if (!(best > tol_on)) { floe_set_err(err, errlen, "%s: zero volume (the vertices are coplanar: flat)", what); goto fail; }
    }
    /* faces */
    P = malloc((size_t)npl * 4 * sizeof *P);
    fv = malloc(((size_t)npl * nv + 1) * sizeof *fv);  /* face vertex lists, concatenated */
    fn = calloc((size_t)npl + 1, sizeof *fn);          /* face f: fv[fn[f] .. fn[f+1]) */
    vid = malloc((size_t)nv * sizeof *vid);
    uv = malloc((size_t)nv * 2 * sizeof *uv);
    hidx = malloc(((size_t)nv + 1) * sizeof *hidx);
    if (!P || !fv || !fn || !vid || !uv || !hidx) goto oom;
    int nf = 0, nfv = 0;
    for (int i = 0; i < npl; i++) {
        const double *q = pl + 4 * i;
        int rep = 0;
        for (int f = 0; f < nf && !rep; f++)
            if (floe_v3_dot(q, P + 4 * f) > 1 - 1e-12) rep = 1;
        if (rep) continue;
        int cnt = 0;
        for (int j = 0; j < nv; j++)
            if (fabs(floe_v3_dot(q, V + 3 * j) - q[3]) <= tol_on) vid[cnt++] = j;
        if (cnt < 3) continue;
        /* in-plane basis u, w with (u, w, n) right-handed: ccw in (u, w) = ccw from outside */
        double u[3], w[3], a[3] = {1, 0, 0};
        if (fabs(q[0]) > 0.6) floe_v3_set(a, 0, 1, 0);
        floe_v3_cross(u, a, q); floe_v3_scale(u, 1 / floe_v3_norm(u));
        floe_v3_cross(w, q, u);
        for (int j = 0; j < cnt; j++) {
            uv[2 * j] = floe_v3_dot(V + 3 * vid[j], u);
            uv[2 * j + 1] = floe_v3_dot(V + 3 * vid[j], w);
        }
        int h = hull2d(uv, cnt, 1e-12 * L * L, hidx);
        if (h < 0) goto oom;
        if (h < 3) continue;
        memcpy(P + 4 * nf, q, 4 * sizeof *P);
        for (int j = 0; j < h; j++) fv[nfv++] = vid[hidx[j]];
        fn[++nf] = nfv;
    }
    if (nf < 4) { floe_set_err(err, errlen, "%s: %s", what, open_msg); goto fail; }
    result = assemble_polyhedron(V, nv, P, nf, fv, fn, L, what, open_msg, err, errlen);
    goto done;
oom:
    floe_set_err(err, errlen, "%s: out of memory", what);
fail:
done:
    free(V); free(P); free(uv); free(vid); free(fv); free(fn); free(hidx);
    return result;
}

/* Faces given (e.g. a convex hull with coplanar triangles merged): no searching, linear in
 * the size; the faces must be convex polygons, counter-clockwise seen from outside, with
 * unit outward planes. */
floe_geometry *floe_polyhedron_from_faces(const double *v, int nv, const int *fstart, const int *fv, int nf,
                                          const double *planes, char *err, size_t errlen) {
    const char *what = "polyhedron from faces";
    if (!v || !fstart || !fv || !planes || nv < 4 || nf < 4) {
        floe_set_err(err, errlen, "%s: need at least 4 vertices and 4 faces", what);
        return NULL;
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            if (!isfinite(v[3 * i + k])) { floe_set_err(err, errlen, "%s: vertex %d is not finite", what, i); return NULL; }
            lo[k] = fmin(lo[k], v[3 * i + k]);
            hi[k] = fmax(hi[k], v[3 * i + k]);
        }
    for (int f = 0; f < nf; f++)
        if (fstart[f + 1] - fstart[f] < 3) { floe_set_err(err, errlen, "%s: face %d has fewer than 3 vertices", what, f); return NULL; }
    for (int k = 0; k < fstart[nf]; k++)
        if (fv[k] < 0 || fv[k] >= nv) { floe_set_err(err, errlen, "%s: a face vertex index is out of range", what); return NULL; }
    double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    return assemble_polyhedron(v, nv, planes, nf, fv, fstart, floe_v3_norm(ext), what, "not closed", err, errlen);
}

floe_geometry *floe_polyhedron_from_planes(const double *planes, int np, char *err, size_t errlen) {
    const char *what = "polyhedron from planes";
    if (!planes || np < 4) { floe_set_err(err, errlen, "%s: need at least 4 planes (got %d)", what, planes ? np : 0); return NULL; }
    double *pl = malloc((size_t)np * 4 * sizeof *pl);
    if (!pl) { floe_set_err(err, errlen, "%s: out of memory", what); return NULL; }
    double dmax = 0;
    for (int i = 0; i < np; i++) {
        const double *q = planes + 4 * i;
        double nn = floe_v3_norm(q);
        if (!isfinite(nn + q[3]) || !(nn > 0)) {
            free(pl);
            floe_set_err(err, errlen, "%s: plane %d has a zero or non-finite normal", what, i);
            return NULL;
        }
        for (int k = 0; k < 4; k++) pl[4 * i + k] = q[k] / nn;
        dmax = fmax(dmax, fabs(pl[4 * i + 3]));
    }
    /* vertex enumeration: every non-singular triple of planes, kept when feasible
     * (O(np^4) in the worst case; fine for the tens of faces of a grain) */
    int cap = 64, nc = 0, spans = 0;
    double *cand = malloc((size_t)cap * 3 * sizeof *cand);
    if (!cand) { free(pl); floe_set_err(err, errlen, "%s: out of memory", what); return NULL; }
    for (int i = 0; i < np; i++)
        for (int j = i + 1; j < np; j++) {
            double nij[3];
            floe_v3_cross(nij, pl + 4 * i, pl + 4 * j);
            if (floe_v3_norm(nij) < 1e-12) continue;
            for (int k = j + 1; k < np; k++) {
                const double *a = pl + 4 * i, *b = pl + 4 * j, *c = pl + 4 * k;
                double det = floe_v3_dot(nij, c);
                if (fabs(det) < 1e-12) continue;
                spans = 1;
                double bc[3], ca[3], X[3] = {0, 0, 0};
                floe_v3_cross(bc, b, c); floe_v3_cross(ca, c, a);
                floe_v3_axpy(X, a[3] / det, bc); floe_v3_axpy(X, b[3] / det, ca); floe_v3_axpy(X, c[3] / det, nij);
                double tol = 1e-10 * fmax(floe_v3_norm(X), dmax);
                int ok = 1;
                for (int m = 0; m < np && ok; m++)
                    if (floe_v3_dot(pl + 4 * m, X) - pl[4 * m + 3] > tol) ok = 0;
                if (!ok) continue;
                if (nc == cap) {
                    cap *= 2;
                    double *t = realloc(cand, (size_t)cap * 3 * sizeof *t);
                    if (!t) { free(cand); free(pl); floe_set_err(err, errlen, "%s: out of memory", what); return NULL; }
                    cand = t;
                }
                floe_v3_copy(cand + 3 * nc, X);
                nc++;
            }
        }
    /* recession cone {d : n_i.d <= 0 for all i}: when the normals span 3D it is pointed, and
     * non-zero exactly when it has an extreme ray, which is +-(n_i x n_j) for a pair */
    double ray[3] = {0, 0, 0};
    int unbounded = 0;
    for (int i = 0; i < np && spans && !unbounded; i++)
        for (int j = i + 1; j < np && !unbounded; j++) {
            double r[3];
            floe_v3_cross(r, pl + 4 * i, pl + 4 * j);
            double rn = floe_v3_norm(r);
            if (rn < 1e-12) continue;
            floe_v3_scale(r, 1 / rn);
            for (int sg = -1; sg <= 1 && !unbounded; sg += 2) {
                int ok = 1;
                for (int m = 0; m < np && ok; m++)
                    if (sg * floe_v3_dot(pl + 4 * m, r) > 1e-12) ok = 0;
                if (ok) { unbounded = 1; floe_v3_copy(ray, r); floe_v3_scale(ray, sg); }
            }
        }
    floe_geometry *g = NULL;
    if (spans && nc > 0 && unbounded)
        floe_set_err(err, errlen, "%s: unbounded (the set extends to infinity along (%.3g, %.3g, %.3g))", what, ray[0] + 0.0, ray[1] + 0.0,
                ray[2] + 0.0);
    else if (!spans) floe_set_err(err, errlen, "%s: unbounded (the normals do not span 3D: the set contains a line) or empty", what);
    else if (nc == 0) floe_set_err(err, errlen, "%s: empty (no point satisfies all the half-spaces)", what);
    else g = build_polyhedron(cand, nc, pl, np, what, "unbounded (the half-spaces do not enclose a finite volume)", err, errlen);
    free(cand); free(pl);
    return g;
}

floe_geometry *floe_polyhedron_from_mesh(const double *v, int nv, const int *tri, int nt, char *err, size_t errlen) {
    const char *what = "polyhedron from mesh";
    if (!v || !tri || nv < 4 || nt < 4) { floe_set_err(err, errlen, "%s: need at least 4 vertices and 4 triangles", what); return NULL; }
    for (int i = 0; i < 3 * nv; i++)
        if (!isfinite(v[i])) { floe_set_err(err, errlen, "%s: vertex %d is not finite", what, i / 3); return NULL; }
    for (int i = 0; i < 3 * nt; i++)
        if (tri[i] < 0 || tri[i] >= nv) { floe_set_err(err, errlen, "%s: triangle %d has vertex index %d out of range", what, i / 3, tri[i]); return NULL; }
    int closed = check_closed(tri, nt, nv);
    if (closed < 0) { floe_set_err(err, errlen, "%s: out of memory", what); return NULL; }
    if (!closed) {
        floe_set_err(err, errlen, "%s: not closed (every edge must be shared by exactly two triangles of opposite orientation; weld duplicate vertices)", what);
        return NULL;
    }
    /* scale and orientation */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, ref[3] = {0, 0, 0};
    for (int i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) { lo[k] = fmin(lo[k], v[3 * i + k]); hi[k] = fmax(hi[k], v[3 * i + k]); }
    for (int k = 0; k < 3; k++) ref[k] = 0.5 * (lo[k] + hi[k]);
    double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}, L = floe_v3_norm(ext);
    double vol = 0;
    for (int t = 0; t < nt; t++) {
        double a[3], b[3], c[3], bc[3];
        floe_v3_sub(a, v + 3 * tri[3 * t], ref); floe_v3_sub(b, v + 3 * tri[3 * t + 1], ref); floe_v3_sub(c, v + 3 * tri[3 * t + 2], ref);
        floe_v3_cross(bc, b, c);
        vol += floe_v3_dot(a, bc) / 6;
    }
    if (!(fabs(vol) > 1e-12 * L * L * L)) { floe_set_err(err, errlen, "%s: zero volume (flat mesh)", what); return NULL; }
    double sgn = vol > 0 ? 1 : -1; /* accept either orientation */
    double *pl = malloc((size_t)nt * 4 * sizeof *pl), *cand = malloc((size_t)3 * nt * 3 * sizeof *cand);
    if (!pl || !cand) { free(pl); free(cand); floe_set_err(err, errlen, "%s: out of memory", what); return NULL; }
    int npl = 0;
    for (int t = 0; t < nt; t++) {
        const double *a = v + 3 * tri[3 * t], *b = v + 3 * tri[3 * t + 1], *c = v + 3 * tri[3 * t + 2];
        for (int k = 0; k < 3; k++) floe_v3_copy(cand + 9 * t + 3 * k, v + 3 * tri[3 * t + k]);
        double ab[3], ac[3], n[3];
        floe_v3_sub(ab, b, a); floe_v3_sub(ac, c, a); floe_v3_cross(n, ab, ac);
        double nn = floe_v3_norm(n);
        if (!(nn > 1e-12 * L * L)) continue; /* sliver: no reliable normal */
        floe_v3_scale(n, sgn / nn);
        double d = floe_v3_dot(n, a);
        for (int i = 0; i < nv; i++)
            if (floe_v3_dot(n, v + 3 * i) - d > 1e-9 * L) {
                free(pl); free(cand);
                floe_set_err(err, errlen, "%s: not convex (vertex %d is outside the plane of triangle %d by %.3g)", what, i,
                        t, floe_v3_dot(n, v + 3 * i) - d);
                return NULL;
            }
        int same = 0;
        for (int f = 0; f < npl && !same; f++)
            if (floe_v3_dot(n, pl + 4 * f) > 1 - 1e-10 && fabs(d - pl[4 * f + 3]) <= 1e-9 * L) same = 1;
        if (same) continue;
        floe_v3_copy(pl + 4 * npl, n);
        pl[4 * npl + 3] = d;
        npl++;
    }
    floe_geometry *g = build_polyhedron(cand, 3 * nt, pl, npl, what, "not closed after merging coplanar faces", err, errlen);
    free(pl); free(cand);
    return g;
}

floe_geometry *floe_prism_create(const double *xy, int n, double height, char *err, size_t errlen) {
    const char *what = "prism";
    if (!(height > 0) || !isfinite(height)) { floe_set_err(err, errlen, "%s: height must be positive and finite (got %g)", what, height); return NULL; }
    if (!xy || n < 3) { floe_set_err(err, errlen, "%s: need at least 3 points (got %d)", what, xy ? n : 0); return NULL; }
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < 2 * n; i++) {
        if (!isfinite(xy[i])) { floe_set_err(err, errlen, "%s: point %d is not finite", what, i / 2); return NULL; }
        lo[i % 2] = fmin(lo[i % 2], xy[i]); hi[i % 2] = fmax(hi[i % 2], xy[i]);
    }
    double L = hypot(hi[0] - lo[0], hi[1] - lo[1]);
    int *h = malloc((size_t)(n + 1) * sizeof *h);
    if (!h) { floe_set_err(err, errlen, "%s: out of memory", what); return NULL; }
    int m = L > 0 ? hull2d(xy, n, 1e-12 * L * L, h) : 0;
    if (m < 3) { free(h); floe_set_err(err, errlen, m < 0 ? "%s: out of memory" : "%s: the points are collinear (zero area)", what); return NULL; }
    double *pl = malloc((size_t)(m + 2) * 4 * sizeof *pl), *cand = malloc((size_t)2 * m * 3 * sizeof *cand);
    if (!pl || !cand) { free(h); free(pl); free(cand); floe_set_err(err, errlen, "%s: out of memory", what); return NULL; }
    for (int i = 0; i < m; i++) {
        const double *a = xy + 2 * h[i], *b = xy + 2 * h[(i + 1) % m];
        double ex = b[0] - a[0], ey = b[1] - a[1], el = hypot(ex, ey);
        double *q = pl + 4 * i;
        q[0] = ey / el; q[1] = -ex / el; q[2] = 0; q[3] = q[0] * a[0] + q[1] * a[1];
        floe_v3_set(cand + 6 * i, a[0], a[1], -0.5 * height);
        floe_v3_set(cand + 6 * i + 3, a[0], a[1], 0.5 * height);
    }
    free(h);
    double *q = pl + 4 * m;
    q[0] = 0; q[1] = 0; q[2] = 1; q[3] = 0.5 * height;
    q[4] = 0; q[5] = 0; q[6] = -1; q[7] = 0.5 * height;
    floe_geometry *g = build_polyhedron(cand, 2 * m, pl, m + 2, what, "not closed (internal error)", err, errlen);
    free(pl); free(cand);
    return g;
}
