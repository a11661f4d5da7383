/* par_internal.h - the MPI decomposition's state (docs/parallel.md). Internal to
 * core/parallel and its callers in core/integrators; compiled only with FLOE_HAVE_MPI.
 *
 * Local store layout on every rank: walls [0, nrep) (unbounded geometries, the same on every
 * rank, in global-id order), owned particles [nrep, nrep + nown) in global-id order, ghosts
 * [nrep + nown, n) in the order received (by source rank, then the source's order). Ghosts
 * carry motion FLOE_FIXED so that the integrators leave them and the neighbour list pairs
 * them neither with each other nor with walls; their true motion shows in their mass: a
 * ghost of a free particle has inv_mass > 0, one of a fixed or kinematic particle 0 (the list
 * pairs the latter with no non-free owned particle, as in one process). */
#ifndef FLOE_PAR_INTERNAL_H
#define FLOE_PAR_INTERNAL_H

#ifdef FLOE_HAVE_MPI
#include <mpi.h>
#include "floe_parallel.h"
#include "world_internal.h"

/* one particle as it travels: every array of the particle store (particle_store.h) and the
 * global id, all as doubles (integers below 2^53 are exact) */
enum { FLOE_PAR_REC = 39 };
/* a particle's state, what a ghost refresh and the mirror gather carry: x v q w L f t */
enum { FLOE_PAR_FWD = 22 };

typedef struct floe_par {
    MPI_Comm comm;
    int rank, size;
    struct Zoltan_Struct *zz;
    int ntotal;              /* particles before the split (global ids 0 .. ntotal - 1) */
    int nrep, nown, nghost;
    long long *gid; int gid_cap; /* per local particle */
    /* the ghosts this rank sends: local indices grouped by destination rank (scount[r] of
     * them to rank r, from sdispl[r]); and those it receives (rcount, rdispl) */
    int *send_idx; int nsend, send_cap;
    int *scount, *sdispl, *rcount, *rdispl;
    /* the ghosts a step refreshes (floe_par_choose_refreshed; docs/parallel.md, "Ghosts"): of
     * those received at the last decomposition, the ones this rank's work between
     * decompositions reads (an end of a listed pair). fsend: the
     * owned particles sent at each refresh, grouped by destination; frecv: the ghosts (local
     * indices) they fill, grouped by source; fcnt: their counts and displacements (send counts,
     * send displacements, receive counts, receive displacements: 4 size, in scount's block).
     * Valid for the neighbour list of build fgen (nl.gen) alone. */
    int *fsend, *frecv; int nfsend, nfrecv;
    int *fcnt;
    long fgen;               /* -1: no subset (every ghost is refreshed) */
    int refresh_all;         /* a force stage may build the list again on one rank alone, from
                                every ghost's present state (a bond that breaks: beam bonds, PD
                                bodies; forces.c; a user's provider may not ask for it under
                                MPI): no subset, every ghost refreshed at every step. Set at the
                                split from the whole world: the same on every rank */
    size_t fsend_cap, frecv_cap;
    int *gcnt;               /* 2 size: counts and displacements of a gather to rank 0 */
    /* scratch allocated at the split with the counts above, so that the exchanges of a step
     * and the first collective of a route or of the ghosts' choice never allocate (a rank
     * that failed alone there would leave the others waiting): the ghost exchanges' counts
     * and displacements in doubles (4 size), a route's (5 size), the ranks' boxes (8 size) */
    int *gc, *rt;
    double *boxes;
    double *sbuf, *rbuf; size_t sbuf_cap, rbuf_cap;
    struct floe_world *mirror; /* rank 0 with outputs: the unsplit world whose observers write
                                  the gathered state (floe_world_parallel_outputs) */
    int has_mirror;          /* every rank: rank 0 has a mirror (set by floe_world_parallel_outputs) */
    MPI_Op sum_min;          /* the energy watchdog's reduction (floe_par_watchdog_values): an
                                element of wd_type, sums then two minima; have_sum_min: created */
    MPI_Datatype wd_type;
    int have_sum_min;
    struct floe_observer **outs; int nouts; /* every rank's own outputs (floe_world_parallel_add_output) */
    int any_nonround;        /* a bounded particle of the world is not a sphere (disc), or the
                                world has beam bonds (their bending reads orientations): the
                                ghost refresh carries orientations (floe_par_forward_comm).
                                Set at the split from the whole world: the same on every rank
                                (a rank's own bond count is not) */
    long rebuilds;           /* decompositions (RCB + migration + ghosts) */
    long long migrated;      /* particles this rank sent to another owner, over the run */
    floe_comm_stats traffic; /* the traffic (floe_world_parallel_comm) */
    /* beam bonds (par_beams.c): records exported at the split (bout), received at a
     * decomposition until the new store exists (bin), broken bonds whose other end is not
     * here (bpark); the halo's reach (the longest intact bond at the decomposition); the
     * neighbour list's rebuild count then (a list rebuilt since, after a bond broke, asks
     * for a decomposition at the next step) */
    double *bout, *bin, *bpark; int nbout, nbin, npark;
    int blost;               /* bonds whose anchor was not owned at the export (internal error) */
    double bout_reach, bond_reach;
    long nl_rebuilds;
    /* the force stages' per-particle rows received at a decomposition (par_forcing.c):
     * records gid + the rows of every registered array, until the new store exists */
    double *ppin; int nppin;
    /* the servo walls' partial and gathered measures (floe_par_servo_totals): allocated at
     * its first call (agreed then), kept */
    double *servo_buf; size_t servo_cap;
    /* the load balance (floe_world_parallel_set_balance): the mode; this rank's seconds of
     * its own work since the last decomposition (force evaluations, and its outputs' and rank
     * 0's mirror observers' evaluations: what the others wait for); under FLOE_BALANCE_TIME, each rank's
     * measured seconds per unit of RCB weight (smoothed over decompositions; 0: none yet) */
    int balance;
    double busy;
    long long *rcb_sum;      /* 2 (2 size + 1): the parts' weights under a cut and a failure flag, this rank's and the sums (rcb_imbalance) */
    double rcb_tried;        /* the kept directions' imbalance when fresh ones last did no better (0: none) */
    double *cost;            /* 2 size: the costs, then a gather's scratch */
    int *bal_ids;            /* 4 size: the parts 0 .. size - 1 twice, then the weight index of each (0s, 1s) */
    float *bal_sz;           /* 2 size: the parts' target sizes, for each criterion (the same) */
    /* PD bodies (par_pd.c): the split's per-body index and masks (w->pd_split points here),
     * the halo's reach for their bonds (the longest acting bond at the last decomposition) */
    struct floe_pd_split *pd_split;
    double pd_reach;
    int *pd_counts;          /* 4 size: the PD ghost exchanges' counts beyond FLOE_PAR_PD_SYNC_RANKS */
    /* each ghost's motion on its owner (w->gmotion points here; the ghost is FLOE_FIXED) */
    unsigned char *gmotion; int gmotion_cap;
    /* rank 0's mirror observers as every rank knows them (floe_world_parallel_outputs): their
     * count, and per observer its split kind (0: gathered; floe_observer_class.split_request),
     * group and its ids (ids[ids_at[k] .. ids_at[k + 1])); the reduced outputs' buffers */
    int nmobs, *mkind, *mgroup, *mids_at, *mdue; long long *mids;
    double *red_buf; size_t red_cap;
} floe_par;

/* the load balance's mode (floe_world_parallel_set_balance; its scratch allocated at the
 * first call): FLOE_OK or FLOE_ENOMEM */
int floe_par_set_balance(floe_par *P, int mode);
/* the traffic accounting (floe_comm_stats' conventions; nothing with one rank): */
/* bytes in msgs messages of kind k */
void floe_par_count(floe_par *P, int k, long long bytes, long long msgs);
/* an exchange in which rank r gets count[r] items of item_bytes: the items to the other
 * ranks, one message to each that gets any */
void floe_par_count_v(floe_par *P, int k, const int *count, long long item_bytes);
/* an MPI_Allreduce of bytes (every rank), an MPI_Bcast (the root's share), a gather or
 * reduction to rank 0 (the other ranks' share), an MPI_Allgather or MPI_Alltoall of bytes to
 * each rank */
void floe_par_count_allreduce(floe_par *P, int k, long long bytes);
void floe_par_count_bcast(floe_par *P, int k, long long bytes);
void floe_par_count_to_root(floe_par *P, int k, long long bytes);
void floe_par_count_all(floe_par *P, int k, long long bytes);

/* decomp.c: the pieces, on the world's store */
/* byte buffers of at least n doubles (0 or FLOE_ENOMEM) */
int floe_par_reserve(double **buf, size_t *cap, size_t n);
/* n doubles of every rank to rank 0 in rank order (MPI_Gatherv; traffic counted as kind k):
 * rank 0 gets *out (malloc'ed, *tot doubles), the others NULL and 0. FLOE_ENOMEM on every
 * rank when rank 0 cannot hold them (nothing is sent then; counts above INT_MAX included).
 * Collective. */
int floe_par_gather_root(floe_par *P, int k, const double *sb, int n, double **out, int *tot);
/* the whole record of local particle i (FLOE_PAR_REC doubles: gid, then the state as
 * floe_par_pack_state writes it, then the constant fields) */
void floe_par_pack(const floe_particles *p, int i, long long gid, double *r);
void floe_par_unpack(floe_particles *p, int i, const double *r, long long *gid);
/* the state of local particle i: x3 v3 q4 w3 L3 f3 t3 (FLOE_PAR_FWD doubles) */
void floe_par_pack_state(const floe_particles *p, int i, double *r);
void floe_par_unpack_state(floe_particles *p, int i, const double *r);
/* send nitems items of m doubles, item k to rank dest[k] (counted as kind); *out (malloc'ed, caller frees)
 * receives *nout items, ordered by source rank then the source's order. Its failures are
 * every rank's: nitems < 0 (this rank failed before the route; nothing sent) or a rank out
 * of memory for its buffers makes every rank return FLOE_ENOMEM (*out NULL). Collective */
int floe_par_route(floe_par *P, int kind, const double *items, const int *dest, int nitems, int m, double **out, int *nout);
/* destination rank of each owned particle by recursive coordinate bisection (Zoltan, weights
 * 1): dest[k] for owned particle nrep + k */
int floe_par_rcb(floe_world *w, floe_par *P, int *dest);
/* send the owned particles with dest[k] != rank to their new owner and keep those received:
 * the owned particles become [nrep, nrep + nown) sorted by global id; ghosts are dropped.
 * A failure of its route is every rank's; one after it (the new store) this rank's alone:
 * pass it to floe_par_ghosts */
int floe_par_migrate(floe_world *w, floe_par *P, const int *dest);
/* the ghosts: every owned particle whose bounding sphere, grown by the largest bounding radius
 * of a rank's owned particles and the skin, reaches the box of that rank's owned centres is
 * sent to it as a ghost (appended at nrep + nown, motion FLOE_FIXED). bad: this rank failed
 * before (floe_par_migrate). Every failure, bad included, is every rank's (FLOE_ENOMEM) */
int floe_par_ghosts(floe_world *w, floe_par *P, double skin, int bad);
/* the largest of rc over the ranks (an MPI_Allreduce, counted as a reduction): a failure on
 * one rank made every rank's before the next collective */
int floe_par_agree(floe_par *P, int rc);
/* refresh the ghosts from their owners: x v w always; q when a bounded particle is not round
 * or beam bonds read it; f when a law has a linear dashpot (its end-of-step velocity reads
 * the ghost's acceleration, pair_an_ext); a ghost's L and t are never read (the owner
 * integrates it). every = 0: the ghosts the step's work reads (P->fsend, P->frecv) while the
 * list is the one they were chosen for, else all; every = 1: all (a decomposition's own
 * refreshes, before the ghosts are chosen again) */
int floe_par_forward_comm(floe_world *w, floe_par *P, int every);
/* after a decomposition's list (collective; allocates nothing: floe_par_ghosts reserved the
 * room): the ghosts this rank reads, told to their owners (a byte a ghost), and the
 * refreshed subsets (P->fsend, P->frecv) of both sides kept for this list */
void floe_par_choose_refreshed(floe_world *w, floe_par *P);
/* the ghosts a step refreshes now (the subset's size, or every ghost held) */
int floe_par_nrefreshed(const floe_world *w, const floe_par *P);
/* the doubles a ghost refresh carries a ghost: 9, + 4 (q), + 3 (f) */
int floe_par_fwd_doubles(const floe_world *w, const floe_par *P);
/* add the ghosts' forces and torques to their owners (the refreshed ghosts while the list
 * is the one they were chosen for: no other ghost is an end of anything that exerts a force,
 * so the others' forces are zero) */
int floe_par_reverse_comm(floe_world *w, floe_par *P);
/* 1 when a law of the world has a linear dashpot (its end-of-step velocity reads the
 * particles' last accelerations, forces.c pair_an_ext): the same on every rank */
int floe_par_laws_dashpot(const floe_world *w);
/* the owners' rows a[i * m .. i * m + m) copied to their ghosts' rows (a holds p->n rows;
 * NULL on a rank that holds no particle). Collective */
int floe_par_forward_rows(floe_par *P, double *a, int m);
/* local index of global id g (-1: not here), from a hash table of the local particles' ids
 * (open addressing, at most half full; the first of equal ids kept) built by
 * floe_par_index_build over locals [0, n) */
typedef struct floe_par_index { long long *key; int *loc; int n, mask; } floe_par_index;
int floe_par_index_build(const floe_par *P, int n, floe_par_index *ix);
int floe_par_index_find(const floe_par_index *ix, long long g);
void floe_par_index_free(floe_par_index *ix);
/* par_beams.c: beam bonds follow their anchor (the end of lower global id). At the split,
 * before the store is reordered: the bonds whose anchor is in mine (by global id = index)
 * set aside. At a decomposition, after RCB and before the migration: the ghosts refreshed,
 * the bonds (or those set aside) and the parked ones routed to the new owner of their
 * anchor (dest of the owned particles), the halo's reach reduced over the ranks. After the
 * ghosts: the set rebuilt from what arrived (FLOE_EINVAL with a message, on every rank,
 * when an intact bond's end is not here) */
int floe_par_beams_split(floe_world *w, floe_par *P, const unsigned char *mine);
int floe_par_beams_out(floe_world *w, floe_par *P, const int *dest);
int floe_par_beams_in(floe_world *w, floe_par *P);
/* the bonds' records gathered on rank 0 into the mirror M's bonds (by global ids), for its
 * outputs; FLOE_EINVAL on rank 0 when they do not match M's bonds */
int floe_par_beams_gather(floe_world *w, floe_par *P, struct floe_world *M);
/* par_pd.c: PD bodies split over the ranks (docs/parallel.md, "PD bodies across ranks").
 * unsupported: 1 and what (for the refusal) when the world's PD bodies cannot run split.
 * split_reach: at the split, before the store is reordered: the halo's reach from the whole
 * world. sync: at a decomposition, before the bisection: the bonds broken since the last one
 * sent to every rank, the plastic stretches and the body-force regions' last forces made
 * whole, the halo's reach measured. out: after the bisection, before the migration: the
 * leaving points' last bond forces and s0 to their new owners. index: after the ghosts: each
 * body's local points, masks and pd_of (FLOE_EINVAL on every rank when an intact bond of an
 * owned point lost its other point). s0_refresh: after a ghost refresh, the ghosts' s0 from
 * their owners (alpha). gather: the bodies' state into rank 0's unsplit world M (outputs,
 * checkpoints). All collective. */
#define FLOE_PAR_PD_SYNC_RANKS 64
int floe_par_pd_unsupported(const floe_world *w, char *what, size_t len);
int floe_par_pd_split_reach(floe_world *w, floe_par *P);
int floe_par_pd_sync(floe_world *w, floe_par *P);
int floe_par_pd_out(floe_world *w, floe_par *P, const int *dest);
int floe_par_pd_index(floe_world *w, floe_par *P);
int floe_par_pd_s0_refresh(floe_world *w, floe_par *P);
int floe_par_pd_gather(floe_world *w, floe_par *P, struct floe_world *M);
/* par_forcing.c: the force stages' per-particle arrays (world_internal.h pps) moved with
 * their particles: at the split (newidx[old] = new local index or -1, nnew rows), at a
 * decomposition (out: after RCB, before the migration, to dest of the owned particles; in:
 * after the ghosts), and by global id into rank 0's unsplit world full at a checkpoint
 * (collective; errors agreed by every rank) */
/* 1 for a force provider that runs split (par_forcing.c): the world's body forces, contacts,
 * beam bonds, servo walls, linear_drag, the ice drags and Coriolis (core/forcing), and a
 * user's provider whose class declares per-particle forces (floe_provider.h, version 2) */
int floe_par_provider_supported(const floe_world *w, const struct floe_provider *pv);
/* at the split: the arrays of nnew rows (*fresh; NULL without arrays), allocated before the
 * ranks agree on the split's memory; then installed with the rows of the particles kept
 * (newidx: old index -> new, -1 dropped) when keep, or freed */
int floe_par_pp_split_alloc(const floe_world *w, int nnew, double ***fresh);
void floe_par_pp_split(floe_world *w, double **fresh, const int *newidx, int nold, int nnew, int keep);
int floe_par_pp_out(floe_world *w, floe_par *P, const int *dest);
int floe_par_pp_in(floe_world *w, floe_par *P);
int floe_par_pp_collect(floe_world *w, floe_par *P, struct floe_world *full);
/* frees the state (Zoltan's too) */
void floe_par_free(floe_par *P);

#endif
#endif
