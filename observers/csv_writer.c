/* csv_writer.c - snapshot of every particle per frame, all frames in one CSV file.
 *
 * Columns:
 *   t [s], id, body, material, x [m], y [m], z [m], vx [m/s], vy [m/s], vz [m/s],
 *   wx [rad/s], wy [rad/s], wz [rad/s], fx [N], fy [N], fz [N], radius [m]
 * id is the world's particle index, body its group tag. Walls (unbounded geometry such as
 * planes) are written too, with radius 0 (their bounding radius is infinite) and their
 * reference point as x, y, z, so that rows can be filtered with radius > 0.
 *
 * The file is created by floe_csv_writer_create; each frame is formatted whole and written
 * at its end (observers/file_writer.h: a killed run leaves no partial row);
 * end() writes the final state if this step was not written yet and closes the file. */
#include "floe_observer.h"
#include "file_writer.h"

#include <math.h>
#include <stdlib.h>

typedef struct csv_writer {
    floe_observer base;
    floe_file_writer out;
    long last_step;
    int observed;
} csv_writer;

static int cw_write(csv_writer *t, floe_world *w) {
    floe_particles_view p;
    FLOE_TRY(floe_world_particles(w, &p));
    double time = floe_world_time(w);
    long step = floe_world_step_count(w);
    /* a NaN or infinity is never written: the frame is refused, naming the value */
    for (int i = 0; i < p.n; i++) {
        static const char *const what[4] = {"position", "velocity", "angular velocity", "force"};
        const double *src[4] = {p.x + 3 * i, p.v + 3 * i, p.w + 3 * i, p.f + 3 * i};
        for (int q = 0; q < 4; q++)
            if (!isfinite(src[q][0]) || !isfinite(src[q][1]) || !isfinite(src[q][2]))
                return floe_world_report_error(w, FLOE_EUNSTABLE, "csv writer: particle %d has a non-finite %s "
                                               "(%g, %g, %g) at t = %g s (step %ld): frame not written to %s", i,
                                               what[q], src[q][0], src[q][1], src[q][2], time, step, t->out.path);
    }
    for (int i = 0; i < p.n; i++) {
        const double *x = p.x + 3 * i, *v = p.v + 3 * i, *om = p.w + 3 * i, *f = p.f + 3 * i;
        double r = isfinite(p.radius[i]) ? p.radius[i] : 0.0;
        int body = p.group ? p.group[i] : 0, mat = p.material ? p.material[i] : 0;
        floe_fw_row(&t->out,
                    "%.17g,%d,%d,%d,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,"
                    "%.16g,%.16g,%.16g,%.16g\n",
                    time, i, body, mat, x[0], x[1], x[2], v[0], v[1], v[2], om[0], om[1], om[2],
                    f[0], f[1], f[2], r);
    }
    t->last_step = step;
    t->observed = 1;
    return floe_fw_flush(&t->out, w);
}

static int cw_observe(floe_observer *o, floe_world *w) {
    csv_writer *t = (csv_writer *)o;
    if (t->observed && t->last_step == floe_world_step_count(w)) return FLOE_OK;
    return cw_write(t, w);
}

static int cw_end(floe_observer *o, floe_world *w) {
    csv_writer *t = (csv_writer *)o;
    int rc = FLOE_OK;
    if (!t->observed || t->last_step != floe_world_step_count(w)) rc = cw_write(t, w);
    int rc2 = floe_fw_close(&t->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void cw_destroy(floe_observer *o) {
    csv_writer *t = (csv_writer *)o;
    floe_fw_free(&t->out);
    free(t);
}

/* checkpoints (floe_observer_base.h): the file's length, the last row block's step */
static size_t cw_state_size(const floe_observer *o) {
    (void)o;
    return floe_fw_state_size();
}
static void cw_save(const floe_observer *o, unsigned char *buf) {
    const csv_writer *t = (const csv_writer *)o;
    floe_fw_state_save(&t->out, t->last_step, t->observed, buf);
}
static int cw_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    csv_writer *t = (csv_writer *)o;
    if (n != floe_fw_state_size())
        return floe_world_report_error(w, FLOE_EINVAL, "%s: checkpoint state does not match", t->out.who);
    return floe_fw_state_restore(&t->out, w, &t->last_step, &t->observed, buf);
}

static const floe_observer_class csv_writer_class = {
    3, "csv_writer", NULL, cw_observe, cw_end, cw_destroy, 0, cw_state_size, cw_save, cw_restore, 0, NULL, NULL};

floe_observer *floe_csv_writer_create(const char *path, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!path || !*path) {
        if (err && errlen) snprintf(err, errlen, "csv writer: need a path");
        return NULL;
    }
    csv_writer *t = calloc(1, sizeof *t);
    if (!t) {
        if (err && errlen) snprintf(err, errlen, "csv writer: out of memory");
        return NULL;
    }
    if (floe_fw_open(&t->out, "csv writer", path,
                     "t [s],id,body,material,x [m],y [m],z [m],vx [m/s],vy [m/s],vz [m/s],wx [rad/s],"
                     "wy [rad/s],wz [rad/s],fx [N],fy [N],fz [N],radius [m]\n", err, errlen) != FLOE_OK) {
        free(t);
        return NULL;
    }
    t->base.klass = &csv_writer_class;
    t->base.period_steps = 1;
    return &t->base;
}
