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

/* floe_v3_dot and floe_v3_cross for the lane forms, always inlined (in the world's large
 * contact stage the compiler stopped inlining floe_base.h's, and a call in a lane loop keeps
 * it scalar); the same operations */
static inline __attribute__((always_inline)) double floe_dot3_l(const double a[3], const double b[3]) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline __attribute__((always_inline)) void floe_cross3_l(double r[3], const double a[3], const double b[3]) {
    const double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
    r[0] = x; r[1] = y; r[2] = z;
}

/* Hertz normal force with the restitution-calibrated dashpot (003 eqs 15-21, 000 eq 36):
 * Sn = 2 E* sqrt(R* d), Fel = 2/3 Sn d, gn = 2 sqrt(5/6) beta sqrt(Sn m*), Fn = max(Fel +
 * gn vn, 0), stored energy 2/5 Fel d. Depth > 0, R*, m* > 0 finite (the caller checks). */
static inline __attribute__((always_inline)) void floe_hertz_normal_lane(double e_star, double beta, double d,
                                                                      double vn, double r_eff, double m_eff,
                                                                      double *fn, double *fel_out, double *Sn_out,
                                                                      double *gn_out, double *energy) {
    const double a = sqrt(r_eff * d);
    const double Sn = 2.0 * e_star * a;
    const double fel = (2.0 / 3.0) * Sn * d; /* 4/3 E* sqrt(R* d) d */
    const double gn = FLOE_HM_DAMP_PREF * beta * sqrt(Sn * m_eff);
    const double Fn = fel + gn * vn;
    *fn = 0.0 > Fn ? 0.0 : Fn; /* floe_clamp0 (NaN and -0 kept), without a branch */
    *fel_out = fel;
    *Sn_out = Sn;
    *gn_out = gn;
    *energy = 0.4 * fel * d;
}

static inline void floe_hertz_normal(double e_star, double beta, const floe_contact *c, floe_normal_force *o) {
    double Fn, fel, Sn, gn, energy;
    floe_hertz_normal_lane(e_star, beta, c->depth, c->vn, c->r_eff, c->m_eff, &Fn, &fel, &Sn, &gn, &energy);
    o->fn = Fn;
    o->fel = fel;
    o->kn = Sn;
    o->gn = gn;
    o->diss = (Fn - fel) * c->vn * c->dt;
    o->energy = energy;
}

/* floe_contact_rotate_history's common cases alone, with its operations: a zero spring (kept)
 * and the small turn (q < 1e-4); returns 1, s unchanged, where the turn is larger (the full
 * form's square root and second division). A batch of contacts in lanes (the world's sphere
 * batches) runs this over all its lanes and the full form only when one of them returns 1:
 * a contact frame turns by sqrt(q) a step, 0.01 rad, almost never (internal: not in the
 * public floe_contact.h). */
static inline __attribute__((always_inline)) int floe_contact_rotate_history_small(double s[3], const double n[3]) {
    const double mag2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2], sn = s[0] * n[0] + s[1] * n[1] + s[2] * n[2];
    const double q = sn * sn / mag2, small = 1.0 + q * (0.5 + 0.375 * q);
    const int keep = mag2 == 0.0, is_small = q < 1e-4;
    for (int k = 0; k < 3; k++) {
        const double ts = (s[k] + -sn * n[k]) * small;
        s[k] = (keep | !is_small) ? s[k] : ts;
    }
    return !keep & !is_small;
}

/* Mindlin tangential spring kt = 8 G* sqrt(R* d) on the stored force Fs (history[0..2],
 * rotated with the contact frame), dashpot gt = gn sqrt(4 G* / E*) (tdr) from the normal
 * dashpot, Coulomb limit mu (Fn + fn_extra); adds the spring energy |Fs|^2 / (2 kt) to
 * *energy and the dashpot and slip losses to *diss. In parts that a batch of contacts runs
 * in lanes (core/world/forces.c sph_flush_lanes; floe_mindlin_tangential_lane is the three in
 * order): the trial (the rotated spring advanced by -kt vt dt, the force it and the dashpot
 * give, the limit, |Ft|^2, 1 / (2 kt) and gt), then the slip onto the limit where |Ft| >
 * limit, which a batch without a slipping contact leaves out; neither has a branch.
 * floe_mindlin_tangential_lane, one contact at a time (the general path), takes the full turn
 * and the slip only where they apply (two branches: not for lanes). */
static inline __attribute__((always_inline)) void floe_mindlin_trial(double g_star, double tdr, double mu, double dt,
                                                                  double r_eff, double depth, const double vt[3],
                                                                  double gn, double fn, double fn_extra, double S[3],
                                                                  double Ft[3], double *gt_out, double *limit,
                                                                  double *ft2, double *half_inv_kt, double *diss) {
    const double kt = 8.0 * g_star * sqrt(r_eff * depth);
    const double gt = gn * tdr; /* sqrt(kt m) = sqrt(Sn m) sqrt(4 G* / E*) */
    for (int k = 0; k < 3; ++k) S[k] += -kt * dt * vt[k]; /* floe_v3_axpy(S, -kt dt, vt) */
    for (int k = 0; k < 3; ++k) Ft[k] = S[k] - gt * vt[k];
    const double vt2 = floe_dot3_l(vt, vt);
    *limit = mu * (fn + fn_extra); /* + the manifold's other springs */
    *ft2 = floe_dot3_l(Ft, Ft);
    *diss += gt * vt2 * dt;
    *half_inv_kt = 0.5 / kt;
    *gt_out = gt;
}
static inline __attribute__((always_inline)) void floe_mindlin_slip(double gt, const double vt[3], double limit,
                                                                 double ft2, double half_inv_kt, double S[3],
                                                                 double Ft[3], double *diss) {
    /* sliding or not without a branch (the branches' values selected: a batch's lanes run it;
     * floe_mindlin_tangential_lane calls it only for a contact that slips) */
    const int slip = ft2 > limit * limit;
    const double ftmag = sqrt(ft2), e_before = floe_dot3_l(S, S) * half_inv_kt, sc = limit / ftmag;
    double Fl[3], Ss[3];
    for (int k = 0; k < 3; ++k) Fl[k] = Ft[k] * sc;
    for (int k = 0; k < 3; ++k) Ss[k] = Fl[k] + gt * vt[k];
    const double dslip = e_before - floe_dot3_l(Ss, Ss) * half_inv_kt;
    for (int k = 0; k < 3; ++k) {
        Ft[k] = slip ? Fl[k] : Ft[k];
        S[k] = slip ? Ss[k] : S[k];
    }
    const double dd = *diss + dslip;
    *diss = slip ? dd : *diss;
}
static inline __attribute__((always_inline)) void floe_mindlin_tangential_lane(double g_star, double tdr, double mu,
                                                                            double dt, double r_eff, double depth,
                                                                            const double n[3], const double vt_in[3],
                                                                            double gn, double fn, double fn_extra,
                                                                            double S[3], double Ft[3], double *energy,
                                                                            double *diss) {
    const double vt[3] = {vt_in[0], vt_in[1], vt_in[2]};
    double gt, limit, ft2, half_inv_kt;
    /* one contact (the general path): the turn's full form and the slip only where taken, as
     * a sphere batch takes them (the same operations for the case taken: the same bits) */
    if (floe_contact_rotate_history_small(S, n)) floe_contact_rotate_history(S, n);
    floe_mindlin_trial(g_star, tdr, mu, dt, r_eff, depth, vt, gn, fn, fn_extra, S, Ft, &gt, &limit, &ft2, &half_inv_kt,
                       diss);
    if (ft2 > limit * limit) floe_mindlin_slip(gt, vt, limit, ft2, half_inv_kt, S, Ft, diss);
    *energy += floe_dot3_l(S, S) * half_inv_kt;
}

static inline void floe_mindlin_tangential(double g_star, double tdr, double mu, const floe_contact *c,
                                           const floe_normal_force *nf, double *Fs, double Ft[3], double *energy,
                                           double *diss) {
    /* the stored force in registers, written back once: updated in place in the history, its
     * element stores were read back by a vector load (a store-forwarding stall per contact) */
    double S[3] = {Fs[0], Fs[1], Fs[2]};
    floe_mindlin_tangential_lane(g_star, tdr, mu, c->dt, c->r_eff, c->depth, c->n, c->vt, nf->gn, nf->fn, c->fn_extra,
                                 S, Ft, energy, diss);
    Fs[0] = S[0]; Fs[1] = S[1]; Fs[2] = S[2];
}

/* Coulomb friction with a shear spring (ParticLS eqs 17-18), in two parts that a batch of
 * contacts runs in lanes (core/world/forces.c sph_flush_lanes): the trial, the spring s
 * (rotated with the contact frame by the caller first, floe_contact_rotate_history) advanced by vt dt and the force
 * it and the dashpot give, with the Coulomb limit mu |Fn| and |Ft|^2; then the force onto
 * the limit and the spring to match (minus_inv_ks = -1 / ks; no spring: s = 0), which the
 * caller keeps for a contact that slips (|Ft| > limit). Neither has a branch. */
static inline __attribute__((always_inline)) void floe_coulomb_trial_rotated(const double vt[3], double dt,
                                                                              double ks, double gs, double mu,
                                                                              double Fn, double *s, double Ft[3],
                                                                              double *limit, double *ft2) {
    for (int k = 0; k < 3; ++k) s[k] += dt * vt[k];
    for (int k = 0; k < 3; ++k) Ft[k] = 0.0 + -ks * s[k];
    for (int k = 0; k < 3; ++k) Ft[k] += -gs * vt[k];
    *limit = mu * fabs(Fn);
    *ft2 = floe_dot3_l(Ft, Ft);
}
static inline __attribute__((always_inline)) void floe_coulomb_slip(const double vt[3], double ks, double gs,
                                                                     double minus_inv_ks, double ratio,
                                                                     const double Ft[3], double Fs[3], double ss[3]) {
    for (int k = 0; k < 3; ++k) Fs[k] = Ft[k] * ratio;
    for (int k = 0; k < 3; ++k) {
        const double v = (Fs[k] + gs * vt[k]) * minus_inv_ks;
        ss[k] = ks > 0.0 ? v : 0.0;
    }
}

/* The two parts on one contact: see floe_contact.h and the linear law's header comment
 * (linear_law.c) for the steps and the energy bookkeeping. */
static inline __attribute__((always_inline)) void floe_coulomb_k(const floe_contact *c, double ks, double gs, double mu,
                                                                  double Fn, double *s, double Ft[3], double *diss)
{
    const double dt = c->dt;
    double limit, ft2;
    /* the spring's turn: the full form's square root and second division only for a turn
     * above 0.01 rad (the same operations either way: the same bits) */
    if (floe_contact_rotate_history_small(s, c->n)) floe_contact_rotate_history(s, c->n);
    floe_coulomb_trial_rotated(c->vt, dt, ks, gs, mu, Fn, s, Ft, &limit, &ft2);
    const double vt2 = floe_v3_dot(c->vt, c->vt);
    /* the slip's values (a square root, two divisions) only for a contact that slips: one
     * contact at a time, the general path (polytopes, compounds: a sphere pair's batch has its
     * own copies, sph_flush_lanes). It was branch-free when the spheres came this way too: in
     * a dense bed they stick and slip at random. A settled bed of polyhedra 3-4 % faster with
     * the branch (issue 14 session 41); the same operations where it slips, the same bits */
    const int slip = ft2 > limit * limit;
    if (!slip) {
        *diss += gs * vt2 * dt;
        return;
    }
    const double ratio = limit / sqrt(ft2); /* ft2 > 0 */
    double Fs[3], ss[3], dslip;
    floe_coulomb_slip(c->vt, ks, gs, ks > 0.0 ? -1.0 / ks : 0.0, ratio, Ft, Fs, ss);
    if (ks > 0.0) {
        const double e_before = 0.5 * ks * floe_v3_dot(s, s);
        dslip = gs * vt2 * dt + (e_before - 0.5 * ks * floe_v3_dot(ss, ss));
    } else {
        dslip = ratio * gs * vt2 * dt;
    }
    for (int k = 0; k < 3; ++k) {
        Ft[k] = Fs[k];
        s[k] = ss[k];
    }
    *diss += dslip;
}

/* the other forces' rate of change of vn (floe_contact.an_ext); 0 at dt = 0 (prepare,
 * refresh: the dashpot sees vn itself) and when not finite */
static inline __attribute__((always_inline)) double floe_linear_an_ext_v(double dt, double an_ext) {
    return ((dt > 0.0) & (fabs(an_ext) < INFINITY)) ? an_ext : 0.0; /* isfinite, without a branch */
}
static inline double floe_linear_an_ext(const floe_contact *c) { return floe_linear_an_ext_v(c->dt, c->an_ext); }

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
/* In lane form (the world's vectorised sphere batch, forces.c): the scalars of one contact, *h3 its
 * history[3] (written back whatever the case), each case's value computed and the one that
 * applies selected, without a branch (the same values as the cases taken one by one; the
 * divisions of the cases not taken are done and dropped, except where the caller passes
 * tension = 0 or may_first = 0 as constants: then those cases' divisions drop out). */
static inline __attribute__((always_inline)) double floe_linear_phase_lane(double kn, double gn, int tension, double d,
                                                                        double vn, double dt, double an_ext,
                                                                        double hm, double *h3, int may_first)
{
    const double h = *h3;
    const int live = dt > 0.0; /* else prepare: nothing advances, the factor is 1 */
    /* the first evaluation (h == 0): the contact began d / vn ago (may_first = 0, a constant:
     * the caller knows h != 0, or that dt is not > 0 (not live: the factor is 1 and h kept
     * whatever r is), and the division drops out) */
    const double r = may_first ? d / (vn * dt) : 0.0;
    const double f_first = ((vn > 0.0) & (d <= 2.0 * vn * dt)) ? 0.5 + (r < 1.0 ? r : 1.0) : 1.0;
    /* later ones: the part of this evaluation's window that the previous one already
     * covered, when it took itself for the last one and the contact went on */
    const double covered = h - 1.0;
    /* the overlap's rate over the next drift: v_{n+3/2} = v_{n+1/2} + dt (a_ext - Fn / m*) */
    const double ae = floe_linear_an_ext_v(dt, an_ext);
    const double fn = (kn * d + gn * (vn + 0.5 * dt * ae)) / (1.0 + gn * hm), vnext = vn + dt * ae - 2.0 * hm * fn;
    const int last = (tension != 0) & (vn < 0.0) & (vnext < 0.0) & (d < -vnext * dt);
    const double f_last = 0.5 + d / (-vnext * dt), f = last ? f_last : 1.0;
    const double h_next = last ? 1.0 + (f - 1.0 > 0.0 ? f - 1.0 : 0.0) : 1.0;
    const double f_next = f - covered > 0.0 ? f - covered : 0.0; /* fmax(., 0) (NaN: 0), inline */
    const int first = h == 0.0;
    *h3 = live ? (first ? 1.0 : h_next) : h;
    return live ? (first ? f_first : f_next) : 1.0;
}

static inline double floe_linear_dashpot_phase(double kn, double gn, int tension, const floe_contact *c, double *hist, double hm)
{
    return floe_linear_phase_lane(kn, gn, tension, c->depth, c->vn, c->dt, c->an_ext, hm, hist + 3, 1);
}

/* floe_linear_normal_k in lane form: the contact's depth, vn, dt, m_eff and an_ext; *h3 its
 * history[3]; the normal force into *fn, the elastic force into *fel, the stored energy into
 * *energy (no branch: the vectorised sphere batch runs it over a batch's contacts at once) */
static inline __attribute__((always_inline)) void floe_linear_normal_lane(double kn, double gn, int tension, double d,
                                                                       double vn, double dt, double m_eff,
                                                                       double an_ext, double *h3, double *fn,
                                                                       double *fel_out, double *energy,
                                                                       int may_first) {
    const double fel = kn * d;
    /* the dashpot at the velocity of the step's end (floe_linear_dashpot_phase) */
    const double hm_v = 0.5 * dt / m_eff, hm = ((m_eff > 0.0) & (m_eff < INFINITY)) ? hm_v : 0.0;
    const double gph = gn * floe_linear_phase_lane(kn, gn, tension, d, vn, dt, an_ext, hm, h3, may_first);
    const double Fn = (fel + gph * (vn + 0.5 * dt * floe_linear_an_ext_v(dt, an_ext))) / (1.0 + gph * hm);
    *fn = ((tension != 0) | !(0.0 > Fn)) ? Fn : 0.0; /* floe_clamp0 unless tension (NaN and -0 kept) */
    *fel_out = fel;
    *energy = 0.5 * kn * d * d;
}

static inline __attribute__((always_inline)) void floe_linear_normal_k(double kn, double gn, int tension,
                                                                  const floe_contact *c, double *hist,
                                                                  floe_normal_force *o)
{
    double Fn, fel, energy;
    /* the lane form with its switches as constants, as the sphere batches call it: the onset
     * phase's division only for a first evaluation, the last-evaluation phase's two only
     * under tension (the same operations for the case taken: the same bits) */
#define LIN_NORMAL_K(TENSION, FIRST)                                                                             \
    floe_linear_normal_lane(kn, gn, (TENSION), c->depth, c->vn, c->dt, c->m_eff, c->an_ext, hist + 3, &Fn, &fel, \
                            &energy, (FIRST))
    const int first = (hist[3] == 0.0) & (c->dt > 0.0); /* (dt 0: nothing advances, f = 1) */
    if (tension) {
        if (first) LIN_NORMAL_K(1, 1);
        else LIN_NORMAL_K(1, 0);
    } else {
        if (first) LIN_NORMAL_K(0, 1);
        else LIN_NORMAL_K(0, 0);
    }
#undef LIN_NORMAL_K
    o->fn = Fn;
    o->fel = fel;
    o->kn = kn;
    o->gn = gn;
    o->diss = (Fn - fel) * c->vn * c->dt; /* damping force actually applied times vn dt */
    o->energy = energy;
}

/* Linear spring-dashpot normal force kn d + gn vn with the onset/release treatment of the
 * dashpot (history[3]; linear_law.c), clamped at 0 unless tension. */
void floe_linear_normal(double kn, double gn, int tension, const floe_contact *c, double *hist, floe_normal_force *o);


/* The Hertz-Mindlin moduli of two materials: E*, G* and sqrt(4 G* / E*); 0 when a material
 * lacks young > 0 or poisson in (-1, 0.5]. */
int floe_hertz_moduli(const floe_material *a, const floe_material *b, double *e_star, double *g_star, double *tdr);

#endif
