/* adaptive.c - the adaptive controller (003 §4.3): a wrapper around the step of any
 * integrator class whose trial step can be undone (FLOE_INTEGRATOR_RESTORES, checked at
 * prepare by choose_dt): it saves the state (particles, state objects, the providers' own
 * state through their save/restore hooks, the ledger, the clock), takes the inner step,
 * and rejects and redoes it with a shorter step when the error measures pass their
 * tolerances. Nothing here names an integrator. */
#include "integrator_parts.h"
#include "floe_parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- adaptive steps (003 §4.3) ----
 * A trial step is taken from a saved state; it is accepted when
 *   eta_v = max_i |v_i(t+dt) - v_i(t)| dt / R_i <= adapt_velocity_tol  and
 *   eta_d = max_contacts |v_n| dt / min(R_i, R_j) <= adapt_depth_tol
 * (the velocity change and the overlap change over the step relative to the particle
 * size), else the state is restored and the step redone with a smaller dt (also when the
 * trial went unstable); the next step grows by the same criterion, at most 2x, within
 * [dt_min, dt_max]. A trial that rebuilt the neighbour list (the contact history changes
 * its layout) cannot be undone and is accepted: the list is rebuilt before a trial whose
 * drift could pass the skin. */

typedef struct floe_snapshot {
    double *d; size_t dcap;
    unsigned char *c; size_t ccap;
    floe_energy energy;
    double elastic_contact, elastic_pd, time, t0;
    double wd_shadow, wd_shadow0;
    long step, step0;
} floe_snapshot;

static void snapshot_free(floe_snapshot *s) {
    if (!s) return;
    free(s->d);
    free(s->c);
    free(s);
}

/* sizes of what a step changes: particle state (22 n), pair history, ledger memories,
 * PD forces and broken flags, state objects */
static void snapshot_sizes(const floe_world *w, size_t *nd, size_t *nc) {
    size_t d = 22 * (size_t)w->p.n;
    for (int s = 0; s < w->nstates; s++) d += w->states[s]->klass->size(w->states[s]);
    *nd = d;
    *nc = providers_state_size(w); /* contact history, bonds, the callbacks' last forces */
}

#define SNAP_COPY(save, a, b, nbytes) \
    do { if ((nbytes) > 0) { if (save) memcpy((a), (b), (nbytes)); else memcpy((b), (a), (nbytes)); } } while (0)

static int snapshot_io(floe_world *w, int save) {
    floe_snapshot *s = w->snap;
    floe_particles *p = &w->p;
    if (save) {
        size_t nd, nc;
        snapshot_sizes(w, &nd, &nc);
        if (nd > s->dcap) {
            double *d = realloc(s->d, nd * sizeof *d);
            if (!d) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            s->d = d;
            s->dcap = nd;
        }
        if (nc > s->ccap) {
            unsigned char *c = realloc(s->c, nc ? nc : 1);
            if (!c) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            s->c = c;
            s->ccap = nc;
        }
        s->energy = w->energy;
        s->elastic_contact = w->elastic_contact;
        s->elastic_pd = w->elastic_pd;
        s->wd_shadow = w->wd_shadow;
        s->wd_shadow0 = w->wd_shadow0;
        s->time = w->time;
        s->t0 = w->t0;
        s->step = w->step;
        s->step0 = w->step0;
    }
    double *d = s->d;
    unsigned char *c = s->c;
    const size_t n = (size_t)p->n;
    /* state objects first: set() may rescale a particle's mass, inertia and momentum,
     * which are restored after */
    for (int k = 0; k < w->nstates; k++) {
        floe_state *st = w->states[k];
        size_t m = st->klass->size(st);
        if (save) st->klass->get(st, d);
        else {
            int rc = st->klass->set(st, w, d);
            if (rc) return floe_world_error(w, rc, "state object %s could not be restored", st->klass->name);
        }
        d += m;
    }
    SNAP_COPY(save, d, p->x, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->v, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->q, 4 * n * sizeof *d); d += 4 * n;
    SNAP_COPY(save, d, p->L, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->w, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->f, 3 * n * sizeof *d); d += 3 * n;
    SNAP_COPY(save, d, p->t, 3 * n * sizeof *d); d += 3 * n;
    /* the providers' own state (floe_provider.h): what a step of each changes */
    providers_state_io(w, c, save);
    if (!save) {
        w->energy = s->energy;
        w->elastic_contact = s->elastic_contact;
        w->elastic_pd = s->elastic_pd;
        w->wd_shadow = s->wd_shadow;
        w->wd_shadow0 = s->wd_shadow0;
        w->time = s->time;
        w->t0 = s->t0;
        w->step = s->step;
        w->step0 = s->step0;
    }
    return FLOE_OK;
}

/* the largest displacement from the neighbour build that the next drift of dt can reach
 * (velocity Verlet and RK2 both move by dt (v + dt/2 F/m); a class that drifts otherwise
 * only moves the rebuild earlier or later, never past the skin unnoticed: the trial that
 * rebuilt is then accepted) */
static double predicted_disp2(const floe_world *w, double dt) {
    const floe_particles *p = &w->p;
    const double *xb = w->nl.x_build;
    if (!xb || w->nl.n_build != p->n) return INFINITY;
    double m2 = 0;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] == FLOE_FIXED) continue;
        double y[3];
        for (int k = 0; k < 3; k++)
            y[k] = p->x[3 * i + k] + dt * (p->v[3 * i + k] + 0.5 * dt * p->inv_mass[i] * p->f[3 * i + k]);
        note_disp(y, xb + 3 * i, &m2);
    }
    return m2;
}

int step_adaptive(floe_world *w, int (*inner)(floe_world *w)) {
    floe_particles *p = &w->p;
    const double tv = w->def.adapt_velocity_tol, td = w->def.adapt_depth_tol;
    if (!w->snap) {
        w->snap = calloc(1, sizeof *w->snap);
        int rc = w->snap ? FLOE_OK : floe_world_error(w, FLOE_ENOMEM, "out of memory");
        if (w->snap) w->snap_free = snapshot_free; /* the world frees it (floe_world_destroy) */
        /* MPI: every rank calls step_adaptive at its first step: agreed there (a rank that
         * returned alone would leave the others in the step's first collective); after a
         * failure no rank keeps one, so that a next step agrees again on every rank */
        if (w->par) rc = floe_par_agree_error(w, rc);
        if (rc) {
            if (w->snap) snapshot_free(w->snap);
            w->snap = NULL;
            return rc;
        }
    }
    for (;;) {
        double dt = fmin(w->dt_next, w->dt_cap);
        if (dt != w->dt) { /* the clock restarts from here at the new step */
            w->t0 = w->time;
            w->step0 = w->step;
            /* the watchdog's conserved form at the new step (the half kick grows as dt):
             * the same state, so its balance goes on continuously */
            double r2 = (dt / w->dt) * (dt / w->dt);
            w->wd_shadow0 += w->wd_shadow * (r2 - 1);
            w->wd_shadow *= r2;
            w->dt = dt;
        }
        double lim = 0.5 * w->nl.skin;
        /* MPI (docs/parallel.md, "Adaptive steps"): every rank decides alike, and a rebuild is a
         * decomposition (the particles may change owner) */
        double need = predicted_disp2(w, dt) > lim * lim;
        floe_par_max(w, &need, 1);
        if (need > 0) {
            int rc = w->par ? floe_world_parallel_rebuild(w) : floe_world_nl_build(w);
            if (rc) return w->par ? rc : floe_world_error(w, rc, "neighbour list rebuild failed (out of memory)");
        }
        /* the snapshot (MPI: its memory agreed, one allreduce a trial) */
        int src = snapshot_io(w, 1);
        if (w->par) src = floe_par_agree_error(w, src);
        if (src) return src;
        const long rb = w->nl.rebuilds;
        w->track_depth = 1;
        int rc = inner(w);
        w->track_depth = 0;
        /* MPI: a trial that failed on some ranks is redone as in one process when every rank
         * returned the failure with the state whole (w->err_agreed 1: a force evaluation's or
         * the closing checks' error, floe_par_agree_error); any other failure stops the run (a
         * rank that failed alone inside the step is not where the others wait) */
        if (rc && w->par && w->err_agreed != 1) return rc;
        double eta_v = 0, eta_d = w->eta_depth;
        /* MPI: a decomposition inside the trial (rare: the test above predicts the drift)
         * reordered the store, so the saved velocities no longer match; the trial is accepted
         * and the next step follows eta_d alone */
        if (!rc && !(w->par && w->nl.rebuilds != rb)) {
            const double *v0 = w->snap->d + 3 * (size_t)p->n; /* after x (states first) */
            size_t so = 0;
            for (int s = 0; s < w->nstates; s++) so += w->states[s]->klass->size(w->states[s]);
            v0 += so;
            for (int i = 0; i < p->n; i++) {
                if (p->motion[i] != FLOE_FREE || !isfinite(p->radius[i])) continue;
                double dv[3];
                floe_v3_sub(dv, p->v + 3 * i, v0 + 3 * i);
                double e = floe_v3_norm(dv) * dt / p->radius[i];
                if (e > eta_v) eta_v = e;
            }
        }
        /* MPI: whether any rank rebuilt, the largest measures over the ranks' owned particles
         * and contacts */
        double m[3] = {w->nl.rebuilds != rb, eta_v, eta_d};
        floe_par_max(w, m, 3);
        const int undoable = m[0] == 0;
        eta_v = m[1];
        eta_d = m[2];
        /* step factor from the criterion: eta_v grows as dt^2 (a dt^2), eta_d as dt */
        double fv = eta_v > 0 ? sqrt(tv / eta_v) : INFINITY, fd = eta_d > 0 ? td / eta_d : INFINITY;
        double f = 0.9 * fmin(fv, fd);
        const int at_min = dt <= w->dt_lo * (1 + 1e-9);
        if ((rc == FLOE_EUNSTABLE || (rc == FLOE_OK && (eta_v > tv || eta_d > td))) && undoable && !at_min) {
            /* (every rank redoes the trial: the decision is agreed above; a state's set()
             * that fails on one rank is agreed here) */
            int rrc = snapshot_io(w, 0);
            if (w->par) rrc = floe_par_agree_error(w, rrc);
            if (rrc) {
                if (w->par) w->err_agreed = 2; /* a rank stopped partway through its restore */
                return rrc;
            }
            w->st.rejected++;
            f = rc ? 0.25 : fmax(0.1, fmin(0.9, f));
            w->dt_next = fmax(w->dt_lo, dt * f);
            w->err[0] = 0;
            w->err_agreed = 0;
            continue;
        }
        if (rc) return rc;
        f = fmax(0.1, fmin(2.0, f));
        if (!(dt < w->dt_next) || f < 1) w->dt_next = fmin(w->dt_hi, fmax(w->dt_lo, dt * f));
        return FLOE_OK;
    }
}
