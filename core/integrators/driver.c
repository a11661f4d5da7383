/* driver.c - the driver's prepare (floe_world_prepare): the store's part (core/world/
 * world_prepare.c), then the step from the critical estimates and the integrator class
 * (its factor and capability flags), the first forces of the scheme, the energy at the
 * start and the observers' start; the estimate queries that prepare first. */
#include "integrator_parts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* the energy of the closing half kick (shadow_term, step.c) over every free particle, from
 * the forces in p->f, p->t (velocity Verlet and leapfrog: the half kick h F / m) or the
 * staggered groups fs, ts, fpd (particle i's at stride * i); 0 for a class without a closing half kick (RK2) */
static double shadow_energy(const floe_world *w, const double *fs, const double *ts, const double *fpd, int stride) {
    const floe_particles *p = &w->p;
    const floe_integrator_class *ic = floe_integrator_class_of(w->def.integrator);
    if (!(ic->flags & FLOE_INTEGRATOR_HALF_KICK) && !fpd) return 0;
    const double h = 0.5 * w->dt, hp = fpd ? 0.5 * w->dt / (w->pd_sub > 0 ? w->pd_sub : 1) : 0;
    double e = 0;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        double dv[3], dL[3];
        for (int k = 0; k < 3; k++) {
            dv[k] = h * p->inv_mass[i] * fs[(size_t)stride * i + k];
            if (fpd && w->pd_every == 1 && w->pd_of && w->pd_of[i] >= 0) dv[k] += hp * p->inv_mass[i] * fpd[(size_t)stride * i + k];
            dL[k] = h * ts[(size_t)stride * i + k];
        }
        e += shadow_term(p, i, dv, dL);
    }
    return e;
}

/* The step, the staggered ratios and the adaptive bounds, from the definition and the
 * estimates. A given dt above the critical estimate is refused unless allowed; so is a PD
 * step of the staggered scheme above the PD estimate. */
int choose_dt(floe_world *w) {
    const floe_world_def *d = &w->def;
    const floe_dt_estimates *e = &w->dte;
    const floe_integrator_class *ic = floe_integrator_class_of(d->integrator);
    if (!ic || !ic->step)
        return floe_world_error(w, FLOE_EINVAL, "integrator %d unknown (velocity_verlet, leapfrog or rk2)", d->integrator);
    if (d->pd_dem != FLOE_PD_DEM_MONOLITHIC && d->pd_dem != FLOE_PD_DEM_STAGGERED)
        return floe_world_error(w, FLOE_EINVAL, "pd_dem scheme %d unknown (monolithic or staggered)", d->pd_dem);
    const int stag = d->pd_dem == FLOE_PD_DEM_STAGGERED;
    /* compatibility from the capability flags (floe_integrator.h) and the providers */
    if (stag && !(ic->flags & FLOE_INTEGRATOR_KICK_DRIFT))
        return floe_world_error(w, FLOE_EINVAL, "the staggered PD-DEM scheme kicks and drifts as velocity Verlet does "
                                "(r-RESPA), and %s; use integrator velocity_verlet with it", ic->why_not_kick_drift);
    if (d->adaptive && !(ic->flags & FLOE_INTEGRATOR_RESTORES))
        return floe_world_error(w, FLOE_EINVAL, "adaptive steps need an integrator whose trial step can be undone "
                                "(velocity_verlet or rk2): %s", ic->why_not_restores);
    if (d->adaptive && stag)
        return floe_world_error(w, FLOE_EINVAL, "adaptive steps and the staggered PD-DEM scheme cannot be combined yet");
    if (w->beams && !(ic->flags & FLOE_INTEGRATOR_UNDAMPED_BONDS))
        return floe_world_error(w, FLOE_EINVAL, "the %s integrator and beam bonds cannot be combined: %s; use "
                                "velocity_verlet or leapfrog", ic->name, ic->why_not_bonds);
    if (d->adaptive)
        for (int k = 0; k < w->nprov; k++) {
            const floe_provider *pv = w->prov[k];
            if (pv->klass->can_save && !pv->klass->can_save(pv, w))
                return floe_world_error(w, FLOE_EINVAL, "adaptive steps and %s cannot be combined yet: their state "
                                        "cannot be restored after a rejected trial step (a bond broken in it would "
                                        "stay broken); use a fixed or automatic step", pv->klass->name);
        }
    if (d->pd_substeps < 0 || d->pd_every < 0 || (d->pd_substeps > 1 && d->pd_every > 1))
        return floe_world_error(w, FLOE_EINVAL, "staggered PD-DEM: substeps (%d) and every (%d) must be >= 1 (substeps 0: "
                                "automatic), and only one of them above 1", d->pd_substeps, d->pd_every);
    if (d->adaptive) {
        const char *bad = NULL;
        if (!(d->adapt_velocity_tol > 0) || !isfinite(d->adapt_velocity_tol)) bad = "velocity tolerance must be > 0";
        else if (!(d->adapt_depth_tol > 0) || !isfinite(d->adapt_depth_tol)) bad = "penetration tolerance must be > 0";
        else if (!(d->dt_min >= 0) || !isfinite(d->dt_min)) bad = "dt_min must be >= 0 (0 = automatic)";
        else if (!(d->dt_max >= 0) || !isfinite(d->dt_max)) bad = "dt_max must be >= 0 (0 = automatic)";
        if (bad) return floe_world_error(w, FLOE_EINVAL, "adaptive steps: %s", bad);
    }
    const int st = stag && w->npd > 0;
    double crit = st && isfinite(e->critical_contact) ? e->critical_contact : e->critical;
    const char *what = st && isfinite(e->critical_contact) ? "the contact critical estimate" : "the critical estimate";
    int lk = st && isfinite(e->critical_contact) ? (e->dt[FLOE_DT_CONTACT_PACKING] == crit ? FLOE_DT_CONTACT_PACKING
                                                    : e->dt[FLOE_DT_CONTACT_IMPACT] == crit ? FLOE_DT_CONTACT_IMPACT
                                                                                              : FLOE_DT_MOTION)
                                                 : e->limiting;
    crit *= ic->dt_factor; /* the class's stable step in critical estimates (1 for every explicit one) */
    if (d->dt > 0) {
        w->dt = d->dt;
        if (isfinite(crit) && w->dt > crit && !d->allow_unstable_dt)
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "time step %g s is above %s %g s (%s, particle %d); use a smaller dt, dt: auto "
                                    "(automatic), or allow_unstable_dt: true",
                                    w->dt, what, crit, lk >= 0 ? floe_dt_kind_name(lk) : "?",
                                    lk >= 0 ? e->particle[lk] : -1);
    } else {
        if (!isfinite(crit))
            return floe_world_error(w, FLOE_EINVAL, "automatic time step: no contact law to estimate it from; give dt");
        w->dt = d->dt_safety * crit;
        if (d->accuracy > 0 && e->accuracy_dt < w->dt) w->dt = e->accuracy_dt; /* time.accuracy */
    }
    w->dte.predicted_error = fmax(e->err1 * w->dt, e->err2 * w->dt * w->dt);
    w->pd_sub = w->pd_every = 1;
    if (st) {
        const double pdc = e->critical_pd;
        int sub = d->pd_substeps, every = d->pd_every > 0 ? d->pd_every : 1;
        if (sub == 0) { /* automatic: the integer ratio of the two critical steps */
            sub = 1;
            if (isfinite(pdc) && every == 1) {
                if (w->dt > d->dt_safety * pdc) sub = (int)ceil(w->dt / (d->dt_safety * pdc) - 1e-9);
                else every = (int)fmax(1.0, floor(d->dt_safety * pdc / w->dt + 1e-9));
            }
        }
        if (sub > 100000 || every > 100000)
            return floe_world_error(w, FLOE_EINVAL, "staggered PD-DEM: ratio %d out of range (at most 100000)", sub > every ? sub : every);
        double dpd = every > 1 ? every * w->dt : w->dt / sub;
        if (isfinite(pdc) && dpd > pdc && !d->allow_unstable_dt)
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "staggered PD-DEM: the PD step %g s (dt %g s %s %d) is above the PD critical estimate "
                                    "%g s (pd_nodal, particle %d); raise substeps, lower every or dt, or allow_unstable_dt: true",
                                    dpd, w->dt, every > 1 ? "x" : "/", every > 1 ? every : sub, pdc,
                                    e->particle[FLOE_DT_PD_NODAL]);
        w->pd_sub = sub;
        w->pd_every = every;
    }
    w->st.pd_substeps = w->pd_sub;
    w->st.pd_every = w->pd_every;
    if (d->adaptive) {
        w->dt_hi = d->dt_max > 0 ? d->dt_max : crit;
        if (!isfinite(w->dt_hi))
            return floe_world_error(w, FLOE_EINVAL, "adaptive steps: no critical estimate to bound the step; give dt_max");
        if (d->dt_max > 0 && isfinite(crit) && d->dt_max > crit && !d->allow_unstable_dt)
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "adaptive steps: dt_max %g s is above the critical estimate %g s; lower it, or "
                                    "allow_unstable_dt: true", d->dt_max, crit);
        w->dt_lo = d->dt_min > 0 ? d->dt_min : 1e-3 * w->dt_hi;
        if (w->dt_lo > w->dt_hi)
            return floe_world_error(w, FLOE_EINVAL, "adaptive steps: dt_min %g s is above dt_max %g s", w->dt_lo, w->dt_hi);
        w->dt = fmin(w->dt_hi, fmax(w->dt_lo, w->dt));
        w->dt_next = w->dt;
    }
    return FLOE_OK;
}

int floe_world_prepare(floe_world *w) {
    if (w->prepared) return FLOE_OK;
    /* a split world is prepared once, before the split (the setters that would need more
     * refuse on it: floe_world_refuse_split); its ranks would not agree on a second */
    if (w->par)
        return floe_world_error(w, FLOE_ENOTSUP, "prepare: the world is split over MPI ranks and is prepared once, "
                                "before floe_world_parallel_init; a change since then asked for another");
    w->err[0] = 0;
    FLOE_TRY(prepare_store(w));
    FLOE_TRY(floe_world_hist_layout(w)); /* the list's history stride, for these laws and shapes */
    FLOE_TRY(choose_dt(w));
    FLOE_TRY(floe_cell_prepare(w)); /* a periodic cell's checks; the list sees its images */
    if (w->step == 0) w->lf_dt_prev = 0; /* leapfrog: the velocities given are synchronised */
    FLOE_TRY(prepare_state(w));
    int rc;
    {
        floe_step_ctx c0 = {&w->p, w->def.dim, 0, w->time, w->dt, 0.0, 0, w->record_contacts || w->obs_need_contacts, 0};
        rc = w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd ? stag_split_forces(w, &c0)
                                                               : floe_world_forces(w, &c0, FLOE_GROUP_ALL);
    }
    if (rc) return rc;
    {
        const floe_particles *p = &w->p;
        const int stag = w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd;
        const double *r = w->stag;
        prepare_ledger(w, stag ? shadow_energy(w, r + STAG_FS, r + STAG_TS, r + STAG_FPD, STAG_W)
                               : shadow_energy(w, p->f, p->t, NULL, 3));
    }
    return prepare_observers(w);
}

int floe_world_dt_estimates(floe_world *w, floe_dt_estimates *out) {
    if (!w->prepared) FLOE_TRY(floe_world_prepare(w));
    *out = w->dte;
    return FLOE_OK;
}
