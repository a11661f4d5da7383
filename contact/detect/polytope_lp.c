/* polytope_lp.c - exact deepest point between two convex polytopes (boxes, polyhedra,
 * polygons): the linear program  min s  s.t.  a_i.x <= b_i (faces of p),
 * c_j.x - s <= d_j (faces of p'), whose optimum x is p's point deepest inside p' and s its
 * SDF value (the SDF of a convex polytope is the largest face-plane distance inside).
 *
 * Why not ADMM here: with only an SDF, the prox of phi' at a ridge of a polytope (where two
 * faces' distance fields meet) is approximate, and ADMM stalls on ridges; measured on 500
 * random box pairs it missed the exact depth by more than 1e-3 x size in about half of them
 * (docs/models.md). The LP is exact, and warm-started from the previous step's basis it
 * usually needs no pivot at all. A dense primal simplex in dim + 1 variables (4 in 3D),
 * starting at the deepest vertex of p, with Bland's rule against cycling. */
#include "floe_polytope_lp.h"
#include <string.h>

/* LU factorisation with partial pivoting of M (n <= 4): P M = L U in place, perm[i] the row
 * of M that is row i of P M; 0 if singular (a pivot below 1e-12). One factorisation gives
 * the basis point (M y = h), the multipliers (M^T lam = e) and a pivot's edge (M d = -e_k). */
typedef struct lu4 { double a[4][4]; int perm[4], n; } lu4;

static int lu_factor(int n, const double M[4][4], lu4 *f) {
    f->n = n;
    for (int i = 0; i < n; i++) {
        f->perm[i] = i;
        for (int j = 0; j < n; j++) f->a[i][j] = M[i][j];
    }
    for (int c = 0; c < n; c++) {
        int p = c;
        for (int i = c + 1; i < n; i++)
            if (fabs(f->a[i][c]) > fabs(f->a[p][c])) p = i;
        if (fabs(f->a[p][c]) < 1e-12) return 0;
        if (p != c) {
            for (int j = 0; j < n; j++) { double t = f->a[c][j]; f->a[c][j] = f->a[p][j]; f->a[p][j] = t; }
            int t = f->perm[c]; f->perm[c] = f->perm[p]; f->perm[p] = t;
        }
        for (int i = c + 1; i < n; i++) {
            double l = f->a[i][c] / f->a[c][c];
            f->a[i][c] = l;
            for (int j = c + 1; j < n; j++) f->a[i][j] -= l * f->a[c][j];
        }
    }
    return 1;
}

/* M y = r */
static void lu_solve(const lu4 *f, const double r[4], double y[4]) {
    const int n = f->n;
    double z[4];
    for (int i = 0; i < n; i++) {
        double s = r[f->perm[i]];
        for (int j = 0; j < i; j++) s -= f->a[i][j] * z[j];
        z[i] = s;
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = z[i];
        for (int j = i + 1; j < n; j++) s -= f->a[i][j] * y[j];
        y[i] = s / f->a[i][i];
    }
}

/* M^T y = r: U^T z = r, L^T v = z, y[perm[i]] = v[i] */
static void lu_solve_t(const lu4 *f, const double r[4], double y[4]) {
    const int n = f->n;
    double z[4], v[4];
    for (int i = 0; i < n; i++) {
        double s = r[i];
        for (int j = 0; j < i; j++) s -= f->a[j][i] * z[j];
        z[i] = s / f->a[i][i];
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = z[i];
        for (int j = i + 1; j < n; j++) s -= f->a[j][i] * v[j];
        v[i] = s;
    }
    for (int i = 0; i < n; i++) y[f->perm[i]] = v[i];
}


/* the LP's row of plane pl in (x, s): an A row (a, 0) <= b, a B row (c, -1) <= d */
static inline void plane_row(const double *pl, int is_b, int dim, double r[4], double *h) {
    for (int i = 0; i < dim; i++) r[i] = pl[i];
    r[dim] = is_b ? -1.0 : 0.0;
    *h = pl[3];
}

/* A 3D basis solved in closed form (no LU): the rows (r_i, e_i) with e_i = 0 (p's faces) or
 * -1 (p''s), M y = h and M^T lam = (0, 0, 0, -1). Subtracting the first B row (c, d) from
 * the other B rows leaves three equations in x alone, R x = g (rows a_i | c_j - c, right-hand
 * sides b_i | d_j - d), solved by Cramer's rule with the cofactor rows u_k (one division);
 * then s = c.x - d. The multipliers: sum lam_i r_i = 0 and the B rows' sum to 1, so with lam_c
 * = 1 - (the others' B multipliers), R^T z = -c: z_k = -u_k.c / det. 0 if there is no B row
 * or |det| < 1e-12 (singular: the caller takes the LU path). Every basis kind (a corner of p
 * on a face of p', edge on edge, face on a corner) the same way. */
typedef struct basis3 {
    const double *c;  /* the first B row's plane */
    int ib;           /* its place in the basis */
    double sb[3];     /* the other rows: 1 for a B row, 0 for an A row */
    double u[3][3];   /* the cofactor rows of R */
    double inv;       /* 1 / det R */
} basis3;

/* the reduction of basis rows M (above): 0 without a B row or when |det| < 1e-12 */
static inline int basis3_setup(const double M[4][4], basis3 *B) {
    /* which rows are B rows decides nothing by a branch: the basis kind varies from pair to
     * pair, and a branch on it was mispredicted (a tenth of the LP's time); a B row's shift
     * by c is a product by 1 or 0, exact, so the same values as the selection */
    const int b0 = M[0][3] != 0.0, b1 = M[1][3] != 0.0, b2 = M[2][3] != 0.0, b3 = M[3][3] != 0.0;
    if (!(b0 | b1 | b2 | b3)) return 0;
    const int ib = !b0 * (1 + !b1 * (1 + !b2)); /* the first B row */
    const double *c = M[ib];
    double r[3][3];
    B->c = c;
    B->ib = ib;
    for (int k = 0; k < 3; k++) {
        const double *q = M[k + (k >= ib)]; /* the other rows, in order */
        B->sb[k] = (double)(q[3] != 0.0);
        for (int i = 0; i < 3; i++) r[k][i] = q[i] - B->sb[k] * c[i];
    }
    floe_v3_cross(B->u[0], r[1], r[2]);
    floe_v3_cross(B->u[1], r[2], r[0]);
    floe_v3_cross(B->u[2], r[0], r[1]);
    const double det = floe_v3_dot(r[0], B->u[0]);
    if (!(fabs(det) >= 1e-12)) return 0;
    B->inv = 1.0 / det;
    return 1;
}

/* M y = h by the reduction: R x = g, then s = c.x - h_ib */
static inline void basis3_solve(const basis3 *B, const double h[4], double y[4]) {
    const int ib = B->ib;
    const double *c = B->c;
    double g[3];
    for (int k = 0; k < 3; k++) g[k] = h[k + (k >= ib)] - B->sb[k] * h[ib];
    for (int i = 0; i < 3; i++) y[i] = (g[0] * B->u[0][i] + g[1] * B->u[1][i] + g[2] * B->u[2][i]) * B->inv;
    y[3] = c[0] * y[0] + c[1] * y[1] + c[2] * y[2] - h[ib];
}

static inline int basis_solve3(const double M[4][4], const double h[4], double y[4], double lam[4]) {
    basis3 B;
    if (!basis3_setup(M, &B)) return 0;
    basis3_solve(&B, h, y);
    double lc = 1.0;
    for (int k = 0; k < 3; k++) {
        const double z = -floe_v3_dot(B.u[k], B.c) * B.inv;
        lam[k + (k >= B.ib)] = z;
        lc -= B.sb[k] * z;
    }
    lam[B.ib] = lc;
    return 1;
}

/* row k of the LP: A rows 0..na-1, then B rows */
static void row(const floe_lp_problem *P, int k, double r[4], double *h) {
    const int is_b = k >= P->na;
    plane_row(is_b ? P->b + 4 * (k - P->na) : P->a + 4 * k, is_b, P->dim, r, h);
}

/* the basis rows' matrix and right-hand side, factorised; 0 if singular */
static int basis_factor(const floe_lp_problem *P, const int *basis, lu4 *f, double h[4]) {
    const int n = P->dim + 1;
    double M[4][4];
    for (int i = 0; i < n; i++) row(P, basis[i], M[i], &h[i]);
    return lu_factor(n, M, f);
}

/* every row holds at y (within tol): p's faces a.x <= b, then p''s c.x - s <= d */
static int feasible(const floe_lp_problem *P, const double y[4], double tol) {
    const double *a = P->a, *b = P->b;
    if (P->dim == 3) {
        for (int k = 0; k < P->na; k++, a += 4)
            if (a[0] * y[0] + a[1] * y[1] + a[2] * y[2] > a[3] + tol) return 0;
        for (int k = 0; k < P->nb; k++, b += 4)
            if (b[0] * y[0] + b[1] * y[1] + b[2] * y[2] - y[3] > b[3] + tol) return 0;
    } else {
        for (int k = 0; k < P->na; k++, a += 4)
            if (a[0] * y[0] + a[1] * y[1] > a[3] + tol) return 0;
        for (int k = 0; k < P->nb; k++, b += 4)
            if (b[0] * y[0] + b[1] * y[1] - y[2] > b[3] + tol) return 0;
    }
    return 1;
}

/* cold start: the vertex of p deepest in p' (largest B row), with dim tight, independent
 * A rows */
static int cold_basis(const floe_lp_problem *P, int *basis, double tol) {
    int dim = P->dim, best = -1;
    double bs = INFINITY;
    for (int v = 0; v < P->nva; v++) {
        const double *x = P->va + 3 * v;
        double s = -INFINITY;
        for (int j = 0; j < P->nb; j++) {
            const double *c = P->b + 4 * j;
            double val = c[0] * x[0] + c[1] * x[1] + (dim == 3 ? c[2] * x[2] : 0.0) - c[3];
            if (val > s) s = val;
        }
        if (s < bs) { bs = s; best = v; }
    }
    if (best < 0) return 0;
    const double *x = P->va + 3 * best;
    int nt = 0;
    double N[3][3];
    for (int i = 0; i < P->na && nt < dim; i++) {
        const double *a = P->a + 4 * i;
        double val = a[0] * x[0] + a[1] * x[1] + (dim == 3 ? a[2] * x[2] : 0.0) - a[3];
        if (fabs(val) > tol) continue;
        /* independent of those taken */
        double c[3] = {a[0], a[1], dim == 3 ? a[2] : 0.0};
        int indep = 1;
        if (nt == 1) {
            double cr[3];
            floe_v3_cross(cr, N[0], c);
            indep = floe_v3_norm(cr) > 1e-9;
        } else if (nt == 2) {
            double cr[3];
            floe_v3_cross(cr, N[0], N[1]);
            indep = fabs(floe_v3_dot(cr, c)) > 1e-9;
        }
        if (!indep) continue;
        floe_v3_copy(N[nt], c);
        basis[nt++] = i;
    }
    if (nt < dim) return 0;
    /* the B row attaining the max */
    int jb = 0;
    double s = -INFINITY;
    for (int j = 0; j < P->nb; j++) {
        const double *c = P->b + 4 * j;
        double val = c[0] * x[0] + c[1] * x[1] + (dim == 3 ? c[2] * x[2] : 0.0) - c[3];
        if (val > s) { s = val; jb = j; }
    }
    basis[dim] = P->na + jb;
    return 1;
}

/* plane k of p' in p's frame from its own (floe_lp_problem.b_body, map) */
static inline void b_plane(const floe_lp_problem *P, int k, double o[4]) {
    const double *Q = P->b_body + 4 * k, *M = P->map, *m = P->map + 9;
    for (int i = 0; i < 3; i++) o[i] = M[i] * Q[0] + M[3 + i] * Q[1] + M[6 + i] * Q[2];
    o[3] = Q[3] - (Q[0] * m[0] + Q[1] * m[1] + Q[2] * m[2]);
}

static void lp_finish(const floe_lp_problem *P, const int *basis, const double y[4], const double (*brow)[4],
                      floe_lp_result *res);

/* the ratios of rows [k0, k0 + nk) of one kind (planes pl, 4 doubles each; e = 0 for p's,
 * -1 for p''s) from y along d: (h - r.y) / (r.d) where r.d > 1e-12 (at least 0), else
 * infinite; the sums as the LU path's loops add them. Without a branch (a vector loop) */
static inline void ratios(int dim, const double *pl, double e, int nk, const double y[4], const double d[4],
                          double *rat) {
    if (dim == 3)
        for (int k = 0; k < nk; k++) {
            const double *r = pl + 4 * k;
            const double rd = 0.0 + r[0] * d[0] + r[1] * d[1] + r[2] * d[2] + e * d[3];
            const double ry = 0.0 + r[0] * y[0] + r[1] * y[1] + r[2] * y[2] + e * y[3];
            const double a = (r[3] - ry) / rd;
            rat[k] = rd <= 1e-12 ? INFINITY : a < 0 ? 0.0 : a;
        }
    else
        for (int k = 0; k < nk; k++) {
            const double *r = pl + 4 * k;
            const double rd = 0.0 + r[0] * d[0] + r[1] * d[1] + e * d[2];
            const double ry = 0.0 + r[0] * y[0] + r[1] * y[1] + e * y[2];
            const double a = (r[3] - ry) / rd;
            rat[k] = rd <= 1e-12 ? INFINITY : a < 0 ? 0.0 : a;
        }
}

/* the primal simplex's ratio test from y along the edge d: the row outside the basis that
 * becomes tight first (the lowest row on a tie within 1e-15), *alpha the step; -1 when none
 * (unbounded). The ratios a chunk of rows at a time without a branch, then the choice in
 * row order (a branch per row, two of them unpredictable, cost about 50 cycles a row) */
static int ratio_test(const floe_lp_problem *P, const int *basis, const double y[4], const double d[4], double *alpha) {
    const int n = P->dim + 1, na = P->na, m = na + P->nb;
    int enter = -1;
    double al = INFINITY, rat[64];
    for (int k0 = 0; k0 < m; k0 += 64) {
        const int k1 = k0 + 64 < m ? k0 + 64 : m;
        const int ka = na < k0 ? k0 : na < k1 ? na : k1; /* [k0, ka) A rows, [ka, k1) B rows */
        if (ka > k0) ratios(P->dim, P->a + 4 * k0, 0.0, ka - k0, y, d, rat);
        if (k1 > ka) ratios(P->dim, P->b + 4 * (ka - na), -1.0, k1 - ka, y, d, rat + (ka - k0));
        for (int i = 0; i < n; i++)
            if (basis[i] >= k0 && basis[i] < k1) rat[basis[i] - k0] = INFINITY; /* the basis rows: out */
        for (int k = k0; k < k1; k++) {
            const double a = rat[k - k0];
            if (a < al - 1e-15 || (a <= al + 1e-15 && enter >= 0 && k < enter)) { al = a; enter = k; }
        }
    }
    *alpha = al;
    return enter;
}

/* 3D, a warm basis feasible at y but not optimal (lam, a multiplier below -1e-12; every row
 * of P->b): the simplex's pivots with each basis solved in closed form (basis3: the edge
 * M d = -e_leave, then the new basis' point and multipliers as a kept basis gets them), not
 * by the LU path's factorisations. A resting contact whose deepest point moves to the next
 * corner of a face needs one pivot (98 % of the pivoting halves of a settled polyhedra bed,
 * 3 % of all): on the LU path each cost about ten kept halves. 1 with the optimum's basis,
 * y and lam and *pivots (its point tested against every row, as a kept basis's); 0 (basis
 * untouched) when a basis is singular, an edge unbounded, the optimum's point outside a row
 * by more than the tolerance or no optimum within LP_PIVOTS3 pivots (P->pivots3_cap where set):
 * the LU path then starts from the given basis */
#define LP_PIVOTS3 8
static int lp_pivot3(const floe_lp_problem *P, int *basis, double y[4], double lam[4], int *pivots) {
    const int cap = P->pivots3_cap ? P->pivots3_cap : LP_PIVOTS3;
    int bs[4];
    memcpy(bs, basis, sizeof bs);
    double M[4][4], h[4];
    for (int i = 0; i < 4; i++) row(P, bs[i], M[i], &h[i]);
    for (int it = 1; it <= cap; it++) {
        int leave = -1; /* Bland: the lowest row among the negative multipliers */
        for (int i = 0; i < 4; i++)
            if (lam[i] < -1e-12 && (leave < 0 || bs[i] < bs[leave])) leave = i;
        double e[4] = {0, 0, 0, 0}, d[4], alpha;
        basis3 B;
        if (leave < 0 || !basis3_setup(M, &B)) return 0;
        e[leave] = -1.0; /* r_leave . d = -1, the other basis rows stay tight */
        basis3_solve(&B, e, d);
        const int enter = ratio_test(P, bs, y, d, &alpha);
        if (enter < 0) return 0;
        bs[leave] = enter;
        row(P, enter, M[leave], &h[leave]);
        if (!basis_solve3(M, h, y, lam)) return 0;
        int opt = 1;
        for (int i = 0; i < 4; i++) opt &= lam[i] >= -1e-12;
        if (opt) { /* the new basis's own point, tested as a kept basis's is */
            const double tol = 1e-12 * (P->scale > 0 ? P->scale : 1.0); /* floe_lp_deepest's */
            if (!feasible(P, y, 1e3 * tol)) return 0;
            memcpy(basis, bs, sizeof bs);
            *pivots = it;
            return 1;
        }
    }
    return 0;
}

/* The lazy problem's warm start (b_body): 1 when the given basis is feasible and optimal (res
 * set, no pivot), 0 when the full problem must be solved. The basis rows are those of the
 * full problem (the same planes, the same factorisation: the same result); the other rows of
 * p' are checked at y's point mapped into p''s frame. */
static int lp_warm_lazy(const floe_lp_problem *P, const int *basis, floe_lp_result *res) {
    const int n = 4, na = P->na, m = na + P->nb;
    const double tol = 1e-12 * (P->scale > 0 ? P->scale : 1.0), ftol = 1e3 * tol;
    double M[4][4], h[4], brow[4][4], y[4];
    for (int i = 0; i < n; i++) {
        const int k = basis[i];
        if (k < 0 || k >= m) return 0;
        if (k < na) plane_row(P->a + 4 * k, 0, 3, M[i], &h[i]);
        else {
            b_plane(P, k - na, brow[i]);
            plane_row(brow[i], 1, 3, M[i], &h[i]);
        }
    }
    double lam[4];
    if (!basis_solve3(M, h, y, lam)) return 0;
    /* every row tested, without an exit per row (the same decisions; the loops vectorise;
     * from the planes' rows by coordinate where the shapes give them, 8 planes a vector, the
     * padded ones always held) */
    const double *a = P->a;
    int bad = 0;
    if (P->a_soa) {
        const int m4 = P->na_soa;
        const double *n0 = P->a_soa, *n1 = n0 + m4, *n2 = n1 + m4, *d = n2 + m4;
        for (int k = 0; k < m4; k++) bad |= n0[k] * y[0] + n1[k] * y[1] + n2[k] * y[2] > d[k] + ftol;
    } else
        for (int k = 0; k < na; k++)
            bad |= a[4 * k] * y[0] + a[4 * k + 1] * y[1] + a[4 * k + 2] * y[2] > a[4 * k + 3] + ftol;
    const double *Mm = P->map, *mm = P->map + 9;
    double X[3];
    for (int i = 0; i < 3; i++) X[i] = Mm[3 * i] * y[0] + Mm[3 * i + 1] * y[1] + Mm[3 * i + 2] * y[2] + mm[i];
    const double *b = P->b_body;
    if (P->b_soa) {
        const int m4 = P->nb_soa;
        const double *n0 = P->b_soa, *n1 = n0 + m4, *n2 = n1 + m4, *d = n2 + m4;
        for (int k = 0; k < m4; k++) bad |= n0[k] * X[0] + n1[k] * X[1] + n2[k] * X[2] - y[3] > d[k] + ftol;
    } else
        for (int k = 0; k < P->nb; k++)
            bad |= b[4 * k] * X[0] + b[4 * k + 1] * X[1] + b[4 * k + 2] * X[2] - y[3] > b[4 * k + 3] + ftol;
    if (bad) return 0;
    for (int i = 0; i < n; i++)
        if (lam[i] < -1e-12) return 0; /* a pivot: the full problem */
    memset(res, 0, sizeof *res);
    res->warm = 1;
    memcpy(res->lambda, lam, sizeof lam);
    lp_finish(P, basis, y, (const double (*)[4])brow, res);
    return 1;
}

int floe_lp_deepest(const floe_lp_problem *P, int *basis, floe_lp_result *res) {
    if (P->b_body) {
        if (P->dim == 3 && basis[0] >= 0 && lp_warm_lazy(P, basis, res)) return FLOE_OK;
        floe_lp_problem F = *P; /* every row: p''s planes into the buffer */
        for (int k = 0; k < P->nb; k++) b_plane(P, k, P->b_buf + 4 * k);
        F.b = P->b_buf;
        F.b_body = NULL;
        F.map = NULL;
        return floe_lp_deepest(&F, basis, res);
    }
    const int dim = P->dim, n = dim + 1, m = P->na + P->nb;
    const double tol = 1e-12 * (P->scale > 0 ? P->scale : 1.0);
    double y[4], h[4];
    lu4 f;
    memset(res, 0, sizeof *res);
    /* warm start: the previous optimum's rows, if they still meet at a feasible point (a
     * resting contact: then usually still optimal, and the loop below stops at once) */
    int ok = basis[0] >= 0;
    for (int i = 0; ok && i < n; i++) ok = basis[i] >= 0 && basis[i] < m;
    if (ok && dim == 3) { /* kept as it is (the lazy path's test, the same operations) */
        double M[4][4], lam[4];
        for (int i = 0; i < n; i++) row(P, basis[i], M[i], &h[i]);
        const int feas = basis_solve3(M, h, y, lam) && feasible(P, y, 1e3 * tol);
        int kept = feas;
        for (int i = 0; kept && i < n; i++) kept = lam[i] >= -1e-12;
        if (kept || (feas && lp_pivot3(P, basis, y, lam, &res->pivots))) {
            res->warm = 1;
            memcpy(res->lambda, lam, sizeof lam);
            lp_finish(P, basis, y, NULL, res);
            return FLOE_OK;
        }
        res->taken_over = feas; /* (y and lam are the LU path's from here) */
    }
    if (ok) ok = basis_factor(P, basis, &f, h);
    if (ok) {
        lu_solve(&f, h, y);
        ok = feasible(P, y, 1e3 * tol);
    }
    res->warm = ok;
    if (!ok) {
        if (!cold_basis(P, basis, 1e-9 * (P->scale > 0 ? P->scale : 1.0)) || !basis_factor(P, basis, &f, h))
            return FLOE_EINVAL;
        lu_solve(&f, h, y);
    }
    int it;
    for (it = 0; it < 200; it++) {
        double lam[4], rhs[4] = {0, 0, 0, 0};
        if (it > 0 && !basis_factor(P, basis, &f, h)) return FLOE_EINVAL;
        rhs[n - 1] = -1.0;
        lu_solve_t(&f, rhs, lam); /* M^T lam = (0, .., -1): the objective min s */
        /* leaving row: Bland (lowest row index among the negative multipliers) */
        int leave = -1;
        for (int i = 0; i < n; i++)
            if (lam[i] < -1e-12 && (leave < 0 || basis[i] < basis[leave])) leave = i;
        if (leave < 0) {
            memcpy(res->lambda, lam, sizeof lam);
            break;
        }
        /* edge direction: r_leave . d = -1, other basis rows stay tight */
        double e[4] = {0, 0, 0, 0}, d[4], alpha;
        e[leave] = -1.0;
        lu_solve(&f, e, d);
        const int enter = ratio_test(P, basis, y, d, &alpha);
        if (enter < 0) return FLOE_EINVAL; /* unbounded: cannot happen for bounded p */
        for (int i = 0; i < n; i++) y[i] += alpha * d[i];
        basis[leave] = enter;
    }
    res->pivots = it;
    if (it >= 200) return FLOE_EINVAL;
    lp_finish(P, basis, y, NULL, res);
    return FLOE_OK;
}

/* the optimum's point, value and normal from the basis, y and res->lambda (brow: the basis
 * rows' planes of p' in p's frame, or NULL: P->b's) */
static void lp_finish(const floe_lp_problem *P, const int *basis, const double y[4], const double (*brow)[4],
                      floe_lp_result *res) {
    const int dim = P->dim, n = dim + 1;
    for (int i = 0; i < dim; i++) res->x[i] = y[i];
    if (dim == 2) res->x[2] = 0.0;
    res->s = y[n - 1];
    /* subgradient of phi' at x: the multipliers of p''s rows (they sum to 1) */
    double g[3] = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        if (basis[i] < P->na) continue;
        const double *c = brow ? brow[i] : P->b + 4 * (basis[i] - P->na);
        for (int k = 0; k < dim; k++) g[k] += res->lambda[i] * c[k];
    }
    double gn = floe_v3_norm(g);
    if (gn > 1e-9) {
        floe_v3_scale(g, 1.0 / gn);
        res->gnorm = gn > 1 ? 1.0 : gn;
    } else { /* the normals cancel (coincident shapes): the face of the largest multiplier */
        int best = -1;
        for (int i = 0; i < n; i++)
            if (basis[i] >= P->na && (best < 0 || res->lambda[i] > res->lambda[best])) best = i;
        floe_v3_set(g, 0, 0, 0);
        if (best >= 0)
            for (int k = 0; k < dim; k++) g[k] = brow ? brow[best][k] : P->b[4 * (basis[best] - P->na) + k];
        double gb = floe_v3_norm(g);
        if (gb > 0) floe_v3_scale(g, 1.0 / gb);
        res->gnorm = 1.0;
    }
    floe_v3_copy(res->normal, g);
}
