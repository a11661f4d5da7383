/* pd_correspondence.c - non-local deformation gradient, strain and stress of a PD body
 * (000 eqs 26-30), for output: shape tensor K_I = sum_J w xi (x) xi V_J (eq 26; the V_J
 * missing in the paper's eq 26 is restored, as in eq 27 and Silling et al. 2007), deformation
 * gradient F_I = (sum_J w Y (x) xi V_J) K_I^-1 with Y = x_J - x_I the deformed bond (eq 27),
 * Green-Lagrange E = (F^T F - 1)/2, compressible Neo-Hookean second Piola-Kirchhoff stress
 * S = G (1 - C^-1) + lambda/2 (J^2 - 1) C^-1 (eq 29) and Cauchy sigma = F S F^T / J (eq 30),
 * von Mises stress of sigma. Intact bonds only (a broken bond carries no deformation), w = 1,
 * beta (partial volume) included. For an affine motion x = F0 X the fit is exact: F_I = F0 at
 * every point with three independent intact bonds. Threaded with b->nthreads (the same bits). */
#include "floe_pd.h"
#include "floe_par.h"
#include <stdlib.h>
#include <string.h>

static double det3(const double A[9]) {
    return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) + A[2] * (A[3] * A[7] - A[4] * A[6]);
}
static int inv3(const double A[9], double B[9]) {
    double d = det3(A);
    double s = fabs(A[0]) + fabs(A[4]) + fabs(A[8]);
    if (!(fabs(d) > 1e-14 * s * s * s)) return 0;
    B[0] = (A[4] * A[8] - A[5] * A[7]) / d; B[1] = (A[2] * A[7] - A[1] * A[8]) / d; B[2] = (A[1] * A[5] - A[2] * A[4]) / d;
    B[3] = (A[5] * A[6] - A[3] * A[8]) / d; B[4] = (A[0] * A[8] - A[2] * A[6]) / d; B[5] = (A[2] * A[3] - A[0] * A[5]) / d;
    B[6] = (A[3] * A[7] - A[4] * A[6]) / d; B[7] = (A[1] * A[6] - A[0] * A[7]) / d; B[8] = (A[0] * A[4] - A[1] * A[3]) / d;
    return 1;
}
static void mul3(const double A[9], const double B[9], double C[9]) {
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}

/* bond k = (i, j), intact: its reference and deformed vectors xi, Y (with j's image across a
 * periodic cell's faces) */
static inline void corr_bond(const floe_pd_body *b, const double *x, int i, int j, int64_t k, double xi[3],
                             double Y[3]) {
    for (int a = 0; a < 3; a++) {
        xi[a] = b->X[3 * (size_t)j + a] - b->X[3 * (size_t)i + a];
        Y[a] = x[3 * (size_t)j + a] - x[3 * (size_t)i + a];
    }
    if (b->img && b->img[k]) { /* across a periodic cell's faces: j's image */
        double s0[3], s1[3];
        floe_img_shift(b->cellH0, b->img[k], s0);
        floe_img_shift(b->cellH, b->img[k], s1);
        for (int a = 0; a < 3; a++) { xi[a] += s0[a]; Y[a] += s1[a]; }
    }
}

/* the bond's share of K and N of one end, whose partner has volume Vo */
static inline void corr_add(double *K, double *N, double w, double Vo, const double xi[3], const double Y[3]) {
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            K[3 * r + c] += w * Vo * xi[r] * xi[c];
            N[3 * r + c] += w * Vo * Y[r] * xi[c];
        }
}

/* Threads (b->nthreads > 1, docs/parallel.md): point q sums its own K and N in the order of
 * the serial loop over the rows, which adds the bonds whose partner q is (rows below q,
 * increasing k) and then q's own row: through an index of the bonds by partner, each bond
 * computed at both its ends, no per-bond buffer. The same bits for any thread count.
 * Returns 0, or -1 when the index cannot be allocated (the caller runs the serial loop). */
static int corr_sums_threaded(const floe_pd_body *b, const double *x, double *K, double *N, int nt) {
    (void)nt; /* without OpenMP (never called there) */
    const int n = b->n;
    const int64_t nb = b->nbond;
    int64_t *roff = calloc((size_t)n + 1, sizeof *roff), *rk = malloc((size_t)(nb > 0 ? nb : 1) * sizeof *rk);
    if (!roff || !rk) { free(roff); free(rk); return -1; }
    for (int64_t k = 0; k < nb; k++) roff[b->partner[k] + 1]++;
    for (int q = 0; q < n; q++) roff[q + 1] += roff[q];
    for (int64_t k = 0; k < nb; k++) rk[roff[b->partner[k]]++] = k;
    for (int q = n; q > 0; q--) roff[q] = roff[q - 1];
    roff[0] = 0;
    FLOE_OMP(omp parallel for schedule(dynamic, 256) num_threads(nt))
    for (int q = 0; q < n; q++) {
        double *Kq = K + 9 * (size_t)q, *Nq = N + 9 * (size_t)q;
        for (int64_t e = roff[q]; e < roff[q + 1]; e++) {
            const int64_t k = rk[e];
            if (b->broken[k]) continue;
            int lo = 0, hi = n - 1; /* the row i of bond k: off[i] <= k < off[i + 1] */
            while (lo < hi) {
                int mid = lo + (hi - lo + 1) / 2;
                if (b->off[mid] <= k) lo = mid;
                else hi = mid - 1;
            }
            double xi[3], Y[3];
            corr_bond(b, x, lo, q, k, xi, Y);
            corr_add(Kq, Nq, (double)b->vfac[k], b->V[lo], xi, Y);
        }
        for (int64_t k = b->off[q]; k < b->off[q + 1]; k++) {
            if (b->broken[k]) continue;
            const int j = b->partner[k];
            double xi[3], Y[3];
            corr_bond(b, x, q, j, k, xi, Y);
            corr_add(Kq, Nq, (double)b->vfac[k], b->V[j], xi, Y);
        }
    }
    free(roff);
    free(rk);
    return 0;
}

int floe_pd_correspondence(const floe_pd_body *b, const double *x, double G, double lambda, double *F, double *E,
                           double *sigma, double *von_mises, int *singular) {
    if (!b || !x) return FLOE_EINVAL;
    const int n = b->n, dim = b->dim;
    double *K = calloc((size_t)n * 9, sizeof *K), *N = calloc((size_t)n * 9, sizeof *N);
    if (!K || !N) { free(K); free(N); return FLOE_ENOMEM; }
    int nt = b->nthreads > 1 && b->nbond >= 2048 ? b->nthreads : 1;
#ifndef _OPENMP
    nt = 1;
#endif
    if (nt <= 1 || corr_sums_threaded(b, x, K, N, nt)) {
        nt = 1;
        for (int i = 0; i < n; i++)
            for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
                if (b->broken[k]) continue;
                int j = b->partner[k];
                double xi[3], Y[3];
                corr_bond(b, x, i, j, k, xi, Y);
                /* the bond seen from i (+xi, +Y, V_j) and from j (-xi, -Y, V_i): the products
                 * are even, only the volume differs */
                corr_add(K + 9 * (size_t)i, N + 9 * (size_t)i, (double)b->vfac[k], b->V[j], xi, Y);
                corr_add(K + 9 * (size_t)j, N + 9 * (size_t)j, (double)b->vfac[k], b->V[i], xi, Y);
            }
    }
    int nsing = 0; /* a count: exact in any order */
    FLOE_OMP(omp parallel for schedule(static) reduction(+ : nsing) num_threads(nt) if (nt > 1))
    for (int i = 0; i < n; i++) {
        double *Ki = K + 9 * (size_t)i, *Ni = N + 9 * (size_t)i, Kinv[9], Fi[9];
        if (dim == 2) { Ki[8] = 1.0; Ni[8] = 1.0; } /* plane: F_zz = 1 */
        if (!inv3(Ki, Kinv)) { /* too few intact bonds: identity, no stress */
            nsing++;
            memset(Fi, 0, sizeof Fi);
            Fi[0] = Fi[4] = Fi[8] = 1.0;
        } else mul3(Ni, Kinv, Fi);
        double C[9], FT[9];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) FT[3 * r + c] = Fi[3 * c + r];
        mul3(FT, Fi, C);
        if (F) memcpy(F + 9 * (size_t)i, Fi, sizeof Fi);
        if (E)
            for (int r = 0; r < 9; r++) E[9 * (size_t)i + r] = 0.5 * (C[r] - (r % 4 == 0 ? 1.0 : 0.0));
        if (sigma || von_mises) {
            double J = det3(Fi), Ci[9], S[9], T[9], sg[9];
            if (!(J > 0) || !inv3(C, Ci)) {
                memset(sg, 0, sizeof sg);
            } else {
                for (int r = 0; r < 9; r++) S[r] = G * ((r % 4 == 0 ? 1.0 : 0.0) - Ci[r]) + 0.5 * lambda * (J * J - 1) * Ci[r];
                mul3(Fi, S, T);
                mul3(T, FT, sg);
                for (int r = 0; r < 9; r++) sg[r] /= J;
            }
            if (sigma) memcpy(sigma + 9 * (size_t)i, sg, sizeof sg);
            if (von_mises) {
                double a = sg[0] - sg[4], bb = sg[4] - sg[8], c = sg[8] - sg[0];
                von_mises[i] = sqrt(0.5 * (a * a + bb * bb + c * c) + 3 * (sg[1] * sg[1] + sg[2] * sg[2] + sg[5] * sg[5]));
            }
        }
    }
    free(K);
    free(N);
    if (singular) *singular = nsing;
    return FLOE_OK;
}
