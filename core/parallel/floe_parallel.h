/* floe_parallel.h - MPI domain decomposition of a DEM world (docs/parallel.md, issue 14).
 *
 * Every rank builds and prepares the same world (the same scene), then
 * floe_world_parallel_init splits it: each rank keeps the particles of its subdomain
 * (recursive coordinate bisection of the particle centres by Zoltan, weights 1) and
 * receives copies (ghosts) of the other ranks' particles whose bounding sphere can reach a
 * particle of its own within the neighbour list's skin. Walls (unbounded geometries) are
 * kept on every rank. After that floe_world_step and floe_world_run go on as in the serial
 * world, with the communication inside: ghosts refreshed after each drift, the forces on
 * ghosts summed back to their owners, migration and new ghosts at every neighbour-list
 * rebuild (all ranks rebuild when any needs to), contact history carried by global ids.
 *
 * The functions are collective over the world's communicator unless they say otherwise.
 * Built without FLOE_WITH_MPI (FLOE_HAVE_MPI undefined), they return FLOE_ENOTSUP. */
#ifndef FLOE_PARALLEL_H
#define FLOE_PARALLEL_H

#include "floe_world.h"

/* 1 when the library was built with MPI (FLOE_WITH_MPI=ON), else 0; not collective */
int floe_parallel_available(void);

/* Split the prepared world over the ranks of comm (a pointer to an MPI_Comm; NULL: MPI_COMM_WORLD),
 * which must hold the same world on every rank (same particles, in the same order; global id =
 * index at this call). What is not yet supported is refused with FLOE_ENOTSUP and a message
 * (docs/parallel.md, "Not yet"): PD bodies of a user material, user state classes, user
 * providers and integrators, and
 * observers added to w itself (outputs go through floe_world_parallel_outputs). */
int floe_world_parallel_init(floe_world *w, const void *comm);

/* decompose again now (RCB, migration, ghosts, the neighbour list), as the step does at
 * every rebuild; a serial world: nothing */
int floe_world_parallel_rebuild(floe_world *w);

/* How the bisection weighs the ranks' shares (docs/parallel.md, "Load balance"):
 * FLOE_BALANCE_WEIGHTS (the default): equal shares of the estimated work (a particle weighs
 * 1, + 0.1 per list entry it is in, 1.3 instead for an entry in contact); every run of the
 * same scene on the same ranks decomposes alike, so its results repeat to the last bit.
 * FLOE_BALANCE_TIME: each rank's share of that estimate is sized by its measured speed (the
 * seconds of its own work, force evaluations and outputs, per unit of estimated work since
 * the last decomposition, averaged with the previous measure), as LAMMPS' `balance weight time`: a
 * rank on a slower or busier core gets less. The cut then depends on the timings: runs agree
 * only within round-off. Set it after floe_world_parallel_init (collective: the same mode on
 * every rank); it takes effect at the next decomposition. A serial world: nothing. */
typedef enum floe_balance { FLOE_BALANCE_WEIGHTS = 0, FLOE_BALANCE_TIME = 1 } floe_balance;
int floe_world_parallel_set_balance(floe_world *w, floe_balance mode);

/* Outputs of a split world: rank 0 passes mirror, an unsplit copy of the world built from
 * the same scene with its observers (outputs) attached; the other ranks pass NULL. After
 * every step whose observers are due, the summed energy ledger goes to the mirror and its
 * observers are called, so that the files are those of a serial run. An observer whose
 * class says how (version 4, split_request: the stress, energy and tracker outputs) gets
 * what it reads reduced over the ranks; for the others the owned particles' state (x v q w
 * L f t, the walls' forces summed) is gathered into the mirror, and for those that read
 * contacts (contacts, force chains, coast load) the contacts of every rank too: the ranks
 * record theirs at the steps one is due (rank 0 says which, a step ahead) and send them, by
 * global ids, in the serial list's order. The observers' kinds are read here: one added to
 * the mirror later is gathered for. The mirror is prepared here, and finished by
 * floe_world_parallel_finish; the caller destroys it. Collective. */
int floe_world_parallel_outputs(floe_world *w, floe_world *mirror);
/* the end of a run: the final state into the mirror (gathered), its observers' end (files closed);
 * a world without a mirror: nothing. Collective. */
int floe_world_parallel_finish(floe_world *w);

/* An output that every rank writes from its own part of the split world (the vtk output's
 * pieces, floe_vtk_writer_create_piece): o is called on every rank with the split world (its
 * owned particles, ghosts and walls) now (the state at the split, as a prepared world's
 * observers are), after every step at which it is due (period_steps or period_time, the same
 * on every rank) and at its end in floe_world_parallel_finish; its observe and end may call
 * the collective functions of this header. It needs no gather: without a mirror
 * (floe_world_parallel_outputs with NULL) no state goes to rank 0. Outputs that read
 * contacts are refused (FLOE_ENOTSUP). The world takes o (also on failure) and destroys it.
 * Collective: every rank adds its outputs in the same order. An output whose observe fails
 * on some ranks only must agree on the failure itself (the VTK pieces do, through
 * floe_world_parallel_sum): a rank that returns alone leaves the others waiting in the next
 * collective. */
int floe_world_parallel_add_output(floe_world *w, floe_observer *o);
/* the outputs added so (*outs, in the order added) and their number; 0 for an unsplit world.
 * An output restored from a checkpoint before it is added (its begun set,
 * floe_world_checkpoint_restore_split_outputs) is not called at the split: it goes on. */
int floe_world_parallel_own_outputs(const floe_world *w, floe_observer *const **outs);

/* The whole state of a split world gathered into full, an unsplit world on rank 0 (the other
 * ranks pass NULL), so that full can be written as a serial checkpoint
 * (floe_world_parallel_checkpoint_save, floe_checkpoint.h): full must be prepared from the same
 * scene (rank 0's mirror of floe_world_parallel_outputs serves); it receives every particle's
 * state (x v q w L f t by global id, the walls' forces summed), the neighbour list of the whole
 * world (the union of the ranks' lists, each pair once, in the serial list's order, with its
 * contact history, touching flags and warm starts, and the positions at the last build), the
 * clock, the energy ledger summed over the ranks (the watchdog's terms with it) and the step
 * and detection statistics. Its observers are not called. Counted as FLOE_COMM_OUTPUT. An
 * error (a missing or foreign full world, out of memory) is returned on every rank. A serial
 * world: nothing. Collective. */
int floe_world_parallel_collect(const floe_world *w, floe_world *full);

/* the largest of rc over the ranks of comm (a pointer to an MPI_Comm; NULL: MPI_COMM_WORLD),
 * so that every rank takes the same branch after a step that may fail on some ranks only (a
 * file read by every rank); rc itself when MPI is not running or the build has none.
 * Collective. */
int floe_parallel_agree(const void *comm, int rc);

/* After floe_world_step or floe_world_run returned an error on a split world: 1 when every
 * rank returned it (docs/parallel.md, "Errors inside a step": a force evaluation's failure,
 * such as a contact deeper than its radius or a contact law's error, with the failing rank's
 * message on every rank; a particle's closing checks; the energy watchdog; an output's
 * failure). The ranks may then go on together: finish the outputs
 * (floe_world_parallel_finish) and stop. 2 when every rank returned it but the split world
 * is not whole (out of memory on some rank, which may have stopped short of the others on
 * its way to the agreement; a failed decomposition, also the split's first one in
 * floe_world_parallel_init): destroy it without writing it. 0 when the error happened on
 * this rank alone (the few places docs/parallel.md lists), while the other ranks may wait in
 * a collective: stop them (MPI_Abort). 1 for an unsplit world (also after a split that failed
 * before its first decomposition, which leaves the world as it was). Not collective. */
int floe_world_parallel_error_agreed(const floe_world *w);

/* rank and size of the world's communicator (0 and 1 for a serial world); not collective */
int floe_world_parallel_rank(const floe_world *w, int *rank, int *size);

/* particles this rank owns (walls excluded) and ghosts it holds; not collective. A serial
 * world owns all its bounded particles and holds no ghosts. */
int floe_world_parallel_counts(const floe_world *w, int *owned, int *ghosts);

/* global id of local particle i (its index in the world before floe_world_parallel_init; the
 * index itself in a serial world); -1 out of range. Not collective. */
long long floe_world_parallel_gid(const floe_world *w, int i);

/* 1 when local particle i is owned by this rank or is a wall (kept on every rank), 0 for a
 * ghost; not collective */
int floe_world_parallel_is_owned(const floe_world *w, int i);

/* the beam bonds (floe_world_beams.h) and the broken ones among them, summed over the ranks
 * (each bond is held by one rank: the owner of its end of lower global id); a serial world:
 * floe_world_beam_bond_count and floe_world_beam_broken_count. In a split world those two
 * and floe_world_beam_bond count and list this rank's bonds only (their ends as local
 * indices: floe_world_parallel_gid gives the global ids; broken bonds whose other end is on
 * another rank are counted here but not listed), and floe_world_write_beam_bonds_csv writes
 * them. Collective. */
int floe_world_parallel_beam_counts(const floe_world *w, long long *bonds, long long *broken);

/* the energy ledger summed over the ranks (a serial world: floe_world_energy) */
int floe_world_parallel_energy(const floe_world *w, floe_energy *out);

/* sum over the ranks of n doubles (in place); a serial world leaves them */
int floe_world_parallel_sum(const floe_world *w, double *v, int n);

/* The traffic of a split world: what this rank sent to other ranks, by kind. Bytes are the
 * payload (no MPI envelopes); Zoltan's own messages during the bisection are not counted.
 * Point-to-point exchanges (MPI_Alltoall(v)) count exactly what goes to each other rank and one
 * message per rank that gets something; a gather or reduction to rank 0 counts the payload on
 * every other rank (one message); MPI_Allgather the payload once for each other rank; an
 * MPI_Allreduce or MPI_Bcast the payload once (on every rank, or on the root), one message:
 * the traffic MPI's algorithm makes of them is a small multiple of that (about 2x for a ring,
 * log2(ranks)x for recursive doubling). A serial world, or one rank, sends nothing. */
typedef enum floe_comm_kind {
    FLOE_COMM_GHOST,   /* the ghosts' state to the ranks that hold them: at every step without a
                        * rebuild x v q w L f t (22 doubles a ghost); at rebuilds every new
                        * ghost's record (39 doubles), the rank's box (7 doubles) to every rank and
                        * the ghost count (1 int) to every rank */
    FLOE_COMM_REVERSE, /* the forces and torques on ghosts summed back to their owners (6 doubles a
                        * ghost, every step) */
    FLOE_COMM_MIGRATE, /* at rebuilds: owned particles to their new owners (39 doubles each), the
                        * contact history of the pairs they anchor (4 + 8 or 10 doubles
                        * a pair, + FLOE_DETECT_WARM with warm starts), the counts of both (1 int
                        * to every rank, twice) */
    FLOE_COMM_REDUCE,  /* reductions: whether any rank rebuilds (1 int a step), the energy
                        * watchdog's ledger (10 doubles a step), the split's checks,
                        * floe_world_parallel_energy and _sum */
    FLOE_COMM_OUTPUT,  /* outputs: rank 0's word on whether the mirror is due (1 int a step, 2
                        * with a mirror), and when it is the summed ledger and the owned
                        * particles' state gathered on rank 0 (1 + 22 doubles a particle), the
                        * walls' forces (6 doubles a wall), floe_world_parallel_gather and
                        * floe_world_parallel_collect (checkpoints) */
    FLOE_COMM_KINDS
} floe_comm_kind;

typedef struct floe_comm_stats {
    long long bytes[FLOE_COMM_KINDS];    /* payload sent to other ranks */
    long long messages[FLOE_COMM_KINDS]; /* messages (or collective contributions) with payload */
    long steps;                          /* steps over which these were counted */
    long rebuilds;                       /* decompositions among them (the split's included) */
    double owned_steps, ghost_steps;     /* sums over those steps of the particles owned and the
                                          * ghosts held at the step's end */
    double refreshed_steps;              /* the same of the ghosts a step refreshes (those the
                                          * step's work reads: docs/parallel.md, "Ghosts") */
    double force_seconds;                /* this rank's wall seconds in force evaluations (its
                                          * own work between the exchanges: the ranks'
                                          * spread is the load imbalance) */
} floe_comm_stats;

/* this rank's traffic since the split or the last reset (a serial world: zeros); not
 * collective */
int floe_world_parallel_comm(const floe_world *w, floe_comm_stats *out);
/* the counts back to zero (a run measured without the split before it); not collective */
int floe_world_parallel_comm_reset(floe_world *w);
/* the name of a kind ("ghost", "reverse", "migrate", "reduce", "output"); not collective */
const char *floe_comm_kind_name(floe_comm_kind k);

/* the positions and velocities of every owned particle gathered on rank 0 into x[3 gid] and
 * v[3 gid] (N = the particle count of the world before the split, walls included; the walls'
 * entries are left as they are); x or v may be NULL; the arrays are used only on rank 0 */
int floe_world_parallel_gather(const floe_world *w, double *x, double *v, int N);

#endif
