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
 *      scene on load errors, grid keys without field: netcdf.
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
static char written[32][320];
static int nwritten;

/* the path of file `name` in the temporary directory (remembered for the clean-up) */
static const char *tmp_path(const char *name) {
    static char p[320];
    snprintf(p, sizeof p, "%s/%s", tmpdir, name);
    if (nwritten < 32) snprintf(written[nwritten++], sizeof written[0], "%s", p);
    return p;
}

/* ---- a NetCDF file of velocities ---- */
typedef struct spec {
    int nx, ny, nt;            /* nt = 0: steady, u and v of dimensions (y, x) */
    const double *x, *y, *t;   /* t in the file's time units */
    const double *u, *v;       /* nt ny nx values (ny nx when steady) */
    const char *time_units;    /* NULL: "seconds since 2000-01-01 00:00:00" */
    const char *x_units;       /* NULL: "m" */
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
    nc_def_dim(nc, "x", (size_t)s->nx, &dx);
    nc_def_dim(nc, "y", (size_t)s->ny, &dy);
    if (s->nt) nc_def_dim(nc, "time", NC_UNLIMITED, &dt);
    nc_def_var(nc, "x", NC_DOUBLE, 1, &dx, &vx);
    nc_def_var(nc, "y", NC_DOUBLE, 1, &dy, &vy);
    const char *xu = s->x_units ? s->x_units : "m";
    nc_put_att_text(nc, vx, "units", strlen(xu), xu);
    nc_put_att_text(nc, vy, "units", 1, "m");
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
    for (int k = 0; k < nwritten; k++) remove(written[k]);
    rmdir(tmpdir);
    return check_summary("test_netcdf");
}

#endif
