/* integrators.c - the integrator classes (floe_integrator.h) and their registry entries
 * (kind "integrator"): name, title, doc, source, flags and critical-step factor of each, in
 * one table; the step of the world's scheme. The Newmark-beta solvers are documented here
 * too (their own solver, floe_newmark.h: not steppable by the world). */
#include "integrator_parts.h"
#include "floe_registry.h"

#include <math.h>
#include <string.h>

/* ---- the integrator classes (floe_integrator.h) ---- */

static const floe_integrator_class integrators[] = {
    {.version = 1, .name = "velocity_verlet", .id = FLOE_VELOCITY_VERLET,
     .flags = FLOE_INTEGRATOR_RESTORES | FLOE_INTEGRATOR_KICK_DRIFT | FLOE_INTEGRATOR_UNDAMPED_BONDS |
              FLOE_INTEGRATOR_HALF_KICK,
     .step = step_verlet, .dt_factor = 1.0},
    {.version = 1, .name = "leapfrog", .id = FLOE_LEAPFROG,
     .flags = FLOE_INTEGRATOR_UNDAMPED_BONDS | FLOE_INTEGRATOR_HALF_KICK,
     .step = step_verlet, /* the same kicks, with the velocities kept at half steps */
     .why_not_restores = "leapfrog keeps half-step velocities, which a rejected step could not restore consistently",
     .why_not_kick_drift = "leapfrog's velocities live at half steps", .dt_factor = 1.0},
    /* RK2: its limit for a pure dashpot is half of Verlet's (gamma dt < 1) and it has none
     * for an undamped spring; the factor stays 1 (the estimate's packing of 12 contacts is
     * a bound well above one contact's, docs/integrators.md), the watchdog and the
     * particle checks stop a run that outgrows it */
    {.version = 1, .name = "rk2", .id = FLOE_RK2, .flags = FLOE_INTEGRATOR_RESTORES, .step = step_rk2,
     .why_not_kick_drift = "RK2 evaluates forces at its midpoint",
     .why_not_bonds = "RK2 has no stable step for undamped bonds (energy grows by 1 + (w dt)^4/4 per step) and its "
                      "midpoint evaluation would book the bonds' energy twice",
     .dt_factor = 1.0},
};
#define NCLASSES (sizeof integrators / sizeof *integrators)

/* the Newmark-beta solvers of bonded systems (floe_newmark.h): documented classes, no world
 * step; the explicit one is stable up to floe_newmark_critical_dt (block Gershgorin bound,
 * factor 1), the implicit average-acceleration one unconditionally on a linear system */
static const floe_integrator_class newmark_explicit = {
    .version = 1, .name = "newmark_explicit", .id = -1, .dt_factor = 1.0,
    .why_not_restores = "a Newmark solver runs its own bonded system (floe_newmark.h), not the world",
    .why_not_kick_drift = "a Newmark solver runs its own bonded system (floe_newmark.h), not the world",
    .why_not_bonds = "a Newmark solver runs its own bonded system (floe_newmark.h), not the world"};
static const floe_integrator_class newmark_implicit = {
    .version = 1, .name = "newmark_implicit", .id = -1, .dt_factor = INFINITY,
    .why_not_restores = "a Newmark solver runs its own bonded system (floe_newmark.h), not the world",
    .why_not_kick_drift = "a Newmark solver runs its own bonded system (floe_newmark.h), not the world",
    .why_not_bonds = "a Newmark solver runs its own bonded system (floe_newmark.h), not the world"};

const floe_integrator_class *floe_integrator_class_of(int integrator) {
    for (size_t k = 0; k < NCLASSES; k++)
        if (integrators[k].id == integrator) return &integrators[k];
    /* a class registered by a plugin */
    const int n = floe_registry_count(FLOE_KIND_INTEGRATOR);
    for (int k = 0; k < n; k++) {
        const floe_registry_entry *e = floe_registry_at(FLOE_KIND_INTEGRATOR, k);
        const floe_integrator_class *c = ((floe_integrator_class_fn)e->create)();
        if (c && c->step && c->id == integrator) return c;
    }
    return NULL;
}

const char *floe_integrator_name(int integrator) {
    const floe_integrator_class *c = floe_integrator_class_of(integrator);
    return c ? c->name : NULL;
}

int step_once(floe_world *w) {
    if (w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd) return step_staggered(w);
    return floe_integrator_class_of(w->def.integrator)->step(w);
}

/* ---- registry entries (kind "integrator") ---- */

static const floe_integrator_class *class_verlet(void) { return &integrators[0]; }
static const floe_integrator_class *class_leapfrog(void) { return &integrators[1]; }
static const floe_integrator_class *class_rk2(void) { return &integrators[2]; }
static const floe_integrator_class *class_newmark_explicit(void) { return &newmark_explicit; }
static const floe_integrator_class *class_newmark_implicit(void) { return &newmark_implicit; }

/* the world integrators take no parameters of their own (time.dt, time.safety and
 * time.adaptive are the driver's, docs/scene-format.md) */
typedef struct no_params { floe_params_head head; } no_params;

/* the Newmark solvers' parameters (floe_newmark_def; set through the C API) */
typedef struct newmark_params {
    floe_params_head head;
    double beta, gamma, damping_ratio, mass_damping, line_search_eps;
    int max_cuts, refactor_on_break, allow_unstable_dt;
} newmark_params;

#define NM_PARAMS(beta_def)                                                                                              \
    {                                                                                                                    \
        {"beta", FLOE_PARAM_REAL, 0, "", 0, 0.5, beta_def, NULL, NULL, "beta of eqs 24-26 (0: explicit central difference)", \
         offsetof(newmark_params, beta)},                                                                                \
        {"gamma", FLOE_PARAM_REAL, 0, "", 0.5, 1, 0.5, NULL, NULL, "gamma of eqs 24-26 (1/2: no numerical damping)",     \
         offsetof(newmark_params, gamma)},                                                                               \
        {"damping_ratio", FLOE_PARAM_REAL, 0, "", 0, INFINITY, 0, NULL, NULL, "xi of the bond dampers (004 eq 8)",      \
         offsetof(newmark_params, damping_ratio)},                                                                       \
        {"mass_damping", FLOE_PARAM_REAL, 0, "1/s", 0, INFINITY, 0, NULL, NULL, "alpha of C += alpha M",               \
         offsetof(newmark_params, mass_damping)},                                                                        \
        {"line_search_eps", FLOE_PARAM_REAL, 0, "", -INFINITY, INFINITY, 0.01, NULL, NULL,                               \
         "tolerated stress excess before a step is cut (eqs 29-30; < 0: never cut)",                                    \
         offsetof(newmark_params, line_search_eps)},                                                                     \
        {"max_cuts", FLOE_PARAM_INT, 0, "", 0, 1000, 12, NULL, NULL, "trial steps redone per step",                      \
         offsetof(newmark_params, max_cuts)},                                                                            \
        {"refactor_on_break", FLOE_PARAM_BOOL, 0, "", 0, 1, 0, NULL, NULL,                                               \
         "refactor when bonds break (default: rank downdate of the factor)", offsetof(newmark_params, refactor_on_break)}, \
        {"allow_unstable_dt", FLOE_PARAM_BOOL, 0, "", 0, 1, 0, NULL, NULL,                                               \
         "accept an explicit step above the critical one", offsetof(newmark_params, allow_unstable_dt)},                 \
    }

static const floe_param newmark_explicit_params[] = NM_PARAMS(0);
static const floe_param newmark_implicit_params[] = NM_PARAMS(0.25);

static const floe_registry_entry entries[] = {
    {.kind = FLOE_KIND_INTEGRATOR, .name = "velocity_verlet", .title = "velocity Verlet",
     .doc = "Kick, drift, forces, kick (the default). Symplectic, second order for position-dependent forces, first "
            "order with dashpots. Stable step: 1 x the critical estimate. Can be undone (adaptive steps), kicks and "
            "drifts (staggered PD-DEM), integrates beam bonds.",
     .source = "ParticLS eq 22; docs/integrators.md", .params_size = sizeof(no_params),
     .create = (floe_fn)class_verlet},
    {.kind = FLOE_KIND_INTEGRATOR, .name = "leapfrog", .title = "leapfrog",
     .doc = "Velocity Verlet with its two half kicks merged: the same trajectory, the velocities stored half a step "
            "back. Stable step: 1 x the critical estimate. Integrates beam bonds; not with adaptive steps or the "
            "staggered scheme.",
     .source = "000 eq 44; docs/integrators.md", .params_size = sizeof(no_params), .create = (floe_fn)class_leapfrog},
    {.kind = FLOE_KIND_INTEGRATOR, .name = "rk2", .title = "RK2 (explicit midpoint)",
     .doc = "Two force evaluations per step; second order also with dashpots, not symplectic (no stable step for an "
            "undamped spring). Stable step: 1 x the critical estimate (a pure dashpot: half of Verlet's). Can be "
            "undone (adaptive steps); not with beam bonds or the staggered scheme.",
     .source = "ParticLS eq 21; docs/integrators.md", .params_size = sizeof(no_params), .create = (floe_fn)class_rk2},
    {.kind = FLOE_KIND_INTEGRATOR, .name = "newmark_explicit", .title = "Newmark-beta, explicit (central difference)",
     .doc = "The bonded-system solver of floe_newmark.h with beta = 0 (C API: floe_newmark_create; not a "
            "time.integrator of a scene). Stable step: 1 x floe_newmark_critical_dt (block Gershgorin bound, "
            "damping included).",
     .source = "004 eqs 13-28", .params = newmark_explicit_params,
     .nparams = (int)(sizeof newmark_explicit_params / sizeof *newmark_explicit_params),
     .params_size = sizeof(newmark_params), .create = (floe_fn)class_newmark_explicit},
    {.kind = FLOE_KIND_INTEGRATOR, .name = "newmark_implicit", .title = "Newmark-beta, implicit (average acceleration)",
     .doc = "The bonded-system solver of floe_newmark.h with beta = 1/4 (C API: floe_newmark_create; not a "
            "time.integrator of a scene), CHOLMOD factors. Unconditionally stable on the linear system; the step is cut "
            "where a bond would pass its strength.",
     .source = "004 eqs 13-30", .params = newmark_implicit_params,
     .nparams = (int)(sizeof newmark_implicit_params / sizeof *newmark_implicit_params),
     .params_size = sizeof(newmark_params), .create = (floe_fn)class_newmark_implicit},
};

int floe_register_builtin_integrators(char *err, size_t errlen) {
    for (size_t k = 0; k < sizeof entries / sizeof *entries; k++) {
        if (floe_registry_find(entries[k].kind, entries[k].name)) continue;
        FLOE_TRY(floe_register(&entries[k], err, errlen));
    }
    return FLOE_OK;
}
