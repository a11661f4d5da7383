/* test_scene_limits.c - hostile or absurd scene files are refused quickly, each with a
 * message naming the file, the position and the field (core/scene/scene.c, issue 10 "a run never
 * lies and never hangs"): step counts that overflow, huge or jammed packings, output
 * intervals below the time resolution, non-regular mesh files. An alarm turns a hang into a
 * failure. */
#include "check.h"
#include "scene_loc.h"
#include "floe_scene.h"
#include "floe_observer.h"
#include "floe_mesh.h"
#include "world_internal.h" /* internal: unit test of the observers' NaN guards: injects a NaN state and calls an observer directly */

#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include "test_files.h"

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
    expect_fail("duration 1e30", t, loc_of(t, "1e30", 0), "time.duration", "1e12 steps");
    t = "dimension: 3\ntime: {duration: 1e30}\n"
        "materials:\n  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
        "laws:\n  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n" ONE_BODY;
    expect_fail("duration 1e30, auto dt", t, loc_of(t, "1e30", 0), "time.duration", "steps of");
}

static void test_packings(void)
{
    printf("packings\n");
    const char *t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                              "     region: {min: [0, 0, 0], max: [1e19, 1, 1]}, count: 10}\n";
    expect_fail("random region 1e19 m", t, loc_of(t, "[1e19", 0), "region", "beyond 1e12 m");
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
    expect_fail("random cannot fit", t, loc_of(t, "1000,", 0), "cannot fit", "1000 particles");
    /* fits by volume (fraction 0.52) but beyond random sequential jamming (0.38) */
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}, count: 125, max_tries: 1000000000}\n";
    expect_fail_n("random jammed", t, loc_of(t, "125,", 0), "jammed", "tries in a row", 20.0);
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}, count: 10, max_tries: 5000000000}\n";
    expect_fail("max_tries 5e9", t, loc_of(t, "5000000000", 0), "max_tries", "1e9");
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [1, 1, 1]}, count: 1000000000000}\n";
    expect_fail("random count 1e12", t, loc_of(t, "1000000000000", 0), "count must be in [1, 1e8]", NULL);
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     spacing: 0.003, region: {min: [0, 0, 0], max: [1e9, 1e9, 1e9]}}\n";
    expect_fail("lattice region 1e9 m", t, loc_of(t, "{min", 0), "too many lattice sites", NULL);
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     spacing: 0.003, region: {min: [0, 0, 0], max: [1e11, 1e11, 1e11]}}\n";
    expect_fail("lattice region 1e11 m", t, loc_of(t, "{min", 0), "too many lattice sites", NULL);
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     spacing: 0.003, region: {min: [0, 0, 0], max: [1e19, 1, 1]}}\n";
    expect_fail("lattice region 1e19 m", t, loc_of(t, "[1e19", 0), "region", "beyond 1e12 m");
}

static void test_intervals(void)
{
    printf("output intervals\n");
    const char *t = BASE_MATS ONE_BODY "outputs:\n  - {type: energy, interval: 1e-300, file: e.csv}\n";
    expect_fail("interval 1e-300", t, loc_of(t, "1e-300", 0), "outputs[0].interval", "time resolution");
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
    expect_fail("FIFO as mesh file", t, loc_of(t, fifo, 0), "not a regular file", "FIFO");
    snprintf(t, sizeof t, BASE_MATS "bodies:\n  - {shape: {mesh: {file: %s}}, material: glass, position: [0, 0, 0]}\n",
             dir);
    expect_fail("directory as mesh file", t, loc_of(t, dir, 0), "not a regular file", "directory");
    remove(fifo);
    rmdir(dir);
}

/* expect the file (written with len bytes of text) to fail with "path:at: " + needles */
static void expect_file_fail(const char *what, const char *text, size_t len, const char *at, const char *n1)
{
    char path[] = "/tmp/floe_limits_XXXXXX";
    int fd = mkstemp(path);
    CHECK(fd >= 0, "mkstemp");
    if (fd < 0) return;
    CHECK(write(fd, text, len) == (ssize_t)len, "write %s", path);
    close(fd);
    char err[1024] = "";
    floe_world *w = NULL;
    int rc = floe_scene_load_ex(path, NULL, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc != FLOE_OK && w == NULL, "%s: loaded but should fail", what);
    char pre[128];
    snprintf(pre, sizeof pre, "%s:%s: ", path, at);
    CHECK(!strncmp(err, pre, strlen(pre)), "%s: message '%s' does not start with '%s'", what, err, pre);
    CHECK(strstr(err, n1) != NULL, "%s: message '%s' lacks '%s'", what, err, n1);
    printf("  %-28s %s\n", what, err);
    remove(path);
}

static void test_text(void)
{
    printf("scene text\n");
    static const char good[] = BASE_MATS ONE_BODY;
    char buf[sizeof good];
    memcpy(buf, good, sizeof good);
    char *p = strstr(buf, "0.01");
    p[1] = '\0'; /* "time: {duration: 0\0.01..." */
    {
        char at[32];
        int l, c;
        sscanf(loc_of(good, "0.01", 0), "%d:%d", &l, &c);
        snprintf(at, sizeof at, "%d:%d", l, c + 1);
        expect_file_fail("NUL byte", buf, sizeof good - 1, at, "NUL byte");
    }
    memcpy(buf, good, sizeof good);
    p = strstr(buf, "glass");
    p[2] = (char)0xff;
    {
        /* line:col of the bad byte = that of "glass" + 2 columns */
        char at[32];
        int l, c;
        sscanf(loc_of(good, "glass", 0), "%d:%d", &l, &c);
        snprintf(at, sizeof at, "%d:%d", l, c + 2);
        expect_file_fail("invalid UTF-8 0xff", buf, sizeof good - 1, at, "invalid UTF-8 (byte 0xff)");
        memcpy(buf, good, sizeof good);
        p[0] = (char)0xc0; /* overlong encoding of '/' */
        p[1] = (char)0xaf;
        snprintf(at, sizeof at, "%d:%d", l, c);
        expect_file_fail("overlong UTF-8", buf, sizeof good - 1, at, "invalid UTF-8 (byte 0xc0)");
        memcpy(buf, good, sizeof good);
        p[0] = (char)0xe2; /* truncated 3-byte sequence */
        p[1] = (char)0x82;
        expect_file_fail("truncated UTF-8", buf, sizeof good - 1, at, "invalid UTF-8 (byte 0xe2)");
    }
    /* valid UTF-8 (names with accents, a 4-byte emoji in a comment) still loads */
    const char *t = BASE_MATS "# \xf0\x9f\x98\x80 caf\xc3\xa9\n" ONE_BODY;
    floe_world *w = NULL;
    char err[1024];
    int rc = floe_scene_load_ex("t.yaml", t, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "valid UTF-8 loads: %s", rc ? err : "");
    floe_world_destroy(w);

    t = BASE_MATS ": 37\n" ONE_BODY;
    expect_fail("empty root key", t, loc_of(t, ": 37", 0), "empty key in the scene", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, : 4, position: [0, 0, 0]}\n";
    expect_fail("empty key in a body", t, loc_of(t, ": 4", 0), "empty key in bodies[0]", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, position: []}\n";
    expect_fail("empty position list", t, loc_of(t, "[]", 0), "position", "got 0");
    t = BASE_MATS "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, position: {}}\n";
    expect_fail("empty position map", t, loc_of(t, "{}", 0), "position", NULL);
    t = "dimension: 3\ntime: {duration: 0.01}\nmaterials:\n  - {name: glass, density: 2500}\n"
        "laws:\n  - {materials: [], model: linear, kn: 1e3}\n" ONE_BODY;
    expect_fail("empty law materials", t, loc_of(t, "[]", 0), "laws[0].materials", NULL);
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: tracker, particles: []}\n";
    expect_fail("empty tracker list", t, loc_of(t, "[]", 0), "particles", NULL);
    t = BASE_MATS "bodies:\n  - {}\n";
    expect_fail("empty body", t, loc_of(t, "- {}", 0), "bodies[0].shape is required", NULL);

    /* two outputs writing one file */
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: csv, file: a.csv}\n  - {type: energy, every: 5, file: ./a.csv}\n";
    expect_fail("two writers of a.csv", t, loc_of(t, "./a.csv", 0), "outputs[0] (line 10, column 23)", "a.csv");
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: csv}\n  - {type: tracker, particles: [0], file: particles.csv}\n";
    expect_fail("default file taken", t, loc_of(t, "particles.csv", 0), "outputs[0] (line 10, column 5)", "particles.csv");
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: vtk, prefix: f}\n  - {type: vtk, prefix: f, every: 7}\n";
    expect_fail("two vtk prefixes", t, loc_of(t, "f, every", 0), "outputs[0]", "f.pvd");
}

static int has_nan_text(const char *t)
{
    return t && (strstr(t, "nan") || strstr(t, "inf") || strstr(t, "NaN") || strstr(t, "Inf"));
}

static void test_nonfinite(void)
{
    printf("parameters that would give NaN, and writers that never write one\n");
    const char *t = "dimension: 3\ntime: {duration: 0.01, dt: 1.0e-5, allow_unstable_dt: true}\n"
                    "materials:\n  - {name: glass, density: 1e-300, young: 1.0e7, poisson: 0.3}\n"
                    "laws:\n  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n"
                    ONE_BODY;
    expect_fail("density 1e-300", t, loc_of(t, "{name", 0), "particle 0 (bodies[0]) of material 'glass'",
                "mass 4.18879e-309 kg");
    t = BASE_MATS "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, position: [0, 0, 0], grow_rate: -1}\n";
    expect_fail("shrinking to zero", t, loc_of(t, "-1}", 0), "growth rate -1 m/s", "to zero at t = 0.001 s");
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass, origin: [0, 0, 0],\n"
                  "     counts: [2, 1, 1], spacing: 0.003, grow: {index: 1, rate: -0.5}}\n";
    expect_fail("packing shrinking to zero", t, loc_of(t, "-0.5", 0), "growth rate -0.5 m/s", "particle 1");

    /* a sphere that shrinks slowly is fine for the scene's duration; run past it, the state
     * object stops the run and the message says why */
    t = BASE_MATS "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, position: [0, 0, 0], grow_rate: -0.05}\n";
    floe_world *w = NULL;
    char err[1024];
    int rc = floe_scene_load_ex("t.yaml", t, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "slow shrink loads: %s", rc ? err : "");
    if (rc == FLOE_OK) {
        rc = floe_world_run(w, 0.05, NULL, NULL);
        const char *msg = floe_world_last_error(w);
        CHECK(rc != FLOE_OK && strstr(msg, "growing_radius") && strstr(msg, "growing radius of particle 0 became"),
              "a radius reaching zero stops with its reason: rc %d '%s'", rc, msg);
        printf("  %-28s %s\n", "radius reaches zero", msg);
        floe_world_destroy(w);
    }

    /* every writer refuses a NaN: its message names the particle and the field, and no file
     * holds "nan" or "inf" */
    char dir[] = "/tmp/floe_limits_XXXXXX";
    CHECK(mkdtemp(dir) != NULL, "mkdtemp");
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass, origin: [0, 0, 0],\n"
                  "     counts: [2, 1, 1], spacing: 0.003}\n"
                  "outputs:\n  - {type: csv, every: 1}\n  - {type: vtk, every: 1, prefix: f}\n"
                  "  - {type: tracker, every: 1, particles: [1]}\n  - {type: energy, every: 1}\n"
                  "  - {type: stress, every: 1, group: all}\n";
    static const char *const names[] = {"csv", "vtk", "tracker", "energy", "stress"};
    static const char *const needles[] = {"csv writer: particle 1 has a non-finite velocity",
                                          "vtk writer: particle 1 has a non-finite velocity",
                                          "particle tracker: particle 1 has a non-finite velocity",
                                          "energy tracker: kinetic_trans is nan", NULL};
    for (int k = 0; k < 4; k++) {
        /* one observer at a time: keep only output k */
        char one[4096];
        const char *o = strstr(t, "outputs:\n");
        const char *lines[5];
        const char *q = o + strlen("outputs:\n");
        for (int j = 0; j < 5; j++) { lines[j] = q; q = strchr(q, '\n') + 1; }
        int len = (int)(strchr(lines[k], '\n') + 1 - lines[k]);
        snprintf(one, sizeof one, "%.*soutputs:\n%.*s", (int)(o - t), t, len, lines[k]);
        w = NULL;
        rc = floe_scene_load_ex("t.yaml", one, dir, 1, &w, NULL, err, sizeof err);
        CHECK(rc == FLOE_OK, "%s: loads: %s", names[k], rc ? err : "");
        if (rc != FLOE_OK) continue;
        /* a NaN velocity at the next step, handed straight to the observer (the world's own
         * check would stop a run first) */
        w->p.v[3 * 1 + 0] = NAN;
        if (k == 3) w->energy.kinetic_trans = NAN; /* the ledger is kept by the step */
        w->step++;
        w->time += w->dt;
        floe_observer *ob = w->obs[0];
        rc = ob->klass->observe(ob, w);
        if (rc == FLOE_OK && ob->klass->end) rc = ob->klass->end(ob, w);
        const char *msg = floe_world_last_error(w);
        CHECK(rc != FLOE_OK && strstr(msg, needles[k]), "%s: NaN velocity: rc %d, message '%s' lacks '%s'", names[k],
              rc, msg, needles[k]);
        printf("  %-28s %s\n", names[k], msg);
        floe_world_destroy(w);
        static const char *const files[] = {"particles.csv", "f_000000.vtu", "track.csv", "energy.csv"};
        char path[600];
        snprintf(path, sizeof path, "%s/%s", dir, files[k]);
        char *txt = slurp(path);
        CHECK(txt && !has_nan_text(txt), "%s: %s %s", names[k], path, txt ? "holds a NaN or inf" : "missing");
        free(txt);
    }
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    CHECK(system(cmd) == 0, "%s", cmd);
}

static void test_yaml_size(void)
{
    printf("alias bombs and huge texts\n");
    /* "billion laughs": 10^9 scalars from ~500 bytes */
    char bomb[2048];
    int n = snprintf(bomb, sizeof bomb, "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n");
    for (int i = 1; i < 9; i++) {
        n += snprintf(bomb + n, sizeof bomb - (size_t)n, "a%d: &a%d [", i, i);
        for (int k = 0; k < 10; k++) n += snprintf(bomb + n, sizeof bomb - (size_t)n, "*a%d%s", i - 1, k < 9 ? ", " : "]\n");
    }
    expect_fail_n("alias bomb (10^9 nodes)", bomb, NULL, "more than 2000000 YAML nodes", "alias bomb", 10.0);
    expect_fail("alias cycle", "a: &a [1, *a]\n", "1:11", "alias *a", "refer to themselves");
    const char *t = BASE_MATS "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, position: *p}\n";
    expect_fail("undefined alias", t, loc_of(t, "*p", 0), "alias *p: no anchor &p", NULL);
    /* aliases and merge keys within bounds still work */
    t = BASE_MATS "bodies:\n  - &b {shape: {sphere: {radius: 0.001}}, material: glass, position: [0, 0, 0]}\n"
                  "  - {<<: *b, position: [0, 0, 1]}\n";
    floe_world *w = NULL;
    char err[1024];
    int rc = floe_scene_load_ex("t.yaml", t, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK && w && w->p.n == 2 && w->p.x[5] == 1.0, "aliases and a merge key: %s", rc ? err : "");
    floe_world_destroy(w);
    /* 3 million numbers written out: refused from the parser's events, before a document */
    size_t len = 6u * 1000000u + 16;
    char *big = malloc(len);
    if (big) {
        size_t k = (size_t)sprintf(big, "a: [");
        for (int i = 0; i < 3000000; i++) { big[k++] = '0'; big[k++] = ','; }
        big[k - 1] = ']';
        big[k++] = '\n';
        big[k] = 0;
        expect_fail_n("3e6 numbers", big, NULL, "more than 2000000 YAML nodes", NULL, 10.0);
        free(big);
    }
    /* a text over 16 MiB is refused before parsing */
    len = (17u << 20);
    big = malloc(len + 1);
    if (big) {
        memset(big, '#', len);
        big[len] = 0;
        expect_fail_n("17 MiB text", big, NULL, "larger than 16 MiB", NULL, 1.0);
        free(big);
    }
}

static void test_memory(void)
{
    printf("memory estimate\n");
    double have = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGE_SIZE);
    if (have > 60e9) {
        printf("  (this machine has %.3g GB: 1e8 particles might fit, skipped)\n", have / 1e9);
        return;
    }
    const char *t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                              "     origin: [0, 0, 0], counts: [1000, 1000, 100], spacing: 0.002}\n";
    expect_fail_n("1e8 particles", t, loc_of(t, "[1000", 0), "bodies[0]: 1e+08 particles", "more than this machine's memory",
                  2.0);
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,\n"
                  "     region: {min: [0, 0, 0], max: [100, 100, 100]}, count: 100000000}\n";
    expect_fail_n("random 1e8", t, loc_of(t, "100000000", 0), "1e+08 particles", "GB", 2.0);
}

/* observers that fail like writers on a full disk: A at step 3 (first), B and C at the end */
typedef struct failing_obs { floe_observer base; const char *name; int fail_observe_at; } failing_obs;

static int fo_observe(floe_observer *o, floe_world *w)
{
    failing_obs *f = (failing_obs *)o;
    if (f->fail_observe_at >= 0 && w->step >= f->fail_observe_at)
        return floe_world_error(w, FLOE_EIO, "%s: write failed: No space left on device", f->name);
    return FLOE_OK;
}

static int fo_end(floe_observer *o, floe_world *w)
{
    failing_obs *f = (failing_obs *)o;
    return floe_world_error(w, FLOE_EIO, "%s: closing failed: No space left on device", f->name);
}

static const floe_observer_class failing_class = {.version = 1, .name = "failing", .observe = fo_observe, .end = fo_end};

static void test_first_error(void)
{
    printf("the first writer error is reported\n");
    floe_world *w = NULL;
    char err[1024];
    int rc = floe_scene_load_ex("t.yaml", BASE_MATS ONE_BODY, NULL, 0, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "load: %s", rc ? err : "");
    if (rc != FLOE_OK) return;
    static const char *const names[3] = {"writer A", "writer B", "writer C"};
    for (int k = 0; k < 3; k++) {
        failing_obs *f = calloc(1, sizeof *f);
        f->base.klass = &failing_class;
        f->base.period_steps = 1;
        f->name = names[k];
        f->fail_observe_at = k == 0 ? 3 : -1;
        CHECK(floe_world_add_observer(w, &f->base) == FLOE_OK, "add observer %d", k);
    }
    w->prepared = 0; /* observers added after the load: prepare again */
    rc = floe_world_run(w, 1e-4, NULL, NULL);
    const char *msg = floe_world_last_error(w);
    CHECK(rc == FLOE_EIO && strstr(msg, "writer A: write failed") && strstr(msg, "at step 3"),
          "run: rc %d, message '%s' should name writer A at step 3", rc, msg);
    printf("  %-28s %s\n", "run", msg);
    floe_world_destroy(w);

    /* floe_world_finish alone: the first failing end() is reported */
    rc = floe_scene_load_ex("t.yaml", BASE_MATS ONE_BODY, NULL, 0, &w, NULL, err, sizeof err);
    if (rc != FLOE_OK) return;
    for (int k = 1; k < 3; k++) {
        failing_obs *f = calloc(1, sizeof *f);
        f->base.klass = &failing_class;
        f->base.period_steps = 1;
        f->name = names[k];
        f->fail_observe_at = -1;
        floe_world_add_observer(w, &f->base);
    }
    w->prepared = 0;
    rc = floe_world_run(w, 1e-4, NULL, NULL);
    msg = floe_world_last_error(w);
    CHECK(rc == FLOE_EIO && strstr(msg, "writer B: closing failed"), "finish: rc %d, message '%s' should name writer B",
          rc, msg);
    printf("  %-28s %s\n", "finish", msg);
    floe_world_destroy(w);
}

int main(void)
{
    alarm(120); /* a hang is a failure */
    test_text();
    test_yaml_size();
    test_nonfinite();
    test_memory();
    test_first_error();
    test_steps();
    test_packings();
    test_intervals();
    test_mesh_fifo();
    return check_summary("test_scene_limits");
}
