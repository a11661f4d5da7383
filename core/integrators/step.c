/* step.c - the steps: velocity Verlet, leapfrog, RK2, staggered PD-DEM (000 §3.2); the
 * rotation and kinematic helpers they share. The bottom of core/integrators: the classes
 * (integrators.c), the adaptive controller (adaptive.c), prepare (driver.c) and the
 * step/run loop with the energy watchdog (watchdog.c) call these, never the reverse. */
#include "integrator_parts.h"
#include "floe_par.h"

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
/* ---- rotation helpers ---- */

/* q <- exp(h omega / 2) q for a small turn a = |h omega| (every stable step): the series of
 * cos(a/2) and sin(a/2)/a to a^4, truncation below 1e-16 for a^2 < 1e-4, no trigonometry
 * (profile of 5,000 polyhedra: sincos was 3 % and q_advance 6 % of the run), then one
 * Newton step for 1/sqrt to keep |out| = 1. Returns 1 when the turn is not small (out is
 * then not the rotation: q_advance takes the exact one); no branch, so that a loop over
 * bodies (aniso_lanes) vectorises */
static inline __attribute__((always_inline)) int q_advance_small(double out[4], const double q[4], const double om[3],
                                                                  double h) {
    const double th[3] = {h * om[0], h * om[1], h * om[2]};
    const double a2 = floe_v3_dot(th, th);
    const double c = 1.0 - a2 * (0.125 - a2 * (1.0 / 384.0)), s = 0.5 - a2 * (1.0 / 48.0 - a2 * (1.0 / 3840.0));
    const double dq[4] = {c, s * th[0], s * th[1], s * th[2]};
    floe_q_mul(out, dq, q);
    const double n2 = out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3];
    const double sc = 1.5 - 0.5 * n2;
    for (int k = 0; k < 4; k++) out[k] *= sc;
    return !(a2 < 1e-4);
}

/* q <- exp(h omega / 2) q, i.e. rotate by the vector h*omega */
static void q_advance(double out[4], const double q[4], const double om[3], double h) {
    if (!q_advance_small(out, q, om, h)) return;
    const double th[3] = {h * om[0], h * om[1], h * om[2]};
    double dq[4];
    floe_q_from_rotvec(dq, th);
    floe_q_mul(out, dq, q);
    floe_q_normalize(out);
}

/* ---- the step ---- */

/* motion callback of particle i: an index particle -> callback, rebuilt when callbacks or
 * particles were added (a linear scan per particle would cost O(k^2) per step for k
 * ramped PD boundary points), and on a world split over MPI ranks after each decomposition
 * (core/parallel sets motion_idx_n to -1: a callback's particle is found by its global id
 * on the rank that owns it now); the first callback set for a particle wins */
static int motion_local(const floe_world *w, int k) {
    return w->nl.gid ? floe_world_local_of(w, w->motions[k].gid, 0) : w->motions[k].particle;
}

static int motion_of(floe_world *w, int i) {
    if (w->motion_idx_n != w->p.n || w->motion_idx_cnt != w->nmotions) {
        int *t = realloc(w->motion_idx, (size_t)(w->p.n > 0 ? w->p.n : 1) * sizeof *t);
        if (!t) { /* out of memory: fall back to the scan */
            for (int k = 0; k < w->nmotions; k++)
                if (motion_local(w, k) == i) return k;
            return -1;
        }
        w->motion_idx = t;
        for (int k = 0; k < w->p.n; k++) t[k] = -1;
        for (int k = w->nmotions - 1; k >= 0; k--) {
            int pi = motion_local(w, k);
            if (pi >= 0 && pi < w->p.n) t[pi] = k;
        }
        w->motion_idx_n = w->p.n;
        w->motion_idx_cnt = w->nmotions;
    }
    return w->motion_idx[i];
}

static void kinematic_velocity(floe_world *w, int i, double t) {
    int k = motion_of(w, i);
    if (k < 0) return;
    w->motions[k].fn(t, w->p.v + 3 * i, w->p.w + 3 * i, w->motions[k].user);
    if (w->def.dim == 2) { w->p.v[3 * i + 2] = 0; w->p.w[3 * i] = w->p.w[3 * i + 1] = 0; }
}

/* End of a step for kinematic particle i: the work it did on the others over the step,
 * -(F_old + F_new)/2 . v_half dt (the trapezoid rule of velocity Verlet, as for the
 * contacts; h = dt/2), then its prescribed velocity at the new time. */
static double kinematic_close(floe_world *w, int i, double h) {
    const floe_particles *p = &w->p;
    const double *fo = w->kin_old + 6 * i;
    double wb = 0;
    for (int k = 0; k < 3; k++)
        wb -= h * ((fo[k] + p->f[3 * i + k]) * p->v[3 * i + k] + (fo[3 + k] + p->t[3 * i + k]) * p->w[3 * i + k]);
    kinematic_velocity(w, i, w->time);
    return wb;
}

/* floe_world_forces(groups), its failure agreed under MPI. pre (MPI): this rank failed since
 * the last agreement, its message set; it evaluates all the same (a stage may hold a
 * collective) and tells the others. A rank whose evaluation failed (a contact too deep, a
 * law's error) tells the others before the reverse sum, where they would wait for it: every
 * rank returns the error. A rank whose own evaluation passed then puts back what the
 * evaluation booked at its end (the tail of floe_world_forces: the elastic energies, the
 * dissipation, the boundary work, the counts, whether the contacts are valid), as one process
 * books none of that from an evaluation that failed; before, those parts of the failed
 * evaluation were in the written energies (an LPS body's elastic energy 2e-10 to 2e-8 of the
 * run's energy off at -np 3, depending on the cut). The body forces' work, booked as their
 * stage runs (first), stays as one process keeps it when a later stage fails; when the
 * stage before it fails (the dashpot's buffers out of memory), one process books none and
 * the ranks keep theirs. This rank's force time is booked (its own work, for the balance). */
static int forces_agreed(floe_world *w, const floe_step_ctx *c, int groups, int pre) {
    const double t0 = w->par ? floe_par_clock() : 0.0;
    char why[sizeof w->err];
    if (pre) memcpy(why, w->err, sizeof why);
    const double el0 = w->energy.elastic, dis0 = w->energy.dissipated, wb0 = w->energy.work_boundary;
    const double ec0 = w->elastic_contact, ep0 = w->elastic_pd;
    const long fe0 = w->st.force_evaluations, pe0 = w->st.pd_evaluations;
    const int cv0 = w->contacts_valid;
    const int own = floe_world_forces(w, c, groups);
    int rc = own;
    if (pre) {
        rc = pre;
        memcpy(w->err, why, sizeof why);
    }
    if (!w->par) return rc;
    floe_par_force_time(w, floe_par_clock() - t0);
    rc = floe_par_agree_error(w, rc);
    if (rc && !own) {
        w->energy.elastic = el0;
        w->energy.dissipated = dis0;
        w->energy.work_boundary = wb0;
        w->elastic_contact = ec0;
        w->elastic_pd = ep0;
        w->st.force_evaluations = fe0;
        w->st.pd_evaluations = pe0;
        w->contacts_valid = cv0;
    }
    return rc;
}

/* every provider's forces on every particle (forces_agreed); under MPI the ghosts' forces are
 * then summed to their owners and the servo walls take their whole forces */
static int forces_all(floe_world *w, floe_step_ctx *c, int pre) {
    int rc = forces_agreed(w, c, FLOE_GROUP_ALL, pre);
    if (!rc && w->par) rc = floe_par_reverse(w);
    if (!rc && w->par) rc = floe_par_servo_totals(w);
    return rc;
}

/* the outcome of a step's close (its kick and checks, after its last collective): under MPI
 * agreed by every rank, each rank calling this once on its way out, failed or not
 * (floe_par_agree_error: the ranks that did not fail return the failing rank's error). With
 * w->close_defer (floe_world_step: a fixed step of velocity Verlet or leapfrog, the energy
 * watchdog on) the agreement is the watchdog's reduction right after the step
 * (floe_par_watchdog_values): this rank's outcome is kept and returned as it is, every rank
 * then agreeing on it there (nothing collective lies between: the close is the step's last
 * collective point) */
static int step_close(floe_world *w, int rc) {
    if (!w->par) return rc;
    if (w->close_defer) {
        if (!w->close_pending || !w->close_rc) w->close_rc = rc; /* (one close a step) */
        w->close_pending = 1;
        w->close_energy = w->energy; /* put back if another rank failed (floe_world_step) */
        w->close_shadow = w->wd_shadow;
        w->close_lf = w->lf_dt_prev;
        return rc;
    }
    return floe_par_agree_error(w, rc);
}

/* forces at the end of a step, with the history and the ledger advancing */
static int forces_advancing(floe_world *w) {
    floe_step_ctx c = ctx_step(w, contacts_wanted(w));
    return forces_all(w, &c, FLOE_OK);
}

/* 1 when check_particle below fails for particle i (its conditions, without the message):
 * for the threaded loops, which call it only for the particles this says fail */
static int particle_fails(const floe_particles *p, int i, const double xold[3]) {
    const double *x = p->x + 3 * i, *v = p->v + 3 * i, *om = p->w + 3 * i;
    for (int k = 0; k < 3; k++)
        if (!isfinite(x[k]) || !isfinite(v[k]) || !isfinite(om[k])) return 1;
    double d[3];
    floe_v3_sub(d, x, xold);
    return floe_v3_norm(d) > 0.5 * p->radius[i];
}

static int check_particle(floe_world *w, int i, const double xold[3]) {
    floe_particles *p = &w->p;
    const double *x = p->x + 3 * i, *v = p->v + 3 * i, *om = p->w + 3 * i;
    for (int k = 0; k < 3; k++)
        if (!isfinite(x[k]) || !isfinite(v[k]) || !isfinite(om[k]))
            return floe_world_error(w, FLOE_EUNSTABLE,
                                    "unstable: particle %lld (body %d) has a non-finite %s at step %ld, t = %g s "
                                    "(force %g %g %g N)",
                                    floe_world_pid(w, i), p->group[i], !isfinite(x[k]) ? "position" : !isfinite(v[k]) ? "velocity" : "angular velocity",
                                    w->step, w->time, p->f[3 * i], p->f[3 * i + 1], p->f[3 * i + 2]);
    double d[3];
    floe_v3_sub(d, x, xold);
    double moved = floe_v3_norm(d);
    if (moved > 0.5 * p->radius[i])
        return floe_world_error(w, FLOE_EUNSTABLE,
                                "unstable: particle %lld (body %d) moved %.3g of its radius in one step at step %ld, "
                                "t = %g s (speed %g m/s): the time step %g s is too large for the contact stiffness "
                                "or the velocities",
                                floe_world_pid(w, i), p->group[i], moved / p->radius[i], w->step, w->time, floe_v3_norm(v), w->dt);
    return FLOE_OK;
}

/* omega of free particle i from its angular momentum */
static inline void omega_update(floe_particles *p, int i) {
    if (p->iso[i]) {
        const double inv = p->inv_iso[i];
        for (int k = 0; k < 3; k++) p->w[3 * i + k] = p->L[3 * i + k] * inv;
    } else floe_omega_from_L(p->q + 4 * i, p->inertia + 3 * i, p->L + 3 * i, p->w + 3 * i);
}

/* omega = R diag(inv) R^T L (floe_omega_from_L with the moments' inverses taken once: five
 * calls a step made fifteen divisions, a chain of latencies in a settled bed's profile) */
static inline __attribute__((always_inline)) void omega_inv(const double q[4], const double inv[3], const double L[3],
                                                             double om[3]) {
    double Lb[3];
    floe_q_rotate_inv(Lb, q, L);
    for (int k = 0; k < 3; k++) Lb[k] *= inv[k];
    floe_q_rotate(om, q, Lb);
}

/* the orientation q of an anisotropic free body (principal moments I) over dt with its
 * angular momentum L: the midpoint rule of eq 23 by two fixed-point passes; om <- omega */

static void rotate_drift_aniso(double *q, const double *I, const double *L, double *om, double dt) {
    const double h = 0.5 * dt;
    double qm[4], omm[3], qn[4], inv[3];
    for (int k = 0; k < 3; k++) inv[k] = I[k] > 0 && isfinite(I[k]) ? 1.0 / I[k] : 0;
    omega_inv(q, inv, L, omm);
    q_advance(qm, q, omm, h);
    for (int it = 0; it < 2; it++) {
        omega_inv(qm, inv, L, omm);
        q_advance(qm, q, omm, h);
    }
    omega_inv(qm, inv, L, omm);
    q_advance(qn, q, omm, dt);
    memcpy(q, qn, sizeof qn);
    omega_inv(q, inv, L, om);
}

/* the orientation of an isotropic free body (1/I = inv) over dt = 2h (eq 23 as the midpoint
 * rule of step_verlet): om <- L / I, q <- exp(dt omega / 2) q without trig, inlined into the
 * particle loop: as a called function (AVX stack realignment, omega and q through memory)
 * it took a third of a 20,000-sphere step; inlined, the 2,000-step bench/dem-settle dropped
 * from 2.85 to 2.1 s of user time (watchdog off, 2026-12-02) */
static inline __attribute__((always_inline)) void rotate_drift_iso(double *q, const double *L, double *om, double inv,
                                                                   double h) {
    for (int k = 0; k < 3; k++) om[k] = L[k] * inv;
    double th[3] = {h * om[0], h * om[1], h * om[2]}, t2 = floe_v3_dot(th, th);
    if (t2 > 0) {
        double c = 1 - 0.5 * t2, dq[4] = {c, th[0], th[1], th[2]}, qn[4];
        floe_q_mul(qn, dq, q);
        double s2 = qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3];
        double sc = 1.5 - 0.5 * s2;
        for (int k = 0; k < 4; k++) q[k] = qn[k] * sc;
    }
}

/* the orientation of free particle i over dt */
static inline void rotate_drift(floe_particles *p, int i, double dt) {
    double *q = p->q + 4 * i, *L = p->L + 3 * i, *om = p->w + 3 * i;
    if (p->iso[i] == 2) for (int k = 0; k < 3; k++) om[k] = L[k] * p->inv_iso[i]; /* orientation unread */
    else if (p->iso[i]) rotate_drift_iso(q, L, om, p->inv_iso[i], 0.5 * dt);
    else if (floe_v3_dot(L, L) > 0) rotate_drift_aniso(q, p->inertia + 3 * i, L, om, dt);
}

/* state objects over the step, RK2 midpoint (eq 21) */
static int advance_states(floe_world *w, double dt) {
    const double h = 0.5 * dt;
    for (int s = 0; s < w->nstates; s++) {
        floe_state *st = w->states[s];
        size_t m = st->klass->size(st);
        double buf[64];
        double *y0 = m <= 16 ? buf : malloc(4 * m * sizeof(double));
        if (!y0) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        double *k1 = y0 + m, *ym = y0 + 2 * m, *k2 = y0 + 3 * m;
        w->err[0] = 0;
        st->klass->get(st, y0);
        int rc = st->klass->rhs(st, w, w->time, y0, k1);
        for (size_t a = 0; a < m && !rc; a++) ym[a] = y0[a] + h * k1[a];
        if (!rc) rc = st->klass->rhs(st, w, w->time + h, ym, k2);
        for (size_t a = 0; a < m && !rc; a++) ym[a] = y0[a] + dt * k2[a];
        if (!rc) rc = st->klass->set(st, w, ym);
        if (y0 != buf) free(y0);
        if (rc) { /* keep the state's own reason */
            char why[sizeof w->err];
            memcpy(why, w->err, sizeof why);
            return floe_world_error(w, rc, "state object %s failed at step %ld: %s", st->klass->name, w->step,
                                    why[0] ? why : floe_strerror(rc));
        }
    }
    return FLOE_OK;
}

/* State objects may change masses in a step (a growing radius with update_mass). Gravity's
 * work over the step is booked with m_n at the drift, but the velocity the step gives is that
 * of the force m_{n+1} g at its end (velocity Verlet's second half kick, the staggered
 * scheme's) or of m_mid g (RK2's midpoint probe): the work is dt (m_n + m_{n+1})/2 g . v to
 * second order (booked with m_n it is first order). growth_masses keeps m_n of the n
 * particles before the states (in the integrators' scratch at doubles [off, off + n); NULL
 * without state objects or gravity, or out of memory: *rc set); growth_gravity_work is the
 * missing half of (m_{n+1} - m_n) dt g . v over the free particles (v: the velocity the
 * states saw, the step's middle one), skipping the staggered scheme's sub-cycled PD points
 * (pd_of, NULL: none; a growing PD point that sub-cycles is not booked: untested). */
static double *ibuf_reserve(floe_world *w, size_t nd);
static double *growth_masses(floe_world *w, int n, size_t off, int *rc) {
    const double *g = w->def.gravity;
    if (!w->nstates || *rc || (g[0] == 0 && g[1] == 0 && g[2] == 0)) return NULL;
    double *b = ibuf_reserve(w, off + (size_t)(n ? n : 1));
    if (!b) {
        *rc = floe_world_error(w, FLOE_ENOMEM, "out of memory");
        return NULL;
    }
    memcpy(b + off, w->p.mass, (size_t)n * sizeof *b);
    return b + off;
}
static double growth_gravity_work(const floe_world *w, const double *mn, int n, double dt, const int *pd_of) {
    const floe_particles *p = &w->p;
    double wb = 0;
    for (int i = 0; i < n; i++) {
        const double dm = p->mass[i] - mn[i];
        if (dm == 0 || p->motion[i] != FLOE_FREE || (pd_of && pd_of[i] >= 0)) continue;
        wb += 0.5 * dt * dm * floe_v3_dot(w->def.gravity, p->v + 3 * i);
    }
    return wb;
}

/* The state objects at the RK2 midpoint for its force evaluation (floe_state_class.probe:
 * y_mid = y_n + dt/2 f(t_n, y_n), the step's own first stage), and (undo) put back; a state
 * without a probe stays at y_n there */
static int state_probes(const floe_state *st) { return st->klass->version >= 2 && st->klass->probe; }
static int probe_states(floe_world *w, double h, int undo) {
    int rc = FLOE_OK;
    if (undo) { /* in reverse: two states on one particle put back what each found */
        for (int s = w->nstates - 1; s >= 0; s--)
            if (state_probes(w->states[s])) w->states[s]->klass->probe(w->states[s], w, NULL);
        return FLOE_OK;
    }
    for (int s = 0; s < w->nstates; s++) {
        floe_state *st = w->states[s];
        if (!state_probes(st)) continue;
        size_t m = st->klass->size(st);
        double buf[32];
        double *y = m <= 16 ? buf : malloc(2 * m * sizeof(double));
        w->err[0] = 0;
        if (!y) rc = floe_world_error(w, FLOE_ENOMEM, "out of memory");
        else {
            double *k1 = y + m;
            st->klass->get(st, y);
            rc = st->klass->rhs(st, w, w->time, y, k1);
            for (size_t a = 0; a < m && !rc; a++) y[a] += h * k1[a];
            if (!rc) rc = st->klass->probe(st, w, y);
            if (y != buf) free(y);
        }
        if (rc) { /* the probed ones back; the state's own reason kept */
            char why[sizeof w->err];
            memcpy(why, w->err, sizeof why);
            for (int u = s - 1; u >= 0; u--)
                if (state_probes(w->states[u])) w->states[u]->klass->probe(w->states[u], w, NULL);
            return floe_world_error(w, rc, "state object %s failed at the RK2 midpoint of step %ld: %s",
                                    st->klass->name, w->step, why[0] ? why : floe_strerror(rc));
        }
    }
    return rc;
}

/* the states over the step, unless this rank failed since the step's last agreement (pre,
 * its message set: MPI only, where the failing rank goes on to the next agreement); under MPI
 * with state objects the outcome is agreed here by every rank (a state's callback may fail on
 * one rank alone); without them it is pre, for the rebuild test to tell every rank. A caller
 * returns a failure at once in one process or when agreed here (states_done) */
static int states_step(floe_world *w, double dt, int pre) {
    int rc = pre ? pre : advance_states(w, dt);
    return w->par && w->nstates ? floe_par_agree_error(w, rc) : rc;
}
static int states_done(const floe_world *w, int rc) { return rc && (!w->par || w->nstates); }

/* the integrators' scratch: at least nd doubles (contents kept when it grows) */
static double *ibuf_reserve(floe_world *w, size_t nd) {
    if (nd <= w->ibuf_cap) return w->ibuf;
    double *b = realloc(w->ibuf, nd * sizeof *b);
    if (!b) return NULL;
    w->ibuf = b;
    w->ibuf_cap = nd;
    return b;
}

/* step counter and time after a step (no drift from repeated sums) */
static void advance_clock(floe_world *w) {
    w->step++;
    w->time = w->t0 + (double)(w->step - w->step0) * w->dt;
}

/* the clock back by a step: a failure that one process returns before advance_clock and MPI
 * tells every rank at the rebuild test after it (floe_par_refresh's told) */
static void retreat_clock(floe_world *w) {
    w->step--;
    w->time = w->t0 + (double)(w->step - w->step0) * w->dt;
}

/* rc: this rank's failure since the step's last agreement (MPI: told to every rank by the
 * rebuild test; one process: returned); flag (or NULL), MPI: this rank's flag in, whether
 * any rank's was set out (floe_par_refresh) */
static int rebuild_if_needed(floe_world *w, double maxd2, int have_xb, int rc, int *flag) {
    if (w->par) { /* MPI: all ranks, ghosts (core/parallel) */
        int told = 0;
        rc = floe_par_refresh(w, maxd2, have_xb, NULL, rc, flag, &told);
        if (told) retreat_clock(w);
        return rc;
    }
    if (rc) return rc;
    /* a law set since the build: pairs under the law "none" were left out (neighbor.c) */
    if (w->law_gen != w->nl_law_gen || (w->cell ? floe_nl_needs_rebuild_cell(&w->nl, &w->p)
                : floe_nl_needs_rebuild_after_drift(&w->nl, &w->p, maxd2, !have_xb || w->nstates > 0))) {
        int rc = floe_world_nl_build(w);
        if (rc) return floe_world_error(w, rc, "neighbour list rebuild failed (out of memory)");
    }
    return FLOE_OK;
}

/* Velocity Verlet (ParticLS eq 22) and leapfrog (000 eq 44). Leapfrog keeps v_{n-1/2}:
 * its one kick per step v_{n+1/2} = v_{n-1/2} + dt a_n is velocity Verlet's two half kicks
 * merged, so both follow the same trajectory (to rounding); they differ in the velocity
 * they store (leapfrog: half a step behind the positions, as in the paper).
 * The free particles' loops read the store through restrict pointers (nothing else in the
 * loop writes it: kinematic particles, whose callbacks see the world, have their own loops),
 * so the compiler keeps a particle's state in registers instead of reloading it after every
 * store to another array. */
/* velocity Verlet's first half kick and drift of the free particles [i0, i1) (one block,
 * floe_par.h); returns their body-force work, raises *maxd2 (the largest squared
 * displacement since the list build) and sets *kin when a kinematic particle is met */
/* the quick checks of a drift by dt at velocity v to position x (radius r): moved more than
 * half the radius, or a position not finite (NaN fails every comparison): 1 = failed */
static inline int drift_failed(const double v[3], const double x[3], double r, double dt) {
    const double d2 = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * (dt * dt), lim = 0.5 * r;
    return !(d2 <= lim * lim) | !(fabs(x[0]) + fabs(x[1]) + fabs(x[2]) < INFINITY);
}

/* Runs of round particles in lanes (drift_block, kick_block): a run of IL free particles
 * whose omega is L / I (iso) takes its per-particle operations in loops over the run that
 * the compiler vectorises; the sums (work, energies) and the checks' first failures then
 * come in particle order from the lanes' arrays, so the bits are those of one particle
 * after the other. Spheres are most of a granular scene: the two loops were a third of a
 * falling dem-settle bed's step. run_len: how many of the IL particles from i are free and
 * isotropic (with the iso flag of particle i, if same), up to the first that is not. */
#define IL 16
static inline int run_len(const unsigned char *MO, const unsigned char *iso, int i, int same) {
    const unsigned char s = iso[i];
    int q = 0;
    while (q < IL && MO[i + q] == FLOE_FREE && iso[i + q] != 0 && (!same || iso[i + q] == s)) q++;
    return q;
}

/* the free anisotropic bodies from i, at most IL (kick_lanes_aniso) */
static inline int aniso_len(const unsigned char *MO, const unsigned char *iso, int i) {
    int q = 0;
    while (q < IL && MO[i + q] == FLOE_FREE && iso[i + q] == 0) q++;
    return q;
}

typedef struct drift_args {
    double k1, dt, h, g[3];
    const double *xb; /* positions at the list build (NULL: none) */
    int clear;        /* the free particles' forces to m g and torques to 0 once read (the force
                         evaluation's clearing of them, forces_clear: w->drift_cleared) */
    double *da;       /* clear: their accelerations f / m into dash_a first (NULL: not wanted) */
} drift_args;
/* drift_block's isotropic case for a run of IL particles, in lanes (the arrays from the run's
 * first particle): the body-force work, the squared displacement since the list build (XB;
 * NULL: 0) and the quick checks per particle, for the caller to take in order; Q (iso 1:
 * the orientation read; NULL for iso 2) advanced as rotate_drift_iso does, its operations in
 * their order and its branch (no turn: q untouched, not renormalised) a select. Not the same
 * bits as the scalar case in every digit: GCC 12's basic-block vectoriser fuses the scalar
 * case's quaternion product into a vfmaddsub (a fused multiply-add, against ISO C's
 * -ffp-contract=off), which drift_lanes_rot is kept from doing (no-tree-slp-vectorize): a
 * turning particle's orientation may differ in the last digit from before (session 14). */
static inline __attribute__((always_inline)) void drift_lanes_body(
    double *restrict X, double *restrict V, double *restrict W, double *restrict LL, double *restrict F,
    double *restrict T, const double *restrict IM, const double *restrict M, const double *restrict II,
    const double *restrict R, const double *restrict XB, const drift_args *a, double *restrict WB,
    double *restrict D2, int *restrict FB, double *restrict Q, const int rot, double *restrict DA) {
    const double k1 = a->k1, dt = a->dt, h = a->h, g0 = a->g[0], g1 = a->g[1], g2 = a->g[2];
    double TH[3][IL];
    for (int q = 0; q < IL; q++) {
        const double im = IM[q], ii = II[q];
        /* the loops over k of the scalar case, written out */
        const double v0 = V[3 * q] + k1 * im * F[3 * q], v1 = V[3 * q + 1] + k1 * im * F[3 * q + 1],
                     v2 = V[3 * q + 2] + k1 * im * F[3 * q + 2];
        const double x0 = X[3 * q] + dt * v0, x1 = X[3 * q + 1] + dt * v1, x2 = X[3 * q + 2] + dt * v2;
        const double L0 = LL[3 * q] + k1 * T[3 * q], L1 = LL[3 * q + 1] + k1 * T[3 * q + 1],
                     L2 = LL[3 * q + 2] + k1 * T[3 * q + 2];
        const double v[3] = {v0, v1, v2}, x[3] = {x0, x1, x2};
        FB[q] = drift_failed(v, x, R[q], dt);
        V[3 * q] = v0; V[3 * q + 1] = v1; V[3 * q + 2] = v2;
        X[3 * q] = x0; X[3 * q + 1] = x1; X[3 * q + 2] = x2;
        LL[3 * q] = L0; LL[3 * q + 1] = L1; LL[3 * q + 2] = L2;
        W[3 * q] = L0 * ii; W[3 * q + 1] = L1 * ii; W[3 * q + 2] = L2 * ii;
        WB[q] = dt * (M[q] * (g0 * v0 + g1 * v1 + g2 * v2));
        TH[0][q] = h * (L0 * ii); /* rotate_drift_iso's theta = h omega */
        TH[1][q] = h * (L1 * ii);
        TH[2][q] = h * (L2 * ii);
    }
    if (a->clear) { /* as forces_clear: the same operations (the lines are in the cache now) */
        if (DA)
            for (int q = 0; q < IL; q++)
                for (int k = 0; k < 3; k++) DA[3 * q + k] = F[3 * q + k] * IM[q];
        for (int q = 0; q < IL; q++) {
            F[3 * q] = M[q] * g0; F[3 * q + 1] = M[q] * g1; F[3 * q + 2] = M[q] * g2;
            T[3 * q] = T[3 * q + 1] = T[3 * q + 2] = 0.0;
        }
    }
    if (rot) {
        /* the orientations into arrays by component, advanced, and back: three loops the
         * compiler vectorises (one loop over Q's groups of four it did not) */
        double B[4][IL], O[4][IL];
        for (int q = 0; q < IL; q++)
            for (int k = 0; k < 4; k++) B[k][q] = Q[4 * q + k];
        for (int q = 0; q < IL; q++) {
            /* rotate_drift_iso: q <- exp(theta) q to second order, then renormalised to first */
            const double t0 = TH[0][q], t1 = TH[1][q], t3 = TH[2][q];
            const double t2 = t0 * t0 + t1 * t1 + t3 * t3, c = 1 - 0.5 * t2;
            const double b0 = B[0][q], b1 = B[1][q], b2 = B[2][q], b3 = B[3][q];
            const double qw = c * b0 - t0 * b1 - t1 * b2 - t3 * b3, qx = c * b1 + t0 * b0 + t1 * b3 - t3 * b2,
                         qy = c * b2 - t0 * b3 + t1 * b0 + t3 * b1, qz = c * b3 + t0 * b2 - t1 * b1 + t3 * b0;
            const double s2 = qw * qw + qx * qx + qy * qy + qz * qz, sc = 1.5 - 0.5 * s2;
            O[0][q] = t2 > 0 ? qw * sc : b0;
            O[1][q] = t2 > 0 ? qx * sc : b1;
            O[2][q] = t2 > 0 ? qy * sc : b2;
            O[3][q] = t2 > 0 ? qz * sc : b3;
        }
        for (int q = 0; q < IL; q++)
            for (int k = 0; k < 4; k++) Q[4 * q + k] = O[k][q];
    }
    if (XB)
        for (int q = 0; q < IL; q++) {
            const double dx = X[3 * q] - XB[3 * q], dy = X[3 * q + 1] - XB[3 * q + 1], dz = X[3 * q + 2] - XB[3 * q + 2];
            D2[q] = dx * dx + dy * dy + dz * dz;
        }
    else
        for (int q = 0; q < IL; q++) D2[q] = 0.0;
}
/* the two cases each in its own function (a test of Q inside the loop kept it scalar) */
#define DRIFT_LANES_ARGS                                                                                             \
    double *restrict X, double *restrict V, double *restrict W, double *restrict LL, double *restrict F,          \
        double *restrict T, const double *restrict IM, const double *restrict M, const double *restrict II,       \
        const double *restrict R, const double *restrict XB, const drift_args *a, double *restrict WB,            \
        double *restrict D2, int *restrict FB, double *restrict DA
static __attribute__((noinline)) void drift_lanes(DRIFT_LANES_ARGS) {
    drift_lanes_body(X, V, W, LL, F, T, IM, M, II, R, XB, a, WB, D2, FB, NULL, 0, DA);
}
#if defined(__clang__) /* GCC's optimize attribute; clang ignores it with a warning */
#define FLOE_NO_SLP
#else
#define FLOE_NO_SLP , optimize("no-tree-slp-vectorize")
#endif
static __attribute__((noinline FLOE_NO_SLP)) void drift_lanes_rot(DRIFT_LANES_ARGS, double *restrict Q) {
    drift_lanes_body(X, V, W, LL, F, T, IM, M, II, R, XB, a, WB, D2, FB, Q, 1, DA);
}
#undef DRIFT_LANES_ARGS

/* kick_block's isotropic case (velocity Verlet) for a run of IL particles, in lanes: the
 * kinetic energies and the shadow term's isotropic part per particle */
static __attribute__((noinline)) void kick_lanes(double *restrict V, double *restrict W, double *restrict LL,
                                                 const double *restrict F, const double *restrict T,
                                                 const double *restrict IM, const double *restrict M,
                                                 const double *restrict II, double h, double *restrict KE,
                                                 double *restrict KR, double *restrict SH) {
    for (int q = 0; q < IL; q++) {
        const double im = IM[q], ii = II[q];
        const double f0 = F[3 * q], f1 = F[3 * q + 1], f2 = F[3 * q + 2], t0 = T[3 * q], t1 = T[3 * q + 1],
                     t2 = T[3 * q + 2];
        SH[q] = im * (f0 * f0 + f1 * f1 + f2 * f2) + ii * (t0 * t0 + t1 * t1 + t2 * t2);
        const double v0 = V[3 * q] + h * im * f0, v1 = V[3 * q + 1] + h * im * f1, v2 = V[3 * q + 2] + h * im * f2;
        const double L0 = LL[3 * q] + h * t0, L1 = LL[3 * q + 1] + h * t1, L2 = LL[3 * q + 2] + h * t2;
        const double w0 = L0 * ii, w1 = L1 * ii, w2 = L2 * ii;
        V[3 * q] = v0; V[3 * q + 1] = v1; V[3 * q + 2] = v2;
        LL[3 * q] = L0; LL[3 * q + 1] = L1; LL[3 * q + 2] = L2;
        W[3 * q] = w0; W[3 * q + 1] = w1; W[3 * q + 2] = w2;
        KE[q] = 0.5 * M[q] * (v0 * v0 + v1 * v1 + v2 * v2);
        KR[q] = 0.5 * (L0 * w0 + L1 * w1 + L2 * w2);
    }
}

/* kick_block's anisotropic case (velocity Verlet) for a run of IL free bodies, in lanes (the
 * arrays from the run's first body): each lane does the scalar case's operations in its order
 * (shadow_term's anisotropic form, the kick, floe_omega_from_L, the kinetic energies), so the
 * same bits; one body after the other, the two inverse rotations and six divisions were a
 * chain of latencies (a settled bed of polyhedra: 3 % of its step) */
static __attribute__((noinline FLOE_NO_SLP)) void kick_lanes_aniso(
    double *restrict V, double *restrict W, double *restrict LL, const double *restrict F, const double *restrict T,
    const double *restrict IM, const double *restrict M, const double *restrict Ia, const double *restrict Qa, double h,
    double *restrict KE, double *restrict KR, double *restrict SH) {
    for (int q = 0; q < IL; q++) {
        const double im = IM[q], *f = F + 3 * q, *t = T + 3 * q, *I = Ia + 3 * q, *qq = Qa + 4 * q;
        double dv[3], dL[3], b[3], v[3], L[3], om[3];
        for (int k = 0; k < 3; k++) { dv[k] = h * im * f[k]; dL[k] = h * t[k]; }
        double e = 0.5 * M[q] * floe_v3_dot(dv, dv); /* shadow_term */
        floe_q_rotate_inv(b, qq, dL);
        for (int k = 0; k < 3; k++) e = I[k] > 0 && isfinite(I[k]) ? e + 0.5 * b[k] * b[k] / I[k] : e;
        SH[q] = e;
        for (int k = 0; k < 3; k++) {
            v[k] = V[3 * q + k] + h * im * f[k];
            L[k] = LL[3 * q + k] + h * t[k];
        }
        floe_omega_from_L(qq, I, L, om);
        for (int k = 0; k < 3; k++) {
            V[3 * q + k] = v[k];
            LL[3 * q + k] = L[k];
            W[3 * q + k] = om[k];
        }
        KE[q] = 0.5 * M[q] * floe_v3_dot(v, v);
        KR[q] = 0.5 * floe_v3_dot(L, om);
    }
}

/* rotate_drift_aniso for up to IL anisotropic free particles at once (idx[0 .. m)), in
 * lanes: the midpoint rule's nine dependent stages (five omega = R I^-1 R^T L, four
 * q <- exp(h omega / 2) q) are a chain of latencies for one body (11 % of a settled bed of
 * polyhedra's step), independent across bodies. Each lane does rotate_drift_aniso's
 * operations in its order, with q_advance's small-turn series; a lane whose turn is not
 * small at some stage (|theta|^2 >= 1e-4, theta = h omega or at the last stage dt omega) is
 * done again by rotate_drift_aniso itself. Lanes beyond m repeat particle idx[0] and are not written. */
static __attribute__((noinline FLOE_NO_SLP)) void aniso_lanes(double *restrict Qa, const double *restrict Ia,
                                                              const double *restrict La, double *restrict Wa,
                                                              const int *idx, int m, double dt) {
    double Q[4][IL], LL[3][IL], INV[3][IL], QN[4][IL], OM[3][IL];
    int BIG[IL];
    for (int l = 0; l < IL; l++) {
        const int i = idx[l < m ? l : 0];
        for (int k = 0; k < 4; k++) Q[k][l] = Qa[4 * (size_t)i + k];
        for (int k = 0; k < 3; k++) {
            LL[k][l] = La[3 * (size_t)i + k];
            const double I = Ia[3 * (size_t)i + k];
            INV[k][l] = I > 0 && isfinite(I) ? 1.0 / I : 0;
        }
    }
    const double h = 0.5 * dt;
    for (int l = 0; l < IL; l++) {
        const double q[4] = {Q[0][l], Q[1][l], Q[2][l], Q[3][l]};
        const double L[3] = {LL[0][l], LL[1][l], LL[2][l]}, inv[3] = {INV[0][l], INV[1][l], INV[2][l]};
        double omm[3], qm[4], qn[4], om[3];
        int big = 0;
        omega_inv(q, inv, L, omm);
        big |= q_advance_small(qm, q, omm, h);
        for (int it = 0; it < 2; it++) {
            omega_inv(qm, inv, L, omm);
            big |= q_advance_small(qm, q, omm, h);
        }
        omega_inv(qm, inv, L, omm);
        big |= q_advance_small(qn, q, omm, dt);
        omega_inv(qn, inv, L, om);
        for (int k = 0; k < 4; k++) QN[k][l] = qn[k];
        for (int k = 0; k < 3; k++) OM[k][l] = om[k];
        BIG[l] = big;
    }
    for (int l = 0; l < m; l++) {
        const int i = idx[l];
        if (BIG[l]) { /* a large turn: the trigonometric path, as one particle alone */
            rotate_drift_aniso(Qa + 4 * (size_t)i, Ia + 3 * (size_t)i, La + 3 * (size_t)i, Wa + 3 * (size_t)i, dt);
            continue;
        }
        for (int k = 0; k < 4; k++) Qa[4 * (size_t)i + k] = QN[k][l];
        for (int k = 0; k < 3; k++) Wa[3 * (size_t)i + k] = OM[k][l];
    }
}

static double drift_block(floe_particles *p, const drift_args *a, int i0, int i1, double *maxd2, int *kin, int *bad) {
    /* restrict: within this block nothing else writes what they point to */
    double *restrict X = p->x, *restrict V = p->v, *restrict Q = p->q, *restrict W = p->w, *restrict LL = p->L;
    const unsigned char *restrict MO = p->motion, *restrict iso = p->iso;
    double *restrict F = p->f, *restrict T = p->t, *restrict DA = a->da;
    const double *restrict IM = p->inv_mass, *restrict M = p->mass;
    const double *restrict II = p->inv_iso, *restrict XB = a->xb, *restrict R = p->radius;
    const double k1 = a->k1, dt = a->dt, h = a->h, g0 = a->g[0], g1 = a->g[1], g2 = a->g[2];
    double wb = 0, md = *maxd2; /* locals: kept in registers */
    int kn = 0, kb = 0;
    int next = i0; /* the first particle a run may start at */
    int ani[IL], nani = 0; /* anisotropic bodies whose orientation waits for aniso_lanes */
    for (int i = i0; i < i1; i++) {
        while (i >= next && i + IL <= i1) {
            /* a run of round particles (iso 2, orientation unread; or iso 1, advanced too), in
             * lanes */
            const int n = run_len(MO, iso, i, 1);
            if (n < IL) { /* particle i + n breaks it: one by one up to there */
                next = i + n + 1;
                break;
            }
            double WB[IL], D2[IL];
            int FB[IL];
            const size_t o3 = 3 * (size_t)i;
            const double *xb = XB ? XB + o3 : NULL;
            double *da = DA ? DA + o3 : NULL;
            if (iso[i] == 1)
                drift_lanes_rot(X + o3, V + o3, W + o3, LL + o3, F + o3, T + o3, IM + i, M + i, II + i, R + i, xb, a, WB, D2,
                                FB, da, Q + 4 * (size_t)i);
            else
                drift_lanes(X + o3, V + o3, W + o3, LL + o3, F + o3, T + o3, IM + i, M + i, II + i, R + i, xb, a, WB, D2, FB,
                            da);
            for (int q = 0; q < IL; q++) {
                kb |= FB[q];
                if (XB && D2[q] > md) md = D2[q]; /* note_disp */
                wb += WB[q];
            }
            i += IL;
        }
        if (i >= i1) break;
        const unsigned char mo = MO[i];
        if (mo != FLOE_FREE) { kn |= mo == FLOE_KINEMATIC; continue; }
        double *x = X + 3 * i, *v = V + 3 * i;
        const double im = IM[i];
        for (int k = 0; k < 3; k++) v[k] += k1 * im * F[3 * i + k];
        for (int k = 0; k < 3; k++) x[k] += dt * v[k];
        /* the quick checks (the messages come after the forces, step_verlet): a particle
         * that moved more than half its radius, or whose position or velocity is not finite
         * (NaN fails every comparison) */
        kb |= drift_failed(v, x, R[i], dt);
        if (XB) note_disp(x, XB + 3 * i, &md);
        /* rotation: L by the half kick, then the orientation over dt (the isotropic fast
         * path q <- exp(dt omega / 2) q without trig, or the midpoint rule) */
        floe_v3_axpy(LL + 3 * i, k1, T + 3 * i);
        if (a->clear) { /* as forces_clear */
            for (int k = 0; k < 3; k++) {
                if (DA) DA[3 * i + k] = F[3 * i + k] * im;
                T[3 * i + k] = 0.0;
            }
            F[3 * i] = M[i] * g0; F[3 * i + 1] = M[i] * g1; F[3 * i + 2] = M[i] * g2;
        }
        if (iso[i] == 2) /* a round particle whose orientation nothing reads: omega only */
            for (int k = 0; k < 3; k++) W[3 * i + k] = LL[3 * i + k] * II[i];
        else if (iso[i]) rotate_drift_iso(Q + 4 * i, LL + 3 * i, W + 3 * i, II[i], h);
        else if (floe_v3_dot(LL + 3 * i, LL + 3 * i) > 0) {
            /* the orientation and omega of body i are read by nothing else in this loop:
             * taken IL at a time in lanes (the blocks are fixed: the same lanes for any
             * thread count) */
            ani[nani++] = i;
            if (nani == IL) {
                aniso_lanes(Q, p->inertia, LL, W, ani, IL, dt);
                nani = 0;
            }
        }
        /* body-force work over the step uses the drift displacement (exact for gravity
         * when the second half adds the same force) */
        wb += dt * (M[i] * (g0 * v[0] + g1 * v[1] + g2 * v[2]));
    }
    if (nani) aniso_lanes(Q, p->inertia, LL, W, ani, nani, dt);
    *maxd2 = md;
    *kin |= kn;
    *bad |= kb;
    return wb;
}

/* the second half kick of the free particles [i0, i1) (leapfrog: their synchronised
 * velocities' energy only): out = kinetic energy, rotational, the shadow term's isotropic
 * and general parts; *bad lowered to the first particle that fails the quick checks */
typedef struct kick_args {
    double h, dt;
    int leap, shadow;
    int recheck; /* MPI: the drift's quick checks again (a particle that failed them may have
                    migrated to this rank in the rebuild between) */
} kick_args;
static void kick_block(floe_particles *p, const kick_args *a, int i0, int i1, double out[4], int *bad) {
    double *restrict V = p->v, *restrict W = p->w, *restrict LL = p->L;
    const double *restrict X = p->x, *restrict R = p->radius;
    const unsigned char *restrict MO = p->motion, *restrict iso = p->iso;
    const double *restrict F = p->f, *restrict T = p->t, *restrict IM = p->inv_mass, *restrict M = p->mass;
    const double *restrict II = p->inv_iso;
    const double h = a->h, dt = a->dt;
    const int leap = a->leap, shadow = a->shadow, recheck = a->recheck;
    double kt = 0, kr = 0, sh_iso = 0, sh = 0;
    int bad_i = *bad;
    int next = leap ? i1 : i0; /* the first particle a run may start at */
    for (int i = i0; i < i1; i++) {
        while (i >= next && i + IL <= i1) {
            /* a run of isotropic free bodies, in lanes (the isotropic case below) */
            const int n = run_len(MO, iso, i, 0), na = n == 0 && !leap && !recheck ? aniso_len(MO, iso, i) : 0;
            double KE[IL], KR[IL], SH[IL];
            const size_t o3 = 3 * (size_t)i;
            if (na == IL) { /* a run of anisotropic free bodies */
                kick_lanes_aniso(V + o3, W + o3, LL + o3, F + o3, T + o3, IM + i, M + i, p->inertia + o3,
                                 p->q + 4 * (size_t)i, h, KE, KR, SH);
                for (int q = 0; q < IL; q++) { /* in order, as one by one */
                    if (shadow) sh += SH[q];
                    kt += KE[q];
                    kr += KR[q];
                    if (!(KE[q] + KR[q] < INFINITY) && i + q < bad_i) bad_i = i + q;
                }
                i += IL;
                continue;
            }
            if (n < IL) { /* particle i + n (or i + na) breaks it: one by one up to there, where a
                           * run of the other kind may start */
                next = i + (n > 0 ? n : na > 0 ? na : 1);
                break;
            }
            if (recheck) /* MPI: the drift's checks on v_half, before the kick (bad_i is a minimum) */
                for (int q = 0; q < IL; q++)
                    if (drift_failed(V + o3 + 3 * q, X + o3 + 3 * q, R[i + q], dt) && i + q < bad_i) bad_i = i + q;
            kick_lanes(V + o3, W + o3, LL + o3, F + o3, T + o3, IM + i, M + i, II + i, h, KE, KR, SH);
            for (int q = 0; q < IL; q++) {
                sh_iso += SH[q];
                kt += KE[q];
                kr += KR[q];
                if (!(KE[q] + KR[q] < INFINITY) && i + q < bad_i) bad_i = i + q;
            }
            i += IL;
        }
        if (i >= i1) break;
        if (MO[i] != FLOE_FREE) continue;
        double *v = V + 3 * i, *L = LL + 3 * i, *om = W + 3 * i;
        const double *f = F + 3 * i, *t = T + 3 * i;
        const double im = IM[i];
        if (recheck && drift_failed(v, X + 3 * i, R[i], dt) && i < bad_i) bad_i = i; /* v: still v_half */
        double ke, kre;
        if (iso[i]) {
            /* isotropic bodies: omega = L / I, and the shadow term's isotropic case
             * 1/2 m |h F/m|^2 + 1/2 |h T|^2 / I (times hh2 after the loop) */
            const double ii = II[i];
            sh_iso += im * (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) + ii * (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            if (!leap) {
                for (int k = 0; k < 3; k++) v[k] += h * im * f[k];
                for (int k = 0; k < 3; k++) L[k] += h * t[k];
                for (int k = 0; k < 3; k++) om[k] = L[k] * ii;
                ke = 0.5 * M[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                kre = 0.5 * (L[0] * om[0] + L[1] * om[1] + L[2] * om[2]);
            } else {
                double vs[3], Ls[3];
                for (int k = 0; k < 3; k++) {
                    vs[k] = v[k] + h * im * f[k];
                    Ls[k] = L[k] + h * t[k];
                }
                double ws[3] = {Ls[0] * ii, Ls[1] * ii, Ls[2] * ii};
                ke = 0.5 * M[i] * floe_v3_dot(vs, vs);
                kre = 0.5 * floe_v3_dot(Ls, ws);
            }
        } else {
            const double *I = p->inertia + 3 * i, *q = p->q + 4 * i;
            if (shadow) {
                double dv[3], dL[3];
                for (int k = 0; k < 3; k++) { dv[k] = h * im * f[k]; dL[k] = h * t[k]; }
                sh += shadow_term(p, i, dv, dL);
            }
            if (!leap) {
                for (int k = 0; k < 3; k++) v[k] += h * im * f[k];
                for (int k = 0; k < 3; k++) L[k] += h * t[k];
                floe_omega_from_L(q, I, L, om);
                ke = 0.5 * M[i] * floe_v3_dot(v, v);
                kre = 0.5 * floe_v3_dot(L, om);
            } else {
                double vs[3], Ls[3], ws[3];
                for (int k = 0; k < 3; k++) {
                    vs[k] = v[k] + h * im * f[k];
                    Ls[k] = L[k] + h * t[k];
                }
                floe_omega_from_L(q, I, Ls, ws);
                ke = 0.5 * M[i] * floe_v3_dot(vs, vs);
                kre = 0.5 * floe_v3_dot(Ls, ws);
            }
        }
        kt += ke;
        kr += kre;
        /* the drift's checks were made in drift_block; here the new velocities' (a force that
         * is not finite) */
        if (!(ke + kre < INFINITY) && i < bad_i) bad_i = i;
    }
    out[0] = kt; out[1] = kr; out[2] = sh_iso; out[3] = sh;
    *bad = bad_i;
}

int step_verlet(floe_world *w) {
    floe_particles *p = &w->p;
    const double dt = w->dt, h = 0.5 * dt;
    int n = p->n;
    const int leap = w->def.integrator == FLOE_LEAPFROG;
    /* leapfrog: the kick spans the two half steps around t_n; the first step after the
     * velocities were synchronised (start) spans half a step */
    const double k1 = leap ? 0.5 * (w->lf_dt_prev + dt) : h, k2 = leap ? 0.0 : h;
    double wb = 0;    /* body-force work this step */
    double maxd2 = 0; /* largest squared displacement since the neighbour build */
    const double *xb = w->nl.x_build;
    const int have_xb = xb && w->nl.n_build == n;
    const unsigned char *motion = p->motion;
    const double g0 = w->def.gravity[0], g1 = w->def.gravity[1], g2 = w->def.gravity[2];
    int kin = 0; /* any kinematic particle */
    int dbad = 0; /* a free particle failed the drift's quick checks */
    if (w->cell) { /* the cell's velocity gradient of this step (MPI: the servo's stress summed
                    * over the ranks) */
        double sg[9];
        int given = 0;
        if (w->par) FLOE_TRY(floe_par_cell_stress(w, sg, &given));
        FLOE_TRY(floe_cell_begin_step(w, given ? sg : NULL));
    }
    /* threads: blocks of FLOE_PAR_BLOCK particles, their sums added in block order (the same
     * bits for any number of threads, floe_par.h) */
    const int B = FLOE_PAR_BLOCK, nb = (n + B - 1) / B, nt = floe_world_loop_threads(w, n);
    double *red = floe_world_reduce_buf(w, (size_t)nb);
    /* out of memory: under MPI this rank goes on (calling the collectives on the way, not
     * moving) to the rebuild test, which tells every rank */
    int pre = nb > 0 && !red ? floe_world_error(w, FLOE_ENOMEM, "out of memory") : FLOE_OK;
    if (pre && !w->par) return pre;
    /* the blocks that hold a kinematic particle (NULL: the loops over them look at every
     * particle) */
    const int n0 = n;
    unsigned char *kinb = NULL;
    if (nb > 0 && (size_t)nb <= w->kinb_cap) kinb = w->kinb;
    else if (nb > 0) {
        unsigned char *t = realloc(w->kinb, (size_t)nb);
        if (t) {
            w->kinb = kinb = t;
            w->kinb_cap = (size_t)nb;
        }
    }
    /* the drift clears the free particles' forces as it reads them (forces_clear's work for
     * them, while their lines are in the cache): not where something between the drift and
     * the force evaluation may read them or change masses (state objects), nor where the
     * evaluation clears a decomposed store (MPI: migration and ghosts); with a linear dashpot
     * once its buffer has room (the evaluation takes f / m first). Between the two, a free
     * particle's force reads m g and its torque 0 (a kinematic particle's motion callback, a
     * provider's exclusion at a rebuild; a step that fails there leaves them so, docs/api.md) */
    const int dash = floe_world_dash_next(w);
    const int fuse = !w->par && !w->nstates && (!dash || w->dash_cap >= 3 * (size_t)n);
    w->st_drift_clears += fuse;
    /* 1. first half kick + drift (eq 22), rotation by the midpoint rule (eq 23); then the
     * kinematic particles at their prescribed velocity */
    if (!pre) {
        const drift_args da = {k1, dt, h, {g0, g1, g2}, have_xb ? xb : NULL, fuse, fuse && dash ? w->dash_a : NULL};
        if (nt > 1) {
            /* the threads' parts by their measured speeds (floe_loop_split; NULL: evenly) */
            const int *cut = floe_loop_split_cuts(w, nt, nb);
            double *sec = w->ls.sec;
            FLOE_OMP(omp parallel num_threads(nt) reduction(max: maxd2) reduction(|: kin, dbad))
            {
                const int nth = floe_par_nthreads();
                for (int part = floe_par_thread(); part < nt; part += nth) {
                    const double t0 = floe_par_wtime();
                    int b0, b1;
                    floe_loop_split_range(cut, nb, nt, part, &b0, &b1);
                    for (int b = b0; b < b1; b++) {
                        int kb = 0;
                        red[b] = drift_block(p, &da, b * B, (b + 1) * B < n ? (b + 1) * B : n, &maxd2, &kb, &dbad);
                        if (kinb) kinb[b] = (unsigned char)kb;
                        kin |= kb;
                    }
                    if (cut) sec[part] += floe_par_wtime() - t0;
                }
            }
        } else
            for (int b = 0; b < nb; b++) {
                int kb = 0;
                red[b] = drift_block(p, &da, b * B, (b + 1) * B < n ? (b + 1) * B : n, &maxd2, &kb, &dbad);
                if (kinb) kinb[b] = (unsigned char)kb;
                kin |= kb;
            }
        for (int b = 0; b < nb; b++) wb += red[b];
    }
    /* MPI: the servo walls' measures again (their controllers count the particles that
     * reach them after this drift, as in one process) */
    if (w->par) FLOE_TRY(floe_par_servo_totals(w));
    if (kin)
        for (int i = 0; i < n; i++) {
            if (kinb && !kinb[i / B]) { /* no kinematic particle in this block */
                i = (i / B + 1) * B - 1;
                continue;
            }
            if (motion[i] != FLOE_KINEMATIC) continue;
            double *x = p->x + 3 * i, *q = p->q + 4 * i;
            /* keep the force of the step's start for the trapezoid work of the boundary */
            memcpy(w->kin_old + 6 * i, p->f + 3 * i, 3 * sizeof(double));
            memcpy(w->kin_old + 6 * i + 3, p->t + 3 * i, 3 * sizeof(double));
            kinematic_velocity(w, i, w->time + h);
            floe_v3_axpy(x, dt, p->v + 3 * i);
            if (have_xb) note_disp(x, xb + 3 * i, &maxd2);
            double qn[4];
            q_advance(qn, q, p->w + 3 * i, dt);
            memcpy(q, qn, sizeof qn);
        }
    /* the periodic cell's affine map of the particles and of the cell itself */
    if (w->cell && !pre) {
        pre = floe_cell_after_drift(w, dt);
        if (pre && !w->par) return pre;
    }
    /* 2. state objects, RK2 midpoint (eq 21); the work of gravity on the mass they add */
    const double *mn = growth_masses(w, n, 0, &pre);
    pre = states_step(w, dt, pre);
    if (states_done(w, pre)) return pre;
    if (mn && !pre) wb += growth_gravity_work(w, mn, n, dt, NULL);
    advance_clock(w);
    /* 3. neighbours and forces at t + dt (MPI: a failure carried here is every rank's, the
     * clock put back where one process leaves it) */
    FLOE_TRY(rebuild_if_needed(w, maxd2, have_xb, pre, &dbad));
    /* MPI (core/parallel): a rebuild migrates particles: the count and the store's arrays
     * may have changed */
    n = p->n;
    motion = p->motion;
    /* ... and a kinematic particle may have arrived on this rank: its step's close (the
     * boundary work, its velocity) is this rank's now (a rank without one at the drift
     * skipped it, and its work was lost from the ledger) */
    if (w->par) kin = 1;
    w->drift_cleared = fuse;
    const int frc = forces_advancing(w);
    w->drift_cleared = 0;
    FLOE_TRY(frc);
    /* 4. second half kick (leapfrog: none; its kinetic energy is that of the synchronised
     * velocity v_{n+1/2} + dt/2 a_{n+1}) */
    double kt = 0, kr = 0, wbound = 0, sh_iso = 0, sh = 0;
    const int shadow = w->def.energy_check != FLOE_CHECK_OFF;
    const double hh2 = 0.5 * h * h;
    int bad = INT_MAX; /* the first free particle that failed the checks below */
    {
        /* the blocks again: a rebuild may have changed the count (MPI) */
        const int nb2 = (n + B - 1) / B, nt2 = floe_world_loop_threads(w, n);
        double *red2 = floe_world_reduce_buf(w, 4 * (size_t)nb2);
        if (nb2 > 0 && !red2) return step_close(w, floe_world_error(w, FLOE_ENOMEM, "out of memory"));
        /* MPI: the drift's checks again only when a rank's drift found a failure (told by the
         * rebuild test; the same values: v_half, x_{n+1}): else they would find nothing */
        const kick_args ka = {h, dt, leap, shadow, w->par != NULL && dbad};
        if (nt2 > 1) {
            const int *cut = floe_loop_split_cuts(w, nt2, nb2); /* the drift's parts */
            double *sec = w->ls.sec;
            FLOE_OMP(omp parallel num_threads(nt2) reduction(min: bad))
            {
                const int nth = floe_par_nthreads();
                for (int part = floe_par_thread(); part < nt2; part += nth) {
                    const double t0 = floe_par_wtime();
                    int b0, b1;
                    floe_loop_split_range(cut, nb2, nt2, part, &b0, &b1);
                    for (int b = b0; b < b1; b++)
                        kick_block(p, &ka, b * B, (b + 1) * B < n ? (b + 1) * B : n, red2 + 4 * (size_t)b, &bad);
                    if (cut) sec[part] += floe_par_wtime() - t0;
                }
            }
            floe_loop_split_update(w);
        } else
            for (int b = 0; b < nb2; b++)
                kick_block(p, &ka, b * B, (b + 1) * B < n ? (b + 1) * B : n, red2 + 4 * (size_t)b, &bad);
        for (int b = 0; b < nb2; b++) {
            const double *rb = red2 + 4 * (size_t)b;
            kt += rb[0]; kr += rb[1]; sh_iso += rb[2]; sh += rb[3];
        }
    }
    /* (the drift's blocks still: without MPI a rebuild keeps the particles) */
    if (kin)
        for (int i = 0; i < n; i++) {
            if (kinb && !w->par && n == n0 && !kinb[i / B]) {
                i = (i / B + 1) * B - 1;
                continue;
            }
            if (motion[i] == FLOE_KINEMATIC) wbound += kinematic_close(w, i, h);
        }
    /* a particle failed the quick test: the checks with the message, from the first one on
     * (one failed the drift's: from the start; under MPI the kick checked again, on the rank
     * that holds it after the rebuild) */
    if (dbad && !w->par) bad = 0;
    for (int i = bad; i < n; i++) {
        if (motion[i] != FLOE_FREE) continue;
        double xold[3];
        for (int k = 0; k < 3; k++) xold[k] = p->x[3 * i + k] - dt * (p->v[3 * i + k] - k2 * p->inv_mass[i] * p->f[3 * i + k]);
        const int rc = check_particle(w, i, xold);
        if (rc) return step_close(w, rc);
    }
    FLOE_TRY(step_close(w, FLOE_OK));
    if (leap) w->lf_dt_prev = dt;
    w->wd_shadow = shadow ? sh + hh2 * sh_iso : 0.0;
    w->energy.kinetic_trans = kt;
    w->energy.kinetic_rot = kr;
    w->energy.work_body += wb;
    w->energy.work_boundary += wbound;
    return FLOE_OK;
}

/* Forces at the RK2 midpoint: the contact history is advanced by dt/2 from the step's
 * start (its midpoint value) and put back afterwards, the body-force and external-force
 * memories of the energy ledger too; nothing is booked in the ledger, no contact recorded,
 * and PD bonds do not break (their forces come from floe_pd_forces_nobreak). */
static int rk2_midpoint_forces(floe_world *w, double h, int pre) {
    floe_neighbor_list *nl = &w->nl;
    /* a probe: every provider's state (contact history, the callbacks' last forces, ...)
     * saved, the forces evaluated with the history advanced by h and no breakage, the
     * state restored: the step itself advances it at its end. pre (MPI): this rank failed
     * before: it still evaluates (forces_all), and every rank returns the failure */
    const size_t nb = providers_state_size(w);
    if (!pre && nb > w->pbuf_cap) {
        unsigned char *t = realloc(w->pbuf, nb);
        if (t) {
            w->pbuf = t;
            w->pbuf_cap = nb;
        } else pre = floe_world_error(w, FLOE_ENOMEM, "out of memory");
        if (pre && !w->par) return pre;
    }
    if (!pre) providers_state_io(w, w->pbuf, 1);
    floe_step_ctx c = {&w->p, w->def.dim, 0, w->time, w->dt, h, 1, 0, 0};
    long rb = nl->rebuilds;
    int rc = forces_all(w, &c, pre);
    w->st.force_evaluations++;
    if (rc) return rc;
    if (nl->rebuilds != rb) return floe_world_error(w, FLOE_EINVAL, "internal: neighbour list rebuilt at the RK2 midpoint");
    providers_state_io(w, w->pbuf, 0);
    return FLOE_OK;
}

/* RK2's particle loops on the world's threads (floe_world_blocks: blocks of FLOE_PAR_BLOCK
 * particles, each block's sums from its first particle on, the blocks' sums in block order:
 * the same bits for any number of threads); the kinematic particles (their motion callbacks)
 * and the checks with a message on one thread, in index order, after the blocks */
typedef struct rk2_ctx {
    floe_world *w;
    double h, dt;
    const double *x0, *v0, *q0, *fm, *xb;
    double *L0, *md; /* md: each block's largest squared displacement since the build */
    int *bad;        /* each block's first free particle that failed the quick checks */
    double *rows;    /* MPI: the closing values (RK2_WD a particle, w->rk2); NULL in one
                        process, where the end reads x0, v0, fm (no rebuild renumbers them) */
    double *mn;      /* a world with state objects: each particle's mass m_n (the end block
                        writes it), and L0 then holds L_n + dt T_mid - L_mid (rk2_grow_block) */
} rk2_ctx;

/* a row of w->rk2 (MPI): v_n, F_mid, x_n of a free particle (the others' are not read) and
 * the midpoint's dashpot accelerations (forces.c). v_{n+1} = v_n + dt F_mid / m is taken at
 * the step's end, with the mass then (a state object may grow it in the step) */
enum { RK2_V = 0, RK2_F = 3, RK2_X = 6, RK2_DASH = 9, RK2_WD = 12 };

/* 1. the midpoint state of the free particles (the fixed ones stay, the kinematic ones after) */
static void rk2_mid_block(void *ctx, int i0, int i1, double *sums) {
    const rk2_ctx *c = ctx;
    floe_particles *p = &c->w->p;
    const double h = c->h;
    sums[0] = 0.0;
    for (int i = i0; i < i1; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        double *x = p->x + 3 * i, *v = p->v + 3 * i, *q = p->q + 4 * i;
        const double im = p->inv_mass[i];
        floe_v3_axpy(x, h, v);
        for (int k = 0; k < 3; k++) v[k] += h * im * p->f[3 * i + k];
        floe_v3_axpy(p->L + 3 * i, h, p->t + 3 * i);
        double qn[4];
        q_advance(qn, q, p->w + 3 * i, h);
        memcpy(q, qn, sizeof qn);
        omega_update(p, i);
    }
}

/* 3. the drift from the start with the midpoint velocities, the free particles' L_{n+1}
 * (with state objects: L stays L_mid for them, and L0 takes L_n + dt T_mid - L_mid, added
 * after them by rk2_grow_block) and what v_{n+1} needs into their rows; sums: the body-force
 * work */
static void rk2_end_block(void *ctx, int i0, int i1, double *sums) {
    const rk2_ctx *c = ctx;
    floe_particles *p = &c->w->p;
    const double dt = c->dt, *g = c->w->def.gravity;
    const double *da = c->rows && c->w->dash_on ? c->w->dash_a : NULL;
    double wb = 0, md = 0;
    for (int i = i0; i < i1; i++) {
        double *r = c->rows ? c->rows + (size_t)i * RK2_WD : NULL;
        if (r) /* the kept dashpot accelerations (0 where none are kept) */
            for (int k = 0; k < 3; k++) r[RK2_DASH + k] = da ? da[3 * i + k] : 0.0;
        if (p->motion[i] == FLOE_FIXED) continue;
        double *x = p->x + 3 * i;
        for (int k = 0; k < 3; k++) x[k] = c->x0[3 * i + k] + dt * p->v[3 * i + k];
        q_advance(p->q + 4 * i, c->q0 + 4 * i, p->w + 3 * i, dt);
        if (c->xb) note_disp(x, c->xb + 3 * i, &md);
        if (p->motion[i] == FLOE_FREE) {
            wb += dt * (p->mass[i] * floe_v3_dot(g, p->v + 3 * i));
            if (c->mn) { /* L stays L_mid for the states; L0 <- what the step adds to it */
                c->mn[i] = p->mass[i];
                for (int k = 0; k < 3; k++)
                    c->L0[3 * i + k] = c->L0[3 * i + k] + dt * p->t[3 * i + k] - p->L[3 * i + k];
            } else
                for (int k = 0; k < 3; k++) p->L[3 * i + k] = c->L0[3 * i + k] + dt * p->t[3 * i + k]; /* L_{n+1} */
            if (r)
                for (int k = 0; k < 3; k++) {
                    r[RK2_V + k] = c->v0[3 * i + k];
                    r[RK2_F + k] = c->fm[3 * i + k];
                    r[RK2_X + k] = c->x0[3 * i + k];
                }
        }
    }
    c->md[i0 / FLOE_PAR_BLOCK] = md;
    sums[0] = wb;
}

/* 3b. a world with state objects, after them: a state that grew a particle (its mass m_n ->
 * m_{n+1}, its inertia I_n -> s I_n; floe_growing_radius_create with update_mass) scaled the
 * L_mid it saw by s and kept v_mid; the added mass and inertia move with the particle, so
 *   m_{n+1} v_{n+1} = m_n v_n + dt F_mid + (m_{n+1} - m_n) v_mid,
 *   L_{n+1} = L_n + dt T_mid + (s - 1) L_mid:
 * the midpoint rule on d(m v)/dt = F + m' v and dL/dt = T + I' w (second order; taking the
 * mass and inertia after the growth instead is first order). L_{n+1} = s L_mid + (L_n + dt
 * T_mid - L_mid) (kept in L0 by the end block); the momentum's growth term goes into F_mid,
 * for v_{n+1} = v_n + dt F_mid / m_{n+1} at the close. Unchanged particles: L_{n+1} is the
 * same sum as without states, to rounding. */
static void rk2_grow_block(void *ctx, int i0, int i1, double *sums) {
    const rk2_ctx *c = ctx;
    floe_particles *p = &c->w->p;
    const double inv_dt = 1.0 / c->dt, *g = c->w->def.gravity;
    double wb = 0;
    for (int i = i0; i < i1; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        for (int k = 0; k < 3; k++) p->L[3 * i + k] += c->L0[3 * i + k];
        const double dm = p->mass[i] - c->mn[i];
        if (dm == 0) continue;
        wb += 0.5 * c->dt * dm * floe_v3_dot(g, p->v + 3 * i); /* growth_gravity_work's */
        double *r = c->rows ? c->rows + (size_t)i * RK2_WD : NULL;
        const double *v0 = r ? r + RK2_V : c->v0 + 3 * i;
        double *fm = r ? r + RK2_F : (double *)c->fm + 3 * i;
        for (int k = 0; k < 3; k++) fm[k] += dm * (p->v[3 * i + k] - v0[k]) * inv_dt;
    }
    sums[0] = wb;
}

/* 4. the free particles' v_{n+1} from their rows and omega from L_{n+1}; sums: their kinetic
 * energies */
static void rk2_close_block(void *ctx, int i0, int i1, double *sums) {
    const rk2_ctx *c = ctx;
    floe_particles *p = &c->w->p;
    const double dt = c->dt;
    double kt = 0, kr = 0;
    int bad = INT_MAX;
    for (int i = i0; i < i1; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        double *v = p->v + 3 * i, *L = p->L + 3 * i, im = p->inv_mass[i];
        const double *r = c->rows ? c->rows + (size_t)i * RK2_WD : NULL;
        const double *v0 = r ? r + RK2_V : c->v0 + 3 * i, *fm = r ? r + RK2_F : c->fm + 3 * i;
        double d2 = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt * dt, lim = 0.5 * p->radius[i];
        for (int k = 0; k < 3; k++) v[k] = v0[k] + dt * im * fm[k];
        omega_update(p, i);
        double ke = 0.5 * p->mass[i] * floe_v3_dot(v, v), kre = 0.5 * floe_v3_dot(L, p->w + 3 * i);
        kt += ke;
        kr += kre;
        if (bad == INT_MAX && (!(d2 <= lim * lim) || !(ke + kre < INFINITY) ||
                               !(fabs(p->x[3 * i]) + fabs(p->x[3 * i + 1]) + fabs(p->x[3 * i + 2]) < INFINITY)))
            bad = i;
    }
    c->bad[i0 / FLOE_PAR_BLOCK] = bad;
    sums[0] = kt;
    sums[1] = kr;
}

/* Explicit midpoint RK2 for the particles (ParticLS eq 21 with y = (x, v, q, L)):
 *   y_mid = y_n + dt/2 f(y_n);  y_{n+1} = y_n + dt f(y_mid).
 * The force at the end of the step, f(y_{n+1}), is evaluated with the midpoint velocities
 * (the velocities of the drift x_{n+1} - x_n = dt v_mid), like velocity Verlet's forces:
 * the contact history then grows by the tangential displacement of the step and the
 * energy ledger's trapezoid work is that of the actual displacement; that force only
 * enters the next step's midpoint, where an O(dt) error costs O(dt^3) locally. */
int step_rk2(floe_world *w) {
    floe_particles *p = &w->p;
    const int n = p->n;
    const double dt = w->dt, h = 0.5 * dt, t_n = w->time;
    /* x0 v0 L0 q0 F_mid, and m_n where state objects may grow a particle's mass */
    const size_t nw = w->nstates ? 17 : 16;
    double *b = ibuf_reserve(w, nw * (size_t)(n ? n : 1));
    /* out of memory before the midpoint forces: one process returns; under MPI this rank goes
     * on to their agreement (calling the collectives on the way, not moving) */
    int pre = b ? FLOE_OK : floe_world_error(w, FLOE_ENOMEM, "out of memory");
    if (pre && !w->par) return pre;
    const int nbk = (n + FLOE_PAR_BLOCK - 1) / FLOE_PAR_BLOCK;
    if (!pre) {
        double *x0 = b, *v0 = b + 3 * (size_t)n, *L0 = b + 6 * (size_t)n, *q0 = b + 9 * (size_t)n;
        floe_world_copy(w, x0, p->x, 3 * (size_t)n * sizeof *x0);
        floe_world_copy(w, v0, p->v, 3 * (size_t)n * sizeof *v0);
        floe_world_copy(w, L0, p->L, 3 * (size_t)n * sizeof *L0);
        floe_world_copy(w, q0, p->q, 4 * (size_t)n * sizeof *q0);
        /* 1. the midpoint state: the free particles on the threads, then the kinematic ones */
        rk2_ctx c = {w, h, dt, x0, v0, q0, NULL, NULL, L0, NULL, NULL, NULL, NULL};
        double s0;
        if (floe_world_blocks(w, n, 1, rk2_mid_block, &c, &s0)) {
            pre = floe_world_error(w, FLOE_ENOMEM, "out of memory");
            if (!w->par) return pre;
        }
    }
    /* MPI: the servo walls' measures at the free particles' midpoint (their controllers count
     * the particles that reach them, as in one process, where the walls come after the bodies) */
    if (w->par) FLOE_TRY(floe_par_servo_totals(w));
    for (int i = 0; i < n && !pre; i++) {
        if (p->motion[i] != FLOE_KINEMATIC) continue;
        double *x = p->x + 3 * i, *v = p->v + 3 * i, *q = p->q + 4 * i;
        memcpy(w->kin_old + 6 * i, p->f + 3 * i, 3 * sizeof(double));
        memcpy(w->kin_old + 6 * i + 3, p->t + 3 * i, 3 * sizeof(double));
        kinematic_velocity(w, i, t_n + h);
        floe_v3_axpy(x, h, v);
        double qn[4];
        q_advance(qn, q, p->w + 3 * i, h);
        memcpy(q, qn, sizeof qn);
    }
    /* 2. forces at the midpoint (MPI: the ghosts' midpoint state from their owners) */
    if (w->par) FLOE_TRY(floe_par_ghost_update(w));
    /* the state objects at the midpoint (a growing radius's contacts), for its forces only */
    const int probed = w->nstates && !pre;
    if (probed) {
        pre = probe_states(w, h, 0);
        if (pre && !w->par) return pre;
    }
    w->time = t_n + h;
    int rc = rk2_midpoint_forces(w, h, pre); /* (agreed under MPI) */
    w->time = t_n;
    if (probed && !pre) probe_states(w, h, 1);
    if (rc) return rc;
    b = w->ibuf; /* the midpoint's scratch may have moved it */
    double *x0 = b, *v0 = b + 3 * (size_t)n, *L0 = b + 6 * (size_t)n, *q0 = b + 9 * (size_t)n;
    double *fm = b + 13 * (size_t)n; /* F_mid */
    double *mn = w->nstates ? b + 16 * (size_t)n : NULL; /* m_n */
    floe_world_copy(w, fm, p->f, 3 * (size_t)n * sizeof *fm);
    /* 3. x_{n+1} = x_n + dt v_mid, q_{n+1} = exp(dt w_mid) q_n, L_{n+1} = L_n + dt T_mid
     * (with state objects after them, 3b: a growing radius scales L_mid); v, w stay at the
     * midpoint values for
     * the forces at the end; v_n and F_mid into the rows, which the end's rebuild carries with
     * their particles (MPI: a decomposition) */
    double wb = 0, maxd2 = 0;
    const double *xb = w->nl.x_build;
    const int have_xb = xb && w->nl.n_build == n;
    int oom = 0; /* MPI: told to every rank at the refresh below (a collective) */
    if (w->par && (w->rk2_n < n || !w->rk2)) {
        double *t = realloc(w->rk2, (size_t)(n ? n : 1) * RK2_WD * sizeof *t);
        if (t) {
            const int old = w->rk2 ? w->rk2_n : 0; /* new rows zero (the others' are sent too) */
            memset(t + (size_t)old * RK2_WD, 0, (size_t)((n ? n : 1) - old) * RK2_WD * sizeof *t);
            w->rk2 = t;
            w->rk2_n = n;
        } else oom = 1;
    }
    {
        /* the blocks' largest displacements since the build */
        double *md = oom ? NULL : malloc((size_t)(nbk > 0 ? nbk : 1) * sizeof *md);
        rk2_ctx c = {w, h, dt, x0, v0, q0, fm, have_xb ? xb : NULL, L0, md, NULL, w->par ? w->rk2 : NULL, mn};
        if (!md || floe_world_blocks(w, n, 1, rk2_end_block, &c, &wb)) oom = 1;
        for (int k = 0; k < nbk && !oom; k++)
            if (md[k] > maxd2) maxd2 = md[k];
        free(md);
        if (oom && !w->par) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    /* (MPI: out of memory for the rows goes on to the next agreement) */
    pre = states_step(w, dt, oom ? floe_world_error(w, FLOE_ENOMEM, "out of memory") : FLOE_OK);
    if (states_done(w, pre)) return pre;
    if (mn && !pre) { /* 3b. (before a rebuild renumbers the particles) */
        rk2_ctx c = {w, h, dt, x0, v0, q0, fm, NULL, L0, NULL, NULL, w->par ? w->rk2 : NULL, mn};
        double s3 = 0;
        if (floe_world_blocks(w, n, 1, rk2_grow_block, &c, &s3)) pre = floe_world_error(w, FLOE_ENOMEM, "out of memory");
        if (pre && !w->par) return pre;
        wb += s3; /* gravity's work on the added mass */
    }
    advance_clock(w);
    /* MPI: a rebuild is a decomposition; the rows travel with their particles (x0 .. fm do
     * not: under MPI not read after this); a failure carried here puts the clock back, as
     * velocity Verlet's */
    if (w->par) {
        const floe_par_carry carry = {&w->rk2, &w->rk2_n, RK2_WD, RK2_DASH};
        int told = 0;
        const int rc = floe_par_refresh(w, maxd2, have_xb, &carry, pre, NULL, &told);
        if (told) retreat_clock(w);
        if (rc) return rc;
    } else FLOE_TRY(rebuild_if_needed(w, maxd2, have_xb, pre, NULL));
    FLOE_TRY(forces_advancing(w));
    /* 4. v_{n+1} = v_n + dt F_mid / m from the rows, omega from L_{n+1} (MPI: the walls
     * and the owned particles; the ghosts are new) */
    double kt = 0, kr = 0, wbound = 0;
    const int nend = w->par ? w->nl.own_hi : n;
    {
        const int nbe = (nend + FLOE_PAR_BLOCK - 1) / FLOE_PAR_BLOCK;
        int *bad = malloc((size_t)(nbe > 0 ? nbe : 1) * sizeof *bad);
        if (!bad) return step_close(w, floe_world_error(w, FLOE_ENOMEM, "out of memory"));
        rk2_ctx c = {w, h, dt, x0, v0, q0, fm, NULL, L0, NULL, bad, w->par ? w->rk2 : NULL, NULL};
        double s2[2];
        if (floe_world_blocks(w, nend, 2, rk2_close_block, &c, s2)) {
            free(bad);
            return step_close(w, floe_world_error(w, FLOE_ENOMEM, "out of memory"));
        }
        kt = s2[0];
        kr = s2[1];
        for (int i = 0; i < nend; i++)
            if (p->motion[i] == FLOE_KINEMATIC) wbound += kinematic_close(w, i, h);
        /* a particle failed the quick checks: the checks with the message, in index order
         * from the first such block on */
        int first = INT_MAX;
        for (int k = 0; k < nbe; k++)
            if (bad[k] < first) first = bad[k];
        free(bad);
        for (int i = first; i < nend; i++) {
            if (p->motion[i] != FLOE_FREE) continue;
            int rc2 = check_particle(w, i, w->par ? w->rk2 + (size_t)i * RK2_WD + RK2_X : x0 + 3 * i);
            if (rc2) return step_close(w, rc2);
        }
    }
    FLOE_TRY(step_close(w, FLOE_OK));
    w->energy.kinetic_trans = kt;
    w->energy.kinetic_rot = kr;
    w->energy.work_body += wb;
    w->energy.work_boundary += wbound;
    return FLOE_OK;
}

/* ---- staggered PD-DEM (000 §3.2-3.3, Algorithm 2) ----
 * Two force groups: the contact and body forces F_C (DEM and coupling forces, gravity and
 * external forces, counted once as the paper requires) and the PD bond forces F_PD. With
 * dt_PD = dt / m the PD points sub-cycle m velocity Verlet steps with F_PD inside each
 * step, between two half kicks with F_C; with dt_PD = k dt, F_PD is applied as two half
 * kicks of k dt / 2 around every k steps of velocity Verlet with F_C. This is the
 * impulse form of multiple time stepping (r-RESPA, Tuckerman, Berne and Martyna 1992):
 * symmetric, second order and symplectic, and with m = k = 1 it is velocity Verlet (the
 * monolithic scheme) with the two groups evaluated separately. Each particle's row of
 * w->stag (STAG_W doubles, stag_rows) holds F_C, its torque and F_PD between steps, the
 * start position of a PD point's cycle and its true velocity while the contact laws read
 * its mean one. The rows are registered with the world (floe_world_pp_attach), so that
 * under MPI each travels with its particle at every decomposition and is gathered for a
 * checkpoint. Under MPI the loops run over the owned particles [0, own_hi) (the ghosts
 * take their owners' positions and velocities at each refresh); the PD group writes the
 * owned points' forces only (forces.c pd_stage), the contact group's forces on ghosts are
 * summed to their owners (stag_forces). */

/* the rows for every particle here (new rows zero), registered at the first call; NULL:
 * out of memory (the error set) */
double *stag_rows(floe_world *w) {
    const int n = w->p.n;
    if (w->stag_n < n || !w->stag) {
        const int cap = n > 0 ? n : 1;
        double *t = realloc(w->stag, (size_t)cap * STAG_W * sizeof *t);
        if (!t) {
            floe_world_error(w, FLOE_ENOMEM, "out of memory");
            return NULL;
        }
        const int old = w->stag ? w->stag_n : 0;
        memset(t + (size_t)old * STAG_W, 0, (size_t)(cap - old) * STAG_W * sizeof *t);
        w->stag = t;
        w->stag_n = cap;
    }
    if (floe_world_pp_attach(w, &w->stag, &w->stag_n, STAG_W)) {
        floe_world_error(w, FLOE_ENOMEM, "out of memory");
        return NULL;
    }
    return w->stag;
}

/* the particles this rank integrates: all, or under MPI the walls and the owned ones */
static int stag_nend(const floe_world *w) { return w->par ? w->nl.own_hi : w->p.n; }

/* is particle i a PD point (any body)? */
static inline int stag_pd(const int *pd_of, int i) { return pd_of[i] >= 0; }

/* the forces of one group (MPI: this rank's force time booked; the contact group's forces on
 * ghosts summed to their owners, with the servo walls' totals; the PD group writes owned
 * points only) */
static int stag_forces(floe_world *w, const floe_step_ctx *ctx, int group, int pre) {
    int rc = forces_agreed(w, ctx, group, pre); /* as forces_all */
    if (!rc && w->par && group == FLOE_GROUP_DEM) rc = floe_par_reverse(w);
    if (!rc && w->par && group == FLOE_GROUP_DEM) rc = floe_par_servo_totals(w);
    return rc;
}

/* evaluate F_C then F_PD at the present state (prepare), p->f = their sum */
int stag_split_forces(floe_world *w, const floe_step_ctx *ctx) {
    floe_particles *p = &w->p;
    if (!stag_rows(w)) return FLOE_ENOMEM;
    FLOE_TRY(stag_forces(w, ctx, FLOE_GROUP_DEM, FLOE_OK));
    const int n = p->n;
    double *r = stag_rows(w);
    if (!r) return FLOE_ENOMEM;
    for (int i = 0; i < n; i++) {
        memcpy(r + (size_t)i * STAG_W + STAG_FS, p->f + 3 * (size_t)i, 3 * sizeof(double));
        memcpy(r + (size_t)i * STAG_W + STAG_TS, p->t + 3 * (size_t)i, 3 * sizeof(double));
    }
    memset(p->f, 0, 3 * (size_t)n * sizeof *p->f);
    FLOE_TRY(stag_forces(w, ctx, FLOE_GROUP_PD, FLOE_OK));
    for (int i = 0; i < n; i++) {
        double *ri = r + (size_t)i * STAG_W;
        memcpy(ri + STAG_FPD, p->f + 3 * (size_t)i, 3 * sizeof(double));
        for (int a = 0; a < 3; a++) p->f[3 * (size_t)i + a] = ri[STAG_FS + a] + ri[STAG_FPD + a];
        memcpy(p->t + 3 * (size_t)i, ri + STAG_TS, 3 * sizeof(double));
    }
    return FLOE_OK;
}

/* The scheme's particle loops on the world's threads, as RK2's (floe_world_blocks: blocks of
 * FLOE_PAR_BLOCK particles, each block's sums in block order: the same bits for any number of
 * threads); the kinematic particles (their motion callbacks), the boundary work and the checks
 * with a message on one thread after the blocks. One context for every loop: `a` is the
 * loop's time factor. */
typedef struct stag_ctx {
    floe_world *w;
    double *r;          /* the rows */
    const int *pd_of;
    double dt, a;
    int ke, m, op;      /* op: what stag_b_pd does */
    int *bad;           /* stag_b_close: each block's first free particle failing the quick checks */
    double *xo;         /* ... and its position at the step's start (3 a block) */
} stag_ctx;

static int stag_blocks(floe_world *w, int n, int nsum, floe_block_fn fn, stag_ctx *c, double *sum) {
    double dummy[4];
    if (floe_world_blocks(w, n, nsum, fn, c, sum ? sum : dummy)) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    return FLOE_OK;
}

/* the PD points' loops (op): 0 the opening kick of a PD cycle (xs = x; a free point's v += a
 * F_PD / m), 1 a sub-step's closing kick (free: v += a F_PD / m), 2 the mean velocity over the
 * span a (vt = v, v = (x - xs) / a), 3 the true velocity back (v = vt), 4 the forces cleared,
 * 5 F_PD from p->f */
static void stag_b_pd(void *ctx, int i0, int i1, double *sums) {
    const stag_ctx *c = ctx;
    floe_particles *p = &c->w->p;
    const double a = c->a;
    sums[0] = 0.0;
    for (int i = i0; i < i1; i++) {
        if (!stag_pd(c->pd_of, i)) continue;
        double *ri = c->r + (size_t)i * STAG_W, *v = p->v + 3 * i;
        switch (c->op) {
        case 0:
            memcpy(ri + STAG_XS, p->x + 3 * i, 3 * sizeof(double));
            if (p->motion[i] == FLOE_FREE) floe_v3_axpy(v, a * p->inv_mass[i], ri + STAG_FPD);
            break;
        case 1:
            if (p->motion[i] == FLOE_FREE) floe_v3_axpy(v, a * p->inv_mass[i], ri + STAG_FPD);
            break;
        case 2:
            memcpy(ri + STAG_VT, v, 3 * sizeof(double));
            for (int k = 0; k < 3; k++) v[k] = (p->x[3 * i + k] - ri[STAG_XS + k]) / a;
            break;
        case 3: memcpy(v, ri + STAG_VT, 3 * sizeof(double)); break;
        case 4: memset(p->f + 3 * (size_t)i, 0, 3 * sizeof(double)); break;
        default: memcpy(ri + STAG_FPD, p->f + 3 * i, 3 * sizeof(double)); break;
        }
    }
}

/* PD bond forces at the present positions into the rows' fpd, with the PD points moving at
 * their mean velocity (x - xs) / span for the ledger's trapezoid work over that span */
/* *pre: this rank's failure since the last agreement (MPI), told to every rank at the
 * forces' agreement (the return value: agreed); a failure after it (the rows' blocks) is put
 * into *pre for the caller to carry to the next one (one process: returned) */
static int stag_pd_forces(floe_world *w, double span, int mean_velocity, int *pre) {
    const int nend = stag_nend(w);
    stag_ctx c = {w, w->stag, w->pd_of, w->dt, span, w->pd_every, w->pd_sub, 2, NULL, NULL};
    if (mean_velocity && !*pre) *pre = stag_blocks(w, nend, 1, stag_b_pd, &c, NULL);
    c.op = 4; /* the PD points' forces cleared */
    if (!*pre) *pre = stag_blocks(w, nend, 1, stag_b_pd, &c, NULL);
    if (*pre && !w->par) return *pre;
    floe_step_ctx fc = ctx_step(w, 0);
    fc.dt = fc.hist_dt = span; /* the PD step spans the cycle */
    int rc = stag_forces(w, &fc, FLOE_GROUP_PD, *pre); /* (agreed under MPI) */
    if (*pre) return rc; /* (MPI) this rank's rows may be absent */
    double dummy;
    c.op = 5; /* F_PD into the rows (the forces' error, if any, keeps its message) */
    int rc2 = floe_world_blocks(w, nend, 1, stag_b_pd, &c, &dummy);
    if (mean_velocity && !rc2) {
        c.op = 3;
        rc2 = floe_world_blocks(w, nend, 1, stag_b_pd, &c, &dummy);
    }
    if (!rc && rc2) {
        *pre = floe_world_error(w, FLOE_ENOMEM, "out of memory");
        if (!w->par) return *pre;
    }
    return rc;
}

/* step 1 of the free and fixed particles: the half kick with F_C and the drift, except a PD
 * point that sub-cycles (ke == 1; its start position kept, whatever its motion); sums: the
 * body-force work */
static void stag_b_open(void *ctx, int i0, int i1, double *sums) {
    const stag_ctx *c = ctx;
    floe_world *w = c->w;
    floe_particles *p = &w->p;
    const double dt = c->dt, h = 0.5 * dt;
    double wb = 0;
    for (int i = i0; i < i1; i++) {
        double *x = p->x + 3 * i, *v = p->v + 3 * i, *ri = c->r + (size_t)i * STAG_W;
        const int sub = c->ke == 1 && stag_pd(c->pd_of, i);
        if (sub) memcpy(ri + STAG_XS, x, 3 * sizeof(double)); /* fixed points too: step 3 reads it */
        if (p->motion[i] != FLOE_FREE) continue;
        floe_v3_axpy(v, h * p->inv_mass[i], ri + STAG_FS);
        floe_v3_axpy(p->L + 3 * i, h, ri + STAG_TS);
        rotate_drift(p, i, dt);
        if (sub) continue;
        floe_v3_axpy(x, dt, v);
        wb += dt * (p->mass[i] * floe_v3_dot(w->def.gravity, v));
    }
    sums[0] = wb;
}

/* a sub-step of the PD points that are not fixed (a = its length): the free ones' opening
 * kick with F_PD, the drift; sums: the body-force work */
static void stag_b_sub(void *ctx, int i0, int i1, double *sums) {
    const stag_ctx *c = ctx;
    floe_world *w = c->w;
    floe_particles *p = &w->p;
    const double d = c->a, hd = 0.5 * d;
    double wb = 0;
    for (int i = i0; i < i1; i++) {
        if (!stag_pd(c->pd_of, i) || p->motion[i] == FLOE_FIXED) continue;
        double *v = p->v + 3 * i;
        if (p->motion[i] == FLOE_FREE) floe_v3_axpy(v, hd * p->inv_mass[i], c->r + (size_t)i * STAG_W + STAG_FPD);
        floe_v3_axpy(p->x + 3 * i, d, v);
        if (p->motion[i] == FLOE_FREE) wb += d * (p->mass[i] * floe_v3_dot(w->def.gravity, v));
    }
    sums[0] = wb;
}

/* after the contact group: F_C and its torque into the rows (and with sub-steps the PD points'
 * true velocities back) */
static void stag_b_rows(void *ctx, int i0, int i1, double *sums) {
    const stag_ctx *c = ctx;
    floe_particles *p = &c->w->p;
    sums[0] = 0.0;
    for (int i = i0; i < i1; i++) {
        double *ri = c->r + (size_t)i * STAG_W;
        if (c->ke == 1 && stag_pd(c->pd_of, i)) memcpy(p->v + 3 * i, ri + STAG_VT, 3 * sizeof(double));
        memcpy(ri + STAG_FS, p->f + 3 * i, 3 * sizeof(double));
        memcpy(ri + STAG_TS, p->t + 3 * i, 3 * sizeof(double));
    }
}

/* 4. p->f = F_C + F_PD; the free particles' closing kicks; sums: kinetic energies, the shadow
 * term (a = 1 when the watchdog reads it); bad, xo: the block's first particle that fails the
 * checks (check_particle) */
static void stag_b_close(void *ctx, int i0, int i1, double *sums) {
    const stag_ctx *c = ctx;
    floe_particles *p = &c->w->p;
    const double dt = c->dt, h = 0.5 * dt;
    const int m = c->m, shadow = c->a != 0.0;
    double kt = 0, kr = 0, sh = 0;
    int bad = INT_MAX;
    double xb[3] = {0, 0, 0};
    for (int i = i0; i < i1; i++) {
        const double *ri = c->r + (size_t)i * STAG_W, *fs = ri + STAG_FS, *ts = ri + STAG_TS, *fpd = ri + STAG_FPD;
        for (int a = 0; a < 3; a++) p->f[3 * i + a] = fs[a] + fpd[a];
        if (p->motion[i] != FLOE_FREE) continue;
        const int subi = c->ke == 1 && stag_pd(c->pd_of, i);
        double *v = p->v + 3 * i, *L = p->L + 3 * i, im = p->inv_mass[i];
        if (shadow) { /* the closing kicks: the last PD sub-step's and F_C's */
            double dv[3], dL[3];
            for (int k = 0; k < 3; k++) {
                dv[k] = h * im * fs[k] + (subi ? 0.5 * dt / m * im * fpd[k] : 0);
                dL[k] = h * ts[k];
            }
            sh += shadow_term(p, i, dv, dL);
        }
        double xold[3], d2;
        if (subi) memcpy(xold, ri + STAG_XS, sizeof xold);
        else for (int k = 0; k < 3; k++) xold[k] = p->x[3 * i + k] - dt * v[k];
        d2 = (p->x[3 * i] - xold[0]) * (p->x[3 * i] - xold[0]) + (p->x[3 * i + 1] - xold[1]) * (p->x[3 * i + 1] - xold[1]) +
             (p->x[3 * i + 2] - xold[2]) * (p->x[3 * i + 2] - xold[2]);
        if (subi) floe_v3_axpy(v, 0.5 * dt / m * im, fpd); /* last PD sub-step */
        floe_v3_axpy(v, h * im, fs);
        floe_v3_axpy(L, h, ts);
        omega_update(p, i);
        double kin = 0.5 * p->mass[i] * floe_v3_dot(v, v), kre = 0.5 * floe_v3_dot(L, p->w + 3 * i);
        kt += kin;
        kr += kre;
        /* the quick checks, then check_particle's own: the first particle of the block that
         * fails it, with its start position (as the serial loop called it for each one the
         * quick checks flagged, in order) */
        const double lim = 0.5 * p->radius[i];
        if (bad == INT_MAX && (!(d2 <= lim * lim) || !(kin + kre < INFINITY)) && particle_fails(p, i, xold)) {
            bad = i;
            memcpy(xb, xold, sizeof xb);
        }
    }
    const int b = i0 / FLOE_PAR_BLOCK;
    c->bad[b] = bad;
    memcpy(c->xo + 3 * (size_t)b, xb, sizeof xb);
    sums[0] = kt;
    sums[1] = kr;
    sums[2] = sh;
}

/* step 1 of kinematic particle i: its force at the step start kept, its velocity from its
 * motion at the half step, the drift (a PD point that sub-cycles drifts in the sub-steps) */
static void stag_kinematic_open(floe_world *w, int i, int ke, const int *pd_of, double dt) {
    floe_particles *p = &w->p;
    memcpy(w->kin_old + 6 * i, p->f + 3 * i, 3 * sizeof(double));
    memcpy(w->kin_old + 6 * i + 3, p->t + 3 * i, 3 * sizeof(double));
    kinematic_velocity(w, i, w->time + 0.5 * dt);
    if (!(ke == 1 && stag_pd(pd_of, i))) floe_v3_axpy(p->x + 3 * i, dt, p->v + 3 * i);
    double qn[4];
    q_advance(qn, p->q + 4 * i, p->w + 3 * i, dt);
    memcpy(p->q + 4 * i, qn, sizeof qn);
}

int step_staggered(floe_world *w) {
    floe_particles *p = &w->p;
    const int m = w->pd_sub, ke = w->pd_every;
    const double dt = w->dt, h = 0.5 * dt, K = ke * dt;
    int nend = stag_nend(w);
    double *r = stag_rows(w);
    /* a failure on this rank (out of memory): one process returns; under MPI the rank goes
     * on to the next agreement (the PD forces', the states', the rebuild test's or the
     * close's), calling the collectives on the way and moving nothing more, as velocity
     * Verlet's (pre; STAG_RUN) */
    int pre = r ? FLOE_OK : FLOE_ENOMEM; /* (stag_rows set the message) */
    if (pre && !w->par) return pre;
#define STAG_RUN(call)                                                                          \
    do {                                                                                       \
        if (!pre && (pre = (call)) != FLOE_OK && !w->par) return pre;                          \
    } while (0)
    const long cyc = ke > 1 ? w->pd_cycle % ke : 0;
    const int pd_start = ke > 1 && cyc % ke == 0, pd_end = ke > 1 && (cyc + 1) % ke == 0;
    double wb = 0, maxd2 = 0, s1;
    stag_ctx c = {w, r, w->pd_of, dt, 0.0, ke, m, 0, NULL, NULL};
    /* PD every k-th step: the opening half kick of a PD cycle */
    if (pd_start) {
        c.op = 0;
        c.a = 0.5 * K;
        STAG_RUN(stag_blocks(w, nend, 1, stag_b_pd, &c, NULL));
    }
    /* 1. half kick with F_C; drift of everything except the PD points that sub-cycle; then
     * the kinematic particles (MPI: after the servo walls' measures are summed over the
     * ranks: their controllers count the free particles after this drift, as in one process) */
    STAG_RUN(stag_blocks(w, nend, 1, stag_b_open, &c, &wb));
    if (w->par) FLOE_TRY(floe_par_servo_totals(w));
    for (int i = 0; i < nend && !pre; i++)
        if (p->motion[i] == FLOE_KINEMATIC) stag_kinematic_open(w, i, ke, c.pd_of, dt);
    /* 2. dt_PD = dt / m: m velocity Verlet sub-steps of the PD points with F_PD (MPI: the
     * ghosts take their owners' new positions before each evaluation) */
    if (ke == 1) {
        const double d = dt / m;
        for (int s = 0; s < m; s++) {
            c.a = d;
            s1 = 0;
            STAG_RUN(stag_blocks(w, nend, 1, stag_b_sub, &c, &s1));
            wb += s1;
            if (w->par) FLOE_TRY(floe_par_ghost_update(w));
            FLOE_TRY(stag_pd_forces(w, d, 0, &pre)); /* (agreed under MPI: pre is told here) */
            if (s == m - 1) break; /* the last sub-step closes with the final kick below */
            c.op = 1;
            c.a = 0.5 * d;
            STAG_RUN(stag_blocks(w, nend, 1, stag_b_pd, &c, NULL));
        }
    }
    const double *mn = growth_masses(w, nend, 0, &pre);
    pre = states_step(w, dt, pre);
    if (states_done(w, pre)) return pre;
    if (mn && !pre) wb += growth_gravity_work(w, mn, nend, dt, ke == 1 ? c.pd_of : NULL);
    advance_clock(w);
    w->pd_cycle++;
    /* 3. F_C at the new positions; sub-cycled PD points move at their mean velocity over
     * the step for the contact laws (the tangential spring grows by the displacement) and
     * the ledger: set before the rebuild, so that under MPI the ghosts take it with their
     * positions, the true one (vt) travelling in the rows with a migrating point */
    if (ke == 1) {
        c.op = 2;
        c.a = dt;
        STAG_RUN(stag_blocks(w, nend, 1, stag_b_pd, &c, NULL));
    }
    {
        const int n = p->n;
        const double *xb = w->nl.x_build;
        const int have_xb = xb && w->nl.n_build == n;
        if (have_xb)
            for (int i = 0; i < n; i++)
                if (p->motion[i] != FLOE_FIXED) note_disp(p->x + 3 * i, xb + 3 * i, &maxd2);
        /* (MPI: a failure carried here is every rank's, the clock put back, and the PD
         * cycle's count with it) */
        const long step_now = w->step;
        const int rrc = rebuild_if_needed(w, maxd2, have_xb, pre, NULL);
        if (rrc) {
            if (w->step != step_now) w->pd_cycle--;
            return rrc;
        }
    }
    /* MPI: a decomposition migrates particles (the store, the rows and pd_of are new) */
    nend = stag_nend(w);
    c.r = r = w->stag;
    c.pd_of = w->pd_of;
    floe_step_ctx fc = ctx_step(w, contacts_wanted(w));
    int rc = stag_forces(w, &fc, FLOE_GROUP_DEM, FLOE_OK);
    if (rc) {
        if (ke == 1) { /* the true velocities back before the error returns (its message kept) */
            double dummy;
            c.op = 3;
            (void)floe_world_blocks(w, nend, 1, stag_b_pd, &c, &dummy);
        }
        return rc;
    }
    STAG_RUN(stag_blocks(w, nend, 1, stag_b_rows, &c, NULL));
    /* PD every k-th step: the closing evaluation and half kick of the cycle */
    if (pd_end) {
        FLOE_TRY(stag_pd_forces(w, K, 1, &pre)); /* (agreed under MPI) */
        c.op = 1;
        c.a = 0.5 * K;
        STAG_RUN(stag_blocks(w, nend, 1, stag_b_pd, &c, NULL));
    }
#undef STAG_RUN
    if (pre) return step_close(w, pre); /* (MPI: told at the close) */
    /* 4. closing half kick with F_C; p->f = F_C + F_PD for the observers; the kinematic
     * particles' step close, then the checks with a message (a block's first particle that
     * failed the quick ones) */
    const int nbe = (nend + FLOE_PAR_BLOCK - 1) / FLOE_PAR_BLOCK;
    int *bad = malloc((size_t)(nbe > 0 ? nbe : 1) * sizeof *bad);
    double *xo = malloc((size_t)(nbe > 0 ? nbe : 1) * 3 * sizeof *xo), s3[3] = {0, 0, 0};
    if (!bad || !xo) {
        free(bad);
        free(xo);
        return step_close(w, floe_world_error(w, FLOE_ENOMEM, "out of memory"));
    }
    c.bad = bad;
    c.xo = xo;
    c.a = w->def.energy_check != FLOE_CHECK_OFF ? 1.0 : 0.0;
    rc = stag_blocks(w, nend, 3, stag_b_close, &c, s3);
    double wbound = 0;
    for (int i = 0; !rc && i < nend; i++)
        if (p->motion[i] == FLOE_KINEMATIC) wbound += kinematic_close(w, i, h);
    for (int b = 0; !rc && b < nbe; b++)
        if (bad[b] != INT_MAX) rc = check_particle(w, bad[b], xo + 3 * (size_t)b);
    free(bad);
    free(xo);
    FLOE_TRY(step_close(w, rc));
    w->wd_shadow = s3[2];
    w->energy.kinetic_trans = s3[0];
    w->energy.kinetic_rot = s3[1];
    w->energy.work_body += wb;
    w->energy.work_boundary += wbound;
    return FLOE_OK;
}

/* Energy of the closing half kick of free particle i (velocity change dv, angular momentum
 * change dL): 1/2 m |dv|^2 + 1/2 dL . I^-1 dL. Velocity Verlet conserves exactly (linear
 * forces) K + U minus this term (1/2 m v_{n+1/2} . v_{n-1/2} + U), not K + U, whose
 * measured value oscillates by up to (w dt/2)^2 / (1 - (w dt/2)^2) near the stability
 * limit; the energy watchdog compares that conserved form (w->wd_shadow). */
double shadow_term(const floe_particles *p, int i, const double dv[3], const double dL[3]) {
    double e = 0.5 * p->mass[i] * floe_v3_dot(dv, dv);
    const double *I = p->inertia + 3 * i;
    if (p->iso[i]) {
        e += 0.5 * floe_v3_dot(dL, dL) * p->inv_iso[i];
    } else {
        double b[3];
        floe_q_rotate_inv(b, p->q + 4 * i, dL);
        for (int k = 0; k < 3; k++)
            if (I[k] > 0 && isfinite(I[k])) e += 0.5 * b[k] * b[k] / I[k];
    }
    return e;
}
