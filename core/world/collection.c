/* collection.c - the sums behind a collection's homogenised stress (floe_view.h,
 * floe_world_collection_sums): one loop over the particles (members, their bounding box) and
 * one over the recorded contacts, in list order. The collection tracker
 * (observers/collection_tracker.c) turns them into the stress of one world; under MPI each
 * rank computes its share and core/parallel reduces them (docs/parallel.md, "Outputs reduced
 * over the ranks"). */
#include "world_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int is_wall(const floe_world *w, int i) {
    return !isfinite(w->p.radius[i]) || floe_world_particle_kind(w, i) == FLOE_GEOM_PLANE;
}

/* motion: the particle's own (a ghost's on its owner) */
static int is_member(const floe_world *w, int group, int i, int motion) {
    if (is_wall(w, i)) return 0;
    if (group < 0) return motion == FLOE_FREE;
    return w->p.group[i] == group;
}

int floe_world_collection_sums(const floe_world *w, int group, double s[FLOE_COLLECTION_SUMS]) {
    if (!w || !s) return FLOE_EINVAL;
    const floe_contact_info *cs;
    const int nc = floe_world_contacts(w, &cs);
    if (nc < 0) return FLOE_EINVAL;
    const floe_particles *p = &w->p;
    const int n = p->n, split = w->nl.gid != NULL && w->par != NULL;
    const int own_hi = split ? w->nl.own_hi : n; /* ghosts from own_hi on */
    unsigned char *member = malloc(n > 0 ? (size_t)n : 1);
    if (!member) return FLOE_ENOMEM;
    memset(s, 0, FLOE_COLLECTION_SUMS * sizeof *s);
    double *lo = s + 12, *hi = s + 15;
    for (int a = 0; a < 3; a++) { lo[a] = INFINITY; hi[a] = -INFINITY; }
    for (int i = 0; i < n; i++) {
        const int ghost = i >= own_hi;
        const int motion = ghost && w->gmotion ? w->gmotion[i - own_hi] : p->motion[i];
        member[i] = (unsigned char)is_member(w, group, i, motion);
        if (!member[i] || ghost) continue; /* a ghost is counted by its owner */
        s[9] += 1;
        const double r = p->radius[i];
        for (int a = 0; a < 3; a++) {
            const double x = p->x[3 * i + a];
            if (x - r < lo[a]) lo[a] = x - r;
            if (x + r > hi[a]) hi[a] = x + r;
        }
    }
    const int periodic = w->cell != NULL;
    double t[9] = {0};
    for (int c = 0; c < nc; c++) {
        const floe_contact_info *rc = &cs[c];
        const int i = rc->i, j = rc->j;
        if (i < 0 || j < 0 || i >= n || j >= n) continue;
        const int mi = member[i], mj = member[j];
        double l[3], f[3];
        if (mi && mj) {
            if (periodic) floe_v3_copy(l, rc->branch);    /* d_ij = x_j' - x_i to j's image */
            else floe_v3_sub(l, p->x + 3 * j, p->x + 3 * i); /* d_ij = x_j - x_i */
            floe_v3_copy(f, rc->force);                   /* force on i (from j) */
            s[10] += 1;
        } else if (mi) {
            floe_v3_sub(l, rc->point, p->x + 3 * i);
            floe_v3_copy(f, rc->force);
            s[11] += 1;
        } else if (mj) {
            floe_v3_sub(l, rc->point, p->x + 3 * j);
            f[0] = -rc->force[0]; f[1] = -rc->force[1]; f[2] = -rc->force[2];
            s[11] += 1;
        } else {
            continue;
        }
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) t[3 * a + b] += l[a] * f[b];
    }
    memcpy(s, t, sizeof t);
    free(member);
    return FLOE_OK;
}
