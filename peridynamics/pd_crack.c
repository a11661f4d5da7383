/* pd_crack.c - pre-cracks of peridynamic bodies (floe_pd.h, "pre-cracks"): a polyline (2D)
 * or a convex planar polygon (3D) that removes every bond crossing it from the families,
 * and the check for holes narrower than the horizon (bonds that bridge them). */
#include <stdlib.h>
#include <string.h>

#include "floe_pd.h"
#include "pd_par.h"

floe_pd_crack floe_pd_crack_segment(const double a[3], const double b[3])
{
    floe_pd_crack c;
    memset(&c, 0, sizeof c);
    c.n = 2;
    floe_v3_copy(c.p[0], a);
    floe_v3_copy(c.p[1], b);
    return c;
}

floe_pd_crack floe_pd_crack_rectangle(const double corner[3], const double e1[3], const double e2[3])
{
    floe_pd_crack c;
    memset(&c, 0, sizeof c);
    c.n = 4;
    floe_v3_copy(c.p[0], corner);
    floe_v3_add(c.p[1], corner, e1);
    floe_v3_add(c.p[2], c.p[1], e2);
    floe_v3_add(c.p[3], corner, e2);
    return c;
}

/* a crack ready for the tests: 3D unit normal (Newell), size (largest extent), bounding box */
typedef struct crack_prep {
    const floe_pd_crack *c;
    int dim;
    double nrm[3], size, lo[3], hi[3];
} crack_prep;

static void crack_prepare(crack_prep *q, const floe_pd_crack *c, int dim)
{
    q->c = c;
    q->dim = dim;
    floe_v3_set(q->nrm, 0, 0, 0);
    floe_v3_copy(q->lo, c->p[0]);
    floe_v3_copy(q->hi, c->p[0]);
    for (int k = 0; k < c->n; k++)
        for (int d = 0; d < 3; d++) {
            q->lo[d] = fmin(q->lo[d], c->p[k][d]);
            q->hi[d] = fmax(q->hi[d], c->p[k][d]);
        }
    if (dim == 2) { q->lo[2] = -INFINITY; q->hi[2] = INFINITY; }
    q->size = 0;
    for (int d = 0; d < dim; d++) q->size = fmax(q->size, q->hi[d] - q->lo[d]);
    if (dim == 3) {
        for (int k = 1; k + 1 < c->n; k++) {
            double a[3], b[3], x[3];
            floe_v3_sub(a, c->p[k], c->p[0]);
            floe_v3_sub(b, c->p[k + 1], c->p[0]);
            floe_v3_cross(x, a, b);
            floe_v3_axpy(q->nrm, 1.0, x);
        }
        double L = floe_v3_norm(q->nrm);
        if (L > 0) floe_v3_scale(q->nrm, 1.0 / L);
    }
}

int floe_pd_crack_check(const floe_pd_crack *c, int dim)
{
    if (!c || (dim != 2 && dim != 3) || c->n < dim || c->n > FLOE_PD_CRACK_MAX_POINTS) return FLOE_EINVAL;
    for (int k = 0; k < c->n; k++)
        for (int d = 0; d < dim; d++)
            if (!isfinite(c->p[k][d])) return FLOE_EINVAL;
    crack_prep q;
    crack_prepare(&q, c, dim);
    if (!(q.size > 0)) return FLOE_EINVAL;
    if (dim == 2) {
        for (int k = 0; k + 1 < c->n; k++)
            if (c->p[k][0] == c->p[k + 1][0] && c->p[k][1] == c->p[k + 1][1]) return FLOE_EINVAL;
        return FLOE_OK;
    }
    /* 3D: non-zero area, planar, convex and simple (the turns all one way, once around) */
    if (!(floe_v3_norm(q.nrm) > 0.5)) return FLOE_EINVAL;
    double area2 = 0;
    for (int k = 1; k + 1 < c->n; k++) {
        double a[3], b[3], x[3];
        floe_v3_sub(a, c->p[k], c->p[0]);
        floe_v3_sub(b, c->p[k + 1], c->p[0]);
        floe_v3_cross(x, a, b);
        area2 += floe_v3_dot(x, q.nrm);
    }
    if (!(area2 > 1e-12 * q.size * q.size)) return FLOE_EINVAL;
    double turn = 0;
    for (int k = 0; k < c->n; k++) {
        double a[3], b[3], x[3];
        floe_v3_sub(a, c->p[k], c->p[0]);
        if (fabs(floe_v3_dot(a, q.nrm)) > 1e-9 * q.size) return FLOE_EINVAL; /* not planar */
        const double *p0 = c->p[k], *p1 = c->p[(k + 1) % c->n], *p2 = c->p[(k + 2) % c->n];
        floe_v3_sub(a, p1, p0);
        floe_v3_sub(b, p2, p1);
        double la = floe_v3_norm(a), lb = floe_v3_norm(b);
        if (!(la > 0) || !(lb > 0)) return FLOE_EINVAL; /* repeated vertex */
        floe_v3_cross(x, a, b);
        double s = floe_v3_dot(x, q.nrm);
        if (s < -1e-12 * la * lb) return FLOE_EINVAL; /* a reflex vertex: not convex */
        turn += atan2(s, floe_v3_dot(a, b));
    }
    if (fabs(turn - 2.0 * M_PI) > 1e-6) return FLOE_EINVAL; /* winds more than once */
    return FLOE_OK;
}

/* 2D: segment a-b against the bond xi-xj (x-y only) */
static int cuts_segment(const double a[3], const double b[3], const double xi[3], const double xj[3])
{
    double ex = b[0] - a[0], ey = b[1] - a[1];
    double di = ex * (xi[1] - a[1]) - ey * (xi[0] - a[0]);
    double dj = ex * (xj[1] - a[1]) - ey * (xj[0] - a[0]);
    if ((di >= 0) == (dj >= 0)) return 0; /* same side (a point on the line: the + side) */
    double t = di / (di - dj);
    double px = xi[0] + t * (xj[0] - xi[0]) - a[0], py = xi[1] + t * (xj[1] - xi[1]) - a[1];
    double u = (px * ex + py * ey) / (ex * ex + ey * ey);
    return u >= -1e-12 && u <= 1.0 + 1e-12;
}

static int prep_cuts(const crack_prep *q, const double xi[3], const double xj[3])
{
    const floe_pd_crack *c = q->c;
    if (q->dim == 2) {
        for (int k = 0; k + 1 < c->n; k++)
            if (cuts_segment(c->p[k], c->p[k + 1], xi, xj)) return 1;
        return 0;
    }
    double a[3], b[3];
    floe_v3_sub(a, xi, c->p[0]);
    floe_v3_sub(b, xj, c->p[0]);
    double di = floe_v3_dot(a, q->nrm), dj = floe_v3_dot(b, q->nrm);
    if ((di >= 0) == (dj >= 0)) return 0;
    double t = di / (di - dj), P[3];
    floe_v3_copy(P, xi);
    for (int d = 0; d < 3; d++) P[d] += t * (xj[d] - xi[d]);
    const double tol = 1e-12 * q->size * q->size;
    for (int k = 0; k < c->n; k++) {
        double e[3], r[3], x[3];
        floe_v3_sub(e, c->p[(k + 1) % c->n], c->p[k]);
        floe_v3_sub(r, P, c->p[k]);
        floe_v3_cross(x, e, r);
        if (floe_v3_dot(x, q->nrm) < -tol) return 0;
    }
    return 1;
}

int floe_pd_crack_cuts(const floe_pd_crack *c, int dim, const double xi[3], const double xj[3])
{
    if (!c || !xi || !xj || (dim != 2 && dim != 3)) return 0;
    crack_prep q;
    crack_prepare(&q, c, dim);
    return prep_cuts(&q, xi, xj);
}

/* the reference position of bond k's partner j: X_j, or its image X_j + H0 n (in xs) */
static const double *pd_partner_ref(const floe_pd_body *b, int64_t k, double xs[3])
{
    const double *xj = b->X + 3 * (size_t)b->partner[k];
    if (!b->img || !b->img[k]) return xj;
    floe_img_shift(b->cellH0, b->img[k], xs);
    floe_v3_add(xs, xs, xj);
    return xs;
}

int64_t floe_pd_add_crack(floe_pd_body *b, const floe_pd_crack *c)
{
    if (!b || floe_pd_crack_check(c, b->dim) != FLOE_OK) return -FLOE_EINVAL;
    if (b->nbond == 0) return 0;
    crack_prep q;
    crack_prepare(&q, c, b->dim);
    uint8_t *cut = calloc((size_t)b->nbond, 1);
    if (!cut) return -FLOE_ENOMEM;
    /* a cut bond has both ends within its length (<= delta + tol) of the crack */
    const double reach = b->delta * (1.0 + 1e-6);
    int64_t ncut = 0;
    for (int i = 0; i < b->n; i++) {
        const double *xi = b->X + 3 * (size_t)i;
        int near = 1;
        for (int d = 0; d < b->dim; d++)
            if (xi[d] < q.lo[d] - reach || xi[d] > q.hi[d] + reach) near = 0;
        if (!near) continue;
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            double xs[3];
            if (prep_cuts(&q, xi, pd_partner_ref(b, k, xs))) { cut[k] = 1; ncut++; }
        }
    }
    if (ncut == 0) { free(cut); return 0; }
    /* compact every per-bond array in place, row by row */
    int64_t kk = 0, start = b->off[0], nbroken_cut = 0;
    for (int i = 0; i < b->n; i++) {
        int64_t end = b->off[i + 1];
        for (int64_t k = start; k < end; k++) {
            if (cut[k]) { nbroken_cut += b->broken[k] != 0; continue; }
            b->partner[kk] = b->partner[k];
            b->len[kk] = b->len[k];
            b->vfac[kk] = b->vfac[k];
            b->broken[kk] = b->broken[k];
            if (b->scorr) b->scorr[kk] = b->scorr[k];
            if (b->wbond) b->wbond[kk] = b->wbond[k];
            if (b->splast) b->splast[kk] = b->splast[k];
            if (b->img) b->img[kk] = b->img[k];
            kk++;
        }
        start = end;
        b->off[i + 1] = kk;
    }
    free(cut);
    b->nbond = kk;
    b->nbroken -= nbroken_cut;
    floe_pd_par_free(b); /* the threads' index of the old bonds */
    b->ncut += ncut;
    /* the material state depends on the families (LPS m_i, the surface corrections) */
    if (b->ops) {
        int had_corr = b->scorr != NULL || b->dten != NULL;
        floe_pd_material m = b->mat;
        int rc = floe_pd_set_material(b, &m);
        if (rc == FLOE_OK && had_corr) rc = floe_pd_surface_correction(b);
        if (rc != FLOE_OK) return -rc;
    }
    return ncut;
}

/* ---- holes narrower than the horizon ---- */

/* the hole's outward normal direction at P (central differences; 2D: in-plane) */
static void sdf_grad(floe_pd_sdf_fn sdf, void *user, int dim, const double P[3], double h, double g[3])
{
    floe_v3_set(g, 0, 0, 0);
    for (int d = 0; d < dim; d++) {
        double a[3], b[3];
        floe_v3_copy(a, P);
        floe_v3_copy(b, P);
        a[d] += h;
        b[d] -= h;
        g[d] = sdf(a, user) - sdf(b, user);
    }
}

/* the point where sdf turns negative between the parameters t0 and t1 on xi -> xj */
static void bisect_surface(floe_pd_sdf_fn sdf, void *user, const double xi[3], const double xj[3], double t0,
                           double t1, int inside1, double P[3])
{
    for (int it = 0; it < 40; it++) {
        double tm = 0.5 * (t0 + t1), Q[3];
        for (int d = 0; d < 3; d++) Q[d] = xi[d] + tm * (xj[d] - xi[d]);
        int in = sdf(Q, user) < 0;
        if (in == inside1) t1 = tm;
        else t0 = tm;
    }
    double t = 0.5 * (t0 + t1);
    for (int d = 0; d < 3; d++) P[d] = xi[d] + t * (xj[d] - xi[d]);
}

/* 1 when the bond xi-xj enters the hole and leaves it through a facing side */
static int bond_bridges(floe_pd_sdf_fn sdf, void *user, int dim, const double xi[3], const double xj[3], double L,
                        double h)
{
    int ns = (int)ceil(L / h);
    if (ns < 4) ns = 4;
    const double tol = 1e-6 * h;
    int k1 = -1, k2 = -1;
    for (int k = 1; k < ns; k++) {
        double t = (double)k / ns, P[3];
        for (int d = 0; d < 3; d++) P[d] = xi[d] + t * (xj[d] - xi[d]);
        if (sdf(P, user) < -tol) {
            if (k1 < 0) k1 = k;
            k2 = k;
        }
    }
    if (k1 < 0) return 0;
    double Pin[3], Pout[3], gin[3], gout[3];
    bisect_surface(sdf, user, xi, xj, (double)(k1 - 1) / ns, (double)k1 / ns, 1, Pin);
    bisect_surface(sdf, user, xi, xj, (double)(k2 + 1) / ns, (double)k2 / ns, 1, Pout);
    sdf_grad(sdf, user, dim, Pin, 1e-3 * h, gin);
    sdf_grad(sdf, user, dim, Pout, 1e-3 * h, gout);
    double nin = floe_v3_norm(gin), nout = floe_v3_norm(gout);
    if (!(nin > 0) || !(nout > 0)) return 0;
    return floe_v3_dot(gin, gout) < -0.5 * nin * nout;
}

int64_t floe_pd_bonds_across(const floe_pd_body *b, floe_pd_sdf_fn sdf, void *user, double at[3])
{
    if (!b || !sdf) return -FLOE_EINVAL;
    if (b->nbond == 0) return 0;
    double *s = malloc((size_t)b->n * sizeof *s);
    if (!s) return -FLOE_ENOMEM;
    for (int i = 0; i < b->n; i++) s[i] = sdf(b->X + 3 * (size_t)i, user);
    const double h = (b->dx > 0 ? b->dx : b->delta / 3.0) / 8.0;
    int64_t cnt = 0;
    for (int i = 0; i < b->n; i++) {
        if (!(s[i] >= 0)) continue; /* a point inside the hole: not a hole of this body */
        const double *xi = b->X + 3 * (size_t)i;
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            /* the segment can reach inside only when s_i + s_j < |xi| (an SDF is 1-Lipschitz) */
            if (!(s[j] >= 0) || s[i] + s[j] >= b->len[k]) continue;
            double xs[3];
            const double *xj = pd_partner_ref(b, k, xs);
            if (!bond_bridges(sdf, user, b->dim, xi, xj, b->len[k], h)) continue;
            if (cnt == 0 && at)
                for (int d = 0; d < 3; d++) at[d] = 0.5 * (xi[d] + xj[d]);
            cnt++;
        }
    }
    free(s);
    return cnt;
}
