/* scene_pd.c - scene section `peridynamics`: PD bodies, regions, holes, cracks and boundary
 * regions; the check that every pair of materials that can touch has a law. */
#include "scene_read.h"

/* ------------------------------------------------------------------------------------ */
/* Peridynamic bodies                                                                    */

/* A region or hole: shape g placed as a body is (docs/scene-format.md, "Shapes"): its centre
 * of mass at x, turned as it is written. Polytopes and compounds keep their SDF in their
 * principal frame, turned by q (sc_geom_frame) from the written coordinates: X_body =
 * R(q)^T (X - x); q is the identity for the primitives. */
typedef struct sc_pd_sdf { floe_geometry *g; double x[3]; double q[4]; } sc_pd_sdf;
static double sc_pd_region_sdf(const double X[3], void *user)
{
    const sc_pd_sdf *r = user;
    double d[3], e[3];
    floe_v3_sub(d, X, r->x);
    floe_q_rotate_inv(e, r->q, d);
    return floe_geometry_sdf(r->g, e);
}
/* the body frame of the region's shape (sc_geom_frame; the centroid offset is not used:
 * the centre of mass goes to position, as for bodies) */
static void sc_pd_frame(sc_pd_sdf *r)
{
    double fx[3];
    sc_geom_frame(r->g, fx, r->q);
}

/* Holes cut out of a PD region (`region: {..., remove: [{shape, position}, ...]}`, e.g. the
 * elliptical hole of ParticLS §5.4 eq 36): a point is kept when it is in the region and in
 * none of the holes. inner->g == NULL: the region is the lattice's box. */
#define SC_PD_MAX_HOLES 16
typedef struct sc_pd_cut { const sc_pd_sdf *inner; int n; sc_pd_sdf hole[SC_PD_MAX_HOLES]; } sc_pd_cut;
static double sc_pd_cut_sdf(const double X[3], void *user)
{
    const sc_pd_cut *c = user;
    double d = c->inner->g ? sc_pd_region_sdf(X, (void *)c->inner) : -INFINITY;
    for (int k = 0; k < c->n; k++) d = fmax(d, -sc_pd_region_sdf(X, (void *)&c->hole[k]));
    return d;
}
static void sc_pd_cut_free(sc_pd_cut *c)
{
    for (int k = 0; k < c->n; k++) floe_geometry_destroy(c->hole[k].g);
    c->n = 0;
}

/* the shape (node sv, key sk) and the position (default the origin) of map m into out; the
 * shape must be bounded ("<what>.shape: the <noun> must be bounded"); out->g is NULL on error */
static int sc_pd_shape_in(sc *s, const sc_map *m, struct fy_node *sv, struct fy_node *sk, const char *what,
                          const char *noun, sc_pd_sdf *out)
{
    char fs[96];
    snprintf(fs, sizeof fs, "%s.shape", what);
    out->g = NULL;
    FLOE_TRY(sc_build_shape(s, sv, sk, fs, 0, &out->g));
    sc_pd_frame(out);
    int rc = sc_vec(s, m, "position", 0, NULL, out->x);
    if (rc == FLOE_OK && !isfinite(floe_geometry_bounding_radius(out->g)))
        rc = sc_fail(s, FLOE_EINVAL, sv, "%s: the %s must be bounded", fs, noun);
    if (rc) { floe_geometry_destroy(out->g); out->g = NULL; }
    return rc;
}

/* {shape, position} of a region or hole (position defaults to the origin) */
static int sc_pd_shape_at(sc *s, struct fy_node *v, struct fy_node *k, const char *what, sc_pd_sdf *out)
{
    static const char *const keys[] = {"shape", "position", NULL};
    sc_map m;
    out->g = NULL;
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, what, keys, &m));
    struct fy_node *sk, *sv = sc_get(&m, "shape", &sk);
    if (!sv) return sc_fail(s, FLOE_EPARSE, v == k ? k : v, "%s.shape is required", what);
    return sc_pd_shape_in(s, &m, sv, sk, what, "shape", out);
}

/* region.remove: a list of {shape, position} holes */
static int sc_pd_parse_remove(sc *s, const sc_map *rm, const char *fr, const sc_pd_sdf *inner, sc_pd_cut *cut,
                              floe_pd_region *r)
{
    struct fy_node *k, *v = sc_get(rm, "remove", &k);
    cut->inner = inner;
    cut->n = 0;
    if (!v) return FLOE_OK;
    if (v == k || sc_is_missing(v) || !fy_node_is_sequence(v))
        return sc_fail(s, FLOE_EPARSE, v == k ? k : v, "%s.remove must be a list of {shape, position}", fr);
    void *it = NULL;
    struct fy_node *e;
    while ((e = fy_node_sequence_iterate(v, &it))) {
        char fh[96];
        snprintf(fh, sizeof fh, "%s.remove[%d]", fr, cut->n);
        if (cut->n == SC_PD_MAX_HOLES) return sc_fail(s, FLOE_EINVAL, e, "%s: at most %d holes", fh, SC_PD_MAX_HOLES);
        FLOE_TRY(sc_pd_shape_at(s, e, NULL, fh, &cut->hole[cut->n]));
        cut->n++;
    }
    r->sdf = sc_pd_cut_sdf;
    r->sdf_user = cut;
    return FLOE_OK;
}

/* peridynamics[i].boundary: regions of the body (reference positions) that are fixed, move
 * at a prescribed velocity or displacement, or carry a body force density (ParticLS eq 37),
 * each with an optional ramp {linear: T} or {exp: T}; floe_world_pd_region does the work. */
static int sc_pd_parse_boundary(sc *s, const sc_map *m, const char *what, int body)
{
    static const char *const keys[] = {"region", "fixed", "velocity", "displacement", "body_force", "ramp", "name", NULL};
    static const char *const region_keys[] = {"box", "shape", "position", NULL};
    static const char *const kinds[] = {"fixed", "velocity", "displacement", "body_force", NULL};
    struct fy_node *k, *v = sc_get(m, "boundary", &k);
    if (!v) return FLOE_OK;
    if (v == k || sc_is_missing(v) || !fy_node_is_sequence(v))
        return sc_fail(s, FLOE_EPARSE, v == k ? k : v,
                       "%s.boundary must be a list of {region, fixed | velocity | displacement | body_force}", what);
    void *it = NULL;
    struct fy_node *e;
    int idx = 0;
    while ((e = fy_node_sequence_iterate(v, &it))) {
        char fb[96];
        snprintf(fb, sizeof fb, "%s.boundary[%d]", what, idx);
        sc_map bm;
        FLOE_TRY(sc_map_open(s, e, e, fb, keys, &bm));
        floe_pd_bc bc = floe_default_pd_bc();
        /* exactly one kind */
        int nk = 0;
        for (int q = 0; kinds[q]; q++)
            if (sc_has(&bm, kinds[q])) { bc.kind = FLOE_PD_BC_FIXED + q; nk++; }
        if (nk != 1)
            return sc_fail(s, FLOE_EINVAL, e, "%s: give exactly one of fixed: true, velocity, displacement, body_force "
                           "(got %d)", fb, nk);
        if (bc.kind == FLOE_PD_BC_FIXED) {
            int fixed;
            FLOE_TRY(sc_bool(s, &bm, "fixed", 1, &fixed));
            if (!fixed) return sc_fail(s, FLOE_EINVAL, e, "%s: fixed: false selects nothing to do (leave the entry out)", fb);
        } else {
            FLOE_TRY(sc_vec(s, &bm, kinds[bc.kind - 1], 1, NULL, bc.value));
            FLOE_TRY(sc_check_planar(s, &bm, kinds[bc.kind - 1], bc.value));
        }
        /* ramp: {linear: T} or {exp: T} */
        struct fy_node *rk, *rv = sc_get(&bm, "ramp", &rk);
        if (rv) {
            static const char *const ramp_keys[] = {"linear", "exp", NULL};
            char fr[112];
            snprintf(fr, sizeof fr, "%s.ramp", fb);
            sc_map rm;
            FLOE_TRY(sc_map_open(s, rv == rk ? NULL : rv, rk, fr, ramp_keys, &rm));
            int lin = sc_has(&rm, "linear"), ex = sc_has(&rm, "exp");
            if (lin + ex != 1) return sc_fail(s, FLOE_EINVAL, rv, "%s: give one of {linear: T} or {exp: T} (s)", fr);
            bc.ramp = lin ? FLOE_PD_RAMP_LINEAR : FLOE_PD_RAMP_EXP;
            FLOE_TRY(sc_num(s, &rm, lin ? "linear" : "exp", 1, 0, &bc.ramp_time));
            if (!(bc.ramp_time > 0)) return sc_range(s, &rm, lin ? "linear" : "exp", "> 0 (s)", bc.ramp_time);
            if (bc.kind == FLOE_PD_BC_FIXED) return sc_fail(s, FLOE_EINVAL, rv, "%s: a fixed region has no ramp", fr);
        } else if (bc.kind == FLOE_PD_BC_DISPLACEMENT)
            return sc_fail(s, FLOE_EINVAL, e, "%s: a displacement needs a ramp ({linear: T} or {exp: T}) over which "
                           "it is applied", fb);
        /* region: a box or a shape at a position, in reference coordinates */
        struct fy_node *gk, *gv = sc_get(&bm, "region", &gk);
        if (!gv) return sc_fail(s, FLOE_EPARSE, e, "%s.region is required ({box: {min, max}} or {shape, position})", fb);
        char fg[112];
        snprintf(fg, sizeof fg, "%s.region", fb);
        sc_map gm;
        FLOE_TRY(sc_map_open(s, gv == gk ? NULL : gv, gk, fg, region_keys, &gm));
        sc_pd_sdf reg = {NULL, {0, 0, 0}, {1, 0, 0, 0}};
        struct fy_node *xk, *xv = sc_get(&gm, "box", &xk);
        if (xv) {
            static const char *const box_keys[] = {"min", "max", NULL};
            char fx[128];
            snprintf(fx, sizeof fx, "%s.box", fg);
            sc_map xm;
            FLOE_TRY(sc_map_open(s, xv == xk ? NULL : xv, xk, fx, box_keys, &xm));
            FLOE_TRY(sc_vec(s, &xm, "min", 1, NULL, bc.lo));
            FLOE_TRY(sc_vec(s, &xm, "max", 1, NULL, bc.hi));
            for (int q = 0; q < s->dim; q++)
                if (!(bc.lo[q] <= bc.hi[q])) return sc_fail(s, FLOE_EINVAL, xv, "%s: min must be <= max on every axis", fx);
            if (s->dim == 2) { bc.lo[2] = -INFINITY; bc.hi[2] = INFINITY; }
        } else {
            if (!sc_has(&gm, "shape")) return sc_fail(s, FLOE_EPARSE, gv, "%s: give box or shape", fg);
            FLOE_TRY(sc_pd_shape_at(s, gv, gk, fg, &reg));
            bc.sdf = sc_pd_region_sdf;
            bc.sdf_user = &reg;
        }
        int n = floe_world_pd_region(s->w, body, &bc);
        floe_geometry_destroy(reg.g);
        if (n <= 0) return sc_fail(s, -n, e, "%s: %s", fb, floe_world_last_error(s->w));
        idx++;
    }
    return FLOE_OK;
}

/* peridynamics[i].cracks: pre-cracks that remove the bonds crossing them (floe_pd_add_crack):
 * {points: [[x, y], ...]} a polyline in 2D, a convex planar polygon in 3D;
 * {rectangle: {corner | center, edges: [e1, e2]}} in 3D. */
static int sc_pd_parse_cracks(sc *s, const sc_map *m, const char *what, floe_pd_body *b)
{
    static const char *const keys[] = {"points", "rectangle", "name", NULL};
    static const char *const rect_keys[] = {"corner", "center", "edges", NULL};
    struct fy_node *k, *v = sc_get(m, "cracks", &k);
    if (!v) return FLOE_OK;
    if (v == k || sc_is_missing(v) || !fy_node_is_sequence(v))
        return sc_fail(s, FLOE_EPARSE, v == k ? k : v, "%s.cracks must be a list of {points} or {rectangle}", what);
    void *it = NULL;
    struct fy_node *e;
    int idx = 0;
    while ((e = fy_node_sequence_iterate(v, &it))) {
        char fc[96];
        snprintf(fc, sizeof fc, "%s.cracks[%d]", what, idx);
        sc_map cm;
        FLOE_TRY(sc_map_open(s, e, e, fc, keys, &cm));
        floe_pd_crack c;
        memset(&c, 0, sizeof c);
        struct fy_node *pk, *pv = sc_get(&cm, "points", &pk), *rk, *rv = sc_get(&cm, "rectangle", &rk);
        if (!pv == !rv)
            return sc_fail(s, FLOE_EPARSE, e, "%s: give points (%s) or rectangle ({corner | center, edges: [e1, e2]}, 3D)",
                           fc, s->dim == 2 ? "a polyline [[x, y], ...]" : "a convex planar polygon [[x, y, z], ...]");
        if (pv) {
            char fp[112];
            snprintf(fp, sizeof fp, "%s.points", fc);
            if (pv == pk || !fy_node_is_sequence(pv))
                return sc_fail(s, FLOE_EPARSE, pv == pk ? pk : pv, "%s must be a list of points", fp);
            int cnt = fy_node_sequence_item_count(pv);
            if (cnt < s->dim || cnt > FLOE_PD_CRACK_MAX_POINTS)
                return sc_fail(s, FLOE_EINVAL, pv, "%s: give %d to %d points (got %d)", fp, s->dim,
                               FLOE_PD_CRACK_MAX_POINTS, cnt);
            for (int q = 0; q < cnt; q++) {
                char f2[128];
                snprintf(f2, sizeof f2, "%s[%d]", fp, q);
                int got;
                FLOE_TRY(sc_node_list(s, fy_node_sequence_get_by_index(pv, q), NULL, f2, 3, s->dim == 2 ? 2 : 0,
                                      c.p[q], &got));
            }
            c.n = cnt;
        } else {
            char fr[112];
            snprintf(fr, sizeof fr, "%s.rectangle", fc);
            if (s->dim != 3) return sc_fail(s, FLOE_EINVAL, rv, "%s: a rectangle is a 3D crack (2D: points)", fr);
            sc_map rm;
            FLOE_TRY(sc_map_open(s, rv == rk ? NULL : rv, rk, fr, rect_keys, &rm));
            int hc = sc_has(&rm, "corner"), hm = sc_has(&rm, "center");
            if (hc == hm) return sc_fail(s, FLOE_EPARSE, rv, "%s: give corner or center", fr);
            double o[3], ed[2][3];
            FLOE_TRY(sc_vec(s, &rm, hc ? "corner" : "center", 1, NULL, o));
            struct fy_node *ek, *ev = sc_get(&rm, "edges", &ek);
            char fe[128];
            snprintf(fe, sizeof fe, "%s.edges", fr);
            if (!ev || ev == ek || !fy_node_is_sequence(ev) || fy_node_sequence_item_count(ev) != 2)
                return sc_fail(s, FLOE_EPARSE, ev && ev != ek ? ev : rv, "%s: give two edge vectors [e1, e2]", fe);
            for (int q = 0; q < 2; q++) {
                char f2[144];
                snprintf(f2, sizeof f2, "%s[%d]", fe, q);
                int got;
                FLOE_TRY(sc_node_list(s, fy_node_sequence_get_by_index(ev, q), NULL, f2, 3, 0, ed[q], &got));
            }
            if (hm)
                for (int d = 0; d < 3; d++) o[d] -= 0.5 * (ed[0][d] + ed[1][d]);
            c = floe_pd_crack_rectangle(o, ed[0], ed[1]);
        }
        if (floe_pd_crack_check(&c, s->dim) != FLOE_OK)
            return sc_fail(s, FLOE_EINVAL, e, "%s: %s", fc,
                           s->dim == 2 ? "the points must be finite and consecutive points distinct"
                                       : "not a convex planar polygon of non-zero area (vertices in order around it)");
        int64_t n = floe_pd_add_crack(b, &c);
        if (n < 0) return sc_fail(s, (int)-n, e, "%s: %s", fc, floe_strerror((int)-n));
        idx++;
    }
    return FLOE_OK;
}

/* region.remove holes narrower than the horizon: bonds that bridge them (floe_pd_bonds_across)
 * are counted on the body (nbridge, bridge_at) for the summary's warning */
static int sc_pd_check_holes(sc *s, const sc_pd_cut *cut, struct fy_node *at, const char *fr, floe_pd_body *b)
{
    for (int k = 0; k < cut->n; k++) {
        double where[3];
        int64_t n = floe_pd_bonds_across(b, sc_pd_region_sdf, (void *)&cut->hole[k], where);
        if (n < 0) return sc_fail(s, (int)-n, at, "%s.remove[%d]: %s", fr, k, floe_strerror((int)-n));
        if (n > 0 && b->nbridge == 0) floe_v3_copy(b->bridge_at, where);
        b->nbridge += n;
    }
    return FLOE_OK;
}

/* peridynamics[i].material: {model: NAME, <its parameters>}, NAME a registered PD material
 * (floe_registry.h FLOE_KIND_PD_MATERIAL: pmb, lps, or a plugin's), its parameters read by
 * its schema and turned into *pm by its constructor */
static int sc_pd_material(sc *s, struct fy_node *mv, struct fy_node *mk, const char *fm, floe_pd_material *pm)
{
    static const char *const no_keys[] = {NULL};
    sc_map mm;
    const char *mname;
    struct fy_node *mat;
    memset(pm, 0, sizeof *pm);
    if (!mv || !fy_node_is_mapping(mv)) return sc_map_open(s, mv, mk, fm, no_keys, &mm); /* its message */
    mm.node = mv;
    mm.at = mv;
    snprintf(mm.what, sizeof mm.what, "%s", fm);
    FLOE_TRY(sc_str(s, &mm, "model", 1, NULL, &mname, &mat));
    const floe_registry_entry *ent = floe_registry_find(FLOE_KIND_PD_MATERIAL, mname);
    if (!ent) {
        const char *names[64];
        int nn = 0;
        for (; nn < floe_registry_count(FLOE_KIND_PD_MATERIAL) && nn < 64; nn++)
            names[nn] = floe_registry_at(FLOE_KIND_PD_MATERIAL, nn)->name;
        char sug[512];
        sc_suggest(sug, sizeof sug, mname, names, nn);
        return sc_fail(s, FLOE_EINVAL, mat, "%s.model: unknown value '%s'%s", fm, mname, sug);
    }
    /* a key of another material: say whose it is */
    void *it = NULL;
    struct fy_node_pair *pr;
    while ((pr = fy_node_mapping_iterate(mv, &it))) {
        const char *ks = sc_text(fy_node_pair_key(pr));
        if (!ks || !strcmp(ks, "model") || floe_schema_index(ent, ks) >= 0) continue;
        for (int q = 0; q < floe_registry_count(FLOE_KIND_PD_MATERIAL); q++) {
            const floe_registry_entry *o = floe_registry_at(FLOE_KIND_PD_MATERIAL, q);
            if (o != ent && floe_schema_index(o, ks) >= 0)
                return sc_fail(s, FLOE_EINVAL, fy_node_pair_key(pr), "%s: %s is a %s option, not one of %s's (floe help "
                               "pd_material %s lists the %s options)", fm, ks, o->name, ent->name, o->name, o->name);
        }
    }
    void *params = calloc(1, ent->params_size);
    if (!params) return sc_fail(s, FLOE_ENOMEM, mv, "out of memory");
    char label[96];
    snprintf(label, sizeof label, "pd_material '%s'", ent->name);
    int rc = sc_read_schema(s, &mm, ent, label, "model", params);
    if (!rc) {
        char err[512] = "";
        int c = ((floe_pd_material_create_fn)ent->create)(params, s->dim, pm, err, sizeof err);
        if (c) rc = sc_fail(s, c, mv, "%s: %s", fm, err[0] ? err : "invalid values");
    }
    free(params);
    return rc;
}

int sc_parse_pd(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys[] = {"region", "spacing", "horizon", "material", "contact_material", "velocity",
                                       "surface_correction", "thickness", "name", "boundary", "lattice", "cracks",
                                       NULL};
    static const char *const region_keys[] = {"box", "shape", "position", "remove", NULL};
    if (!seq) return FLOE_OK;
    if (sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, sc_is_missing(seq) ? key : seq,
                       "peridynamics must be a list of {region, spacing, material, contact_material}");
    void *it = NULL;
    struct fy_node *e;
    int idx = 0;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        char what[48];
        snprintf(what, sizeof what, "peridynamics[%d]", idx);
        sc_map m;
        FLOE_TRY(sc_map_open(s, e, e, what, keys, &m));
        floe_pd_region r;
        memset(&r, 0, sizeof r);
        r.dim = s->dim;
        FLOE_TRY(sc_pos_num(s, &m, "spacing", &r.dx));
        FLOE_TRY(sc_num(s, &m, "horizon", 0, 3.0, &r.horizon_factor));
        if (!(r.horizon_factor >= 1 && r.horizon_factor <= 10))
            return sc_range(s, &m, "horizon", "in [1, 10] (the horizon in lattice spacings)", r.horizon_factor);
        /* lattice: cubic (square in 2D, the default) or hexagonal (2D triangular, 3D HCP);
         * the order of the names is FLOE_PD_LATTICE_CUBIC, FLOE_PD_LATTICE_HEXAGONAL */
        static const char *const lattices[] = {"cubic", "hexagonal", NULL};
        FLOE_TRY(sc_enum(s, &m, "lattice", lattices, FLOE_PD_LATTICE_CUBIC, &r.lattice));
        if (s->dim == 2) FLOE_TRY(sc_num(s, &m, "thickness", 0, r.dx, &r.thickness));
        /* region: a box, or any shape placed at a position (its SDF selects the points) */
        struct fy_node *rk, *rv = sc_get(&m, "region", &rk);
        if (!rv) return sc_fail(s, FLOE_EPARSE, e, "%s.region is required ({box: {min, max}} or {shape, position})", what);
        char fr[64];
        snprintf(fr, sizeof fr, "%s.region", what);
        sc_map rm;
        FLOE_TRY(sc_map_open(s, rv == rk ? NULL : rv, rk, fr, region_keys, &rm));
        sc_pd_sdf reg = {NULL, {0, 0, 0}, {1, 0, 0, 0}};
        struct fy_node *bk, *bv = sc_get(&rm, "box", &bk);
        if (bv) {
            static const char *const box_keys[] = {"min", "max", NULL};
            char fb[80];
            snprintf(fb, sizeof fb, "%s.box", fr);
            sc_map bm;
            FLOE_TRY(sc_map_open(s, bv == bk ? NULL : bv, bk, fb, box_keys, &bm));
            FLOE_TRY(sc_vec(s, &bm, "min", 1, NULL, r.lo));
            FLOE_TRY(sc_vec(s, &bm, "max", 1, NULL, r.hi));
            if (s->dim == 2) r.hi[2] = r.lo[2] = 0;
            for (int k = 0; k < s->dim; k++)
                if (!(r.hi[k] - r.lo[k] >= r.dx))
                    return sc_fail(s, FLOE_EINVAL, bv, "%s: max - min must be at least one spacing on every axis", fb);
            if (s->dim == 2) { r.lo[2] = -0.5 * r.dx; r.hi[2] = 0.5 * r.dx; }
        } else {
            struct fy_node *sk2, *sv2 = sc_get(&rm, "shape", &sk2);
            if (!sv2) return sc_fail(s, FLOE_EPARSE, rv, "%s: give box or shape", fr);
            FLOE_TRY(sc_pd_shape_in(s, &rm, sv2, sk2, fr, "region", &reg));
            double rb = floe_geometry_bounding_radius(reg.g);
            for (int k = 0; k < 3; k++) { r.lo[k] = reg.x[k] - rb; r.hi[k] = reg.x[k] + rb; }
            if (s->dim == 2) { r.lo[2] = -0.5 * r.dx; r.hi[2] = 0.5 * r.dx; }
            r.sdf = sc_pd_region_sdf;
            r.sdf_user = &reg;
        }
        /* material */
        struct fy_node *mk, *mv = sc_get(&m, "material", &mk);
        if (!mv) {
            floe_geometry_destroy(reg.g);
            return sc_fail(s, FLOE_EPARSE, e, "%s.material is required ({model: pmb | lps, density, ...})", what);
        }
        char fm[64];
        snprintf(fm, sizeof fm, "%s.material", what);
        floe_pd_material pm;
        int rc = sc_pd_material(s, mv == mk ? NULL : mv, mk, fm, &pm);
        floe_pd_body *b = NULL;
        sc_pd_cut cut = {NULL, 0, {{NULL, {0, 0, 0}, {1, 0, 0, 0}}}};
        if (!rc) rc = sc_pd_parse_remove(s, &rm, fr, &reg, &cut, &r);
        if (!rc) { /* the box's lattice points and their bonds bound what the body needs */
            double pts = 1, mh = r.horizon_factor > 0 ? r.horizon_factor : 3;
            for (int a = 0; a < s->dim; a++) pts *= floor((r.hi[a] - r.lo[a]) / r.dx) + 1;
            double bonds = pts * (s->dim == 3 ? 4.0 / 3.0 * M_PI * mh * mh * mh : M_PI * mh * mh);
            double need = sc_mem_estimate(s, pts) + bonds * SC_BYTES_PER_BOND, have = sc_phys_mem();
            if (!(need <= have))
                rc = sc_fail(s, FLOE_ENOMEM, rv, "%s: up to %.4g points and %.4g bonds at spacing %g: the scene would "
                             "need about %.3g GB (estimate), more than this machine's memory (%.3g GB)", fr, pts, bonds,
                             r.dx, need / 1e9, have / 1e9);
        }
        if (!rc) {
            int c = floe_pd_body_create(&b, &r);
            if (c) rc = sc_fail(s, c, rv, "%s: could not discretise the region (%s)", fr, floe_strerror(c));
            else if (b->n < 2) rc = sc_fail(s, FLOE_EINVAL, rv, "%s: the region holds %d lattice points at spacing %g", fr, b->n, r.dx);
        }
        if (!rc) rc = sc_pd_parse_cracks(s, &m, what, b);
        if (!rc) rc = sc_pd_check_holes(s, &cut, rv, fr, b);
        floe_geometry_destroy(reg.g);
        sc_pd_cut_free(&cut);
        if (!rc) {
            int c = floe_pd_set_material(b, &pm);
            if (c) rc = sc_fail(s, c, mv, "%s: %s", fm, c == FLOE_ENOTSUP ? "not available in this dimension" : "invalid values");
        }
        /* a user material without a surface correction goes without one unless asked */
        int corr = 1, corr_def = pm.model != FLOE_PD_USER || (pm.ops && pm.ops->surface_correction);
        if (!rc) rc = sc_bool(s, &m, "surface_correction", corr_def, &corr);
        if (!rc && corr) {
            int c = floe_pd_surface_correction(b);
            if (c) rc = sc_fail(s, c, e, "%s: surface correction failed", what);
        }
        const char *cname;
        struct fy_node *cat;
        int cmat = -1;
        double v0[3];
        if (!rc) rc = sc_str(s, &m, "contact_material", 1, NULL, &cname, &cat);
        if (!rc) {
            char fc[80];
            snprintf(fc, sizeof fc, "%s.contact_material", what);
            rc = sc_material_ref(s, cname, cat, fc, &cmat);
        }
        if (!rc) rc = sc_vec(s, &m, "velocity", 0, NULL, v0);
        if (rc) { floe_pd_body_destroy(b); return rc; }
        int n = b->n, first;
        rc = floe_world_add_pd_body(s->w, b, cmat, v0, &first); /* owns b */
        if (rc) return sc_fail(s, rc, e, "%s: %s", what, floe_world_last_error(s->w));
        FLOE_TRY(sc_pd_parse_boundary(s, &m, what, floe_world_pd_body_count(s->w) - 1));
        sc_mat *mt = &s->mats[cmat];
        if (!mt->body_user) { mt->body_user = cat; mt->body_entry = idx; }
        mt->nbody += n;
        mt->nfree = 1;
        s->nparticles += n;
        s->nspheres += n; /* its points touch as spheres of the contact radius */
        idx++;
    }
    return FLOE_OK;
}

/* Every pair of materials that can meet needs a law: two particles of the material (a = b)
 * or one of each, at least one of them free. Walls count as non-free particles. */
int sc_check_pairs(sc *s)
{
    for (int a = 0; a < s->nmats; a++)
        for (int b = a; b < s->nmats; b++) {
            const sc_mat *A = &s->mats[a], *B = &s->mats[b];
            if (s->law_at && s->law_at[a * s->nmats + b]) continue;
            int na = A->nbody + A->nwall, nb = B->nbody + B->nwall;
            int meet = a == b ? na >= 2 && A->nfree : na && nb && (A->nfree || B->nfree);
            if (!meet) continue;
            /* name a user of each (a body before a wall), point at the later one */
            struct fy_node *ua = A->body_user ? A->body_user : A->wall_user;
            struct fy_node *ub = B->body_user ? B->body_user : B->wall_user;
            char users[128];
            char sa[32], sb[32];
            if (A->body_user) snprintf(sa, sizeof sa, "bodies[%d]", A->body_entry);
            else snprintf(sa, sizeof sa, "walls[%d]", A->wall_entry);
            if (B->body_user) snprintf(sb, sizeof sb, "bodies[%d]", B->body_entry);
            else snprintf(sb, sizeof sb, "walls[%d]", B->wall_entry);
            if (a == b && A->body_user && A->wall_user && A->nbody == 1) {
                snprintf(sb, sizeof sb, "walls[%d]", A->wall_entry);
                ub = A->wall_user;
            }
            if (!strcmp(sa, sb)) snprintf(users, sizeof users, "%s", sa);
            else snprintf(users, sizeof users, "%s and %s", sa, sb);
            struct fy_node *at = sc_line(s, ub) > sc_line(s, ua) ? ub : ua;
            return sc_fail(s, FLOE_EINVAL, at,
                           "no contact law for materials (%s, %s), used by %s: add "
                           "{materials: [%s, %s], model: ...} to laws",
                           A->m.name, B->m.name, users, A->m.name, B->m.name);
        }
    return FLOE_OK;
}
