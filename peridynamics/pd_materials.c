/* pd_materials.c - PD material vtables: PMB bond-based (000 eqs 9-12, 003 eqs 2-5) and the
 * linear peridynamic solid (000 eqs 15-25, ParticLS eqs 30-35). One pass per bond (each bond
 * is stored once, i < j); forces are applied to both ends. */
#include <float.h>
#include <stdlib.h>

#include "floe_pd.h"

/* ---------------------------------------------------------------- PMB ---- */

static void free_lps(floe_pd_body *b)
{
    free(b->m);
    free(b->theta);
    free(b->wbond);
    b->m = b->theta = b->wbond = NULL;
}

/* Micromodulus: 3D c = 18K/(pi delta^4) (000 eq 10; equals 003 eq 3 at nu = 1/4);
 * 2D plane stress c = 9E/(pi h delta^3) (nu = 1/3), plane strain c = 48E/(5 pi h delta^3)
 * (nu = 1/4) (Bobaru et al. 2009; Ha & Bobaru 2010), h the thickness. 000 gives only the 3D
 * constant. */
static int pmb_init(floe_pd_body *b)
{
    const floe_pd_material *m = &b->mat;
    double c = m->c;
    if (!(c >= 0) || !(m->alpha >= 0) || !isfinite(m->alpha)) return FLOE_EINVAL;
    if (c == 0) {
        double d = b->delta;
        if (b->dim == 3) {
            if (!(m->K > 0)) return FLOE_EINVAL;
            c = 18.0 * m->K / (M_PI * d * d * d * d);
        } else {
            if (!(m->E > 0)) return FLOE_EINVAL;
            double h = b->thickness;
            c = m->plane == FLOE_PD_PLANE_STRAIN ? 48.0 * m->E / (5.0 * M_PI * h * d * d * d)
                                                 : 9.0 * m->E / (M_PI * h * d * d * d);
        }
    }
    /* per-point critical stretch (alpha > 0): s0 starts at DBL_MAX, as in LAMMPS, so no bond
     * breaks before the first evaluation has measured the stretches */
    if (m->alpha > 0) {
        if (!b->s0) {
            b->s0 = malloc(2 * (size_t)(b->n > 0 ? b->n : 1) * sizeof *b->s0);
            if (!b->s0) return FLOE_ENOMEM;
        }
        for (int i = 0; i < b->n; i++) b->s0[i] = DBL_MAX;
    } else {
        free(b->s0);
        b->s0 = NULL;
    }
    b->c = c;
    free_lps(b);
    return FLOE_OK;
}

static double pmb_c(const floe_pd_body *b) { return b->c; }

/* 000 eqs 9-12 / 003 eq 2: pair force c s mu beta V_i V_j along the deformed bond, with
 * s = (|y| - |xi|)/|xi| (003 eq 4). A bond breaks when s > s_c and stays broken; a broken
 * bond still pushes in compression when broken_tension_only is set (003: mu = 1 for s <= 0).
 * Energy per bond: 1/2 c s^2 |xi| beta V_i V_j, whose gradient is the force above.
 *
 * With alpha > 0 (LAMMPS pair peri/pmb, Parks et al. 2008) the critical stretch of bond
 * (i, j) is min(s0_i, s0_j) with s0 from the previous evaluation, and this evaluation builds
 * s0_i = s00 - alpha min_j s_ij = max_j (s00 - alpha s_ij) over i's bonds intact at its start
 * (a bond breaking now still counts, as in LAMMPS; a point without intact bonds gets
 * DBL_MAX), s00 = s_c. Also as in LAMMPS, a bond that breaks in this evaluation still
 * carries its force (and energy) in it; the constant-s_c rule drops it at once. (Measured on
 * the pd-impact benchmark: with this order floe's damage follows LAMMPS' within 2.4 % at
 * every 100 steps; without it 8-11 % off.) Without breakage (s_c = 0,
 * floe_pd_forces_nobreak) s0 is left as is.
 * `alpha_on` is a constant at both call sites, so the compiler drops the branch from the
 * constant-s_c loop. */
static inline double pmb_forces_impl(floe_pd_body *b, const double *x, double *f, const int alpha_on)
{
    const double c = b->c, s_c = b->s_c, alpha = b->mat.alpha;
    const int comp = b->mat.broken_tension_only;
    const double *V = b->V;
    const int32_t *part = b->partner;
    const double *len = b->len;
    const float *vfac = b->vfac, *scorr = b->scorr;
    uint8_t *brk = b->broken;
    const double *s0 = alpha_on ? b->s0 : NULL;
    double *s0n = alpha_on ? b->s0 + b->n : NULL;
    if (alpha_on)
        for (int i = 0; i < b->n; i++) s0n[i] = -INFINITY;
    double energy = 0.0;
    int64_t nbroken = 0;
    for (int i = 0; i < b->n; i++) {
        const double xi0 = x[3 * (size_t)i], xi1 = x[3 * (size_t)i + 1], xi2 = x[3 * (size_t)i + 2];
        const double Vi = V[i];
        const double s0i = alpha_on ? s0[i] : 0.0;
        double s0ni = alpha_on ? s0n[i] : 0.0;
        double fi0 = 0, fi1 = 0, fi2 = 0, ei = 0;
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            const int j = part[k];
            const double *xj = x + 3 * (size_t)j;
            double d0 = xj[0] - xi0, d1 = xj[1] - xi1, d2 = xj[2] - xi2;
            double r = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
            double L = len[k];
            double s = (r - L) / L;
            if (brk[k]) {
                if (!comp || s >= 0) continue;
            } else {
                double sck = s_c;
                if (alpha_on) {
                    double t = s_c - alpha * s;
                    if (t > s0ni) s0ni = t;
                    if (t > s0n[j]) s0n[j] = t;
                    sck = s0i < s0[j] ? s0i : s0[j];
                }
                if (s_c > 0 && s > sck) {
                    brk[k] = 1;
                    nbroken++;
                    /* LAMMPS' order with alpha: the bond's force of this evaluation is applied,
                     * then it breaks */
                    if ((!comp || s >= 0) && !alpha_on) continue;
                }
            }
            if (!(r > 0)) continue;
            double w = (double)vfac[k] * (scorr ? (double)scorr[k] : 1.0) * Vi * V[j];
            double fm = c * s * w / r;
            ei += 0.5 * c * s * s * L * w;
            double g0 = fm * d0, g1 = fm * d1, g2 = fm * d2;
            fi0 += g0; fi1 += g1; fi2 += g2;
            double *fj = f + 3 * (size_t)j;
            fj[0] -= g0; fj[1] -= g1; fj[2] -= g2;
        }
        if (alpha_on) s0n[i] = s0ni;
        f[3 * (size_t)i] += fi0;
        f[3 * (size_t)i + 1] += fi1;
        f[3 * (size_t)i + 2] += fi2;
        energy += ei;
    }
    if (alpha_on)
        for (int i = 0; i < b->n; i++) b->s0[i] = s0n[i] == -INFINITY ? DBL_MAX : s0n[i];
    b->nbroken += nbroken;
    return energy;
}

static double pmb_forces(floe_pd_body *b, const double *x, double *f)
{
    if (b->s0 && b->s_c > 0) return pmb_forces_impl(b, x, f, 1);
    return pmb_forces_impl(b, x, f, 0);
}

const floe_pd_material_ops floe_pd_pmb_ops = {"pmb", pmb_init, pmb_forces, pmb_c};

/* ---------------------------------------------------------------- LPS ---- */

/* Weighted volume m_i = sum_j w |xi|^2 beta V_j (000 eq 19, ParticLS eq 31), fixed in the
 * reference configuration (broken bonds keep counting in m, as in Peridigm). Influence
 * w = 1 or exp(-|xi|^2/delta^2) (ParticLS eq 33). 3D only for now. */
static int lps_init(floe_pd_body *b)
{
    const floe_pd_material *m = &b->mat;
    if (b->dim != 3) return FLOE_ENOTSUP;
    if (!(m->K > 0) || !(m->G > 0) || m->alpha != 0) return FLOE_EINVAL;
    if (m->influence != FLOE_PD_W_ONE && m->influence != FLOE_PD_W_GAUSS) return FLOE_EINVAL;
    size_t n = (size_t)(b->n > 0 ? b->n : 1), nb = (size_t)(b->nbond > 0 ? b->nbond : 1);
    double *mm = calloc(n, sizeof *mm), *th = calloc(n, sizeof *th), *w = NULL;
    if (m->influence == FLOE_PD_W_GAUSS) w = malloc(nb * sizeof *w);
    if (!mm || !th || (m->influence == FLOE_PD_W_GAUSS && !w)) {
        free(mm); free(th); free(w);
        return FLOE_ENOMEM;
    }
    double d2 = b->delta * b->delta;
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            double L = b->len[k];
            double wk = 1.0;
            if (w) wk = w[k] = exp(-L * L / d2);
            double a = wk * L * L * b->vfac[k];
            mm[i] += a * b->V[j];
            mm[j] += a * b->V[i];
        }
    free_lps(b);
    free(b->s0); /* PMB alpha state */
    b->s0 = NULL;
    b->m = mm;
    b->theta = th;
    b->wbond = w;
    /* the equivalent PMB c (for s_c from G_c and the time step) */
    double Keq = (m->K + 4.0 / 3.0 * m->G) / 1.8;
    double d = b->delta;
    b->c = 18.0 * Keq / (M_PI * d * d * d * d);
    return FLOE_OK;
}

static double lps_c(const floe_pd_body *b) { return b->c; }

/* 000 eqs 18-25 / ParticLS eqs 30-35:
 *   e = |y| - |xi|, theta_i = 3/m_i sum_j w |xi| e beta V_j,
 *   e^d = e - theta_i |xi|/3, t_ij = 3 K theta_i w |xi| / m_i + alpha_i w e^d,
 *   alpha_i = 15 G / m_i, force on i: sum_j (t_ij + t_ji) beta V_i V_j M (000 eq 14);
 * energy sum_i V_i (K theta_i^2/2 + alpha_i/2 sum_j w (e^d_ij)^2 beta V_j) (000 eq 24).
 * Broken bonds (stretch e/|xi| > s_c, checked in the first pass) drop out of theta and t. */
static double lps_forces(floe_pd_body *b, const double *x, double *f)
{
    const int n = b->n;
    const double K = b->mat.K, G = b->mat.G, s_c = b->s_c;
    const double *V = b->V, *len = b->len, *wb = b->wbond, *m = b->m, *ac = b->acorr;
    const float *vfac = b->vfac;
    const int32_t *part = b->partner;
    uint8_t *brk = b->broken;
    double *th = b->theta;
    int64_t nbroken = 0;
    for (int i = 0; i < n; i++) th[i] = 0;
    /* pass 1: dilatation, breakage */
    for (int i = 0; i < n; i++) {
        const double *xi = x + 3 * (size_t)i;
        double ti = 0;
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            if (brk[k]) continue;
            const int j = part[k];
            const double *xj = x + 3 * (size_t)j;
            double d0 = xj[0] - xi[0], d1 = xj[1] - xi[1], d2 = xj[2] - xi[2];
            double L = len[k];
            double e = sqrt(d0 * d0 + d1 * d1 + d2 * d2) - L;
            if (s_c > 0 && e > s_c * L) {
                brk[k] = 1;
                nbroken++;
                continue;
            }
            double a = (wb ? wb[k] : 1.0) * L * e * (double)vfac[k];
            ti += a * V[j];
            th[j] += a * V[i];
        }
        th[i] += ti;
    }
    for (int i = 0; i < n; i++) th[i] = m[i] > 0 ? 3.0 * th[i] / m[i] : 0.0;
    /* pass 2: forces and energy */
    double energy = 0.0;
    for (int i = 0; i < n; i++) {
        const double xi0 = x[3 * (size_t)i], xi1 = x[3 * (size_t)i + 1], xi2 = x[3 * (size_t)i + 2];
        const double Vi = V[i], thi = th[i];
        const double mi = m[i] > 0 ? m[i] : 1.0;
        const double ki = 3.0 * K * thi / mi, ai = 15.0 * G / mi * (ac ? ac[i] : 1.0);
        double fi0 = 0, fi1 = 0, fi2 = 0, ei = 0.5 * K * thi * thi * Vi;
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            if (brk[k]) continue;
            const int j = part[k];
            const double *xj = x + 3 * (size_t)j;
            double d0 = xj[0] - xi0, d1 = xj[1] - xi1, d2 = xj[2] - xi2;
            double r = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
            double L = len[k], e = r - L;
            double w = wb ? wb[k] : 1.0;
            double mj = m[j] > 0 ? m[j] : 1.0;
            double edi = e - thi * L / 3.0, edj = e - th[j] * L / 3.0;
            double aj = 15.0 * G / mj * (ac ? ac[j] : 1.0);
            double tij = ki * w * L + ai * w * edi;
            double tji = 3.0 * K * th[j] / mj * w * L + aj * w * edj;
            double bv = (double)vfac[k] * Vi * V[j];
            ei += 0.5 * w * bv * (ai * edi * edi + aj * edj * edj);
            if (!(r > 0)) continue;
            double fm = (tij + tji) * bv / r;
            double g0 = fm * d0, g1 = fm * d1, g2 = fm * d2;
            fi0 += g0; fi1 += g1; fi2 += g2;
            double *fj = f + 3 * (size_t)j;
            fj[0] -= g0; fj[1] -= g1; fj[2] -= g2;
        }
        f[3 * (size_t)i] += fi0;
        f[3 * (size_t)i + 1] += fi1;
        f[3 * (size_t)i + 2] += fi2;
        /* theta_j's K theta^2/2 V_j term is added when the loop reaches j */
        energy += ei;
    }
    b->nbroken += nbroken;
    return energy;
}

const floe_pd_material_ops floe_pd_lps_ops = {"lps", lps_init, lps_forces, lps_c};

/* ------------------------------------------------------- bond visitor ---- */
int floe_pd_bond_forces(floe_pd_body *b, const double *x, floe_pd_bond_visit_fn fn, void *user)
{
    if (!b || !b->ops || !x || !fn) return FLOE_EINVAL;
    const int lps = b->mat.model == FLOE_PD_LPS;
    double *th = b->theta;
    if (lps) {
        for (int i = 0; i < b->n; i++) th[i] = 0;
        for (int i = 0; i < b->n; i++)
            for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
                if (b->broken[k]) continue;
                int j = b->partner[k];
                double d[3];
                floe_v3_sub(d, x + 3 * (size_t)j, x + 3 * (size_t)i);
                double L = b->len[k], e = floe_v3_norm(d) - L;
                double a = (b->wbond ? b->wbond[k] : 1.0) * L * e * (double)b->vfac[k];
                th[i] += a * b->V[j];
                th[j] += a * b->V[i];
            }
        for (int i = 0; i < b->n; i++) th[i] = b->m[i] > 0 ? 3.0 * th[i] / b->m[i] : 0.0;
    }
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            double d[3];
            floe_v3_sub(d, x + 3 * (size_t)j, x + 3 * (size_t)i);
            double r = floe_v3_norm(d), L = b->len[k], s = (r - L) / L;
            if (b->broken[k] && (lps || !b->mat.broken_tension_only || s >= 0)) continue;
            if (!(r > 0)) continue;
            double bv = (double)b->vfac[k] * b->V[i] * b->V[j], fm;
            if (!lps) {
                fm = b->c * s * bv * (b->scorr ? (double)b->scorr[k] : 1.0);
            } else {
                double w = b->wbond ? b->wbond[k] : 1.0, e = r - L;
                double mi = b->m[i] > 0 ? b->m[i] : 1.0, mj = b->m[j] > 0 ? b->m[j] : 1.0;
                double ai = 15.0 * b->mat.G / mi * (b->acorr ? b->acorr[i] : 1.0);
                double aj = 15.0 * b->mat.G / mj * (b->acorr ? b->acorr[j] : 1.0);
                double tij = 3.0 * b->mat.K * th[i] / mi * w * L + ai * w * (e - th[i] * L / 3.0);
                double tji = 3.0 * b->mat.K * th[j] / mj * w * L + aj * w * (e - th[j] * L / 3.0);
                fm = (tij + tji) * bv;
            }
            double f[3] = {fm * d[0] / r, fm * d[1] / r, fm * d[2] / r};
            fn(i, j, k, f, user);
        }
    return FLOE_OK;
}
