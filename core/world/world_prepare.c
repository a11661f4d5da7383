/* world_prepare.c - the store's part of prepare (providers, masses, the laws and detectors
 * every pair needs, estimates; the neighbour list and clock; the energy at the start; the
 * observers' start), observers and finish. floe_world_prepare itself, which chooses the step
 * and evaluates the first forces with the integrator, is the driver's
 * (core/integrators/driver.c). */
#include "world_parts.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const floe_provider_class floe_body_provider_class, floe_beam_provider_class, floe_contact_provider_class,
    floe_pd_provider_class;

/* The providers of this scene, in evaluation order: body forces, beam bonds (when there are
 * bonds), contacts, PD bonds (when there are PD bodies). Model only what the scene holds. */
static int build_providers(floe_world *w) {
    const floe_provider_class *want[4];
    int n = 0;
    want[n++] = &floe_body_provider_class;
    if (w->beams) want[n++] = &floe_beam_provider_class;
    want[n++] = &floe_contact_provider_class;
    if (w->npd) want[n++] = &floe_pd_provider_class;
    for (int k = 0; k < w->nprov; k++)
        if (!floe_provider_is_user(w, w->prov[k])) free(w->prov[k]);
    w->nprov = 0;
    if (grow((void **)&w->prov, &w->prov_cap, n + w->nuprov, sizeof *w->prov))
        return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    for (int k = 0; k < n; k++) {
        floe_provider *pv = malloc(sizeof *pv);
        if (!pv) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        pv->klass = want[k];
        w->prov[w->nprov++] = pv;
        /* user providers (floe_world_add_provider) after the body forces, in their order */
        for (int u = 0; k == 0 && u < w->nuprov; u++) w->prov[w->nprov++] = w->uprov[u];
    }
    return FLOE_OK;
}

int floe_world_provider_count(const floe_world *w) { return w ? w->nprov : 0; }
const floe_provider *floe_world_provider(const floe_world *w, int k) {
    return w && k >= 0 && k < w->nprov ? w->prov[k] : NULL;
}

/* the context of an evaluation at the end of a step (history and ledger advance) */
floe_step_ctx ctx_step(floe_world *w, int record) {
    floe_step_ctx c = {&w->p, w->def.dim, 1, w->time, w->dt, w->dt, 0, record, w->track_depth};
    return c;
}

/* bytes of every provider's state; save = 1 writes them into buf, 0 reads them back */
size_t providers_state_size(const floe_world *w) {
    size_t n = 0;
    for (int k = 0; k < w->nprov; k++)
        if (w->prov[k]->klass->state_size) n += w->prov[k]->klass->state_size(w->prov[k], w);
    return n;
}
void providers_state_io(floe_world *w, unsigned char *buf, int save) {
    for (int k = 0; k < w->nprov; k++) {
        floe_provider *pv = w->prov[k];
        if (!pv->klass->state_size) continue;
        size_t m = pv->klass->state_size(pv, w);
        if (save) pv->klass->save(pv, w, buf);
        else pv->klass->restore(pv, w, buf);
        buf += m;
    }
}

int prepare_store(floe_world *w) {
    floe_particles *p = &w->p;
    FLOE_TRY(build_providers(w));
    /* masses and inertia */
    for (int i = 0; i < p->n; i++) {
        const floe_geometry *g = w->geoms[p->geom[i]];
        if (!isfinite(p->radius[i])) {
            p->mass[i] = INFINITY;
            p->inv_mass[i] = 0;
            floe_v3_set(p->inertia + 3 * i, INFINITY, INFINITY, INFINITY);
            continue;
        }
        if (!(p->radius[i] > 0)) return floe_world_error(w, FLOE_EINVAL, "particle %d: bounding radius must be > 0", i);
        floe_mass_properties mp;
        int mdim = (w->def.dim == 2 && w->def.mass_2d_area) ? 2 : 3;
        int polygon = floe_geometry_dimension(g) == 2;
        if (polygon && w->def.dim == 3)
            return floe_world_error(w, FLOE_EINVAL,
                                    "particle %d: a polygon is a 2D shape (dim: 2); in 3D use a prism or polyhedron", i);
        if (polygon) mdim = 2; /* a polygon has no 3D body: mass per metre of thickness */
        const double h = p->thick ? p->thick[i] : 0;
        if (h > 0) mdim = 2;   /* a floe: area x thickness */
        if (w->def.dim == 2 && floe_geometry_dimension(g) == 3)
            return floe_world_error(w, FLOE_EINVAL,
                                    "particle %d: a polyhedron (or prism, mesh) is a 3D shape; in 2D use a polygon", i);
        int rc = floe_geometry_mass_properties(g, mdim, w->mats[p->material[i]].density, &mp);
        if (rc) return floe_world_error(w, rc, "particle %d: mass properties of its %s failed", i, g->klass->name);
        /* the body frame must be the principal frame at the centre of mass: the integrator
         * rotates about the origin with the inertia diagonal in the body axes */
        double off = floe_v3_norm(mp.centroid);
        if (off > 1e-2 * p->radius[i] || mp.off_axis > 1e-2)
            return floe_world_error(w, FLOE_EINVAL,
                                    "particle %d: its %s shape has its centre of mass at (%g, %g, %g) and "
                                    "off-diagonal inertia %.2g (relative): define the SDF about the centre "
                                    "of mass with the principal axes along x, y, z",
                                    i, g->klass->name, mp.centroid[0], mp.centroid[1], mp.centroid[2], mp.off_axis);
        if (h > 0) { /* a floe of thickness h: mass and inertia per metre, times h */
            mp.mass *= h;
            for (int k = 0; k < 3; k++) mp.inertia[k] *= h;
        }
        if (p->mass[i] > 0) { /* user mass: scale inertia */
            double s = p->mass[i] / mp.mass;
            for (int k = 0; k < 3; k++) mp.inertia[k] *= s;
        } else p->mass[i] = mp.mass;
        if (!(p->mass[i] > 0) || !isfinite(p->mass[i]))
            return floe_world_error(w, FLOE_EINVAL, "particle %d: mass must be > 0 and finite (got %g)", i, p->mass[i]);
        memcpy(p->inertia + 3 * i, mp.inertia, sizeof mp.inertia);
        {
            const double *I = mp.inertia;
            double imax = fmax(I[0], fmax(I[1], I[2])), imin = fmin(I[0], fmin(I[1], I[2]));
            /* 2D rotates about z only, so only I_zz matters: treat as isotropic with I_zz */
            p->iso[i] = w->def.dim == 2 || imax - imin <= 1e-12 * imax;
            if (w->def.dim == 2) p->inertia[3 * i] = p->inertia[3 * i + 1] = I[2];
        }
        floe_particle_inv_iso_update(p, i);
        p->inv_mass[i] = p->motion[i] == FLOE_FREE ? 1.0 / p->mass[i] : 0;
        L_from_omega(p->q + 4 * i, p->inertia + 3 * i, p->w + 3 * i, p->L + 3 * i);
    }
    orientation_refresh(w);
    /* laws whose critical step assumes the thickest floe (Hopkins' thickness_max): no floe of
     * their materials may be thicker, or the step estimate would be unsafe */
    if (p->thick)
        for (int a = 0; a < w->nmats; a++)
            for (int b = a; b < w->nmats; b++) {
                const floe_contact_law *law = w->laws[a * w->nmats + b];
                const double hmax = law ? floe_contact_law_info(law).thickness_max : 0;
                if (!(hmax > 0)) continue;
                for (int i = 0; i < p->n; i++)
                    if ((p->material[i] == a || p->material[i] == b) && p->thick[i] > hmax)
                        return floe_world_error(w, FLOE_EINVAL,
                                                "particle %d (body %d) is %g m thick, more than thickness_max = %g m "
                                                "of the %s law for (%s, %s), which its critical time step assumes: "
                                                "set the law's thickness_max to the thickest floe",
                                                i, p->group[i], p->thick[i], hmax, law->klass->name, w->mats[a].name,
                                                w->mats[b].name);
            }
    /* every material pair that can meet needs a law; every geometry pair a detector */
    for (int a = 0; a < w->nmats; a++)
        for (int b = a; b < w->nmats; b++) {
            if (w->laws[a * w->nmats + b]) continue;
            int used_a = 0, used_b = 0, free_a = 0, free_b = 0;
            for (int i = 0; i < p->n; i++) {
                if (p->material[i] == a) { used_a++; free_a |= p->motion[i] == FLOE_FREE; }
                if (p->material[i] == b) { used_b++; free_b |= p->motion[i] == FLOE_FREE; }
            }
            /* a pair can meet if both are present (two particles when a == b) and one is free */
            int meet = a == b ? used_a >= 2 && free_a : used_a && used_b && (free_a || free_b);
            if (meet)
                return floe_world_error(w, FLOE_EINVAL, "no contact law for the material pair (%s, %s)",
                                        w->mats[a].name, w->mats[b].name);
        }
    {
        /* geometry pairs present among (free, any) particles; geometries of one class that
         * are not unions stand for each other (detection goes by class: a field of 10,000
         * floes has 10,000 polygons of one class) */
        int ng = w->ngeoms;
        int *seen = calloc((size_t)ng * 4, sizeof(int));
        if (!seen) return FLOE_ENOMEM;
        int *rep = seen + 2 * ng, *firsts = seen + 3 * ng, nfirst = 0;
        for (int g = 0; g < ng; g++) {
            const floe_geometry *G = w->geoms[g];
            rep[g] = g;
            if (G->klass->piece || floe_geometry_piece_count(G) != 1) continue;
            int r = 0;
            while (r < nfirst && w->geoms[firsts[r]]->klass != G->klass) r++; /* a handful of classes */
            if (r == nfirst) firsts[nfirst++] = g;
            rep[g] = firsts[r];
        }
        for (int i = 0; i < p->n; i++) seen[2 * rep[p->geom[i]] + (p->motion[i] == FLOE_FREE)]++;
        int rc = FLOE_OK;
        for (int a = 0; a < ng && !rc; a++) {
            if (!seen[2 * a + 1]) continue;
            for (int b = 0; b < ng && !rc; b++) {
                int nb = seen[2 * b] + seen[2 * b + 1];
                if (nb < (a == b ? 2 : 1)) continue;
                if (!floe_detect_supported(w->geoms[a], w->geoms[b]))
                    rc = floe_world_error(w, FLOE_ENOTSUP, "no contact detector for the pair %s-%s",
                                          w->geoms[a]->klass->name, w->geoms[b]->klass->name);
                else if (floe_detect_needs_warm(w->geoms[a], w->geoms[b]))
                    w->nl.use_warm = 1; /* ADMM / LP pairs: keep warm starts */
            }
        }
        free(seen);
        if (rc) return rc;
    }
    if (w->npd) {
        /* PD bookkeeping: the body index of particles added after the bodies, last forces */
        if (w->pd_npts_alloc < p->n) {
            int *po = realloc(w->pd_of, (size_t)p->n * sizeof *po);
            if (!po) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            for (int i = w->pd_npts_alloc; i < p->n; i++) po[i] = -1;
            w->pd_of = po;
            w->pd_npts_alloc = p->n;
        }
        double *fo = realloc(w->pd_fold, (size_t)3 * w->pd_npts * sizeof *fo);
        if (fo) w->pd_fold = fo;
        double *fn = fo ? realloc(w->pd_fnew, (size_t)3 * w->pd_npts * sizeof *fn) : NULL;
        if (fn) w->pd_fnew = fn;
        double *eo = fn ? realloc(w->pd_eold, (size_t)w->npd * sizeof *eo) : NULL;
        if (eo) w->pd_eold = eo;
        if (!fo || !fn || !eo) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        if (w->pd_diss_n < w->npd) { /* the watchdog's per-body dissipation, kept across re-prepares */
            double *pdd = realloc(w->pd_diss, (size_t)w->npd * sizeof *pdd);
            if (!pdd) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            for (int k = w->pd_diss_n; k < w->npd; k++) pdd[k] = 0;
            w->pd_diss = pdd;
            double *sum = realloc(w->pd_diss_sum, (size_t)w->npd * sizeof *sum);
            if (!sum) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
            w->pd_diss_sum = sum;
            w->pd_diss_n = w->npd;
        }
        memset(w->pd_fold, 0, (size_t)3 * w->pd_npts * sizeof *fo);
    }
    return estimate_dt(w);
}

int prepare_state(floe_world *w) {
    floe_particles *p = &w->p;
    int rc = floe_world_nl_build(w);
    if (rc) return floe_world_error(w, rc, "neighbour list build failed (out of memory)");
    {
        double *ko = realloc(w->kin_old, (size_t)(p->n ? p->n : 1) * 6 * sizeof(double));
        if (!ko) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        w->kin_old = ko;
        w->kin_old_n = p->n;
        /* written at a step's start and read at its end, with an MPI decomposition between
         * them: registered as a per-particle row, so that it travels with its particle, in a
         * world that has kinematic particles (the others' migrations carry nothing more; a
         * motion set later unprepares the world), first among the rows (its place then does
         * not depend on when the world was prepared) */
        int kin = 0;
        for (int i = 0; i < p->n && !kin; i++) kin = p->motion[i] == FLOE_KINEMATIC;
        if (kin && floe_world_pp_attach_first(w, &w->kin_old, &w->kin_old_n, 6))
            return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    /* the watchdog's floor on the energy scale: every free particle lifted by its size
     * against gravity (a resting pile has little kinetic energy, yet that is the energy
     * its contacts are measured against) */
    {
        double g = floe_v3_norm(w->def.gravity), gs = 0;
        for (int i = 0; i < p->n; i++)
            if (p->motion[i] == FLOE_FREE && isfinite(p->radius[i])) gs += p->mass[i] * g * p->radius[i];
        w->wd_gscale = gs;
    }
    w->prepared = 1;
    w->t0 = w->time;
    w->step0 = w->step;
    return FLOE_OK;
}

void prepare_ledger(floe_world *w, double shadow) {
    const floe_particles *p = &w->p;
    /* energy at start */
    floe_energy *e = &w->energy;
    double kt = 0, kr = 0;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE) continue;
        kt += 0.5 * p->mass[i] * floe_v3_dot(p->v + 3 * i, p->v + 3 * i);
        kr += 0.5 * floe_v3_dot(p->L + 3 * i, p->w + 3 * i);
    }
    e->kinetic_trans = kt;
    e->kinetic_rot = kr;
    w->wd_shadow = shadow;
    w->wd_shadow0 = w->wd_shadow; /* the watchdog's balance restarts with the ledger */
    if (w->step == 0) {
        e->initial = kt + kr + e->elastic;
        e->work_body = e->work_boundary = e->dissipated = 0;
    } else {
        /* re-prepared mid-run (particles added, motion changed): the ledger goes on from
         * the present state, so the balance error restarts from 0 here */
        e->initial = kt + kr + e->elastic + e->dissipated - e->work_body - e->work_boundary;
    }
}

int prepare_observers(floe_world *w) {
    for (int k = 0; k < w->nobs; k++) {
        floe_observer *o = w->obs[k];
        if (o->begun) continue; /* re-prepared mid-run: already writing */
        o->begun = 1;
        o->next_time = w->time;
        if (o->klass->begin) {
            int rc = o->klass->begin(o, w);
            if (rc) return floe_world_error(w, rc, "observer %s failed to start: %s", o->klass->name,
                                            w->err[0] ? w->err : "(no message)");
        }
    }
    return observers_call(w, 1);
}

static int observer_due(const floe_world *w, const floe_observer *o) {
    if (o->period_steps > 0) return w->step % o->period_steps == 0;
    if (o->period_time > 0) return w->time >= o->next_time - 1e-9 * w->dt;
    return 1;
}

/* contact records are kept only at force evaluations that an observer will read */
int contacts_wanted(const floe_world *w) {
    if (w->record_contacts) return 1;
    /* MPI: the mirror's outputs read the contacts gathered from every rank */
    if (w->par_contacts && (w->par_contacts & 2 || w->last_step_of_run)) return 1;
    if (!w->obs_need_contacts) return 0;
    if (w->last_step_of_run) return 1; /* observers write the final state at the end */
    for (int k = 0; k < w->nobs; k++)
        if (w->obs[k]->klass->needs_contacts && observer_due(w, w->obs[k])) return 1;
    return 0;
}

int observers_call(floe_world *w, int force_all) {
    if (w->obs_muted) return FLOE_OK;
    for (int k = 0; k < w->nobs; k++) {
        floe_observer *o = w->obs[k];
        int due = force_all || observer_due(w, o);
        if (!due) continue;
        if (o->period_time > 0 && o->period_steps <= 0)
            while (o->next_time <= w->time + 1e-9 * w->dt) o->next_time += o->period_time;
        w->err[0] = 0;
        int rc = o->klass->observe(o, w);
        if (rc) {
            char why[sizeof w->err];
            memcpy(why, w->err, sizeof why);
            return floe_world_error(w, rc, "observer %s failed at step %ld: %s", o->klass->name, w->step,
                                    why[0] ? why : floe_strerror(rc));
        }
    }
    return FLOE_OK;
}

int floe_world_finish(floe_world *w) {
    int rc = FLOE_OK;
    char first[sizeof w->err]; /* the first failure's message is the one reported (a full disk
                                  fails every writer: the first names the cause) */
    first[0] = 0;
    for (int k = 0; k < w->nobs; k++) {
        floe_observer *o = w->obs[k];
        if (o->ended) continue;
        o->ended = 1;
        if (o->klass->end) {
            int r = o->klass->end(o, w);
            if (r && !rc) { rc = r; memcpy(first, w->err, sizeof first); }
        }
    }
    if (rc) memcpy(w->err, first, sizeof first);
    w->finished = 1;
    return rc;
}
