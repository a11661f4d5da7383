/* floe_registry.h - registries of named components with parameter schemas (issue #11).
 *
 * Every extensible kind (shapes, contact laws, normal and tangential parts of composed laws
 * (contact/laws/floe_contact.h), outputs, PD materials, force providers, integrators and
 * packings) keeps a registry: a name, a one-paragraph doc, a constructor and a parameter
 * schema (key, type, unit, range, default, one-line doc). The scene loader reads a
 * component's parameters generically from its schema (validation, closest-key hints,
 * file:line:col), `floe help` and `floe info` print the schemas, and docs/reference.md is
 * generated from them. A plugin (a shared library named in a scene's `plugins:` or by
 * `floe run --plugin`) registers its components by calling floe_register from its init
 * function, exactly as the built-ins do.
 *
 * The registry is process-wide: register before worlds are built on several threads. */
#ifndef FLOE_REGISTRY_H
#define FLOE_REGISTRY_H

#include <stddef.h>

/* the kinds with a registry (strings, so that a plugin may add a kind of its own) */
#define FLOE_KIND_LAW "law"
#define FLOE_KIND_SHAPE "shape"
#define FLOE_KIND_OBSERVER "output"
#define FLOE_KIND_PD_MATERIAL "pd_material" /* peridynamics/floe_pd.h floe_pd_material_create_fn */
#define FLOE_KIND_PROVIDER "provider"       /* core/world/floe_provider.h floe_provider_create_fn */
#define FLOE_KIND_PACKING "packing"         /* core/scene/floe_scene.h: the bodies' particle generators */
#define FLOE_KIND_INTEGRATOR "integrator" /* floe_integrator.h: create returns the class */

typedef enum floe_param_type {
    FLOE_PARAM_REAL,     /* double */
    FLOE_PARAM_INT,      /* int */
    FLOE_PARAM_BOOL,     /* int 0/1 (true/false, yes/no, on/off, 1/0) */
    FLOE_PARAM_STRING,   /* char[FLOE_PARAM_STRING_MAX] */
    FLOE_PARAM_CHOICE,   /* int: index into the '|'-separated choices */
    FLOE_PARAM_VEC3,     /* double[3] (2 numbers accepted in a 2D scene, z = 0, unless
                            FLOE_PARAM_XYZ) */
    /* documented only: the kind's loader reads these itself (entries flagged
     * FLOE_ENTRY_LOADER_PARSES); the generic reader refuses them */
    FLOE_PARAM_POINTS,   /* a list of points [[x, y(, z)], ...] */
    FLOE_PARAM_NODE      /* any YAML value (a nested shape, a list of pieces, ...) */
} floe_param_type;

#define FLOE_PARAM_STRING_MAX 256

/* a generic function pointer (constructors are stored as this and cast back by their kind) */
typedef void (*floe_fn)(void);

enum {
    FLOE_PARAM_REQUIRED = 1,  /* no default: the key must be given */
    FLOE_PARAM_MIN_OPEN = 2,  /* value > min (otherwise >= min) */
    FLOE_PARAM_MAX_OPEN = 4,  /* value < max (otherwise <= max) */
    FLOE_PARAM_XYZ = 8        /* VEC3: three numbers also in 2D */
};

/* One parameter. A range of min = -INFINITY, max = INFINITY (or both 0) means any finite
 * number; for VEC3 the range applies to each component. */
typedef struct floe_param {
    const char *key;
    floe_param_type type;
    int flags;
    const char *unit;         /* "Pa", "N/m", "" for dimensionless */
    double min, max;
    double def;               /* default of REAL, INT, BOOL, CHOICE (index) */
    const char *def_text;     /* default of STRING; for VEC3 unused (default 0 0 0) */
    const char *choices;      /* CHOICE: "a|b|c" */
    const char *doc;          /* one line */
    size_t offset;            /* where the value goes in the parameter struct */
} floe_param;

/* Every parameter struct starts with this head: bit k of `given` is set when parameter k
 * of the schema was given in the scene (not defaulted), so that a constructor can tell
 * alternatives apart (e.g. a stiffness given, or derived from other keys). */
typedef struct floe_params_head {
    unsigned long long given;
} floe_params_head;

#define FLOE_PARAMS_MAX 64

typedef struct floe_registry_entry {
    const char *kind;         /* FLOE_KIND_* */
    const char *name;         /* the name a scene uses */
    const char *title;        /* a short human label ("Hertz-Mindlin"), for summaries */
    const char *doc;          /* what it is, one paragraph */
    const char *source;       /* equation, paper or docs section it implements (may be NULL) */
    const floe_param *params; /* schema (nparams entries) */
    int nparams;
    size_t params_size;       /* bytes of the parameter struct (starts with floe_params_head) */
    floe_fn create;           /* the kind's constructor, cast to floe_fn (its real type is the
                                 kind's: floe_law_create_fn, floe_shape_create_fn, ...) */
    const char *keys_extra;   /* keys the kind's loader reads itself, '|'-separated (e.g.
                                 "materials|model" for laws), or NULL */
    int flags;                /* FLOE_ENTRY_* and kind-specific flags (from bit 8 on) */
    const char *origin;       /* set by the registry: "built-in" or the plugin's path */
} floe_registry_entry;

/* Registers a copy of *e (its strings and schema must outlive the registry: static data).
 * FLOE_EINVAL when kind, name or create is missing, params_size does not cover
 * floe_params_head, or a schema entry is malformed (a parameter without key or doc, an
 * offset outside the parameter struct, a choice without choices or whose default is not
 * among them, a duplicate key, too many parameters), and also when kind/name is taken. A
 * default outside the range is allowed: it reads "not given". The message goes to err. */
int floe_register(const floe_registry_entry *e, char *err, size_t errlen);
/* Registers each of the n entries of list that is not registered yet (a kind's built-in
 * list, registered again without error): FLOE_OK or the first error. */
int floe_register_list(const floe_registry_entry *const *list, size_t n, char *err, size_t errlen);
/* The entry of kind/name, or NULL. */
const floe_registry_entry *floe_registry_find(const char *kind, const char *name);
/* Entries of a kind in registration order: count, and entry k (NULL out of range). kind
 * NULL counts every entry. */
int floe_registry_count(const char *kind);
const floe_registry_entry *floe_registry_at(const char *kind, int k);
/* The closest registered name of a kind to `name` (edit distance <= 2 + len/4), or NULL. */
const char *floe_registry_closest(const char *kind, const char *name);
/* Optimal-string-alignment edit distance (a transposition is one edit; 99 for names over
 * 63 characters): the closest-name hints of the registries and the scene loader. */
int floe_edit_distance(const char *a, const char *b);
/* Index of key in the schema, or -1. */
int floe_schema_index(const floe_registry_entry *e, const char *key);
/* 1 when parameter `key` was given in the scene (floe_params_head.given) */
int floe_params_given(const floe_registry_entry *e, const void *params, const char *key);
/* Writes every default into params (size e->params_size, zeroed first). */
void floe_params_defaults(const floe_registry_entry *e, void *params);
/* Checks one number against parameter p's type and range: 0 when it is valid, otherwise
 * writes "must be > 0 (Pa)" (the condition and unit) into why. */
int floe_param_check(const floe_param *p, double value, char *why, size_t whylen);
/* Describes a parameter's range as text ("> 0", "in [0, 1]", "any"), into buf. */
void floe_param_range_text(const floe_param *p, char *buf, size_t len);
/* entry flag: the scene loader of the kind reads this entry's parameters itself (nested
 * shapes, point lists); its schema documents them */
#define FLOE_ENTRY_LOADER_PARSES 1

/* The label of `origin` for built-ins */
#define FLOE_ORIGIN_BUILTIN "built-in"
/* Sets the origin recorded for the entries registered from now on (NULL: built-in); the
 * plugin loader sets it around a plugin's init. */
void floe_registry_set_origin(const char *origin);

#endif
