/* newmark_io.c - the Newmark-beta solver's queries, VTK and CSV output, and the solver
 * built from a world's particles and beam bonds. */
#include "newmark_base.h"

/* ---- queries, output ---- */

double floe_newmark_time(const floe_newmark *s) { return s->t; }
int floe_newmark_node_count(const floe_newmark *s) { return s->n; }
int floe_newmark_bond_count(const floe_newmark *s) { return s->nb; }

int floe_newmark_get(const floe_newmark *s, int i, double u[3], double rot[3], double v[3], double w[3]) {
    if (i < 0 || i >= s->n) return FLOE_EINVAL;
    const double *U = s->u + s->nd * i, *V = s->v + s->nd * i;
    if (s->dim == 2) {
        if (u) floe_v3_set(u, U[0], U[1], 0);
        if (rot) floe_v3_set(rot, 0, 0, U[2]);
        if (v) floe_v3_set(v, V[0], V[1], 0);
        if (w) floe_v3_set(w, 0, 0, V[2]);
    } else {
        if (u) floe_v3_copy(u, U);
        if (rot) floe_v3_copy(rot, U + 3);
        if (v) floe_v3_copy(v, V);
        if (w) floe_v3_copy(w, V + 3);
    }
    return FLOE_OK;
}

int floe_newmark_bond_state(const floe_newmark *s, int k, int *broken, double *t_broken, double *sigma, double *tau) {
    if (k < 0 || k >= s->nb) return FLOE_EINVAL;
    const nm_bond *b = &s->b[k];
    if (broken) *broken = b->broken;
    if (t_broken) *t_broken = b->t_broken;
    if (sigma) *sigma = b->sigma;
    if (tau) *tau = b->tau;
    return FLOE_OK;
}

int floe_newmark_get_stats(const floe_newmark *s, floe_newmark_stats *out) {
    *out = s->st;
    return FLOE_OK;
}

int floe_newmark_write_vtu(floe_newmark *s, const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) return nm_error(s, FLOE_EIO, "cannot write %s", path);
    fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
               "<UnstructuredGrid>\n<Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">\n<Points>\n"
               "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n", s->n, s->nb);
    for (int i = 0; i < s->n; i++) {
        double u[3];
        floe_newmark_get(s, i, u, NULL, NULL, NULL);
        fprintf(f, "%.9g %.9g %.9g\n", s->x[3 * i] + u[0], s->x[3 * i + 1] + u[1], s->x[3 * i + 2] + u[2]);
    }
    fprintf(f, "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n");
    for (int k = 0; k < s->nb; k++) fprintf(f, "%d %d\n", s->b[k].i, s->b[k].j);
    fprintf(f, "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n");
    for (int k = 0; k < s->nb; k++) fprintf(f, "%d\n", 2 * (k + 1));
    fprintf(f, "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for (int k = 0; k < s->nb; k++) fprintf(f, "3\n");
    fprintf(f, "</DataArray>\n</Cells>\n<CellData Scalars=\"broken\">\n"
               "<DataArray type=\"Int32\" Name=\"broken\" format=\"ascii\">\n");
    for (int k = 0; k < s->nb; k++) fprintf(f, "%d\n", s->b[k].broken);
    fprintf(f, "</DataArray>\n<DataArray type=\"Float64\" Name=\"t_broken\" format=\"ascii\">\n");
    for (int k = 0; k < s->nb; k++) fprintf(f, "%.9g\n", s->b[k].t_broken);
    fprintf(f, "</DataArray>\n<DataArray type=\"Float64\" Name=\"sigma\" format=\"ascii\">\n");
    for (int k = 0; k < s->nb; k++) fprintf(f, "%.9g\n", s->b[k].sigma);
    fprintf(f, "</DataArray>\n</CellData>\n<PointData Vectors=\"displacement\">\n"
               "<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (int i = 0; i < s->n; i++) {
        double u[3];
        floe_newmark_get(s, i, u, NULL, NULL, NULL);
        fprintf(f, "%.9g %.9g %.9g\n", u[0], u[1], u[2]);
    }
    fprintf(f, "</DataArray>\n</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    int bad = ferror(f);
    if (fclose(f) || bad) return nm_error(s, FLOE_EIO, "error writing %s", path);
    return FLOE_OK;
}

int floe_newmark_write_bonds_csv(floe_newmark *s, const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) return nm_error(s, FLOE_EIO, "cannot write %s", path);
    fprintf(f, "i,j,x [m],y [m],z [m],broken,t_broken [s],sigma [Pa],tau [Pa],sigma_lim [Pa]\n");
    for (int k = 0; k < s->nb; k++) {
        const nm_bond *b = &s->b[k];
        const double *xi = s->x + 3 * b->i, *xj = s->x + 3 * b->j;
        fprintf(f, "%d,%d,%.9g,%.9g,%.9g,%d,%.9g,%.9g,%.9g,%.9g\n", b->i, b->j, 0.5 * (xi[0] + xj[0]),
                0.5 * (xi[1] + xj[1]), 0.5 * (xi[2] + xj[2]), b->broken, b->t_broken, b->sigma, b->tau, b->sig_lim);
    }
    int bad = ferror(f);
    if (fclose(f) || bad) return nm_error(s, FLOE_EIO, "error writing %s", path);
    return FLOE_OK;
}

/* ---- from a world ---- */

floe_newmark *floe_newmark_from_world(floe_world *w, const floe_newmark_def *def0, char *err, size_t errlen) {
    int rc = floe_world_prepare(w);
    if (rc) {
        if (err && errlen) snprintf(err, errlen, "world prepare failed: %s", floe_world_last_error(w));
        return NULL;
    }
    floe_newmark_def def = *def0;
    def.dim = w->def.dim;
    floe_newmark *s = floe_newmark_create(&def, err, errlen);
    if (!s) return NULL;
    s->nthreads = w->nthreads; /* the world's threads */
    const floe_particles *p = &w->p;
    for (int i = 0; i < p->n && !rc; i++) {
        int wall = !isfinite(p->radius[i]) || !isfinite(p->mass[i]);
        const double *I = p->inertia + 3 * i;
        double J = wall ? 1.0 : fmin(I[0], fmin(I[1], I[2]));
        int k = floe_newmark_add_node(s, p->x + 3 * i, wall ? 1.0 : p->mass[i], J);
        if (k < 0) { rc = -k; break; }
        if (wall || p->motion[i] != FLOE_FREE) floe_newmark_fix(s, i, FLOE_NM_ALL);
        else {
            double f[3];
            for (int a = 0; a < 3; a++) f[a] = p->mass[i] * w->def.gravity[a];
            floe_newmark_set_load(s, i, f, NULL);
            floe_newmark_set_initial(s, i, NULL, NULL, p->v + 3 * i, p->w + 3 * i);
        }
    }
    for (int k = 0; k < floe_world_beam_bond_count(w) && !rc; k++) {
        floe_beam_bond_info bi;
        floe_world_beam_bond(w, k, &bi);
        if (bi.broken) continue;
        int r = floe_newmark_add_bond(s, bi.i, bi.j, &bi.section, bi.sigma_lim, bi.tau_lim);
        if (r < 0) rc = -r;
    }
    if (rc) {
        if (err && errlen) snprintf(err, errlen, "%s", s->err);
        floe_newmark_destroy(s);
        return NULL;
    }
    return s;
}

int floe_newmark_implicit_available(void) {
#ifdef FLOE_HAVE_CHOLMOD
    return 1;
#else
    return 0;
#endif
}
