/* registry.c - registries of named components with parameter schemas (floe_registry.h). */
#include "floe_registry.h"
#include "floe_base.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct registry {
    floe_registry_entry *e;
    int n, cap;
    const char *origin;
} registry;

static registry reg; /* process-wide (floe_registry.h) */

void floe_registry_set_origin(const char *origin) { reg.origin = origin; }

static int fail(char *err, size_t errlen, const char *fmt, const char *a, const char *b, const char *c) {
    if (err && errlen) snprintf(err, errlen, fmt, a, b, c ? c : "");
    return FLOE_EINVAL;
}

static int range_ok(const floe_param *p, double v) {
    if (p->type == FLOE_PARAM_STRING) return 1;
    if (p->type == FLOE_PARAM_CHOICE || p->type == FLOE_PARAM_BOOL) return 1;
    if (!isfinite(v)) return 0;
    if (p->min == 0 && p->max == 0 && !(p->flags & (FLOE_PARAM_MIN_OPEN | FLOE_PARAM_MAX_OPEN))) return 1;
    if (p->flags & FLOE_PARAM_MIN_OPEN ? !(v > p->min) : !(v >= p->min)) return 0;
    if (p->flags & FLOE_PARAM_MAX_OPEN ? !(v < p->max) : !(v <= p->max)) return 0;
    return 1;
}

static int count_choices(const char *c) {
    if (!c || !*c) return 0;
    int n = 1;
    for (; *c; c++) n += *c == '|';
    return n;
}

int floe_register(const floe_registry_entry *e, char *err, size_t errlen) {
    if (!e || !e->kind || !e->name || !e->name[0] || !e->create)
        return fail(err, errlen, "register: kind, name and create are required%s%s%s", "", "", "");
    if (e->nparams < 0 || e->nparams > FLOE_PARAMS_MAX || (e->nparams && !e->params))
        return fail(err, errlen, "register %s '%s': bad schema (0 to 64 parameters)%s", e->kind, e->name, "");
    if (e->params_size < sizeof(floe_params_head))
        return fail(err, errlen, "register %s '%s': params_size must cover floe_params_head%s", e->kind, e->name, "");
    if (floe_registry_find(e->kind, e->name)) {
        const floe_registry_entry *o = floe_registry_find(e->kind, e->name);
        return fail(err, errlen, "register: %s '%s' is already registered (%s)", e->kind, e->name, o->origin);
    }
    for (int k = 0; k < e->nparams; k++) {
        const floe_param *p = &e->params[k];
        if (!p->key || !p->key[0] || !p->doc)
            return fail(err, errlen, "register %s '%s': parameter %s has no key or doc", e->kind, e->name,
                        p->key ? p->key : "?");
        if (p->type == FLOE_PARAM_POINTS || p->type == FLOE_PARAM_NODE) {
            if (!(e->flags & FLOE_ENTRY_LOADER_PARSES))
                return fail(err, errlen, "register %s '%s': parameter %s: point lists and nested values need an "
                            "entry its kind's loader parses", e->kind, e->name, p->key);
            continue;
        }
        size_t sz = p->type == FLOE_PARAM_REAL ? sizeof(double)
                  : p->type == FLOE_PARAM_VEC3 ? 3 * sizeof(double)
                  : p->type == FLOE_PARAM_STRING ? FLOE_PARAM_STRING_MAX : sizeof(int);
        if (!(e->flags & FLOE_ENTRY_LOADER_PARSES) &&
            (p->offset < sizeof(floe_params_head) || p->offset + sz > e->params_size))
            return fail(err, errlen, "register %s '%s': parameter %s lies outside the parameter struct", e->kind,
                        e->name, p->key);
        if (p->type == FLOE_PARAM_CHOICE && count_choices(p->choices) < 1)
            return fail(err, errlen, "register %s '%s': choice parameter %s has no choices", e->kind, e->name, p->key);
        if (p->type == FLOE_PARAM_CHOICE && !(p->def >= 0 && p->def < count_choices(p->choices)))
            return fail(err, errlen, "register %s '%s': default of %s is not one of its choices", e->kind, e->name,
                        p->key);
        /* a default outside the range is allowed: it reads "not given" (alternatives such as
         * stiffness or micromodulus, told apart by floe_params_given) */
        for (int q = 0; q < k; q++)
            if (!strcmp(e->params[q].key, p->key))
                return fail(err, errlen, "register %s '%s': parameter %s appears twice", e->kind, e->name, p->key);
    }
    if (reg.n == reg.cap) {
        int nc = reg.cap ? 2 * reg.cap : 32;
        floe_registry_entry *ne = realloc(reg.e, (size_t)nc * sizeof *ne);
        if (!ne) {
            if (err && errlen) snprintf(err, errlen, "out of memory");
            return FLOE_ENOMEM;
        }
        reg.e = ne;
        reg.cap = nc;
    }
    reg.e[reg.n] = *e;
    reg.e[reg.n].origin = reg.origin ? reg.origin : FLOE_ORIGIN_BUILTIN;
    reg.n++;
    return FLOE_OK;
}

const floe_registry_entry *floe_registry_find(const char *kind, const char *name) {
    if (!kind || !name) return NULL;
    for (int k = 0; k < reg.n; k++)
        if (!strcmp(reg.e[k].kind, kind) && !strcmp(reg.e[k].name, name)) return &reg.e[k];
    return NULL;
}

int floe_registry_count(const char *kind) {
    int n = 0;
    for (int k = 0; k < reg.n; k++) n += !kind || !strcmp(reg.e[k].kind, kind);
    return n;
}

const floe_registry_entry *floe_registry_at(const char *kind, int idx) {
    for (int k = 0; k < reg.n; k++)
        if ((!kind || !strcmp(reg.e[k].kind, kind)) && idx-- == 0) return &reg.e[k];
    return NULL;
}

int floe_edit_distance(const char *a, const char *b) {
    int la = (int)strlen(a), lb = (int)strlen(b);
    if (la > 63 || lb > 63) return 99;
    int d[64][64];
    for (int i = 0; i <= la; i++) d[i][0] = i;
    for (int j = 0; j <= lb; j++) d[0][j] = j;
    for (int i = 1; i <= la; i++)
        for (int j = 1; j <= lb; j++) {
            int c = a[i - 1] != b[j - 1];
            int v = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < v) v = d[i][j - 1] + 1;
            if (d[i - 1][j - 1] + c < v) v = d[i - 1][j - 1] + c;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] && d[i - 2][j - 2] + 1 < v)
                v = d[i - 2][j - 2] + 1;
            d[i][j] = v;
        }
    return d[la][lb];
}

const char *floe_registry_closest(const char *kind, const char *name) {
    const char *best = NULL;
    int bd = 3 + (int)strlen(name) / 4;
    for (int k = 0; k < reg.n; k++) {
        if (strcmp(reg.e[k].kind, kind)) continue;
        int d = floe_edit_distance(name, reg.e[k].name);
        if (d < bd) { bd = d; best = reg.e[k].name; }
    }
    return best;
}

int floe_schema_index(const floe_registry_entry *e, const char *key) {
    for (int k = 0; k < e->nparams; k++)
        if (!strcmp(e->params[k].key, key)) return k;
    return -1;
}

int floe_params_given(const floe_registry_entry *e, const void *params, const char *key) {
    int k = floe_schema_index(e, key);
    return k >= 0 && (((const floe_params_head *)params)->given >> k & 1);
}

void floe_params_defaults(const floe_registry_entry *e, void *params) {
    memset(params, 0, e->params_size);
    for (int k = 0; k < e->nparams; k++) {
        const floe_param *p = &e->params[k];
        char *at = (char *)params + p->offset;
        switch (p->type) {
        case FLOE_PARAM_REAL: { double v = p->def; memcpy(at, &v, sizeof v); break; }
        case FLOE_PARAM_VEC3:
        case FLOE_PARAM_POINTS:
        case FLOE_PARAM_NODE: break;
        case FLOE_PARAM_STRING: snprintf(at, FLOE_PARAM_STRING_MAX, "%s", p->def_text ? p->def_text : ""); break;
        default: { int v = (int)p->def; memcpy(at, &v, sizeof v); break; }
        }
    }
}

void floe_param_range_text(const floe_param *p, char *buf, size_t len) {
    const int any = p->min == 0 && p->max == 0 && !(p->flags & (FLOE_PARAM_MIN_OPEN | FLOE_PARAM_MAX_OPEN));
    if (p->type == FLOE_PARAM_BOOL || p->type == FLOE_PARAM_STRING || p->type == FLOE_PARAM_POINTS ||
        p->type == FLOE_PARAM_NODE) {
        snprintf(buf, len, "-");
        return;
    }
    if (p->type == FLOE_PARAM_CHOICE) { snprintf(buf, len, "%s", p->choices); return; }
    if (any || (isinf(p->min) && isinf(p->max))) { snprintf(buf, len, "any"); return; }
    const char *lo = p->flags & FLOE_PARAM_MIN_OPEN ? ">" : ">=", *hi = p->flags & FLOE_PARAM_MAX_OPEN ? "<" : "<=";
    if (isinf(p->max)) snprintf(buf, len, "%s %g", lo, p->min);
    else if (isinf(p->min)) snprintf(buf, len, "%s %g", hi, p->max);
    else snprintf(buf, len, "in %c%g, %g%c", p->flags & FLOE_PARAM_MIN_OPEN ? '(' : '[', p->min, p->max,
                  p->flags & FLOE_PARAM_MAX_OPEN ? ')' : ']');
}

int floe_param_check(const floe_param *p, double v, char *why, size_t whylen) {
    if (p->type == FLOE_PARAM_INT && v != floor(v)) {
        if (why && whylen) snprintf(why, whylen, "must be a whole number");
        return FLOE_EINVAL;
    }
    if (range_ok(p, v)) return FLOE_OK;
    if (why && whylen) {
        char r[96];
        floe_param_range_text(p, r, sizeof r);
        if (!strcmp(r, "any")) snprintf(r, sizeof r, "finite");
        snprintf(why, whylen, "must be %s%s%s%s", r, p->unit && p->unit[0] ? " (" : "", p->unit ? p->unit : "",
                 p->unit && p->unit[0] ? ")" : "");
    }
    return FLOE_EINVAL;
}

int floe_register_list(const floe_registry_entry *const *list, size_t n, char *err, size_t errlen) {
    for (size_t k = 0; k < n; k++) {
        if (floe_registry_find(list[k]->kind, list[k]->name)) continue;
        int rc = floe_register(list[k], err, errlen);
        if (rc) return rc;
    }
    return FLOE_OK;
}
