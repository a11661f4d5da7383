/* beam_bond.c - beam bonds between particles (ParticLS §5.5; 004 §2, eqs 7 and 11):
 * set-up within a radius, the co-rotational bond law (force and torque), breakage by the
 * stresses of eq 11 with per-bond strengths from a seeded normal distribution, the bonds'
 * critical time step, and the exclusion of bonded pairs from contact. floe_beam.h has the
 * equations. */
#include "beam_set.h"
#include "floe_rng.h"
#include "floe_par.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* index-returning calls give -error */
#define TRY_NEG(expr) do { int rc_ = (expr); if (rc_) return -rc_; } while (0)

typedef struct beam_bond {
    int i, j;
    floe_beam_section s;
    double ci[3], cj[3];     /* bond direction at creation, in the body frames of i and j */
    double ni[3], nj[3];     /* a normal to it at creation, body frames (twist reference) */
    double xi;               /* damping ratio */
    double damp;             /* 2 xi / omega_a (s), cached at prepare */
    double sig_lim, tau_lim;
    double sigc_lim, tan_phi; /* compressive strength (Pa), Mohr-Coulomb slope */
    int ellipse;              /* the elliptical yield (FLOE_BEAM_YIELD_ELLIPSE) */
    double sigma, tau, sigc; /* last stresses: tensile and compressive fibre, shear */
    int mode;                /* 0 intact, 1 tension, 2 shear, 3 compression */
    double fold[9];          /* last force on i, torques on i and j (energy ledger) */
    double energy;           /* last stored energy */
    double t_broken;
    double s_broken, lim_broken; /* the stress of its mode that broke it and that strength */
    double x_broken[3];          /* the midpoint of the centres at the break */
    int broken;
} beam_bond;

struct floe_beam_set {
    beam_bond *b;
    int n, cap, nbroken;
    /* bonded partners of each particle (both directions), sorted: off[n_csr + 1] */
    int *off, *adj, *adj_bond, n_csr;
    unsigned long long rng;   /* strengths of single bonds: one stream per seed (rng_seed) */
    unsigned long long rng_seed;
    int rng_set;
    /* threads (docs/parallel.md): the bond loop on nthreads (> 1) threads writes each bond's
     * force on i and torques on i and j into pf (9 per bond; act[k] = 1 when it has them),
     * then every particle gathers its bonds in bond order, as the serial loop adds them: bix
     * holds per particle (bix_off) its bonds as 2k (end i) or 2k + 1 (end j), ascending, built
     * for bix_np particles at generation bix_gen of the bonds (gen: bumped by push and
     * truncate). Sums per block of FLOE_PAR_BLOCK bonds (blk), added in block order. */
    int nthreads;
    long gen, bix_gen;
    double *pf; unsigned char *act; size_t pf_cap, act_cap;
    int *bix, *bix_off, bix_np; size_t bix_cap;
    double *blk; int *blkn; int blk_cap;
};

/* ---- breakage by the elliptical yield (floe_beam.h, FLOE_BEAM_YIELD_ELLIPSE) ---- */

/* the fibres of normal stress sp (tension side, N/A + bend) and sm (N/A - bend) under the
 * shear tau: 0 inside the ellipse, else the mode (1 tension, 2 shear, 3 compression) and the
 * stress of that mode (compression as a magnitude) with the envelope's value there */
static int ellipse_mode(const beam_bond *b, double sp, double sm, double tau, double *stress, double *strength) {
    const double st = b->sig_lim, sc = b->sigc_lim, ts = b->tau_lim;
    const double s0 = 0.5 * (st - sc), a = 0.5 * (st + sc);
    const double y = ts > 0 ? (tau / ts) * (tau / ts) : (tau != 0 ? INFINITY : 0);
    const double xp = a > 0 ? ((sp - s0) / a) * ((sp - s0) / a) : INFINITY;
    const double xm = a > 0 ? ((sm - s0) / a) * ((sm - s0) / a) : INFINITY;
    const double s = xp >= xm ? sp : sm, x = xp >= xm ? xp : xm;
    if (!(x + y >= 1)) return 0;
    if (x >= y) {
        const double r = a * sqrt(fmax(0.0, 1 - y));
        *stress = s > s0 ? s : -s;
        *strength = s > s0 ? s0 + r : r - s0;
        return s > s0 ? 1 : 3;
    }
    *stress = tau;
    *strength = ts * sqrt(fmax(0.0, 1 - x));
    return 2;
}

/* ---- section, local stiffness, stresses ---- */

void floe_beam_local_stiffness(const floe_beam_section *s, int dim, double *K) {
    const int n = dim == 2 ? 6 : 12;
    memset(K, 0, (size_t)n * n * sizeof *K);
    const double l = s->l, ka = s->E * s->A / l, f = 1.0 / (1.0 + s->phi);
    const double a = 12.0 * s->E * s->I / (l * l * l) * f, b = 6.0 * s->E * s->I / (l * l) * f;
    const double c = (4.0 + s->phi) * s->E * s->I / l * f, d = (2.0 - s->phi) * s->E * s->I / l * f;
#define KS(r, q, val) do { K[(r) * n + (q)] = (val); K[(q) * n + (r)] = (val); } while (0)
    if (dim == 2) {
        /* (u, v, theta) of end i, then of end j: 004 eq 7 */
        KS(0, 0, ka); KS(3, 3, ka); KS(0, 3, -ka);
        KS(1, 1, a); KS(1, 2, b); KS(1, 4, -a); KS(1, 5, b);
        KS(2, 2, c); KS(2, 4, -b); KS(2, 5, d);
        KS(4, 4, a); KS(4, 5, -b); KS(5, 5, c);
    } else {
        const double kt = s->G * s->J / l;
        KS(0, 0, ka); KS(6, 6, ka); KS(0, 6, -ka);
        KS(3, 3, kt); KS(9, 9, kt); KS(3, 9, -kt);
        /* bending in the x-y plane: v with theta_z */
        KS(1, 1, a); KS(1, 5, b); KS(1, 7, -a); KS(1, 11, b);
        KS(5, 5, c); KS(5, 7, -b); KS(5, 11, d);
        KS(7, 7, a); KS(7, 11, -b); KS(11, 11, c);
        /* bending in the x-z plane: w with theta_y (opposite coupling signs) */
        KS(2, 2, a); KS(2, 4, -b); KS(2, 8, -a); KS(2, 10, -b);
        KS(4, 4, c); KS(4, 8, b); KS(4, 10, d);
        KS(8, 8, a); KS(8, 10, b); KS(10, 10, c);
    }
#undef KS
}

void floe_beam_local_apply(const floe_beam_section *s, int dim, const double *u, double *f) {
    const double l = s->l, ka = s->E * s->A / l, g = 1.0 / (1.0 + s->phi);
    const double a = 12.0 * s->E * s->I / (l * l * l) * g, b = 6.0 * s->E * s->I / (l * l) * g;
    const double c = (4.0 + s->phi) * s->E * s->I / l * g, d = (2.0 - s->phi) * s->E * s->I / l * g;
    if (dim == 2) {
        double n = ka * (u[0] - u[3]), dv = u[1] - u[4];
        f[0] = n;
        f[3] = -n;
        f[1] = a * dv + b * (u[2] + u[5]);
        f[4] = -f[1];
        f[2] = b * dv + c * u[2] + d * u[5];
        f[5] = b * dv + d * u[2] + c * u[5];
    } else {
        const double kt = s->G * s->J / l;
        double n = ka * (u[0] - u[6]), t = kt * (u[3] - u[9]), dv = u[1] - u[7], dw = u[2] - u[8];
        f[0] = n;
        f[6] = -n;
        f[3] = t;
        f[9] = -t;
        f[1] = a * dv + b * (u[5] + u[11]);
        f[7] = -f[1];
        f[5] = b * dv + c * u[5] + d * u[11];
        f[11] = b * dv + d * u[5] + c * u[11];
        f[2] = a * dw - b * (u[4] + u[10]);
        f[8] = -f[2];
        f[4] = -b * dw + c * u[4] + d * u[10];
        f[10] = -b * dw + d * u[4] + c * u[10];
    }
}

void floe_beam_block_norms(const floe_beam_section *s, int dim, double out[4]) {
    const double l = s->l, g = 1.0 / (1.0 + s->phi), EI = s->E * s->I;
    out[0] = fmax(s->E * s->A / l, 12.0 * EI / (l * l * l) * g);
    out[1] = 6.0 * EI / (l * l) * g;
    out[2] = (4.0 + s->phi) * EI / l * g;
    out[3] = fabs(2.0 - s->phi) * EI / l * g;
    if (dim == 3) {
        double kt = s->G * s->J / l;
        out[2] = fmax(out[2], kt);
        out[3] = fmax(out[3], kt);
    }
}

void floe_beam_stress(const floe_beam_section *s, int dim, const double *f, double *sigma, double *tau) {
    /* f = K u is the internal force at the ends: tension pulls end j back (-x) */
    if (dim == 2) {
        double N = 0.5 * (f[3] - f[0]), M = fmax(fabs(f[2]), fabs(f[5])), V = 0.5 * (fabs(f[1]) + fabs(f[4]));
        *sigma = N / s->A + M / s->W;
        *tau = 1.5 * V / s->A;
    } else {
        double N = 0.5 * (f[6] - f[0]);
        double M = fmax(hypot(f[4], f[5]), hypot(f[10], f[11]));
        double V = 0.5 * (hypot(f[1], f[2]) + hypot(f[7], f[8]));
        double T = 0.5 * (fabs(f[3]) + fabs(f[9]));
        *sigma = N / s->A + M / s->W;
        *tau = 1.5 * V / s->A + T / (2.0 * s->W);
    }
}

double floe_beam_normal(unsigned long long *state) { return floe_rng_normal(state); }

floe_beam_params floe_default_beam_params(void) {
    floe_beam_params p;
    memset(&p, 0, sizeof p);
    p.poisson = 0.25;
    p.radius_ratio = 1.0;
    p.thickness = 1.0;
    p.seed = 1;
    p.group = FLOE_BEAM_ALL_GROUPS;
    return p;
}

int floe_beam_check_params(const floe_beam_params *par, char *err, size_t errlen) {
    const char *bad = NULL;
    if (!par) bad = "params is NULL";
    else if (!(par->young > 0) || !isfinite(par->young)) bad = "young must be > 0";
    else if (!(par->poisson > -1 && par->poisson < 0.5)) bad = "poisson must be in (-1, 0.5)";
    else if (par->shear_coefficient < 0 || !isfinite(par->shear_coefficient)) bad = "shear_coefficient must be >= 0";
    else if (par->area < 0 || !isfinite(par->area)) bad = "area must be >= 0 (0 = from radius_ratio)";
    else if (par->area > 0 && (!(par->inertia > 0) || !isfinite(par->inertia))) bad = "inertia must be > 0 when area is given";
    else if (par->polar < 0 || !isfinite(par->polar)) bad = "polar must be >= 0";
    else if (par->section_modulus < 0 || !isfinite(par->section_modulus)) bad = "section_modulus must be >= 0";
    else if (par->area == 0 && (!(par->radius_ratio > 0) || !isfinite(par->radius_ratio)))
        bad = "radius_ratio must be > 0 (or give area and inertia)";
    else if (par->thickness < 0 || !isfinite(par->thickness)) bad = "thickness must be >= 0";
    else if (!(par->damping_ratio >= 0) || !isfinite(par->damping_ratio)) bad = "damping_ratio must be >= 0";
    else if (!(par->tensile_strength >= 0 && par->tensile_sd >= 0) || !isfinite(par->tensile_strength + par->tensile_sd))
        bad = "tensile_strength and tensile_sd must be >= 0";
    else if (!(par->shear_strength >= 0 && par->shear_sd >= 0) || !isfinite(par->shear_strength + par->shear_sd))
        bad = "shear_strength and shear_sd must be >= 0";
    else if (!(par->compressive_strength >= 0 && par->compressive_sd >= 0) ||
             !isfinite(par->compressive_strength + par->compressive_sd))
        bad = "compressive_strength and compressive_sd must be >= 0";
    else if (!(par->friction_angle >= 0 && par->friction_angle < 90)) bad = "friction_angle must be in [0, 90) degrees";
    else if (!(par->max_distance >= 0) || !isfinite(par->max_distance)) bad = "max_distance must be >= 0";
    else if (par->yield != FLOE_BEAM_YIELD_LIMITS && par->yield != FLOE_BEAM_YIELD_ELLIPSE)
        bad = "yield must be FLOE_BEAM_YIELD_LIMITS or FLOE_BEAM_YIELD_ELLIPSE";
    else if (par->yield == FLOE_BEAM_YIELD_ELLIPSE &&
             !(par->tensile_strength > 0 && par->compressive_strength > 0 && par->shear_strength > 0))
        bad = "the elliptical yield needs tensile_strength, compressive_strength and shear_strength > 0";
    else if (par->yield == FLOE_BEAM_YIELD_ELLIPSE && par->friction_angle != 0)
        bad = "friction_angle is for the Mohr-Coulomb limits, not the elliptical yield (its compression side "
              "already strengthens the bond in shear)";
    if (bad) {
        if (err && errlen) snprintf(err, errlen, "beam bonds: %s", bad);
        return FLOE_EINVAL;
    }
    return FLOE_OK;
}

floe_beam_set *floe_beam_set_create(void) { return calloc(1, sizeof(floe_beam_set)); }

void floe_beam_set_destroy(floe_beam_set *s) {
    if (!s) return;
    free(s->b);
    free(s->off); free(s->adj); free(s->adj_bond);
    free(s->pf); free(s->act); free(s->bix); free(s->bix_off); free(s->blk); free(s->blkn);
    free(s);
}

/* bond index of the pair (i, j), or -1 */
int floe_beam_set_find(const floe_beam_set *s, int i, int j) {
    if (i < 0 || i >= s->n_csr) return -1;
    int lo = s->off[i], hi = s->off[i + 1];
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (s->adj[mid] < j) lo = mid + 1;
        else hi = mid;
    }
    return lo < s->off[i + 1] && s->adj[lo] == j ? s->adj_bond[lo] : -1;
}

typedef struct { int partner, bond; } adj_entry;
static int cmp_adj(const void *a, const void *b) {
    const adj_entry *x = a, *y = b;
    return (x->partner > y->partner) - (x->partner < y->partner);
}

/* CSR of bonded partners over the first n particles */
int floe_beam_set_index(floe_beam_set *s, int n) {
    int *off = calloc((size_t)n + 1, sizeof *off);
    adj_entry *e = malloc((size_t)(2 * s->n + 1) * sizeof *e);
    int *adj = malloc((size_t)(2 * s->n + 1) * sizeof *adj), *ab = malloc((size_t)(2 * s->n + 1) * sizeof *ab);
    if (!off || !e || !adj || !ab) { free(off); free(e); free(adj); free(ab); return FLOE_ENOMEM; }
    for (int k = 0; k < s->n; k++) { off[s->b[k].i + 1]++; off[s->b[k].j + 1]++; }
    for (int i = 0; i < n; i++) off[i + 1] += off[i];
    int *fill = malloc((size_t)(n + 1) * sizeof *fill);
    if (!fill) { free(off); free(e); free(adj); free(ab); return FLOE_ENOMEM; }
    memcpy(fill, off, (size_t)(n + 1) * sizeof *fill);
    for (int k = 0; k < s->n; k++) {
        e[fill[s->b[k].i]++] = (adj_entry){s->b[k].j, k};
        e[fill[s->b[k].j]++] = (adj_entry){s->b[k].i, k};
    }
    free(fill);
    for (int i = 0; i < n; i++) qsort(e + off[i], (size_t)(off[i + 1] - off[i]), sizeof *e, cmp_adj);
    for (int a = 0; a < off[n]; a++) { adj[a] = e[a].partner; ab[a] = e[a].bond; }
    free(e);
    free(s->off); free(s->adj); free(s->adj_bond);
    s->off = off; s->adj = adj; s->adj_bond = ab; s->n_csr = n;
    return FLOE_OK;
}

int floe_beam_set_excludes(const floe_beam_set *s, int i, int j) {
    int k = floe_beam_set_find(s, i, j);
    return k >= 0 && !s->b[k].broken;
}

/* a unit normal to e */
static void any_normal(double nrm[3], const double e[3]) {
    double ax[3] = {0, 0, 0};
    int k = fabs(e[0]) <= fabs(e[1]) && fabs(e[0]) <= fabs(e[2]) ? 0 : fabs(e[1]) <= fabs(e[2]) ? 1 : 2;
    ax[k] = 1;
    floe_v3_cross(nrm, e, ax);
    floe_v3_scale(nrm, 1.0 / floe_v3_norm(nrm));
}

int floe_beam_set_push(floe_beam_set *s, const floe_particles *p, int dim, int i, int j,
                       const floe_beam_params *par, unsigned long long *rng, char *err, size_t errlen) {
    double d[3];
    floe_v3_sub(d, p->x + 3 * j, p->x + 3 * i);
    double l = floe_v3_norm(d);
    if (!(l > 0)) {
        if (err && errlen) snprintf(err, errlen, "beam bond %d-%d: the particles are at the same place", i, j);
        return -FLOE_EINVAL;
    }
    if (s->n == s->cap) {
        int nc = s->cap ? 2 * s->cap : 64;
        beam_bond *nb = realloc(s->b, (size_t)nc * sizeof *nb);
        if (!nb) {
            if (err && errlen) snprintf(err, errlen, "out of memory");
            return -FLOE_ENOMEM;
        }
        s->b = nb;
        s->cap = nc;
    }
    beam_bond *b = &s->b[s->n];
    memset(b, 0, sizeof *b);
    b->i = i;
    b->j = j;
    floe_beam_section *sec = &b->s;
    sec->l = l;
    sec->E = par->young;
    sec->G = par->young / (2.0 * (1.0 + par->poisson));
    if (par->area > 0) {
        sec->A = par->area;
        sec->I = par->inertia;
        sec->J = par->polar > 0 ? par->polar : 2.0 * par->inertia;
        sec->W = par->section_modulus > 0 ? par->section_modulus : par->inertia / sqrt(par->area / M_PI);
    } else {
        double r = par->radius_ratio * fmin(p->radius[i], p->radius[j]);
        if (dim == 2) { /* rectangle 2r high, `thickness` wide */
            double bw = par->thickness > 0 ? par->thickness : 1.0, h = 2.0 * r;
            sec->A = bw * h;
            sec->I = bw * h * h * h / 12.0;
            sec->J = 2.0 * sec->I;
            sec->W = bw * h * h / 6.0;
        } else {
            sec->A = M_PI * r * r;
            sec->I = 0.25 * M_PI * r * r * r * r;
            sec->J = 2.0 * sec->I;
            sec->W = 0.25 * M_PI * r * r * r;
        }
    }
    if (par->timoshenko) {
        double kappa = par->shear_coefficient > 0 ? par->shear_coefficient : 5.0 / 6.0;
        sec->phi = 12.0 * sec->E * sec->I / (kappa * sec->G * sec->A * l * l);
    }
    double e[3] = {d[0] / l, d[1] / l, d[2] / l}, nrm[3];
    if (dim == 2) floe_v3_set(nrm, 0, 0, 1);
    else any_normal(nrm, e);
    floe_q_rotate_inv(b->ci, p->q + 4 * i, e);
    floe_q_rotate_inv(b->cj, p->q + 4 * j, e);
    floe_q_rotate_inv(b->ni, p->q + 4 * i, nrm);
    floe_q_rotate_inv(b->nj, p->q + 4 * j, nrm);
    b->xi = par->damping_ratio;
    b->sig_lim = INFINITY;
    b->tau_lim = INFINITY;
    if (par->tensile_strength > 0) b->sig_lim = fmax(0.0, par->tensile_strength + par->tensile_sd * floe_beam_normal(rng));
    if (par->shear_strength > 0) b->tau_lim = fmax(0.0, par->shear_strength + par->shear_sd * floe_beam_normal(rng));
    b->sigc_lim = INFINITY;
    if (par->compressive_strength > 0)
        b->sigc_lim = fmax(0.0, par->compressive_strength + par->compressive_sd * floe_beam_normal(rng));
    b->tan_phi = tan(par->friction_angle * M_PI / 180);
    b->ellipse = par->yield == FLOE_BEAM_YIELD_ELLIPSE;
    b->mode = 0;
    b->sigc = 0;
    b->t_broken = -1;
    b->s_broken = b->lim_broken = 0;
    memset(b->x_broken, 0, sizeof b->x_broken);
    s->gen++;
    return s->n++;
}

unsigned long long *floe_beam_set_rng(floe_beam_set *s, unsigned long long seed) {
    if (!s->rng_set || s->rng_seed != seed) {
        s->rng = s->rng_seed = seed;
        s->rng_set = 1;
    }
    return &s->rng;
}

void floe_beam_set_truncate(floe_beam_set *s, int n) {
    if (n >= 0 && n < s->n) {
        s->n = n;
        s->gen++;
    }
}

size_t floe_beam_set_rec_size(void) { return sizeof(beam_bond); }

int floe_beam_set_rec_get(const floe_beam_set *s, int k, void *rec, int *i, int *j, int *broken) {
    if (!s || k < 0 || k >= s->n) return FLOE_EINVAL;
    const beam_bond *b = &s->b[k];
    memcpy(rec, b, sizeof *b);
    *i = b->i;
    *j = b->j;
    *broken = b->broken;
    return FLOE_OK;
}

int floe_beam_set_rec_put(floe_beam_set *s, int k, const void *rec) {
    if (!s || k < 0 || k >= s->n) return FLOE_EINVAL;
    beam_bond *b = &s->b[k];
    const int i = b->i, j = b->j, was = b->broken != 0;
    memcpy(b, rec, sizeof *b);
    b->i = i;
    b->j = j;
    s->nbroken += (b->broken != 0) - was;
    return FLOE_OK;
}

int floe_beam_rec_broken(const void *rec) {
    beam_bond b;
    memcpy(&b, rec, sizeof b);
    return b.broken;
}

int floe_beam_set_rec_replace(floe_beam_set *s, const unsigned char *recs, size_t stride, const int *ii, const int *jj,
                              int n) {
    if (n > s->cap) {
        beam_bond *nb = realloc(s->b, (size_t)n * sizeof *nb);
        if (!nb) return FLOE_ENOMEM;
        s->b = nb;
        s->cap = n;
    }
    int nbroken = 0;
    for (int k = 0; k < n; k++) {
        beam_bond *b = &s->b[k];
        memcpy(b, recs + (size_t)k * stride, sizeof *b);
        b->i = ii[k];
        b->j = jj[k];
        nbroken += b->broken != 0;
    }
    s->n = n;
    s->nbroken = nbroken;
    s->gen++; /* the threads' per-particle index again */
    return FLOE_OK;
}

void floe_beam_set_threads(floe_beam_set *s, int nthreads) {
    if (s) s->nthreads = nthreads;
}
int floe_beam_set_threaded(const floe_beam_set *s) { return s && s->pf; }

int floe_beam_set_count(const floe_beam_set *s) { return s ? s->n : 0; }
int floe_beam_set_broken(const floe_beam_set *s) { return s ? s->nbroken : 0; }

size_t floe_beam_set_state_size(const floe_beam_set *s) {
    return s ? sizeof(int) + (size_t)s->n * sizeof(beam_bond) : 0;
}
void floe_beam_set_state_save(const floe_beam_set *s, unsigned char *buf) {
    if (!s) return;
    memcpy(buf, &s->nbroken, sizeof(int));
    if (s->n) memcpy(buf + sizeof(int), s->b, (size_t)s->n * sizeof(beam_bond));
}
int floe_beam_set_state_restore(floe_beam_set *s, const unsigned char *buf, size_t n) {
    if (!s || n != floe_beam_set_state_size(s)) return FLOE_EINVAL;
    memcpy(&s->nbroken, buf, sizeof(int));
    if (s->n) memcpy(s->b, buf + sizeof(int), (size_t)s->n * sizeof(beam_bond));
    return FLOE_OK;
}

int floe_beam_set_info(const floe_beam_set *s, int k, floe_beam_bond_info *o) {
    if (!s || k < 0 || k >= s->n) return FLOE_EINVAL;
    const beam_bond *b = &s->b[k];
    o->i = b->i;
    o->j = b->j;
    o->broken = b->broken;
    o->t_broken = b->t_broken;
    o->sigma = b->sigma;
    o->tau = b->tau;
    o->sigma_lim = b->sig_lim;
    o->tau_lim = b->tau_lim;
    o->sigma_c = b->sigc;
    o->sigma_c_lim = b->sigc_lim;
    o->mode = b->mode;
    o->section = b->s;
    o->stress_broken = b->s_broken;
    o->strength_broken = b->lim_broken;
    memcpy(o->x_broken, b->x_broken, sizeof o->x_broken);
    return FLOE_OK;
}

int floe_beam_set_write_csv(const floe_beam_set *s, const floe_particles *p, const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) return FLOE_EIO;
    fprintf(f, "i,j,x [m],y [m],z [m],broken,t_broken [s],sigma [Pa],tau [Pa],sigma_lim [Pa]\n");
    for (int k = 0; s && k < s->n; k++) {
        const beam_bond *b = &s->b[k];
        const double *xi = p->x + 3 * b->i, *xj = p->x + 3 * b->j;
        fprintf(f, "%d,%d,%.9g,%.9g,%.9g,%d,%.9g,%.9g,%.9g,%.9g\n", b->i, b->j, 0.5 * (xi[0] + xj[0]),
                0.5 * (xi[1] + xj[1]), 0.5 * (xi[2] + xj[2]), b->broken, b->t_broken, b->sigma, b->tau, b->sig_lim);
    }
    int bad = ferror(f);
    if (fclose(f) || bad) return FLOE_EIO;
    return FLOE_OK;
}

/* ---- time step ---- */

double floe_beam_set_critical_dt(floe_beam_set *s, const floe_particles *p, int dim) {
    if (!s || s->n == 0) return INFINITY;
    double dmax = 0;
    for (int k = 0; k < s->n; k++) { /* per-bond damping time, from the masses of prepare */
        beam_bond *b = &s->b[k];
        double inv = p->inv_mass[b->i] + p->inv_mass[b->j], mr = inv > 0 ? 1.0 / inv : INFINITY;
        double ka = b->s.E * b->s.A / b->s.l;
        b->damp = b->xi > 0 && isfinite(mr) ? 2.0 * b->xi * sqrt(mr / ka) : 0.0;
        if (!b->broken && b->damp > dmax) dmax = b->damp;
    }
    /* rows of M^-1/2 K M^-1/2 by (particle, translation | rotation): sums of the spectral
     * norms of the 3x3 blocks over the particle's bonds (a block Gershgorin bound on the
     * largest eigenvalue; the norms do not depend on the bond's direction) */
    double lmax = 0;
    for (int a = 0; a < s->n_csr; a++) {
        if (p->motion[a] != FLOE_FREE || s->off[a] == s->off[a + 1]) continue;
        const double *Ia = p->inertia + 3 * a;
        double ma = p->mass[a], Ja = fmin(Ia[0], fmin(Ia[1], Ia[2])), rt = 0, rr = 0;
        for (int q = s->off[a]; q < s->off[a + 1]; q++) {
            const beam_bond *b = &s->b[s->adj_bond[q]];
            if (b->broken) continue;
            int o = s->adj[q];
            double nrm[4];
            floe_beam_block_norms(&b->s, dim, nrm);
            rt += nrm[0] / ma + nrm[1] / sqrt(ma * Ja);
            rr += nrm[1] / sqrt(ma * Ja) + nrm[2] / Ja;
            if (p->motion[o] == FLOE_FREE) {
                const double *Io = p->inertia + 3 * o;
                double mo = p->mass[o], Jo = fmin(Io[0], fmin(Io[1], Io[2]));
                rt += nrm[0] / sqrt(ma * mo) + nrm[1] / sqrt(ma * Jo);
                rr += nrm[1] / sqrt(Ja * mo) + nrm[3] / sqrt(Ja * Jo);
            }
        }
        lmax = fmax(lmax, fmax(rt, rr));
    }
    if (!(lmax > 0)) return INFINITY;
    double om = sqrt(lmax), zeta = 0.5 * dmax * om;
    return 2.0 / om * (sqrt(1.0 + zeta * zeta) - zeta);
}

/* ---- forces ---- */

/* Bond k (skipped when broken): its forces and torques, stresses, breakage and ledger; its
 * energy added to *el, its dissipation to *ds (when stepping), a break counted in *nbreak.
 * Serial (pf NULL): the forces added to p->f, p->t. Threaded: the force on i and the
 * torques on i and j into pf + 9k with act[k] = 1 (0: nothing to add). */
static inline __attribute__((always_inline)) void beam_eval(floe_beam_set *s, const floe_step_ctx *ctx, int k,
                                                            double *pf, unsigned char *act, double *el, double *ds,
                                                            int *nbreak) {
    floe_particles *p = ctx->p;
    const int stepping = ctx->stepping, dim = ctx->dim;
    const double dt = ctx->dt;
    beam_bond *b = &s->b[k];
    if (act) act[k] = 0;
    if (b->broken) return;
    const int i = b->i, j = b->j;
    const floe_beam_section *c = &b->s;
    const double *xi = p->x + 3 * i, *xj = p->x + 3 * j, *qi = p->q + 4 * i, *qj = p->q + 4 * j;
    double d[3], e[3], ti[3], tj[3], thi[3], thj[3];
    floe_v3_sub(d, xj, xi);
    double L = floe_v3_norm(d);
    for (int a = 0; a < 3; a++) e[a] = d[a] / L;
    floe_q_rotate(ti, qi, b->ci);
    floe_q_rotate(tj, qj, b->cj);
    floe_v3_cross(thi, e, ti); /* end rotations relative to the chord */
    floe_v3_cross(thj, e, tj);
    double twist = 0;
    if (dim == 3) {
        double ni[3], nj[3], cr[3];
        floe_q_rotate(ni, qi, b->ni);
        floe_q_rotate(nj, qj, b->nj);
        floe_v3_axpy(ni, -floe_v3_dot(ni, e), e);
        floe_v3_axpy(nj, -floe_v3_dot(nj, e), e);
        floe_v3_cross(cr, ni, nj);
        twist = atan2(floe_v3_dot(cr, e), floe_v3_dot(ni, nj));
    }
    const double l0 = c->l, f = 1.0 / (1.0 + c->phi), ka = c->E * c->A / l0, kt = c->G * c->J / l0;
    const double c1 = (4.0 + c->phi) * c->E * c->I / l0 * f, c2 = (2.0 - c->phi) * c->E * c->I / l0 * f;
    double u = L - l0, N = ka * u, T = kt * twist, Mi[3], Mj[3];
    for (int a = 0; a < 3; a++) {
        Mi[a] = c1 * thi[a] + c2 * thj[a];
        Mj[a] = c2 * thi[a] + c1 * thj[a];
    }
    double energy = 0.5 * (N * u + floe_v3_dot(thi, Mi) + floe_v3_dot(thj, Mj) + T * twist);
    /* stresses of 004 eq 11 from the elastic forces */
    double Ms[3];
    floe_v3_add(Ms, Mi, Mj);
    const double bend = fmax(floe_v3_norm(Mi), floe_v3_norm(Mj)) / c->W;
    double sigma = N / c->A + bend, sigc = -N / c->A + bend;
    double tau = 1.5 * floe_v3_norm(Ms) / (L * c->A) + fabs(T) / (2.0 * c->W);
    b->sigma = sigma;
    b->tau = tau;
    b->sigc = sigc;
    double Fi[3] = {0, 0, 0}, Ti[3] = {0, 0, 0}, Tj[3] = {0, 0, 0};
    double s_brk = 0, l_brk = 0;
    int mode;
    if (b->ellipse)
        mode = ellipse_mode(b, sigma, -sigc, tau, &s_brk, &l_brk);
    else {
        /* Mohr-Coulomb: axial compression raises the shear limit */
        const double tau_lim = b->tau_lim + (N < 0 ? b->tan_phi * (-N / c->A) : 0.0);
        mode = sigma > b->sig_lim ? 1 : tau > tau_lim ? 2 : sigc > b->sigc_lim ? 3 : 0;
        s_brk = mode == 1 ? sigma : mode == 2 ? tau : sigc;
        l_brk = mode == 1 ? b->sig_lim : mode == 2 ? tau_lim : b->sigc_lim;
    }
    if (stepping && mode) {
        b->mode = mode;
        b->s_broken = s_brk;
        b->lim_broken = l_brk;
        for (int a = 0; a < 3; a++) b->x_broken[a] = 0.5 * (xi[a] + xj[a]);
        b->sigc = 0;
        b->broken = 1;
        b->t_broken = ctx->time;
        b->sigma = b->tau = 0;
        (*nbreak)++;
        energy = 0;
    } else {
        if (b->damp > 0) { /* stiffness-proportional damping on the deformation rates */
            const double *vi = p->v + 3 * i, *vj = p->v + 3 * j, *wi = p->w + 3 * i, *wj = p->w + 3 * j;
            double vr[3], wch[3], rdi[3], rdj[3];
            floe_v3_sub(vr, vj, vi);
            floe_v3_cross(wch, e, vr);
            floe_v3_scale(wch, 1.0 / L);
            double wie = floe_v3_dot(wi, e), wje = floe_v3_dot(wj, e);
            for (int a = 0; a < 3; a++) {
                rdi[a] = wi[a] - wie * e[a] - wch[a];
                rdj[a] = wj[a] - wje * e[a] - wch[a];
            }
            if (dim == 2) rdi[0] = rdi[1] = rdj[0] = rdj[1] = 0;
            const double h = b->damp;
            N += h * ka * floe_v3_dot(e, vr);
            T += dim == 3 ? h * kt * (wje - wie) : 0.0;
            for (int a = 0; a < 3; a++) {
                Mi[a] += h * (c1 * rdi[a] + c2 * rdj[a]);
                Mj[a] += h * (c2 * rdi[a] + c1 * rdj[a]);
            }
            floe_v3_add(Ms, Mi, Mj);
        }
        /* force on j: -N e + ((M_i + M_j) x e) / L; torques -M_i + T e and -M_j - T e */
        double Fj[3];
        floe_v3_cross(Fj, Ms, e);
        for (int a = 0; a < 3; a++) {
            Fj[a] = Fj[a] / L - N * e[a];
            Fi[a] = -Fj[a];
            Ti[a] = -Mi[a] + T * e[a];
            Tj[a] = -Mj[a] - T * e[a];
        }
        if (pf) { /* the gather adds -Fi = Fj to j */
            double *q = pf + 9 * (size_t)k;
            memcpy(q, Fi, sizeof Fi);
            memcpy(q + 3, Ti, sizeof Ti);
            memcpy(q + 6, Tj, sizeof Tj);
            act[k] = 1;
        } else
            for (int a = 0; a < 3; a++) {
                p->f[3 * i + a] += Fi[a];
                p->f[3 * j + a] += Fj[a];
                p->t[3 * i + a] += Ti[a];
                p->t[3 * j + a] += Tj[a];
            }
    }
    if (stepping) {
        /* ledger: work of the bond forces over the step (trapezoid, mid-step velocities) */
        const double *vi = p->v + 3 * i, *vj = p->v + 3 * j, *wi = p->w + 3 * i, *wj = p->w + 3 * j;
        double wk = 0;
        for (int a = 0; a < 3; a++)
            wk += (Fi[a] + b->fold[a]) * (vi[a] - vj[a]) + (Ti[a] + b->fold[3 + a]) * wi[a] +
                  (Tj[a] + b->fold[6 + a]) * wj[a];
        *ds += -0.5 * wk * dt - (energy - b->energy);
    }
    memcpy(b->fold, Fi, sizeof Fi);
    memcpy(b->fold + 3, Ti, sizeof Ti);
    memcpy(b->fold + 6, Tj, sizeof Tj);
    b->energy = energy;
    *el += energy;
}

static int beam_grow(void **ptr, size_t need, size_t *cap, size_t size) {
    if (need <= *cap) return 0;
    void *t = realloc(*ptr, need * size);
    if (!t) return -1;
    *ptr = t;
    *cap = need;
    return 0;
}

/* the threaded loop's buffers for nblk blocks and n particles, the particles' bonds rebuilt
 * when bonds were added or dropped; -1: out of memory (the caller runs the serial loop,
 * which gives the same bits) */
static int beam_par_prepare(floe_beam_set *s, int n, int nblk) {
    const size_t nb = (size_t)(s->n > 0 ? s->n : 1);
    if (beam_grow((void **)&s->pf, 9 * nb, &s->pf_cap, sizeof(double)) ||
        beam_grow((void **)&s->act, nb, &s->act_cap, 1))
        return -1;
    if (nblk > s->blk_cap) {
        double *e = realloc(s->blk, 2 * (size_t)nblk * sizeof *e);
        if (!e) return -1;
        s->blk = e;
        int *c = realloc(s->blkn, (size_t)nblk * sizeof *c);
        if (!c) return -1;
        s->blkn = c;
        s->blk_cap = nblk;
    }
    if (!s->bix_off || s->bix_gen != s->gen || s->bix_np != n) {
        int *off = realloc(s->bix_off, ((size_t)n + 1) * sizeof *off);
        if (!off) return -1;
        s->bix_off = off;
        s->bix_np = -1; /* unbuilt until the end */
        if (beam_grow((void **)&s->bix, 2 * nb, &s->bix_cap, sizeof(int))) return -1;
        memset(off, 0, ((size_t)n + 1) * sizeof *off);
        for (int k = 0; k < s->n; k++) { off[s->b[k].i + 1]++; off[s->b[k].j + 1]++; }
        for (int q = 0; q < n; q++) off[q + 1] += off[q];
        for (int k = 0; k < s->n; k++) { /* in bond order: a particle's bonds ascend */
            s->bix[off[s->b[k].i]++] = 2 * k;
            s->bix[off[s->b[k].j]++] = 2 * k + 1;
        }
        for (int q = n; q > 0; q--) off[q] = off[q - 1];
        off[0] = 0;
        s->bix_np = n;
        s->bix_gen = s->gen;
    }
    return 0;
}

int floe_beam_set_forces(floe_beam_set *s, const floe_step_ctx *ctx, double *elastic, double *dissipated) {
    if (!s) return 0;
    floe_particles *p = ctx->p;
    const int stepping = ctx->stepping, nbond = s->n, B = FLOE_PAR_BLOCK, nblk = (nbond + B - 1) / B;
    int nbreak = 0;
    double el = 0, ds = 0;
    int nt = s->nthreads < nblk ? s->nthreads : nblk;
#ifndef _OPENMP
    nt = 1;
#endif
    if (nt > 1 && beam_par_prepare(s, p->n, nblk)) nt = 1;
    if (nt <= 1) {
        for (int c = 0; c < nblk; c++) {
            const int k1 = (c + 1) * B < nbond ? (c + 1) * B : nbond;
            double eb = 0, db = 0;
            for (int k = c * B; k < k1; k++) beam_eval(s, ctx, k, NULL, NULL, &eb, &db, &nbreak);
            el += eb;
            ds += db;
        }
    } else {
        double *pf = s->pf, *blk = s->blk;
        unsigned char *act = s->act;
        int *blkn = s->blkn;
        const int n = p->n, *off = s->bix_off, *bix = s->bix;
        double *f = p->f, *tq = p->t;
        FLOE_OMP(omp parallel num_threads(nt))
        {
            FLOE_OMP(omp for schedule(dynamic, 1))
            for (int c = 0; c < nblk; c++) {
                const int k1 = (c + 1) * B < nbond ? (c + 1) * B : nbond;
                double eb = 0, db = 0;
                int nbk = 0;
                for (int k = c * B; k < k1; k++) beam_eval(s, ctx, k, pf, act, &eb, &db, &nbk);
                blk[2 * c] = eb;
                blk[2 * c + 1] = db;
                blkn[c] = nbk;
            }
            /* each particle's forces in bond order, as the serial loop adds them */
            FLOE_OMP(omp for schedule(static))
            for (int q = 0; q < n; q++) {
                const int e1 = off[q + 1];
                if (off[q] == e1) continue;
                double fq[3] = {f[3 * q], f[3 * q + 1], f[3 * q + 2]};
                double tq_[3] = {tq[3 * q], tq[3 * q + 1], tq[3 * q + 2]};
                for (int e = off[q]; e < e1; e++) {
                    const int k = bix[e] >> 1;
                    if (!act[k]) continue;
                    const double *bk = pf + 9 * (size_t)k;
                    if (bix[e] & 1)
                        for (int a = 0; a < 3; a++) { fq[a] += -bk[a]; tq_[a] += bk[6 + a]; }
                    else
                        for (int a = 0; a < 3; a++) { fq[a] += bk[a]; tq_[a] += bk[3 + a]; }
                }
                for (int a = 0; a < 3; a++) { f[3 * q + a] = fq[a]; tq[3 * q + a] = tq_[a]; }
            }
        }
        for (int c = 0; c < nblk; c++) {
            el += blk[2 * c];
            ds += blk[2 * c + 1];
            nbreak += blkn[c];
        }
    }
    s->nbroken += nbreak;
    *elastic += el;
    if (stepping) *dissipated += ds;
    return nbreak;
}
