/* contact_writer.c - the contacts of the world as outputs (issue #13, "contact export"):
 *
 *   `contacts`      CSV, one row per contact and observation:
 *                     t [s], i, j, x, y, z [m] (the contact point), nx, ny, nz (the unit
 *                     normal from i to j), fn [N] (normal force magnitude), ft [N] (the
 *                     tangential force's magnitude), fx, fy, fz [N] (the force on i; j gets
 *                     minus it), depth [m] (the deepest-point overlap), energy [J] (stored);
 *   `force_chains`  a VTK series (PREFIX_NNNNNN.vtu, PREFIX.pvd): one line cell per contact
 *                     between two bodies with centres (walls and other unbounded bodies left
 *                     out) from the centre of i to that of j, cell data fn, ft, force,
 *                     depth, for ParaView to draw force chains (colour and width by fn).
 *
 * Both read floe_world_contacts (their class asks the world to record the contacts at the
 * evaluations they observe). The tangential force is force - (force . n) n. */
#include "floe_observer.h"
#include "file_writer.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static double tangential(const floe_contact_info *c) {
    const double fn = c->force[0] * c->n[0] + c->force[1] * c->n[1] + c->force[2] * c->n[2];
    double t2 = 0;
    for (int a = 0; a < 3; a++) {
        const double t = c->force[a] - fn * c->n[a];
        t2 += t * t;
    }
    return sqrt(t2);
}

static int recorded(floe_world *w, const char *who, const floe_contact_info **ci) {
    int nc = floe_world_contacts(w, ci);
    if (nc < 0)
        return -floe_world_report_error(w, FLOE_EINVAL, "%s: the contacts were not recorded at t = %g s", who,
                                        floe_world_time(w));
    return nc;
}

/* ---- contacts: CSV ---- */

typedef struct contact_csv {
    floe_observer base;
    floe_file_writer out;
    long last_step;
    int observed;
} contact_csv;

static int cc_write(contact_csv *c, floe_world *w) {
    const long step = floe_world_step_count(w);
    if (c->observed && c->last_step == step) return FLOE_OK;
    const floe_contact_info *ci = NULL;
    const int nc = recorded(w, "contacts", &ci);
    if (nc < 0) return -nc;
    const double t = floe_world_time(w);
    for (int k = 0; k < nc; k++) {
        const floe_contact_info *q = ci + k;
        floe_fw_row(&c->out, "%.17g,%d,%d,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g\n",
                    t, q->i, q->j, q->point[0], q->point[1], q->point[2], q->n[0], q->n[1], q->n[2], q->fn,
                    tangential(q), q->force[0], q->force[1], q->force[2], q->depth, q->energy);
    }
    c->last_step = step;
    c->observed = 1;
    return floe_fw_flush(&c->out, w);
}

static int cc_observe(floe_observer *o, floe_world *w) { return cc_write((contact_csv *)o, w); }

static int cc_end(floe_observer *o, floe_world *w) {
    contact_csv *c = (contact_csv *)o;
    /* a flush after a failure may find no contacts recorded: nothing to add then */
    int rc = floe_world_contacts(w, NULL) >= 0 ? cc_write(c, w) : FLOE_OK;
    int rc2 = floe_fw_close(&c->out, w);
    return rc != FLOE_OK ? rc : rc2;
}

static void cc_destroy(floe_observer *o) {
    contact_csv *c = (contact_csv *)o;
    floe_fw_free(&c->out);
    free(c);
}

/* checkpoints (floe_observer_base.h): the file's length, the last row block's step */
static size_t cc_state_size(const floe_observer *o) {
    (void)o;
    return floe_fw_state_size();
}
static void cc_save(const floe_observer *o, unsigned char *buf) {
    const contact_csv *t = (const contact_csv *)o;
    floe_fw_state_save(&t->out, t->last_step, t->observed, buf);
}
static int cc_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    contact_csv *t = (contact_csv *)o;
    if (n != floe_fw_state_size())
        return floe_world_report_error(w, FLOE_EINVAL, "%s: checkpoint state does not match", t->out.who);
    return floe_fw_state_restore(&t->out, w, &t->last_step, &t->observed, buf);
}

static const floe_observer_class contact_csv_class = {3, "contacts", NULL, cc_observe, cc_end, cc_destroy, 1,
    cc_state_size, cc_save, cc_restore, 0, NULL, NULL};

floe_observer *floe_contact_csv_create(const char *path, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!path || !*path) {
        if (err && errlen) snprintf(err, errlen, "contacts: need a path");
        return NULL;
    }
    contact_csv *c = calloc(1, sizeof *c);
    if (!c) {
        if (err && errlen) snprintf(err, errlen, "contacts: out of memory");
        return NULL;
    }
    if (floe_fw_open(&c->out, "contacts", path,
                     "t [s],i,j,x [m],y [m],z [m],nx,ny,nz,fn [N],ft [N],fx [N],fy [N],fz [N],depth [m],energy [J]\n",
                     err, errlen)) {
        free(c);
        return NULL;
    }
    c->base.klass = &contact_csv_class;
    c->base.period_steps = 1;
    return &c->base;
}

/* ---- force chains: VTK lines ---- */

typedef struct force_chains {
    floe_observer base;
    floe_fw_series ser;
    int *sel;      /* the contacts drawn (both bodies bounded) */
    double *buf;   /* one array's values */
    int cap;
} force_chains;

static int fc_reserve(force_chains *c, int n) {
    if (n <= c->cap) return FLOE_OK;
    int *s = realloc(c->sel, (size_t)n * sizeof *s);
    if (!s) return FLOE_ENOMEM;
    c->sel = s;
    double *b = realloc(c->buf, (size_t)n * 6 * sizeof *b);
    if (!b) return FLOE_ENOMEM;
    c->buf = b;
    c->cap = n;
    return FLOE_OK;
}

static void fc_array(FILE *f, const char *name, int ncomp, int m, const double *buf) {
    fprintf(f, "        <DataArray type=\"Float64\" Name=\"%s\"", name);
    if (ncomp > 1) fprintf(f, " NumberOfComponents=\"%d\"", ncomp);
    fputs(" format=\"ascii\">\n", f);
    floe_fw_vtk_ascii_values(f, FLOE_FW_FLOAT64, ncomp, m, buf);
    fputs("        </DataArray>\n", f);
}

static int fc_write(force_chains *c, floe_world *w) {
    const floe_contact_info *ci = NULL;
    const int nc = recorded(w, "force_chains", &ci);
    if (nc < 0) return -nc;
    floe_particles_view v;
    FLOE_TRY(floe_world_particles(w, &v));
    if (fc_reserve(c, nc > 0 ? nc : 1)) return floe_world_report_error(w, FLOE_ENOMEM, "force_chains: out of memory");
    int m = 0;
    for (int k = 0; k < nc; k++)
        if (isfinite(v.radius[ci[k].i]) && isfinite(v.radius[ci[k].j])) c->sel[m++] = k;
    const double time = floe_world_time(w);
    const long step = floe_world_step_count(w);
    floe_fw_replace r;
    FLOE_TRY(floe_fw_series_begin(&c->ser, w, &r));
    FILE *f = r.f;
    floe_fw_vtu_begin(f, time, step);
    fprintf(f, "    <Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">\n      <CellData Scalars=\"fn\">\n", 2 * m, m);
    for (int q = 0; q < m; q++) c->buf[q] = ci[c->sel[q]].fn;
    fc_array(f, "fn", 1, m, c->buf);
    for (int q = 0; q < m; q++) c->buf[q] = tangential(ci + c->sel[q]);
    fc_array(f, "ft", 1, m, c->buf);
    for (int q = 0; q < m; q++) memcpy(c->buf + 3 * q, ci[c->sel[q]].force, 3 * sizeof(double));
    fc_array(f, "force", 3, m, c->buf);
    for (int q = 0; q < m; q++) c->buf[q] = ci[c->sel[q]].depth;
    fc_array(f, "depth", 1, m, c->buf);
    fputs("      </CellData>\n      <Points>\n", f);
    /* two points per line: the centres of i and j (written a line's worth at a time) */
    fputs("        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n", f);
    for (int q = 0; q < m; q++) {
        const floe_contact_info *k = ci + c->sel[q];
        memcpy(c->buf, v.x + 3 * k->i, 3 * sizeof(double));
        memcpy(c->buf + 3, v.x + 3 * k->j, 3 * sizeof(double));
        floe_fw_vtk_ascii_values(f, FLOE_FW_FLOAT64, 3, 2, c->buf);
    }
    fputs("        </DataArray>\n      </Points>\n      <Cells>\n"
          "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n", f);
    for (int q = 0; q < m; q++) fprintf(f, "%d %d\n", 2 * q, 2 * q + 1);
    fputs("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n", f);
    for (int q = 0; q < m; q++) fprintf(f, "%d\n", 2 * (q + 1));
    fputs("        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n", f);
    for (int q = 0; q < m; q++) fputs("3\n", f); /* VTK_LINE */
    fputs("        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n", f);
    return floe_fw_series_commit(&c->ser, w, &r, time, step);
}

static int fc_observe(floe_observer *o, floe_world *w) {
    force_chains *c = (force_chains *)o;
    return floe_fw_series_due(&c->ser, floe_world_step_count(w)) ? fc_write(c, w) : FLOE_OK;
}

static int fc_end(floe_observer *o, floe_world *w) {
    force_chains *c = (force_chains *)o;
    if (floe_world_contacts(w, NULL) < 0) return FLOE_OK; /* a flush after a failure: none recorded */
    return floe_fw_series_due(&c->ser, floe_world_step_count(w)) ? fc_write(c, w) : FLOE_OK;
}

static void fc_destroy(floe_observer *o) {
    force_chains *c = (force_chains *)o;
    floe_fw_series_free(&c->ser);
    free(c->sel);
    free(c->buf);
    free(c);
}

/* checkpoints (floe_observer_base.h): the series' frames */
static size_t fc_state_size(const floe_observer *o) {
    return floe_fw_series_state_size(&((const force_chains *)o)->ser);
}
static void fc_save(const floe_observer *o, unsigned char *buf) {
    floe_fw_series_state_save(&((const force_chains *)o)->ser, buf);
}
static int fc_restore(floe_observer *o, floe_world *w, const unsigned char *buf, size_t n) {
    return floe_fw_series_state_restore(&((force_chains *)o)->ser, w, buf, n);
}

static const floe_observer_class force_chains_class = {3, "force_chains", NULL, fc_observe, fc_end, fc_destroy, 1,
    fc_state_size, fc_save, fc_restore, 0, NULL, NULL};

floe_observer *floe_force_chains_create(const char *dir, const char *prefix, char *err, size_t errlen) {
    if (err && errlen) err[0] = '\0';
    if (!dir || !*dir) dir = ".";
    if (!prefix || !*prefix || strchr(prefix, '/')) {
        if (err && errlen) snprintf(err, errlen, "force_chains: the prefix must be a name without '/'");
        return NULL;
    }
    force_chains *c = calloc(1, sizeof *c);
    if (!c || floe_fw_series_init(&c->ser, "force_chains", dir, prefix)) {
        if (err && errlen) snprintf(err, errlen, "force_chains: out of memory");
        free(c);
        return NULL;
    }
    /* an empty collection now: checks that the directory is writable */
    int rc = floe_fw_write_pvd(c->ser.dir, c->ser.prefix, NULL, 0);
    if (rc != FLOE_OK) {
        if (err && errlen)
            snprintf(err, errlen, "force_chains: cannot write %s/%s.pvd: %s", c->ser.dir, c->ser.prefix,
                     rc == FLOE_ENOMEM ? "out of memory" : strerror(errno));
        fc_destroy(&c->base);
        return NULL;
    }
    c->base.klass = &force_chains_class;
    c->base.period_steps = 1;
    return &c->base;
}
