/* overlap.c - overlap integrals of two convex polytopes (the overlap-area law).
 *
 * For bodies X, Y the term I_XY = ∫_{X∩Y} -φ_Y is the stored energy per unit stiffness of a
 * Winkler foundation seen from Y; moving X rigidly changes X∩Y only on ∂X, where the
 * integrand is the depth d_Y = min_f (h_f - n_f.x), so -dI_XY/dx_X is the pressure d_Y on
 * ∂X ∩ Y, pushing X out. d_Y is linear inside the region where one face f of Y is nearest,
 * and those regions are convex (h_f - n_f.x <= h_g - n_g.x for all g): the integrals below
 * clip X∩Y by them and integrate linear functions exactly (2D: along each edge; 3D: over
 * each clipped face polygon and each clipped polyhedron). */
#include "floe_overlap.h"
#include <string.h>

#define OV_MAX FLOE_OVERLAP_MAX

/* Sutherland-Hodgman: P (n corners) ∩ {a.x <= b}; P unchanged when all of it is inside */
static int ov_clip(double (*P)[2], int n, double ax, double ay, double b) {
    double d[OV_MAX], Q[OV_MAX][2];
    int out = 0, m = 0;
    for (int i = 0; i < n; i++) {
        d[i] = ax * P[i][0] + ay * P[i][1] - b;
        out |= d[i] > 0;
    }
    if (!out) return n;
    for (int i = 0, j = n - 1; i < n && m < OV_MAX - 1; j = i++) { /* the edge from corner j to i */
        const double dp = d[j], dq = d[i];
        if (dp <= 0) { Q[m][0] = P[j][0]; Q[m][1] = P[j][1]; m++; }
        if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
            const double t = dp / (dp - dq);
            Q[m][0] = P[j][0] + t * (P[i][0] - P[j][0]);
            Q[m][1] = P[j][1] + t * (P[i][1] - P[j][1]);
            m++;
        }
    }
    memcpy(P, Q, sizeof(double) * 2 * (size_t)m);
    return m;
}

/* area and centroid, from the first corner (a thin overlap of two floes far from the
 * origin keeps its digits) */
static double ov_area(double (*P)[2], int n, double c[2]) {
    double a = 0, cx = 0, cy = 0;
    const double ox = P[0][0], oy = P[0][1];
    for (int i = 1; i + 1 < n; i++) {
        const double px = P[i][0] - ox, py = P[i][1] - oy, qx = P[i + 1][0] - ox, qy = P[i + 1][1] - oy;
        double cr = px * qy - qx * py;
        a += cr;
        cx += (px + qx) * cr;
        cy += (py + qy) * cr;
    }
    a *= 0.5;
    if (c) {
        c[0] = ox + (a != 0 ? cx / (6 * a) : 0);
        c[1] = oy + (a != 0 ? cy / (6 * a) : 0);
    }
    return a;
}

/* the lines of Y that can be nearest somewhere in the convex polygon O: with m_f and M_f the
 * least and greatest depth h_f - n_f.x of line f over O's corners, d_Y <= U = min_f M_f on O,
 * so a line with m_f > U is nowhere the nearest (depths are linear, their extremes are at
 * corners). A thin overlap keeps one to three of Y's lines. */
static int ov_active(double (*O)[2], int no, double (*Y)[3], int ny, int *act) {
    double lo[OV_MAX], U = INFINITY, span = 0;
    for (int k = 0; k < ny; k++) {
        double mn = INFINITY, mx = -INFINITY;
        for (int v = 0; v < no; v++) {
            double d = Y[k][2] - Y[k][0] * O[v][0] - Y[k][1] * O[v][1];
            mn = d < mn ? d : mn;
            mx = d > mx ? d : mx;
        }
        lo[k] = mn;
        if (mx < U) U = mx;
        if (mx - mn > span) span = mx - mn;
    }
    const double eps = 1e-9 * (fabs(U) + span); /* a line at the edge of the test stays in */
    int na = 0;
    for (int k = 0; k < ny; k++)
        if (lo[k] <= U + eps) act[na++] = k;
    return na;
}

/* one term: I_XY = ∫_O d_Y over the overlap O = X ∩ Y and the load on X (force f, moment m
 * about the origin, per unit stiffness), -dI_XY/dx_X = -∫_{∂X∩Y} d_Y n_X ds. d_Y vanishes on
 * ∂Y, so by the divergence theorem that boundary integral is ∫_O ∇d_Y dA, and with the
 * regions R_f of O where line f of Y is the nearest (∇d_Y = -n_f there; area a_f, centroid
 * c_f):
 *     I = Σ a_f (h_f - n_f.c_f),   f = Σ a_f n_f,   m = Σ (a_f c_f) × n_f.
 * Only areas and first moments: the last region is O less the others. act: Y's lines that
 * are nearest somewhere in O (ov_active); aO, cO: O's area and centroid. */
static double ov_term2(double (*Y)[3], const int *act, int nact, double (*O)[2], int no, double aO,
                       const double cO[2], double f[2], double *m) {
    double I = 0, ar = aO, mx = aO * cO[0], my = aO * cO[1];
    f[0] = f[1] = *m = 0;
    for (int fa = 0; fa + 1 < nact; fa++) {
        const double *F = Y[act[fa]];
        double R[OV_MAX][2], c[2];
        memcpy(R, O, sizeof(double) * 2 * (size_t)no);
        int nr = no;
        for (int g = 0; g < nact && nr > 2; g++) {
            if (g == fa) continue; /* h_f - n_f.x <= h_g - n_g.x */
            const double *G = Y[act[g]];
            nr = ov_clip(R, nr, G[0] - F[0], G[1] - F[1], G[2] - F[2]);
        }
        if (nr < 3) continue;
        const double a = ov_area(R, nr, c);
        I += a * (F[2] - F[0] * c[0] - F[1] * c[1]);
        f[0] += a * F[0];
        f[1] += a * F[1];
        *m += a * (c[0] * F[1] - c[1] * F[0]);
        ar -= a;
        mx -= a * c[0];
        my -= a * c[1];
    }
    const double *F = Y[act[nact - 1]];
    if (ar > 0) {
        I += ar * F[2] - F[0] * mx - F[1] * my;
        f[0] += ar * F[0];
        f[1] += ar * F[1];
        *m += mx * F[1] - my * F[0];
    }
    return I;
}

int floe_overlap_pair2(double (*A)[2], int na, double (*LA)[3], int la, double (*B)[2], int nb, double (*LB)[3],
                       int lb, floe_overlap2 *out) {
    memset(out, 0, sizeof *out);
    (void)B;
    (void)nb;
    double O[OV_MAX][2];
    if (na > OV_MAX || nb > OV_MAX || la > OV_MAX || lb > OV_MAX) return -1;
    memcpy(O, A, sizeof(double) * 2 * (size_t)na);
    int no = na;
    for (int k = 0; k < lb && no > 2; k++) no = ov_clip(O, no, LB[k][0], LB[k][1], LB[k][2]);
    if (no < 3) return 0;
    double e2 = 0; /* the overlap's size squared */
    for (int v = 1; v < no; v++) {
        const double dx = O[v][0] - O[0][0], dy = O[v][1] - O[0][1];
        e2 = dx * dx + dy * dy > e2 ? dx * dx + dy * dy : e2;
    }
    out->area = ov_area(O, no, out->cen);
    /* a sliver thinner than 1e-10 of its length is two polygons that share an edge (a
     * Voronoi field): its area and centroid are round-off; touching, not overlapping */
    if (!(out->area > 1e-10 * e2)) {
        out->area = 0;
        return 0;
    }
    int actA[OV_MAX], actB[OV_MAX];
    const int nactB = ov_active(O, no, LB, lb, actB), nactA = ov_active(O, no, LA, la, actA);
    double f1[2], f2[2], m1, m2;
    const double I1 = ov_term2(LB, actB, nactB, O, no, out->area, out->cen, f1, &m1); /* on A, in B */
    const double I2 = ov_term2(LA, actA, nactA, O, no, out->area, out->cen, f2, &m2); /* on B, in A */
    /* on A: half of each term, the second by action and reaction */
    out->f[0] = 0.5 * (f1[0] - f2[0]);
    out->f[1] = 0.5 * (f1[1] - f2[1]);
    out->m = 0.5 * (m1 - m2);
    out->I = 0.5 * (I1 + I2);
    return 1;
}

double floe_overlap_pen2(double (*X)[2], int nx, const double L[3]) {
    double pen = -INFINITY;
    for (int v = 0; v < nx; v++) {
        const double d = L[2] - L[0] * X[v][0] - L[1] * X[v][1];
        pen = d > pen ? d : pen;
    }
    return pen;
}

int floe_overlap_axis2(double (*A)[2], int na, double (*LA)[3], int la, double (*B)[2], int nb, double (*LB)[3],
                       int lb, double tol) {
    for (int k = 0; k < la; k++)
        if (floe_overlap_pen2(B, nb, LA[k]) <= tol) return k + 1;
    for (int k = 0; k < lb; k++)
        if (floe_overlap_pen2(A, na, LB[k]) <= tol) return la + k + 1;
    return 0;
}


/* ---- 3D ---- */

static void sort_ccw(double (*P)[3], int n, const double nrm[3]) {
    double c[3] = {0, 0, 0}, u[3], t[3], ang[2 * FLOE_POLY3_CORNERS];
    for (int k = 0; k < n; k++) floe_v3_add(c, c, P[k]);
    floe_v3_scale(c, 1.0 / n);
    /* a reference direction in the plane */
    floe_v3_sub(u, P[0], c);
    double un = floe_v3_norm(u);
    if (!(un > 0)) return;
    floe_v3_scale(u, 1.0 / un);
    floe_v3_cross(t, nrm, u);
    for (int k = 0; k < n; k++) {
        double r[3];
        floe_v3_sub(r, P[k], c);
        ang[k] = atan2(floe_v3_dot(r, t), floe_v3_dot(r, u));
    }
    for (int a = 1; a < n; a++)
        for (int b = a; b > 0 && ang[b] < ang[b - 1]; b--) {
            double ta = ang[b], tp[3];
            ang[b] = ang[b - 1]; ang[b - 1] = ta;
            floe_v3_copy(tp, P[b]); floe_v3_copy(P[b], P[b - 1]); floe_v3_copy(P[b - 1], tp);
        }
}

int floe_poly3_from_planes(const double *planes, int np, const double *V, int nv, double tol, floe_poly3 *P) {
    if (np > FLOE_POLY3_FACES) return -1;
    P->nf = 0;
    for (int f = 0; f < np; f++) {
        const double *pl = planes + 4 * f;
        int m = 0;
        for (int v = 0; v < nv; v++)
            if (fabs(floe_v3_dot(pl, V + 3 * v) - pl[3]) <= tol) {
                if (m >= FLOE_POLY3_CORNERS) return -1;
                floe_v3_copy(P->v[P->nf][m++], V + 3 * v);
            }
        if (m < 3) continue;
        sort_ccw(P->v[P->nf], m, pl);
        P->nv[P->nf] = m;
        floe_v3_copy(P->n[P->nf], pl);
        P->tag[P->nf] = 1;
        P->nf++;
    }
    return 0;
}

/* keep the part of P with a.x <= b; the cut becomes a new face (tag 0) */
static void clip3(floe_poly3 *P, const double a[3], double b, double tol) {
    double cap[FLOE_POLY3_CORNERS * 2][3];
    int nc = 0;
    int out = 0;
    for (int f = 0; f < P->nf; f++) {
        double Q[FLOE_POLY3_CORNERS][3];
        int m = 0, n = P->nv[f];
        for (int i = 0; i < n; i++) {
            const double *p = P->v[f][i], *q = P->v[f][(i + 1) % n];
            double dp = floe_v3_dot(a, p) - b, dq = floe_v3_dot(a, q) - b;
            if (dp <= 0 && m < FLOE_POLY3_CORNERS) floe_v3_copy(Q[m++], p);
            if (fabs(dp) <= tol && nc < 2 * FLOE_POLY3_CORNERS) floe_v3_copy(cap[nc++], p);
            if (((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) && m < FLOE_POLY3_CORNERS) {
                double t = dp / (dp - dq);
                for (int k = 0; k < 3; k++) Q[m][k] = p[k] + t * (q[k] - p[k]);
                if (nc < 2 * FLOE_POLY3_CORNERS) floe_v3_copy(cap[nc++], Q[m]);
                m++;
            }
        }
        if (m < 3) continue;
        memcpy(P->v[out], Q, sizeof(double) * 3 * (size_t)m);
        P->nv[out] = m;
        floe_v3_copy(P->n[out], P->n[f]);
        P->tag[out] = P->tag[f];
        out++;
    }
    P->nf = out;
    /* the cap: distinct points on the plane */
    double C[FLOE_POLY3_CORNERS][3];
    int k = 0;
    for (int i = 0; i < nc && k < FLOE_POLY3_CORNERS; i++) {
        int dup = 0;
        for (int j = 0; j < k && !dup; j++) {
            double d[3];
            floe_v3_sub(d, cap[i], C[j]);
            dup = floe_v3_norm(d) <= tol;
        }
        if (!dup) floe_v3_copy(C[k++], cap[i]);
    }
    if (k >= 3 && P->nf < FLOE_POLY3_FACES) {
        double an = floe_v3_norm(a), nrm[3] = {a[0] / an, a[1] / an, a[2] / an};
        sort_ccw(C, k, nrm);
        memcpy(P->v[P->nf], C, sizeof(double) * 3 * (size_t)k);
        P->nv[P->nf] = k;
        floe_v3_copy(P->n[P->nf], nrm);
        P->tag[P->nf] = 0;
        P->nf++;
    }
}

/* volume and centroid by tetrahedra from the mean corner */
static double vol3(const floe_poly3 *P, double cen[3]) {
    double o[3] = {0, 0, 0}, vol = 0, acc[3] = {0, 0, 0};
    int cnt = 0;
    for (int f = 0; f < P->nf; f++)
        for (int i = 0; i < P->nv[f]; i++) { floe_v3_add(o, o, P->v[f][i]); cnt++; }
    if (!cnt) { floe_v3_set(cen, 0, 0, 0); return 0; }
    floe_v3_scale(o, 1.0 / cnt);
    for (int f = 0; f < P->nf; f++)
        for (int i = 1; i + 1 < P->nv[f]; i++) {
            const double *a = P->v[f][0], *b = P->v[f][i], *c = P->v[f][i + 1];
            double ea[3], eb[3], ec[3], cr[3];
            floe_v3_sub(ea, a, o); floe_v3_sub(eb, b, o); floe_v3_sub(ec, c, o);
            floe_v3_cross(cr, eb, ec);
            double v = floe_v3_dot(ea, cr) / 6.0;
            vol += v;
            for (int k = 0; k < 3; k++) acc[k] += v * (o[k] + a[k] + b[k] + c[k]) / 4.0;
        }
    if (vol != 0) for (int k = 0; k < 3; k++) cen[k] = acc[k] / vol;
    else floe_v3_copy(cen, o);
    return vol;
}

/* copy the used part only (a floe_poly3 is 37 KB) */
static void copy3(floe_poly3 *dst, const floe_poly3 *src) {
    dst->nf = src->nf;
    for (int f = 0; f < src->nf; f++) {
        dst->nv[f] = src->nv[f];
        dst->tag[f] = src->tag[f];
        floe_v3_copy(dst->n[f], src->n[f]);
        memcpy(dst->v[f], src->v[f], sizeof(double) * 3 * (size_t)src->nv[f]);
    }
}

double floe_overlap_term3(const floe_poly3 *X, const double *Yp, int ny, double tol, double f[3], double m[3],
                          double *vol, double cen[3], double *area) {
    floe_poly3 *P, *Q;
    floe_v3_set(f, 0, 0, 0);
    floe_v3_set(m, 0, 0, 0);
    *vol = *area = 0;
    floe_v3_set(cen, 0, 0, 0);
    /* X ∩ Y, and its part nearest one face of Y (2 x 37 KB) */
    floe_poly3 buf[2];
    P = &buf[0];
    Q = &buf[1];
    copy3(P, X);
    for (int k = 0; k < ny && P->nf > 0; k++) clip3(P, Yp + 4 * k, Yp[4 * k + 3], tol);
    if (P->nf < 4) return 0;
    *vol = vol3(P, cen);
    double I = 0;
    for (int fk = 0; fk < ny; fk++) {
        const double *nf = Yp + 4 * fk;
        copy3(Q, P);
        for (int g = 0; g < ny && Q->nf > 0; g++) {
            if (g == fk) continue;
            const double *ng = Yp + 4 * g;
            double a[3] = {ng[0] - nf[0], ng[1] - nf[1], ng[2] - nf[2]};
            if (floe_v3_norm(a) < 1e-14) continue;
            clip3(Q, a, ng[3] - nf[3], tol);
        }
        if (Q->nf < 4) continue;
        double c[3], v = vol3(Q, c);
        I += v * (nf[3] - floe_v3_dot(nf, c));
        /* the pressure on X's own faces in this region */
        for (int fc = 0; fc < Q->nf; fc++) {
            if (!Q->tag[fc]) continue;
            const double *n = Q->n[fc];
            double sd = 0, sx[3] = {0, 0, 0};
            for (int i = 1; i + 1 < Q->nv[fc]; i++) {
                const double *t[3] = {Q->v[fc][0], Q->v[fc][i], Q->v[fc][i + 1]};
                double e1[3], e2[3], cr[3], d[3], dsum = 0, vsum[3] = {0, 0, 0};
                floe_v3_sub(e1, t[1], t[0]);
                floe_v3_sub(e2, t[2], t[0]);
                floe_v3_cross(cr, e1, e2);
                double A = 0.5 * floe_v3_norm(cr);
                *area += A;
                for (int k = 0; k < 3; k++) {
                    d[k] = nf[3] - floe_v3_dot(nf, t[k]);
                    dsum += d[k];
                    floe_v3_add(vsum, vsum, t[k]);
                }
                sd += A * dsum / 3.0;
                for (int k = 0; k < 3; k++)
                    sx[k] += A / 12.0 * (d[0] * t[0][k] + d[1] * t[1][k] + d[2] * t[2][k] + dsum * vsum[k]);
            }
            /* load -d n on the face: force -sd n, moment -(∫ x d) × n */
            double mm[3];
            floe_v3_axpy(f, -sd, n);
            floe_v3_cross(mm, sx, n);
            floe_v3_axpy(m, -1.0, mm);
        }
    }
    return I;
}
