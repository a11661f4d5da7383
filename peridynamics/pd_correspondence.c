/* pd_correspondence.c - non-local deformation gradient, strain and stress of a PD body
 * (000 eqs 26-30), for output: shape tensor K_I = sum_J w xi (x) xi V_J (eq 26; the V_J
 * missing in the paper's eq 26 is restored, as in eq 27 and Silling et al. 2007), deformation
 * gradient F_I = (sum_J w Y (x) xi V_J) K_I^-1 with Y = x_J - x_I the deformed bond (eq 27),
 * Green-Lagrange E = (F^T F - 1)/2, compressible Neo-Hookean second Piola-Kirchhoff stress
 * S = G (1 - C^-1) + lambda/2 (J^2 - 1) C^-1 (eq 29) and Cauchy sigma = F S F^T / J (eq 30),
 * von Mises stress of sigma. Intact bonds only (a broken bond carries no deformation), w = 1,
 * beta (partial volume) included. For an affine motion x = F0 X the fit is exact: F_I = F0 at
 * every point with three independent intact bonds. */
#include "floe_pd.h"
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

int floe_pd_correspondence(const floe_pd_body *b, const double *x, double G, double lambda, double *F, double *E,
                           double *sigma, double *von_mises, int *singular) {
    if (!b || !x) return FLOE_EINVAL;
    const int n = b->n, dim = b->dim;
    double *K = calloc((size_t)n * 9, sizeof *K), *N = calloc((size_t)n * 9, sizeof *N);
    if (!K || !N) { free(K); free(N); return FLOE_ENOMEM; }
    for (int i = 0; i < n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            if (b->broken[k]) continue;
            int j = b->partner[k];
            double xi[3], Y[3], w = (double)b->vfac[k];
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
            /* the bond seen from i (+xi, +Y, V_j) and from j (-xi, -Y, V_i): the products
             * are even, only the volume differs */
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++) {
                    K[9 * (size_t)i + 3 * r + c] += w * b->V[j] * xi[r] * xi[c];
                    K[9 * (size_t)j + 3 * r + c] += w * b->V[i] * xi[r] * xi[c];
                    N[9 * (size_t)i + 3 * r + c] += w * b->V[j] * Y[r] * xi[c];
                    N[9 * (size_t)j + 3 * r + c] += w * b->V[i] * Y[r] * xi[c];
                }
        }
    int nsing = 0;
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
