/* short_range.c - the classic peridynamic short-range repulsive contact force as a contact
 * law, and the "none" law that keeps a pair of materials out of contact.
 *
 * Short-range force (Silling & Askari 2005, Comput Struct 83:1526, eq 20; the EMU manual
 * value c_s = 15 c that LAMMPS pair peri/pmb uses; the PD-SRRFM column of 003 Table 1):
 * between two nodes closer than the short-range distance d_s,
 *   f = c_s / delta * (d_s - |y|) * V_i V_j      (force, N; repulsive along the line of
 *                                                 centres; zero for |y| >= d_s)
 * with c_s = factor * c (factor 15), c the PMB micromodulus (N/m^6), delta the horizon (m)
 * and V the node volumes. floe sets d_s = R_i + R_j, the sum of the contact radii, so that
 * d_s - |y| is exactly the contact depth of the two spheres and the law is a linear spring
 *   F_n = k d,   k = c_s V_i V_j / delta   (N/m),   energy k d^2 / 2,
 * with no damping, no friction and no tension. (Silling and LAMMPS use
 * d_s = min(0.9 |x_i - x_j|, 1.35 (r_i + r_j)) with r the node radius, half the spacing in
 * LAMMPS: 1.35 dx for non-bonded lattice neighbours; floe's PD contact radius
 * R = (3V/4pi)^(1/3) = 0.62 dx gives d_s = 1.24 dx between two points of a lattice, 8 % less;
 * bonded family members never enter contact in floe.)
 *
 * "none": the world never evaluates a contact between the two materials
 * (floe_contact_law_no_contact(), checked in core/world/forces.c before detection), so such a pair
 * never gets a force and never trips the interpenetration guard. */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "floe_contact.h"

/* ---------------------------------------------------------- short range ---- */

static int sr_force(const floe_contact_law *law_, const floe_contact *c, double *hist,
                    floe_contact_result *out)
{
    const floe_short_range_law *L = (const floe_short_range_law *)law_;
    (void)hist;
    const double d = c->depth > 0.0 ? c->depth : 0.0;
    const double Fn = L->k * d;
    for (int a = 0; a < 3; a++) {
        out->force[a] = -Fn * c->n[a];
        out->torque_i[a] = 0.0;
        out->torque_j[a] = 0.0;
    }
    out->energy = 0.5 * L->k * d * d;
    out->dissipation = 0.0;
    out->fn = Fn;
    return FLOE_OK;
}

static void sr_stiffness(const floe_contact_law *law_, double r_eff, double m_eff, double depth,
                         double *kn, double *cn)
{
    (void)r_eff; (void)m_eff; (void)depth;
    if (kn) *kn = ((const floe_short_range_law *)law_)->k;
    if (cn) *cn = 0.0;
}

static void sr_destroy(floe_contact_law *law) { free(law); }

const floe_contact_law_class floe_short_range_law_class = {
    1, "short_range", 0, sr_force, sr_stiffness, sr_destroy, NULL, NULL
};

floe_contact_law *floe_short_range_law_create(double k)
{
    if (!(k > 0.0) || !isfinite(k)) return NULL;
    floe_short_range_law *L = calloc(1, sizeof *L);
    if (!L) return NULL;
    L->base.klass = &floe_short_range_law_class;
    L->k = k;
    return &L->base;
}

floe_contact_law *floe_short_range_law_create_pd(double c, double delta, double v_a, double v_b, double factor)
{
    if (factor <= 0.0) factor = 15.0;
    if (!(c > 0.0) || !(delta > 0.0) || !(v_a > 0.0) || !(v_b > 0.0) || !isfinite(factor)) return NULL;
    floe_contact_law *law = floe_short_range_law_create(factor * c * v_a * v_b / delta);
    if (law) {
        floe_short_range_law *L = (floe_short_range_law *)law;
        L->c_s = factor * c;
        L->delta = delta;
        L->v_a = v_a;
        L->v_b = v_b;
    }
    return law;
}

/* ----------------------------------------------------------------- none ---- */

static int none_force(const floe_contact_law *law, const floe_contact *c, double *hist,
                      floe_contact_result *out)
{
    (void)law; (void)c; (void)hist;
    memset(out, 0, sizeof *out);
    return FLOE_OK;
}

static void none_stiffness(const floe_contact_law *law, double r_eff, double m_eff, double depth,
                           double *kn, double *cn)
{
    (void)law; (void)r_eff; (void)m_eff; (void)depth;
    if (kn) *kn = 0.0;
    if (cn) *cn = 0.0;
}

static void none_destroy(floe_contact_law *law) { free(law); }

const floe_contact_law_class floe_no_contact_law_class = {
    1, "none", 0, none_force, none_stiffness, none_destroy, NULL, NULL
};

floe_contact_law *floe_no_contact_law_create(void)
{
    floe_contact_law *L = calloc(1, sizeof *L);
    if (!L) return NULL;
    L->klass = &floe_no_contact_law_class;
    return L;
}

/* ---- registry entries: short_range and none (floe_registry.h) ---- */

extern const floe_registry_entry floe_law_entry_short_range;

typedef struct sr_params {
    floe_params_head head;
    double stiffness, micromodulus, horizon, volume, factor;
} sr_params;

static const floe_param sr_schema[] = {
    {.key = "stiffness", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "N/m", .min = 0,
     .max = INFINITY, .doc = "spring stiffness k (or give micromodulus, horizon and volume)",
     .offset = offsetof(sr_params, stiffness)},
    {.key = "micromodulus", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "N/m^6", .min = 0,
     .max = INFINITY, .doc = "PD micromodulus c: k = factor c volume^2 / horizon",
     .offset = offsetof(sr_params, micromodulus)},
    {.key = "horizon", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "m", .min = 0, .max = INFINITY,
     .doc = "PD horizon delta (with micromodulus)", .offset = offsetof(sr_params, horizon)},
    {.key = "volume", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "m^3", .min = 0, .max = INFINITY,
     .doc = "the points' volume V (with micromodulus)", .offset = offsetof(sr_params, volume)},
    {.key = "factor", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "", .min = 0, .max = INFINITY,
     .def = 15.0, .doc = "c_s = factor x micromodulus (LAMMPS and EMU use 15)", .offset = offsetof(sr_params, factor)},
};

static floe_contact_law *sr_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                   size_t errlen) {
    (void)a;
    (void)b;
    const sr_params *P = params;
    const floe_registry_entry *e = &floe_law_entry_short_range;
    double k = P->stiffness;
    if (floe_params_given(e, P, "stiffness")) {
        if (floe_params_given(e, P, "micromodulus") || floe_params_given(e, P, "horizon") ||
            floe_params_given(e, P, "volume") || floe_params_given(e, P, "factor")) {
            snprintf(err, errlen, "give stiffness, or micromodulus, horizon, volume (and factor), not both");
            return NULL;
        }
    } else {
        if (!floe_params_given(e, P, "micromodulus")) {
            snprintf(err, errlen, "short_range needs stiffness (N/m), or micromodulus (N/m^6), horizon (m) and volume (m^3)");
            return NULL;
        }
        if (!floe_params_given(e, P, "horizon") || !floe_params_given(e, P, "volume")) {
            snprintf(err, errlen, "short_range with micromodulus needs horizon (m) and volume (m^3)");
            return NULL;
        }
        k = P->factor * P->micromodulus * P->volume * P->volume / P->horizon;
        if (!(k > 0 && isfinite(k))) {
            snprintf(err, errlen, "factor x micromodulus x volume^2 / horizon = %g is not a finite positive stiffness", k);
            return NULL;
        }
    }
    floe_contact_law *law = floe_short_range_law_create(k);
    if (!law) snprintf(err, errlen, "out of memory");
    return law;
}

const floe_registry_entry floe_law_entry_short_range = {
    .kind = FLOE_KIND_LAW, .name = "short_range", .title = "PD short-range repulsion",
    .doc = "Silling's short-range repulsive force between PD points: a linear spring on the overlap of their "
           "contact spheres, no damping or friction.",
    .source = "Silling & Askari 2005; LAMMPS pair peri; docs/models.md",
    .params = sr_schema, .nparams = (int)(sizeof sr_schema / sizeof *sr_schema), .params_size = sizeof(sr_params),
    .create = (floe_fn)sr_create};

static floe_contact_law *none_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                     size_t errlen) {
    (void)params;
    (void)a;
    (void)b;
    floe_contact_law *law = floe_no_contact_law_create();
    if (!law) snprintf(err, errlen, "out of memory");
    return law;
}

const floe_registry_entry floe_law_entry_none = {
    .kind = FLOE_KIND_LAW, .name = "none", .title = "none (never in contact)",
    .doc = "The pair never touches: no detection, no force (e.g. PD points of one body against each other).",
    .source = "docs/models.md", .params = NULL, .nparams = 0, .params_size = sizeof(floe_params_head),
    .create = (floe_fn)none_create};
