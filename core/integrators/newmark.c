/* newmark.c - explicit and implicit Newmark-beta for bonded systems (004 §3-4, eqs 13-30):
 * nodes + beam bonds (004 eq 7) + supports + loads; sparse K, C, M assembled in the bonds'
 * local frames and factored by SuiteSparse CHOLMOD (implicit), block-diagonal node solves
 * (explicit), incremental internal forces (eqs 19-20), stresses and breakage (eqs 10-11),
 * step cuts by the line search of eqs 29-30. floe_newmark.h has the equations. */
#include "newmark_base.h"

floe_newmark_def floe_newmark_default_def(void) {
    floe_newmark_def d;
    memset(&d, 0, sizeof d);
    d.dim = 2;
    d.beta = 0.25;
    d.gamma = 0.5;
    d.line_search_eps = 0.01;
    d.max_cuts = 12;
    return d;
}

floe_newmark *floe_newmark_create(const floe_newmark_def *def, char *err, size_t errlen) {
    const char *bad = NULL;
    if (!def) bad = "definition is NULL";
    else if (def->dim != 2 && def->dim != 3) bad = "dim must be 2 or 3";
    else if (!(def->beta >= 0 && 2 * def->beta <= 1)) bad = "beta must satisfy 0 <= 2 beta <= 1 (eq 16)";
    else if (!(def->gamma >= 0.5 && def->gamma <= 1)) bad = "gamma must be in [1/2, 1]";
    else if (!(def->dt > 0) || !isfinite(def->dt)) bad = "dt must be > 0";
    else if (!(def->damping_ratio >= 0) || !isfinite(def->damping_ratio)) bad = "damping_ratio must be >= 0";
    else if (!(def->mass_damping >= 0) || !isfinite(def->mass_damping)) bad = "mass_damping must be >= 0";
    else if (!isfinite(def->line_search_eps)) bad = "line_search_eps must be finite";
    else if (def->max_cuts < 0) bad = "max_cuts must be >= 0";
#ifndef FLOE_HAVE_CHOLMOD
    else if (def->beta > 0) {
        if (err && errlen)
            snprintf(err, errlen, "implicit Newmark (beta > 0) needs SuiteSparse CHOLMOD: this build has "
                                  "FLOE_WITH_CHOLMOD=OFF");
        return NULL;
    }
#endif
    if (bad) {
        if (err && errlen) snprintf(err, errlen, "invalid Newmark definition: %s", bad);
        return NULL;
    }
    floe_newmark *s = calloc(1, sizeof *s);
    if (!s) {
        if (err && errlen) snprintf(err, errlen, "out of memory");
        return NULL;
    }
    s->def = *def;
    s->dim = def->dim;
    s->nd = def->dim == 2 ? 3 : 6;
    s->st.t_first_break = -1;
    s->ablk_epoch = -1;
    s->inc_epoch = -1;
    return s;
}

int floe_newmark_set_threads(floe_newmark *s, int nthreads) {
    int code;
    const char *why = floe_par_threads_refused(nthreads, &code);
    if (why) return nm_error(s, code, "threads: %d %s", nthreads, why);
    s->nthreads = nthreads;
    return FLOE_OK;
}

static void free_arrays(floe_newmark *s) {
    free(s->x); free(s->mass); free(s->inertia); free(s->fix); free(s->F);
    free(s->u); free(s->v); free(s->a); free(s->fint);
    free(s->du); free(s->vnew); free(s->anew); free(s->kd); free(s->an); free(s->bn); free(s->rhs);
    free(s->cv0); free(s->cv1);
}

#ifdef FLOE_HAVE_CHOLMOD
static void free_cholmod(floe_newmark *s) {
    if (!s->cc_started) return;
    cholmod_free_sparse(&s->A, &s->cc);
    for (int k = 0; k < NM_SLOTS; k++) cholmod_free_factor(&s->L[k], &s->cc);
    cholmod_free_dense(&s->B, &s->cc);
    cholmod_free_dense(&s->X, &s->cc);
    cholmod_free_dense(&s->Y, &s->cc);
    cholmod_free_dense(&s->E, &s->cc);
    cholmod_finish(&s->cc);
    s->cc_started = 0;
    free(s->bpos);
    free(s->npos);
    free(s->pinv);
    s->bpos = s->npos = s->pinv = NULL;
}
#endif

void floe_newmark_destroy(floe_newmark *s) {
    if (!s) return;
    free_arrays(s);
    free(s->b);
    free(s->eq);
    free(s->cblk);
    free(s->ablk);
    free(s->inc_off); free(s->inc); free(s->gdf); free(s->bsum); free(s->bbrk); free(s->bflag); free(s->vsum);
#ifdef FLOE_HAVE_CHOLMOD
    free_cholmod(s);
#endif
    free(s);
}

const char *floe_newmark_last_error(const floe_newmark *s) { return s->err; }

/* ---- set-up ---- */

static int grow_nodes(floe_newmark *s, int need) {
    if (need <= s->cap) return FLOE_OK;
    int nc = s->cap ? 2 * s->cap : 64;
    while (nc < need) nc *= 2;
    const size_t nd = (size_t)s->nd;
#define RE(f, k) do { void *t_ = realloc(s->f, (size_t)nc * (k) * sizeof *s->f); if (!t_) return FLOE_ENOMEM; s->f = t_; } while (0)
    RE(x, 3); RE(mass, 1); RE(inertia, 1); RE(fix, 1); RE(F, nd);
    RE(u, nd); RE(v, nd); RE(a, nd); RE(fint, nd);
    RE(du, nd); RE(vnew, nd); RE(anew, nd); RE(kd, nd); RE(an, nd); RE(bn, nd); RE(rhs, nd); RE(cv0, nd); RE(cv1, nd);
#undef RE
    s->cap = nc;
    return FLOE_OK;
}

int floe_newmark_add_node(floe_newmark *s, const double x[3], double mass, double inertia) {
    if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2]))
        return -nm_error(s, FLOE_EINVAL, "node: position must be finite");
    if (!(mass > 0) || !isfinite(mass)) return -nm_error(s, FLOE_EINVAL, "node: mass must be > 0 (got %g)", mass);
    if (!(inertia > 0) || !isfinite(inertia))
        return -nm_error(s, FLOE_EINVAL, "node: rotational inertia must be > 0 (got %g)", inertia);
    if (grow_nodes(s, s->n + 1)) return -nm_error(s, FLOE_ENOMEM, "out of memory");
    int i = s->n++, nd = s->nd;
    memcpy(s->x + 3 * i, x, 3 * sizeof *x);
    if (s->dim == 2) s->x[3 * i + 2] = 0;
    s->mass[i] = mass;
    s->inertia[i] = inertia;
    s->fix[i] = 0;
    for (int k = 0; k < nd; k++) s->F[nd * i + k] = s->u[nd * i + k] = s->v[nd * i + k] = 0;
    s->prepared = 0;
    return i;
}

/* rows of R: e, then two normals (2D: e_perp in the plane; 3D: any right-handed pair) */
static void bond_frame(int dim, const double e[3], double R[9]) {
    R[0] = e[0]; R[1] = e[1]; R[2] = e[2];
    if (dim == 2) {
        R[3] = -e[1]; R[4] = e[0]; R[5] = 0;
    } else {
        double ax[3] = {0, 0, 0}, y[3];
        int k = fabs(e[0]) <= fabs(e[1]) && fabs(e[0]) <= fabs(e[2]) ? 0 : fabs(e[1]) <= fabs(e[2]) ? 1 : 2;
        ax[k] = 1;
        floe_v3_cross(y, ax, e);
        floe_v3_scale(y, 1.0 / floe_v3_norm(y));
        R[3] = y[0]; R[4] = y[1]; R[5] = y[2];
    }
    floe_v3_cross(R + 6, R, R + 3);
}

int floe_newmark_add_bond(floe_newmark *s, int i, int j, const floe_beam_section *sec, double sigma_lim, double tau_lim) {
    if (i < 0 || j < 0 || i >= s->n || j >= s->n || i == j)
        return -nm_error(s, FLOE_EINVAL, "bond: nodes %d and %d must be two different indices < %d", i, j, s->n);
    if (!sec || !(sec->E > 0) || !(sec->A > 0) || !(sec->I > 0) || !(sec->W > 0) || !(sec->phi >= 0) ||
        (s->dim == 3 && !(sec->G > 0 && sec->J > 0)) || !isfinite(sec->E + sec->A + sec->I + sec->W + sec->phi))
        return -nm_error(s, FLOE_EINVAL, "bond %d-%d: the section needs E, A, I, W > 0 (3D: G, J > 0) and phi >= 0", i, j);
    if (!(sigma_lim >= 0) || !(tau_lim >= 0))
        return -nm_error(s, FLOE_EINVAL, "bond %d-%d: strengths must be >= 0 (INFINITY: unbreakable)", i, j);
    double d[3];
    floe_v3_sub(d, s->x + 3 * j, s->x + 3 * i);
    double l = floe_v3_norm(d);
    if (!(l > 0)) return -nm_error(s, FLOE_EINVAL, "bond %d-%d: the nodes are at the same place", i, j);
    if (s->nb == s->bcap) {
        int nc = s->bcap ? 2 * s->bcap : 64;
        nm_bond *nbp = realloc(s->b, (size_t)nc * sizeof *nbp);
        if (!nbp) return -nm_error(s, FLOE_ENOMEM, "out of memory");
        s->b = nbp;
        s->bcap = nc;
    }
    nm_bond *b = &s->b[s->nb];
    memset(b, 0, sizeof *b);
    b->i = i;
    b->j = j;
    b->s = *sec;
    b->s.l = l;
    floe_v3_scale(d, 1.0 / l);
    bond_frame(s->dim, d, b->R);
    b->sig_lim = sigma_lim;
    b->tau_lim = tau_lim;
    b->t_broken = -1;
    const floe_beam_section *c = &b->s;
    double g = 1.0 / (1.0 + c->phi), EI = c->E * c->I;
    b->k[0] = c->E * c->A / l;
    b->k[1] = 12.0 * EI / (l * l * l) * g;
    b->k[2] = 6.0 * EI / (l * l) * g;
    b->k[3] = (4.0 + c->phi) * EI / l * g;
    b->k[4] = (2.0 - c->phi) * EI / l * g;
    b->k[5] = c->G * c->J / l;
    b->inv_a = 1.0 / c->A;
    b->inv_w = 1.0 / c->W;
    s->prepared = 0;
    return s->nb++;
}

int floe_newmark_fix(floe_newmark *s, int i, unsigned mask) {
    if (i < 0 || i >= s->n) return nm_error(s, FLOE_EINVAL, "fix: node %d out of range", i);
    s->fix[i] |= mask & FLOE_NM_ALL;
    s->prepared = 0;
    return FLOE_OK;
}

/* component k of node i in the dim's layout: 2D (ux, uy, rz), 3D (ux, uy, uz, rx, ry, rz) */
static unsigned comp_mask(int dim, int k) {
    static const unsigned m2[3] = {FLOE_NM_UX, FLOE_NM_UY, FLOE_NM_RZ};
    return dim == 2 ? m2[k] : 1u << k;
}

int floe_newmark_set_load(floe_newmark *s, int i, const double f[3], const double m[3]) {
    if (i < 0 || i >= s->n) return nm_error(s, FLOE_EINVAL, "load: node %d out of range", i);
    double *F = s->F + s->nd * i;
    for (int k = 0; k < 3; k++)
        if (!isfinite(f ? f[k] : 0) || !isfinite(m ? m[k] : 0)) return nm_error(s, FLOE_EINVAL, "load: must be finite");
    if (s->dim == 2) { F[0] = f ? f[0] : 0; F[1] = f ? f[1] : 0; F[2] = m ? m[2] : 0; }
    else for (int k = 0; k < 3; k++) { F[k] = f ? f[k] : 0; F[3 + k] = m ? m[k] : 0; }
    return FLOE_OK;
}

int floe_newmark_set_load_factor(floe_newmark *s, floe_newmark_load_fn fn, void *user) {
    s->lf = fn;
    s->lf_user = user;
    return FLOE_OK;
}

int floe_newmark_set_initial(floe_newmark *s, int i, const double u[3], const double rot[3], const double v[3],
                             const double w[3]) {
    if (i < 0 || i >= s->n) return nm_error(s, FLOE_EINVAL, "initial: node %d out of range", i);
    if (s->prepared || s->st.steps) return nm_error(s, FLOE_EINVAL, "initial: only before the first step");
    double *U = s->u + s->nd * i, *V = s->v + s->nd * i;
    const double z[3] = {0, 0, 0};
    if (!u) u = z;
    if (!rot) rot = z;
    if (!v) v = z;
    if (!w) w = z;
    if (s->dim == 2) { U[0] = u[0]; U[1] = u[1]; U[2] = rot[2]; V[0] = v[0]; V[1] = v[1]; V[2] = w[2]; }
    else for (int k = 0; k < 3; k++) { U[k] = u[k]; U[3 + k] = rot[k]; V[k] = v[k]; V[3 + k] = w[k]; }
    return FLOE_OK;
}

/* ---- bond kernels ---- */

/* f = K_loc u (004 eq 7) from the cached entries: floe_beam_local_apply without divisions */
static inline void local_apply(const nm_bond *b, int dim, const double *u, double *f) {
    const double *k = b->k;
    if (dim == 2) {
        double n = k[0] * (u[0] - u[3]), dv = u[1] - u[4];
        f[0] = n;
        f[3] = -n;
        f[1] = k[1] * dv + k[2] * (u[2] + u[5]);
        f[4] = -f[1];
        f[2] = k[2] * dv + k[3] * u[2] + k[4] * u[5];
        f[5] = k[2] * dv + k[4] * u[2] + k[3] * u[5];
    } else {
        double n = k[0] * (u[0] - u[6]), t = k[5] * (u[3] - u[9]), dv = u[1] - u[7], dw = u[2] - u[8];
        f[0] = n;
        f[6] = -n;
        f[3] = t;
        f[9] = -t;
        f[1] = k[1] * dv + k[2] * (u[5] + u[11]);
        f[7] = -f[1];
        f[5] = k[2] * dv + k[3] * u[5] + k[4] * u[11];
        f[11] = k[2] * dv + k[4] * u[5] + k[3] * u[11];
        f[2] = k[1] * dw - k[2] * (u[4] + u[10]);
        f[8] = -f[2];
        f[4] = -k[2] * dw + k[3] * u[4] + k[4] * u[10];
        f[10] = -k[2] * dw + k[4] * u[4] + k[3] * u[10];
    }
}

/* eq 11 from the local end forces (floe_beam_stress with the cached 1/A, 1/W) */
static inline void local_stress(const nm_bond *b, int dim, const double *f, double *sigma, double *tau) {
    if (dim == 2) {
        *sigma = 0.5 * (f[3] - f[0]) * b->inv_a + fmax(fabs(f[2]), fabs(f[5])) * b->inv_w;
        *tau = 0.75 * (fabs(f[1]) + fabs(f[4])) * b->inv_a;
    } else floe_beam_stress(&b->s, dim, f, sigma, tau);
}

static double bond_ratio(const nm_bond *b, double sig, double tau) {
    double r = 0;
    if (isfinite(b->sig_lim)) r = b->sig_lim > 0 ? sig / b->sig_lim : (sig > 0 ? INFINITY : 0);
    if (isfinite(b->tau_lim)) r = fmax(r, b->tau_lim > 0 ? tau / b->tau_lim : (tau > 0 ? INFINITY : 0));
    return r;
}

/* ---- the bond passes (threads: docs/parallel.md, "What runs threaded") ---- */

/* every node's intact bonds in bond order (entries 2 k + e), for the gathers; rebuilt when
 * bonds break (the epoch) */
static int build_incidence(floe_newmark *s) {
    if (s->inc_epoch == s->epoch && s->inc_off) return FLOE_OK;
    int *off = realloc(s->inc_off, (size_t)(s->n + 1) * sizeof *off);
    if (off) s->inc_off = off;
    int *in = off ? realloc(s->inc, (size_t)(s->nb > 0 ? 2 * s->nb : 1) * sizeof *in) : NULL;
    if (in) s->inc = in;
    if (!off || !in) return nm_error(s, FLOE_ENOMEM, "out of memory");
    memset(off, 0, (size_t)(s->n + 1) * sizeof *off);
    for (int k = 0; k < s->nb; k++)
        if (!s->b[k].broken) { off[s->b[k].i]++; off[s->b[k].j]++; }
    int at = 0;
    for (int i = 0; i < s->n; i++) { const int c = off[i]; off[i] = at; at += c; }
    off[s->n] = at;
    for (int k = 0; k < s->nb; k++) /* in bond order: each node's entries ascend */
        if (!s->b[k].broken) { in[off[s->b[k].i]++] = 2 * k; in[off[s->b[k].j]++] = 2 * k + 1; }
    for (int i = s->n; i > 0; i--) off[i] = off[i - 1]; /* the fill moved each start to the next's */
    off[0] = 0;
    s->inc_epoch = s->epoch;
    return FLOE_OK;
}

/* out = the sum over each node's intact bonds of their ends' forces (gdf), in bond order */
static void gather_nodes(floe_newmark *s, double *out) {
    const int nd = s->nd, n = s->n, nt = nm_threads(s, (long)nd * n);
    const int *off = s->inc_off, *in = s->inc;
    const double *gdf = s->gdf;
    FLOE_OMP(omp parallel for num_threads(nt) schedule(static) if(nt > 1))
    for (int i = 0; i < n; i++) {
        double acc[6] = {0, 0, 0, 0, 0, 0};
        for (int p = off[i]; p < off[i + 1]; p++) {
            const double *g = gdf + (size_t)nd * in[p];
            for (int c = 0; c < nd; c++) acc[c] += g[c];
        }
        for (int c = 0; c < nd; c++) out[(size_t)nd * i + c] = acc[c];
    }
}

enum { NM_APPLY, NM_TRIAL, NM_ACCEPT };

/* one pass over the intact bonds with the global vector g, out = the nodes' sums:
 *   NM_APPLY  out = K g;
 *   NM_TRIAL  the trial increments dfl = K_loc T^T g, out = their sum (kd), the trial
 *             stresses; *de = the change of stored energy;
 *   NM_ACCEPT the same, and the trial accepted at once (fl += dfl, the stresses), the bonds at
 *             or above their strength flagged (bflag, bbrk): the explicit step, which never
 *             redoes a trial */
static int bond_pass(floe_newmark *s, const double *g, double *out, int mode, double *de) {
    double t0 = now_s();
    const int nb = s->nb, n2 = 2 * s->nd, dim = s->dim, B = FLOE_PAR_BLOCK;
    const int nblk = (nb + B - 1) / B, nt = nm_threads(s, nb), nd = s->nd;
    if (nt > 1) FLOE_TRY(build_incidence(s)); /* the gather's index (one thread scatters) */
    nm_bond *bonds = s->b;
    double *gdf = s->gdf, *bsum = s->bsum;
    int *bbrk = s->bbrk;
    unsigned char *bflag = s->bflag;
    /* one thread: each bond's ends added to out at once, in bond order, from the same values
     * the gather adds in the same order (the same bits, without gdf's traffic) */
    const int scatter = nt == 1;
    if (scatter) memset(out, 0, (size_t)nd * s->n * sizeof *out);
    FLOE_OMP(omp parallel for num_threads(nt) schedule(static) if(nt > 1))
    for (int blk = 0; blk < nblk; blk++) {
        const int k1 = (blk + 1) * B < nb ? (blk + 1) * B : nb;
        double sum = 0, ul[12], f[12], g12[12];
        int brk = 0;
        for (int k = blk * B; k < k1; k++) {
            nm_bond *b = &bonds[k];
            if (b->broken) continue;
            double *gd = scatter ? g12 : gdf + (size_t)n2 * k;
            to_local(s, b, g, ul);
            if (mode == NM_APPLY) local_apply(b, dim, ul, f);
            else local_apply(b, dim, ul, b->dfl);
            ends_global(s, b, mode == NM_APPLY ? f : b->dfl, gd);
            if (scatter)
                for (int c = 0; c < nd; c++) {
                    out[(size_t)nd * b->i + c] += gd[c];
                    out[(size_t)nd * b->j + c] += gd[nd + c];
                }
            if (mode == NM_APPLY) continue;
            for (int c = 0; c < n2; c++) {
                f[c] = b->fl[c] + b->dfl[c];
                sum += (b->fl[c] + 0.5 * b->dfl[c]) * ul[c];
            }
            local_stress(b, dim, f, &b->sig_tr, &b->tau_tr);
            if (mode == NM_ACCEPT) {
                if (n2 == 6) memcpy(b->fl, f, 6 * sizeof *f); /* constant sizes: inline moves */
                else memcpy(b->fl, f, 12 * sizeof *f);
                b->sigma = b->sig_tr;
                b->tau = b->tau_tr;
                bflag[k] = bond_ratio(b, b->sigma, b->tau) >= 1;
                brk += bflag[k];
            }
        }
        bsum[blk] = sum;
        bbrk[blk] = brk;
    }
    if (!scatter) gather_nodes(s, out);
    if (de) {
        double e = 0;
        for (int blk = 0; blk < nblk; blk++) e += bsum[blk];
        *de = e;
    }
    s->st.seconds_bonds += now_s() - t0;
    return FLOE_OK;
}

/* the trial of the last NM_TRIAL pass accepted (the implicit step): fl += dfl, the stresses,
 * the bonds at or above their strength flagged */
static void accept_pass(floe_newmark *s) {
    const int nb = s->nb, n2 = 2 * s->nd, B = FLOE_PAR_BLOCK;
    const int nblk = (nb + B - 1) / B, nt = nm_threads(s, nb);
    nm_bond *bonds = s->b;
    int *bbrk = s->bbrk;
    unsigned char *bflag = s->bflag;
    FLOE_OMP(omp parallel for num_threads(nt) schedule(static) if(nt > 1))
    for (int blk = 0; blk < nblk; blk++) {
        const int k1 = (blk + 1) * B < nb ? (blk + 1) * B : nb;
        int brk = 0;
        for (int k = blk * B; k < k1; k++) {
            nm_bond *b = &bonds[k];
            if (b->broken) continue;
            for (int c = 0; c < n2; c++) b->fl[c] += b->dfl[c];
            b->sigma = b->sig_tr;
            b->tau = b->tau_tr;
            bflag[k] = bond_ratio(b, b->sigma, b->tau) >= 1;
            brk += bflag[k];
        }
        bbrk[blk] = brk;
    }
}


/* ---- damping blocks (eq 8) ---- */

static void bond_dampers(floe_newmark *s, nm_bond *b) {
    const double xi = s->def.damping_ratio;
    memset(b->c, 0, sizeof b->c);
    if (!(xi > 0)) return;
    double mi = s->mass[b->i], mj = s->mass[b->j], Ji = s->inertia[b->i], Jj = s->inertia[b->j];
    double mr = mi * mj / (mi + mj), Jr = Ji * Jj / (Ji + Jj);
    double K[144];
    const int n2 = 2 * s->nd;
    floe_beam_local_stiffness(&b->s, s->dim, K);
    if (s->nd == 3) {
        b->c[0] = 2 * xi * sqrt(K[0] * mr);
        b->c[1] = 2 * xi * sqrt(K[1 * n2 + 1] * mr);
        b->c[5] = 2 * xi * sqrt(K[2 * n2 + 2] * Jr);
    } else
        for (int r = 0; r < 3; r++) {
            b->c[r] = 2 * xi * sqrt(K[r * n2 + r] * mr);
            b->c[3 + r] = 2 * xi * sqrt(K[(3 + r) * n2 + 3 + r] * Jr);
        }
}

/* the C block of every node: sum over its intact bonds of T^T diag(c) T, plus alpha M */
static void build_cblk(floe_newmark *s) {
    const int nd = s->nd, nn = nd * nd;
    memset(s->cblk, 0, (size_t)s->n * nn * sizeof *s->cblk);
    for (int i = 0; i < s->n; i++) {
        double *C = s->cblk + (size_t)nn * i;
        for (int k = 0; k < nd; k++) {
            int rot = nd == 3 ? k == 2 : k >= 3;
            C[k * nd + k] = s->def.mass_damping * (rot ? s->inertia[i] : s->mass[i]);
        }
    }
    for (int k = 0; k < s->nb; k++) {
        nm_bond *b = &s->b[k];
        if (b->broken) continue;
        double D[36];
        bond_damper_block(nd, b, D);
        const int ends[2] = {b->i, b->j};
        for (int e = 0; e < 2; e++) {
            double *C = s->cblk + (size_t)nn * ends[e];
            for (int q = 0; q < nn; q++) C[q] += D[q];
        }
    }
}

/* out = C g (node blocks) */
static void c_apply(const floe_newmark *s, const double *g, double *out) {
    const int nd = s->nd, nn = nd * nd;
    if (!(s->def.damping_ratio > 0) && !(s->def.mass_damping > 0)) {
        memset(out, 0, (size_t)nd * s->n * sizeof *out);
        return;
    }
    const int n = s->n, nt = nm_threads(s, (long)nd * n);
    FLOE_OMP(omp parallel for num_threads(nt) schedule(static) if(nt > 1))
    for (int i = 0; i < n; i++) {
        const double *C = s->cblk + (size_t)nn * i, *q = g + (size_t)nd * i;
        double *o = out + (size_t)nd * i;
        for (int r = 0; r < nd; r++) {
            double acc = 0;
            for (int c = 0; c < nd; c++) acc += C[r * nd + c] * q[c];
            o[r] = acc;
        }
    }
}

/* ---- critical steps ---- */

double floe_newmark_critical_dt(floe_newmark *s) {
    const int nd = s->nd, n = s->n;
    double *row = calloc((size_t)(n ? n : 1) * 2, sizeof *row);
    double *crow = calloc((size_t)(n ? n : 1) * 2, sizeof *crow);
    if (!row || !crow) { free(row); free(crow); return 0; }
    /* a node's translation (rotation) group takes part when one of its components is free */
    unsigned tmask = nd == 3 ? (FLOE_NM_UX | FLOE_NM_UY) : (FLOE_NM_UX | FLOE_NM_UY | FLOE_NM_UZ);
    unsigned rmask = nd == 3 ? FLOE_NM_RZ : (FLOE_NM_RX | FLOE_NM_RY | FLOE_NM_RZ);
    for (int k = 0; k < s->nb; k++) {
        nm_bond *b = &s->b[k];
        if (b->broken) continue;
        bond_dampers(s, b);
        double nrm[4];
        floe_beam_block_norms(&b->s, s->dim, nrm);
        int ends[2] = {b->i, b->j};
        for (int e = 0; e < 2; e++) {
            int a = ends[e], o = ends[1 - e];
            int at = (s->fix[a] & tmask) != tmask, ar = (s->fix[a] & rmask) != rmask;
            int ot = (s->fix[o] & tmask) != tmask, orr = (s->fix[o] & rmask) != rmask;
            double ma = s->mass[a], Ja = s->inertia[a], mo = s->mass[o], Jo = s->inertia[o];
            if (at) {
                row[2 * a] += nrm[0] / ma + (ar ? nrm[1] / sqrt(ma * Ja) : 0) + (ot ? nrm[0] / sqrt(ma * mo) : 0) +
                              (orr ? nrm[1] / sqrt(ma * Jo) : 0);
                crow[2 * a] += fmax(b->c[0], fmax(b->c[1], b->c[2])) / ma;
            }
            if (ar) {
                row[2 * a + 1] += nrm[2] / Ja + (at ? nrm[1] / sqrt(ma * Ja) : 0) + (ot ? nrm[1] / sqrt(Ja * mo) : 0) +
                                  (orr ? nrm[3] / sqrt(Ja * Jo) : 0);
                crow[2 * a + 1] += fmax(b->c[3], fmax(b->c[4], b->c[5])) / Ja;
            }
        }
    }
    double lmax = 0, cmax = 0;
    for (int a = 0; a < 2 * n; a++) {
        lmax = fmax(lmax, row[a]);
        cmax = fmax(cmax, crow[a]);
    }
    free(row);
    free(crow);
    if (!(lmax > 0)) return INFINITY;
    double om = sqrt(lmax), zeta = 0.5 * (cmax + s->def.mass_damping) / om;
    return 2.0 / om * (sqrt(1.0 + zeta * zeta) - zeta);
}

double floe_newmark_critical_dt_diag(floe_newmark *s) {
    const int nd = s->nd, N = nd * s->n, n2 = 2 * nd;
    double *kd = calloc((size_t)(N ? N : 1), sizeof *kd);
    if (!kd) return 0;
    double K[144];
    for (int k = 0; k < s->nb; k++) {
        const nm_bond *b = &s->b[k];
        if (b->broken) continue;
        floe_beam_local_stiffness(&b->s, s->dim, K);
        /* diagonal of T^T K T for each end component */
        const int ends[2] = {b->i, b->j};
        for (int e = 0; e < 2; e++)
            for (int c = 0; c < nd; c++) {
                double g[12] = {0}, ul[12], fl[12], out[12] = {0};
                nm_bond tmp = *b;
                tmp.i = 0;
                tmp.j = 1;
                g[nd * e + c] = 1;
                to_local(s, &tmp, g, ul);
                for (int r = 0; r < n2; r++) {
                    double acc = 0;
                    for (int q = 0; q < n2; q++) acc += K[r * n2 + q] * ul[q];
                    fl[r] = acc;
                }
                add_global(s, &tmp, fl, 1.0, out);
                kd[(size_t)nd * ends[e] + c] += out[nd * e + c];
            }
    }
    double dt = INFINITY;
    for (int i = 0; i < s->n; i++)
        for (int c = 0; c < nd; c++)
            if (!(s->fix[i] & comp_mask(s->dim, c)) && kd[nd * i + c] > 0)
                dt = fmin(dt, 2.0 * sqrt(node_m(s, i, c) / kd[nd * i + c]));
    free(kd);
    return dt;
}

/* ---- prepare, step ---- */

static double load_factor(const floe_newmark *s, double t) { return s->lf ? s->lf(t, s->lf_user) : 1.0; }

static double kinetic(const floe_newmark *s, const double *v) {
    double e = 0;
    for (int i = 0; i < s->n; i++)
        for (int k = 0; k < s->nd; k++) e += 0.5 * node_m(s, i, k) * v[s->nd * i + k] * v[s->nd * i + k];
    return e;
}

int floe_newmark_prepare(floe_newmark *s) {
    if (s->prepared) return FLOE_OK;
    const int nd = s->nd, N = nd * s->n;
    if (s->n == 0) return nm_error(s, FLOE_EINVAL, "the system has no nodes");
    if (s->st.steps > 0)
        return nm_error(s, FLOE_EINVAL, "the system was changed after its first step (set it up before stepping)");
    int *eq = realloc(s->eq, (size_t)N * sizeof *eq);
    double *cb = realloc(s->cblk, (size_t)s->n * nd * nd * sizeof *cb);
    if (eq) s->eq = eq;
    if (cb) s->cblk = cb;
    if (!eq || !cb) return nm_error(s, FLOE_ENOMEM, "out of memory");
    s->neq = 0;
    for (int i = 0; i < s->n; i++)
        for (int k = 0; k < nd; k++) s->eq[nd * i + k] = (s->fix[i] & comp_mask(s->dim, k)) ? -1 : s->neq++;
    for (int k = 0; k < N; k++)
        if (s->eq[k] < 0) { s->u[k] = 0; s->v[k] = 0; }
    for (int k = 0; k < s->nb; k++) bond_dampers(s, &s->b[k]);
    build_cblk(s);
    {
        const int nblk = (s->nb + FLOE_PAR_BLOCK - 1) / FLOE_PAR_BLOCK + 1;
        double *gd = realloc(s->gdf, (size_t)(s->nb > 0 ? s->nb : 1) * 2 * nd * sizeof *gd);
        if (gd) s->gdf = gd;
        double *bs = realloc(s->bsum, (size_t)nblk * sizeof *bs);
        if (bs) s->bsum = bs;
        int *bk = realloc(s->bbrk, (size_t)nblk * sizeof *bk);
        if (bk) s->bbrk = bk;
        unsigned char *bf = realloc(s->bflag, (size_t)(s->nb > 0 ? s->nb : 1));
        if (bf) s->bflag = bf;
        double *vs = realloc(s->vsum, (size_t)4 * ((N + FLOE_PAR_BLOCK - 1) / FLOE_PAR_BLOCK + 1) * sizeof *vs);
        if (vs) s->vsum = vs;
        if (!gd || !bs || !bk || !bf || !vs) return nm_error(s, FLOE_ENOMEM, "out of memory");
        s->inc_epoch = -1; /* bonds may have been added: the gathers' index again */
    }
    if (s->def.beta == 0) {
        double dtc = floe_newmark_critical_dt(s);
        if (s->def.dt > dtc && !s->def.allow_unstable_dt)
            return nm_error(s, FLOE_EUNSTABLE,
                            "explicit Newmark: dt %g s is above the critical step %g s (block Gershgorin bound); use a "
                            "smaller dt or allow_unstable_dt",
                            s->def.dt, dtc);
        double *ab = realloc(s->ablk, (size_t)s->n * nd * nd * sizeof *ab);
        if (!ab) return nm_error(s, FLOE_ENOMEM, "out of memory");
        s->ablk = ab;
        s->ablk_epoch = -1;
    } else {
#ifdef FLOE_HAVE_CHOLMOD
        free_cholmod(s);
        cholmod_start(&s->cc);
        s->cc_started = 1;
        s->cc.print = 0;
        /* simplicial LDL': with Debian's reference BLAS it factored the 45,000-unknown beam of
         * bench/beam-newmark 1.4x faster than the supernodal method, and it is the form
         * cholmod_updown works on (bond breaks are rank downdates, below) */
        s->cc.supernodal = CHOLMOD_SIMPLICIAL;
        FLOE_TRY(build_pattern(s));
        s->B = cholmod_zeros((size_t)s->neq, 1, CHOLMOD_REAL, &s->cc);
        if (!s->B) return nm_error(s, FLOE_ENOMEM, "out of memory");
        FLOE_TRY(factor(s, 0, s->def.dt));
#else
        return nm_error(s, FLOE_ENOTSUP, "implicit Newmark needs CHOLMOD: this build has FLOE_WITH_CHOLMOD=OFF");
#endif
    }
    /* initial internal forces f_int = K u0 and bond forces from zero (a system prepared
     * again before its first step starts over); a0 from eq 15 at t = 0 */
    for (int k = 0; k < s->nb; k++) memset(s->b[k].fl, 0, sizeof s->b[k].fl);
    double e0 = 0;
    FLOE_TRY(bond_pass(s, s->u, s->fint, NM_TRIAL, &e0));
    for (int k = 0; k < s->nb; k++) {
        nm_bond *b = &s->b[k];
        if (b->broken) continue;
        memcpy(b->fl, b->dfl, sizeof b->fl);
        b->sigma = b->sig_tr;
        b->tau = b->tau_tr;
    }
    c_apply(s, s->v, s->cv0);
    const double lam = load_factor(s, s->t);
    for (int k = 0; k < N; k++) {
        int i = k / nd;
        s->a[k] = s->eq[k] < 0 ? 0.0 : (lam * s->F[k] - s->fint[k] - s->cv0[k]) / node_m(s, i, k % nd);
    }
    s->st.energy_elastic = e0; /* (f + df/2) . du from zero: K u0 . u0 / 2 */
    s->st.energy_kinetic = kinetic(s, s->v);
    s->st.energy_initial = s->st.energy_elastic + s->st.energy_kinetic;
    s->st.work_external = 0;
    s->st.dissipated = 0;
    s->prepared = 1;
    return FLOE_OK;
}

/* the step of level k: dt 2^(-k/2) (the same double every time: factors are found again) */
static double level_dt(double dt_full, int k) { return k <= 0 ? dt_full : dt_full * pow(2.0, -0.5 * k); }

static int do_step(floe_newmark *s, double dt_full) {
    const int nd = s->nd, N = nd * s->n;
    const double beta = s->def.beta, gamma = s->def.gamma;
    /* implicit step control: the step starts at the level the last step left (shorter
     * steps while a crack runs, doubled back after a step without breaks) */
    int level = beta > 0 && s->def.line_search_eps >= 0 ? s->level : 0, k_over = -1, k_under = -1;
    double dt = level_dt(dt_full, level), de = 0, dt_lo = 0, dt_hi = 0, r_lo = 0, r_hi = 0;
    int cuts = 0, final_trial = 0, accepted = 0;
    const int ntv = nm_threads(s, N); /* the element-wise loops (no sums) */
    for (;;) {
        FLOE_OMP(omp parallel for num_threads(ntv) schedule(static) if(ntv > 1))
        for (int k = 0; k < N; k++) {
            if (s->eq[k] < 0) { s->an[k] = s->bn[k] = 0; continue; }
            s->an[k] = dt * s->v[k] + 0.5 * dt * dt * (1 - 2 * beta) * s->a[k];
            s->bn[k] = s->v[k] + (1 - gamma) * dt * s->a[k];
        }
        const double lam = load_factor(s, s->t + dt);
        c_apply(s, s->bn, s->rhs);
        if (beta == 0) {
            /* central difference: du = a_n, internal forces at n+1 first (eqs 19-20). The
             * node blocks first: the bond pass accepts the step (nothing may fail after it) */
            if (s->ablk_dt != dt || s->ablk_epoch != s->epoch) FLOE_TRY(build_ablk(s, dt));
            memcpy(s->du, s->an, (size_t)N * sizeof *s->du);
            FLOE_TRY(bond_pass(s, s->du, s->kd, NM_ACCEPT, &de));
            accepted = 1;
            FLOE_OMP(omp parallel for num_threads(ntv) schedule(static) if(ntv > 1))
            for (int k = 0; k < N; k++) s->rhs[k] = lam * s->F[k] - s->fint[k] - s->kd[k] - s->rhs[k];
            FLOE_TRY(solve_explicit(s, dt, s->rhs, s->anew));
            FLOE_OMP(omp parallel for num_threads(ntv) schedule(static) if(ntv > 1))
            for (int k = 0; k < N; k++) s->vnew[k] = s->bn[k] + gamma * dt * s->anew[k];
            break;
        }
#ifdef FLOE_HAVE_CHOLMOD
        /* eq 26 */
        FLOE_TRY(bond_pass(s, s->an, s->kd, NM_APPLY, NULL));
        for (int k = 0; k < N; k++) s->rhs[k] = lam * s->F[k] - s->fint[k] - s->kd[k] - s->rhs[k];
        FLOE_TRY(solve_implicit(s, dt, s->rhs, s->anew));
        for (int k = 0; k < N; k++) {
            s->du[k] = s->an[k] + beta * dt * dt * s->anew[k];
            s->vnew[k] = s->bn[k] + gamma * dt * s->anew[k];
        }
        FLOE_TRY(bond_pass(s, s->du, s->kd, NM_TRIAL, &de));
        /* line search (eqs 29-30): the fraction alpha of du at which the first bond reaches
         * its strength, and the step redone with dt sqrt(alpha); the steps are the levels
         * dt 2^(-k/2), searched by bisection between the longest step known to exceed the
         * strength and the shortest known to stay below (floe_newmark.h) */
        const double eps = s->def.line_search_eps;
        double rmax = 0, alpha = 1;
        for (int k = 0; k < s->nb; k++) {
            const nm_bond *b = &s->b[k];
            if (b->broken) continue;
            double r = bond_ratio(b, b->sig_tr, b->tau_tr);
            if (r > rmax) rmax = r;
            if (r > 1) {
                double r0 = bond_ratio(b, b->sigma, b->tau);
                double f = r > r0 ? (1 + 0.5 * fmax(eps, 0.0) - r0) / (r - r0) : 0;
                if (f < alpha) alpha = f;
            }
        }
        if (eps < 0 || final_trial || (rmax <= 1 + eps && (rmax >= 1 || cuts == 0))) break;
        if (rmax > 1 + eps) { k_over = level; dt_hi = dt; r_hi = rmax; }
        else { k_under = level; dt_lo = dt; r_lo = rmax; }
        int next = -1;
        double dt_next = 0;
        if (k_under < 0 && k_over >= 0 && dt_hi == level_dt(dt_full, k_over) && level < NM_LEVELS) {
            /* eq 30: dt sqrt(alpha), i.e. -log2(alpha) levels further (at least one) */
            double a = fmin(fmax(alpha, 1e-12), 1.0);
            next = level + (int)fmax(1.0, floor(-log2(a) + 0.5));
            if (next > NM_LEVELS) next = NM_LEVELS;
        } else if (k_under < 0) {
            break; /* the shortest level exceeds: its bonds break */
        } else if (cuts >= s->def.max_cuts || dt_hi < 1.02 * dt_lo) {
            /* no landing in [1, 1 + eps]: the shortest step known to exceed, its bonds break */
            if (dt == dt_hi) break;
            dt_next = dt_hi;
            final_trial = 1;
        } else if (k_under - k_over > 1 && dt_lo == level_dt(dt_full, k_under) && dt_hi == level_dt(dt_full, k_over)) {
            next = (k_over + k_under) / 2; /* bisection on the levels (their factors are kept) */
        } else {
            /* adjacent levels: log-linear interpolation of the stress ratio inside the bracket */
            double f = (1 + 0.5 * fmax(eps, 0.0) - r_lo) / (r_hi - r_lo);
            f = fmin(fmax(f, 0.1), 0.9);
            dt_next = exp(log(dt_lo) + f * (log(dt_hi) - log(dt_lo)));
        }
        if (next >= 0) {
            level = next;
            dt = level_dt(dt_full, level);
        } else {
            dt = dt_next;
        }
        cuts++;
        s->st.cuts++;
        continue;
#else
        (void)k_over; (void)k_under; (void)dt_lo; (void)dt_hi; (void)r_lo; (void)r_hi; (void)cuts; (void)final_trial;
        return nm_error(s, FLOE_ENOTSUP, "implicit Newmark needs CHOLMOD (FLOE_WITH_CHOLMOD=OFF)");
#endif
    }
    /* accept: work of the loads and of the dampers (trapezoid), then the state */
    const double lam0 = load_factor(s, s->t), lam1 = load_factor(s, s->t + dt);
    c_apply(s, s->v, s->cv0);
    c_apply(s, s->vnew, s->cv1);
    /* the state, with the step's sums per block of dofs (in block order: the same bits for
     * any thread count): the loads' and the dampers' work, the kinetic energy, and the
     * kinetic energy the loads can give a free dof in one step (the instability check) */
    double wext = 0, wdamp = 0, ke = 0, fsc = 0;
    {
        const int B = FLOE_PAR_BLOCK, nblk = (N + B - 1) / B;
        double *vs = s->vsum;
        FLOE_OMP(omp parallel for num_threads(ntv) schedule(static) if(ntv > 1))
        for (int blk = 0; blk < nblk; blk++) {
            const int k1 = (blk + 1) * B < N ? (blk + 1) * B : N;
            double we = 0, wd = 0, e = 0, fs = 0;
            int node = blk * B / nd, comp = blk * B % nd; /* k's node and component */
            for (int k = blk * B; k < k1; k++, comp = comp + 1 == nd ? 0 : comp + 1, node += comp == 0) {
                s->u[k] += s->du[k];
                s->v[k] = s->vnew[k];
                s->a[k] = s->anew[k];
                s->fint[k] += s->kd[k];
                const double m = node_m(s, node, comp);
                e += 0.5 * m * s->v[k] * s->v[k];
                if (s->eq[k] < 0) continue;
                we += 0.5 * (lam0 + lam1) * s->F[k] * s->du[k];
                wd += 0.5 * (s->cv0[k] + s->cv1[k]) * s->du[k];
                if (s->F[k] != 0) {
                    const double fk = lam1 * s->F[k] * dt;
                    fs += fk * fk / (2.0 * m);
                }
            }
            vs[4 * blk] = we; vs[4 * blk + 1] = wd; vs[4 * blk + 2] = e; vs[4 * blk + 3] = fs;
        }
        for (int blk = 0; blk < nblk; blk++) {
            wext += vs[4 * blk]; wdamp += vs[4 * blk + 1]; ke += vs[4 * blk + 2]; fsc += vs[4 * blk + 3];
        }
    }
    s->t += dt;
    s->st.steps++;
    s->st.work_external += wext;
    s->st.dissipated += wdamp;
    s->st.energy_elastic += de;
    /* breakage (eq 11): bonds at or beyond their strength (flagged by the accepting pass),
     * in bond order */
    if (!accepted) accept_pass(s);
    int broke = 0, *blist = NULL, nbrk = 0;
    for (int blk = 0; blk < (s->nb + FLOE_PAR_BLOCK - 1) / FLOE_PAR_BLOCK; blk++) nbrk += s->bbrk[blk];
    /* the list first: nothing fails once the bonds start breaking */
    if (nbrk && !(blist = malloc((size_t)nbrk * sizeof *blist))) return nm_error(s, FLOE_ENOMEM, "out of memory");
    for (int k = 0; k < s->nb; k++) {
        if (k % FLOE_PAR_BLOCK == 0 && !s->bbrk[k / FLOE_PAR_BLOCK]) {
            k += FLOE_PAR_BLOCK - 1; /* a block without a break */
            continue;
        }
        nm_bond *b = &s->b[k];
        if (b->broken) continue;
        if (s->bflag[k]) {
            /* released: its internal force leaves f_int, its energy is dissipated */
            add_global(s, b, b->fl, -1.0, s->fint);
            double eb = 0, ul[12];
            to_local(s, b, s->u, ul);
            for (int c = 0; c < 2 * nd; c++) eb += 0.5 * b->fl[c] * ul[c];
            /* the stored energy of a bond loaded from zero is f . u / 2 in its frame */
            s->st.energy_elastic -= eb;
            s->st.dissipated += eb;
            memset(b->fl, 0, sizeof b->fl);
            b->broken = 1;
            b->t_broken = s->t;
            s->st.broken++;
            if (s->st.t_first_break < 0) s->st.t_first_break = s->t;
            blist[broke++] = k;
        }
    }
    if (broke) {
        /* the factor for dt: a rank downdate keeps it (implicit), unless asked to refactor */
#ifdef FLOE_HAVE_CHOLMOD
        int keep[NM_SLOTS] = {0};
        for (int slot = 0; slot < NM_SLOTS; slot++)
            if (beta > 0 && !s->def.refactor_on_break && s->L[slot] && s->Lepoch[slot] == s->epoch &&
                s->since_refactor[slot] + broke <= 256) {
                int rc = downdate_bonds(s, slot, blist, broke);
                if (rc) { free(blist); return rc; }
                keep[slot] = 1;
            }
#endif
        s->epoch++;
#ifdef FLOE_HAVE_CHOLMOD
        for (int slot = 0; slot < NM_SLOTS; slot++)
            if (keep[slot]) s->Lepoch[slot] = s->epoch;
#endif
        /* the node blocks of C hold the bonds' dampers; without them (damping_ratio 0) C is
         * alpha M and the explicit blocks of M + gamma dt C stay as they are */
        if (s->def.damping_ratio > 0) build_cblk(s);
        else if (s->ablk_epoch == s->epoch - 1) s->ablk_epoch = s->epoch;
    }
    free(blist);
    /* the next step: the same level while bonds break, twice as long after a quiet step */
    if (dt != level_dt(dt_full, level) && k_under >= 0) level = k_under; /* off the ladder: the level below */
    s->level = broke ? level : (level >= 2 ? level - 2 : 0);
    s->st.energy_kinetic = ke;
    double e = s->st.energy_kinetic + s->st.energy_elastic;
    /* what the energy may reach: what was put in, plus what the loads can give a free node
     * in one step (the explicit scheme books the work one step after the velocity) */
    double scale = fabs(s->st.energy_initial) + fabs(s->st.work_external) + fabs(s->st.dissipated) + fsc;
    if (!isfinite(e) || e > 100.0 * scale + 1e-300) {
        double dtc = floe_newmark_critical_dt(s);
        return nm_error(s, FLOE_EUNSTABLE,
                        "Newmark (beta %g) unstable at step %ld, t = %g s: energy %.3g J grew beyond 100 x the energy "
                        "put in (%.3g J); dt %g s, critical step of the explicit scheme %g s",
                        beta, s->st.steps, s->t, e, scale, dt, dtc);
    }
    return FLOE_OK;
}

int floe_newmark_step(floe_newmark *s) {
    FLOE_TRY(floe_newmark_prepare(s));
    return do_step(s, s->def.dt);
}

int floe_newmark_run(floe_newmark *s, double t_end) {
    FLOE_TRY(floe_newmark_prepare(s));
    while (s->t < t_end - 1e-9 * s->def.dt) {
        double dt = fmin(s->def.dt, t_end - s->t);
        if (dt > 0.999999 * s->def.dt) dt = s->def.dt;
        FLOE_TRY(do_step(s, dt));
    }
    return FLOE_OK;
}
