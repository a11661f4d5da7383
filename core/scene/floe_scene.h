/* floe_scene.h - YAML scene files (docs/scene-format.md), parsed with libfyaml.
 * Errors carry "file:line:column: message"; unknown keys name the closest valid key. */
#ifndef FLOE_SCENE_H
#define FLOE_SCENE_H

#include "floe_world.h"

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

/* The built-in default demo scene (YAML text). */
const char *floe_scene_default_demo(void);

/* Either form, with control over the outputs: text == NULL reads the file at path;
 * with_outputs == 0 validates the outputs section without creating any directory or file
 * (used by `floe check`). */
int floe_scene_load_ex(const char *path, const char *text, const char *outdir, int with_outputs,
                       floe_world **out_world, floe_scene_info *info, char *err, size_t errlen);

#endif
