/* world_pd.c - peridynamic bodies of a world and their boundary regions (ParticLS eq 37). */
#include "world_parts.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
/* ---- peridynamic bodies ---- */

/* Contact exclusion of two points of the same PD body. An unbonded pair (beyond the
 * horizon, or across a pre-crack: floe_pd_add_crack removes those bonds) meets by contact
 * unless its contact spheres overlap in the reference configuration, as a broken pair
 * below (only a pre-crack makes such pairs on a lattice). A bonded pair gets no contact while
 * its bond is intact (the bond is the interaction), nor when it is broken but still acts
 * (a PMB bond with broken_tension_only pushes in compression, 003 eq 2 mu = 1). Other broken
 * pairs meet by contact, except those whose contact spheres already overlap in the
 * reference configuration (|xi| < R_i + R_j: the nearest lattice neighbours at 1 dx, with
 * R = 0.62 dx): a contact there would push the faces of a fresh crack apart at once with
 * the force of a 0.24 dx overlap. Across a crack the next pairs (sqrt 2 dx) are in contact
 * range, so closing cracks still resist. */
int floe_pd_pair_excluded(const floe_world *w, int i, int j) {
    int bi = w->pd_of[i];
    if (bi < 0 || bi != w->pd_of[j]) return 0;
    const int li = floe_pd_local(w, bi, i), lj = floe_pd_local(w, bi, j);
    const floe_pd_body *b = w->pd[bi];
    int64_t k = floe_pd_bond_index(b, li, lj);
    if (k < 0) { /* not bonded (a pre-crack's faces, floe_pd_add_crack): as a broken pair */
        double d[3];
        floe_v3_sub(d, b->X + 3 * (size_t)lj, b->X + 3 * (size_t)li);
        return floe_v3_norm(d) < w->p.radius[i] + w->p.radius[j];
    }
    if (!b->broken[k]) return 1;
    if (b->mat.model == FLOE_PD_PMB && b->mat.broken_tension_only) return 1;
    return b->len[k] < w->p.radius[i] + w->p.radius[j];
}

/* the pairs that never enter the contact list: bonded PD family members (pd_exclude) and
 * particles held by an intact beam bond (pairs under the law "none": neighbor.c) */
static int world_exclude(const void *ctx, int i, int j) {
    const floe_world *w = ctx;
    if (w->nprov) { /* the providers that hold pairs (PD families, beam bonds, ...) */
        for (int k = 0; k < w->nprov; k++) {
            const floe_provider *pv = w->prov[k];
            if (pv->klass->excludes && pv->klass->excludes(pv, w, i, j)) return 1;
        }
        return 0;
    }
    if (w->npd && floe_pd_pair_excluded(w, i, j)) return 1; /* before the first prepare */
    return w->beams && floe_beam_set_excludes(w->beams, i, j);
}

/* a pair through image n of the periodic cell: excluded as above when its points are bonded
 * (across the faces: the cell is wider than two horizons, so the image within contact reach
 * is the bond's); an unbonded pair of one body (a crack cut after the cell was set,
 * floe_pd_add_crack) as a broken pair, its reference distance through the same image */
static int world_exclude_image(const void *ctx, int i, int j, const int n[3]) {
    const floe_world *w = ctx;
    if (!w->npd) return 0;
    int bi = w->pd_of[i];
    if (bi < 0 || bi != w->pd_of[j]) return 0;
    const int li = floe_pd_local(w, bi, i), lj = floe_pd_local(w, bi, j);
    const floe_pd_body *b = w->pd[bi];
    if (floe_pd_bond_index(b, li, lj) >= 0) return floe_pd_pair_excluded(w, i, j);
    double d[3];
    floe_v3_sub(d, b->X + 3 * (size_t)lj, b->X + 3 * (size_t)li);
    for (int r = 0; r < 3; r++) d[r] += b->cellH0[3 * r] * n[0] + b->cellH0[3 * r + 1] * n[1] + b->cellH0[3 * r + 2] * n[2];
    return floe_v3_norm(d) < w->p.radius[i] + w->p.radius[j];
}

void floe_world_install_exclusion(floe_world *w) {
    w->nl.exclude = world_exclude;
    w->nl.exclude_image = world_exclude_image;
    w->nl.exclude_ctx = w;
}

/* 1 when broken pairs of body b can meet by contact (pd_exclude) */
static int pd_broken_pairs_touch(const floe_pd_body *b) {
    return !(b->mat.model == FLOE_PD_PMB && b->mat.broken_tension_only);
}

/* 1 when the neighbour list holds the pair (i, j), i < j (sorted by (i, j): a binary
 * search; if the list were not sorted this only ever answers 0, i.e. rebuild) */
static int nl_has_pair(const floe_neighbor_list *nl, int i, int j) {
    int lo = 0, hi = nl->npairs;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (nl->pi[mid] < i || (nl->pi[mid] == i && nl->pj[mid] < j)) lo = mid + 1;
        else hi = mid;
    }
    return lo < nl->npairs && nl->pi[lo] == i && nl->pj[lo] == j;
}

int floe_pd_broken_pairs_reachable(floe_world *w) {
    /* bonds broke this evaluation: a broken pair that may now touch (pd_exclude) and is
     * within reach (R_i + R_j + skin) must be in the list before it can touch; the Verlet
     * criterion does not see it (nothing moved), so rebuild now. Only bodies whose broken
     * pairs can touch are scanned, and only at evaluations where their count changed. */
    int rebuild = 0;
    const floe_particles *p = &w->p;
    for (int b = 0; b < w->npd; b++) {
        floe_pd_body *pb = w->pd[b];
        if ((long long)pb->nbroken == w->pd_nbroken_seen[b]) continue;
        w->pd_nbroken_seen[b] = (long long)pb->nbroken;
        if (rebuild || !pd_broken_pairs_touch(pb)) continue;
        double skin = w->nl.skin;
        for (int i = 0; i < pb->n && !rebuild; i++)
            for (int64_t k = pb->off[i]; k < pb->off[i + 1]; k++) {
                if (!pb->broken[k]) continue;
                int a = floe_pd_particle(w, b, i), c = floe_pd_particle(w, b, pb->partner[k]);
                if (a < 0 || c < 0) continue; /* split: not both here (the pair's rank sees it) */
                double rr = p->radius[a] + p->radius[c];
                if (pb->len[k] < rr) continue; /* excluded (overlap in the reference) */
                if (p->motion[a] != FLOE_FREE && p->motion[c] != FLOE_FREE) continue;
                double d[3];
                floe_v3_sub(d, p->x + 3 * c, p->x + 3 * a);
                if (pb->img && pb->img[k]) { /* across the periodic cell's faces: c's image */
                    double sh[3];
                    floe_img_shift(w->cell->H, pb->img[k], sh);
                    floe_v3_add(d, d, sh);
                }
                if (floe_v3_dot(d, d) > (rr + skin) * (rr + skin)) continue;
                if (!nl_has_pair(&w->nl, a, c)) { rebuild = 1; break; }
            }
    }
    return rebuild;
}

/* the contact radius of a point of volume V */
static double pd_contact_radius(const floe_pd_body *b, double V) {
    return b->dim == 3 ? cbrt(3.0 * V / (4.0 * M_PI)) : sqrt(V / (M_PI * b->thickness));
}

int floe_world_pd_periodic(floe_world *w, struct floe_pd_body *b, int k) {
    const floe_cell_state *c = w->cell;
    int rc = floe_pd_make_periodic(b, c->o, c->H, c->H);
    if (rc == FLOE_EINVAL)
        return floe_world_error(w, rc, "PD body %d: its families cannot be found through the periodic cell's images: "
                                "the cell must be wider than two horizons (2 x %g m) across every pair of faces, and no "
                                "two points may lie on one spot through the faces (points on both of two opposite "
                                "faces)%s", k, b->delta, b->nbroken ? ", and no bond may be broken yet" : "");
    if (rc == FLOE_ENOTSUP)
        return floe_world_error(w, rc, "PD body %d: a body with pre-cracks or a user material cannot bond through the "
                                "periodic cell's images (set the cell first and cut the cracks after, on its own "
                                "material)", k);
    if (rc != FLOE_OK) return floe_world_error(w, rc, "PD body %d: periodic families: %s", k, floe_strerror(rc));
    return FLOE_OK;
}

int floe_world_add_pd_body(floe_world *w, struct floe_pd_body *body, int material, const double v0[3], int *first) {
    if (!body) return floe_world_error(w, FLOE_EINVAL, "PD body: NULL");
    if (floe_world_refuse_split(w, "add_pd_body")) {
        floe_pd_body_destroy(body); /* owned, as on every error */
        return FLOE_ENOTSUP;
    }
    if (material < 0 || material >= w->nmats) {
        floe_pd_body_destroy(body);
        return floe_world_error(w, FLOE_EINVAL, "PD body: contact material index %d out of range", material);
    }
    if (!body->ops || body->n < 1 || body->dim != w->def.dim) {
        int bd = body->dim;
        floe_pd_body_destroy(body);
        return floe_world_error(w, FLOE_EINVAL, "PD body: %s", bd != w->def.dim ? "its dimension differs from the world's"
                                                                                 : "no points or no material set");
    }
    if (v0 && !(isfinite(v0[0]) && isfinite(v0[1]) && isfinite(v0[2]))) {
        floe_pd_body_destroy(body);
        return floe_world_error(w, FLOE_EINVAL, "PD body: the initial velocity must be finite");
    }
    if (w->cell) { /* families through the cell's images (docs/periodic.md) */
        int rc = floe_world_pd_periodic(w, body, w->npd);
        if (rc != FLOE_OK) { floe_pd_body_destroy(body); return rc; }
    }
    if (w->npd == w->pd_cap) {
        int nc = w->pd_cap ? 2 * w->pd_cap : 4;
        struct floe_pd_body **a = realloc(w->pd, (size_t)nc * sizeof *a);
        if (a) w->pd = a;
        int *b = a ? realloc(w->pd_first, (size_t)nc * sizeof *b) : NULL;
        if (b) w->pd_first = b;
        long long *s = b ? realloc(w->pd_nbroken_seen, (size_t)nc * sizeof *s) : NULL;
        if (s) w->pd_nbroken_seen = s;
        if (!a || !b || !s) { floe_pd_body_destroy(body); return floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
        w->pd_cap = nc;
    }
    /* on any failure below, the particles and geometries added so far are removed again:
     * a failed add leaves the world as it was */
    const int ng0 = w->ngeoms, n0 = w->p.n, prepared0 = w->prepared;
    int rc = FLOE_OK, r;
    /* one sphere geometry per point volume (lattice bodies: one) */
    double Vg = 0;
    int gi = -1;
    for (int i = 0; i < body->n && rc == FLOE_OK; i++) {
        if (gi < 0 || body->V[i] != Vg) {
            Vg = body->V[i];
            double R = pd_contact_radius(body, Vg);
            floe_geometry *g = floe_sphere_create(R);
            gi = g ? floe_world_add_geometry(w, g) : -FLOE_ENOMEM;
            if (gi < 0) {
                floe_geometry_destroy(g);
                if (isfinite(R) && R > 0) rc = floe_world_error(w, FLOE_ENOMEM, "out of memory");
                else rc = floe_world_error(w, FLOE_EINVAL, "PD body: point %d: volume %g gives no contact radius", i, Vg);
                break;
            }
        }
        floe_particle_def d = floe_default_particle_def();
        d.geometry = gi;
        d.material = material;
        floe_v3_copy(d.x, body->X + 3 * i);
        if (v0) floe_v3_copy(d.v, v0);
        d.mass = body->mat.rho * body->V[i];
        d.group = -2 - w->npd; /* PD body k writes body = -2 - k in outputs */
        if ((r = floe_world_add_particle(w, &d)) < 0) {
            char why[sizeof w->err];
            memcpy(why, w->err, sizeof why);
            rc = floe_world_error(w, -r, "PD body: point %d: %s", i, why);
        }
    }
    /* body index of every particle (allocated with the first PD body) */
    int *po = NULL;
    if (rc == FLOE_OK) {
        po = realloc(w->pd_of, (size_t)(w->p.cap > 0 ? w->p.cap : 1) * sizeof *po);
        if (po) w->pd_of = po;
        else rc = floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    if (rc != FLOE_OK) {
        for (int g = ng0; g < w->ngeoms; g++) floe_geometry_destroy(w->geoms[g]);
        w->ngeoms = ng0;
        w->p.n = n0;
        w->prepared = prepared0;
        floe_pd_body_destroy(body);
        return rc;
    }
    for (int i = w->npd ? w->pd_npts_alloc : 0; i < n0; i++) po[i] = -1;
    for (int i = n0; i < w->p.n; i++) po[i] = w->npd;
    w->pd_npts_alloc = w->p.n;
    w->pd[w->npd] = body;
    w->pd_first[w->npd] = n0;
    w->pd_nbroken_seen[w->npd] = (long long)body->nbroken;
    w->npd++;
    w->pd_npts += body->n;
    floe_world_install_exclusion(w);
    if (first) *first = n0;
    w->prepared = 0;
    return FLOE_OK;
}

floe_pd_split *floe_pd_split_new(const floe_world *w) {
    floe_pd_split *S = calloc(1, sizeof *S);
    if (!S) return NULL;
    S->nbody = w->npd;
    S->loc = calloc((size_t)(w->npd ? w->npd : 1), sizeof *S->loc);
    S->mask = calloc((size_t)(w->npd ? w->npd : 1), sizeof *S->mask);
    S->xb = calloc((size_t)(w->npd ? w->npd : 1), sizeof *S->xb);
    S->snap = calloc((size_t)(w->npd ? w->npd : 1), sizeof *S->snap);
    int bad = !S->loc || !S->mask || !S->xb || !S->snap;
    for (int b = 0; b < w->npd && !bad; b++) {
        const floe_pd_body *pb = w->pd[b];
        const size_t n = (size_t)pb->n, nb = (size_t)(pb->nbond > 0 ? pb->nbond : 1);
        S->loc[b] = malloc(n * sizeof **S->loc);
        S->mask[b] = calloc(n, 1);
        S->xb[b] = calloc(3 * n, sizeof **S->xb);
        S->snap[b] = malloc(nb); /* the flags now: every rank holds the same at the split */
        bad = !S->loc[b] || !S->mask[b] || !S->xb[b] || !S->snap[b];
        if (!bad && pb->nbond > 0) memcpy(S->snap[b], pb->broken, (size_t)pb->nbond);
    }
    if (bad) {
        floe_pd_split_free(S);
        return NULL;
    }
    return S;
}

void floe_pd_split_free(floe_pd_split *S) {
    if (!S) return;
    for (int b = 0; b < S->nbody; b++) {
        if (S->loc) free(S->loc[b]);
        if (S->mask) free(S->mask[b]);
        if (S->xb) free(S->xb[b]);
        if (S->snap) free(S->snap[b]);
    }
    free(S->loc); free(S->mask); free(S->xb); free(S->snap);
    free(S->tx); free(S->rx);
    free(S);
}

void floe_pd_split_gather(floe_world *w) {
    const floe_pd_split *S = w->pd_split;
    for (int b = 0; b < w->npd; b++) {
        const int *loc = S->loc[b];
        double *xb = S->xb[b];
        for (int q = 0; q < w->pd[b]->n; q++)
            if (loc[q] >= 0) memcpy(xb + 3 * (size_t)q, w->p.x + 3 * (size_t)loc[q], 3 * sizeof *xb);
    }
}

int floe_world_pd_point(const floe_world *w, int k, int i) {
    if (k < 0 || k >= w->npd || i < 0 || i >= w->p.n || !w->pd_of || i >= w->pd_npts_alloc || w->pd_of[i] != k) return -1;
    return floe_pd_local(w, k, i);
}
const double *floe_world_pd_positions(const floe_world *w, int k) {
    return k >= 0 && k < w->npd ? floe_pd_positions(w, k) : NULL;
}

int floe_world_pd_body_count(const floe_world *w) { return w->npd; }
struct floe_pd_body *floe_world_pd_body(const floe_world *w, int k, int *first) {
    if (k < 0 || k >= w->npd) return NULL;
    if (first) *first = w->pd_first[k];
    return w->pd[k];
}

/* ---- PD boundary regions (ParticLS eq 37) ---- */

floe_pd_bc floe_default_pd_bc(void) {
    floe_pd_bc bc;
    memset(&bc, 0, sizeof bc);
    return bc;
}

int floe_world_pd_region_count(const floe_world *w) { return w->npd_bc; }
int floe_world_pd_region_points(const floe_world *w, int r) {
    return r >= 0 && r < w->npd_bc ? w->pd_bc[r]->n : -1;
}

/* ramp(t) and its derivative */
static double pd_ramp(const floe_pd_bc *bc, double t, double *deriv) {
    double T = bc->ramp_time;
    if (t < 0) t = 0;
    switch (bc->ramp) {
    case FLOE_PD_RAMP_LINEAR:
        if (deriv) *deriv = t < T ? 1.0 / T : 0.0;
        return t < T ? t / T : 1.0;
    case FLOE_PD_RAMP_EXP:
        if (deriv) *deriv = exp(-t / T) / T;
        return -expm1(-t / T);
    default:
        if (deriv) *deriv = 0.0;
        return 1.0;
    }
}

/* kinematic region points with a time-dependent velocity (floe_world_set_motion) */
static void pd_bc_motion(double t, double v[3], double om[3], void *user) {
    const floe_pd_bc_rec *r = user;
    double dr, s = pd_ramp(&r->def, t, &dr);
    double f = r->def.kind == FLOE_PD_BC_DISPLACEMENT ? dr : s;
    for (int k = 0; k < 3; k++) { v[k] = f * r->def.value[k]; om[k] = 0; }
}

static void pd_bc_free(floe_pd_bc_rec *r) {
    if (!r) return;
    free(r->pts);
    free(r->fold);
    free(r);
}

int floe_world_pd_region(floe_world *w, int body, const floe_pd_bc *bc) {
    if (floe_world_refuse_split(w, "pd_region")) return -FLOE_ENOTSUP;
    if (!bc) return -floe_world_error(w, FLOE_EINVAL, "PD region: NULL definition");
    if (body < 0 || body >= w->npd)
        return -floe_world_error(w, FLOE_EINVAL, "PD region: body %d out of range (%d PD bodies)", body, w->npd);
    const char *bad = NULL;
    int kind = bc->kind;
    if (kind < FLOE_PD_BC_FIXED || kind > FLOE_PD_BC_BODY_FORCE) bad = "kind must be fixed, velocity, displacement or body force";
    else if (bc->ramp < FLOE_PD_RAMP_NONE || bc->ramp > FLOE_PD_RAMP_EXP) bad = "unknown ramp";
    else if (bc->ramp != FLOE_PD_RAMP_NONE && !(bc->ramp_time > 0 && isfinite(bc->ramp_time)))
        bad = "a ramp needs ramp_time > 0";
    else if (kind == FLOE_PD_BC_DISPLACEMENT && bc->ramp == FLOE_PD_RAMP_NONE)
        bad = "a prescribed displacement needs a ramp (linear or exp) over which it is applied";
    else if (!isfinite(bc->value[0]) || !isfinite(bc->value[1]) || !isfinite(bc->value[2])) bad = "value must be finite";
    else if (!bc->sdf)
        for (int k = 0; k < 3 && !bad; k++)
            if (!(bc->lo[k] <= bc->hi[k])) bad = "the box needs lo <= hi on every axis";
    if (bad) return -floe_world_error(w, FLOE_EINVAL, "PD region %d: %s", w->npd_bc, bad);
    const floe_pd_body *pb = w->pd[body];
    const int f0 = w->pd_first[body];
    floe_pd_bc_rec *r = calloc(1, sizeof *r);
    if (!r) return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    r->def = *bc;
    r->def.sdf = NULL; /* read here only: the caller's data need not outlive this call */
    r->def.sdf_user = NULL;
    r->body = body;
    for (int pass = 0; pass < 2; pass++) {
        int n = 0;
        for (int i = 0; i < pb->n; i++) {
            const double *X = pb->X + 3 * (size_t)i;
            int in = bc->sdf ? bc->sdf(X, bc->sdf_user) <= 0
                             : X[0] >= bc->lo[0] && X[0] <= bc->hi[0] && X[1] >= bc->lo[1] && X[1] <= bc->hi[1] &&
                                   (w->def.dim == 2 || (X[2] >= bc->lo[2] && X[2] <= bc->hi[2]));
            if (!in) continue;
            if (pass == 1) r->pts[n] = f0 + i;
            n++;
        }
        if (pass == 0) {
            if (n == 0) {
                pd_bc_free(r);
                return -floe_world_error(w, FLOE_EINVAL, "PD region %d selects no point of PD body %d (%d points)",
                                         w->npd_bc, body, pb->n);
            }
            r->n = n;
            r->pts = malloc((size_t)n * sizeof *r->pts);
            if (!r->pts) { pd_bc_free(r); return -floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
        }
    }
    const int moving = kind != FLOE_PD_BC_BODY_FORCE;
    if (moving) /* one fixed/velocity/displacement region per point */
        for (int q = 0; q < w->npd_bc; q++) {
            const floe_pd_bc_rec *o = w->pd_bc[q];
            if (o->body != body || o->def.kind == FLOE_PD_BC_BODY_FORCE) continue;
            int shared = 0;
            for (int a = 0, c = 0; a < r->n && c < o->n;) { /* both lists ascending */
                if (r->pts[a] == o->pts[c]) { shared++; a++; c++; }
                else if (r->pts[a] < o->pts[c]) a++;
                else c++;
            }
            if (shared) {
                pd_bc_free(r);
                return -floe_world_error(w, FLOE_EINVAL, "PD region %d shares %d points with region %d: a point "
                                         "may be in one fixed, velocity or displacement region only", w->npd_bc, shared, q);
            }
        }
    if (kind == FLOE_PD_BC_BODY_FORCE) {
        r->fold = calloc(3 * (size_t)r->n, sizeof *r->fold);
        if (!r->fold) { pd_bc_free(r); return -floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
    }
    if (grow((void **)&w->pd_bc, &w->pd_bc_cap, w->npd_bc + 1, sizeof *w->pd_bc)) {
        pd_bc_free(r);
        return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    /* the motion of the points: fixed, constant velocity (kinematic without a callback keeps
     * its velocity), or a time-dependent velocity through a motion callback */
    int timed = moving && kind != FLOE_PD_BC_FIXED && bc->ramp != FLOE_PD_RAMP_NONE;
    if (timed && grow((void **)&w->motions, &w->motions_cap, w->nmotions + r->n, sizeof *w->motions)) {
        pd_bc_free(r);
        return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    w->pd_bc[w->npd_bc++] = r;
    if (moving) {
        floe_particles *p = &w->p;
        double v[3], om[3];
        pd_bc_motion(w->time, v, om, r);
        for (int a = 0; a < r->n; a++) {
            int i = r->pts[a];
            p->motion[i] = kind == FLOE_PD_BC_FIXED ? FLOE_FIXED : FLOE_KINEMATIC;
            p->inv_mass[i] = 0;
            floe_v3_set(p->w + 3 * i, 0, 0, 0);
            if (kind == FLOE_PD_BC_FIXED) floe_v3_set(p->v + 3 * i, 0, 0, 0);
            else floe_v3_copy(p->v + 3 * i, v);
            if (w->def.dim == 2) p->v[3 * i + 2] = 0;
            if (timed) w->motions[w->nmotions++] = (floe_motion_cb){i, pd_bc_motion, r, w->nl.gid ? w->nl.gid[i] : i};
        }
        w->prepared = 0;
    }
    return r->n;
}

double floe_pd_bc_forces(floe_world *w) {
    floe_particles *p = &w->p;
    const double t = w->time, dt = w->dt;
    double work = 0;
    for (int q = 0; q < w->npd_bc; q++) {
        floe_pd_bc_rec *r = w->pd_bc[q];
        if (r->def.kind != FLOE_PD_BC_BODY_FORCE) continue;
        const floe_pd_body *pb = w->pd[r->body];
        const int f0 = w->pd_first[r->body];
        double b[3], s = pd_ramp(&r->def, t, NULL);
        for (int k = 0; k < 3; k++) b[k] = s * r->def.value[k];
        /* MPI (a split body): each region point on the rank that owns it; the others' last
         * forces stay as they are, made whole at each decomposition (core/parallel/par_pd.c) */
        const uint8_t *own = w->pd_split ? w->pd_split->mask[r->body] : NULL;
        for (int a = 0; a < r->n; a++) {
            const int q = r->pts[a] - f0, i = floe_pd_particle(w, r->body, q);
            if (own && own[q] != FLOE_PD_OWNED) continue;
            double *old = r->fold + 3 * a;
            if (p->motion[i] != FLOE_FREE) { floe_v3_set(old, 0, 0, 0); continue; }
            double V = pb->V[q], f[3];
            double bi[3] = {b[0], b[1], b[2]}; /* each point's callback gets the ramped value */
            if (r->def.force_fn) r->def.force_fn(t, pb->X + 3 * (size_t)q, bi, r->def.force_user);
            for (int k = 0; k < 3; k++) f[k] = bi[k] * V;
            if (w->def.dim == 2) f[2] = 0;
            floe_v3_add(p->f + 3 * i, p->f + 3 * i, f);
            /* velocities are at mid-step here (dx = v dt): work = (F_old + F_new)/2 . dx */
            for (int k = 0; k < 3; k++) work += 0.5 * dt * (f[k] + old[k]) * p->v[3 * i + k];
            floe_v3_copy(old, f);
        }
    }
    return work;
}
