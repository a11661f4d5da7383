/* overlap_law.c - overlap-area contact for 2D polygons (floe_contact.h).
 *
 * The geometry (contact/detect/detect.c, floe_detect_overlap) gives the overlap area A, the
 * integral I = (∫_{A∩B} -φ_B dA + ∫_{A∩B} -φ_A dA)/2 and its exact gradient, the resultant
 * -dI/dx_i, at a point on its line of action. With stored energy ka I the elastic force is
 * ka times that resultant: a conservative Winkler foundation (pressure ka x local depth on
 * the boundary of each body inside the other), whose normal force is ka A wherever one
 * edge of each polygon bounds the overlap (SubZero's "force proportional to the overlap
 * area", here as the gradient of an energy, so collisions conserve energy and flat edges
 * rest without rocking).
 * Normal:      Fn = ka |g| + gn vn, clamped at >= 0 (g = area_force);
 * Tangential:  the linear law's Coulomb spring (floe_contact_coulomb).
 * Couples:     rocking dashpot gn l^2/12 across n; twist about n (3D) by a torsion spring and
 *              dashpot with a Coulomb limit (twist_couple).
 * Output:      force on i = ka g - gn vn n + Ft (n = -g/|g|), energy ka I + ks |s|^2 / 2 + the
 *              torsion spring's. */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include "floe_contact.h"

/* Twist about the normal. One friction point cannot resist it; a contact patch can: its
 * shear springs and dashpots (ks, gs per contact, spread over a square patch of area A =
 * area_l2 in 3D) act on the relative twist angle theta (history slot) as a torsion spring
 * ks A/6 and dashpot gs A/6 (polar moment A^2/6 of the square, per area), the couple limited
 * by Coulomb friction over a disc of that area, mu Fn (2/3) sqrt(A/pi). Returns the couple on
 * i about n in *Mt, the spring's energy in *et; adds its dissipation to *diss. */
static void twist_couple(const floe_overlap_law *L, const floe_contact *c, double Fn, double wn, double *theta,
                         double *Mt, double *et, double *diss)
{
    const double A = c->area_l2;
    if (!(Fn > 0.0) || !(A > 0.0) || wn == 0.0) {
        if (!(Fn > 0.0) && *theta != 0.0) { /* unloaded: the spring lets go */
            *diss += 0.5 * L->ks * A / 6.0 * *theta * *theta;
            *theta = 0.0;
        }
        if (*theta == 0.0) return;
    }
    const double kt = L->ks * A / 6.0, gt = L->gs * A / 6.0;
    const double limit = L->mu * Fn * (2.0 / 3.0) * sqrt(A / M_PI);
    *theta += wn * c->dt;
    double m = -kt * *theta - gt * wn;
    if (fabs(m) > limit) { /* slipping: the spring keeps what Coulomb allows */
        const double e_before = 0.5 * kt * *theta * *theta;
        m = m > 0 ? limit : -limit;
        *theta = kt > 0.0 ? -(m + gt * wn) / kt : 0.0;
        *diss += e_before - 0.5 * kt * *theta * *theta;
    }
    *diss += gt * wn * wn * c->dt;
    *Mt = m;
    *et = 0.5 * kt * *theta * *theta;
}

static int overlap_force(const floe_contact_law *law_, const floe_contact *c, double *hist, floe_contact_result *out)
{
    const floe_overlap_law *L = (const floe_overlap_law *)law_;
    const double fel = L->ka * floe_v3_norm(c->area_force), vn = c->vn;
    double Fn = fel + L->gn * vn;
    if (Fn < 0.0) Fn = 0.0;
    double diss = (Fn - fel) * vn * c->dt;
    double Ft[3];
    floe_contact_coulomb(c, L->ks, L->gs, L->mu, Fn, hist, Ft, &diss);
    /* the dashpot acts at the resultant's point; distributed over a patch of size l it also
     * resists rocking: couple gn l^2/12 times the part of w_i - w_j across n */
    const double wn = floe_v3_dot(c->wr, c->n), cr = L->gn * c->area_l2 / 12.0;
    double wrock[3];
    for (int k = 0; k < 3; ++k) wrock[k] = c->wr[k] - wn * c->n[k];
    diss += cr * floe_v3_dot(wrock, wrock) * c->dt;
    /* twist about n (3D; 0 in 2D, where w is normal to n): */
    double Mt = 0.0, et = 0.0;
    twist_couple(L, c, Fn, wn, hist + 3, &Mt, &et, &diss);
    for (int k = 0; k < 3; ++k) {
        /* elastic part along the exact gradient (and its couple); the dashpot along n */
        out->force[k] = L->ka * c->area_force[k] - (Fn - fel) * c->n[k] + Ft[k];
        out->torque_i[k] = L->ka * c->area_couple[k] - cr * wrock[k] + Mt * c->n[k];
        out->torque_j[k] = -L->ka * c->area_couple[k] + cr * wrock[k] - Mt * c->n[k];
    }
    out->energy = L->ka * c->area_energy + 0.5 * L->ks * floe_v3_dot(hist, hist) + et;
    out->dissipation = diss;
    out->fn = Fn;
    return FLOE_OK;
}

/* for the critical step: a flat contact of the representative size, stiffness ka x length
 * (2D: the overlap grows by the contact length per unit depth, at most the
 * diameter: 4 r_eff for two equal bodies) */
static void overlap_stiffness(const floe_contact_law *law_, double r_eff, double m_eff, double depth, double *kn,
                              double *cn)
{
    const floe_overlap_law *L = (const floe_overlap_law *)law_;
    (void)m_eff; (void)depth;
    if (kn) *kn = L->ka * 4.0 * r_eff;
    if (cn) *cn = L->gn;
}

static void overlap_tangential(const floe_contact_law *law_, double r_eff, double m_eff, double depth, double *kt,
                               double *ct)
{
    const floe_overlap_law *L = (const floe_overlap_law *)law_;
    (void)r_eff; (void)m_eff; (void)depth;
    if (kt) *kt = L->ks;
    if (ct) *ct = L->gs;
}

static void overlap_destroy(floe_contact_law *law) { free(law); }

static void overlap_info(const floe_contact_law *law, floe_law_info *info)
{
    (void)law;
    info->needs_overlap = 1; /* reads floe_contact.area* */
    info->spreads_load = 1;  /* its stiffness counts the contact length */
}

const floe_contact_law_class floe_overlap_law_class = {
    1, "overlap_area", 3, overlap_force, overlap_stiffness, overlap_destroy, overlap_tangential, overlap_info
};

floe_contact_law *floe_overlap_law_create(double ka, double ks, double gn, double gs, double mu)
{
    if (!(ka > 0.0) || !(ks >= 0.0) || !(gn >= 0.0) || !(gs >= 0.0) || !(mu >= 0.0) || !isfinite(ka) ||
        !isfinite(ks) || !isfinite(gn) || !isfinite(gs) || isnan(mu))
        return NULL;
    floe_overlap_law *L = calloc(1, sizeof *L);
    if (!L) return NULL;
    L->base.klass = &floe_overlap_law_class;
    L->ka = ka; L->ks = ks; L->gn = gn; L->gs = gs; L->mu = mu;
    return &L->base;
}

/* ---- registry entry (floe_registry.h) ---- */

typedef struct ov_params {
    floe_params_head head;
    double stiffness, ks, gn, gs, friction;
} ov_params;

static const floe_param ov_schema[] = {
    {.key = "stiffness", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "N/m^3",
     .min = 0, .max = INFINITY, .doc = "force per m^2 of overlap and m of depth (2D: per m^3 of overlap area)",
     .offset = offsetof(ov_params, stiffness)},
    {.key = "ks", .type = FLOE_PARAM_REAL, .unit = "N/m", .min = 0, .max = INFINITY,
     .doc = "tangential spring stiffness", .offset = offsetof(ov_params, ks)},
    {.key = "gn", .type = FLOE_PARAM_REAL, .unit = "N s/m", .min = 0, .max = INFINITY, .doc = "normal dashpot",
     .offset = offsetof(ov_params, gn)},
    {.key = "gs", .type = FLOE_PARAM_REAL, .unit = "N s/m", .min = 0, .max = INFINITY, .doc = "tangential dashpot",
     .offset = offsetof(ov_params, gs)},
    {.key = "friction", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY,
     .doc = "Coulomb friction coefficient mu", .offset = offsetof(ov_params, friction)},
};

static floe_contact_law *ov_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                   size_t errlen) {
    (void)a;
    (void)b;
    const ov_params *P = params;
    floe_contact_law *law = floe_overlap_law_create(P->stiffness, P->ks, P->gn, P->gs, P->friction);
    if (!law) snprintf(err, errlen, "out of memory");
    return law;
}

const floe_registry_entry floe_law_entry_overlap_area = {
    .kind = FLOE_KIND_LAW, .name = "overlap_area", .title = "overlap area",
    .doc = "Polytope pairs: elastic force from the overlap area (2D) or volume (3D) and its energy integral "
           "(Winkler foundation), with tangential spring, dashpots and Coulomb friction (SubZero-style).",
    .source = "docs/models.md, \"Overlap-area law\"",
    .params = ov_schema, .nparams = (int)(sizeof ov_schema / sizeof *ov_schema), .params_size = sizeof(ov_params),
    .create = (floe_fn)ov_create};
