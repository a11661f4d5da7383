/* test_polytope_contact.c - contact between convex polytopes (2D polygons, boxes, prisms,
 * tetrahedra, random polyhedra) through the world, as a user meets it:
 *  1. the depth a world reports is the documented deepest-point depth
 *     max(-phi_B(x1), -phi_A(x2)), checked against GLPK's simplex on random pairs at scales
 *     1e-3 .. 1e3 m (>= 99 % within 1e-9 of the size);
 *  2. frictionless, undamped collisions of random polygon pairs (2D, mass per area) and
 *     polyhedron pairs (3D) at mm and km scale conserve kinetic + elastic energy within
 *     1e-3 (relative, after separation) at 0.02 x critical and within 1e-2 at the default
 *     step (the integrator's error there, ~1/(steps per collision)^2), in >= 97 % (95 % at
 *     the default step) of the incidences (docs/models.md);
 *  3. stacks of boxes (3D off-centre on the faces below, 2D off-centre by 0.2 of a side)
 *     and a pile of prisms at rest stay at rest under the linear law (the contact
 *     manifold): after settling, every point of every body moves less than 1e-6 of its size
 *     over 10^5 steps; a box spinning on a wall slows at the Coulomb rate of its corners;
 *  4. the overlap-area/volume law (model: overlap_area): force and moment are the exact
 *     gradient of its energy; flat faces; off-centre stacks at rest in 2D and 3D (the 3D
 *     one needs the patch's twist friction); a box spinning on a floor slows at the
 *     Coulomb rate of its patch (1 %); collisions conserve energy. */
#include "floe.h"
#include "world_read.h"
#include "floe_contact.h"
#include "floe_geometry.h"
#include "check.h"
#include <glpk.h>
#include <stdlib.h>
#include <string.h>

#define TEST_RNG_SEED 0x9E3779B97F4A7C15ULL
#include "test_rng.h"
static void quat_z(double q[4], double th) { q[0] = cos(th / 2); q[1] = q[2] = 0; q[3] = sin(th / 2); }

/* ---- shapes ---- */
static floe_geometry *rand_polygon(double r) {
    double xy[2 * 12];
    int n = 3 + (int)(urand() * 7);
    double th0 = uni(0, 2 * M_PI);
    for (int k = 0; k < n; k++) {
        double th = th0 + 2 * M_PI * (k + uni(-0.3, 0.3)) / n, rr = r * uni(0.6, 1.0);
        xy[2 * k] = rr * cos(th);
        xy[2 * k + 1] = rr * sin(th);
    }
    char err[128];
    floe_geometry *g = floe_polygon_create(xy, n, err, sizeof err);
    return g ? g : rand_polygon(r);
}
static floe_geometry *rand_polyhedron(double r) {
    double pl[4 * 24];
    char err[128];
    int kind = (int)(urand() * 4);
    if (kind == 0) return floe_box_create(r * uni(0.5, 1.5), r * uni(0.5, 1.5), r * uni(0.5, 1.5));
    if (kind == 1) { /* prism of a random polygon */
        double xy[2 * 8];
        int n = 3 + (int)(urand() * 5);
        for (int k = 0; k < n; k++) {
            double th = 2 * M_PI * (k + uni(-0.3, 0.3)) / n;
            xy[2 * k] = r * cos(th);
            xy[2 * k + 1] = r * sin(th);
        }
        floe_geometry *g = floe_prism_create(xy, n, r * uni(0.4, 1.5), err, sizeof err);
        return g ? g : rand_polyhedron(r);
    }
    int n = kind == 2 ? 4 : 10 + (int)(urand() * 10); /* tetrahedron or a random hull */
    for (;;) {
        for (int i = 0; i < n; i++) {
            rand_unit(pl + 4 * i);
            pl[4 * i + 3] = r * uni(0.6, 1.0);
        }
        floe_geometry *g = floe_polyhedron_from_planes(pl, n, err, sizeof err);
        if (g && floe_geometry_bounding_radius(g) <= 3 * r) return g;
        if (g) floe_geometry_destroy(g);
    }
}

/* world-frame face planes (n, d: n.x <= d inside) of particle i (box or polytope) */
static int world_planes(const floe_world *w, int i, double *out) {
    const floe_geometry *g = floe_world_particle_geometry(w, i);
    double buf[24];
    const double *P;
    int np;
    if (g->klass == &floe_box_class) {
        const double *h = ((const floe_box *)g)->half;
        for (int a = 0; a < 3; a++)
            for (int s = 0; s < 2; s++) {
                double *B = buf + 4 * (2 * a + s);
                B[0] = B[1] = B[2] = 0;
                B[a] = s ? 1.0 : -1.0;
                B[3] = h[a];
            }
        P = buf;
        np = floe_world_definition(w)->dim == 2 ? 4 : 6;
    } else {
        const floe_polytope *p = (const floe_polytope *)g;
        P = p->plane;
        np = p->np;
    }
    const double *x = pview(w).x + 3 * i, *q = pview(w).q + 4 * i;
    for (int k = 0; k < np; k++) {
        double n[3];
        floe_q_rotate(n, q, P + 4 * k);
        floe_v3_copy(out + 4 * k, n);
        out[4 * k + 3] = P[4 * k + 3] + floe_v3_dot(n, x);
    }
    return np;
}

/* GLPK: the largest depth of a point of A inside B, -min_{x in A} max_f (n_f.x - d_f) */
static double glpk_depth(int dim, const double *A, int na, const double *B, int nb) {
    glp_prob *lp = glp_create_prob();
    glp_set_obj_dir(lp, GLP_MIN);
    int nc = dim + 1;
    glp_add_cols(lp, nc);
    for (int j = 1; j <= nc; j++) glp_set_col_bnds(lp, j, GLP_FR, 0, 0);
    glp_set_obj_coef(lp, nc, 1.0);
    glp_add_rows(lp, na + nb);
    int ind[5] = {0, 1, 2, 3, 4};
    for (int i = 0; i < na + nb; i++) {
        const double *P = i < na ? A + 4 * i : B + 4 * (i - na);
        double val[5] = {0};
        for (int k = 0; k < dim; k++) val[1 + k] = P[k];
        val[nc] = i < na ? 0.0 : -1.0;
        glp_set_mat_row(lp, i + 1, nc, ind, val);
        glp_set_row_bnds(lp, i + 1, GLP_UP, 0, P[3]);
    }
    glp_smcp parm;
    glp_init_smcp(&parm);
    parm.msg_lev = GLP_MSG_OFF;
    int rc = glp_simplex(lp, &parm);
    double t = (rc == 0 && glp_get_status(lp) == GLP_OPT) ? glp_get_col_prim(lp, nc) : NAN;
    glp_delete_prob(lp);
    return -t;
}

static int use_overlap = 0; /* 1: the overlap-area law (2D), ka = kn / size */
static double overlap_size = 1;

static floe_world *make_world(int dim, double density, double kn, double gn, double mu, double grav) {
    floe_world_def d = floe_default_world_def();
    d.dim = dim;
    d.mass_2d_area = dim == 2;
    d.gravity[dim == 2 ? 1 : 2] = -grav;
    floe_world *w = floe_world_create(&d, NULL, 0);
    floe_material m = {"ice", density, 1e9, 0.3};
    floe_world_add_material(w, &m);
    if (use_overlap) /* force ~ ka x overlap area (2D) or volume (3D) ~ kn d */
        floe_world_set_law(w, 0, 0, floe_overlap_law_create(kn / pow(overlap_size, dim - 1), 0.5 * kn, gn, 0.5 * gn, mu));
    else
        floe_world_set_law(w, 0, 0, floe_linear_law_create(kn, 0.5 * kn, gn, 0.5 * gn, mu));
    return w;
}

static int add_body(floe_world *w, floe_geometry *g, const double x[3], const double q[4], const double v[3],
                    const double om[3]) {
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, g);
    floe_v3_copy(p.x, x);
    memcpy(p.q, q, sizeof p.q);
    if (v) floe_v3_copy(p.v, v);
    if (om) floe_v3_copy(p.w, om);
    return floe_world_add_particle(w, &p);
}

/* ---- 1. reported depth against GLPK ---- */
static void test_depth(int dim) {
    glp_term_out(GLP_OFF);
    int n = 0, good = 0, contacts = 0;
    double worst = 0;
    for (int t = 0; t < 400; t++) {
        double scale = pow(10.0, uni(-3, 3));
        floe_world *w = make_world(dim, 1000, 1e3 * scale, 0, 0, 0);
        floe_world_record_contacts(w, 1);
        floe_geometry *ga = dim == 2 ? rand_polygon(scale * uni(0.5, 1)) : rand_polyhedron(scale * uni(0.5, 1));
        floe_geometry *gb = dim == 2 ? rand_polygon(scale * uni(0.5, 1)) : rand_polyhedron(scale * uni(0.5, 1));
        double ra = floe_geometry_bounding_radius(ga), rb = floe_geometry_bounding_radius(gb);
        double qa[4], qb[4], u[3], xa[3] = {0, 0, 0}, xb[3];
        if (dim == 2) {
            quat_z(qa, uni(0, 2 * M_PI));
            quat_z(qb, uni(0, 2 * M_PI));
            double th = uni(0, 2 * M_PI);
            floe_v3_set(u, cos(th), sin(th), 0);
        } else {
            rand_quat(qa);
            rand_quat(qb);
            rand_unit(u);
        }
        double dist = uni(0.3, 1.0) * (ra + rb);
        for (int k = 0; k < 3; k++) xb[k] = dist * u[k];
        add_body(w, ga, xa, qa, NULL, NULL);
        add_body(w, gb, xb, qb, NULL, NULL);
        int rc = floe_world_prepare(w);
        if (!rc) rc = floe_world_step(w);
        if (rc) { /* a very deep random overlap may be refused as unstable: not a depth sample */
            floe_world_destroy(w);
            continue;
        }
        double A[4 * 64], B[4 * 64];
        int na = world_planes(w, 0, A), nb = world_planes(w, 1, B);
        double ref = fmax(glpk_depth(dim, A, na, B, nb), glpk_depth(dim, B, nb, A, na));
        const floe_contact_info *ci = NULL;
        double got = floe_world_contacts(w, &ci) > 0 ? ci[0].depth : 0.0;
        double size = fmin(ra, rb);
        if (ref > 1e-9 * size) {
            n++;
            contacts += floe_world_contact_count(w) > 0;
            double e = fabs(got - ref) / size;
            good += e <= 1e-9;
            if (e > worst) worst = e;
        }
        floe_world_destroy(w);
    }
    printf("  %dD depth vs GLPK: %d of %d overlapping pairs within 1e-9 x size (worst %.2e), %d reported\n", dim, good,
           n, worst, contacts);
    CHECK(n >= 100 && good >= 0.99 * n, "%dD world depth equals the deepest-point depth (GLPK) in %d of %d pairs", dim,
          good, n);
}

/* ---- 2. frictionless undamped collisions ---- */
static double kinetic(const floe_world *w) {
    floe_energy e = floe_world_energy(w);
    return e.kinetic_trans + e.kinetic_rot;
}

/* one random incidence; returns the relative energy error after separation (NAN if the run
 * failed), *peak the largest |E(t) - E0| / E0 during the collision */
static double collide(int dim, double scale, double dt_frac, double *peak, char *why, size_t nwhy) {
    double kn = 1e8 * scale / 1e3;
    overlap_size = scale;
    floe_world *w = make_world(dim, 917, kn, 0, 0, 0);
    floe_geometry *ga = dim == 2 ? rand_polygon(scale * uni(0.5, 1)) : rand_polyhedron(scale * uni(0.5, 1));
    floe_geometry *gb = dim == 2 ? rand_polygon(scale * uni(0.5, 1)) : rand_polyhedron(scale * uni(0.5, 1));
    double ra = floe_geometry_bounding_radius(ga), rb = floe_geometry_bounding_radius(gb);
    double qa[4], qb[4], u[3], lat[3], xa[3] = {0, 0, 0}, xb[3];
    if (dim == 2) {
        quat_z(qa, uni(0, 2 * M_PI));
        quat_z(qb, uni(0, 2 * M_PI));
        double th = uni(0, 2 * M_PI);
        floe_v3_set(u, cos(th), sin(th), 0);
        floe_v3_set(lat, -sin(th), cos(th), 0);
    } else {
        rand_quat(qa);
        rand_quat(qb);
        rand_unit(u);
        double t[3];
        rand_unit(t);
        floe_v3_cross(lat, u, t);
        floe_v3_scale(lat, 1.0 / floe_v3_norm(lat));
    }
    /* impact parameter up to the sum of the radii: glancing corner hits included */
    double b = uni(-0.8, 0.8) * (ra + rb);
    for (int k = 0; k < 3; k++) xb[k] = 1.02 * (ra + rb) * u[k] + b * lat[k];
    /* this test measures the energy error itself (the watchdog would stop the 1-3 % of
     * deepest-point incidences that create more than 5 % at the default step) */
    floe_world_set_energy_check(w, FLOE_CHECK_OFF, 0);
    int ia = add_body(w, ga, xa, qa, NULL, NULL), ib = add_body(w, gb, xb, qb, NULL, NULL);
    (void)ia;
    (void)ib;
    if (floe_world_prepare(w)) {
        snprintf(why, nwhy, "prepare: %s", floe_world_last_error(w));
        floe_world_destroy(w);
        return NAN;
    }
    /* speed: a few per cent of the size as the largest overlap */
    double m = pview(w).mass[0] * pview(w).mass[1] / (pview(w).mass[0] + pview(w).mass[1]);
    double v = 0.02 * fmin(ra, rb) * sqrt(kn / m);
    double vel[2][3], omg[2][3] = {{0, 0, 0}, {0, 0, 0}};
    for (int k = 0; k < 3; k++) {
        vel[0][k] = 0.5 * v * u[k];
        vel[1][k] = -0.5 * v * u[k];
    }
    double om = v / fmin(ra, rb);
    if (dim == 2) {
        omg[0][2] = uni(-0.3, 0.3) * om;
        omg[1][2] = uni(-0.3, 0.3) * om;
    } else {
        double t[3];
        rand_unit(t);
        for (int k = 0; k < 3; k++) omg[0][k] = 0.3 * om * t[k] * urand();
        rand_unit(t);
        for (int k = 0; k < 3; k++) omg[1][k] = 0.3 * om * t[k] * urand();
    }
    for (int i = 0; i < 2; i++) floe_world_set_velocity(w, i, vel[i], omg[i]);
    /* redo the step for these velocities (automatic, or dt_frac x critical) */
    const int allow = floe_world_definition(w)->allow_unstable_dt;
    floe_world_set_dt(w, 0, allow);
    if (dt_frac > 0) {
        floe_world_prepare(w);
        floe_world_set_dt(w, dt_frac * floe_world_critical_dt(w), allow);
    }
    if (floe_world_prepare(w)) {
        snprintf(why, nwhy, "prepare: %s", floe_world_last_error(w));
        floe_world_destroy(w);
        return NAN;
    }
    double E0 = kinetic(w), worst = 0;
    int touched = 0;
    long apart = 0, s;
    long max_steps = (long)(20 * 2 * (ra + rb) / v / floe_world_dt(w)) + 2000;
    for (s = 0; s < max_steps; s++) {
        if (floe_world_step(w)) {
            snprintf(why, nwhy, "step: %s", floe_world_last_error(w));
            floe_world_destroy(w);
            return NAN;
        }
        floe_energy e = floe_world_energy(w);
        double dE = fabs(e.kinetic_trans + e.kinetic_rot + e.elastic - E0) / E0;
        if (dE > worst) worst = dE;
        if (floe_world_contact_count(w) > 0) { touched = 1; apart = 0; }
        else if (touched && ++apart > 50) {
            /* separating: bounding spheres apart for good */
            double dx[3];
            floe_v3_sub(dx, pview(w).x + 3, pview(w).x);
            if (floe_v3_norm(dx) > ra + rb) break;
        }
    }
    double err = fabs(kinetic(w) - E0) / E0;
    *peak = worst;
    if (!touched) err = -1; /* missed: not a sample */
    snprintf(why, nwhy, "%ld steps", s);
    floe_world_destroy(w);
    return err;
}

static void test_collisions(int dim, double scale, double dt_frac, int count, double tol) {
    int n = 0, bad = 0, fails = 0;
    double worst = 0, worst_peak = 0, sum = 0;
    char why[512];
    for (int t = 0; t < count; t++) {
        double peak = 0;
        double e = collide(dim, scale, dt_frac, &peak, why, sizeof why);
        if (isnan(e)) {
            if (fails++ < 3) fprintf(stderr, "  collision %d failed: %s\n", t, why);
            continue;
        }
        if (e < 0) continue;
        n++;
        sum += e;
        if (e > tol) {
            if (bad++ < 3) fprintf(stderr, "  %dD collision %d (scale %g): energy error %.3g (%s)\n", dim, t, scale, e, why);
        }
        if (e > worst) worst = e;
        if (peak > worst_peak) worst_peak = peak;
    }
    printf("  %s%dD collisions at %g m, dt %s: %d hits, energy error after separation max %.2e mean %.2e, "
           "peak during contact %.2e; %d above %.0e, %d runs failed\n",
           use_overlap ? "overlap-area law, " : "", dim, scale, dt_frac > 0 ? "0.02 x critical" : "default", n, worst, n ? sum / n : 0, worst_peak, bad, tol, fails);
    /* measured: 1-2 % of the incidences stay above (worst 2e-2 at 0.02 x critical), an
     * open item of issue 10; the old midpoint/face-overlap contact had 90 % above, worst 3 */
    /* the overlap-area law's energy is smooth: every incidence within the tolerance */
    double share = use_overlap ? 0.0 : dt_frac > 0 ? 0.03 : 0.05;
    CHECK(n >= (count + 1) / 2 && bad <= ceil(share * n) && fails == 0,
          "%dD frictionless collisions at %g m conserve energy within %.0e in %.0f %% of the incidences: %d of %d "
          "above, %d failed (worst %.3g)", dim, scale, tol, 100 * (1 - share), bad, n, fails, worst);
}

/* ---- 3. stacks at rest ---- */
static double body_drift(const floe_world *w, int i, const double *x0, const double *q0, double size) {
    /* the largest displacement of the corners of a cube of side `size` around the centre */
    double worst = 0;
    for (int c = 0; c < 8; c++) {
        double X[3] = {(c & 1 ? 0.5 : -0.5) * size, (c & 2 ? 0.5 : -0.5) * size, (c & 4 ? 0.5 : -0.5) * size};
        double a[3], b[3];
        floe_q_rotate(a, pview(w).q + 4 * i, X);
        floe_v3_add(a, a, pview(w).x + 3 * i);
        floe_q_rotate(b, q0 + 4 * i, X);
        floe_v3_add(b, b, x0 + 3 * i);
        floe_v3_sub(a, a, b);
        double d = floe_v3_norm(a);
        if (d > worst) worst = d;
    }
    return worst;
}

static void run_rest(floe_world *w, const char *name, double size, long settle) {
    int rc = floe_world_prepare(w);
    CHECK(rc == FLOE_OK, "%s prepare: %s", name, floe_world_last_error(w));
    if (rc) return;
    long hold = 100000;
    for (long s = 0; s < settle && !rc; s++) rc = floe_world_step(w);
    int n = pview(w).n;
    double *x0 = malloc(sizeof(double) * 3 * n), *q0 = malloc(sizeof(double) * 4 * n);
    memcpy(x0, pview(w).x, sizeof(double) * 3 * n);
    memcpy(q0, pview(w).q, sizeof(double) * 4 * n);
    for (long s = 0; s < hold && !rc; s++) rc = floe_world_step(w);
    CHECK(rc == FLOE_OK, "%s run: %s", name, floe_world_last_error(w));
    double worst = 0;
    for (int i = 0; i < n; i++)
        if (pview(w).motion[i] == FLOE_FREE) worst = fmax(worst, body_drift(w, i, x0, q0, size));
    printf("  %s: drift over %ld steps after settling %.2e of a size (bound 1e-6), %d contacts\n", name, hold,
           worst / size, floe_world_contact_count(w));
    CHECK(worst < 1e-6 * size, "%s at rest: drift %.3g of a size over 1e5 steps (bound 1e-6)", name, worst / size);
    free(x0);
    free(q0);
}

static void test_box_stack(void) {
    const double a = 0.1, rho = 1000, m = rho * a * a * a, kn = 1e5 * m / 1e-3 * 1e-2;
    floe_world *w = make_world(3, rho, kn, 2 * 0.5 * sqrt(kn * m), 0.5, 9.81);
    double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
    floe_world_add_wall(w, o, nz, 0, FLOE_FIXED);
    double q[4] = {1, 0, 0, 0};
    double z = 0;
    /* three boxes of different sizes, off-centre, the middle one overhanging the edge of the
     * bottom one: the manifold (corner springs, friction and dashpot at its load centre,
     * rocking and twist couples) holds them; a single deepest point rocked */
    double side[3] = {1.2 * a, a, 0.8 * a}, off[3] = {0, 0.2 * a, -0.1 * a};
    for (int k = 0; k < 3; k++) {
        double x[3] = {off[k], 0.1 * off[k], z + 0.5 * side[k]};
        add_body(w, floe_box_create(side[k], side[k], side[k]), x, q, NULL, NULL);
        z += side[k];
    }
    run_rest(w, "stack of 3 boxes, off-centre by 0.2 and 0.1 (overhanging)", a, 40000);
    floe_world_destroy(w);
}

/* 2D: a fixed 6 x 1 polygon slab under y = 0 and three 1 m squares on it, the middle one
 * off-centre by 0.2, the top one by -0.1 (walls are not polygons: the overlap law needs
 * polygon pairs) */
static void add_square_stack(floe_world *w) {
    char err[64];
    double floor_xy[8] = {-3, -0.5, 3, -0.5, 3, 0.5, -3, 0.5}, sq[8] = {-0.5, -0.5, 0.5, -0.5, 0.5, 0.5, -0.5, 0.5};
    double q[4] = {1, 0, 0, 0}, off[3] = {0, 0.2, -0.1};
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_polygon_create(floor_xy, 4, err, sizeof err));
    p.motion = FLOE_FIXED;
    floe_v3_set(p.x, 0, -0.5, 0);
    floe_world_add_particle(w, &p);
    for (int k = 0; k < 3; k++) {
        double x[3] = {off[k], 0.5 + k, 0};
        add_body(w, floe_polygon_create(sq, 4, err, sizeof err), x, q, NULL, NULL);
    }
}

static void test_box_stack2(void) {
    /* 2D, linear law: three 1 m squares on a fixed polygon slab, off-centre by 0.2 and 0.1:
     * the manifold's two springs per flat contact hold them (a single deepest point rocked) */
    const double a = 1, rho = 917, m = rho * a * a, kn = 1e3 * m * 9.81 / a;
    floe_world *w = make_world(2, rho, kn, 2 * 0.5 * sqrt(kn * m), 0.5, 9.81);
    add_square_stack(w);
    run_rest(w, "linear law: 2D stack of 3 squares, off-centre by 0.2 and 0.1", a, 40000);
    floe_world_destroy(w);
}

static void test_manifold_twist(void) {
    /* 3D, linear law: a box (side a, height a/2) spinning about the vertical on a wall slows
     * by Coulomb friction at its four corners (the manifold): couple mu m g a/sqrt(2), so
     * d(omega)/dt = mu m g (a/sqrt 2) / I_z = 12 mu g / (sqrt(2) 2 a) (I_z = m a^2/6);
     * undamped, frictional */
    const double a = 0.1, h = 0.05, rho = 1000, m = rho * a * a * h, kn = 1e5 * m * 9.81 / a, mu = 0.4, g = 9.81;
    floe_world *w = make_world(3, rho, kn, 0, mu, g);
    double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1}, q[4] = {1, 0, 0, 0};
    floe_world_add_wall(w, o, nz, 0, FLOE_FIXED);
    double x[3] = {0, 0, 0.5 * h - m * g / (4 * kn)}, om[3] = {0, 0, 12.0}; /* stops after 0.072 s */
    int b = add_body(w, floe_box_create(a, a, h), x, q, NULL, om);
    CHECK(floe_world_prepare(w) == FLOE_OK, "manifold twist prepare: %s", floe_world_last_error(w));
    double t1 = 0.01, t2 = 0.05, w1 = NAN, w2;
    while (floe_world_time(w) < t2 && floe_world_step(w) == FLOE_OK)
        if (isnan(w1) && floe_world_time(w) >= t1) w1 = pview(w).w[3 * b + 2], t1 = floe_world_time(w);
    w2 = pview(w).w[3 * b + 2];
    t2 = floe_world_time(w);
    double alpha = (w1 - w2) / (t2 - t1), ref = mu * m * g * (a / sqrt(2.0)) / (m * a * a / 6);
    printf("  3D box spinning on a wall (linear law, manifold): d(omega)/dt %.5g rad/s^2, Coulomb at the corners "
           "%.5g (rel %.2e)\n", alpha, ref, fabs(alpha / ref - 1));
    CHECK(fabs(alpha / ref - 1) < 2e-2, "manifold twist friction: deceleration %.5g vs %.5g (bound 2 %%)", alpha, ref);
    floe_world_destroy(w);
}

static void test_prism_pile(void) {
    const double a = 0.1, rho = 1000, m = rho * a * a * a, kn = 1e3 * m / 1e-3;
    floe_world *w = make_world(3, rho, kn, 2 * 0.5 * sqrt(kn * m), 0.5, 9.81);
    double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
    floe_world_add_wall(w, o, nz, 0, FLOE_FIXED);
    double hex[12], tri[6] = {0.6 * a, 0, -0.3 * a, 0.5 * a, -0.3 * a, -0.5 * a};
    for (int k = 0; k < 6; k++) {
        hex[2 * k] = 0.5 * a * cos(M_PI * k / 3);
        hex[2 * k + 1] = 0.5 * a * sin(M_PI * k / 3);
    }
    char err[128];
    double z = 0;
    for (int k = 0; k < 4; k++) {
        double h = 0.3 * a;
        floe_geometry *g = k % 2 ? floe_prism_create(tri, 3, h, err, sizeof err) : floe_prism_create(hex, 6, h, err, sizeof err);
        const floe_polytope *p = (const floe_polytope *)g;
        /* as written: X_input = R(frame_q) X_body + frame_x, input origin at (0.1 a k, 0, z + h/2) */
        double x[3] = {0.1 * a * k + p->frame_x[0], p->frame_x[1], z + 0.5 * h + p->frame_x[2]}, qi[4];
        memcpy(qi, p->frame_q, sizeof qi);
        add_body(w, g, x, qi, NULL, NULL);
        z += h;
    }
    run_rest(w, "pile of 4 prisms", a, 40000);
    floe_world_destroy(w);
}

/* ---- 4. the overlap-area law: exact gradient, flat edges, rest ---- */

/* the contact and overlap of bodies 0 and 1 into c (both always computed: the overlap
 * energy is defined where the detection misses): 1 when both find a contact */
static int detect_overlap(floe_world *w, floe_contact *c) {
    memset(c, 0, sizeof *c);
    int touch = floe_world_probe_contact(w, 0, 1, 0, c) == 1;
    return floe_world_probe_overlap(w, 0, 1, 0, c) == 1 && touch;
}

/* adds ga at the origin (orientation qa) and gb at xb (qb) to the empty world w, their
 * overlap contact into c: 1, or 0 (w destroyed) when they do not touch */
static int add_overlap_pair(floe_world *w, floe_geometry *ga, const double qa[4], floe_geometry *gb,
                            const double xb[3], const double qb[4], floe_contact *c) {
    const double xa[3] = {0, 0, 0};
    add_body(w, ga, xa, qa, NULL, NULL);
    add_body(w, gb, xb, qb, NULL, NULL);
    if (detect_overlap(w, c)) return 1;
    floe_world_destroy(w);
    return 0;
}

/* -dI/dq of the overlap energy I by central differences, q the translations of body 0 and
 * its rotations about its centre (2D: x, y, about z; 3D: x, y, z, about x, y, z), a rotation
 * as the arc length at `scale` (so g holds the force, then the moment / scale) */
static void overlap_gradient(floe_world *w, int dim, double scale, double *g) {
    const int nt = dim, nq = dim == 2 ? 3 : 6;
    double h = 1e-6 * scale;
    for (int k = 0; k < nq; k++) {
        double Ip = 0, Im = 0;
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            double x0[3], q0[4];
            memcpy(x0, pview(w).x, sizeof x0);
            memcpy(q0, pview(w).q, sizeof q0);
            if (k < nt) {
                double x1[3] = {x0[0], x0[1], x0[2]};
                x1[k] += sgn * h;
                floe_world_set_pose(w, 0, x1, NULL);
            } else {
                double th[3] = {0, 0, 0}, dq[4], qn[4];
                if (dim == 2) quat_z(dq, sgn * h / scale);
                else {
                    th[k - nt] = sgn * h / scale;
                    floe_q_from_rotvec(dq, th);
                }
                floe_q_mul(qn, dq, q0);
                floe_world_set_pose(w, 0, NULL, qn);
            }
            floe_contact c2;
            detect_overlap(w, &c2);
            if (sgn < 0) Im = c2.area_energy; else Ip = c2.area_energy;
            floe_world_set_pose(w, 0, x0, q0);
        }
        g[k] = -(Ip - Im) / (2 * h) * (k < nt ? 1 : scale);
    }
}

static void test_overlap_gradient(void) {
    int n = 0, bad = 0, flat_ok = 0;
    double worst = 0;
    for (int t = 0; t < 200; t++) {
        double scale = pow(10.0, uni(-3, 3));
        floe_world *w = make_world(2, 917, 1, 0, 0, 0);
        floe_geometry *ga = rand_polygon(scale), *gb = rand_polygon(scale);
        double qa[4], qb[4], xb[3];
        quat_z(qa, uni(0, 2 * M_PI));
        quat_z(qb, uni(0, 2 * M_PI));
        double th = uni(0, 2 * M_PI), dist = uni(0.5, 1.6) * scale;
        floe_v3_set(xb, dist * cos(th), dist * sin(th), 0);
        floe_contact c;
        if (!add_overlap_pair(w, ga, qa, gb, xb, qb, &c)) continue;
        n++;
        double g[3], F[3], Mz;
        overlap_gradient(w, 2, scale, g);
        floe_v3_copy(F, c.area_force);
        Mz = (c.point[0] - pview(w).x[0]) * F[1] - (c.point[1] - pview(w).x[1]) * F[0];
        double ref = fmax(fabs(F[0]) + fabs(F[1]), c.area);
        double e = fmax(fmax(fabs(g[0] - F[0]), fabs(g[1] - F[1])), fabs(g[2] - Mz) / scale) / ref;
        if (e > worst) worst = e;
        if (e > 1e-5) bad++;
        floe_world_destroy(w);
    }
    /* two aligned squares, one moved by (0.3, -0.2) of a side into the other: the force is
     * the overlap area, along the axis */
    {
        floe_world *w = make_world(2, 917, 1, 0, 0, 0);
        double sq[8] = {-0.5, -0.5, 0.5, -0.5, 0.5, 0.5, -0.5, 0.5}, q[4] = {1, 0, 0, 0};
        char err[64];
        double xa[3] = {0, 0, 0}, xb[3] = {0.3, 0.98, 0};
        add_body(w, floe_polygon_create(sq, 4, err, sizeof err), xa, q, NULL, NULL);
        add_body(w, floe_polygon_create(sq, 4, err, sizeof err), xb, q, NULL, NULL);
        floe_contact c;
        if (detect_overlap(w, &c)) {
            double A = 0.7 * 0.02;
            printf("  overlap law, flat edges: area %.6g (exact %.6g), force (%.3g, %.6g), energy %.6g (exact %.6g)\n",
                   c.area, A, c.area_force[0], c.area_force[1], c.area_energy, 0.7 * 0.02 * 0.02 / 2);
            /* the corners of the overlap are nearer the side edges: corrections of order d / L */
            flat_ok = fabs(c.area - A) < 1e-12 && fabs(c.area_force[1] / A + 1) < 0.03 &&
                      fabs(c.area_force[0]) < 0.03 * A && fabs(c.area_energy / (A * 0.02 / 2) - 1) < 0.03;
        }
        floe_world_destroy(w);
    }
    printf("  overlap law: gradient of I vs force and moment on %d random polygon pairs: worst %.2e of the area\n", n,
           worst);
    CHECK(n >= 100 && bad == 0, "overlap-area force is the gradient of its energy (%d of %d beyond 1e-5, worst %.3g)", bad,
          n, worst);
    CHECK(flat_ok, "overlap law on aligned squares: force = overlap area along the edge normal, energy = A d / 2 "
                   "(within d / L = 2 %%)");
}

/* 3D: the same gradient check on random polyhedron pairs (translations and rotations of A) */
static void test_overlap_gradient3(void) {
    int n = 0, bad = 0;
    double worst = 0;
    for (int t = 0; t < 120; t++) {
        double scale = pow(10.0, uni(-3, 3));
        floe_world *w = make_world(3, 917, 1, 0, 0, 0);
        floe_geometry *ga = rand_polyhedron(scale * 0.7), *gb = rand_polyhedron(scale * 0.7);
        double qa[4], qb[4], xb[3], u[3];
        rand_quat(qa);
        rand_quat(qb);
        rand_unit(u);
        double dist = uni(0.5, 1.2) * scale;
        for (int k = 0; k < 3; k++) xb[k] = dist * u[k];
        floe_contact c;
        if (!add_overlap_pair(w, ga, qa, gb, xb, qb, &c)) continue;
        n++;
        double g[6], M[3], r[3];
        overlap_gradient(w, 3, scale, g);
        /* moment on A about its centre: (point - x) x F + couple */
        floe_v3_sub(r, c.point, pview(w).x);
        floe_v3_cross(M, r, c.area_force);
        floe_v3_add(M, M, c.area_couple);
        double ref = fmax(floe_v3_norm(c.area_force), c.area / scale), e = 0;
        for (int k = 0; k < 3; k++) {
            e = fmax(e, fabs(g[k] - c.area_force[k]) / ref);
            e = fmax(e, fabs(g[3 + k] - M[k]) / (ref * scale));
        }
        if (e > worst) worst = e;
        if (e > 1e-5) bad++;
        floe_world_destroy(w);
    }
    printf("  overlap law 3D: gradient of I vs force and moment on %d random polyhedron pairs: worst %.2e\n", n, worst);
    CHECK(n >= 60 && bad == 0, "3D overlap-volume force is the gradient of its energy (%d of %d beyond 1e-5, worst %.3g)",
          bad, n, worst);
}

static void test_overlap_rest(void) {
    /* 2D: three boxes of 1 m stacked on a wall, the middle one off-centre by 0.2 m, under
     * gravity: a Winkler foundation holds them at rest */
    use_overlap = 1;
    const double a = 1, rho = 917, m = rho * a * a, kn = 1e3 * m * 9.81 / a;
    overlap_size = a;
    floe_world *w = make_world(2, rho, kn, 2 * 0.5 * sqrt(kn * m), 0.5, 9.81);
    add_square_stack(w);
    /* the off-centre stack tilts and slides into place slowly: 60 s of settling */
    run_rest(w, "overlap-area law: 2D stack of 3 boxes, off-centre by 0.2 and 0.1", a, 400000);
    floe_world_destroy(w);
    use_overlap = 0;
}

static void test_overlap_rest3(void) {
    /* 3D: three boxes of 1 m stacked on a fixed box floor, off-centre by 0.2 and 0.1 in x and
     * y, under gravity: the overlap-volume foundation and the contact's twist resistance hold
     * them at rest (no rocking, no slow twist about the vertical) */
    use_overlap = 1;
    const double a = 1, rho = 917, m = rho * a * a * a, kn = 1e3 * m * 9.81 / a;
    overlap_size = a;
    double q[4] = {1, 0, 0, 0};
    floe_world *w = make_world(3, rho, kn, 2 * 0.5 * sqrt(kn * m), 0.5, 9.81);
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_box_create(6, 6, 1));
    p.motion = FLOE_FIXED;
    floe_v3_set(p.x, 0, 0, -0.5);
    floe_world_add_particle(w, &p);
    double off[3] = {0, 0.2, -0.1};
    for (int k = 0; k < 3; k++) {
        double x[3] = {off[k] * a, 0.5 * off[k] * a, (0.5 + k) * a};
        add_body(w, floe_box_create(a, a, a), x, q, NULL, NULL);
    }
    run_rest(w, "overlap-volume law: 3D stack of 3 boxes, off-centre by 0.2 and 0.1", a, 400000);
    floe_world_destroy(w);
    use_overlap = 0;
}

static void test_overlap_twist(void) {
    /* 3D: a 1 m box spinning about the vertical on a floor slows by Coulomb friction over its
     * contact patch: couple mu m g (2/3) sqrt(A/pi), so d(omega)/dt = 4 mu g / (a sqrt(pi))
     * (I = m a^2/6, A = a^2); undamped, placed at its resting depth m g / (ka A) */
    use_overlap = 1;
    const double a = 1, rho = 917, m = rho * a * a * a, kn = 1e3 * m * 9.81 / a, mu = 0.5, g = 9.81;
    overlap_size = a;
    floe_world *w = make_world(3, rho, kn, 0, mu, g);
    floe_particle_def p = floe_default_particle_def();
    p.geometry = floe_world_add_geometry(w, floe_box_create(6, 6, 1));
    p.motion = FLOE_FIXED;
    floe_v3_set(p.x, 0, 0, -0.5);
    floe_world_add_particle(w, &p);
    double q[4] = {1, 0, 0, 0}, x[3] = {0, 0, 0.5 * a - m * g / (kn / (a * a) * a * a)}, om[3] = {0, 0, 1.0};
    int b = add_body(w, floe_box_create(a, a, a), x, q, NULL, om);
    CHECK(floe_world_prepare(w) == FLOE_OK, "twist prepare: %s", floe_world_last_error(w));
    double t1 = 0.02, t2 = 0.06, w1 = NAN, w2 = NAN;
    while (floe_world_time(w) < t2 && floe_world_step(w) == FLOE_OK)
        if (isnan(w1) && floe_world_time(w) >= t1) w1 = pview(w).w[3 * b + 2], t1 = floe_world_time(w);
    w2 = pview(w).w[3 * b + 2];
    t2 = floe_world_time(w);
    double alpha = (w1 - w2) / (t2 - t1), ref = 4 * mu * g / (a * sqrt(M_PI));
    printf("  3D box spinning on a floor (overlap law): d(omega)/dt %.5g rad/s^2, Coulomb over the patch %.5g "
           "(rel %.2e)\n", alpha, ref, fabs(alpha / ref - 1));
    CHECK(fabs(alpha / ref - 1) < 1e-2, "twist friction: deceleration %.5g vs %.5g (bound 1 %%)", alpha, ref);
    floe_world_destroy(w);
    use_overlap = 0;
}

int main(int argc, char **argv) {
    if (argc > 1 && !strcmp(argv[1], "stacks")) { /* the point-law stacks alone */
        test_box_stack();
        test_box_stack2();
        test_prism_pile();
        test_manifold_twist();
        return check_summary("test_polytope_contact stacks");
    }
    if (argc > 1 && !strcmp(argv[1], "rest3")) { /* the 3D overlap-law cases alone */
        test_overlap_twist();
        test_overlap_rest3();
        return check_summary("test_polytope_contact rest3");
    }
    test_depth(2);
    test_depth(3);
    /* at the default step the error is the integrator's (restitution within 0.5 %); at
     * 0.02 x critical the contact must conserve energy within 1e-3. Counts keep the test
     * near a minute ("full" multiplies them by 4). */
    /* FLOE_TEST_QUICK (set for the sanitizer build, tests/CMakeLists.txt): a third */
    int f = argc > 1 && !strcmp(argv[1], "full") ? 12 : getenv("FLOE_TEST_QUICK") ? 1 : 3;
    for (int dim = 2; dim <= 3; dim++)
        for (int sc = 0; sc < 2; sc++) {
            double scale = sc ? 1e-3 : 1e3;
            test_collisions(dim, scale, 0, 20 * f, 1e-2);
            test_collisions(dim, scale, 0.02, 7 * f, 1e-3);
        }
    test_box_stack();
    test_box_stack2();
    test_prism_pile();
    test_manifold_twist();
    test_overlap_gradient();
    test_overlap_gradient3();
    test_overlap_rest();
    test_overlap_twist();
    if (!getenv("FLOE_TEST_QUICK")) /* 5e5 steps of 3 box pairs: too long under the sanitizers */
        test_overlap_rest3();
    use_overlap = 1;
    for (int dim = 2; dim <= 3; dim++)
        for (int sc = 0; sc < 2; sc++) {
            /* conservative and smooth: within 1e-3 at the default step as well */
            test_collisions(dim, sc ? 1e-3 : 1e3, 0, (dim == 3 ? 4 : 13) * f, 1e-3);
            test_collisions(dim, sc ? 1e-3 : 1e3, 0.02, (dim == 3 ? 2 : 3) * f, 1e-3);
        }
    use_overlap = 0;
    return check_summary("test_polytope_contact");
}
