/* errors.c - the error convention (floe_base.h, error_text.h): code names and messages. */
#include "floe_base.h"
#include "error_text.h"

#include <stdio.h>

const char *floe_strerror(int code) {
    switch (code) {
    case FLOE_OK: return "FLOE_OK";
    case FLOE_EINVAL: return "FLOE_EINVAL";
    case FLOE_ENOMEM: return "FLOE_ENOMEM";
    case FLOE_EIO: return "FLOE_EIO";
    case FLOE_EPARSE: return "FLOE_EPARSE";
    case FLOE_EUNSTABLE: return "FLOE_EUNSTABLE";
    case FLOE_ENOTSUP: return "FLOE_ENOTSUP";
    case FLOE_ESTOP: return "FLOE_ESTOP";
    default: return "FLOE_E?";
    }
}

int floe_error_vset(char *buf, size_t len, int code, const char *fmt, va_list ap) {
    if (buf && len) vsnprintf(buf, len, fmt, ap);
    return code;
}

int floe_error_set(char *buf, size_t len, int code, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    floe_error_vset(buf, len, code, fmt, ap);
    va_end(ap);
    return code;
}
