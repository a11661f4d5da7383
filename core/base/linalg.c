/* linalg.c - small dense linear algebra (floe_linalg.h): the one symmetric eigen-solver
 * (cyclic Jacobi) used for principal frames of inertia (3 x 3) and the modes of a bonded
 * pair in the Newmark-beta solver (up to 12 x 12), and the quaternion of a rotation matrix
 * (Shepperd). */
#include "floe_linalg.h"
#include "floe_base.h"

#include <math.h>

/* Cyclic Jacobi: A' = J^T A J for each pair (p, q), with the rotation chosen to zero A'_pq
 * (Numerical Recipes' stable form, t = sgn(theta) / (|theta| + sqrt(theta^2 + 1))). Converges
 * quadratically; 50 sweeps is far more than these sizes ever need. */
void floe_sym_eigen(double *A, int m, double *V) {
    for (int p = 0; p < m; p++)
        for (int q = 0; q < m; q++) V[p * m + q] = p == q;
    for (int sweep = 0; sweep < 50; sweep++) {
        double off = 0, diag = 0;
        for (int p = 0; p < m; p++) {
            diag += A[p * m + p] * A[p * m + p];
            for (int q = p + 1; q < m; q++) off += A[p * m + q] * A[p * m + q];
        }
        if (off == 0 || off <= 1e-36 * diag) break;
        for (int p = 0; p < m - 1; p++)
            for (int q = p + 1; q < m; q++) {
                double apq = A[p * m + q];
                if (apq == 0) continue;
                if (fabs(apq) <= 1e-20 * (fabs(A[p * m + p]) + fabs(A[q * m + q]))) {
                    A[p * m + q] = A[q * m + p] = 0;
                    continue;
                }
                double th = 0.5 * (A[q * m + q] - A[p * m + p]) / apq;
                double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < m; k++) { /* A J */
                    double akp = A[k * m + p], akq = A[k * m + q];
                    A[k * m + p] = c * akp - s * akq;
                    A[k * m + q] = s * akp + c * akq;
                }
                for (int k = 0; k < m; k++) { /* J^T (A J) */
                    double apk = A[p * m + k], aqk = A[q * m + k];
                    A[p * m + k] = c * apk - s * aqk;
                    A[q * m + k] = s * apk + c * aqk;
                }
                A[p * m + q] = A[q * m + p] = 0;
                for (int k = 0; k < m; k++) {
                    double vkp = V[k * m + p], vkq = V[k * m + q];
                    V[k * m + p] = c * vkp - s * vkq;
                    V[k * m + q] = s * vkp + c * vkq;
                }
            }
    }
}

void floe_sym3_eigen(const double A0[3][3], double l[3], double V[3][3]) {
    double A[9], W[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) A[3 * i + j] = 0.5 * (A0[i][j] + A0[j][i]);
    floe_sym_eigen(A, 3, W);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) V[i][j] = W[3 * i + j];
        l[i] = A[4 * i];
    }
    /* ascending order (selection sort on 3 entries, columns follow) */
    for (int i = 0; i < 2; i++) {
        int m = i;
        for (int j = i + 1; j < 3; j++)
            if (l[j] < l[m]) m = j;
        if (m != i) {
            double t = l[i]; l[i] = l[m]; l[m] = t;
            for (int k = 0; k < 3; k++) { t = V[k][i]; V[k][i] = V[k][m]; V[k][m] = t; }
        }
    }
    /* right-handed: det V = +1 */
    double det = V[0][0] * (V[1][1] * V[2][2] - V[1][2] * V[2][1]) - V[0][1] * (V[1][0] * V[2][2] - V[1][2] * V[2][0]) +
                 V[0][2] * (V[1][0] * V[2][1] - V[1][1] * V[2][0]);
    if (det < 0)
        for (int k = 0; k < 3; k++) V[k][2] = -V[k][2];
}

/* Shepperd's method: take the square root of the largest of 1 + trace and the 1 + 2 R_ii -
 * trace terms (no cancellation), the other components from the off-diagonal sums and
 * differences. floe_q_rotate(q, v) = R v. */
void floe_q_from_matrix(double q[4], const double R[3][3]) {
    double tr = R[0][0] + R[1][1] + R[2][2];
    int k = -1;
    double best = tr;
    for (int i = 0; i < 3; i++)
        if (R[i][i] > best) { best = R[i][i]; k = i; }
    if (k < 0) {
        double w = 0.5 * sqrt(fmax(1 + tr, 0)), f = 0.25 / w;
        q[0] = w; q[1] = (R[2][1] - R[1][2]) * f; q[2] = (R[0][2] - R[2][0]) * f; q[3] = (R[1][0] - R[0][1]) * f;
    } else if (k == 0) {
        double x = 0.5 * sqrt(fmax(1 + R[0][0] - R[1][1] - R[2][2], 0)), f = 0.25 / x;
        q[1] = x; q[0] = (R[2][1] - R[1][2]) * f; q[2] = (R[0][1] + R[1][0]) * f; q[3] = (R[0][2] + R[2][0]) * f;
    } else if (k == 1) {
        double y = 0.5 * sqrt(fmax(1 - R[0][0] + R[1][1] - R[2][2], 0)), f = 0.25 / y;
        q[2] = y; q[0] = (R[0][2] - R[2][0]) * f; q[1] = (R[0][1] + R[1][0]) * f; q[3] = (R[1][2] + R[2][1]) * f;
    } else {
        double z = 0.5 * sqrt(fmax(1 - R[0][0] - R[1][1] + R[2][2], 0)), f = 0.25 / z;
        q[3] = z; q[0] = (R[1][0] - R[0][1]) * f; q[1] = (R[0][2] + R[2][0]) * f; q[2] = (R[1][2] + R[2][1]) * f;
    }
    if (q[0] < 0) { q[0] = -q[0]; q[1] = -q[1]; q[2] = -q[2]; q[3] = -q[3]; }
    floe_q_normalize(q);
}
