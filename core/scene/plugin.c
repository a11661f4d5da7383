/* plugin.c - plugins: shared libraries that register components (floe_registry.h).
 *
 * A plugin exports `int floe_plugin_init(char *err, size_t errlen)`, which calls
 * floe_register for each of its shapes, laws or outputs exactly as the built-ins do, and
 * returns FLOE_OK (or an error code with a message). The host program (the floe CLI) is
 * linked with every library symbol exported (-rdynamic and the whole static library), so
 * a plugin links against nothing: it resolves floe's functions in the host. A plugin is
 * loaded once per path; its entries are then part of the registry for the process. */
#include "floe_scene.h"
#include "floe_registry.h"

#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef int (*plugin_init_fn)(char *err, size_t errlen);

typedef struct plugin_rec {
    char *path;
    void *handle;
} plugin_rec;

static plugin_rec *loaded;
static int nloaded;

int floe_plugin_load(const char *path, char *err, size_t errlen) {
    char dummy[8];
    if (!err || !errlen) { err = dummy; errlen = sizeof dummy; }
    err[0] = 0;
    if (!path || !path[0]) {
        snprintf(err, errlen, "plugin: empty path");
        return FLOE_EINVAL;
    }
    for (int k = 0; k < nloaded; k++)
        if (!strcmp(loaded[k].path, path)) return FLOE_OK; /* already loaded */
    FLOE_TRY(floe_register_builtins(err, errlen));
    void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        const char *why = dlerror();
        snprintf(err, errlen, "plugin %s: cannot load it: %s", path, why ? why : "unknown reason");
        return FLOE_EIO;
    }
    plugin_init_fn init;
    /* the POSIX-sanctioned way of turning dlsym's object pointer into a function pointer */
    *(void **)(&init) = dlsym(h, "floe_plugin_init");
    if (!init) {
        snprintf(err, errlen, "plugin %s: it has no floe_plugin_init function (int floe_plugin_init(char *err, "
                 "size_t errlen), docs/extending.md)", path);
        dlclose(h);
        return FLOE_EINVAL;
    }
    plugin_rec *nl = realloc(loaded, (size_t)(nloaded + 1) * sizeof *nl);
    char *copy = malloc(strlen(path) + 1);
    if (!nl || !copy) {
        free(copy);
        if (nl) loaded = nl;
        dlclose(h);
        snprintf(err, errlen, "out of memory");
        return FLOE_ENOMEM;
    }
    loaded = nl;
    strcpy(copy, path);
    /* the entries it registers keep pointers into it: it stays loaded for the process */
    loaded[nloaded].path = copy;
    loaded[nloaded].handle = h;
    nloaded++;
    char ierr[512] = "";
    floe_registry_set_origin(copy);
    int rc = init(ierr, sizeof ierr);
    floe_registry_set_origin(NULL);
    if (rc != FLOE_OK) {
        snprintf(err, errlen, "plugin %s: its init failed (%s): %s", path, floe_strerror(rc),
                 ierr[0] ? ierr : "no message");
        return rc;
    }
    return FLOE_OK;
}

int floe_plugin_count(void) { return nloaded; }

const char *floe_plugin_path(int k) { return k >= 0 && k < nloaded ? loaded[k].path : NULL; }
