/* world_beams.c - beam bonds of a world (floe_world_beams.h): which pairs to bond (groups,
 * radius factor, a k-d tree over the candidates), the bond set (contact/bonds/beam_bond.c)
 * holding them, and the world's accessors. The set's forces run in core/world/forces.c. */
#include "world_internal.h"
#include "beam_set.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* index-returning calls give -error */
#define TRY_NEG(expr) do { int rc_ = (expr); if (rc_) return -rc_; } while (0)

static int check_params(floe_world *w, const floe_beam_params *par) {
    char msg[256];
    int rc = floe_beam_check_params(par, msg, sizeof msg);
    return rc ? floe_world_error(w, rc, "%s", msg) : FLOE_OK;
}

static int set_get(floe_world *w, floe_beam_set **out) {
    if (!w->beams) {
        w->beams = floe_beam_set_create();
        if (!w->beams) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    }
    *out = w->beams;
    return FLOE_OK;
}

static int push_bond(floe_world *w, floe_beam_set *s, int i, int j, const floe_beam_params *par,
                     unsigned long long *rng) {
    char msg[256];
    int k = floe_beam_set_push(s, &w->p, w->def.dim, i, j, par, rng, msg, sizeof msg);
    if (k < 0) floe_world_error(w, -k, "%s", msg);
    return k;
}

/* Particles a bond set may bond: those of par->group, or with FLOE_BEAM_ALL_GROUPS every
 * particle except the points of peridynamic bodies (already bonded by their PD bonds;
 * name their group to bond them anyway). */
static int group_ok(const floe_world *w, const floe_beam_params *par, int i) {
    if (par->group == FLOE_BEAM_ALL_GROUPS) return !(w->pd_of && i < w->pd_npts_alloc && w->pd_of[i] >= 0);
    return w->p.group[i] == par->group;
}

/* a world split over MPI ranks (core/parallel) holds each bond on one rank, by global ids:
 * bonds are made before the split */
int floe_world_add_beam_bond(floe_world *w, int i, int j, const floe_beam_params *par) {
    TRY_NEG(floe_world_refuse_split(w, "add_beam_bond"));
    TRY_NEG(check_params(w, par));
    const floe_particles *p = &w->p;
    if (i < 0 || j < 0 || i >= p->n || j >= p->n || i == j)
        return -floe_world_error(w, FLOE_EINVAL, "beam bond: particles %d and %d must be two different indices < %d", i, j, p->n);
    if (!isfinite(p->radius[i]) || !isfinite(p->radius[j]))
        return -floe_world_error(w, FLOE_EINVAL, "beam bond %d-%d: walls cannot be bonded", i, j);
    floe_beam_set *s = NULL;
    TRY_NEG(set_get(w, &s));
    if (floe_beam_set_find(s, i, j) >= 0) return -floe_world_error(w, FLOE_EINVAL, "beam bond %d-%d: already bonded", i, j);
    /* bonds added one at a time continue one random stream per seed, so that their
     * strengths are drawn from the distribution rather than all equal */
    int k = push_bond(w, s, i < j ? i : j, i < j ? j : i, par, floe_beam_set_rng(s, par->seed));
    if (k < 0) return k;
    if (floe_beam_set_index(s, p->n)) return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    floe_world_install_exclusion(w);
    w->prepared = 0;
    return k;
}

typedef struct { int *idx; int n, cap, oom; } visit_buf;
static void visit_push(int index, double d2, void *user) {
    (void)d2;
    visit_buf *v = user;
    if (v->oom) return;
    if (v->n == v->cap) {
        int nc = v->cap ? 2 * v->cap : 64;
        int *t = realloc(v->idx, (size_t)nc * sizeof *t);
        if (!t) { v->oom = 1; return; }
        v->idx = t;
        v->cap = nc;
    }
    v->idx[v->n++] = index;
}
static int cmp_int(const void *a, const void *b) { return (*(const int *)a > *(const int *)b) - (*(const int *)a < *(const int *)b); }

int floe_world_add_beam_bonds(floe_world *w, double radius_factor, const floe_beam_params *par) {
    TRY_NEG(floe_world_refuse_split(w, "add_beam_bonds"));
    TRY_NEG(check_params(w, par));
    if (par->max_distance == 0 && (!(radius_factor > 0) || !isfinite(radius_factor)))
        return -floe_world_error(w, FLOE_EINVAL, "beam bonds: radius_factor must be > 0 (or set max_distance)");
    const floe_particles *p = &w->p;
    floe_beam_set *s = NULL;
    TRY_NEG(set_get(w, &s));
    /* candidates: finite particles of the group */
    int *cand = malloc((size_t)(p->n ? p->n : 1) * sizeof *cand);
    double *pts = malloc((size_t)(p->n ? p->n : 1) * 3 * sizeof *pts);
    if (!cand || !pts) { free(cand); free(pts); return -floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
    int nc = 0;
    double rmax = 0;
    for (int i = 0; i < p->n; i++) {
        if (!isfinite(p->radius[i]) || !group_ok(w, par, i)) continue;
        memcpy(pts + 3 * nc, p->x + 3 * i, 3 * sizeof *pts);
        cand[nc++] = i;
        if (p->radius[i] > rmax) rmax = p->radius[i];
    }
    floe_kdtree *tree = nc ? floe_kdtree_build(pts, nc, w->def.dim, 16) : NULL;
    free(pts);
    if (nc && !tree) { free(cand); return -floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
    if (floe_beam_set_index(s, p->n)) { floe_kdtree_destroy(tree); free(cand); return -floe_world_error(w, FLOE_ENOMEM, "out of memory"); }
    unsigned long long rng = par->seed;
    visit_buf vb = {NULL, 0, 0, 0};
    int added = 0, rc = FLOE_OK;
    const int n_before = floe_beam_set_count(s);
    for (int a = 0; a < nc && !rc; a++) {
        int i = cand[a];
        double reach = par->max_distance > 0 ? par->max_distance : radius_factor * (p->radius[i] + rmax);
        vb.n = 0;
        floe_kdtree_radius_visit(tree, p->x + 3 * i, reach, visit_push, &vb);
        if (vb.oom) { rc = floe_world_error(w, FLOE_ENOMEM, "out of memory"); break; }
        for (int q = 0; q < vb.n; q++) vb.idx[q] = cand[vb.idx[q]];
        qsort(vb.idx, (size_t)vb.n, sizeof *vb.idx, cmp_int); /* bond order independent of the tree */
        for (int q = 0; q < vb.n; q++) {
            int j = vb.idx[q];
            if (j <= i) continue;
            if (p->motion[i] != FLOE_FREE && p->motion[j] != FLOE_FREE) continue;
            double d[3];
            floe_v3_sub(d, p->x + 3 * j, p->x + 3 * i);
            double dist = floe_v3_norm(d);
            double lim = par->max_distance > 0 ? par->max_distance : radius_factor * (p->radius[i] + p->radius[j]);
            if (dist > lim) continue;
            if (floe_beam_set_find(s, i, j) >= 0) continue; /* bonded by an earlier call */
            int k = push_bond(w, s, i, j, par, &rng);
            if (k < 0) { rc = -k; break; }
            added++;
        }
    }
    free(vb.idx);
    free(cand);
    floe_kdtree_destroy(tree);
    if (rc) { floe_beam_set_truncate(s, n_before); floe_beam_set_index(s, p->n); return -rc; }
    if (floe_beam_set_index(s, p->n)) return -floe_world_error(w, FLOE_ENOMEM, "out of memory");
    floe_world_install_exclusion(w);
    w->prepared = 0;
    return added;
}

int floe_world_beam_bond_count(const floe_world *w) { return floe_beam_set_count(w->beams); }
int floe_world_beam_broken_count(const floe_world *w) { return floe_beam_set_broken(w->beams); }

int floe_world_beam_bond(const floe_world *w, int k, floe_beam_bond_info *o) {
    return floe_beam_set_info(w->beams, k, o);
}

int floe_world_write_beam_bonds_csv(floe_world *w, const char *path) {
    int rc = floe_beam_set_write_csv(w->beams, &w->p, path);
    if (rc) return floe_world_error(w, rc, "cannot write %s", path);
    return FLOE_OK;
}

double floe_world_beam_critical_dt(floe_world *w) { return floe_beam_set_critical_dt(w->beams, &w->p, w->def.dim); }
