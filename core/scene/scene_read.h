/* scene_read.h - the scene loader's shared context and helpers (the files of core/scene),
 * one file per section of a scene: scene_read.c (errors, YAML node helpers, schema
 * reader, RNG), scene_materials.c (materials, laws, walls), scene_bodies.c (shapes,
 * bodies, packings), scene_pd.c (peridynamic bodies), scene_outputs.c (outputs, bonds),
 * scene.c (the root, time, checks, summary, loading). Internal: not installed. */
#ifndef FLOE_SCENE_INTERNAL_H
#define FLOE_SCENE_INTERNAL_H
#include "floe_scene.h"
#include "floe_registry.h"
#include "floe_rng.h"
#include "floe_state.h"
#include "world_internal.h"
#include "floe_observer.h"
#include "floe_mesh.h"
#include "floe_pd.h"
#include "floe_beam.h"
#include "floe_provider.h"
#include "floe_servo.h"

#include <errno.h>
#include <libfyaml.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* Field names in messages ("bodies[3].shape.compound.pieces[1]...") are built in fixed
 * buffers; a name that long is cut, which only shortens the message. */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wformat-truncation"
#endif

#define SC_MAX_PARTICLES_PER_ENTRY 100000000L
/* scene text: 16 MiB at most */
#define SC_MAX_TEXT ((size_t)16 << 20)
/* a run of more steps than this would never end (and the step count must fit a long) */
#define SC_MAX_STEPS 1.0e12
/* random packing: placement stops after this many tries in a row without a placement */
#define SC_MAX_FAILED_TRIES 10000000L
#define SC_MAX_TRIES 1000000000L
/* random packing of drawn radii: refused outright when the spheres' solid would fill more
 * of the region than a random close packing does (3D 0.64, 2D 0.84) */
#define SC_RANDOM_MAX_FRACTION(dim) ((dim) == 3 ? 0.64 : 0.84)
/* Memory a scene needs, estimated before its particles are made (measured: 64k and 256k
 * touching spheres, check and run, ~550 B per particle; brittle-cylinder-impact ~35 B per
 * PD bond): a scene beyond the machine's memory is refused instead of dying part-way. */
#define SC_BYTES_BASE 16.0e6
#define SC_BYTES_PER_PARTICLE 700.0
#define SC_BYTES_PER_BOND 40.0
/* with threads (OpenMP's default above one): the contact stage's per-entry forces and the
 * particles' entry lists (docs/parallel.md), 81 B per list entry, ~3-6 entries per particle */
#define SC_BYTES_PER_PARTICLE_THREADS 300.0


/* ------------------------------------------------------------------------------------ */
/* Loader context                                                                        */

typedef struct sc_mat {
    floe_material m;
    int has_young, has_poisson;
    struct fy_node *at;           /* the entry, for messages */
    struct fy_node *body_user;    /* first `material:` node of a body using it */
    struct fy_node *wall_user;    /* first `material:` node of a wall using it */
    int body_entry, wall_entry;   /* indices of those users */
    long nbody, nwall;            /* particles / walls of this material */
    int nfree;                    /* some particle of this material is free */
} sc_mat;

typedef struct sc_law {
    int a, b;
    const floe_registry_entry *ent;  /* the registered law (floe_registry.h) */
    void *params;                    /* its parameter struct, read by its schema */
    struct fy_node *node;            /* the entry (messages) */
    /* a composed law (normal: {...}, tangential: {...}): ent/params are the normal part's,
     * ent_t/params_t the tangential part's (NULL: frictionless) */
    int composed;
    const floe_registry_entry *ent_t;
    void *params_t;
} sc_law;

typedef struct sc_output {
    char type[64];
    const floe_registry_entry *ent; /* the registered output */
    void *uparams;                  /* a plugin output's parameters (its schema) */
    char target[512];
    long every;
    double interval;
    struct fy_node *name_at;      /* file / prefix value (NULL: the default), for messages */
    char file[520];               /* the file it writes (vtk: its .pvd), to refuse two writers of one file */
} sc_output;

typedef struct sc {
    const char *path;
    const char *text;
    long textlen;
    char *err;
    size_t errlen;
    int dim;
    floe_world *w;
    sc_mat *mats;
    int nmats;
    sc_law *laws;
    int nlaws;
    struct fy_node **law_at;     /* nmats*nmats: node of the law given for the pair */
    int nbody_entries;
    int nparticles, nwalls, nstates, nobservers;
    int nspheres, nboxes;
    int *entry_first, *entry_count; /* particle range of each body entry */
    sc_output *outs;
    int nouts;
    int outs_cap; /* entries allocated in outs (each one's uparams freed with the loader, parsed or not) */
    double duration, dt_given, safety;
    int dt_auto;
    int grow_particle[8];
    int ngrow_listed;
} sc;

/* A mapping being read: which node, where it came from (for messages), its dotted path. */
typedef struct sc_map {
    struct fy_node *node;
    struct fy_node *at;
    char what[96];
} sc_map;

typedef struct sc_rng { unsigned long long s; } sc_rng; /* floe_rng.h */

/* A radius distribution (scene_psd.c): kind 0 uniform [lo, hi], 1 lognormal (ln r normal
 * of mean mu and deviation sigma, truncated to [lo, hi]), 2 given radii r with their count
 * probabilities p; seed of its own stream. */
#define SC_PSD_MAX_GIVEN 64
typedef struct sc_psd {
    int kind;
    double lo, hi, mu, sigma;
    int ngiven;
    double r[SC_PSD_MAX_GIVEN], p[SC_PSD_MAX_GIVEN];
    unsigned long long seed;
} sc_psd;

/* the helpers shared by the section files (names kept short here, prefixed in the library) */
#define sc_bool floe_sc_bool
#define sc_build_laws floe_sc_build_laws
#define sc_build_shape floe_sc_build_shape
#define sc_check_memory floe_sc_check_memory
#define sc_check_pairs floe_sc_check_pairs
#define sc_check_planar floe_sc_check_planar
#define sc_enum floe_sc_enum
#define sc_fail floe_sc_fail
#define sc_fail_pos floe_sc_fail_pos
#define sc_field floe_sc_field
#define sc_geom_frame floe_sc_geom_frame
#define sc_get floe_sc_get
#define sc_has floe_sc_has
#define sc_is_missing floe_sc_is_missing
#define sc_line floe_sc_line
#define sc_loc floe_sc_loc
#define sc_long floe_sc_long
#define sc_map_open floe_sc_map_open
#define sc_material_ref floe_sc_material_ref
#define sc_mem_estimate floe_sc_mem_estimate
#define sc_node_list floe_sc_node_list
#define sc_node_long floe_sc_node_long
#define sc_num floe_sc_num
#define sc_parse_bodies floe_sc_parse_bodies
#define sc_parse_bonds floe_sc_parse_bonds
#define sc_parse_forces floe_sc_parse_forces
#define sc_floe_field floe_sc_floe_field
#define sc_floe_entry floe_sc_floe_entry
#define sc_polygons_file floe_sc_polygons_file
#define sc_polys_build floe_sc_polys_build
#define sc_polys_create floe_sc_polys_create
#define sc_polys_destroy floe_sc_polys_destroy
#define sc_polys_fail floe_sc_polys_fail
#define sc_polys_fail_at floe_sc_polys_fail_at
#define sc_polys_names floe_sc_polys_names
#define sc_polys_ring floe_sc_polys_ring
#define sc_polys_thickness floe_sc_polys_thickness
#define sc_shapefile_read floe_sc_shapefile_read
#define sc_parse_laws floe_sc_parse_laws
#define sc_parse_materials floe_sc_parse_materials
#define sc_parse_outputs floe_sc_parse_outputs
#define sc_parse_pd floe_sc_parse_pd
#define sc_parse_walls floe_sc_parse_walls
#define sc_phys_mem floe_sc_phys_mem
#define sc_pos_num floe_sc_pos_num
#define sc_parse_psd floe_sc_parse_psd
#define sc_psd_draw floe_sc_psd_draw
#define sc_parse_prepare floe_sc_parse_prepare
#define sc_range floe_sc_range
#define sc_read_schema floe_sc_read_schema
#define sc_rng_uniform floe_sc_rng_uniform
#define sc_str floe_sc_str
#define sc_suggest floe_sc_suggest
#define sc_text floe_sc_text
#define sc_type_name floe_sc_type_name
#define sc_vec floe_sc_vec

int sc_bool(sc *s, const sc_map *m, const char *key, int def, int *out);
int sc_build_laws(sc *s);
int sc_build_shape(sc *s, struct fy_node *v, struct fy_node *k, const char *f, int depth,
                          floe_geometry **out);
int sc_check_memory(sc *s, struct fy_node *at, const char *what, double more);
int sc_check_pairs(sc *s);
int sc_check_planar(sc *s, const sc_map *m, const char *key, const double x[3]);
int sc_enum(sc *s, const sc_map *m, const char *key, const char *const *names, int def,
                   int *out);
void sc_field(char *buf, size_t len, const sc_map *m, const char *key);
void sc_geom_frame(const floe_geometry *g, double fx[3], double fq[4]);
struct fy_node *sc_get(const sc_map *m, const char *key, struct fy_node **keyp);
int sc_has(const sc_map *m, const char *key);
int sc_is_missing(struct fy_node *n);
int sc_line(const sc *s, struct fy_node *n);
int sc_loc(const sc *s, struct fy_node *n, int *line, int *col);
int sc_long(sc *s, const sc_map *m, const char *key, int required, long def, long *out);
int sc_map_open(sc *s, struct fy_node *node, struct fy_node *at, const char *what,
                       const char *const *keys, sc_map *m);
int sc_material_ref(sc *s, const char *name, struct fy_node *at, const char *field, int *out);
double sc_mem_estimate(const sc *s, double more_particles);
int sc_node_list(sc *s, struct fy_node *v, struct fy_node *k, const char *field, int n,
                        int n2, double *out, int *got);
int sc_node_long(sc *s, struct fy_node *v, struct fy_node *k, const char *field, long *out);
/* order[0..n) = the indices of the n points x (stride doubles apart, dim coordinates in the
 * box [lo, hi], every axis scaled by its longest side) in Morton order: neighbours in space
 * get nearby ranks (ties by index). FLOE_ENOMEM when out of memory */
int sc_morton_order(const double *x, long n, int stride, int dim, const double *lo, const double *hi, long *order);
int sc_num(sc *s, const sc_map *m, const char *key, int required, double def, double *out);
int sc_parse_bodies(sc *s, struct fy_node *seq, struct fy_node *key);
int sc_parse_cell(sc *s, struct fy_node *v, struct fy_node *key);
int sc_parse_bonds(sc *s, struct fy_node *seq, struct fy_node *key);
int sc_parse_forces(sc *s, struct fy_node *seq, struct fy_node *key);
/* a body entry {floe_field: {...}, material, ...}: a Voronoi field of 2D floes (scene_floes.c) */
int sc_floe_field(sc *s, struct fy_node *e, int entry, const char *what);
/* the keys every floe entry shares: material (its index), velocity, motion (scene_floes.c) */
int sc_floe_entry(sc *s, const sc_map *m, int entry, const char *what, int *mat, double v[3], int *motion);
/* a body entry {polygons_file: PATH, material, ...}: floes, coasts and islands from a GeoJSON
 * file of polygons, or from an ESRI shapefile when PATH ends in .shp (scene_geojson.c) */
int sc_polygons_file(sc *s, struct fy_node *e, int entry, const char *what);
/* The polygons of a polygons_file entry as its reader hands them over (scene_polygons.c): one
 * path checks every ring and builds the bodies, whatever the file's format. */
typedef struct sc_polys sc_polys;
/* an empty set for the entry `what` ("bodies[2].polygons_file", copied) reading `file`
 * (borrowed), at node `at` (for messages), entry thickness h (m; 0: none); NULL out of memory */
sc_polys *sc_polys_create(sc *s, struct fy_node *at, const char *what, const char *file, double h);
void sc_polys_destroy(sc_polys *g);
/* checks that no two polygons overlap, then adds one body per polygon (material mat, the
 * entry's velocity and motion where a polygon's `fixed` does not say, group `entry`) */
int sc_polys_build(sc_polys *g, int mat, const double v[3], int motion, int entry);
/* the words naming a polygon in messages: "feature"/"shape", "polygon"/"part" (the parts
 * of a multi-polygon) and its ring ("ring 0"/"the ring") */
void sc_polys_names(sc_polys *g, const char *unit, const char *part, const char *ring);
/* the entry's thickness (m; 0: none): a polygon's own thickness overrides it */
double sc_polys_thickness(const sc_polys *g);
/* One outer ring of polygon `feature` (part `part` of it; -1: a single polygon): n points
 * (x, y), as the file writes them (the closing point and repeats may be there; point k is
 * named k in messages), thickness h (m; 0: none), fixed -1 (not said), 0 or 1. Checked
 * (finite, >= 3 distinct points, simple, non-zero area), cut into convex pieces, kept;
 * FLOE_OK or the error reported at the entry naming the file and the polygon. */
int sc_polys_ring(sc_polys *g, int feature, int part, const double *xy, long n, double h, int fixed);
/* an error at the entry, "what: file: message" */
int sc_polys_fail(sc_polys *g, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* the same at a line and column of the file, "what: file:line:col: message" */
int sc_polys_fail_at(sc_polys *g, int code, int line, int col, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;
/* Reads the polygons of an ESRI shapefile (path: its .shp) into g through shapelib
 * (scene_shapefile.c); without FLOE_WITH_SHAPELIB an error naming the option. */
int sc_shapefile_read(sc_polys *g, const char *path);
int sc_parse_laws(sc *s, struct fy_node *seq, struct fy_node *key);
int sc_parse_materials(sc *s, struct fy_node *seq, struct fy_node *key);
int sc_parse_outputs(sc *s, struct fy_node *seq, struct fy_node *key, const char *outdir,
                            int with_outputs);
int sc_parse_pd(sc *s, struct fy_node *seq, struct fy_node *key);
/* the body's radius_distribution (scene_psd.c), and n radii drawn from it into r, largest first */
int sc_parse_psd(sc *s, const sc_map *body, sc_psd *d);
int sc_psd_draw(const sc_psd *d, long n, double *r);
/* the scene's prepare block at node v (key k; scene_prepare.c): read and its walls made servo
 * walls; run = 1 also runs it (compaction, friction, the clock back to 0) and writes a line
 * saying what it reached into done */
int sc_parse_prepare(sc *s, struct fy_node *v, struct fy_node *k, int run, char *done, size_t donelen);
int sc_parse_walls(sc *s, struct fy_node *seq, struct fy_node *key);
double sc_phys_mem(void);
int sc_pos_num(sc *s, const sc_map *m, const char *key, double *out);
int sc_range(sc *s, const sc_map *m, const char *key, const char *cond, double got);
int sc_read_schema(sc *s, const sc_map *m, const floe_registry_entry *ent, const char *label,
                          const char *loader_keys, void *params);
double sc_rng_uniform(sc_rng *r);
int sc_str(sc *s, const sc_map *m, const char *key, int required, const char *def,
                  const char **out, struct fy_node **at);
void sc_suggest(char *buf, size_t len, const char *word, const char *const *names, int n);
const char *sc_text(struct fy_node *n);
const char *sc_type_name(struct fy_node *n);
int sc_vec(sc *s, const sc_map *m, const char *key, int required, const double def[3],
                  double out[3]);
/* Errors: "path:line:col: message" (or "path: message" when the position is unknown) into
 * the caller's buffer; they return code (FLOE_EINVAL for 0). At a node: */
int sc_fail(sc *s, int code, struct fy_node *at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
/* the same at a byte offset of the text (-1: no position) */
int sc_fail_pos(sc *s, int code, long pos, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#endif
