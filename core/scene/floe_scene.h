/* floe_scene.h - YAML scene files (docs/scene-format.md), parsed with libfyaml.
 * Errors carry "file:line:column: message"; unknown keys name the closest valid key. */
#ifndef FLOE_SCENE_H
#define FLOE_SCENE_H

#include "floe_world.h"

#include <stdio.h>

typedef struct floe_scene_info {
    char name[128];
    double duration;          /* s, simulated time to run */
    int nparticles, nwalls, nmaterials, nlaws, nobservers, nstates;
    char summary[4096];       /* human-readable description for `floe check` */
} floe_scene_info;

/* Load a scene from a file (path) or from a string (text, with `path` used only in
 * messages). Observers write into outdir (created if missing; NULL = "out").
 * On success *out_world is a prepared-to-run world owned by the caller.
 * On failure returns an error code and writes "file:line:col: message" to err. */
int floe_scene_load(const char *path, const char *outdir, floe_world **out_world,
                    floe_scene_info *info, char *err, size_t errlen);
int floe_scene_load_string(const char *text, const char *path, const char *outdir,
                           floe_world **out_world, floe_scene_info *info,
                           char *err, size_t errlen);

/* Registers the built-in laws, shapes, outputs and integrators (floe_registry.h); idempotent. The scene
 * loader calls it; call it yourself before floe_registry_find or floe_register. */
int floe_register_builtins(char *err, size_t errlen);

/* Plugins (core/scene/plugin.c, docs/extending.md): loads the shared library at path and
 * calls its `int floe_plugin_init(char *err, size_t errlen)`, which registers shapes, laws
 * or outputs with floe_register. Loading the same path again does nothing. FLOE_EIO when it
 * cannot be loaded, FLOE_EINVAL without the init function, or the init's own error; the
 * message goes to err. The host program must export floe's symbols (the floe CLI does;
 * docs/extending.md says how for your own program). */
int floe_plugin_load(const char *path, char *err, size_t errlen);
/* Plugins loaded so far, and the path of plugin k. */
int floe_plugin_count(void);
const char *floe_plugin_path(int k);

/* The registries as text (`floe help`): kind NULL = every kind (shape, law, output), name
 * NULL = the list of a kind (or, with markdown, every entry in full); markdown = 1 writes
 * docs/reference.md (built-ins only). FLOE_EINVAL with a message for an unknown kind or
 * name. */
int floe_reference_write(FILE *f, const char *kind, const char *name, int markdown, char *err, size_t errlen);

/* The built-in default demo scene (YAML text). */
const char *floe_scene_default_demo(void);

/* Either form, with control over the outputs: text == NULL reads the file at path;
 * with_outputs == 0 validates the outputs section without creating any directory or file
 * (used by `floe check`). */
int floe_scene_load_ex(const char *path, const char *text, const char *outdir, int with_outputs,
                       floe_world **out_world, floe_scene_info *info, char *err, size_t errlen);

#endif
