/* builtins.c - registers every built-in component of every kind (floe_registry.h). The
 * scene loader and the CLI call it before they look anything up; a program that uses the
 * registry itself calls it once too. Each kind keeps its own list beside its components
 * (contact/laws/builtin_laws.c, ...). */
#include "floe_scene.h"
#include "floe_contact.h"
#include "floe_geometry.h"
#include "floe_observer.h"
#include "floe_provider.h"
#include "floe_forcing.h"
#include "floe_pd.h"
#include "floe_integrator.h"

int floe_register_builtins(char *err, size_t errlen) {
    FLOE_TRY(floe_register_builtin_laws(err, errlen));
    FLOE_TRY(floe_register_builtin_shapes(err, errlen));
    FLOE_TRY(floe_register_builtin_outputs(err, errlen));
    FLOE_TRY(floe_register_builtin_pd_materials(err, errlen));
    FLOE_TRY(floe_register_builtin_providers(err, errlen));
    FLOE_TRY(floe_register_builtin_forcing(err, errlen));
    FLOE_TRY(floe_register_builtin_packings(err, errlen));
    FLOE_TRY(floe_register_builtin_integrators(err, errlen));
    return FLOE_OK;
}
