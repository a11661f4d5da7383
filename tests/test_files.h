/* test_files.h - reading back the small text files that the tests make their outputs write. */
#ifndef FLOE_TEST_FILES_H
#define FLOE_TEST_FILES_H

#include <stdio.h>
#include <stdlib.h>

/* Read a whole small text file, NUL-terminated (NULL if missing); the caller frees it. */
static inline char *slurp(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    if (!s) { fclose(f); return NULL; }
    size_t got = fread(s, 1, (size_t)n, f);
    s[got] = '\0';
    fclose(f);
    return s;
}
#endif
