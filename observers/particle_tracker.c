/* particle_tracker.c - ParticLS ParticleTracker (§4.3): the state of chosen particles as
 * CSV rows, one row per tracked particle per observation.
 *
 * Columns (header row with units):
 *   t [s], id, x [m], y [m], z [m], vx [m/s], vy [m/s], vz [m/s],
 *   wx [rad/s], wy [rad/s], wz [rad/s], q0, q1, q2, q3, fx [N], fy [N], fz [N]
 * id is the world's particle index; q = (w, x, y, z) is the body -> world orientation.
 *
 * The file is created (truncated) by floe_particle_tracker_create; each observation's rows
 * are formatted whole and written at its end (observers/file_writer.h: a killed run leaves
 * no partial row). end() writes the final state if this step was not observed yet, then
 * closes the file; a later observation (a run continued after finish) appends to it. */
#include "floe_observer.h"
#include "file_writer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct particle_tracker {
    floe_observer base;
    floe_file_writer out;
    int *ids;
    int n;
    long last_step;
    int observed;   /* at least one row block written */
} particle_tracker;

static const floe_observer_class particle_tracker_class;

static int pt_check_ids(particle_tracker *t, floe_world *w) {
    int np = floe_world_particle_count(w);
    for (int k = 0; k < t->n; k++)
        if (t->ids[k] >= np)
            return floe_world_report_error(w, FLOE_EINVAL,
                                           "particle tracker %s: particle id %d out of range (%d particles)",
                                           t->out.path, t->ids[k], np);
    return FLOE_OK;
}

static int pt_begin(floe_observer *o, floe_world *w) {
    return pt_check_ids((particle_tracker *)o, w);
}

static int pt_write(particle_tracker *t, floe_world *w) {
    FLOE_TRY(pt_check_ids(t, w));
    floe_particles_view p;
    FLOE_TRY(floe_world_particles(w, &p));
    double time = floe_world_time(w);
    long step = floe_world_step_count(w);
    /* a NaN or infinity is never written: the row is refused, naming the value */
    for (int k = 0; k < t->n; k++) {
        static const char *const what[] = {"position", "velocity", "angular velocity", "orientation", "force"};
        static const int len[] = {3, 3, 3, 4, 3};
        int i = t->ids[k];
        const double *src[] = {p.x + 3 * i, p.v + 3 * i, p.w + 3 * i, p.q + 4 * i, p.f + 3 * i};
        for (int q = 0; q < 5; q++)
            for (int c = 0; c < len[q]; c++)
                if (!isfinite(src[q][c]))
                    return floe_world_report_error(w, FLOE_EUNSTABLE, "particle tracker: particle %d has a non-finite "
                                                   "%s (component %d = %g) at t = %g s (step %ld): not written to %s",
                                                   i, what[q], c, src[q][c], time, step, t->out.path);
    }
    for (int k = 0; k < t->n; k++) {
        int i = t->ids[k];
        const double *x = p.x + 3 * i, *v = p.v + 3 * i, *om = p.w + 3 * i;
        const double *q = p.q + 4 * i, *f = p.f + 3 * i;
        floe_fw_row(&t->out,
                    "%.17g,%d,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,"
                    "%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g\n",
                    time, i, x[0], x[1], x[2], v[0], v[1], v[2], om[0], om[1], om[2],
                    q[0], q[1], q[2], q[3], f[0], f[1], f[2]);
    }
    t->last_step = step;
    t->observed = 1;
    return floe_fw_flush(&t->out, w);
}

static int pt_observe(floe_observer *o, floe_world *w) {
    particle_tracker *t = (particle_tracker *)o;
    if (t->observed && t->last_step == floe_world_step_count(w)) return FLOE_OK; /* already written */
    return pt_write(t, w);
}

static int pt_end(floe_observer *o, floe_world *w) {
    particle_tracker *t = (particle_tracker *)o;
    int rc = FLOE_OK;
    if (!t->observed || t->last_step != floe_world_step_count(w)) rc = pt_write(t, w);
    int rc2 = floe_fw_close(&t->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void pt_destroy(floe_observer *o) {
    particle_tracker *t = (particle_tracker *)o;
    floe_fw_free(&t->out);
    free(t->ids);
    free(t);
}

/* checkpoints (floe_observer_base.h): the file's length, the last row block's step */
static size_t pt_state_size(const floe_observer *o) {
    (void)o;
    return floe_fw_state_size();
}
static void pt_save(const floe_observer *o, unsigned char *buf) {
    const particle_tracker *t = (const particle_tracker *)o;
    floe_fw_state_save(&t->out, t->last_step, t->observed, buf);
}
static int pt_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    particle_tracker *t = (particle_tracker *)o;
    if (n != floe_fw_state_size())
        return floe_world_report_error(w, FLOE_EINVAL, "%s: checkpoint state does not match", t->out.who);
    return floe_fw_state_restore(&t->out, w, &t->last_step, &t->observed, buf);
}

/* under MPI (version 4): only the listed particles are brought to rank 0 */
static int pt_split_request(const floe_observer *o, floe_split_request *req) {
    const particle_tracker *t = (const particle_tracker *)o;
    req->kind = FLOE_SPLIT_PARTICLES;
    req->ids = t->ids;
    req->nids = t->n;
    return FLOE_OK;
}

static const floe_observer_class particle_tracker_class = {
    4, "particle_tracker", pt_begin, pt_observe, pt_end, pt_destroy, 0, pt_state_size, pt_save, pt_restore,
    FLOE_OBSERVER_READS_LISTED, pt_split_request, NULL};

floe_observer *floe_particle_tracker_create(const char *path, const int *ids, int n,
                                            char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!path || !*path || !ids || n <= 0) {
        if (err && errlen) snprintf(err, errlen, "particle tracker: need a path and at least one id");
        return NULL;
    }
    for (int k = 0; k < n; k++)
        if (ids[k] < 0) {
            if (err && errlen) snprintf(err, errlen, "particle tracker: negative particle id %d", ids[k]);
            return NULL;
        }
    particle_tracker *t = calloc(1, sizeof *t);
    if (t) t->ids = malloc((size_t)n * sizeof *t->ids);
    if (!t || !t->ids) {
        if (err && errlen) snprintf(err, errlen, "particle tracker: out of memory");
        if (t) free(t->ids);
        free(t);
        return NULL;
    }
    memcpy(t->ids, ids, (size_t)n * sizeof *ids);
    t->n = n;
    if (floe_fw_open(&t->out, "particle tracker", path,
                     "t [s],id,x [m],y [m],z [m],vx [m/s],vy [m/s],vz [m/s],wx [rad/s],wy [rad/s],"
                     "wz [rad/s],q0,q1,q2,q3,fx [N],fy [N],fz [N]\n", err, errlen) != FLOE_OK) {
        free(t->ids);
        free(t);
        return NULL;
    }
    t->base.klass = &particle_tracker_class;
    t->base.period_steps = 1;
    t->base.orient_ids = t->ids; /* it reads the orientations of these particles only */
    t->base.norient_ids = n;
    return &t->base;
}
