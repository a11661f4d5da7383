/* netcdf_field.c - gridded, time-varying velocity fields (floe_forcing.h, docs/sea-ice.md
 * "Velocity fields"): the grid (rectilinear, spacing uniform or not: cells found by
 * bisection), its interpolation (bilinear in x and y, linear in t, the point and the time
 * clamped into the grid), the map projections of grids in longitude and latitude
 * (equirectangular on a sphere; polar stereographic on an ellipsoid, Snyder 1987, "Map
 * Projections: A Working Manual", USGS Prof. Paper 1395, chapters 7, 14, 15, 20, 21), and
 * the reader of NetCDF files written with the CF conventions (CF 1.11: section 4 coordinate
 * types, 4.1 latitude and 4.2 longitude units, 4.4 time units "U since DATE", 8.1 packed
 * data scale_factor/add_offset, 2.5.1 _FillValue/missing_value), through libnetcdf (opened
 * at the first file read) when floe is built with FLOE_WITH_NETCDF. */
#include "floe_forcing.h"

#include <ctype.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef FLOE_HAVE_NETCDF
#include <dlfcn.h>
#include <netcdf.h>
#include <unistd.h>
#endif

/* ======================= map projections ======================= */

#define DEG (M_PI / 180)

/* a projection with its constants worked out */
typedef struct proj {
    floe_projection p;
    double R, c0;       /* equirectangular: R and R cos(lat0) */
    double a, e, K;     /* polar stereographic: rho = K t (Snyder 21-33, 21-34) */
    double sgn;         /* +1 north pole, -1 south */
} proj;

/* Snyder eq. 15-9: t(phi) = tan(pi/4 - phi/2) / [(1 - e sin phi)/(1 + e sin phi)]^(e/2) */
static double ps_t(double phi, double e) {
    const double es = e * sin(phi);
    return tan(M_PI / 4 - phi / 2) / pow((1 - es) / (1 + es), e / 2);
}

static void proj_init(proj *q, const floe_projection *p) {
    memset(q, 0, sizeof *q);
    q->p = *p;
    if (p->kind == FLOE_PROJECTION_EQUIRECTANGULAR) {
        q->R = FLOE_EARTH_RADIUS;
        q->c0 = q->R * cos(p->lat0 * DEG);
    } else if (p->kind == FLOE_PROJECTION_POLAR_STEREOGRAPHIC) {
        q->a = p->a > 0 ? p->a : FLOE_WGS84_A;
        const double rf = p->rf > 0 ? p->rf : FLOE_WGS84_RF, f = isinf(rf) ? 0 : 1 / rf;
        q->e = sqrt(f * (2 - f));
        q->sgn = p->lat_ts < 0 ? -1 : 1;
        const double pc = q->sgn * p->lat_ts * DEG, e = q->e; /* the north pole's formulas */
        if (pc >= M_PI / 2) /* true scale at the pole, k0 = 1: Snyder eq. 21-33 */
            q->K = 2 * q->a / sqrt(pow(1 + e, 1 + e) * pow(1 - e, 1 - e));
        else /* eq. 21-34 with m_c from eq. 14-15: m = cos phi / sqrt(1 - e^2 sin^2 phi) */
            q->K = q->a * cos(pc) / sqrt(1 - e * e * sin(pc) * sin(pc)) / ps_t(pc, e);
    }
}

static void proj_forward(const proj *q, const double ll[2], double xy[2]) {
    switch (q->p.kind) {
    case FLOE_PROJECTION_EQUIRECTANGULAR:
        xy[0] = q->c0 * (ll[0] - q->p.lon0) * DEG;
        xy[1] = q->R * (ll[1] - q->p.lat0) * DEG;
        break;
    case FLOE_PROJECTION_POLAR_STEREOGRAPHIC: {
        /* the south pole's aspect is the north's with phi, lambda, lambda0, x and y negated */
        const double s = q->sgn, rho = q->K * ps_t(s * ll[1] * DEG, q->e), dl = (ll[0] - q->p.lon0) * DEG;
        xy[0] = rho * sin(dl);      /* eq. 21-30 */
        xy[1] = -s * rho * cos(dl); /* eq. 21-31 */
        break;
    }
    default:
        xy[0] = ll[0];
        xy[1] = ll[1];
    }
}

static void proj_inverse(const proj *q, const double xy[2], double ll[2]) {
    switch (q->p.kind) {
    case FLOE_PROJECTION_EQUIRECTANGULAR:
        ll[0] = q->p.lon0 + xy[0] / q->c0 / DEG;
        ll[1] = q->p.lat0 + xy[1] / q->R / DEG;
        break;
    case FLOE_PROJECTION_POLAR_STEREOGRAPHIC: {
        const double s = q->sgn, e = q->e, rho = hypot(xy[0], xy[1]); /* eq. 20-18 */
        const double t = rho / q->K;                                   /* eqs. 21-39, 21-40 */
        double phi = M_PI / 2 - 2 * atan(t);                           /* eq. 7-11, then 7-9 */
        for (int k = 0; k < 30; k++) {
            const double es = e * sin(phi), next = M_PI / 2 - 2 * atan(t * pow((1 - es) / (1 + es), e / 2));
            const double d = fabs(next - phi);
            phi = next;
            if (d <= 1e-15) break;
        }
        ll[1] = s * phi / DEG;
        ll[0] = q->p.lon0 + (rho > 0 ? atan2(xy[0], -s * xy[1]) / DEG : 0); /* eq. 20-16 */
        break;
    }
    default:
        ll[0] = xy[0];
        ll[1] = xy[1];
    }
}

static double proj_east_angle(const proj *q, const double xy[2]) {
    if (q->p.kind != FLOE_PROJECTION_POLAR_STEREOGRAPHIC || (xy[0] == 0 && xy[1] == 0)) return 0;
    /* east is along the parallel (a circle about the pole): d(x, y)/d lambda */
    return q->sgn * atan2(xy[0], -q->sgn * xy[1]);
}

int floe_projection_check(const floe_projection *p, char *err, size_t errlen) {
    if (!p || (unsigned)p->kind > FLOE_PROJECTION_POLAR_STEREOGRAPHIC) {
        snprintf(err, errlen, "projection: unknown kind %d", p ? (int)p->kind : -1);
        return FLOE_EINVAL;
    }
    if (!isfinite(p->lon0) || !isfinite(p->lat0) || !isfinite(p->lat_ts) || !isfinite(p->a) || isnan(p->rf)) {
        snprintf(err, errlen, "projection: lon0, lat0, lat_ts and a must be finite");
        return FLOE_EINVAL;
    }
    if (p->kind == FLOE_PROJECTION_EQUIRECTANGULAR && !(fabs(p->lat0) < 90)) {
        snprintf(err, errlen, "projection equirectangular: lat0 must be in (-90, 90) degrees, got %g", p->lat0);
        return FLOE_EINVAL;
    }
    if (p->kind == FLOE_PROJECTION_POLAR_STEREOGRAPHIC) {
        if (!(fabs(p->lat_ts) <= 90) || p->lat_ts == 0) {
            snprintf(err, errlen, "projection polar_stereographic: lat_ts must be in [-90, 0) (south pole) or (0, 90] "
                     "(north pole) degrees, got %g", p->lat_ts);
            return FLOE_EINVAL;
        }
        if (p->a < 0 || (p->rf != 0 && !(p->rf > 1))) {
            snprintf(err, errlen, "projection polar_stereographic: the ellipsoid needs a > 0 (m) and rf > 1 (0: WGS84), "
                     "got a = %g, rf = %g", p->a, p->rf);
            return FLOE_EINVAL;
        }
    }
    return FLOE_OK;
}

void floe_projection_forward(const floe_projection *p, const double lonlat[2], double xy[2]) {
    proj q;
    proj_init(&q, p);
    proj_forward(&q, lonlat, xy);
}

void floe_projection_inverse(const floe_projection *p, const double xy[2], double lonlat[2]) {
    proj q;
    proj_init(&q, p);
    proj_inverse(&q, xy, lonlat);
}

double floe_projection_east_angle(const floe_projection *p, const double xy[2]) {
    proj q;
    proj_init(&q, p);
    return proj_east_angle(&q, xy);
}

/* ======================= the grid ======================= */

struct floe_field_grid {
    atomic_int refs;
    int nx, ny, nt;
    double *x, *y, *t;  /* nodes (m, m; or lon, lat in degrees when projected) and record times (s) */
    double *u, *v;      /* nt ny nx: record k, row j, column i at (k ny + j) nx + i */
    double umax, gmax;  /* largest |u| (m/s) and velocity gradient component (1/s, per scene metre) */
    proj pr;            /* the scene's map onto (x, y) (kind NONE: the identity) */
    char label[512];    /* the file, for messages */
};

floe_field_grid_def floe_field_grid_default(void) {
    floe_field_grid_def d = {.file = NULL, .u_var = "u", .v_var = "v", .x_var = "x", .y_var = "y",
                             .time_var = "time", .scale = 1.0};
    return d;
}

static void grid_free(floe_field_grid *g) {
    if (!g) return;
    free(g->x);
    free(g->y);
    free(g->t);
    free(g->u);
    free(g->v);
    free(g);
}

floe_field_grid *floe_field_grid_retain(floe_field_grid *g) {
    if (g) atomic_fetch_add(&g->refs, 1);
    return g;
}

void floe_field_grid_release(floe_field_grid *g) {
    if (g && atomic_fetch_sub(&g->refs, 1) == 1) grid_free(g);
}

/* the coordinate c[n] named `name`: finite, strictly increasing, with `least` values at least */
static int check_axis(const double *c, int n, int least, const char *label, const char *name, char *err,
                      size_t errlen) {
    if (n < least) {
        snprintf(err, errlen, "field file %s: '%s' has %d value%s: a grid needs at least %d along each axis", label,
                 name, n, n == 1 ? "" : "s", least);
        return FLOE_EINVAL;
    }
    for (int k = 0; k < n; k++) {
        if (!isfinite(c[k])) {
            snprintf(err, errlen, "field file %s: '%s'[%d] is not finite (%g)", label, name, k, c[k]);
            return FLOE_EINVAL;
        }
        if (k && !(c[k] > c[k - 1])) {
            snprintf(err, errlen, "field file %s: '%s' is not strictly increasing ('%s'[%d] = %.17g after '%s'[%d] = "
                     "%.17g)", label, name, name, k, c[k], name, k - 1, c[k - 1]);
            return FLOE_EINVAL;
        }
    }
    return FLOE_OK;
}

static double *copy_of(const double *a, size_t n) {
    double *c = malloc(n * sizeof *c);
    if (c) memcpy(c, a, n * sizeof *c);
    return c;
}

/* the scene distance between nodes (i, j) and (i + di, j + dj) */
static double node_distance(const floe_field_grid *g, int i, int j, int di, int dj) {
    if (g->pr.p.kind == FLOE_PROJECTION_NONE) return di ? g->x[i + 1] - g->x[i] : g->y[j + 1] - g->y[j];
    const double a[2] = {g->x[i], g->y[j]}, b[2] = {g->x[i + di], g->y[j + dj]};
    double pa[2], pb[2];
    proj_forward(&g->pr, a, pa);
    proj_forward(&g->pr, b, pb);
    return hypot(pb[0] - pa[0], pb[1] - pa[1]);
}

/* the largest |u| and velocity gradient component (differences along the cells' edges, per
 * metre of the scene; two nodes on one point, a pole, are skipped) */
static void grid_bounds(floe_field_grid *g) {
    const int nx = g->nx, ny = g->ny;
    double um = 0, gm = 0;
    for (int k = 0; k < g->nt; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                const size_t o = ((size_t)k * ny + j) * nx + i;
                um = fmax(um, hypot(g->u[o], g->v[o]));
                if (i + 1 < nx) {
                    const double h = node_distance(g, i, j, 1, 0);
                    if (h > 0) gm = fmax(gm, fmax(fabs(g->u[o + 1] - g->u[o]), fabs(g->v[o + 1] - g->v[o])) / h);
                }
                if (j + 1 < ny) {
                    const double h = node_distance(g, i, j, 0, 1);
                    if (h > 0) gm = fmax(gm, fmax(fabs(g->u[o + nx] - g->u[o]), fabs(g->v[o + nx] - g->v[o])) / h);
                }
            }
    g->umax = um;
    g->gmax = gm;
}

/* builds a grid that takes the arrays (on success and on failure); names: of x, y and time */
static floe_field_grid *grid_build(int nx, double *x, int ny, double *y, int nt, double *t, double *u, double *v,
                                   const floe_projection *pj, const char *label, const char *const names[3],
                                   char *err, size_t errlen) {
    floe_field_grid *g = calloc(1, sizeof *g);
    if (!g || !x || !y || !t || !u || !v) {
        snprintf(err, errlen, "field file %s: out of memory", label);
        free(g), free(x), free(y), free(t), free(u), free(v);
        return NULL;
    }
    atomic_init(&g->refs, 1);
    g->nx = nx, g->ny = ny, g->nt = nt;
    g->x = x, g->y = y, g->t = t, g->u = u, g->v = v;
    snprintf(g->label, sizeof g->label, "%s", label);
    if (check_axis(x, nx, 2, label, names[0], err, errlen) || check_axis(y, ny, 2, label, names[1], err, errlen) ||
        check_axis(t, nt, 1, label, names[2], err, errlen)) {
        grid_free(g);
        return NULL;
    }
    if (pj && pj->kind != FLOE_PROJECTION_NONE) {
        char why[256];
        if (floe_projection_check(pj, why, sizeof why)) {
            snprintf(err, errlen, "field file %s: %s", label, why);
            grid_free(g);
            return NULL;
        }
        /* latitudes on the sphere; the polar stereographic sends the other pole to infinity */
        const double far = pj->kind == FLOE_PROJECTION_POLAR_STEREOGRAPHIC ? (pj->lat_ts < 0 ? 90 : -90) : 0;
        if (y[0] < -90 || y[ny - 1] > 90 || (far && (y[0] == far || y[ny - 1] == far))) {
            snprintf(err, errlen, "field file %s: the latitude '%s' spans [%g, %g] degrees: it must lie in [-90, 90]%s",
                     label, names[1], y[0], y[ny - 1], far ? ", without the pole opposite to the polar stereographic's" : "");
            grid_free(g);
            return NULL;
        }
        proj_init(&g->pr, pj);
    }
    const size_t n = (size_t)nt * ny * nx;
    for (size_t k = 0; k < n; k++)
        if (!isfinite(u[k]) || !isfinite(v[k])) {
            snprintf(err, errlen, "field file %s: the velocity at value %zu is not finite (%g, %g)", label, k, u[k],
                     v[k]);
            grid_free(g);
            return NULL;
        }
    grid_bounds(g);
    return g;
}

/* n1 n2 n3 values fit in memory addresses */
static int size_ok(double n1, double n2, double n3) { return n1 * n2 * n3 * sizeof(double) < (double)SIZE_MAX / 4; }

floe_field_grid *floe_field_grid_create(int nx, const double *x, int ny, const double *y, int nt, const double *t,
                                        const double *u, const double *v, const char *label, char *err,
                                        size_t errlen) {
    if (!label) label = "(arrays)";
    if (!x || !y || !t || !u || !v || nx < 0 || ny < 0 || nt < 1 || !size_ok(nx, ny, nt)) {
        snprintf(err, errlen, "field file %s: the grid needs x, y, t, u and v (nt >= 1)", label);
        return NULL;
    }
    const size_t n = (size_t)nt * ny * nx;
    static const char *const names[3] = {"x", "y", "t"};
    return grid_build(nx, copy_of(x, (size_t)nx), ny, copy_of(y, (size_t)ny), nt, copy_of(t, (size_t)nt),
                      copy_of(u, n), copy_of(v, n), NULL, label, names, err, errlen);
}

/* the cell [c[i], c[i+1]] holding s (clamped into [c[0], c[n-1]]) and the fraction f of s in it */
static int cell_of(const double *c, int n, double s, double *f) {
    if (n < 2 || s <= c[0]) {
        *f = 0;
        return 0;
    }
    if (s >= c[n - 1]) {
        *f = 1;
        return n - 2;
    }
    int lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        const int mid = lo + (hi - lo) / 2;
        if (c[mid] <= s) lo = mid;
        else hi = mid;
    }
    *f = (s - c[lo]) / (c[lo + 1] - c[lo]);
    return lo;
}

static double bilinear(const double *a, int nx, double fx, double fy) {
    return (1 - fy) * ((1 - fx) * a[0] + fx * a[1]) + fy * ((1 - fx) * a[nx] + fx * a[nx + 1]);
}

/* longitude lon taken modulo 360 into [lo, lo + 360) */
static double wrap_lon(double lon, double lo) { return lon - 360 * floor((lon - lo) / 360); }

void floe_field_grid_eval(const floe_field_grid *g, const double x[3], double t, double u[3]) {
    double fx, fy, ft, p[2] = {x[0], x[1]};
    if (g->pr.p.kind != FLOE_PROJECTION_NONE) {
        proj_inverse(&g->pr, x, p);
        p[0] = wrap_lon(p[0], g->x[0]);
    }
    const int i = cell_of(g->x, g->nx, p[0], &fx), j = cell_of(g->y, g->ny, p[1], &fy);
    const int k = cell_of(g->t, g->nt, t, &ft);
    const size_t o = ((size_t)k * g->ny + j) * g->nx + i, rec = (size_t)g->ny * g->nx;
    u[0] = bilinear(g->u + o, g->nx, fx, fy);
    u[1] = bilinear(g->v + o, g->nx, fx, fy);
    u[2] = 0;
    if (g->nt > 1) {
        u[0] = (1 - ft) * u[0] + ft * bilinear(g->u + o + rec, g->nx, fx, fy);
        u[1] = (1 - ft) * u[1] + ft * bilinear(g->v + o + rec, g->nx, fx, fy);
    }
    const double a = proj_east_angle(&g->pr, x);
    if (a != 0) { /* (east, north) turned into (x, y) */
        const double c = cos(a), s = sin(a), ue = u[0];
        u[0] = c * ue - s * u[1];
        u[1] = s * ue + c * u[1];
    }
}

void floe_field_grid_extent(const floe_field_grid *g, double lo[2], double hi[2], double t[2]) {
    lo[0] = g->x[0];
    hi[0] = g->x[g->nx - 1];
    lo[1] = g->y[0];
    hi[1] = g->y[g->ny - 1];
    t[0] = g->t[0];
    t[1] = g->t[g->nt - 1];
}

floe_projection floe_field_grid_projection(const floe_field_grid *g) { return g->pr.p; }

/* the longitude and latitude ranges of the scene's box [c - r, c + r] (degrees, lon[0] from
 * the projection's inverse, lon[1] - lon[0] < 360); *all: every longitude (the box holds the
 * polar stereographic's pole) */
static void box_lonlat(const proj *q, const double c[2], double r, double lon[2], double lat[2], int *all) {
    const double xs[2] = {c[0] - r, c[0] + r}, ys[2] = {c[1] - r, c[1] + r};
    *all = 0;
    if (q->p.kind == FLOE_PROJECTION_EQUIRECTANGULAR) { /* affine, increasing */
        double lo[2], hi[2];
        const double a[2] = {xs[0], ys[0]}, b[2] = {xs[1], ys[1]};
        proj_inverse(q, a, lo);
        proj_inverse(q, b, hi);
        lon[0] = lo[0], lon[1] = hi[0], lat[0] = lo[1], lat[1] = hi[1];
        return;
    }
    /* polar stereographic: the latitude is monotone in the distance rho to the pole, the
     * longitude the angle about it: the nearest and farthest points of the box give the
     * latitudes, its corners the longitudes (seen from outside, a convex box spans less than
     * 180 degrees about the pole, between two of its corners) */
    const double dx = fmax(0, fmax(xs[0], -xs[1])), dy = fmax(0, fmax(ys[0], -ys[1]));
    double rmax = 0, ll[2], l0 = 0, dmin = 0, dmax = 0;
    for (int k = 0; k < 4; k++) {
        const double p[2] = {xs[k & 1], ys[k >> 1]};
        rmax = fmax(rmax, hypot(p[0], p[1]));
        proj_inverse(q, p, ll);
        if (k == 0) l0 = ll[0];
        const double d = remainder(ll[0] - l0, 360);
        dmin = fmin(dmin, d);
        dmax = fmax(dmax, d);
    }
    const double pn[2] = {hypot(dx, dy), 0}, pf[2] = {rmax, 0};
    double ln[2], lf[2];
    proj_inverse(q, pn, ln);
    proj_inverse(q, pf, lf);
    lat[0] = fmin(ln[1], lf[1]);
    lat[1] = fmax(ln[1], lf[1]);
    *all = dx == 0 && dy == 0;
    lon[0] = l0 + dmin;
    lon[1] = l0 + dmax;
}

int floe_field_grid_covers(const floe_field_grid *g, const double x[3], double r, int i, char *err, size_t errlen) {
    const double lo[2] = {g->x[0], g->y[0]}, hi[2] = {g->x[g->nx - 1], g->y[g->ny - 1]};
    if (g->pr.p.kind == FLOE_PROJECTION_NONE) {
        if (x[0] - r >= lo[0] && x[0] + r <= hi[0] && x[1] - r >= lo[1] && x[1] + r <= hi[1]) return FLOE_OK;
        snprintf(err, errlen, "field file %s: the grid x in [%g, %g], y in [%g, %g] does not cover particle %d at "
                 "(%g, %g) (radius %g)", g->label, lo[0], hi[0], lo[1], hi[1], i, x[0], x[1], r);
        return FLOE_EINVAL;
    }
    double lon[2], lat[2];
    int all;
    box_lonlat(&g->pr, x, r, lon, lat, &all);
    const double w0 = wrap_lon(lon[0], lo[0]), w1 = lon[1] + (w0 - lon[0]);
    const int in_lon = all ? hi[0] - lo[0] >= 360 : w1 <= hi[0];
    if (in_lon && lat[0] >= lo[1] && lat[1] <= hi[1]) return FLOE_OK;
    char span[96];
    if (all) snprintf(span, sizeof span, "every longitude (it holds the pole)");
    else snprintf(span, sizeof span, "lon [%.6g, %.6g]", w0, w1);
    snprintf(err, errlen, "field file %s: the grid lon in [%g, %g], lat in [%g, %g] (degrees) does not cover particle %d "
             "at (%g, %g) (radius %g): its box spans %s, lat [%.6g, %.6g]", g->label, lo[0], hi[0], lo[1], hi[1], i,
             x[0], x[1], r, span, lat[0], lat[1]);
    return FLOE_EINVAL;
}

const char *floe_field_grid_label(const floe_field_grid *g) { return g->label; }
double floe_field_grid_max_speed(const floe_field_grid *g) { return g->umax; }
double floe_field_grid_max_gradient(const floe_field_grid *g) { return g->gmax; }

/* ======================= the NetCDF reader ======================= */

#ifdef FLOE_HAVE_NETCDF

int floe_field_grid_netcdf(void) { return 1; }

/* libnetcdf is opened with dlopen when a file is read, not linked: it brings HDF5, curl and
 * TLS libraries whose loading costs every floe process about 10 MB of memory and 30 ms,
 * field file or not. The functions floe calls, typed as their netcdf.h prototypes (checked
 * at compile time, without referring to the symbols). */
#define NC_FUNCTIONS(X) \
    X(open, int, (const char *, int, int *)) \
    X(close, int, (int)) \
    X(strerror, const char *, (int)) \
    X(inq_varid, int, (int, const char *, int *)) \
    X(inq_nvars, int, (int, int *)) \
    X(inq_varname, int, (int, int, char *)) \
    X(inq_varndims, int, (int, int, int *)) \
    X(inq_vardimid, int, (int, int, int *)) \
    X(inq_vartype, int, (int, int, nc_type *)) \
    X(inq_dim, int, (int, int, char *, size_t *)) \
    X(inq_dimname, int, (int, int, char *)) \
    X(inq_dimlen, int, (int, int, size_t *)) \
    X(inq_att, int, (int, int, const char *, nc_type *, size_t *)) \
    X(get_att_text, int, (int, int, const char *, char *)) \
    X(get_att_string, int, (int, int, const char *, char **)) \
    X(free_string, int, (size_t, char **)) \
    X(get_att_double, int, (int, int, const char *, double *)) \
    X(get_var_double, int, (int, int, double *))

#define NC_TYPEDEF(name, ret, args) typedef ret(*nc_##name##_fn) args;
NC_FUNCTIONS(NC_TYPEDEF)
#define NC_MEMBER(name, ret, args) nc_##name##_fn name;
typedef struct nc_api {
    NC_FUNCTIONS(NC_MEMBER)
} nc_api;
#define NC_TYPED(name, ret, args) \
    _Static_assert(_Generic(&nc_##name, nc_##name##_fn: 1, default: 0), "nc_" #name " as in netcdf.h");
NC_FUNCTIONS(NC_TYPED)

/* the library found at configure time: its SONAME (libnetcdf.so.19), searched as the
 * dynamic loader does, then its path */
#ifndef FLOE_NETCDF_SONAME
#define FLOE_NETCDF_SONAME "libnetcdf.so"
#endif
#ifndef FLOE_NETCDF_PATH
#define FLOE_NETCDF_PATH "libnetcdf.so"
#endif

/* fills f from libnetcdf; FLOE_OK or a message in err. The library is never closed (dlopen
 * counts the references; HDF5, under it, registers exit handlers), so that it is loaded once
 * per process and every later call is a lookup. */
static int nc_api_load(nc_api *f, const char *file, char *err, size_t errlen) {
    static const char *const libs[] = {FLOE_NETCDF_SONAME, FLOE_NETCDF_PATH};
    void *h = NULL;
    char why[256] = "";
    for (size_t k = 0; k < sizeof libs / sizeof *libs && !h; k++) {
        h = dlopen(libs[k], RTLD_NOW | RTLD_LOCAL);
        const char *e = h ? NULL : dlerror();
        if (e && k == 0) snprintf(why, sizeof why, "%s", e);
    }
    if (!h) {
        snprintf(err, errlen, "field file %s: cannot load the NetCDF library %s (%s): install libnetcdf (Debian "
                 "package libnetcdf-dev)", file, FLOE_NETCDF_SONAME, why);
        return FLOE_ENOTSUP;
    }
#define NC_NAME(name, ret, args) "nc_" #name,
#define NC_SLOT(name, ret, args) (void **)&f->name,
    static const char *const names[] = {NC_FUNCTIONS(NC_NAME)};
    void **slot[] = {NC_FUNCTIONS(NC_SLOT)};
    for (size_t k = 0; k < sizeof slot / sizeof *slot; k++) {
        void *sym = dlsym(h, names[k]);
        if (!sym) {
            snprintf(err, errlen, "field file %s: the NetCDF library has no %s", file, names[k]);
            return FLOE_ENOTSUP;
        }
        memcpy(slot[k], &sym, sizeof sym); /* POSIX: a data pointer converts to a function pointer */
    }
    return FLOE_OK;
}

typedef struct ncr {
    nc_api f;
    int nc;           /* the open file */
    const char *file;
    char *err;
    size_t errlen;
    int projected;    /* x and y are longitude and latitude (a projection was given) */
} ncr;

/* the message of a libnetcdf status */
static int nc_fail(ncr *r, int status, const char *what) {
    snprintf(r->err, r->errlen, "field file %s: %s: %s", r->file, what, r->f.strerror(status));
    return FLOE_EINVAL;
}

/* the id of variable `name`; missing: the message lists the file's variables */
static int var_id(ncr *r, const char *name, int *id) {
    if (r->f.inq_varid(r->nc, name, id) == NC_NOERR) return FLOE_OK;
    char list[768] = "";
    int nv = 0;
    r->f.inq_nvars(r->nc, &nv);
    size_t at = 0;
    for (int k = 0; k < nv && at + 4 < sizeof list; k++) {
        char vn[NC_MAX_NAME + 1];
        if (r->f.inq_varname(r->nc, k, vn) != NC_NOERR) continue;
        at += (size_t)snprintf(list + at, sizeof list - at, "%s%s", k ? ", " : "", vn);
    }
    snprintf(r->err, r->errlen, "field file %s has no variable '%s' (it has: %s)", r->file, name,
             nv ? list : "no variables");
    return FLOE_EINVAL;
}

/* text attribute `name` of variable var into buf: 1, or 0 when absent or not text */
static int att_text(const ncr *r, int var, const char *name, char *buf, size_t len) {
    nc_type ty;
    size_t n;
    buf[0] = 0;
    if (r->f.inq_att(r->nc, var, name, &ty, &n) != NC_NOERR) return 0;
    if (ty == NC_CHAR) {
        char *all = malloc(n + 1);
        int ok = all && r->f.get_att_text(r->nc, var, name, all) == NC_NOERR;
        if (ok) {
            size_t m = n < len - 1 ? n : len - 1;
            memcpy(buf, all, m);
            buf[m] = 0;
        }
        free(all);
        return ok;
    }
    if (ty == NC_STRING && n >= 1) {
        char **s = calloc(n, sizeof *s);
        int ok = s && r->f.get_att_string(r->nc, var, name, s) == NC_NOERR;
        if (ok) snprintf(buf, len, "%s", s[0] ? s[0] : "");
        if (ok) r->f.free_string(n, s);
        free(s);
        return ok;
    }
    return 0;
}

/* numeric attribute `name` of var: up to max values into vals; their count (0 when absent or text) */
static int att_doubles(const ncr *r, int var, const char *name, double *vals, int max) {
    nc_type ty;
    size_t n;
    if (r->f.inq_att(r->nc, var, name, &ty, &n) != NC_NOERR || ty == NC_CHAR || ty == NC_STRING || n == 0) return 0;
    double *all = malloc(n * sizeof *all);
    if (!all || r->f.get_att_double(r->nc, var, name, all) != NC_NOERR) {
        free(all);
        return 0;
    }
    int k = (int)(n < (size_t)max ? n : (size_t)max);
    memcpy(vals, all, (size_t)k * sizeof *vals);
    free(all);
    return k;
}

/* the default fill value of a type (netcdf.h NC_FILL_*): 0 when reading does not check one
 * (bytes and characters, as the NetCDF user guide says) */
static int default_fill(nc_type ty, double *f) {
    switch (ty) {
    case NC_DOUBLE: *f = NC_FILL_DOUBLE; return 1;
    case NC_FLOAT: *f = NC_FILL_FLOAT; return 1;
    case NC_SHORT: *f = NC_FILL_SHORT; return 1;
    case NC_INT: *f = NC_FILL_INT; return 1;
    case NC_USHORT: *f = NC_FILL_USHORT; return 1;
    case NC_UINT: *f = NC_FILL_UINT; return 1;
    case NC_INT64: *f = (double)NC_FILL_INT64; return 1;
    case NC_UINT64: *f = (double)NC_FILL_UINT64; return 1;
    default: return 0;
    }
}

/* "(time, y, x)" and "(3, 4, 5)": the dimension names and lengths of a variable */
static void dims_text(const ncr *r, int nd, const int *dims, char *names, char *lens, size_t len) {
    size_t a = 0, b = 0;
    a += (size_t)snprintf(names, len, "(");
    b += (size_t)snprintf(lens, len, "(");
    for (int k = 0; k < nd && a < len && b < len; k++) {
        char dn[NC_MAX_NAME + 1] = "?";
        size_t dl = 0;
        r->f.inq_dim(r->nc, dims[k], dn, &dl);
        a += (size_t)snprintf(names + a, len - a, "%s%s", k ? ", " : "", dn);
        b += (size_t)snprintf(lens + b, len - b, "%s%zu", k ? ", " : "", dl);
    }
    if (a < len) snprintf(names + a, len - a, ")");
    if (b < len) snprintf(lens + b, len - b, ")");
}

/* reads variable var (`name`, nd dimensions of lengths dl) as double: refuses fill values and
 * non-finite numbers (naming the index), then unpacks it (CF 8.1: scale_factor, add_offset) */
static int read_values(ncr *r, int var, const char *name, int nd, const size_t *dl, double **out) {
    size_t n = 1;
    for (int k = 0; k < nd; k++) n *= dl[k];
    double *a = malloc((n ? n : 1) * sizeof *a);
    if (!a) {
        snprintf(r->err, r->errlen, "field file %s: out of memory reading '%s' (%zu values)", r->file, name, n);
        return FLOE_ENOMEM;
    }
    int st = r->f.get_var_double(r->nc, var, a);
    if (st != NC_NOERR) {
        free(a);
        char what[NC_MAX_NAME + 32];
        snprintf(what, sizeof what, "reading '%s'", name);
        return nc_fail(r, st, what);
    }
    double fill[9];
    const char *fname[9];
    int nf = att_doubles(r, var, "_FillValue", fill, 1);
    if (nf) fname[0] = "_FillValue";
    else {
        nc_type ty;
        if (r->f.inq_vartype(r->nc, var, &ty) == NC_NOERR && default_fill(ty, fill)) fname[nf++] = "the default fill value";
    }
    int nm = att_doubles(r, var, "missing_value", fill + nf, 8);
    for (int k = 0; k < nm; k++) fname[nf + k] = "missing_value";
    nf += nm;
    double sf = 1, ao = 0;
    att_doubles(r, var, "scale_factor", &sf, 1);
    att_doubles(r, var, "add_offset", &ao, 1);
    for (size_t k = 0; k < n; k++) {
        int bad = -1;
        for (int m = 0; m < nf && bad < 0; m++)
            if (a[k] == fill[m]) bad = m;
        if (bad >= 0 || !isfinite(a[k])) {
            char idx[96] = "", dn[256], dlen[256];
            size_t rest = k, at = 0;
            size_t sub[NC_MAX_VAR_DIMS];
            for (int d = nd - 1; d >= 0; d--) {
                sub[d] = dl[d] ? rest % dl[d] : 0;
                rest = dl[d] ? rest / dl[d] : 0;
            }
            for (int d = 0; d < nd && at < sizeof idx; d++)
                at += (size_t)snprintf(idx + at, sizeof idx - at, "%s%zu", d ? ", " : "", sub[d]);
            int dims[NC_MAX_VAR_DIMS];
            r->f.inq_vardimid(r->nc, var, dims);
            dims_text(r, nd, dims, dn, dlen, sizeof dn);
            if (bad >= 0)
                snprintf(r->err, r->errlen, "field file %s: variable '%s' holds a fill value (%s %g) at index [%s] %s: "
                         "missing data are not supported (fill them or cut the grid)", r->file, name, fname[bad],
                         fill[bad], idx, dn);
            else
                snprintf(r->err, r->errlen, "field file %s: variable '%s' holds %g at index [%s] %s", r->file, name,
                         a[k], idx, dn);
            free(a);
            return FLOE_EINVAL;
        }
        a[k] = a[k] * sf + ao;
    }
    *out = a;
    return FLOE_OK;
}

/* a lower-case copy of s (up to len) */
static void lower(char *d, const char *s, size_t len) {
    size_t k = 0;
    for (; s[k] && k + 1 < len; k++) d[k] = (char)tolower((unsigned char)s[k]);
    d[k] = 0;
}

static int word_in(const char *w, const char *const *list) {
    for (; *list; list++)
        if (!strcmp(w, *list)) return 1;
    return 0;
}

/* CF 4.1, 4.2: "degrees_east" (also degree_east, degree_E, degrees_E, degreeE, degreesE),
 * "degrees_north" (the same forms with N), plain "degrees": 'e', 'n', 'd'; 0 otherwise */
static char degree_kind(const char *lu) {
    if (strncmp(lu, "degree", 6)) return 0;
    const char *r = lu + 6;
    if (*r == 's') r++;
    if (*r == '_') r++;
    if (!*r) return 'd';
    if (!strcmp(r, "east") || !strcmp(r, "e")) return 'e';
    if (!strcmp(r, "north") || !strcmp(r, "n")) return 'n';
    return 0;
}

/* the factor to metres of a coordinate's units (absent: metres); with a projection, a
 * longitude (axis 0) or latitude (axis 1) in degrees (absent: degrees) */
static int coordinate_units(ncr *r, int var, const char *name, int axis, double *to_m) {
    char u[128], lu[128];
    *to_m = 1;
    if (!att_text(r, var, "units", u, sizeof u)) return FLOE_OK;
    lower(lu, u, sizeof lu);
    static const char *const m[] = {"m", "meter", "meters", "metre", "metres", NULL};
    static const char *const km[] = {"km", "kilometer", "kilometers", "kilometre", "kilometres", NULL};
    const char deg = degree_kind(lu);
    const int metres = word_in(lu, m) || word_in(lu, km);
    if (r->projected) {
        if (deg == (axis ? 'e' : 'n'))
            snprintf(r->err, r->errlen, "field file %s: '%s' is a %s (units '%s'): %s must name the %s (units %s)",
                     r->file, name, axis ? "longitude" : "latitude", u, axis ? "y_var" : "x_var",
                     axis ? "latitude" : "longitude", axis ? "degrees_north" : "degrees_east");
        else if (deg)
            return FLOE_OK;
        else if (metres)
            snprintf(r->err, r->errlen, "field file %s: '%s' is in metres (units '%s'), but a projection maps the "
                     "scene onto longitude and latitude: drop the key projection for a grid in metres", r->file, name,
                     u);
        else
            snprintf(r->err, r->errlen, "field file %s: the units '%s' of '%s' are not degrees (a projection reads "
                     "longitude and latitude: degrees_east, degrees_north)", r->file, u, name);
        return FLOE_EINVAL;
    }
    if (word_in(lu, m)) return FLOE_OK;
    if (word_in(lu, km)) {
        *to_m = 1000;
        return FLOE_OK;
    }
    if (deg || !strncmp(lu, "degree", 6))
        snprintf(r->err, r->errlen, "field file %s: '%s' is in degrees (units '%s'): add the key projection "
                 "(equirectangular with lon0 and lat0, or polar_stereographic with lon0 and lat_ts) to map the "
                 "scene's metres onto longitude and latitude (x_var the longitude, y_var the latitude)", r->file,
                 name, u);
    else
        snprintf(r->err, r->errlen, "field file %s: the units '%s' of '%s' are not a length (m or km: projected "
                 "coordinates) nor degrees (with the key projection)", r->file, u, name);
    return FLOE_EINVAL;
}

/* the factor to seconds of a time's units "U since DATE" (CF 4.4) */
static int time_units(ncr *r, int var, const char *name, double *to_s) {
    char u[256], lu[256], w[32];
    if (!att_text(r, var, "units", u, sizeof u)) {
        snprintf(r->err, r->errlen, "field file %s: '%s' has no units (seconds, minutes, hours or days since a date)",
                 r->file, name);
        return FLOE_EINVAL;
    }
    lower(lu, u, sizeof lu);
    static const char *const sec[] = {"seconds", "second", "secs", "sec", "s", NULL};
    static const char *const min[] = {"minutes", "minute", "mins", "min", NULL};
    static const char *const hour[] = {"hours", "hour", "hrs", "hr", "h", NULL};
    static const char *const day[] = {"days", "day", "d", NULL};
    int used = 0;
    if (sscanf(lu, " %31[a-z] since %n", w, &used) == 1 && used > 0) {
        if (word_in(w, sec)) *to_s = 1;
        else if (word_in(w, min)) *to_s = 60;
        else if (word_in(w, hour)) *to_s = 3600;
        else if (word_in(w, day)) *to_s = 86400;
        else used = 0;
        if (used) return FLOE_OK;
    }
    snprintf(r->err, r->errlen, "field file %s: the time units '%s' of '%s' are not supported (seconds, minutes, "
             "hours or days since a date)", r->file, u, name);
    return FLOE_EINVAL;
}

/* the velocities' dimensions, for messages */
typedef struct vel_dims {
    const char *u;  /* the u variable's name */
    int ydim;       /* the dimension of y */
    char names[256], lens[256];
} vel_dims;

/* a one-dimensional coordinate variable `name` on dimension dim, the velocities' `which`
 * one: its values (in m or s from its units) */
static int read_axis(ncr *r, const vel_dims *vd, const char *name, const char *which, int dim, int is_time,
                     double **out, int *n) {
    int var, nd;
    FLOE_TRY(var_id(r, name, &var));
    r->f.inq_varndims(r->nc, var, &nd);
    int d[NC_MAX_VAR_DIMS];
    r->f.inq_vardimid(r->nc, var, d);
    if (nd != 1 || d[0] != dim) {
        char dn[NC_MAX_NAME + 1] = "?", cn[256], cl[256];
        r->f.inq_dimname(r->nc, dim, dn);
        dims_text(r, nd, d, cn, cl, sizeof cn);
        snprintf(r->err, r->errlen, "field file %s: wrong dimensions: '%s' is %s, expected (time, y, x) or (y, x): "
                 "the coordinate '%s' must be one-dimensional on its %s dimension '%s' (it is %s)", r->file, vd->u,
                 vd->names, name, which, dn, cn);
        return FLOE_EINVAL;
    }
    double f = 1;
    FLOE_TRY(is_time ? time_units(r, var, name, &f) : coordinate_units(r, var, name, dim == vd->ydim, &f));
    size_t len;
    r->f.inq_dimlen(r->nc, dim, &len);
    if (len > INT32_MAX) {
        snprintf(r->err, r->errlen, "field file %s: '%s' has too many values (%zu)", r->file, name, len);
        return FLOE_EINVAL;
    }
    FLOE_TRY(read_values(r, var, name, 1, &len, out));
    for (size_t k = 0; k < len; k++) (*out)[k] *= f;
    *n = (int)len;
    return FLOE_OK;
}

/* the velocity component `name`: its id, number of dimensions and their ids */
static int velocity_var(ncr *r, const char *name, int *var, int *nd, int dims[NC_MAX_VAR_DIMS]) {
    FLOE_TRY(var_id(r, name, var));
    r->f.inq_varndims(r->nc, *var, nd);
    r->f.inq_vardimid(r->nc, *var, dims);
    if (*nd != 2 && *nd != 3) {
        char dn[256], dl[256];
        dims_text(r, *nd, dims, dn, dl, sizeof dn);
        snprintf(r->err, r->errlen, "field file %s: wrong dimensions: '%s' has %d dimension%s %s; expected (time, y, x) "
                 "or (y, x)", r->file, name, *nd, *nd == 1 ? "" : "s", dn);
        return FLOE_EINVAL;
    }
    return FLOE_OK;
}

static floe_field_grid *read_grid(ncr *r, const floe_field_grid_def *d) {
    int uv, vv, nu, nv, du[NC_MAX_VAR_DIMS], dv[NC_MAX_VAR_DIMS];
    if (velocity_var(r, d->u_var, &uv, &nu, du) || velocity_var(r, d->v_var, &vv, &nv, dv)) return NULL;
    if (nu != nv || memcmp(du, dv, (size_t)nu * sizeof *du)) {
        char un[256], ul[256], vn[256], vl[256];
        dims_text(r, nu, du, un, ul, sizeof un);
        dims_text(r, nv, dv, vn, vl, sizeof vn);
        snprintf(r->err, r->errlen, "field file %s: mismatched shapes: '%s' is %s = %s but '%s' is %s = %s (the "
                 "components must share their grid)", r->file, d->u_var, un, ul, d->v_var, vn, vl);
        return NULL;
    }
    double *x = NULL, *y = NULL, *t = NULL, *u = NULL, *v = NULL;
    int nx = 0, ny = 0, nt = 1;
    vel_dims vd = {.u = d->u_var, .ydim = du[nu - 2]};
    dims_text(r, nu, du, vd.names, vd.lens, sizeof vd.names);
    int ok = !read_axis(r, &vd, d->x_var, "last", du[nu - 1], 0, &x, &nx) &&
             !read_axis(r, &vd, d->y_var, nu == 3 ? "second" : "first", du[nu - 2], 0, &y, &ny);
    if (ok && nu == 3) ok = !read_axis(r, &vd, d->time_var, "first", du[0], 1, &t, &nt);
    else if (ok) ok = (t = calloc(1, sizeof *t)) != NULL;
    size_t dl[3] = {(size_t)nt, (size_t)ny, (size_t)nx};
    const size_t *dls = nu == 3 ? dl : dl + 1;
    if (ok && !size_ok(nx, ny, nt)) {
        snprintf(r->err, r->errlen, "field file %s: the grid is too large (%d x %d x %d)", r->file, nt, ny, nx);
        ok = 0;
    }
    ok = ok && !read_values(r, uv, d->u_var, nu, dls, &u) && !read_values(r, vv, d->v_var, nv, dls, &v);
    if (!ok) {
        if (!r->err[0]) snprintf(r->err, r->errlen, "field file %s: out of memory", r->file);
        free(x), free(y), free(t), free(u), free(v);
        return NULL;
    }
    const size_t n = (size_t)nt * ny * nx;
    for (size_t k = 0; k < n; k++) {
        u[k] *= d->scale;
        v[k] *= d->scale;
    }
    const char *const names[3] = {d->x_var, d->y_var, d->time_var};
    return grid_build(nx, x, ny, y, nt, t, u, v, &d->projection, r->file, names, r->err, r->errlen);
}

floe_field_grid *floe_field_grid_load(const floe_field_grid_def *def, char *err, size_t errlen) {
    floe_field_grid_def d = floe_field_grid_default();
    if (def) {
        d.file = def->file;
        if (def->u_var && def->u_var[0]) d.u_var = def->u_var;
        if (def->v_var && def->v_var[0]) d.v_var = def->v_var;
        if (def->x_var && def->x_var[0]) d.x_var = def->x_var;
        if (def->y_var && def->y_var[0]) d.y_var = def->y_var;
        if (def->time_var && def->time_var[0]) d.time_var = def->time_var;
        d.scale = def->scale;
        d.projection = def->projection;
    }
    if (!d.file || !d.file[0]) {
        snprintf(err, errlen, "field netcdf: a file is required");
        return NULL;
    }
    if (!isfinite(d.scale)) {
        snprintf(err, errlen, "field file %s: scale must be finite", d.file);
        return NULL;
    }
    ncr r = {.nc = -1, .file = d.file, .err = err, .errlen = errlen,
             .projected = d.projection.kind != FLOE_PROJECTION_NONE};
    err[0] = 0;
    char why[256];
    if (r.projected && floe_projection_check(&d.projection, why, sizeof why)) {
        snprintf(err, errlen, "field file %s: %s", d.file, why);
        return NULL;
    }
    if (nc_api_load(&r.f, d.file, err, errlen)) return NULL;
    int st = r.f.open(d.file, NC_NOWRITE, &r.nc);
    if (st != NC_NOERR) {
        char cwd[512];
        if (d.file[0] != '/' && getcwd(cwd, sizeof cwd)) {
            char what[600];
            snprintf(what, sizeof what, "cannot open it (a relative path opens from the current directory, %s)", cwd);
            nc_fail(&r, st, what);
        } else nc_fail(&r, st, "cannot open it");
        return NULL;
    }
    floe_field_grid *g = read_grid(&r, &d);
    r.f.close(r.nc);
    return g;
}

#else /* without NetCDF */

int floe_field_grid_netcdf(void) { return 0; }

floe_field_grid *floe_field_grid_load(const floe_field_grid_def *def, char *err, size_t errlen) {
    snprintf(err, errlen, "field file %s: floe was built without NetCDF (configure with -DFLOE_WITH_NETCDF=ON; Debian "
             "package libnetcdf-dev)", def && def->file ? def->file : "?");
    return NULL;
}

#endif
