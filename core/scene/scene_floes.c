/* scene_floes.c - a body entry `{floe_field: {...}, material, ...}`: a field of 2D
 * polygon floes from a Voronoi tessellation of a rectangle (geometry/voronoi.c), Lloyd-
 * relaxed, at a target ice concentration, with a thickness per floe (docs/sea-ice.md,
 * "Floe fields"). Each cell becomes one floe: its own convex polygon, placed where the
 * cell is (the polygon's centroid and principal axes), thickness h (+- a uniform spread).
 *
 * With `size_distribution` (a truncated power law N(>D) ~ D^-alpha on [min, max], or a
 * table of diameters and number fractions) the floes' diameters D = 2 sqrt(A / pi) are
 * drawn from it until their area reaches concentration x region, and the cells are power
 * cells of those areas / concentration (floe_voronoi_areas), Lloyd-relaxed the same way
 * (docs/sea-ice.md, "Floe size distributions"). */
#include "scene_read.h"
#include "floe_voronoi.h"
#include "floe_rng.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static const char *const field_keys[] = {"region", "count", "lloyd", "concentration", "seed", "thickness",
                                         "thickness_spread", "size_distribution", NULL};

/* relative tolerance of the cells' areas against the drawn floes' (floe_voronoi_areas) */
#define FSD_AREA_TOL 1e-6
#define FSD_MAX_FLOES 10000000

/* a floe size distribution: a truncated Pareto law of the diameters, number density
 * N(>D) ~ D^-alpha on [dmin, dmax] (Rothrock & Thorndike 1984; Stern et al. 2018), or a
 * given discrete one (ng diameters gd with number fractions gf) */
typedef struct fsd {
    int given;
    double alpha, dmin, dmax;
    int ng;
    double *gd, *gf;
} fsd;

/* the `given: [[D, fraction], ...]` table: diameters > 0 increasing, fractions >= 0
 * summing to 1 (1e-6) */
static int fsd_given(sc *s, const sc_map *dm, fsd *d) {
    struct fy_node *k, *v = sc_get(dm, "given", &k);
    char fg[224];
    sc_field(fg, sizeof fg, dm, "given");
    if (!v || v == k || !fy_node_is_sequence(v) || fy_node_sequence_item_count(v) < 1)
        return sc_fail(s, FLOE_EPARSE, v && v != k ? v : k, "%s must be a list of [diameter, number fraction] pairs", fg);
    int n = fy_node_sequence_item_count(v);
    d->gd = malloc(2 * (size_t)n * sizeof *d->gd);
    if (!d->gd) return sc_fail(s, FLOE_ENOMEM, v, "out of memory");
    d->gf = d->gd + n;
    d->ng = n;
    double sum = 0;
    for (int i = 0; i < n; i++) {
        char fi[240];
        snprintf(fi, sizeof fi, "%s[%d]", fg, i);
        struct fy_node *e = fy_node_sequence_get_by_index(v, i);
        double pair[2];
        int got;
        FLOE_TRY(sc_node_list(s, e, NULL, fi, 2, 0, pair, &got));
        if (!(pair[0] > 0 && isfinite(pair[0])))
            return sc_fail(s, FLOE_EINVAL, e, "%s: the diameter must be > 0 (m) (got %g)", fi, pair[0]);
        if (i > 0 && !(pair[0] > d->gd[i - 1]))
            return sc_fail(s, FLOE_EINVAL, e, "%s: the diameters must increase (%g after %g)", fi, pair[0], d->gd[i - 1]);
        if (!(pair[1] >= 0 && pair[1] <= 1))
            return sc_fail(s, FLOE_EINVAL, e, "%s: the number fraction must be in [0, 1] (got %g)", fi, pair[1]);
        d->gd[i] = pair[0];
        d->gf[i] = pair[1];
        sum += pair[1];
    }
    if (fabs(sum - 1) > 1e-6)
        return sc_fail(s, FLOE_EINVAL, v, "%s: the number fractions sum to %.9g, not 1 (within 1e-6)", fg, sum);
    d->dmin = d->gd[0];
    d->dmax = d->gd[n - 1];
    return FLOE_OK;
}

/* `size_distribution: {power_law: alpha, min: D, max: D}` or `{given: [[D, f], ...]}` */
static int fsd_read(sc *s, const sc_map *fm, fsd *d) {
    static const char *const keys[] = {"power_law", "min", "max", "given", NULL};
    struct fy_node *k, *v = sc_get(fm, "size_distribution", &k);
    char f[192];
    sc_field(f, sizeof f, fm, "size_distribution");
    sc_map dm;
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, f, keys, &dm));
    int pl = sc_has(&dm, "power_law"), gv = sc_has(&dm, "given");
    if (pl == gv)
        return sc_fail(s, FLOE_EINVAL, dm.at, "%s: give either power_law (with min and max) or given", f);
    if (gv) {
        if (sc_has(&dm, "min") || sc_has(&dm, "max"))
            return sc_fail(s, FLOE_EINVAL, sc_get(&dm, sc_has(&dm, "min") ? "min" : "max", NULL),
                           "%s: min and max belong to power_law (a given table sets its own diameters)", f);
        d->given = 1;
        return fsd_given(s, &dm, d);
    }
    FLOE_TRY(sc_num(s, &dm, "power_law", 1, 0, &d->alpha));
    if (!(d->alpha > 0 && d->alpha <= 20))
        return sc_range(s, &dm, "power_law", "in (0, 20] (the exponent alpha of N(>D) ~ D^-alpha)", d->alpha);
    FLOE_TRY(sc_num(s, &dm, "min", 1, 0, &d->dmin));
    if (!(d->dmin > 0)) return sc_range(s, &dm, "min", "> 0 (m: the smallest floe diameter)", d->dmin);
    FLOE_TRY(sc_num(s, &dm, "max", 1, 0, &d->dmax));
    if (!(d->dmax > d->dmin && isfinite(d->dmax)))
        return sc_fail(s, FLOE_EINVAL, sc_get(&dm, "max", NULL), "%s.max must exceed min (got max %g <= min %g)", f, d->dmax,
                       d->dmin);
    return FLOE_OK;
}

/* one diameter: the inverse of the truncated Pareto law's distribution function
 * F(D) = (1 - (dmin/D)^alpha) / (1 - (dmin/dmax)^alpha), or a draw from the table */
static double fsd_draw(const fsd *d, unsigned long long *rng) {
    double u = floe_rng_uniform(rng);
    if (d->given) {
        double c = 0;
        for (int i = 0; i < d->ng; i++)
            if (u < (c += d->gf[i])) return d->gd[i];
        return d->gd[d->ng - 1];
    }
    double q = pow(d->dmin / d->dmax, d->alpha);
    return fmin(d->dmax, d->dmin * pow(1 - u * (1 - q), -1 / d->alpha));
}

/* the mean floe area E[pi D^2 / 4] */
static double fsd_mean_area(const fsd *d) {
    double m2 = 0;
    if (d->given) {
        for (int i = 0; i < d->ng; i++) m2 += d->gf[i] * d->gd[i] * d->gd[i];
    } else {
        double a = d->alpha, q = pow(d->dmin / d->dmax, a), c = a * pow(d->dmin, a) / (1 - q);
        m2 = fabs(a - 2) < 1e-9 ? c * log(d->dmax / d->dmin)
                                : c * (pow(d->dmax, 2 - a) - pow(d->dmin, 2 - a)) / (2 - a);
    }
    return 0.25 * M_PI * m2;
}

/* the floes' areas (*n of them, malloc'd into *areas): diameters drawn until their area is
 * nearest to ice = concentration x region (the last draw kept or not, whichever is
 * nearer), then all scaled by the same factor to sum to ice exactly */
static int fsd_areas(sc *s, struct fy_node *at, const char *f, const fsd *d, double ice, unsigned long long seed,
                     double **areas, int *n) {
    double expect = ice / fsd_mean_area(d);
    if (expect > FSD_MAX_FLOES)
        return sc_fail(s, FLOE_EINVAL, at, "%s.size_distribution: about %.3g floes fill the region (more than 1e7): "
                       "raise the smallest diameter or shrink the region", f, expect);
    FLOE_TRY(sc_check_memory(s, at, f, expect));
    size_t cap = (size_t)(1.2 * expect) + 16;
    double *a = malloc(cap * sizeof *a), sum = 0;
    if (!a) return sc_fail(s, FLOE_ENOMEM, at, "out of memory");
    int m = 0;
    unsigned long long rng = seed ^ 0x5851f42d4c957f2dull; /* diameters: their own stream */
    while (sum < ice) {
        if (m == FSD_MAX_FLOES) {
            free(a);
            return sc_fail(s, FLOE_EINVAL, at, "%s.size_distribution: more than 1e7 floes", f);
        }
        if ((size_t)m == cap) {
            double *b = realloc(a, (cap *= 2) * sizeof *a);
            if (!b) {
                free(a);
                return sc_fail(s, FLOE_ENOMEM, at, "out of memory");
            }
            a = b;
        }
        double D = fsd_draw(d, &rng);
        a[m++] = 0.25 * M_PI * D * D;
        sum += a[m - 1];
    }
    if (m > 1 && sum - ice > ice - (sum - a[m - 1])) sum -= a[--m];
    for (int k = 0; k < m; k++) a[k] *= ice / sum;
    *areas = a;
    *n = m;
    return FLOE_OK;
}

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
    long count = 0, lloyd, seed;
    double conc, h, dh;
    fsd dist = {0};
    int with_fsd = sc_has(&fm, "size_distribution");
    if (with_fsd && sc_has(&fm, "count"))
        return sc_fail(s, FLOE_EINVAL, sc_get(&fm, "count", NULL),
                       "%s: count and size_distribution exclude each other (the distribution, the region and the "
                       "concentration set the number of floes)", f);
    if (!with_fsd) {
        FLOE_TRY(sc_long(s, &fm, "count", 1, 0, &count));
        if (count < 1 || count > 10000000) return sc_range(s, &fm, "count", "in [1, 1e7]", (double)count);
    }
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
    double *areas = NULL;
    if (with_fsd) {
        int rc = fsd_read(s, &fm, &dist);
        double side = fmin(hi[0] - lo[0], hi[1] - lo[1]);
        if (rc == FLOE_OK && dist.dmax > sqrt(conc) * side)
            rc = sc_fail(s, FLOE_EINVAL, sc_get(&fm, "size_distribution", NULL),
                         "%s.size_distribution: the largest floe (%g m) must fit, with its share of open water, in the "
                         "region: at most sqrt(concentration) x the region's shorter side = %g m", f, dist.dmax, sqrt(conc) * side);
        int nf = 0;
        if (rc == FLOE_OK)
            rc = fsd_areas(s, sc_get(&fm, "size_distribution", NULL), f, &dist, conc * (hi[0] - lo[0]) * (hi[1] - lo[1]),
                           (unsigned long long)seed, &areas, &nf);
        free(dist.gd);
        if (rc) return rc;
        count = nf;
    }
    int rc = sc_check_memory(s, fk, f, (double)count);
    /* material, velocity, motion */
    int mat, mo;
    double v[3];
    if (rc == FLOE_OK) rc = sc_floe_entry(s, &m, entry, what, &mat, v, &mo);
    /* the tessellation */
    double *seeds = rc ? NULL : malloc((size_t)count * 2 * sizeof *seeds);
    if (!rc && !seeds) rc = sc_fail(s, FLOE_ENOMEM, fk, "out of memory");
    if (rc) {
        free(areas);
        return rc;
    }
    floe_voronoi vor;
    char err[512] = "";
    rc = floe_voronoi_random_seeds(lo, hi, (int)count, (unsigned long long)seed, seeds);
    if (!rc && areas) rc = floe_voronoi_areas(lo, hi, seeds, areas, (int)count, (int)lloyd, FSD_AREA_TOL, &vor, err, sizeof err);
    else if (!rc) rc = floe_voronoi_rect(lo, hi, seeds, (int)count, (int)lloyd, &vor, err, sizeof err);
    free(seeds);
    free(areas);
    if (rc) return sc_fail(s, rc, fk, "%s: the %s tessellation failed: %s", f, with_fsd ? "power" : "Voronoi",
                           err[0] ? err : "out of memory");
    if (conc < 1) rc = floe_voronoi_scale_cells(&vor, sqrt(conc));
    /* the floes in Morton order of their centroids: neighbours get nearby indices, so that a
     * contact's two floes (and their polygons) sit near each other in memory (the random
     * seeds' order made every neighbour pair a cache miss: 10,000 floes stepped 1.4x
     * slower with contacts) */
    long *ord = rc ? NULL : malloc((size_t)(vor.n > 0 ? vor.n : 1) * sizeof *ord);
    if (!rc && (!ord || sc_morton_order(vor.centroid, vor.n, 2, 2, lo, hi, ord))) {
        free(ord);
        floe_voronoi_free(&vor);
        return sc_fail(s, FLOE_ENOMEM, fk, "%s: out of memory", f);
    }
    unsigned long long rng = (unsigned long long)seed ^ 0x9e3779b97f4a7c15ull; /* thicknesses: their own stream */
    for (int kk = 0; kk < vor.n && rc == FLOE_OK; kk++) {
        const int k = (int)ord[kk];
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
        if (gi < 0) { /* not taken: still ours */
            floe_geometry_destroy(g);
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
    free(ord);
    floe_voronoi_free(&vor);
    return rc;
}
