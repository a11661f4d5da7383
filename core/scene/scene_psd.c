/* scene_psd.c - radius distributions of sphere (2D: disc) packings (docs/granular.md,
 * "Radius distributions"): a packing entry's `radius_distribution` replaces its shape; each
 * particle gets a radius drawn from
 *   {uniform: [rmin, rmax]}                     uniform in r, by number;
 *   {lognormal: {median | mean, sigma, min, max}}   ln r normal with standard deviation
 *                                               sigma, truncated to [min, max] by rejection
 *                                               (mean: the untruncated mean, median =
 *                                               mean exp(-sigma^2 / 2)); by number;
 *   {given: [[r, fraction], ...], by: volume | number}   discrete radii; the fractions (any
 *                                               positive weights, normalised) are of the
 *                                               solid volume (mass for one material: a
 *                                               sieve curve, the default) or of the count;
 * with `seed` (its own stream, 1 by default). The radii come back sorted largest first (the
 * random packing places them in that order). */
#include "scene_read.h"

enum { PSD_UNIFORM = 0, PSD_LOGNORMAL = 1, PSD_GIVEN = 2 };

static int psd_cmp_desc(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? 1 : x > y ? -1 : 0;
}

static int psd_uniform(sc *s, struct fy_node *v, struct fy_node *k, const char *f, sc_psd *d)
{
    double r[2];
    int got;
    FLOE_TRY(sc_node_list(s, v, k, f, 2, 0, r, &got));
    if (!(r[0] > 0) || !(r[1] >= r[0]) || !isfinite(r[1]))
        return sc_fail(s, FLOE_EINVAL, v, "%s: [rmin, rmax] must have 0 < rmin <= rmax (got [%g, %g])", f, r[0],
                       r[1]);
    d->lo = r[0];
    d->hi = r[1];
    return FLOE_OK;
}

static int psd_lognormal(sc *s, struct fy_node *v, struct fy_node *k, const char *f, sc_psd *d)
{
    static const char *const keys[] = {"median", "mean", "sigma", "min", "max", NULL};
    sc_map m;
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, f, keys, &m));
    int has_med = sc_has(&m, "median"), has_mean = sc_has(&m, "mean");
    if (has_med == has_mean)
        return sc_fail(s, FLOE_EPARSE, has_mean ? sc_get(&m, "mean", NULL) : m.at,
                       "%s: give either median or mean (m)", f);
    double c, sigma;
    FLOE_TRY(sc_num(s, &m, has_med ? "median" : "mean", 1, 0, &c));
    if (!(c > 0) || !isfinite(c)) return sc_range(s, &m, has_med ? "median" : "mean", "> 0 (m)", c);
    FLOE_TRY(sc_num(s, &m, "sigma", 1, 0, &sigma));
    if (!(sigma >= 0) || !(sigma <= 5)) return sc_range(s, &m, "sigma", "in [0, 5] (of ln r)", sigma);
    FLOE_TRY(sc_num(s, &m, "min", 0, 0.0, &d->lo));
    FLOE_TRY(sc_num(s, &m, "max", 0, INFINITY, &d->hi));
    if (!(d->lo >= 0)) return sc_range(s, &m, "min", ">= 0 (m)", d->lo);
    if (!(d->hi > d->lo)) return sc_range(s, &m, "max", "> min (m)", d->hi);
    d->mu = log(c) - (has_mean ? 0.5 * sigma * sigma : 0.0);
    d->sigma = sigma;
    /* rejection must accept often enough: the probability of [min, max] under the normal
     * of ln r (min = 0: the lower tail is all in) */
    double zl = d->lo > 0 ? (log(d->lo) - d->mu) : -INFINITY, zh = isfinite(d->hi) ? log(d->hi) - d->mu : INFINITY;
    double pin = sigma > 0 ? 0.5 * (erfc(-zh / (sigma * sqrt(2.0))) - erfc(-zl / (sigma * sqrt(2.0))))
                           : (zl <= 0 && zh >= 0 ? 1.0 : 0.0);
    if (!(pin >= 1e-3))
        return sc_fail(s, FLOE_EINVAL, m.at, "%s: [min, max] = [%g, %g] holds only %.2g of the distribution "
                       "(median %g, sigma %g): widen it", f, d->lo, d->hi, pin, exp(d->mu), sigma);
    return FLOE_OK;
}

static int psd_given(sc *s, struct fy_node *v, struct fy_node *k, const char *f, int by_volume, int dim, sc_psd *d)
{
    if (!v || v == k || !fy_node_is_sequence(v) || fy_node_sequence_item_count(v) < 1)
        return sc_fail(s, FLOE_EPARSE, v && v != k ? v : k, "%s must be a list of [radius, fraction] pairs", f);
    int n = fy_node_sequence_item_count(v);
    if (n > SC_PSD_MAX_GIVEN) return sc_fail(s, FLOE_EINVAL, v, "%s: %d radii (at most %d)", f, n, SC_PSD_MAX_GIVEN);
    double total = 0;
    for (int i = 0; i < n; i++) {
        char f2[192];
        snprintf(f2, sizeof f2, "%s[%d]", f, i);
        struct fy_node *e = fy_node_sequence_get_by_index(v, i);
        double rf[2];
        int got;
        FLOE_TRY(sc_node_list(s, e, NULL, f2, 2, 0, rf, &got));
        if (!(rf[0] > 0) || !isfinite(rf[0]))
            return sc_fail(s, FLOE_EINVAL, e, "%s: the radius must be > 0 (got %g)", f2, rf[0]);
        if (!(rf[1] >= 0) || !isfinite(rf[1]))
            return sc_fail(s, FLOE_EINVAL, e, "%s: the fraction must be >= 0 (got %g)", f2, rf[1]);
        for (int j = 0; j < i; j++)
            if (d->r[j] == rf[0]) return sc_fail(s, FLOE_EINVAL, e, "%s: radius %g is listed twice", f2, rf[0]);
        d->r[i] = rf[0];
        /* the probability of drawing radius r: its count fraction; a volume fraction f
         * means f / r^dim in number */
        d->p[i] = by_volume ? rf[1] / pow(rf[0], dim) : rf[1];
        total += d->p[i];
    }
    if (!(total > 0)) return sc_fail(s, FLOE_EINVAL, v, "%s: the fractions sum to 0", f);
    for (int i = 0; i < n; i++) d->p[i] /= total;
    d->ngiven = n;
    return FLOE_OK;
}

int sc_parse_psd(sc *s, const sc_map *body, sc_psd *d)
{
    static const char *const keys[] = {"uniform", "lognormal", "given", "by", "seed", NULL};
    static const char *const kinds[] = {"uniform", "lognormal", "given", NULL};
    static const char *const bys[] = {"volume", "number", NULL};
    memset(d, 0, sizeof *d);
    struct fy_node *k, *v = sc_get(body, "radius_distribution", &k);
    char f[160];
    sc_field(f, sizeof f, body, "radius_distribution");
    sc_map m;
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, f, keys, &m));
    int kind = -1, nk = 0;
    for (int q = 0; kinds[q]; q++)
        if (sc_has(&m, kinds[q])) { kind = q; nk++; }
    if (nk != 1)
        return sc_fail(s, FLOE_EPARSE, v, "%s: give exactly one of uniform: [rmin, rmax], lognormal: {median, "
                       "sigma, min, max} or given: [[r, fraction], ...]", f);
    d->kind = kind;
    long seed;
    FLOE_TRY(sc_long(s, &m, "seed", 0, 1, &seed));
    d->seed = (unsigned long long)seed;
    if (sc_has(&m, "by") && kind != PSD_GIVEN)
        return sc_fail(s, FLOE_EPARSE, sc_get(&m, "by", NULL), "%s.by is for given radii (uniform and lognormal "
                       "draw by number)", f);
    int by;
    FLOE_TRY(sc_enum(s, &m, "by", bys, 0, &by));
    struct fy_node *kk, *kv = sc_get(&m, kinds[kind], &kk);
    char f2[192];
    snprintf(f2, sizeof f2, "%s.%s", f, kinds[kind]);
    if (kind == PSD_UNIFORM) return psd_uniform(s, kv, kk, f2, d);
    if (kind == PSD_LOGNORMAL) return psd_lognormal(s, kv, kk, f2, d);
    return psd_given(s, kv, kk, f2, by == 0, s->dim, d);
}

static double psd_one(const sc_psd *d, unsigned long long *rng)
{
    if (d->kind == PSD_UNIFORM) return d->lo + (d->hi - d->lo) * floe_rng_uniform(rng);
    if (d->kind == PSD_LOGNORMAL) {
        for (;;) { /* truncated by rejection (accepts >= 1e-3 of the draws: sc_parse_psd) */
            double r = exp(d->mu + d->sigma * floe_rng_normal(rng));
            if (r >= d->lo && r <= d->hi && r > 0) return r;
        }
    }
    double u = floe_rng_uniform(rng), c = 0;
    for (int i = 0; i < d->ngiven; i++) {
        c += d->p[i];
        if (u < c) return d->r[i];
    }
    for (int i = d->ngiven - 1; i >= 0; i--) /* rounding left u above the last sum */
        if (d->p[i] > 0) return d->r[i];
    return d->r[0];
}

int sc_psd_draw(const sc_psd *d, long n, double *r)
{
    unsigned long long rng = d->seed;
    for (long i = 0; i < n; i++) r[i] = psd_one(d, &rng);
    qsort(r, (size_t)n, sizeof *r, psd_cmp_desc);
    return FLOE_OK;
}
