/* mesh.c - triangle meshes as particle shapes (floe_mesh.h): import with assimp, mesh
 * checks, and the shapes built from meshes (convex hull, convex decomposition). The CGAL
 * algorithms are in mesh_cgal.cpp; built without CGAL (FLOE_WITH_CGAL=OFF) or without assimp
 * (FLOE_WITH_ASSIMP=OFF) the functions that need them return FLOE_ENOTSUP and a message
 * naming the option. */
#include "geometry_internal.h"
#include "floe_mesh.h"
#ifdef FLOE_HAVE_CGAL
#include "mesh_cgal.h"
#endif

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#ifdef FLOE_HAVE_ASSIMP
#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#endif

#define NO_ASSIMP_MSG "floe was built without FLOE_WITH_ASSIMP: reconfigure with -DFLOE_WITH_ASSIMP=ON (libassimp-dev)"
#define NO_CGAL_MSG "floe was built without FLOE_WITH_CGAL: reconfigure with -DFLOE_WITH_CGAL=ON (libcgal-dev)"


/* err = prefix + err (the message of a callee), e.g. the file name before a hull error */
static void prefix_err(char *err, size_t errlen, const char *prefix) {
    char tmp[512];
    if (!err || errlen == 0) return;
    snprintf(tmp, sizeof tmp, "%s", err);
    snprintf(err, errlen, "%s%s", prefix, tmp);
}

static const char *nm(const char *name) { return name ? name : "mesh"; }

int floe_mesh_features(void) {
    int f = 0;
#ifdef FLOE_HAVE_ASSIMP
    f |= FLOE_MESH_HAVE_ASSIMP;
#endif
#ifdef FLOE_HAVE_CGAL
    f |= FLOE_MESH_HAVE_CGAL;
#endif
    return f;
}

void floe_mesh_free(floe_mesh *m) {
    if (!m) return;
    free(m->v);
    free(m->tri);
    m->v = NULL;
    m->tri = NULL;
    m->nv = m->nt = 0;
}

/* ---- loading ---- */

#ifdef FLOE_HAVE_ASSIMP
typedef struct vkey { double x[3]; int idx; } vkey;

static int vkey_cmp(const void *a, const void *b) {
    const vkey *p = a, *q = b;
    for (int k = 0; k < 3; k++) {
        if (p->x[k] < q->x[k]) return -1;
        if (p->x[k] > q->x[k]) return 1;
    }
    return (p->idx > q->idx) - (p->idx < q->idx);
}

/* joins vertices at exactly the same position (assimp keeps STL corners apart when their
 * facet normals differ) and drops vertices no triangle uses */
static int weld(floe_mesh *m) {
    int nv = m->nv;
    vkey *k = malloc((size_t)(nv > 0 ? nv : 1) * sizeof *k);
    int *map = malloc((size_t)(nv > 0 ? nv : 1) * sizeof *map);
    int *used = calloc((size_t)(nv > 0 ? nv : 1), sizeof *used);
    double *v = malloc((size_t)(nv > 0 ? nv : 1) * 3 * sizeof *v);
    if (!k || !map || !used || !v) {
        free(k), free(map), free(used), free(v);
        return FLOE_ENOMEM;
    }
    for (int t = 0; t < 3 * m->nt; t++) used[m->tri[t]] = 1;
    int n = 0;
    for (int i = 0; i < nv; i++) {
        if (!used[i]) continue;
        memcpy(k[n].x, m->v + 3 * i, 3 * sizeof(double));
        k[n++].idx = i;
    }
    qsort(k, (size_t)n, sizeof *k, vkey_cmp);
    int out = 0;
    for (int i = 0; i < n; i++) {
        if (i == 0 || memcmp(k[i].x, k[i - 1].x, 3 * sizeof(double)) != 0) {
            memcpy(v + 3 * out, k[i].x, 3 * sizeof(double));
            out++;
        }
        map[k[i].idx] = out - 1;
    }
    for (int t = 0; t < 3 * m->nt; t++) m->tri[t] = map[m->tri[t]];
    free(m->v);
    m->v = v;
    m->nv = out;
    free(k), free(map), free(used);
    return FLOE_OK;
}
#endif

int floe_mesh_load(const char *path, double scale, floe_mesh *out, char *err, size_t errlen) {
    if (!out) return FLOE_EINVAL;
    out->nv = out->nt = 0;
    out->v = NULL;
    out->tri = NULL;
    if (!path) {
        floe_set_err(err, errlen, "mesh file: no path given");
        return FLOE_EINVAL;
    }
#ifndef FLOE_HAVE_ASSIMP
    (void)scale;
    floe_set_err(err, errlen, "cannot read mesh file '%s': " NO_ASSIMP_MSG, path);
    return FLOE_ENOTSUP;
#else
    if (!(scale > 0) || !isfinite(scale)) {
        floe_set_err(err, errlen, "mesh file '%s': scale %g must be positive and finite", path, scale);
        return FLOE_EINVAL;
    }
    /* a FIFO, device or directory would block or never end: only regular files */
    struct stat st;
    if (stat(path, &st) != 0) {
        floe_set_err(err, errlen, "cannot read mesh file '%s': %s", path, strerror(errno));
        return FLOE_EIO;
    }
    if (!S_ISREG(st.st_mode)) {
        floe_set_err(err, errlen, "mesh file '%s' is not a regular file (%s)", path,
                     S_ISDIR(st.st_mode) ? "a directory" : S_ISFIFO(st.st_mode) ? "a FIFO" : "a device or socket");
        return FLOE_EIO;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        floe_set_err(err, errlen, "cannot read mesh file '%s': %s", path, strerror(errno));
        return FLOE_EIO;
    }
    int c = fgetc(f);
    fclose(f);
    if (c == EOF) {
        floe_set_err(err, errlen, "mesh file '%s' is empty (0 bytes): no triangles", path);
        return FLOE_EIO;
    }
    const struct aiScene *sc = aiImportFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                      aiProcess_PreTransformVertices | aiProcess_SortByPType);
    if (!sc) {
        const char *msg = aiGetErrorString();
        floe_set_err(err, errlen, "cannot read mesh file '%s': %s", path, msg && *msg ? msg : "unknown assimp error");
        return FLOE_EIO;
    }
    long nv = 0, nt = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *me = sc->mMeshes[i];
        if (!(me->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        for (unsigned j = 0; j < me->mNumFaces; j++)
            if (me->mFaces[j].mNumIndices == 3) nt++;
        nv += me->mNumVertices;
    }
    if (nt == 0) {
        aiReleaseImport(sc);
        floe_set_err(err, errlen, "mesh file '%s' has no triangles (empty mesh)", path);
        return FLOE_EINVAL;
    }
    if (nv > 0x7fffffffL / 3 || nt > 0x7fffffffL / 3) {
        aiReleaseImport(sc);
        floe_set_err(err, errlen, "mesh file '%s' is too large (%ld vertices, %ld triangles)", path, nv, nt);
        return FLOE_EINVAL;
    }
    out->v = malloc((size_t)nv * 3 * sizeof(double));
    out->tri = malloc((size_t)nt * 3 * sizeof(int));
    if (!out->v || !out->tri) {
        aiReleaseImport(sc);
        floe_mesh_free(out);
        floe_set_err(err, errlen, "mesh file '%s': out of memory", path);
        return FLOE_ENOMEM;
    }
    int iv = 0, it = 0, bad = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *me = sc->mMeshes[i];
        if (!(me->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        int base = iv;
        for (unsigned j = 0; j < me->mNumVertices; j++, iv++) {
            const double p[3] = {me->mVertices[j].x, me->mVertices[j].y, me->mVertices[j].z};
            for (int k = 0; k < 3; k++) {
                out->v[3 * iv + k] = scale * p[k];
                if (!isfinite(out->v[3 * iv + k])) bad = 1;
            }
        }
        for (unsigned j = 0; j < me->mNumFaces; j++) {
            const struct aiFace *fa = &me->mFaces[j];
            if (fa->mNumIndices != 3) continue;
            for (int k = 0; k < 3; k++) out->tri[3 * it + k] = base + (int)fa->mIndices[k];
            it++;
        }
    }
    aiReleaseImport(sc);
    out->nv = iv;
    out->nt = it;
    if (bad) {
        floe_mesh_free(out);
        floe_set_err(err, errlen, "mesh file '%s' has a non-finite vertex coordinate (NaN or infinity after scale %g)", path,
                scale);
        return FLOE_EINVAL;
    }
    if (weld(out) != FLOE_OK) {
        floe_mesh_free(out);
        floe_set_err(err, errlen, "mesh file '%s': out of memory", path);
        return FLOE_ENOMEM;
    }
    return FLOE_OK;
#endif
}

/* ---- checks ---- */

typedef struct dedge { int a, b, t; } dedge; /* a < b; t: +1 if the triangle runs a->b, -1 if b->a */

static int dedge_cmp(const void *x, const void *y) {
    const dedge *p = x, *q = y;
    if (p->a != q->a) return (p->a > q->a) - (p->a < q->a);
    if (p->b != q->b) return (p->b > q->b) - (p->b < q->b);
    return (p->t > q->t) - (p->t < q->t);
}

static double bbox_diag(const floe_mesh *m) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < m->nv; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->v[3 * i + k]);
            hi[k] = fmax(hi[k], m->v[3 * i + k]);
        }
    double d2 = 0;
    for (int k = 0; k < 3; k++) d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return sqrt(d2);
}

/* six times the signed volume enclosed by the triangles (positive: outward orientation) */
static double volume6(const floe_mesh *m) {
    double s = 0, c[3] = {m->v[0], m->v[1], m->v[2]};
    for (int t = 0; t < m->nt; t++) {
        const double *a = m->v + 3 * m->tri[3 * t], *b = m->v + 3 * m->tri[3 * t + 1], *d = m->v + 3 * m->tri[3 * t + 2];
        double u[3] = {a[0] - c[0], a[1] - c[1], a[2] - c[2]};
        double v[3] = {b[0] - c[0], b[1] - c[1], b[2] - c[2]};
        double w[3] = {d[0] - c[0], d[1] - c[1], d[2] - c[2]};
        s += u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
    }
    return s;
}

int floe_mesh_validate(const floe_mesh *m, const char *name, char *err, size_t errlen) {
    if (!m || m->nt <= 0 || m->nv <= 0 || !m->v || !m->tri) {
        floe_set_err(err, errlen, "%s is empty: no triangles", nm(name));
        return FLOE_EINVAL;
    }
    for (int i = 0; i < 3 * m->nv; i++)
        if (!isfinite(m->v[i])) {
            floe_set_err(err, errlen, "%s: vertex %d has a non-finite coordinate", nm(name), i / 3);
            return FLOE_EINVAL;
        }
    for (int i = 0; i < 3 * m->nt; i++)
        if (m->tri[i] < 0 || m->tri[i] >= m->nv) {
            floe_set_err(err, errlen, "%s: triangle %d has vertex index %d out of range [0, %d)", nm(name), i / 3,
                    m->tri[i], m->nv);
            return FLOE_EINVAL;
        }
    double diag = bbox_diag(m);
    if (!(diag > 0)) {
        floe_set_err(err, errlen, "%s is degenerate: all vertices coincide (zero volume)", nm(name));
        return FLOE_EINVAL;
    }
    /* zero-area triangles: |cross| relative to the size of the mesh */
    for (int t = 0; t < m->nt; t++) {
        const int *f = m->tri + 3 * t;
        const double *a = m->v + 3 * f[0], *b = m->v + 3 * f[1], *c = m->v + 3 * f[2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || len <= 1e-14 * diag * diag) {
            floe_set_err(err, errlen, "%s is degenerate: triangle %d (vertices %d %d %d) has zero area", nm(name), t, f[0],
                    f[1], f[2]);
            return FLOE_EINVAL;
        }
    }
    /* closed and consistently oriented: every edge in exactly two triangles, once each way */
    size_t ne = 3 * (size_t)m->nt;
    dedge *e = malloc(ne * sizeof *e);
    if (!e) {
        floe_set_err(err, errlen, "%s: out of memory", nm(name));
        return FLOE_ENOMEM;
    }
    for (int t = 0; t < m->nt; t++)
        for (int k = 0; k < 3; k++) {
            int a = m->tri[3 * t + k], b = m->tri[3 * t + (k + 1) % 3];
            dedge *d = &e[3 * (size_t)t + (size_t)k];
            d->a = a < b ? a : b;
            d->b = a < b ? b : a;
            d->t = a < b ? 1 : -1;
        }
    qsort(e, ne, sizeof *e, dedge_cmp);
    int rc = FLOE_OK;
    for (size_t i = 0; i < ne && rc == FLOE_OK;) {
        size_t j = i + 1;
        while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b) j++;
        size_t cnt = j - i;
        if (cnt == 1) {
            floe_set_err(err, errlen, "%s is open (not closed): edge %d-%d belongs to only one triangle", nm(name), e[i].a,
                    e[i].b);
            rc = FLOE_EINVAL;
        } else if (cnt > 2) {
            floe_set_err(err, errlen, "%s is not a 2-manifold: edge %d-%d belongs to %zu triangles", nm(name), e[i].a,
                    e[i].b, cnt);
            rc = FLOE_EINVAL;
        } else if (e[i].t == e[i + 1].t) {
            floe_set_err(err, errlen,
                    "%s is not consistently oriented: the two triangles at edge %d-%d run the same way", nm(name),
                    e[i].a, e[i].b);
            rc = FLOE_EINVAL;
        }
        i = j;
    }
    free(e);
    if (rc != FLOE_OK) return rc;
    double v6 = volume6(m);
    if (fabs(v6) <= 1e-12 * diag * diag * diag) {
        floe_set_err(err, errlen, "%s is degenerate: it encloses zero volume (flat)", nm(name));
        return FLOE_EINVAL;
    }
    if (v6 < 0) {
        floe_set_err(err, errlen, "%s is inside out: its triangles face inward (negative volume %g)", nm(name), v6 / 6);
        return FLOE_EINVAL;
    }
#ifdef FLOE_HAVE_CGAL
    const floe_cgal_mesh cm = {m->nv, m->nt, m->v, m->tri};
    return floe_cgal_validate(&cm, name, err, errlen);
#else
    return FLOE_OK;
#endif
}

/* ---- hull, decomposition and distances: CGAL (mesh_cgal.h) on the mesh's arrays ---- */

#ifdef FLOE_HAVE_CGAL
/* the arrays of a CGAL result handed over to a floe_mesh */
static void take_cgal(floe_cgal_mesh *from, floe_mesh *to) {
    to->nv = from->nv;
    to->nt = from->nt;
    to->v = from->v;
    to->tri = from->tri;
    from->v = NULL;
    from->tri = NULL;
    from->nv = from->nt = 0;
}

int floe_mesh_hull(const double *pts, int n, floe_mesh *hull, char *err, size_t errlen) {
    if (!hull) return FLOE_EINVAL;
    floe_cgal_mesh h = {0, 0, NULL, NULL};
    int rc = floe_cgal_hull(pts, n, &h, err, errlen);
    take_cgal(&h, hull);
    return rc;
}

int floe_mesh_decompose(const floe_mesh *m, const char *name, floe_mesh **pieces, int *npieces, char *err,
                        size_t errlen) {
    if (!pieces || !npieces) return FLOE_EINVAL;
    *pieces = NULL;
    *npieces = 0;
    floe_cgal_mesh *cp = NULL;
    int np = 0;
    const floe_cgal_mesh cm = {m ? m->nv : 0, m ? m->nt : 0, m ? m->v : NULL, m ? m->tri : NULL};
    int rc = floe_cgal_decompose(&cm, name, &cp, &np, err, errlen);
    if (rc != FLOE_OK) return rc;
    floe_mesh *out = malloc((size_t)np * sizeof *out);
    if (!out) {
        for (int k = 0; k < np; k++) floe_cgal_mesh_free(&cp[k]);
        free(cp);
        floe_set_err(err, errlen, "%s: out of memory in the convex decomposition", nm(name));
        return FLOE_ENOMEM;
    }
    for (int k = 0; k < np; k++) take_cgal(&cp[k], &out[k]);
    free(cp);
    *pieces = out;
    *npieces = np;
    return FLOE_OK;
}

int floe_mesh_distances(const floe_mesh *m, const double *pts, int n, double *dist) {
    if (!m) return floe_cgal_distances(NULL, pts, n, dist);
    const floe_cgal_mesh cm = {m->nv, m->nt, m->v, m->tri};
    return floe_cgal_distances(&cm, pts, n, dist);
}
#else
int floe_mesh_hull(const double *pts, int n, floe_mesh *hull, char *err, size_t errlen) {
    (void)pts, (void)n;
    if (hull) hull->nv = hull->nt = 0, hull->v = NULL, hull->tri = NULL;
    floe_set_err(err, errlen, "convex hull: " NO_CGAL_MSG);
    return FLOE_ENOTSUP;
}

int floe_mesh_decompose(const floe_mesh *m, const char *name, floe_mesh **pieces, int *npieces, char *err,
                        size_t errlen) {
    (void)m;
    if (pieces) *pieces = NULL;
    if (npieces) *npieces = 0;
    floe_set_err(err, errlen, "%s: convex decomposition: " NO_CGAL_MSG, nm(name));
    return FLOE_ENOTSUP;
}

int floe_mesh_distances(const floe_mesh *m, const double *pts, int n, double *dist) {
    (void)m, (void)pts;
    for (int i = 0; dist && i < n; i++) dist[i] = NAN;
    return FLOE_ENOTSUP;
}
#endif

/* ---- shapes ---- */

/* directed edge a -> b of triangle t (sorted by (a, b) to find the opposite b -> a) */
typedef struct hedge { int a, b, t; } hedge;

static int hedge_cmp(const void *x, const void *y) {
    const hedge *p = x, *q = y;
    if (p->a != q->a) return (p->a > q->a) - (p->a < q->a);
    return (p->b > q->b) - (p->b < q->b);
}

static const hedge *hedge_find(const hedge *e, size_t ne, int a, int b) {
    hedge key = {a, b, 0};
    return bsearch(&key, e, ne, sizeof *e, hedge_cmp);
}

static void tri_normal(const floe_mesh *h, int t, double n[3]) {
    const double *a = h->v + 3 * h->tri[3 * t], *b = h->v + 3 * h->tri[3 * t + 1], *c = h->v + 3 * h->tri[3 * t + 2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++) n[k] = l > 0 ? n[k] / l : 0;
}

/* Faces of a closed, outward triangle mesh of a convex hull: neighbouring triangles in the
 * plane of a seed triangle (normals within 1e-12, vertices within 1e-12 of the size) are
 * grown into one face, whose boundary loop (the group's edges whose opposite lies outside it)
 * is the face polygon. A group whose boundary is not one simple loop is split back into its
 * triangles. O(n log n) time, linear memory. */
static floe_geometry *hull_polyhedron(const floe_mesh *h, char *err, size_t errlen) {
    int nt = h->nt, nv = h->nv;
    size_t ne = 3 * (size_t)nt;
    hedge *e = malloc(ne * sizeof *e);
    int *grp = malloc((size_t)nt * sizeof *grp), *stack = malloc((size_t)nt * sizeof *stack);
    int *fstart = malloc(((size_t)nt + 1) * sizeof *fstart), *fv = malloc(ne * sizeof *fv);
    int *next = malloc((size_t)nv * sizeof *next), *members = malloc((size_t)nt * sizeof *members);
    double *planes = malloc((size_t)nt * 4 * sizeof *planes);
    floe_geometry *g = NULL;
    if (!e || !grp || !stack || !fstart || !fv || !next || !members || !planes) {
        floe_set_err(err, errlen, "convex hull: out of memory");
        goto done;
    }
    for (int t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            hedge *d = &e[3 * (size_t)t + (size_t)k];
            d->a = h->tri[3 * t + k];
            d->b = h->tri[3 * t + (k + 1) % 3];
            d->t = t;
        }
    qsort(e, ne, sizeof *e, hedge_cmp);
    double L = bbox_diag(h), tol = 1e-12 * L;
    for (int t = 0; t < nt; t++) grp[t] = -1;
    for (int i = 0; i < nv; i++) next[i] = -1;
    int nf = 0, nfv = 0;
    fstart[0] = 0;
    for (int seed = 0; seed < nt; seed++) {
        if (grp[seed] >= 0) continue;
        double n[3];
        tri_normal(h, seed, n);
        const double *p0 = h->v + 3 * h->tri[3 * seed];
        double d = n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2];
        /* grow the group over edges */
        int sp = 0, nm = 0;
        stack[sp++] = seed;
        grp[seed] = nf;
        while (sp > 0) {
            int t = stack[--sp];
            members[nm++] = t;
            for (int k = 0; k < 3; k++) {
                const hedge *o = hedge_find(e, ne, h->tri[3 * t + (k + 1) % 3], h->tri[3 * t + k]);
                if (!o || grp[o->t] >= 0) continue;
                double m[3];
                tri_normal(h, o->t, m);
                if (n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < 1 - 1e-12) continue;
                int on = 1;
                for (int q = 0; q < 3 && on; q++) {
                    const double *x = h->v + 3 * h->tri[3 * o->t + q];
                    on = fabs(n[0] * x[0] + n[1] * x[1] + n[2] * x[2] - d) <= tol;
                }
                if (!on) continue;
                grp[o->t] = nf;
                stack[sp++] = o->t;
            }
        }
        /* boundary loop: the members' edges whose opposite triangle is in another group */
        int nb = 0, start = -1, ok = 1;
        for (int j = 0; j < nm && ok; j++)
            for (int k = 0; k < 3; k++) {
                int t = members[j], a = h->tri[3 * t + k], b = h->tri[3 * t + (k + 1) % 3];
                const hedge *o = hedge_find(e, ne, b, a);
                if (o && grp[o->t] == nf) continue;
                if (next[a] >= 0) { ok = 0; break; } /* a vertex twice on the boundary */
                next[a] = b;
                start = a;
                nb++;
            }
        int cnt = 0;
        if (ok && start >= 0) {
            int a = start;
            do {
                fv[nfv + cnt++] = a;
                a = next[a];
            } while (a >= 0 && a != start && cnt <= nb);
            ok = a == start && cnt == nb;
        }
        for (int j = 0; j < nm; j++) /* clear the marks */
            for (int k = 0; k < 3; k++) next[h->tri[3 * members[j] + k]] = -1;
        if (ok && nm > 1) {
            double *P = planes + 4 * nf;
            P[0] = n[0], P[1] = n[1], P[2] = n[2];
            double dm = -INFINITY;
            for (int q = 0; q < cnt; q++) {
                const double *x = h->v + 3 * fv[nfv + q];
                dm = fmax(dm, n[0] * x[0] + n[1] * x[1] + n[2] * x[2]);
            }
            P[3] = dm;
            nfv += cnt;
            fstart[++nf] = nfv;
            continue;
        }
        /* one face per triangle */
        for (int j = 0; j < nm; j++) {
            int t = members[j];
            double m[3];
            tri_normal(h, t, m);
            const double *x = h->v + 3 * h->tri[3 * t];
            double *P = planes + 4 * nf;
            P[0] = m[0], P[1] = m[1], P[2] = m[2];
            P[3] = m[0] * x[0] + m[1] * x[1] + m[2] * x[2];
            for (int k = 0; k < 3; k++) fv[nfv++] = h->tri[3 * t + k];
            grp[t] = nf;
            fstart[++nf] = nfv;
        }
    }
    g = floe_polyhedron_from_faces(h->v, nv, fstart, fv, nf, planes, err, errlen);
done:
    free(e), free(grp), free(stack), free(fstart), free(fv), free(next), free(members), free(planes);
    return g;
}

floe_geometry *floe_polyhedron_from_points(const double *pts, int n, char *err, size_t errlen) {
    floe_mesh h;
    if (floe_mesh_hull(pts, n, &h, err, errlen) != FLOE_OK) return NULL;
    floe_geometry *g = hull_polyhedron(&h, err, errlen);
    floe_mesh_free(&h);
    return g;
}

static void flip(floe_mesh *m) {
    for (int t = 0; t < m->nt; t++) {
        int s = m->tri[3 * t + 1];
        m->tri[3 * t + 1] = m->tri[3 * t + 2];
        m->tri[3 * t + 2] = s;
    }
}

floe_geometry *floe_mesh_shape(const char *path, const char *mode, double scale, char *err, size_t errlen) {
    int hull = mode && strcmp(mode, "hull") == 0, dec = mode && strcmp(mode, "decompose") == 0;
    if (!hull && !dec) {
        floe_set_err(err, errlen, "mesh file '%s': unknown mode '%s' (use \"hull\" or \"decompose\")", path ? path : "",
                mode ? mode : "(null)");
        return NULL;
    }
    if (!(floe_mesh_features() & FLOE_MESH_HAVE_CGAL)) {
        floe_set_err(err, errlen, "mesh file '%s' (mode %s): " NO_CGAL_MSG, path ? path : "", mode);
        return NULL;
    }
    floe_mesh m;
    if (floe_mesh_load(path, scale, &m, err, errlen) != FLOE_OK) return NULL;
    char pre[300];
    snprintf(pre, sizeof pre, "mesh file '%s': ", path);
    /* both modes: an inward-facing closed mesh is the same solid: turn it outward; open,
     * self-intersecting or degenerate meshes are refused (a hull of an open mesh would
     * silently close it) */
    if (m.nt > 0 && volume6(&m) < 0) flip(&m);
    char name[300];
    snprintf(name, sizeof name, "mesh file '%s'", path);
    if (floe_mesh_validate(&m, name, err, errlen) != FLOE_OK) {
        floe_mesh_free(&m);
        return NULL;
    }
    if (hull) {
        floe_geometry *g = floe_polyhedron_from_points(m.v, m.nv, err, errlen);
        floe_mesh_free(&m);
        if (!g) prefix_err(err, errlen, pre);
        return g;
    }
    floe_mesh *pc = NULL;
    int np = 0;
    int rc = floe_mesh_decompose(&m, name, &pc, &np, err, errlen);
    floe_mesh_free(&m);
    if (rc != FLOE_OK) return NULL;
    floe_geometry **g = calloc((size_t)np, sizeof *g);
    double *x = malloc((size_t)np * 3 * sizeof *x), *q = malloc((size_t)np * 4 * sizeof *q);
    int ok = g && x && q;
    if (!ok) floe_set_err(err, errlen, "mesh file '%s': out of memory", path);
    for (int i = 0; ok && i < np; i++) {
        g[i] = floe_polyhedron_from_mesh(pc[i].v, pc[i].nv, pc[i].tri, pc[i].nt, err, errlen);
        if (!g[i]) {
            char what[64];
            snprintf(what, sizeof what, "convex piece %d of %d: ", i + 1, np);
            prefix_err(err, errlen, what);
            prefix_err(err, errlen, pre);
            ok = 0;
            break;
        }
        const floe_polytope *p = (const floe_polytope *)g[i];
        memcpy(x + 3 * i, p->frame_x, 3 * sizeof(double));
        memcpy(q + 4 * i, p->frame_q, 4 * sizeof(double));
    }
    for (int i = 0; i < np; i++) floe_mesh_free(&pc[i]);
    free(pc);
    floe_geometry *out = NULL;
    if (ok) {
        out = floe_compound_create(g, x, q, np, 3, err, errlen); /* owns the pieces */
        if (!out) prefix_err(err, errlen, pre);
    } else if (g) {
        for (int i = 0; i < np; i++)
            if (g[i]) floe_geometry_destroy(g[i]);
    }
    free(g), free(x), free(q);
    return out;
}
