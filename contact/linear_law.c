/* linear_law.c - linear elastic / viscoelastic contact with Coulomb friction
 * (ParticLS eqs 16-20).
 *
 * Normal:      Fn = kn d + gn vn           (vn > 0 approaching, so the dashpot opposes
 *                                           approach), clamped at Fn >= 0 unless tension.
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
#include <stdlib.h>

#include "floe_contact.h"

static const double linear_pi = 3.14159265358979323846;

static int linear_force(const floe_contact_law *law_, const floe_contact *c, double *hist,
                        floe_contact_result *out)
{
    const floe_linear_law *L = (const floe_linear_law *)law_;
    const double d = c->depth, vn = c->vn, dt = c->dt;

    /* normal */
    const double fel = L->kn * d;
    double Fn = fel + L->gn * vn;
    if (!L->tension && Fn < 0.0) Fn = 0.0;
    double diss = (Fn - fel) * vn * dt; /* damping force actually applied times vn dt */

    /* tangential */
    double *s = hist;
    floe_contact_rotate_history(s, c->n);
    floe_v3_axpy(s, dt, c->vt);
    double Ft[3] = {0.0, 0.0, 0.0};
    floe_v3_axpy(Ft, -L->ks, s);
    floe_v3_axpy(Ft, -L->gs, c->vt);
    const double vt2 = floe_v3_dot(c->vt, c->vt);
    const double limit = L->mu * fabs(Fn);
    const double ft2 = floe_v3_dot(Ft, Ft);
    if (ft2 > limit * limit) {
        const double ratio = limit / sqrt(ft2);
        floe_v3_scale(Ft, ratio);
        if (L->ks > 0.0) {
            const double e_before = 0.5 * L->ks * floe_v3_dot(s, s), minus_inv_ks = -1.0 / L->ks;
            for (int k = 0; k < 3; ++k) s[k] = (Ft[k] + L->gs * c->vt[k]) * minus_inv_ks;
            diss += L->gs * vt2 * dt + (e_before - 0.5 * L->ks * floe_v3_dot(s, s));
        } else {
            /* pure dashpot: only a fraction of it is applied */
            floe_v3_set(s, 0.0, 0.0, 0.0);
            diss += ratio * L->gs * vt2 * dt;
        }
    } else {
        diss += L->gs * vt2 * dt;
    }

    for (int k = 0; k < 3; ++k) {
        out->force[k] = -Fn * c->n[k] + Ft[k];
        out->torque_i[k] = 0.0;
        out->torque_j[k] = 0.0;
    }
    out->energy = 0.5 * L->kn * d * d + 0.5 * L->ks * floe_v3_dot(s, s);
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

const floe_contact_law_class floe_linear_law_class = {
    1, "linear", 3, linear_force, linear_stiffness, linear_destroy, linear_tangential
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
