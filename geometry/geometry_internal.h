/* geometry_internal.h - helpers shared by the geometry sources (not installed). */
#ifndef FLOE_GEOMETRY_INTERNAL_H
#define FLOE_GEOMETRY_INTERNAL_H

#include <stddef.h>

/* printf into err[errlen] when err is given (constructors' error messages) */
void floe_set_err(char *err, size_t errlen, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#endif
