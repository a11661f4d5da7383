/* floe_overlap.h - overlap integrals of two convex polytopes for the overlap-area law
 * (contact/detect/overlap.c; docs/models.md "Overlap-area law"). Internal to the contact layer. */
#ifndef FLOE_OVERLAP_H
#define FLOE_OVERLAP_H

#include "floe_base.h"

#define FLOE_OVERLAP_MAX 64 /* corners of a polygon handled (2D) */
#define FLOE_POLY3_FACES 48  /* faces of a polyhedron handled (3D) */
#define FLOE_POLY3_CORNERS 32 /* corners of one of its faces */

/* Both terms of two convex polygons A, B at once (CCW corners and lines n.x <= h as
 * (nx, ny, h), world or any common frame): the overlap O = A ∩ B clipped once, each term's
 * depth integrals over only the lines nearest somewhere in O. f, m: the load on A (half of
 * each term, -dI/dx_A; moment about the frame's origin), I = (I_AB + I_BA)/2, the overlap's
 * area and centroid. Returns 1 when they overlap (area > 0), 0 when apart, -1 when a polygon
 * has more than FLOE_OVERLAP_MAX corners. */
typedef struct floe_overlap2 {
    double f[2], m, I, area, cen[2];
} floe_overlap2;
int floe_overlap_pair2(double (*A)[2], int na, double (*LA)[3], int la, double (*B)[2], int nb, double (*LB)[3],
                       int lb, floe_overlap2 *out);

/* Separating lines of two convex polygons (same inputs): the first line (k + 1 for A's line k,
 * la + k + 1 for B's line k) behind which the other polygon's corners lie no deeper than tol
 * (apart, or touching), 0 when there is none (they overlap). floe_overlap_pen2: how deep the
 * corners of X lie behind the line L (n.x <= h inside), at most (a cached line tested again). */
int floe_overlap_axis2(double (*A)[2], int na, double (*LA)[3], int la, double (*B)[2], int nb, double (*LB)[3],
                       int lb, double tol);
double floe_overlap_pen2(double (*X)[2], int nx, const double L[3]);

/* A convex polyhedron as face polygons (world frame). */
typedef struct floe_poly3 {
    int nf;
    int nv[FLOE_POLY3_FACES];            /* corners of each face */
    double n[FLOE_POLY3_FACES][3];       /* outward unit normals */
    int tag[FLOE_POLY3_FACES];           /* 1: a face of the original body's boundary */
    double v[FLOE_POLY3_FACES][FLOE_POLY3_CORNERS][3];
} floe_poly3;

/* faces of the convex polytope with planes (n, h: n.x <= h, world) and corners V: the corners
 * on each plane (within tol), ordered counter-clockwise about its normal. Returns 0, or -1
 * when it does not fit FLOE_POLY3_FACES / FLOE_POLY3_CORNERS. */
int floe_poly3_from_planes(const double *planes, int np, const double *V, int nv, double tol, floe_poly3 *P);

/* 3D term: I_XY = ∫_{X∩Y} -φ_Y dV, and the load on X (force f, moment m about the origin):
 * the pressure -φ_Y on the faces of X inside Y; *vol, cen: volume and centroid of X∩Y,
 * *area: the area of X's boundary inside Y. Y is given by its planes (n, h). */
double floe_overlap_term3(const floe_poly3 *X, const double *Yplanes, int ny, double tol, double f[3], double m[3],
                          double *vol, double cen[3], double *area);

#endif
