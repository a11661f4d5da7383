/* servo_walls.c - servo walls (floe_servo.h, docs/granular.md "Servo walls"): a plane wall
 * becomes a kinematic particle whose motion callback is a velocity servo on the pressure
 * the particles put on it. The controllers live in one force provider ("servo_walls",
 * owned by the world) that adds no force: its evaluation at prepare resolves the automatic
 * areas and gains and reports a wall set that is not a box. The wall's work on the particles
 * is the integrator's boundary work (core/integrators/step.c kinematic_close), so the
 * energy ledger closes with the servo as with any moving wall.
 *
 * A periodic cell's stress servo would use the same two measures (pressure, set a rate):
 * the cell's strain rate in place of the walls' speeds. */
#include "world_parts.h"
#include "floe_servo.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct servo_wall {
    floe_world *w;
    int wall;
    floe_servo_def def;       /* as given */
    double pressure;          /* the target in use */
    int speed_mode;           /* 1: move at speed (m/s, outwards > 0) */
    double speed;
    double n[3];              /* the wall's normal into the domain */
    int box[4];               /* area auto: the walls of the other axes (-e_b, +e_b pairs) */
    int nbox;
    double delta_star;        /* the law's overlap at the contact force P A_c (0: unresolved) */
    double a_c;               /* wall area per contact, m^2 (2D: m) */
    int resolved;
    /* under MPI (floe_servo_set_totals): the wall's normal force f.n and its contacts summed
     * over the ranks, read by the controller in place of this rank's parts */
    int have_tot;
    double tot_fn, tot_nc;
} servo_wall;

typedef struct servo_set {
    floe_provider base;
    servo_wall **s;
    int n, cap;
} servo_set;

static void wall_normal(const floe_world *w, int i, double n[3]) {
    const double ez[3] = {0, 0, 1};
    floe_q_rotate(n, w->p.q + 4 * (size_t)i, ez);
}

static int is_wall(const floe_world *w, int i) {
    return i >= 0 && i < w->p.n && w->p.kind[i] == FLOE_GEOM_PLANE;
}

/* the axis of a unit normal along a coordinate axis (-1: oblique) and its sign */
static int axis_of(const double n[3], int *sign) {
    for (int a = 0; a < 3; a++)
        if (fabs(fabs(n[a]) - 1.0) < 1e-9) {
            *sign = n[a] > 0 ? 1 : -1;
            return a;
        }
    return -1;
}

static double servo_area(const servo_wall *r) {
    if (r->def.area > 0) return r->def.area;
    if (!r->resolved || r->nbox == 0) return NAN;
    const floe_world *w = r->w;
    double A = 1;
    for (int k = 0; k < r->nbox; k += 2) {
        int lo = r->box[k], hi = r->box[k + 1]; /* lo: normal +e_b, hi: normal -e_b */
        double nl[3];
        wall_normal(w, lo, nl);
        int sg;
        int b = axis_of(nl, &sg);
        A *= w->p.x[3 * (size_t)hi + b] - w->p.x[3 * (size_t)lo + b];
    }
    return A;
}

static double servo_pressure(const servo_wall *r) {
    const double *f = r->w->p.f + 3 * (size_t)r->wall;
    return -(r->have_tot ? r->tot_fn : floe_v3_dot(f, r->n)) / servo_area(r);
}

/* the normal force of the wall-particle law at depth d (a head-on contact at rest) */
static double law_fn(const floe_contact_law *law, double d, double rad, double mass, double dt) {
    floe_contact c;
    memset(&c, 0, sizeof c);
    c.i = 0;
    c.j = 1;
    c.n[0] = 1;
    c.depth = d;
    c.x2[0] = d;
    c.point[0] = 0.5 * d;
    c.r_eff = rad;
    c.m_eff = mass;
    c.dt = dt > 0 ? dt : 1e-6;
    c.gscale = 1;
    c.thick_i = c.thick_j = 1;
    c.rad_i = rad;
    c.rad_j = INFINITY;
    /* at rest, held there: a linear dashpot sees the other forces' acceleration Fn / m*
     * (floe_contact.an_ext), a fixed point reached by repeating the call (the force is
     * kn d within 1e-12; other laws ignore an_ext and give the same force at once) */
    double fn = NAN;
    for (int it = 0; it < 100; it++) {
        double hist[FLOE_MAX_HISTORY] = {0};
        floe_contact_result res;
        memset(&res, 0, sizeof res);
        if (law->klass->force(law, &c, hist, &res)) return NAN;
        const double f = fabs(res.fn) > 0 ? fabs(res.fn) : floe_v3_norm(res.force);
        if (fabs(f - fn) <= 1e-12 * f) return f;
        fn = f;
        c.an_ext = fabs(res.fn) / mass;
    }
    return fn;
}

/* delta_s of the gain rule: mean radius and mass of the free particles, the law of the wall
 * with the first free particle's material, A_c = (2 r)^2 or 2 r, bisection on the force */
static int servo_resolve_gain(servo_wall *r) {
    floe_world *w = r->w;
    const floe_particles *p = &w->p;
    double rs = 0, ms = 0;
    int nf = 0, mat = -1;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE || !isfinite(p->radius[i])) continue;
        if (mat < 0) mat = p->material[i];
        rs += p->radius[i];
        ms += p->mass[i];
        nf++;
    }
    if (!nf) return floe_world_error(w, FLOE_EINVAL, "servo wall %d: no free particle to push", r->wall);
    double rad = rs / nf, mass = ms / nf;
    const floe_contact_law *law = w->laws[p->material[r->wall] * w->nmats + mat];
    if (!law) return floe_world_error(w, FLOE_EINVAL, "servo wall %d: no contact law with the particles", r->wall);
    r->a_c = w->def.dim == 3 ? 4.0 * rad * rad : 2.0 * rad;
    const double fstar = r->pressure * r->a_c, dt = w->dt;
    double lo = 0, hi = rad, fhi = law_fn(law, hi, rad, mass, dt);
    if (!(fhi > 0) || !isfinite(fhi)) {
        /* a law this probe cannot drive: its linearised stiffness at 1 % of the radius */
        double kn = 0, cn = 0;
        law->klass->stiffness(law, rad, mass, 0.01 * rad, &kn, &cn);
        if (!(kn > 0)) return floe_world_error(w, FLOE_EINVAL, "servo wall %d: the contact law %s gives no normal "
                                               "stiffness: give the servo's gain", r->wall, law->klass->name);
        r->delta_star = fmin(fstar / kn, rad);
        return FLOE_OK;
    }
    if (fhi <= fstar) {
        r->delta_star = rad; /* the target needs overlaps beyond a radius: cap */
        return FLOE_OK;
    }
    for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; it++) {
        double mid = 0.5 * (lo + hi);
        if (law_fn(law, mid, rad, mass, dt) < fstar) lo = mid;
        else hi = mid;
    }
    r->delta_star = hi;
    return FLOE_OK;
}

/* area auto: for every other axis, the walls with normals +e_b and -e_b */
static int servo_resolve_box(servo_wall *r) {
    floe_world *w = r->w;
    int sg, a = axis_of(r->n, &sg);
    if (a < 0)
        return floe_world_error(w, FLOE_EINVAL, "servo wall %d: area auto needs an axis-aligned wall (normal (%g, %g, "
                                "%g)): give its area", r->wall, r->n[0], r->n[1], r->n[2]);
    r->nbox = 0;
    for (int b = 0; b < w->def.dim; b++) {
        if (b == a) continue;
        int found[2] = {-1, -1};
        for (int i = 0; i < w->p.n; i++) {
            if (!is_wall(w, i)) continue;
            double n[3];
            wall_normal(w, i, n);
            int s2, ax = axis_of(n, &s2);
            if (ax == b && found[s2 > 0 ? 0 : 1] < 0) found[s2 > 0 ? 0 : 1] = i;
        }
        if (found[0] < 0 || found[1] < 0)
            return floe_world_error(w, FLOE_EINVAL, "servo wall %d: area auto needs a box of %d walls: no wall with "
                                    "normal %s%c: give its area", r->wall, 2 * w->def.dim, found[0] < 0 ? "+" : "-",
                                    "xyz"[b]);
        r->box[r->nbox++] = found[0];
        r->box[r->nbox++] = found[1];
    }
    r->resolved = 1;
    double A = servo_area(r);
    if (!(A > 0))
        return floe_world_error(w, FLOE_EINVAL, "servo wall %d: the box's walls enclose no area (%g)", r->wall, A);
    return FLOE_OK;
}

static int servo_resolve(servo_wall *r) {
    wall_normal(r->w, r->wall, r->n);
    r->resolved = 0;
    if (r->def.area <= 0) FLOE_TRY(servo_resolve_box(r));
    if (r->def.gain <= 0) FLOE_TRY(servo_resolve_gain(r));
    r->resolved = 1;
    return FLOE_OK;
}

/* free particles whose bounding sphere reaches the wall: its contacts (an upper bound for
 * other shapes than spheres) */
static int servo_contacts(const servo_wall *r) {
    const floe_particles *p = &r->w->p;
    const double *xw = p->x + 3 * (size_t)r->wall;
    int nc = 0;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        const double *x = p->x + 3 * (size_t)i;
        double d = (x[0] - xw[0]) * r->n[0] + (x[1] - xw[1]) * r->n[1] + (x[2] - xw[2]) * r->n[2];
        nc += d < p->radius[i];
    }
    return nc;
}

/* the servo law (floe_servo.h): outward normal speed */
static double servo_speed(const servo_wall *r) {
    if (r->speed_mode) return r->speed;
    const double dt = r->w->dt, P = r->pressure;
    double p = servo_pressure(r), A = servo_area(r);
    if (!isfinite(p) || !(dt > 0)) return 0;
    double vmax = r->def.max_speed > 0 ? r->def.max_speed : FLOE_SERVO_BETA * r->delta_star / dt;
    double v;
    if (r->def.gain > 0) v = r->def.gain * (p - P);
    else {
        /* the wall's stiffness: its n_c contacts at the secant stiffness f_s / delta_s of the
         * target; none: as fast as allowed */
        int nc = r->have_tot ? (int)r->tot_nc : servo_contacts(r);
        v = nc ? FLOE_SERVO_BETA * r->delta_star * A * (p - P) / (nc * P * r->a_c * dt) : (p < P ? -vmax : vmax);
    }
    return v > vmax ? vmax : v < -vmax ? -vmax : v;
}

static void servo_motion(double t, double v[3], double om[3], void *user) {
    servo_wall *r = user;
    (void)t;
    if (!r->resolved && servo_resolve(r)) { /* reported by the provider at prepare */
        v[0] = v[1] = v[2] = 0;
    } else {
        double s = servo_speed(r);
        for (int k = 0; k < 3; k++) v[k] = -s * r->n[k];
    }
    om[0] = om[1] = om[2] = 0;
}

/* the provider: no force; at prepare (and every evaluation until then) resolve */
static int servo_forces(floe_provider *pv, floe_world *w, const struct floe_step_ctx *ctx, floe_provider_out *out) {
    servo_set *S = (servo_set *)pv;
    (void)w;
    (void)out;
    if (ctx->stepping) return FLOE_OK;
    for (int k = 0; k < S->n; k++) FLOE_TRY(servo_resolve(S->s[k]));
    return FLOE_OK;
}

static void servo_destroy(floe_provider *pv) {
    servo_set *S = (servo_set *)pv;
    for (int k = 0; k < S->n; k++) free(S->s[k]);
    free(S->s);
    free(S);
}

static const floe_provider_class servo_class = {
    .version = 1, .name = "servo_walls", .group = FLOE_GROUP_DEM, .forces = servo_forces, .destroy = servo_destroy};

static servo_set *servo_set_of(const floe_world *w) {
    for (int k = 0; k < w->nuprov; k++)
        if (w->uprov[k]->klass == &servo_class) return (servo_set *)w->uprov[k];
    return NULL;
}

static servo_wall *servo_of(const floe_world *w, int wall) {
    servo_set *S = w ? servo_set_of(w) : NULL;
    for (int k = 0; S && k < S->n; k++)
        if (S->s[k]->wall == wall) return S->s[k];
    return NULL;
}

floe_servo_def floe_default_servo_def(void) {
    floe_servo_def d;
    memset(&d, 0, sizeof d);
    return d;
}

static int check_def(floe_world *w, int wall, const floe_servo_def *d) {
    if (!d) return floe_world_error(w, FLOE_EINVAL, "servo wall %d: the definition is NULL", wall);
    if (!(d->pressure > 0) || !isfinite(d->pressure))
        return floe_world_error(w, FLOE_EINVAL, "servo wall %d: pressure must be > 0 (got %g)", wall, d->pressure);
    if (!(d->max_speed >= 0) || !isfinite(d->max_speed))
        return floe_world_error(w, FLOE_EINVAL, "servo wall %d: max_speed must be >= 0 (got %g)", wall, d->max_speed);
    if (!(d->gain >= 0) || !isfinite(d->gain))
        return floe_world_error(w, FLOE_EINVAL, "servo wall %d: gain must be >= 0 (got %g)", wall, d->gain);
    if (!(d->area >= 0) || !isfinite(d->area))
        return floe_world_error(w, FLOE_EINVAL, "servo wall %d: area must be >= 0 (got %g)", wall, d->area);
    return FLOE_OK;
}

int floe_world_add_servo_wall(floe_world *w, int wall, const floe_servo_def *def) {
    if (!w) return FLOE_EINVAL;
    if (!is_wall(w, wall)) return floe_world_error(w, FLOE_EINVAL, "servo wall: particle %d is not a wall", wall);
    FLOE_TRY(check_def(w, wall, def));
    if (servo_of(w, wall)) return floe_world_error(w, FLOE_EINVAL, "servo wall %d: it is a servo wall already", wall);
    for (int k = 0; k < w->nmotions; k++)
        if (w->motions[k].particle == wall)
            return floe_world_error(w, FLOE_EINVAL, "servo wall %d: the wall has a motion already", wall);
    const double *v = w->p.v + 3 * (size_t)wall;
    if (v[0] != 0 || v[1] != 0 || v[2] != 0)
        return floe_world_error(w, FLOE_EINVAL, "servo wall %d: the wall has a velocity already", wall);
    servo_set *S = servo_set_of(w);
    if (!S) {
        if (w->prepared)
            return floe_world_error(w, FLOE_EINVAL, "servo wall %d: add the first servo wall before the world is "
                                    "prepared", wall);
        S = calloc(1, sizeof *S);
        if (!S) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        S->base.klass = &servo_class;
        int rc = floe_world_add_provider(w, &S->base);
        if (rc) {
            free(S);
            return rc;
        }
        w->servo_pv = &S->base;
    }
    if (grow((void **)&S->s, &S->cap, S->n + 1, sizeof *S->s)) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    servo_wall *r = calloc(1, sizeof *r);
    if (!r) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    r->w = w;
    r->wall = wall;
    r->def = *def;
    r->pressure = def->pressure;
    int rc = floe_world_set_motion(w, wall, servo_motion, r);
    if (rc) {
        free(r);
        return rc;
    }
    S->s[S->n++] = r;
    return FLOE_OK;
}

int floe_world_servo_set_pressure(floe_world *w, int wall, double pressure) {
    servo_wall *r = servo_of(w, wall);
    if (!r) return w ? floe_world_error(w, FLOE_EINVAL, "particle %d is not a servo wall", wall) : FLOE_EINVAL;
    if (!(pressure > 0) || !isfinite(pressure))
        return floe_world_error(w, FLOE_EINVAL, "servo wall %d: pressure must be > 0 (got %g)", wall, pressure);
    if (pressure != r->pressure && r->resolved && r->def.gain <= 0) {
        r->pressure = pressure;
        FLOE_TRY(servo_resolve(r)); /* delta_s follows the target */
    }
    r->pressure = pressure;
    r->speed_mode = 0;
    return FLOE_OK;
}

int floe_world_servo_set_speed(floe_world *w, int wall, double speed) {
    servo_wall *r = servo_of(w, wall);
    if (!r) return w ? floe_world_error(w, FLOE_EINVAL, "particle %d is not a servo wall", wall) : FLOE_EINVAL;
    if (!isfinite(speed)) return floe_world_error(w, FLOE_EINVAL, "servo wall %d: speed must be finite", wall);
    r->speed_mode = 1;
    r->speed = speed;
    return FLOE_OK;
}

int floe_world_servo_reset(floe_world *w, int wall) {
    servo_wall *r = servo_of(w, wall);
    if (!r) return w ? floe_world_error(w, FLOE_EINVAL, "particle %d is not a servo wall", wall) : FLOE_EINVAL;
    r->speed_mode = 0;
    return floe_world_servo_set_pressure(w, wall, r->def.pressure);
}

double floe_world_wall_pressure(const floe_world *w, int wall) {
    const servo_wall *r = servo_of(w, wall);
    return r && r->resolved ? servo_pressure(r) : NAN;
}

double floe_world_servo_area(const floe_world *w, int wall) {
    const servo_wall *r = servo_of(w, wall);
    return r && r->resolved ? servo_area(r) : NAN;
}

int floe_world_is_servo_wall(const floe_world *w, int wall) { return servo_of(w, wall) != NULL; }

int floe_servo_is_provider(const floe_provider *pv) { return pv && pv->klass == &servo_class; }

int floe_servo_count(const floe_world *w) {
    const servo_set *S = servo_set_of(w);
    return S ? S->n : 0;
}

void floe_servo_partials(const floe_world *w, double *v) {
    const servo_set *S = servo_set_of(w);
    for (int k = 0; S && k < S->n; k++) {
        const servo_wall *r = S->s[k];
        v[2 * k] = floe_v3_dot(w->p.f + 3 * (size_t)r->wall, r->n);
        v[2 * k + 1] = servo_contacts(r);
    }
}

void floe_servo_set_totals(floe_world *w, const double *v) {
    servo_set *S = servo_set_of(w);
    for (int k = 0; S && k < S->n; k++) {
        S->s[k]->have_tot = 1;
        S->s[k]->tot_fn = v[2 * k];
        S->s[k]->tot_nc = v[2 * k + 1];
    }
}

void floe_servo_renumber(floe_world *w, const int *newidx) {
    servo_set *S = servo_set_of(w);
    for (int k = 0; S && k < S->n; k++) {
        servo_wall *r = S->s[k];
        r->wall = newidx[r->wall];
        for (int b = 0; b < r->nbox; b++) r->box[b] = newidx[r->box[b]];
    }
}

int floe_world_servo_check(floe_world *w, int wall) {
    servo_wall *r = servo_of(w, wall);
    if (!r) return w ? floe_world_error(w, FLOE_EINVAL, "particle %d is not a servo wall", wall) : FLOE_EINVAL;
    if (r->def.area > 0) return FLOE_OK;
    wall_normal(w, wall, r->n);
    int rc = servo_resolve_box(r);
    r->resolved = 0; /* the gain is resolved at prepare */
    return rc;
}

int floe_world_set_law_friction(floe_world *w, int a, int b, double mu) {
    if (!w) return FLOE_EINVAL;
    if (!(mu >= 0) || !isfinite(mu)) return floe_world_error(w, FLOE_EINVAL, "friction must be >= 0 (got %g)", mu);
    int nm = w->nmats;
    if (a >= nm || b >= nm || (a >= 0 && b < 0))
        return floe_world_error(w, FLOE_EINVAL, "set_law_friction: material pair (%d, %d) out of range", a, b);
    for (int i = a < 0 ? 0 : a; i < (a < 0 ? nm : a + 1); i++)
        for (int j = a < 0 ? i : b; j < (a < 0 ? nm : b + 1); j++) {
            floe_contact_law *law = w->laws ? w->laws[i * nm + j] : NULL;
            if (!law) {
                if (a < 0) continue;
                return floe_world_error(w, FLOE_EINVAL, "set_law_friction: no law for materials (%d, %d)", i, j);
            }
            if (floe_contact_law_no_contact(law)) continue;
            int rc = floe_contact_law_set_friction(law, mu);
            if (rc) return floe_world_error(w, rc, "set_law_friction: the law %s of materials (%d, %d) cannot change "
                                            "its friction", law->klass->name, i, j);
        }
    return FLOE_OK;
}
