/* linalg.c - small dense linear algebra for the principal frames of inertia: symmetric 3x3
 * eigen-decomposition (cyclic Jacobi) and the quaternion of a rotation matrix (Shepperd). */
#include "floe_geometry.h"

/* Cyclic Jacobi: A' = J^T A J for each pair (p, q), with the rotation chosen to zero A'_pq
 * (Numerical Recipes' stable form, t = sgn(theta) / (|theta| + sqrt(theta^2 + 1))). Converges
 * quadratically; 50 sweeps is far more than a 3x3 ever needs. */
void floe_sym3_eigen(const double A0[3][3], double l[3], double V[3][3]) {
    double A[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            A[i][j] = 0.5 * (A0[i][j] + A0[j][i]);
            V[i][j] = i == j ? 1.0 : 0.0;
        }
    for (int sweep = 0; sweep < 50; sweep++) {
        double off = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
        double diag = A[0][0] * A[0][0] + A[1][1] * A[1][1] + A[2][2] * A[2][2];
        if (off == 0 || off <= 1e-36 * diag) break;
        for (int p = 0; p < 2; p++)
            for (int q = p + 1; q < 3; q++) {
                double apq = A[p][q];
                if (apq == 0) continue;
                if (fabs(apq) <= 1e-20 * (fabs(A[p][p]) + fabs(A[q][q]))) {
                    A[p][q] = A[q][p] = 0;
                    continue;
                }
                double th = 0.5 * (A[q][q] - A[p][p]) / apq;
                double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; k++) { /* A J */
                    double akp = A[k][p], akq = A[k][q];
                    A[k][p] = c * akp - s * akq; A[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) { /* J^T (A J) */
                    double apk = A[p][k], aqk = A[q][k];
                    A[p][k] = c * apk - s * aqk; A[q][k] = s * apk + c * aqk;
                }
                A[p][q] = A[q][p] = 0;
                for (int k = 0; k < 3; k++) {
                    double vkp = V[k][p], vkq = V[k][q];
                    V[k][p] = c * vkp - s * vkq; V[k][q] = s * vkp + c * vkq;
                }
            }
    }
    for (int k = 0; k < 3; k++) l[k] = A[k][k];
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
