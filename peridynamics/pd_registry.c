/* pd_registry.c - the built-in PD materials as registered components (floe_registry.h,
 * kind FLOE_KIND_PD_MATERIAL): their parameter schemas and constructors. A scene names one
 * by `peridynamics: [{material: {model: NAME, ...}}]`; a plugin registers its own the same
 * way (docs/extending.md, "A PD material"). */
#include "floe_pd.h"
#include "floe_registry.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>

/* ---- pmb: prototype microelastic brittle (bond-based) ---- */

typedef struct pmb_params {
    floe_params_head head;
    double rho, K, E, s_c, G_c, alpha, ycomp, yten;
    int plane;
} pmb_params;

static const floe_param pmb_schema[] = {
    {.key = "density", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "kg/m^3",
     .min = 0, .max = INFINITY, .doc = "mass density", .offset = offsetof(pmb_params, rho)},
    {.key = "bulk_modulus", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "Pa", .min = 0,
     .max = INFINITY, .def = 0, .doc = "bulk modulus K (3D: c = 18K/(pi delta^4)); required unless young (2D)",
     .offset = offsetof(pmb_params, K)},
    {.key = "young", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MIN_OPEN, .unit = "Pa", .min = 0, .max = INFINITY,
     .def = 0, .doc = "2D: Young's modulus instead of bulk_modulus (nu fixed by the model)",
     .offset = offsetof(pmb_params, E)},
    {.key = "critical_stretch", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY, .def = 0,
     .doc = "bond breaks above this stretch (0 with no fracture_energy: never)", .offset = offsetof(pmb_params, s_c)},
    {.key = "fracture_energy", .type = FLOE_PARAM_REAL, .unit = "J/m^2", .min = 0, .max = INFINITY, .def = 0,
     .doc = "G_c: critical stretch from 003 eq 5 (instead of critical_stretch)", .offset = offsetof(pmb_params, G_c)},
    {.key = "alpha", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_MAX_OPEN, .unit = "", .min = 0, .max = 1e3,
     .def = 0, .doc = "per-point critical stretch s0 = s_c - alpha s_min (LAMMPS peri/pmb); 0: constant s_c",
     .offset = offsetof(pmb_params, alpha)},
    {.key = "yield_compression", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY, .def = 0,
     .doc = "elastic-perfectly-plastic bonds: yield stretch magnitude in compression (003 eq 6); 0: elastic",
     .offset = offsetof(pmb_params, ycomp)},
    {.key = "yield_tension", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY, .def = 0,
     .doc = "the same in tension; 0: none", .offset = offsetof(pmb_params, yten)},
    {.key = "plane", .type = FLOE_PARAM_CHOICE, .choices = "stress|strain", .def = 0,
     .doc = "2D only: plane stress (nu = 1/3) or plane strain (nu = 1/4)", .offset = offsetof(pmb_params, plane)},
};

static int fail(char *err, size_t errlen, const char *msg) {
    snprintf(err, errlen, "%s", msg);
    return FLOE_EINVAL;
}

/* checks shared by pmb and lps: one breakage criterion; plane in 2D only */
static int common_checks(const floe_registry_entry *e, const void *params, double s_c, double G_c, int plane,
                         int dim, char *err, size_t errlen) {
    if (s_c > 0 && G_c > 0) return fail(err, errlen, "give critical_stretch or fracture_energy, not both");
    if (floe_params_given(e, params, "plane") && plane != 0 && dim != 2) return fail(err, errlen, "plane is a 2D option");
    return FLOE_OK;
}

const floe_registry_entry floe_pd_material_entry_pmb;

static int pmb_create(const void *params, int dim, floe_pd_material *out, char *err, size_t errlen) {
    const pmb_params *p = params;
    if ((p->ycomp > 0 || p->yten > 0) && p->alpha > 0)
        return fail(err, errlen, "plastic bonds and alpha cannot be combined");
    FLOE_TRY(common_checks(&floe_pd_material_entry_pmb, params, p->s_c, p->G_c, p->plane, dim, err, errlen));
    if (!(p->K > 0) && !(dim == 2 && p->E > 0))
        return fail(err, errlen, dim == 2 ? "bulk_modulus > 0 is required (2D PMB: or young)"
                                          : "bulk_modulus > 0 is required");
    *out = floe_pd_material_pmb(p->rho, p->K, p->s_c);
    if (dim == 2 && p->E > 0) out->E = p->E;
    out->G_c = p->G_c;
    out->alpha = p->alpha;
    out->yield_compression = p->ycomp;
    out->yield_tension = p->yten;
    out->plane = p->plane ? FLOE_PD_PLANE_STRAIN : FLOE_PD_PLANE_STRESS;
    return FLOE_OK;
}

const floe_registry_entry floe_pd_material_entry_pmb = {
    .kind = FLOE_KIND_PD_MATERIAL, .name = "pmb", .title = "prototype microelastic brittle (bond-based)",
    .doc = "Bond-based peridynamics: every bond a spring of stretch s = (|y| - |xi|)/|xi| with force c s beta V_i V_j, "
           "c = 18K/(pi delta^4) in 3D (Poisson's ratio fixed at 1/4; 2D: plane stress 1/3, plane strain 1/4). Bonds "
           "break above the critical stretch, optionally per point (alpha) or yield plastically.",
    .source = "000 eqs 9-12, 003 eqs 2-7; docs/models.md, \"Peridynamics\"",
    .params = pmb_schema, .nparams = 9, .params_size = sizeof(pmb_params), .create = (floe_fn)pmb_create,
    .keys_extra = "model"};

/* ---- lps: linear peridynamic solid (state-based) ---- */

typedef struct lps_params {
    floe_params_head head;
    double rho, K, G, s_c, G_c;
    int influence, plane;
} lps_params;

static const floe_param lps_schema[] = {
    {.key = "density", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "kg/m^3",
     .min = 0, .max = INFINITY, .doc = "mass density", .offset = offsetof(lps_params, rho)},
    {.key = "bulk_modulus", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "Pa",
     .min = 0, .max = INFINITY, .doc = "bulk modulus K", .offset = offsetof(lps_params, K)},
    {.key = "shear_modulus", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "Pa",
     .min = 0, .max = INFINITY, .doc = "shear modulus G", .offset = offsetof(lps_params, G)},
    {.key = "critical_stretch", .type = FLOE_PARAM_REAL, .unit = "", .min = 0, .max = INFINITY, .def = 0,
     .doc = "bond breaks above this stretch (0 with no fracture_energy: never)", .offset = offsetof(lps_params, s_c)},
    {.key = "fracture_energy", .type = FLOE_PARAM_REAL, .unit = "J/m^2", .min = 0, .max = INFINITY, .def = 0,
     .doc = "G_c: critical stretch from 003 eq 5 with the PMB c of the same K", .offset = offsetof(lps_params, G_c)},
    {.key = "influence", .type = FLOE_PARAM_CHOICE, .choices = "constant|gaussian", .def = 0,
     .doc = "influence function w: 1, or exp(-|xi|^2/delta^2) (ParticLS eq 33)", .offset = offsetof(lps_params, influence)},
    {.key = "plane", .type = FLOE_PARAM_CHOICE, .choices = "stress|strain", .def = 0,
     .doc = "2D only: plane stress or plane strain of the 3D solid", .offset = offsetof(lps_params, plane)},
};

const floe_registry_entry floe_pd_material_entry_lps;

static int lps_create(const void *params, int dim, floe_pd_material *out, char *err, size_t errlen) {
    const lps_params *p = params;
    FLOE_TRY(common_checks(&floe_pd_material_entry_lps, params, p->s_c, p->G_c, p->plane, dim, err, errlen));
    if (!(p->K > 0)) return fail(err, errlen, "bulk_modulus > 0 is required");
    *out = floe_pd_material_lps(p->rho, p->K, p->G, p->s_c, p->influence ? FLOE_PD_W_GAUSS : FLOE_PD_W_ONE);
    out->G_c = p->G_c;
    out->plane = p->plane ? FLOE_PD_PLANE_STRAIN : FLOE_PD_PLANE_STRESS;
    return FLOE_OK;
}

const floe_registry_entry floe_pd_material_entry_lps = {
    .kind = FLOE_KIND_PD_MATERIAL, .name = "lps", .title = "linear peridynamic solid (state-based)",
    .doc = "Ordinary state-based peridynamics: a dilatation and a deviatoric part from K and G (any Poisson's ratio), "
           "with the position-aware surface correction. Bonds break above the critical stretch.",
    .source = "000 eqs 15-25, ParticLS eqs 30-35; docs/models.md, \"LPS surface correction\"",
    .params = lps_schema, .nparams = 7, .params_size = sizeof(lps_params), .create = (floe_fn)lps_create,
    .keys_extra = "model"};

static const floe_registry_entry *const builtin[] = {&floe_pd_material_entry_pmb, &floe_pd_material_entry_lps};

int floe_register_builtin_pd_materials(char *err, size_t errlen) {
    return floe_register_list(builtin, sizeof builtin / sizeof *builtin, err, errlen);
}
