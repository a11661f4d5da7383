/* watchdog.c - the top of the driver: floe_world_step (the scheme's step, or the adaptive
 * controller around it, then the energy watchdog and the observers) and floe_world_run;
 * the energy watchdog: a run that creates energy stops, naming the pair or PD body. */
#include "integrator_parts.h"
#include "floe_parallel.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
/* ---- energy watchdog ----
 * After every accepted step: energy created beyond tol x the energy scale (the largest
 * K + elastic + |work_body| + |work_boundary| seen, at least sum m |g| R over the free
 * particles) stops the run (or warns once). Four
 * measures, each O(1) or O(PD bodies) per step: the contact with the most negative
 * dissipation over its life (forces.c keeps it in the pair's history), each PD body's bond
 * dissipation, the ledger's total dissipation, and the balance error (energy that appeared
 * outside the ledger: the integration). The diagnosis below runs only when one trips. */

int floe_world_set_energy_check(floe_world *w, int mode, double tol) {
    if (!floe_energy_check_name(mode) || !(tol >= 0 && tol < 1))
        return floe_world_error(w, FLOE_EINVAL, "energy check: mode %d (stop, warn or off) or tolerance %g (in [0, 1)) "
                                "invalid", mode, tol);
    w->def.energy_check = mode;
    w->def.energy_check_tol = tol > 0 ? tol : 0.05;
    return FLOE_OK;
}

int floe_world_energy_check(const floe_world *w, floe_energy_check_state *out) {
    out->mode = w->def.energy_check;
    out->tolerance = w->def.energy_check_tol;
    out->scale = w->wd_scale;
    out->created = w->wd_created;
    out->tripped_step = w->wd_step;
    out->message = w->wd_msg;
    return FLOE_OK;
}

/* kinetic + elastic energy of PD body k (J) */
static double pd_body_energy(const floe_world *w, int k) {
    const floe_particles *p = &w->p;
    double e = w->pd_eold ? w->pd_eold[k] : 0;
    for (int i = w->pd_first[k]; i < w->pd_first[k] + w->pd[k]->n; i++)
        if (p->motion[i] == FLOE_FREE) e += 0.5 * p->mass[i] * floe_v3_dot(p->v + 3 * i, p->v + 3 * i);
    return e;
}

/* "PD body k (particles a..b)" into buf */
static void pd_body_name(const floe_world *w, int k, char *buf, size_t len) {
    snprintf(buf, len, "PD body %d (particles %d..%d)", k, w->pd_first[k], w->pd_first[k] + w->pd[k]->n - 1);
}

/* the likely cause when PD bodies run staggered with several rates (else "") */
static const char *stag_cause(const floe_world *w, char *buf, size_t len) {
    buf[0] = 0;
    if (w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd && (w->pd_sub > 1 || w->pd_every > 1))
        snprintf(buf, len, "staggered PD-DEM with %s %d: the contact impulses on the PD points resonate with the "
                 "body's modes (the step %g s is too long for them); use fewer substeps (or scheme: monolithic) "
                 "or a smaller dt", w->pd_every > 1 ? "every" : "substeps", w->pd_every > 1 ? w->pd_every : w->pd_sub,
                 w->dt);
    return buf;
}

/* a step taken: the statistics (floe_world_step_stats) */
static void step_accepted(floe_world *w) {
    floe_step_stats *s = &w->st;
    s->accepted++;
    if (s->dt_min_used == 0 || w->dt < s->dt_min_used) s->dt_min_used = w->dt;
    if (w->dt > s->dt_max_used) s->dt_max_used = w->dt;
}

/* close_rc (MPI, or NULL): this rank's outcome of the step's close, agreed by the watchdog's
 * reduction (floe_par_watchdog_values; step.c step_close deferred it): the agreed failure is
 * returned, else the step is counted and checked */
static int energy_watchdog(floe_world *w, const int *close_rc) {
    if (w->def.energy_check == FLOE_CHECK_OFF) return close_rc ? *close_rc : FLOE_OK; /* (not deferred then) */
    /* MPI: the ledger summed over the ranks (core/parallel), the same on every rank */
    floe_energy er = w->energy;
    double shadow = w->wd_shadow, shadow0 = w->wd_shadow0, pair_min = w->wd_pair_min;
    /* the PD bodies' dissipation (MPI: summed over the ranks, as the ledger) */
    const int npdd = w->npd < w->pd_diss_n ? w->npd : w->pd_diss_n;
    const double *pd_diss = w->pd_diss;
    if (w->par) { /* a copy to sum, kept with the world (prepare): nothing to allocate here */
        double *pdd_sum = w->pd_diss_sum;
        if (npdd) memcpy(pdd_sum, w->pd_diss, (size_t)npdd * sizeof *pdd_sum);
        const int arc = floe_par_watchdog_values(w, &er, &shadow, &shadow0, &pair_min, pdd_sum, npdd, close_rc);
        if (arc) { /* the step's close failed on some rank: every rank returns it */
            if (close_rc && !*close_rc) { /* this rank's close passed: what its integrator set after it undone */
                w->energy = w->close_energy;
                w->wd_shadow = w->close_shadow;
                w->lf_dt_prev = w->close_lf;
            }
            return arc;
        }
        pd_diss = pdd_sum;
    }
    if (close_rc) step_accepted(w);
    const floe_energy *e = &er;
    const double cur = e->kinetic_trans + e->kinetic_rot + e->elastic;
    double sc = fmax(fmax(cur + fabs(e->work_body) + fabs(e->work_boundary), fabs(e->initial)), w->wd_gscale);
    if (sc > w->wd_scale) w->wd_scale = sc;
    const double S = w->wd_scale, tol = w->def.energy_check_tol;
    if (!(S > 0)) return FLOE_OK;
    double c_pair = -pair_min / S, c_pd = 0, c_led = -(e->dissipated + e->elastic) / S;
    /* the balance in the form velocity Verlet conserves (shadow_term) */
    double c_bal = (cur - shadow + e->dissipated - (e->initial - shadow0) - e->work_body - e->work_boundary) / S;
    int kb = -1;
    for (int k = 0; k < npdd; k++)
        if (-pd_diss[k] / S > c_pd) { c_pd = -pd_diss[k] / S; kb = k; }
    /* above half the critical step the measured energy of forces that are not linear (or
     * not exactly the gradient of the reported energy, as beam bonds) oscillates by tens of
     * per cent at a stable step (26 % at 0.95 x the bond limit, tests/test_beam.c): there
     * the balance trips only when half the scale appeared (an instability passes that in a
     * few steps) */
    const double tol_bal = w->dt > 0.5 * w->dt_crit ? fmax(tol, 0.5) : tol;
    double created = fmax(fmax(c_pair, c_pd), fmax(c_led, c_bal));
    if (created > w->wd_created) w->wd_created = created;
    /* (NaN passes no test: the particle checks report it) */
    if (!(c_pair > tol || c_pd > tol || c_led > tol || c_bal > tol_bal)) return FLOE_OK;
    if (w->wd_step >= 0 && w->def.energy_check == FLOE_CHECK_WARN) return FLOE_OK; /* warned once */
    /* MPI: every rank took this decision alike (from the sums); the culprit may live on
     * another rank: each rank names its own candidate and the worst one's words are every
     * rank's (floe_par_pick, collective: the branches below are taken alike on every rank) */
    const int par = w->par != NULL;
    char what[256] = "", cause[512] = "", cause0[512] = "", name[96] = ""; /* (zero-filled: broadcast whole) */
    const floe_particles *p = &w->p;
    stag_cause(w, cause0, sizeof cause0);
    memcpy(cause, cause0, sizeof cause);
    /* a contact: this step's worst, or the run's worst when the ledger as a whole went
     * negative (under MPI: whether any rank's worst is negative, from the pick) */
    int pair_case = c_pair > tol || (c_led > tol && c_pd <= tol && w->wd_worst < 0);
    if (par && !(c_pair > tol)) pair_case = c_led > tol && c_pd <= tol;
    if (pair_case) {
        int i = c_pair > tol ? w->wd_pair_i : w->wd_worst_i, j = c_pair > tol ? w->wd_pair_j : w->wd_worst_j;
        double d = c_pair > tol ? w->wd_pair_min : w->wd_worst;
        /* under MPI the run's worst contact may have left this rank since (index -1) */
        const int here = i >= 0 && j >= 0 && i < p->n && j < p->n;
        const floe_contact_law *law = here ? w->laws[p->material[i] * w->nmats + p->material[j]] : NULL;
        const int pdk = here && w->pd_of ? (w->pd_of[i] >= 0 ? w->pd_of[i] : w->pd_of[j]) : -1;
        name[0] = 0;
        if (pdk >= 0) {
            char pn[80];
            pd_body_name(w, pdk, pn, sizeof pn);
            snprintf(name, sizeof name, ", a point of %s", pn);
        }
        snprintf(what, sizeof what, "the contact of particles %d and %d (bodies %d, %d%s; law %s) gave back %.3g J "
                 "more than it received since it began", (int)floe_world_parallel_gid(w, i), (int)floe_world_parallel_gid(w, j),
                 here ? p->group[i] : -1, here ? p->group[j] : -1, name,
                 law ? law->klass->name : "?", -d);
        if (!cause[0] || pdk < 0)
            snprintf(cause, sizeof cause, "the contact law creates energy (negative damping, or unloading stiffer "
                     "than loading), or the step %g s is too large for its stiffness", w->dt);
        if (par) { /* the rank with the worst contact (one that left every rank: none) */
            const double worst = floe_par_pick(w, here && d < 0 ? -d : -INFINITY, what, sizeof what, cause, sizeof cause);
            if (!(worst > 0) && c_pair > tol) /* (no rank holds this step's worst: not expected) */
                snprintf(what, sizeof what, "summed over the MPI ranks: pair %.3g, ledger %.3g, balance %.3g of the "
                         "scale", c_pair, c_led, c_bal);
            else if (!(worst > 0)) { /* no rank's worst is negative */
                pair_case = 0;
                memcpy(cause, cause0, sizeof cause);
                name[0] = 0;
            }
        }
    }
    if (pair_case) {
        /* named */
    } else if (c_pd > tol || (c_led > tol && kb >= 0)) {
        /* (MPI: kb and pd_diss are the sums' over the ranks, pd_first the global ids) */
        pd_body_name(w, kb, name, sizeof name);
        snprintf(what, sizeof what, "the bonds of %s gave back %.3g J more than they took", name, -pd_diss[kb]);
        if (!cause[0])
            snprintf(cause, sizeof cause, "the bond forces' integration is unstable: the step %g s is too large "
                     "for the bond stiffness", w->dt);
    } else if (par && w->npd) {
        /* MPI with PD bodies: the bodies' energies are not summed here; the measures only */
        snprintf(what, sizeof what, "summed over the MPI ranks: pair %.3g, ledger %.3g, balance %.3g of the scale",
                 c_pair, c_led, c_bal);
        if (!cause[0])
            snprintf(cause, sizeof cause, "the integration created it: the step %g s is too large for the stiffness; "
                     "lower dt or safety", w->dt);
    } else {
        /* energy appeared outside the ledger: name the PD body or particle that holds most */
        double best = -1;
        int bi = -1;
        kb = -1;
        for (int k = 0; k < w->npd; k++) {
            double eb = pd_body_energy(w, k);
            if (eb > best) { best = eb; kb = k; }
        }
        if (kb >= 0) pd_body_name(w, kb, name, sizeof name);
        if (!cause[0] || kb < 0) {
            best = -1;
            for (int i = 0; i < p->n; i++)
                if (p->motion[i] == FLOE_FREE && (!w->pd_of || w->pd_of[i] < 0 || !cause[0])) {
                    double ek = 0.5 * p->mass[i] * floe_v3_dot(p->v + 3 * i, p->v + 3 * i);
                    if (ek > best) { best = ek; bi = i; }
                }
            if (bi >= 0 && (!cause[0] || kb < 0)) {
                if (w->pd_of && w->pd_of[bi] >= 0) pd_body_name(w, w->pd_of[bi], name, sizeof name);
                else snprintf(name, sizeof name, "particle %d (body %d)", (int)floe_world_parallel_gid(w, bi),
                              p->group[bi]);
            }
            if (!cause[0]) {
                const floe_geometry_class *gk = bi >= 0 ? w->geoms[p->geom[bi]]->klass : NULL;
                const int poly = gk && (gk->polytope || gk->piece_count); /* a polytope or a union of pieces */
                snprintf(cause, sizeof cause, "the integration created it: the step %g s is too large for the "
                         "stiffness, or a force is not conservative (a body-force callback)%s; lower dt or safety",
                         w->dt, poly ? ", or a polytope contact under a point law (linear, Hertz) crossed a kink of "
                         "the deepest-point depth (an edge lying on a face: docs/models.md, \"Contact manifold\"; "
                         "model: overlap_area has none)" : "");
            }
        }
        /* MPI (no PD bodies): the rank holding the most energetic particle names it (owned
         * free particles: a ghost is FIXED here) */
        if (par) floe_par_pick(w, bi >= 0 ? best : -INFINITY, name, sizeof name, cause, sizeof cause);
        snprintf(what, sizeof what, "the energy grew %.3g J beyond the ledger (balance error), most of it in %s",
                 c_bal * S, bi >= 0 || kb >= 0 || (par && name[0]) ? name : "?");
    }
    snprintf(w->wd_msg, sizeof w->wd_msg,
             "energy watchdog: %.1f %% of the energy scale %.3g J created by step %ld (t = %g s): %s; likely cause: %s",
             100 * created, S, w->step, w->time, what, cause);
    if (w->wd_step < 0) w->wd_step = w->step;
    if (w->def.energy_check == FLOE_CHECK_WARN) {
        fprintf(stderr, "floe: warning: %s (checks: energy: warn, the run goes on)\n", w->wd_msg);
        return FLOE_OK;
    }
    if (par) w->err_agreed = 1; /* from the sums: every rank stops here */
    return floe_world_error(w, FLOE_EUNSTABLE, "%s", w->wd_msg);
}

int floe_world_step(floe_world *w) {
    if (!w->prepared) FLOE_TRY(floe_world_prepare(w));
    w->err_agreed = 0; /* MPI: set by an error every rank returns (core/parallel) */
    /* MPI, a fixed step of velocity Verlet or leapfrog with the watchdog on: the step's close
     * is agreed in the watchdog's reduction (one collective a step less; step.c step_close).
     * RK2 and the staggered scheme keep their own agreement (tested so) */
    w->close_defer = w->par && !w->def.adaptive && w->def.energy_check != FLOE_CHECK_OFF &&
                     (w->def.integrator == FLOE_VELOCITY_VERLET || w->def.integrator == FLOE_LEAPFROG) &&
                     !(w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd);
    w->close_pending = 0;
    int rc = w->def.adaptive ? step_adaptive(w, step_once) : step_once(w);
    w->close_defer = 0;
    if (w->close_pending) { /* every rank reached the close: agreed now */
        w->close_pending = 0;
        const int mine = rc ? rc : w->close_rc;
        FLOE_TRY(energy_watchdog(w, &mine));
    } else {
        if (rc) return rc; /* (agreed before the close, under MPI) */
        step_accepted(w);
        FLOE_TRY(energy_watchdog(w, NULL));
    }
    if (w->par) FLOE_TRY(floe_par_observe(w, 0)); /* MPI: the outputs of rank 0's unsplit mirror */
    return observers_call(w, 0);
}

/* the step becomes dt from the present state on (the clock restarts here; the watchdog's
 * conserved form follows the closing half kick, which grows as dt: its balance goes on) */
static void change_dt(floe_world *w, double dt) {
    if (dt == w->dt) return;
    const double r = dt / w->dt;
    w->t0 = w->time;
    w->step0 = w->step;
    w->wd_shadow0 += w->wd_shadow * (r * r - 1);
    w->wd_shadow *= r * r;
    w->dt = dt;
}

/* the step may be shortened for the last one (velocity Verlet, RK2: a class whose trial
 * step can be undone takes any step; not the staggered scheme's PD cycle of several steps,
 * not leapfrog, whose kick spans the previous step too) */
static int can_shorten(const floe_world *w) {
    const floe_integrator_class *ic = floe_integrator_class_of(w->def.integrator);
    if (!ic || !(ic->flags & FLOE_INTEGRATOR_RESTORES)) return 0;
    return !(w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd && w->pd_every > 1);
}

int floe_world_run(floe_world *w, double t_end, floe_progress_fn progress, void *user) {
    int rc = floe_world_prepare(w);
    if (rc) { floe_world_finish(w); return rc; }
    if (!w->def.adaptive) {
        /* Fixed step: the whole steps that end at or before t_end (counted from the clock's
         * origin t0, step0, so that a run continued from a checkpoint takes the same steps),
         * then, when the integrator takes a shorter step, one that ends at t_end; leapfrog
         * and the staggered scheme with a PD cycle end on the last whole step (at most one
         * step before t_end). */
        const double dt = w->dt;
        long last = w->step0 + (long)floor((t_end - w->t0) / dt + 1e-9);
        long nfull = last - w->step;
        if (nfull < 0) nfull = 0;
        const double t_full = w->t0 + (double)(w->step + nfull - w->step0) * dt;
        const int tail = can_shorten(w) && t_end - t_full > 1e-9 * dt;
        const long nsteps = nfull + tail;
        for (long s = 0; s < nsteps; s++) {
            const int short_step = tail && s == nfull;
            w->last_step_of_run = s == nsteps - 1;
            if (short_step) change_dt(w, t_end - w->time);
            rc = floe_world_step(w);
            if (short_step) change_dt(w, dt); /* later runs go on with the scene's step */
            w->last_step_of_run = 0;
            if (rc) break;
            if (progress && progress(w, s + 1, nsteps, user)) {
                rc = floe_world_error(w, FLOE_ESTOP, "stopped by the progress callback at step %ld", w->step);
                break;
            }
        }
    } else {
        /* adaptive: steps until t_end, the last one cut to end there */
        const double eps = 1e-9 * w->dt_lo;
        for (long s = 0; w->time < t_end - eps; s++) {
            w->dt_cap = t_end - w->time;
            w->last_step_of_run = w->dt_next >= w->dt_cap - eps;
            rc = floe_world_step(w);
            w->last_step_of_run = 0;
            w->dt_cap = INFINITY;
            if (rc) break;
            long left = (long)ceil((t_end - w->time) / w->dt_next - 1e-9);
            if (progress && progress(w, s + 1, s + 1 + (left > 0 ? left : 0), user)) {
                rc = floe_world_error(w, FLOE_ESTOP, "stopped by the progress callback at step %ld", w->step);
                break;
            }
        }
    }
    if (rc && rc != FLOE_ESTOP) {
        /* flush the state at failure so the outputs show what happened */
        char keep[sizeof w->err];
        memcpy(keep, w->err, sizeof keep);
        observers_call(w, 1);
        /* MPI: when every rank returned the error and the state is whole (err_agreed 1: not
         * out of memory, not a failed decomposition), rank 0's mirror writes the state at the
         * failure too (collective: the ranks are all here) */
        if (w->par && w->err_agreed == 1) (void)floe_par_observe(w, 1);
        memcpy(w->err, keep, sizeof keep);
    }
    char keep[sizeof w->err];
    memcpy(keep, w->err, sizeof keep);
    int rc2 = floe_world_finish(w);
    if (rc) memcpy(w->err, keep, sizeof keep); /* the run's first error, not a writer's at the end */
    return rc ? rc : rc2;
}
