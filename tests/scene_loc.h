/* scene_loc.h - "LINE:COL" (1-based) of the n-th (0-based) occurrence of needle in a scene
 * text, as the loader reports positions ("?:?" when absent); four static buffers, so four
 * results may be used at once. For tests/test_scene_errors.c and tests/test_scene_limits.c. */
#ifndef FLOE_TEST_SCENE_LOC_H
#define FLOE_TEST_SCENE_LOC_H
#include <stdio.h>
#include <string.h>

static const char *loc_of(const char *text, const char *needle, int nth)
{
    static char buf[4][32];
    static int slot = 0;
    const char *p = text;
    for (int k = 0; p && k <= nth; k++) {
        p = strstr(p, needle);
        if (p && k < nth) p++;
    }
    char *b = buf[slot++ % 4];
    if (!p) { snprintf(b, 32, "?:?"); return b; }
    int line = 1, col = 1;
    for (const char *q = text; q < p; q++) {
        if (*q == '\n') { line++; col = 1; }
        else col++;
    }
    snprintf(b, 32, "%d:%d", line, col);
    return b;
}

#endif
