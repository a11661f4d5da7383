/* fuzz_scene.c - libFuzzer harness over the scene loader (core/scene/scene.c): every input is a
 * scene text; floe_scene_load_ex must return (an error with a message, or a prepared world)
 * without crashing, leaking, hanging or invoking undefined behaviour. Outputs are validated
 * but not created (with_outputs = 0), so no file is written. Built by scripts/fuzz.sh
 * (CMake option FLOE_FUZZ=ON with clang); findings and run times: docs/robustness.md. */
#include "floe_scene.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1);
    if (!text) return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    char err[1024];
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_ex("fuzz.yaml", text, NULL, 0, &w, &info, err, sizeof err);
    /* the contract: an error always comes with a message naming the file, success with a world */
    if (rc != FLOE_OK && (w != NULL || strncmp(err, "fuzz.yaml", 9) != 0)) {
        fprintf(stderr, "fuzz_scene: rc %d with world %p and message '%s'\n", rc, (void *)w, err);
        abort();
    }
    if (rc == FLOE_OK && !w) {
        fprintf(stderr, "fuzz_scene: success without a world\n");
        abort();
    }
    floe_world_destroy(w);
    free(text);
    return 0;
}
