/* beam_newmark.c - the benchmark of 004 §5: a simply supported concrete beam (3 m long,
 * cross-section 1 x 0.5 m, E = 30 GPa, nu = 0.25, uniform load 230 kN/m, bond strengths
 * N(6 MPa, 0.05 MPa)) discretised by a square lattice of nodes joined by Timoshenko beam
 * bonds, run to t = 0.5 s by explicit Newmark (20 % of the critical step of eq 28) and by
 * implicit average acceleration (1 % of the total time), core/integrators/floe_newmark.h. Prints the
 * per-step times before and after the first crack (medians), totals, the crack location,
 * and writes the crack pattern (VTU for ParaView and CSV).
 *
 *   bench_beam_newmark [--h 0.05] [--scheme both|explicit|implicit] [--t-end 0.5]
 *                      [--explicit-t-end T] [--xi 0] [--alpha 0] [--eps 0.01] [--max-cuts 12]
 *                      [--ramp 0] [--support 0] [--strength 6e6] [--t-compare 0.005]
 *                      [--seed 1] [--out DIR]
 *
 * Lattice: nodes on a square grid of spacing ~h (nx = 3/h + 1 columns from x = 0 to 3 m,
 * 0.5/h rows), horizontal and vertical Timoshenko bonds of section h x 1 m. Supports: the
 * end sections are held vertically (the reaction spread over the depth, free to turn),
 * one node held horizontally; --support n holds n bottom nodes at each end instead (point
 * supports concentrate the stress: 7.9 MPa there against 6.4 MPa at mid-span, static).
 * --explicit-t-end stops the explicit run early and estimates its total from the median
 * per-step times (as 004 Table 1 does for 7,676 elements); the crack comparison then uses
 * the implicit state at the same times. Density 2400 kg/m^3 is inferred from 004 Table 1
 * (its Delta t_crit = h sqrt(rho / E) exactly); the load is applied suddenly at t = 0
 * (--ramp T: linearly over T) and the beam has no self-weight (004 does not mention one);
 * no damping unless --xi (004 eq 8) or --alpha (mass-proportional). compare.py compares
 * the crack patterns of two runs. */
#include "floe_newmark.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_d(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}
static double median(double *v, long n) {
    if (n <= 0) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

typedef struct {
    double h, t_end, t_explicit, xi, alpha, ramp, strength, t_compare, eps;
    int max_cuts;
    int support;                 /* bottom nodes held at each end */
    unsigned long long seed;
    const char *out;
} opts;

typedef struct {
    int nx, ny;                  /* nodes along x (columns), rows */
    double hx, hy;
} lattice;

/* the beam: nodes at x = i hx (i = 0..nx-1, supports at x = 0 and 3 m on the bottom row),
 * y = (j + 1/2) hy; horizontal and vertical bonds of section hy x 1 m and hx x 1 m */
static double ramp_fn(double t, void *user) {
    double T = *(const double *)user;
    return T > 0 ? fmin(t / T, 1.0) : 1.0;
}

static floe_newmark *build(const opts *o, double beta, double dt, lattice *lt, int allow) {
    const double Lb = 3.0, H = 0.5, B = 1.0, E = 30e9, nu = 0.25, rho = 2400, q = 230e3;
    lattice L;
    L.nx = (int)lround(Lb / o->h) + 1;
    L.ny = (int)lround(H / o->h);
    L.hx = Lb / (L.nx - 1);
    L.hy = H / L.ny;
    *lt = L;
    floe_newmark_def d = floe_newmark_default_def();
    d.dim = 2;
    d.beta = beta;
    d.dt = dt;
    d.damping_ratio = o->xi;
    d.mass_damping = o->alpha;
    d.allow_unstable_dt = allow;
    d.line_search_eps = o->eps;
    d.max_cuts = o->max_cuts;
    char err[256];
    floe_newmark *s = floe_newmark_create(&d, err, sizeof err);
    if (!s) { fprintf(stderr, "create: %s\n", err); exit(1); }
    for (int j = 0; j < L.ny; j++)
        for (int i = 0; i < L.nx; i++) {
            double x[3] = {i * L.hx, (j + 0.5) * L.hy, 0};
            double w = (i == 0 || i == L.nx - 1) ? 0.5 : 1.0; /* end columns: half cells */
            double m = rho * w * L.hx * L.hy * B, J = m * (w * w * L.hx * L.hx + L.hy * L.hy) / 12.0;
            floe_newmark_add_node(s, x, m, J);
        }
    unsigned long long rng = o->seed;
    floe_beam_section hs = {0}, vs = {0};
    hs.E = vs.E = E;
    hs.G = vs.G = E / (2 * (1 + nu));
    hs.A = L.hy * B;
    hs.I = B * L.hy * L.hy * L.hy / 12;
    hs.W = B * L.hy * L.hy / 6;
    hs.phi = 12 * E * hs.I / ((5.0 / 6.0) * hs.G * hs.A * L.hx * L.hx);
    vs.A = L.hx * B;
    vs.I = B * L.hx * L.hx * L.hx / 12;
    vs.W = B * L.hx * L.hx / 6;
    vs.phi = 12 * E * vs.I / ((5.0 / 6.0) * vs.G * vs.A * L.hy * L.hy);
    hs.J = hs.I;
    vs.J = vs.I;
    for (int j = 0; j < L.ny; j++)
        for (int i = 0; i < L.nx; i++) {
            int a = j * L.nx + i;
            if (i + 1 < L.nx)
                floe_newmark_add_bond(s, a, a + 1, &hs, o->strength + 0.05e6 * floe_beam_normal(&rng), INFINITY);
            if (j + 1 < L.ny) {
                floe_beam_section v2 = vs;
                if (i == 0 || i == L.nx - 1) { v2.A *= 0.5; v2.I *= 0.5; v2.W *= 0.5; v2.J *= 0.5; }
                floe_newmark_add_bond(s, a, a + L.nx, &v2, o->strength + 0.05e6 * floe_beam_normal(&rng), INFINITY);
            }
        }
    if (o->support > 0) {
        /* point supports: pin at the bottom left, roller at the bottom right (over
         * `support` bottom nodes each) */
        for (int k = 0; k < o->support && k < L.nx / 2; k++) {
            floe_newmark_fix(s, k, k == 0 ? FLOE_NM_UX | FLOE_NM_UY : FLOE_NM_UY);
            floe_newmark_fix(s, L.nx - 1 - k, FLOE_NM_UY);
        }
    } else {
        /* end sections held vertically (the reaction spread over the depth, free to turn:
         * the Saint-Venant form of a simple support), one node held horizontally */
        for (int j = 0; j < L.ny; j++) {
            floe_newmark_fix(s, j * L.nx, FLOE_NM_UY | (j == L.ny / 2 ? FLOE_NM_UX : 0));
            floe_newmark_fix(s, j * L.nx + L.nx - 1, FLOE_NM_UY);
        }
    }
    floe_newmark_set_load_factor(s, ramp_fn, (void *)&o->ramp);
    for (int i = 0; i < L.nx; i++) {
        double w = (i == 0 || i == L.nx - 1) ? 0.5 : 1.0, f[3] = {0, -q * w * L.hx, 0};
        floe_newmark_set_load(s, (L.ny - 1) * L.nx + i, f, NULL);
    }
    return s;
}

typedef struct {
    const char *name;
    int elements, bonds;
    double dt_crit_diag, dt_crit_bound, dt;
    long steps, cuts, factorizations;
    double tb_med, tu_med, total, total_est, t_stop;
    double tb_intact;            /* median step of the intact beam */
    int estimated;
    double t_first, tip_mid;
    int broken;
    double *tbr, *xmid;          /* per bond: time of breaking (-1: intact), midpoint x */
} result;

/* broken bonds at time t: count, x extent and centroid of their midpoints */
static void crack_at(const result *r, double t, int *n, double *xmin, double *xmax, double *xmean) {
    *n = 0;
    *xmin = INFINITY;
    *xmax = -INFINITY;
    *xmean = 0;
    for (int k = 0; k < r->bonds; k++)
        if (r->tbr[k] >= 0 && r->tbr[k] <= t) {
            (*n)++;
            *xmin = fmin(*xmin, r->xmid[k]);
            *xmax = fmax(*xmax, r->xmid[k]);
            *xmean += r->xmid[k];
        }
    if (*n) *xmean /= *n;
}

/* median time of a step of the intact beam (no bond can break: the cost per step before
 * cracking, without the cuts of the step where the first crack forms) */
static double intact_step_time(const opts *o, int implicit, double dt) {
    opts q = *o;
    q.strength = 1e30;
    lattice L;
    floe_newmark *s = build(&q, implicit ? 0.25 : 0.0, dt, &L, 0);
    if (floe_newmark_prepare(s)) { floe_newmark_destroy(s); return NAN; }
    int n = implicit ? 20 : 200;
    double t[200];
    for (int k = 0; k < n; k++) {
        double a = now_s();
        floe_newmark_step(s);
        t[k] = now_s() - a;
    }
    floe_newmark_destroy(s);
    return median(t, n);
}

static int run_scheme(const opts *o, int implicit, result *r) {
    lattice L;
    double t_stop = implicit ? o->t_end : fmin(o->t_end, o->t_explicit > 0 ? o->t_explicit : o->t_end);
    /* step: explicit 20 % of eq 28, implicit 1 % of the total time */
    floe_newmark *probe = build(o, 0.0, 1.0, &L, 1);
    double dtd = floe_newmark_critical_dt_diag(probe), dtb = floe_newmark_critical_dt(probe);
    floe_newmark_destroy(probe);
    double dt = implicit ? 0.01 * o->t_end : 0.2 * dtd;
    floe_newmark *s = build(o, implicit ? 0.25 : 0.0, dt, &L, 0);
    memset(r, 0, sizeof *r);
    r->name = implicit ? "implicit" : "explicit";
    r->elements = floe_newmark_node_count(s);
    r->bonds = floe_newmark_bond_count(s);
    r->dt_crit_diag = dtd;
    r->dt_crit_bound = dtb;
    r->dt = dt;
    double t0 = now_s();
    int rc = floe_newmark_prepare(s);
    if (rc) { fprintf(stderr, "%s prepare: %s\n", r->name, floe_newmark_last_error(s)); return rc; }
    long cap = (long)ceil(t_stop / dt) + 1000, nb4 = 0, naf = 0;
    double *tb = malloc((size_t)cap * sizeof *tb), *tu = malloc((size_t)cap * sizeof *tu);
    while (floe_newmark_time(s) < t_stop - 1e-9 * dt) {
        floe_newmark_stats st;
        floe_newmark_get_stats(s, &st);
        int before = st.broken == 0;
        double a = now_s(), t = floe_newmark_time(s);
        rc = t + dt <= t_stop ? floe_newmark_step(s) : floe_newmark_run(s, t_stop); /* the last one lands on t_stop */
        double e = now_s() - a;
        if (rc) { fprintf(stderr, "%s step: %s\n", r->name, floe_newmark_last_error(s)); break; }
        if (before && nb4 < cap) tb[nb4++] = e;
        else if (!before && naf < cap) tu[naf++] = e;
    }
    r->total = now_s() - t0;
    floe_newmark_stats st;
    floe_newmark_get_stats(s, &st);
    r->steps = st.steps;
    r->cuts = st.cuts;
    r->factorizations = st.factorizations;
    r->t_first = st.t_first_break;
    r->tb_med = median(tb, nb4);
    r->tb_intact = intact_step_time(o, implicit, dt);
    r->tu_med = median(tu, naf);
    r->t_stop = floe_newmark_time(s);
    r->estimated = r->t_stop < o->t_end - 1e-9;
    if (r->estimated) {
        double left = (o->t_end - r->t_stop) / dt, per = naf ? r->tu_med : r->tb_med;
        r->total_est = r->total + left * per;
    } else r->total_est = r->total;
    /* mid-span deflection (bottom row) */
    double u[3];
    floe_newmark_get(s, L.nx / 2, u, NULL, NULL, NULL);
    r->tip_mid = u[1];
    char path[1024];
    snprintf(path, sizeof path, "%s/crack_%s_h%g.vtu", o->out, r->name, o->h);
    floe_newmark_write_vtu(s, path);
    snprintf(path, sizeof path, "%s/bonds_%s_h%g.csv", o->out, r->name, o->h);
    floe_newmark_write_bonds_csv(s, path);
    free(tb);
    free(tu);
    r->tbr = malloc((size_t)r->bonds * sizeof *r->tbr);
    r->xmid = malloc((size_t)r->bonds * sizeof *r->xmid);
    for (int k = 0; k < r->bonds; k++) {
        int br;
        floe_newmark_bond_state(s, k, &br, r->tbr + k, NULL, NULL);
        if (!br) r->tbr[k] = -1;
    }
    /* midpoints from the lattice: bonds in creation order (see build) */
    for (int j = 0, k = 0; j < L.ny; j++)
        for (int i = 0; i < L.nx; i++) {
            if (i + 1 < L.nx) r->xmid[k++] = (i + 0.5) * L.hx;
            if (j + 1 < L.ny) r->xmid[k++] = i * L.hx;
        }
    r->broken = st.broken;
    double xmin, xmax, xmean;
    int nbk;
    crack_at(r, INFINITY, &nbk, &xmin, &xmax, &xmean);
    printf("%s h=%g: %d elements, %d bonds, dt_crit eq28 %.3e s (bound %.3e s), dt %.3e s, %ld steps (%ld cuts, %ld "
           "factorizations) to t = %.4g s, first crack t = %.4g s, %d broken (x %.3f..%.3f, centroid %.3f), per step "
           "intact %.3e s, before the first crack %.3e s, after %.3e s, total %.2f s%s%.2f s, mid-span uy %.3e m\n",
           r->name, o->h, r->elements, r->bonds, dtd, dtb, dt, r->steps, r->cuts, r->factorizations, r->t_stop,
           r->t_first, r->broken, xmin, xmax, xmean, r->tb_intact, r->tb_med, r->tu_med, r->total,
           r->estimated ? ", estimated to 0.5 s: " : " = ", r->total_est, r->tip_mid);
    printf("  %s h=%g: wall time in factorizations %.2f s, solves %.2f s, bond kernels %.2f s\n", r->name, o->h,
           st.seconds_factor, st.seconds_solve, st.seconds_bonds);
    fflush(stdout);
    floe_newmark_destroy(s);
    return rc;
}

int main(int argc, char **argv) {
    opts o = {0.05, 0.5, 0, 0, 0, 0, 6e6, 0.005, 0.01, 12, 0, 1, "out/beam-newmark"};
    const char *scheme = "both";
    for (int k = 1; k < argc; k++) {
        if (!strcmp(argv[k], "--h") && k + 1 < argc) o.h = atof(argv[++k]);
        else if (!strcmp(argv[k], "--scheme") && k + 1 < argc) scheme = argv[++k];
        else if (!strcmp(argv[k], "--t-end") && k + 1 < argc) o.t_end = atof(argv[++k]);
        else if (!strcmp(argv[k], "--explicit-t-end") && k + 1 < argc) o.t_explicit = atof(argv[++k]);
        else if (!strcmp(argv[k], "--xi") && k + 1 < argc) o.xi = atof(argv[++k]);
        else if (!strcmp(argv[k], "--alpha") && k + 1 < argc) o.alpha = atof(argv[++k]);
        else if (!strcmp(argv[k], "--eps") && k + 1 < argc) o.eps = atof(argv[++k]);
        else if (!strcmp(argv[k], "--max-cuts") && k + 1 < argc) o.max_cuts = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--t-compare") && k + 1 < argc) o.t_compare = atof(argv[++k]);
        else if (!strcmp(argv[k], "--ramp") && k + 1 < argc) o.ramp = atof(argv[++k]);
        else if (!strcmp(argv[k], "--strength") && k + 1 < argc) o.strength = atof(argv[++k]);
        else if (!strcmp(argv[k], "--support") && k + 1 < argc) o.support = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--seed") && k + 1 < argc) o.seed = strtoull(argv[++k], NULL, 10);
        else if (!strcmp(argv[k], "--out") && k + 1 < argc) o.out = argv[++k];
        else {
            fprintf(stderr, "usage: %s [--h 0.05] [--scheme both|explicit|implicit] [--t-end 0.5] "
                            "[--explicit-t-end T] [--xi 0] [--alpha 0] [--eps 0.01] [--max-cuts 12] [--ramp 0] "
                            "[--support 0] [--strength 6e6] [--t-compare 0.005] [--seed 1] [--out DIR]\n", argv[0]);
            return 2;
        }
    }
    if (!(o.h > 0 && o.h <= 0.25)) { fprintf(stderr, "--h must be in (0, 0.25]\n"); return 2; }
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "%s", o.out);
    for (char *p = cmd + 1; *p; p++)
        if (*p == '/') { *p = 0; mkdir(cmd, 0777); *p = '/'; }
    mkdir(cmd, 0777);
    result re = {0}, ri = {0};
    int do_e = strcmp(scheme, "implicit") != 0, do_i = strcmp(scheme, "explicit") != 0, rc = 0;
    if (do_e) rc |= run_scheme(&o, 0, &re);
    if (do_i) rc |= run_scheme(&o, 1, &ri);
    if (do_e && do_i && re.tbr && ri.tbr) {
        /* same crack? the broken bonds of both runs at the same times */
        double tc[4] = {o.t_compare, 2 * o.t_compare, 5 * o.t_compare, fmin(re.t_stop, ri.t_stop)};
        for (int c = 0; c < 4; c++) {
            int inter = 0, uni = 0, ne, ni;
            double a0, a1, am, b0, b1, bm;
            for (int k = 0; k < re.bonds; k++) {
                int be = re.tbr[k] >= 0 && re.tbr[k] <= tc[c], bi = ri.tbr[k] >= 0 && ri.tbr[k] <= tc[c];
                inter += be && bi;
                uni += be || bi;
            }
            crack_at(&re, tc[c], &ne, &a0, &a1, &am);
            crack_at(&ri, tc[c], &ni, &b0, &b1, &bm);
            printf("crack at t = %.4g s: explicit %d broken (x %.3f..%.3f, centroid %.3f), implicit %d (x %.3f..%.3f, "
                   "centroid %.3f), common %d, Jaccard %.3f\n",
                   tc[c], ne, a0, a1, am, ni, b0, b1, bm, inter, uni ? (double)inter / uni : 1.0);
        }
        printf("wall time h=%g: explicit %s%.2f s, implicit %.2f s: implicit %.1fx faster\n", o.h,
               re.estimated ? "(estimated) " : "", re.total_est, ri.total, re.total_est / ri.total);
    }
    free(re.tbr);
    free(re.xmid);
    free(ri.tbr);
    free(ri.xmid);
    return rc ? 1 : 0;
}
