/* test_scene_errors.c - scene files (core/scene/scene.c, docs/scene-format.md): every error
 * names the file, line and column and the offending field; valid scenes build the right
 * particles (lattice, hexagonal 2D/3D, random, region-filled HCP of the RVE example). */
#include "check.h"
#include "scene_loc.h"
#include "floe_scene.h"
#include "floe.h"
#include "world_read.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BASE_MATS                                                                      \
    "dimension: 3\n"                                                                   \
    "time: {duration: 0.01}\n"                                                         \
    "materials:\n"                                                                     \
    "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"                  \
    "laws:\n"                                                                          \
    "  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n"
#define ONE_BODY "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, position: [0, 0, 0]}\n"

/* Replace the first occurrence of `from` in base by `to` (static buffer). */
static const char *edit(const char *base, const char *from, const char *to)
{
    static char buf[4][8192];
    static int slot = 0;
    char *b = buf[slot++ % 4];
    const char *p = strstr(base, from);
    if (!p) { snprintf(b, 8192, "%s", base); fprintf(stderr, "edit: '%s' not found\n", from); return b; }
    snprintf(b, 8192, "%.*s%s%s", (int)(p - base), base, to, p + strlen(from));
    return b;
}

static int load(const char *text, floe_world **w, floe_scene_info *info, char *err, size_t len)
{
    return floe_scene_load_ex("t.yaml", text, NULL, 0, w, info, err, len);
}

/* The scene must fail; the message must start with "t.yaml:<at>: " (at = "L:C", or NULL for
 * no location check) and contain each needle. */
static void expect_error(const char *what, const char *text, const char *at, const char *n1,
                         const char *n2)
{
    char err[1024] = "";
    floe_world *w = (floe_world *)1;
    floe_scene_info info;
    int rc = load(text, &w, &info, err, sizeof err);
    CHECK(rc != FLOE_OK, "%s: loaded but should fail", what);
    CHECK(w == NULL, "%s: world not NULL on failure", what);
    if (at) {
        char pre[64];
        snprintf(pre, sizeof pre, "t.yaml:%s: ", at);
        CHECK(!strncmp(err, pre, strlen(pre)), "%s: message '%s' does not start with '%s'", what, err,
              pre);
    }
    if (n1) CHECK(strstr(err, n1) != NULL, "%s: message '%s' lacks '%s'", what, err, n1);
    if (n2) CHECK(strstr(err, n2) != NULL, "%s: message '%s' lacks '%s'", what, err, n2);
    printf("  %-28s %s\n", what, err);
}

static void expect_file_error(const char *file, const char *at, const char *n1, const char *n2)
{
    char path[1024], err[1024] = "";
    snprintf(path, sizeof path, "%s/scenes/%s", FLOE_TEST_DIR, file);
    floe_world *w = NULL;
    floe_scene_info info;
    int rc = floe_scene_load_ex(path, NULL, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc != FLOE_OK && w == NULL, "%s: loaded but should fail", file);
    char pre[1100];
    snprintf(pre, sizeof pre, "%s:%s: ", path, at);
    CHECK(!strncmp(err, pre, strlen(pre)), "%s: message '%s' does not start with '%s'", file, err, pre);
    if (n1) CHECK(strstr(err, n1) != NULL, "%s: message '%s' lacks '%s'", file, err, n1);
    if (n2) CHECK(strstr(err, n2) != NULL, "%s: message '%s' lacks '%s'", file, err, n2);
    printf("  %-28s %s\n", file, err);
}

static int count_group(const floe_world *w, int g)
{
    int n = 0;
    for (int i = 0; i < pview(w).n; i++) n += pview(w).group[i] == g;
    return n;
}

static void test_malformed(void)
{
    printf("malformed YAML\n");
    expect_file_error("bad_indent.yaml", "10:4", "YAML", NULL);
    expect_file_error("bad_unclosed.yaml", "11:15", "never closed", NULL);
    const char *t = BASE_MATS "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass, "
                              "position: [0, 0, 0\n";
    expect_error("unclosed [ (string)", t, loc_of(t, "[0, 0, 0", 0), "'[' is never closed", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {sphere: {radius: 0.001}}, material: glass\n";
    expect_error("unclosed {", t, loc_of(t, "{shape", 0), "'{' is never closed", NULL);
    t = BASE_MATS "bodies:\n  - shape: {sphere: {radius: 0.001}}\n      material: glass\n";
    expect_error("bad indentation", t, "9:7", "YAML", NULL);
    t = "dimension: 3\ndimension: 2\n";
    expect_error("duplicate key", t, "2:1", "duplicate key", NULL);
    expect_error("empty scene", "", NULL, "t.yaml", "empty");
    expect_error("not a mapping", "- 1\n- 2\n", "1:1", "must be a mapping", NULL);
    char err[512];
    floe_world *w = NULL;
    int rc = floe_scene_load("/nonexistent/dir/scene.yaml", NULL, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_EIO && w == NULL && strstr(err, "/nonexistent/dir/scene.yaml"),
          "missing file: rc %d, '%s'", rc, err);
}

static void test_keys(void)
{
    printf("unknown keys\n");
    expect_file_error("bad_key.yaml", "10:5", "unknown key 'frition'", "did you mean 'friction'?");
    const char *t = edit(BASE_MATS ONE_BODY, "friction: 0.5", "frition: 0.5");
    expect_error("misspelled friction", t, loc_of(t, "frition", 0), "'frition'",
                 "did you mean 'friction'?");
    t = edit(BASE_MATS ONE_BODY, "bodies:", "bodys:");
    expect_error("misspelled bodies", t, loc_of(t, "bodys", 0), "'bodys'", "did you mean 'bodies'?");
    t = edit(BASE_MATS ONE_BODY, "position:", "positon:");
    expect_error("misspelled position", t, loc_of(t, "positon", 0), "'positon'",
                 "did you mean 'position'?");
    t = edit(BASE_MATS ONE_BODY, "density:", "densty:");
    expect_error("misspelled density", t, loc_of(t, "densty", 0), "did you mean 'density'?", NULL);
    t = edit(BASE_MATS ONE_BODY, "radius:", "raduis:");
    expect_error("transposed radius", t, loc_of(t, "raduis", 0), "did you mean 'radius'?", NULL);
    t = edit(BASE_MATS ONE_BODY, "{duration: 0.01}", "{duration: 0.01, sfety: 0.5}");
    expect_error("misspelled safety", t, loc_of(t, "sfety", 0), "did you mean 'safety'?", NULL);
    t = edit(BASE_MATS ONE_BODY, "friction: 0.5}", "friction: 0.5, gn: 1}");
    expect_error("key of another model", t, loc_of(t, "gn:", 0), "'gn'", "hertz_mindlin");
    t = edit(BASE_MATS ONE_BODY, "model: hertz_mindlin", "model: hertz");
    expect_error("unknown model", t, loc_of(t, "hertz,", 0), "unknown value 'hertz'",
                 "hertz_mindlin");
    t = edit(BASE_MATS ONE_BODY, "{shape:", "{packing: lattise, shape:");
    expect_error("unknown packing", t, loc_of(t, "lattise", 0), "did you mean 'lattice'?", NULL);
    t = edit(BASE_MATS ONE_BODY, "{sphere:", "{spere:");
    expect_error("unknown shape", t, loc_of(t, "spere", 0), "did you mean 'sphere'?", NULL);
}

static void test_physics(void)
{
    printf("invalid physics\n");
    const char *b = BASE_MATS ONE_BODY;
    const char *t = edit(b, "radius: 0.001", "radius: -0.001");
    expect_error("negative radius", t, loc_of(t, "-0.001", 0), "radius", "> 0");
    t = edit(b, "radius: 0.001", "radius: 0");
    expect_error("zero radius", t, loc_of(t, "0}}", 0), "radius", "> 0");
    t = edit(b, "poisson: 0.3", "poisson: 0.5");
    expect_error("poisson 0.5", t, loc_of(t, "0.5}", 0), "poisson", "(-1, 0.5)");
    t = edit(b, "poisson: 0.3", "poisson: 0.7");
    expect_error("poisson 0.7", t, loc_of(t, "0.7", 0), "poisson", NULL);
    t = edit(b, "poisson: 0.3", "poisson: -1");
    expect_error("poisson -1", t, loc_of(t, "-1", 0), "poisson", NULL);
    t = edit(b, "density: 2500", "density: 0");
    expect_error("density 0", t, loc_of(t, "0,", 0), "density", "> 0");
    t = edit(b, "density: 2500", "density: -2500");
    expect_error("density < 0", t, loc_of(t, "-2500", 0), "density", NULL);
    t = edit(b, "young: 1.0e7", "young: 0");
    expect_error("young 0", t, loc_of(t, "0, poisson", 0), "young", "> 0");
    t = edit(b, "{duration: 0.01}", "{duration: 0.01, dt: -1.0e-5}");
    expect_error("dt < 0", t, loc_of(t, "-1.0e-5", 0), "time.dt", NULL);
    t = edit(b, "{duration: 0.01}", "{duration: 0}");
    expect_error("duration 0", t, loc_of(t, "0}", 0), "time.duration", NULL);
    t = edit(b, "{duration: 0.01}", "{duration: 0.01, dt: 1.0e-3}");
    expect_error("dt above critical", t, loc_of(t, "1.0e-3", 0), "critical", NULL);
    t = edit(b, "{duration: 0.01}", "{duration: 0.01, safety: 1.5}");
    expect_error("safety > 1", t, loc_of(t, "1.5", 0), "time.safety", NULL);
    t = edit(b, "restitution: 0.5", "restitution: 0");
    expect_error("restitution 0", t, loc_of(t, "0, friction", 0), "restitution", "(0, 1]");
    t = edit(b, "restitution: 0.5", "restitution: 1.2");
    expect_error("restitution > 1", t, loc_of(t, "1.2", 0), "restitution", NULL);
    t = edit(b, "friction: 0.5", "friction: -0.1");
    expect_error("friction < 0", t, loc_of(t, "-0.1", 0), "friction", NULL);
    t = edit(b, "dimension: 3", "dimension: 4");
    expect_error("dimension 4", t, "1:12", "dimension", "2 or 3");
    t = edit(b, "model: hertz_mindlin, restitution: 0.5, friction: 0.5",
             "model: linear, kn: -20, ks: 10");
    expect_error("kn < 0", t, loc_of(t, "-20", 0), "kn", NULL);
    t = edit(b, "model: hertz_mindlin, restitution: 0.5, friction: 0.5",
             "model: viscoelastic, kn: 20, ks: 10, gn: -1, gs: 0");
    expect_error("gn < 0", t, loc_of(t, "-1", 0), "gn", NULL);
    t = edit(b, "young: 1.0e7, poisson: 0.3", "poisson: 0.3");
    expect_error("hertz needs young", t, "4:5", "young", "hertz_mindlin");
    t = edit(b, "position: [0, 0, 0]}", "position: [0, 0, 0], grow_rate: 1}");
    t = edit(t, "{sphere: {radius: 0.001}}", "{box: {size: [0.001, 0.001, 0.001]}}");
    expect_error("box cannot grow", t, NULL, "only spheres can grow", NULL);
}

static void test_materials_and_laws(void)
{
    printf("materials and laws\n");
    const char *b = BASE_MATS ONE_BODY;
    const char *t = edit(b, "material: glass,", "material: glas,");
    expect_error("unknown body material", t, loc_of(t, "glas,", 0), "unknown material 'glas'",
                 "did you mean 'glass'?");
    t = edit(b, "[glass, glass]", "[glass, steel]");
    expect_error("unknown law material", t, loc_of(t, "steel", 0), "unknown material 'steel'", NULL);
    t = edit(b, "[glass, glass]", "[glass]");
    expect_error("law with 1 material", t, loc_of(t, "[glass]", 0), "laws[0].materials",
                 "2 material names");
    t = BASE_MATS "  - {materials: [glass, glass], model: linear, kn: 1, ks: 1}\n" ONE_BODY;
    expect_error("duplicate law", t, loc_of(t, "[glass, glass]", 1), "already given at line 6",
                 NULL);
    t = "dimension: 3\ntime: {duration: 0.01}\nmaterials:\n"
        "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
        "  - {name: glass, density: 7800, young: 2.0e8, poisson: 0.3}\n" ONE_BODY;
    expect_error("duplicate material", t, "5:12", "already defined at line 4", NULL);
    expect_file_error("bad_missing_law.yaml", "13:50", "no contact law for materials (glass, steel)",
                      "bodies[0] and bodies[1]");
    t = "dimension: 3\ntime: {duration: 0.01}\nmaterials:\n"
        "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
        "  - {name: steel, density: 7800, young: 2.0e8, poisson: 0.3}\n"
        "laws:\n  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5}\n"
        "walls:\n  - {point: [0, 0, 0], normal: [0, 0, 1], material: steel}\n" ONE_BODY;
    expect_error("missing wall law", t, loc_of(t, "glass, position", 0), "(glass, steel)", "walls[0]");
    /* a single particle of a material needs no law with itself */
    t = "dimension: 3\ntime: {duration: 0.01, dt: 1e-4}\nmaterials:\n"
        "  - {name: steel, density: 7800, young: 2.0e8, poisson: 0.3}\n" ONE_BODY;
    t = edit(t, "material: glass", "material: steel");
    char err[512];
    floe_world *w = NULL;
    int rc = load(t, &w, NULL, err, sizeof err);
    CHECK(rc == FLOE_OK, "lone particle without a law: %s", err);
    floe_world_destroy(w);
}

static void test_types(void)
{
    printf("wrong types\n");
    const char *b = BASE_MATS ONE_BODY;
    const char *t = edit(b, "radius: 0.001", "radius: \"big\"");
    expect_error("string radius", t, loc_of(t, "\"big\"", 0), "radius", "expected a number");
    t = edit(b, "radius: 0.001", "radius: abc");
    expect_error("word radius", t, loc_of(t, "abc", 0), "expected a number", NULL);
    t = edit(b, "position: [0, 0, 0]", "position: [0, 0]");
    expect_error("short position", t, loc_of(t, "[0, 0]", 0), "position",
                 "expected a list of 3 numbers, got 2 entries");
    t = edit(b, "position: [0, 0, 0]", "position: [0, 0, 0, 0]");
    expect_error("long position", t, loc_of(t, "[0, 0, 0, 0]", 0), "got 4 entries", NULL);
    t = edit(b, "position: [0, 0, 0]", "position: [0, x, 0]");
    expect_error("bad list entry", t, loc_of(t, "x, 0]", 0), "position[1]", "expected a number");
    t = edit(b, "position: [0, 0, 0]", "position: 0");
    expect_error("scalar position", t, loc_of(t, "0}", 0), "expected a list", NULL);
    t = edit(b, "dimension: 3", "dimension: 3.5");
    expect_error("float dimension", t, "1:12", "expected an integer", NULL);
    t = edit(b, "materials:\n  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}",
             "materials: {name: glass}");
    expect_error("materials not a list", t, loc_of(t, "{name", 0), "materials must be a list",
                 NULL);
    t = edit(b, "{duration: 0.01}", "{duration: 0.01, allow_unstable_dt: maybe}");
    expect_error("bad bool", t, loc_of(t, "maybe", 0), "true or false", NULL);
    t = edit(b, "{sphere: {radius: 0.001}}", "{sphere: {radius: 0.001}, box: {size: [1, 1, 1]}}");
    expect_error("two shapes", t, NULL, "exactly one shape", NULL);
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass, "
                  "origin: [0, 0, 0], counts: [3, 3], spacing: 0.0025}\n";
    expect_error("2 counts in 3D", t, loc_of(t, "[3, 3]", 0), "counts", "3 numbers");
    t = edit(t, "counts: [3, 3]", "counts: [3, 0, 2]");
    expect_error("zero count", t, loc_of(t, "0, 2]", 0), "counts[1]", ">= 1");
}

static void test_packing_errors(void)
{
    printf("packing errors\n");
    const char *t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, "
                              "material: glass, origin: [0, 0, 0], counts: [3, 3, 2], spacing: 0.0015}\n";
    expect_error("overlapping lattice", t, loc_of(t, "0.0015", 0), "spacing", "overlap");
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass, "
                  "region: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}, count: 1000, max_tries: 20000}\n";
    expect_error("random cannot fit", t, loc_of(t, "1000", 0), "cannot fit", NULL);
    t = edit(t, "count: 1000", "count: 100");
    expect_error("random runs out of tries", t, loc_of(t, "100,", 0), "could only place", "raise max_tries");
    t = BASE_MATS "bodies:\n  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass, "
                  "region: {min: [0, 0, 0], max: [0.01, 0.0, 0.01]}, count: 10}\n";
    expect_error("empty region", t, NULL, "max must exceed min", NULL);
    t = BASE_MATS "bodies:\n  - {packing: hexagonal, shape: {sphere: {radius: 0.001}}, material: glass, "
                  "origin: [0, 0, 0], counts: [2, 2, 2], spacing: 0.002, grow: {index: 8, rate: 1}}\n";
    expect_error("grow index out of range", t, NULL, "grow.index 8", "8 particles");
    t = BASE_MATS "bodies:\n  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass, "
                  "spacing: 0.002}\n";
    expect_error("lattice without counts", t, NULL, "counts", "region");
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: tracker, every: 10, particles: [0, 3]}\n";
    expect_error("tracker id", t, loc_of(t, "3]", 0), "particle 3 does not exist", NULL);
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: stress, every: 10, group: 2}\n";
    expect_error("stress group", t, loc_of(t, "2}", 0), "group", NULL);
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: vtk, every: 0}\n";
    expect_error("every 0", t, loc_of(t, "0}", 0), "every", NULL);
    /* a registered output that fails after its parameters were read: the parameters are
     * freed with the loader (a leak the fuzzer found, seen by the sanitizer build) */
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: contacts, every: 0}\n";
    expect_error("registered output, every 0", t, loc_of(t, "0}", 0), "every", NULL);
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: energy, every: 5}\n  - {type: contacts, interval: -1}\n";
    expect_error("registered output, second, bad interval", t, loc_of(t, "-1}", 0), "interval", NULL);
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: vtk, every: 10, interval: 0.1}\n";
    expect_error("every and interval", t, NULL, "not both", NULL);
    t = BASE_MATS ONE_BODY "outputs:\n  - {type: energy, prefix: e}\n";
    expect_error("key of another output", t, loc_of(t, "prefix", 0), "'prefix'", "type energy");
    const char *t2 = edit(BASE_MATS ONE_BODY, "dimension: 3", "dimension: 2");
    t2 = edit(t2, "position: [0, 0, 0]", "position: [0, 0, 1]");
    expect_error("2D z position", t2, loc_of(t2, "[0, 0, 1]", 0), "z component must be 0", NULL);
    t2 = edit(BASE_MATS ONE_BODY, "dimension: 3", "dimension: 3\nmass_2d: area");
    expect_error("mass_2d in 3D", t2, "2:10", "mass_2d", "dimension: 2");
}

static void test_valid(void)
{
    printf("valid scenes\n");
    char path[1024], err[1024] = "";
    floe_world *w = NULL;
    floe_scene_info info;

    snprintf(path, sizeof path, "%s/scenes/valid_packings.yaml", FLOE_TEST_DIR);
    int rc = floe_scene_load_ex(path, NULL, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && w, "valid_packings.yaml: %s", err);
    if (w) {
        CHECK(info.nparticles == 74, "particles %d, expected 74", info.nparticles);
        CHECK(info.nwalls == 1 && info.nmaterials == 2 && info.nlaws == 3, "walls %d mats %d laws %d",
              info.nwalls, info.nmaterials, info.nlaws);
        CHECK(floe_world_particle_count(w) == 75, "world particles %d (74 + 1 wall)",
              floe_world_particle_count(w));
        CHECK(count_group(w, 0) == 18, "lattice 3x3x2: %d particles", count_group(w, 0));
        CHECK(count_group(w, 1) == 24, "hexagonal 4x3x2: %d particles", count_group(w, 1));
        CHECK(count_group(w, 2) == 30, "random: %d particles", count_group(w, 2));
        CHECK(count_group(w, 3) == 1 && count_group(w, 4) == 1, "single bodies");
        CHECK(strstr(info.summary, "critical dt") != NULL, "summary lacks the critical dt");
        CHECK(strstr(info.summary, "sphere-sphere analytic") != NULL, "summary lacks the detectors");
        CHECK(strcmp(info.name, "packings") == 0, "name '%s'", info.name);
        CHECK(floe_world_dt(w) > 0 && floe_world_dt(w) <= 0.2 * floe_world_critical_dt(w) * (1 + 1e-12),
              "automatic dt %g vs critical %g", floe_world_dt(w), floe_world_critical_dt(w));
        /* HCP: body 1 starts at (0.02, 0, 0.002); second layer shifted by (d/2, d sqrt(3)/6, d sqrt(2/3)) */
        int first = -1;
        for (int i = 0; i < pview(w).n && first < 0; i++) if (pview(w).group[i] == 1) first = i;
        const double d = 0.002;
        const double *x0 = pview(w).x + 3 * first;
        CHECK_NEAR(x0[0], 0.02, 1e-12, "hcp site 0 x");
        const double *x4 = pview(w).x + 3 * (first + 4);   /* row 1, i = 0: offset d/2 */
        CHECK_NEAR(x4[0] - x0[0], 0.5 * d, 1e-9, "hcp row 1 x offset d/2");
        CHECK_NEAR(x4[1] - x0[1], d * sqrt(3.0) / 2, 1e-9, "hcp row spacing d sqrt(3)/2");
        const double *x12 = pview(w).x + 3 * (first + 12); /* layer 1 */
        CHECK_NEAR(x12[2] - x0[2], d * sqrt(2.0 / 3.0), 1e-9, "hcp layer spacing d sqrt(2/3)");
        CHECK_NEAR(x12[0] - x0[0], 0.5 * d, 1e-9, "hcp layer B x shift d/2");
        CHECK_NEAR(x12[1] - x0[1], d * sqrt(3.0) / 6, 1e-9, "hcp layer B y shift d sqrt(3)/6");
        /* nearest-neighbour distance in HCP is d */
        double dmin = 1e9;
        for (int i = first; i < first + 24; i++)
            for (int j = i + 1; j < first + 24; j++) {
                double r[3];
                floe_v3_sub(r, pview(w).x + 3 * i, pview(w).x + 3 * j);
                if (floe_v3_norm(r) < dmin) dmin = floe_v3_norm(r);
            }
        CHECK_NEAR(dmin, d, 1e-9, "hcp nearest neighbour distance");
        /* random: inside the region, no overlaps */
        int ok_in = 1, ok_sep = 1;
        for (int i = 0; i < pview(w).n; i++) {
            if (pview(w).group[i] != 2) continue;
            const double *x = pview(w).x + 3 * i;
            if (x[0] < 0.001 || x[0] > 0.019 || x[1] < 0.021 || x[1] > 0.039 || x[2] < 0.002 ||
                x[2] > 0.019)
                ok_in = 0;
            for (int j = i + 1; j < pview(w).n; j++) {
                if (pview(w).group[j] != 2) continue;
                double r[3];
                floe_v3_sub(r, x, pview(w).x + 3 * j);
                if (floe_v3_norm(r) < 0.002) ok_sep = 0;
            }
        }
        CHECK(ok_in, "random particles must lie inside the region");
        CHECK(ok_sep, "random particles must not overlap");
        floe_world_destroy(w);
    }

    snprintf(path, sizeof path, "%s/scenes/valid_2d.yaml", FLOE_TEST_DIR);
    w = NULL;
    rc = floe_scene_load_ex(path, NULL, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && w, "valid_2d.yaml: %s", err);
    if (w) {
        CHECK(info.nparticles == 33 && info.nstates == 1, "2D: %d particles, %d states",
              info.nparticles, info.nstates);
        CHECK(count_group(w, 0) == 25 && count_group(w, 1) == 8, "2D groups %d %d", count_group(w, 0),
              count_group(w, 1));
        const double *x12 = pview(w).x + 3 * 12, *x5 = pview(w).x + 3 * 5;
        CHECK_NEAR(x12[0], 0.4, 1e-12, "2D hex middle x (row 2 not offset)");
        CHECK_NEAR(x12[1], 0.4 * sqrt(3.0) / 2, 1e-12, "2D hex middle y = 2 d sqrt(3)/2");
        CHECK_NEAR(x5[0], 0.1, 1e-12, "2D hex row 1 offset by d/2");
        CHECK(x12[2] == 0, "2D z = 0");
        CHECK(pview(w).geometry[12] != pview(w).geometry[11], "the growing sphere has its own geometry");
        CHECK(pview(w).geometry[11] == pview(w).geometry[13], "the others share one geometry");
        floe_world_destroy(w);
    }

    /* dt: 0 is an error naming the field; dt: auto is automatic; dt above critical is
     * accepted with allow_unstable_dt */
    const char *t = edit(BASE_MATS ONE_BODY, "{duration: 0.01}", "{duration: 0.01, dt: 0}");
    w = NULL;
    rc = load(t, &w, &info, err, sizeof err);
    CHECK(rc != FLOE_OK && !w && strstr(err, "dt") && strstr(err, "> 0"), "dt: 0 must be refused naming dt: %s", err);
    t = edit(BASE_MATS ONE_BODY, "{duration: 0.01}", "{duration: 0.01, dt: auto}");
    w = NULL;
    rc = load(t, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && w && floe_world_dt(w) > 0, "dt: auto = automatic: %s", err);
    floe_world_destroy(w);
    t = edit(BASE_MATS ONE_BODY, "{duration: 0.01}",
             "{duration: 0.01, dt: 1.0e-3, allow_unstable_dt: true}");
    w = NULL;
    rc = load(t, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && w && floe_world_dt(w) == 1.0e-3, "allow_unstable_dt: %s", err);
    floe_world_destroy(w);

    /* the default demo and the two examples */
    w = NULL;
    rc = floe_scene_load_ex("<demo>", floe_scene_default_demo(), NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && info.nparticles == 2000 && info.nwalls == 5, "demo: rc %d, %d particles: %s",
          rc, info.nparticles, err);
    floe_world_destroy(w);

    snprintf(path, sizeof path, "%s/examples/rve-compression/scene.yaml", FLOE_SOURCE_DIR);
    w = NULL;
    rc = floe_scene_load_ex(path, NULL, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && w, "rve-compression: %s", err);
    if (w) {
        CHECK(info.nparticles == 16483, "RVE: %d spheres, expected 16,483 (peers' HCP packing)",
              info.nparticles);
        double gap = 1e9, top = 0;
        const double L[3] = {0.85, 0.85, 1.0};
        for (int i = 0; i < pview(w).n; i++) {
            if (pview(w).group[i] != 0) continue;
            for (int k = 0; k < 3; k++) {
                double g = fmin(pview(w).x[3 * i + k], L[k] - pview(w).x[3 * i + k]);
                if (g < gap) gap = g;
            }
            if (pview(w).x[3 * i + 2] > top) top = pview(w).x[3 * i + 2];
        }
        CHECK(gap >= 0.019 + 1e-4 - 1e-12, "RVE: a centre is %g from a wall (< R + 1e-4)", gap);
        CHECK_NEAR(top + 0.019, 0.969, 1e-3, "RVE top of the packing (peers: 0.969)");
        CHECK(floe_world_dt(w) == 5.0e-5, "RVE dt %g", floe_world_dt(w));
        floe_world_destroy(w);
    }
    snprintf(path, sizeof path, "%s/examples/dilating-sphere/scene.yaml", FLOE_SOURCE_DIR);
    w = NULL;
    rc = floe_scene_load_ex(path, NULL, NULL, 0, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK && info.nparticles == 25 && info.nstates == 1,
          "dilating-sphere: rc %d, %d particles, %d states: %s", rc, info.nparticles, info.nstates, err);
    floe_world_destroy(w);
}


/* shapes of issue #3: every shape kind builds, bad shapes name the field and the defect */
static void test_shapes(void)
{
    const char *t;
    t = BASE_MATS "bodies:\n  - {shape: {polyhedron: {planes: [[1,0,0,1],[-1,0,0,1],[0,1,0,1],[0,-1,0,1],[0,0,1,1]]}}, "
                  "material: glass, position: [0, 0, 0]}\n";
    expect_error("unbounded planes", t, loc_of(t, "[[1,0,0,1]", 0), "bodies[0].shape.polyhedron.planes", "unbounded");
    t = BASE_MATS "bodies:\n  - {shape: {polyhedron: {vertices: [[0,0,0],[1,0,0]], planes: [[1,0,0,1]]}}, "
                  "material: glass, position: [0, 0, 0]}\n";
    expect_error("vertices and planes", t, loc_of(t, "polyhedron", 0), "either vertices", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {polygon: {vertices: [[0,0],[1,0],[0,1]]}}, material: glass, position: [0, 0, 0]}\n";
    expect_error("polygon in 3D", t, loc_of(t, "polygon", 0), "2D shape", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {prism: {vertices: [[0,0],[1,0],[2,0]], height: 1}}, material: glass, "
                  "position: [0, 0, 0]}\n";
    expect_error("collinear prism", t, loc_of(t, "[[0,0]", 0), "bodies[0].shape.prism.vertices", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {ellipsoid: {semi_axes: [1, 0, 1]}}, material: glass, position: [0, 0, 0]}\n";
    expect_error("ellipsoid axis 0", t, loc_of(t, "[1, 0, 1]", 0), "semi_axes[1] must be > 0", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {cylinder: {radius: 1}}, material: glass, position: [0, 0, 0]}\n";
    expect_error("cylinder without height", t, NULL, "height", "required");
    t = BASE_MATS "bodies:\n  - {shape: {rounded: {radius: 0.1, shape: {sphre: {radius: 1}}}}, material: glass, "
                  "position: [0, 0, 0]}\n";
    expect_error("rounded inner misspelled", t, loc_of(t, "sphre", 0), "did you mean 'sphere'?", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {compound: {pieces: [{shape: {box: {size: [1,1,1]}}, postion: [0,0,0]}]}}, "
                  "material: glass, position: [0, 0, 0]}\n";
    expect_error("compound piece key", t, loc_of(t, "postion", 0), "did you mean 'position'?", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {mesh: {file: no-such-grain.stl}}, material: glass, position: [0, 0, 0]}\n";
    expect_error("missing mesh file", t, loc_of(t, "no-such-grain.stl", 0), "no-such-grain.stl", NULL);
    t = BASE_MATS "bodies:\n  - {shape: {mesh: {file: g.stl, mode: hul}}, material: glass, position: [0, 0, 0]}\n";
    expect_error("mesh mode", t, loc_of(t, "hul}", 0), "did you mean 'hull'?", NULL);
    t = BASE_MATS "contact_detection: {tolerance: 2}\n" ONE_BODY;
    expect_error("ADMM tolerance", t, loc_of(t, "2}", 0), "contact_detection.tolerance", NULL);

    /* every convex kind in one valid scene, with the orientation of a polyhedron kept */
    t = BASE_MATS
        "contact_detection: {tolerance: 1.0e-8, max_iterations: 50}\n"
        "bodies:\n"
        "  - {shape: {box: {size: [1, 1, 1]}}, material: glass, position: [0, 0, 0]}\n"
        "  - {shape: {polyhedron: {planes: [[1,0,0,1],[-1,0,0,1],[0,1,0,2],[0,-1,0,2],[0,0,1,3],[0,0,-1,3]]}}, "
        "material: glass, position: [5, 0, 0]}\n"
        "  - {shape: {prism: {vertices: [[0,0],[1,0],[0,1]], height: 0.5}}, material: glass, position: [10, 0, 0]}\n"
        "  - {shape: {ellipsoid: {semi_axes: [1, 2, 3]}}, material: glass, position: [15, 0, 0]}\n"
        "  - {shape: {cylinder: {radius: 1, height: 2}}, material: glass, position: [20, 0, 0]}\n"
        "  - {shape: {capsule: {radius: 1, length: 2}}, material: glass, position: [25, 0, 0]}\n"
        "  - {shape: {cone: {radius: 1, height: 2}}, material: glass, position: [30, 0, 0]}\n"
        "  - {shape: {rounded: {radius: 0.1, shape: {box: {size: [1, 1, 1]}}}}, material: glass, position: [35, 0, 0]}\n"
        "  - {shape: {compound: {pieces: [{shape: {box: {size: [2, 1, 1]}}}, {shape: {box: {size: [1, 1, 2]}}, "
        "position: [0.5, 0, 1.5]}]}}, material: glass, position: [40, 0, 0]}\n";
    floe_world *w = NULL;
    floe_scene_info info;
    char err[1024];
    int rc = load(t, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "all convex shapes load: %s", rc ? err : "");
    if (rc == FLOE_OK) {
        CHECK(pview(w).n == 9, "9 bodies (got %d)", pview(w).n);
        floe_admm_options ao;
        floe_world_admm_options(w, &ao);
        CHECK(ao.tol == 1.0e-8 && ao.max_iter == 50, "contact_detection options reach the world");
        CHECK(pview(w).pieces[8] == 2, "the compound has 2 pieces (got %d)", pview(w).pieces[8]);
        /* the 2 x 4 x 6 polyhedron: principal axes are a permutation, the orientation maps
         * them back onto the input axes, so its world extent along y is 4 */
        const floe_geometry *g = floe_world_particle_geometry(w, 1);
        double ey[3] = {0, 1, 0}, eb[3], X[3];
        floe_q_rotate_inv(eb, pview(w).q + 4, ey);
        g->klass->support(g, eb, X);
        CHECK(fabs(floe_v3_dot(X, eb) - 2.0) < 1e-12, "polyhedron keeps its input orientation (half extent along y %g)",
              floe_v3_dot(X, eb));
        floe_world_destroy(w);
    }
}

/* peridynamic bodies in a scene */
static void test_pd_scene(void)
{
    const char *base = BASE_MATS
        "peridynamics:\n"
        "  - region: {box: {min: [0, 0, 0], max: [0.01, 0.01, 0.004]}}\n"
        "    spacing: 0.001\n"
        "    material: {model: pmb, density: 2200, bulk_modulus: 14.9e9, critical_stretch: 0.001}\n"
        "    contact_material: glass\n";
    floe_world *w = NULL;
    floe_scene_info info;
    char err[1024];
    int rc = load(base, &w, &info, err, sizeof err);
    CHECK(rc == FLOE_OK, "a PD-only scene loads: %s", rc ? err : "");
    if (rc == FLOE_OK) {
        CHECK(floe_world_pd_body_count(w) == 1 && pview(w).n == 10 * 10 * 4, "one PD body of 400 points (got %d bodies, %d particles)", floe_world_pd_body_count(w),
              pview(w).n);
        CHECK(pview(w).group[0] == -2, "PD points are body -2 in outputs");
        floe_world_destroy(w);
    }
    const char *t;
    t = edit(base, "model: pmb", "model: pdm");
    expect_error("PD model", t, loc_of(t, "pdm", 0), "did you mean 'pmb'?", NULL);
    t = edit(base, "spacing: 0.001", "spacing: 0");
    expect_error("PD spacing", t, loc_of(t, "0\n    material", 0), "peridynamics[0].spacing must be > 0", NULL);
    t = edit(base, "model: pmb", "model: lps");
    expect_error("LPS without G", t, NULL, "shear_modulus", NULL);
    t = edit(base, "contact_material: glass", "contact_material: glas");
    expect_error("PD contact material", t, loc_of(t, "glas\n", 0), "glas", NULL);
    t = edit(base, "critical_stretch: 0.001}", "critical_stretch: 0.001, fracture_energy: 10}");
    expect_error("stretch and energy", t, NULL, "not both", NULL);
}

/* the periodic cell block (core/scene/scene_cell.c, docs/periodic.md) */
static void test_cell(void)
{
    printf("periodic cell\n");
    const char *ok = BASE_MATS ONE_BODY "cell: {size: [0.01, 0.01, 0.01]}\n";
    const char *t = edit(ok, "size:", "sise:");
    expect_error("cell key misspelled", t, loc_of(t, "sise", 0), "did you mean 'size'?", NULL);
    t = edit(ok, "[0.01, 0.01, 0.01]", "[0.01, 0, 0.01]");
    expect_error("cell size 0", t, NULL, "cell.size", "> 0");
    t = edit(ok, "0.01]}", "0.01], strain_rate: {xx: -1}, stress: {xx: -100}, max_strain_rate: 1}");
    expect_error("rate and stress on xx", t, NULL, "xx", "both a strain rate and a stress");
    t = edit(ok, "0.01]}", "0.01], stress: {zz: -100}}");
    expect_error("stress without max rate", t, NULL, "max_strain_rate", "required");
    t = edit(ok, "0.01]}", "0.01], strain_rate: {xq: 1}}");
    expect_error("unknown component", t, loc_of(t, "xq", 0), "'xq'", NULL);
    t = edit(ok, "[0.01, 0.01, 0.01]", "[0.003, 0.01, 0.01]");
    expect_error("cell of 1.5 diameters", t, loc_of(t, "[0.003", 0), "two particle diameters", NULL);
}

int main(void)
{
    test_malformed();
    test_keys();
    test_physics();
    test_materials_and_laws();
    test_types();
    test_packing_errors();
    test_valid();
    test_shapes();
    test_pd_scene();
    test_cell();
    return check_summary("test_scene_errors");
}
