/* scene_bodies.c - scene section `bodies`: shapes (registered shapes, read by their schemas,
 * and the point-list and nested shapes the loader reads itself), single bodies and packings
 * (lattice, hexagonal, random). */
#include "scene_read.h"

/* ------------------------------------------------------------------------------------ */
/* Bodies                                                                                */

typedef struct sc_shape {
    int kind;            /* 0 sphere, 1 box, 2 any other shape (built from node) */
    double radius;       /* sphere */
    double size[3];      /* box */
    double rb;           /* bounding radius */
    double fq[4];        /* orientation of the body frame in the shape's input coordinates */
    struct fy_node *node, *key;
    char field[160];
} sc_shape;

/* body frame of a shape in its input coordinates (polytopes, compounds: centroid and
 * principal axes; primitives: identity) */
void sc_geom_frame(const floe_geometry *g, double fx[3], double fq[4])
{
    floe_v3_set(fx, 0, 0, 0);
    floe_q_identity(fq);
    if (g->klass == &floe_polytope_class) {
        const floe_polytope *p = (const floe_polytope *)g;
        floe_v3_copy(fx, p->frame_x);
        memcpy(fq, p->frame_q, 4 * sizeof(double));
    } else if (g->klass == &floe_compound_class) {
        const floe_compound *c = (const floe_compound *)g;
        floe_v3_copy(fx, c->frame_x);
        memcpy(fq, c->frame_q, 4 * sizeof(double));
    }
}

/* A list of points (each 2 or 3 numbers): *out malloc'd, dim numbers per point. */
static int sc_points_list(sc *s, struct fy_node *v, struct fy_node *k, const char *f, int dim, int min,
                          double **out, int *n)
{
    *out = NULL;
    *n = 0;
    if (!v || v == k || !fy_node_is_sequence(v))
        return sc_fail(s, FLOE_EPARSE, v && v != k ? v : k, "%s must be a list of %d-number points", f, dim);
    int cnt = fy_node_sequence_item_count(v);
    if (cnt < min)
        return sc_fail(s, FLOE_EINVAL, v, "%s needs at least %d points (got %d)", f, min, cnt);
    double *x = malloc((size_t)cnt * dim * sizeof(double));
    if (!x) return sc_fail(s, FLOE_ENOMEM, v, "out of memory");
    for (int i = 0; i < cnt; i++) {
        char f2[192];
        snprintf(f2, sizeof f2, "%s[%d]", f, i);
        int got;
        int rc = sc_node_list(s, fy_node_sequence_get_by_index(v, i), NULL, f2, dim, 0, x + (size_t)dim * i, &got);
        if (rc) { free(x); return rc; }
    }
    *out = x;
    *n = cnt;
    return FLOE_OK;
}

/* Build any shape from its {kind: {...}} mapping (f names the field in messages). */
int sc_build_shape(sc *s, struct fy_node *v, struct fy_node *k, const char *f, int depth,
                          floe_geometry **out)
{
    *out = NULL;
    if (depth > 8) return sc_fail(s, FLOE_EPARSE, v, "%s: shapes nested too deep", f);
    sc_map m;
    const char *kinds[128];
    int nk = 0;
    for (; nk < floe_registry_count(FLOE_KIND_SHAPE) && nk < 127; nk++)
        kinds[nk] = floe_registry_at(FLOE_KIND_SHAPE, nk)->name;
    kinds[nk] = NULL;
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, f, kinds, &m));
    if (fy_node_mapping_item_count(v) != 1) {
        char list[1024];
        size_t L = 0;
        list[0] = 0;
        for (int q = 0; q < nk && L < sizeof list; q++)
            L += (size_t)snprintf(list + L, sizeof list - L, "%s%s", q ? (q == nk - 1 ? " or " : ", ") : "", kinds[q]);
        return sc_fail(s, FLOE_EPARSE, v, "%s: give exactly one shape (%s)", f, list);
    }
    struct fy_node_pair *pr = fy_node_mapping_get_by_index(v, 0);
    struct fy_node *sk = fy_node_pair_key(pr), *sv = fy_node_pair_value(pr);
    const char *kind = sc_text(sk);
    if (!kind) return sc_fail(s, FLOE_EPARSE, v, "%s: the shape kind must be a plain name", f);
    char f2[160], err[512] = "";
    snprintf(f2, sizeof f2, "%s.%s", f, kind);
    floe_geometry *g = NULL;
    sc_map sm;
#define OPEN(...) do { static const char *const keys_[] = {__VA_ARGS__, NULL}; \
        FLOE_TRY(sc_map_open(s, sv == sk ? NULL : sv, sk, f2, keys_, &sm)); } while (0)
    const floe_registry_entry *ent = floe_registry_find(FLOE_KIND_SHAPE, kind);
    if (!(ent->flags & FLOE_ENTRY_LOADER_PARSES)) {
        /* a shape read by its schema (sphere, box, ellipsoid, ..., and plugins' shapes) */
        static const char *const none_[] = {NULL};
        char label[96];
        snprintf(label, sizeof label, "shape '%s'", ent->name);
        void *params = calloc(1, ent->params_size);
        if (!params) return sc_fail(s, FLOE_ENOMEM, sk, "out of memory");
        int rc = sv == sk || !fy_node_is_mapping(sv) ? sc_map_open(s, sv == sk ? NULL : sv, sk, f2, none_, &sm) : FLOE_OK;
        if (!rc) {
            sm.node = sv;
            sm.at = sk;
            snprintf(sm.what, sizeof sm.what, "%s", f2);
            rc = sc_read_schema(s, &sm, ent, label, NULL, params);
        }
        if (!rc) {
            g = ((floe_shape_create_fn)ent->create)(params, s->dim, err, sizeof err);
            if (!g) rc = sc_fail(s, FLOE_EINVAL, sk, "%s: %s", f2, err[0] ? err : "could not create the shape");
        }
        free(params);
        FLOE_TRY(rc);
    } else if (!strcmp(kind, "polyhedron")) {
        OPEN("vertices", "planes");
        struct fy_node *vk, *vv = sc_get(&sm, "vertices", &vk), *pk, *pv = sc_get(&sm, "planes", &pk);
        if (!vv == !pv)
            return sc_fail(s, FLOE_EPARSE, sk, "%s: give either vertices (convex hull) or planes ([nx, ny, nz, d]: "
                           "n.x <= d inside)", f2);
        double *pts;
        int n;
        char f3[192];
        snprintf(f3, sizeof f3, "%s.%s", f2, vv ? "vertices" : "planes");
        if (vv) {
            FLOE_TRY(sc_points_list(s, vv, vk, f3, 3, 4, &pts, &n));
            g = floe_polyhedron_from_points(pts, n, err, sizeof err);
        } else {
            FLOE_TRY(sc_points_list(s, pv, pk, f3, 4, 4, &pts, &n));
            g = floe_polyhedron_from_planes(pts, n, err, sizeof err);
        }
        free(pts);
        if (!g) return sc_fail(s, FLOE_EINVAL, vv ? vv : pv, "%s: %s", f3, err);
    } else if (!strcmp(kind, "polygon") || !strcmp(kind, "prism")) {
        int prism = kind[1] == 'r';
        if (prism) OPEN("vertices", "height");
        else OPEN("vertices");
        if (!prism && s->dim != 2)
            return sc_fail(s, FLOE_EINVAL, sk, "%s: a polygon is a 2D shape (dim: 2); in 3D use prism or polyhedron", f2);
        struct fy_node *vk, *vv = sc_get(&sm, "vertices", &vk);
        if (!vv) return sc_fail(s, FLOE_EPARSE, sk, "%s.vertices is required ([[x, y], ...])", f2);
        double *pts, h = 0;
        int n;
        char f3[192];
        snprintf(f3, sizeof f3, "%s.vertices", f2);
        if (prism) FLOE_TRY(sc_pos_num(s, &sm, "height", &h));
        FLOE_TRY(sc_points_list(s, vv, vk, f3, 2, 3, &pts, &n));
        g = prism ? floe_prism_create(pts, n, h, err, sizeof err) : floe_polygon_create(pts, n, err, sizeof err);
        free(pts);
        if (!g) return sc_fail(s, FLOE_EINVAL, vv, "%s: %s", f3, err);
    } else if (!strcmp(kind, "rounded")) {
        double r;
        OPEN("radius", "shape");
        FLOE_TRY(sc_pos_num(s, &sm, "radius", &r));
        struct fy_node *ik, *iv = sc_get(&sm, "shape", &ik);
        if (!iv) return sc_fail(s, FLOE_EPARSE, sk, "%s.shape is required (the shape to round)", f2);
        char f3[192];
        snprintf(f3, sizeof f3, "%s.shape", f2);
        floe_geometry *inner;
        FLOE_TRY(sc_build_shape(s, iv, ik, f3, depth + 1, &inner));
        if (inner->klass->kind == FLOE_GEOM_COMPOUND || inner->klass->kind == FLOE_GEOM_PLANE) {
            floe_geometry_destroy(inner);
            return sc_fail(s, FLOE_EINVAL, iv, "%s: only a convex shape can be rounded", f3);
        }
        g = floe_rounded_create(inner, r);
    } else if (!strcmp(kind, "compound")) {
        OPEN("pieces");
        struct fy_node *pk, *pv = sc_get(&sm, "pieces", &pk);
        if (!pv || pv == pk || !fy_node_is_sequence(pv) || fy_node_sequence_item_count(pv) < 1)
            return sc_fail(s, FLOE_EPARSE, pv && pv != pk ? pv : sk,
                           "%s.pieces must be a list of {shape, position, orientation}", f2);
        int n = fy_node_sequence_item_count(pv);
        floe_geometry **pieces = calloc((size_t)n, sizeof *pieces);
        double *px = calloc((size_t)n * 3, sizeof(double)), *pq = calloc((size_t)n * 4, sizeof(double));
        int rc = pieces && px && pq ? FLOE_OK : sc_fail(s, FLOE_ENOMEM, pv, "out of memory");
        for (int i = 0; i < n && rc == FLOE_OK; i++) {
            static const char *const piece_keys[] = {"shape", "position", "orientation", NULL};
            char f3[192];
            snprintf(f3, sizeof f3, "%s.pieces[%d]", f2, i);
            struct fy_node *e = fy_node_sequence_get_by_index(pv, i);
            sc_map pm;
            rc = sc_map_open(s, e, e, f3, piece_keys, &pm);
            struct fy_node *shk = NULL, *shv = rc ? NULL : sc_get(&pm, "shape", &shk);
            if (rc == FLOE_OK && !shv) rc = sc_fail(s, FLOE_EPARSE, e, "%s.shape is required", f3);
            double pos[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
            if (rc == FLOE_OK) rc = sc_vec(s, &pm, "position", 0, NULL, pos);
            struct fy_node *ok, *ov = rc ? NULL : sc_get(&pm, "orientation", &ok);
            if (rc == FLOE_OK && ov) {
                int got;
                char f4[224];
                snprintf(f4, sizeof f4, "%s.orientation", f3);
                rc = sc_node_list(s, ov, ok, f4, 4, 0, q, &got);
                double qn = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
                if (rc == FLOE_OK && !(qn > 0)) rc = sc_fail(s, FLOE_EINVAL, ov, "%s must be a non-zero quaternion", f4);
                if (rc == FLOE_OK) floe_q_normalize(q);
            }
            if (rc == FLOE_OK) {
                char f4[224];
                snprintf(f4, sizeof f4, "%s.shape", f3);
                rc = sc_build_shape(s, shv, shk, f4, depth + 1, &pieces[i]);
            }
            if (rc == FLOE_OK && pieces[i]->klass->kind == FLOE_GEOM_COMPOUND)
                rc = sc_fail(s, FLOE_EINVAL, shv, "%s.shape: a piece must be convex (not a compound or mesh "
                             "decomposition)", f3);
            if (rc == FLOE_OK) {
                /* the piece's body frame placed in the compound's input coordinates */
                double fx[3], fq[4], off[3];
                sc_geom_frame(pieces[i], fx, fq);
                floe_q_rotate(off, q, fx);
                for (int c = 0; c < 3; c++) px[3 * i + c] = pos[c] + off[c];
                floe_q_mul(pq + 4 * i, q, fq);
            }
        }
        if (rc == FLOE_OK) {
            g = floe_compound_create(pieces, px, pq, n, s->dim, err, sizeof err); /* owns the pieces */
            if (!g) rc = sc_fail(s, FLOE_EINVAL, pv, "%s: %s", f2, err);
        } else if (pieces) {
            for (int i = 0; i < n; i++) floe_geometry_destroy(pieces[i]);
        }
        free(pieces);
        free(px);
        free(pq);
        if (rc) return rc;
    } else { /* mesh */
        OPEN("file", "mode", "scale");
        const char *file, *mode;
        struct fy_node *fat;
        double scale;
        FLOE_TRY(sc_str(s, &sm, "file", 1, NULL, &file, &fat));
        static const char *const modes[] = {"hull", "decompose", NULL};
        int mi;
        FLOE_TRY(sc_enum(s, &sm, "mode", modes, 0, &mi));
        mode = modes[mi];
        FLOE_TRY(sc_num(s, &sm, "scale", 0, 1.0, &scale));
        if (!(scale > 0)) return sc_range(s, &sm, "scale", "> 0", scale);
        if (s->dim != 3) return sc_fail(s, FLOE_EINVAL, sk, "%s: meshes are 3D shapes (dim: 3)", f2);
        /* relative paths are relative to the scene file */
        char path[1024];
        const char *slash = s->path ? strrchr(s->path, '/') : NULL;
        if (file[0] != '/' && slash)
            snprintf(path, sizeof path, "%.*s/%s", (int)(slash - s->path), s->path, file);
        else snprintf(path, sizeof path, "%s", file);
        g = floe_mesh_shape(path, mode, scale, err, sizeof err);
        if (!g) return sc_fail(s, (floe_mesh_features() & (FLOE_MESH_HAVE_ASSIMP | FLOE_MESH_HAVE_CGAL)) ==
                                      (FLOE_MESH_HAVE_ASSIMP | FLOE_MESH_HAVE_CGAL) ? FLOE_EINVAL : FLOE_ENOTSUP,
                               fat, "%s.file: %s", f2, err);
    }
#undef OPEN
    if (!g) return sc_fail(s, FLOE_EINVAL, sk, "%s: could not create the shape%s%s", f2, err[0] ? ": " : "", err);
    *out = g;
    return FLOE_OK;
}

static int sc_parse_shape(sc *s, const sc_map *body, sc_shape *sh)
{
    struct fy_node *k;
    struct fy_node *v = sc_get(body, "shape", &k);
    char f[128];
    sc_field(f, sizeof f, body, "shape");
    memset(sh, 0, sizeof *sh);
    floe_q_identity(sh->fq);
    if (sc_has(body, "radius_distribution")) {
        /* spheres (discs) of drawn radii (scene_psd.c): sc_parse_bodies sets the radius */
        if (v)
            return sc_fail(s, FLOE_EPARSE, k, "%s: give either shape or radius_distribution (spheres of drawn "
                           "radii)", f);
        sh->kind = 0;
        snprintf(sh->field, sizeof sh->field, "%s.radius_distribution", body->what);
        return FLOE_OK;
    }
    if (!v)
        return sc_fail(s, FLOE_EPARSE, body->at, "%s is required ({sphere: {radius: R}}, "
                       "{box: {size: [lx, ly, lz]}}, polyhedron, ...: docs/scene-format.md)", f);
    floe_geometry *g;
    FLOE_TRY(sc_build_shape(s, v, k, f, 0, &g));
    sh->node = v;
    sh->key = k;
    snprintf(sh->field, sizeof sh->field, "%s", f);
    sh->rb = floe_geometry_bounding_radius(g);
    if (g->klass == &floe_sphere_class) {
        sh->kind = 0;
        sh->radius = ((const floe_sphere *)g)->radius;
    } else if (g->klass == &floe_box_class) {
        sh->kind = 1;
        for (int i = 0; i < 3; i++) sh->size[i] = 2 * ((const floe_box *)g)->half[i];
    } else {
        sh->kind = 2;
        double fx[3];
        sc_geom_frame(g, fx, sh->fq);
    }
    floe_geometry_destroy(g);
    return FLOE_OK;
}

static int sc_add_geometry(sc *s, const sc_shape *sh, struct fy_node *at, const char *what, int *gi)
{
    floe_geometry *g;
    if (sh->kind == 0) g = floe_sphere_create(sh->radius);
    else if (sh->kind == 1) g = floe_box_create(sh->size[0], sh->size[1], sh->size[2]);
    else FLOE_TRY(sc_build_shape(s, sh->node, sh->key, sh->field, 0, &g));
    if (!g) return sc_fail(s, FLOE_ENOMEM, at, "%s: could not create the shape", what);
    int r = floe_world_add_geometry(s->w, g);
    if (r < 0) {
        floe_geometry_destroy(g);
        return sc_fail(s, -r, at, "%s: %s", what, floe_world_last_error(s->w));
    }
    *gi = r;
    return FLOE_OK;
}

/* What every body entry shares: material, initial motion, orientation, growth. */
typedef struct sc_common {
    sc_shape shape;
    int material;
    double v[3], w[3], q[4];
    floe_motion motion;
    int grow;            /* 1: one particle grows */
    long grow_index;
    double grow_rate;
    struct fy_node *grow_at;     /* the rate's node, for messages */
    int grow_update_mass;
    double thickness;    /* 2D floes: h, m (0: none) */
} sc_common;

static const char *const sc_motions[] = {"free", "fixed", "kinematic", NULL};

static int sc_parse_common(sc *s, const sc_map *m, int entry, int packing, sc_common *c)
{
    static const char *const grow_keys_single[] = {"rate", "update_mass", NULL};
    static const char *const grow_keys_packing[] = {"index", "rate", "update_mass", NULL};
    FLOE_TRY(sc_parse_shape(s, m, &c->shape));
    const char *mname;
    struct fy_node *mat_at;
    FLOE_TRY(sc_str(s, m, "material", 1, NULL, &mname, &mat_at));
    char f[128];
    snprintf(f, sizeof f, "%s.material", m->what);
    FLOE_TRY(sc_material_ref(s, mname, mat_at, f, &c->material));
    if (!s->mats[c->material].body_user) {
        s->mats[c->material].body_user = mat_at;
        s->mats[c->material].body_entry = entry;
    }
    FLOE_TRY(sc_vec(s, m, "velocity", 0, NULL, c->v));
    FLOE_TRY(sc_check_planar(s, m, "velocity", c->v));
    {
        struct fy_node *k;
        struct fy_node *v = sc_get(m, "angular_velocity", &k);
        char fw[128];
        sc_field(fw, sizeof fw, m, "angular_velocity");
        c->w[0] = c->w[1] = c->w[2] = 0;
        if (v) {
            int got;
            FLOE_TRY(sc_node_list(s, v, k, fw, 3, 0, c->w, &got));
            if (s->dim == 2 && (c->w[0] != 0 || c->w[1] != 0))
                return sc_fail(s, FLOE_EINVAL, v,
                               "%s: in a 2D scene only the z component may be non-zero", fw);
        }
    }
    {
        struct fy_node *k;
        struct fy_node *v = sc_get(m, "orientation", &k);
        char fq[128];
        sc_field(fq, sizeof fq, m, "orientation");
        floe_q_identity(c->q);
        if (v) {
            int got;
            FLOE_TRY(sc_node_list(s, v, k, fq, 4, 0, c->q, &got));
            double n = sqrt(c->q[0] * c->q[0] + c->q[1] * c->q[1] + c->q[2] * c->q[2] +
                            c->q[3] * c->q[3]);
            if (!(n > 0))
                return sc_fail(s, FLOE_EINVAL, v, "%s must be a non-zero quaternion [w, x, y, z]", fq);
            floe_q_normalize(c->q);
            if (s->dim == 2 && (c->q[1] != 0 || c->q[2] != 0))
                return sc_fail(s, FLOE_EINVAL, v,
                               "%s: in a 2D scene the orientation must be a rotation about z "
                               "([w, 0, 0, z])", fq);
        }
    }
    {
        /* the orientation turns the shape as written; its body (principal) frame sits at
         * frame_q within those coordinates */
        double q[4];
        floe_q_mul(q, c->q, c->shape.fq);
        floe_q_normalize(q);
        memcpy(c->q, q, sizeof q);
    }
    int mo;
    FLOE_TRY(sc_enum(s, m, "motion", sc_motions, 0, &mo));
    c->motion = (floe_motion)mo;
    c->thickness = 0;
    if (sc_has(m, "thickness")) { /* a floe: mass = density x area x thickness */
        if (s->dim != 2)
            return sc_fail(s, FLOE_EINVAL, sc_get(m, "thickness", NULL),
                           "%s.thickness is for 2D floes (dimension: 2)", m->what);
        FLOE_TRY(sc_num(s, m, "thickness", 1, 0, &c->thickness));
        if (!(c->thickness > 0)) return sc_range(s, m, "thickness", "> 0 (m)", c->thickness);
    }

    c->grow = 0;
    c->grow_index = 0;
    c->grow_update_mass = 0;
    struct fy_node *gk;
    struct fy_node *gv = sc_get(m, "grow", &gk);
    int has_rate = sc_has(m, "grow_rate");
    if (gv && has_rate)
        return sc_fail(s, FLOE_EPARSE, gk, "%s: give either grow_rate or grow, not both", m->what);
    if (has_rate) {
        if (packing)
            return sc_fail(s, FLOE_EPARSE, m->at,
                           "%s: grow_rate is for single bodies; for a packing use "
                           "grow: {index: I, rate: R}", m->what);
        FLOE_TRY(sc_num(s, m, "grow_rate", 1, 0, &c->grow_rate));
        c->grow_at = sc_get(m, "grow_rate", NULL);
        c->grow = 1;
    } else if (gv) {
        char fg[128];
        sc_field(fg, sizeof fg, m, "grow");
        sc_map gm;
        FLOE_TRY(sc_map_open(s, gv == gk ? NULL : gv, gk, fg,
                             packing ? grow_keys_packing : grow_keys_single, &gm));
        FLOE_TRY(sc_num(s, &gm, "rate", 1, 0, &c->grow_rate));
        c->grow_at = sc_get(&gm, "rate", NULL);
        if (packing) {
            FLOE_TRY(sc_long(s, &gm, "index", 1, 0, &c->grow_index));
            if (c->grow_index < 0) return sc_range(s, &gm, "index", ">= 0", (double)c->grow_index);
        }
        FLOE_TRY(sc_bool(s, &gm, "update_mass", 0, &c->grow_update_mass));
        c->grow = 1;
    }
    if (c->grow && c->shape.kind != 0)
        return sc_fail(s, FLOE_EINVAL, gv ? gk : m->at,
                       "%s: only spheres can grow (growing radius state)", m->what);
    return FLOE_OK;
}

static int sc_add_one(sc *s, const sc_common *c, int gi, const double x[3], int entry,
                      struct fy_node *at, const char *what, int *pidx)
{
    floe_particle_def d = floe_default_particle_def();
    d.geometry = gi;
    d.material = c->material;
    floe_v3_copy(d.x, x);
    floe_v3_copy(d.v, c->v);
    floe_v3_copy(d.w, c->w);
    for (int k = 0; k < 4; k++) d.q[k] = c->q[k];
    d.motion = c->motion;
    d.group = entry;
    d.thickness = c->thickness;
    int r = floe_world_add_particle(s->w, &d);
    if (r < 0) return sc_fail(s, -r, at, "%s: %s", what, floe_world_last_error(s->w));
    *pidx = r;
    s->mats[c->material].nbody++;
    if (c->motion == FLOE_FREE) s->mats[c->material].nfree = 1;
    s->nparticles++;
    if (c->shape.kind == 0) s->nspheres++;
    else s->nboxes++;
    return FLOE_OK;
}

static int sc_add_growth(sc *s, const sc_common *c, int particle, struct fy_node *at,
                         const char *what)
{
    /* a shrinking sphere must keep a positive radius to the end of the run */
    double r0 = s->w->p.radius[particle], r1 = r0 + c->grow_rate * s->duration;
    if (!(r1 > 0))
        return sc_fail(s, FLOE_EINVAL, c->grow_at ? c->grow_at : at,
                       "%s: growth rate %g m/s shrinks the radius %g m of particle %d to zero at t = %g s, "
                       "before the end of the run (time.duration %g s)", what, c->grow_rate, r0, particle,
                       -r0 / c->grow_rate, s->duration);
    floe_state *st = floe_growing_radius_create(s->w, particle, c->grow_rate, c->grow_update_mass);
    if (!st)
        return sc_fail(s, FLOE_EINVAL, at, "%s: could not create the growing radius of particle %d",
                       what, particle);
    int r = floe_world_add_state(s->w, st);
    if (r != FLOE_OK) { /* not taken: still ours */
        if (st->klass->destroy) st->klass->destroy(st);
        else free(st);
        return sc_fail(s, r < 0 ? -r : r, at, "%s: %s", what, floe_world_last_error(s->w));
    }
    if (s->ngrow_listed < (int)(sizeof s->grow_particle / sizeof s->grow_particle[0]))
        s->grow_particle[s->ngrow_listed++] = particle;
    s->nstates++;
    return FLOE_OK;
}

/* Region {min: [...], max: [...]} with min < max on the active axes. */
static int sc_parse_region(sc *s, const sc_map *m, double lo[3], double hi[3])
{
    static const char *const keys[] = {"min", "max", NULL};
    struct fy_node *k;
    struct fy_node *v = sc_get(m, "region", &k);
    char f[128];
    sc_field(f, sizeof f, m, "region");
    sc_map rm;
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, f, keys, &rm));
    FLOE_TRY(sc_vec(s, &rm, "min", 1, NULL, lo));
    FLOE_TRY(sc_vec(s, &rm, "max", 1, NULL, hi));
    for (int a = 0; a < s->dim; a++) {
        if (!(hi[a] > lo[a]))
            return sc_fail(s, FLOE_EINVAL, sc_get(&rm, "max", NULL),
                           "%s: max must exceed min on every axis (axis %c: %g <= %g)", f, "xyz"[a],
                           hi[a], lo[a]);
        if (!(hi[a] - lo[a] <= 1e12))
            return sc_fail(s, FLOE_EINVAL, sc_get(&rm, "max", NULL),
                           "%s: the region is %g m long along %c, beyond 1e12 m", f, hi[a] - lo[a],
                           "xyz"[a]);
    }
    if (s->dim == 2) { lo[2] = hi[2] = 0; }
    return FLOE_OK;
}

/* Lattice site (i, j, k) of a simple-cubic or hexagonal (2D triangular / 3D HCP) packing,
 * relative to the origin. HCP: ABAB triangular layers, B shifted by (d/2, d sqrt(3)/6). */
static void sc_site(int hex, int dim, double d, long i, long j, long k, double x[3])
{
    if (!hex) {
        x[0] = (double)i * d;
        x[1] = (double)j * d;
        x[2] = dim == 3 ? (double)k * d : 0.0;
        return;
    }
    double ox = 0, oy = 0;
    if (dim == 3 && (k % 2)) { ox = 0.5 * d; oy = d * sqrt(3.0) / 6.0; }
    x[0] = ox + ((j % 2) ? 0.5 * d : 0.0) + (double)i * d;
    x[1] = oy + (double)j * (d * sqrt(3.0) / 2.0);
    x[2] = dim == 3 ? (double)k * (d * sqrt(2.0 / 3.0)) : 0.0;
}

typedef struct sc_points { double *x; long n, cap; } sc_points;

static int sc_points_push(sc_points *p, const double x[3])
{
    if (p->n == p->cap) {
        long nc = p->cap ? 2 * p->cap : 256;
        double *nx = realloc(p->x, (size_t)nc * 3 * sizeof *nx);
        if (!nx) return FLOE_ENOMEM;
        p->x = nx;
        p->cap = nc;
    }
    floe_v3_copy(p->x + 3 * p->n, x);
    p->n++;
    return FLOE_OK;
}

static int sc_lattice(sc *s, const sc_map *m, int hex, sc_points *pts, const sc_common *c)
{
    double d;
    FLOE_TRY(sc_num(s, m, "spacing", 1, 0, &d));
    if (!(d > 0)) return sc_range(s, m, "spacing", "> 0 (m)", d);
    double jitter;
    FLOE_TRY(sc_num(s, m, "jitter", 0, 0.0, &jitter));
    if (!(jitter >= 0)) return sc_range(s, m, "jitter", ">= 0 (m)", jitter);
    long seed;
    FLOE_TRY(sc_long(s, m, "seed", 0, 1, &seed));
    /* spheres must not overlap initially: nearest neighbours are d apart in both packings */
    if (c->shape.kind == 0 && d - 2.0 * jitter < 2.0 * c->shape.radius * (1.0 - 1e-9)) {
        if (jitter > 0)
            return sc_fail(s, FLOE_EINVAL, sc_get(m, "spacing", NULL),
                           "%s.spacing - 2 x jitter (%g) is less than the sphere diameter %g: "
                           "spheres would overlap", m->what, d - 2.0 * jitter, 2.0 * c->shape.radius);
        return sc_fail(s, FLOE_EINVAL, sc_get(m, "spacing", NULL),
                       "%s.spacing (%g) is less than the sphere diameter %g: spheres would overlap",
                       m->what, d, 2.0 * c->shape.radius);
    }
    int has_counts = sc_has(m, "counts"), has_region = sc_has(m, "region");
    if (has_counts == has_region)
        return sc_fail(s, FLOE_EPARSE, has_region ? sc_get(m, "region", NULL) : m->at,
                       "%s: give either counts (with origin) or region", m->what);
    double origin[3];
    long cnt[3] = {1, 1, 1};
    double lo[3], hi[3];
    int use_region = has_region;
    if (has_counts) {
        FLOE_TRY(sc_vec(s, m, "origin", 1, NULL, origin));
        FLOE_TRY(sc_check_planar(s, m, "origin", origin));
        struct fy_node *k;
        struct fy_node *v = sc_get(m, "counts", &k);
        char f[128];
        sc_field(f, sizeof f, m, "counts");
        double dc[3];
        int got;
        FLOE_TRY(sc_node_list(s, v, k, f, s->dim == 3 ? 3 : 3, s->dim == 2 ? 2 : 0, dc, &got));
        if (got == 2) dc[2] = 1;
        double total = 1;
        for (int a = 0; a < 3; a++) {
            if (dc[a] != floor(dc[a]) || dc[a] < 1)
                return sc_fail(s, FLOE_EINVAL, fy_node_sequence_get_by_index(v, a < got ? a : 0),
                               "%s[%d] must be an integer >= 1 (got %g)", f, a, dc[a]);
            total *= dc[a];
            cnt[a] = (long)dc[a];
        }
        if (s->dim == 2 && cnt[2] != 1)
            return sc_fail(s, FLOE_EINVAL, v, "%s: the third count must be 1 in a 2D scene", f);
        if (total > (double)SC_MAX_PARTICLES_PER_ENTRY)
            return sc_fail(s, FLOE_EINVAL, v, "%s: %g particles is too many", f, total);
    } else {
        if (sc_has(m, "origin"))
            return sc_fail(s, FLOE_EPARSE, sc_get(m, "origin", NULL),
                           "%s: origin is not used with region (the lattice starts at region.min)",
                           m->what);
        FLOE_TRY(sc_parse_region(s, m, lo, hi));
        floe_v3_copy(origin, lo);
        /* counts large enough to cover the region; sites beyond max are skipped */
        double step[3] = {d, hex ? d * sqrt(3.0) / 2.0 : d, hex ? d * sqrt(2.0 / 3.0) : d};
        double total = 1, cd[3];
        for (int a = 0; a < 3; a++) {
            cd[a] = a < s->dim ? floor((hi[a] - lo[a]) / step[a]) + 2 : 1;
            total *= cd[a];
        }
        if (!(total <= 4.0 * (double)SC_MAX_PARTICLES_PER_ENTRY))
            return sc_fail(s, FLOE_EINVAL, sc_get(m, "region", NULL),
                           "%s.region holds too many lattice sites (%.3g at spacing %g; at most 1e8 "
                           "particles per entry)", m->what, total, d);
        for (int a = 0; a < 3; a++) cnt[a] = (long)cd[a];
    }
    FLOE_TRY(sc_check_memory(s, has_counts ? sc_get(m, "counts", NULL) : sc_get(m, "region", NULL), m->what,
                             (double)cnt[0] * (double)cnt[1] * (double)cnt[2]));
    sc_rng rng = {(uint64_t)seed};
    for (long k = 0; k < cnt[2]; k++)
        for (long j = 0; j < cnt[1]; j++)
            for (long i = 0; i < cnt[0]; i++) {
                double x[3];
                sc_site(hex, s->dim, d, i, j, k, x);
                floe_v3_add(x, x, origin);
                if (use_region) {
                    int out = 0;
                    for (int a = 0; a < s->dim; a++)
                        if (x[a] > hi[a] + 1e-12 * d) out = 1;
                    if (out) continue;
                }
                if (jitter > 0)
                    for (int a = 0; a < s->dim; a++)
                        x[a] += jitter * (2.0 * sc_rng_uniform(&rng) - 1.0);
                if (sc_points_push(pts, x)) return sc_fail(s, FLOE_ENOMEM, m->at, "out of memory");
            }
    if (pts->n == 0)
        return sc_fail(s, FLOE_EINVAL, sc_get(m, "region", NULL),
                       "%s.region is too small for a single lattice site", m->what);
    return FLOE_OK;
}

/* Random sequential placement of non-overlapping bounding spheres inside the region (each
 * particle lies entirely inside it), with a cell grid for the overlap test. */
static int sc_random_count(sc *s, const sc_map *m, long *count)
{
    FLOE_TRY(sc_long(s, m, "count", 1, 0, count));
    if (*count < 1 || *count > SC_MAX_PARTICLES_PER_ENTRY)
        return sc_range(s, m, "count", "in [1, 1e8] (particles per entry)", (double)*count);
    return FLOE_OK;
}

/* radii: NULL (every particle's bounding radius is the shape's) or count drawn radii, largest
 * first (scene_psd.c): each sphere then lies inside the region and apart from the others */
static int sc_random(sc *s, const sc_map *m, sc_points *pts, const sc_common *c, const double *radii)
{
    double lo[3], hi[3];
    FLOE_TRY(sc_parse_region(s, m, lo, hi));
    long count, seed, max_tries;
    FLOE_TRY(sc_random_count(s, m, &count));
    FLOE_TRY(sc_long(s, m, "seed", 0, 1, &seed));
    FLOE_TRY(sc_long(s, m, "max_tries", 0, 100000, &max_tries));
    if (max_tries < 1 || max_tries > SC_MAX_TRIES)
        return sc_range(s, m, "max_tries", "in [1, 1e9]", (double)max_tries);
    if (max_tries < count) max_tries = count;
    double rb = c->shape.rb;
    double a0[3], a1[3];
    for (int a = 0; a < 3; a++) {
        if (a < s->dim) {
            a0[a] = lo[a] + rb;
            a1[a] = hi[a] - rb;
            if (a1[a] < a0[a])
                return sc_fail(s, FLOE_EINVAL, sc_get(m, "region", NULL),
                               "%s.region is narrower than one particle (bounding diameter %g) "
                               "along %c", m->what, 2 * rb, "xyz"[a]);
        } else {
            a0[a] = a1[a] = lo[a];
        }
    }
    /* the bounding spheres of count particles cannot fill more than the region */
    if (radii) {
        double vreg = 1, vsum = 0;
        for (int a = 0; a < s->dim; a++) vreg *= hi[a] - lo[a];
        for (long i = 0; i < count; i++)
            vsum += s->dim == 3 ? 4.0 / 3.0 * M_PI * radii[i] * radii[i] * radii[i] : M_PI * radii[i] * radii[i];
        if (vsum > SC_RANDOM_MAX_FRACTION(s->dim) * vreg)
            return sc_fail(s, FLOE_EINVAL, sc_get(m, "count", NULL),
                           "%s: %ld spheres of the radius distribution (solid %s %g) cannot be placed apart in the "
                           "region (%s %g): they would fill %.0f %% of it, more than a random close packing (%.0f %%); "
                           "enlarge region or lower count", m->what, count, s->dim == 3 ? "volume" : "area", vsum,
                           s->dim == 3 ? "volume" : "area", vreg, 100.0 * vsum / vreg,
                           100.0 * SC_RANDOM_MAX_FRACTION(s->dim));
    } else {
        double vreg = 1, vone = s->dim == 3 ? 4.0 / 3.0 * M_PI * rb * rb * rb : M_PI * rb * rb;
        for (int a = 0; a < s->dim; a++) vreg *= hi[a] - lo[a];
        if ((double)count * vone > vreg)
            return sc_fail(s, FLOE_EINVAL, sc_get(m, "count", NULL),
                           "%s: %ld particles (bounding volume %g each) cannot fit in the region "
                           "(volume %g): enlarge region or lower count", m->what, count, vone, vreg);
    }
    /* cell grid: cells at least one diameter wide, at most ~4M cells (the counts are
     * computed in double: a huge region would overflow a long) */
    double cell = 2.0 * rb;
    long nc[3];
    for (;;) {
        double total = 1, ncd[3];
        for (int a = 0; a < 3; a++) {
            ncd[a] = a < s->dim ? floor((a1[a] - a0[a]) / cell) + 1 : 1;
            total *= ncd[a];
        }
        if (total <= 4.0e6) {
            for (int a = 0; a < 3; a++) nc[a] = (long)ncd[a];
            break;
        }
        cell *= total > 1e12 ? 2.0 * cbrt(total / 4.0e6) : 1.5;
    }
    FLOE_TRY(sc_check_memory(s, sc_get(m, "count", NULL), m->what, (double)count));
    long ncells = nc[0] * nc[1] * nc[2];
    long *head = malloc((size_t)ncells * sizeof *head);
    long *next = malloc((size_t)count * sizeof *next);
    if (!head || !next) {
        free(head);
        free(next);
        return sc_fail(s, FLOE_ENOMEM, m->at, "out of memory");
    }
    for (long i = 0; i < ncells; i++) head[i] = -1;
    sc_rng rng = {(uint64_t)seed};
    long placed = 0, tries = 0, failed = 0;
    double d2min = 4.0 * rb * rb;
    while (placed < count && tries < max_tries && failed < SC_MAX_FAILED_TRIES) {
        tries++;
        failed++;
        double x[3];
        long ci[3];
        /* with radii: this sphere's room is the region less its own radius (rb is the
         * largest, the first one's) */
        const double ri = radii ? radii[placed] : rb, shrink = rb - ri;
        for (int a = 0; a < 3; a++) {
            x[a] = a < s->dim ? a0[a] - shrink + (a1[a] - a0[a] + 2.0 * shrink) * sc_rng_uniform(&rng) : a0[a];
            ci[a] = a < s->dim ? (long)floor((x[a] - a0[a]) / cell) : 0;
            if (ci[a] < 0) ci[a] = 0; /* a smaller sphere nearer the wall than rb */
            if (ci[a] >= nc[a]) ci[a] = nc[a] - 1;
        }
        int ok = 1;
        for (long dz = (s->dim == 3 ? -1 : 0); dz <= (s->dim == 3 ? 1 : 0) && ok; dz++)
            for (long dy = -1; dy <= 1 && ok; dy++)
                for (long dx = -1; dx <= 1 && ok; dx++) {
                    long cx = ci[0] + dx, cy = ci[1] + dy, cz = ci[2] + dz;
                    if (cx < 0 || cy < 0 || cz < 0 || cx >= nc[0] || cy >= nc[1] || cz >= nc[2])
                        continue;
                    for (long q = head[(cz * nc[1] + cy) * nc[0] + cx]; q >= 0 && ok; q = next[q]) {
                        double r[3];
                        floe_v3_sub(r, x, pts->x + 3 * q);
                        double dmin = radii ? ri + radii[q] : 0;
                        if (floe_v3_dot(r, r) < (radii ? dmin * dmin : d2min)) ok = 0;
                    }
                }
        if (!ok) continue;
        failed = 0;
        if (sc_points_push(pts, x)) {
            free(head);
            free(next);
            return sc_fail(s, FLOE_ENOMEM, m->at, "out of memory");
        }
        long cid = (ci[2] * nc[1] + ci[1]) * nc[0] + ci[0];
        next[placed] = head[cid];
        head[cid] = placed;
        placed++;
    }
    free(head);
    free(next);
    if (placed < count && failed >= SC_MAX_FAILED_TRIES)
        return sc_fail(s, FLOE_EINVAL, sc_get(m, "count", NULL),
                       "%s: could only place %ld of %ld particles without overlap in the region: "
                       "%ld tries in a row found no room (the region is jammed; enlarge region or "
                       "lower count)", m->what, placed, count, failed);
    if (placed < count)
        return sc_fail(s, FLOE_EINVAL, sc_get(m, "count", NULL),
                       "%s: could only place %ld of %ld particles without overlap in the region "
                       "after %ld tries (enlarge region, lower count, or raise max_tries)",
                       m->what, placed, count, max_tries);
    return FLOE_OK;
}

static const char *const sc_packings[] = {"lattice", "hexagonal", "random", NULL};
#define SC_PACKING_USER 4
/* the body keys the loader reads for every packing (a registered packing gets the rest) */
#define SC_BODY_KEYS_TEXT "packing|shape|material|velocity|angular_velocity|orientation|motion|name|grow"

/* The packing of bodies entry e: *kind 3 for a single body (no packing key), 0..2 for the
 * built-ins (sc_packings), SC_PACKING_USER for a registered one (*ent) */
static int sc_packing_of(sc *s, struct fy_node *e, const char *what, const floe_registry_entry **ent, int *kind)
{
    static const char *const none[] = {NULL};
    sc_map m = {e, e, ""};
    *ent = NULL;
    *kind = 3;
    if (!e || !fy_node_is_mapping(e)) return sc_map_open(s, e, e, what, none, &m); /* its message */
    snprintf(m.what, sizeof m.what, "%s", what);
    const char *t;
    struct fy_node *at;
    FLOE_TRY(sc_str(s, &m, "packing", 0, NULL, &t, &at));
    if (!t) return FLOE_OK;
    *ent = floe_registry_find(FLOE_KIND_PACKING, t);
    if (!*ent) {
        const char *names[64];
        int nn = 0;
        for (; nn < floe_registry_count(FLOE_KIND_PACKING) && nn < 64; nn++)
            names[nn] = floe_registry_at(FLOE_KIND_PACKING, nn)->name;
        char f[160], sug[512];
        sc_field(f, sizeof f, &m, "packing");
        sc_suggest(sug, sizeof sug, t, names, nn);
        return sc_fail(s, FLOE_EINVAL, at, "%s: unknown value '%s'%s", f, t, sug);
    }
    *kind = SC_PACKING_USER;
    for (int q = 0; sc_packings[q]; q++)
        if (!strcmp(t, sc_packings[q]) && ((*ent)->flags & FLOE_ENTRY_LOADER_PARSES)) *kind = q;
    return FLOE_OK;
}

/* A registered packing of a plugin (floe_packing_create_fn): its parameters by its schema,
 * the centres from its constructor, checked (finite, z = 0 in 2D, a sane count) */
static int sc_user_packing(sc *s, const sc_map *m, const floe_registry_entry *ent, sc_points *pts, const sc_common *c)
{
    void *params = calloc(1, ent->params_size);
    if (!params) return sc_fail(s, FLOE_ENOMEM, m->at, "out of memory");
    char label[96];
    snprintf(label, sizeof label, "packing '%s'", ent->name);
    int rc = sc_read_schema(s, m, ent, label, SC_BODY_KEYS_TEXT, params);
    double *x = NULL;
    long n = 0;
    if (!rc) {
        char err[512] = "";
        int g = ((floe_packing_create_fn)ent->create)(params, s->dim, c->shape.rb, &x, &n, err, sizeof err);
        if (g) rc = sc_fail(s, g, m->at, "%s: packing '%s': %s", m->what, ent->name, err[0] ? err : floe_strerror(g));
        else if (n < 1 || n > SC_MAX_PARTICLES_PER_ENTRY || !x)
            rc = sc_fail(s, FLOE_EINVAL, m->at, "%s: packing '%s' made %ld particles (1 to 1e8)", m->what, ent->name, n);
    }
    free(params);
    if (!rc) rc = sc_check_memory(s, m->at, m->what, (double)n);
    for (long i = 0; i < n && !rc; i++) {
        double *p = x + 3 * i;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]) || (s->dim == 2 && p[2] != 0))
            rc = sc_fail(s, FLOE_EINVAL, m->at, "%s: packing '%s': particle %ld at (%g, %g, %g) is not %s", m->what,
                         ent->name, i, p[0], p[1], p[2], s->dim == 2 ? "finite in the plane z = 0" : "finite");
        else if (sc_points_push(pts, p)) rc = sc_fail(s, FLOE_ENOMEM, m->at, "out of memory");
    }
    free(x);
    return rc;
}

int sc_parse_bodies(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys_single[] = {"shape", "material", "position", "velocity",
                                              "angular_velocity", "orientation", "motion", "name", "thickness",
                                              "grow_rate", "grow", "packing", NULL};
    static const char *const keys_lattice[] = {"packing", "shape", "material", "origin", "counts",
                                               "region", "spacing", "jitter", "seed", "velocity",
                                               "angular_velocity", "orientation", "motion", "name", "thickness",
                                               "grow", NULL};
    static const char *const keys_random[] = {"packing", "shape", "material", "region", "count",
                                              "seed", "max_tries", "velocity", "angular_velocity",
                                              "orientation", "motion", "name", "grow", "thickness",
                                              "radius_distribution", NULL};
    static const char *const keys_all[] = {"shape", "material", "position", "velocity",
                                           "angular_velocity", "orientation", "motion", "name", "thickness",
                                           "grow_rate", "grow", "packing", "origin", "counts",
                                           "region", "spacing", "jitter", "seed", "count",
                                           "max_tries", "radius_distribution", NULL};
    if (!seq || sc_is_missing(seq))
        return sc_fail(s, FLOE_EPARSE, key, "bodies must be a non-empty list of bodies or packings");
    if (!fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, seq, "bodies must be a list, got %s", sc_type_name(seq));
    int n = fy_node_sequence_item_count(seq);
    if (n == 0) return sc_fail(s, FLOE_EPARSE, key, "bodies: the list is empty");
    s->entry_first = calloc((size_t)n, sizeof *s->entry_first);
    s->entry_count = calloc((size_t)n, sizeof *s->entry_count);
    if (!s->entry_first || !s->entry_count) return sc_fail(s, FLOE_ENOMEM, key, "out of memory");
    void *it = NULL;
    struct fy_node *e;
    int entry = 0;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        char what[32];
        snprintf(what, sizeof what, "bodies[%d]", entry);
        if (fy_node_is_mapping(e) && fy_node_mapping_lookup_by_string(e, "floe_field", -1)) {
            s->entry_first[entry] = s->nparticles; /* a Voronoi floe field (scene_floes.c) */
            FLOE_TRY(sc_floe_field(s, e, entry, what));
            s->entry_count[entry] = s->nparticles - s->entry_first[entry];
            s->nbody_entries = ++entry;
            continue;
        }
        if (fy_node_is_mapping(e) && fy_node_mapping_lookup_by_string(e, "polygons_file", -1)) {
            s->entry_first[entry] = s->nparticles; /* floes from a GeoJSON file (scene_geojson.c) */
            FLOE_TRY(sc_polygons_file(s, e, entry, what));
            s->entry_count[entry] = s->nparticles - s->entry_first[entry];
            s->nbody_entries = ++entry;
            continue;
        }
        sc_map m;
        /* packing: a registered packing (floe_registry.h FLOE_KIND_PACKING); none: one body */
        const floe_registry_entry *pent = NULL;
        int packing;
        FLOE_TRY(sc_packing_of(s, e, what, &pent, &packing));
        if (packing == SC_PACKING_USER) { /* its schema checks the keys (sc_user_packing) */
            m.node = m.at = e;
            snprintf(m.what, sizeof m.what, "%s", what);
        } else
            FLOE_TRY(sc_map_open(s, e, e, what, keys_all, &m));
        const char *const *valid = packing == 3 ? keys_single
                                   : packing == 2 ? keys_random : keys_lattice;
        if (packing != SC_PACKING_USER) {
            void *it2 = NULL;
            struct fy_node_pair *p;
            while ((p = fy_node_mapping_iterate(e, &it2))) {
                const char *ks = sc_text(fy_node_pair_key(p));
                int ok = 0, nv = 0;
                for (; valid[nv]; nv++) ok |= !strcmp(ks, valid[nv]);
                if (!ok) {
                    char sug[512];
                    sc_suggest(sug, sizeof sug, ks, valid, nv);
                    return sc_fail(s, FLOE_EPARSE, fy_node_pair_key(p),
                                   "unknown key '%s' in %s (%s)%s", ks, what,
                                   packing == 3 ? "a single body" : sc_packings[packing], sug);
                }
            }
        }
        if (packing != 2 && packing != SC_PACKING_USER && sc_has(&m, "radius_distribution"))
            return sc_fail(s, FLOE_EPARSE, sc_get(&m, "radius_distribution", NULL),
                           "%s.radius_distribution is for the random packing (packing: random)", what);
        sc_common c;
        FLOE_TRY(sc_parse_common(s, &m, entry, packing != 3, &c));
        s->entry_first[entry] = s->nparticles;
        const char *bname;
        FLOE_TRY(sc_str(s, &m, "name", 0, NULL, &bname, NULL));
        if (packing == 3) {
            double x[3];
            FLOE_TRY(sc_vec(s, &m, "position", 1, NULL, x));
            FLOE_TRY(sc_check_planar(s, &m, "position", x));
            int gi, pidx;
            FLOE_TRY(sc_add_geometry(s, &c.shape, e, what, &gi));
            FLOE_TRY(sc_add_one(s, &c, gi, x, entry, e, what, &pidx));
            if (c.grow) FLOE_TRY(sc_add_growth(s, &c, pidx, e, what));
        } else {
            sc_points pts = {0};
            double *radii = NULL; /* a radius distribution's radii, largest first */
            int rc = FLOE_OK;
            if (packing == 2 && sc_has(&m, "radius_distribution")) {
                sc_psd psd;
                long count = 0;
                rc = sc_parse_psd(s, &m, &psd);
                if (!rc) rc = sc_random_count(s, &m, &count);
                if (!rc) rc = sc_check_memory(s, sc_get(&m, "count", NULL), what, (double)count);
                if (!rc && !(radii = malloc((size_t)count * sizeof *radii)))
                    rc = sc_fail(s, FLOE_ENOMEM, e, "out of memory");
                if (!rc) rc = sc_psd_draw(&psd, count, radii);
                if (!rc) c.shape.radius = c.shape.rb = radii[0];
            }
            if (!rc)
                rc = packing == SC_PACKING_USER ? sc_user_packing(s, &m, pent, &pts, &c)
                   : packing == 2 ? sc_random(s, &m, &pts, &c, radii)
                                  : sc_lattice(s, &m, packing == 1, &pts, &c);
            if (rc == FLOE_OK && c.grow && c.grow_index >= pts.n) {
                struct fy_node *gk;
                sc_get(&m, "grow", &gk);
                rc = sc_fail(s, FLOE_EINVAL, gk, "%s.grow.index %ld is out of range: the packing "
                             "has %ld particles", what, c.grow_index, pts.n);
            }
            if (rc == FLOE_OK && (double)s->nparticles + (double)pts.n > 2.0e9)
                rc = sc_fail(s, FLOE_EINVAL, e, "%s: too many particles", what);
            int gi = -1, *geo = NULL;
            long *order = NULL;
            if (rc == FLOE_OK && !radii) rc = sc_add_geometry(s, &c.shape, e, what, &gi);
            /* drawn radii: one geometry per distinct radius (the radii come sorted, largest
             * first), geo[i] point i's */
            if (rc == FLOE_OK && radii && !(geo = malloc((size_t)pts.n * sizeof *geo)))
                rc = sc_fail(s, FLOE_ENOMEM, e, "out of memory");
            for (long i = 0; radii && i < pts.n && rc == FLOE_OK; i++) {
                if (i == 0 || radii[i] != radii[i - 1]) {
                    c.shape.radius = radii[i];
                    rc = sc_add_geometry(s, &c.shape, e, what, &gi);
                }
                geo[i] = gi;
            }
            /* a random packing's particles numbered in Morton order of their centres, not
             * in the order they were placed (a random one): the contact loop then reads its
             * pairs' data from nearby memory (bench/RESULTS.md, issue 14 session 31) */
            if (rc == FLOE_OK && packing == 2) {
                double lo[3], hi[3];
                rc = sc_parse_region(s, &m, lo, hi);
                if (rc == FLOE_OK && (!(order = malloc((size_t)pts.n * sizeof *order)) ||
                                      sc_morton_order(pts.x, pts.n, 3, s->dim, lo, hi, order)))
                    rc = sc_fail(s, FLOE_ENOMEM, e, "out of memory");
            }
            /* the growing-radius state gives its particle its own geometry */
            for (long k = 0; k < pts.n && rc == FLOE_OK; k++) {
                const long i = order ? order[k] : k;
                int pidx;
                rc = sc_add_one(s, &c, radii ? geo[i] : gi, pts.x + 3 * i, entry, e, what, &pidx);
                if (rc == FLOE_OK && c.grow && k == c.grow_index)
                    rc = sc_add_growth(s, &c, pidx, e, what);
            }
            free(order);
            free(geo);
            free(pts.x);
            free(radii);
            if (rc != FLOE_OK) return rc;
        }
        s->entry_count[entry] = s->nparticles - s->entry_first[entry];
        s->nbody_entries = ++entry;
    }
    return FLOE_OK;
}
