/* reference.c - the registries' schemas as text: `floe help` and docs/reference.md (which
 * CI regenerates and compares, so the reference cannot go stale). */
#include "floe_scene.h"
#include "floe_registry.h"

#include <stdio.h>
#include <string.h>

static const char *type_name(floe_param_type t) {
    switch (t) {
    case FLOE_PARAM_REAL: return "number";
    case FLOE_PARAM_INT: return "integer";
    case FLOE_PARAM_BOOL: return "true/false";
    case FLOE_PARAM_STRING: return "text";
    case FLOE_PARAM_CHOICE: return "choice";
    case FLOE_PARAM_VEC3: return "[x, y, z]";
    case FLOE_PARAM_POINTS: return "list of points";
    case FLOE_PARAM_NODE: return "see doc";
    }
    return "?";
}

static void default_text(const floe_param *p, char *buf, size_t len) {
    if (p->flags & FLOE_PARAM_REQUIRED) { snprintf(buf, len, "required"); return; }
    if (p->type == FLOE_PARAM_POINTS || p->type == FLOE_PARAM_NODE) { snprintf(buf, len, "-"); return; }
    /* a default outside the range reads "not given" (floe_registry.h): an alternative */
    if ((p->type == FLOE_PARAM_REAL || p->type == FLOE_PARAM_INT) && floe_param_check(p, p->def, NULL, 0)) {
        snprintf(buf, len, "not given");
        return;
    }
    switch (p->type) {
    case FLOE_PARAM_REAL: snprintf(buf, len, "%g", p->def); break;
    case FLOE_PARAM_INT: snprintf(buf, len, "%d", (int)p->def); break;
    case FLOE_PARAM_BOOL: snprintf(buf, len, "%s", p->def != 0 ? "true" : "false"); break;
    case FLOE_PARAM_STRING: snprintf(buf, len, "%s", p->def_text ? p->def_text : "\"\""); break;
    case FLOE_PARAM_CHOICE: {
        const char *c = p->choices;
        for (int k = 0; k < (int)p->def && c; k++) { c = strchr(c, '|'); if (c) c++; }
        const char *e = c ? strchr(c, '|') : NULL;
        snprintf(buf, len, "%.*s", c ? (e ? (int)(e - c) : (int)strlen(c)) : 1, c ? c : "?");
        break;
    }
    case FLOE_PARAM_VEC3: snprintf(buf, len, "[0, 0, 0]"); break;
    default: snprintf(buf, len, "-");
    }
}

/* The kinds `floe help` and docs/reference.md list, in order: kind, heading, where a scene
 * names them. A new kind is one line here. */
static const struct help_kind {
    const char *kind, *heading, *intro;
} help_kinds[] = {
    {FLOE_KIND_SHAPE, "Shapes", "Shapes, named in `shape: {NAME: {...}}` of bodies and PD regions."},
    {FLOE_KIND_LAW, "Contact laws", "Contact laws, named in `laws: [{materials: [a, b], model: NAME, ...}]`."},
    {FLOE_KIND_NORMAL, "Normal parts of composed contact laws",
     "Normal parts, composed with a tangential part in `laws: [{materials: [a, b], normal: {model: NAME, ...}, "
     "tangential: {model: NAME, ...}}]`."},
    {FLOE_KIND_TANGENTIAL, "Tangential parts of composed contact laws",
     "Tangential (friction) parts of a composed law: `tangential: {model: NAME, ...}` beside its `normal:` "
     "(none: frictionless)."},
    {FLOE_KIND_OBSERVER, "Outputs",
     "Outputs, named in `outputs: [{type: NAME, every: N | interval: T, ...}]` (every: steps, default 100; "
     "interval: seconds of simulated time)."},
    {FLOE_KIND_PD_MATERIAL, "PD materials",
     "PD materials, named in `peridynamics: [{material: {model: NAME, ...}, ...}]`."},
    {FLOE_KIND_PROVIDER, "Force providers",
     "Force providers, named in `forces: [{type: NAME, ...}]`; they act on every free particle after gravity."},
    {FLOE_KIND_INTEGRATOR, "Integrators",
     "Time integrators, named in `time: {integrator: NAME}` (floe_integrator.h); the Newmark-beta solvers of bonded "
     "systems are documented here and run through the C API (floe_newmark.h)."},
    {FLOE_KIND_PACKING, "Packings",
     "Packings, named in `bodies: [{packing: NAME, shape, material, ...}]` (no packing: one body at `position`)."},
};
#define NKINDS ((int)(sizeof help_kinds / sizeof *help_kinds))

int floe_help_kind_count(void) { return NKINDS; }
const char *floe_help_kind(int k) { return k >= 0 && k < NKINDS ? help_kinds[k].kind : NULL; }

static void write_entry(FILE *f, const floe_registry_entry *e, int md) {
    if (md) {
        fprintf(f, "### `%s`%s%s\n\n%s\n\n", e->name, e->title && strcmp(e->title, e->name) ? " — " : "",
                e->title && strcmp(e->title, e->name) ? e->title : "", e->doc ? e->doc : "");
        if (e->source) fprintf(f, "Source: %s.\n\n", e->source);
        if (!e->nparams) {
            fprintf(f, "No parameters.\n\n");
            return;
        }
        fprintf(f, "| key | type | unit | range | default | meaning |\n|---|---|---|---|---|---|\n");
    } else {
        fprintf(f, "%s %s%s%s%s\n  %s\n", e->kind, e->name, e->title ? " (" : "", e->title ? e->title : "",
                e->title ? ")" : "", e->doc ? e->doc : "");
        if (e->source) fprintf(f, "  source: %s\n", e->source);
        fprintf(f, "  from: %s\n", e->origin);
        if (!e->nparams) {
            fprintf(f, "  no parameters\n");
            return;
        }
        fprintf(f, "  %-14s %-14s %-8s %-16s %-10s %s\n", "key", "type", "unit", "range", "default", "meaning");
    }
    for (int k = 0; k < e->nparams; k++) {
        const floe_param *p = &e->params[k];
        char range[96], def[96];
        floe_param_range_text(p, range, sizeof range);
        default_text(p, def, sizeof def);
        const char *unit = p->unit && p->unit[0] ? p->unit : "-";
        if (md)
            fprintf(f, "| `%s` | %s | %s | %s | %s | %s |\n", p->key, type_name(p->type), unit, range, def, p->doc);
        else
            fprintf(f, "  %-14s %-14s %-8s %-16s %-10s %s\n", p->key, type_name(p->type), unit, range, def, p->doc);
    }
    fprintf(f, "\n");
}

int floe_reference_write(FILE *f, const char *kind, const char *name, int markdown, char *err, size_t errlen) {
    FLOE_TRY(floe_register_builtins(err, errlen));
    if (markdown) {
        fprintf(f, "# Component reference\n\n"
                   "Generated by `floe help --markdown` from the registries' schemas (floe_registry.h);\n"
                   "CI regenerates it and fails when this file differs. Do not edit by hand.\n\n");
    }
    int found = 0;
    for (int q = 0; q < NKINDS; q++) {
        const char *kq = help_kinds[q].kind;
        if (kind && strcmp(kind, kq)) continue;
        found = 1;
        if (markdown) fprintf(f, "## %s\n\n%s\n\n", help_kinds[q].heading, help_kinds[q].intro);
        else if (!name) fprintf(f, "%s\n", help_kinds[q].intro);
        int n = floe_registry_count(kq), shown = 0;
        for (int k = 0; k < n; k++) {
            const floe_registry_entry *e = floe_registry_at(kq, k);
            if (name && strcmp(e->name, name)) continue;
            if (markdown && strcmp(e->origin, FLOE_ORIGIN_BUILTIN)) continue; /* plugins: not in the docs */
            shown++;
            if (name || markdown) write_entry(f, e, markdown);
            else fprintf(f, "  %-14s %s%s%s\n", e->name, e->title ? e->title : "",
                         strcmp(e->origin, FLOE_ORIGIN_BUILTIN) ? "  [plugin " : "",
                         strcmp(e->origin, FLOE_ORIGIN_BUILTIN) ? e->origin : "");
        }
        if (name && !shown) {
            const char *near = floe_registry_closest(kq, name);
            if (!near) { /* a part of exactly one name ("verlet") */
                int hits = 0;
                for (int k = 0; k < n; k++)
                    if (strstr(floe_registry_at(kq, k)->name, name)) { near = floe_registry_at(kq, k)->name; hits++; }
                if (hits != 1) near = NULL;
            }
            snprintf(err, errlen, "no %s named '%s'%s%s%s (floe help %s lists them)", kq, name,
                     near ? " (did you mean '" : "", near ? near : "", near ? "'?)" : "", kq);
            return FLOE_EINVAL;
        }
    }
    if (!found) {
        char list[256] = "";
        for (int q = 0; q < NKINDS; q++) {
            size_t l = strlen(list);
            snprintf(list + l, sizeof list - l, "%s%s", q ? ", " : "", help_kinds[q].kind);
        }
        snprintf(err, errlen, "unknown kind '%s' (kinds: %s)", kind, list);
        return FLOE_EINVAL;
    }
    return FLOE_OK;
}
