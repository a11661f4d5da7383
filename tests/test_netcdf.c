/* test_netcdf.c - gridded, time-varying velocity fields read from NetCDF files
 * (core/forcing/netcdf_field.c, docs/sea-ice.md "Velocity fields"); the files are written
 * here with the netCDF C API into a temporary directory:
 *  (1) a field linear in x, y and t (plus an x y t term, which trilinear interpolation also
 *      reproduces) on a non-uniform grid with times in hours: 1000 random points and times
 *      inside the grid equal the function to 1e-12 relative; times before the first record
 *      and after the last read the first and last record (clamped, 1e-12); the steady (y, x)
 *      form, the uniform part U added, the grid built from arrays equal to the file's;
 *  (2) a floe in free drift through scenes (ocean_drag and geostrophic coriolis, field:
 *      netcdf) under a uniform gridded current with three records matches the same scene with
 *      the analytic uniform field to 1e-12 after 60 steps; a relative path opens from the
 *      current directory;
 *  (3) CF packing: shorts with scale_factor and add_offset read as raw * scale_factor +
 *      add_offset (1e-12), times the `scale` key;
 *  (4) errors, each message checked for its key words: a missing variable (named, and the
 *      file's variables listed), a missing file, a fill value in the data (variable and
 *      index), x not increasing, unsupported time units, x in degrees, u and v of different
 *      shapes, a grid not covering a floe (refused at prepare, naming the particle), a floe
 *      drifting out of the grid during the run (refused, with the time), file:line of the
 *      scene on load errors, grid keys without field: netcdf;
 *  (5) grids in longitude and latitude: equirectangular (lon0 -30, lat0 75) on a non-uniform
 *      lon/lat grid, a field linear in lon, lat and t read back at 200 scene points to 1e-12
 *      (the expected lon, lat from x = R (lon - lon0) cos(lat0), y = R (lat - lat0) written
 *      out here), its largest gradient per scene metre, a grid written 0..360 read at
 *      lon0 - 30 = 330, coverage checked in lon/lat ranges (a floe past lon -20 refused by
 *      the C API and at a scene's prepare); refused: degrees without projection (the message
 *      names the key to add, also through a scene), metres with one, latitudes along x,
 *      lat0 90, lat0 with polar_stereographic, lon0 without netcdf. Polar stereographic:
 *      Snyder's (1987) worked example (International ellipsoid, 71 S, 100 W; 75 S, 150 E:
 *      x = -1,540,033.6 m, y = -560,526.4 m) to 0.05 m, the scale 1 along lat_ts = 70 N
 *      (WGS84, 1e-9), lon0 along -y, 1000 round trips (1e-11 degrees); a grid round the
 *      north pole with a field linear in lon, lat, turned from (east, north) into x, y, at 300
 *      scene points to 1e-12; coverage of the pole and of a sector; the opposite pole refused.
 * Built without FLOE_WITH_NETCDF it prints "skipped: built without FLOE_WITH_NETCDF". */
#include "check.h"
#include "floe.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef FLOE_HAVE_NETCDF

int main(void) {
    printf("skipped: built without FLOE_WITH_NETCDF\n");
    return 0;
}

#else

#include <netcdf.h>
#include <unistd.h>


/* uniform in [0, 1) (xorshift64*) */
static double urand(void) {
    static unsigned long long s = 0x6e657463646675ULL;
    s ^= s >> 12, s ^= s << 25, s ^= s >> 27;
    return (double)((s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

static char tmpdir[256];
static char written[48][320];
static int nwritten;

/* the path of file `name` in the temporary directory (remembered for the clean-up) */
static const char *tmp_path(const char *name) {
    static char p[320];
    snprintf(p, sizeof p, "%s/%s", tmpdir, name);
    if (nwritten < 48) snprintf(written[nwritten++], sizeof written[0], "%s", p);
    return p;
}

/* ---- a NetCDF file of velocities ---- */
typedef struct spec {
    int nx, ny, nt;            /* nt = 0: steady, u and v of dimensions (y, x) */
    const double *x, *y, *t;   /* t in the file's time units */
    const double *u, *v;       /* nt ny nx values (ny nx when steady) */
    const char *time_units;    /* NULL: "seconds since 2000-01-01 00:00:00" */
    const char *x_units;       /* NULL: "m" */
    const char *y_units;       /* NULL: "m" */
    const char *x_name, *y_name; /* the coordinates' names (NULL: "x", "y") */
    int packed;                /* u, v stored as shorts with scale_factor and add_offset */
    double sf, ao;
    int has_fill;              /* u has _FillValue `fill` */
    double fill;
    int v_steady;              /* v on (y, x) while u is on (time, y, x) */
    int transposed;            /* u and v on (time, x, y) */
} spec;

static int nc_ok(int st, const char *what) {
    CHECK(st == NC_NOERR, "netCDF %s: %s", what, nc_strerror(st));
    return st == NC_NOERR;
}

/* writes spec s to path (variables in the order x, y, time, u, v): 1 on success */
static int write_nc(const char *path, const spec *s) {
    int nc, dx, dy, dt = -1, vx, vy, vt = -1, vu, vv;
    if (!nc_ok(nc_create(path, NC_CLOBBER | NC_NETCDF4, &nc), "nc_create")) return 0;
    const char *xn = s->x_name ? s->x_name : "x", *yn = s->y_name ? s->y_name : "y";
    nc_def_dim(nc, xn, (size_t)s->nx, &dx);
    nc_def_dim(nc, yn, (size_t)s->ny, &dy);
    if (s->nt) nc_def_dim(nc, "time", NC_UNLIMITED, &dt);
    nc_def_var(nc, xn, NC_DOUBLE, 1, &dx, &vx);
    nc_def_var(nc, yn, NC_DOUBLE, 1, &dy, &vy);
    const char *xu = s->x_units ? s->x_units : "m", *yu = s->y_units ? s->y_units : "m";
    nc_put_att_text(nc, vx, "units", strlen(xu), xu);
    nc_put_att_text(nc, vy, "units", strlen(yu), yu);
    if (s->nt) {
        nc_def_var(nc, "time", NC_DOUBLE, 1, &dt, &vt);
        const char *tu = s->time_units ? s->time_units : "seconds since 2000-01-01 00:00:00";
        nc_put_att_text(nc, vt, "units", strlen(tu), tu);
    }
    int d3[3] = {dt, s->transposed ? dx : dy, s->transposed ? dy : dx}, *dims = s->nt ? d3 : d3 + 1, nd = s->nt ? 3 : 2;
    nc_type ty = s->packed ? NC_SHORT : NC_DOUBLE;
    nc_def_var(nc, "u", ty, nd, dims, &vu);
    nc_def_var(nc, "v", ty, s->v_steady ? 2 : nd, s->v_steady ? d3 + 1 : dims, &vv);
    const char *vel = "m s-1";
    nc_put_att_text(nc, vu, "units", strlen(vel), vel);
    nc_put_att_text(nc, vv, "units", strlen(vel), vel);
    if (s->packed) {
        nc_put_att_double(nc, vu, "scale_factor", NC_DOUBLE, 1, &s->sf);
        nc_put_att_double(nc, vu, "add_offset", NC_DOUBLE, 1, &s->ao);
        nc_put_att_double(nc, vv, "scale_factor", NC_DOUBLE, 1, &s->sf);
        nc_put_att_double(nc, vv, "add_offset", NC_DOUBLE, 1, &s->ao);
    }
    if (s->has_fill) nc_def_var_fill(nc, vu, 0, &s->fill);
    if (!nc_ok(nc_enddef(nc), "nc_enddef")) return 0;
    nc_put_var_double(nc, vx, s->x);
    nc_put_var_double(nc, vy, s->y);
    if (s->nt) {
        size_t start = 0, count = (size_t)s->nt;
        nc_put_vara_double(nc, vt, &start, &count, s->t);
        size_t st3[3] = {0, 0, 0}, ct3[3] = {(size_t)s->nt, (size_t)s->ny, (size_t)s->nx};
        nc_put_vara_double(nc, vu, st3, ct3, s->u);
        if (s->v_steady) nc_put_var_double(nc, vv, s->v);
        else nc_put_vara_double(nc, vv, st3, ct3, s->v);
    } else {
        nc_put_var_double(nc, vu, s->u);
        nc_put_var_double(nc, vv, s->v);
    }
    return nc_ok(nc_close(nc), "nc_close");
}

static floe_field_grid *load(const char *path, const char *u_var, double scale, char *err, size_t len) {
    floe_field_grid_def d = floe_field_grid_default();
    d.file = path;
    if (u_var) d.u_var = u_var;
    d.scale = scale;
    return floe_field_grid_load(&d, err, len);
}

/* ---- (1) a linear field on a non-uniform grid ---- */
enum { NX = 7, NY = 6, NT = 4 };
static double gx[NX], gy[NY], gt_h[NT], gt_s[NT];

static void lin(double x, double y, double t, double u[2]) {
    u[0] = 0.8 + 3e-5 * x - 2e-5 * y + 1.5e-5 * t + 1e-13 * x * y * t;
    u[1] = -0.6 - 1e-5 * x + 4e-5 * y - 2e-5 * t;
}

static void make_grid(void) {
    for (int i = 0; i < NX; i++) gx[i] = -6000 + 12000 * pow(i / (double)(NX - 1), 1.7); /* non-uniform */
    for (int j = 0; j < NY; j++) gy[j] = -3000 + 500 * j + 120 * j * j;
    const double th[NT] = {0, 1, 2.5, 4}; /* hours */
    for (int k = 0; k < NT; k++) gt_h[k] = th[k], gt_s[k] = 3600 * th[k];
}

static void fill_linear(double *u, double *v, int nt, const double *ts) {
    for (int k = 0; k < nt; k++)
        for (int j = 0; j < NY; j++)
            for (int i = 0; i < NX; i++) {
                double w[2];
                lin(gx[i], gy[j], ts[k], w);
                size_t o = ((size_t)k * NY + j) * NX + i;
                u[o] = w[0];
                v[o] = w[1];
            }
}

static void test_linear(void) {
    make_grid();
    double u[NT * NY * NX], v[NT * NY * NX];
    fill_linear(u, v, NT, gt_s);
    spec s = {.nx = NX, .ny = NY, .nt = NT, .x = gx, .y = gy, .t = gt_h, .u = u, .v = v,
              .time_units = "hours since 2001-03-01 00:00:00"};
    const char *path = tmp_path("linear.nc");
    if (!write_nc(path, &s)) return;
    char err[1024] = "";
    floe_field_grid *g = load(path, NULL, 1.0, err, sizeof err);
    CHECK(g != NULL, "linear field loads: %s", err);
    if (!g) return;
    double lo[2], hi[2], tr[2];
    floe_field_grid_extent(g, lo, hi, tr);
    CHECK(lo[0] == gx[0] && hi[0] == gx[NX - 1] && lo[1] == gy[0] && hi[1] == gy[NY - 1],
          "extent x [%g, %g], y [%g, %g]", lo[0], hi[0], lo[1], hi[1]);
    CHECK(tr[0] == 0 && tr[1] == 4 * 3600.0, "times in seconds (hours x 3600): [%g, %g]", tr[0], tr[1]);
    floe_field f;
    memset(&f, 0, sizeof f);
    f.kind = FLOE_FIELD_GRID;
    f.grid = g;
    double worst = 0;
    for (int n = 0; n < 1000; n++) {
        const double x[3] = {lo[0] + (hi[0] - lo[0]) * urand(), lo[1] + (hi[1] - lo[1]) * urand(), 0};
        const double t = tr[1] * urand();
        double ue[2], ug[3];
        lin(x[0], x[1], t, ue);
        floe_field_eval(&f, x, t, ug);
        for (int c = 0; c < 2; c++) worst = fmax(worst, fabs(ug[c] - ue[c]) / fabs(ue[c]));
        if (ug[2] != 0) worst = INFINITY;
    }
    printf("  1000 random points and times: worst relative error %.2e\n", worst);
    CHECK(worst <= 1e-12, "the linear field is interpolated exactly (worst %g > 1e-12)", worst);
    /* clamped in time: before the first record, after the last */
    double worst_c = 0;
    for (int n = 0; n < 100; n++) {
        const double x[3] = {lo[0] + (hi[0] - lo[0]) * urand(), lo[1] + (hi[1] - lo[1]) * urand(), 0};
        const int late = n & 1;
        const double t = late ? tr[1] * (1 + urand()) : -tr[1] * urand();
        double ue[2], ug[3];
        lin(x[0], x[1], late ? tr[1] : tr[0], ue);
        floe_field_grid_eval(g, x, t, ug);
        for (int c = 0; c < 2; c++) worst_c = fmax(worst_c, fabs(ug[c] - ue[c]) / fabs(ue[c]));
    }
    CHECK(worst_c <= 1e-12, "outside the time range: the first or last record (worst %g)", worst_c);
    /* the uniform part U adds */
    f.U[0] = 0.25;
    f.U[1] = -0.5;
    {
        const double x[3] = {100, 200, 0};
        double ue[2], ug[3];
        lin(x[0], x[1], 500, ue);
        floe_field_eval(&f, x, 500, ug);
        CHECK_NEAR(ug[0], ue[0] + 0.25, 1e-12, "U + grid: x");
        CHECK_NEAR(ug[1], ue[1] - 0.5, 1e-12, "U + grid: y");
    }
    CHECK(floe_field_check(&f, err, sizeof err) == FLOE_OK, "a grid field checks: %s", err);
    /* the same grid from arrays */
    floe_field_grid *ga = floe_field_grid_create(NX, gx, NY, gy, NT, gt_s, u, v, "arrays", err, sizeof err);
    CHECK(ga != NULL, "grid from arrays: %s", err);
    if (ga) {
        double d = 0;
        for (int n = 0; n < 100; n++) {
            const double x[3] = {lo[0] + (hi[0] - lo[0]) * urand(), lo[1] + (hi[1] - lo[1]) * urand(), 0};
            const double t = tr[1] * urand();
            double a[3], b[3];
            floe_field_grid_eval(g, x, t, a);
            floe_field_grid_eval(ga, x, t, b);
            d = fmax(d, fmax(fabs(a[0] - b[0]), fabs(a[1] - b[1])));
        }
        CHECK(d == 0, "arrays and file give the same grid (max difference %g)", d);
        floe_field_grid_release(ga);
    }
    floe_field_grid_release(g);
    /* steady: (y, x) */
    double us[NY * NX], vs[NY * NX];
    const double t0 = 0;
    fill_linear(us, vs, 1, &t0);
    spec s2 = {.nx = NX, .ny = NY, .nt = 0, .x = gx, .y = gy, .u = us, .v = vs};
    const char *p2 = tmp_path("steady.nc");
    if (!write_nc(p2, &s2)) return;
    g = load(p2, NULL, 1.0, err, sizeof err);
    CHECK(g != NULL, "steady field loads: %s", err);
    if (g) {
        double worst_s = 0;
        for (int n = 0; n < 200; n++) {
            const double x[3] = {lo[0] + (hi[0] - lo[0]) * urand(), lo[1] + (hi[1] - lo[1]) * urand(), 0};
            double ue[2], ug[3];
            lin(x[0], x[1], 0, ue);
            floe_field_grid_eval(g, x, 1e5 * urand(), ug);
            for (int c = 0; c < 2; c++) worst_s = fmax(worst_s, fabs(ug[c] - ue[c]) / fabs(ue[c]));
        }
        CHECK(worst_s <= 1e-12, "steady (y, x) field at any time: worst %g", worst_s);
        floe_field_grid_release(g);
    }
}

/* ---- (2) free drift through scenes ---- */
static const char *drift_scene =
    "dimension: 2\n"
    "mass_2d: area\n"
    "time: {duration: 600, dt: 10}\n"
    "gravity: [0, 0]\n"
    "materials: [{name: ice, density: 920, young: 6e6, poisson: 0.3}]\n"
    "laws: [{materials: [ice, ice], model: linear, kn: 1e3, ks: 0}]\n"
    "bodies:\n"
    "  - {material: ice, position: [%g, 0], thickness: 0.5, velocity: [%g, 0], shape: {polygon: {vertices: "
    "[[-500, -300], [500, -300], [400, 300], [-450, 250]]}}}\n"
    "forces:\n"
    "  - {type: ocean_drag, %s}\n"
    "  - {type: coriolis, tilt: geostrophic, %s}\n";

static floe_world *load_scene(const char *field, double x0, double v0, char *err, size_t len) {
    char text[4096];
    snprintf(text, sizeof text, drift_scene, x0, v0, field, field);
    floe_world *w = NULL;
    err[0] = 0;
    if (floe_scene_load_ex("t.yaml", text, NULL, 0, &w, NULL, err, len) != FLOE_OK) {
        floe_world_destroy(w);
        return NULL;
    }
    return w;
}

/* runs `steps` steps: FLOE_OK, or the failing step's code */
static int run_steps(floe_world *w, int steps) {
    int rc = floe_world_prepare(w);
    for (int k = 0; k < steps && rc == FLOE_OK; k++) rc = floe_world_step(w);
    return rc;
}

static void uniform_file(const char *name, double U0, double U1, double xlo, double xhi) {
    const double x[3] = {xlo, 0.5 * (xlo + xhi), xhi}, y[3] = {-5000, 100, 5000}, t[3] = {0, 200, 100000};
    double u[27], v[27];
    for (int k = 0; k < 27; k++) u[k] = U0, v[k] = U1;
    spec s = {.nx = 3, .ny = 3, .nt = 3, .x = x, .y = y, .t = t, .u = u, .v = v};
    write_nc(name, &s);
}

static void test_drift(void) {
    const double U[2] = {0.3, -0.12};
    const char *path = tmp_path("uniform.nc");
    uniform_file(path, U[0], U[1], -5000, 5000);
    char err[1024], field[512];
    snprintf(field, sizeof field, "velocity: [%.17g, %.17g]", U[0], U[1]);
    floe_world *wa = load_scene(field, 0, 0, err, sizeof err);
    CHECK(wa != NULL, "analytic scene: %s", err);
    snprintf(field, sizeof field, "field: netcdf, file: '%s'", path);
    floe_world *wg = load_scene(field, 0, 0, err, sizeof err);
    CHECK(wg != NULL, "netcdf scene: %s", err);
    /* the same, opened by a relative path from the current directory */
    char cwd[512];
    floe_world *wr = NULL;
    if (getcwd(cwd, sizeof cwd) && chdir(tmpdir) == 0) {
        wr = load_scene("field: netcdf, file: uniform.nc", 0, 0, err, sizeof err);
        CHECK(wr != NULL, "a relative path opens from the current directory: %s", err);
        CHECK(chdir(cwd) == 0, "back to %s", cwd);
    }
    /* a scene file elsewhere: its relative `file` is relative to the scene's folder */
    {
        char text[4096], spath[1024];
        snprintf(text, sizeof text, drift_scene, 0.0, 0.0, "field: netcdf, file: uniform.nc",
                 "field: netcdf, file: uniform.nc");
        snprintf(spath, sizeof spath, "%s/scene.yaml", tmpdir);
        floe_world *ws = NULL;
        err[0] = 0;
        int rc = floe_scene_load_ex(spath, text, NULL, 0, &ws, NULL, err, sizeof err);
        CHECK(rc == FLOE_OK, "a relative file opens from the scene file's folder: %s", err);
        floe_world_destroy(ws);
    }
    if (wa && wg && wr) {
        int ra = run_steps(wa, 60), rg = run_steps(wg, 60), rr = run_steps(wr, 60);
        CHECK(ra == FLOE_OK && rg == FLOE_OK && rr == FLOE_OK, "the drifts run: %s / %s / %s",
              floe_world_last_error(wa), floe_world_last_error(wg), floe_world_last_error(wr));
        floe_particle_state a, b, c;
        floe_world_get_particle(wa, 0, &a);
        floe_world_get_particle(wg, 0, &b);
        floe_world_get_particle(wr, 0, &c);
        double dv = hypot(b.v[0] - a.v[0], b.v[1] - a.v[1]) / hypot(a.v[0], a.v[1]);
        double dx = hypot(b.x[0] - a.x[0], b.x[1] - a.x[1]) / hypot(a.x[0], a.x[1]);
        double dw = fabs(b.w[2] - a.w[2]) / fmax(fabs(a.w[2]), 1e-300);
        printf("  free drift, 600 s: v = (%.9f, %.9f) analytic, (%.9f, %.9f) netcdf; x = (%.3f, %.3f)\n", a.v[0],
               a.v[1], b.v[0], b.v[1], a.x[0], a.x[1]);
        CHECK(hypot(a.v[0], a.v[1]) > 0.01, "the floe drifts (%g m/s)", hypot(a.v[0], a.v[1]));
        CHECK(dv <= 1e-12, "netcdf uniform current = analytic: velocity (rel %g)", dv);
        CHECK(dx <= 1e-12, "netcdf uniform current = analytic: position (rel %g)", dx);
        CHECK(dw <= 1e-12 || fabs(b.w[2] - a.w[2]) < 1e-18, "netcdf = analytic: spin (%g vs %g)", b.w[2], a.w[2]);
        CHECK(c.x[0] == b.x[0] && c.x[1] == b.x[1] && c.v[0] == b.v[0], "relative path: the same drift");
    }
    floe_world_destroy(wa);
    floe_world_destroy(wg);
    floe_world_destroy(wr);
}

/* ---- (3) CF packing ---- */
static void test_packed(void) {
    const double x[2] = {0, 1000}, y[2] = {0, 500}, t[2] = {0, 10};
    const double ru[8] = {100, 200, -300, 400, 5, 6, 7, 8}, rv[8] = {-1, -2, 30, 40, 500, 600, -700, 800};
    spec s = {.nx = 2, .ny = 2, .nt = 2, .x = x, .y = y, .t = t, .u = ru, .v = rv, .packed = 1, .sf = 0.01,
              .ao = -1.5};
    const char *path = tmp_path("packed.nc");
    if (!write_nc(path, &s)) return;
    char err[1024];
    for (int pass = 0; pass < 2; pass++) {
        const double scale = pass ? 2.0 : 1.0;
        floe_field_grid *g = load(path, NULL, scale, err, sizeof err);
        CHECK(g != NULL, "packed file loads: %s", err);
        if (!g) return;
        double worst = 0;
        for (int k = 0; k < 2; k++)
            for (int j = 0; j < 2; j++)
                for (int i = 0; i < 2; i++) {
                    const double p[3] = {x[i], y[j], 0};
                    double w[3];
                    floe_field_grid_eval(g, p, t[k], w);
                    const int o = (k * 2 + j) * 2 + i;
                    worst = fmax(worst, fabs(w[0] - scale * (ru[o] * 0.01 - 1.5)) / fabs(ru[o] * 0.01 - 1.5));
                    worst = fmax(worst, fabs(w[1] - scale * (rv[o] * 0.01 - 1.5)) / fabs(rv[o] * 0.01 - 1.5));
                }
        CHECK(worst <= 1e-12, "scale %g x (raw scale_factor + add_offset) at the nodes (worst %g)", scale, worst);
        floe_field_grid_release(g);
    }
}

/* ---- (4) errors ---- */
static int has(const char *s, const char *w) { return strstr(s, w) != NULL; }

/* loads path (u variable u_var) and expects a failure whose message holds every word */
static void expect_load_error(const char *path, const char *u_var, const char *const *words, const char *what) {
    char err[1024] = "";
    floe_field_grid *g = load(path, u_var, 1.0, err, sizeof err);
    int ok = !g;
    for (int k = 0; words[k]; k++) ok = ok && has(err, words[k]);
    CHECK(ok, "%s refused with its key words: '%s'", what, err);
    printf("  %s: %s\n", what, err);
    floe_field_grid_release(g);
}

/* a 2D world of ice without gravity, dt 10 s */
static floe_world *bare_world(void) {
    floe_world_def wd = floe_default_world_def();
    wd.dim = 2;
    wd.mass_2d_area = 1;
    wd.dt = 10;
    wd.allow_unstable_dt = 1;
    wd.gravity[2] = 0;
    floe_world *w = floe_world_create(&wd, NULL, 0);
    floe_material m = {"ice", 920, 6e6, 0.3};
    floe_world_add_material(w, &m);
    return w;
}

/* a 400 x 200 m floe, 1 m thick, at (x, y) */
static void add_floe(floe_world *w, double x, double y) {
    char err[256];
    const double xy[8] = {-200, -100, 200, -100, 200, 100, -200, 100};
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_polygon_create(xy, 4, err, sizeof err));
    p.thickness = 1;
    p.x[0] = x;
    p.x[1] = y;
    floe_world_add_particle(w, &p);
}

static void test_errors(void) {
    const double x[3] = {0, 1000, 2000}, y[2] = {0, 500}, t[2] = {0, 60};
    double u[12], v[12];
    for (int k = 0; k < 12; k++) u[k] = 0.1 * k, v[k] = -0.05 * k;
    spec s = {.nx = 3, .ny = 2, .nt = 2, .x = x, .y = y, .t = t, .u = u, .v = v};
    const char *good = tmp_path("good.nc");
    char goodp[320];
    snprintf(goodp, sizeof goodp, "%s", good);
    write_nc(goodp, &s);
    {
        const char *w[] = {"no variable 'uu'", "(it has: x, y, time, u, v)", "good.nc", NULL};
        expect_load_error(goodp, "uu", w, "missing variable");
    }
    {
        const char *w[] = {"nope.nc", "No such file", NULL};
        expect_load_error(tmp_path("nope.nc"), NULL, w, "missing file");
    }
    {
        spec f = s;
        double uf[12];
        memcpy(uf, u, sizeof uf);
        uf[(1 * 2 + 1) * 3 + 2] = -999; /* record 1, row 1, column 2 */
        f.u = uf;
        f.has_fill = 1;
        f.fill = -999;
        const char *p = tmp_path("fill.nc");
        write_nc(p, &f);
        const char *w[] = {"fill value", "'u'", "[1, 1, 2]", "(time, y, x)", "_FillValue", NULL};
        expect_load_error(p, NULL, w, "fill value in the data");
    }
    {
        spec f = s;
        const double xb[3] = {0, 1000, 1000};
        f.x = xb;
        const char *p = tmp_path("xbad.nc");
        write_nc(p, &f);
        const char *w[] = {"'x' is not strictly increasing", "'x'[2] = 1000", NULL};
        expect_load_error(p, NULL, w, "x not increasing");
    }
    {
        spec f = s;
        f.time_units = "months since 2000-01-01";
        const char *p = tmp_path("months.nc");
        write_nc(p, &f);
        const char *w[] = {"time units", "months since 2000-01-01", "not supported", NULL};
        expect_load_error(p, NULL, w, "unsupported time units");
    }
    {
        spec f = s;
        f.x_units = "degrees_east";
        const char *p = tmp_path("degrees.nc");
        write_nc(p, &f);
        const char *w[] = {"'x' is in degrees", "metres", NULL};
        expect_load_error(p, NULL, w, "longitudes");
    }
    {
        spec f = s;
        f.v_steady = 1;
        const char *p = tmp_path("shapes.nc");
        write_nc(p, &f);
        const char *w[] = {"mismatched shapes", "'u' is (time, y, x) = (2, 2, 3)", "'v' is (y, x) = (2, 3)", NULL};
        expect_load_error(p, NULL, w, "u and v of different shapes");
    }
    {
        spec f = s;
        f.transposed = 1;
        const char *p = tmp_path("transposed.nc");
        write_nc(p, &f);
        const char *w[] = {"wrong dimensions", "'u' is (time, x, y)", "expected (time, y, x) or (y, x)", NULL};
        expect_load_error(p, NULL, w, "u on (time, x, y)");
    }
    char err[1024], field[512];
    /* load errors through a scene: file:line of the entry */
    snprintf(field, sizeof field, "field: netcdf, file: '%s', u_var: uu", goodp);
    floe_world *w = load_scene(field, 0, 0, err, sizeof err);
    CHECK(!w && has(err, "t.yaml:10:") && has(err, "no variable 'uu'"), "scene: missing variable at its line: %s", err);
    printf("  through the scene: %s\n", err);
    floe_world_destroy(w);
    w = load_scene("velocity: [0.1, 0], file: x.nc", 0, 0, err, sizeof err);
    CHECK(!w && has(err, "file is only read with field: netcdf"), "file without netcdf: %s", err);
    floe_world_destroy(w);
    w = load_scene("field: netcdf", 0, 0, err, sizeof err);
    CHECK(!w && has(err, "needs file"), "netcdf without file: %s", err);
    floe_world_destroy(w);
    /* a grid that does not cover the floe: refused at prepare (the scene loader prepares the
     * world), naming it */
    const char *small = tmp_path("small.nc");
    uniform_file(small, 0.5, 0, -2000, 2000);
    snprintf(field, sizeof field, "field: netcdf, file: '%s'", small);
    w = load_scene(field, 1800, 0, err, sizeof err);
    int rc = w ? floe_world_prepare(w) : FLOE_EINVAL;
    const char *m = w ? floe_world_last_error(w) : err;
    CHECK(rc != FLOE_OK && has(m, "does not cover particle 0") && has(m, "the grid x in [-2000, 2000]") &&
              has(m, "field file") && has(m, "small.nc") && has(m, "at (1800, 0) (radius") && !has(m, "at t ="),
          "a floe outside the grid refused at prepare: %s", m);
    printf("  floe outside the grid: %s\n", m);
    floe_world_destroy(w);
    /* the same through the C API: floe_world_prepare refuses */
    {
        floe_field_grid *g = load(small, NULL, 1.0, err, sizeof err);
        floe_coriolis_def cd = floe_coriolis_default();
        cd.tilt = FLOE_TILT_GEOSTROPHIC;
        cd.field.kind = FLOE_FIELD_GRID;
        cd.field.grid = g;
        floe_provider *pv = floe_coriolis_create(&cd, err, sizeof err);
        floe_field_grid_release(g);
        floe_world *wc = bare_world();
        add_floe(wc, -1900, 0);
        CHECK(pv && floe_world_add_provider(wc, pv) == FLOE_OK, "coriolis with a grid added: %s", err);
        rc = floe_world_prepare(wc);
        m = floe_world_last_error(wc);
        CHECK(rc != FLOE_OK && has(m, "coriolis: field file") && has(m, "does not cover particle 0"),
              "C API: prepare refuses a floe outside the grid: %s", m);
        floe_world_destroy(wc);
    }
    /* drifting out during the run: 0.5 m/s towards the edge 1000 m away */
    w = load_scene(field, 800, 0.5, err, sizeof err);
    CHECK(w != NULL, "drifting scene loads: %s", err);
    if (w) {
        rc = run_steps(w, 200);
        m = floe_world_last_error(w);
        CHECK(rc != FLOE_OK && has(m, "does not cover particle 0") && has(m, "at t = "),
              "a floe leaving the grid is refused with the time: %s", m);
        printf("  floe leaving the grid: %s\n", m);
        floe_world_destroy(w);
    }
}

/* the C API: the provider holds its own reference to the grid */
static void test_ownership(void) {
    char err[1024];
    const char *path = tmp_path("own.nc");
    uniform_file(path, 0.2, 0.1, -5000, 5000);
    floe_field_grid *g = load(path, NULL, 1.0, err, sizeof err);
    CHECK(g != NULL, "own.nc loads: %s", err);
    if (!g) return;
    floe_drag_def d = floe_ocean_drag_default();
    d.field.kind = FLOE_FIELD_GRID;
    d.field.grid = g;
    floe_provider *pv = floe_drag_create("ocean_drag", &d, err, sizeof err);
    floe_field_grid_release(g); /* the caller's reference */
    CHECK(pv != NULL, "drag with a grid: %s", err);
    floe_world *w = bare_world();
    add_floe(w, 0, 0);
    CHECK(pv && floe_world_add_provider(w, pv) == FLOE_OK, "provider added: %s", floe_world_last_error(w));
    int rc = run_steps(w, 10);
    floe_particle_state st;
    floe_world_get_particle(w, 0, &st);
    CHECK(rc == FLOE_OK && st.v[0] > 0 && st.v[1] > 0, "the floe moves with the current (%g, %g): %s", st.v[0],
          st.v[1], floe_world_last_error(w));
    floe_world_destroy(w);
    d.field.grid = NULL;
    CHECK(!floe_drag_create("ocean_drag", &d, err, sizeof err) && has(err, "no grid"), "grid field without data: %s",
          err);
}

/* ---- (5) grids in longitude and latitude ---- */
#define R_EARTH 6371000.0
#define DEGR (M_PI / 180)

/* a field linear in lon, lat (degrees) and t (s) */
static void lin_ll(double lon, double lat, double t, double u[2]) {
    u[0] = 0.1 + 0.01 * lon - 0.02 * lat + 1e-6 * t;
    u[1] = -0.2 + 0.015 * lon + 0.005 * lat - 2e-6 * t;
}

/* writes a (time, lat, lon) file of lin_ll on the nodes lon[nx], lat[ny], times (hours) t[nt] */
static int write_ll(const char *path, int nx, const double *lon, int ny, const double *lat, int nt, const double *th) {
    double *u = malloc(sizeof(double) * nx * ny * nt), *v = malloc(sizeof(double) * nx * ny * nt);
    for (int k = 0; k < nt; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                double w[2];
                lin_ll(lon[i], lat[j], 3600 * th[k], w);
                u[((size_t)k * ny + j) * nx + i] = w[0];
                v[((size_t)k * ny + j) * nx + i] = w[1];
            }
    spec s = {.nx = nx, .ny = ny, .nt = nt, .x = lon, .y = lat, .t = th, .u = u, .v = v,
              .time_units = "hours since 2020-01-01", .x_units = "degrees_east", .y_units = "degrees_north",
              .x_name = "lon", .y_name = "lat"};
    int ok = write_nc(path, &s);
    free(u);
    free(v);
    return ok;
}

static floe_field_grid *load_ll(const char *path, floe_projection pj, char *err, size_t len) {
    floe_field_grid_def d = floe_field_grid_default();
    d.file = path;
    d.x_var = "lon";
    d.y_var = "lat";
    d.projection = pj;
    return floe_field_grid_load(&d, err, len);
}

static void test_equirectangular(void) {
    enum { NLON = 9, NLAT = 7 };
    double lon[NLON], lat[NLAT];
    const double th[2] = {0, 6};
    for (int i = 0; i < NLON; i++) lon[i] = -40 + 20 * pow(i / (NLON - 1.0), 1.3); /* non-uniform */
    for (int j = 0; j < NLAT; j++) lat[j] = 70 + 10 * j / (NLAT - 1.0);
    char path[320];
    snprintf(path, sizeof path, "%s", tmp_path("lonlat.nc"));
    if (!write_ll(path, NLON, lon, NLAT, lat, 2, th)) return;
    char err[1024];
    const floe_projection pj = {.kind = FLOE_PROJECTION_EQUIRECTANGULAR, .lon0 = -30, .lat0 = 75};
    floe_field_grid *g = load_ll(path, pj, err, sizeof err);
    CHECK(g != NULL, "a lon/lat grid loads with projection equirectangular: %s", err);
    if (!g) return;
    /* the scene's points: chosen ones, then random ones inside the grid (about +-250 km in x,
     * +-550 km in y: lon -40..-20, lat 70..80 at lon0 -30, lat0 75) */
    double pts[200][2] = {{0, 0}, {1e5, 0}, {0, -2e5}, {-2.5e5, 5e5}, {2.8e5, -5.5e5}};
    for (int n = 5; n < 200; n++) pts[n][0] = -2.8e5 + 5.6e5 * urand(), pts[n][1] = -5.5e5 + 1.1e6 * urand();
    double worst = 0;
    for (int n = 0; n < 200; n++) {
        /* x = R (lon - lon0) cos(lat0), y = R (lat - lat0), in radians */
        const double lo = -30 + pts[n][0] / (R_EARTH * cos(75 * DEGR)) / DEGR, la = 75 + pts[n][1] / R_EARTH / DEGR;
        const double t = 6 * 3600 * urand(), x[3] = {pts[n][0], pts[n][1], 0};
        double ue[2], ug[3];
        lin_ll(lo, la, t, ue);
        floe_field_grid_eval(g, x, t, ug);
        for (int c = 0; c < 2; c++) worst = fmax(worst, fabs(ug[c] - ue[c]) / fabs(ue[c]));
        if (n == 1) printf("  scene (100 km, 0) is (lon, lat) = (%.12g, %.12g): u = (%.15g, %.15g)\n", lo, la, ug[0], ug[1]);
    }
    printf("  equirectangular lon/lat grid, 200 scene points: worst relative error %.2e\n", worst);
    CHECK(worst <= 1e-12, "a field linear in lon, lat, t is read back exactly at the scene's points (worst %g)", worst);
    /* the largest gradient per metre of the scene: dv/dlon = 0.015 per degree over R cos(lat0) dlon */
    CHECK_NEAR(floe_field_grid_max_gradient(g), 0.015 / (R_EARTH * cos(75 * DEGR) * DEGR), 1e-9,
               "max gradient (1/s): dv/dx of the lon/lat field");
    floe_projection got = floe_field_grid_projection(g);
    CHECK(got.kind == FLOE_PROJECTION_EQUIRECTANGULAR && got.lon0 == -30 && got.lat0 == 75, "the grid's projection");
    /* coverage in the scene's metres: a 10 km floe at the centre, one beyond lon -20 */
    const double in[3] = {0, 0, 0}, out[3] = {3.0e5, 0, 0};
    CHECK(floe_field_grid_covers(g, in, 1e4, 0, err, sizeof err) == FLOE_OK, "covers the centre: %s", err);
    int rc = floe_field_grid_covers(g, out, 1e4, 3, err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "the grid lon in [-40, -20], lat in [70, 80] (degrees)") &&
              has(err, "does not cover particle 3") && has(err, "its box spans lon [-19."),
          "a floe beyond lon -20 is not covered: %s", err);
    printf("  not covered: %s\n", err);
    floe_field_grid_release(g);
    /* longitudes written 0..360: the scene's lon -30 is read at 330 */
    double lon360[NLON];
    for (int i = 0; i < NLON; i++) lon360[i] = lon[i] + 360;
    char p360[320];
    snprintf(p360, sizeof p360, "%s", tmp_path("lon360.nc"));
    if (!write_ll(p360, NLON, lon360, NLAT, lat, 2, th)) return;
    g = load_ll(p360, pj, err, sizeof err);
    CHECK(g != NULL, "a 0..360 grid loads: %s", err);
    if (g) {
        const double x[3] = {1e5, 2e5, 0};
        const double lo = 330 + 1e5 / (R_EARTH * cos(75 * DEGR)) / DEGR, la = 75 + 2e5 / R_EARTH / DEGR;
        double ue[2], ug[3];
        lin_ll(lo, la, 0, ue);
        floe_field_grid_eval(g, x, 0, ug);
        CHECK(fabs(ug[0] - ue[0]) <= 1e-12 * fabs(ue[0]) && fabs(ug[1] - ue[1]) <= 1e-12 * fabs(ue[1]),
              "lon0 -30 on a 310..340 grid: read at lon %g (%.17g, %.17g vs %.17g, %.17g)", lo, ug[0], ug[1], ue[0],
              ue[1]);
        CHECK(floe_field_grid_covers(g, x, 1e4, 0, err, sizeof err) == FLOE_OK, "and covered: %s", err);
        floe_field_grid_release(g);
    }
    /* refused: degrees without a projection (the message says which key to add), metres with
     * one, lon and lat swapped, a bad lat0 */
    {
        floe_projection none = {0};
        g = load_ll(path, none, err, sizeof err);
        CHECK(!g && has(err, "'lon' is in degrees") && has(err, "add the key projection") &&
                  has(err, "equirectangular with lon0 and lat0"),
              "degrees without a projection: %s", err);
        printf("  no projection: %s\n", err);
        floe_field_grid_release(g);
        g = load(tmp_path("good.nc"), NULL, 1.0, err, sizeof err); /* metres: fine without */
        floe_field_grid_release(g);
        floe_field_grid_def d = floe_field_grid_default();
        d.file = tmp_path("good.nc");
        d.projection = pj;
        g = floe_field_grid_load(&d, err, sizeof err);
        CHECK(!g && has(err, "'x' is in metres") && has(err, "drop the key projection"), "metres with a projection: %s",
              err);
        floe_field_grid_release(g);
        const double sx[2] = {70, 80}, sy[2] = {-40, -20}, su[4] = {1, 2, 3, 4};
        spec sw = {.nx = 2, .ny = 2, .x = sx, .y = sy, .u = su, .v = su, .x_units = "degrees_north",
                   .y_units = "degrees_east", .x_name = "lon", .y_name = "lat"};
        char pswap[320];
        snprintf(pswap, sizeof pswap, "%s", tmp_path("swapped.nc"));
        write_nc(pswap, &sw);
        g = load_ll(pswap, pj, err, sizeof err);
        CHECK(!g && has(err, "'lon' is a latitude (units 'degrees_north'): x_var must name the longitude"),
              "latitudes along x refused: %s", err);
        printf("  swapped: %s\n", err);
        floe_field_grid_release(g);
        floe_projection bad = pj;
        bad.lat0 = 90;
        g = load_ll(path, bad, err, sizeof err);
        CHECK(!g && has(err, "lat0 must be in (-90, 90)"), "lat0 90 refused: %s", err);
        floe_field_grid_release(g);
    }
    /* through a scene: the keys, the coverage at prepare, the keys' checks */
    char field[768];
    floe_world *w;
    snprintf(field, sizeof field, "field: netcdf, file: '%s', x_var: lon, y_var: lat, projection: equirectangular, "
             "lon0: -30, lat0: 75", path);
    w = load_scene(field, 0, 0, err, sizeof err);
    CHECK(w != NULL, "a scene with projection: equirectangular loads: %s", err);
    if (w) {
        rc = run_steps(w, 10);
        floe_particle_state st;
        floe_world_get_particle(w, 0, &st);
        double ue[2];
        lin_ll(-30, 75, 0, ue);
        CHECK(rc == FLOE_OK && st.v[0] * ue[0] > 0 && st.v[1] * ue[1] > 0,
              "the floe at (lon0, lat0) drifts with the current there (%g, %g): v (%g, %g): %s", ue[0], ue[1], st.v[0],
              st.v[1], floe_world_last_error(w));
        floe_world_destroy(w);
    }
    w = load_scene(field, 2.95e5, 0, err, sizeof err);
    rc = w ? floe_world_prepare(w) : FLOE_EINVAL;
    const char *m = w ? floe_world_last_error(w) : err;
    CHECK(rc != FLOE_OK && has(m, "does not cover particle 0") && has(m, "lon in [-40, -20]"),
          "a floe east of the lon/lat grid refused at prepare: %s", m);
    floe_world_destroy(w);
    snprintf(field, sizeof field, "field: netcdf, file: '%s', x_var: lon, y_var: lat", path);
    w = load_scene(field, 0, 0, err, sizeof err);
    CHECK(!w && has(err, "t.yaml:10:") && has(err, "is in degrees") && has(err, "add the key projection"),
          "scene: a file in degrees without projection: %s", err);
    printf("  through the scene: %s\n", err);
    floe_world_destroy(w);
    snprintf(field, sizeof field, "field: netcdf, file: '%s', x_var: lon, y_var: lat, projection: polar_stereographic, "
             "lat0: 75", path);
    w = load_scene(field, 0, 0, err, sizeof err);
    CHECK(!w && has(err, "lat0 is only read with projection: equirectangular (not polar_stereographic)"),
          "lat0 with polar: %s", err);
    floe_world_destroy(w);
    snprintf(field, sizeof field, "field: netcdf, file: '%s', lon0: 10", path);
    w = load_scene(field, 0, 0, err, sizeof err);
    CHECK(!w && has(err, "lon0 is only read with a projection"), "lon0 without projection: %s", err);
    floe_world_destroy(w);
    w = load_scene("velocity: [0.1, 0], lon0: 3", 0, 0, err, sizeof err);
    CHECK(!w && has(err, "lon0 is only read with field: netcdf"), "lon0 without netcdf: %s", err);
    floe_world_destroy(w);
}

static void test_polar_stereographic(void) {
    char err[1024];
    /* Snyder (1987), the numerical example of the polar stereographic ellipsoid: International
     * ellipsoid (a = 6,378,388 m, e^2 = 0.00672267: rf = 297), south pole, standard parallel
     * 71 S, central meridian 100 W; the point 75 S, 150 E: x = -1,540,033.6 m, y = -560,526.4 m */
    const floe_projection sn = {.kind = FLOE_PROJECTION_POLAR_STEREOGRAPHIC, .lon0 = -100, .lat_ts = -71,
                                .a = 6378388, .rf = 297};
    CHECK(floe_projection_check(&sn, err, sizeof err) == FLOE_OK, "Snyder's projection checks: %s", err);
    const double ll[2] = {150, -75};
    double xy[2], back[2];
    floe_projection_forward(&sn, ll, xy);
    printf("  Snyder's example: x = %.2f m, y = %.2f m (book: -1540033.6, -560526.4)\n", xy[0], xy[1]);
    CHECK(fabs(xy[0] + 1540033.6) <= 0.05 && fabs(xy[1] + 560526.4) <= 0.05,
          "Snyder's polar stereographic example to his 0.1 m (%.3f, %.3f)", xy[0], xy[1]);
    floe_projection_inverse(&sn, xy, back);
    CHECK(fabs(remainder(back[0] - 150, 360)) <= 1e-10 && fabs(back[1] + 75) <= 1e-10,
          "and back: (%.15g, %.15g)", back[0], back[1]);
    /* WGS84, north (EPSG:3413: lon0 -45, lat_ts 70): true scale along 70 N, round trips */
    const floe_projection ns = {.kind = FLOE_PROJECTION_POLAR_STEREOGRAPHIC, .lon0 = -45, .lat_ts = 70};
    {
        const double a = 6378137, f = 1 / 298.257223563, e2 = f * (2 - f), p = 70 * DEGR;
        const double par = a * cos(p) / sqrt(1 - e2 * sin(p) * sin(p)); /* the parallel's radius */
        const double l1[2] = {10, 70}, l2[2] = {10 + 1e-4, 70};
        double p1[2], p2[2];
        floe_projection_forward(&ns, l1, p1);
        floe_projection_forward(&ns, l2, p2);
        const double k = hypot(p2[0] - p1[0], p2[1] - p1[1]) / (par * 1e-4 * DEGR);
        printf("  scale factor along 70 N: %.12f\n", k);
        CHECK(fabs(k - 1) <= 1e-9, "true scale along lat_ts (k = %.12f)", k);
        const double pole[2] = {123, 90};
        floe_projection_forward(&ns, pole, p1);
        CHECK(hypot(p1[0], p1[1]) <= 1e-6, "the pole at the origin (%g, %g)", p1[0], p1[1]);
        const double m45[2] = {-45, 80}, m45e[2] = {45, 80};
        floe_projection_forward(&ns, m45, p1);
        floe_projection_forward(&ns, m45e, p2);
        CHECK(fabs(p1[0]) <= 1e-9 && p1[1] < 0 && fabs(p2[1]) <= 1e-9 && p2[0] > 0,
              "lon0 runs down -y, 90 degrees east of it along +x: (%g, %g), (%g, %g)", p1[0], p1[1], p2[0], p2[1]);
        double worst = 0;
        for (int n = 0; n < 1000; n++) {
            const double q[2] = {-180 + 360 * urand(), 30 + 60 * urand()};
            double z[2], r[2];
            floe_projection_forward(&ns, q, z);
            floe_projection_inverse(&ns, z, r);
            worst = fmax(worst, fmax(fabs(remainder(r[0] - q[0], 360)) * cos(q[1] * DEGR), fabs(r[1] - q[1])));
        }
        printf("  1000 round trips lon/lat -> x, y -> lon/lat: worst %.2e degrees\n", worst);
        CHECK(worst <= 1e-11, "round trips (worst %g degrees)", worst);
    }
    /* a grid all round the pole, lon -180..180 every 15, lat 60..90: the field turned into x, y */
    enum { NLON = 25, NLAT = 7 };
    double lon[NLON], lat[NLAT];
    const double th[1] = {0};
    for (int i = 0; i < NLON; i++) lon[i] = -180 + 15 * i;
    for (int j = 0; j < NLAT; j++) lat[j] = 60 + 5 * j;
    char path[320];
    snprintf(path, sizeof path, "%s", tmp_path("polar.nc"));
    if (!write_ll(path, NLON, lon, NLAT, lat, 1, th)) return;
    floe_field_grid *g = load_ll(path, ns, err, sizeof err);
    CHECK(g != NULL, "a lon/lat grid loads with projection polar_stereographic: %s", err);
    if (!g) return;
    double worst = 0;
    for (int n = 0; n < 300; n++) {
        /* within 2,500 km of the pole (latitude above about 67 N) */
        const double r = 2.5e6 * sqrt(urand()), th2 = 2 * M_PI * urand(), x[3] = {r * cos(th2), r * sin(th2), 0};
        double q[2], ue[2], ug[3];
        floe_projection_inverse(&ns, x, q);
        const double lo = q[0] - 360 * floor((q[0] + 180) / 360); /* into the grid's [-180, 180) */
        lin_ll(lo, q[1], 0, ue);
        /* east at x: along the parallel, counter-clockwise about the north pole */
        const double a = atan2(x[0], -x[1]), e[2] = {cos(a), sin(a)}, nn[2] = {-sin(a), cos(a)};
        const double want[2] = {ue[0] * e[0] + ue[1] * nn[0], ue[0] * e[1] + ue[1] * nn[1]};
        floe_field_grid_eval(g, x, 0, ug);
        const double sc = hypot(want[0], want[1]);
        worst = fmax(worst, hypot(ug[0] - want[0], ug[1] - want[1]) / sc);
    }
    printf("  polar stereographic lon/lat grid, 300 scene points: worst relative error %.2e\n", worst);
    CHECK(worst <= 1e-12, "the field linear in lon, lat, turned from (east, north) into (x, y) (worst %g)", worst);
    /* a floe over the pole: covered by a grid all round it up to 90 N */
    const double pole[3] = {1e3, -2e3, 0};
    CHECK(floe_field_grid_covers(g, pole, 5e4, 0, err, sizeof err) == FLOE_OK, "the pole is covered: %s", err);
    floe_field_grid_release(g);
    /* a sector lon -90..0, lat 60..85: a floe at lon -45, lat 75 is covered, one at lon +10 and one over the pole not */
    double sec[7];
    for (int i = 0; i < 7; i++) sec[i] = -90 + 15 * i;
    const double slat[6] = {60, 65, 70, 75, 80, 85};
    char ps[320];
    snprintf(ps, sizeof ps, "%s", tmp_path("sector.nc"));
    if (!write_ll(ps, 7, sec, 6, slat, 1, th)) return;
    g = load_ll(ps, ns, err, sizeof err);
    CHECK(g != NULL, "a sector loads: %s", err);
    if (!g) return;
    double x1[3] = {0, 0, 0}, x2[3] = {0, 0, 0};
    const double l1[2] = {-45, 75}, l2[2] = {10, 75};
    floe_projection_forward(&ns, l1, x1);
    floe_projection_forward(&ns, l2, x2);
    CHECK(floe_field_grid_covers(g, x1, 2e4, 0, err, sizeof err) == FLOE_OK, "lon -45, lat 75 covered: %s", err);
    int rc = floe_field_grid_covers(g, x2, 2e4, 1, err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "does not cover particle 1") && has(err, "lon in [-90, 0]"), "lon 10 not covered: %s",
          err);
    printf("  not covered: %s\n", err);
    rc = floe_field_grid_covers(g, pole, 5e4, 2, err, sizeof err);
    CHECK(rc != FLOE_OK && has(err, "every longitude"), "the pole not covered by a sector: %s", err);
    floe_field_grid_release(g);
    /* a grid reaching the south pole with the north pole's projection */
    const double slat2[3] = {-90, 0, 80};
    char pfar[320];
    snprintf(pfar, sizeof pfar, "%s", tmp_path("far.nc"));
    if (!write_ll(pfar, 7, sec, 3, slat2, 1, th)) return;
    g = load_ll(pfar, ns, err, sizeof err);
    CHECK(!g && has(err, "without the pole opposite"), "the opposite pole refused: %s", err);
    floe_field_grid_release(g);
}

int main(void) {
    snprintf(tmpdir, sizeof tmpdir, "/tmp/floe_netcdf_XXXXXX");
    if (!mkdtemp(tmpdir)) {
        perror("mkdtemp");
        return 1;
    }
    CHECK(floe_field_grid_netcdf() == 1, "built with NetCDF");
    test_linear();
    test_drift();
    test_packed();
    test_errors();
    test_ownership();
    test_equirectangular();
    test_polar_stereographic();
    for (int k = 0; k < nwritten; k++) remove(written[k]);
    rmdir(tmpdir);
    return check_summary("test_netcdf");
}

#endif
