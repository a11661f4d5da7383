/* hopkins_law.c - Hopkins' elastic-plastic ridging law for sea-ice floes, as DEMSI uses it
 * (Hopkins 2004, Eng. Comput. 21; Turner et al. 2022, GMD 15; DEMSI-LAMMPS
 * pair_gran_hopkins_kokkos.cpp, read as equations: docs/sea-ice.md, "Ridging law").
 *
 * Per unit contact length L = 4 R* (4 r_i r_j / (r_i + r_j) for discs), the normal force is
 * a Kelvin-Voigt element (stiffness k_e, dashpot c_e) in series with a hardening plastic
 * slider (yield k_r, hardening k_p):
 *   F/L = k_e d_e + c_e d_e'  (elastic)     F/L = k_r + k_p d_p  (ridging)    d = d_e + d_p
 *   k_e = min_k E h_k / (2 r_k) over the floes (a wall: the floe's), c_e = 2 eta sqrt(k_e L m*) / L,
 *   h_r = (h_i + h_j) / 2 (a wall: the floe's h), k_r = C_f h_r, k_p = C_h h_r^2.
 * Each step (backward Euler on the series element, the previous ridging force F_prev):
 *   F_el = (k_e (d - d_p) + c_e d') L
 *   F_r  = [F_prev/(k_p dt) + d' L + (k_e L/c_e) d + k_e k_r L/(c_e k_p)]
 *          / [1/(k_p dt) + (1 + k_e/k_p)/c_e]          (c_e -> 0: k_e L (k_p d + k_r)/(k_p + k_e))
 *   d_p,r = (F_r - k_r L)/(k_p L), its rate d_p,r' = d' - (F_r - k_e L (d - d_p,r))/(c_e L);
 * the contact ridges (F = F_r, d_p := d_p,r) when F_r < F_el, d_p,r > 0 and d_p,r' > 0, else
 * it is elastic (F = F_el, d_p kept); F_prev := F_r. Once d <= d_p the floes carry no load
 * (the ridge is permanent: F_prev and the shear spring reset). F >= 0.
 * Tangential: a spring k_t = G h_eff (G = E / (2 (1 + nu)), h_eff = 1/(1/h_i + 1/h_j)) and a
 * dashpot g_t on the slip along t = k x n, capped by Coulomb mu F (the spring reset to the
 * cap when sliding). History: d_p, F_prev, the shear spring s. A 2D law (floes in the plane).
 * Stored energy: k_e L d_e^2 / 2 + k_t s^2 / 2; the ridging work is dissipated.
 * Two polygons: d and L come from their overlap (A, I: L = A^2/(2I), d = 2I/A, exact for a
 * flat overlap), the force along the overlap energy's gradient g_A (elastic: exactly
 * k_e g_A, the gradient of k_e I), so that edge-on-edge contacts conserve energy; discs
 * and walls: the deepest point, L = 4 R*. */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include "floe_contact.h"

typedef struct hopkins_law {
    floe_contact_law base;
    double E, nu, eta, cf, ch, gt, hmax;
} hopkins_law;

typedef struct hk_geom {
    double L, ke, ce, kr, kp, kt;
} hk_geom;

static void hk_setup(const hopkins_law *H, const floe_contact *c, hk_geom *g) {
    const double hi = c->thick_i > 0 ? c->thick_i : 1.0, hj = c->thick_j > 0 ? c->thick_j : 1.0;
    const int wi = !(c->rad_i < INFINITY), wj = !(c->rad_j < INFINITY);
    const double ri = c->rad_i, rj = c->rad_j;
    g->L = wi ? 4 * rj : wj ? 4 * ri : 4 * ri * rj / (ri + rj);
    const double ki = wi ? INFINITY : H->E * hi / (2 * ri), kj = wj ? INFINITY : H->E * hj / (2 * rj);
    g->ke = ki < kj ? ki : kj;
    const double m = c->m_eff < INFINITY ? c->m_eff : 0;
    g->ce = 2 * H->eta * sqrt(g->ke * g->L * m) / g->L;
    const double hr = wi ? hj : wj ? hi : 0.5 * (hi + hj);
    g->kr = H->cf * hr;
    g->kp = H->ch * hr * hr;
    const double heff = wi ? hj : wj ? hi : 1.0 / (1.0 / hi + 1.0 / hj);
    g->kt = H->E / (2 * (1 + H->nu)) * heff;
}

static int hopkins_force(const floe_contact_law *law_, const floe_contact *c, double *hist, floe_contact_result *out) {
    const hopkins_law *H = (const hopkins_law *)law_;
    hk_geom g;
    hk_setup(H, c, &g);
    /* two polygons: the overlap (area A, energy integral I, its gradient g_A) gives the
     * contact length L = A^2 / (2 I) and the depth d = 2 I / A (a flat overlap of width L and
     * depth d: A = L d, I = L d^2 / 2); the force acts along g_A, so that the elastic part
     * k_e g_A is the gradient of k_e I (conservative across edge-on-edge contacts) */
    const double ga = floe_v3_norm(c->area_force);
    const int ov = c->area > 0 && c->area_energy > 0 && ga > 0;
    if (ov) {
        g.L = c->area * c->area / (2 * c->area_energy);
        const double m = c->m_eff < INFINITY ? c->m_eff : 0;
        g.ce = 2 * H->eta * sqrt(g.ke * g.L * m) / g.L;
    }
    const double d = ov ? 2 * c->area_energy / c->area : c->depth, dd = c->vn, dt = c->dt, L = g.L;
    double *dp = hist, *fprev = hist + 1, *s = hist + 2;
    const double de = d - *dp;
    double diss = 0;
    if (!(de > 0)) { /* behind the ridge: no load */
        if (dt > 0) {
            diss += 0.5 * g.kt * *s * *s; /* the shear spring lets go */
            *fprev = 0;
            *s = 0;
        }
        out->fn = 0;
        out->energy = 0;
        out->dissipation = diss;
        return FLOE_OK;
    }
    double F = (g.ke * de + g.ce * dd) * L; /* elastic branch */
    if (dt > 0 && g.kp > 0) {
        double Fr;
        if (g.ce > 0)
            Fr = (*fprev / (g.kp * dt) + dd * L + g.ke * L / g.ce * d + g.ke * g.kr * L / (g.ce * g.kp)) /
                 (1 / (g.kp * dt) + (1 + g.ke / g.kp) / g.ce);
        else
            Fr = g.ke * L * (g.kp * d + g.kr) / (g.kp + g.ke);
        const double dpr = (Fr - g.kr * L) / (g.kp * L);
        /* the plastic rate: without a dashpot the elastic part follows the total rate
         * through the series stiffness */
        const double dpr_rate = g.ce > 0 ? dd - (Fr - g.ke * L * (d - dpr)) / (g.ce * L) : dd * g.ke / (g.ke + g.kp);
        if (Fr < F && dpr > 0 && dpr_rate > 0) {
            F = Fr;
            *dp = dpr;
        }
        *fprev = Fr;
    }
    if (F < 0) F = 0;
    /* tangential: along t = k x n (the plane's tangent) */
    const double t[3] = {-c->n[1], c->n[0], 0};
    const double vt = c->vt[0] * t[0] + c->vt[1] * t[1];
    if (dt > 0) *s += vt * dt;
    double Ft = -g.kt * *s - H->gt * vt;
    const double lim = H->base.friction * (F + c->fn_extra);
    if (fabs(Ft) > lim) {
        const double e0 = 0.5 * g.kt * *s * *s;
        Ft = Ft > 0 ? lim : -lim;
        if (dt > 0) *s = g.kt > 0 ? -(Ft + H->gt * vt) / g.kt : 0;
        diss += e0 - 0.5 * g.kt * *s * *s;
    }
    /* force on i: the normal pushes i away from j (-n; polygons: along g_A, scaled so that
     * an elastic contact without damping gets exactly k_e g_A) */
    for (int k = 0; k < 3; k++)
        out->force[k] = (ov ? F * c->area_force[k] / c->area : -F * c->n[k]) + Ft * t[k];
    const double dnew = d - *dp;
    out->energy = 0.5 * g.ke * L * dnew * dnew + 0.5 * g.kt * *s * *s;
    out->dissipation = diss;
    out->fn = F;
    return FLOE_OK;
}

/* for the critical step: the elastic branch of a contact between two floes of the thickest
 * thickness the law expects (hmax) and radius 2 r_eff each */
static void hopkins_stiffness(const floe_contact_law *law_, double r_eff, double m_eff, double depth, double *kn,
                              double *cn) {
    const hopkins_law *H = (const hopkins_law *)law_;
    (void)depth;
    const double r = 2 * r_eff, L = 4 * r_eff, ke = H->E * H->hmax / (2 * r);
    if (kn) *kn = ke * L;
    if (cn) *cn = 2 * H->eta * sqrt(ke * L * (m_eff < INFINITY ? m_eff : 0));
}

static void hopkins_tangential(const floe_contact_law *law_, double r_eff, double m_eff, double depth, double *kt,
                               double *ct) {
    const hopkins_law *H = (const hopkins_law *)law_;
    (void)r_eff;
    (void)m_eff;
    (void)depth;
    if (kt) *kt = H->E / (2 * (1 + H->nu)) * 0.5 * H->hmax;
    if (ct) *ct = H->gt;
}

static void hopkins_info(const floe_contact_law *law, floe_law_info *info) {
    info->thickness_max = ((const hopkins_law *)law)->hmax;
    info->needs_floe = 1;
    info->single_point = 1;
    info->prefers_overlap = 1;
    info->spreads_load = 1;
}

static void hopkins_destroy(floe_contact_law *law) { free(law); }

const floe_contact_law_class floe_hopkins_law_class = {
    1, "hopkins", 3, hopkins_force, hopkins_stiffness, hopkins_destroy, hopkins_tangential, hopkins_info};

floe_contact_law *floe_hopkins_law_create(const floe_hopkins_def *d, char *err, size_t errlen) {
    const char *bad = NULL;
    if (!d) bad = "no definition";
    else if (!(d->young > 0) || !isfinite(d->young)) bad = "young must be > 0 (Pa)";
    else if (!(d->poisson > -1 && d->poisson < 0.5)) bad = "poisson must be in (-1, 0.5)";
    else if (!(d->damping >= 0) || !isfinite(d->damping)) bad = "damping must be >= 0";
    else if (!(d->plastic_friction >= 0) || !isfinite(d->plastic_friction)) bad = "plastic_friction must be >= 0 (Pa)";
    else if (!(d->plastic_hardening > 0) || !isfinite(d->plastic_hardening))
        bad = "plastic_hardening must be > 0 (Pa/m^2)";
    else if (!(d->friction >= 0) || !isfinite(d->friction)) bad = "friction must be >= 0";
    else if (!(d->gs >= 0) || !isfinite(d->gs)) bad = "gs must be >= 0 (N s/m)";
    else if (!(d->thickness_max > 0) || !isfinite(d->thickness_max)) bad = "thickness_max must be > 0 (m)";
    if (bad) {
        snprintf(err, errlen, "hopkins: %s", bad);
        return NULL;
    }
    hopkins_law *H = calloc(1, sizeof *H);
    if (!H) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    H->base.klass = &floe_hopkins_law_class;
    H->base.friction = d->friction;
    H->E = d->young;
    H->nu = d->poisson;
    H->eta = d->damping;
    H->cf = d->plastic_friction;
    H->ch = d->plastic_hardening;
    H->gt = d->gs;
    H->hmax = d->thickness_max;
    return &H->base;
}

floe_hopkins_def floe_hopkins_default(void) {
    floe_hopkins_def d = {0};
    d.young = 2.0e9;          /* DEMSI testcases config_ridging.xml elasticModulus */
    d.poisson = 0.3;          /* poissonRatio */
    d.damping = 0.1;          /* nonbondedNormalDamping */
    d.plastic_friction = 26126; /* k_r = 26126 h (DEMSI pair_gran_hopkins.cpp, older version) */
    d.plastic_hardening = 928;  /* k_p = 928 h^2 (same) */
    d.friction = 0.3;         /* tangentialFriction */
    d.gs = 0;
    d.thickness_max = 5.0;
    return d;
}

/* ---- registry entry (floe_registry.h) ---- */

typedef struct hk_params {
    floe_params_head head;
    double young, poisson, damping, plastic_friction, plastic_hardening, friction, gs, thickness_max;
} hk_params;

static const floe_param hk_schema[] = {
    {.key = "young", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "Pa", .min = 0, .max = INFINITY,
     .def = 2.0e9, .doc = "ice's Young's modulus E (k_e = E h / (2 r); DEMSI 2e9)", .offset = offsetof(hk_params, young)},
    {.key = "poisson", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN | FLOE_PARAM_MAX_OPEN, .unit = "",
     .min = -1, .max = 0.5, .def = 0.3, .doc = "Poisson's ratio (shear modulus G = E / (2 (1 + nu)))",
     .offset = offsetof(hk_params, poisson)},
    {.key = "damping", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY, .def = 0.1,
     .doc = "normal damping eta, a fraction of the contact's critical damping (DEMSI 0.1)",
     .offset = offsetof(hk_params, damping)},
    {.key = "plastic_friction", .type = FLOE_PARAM_REAL, .unit = "Pa", .min = 0, .max = INFINITY, .def = 26126,
     .doc = "C_f: ridging yield force per length k_r = C_f h_r (DEMSI's 26126 h)",
     .offset = offsetof(hk_params, plastic_friction)},
    {.key = "plastic_hardening", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "Pa/m^2", .min = 0,
     .max = INFINITY, .def = 928, .doc = "C_h: ridging hardening k_p = C_h h_r^2 (DEMSI's 928 h^2)",
     .offset = offsetof(hk_params, plastic_hardening)},
    {.key = "friction", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY, .def = 0.3,
     .doc = "Coulomb friction mu (DEMSI 0.3)", .offset = offsetof(hk_params, friction)},
    {.key = "gs", .type = FLOE_PARAM_REAL, .unit = "N s/m", .min = 0, .max = INFINITY, .def = 0,
     .doc = "tangential dashpot", .offset = offsetof(hk_params, gs)},
    {.key = "thickness_max", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "m", .min = 0,
     .max = INFINITY, .def = 5.0, .doc = "the thickest floe it meets: the critical time step's stiffness uses it",
     .offset = offsetof(hk_params, thickness_max)},
};

static floe_contact_law *hk_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                   size_t errlen) {
    (void)a;
    (void)b;
    const hk_params *P = params;
    floe_hopkins_def d = {P->young, P->poisson, P->damping, P->plastic_friction, P->plastic_hardening, P->friction,
                          P->gs, P->thickness_max};
    return floe_hopkins_law_create(&d, err, errlen);
}

const floe_registry_entry floe_law_entry_hopkins = {
    .kind = FLOE_KIND_LAW, .name = "hopkins", .title = "Hopkins ridging (sea ice)",
    .doc = "2D sea-ice floes: Hopkins' elastic-plastic ridging law as DEMSI uses it. Per unit contact length L = "
           "4 R*, a Kelvin-Voigt element (k_e = min E h/(2r), damping a fraction of critical) in series with a "
           "hardening plastic slider (yield C_f h_r, hardening C_h h_r^2): ridging is permanent, unloading elastic; "
           "a tangential spring G h_eff with Coulomb friction. Reads each floe's thickness.",
    .source = "docs/sea-ice.md, \"Ridging law\"; Hopkins (2004) Eng. Comput. 21; DEMSI pair_gran_hopkins",
    .params = hk_schema, .nparams = (int)(sizeof hk_schema / sizeof *hk_schema), .params_size = sizeof(hk_params),
    .create = (floe_fn)hk_create};
