/* floe_checkpoint.h - checkpoints: a world's whole state between two steps, in a file or in
 * memory, so that a run stopped there continues bit for bit as if it had not stopped
 * (issue #13, docs/checkpoints.md).
 *
 * What is saved: the particles' state (positions, velocities, orientations, angular
 * momenta and velocities, forces, masses and radii), the state objects, the neighbour list
 * exactly (pairs in their order, contact history, touching flags, ADMM/LP warm starts, the
 * positions at its build), every force provider's state through its save/restore hooks
 * (floe_provider.h: PD bonds and damage, body-force memories, forcing), the beam bonds, the
 * clock and the integrator's memory (leapfrog's last step, the adaptive step, the staggered
 * scheme's PD cycle and forces), the energy ledger and the watchdog's terms, the step and
 * detection statistics; in a file also the observers' state through their hooks
 * (floe_observer_base.h), so that their files go on as if the run had not stopped.
 *
 * A checkpoint is loaded into a world freshly built from the same scene (the same
 * particles, materials, laws, providers, observers in the same order), before its first
 * step: the load prepares it without its first observation and puts the state back.
 *
 * The file: the magic "FLOECKPT", the format (FLOE_CHECKPOINT_FORMAT), the floe version that
 * wrote it, a 64-bit hash of the scene (the caller's: the CLI hashes the scene file's text),
 * the scene's name, then tagged sections (a 4-character tag, a 64-bit length, the bytes) and
 * a closing section with a hash of everything before it. Written to PATH.tmp and renamed
 * onto PATH. Refused with a message (never a crash): another magic (not a checkpoint),
 * another format or floe version ("written by floe X, format N; this is floe Y, format
 * M"), another scene (hash mismatch: both names), a truncated or corrupted file, a section
 * whose size does not match this world (another scene with the same text hash), an
 * observer without checkpoint hooks. Byte order and type sizes are this machine's: a
 * checkpoint is for continuing on the same kind of machine (the format records the byte
 * order and refuses another). */
#ifndef FLOE_CHECKPOINT_H
#define FLOE_CHECKPOINT_H

#include "floe_world.h"

#include <stddef.h>
#include <stdint.h>

#define FLOE_CHECKPOINT_FORMAT 6 /* 6: a sphere-wall entry in the bounded particle's row (its history's pair the other way round where the wall's index is lower); 5: a random packing's particles numbered in Morton order (a format 4 file would put its particles' states on others); 4: NLST entries of FLOE_HIST_COMPACT or FLOE_MAX_HISTORY doubles, the ledger first; 3: the CELL section holds the PD bonds' virial */

/* FNV-1a 64-bit hash of n bytes continuing from h (start with FLOE_CHECKPOINT_HASH0) */
#define FLOE_CHECKPOINT_HASH0 0xcbf29ce484222325ULL
uint64_t floe_checkpoint_hash(uint64_t h, const void *data, size_t n);

/* Writes the world's state (after its first step or prepare; between steps) to path,
 * atomically (path.tmp, then rename). scene_hash and scene_name identify the scene for the
 * load's check (scene_name may be NULL). FLOE_OK, or FLOE_EINVAL (not prepared) / FLOE_EIO /
 * FLOE_ENOMEM with a message in err. */
int floe_world_checkpoint_save(const floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name,
                               char *err, size_t errlen);
/* Loads a checkpoint into w, a world freshly built from the same scene and not yet
 * prepared (its outputs opened with floe_outputs_keep_existing(1) when they are to be
 * continued). FLOE_OK, or FLOE_EINVAL with the reason in err (not a checkpoint, another
 * version or format, another scene, truncated or corrupted, an observer without hooks),
 * FLOE_EIO, FLOE_ENOMEM. After a failed load the world must be destroyed. */
int floe_world_checkpoint_load(floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name,
                               char *err, size_t errlen);
/* The same without the observers' section (skipped, not read):
 * for a world whose outputs are continued elsewhere, an MPI rank's share of a run whose
 * outputs rank 0's mirror writes (floe_world_parallel_checkpoint_load). */
int floe_world_checkpoint_load_state(floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name,
                                     char *err, size_t errlen);

/* Under MPI (floe_parallel.h, docs/parallel.md). The file is the serial one: written under
 * any number of ranks, it continues under any other number, or in one process.
 * _save: collective over a split world w: its whole state is gathered into full, an unsplit
 * world prepared from the same scene on rank 0 (NULL on the others; rank 0's output mirror
 * serves: its observers' state is the file's), then rank 0 writes full's checkpoint; every
 * rank returns the outcome (another rank's message: "rank 0 could not write"). An unsplit
 * world: floe_world_checkpoint_save(w).
 * A restart under MPI (cli/main.c): every rank reads the file into its world, freshly built
 * from the scene without outputs, with floe_world_checkpoint_load_state; the ranks agree on
 * the outcome (floe_parallel_agree: a rank that failed alone leaves none waiting); then the
 * world is split as a fresh run's is (floe_world_parallel_init), the contact history carried
 * to the pairs' new owners. Rank 0's output mirror, if any, is loaded with
 * floe_world_checkpoint_load (its observers continue their files). */
int floe_world_parallel_checkpoint_save(const floe_world *w, floe_world *full, const char *path, uint64_t scene_hash,
                                        const char *scene_name, char *err, size_t errlen);
/* The outputs that every rank of a split world writes itself (floe_world_parallel_add_output:
 * the vtk pieces) are in the file too: rank 0's, after the mirror's observers, marked as such
 * (their state, the series' frames and times, is every rank's; a world's load skips them, and
 * a run in one process refuses a file that holds some). At a restart every rank restores its
 * nobs such outputs, before it adds them to its split world, from the file (in the order they
 * were added); a file holding another number of them is refused (0: written by one process). */
int floe_world_checkpoint_restore_split_outputs(floe_world *w, floe_observer **obs, int nobs, const char *path,
                                                uint64_t scene_hash, const char *scene_name, char *err, size_t errlen);

/* The same state in memory, without the observers (for a caller that runs a world
 * repeatedly from one state, e.g. a representative volume): the bytes needed (0 when the
 * world is not prepared), the state written into buf (len >= that size), and read back
 * into the same world or a fresh one of the same scene (restore prepares it first).
 * FLOE_OK or an error code with the message in err. */
size_t floe_world_state_size(const floe_world *w);
int floe_world_state_save(const floe_world *w, void *buf, size_t len, char *err, size_t errlen);
int floe_world_state_restore(floe_world *w, const void *buf, size_t len, char *err, size_t errlen);

/* While on (this thread), the observers' files opened from then on (the scene loader's
 * outputs) keep their content instead of being truncated: a restart sets it around loading
 * its scene, and the checkpoint load cuts each file back to its length at the checkpoint.
 * Defined by the observers' file writer (observers/file_writer.c). */
void floe_outputs_keep_existing(int on);

#endif
