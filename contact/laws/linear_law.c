/* linear_law.c - linear elastic / viscoelastic contact with Coulomb friction
 * (ParticLS eqs 16-20).
 *
 * Normal:      Fn = kn d + gn vn           (vn > 0 approaching, so the dashpot opposes
 *                                           approach), clamped at Fn >= 0 unless tension.
 * Onset/release: history[3] marks a contact already evaluated; the dashpot's first and
 *              last evaluations are weighted by the part of the step in contact
 *              (linear_dashpot_phase below).
 * Tangential:  history[0..2] = s, the shear spring displacement. Each call
 *              1. rotates s onto the current tangent plane (drop its normal component and
 *                 rescale it to its old length, as LIGGGHTS/LAMMPS do), so the spring
 *                 follows the rigid rotation of the contact frame;
 *              2. s += vt dt;
 *              3. trial force Ft = -ks s - gs vt;
 *              4. Coulomb: if |Ft| > mu |Fn|, Ft is scaled to length mu |Fn| and the spring
 *                 is reset so that -ks s - gs vt reproduces it: s = -(Ft + gs vt)/ks
 *                 (LAMMPS gran/hooke/history). The drop of the spring energy is slip loss.
 * Output:      force on i = -Fn n + Ft; energy = kn d^2/2 + ks |s|^2/2;
 *              dissipation = (normal damping force actually applied) vn dt
 *                            + gs |vt|^2 dt + slip loss;  fn = Fn.
 * With tension = 1 (paper form), the Coulomb limit uses |Fn|.
 *
 * Energy bookkeeping: the normal part is exact, d(kn d^2/2)/dt = kn d vn, so the energy
 * removed from the particles beyond the elastic store is (Fn - kn d) vn dt; with the clamp
 * active (Fn = 0) this is -kn d vn dt >= 0. The slip loss can be negative in the rare case
 * where the dashpot alone exceeds the Coulomb limit (the reset spring then grows); it is
 * reported as is, so that the sum of energy changes balances. */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include "floe_contact.h"
#include "law_parts.h"

static const double linear_pi = 3.14159265358979323846;

/* the other forces' rate of change of vn (floe_contact.an_ext); 0 at dt = 0 (prepare,
 * refresh: the dashpot sees vn itself) and when not finite */
static inline double linear_an_ext(const floe_contact *c) {
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
static double linear_dashpot_phase(double kn, double gn, int tension, const floe_contact *c, double *hist, double hm)
{
    const double d = c->depth, vn = c->vn, dt = c->dt;
    if (!(dt > 0.0)) return 1.0; /* prepare: nothing advances */
    if (hist[3] == 0.0) { /* first evaluation: the contact began d / vn ago */
        hist[3] = 1.0;
        return vn > 0.0 && d <= 2.0 * vn * dt ? 0.5 + fmin(d / (vn * dt), 1.0) : 1.0;
    }
    /* the part of this evaluation's window that the previous one already covered, when it
     * took itself for the last one and the contact went on */
    const double covered = hist[3] - 1.0;
    double f = 1.0;
    hist[3] = 1.0;
    if (tension && vn < 0.0) {
        /* the overlap's rate over the next drift: v_{n+3/2} = v_{n+1/2} + dt (a_ext - Fn / m*) */
        const double ae = linear_an_ext(c);
        const double fn = (kn * d + gn * (vn + 0.5 * dt * ae)) / (1.0 + gn * hm), vnext = vn + dt * ae - 2.0 * hm * fn;
        if (vnext < 0.0 && d < -vnext * dt) {
            f = 0.5 + d / (-vnext * dt);
            hist[3] = 1.0 + fmax(f - 1.0, 0.0);
        }
    }
    return fmax(f - covered, 0.0);
}

void floe_linear_normal(double kn, double gn, int tension, const floe_contact *c, double *hist, floe_normal_force *o)
{
    const double d = c->depth, vn = c->vn, dt = c->dt;
    const double fel = kn * d;
    /* the dashpot at the velocity of the step's end (linear_dashpot_phase) */
    const double hm = c->m_eff > 0.0 && isfinite(c->m_eff) ? 0.5 * dt / c->m_eff : 0.0;
    const double gph = gn * linear_dashpot_phase(kn, gn, tension, c, hist, hm);
    double Fn = (fel + gph * (vn + 0.5 * dt * linear_an_ext(c))) / (1.0 + gph * hm);
    if (!tension && Fn < 0.0) Fn = 0.0;
    o->fn = Fn;
    o->fel = fel;
    o->kn = kn;
    o->gn = gn;
    o->diss = (Fn - fel) * vn * dt; /* damping force actually applied times vn dt */
    o->energy = 0.5 * kn * d * d;
}

static int linear_force(const floe_contact_law *law_, const floe_contact *c, double *hist,
                        floe_contact_result *out)
{
    const floe_linear_law *L = (const floe_linear_law *)law_;
    floe_normal_force nf;
    floe_linear_normal(L->kn, L->gn, L->tension, c, hist, &nf);
    const double Fn = nf.fn;
    double diss = nf.diss;

    /* tangential */
    double *s = hist, Ft[3];
    floe_contact_coulomb(c, L->ks, L->gs, L->mu, fabs(Fn) + c->fn_extra, s, Ft, &diss);

    for (int k = 0; k < 3; ++k) {
        out->force[k] = -Fn * c->n[k] + Ft[k];
        out->torque_i[k] = 0.0;
        out->torque_j[k] = 0.0;
    }
    out->energy = nf.energy + 0.5 * L->ks * floe_v3_dot(s, s);
    out->dissipation = diss;
    out->fn = Fn;
    return FLOE_OK;
}

static void linear_stiffness(const floe_contact_law *law_, double r_eff, double m_eff,
                             double depth, double *kn, double *cn)
{
    const floe_linear_law *L = (const floe_linear_law *)law_;
    (void)r_eff; (void)m_eff; (void)depth;
    if (kn) *kn = L->kn;
    if (cn) *cn = L->gn;
}

static void linear_tangential(const floe_contact_law *law_, double r_eff, double m_eff,
                              double depth, double *kt, double *ct)
{
    const floe_linear_law *L = (const floe_linear_law *)law_;
    (void)r_eff; (void)m_eff; (void)depth;
    if (kt) *kt = L->ks;
    if (ct) *ct = L->gs;
}

static void linear_destroy(floe_contact_law *law) { free(law); }

static void linear_info(const floe_contact_law *law_, floe_law_info *info)
{
    const floe_linear_law *L = (const floe_linear_law *)law_;
    info->linear_kn = L->kn;
    info->linear_gn = L->gn;
}

const floe_contact_law_class floe_linear_law_class = {
    1, "linear", 4, linear_force, linear_stiffness, linear_destroy, linear_tangential, linear_info
};

floe_contact_law *floe_linear_law_create(double kn, double ks, double gn, double gs, double mu)
{
    if (!(kn >= 0.0) || !(ks >= 0.0) || !(gn >= 0.0) || !(gs >= 0.0) || !(mu >= 0.0) ||
        !isfinite(kn) || !isfinite(ks) || !isfinite(gn) || !isfinite(gs) || isnan(mu))
        return NULL;
    floe_linear_law *L = calloc(1, sizeof *L);
    if (!L) return NULL;
    L->base.klass = &floe_linear_law_class;
    L->kn = kn; L->ks = ks; L->gn = gn; L->gs = gs; L->mu = mu;
    L->base.friction = mu;
    L->tension = 0;
    return &L->base;
}

double floe_linear_restitution(double k, double c, double m)
{
    if (!(k > 0.0) || !(c >= 0.0) || !(m > 0.0)) return NAN;
    if (isinf(m)) return 1.0; /* immovable body: the dashpot does not act in finite time */
    const double zeta = c / (2.0 * sqrt(k * m));
    if (zeta >= 1.0) return 0.0;
    return exp(-linear_pi * zeta / sqrt(1.0 - zeta * zeta));
}

/* ---- registry entries: linear and viscoelastic (floe_registry.h) ---- */

typedef struct linear_params {
    floe_params_head head;
    double kn, ks, gn, gs, friction;
    int tension;
} linear_params;

#define LIN_KN {.key = "kn", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "N/m", \
                .min = 0, .max = INFINITY, .doc = "normal stiffness", .offset = offsetof(linear_params, kn)}
#define LIN_KS {.key = "ks", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED, .unit = "N/m", .min = 0, \
                .max = INFINITY, .doc = "tangential (shear) spring stiffness", .offset = offsetof(linear_params, ks)}
#define LIN_MU {.key = "friction", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY, \
                .doc = "Coulomb friction coefficient mu", .offset = offsetof(linear_params, friction)}
#define LIN_TENSION {.key = "tension", .type = FLOE_PARAM_BOOL, .unit = "", \
                     .doc = "true: the total normal force may become attractive (the paper's form); false: clamped at 0", \
                     .offset = offsetof(linear_params, tension)}

static const floe_param linear_schema[] = {LIN_KN, LIN_KS, LIN_MU, LIN_TENSION};
static const floe_param viscoelastic_schema[] = {
    LIN_KN, LIN_KS,
    {.key = "gn", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED, .unit = "N s/m", .min = 0, .max = INFINITY,
     .doc = "normal dashpot", .offset = offsetof(linear_params, gn)},
    {.key = "gs", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED, .unit = "N s/m", .min = 0, .max = INFINITY,
     .doc = "tangential dashpot", .offset = offsetof(linear_params, gs)},
    LIN_MU, LIN_TENSION};

static floe_contact_law *linear_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                       size_t errlen) {
    (void)a;
    (void)b;
    const linear_params *P = params;
    floe_contact_law *law = floe_linear_law_create(P->kn, P->ks, P->gn, P->gs, P->friction);
    if (!law) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    ((floe_linear_law *)law)->tension = P->tension;
    return law;
}

const floe_registry_entry floe_law_entry_linear = {
    .kind = FLOE_KIND_LAW, .name = "linear", .title = "linear elastic",
    .doc = "Linear spring normal force with a Coulomb-limited tangential spring (no damping).",
    .source = "ParticLS eqs 16-18 with gn = gs = 0; docs/models.md",
    .params = linear_schema, .nparams = (int)(sizeof linear_schema / sizeof *linear_schema),
    .params_size = sizeof(linear_params), .create = (floe_fn)linear_create};

const floe_registry_entry floe_law_entry_viscoelastic = {
    .kind = FLOE_KIND_LAW, .name = "viscoelastic", .title = "linear viscoelastic",
    .doc = "Linear spring-dashpot (Kelvin-Voigt) normal force with a Coulomb-limited tangential spring-dashpot.",
    .source = "ParticLS eqs 16-20; docs/models.md",
    .params = viscoelastic_schema, .nparams = (int)(sizeof viscoelastic_schema / sizeof *viscoelastic_schema),
    .params_size = sizeof(linear_params), .create = (floe_fn)linear_create};
