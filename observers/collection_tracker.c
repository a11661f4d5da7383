/* collection_tracker.c - ParticLS CollectionTracker (§4.3): homogenised Cauchy stress,
 * coordination number and contact counts of a collection of particles, as CSV.
 *
 * Collection ("members"): group -1 = every particle with motion FLOE_FREE and a bounded
 * radius; group g >= 0 = every particle whose group tag ("body") is g and whose radius is
 * bounded (whatever its motion). Walls (unbounded radius, FLOE_GEOM_PLANE) are never members.
 *
 * Stress (Love-Weber; ParticLS eq 24 written once per contact):
 *
 *     sigma = (1/V) sum_{p in members} sum_{c touching p} (x^c - x_p) (x) f^{c->p}
 *
 * where x^c is the contact point, x_p the centre of mass of p and f^{c->p} the contact force
 * acting ON p. For a contact between two members i and j (the stored force is the force on
 * i, F_i; j receives -F_i) the two halves add up to the branch-vector form of eq 24:
 *
 *     (x^c - x_i) (x) F_i + (x^c - x_j) (x) (-F_i) = d_ij (x) F_i,   d_ij = x_j - x_i,
 *
 * i.e. d_ij (x) F_ji with F_ji the force on i from j (= -F_ij, the force on j from i).
 * A contact between a member and a non-member (wall, fixed or kinematic particle, a particle
 * of another group) contributes only the member's half: (x^c - x_m) (x) f^{c->m}.
 * Contacts between two non-members are ignored. The paper's double sum over ordered pairs
 * (i, j) and (j, i) would count every contact twice; we count each contact once, which is
 * the Love-Weber average (mean stress over V of a body in equilibrium: for a column of
 * particles squeezed between two walls by a force F over an area A it gives sigma_zz = -F/A).
 *
 * Sign convention: TENSION POSITIVE, COMPRESSION NEGATIVE (continuum-mechanics convention).
 * A repulsive contact pushes i away from j, so F_i . d_ij < 0 and the diagonal term is
 * negative: a compressed packing has negative normal stresses. The tensor accumulated this
 * way, s_ab = (1/V) sum l_a f_b, is symmetric only in static equilibrium; we report its
 * symmetric part (sxy = (s_xy + s_yx)/2, ...).
 *
 * In a periodic cell (floe_cell.h) d_ij runs to j's image and V is the cell's volume.
 *
 * Volume V: the value given (> 0), otherwise the axis-aligned bounding box of the members,
 * each inflated by its bounding radius (an overestimate for non-spherical shapes). In 2D the
 * box is the bounding rectangle in x, y times a thickness of 1 m (consistent with 2D masses
 * per metre thickness), so the stress is in Pa for a 1 m thick slab.
 *
 * Coordination number Z = 2 x contacts / members, where contacts counts member-member
 * contacts only; member-non-member contacts are in the separate wall_contacts column (the
 * coordination including them is (2 contacts + wall_contacts) / members).
 *
 * The contacts used are those of the world's current step (floe_world_contacts). An empty
 * collection writes zero stress, zero coordination and zero volume.
 *
 * CSV columns:
 *   t [s],sxx [Pa],syy [Pa],szz [Pa],sxy [Pa],sxz [Pa],syz [Pa],coordination,contacts,
 *   wall_contacts,volume [m^3]
 * The file is created by floe_collection_tracker_create; each row is formatted whole and
 * written at the end of the observation (observers/file_writer.h: a killed run leaves no
 * partial row); end() writes the final state if this step was not observed yet and closes
 * the file. */
#include "floe_observer.h"
#include "file_writer.h"
#include "floe_cell.h"
#include "floe_parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct collection_tracker {
    floe_observer base;
    floe_file_writer out;
    int group;
    double volume;
    floe_collection_stats last;
    long last_step;
    int observed;
} collection_tracker;

static const floe_observer_class collection_tracker_class;

/* the stats of the collection from its sums (floe_world_collection_sums: one world's, or the
 * ranks' reduced) */
static void stats_finish(const floe_world *w, int dim, const double s[FLOE_COLLECTION_SUMS], double volume,
                         floe_collection_stats *out) {
    memset(out, 0, sizeof *out);
    out->time = floe_world_time(w);
    out->particles = (int)s[9];
    out->contacts = (int)s[10];
    out->wall_contacts = (int)s[11];
    const double *lo = s + 12, *hi = s + 15;
    double V = volume;
    const int periodic = floe_world_cell(w, NULL, NULL);
    if (!(V > 0) && periodic) V = floe_world_cell_volume(w); /* the periodic cell's */
    if (!(V > 0)) {
        if (out->particles == 0)
            V = 0;
        else if (dim == 2)
            V = (hi[0] - lo[0]) * (hi[1] - lo[1]) * 1.0; /* 1 m thickness */
        else
            V = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    }
    out->volume = V;
    if (V > 0) {
        double iv = 1.0 / V;
        out->sigma[0] = s[0] * iv;
        out->sigma[1] = s[4] * iv;
        out->sigma[2] = s[8] * iv;
        out->sigma[3] = 0.5 * (s[1] + s[3]) * iv;
        out->sigma[4] = 0.5 * (s[2] + s[6]) * iv;
        out->sigma[5] = 0.5 * (s[5] + s[7]) * iv;
    }
    out->coordination = out->particles > 0 ? 2.0 * out->contacts / out->particles : 0.0;
}

int floe_collection_stress(const floe_world *w, int group, double volume,
                           floe_collection_stats *out) {
    if (!w || !out) return FLOE_EINVAL;
    int rank = 0, size = 1;
    floe_world_parallel_rank(w, &rank, &size);
    if (size > 1) return FLOE_ENOTSUP; /* a split world: this rank's share (the outputs reduce it) */
    double s[FLOE_COLLECTION_SUMS];
    FLOE_TRY(floe_world_collection_sums(w, group, s)); /* FLOE_EINVAL: contacts not recorded */
    floe_particles_view p;
    FLOE_TRY(floe_world_particles(w, &p));
    stats_finish(w, p.dim, s, volume, out);
    return FLOE_OK;
}

/* contacts recorded at this step (a flush after a failure may have none) */
static int has_contacts(const floe_world *w) { return floe_world_contacts(w, NULL) >= 0; }

/* the row of the sums s (this world's, or the ranks' reduced) */
static int ct_write_sums(collection_tracker *t, floe_world *w, const double *s) {
    floe_particles_view p;
    FLOE_TRY(floe_world_particles(w, &p));
    stats_finish(w, p.dim, s, t->volume, &t->last);
    const floe_collection_stats *st = &t->last;
    {
        /* a NaN or infinity is never written: the row is refused, naming the value */
        static const char *const what[] = {"sxx", "syy", "szz", "sxy", "sxz", "syz", "coordination", "volume"};
        const double val[] = {st->sigma[0], st->sigma[1], st->sigma[2], st->sigma[3], st->sigma[4],
                              st->sigma[5], st->coordination, st->volume};
        for (int q = 0; q < 8; q++)
            if (!isfinite(val[q]))
                return floe_world_report_error(w, FLOE_EUNSTABLE, "collection tracker: %s is %g at t = %g s "
                                               "(step %ld): not written to %s", what[q], val[q], st->time,
                                               floe_world_step_count(w), t->out.path);
    }
    floe_fw_row(&t->out, "%.17g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%d,%d,%.16g\n", st->time,
                st->sigma[0], st->sigma[1], st->sigma[2], st->sigma[3], st->sigma[4], st->sigma[5],
                st->coordination, st->contacts, st->wall_contacts, st->volume);
    t->last_step = floe_world_step_count(w);
    t->observed = 1;
    return floe_fw_flush(&t->out, w);
}

static int ct_write(collection_tracker *t, floe_world *w) {
    double s[FLOE_COLLECTION_SUMS];
    const int rc = floe_world_collection_sums(w, t->group, s);
    if (rc == FLOE_EINVAL) return FLOE_OK; /* no contacts recorded */
    if (rc) return floe_world_report_error(w, rc, "collection tracker: out of memory");
    return ct_write_sums(t, w, s);
}

static int ct_observe(floe_observer *o, floe_world *w) {
    collection_tracker *t = (collection_tracker *)o;
    if (t->observed && t->last_step == floe_world_step_count(w)) return FLOE_OK;
    if (!has_contacts(w)) return FLOE_OK; /* a flush without contact records (after a failure) */
    return ct_write(t, w);
}

static int ct_end(floe_observer *o, floe_world *w) {
    collection_tracker *t = (collection_tracker *)o;
    int rc = FLOE_OK;
    if ((!t->observed || t->last_step != floe_world_step_count(w)) && has_contacts(w)) rc = ct_write(t, w);
    int rc2 = floe_fw_close(&t->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void ct_destroy(floe_observer *o) {
    collection_tracker *t = (collection_tracker *)o;
    floe_fw_free(&t->out);
    free(t);
}

static size_t ct_state_size(const floe_observer *o);
static void ct_save(const floe_observer *o, unsigned char *buf);
static int ct_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n);
/* under MPI (version 4): the ranks' sums reduced on rank 0 instead of every contact gathered */
static int ct_split_request(const floe_observer *o, floe_split_request *req) {
    req->kind = FLOE_SPLIT_COLLECTION;
    req->group = ((const collection_tracker *)o)->group;
    return FLOE_OK;
}

static int ct_observe_sums(floe_observer *o, floe_world *w, const double *sums) {
    collection_tracker *t = (collection_tracker *)o;
    if (t->observed && t->last_step == floe_world_step_count(w)) return FLOE_OK;
    return ct_write_sums(t, w, sums);
}

static const floe_observer_class collection_tracker_class = {
    4, "collection_tracker", NULL, ct_observe, ct_end, ct_destroy, 1,
    ct_state_size, ct_save, ct_restore, 0, /* checkpoint hooks (end of file) */
    ct_split_request, ct_observe_sums};

int floe_collection_tracker_last(const floe_observer *o, double sigma[6], double *coord) {
    if (!o || o->klass != &collection_tracker_class) return FLOE_EINVAL;
    const collection_tracker *t = (const collection_tracker *)o;
    if (!t->observed) return FLOE_EINVAL;
    if (sigma) memcpy(sigma, t->last.sigma, sizeof t->last.sigma);
    if (coord) *coord = t->last.coordination;
    return FLOE_OK;
}

floe_observer *floe_collection_tracker_create(const char *path, int group, double volume,
                                              char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!path || !*path || group < -1 || !(volume == volume) || isinf(volume)) {
        if (err && errlen)
            snprintf(err, errlen, "collection tracker: need a path, group >= -1 and a finite volume");
        return NULL;
    }
    collection_tracker *t = calloc(1, sizeof *t);
    if (!t) {
        if (err && errlen) snprintf(err, errlen, "collection tracker: out of memory");
        return NULL;
    }
    t->group = group;
    t->volume = volume;
    if (floe_fw_open(&t->out, "collection tracker", path,
                     "t [s],sxx [Pa],syy [Pa],szz [Pa],sxy [Pa],sxz [Pa],syz [Pa],coordination,contacts,"
                     "wall_contacts,volume [m^3]\n", err, errlen) != FLOE_OK) {
        free(t);
        return NULL;
    }
    t->base.klass = &collection_tracker_class;
    t->base.period_steps = 1;
    return &t->base;
}

/* checkpoints (floe_observer_base.h): the file's length, the last row's step and values */
static size_t ct_state_size(const floe_observer *o) {
    (void)o;
    return floe_fw_state_size() + sizeof(floe_collection_stats);
}
static void ct_save(const floe_observer *o, unsigned char *buf) {
    const collection_tracker *t = (const collection_tracker *)o;
    buf = floe_fw_state_save(&t->out, t->last_step, t->observed, buf);
    floe_fw_put(buf, &t->last, sizeof t->last);
}
static int ct_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    collection_tracker *t = (collection_tracker *)o;
    if (n != ct_state_size(o))
        return floe_world_report_error(w, FLOE_EINVAL, "collection tracker: checkpoint state does not match");
    FLOE_TRY(floe_fw_state_restore(&t->out, w, &t->last_step, &t->observed, buf));
    floe_fw_get(buf + floe_fw_state_size(), &t->last, sizeof t->last);
    return FLOE_OK;
}
