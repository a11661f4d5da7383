/* world_internal.h - the world's data, shared by the library modules (core, contact,
 * observers, cli). Users go through floe_world.h; this layout may change. */
#ifndef FLOE_WORLD_INTERNAL_H
#define FLOE_WORLD_INTERNAL_H

#include <stdint.h>

#include "floe_world.h"
#include "floe_view.h"
#include "floe_state.h"
#include "floe_kdtree.h"
#include "floe_observer_base.h"
#include "floe_detect.h"
#include "particle_store.h"
#include "floe_world_beams.h"
#include "floe_cell.h"
#include "periodic_state.h"


/* a motion callback: particle is its local index (renumbered at an MPI split; -1 when on
 * another rank), gid its index in the unsplit world (where a split world finds it after a
 * migration, step.c motion_of) */
typedef struct floe_motion_cb { int particle; floe_motion_fn fn; void *user; long long gid; } floe_motion_cb;

/* One active contact of the current step (the public floe_contact_info, floe_view.h). */
typedef floe_contact_info floe_contact_rec;

/* Neighbour list with Verlet skin and per-pair history kept across rebuilds. */
typedef struct floe_neighbor_list {
    floe_kdtree *tree;       /* during a build's search only (NULL otherwise) */
    int npairs, cap;
    int *pi, *pj;            /* candidate pairs, i < j (MPI: by global id), walls included,
                              * except a bounded particle and a wall: the bounded one is i, so
                              * i > j where the wall's index is lower (neighbor.c push_pair) */
    int *sub;                /* piece pair FLOE_SUB(a, b) of compound bodies (0 otherwise) */
    int *img;                /* periodic cell: image code of j (floe_img_encode); NULL without */
    const floe_cell_state *cell; /* the world's cell (NULL: none), set before a build */
    double Hb[9];            /* the cell at the last build */
    double rmax_b;           /* the largest bounding radius at the last build */
    double *warm;            /* npairs * FLOE_DETECT_WARM warm-start state (ADMM/LP), allocated
                                only when the scene has such pairs (use_warm) */
    int use_warm;
    double *hist;            /* npairs * hs: each entry's history (floe_contact.h) */
    int hs;                  /* doubles per entry: FLOE_MAX_HISTORY, or FLOE_HIST_COMPACT where
                                the world's laws and shapes allow (floe_world_hist_layout) */
    unsigned char *touching; /* pair was in contact last step */
    double *x_build;         /* 3n positions at the last build */
    double *r_build;         /* n bounding radii at the last build */
    double *q_walls;         /* 4 per wall: orientation at the last build */
    int n_build;
    double skin;
    long rebuilds;
    long gen;                /* builds so far, failed ones included (threads' pair index, forces.c) */
    int *walls; int nwalls;  /* particles with unbounded geometry (planes) */
    /* threads of the build's search (neighbor.c; set by the world: floe_world_loop_threads)
     * and their buffers of found entries (freed after each build) and tree-query scratch */
    int threads;
    struct floe_nl_found *found; int nfound;
    /* optional: pairs for which exclude(ctx, i, j) is non-zero are never listed (the bonded
     * family members of a peridynamic body) */
    int (*exclude)(const void *ctx, int i, int j);
    const void *exclude_ctx;
    /* the same for a pair through an image of a periodic cell (PD bonds across the faces;
     * NULL: image pairs are never excluded) */
    int (*exclude_image)(const void *ctx, int i, int j, const int n[3]); /* j's image x_j + H n */
    /* MPI domain decomposition (core/parallel, docs/parallel.md): particles from own_hi on are
     * ghosts; a pair of a ghost and an owned particle is listed only when the owned one has
     * the lower global id gid[] (the other rank lists it otherwise), ghost pairs never.
     * gid NULL: serial. Walls (replicated on every rank) are [0, rep_hi), the owned particles
     * [rep_hi, own_hi), each range sorted by gid */
    const long long *gid;
    int own_hi, rep_hi;
    /* optional (set by floe_world_nl_build when a law is "none"): none[a * nmat + b] = 1 for
     * the materials a, b under the law "none", whose pairs are never listed; inert[a] = 1 when
     * a's particles touch nothing present: they search for no pairs */
    const unsigned char *none, *inert;
    int nmat;
} floe_neighbor_list;

/* The particle loops' split over threads (the drift and the kick, core/integrators/step.c):
 * part t takes the blocks [cut[t], cut[t + 1]) of nb, in order; the parts' sizes follow the
 * threads' measured seconds per block (two cores need not run at one speed: the VM's two
 * vCPUs differ by up to 1.6x at these loops, bench/RESULTS.md issue 14 session 16). Which
 * thread updates which particle never changes the bits (each block's sums are added in block
 * order). */
typedef struct floe_loop_split {
    int nt, nb, cap; /* the split below is for nt parts over nb blocks */
    int *cut;        /* nt + 1 */
    double *spb;     /* per part: seconds per block, smoothed (0: not measured yet) */
    double *sec;     /* per part: seconds of this step's loops so far */
} floe_loop_split;

struct floe_world {
    floe_world_def def;
    char err[1024];
    floe_particles p;
    floe_geometry **geoms; int ngeoms, geoms_cap;
    int pieces_seen, any_pieces; /* geoms[0 .. pieces_seen) looked at: any of them a compound */
    floe_material *mats; int nmats, mats_cap;
    floe_contact_law **laws;  /* nmats x nmats (symmetric, owned once via law_owned) */
    /* pairs under the law "none" stay out of the list (world_exclude, nl.inert): a law set
     * after a build makes the next step rebuild (law_gen != nl_law_gen) */
    long law_gen, nl_law_gen;
    /* the history stride the laws and shapes need (floe_world_hist_layout), for law_gen
     * hs_law_gen and geoms[0 .. hs_ngeoms) (hs_need 0: not yet looked at) */
    int hs_need, hs_ngeoms; long hs_law_gen;
    unsigned char *inert; int inert_cap; /* nl.none and nl.inert (world.c inert_materials) */
    floe_contact_law **law_owned; int nlaws_owned, law_owned_cap;
    floe_motion_cb *motions; int nmotions, motions_cap;
    int *motion_idx; int motion_idx_n, motion_idx_cnt; /* particle -> motion callback (world.c) */
    floe_body_force_fn body_force; void *body_force_user;
    int body_force_threaded; /* floe_world_set_body_force_threaded: called from the threads */
    double *fb_old; int fb_n;   /* last callback force and torque per particle (6n) */
    double *kin_old; int kin_old_n; /* force and torque of kinematic particles at the step start
                                       (6 a particle, kin_old_n rows; a pps row: under MPI it moves
                                       with its particle at a decomposition inside a step) */
    unsigned char *kinb; size_t kinb_cap; /* velocity Verlet: per block of particles, any kinematic
                                             one in it (step.c; its loops over them skip the rest) */
    /* per-particle state of the force stages (the last forces of a trapezoid work, a held
     * drag): arrays of m doubles a particle, indexed by local particle and grown by their
     * owners, registered with floe_world_pp_attach so that the MPI decomposition moves each
     * row with its particle (core/parallel/par_forcing.c); *n: the rows allocated */
    struct floe_pp_state { double **arr; int *n; int m; } *pps; int npps, pps_cap;
    floe_state **states; int nstates, states_cap;
    floe_observer **obs; int nobs, obs_cap;
    floe_neighbor_list nl;
    floe_contact_rec *contacts; int ncontacts, contacts_cap;
    double time, dt, dt_crit;
    double v_expected;        /* relative speed used by the time-step estimate */
    long step;
    double t0; long step0;   /* time and step at prepare: time = t0 + (step - step0) dt */
    int prepared;
    int record_contacts;      /* the user asked to keep w->contacts every step */
    int obs_need_contacts;    /* some observer reads w->contacts when it is due */
    int contacts_valid;       /* w->contacts holds every contact of the last evaluation */
    int last_step_of_run;     /* floe_world_run's final step: record for the end() flush */
    int orient_mode;          /* floe_orientation_mode (floe_world_set_orientation) */
    int orient_extra;         /* outputs outside w->obs read orientations (MPI: the pieces,
                               * rank 0's mirror; set by core/parallel) */
    int par_contacts;         /* MPI (core/parallel): rank 0's mirror has outputs that read
                               * contacts: bit 0, the same on every rank; bit 1, one of them is
                               * due at the next step (floe_par_observe decides, every rank) */
    int finished;
    floe_energy energy;
    floe_detect_state det;     /* detect.c's statistics and scratch (floe_detect_ctx.det) */
    /* the separation cache (forces.c sep_update; floe_detect_ctx.sep), only in scenes with
     * boxes, convex or compound shapes, without a periodic cell or MPI: per particle its
     * motion bound (the sum of |dx| + radius x turned angle + |dr| over the evaluations since
     * the reset) and its pose then (x, q, radius: 8 doubles); per list entry a gap and the
     * pair's bound when it was measured. Reset at each list build; a checkpoint carries it
     * (section SEPC), a restore without it resets it (sep_n = -1) */
    double *sep_d, *sep_pose, *sep_pair;
    int *sep_geom;
    int sep_n, sep_np, sep_on;
    int mf_cache_off;         /* 1: polytope manifolds without their corner cache (tests: the same bits) */
    int lanes_off;            /* 1: sphere pairs through the general pair body, not the fused lanes
                                 (tests: the same bits) */
    long sep_gen;
    /* peridynamic bodies (peridynamics/floe_pd.h): body k's points are the particles
     * pd_first[k] .. pd_first[k] + n - 1; nothing is allocated without PD bodies */
    struct floe_pd_body **pd; int *pd_first; int npd, pd_cap;
    int *pd_of;              /* n (only with PD bodies): body index of each particle or -1 */
    double *pd_fold;         /* 3 x (PD points): last PD force, for the energy ledger */
    double *pd_fnew;         /* the same size: this evaluation's (swapped with pd_fold) */
    double *pd_eold;         /* npd: last PD elastic energy */
    int pd_npts;
    int pd_npts_alloc;       /* particles covered by pd_of */
    /* PD boundary regions (floe_world_pd_region); none allocated without them */
    struct floe_pd_bc_rec **pd_bc; int npd_bc, pd_bc_cap;
    long long *pd_nbroken_seen; /* npd: broken bonds of each body when the contact list was
                                   last checked for newly broken pairs (floe_pd_after_forces) */
    /* PD bodies of a world split over MPI ranks (core/parallel/par_pd.c fills it at every
     * decomposition; NULL unsplit): pd_first[k] is then the global id of body k's first
     * point, and a point's body-local index its global id less that */
    struct floe_pd_split *pd_split;
    /* time integration (core/integrators, issue #5): critical-step estimates, integrators,
     * adaptive steps, staggered PD-DEM; scratch only when a scheme needs it */
    floe_dt_estimates dte;    /* at prepare */
    double *dt_part;          /* n: critical estimate of each particle (limiting kinds) */
    double lf_dt_prev;        /* leapfrog: the previous step (0: velocities synchronised) */
    double *ibuf; size_t ibuf_cap; /* integrator scratch (RK2's start state) */
    /* MPI: RK2's closing values per particle (step.c RK2_*: v_n, F_mid, x_n, the kept dashpot
     * accelerations), rk2_n rows: written before the step's end rebuild and read after it,
     * registered as a per-particle row for that rebuild only, so that they travel with their
     * particles through a decomposition (one process reads its scratch instead) */
    double *rk2; int rk2_n;
    double *stag; int stag_n;      /* the staggered PD-DEM scheme's rows (core/integrators/step.c
                                      stag_rows; registered as a force stage's pps), stag_n rows */
    double *dash_a; size_t dash_cap; /* 3n: each particle's acceleration f / m of the last force
                                   evaluation, copied from p->f as an evaluation begins when a
                                   linear dashpot asks for it (forces.c, floe_contact.an_ext) */
    int dash_on;              /* dash_a holds this evaluation's copy */
    int dash_keep;            /* the last evaluation was an RK2 probe: keep its copy */
    int drift_cleared;        /* velocity Verlet's or leapfrog's drift set the free particles'
                                 forces to m g and their torques to 0 (and their dash_a first,
                                 when the evaluation takes them): forces_clear sees to the others
                                 alone; set for the step's force evaluation only (step.c, forces.c) */
    long st_drift_clears;     /* steps whose drift did so (tests/test_drift_clear.c) */
    /* the sphere batches (forces.c sph_flush_lanes) on one thread: [0] all, then those that
     * took a rare case's full form: [1] a spring turned by more than 0.01 rad, [2] a linear
     * contact's first evaluation, [3] a slipping contact (tests/test_sphere_path.c) */
    long st_lanes[4];
    struct floe_snapshot *snap; /* adaptive: the state at the start of the trial step (owned by
                                   the controller, core/integrators/adaptive.c; freed by
                                   floe_world_destroy through snap_free) */
    void (*snap_free)(struct floe_snapshot *snap);
    int track_depth;          /* forces.c records eta_depth (adaptive) */
    double eta_depth;         /* max over contacts of |v_n| dt / min(R_i, R_j) at the last evaluation */
    double elastic_contact, elastic_pd; /* the two parts of energy.elastic */
    int pd_sub, pd_every;     /* staggered: PD sub-steps per step, steps per PD step */
    long pd_cycle;            /* staggered, every > 1: steps into the current PD cycle (kept across
                                 re-prepares so an open cycle is closed, not reopened) */
    double dt_next;           /* adaptive: the step proposed for the next step */
    double dt_lo, dt_hi;      /* adaptive: the bounds in use */
    double dt_cap;            /* adaptive: the step may not pass this (floe_world_run's end) */
    floe_step_stats st;
    /* energy watchdog (core/integrators/watchdog.c energy_watchdog): the dissipation of each PD body's
     * bonds since it was added (npd), the contact with the most negative dissipation over
     * its life at the last advancing evaluation (forces.c, reset there) and over the run */
    double *pd_diss; int pd_diss_n;
    double *pd_diss_sum; /* the watchdog's copy to sum over the ranks (pd_diss_n; MPI): no allocation in a step */
    double wd_pair_min; int wd_pair_i, wd_pair_j;
    double wd_worst; int wd_worst_i, wd_worst_j;
    double wd_scale;          /* the energy scale: largest K + elastic + |work| seen */
    double wd_gscale;         /* its floor: sum of m |g| R over the free particles (prepare) */
    double wd_shadow, wd_shadow0; /* energy of the last closing half kick, now and at prepare
                                 (core/integrators/step.c shadow_term; 0 without a closing half kick: RK2) */
    double wd_created;        /* largest created fraction of the scale seen */
    long wd_step;             /* step at which the tolerance was passed (-1: not yet) */
    char wd_msg[1024];
    /* beam bonds (contact/bonds/floe_beam.h, issue #5); NULL without bonds */
    struct floe_beam_set *beams; /* contact/bonds/beam_set.h */
    /* the force providers of the staged step (floe_provider.h), built at prepare, and the
     * byte buffer of their state for RK2's midpoint probe */
    struct floe_provider **prov; int nprov, prov_cap;
    /* user providers (floe_world_add_provider, providers.c), owned by the world; prov
     * holds them too once prepared */
    struct floe_provider **uprov; int nuprov, uprov_cap;
    const struct floe_provider *servo_pv; /* the servo walls' provider among uprov (servo_walls.c
                                             sets it; orientation_refresh knows it reads no
                                             orientation), NULL without servo walls */
    unsigned char *pbuf; size_t pbuf_cap;
    floe_cell_state *cell;    /* periodic cell (floe_cell.h, cell.c); NULL without */
    int obs_muted;            /* observers not called (the RVE's probes, core/integrators/rve.c) */
    /* threads (floe_par.h, docs/parallel.md) */
    int nthreads;             /* asked for (floe_world_set_threads; 0: OpenMP's default) */
    int par_grain;            /* loops over fewer items run on one thread (the same bits either way) */
    struct floe_par_scratch *thr; /* the threaded contact stage's buffers (forces.c); NULL until used */
    double *red; size_t red_cap;  /* per-block partial sums of threaded loops (floe_world_reduce_buf) */
    floe_loop_split ls;           /* the drift's and the kick's parts (floe_loop_split_cuts) */
    /* MPI domain decomposition (core/parallel/par_internal.h); NULL: serial. Freed through
     * par_free by floe_world_destroy */
    struct floe_par *par;
    /* a split world's ghosts (from nl.own_hi on): each one's motion on its owner (a ghost is
     * FLOE_FIXED here: its owner integrates it), set by core/parallel at each decomposition */
    const unsigned char *gmotion;
    void (*par_free)(struct floe_par *par);
    /* a split world: the last error a step returned was agreed by every rank (each returned
     * it: core/parallel floe_par_agree_error): 1, or 2 when the state is not whole (out of
     * memory: a rank may have stopped short on its way to the agreement; a failed
     * decomposition); 0 otherwise; reset at each step */
    int err_agreed;
    /* a split world's step close (core/integrators step.c step_close): with close_defer set
     * (floe_world_step, a fixed step with the energy watchdog on) its agreement is not a
     * reduction of its own but rides with the watchdog's (floe_par_watchdog_values):
     * close_pending says the close was reached, close_rc is this rank's outcome there */
    int close_defer, close_pending, close_rc;
    /* what the integrator sets after a close that passed on this rank (the ledger's step
     * sums, the watchdog's conserved form, leapfrog's last step), as it was at the close:
     * put back when another rank failed there, so that every rank holds what one process
     * holds after a failed close (the state written at the failure) */
    floe_energy close_energy;
    double close_shadow, close_lf;
};

/* the index of local particle i in the unsplit world, as the messages name it (the serial
 * run's index): its global id on a split world (nl.gid, set at each decomposition), i
 * otherwise */
static inline long long floe_world_pid(const floe_world *w, int i) {
    return w->nl.gid && i >= 0 && i < w->p.n ? w->nl.gid[i] : (long long)i;
}

/* 1 when state object s runs on a world split over MPI ranks (state.c: the built-in
 * classes, which every rank keeps and advances alike; a user's class may read particles by
 * index, which a split renumbers) */
int floe_state_splits(const floe_state *s);

/* scratch for n per-block partial sums (NULL: out of memory), kept by the world */
double *floe_world_reduce_buf(floe_world *w, size_t n);
/* the parts of a particle loop over nb blocks on nt threads (floe_loop_split; NULL: out of
 * memory, split evenly then): even at first and whenever nt or nb changes, then cut again by
 * floe_loop_split_update */
const int *floe_loop_split_cuts(floe_world *w, int nt, int nb);
/* after the step's particle loops (every part's seconds in w->ls.sec): the seconds per block
 * smoothed (a quarter of each new measure), and when the slowest part is predicted to take
 * 5 % more than the mean, the parts cut again in proportion to the threads' speeds */
void floe_loop_split_update(floe_world *w);
/* part `part`'s blocks [*b0, *b1) of nb blocks on nt parts: by the cut, or evenly when cut is
 * NULL (as schedule(static)) */
static inline void floe_loop_split_range(const int *cut, int nb, int nt, int part, int *b0, int *b1) {
    *b0 = cut ? cut[part] : (int)((long long)nb * part / nt);
    *b1 = cut ? cut[part + 1] : (int)((long long)nb * (part + 1) / nt);
}
/* memcpy on the world's threads (from 2 MiB on: one chunk a thread; the same bytes) */
void floe_world_copy(const floe_world *w, void *dst, const void *src, size_t bytes);
/* memset to 0 on the world's threads (from 512 KiB on) */
void floe_world_zero(const floe_world *w, void *dst, size_t bytes);
/* threads for a loop over `items` items (1 below the grain or without OpenMP) */
int floe_world_loop_threads(const floe_world *w, long items);
/* A particle loop on the world's threads (the forcing providers): fn(ctx, i0, i1, sums) over
 * the blocks [i0, i1) of FLOE_PAR_BLOCK particles of [0, n), each block writing its nsum
 * (1-4) partial sums, which are added in block order into sum: the same bits for any number
 * of threads (one block: the plain running sum). fn writes only its block's particles' rows.
 * FLOE_ENOMEM (nothing run) when the blocks' scratch cannot be had. */
typedef void (*floe_block_fn)(void *ctx, int i0, int i1, double *sums);
int floe_world_blocks(floe_world *w, int n, int nsum, floe_block_fn fn, void *ctx, double *sum);
/* errors of the calling thread go to buf (NULL: back to the world's): a threaded stage keeps
 * each thread's first error and reports the one a serial run would have met first */
void floe_world_error_to(char *buf, size_t len);
/* the threaded contact stage's buffers (forces.c), kept across evaluations by the world */
/* the contact records of one part of the threaded stage (forces.c) */
typedef struct floe_rec_sink {
    floe_contact_rec *r;
    int n, cap;
} floe_rec_sink;

typedef struct floe_par_scratch {
    double *pf; unsigned char *act; size_t pf_cap, act_cap; /* per entry: force on i, torques of i, j */
    int *gl; size_t gl_cap;                          /* the particles with entries in more than one
                                                       part (the gather's), in index order, and their cut into
                                                       the threads' shares by entries: share t is
                                                       gl[gc[t] .. gc[t+1]) (forces.c par_prepare,
                                                       with lead[]) */
    int *gc; size_t gc_cap;
    int *adj, *adj_off; size_t adj_cap; int adj_np; long adj_gen; /* per particle: the entries it is
                                                       j of, in list order (adj_off: n + 1 offsets) */
    int *row;                                        /* n + 1: entries [row[i], row[i+1]) have pi = i */
    unsigned char *bpart; size_t bpart_cap;          /* per block: its part (par_prepare) */
    unsigned char *lead;                             /* per particle: the part of its first entry, whose
                                                       thread adds its forces directly (those of the
                                                       parts after it are gathered; forces.c
                                                       par_prepare, pair_apply) */
    int *brange;                                     /* 2n: per particle the first and last block holding
                                                       an entry of it (INT_MAX, -1: none), per list build */
    int *pb; int pb_nt; long pb_gen;                 /* the parts: part t is blocks [pb[t], pb[t+1]) on
                                                       thread t, cut for pb_nt threads (pb[pb_nt]: the
                                                       blocks) and the list of build pb_gen
                                                       (par_prepare); pb_nt 0: not cut */
    struct stage_acc *blk; int blk_cap;              /* per block (forces.c) */
    double *bs, *bt; int bt_cap, bt_nb;              /* per block: its stage time at the last
                                                       evaluation (s) and smoothed, for bt_nb
                                                       blocks (0: none yet); recut: the parts are
                                                       cut by bt at the next evaluation */
    int recut;
    int *bf; size_t bf_cap; int bf_nb, bf_n; long bf_gen; /* the first particle of each of the bf_nb
                                                       blocks of list bf_gen (bf[bf_nb] = bf_n, its
                                                       particles): the blocks whose times bt holds,
                                                       for the next list's first cut */
    floe_rec_sink *rs; int nrs;                      /* per part: its contact records (recording) */
    floe_detect_state *det; int ndet;                /* per thread */
    char (*err)[1024]; int *fail_b, *fail_rc; int nerr;
} floe_par_scratch;
void floe_par_scratch_free(floe_par_scratch *ps);

/* room for at least need particles in the store (world.c; contents kept) */
int floe_world_reserve_particles(floe_world *w, int need);
/* the n particles from index src moved to index dst, every array of the store (the ranges may
 * overlap; within the capacity; world.c) */
void floe_world_move_particles(floe_world *w, int dst, int src, int n);
/* the local index of the particle whose index in the unsplit world is id: itself in one
 * process; on a world split over MPI ranks its wall or owned copy (binary search of the two
 * ranges, each sorted by global id), with ghosts 1 also a ghost copy (a scan), -1 when this
 * rank holds none */
int floe_world_local_of(const floe_world *w, long long id, int ghosts);
/* the store and the neighbour list's arrays shrunk to their contents and a quarter more
 * where they hold more than half as much again, and, when that shrank something or the
 * caller freed memory itself (released), the freed memory returned to the system: after a
 * world split over MPI ranks keeps its part (core/parallel). A shrink that finds no memory
 * keeps the larger arrays */
void floe_world_trim(floe_world *w, int released);

/* The staged force evaluation (core/world/forces.c, floe_provider.h): the providers of the
 * groups (FLOE_GROUP_DEM: body forces, beam bonds, contacts; FLOE_GROUP_PD: PD bonds) in
 * order, the neighbour list rebuilt between stages when one asks, the ledger booked from
 * their accumulators. The DEM group zeroes p->f and p->t first; the PD group adds. */
int floe_world_forces(floe_world *w, const floe_step_ctx *ctx, int groups);
/* providers.c: 1 when pv is a user provider (owned through uprov); frees every provider */
int floe_provider_is_user(const floe_world *w, const struct floe_provider *pv);
void floe_world_providers_free(floe_world *w);
/* the forces at the present state, advancing nothing (as at prepare; for tests) */
int floe_compute_forces(floe_world *w);

/* one PD boundary region: its definition and the world indices of its points */
typedef struct floe_pd_bc_rec {
    floe_pd_bc def;
    int body, n;
    int *pts;                /* n particle indices */
    double *fold;            /* BODY_FORCE: 3n last external force, for the trapezoid work */
} floe_pd_bc_rec;

/* PD boundary regions and breakage (core/world/world_pd.c, next to floe_world_add_pd_body):
 * add the body forces of every body-force region to p->f and return their work over the
 * step (trapezoid, mid-step velocities; the caller books it when stepping); after the
 * bond forces, 1 when a newly broken bond lets a pair within reach meet by contact and the
 * list lacks it (the world then rebuilds the list); the pairs of a PD body that never
 * enter the contact list (bonded family members; floe_world_add_pd_body). */
double floe_pd_bc_forces(floe_world *w);
/* A world's PD bodies split over MPI ranks (w->pd_split): per body, the local particle of
 * each point (-1: not on this rank), the bond loop's mask (floe_pd_body.split: owned, ghost
 * or absent) and its positions gathered from the store (3 n; an absent point's never read) */
typedef struct floe_pd_split {
    const long long *gid;    /* per local particle (the decomposition's) */
    int **loc;
    uint8_t **mask;
    double **xb;
    uint8_t **snap;          /* per body: the broken flags as every rank held them after the
                              * last decomposition (par_pd.c flags_sync sends the bonds broken
                              * since) */
    int nbody;
    /* the ghost exchanges of LPS's theta (and q) and alpha's s0: up to 2 doubles a ghost sent
     * and received (sized at each decomposition, so that an exchange, inside the bond loop
     * for LPS, allocates nothing) */
    double *tx, *rx;
    size_t tx_cap, rx_cap;
} floe_pd_split;
/* body-local index of particle i of PD body b (i's body is b) */
static inline int floe_pd_local(const floe_world *w, int b, int i) {
    return (int)((w->pd_split ? w->pd_split->gid[i] : (long long)i) - w->pd_first[b]);
}
/* local particle of point q of PD body b, -1 when not on this rank */
static inline int floe_pd_particle(const floe_world *w, int b, int q) {
    return w->pd_split ? w->pd_split->loc[b][q] : w->pd_first[b] + q;
}
/* the positions of PD body b's points, contiguous (split: gathered, floe_pd_split_gather) */
static inline const double *floe_pd_positions(const floe_world *w, int b) {
    return w->pd_split ? w->pd_split->xb[b] : w->p.x + 3 * (size_t)w->pd_first[b];
}
/* a split's arrays for the world's PD bodies (NULL: out of memory), and their release */
floe_pd_split *floe_pd_split_new(const floe_world *w);
void floe_pd_split_free(floe_pd_split *S);
/* split: every PD body's present points' positions into xb (before its bond loop) */
void floe_pd_split_gather(floe_world *w);
int floe_pd_broken_pairs_reachable(floe_world *w);
int floe_pd_pair_excluded(const floe_world *w, int i, int j);
/* the families of PD body b (index k) through the periodic cell's images (world_pd.c) */
int floe_world_pd_periodic(floe_world *w, struct floe_pd_body *b, int k);

/* the contact list's exclusion of bonded pairs (PD families, beam bonds), installed when
 * either is added (core/world/world.c) */
void floe_world_install_exclusion(floe_world *w);

/* dash_a sized for every particle here (3 p.n doubles; forces.c); FLOE_ENOMEM */
int floe_world_dash_reserve(floe_world *w);
/* 1 when the next force evaluation (not an RK2 probe) copies the accelerations into dash_a */
int floe_world_dash_next(const floe_world *w);

int floe_world_error(floe_world *w, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* FLOE_ENOTSUP, with a message naming what, when the world is split over MPI ranks
 * (floe_world_parallel_init): the changes that make a world prepare again (particles,
 * shapes, bonds, the time step, the cell, motions, the body force) are made before the
 * split, as every rank would have to agree on the new state; 0 otherwise (core/world/world.c) */
int floe_world_refuse_split(floe_world *w, const char *what);

/* neighbour list (core/world/neighbor.c) */
int floe_nl_init(floe_neighbor_list *nl);
void floe_nl_free(floe_neighbor_list *nl);
int floe_nl_needs_rebuild(const floe_neighbor_list *nl, const floe_particles *p);
/* the same, given the largest squared displacement since the build measured during the
 * drift (growth = 1: some radius may have changed, do the full check) */
int floe_nl_needs_rebuild_after_drift(const floe_neighbor_list *nl, const floe_particles *p, double maxd2,
                                      int growth);
int floe_nl_build(floe_neighbor_list *nl, const floe_particles *p, int dim, int leaf_size);
/* each entry's history to hs doubles (floe_contact.h: the slots both layouts have are kept,
 * the others zero); FLOE_ENOMEM leaves the list as it was */
int floe_nl_set_stride(floe_neighbor_list *nl, int hs);
/* the entries (first particle < n) put in the order a build leaves them, (i, j, piece pair,
 * image), with their history, touching flags and warm starts: the next build then carries
 * the history by its row merge, not a hash of every entry (MPI's imported history,
 * core/parallel). Entries out of range: left as they are (FLOE_OK); FLOE_ENOMEM */
int floe_nl_sort(floe_neighbor_list *nl, int n);
/* the entries' index arrays shrunk to npairs and a quarter more where their capacity is more
 * than half as much again (a shrink that fails keeps the array); 1 when it shrank them */
int floe_nl_trim(floe_neighbor_list *nl);
/* the entries and their history freed (npairs 0): a world that is never stepped and whose
 * list is filled whole when needed (rank 0's mirror of a split world, core/parallel) */
void floe_nl_drop_entries(floe_neighbor_list *nl);
/* the world's list rebuilt from its particles, its search on the world's threads */
int floe_world_nl_build(floe_world *w);
/* the list's history stride this world's laws and shapes need (floe_contact.h:
 * FLOE_HIST_COMPACT when every law keeps at most 3 doubles and every shape is a sphere or a
 * plane, else FLOE_MAX_HISTORY), the list's entries restrided when it differs. Looked at
 * again only when a law or a geometry was added. Before each build and each contact stage */
int floe_world_hist_layout(floe_world *w);

/* the periodic cell (core/world/cell.c): checks at prepare (what a cell refuses, its width),
 * the step's velocity gradient (servo, strain path) before the drift, the affine map of the
 * particles and the cell after it, and the rebuild test that discounts the affine motion */
int floe_cell_prepare(floe_world *w);
/* sigma: the cell's stress given (MPI: summed over the ranks, floe_par_cell_stress), NULL: this
 * world's own (floe_world_cell_stress) */
int floe_cell_begin_step(floe_world *w, const double *sigma);
/* the cell's stress from its sums (floe_world_cell_stress; MPI: the ranks' sums, floe_par_cell_stress):
 * the contacts' virial vir, the PD bonds' pvir, the free particles' sum of m v (x) v mvv (the
 * fluctuation), the volume V; sigma = sym(vir + pvir) / V - mvv / V */
void floe_cell_stress_of(const double vir[9], const double pvir[9], const double mvv[9], double V, double sigma[9]);
/* mvv += the sum of m v (x) v over the free particles of [lo, hi) */
void floe_cell_mvv(const floe_particles *p, int lo, int hi, double mvv[9]);
int floe_cell_after_drift(floe_world *w, double dt);
int floe_nl_needs_rebuild_cell(const floe_neighbor_list *nl, const floe_particles *p);
int floe_cell_path_begin(floe_world *w, const double de[9], double max_rate, const int *stress_mask, long *nsteps);
void floe_cell_path_end(floe_world *w);

/* the separation cache was set up for the world's particles and list now (their count, the
 * list's entries and build; sep_on says whether it is kept: a list without a box, convex or
 * compound shape keeps none): forces.c sep_update scans the kinds again only otherwise.
 * ..._current: and its arrays exist, which a checkpoint writes only then
 * (core/integrators/checkpoint.c, section SEPC) */
static inline int floe_world_sep_seen(const floe_world *w) {
    return w->sep_n == w->p.n && w->sep_np == w->nl.npairs && w->sep_gen == w->nl.gen;
}
static inline int floe_world_sep_current(const floe_world *w) {
    return w->sep_d && floe_world_sep_seen(w);
}

/* detection of the pair (i, j), piece pair sub, at the particles' current poses
 * (contact/detect/floe_detect.h); for tests and diagnostics */
int floe_world_detect(floe_world *w, int i, int j, int sub, double *warm, floe_contact *c);
int floe_world_detect_overlap(floe_world *w, int i, int j, int sub, floe_contact *c);

/* world.c: registers the per-particle array *arr (m doubles a particle, *n rows; the
 * owner grows it and keeps *n up to date) of a force stage (pps above); once per array (a
 * second call is nothing); FLOE_ENOMEM */
int floe_world_pp_attach(floe_world *w, double **arr, int *n, int m);
/* the same, the array first among the registered ones (an array registered at prepare, when it
 * may come after others: the split world and a mirror prepared once then list the rows in
 * the same order, which the checkpoint's gather (floe_par_pp_collect) relies on) */
int floe_world_pp_attach_first(floe_world *w, double **arr, int *n, int m);
/* the array no longer registered (nothing if it is not) */
void floe_world_pp_detach(floe_world *w, double **arr);

#endif
