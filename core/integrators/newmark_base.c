/* newmark_base.c - the bottom of the Newmark-beta solver's files: its error message (the
 * shared convention of core/base/error_text.h: a FLOE_E* code returned, the message kept
 * for floe_newmark_last_error) and its wall clock for the timing statistics. */
#include "newmark_base.h"
#include "error_text.h"

int nm_error(floe_newmark *s, int code, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    floe_error_vset(s->err, sizeof s->err, code, fmt, ap); /* the one convention (error_text.h) */
    va_end(ap);
    return code;
}

double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
