/* fracture_events.c - the breaks of beam bonds as a list of events (sea ice, docs/sea-ice.md
 * "Outputs"), as CSV: one row per bond that broke, written at the first observation after
 * its break, every break once:
 *   t [s], step, i, j, mode (tension | shear | compression), x [m], y [m], z [m],
 *   stress [Pa], strength [Pa]
 * t is the time of the force evaluation that broke the bond (the end of its step), (x, y, z)
 * the midpoint of the two centres then, stress the stress of that mode (tensile fibre
 * stress, shear stress, compressive fibre stress) and strength the bond's strength in that
 * mode (in shear with its Mohr-Coulomb term). The bond set keeps these per bond
 * (floe_world_beam_bond); an observation reads them only when the count of broken bonds
 * has grown since the last one, scans the bonds and writes the new breaks ordered by time,
 * then bond index. step is counted back from the observation's step by the world's step
 * length (exact for fixed steps; adaptive steps are refused with bonds). */
#include "floe_observer.h"
#include "file_writer.h"
#include "floe_world_beams.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* a break not yet written: its time and bond */
typedef struct fe_break {
    double t;
    int k;
} fe_break;

typedef struct fracture_events {
    floe_observer base;
    floe_file_writer out;
    int reported;             /* breaks written */
    int nb;                   /* bonds sized for */
    unsigned char *done;      /* per bond: its break written */
    fe_break *fresh;          /* the bonds broken since the last observation */
} fracture_events;

static int by_time(const void *a, const void *b) {
    const fe_break *x = a, *y = b;
    if (x->t != y->t) return x->t < y->t ? -1 : 1;
    return (x->k > y->k) - (x->k < y->k);
}

static int fe_reserve(fracture_events *f, int nb) {
    if (nb <= f->nb) return FLOE_OK;
    unsigned char *d = realloc(f->done, (size_t)nb);
    if (!d) return FLOE_ENOMEM;
    f->done = d;
    memset(f->done + f->nb, 0, (size_t)(nb - f->nb));
    fe_break *q = realloc(f->fresh, (size_t)nb * sizeof *q);
    if (!q) return FLOE_ENOMEM;
    f->fresh = q;
    f->nb = nb;
    return FLOE_OK;
}

static int fe_write(fracture_events *f, floe_world *w) {
    const int broken = floe_world_beam_broken_count(w);
    if (broken == f->reported) return FLOE_OK;
    const int nb = floe_world_beam_bond_count(w);
    if (fe_reserve(f, nb)) return floe_world_report_error(w, FLOE_ENOMEM, "fracture_events: out of memory");
    int nfresh = 0;
    for (int k = 0; k < nb; k++) {
        floe_beam_bond_info b;
        if (f->done[k] || floe_world_beam_bond(w, k, &b) || !b.broken) continue;
        f->fresh[nfresh++] = (fe_break){b.t_broken, k};
        f->done[k] = 1;
    }
    qsort(f->fresh, (size_t)nfresh, sizeof *f->fresh, by_time);
    static const char *const modes[] = {"intact", "tension", "shear", "compression"};
    const double t = floe_world_time(w), dt = floe_world_dt(w);
    const long step = floe_world_step_count(w);
    for (int r = 0; r < nfresh; r++) {
        floe_beam_bond_info b;
        floe_world_beam_bond(w, f->fresh[r].k, &b);
        long sb = dt > 0 ? step - lround((t - b.t_broken) / dt) : step;
        floe_fw_row(&f->out, "%.17g,%ld,%d,%d,%s,%.10g,%.10g,%.10g,%.10g,%.10g\n", b.t_broken, sb, b.i, b.j,
                    modes[b.mode >= 0 && b.mode <= 3 ? b.mode : 0], b.x_broken[0], b.x_broken[1], b.x_broken[2],
                    b.stress_broken, b.strength_broken);
    }
    f->reported += nfresh;
    return floe_fw_flush(&f->out, w);
}

static int fe_observe(floe_observer *o, floe_world *w) { return fe_write((fracture_events *)o, w); }

static int fe_end(floe_observer *o, floe_world *w) {
    fracture_events *f = (fracture_events *)o;
    int rc = fe_write(f, w);
    int rc2 = floe_fw_close(&f->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void fe_destroy(floe_observer *o) {
    fracture_events *f = (fracture_events *)o;
    floe_fw_free(&f->out);
    free(f->done);
    free(f->fresh);
    free(f);
}

/* checkpoints (floe_observer_base.h): the file, the breaks written */
static size_t fe_state_size(const floe_observer *o) {
    const fracture_events *f = (const fracture_events *)o;
    return floe_fw_state_size() + 2 * sizeof(int) + (size_t)f->nb;
}
static void fe_save(const floe_observer *o, unsigned char *buf) {
    const fracture_events *f = (const fracture_events *)o;
    buf = floe_fw_state_save(&f->out, 0, 0, buf);
    buf = floe_fw_put(buf, &f->reported, sizeof f->reported);
    buf = floe_fw_put(buf, &f->nb, sizeof f->nb);
    if (f->nb) floe_fw_put(buf, f->done, (size_t)f->nb);
}
static int fe_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    fracture_events *f = (fracture_events *)o;
    int nb = -1, reported;
    long ls;
    int obs;
    if (n >= floe_fw_state_size() + 2 * sizeof nb) memcpy(&nb, buf + floe_fw_state_size() + sizeof nb, sizeof nb);
    if (nb < 0 || n != floe_fw_state_size() + 2 * sizeof(int) + (size_t)nb)
        return floe_world_report_error(w, FLOE_EINVAL, "fracture_events: checkpoint state does not match");
    if (fe_reserve(f, nb)) return floe_world_report_error(w, FLOE_ENOMEM, "fracture_events: out of memory");
    FLOE_TRY(floe_fw_state_restore(&f->out, w, &ls, &obs, buf));
    buf += floe_fw_state_size();
    buf = floe_fw_get(buf, &reported, sizeof reported);
    buf += sizeof nb;
    if (nb) floe_fw_get(buf, f->done, (size_t)nb);
    f->reported = reported;
    return FLOE_OK;
}

static const floe_observer_class fracture_events_class = {3, "fracture_events", NULL, fe_observe, fe_end, fe_destroy,
                                                          0, fe_state_size, fe_save, fe_restore, 0, NULL, NULL};

floe_observer *floe_fracture_events_create(const char *path, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!path || !*path) {
        if (err && errlen) snprintf(err, errlen, "fracture_events: need a path");
        return NULL;
    }
    fracture_events *f = calloc(1, sizeof *f);
    if (!f) {
        if (err && errlen) snprintf(err, errlen, "fracture_events: out of memory");
        return NULL;
    }
    if (floe_fw_open(&f->out, "fracture_events", path,
                     "t [s],step,i,j,mode,x [m],y [m],z [m],stress [Pa],strength [Pa]\n", err, errlen)) {
        free(f);
        return NULL;
    }
    f->base.klass = &fracture_events_class;
    f->base.period_steps = 1;
    return &f->base;
}
