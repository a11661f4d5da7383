/* scene_materials.c - scene sections `materials`, `laws` (registered laws, read by their
 * schemas) and `walls`. */
#include "scene_read.h"

/* ------------------------------------------------------------------------------------ */
/* Materials and laws                                                                    */

static int sc_find_material(const sc *s, const char *name)
{
    for (int i = 0; i < s->nmats; i++)
        if (!strcmp(s->mats[i].m.name, name)) return i;
    return -1;
}

int sc_material_ref(sc *s, const char *name, struct fy_node *at, const char *field, int *out)
{
    int i = sc_find_material(s, name);
    if (i >= 0) { *out = i; return FLOE_OK; }
    const char *names[256];
    int n = s->nmats < 256 ? s->nmats : 256;
    for (int j = 0; j < n; j++) names[j] = s->mats[j].m.name;
    char sug[512] = "";
    if (n) sc_suggest(sug, sizeof sug, name, names, n);
    else snprintf(sug, sizeof sug, " (no materials are defined)");
    return sc_fail(s, FLOE_EINVAL, at, "%s: unknown material '%s'%s", field, name, sug);
}

int sc_parse_materials(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys[] = {"name", "density", "young", "poisson", NULL};
    if (!seq || sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, seq && !sc_is_missing(seq) ? seq : key,
                       "materials must be a list of {name, density, young, poisson}");
    int n = fy_node_sequence_item_count(seq);
    if (n == 0) return sc_fail(s, FLOE_EPARSE, key, "materials: the list is empty");
    s->mats = calloc((size_t)n, sizeof *s->mats);
    if (!s->mats) return sc_fail(s, FLOE_ENOMEM, key, "out of memory");
    void *it = NULL;
    struct fy_node *e;
    int i = 0;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        char what[32];
        snprintf(what, sizeof what, "materials[%d]", i);
        sc_map m;
        FLOE_TRY(sc_map_open(s, e, e, what, keys, &m));
        sc_mat *mt = &s->mats[i];
        const char *name;
        struct fy_node *nat;
        FLOE_TRY(sc_str(s, &m, "name", 1, NULL, &name, &nat));
        if (strlen(name) >= sizeof mt->m.name)
            return sc_fail(s, FLOE_EINVAL, nat, "%s.name is too long (max %d characters)", what,
                           (int)sizeof mt->m.name - 1);
        int dup = sc_find_material(s, name);
        if (dup >= 0)
            return sc_fail(s, FLOE_EINVAL, nat, "%s.name: material '%s' is already defined at line %d",
                           what, name, sc_line(s, s->mats[dup].at));
        snprintf(mt->m.name, sizeof mt->m.name, "%s", name);
        mt->at = e;
        mt->body_entry = mt->wall_entry = -1;
        FLOE_TRY(sc_num(s, &m, "density", 1, 0, &mt->m.density));
        if (!(mt->m.density > 0)) return sc_range(s, &m, "density", "> 0 (kg/m^3)", mt->m.density);
        mt->has_young = sc_has(&m, "young");
        mt->has_poisson = sc_has(&m, "poisson");
        FLOE_TRY(sc_num(s, &m, "young", 0, 0.0, &mt->m.young));
        if (mt->has_young && !(mt->m.young > 0))
            return sc_range(s, &m, "young", "> 0 (Pa)", mt->m.young);
        FLOE_TRY(sc_num(s, &m, "poisson", 0, 0.3, &mt->m.poisson));
        if (!(mt->m.poisson > -1.0 && mt->m.poisson < 0.5))
            return sc_range(s, &m, "poisson", "in (-1, 0.5)", mt->m.poisson);
        s->nmats = ++i;
    }
    return FLOE_OK;
}

/* The names of the registered laws (for the `model` key's suggestions). */
static int sc_law_names(const char **names, int max)
{
    int n = 0;
    for (int k = 0; k < floe_registry_count(FLOE_KIND_LAW) && n < max; k++)
        names[n++] = floe_registry_at(FLOE_KIND_LAW, k)->name;
    return n;
}

/* One part of a composed law: KEY: {model: NAME, <its parameters>} of kind `kind`. */
static int sc_read_part(sc *s, const sc_map *m, const char *key, const char *kind, const floe_registry_entry **ent,
                        void **params)
{
    struct fy_node *k, *v = sc_get(m, key, &k);
    *ent = NULL;
    *params = NULL;
    if (!v) return FLOE_OK;
    char f[160];
    sc_field(f, sizeof f, m, key);
    if (v == k || sc_is_missing(v) || !fy_node_is_mapping(v))
        return sc_fail(s, FLOE_EPARSE, v == k || sc_is_missing(v) ? k : v,
                       "%s must be a mapping ({model: NAME, ...}; floe help %s lists the models), got %s", f, kind,
                       v == k || sc_is_missing(v) ? "nothing" : sc_type_name(v));
    sc_map pm = {v, v, ""};
    snprintf(pm.what, sizeof pm.what, "%s", f);
    const char *model;
    struct fy_node *at;
    FLOE_TRY(sc_str(s, &pm, "model", 1, NULL, &model, &at));
    const floe_registry_entry *e = floe_registry_find(kind, model);
    if (!e) {
        const char *names[128];
        int n = 0;
        for (int q = 0; q < floe_registry_count(kind) && n < 128; q++) names[n++] = floe_registry_at(kind, q)->name;
        char sug[1024];
        sc_suggest(sug, sizeof sug, model, names, n);
        return sc_fail(s, FLOE_EINVAL, at, "%s.model: unknown %s part '%s'%s", f, kind, model, sug);
    }
    *params = calloc(1, e->params_size ? e->params_size : 1);
    if (!*params) return sc_fail(s, FLOE_ENOMEM, v, "out of memory");
    *ent = e;
    char label[96];
    snprintf(label, sizeof label, "%s model '%s'", kind, e->name);
    return sc_read_schema(s, &pm, e, label, "model", *params);
}

/* Create the law of entry L (a registered law, or a composed one); NULL with err. */
static floe_contact_law *sc_law_create(const sc *s, const sc_law *L, char *err, size_t errlen)
{
    const floe_material *ma = &s->mats[L->a].m, *mb = &s->mats[L->b].m;
    if (!L->composed) return ((floe_law_create_fn)L->ent->create)(L->params, ma, mb, err, errlen);
    floe_normal_part *np = ((floe_normal_create_fn)L->ent->create)(L->params, ma, mb, err, errlen);
    if (!np) return NULL;
    floe_tangential_part *tp = NULL;
    if (L->ent_t) {
        tp = ((floe_tangential_create_fn)L->ent_t->create)(L->params_t, ma, mb, err, errlen);
        if (!tp) { floe_normal_part_destroy(np); return NULL; }
    }
    floe_contact_law *law = floe_composed_law_create(np, tp);
    if (!law) snprintf(err, errlen, "out of memory");
    return law;
}

int sc_parse_laws(sc *s, struct fy_node *seq, struct fy_node *key)
{
    if (!seq) return FLOE_OK;
    if (sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, sc_is_missing(seq) ? key : seq,
                       "laws must be a list of {materials: [a, b], model: ..., ...}");
    int n = fy_node_sequence_item_count(seq);
    s->laws = calloc((size_t)(n ? n : 1), sizeof *s->laws);
    s->law_at = calloc((size_t)s->nmats * (size_t)s->nmats, sizeof *s->law_at);
    if (!s->laws || !s->law_at) return sc_fail(s, FLOE_ENOMEM, key, "out of memory");
    void *it = NULL;
    struct fy_node *e;
    int i = 0;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        char what[32];
        snprintf(what, sizeof what, "laws[%d]", i);
        sc_map m = {e, e, ""};
        snprintf(m.what, sizeof m.what, "%s", what);
        if (!fy_node_is_mapping(e))
            return sc_fail(s, FLOE_EPARSE, e, "%s must be a mapping ({materials: [a, b], model: ..., ...}), got %s",
                           what, sc_is_missing(e) ? "nothing" : sc_type_name(e));
        /* model: the name of a registered law, or normal: + tangential: parts */
        const int composed = !sc_has(&m, "model") && (sc_has(&m, "normal") || sc_has(&m, "tangential"));
        if (!composed && !sc_has(&m, "model"))
            return sc_fail(s, FLOE_EPARSE, e,
                           "%s: give model: NAME (floe help law) or normal: {model: NAME, ...} with an optional "
                           "tangential: {model: NAME, ...} (floe help normal, floe help tangential)", what);
        if (composed) {
            static const char *const ckeys[] = {"materials", "normal", "tangential", NULL};
            FLOE_TRY(sc_map_open(s, e, e, what, ckeys, &m));
            if (!sc_has(&m, "normal"))
                return sc_fail(s, FLOE_EPARSE, e, "%s: a tangential part needs a normal part (normal: {model: "
                                                  "NAME, ...}; floe help normal)", what);
        }
        const char *model = NULL;
        struct fy_node *mat = NULL;
        if (!composed) FLOE_TRY(sc_str(s, &m, "model", 1, NULL, &model, &mat));
        const floe_registry_entry *ent = composed ? NULL : floe_registry_find(FLOE_KIND_LAW, model);
        if (!composed && !ent) {
            const char *names[128];
            char sug[1024];
            sc_suggest(sug, sizeof sug, model, names, sc_law_names(names, 128));
            return sc_fail(s, FLOE_EINVAL, mat, "%s.model: unknown value '%s'%s", what, model, sug);
        }
        sc_law *L = &s->laws[i];
        L->node = e;
        s->nlaws = i + 1; /* freed with the loader from here on */
        if (composed) {
            L->composed = 1;
            FLOE_TRY(sc_read_part(s, &m, "normal", FLOE_KIND_NORMAL, &L->ent, &L->params));
            FLOE_TRY(sc_read_part(s, &m, "tangential", FLOE_KIND_TANGENTIAL, &L->ent_t, &L->params_t));
            ent = L->ent;
        } else {
            L->ent = ent;
            L->params = calloc(1, ent->params_size);
            if (!L->params) return sc_fail(s, FLOE_ENOMEM, e, "out of memory");
        }
        /* materials: [a, b] */
        struct fy_node *mk;
        struct fy_node *mv = sc_get(&m, "materials", &mk);
        if (!mv) return sc_fail(s, FLOE_EPARSE, e, "%s.materials is required ([a, b])", what);
        if (mv == mk || !fy_node_is_sequence(mv) || fy_node_sequence_item_count(mv) != 2)
        {
            char got[48];
            if (mv != mk && fy_node_is_sequence(mv))
                snprintf(got, sizeof got, "%d", fy_node_sequence_item_count(mv));
            else
                snprintf(got, sizeof got, "%s", mv == mk ? "nothing" : sc_type_name(mv));
            return sc_fail(s, FLOE_EPARSE, mv == mk ? mk : mv,
                           "%s.materials: expected a list of 2 material names, got %s", what, got);
        }
        int ab[2];
        for (int j = 0; j < 2; j++) {
            struct fy_node *c = fy_node_sequence_get_by_index(mv, j);
            const char *nm = sc_text(c);
            char f[64];
            snprintf(f, sizeof f, "%s.materials[%d]", what, j);
            if (!nm || sc_is_missing(c))
                return sc_fail(s, FLOE_EPARSE, c ? c : mv, "%s: expected a material name", f);
            FLOE_TRY(sc_material_ref(s, nm, c, f, &ab[j]));
        }
        L->a = ab[0];
        L->b = ab[1];
        struct fy_node **slot = &s->law_at[L->a * s->nmats + L->b];
        if (*slot)
            return sc_fail(s, FLOE_EINVAL, mv,
                           "%s: a law for materials (%s, %s) is already given at line %d", what,
                           s->mats[L->a].m.name, s->mats[L->b].m.name, sc_line(s, *slot));
        *slot = mv;
        s->law_at[L->b * s->nmats + L->a] = mv;
        char label[96];
        snprintf(label, sizeof label, "model '%s'", ent->name);
        if (!composed) FLOE_TRY(sc_read_schema(s, &m, ent, label, "materials|model", L->params));
        if ((ent->flags | (L->ent_t ? L->ent_t->flags : 0)) & FLOE_LAW_NEEDS_YOUNG)
            for (int j = 0; j < 2; j++) {
                const sc_mat *mt = &s->mats[ab[j]];
                if (!mt->has_young)
                    return sc_fail(s, FLOE_EINVAL, mt->at,
                                   "material '%s' needs young (Pa): the %s law %s "
                                   "(line %d) uses it", mt->m.name,
                                   (ent->flags & FLOE_LAW_NEEDS_YOUNG) || !L->ent_t ? ent->name : L->ent_t->name,
                                   what, sc_line(s, e));
            }
        /* the constructor's own checks (alternatives, combinations), reported at the entry */
        char err[512] = "";
        floe_contact_law *probe = sc_law_create(s, L, err, sizeof err);
        if (!probe) return sc_fail(s, FLOE_EINVAL, e, "%s: %s", what, err[0] ? err : "could not create the law");
        floe_contact_law_destroy(probe);
        i++;
    }
    return FLOE_OK;
}

int sc_build_laws(sc *s)
{
    for (int i = 0; i < s->nlaws; i++) {
        const sc_law *L = &s->laws[i];
        char err[512] = "";
        floe_contact_law *law = sc_law_create(s, L, err, sizeof err);
        struct fy_node *at = s->law_at[L->a * s->nmats + L->b];
        if (!law)
            return sc_fail(s, FLOE_EINVAL, at, "laws[%d]: could not create the %s law%s%s", i, L->ent->name,
                           err[0] ? ": " : "", err);
        int rc = floe_world_set_law(s->w, L->a, L->b, law);
        if (rc != FLOE_OK)
            return sc_fail(s, rc, at, "laws[%d]: %s", i, floe_world_last_error(s->w));
    }
    return FLOE_OK;
}

/* ------------------------------------------------------------------------------------ */
/* Walls                                                                                 */

/* walls[i].servo: {pressure, max_speed, gain, area: A | auto} (floe_servo.h) */
static int sc_wall_servo(sc *s, const sc_map *wm, int idx)
{
    static const char *const keys[] = {"pressure", "max_speed", "gain", "area", NULL};
    struct fy_node *k, *v = sc_get(wm, "servo", &k);
    char f[96];
    sc_field(f, sizeof f, wm, "servo");
    sc_map m;
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, f, keys, &m));
    floe_servo_def d = floe_default_servo_def();
    FLOE_TRY(sc_num(s, &m, "pressure", 1, 0, &d.pressure));
    if (!(d.pressure > 0)) return sc_range(s, &m, "pressure", "> 0 (Pa; 2D: N/m)", d.pressure);
    FLOE_TRY(sc_num(s, &m, "max_speed", 0, 0.0, &d.max_speed));
    if (!(d.max_speed >= 0)) return sc_range(s, &m, "max_speed", ">= 0 (m/s; 0: automatic)", d.max_speed);
    FLOE_TRY(sc_num(s, &m, "gain", 0, 0.0, &d.gain));
    if (!(d.gain >= 0)) return sc_range(s, &m, "gain", ">= 0 (m/(s Pa); 0: automatic)", d.gain);
    struct fy_node *av = sc_get(&m, "area", NULL);
    const char *at = av ? sc_text(av) : NULL;
    if (av && !(at && !strcmp(at, "auto"))) {
        FLOE_TRY(sc_num(s, &m, "area", 1, 0.0, &d.area));
        if (!(d.area > 0)) return sc_range(s, &m, "area", "> 0 (m^2; 2D: m) or auto", d.area);
    }
    int rc = floe_world_add_servo_wall(s->w, idx, &d);
    if (rc) return sc_fail(s, rc, v, "%s: %s", f, floe_world_last_error(s->w));
    return FLOE_OK;
}

int sc_parse_walls(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys[] = {"point", "normal", "material", "velocity", "name", "servo", NULL};
    if (!seq) return FLOE_OK;
    if (sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, sc_is_missing(seq) ? key : seq,
                       "walls must be a list of {point, normal, material}");
    void *it = NULL;
    struct fy_node *e;
    int i = 0;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        char what[32];
        snprintf(what, sizeof what, "walls[%d]", i);
        sc_map m;
        FLOE_TRY(sc_map_open(s, e, e, what, keys, &m));
        double p[3], n[3], v[3];
        FLOE_TRY(sc_vec(s, &m, "point", 1, NULL, p));
        FLOE_TRY(sc_vec(s, &m, "normal", 1, NULL, n));
        FLOE_TRY(sc_vec(s, &m, "velocity", 0, NULL, v));
        FLOE_TRY(sc_check_planar(s, &m, "normal", n));
        FLOE_TRY(sc_check_planar(s, &m, "velocity", v));
        double nn = floe_v3_norm(n);
        if (!(nn > 0)) {
            struct fy_node *k;
            struct fy_node *nv = sc_get(&m, "normal", &k);
            return sc_fail(s, FLOE_EINVAL, nv, "%s.normal must be a non-zero vector", what);
        }
        floe_v3_scale(n, 1.0 / nn);
        const char *mname;
        struct fy_node *mat_at;
        FLOE_TRY(sc_str(s, &m, "material", 1, NULL, &mname, &mat_at));
        int mat = -1;
        char f[48];
        snprintf(f, sizeof f, "%s.material", what);
        FLOE_TRY(sc_material_ref(s, mname, mat_at, f, &mat));
        if (!s->mats[mat].wall_user) {
            s->mats[mat].wall_user = mat_at;
            s->mats[mat].wall_entry = i;
        }
        s->mats[mat].nwall++;
        const char *wname;
        FLOE_TRY(sc_str(s, &m, "name", 0, NULL, &wname, NULL));
        int moving = v[0] != 0 || v[1] != 0 || v[2] != 0;
        int idx = floe_world_add_wall(s->w, p, n, mat, moving ? FLOE_KINEMATIC : FLOE_FIXED);
        if (idx < 0) return sc_fail(s, -idx, e, "%s: %s", what, floe_world_last_error(s->w));
        if (moving) {
            /* a kinematic particle moves with its prescribed (here constant) velocity */
            floe_v3_copy(s->w->p.v + 3 * idx, v);
        }
        if (sc_has(&m, "servo")) {
            if (moving)
                return sc_fail(s, FLOE_EPARSE, sc_get(&m, "servo", NULL), "%s: give either velocity or servo (a servo "
                               "wall moves by itself)", what);
            FLOE_TRY(sc_wall_servo(s, &m, idx));
        }
        s->nwalls = ++i;
    }
    /* the servo walls' automatic areas need the box of the other walls: checked here, at
     * their entries */
    it = NULL;
    i = 0;
    int first = s->w->p.n - s->nwalls;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        if (floe_world_is_servo_wall(s->w, first + i) && floe_world_servo_check(s->w, first + i))
            return sc_fail(s, FLOE_EINVAL, fy_node_mapping_lookup_by_string(e, "servo", -1), "walls[%d].servo: %s", i,
                           floe_world_last_error(s->w));
        i++;
    }
    return FLOE_OK;
}
