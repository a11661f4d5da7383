/* floe_forcing.h - environmental forcing of 2D floes (sea ice, docs/sea-ice.md): velocity
 * fields of the ocean and the atmosphere, quadratic drag with a turning angle integrated
 * over each floe's area, Coriolis and the sea-surface tilt. Each is a force provider
 * (floe_provider.h), registered under the kind "provider" so that a scene names it in
 * `forces:`; C code creates them with the functions below and adds them with
 * floe_world_add_provider.
 *
 * Conventions (as SubZero, Montemuro et al. 2023, and Hibler 1979): x east, y north, f > 0
 * in the northern hemisphere, k the unit vector up (+z); a turning angle theta > 0 rotates
 * the stress counter-clockwise. Forces are in N when the floes have a thickness (masses in
 * kg), per metre of thickness otherwise. */
#ifndef FLOE_FORCING_H
#define FLOE_FORCING_H

#include "floe_provider.h"

/* ---- velocity fields (2D, in the plane z = 0) ---- */
typedef enum floe_field_kind {
    FLOE_FIELD_UNIFORM = 0, /* u = U */
    FLOE_FIELD_SHEAR = 1,   /* u = U + (rate (y - c_y), 0): simple shear about the line y = c_y */
    FLOE_FIELD_GYRE = 2,    /* u = U + curl of psi = S L/pi sin(pi (x - c_x)/L) sin(pi (y - c_y)/L)
                               (one closed gyre filling the square [c, c + L]^2, counter-clockwise
                               for S > 0, peak speed S at the middle of its sides) */
    FLOE_FIELD_VORTEX = 3,  /* u = U + a Rankine vortex about c: azimuthal speed S r/R inside the
                               core radius R, S R/r outside (counter-clockwise for S > 0) */
    FLOE_FIELD_GRID = 4     /* u = U + gridded data (floe_field_grid, read from a NetCDF file):
                               bilinear in x, y and linear in t between the records */
} floe_field_kind;

/* Gridded, time-varying velocity data (core/forcing/netcdf_field.c): opaque, immutable once
 * built, reference-counted (floe_field_grid_retain/release; the count is atomic). */
typedef struct floe_field_grid floe_field_grid;

typedef struct floe_field {
    floe_field_kind kind;
    double U[3];        /* uniform part, m/s (z ignored) */
    double rate;        /* shear: du_x/dy, 1/s */
    double speed;       /* gyre, vortex: S, m/s */
    double length;      /* gyre: L (m); vortex: R (m) */
    double center[3];   /* shear: c_y; gyre: the corner c; vortex: the centre c (m) */
    floe_field_grid *grid; /* grid: the data, borrowed: a provider created with this field takes
                              its own reference, the caller keeps (and releases) its own */
} floe_field;

/* The field's velocity u at position x (m) and time t (s): u[2] = 0. A grid is evaluated at
 * the point clamped into its extent (the providers refuse particles outside it first:
 * floe_field_covers) and at t clamped into its records' time range. */
void floe_field_eval(const floe_field *f, const double x[3], double t, double u[3]);
/* An upper bound of |u| over the plane (the gyre and vortex peaks plus |U|; INFINITY for a
 * shear, whose speed grows without bound; a grid: |U| plus its largest |u| over the data) */
double floe_field_max_speed(const floe_field *f);
/* "uniform", "shear", "gyre", "vortex", "netcdf" (NULL out of range) */
const char *floe_field_kind_name(int kind);
/* FLOE_OK, or FLOE_EINVAL with what is wrong in err (a non-finite value, a gyre or vortex
 * without a positive length, a grid field without its data) */
int floe_field_check(const floe_field *f, char *err, size_t errlen);
/* FLOE_OK when the field is defined over the bounding box [x - r, x + r] of particle i (every
 * analytic field is); a grid: floe_field_grid_covers. */
int floe_field_covers(const floe_field *f, const double x[3], double r, int i, char *err, size_t errlen);

/* ---- map projections: the scene's plane (x east, y north, metres) as a map of the Earth,
 * for grids in longitude and latitude (docs/sea-ice.md, "Longitude/latitude grids") ---- */
typedef enum floe_projection_kind {
    FLOE_PROJECTION_NONE = 0,            /* the grid is in the scene's metres */
    FLOE_PROJECTION_EQUIRECTANGULAR = 1, /* a sphere of radius FLOE_EARTH_RADIUS (Snyder 1987,
                                            eqs. 12-1, 12-2): x = R (lon - lon0) cos(lat0),
                                            y = R (lat - lat0), angles in radians */
    FLOE_PROJECTION_POLAR_STEREOGRAPHIC = 2 /* an ellipsoid, polar aspect, true scale along
                                            lat_ts (Snyder 1987, eqs. 21-30 to 21-34, 15-9,
                                            14-15; inverse 20-16, 20-18, 21-39, 21-40, 7-9) */
} floe_projection_kind;
#define FLOE_EARTH_RADIUS 6371000.0      /* m, the Earth's mean radius (IUGG) */
#define FLOE_WGS84_A 6378137.0           /* m, WGS84 semi-major axis (EPSG:7030) */
#define FLOE_WGS84_RF 298.257223563      /* WGS84 inverse flattening */
typedef struct floe_projection {
    floe_projection_kind kind;
    double lon0;   /* degrees: equirectangular: the longitude of x = 0; polar stereographic: the
                      central meridian, straight down (-y) from the north pole, up (+y) from
                      the south pole (EPSG:3413: -45) */
    double lat0;   /* degrees, equirectangular: the latitude of y = 0, |lat0| < 90 (the scale
                      is true along it) */
    double lat_ts; /* degrees, polar stereographic: the latitude of true scale, > 0 for the
                      north pole, < 0 for the south (EPSG:3413: 70; EPSG:3031: -71) */
    double a, rf;  /* polar stereographic: the ellipsoid's semi-major axis (m) and inverse
                      flattening; 0: WGS84's (rf = INFINITY: a sphere of radius a) */
} floe_projection;
/* FLOE_OK, or FLOE_EINVAL with what is wrong (an unknown kind, a value not finite, |lat0| >=
 * 90, lat_ts 0 or beyond 90, a <= 0, rf <= 1) */
int floe_projection_check(const floe_projection *p, char *err, size_t errlen);
/* (lon, lat) in degrees to the scene's (x, y) in metres, and back (lon in (lon0 - 180,
 * lon0 + 180] for the polar stereographic; the inverse's latitude to round-off). NONE: the
 * identity. */
void floe_projection_forward(const floe_projection *p, const double lonlat[2], double xy[2]);
void floe_projection_inverse(const floe_projection *p, const double xy[2], double lonlat[2]);
/* The angle (radians, counter-clockwise) from the scene's +x to east at (x, y): a velocity
 * (east, north) is (x, y) turned by it. 0 for NONE and equirectangular; lon - lon0 at the
 * north pole's polar stereographic, lon0 - lon at the south's. */
double floe_projection_east_angle(const floe_projection *p, const double xy[2]);

/* ---- gridded fields ----
 * Velocities u[k][j][i] at the nodes (x_i, y_j) of a rectilinear grid (coordinates strictly
 * increasing, uniformly spaced or not; at least 2 nodes per axis) and the times t_k (s,
 * strictly increasing; one record: a steady field). */
typedef struct floe_field_grid_def {
    const char *file;       /* NetCDF file (CF conventions); a relative path is opened from the
                               current directory (a scene's `file` is first made relative to
                               the scene file's folder, core/scene/scene_forces.c) */
    const char *u_var, *v_var; /* the velocity components' variables ("u", "v") */
    const char *x_var, *y_var; /* the coordinates ("x", "y"): metres, or longitude and latitude
                               in degrees with a projection */
    const char *time_var;   /* the time coordinate ("time"), read when u and v are (time, y, x) */
    double scale;           /* multiplier of the velocities read (1) */
    floe_projection projection; /* NONE: x, y in metres (m or km); otherwise x_var is the
                               longitude and y_var the latitude (units degrees_east and
                               degrees_north, or none), the scene's points are mapped onto
                               them and the velocities (east, north) turned into the scene's
                               x and y (floe_projection_east_angle) */
} floe_field_grid_def;
floe_field_grid_def floe_field_grid_default(void);
/* Reads a grid from a NetCDF file: u and v as double, of dimensions (time, y, x) or (y, x)
 * (steady), the same for both; x, y and time one-dimensional on those dimensions, strictly
 * increasing; CF scale_factor and add_offset applied; a value equal to _FillValue,
 * missing_value (or the type's default fill when no _FillValue is set) or not finite is
 * refused, as are x or y in degrees without a projection (the message says which key to
 * add) and metres with one; the time's units "seconds|minutes|hours|days since
 * DATE", converted to seconds (the simulation time t is the file's time in seconds since its
 * DATE). Returns the grid with one reference (the caller's: floe_field_grid_release), or NULL
 * with the message in err: "field file F: ...". Without FLOE_WITH_NETCDF: NULL, err says so. */
floe_field_grid *floe_field_grid_load(const floe_field_grid_def *d, char *err, size_t errlen);
/* A grid from arrays (copied): x[nx], y[ny], t[nt] (s) and u, v of nt*ny*nx values, node
 * (i, j) of record k at index (k ny + j) nx + i; `label` names it in messages (the file).
 * One reference, or NULL with the message in err. */
floe_field_grid *floe_field_grid_create(int nx, const double *x, int ny, const double *y, int nt, const double *t,
                                        const double *u, const double *v, const char *label, char *err,
                                        size_t errlen);
/* Adds a reference and returns g (NULL: NULL). */
floe_field_grid *floe_field_grid_retain(floe_field_grid *g);
/* Drops a reference; the last one frees the grid (NULL: nothing). */
void floe_field_grid_release(floe_field_grid *g);
/* The grid's velocity (m/s) at the scene's point (x[0], x[1]) (m) and time t, both clamped
 * into its extent: bilinear in space, linear in time (exact for fields linear in x, y and
 * t); a projected grid is interpolated at the point's (lon, lat), linear in lon and lat, the
 * longitude taken modulo 360 into the grid's range, and its (east, north) turned into x, y;
 * u[2] = 0 */
void floe_field_grid_eval(const floe_field_grid *g, const double x[3], double t, double u[3]);
/* Its extent in its own coordinates: x in [lo[0], hi[0]], y in [lo[1], hi[1]] (m, or
 * longitude and latitude in degrees when projected), times in [t[0], t[1]] (s) */
void floe_field_grid_extent(const floe_field_grid *g, double lo[2], double hi[2], double t[2]);
/* Its projection (kind NONE: metres) */
floe_projection floe_field_grid_projection(const floe_field_grid *g);
/* FLOE_OK when the grid covers the scene's box [x - r, x + r] of particle i, mapped into the
 * grid's coordinates when projected (the box's longitude and latitude ranges); otherwise
 * FLOE_EINVAL with "field file F: the grid x in [a, b], y in [c, d] does not cover particle i
 * at (x, y) (radius r)" in err ("the grid lon in [a, b], lat in [c, d] (degrees) ..." with the
 * box's ranges when projected). */
int floe_field_grid_covers(const floe_field_grid *g, const double x[3], double r, int i, char *err, size_t errlen);
/* Its label (the file), the largest |u| over its data (m/s), and the largest velocity
 * gradient component over its cells (1/s) */
const char *floe_field_grid_label(const floe_field_grid *g);
double floe_field_grid_max_speed(const floe_field_grid *g);
double floe_field_grid_max_gradient(const floe_field_grid *g);
/* 1 when floe was built with NetCDF (FLOE_WITH_NETCDF), 0 otherwise */
int floe_field_grid_netcdf(void);

/* ---- quadratic drag: tau = rho C_d |du| R(theta) du over the floe's area ---- */
typedef struct floe_drag_def {
    double rho;             /* fluid density, kg/m^3 */
    double cd;              /* drag coefficient (ice-water or ice-air) */
    double turning_angle;   /* theta, radians (> 0: counter-clockwise, northern hemisphere) */
    floe_field field;       /* the fluid's velocity */
    int quadrature;         /* subdivision level n of the area quadrature (>= 1; 0: 1):
                               polygons: n^2 triangles per fan triangle, 3 points each;
                               discs: n + 1 Gauss-Legendre rings x 8n angles; other shapes:
                               a grid of (8n)^2 */
    int every;              /* evaluate every k-th step (>= 1; 0: 1), holding the force and
                               torque in between (SubZero couples every 10 steps): k times
                               cheaper, the drag lagging by up to k steps */
} floe_drag_def;
/* SubZero's ocean (rho 1027, C_d 3e-3, theta 15 deg) and atmosphere (rho 1.2, C_d 1e-3,
 * theta 0): Subzero.jl src/simulation_components/simulation.jl `Constants` */
floe_drag_def floe_ocean_drag_default(void);
floe_drag_def floe_wind_drag_default(void);
/* A drag provider named `name` ("ocean_drag", "wind_drag", ...; copied), NULL with the
 * message in err for invalid parameters. 2D worlds only (refused at the first evaluation
 * of a 3D world). */
floe_provider *floe_drag_create(const char *name, const floe_drag_def *d, char *err, size_t errlen);

/* ---- Coriolis, F = -m f k x (v - U_g), with the sea-surface tilt ----
 * On every free particle's centre of mass (no torque), with the tilt of the sea surface:
 *   none:        U_g = 0 (Coriolis alone);
 *   geostrophic: the surface slopes so that the current `field` is in geostrophic balance
 *                (g grad(eta) = -f k x U_o, SubZero's "tilt"): U_g = U_o(x_c), Coriolis acts
 *                on the velocity relative to the current;
 *   slope:       a given slope: F adds -m g grad(eta) (U_g = 0).
 * Under velocity Verlet the rotation by f over a step is applied as the implicit-midpoint
 * (Cayley) rotation of v - U_g: a free inertial oscillation keeps its amplitude to round-off
 * and its period 2 pi / f to (f dt)^2 / 12 (an explicit force would grow the amplitude by
 * exp(pi f dt) per period); other integrators take -m f k x (v - U_g) as it is. */
#define FLOE_EARTH_OMEGA 7.2921e-5 /* rad/s, sidereal rotation rate of the Earth */
/* f = 2 Omega sin(latitude), latitude in degrees (negative south) */
double floe_coriolis_parameter(double latitude_deg);
typedef enum floe_tilt_kind { FLOE_TILT_NONE = 0, FLOE_TILT_GEOSTROPHIC = 1, FLOE_TILT_SLOPE = 2 } floe_tilt_kind;
typedef struct floe_coriolis_def {
    double f;               /* Coriolis parameter, 1/s (1.4e-4, SubZero's; > 0 north) */
    floe_tilt_kind tilt;
    floe_field field;       /* geostrophic: the current */
    double slope[3];        /* slope: grad(eta) (dimensionless; z ignored) */
    double g;               /* slope: gravity, m/s^2 (9.81) */
} floe_coriolis_def;
floe_coriolis_def floe_coriolis_default(void);
floe_provider *floe_coriolis_create(const floe_coriolis_def *d, char *err, size_t errlen);

/* ---- area quadrature of a 2D shape (body frame): points (3 doubles each, z = 0) and
 * weights (m^2, summing to the shape's area) ---- */
typedef struct floe_area_quadrature {
    int n;
    double *x;   /* 3n */
    double *w;   /* n */
    double area; /* the shape's area (sum of w) */
} floe_area_quadrature;
/* Builds the quadrature of g at level `level` (>= 1): polygons and compound bodies of
 * polygons (fan triangles from the centroid, each cut into level^2 similar triangles, each
 * by a 3-point rule exact for quadratics), discs (level + 1 Gauss-Legendre rings x 8 level
 * angles: exact for polynomials in r up to degree 2 level + 1 times trigonometric ones of
 * order < 8 level),
 * any other bounded 2D shape by a (8 level)^2 grid of its bounding square (cells whose
 * centre has sdf < 0; weights rescaled to its area from mass properties). FLOE_OK, or an
 * error with the message in err. */
int floe_area_quadrature_build(const floe_geometry *g, int level, floe_area_quadrature *q, char *err, size_t errlen);
void floe_area_quadrature_free(floe_area_quadrature *q);

/* Registers ocean_drag, wind_drag and coriolis (kind "provider");
 * floe_register_builtins calls it. */
int floe_register_builtin_forcing(char *err, size_t errlen);

#endif
