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

/* FLOE_OK when the Lipschitz constant L of the shape `name` (worst pair a, b) is at most
 * FLOE_SDF_LIPSCHITZ_MAX, else FLOE_EINVAL with the message that names the contract */
int floe_lipschitz_verdict(const char *name, double L, const double a[3], const double b[3], char *err,
                           size_t errlen);

#endif
