/* test_contact_export: the `contacts` (CSV) and `force_chains` (VTK lines) outputs
 * (observers/contact_writer.c) against a case computed by hand:
 *   - sphere 0 (free, R = 1) at the origin, sphere 1 (kinematic, R = 1) at x = 1.99 sliding
 *     along y at 0.1 m/s, a wall at x = -0.995 (normal +x: the solid is x < -0.995); linear law kn = 1000 N/m,
 *     ks = 500 N/m, friction 0.3, one step of 1e-4 s;
 *   - contacts.csv: two contacts at the last time; sphere-sphere fn = kn x 0.01 = 10 N,
 *     normal along +x from the lower index to the higher, depth 0.01, ft = ks vt dt (the
 *     tangential spring after one step, below Coulomb), the force on i = -fn n + the
 *     tangential part; sphere-wall fn = kn x 0.005 = 5 N;
 *   - the stored energy kn d^2 / 2 + ks s^2 / 2;
 *   - force_chains: one line (the wall contact left out), from centre to centre, fn = 10 N;
 *   - the public API (floe_world_contacts) gives the same contacts. */
#include "check.h"
#include "floe.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int main(void) {
    char err[1024] = "";
    floe_register_builtins(err, sizeof err);
    char dir[] = "/tmp/floe_contacts_XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return check_summary("test_contact_export");
    }
    const double kn = 1000, ks = 500, dt = 1e-4, vt = 0.1;
    char scene[2048];
    snprintf(scene, sizeof scene,
             "time: {duration: %g, dt: %g, allow_unstable_dt: true}\n"
             "gravity: [0, 0, 0]\n"
             "materials: [{name: m, density: 1000}]\n"
             "laws: [{materials: [m, m], model: linear, kn: %g, ks: %g, friction: 0.3}]\n"
             "bodies:\n"
             "  - {material: m, position: [0, 0, 0], shape: {sphere: {radius: 1}}}\n"
             "  - {material: m, position: [1.99, 0, 0], velocity: [0, %g, 0], motion: kinematic, shape: {sphere: {radius: 1}}}\n"
             "walls:\n"
             "  - {name: left, point: [-0.995, 0, 0], normal: [1, 0, 0], material: m}\n"
             "outputs:\n"
             "  - {type: contacts, every: 1, file: contacts.csv}\n"
             "  - {type: force_chains, every: 1, prefix: chains}\n",
             dt, dt, kn, ks, vt);
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_ex("contacts.yaml", scene, dir, 1, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "scene: %s", err);
    if (rc != FLOE_OK) return check_summary("test_contact_export");
    CHECK(floe_world_run(w, info.duration, NULL, NULL) == FLOE_OK, "run: %s", floe_world_last_error(w));
    /* the API: the contacts of the last evaluation (recorded for the outputs) */
    const floe_contact_info *ci = NULL;
    int nc = floe_world_contacts(w, &ci);
    CHECK(nc == 2, "API: two contacts (got %d)", nc);
    double api_fn_sum = 0;
    for (int k = 0; k < nc; k++) api_fn_sum += ci[k].fn;
    floe_world_destroy(w);

    /* contacts.csv: the rows of the last time */
    char path[512], line[1024];
    snprintf(path, sizeof path, "%s/contacts.csv", dir);
    FILE *f = fopen(path, "r");
    CHECK(f != NULL, "contacts.csv written");
    double tlast = -1;
    double rows[8][16];
    int nrows = 0;
    CHECK(f && fgets(line, sizeof line, f) && strncmp(line, "t [s],i,j,x [m]", 15) == 0, "contacts.csv header: %s",
          line);
    while (f && fgets(line, sizeof line, f)) {
        double r[16];
        int i, j;
        if (sscanf(line, "%lf,%d,%d,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &r[0], &i, &j, &r[3], &r[4],
                   &r[5], &r[6], &r[7], &r[8], &r[9], &r[10], &r[11], &r[12], &r[13], &r[14], &r[15]) != 16) {
            CHECK(0, "contacts.csv row: %s", line);
            continue;
        }
        r[1] = i;
        r[2] = j;
        if (r[0] > tlast) {
            tlast = r[0];
            nrows = 0;
        }
        if (nrows < 8) memcpy(rows[nrows++], r, sizeof r);
    }
    if (f) fclose(f);
    CHECK_NEAR(tlast, dt, 1e-12, "contacts.csv: the last rows at t = dt");
    CHECK(nrows == 2, "contacts.csv: two contacts at the last time (got %d)", nrows);
    double fn_sum = 0;
    for (int k = 0; k < nrows; k++) {
        const double *r = rows[k];
        fn_sum += r[9];
        const int sphere_pair = (r[1] == 0 && r[2] == 1) || (r[1] == 1 && r[2] == 0);
        if (sphere_pair) {
            const double sgn = r[1] == 0 ? 1.0 : -1.0; /* n from i to j: +x when i is sphere 0 */
            CHECK_NEAR(r[6] * sgn, 1.0, 1e-9, "sphere pair: the normal along x from i to j");
            CHECK_NEAR(r[9], kn * 0.01, 1e-6, "sphere pair: fn = kn d");
            CHECK_NEAR(r[14], 0.01, 1e-6, "sphere pair: depth");
            CHECK_NEAR(r[3], 0.995, 1e-6, "sphere pair: the contact point midway in the overlap");
            CHECK_NEAR(r[10], ks * vt * dt, 1e-6, "sphere pair: ft = ks vt dt (one step of the spring)");
            CHECK_NEAR(r[11] * sgn, -kn * 0.01, 1e-6, "sphere pair: the force on i pushes it back along x");
            CHECK(r[10] <= 0.3 * r[9], "sphere pair: ft %g within Coulomb %g", r[10], 0.3 * r[9]);
            const double s = vt * dt;
            CHECK_NEAR(r[15], 0.5 * kn * 0.01 * 0.01 + 0.5 * ks * s * s, 1e-6,
                       "sphere pair: stored energy kn d^2/2 + ks s^2/2");
        } else {
            CHECK_NEAR(r[9], kn * 0.005, 1e-6, "sphere-wall: fn = kn d");
            CHECK(fabs(r[10]) < 1e-12, "sphere-wall: no tangential force (%g)", r[10]);
        }
    }
    CHECK_NEAR(api_fn_sum, fn_sum, 1e-9, "the API's contacts = the CSV's (10 digits)");

    /* force_chains: the last frame has one line, fn 10 N */
    int frames = 0;
    for (;; frames++) {
        snprintf(path, sizeof path, "%s/chains_%06d.vtu", dir, frames);
        if (access(path, R_OK) != 0) break;
    }
    CHECK(frames >= 1, "force_chains frames written (%d)", frames);
    snprintf(path, sizeof path, "%s/chains_%06d.vtu", dir, frames - 1);
    f = fopen(path, "r");
    int cells = -1, points = -1;
    double fn_line = -1;
    int in_fn = 0;
    while (f && fgets(line, sizeof line, f)) {
        const char *p = strstr(line, "NumberOfPoints=\"");
        if (p) sscanf(p, "NumberOfPoints=\"%d\" NumberOfCells=\"%d\"", &points, &cells);
        if (in_fn) {
            sscanf(line, "%lf", &fn_line);
            in_fn = 0;
        }
        if (strstr(line, "Name=\"fn\"")) in_fn = 1;
    }
    if (f) fclose(f);
    CHECK(cells == 1 && points == 2, "force_chains: one line of two points, the wall left out (cells %d)", cells);
    CHECK_NEAR(fn_line, kn * 0.01, 1e-6, "force_chains: the line's fn");
    snprintf(path, sizeof path, "%s/chains.pvd", dir);
    CHECK(access(path, R_OK) == 0, "force_chains: the .pvd written");
    return check_summary("test_contact_export");
}
