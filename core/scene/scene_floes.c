/* scene_floes.c - a body entry `{floe_field: {...}, material, ...}`: a field of 2D
 * polygon floes from a Voronoi tessellation of a rectangle (geometry/voronoi.c), Lloyd-
 * relaxed, at a target ice concentration, with a thickness per floe (docs/sea-ice.md,
 * "Floe fields"). Each cell becomes one floe: its own convex polygon, placed where the
 * cell is (the polygon's centroid and principal axes), thickness h (+- a uniform spread). */
#include "scene_internal.h"
#include "floe_voronoi.h"
#include "floe_rng.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const field_keys[] = {"region", "count", "lloyd", "concentration", "seed", "thickness",
                                         "thickness_spread", NULL};

/* the keys every floe entry shares (a field, a GeoJSON file): material, velocity, motion */
int sc_floe_entry(sc *s, const sc_map *m, int entry, const char *what, int *mat, double v[3], int *motion)
{
    static const char *const motions[] = {"free", "fixed", "kinematic", NULL};
    const char *mname;
    struct fy_node *mat_at;
    FLOE_TRY(sc_str(s, m, "material", 1, NULL, &mname, &mat_at));
    char fmat[128];
    snprintf(fmat, sizeof fmat, "%s.material", what);
    FLOE_TRY(sc_material_ref(s, mname, mat_at, fmat, mat));
    if (!s->mats[*mat].body_user) {
        s->mats[*mat].body_user = mat_at;
        s->mats[*mat].body_entry = entry;
    }
    FLOE_TRY(sc_vec(s, m, "velocity", 0, NULL, v));
    FLOE_TRY(sc_check_planar(s, m, "velocity", v));
    return sc_enum(s, m, "motion", motions, 0, motion);
}

int sc_floe_field(sc *s, struct fy_node *e, int entry, const char *what)
{
    static const char *const keys[] = {"floe_field", "material", "velocity", "motion", "name", NULL};
    sc_map m;
    FLOE_TRY(sc_map_open(s, e, e, what, keys, &m));
    struct fy_node *fk, *fv = sc_get(&m, "floe_field", &fk);
    if (s->dim != 2)
        return sc_fail(s, FLOE_EINVAL, fk, "%s.floe_field: floe fields are 2D (dimension: 2)", what);
    char f[160];
    sc_field(f, sizeof f, &m, "floe_field");
    sc_map fm;
    FLOE_TRY(sc_map_open(s, fv == fk ? NULL : fv, fk, f, field_keys, &fm));
    /* region */
    static const char *const rkeys[] = {"min", "max", NULL};
    struct fy_node *rk, *rv = sc_get(&fm, "region", &rk);
    char fr[192];
    sc_field(fr, sizeof fr, &fm, "region");
    if (!rv) return sc_fail(s, FLOE_EPARSE, fm.at, "%s: region {min: [x, y], max: [x, y]} is required", f);
    sc_map rm;
    FLOE_TRY(sc_map_open(s, rv == rk ? NULL : rv, rk, fr, rkeys, &rm));
    double lo[3], hi[3];
    FLOE_TRY(sc_vec(s, &rm, "min", 1, NULL, lo));
    FLOE_TRY(sc_vec(s, &rm, "max", 1, NULL, hi));
    for (int a = 0; a < 2; a++)
        if (!(hi[a] > lo[a]))
            return sc_fail(s, FLOE_EINVAL, sc_get(&rm, "max", NULL), "%s: max must exceed min on x and y (axis %c: %g <= %g)",
                           fr, "xy"[a], hi[a], lo[a]);
    long count, lloyd, seed;
    double conc, h, dh;
    FLOE_TRY(sc_long(s, &fm, "count", 1, 0, &count));
    if (count < 1 || count > 10000000) return sc_range(s, &fm, "count", "in [1, 1e7]", (double)count);
    FLOE_TRY(sc_long(s, &fm, "lloyd", 0, 3, &lloyd));
    if (lloyd < 0 || lloyd > 1000) return sc_range(s, &fm, "lloyd", "in [0, 1000] (Lloyd iterations)", (double)lloyd);
    FLOE_TRY(sc_long(s, &fm, "seed", 0, 1, &seed));
    FLOE_TRY(sc_num(s, &fm, "concentration", 0, 1.0, &conc));
    if (!(conc > 0 && conc <= 1)) return sc_range(s, &fm, "concentration", "in (0, 1] (ice area fraction)", conc);
    FLOE_TRY(sc_num(s, &fm, "thickness", 1, 0, &h));
    if (!(h > 0)) return sc_range(s, &fm, "thickness", "> 0 (m)", h);
    FLOE_TRY(sc_num(s, &fm, "thickness_spread", 0, 0, &dh));
    if (!(dh >= 0 && dh < h))
        return sc_range(s, &fm, "thickness_spread", "in [0, thickness) (m: h is uniform in thickness +- spread)", dh);
    FLOE_TRY(sc_check_memory(s, fk, f, (double)count));
    /* material, velocity, motion */
    int mat, mo;
    double v[3];
    FLOE_TRY(sc_floe_entry(s, &m, entry, what, &mat, v, &mo));
    /* the tessellation */
    double *seeds = malloc((size_t)count * 2 * sizeof *seeds);
    if (!seeds) return sc_fail(s, FLOE_ENOMEM, fk, "out of memory");
    floe_voronoi vor;
    char err[512] = "";
    int rc = floe_voronoi_random_seeds(lo, hi, (int)count, (unsigned long long)seed, seeds);
    if (!rc) rc = floe_voronoi_rect(lo, hi, seeds, (int)count, (int)lloyd, &vor, err, sizeof err);
    free(seeds);
    if (rc) return sc_fail(s, rc, fk, "%s: the Voronoi tessellation failed: %s", f, err[0] ? err : "out of memory");
    if (conc < 1) rc = floe_voronoi_scale_cells(&vor, sqrt(conc));
    unsigned long long rng = (unsigned long long)seed ^ 0x9e3779b97f4a7c15ull; /* thicknesses: their own stream */
    for (int k = 0; k < vor.n && rc == FLOE_OK; k++) {
        int nv = vor.start[k + 1] - vor.start[k];
        floe_geometry *g = floe_polygon_create(vor.xy + 2 * vor.start[k], nv, err, sizeof err);
        if (!g) {
            rc = sc_fail(s, FLOE_EINVAL, fk, "%s: floe %d: %s", f, k, err);
            break;
        }
        const floe_polytope *pg = (const floe_polytope *)g;
        floe_particle_def d = floe_default_particle_def();
        floe_v3_copy(d.x, pg->frame_x);
        memcpy(d.q, pg->frame_q, sizeof d.q);
        int gi = floe_world_add_geometry(s->w, g);
        if (gi < 0) {
            rc = sc_fail(s, -gi, fk, "%s: floe %d: %s", f, k, floe_world_last_error(s->w));
            break;
        }
        d.geometry = gi;
        d.material = mat;
        floe_v3_copy(d.v, v);
        d.motion = (floe_motion)mo;
        d.group = entry;
        d.thickness = dh > 0 ? h + dh * (2 * floe_rng_uniform(&rng) - 1) : h;
        int r = floe_world_add_particle(s->w, &d);
        if (r < 0) {
            rc = sc_fail(s, -r, fk, "%s: floe %d: %s", f, k, floe_world_last_error(s->w));
            break;
        }
        s->mats[mat].nbody++;
        if (mo == FLOE_FREE) s->mats[mat].nfree = 1;
        s->nparticles++;
        s->nboxes++;
    }
    floe_voronoi_free(&vor);
    return rc;
}
