/* newmark_solve.c - the Newmark-beta solves: the sparse K, C, M pattern and CHOLMOD
 * factors with rank-one downdates for broken bonds (implicit), block-diagonal node solves
 * (explicit). */
#include "newmark_base.h"

/* ---- sparse matrix (implicit) ---- */

#ifdef FLOE_HAVE_CHOLMOD
typedef struct { int r, c; } rc_pair;
static int cmp_rc(const void *a, const void *b) {
    const rc_pair *x = a, *y = b;
    if (x->c != y->c) return (x->c > y->c) - (x->c < y->c);
    return (x->r > y->r) - (x->r < y->r);
}

static int find_pos(const cholmod_sparse *A, int r, int c) {
    const int *Ap = A->p, *Ai = A->i;
    int lo = Ap[c], hi = Ap[c + 1];
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (Ai[mid] < r) lo = mid + 1;
        else hi = mid;
    }
    return lo < Ap[c + 1] && Ai[lo] == r ? lo : -1;
}

/* equation numbers of the 2 nd components of bond b's ends */
static void bond_eqs(const floe_newmark *s, const nm_bond *b, int *e) {
    for (int k = 0; k < s->nd; k++) {
        e[k] = s->eq[s->nd * b->i + k];
        e[s->nd + k] = s->eq[s->nd * b->j + k];
    }
}

/* the pattern: every node's diagonal block and every bond's block, upper triangle */
int build_pattern(floe_newmark *s) {
    const int nd = s->nd, n2 = 2 * nd;
    size_t cap = (size_t)s->n * nd * nd + (size_t)s->nb * n2 * n2 + 1;
    rc_pair *pr = malloc(cap * sizeof *pr);
    if (!pr) return nm_error(s, FLOE_ENOMEM, "out of memory");
    size_t m = 0;
    for (int i = 0; i < s->n; i++)
        for (int p = 0; p < nd; p++)
            for (int q = 0; q < nd; q++) {
                int r = s->eq[nd * i + p], c = s->eq[nd * i + q];
                if (r >= 0 && c >= 0 && r <= c) pr[m++] = (rc_pair){r, c};
            }
    int e[12];
    for (int k = 0; k < s->nb; k++) {
        bond_eqs(s, &s->b[k], e);
        for (int p = 0; p < n2; p++)
            for (int q = 0; q < n2; q++)
                if (e[p] >= 0 && e[q] >= 0 && e[p] <= e[q]) pr[m++] = (rc_pair){e[p], e[q]};
    }
    qsort(pr, m, sizeof *pr, cmp_rc);
    size_t u = 0;
    for (size_t k = 0; k < m; k++)
        if (u == 0 || pr[k].r != pr[u - 1].r || pr[k].c != pr[u - 1].c) pr[u++] = pr[k];
    s->A = cholmod_allocate_sparse((size_t)s->neq, (size_t)s->neq, u, 1, 1, 1, CHOLMOD_REAL, &s->cc);
    if (!s->A) { free(pr); return nm_error(s, FLOE_ENOMEM, "CHOLMOD: out of memory for the matrix"); }
    int *Ap = s->A->p, *Ai = s->A->i;
    memset(Ap, 0, ((size_t)s->neq + 1) * sizeof *Ap);
    for (size_t k = 0; k < u; k++) { Ap[pr[k].c + 1]++; Ai[k] = pr[k].r; }
    for (int c = 0; c < s->neq; c++) Ap[c + 1] += Ap[c];
    free(pr);
    s->bpos = malloc(((size_t)s->nb * n2 * n2 + 1) * sizeof *s->bpos);
    s->npos = malloc(((size_t)s->n * nd * nd + 1) * sizeof *s->npos);
    if (!s->bpos || !s->npos) return nm_error(s, FLOE_ENOMEM, "out of memory");
    for (int i = 0; i < s->n; i++)
        for (int p = 0; p < nd; p++)
            for (int q = 0; q < nd; q++) {
                int r = s->eq[nd * i + p], c = s->eq[nd * i + q];
                s->npos[(size_t)i * nd * nd + p * nd + q] = r >= 0 && c >= 0 && r <= c ? find_pos(s->A, r, c) : -1;
            }
    for (int k = 0; k < s->nb; k++) {
        bond_eqs(s, &s->b[k], e);
        for (int p = 0; p < n2; p++)
            for (int q = 0; q < n2; q++)
                s->bpos[(size_t)k * n2 * n2 + p * n2 + q] =
                    e[p] >= 0 && e[q] >= 0 && e[p] <= e[q] ? find_pos(s->A, e[p], e[q]) : -1;
    }
    return FLOE_OK;
}

/* global stiffness of bond b: T^T K T (2 nd x 2 nd, row-major) */
static void bond_global_k(const floe_newmark *s, const nm_bond *b, double *Kg) {
    const int n2 = 2 * s->nd;
    double K[144], col[12], fl[12];
    floe_beam_local_stiffness(&b->s, s->dim, K);
    /* column q of T^T K T = T^T K (T e_q): a unit global component through the kernels */
    nm_bond tmp = *b;
    double g[12];
    for (int q = 0; q < n2; q++) {
        memset(g, 0, sizeof g);
        g[q] = 1;
        /* to_local/add_global index nodes: use a two-node scratch layout (ends 0 and 1) */
        tmp.i = 0;
        tmp.j = 1;
        to_local(s, &tmp, g, col);
        for (int r = 0; r < n2; r++) {
            double acc = 0;
            for (int c = 0; c < n2; c++) acc += K[r * n2 + c] * col[c];
            fl[r] = acc;
        }
        double out[12] = {0};
        add_global(s, &tmp, fl, 1.0, out);
        for (int r = 0; r < n2; r++) Kg[r * n2 + q] = out[r];
    }
}

/* numeric values of K beta dt^2 + C gamma dt + M and the factor in slot k */
int factor(floe_newmark *s, int slot, double dt) {
    double t0 = now_s();
    const int nd = s->nd, nn = nd * nd, n2 = 2 * nd;
    double *Ax = s->A->x;
    memset(Ax, 0, s->A->nzmax * sizeof *Ax);
    const double kb = s->def.beta * dt * dt, cg = s->def.gamma * dt;
    for (int i = 0; i < s->n; i++) {
        const int *pos = s->npos + (size_t)nn * i;
        const double *C = s->cblk + (size_t)nn * i;
        for (int p = 0; p < nd; p++)
            for (int q = 0; q < nd; q++) {
                int at = pos[p * nd + q];
                if (at < 0) continue;
                Ax[at] += cg * C[p * nd + q] + (p == q ? node_m(s, i, p) : 0.0);
            }
    }
    double Kg[144];
    for (int k = 0; k < s->nb; k++) {
        const nm_bond *b = &s->b[k];
        if (b->broken) continue;
        bond_global_k(s, b, Kg);
        const int *pos = s->bpos + (size_t)k * n2 * n2;
        for (int p = 0; p < n2; p++)
            for (int q = 0; q < n2; q++)
                if (pos[p * n2 + q] >= 0) Ax[pos[p * n2 + q]] += kb * Kg[p * n2 + q];
    }
    if (!s->L[slot]) {
        s->L[slot] = cholmod_analyze(s->A, &s->cc);
        if (!s->L[slot]) return nm_error(s, FLOE_ENOMEM, "CHOLMOD analyze failed (status %d)", s->cc.status);
    }
    if (!cholmod_factorize(s->A, s->L[slot], &s->cc) || s->cc.status != CHOLMOD_OK)
        return nm_error(s, s->cc.status == CHOLMOD_NOT_POSDEF ? FLOE_EUNSTABLE : FLOE_ENOMEM,
                        "CHOLMOD factorize failed (status %d%s)", s->cc.status,
                        s->cc.status == CHOLMOD_NOT_POSDEF ? ": the matrix is not positive definite" : "");
    s->Ldt[slot] = dt;
    s->Lepoch[slot] = s->epoch;
    s->since_refactor[slot] = 0;
    s->st.factorizations++;
    s->st.seconds_factor += now_s() - t0;
    return FLOE_OK;
}

/* x = A(dt)^-1 rhs over the free components (refactoring when needed) */
int solve_implicit(floe_newmark *s, double dt, const double *rhs, double *x) {
    /* the slot factored for this step at the present bonds, else the least recently used */
    int slot = -1;
    for (int k = 0; k < NM_SLOTS && slot < 0; k++)
        if (s->L[k] && s->Ldt[k] == dt && s->Lepoch[k] == s->epoch) slot = k;
    if (slot < 0) {
        slot = 0;
        for (int k = 1; k < NM_SLOTS; k++)
            if (!s->L[k] || (s->L[slot] && s->Lused[k] < s->Lused[slot])) slot = k;
        FLOE_TRY(factor(s, slot, dt));
    }
    s->Lused[slot] = ++s->use_clock;
    double t0 = now_s();
    double *Bx = s->B->x;
    const int N = s->nd * s->n;
    for (int k = 0; k < N; k++)
        if (s->eq[k] >= 0) Bx[s->eq[k]] = rhs[k];
    if (!cholmod_solve2(CHOLMOD_A, s->L[slot], s->B, NULL, &s->X, NULL, &s->Y, &s->E, &s->cc))
        return nm_error(s, FLOE_ENOMEM, "CHOLMOD solve failed (status %d)", s->cc.status);
    const double *Xx = s->X->x;
    for (int k = 0; k < N; k++) x[k] = s->eq[k] >= 0 ? Xx[s->eq[k]] : 0.0;
    s->st.seconds_solve += now_s() - t0;
    return FLOE_OK;
}


/* the bond's term of K beta dt^2 + C gamma dt (2 nd x 2 nd): stiffness and its eq 8 dampers */
static void bond_term(const floe_newmark *s, const nm_bond *b, double dt, double *Bm) {
    const int nd = s->nd, n2 = 2 * nd;
    bond_global_k(s, b, Bm);
    for (int k = 0; k < n2 * n2; k++) Bm[k] *= s->def.beta * dt * dt;
    const double cg = s->def.gamma * dt;
    double D[36];
    bond_damper_block(nd, b, D);
    for (int e = 0; e < 2; e++) {
        int o = nd * e;
        for (int p = 0; p < nd; p++)
            for (int q = 0; q < nd; q++) Bm[(o + p) * n2 + o + q] += cg * D[p * nd + q];
    }
}

typedef struct { int row; double x; } nz_entry;
static int cmp_nz(const void *a, const void *b) {
    const nz_entry *x = a, *y = b;
    return (x->row > y->row) - (x->row < y->row);
}

/* remove the bonds broken[0 .. nbr) from the factor in slot by one multiple-rank
 * downdate: each bond's PSD term split as sum_k (sqrt(lambda_k) v_k)(sqrt(lambda_k) v_k)^T */
int downdate_bonds(floe_newmark *s, int slot, const int *broken, int nbr) {
    double t0 = now_s();
    const int nd = s->nd, n2 = 2 * nd;
    if (!s->pinv) { /* both slots share the ordering of the same pattern */
        s->pinv = malloc(((size_t)s->neq + 1) * sizeof *s->pinv);
        if (!s->pinv) return nm_error(s, FLOE_ENOMEM, "out of memory");
        const int *P = s->L[slot]->Perm;
        for (int k = 0; k < s->neq; k++) s->pinv[P[k]] = k;
    }
    cholmod_sparse *C = cholmod_allocate_sparse((size_t)s->neq, (size_t)nbr * n2, (size_t)nbr * n2 * n2, 1, 1, 0,
                                                CHOLMOD_REAL, &s->cc);
    if (!C) return nm_error(s, FLOE_ENOMEM, "CHOLMOD: out of memory for a downdate");
    int *Cp = C->p, *Ci = C->i;
    double *Cx = C->x;
    int ncol = 0, nnz = 0;
    Cp[0] = 0;
    for (int q = 0; q < nbr; q++) {
        const nm_bond *b = &s->b[broken[q]];
        double Bm[144], A[144], V[144];
        int e[12], fr[12], m = 0;
        bond_eqs(s, b, e);
        bond_term(s, b, s->Ldt[slot], Bm);
        for (int p = 0; p < n2; p++)
            if (e[p] >= 0) fr[m++] = p;
        for (int p = 0; p < m; p++)
            for (int r = 0; r < m; r++) A[p * m + r] = 0.5 * (Bm[fr[p] * n2 + fr[r]] + Bm[fr[r] * n2 + fr[p]]);
        floe_sym_eigen(A, m, V); /* core/base/floe_linalg.h */
        double lmax = 0;
        for (int k = 0; k < m; k++) lmax = fmax(lmax, A[k * m + k]);
        for (int k = 0; k < m; k++) {
            double lam = A[k * m + k];
            if (!(lam > 1e-13 * lmax)) continue; /* rigid modes of the bond (zero) */
            nz_entry col[12];
            int c = 0;
            for (int p = 0; p < m; p++) {
                double x = sqrt(lam) * V[p * m + k];
                if (x != 0) col[c++] = (nz_entry){s->pinv[e[fr[p]]], x};
            }
            qsort(col, (size_t)c, sizeof *col, cmp_nz);
            for (int p = 0; p < c; p++) { Ci[nnz] = col[p].row; Cx[nnz] = col[p].x; nnz++; }
            Cp[++ncol] = nnz;
        }
    }
    C->ncol = (size_t)ncol;
    int ok = ncol == 0 || cholmod_updown(0, C, s->L[slot], &s->cc);
    cholmod_free_sparse(&C, &s->cc);
    s->st.seconds_factor += now_s() - t0;
    if (!ok || s->cc.status != CHOLMOD_OK) return nm_error(s, FLOE_ENOMEM, "CHOLMOD downdate failed (status %d)", s->cc.status);
    s->st.downdates += nbr;
    s->since_refactor[slot] += nbr;
    return FLOE_OK;
}

#endif

/* x = (M + gamma dt C)^-1 rhs, node by node (explicit) */
int solve_explicit(floe_newmark *s, double dt, const double *rhs, double *x) {
    if (s->ablk_dt != dt || s->ablk_epoch != s->epoch) FLOE_TRY(build_ablk(s, dt));
    double t0 = now_s();
    const int nd = s->nd, nn = nd * nd, n = s->n;
    const int nt = nm_threads(s, (long)nd * n);
    FLOE_OMP(omp parallel for num_threads(nt) schedule(static) if(nt > 1)) /* element-wise: the same bits */
    for (int i = 0; i < n; i++) {
        const double *O = s->ablk + (size_t)nn * i, *r = rhs + (size_t)nd * i;
        double *o = x + (size_t)nd * i;
        for (int p = 0; p < nd; p++) {
            double acc = 0;
            for (int q = 0; q < nd; q++) acc += O[p * nd + q] * r[q];
            o[p] = acc;
        }
    }
    s->st.seconds_solve += now_s() - t0;
    return FLOE_OK;
}

/* explicit: inverse of the free part of M + gamma dt C for every node (Gauss-Jordan on at
 * most 6 x 6, symmetric positive definite) */
int build_ablk(floe_newmark *s, double dt) {
    const int nd = s->nd, nn = nd * nd, n = s->n, nt = nm_threads(s, (long)nd * n);
    int bad = n; /* the lowest node whose block is not positive definite (any thread count) */
    FLOE_OMP(omp parallel for num_threads(nt) schedule(static) if(nt > 1) reduction(min : bad))
    for (int i = 0; i < n; i++) {
        double A[36], Inv[36];
        int fr[6], m = 0;
        for (int k = 0; k < nd; k++)
            if (s->eq[nd * i + k] >= 0) fr[m++] = k;
        for (int p = 0; p < m; p++)
            for (int q = 0; q < m; q++) {
                A[p * m + q] = s->def.gamma * dt * s->cblk[(size_t)nn * i + fr[p] * nd + fr[q]];
                Inv[p * m + q] = p == q;
            }
        for (int p = 0; p < m; p++) A[p * m + p] += node_m(s, i, fr[p]);
        int pd = 1;
        for (int c = 0; c < m && pd; c++) {
            double piv = A[c * m + c];
            if (!(piv > 0)) {
                pd = 0;
                if (i < bad) bad = i;
                break;
            }
            for (int q = 0; q < m; q++) { A[c * m + q] /= piv; Inv[c * m + q] /= piv; }
            for (int r = 0; r < m; r++) {
                if (r == c) continue;
                double f = A[r * m + c];
                if (f == 0) continue;
                for (int q = 0; q < m; q++) { A[r * m + q] -= f * A[c * m + q]; Inv[r * m + q] -= f * Inv[c * m + q]; }
            }
        }
        double *O = s->ablk + (size_t)nn * i;
        memset(O, 0, (size_t)nn * sizeof *O);
        for (int p = 0; p < m; p++)
            for (int q = 0; q < m; q++) O[fr[p] * nd + fr[q]] = Inv[p * m + q];
    }
    if (bad < n) {
        s->ablk_epoch = -1; /* a partial set of blocks: built again at the next try */
        return nm_error(s, FLOE_EUNSTABLE, "node %d: M + gamma dt C is not positive definite", bad);
    }
    s->ablk_dt = dt;
    s->ablk_epoch = s->epoch;
    return FLOE_OK;
}
