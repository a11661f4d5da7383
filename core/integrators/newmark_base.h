/* newmark_base.h - the Newmark-beta solver's data and the helpers its files share
 * (core/integrators: newmark.c, newmark_solve.c, newmark_io.c, newmark_base.c). Internal:
 * not installed. The files call downward only: newmark.c and newmark_io.c -> newmark_solve.c
 * -> newmark_base.c. */
#ifndef FLOE_NEWMARK_BASE_H
#define FLOE_NEWMARK_BASE_H
#include "floe_newmark.h"
#include "world_internal.h"
#include "floe_par.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifdef FLOE_HAVE_CHOLMOD
#include <cholmod.h>
#endif

#define NM_SLOTS 4      /* factors kept for different steps (implicit) */
#define NM_LEVELS 20    /* shortest step of the step control: dt 2^(-20/2) ~ 1e-3 dt */

/* what every step reads first (the bond passes stream the bonds: a 2D bond's step touches
 * 6 of its 8 cache lines in this order, 7 in the order of the fields' meaning) */
typedef struct nm_bond {
    int i, j;
    int broken;
    double R[9];             /* rows: the local axes (e, y', z') in global components */
    double k[6];             /* EA/l, 12EI/(l^3(1+phi)), 6EI/(l^2(1+phi)), (4+phi)EI/(l(1+phi)),
                                (2-phi)EI/(l(1+phi)), GJ/l: the entries of eq 7 */
    double inv_a, inv_w;     /* 1/A, 1/W for eq 11 */
    double sig_lim, tau_lim;
    double sigma, tau;       /* stresses at the last accepted step */
    double sig_tr, tau_tr;   /* at the trial step */
    double fl[12];           /* local internal forces at the ends (eq 10), incremental (eq 20) */
    double dfl[12];          /* the trial step's increment */
    floe_beam_section s;
    double c[6];             /* eq 8 dampers on the local components of each end (3 + 3) */
    double t_broken;
} nm_bond;

struct floe_newmark {
    floe_newmark_def def;
    char err[512];
    int dim, nd;
    int n, cap;
    double *x, *mass, *inertia;
    unsigned *fix;
    double *F;               /* nd n load pattern */
    double *u, *v, *a, *fint; /* nd n state */
    double *du, *vnew, *anew, *kd, *an, *bn, *rhs, *cv0, *cv1; /* nd n scratch */
    nm_bond *b;
    int nb, bcap;
    floe_newmark_load_fn lf;
    void *lf_user;
    int prepared;
    double t;
    int *eq;                 /* nd n: equation of each component, -1 if supported */
    int neq;
    double *cblk;            /* n nd^2: C block of each node (eq 8 + alpha M) */
    double *ablk;            /* explicit: n nd^2: inverse of the free part of M + gamma dt C */
    double ablk_dt;
    long ablk_epoch;
    long epoch;              /* bumped when bonds break: older factors are stale */
    int level;               /* implicit step control: the step is dt 2^(-level/2) */
    floe_newmark_stats st;
    double energy_scale;     /* for the instability check */
    /* threads (floe_newmark_set_threads; 0: OpenMP's default). The bond passes run over
     * blocks of FLOE_PAR_BLOCK bonds; each bond writes its ends' forces in global components
     * (gdf), and each node gathers its intact bonds' ends in bond order (inc), the order of
     * the serial scatter: the same bits for any thread count */
    int nthreads;
    int *inc_off, *inc;      /* n + 1 offsets into inc; entries 2 k + e (bond k, end e) */
    long inc_epoch;          /* the epoch inc was built for (-1: none) */
    double *gdf;             /* nb 2 nd: each bond end's force of the last pass */
    double *bsum;            /* per block: its bonds' change of stored energy */
    int *bbrk;               /* per block: its bonds at or above their strength */
    unsigned char *bflag;    /* nb: at or above its strength at the last accepted step */
    double *vsum;            /* per block of FLOE_PAR_BLOCK dofs: 4 sums of the step */
#ifdef FLOE_HAVE_CHOLMOD
    cholmod_common cc;
    int cc_started;
    cholmod_sparse *A;
    cholmod_factor *L[NM_SLOTS]; /* factors for the steps in use (the full step and the
                                    shorter ones of the step control), least recently used
                                    replaced */
    double Ldt[NM_SLOTS];
    long Lepoch[NM_SLOTS], Lused[NM_SLOTS], use_clock;
    int *bpos;               /* nb (2 nd)^2: positions in A->x of each bond's entries (-1: none) */
    int *npos;               /* n nd^2: positions of each node's diagonal block */
    int *pinv;               /* inverse of the fill-reducing permutation (the same in every
                                slot: one pattern, one analysis), for downdates */
    long since_refactor[NM_SLOTS]; /* downdates of L[k] since its factorization */
    cholmod_dense *B, *X, *Y, *E;
#endif
};

#define build_ablk floe_nm_build_ablk
#define build_pattern floe_nm_build_pattern
#define downdate_bonds floe_nm_downdate_bonds
#define factor floe_nm_factor
#define nm_error floe_nm_nm_error
#define now_s floe_nm_now_s
#define solve_explicit floe_nm_solve_explicit
#define solve_implicit floe_nm_solve_implicit

int build_ablk(floe_newmark *s, double dt);
int build_pattern(floe_newmark *s);
int downdate_bonds(floe_newmark *s, int slot, const int *broken, int nbr);
int factor(floe_newmark *s, int slot, double dt);
double now_s(void);
int solve_explicit(floe_newmark *s, double dt, const double *rhs, double *x);
int solve_implicit(floe_newmark *s, double dt, const double *rhs, double *x);
int nm_error(floe_newmark *s, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* ---- the bond kernels and node masses every file of the solver uses (inline: the
 * assembly and the per-step loops keep them inlined; in this header, below every file, so
 * that newmark.c -> newmark_solve.c -> newmark_base.c stays one direction) ---- */

/* local end components of the global vector g (2 nd) */
static inline void to_local(const floe_newmark *s, const nm_bond *b, const double *g, double *ul) {
    const int nd = s->nd;
    const double *R = b->R;
    const int ends[2] = {b->i, b->j};
    for (int e = 0; e < 2; e++) {
        const double *q = g + (size_t)nd * ends[e];
        double *o = ul + nd * e;
        if (nd == 3) {
            o[0] = R[0] * q[0] + R[1] * q[1];
            o[1] = R[3] * q[0] + R[4] * q[1];
            o[2] = q[2];
        } else {
            for (int r = 0; r < 3; r++) {
                o[r] = R[3 * r] * q[0] + R[3 * r + 1] * q[1] + R[3 * r + 2] * q[2];
                o[3 + r] = R[3 * r] * q[3] + R[3 * r + 1] * q[4] + R[3 * r + 2] * q[5];
            }
        }
    }
}

/* gd = T fl: a bond's local end forces in global components, both ends (2 nd values) */
static inline void ends_global(const floe_newmark *s, const nm_bond *b, const double *fl, double *gd) {
    const double *R = b->R;
    if (s->nd == 3)
        for (int e = 0; e < 2; e++) {
            const double *f = fl + 3 * e;
            double *q = gd + 3 * e;
            q[0] = R[0] * f[0] + R[3] * f[1];
            q[1] = R[1] * f[0] + R[4] * f[1];
            q[2] = f[2];
        }
    else
        for (int e = 0; e < 2; e++) {
            const double *f = fl + 6 * e;
            double *q = gd + 6 * e;
            for (int c = 0; c < 3; c++) {
                q[c] = R[c] * f[0] + R[3 + c] * f[1] + R[6 + c] * f[2];
                q[3 + c] = R[c] * f[3] + R[3 + c] * f[4] + R[6 + c] * f[5];
            }
        }
}

/* g += sc T fl: the same end forces added to the nodes' global rows, scaled by sc */
static inline void add_global(const floe_newmark *s, const nm_bond *b, const double *fl, double sc, double *g) {
    const int nd = s->nd;
    double gd[12];
    ends_global(s, b, fl, gd);
    const int ends[2] = {b->i, b->j};
    for (int e = 0; e < 2; e++) {
        double *q = g + (size_t)nd * ends[e];
        for (int c = 0; c < nd; c++) q[c] += sc * gd[nd * e + c];
    }
}

/* the dampers of bond b at either end in the node's nd dofs, T^T diag(c) T (nd x nd,
 * row-major; 2D: the x, y dampers in the bond's axes and the rotational one) */
static inline void bond_damper_block(int nd, const nm_bond *b, double *D) {
    const double *R = b->R;
    memset(D, 0, (size_t)(nd * nd) * sizeof *D);
    if (nd == 3) {
        for (int p = 0; p < 2; p++)
            for (int q = 0; q < 2; q++)
                D[p * 3 + q] = R[p] * b->c[0] * R[q] + R[3 + p] * b->c[1] * R[3 + q];
        D[8] = b->c[5];
    } else
        for (int p = 0; p < 3; p++)
            for (int q = 0; q < 3; q++) {
                double ct = 0, cr = 0;
                for (int r = 0; r < 3; r++) {
                    ct += R[3 * r + p] * b->c[r] * R[3 * r + q];
                    cr += R[3 * r + p] * b->c[3 + r] * R[3 * r + q];
                }
                D[p * 6 + q] = ct;
                D[(3 + p) * 6 + 3 + q] = cr;
            }
}

/* the solver's threads for a loop of m items: 1 below a size where a parallel region costs
 * more than it gives */
static inline int nm_threads(const floe_newmark *s, long m) {
    if (m < 2 * FLOE_PAR_BLOCK) return 1;
    return s->nthreads > 0 ? s->nthreads : floe_par_max_threads();
}

static inline double node_m(const floe_newmark *s, int i, int k) {
    int rot = s->nd == 3 ? k == 2 : k >= 3;
    return rot ? s->inertia[i] : s->mass[i];
}

#endif
