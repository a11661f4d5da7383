/* coast_load.c - the ice load on coasts (sea ice, docs/sea-ice.md "Outputs"), as CSV: for
 * each fixed or kinematic body (a coast, an island, a structure; walls included), or the
 * one body or the body entry chosen, one row per observation:
 *   t [s], body, contacts, fx [N], fy [N], force [N], length [m], per_length [N/m]
 * (fx, fy) is the sum of the contact forces on the body at the last force evaluation,
 * contacts their number, force |(fx, fy)|, length the length of coast in contact and
 * per_length = force / length, the line load that ice-load studies report in N/m (0 when
 * length is 0).
 *
 * length is, unless the output is given a fixed `length`, the sum over the ice in contact
 * of the length of each contact patch: for two polytopes (polygons, compounds of them),
 * L = A^2 / (2 I) summed over their touching piece pairs, A the overlap area and I the
 * overlap's energy integral from the overlap detector (floe_world_probe_overlap): exact
 * for a flat patch (A = L d, I = L d^2 / 2), the contact length of Hopkins' law
 * (docs/sea-ice.md, "Ridging law"); for other shapes the chord of a disc of the partner's
 * bounding radius R at the contact's depth d, 2 sqrt(d (2R - d)). 2D only. */
#include "floe_observer.h"
#include "file_writer.h"
#include "floe_detect.h"
#include "floe_view.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct coast_load {
    floe_observer base;
    floe_file_writer out;
    int body, group;      /* -1: any */
    double length;        /* > 0: the fixed length of the line load */
    long last_step;
    int observed;
    int n;                /* particles sized for */
    double *acc;          /* per particle: fx, fy, contacts, length */
    int *pairs, npairs, cap_pairs; /* (coast, ice) pairs whose length is counted */
} coast_load;

/* particle i is a coast this output reports */
static int is_coast(const coast_load *c, const floe_particles_view *v, int i) {
    if (v->motion[i] == FLOE_FREE) return 0;
    if (c->body >= 0 && i != c->body) return 0;
    return c->group < 0 || v->group[i] == c->group;
}

/* the patch length between coast b and ice o (file comment) */
static double patch_length(floe_world *w, const floe_particles_view *v, int b, int o, double depth) {
    double L = 0;
    for (int a = 0; a < v->pieces[b]; a++)
        for (int e = 0; e < v->pieces[o]; e++) {
            floe_contact c;
            memset(&c, 0, sizeof c);
            int rc = floe_world_probe_overlap(w, b, o, FLOE_SUB(a, e), &c);
            if (rc < 0) { /* not two polytopes: the chord */
                double R = v->radius[o], d = fmin(fmax(depth, 0), R);
                return 2 * sqrt(d * (2 * R - d));
            }
            if (rc == 1 && c.area > 0 && c.area_energy > 0) L += c.area * c.area / (2 * c.area_energy);
        }
    return L;
}

static int seen_pair(coast_load *c, int b, int o) {
    for (int k = 0; k < c->npairs; k++)
        if (c->pairs[2 * k] == b && c->pairs[2 * k + 1] == o) return 1;
    if (c->npairs == c->cap_pairs) {
        int cap = c->cap_pairs ? 2 * c->cap_pairs : 64;
        int *p = realloc(c->pairs, 2 * (size_t)cap * sizeof *p);
        if (!p) return -1;
        c->pairs = p;
        c->cap_pairs = cap;
    }
    c->pairs[2 * c->npairs] = b;
    c->pairs[2 * c->npairs + 1] = o;
    c->npairs++;
    return 0;
}

static int cl_write(coast_load *c, floe_world *w) {
    floe_particles_view v;
    FLOE_TRY(floe_world_particles(w, &v));
    if (v.n > c->n) {
        double *a = realloc(c->acc, 4 * (size_t)v.n * sizeof *a);
        if (!a) return floe_world_report_error(w, FLOE_ENOMEM, "coast_load: out of memory");
        c->acc = a;
        c->n = v.n;
    }
    memset(c->acc, 0, 4 * (size_t)v.n * sizeof *c->acc);
    const floe_contact_info *ci = NULL;
    int nc = floe_world_contacts(w, &ci);
    if (nc < 0)
        return floe_world_report_error(w, FLOE_EINVAL, "coast_load: the contacts were not recorded at t = %g s",
                                       floe_world_time(w));
    c->npairs = 0;
    for (int k = 0; k < nc; k++)
        for (int side = 0; side < 2; side++) {
            int b = side ? ci[k].j : ci[k].i, o = side ? ci[k].i : ci[k].j;
            if (!is_coast(c, &v, b)) continue;
            double *a = c->acc + 4 * (size_t)b, s = side ? -1.0 : 1.0; /* force acts on i, -force on j */
            a[0] += s * ci[k].force[0];
            a[1] += s * ci[k].force[1];
            a[2] += 1;
            if (c->length > 0) continue;
            int seen = seen_pair(c, b, o);
            if (seen < 0) return floe_world_report_error(w, FLOE_ENOMEM, "coast_load: out of memory");
            if (!seen) a[3] += patch_length(w, &v, b, o, ci[k].depth);
        }
    const double t = floe_world_time(w);
    for (int i = 0; i < v.n; i++) {
        if (!is_coast(c, &v, i)) continue;
        const double *a = c->acc + 4 * (size_t)i, L = c->length > 0 ? c->length : a[3], F = hypot(a[0], a[1]);
        if (!isfinite(F) || !isfinite(L))
            return floe_world_report_error(w, FLOE_EUNSTABLE, "coast_load: the load on body %d is not finite at t = %g s",
                                           i, t);
        floe_fw_row(&c->out, "%.17g,%d,%.0f,%.10g,%.10g,%.10g,%.10g,%.10g\n", t, i, a[2], a[0], a[1], F, L,
                    L > 0 ? F / L : 0.0);
    }
    c->last_step = floe_world_step_count(w);
    c->observed = 1;
    return floe_fw_flush(&c->out, w);
}

static int cl_begin(floe_observer *o, floe_world *w) {
    coast_load *c = (coast_load *)o;
    int n = floe_world_particle_count(w);
    if (c->body >= n)
        return floe_world_report_error(w, FLOE_EINVAL, "coast_load: body %d out of range (%d particles)", c->body, n);
    return FLOE_OK;
}

static int cl_observe(floe_observer *o, floe_world *w) {
    coast_load *c = (coast_load *)o;
    if (c->observed && c->last_step == floe_world_step_count(w)) return FLOE_OK;
    return cl_write(c, w);
}

static int cl_end(floe_observer *o, floe_world *w) {
    coast_load *c = (coast_load *)o;
    int rc = FLOE_OK;
    /* a flush after a failure or a stop may find no contacts recorded: nothing to add then */
    if ((!c->observed || c->last_step != floe_world_step_count(w)) && floe_world_contacts(w, NULL) >= 0)
        rc = cl_write(c, w);
    int rc2 = floe_fw_close(&c->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void cl_destroy(floe_observer *o) {
    coast_load *c = (coast_load *)o;
    floe_fw_free(&c->out);
    free(c->acc);
    free(c->pairs);
    free(c);
}

/* checkpoints (floe_observer_base.h): the file's length, the last row block's step */
static size_t cl_state_size(const floe_observer *o) {
    (void)o;
    return floe_fw_state_size();
}
static void cl_save(const floe_observer *o, unsigned char *buf) {
    const coast_load *t = (const coast_load *)o;
    floe_fw_state_save(&t->out, t->last_step, t->observed, buf);
}
static int cl_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    coast_load *t = (coast_load *)o;
    if (n != floe_fw_state_size())
        return floe_world_report_error(w, FLOE_EINVAL, "%s: checkpoint state does not match", t->out.who);
    return floe_fw_state_restore(&t->out, w, &t->last_step, &t->observed, buf);
}

static const floe_observer_class coast_load_class = {3, "coast_load", cl_begin, cl_observe, cl_end, cl_destroy, 1,
    cl_state_size, cl_save, cl_restore, 0, NULL, NULL};

floe_observer *floe_coast_load_create(const char *path, int dim, int body, int group, double length, char *err,
                                      size_t errlen) {
    if (err && errlen) err[0] = '\0';
    const char *bad = dim != 2 ? "coast_load is a 2D output (dimension: 2)"
                      : !path || !*path ? "coast_load: need a path"
                      : !(length >= 0 && isfinite(length)) ? "coast_load: length must be >= 0 (m; 0: the contact length)"
                                                           : NULL;
    if (bad) {
        if (err && errlen) snprintf(err, errlen, "%s", bad);
        return NULL;
    }
    coast_load *c = calloc(1, sizeof *c);
    if (!c) {
        if (err && errlen) snprintf(err, errlen, "coast_load: out of memory");
        return NULL;
    }
    if (floe_fw_open(&c->out, "coast_load", path,
                     "t [s],body,contacts,fx [N],fy [N],force [N],length [m],per_length [N/m]\n", err, errlen)) {
        free(c);
        return NULL;
    }
    c->body = body < 0 ? -1 : body;
    c->group = group < 0 ? -1 : group;
    c->length = length;
    c->base.klass = &coast_load_class;
    c->base.period_steps = 1;
    return &c->base;
}
