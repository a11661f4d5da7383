/* tradeoff.c - accuracy versus time of the convex contact detectors: floe's ADMM (tolerances
 * 1e-2 .. 1e-10, cold and warm), floe's polytope LP (cold and warm) and libccd's MPR and
 * GJK+EPA penetration (the peer benchmark /work/shared/peers/ccd-mpr, mirrored), in one
 * program on the same pairs.
 *
 * Set P (random polytopes, the peer's set): each body is the convex hull of U{20..40}
 * random points on the unit sphere (hull built here by brute force, then
 * floe_polyhedron_from_mesh), randomly rotated; the second centre at a random direction
 * and distance U(0, 1.5); pairs kept when ccdGJKIntersect says they overlap (as the peer).
 * Set B (the peer's axis-aligned boxes): half extents U(0.2, 1), overlapping on every axis.
 *
 * Each pair is solved at pose B1 = B0 moved by a small rigid motion (1e-4 rad and 1e-4 per
 * axis, a DEM step); "warm" methods start from their state at B0 (ADMM: the 16 warm
 * doubles; LP: the bases), "cold" ones from scratch. Time per pair = median over REPS of
 * (loop time / pairs); the warm states are restored, untimed, before each repetition.
 *
 * References (exact):
 *   deepest-point depth (what floe returns): max over the two halves of -s, s the optimum of
 *   the LP  min t s.t. x in p, n.x - d <= t for every face of p', solved by GLPK's simplex
 *   (set B: closed form, checked against GLPK); normal: the dual-weighted face normal of the deeper half.
 *   minimum translation distance (what libccd returns): exact only on set B, min over the
 *   axes of h1 + h2 - |dc|, along that axis.
 * On set P, libccd's error against the deepest-point reference mixes the difference of
 * definitions with the error; on set B both definitions are exact and both are reported.
 *
 * Usage: bench_contact_tradeoff [NPAIRS=2000] [REPS=3]  (one thread; prints a table and
 * CSV lines "csv,set,method,param,us,err_med,err_p90,err_max,ang_med,fails")
 */
#include "floe.h"
#include "floe_admm.h"
#include "floe_polytope_lp.h"
#include <ccd/ccd.h>
#include <glpk.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static unsigned long long rs = 0x9E3779B97F4A7C15ULL;
static double urand(void) {
    rs ^= rs >> 12; rs ^= rs << 25; rs ^= rs >> 27;
    return (double)((rs * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}
static void rand_unit(double u[3]) {
    double z = 2 * urand() - 1, phi = 2 * M_PI * urand(), s = sqrt(1 - z * z);
    u[0] = s * cos(phi); u[1] = s * sin(phi); u[2] = z;
}
static void rand_quat(double q[4]) {
    double u1 = urand(), u2 = urand(), u3 = urand();
    q[0] = sqrt(1 - u1) * sin(2 * M_PI * u2); q[1] = sqrt(1 - u1) * cos(2 * M_PI * u2);
    q[2] = sqrt(u1) * sin(2 * M_PI * u3); q[3] = sqrt(u1) * cos(2 * M_PI * u3);
}
static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}
static int cmpd(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}
static double quant(double *v, int n, double q) {
    if (n <= 0) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmpd);
    return v[(int)(q * (n - 1) + 0.5)];
}

/* ---- bodies ---- */
typedef struct body {
    floe_geometry *g;
    floe_pose pose;
    int np;
    const double *plane; /* body frame */
    const double *vb;    /* body-frame vertices */
    int nv;
    double vw[3 * 80];   /* world vertices (libccd support) */
    double planes_buf[24];
} body;

static void body_world(body *b) {
    for (int i = 0; i < b->nv; i++) {
        floe_q_rotate(b->vw + 3 * i, b->pose.q, b->vb + 3 * i);
        floe_v3_add(b->vw + 3 * i, b->vw + 3 * i, b->pose.x);
    }
}

/* convex hull of n points in general position (brute force over triples), as triangles
 * counter-clockwise seen from outside; returns the triangle count */
static int hull(const double *p, int n, int *tri) {
    int nt = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            for (int k = j + 1; k < n; k++) {
                double e1[3], e2[3], nn[3];
                floe_v3_sub(e1, p + 3 * j, p + 3 * i);
                floe_v3_sub(e2, p + 3 * k, p + 3 * i);
                floe_v3_cross(nn, e1, e2);
                double d = floe_v3_dot(nn, p + 3 * i);
                int pos = 0, neg = 0;
                for (int m = 0; m < n && !(pos && neg); m++) {
                    if (m == i || m == j || m == k) continue;
                    double s = floe_v3_dot(nn, p + 3 * m) - d;
                    if (s > 1e-12) pos = 1;
                    else if (s < -1e-12) neg = 1;
                }
                if (pos && neg) continue;
                if (pos) { tri[3 * nt] = i; tri[3 * nt + 1] = k; tri[3 * nt + 2] = j; }
                else { tri[3 * nt] = i; tri[3 * nt + 1] = j; tri[3 * nt + 2] = k; }
                nt++;
            }
    return nt;
}

static int make_poly(body *b, const double c[3]) {
    double pts[3 * 40], qr[4];
    int tri[3 * 2 * 40 * 3];
    char err[256];
    for (;;) {
        int n = 20 + (int)(urand() * 21);
        if (n > 40) n = 40;
        for (int i = 0; i < n; i++) rand_unit(pts + 3 * i);
        int nt = hull(pts, n, tri);
        b->g = floe_polyhedron_from_mesh(pts, n, tri, nt, err, sizeof err);
        if (b->g) break;
        fprintf(stderr, "hull rejected (%s), retrying\n", err);
    }
    const floe_polytope *P = (const floe_polytope *)b->g;
    rand_quat(qr);
    /* world = R(qr) X_input + c, X_input = R(frame_q) X_body + frame_x */
    double fx[3];
    floe_q_mul(b->pose.q, qr, P->frame_q);
    floe_q_rotate(fx, qr, P->frame_x);
    floe_v3_add(b->pose.x, c, fx);
    b->pose.g = b->g;
    b->np = P->np;
    b->plane = P->plane;
    b->vb = P->v;
    b->nv = P->nv;
    body_world(b);
    return 0;
}

static void make_box(body *b, const double h[3], const double c[3]) {
    b->g = floe_box_create(2 * h[0], 2 * h[1], 2 * h[2]);
    b->pose.g = b->g;
    floe_v3_copy(b->pose.x, c);
    floe_q_identity(b->pose.q);
    for (int a = 0; a < 3; a++)
        for (int s = 0; s < 2; s++) {
            double *P = b->planes_buf + 4 * (2 * a + s);
            P[0] = P[1] = P[2] = 0;
            P[a] = s ? 1.0 : -1.0;
            P[3] = h[a];
        }
    b->np = 6;
    b->plane = b->planes_buf;
    b->vb = ((const floe_box *)b->g)->vert;
    b->nv = 8;
    body_world(b);
}

static void move_small(body *b, double eps) {
    double th[3], dq[4], q[4];
    for (int k = 0; k < 3; k++) { th[k] = eps * (2 * urand() - 1); b->pose.x[k] += eps * (2 * urand() - 1); }
    floe_q_from_rotvec(dq, th);
    floe_q_mul(q, dq, b->pose.q);
    floe_q_normalize(q);
    memcpy(b->pose.q, q, sizeof q);
    body_world(b);
}

/* ---- libccd ---- */
static void ccd_support(const void *obj, const ccd_vec3_t *d, ccd_vec3_t *out) {
    const body *b = (const body *)obj;
    int best = 0;
    double bd = -1e300;
    for (int i = 0; i < b->nv; i++) {
        double t = b->vw[3 * i] * d->v[0] + b->vw[3 * i + 1] * d->v[1] + b->vw[3 * i + 2] * d->v[2];
        if (t > bd) { bd = t; best = i; }
    }
    ccdVec3Set(out, b->vw[3 * best], b->vw[3 * best + 1], b->vw[3 * best + 2]);
}
static void ccd_center(const void *obj, ccd_vec3_t *c) {
    const body *b = (const body *)obj;
    ccdVec3Set(c, b->pose.x[0], b->pose.x[1], b->pose.x[2]);
}

/* ---- planes into a frame ---- */
static void plane_to(const double P[4], const floe_pose *from, const floe_pose *to, double out[4]) {
    double nw[3], d[3];
    floe_q_rotate(nw, from->q, P);
    if (to) {
        floe_q_rotate_inv(out, to->q, nw);
        floe_v3_sub(d, from->x, to->x);
    } else {
        floe_v3_copy(out, nw);
        floe_v3_copy(d, from->x);
    }
    out[3] = P[3] + floe_v3_dot(nw, d);
}

/* ---- exact reference: GLPK, deepest point of p in p' (world); w[] the dual weights of p''s
 * rows. Returns t (NaN on failure), the outward normal of p' (dual-weighted) in nrm. ---- */
static double glpk_half(const body *p, const body *pp, double nrm[3], double *gmag) {
    double A[4 * 80], B[4 * 80];
    for (int k = 0; k < p->np; k++) plane_to(p->plane + 4 * k, &p->pose, NULL, A + 4 * k);
    for (int k = 0; k < pp->np; k++) plane_to(pp->plane + 4 * k, &pp->pose, NULL, B + 4 * k);
    int na = p->np, nb = pp->np;
    glp_prob *lp = glp_create_prob();
    glp_set_obj_dir(lp, GLP_MIN);
    glp_add_cols(lp, 4);
    for (int j = 1; j <= 4; j++) glp_set_col_bnds(lp, j, GLP_FR, 0, 0);
    glp_set_obj_coef(lp, 4, 1.0);
    glp_add_rows(lp, na + nb);
    int ind[5] = {0, 1, 2, 3, 4};
    for (int i = 0; i < na + nb; i++) {
        const double *P = i < na ? A + 4 * i : B + 4 * (i - na);
        double val[5] = {0, P[0], P[1], P[2], -1.0};
        glp_set_mat_row(lp, i + 1, i < na ? 3 : 4, ind, val);
        glp_set_row_bnds(lp, i + 1, GLP_UP, 0, P[3]);
    }
    glp_smcp parm;
    glp_init_smcp(&parm);
    parm.msg_lev = GLP_MSG_OFF;
    parm.presolve = GLP_OFF;
    /* floating-point simplex only: glp_exact converts the double data to rationals
     * inexactly (measured: 1e-12 off on a box pair whose double simplex is exact) */
    int rc = glp_simplex(lp, &parm);
    double t = NAN;
    if (rc == 0 && glp_get_status(lp) == GLP_OPT) {
        t = glp_get_col_prim(lp, 4);
        double g[3] = {0, 0, 0};
        for (int i = 0; i < nb; i++) {
            double w = -glp_get_row_dual(lp, na + i + 1);
            if (w > 0) floe_v3_axpy(g, w, B + 4 * i);
        }
        double gn = floe_v3_norm(g);
        if (gn > 0) floe_v3_scale(g, 1 / gn);
        floe_v3_copy(nrm, g);
        *gmag = gn;
    }
    glp_delete_prob(lp);
    return t;
}

/* deepest-point reference of a pair: depth = max(-s1, -s2); normal from a to b. The
 * normal is the dual-weighted sum of the tight face normals; when the deepest point is the
 * Chebyshev centre of the other body (deep overlaps) that sum is ~0 and the normal is not
 * defined: *defined = 0 when its length is below 0.1. */
static double dp_reference(const body *a, const body *b, double n[3], int *defined) {
    double n1[3] = {0, 0, 0}, n2[3] = {0, 0, 0}, g1 = 0, g2 = 0;
    double s1 = glpk_half(a, b, n1, &g1), s2 = glpk_half(b, a, n2, &g2);
    if (-s1 >= -s2) {
        floe_v3_set(n, -n1[0], -n1[1], -n1[2]);
        *defined = g1 >= 0.1;
        return -s1;
    }
    floe_v3_copy(n, n2);
    *defined = g2 >= 0.1;
    return -s2;
}

/* ---- floe LP pair (as contact/detect/detect.c polytope_pair): planes of b into a's frame ---- */
static double lp_scratch[4 * 80];
static int lp_half(const body *a, const body *b, int *basis, double *s, double n[3]) {
    for (int k = 0; k < b->np; k++) plane_to(b->plane + 4 * k, &b->pose, &a->pose, lp_scratch + 4 * k);
    floe_lp_problem P = {3, a->plane, a->np, lp_scratch, b->np, a->vb, a->nv, 1.0, NULL, NULL, NULL};
    floe_lp_result r;
    int rc = floe_lp_deepest(&P, basis, &r);
    if (rc) return rc;
    *s = r.s;
    floe_q_rotate(n, a->pose.q, r.normal);
    return 0;
}
static int lp_pair(const body *a, const body *b, int *basis8, double *depth, double n[3]) {
    double s1, s2, n1[3], n2[3];
    if (lp_half(a, b, basis8, &s1, n1)) return -1;
    if (!(s1 < 0)) { *depth = 0; return 0; }
    if (lp_half(b, a, basis8 + 4, &s2, n2)) return -1;
    if (!(s2 < 0)) { *depth = 0; return 0; }
    if (-s1 >= -s2) { *depth = -s1; floe_v3_set(n, -n1[0], -n1[1], -n1[2]); }
    else { *depth = -s2; floe_v3_copy(n, n2); }
    return 1;
}

/* ---- methods ---- */
enum { M_ADMM, M_LP, M_MPR, M_EPA };
typedef struct method {
    int kind, warm;
    double tol;
    const char *name;
} method;

typedef struct result_row {
    double us, err_med, err_p90, err_max, ang_med, ang_p90, mtd_med, mtd_max, within;
    int fails;
} result_row;

static double angle(const double a[3], const double b[3]) {
    double na = floe_v3_norm(a), nb = floe_v3_norm(b);
    if (!(na > 0 && nb > 0)) return M_PI;
    double c = floe_v3_dot(a, b) / (na * nb);
    return acos(fmax(-1.0, fmin(1.0, c)));
}

/* run one method on n pairs (A[i], B1[i]) with warm state from (A[i], B0[i]); depth and
 * normal out */
static double run_method(const method *m, body *A, body *B0, body *B1, int n, int reps, double *depth,
                         double (*nrm)[3], int *fails) {
    floe_admm_options o;
    floe_admm_default_options(&o);
    if (m->kind == M_ADMM) o.tol = m->tol;
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccd.support2 = ccd_support;
    ccd.center1 = ccd.center2 = ccd_center;
    ccd.max_iterations = 1000;
    if (m->kind == M_MPR || m->kind == M_EPA) ccd.mpr_tolerance = ccd.epa_tolerance = m->tol;
    double *warm = NULL, *warm0 = NULL;
    int *basis = NULL, *basis0 = NULL;
    if (m->warm && m->kind == M_ADMM) {
        warm = malloc(sizeof(double) * FLOE_ADMM_WARM * n);
        warm0 = malloc(sizeof(double) * FLOE_ADMM_WARM * n);
        for (int i = 0; i < n; i++) {
            floe_admm_result r;
            double *w = warm0 + FLOE_ADMM_WARM * i;
            for (int k = 0; k < FLOE_ADMM_WARM; k++) w[k] = NAN;
            floe_admm_contact(&A[i].pose, &B0[i].pose, &o, w, &r);
        }
    }
    if (m->kind == M_LP) {
        basis = malloc(sizeof(int) * 8 * n);
        basis0 = malloc(sizeof(int) * 8 * n);
        for (int i = 0; i < n; i++) {
            int *b = basis0 + 8 * i;
            for (int k = 0; k < 8; k++) b[k] = -1;
            if (m->warm) {
                double d, nn[3];
                lp_pair(&A[i], &B0[i], b, &d, nn);
            }
        }
    }
    double *t = malloc(sizeof(double) * reps);
    for (int r = 0; r < reps; r++) {
        if (warm) memcpy(warm, warm0, sizeof(double) * FLOE_ADMM_WARM * n);
        if (basis) memcpy(basis, basis0, sizeof(int) * 8 * n);
        int nf = 0;
        double t0 = now();
        for (int i = 0; i < n; i++) {
            if (m->kind == M_ADMM) {
                floe_admm_result res;
                floe_admm_contact(&A[i].pose, &B1[i].pose, &o, warm ? warm + FLOE_ADMM_WARM * i : NULL, &res);
                depth[i] = res.penetrating ? res.depth : 0;
                memcpy(nrm[i], res.n, sizeof res.n);
                nf += !res.converged;
            } else if (m->kind == M_LP) {
                int rc = lp_pair(&A[i], &B1[i], basis + 8 * i, &depth[i], nrm[i]);
                if (rc < 0) { nf++; depth[i] = NAN; }
            } else {
                ccd_real_t d;
                ccd_vec3_t dir, pos;
                int rc = (m->kind == M_MPR ? ccdMPRPenetration : ccdGJKPenetration)(&A[i], &B1[i], &ccd, &d, &dir, &pos);
                if (rc != 0) { nf++; d = NAN; }
                depth[i] = d;
                floe_v3_set(nrm[i], dir.v[0], dir.v[1], dir.v[2]);
            }
        }
        t[r] = (now() - t0) / n;
        *fails = nf;
    }
    double med = quant(t, reps, 0.5);
    free(t); free(warm); free(warm0); free(basis); free(basis0);
    return med;
}

static void errors(const double *depth, double (*nrm)[3], const double *ref, double (*rn)[3], int n, double *med,
                   double *p90, double *mx, double *amed, double *ap90, double *within) {
    double *e = malloc(sizeof(double) * n), *a = malloc(sizeof(double) * n);
    int ne = 0, ok = 0, na = 0;
    for (int i = 0; i < n; i++) {
        double err = isfinite(depth[i]) ? fabs(depth[i] - ref[i]) : INFINITY;
        e[ne++] = err;
        if (isfinite(rn[i][0])) a[na++] = angle(nrm[i], rn[i]);
        ok += err <= 1e-4;
    }
    *med = quant(e, ne, 0.5);
    *p90 = quant(e, ne, 0.9);
    *mx = quant(e, ne, 1.0);
    if (amed) *amed = quant(a, na, 0.5);
    if (ap90) *ap90 = quant(a, na, 0.9);
    if (within) *within = 100.0 * ok / n;
    free(e);
    free(a);
}

int main(int argc, char **argv) {
    int n = argc > 1 ? atoi(argv[1]) : 2000, reps = argc > 2 ? atoi(argv[2]) : 3;
    glp_term_out(GLP_OFF);
    const double eps = 1e-4; /* per-step motion */
    method M[] = {
        {M_ADMM, 0, 1e-2, "ADMM cold"}, {M_ADMM, 0, 1e-4, "ADMM cold"}, {M_ADMM, 0, 1e-6, "ADMM cold"},
        {M_ADMM, 0, 1e-8, "ADMM cold"}, {M_ADMM, 0, 1e-10, "ADMM cold"}, {M_ADMM, 1, 1e-2, "ADMM warm"},
        {M_ADMM, 1, 1e-4, "ADMM warm"}, {M_ADMM, 1, 1e-6, "ADMM warm"}, {M_ADMM, 1, 1e-8, "ADMM warm"},
        {M_ADMM, 1, 1e-10, "ADMM warm"}, {M_LP, 0, 0, "LP cold"}, {M_LP, 1, 0, "LP warm"},
        {M_MPR, 0, 1e-4, "libccd MPR"}, {M_MPR, 0, 1e-8, "libccd MPR"}, {M_EPA, 0, 1e-4, "libccd GJK+EPA"},
        {M_EPA, 0, 1e-8, "libccd GJK+EPA"},
    };
    const int nm = (int)(sizeof M / sizeof M[0]);
    double *depth = malloc(sizeof(double) * n), (*nrm)[3] = malloc(sizeof(double[3]) * n);

    /* ---- set P ---- */
    body *A = calloc((size_t)n, sizeof *A), *B0 = calloc((size_t)n, sizeof *B0), *B1 = calloc((size_t)n, sizeof *B1);
    double *ref = malloc(sizeof(double) * n), (*rn)[3] = malloc(sizeof(double[3]) * n);
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccd.support2 = ccd_support;
    ccd.center1 = ccd.center2 = ccd_center;
    int tries = 0, ndef = 0;
    for (int i = 0; i < n;) {
        double c0[3] = {0, 0, 0}, u[3], c1[3];
        rand_unit(u);
        double dist = 1.5 * urand();
        for (int k = 0; k < 3; k++) c1[k] = dist * u[k];
        make_poly(&A[i], c0);
        make_poly(&B0[i], c1);
        tries++;
        B1[i] = B0[i];
        move_small(&B1[i], eps);
        double nr[3];
        int def = 0;
        double d = dp_reference(&A[i], &B1[i], nr, &def);
        if (ccdGJKIntersect(&A[i], &B1[i], &ccd) && d > 0 && isfinite(d)) {
            ref[i] = d;
            memcpy(rn[i], nr, sizeof nr);
            ndef += def;
            if (!def) floe_v3_set(rn[i], NAN, NAN, NAN);
            i++;
        } else {
            floe_geometry_destroy(A[i].g);
            floe_geometry_destroy(B0[i].g);
        }
    }
    printf("set P: %d pairs of random polytopes (hull of 20-40 unit-sphere points; kept %d of %d candidates), "
           "solved after a motion of %.0e (warm: from the state before it), %d repetitions\n",
           n, n, tries, eps, reps);
    printf("normal angle (rad) over the %d pairs whose deepest-point normal is defined (dual-weighted face normal "
           "longer than 0.1; deeper pairs have the Chebyshev centre as deepest point)\n", ndef);
    printf("%-16s %-7s %10s | %-34s | %-19s | %s\n", "method", "tol", "us/pair", "depth err vs deepest-point (med p90 max)",
           "normal angle (med p90)", "not conv./fail");
    for (int k = 0; k < nm; k++) {
        int fails = 0;
        double us = 1e6 * run_method(&M[k], A, B0, B1, n, reps, depth, nrm, &fails);
        double med, p90, mx, am, a90;
        errors(depth, nrm, ref, rn, n, &med, &p90, &mx, &am, &a90, NULL);
        char tol[16] = "-";
        if (M[k].kind != M_LP) snprintf(tol, sizeof tol, "%.0e", M[k].tol);
        printf("%-16s %-7s %10.3f | %10.2e %10.2e %10.2e   | %8.2e %8.2e   | %d\n", M[k].name, tol, us, med, p90, mx, am,
               a90, fails);
        printf("csv,P,%s,%s,%.4f,%.3e,%.3e,%.3e,%.3e,%d\n", M[k].name, tol, us, med, p90, mx, am, fails);
    }
    for (int i = 0; i < n; i++) { floe_geometry_destroy(A[i].g); floe_geometry_destroy(B0[i].g); }

    /* ---- set B: axis-aligned boxes, both references exact ---- */
    double *mtd = malloc(sizeof(double) * n), (*mn)[3] = malloc(sizeof(double[3]) * n);
    int same = 0;
    double glpk_dev = 0;
    for (int i = 0; i < n; i++) {
        double ha[3], hb[3], cb[3], c0[3] = {0, 0, 0}, best = 1e300;
        int ax = 0;
        for (int k = 0; k < 3; k++) {
            ha[k] = 0.2 + 0.8 * urand();
            hb[k] = 0.2 + 0.8 * urand();
            double s = ha[k] + hb[k];
            cb[k] = (2 * urand() - 1) * 0.95 * s;
            double o = s - fabs(cb[k]);
            if (o < best) { best = o; ax = k; }
        }
        make_box(&A[i], ha, c0);
        make_box(&B0[i], hb, cb);
        B1[i] = B0[i];
        B1[i].plane = B1[i].planes_buf;
        B1[i].vb = ((const floe_box *)B1[i].g)->vert;
        mtd[i] = best;
        floe_v3_set(mn[i], 0, 0, 0);
        mn[i][ax] = cb[ax] >= 0 ? 1 : -1;
        /* deepest point in closed form: min over x in a of max_k (|x_k - c_k| - hb_k) is
         * separable, s1 = max_k (max(|c_k| - ha_k, 0) - hb_k), and s2 likewise */
        double s1 = -INFINITY, s2 = -INFINITY;
        int k1 = 0, k2 = 0;
        for (int k = 0; k < 3; k++) {
            double g1 = fmax(fabs(cb[k]) - ha[k], 0) - hb[k], g2 = fmax(fabs(cb[k]) - hb[k], 0) - ha[k];
            if (g1 > s1) { s1 = g1; k1 = k; }
            if (g2 > s2) { s2 = g2; k2 = k; }
        }
        int kk = -s1 >= -s2 ? k1 : k2;
        ref[i] = fmax(-s1, -s2);
        floe_v3_set(rn[i], 0, 0, 0);
        rn[i][kk] = cb[kk] >= 0 ? 1 : -1;
        int def;
        double ng[3], rg = dp_reference(&A[i], &B1[i], ng, &def);
        glpk_dev = fmax(glpk_dev, fabs(rg - ref[i]));
        same += fabs(ref[i] - mtd[i]) <= 1e-12;
    }
    printf("\nset B: %d axis-aligned box pairs (the peer's set, no motion: warm = re-solve of the same pose); "
           "deepest-point depth = minimum translation distance in %d of them (%.1f %%); closed-form "
           "deepest point vs GLPK: max |diff| %.1e\n",
           n, same, 100.0 * same / n, glpk_dev);
    printf("%-16s %-7s %10s | %-34s | %-34s | %s\n", "method", "tol", "us/pair", "depth err vs MTD (med p90 max)",
           "depth err vs deepest-point (med p90 max)", "within 1e-4 of MTD / fail");
    for (int k = 0; k < nm; k++) {
        int fails = 0;
        double us = 1e6 * run_method(&M[k], A, B0, B1, n, reps, depth, nrm, &fails);
        double med, p90, mx, dmed, dp90, dmx, within;
        errors(depth, nrm, mtd, mn, n, &med, &p90, &mx, NULL, NULL, &within);
        errors(depth, nrm, ref, rn, n, &dmed, &dp90, &dmx, NULL, NULL, NULL);
        char tol[16] = "-";
        if (M[k].kind != M_LP) snprintf(tol, sizeof tol, "%.0e", M[k].tol);
        printf("%-16s %-7s %10.3f | %10.2e %10.2e %10.2e   | %10.2e %10.2e %10.2e   | %5.1f %% / %d\n", M[k].name, tol,
               us, med, p90, mx, dmed, dp90, dmx, within, fails);
        printf("csv,B,%s,%s,%.4f,%.3e,%.3e,%.3e,%.3e,%.3e,%d\n", M[k].name, tol, us, med, p90, mx, dmed, dp90, fails);
    }
    for (int i = 0; i < n; i++) { floe_geometry_destroy(A[i].g); floe_geometry_destroy(B0[i].g); }
    free(A); free(B0); free(B1); free(ref); free(rn); free(mtd); free(mn); free(depth); free(nrm);
    return 0;
}
