/* law_parts.h - the normal and tangential kernels that the built-in laws and the composed
 * law's parts share (contact/laws only; internal): one copy of each formula, inlined into
 * the fused laws (hertz_mindlin, linear) so that the sphere path pays no call per part. */
#ifndef FLOE_LAW_PARTS_H
#define FLOE_LAW_PARTS_H

#include "floe_contact.h"


#define FLOE_HM_DAMP_PREF 1.8257418583505538 /* 2 sqrt(5/6) */

/* Hertz normal force with the restitution-calibrated dashpot (003 eqs 15-21, 000 eq 36):
 * Sn = 2 E* sqrt(R* d), Fel = 2/3 Sn d, gn = 2 sqrt(5/6) beta sqrt(Sn m*), Fn = max(Fel +
 * gn vn, 0), stored energy 2/5 Fel d. Depth > 0, R*, m* > 0 finite (the caller checks). */
static inline void floe_hertz_normal(double e_star, double beta, const floe_contact *c, floe_normal_force *o) {
    const double d = c->depth, vn = c->vn;
    const double a = sqrt(c->r_eff * d);
    const double Sn = 2.0 * e_star * a;
    const double fel = (2.0 / 3.0) * Sn * d; /* 4/3 E* sqrt(R* d) d */
    const double gn = FLOE_HM_DAMP_PREF * beta * sqrt(Sn * c->m_eff);
    double Fn = fel + gn * vn;
    if (Fn < 0.0) Fn = 0.0;
    o->fn = Fn;
    o->fel = fel;
    o->kn = Sn;
    o->gn = gn;
    o->diss = (Fn - fel) * vn * c->dt;
    o->energy = 0.4 * fel * d;
}

/* Mindlin tangential spring kt = 8 G* sqrt(R* d) on the stored force Fs (history[0..2],
 * rotated with the contact frame), dashpot gt = gn sqrt(4 G* / E*) (tdr) from the normal
 * dashpot, Coulomb limit mu (Fn + fn_extra); adds the spring energy |Fs|^2 / (2 kt) to
 * *energy and the dashpot and slip losses to *diss. */
static inline void floe_mindlin_tangential(double g_star, double tdr, double mu, const floe_contact *c,
                                           const floe_normal_force *nf, double *Fs, double Ft[3], double *energy,
                                           double *diss) {
    const double dt = c->dt;
    const double kt = 8.0 * g_star * sqrt(c->r_eff * c->depth);
    const double gt = nf->gn * tdr; /* sqrt(kt m) = sqrt(Sn m) sqrt(4 G* / E*) */
    const double vt[3] = {c->vt[0], c->vt[1], c->vt[2]};
    /* the stored force in registers, written back once: updated in place in the history, its
     * element stores were read back by a vector load (a store-forwarding stall per contact) */
    double S[3] = {Fs[0], Fs[1], Fs[2]};
    floe_contact_rotate_history(S, c->n);
    floe_v3_axpy(S, -kt * dt, vt);
    for (int k = 0; k < 3; ++k) Ft[k] = S[k] - gt * vt[k];
    const double vt2 = floe_v3_dot(vt, vt);
    const double limit = mu * (nf->fn + c->fn_extra); /* + the manifold's other springs */
    const double ft2 = floe_v3_dot(Ft, Ft);
    *diss += gt * vt2 * dt;
    const double half_inv_kt = 0.5 / kt;
    if (ft2 > limit * limit) {
        const double ftmag = sqrt(ft2);
        const double e_before = floe_v3_dot(S, S) * half_inv_kt;
        floe_v3_scale(Ft, limit / ftmag);
        for (int k = 0; k < 3; ++k) S[k] = Ft[k] + gt * vt[k];
        *diss += e_before - floe_v3_dot(S, S) * half_inv_kt;
    }
    *energy += floe_v3_dot(S, S) * half_inv_kt;
    Fs[0] = S[0]; Fs[1] = S[1]; Fs[2] = S[2];
}

/* Linear spring-dashpot normal force kn d + gn vn with the onset/release treatment of the
 * dashpot (history[3]; linear_law.c), clamped at 0 unless tension. */
void floe_linear_normal(double kn, double gn, int tension, const floe_contact *c, double *hist, floe_normal_force *o);

/* The Hertz-Mindlin moduli of two materials: E*, G* and sqrt(4 G* / E*); 0 when a material
 * lacks young > 0 or poisson in (-1, 0.5]. */
int floe_hertz_moduli(const floe_material *a, const floe_material *b, double *e_star, double *g_star, double *tdr);

#endif
