/* error_text.h - the one error convention's message half (floe_base.h has the codes):
 * every component that keeps the message of its last error (the world, the Newmark
 * solver, ...) formats it into its buffer here and returns the code. Internal. */
#ifndef FLOE_ERROR_TEXT_H
#define FLOE_ERROR_TEXT_H

#include <stdarg.h>
#include <stddef.h>

/* Formats fmt into buf (len bytes, truncated; nothing when buf is NULL or len 0) and
 * returns code. */
int floe_error_vset(char *buf, size_t len, int code, const char *fmt, va_list ap);
int floe_error_set(char *buf, size_t len, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#endif
