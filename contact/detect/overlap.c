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

/* Sutherland-Hodgman: P (n corners) ∩ {a.x <= b} */
static int ov_clip(double (*P)[2], int n, double ax, double ay, double b) {
    double Q[OV_MAX][2];
    int m = 0;
    for (int i = 0; i < n && m < OV_MAX - 1; i++) {
        const double *p = P[i], *q = P[(i + 1) % n];
        double dp = ax * p[0] + ay * p[1] - b, dq = ax * q[0] + ay * q[1] - b;
        if (dp <= 0) { Q[m][0] = p[0]; Q[m][1] = p[1]; m++; }
        if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
            double t = dp / (dp - dq);
            Q[m][0] = p[0] + t * (q[0] - p[0]);
            Q[m][1] = p[1] + t * (q[1] - p[1]);
            m++;
        }
    }
    memcpy(P, Q, sizeof(double) * 2 * (size_t)m);
    return m;
}

static double ov_area(double (*P)[2], int n, double c[2]) {
    double a = 0, cx = 0, cy = 0;
    for (int i = 0; i < n; i++) {
        const double *p = P[i], *q = P[(i + 1) % n];
        double cr = p[0] * q[1] - q[0] * p[1];
        a += cr;
        cx += (p[0] + q[0]) * cr;
        cy += (p[1] + q[1]) * cr;
    }
    a *= 0.5;
    if (c) {
        c[0] = a != 0 ? cx / (6 * a) : 0;
        c[1] = a != 0 ? cy / (6 * a) : 0;
    }
    return a;
}

/* one term: the load on X (force f, moment m about the origin, per unit stiffness) and
 * I_XY; also the overlap polygon's area and centroid */
double floe_overlap_term2(double (*X)[2], int nx, double (*Y)[3], int ny, double f[2], double *m, double *area,
                          double cen[2]) {
    f[0] = f[1] = *m = 0;
    for (int e = 0; e < nx; e++) {
        const double *p = X[e], *q = X[(e + 1) % nx];
        double dx = q[0] - p[0], dy = q[1] - p[1], len = sqrt(dx * dx + dy * dy);
        if (!(len > 0)) continue;
        double nxe = dy / len, nye = -dx / len; /* outward normal of a CCW polygon */
        /* the part of the edge inside Y: t in [t0, t1] */
        double t0 = 0, t1 = 1;
        for (int k = 0; k < ny && t0 < t1; k++) {
            double v0 = Y[k][2] - Y[k][0] * p[0] - Y[k][1] * p[1], sl = -(Y[k][0] * dx + Y[k][1] * dy);
            /* v0 + sl t >= 0 inside */
            if (sl == 0) { if (v0 < 0) t1 = t0; continue; }
            double tc = -v0 / sl;
            if (sl > 0) { if (tc > t0) t0 = tc; }
            else if (tc < t1) t1 = tc;
        }
        if (!(t1 > t0)) continue;
        /* d_Y along the piece: the lower envelope of the lines' depth, walked piece by piece */
        double t = t0;
        for (int guard = 0; guard <= ny && t < t1; guard++) {
            int fb = -1;
            double vb = INFINITY, sb = 0;
            for (int k = 0; k < ny; k++) {
                double v = Y[k][2] - Y[k][0] * (p[0] + t * dx) - Y[k][1] * (p[1] + t * dy);
                double sl = -(Y[k][0] * dx + Y[k][1] * dy);
                if (v < vb - 1e-15 * len || (v <= vb + 1e-15 * len && sl < sb)) { vb = v; sb = sl; fb = k; }
            }
            double tn = t1;
            for (int k = 0; k < ny; k++) {
                if (k == fb) continue;
                double v = Y[k][2] - Y[k][0] * (p[0] + t * dx) - Y[k][1] * (p[1] + t * dy);
                double sl = -(Y[k][0] * dx + Y[k][1] * dy);
                if (sl < sb) {
                    double tc = t + (v - vb) / (sb - sl);
                    if (tc > t && tc < tn) tn = tc;
                }
            }
            double da = vb, db = vb + sb * (tn - t), L = (tn - t) * len;
            if (da < 0) da = 0;
            if (db < 0) db = 0;
            double ax = p[0] + t * dx, ay = p[1] + t * dy, bx = p[0] + tn * dx, by = p[1] + tn * dy;
            double s0 = 0.5 * L * (da + db);                        /* ∫ d ds */
            double mx = L * (da * (2 * ax + bx) + db * (ax + 2 * bx)) / 6; /* ∫ x d ds */
            double my = L * (da * (2 * ay + by) + db * (ay + 2 * by)) / 6;
            f[0] -= s0 * nxe;
            f[1] -= s0 * nye;
            *m -= mx * nye - my * nxe; /* ∫ x × (-d n) */
            t = tn;
        }
    }
    /* I_XY: the overlap split into the regions nearest to each line of Y */
    double O[OV_MAX][2];
    memcpy(O, X, sizeof(double) * 2 * (size_t)nx);
    int no = nx;
    for (int k = 0; k < ny && no > 0; k++) no = ov_clip(O, no, Y[k][0], Y[k][1], Y[k][2]);
    *area = no > 2 ? ov_area(O, no, cen) : 0;
    double I = 0;
    for (int fk = 0; fk < ny && no > 2; fk++) {
        double R[OV_MAX][2], c[2];
        memcpy(R, O, sizeof(double) * 2 * (size_t)no);
        int nr = no;
        for (int g = 0; g < ny && nr > 2; g++) {
            if (g == fk) continue; /* h_f - n_f.x <= h_g - n_g.x */
            nr = ov_clip(R, nr, Y[g][0] - Y[fk][0], Y[g][1] - Y[fk][1], Y[g][2] - Y[fk][2]);
        }
        if (nr < 3) continue;
        double a = ov_area(R, nr, c);
        I += a * (Y[fk][2] - Y[fk][0] * c[0] - Y[fk][1] * c[1]);
    }
    return I;
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
