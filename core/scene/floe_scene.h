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

/* Packings (floe_registry.h kind FLOE_KIND_PACKING): the particle generators of a scene's
 * `bodies: [{packing: NAME, shape, material, ..., <its parameters>}]`. The built-ins
 * (lattice, hexagonal, random; core/scene/packings.c) are read by the loader itself
 * (FLOE_ENTRY_LOADER_PARSES; their schemas document them). A registered packing of your
 * own gets its parameter struct (read by its schema), the scene's dimension and the
 * particle's bounding radius, and returns *n centres in *x (3n doubles, malloc'd; the
 * loader frees them) or an error code with a message; in 2D z must be 0. The loader keeps
 * the body keys (shape, material, velocity, angular_velocity, orientation, motion, name,
 * grow) for itself. */
typedef int (*floe_packing_create_fn)(const void *params, int dim, double bounding_radius, double **x, long *n,
                                      char *err, size_t errlen);
int floe_register_builtin_packings(char *err, size_t errlen);

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
/* The kinds floe help lists (shape, law, normal, tangential, output, ...): count and k-th. */
int floe_help_kind_count(void);
const char *floe_help_kind(int k);

/* A scene's `prepare` block (docs/granular.md, "Preparation") runs when the scene is loaded
 * for a run (not by `floe check`): its progress lines go to f (NULL, the default: silent;
 * the CLI may pass stderr). Process-wide. */
void floe_scene_set_prepare_log(FILE *f);

/* The built-in default demo scene (YAML text). */
const char *floe_scene_default_demo(void);

/* Either form, with control over the outputs: text == NULL reads the file at path;
 * with_outputs is one of
 *   FLOE_SCENE_RUN (1)        a run: the `prepare` block runs, the outputs are opened;
 *   FLOE_SCENE_NO_OUTPUTS (2) a run without files: the `prepare` block runs, the outputs
 *                             section is only validated (the Python package's outputs=False);
 *   FLOE_SCENE_CHECK (0)      `floe check`: neither runs; nothing is created. */
#define FLOE_SCENE_CHECK 0
#define FLOE_SCENE_RUN 1
#define FLOE_SCENE_NO_OUTPUTS 2
/* MPI runs (the CLI under mpirun, docs/parallel.md): what the loads of this thread that open
 * outputs (FLOE_SCENE_RUN) do with the scene's `vtk` outputs, until set again.
 *   FLOE_SCENE_VTK_SERIAL (0, the default): opened and attached like the other outputs;
 *   FLOE_SCENE_VTK_SKIP (1): validated, not opened (rank 0's mirror when the ranks write the
 *                            vtk pieces); the other outputs are opened;
 *   FLOE_SCENE_VTK_PIECES (2): only the vtk outputs are opened, each as the writer of rank
 *                            `rank`'s piece of `size` (floe_vtk_writer_create_piece), and
 *                            handed to take(ctx, o), which owns it from then on (a nonzero
 *                            return fails the load), instead of being attached to the world;
 *                            the other outputs are only validated.
 * rank, size, take and ctx are read in mode 2 only. FLOE_EINVAL for a mode or rank that does
 * not exist. */
#define FLOE_SCENE_VTK_SERIAL 0
#define FLOE_SCENE_VTK_SKIP 1
#define FLOE_SCENE_VTK_PIECES 2
int floe_scene_set_vtk_mode(int mode, int rank, int size, int (*take)(void *ctx, floe_observer *o), void *ctx);

int floe_scene_load_ex(const char *path, const char *text, const char *outdir, int with_outputs,
                       floe_world **out_world, floe_scene_info *info, char *err, size_t errlen);

#endif
