/* outline_writer.c - the particles of a 2D world as their outlines: VTK XML UnstructuredGrid
 * files of VTK_POLYGON cells, one per frame, for ParaView (sea-ice floes drawn as the
 * polygons they are; the `vtk` output draws every particle as a point).
 *
 * Files, as the vtk output writes them (the series helpers of file_writer.h):
 *   PREFIX_NNNNNN.vtu  frame NNNNNN (0, 1, 2, ... in order of writing)
 *   PREFIX.pvd         ParaView collection (timestep = simulated time), rewritten after
 *                      every frame; every file goes through a temporary name and a rename.
 *
 * Content of a frame: for every particle with a bounded radius (walls left out), its outline
 * in world coordinates (z = 0), counter-clockwise, as VTK_POLYGON (7) cells:
 *   - a convex polytope (polygon, 2D box): its corners (the class's `polytope` in 2D; their
 *     convex hull, so that any order of the corners gives the polygon);
 *   - a compound (floe_geometry_piece_count > 1, e.g. a non-convex floe made of convex
 *     pieces): one cell per piece, the piece's outline placed by its pose in the body frame
 *     (the class's `piece`), every cell carrying the particle's id;
 *   - any other shape (a disc, an ellipse, a user SDF): `segments` points, one on each ray
 *     from the body origin at the angles 2 pi k / segments (k = 0 at the body x axis): the
 *     outermost point of the ray on the boundary (ray_exit). Exact to rounding for a shape
 *     that is star-shaped about its origin (every ray crosses the boundary once). The
 *     polygon is inscribed: a disc of radius r gives the area (N/2) r^2 sin(2 pi / N).
 *   A body-frame point p of particle i (position x, orientation q) is at x + R(q) p.
 * Cell data: id (Int32, world particle index), body (Int32, group tag), material (Int32),
 *   velocity (Float64 x3, m/s), angular_velocity (Float64 x3, rad/s), area (Float64, m^2:
 *   the polygon's own area, as drawn) and thickness (Float64, m: a floe's, 0 for a body
 *   without one). No point data.
 * Field data: TimeValue (Float64, s) and Step (Int64), as the vtk output.
 *
 * Particle state is read through the public view only (floe_world_get_particle and the
 * world's geometry accessors). A NaN or infinity is never written: the frame is refused
 * (FLOE_EUNSTABLE, reported) naming the particle. Encoding: raw binary appended data by
 * default, ASCII on request; frames without cells are written in ASCII (empty arrays).
 * end() writes the final state if this step was not written yet. */
#include "floe_observer.h"
#include "file_writer.h"
#include "floe_view.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define OUTLINE_TWO_PI 6.283185307179586476925286766559

typedef struct pt2 { double x, y; } pt2;

typedef struct outline_writer {
    floe_observer base;
    floe_fw_series ser;              /* DIR/PREFIX_NNNNNN.vtu, DIR/PREFIX.pvd */
    int ascii, segments;
    /* the frame being assembled: cells */
    int ncell, cell_cap;
    int32_t *id, *body, *material;
    double *vel, *angvel, *area;     /* 3, 3 and 1 per cell */
    double *thick;                   /* 1 per cell: the floe's thickness (m; 0: none) */
    int64_t *offsets;                /* the end of each cell's points */
    uint8_t *types;
    /* ... and their points (each cell's points consecutive) */
    int npt, pt_cap;
    double *pts;                     /* 3 per point, world frame */
    int64_t *conn;
    /* one outline in its own frame, and the hull's work space */
    pt2 *loc, *hull;
    int loc_cap;
} outline_writer;

static const floe_observer_class outline_writer_class;

enum { O_ID, O_BODY, O_MATERIAL, O_VELOCITY, O_ANGVEL, O_AREA, O_THICK, O_POINTS, O_CONN, O_OFFSETS, O_TYPES, O_COUNT };

typedef struct array_desc { const char *name; floe_fw_vtk_type type; int ncomp; } array_desc;

static const array_desc arrays[O_COUNT] = {
    {"id", FLOE_FW_INT32, 1},      {"body", FLOE_FW_INT32, 1},       {"material", FLOE_FW_INT32, 1},
    {"velocity", FLOE_FW_FLOAT64, 3}, {"angular_velocity", FLOE_FW_FLOAT64, 3}, {"area", FLOE_FW_FLOAT64, 1},
    {"thickness", FLOE_FW_FLOAT64, 1}, {"Points", FLOE_FW_FLOAT64, 3}, {"connectivity", FLOE_FW_INT64, 1}, {"offsets", FLOE_FW_INT64, 1},
    {"types", FLOE_FW_UINT8, 1},
};

/* the values of array k and their number of tuples */
static const void *array_data(const outline_writer *o, int k, int *tuples) {
    *tuples = k == O_POINTS || k == O_CONN ? o->npt : o->ncell;
    switch (k) {
    case O_ID: return o->id;
    case O_BODY: return o->body;
    case O_MATERIAL: return o->material;
    case O_VELOCITY: return o->vel;
    case O_ANGVEL: return o->angvel;
    case O_AREA: return o->area;
    case O_THICK: return o->thick;
    case O_POINTS: return o->pts;
    case O_CONN: return o->conn;
    case O_OFFSETS: return o->offsets;
    default: return o->types;
    }
}

/* ---- storage ---- */

static int grow(void **p, size_t elem, int n) {
    void *q = realloc(*p, (size_t)n * elem);
    if (!q) return FLOE_ENOMEM;
    *p = q;
    return FLOE_OK;
}

/* room for `more` cells and `more_pts` points */
static int reserve(outline_writer *o, int more, int more_pts) {
    if (o->ncell + more > o->cell_cap) {
        int c = 2 * o->cell_cap > o->ncell + more ? 2 * o->cell_cap : o->ncell + more + 16;
        if (grow((void **)&o->id, sizeof *o->id, c) || grow((void **)&o->body, sizeof *o->body, c) ||
            grow((void **)&o->material, sizeof *o->material, c) || grow((void **)&o->vel, 3 * sizeof *o->vel, c) ||
            grow((void **)&o->angvel, 3 * sizeof *o->angvel, c) || grow((void **)&o->area, sizeof *o->area, c) ||
            grow((void **)&o->thick, sizeof *o->thick, c) ||
            grow((void **)&o->offsets, sizeof *o->offsets, c) || grow((void **)&o->types, sizeof *o->types, c))
            return FLOE_ENOMEM;
        o->cell_cap = c;
    }
    if (o->npt + more_pts > o->pt_cap) {
        int c = 2 * o->pt_cap > o->npt + more_pts ? 2 * o->pt_cap : o->npt + more_pts + 64;
        if (grow((void **)&o->pts, 3 * sizeof *o->pts, c) || grow((void **)&o->conn, sizeof *o->conn, c))
            return FLOE_ENOMEM;
        o->pt_cap = c;
    }
    return FLOE_OK;
}

static int reserve_local(outline_writer *o, int n) {
    if (n <= o->loc_cap) return FLOE_OK;
    if (grow((void **)&o->loc, sizeof *o->loc, n) || grow((void **)&o->hull, sizeof *o->hull, n + 1))
        return FLOE_ENOMEM;
    o->loc_cap = n;
    return FLOE_OK;
}

/* ---- one convex shape's outline in its own frame ---- */

static int cmp_pt2(const void *a, const void *b) {
    const pt2 *p = a, *q = b;
    if (p->x != q->x) return p->x < q->x ? -1 : 1;
    return (p->y > q->y) - (p->y < q->y);
}

static double cross3(pt2 o, pt2 a, pt2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

/* the convex hull of p[0..n) (Andrew's monotone chain), counter-clockwise and without
 * collinear or repeated points, into h (n + 1 room); returns its number of corners */
static int convex_hull(pt2 *p, int n, pt2 *h) {
    qsort(p, (size_t)n, sizeof *p, cmp_pt2);
    int k = 0;
    for (int i = 0; i < n; i++) {
        while (k >= 2 && cross3(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k++] = p[i];
    }
    for (int i = n - 2, lo = k + 1; i >= 0; i--) {
        while (k >= lo && cross3(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k++] = p[i];
    }
    return k > 1 ? k - 1 : k;
}

static double sdf_at(const floe_geometry *g, double t, double c, double s) {
    const double X[3] = {t * c, t * s, 0.0};
    return floe_geometry_sdf(g, X);
}

/* The distance from the origin, along the ray of direction (c, s), of the outermost point
 * where the ray meets the shape's boundary: march in from just outside the bounding circle
 * with steps of the SDF (which never overestimates the distance to the surface, so no
 * crossing is stepped over; the steps are at least R/1024, which only a feature thinner than
 * that could slip between), then bisect between the last point outside and the first inside
 * down to rounding. A class's `project` would give the nearest surface point, which is on
 * the ray only for a disc; bisection is exact on every ray. 0 when the ray misses the shape
 * (an origin outside a shape that is not star-shaped about it); NaN when the SDF is. */
static double ray_exit(const floe_geometry *g, double c, double s, double R) {
    double t_out = R * (1.0 + 1.0 / 64.0), d = sdf_at(g, t_out, c, s);
    for (int k = 0; k < 16 && d <= 0; k++) { /* a bounding radius that is not one */
        t_out *= 2.0;
        d = sdf_at(g, t_out, c, s);
    }
    if (isnan(d)) return NAN;
    if (d <= 0) return t_out;
    double floor_step = R / 1024.0, t_in = -1.0, t = t_out;
    while (t > 0) {
        t -= d > floor_step ? d : floor_step;
        if (t < 0) t = 0;
        d = sdf_at(g, t, c, s);
        if (isnan(d)) return NAN;
        if (d <= 0) {
            t_in = t;
            break;
        }
        t_out = t;
        if (t == 0) break;
    }
    if (t_in < 0) return 0.0;
    for (int k = 0; k < 200 && t_out - t_in > 2.0 * DBL_EPSILON * t_out; k++) {
        double mid = 0.5 * (t_in + t_out);
        if (mid <= t_in || mid >= t_out) break;
        d = sdf_at(g, mid, c, s);
        if (isnan(d)) return NAN;
        if (d <= 0) t_in = mid;
        else t_out = mid;
    }
    return 0.5 * (t_in + t_out);
}

/* the outline of the convex (or star-shaped) shape h in its own frame into o->loc:
 * FLOE_OK with *n points, or FLOE_ENOMEM */
static int shape_outline(outline_writer *o, const floe_geometry *h, int *n) {
    floe_polytope_view pv;
    if (floe_geometry_polytope(h, 2, &pv) && pv.nv >= 3) {
        FLOE_TRY(reserve_local(o, pv.nv));
        for (int k = 0; k < pv.nv; k++) o->loc[k] = (pt2){pv.v[3 * k], pv.v[3 * k + 1]};
        int m = convex_hull(o->loc, pv.nv, o->hull);
        memcpy(o->loc, o->hull, (size_t)m * sizeof *o->loc);
        *n = m;
        return FLOE_OK;
    }
    int N = o->segments;
    FLOE_TRY(reserve_local(o, N));
    double R = floe_geometry_bounding_radius(h);
    for (int k = 0; k < N; k++) {
        double a = OUTLINE_TWO_PI * k / N, c = cos(a), s = sin(a);
        double r = ray_exit(h, c, s, R);
        o->loc[k] = (pt2){r * c, r * s};
    }
    *n = N;
    return FLOE_OK;
}

/* ---- cells ---- */

/* Appends the outline o->loc[0..n) of a shape whose frame sits at (px, pq) in the body frame
 * of particle i (state st) as one polygon cell, counter-clockwise in the world. */
static int add_cell(outline_writer *o, int i, const floe_particle_state *st, int n, const double px[3],
                    const double pq[4]) {
    FLOE_TRY(reserve(o, 1, n));
    double *rel = o->pts + 3 * (size_t)o->npt; /* world offsets from the centre first */
    double twice = 0.0;
    for (int k = 0; k < n; k++) {
        double p[3] = {o->loc[k].x, o->loc[k].y, 0.0}, b[3], r[3];
        floe_q_rotate(b, pq, p);
        for (int c = 0; c < 3; c++) b[c] += px[c];
        floe_q_rotate(r, st->q, b);
        rel[3 * k] = r[0];
        rel[3 * k + 1] = r[1];
        rel[3 * k + 2] = 0.0;
    }
    for (int k = 0; k < n; k++) { /* shoelace on the offsets: exact of the translation */
        const double *a = rel + 3 * k, *b = rel + 3 * ((k + 1) % n);
        twice += a[0] * b[1] - a[1] * b[0];
    }
    if (twice < 0) { /* clockwise: reverse */
        for (int a = 0, b = n - 1; a < b; a++, b--)
            for (int c = 0; c < 2; c++) {
                double t = rel[3 * a + c];
                rel[3 * a + c] = rel[3 * b + c];
                rel[3 * b + c] = t;
            }
    }
    for (int k = 0; k < n; k++) {
        rel[3 * k] += st->x[0];
        rel[3 * k + 1] += st->x[1];
        o->conn[o->npt + k] = o->npt + k;
    }
    o->npt += n;
    int j = o->ncell++;
    o->id[j] = (int32_t)i;
    o->body[j] = (int32_t)st->group;
    o->material[j] = (int32_t)st->material;
    memcpy(o->vel + 3 * (size_t)j, st->v, 3 * sizeof(double));
    memcpy(o->angvel + 3 * (size_t)j, st->w, 3 * sizeof(double));
    o->area[j] = 0.5 * fabs(twice);
    o->thick[j] = st->thickness;
    o->offsets[j] = o->npt;
    o->types[j] = 7; /* VTK_POLYGON */
    return FLOE_OK;
}

/* the cells of particle i: one, or one per piece of a compound */
static int add_particle(outline_writer *o, const floe_world *w, int i, const floe_particle_state *st) {
    const floe_geometry *g = floe_world_particle_geometry(w, i);
    if (!g) return FLOE_OK;
    static const double origin[3] = {0, 0, 0}, identity[4] = {1, 0, 0, 0};
    int np = floe_geometry_piece_count(g), n = 0;
    if (np <= 1 || !g->klass->piece) {
        FLOE_TRY(shape_outline(o, g, &n));
        return add_cell(o, i, st, n, origin, identity);
    }
    for (int k = 0; k < np; k++) {
        double px[3], pq[4], pr;
        const floe_geometry *h = g->klass->piece(g, k, px, pq, &pr);
        if (!h) continue;
        FLOE_TRY(shape_outline(o, h, &n));
        FLOE_TRY(add_cell(o, i, st, n, px, pq));
    }
    return FLOE_OK;
}

/* the name of the first non-finite value of cells [c0, ncell), or NULL */
static const char *non_finite(const outline_writer *o, int c0) {
    for (int j = c0; j < o->ncell; j++) {
        for (int c = 0; c < 3; c++) {
            if (!isfinite(o->vel[3 * (size_t)j + c])) return "velocity";
            if (!isfinite(o->angvel[3 * (size_t)j + c])) return "angular_velocity";
        }
        if (!isfinite(o->area[j])) return "outline (area)";
        for (int64_t p = j ? o->offsets[j - 1] : 0; p < o->offsets[j]; p++)
            for (int c = 0; c < 3; c++)
                if (!isfinite(o->pts[3 * p + c])) return "outline point";
    }
    return NULL;
}

/* the frame's cells from the world's particles: FLOE_OK, or an error reported through w */
static int assemble(outline_writer *o, floe_world *w) {
    o->ncell = o->npt = 0;
    int n = floe_world_particle_count(w);
    for (int i = 0; i < n; i++) {
        floe_particle_state st;
        if (floe_world_get_particle(w, i, &st) != FLOE_OK) continue;
        if (!isfinite(st.radius) || floe_world_particle_kind(w, i) == FLOE_GEOM_PLANE) continue; /* walls */
        int c0 = o->ncell;
        const char *bad = NULL;
        for (int c = 0; c < 3 && !bad; c++)
            if (!isfinite(st.x[c])) bad = "position";
        for (int c = 0; c < 4 && !bad; c++)
            if (!isfinite(st.q[c])) bad = "orientation";
        if (!bad) {
            if (add_particle(o, w, i, &st) != FLOE_OK)
                return floe_world_report_error(w, FLOE_ENOMEM, "outline writer: out of memory");
            bad = non_finite(o, c0);
        }
        if (bad)
            return floe_world_report_error(w, FLOE_EUNSTABLE, "outline writer: particle %d has a non-finite %s at "
                                           "t = %g s (step %ld): frame not written", i, bad, floe_world_time(w),
                                           floe_world_step_count(w));
    }
    return FLOE_OK;
}

/* ---- files ---- */

static void write_frame(const outline_writer *o, FILE *f, double time, long step) {
    int ascii = o->ascii || o->ncell == 0;
    floe_fw_vtu_begin(f, time, step);
    fprintf(f, "    <Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">\n      <PointData>\n      </PointData>\n",
            o->npt, o->ncell);
    uint64_t offset = 0;
    for (int k = 0; k < O_COUNT; k++) {
        if (k == O_ID) fputs("      <CellData Scalars=\"area\" Vectors=\"velocity\">\n", f);
        if (k == O_POINTS) fputs("      </CellData>\n      <Points>\n", f);
        if (k == O_CONN) fputs("      </Points>\n      <Cells>\n", f);
        const array_desc *a = &arrays[k];
        int m;
        const void *data = array_data(o, k, &m);
        fprintf(f, "        <DataArray type=\"%s\" Name=\"%s\"", floe_fw_vtk_type_name(a->type), a->name);
        if (a->ncomp > 1) fprintf(f, " NumberOfComponents=\"%d\"", a->ncomp);
        if (ascii) {
            fputs(" format=\"ascii\">\n", f);
            floe_fw_vtk_ascii_values(f, a->type, a->ncomp, m, data);
            fputs("        </DataArray>\n", f);
        } else {
            fprintf(f, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)offset);
            offset += sizeof(uint64_t) + (uint64_t)m * (uint64_t)a->ncomp * floe_fw_vtk_type_size(a->type);
        }
    }
    fputs("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n", f);
    if (!ascii) {
        fputs("  <AppendedData encoding=\"raw\">\n   _", f);
        for (int k = 0; k < O_COUNT; k++) {
            int m;
            const void *data = array_data(o, k, &m);
            uint64_t nbytes = (uint64_t)m * (uint64_t)arrays[k].ncomp * floe_fw_vtk_type_size(arrays[k].type);
            fwrite(&nbytes, sizeof nbytes, 1, f);
            fwrite(data, 1, (size_t)nbytes, f);
        }
        fputs("\n  </AppendedData>\n", f);
    }
    fputs("</VTKFile>\n", f);
}

static int ow_write(outline_writer *o, floe_world *w) {
    double time = floe_world_time(w);
    long step = floe_world_step_count(w);
    FLOE_TRY(assemble(o, w));
    floe_fw_replace r;
    FLOE_TRY(floe_fw_series_begin(&o->ser, w, &r));
    write_frame(o, r.f, time, step);
    return floe_fw_series_commit(&o->ser, w, &r, time, step);
}

static int ow_observe(floe_observer *b, floe_world *w) {
    outline_writer *o = (outline_writer *)b;
    return floe_fw_series_due(&o->ser, floe_world_step_count(w)) ? ow_write(o, w) : FLOE_OK;
}

static int ow_end(floe_observer *b, floe_world *w) {
    outline_writer *o = (outline_writer *)b;
    return floe_fw_series_due(&o->ser, floe_world_step_count(w)) ? ow_write(o, w) : FLOE_OK;
}

static void ow_destroy(floe_observer *b) {
    outline_writer *o = (outline_writer *)b;
    floe_fw_series_free(&o->ser);
    free(o->id);
    free(o->body);
    free(o->material);
    free(o->vel);
    free(o->angvel);
    free(o->area);
    free(o->thick);
    free(o->offsets);
    free(o->types);
    free(o->pts);
    free(o->conn);
    free(o->loc);
    free(o->hull);
    free(o);
}

/* checkpoints (floe_observer_base.h): the series' frames */
static size_t ow_state_size(const floe_observer *o) {
    return floe_fw_series_state_size(&((const outline_writer *)o)->ser);
}
static void ow_save(const floe_observer *o, unsigned char *buf) {
    floe_fw_series_state_save(&((const outline_writer *)o)->ser, buf);
}
static int ow_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    return floe_fw_series_state_restore(&((outline_writer *)o)->ser, w, buf, n);
}

static const floe_observer_class outline_writer_class = {
    3, "outline_writer", NULL, ow_observe, ow_end, ow_destroy, 0, ow_state_size, ow_save, ow_restore, 1, NULL, NULL};

floe_observer *floe_outline_writer_create(const char *dir, const char *prefix, int dim, int segments, int ascii,
                                          char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (dim != 2) {
        if (err && errlen) snprintf(err, errlen, "outlines is a 2D output (dimension: 2); use vtk in 3D");
        return NULL;
    }
    if (segments < 3) {
        if (err && errlen) snprintf(err, errlen, "outline writer: segments must be >= 3 (got %d)", segments);
        return NULL;
    }
    if (!dir || !*dir) dir = ".";
    if (!prefix || !*prefix) prefix = "outlines";
    if (strchr(prefix, '/')) {
        if (err && errlen) snprintf(err, errlen, "outline writer: prefix '%s' must not contain '/'", prefix);
        return NULL;
    }
    outline_writer *o = calloc(1, sizeof *o);
    if (!o || floe_fw_series_init(&o->ser, "outline writer", dir, prefix)) {
        if (err && errlen) snprintf(err, errlen, "outline writer: out of memory");
        if (o) ow_destroy(&o->base);
        return NULL;
    }
    o->segments = segments;
    o->ascii = ascii != 0;
    size_t L = strlen(o->ser.dir); /* strip trailing slashes (keep "/") */
    while (L > 1 && o->ser.dir[L - 1] == '/') o->ser.dir[--L] = '\0';
    /* an empty collection now: checks that the directory is writable */
    int rc = floe_fw_write_pvd(o->ser.dir, o->ser.prefix, NULL, 0);
    if (rc != FLOE_OK) {
        if (err && errlen)
            snprintf(err, errlen, "outline writer: cannot write %s/%s.pvd: %s", o->ser.dir, o->ser.prefix,
                     rc == FLOE_ENOMEM ? "out of memory" : strerror(errno));
        ow_destroy(&o->base);
        return NULL;
    }
    o->base.klass = &outline_writer_class;
    o->base.period_steps = 1;
    return &o->base;
}
