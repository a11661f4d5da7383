/* scene_read.c - the scene loader's reading helpers: errors at file:line:col, YAML nodes,
 * numbers, names, vectors, schema-driven parameters (floe_registry.h) and the packing RNG. */
#include "scene_read.h"
#include "floe_par.h"

static long sc_pos(const sc *s, struct fy_node *n);
static int sc_loc_pos(const sc *s, long pos, int *line, int *col);

static int sc_vfail_pos(sc *s, int code, long pos, const char *fmt, va_list ap)
{
    char msg[768];
    vsnprintf(msg, sizeof msg, fmt, ap);
    int line, col;
    if (s->err && s->errlen) {
        if (sc_loc_pos(s, pos, &line, &col))
            snprintf(s->err, s->errlen, "%s:%d:%d: %s", s->path, line, col, msg);
        else
            snprintf(s->err, s->errlen, "%s: %s", s->path, msg);
    }
    return code ? code : FLOE_EINVAL;
}

int sc_fail_pos(sc *s, int code, long pos, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = sc_vfail_pos(s, code, pos, fmt, ap);
    va_end(ap);
    return rc;
}

int sc_fail(sc *s, int code, struct fy_node *at, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = sc_vfail_pos(s, code, sc_pos(s, at), fmt, ap);
    va_end(ap);
    return rc;
}

/* ------------------------------------------------------------------------------------ */
/* Node helpers                                                                          */

/* Byte offset of a node's first character in the text: scalars from their token (the
 * opening quote of a quoted scalar), flow collections from their bracket (found by
 * scanning back from the first entry), block collections from their first entry.
 * Returns -1 when unknown (empty block collection, NULL). */
static long sc_pos_direct(const sc *s, struct fy_node *n);

static int sc_blank(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

/* A node with no token of its own (an empty key `: 3`, an empty collection `[]` or `{}`):
 * found from its neighbours in the parent. An empty key is at the ':' before its value; an
 * empty value is the first character after its key's ':'; an empty entry of a sequence is
 * after the ',' that follows the previous entry. Otherwise the parent's position. */
static long sc_pos_fallback(const sc *s, struct fy_node *n, int depth)
{
    struct fy_node *par = fy_node_get_parent(n);
    if (!par || depth > 64) return -1;
    if (fy_node_is_mapping(par)) {
        void *it = NULL;
        struct fy_node_pair *p;
        while ((p = fy_node_mapping_iterate(par, &it))) {
            struct fy_node *k = fy_node_pair_key(p), *v = fy_node_pair_value(p);
            if (k == n && v && v != n) {
                long q = sc_pos_direct(s, v);
                if (q < 0) break;
                for (q--; q > 0 && sc_blank(s->text[q]); q--) {}
                return q >= 0 ? q : 0;
            }
            if (v == n && k && k != n) {
                struct fy_token *t = fy_node_is_scalar(k) ? fy_node_get_scalar_token(k) : NULL;
                const struct fy_mark *e = t ? fy_token_end_mark(t) : NULL;
                long q = e ? (long)e->input_pos : -1;
                if (q < 0 || q > s->textlen) break;
                while (q < s->textlen && (s->text[q] == ' ' || s->text[q] == '\t' || s->text[q] == '"' ||
                                          s->text[q] == '\''))
                    q++;
                if (q < s->textlen && s->text[q] == ':') q++;
                while (q < s->textlen && sc_blank(s->text[q])) q++;
                return q;
            }
        }
    } else if (fy_node_is_sequence(par)) {
        void *it = NULL;
        struct fy_node *c, *prev = NULL;
        while ((c = fy_node_sequence_iterate(par, &it)) && c != n) prev = c;
        long q = prev ? sc_pos_direct(s, prev) : -1;
        if (q >= 0 && fy_node_get_style(par) == FYNS_FLOW) {
            while (q < s->textlen && s->text[q] != ',' && s->text[q] != '\n') q++;
            if (q < s->textlen && s->text[q] == ',') q++;
            while (q < s->textlen && sc_blank(s->text[q])) q++;
            return q;
        }
    }
    long q = sc_pos_direct(s, par);
    return q >= 0 ? q : sc_pos_fallback(s, par, depth + 1);
}

static long sc_pos(const sc *s, struct fy_node *n)
{
    long q = sc_pos_direct(s, n);
    return q >= 0 || !n ? q : sc_pos_fallback(s, n, 0);
}

static long sc_pos_direct(const sc *s, struct fy_node *n)
{
    if (!n) return -1;
    switch (fy_node_get_type(n)) {
    case FYNT_SCALAR: {
        struct fy_token *t = fy_node_get_scalar_token(n);
        const struct fy_mark *m = t ? fy_token_start_mark(t) : NULL;
        if (!m) return -1;
        long pos = (long)m->input_pos;
        enum fy_node_style st = fy_node_get_style(n);
        if ((st == FYNS_SINGLE_QUOTED || st == FYNS_DOUBLE_QUOTED) && pos > 0 && pos <= s->textlen &&
            (s->text[pos - 1] == '"' || s->text[pos - 1] == '\''))
            pos--;
        if (st == FYNS_ALIAS && pos > 0 && pos <= s->textlen && s->text[pos - 1] == '*') pos--;
        return pos;
    }
    case FYNT_MAPPING:
    case FYNT_SEQUENCE: {
        void *it = NULL;
        long pos = -1;
        if (fy_node_is_mapping(n)) {
            struct fy_node_pair *p = fy_node_mapping_iterate(n, &it);
            if (p) pos = sc_pos_direct(s, fy_node_pair_key(p));
        } else {
            struct fy_node *c = fy_node_sequence_iterate(n, &it);
            if (c) pos = sc_pos_direct(s, c);
        }
        if (pos > 0 && pos <= s->textlen && fy_node_get_style(n) == FYNS_FLOW) {
            char open = fy_node_is_mapping(n) ? '{' : '[';
            long q = pos - 1;
            while (q >= 0 && (s->text[q] == ' ' || s->text[q] == '\t' || s->text[q] == '\n' ||
                              s->text[q] == '\r'))
                q--;
            if (q >= 0 && s->text[q] == open) pos = q;
        } else if (pos > 0 && pos <= s->textlen && fy_node_is_sequence(n)) {
            /* block sequence: the '-' of its first entry */
            long q = pos - 1;
            while (q >= 0 && (s->text[q] == ' ' || s->text[q] == '\t')) q--;
            if (q >= 0 && s->text[q] == '-') pos = q;
        }
        return pos;
    }
    }
    return -1;
}

/* 1-based line and column of a node (0 if unknown). */
int sc_loc(const sc *s, struct fy_node *n, int *line, int *col)
{
    return sc_loc_pos(s, sc_pos(s, n), line, col);
}

static int sc_loc_pos(const sc *s, long pos, int *line, int *col)
{
    if (pos < 0 || pos > s->textlen) return 0;
    int l = 1, c = 1;
    for (long i = 0; i < pos; i++) {
        if (s->text[i] == '\n') { l++; c = 1; }
        else if ((s->text[i] & 0xC0) != 0x80) c++;   /* count UTF-8 characters */
    }
    *line = l;
    *col = c;
    return 1;
}

int sc_line(const sc *s, struct fy_node *n)
{
    int l = 0, c = 0;
    return sc_loc(s, n, &l, &c) ? l : 0;
}

/* Scalar text (NUL-terminated, owned by the document) or NULL if not a scalar. */
const char *sc_text(struct fy_node *n)
{
    if (!n || !fy_node_is_scalar(n)) return NULL;
    return fy_node_get_scalar0(n);
}

int sc_is_missing(struct fy_node *n)
{
    if (!n) return 1;
    if (!fy_node_is_scalar(n)) return 0;
    if (fy_node_get_style(n) != FYNS_PLAIN) return 0;
    const char *t = fy_node_get_scalar0(n);
    return !t || !*t || !strcmp(t, "~") || !strcmp(t, "null") || !strcmp(t, "Null") ||
           !strcmp(t, "NULL");
}

const char *sc_type_name(struct fy_node *n)
{
    if (!n) return "nothing";
    switch (fy_node_get_type(n)) {
    case FYNT_SCALAR: return fy_node_get_style(n) == FYNS_PLAIN ? "a scalar" : "a string";
    case FYNT_SEQUENCE: return "a list";
    case FYNT_MAPPING: return "a mapping";
    }
    return "something else";
}

/* the edit distance of the registries (floe_registry.h): one implementation */
static int sc_edit_distance(const char *a, const char *b) { return floe_edit_distance(a, b); }

/* " (did you mean 'x'?)" for the closest of names[0..n), or a list of the valid names. */
void sc_suggest(char *buf, size_t len, const char *word, const char *const *names, int n)
{
    int best = -1, bestd = 1 << 30;
    for (int i = 0; i < n; i++) {
        int d = sc_edit_distance(word, names[i]);
        if (d < bestd) { bestd = d; best = i; }
    }
    int wl = (int)strlen(word);
    int limit = wl / 2 > 2 ? wl / 2 : 2;
    if (best >= 0 && bestd <= limit) {
        snprintf(buf, len, " (did you mean '%s'?)", names[best]);
        return;
    }
    size_t k = (size_t)snprintf(buf, len, " (valid: ");
    for (int i = 0; i < n && k < len; i++)
        k += (size_t)snprintf(buf + k, len - k, "%s%s", i ? ", " : "", names[i]);
    if (k < len) snprintf(buf + k, len - k, ")");
}


void sc_field(char *buf, size_t len, const sc_map *m, const char *key)
{
    if (m->what[0]) snprintf(buf, len, "%s.%s", m->what, key);
    else snprintf(buf, len, "%s", key);
}

/* Open a mapping and check its keys against keys[] (NULL-terminated). */
int sc_map_open(sc *s, struct fy_node *node, struct fy_node *at, const char *what,
                       const char *const *keys, sc_map *m)
{
    m->node = node;
    m->at = at ? at : node;
    snprintf(m->what, sizeof m->what, "%s", what);
    if (!node || !fy_node_is_mapping(node))
        return sc_fail(s, FLOE_EPARSE, node && !sc_is_missing(node) ? node : at,
                       "%s must be a mapping ({key: value, ...}), got %s", what[0] ? what : "scene",
                       sc_is_missing(node) ? "nothing" : sc_type_name(node));
    int nkeys = 0;
    while (keys[nkeys]) nkeys++;
    void *it = NULL;
    struct fy_node_pair *p;
    while ((p = fy_node_mapping_iterate(node, &it))) {
        struct fy_node *k = fy_node_pair_key(p);
        const char *ks = sc_text(k);
        if (!ks)
            return sc_fail(s, FLOE_EPARSE, k ? k : node, "%s: keys must be plain names",
                           what[0] ? what : "scene");
        if (!*ks) {
            /* an empty key has no token: it sits at the ':' before its value */
            long q = sc_pos_direct(s, k);
            struct fy_node *v = fy_node_pair_value(p);
            if (q < 0 && v && (q = sc_pos(s, v)) >= 0)
                for (q--; q > 0 && sc_blank(s->text[q]); q--) {}
            if (q < 0) q = sc_pos(s, node);
            return sc_fail_pos(s, FLOE_EPARSE, q, "empty key in %s (a ':' with no name before it)",
                               what[0] ? what : "the scene");
        }
        int found = 0;
        for (int i = 0; i < nkeys && !found; i++) found = !strcmp(ks, keys[i]);
        if (!found) {
            char sug[512];
            sc_suggest(sug, sizeof sug, ks, keys, nkeys);
            if (what[0])
                return sc_fail(s, FLOE_EPARSE, k, "unknown key '%s' in %s%s", ks, what, sug);
            return sc_fail(s, FLOE_EPARSE, k, "unknown key '%s'%s", ks, sug);
        }
    }
    return FLOE_OK;
}

/* Value of key (NULL if absent); *keyp receives the key node. */
struct fy_node *sc_get(const sc_map *m, const char *key, struct fy_node **keyp)
{
    void *it = NULL;
    struct fy_node_pair *p;
    if (keyp) *keyp = NULL;
    while ((p = fy_node_mapping_iterate(m->node, &it))) {
        struct fy_node *k = fy_node_pair_key(p);
        const char *ks = sc_text(k);
        if (ks && !strcmp(ks, key)) {
            if (keyp) *keyp = k;
            struct fy_node *v = fy_node_pair_value(p);
            return v ? v : k;   /* an empty value reads as the (scalar) key: reported missing */
        }
    }
    return NULL;
}

int sc_has(const sc_map *m, const char *key) { return sc_get(m, key, NULL) != NULL; }

/* Parse a number from a node. */
static int sc_node_num(sc *s, struct fy_node *v, struct fy_node *k, const char *field, double *out)
{
    if (!v || v == k || sc_is_missing(v))
        return sc_fail(s, FLOE_EPARSE, k ? k : v, "%s: missing value (expected a number)", field);
    if (!fy_node_is_scalar(v))
        return sc_fail(s, FLOE_EPARSE, v, "%s: expected a number, got %s", field, sc_type_name(v));
    const char *t = fy_node_get_scalar0(v);
    if (fy_node_get_style(v) != FYNS_PLAIN)
        return sc_fail(s, FLOE_EPARSE, v, "%s: expected a number, got the string \"%s\"", field, t);
    char *end = NULL;
    errno = 0;
    double x = strtod(t, &end);
    if (end == t || *end || errno == ERANGE)
        return sc_fail(s, FLOE_EPARSE, v, "%s: expected a number, got '%s'", field, t);
    if (!isfinite(x))
        return sc_fail(s, FLOE_EINVAL, v, "%s must be finite (got '%s')", field, t);
    *out = x;
    return FLOE_OK;
}

int sc_node_long(sc *s, struct fy_node *v, struct fy_node *k, const char *field, long *out)
{
    if (!v || v == k || sc_is_missing(v))
        return sc_fail(s, FLOE_EPARSE, k ? k : v, "%s: missing value (expected an integer)", field);
    const char *t = sc_text(v);
    if (!t || fy_node_get_style(v) != FYNS_PLAIN)
        return sc_fail(s, FLOE_EPARSE, v, "%s: expected an integer, got %s", field,
                       t ? "a string" : sc_type_name(v));
    char *end = NULL;
    errno = 0;
    long x = strtol(t, &end, 10);
    if (end == t || *end || errno == ERANGE) {
        /* accept integral floats written as 1e3 */
        double d = strtod(t, &end);
        if (end == t || *end || d != floor(d) || fabs(d) > 1e15)
            return sc_fail(s, FLOE_EPARSE, v, "%s: expected an integer, got '%s'", field, t);
        x = (long)d;
    }
    *out = x;
    return FLOE_OK;
}

int sc_num(sc *s, const sc_map *m, const char *key, int required, double def, double *out)
{
    struct fy_node *k;
    struct fy_node *v = sc_get(m, key, &k);
    char f[160];
    sc_field(f, sizeof f, m, key);
    if (!v) {
        if (required) return sc_fail(s, FLOE_EPARSE, m->at, "%s is required", f);
        *out = def;
        return FLOE_OK;
    }
    return sc_node_num(s, v, k, f, out);
}

int sc_long(sc *s, const sc_map *m, const char *key, int required, long def, long *out)
{
    struct fy_node *k;
    struct fy_node *v = sc_get(m, key, &k);
    char f[160];
    sc_field(f, sizeof f, m, key);
    if (!v) {
        if (required) return sc_fail(s, FLOE_EPARSE, m->at, "%s is required", f);
        *out = def;
        return FLOE_OK;
    }
    return sc_node_long(s, v, k, f, out);
}

int sc_bool(sc *s, const sc_map *m, const char *key, int def, int *out)
{
    struct fy_node *k;
    struct fy_node *v = sc_get(m, key, &k);
    char f[160];
    sc_field(f, sizeof f, m, key);
    if (!v) { *out = def; return FLOE_OK; }
    const char *t = sc_text(v);
    if (!t || v == k || fy_node_get_style(v) != FYNS_PLAIN)
        return sc_fail(s, FLOE_EPARSE, v == k ? k : v, "%s: expected true or false", f);
    if (!strcmp(t, "true") || !strcmp(t, "True") || !strcmp(t, "TRUE") || !strcmp(t, "yes")) {
        *out = 1;
        return FLOE_OK;
    }
    if (!strcmp(t, "false") || !strcmp(t, "False") || !strcmp(t, "FALSE") || !strcmp(t, "no")) {
        *out = 0;
        return FLOE_OK;
    }
    return sc_fail(s, FLOE_EPARSE, v, "%s: expected true or false, got '%s'", f, t);
}

/* A string value; *at receives its node. */
int sc_str(sc *s, const sc_map *m, const char *key, int required, const char *def,
                  const char **out, struct fy_node **at)
{
    struct fy_node *k;
    struct fy_node *v = sc_get(m, key, &k);
    char f[160];
    sc_field(f, sizeof f, m, key);
    if (at) *at = v ? v : m->at;
    if (!v) {
        if (required) return sc_fail(s, FLOE_EPARSE, m->at, "%s is required", f);
        *out = def;
        return FLOE_OK;
    }
    if (v == k || sc_is_missing(v))
        return sc_fail(s, FLOE_EPARSE, k, "%s: missing value (expected a name)", f);
    if (!fy_node_is_scalar(v))
        return sc_fail(s, FLOE_EPARSE, v, "%s: expected a name, got %s", f, sc_type_name(v));
    *out = fy_node_get_scalar0(v);
    return FLOE_OK;
}

/* One of a fixed set of words. */
int sc_enum(sc *s, const sc_map *m, const char *key, const char *const *names, int def,
                   int *out)
{
    const char *t;
    struct fy_node *at;
    FLOE_TRY(sc_str(s, m, key, def < 0, NULL, &t, &at));
    if (!t) { *out = def; return FLOE_OK; }
    int n = 0;
    for (; names[n]; n++)
        if (!strcmp(t, names[n])) { *out = n; return FLOE_OK; }
    char f[160], sug[256];
    sc_field(f, sizeof f, m, key);
    sc_suggest(sug, sizeof sug, t, names, n);
    return sc_fail(s, FLOE_EINVAL, at, "%s: unknown value '%s'%s", f, t, sug);
}

/* A list of numbers of length n (or n2 when n2 > 0 is also accepted; missing entries are 0).
 * Returns the length read in *got. */
int sc_node_list(sc *s, struct fy_node *v, struct fy_node *k, const char *field, int n,
                        int n2, double *out, int *got)
{
    char want[64];
    if (n2 > 0) snprintf(want, sizeof want, "a list of %d or %d numbers", n2, n);
    else snprintf(want, sizeof want, "a list of %d numbers", n);
    if (!v || v == k || sc_is_missing(v))
        return sc_fail(s, FLOE_EPARSE, k ? k : v, "%s: missing value (expected %s)", field, want);
    if (!fy_node_is_sequence(v))
        return sc_fail(s, FLOE_EPARSE, v, "%s: expected %s, got %s", field, want, sc_type_name(v));
    int cnt = fy_node_sequence_item_count(v);
    if (cnt != n && !(n2 > 0 && cnt == n2))
        return sc_fail(s, FLOE_EPARSE, v, "%s: expected %s, got %d %s", field, want, cnt,
                       cnt == 1 ? "entry" : "entries");
    void *it = NULL;
    struct fy_node *c;
    int i = 0;
    for (int j = 0; j < n; j++) out[j] = 0;
    while ((c = fy_node_sequence_iterate(v, &it))) {
        char f2[192];
        snprintf(f2, sizeof f2, "%s[%d]", field, i);
        FLOE_TRY(sc_node_num(s, c, NULL, f2, &out[i]));
        i++;
    }
    *got = cnt;
    return FLOE_OK;
}

/* A vector: 3 numbers, or 2 in a 2D scene (z = 0). */
int sc_vec(sc *s, const sc_map *m, const char *key, int required, const double def[3],
                  double out[3])
{
    struct fy_node *k;
    struct fy_node *v = sc_get(m, key, &k);
    char f[160];
    sc_field(f, sizeof f, m, key);
    if (!v) {
        if (required) return sc_fail(s, FLOE_EPARSE, m->at, "%s is required", f);
        for (int i = 0; i < 3; i++) out[i] = def ? def[i] : 0.0;
        return FLOE_OK;
    }
    int got;
    return sc_node_list(s, v, k, f, 3, s->dim == 2 ? 2 : 0, out, &got);
}

/* In 2D, the z component of a point/velocity/direction must be zero. */
int sc_check_planar(sc *s, const sc_map *m, const char *key, const double x[3])
{
    if (s->dim != 2 || x[2] == 0.0) return FLOE_OK;
    struct fy_node *k;
    struct fy_node *v = sc_get(m, key, &k);
    char f[160];
    sc_field(f, sizeof f, m, key);
    return sc_fail(s, FLOE_EINVAL, v ? v : m->at,
                   "%s: z component must be 0 in a 2D scene (got %g)", f, x[2]);
}

/* Report a range error on a field (the value node if present). */
int sc_range(sc *s, const sc_map *m, const char *key, const char *cond, double got)
{
    struct fy_node *k;
    struct fy_node *v = sc_get(m, key, &k);
    char f[160];
    sc_field(f, sizeof f, m, key);
    return sc_fail(s, FLOE_EINVAL, v ? v : m->at, "%s must be %s (got %g)", f, cond, got);
}

/* ------------------------------------------------------------------------------------ */
/* Parameters read from a registered component's schema (floe_registry.h)               */

/* 1 when key is one of the '|'-separated words of list */
static int sc_in_list(const char *list, const char *key)
{
    size_t n = strlen(key);
    for (const char *p = list; p && *p;) {
        const char *e = strchr(p, '|');
        size_t l = e ? (size_t)(e - p) : strlen(p);
        if (l == n && !strncmp(p, key, n)) return 1;
        p = e ? e + 1 : NULL;
    }
    return 0;
}

/* Fills params (ent->params_size bytes) from the mapping m by the schema of ent: unknown
 * keys (besides ent->keys_extra, which the caller reads) get the closest key or the list,
 * absent required keys and values out of range are reported at their position. `label`
 * names the component in messages ("model 'linear'"); loader_keys ("a|b") are the keys
 * the kind's loader reads itself. */
int sc_read_schema(sc *s, const sc_map *m, const floe_registry_entry *ent, const char *label,
                          const char *loader_keys, void *params)
{
    floe_params_defaults(ent, params);
    floe_params_head *head = params;
    const char *names[FLOE_PARAMS_MAX];
    for (int k = 0; k < ent->nparams; k++) names[k] = ent->params[k].key;
    void *it = NULL;
    struct fy_node_pair *pr;
    while ((pr = fy_node_mapping_iterate(m->node, &it))) {
        const char *ks = sc_text(fy_node_pair_key(pr));
        if (!ks || sc_in_list(loader_keys, ks) || sc_in_list(ent->keys_extra, ks) || floe_schema_index(ent, ks) >= 0)
            continue;
        char sug[512] = "";
        if (ent->nparams) sc_suggest(sug, sizeof sug, ks, names, ent->nparams);
        else snprintf(sug, sizeof sug, " (it takes no parameters)");
        return sc_fail(s, FLOE_EPARSE, fy_node_pair_key(pr), "unknown key '%s' in %s: not valid for %s%s", ks, m->what, label,
                       sug);
    }
    for (int k = 0; k < ent->nparams; k++) {
        const floe_param *p = &ent->params[k];
        char *at = (char *)params + p->offset;
        struct fy_node *kn, *v = sc_get(m, p->key, &kn);
        char f[160];
        sc_field(f, sizeof f, m, p->key);
        if (!v) {
            if (p->flags & FLOE_PARAM_REQUIRED)
                return sc_fail(s, FLOE_EPARSE, m->at, "%s is required for %s (%s%s%s)", f, label, p->doc,
                               p->unit && p->unit[0] ? ", " : "", p->unit ? p->unit : "");
            continue;
        }
        head->given |= 1ull << k;
        double x = 0, vec[3] = {0, 0, 0};
        int iv = 0, got = 0;
        switch (p->type) {
        case FLOE_PARAM_REAL:
        case FLOE_PARAM_INT:
            FLOE_TRY(sc_node_num(s, v, kn, f, &x));
            break;
        case FLOE_PARAM_BOOL:
            FLOE_TRY(sc_bool(s, m, p->key, 0, &iv));
            memcpy(at, &iv, sizeof iv);
            continue;
        case FLOE_PARAM_STRING: {
            const char *t;
            FLOE_TRY(sc_str(s, m, p->key, 1, NULL, &t, NULL));
            if (strlen(t) >= FLOE_PARAM_STRING_MAX)
                return sc_fail(s, FLOE_EINVAL, v, "%s: longer than %d characters", f, FLOE_PARAM_STRING_MAX - 1);
            snprintf(at, FLOE_PARAM_STRING_MAX, "%s", t);
            continue;
        }
        case FLOE_PARAM_CHOICE: {
            const char *t, *words[64];
            char buf[512];
            snprintf(buf, sizeof buf, "%s", p->choices);
            int nw = 0;
            for (char *w = strtok(buf, "|"); w && nw < 64; w = strtok(NULL, "|")) words[nw++] = w;
            FLOE_TRY(sc_str(s, m, p->key, 1, NULL, &t, NULL));
            for (iv = 0; iv < nw && strcmp(words[iv], t); iv++) {}
            if (iv == nw) {
                char sug[512];
                sc_suggest(sug, sizeof sug, t, words, nw);
                return sc_fail(s, FLOE_EINVAL, v, "%s: unknown value '%s'%s", f, t, sug);
            }
            memcpy(at, &iv, sizeof iv);
            continue;
        }
        case FLOE_PARAM_POINTS:
        case FLOE_PARAM_NODE:
            return sc_fail(s, FLOE_ENOTSUP, kn, "%s: %s reads this key itself (a point list or nested value)", f, label);
        case FLOE_PARAM_VEC3:
            FLOE_TRY(sc_node_list(s, v, kn, f, 3, s->dim == 2 && !(p->flags & FLOE_PARAM_XYZ) ? 2 : 0, vec, &got));
            for (int c = 0; c < 3; c++) {
                char why[160];
                if (floe_param_check(p, vec[c], why, sizeof why))
                    return sc_fail(s, FLOE_EINVAL, v, "%s[%d] %s (got %g)", f, c, why, vec[c]);
            }
            memcpy(at, vec, sizeof vec);
            continue;
        }
        char why[160];
        if (floe_param_check(p, x, why, sizeof why)) return sc_fail(s, FLOE_EINVAL, v, "%s %s (got %g)", f, why, x);
        if (p->type == FLOE_PARAM_REAL) memcpy(at, &x, sizeof x);
        else {
            if (!(fabs(x) < 2e9)) return sc_fail(s, FLOE_EINVAL, v, "%s: %g is out of the integer range", f, x);
            iv = (int)x;
            memcpy(at, &iv, sizeof iv);
        }
    }
    return FLOE_OK;
}

/* ------------------------------------------------------------------------------------ */
/* Random numbers: splitmix64 (deterministic per seed, platform independent)            */


double sc_rng_uniform(sc_rng *r) { return floe_rng_uniform(&r->s); }

/* ------------------------------------------------------------------------------------ */
/* Spatial order: Morton (Z-order) keys of points in a box                              */

typedef struct sc_keyed { uint64_t key; long idx; } sc_keyed;

/* the low 21 bits of v spread to every third bit (3D) or every second bit (2D) */
static uint64_t sc_spread(uint64_t v, int dim)
{
    v &= 0x1fffff;
    if (dim == 2) {
        v = (v | (v << 16)) & 0x0000ffff0000ffffull;
        v = (v | (v << 8)) & 0x00ff00ff00ff00ffull;
        v = (v | (v << 4)) & 0x0f0f0f0f0f0f0f0full;
        v = (v | (v << 2)) & 0x3333333333333333ull;
        return (v | (v << 1)) & 0x5555555555555555ull;
    }
    v = (v | (v << 32)) & 0x001f00000000ffffull;
    v = (v | (v << 16)) & 0x001f0000ff0000ffull;
    v = (v | (v << 8)) & 0x100f00f00f00f00full;
    v = (v | (v << 4)) & 0x10c30c30c30c30c3ull;
    return (v | (v << 2)) & 0x1249249249249249ull;
}

static int sc_by_key(const void *a, const void *b)
{
    const sc_keyed *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return (x->idx > y->idx) - (x->idx < y->idx);
}

int sc_morton_order(const double *x, long n, int stride, int dim, const double *lo, const double *hi, long *order)
{
    sc_keyed *k = malloc((size_t)(n > 0 ? n : 1) * sizeof *k);
    if (!k) return FLOE_ENOMEM;
    /* one scale for every axis, the box's longest side: a thin axis scaled to the same 21
     * bits would own the key's top bit, and neighbours across its middle would get far
     * ranks (a slab a few diameters thick) */
    const double top = (double)0x1fffff;
    double side = 0;
    for (int a = 0; a < dim; a++)
        if (hi[a] - lo[a] > side) side = hi[a] - lo[a];
    for (long i = 0; i < n; i++) {
        uint64_t key = 0;
        for (int a = 0; a < dim; a++) {
            double u = side > 0 ? (x[stride * i + a] - lo[a]) / side : 0.0;
            u = u > 0 ? (u < 1 ? u : 1) : 0; /* NaN: 0 */
            key |= sc_spread((uint64_t)(u * top), dim) << a;
        }
        k[i].key = key;
        k[i].idx = i;
    }
    qsort(k, (size_t)n, sizeof *k, sc_by_key);
    for (long i = 0; i < n; i++) order[i] = k[i].idx;
    free(k);
    return FLOE_OK;
}

/* Memory a scene needs (SC_BYTES_* in scene_read.h) */

double sc_phys_mem(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), ps = sysconf(_SC_PAGE_SIZE);
    double have = pages > 0 && ps > 0 ? (double)pages * (double)ps : INFINITY;
#ifdef FLOE_SCENE_MEMORY_CAP
    have = fmin(have, FLOE_SCENE_MEMORY_CAP); /* the fuzzing build (-DFLOE_FUZZ=ON) */
#endif
    return have;
}

double sc_mem_estimate(const sc *s, double more_particles)
{
    double bonds = 0;
    for (int b = 0; s->w && b < s->w->npd; b++) bonds += (double)s->w->pd[b]->nbond;
    double n = (s->w ? (double)s->w->p.n : 0.0) + more_particles;
    const double per = SC_BYTES_PER_PARTICLE + (floe_par_max_threads() > 1 ? SC_BYTES_PER_PARTICLE_THREADS : 0.0);
    return SC_BYTES_BASE + n * per + bonds * SC_BYTES_PER_BOND;
}

/* refuse `more` particles (or the scene so far, more = 0) beyond the machine's memory */
int sc_check_memory(sc *s, struct fy_node *at, const char *what, double more)
{
    double need = sc_mem_estimate(s, more), have = sc_phys_mem();
    if (need <= have) return FLOE_OK;
    if (more > 0)
        return sc_fail(s, FLOE_ENOMEM, at, "%s: %.4g particles: the scene would need about %.3g GB (estimate, "
                       "%.0f bytes per particle), more than this machine's memory (%.3g GB)", what, more,
                       need / 1e9, SC_BYTES_PER_PARTICLE, have / 1e9);
    return sc_fail(s, FLOE_ENOMEM, at, "%s needs about %.3g GB (estimate: %d particles, %.0f bytes each, and "
                   "%.0f bytes per PD bond), more than this machine's memory (%.3g GB)", what, need / 1e9,
                   s->w ? s->w->p.n : 0, SC_BYTES_PER_PARTICLE, SC_BYTES_PER_BOND, have / 1e9);
}

/* a required length > 0 (m) */
int sc_pos_num(sc *s, const sc_map *m, const char *key, double *out)
{
    FLOE_TRY(sc_num(s, m, key, 1, 0, out));
    if (!(*out > 0)) return sc_range(s, m, key, "> 0 (m)", *out);
    return FLOE_OK;
}
