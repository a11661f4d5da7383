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
#include "law_kernels.h"

static const double linear_pi = 3.14159265358979323846;

void floe_linear_normal(double kn, double gn, int tension, const floe_contact *c, double *hist, floe_normal_force *o)
{
    floe_linear_normal_k(kn, gn, tension, c, hist, o);
}

static int linear_force(const floe_contact_law *law_, const floe_contact *c, double *hist,
                        floe_contact_result *out)
{
    out->fn = floe_linear_kernel((const floe_linear_law *)law_, c, hist, out->force, &out->energy, &out->dissipation);
    for (int k = 0; k < 3; ++k) out->torque_i[k] = out->torque_j[k] = 0.0;
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
