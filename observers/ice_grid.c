/* ice_grid.c - sea ice on a regular grid (docs/sea-ice.md "Outputs"): per cell of an nx x ny
 * grid over a rectangle, the ice concentration (the fraction of the cell inside floes), the
 * mean ice velocity and the mean ice thickness over the ice in it, written as a VTK series
 * (one .vtu per frame, each cell a VTK_QUAD, ASCII; DIR/PREFIX.pvd lists the frames), for
 * ParaView or a comparison with a continuum model's fields.
 *
 * Each cell is sampled at s x s points (the centres of its s x s sub-cells); a point counts
 * as ice when it is inside a free 2D particle (its SDF < 0; the first such particle by id
 * where floes overlap), and then carries that particle's velocity at the point (v + w k x r)
 * and thickness (1 m for a particle without one). Concentration = ice points / s^2 (exact
 * for a floe edge on the sub-cell lines, error O(1/s) otherwise); velocity and thickness are
 * the means over the ice points (0 without ice). 2D only. */
#include "floe_observer.h"
#include "file_writer.h"
#include "floe_view.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct ice_grid {
    floe_observer base;
    floe_fw_series ser;   /* DIR/PREFIX_NNNNNN.vtu, DIR/PREFIX.pvd */
    double lo[2], hi[2];
    int nx, ny, s;
    unsigned char *owned; /* per sample: taken by a floe already */
    double *acc;          /* per cell: ice samples, vx, vy, h sums */
} ice_grid;

static void ig_sample(ice_grid *g, const floe_world *w, const floe_particles_view *v) {
    const int nx = g->nx, ny = g->ny, s = g->s, NX = nx * s, NY = ny * s;
    const double hx = (g->hi[0] - g->lo[0]) / NX, hy = (g->hi[1] - g->lo[1]) / NY;
    memset(g->owned, 0, (size_t)NX * NY);
    memset(g->acc, 0, (size_t)nx * ny * 4 * sizeof *g->acc);
    for (int i = 0; i < v->n; i++) {
        if (v->motion[i] != FLOE_FREE || !(v->radius[i] < INFINITY)) continue;
        const floe_geometry *geo = floe_world_particle_geometry(w, i);
        if (!geo) continue;
        const double *x = v->x + 3 * i, *q = v->q + 4 * i, R = v->radius[i];
        const double ca = q[0] * q[0] - q[3] * q[3], sa = 2 * q[0] * q[3]; /* rotation about z */
        const double h = v->thickness && v->thickness[i] > 0 ? v->thickness[i] : 1.0, wz = v->w[3 * i + 2];
        int i0 = (int)floor((x[0] - R - g->lo[0]) / hx), i1 = (int)ceil((x[0] + R - g->lo[0]) / hx);
        int j0 = (int)floor((x[1] - R - g->lo[1]) / hy), j1 = (int)ceil((x[1] + R - g->lo[1]) / hy);
        if (i0 < 0) i0 = 0;
        if (j0 < 0) j0 = 0;
        if (i1 > NX) i1 = NX;
        if (j1 > NY) j1 = NY;
        for (int b = j0; b < j1; b++)
            for (int a = i0; a < i1; a++) {
                unsigned char *own = g->owned + (size_t)b * NX + a;
                if (*own) continue;
                const double rx = g->lo[0] + (a + 0.5) * hx - x[0], ry = g->lo[1] + (b + 0.5) * hy - x[1];
                const double X[3] = {ca * rx + sa * ry, -sa * rx + ca * ry, 0}; /* into the body frame */
                if (!(floe_geometry_sdf(geo, X) < 0)) continue;
                *own = 1;
                double *c = g->acc + 4 * ((size_t)(b / s) * nx + (size_t)(a / s));
                c[0] += 1;
                c[1] += v->v[3 * i] - wz * ry;
                c[2] += v->v[3 * i + 1] + wz * rx;
                c[3] += h;
            }
    }
}

static void ig_frame(const ice_grid *g, FILE *f, double time, long step) {
    const int nx = g->nx, ny = g->ny, nc = nx * ny, np = (nx + 1) * (ny + 1);
    const double hx = (g->hi[0] - g->lo[0]) / nx, hy = (g->hi[1] - g->lo[1]) / ny, s2 = (double)g->s * g->s;
    floe_fw_vtu_begin(f, time, step);
    fprintf(f, "    <Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">\n      <PointData>\n      </PointData>\n", np, nc);
    fputs("      <CellData Scalars=\"concentration\" Vectors=\"velocity\">\n", f);
    fputs("        <DataArray type=\"Float64\" Name=\"concentration\" format=\"ascii\">\n", f);
    for (int k = 0; k < nc; k++) fprintf(f, "%.17g\n", g->acc[4 * k] / s2);
    fputs("        </DataArray>\n        <DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" "
          "format=\"ascii\">\n", f);
    for (int k = 0; k < nc; k++) {
        const double *c = g->acc + 4 * k, m = c[0] > 0 ? 1.0 / c[0] : 0;
        fprintf(f, "%.17g %.17g 0\n", c[1] * m, c[2] * m);
    }
    fputs("        </DataArray>\n        <DataArray type=\"Float64\" Name=\"thickness\" format=\"ascii\">\n", f);
    for (int k = 0; k < nc; k++) fprintf(f, "%.17g\n", g->acc[4 * k] > 0 ? g->acc[4 * k + 3] / g->acc[4 * k] : 0);
    fputs("        </DataArray>\n      </CellData>\n      <Points>\n"
          "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n", f);
    for (int j = 0; j <= ny; j++)
        for (int i = 0; i <= nx; i++) fprintf(f, "%.17g %.17g 0\n", g->lo[0] + i * hx, g->lo[1] + j * hy);
    fputs("        </DataArray>\n      </Points>\n      <Cells>\n"
          "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n", f);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            const long a = (long)j * (nx + 1) + i;
            fprintf(f, "%ld %ld %ld %ld\n", a, a + 1, a + nx + 2, a + nx + 1);
        }
    fputs("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n", f);
    for (int k = 0; k < nc; k++) fprintf(f, "%ld\n", 4L * (k + 1));
    fputs("        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n", f);
    for (int k = 0; k < nc; k++) fputs("9\n", f); /* VTK_QUAD */
    fputs("        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n", f);
}

static int ig_write(ice_grid *g, floe_world *w) {
    floe_particles_view v;
    FLOE_TRY(floe_world_particles(w, &v));
    ig_sample(g, w, &v);
    const double time = floe_world_time(w);
    const long step = floe_world_step_count(w);
    floe_fw_replace r;
    FLOE_TRY(floe_fw_series_begin(&g->ser, w, &r));
    ig_frame(g, r.f, time, step);
    return floe_fw_series_commit(&g->ser, w, &r, time, step);
}

static int ig_observe(floe_observer *o, floe_world *w) {
    ice_grid *g = (ice_grid *)o;
    return floe_fw_series_due(&g->ser, floe_world_step_count(w)) ? ig_write(g, w) : FLOE_OK;
}

static int ig_end(floe_observer *o, floe_world *w) {
    ice_grid *g = (ice_grid *)o;
    return floe_fw_series_due(&g->ser, floe_world_step_count(w)) ? ig_write(g, w) : FLOE_OK;
}

static void ig_destroy(floe_observer *o) {
    ice_grid *g = (ice_grid *)o;
    floe_fw_series_free(&g->ser);
    free(g->owned);
    free(g->acc);
    free(g);
}

/* checkpoints (floe_observer_base.h): the series' frames */
static size_t ig_state_size(const floe_observer *o) {
    return floe_fw_series_state_size(&((const ice_grid *)o)->ser);
}
static void ig_save(const floe_observer *o, unsigned char *buf) {
    floe_fw_series_state_save(&((const ice_grid *)o)->ser, buf);
}
static int ig_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    return floe_fw_series_state_restore(&((ice_grid *)o)->ser, w, buf, n);
}

static const floe_observer_class ice_grid_class = {3, "ice_grid", NULL, ig_observe, ig_end, ig_destroy, 0,
    ig_state_size, ig_save, ig_restore, 1, NULL, NULL};

floe_observer *floe_ice_grid_create(const char *dir, const char *prefix, int dim, const double lo[2],
                                    const double hi[2], int nx, int ny, int samples, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    const char *bad = dim != 2 ? "ice_grid is a 2D output (dimension: 2)"
                      : !dir || !prefix || !*prefix ? "ice_grid: need a directory and a prefix"
                      : !(hi[0] > lo[0] && hi[1] > lo[1] && isfinite(hi[0] - lo[0]) && isfinite(hi[1] - lo[1]))
                          ? "ice_grid: max must exceed min on x and y (finite)"
                      : nx < 1 || ny < 1 || samples < 1 ? "ice_grid: cells and samples must be >= 1"
                      : (double)nx * ny * samples * samples > 1e8 ? "ice_grid: more than 1e8 samples (cells x samples^2)"
                                                                  : NULL;
    if (bad) {
        if (err && errlen) snprintf(err, errlen, "%s", bad);
        return NULL;
    }
    ice_grid *g = calloc(1, sizeof *g);
    if (g) {
        g->owned = malloc((size_t)nx * ny * samples * samples);
        g->acc = malloc((size_t)nx * ny * 4 * sizeof *g->acc);
    }
    if (!g || floe_fw_series_init(&g->ser, "ice_grid", dir, prefix) || !g->owned || !g->acc) {
        if (g) ig_destroy(&g->base);
        if (err && errlen) snprintf(err, errlen, "ice_grid: out of memory");
        return NULL;
    }
    memcpy(g->lo, lo, sizeof g->lo);
    memcpy(g->hi, hi, sizeof g->hi);
    g->nx = nx;
    g->ny = ny;
    g->s = samples;
    g->base.klass = &ice_grid_class;
    g->base.period_steps = 1;
    return &g->base;
}
