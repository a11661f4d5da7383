/* floe_linalg.h - small dense linear algebra: the one symmetric eigen-solver and rotations. */
#ifndef FLOE_LINALG_H
#define FLOE_LINALG_H

/* Symmetric m x m eigen-decomposition (cyclic Jacobi, m small: 3 for inertia, up to 12 for
 * a bonded pair): A (row-major) is destroyed, its diagonal ends as the eigenvalues, V
 * (row-major) receives the eigenvectors as columns. */
void floe_sym_eigen(double *A, int m, double *V);
/* Symmetric 3x3 eigen-decomposition: A = V diag(l) V^T, columns of V are the eigenvectors
 * (right-handed), l ascending. For the principal frames. */
void floe_sym3_eigen(const double A[3][3], double l[3], double V[3][3]);
/* Quaternion (w, x, y, z) of a rotation matrix */
void floe_q_from_matrix(double q[4], const double R[3][3]);

#endif
