/* builtin_laws.c - the built-in contact laws, one line each: a new law is one file (its
 * class, parameter struct, schema and registry entry) plus one line here, or a plugin
 * calling floe_register (docs/extending.md). */
#include "floe_contact.h"

extern const floe_registry_entry floe_law_entry_hertz_mindlin, floe_law_entry_linear, floe_law_entry_viscoelastic,
    floe_law_entry_short_range, floe_law_entry_none, floe_law_entry_overlap_area, floe_law_entry_hopkins, floe_normal_entry_hooke,
    floe_normal_entry_hertz, floe_tangential_entry_coulomb, floe_tangential_entry_mindlin;

static const floe_registry_entry *const builtin[] = {
    &floe_law_entry_hertz_mindlin,
    &floe_law_entry_linear,
    &floe_law_entry_viscoelastic,
    &floe_law_entry_short_range,
    &floe_law_entry_none,
    &floe_law_entry_overlap_area,
    &floe_law_entry_hopkins,
    /* the parts a scene composes (laws: [{normal: ..., tangential: ...}]) */
    &floe_normal_entry_hooke,
    &floe_normal_entry_hertz,
    &floe_tangential_entry_coulomb,
    &floe_tangential_entry_mindlin,
};

int floe_register_builtin_laws(char *err, size_t errlen) {
    return floe_register_list(builtin, sizeof builtin / sizeof *builtin, err, errlen);
}
