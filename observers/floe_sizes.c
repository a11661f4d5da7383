/* floe_sizes.c - the floe size distribution over time (sea ice, docs/sea-ice.md "Outputs"),
 * as CSV: a floe is a connected set of free 2D particles joined by intact beam bonds (a
 * rigid floe is one particle; a bonded floe breaks into fragments as its bonds break), one
 * row per floe per observation:
 *   t [s], floe (its smallest particle id), particles, area [m^2], x [m], y [m]
 * with the area the sum of its particles' areas (their 2D mass properties) and (x, y) the
 * area-weighted centroid of their centres. Fixed and kinematic particles (coasts, walls)
 * are not floes. Rows are ordered by floe id; every observation is one flush of whole rows
 * (observers/file_writer.h). 2D only. */
#include "floe_observer.h"
#include "file_writer.h"
#include "floe_view.h"
#include "floe_world_beams.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct floe_sizes {
    floe_observer base;
    floe_file_writer out;
    long last_step;
    int observed;
    int n;          /* particles sized for */
    int *parent;    /* union-find */
    double *area;   /* per particle (cached: the geometry's area; -1 not yet) */
    double *acc;    /* per root: area, area x, area y, count */
} floe_sizes;

static int find(int *parent, int i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static int fs_reserve(floe_sizes *s, int n) {
    if (n <= s->n) return FLOE_OK;
    int *p = realloc(s->parent, (size_t)n * sizeof *p);
    if (!p) return FLOE_ENOMEM;
    s->parent = p;
    double *a = realloc(s->area, (size_t)n * sizeof *a);
    if (!a) return FLOE_ENOMEM;
    s->area = a;
    for (int i = s->n; i < n; i++) s->area[i] = -1;
    double *c = realloc(s->acc, (size_t)n * 4 * sizeof *c);
    if (!c) return FLOE_ENOMEM;
    s->acc = c;
    s->n = n;
    return FLOE_OK;
}

static int fs_write(floe_sizes *s, floe_world *w) {
    floe_particles_view v;
    FLOE_TRY(floe_world_particles(w, &v));
    if (fs_reserve(s, v.n)) return floe_world_report_error(w, FLOE_ENOMEM, "floe_sizes: out of memory");
    for (int i = 0; i < v.n; i++) s->parent[i] = i;
    const int nb = floe_world_beam_bond_count(w);
    for (int k = 0; k < nb; k++) {
        floe_beam_bond_info b;
        if (floe_world_beam_bond(w, k, &b) || b.broken) continue;
        if (v.motion[b.i] != FLOE_FREE || v.motion[b.j] != FLOE_FREE) continue;
        int ri = find(s->parent, b.i), rj = find(s->parent, b.j);
        if (ri != rj) s->parent[ri > rj ? ri : rj] = ri < rj ? ri : rj; /* the smaller id is the root */
    }
    memset(s->acc, 0, (size_t)v.n * 4 * sizeof *s->acc);
    for (int i = 0; i < v.n; i++) {
        if (v.motion[i] != FLOE_FREE) continue;
        if (s->area[i] < 0) {
            floe_mass_properties mp;
            const floe_geometry *g = floe_world_particle_geometry(w, i);
            s->area[i] = g && !floe_geometry_mass_properties(g, 2, 1.0, &mp) ? mp.volume : 0;
        }
        double *a = s->acc + 4 * (size_t)find(s->parent, i);
        a[0] += s->area[i];
        a[1] += s->area[i] * v.x[3 * i];
        a[2] += s->area[i] * v.x[3 * i + 1];
        a[3] += 1;
    }
    const double t = floe_world_time(w);
    for (int i = 0; i < v.n; i++) {
        const double *a = s->acc + 4 * (size_t)i;
        if (v.motion[i] != FLOE_FREE || s->parent[i] != i || !(a[3] > 0)) continue;
        double x = a[0] > 0 ? a[1] / a[0] : v.x[3 * i], y = a[0] > 0 ? a[2] / a[0] : v.x[3 * i + 1];
        if (!isfinite(x) || !isfinite(y))
            return floe_world_report_error(w, FLOE_EUNSTABLE, "floe_sizes: floe %d's centroid is not finite at t = %g s",
                                           i, t);
        floe_fw_row(&s->out, "%.17g,%d,%.0f,%.10g,%.10g,%.10g\n", t, i, a[3], a[0], x, y);
    }
    s->last_step = floe_world_step_count(w);
    s->observed = 1;
    return floe_fw_flush(&s->out, w);
}

static int fs_observe(floe_observer *o, floe_world *w) {
    floe_sizes *s = (floe_sizes *)o;
    if (s->observed && s->last_step == floe_world_step_count(w)) return FLOE_OK;
    return fs_write(s, w);
}

static int fs_end(floe_observer *o, floe_world *w) {
    floe_sizes *s = (floe_sizes *)o;
    int rc = FLOE_OK;
    if (!s->observed || s->last_step != floe_world_step_count(w)) rc = fs_write(s, w);
    int rc2 = floe_fw_close(&s->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void fs_destroy(floe_observer *o) {
    floe_sizes *s = (floe_sizes *)o;
    floe_fw_free(&s->out);
    free(s->parent);
    free(s->area);
    free(s->acc);
    free(s);
}

/* checkpoints (floe_observer_base.h): the file's length, the last row block's step */
static size_t fs_state_size(const floe_observer *o) {
    (void)o;
    return floe_fw_state_size();
}
static void fs_save(const floe_observer *o, unsigned char *buf) {
    const floe_sizes *t = (const floe_sizes *)o;
    floe_fw_state_save(&t->out, t->last_step, t->observed, buf);
}
static int fs_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    floe_sizes *t = (floe_sizes *)o;
    if (n != floe_fw_state_size())
        return floe_world_report_error(w, FLOE_EINVAL, "%s: checkpoint state does not match", t->out.who);
    return floe_fw_state_restore(&t->out, w, &t->last_step, &t->observed, buf);
}

static const floe_observer_class floe_sizes_class = {3, "floe_sizes", NULL, fs_observe, fs_end, fs_destroy, 0,
    fs_state_size, fs_save, fs_restore, 0, NULL, NULL};

floe_observer *floe_sizes_create(const char *path, int dim, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (dim != 2) {
        if (err && errlen) snprintf(err, errlen, "floe_sizes is a 2D output (dimension: 2)");
        return NULL;
    }
    if (!path || !*path) {
        if (err && errlen) snprintf(err, errlen, "floe_sizes: need a path");
        return NULL;
    }
    floe_sizes *s = calloc(1, sizeof *s);
    if (!s) {
        if (err && errlen) snprintf(err, errlen, "floe_sizes: out of memory");
        return NULL;
    }
    if (floe_fw_open(&s->out, "floe_sizes", path, "t [s],floe,particles,area [m^2],x [m],y [m]\n", err, errlen)) {
        free(s);
        return NULL;
    }
    s->base.klass = &floe_sizes_class;
    s->base.period_steps = 1;
    return &s->base;
}
