/* floe_provider.h - force providers and the staged step (issue #11, docs/architecture.md).
 *
 * Everything that puts forces on particles is a provider: body forces (PD body-force
 * regions, the body-force callback; gravity is set where the forces are cleared, before the
 * first stage), user providers (floe_world_add_provider,
 * a scene's forces:, e.g. linear_drag in user_providers.c), beam bonds, contacts, PD bonds
 * (later: periodic cells). The world evaluates them in a fixed order through a
 * per-step context (particle_store.h floe_step_ctx: stepping, probe, history step, record),
 * never through flags on the world, and rebuilds the neighbour list between stages when a
 * provider asks (a bond broke and its pair may now touch), never inside one.
 *
 * Each provider declares what the world needs around the step:
 *   critical_dt   its stability limit (a user provider's is the time-step estimate's kind
 *                 FLOE_DT_PROVIDER; the beam stage's is FLOE_DT_BEAM);
 *   excludes      pairs it holds, that must never enter the contact list (bonded pairs);
 *   state         bytes of its own state that a step changes (contact history, a bond's
 *                 last force, broken flags), saved and restored by the adaptive controller
 *                 when it rejects a trial step, and by RK2 around its midpoint probe; a
 *                 component that changes state without declaring it here would make a
 *                 rejected step silently wrong, which is why there is no other way;
 *   group         FLOE_GROUP_DEM or FLOE_GROUP_PD: the staggered PD-DEM scheme evaluates
 *                 the groups at their own rates.
 * A provider splits its work over threads or subdomains by itself (later): the world only
 * calls forces() once per stage. */
#ifndef FLOE_PROVIDER_H
#define FLOE_PROVIDER_H

#include "floe_world.h"
#include "floe_provider_ctx.h"

typedef struct floe_provider floe_provider;
struct floe_step_ctx; /* particle_store.h (internal): the store and the evaluation's kind */

enum { FLOE_GROUP_DEM = 1, FLOE_GROUP_PD = 2, FLOE_GROUP_ALL = 3 };

/* What one evaluation adds to the ledger. The world passes one accumulator to every
 * provider of a group, in order: each adds its own part. */
typedef struct floe_provider_out {
    double elastic;        /* stored energy after the evaluation, J */
    double dissipated;     /* when stepping: dissipated over the step (work - stored change), J */
    double work_boundary;  /* when stepping: work of moving boundaries and growing surfaces, J */
    int rebuild;           /* set to 1: pairs changed, rebuild the neighbour list before the
                              next stage */
} floe_provider_out;

/* floe_provider_class.splits (version 2): how a provider's work splits over MPI ranks */
enum { FLOE_PROVIDER_PER_PARTICLE = 1 };

typedef struct floe_provider_class {
    int version;           /* 1, or 2 with splits */
    const char *name;
    int group;             /* FLOE_GROUP_DEM or FLOE_GROUP_PD */
    /* required: add forces and torques to ctx->p->f and ->t (zeroed by the world before the
     * DEM group), and the ledger terms to out */
    int (*forces)(floe_provider *pv, floe_world *w, const struct floe_step_ctx *ctx, floe_provider_out *out);
    /* optional: the provider's critical time step (s, > 0; INFINITY: no limit), read at
     * prepare by the time-step estimate (floe_dt_estimates kind FLOE_DT_PROVIDER) */
    double (*critical_dt)(floe_provider *pv, floe_world *w);
    /* optional: 1 when the pair (i, j) must never enter the contact list */
    int (*excludes)(const floe_provider *pv, const floe_world *w, int i, int j);
    /* optional: the bytes of state a step changes; save writes them, restore reads them */
    size_t (*state_size)(const floe_provider *pv, const floe_world *w);
    void (*save)(const floe_provider *pv, const floe_world *w, unsigned char *buf);
    void (*restore)(floe_provider *pv, floe_world *w, const unsigned char *buf);
    /* optional: 1 when the provider can save its state (NULL with state_size set: always);
     * 0 makes the adaptive controller refuse the scene, naming the provider */
    int (*can_save)(const floe_provider *pv, const floe_world *w);
    void (*destroy)(floe_provider *pv);
    /* version 2: whether a world split over MPI ranks (floe_parallel.h) may run it. 0: not (the
     * split is refused, naming it). FLOE_PROVIDER_PER_PARTICLE: the force and torque it adds
     * to particle i depend only on i's own fields of floe_provider_ctx and on what every rank
     * holds alike (its parameters, the time, the step); it adds them to free particles only
     * (a rank's ghosts, its copies of the neighbouring ranks' particles, are stored
     * FLOE_FIXED); its ledger terms (out) are sums over the particles it acts on; it keeps no
     * state (no state_size), excludes no pairs and never asks for a rebuild (out->rebuild: a
     * split world refuses it with FLOE_ENOTSUP, naming the provider). Each rank then runs it on the particles
     * it owns, and the ranks' ledger terms are summed. On a split world i is the rank's
     * local index, not the particle's id in the scene: the force must not depend on i itself
     * (floe_world_parallel_gid gives the id) nor on the world as a whole through w (tested:
     * velocity Verlet and RK2 in FLOE_GROUP_DEM; velocity Verlet and the staggered PD-DEM
     * scheme in FLOE_GROUP_PD, on a PD body's points). */
    int splits;
} floe_provider_class;

struct floe_provider {
    const floe_provider_class *klass;
};

/* A user provider (a plugin's, or a registered kind "provider" named in a scene's
 * `forces:`): a struct that starts with `floe_provider base` and a class whose forces()
 * reads the evaluation through floe_provider_ctx_of(ctx) (floe_provider_ctx.h). Add it
 * before the world is prepared (its first step): FLOE_OK and the world owns it (freed by
 * klass->destroy, or free() when NULL, at floe_world_destroy); otherwise an error code with
 * the message in floe_world_last_error, and the caller keeps it (NULL, a class without
 * name or forces, a version other than 1 or 2, a version-2 class whose splits is neither 0
 * nor FLOE_PROVIDER_PER_PARTICLE or that declares per-particle forces with a state or
 * excludes, a world already prepared). User providers run
 * after the body forces and before beam bonds and contacts, in the order they were added;
 * group FLOE_GROUP_PD ones run with the PD bonds (the staggered scheme's PD rate). Their
 * state (state_size/save/restore) is saved and restored with every other provider's
 * around a rejected adaptive step and RK2's probe; excludes() keeps pairs out of the
 * contact list. */
int floe_world_add_provider(floe_world *w, floe_provider *pv);

/* The constructor of a registered provider (floe_registry.h, kind FLOE_KIND_PROVIDER): its
 * parameter struct read by the schema, and the world it will be added to (its particles
 * are all added). NULL with a message in err for invalid parameters. */
typedef floe_provider *(*floe_provider_create_fn)(const void *params, const floe_world *w, char *err, size_t errlen);
/* Registers the built-in providers (linear_drag); floe_register_builtins calls it. */
int floe_register_builtin_providers(char *err, size_t errlen);

/* The world's providers in evaluation order (built at prepare from what the scene holds:
 * a scene without bonds or PD has no such stage). */
int floe_world_provider_count(const floe_world *w);
const floe_provider *floe_world_provider(const floe_world *w, int k);

/* pv's class's splits: 0 for a version-1 class (which has no such field) or NULL */
int floe_provider_splits(const floe_provider *pv);

#endif
