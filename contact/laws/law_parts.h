/* law_parts.h - the normal and tangential kernels that the built-in laws and the composed
 * law's parts share (contact/laws only; internal): one copy of each formula, inlined into
 * the fused laws (hertz_mindlin, linear) so that the sphere path pays no call per part. */
#ifndef FLOE_LAW_PARTS_H
#define FLOE_LAW_PARTS_H

#include "floe_contact.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* x < 0 ? 0 : x, with NaN and -0 kept (MAXSD returns its second operand for a NaN or two
 * zeros) */
static inline double floe_clamp0(double x) {
#if defined(__SSE2__)
    return _mm_cvtsd_f64(_mm_max_sd(_mm_setzero_pd(), _mm_set_sd(x)));
#else
    return x < 0.0 ? 0.0 : x;
#endif
}

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
    const double Fn = floe_clamp0(fel + gn * vn);
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
    /* sliding or not without a branch (as floe_coulomb_k: the branches' values selected) */
    const int slip = ft2 > limit * limit;
    const double ftmag = sqrt(ft2), e_before = floe_v3_dot(S, S) * half_inv_kt, sc = limit / ftmag;
    double Fl[3], Ss[3];
    for (int k = 0; k < 3; ++k) Fl[k] = Ft[k] * sc;
    for (int k = 0; k < 3; ++k) Ss[k] = Fl[k] + gt * vt[k];
    const double dslip = e_before - floe_v3_dot(Ss, Ss) * half_inv_kt;
    for (int k = 0; k < 3; ++k) {
        Ft[k] = slip ? Fl[k] : Ft[k];
        S[k] = slip ? Ss[k] : S[k];
    }
    *diss = slip ? *diss + dslip : *diss;
    *energy += floe_v3_dot(S, S) * half_inv_kt;
    Fs[0] = S[0]; Fs[1] = S[1]; Fs[2] = S[2];
}

/* Coulomb friction with a shear spring (ParticLS eqs 17-18), in two parts that a batch of
 * contacts can run apart (law_kernels.h floe_linear_kernel_batch): the trial, the spring s
 * advanced and the force it and the dashpot give, with the Coulomb limit mu |Fn| and |Ft|^2;
 * then, for a contact that slips (|Ft| > limit), the force onto the limit and the spring to
 * match (minus_inv_ks = -1 / ks; no spring: s = 0). */
static inline __attribute__((always_inline)) void floe_coulomb_trial(const floe_contact *c, double ks, double gs,
                                                                      double mu, double Fn, double *s, double Ft[3],
                                                                      double *limit, double *ft2) {
    floe_contact_rotate_history(s, c->n);
    floe_v3_axpy(s, c->dt, c->vt);
    floe_v3_set(Ft, 0.0, 0.0, 0.0);
    floe_v3_axpy(Ft, -ks, s);
    floe_v3_axpy(Ft, -gs, c->vt);
    *limit = mu * fabs(Fn);
    *ft2 = floe_v3_dot(Ft, Ft);
}

static inline __attribute__((always_inline)) void floe_coulomb_slip(const double vt[3], double ks, double gs,
                                                                     double minus_inv_ks, double ratio,
                                                                     const double Ft[3], double Fs[3], double ss[3]) {
    for (int k = 0; k < 3; ++k) Fs[k] = Ft[k] * ratio;
    if (ks > 0.0)
        for (int k = 0; k < 3; ++k) ss[k] = (Fs[k] + gs * vt[k]) * minus_inv_ks;
    else
        floe_v3_set(ss, 0.0, 0.0, 0.0);
}

/* The two parts on one contact: see floe_contact.h and the linear law's header comment
 * (linear_law.c) for the steps and the energy bookkeeping. */
static inline __attribute__((always_inline)) void floe_coulomb_k(const floe_contact *c, double ks, double gs, double mu,
                                                                  double Fn, double *s, double Ft[3], double *diss)
{
    const double dt = c->dt;
    double limit, ft2;
    floe_coulomb_trial(c, ks, gs, mu, Fn, s, Ft, &limit, &ft2);
    const double vt2 = floe_v3_dot(c->vt, c->vt);
    /* sliding or not, without a branch: in a dense bed contacts stick and slip at random, and
     * a mispredicted branch per contact cost more than the slip's arithmetic done always (the
     * values selected are those of the branches, so the same bits) */
    const int slip = ft2 > limit * limit;
    const double ratio = limit / sqrt(ft2); /* read only when slipping: ft2 > 0 then */
    double Fs[3], ss[3], dslip;
    floe_coulomb_slip(c->vt, ks, gs, ks > 0.0 ? -1.0 / ks : 0.0, ratio, Ft, Fs, ss);
    if (ks > 0.0) {
        const double e_before = 0.5 * ks * floe_v3_dot(s, s);
        dslip = gs * vt2 * dt + (e_before - 0.5 * ks * floe_v3_dot(ss, ss));
    } else {
        dslip = ratio * gs * vt2 * dt;
    }
    for (int k = 0; k < 3; ++k) {
        Ft[k] = slip ? Fs[k] : Ft[k];
        s[k] = slip ? ss[k] : s[k];
    }
    *diss += slip ? dslip : gs * vt2 * dt;
}

/* the other forces' rate of change of vn (floe_contact.an_ext); 0 at dt = 0 (prepare,
 * refresh: the dashpot sees vn itself) and when not finite */
static inline double floe_linear_an_ext(const floe_contact *c) {
    return c->dt > 0.0 && isfinite(c->an_ext) ? c->an_ext : 0.0;
}

/* Onset and release of the dashpot (issue 10 B). The dashpot force jumps by gn vn when
 * the contact begins and (with tension) when it ends, inside a step. Velocity Verlet
 * applies each force evaluation over [t - dt/2, t + dt/2] (two half kicks), so the impulse
 * of the jump depends on where in the step it happens: a first-order error in dt that made
 * e range over 0.288..0.301 at e = 0.3 and the default step, by onset phase. The first
 * evaluation of a contact (history[3] == 0), which began tau = d / vn before it (tau <= dt),
 * scales the dashpot by (dt/2 + tau) / dt, its true window [t - tau, t + dt/2]; with
 * tension, an evaluation after which the overlap reaches 0 within tau_r = d / -v_{n+3/2}
 * < dt (the last one) scales it by (dt/2 + tau_r) / dt, and when the contact goes on all
 * the same (the prediction missed by the change of force), the next evaluation leaves out
 * the part already covered (history[3] - 1). Without tension the force reaches 0
 * continuously at kn d + gn vn = 0 (no jump at the end). Returns the factor (1 inside).
 * The velocity. The law sees the mid-step velocity v_{n+1/2} (the positions are at t_{n+1},
 * the closing half kick comes after the forces), which lags the dashpot by half a step: a
 * bias of first order in zeta w dt (e 0.0959 for 0.1 at the default step). The normal
 * dashpot takes the velocity at t_{n+1} instead, v_{n+1} = v_{n+1/2} + (dt/2) (a_ext - Fn/m*):
 * the closing half kick of the pair's normal motion, with this contact's new force solved
 * with it and the other forces' part a_ext = c->an_ext from the last evaluation (the world's
 * accelerations less this contact's last force, core/world/forces.c):
 *     Fn = (kn d + gn (vn + a_ext dt/2)) / (1 + gn dt / (2 m*)).
 * Two bodies alone (a_ext = 0): exact for the pair's normal motion under velocity Verlet.
 * A contact at rest held by others (a_ext = Fn_last / m*): Fn = kn d exactly, where
 * a_ext = 0 would give kn d / (1 + gn dt / (2 m*)), a static stiffness too low by
 * zeta w dt (issue 10 B's form before; 2.2-4.3 % in tests/test_dashpot_static.c, about
 * 14 % estimated for the ParticLS §5.3 RVE). Lagging the whole acceleration instead (this contact's own force
 * too) is unstable from 0.6-0.8 of the critical step (a chain of 20 masses: spectral radius
 * 2.1 at the critical step, zeta 0.3); the implicit own term keeps it stable up to it. */
static inline double floe_linear_dashpot_phase(double kn, double gn, int tension, const floe_contact *c, double *hist, double hm)
{
    const double d = c->depth, vn = c->vn, dt = c->dt;
    if (!(dt > 0.0)) return 1.0; /* prepare: nothing advances */
    if (hist[3] == 0.0) { /* first evaluation: the contact began d / vn ago */
        hist[3] = 1.0;
        if (!(vn > 0.0 && d <= 2.0 * vn * dt)) return 1.0;
        const double r = d / (vn * dt);
        return 0.5 + (r < 1.0 ? r : 1.0); /* fmin(r, 1), without the library call */
    }
    /* the part of this evaluation's window that the previous one already covered, when it
     * took itself for the last one and the contact went on */
    const double covered = hist[3] - 1.0;
    double f = 1.0;
    hist[3] = 1.0;
    if (tension && vn < 0.0) {
        /* the overlap's rate over the next drift: v_{n+3/2} = v_{n+1/2} + dt (a_ext - Fn / m*) */
        const double ae = floe_linear_an_ext(c);
        const double fn = (kn * d + gn * (vn + 0.5 * dt * ae)) / (1.0 + gn * hm), vnext = vn + dt * ae - 2.0 * hm * fn;
        if (vnext < 0.0 && d < -vnext * dt) {
            f = 0.5 + d / (-vnext * dt);
            hist[3] = 1.0 + (f - 1.0 > 0.0 ? f - 1.0 : 0.0);
        }
    }
    return f - covered > 0.0 ? f - covered : 0.0; /* fmax(., 0) (NaN: 0), inline */
}

static inline __attribute__((always_inline)) void floe_linear_normal_k(double kn, double gn, int tension,
                                                                  const floe_contact *c, double *hist,
                                                                  floe_normal_force *o)
{
    const double d = c->depth, vn = c->vn, dt = c->dt;
    const double fel = kn * d;
    /* the dashpot at the velocity of the step's end (floe_linear_dashpot_phase) */
    const double hm = c->m_eff > 0.0 && isfinite(c->m_eff) ? 0.5 * dt / c->m_eff : 0.0;
    const double gph = gn * floe_linear_dashpot_phase(kn, gn, tension, c, hist, hm);
    double Fn = (fel + gph * (vn + 0.5 * dt * floe_linear_an_ext(c))) / (1.0 + gph * hm);
    if (!tension) Fn = floe_clamp0(Fn);
    o->fn = Fn;
    o->fel = fel;
    o->kn = kn;
    o->gn = gn;
    o->diss = (Fn - fel) * vn * dt; /* damping force actually applied times vn dt */
    o->energy = 0.5 * kn * d * d;
}

/* Linear spring-dashpot normal force kn d + gn vn with the onset/release treatment of the
 * dashpot (history[3]; linear_law.c), clamped at 0 unless tension. */
void floe_linear_normal(double kn, double gn, int tension, const floe_contact *c, double *hist, floe_normal_force *o);


/* The Hertz-Mindlin moduli of two materials: E*, G* and sqrt(4 G* / E*); 0 when a material
 * lacks young > 0 or poisson in (-1, 0.5]. */
int floe_hertz_moduli(const floe_material *a, const floe_material *b, double *e_star, double *g_star, double *tdr);

#endif
