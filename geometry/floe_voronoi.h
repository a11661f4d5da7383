/* floe_voronoi.h - 2D Voronoi tessellation of a rectangle with Lloyd relaxation, for fields
 * of sea-ice floes (the floe fields of SubZero, Manucharyan & Montemuro 2022, and
 * Subzero.jl): n seeds, one convex cell per seed, the cells tile the rectangle.
 *
 * Cell k is the rectangle clipped by the bisector half-planes |x - s_k| <= |x - s_j| of the
 * other seeds (geometry/voronoi.c). Only nearby seeds are tried, found with a k-d tree:
 * the nearest ones first, then, until no seed outside can cut the cell (the security
 * radius criterion, or the empty circle of each corner), the nearest seeds of each
 * corner. O(n log n) per tessellation, also for clustered or collinear seeds.
 *
 * Lloyd relaxation (Lloyd 1982, Du, Faber & Gunzburger 1999) moves each seed to the
 * centroid of its cell and tessellates again; it lowers the quantization energy
 * sum_k int_cell_k |x - s_k|^2 dA at every iteration and evens out the cell areas.
 *
 * Power (Laguerre) tessellations give each seed a weight w_k: cell k holds the points of
 * least power distance |x - s_k|^2 - w_k (Aurenhammer 1987). The bisectors move, a cell may
 * not hold its seed, and a cell may be empty. With weights chosen by a damped Newton method
 * (floe_voronoi_areas) the cells get prescribed areas: fields of floes of a given size
 * distribution (docs/sea-ice.md, "Floe size distributions"). */
#ifndef FLOE_VORONOI_H
#define FLOE_VORONOI_H

#include <stddef.h>

/* A tessellation. Cell k's corners are xy[2*start[k] .. 2*start[k+1]-1] (x, y pairs),
 * counter-clockwise, a strictly convex polygon with at least 3 corners inside the
 * rectangle: corners that would make an edge shorter than 1e-9 x the cell's bounding-box
 * diagonal, or a turn of less than 1e-12 rad, are removed (the corners are computed
 * relative to the seed, then offset and rounded). seed (2n) are the seeds of these
 * cells (after Lloyd relaxation, the relaxed ones), area (n) and centroid (2n) those of the
 * polygons. In a power tessellation (weight not NULL: the seeds' weights, n) a cell may be
 * empty (no corners, area 0, centroid at its seed) and need not hold its seed. All arrays
 * are owned by the struct: floe_voronoi_free. */
typedef struct floe_voronoi {
    int n;            /* number of cells (= seeds) */
    double *xy;       /* 2 start[n] corner coordinates */
    int *start;       /* n + 1 offsets into the corners */
    double *seed;     /* 2n */
    double *area;     /* n */
    double *centroid; /* 2n */
    double *weight;   /* n, power tessellations only (NULL otherwise) */
} floe_voronoi;

/* Voronoi tessellation of the rectangle [lo, hi] for the n seeds seeds[2k], seeds[2k+1]
 * (inside the rectangle or on its boundary), then lloyd_iterations Lloyd steps (0: the
 * plain tessellation of the given seeds). On success *out holds the tessellation of the
 * final seeds (free with floe_voronoi_free); on failure *out is zeroed. Errors
 * (FLOE_EINVAL, with a message in err): non-finite coordinates, hi <= lo, n < 1 or above
 * 100,000,000, lloyd_iterations < 0, a seed outside the rectangle, two seeds closer than
 * 1e-12 x the rectangle's diagonal (the message names both), a cell that degenerates to
 * less than 3 corners (seeds nearly coincident); FLOE_ENOMEM. err may be NULL. */
int floe_voronoi_rect(const double lo[2], const double hi[2], const double *seeds, int n, int lloyd_iterations,
                      floe_voronoi *out, char *err, size_t errlen);

/* Power tessellation of the rectangle [lo, hi] for the n seeds with the weights
 * weights[k] (m^2; equal weights give the Voronoi tessellation): cell k is the part of the
 * rectangle where |x - s_k|^2 - w_k is least. Cells may be empty. Errors as
 * floe_voronoi_rect, and non-finite or NULL weights. */
int floe_voronoi_power_rect(const double lo[2], const double hi[2], const double *seeds, const double *weights, int n,
                            floe_voronoi *out, char *err, size_t errlen);

/* A power tessellation of the rectangle [lo, hi] whose cell k has the area areas[k] (the
 * areas are scaled to sum to the rectangle's area) to the relative tolerance tol, starting
 * from the n seeds; then lloyd_iterations times the seeds are moved to their cells'
 * centroids and the weights solved again (capacity-constrained centroidal power cells:
 * rounder cells). The weights come from a damped Newton method (Kitagawa, Merigot &
 * Thibert 2019) started from equal weights, each step a conjugate-gradient solve on the
 * cells' adjacency; out->weight holds them. Errors (FLOE_EINVAL with a message): those of
 * floe_voronoi_rect, an area not positive and finite, tol not in (0, 0.5], a Newton
 * method that does not converge in 200 steps; FLOE_ENOMEM. */
int floe_voronoi_areas(const double lo[2], const double hi[2], const double *seeds, const double *areas, int n,
                       int lloyd_iterations, double tol, floe_voronoi *out, char *err, size_t errlen);

/* Free the arrays of a tessellation and zero it (a zeroed struct is fine). */
void floe_voronoi_free(floe_voronoi *v);

/* n seeds uniform in the rectangle [lo, hi] into out[2n], from floe_rng (splitmix64)
 * started at seed: the same points on every platform. FLOE_EINVAL for non-finite or
 * empty rectangles, n < 1 or out NULL. */
int floe_voronoi_random_seeds(const double lo[2], const double hi[2], int n, unsigned long long seed, double *out);

/* Shrink every cell about its centroid by the factor s in (0, 1]: corners
 * c + s (x - c), areas times s^2 (recomputed from the corners), centroids kept. A field of
 * ice concentration c (area fraction) is s = sqrt(c) applied to a tiling. The seeds are
 * left as they were (a seed may then lie outside its shrunk cell). FLOE_EINVAL when s is
 * not in (0, 1] or v is NULL. */
int floe_voronoi_scale_cells(floe_voronoi *v, double s);

#endif
