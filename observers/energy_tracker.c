/* energy_tracker.c - energy bookkeeping of the world as CSV (floe_world_energy and
 * floe_world_energy_balance_error), one row per observation.
 *
 * Columns (J unless stated):
 *   t [s], kinetic_trans [J], kinetic_rot [J], elastic [J], work_body [J],
 *   work_boundary [J], dissipated [J], initial [J], balance_error
 * balance_error is the relative error of initial + work = current + dissipated (no unit).
 *
 * The file is created by floe_energy_tracker_create and flushed after every observation;
 * end() writes the final state if this step was not observed yet and closes the file. */
#include "floe_observer.h"
#include "world_internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

typedef struct energy_tracker {
    floe_observer base;
    char *path;
    FILE *f;
    long last_step;
    int observed;
} energy_tracker;

static int et_write(energy_tracker *t, floe_world *w) {
    if (!t->f) {
        t->f = fopen(t->path, "a");
        if (!t->f)
            return floe_world_error(w, FLOE_EIO, "energy tracker: cannot reopen %s: %s", t->path,
                                    strerror(errno));
    }
    floe_energy e = floe_world_energy(w);
    double err = floe_world_energy_balance_error(w);
    {
        /* a NaN or infinity is never written: the row is refused, naming the value */
        static const char *const what[] = {"kinetic_trans", "kinetic_rot", "elastic", "work_body",
                                           "work_boundary", "dissipated", "initial", "balance_error"};
        const double val[] = {e.kinetic_trans, e.kinetic_rot, e.elastic, e.work_body, e.work_boundary,
                              e.dissipated, e.initial, err};
        for (int q = 0; q < 8; q++)
            if (!isfinite(val[q]))
                return floe_world_error(w, FLOE_EUNSTABLE, "energy tracker: %s is %g at t = %g s (step %ld): "
                                        "not written to %s", what[q], val[q], w->time, w->step, t->path);
    }
    fprintf(t->f, "%.17g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g,%.16g\n", w->time,
            e.kinetic_trans, e.kinetic_rot, e.elastic, e.work_body, e.work_boundary,
            e.dissipated, e.initial, err);
    t->last_step = w->step;
    t->observed = 1;
    if (fflush(t->f) != 0 || ferror(t->f))
        return floe_world_error(w, FLOE_EIO, "energy tracker: write to %s failed: %s", t->path,
                                strerror(errno));
    return FLOE_OK;
}

static int et_observe(floe_observer *o, floe_world *w) {
    energy_tracker *t = (energy_tracker *)o;
    if (t->observed && t->last_step == w->step) return FLOE_OK;
    return et_write(t, w);
}

static int et_end(floe_observer *o, floe_world *w) {
    energy_tracker *t = (energy_tracker *)o;
    int rc = FLOE_OK;
    if (!t->observed || t->last_step != w->step) rc = et_write(t, w);
    if (t->f) {
        if (fclose(t->f) != 0 && rc == FLOE_OK)
            rc = floe_world_error(w, FLOE_EIO, "energy tracker: closing %s failed", t->path);
        t->f = NULL;
    }
    return rc;
}

static void et_destroy(floe_observer *o) {
    energy_tracker *t = (energy_tracker *)o;
    if (t->f) fclose(t->f);
    free(t->path);
    free(t);
}

static const floe_observer_class energy_tracker_class = {
    1, "energy_tracker", NULL, et_observe, et_end, et_destroy, 0};

floe_observer *floe_energy_tracker_create(const char *path, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!path || !*path) {
        if (err && errlen) snprintf(err, errlen, "energy tracker: need a path");
        return NULL;
    }
    energy_tracker *t = calloc(1, sizeof *t);
    if (t) t->path = malloc(strlen(path) + 1);
    if (!t || !t->path) {
        if (err && errlen) snprintf(err, errlen, "energy tracker: out of memory");
        free(t);
        return NULL;
    }
    strcpy(t->path, path);
    t->f = fopen(path, "w");
    if (!t->f) {
        if (err && errlen) snprintf(err, errlen, "energy tracker: cannot open %s: %s", path, strerror(errno));
        et_destroy(&t->base);
        return NULL;
    }
    fputs("t [s],kinetic_trans [J],kinetic_rot [J],elastic [J],work_body [J],work_boundary [J],"
          "dissipated [J],initial [J],balance_error\n", t->f);
    fflush(t->f);
    t->base.klass = &energy_tracker_class;
    t->base.period_steps = 1;
    return &t->base;
}
