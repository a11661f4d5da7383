/* floe_kdtree.h - static balanced k-d tree in C, in the style of nanoflann: points are
 * referenced through an index permutation (no copies of the caller's array beyond a
 * packed coordinate buffer), nodes split at the midpoint of the widest bounding-box
 * dimension with leaf buckets, queries use incremental squared distances to node boxes.
 * Queries never allocate. */
#ifndef FLOE_KDTREE_H
#define FLOE_KDTREE_H

#include <stddef.h>

typedef struct floe_kdtree floe_kdtree;

/* Build over n points pts[3*i .. 3*i+2] (the z coordinate is ignored when dim == 2).
 * The tree copies the coordinates. leaf_size <= 0 selects 16. Returns NULL on ENOMEM. */
floe_kdtree *floe_kdtree_build(const double *pts, int n, int dim, int leaf_size);
/* The same tree (node for node) built on up to nthreads OpenMP threads: the subtrees below
 * its top levels each on a thread, then joined (fewer than 4,096 points, or nthreads <= 1:
 * floe_kdtree_build's path; without OpenMP the subtrees are built one after the other). */
floe_kdtree *floe_kdtree_build_threads(const double *pts, int n, int dim, int leaf_size, int nthreads);
void floe_kdtree_destroy(floe_kdtree *t);
int floe_kdtree_size(const floe_kdtree *t);

/* Indices of all points with |p - q| <= r, unsorted, written to out[0 .. min(count,cap)).
 * Returns the total count, which may exceed cap (then call again with a larger buffer). */
int floe_kdtree_radius(const floe_kdtree *t, const double q[3], double r, int *out, int cap);

/* Callback form: fn(index, dist2, user) is called for each point within r. */
typedef void (*floe_kdtree_visit_fn)(int index, double dist2, void *user);
void floe_kdtree_radius_visit(const floe_kdtree *t, const double q[3], double r,
                              floe_kdtree_visit_fn fn, void *user);

/* k nearest neighbours of q sorted by distance: idx[0..k), d2[0..k). Returns the number
 * found (min(k, n)). */
int floe_kdtree_knn(const floe_kdtree *t, const double q[3], int k, int *idx, double *d2);

/* Index permutation in tree (leaf) order, n entries: a spatially coherent ordering. */
const int *floe_kdtree_order(const floe_kdtree *t);

#endif
