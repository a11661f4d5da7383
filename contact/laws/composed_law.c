/* composed_law.c - a contact law composed of a normal part and a tangential part
 * (floe_contact.h; MercuryDPM's normal force + friction force), and the built-in parts:
 *   normal:     hooke   linear spring-dashpot (ParticLS eqs 16, 19)
 *               hertz   Hertz with the restitution-calibrated dashpot (003 eqs 15-21)
 *   tangential: coulomb linear shear spring-dashpot with a Coulomb limit (ParticLS eqs 17-18, 20)
 *               mindlin Mindlin spring 8 G* sqrt(R* d) with a Coulomb limit (000 eq 36)
 * The kernels are those of the fused laws (law_parts.h, linear_law.c, contact_law.c), so
 * hertz + mindlin is hertz_mindlin and hooke + coulomb is viscoelastic to rounding. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include "floe_contact.h"
#include "law_parts.h"

typedef struct floe_composed_law {
    floe_contact_law base;
    floe_normal_part *np;
    floe_tangential_part *tp; /* NULL: frictionless */
} floe_composed_law;

void floe_normal_part_destroy(floe_normal_part *np) {
    if (!np) return;
    if (np->klass && np->klass->destroy) np->klass->destroy(np);
    else free(np);
}

void floe_tangential_part_destroy(floe_tangential_part *tp) {
    if (!tp) return;
    if (tp->klass && tp->klass->destroy) tp->klass->destroy(tp);
    else free(tp);
}

static int composed_set_friction(floe_contact_law *law, double mu) {
    floe_composed_law *L = (floe_composed_law *)law;
    if (!L->tp) return FLOE_ENOTSUP;
    L->tp->friction = mu;
    law->friction = mu;
    return FLOE_OK;
}

/* the laws' friction setter (floe_contact.h), here beside the composed law it reaches into */
int floe_contact_law_set_friction(floe_contact_law *law, double mu)
{
    if (!law || !law->klass || !(mu >= 0.0) || !isfinite(mu)) return FLOE_EINVAL;
    const floe_contact_law_class *k = law->klass;
    if (k == &floe_linear_law_class) ((floe_linear_law *)law)->mu = mu;
    else if (k == &floe_hertz_mindlin_law_class) ((floe_hertz_mindlin_law *)law)->mu = mu;
    else if (k == &floe_overlap_law_class) ((floe_overlap_law *)law)->mu = mu;
    else if (k == &floe_composed_law_class) return composed_set_friction(law, mu);
    else if (k != &floe_hopkins_law_class) return FLOE_ENOTSUP; /* hopkins reads base.friction */
    law->friction = mu;
    return FLOE_OK;
}

static int composed_force(const floe_contact_law *law, const floe_contact *c, double *hist, floe_contact_result *out) {
    const floe_composed_law *L = (const floe_composed_law *)law;
    for (int k = 0; k < 3; ++k) out->force[k] = out->torque_i[k] = out->torque_j[k] = 0.0;
    out->energy = out->dissipation = out->fn = 0.0;
    floe_normal_force nf = {0};
    FLOE_TRY(L->np->klass->force(L->np, c, hist, &nf));
    double ft[3] = {0.0, 0.0, 0.0}, energy = nf.energy, diss = nf.diss;
    if (L->tp) FLOE_TRY(L->tp->klass->force(L->tp, c, &nf, hist, ft, &energy, &diss));
    for (int k = 0; k < 3; ++k) out->force[k] = -nf.fn * c->n[k] + ft[k];
    out->energy = energy;
    out->dissipation = diss;
    out->fn = nf.fn;
    return FLOE_OK;
}

static void composed_stiffness(const floe_contact_law *law, double r_eff, double m_eff, double depth, double *kn,
                               double *cn) {
    const floe_composed_law *L = (const floe_composed_law *)law;
    double k = 0.0, g = 0.0;
    L->np->klass->stiffness(L->np, r_eff, m_eff, depth, &k, &g);
    if (kn) *kn = k;
    if (cn) *cn = g;
}

static void composed_tangential(const floe_contact_law *law, double r_eff, double m_eff, double depth, double *kt,
                                double *ct) {
    const floe_composed_law *L = (const floe_composed_law *)law;
    double k = 0.0, g = 0.0, a = 0.0, b = 0.0;
    if (L->tp && L->tp->klass->stiffness) {
        L->np->klass->stiffness(L->np, r_eff, m_eff, depth, &a, &b);
        L->tp->klass->stiffness(L->tp, r_eff, m_eff, depth, a, b, &k, &g);
    }
    if (kt) *kt = k;
    if (ct) *ct = g;
}

static void composed_info(const floe_contact_law *law, floe_law_info *info) {
    const floe_composed_law *L = (const floe_composed_law *)law;
    if (L->np->klass->info) L->np->klass->info(L->np, info);
}

static void composed_destroy(floe_contact_law *law) {
    floe_composed_law *L = (floe_composed_law *)law;
    floe_normal_part_destroy(L->np);
    floe_tangential_part_destroy(L->tp);
    free(L);
}

const floe_contact_law_class floe_composed_law_class = {
    1, "composed", FLOE_LAW_HISTORY, composed_force, composed_stiffness, composed_destroy, composed_tangential,
    composed_info};

floe_contact_law *floe_composed_law_create(floe_normal_part *np, floe_tangential_part *tp) {
    floe_composed_law *L = np && np->klass && np->klass->force && np->klass->stiffness &&
                                   (!tp || (tp->klass && tp->klass->force))
                               ? calloc(1, sizeof *L)
                               : NULL;
    if (!L) {
        floe_normal_part_destroy(np);
        floe_tangential_part_destroy(tp);
        return NULL;
    }
    L->base.klass = &floe_composed_law_class;
    L->base.friction = tp ? tp->friction : 0.0;
    L->np = np;
    L->tp = tp;
    return &L->base;
}

/* ---- normal: hooke ---- */

typedef struct hooke_part {
    floe_normal_part base;
    double kn, gn;
    int tension;
} hooke_part;

static int hooke_force(const floe_normal_part *np, const floe_contact *c, double *hist, floe_normal_force *out) {
    const hooke_part *H = (const hooke_part *)np;
    floe_linear_normal(H->kn, H->gn, H->tension, c, hist, out);
    return FLOE_OK;
}
static void hooke_stiffness(const floe_normal_part *np, double r_eff, double m_eff, double depth, double *kn,
                            double *cn) {
    const hooke_part *H = (const hooke_part *)np;
    (void)r_eff; (void)m_eff; (void)depth;
    *kn = H->kn;
    *cn = H->gn;
}
static void hooke_info(const floe_normal_part *np, floe_law_info *info) {
    const hooke_part *H = (const hooke_part *)np;
    info->linear_kn = H->kn;
    info->linear_gn = H->gn;
}
static const floe_normal_part_class hooke_class = {1, "hooke", hooke_force, hooke_stiffness, hooke_info, NULL};

typedef struct hooke_params {
    floe_params_head head;
    double stiffness, damping;
    int tension;
} hooke_params;

static const floe_param hooke_schema[] = {
    {.key = "stiffness", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "N/m",
     .min = 0, .max = INFINITY, .doc = "normal spring kn", .offset = offsetof(hooke_params, stiffness)},
    {.key = "damping", .type = FLOE_PARAM_REAL, .unit = "N s/m", .min = 0, .max = INFINITY,
     .doc = "normal dashpot gn (0: elastic)", .offset = offsetof(hooke_params, damping)},
    {.key = "tension", .type = FLOE_PARAM_BOOL, .doc = "let the total normal force become attractive (paper form)",
     .offset = offsetof(hooke_params, tension)},
};

floe_normal_part *floe_hooke_part_create(double kn, double gn, int tension) {
    if (!(kn > 0.0) || !isfinite(kn) || !(gn >= 0.0) || !isfinite(gn)) return NULL;
    hooke_part *H = calloc(1, sizeof *H);
    if (!H) return NULL;
    H->base.klass = &hooke_class;
    H->kn = kn;
    H->gn = gn;
    H->tension = tension != 0;
    return &H->base;
}

static floe_normal_part *hooke_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                      size_t errlen) {
    const hooke_params *P = params;
    (void)a; (void)b;
    floe_normal_part *np = floe_hooke_part_create(P->stiffness, P->damping, P->tension);
    if (!np) snprintf(err, errlen, "could not create the hooke part (out of memory)");
    return np;
}

const floe_registry_entry floe_normal_entry_hooke = {
    .kind = FLOE_KIND_NORMAL, .name = "hooke", .title = "linear spring-dashpot",
    .doc = "Fn = kn d + gn vn (clamped at 0 unless tension), the dashpot's onset and release weighted by the part "
           "of the step in contact; history[3].",
    .source = "ParticLS eqs 16, 19; docs/models.md",
    .params = hooke_schema, .nparams = (int)(sizeof hooke_schema / sizeof *hooke_schema),
    .params_size = sizeof(hooke_params), .create = (floe_fn)hooke_create};

/* ---- normal: hertz ---- */

typedef struct hertz_part {
    floe_normal_part base;
    double e_star, beta, restitution;
} hertz_part;

static int hertz_force(const floe_normal_part *np, const floe_contact *c, double *hist, floe_normal_force *out) {
    const hertz_part *H = (const hertz_part *)np;
    (void)hist;
    const double m = c->m_eff, R = c->r_eff;
    if (!(m > 0.0) || !isfinite(m) || !(R > 0.0) || !isfinite(R)) return FLOE_EINVAL;
    if (!(c->depth > 0.0)) return FLOE_OK;
    floe_hertz_normal(H->e_star, H->beta, c, out);
    return FLOE_OK;
}
static void hertz_stiffness(const floe_normal_part *np, double r_eff, double m_eff, double depth, double *kn,
                            double *cn) {
    const hertz_part *H = (const hertz_part *)np;
    double k = 0.0, g = 0.0;
    if (depth > 0.0 && r_eff > 0.0) {
        k = 2.0 * H->e_star * sqrt(r_eff * depth);
        if (m_eff > 0.0) g = FLOE_HM_DAMP_PREF * H->beta * sqrt(k * m_eff);
    }
    *kn = k;
    *cn = g;
}
static void hertz_info(const floe_normal_part *np, floe_law_info *info) {
    const hertz_part *H = (const hertz_part *)np;
    info->hertz_e_star = H->e_star;
    info->restitution = H->restitution;
}
static const floe_normal_part_class hertz_class = {1, "hertz", hertz_force, hertz_stiffness, hertz_info, NULL};

typedef struct restitution_params {
    floe_params_head head;
    double restitution;
} restitution_params;

static const floe_param hertz_schema[] = {
    {.key = "restitution", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "",
     .min = 0, .max = 1, .doc = "coefficient of restitution e of a head-on collision (the damping is calibrated to it)",
     .offset = offsetof(restitution_params, restitution)},
};

floe_normal_part *floe_hertz_part_create(const floe_material *a, const floe_material *b, double restitution) {
    double e_star, g_star, tdr;
    if (!floe_hertz_moduli(a, b, &e_star, &g_star, &tdr) || !(restitution > 0.0 && restitution <= 1.0)) return NULL;
    const double beta = floe_hertz_damping_for_restitution(restitution);
    if (!isfinite(beta)) return NULL;
    hertz_part *H = calloc(1, sizeof *H);
    if (!H) return NULL;
    H->base.klass = &hertz_class;
    H->e_star = e_star;
    H->beta = beta;
    H->restitution = restitution;
    return &H->base;
}

static floe_normal_part *hertz_create(const void *params, const floe_material *a, const floe_material *b, char *err,
                                      size_t errlen) {
    const restitution_params *P = params;
    floe_normal_part *np = floe_hertz_part_create(a, b, P->restitution);
    if (!np) snprintf(err, errlen, "could not create the hertz part (the materials need young > 0 and poisson in "
                                   "(-1, 0.5])");
    return np;
}

const floe_registry_entry floe_normal_entry_hertz = {
    .kind = FLOE_KIND_NORMAL, .name = "hertz", .title = "Hertz, damped to a restitution",
    .doc = "Fn = 4/3 E* sqrt(R*) d^(3/2) + 2 sqrt(5/6) beta sqrt(Sn m*) vn, Sn = 2 E* sqrt(R* d), beta calibrated so "
           "that a head-on collision restitutes e; E* from the materials' young and poisson.",
    .source = "003 eqs 15-21, 000 eq 36; docs/models.md",
    .params = hertz_schema, .nparams = (int)(sizeof hertz_schema / sizeof *hertz_schema),
    .params_size = sizeof(restitution_params), .create = (floe_fn)hertz_create, .flags = FLOE_LAW_NEEDS_YOUNG};

/* ---- tangential: coulomb ---- */

typedef struct coulomb_part {
    floe_tangential_part base;
    double ks, gs;
} coulomb_part;

static int coulomb_force(const floe_tangential_part *tp, const floe_contact *c, const floe_normal_force *nf,
                         double *hist, double ft[3], double *energy, double *diss) {
    const coulomb_part *C = (const coulomb_part *)tp;
    floe_contact_coulomb(c, C->ks, C->gs, tp->friction, fabs(nf->fn) + c->fn_extra, hist, ft, diss);
    *energy += 0.5 * C->ks * floe_v3_dot(hist, hist);
    return FLOE_OK;
}
static void coulomb_stiffness(const floe_tangential_part *tp, double r_eff, double m_eff, double depth, double kn,
                              double cn, double *kt, double *ct) {
    const coulomb_part *C = (const coulomb_part *)tp;
    (void)r_eff; (void)m_eff; (void)depth; (void)kn; (void)cn;
    *kt = C->ks;
    *ct = C->gs;
}
static const floe_tangential_part_class coulomb_class = {1, "coulomb", coulomb_force, coulomb_stiffness, NULL};

typedef struct coulomb_params {
    floe_params_head head;
    double friction, stiffness, damping;
} coulomb_params;

static const floe_param coulomb_schema[] = {
    {.key = "friction", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED, .unit = "", .min = 0, .max = INFINITY,
     .doc = "Coulomb friction coefficient mu", .offset = offsetof(coulomb_params, friction)},
    {.key = "stiffness", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED | FLOE_PARAM_MIN_OPEN, .unit = "N/m",
     .min = 0, .max = INFINITY, .doc = "shear spring ks", .offset = offsetof(coulomb_params, stiffness)},
    {.key = "damping", .type = FLOE_PARAM_REAL, .unit = "N s/m", .min = 0, .max = INFINITY,
     .doc = "shear dashpot gs", .offset = offsetof(coulomb_params, damping)},
};

floe_tangential_part *floe_coulomb_part_create(double mu, double ks, double gs) {
    if (!(mu >= 0.0) || !(ks > 0.0) || !isfinite(ks) || !(gs >= 0.0) || !isfinite(gs)) return NULL;
    coulomb_part *C = calloc(1, sizeof *C);
    if (!C) return NULL;
    C->base.klass = &coulomb_class;
    C->base.friction = mu;
    C->ks = ks;
    C->gs = gs;
    return &C->base;
}

static floe_tangential_part *coulomb_create(const void *params, const floe_material *a, const floe_material *b,
                                            char *err, size_t errlen) {
    const coulomb_params *P = params;
    (void)a; (void)b;
    floe_tangential_part *tp = floe_coulomb_part_create(P->friction, P->stiffness, P->damping);
    if (!tp) snprintf(err, errlen, "could not create the coulomb part (out of memory)");
    return tp;
}

const floe_registry_entry floe_tangential_entry_coulomb = {
    .kind = FLOE_KIND_TANGENTIAL, .name = "coulomb", .title = "Coulomb shear spring-dashpot",
    .doc = "Ft = -ks s - gs vt limited to mu |Fn|, the spring s following the contact frame and reset on slip "
           "(LAMMPS gran/hooke/history); history[0..2].",
    .source = "ParticLS eqs 17-18, 20; docs/models.md",
    .params = coulomb_schema, .nparams = (int)(sizeof coulomb_schema / sizeof *coulomb_schema),
    .params_size = sizeof(coulomb_params), .create = (floe_fn)coulomb_create};

/* ---- tangential: mindlin ---- */

typedef struct mindlin_part {
    floe_tangential_part base;
    double g_star, tdr;
} mindlin_part;

static int mindlin_force(const floe_tangential_part *tp, const floe_contact *c, const floe_normal_force *nf,
                         double *hist, double ft[3], double *energy, double *diss) {
    const mindlin_part *M = (const mindlin_part *)tp;
    if (!(c->depth > 0.0) || !(c->r_eff > 0.0)) { floe_v3_set(ft, 0.0, 0.0, 0.0); return FLOE_OK; }
    floe_mindlin_tangential(M->g_star, M->tdr, tp->friction, c, nf, hist, ft, energy, diss);
    return FLOE_OK;
}
static void mindlin_stiffness(const floe_tangential_part *tp, double r_eff, double m_eff, double depth, double kn,
                              double cn, double *kt, double *ct) {
    const mindlin_part *M = (const mindlin_part *)tp;
    (void)m_eff; (void)kn;
    *kt = depth > 0.0 && r_eff > 0.0 ? 8.0 * M->g_star * sqrt(r_eff * depth) : 0.0;
    *ct = cn * M->tdr;
}
static const floe_tangential_part_class mindlin_class = {1, "mindlin", mindlin_force, mindlin_stiffness, NULL};

typedef struct friction_params {
    floe_params_head head;
    double friction;
} friction_params;

static const floe_param mindlin_schema[] = {
    {.key = "friction", .type = FLOE_PARAM_REAL, .flags = FLOE_PARAM_REQUIRED, .unit = "", .min = 0, .max = INFINITY,
     .doc = "Coulomb friction coefficient mu", .offset = offsetof(friction_params, friction)},
};

floe_tangential_part *floe_mindlin_part_create(const floe_material *a, const floe_material *b, double mu) {
    double e_star, g_star, tdr;
    if (!floe_hertz_moduli(a, b, &e_star, &g_star, &tdr) || !(mu >= 0.0)) return NULL;
    mindlin_part *M = calloc(1, sizeof *M);
    if (!M) return NULL;
    M->base.klass = &mindlin_class;
    M->base.friction = mu;
    M->g_star = g_star;
    M->tdr = tdr;
    return &M->base;
}

static floe_tangential_part *mindlin_create(const void *params, const floe_material *a, const floe_material *b,
                                            char *err, size_t errlen) {
    const friction_params *P = params;
    floe_tangential_part *tp = floe_mindlin_part_create(a, b, P->friction);
    if (!tp) snprintf(err, errlen, "could not create the mindlin part (the materials need young > 0 and poisson in "
                                   "(-1, 0.5])");
    return tp;
}

const floe_registry_entry floe_tangential_entry_mindlin = {
    .kind = FLOE_KIND_TANGENTIAL, .name = "mindlin", .title = "Mindlin spring",
    .doc = "kt = 8 G* sqrt(R* d) on the stored force, dashpot gn sqrt(4 G*/E*) from the normal part's, limited to "
           "mu (Fn + manifold springs); G*, E* from the materials' young and poisson; history[0..2].",
    .source = "000 eq 36, 003 eqs 9-14; docs/models.md",
    .params = mindlin_schema, .nparams = (int)(sizeof mindlin_schema / sizeof *mindlin_schema),
    .params_size = sizeof(friction_params), .create = (floe_fn)mindlin_create, .flags = FLOE_LAW_NEEDS_YOUNG};
