/* law_kernels.h - the built-in laws' force kernels on one contact (hertz_mindlin.c,
 * linear_law.c), from the parts in law_parts.h. The world's sphere batches
 * (core/world/forces.c, sph_flush_lanes) call those parts' lane forms directly, over 16
 * contacts at a time: one copy of each formula for both. */
#ifndef FLOE_LAW_KERNELS_H
#define FLOE_LAW_KERNELS_H

#include "law_parts.h"


/* Each kernel in its two stages, the normal force (floe_hertz_normal, floe_linear_normal_k)
 * and then the rest (floe_hm_kernel_t, floe_linear_kernel_t: the tangential force, the total
 * force and energy). */

/* Hertz-Mindlin (hertz_mindlin.c) on a contact whose depth > 0, n, vn, vt, r_eff and m_eff
 * (finite, > 0), dt and fn_extra are set: the force on i into F, the stored energy into
 * *energy and the losses of this evaluation into *diss; hist[0..2], the tangential spring,
 * advanced. Returns the normal force Fn. */
static inline __attribute__((always_inline)) void floe_hm_kernel_t(const floe_hertz_mindlin_law *H,
                                                                    const floe_contact *c,
                                                                    const floe_normal_force *nf, double *hist,
                                                                    double F[3], double *energy, double *diss) {
    double Ft[3];
    *energy = nf->energy;
    *diss = nf->diss;
    floe_mindlin_tangential(H->g_star, H->tangent_damping_ratio, H->mu, c, nf, hist, Ft, energy, diss);
    for (int k = 0; k < 3; ++k) F[k] = -nf->fn * c->n[k] + Ft[k];
}

static inline __attribute__((always_inline)) double floe_hm_kernel(const floe_hertz_mindlin_law *H,
                                                                    const floe_contact *c, double *hist,
                                                                    double F[3], double *energy, double *diss) {
    floe_normal_force nf;
    floe_hertz_normal(H->e_star, H->damping_ratio, c, &nf);
    floe_hm_kernel_t(H, c, &nf, hist, F, energy, diss);
    return nf.fn;
}

/* The linear (viscoelastic) law (linear_law.c) on a contact whose depth > 0, n, vn, vt,
 * m_eff, dt, an_ext and fn_extra are set: as floe_hm_kernel; hist[0..2] is the shear spring's
 * elongation, hist[3] the dashpot's phase. Returns the normal force Fn. */
static inline __attribute__((always_inline)) void floe_linear_kernel_t(const floe_linear_law *L,
                                                                        const floe_contact *c,
                                                                        const floe_normal_force *nf, double *hist,
                                                                        double F[3], double *energy, double *diss) {
    const double Fn = nf->fn;
    double d = nf->diss, Ft[3];
    floe_coulomb_k(c, L->ks, L->gs, L->mu, fabs(Fn) + c->fn_extra, hist, Ft, &d);
    for (int k = 0; k < 3; ++k) F[k] = -Fn * c->n[k] + Ft[k];
    *energy = nf->energy + 0.5 * L->ks * floe_v3_dot(hist, hist);
    *diss = d;
}

static inline __attribute__((always_inline)) double floe_linear_kernel(const floe_linear_law *L, const floe_contact *c,
                                                                        double *hist, double F[3], double *energy,
                                                                        double *diss) {
    floe_normal_force nf;
    floe_linear_normal_k(L->kn, L->gn, L->tension, c, hist, &nf);
    floe_linear_kernel_t(L, c, &nf, hist, F, energy, diss);
    return nf.fn;
}

#endif
