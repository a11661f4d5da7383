/* vtk_writer.c - particles as VTK XML UnstructuredGrid files, one per frame, for ParaView
 * and VTK 9 (vtkXMLUnstructuredGridReader).
 *
 * Files, in the directory given to floe_vtk_writer_create:
 *   PREFIX_NNNNNN.vtu  frame NNNNNN (0, 1, 2, ... in order of writing)
 *   PREFIX.pvd         ParaView collection (timestep = simulated time, file = frame file),
 *                      rewritten after every frame (through a temporary file and rename) so
 *                      that a run that stops or crashes still leaves a valid series.
 * Each .vtu is also written through a temporary file and renamed when complete.
 *
 * Content of a frame: one point per particle with a bounded radius (walls, whose geometry is
 * unbounded, are left out), at its centre of mass; one VTK_VERTEX cell per point.
 * Point data:
 *   id (Int32, world particle index), body (Int32, group tag), material (Int32),
 *   motion (Int32: 0 free, 1 fixed, 2 kinematic), radius (Float64, bounding radius, m),
 *   velocity (Float64 x3, m/s), angular_velocity (Float64 x3, rad/s), force (Float64 x3, N),
 *   torque (Float64 x3, N m), orientation (Float64 x4, unit quaternion w, x, y, z,
 *   body -> world).
 * Scenes with peridynamic bodies add, for their points (0 for other particles): damage
 *   (Float64), von_mises (Float64, Pa), force_density (Float64 x3, force / point volume,
 *   N/m^3) and strain (Float64 x9, Green-Lagrange, row-major).
 * Field data: TimeValue (Float64, s; ParaView reads it as the time of a single file) and
 * Step (Int64).
 *
 * Encoding: raw binary appended data (header_type UInt64, the machine's byte order declared
 * in byte_order) by default; ASCII with floe_vtk_writer_set_ascii(o, 1). Frames with no
 * particles are written in ASCII (empty arrays).
 *
 * end() writes the final state if this step was not written yet.
 *
 * Pieces (floe_vtk_writer_create_piece; an MPI run, docs/parallel.md): the writer of rank R
 * of S writes frame NNNNNN as PREFIX_NNNNNN_R.vtu, the same content for the particles its
 * split world owns (ghosts and walls left out; id is the global particle id,
 * floe_world_parallel_gid); once every rank has its piece (floe_world_parallel_sum: the
 * writers of all ranks are called at the same steps), rank 0 writes PREFIX_NNNNNN.pvtu
 * (PUnstructuredGrid naming the S pieces and declaring the pieces' arrays) and PREFIX.pvd
 * lists the .pvtu files. A piece with no particle is written (ASCII, empty arrays). */
#include "floe_observer.h"
#include "file_writer.h"
#include "floe_pd.h"
#include "floe_cell.h"
#include "floe_parallel.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct vtk_writer {
    floe_observer base;
    floe_fw_series ser; /* DIR/PREFIX_NNNNNN.vtu, DIR/PREFIX.pvd */
    int ascii;
    int *idx;
    int idx_cap;
    unsigned char *buf;
    size_t buf_cap;
    int rank, size; /* pieces: rank of size (size 0: a serial series of .vtu frames) */
} vtk_writer;

static const floe_observer_class vtk_writer_class, vtk_piece_class;

enum {
    A_ID, A_BODY, A_MATERIAL, A_MOTION, A_RADIUS, A_VELOCITY, A_ANGVEL, A_FORCE, A_TORQUE,
    A_ORIENT, A_DAMAGE, A_VONMISES, A_FDENS, A_STRAIN, A_IMAGE, A_NPOINTDATA,
    A_POINTS = A_NPOINTDATA, A_CONN, A_OFFSETS, A_TYPES, A_COUNT
};

typedef struct array_desc { const char *name; floe_fw_vtk_type type; int ncomp; } array_desc;

static const array_desc arrays[A_COUNT] = {
    {"id", FLOE_FW_INT32, 1},          {"body", FLOE_FW_INT32, 1},
    {"material", FLOE_FW_INT32, 1},    {"motion", FLOE_FW_INT32, 1},
    {"radius", FLOE_FW_FLOAT64, 1},    {"velocity", FLOE_FW_FLOAT64, 3},
    {"angular_velocity", FLOE_FW_FLOAT64, 3}, {"force", FLOE_FW_FLOAT64, 3},
    {"torque", FLOE_FW_FLOAT64, 3},    {"orientation", FLOE_FW_FLOAT64, 4},
    {"damage", FLOE_FW_FLOAT64, 1},    {"von_mises", FLOE_FW_FLOAT64, 1},
    {"force_density", FLOE_FW_FLOAT64, 3}, {"strain", FLOE_FW_FLOAT64, 9},
    {"image", FLOE_FW_INT32, 3},
    {"Points", FLOE_FW_FLOAT64, 3},    {"connectivity", FLOE_FW_INT64, 1},
    {"offsets", FLOE_FW_INT64, 1},     {"types", FLOE_FW_UINT8, 1},
};

static int is_wall(const floe_world *w, const floe_particles_view *p, int i) {
    if (!isfinite(p->radius[i])) return 1;
    return floe_world_particle_kind(w, i) == FLOE_GEOM_PLANE;
}

/* Fill buf with array k for the m points listed in v->idx. */
static void fill_array(const vtk_writer *v, const floe_world *w, int k, int m, void *buf) {
    floe_particles_view view;
    const floe_particles_view *p = &view;
    if (floe_world_particles(w, &view) != FLOE_OK) return;
    int npd = floe_world_pd_body_count(w);
    int32_t *i32 = buf;
    int64_t *i64 = buf;
    double *f64 = buf;
    uint8_t *u8 = buf;
    const double *src = NULL;
    int nc = arrays[k].ncomp;
    switch (k) {
    case A_ID:
        for (int a = 0; a < m; a++) i32[a] = (int32_t)(v->size ? floe_world_parallel_gid(w, v->idx[a]) : v->idx[a]);
        return;
    case A_BODY: for (int a = 0; a < m; a++) i32[a] = p->group ? (int32_t)p->group[v->idx[a]] : 0; return;
    case A_MATERIAL: for (int a = 0; a < m; a++) i32[a] = p->material ? (int32_t)p->material[v->idx[a]] : 0; return;
    case A_MOTION: for (int a = 0; a < m; a++) i32[a] = p->motion ? (int32_t)p->motion[v->idx[a]] : 0; return;
    case A_RADIUS: for (int a = 0; a < m; a++) f64[a] = p->radius[v->idx[a]]; return;
    case A_CONN: for (int a = 0; a < m; a++) i64[a] = a; return;
    case A_OFFSETS: for (int a = 0; a < m; a++) i64[a] = a + 1; return;
    case A_TYPES: for (int a = 0; a < m; a++) u8[a] = 1; /* VTK_VERTEX */ return;
    case A_VELOCITY: src = p->v; break;
    case A_ANGVEL: src = p->w; break;
    case A_FORCE: src = p->f; break;
    case A_TORQUE: src = p->t; break;
    case A_ORIENT: src = p->q; break;
    case A_DAMAGE: { /* peridynamic points: local damage (003 eq 7); other particles 0 */
        for (int a = 0; a < m; a++) f64[a] = 0.0;
        for (int b = 0; b < npd; b++) {
            const floe_pd_body *pb = floe_world_pd_body(w, b, NULL);
            if (!pb) continue;
            double *phi = malloc((size_t)pb->n * sizeof *phi);
            if (!phi || floe_pd_damage(pb, phi) != FLOE_OK) { free(phi); continue; }
            for (int a = 0; a < m; a++) {
                int i = floe_world_pd_point(w, b, v->idx[a]);
                if (i >= 0 && i < pb->n) f64[a] = phi[i];
            }
            free(phi);
        }
        return;
    }
    case A_VONMISES: { /* peridynamic points: correspondence von Mises stress (000 eqs 26-30)
                        * with the body's G and lambda (PMB: nu = 1/4, G = lambda = 0.6 K) */
        for (int a = 0; a < m; a++) f64[a] = 0.0;
        for (int b = 0; b < npd; b++) {
            const floe_pd_body *pb = floe_world_pd_body(w, b, NULL);
            if (!pb) continue;
            double K = pb->mat.K, G = pb->mat.model == FLOE_PD_LPS ? pb->mat.G : 0.6 * K;
            if (pb->mat.model != FLOE_PD_LPS && !(K > 0) && pb->mat.E > 0) G = 0.4 * pb->mat.E; /* 2D PMB */
            double lam = pb->mat.model == FLOE_PD_LPS ? K - 2.0 * G / 3.0 : G;
            double *vm = malloc((size_t)pb->n * sizeof *vm);
            if (!vm || floe_pd_correspondence(pb, floe_world_pd_positions(w, b), G, lam, NULL, NULL, NULL, vm, NULL) != FLOE_OK) {
                free(vm);
                continue;
            }
            for (int a = 0; a < m; a++) {
                int i = floe_world_pd_point(w, b, v->idx[a]);
                if (i >= 0 && i < pb->n) f64[a] = vm[i];
            }
            free(vm);
        }
        return;
    }
    case A_FDENS: /* peridynamic points: total force / point volume (N/m^3, ParticLS Fig. 9) */
    case A_STRAIN: { /* peridynamic points: Green-Lagrange strain (000 eq 28, row-major 3x3) */
        for (int a = 0; a < m * nc; a++) f64[a] = 0.0;
        for (int b = 0; b < npd; b++) {
            const floe_pd_body *pb = floe_world_pd_body(w, b, NULL);
            if (!pb) continue;
            double *E = NULL;
            if (k == A_STRAIN) {
                E = malloc((size_t)pb->n * 9 * sizeof *E);
                if (!E || floe_pd_correspondence(pb, floe_world_pd_positions(w, b), 1.0, 1.0, NULL, E, NULL, NULL, NULL) != FLOE_OK) {
                    free(E);
                    continue;
                }
            }
            for (int a = 0; a < m; a++) {
                int i = floe_world_pd_point(w, b, v->idx[a]);
                if (i < 0 || i >= pb->n) continue;
                for (int c = 0; c < nc; c++)
                    f64[(size_t)a * nc + c] = k == A_STRAIN ? E[9 * (size_t)i + c] : p->f[3 * (size_t)v->idx[a] + c] / pb->V[i];
            }
            free(E);
        }
        return;
    }
    case A_POINTS:
        if (floe_world_cell(w, NULL, NULL)) { /* a periodic cell: wrapped into it */
            for (int a = 0; a < m; a++) floe_world_cell_wrap(w, p->x + 3 * (size_t)v->idx[a], f64 + 3 * (size_t)a);
            return;
        }
        src = p->x;
        break;
    case A_IMAGE: { /* the integer image n of each point: unwrapped = Points + H n */
        double xw[3];
        int n[3];
        for (int a = 0; a < m; a++) {
            floe_world_cell_wrap_image(w, p->x + 3 * (size_t)v->idx[a], xw, n);
            for (int c = 0; c < 3; c++) i32[3 * (size_t)a + c] = n[c];
        }
        return;
    }
    default: return;
    }
    for (int a = 0; a < m; a++)
        for (int c = 0; c < nc; c++)
            f64[(size_t)a * nc + c] = src ? src[(size_t)v->idx[a] * nc + c] : 0.0;
}

/* First non-finite value of a Float64 array filled by fill_array: its point (index into
 * v->idx) or -1. A NaN or infinity is never written: the frame is refused instead. */
static int first_non_finite(int k, int m, const void *buf) {
    if (arrays[k].type != FLOE_FW_FLOAT64) return -1;
    const double *f64 = buf;
    size_t n = (size_t)m * (size_t)arrays[k].ncomp;
    for (size_t e = 0; e < n; e++)
        if (!isfinite(f64[e])) return (int)(e / (size_t)arrays[k].ncomp);
    return -1;
}

static int non_finite_error(floe_world *w, const vtk_writer *v, int k, int a) {
    return floe_world_report_error(w, FLOE_EUNSTABLE, "vtk writer: particle %d has a non-finite %s at t = %g s "
                                   "(step %ld): frame not written", v->idx[a], arrays[k].name, floe_world_time(w),
                                   floe_world_step_count(w));
}

/* Fills array k of the m points into v->buf: FLOE_OK, or FLOE_EUNSTABLE (reported) when a
 * value is not finite */
static int fill_finite(const vtk_writer *v, floe_world *w, int k, int m) {
    fill_array(v, w, k, m, v->buf);
    int a = first_non_finite(k, m, v->buf);
    return a >= 0 ? non_finite_error(w, v, k, a) : FLOE_OK;
}

/* the points to write into v->idx (a piece: the owned ones), v->buf large enough for them;
 * the count, or -FLOE_ENOMEM (reported) */
static int vw_select(vtk_writer *v, floe_world *w, const floe_particles_view *p) {
    if (v->idx_cap < p->n) {
        int *ni = realloc(v->idx, (size_t)p->n * sizeof *ni);
        if (!ni) return -floe_world_report_error(w, FLOE_ENOMEM, "vtk writer: out of memory");
        v->idx = ni;
        v->idx_cap = p->n;
    }
    int m = 0;
    for (int i = 0; i < p->n; i++)
        if (!is_wall(w, p, i) && (!v->size || floe_world_parallel_is_owned(w, i))) v->idx[m++] = i;
    size_t need = (size_t)(m > 0 ? m : 1) * 9 * sizeof(double); /* the widest array: strain */
    if (v->buf_cap < need) {
        unsigned char *nb = realloc(v->buf, need);
        if (!nb) return -floe_world_report_error(w, FLOE_ENOMEM, "vtk writer: out of memory");
        v->buf = nb;
        v->buf_cap = need;
    }
    return m;
}

/* the state arrays are checked before a file is opened (the derived PD arrays as they are
 * computed) */
static int vw_check(vtk_writer *v, floe_world *w, int m) {
    static const int state_arrays[] = {A_RADIUS, A_VELOCITY, A_ANGVEL, A_FORCE, A_TORQUE, A_ORIENT, A_POINTS};
    for (size_t q = 0; q < sizeof state_arrays / sizeof *state_arrays; q++) {
        FLOE_TRY(fill_finite(v, w, state_arrays[q], m));
    }
    return FLOE_OK;
}

/* array k is written in this world (the PD arrays only with PD bodies, image in a cell) */
static int vw_has_array(const floe_world *w, int k) {
    if (k >= A_DAMAGE && k <= A_STRAIN && !floe_world_pd_body_count(w)) return 0;
    if (k == A_IMAGE && !floe_world_cell(w, NULL, NULL)) return 0;
    return 1;
}

/* the content of a .vtu of the m points of v->idx into f; FLOE_OK, or the error of an array
 * that is not finite (reported; the caller abandons the file) */
static int vw_write_vtu(vtk_writer *v, floe_world *w, FILE *f, int m) {
    int ascii = v->ascii || m == 0;
    floe_fw_vtu_begin(f, floe_world_time(w), floe_world_step_count(w));
    fprintf(f, "    <Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">\n", m, m);

    uint64_t offset = 0;
    for (int k = 0; k < A_COUNT; k++) {
        if (k == 0) fputs("      <PointData Scalars=\"radius\" Vectors=\"velocity\">\n", f);
        if (k == A_POINTS) fputs("      </PointData>\n      <CellData>\n      </CellData>\n      <Points>\n", f);
        if (k == A_CONN) fputs("      </Points>\n      <Cells>\n", f);
        if (!vw_has_array(w, k)) continue;
        const array_desc *a = &arrays[k];
        fprintf(f, "        <DataArray type=\"%s\" Name=\"%s\"", floe_fw_vtk_type_name(a->type), a->name);
        if (a->ncomp > 1) fprintf(f, " NumberOfComponents=\"%d\"", a->ncomp);
        if (ascii) {
            fputs(" format=\"ascii\">\n", f);
            FLOE_TRY(fill_finite(v, w, k, m));
            floe_fw_vtk_ascii_values(f, a->type, a->ncomp, m, v->buf);
            fputs("        </DataArray>\n", f);
        } else {
            fprintf(f, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)offset);
            offset += sizeof(uint64_t) + (uint64_t)m * (uint64_t)a->ncomp * floe_fw_vtk_type_size(a->type);
        }
    }
    fputs("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n", f);
    if (!ascii) {
        fputs("  <AppendedData encoding=\"raw\">\n   _", f);
        for (int k = 0; k < A_COUNT; k++) {
            if (!vw_has_array(w, k)) continue;
            const array_desc *a = &arrays[k];
            uint64_t nbytes = (uint64_t)m * (uint64_t)a->ncomp * floe_fw_vtk_type_size(a->type);
            FLOE_TRY(fill_finite(v, w, k, m));
            fwrite(&nbytes, sizeof nbytes, 1, f);
            fwrite(v->buf, 1, (size_t)nbytes, f);
        }
        fputs("\n  </AppendedData>\n", f);
    }
    fputs("</VTKFile>\n", f);
    return FLOE_OK;
}

static int vw_write(vtk_writer *v, floe_world *w) {
    floe_particles_view view;
    FLOE_TRY(floe_world_particles(w, &view));
    double time = floe_world_time(w);
    long step = floe_world_step_count(w);
    int m = vw_select(v, w, &view);
    if (m < 0) return -m;
    FLOE_TRY(vw_check(v, w, m));
    /* the frame goes to PREFIX_NNNNNN.vtu.tmp, renamed into place when complete; the .pvd is
     * rewritten after it, so that at every instant it lists only complete frames */
    floe_fw_replace r;
    FLOE_TRY(floe_fw_series_begin(&v->ser, w, &r));
    int bad = vw_write_vtu(v, w, r.f, m);
    if (bad != FLOE_OK) {
        floe_fw_series_abandon(&v->ser, &r);
        return bad;
    }
    return floe_fw_series_commit(&v->ser, w, &r, time, step);
}

/* ---- pieces ---- */

/* PREFIX_NNNNNN.pvtu (rank 0): the pieces' arrays and the size pieces */
static int vw_write_pvtu(vtk_writer *v, floe_world *w, int frame) {
    char *path = floe_fw_series_path(v->ser.dir, v->ser.prefix, frame, ".pvtu");
    if (!path) return floe_world_report_error(w, FLOE_ENOMEM, "vtk writer: out of memory");
    floe_fw_replace r;
    int rc = floe_fw_replace_begin(&r, path);
    if (rc != FLOE_OK) {
        rc = floe_world_report_error(w, rc, "vtk writer: cannot open %s.tmp: %s", path, strerror(errno));
        free(path);
        return rc;
    }
    FILE *f = r.f;
    fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" "
               "byte_order=\"%s\" header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n",
            floe_fw_vtk_byte_order());
    for (int k = 0; k < A_CONN; k++) {
        if (k == 0) fputs("    <PPointData Scalars=\"radius\" Vectors=\"velocity\">\n", f);
        if (k == A_POINTS) fputs("    </PPointData>\n    <PCellData>\n    </PCellData>\n    <PPoints>\n", f);
        if (!vw_has_array(w, k)) continue;
        const array_desc *a = &arrays[k];
        fprintf(f, "      <PDataArray type=\"%s\" Name=\"%s\"", floe_fw_vtk_type_name(a->type), a->name);
        if (a->ncomp > 1) fprintf(f, " NumberOfComponents=\"%d\"", a->ncomp);
        fputs("/>\n", f);
    }
    fputs("    </PPoints>\n", f);
    for (int q = 0; q < v->size; q++) {
        char suffix[32];
        snprintf(suffix, sizeof suffix, "_%d.vtu", q);
        char *name = floe_fw_series_path(NULL, v->ser.prefix, frame, suffix);
        if (!name) {
            floe_fw_replace_abandon(&r);
            free(path);
            return floe_world_report_error(w, FLOE_ENOMEM, "vtk writer: out of memory");
        }
        fprintf(f, "    <Piece Source=\"%s\"/>\n", name);
        free(name);
    }
    fputs("  </PUnstructuredGrid>\n</VTKFile>\n", f);
    rc = floe_fw_replace_commit(&r);
    if (rc != FLOE_OK) rc = floe_world_report_error(w, rc, "vtk writer: writing %s failed: %s", path, strerror(errno));
    free(path);
    return rc;
}

/* whether every rank succeeded (the sum of the failures over the ranks); a rank that did
 * but another did not reports it */
static int vw_agree(floe_world *w, int rc, int frame, const char *what) {
    double bad = rc != FLOE_OK;
    floe_world_parallel_sum(w, &bad, 1);
    if (bad > 0 && rc == FLOE_OK)
        rc = floe_world_report_error(w, FLOE_EIO, "vtk writer: frame %d not written: %s failed on another rank", frame,
                                     what);
    return rc;
}

/* this rank's piece of the frame; rank 0 then the .pvtu and the .pvd. Every rank reaches the
 * two agreements (collective), whatever failed before them. */
static int vw_write_piece(vtk_writer *v, floe_world *w) {
    floe_fw_series *s = &v->ser;
    const int frame = s->frames;
    double time = floe_world_time(w);
    long step = floe_world_step_count(w);
    floe_particles_view view;
    int rc = floe_world_particles(w, &view);
    if (rc == FLOE_OK && s->frames == s->cap) {
        int nc = s->cap ? 2 * s->cap : 64;
        double *t = realloc(s->times, (size_t)nc * sizeof *t);
        if (!t) rc = floe_world_report_error(w, FLOE_ENOMEM, "vtk writer: out of memory");
        else { s->times = t; s->cap = nc; }
    }
    int m = rc == FLOE_OK ? vw_select(v, w, &view) : 0;
    if (m < 0) { rc = -m; m = 0; }
    if (rc == FLOE_OK) rc = vw_check(v, w, m);
    if (rc == FLOE_OK) {
        char suffix[32];
        snprintf(suffix, sizeof suffix, "_%d.vtu", v->rank);
        char *path = floe_fw_series_path(s->dir, s->prefix, frame, suffix);
        floe_fw_replace r;
        if (!path) rc = floe_world_report_error(w, FLOE_ENOMEM, "vtk writer: out of memory");
        else if ((rc = floe_fw_replace_begin(&r, path)) != FLOE_OK)
            rc = floe_world_report_error(w, rc, "vtk writer: cannot open %s.tmp: %s", path, strerror(errno));
        else if ((rc = vw_write_vtu(v, w, r.f, m)) != FLOE_OK)
            floe_fw_replace_abandon(&r);
        else if ((rc = floe_fw_replace_commit(&r)) != FLOE_OK)
            rc = floe_world_report_error(w, rc, "vtk writer: writing %s failed: %s", path, strerror(errno));
        free(path);
    }
    rc = vw_agree(w, rc, frame, "a piece");
    if (rc != FLOE_OK) return rc;
    s->times[frame] = time;
    if (v->rank == 0) {
        rc = vw_write_pvtu(v, w, frame);
        if (rc == FLOE_OK && (rc = floe_fw_write_pvd_as(s->dir, s->prefix, s->times, frame + 1, ".pvtu")) != FLOE_OK)
            rc = floe_world_report_error(w, rc, "vtk writer: writing %s/%s.pvd failed: %s", s->dir, s->prefix,
                                         rc == FLOE_ENOMEM ? "out of memory" : strerror(errno));
    }
    rc = vw_agree(w, rc, frame, "the .pvtu or the .pvd (rank 0)");
    if (rc != FLOE_OK) return rc;
    s->frames = frame + 1;
    s->last_step = step;
    s->observed = 1;
    return FLOE_OK;
}

static int vw_observe(floe_observer *o, floe_world *w) {
    vtk_writer *v = (vtk_writer *)o;
    if (!floe_fw_series_due(&v->ser, floe_world_step_count(w))) return FLOE_OK;
    return v->size ? vw_write_piece(v, w) : vw_write(v, w);
}

static int vw_end(floe_observer *o, floe_world *w) { return vw_observe(o, w); }

static void vw_destroy(floe_observer *o) {
    vtk_writer *v = (vtk_writer *)o;
    floe_fw_series_free(&v->ser);
    free(v->idx);
    free(v->buf);
    free(v);
}

/* checkpoints (floe_observer_base.h): the series' frames */
static size_t vw_state_size(const floe_observer *o) {
    return floe_fw_series_state_size(&((const vtk_writer *)o)->ser);
}
static void vw_save(const floe_observer *o, unsigned char *buf) {
    floe_fw_series_state_save(&((const vtk_writer *)o)->ser, buf);
}
static int vw_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    return floe_fw_series_state_restore(&((vtk_writer *)o)->ser, w, buf, n);
}

/* pieces: the same state (the series' frames and times, every rank's; rank 0 writes it under
 * MPI, floe_world_parallel_checkpoint_save); the restore rewrites the .pvd of the .pvtu frames
 * up to the checkpoint (rank 0), the frames after it written again, with this run's number of
 * pieces (a frame's .pvtu names its own pieces: the rank count may change at a restart) */
static int vw_piece_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    vtk_writer *v = (vtk_writer *)o;
    return floe_fw_series_state_restore_as(&v->ser, w, buf, n, ".pvtu", v->rank == 0 ? 2 : 0);
}

static const floe_observer_class vtk_writer_class = {
    3, "vtk_writer", NULL, vw_observe, vw_end, vw_destroy, 0, vw_state_size, vw_save, vw_restore, 1, NULL, NULL};
static const floe_observer_class vtk_piece_class = {
    3, "vtk_writer", NULL, vw_observe, vw_end, vw_destroy, 0, vw_state_size, vw_save, vw_piece_restore, 1, NULL, NULL};

int floe_vtk_writer_set_ascii(floe_observer *o, int ascii) {
    if (!o || (o->klass != &vtk_writer_class && o->klass != &vtk_piece_class)) return FLOE_EINVAL;
    ((vtk_writer *)o)->ascii = ascii != 0;
    return FLOE_OK;
}

static floe_observer *vw_create(const char *dir, const char *prefix, int rank, int size, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (size < 0 || rank < 0 || (size > 0 && rank >= size)) {
        if (err && errlen) snprintf(err, errlen, "vtk writer: rank %d of %d ranks does not exist", rank, size);
        return NULL;
    }
    if (!dir || !*dir) dir = ".";
    if (!prefix || !*prefix) prefix = "particles";
    vtk_writer *v = calloc(1, sizeof *v);
    if (!v || floe_fw_series_init(&v->ser, "vtk writer", dir, prefix)) {
        if (err && errlen) snprintf(err, errlen, "vtk writer: out of memory");
        if (v) vw_destroy(&v->base);
        return NULL;
    }
    /* strip trailing slashes (keep "/") */
    size_t L = strlen(v->ser.dir);
    while (L > 1 && v->ser.dir[L - 1] == '/') v->ser.dir[--L] = '\0';
    v->rank = rank;
    v->size = size;
    /* an empty collection now: checks that the directory is writable (pieces: rank 0's) */
    int rc = rank == 0 ? floe_fw_write_pvd(v->ser.dir, v->ser.prefix, NULL, 0) : FLOE_OK;
    if (rc != FLOE_OK) {
        if (err && errlen)
            snprintf(err, errlen, "vtk writer: cannot write %s/%s.pvd: %s", v->ser.dir, v->ser.prefix,
                     rc == FLOE_ENOMEM ? "out of memory" : strerror(errno));
        vw_destroy(&v->base);
        return NULL;
    }
    v->base.klass = size ? &vtk_piece_class : &vtk_writer_class;
    v->base.period_steps = 1;
    return &v->base;
}

floe_observer *floe_vtk_writer_create(const char *dir, const char *prefix, char *err, size_t errlen) {
    return vw_create(dir, prefix, 0, 0, err, errlen);
}

floe_observer *floe_vtk_writer_create_piece(const char *dir, const char *prefix, int rank, int size, char *err,
                                            size_t errlen) {
    if (size < 1) {
        if (err && errlen) snprintf(err, errlen, "vtk writer: pieces of %d ranks", size);
        return NULL;
    }
    return vw_create(dir, prefix, rank, size, err, errlen);
}
