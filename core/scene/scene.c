/* scene.c - YAML scene files -> a prepared floe_world (format: docs/scene-format.md).
 *
 * Parsed with libfyaml's document API. Every mapping is checked against the keys valid at
 * that place (unknown keys name the closest valid one by edit distance); every value is
 * type-checked and range-checked, and every message is "file:line:column: message" with
 * 1-based line and column. Packings (lattice, hexagonal, random) are expanded here; the
 * world does the physics. ParticLS §5.2 (growing radius) and §5.3 (RVE) are the examples. */
#include "floe_scene.h"
#include "floe_registry.h"
#include "floe_state.h"
#include "world_internal.h"
#include "floe_observer.h"
#include "floe_mesh.h"
#include "floe_pd.h"
#include "floe_beam.h"

#include <errno.h>
#include <libfyaml.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* Field names in messages ("bodies[3].shape.compound.pieces[1]...") are built in fixed
 * buffers; a name that long is cut, which only shortens the message. */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wformat-truncation"
#endif

#define SC_MAX_PARTICLES_PER_ENTRY 100000000L
/* scene text: 16 MiB at most */
#define SC_MAX_TEXT ((size_t)16 << 20)
/* a run of more steps than this would never end (and the step count must fit a long) */
#define SC_MAX_STEPS 1.0e12
/* random packing: placement stops after this many tries in a row without a placement */
#define SC_MAX_FAILED_TRIES 10000000L
#define SC_MAX_TRIES 1000000000L

/* ------------------------------------------------------------------------------------ */
/* Loader context                                                                        */

typedef struct sc_mat {
    floe_material m;
    int has_young, has_poisson;
    struct fy_node *at;           /* the entry, for messages */
    struct fy_node *body_user;    /* first `material:` node of a body using it */
    struct fy_node *wall_user;    /* first `material:` node of a wall using it */
    int body_entry, wall_entry;   /* indices of those users */
    long nbody, nwall;            /* particles / walls of this material */
    int nfree;                    /* some particle of this material is free */
} sc_mat;

typedef struct sc_law {
    int a, b;
    const floe_registry_entry *ent;  /* the registered law (floe_registry.h) */
    void *params;                    /* its parameter struct, read by its schema */
    struct fy_node *node;            /* the entry (messages) */
} sc_law;

typedef struct sc_output {
    char type[64];
    const floe_registry_entry *ent; /* the registered output */
    void *uparams;                  /* a plugin output's parameters (its schema) */
    char target[512];
    long every;
    double interval;
    struct fy_node *name_at;      /* file / prefix value (NULL: the default), for messages */
    char file[520];               /* the file it writes (vtk: its .pvd), to refuse two writers of one file */
} sc_output;

typedef struct sc {
    const char *path;
    const char *text;
    long textlen;
    char *err;
    size_t errlen;
    int dim;
    floe_world *w;
    sc_mat *mats;
    int nmats;
    sc_law *laws;
    int nlaws;
    struct fy_node **law_at;     /* nmats*nmats: node of the law given for the pair */
    int nbody_entries;
    int nparticles, nwalls, nstates, nobservers;
    int nspheres, nboxes;
    int *entry_first, *entry_count; /* particle range of each body entry */
    sc_output *outs;
    int nouts;
    double duration, dt_given, safety;
    int dt_auto;
    int grow_particle[8];
    int ngrow_listed;
} sc;

static long sc_pos(const sc *s, struct fy_node *n);
static int sc_loc_pos(const sc *s, long pos, int *line, int *col);

/* Errors: "path:line:col: message" (or "path: message" when the position is unknown) into
 * the caller's buffer; they return code (FLOE_EINVAL for 0). At a node: */
static int sc_fail(sc *s, int code, struct fy_node *at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* the same at a byte offset of the text (-1: no position) */
static int sc_fail_pos(sc *s, int code, long pos, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

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

static int sc_fail_pos(sc *s, int code, long pos, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = sc_vfail_pos(s, code, pos, fmt, ap);
    va_end(ap);
    return rc;
}

static int sc_fail(sc *s, int code, struct fy_node *at, const char *fmt, ...)
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
static int sc_loc(const sc *s, struct fy_node *n, int *line, int *col)
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

static int sc_line(const sc *s, struct fy_node *n)
{
    int l = 0, c = 0;
    return sc_loc(s, n, &l, &c) ? l : 0;
}

/* Scalar text (NUL-terminated, owned by the document) or NULL if not a scalar. */
static const char *sc_text(struct fy_node *n)
{
    if (!n || !fy_node_is_scalar(n)) return NULL;
    return fy_node_get_scalar0(n);
}

static int sc_is_missing(struct fy_node *n)
{
    if (!n) return 1;
    if (!fy_node_is_scalar(n)) return 0;
    if (fy_node_get_style(n) != FYNS_PLAIN) return 0;
    const char *t = fy_node_get_scalar0(n);
    return !t || !*t || !strcmp(t, "~") || !strcmp(t, "null") || !strcmp(t, "Null") ||
           !strcmp(t, "NULL");
}

static const char *sc_type_name(struct fy_node *n)
{
    if (!n) return "nothing";
    switch (fy_node_get_type(n)) {
    case FYNT_SCALAR: return fy_node_get_style(n) == FYNS_PLAIN ? "a scalar" : "a string";
    case FYNT_SEQUENCE: return "a list";
    case FYNT_MAPPING: return "a mapping";
    }
    return "something else";
}

/* Optimal-string-alignment edit distance (a transposition counts as one edit). */
static int sc_edit_distance(const char *a, const char *b)
{
    int la = (int)strlen(a), lb = (int)strlen(b);
    if (la > 63 || lb > 63) return 99;
    int d[64][64];
    for (int i = 0; i <= la; i++) d[i][0] = i;
    for (int j = 0; j <= lb; j++) d[0][j] = j;
    for (int i = 1; i <= la; i++)
        for (int j = 1; j <= lb; j++) {
            int cost = a[i - 1] != b[j - 1];
            int v = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < v) v = d[i][j - 1] + 1;
            if (d[i - 1][j - 1] + cost < v) v = d[i - 1][j - 1] + cost;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                d[i - 2][j - 2] + 1 < v)
                v = d[i - 2][j - 2] + 1;
            d[i][j] = v;
        }
    return d[la][lb];
}

/* " (did you mean 'x'?)" for the closest of names[0..n), or a list of the valid names. */
static void sc_suggest(char *buf, size_t len, const char *word, const char *const *names, int n)
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

/* A mapping being read: which node, where it came from (for messages), its dotted path. */
typedef struct sc_map {
    struct fy_node *node;
    struct fy_node *at;
    char what[96];
} sc_map;

static void sc_field(char *buf, size_t len, const sc_map *m, const char *key)
{
    if (m->what[0]) snprintf(buf, len, "%s.%s", m->what, key);
    else snprintf(buf, len, "%s", key);
}

/* Open a mapping and check its keys against keys[] (NULL-terminated). */
static int sc_map_open(sc *s, struct fy_node *node, struct fy_node *at, const char *what,
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
static struct fy_node *sc_get(const sc_map *m, const char *key, struct fy_node **keyp)
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

static int sc_has(const sc_map *m, const char *key) { return sc_get(m, key, NULL) != NULL; }

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

static int sc_node_long(sc *s, struct fy_node *v, struct fy_node *k, const char *field, long *out)
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

static int sc_num(sc *s, const sc_map *m, const char *key, int required, double def, double *out)
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

static int sc_long(sc *s, const sc_map *m, const char *key, int required, long def, long *out)
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

static int sc_bool(sc *s, const sc_map *m, const char *key, int def, int *out)
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
static int sc_str(sc *s, const sc_map *m, const char *key, int required, const char *def,
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
static int sc_enum(sc *s, const sc_map *m, const char *key, const char *const *names, int def,
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
static int sc_node_list(sc *s, struct fy_node *v, struct fy_node *k, const char *field, int n,
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
static int sc_vec(sc *s, const sc_map *m, const char *key, int required, const double def[3],
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
static int sc_check_planar(sc *s, const sc_map *m, const char *key, const double x[3])
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
static int sc_range(sc *s, const sc_map *m, const char *key, const char *cond, double got)
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
static int sc_read_schema(sc *s, const sc_map *m, const floe_registry_entry *ent, const char *label,
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

typedef struct sc_rng { uint64_t s; } sc_rng;

static uint64_t sc_rng_next(sc_rng *r)
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double sc_rng_uniform(sc_rng *r) { return (double)(sc_rng_next(r) >> 11) * 0x1.0p-53; }

/* ------------------------------------------------------------------------------------ */
/* Materials and laws                                                                    */

static int sc_find_material(const sc *s, const char *name)
{
    for (int i = 0; i < s->nmats; i++)
        if (!strcmp(s->mats[i].m.name, name)) return i;
    return -1;
}

static int sc_material_ref(sc *s, const char *name, struct fy_node *at, const char *field, int *out)
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

static int sc_parse_materials(sc *s, struct fy_node *seq, struct fy_node *key)
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

static int sc_parse_laws(sc *s, struct fy_node *seq, struct fy_node *key)
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
        /* model: the name of a registered law */
        const char *model;
        struct fy_node *mat;
        FLOE_TRY(sc_str(s, &m, "model", 1, NULL, &model, &mat));
        const floe_registry_entry *ent = floe_registry_find(FLOE_KIND_LAW, model);
        if (!ent) {
            const char *names[128];
            char sug[1024];
            sc_suggest(sug, sizeof sug, model, names, sc_law_names(names, 128));
            return sc_fail(s, FLOE_EINVAL, mat, "%s.model: unknown value '%s'%s", what, model, sug);
        }
        sc_law *L = &s->laws[i];
        L->ent = ent;
        L->node = e;
        L->params = calloc(1, ent->params_size);
        if (!L->params) return sc_fail(s, FLOE_ENOMEM, e, "out of memory");
        s->nlaws = i + 1; /* freed with the loader from here on */
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
        FLOE_TRY(sc_read_schema(s, &m, ent, label, "materials|model", L->params));
        if (ent->flags & FLOE_LAW_NEEDS_YOUNG)
            for (int j = 0; j < 2; j++) {
                const sc_mat *mt = &s->mats[ab[j]];
                if (!mt->has_young)
                    return sc_fail(s, FLOE_EINVAL, mt->at,
                                   "material '%s' needs young (Pa): the %s law %s "
                                   "(line %d) uses it", mt->m.name, ent->name, what, sc_line(s, e));
            }
        /* the constructor's own checks (alternatives, combinations), reported at the entry */
        char err[512] = "";
        floe_contact_law *probe = ((floe_law_create_fn)ent->create)(L->params, &s->mats[L->a].m, &s->mats[L->b].m,
                                                                    err, sizeof err);
        if (!probe) return sc_fail(s, FLOE_EINVAL, e, "%s: %s", what, err[0] ? err : "could not create the law");
        floe_contact_law_destroy(probe);
        i++;
    }
    return FLOE_OK;
}

static int sc_build_laws(sc *s)
{
    for (int i = 0; i < s->nlaws; i++) {
        const sc_law *L = &s->laws[i];
        char err[512] = "";
        floe_contact_law *law = ((floe_law_create_fn)L->ent->create)(L->params, &s->mats[L->a].m,
                                                                     &s->mats[L->b].m, err, sizeof err);
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

static int sc_parse_walls(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys[] = {"point", "normal", "material", "velocity", "name", NULL};
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
        s->nwalls = ++i;
    }
    return FLOE_OK;
}

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
static void sc_geom_frame(const floe_geometry *g, double fx[3], double fq[4])
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

static int sc_pos_num(sc *s, const sc_map *m, const char *key, double *out)
{
    FLOE_TRY(sc_num(s, m, key, 1, 0, out));
    if (!(*out > 0)) return sc_range(s, m, key, "> 0 (m)", *out);
    return FLOE_OK;
}

/* Build any shape from its {kind: {...}} mapping (f names the field in messages). */
static int sc_build_shape(sc *s, struct fy_node *v, struct fy_node *k, const char *f, int depth,
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
    if (r != FLOE_OK)
        return sc_fail(s, r < 0 ? -r : r, at, "%s: %s", what, floe_world_last_error(s->w));
    if (s->ngrow_listed < (int)(sizeof s->grow_particle / sizeof s->grow_particle[0]))
        s->grow_particle[s->ngrow_listed++] = particle;
    s->nstates++;
    return FLOE_OK;
}

/* Memory a scene needs, estimated before its particles are made (measured: 64k and 256k
 * touching spheres, check and run, ~550 B per particle; brittle-cylinder-impact ~35 B per
 * PD bond): a scene beyond the machine's memory is refused instead of dying part-way. */
#define SC_BYTES_BASE 16.0e6
#define SC_BYTES_PER_PARTICLE 700.0
#define SC_BYTES_PER_BOND 40.0

static double sc_phys_mem(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), ps = sysconf(_SC_PAGE_SIZE);
    double have = pages > 0 && ps > 0 ? (double)pages * (double)ps : INFINITY;
#ifdef FLOE_SCENE_MEMORY_CAP
    have = fmin(have, FLOE_SCENE_MEMORY_CAP); /* the fuzzing build (-DFLOE_FUZZ=ON) */
#endif
    return have;
}

static double sc_mem_estimate(const sc *s, double more_particles)
{
    double bonds = 0;
    for (int b = 0; s->w && b < s->w->npd; b++) bonds += (double)s->w->pd[b]->nbond;
    double n = (s->w ? (double)s->w->p.n : 0.0) + more_particles;
    return SC_BYTES_BASE + n * SC_BYTES_PER_PARTICLE + bonds * SC_BYTES_PER_BOND;
}

/* refuse `more` particles (or the scene so far, more = 0) beyond the machine's memory */
static int sc_check_memory(sc *s, struct fy_node *at, const char *what, double more)
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
static int sc_random(sc *s, const sc_map *m, sc_points *pts, const sc_common *c)
{
    double lo[3], hi[3];
    FLOE_TRY(sc_parse_region(s, m, lo, hi));
    long count, seed, max_tries;
    FLOE_TRY(sc_long(s, m, "count", 1, 0, &count));
    if (count < 1 || count > SC_MAX_PARTICLES_PER_ENTRY)
        return sc_range(s, m, "count", "in [1, 1e8] (particles per entry)", (double)count);
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
    {
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
        for (int a = 0; a < 3; a++) {
            x[a] = a < s->dim ? a0[a] + (a1[a] - a0[a]) * sc_rng_uniform(&rng) : a0[a];
            ci[a] = a < s->dim ? (long)floor((x[a] - a0[a]) / cell) : 0;
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
                        if (floe_v3_dot(r, r) < d2min) ok = 0;
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

static int sc_parse_bodies(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys_single[] = {"shape", "material", "position", "velocity",
                                              "angular_velocity", "orientation", "motion", "name",
                                              "grow_rate", "grow", "packing", NULL};
    static const char *const keys_lattice[] = {"packing", "shape", "material", "origin", "counts",
                                               "region", "spacing", "jitter", "seed", "velocity",
                                               "angular_velocity", "orientation", "motion", "name",
                                               "grow", NULL};
    static const char *const keys_random[] = {"packing", "shape", "material", "region", "count",
                                              "seed", "max_tries", "velocity", "angular_velocity",
                                              "orientation", "motion", "name", "grow", NULL};
    static const char *const keys_all[] = {"shape", "material", "position", "velocity",
                                           "angular_velocity", "orientation", "motion", "name",
                                           "grow_rate", "grow", "packing", "origin", "counts",
                                           "region", "spacing", "jitter", "seed", "count",
                                           "max_tries", NULL};
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
        sc_map m;
        FLOE_TRY(sc_map_open(s, e, e, what, keys_all, &m));
        int packing;
        FLOE_TRY(sc_enum(s, &m, "packing", sc_packings, 3, &packing));
        const char *const *valid = packing == 3 ? keys_single
                                   : packing == 2 ? keys_random : keys_lattice;
        {
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
            int rc = packing == 2 ? sc_random(s, &m, &pts, &c)
                                  : sc_lattice(s, &m, packing == 1, &pts, &c);
            if (rc == FLOE_OK && c.grow && c.grow_index >= pts.n) {
                struct fy_node *gk;
                sc_get(&m, "grow", &gk);
                rc = sc_fail(s, FLOE_EINVAL, gk, "%s.grow.index %ld is out of range: the packing "
                             "has %ld particles", what, c.grow_index, pts.n);
            }
            if (rc == FLOE_OK && (double)s->nparticles + (double)pts.n > 2.0e9)
                rc = sc_fail(s, FLOE_EINVAL, e, "%s: too many particles", what);
            int gi = -1;
            if (rc == FLOE_OK) rc = sc_add_geometry(s, &c.shape, e, what, &gi);
            /* one shared geometry; the growing-radius state gives its particle its own */
            for (long i = 0; i < pts.n && rc == FLOE_OK; i++) {
                int pidx;
                rc = sc_add_one(s, &c, gi, pts.x + 3 * i, entry, e, what, &pidx);
                if (rc == FLOE_OK && c.grow && i == c.grow_index)
                    rc = sc_add_growth(s, &c, pidx, e, what);
            }
            free(pts.x);
            if (rc != FLOE_OK) return rc;
        }
        s->entry_count[entry] = s->nparticles - s->entry_first[entry];
        s->nbody_entries = ++entry;
    }
    return FLOE_OK;
}

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

static int sc_parse_pd(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys[] = {"region", "spacing", "horizon", "material", "contact_material", "velocity",
                                       "surface_correction", "thickness", "name", "boundary", "lattice", "cracks",
                                       NULL};
    static const char *const region_keys[] = {"box", "shape", "position", "remove", NULL};
    static const char *const mat_keys[] = {"model", "density", "bulk_modulus", "shear_modulus", "young",
                                           "critical_stretch", "fracture_energy", "influence", "alpha",
                                           "yield_compression", "yield_tension", "plane", NULL};
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
        sc_map mm;
        int rc = sc_map_open(s, mv == mk ? NULL : mv, mk, fm, mat_keys, &mm);
        static const char *const models[] = {"pmb", "lps", NULL};
        static const char *const infl[] = {"constant", "gaussian", NULL};
        int model = 0, inf = 0;
        double rho = 0, K = 0, G = 0, E = 0, sc_ = 0, Gc = 0, alpha = 0;
        if (!rc) rc = sc_enum(s, &mm, "model", models, -1, &model);
        if (!rc) rc = sc_pos_num(s, &mm, "density", &rho);
        if (!rc) rc = sc_num(s, &mm, "bulk_modulus", 0, 0, &K);
        if (!rc) rc = sc_num(s, &mm, "shear_modulus", 0, 0, &G);
        if (!rc) rc = sc_num(s, &mm, "young", 0, 0, &E);
        if (!rc) rc = sc_num(s, &mm, "critical_stretch", 0, 0, &sc_);
        if (!rc) rc = sc_num(s, &mm, "fracture_energy", 0, 0, &Gc);
        if (!rc) rc = sc_enum(s, &mm, "influence", infl, 0, &inf);
        /* PMB per-point critical stretch (LAMMPS peri/pmb): s0 = critical_stretch - alpha s_min */
        if (!rc) rc = sc_num(s, &mm, "alpha", 0, 0, &alpha);
        if (!rc && !(alpha >= 0 && alpha < 1e3)) rc = sc_range(s, &mm, "alpha", ">= 0", alpha);
        if (!rc && alpha > 0 && model != 0) rc = sc_fail(s, FLOE_EINVAL, mv, "%s: alpha is a pmb option", fm);
        /* PMB elastic-perfectly-plastic bonds (003 eq 6): yield stretches (magnitudes) */
        double ycomp = 0, yten = 0;
        int plane = 0;
        static const char *const planes[] = {"stress", "strain", NULL};
        if (!rc) rc = sc_num(s, &mm, "yield_compression", 0, 0, &ycomp);
        if (!rc && !(ycomp >= 0 && isfinite(ycomp))) rc = sc_range(s, &mm, "yield_compression", ">= 0 (a stretch magnitude)", ycomp);
        if (!rc) rc = sc_num(s, &mm, "yield_tension", 0, 0, &yten);
        if (!rc && !(yten >= 0 && isfinite(yten))) rc = sc_range(s, &mm, "yield_tension", ">= 0 (a stretch)", yten);
        if (!rc && (ycomp > 0 || yten > 0) && model != 0)
            rc = sc_fail(s, FLOE_EINVAL, mv, "%s: yield_compression / yield_tension are pmb options", fm);
        if (!rc && (ycomp > 0 || yten > 0) && alpha > 0)
            rc = sc_fail(s, FLOE_EINVAL, mv, "%s: plastic bonds and alpha cannot be combined", fm);
        if (!rc) rc = sc_enum(s, &mm, "plane", planes, 0, &plane);
        if (!rc && plane != 0 && s->dim != 2) rc = sc_fail(s, FLOE_EINVAL, mv, "%s: plane is a 2D option", fm);
        if (!rc && !(K > 0) && !(s->dim == 2 && model == 0 && E > 0))
            rc = sc_fail(s, FLOE_EINVAL, mv, "%s: bulk_modulus > 0 is required%s", fm,
                         s->dim == 2 ? " (2D PMB: or young)" : "");
        if (!rc && model == 1 && !(G > 0)) rc = sc_fail(s, FLOE_EINVAL, mv, "%s: lps needs shear_modulus > 0", fm);
        if (!rc && (sc_ < 0 || Gc < 0)) rc = sc_fail(s, FLOE_EINVAL, mv, "%s: critical_stretch and fracture_energy must be >= 0", fm);
        if (!rc && sc_ > 0 && Gc > 0) rc = sc_fail(s, FLOE_EINVAL, mv, "%s: give critical_stretch or fracture_energy, not both", fm);
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
            floe_pd_material pm = model == 0 ? floe_pd_material_pmb(rho, K, sc_)
                                             : floe_pd_material_lps(rho, K, G, sc_, inf ? FLOE_PD_W_GAUSS : FLOE_PD_W_ONE);
            if (model == 0 && s->dim == 2 && E > 0) pm.E = E;
            pm.G_c = Gc;
            pm.alpha = alpha;
            pm.yield_compression = ycomp;
            pm.yield_tension = yten;
            pm.plane = plane ? FLOE_PD_PLANE_STRAIN : FLOE_PD_PLANE_STRESS;
            int c = floe_pd_set_material(b, &pm);
            if (c) rc = sc_fail(s, c, mv, "%s: %s", fm, c == FLOE_ENOTSUP ? "not available in this dimension" : "invalid values");
        }
        int corr = 1;
        if (!rc) rc = sc_bool(s, &m, "surface_correction", 1, &corr);
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
static int sc_check_pairs(sc *s)
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

/* ------------------------------------------------------------------------------------ */
/* Outputs                                                                               */

static int sc_mkdir_p(const char *dir)
{
    char buf[1024];
    size_t n = strlen(dir);
    if (n == 0 || n >= sizeof buf) return -1;
    memcpy(buf, dir, n + 1);
    for (size_t i = 1; i <= n; i++) {
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -1;
            buf[i] = c;
        }
    }
    struct stat st;
    return stat(dir, &st) == 0 && S_ISDIR(st.st_mode) ? 0 : -1;
}

static const char *const sc_output_types[] = {"vtk", "csv", "energy", "stress", "tracker", NULL};

static int sc_parse_outputs(sc *s, struct fy_node *seq, struct fy_node *key, const char *outdir,
                            int with_outputs)
{
    static const char *const keys_by_type[5][8] = {
        {"type", "every", "interval", "prefix", "ascii", NULL},
        {"type", "every", "interval", "file", NULL},
        {"type", "every", "interval", "file", NULL},
        {"type", "every", "interval", "file", "group", "volume", NULL},
        {"type", "every", "interval", "file", "particles", "walls", NULL},
    };
    static const char *const keys_all[] = {"type", "every", "interval", "prefix", "ascii", "file",
                                           "group", "volume", "particles", "walls", NULL};
    static const char *const defaults[] = {"frame", "particles.csv", "energy.csv", "stress.csv",
                                           "track.csv"};
    if (!seq) return FLOE_OK;
    if (sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, sc_is_missing(seq) ? key : seq,
                       "outputs must be a list of {type: vtk|csv|energy|stress|tracker, ...}");
    int n = fy_node_sequence_item_count(seq);
    s->outs = calloc((size_t)(n ? n : 1), sizeof *s->outs);
    if (!s->outs) return sc_fail(s, FLOE_ENOMEM, key, "out of memory");
    if (with_outputs && n > 0 && sc_mkdir_p(outdir) != 0)
        return sc_fail(s, FLOE_EIO, key, "cannot create the output directory '%s': %s", outdir,
                       strerror(errno));
    void *it = NULL;
    struct fy_node *e;
    int i = 0;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        char what[32];
        snprintf(what, sizeof what, "outputs[%d]", i);
        sc_map m = {e, e, ""};
        snprintf(m.what, sizeof m.what, "%s", what);
        if (!fy_node_is_mapping(e))
            return sc_fail(s, FLOE_EPARSE, e, "%s must be a mapping ({type: ..., every: N, ...}), got %s", what,
                           sc_is_missing(e) ? "nothing" : sc_type_name(e));
        /* type: a built-in output or one registered by a plugin (read by its schema) */
        int type = -1;
        const char *tname;
        struct fy_node *tat;
        FLOE_TRY(sc_str(s, &m, "type", 1, NULL, &tname, &tat));
        for (int q = 0; sc_output_types[q]; q++)
            if (!strcmp(tname, sc_output_types[q])) type = q;
        const floe_registry_entry *ent = floe_registry_find(FLOE_KIND_OBSERVER, tname);
        if (!ent) {
            const char *names[128];
            int nn = 0;
            for (; nn < floe_registry_count(FLOE_KIND_OBSERVER) && nn < 128; nn++)
                names[nn] = floe_registry_at(FLOE_KIND_OBSERVER, nn)->name;
            char sug[1024];
            sc_suggest(sug, sizeof sug, tname, names, nn);
            return sc_fail(s, FLOE_EINVAL, tat, "%s.type: unknown value '%s'%s", what, tname, sug);
        }
        void *uparams = NULL; /* a registered output's parameters */
        if (type < 0) {
            char label[96];
            snprintf(label, sizeof label, "type %s", ent->name);
            uparams = calloc(1, ent->params_size);
            if (!uparams) return sc_fail(s, FLOE_ENOMEM, e, "out of memory");
            int rc = sc_read_schema(s, &m, ent, label, "type|every|interval|file", uparams);
            if (rc) { free(uparams); return rc; }
        } else {
            FLOE_TRY(sc_map_open(s, e, e, what, keys_all, &m));
            int nv = 0;
            while (keys_by_type[type][nv]) nv++;
            void *it2 = NULL;
            struct fy_node_pair *p;
            while ((p = fy_node_mapping_iterate(e, &it2))) {
                const char *ks = sc_text(fy_node_pair_key(p));
                int ok = 0;
                for (int j = 0; j < nv; j++) ok |= !strcmp(ks, keys_by_type[type][j]);
                if (!ok) {
                    char sug[512];
                    sc_suggest(sug, sizeof sug, ks, keys_by_type[type], nv);
                    return sc_fail(s, FLOE_EPARSE, fy_node_pair_key(p),
                                   "unknown key '%s' in %s (type %s)%s", ks, what,
                                   sc_output_types[type], sug);
                }
            }
        }
        sc_output *o = &s->outs[i];
        snprintf(o->type, sizeof o->type, "%s", tname);
        o->uparams = uparams; /* freed with the loader */
        o->ent = ent;
        char udefault[160];
        snprintf(udefault, sizeof udefault, "%s.csv", tname);
        if (sc_has(&m, "every") && sc_has(&m, "interval"))
            return sc_fail(s, FLOE_EPARSE, sc_get(&m, "interval", NULL),
                           "%s: give either every (steps) or interval (seconds), not both", what);
        FLOE_TRY(sc_long(s, &m, "every", 0, 100, &o->every));
        FLOE_TRY(sc_num(s, &m, "interval", 0, 0.0, &o->interval));
        if (sc_has(&m, "interval")) {
            if (!(o->interval > 0)) return sc_range(s, &m, "interval", "> 0 (s)", o->interval);
            /* the world steps next_time by interval until it passes t: an interval below the
             * time resolution would never get there */
            if (!(o->interval >= 1e-9 * s->duration))
                return sc_fail(s, FLOE_EINVAL, sc_get(&m, "interval", NULL),
                               "%s.interval %g s is below the time resolution of this run (1e-9 x "
                               "time.duration = %g s)", what, o->interval, 1e-9 * s->duration);
            o->every = 0;
        } else if (o->every < 1) {
            return sc_range(s, &m, "every", ">= 1 (steps)", (double)o->every);
        }
        const char *name;
        struct fy_node *name_at;
        FLOE_TRY(sc_str(s, &m, type == 0 ? "prefix" : "file", 0, type < 0 ? udefault : defaults[type], &name, &name_at));
        if (!*name || (type == 0 && strchr(name, '/')))
            return sc_fail(s, FLOE_EINVAL, name_at, "%s.%s: '%s' is not a valid %s", what,
                           type == 0 ? "prefix" : "file", name, type == 0 ? "prefix" : "file name");
        if (type == 0 || name[0] != '/')
            snprintf(o->target, sizeof o->target, "%s/%s", outdir, name);
        else
            snprintf(o->target, sizeof o->target, "%s", name);
        /* two writers of one file would interleave and corrupt it */
        {
            const char *nm = name;
            while (nm[0] == '.' && nm[1] == '/') nm += 2;
            if (type == 0 || nm[0] != '/') snprintf(o->file, sizeof o->file, "%s/%s%s", outdir, nm, type == 0 ? ".pvd" : "");
            else snprintf(o->file, sizeof o->file, "%s", nm);
            o->name_at = name_at;
            for (int j = 0; j < i; j++) {
                if (strcmp(s->outs[j].file, o->file) != 0) continue;
                int l = 0, c = 0;
                struct fy_node *prev = s->outs[j].name_at ? s->outs[j].name_at
                                                          : fy_node_sequence_get_by_index(seq, j);
                sc_loc(s, prev, &l, &c);
                return sc_fail(s, FLOE_EINVAL, name_at ? name_at : e,
                               "%s writes %s, which outputs[%d] (line %d, column %d) writes too: give "
                               "each output its own %s", what, o->file, j, l, c,
                               type == 0 ? "prefix" : "file");
            }
        }

        long group = -1;
        double volume = 0;
        int ascii = 0;
        if (type == 0) FLOE_TRY(sc_bool(s, &m, "ascii", 0, &ascii));
        int *ids = NULL, nids = 0;
        if (type == 3) {
            struct fy_node *gk;
            struct fy_node *gv = sc_get(&m, "group", &gk);
            if (gv && !(sc_text(gv) && !strcmp(sc_text(gv), "all"))) {
                char f[64];
                snprintf(f, sizeof f, "%s.group", what);
                FLOE_TRY(sc_node_long(s, gv, gk, f, &group));
                if (group < 0 || group >= s->nbody_entries)
                    return sc_fail(s, FLOE_EINVAL, gv,
                                   "%s must be 'all' or a body index in [0, %d] (got %ld)", f,
                                   s->nbody_entries - 1, group);
            }
            FLOE_TRY(sc_num(s, &m, "volume", 0, 0.0, &volume));
            if (!(volume >= 0)) return sc_range(s, &m, "volume", ">= 0 (0 = bounding box)", volume);
        }
        if (type == 4) {
            /* particles: body particle ids; walls: wall indices (world id nparticles + i) */
            static const char *const lists[2] = {"particles", "walls"};
            struct fy_node *lv[2], *lk[2];
            int cnt[2] = {0, 0};
            for (int l = 0; l < 2; l++) {
                lv[l] = sc_get(&m, lists[l], &lk[l]);
                if (!lv[l]) continue;
                if (lv[l] == lk[l] || !fy_node_is_sequence(lv[l]) ||
                    fy_node_sequence_item_count(lv[l]) == 0)
                    return sc_fail(s, FLOE_EPARSE, lv[l] == lk[l] ? lk[l] : lv[l],
                                   "%s.%s: expected a non-empty list of %s", what, lists[l],
                                   l ? "wall indices" : "particle ids");
                cnt[l] = fy_node_sequence_item_count(lv[l]);
            }
            if (!lv[0] && !lv[1])
                return sc_fail(s, FLOE_EPARSE, e, "%s: give particles (a list of particle ids) "
                               "and/or walls (a list of wall indices)", what);
            ids = malloc((size_t)(cnt[0] + cnt[1]) * sizeof *ids);
            if (!ids) return sc_fail(s, FLOE_ENOMEM, e, "out of memory");
            for (int l = 0; l < 2; l++)
                for (int j = 0; j < cnt[l]; j++) {
                    struct fy_node *c = fy_node_sequence_get_by_index(lv[l], j);
                    char f2[96];
                    snprintf(f2, sizeof f2, "%s.%s[%d]", what, lists[l], j);
                    long id = -1;
                    long lim = l ? s->nwalls : s->nparticles;
                    int rc = sc_node_long(s, c, NULL, f2, &id);
                    if (rc == FLOE_OK && (id < 0 || id >= lim))
                        rc = sc_fail(s, FLOE_EINVAL, c, "%s: %s %ld does not exist (the scene has "
                                     "%ld %s, 0..%ld)", f2, l ? "wall" : "particle", id, lim,
                                     l ? "walls" : "particles", lim - 1);
                    if (rc != FLOE_OK) { free(ids); return rc; }
                    ids[nids++] = (int)(l ? s->nparticles + id : id);
                }
        }
        if (with_outputs) {
            char oerr[512] = "";
            floe_observer *obs = NULL;
            if (type < 0) {
                floe_output_ctx octx = {outdir, o->target, s->w, s->dim};
                obs = ((floe_output_create_fn)ent->create)(uparams, &octx, oerr, sizeof oerr);
            }
            switch (type) {
            case 0:
                obs = floe_vtk_writer_create(outdir, name, oerr, sizeof oerr);
                if (obs && ascii) floe_vtk_writer_set_ascii(obs, 1);
                break;
            case 1: obs = floe_csv_writer_create(o->target, oerr, sizeof oerr); break;
            case 2: obs = floe_energy_tracker_create(o->target, oerr, sizeof oerr); break;
            case 3: obs = floe_collection_tracker_create(o->target, (int)group, volume, oerr,
                                                         sizeof oerr);
                break;
            case 4: obs = floe_particle_tracker_create(o->target, ids, nids, oerr, sizeof oerr); break;
            }
            free(ids);
            if (!obs)
                return sc_fail(s, FLOE_EIO, e, "%s (%s): %s", what, o->type,
                               oerr[0] ? oerr : "could not create the output");
            obs->period_steps = o->every;
            obs->period_time = o->every ? 0.0 : o->interval;
            int rc = floe_world_add_observer(s->w, obs);
            if (rc != FLOE_OK) {
                floe_observer_destroy(obs);
                return sc_fail(s, rc < 0 ? -rc : rc, e, "%s: %s", what,
                               floe_world_last_error(s->w));
            }
        } else {
            free(ids);
        }
        s->nouts = ++i;
        s->nobservers = i;
    }
    return FLOE_OK;
}

/* ------------------------------------------------------------------------------------ */
/* Summary                                                                               */

typedef struct sc_buf { char *p; size_t len, n; } sc_buf;

static void sc_cat(sc_buf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void sc_cat(sc_buf *b, const char *fmt, ...)
{
    if (b->n + 1 >= b->len) return;
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->p + b->n, b->len - b->n, fmt, ap);
    va_end(ap);
    if (k < 0) return;
    b->n += (size_t)k;
    if (b->n >= b->len) {
        b->n = b->len - 1;
        if (b->len > 5) memcpy(b->p + b->len - 5, "...\n", 5);
    }
}

/* "key value unit, ..." of a component's parameters (given ones and defaults) */
static void sc_params_text(char *buf, size_t len, const floe_registry_entry *ent, const void *params)
{
    size_t k = 0;
    buf[0] = 0;
    for (int q = 0; q < ent->nparams && k < len; q++) {
        const floe_param *p = &ent->params[q];
        const char *at = (const char *)params + p->offset;
        if ((p->flags & FLOE_PARAM_REQUIRED) == 0 && !floe_params_given(ent, params, p->key) &&
            p->type != FLOE_PARAM_REAL)
            continue; /* defaults of flags and names are not news */
        if (!floe_params_given(ent, params, p->key) && p->type == FLOE_PARAM_REAL && p->def == 0) continue;
        const char *sep = k ? ", " : "", *u = p->unit && p->unit[0] ? " " : "", *un = p->unit ? p->unit : "";
        int iv;
        double x, v3[3];
        switch (p->type) {
        case FLOE_PARAM_REAL:
            memcpy(&x, at, sizeof x);
            k += (size_t)snprintf(buf + k, len - k, "%s%s %g%s%s", sep, p->key, x, u, un);
            break;
        case FLOE_PARAM_VEC3:
            memcpy(v3, at, sizeof v3);
            k += (size_t)snprintf(buf + k, len - k, "%s%s [%g, %g, %g]%s%s", sep, p->key, v3[0], v3[1], v3[2], u, un);
            break;
        case FLOE_PARAM_STRING:
            k += (size_t)snprintf(buf + k, len - k, "%s%s %s", sep, p->key, at);
            break;
        default:
            memcpy(&iv, at, sizeof iv);
            if (p->type == FLOE_PARAM_BOOL) k += (size_t)snprintf(buf + k, len - k, "%s%s %s", sep, p->key, iv ? "true" : "false");
            else k += (size_t)snprintf(buf + k, len - k, "%s%s %d%s%s", sep, p->key, iv, u, un);
        }
    }
}

static void sc_summary(sc *s, const char *name, const char *outdir, int with_outputs,
                       floe_scene_info *info)
{
    sc_buf b = {info->summary, sizeof info->summary, 0};
    info->summary[0] = '\0';
    floe_world *w = s->w;
    if (name[0]) sc_cat(&b, "scene:      %s (%s)\n", name, s->path);
    else sc_cat(&b, "scene:      %s\n", s->path);
    sc_cat(&b, "dimension:  %d%s\n", s->dim,
           s->dim == 2 ? (w->def.mass_2d_area ? " (motion in x-y; masses from area, per metre)"
                                               : " (motion in x-y; masses of the 3D shapes)")
                       : "");
    sc_cat(&b, "particles:  %d (%d spheres, %d other shapes) in %d body entr%s; walls: %d\n",
           s->nparticles, s->nspheres, s->nboxes, s->nbody_entries,
           s->nbody_entries == 1 ? "y" : "ies", s->nwalls);
    for (int e = 0; e < s->nbody_entries && e < 12; e++)
        sc_cat(&b, "  body %d: particles %d..%d\n", e, s->entry_first[e],
               s->entry_first[e] + s->entry_count[e] - 1);
    if (s->nbody_entries > 12) sc_cat(&b, "  ... %d more body entries\n", s->nbody_entries - 12);
    for (int k = 0; k < floe_world_pd_body_count(w); k++) {
        int f0;
        const floe_pd_body *pb = floe_world_pd_body(w, k, &f0);
        sc_cat(&b, "  peridynamics %d: particles %d..%d (body %d in outputs), %s, %lld bonds (%.1f per point), "
               "horizon %g m, critical stretch %g, nodal dt %.3g s\n",
               k, f0, f0 + pb->n - 1, -2 - k, pb->ops->name, (long long)pb->nbond, 2.0 * (double)pb->nbond / pb->n,
               pb->delta, pb->s_c, floe_pd_dt_nodal(pb));
        if (pb->ncut > 0) sc_cat(&b, "    cracks cut %lld bonds\n", (long long)pb->ncut);
        if (pb->nbridge > 0)
            sc_cat(&b, "    WARNING: %lld bonds bridge a removed region (region.remove narrower than the horizon "
                   "%g m, e.g. at (%g, %g, %g)): it does not separate the material; cut them with cracks\n",
                   (long long)pb->nbridge, pb->delta, pb->bridge_at[0], pb->bridge_at[1], pb->bridge_at[2]);
    }
    for (int q = 0; q < w->npd_bc; q++) { /* PD boundary regions */
        static const char *const kinds[] = {"?", "fixed", "velocity", "displacement", "body force"};
        static const char *const ramps[] = {"", ", linear ramp", ", exponential ramp"};
        const floe_pd_bc_rec *r = w->pd_bc[q];
        int k = r->def.kind >= 1 && r->def.kind <= 4 ? r->def.kind : 0;
        int rp = r->def.ramp >= 0 && r->def.ramp <= 2 ? r->def.ramp : 0;
        sc_cat(&b, "  boundary %d: peridynamics %d, %d points, %s", q, r->body, r->n, kinds[k]);
        if (k >= 2 && !r->def.force_fn)
            sc_cat(&b, " (%g, %g, %g)", r->def.value[0], r->def.value[1], r->def.value[2]);
        if (k == 4 && r->def.force_fn) sc_cat(&b, " (callback)");
        if (k >= 2) sc_cat(&b, "%s", ramps[rp]);
        if (rp) sc_cat(&b, " over %g s", r->def.ramp_time);
        sc_cat(&b, "\n");
    }
    if (floe_world_beam_bond_count(w) > 0)
        sc_cat(&b, "  beam bonds: %d (%d broken), critical dt %.3g s\n", floe_world_beam_bond_count(w),
               floe_world_beam_broken_count(w), floe_world_beam_critical_dt(w));
    sc_cat(&b, "materials:\n");
    for (int i = 0; i < s->nmats && i < 16; i++) {
        const floe_material *m = &s->mats[i].m;
        if (s->mats[i].has_young)
            sc_cat(&b, "  %s: density %g kg/m^3, E %g Pa, nu %g\n", m->name, m->density, m->young,
                   m->poisson);
        else
            sc_cat(&b, "  %s: density %g kg/m^3\n", m->name, m->density);
    }
    sc_cat(&b, "laws:\n");
    for (int i = 0; i < s->nlaws && i < 32; i++) {
        const sc_law *L = &s->laws[i];
        char line[512];
        sc_params_text(line, sizeof line, L->ent, L->params);
        sc_cat(&b, "  %s-%s: %s%s%s\n", s->mats[L->a].m.name, s->mats[L->b].m.name,
               L->ent->title ? L->ent->title : L->ent->name, line[0] ? ", " : "", line);
    }
    sc_cat(&b, "detectors:  ");
    int first = 1;
    const char *pairs[6];
    int np = 0;
    if (s->nspheres >= 2) pairs[np++] = "sphere-sphere analytic";
    if (s->nspheres && s->nwalls) pairs[np++] = "sphere-wall analytic";
    if (s->nspheres && s->nboxes) pairs[np++] = "sphere-other by the other shape's SDF at the centre";
    if (s->nboxes && s->nwalls) pairs[np++] = "shape-wall by vertices or support point";
    if (s->nboxes >= 2) pairs[np++] = "shape-shape by the polytope LP or ADMM";
    for (int i = 0; i < np; i++, first = 0) sc_cat(&b, "%s%s", first ? "" : ", ", pairs[i]);
    sc_cat(&b, "%s\n", first ? "none (no pair of particles can touch)" : "");
    sc_cat(&b, "gravity:    (%g, %g, %g) m/s^2\n", w->def.gravity[0], w->def.gravity[1],
           w->def.gravity[2]);
    double dtc = floe_world_critical_dt(w), dt = floe_world_dt(w);
    floe_dt_estimates est;
    floe_world_dt_estimates(w, &est);
    sc_cat(&b, "time step:  critical dt estimate %.4g s (%s, particle %d); dt %.4g s (%s)\n", dtc,
           est.limiting >= 0 ? floe_dt_kind_name(est.limiting) : "none", est.limiting_particle, dt,
           s->dt_auto ? "automatic" : "given");
    if (s->dt_auto && w->def.accuracy > 0 && est.accuracy_dt <= dt)
        sc_cat(&b, "            = the step for time.accuracy %g (safety %g x critical would be %.4g s)\n",
               w->def.accuracy, s->safety, s->safety * dtc);
    else if (s->dt_auto) sc_cat(&b, "            = safety %g x critical\n", s->safety);
    else if (dt > dtc) sc_cat(&b, "            WARNING: dt is above the critical estimate "
                               "(allow_unstable_dt: true)\n");
    if (est.err1 > 0 || est.err2 > 0)
        sc_cat(&b, "            predicted restitution error %.2g (relative, the laws' error model)%s\n",
               est.predicted_error, w->def.accuracy > 0 ? "" : "; time.accuracy sets a target");
    sc_cat(&b, "integrator: %s", floe_integrator_name(w->def.integrator));
    if (w->def.adaptive)
        sc_cat(&b, ", adaptive steps in [%.4g, %.4g] s (velocity tolerance %g, penetration tolerance %g)",
               w->dt_lo, w->dt_hi, w->def.adapt_velocity_tol, w->def.adapt_depth_tol);
    if (w->def.pd_dem == FLOE_PD_DEM_STAGGERED && floe_world_pd_body_count(w) > 0)
        sc_cat(&b, ", staggered PD-DEM: PD step %.4g s (%s %d)", w->pd_every > 1 ? w->pd_every * dt : dt / w->pd_sub,
               w->pd_every > 1 ? "every" : "substeps", w->pd_every > 1 ? w->pd_every : w->pd_sub);
    sc_cat(&b, "\n");
    double nsteps = dt > 0 ? ceil(s->duration / dt - 1e-9) : 0;
    sc_cat(&b, "duration:   %g s = %s%.0f steps\n", s->duration, w->def.adaptive ? "at most " : "",
           w->def.adaptive && w->dt_lo > 0 ? ceil(s->duration / w->dt_lo - 1e-9) : nsteps);
    sc_cat(&b, "memory:     about %.3g MB (estimate; this machine has %.3g GB)\n", sc_mem_estimate(s, 0) / 1e6,
           sc_phys_mem() / 1e9);
    if (s->nstates) {
        sc_cat(&b, "states:     %d growing radi%s (particle", s->nstates, s->nstates == 1 ? "us" : "i");
        for (int i = 0; i < s->ngrow_listed; i++) sc_cat(&b, "%s%d", i ? ", " : " ", s->grow_particle[i]);
        sc_cat(&b, "%s)\n", s->nstates > s->ngrow_listed ? ", ..." : "");
    }
    if (s->nouts) {
        sc_cat(&b, "outputs%s:\n", with_outputs ? "" : " (not opened by check)");
        for (int i = 0; i < s->nouts; i++) {
            const sc_output *o = &s->outs[i];
            if (o->every) sc_cat(&b, "  %s every %ld steps -> %s%s\n", o->type, o->every, o->target,
                                 !strcmp(o->type, "vtk") ? "_NNNNNN.vtu" : "");
            else sc_cat(&b, "  %s every %g s -> %s%s\n", o->type, o->interval, o->target,
                        !strcmp(o->type, "vtk") ? "_NNNNNN.vtu" : "");
        }
    } else {
        sc_cat(&b, "outputs:    none (output directory %s unused)\n", outdir);
    }
}

/* ------------------------------------------------------------------------------------ */
/* Beam bonds (contact/bonds/floe_beam.h, issue #5): `bonds:` a list of bond sets, each bonding   */
/* the particles within a radius (floe_world_add_beam_bonds)                              */

static int sc_parse_bonds(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys[] = {"young", "poisson", "radius_factor", "max_distance", "timoshenko",
                                       "shear_coefficient", "area", "inertia", "polar", "section_modulus",
                                       "radius_ratio", "thickness", "damping_ratio", "tensile_strength",
                                       "tensile_sd", "shear_strength", "shear_sd", "seed", "group", NULL};
    if (!seq) return FLOE_OK;
    if (sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, sc_is_missing(seq) ? key : seq,
                       "bonds must be a list of {young, radius_factor, ...} (beam bonds)");
    void *it = NULL;
    struct fy_node *e;
    for (int i = 0; (e = fy_node_sequence_iterate(seq, &it)); i++) {
        char what[32];
        snprintf(what, sizeof what, "bonds[%d]", i);
        sc_map m;
        FLOE_TRY(sc_map_open(s, e, e, what, keys, &m));
        floe_beam_params bp = floe_default_beam_params();
        double rf = 1.01;
        long seed = 1, group = 0;
        int has_group = sc_has(&m, "group");
        FLOE_TRY(sc_num(s, &m, "young", 1, 0, &bp.young));
        FLOE_TRY(sc_num(s, &m, "poisson", 0, bp.poisson, &bp.poisson));
        FLOE_TRY(sc_num(s, &m, "radius_factor", 0, rf, &rf));
        FLOE_TRY(sc_num(s, &m, "max_distance", 0, 0, &bp.max_distance));
        FLOE_TRY(sc_bool(s, &m, "timoshenko", 0, &bp.timoshenko));
        FLOE_TRY(sc_num(s, &m, "shear_coefficient", 0, 0, &bp.shear_coefficient));
        FLOE_TRY(sc_num(s, &m, "area", 0, 0, &bp.area));
        FLOE_TRY(sc_num(s, &m, "inertia", 0, 0, &bp.inertia));
        FLOE_TRY(sc_num(s, &m, "polar", 0, 0, &bp.polar));
        FLOE_TRY(sc_num(s, &m, "section_modulus", 0, 0, &bp.section_modulus));
        FLOE_TRY(sc_num(s, &m, "radius_ratio", 0, bp.radius_ratio, &bp.radius_ratio));
        FLOE_TRY(sc_num(s, &m, "thickness", 0, bp.thickness, &bp.thickness));
        FLOE_TRY(sc_num(s, &m, "damping_ratio", 0, 0, &bp.damping_ratio));
        FLOE_TRY(sc_num(s, &m, "tensile_strength", 0, 0, &bp.tensile_strength));
        FLOE_TRY(sc_num(s, &m, "tensile_sd", 0, 0, &bp.tensile_sd));
        FLOE_TRY(sc_num(s, &m, "shear_strength", 0, 0, &bp.shear_strength));
        FLOE_TRY(sc_num(s, &m, "shear_sd", 0, 0, &bp.shear_sd));
        FLOE_TRY(sc_long(s, &m, "seed", 0, 1, &seed));
        FLOE_TRY(sc_long(s, &m, "group", 0, 0, &group));
        if (seed < 0) return sc_range(s, &m, "seed", ">= 0", (double)seed);
        bp.seed = (unsigned long long)seed;
        bp.group = has_group ? (int)group : FLOE_BEAM_ALL_GROUPS;
        if (!(rf > 0)) return sc_range(s, &m, "radius_factor", "> 0", rf);
        int rc = floe_world_add_beam_bonds(s->w, rf, &bp);
        if (rc < 0) return sc_fail(s, -rc, e, "%s: %s", what, floe_world_last_error(s->w));
        if (rc == 0)
            return sc_fail(s, FLOE_EINVAL, e, "%s: no pair of particles is within reach (radius_factor %g x (R_i + R_j)%s)",
                           what, rf, bp.max_distance > 0 ? " or max_distance" : "");
    }
    return FLOE_OK;
}

/* ------------------------------------------------------------------------------------ */
/* Loading                                                                               */

static const char *const sc_root_keys[] = {"name", "description", "dimension", "time", "gravity",
                                           "neighbor", "contact_detection", "mass_2d", "materials", "laws",
                                           "walls", "bodies", "peridynamics", "outputs", "bonds", "checks", "plugins",
                                           NULL};

/* checks: {energy: stop | warn | off, energy_tolerance} (the energy watchdog, floe_world.h) */
static int sc_checks(sc *s, const sc_map *r, floe_world_def *def)
{
    static const char *const ck_keys[] = {"energy", "energy_tolerance", NULL};
    static const char *const modes[] = {"stop", "warn", "off", NULL};
    struct fy_node *ck, *cv = sc_get(r, "checks", &ck);
    if (!cv) return FLOE_OK;
    sc_map cm;
    FLOE_TRY(sc_map_open(s, cv == ck ? NULL : cv, ck, "checks", ck_keys, &cm));
    FLOE_TRY(sc_enum(s, &cm, "energy", modes, FLOE_CHECK_STOP, &def->energy_check));
    FLOE_TRY(sc_num(s, &cm, "energy_tolerance", 0, def->energy_check_tol, &def->energy_check_tol));
    if (!(def->energy_check_tol > 0 && def->energy_check_tol < 1))
        return sc_range(s, &cm, "energy_tolerance", "in (0, 1) (fraction of the energy scale)", def->energy_check_tol);
    return FLOE_OK;
}

/* time.integrator, time.adaptive, time.pd_dem (docs/scene-format.md, docs/integrators.md) */
static int sc_time_integration(sc *s, const sc_map *tm, floe_world_def *def)
{
    static const char *const integ[] = {"velocity_verlet", "leapfrog", "rk2", NULL};
    static const char *const schemes[] = {"monolithic", "staggered", NULL};
    static const char *const ad_keys[] = {"dt_min", "dt_max", "velocity_tolerance", "penetration_tolerance", NULL};
    static const char *const pd_keys[] = {"scheme", "substeps", "every", NULL};
    FLOE_TRY(sc_enum(s, tm, "integrator", integ, FLOE_VELOCITY_VERLET, &def->integrator));
    struct fy_node *ak, *av = sc_get(tm, "adaptive", &ak);
    if (av && av != ak && fy_node_is_mapping(av)) {
        sc_map am;
        FLOE_TRY(sc_map_open(s, av, ak, "time.adaptive", ad_keys, &am));
        def->adaptive = 1;
        FLOE_TRY(sc_num(s, &am, "dt_min", 0, 0.0, &def->dt_min));
        if (!(def->dt_min >= 0)) return sc_range(s, &am, "dt_min", ">= 0 s (0 = 1e-3 x dt_max)", def->dt_min);
        FLOE_TRY(sc_num(s, &am, "dt_max", 0, 0.0, &def->dt_max));
        if (!(def->dt_max >= 0)) return sc_range(s, &am, "dt_max", ">= 0 s (0 = the critical estimate)", def->dt_max);
        if (def->dt_min > 0 && def->dt_max > 0 && def->dt_min > def->dt_max)
            return sc_range(s, &am, "dt_min", "<= dt_max", def->dt_min);
        FLOE_TRY(sc_num(s, &am, "velocity_tolerance", 0, def->adapt_velocity_tol, &def->adapt_velocity_tol));
        if (!(def->adapt_velocity_tol > 0 && def->adapt_velocity_tol < 1))
            return sc_range(s, &am, "velocity_tolerance", "in (0, 1)", def->adapt_velocity_tol);
        FLOE_TRY(sc_num(s, &am, "penetration_tolerance", 0, def->adapt_depth_tol, &def->adapt_depth_tol));
        if (!(def->adapt_depth_tol > 0 && def->adapt_depth_tol < 1))
            return sc_range(s, &am, "penetration_tolerance", "in (0, 1)", def->adapt_depth_tol);
    } else {
        FLOE_TRY(sc_bool(s, tm, "adaptive", 0, &def->adaptive));
    }
    struct fy_node *pk, *pv = sc_get(tm, "pd_dem", &pk);
    if (pv) {
        sc_map pm;
        FLOE_TRY(sc_map_open(s, pv == pk ? NULL : pv, pk, "time.pd_dem", pd_keys, &pm));
        FLOE_TRY(sc_enum(s, &pm, "scheme", schemes, FLOE_PD_DEM_MONOLITHIC, &def->pd_dem));
        struct fy_node *sk, *sv = sc_get(&pm, "substeps", &sk);
        long sub = 1, every = 1;
        if (sv && sv != sk && sc_text(sv) && !strcmp(sc_text(sv), "auto")) sub = 0;
        else FLOE_TRY(sc_long(s, &pm, "substeps", 0, 1, &sub));
        if (sub < 0 || sub > 100000) return sc_range(s, &pm, "substeps", "in [1, 100000] or auto", (double)sub);
        FLOE_TRY(sc_long(s, &pm, "every", 0, 1, &every));
        if (every < 1 || every > 100000) return sc_range(s, &pm, "every", "in [1, 100000]", (double)every);
        if (sub != 1 && every > 1)
            return sc_fail(s, FLOE_EINVAL, pv, "time.pd_dem: give substeps (PD sub-cycled, dt_PD = dt / m) or every "
                           "(PD every k-th step, dt_PD = k dt), not both");
        if ((sub != 1 || every > 1) && def->pd_dem != FLOE_PD_DEM_STAGGERED)
            return sc_fail(s, FLOE_EINVAL, pv, "time.pd_dem: substeps and every need scheme: staggered");
        def->pd_substeps = (int)sub;
        def->pd_every = (int)every;
    }
    return FLOE_OK;
}

/* Every free particle needs a normal positive mass and inertia whose inverses are finite: a
 * density of 1e-300 gives a subnormal mass, an infinite inverse and NaN at the first step. */
static int sc_check_masses(sc *s)
{
    const floe_particles *p = &s->w->p;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE || !isfinite(p->radius[i])) continue;
        double m = p->mass[i];
        int bad = !(m > 0) || !isnormal(m) || !isfinite(1.0 / m) || !isfinite(m);
        for (int a = 0; a < 3 && !bad; a++) {
            double I = p->inertia[3 * i + a];
            bad = !(I > 0) || !isnormal(I) || !isfinite(1.0 / I) || !isfinite(I);
        }
        if (!bad) continue;
        int mat = p->material[i], entry = -1;
        for (int e = 0; e < s->nbody_entries && entry < 0; e++)
            if (i >= s->entry_first[e] && i < s->entry_first[e] + s->entry_count[e]) entry = e;
        char where[64] = "";
        if (entry >= 0) snprintf(where, sizeof where, " (bodies[%d])", entry);
        return sc_fail(s, FLOE_EINVAL, mat >= 0 && mat < s->nmats ? s->mats[mat].at : NULL,
                       "particle %d%s of material '%s' (density %g kg/m^3) has mass %g kg and inertia "
                       "(%g, %g, %g) kg m^2: not a usable number (its inverse is not finite); check "
                       "the density and the size", i, where, mat >= 0 && mat < s->nmats ? s->mats[mat].m.name : "?", mat >= 0 && mat < s->nmats ? s->mats[mat].m.density : 0.0,
                       m, p->inertia[3 * i], p->inertia[3 * i + 1], p->inertia[3 * i + 2]);
    }
    return FLOE_OK;
}

/* duration / dt must be a step count a run can reach (1e30 s would overflow the count) */
static int sc_check_steps(sc *s, const sc_map *tm, double dt, const char *which)
{
    double n = s->duration / dt;
    if (dt > 0 && !(n <= SC_MAX_STEPS))
        return sc_fail(s, FLOE_EINVAL, sc_get(tm, "duration", NULL),
                       "time.duration %g s is %.3g steps of %g s (%s): more than 1e12 steps", s->duration,
                       n, dt, which);
    return FLOE_OK;
}

/* plugins: [path.so, ...] (relative to the scene file): shared libraries whose init
 * registers shapes, laws or outputs that the rest of the scene names (core/scene/plugin.c) */
static int sc_parse_plugins(sc *s, const sc_map *r)
{
    struct fy_node *pk, *pv = sc_get(r, "plugins", &pk);
    if (!pv) return FLOE_OK;
    if (pv == pk || !fy_node_is_sequence(pv))
        return sc_fail(s, FLOE_EPARSE, pv == pk ? pk : pv, "plugins must be a list of shared-library paths "
                       "([./my_plugin.so, ...]), got %s", pv == pk ? "nothing" : sc_type_name(pv));
#if defined(FLOE_SCENE_NO_PLUGINS)
    /* the fuzzer's build: a scene must not make the loader run code from arbitrary files */
    return sc_fail(s, FLOE_ENOTSUP, pk, "plugins are disabled in this build (FLOE_SCENE_NO_PLUGINS)");
#endif
    void *it = NULL;
    struct fy_node *e;
    int i = 0;
    while ((e = fy_node_sequence_iterate(pv, &it))) {
        const char *file = sc_text(e);
        if (!file || !file[0] || !fy_node_is_scalar(e))
            return sc_fail(s, FLOE_EPARSE, e, "plugins[%d]: expected a path to a shared library", i);
        char path[1024];
        const char *slash = s->path ? strrchr(s->path, '/') : NULL;
        if (file[0] != '/' && slash)
            snprintf(path, sizeof path, "%.*s/%s", (int)(slash - s->path), s->path, file);
        else if (file[0] != '/' && !strchr(file, '/'))
            snprintf(path, sizeof path, "./%s", file); /* dlopen searches the library path otherwise */
        else
            snprintf(path, sizeof path, "%s", file);
        char err[768];
        int rc = floe_plugin_load(path, err, sizeof err);
        if (rc) return sc_fail(s, rc, e, "plugins[%d]: %s", i, err);
        i++;
    }
    return FLOE_OK;
}

static int sc_build(sc *s, struct fy_node *root, const char *outdir, int with_outputs,
                    floe_scene_info *info)
{
    static const char *const time_keys[] = {"duration", "dt", "safety", "allow_unstable_dt", "integrator",
                                            "adaptive", "pd_dem", "accuracy", NULL};
    static const char *const nb_keys[] = {"skin", "leaf_size", NULL};
    static const char *const mass2d[] = {"volume", "area", NULL};
    sc_map r;
    FLOE_TRY(sc_map_open(s, root, root, "", sc_root_keys, &r));
    FLOE_TRY(sc_parse_plugins(s, &r));

    const char *name;
    FLOE_TRY(sc_str(s, &r, "name", 0, "", &name, NULL));
    snprintf(info->name, sizeof info->name, "%s", name);
    const char *descr;
    FLOE_TRY(sc_str(s, &r, "description", 0, "", &descr, NULL));

    long dim;
    FLOE_TRY(sc_long(s, &r, "dimension", 0, 3, &dim));
    if (dim != 2 && dim != 3) return sc_range(s, &r, "dimension", "2 or 3", (double)dim);
    s->dim = (int)dim;

    floe_world_def def = floe_default_world_def();
    def.dim = s->dim;

    struct fy_node *tk;
    struct fy_node *tv = sc_get(&r, "time", &tk);
    if (!tv) return sc_fail(s, FLOE_EPARSE, root, "time is required ({duration: seconds})");
    sc_map tm;
    FLOE_TRY(sc_map_open(s, tv == tk ? NULL : tv, tk, "time", time_keys, &tm));
    FLOE_TRY(sc_num(s, &tm, "duration", 1, 0, &s->duration));
    if (!(s->duration > 0)) return sc_range(s, &tm, "duration", "> 0 (s)", s->duration);
    {
        struct fy_node *dk;
        struct fy_node *dv = sc_get(&tm, "dt", &dk);
        s->dt_given = 0;
        if (dv && dv != dk && sc_text(dv) && !strcmp(sc_text(dv), "auto")) {
            s->dt_given = 0;
        } else {
            FLOE_TRY(sc_num(s, &tm, "dt", 0, 0.0, &s->dt_given));
            if (dv && !(s->dt_given > 0))
                return sc_range(s, &tm, "dt", "> 0 s (write dt: auto, or omit dt, for the automatic step)",
                                s->dt_given);
        }
        s->dt_auto = s->dt_given == 0;
    }
    FLOE_TRY(sc_num(s, &tm, "safety", 0, def.dt_safety > 0 ? def.dt_safety : 0.2, &s->safety));
    if (!(s->safety > 0 && s->safety <= 1)) return sc_range(s, &tm, "safety", "in (0, 1]", s->safety);
    FLOE_TRY(sc_bool(s, &tm, "allow_unstable_dt", 0, &def.allow_unstable_dt));
    FLOE_TRY(sc_num(s, &tm, "accuracy", 0, 0.0, &def.accuracy));
    if (sc_has(&tm, "accuracy") && !(def.accuracy > 0 && def.accuracy < 0.5))
        return sc_range(s, &tm, "accuracy", "in (0, 0.5) (relative error of the restitution)", def.accuracy);
    def.dt = s->dt_given;
    def.dt_safety = s->safety;
    FLOE_TRY(sc_time_integration(s, &tm, &def));
    FLOE_TRY(sc_check_steps(s, &tm, def.adaptive ? def.dt_min : s->dt_given,
                            def.adaptive ? "time.adaptive.dt_min" : "time.dt"));

    double g[3];
    FLOE_TRY(sc_vec(s, &r, "gravity", 0, NULL, g));
    FLOE_TRY(sc_check_planar(s, &r, "gravity", g));
    floe_v3_copy(def.gravity, g);

    struct fy_node *nk;
    struct fy_node *nv = sc_get(&r, "neighbor", &nk);
    if (nv) {
        sc_map nm;
        FLOE_TRY(sc_map_open(s, nv == nk ? NULL : nv, nk, "neighbor", nb_keys, &nm));
        FLOE_TRY(sc_num(s, &nm, "skin", 0, 0.0, &def.skin));
        if (!(def.skin >= 0)) return sc_range(s, &nm, "skin", ">= 0 (m; 0 = automatic)", def.skin);
        long leaf;
        FLOE_TRY(sc_long(s, &nm, "leaf_size", 0, def.leaf_size > 0 ? def.leaf_size : 16, &leaf));
        if (leaf < 1 || leaf > 1024) return sc_range(s, &nm, "leaf_size", "in [1, 1024]", (double)leaf);
        def.leaf_size = (int)leaf;
    }
    FLOE_TRY(sc_checks(s, &r, &def));
    if (sc_has(&r, "mass_2d")) {
        if (s->dim != 2)
            return sc_fail(s, FLOE_EINVAL, sc_get(&r, "mass_2d", NULL),
                           "mass_2d is only valid with dimension: 2");
        int mm;
        FLOE_TRY(sc_enum(s, &r, "mass_2d", mass2d, 0, &mm));
        def.mass_2d_area = mm;
    }

    struct fy_node *mk;
    struct fy_node *mv = sc_get(&r, "materials", &mk);
    if (!mv) return sc_fail(s, FLOE_EPARSE, root, "materials is required (a list of {name, density, ...})");
    FLOE_TRY(sc_parse_materials(s, mv == mk ? NULL : mv, mk));
    struct fy_node *lk;
    struct fy_node *lv = sc_get(&r, "laws", &lk);
    FLOE_TRY(sc_parse_laws(s, lv == lk ? NULL : lv, lk));

    char werr[512] = "";
    s->w = floe_world_create(&def, werr, sizeof werr);
    if (!s->w) return sc_fail(s, FLOE_EINVAL, NULL, "%s", werr[0] ? werr : "invalid world definition");
    for (int i = 0; i < s->nmats; i++) {
        /* young is only used by hertz_mindlin laws (checked above); the world wants one */
        floe_material wm = s->mats[i].m;
        if (!s->mats[i].has_young) wm.young = 1.0;
        int rc = floe_world_add_material(s->w, &wm);
        if (rc < 0) return sc_fail(s, -rc, s->mats[i].at, "materials[%d]: %s", i,
                                   floe_world_last_error(s->w));
    }
    FLOE_TRY(sc_build_laws(s));
    {
        /* ADMM options (pairs of convex shapes other than polytopes and spheres) */
        static const char *const cd_keys[] = {"tolerance", "max_iterations", NULL};
        struct fy_node *ck, *cv = sc_get(&r, "contact_detection", &ck);
        if (cv) {
            sc_map cm;
            FLOE_TRY(sc_map_open(s, cv == ck ? NULL : cv, ck, "contact_detection", cd_keys, &cm));
            floe_admm_options *o = &s->w->det.admm;
            FLOE_TRY(sc_num(s, &cm, "tolerance", 0, o->tol, &o->tol));
            if (!(o->tol > 0 && o->tol < 1))
                return sc_range(s, &cm, "tolerance", "in (0, 1) (relative to the smaller particle size)", o->tol);
            long mi;
            FLOE_TRY(sc_long(s, &cm, "max_iterations", 0, o->max_iter, &mi));
            if (mi < 1 || mi > 100000) return sc_range(s, &cm, "max_iterations", "in [1, 100000]", (double)mi);
            o->max_iter = (int)mi;
        }
    }

    /* bodies first: body particle i is world particle i (ids in outputs and trackers) */
    struct fy_node *bk;
    struct fy_node *bv = sc_get(&r, "bodies", &bk);
    struct fy_node *pdk;
    struct fy_node *pdv = sc_get(&r, "peridynamics", &pdk);
    if (!bv && !pdv)
        return sc_fail(s, FLOE_EPARSE, root, "bodies is required (a list of bodies or packings; or peridynamics)");
    if (bv) FLOE_TRY(sc_parse_bodies(s, bv == bk ? NULL : bv, bk));
    FLOE_TRY(sc_parse_pd(s, pdv == pdk ? NULL : pdv, pdk));
    struct fy_node *wk;
    struct fy_node *wv = sc_get(&r, "walls", &wk);
    FLOE_TRY(sc_parse_walls(s, wv == wk ? NULL : wv, wk));
    { struct fy_node *bok, *bov = sc_get(&r, "bonds", &bok); FLOE_TRY(sc_parse_bonds(s, bov == bok ? NULL : bov, bok)); } /* beam bonds */
    FLOE_TRY(sc_check_pairs(s));
    FLOE_TRY(sc_check_memory(s, NULL, "the scene", 0));
    struct fy_node *ok;
    struct fy_node *ov = sc_get(&r, "outputs", &ok);
    FLOE_TRY(sc_parse_outputs(s, ov == ok ? NULL : ov, ok, outdir, with_outputs));

    int rc = floe_world_prepare(s->w);
    if (rc != FLOE_OK)
        return sc_fail(s, rc, rc == FLOE_EUNSTABLE && !s->dt_auto ? sc_get(&tm, "dt", NULL) : NULL,
                       "%s", floe_world_last_error(s->w));
    FLOE_TRY(sc_check_steps(s, &tm, s->w->def.adaptive ? s->w->dt_lo : s->w->dt,
                            s->w->def.adaptive ? "the smallest adaptive step" : "the time step"));
    FLOE_TRY(sc_check_masses(s));
    /* an output interval not longer than a fixed step writes every step: say so to the
     * world, which then need not count intervals one by one */
    for (int k = 0; k < s->w->nobs && !s->w->def.adaptive; k++) {
        floe_observer *o = s->w->obs[k];
        if (o->period_steps <= 0 && o->period_time > 0 && o->period_time <= s->w->dt) o->period_steps = 1;
    }

    info->duration = s->duration;
    info->nparticles = s->nparticles;
    info->nwalls = s->nwalls;
    info->nmaterials = s->nmats;
    info->nlaws = s->nlaws;
    info->nobservers = s->nobservers;
    info->nstates = s->nstates;
    sc_summary(s, info->name, outdir, with_outputs, info);
    return FLOE_OK;
}

/* Position of the innermost bracket `open` ('[' or '{') still open at the end of the text:
 * libfyaml reports an unclosed flow collection at the end of the input, the user wants to
 * know where it was opened. A light scanner: flow indicators count inside flow collections
 * and at the start of a block value; quoted scalars and comments are skipped. */
static int sc_find_unclosed(const char *text, char open, int *line_out, int *col_out)
{
    struct { char c; int line, col; } st[256];
    int n = 0, line = 1, col = 1, value_start = 1;
    for (const char *p = text; *p; p++, col++) {
        char c = *p;
        if (c == '\n') { line++; col = 0; value_start = 1; continue; }
        if (c == ' ' || c == '\t') continue;
        if (c == '#' && (p == text || p[-1] == ' ' || p[-1] == '\t' || p[-1] == '\n')) {
            while (p[1] && p[1] != '\n') { p++; col++; }
            continue;
        }
        if ((c == '"' || c == '\'') && (n > 0 || value_start)) {
            char q = c;
            while (p[1]) {
                p++;
                col++;
                if (*p == '\n') { line++; col = 0; continue; }
                if (q == '"' && *p == '\\' && p[1]) { p++; col++; continue; }
                if (*p == q) {
                    if (q == '\'' && p[1] == '\'') { p++; col++; continue; }
                    break;
                }
            }
            value_start = 0;
            continue;
        }
        if ((c == '[' || c == '{') && (n > 0 || value_start)) {
            if (n < 256) { st[n].c = c; st[n].line = line; st[n].col = col; }
            n++;
            value_start = 1;
            continue;
        }
        if ((c == ']' || c == '}') && n > 0) { n--; value_start = 0; continue; }
        if (c == ',' && n > 0) { value_start = 1; continue; }
        if ((c == ':' || c == '-' || c == '?') && (p[1] == ' ' || p[1] == '\n' || p[1] == '\t' ||
                                                   (n > 0 && (p[1] == ',' || p[1] == ']' || p[1] == '}')))) {
            value_start = 1;
            continue;
        }
        value_start = 0;
    }
    for (int i = (n < 256 ? n : 256) - 1; i >= 0; i--)
        if (st[i].c == open) { *line_out = st[i].line; *col_out = st[i].col; return 1; }
    return 0;
}

/* Collected libfyaml diagnostics -> "path:line:col: message" (first error). */
static int sc_parse_error(sc *s, struct fy_diag *diag, const char *text)
{
    void *it = NULL;
    struct fy_diag_error *e;
    while ((e = fy_diag_errors_iterate(diag, &it))) {
        if (e->type < FYET_ERROR) continue;
        char msg[512];
        snprintf(msg, sizeof msg, "%s", e->msg ? e->msg : "malformed YAML");
        size_t n = strlen(msg);
        while (n && (msg[n - 1] == '\n' || msg[n - 1] == ' ')) msg[--n] = '\0';
        int el = e->line > 0 ? e->line : 0, ec = e->column > 0 ? e->column : 1;
        /* libfyaml reports an unclosed flow collection where it noticed (often the end of
         * the input); the user wants the bracket that was opened */
        int l1 = 0, c1 = 0, l2 = 0, c2 = 0;
        int h1 = sc_find_unclosed(text, '[', &l1, &c1), h2 = sc_find_unclosed(text, '{', &l2, &c2);
        char open = 0;
        int ol = 0, oc = 0;
        if (h1 && (!h2 || l1 > l2 || (l1 == l2 && c1 > c2))) { open = '['; ol = l1; oc = c1; }
        else if (h2) { open = '{'; ol = l2; oc = c2; }
        if (open && (ol > el || (ol == el && oc >= ec))) open = 0;
        if (open)
            snprintf(s->err, s->errlen, "%s:%d:%d: YAML syntax error: '%c' is never closed (%s "
                     "at line %d, column %d)", s->path, ol, oc, open, msg, el, ec);
        else if (el > 0)
            snprintf(s->err, s->errlen, "%s:%d:%d: YAML syntax error: %s", s->path, el, ec, msg);
        else
            snprintf(s->err, s->errlen, "%s: YAML syntax error: %s", s->path, msg);
        return FLOE_EPARSE;
    }
    snprintf(s->err, s->errlen, "%s: empty scene or malformed YAML (no document)", s->path);
    return FLOE_EPARSE;
}

/* Offset of the first byte that is not part of well-formed UTF-8 (RFC 3629: no overlong
 * forms, no surrogates, at most U+10FFFF), -1 if the text is valid. */
static long sc_bad_utf8(const char *text, long len)
{
    const unsigned char *u = (const unsigned char *)text;
    long i = 0;
    while (i < len) {
        unsigned c = u[i];
        if (c < 0x80) { i++; continue; }
        int n;
        unsigned lo = 0x80, hi = 0xBF;
        if (c >= 0xC2 && c <= 0xDF) n = 1;
        else if (c >= 0xE0 && c <= 0xEF) {
            n = 2;
            if (c == 0xE0) lo = 0xA0;
            if (c == 0xED) hi = 0x9F;
        } else if (c >= 0xF0 && c <= 0xF4) {
            n = 3;
            if (c == 0xF0) lo = 0x90;
            if (c == 0xF4) hi = 0x8F;
        } else return i;
        for (int k = 1; k <= n; k++) {
            if (i + k >= len) return i;
            unsigned d = u[i + k];
            if (d < (k == 1 ? lo : 0x80) || d > (k == 1 ? hi : 0xBF)) return i;
        }
        i += n + 1;
    }
    return -1;
}

/* Nodes of the document once its aliases are expanded, counted without expanding them: a
 * 1 KB "billion laughs" alias bomb would otherwise take gigabytes. The walk stops as soon as
 * the count passes limit (so it costs at most limit visits) or aliases nest deeper than
 * SC_MAX_ALIAS_DEPTH. *bad receives the alias where it stopped. Returns the count (> limit:
 * too large; -1: too deep or an unresolvable alias). */
#define SC_MAX_NODES 2000000L
#define SC_MAX_ALIAS_DEPTH 64
static long sc_count_nodes(struct fy_node *n, long count, long limit, int alias_depth, struct fy_node **bad)
{
    if (!n || count > limit) return count;
    if (fy_node_is_alias(n)) {
        if (alias_depth >= SC_MAX_ALIAS_DEPTH) { *bad = n; return -1; }
        struct fy_node *t = fy_node_resolve_alias(n);
        if (!t) { *bad = n; return -1; }
        long c = sc_count_nodes(t, count, limit, alias_depth + 1, bad);
        if (c > limit) *bad = n; /* the outermost alias on the way */
        return c;
    }
    count++;
    void *it = NULL;
    if (fy_node_is_mapping(n)) {
        struct fy_node_pair *p;
        while ((p = fy_node_mapping_iterate(n, &it)) && count >= 0 && count <= limit) {
            count = sc_count_nodes(fy_node_pair_key(p), count, limit, alias_depth, bad);
            if (count >= 0) count = sc_count_nodes(fy_node_pair_value(p), count, limit, alias_depth, bad);
        }
    } else if (fy_node_is_sequence(n)) {
        struct fy_node *c;
        while ((c = fy_node_sequence_iterate(n, &it)) && count >= 0 && count <= limit)
            count = sc_count_nodes(c, count, limit, alias_depth, bad);
    }
    return count;
}

/* Nodes written in the text (aliases not expanded), counted from the parser's events before
 * a document is built: a 16 MiB list of numbers would take gigabytes as a document. Stops
 * past limit; a syntax error ends the count (the document build reports it). */
static long sc_count_events(const char *text, size_t len, long limit, struct fy_diag *diag)
{
    struct fy_parse_cfg cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.flags = FYPCF_QUIET;
    cfg.diag = diag;
    struct fy_parser *fyp = fy_parser_create(&cfg);
    if (!fyp) return 0;
    long n = 0;
    if (fy_parser_set_string(fyp, text, len) == 0) {
        struct fy_event *ev;
        while (n <= limit && (ev = fy_parser_parse(fyp))) {
            enum fy_event_type t = ev->type;
            n += t == FYET_SCALAR || t == FYET_ALIAS || t == FYET_MAPPING_START || t == FYET_SEQUENCE_START;
            fy_parser_event_free(fyp, ev);
        }
    }
    fy_parser_destroy(fyp);
    return n;
}

static void sc_diag_discard(struct fy_diag *diag, void *user, const char *buf, size_t len)
{
    (void)diag;
    (void)user;
    (void)buf;
    (void)len;
}

int floe_scene_load_ex(const char *path, const char *text, const char *outdir, int with_outputs,
                       floe_world **out_world, floe_scene_info *info, char *err, size_t errlen)
{
    char dummy_err[8];
    floe_scene_info dummy_info;
    if (!err || !errlen) { err = dummy_err; errlen = sizeof dummy_err; }
    if (!info) info = &dummy_info;
    err[0] = '\0';
    memset(info, 0, sizeof *info);
    if (out_world) *out_world = NULL;
    if (!path) path = "<scene>";
    if (!outdir) outdir = "out";

    {
        char rerr[256];
        int rc = floe_register_builtins(rerr, sizeof rerr);
        if (rc) {
            snprintf(err, errlen, "%s: %s", path, rerr);
            return rc;
        }
    }
    sc s;
    memset(&s, 0, sizeof s);
    s.path = path;
    s.err = err;
    s.errlen = errlen;
    s.dim = 3;

    char *owned = NULL;
    if (!text) {
        FILE *f = fopen(path, "rb");
        if (!f) {
            snprintf(err, errlen, "%s: cannot open scene file: %s", path, strerror(errno));
            return FLOE_EIO;
        }
        size_t cap = 1 << 16, n = 0;
        owned = malloc(cap);
        while (owned) {
            size_t k = fread(owned + n, 1, cap - n - 1, f);
            n += k;
            if (k == 0) break;
            if (n > SC_MAX_TEXT) {
                fclose(f);
                free(owned);
                snprintf(err, errlen, "%s: the scene file is larger than %zu MiB (a scene lists "
                         "packings, not particles; meshes are separate files)", path, SC_MAX_TEXT >> 20);
                return FLOE_EINVAL;
            }
            if (n + 1 == cap) {
                char *p = realloc(owned, cap * 2);
                if (!p) { free(owned); owned = NULL; break; }
                owned = p;
                cap *= 2;
            }
        }
        int bad = ferror(f);
        fclose(f);
        if (!owned || bad) {
            free(owned);
            snprintf(err, errlen, "%s: cannot read scene file", path);
            return bad ? FLOE_EIO : FLOE_ENOMEM;
        }
        owned[n] = '\0';
        text = owned;
        s.text = text;
        s.textlen = (long)n;
        const char *nul = memchr(text, '\0', n);
        if (nul) {
            s.textlen = (long)(nul - text);
            int rc = sc_fail_pos(&s, FLOE_EPARSE, (long)(nul - text), "a NUL byte (byte %ld of %zu): a scene is "
                                 "UTF-8 text", (long)(nul - text), n);
            free(owned);
            return rc;
        }
    }
    if (strlen(text) > SC_MAX_TEXT) {
        free(owned);
        snprintf(err, errlen, "%s: the scene text is larger than %zu MiB", path, SC_MAX_TEXT >> 20);
        return FLOE_EINVAL;
    }
    {
        s.text = text;
        s.textlen = (long)strlen(text);
        long bad = sc_bad_utf8(text, s.textlen);
        if (bad >= 0) {
            int rc = sc_fail_pos(&s, FLOE_EPARSE, bad, "invalid UTF-8 (byte 0x%02x): a scene is UTF-8 text",
                                 (unsigned)(unsigned char)text[bad]);
            free(owned);
            return rc;
        }
    }

    struct fy_diag_cfg dcfg;
    fy_diag_cfg_default(&dcfg);
    dcfg.fp = NULL;
    dcfg.output_fn = sc_diag_discard;
    dcfg.colorize = false;
    struct fy_diag *diag = fy_diag_create(&dcfg);
    if (!diag) {
        free(owned);
        snprintf(err, errlen, "%s: out of memory", path);
        return FLOE_ENOMEM;
    }
    fy_diag_set_collect_errors(diag, true);
    struct fy_parse_cfg pcfg;
    memset(&pcfg, 0, sizeof pcfg);
    pcfg.flags = FYPCF_QUIET; /* aliases are resolved below, once their expansion is counted */
    pcfg.diag = diag;
    s.text = text;
    s.textlen = (long)strlen(text);
    struct fy_diag *diag2 = fy_diag_create(&dcfg); /* the count's own diagnostics, discarded */
    long written = diag2 ? sc_count_events(text, strlen(text), SC_MAX_NODES, diag2) : 0;
    if (diag2) fy_diag_destroy(diag2);
    if (written > SC_MAX_NODES) {
        fy_diag_destroy(diag);
        free(owned);
        return sc_fail(&s, FLOE_EPARSE, NULL, "the scene has more than %ld YAML nodes: refused (list "
                       "packings, not particles)", SC_MAX_NODES);
    }
    struct fy_document *doc = fy_document_build_from_string(&pcfg, text, strlen(text));
    int rc = FLOE_OK;
    if (!doc || fy_diag_got_error(diag)) {
        rc = sc_parse_error(&s, diag, text);
    } else {
        struct fy_node *bad = NULL;
        long nodes = sc_count_nodes(fy_document_root(doc), 0, SC_MAX_NODES, 0, &bad);
        if (nodes < 0) {
            const char *an = bad && fy_node_is_scalar(bad) ? fy_node_get_scalar0(bad) : NULL;
            rc = sc_fail(&s, FLOE_EPARSE, bad, "alias *%s: no anchor &%s before it, or aliases that nest deeper "
                         "than %d or refer to themselves", an ? an : "?", an ? an : "?", SC_MAX_ALIAS_DEPTH);
        }
        else if (nodes > SC_MAX_NODES)
            rc = sc_fail(&s, FLOE_EPARSE, bad, "the scene expands to more than %ld YAML nodes%s: refused (an "
                         "alias bomb?)", SC_MAX_NODES, bad ? " through this alias" : "");
        else if (fy_document_resolve(doc) != 0 || fy_diag_got_error(diag))
            rc = sc_parse_error(&s, diag, text);
    }
    if (rc != FLOE_OK) {
    } else {
        struct fy_node *root = fy_document_root(doc);
        if (!root || sc_is_missing(root))
            rc = sc_fail(&s, FLOE_EPARSE, NULL, "empty scene: expected a mapping with time, "
                         "materials, laws and bodies");
        else
            rc = sc_build(&s, root, outdir, with_outputs, info);
    }
    if (doc) fy_document_destroy(doc);
    fy_diag_destroy(diag);
    free(owned);

    free(s.mats);
    for (int i = 0; i < s.nlaws; i++) free(s.laws[i].params);
    free(s.laws);
    free(s.law_at);
    free(s.entry_first);
    free(s.entry_count);
    for (int i = 0; i < s.nouts; i++) free(s.outs[i].uparams);
    free(s.outs);
    if (rc != FLOE_OK) {
        if (s.w) floe_world_destroy(s.w);
        if (!err[0]) snprintf(err, errlen, "%s: %s", path, floe_strerror(rc));
        return rc;
    }
    if (out_world) *out_world = s.w;
    else floe_world_destroy(s.w);
    return FLOE_OK;
}

int floe_scene_load(const char *path, const char *outdir, floe_world **out_world,
                    floe_scene_info *info, char *err, size_t errlen)
{
    return floe_scene_load_ex(path, NULL, outdir, 1, out_world, info, err, errlen);
}

int floe_scene_load_string(const char *text, const char *path, const char *outdir,
                           floe_world **out_world, floe_scene_info *info, char *err, size_t errlen)
{
    if (!text) {
        if (err && errlen) snprintf(err, errlen, "%s: no scene text", path ? path : "<string>");
        return FLOE_EINVAL;
    }
    return floe_scene_load_ex(path ? path : "<string>", text, outdir, 1, out_world, info, err,
                              errlen);
}

/* ------------------------------------------------------------------------------------ */
/* Default demo: ~2,000 glass beads poured into a box (Hertz-Mindlin, e = 0.5, mu = 0.5). */

static const char sc_demo[] =
    "# floe default demo: 2,000 glass beads (r = 1 mm) poured into a 30 mm x 30 mm box.\n"
    "# dt is automatic: 0.75 x the critical estimate (about 1.6e-5 s, 15,000 steps).\n"
    "name: pour\n"
    "dimension: 3\n"
    "time: {duration: 0.25, safety: 0.75}\n"
    "gravity: [0, 0, -9.81]\n"
    "neighbor: {skin: 0.0005}\n"
    "materials:\n"
    "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
    "laws:\n"
    "  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n"
    "walls:\n"
    "  - {point: [0, 0, 0], normal: [0, 0, 1], material: glass}\n"
    "  - {point: [0, 0, 0], normal: [1, 0, 0], material: glass}\n"
    "  - {point: [0.03, 0, 0], normal: [-1, 0, 0], material: glass}\n"
    "  - {point: [0, 0, 0], normal: [0, 1, 0], material: glass}\n"
    "  - {point: [0, 0.03, 0], normal: [0, -1, 0], material: glass}\n"
    "bodies:\n"
    "  - packing: random\n"
    "    shape: {sphere: {radius: 0.001}}\n"
    "    material: glass\n"
    "    region: {min: [0, 0, 0.002], max: [0.03, 0.03, 0.06]}\n"
    "    count: 2000\n"
    "    seed: 7\n"
    "outputs:\n"
    "  - {type: vtk, every: 2000, prefix: frame}\n"
    "  - {type: energy, every: 100, file: energy.csv}\n"
    "  - {type: stress, every: 100, file: stress.csv, group: all}\n";

const char *floe_scene_default_demo(void) { return sc_demo; }
