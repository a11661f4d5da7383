/* floe_detect.h - contact detection (contact/detect/detect.c): two bodies' poses and a
 * small context in, the contact summary of ParticLS eq 15 out. Nothing here knows the
 * world: the caller (the world's contact provider) hands the poses of each listed pair. */
#ifndef FLOE_DETECT_H
#define FLOE_DETECT_H

#include "floe_admm.h"
#include "floe_contact.h"

/* piece pair of a neighbour-list entry (compound bodies: one entry per piece pair) */
#define FLOE_SUB(a, b) ((a) << 16 | (b))
#define FLOE_SUB_A(s) ((s) >> 16)
#define FLOE_SUB_B(s) ((s) & 0xffff)
#define FLOE_DETECT_WARM FLOE_ADMM_WARM
#define FLOE_DETECT_HIST 64

/* detector options, scratch and statistics (contact/detect.c) */
typedef struct floe_detect_state {
    floe_admm_options admm;
    double *scratch; int scratch_cap;
    long calls, iterations;      /* ADMM/LP pair evaluations and their iterations (pivots + 1) */
    long admm_calls, lp_calls;
    long separated;              /* pairs found apart before LP/ADMM (support test or separation cache) */
    long sep_cached;             /* of those, by the separation cache (a gap still open) without a test */
    long mf_cached;              /* polytope manifolds from their corner cache (detect.c manifold) */
    long lp_halves, lp_kept, lp_cold; /* polytope LP halves; of which the previous basis was
                                         kept without a pivot (resting contacts); started cold */
    long nonconverged;           /* ADMM evaluations that hit max_iter (a counted warning) */
    long hist[FLOE_DETECT_HIST]; /* iterations per evaluation (last bin: that many or more) */
    int cur_i, cur_j;
    int first_bad_i, first_bad_j; long first_bad_step;
} floe_detect_state;

/* one body as detection sees it: its geometry, centre and orientation (body -> world), its
 * current bounding radius (a sphere's radius; for compounds, of the whole body) and its id */
typedef struct floe_body_ref {
    const floe_geometry *g;
    const double *x, *q;
    double radius;
    int id;
} floe_body_ref;

/* what a detection call needs besides the two bodies: the dimension (2 or 3), the step
 * (for the first non-converged ADMM call's report), the options, scratch and statistics */
typedef struct floe_detect_ctx {
    int dim;
    long step;
    floe_detect_state *det;
    /* optional, the separation cache (docs/models.md, "Polytope pairs: the separation
     * cache"): sep, this pair's two doubles (a gap, the pair's motion bound when it was
     * measured; NaN: none), and motion, the pair's motion bound now (the two bodies' sums
     * of |dx| + radius x turned angle since the cache was reset). NULL: no cache */
    double *sep;
    double motion;
    int no_corner_cache; /* 1: polytope manifolds test every corner (detect.c manifold; tests) */
} floe_detect_ctx;

/* The separation cache's test (docs/models.md): 1 (and counted) when this pair's kept gap is
 * still open, i.e. the pair's motion since the gap was measured, plus the bound's own
 * round-off, is below it; the pair is then apart without a look at the shapes. Only a
 * convex pair found apart keeps a gap (detect.c sep_keep), so a caller may ask before the
 * detector's dispatch (the world's contact stage does, for pairs beyond spheres and walls). */
static inline int floe_detect_sep_open(const double *sc, double motion) {
    return motion - sc[1] + 1e-9 * motion < sc[0]; /* NaN (no gap kept, no bound): 0 */
}
static inline int floe_detect_sep_holds(floe_detect_ctx *w) {
    const double *sc = w->sep;
    if (!(sc && floe_detect_sep_open(sc, w->motion))) return 0;
    w->det->sep_cached++;
    w->det->separated++;
    return 1;
}

/* fills c (x1, x2, n, depth, point, r_eff, i, j) for piece pair `sub` (FLOE_SUB) of the two
 * bodies; returns 1 if penetrating, 0 if not, < 0 on error (-FLOE_ENOTSUP: no detector). */
int floe_detect(floe_detect_ctx *ctx, const floe_body_ref *a, const floe_body_ref *b, int sub, double *warm,
                floe_contact *c);
/* overlap area, its energy integral and conservative resultant for a polytope pair (the
 * overlap-area law): fills area, area_force, area_energy, and moves point and n onto the
 * resultant; 1 if they overlap, 0 if not, -FLOE_ENOTSUP for other pairs. 2D: a test on its
 * own (no point detection before it): also fills i, j, depth (2I/A), x1 = x2 = point, r_eff;
 * warm (may be NULL): the pair's slot, where warm[0] caches a separating line. */
int floe_detect_overlap(const floe_detect_ctx *ctx, const floe_body_ref *a, const floe_body_ref *b, int sub,
                        double *warm, floe_contact *c);
/* the height of a point xs above the plane through xp with normal nw = q_p (0, 0, 1) (into
 * nw): a sphere of radius r there touches the plane when it is below r */
static inline double floe_plane_height(const double xs[3], const double xp[3], const double qp[4], double nw[3]) {
    const double ez[3] = {0, 0, 1};
    double d[3];
    floe_q_rotate(nw, qp, ez);
    floe_v3_sub(d, xs, xp);
    return floe_v3_dot(d, nw);
}
/* A sphere (centre xs, radius r) against a wall (a plane body at xp, orientation qp: the
 * half-space z <= 0 of its frame): 1 and c filled seen from the sphere (x1 on the sphere, x2
 * on the wall, n from the sphere into the wall, the midpoint as the point) if they touch,
 * else 0. Inline: detection's sphere-plane pair and the world's sphere path share it. */
static inline int floe_sphere_plane_contact(const double xs[3], double r, const double xp[3], const double qp[4],
                                            floe_contact *c) {
    double nw[3];
    const double s = floe_plane_height(xs, xp, qp, nw);
    if (s >= r) return 0;
    floe_v3_set(c->n, -nw[0], -nw[1], -nw[2]);
    c->depth = r - s;
    for (int k = 0; k < 3; k++) {
        c->x1[k] = xs[k] - r * nw[k];
        c->x2[k] = xs[k] - s * nw[k];
    }
    c->r_eff = r;
    for (int k = 0; k < 3; k++) c->point[k] = 0.5 * (c->x1[k] + c->x2[k]);
    return 1;
}

/* 1 if a detector exists for the two geometries (every piece pair of compounds) */
int floe_detect_supported(const floe_geometry *a, const floe_geometry *b);
/* 1 if some piece pair goes through ADMM or the polytope LP (needs warm-start storage) */
int floe_detect_needs_warm(const floe_geometry *a, const floe_geometry *b);
int floe_piece_count(const floe_geometry *g);
/* world centre and bounding radius of piece `piece` of a body */
void floe_piece_centre(const floe_body_ref *body, int piece, double c[3], double *r);

#endif
