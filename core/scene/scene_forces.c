/* scene_forces.c - scene section `forces`: registered force providers (floe_provider.h,
 * kind FLOE_KIND_PROVIDER), each `{type: NAME, <its parameters>}` read by its schema and
 * added to the world (floe_world_add_provider). A relative `file` parameter is made
 * relative to the scene file's folder. */
#include "scene_read.h"

/* the registered names of a kind, for "did you mean" */
static void sc_kind_suggest(char *buf, size_t len, const char *kind, const char *word)
{
    const char *names[128];
    int n = 0;
    for (; n < floe_registry_count(kind) && n < 128; n++) names[n] = floe_registry_at(kind, n)->name;
    sc_suggest(buf, len, word, names, n);
}

int sc_parse_forces(sc *s, struct fy_node *seq, struct fy_node *key)
{
    if (!seq) return FLOE_OK;
    if (sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, sc_is_missing(seq) ? key : seq,
                       "forces must be a list of {type: NAME, ...} (floe help provider lists them)");
    void *it = NULL;
    struct fy_node *e;
    int i = 0;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        sc_map m = {e, e, ""};
        snprintf(m.what, sizeof m.what, "forces[%d]", i);
        if (!fy_node_is_mapping(e))
            return sc_fail(s, FLOE_EPARSE, e, "%s must be a mapping ({type: NAME, ...}), got %s", m.what,
                           sc_is_missing(e) ? "nothing" : sc_type_name(e));
        const char *tname;
        struct fy_node *tat;
        FLOE_TRY(sc_str(s, &m, "type", 1, NULL, &tname, &tat));
        const floe_registry_entry *ent = floe_registry_find(FLOE_KIND_PROVIDER, tname);
        if (!ent) {
            char sug[1024];
            sc_kind_suggest(sug, sizeof sug, FLOE_KIND_PROVIDER, tname);
            return sc_fail(s, FLOE_EINVAL, tat, "%s.type: unknown force provider '%s'%s", m.what, tname, sug);
        }
        void *params = calloc(1, ent->params_size);
        if (!params) return sc_fail(s, FLOE_ENOMEM, e, "out of memory");
        char label[96];
        snprintf(label, sizeof label, "provider '%s'", ent->name);
        int rc = sc_read_schema(s, &m, ent, label, "type", params);
        /* a relative `file` (a NetCDF field's) is relative to the scene file, as a mesh's */
        const int fk = floe_schema_index(ent, "file");
        const char *slash = s->path ? strrchr(s->path, '/') : NULL;
        if (!rc && fk >= 0 && ent->params[fk].type == FLOE_PARAM_STRING && slash) {
            char *f = (char *)params + ent->params[fk].offset;
            if (f[0] && f[0] != '/') {
                char full[2 * FLOE_PARAM_STRING_MAX];
                int len = snprintf(full, sizeof full, "%.*s/%s", (int)(slash - s->path), s->path, f);
                if (len < 0 || len >= FLOE_PARAM_STRING_MAX)
                    rc = sc_fail(s, FLOE_EINVAL, sc_get(&m, "file", NULL), "%s.file: the path %s is longer than %d "
                                 "characters", m.what, full, FLOE_PARAM_STRING_MAX - 1);
                else memcpy(f, full, (size_t)len + 1);
            }
        }
        floe_provider *pv = NULL;
        if (!rc) {
            char err[512] = "";
            pv = ((floe_provider_create_fn)ent->create)(params, s->w, err, sizeof err);
            if (!pv) rc = sc_fail(s, FLOE_EINVAL, e, "%s: %s", m.what, err[0] ? err : "the provider refused its parameters");
        }
        free(params);
        if (rc) return rc;
        rc = floe_world_add_provider(s->w, pv);
        if (rc) {
            if (pv->klass->destroy) pv->klass->destroy(pv);
            else free(pv);
            return sc_fail(s, rc, e, "%s: %s", m.what, floe_world_last_error(s->w));
        }
        i++;
    }
    return FLOE_OK;
}
