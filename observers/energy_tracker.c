/* energy_tracker.c - energy bookkeeping of the world as CSV (floe_world_energy and
 * floe_world_energy_balance_error), one row per observation.
 *
 * Columns (J unless stated):
 *   t [s], kinetic_trans [J], kinetic_rot [J], elastic [J], work_body [J],
 *   work_boundary [J], dissipated [J], initial [J], balance_error
 * balance_error is the relative error of initial + work = current + dissipated (no unit).
 *
 * The file is created by floe_energy_tracker_create; each row is formatted whole and
 * written at the end of the observation (observers/file_writer.h: a killed run leaves no
 * partial row);
 * end() writes the final state if this step was not observed yet and closes the file. */
#include "floe_observer.h"
#include "file_writer.h"

#include <math.h>
#include <stdlib.h>

typedef struct energy_tracker {
    floe_observer base;
    floe_file_writer out;
    long last_step;
    int observed;
} energy_tracker;

static int et_write(energy_tracker *t, floe_world *w) {
    floe_energy e = floe_world_energy(w);
    double err = floe_world_energy_balance_error(w);
    double time = floe_world_time(w);
    long step = floe_world_step_count(w);
    {
        /* a NaN or infinity is never written: the row is refused, naming the value */
        static const char *const what[] = {"kinetic_trans", "kinetic_rot", "elastic", "work_body",
                                           "work_boundary", "dissipated", "initial", "balance_error"};
        const double val[] = {e.kinetic_trans, e.kinetic_rot, e.elastic, e.work_body, e.work_boundary,
                              e.dissipated, e.initial, err};
        for (int q = 0; q < 8; q++)
            if (!isfinite(val[q]))
                return floe_world_report_error(w, FLOE_EUNSTABLE, "energy tracker: %s is %g at t = %g s (step %ld): "
                                               "not written to %s", what[q], val[q], time, step, t->out.path);
    }
    floe_fw_row(&t->out, "%.17g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g\n", time,
                e.kinetic_trans, e.kinetic_rot, e.elastic, e.work_body, e.work_boundary,
                e.dissipated, e.initial, err);
    t->last_step = step;
    t->observed = 1;
    return floe_fw_flush(&t->out, w);
}

static int et_observe(floe_observer *o, floe_world *w) {
    energy_tracker *t = (energy_tracker *)o;
    if (t->observed && t->last_step == floe_world_step_count(w)) return FLOE_OK;
    return et_write(t, w);
}

static int et_end(floe_observer *o, floe_world *w) {
    energy_tracker *t = (energy_tracker *)o;
    int rc = FLOE_OK;
    if (!t->observed || t->last_step != floe_world_step_count(w)) rc = et_write(t, w);
    int rc2 = floe_fw_close(&t->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void et_destroy(floe_observer *o) {
    energy_tracker *t = (energy_tracker *)o;
    floe_fw_free(&t->out);
    free(t);
}

/* checkpoints (floe_observer_base.h): the file's length, the last row block's step */
static size_t et_state_size(const floe_observer *o) {
    (void)o;
    return floe_fw_state_size();
}
static void et_save(const floe_observer *o, unsigned char *buf) {
    const energy_tracker *t = (const energy_tracker *)o;
    floe_fw_state_save(&t->out, t->last_step, t->observed, buf);
}
static int et_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    energy_tracker *t = (energy_tracker *)o;
    if (n != floe_fw_state_size())
        return floe_world_report_error(w, FLOE_EINVAL, "%s: checkpoint state does not match", t->out.who);
    return floe_fw_state_restore(&t->out, w, &t->last_step, &t->observed, buf);
}

/* under MPI (version 4): the ledger is summed over the ranks; nothing is gathered */
static int et_split_request(const floe_observer *o, floe_split_request *req) {
    (void)o;
    req->kind = FLOE_SPLIT_CLOCK;
    return FLOE_OK;
}

static const floe_observer_class energy_tracker_class = {
    4, "energy_tracker", NULL, et_observe, et_end, et_destroy, 0, et_state_size, et_save, et_restore, 0,
    et_split_request, NULL};

floe_observer *floe_energy_tracker_create(const char *path, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!path || !*path) {
        if (err && errlen) snprintf(err, errlen, "energy tracker: need a path");
        return NULL;
    }
    energy_tracker *t = calloc(1, sizeof *t);
    if (!t) {
        if (err && errlen) snprintf(err, errlen, "energy tracker: out of memory");
        return NULL;
    }
    if (floe_fw_open(&t->out, "energy tracker", path,
                     "t [s],kinetic_trans [J],kinetic_rot [J],elastic [J],work_body [J],work_boundary [J],"
                     "dissipated [J],initial [J],balance_error\n", err, errlen) != FLOE_OK) {
        free(t);
        return NULL;
    }
    t->base.klass = &energy_tracker_class;
    t->base.period_steps = 1;
    return &t->base;
}
