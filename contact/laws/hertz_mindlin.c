/* hertz_mindlin.c - Hertz-Mindlin contact with restitution-calibrated damping and Coulomb
 * friction (003 eqs 12-22, 000 eqs 34-36, LIGGGHTS hertz/history).
 *
 * Effective properties
 *   E* = 1 / ((1 - nu_a^2)/E_a + (1 - nu_b^2)/E_b),   G_i = E_i / (2 (1 + nu_i)),
 *   G* = 1 / ((2 - nu_a)/G_a + (2 - nu_b)/G_b).
 *
 * Normal (d = depth, vn > 0 approaching, a = sqrt(R* d)):
 *   Fe = 4/3 E* a d,   Sn = dFe/dd = 2 E* a,
 *   Fd = 2 sqrt(5/6) beta sqrt(Sn m*) vn          (LIGGGHTS form),
 *   Fn = max(Fe + Fd, 0).
 * Tangential: kt = St = 8 G* a, gt = 2 sqrt(5/6) beta sqrt(St m*). history[0..2] holds the
 *   elastic tangential spring FORCE Fs (incremental form, as LIGGGHTS scales the shear
 *   history by kt): each call rotates Fs onto the current tangent plane (drop the normal
 *   component, keep the length), then Fs -= kt vt dt; trial Ft = Fs - gt vt; if
 *   |Ft| > mu Fn, Ft is scaled to mu Fn and Fs = Ft + gt vt (the elastic part that gives
 *   the capped total), the drop of the spring energy |Fs|^2/(2 kt) counting as slip loss.
 * Output: force on i = -Fn n + Ft; energy = 8/15 E* sqrt(R*) d^(5/2) + |Fs|^2/(2 kt);
 *   dissipation = (Fn - Fe) vn dt + gt |vt|^2 dt + slip loss; fn = Fn.
 *
 * beta = law->damping_ratio is NOT the LIGGGHTS beta(e) = -ln e / sqrt(ln^2 e + pi^2)
 * (exact only for a linear spring); it is calibrated so that a head-on collision of two
 * bodies under this very law restitutes exactly e, see floe_hertz_damping_for_restitution.
 *
 * Dimensionless collision. A head-on collision with relative normal speed v0 obeys
 *   m* d'' = -max(K d^(3/2) + 2 sqrt(5/6) beta sqrt(3/2 K m*) d^(1/4) d', 0),
 * K = 4/3 E* sqrt(R*) (so Sn = 3/2 K d^(1/2)), d(0) = 0, d'(0) = v0. With d = L x, t = T tau,
 *   T = (m* / (K sqrt(v0)))^(2/5),   L = v0 T
 * (chosen so that m* L / T^2 = K L^(3/2) and x'(0) = 1), dividing by m* L / T^2 gives
 *   x'' = -max(x^(3/2) + c x^(1/4) x', 0),   x(0) = 0, x'(0) = 1,
 *   c = 2 sqrt(5/6) beta sqrt(3/2) sqrt(K/m*) L^(1/4) T = 2 sqrt(5/6) sqrt(3/2) beta
 *     = sqrt(5) beta,
 * because T^2 K L^(1/2) / m* = 1. So e = -x'(end) depends on beta only, not on the impact
 * speed, the masses, the radii or the moduli.
 *
 * Contact-end rule. The total normal force is clamped at >= 0 (no attraction). Once the
 * clamp engages on the way out (x' < 0), x^(5/4) + c x' stays negative (x keeps falling at
 * constant speed), so the force stays zero until x returns to 0: "the force reaches zero"
 * and "x returns to 0" give the same exit speed, and the law applies the same clamp.
 *
 * Walls / fixed partners: the law expects finite, positive c->m_eff and c->r_eff. The caller
 * sets m_eff to the free particle's mass when the partner is fixed or kinematic, and r_eff
 * to the sphere's radius for a sphere on a plane. Non-finite values return FLOE_EINVAL. */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include "floe_contact.h"
#include "law_kernels.h"

#define HM_SQRT5 2.2360679774997897

/* ---- calibration: dimensionless collision ODE ---- */

static double hm_accel(double x, double v, double c)
{
    if (x <= 0.0) return 0.0;
    const double r = sqrt(x), q = sqrt(r);
    const double f = x * r + c * q * v;
    return f > 0.0 ? -f : 0.0;
}

/* Restitution -x'(end) of x'' = -max(x^1.5 + c x^0.25 x', 0), x(0) = 0, x'(0) = 1, by RK4.
 * x^(1/4) is singular at tau = 0 (uniform RK4 would converge only as h^(5/4)), so the
 * integration starts at tau0 = 1e-12 from the series x = tau, x' = 1 - 4/5 c tau^(5/4) and
 * uses graded steps min(h, tau/20) near the start. The step h shrinks with c, as the
 * initial damping rate ~ c x^(1/4) ~ c^(4/5). Relative accuracy ~1e-10 (checked by halving
 * h). */
static double hm_restitution_of_c(double c)
{
    double h = 2e-4;
    if (c > 1.0) h /= pow(c, 0.8);
    double t = 1e-12;
    double x = t, v = 1.0 - 0.8 * c * pow(t, 1.25);
    const long maxsteps = 400000000L;
    for (long it = 0; it < maxsteps; ++it) {
        const double hh = fmin(h, 0.05 * t);
        const double a1 = hm_accel(x, v, c);
        const double x2 = x + 0.5 * hh * v, v2 = v + 0.5 * hh * a1;
        const double a2 = hm_accel(x2, v2, c);
        const double x3 = x + 0.5 * hh * v2, v3 = v + 0.5 * hh * a2;
        const double a3 = hm_accel(x3, v3, c);
        const double x4 = x + hh * v3, v4 = v + hh * a3;
        const double a4 = hm_accel(x4, v4, c);
        x += hh / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4);
        v += hh / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
        t += hh;
        if (v < 0.0) {
            if (x <= 0.0) return -v;
            /* clamp engaged on the way out: the speed is final */
            const double r = sqrt(x);
            if (x * r + c * sqrt(r) * v <= 0.0) return -v;
        }
    }
    return NAN;
}

static double hm_calibrate(double e)
{
    /* e(c) decreases monotonically from 1 (c = 0) to 0 (c -> inf) */
    double lo = 0.0, hi = 1.0;
    while (hm_restitution_of_c(hi) > e) {
        lo = hi;
        hi *= 2.0;
        if (hi > 1e4) return NAN;
    }
    for (int it = 0; it < 200 && hi - lo > 1e-13 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (hm_restitution_of_c(mid) > e) lo = mid; else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* small per-thread cache of computed values */
#define HM_CACHE 8
static _Thread_local struct { double e, beta; } hm_cache[HM_CACHE];
static _Thread_local int hm_cache_n = 0, hm_cache_next = 0;

double floe_hertz_damping_for_restitution(double e)
{
    if (isnan(e) || e > 1.0) return NAN;
    if (e == 1.0) return 0.0;
    if (e <= 0.0) return INFINITY;
    for (int k = 0; k < hm_cache_n; ++k)
        if (hm_cache[k].e == e) return hm_cache[k].beta;
    const double beta = hm_calibrate(e) / HM_SQRT5;
    if (isfinite(beta)) {
        hm_cache[hm_cache_next].e = e;
        hm_cache[hm_cache_next].beta = beta;
        hm_cache_next = (hm_cache_next + 1) % HM_CACHE;
        if (hm_cache_n < HM_CACHE) hm_cache_n++;
    }
    return beta;
}

/* ---- the law ---- */

static int hm_force(const floe_contact_law *law_, const floe_contact *c, double *hist,
                    floe_contact_result *out)
{
    const floe_hertz_mindlin_law *H = (const floe_hertz_mindlin_law *)law_;
    const double d = c->depth, m = c->m_eff, R = c->r_eff;
    for (int k = 0; k < 3; ++k) out->force[k] = out->torque_i[k] = out->torque_j[k] = 0.0;
    out->energy = out->dissipation = out->fn = 0.0;
    if (!(m > 0.0) || !isfinite(m) || !(R > 0.0) || !isfinite(R)) return FLOE_EINVAL;
    if (!(d > 0.0)) {
        floe_v3_set(hist, 0.0, 0.0, 0.0);
        return FLOE_OK;
    }
    /* the normal and tangential parts of the composed law, fused (law_kernels.h) */
    out->fn = floe_hm_kernel(H, c, hist, out->force, &out->energy, &out->dissipation);
    return FLOE_OK;
}

static void hm_stiffness(const floe_contact_law *law_, double r_eff, double m_eff,
                         double depth, double *kn, double *cn)
{
    const floe_hertz_mindlin_law *H = (const floe_hertz_mindlin_law *)law_;
    double k = 0.0, g = 0.0;
    if (depth > 0.0 && r_eff > 0.0) {
        k = 2.0 * H->e_star * sqrt(r_eff * depth);
        if (m_eff > 0.0) g = FLOE_HM_DAMP_PREF * H->damping_ratio * sqrt(k * m_eff);
    }
    if (kn) *kn = k;
    if (cn) *cn = g;
}

static void hm_tangential(const floe_contact_law *law_, double r_eff, double m_eff, double depth,
                          double *kt, double *ct)
{
    const floe_hertz_mindlin_law *H = (const floe_hertz_mindlin_law *)law_;
    double kn = 0.0, cn = 0.0;
    hm_stiffness(law_, r_eff, m_eff, depth, &kn, &cn);
    /* kt = 8 G* sqrt(R* d) = kn (4 G* / E*); damping scaled by the square root of that */
    double ratio = H->tangent_damping_ratio * H->tangent_damping_ratio;
    if (kt) *kt = kn * ratio;
    if (ct) *ct = cn * H->tangent_damping_ratio;
}

static void hm_destroy(floe_contact_law *law) { free(law); }

static void hm_info(const floe_contact_law *law_, floe_law_info *info)
{
    const floe_hertz_mindlin_law *H = (const floe_hertz_mindlin_law *)law_;
    info->hertz_e_star = H->e_star;
    info->restitution = H->restitution;
}

const floe_contact_law_class floe_hertz_mindlin_law_class = {
    1, "hertz_mindlin", 3, hm_force, hm_stiffness, hm_destroy, hm_tangential, hm_info
};

static int hm_material_ok(const floe_material *m)
{
    return m && m->young > 0.0 && isfinite(m->young) && m->poisson > -1.0 && m->poisson <= 0.5;
}

int floe_hertz_moduli(const floe_material *ma, const floe_material *mb, double *e_star, double *g_star, double *tdr)
{
    if (!hm_material_ok(ma) || !hm_material_ok(mb)) return 0;
    const double Ea = ma->young, Eb = mb->young, na = ma->poisson, nb = mb->poisson;
    const double Ga = Ea / (2.0 * (1.0 + na)), Gb = Eb / (2.0 * (1.0 + nb));
    *e_star = 1.0 / ((1.0 - na * na) / Ea + (1.0 - nb * nb) / Eb);
    *g_star = 1.0 / ((2.0 - na) / Ga + (2.0 - nb) / Gb);
    *tdr = sqrt(4.0 * *g_star / *e_star);
    return 1;
}

floe_contact_law *floe_hertz_mindlin_law_create(const floe_material *ma, const floe_material *mb,
                                                double restitution, double mu)
{
    if (!hm_material_ok(ma) || !hm_material_ok(mb)) return NULL;
    if (!(restitution > 0.0 && restitution <= 1.0) || !(mu >= 0.0)) return NULL;
    const double beta = floe_hertz_damping_for_restitution(restitution);
    if (!isfinite(beta)) return NULL;
    floe_hertz_mindlin_law *H = calloc(1, sizeof *H);
    if (!H) return NULL;
    H->base.klass = &floe_hertz_mindlin_law_class;
    floe_hertz_moduli(ma, mb, &H->e_star, &H->g_star, &H->tangent_damping_ratio);
    H->restitution = restitution;
    H->mu = mu;
    H->base.friction = mu;
    H->damping_ratio = beta;
    return &H->base;
}

/* ---- registry entry (floe_registry.h) ---- */

typedef struct hm_params {
    floe_params_head head;
    double restitution, friction;
} hm_params;

static const floe_param hm_schema[] = {
    {.key = "restitution", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "",
     .min = 0, .max = 1, .doc = "coefficient of restitution e of a head-on collision (the damping is calibrated to it)",
     .offset = offsetof(hm_params, restitution)},
    {.key = "friction", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY,
     .doc = "Coulomb friction coefficient mu", .offset = offsetof(hm_params, friction)},
};

static floe_contact_law *hm_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                   size_t errlen) {
    const hm_params *P = params;
    floe_contact_law *law = floe_hertz_mindlin_law_create(a, b, P->restitution, P->friction);
    if (!law) snprintf(err, errlen, "could not create the law (the materials need young > 0 and poisson in (-1, 0.5))");
    return law;
}

const floe_registry_entry floe_law_entry_hertz_mindlin = {
    .kind = FLOE_KIND_LAW, .name = "hertz_mindlin", .title = "Hertz-Mindlin",
    .doc = "Hertz normal force and Mindlin tangential spring with Coulomb limit, damped to a given restitution; "
           "stiffness from the materials' young and poisson.",
    .source = "000 §2.3, 003 eqs 9-14; docs/models.md",
    .params = hm_schema, .nparams = (int)(sizeof hm_schema / sizeof *hm_schema), .params_size = sizeof(hm_params),
    .create = (floe_fn)hm_create, .flags = FLOE_LAW_NEEDS_YOUNG};
