/* gate_flux.c - the area flux of floes through a gate line (sea ice, docs/sea-ice.md
 * "Outputs"), as CSV: a gate is the segment from A to B; a free 2D particle crosses it when
 * its centre passes from one side of the line to the other between two observations while
 * its projection falls on the segment; crossings towards the right of A -> B (the side of
 * the normal (B - A) rotated clockwise) count positive. One row per observation:
 *   t [s], crossings (net count since the start), area [m^2] (net floe area through the
 *   gate since the start), rate [m^2/s] (area through since the last row / the time since)
 * Observe often enough that no floe crosses and comes back between two rows (interval a
 * fraction of floe size / speed). 2D only. */
#include "floe_observer.h"
#include "file_writer.h"
#include "floe_view.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct gate_flux {
    floe_observer base;
    floe_file_writer out;
    double a[2], b[2];
    long last_step;
    int observed;
    int n;
    signed char *side;   /* per particle: -1 left, +1 right, 0 not yet seen */
    double *area;        /* per particle (cached; -1 not yet) */
    double net_area, last_area, last_t;
    long crossings;
} gate_flux;

static int gf_write(gate_flux *g, floe_world *w) {
    floe_particles_view v;
    FLOE_TRY(floe_world_particles(w, &v));
    if (v.n > g->n) {
        signed char *s = realloc(g->side, (size_t)v.n);
        double *a = s ? realloc(g->area, (size_t)v.n * sizeof *a) : NULL;
        if (s) g->side = s;
        if (!s || !a) return floe_world_report_error(w, FLOE_ENOMEM, "gate_flux: out of memory");
        g->area = a;
        for (int i = g->n; i < v.n; i++) {
            g->side[i] = 0;
            g->area[i] = -1;
        }
        g->n = v.n;
    }
    const double ex = g->b[0] - g->a[0], ey = g->b[1] - g->a[1], L2 = ex * ex + ey * ey;
    for (int i = 0; i < v.n; i++) {
        if (v.motion[i] != FLOE_FREE) continue;
        const double px = v.x[3 * i] - g->a[0], py = v.x[3 * i + 1] - g->a[1];
        const double cr = ex * py - ey * px; /* > 0: left of A -> B */
        const signed char s = cr > 0 ? -1 : 1;
        const double t = (px * ex + py * ey) / L2;
        if (g->side[i] && s != g->side[i] && t >= 0 && t <= 1) {
            if (g->area[i] < 0) {
                floe_mass_properties mp;
                const floe_geometry *geo = floe_world_particle_geometry(w, i);
                g->area[i] = geo && !floe_geometry_mass_properties(geo, 2, 1.0, &mp) ? mp.volume : 0;
            }
            g->crossings += s;
            g->net_area += s * g->area[i];
        }
        g->side[i] = s;
    }
    const double time = floe_world_time(w);
    const double rate = time > g->last_t ? (g->net_area - g->last_area) / (time - g->last_t) : 0;
    floe_fw_row(&g->out, "%.17g,%ld,%.10g,%.10g\n", time, g->crossings, g->net_area, rate);
    g->last_area = g->net_area;
    g->last_t = time;
    g->last_step = floe_world_step_count(w);
    g->observed = 1;
    return floe_fw_flush(&g->out, w);
}

static int gf_observe(floe_observer *o, floe_world *w) {
    gate_flux *g = (gate_flux *)o;
    if (g->observed && g->last_step == floe_world_step_count(w)) return FLOE_OK;
    return gf_write(g, w);
}

static int gf_end(floe_observer *o, floe_world *w) {
    gate_flux *g = (gate_flux *)o;
    int rc = FLOE_OK;
    if (!g->observed || g->last_step != floe_world_step_count(w)) rc = gf_write(g, w);
    int rc2 = floe_fw_close(&g->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void gf_destroy(floe_observer *o) {
    gate_flux *g = (gate_flux *)o;
    floe_fw_free(&g->out);
    free(g->side);
    free(g->area);
    free(g);
}

/* checkpoints (floe_observer_base.h): the file, each particle's side and the sums */
static size_t gf_state_size(const floe_observer *o) {
    const gate_flux *g = (const gate_flux *)o;
    return floe_fw_state_size() + sizeof(int) + (size_t)g->n + 3 * sizeof(double) + sizeof(long);
}
static void gf_save(const floe_observer *o, unsigned char *buf) {
    const gate_flux *g = (const gate_flux *)o;
    buf = floe_fw_state_save(&g->out, g->last_step, g->observed, buf);
    buf = floe_fw_put(buf, &g->n, sizeof g->n);
    if (g->n) buf = floe_fw_put(buf, g->side, (size_t)g->n);
    const double d[3] = {g->net_area, g->last_area, g->last_t};
    buf = floe_fw_put(buf, d, sizeof d);
    floe_fw_put(buf, &g->crossings, sizeof g->crossings);
}
static int gf_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    gate_flux *g = (gate_flux *)o;
    int m = -1;
    if (n >= floe_fw_state_size() + sizeof m) memcpy(&m, buf + floe_fw_state_size(), sizeof m);
    if (m < 0 || n != floe_fw_state_size() + sizeof(int) + (size_t)m + 3 * sizeof(double) + sizeof(long))
        return floe_world_report_error(w, FLOE_EINVAL, "gate_flux: checkpoint state does not match");
    signed char *sd = realloc(g->side, (size_t)(m ? m : 1));
    double *a = sd ? realloc(g->area, (size_t)(m ? m : 1) * sizeof *a) : NULL;
    if (sd) g->side = sd;
    if (!sd || !a) return floe_world_report_error(w, FLOE_ENOMEM, "gate_flux: out of memory");
    g->area = a;
    for (int i = 0; i < m; i++) a[i] = -1;
    g->n = m;
    FLOE_TRY(floe_fw_state_restore(&g->out, w, &g->last_step, &g->observed, buf));
    buf += floe_fw_state_size() + sizeof m;
    if (m) buf = floe_fw_get(buf, g->side, (size_t)m);
    double d[3];
    buf = floe_fw_get(buf, d, sizeof d);
    g->net_area = d[0]; g->last_area = d[1]; g->last_t = d[2];
    floe_fw_get(buf, &g->crossings, sizeof g->crossings);
    return FLOE_OK;
}

static const floe_observer_class gate_flux_class = {3, "gate_flux", NULL, gf_observe, gf_end, gf_destroy, 0,
                                                    gf_state_size, gf_save, gf_restore, 0, NULL, NULL};

floe_observer *floe_gate_flux_create(const char *path, int dim, const double a[2], const double b[2], char *err,
                                     size_t errlen) {
    if (err && errlen) err[0] = '\0';
    const char *bad = dim != 2 ? "gate_flux is a 2D output (dimension: 2)"
                      : !path || !*path ? "gate_flux: need a path"
                      : !(isfinite(a[0]) && isfinite(a[1]) && isfinite(b[0]) && isfinite(b[1])) ? "gate_flux: from and to must be finite"
                      : a[0] == b[0] && a[1] == b[1] ? "gate_flux: from and to must differ (a segment)"
                                                     : NULL;
    if (bad) {
        if (err && errlen) snprintf(err, errlen, "%s", bad);
        return NULL;
    }
    gate_flux *g = calloc(1, sizeof *g);
    if (!g) {
        if (err && errlen) snprintf(err, errlen, "gate_flux: out of memory");
        return NULL;
    }
    if (floe_fw_open(&g->out, "gate_flux", path, "t [s],crossings,area [m^2],rate [m^2/s]\n", err, errlen)) {
        free(g);
        return NULL;
    }
    memcpy(g->a, a, sizeof g->a);
    memcpy(g->b, b, sizeof g->b);
    g->base.klass = &gate_flux_class;
    g->base.period_steps = 1;
    return &g->base;
}
