/* floe_polytope_lp.h - exact deepest point of one convex polytope inside another (a linear
 * program in dim + 1 variables solved by a small dense simplex; see polytope_lp.c). */
#ifndef FLOE_POLYTOPE_LP_H
#define FLOE_POLYTOPE_LP_H

#include "floe_base.h"

typedef struct floe_lp_problem {
    int dim;            /* 2 or 3 */
    const double *a;    /* na planes of p: (n, d), n.x <= d inside (world frame) */
    int na;
    const double *b;    /* nb planes of p' */
    int nb;
    const double *va;   /* nva vertices of p (3 doubles each, world), for the cold start */
    int nva;
    double scale;       /* length scale for tolerances (the particle size) */
    /* optional (NULL: b holds p''s planes): p''s planes in its own frame, b_body, and the
     * map from p's frame into it, map = (M row-major, m): X' = M x + m, with b_buf, room for
     * nb planes that the LP fills (n = M^T n', d = d' - n'.m) when it needs every row (2D; in
     * 3D a pivot or a cold start); b is then unread. In 3D a warm basis that stays optimal
     * reads its own rows alone and checks the others at the point mapped into p''s frame */
    const double *b_body;
    const double *map;
    double *b_buf;
    /* optional, 3D (NULL: none): p's planes a and p''s b_body as four rows of na_soa / nb_soa
     * doubles (floe_polytope_view.plane_soa): a warm basis's tests of every plane read them */
    const double *a_soa, *b_soa;
    int na_soa, nb_soa;
    /* the pivots in closed form a feasible warm basis (3D) may take before the LU path takes
     * over from it: 0 for the default (LP_PIVOTS3, polytope_lp.c), negative for none (tests
     * exercise the LU path's take-over with it) */
    int pivots3_cap;
} floe_lp_problem;

typedef struct floe_lp_result {
    double x[3];        /* p's point deepest in p' (world) */
    double s;           /* phi'(x): negative when it penetrates */
    double normal[3];   /* unit outward normal of p' at x (a subgradient of phi', normalised) */
    double gnorm;       /* |sum of the multipliers x face normals| <= 1: the length of that
                           subgradient before normalising (< 1 where x is equidistant from
                           several faces of p') */
    double lambda[4];
    int pivots;         /* simplex pivots taken */
    int warm;           /* 1 if the given basis was feasible and used */
    int taken_over;     /* 1 if the pivots in closed form gave up (floe_lp_problem.pivots3_cap)
                           and the LU path went on: from the given basis (warm 1), or cold
                           where the basis failed its own factorisation or test (warm 0) */
} floe_lp_result;

/* basis: dim + 1 row indices (A rows 0..na-1, then B rows), in: the previous optimum
 * (basis[0] < 0 for a cold start), out: the new one. Returns FLOE_OK or FLOE_EINVAL
 * (degenerate input: no vertex, singular basis). */
int floe_lp_deepest(const floe_lp_problem *P, int *basis, floe_lp_result *res);

#endif
