/* floe_overlap.h - overlap integrals of two convex polytopes for the overlap-area law
 * (contact/detect/overlap.c; docs/models.md "Overlap-area law"). Internal to the contact layer. */
#ifndef FLOE_OVERLAP_H
#define FLOE_OVERLAP_H

#include "floe_base.h"

#define FLOE_OVERLAP_MAX 64 /* corners of a polygon handled (2D) */
#define FLOE_POLY3_FACES 48  /* faces of a polyhedron handled (3D) */
#define FLOE_POLY3_CORNERS 32 /* corners of one of its faces */

/* 2D term for polygons X (CCW corners, world) and Y (lines n.x <= h as (nx, ny, h)):
 * returns I_XY = ∫_{X∩Y} -φ_Y dA; f, *m: the load on X (-dI_XY/dx_X: force, moment about the
 * origin); *area, cen: area and centroid of X∩Y. */
double floe_overlap_term2(double (*X)[2], int nx, double (*Y)[3], int ny, double f[2], double *m, double *area,
                          double cen[2]);

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
