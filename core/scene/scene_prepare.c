/* scene_prepare.c - scene section `prepare` (docs/granular.md, "Preparation"): an isotropic
 * compaction of the sample in its box of walls to a target pressure or porosity, then
 * friction switched on, run by the loader before the outputs are added (the main run starts
 * from the prepared packing at t = 0, with a fresh energy ledger):
 *
 *   prepare:
 *     compact: {pressure: P} | {porosity: n}
 *     then: {friction: mu}          # optional: the particle laws' Coulomb coefficient
 *     max_time: T                   # s of preparation at most (an error when not reached)
 *     max_speed: v                  # wall speed at most, m/s (default 1e-3 mean radius / dt)
 *     tolerance: 0.01               # relative, on every wall's pressure / on the porosity
 *     hold: 500                     # steps in a row within the tolerance (pressure), or of
 *                                   # rest after the porosity is reached
 *
 * The controller only measures pressures and the box and sets wall targets or speeds
 * (floe_servo.h): a periodic cell's stress servo would replace the box walls by the cell's
 * strain rate behind the same two calls (prep_measure, prep_drive). */
#include "scene_read.h"
#include "floe_cell.h"

static FILE *prep_log_file;

void floe_scene_set_prepare_log(FILE *f) { prep_log_file = f; }

typedef struct prep {
    int porosity;          /* 1: target porosity, 0: target pressure */
    double target;         /* Pa (2D N/m) or porosity */
    int has_mu;
    double mu, max_time, max_speed, tol;
    long hold;
    int wall[3][2];        /* per axis: the wall with normal +e_a, -e_a */
    int added[3][2];       /* 1: made a servo wall for the preparation only */
    struct fy_node *at;
} prep;

/* the box of 2 x dim axis-aligned walls */
static int prep_box(sc *s, prep *pp)
{
    floe_world *w = s->w;
    for (int a = 0; a < 3; a++) pp->wall[a][0] = pp->wall[a][1] = -1;
    for (int i = 0; i < w->p.n; i++) {
        if (w->p.kind[i] != FLOE_GEOM_PLANE) continue;
        double n[3];
        const double ez[3] = {0, 0, 1};
        floe_q_rotate(n, w->p.q + 4 * (size_t)i, ez);
        for (int a = 0; a < s->dim; a++)
            if (fabs(fabs(n[a]) - 1) < 1e-9 && pp->wall[a][n[a] > 0 ? 0 : 1] < 0) pp->wall[a][n[a] > 0 ? 0 : 1] = i;
    }
    for (int a = 0; a < s->dim; a++)
        for (int k = 0; k < 2; k++)
            if (pp->wall[a][k] < 0)
                return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: the compaction needs a box of %d axis-aligned walls: "
                               "there is no wall with normal %c%c", 2 * s->dim, k ? '-' : '+', "xyz"[a]);
    return FLOE_OK;
}

/* box lengths and volume (2D: area) */
static double prep_volume(const sc *s, const prep *pp, double L[3])
{
    double V = 1;
    for (int a = 0; a < s->dim; a++) {
        L[a] = s->w->p.x[3 * (size_t)pp->wall[a][1] + a] - s->w->p.x[3 * (size_t)pp->wall[a][0] + a];
        V *= L[a];
    }
    return V;
}

/* the measure: the walls' smallest and largest pressure */
static void prep_measure(const sc *s, const prep *pp, double *pmin, double *pmax)
{
    *pmin = INFINITY;
    *pmax = -INFINITY;
    for (int a = 0; a < s->dim; a++)
        for (int k = 0; k < 2; k++) {
            double p = floe_world_wall_pressure(s->w, pp->wall[a][k]);
            *pmin = fmin(*pmin, p);
            *pmax = fmax(*pmax, p);
        }
}

/* the drive: porosity mode, every wall inward at v_max L_a / L_max, slowed over the last
 * 2 % of volumetric strain (speed 0 once the target volume is reached) */
static int prep_drive(sc *s, const prep *pp, double e, const double L[3])
{
    double lmax = 0;
    for (int a = 0; a < s->dim; a++) lmax = fmax(lmax, L[a]);
    double f = e <= 0 ? 0 : fmax(fmin(1.0, e / 0.02), 0.05);
    for (int a = 0; a < s->dim; a++)
        for (int k = 0; k < 2; k++)
            FLOE_TRY(floe_world_servo_set_speed(s->w, pp->wall[a][k], -pp->max_speed * f * L[a] / lmax));
    return FLOE_OK;
}

static int prep_parse(sc *s, struct fy_node *v, struct fy_node *k, prep *pp)
{
    static const char *const keys[] = {"compact", "then", "max_time", "max_speed", "tolerance", "hold", NULL};
    static const char *const ckeys[] = {"pressure", "porosity", NULL};
    static const char *const tkeys[] = {"friction", NULL};
    memset(pp, 0, sizeof *pp);
    pp->at = k;
    sc_map m, cm;
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, "prepare", keys, &m));
    struct fy_node *ck, *cv = sc_get(&m, "compact", &ck);
    if (!cv) return sc_fail(s, FLOE_EPARSE, k, "prepare.compact is required ({pressure: P} or {porosity: n})");
    FLOE_TRY(sc_map_open(s, cv == ck ? NULL : cv, ck, "prepare.compact", ckeys, &cm));
    if (sc_has(&cm, "pressure") == sc_has(&cm, "porosity"))
        return sc_fail(s, FLOE_EPARSE, cv, "prepare.compact: give either pressure (Pa; 2D N/m) or porosity");
    pp->porosity = sc_has(&cm, "porosity");
    if (pp->porosity) {
        FLOE_TRY(sc_num(s, &cm, "porosity", 1, 0, &pp->target));
        if (!(pp->target > 0 && pp->target < 1)) return sc_range(s, &cm, "porosity", "in (0, 1)", pp->target);
    } else FLOE_TRY(sc_pos_num(s, &cm, "pressure", &pp->target));
    struct fy_node *tk, *tv = sc_get(&m, "then", &tk);
    if (tv) {
        sc_map tm;
        FLOE_TRY(sc_map_open(s, tv == tk ? NULL : tv, tk, "prepare.then", tkeys, &tm));
        FLOE_TRY(sc_num(s, &tm, "friction", 1, 0, &pp->mu));
        if (!(pp->mu >= 0) || !isfinite(pp->mu)) return sc_range(s, &tm, "friction", ">= 0", pp->mu);
        pp->has_mu = 1;
    }
    FLOE_TRY(sc_pos_num(s, &m, "max_time", &pp->max_time));
    FLOE_TRY(sc_num(s, &m, "max_speed", 0, 0.0, &pp->max_speed));
    if (!(pp->max_speed >= 0) || !isfinite(pp->max_speed))
        return sc_range(s, &m, "max_speed", ">= 0 (m/s; 0: automatic)", pp->max_speed);
    FLOE_TRY(sc_num(s, &m, "tolerance", 0, 0.01, &pp->tol));
    if (!(pp->tol > 0 && pp->tol < 1)) return sc_range(s, &m, "tolerance", "in (0, 1)", pp->tol);
    FLOE_TRY(sc_long(s, &m, "hold", 0, 500, &pp->hold));
    if (pp->hold < 1 || pp->hold > 100000000L) return sc_range(s, &m, "hold", "in [1, 1e8] (steps)", (double)pp->hold);
    return FLOE_OK;
}

/* the box's walls under control: a servo wall of the scene keeps its definition (restored
 * after), another wall becomes one for the preparation and is held still after */
static int prep_servo(sc *s, prep *pp)
{
    for (int a = 0; a < s->dim; a++)
        for (int k = 0; k < 2; k++) {
            int i = pp->wall[a][k];
            if (floe_world_is_servo_wall(s->w, i)) continue;
            floe_servo_def d = floe_default_servo_def();
            d.pressure = pp->porosity ? 1.0 : pp->target;
            d.max_speed = pp->max_speed;
            int rc = floe_world_add_servo_wall(s->w, i, &d);
            if (rc) return sc_fail(s, rc, pp->at, "prepare: %s", floe_world_last_error(s->w));
            pp->added[a][k] = 1;
        }
    return FLOE_OK;
}

static int prep_step(sc *s, const prep *pp)
{
    int rc = floe_world_step(s->w);
    if (rc)
        return sc_fail(s, rc, pp->at, "prepare: step %ld (t = %g s) failed: %s", floe_world_step_count(s->w),
                       floe_world_time(s->w), floe_world_last_error(s->w));
    return FLOE_OK;
}

static int prep_run(sc *s, prep *pp, char *done, size_t donelen)
{
    floe_world *w = s->w;
    double L[3];
    const double vs = floe_world_solid_volume(s->w);
    if (!(vs > 0)) return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: there are no free particles to compact");
    double V = prep_volume(s, pp, L);
    if (!(V > 0)) return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: the box's walls enclose no volume (%g)", V);
    if (pp->max_speed <= 0) {
        double rs = 0;
        int nf = 0;
        for (int i = 0; i < w->p.n; i++)
            if (w->p.motion[i] == FLOE_FREE) { rs += w->p.radius[i]; nf++; }
        pp->max_speed = 1e-3 * (rs / nf) / w->dt;
    }
    const long every = 1000;
    double pmin = 0, pmax = 0;
    if (!pp->porosity) {
        for (int a = 0; a < s->dim; a++)
            for (int k = 0; k < 2; k++) FLOE_TRY(floe_world_servo_set_pressure(w, pp->wall[a][k], pp->target));
        long in = 0;
        while (in < pp->hold) {
            if (w->time >= pp->max_time) {
                V = prep_volume(s, pp, L);
                return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: the pressure %g was not reached within max_time %g s "
                               "(%ld steps): the walls' pressures are %.4g to %.4g (%.3g %% off at most), the "
                               "porosity %.4f", pp->target, pp->max_time, floe_world_step_count(w), pmin + 0.0, pmax + 0.0,
                               100 * fmax(fabs(pmin - pp->target), fabs(pmax - pp->target)) / pp->target, 1 - vs / V);
            }
            FLOE_TRY(prep_step(s, pp));
            prep_measure(s, pp, &pmin, &pmax);
            int ok = fabs(pmin - pp->target) <= pp->tol * pp->target && fabs(pmax - pp->target) <= pp->tol * pp->target;
            in = ok ? in + 1 : 0;
            if (prep_log_file && floe_world_step_count(w) % every == 0)
                fprintf(prep_log_file, "prepare: step %ld t %.4g s pressure %.4g..%.4g (target %g) porosity %.4f\n",
                        floe_world_step_count(w), w->time, pmin, pmax, pp->target, 1 - vs / prep_volume(s, pp, L));
        }
    } else {
        const double vt = vs / (1 - pp->target);
        for (;;) {
            V = prep_volume(s, pp, L);
            double e = log(V / vt);
            FLOE_TRY(prep_drive(s, pp, e, L));
            if (e <= 0) break;
            if (w->time >= pp->max_time)
                return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: the porosity %g was not reached within max_time %g s "
                               "(%ld steps): it is %.4f (box volume %.4g, target %.4g)", pp->target, pp->max_time,
                               floe_world_step_count(w), 1 - vs / V, V, vt);
            FLOE_TRY(prep_step(s, pp));
            if (prep_log_file && floe_world_step_count(w) % every == 0) {
                prep_measure(s, pp, &pmin, &pmax);
                fprintf(prep_log_file, "prepare: step %ld t %.4g s porosity %.4f (target %g) pressure %.4g..%.4g\n",
                        floe_world_step_count(w), w->time, 1 - vs / V, pp->target, pmin, pmax);
            }
        }
        /* at rest in the fixed box for hold steps */
        for (long k = 0; k < pp->hold; k++) FLOE_TRY(prep_step(s, pp));
        prep_measure(s, pp, &pmin, &pmax);
    }
    V = prep_volume(s, pp, L);
    double n = 1 - vs / V;
    if (pp->porosity && fabs(n - pp->target) > pp->tol * pp->target)
        return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: the porosity reached %.5f is off the target %g by more than "
                       "the tolerance", n, pp->target);
    snprintf(done, donelen, "prepared: %s in %ld steps (%.4g s): porosity %.4f, wall pressures %.4g to %.4g%s",
             pp->porosity ? "compacted to the porosity" : "compacted to the pressure", floe_world_step_count(w),
             w->time, n, pmin, pmax, pp->has_mu ? ", then friction switched on" : "");
    return FLOE_OK;
}

/* A periodic cell (floe_cell.h): the same two targets through the cell's control instead
 * of walls. Pressure: every normal stress held at -P by the cell's servo (its max_rate the
 * scene's, else max_speed / the cell's smallest width), off-diagonal rates 0, until the
 * three (2D: two) normal stresses are within the tolerance for `hold` steps in a row.
 * Porosity: every axis at the same inward rate (slowed over the last 2 % of volumetric
 * strain) until the cell's volume gives the porosity, then `hold` steps with the cell fixed.
 * The scene's own control is put back after. */
static int prep_cell_measure(const sc *s, double *pmin, double *pmax)
{
    double sig[9];
    *pmin = INFINITY;
    *pmax = -INFINITY;
    if (floe_world_cell_stress(s->w, sig, NULL) != FLOE_OK) { *pmin = *pmax = 0; return FLOE_OK; }
    for (int a = 0; a < s->dim; a++) {
        *pmin = fmin(*pmin, -sig[4 * a]);
        *pmax = fmax(*pmax, -sig[4 * a]);
    }
    return FLOE_OK;
}

static int prep_run_cell(sc *s, prep *pp, char *done, size_t donelen)
{
    floe_world *w = s->w;
    floe_cell_control keep, c = floe_default_cell_control();
    floe_world_cell_get_control(w, &keep);
    const double vs = floe_world_solid_volume(s->w);
    if (!(vs > 0)) return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: there are no free particles to compact");
    double wd[3];
    floe_world_cell_widths(w, wd);
    const double wmin = fmin(wd[0], fmin(wd[1], wd[2]));
    if (pp->max_speed <= 0) {
        double rs = 0;
        int nf = 0;
        for (int i = 0; i < w->p.n; i++)
            if (w->p.motion[i] == FLOE_FREE) { rs += w->p.radius[i]; nf++; }
        pp->max_speed = 1e-3 * (rs / nf) / w->dt;
    }
    const double rate = keep.max_rate > 0 ? keep.max_rate : pp->max_speed / wmin;
    double pmin = 0, pmax = 0, V;
    if (!pp->porosity) {
        for (int a = 0; a < s->dim; a++) {
            c.mode[4 * a] = FLOE_CELL_STRESS;
            c.stress[4 * a] = -pp->target;
        }
        c.max_rate = rate;
        c.servo_time = keep.servo_time;
        if (floe_world_cell_set_control(w, &c)) return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: %s", floe_world_last_error(w));
        long in = 0;
        while (in < pp->hold) {
            if (w->time >= pp->max_time)
                return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: the pressure %g was not reached within max_time %g s "
                               "(%ld steps): the cell's normal stresses are -%.4g to -%.4g, the porosity %.4f",
                               pp->target, pp->max_time, floe_world_step_count(w), pmin, pmax,
                               1 - vs / floe_world_cell_volume(w));
            FLOE_TRY(prep_step(s, pp));
            prep_cell_measure(s, &pmin, &pmax);
            int ok = fabs(pmin - pp->target) <= pp->tol * pp->target && fabs(pmax - pp->target) <= pp->tol * pp->target;
            in = ok ? in + 1 : 0;
        }
    } else {
        const double vt = vs / (1 - pp->target);
        for (;;) {
            V = floe_world_cell_volume(w);
            double e = log(V / vt);
            if (e <= 0) break;
            if (w->time >= pp->max_time)
                return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: the porosity %g was not reached within max_time %g s "
                               "(%ld steps): it is %.4f", pp->target, pp->max_time, floe_world_step_count(w), 1 - vs / V);
            double f = fmax(fmin(1.0, e / 0.02), 0.05);
            /* the step at this rate would pass the target: only what is left of the strain */
            double r = fmin(rate * f, e / (s->dim * w->dt));
            for (int a = 0; a < s->dim; a++) c.rate[4 * a] = -r;
            if (floe_world_cell_set_control(w, &c)) return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: %s", floe_world_last_error(w));
            FLOE_TRY(prep_step(s, pp));
        }
        floe_cell_control fixed = floe_default_cell_control();
        floe_world_cell_set_control(w, &fixed);
        for (long k = 0; k < pp->hold; k++) FLOE_TRY(prep_step(s, pp));
        prep_cell_measure(s, &pmin, &pmax);
    }
    V = floe_world_cell_volume(w);
    double n = 1 - vs / V;
    if (pp->porosity && fabs(n - pp->target) > pp->tol * pp->target)
        return sc_fail(s, FLOE_EINVAL, pp->at, "prepare: the porosity reached %.5f is off the target %g by more than "
                       "the tolerance", n, pp->target);
    floe_world_cell_set_control(w, &keep);
    snprintf(done, donelen, "prepared: %s in the periodic cell in %ld steps (%.4g s): porosity %.4f, normal stresses "
             "-%.4g to -%.4g Pa%s", pp->porosity ? "compacted to the porosity" : "compacted to the pressure",
             floe_world_step_count(w), w->time, n, pmin, pmax, pp->has_mu ? ", then friction switched on" : "");
    return FLOE_OK;
}

/* friction on: the laws between the materials of free particles */
static int prep_friction(sc *s, const prep *pp)
{
    floe_world *w = s->w;
    int nm = w->nmats;
    unsigned char *used = calloc((size_t)(nm ? nm : 1), 1);
    if (!used) return sc_fail(s, FLOE_ENOMEM, pp->at, "out of memory");
    for (int i = 0; i < w->p.n; i++)
        if (w->p.motion[i] == FLOE_FREE) used[w->p.material[i]] = 1;
    int rc = FLOE_OK;
    for (int a = 0; a < nm && !rc; a++)
        for (int b = a; b < nm && !rc; b++)
            if (used[a] && used[b] && w->laws[a * nm + b] && !floe_contact_law_no_contact(w->laws[a * nm + b])) {
                rc = floe_world_set_law_friction(w, a, b, pp->mu);
                if (rc) rc = sc_fail(s, rc, pp->at, "prepare.then.friction: %s", floe_world_last_error(w));
            }
    free(used);
    return rc;
}

int sc_parse_prepare(sc *s, struct fy_node *v, struct fy_node *k, int run, char *done, size_t donelen)
{
    prep pp;
    done[0] = 0;
    FLOE_TRY(prep_parse(s, v, k, &pp));
    if (floe_world_cell(s->w, NULL, NULL)) { /* a periodic cell: its control, no walls */
        if (!run) return FLOE_OK;
        int rc = floe_world_prepare(s->w);
        if (rc) return sc_fail(s, rc, pp.at, "prepare: %s", floe_world_last_error(s->w));
        FLOE_TRY(prep_run_cell(s, &pp, done, donelen));
        if (pp.has_mu) FLOE_TRY(prep_friction(s, &pp));
        s->w->time = 0;
        s->w->step = 0;
        s->w->prepared = 0;
        if (prep_log_file) fprintf(prep_log_file, "%s\n", done);
        return FLOE_OK;
    }
    FLOE_TRY(prep_box(s, &pp));
    FLOE_TRY(prep_servo(s, &pp));
    if (!run) return FLOE_OK;
    int rc = floe_world_prepare(s->w);
    if (rc) return sc_fail(s, rc, pp.at, "prepare: %s", floe_world_last_error(s->w));
    FLOE_TRY(prep_run(s, &pp, done, donelen));
    if (pp.has_mu) FLOE_TRY(prep_friction(s, &pp));
    for (int a = 0; a < s->dim; a++)
        for (int j = 0; j < 2; j++) {
            int i = pp.wall[a][j];
            rc = pp.added[a][j] ? floe_world_servo_set_speed(s->w, i, 0.0) : floe_world_servo_reset(s->w, i);
            if (rc) return sc_fail(s, rc, pp.at, "prepare: %s", floe_world_last_error(s->w));
        }
    /* the main run starts here: its clock at 0, its energy ledger from this state (a world
     * re-prepared at step 0 restarts the ledger) */
    s->w->time = 0;
    s->w->step = 0;
    s->w->prepared = 0;
    if (prep_log_file) fprintf(prep_log_file, "%s\n", done);
    return FLOE_OK;
}
