/* beam_set.h - a set of beam bonds over the particle store (contact/bonds/beam_bond.c),
 * the provider behind floe_world_add_beam_bonds (core/world/world_beams.c). Internal. */
#ifndef FLOE_BEAM_SET_H
#define FLOE_BEAM_SET_H

#include "floe_beam.h"
#include "particle_store.h"

typedef struct floe_beam_set floe_beam_set;

floe_beam_set *floe_beam_set_create(void);
void floe_beam_set_destroy(floe_beam_set *s);
/* FLOE_EINVAL with "beam bonds: <field> must ..." in err when par is out of range */
int floe_beam_check_params(const floe_beam_params *par, char *err, size_t errlen);
/* bond index of the pair (i, j), or -1 */
int floe_beam_set_find(const floe_beam_set *s, int i, int j);
/* appends the bond i-j (i < j) from the present poses; strengths drawn from *rng. Returns
 * its index or -error (message in err). Call floe_beam_set_index afterwards. */
int floe_beam_set_push(floe_beam_set *s, const floe_particles *p, int dim, int i, int j,
                       const floe_beam_params *par, unsigned long long *rng, char *err, size_t errlen);
/* bonds added one at a time continue one random stream per seed */
unsigned long long *floe_beam_set_rng(floe_beam_set *s, unsigned long long seed);
/* drops the bonds from index n on (a failed batch) */
void floe_beam_set_truncate(floe_beam_set *s, int n);
/* MPI (core/parallel, docs/parallel.md "Beam bonds"): a bond's whole record (section,
 * reference frame, strengths, stresses, last forces and energy, broken flag and break) as
 * rec_size bytes, to move it between ranks; rec_get copies bond k's and gives its ends
 * and broken flag; rec_replace makes the set the n records at recs (stride bytes apart)
 * with their ends renumbered to ii[k], jj[k] (local indices), the broken count recounted
 * (FLOE_ENOMEM leaves the set as it was); call floe_beam_set_index afterwards */
size_t floe_beam_set_rec_size(void);
int floe_beam_set_rec_get(const floe_beam_set *s, int k, void *rec, int *i, int *j, int *broken);
int floe_beam_rec_broken(const void *rec);
/* bond k's record replaced by rec, its ends kept (an unsplit copy of the world takes the
 * state of the split world's bonds); the broken count follows */
int floe_beam_set_rec_put(floe_beam_set *s, int k, const void *rec);
int floe_beam_set_rec_replace(floe_beam_set *s, const unsigned char *recs, size_t stride, const int *ii, const int *jj,
                              int n);
/* threads for the bond loop of floe_beam_set_forces (the world sets it per evaluation; 0 or 1:
 * one); the results are the same bits for any count (docs/parallel.md) */
void floe_beam_set_threads(floe_beam_set *s, int nthreads);
/* 1 once an evaluation ran threaded (its buffers exist; for tests) */
int floe_beam_set_threaded(const floe_beam_set *s);
/* the partner index over the first n particles (after pushes): FLOE_OK or FLOE_ENOMEM */
int floe_beam_set_index(floe_beam_set *s, int n);
int floe_beam_set_count(const floe_beam_set *s);
int floe_beam_set_broken(const floe_beam_set *s);
int floe_beam_set_info(const floe_beam_set *s, int k, floe_beam_bond_info *out);
/* 1 when i and j are held by an intact bond (they never enter the contact list) */
int floe_beam_set_excludes(const floe_beam_set *s, int i, int j);
/* the bonds as CSV; FLOE_EIO when the file cannot be written */
int floe_beam_set_write_csv(const floe_beam_set *s, const floe_particles *p, const char *path);
/* Critical time step (s, INFINITY without bonds): a block Gershgorin bound on the highest
 * frequency of the bonded particles' translations and rotations, damping included; caches
 * the per-bond damping from the present masses. */
double floe_beam_set_critical_dt(floe_beam_set *s, const floe_particles *p, int dim);
/* Adds the bond forces and torques to p->f, p->t; the bonds' stored energy to *elastic and,
 * when ctx->stepping, their dissipation over the step (work of the bond forces minus the
 * change of stored energy: damping and the energy of breaking bonds) to *dissipated. Bonds
 * whose stress exceeds the strength break (only when stepping). Returns the number of bonds
 * broken by this call: the caller lets those pairs meet by contact. */
int floe_beam_set_forces(floe_beam_set *s, const floe_step_ctx *ctx, double *elastic, double *dissipated);
/* The bytes of what a step changes in the bonds (last stresses, forces and energies, broken
 * flags and the breaks' records; the bonds' whole records, so a layout change shows as a
 * size mismatch): checkpoints (core/integrators/checkpoint.c). restore returns FLOE_EINVAL
 * when n bytes are not this set's size (another scene). */
size_t floe_beam_set_state_size(const floe_beam_set *s);
void floe_beam_set_state_save(const floe_beam_set *s, unsigned char *buf);
int floe_beam_set_state_restore(floe_beam_set *s, const unsigned char *buf, size_t n);

#endif
