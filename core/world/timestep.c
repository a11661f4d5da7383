/* timestep.c - critical time-step estimates (contact, Rayleigh, Hertz, PD, beam bonds) and
 * the critical-step table of floe_dt_estimates (docs/integrators.md). The choice of the
 * step from them, which depends on the integrator, is the driver's
 * (core/integrators/driver.c). */
#include "world_parts.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
/* ---- preparation ---- */

/* Representative overlap: the larger of 2 % of R* and the overlap at which a collision
 * at relative speed v stores its kinetic energy (energy ~ (4/15) k_tangent d^2, exact for
 * Hertz; conservative for linear springs), found by bisection on the law's stiffness. */
static double rep_depth(const floe_contact_law *law, double r_eff, double m_eff, double v) {
    double lo = 0.02 * r_eff, hi = r_eff, kn, cn;
    double target = 0.5 * m_eff * v * v;
    law->klass->stiffness(law, r_eff, m_eff, lo, &kn, &cn);
    if (4.0 / 15.0 * kn * lo * lo >= target) return lo;
    law->klass->stiffness(law, r_eff, m_eff, hi, &kn, &cn);
    if (4.0 / 15.0 * kn * hi * hi <= target) return hi;
    for (int it = 0; it < 60; it++) {
        double mid = 0.5 * (lo + hi);
        law->klass->stiffness(law, r_eff, m_eff, mid, &kn, &cn);
        if (4.0 / 15.0 * kn * mid * mid < target) lo = mid;
        else hi = mid;
    }
    return hi;
}

/* Explicit stability of one particle of mass m held by springs k and dashpots c of a law
 * at a representative contact (r_eff, m_eff): a particle with contacts n_c has the
 * stiffness matrix sum_c k n n^T, and by Gershgorin its highest mode is at most twice that
 * sum's largest eigenvalue: omega^2 <= C k / m with C = 2 n_c / d (8 for the 12 contacts
 * of a close packing in 3D, 6 for the 6 of a hexagonal packing in 2D); the dashpots add up
 * the same way (the peers' "8 gamma / m"). Spring-dashpot limit:
 * dt < (2/omega)(sqrt(1 + zeta^2) - zeta). */
static void pair_estimate(const floe_contact_law *law, double r_eff, double m_eff, double m, double rot, double rotn,
                          double C, double v, double *dt) {
    double kn = 0, cn = 0, depth = rep_depth(law, r_eff, m_eff, v);
    law->klass->stiffness(law, r_eff, m_eff, depth, &kn, &cn);
    /* the normal force on a non-spherical body need not pass through its centre (a corner
     * of a polygon hit sideways): its contact point then moves as a mass m / rotn, which
     * shortens the contact period by sqrt(rotn) (spheres: rotn = 1) */
    kn *= rotn;
    cn *= rotn;
    /* polytopes under a point law touch through a contact manifold (rotn includes its
     * factor, floe_dt_estimates); the overlap law spreads its load instead (its own
     * stiffness counts the contact length) */
    if (rotn > rot && floe_contact_law_info(law).spreads_load) {
        kn *= rot / rotn;
        cn *= rot / rotn;
    }
    if (law->klass->tangential_stiffness) {
        /* tangential springs act at the surface: the contact point of a particle of mass m,
         * radius R and inertia I moves as a mass 1/(1/m + R^2/I) = m/rot */
        double kt = 0, ct = 0;
        law->klass->tangential_stiffness(law, r_eff, m_eff, depth, &kt, &ct);
        if (kt * rot > kn) kn = kt * rot;
        if (ct * rot > cn) cn = ct * rot;
    }
    if (!(kn > 0)) return;
    double k = C * kn, c = C * cn;
    double om = sqrt(k / m), zeta = c / (2 * sqrt(k * m));
    double d = 2.0 / om * (sqrt(1 + zeta * zeta) - zeta);
    if (d < *dt) *dt = d;
}

/* Per-particle estimates of one (material, mass, radius, rotation factor), cached: most
 * scenes have few distinct particles */
typedef struct dt_cache_entry {
    int mat;
    double m, r, rot;
    double rotn;    /* rot for non-spherical bodies (normal forces off the centre), else 1 */
    double packing, impact, sqrt_mk, hertz;
    double err1, err2;        /* restitution error model (floe_dt_estimates) */
} dt_cache_entry;
#define DT_CACHE 1024

static void particle_contact_estimates(const floe_world *w, dt_cache_entry *e, double vrel) {
    const double C = w->def.dim == 3 ? 8.0 : 6.0, nc = w->def.dim == 3 ? 12.0 : 6.0;
    const double m = e->m, R = e->r, rot = e->rot, rotn = e->rotn;
    e->packing = e->impact = e->sqrt_mk = e->hertz = INFINITY;
    e->err1 = e->err2 = 0;
    for (int m2 = 0; m2 < w->nmats; m2++) {
        const floe_contact_law *law = w->laws[e->mat * w->nmats + m2];
        if (!law) continue;
        /* partner of the same size (m* = m/2, R* = R/2) and a wall (m* = m, R* = R) */
        /* a packing (all contacts of a close packing at a 2 % overlap) and an impact at
         * the expected speed (one contact, C = 2, at the overlap of the collision) */
        pair_estimate(law, 0.5 * R, 0.5 * m, m, rot, rotn, C, 0, &e->packing);
        pair_estimate(law, R, m, m, rot, rotn, C, 0, &e->packing);
        pair_estimate(law, 0.5 * R, 0.5 * m, m, rot, rotn, 2.0, vrel, &e->impact);
        pair_estimate(law, R, m, m, rot, rotn, 2.0, vrel, &e->impact);
        /* 000 eq 43: sqrt(m / k_bar), k_bar = the normal stiffnesses of the n_c contacts of
         * a close packing at 2 % overlap (004 eq 28 takes 2 sqrt(m_ii / k_ii) of the same) */
        for (int s = 0; s < 2; s++) {
            double re = s ? R : 0.5 * R, me = s ? m : 0.5 * m, kn = 0, cn = 0;
            law->klass->stiffness(law, re, me, 0.02 * re, &kn, &cn);
            if (kn > 0 && sqrt(m / (nc * kn)) < e->sqrt_mk) e->sqrt_mk = sqrt(m / (nc * kn));
            /* Hertz contact duration at the expected speed, 2.87 (m*^2 / (R* E*^2 v))^(1/5)
             * (E* of the law: the force is 4/3 E* sqrt(R*) d^(3/2)) */
            const floe_law_info info = floe_contact_law_info(law);
            if (info.hertz_e_star > 0 && vrel > 0) {
                double es = info.hertz_e_star;
                double th = 2.87 * pow(me * me / (re * es * es * vrel), 0.2);
                if (th < e->hertz) e->hertz = th;
                /* restitution error ~ A(e) / N, N = th / dt (first order: the damping grows
                 * as d^(1/4) from the onset; tests/test_restitution_onset.c) */
                double er = isnan(info.restitution) ? 1.0 : info.restitution;
                double A = 3.5 * pow(1 - er, 1.5) + 0.02;
                if (A / th > e->err1) e->err1 = A / th;
            }
            if (info.linear_kn > 0) {
                /* ~ A(e) / N^2, N = pi / w_d / dt (the dashpot's onset and release treated in
                 * contact/laws/linear_law.c) */
                double kk = info.linear_kn, z = info.linear_gn / (2 * sqrt(kk * me));
                if (kk > 0 && z < 1) {
                    double tc = M_PI / (sqrt(kk / me) * sqrt(1 - z * z));
                    double er = floe_linear_restitution(kk, info.linear_gn, me), A = 3 + 12 * (1 - er) * (1 - er);
                    if (A / (tc * tc) > e->err2) e->err2 = A / (tc * tc);
                }
            }
        }
    }
}

/* record dt for kind k at particle i when it is the smallest so far */
static void dt_note(floe_dt_estimates *d, int k, double dt, int i) {
    if (dt < d->dt[k]) { d->dt[k] = dt; d->particle[k] = i; }
}

const char *floe_dt_kind_name(int kind) {
    static const char *const names[FLOE_DT_NKINDS] = {"contact_packing", "contact_impact", "motion", "pd_nodal",
                                                      "pd_cfl", "dem_sqrt_m_k", "rayleigh", "hertz", "beam_bond",
                                                      "provider"};
    return kind >= 0 && kind < FLOE_DT_NKINDS ? names[kind] : NULL;
}

/* Every estimate of floe_dt_estimates, per particle (w->dt_part: the smallest limiting
 * kind of each particle) and global (w->dte, w->dt_crit). */
int estimate_dt(floe_world *w) {
    floe_particles *p = &w->p;
    floe_dt_estimates *d = &w->dte;
    memset(d, 0, sizeof *d);
    for (int k = 0; k < FLOE_DT_NKINDS; k++) { d->dt[k] = INFINITY; d->particle[k] = -1; }
    d->limits[FLOE_DT_CONTACT_PACKING] = d->limits[FLOE_DT_CONTACT_IMPACT] = 1;
    d->limits[FLOE_DT_MOTION] = d->limits[FLOE_DT_PD_NODAL] = 1;
    double *dp = realloc(w->dt_part, (size_t)(p->n ? p->n : 1) * sizeof *dp);
    if (!dp) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    w->dt_part = dp;
    /* largest relative speed to expect: twice the fastest particle plus the free fall
     * over the extent of the scene along gravity */
    double vmax = 0, gmag = floe_v3_norm(w->def.gravity), lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] == FLOE_FIXED) continue;
        double s = floe_v3_norm(p->v + 3 * i);
        if (s > vmax) vmax = s;
        if (gmag > 0 && isfinite(p->radius[i])) {
            double h = floe_v3_dot(p->x + 3 * i, w->def.gravity) / gmag;
            if (h < lo) lo = h;
            if (h > hi) hi = h;
        }
    }
    double vrel = 2 * vmax + (hi > lo ? sqrt(2 * gmag * (hi - lo)) : 0);
    w->v_expected = d->v_expected = vrel;
    /* materials in a Hertz-Mindlin law: the Rayleigh step of their particles */
    unsigned char *hertz_mat = calloc((size_t)(w->nmats ? w->nmats : 1), 1);
    dt_cache_entry *cache = calloc(DT_CACHE, sizeof *cache);
    if (!hertz_mat || !cache) {
        free(hertz_mat);
        free(cache);
        return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    for (int a = 0; a < w->nmats; a++)
        for (int b = 0; b < w->nmats; b++) {
            const floe_contact_law *law = w->laws[a * w->nmats + b];
            if (law && floe_contact_law_info(law).hertz_e_star > 0) hertz_mat[a] = hertz_mat[b] = 1;
        }
    for (int k = 0; k < DT_CACHE; k++) cache[k].mat = -1;
    double *mfac = malloc((size_t)(w->ngeoms > 0 ? w->ngeoms : 1) * sizeof *mfac); /* NULL: computed each time */
    if (mfac)
        for (int k = 0; k < w->ngeoms; k++) mfac[k] = -1.0;
    for (int i = 0; i < p->n; i++) {
        dp[i] = INFINITY;
        if (p->motion[i] != FLOE_FREE || !isfinite(p->radius[i])) continue;
        /* 1 + m R^2 / I: 3.5 for a sphere */
        const double *I = p->inertia + 3 * i;
        double imin = w->def.dim == 2 ? I[2] : fmin(I[0], fmin(I[1], I[2]));
        double rot = imin > 0 ? fmax(1.0, 1 + p->mass[i] * p->radius[i] * p->radius[i] / imin) : 1.0;
        double rotn = p->kind[i] == FLOE_GEOM_SPHERE ? 1.0 : rot;
        /* polytopes touch through a contact manifold (up to 2 corner springs in 2D, 4 in 3D),
         * which can be stiffer in rocking than one point at the bounding radius (a thin
         * square plate flat on a face: 12 k/m against 1 + m R^2/I_min = 7): the larger */
        if (p->kind[i] != FLOE_GEOM_SPHERE && mfac) { /* per shape (it depends on I/m only) */
            double *f = mfac + p->geom[i];
            if (*f < 0) *f = floe_polytope_manifold_factor(w->geoms[p->geom[i]], w->def.dim, I, p->mass[i]);
            rotn = fmax(rotn, *f);
        } else if (p->kind[i] != FLOE_GEOM_SPHERE) {
            rotn = fmax(rotn, floe_polytope_manifold_factor(w->geoms[p->geom[i]], w->def.dim, I, p->mass[i]));
        }
        dt_cache_entry key = {p->material[i], p->mass[i], p->radius[i], rot, rotn, 0, 0, 0, 0, 0, 0};
        unsigned long long hsh = (unsigned long long)key.mat * 0x9E3779B97F4A7C15ull;
        const double vals[4] = {key.m, key.r, key.rot, key.rotn};
        for (int k = 0; k < 4; k++) {
            unsigned long long bits;
            memcpy(&bits, &vals[k], sizeof bits);
            hsh = (hsh ^ bits) * 0x100000001B3ull;
        }
        dt_cache_entry *e = &cache[(hsh >> 20) % DT_CACHE];
        if (!(e->mat == key.mat && e->m == key.m && e->r == key.r && e->rot == key.rot && e->rotn == key.rotn)) {
            *e = key;
            particle_contact_estimates(w, e, vrel);
        }
        dt_note(d, FLOE_DT_CONTACT_PACKING, e->packing, i);
        dt_note(d, FLOE_DT_CONTACT_IMPACT, e->impact, i);
        dt_note(d, FLOE_DT_DEM_SQRT_MK, e->sqrt_mk, i);
        dt_note(d, FLOE_DT_HERTZ, e->hertz, i);
        if (e->err1 > d->err1) d->err1 = e->err1;
        if (e->err2 > d->err2) d->err2 = e->err2;
        double mine = fmin(e->packing, e->impact);
        /* motion: no particle may move more than half its radius in a step (the stability
         * check of the step stops the run past that) */
        if (vrel > 0) {
            double dm = 0.5 * p->radius[i] / vrel;
            dt_note(d, FLOE_DT_MOTION, dm, i);
            if (dm < mine) mine = dm;
        }
        if (hertz_mat[p->material[i]]) {
            /* Rayleigh wave crossing the particle: pi R sqrt(rho / G) / (0.1631 nu + 0.8766) */
            const floe_material *mt = &w->mats[p->material[i]];
            double G = mt->young / (2 * (1 + mt->poisson));
            double dr = M_PI * p->radius[i] * sqrt(mt->density / G) / (0.1631 * mt->poisson + 0.8766);
            dt_note(d, FLOE_DT_RAYLEIGH, dr, i);
        }
        dp[i] = mine;
    }
    free(hertz_mat);
    free(cache);
    free(mfac);
    /* peridynamic bodies: the nodal estimate sqrt(2 rho / sum_j V_j c/|xi|) per point
     * (Silling and Askari 2005; measured limits 2.1x (PMB) and 1.8x (LPS) of it,
     * tests/test_pd.c), as floe_pd_dt_nodal; and the CFL step of 000 eqs 41-42 per body */
    for (int k = 0; k < w->npd; k++) {
        const floe_pd_body *b = w->pd[k];
        double *sum = calloc((size_t)b->n, sizeof *sum);
        if (!sum) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        double c = b->ops->bond_micromodulus(b);
        for (int i = 0; i < b->n; i++)
            for (int64_t q = b->off[i]; q < b->off[i + 1]; q++) {
                int j = b->partner[q];
                double s = b->vfac[q] * (b->scorr ? b->scorr[q] : 1.0f) * c / b->len[q];
                sum[i] += s * b->V[j];
                sum[j] += s * b->V[i];
            }
        for (int i = 0; i < b->n; i++) {
            const int pi = floe_pd_particle(w, k, i); /* (MPI: -1 when not on this rank) */
            if (pi < 0 || !(sum[i] > 0) || p->motion[pi] != FLOE_FREE) continue;
            double dn = sqrt(2.0 * b->mat.rho / sum[i]);
            dt_note(d, FLOE_DT_PD_NODAL, dn, pi);
            if (dn < dp[pi]) dp[pi] = dn;
        }
        free(sum);
        double dc = floe_pd_dt_cfl(b);
        if (dc > 0) dt_note(d, FLOE_DT_PD_CFL, dc, floe_pd_particle(w, k, 0));
    }
    if (w->beams) { /* beam bonds */
        d->limits[FLOE_DT_BEAM] = 1;
        d->dt[FLOE_DT_BEAM] = floe_world_beam_critical_dt(w);
    }
    for (int k = 0; k < w->nuprov; k++) { /* user providers' own stability limits */
        floe_provider *pv = w->uprov[k];
        if (!pv->klass->critical_dt) continue;
        const double dpv = pv->klass->critical_dt(pv, w);
        if (!(dpv > 0)) return floe_world_error(w, FLOE_EINVAL, "force provider %s: critical_dt gave %g s (must be > 0; "
                                                "INFINITY for no limit)", pv->klass->name, dpv);
        if (dpv < INFINITY) d->limits[FLOE_DT_PROVIDER] = 1;
        if (dpv < d->dt[FLOE_DT_PROVIDER]) d->dt[FLOE_DT_PROVIDER] = dpv;
    }
    d->critical = INFINITY;
    d->limiting = d->limiting_particle = -1;
    for (int k = 0; k < FLOE_DT_NKINDS; k++)
        if (d->limits[k] && d->dt[k] < d->critical) {
            d->critical = d->dt[k];
            d->limiting = k;
            d->limiting_particle = d->particle[k];
        }
    d->critical_contact = fmin(d->dt[FLOE_DT_CONTACT_PACKING], fmin(d->dt[FLOE_DT_CONTACT_IMPACT], d->dt[FLOE_DT_MOTION]));
    d->critical_pd = d->dt[FLOE_DT_PD_NODAL];
    d->accuracy_dt = INFINITY;
    if (w->def.accuracy > 0) {
        const double a = w->def.accuracy;
        if (d->err1 > 0) d->accuracy_dt = a / d->err1;
        if (d->err2 > 0) d->accuracy_dt = fmin(d->accuracy_dt, sqrt(a / d->err2));
    }
    w->dt_crit = d->critical;
    return FLOE_OK;
}
