/* test_scene_limits.c - hostile or absurd scene files are refused quickly, each with a
 * message naming the file, the position and the field (core/scene.c, issue 10 "a run never
 * lies and never hangs"): step counts that overflow, huge or jammed packings, output
 * intervals below the time resolution, non-regular mesh files. An alarm turns a hang into a
 * failure. */
#include "check.h"
#include "floe_scene.h"
#include "floe_observer.h"
#include "floe_mesh.h"
#include "world_internal.h"

#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define BASE_MATS                                                                      \
    "dimension: 3\n"                                                                   \
    "time: {duration: 0.01, dt: 1.0e-5}\n"                                             \
    "materials:\n"                                                                     \
    "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"                  \
    "laws:\n"                                                                          \
    "  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n"
#define ONE_BODY "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, position: [0, 0, 0]}\n"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* "LINE:COL" (1-based) of the first occurrence of needle in text */
static const char *loc_of(const char *text, const char *needle)
{
    static char buf[4][32];
    static int slot = 0;
    const char *p = strstr(text, needle);
    char *b = buf[slot++ % 4];
    if (!p) { snprintf(b, 32, "?:?"); return b; }
    int line = 1, col = 1;
    for (const char *q = text; q < p; q++) {
        if (*q == '\n') { line++; col = 1; }
        else col++;
    }
    snprintf(b, 32, "%d:%d", line, col);
    return b;
}

/* The scene (text of length len, may hold NUL bytes) must fail within max_s seconds; the
 * message must start with "t.yaml:<at>: " (at NULL: "t.yaml") and contain each needle. */
static void expect_fail_n(const char *what, const char *text, const char *at, const char *n1, const char *n2,
                          double max_s)
{
    char err[1024] = "";
    floe_world *w = (floe_world *)1;
    floe_scene_info info;
    double t0 = now_s();
    int rc = floe_scene_load_ex("t.yaml", text, NULL, 0, &w, &info, err, sizeof err);
    double el = now_s() - t0;
    CHECK(rc != FLOE_OK, "%s: loaded but should fail", what);
    CHECK(w == NULL, "%s: world not NULL on failure", what);
    char pre[64];
    if (at) snprintf(pre, sizeof pre, "t.yaml:%s: ", at);
    else snprintf(pre, sizeof pre, "t.yaml");
    CHECK(!strncmp(err, pre, strlen(pre)), "%s: message '%s' does not start with '%s'", what, err, pre);
    if (n1) CHECK(strstr(err, n1) != NULL, "%s: message '%s' lacks '%s'", what, err, n1);
    if (n2) CHECK(strstr(err, n2) != NULL, "%s: message '%s' lacks '%s'", what, err, n2);
    CHECK(el <= max_s, "%s: refused after %.2f s (limit %.1f s)", what, el, max_s);
    printf("  %-28s %.2f s  %s\n", what, el, err);
}
#define expect_fail(what, text, at, n1, n2) expect_fail_n(what, text, at, n1, n2, 5.0)

static void test_steps(void)
{
    printf("step counts\n");
    const char *t = "dimension: 3\ntime: {duration: 1e30, dt: 1.0e-5}\n"
                    "materials:\n  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
                    "laws:\n  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n" ONE_BODY;
    expect_fail("duration 1e30", t, loc_of(t, "1e30"), "time.duration", "1e12 steps");
    t = "dimension: 3\ntime: {duration: 1e30}\n"
        "materials:\n  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
        "laws:\n  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n" ONE_BODY;
    expect_fail("duration 1e30, auto dt", t, loc_of(t, "1e30"), "time.duration", "steps of");
}

static void test_packings(void)
{
    printf("packings\n");
    const char *t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                              "     region: {min: [0, 0, 0], max: [1e19, 1, 1]}, count: 10}\n";
    expect_fail("random region 1e19 m", t, loc_of(t, "[1e19"), "region", "beyond 1e12 m");
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [1e11, 1e11, 1e11]}, count: 10}\n";
    {
        char err[1024];
        floe_world *w = NULL;
        double t0 = now_s();
        int rc = floe_scene_load_ex("t.yaml", t, NULL, 0, &w, NULL, err, sizeof err);
        CHECK(rc == FLOE_OK && w && w->p.n == 10, "random packing in a 1e11 m region: %s", rc ? err : "");
        CHECK(now_s() - t0 < 5, "... in %.2f s", now_s() - t0);
        floe_world_destroy(w);
    }
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}, count: 1000, max_tries: 1000000000}\n";
    expect_fail("random cannot fit", t, loc_of(t, "1000,"), "cannot fit", "1000 particles");
    /* fits by volume (fraction 0.52) but beyond random sequential jamming (0.38) */
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}, count: 125, max_tries: 1000000000}\n";
    expect_fail_n("random jammed", t, loc_of(t, "125,"), "jammed", "tries in a row", 20.0);
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}, count: 10, max_tries: 5000000000}\n";
    expect_fail("max_tries 5e9", t, loc_of(t, "5000000000"), "max_tries", "1e9");
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [1, 1, 1]}, count: 1000000000000}\n";
    expect_fail("random count 1e12", t, loc_of(t, "1000000000000"), "count must be in [1, 1e8]", NULL);
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     spacing: 0.003, region: {min: [0, 0, 0], max: [1e9, 1e9, 1e9]}}\n";
    expect_fail("lattice region 1e9 m", t, loc_of(t, "{min"), "too many lattice sites", NULL);
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     spacing: 0.003, region: {min: [0, 0, 0], max: [1e11, 1e11, 1e11]}}\n";
    expect_fail("lattice region 1e11 m", t, loc_of(t, "{min"), "too many lattice sites", NULL);
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     spacing: 0.003, region: {min: [0, 0, 0], max: [1e19, 1, 1]}}\n";
    expect_fail("lattice region 1e19 m", t, loc_of(t, "[1e19"), "region", "beyond 1e12 m");
}

static void test_intervals(void)
{
    printf("output intervals\n");
    const char *t = BASE_MATS ONE_BODY "outputs:\n  - {type: energy, interval: 1e-300, file: e.csv}\n";
    expect_fail("interval 1e-300", t, loc_of(t, "1e-300"), "outputs[0].interval", "time resolution");
    /* an interval shorter than the step writes every step (and the world does not count the
     * intervals one by one) */
    char dir[] = "/tmp/floe_limits_XXXXXX";
    CHECK(mkdtemp(dir) != NULL, "mkdtemp");
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: energy, interval: 1e-10, file: e.csv}\n";
    floe_world *w = NULL;
    char err[1024];
    int rc = floe_scene_load_ex("t.yaml", t, dir, 1, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "interval 1e-10 s loads: %s", rc ? err : "");
    if (rc == FLOE_OK) {
        CHECK(w->nobs == 1 && w->obs[0]->period_steps == 1, "interval below dt -> every step (period_steps %ld)",
              w->nobs ? w->obs[0]->period_steps : -1L);
        double t0 = now_s();
        rc = floe_world_run(w, 1e-3, NULL, NULL);
        CHECK(rc == FLOE_OK && now_s() - t0 < 5, "100 steps with interval 1e-10 s: rc %d, %.2f s", rc, now_s() - t0);
        floe_world_destroy(w);
        char p[512];
        snprintf(p, sizeof p, "%s/e.csv", dir);
        FILE *f = fopen(p, "r");
        int lines = 0, c;
        while (f && (c = fgetc(f)) != EOF) lines += c == '\n';
        if (f) fclose(f);
        CHECK(lines == 1 + 101, "e.csv has a header and 101 rows (got %d lines)", lines);
        remove(p);
    }
    rmdir(dir);
}

static void test_mesh_fifo(void)
{
    printf("mesh files\n");
    if (!(floe_mesh_features() & FLOE_MESH_HAVE_ASSIMP)) {
        printf("  (built without assimp: skipped)\n");
        return;
    }
    char dir[] = "/tmp/floe_limits_XXXXXX";
    CHECK(mkdtemp(dir) != NULL, "mkdtemp");
    char fifo[512];
    snprintf(fifo, sizeof fifo, "%s/grain.stl", dir);
    CHECK(mkfifo(fifo, 0600) == 0, "mkfifo %s", fifo);
    char t[2048];
    snprintf(t, sizeof t, BASE_MATS "bodies:\n  - {shape: {mesh: {file: %s}}, material: glass, position: [0, 0, 0]}\n",
             fifo);
    expect_fail("FIFO as mesh file", t, loc_of(t, fifo), "not a regular file", "FIFO");
    snprintf(t, sizeof t, BASE_MATS "bodies:\n  - {shape: {mesh: {file: %s}}, material: glass, position: [0, 0, 0]}\n",
             dir);
    expect_fail("directory as mesh file", t, loc_of(t, dir), "not a regular file", "directory");
    remove(fifo);
    rmdir(dir);
}

int main(void)
{
    alarm(120); /* a hang is a failure */
    test_steps();
    test_packings();
    test_intervals();
    test_mesh_fifo();
    return check_summary("test_scene_limits");
}
