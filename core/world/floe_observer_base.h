/* floe_observer_base.h - the observer class (ParticLS §4.3), as the world calls it: every
 * `period_steps` steps or every `period_time` seconds of simulated time, once at the start
 * and once at the end (also when a run stops on an error, so that what was computed is
 * written). The built-in observers are in observers/floe_observer.h. */
#ifndef FLOE_OBSERVER_BASE_H
#define FLOE_OBSERVER_BASE_H

#include "floe_world.h"
#include "floe_registry.h"

/* an output's cheaper way under MPI (version 4, split_request below) */
enum { FLOE_SPLIT_CLOCK = 1, FLOE_SPLIT_PARTICLES = 2, FLOE_SPLIT_COLLECTION = 3 };
typedef struct floe_split_request {
    int kind;       /* FLOE_SPLIT_* */
    int group;      /* FLOE_SPLIT_COLLECTION: the group (-1: every free particle) */
    const int *ids; /* FLOE_SPLIT_PARTICLES: nids world indices */
    int nids;
} floe_split_request;

typedef struct floe_observer_class {
    int version; /* 1; 2 with the checkpoint hooks below; 3 with reads_orientation; 4 with split_request */
    const char *name;
    int (*begin)(floe_observer *o, floe_world *w);      /* optional */
    int (*observe)(floe_observer *o, floe_world *w);    /* required */
    int (*end)(floe_observer *o, floe_world *w);        /* optional: flush, close */
    void (*destroy)(floe_observer *o);                  /* optional */
    int needs_contacts;   /* 1: reads floe_world_contacts, so the world records every contact */
    /* version 2, optional (docs/checkpoints.md): what the observer needs to go on writing
     * after a restart as if the run had not stopped (its files' lengths, frame counts, what
     * it accumulates). A checkpoint is written between steps, after the observers of the
     * step. restore is called on an observer of a world freshly built from the same scene,
     * after its begin(): it cuts its files back to their length at the checkpoint (they were
     * opened without truncating, floe_outputs_keep_existing) and takes the state back; n is
     * the size saved. A world holding an observer without these hooks can save a checkpoint
     * but not load one (the message names the observer). */
    size_t (*state_size)(const floe_observer *o);
    void (*save)(const floe_observer *o, unsigned char *buf);
    int (*restore)(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n);
    /* version 3: 1 when the observer reads the particles' orientations (floe_particles_view
     * q). The orientation of a round particle (a sphere, a disc) is integrated only when
     * something reads it (floe_world_set_orientation): an observer of version 1 or 2 is taken
     * to read it. FLOE_OBSERVER_READS_LISTED: only the orientations of the particles the
     * instance lists in floe_observer.orient_ids (a particle tracker). */
    int reads_orientation;
    /* version 4, optional (docs/parallel.md, "Outputs reduced over the ranks"): under MPI the
     * observers live on rank 0's unsplit mirror of the world, and by default every particle's
     * state (and every contact, for a class that reads them) is gathered to rank 0 before an
     * observation. split_request tells a cheaper way: FLOE_OK with *req filled in takes it
     * (anything else keeps the gather). Its kinds:
     *   FLOE_SPLIT_CLOCK: observe reads only the clock and the energy ledger (summed over the
     *     ranks): nothing is gathered;
     *   FLOE_SPLIT_PARTICLES: observe reads the state (x v q w L f t) of the particles listed in
     *     req->ids (world indices, walls included; read when floe_world_parallel_outputs
     *     runs): those alone are brought to rank 0;
     *   FLOE_SPLIT_COLLECTION: every rank computes floe_world_collection_sums(w, req->group)
     *     over its share, and rank 0 calls observe_sums with the sums over the ranks (the box
     *     reduced by minimum and maximum) instead of observe. It is not called when some rank
     *     did not record its contacts at that step (observe then sees none either). Taken
     *     only by a class with needs_contacts (the ranks record contacts for those). */
    int (*split_request)(const floe_observer *o, floe_split_request *req);
    int (*observe_sums)(floe_observer *o, floe_world *w, const double *sums);
} floe_observer_class;


enum { FLOE_OBSERVER_READS_LISTED = 2 };

struct floe_observer {
    const floe_observer_class *klass;
    long period_steps;      /* > 0: every n steps */
    double period_time;     /* > 0: every this many seconds (used when period_steps = 0) */
    double next_time;       /* bookkeeping of the world */
    int ended;
    int begun;
    /* read only when the class's reads_orientation is FLOE_OBSERVER_READS_LISTED: the world
     * indices of the particles whose orientations it reads (the observer owns the array) */
    const int *orient_ids;
    int norient_ids;
};

/* Destroys an observer the world does not own (the world destroys those added to it). */
void floe_observer_destroy(floe_observer *o);

/* ---- outputs as registered components (floe_registry.h, kind FLOE_KIND_OBSERVER,
 * "output") ----
 * A registered output gives a parameter schema and this constructor. A scene names it as
 * `outputs: [{type: <name>, every: N | interval: T, file: F, <its parameters>}]`; `every`,
 * `interval` and `file` are read by the loader (file defaults to <name>.csv, relative to the
 * output directory). The world owns the observer once the loader adds it. */
typedef struct floe_output_ctx {
    const char *outdir;      /* the run's output directory (exists when with_outputs) */
    const char *path;        /* outdir/file, or file when absolute */
    const floe_world *world; /* the world being built (its particles are all added) */
    int dim;
} floe_output_ctx;
typedef floe_observer *(*floe_output_create_fn)(const void *params, const floe_output_ctx *ctx, char *err,
                                                size_t errlen);

#endif
