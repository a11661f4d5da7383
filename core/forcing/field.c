/* field.c - velocity fields of the ocean and the atmosphere (floe_forcing.h): the analytic
 * ones, and the dispatch to gridded data (netcdf_field.c). */
#include "floe_forcing.h"

#include <math.h>
#include <stdio.h>

static const char *const kind_names[] = {"uniform", "shear", "gyre", "vortex", "netcdf"};

const char *floe_field_kind_name(int kind) {
    return kind >= 0 && kind < (int)(sizeof kind_names / sizeof *kind_names) ? kind_names[kind] : NULL;
}

void floe_field_eval(const floe_field *f, const double x[3], double t, double u[3]) {
    /* the analytic fields are steady: only a grid reads t */
    u[0] = f->U[0];
    u[1] = f->U[1];
    u[2] = 0;
    double X = x[0] - f->center[0], Y = x[1] - f->center[1];
    switch (f->kind) {
    case FLOE_FIELD_SHEAR:
        u[0] += f->rate * Y;
        break;
    case FLOE_FIELD_GYRE: {
        /* psi = S L/pi sin(pi X/L) sin(pi Y/L): u = dpsi/dy, v = -dpsi/dx */
        double k = M_PI / f->length;
        u[0] += f->speed * sin(k * X) * cos(k * Y);
        u[1] -= f->speed * cos(k * X) * sin(k * Y);
        break;
    }
    case FLOE_FIELD_VORTEX: {
        /* sqrt, not hypot (a library call ten times dearer): distances of a domain, no overflow */
        const double r2 = X * X + Y * Y, R = f->length;
        if (r2 > 0) {
            const double w = r2 <= R * R ? f->speed / R : f->speed * R / r2; /* azimuthal speed / r */
            u[0] -= w * Y;
            u[1] += w * X;
        }
        break;
    }
    case FLOE_FIELD_GRID: {
        double g[3];
        floe_field_grid_eval(f->grid, x, t, g);
        u[0] += g[0];
        u[1] += g[1];
        break;
    }
    default:
        break;
    }
}

double floe_field_max_speed(const floe_field *f) {
    double u = hypot(f->U[0], f->U[1]);
    switch (f->kind) {
    case FLOE_FIELD_SHEAR: return f->rate != 0 ? INFINITY : u;
    case FLOE_FIELD_GYRE:
    case FLOE_FIELD_VORTEX: return u + fabs(f->speed);
    case FLOE_FIELD_GRID: return u + (f->grid ? floe_field_grid_max_speed(f->grid) : 0);
    default: return u;
    }
}

int floe_field_check(const floe_field *f, char *err, size_t errlen) {
    if (!floe_field_kind_name((int)f->kind)) {
        snprintf(err, errlen, "field: unknown kind %d", (int)f->kind);
        return FLOE_EINVAL;
    }
    const double v[] = {f->U[0], f->U[1], f->rate, f->speed, f->length, f->center[0], f->center[1]};
    for (size_t k = 0; k < sizeof v / sizeof *v; k++)
        if (!isfinite(v[k])) {
            snprintf(err, errlen, "field: every value must be finite");
            return FLOE_EINVAL;
        }
    if ((f->kind == FLOE_FIELD_GYRE || f->kind == FLOE_FIELD_VORTEX) && !(f->length > 0)) {
        snprintf(err, errlen, "field %s: length must be > 0 (m), got %g", kind_names[f->kind], f->length);
        return FLOE_EINVAL;
    }
    if (f->kind == FLOE_FIELD_GRID && !f->grid) {
        snprintf(err, errlen, "field netcdf: no grid data (floe_field.grid is NULL)");
        return FLOE_EINVAL;
    }
    return FLOE_OK;
}

int floe_field_covers(const floe_field *f, const double x[3], double r, int i, char *err, size_t errlen) {
    if (f->kind != FLOE_FIELD_GRID || !f->grid) return FLOE_OK;
    return floe_field_grid_covers(f->grid, x, r, i, err, errlen);
}
