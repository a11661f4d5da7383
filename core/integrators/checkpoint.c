/* checkpoint.c - a world's state in a file or in memory, to continue a run bit for bit
 * (floe_checkpoint.h, docs/checkpoints.md). The state is a list of tagged sections, each
 * written and read by one pair of functions below; a new part of the world (the periodic
 * cell, the neighbour list's images) is one more pair and one line in each of the tables
 * `sections` (save, restore). Readers check every length against the world they fill, so
 * that a checkpoint of another scene is refused instead of read out of bounds. */
#include "alloc_util.h"
#include "integrator_parts.h"
#include "error_text.h"
#include "floe_checkpoint.h"
#include "floe_parallel.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAGIC "FLOECKPT"
#define MAGIC_MEM "FLOESTAT"
#define BOM 0x01020304u
#define TAG(a, b, c, d) ((uint32_t)(a) | (uint32_t)(b) << 8 | (uint32_t)(c) << 16 | (uint32_t)(d) << 24)
#define TAG_END TAG('E', 'N', 'D', ' ')

uint64_t floe_checkpoint_hash(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = data;
    for (size_t k = 0; k < n; k++) {
        h ^= p[k];
        h *= 0x100000001b3ULL;
    }
    return h;
}

/* ---- a growing output buffer (count only when cnt is set) ---- */
typedef struct obuf {
    unsigned char *p;
    size_t len, cap;
    int nomem;
} obuf;

static void put(obuf *b, const void *src, size_t n) {
    if (b->nomem || n == 0) return;
    if (b->len + n > b->cap) {
        size_t c = b->cap ? 2 * b->cap : 1 << 16;
        while (c < b->len + n) c *= 2;
        unsigned char *q = realloc(b->p, c);
        if (!q) { b->nomem = 1; return; }
        b->p = q;
        b->cap = c;
    }
    memcpy(b->p + b->len, src, n);
    b->len += n;
}
#define PUT(b, v) put((b), &(v), sizeof(v))
/* n bytes at the end of b for the caller to fill (NULL when out of memory) */
static unsigned char *room(obuf *b, size_t n) {
    static const unsigned char zero[256];
    size_t at = b->len;
    for (size_t k = 0; k < n && !b->nomem; k += sizeof zero) put(b, zero, n - k < sizeof zero ? n - k : sizeof zero);
    return b->nomem ? NULL : b->p + at;
}
static void put_str(obuf *b, const char *s) {
    uint32_t n = s ? (uint32_t)strlen(s) : 0;
    PUT(b, n);
    put(b, s, n);
}
/* a section: its tag and length (patched by sec_end) */
static size_t sec_begin(obuf *b, uint32_t tag) {
    uint64_t len = 0;
    PUT(b, tag);
    size_t at = b->len;
    PUT(b, len);
    return at;
}
static void sec_end(obuf *b, size_t at) {
    if (b->nomem) return;
    uint64_t len = b->len - at - sizeof len;
    memcpy(b->p + at, &len, sizeof len);
}

/* ---- reading: a cursor over one section, every read bounds-checked ---- */
typedef struct ibuf {
    const unsigned char *p;
    size_t len, pos;
    int bad;
} ibuf;

static int get(ibuf *r, void *dst, size_t n) {
    if (r->bad || n > r->len - r->pos) { r->bad = 1; return 0; }
    if (n) memcpy(dst, r->p + r->pos, n);
    r->pos += n;
    return 1;
}
#define GET(r, v) get((r), &(v), sizeof(v))
static void get_str(ibuf *r, char *dst, size_t cap) {
    uint32_t n = 0;
    GET(r, n);
    if (r->bad || n > r->len - r->pos) { r->bad = 1; dst[0] = 0; return; }
    size_t k = n < cap - 1 ? n : cap - 1;
    memcpy(dst, r->p + r->pos, k);
    dst[k] = 0;
    r->pos += n;
}

static const char *tag_name(uint32_t tag, char buf[5]) {
    for (int k = 0; k < 4; k++) buf[k] = (char)(tag >> (8 * k));
    buf[4] = 0;
    return buf;
}

/* ---- the sections ---- */

/* the clock and the integrator's memory */
static void save_clock(const floe_world *w, obuf *b) {
    const double d[9] = {w->time, w->dt, w->t0, w->dt_crit, w->lf_dt_prev, w->dt_next, w->dt_lo, w->dt_hi, w->dt_cap};
    const long l[3] = {w->step, w->step0, w->pd_cycle};
    const int k[2] = {w->pd_sub, w->pd_every};
    PUT(b, d); PUT(b, l); PUT(b, k);
}
static int restore_clock(floe_world *w, ibuf *r, char *err, size_t errlen) {
    double d[9];
    long l[3];
    int k[2];
    GET(r, d); GET(r, l); GET(r, k);
    if (r->bad) return floe_error_set(err, errlen, FLOE_EINVAL, "section CLOK is short");
    if (k[0] != w->pd_sub || k[1] != w->pd_every)
        return floe_error_set(err, errlen, FLOE_EINVAL, "the staggered PD-DEM ratio (substeps %d, every %d) is not this scene's "
                    "(%d, %d)", k[0], k[1], w->pd_sub, w->pd_every);
    w->time = d[0]; w->dt = d[1]; w->t0 = d[2]; w->dt_crit = d[3]; w->lf_dt_prev = d[4];
    w->dt_next = d[5]; w->dt_lo = d[6]; w->dt_hi = d[7]; w->dt_cap = d[8];
    w->step = l[0]; w->step0 = l[1]; w->pd_cycle = l[2];
    return FLOE_OK;
}

/* the energy ledger and the watchdog */
static void save_energy(const floe_world *w, obuf *b) {
    PUT(b, w->energy);
    const double d[10] = {w->elastic_contact, w->elastic_pd, w->eta_depth, w->wd_pair_min, w->wd_worst, w->wd_scale,
                          w->wd_shadow, w->wd_shadow0, w->wd_created, w->wd_gscale};
    const int k[4] = {w->wd_pair_i, w->wd_pair_j, w->wd_worst_i, w->wd_worst_j};
    PUT(b, d); PUT(b, k); PUT(b, w->wd_step);
    put_str(b, w->wd_msg);
}
static int restore_energy(floe_world *w, ibuf *r, char *err, size_t errlen) {
    double d[10];
    int k[4];
    GET(r, w->energy); GET(r, d); GET(r, k); GET(r, w->wd_step);
    get_str(r, w->wd_msg, sizeof w->wd_msg);
    if (r->bad) return floe_error_set(err, errlen, FLOE_EINVAL, "section ENRG is short");
    w->elastic_contact = d[0]; w->elastic_pd = d[1]; w->eta_depth = d[2]; w->wd_pair_min = d[3]; w->wd_worst = d[4];
    w->wd_scale = d[5]; w->wd_shadow = d[6]; w->wd_shadow0 = d[7]; w->wd_created = d[8]; w->wd_gscale = d[9];
    w->wd_pair_i = k[0]; w->wd_pair_j = k[1]; w->wd_worst_i = k[2]; w->wd_worst_j = k[3];
    return FLOE_OK;
}

/* step and detection statistics */
static void save_stats(const floe_world *w, obuf *b) {
    const floe_detect_state *d = &w->det;
    PUT(b, w->st);
    const long l[7] = {d->calls, d->iterations, d->admm_calls, d->lp_calls, d->separated, d->nonconverged,
                       d->first_bad_step};
    const int k[4] = {d->cur_i, d->cur_j, d->first_bad_i, d->first_bad_j};
    PUT(b, l); PUT(b, d->hist); PUT(b, k);
}
static int restore_stats(floe_world *w, ibuf *r, char *err, size_t errlen) {
    floe_detect_state *d = &w->det;
    long l[7];
    int k[4];
    GET(r, w->st); GET(r, l); GET(r, d->hist); GET(r, k);
    if (r->bad) return floe_error_set(err, errlen, FLOE_EINVAL, "section STAT is short");
    d->calls = l[0]; d->iterations = l[1]; d->admm_calls = l[2]; d->lp_calls = l[3]; d->separated = l[4];
    d->nonconverged = l[5]; d->first_bad_step = l[6];
    d->cur_i = k[0]; d->cur_j = k[1]; d->first_bad_i = k[2]; d->first_bad_j = k[3];
    return FLOE_OK;
}

/* the particle arrays a run changes (state objects may change mass, inertia and radius) */
#define PART_ARRAYS(X)                                                                                  \
    X(x, 3) X(v, 3) X(q, 4) X(w, 3) X(L, 3) X(f, 3) X(t, 3) X(mass, 1) X(inv_mass, 1) X(inertia, 3)     \
    X(radius, 1) X(rdot, 1) X(inv_iso, 1)
static void save_particles(const floe_world *w, obuf *b) {
    const floe_particles *p = &w->p;
    const size_t n = (size_t)p->n;
    PUT(b, p->n);
#define X(a, c) put(b, p->a, (c) * n * sizeof(double));
    PART_ARRAYS(X)
#undef X
}
static int restore_particles(floe_world *w, ibuf *r, char *err, size_t errlen) {
    floe_particles *p = &w->p;
    int n = -1;
    GET(r, n);
    if (n != p->n)
        return floe_error_set(err, errlen, FLOE_EINVAL, "the checkpoint holds %d particles, this world %d: another scene", n, p->n);
#define X(a, c) get(r, p->a, (c) * (size_t)n * sizeof(double));
    PART_ARRAYS(X)
#undef X
    return r->bad ? floe_error_set(err, errlen, FLOE_EINVAL, "section PART is short") : FLOE_OK;
}

/* state objects (floe_state.h): their values through get/set */
static void save_states(const floe_world *w, obuf *b) {
    PUT(b, w->nstates);
    for (int k = 0; k < w->nstates; k++) {
        const floe_state *s = w->states[k];
        uint64_t m = s->klass->size(s);
        double buf[64];
        double *y = m <= 64 ? buf : malloc(m * sizeof *y);
        if (!y) { b->nomem = 1; return; }
        s->klass->get(s, y);
        PUT(b, m);
        put(b, y, m * sizeof *y);
        if (y != buf) free(y);
    }
}
static int restore_states(floe_world *w, ibuf *r, char *err, size_t errlen) {
    int ns = -1;
    GET(r, ns);
    if (ns != w->nstates)
        return floe_error_set(err, errlen, FLOE_EINVAL, "the checkpoint holds %d state objects, this world %d", ns, w->nstates);
    for (int k = 0; k < ns; k++) {
        floe_state *s = w->states[k];
        uint64_t m = 0;
        GET(r, m);
        if (r->bad || m != s->klass->size(s) || m * sizeof(double) > r->len - r->pos)
            return floe_error_set(err, errlen, FLOE_EINVAL, "state object %d (%s): size does not match", k, s->klass->name);
        double *y = malloc((m ? m : 1) * sizeof *y);
        if (!y) return floe_error_set(err, errlen, FLOE_ENOMEM, "out of memory");
        get(r, y, m * sizeof *y);
        w->err[0] = 0;
        int rc = s->klass->set(s, w, y);
        free(y);
        if (rc) return floe_error_set(err, errlen, rc, "state object %s could not be restored: %s", s->klass->name, w->err);
    }
    return FLOE_OK;
}

/* the neighbour list, exactly: its pairs in their order with their history, touching flags
 * and warm starts, and what its next rebuild is decided from */
static void save_neighbors(const floe_world *w, obuf *b) {
    const floe_neighbor_list *nl = &w->nl;
    const size_t np = (size_t)nl->npairs;
    const int warm = nl->use_warm && nl->warm != NULL;
    const int k[5] = {nl->npairs, warm, nl->n_build, nl->nwalls, nl->hs};
    PUT(b, k); PUT(b, nl->skin); PUT(b, nl->rebuilds);
    put(b, nl->pi, np * sizeof(int));
    put(b, nl->pj, np * sizeof(int));
    put(b, nl->sub, np * sizeof(int));
    put(b, nl->hist, np * (size_t)nl->hs * sizeof(double));
    put(b, nl->touching, np);
    if (warm) put(b, nl->warm, np * FLOE_DETECT_WARM * sizeof(double));
    put(b, nl->x_build, 3 * (size_t)nl->n_build * sizeof(double));
    put(b, nl->r_build, (size_t)nl->n_build * sizeof(double));
    put(b, nl->walls, (size_t)nl->nwalls * sizeof(int));
    put(b, nl->q_walls, 4 * (size_t)nl->nwalls * sizeof(double));
}
/* realloc to at least n bytes (n = 0: one) */
/* n bytes (alloc_util.h) */
static int resize(void **ptr, size_t n) { return floe_resize(ptr, n, 1); }
static int restore_neighbors(floe_world *w, ibuf *r, char *err, size_t errlen) {
    floe_neighbor_list *nl = &w->nl;
    w->sep_n = -1; /* the list's entries are replaced: the separation cache starts again */
    int k[5];
    GET(r, k); GET(r, nl->skin); GET(r, nl->rebuilds);
    const int np = k[0], warm = k[1], nb = k[2], nwl = k[3], hs = k[4];
    if (!r->bad && hs != FLOE_HIST_COMPACT && hs != FLOE_MAX_HISTORY)
        return floe_error_set(err, errlen, FLOE_EINVAL, "section NLST: %d doubles of history per entry (%d or %d here)", hs,
                              FLOE_HIST_COMPACT, FLOE_MAX_HISTORY);
    if (r->bad || np < 0 || nb != w->p.n || nwl < 0 || nwl > w->p.n)
        return floe_error_set(err, errlen, FLOE_EINVAL, "section NLST does not match this world (%d particles at the build, %d "
                    "here)", nb, w->p.n);
    if (warm && !nl->use_warm)
        return floe_error_set(err, errlen, FLOE_EINVAL, "section NLST has warm starts that this scene does not use");
    const size_t n = (size_t)np;
    int rc = resize((void **)&nl->pi, n * sizeof(int));
    if (!rc) rc = resize((void **)&nl->pj, n * sizeof(int));
    if (!rc) rc = resize((void **)&nl->sub, n * sizeof(int));
    if (!rc) rc = resize((void **)&nl->hist, n * (size_t)hs * sizeof(double));
    if (!rc) rc = resize((void **)&nl->touching, n);
    if (!rc && nl->use_warm) rc = resize((void **)&nl->warm, n * FLOE_DETECT_WARM * sizeof(double));
    if (!rc) rc = resize((void **)&nl->x_build, 3 * (size_t)nb * sizeof(double));
    if (!rc) rc = resize((void **)&nl->r_build, (size_t)nb * sizeof(double));
    if (!rc) rc = resize((void **)&nl->walls, (size_t)nwl * sizeof(int));
    if (!rc) rc = resize((void **)&nl->q_walls, 4 * (size_t)nwl * sizeof(double));
    if (rc) return floe_error_set(err, errlen, FLOE_ENOMEM, "out of memory");
    nl->npairs = nl->cap = np;
    nl->hs = hs; /* (restrided at the end of this function if this world needs another) */
    nl->gen++; /* a new list: the threads' per-particle index is rebuilt (forces.c) */
    nl->n_build = nb;
    nl->nwalls = nwl;
    get(r, nl->pi, n * sizeof(int));
    get(r, nl->pj, n * sizeof(int));
    get(r, nl->sub, n * sizeof(int));
    get(r, nl->hist, n * (size_t)hs * sizeof(double));
    get(r, nl->touching, n);
    if (warm) get(r, nl->warm, n * FLOE_DETECT_WARM * sizeof(double));
    else if (nl->use_warm)
        for (size_t a = 0; a < n * FLOE_DETECT_WARM; a++) nl->warm[a] = NAN;
    get(r, nl->x_build, 3 * (size_t)nb * sizeof(double));
    get(r, nl->r_build, (size_t)nb * sizeof(double));
    get(r, nl->walls, (size_t)nwl * sizeof(int));
    get(r, nl->q_walls, 4 * (size_t)nwl * sizeof(double));
    if (r->bad) {
        nl->npairs = nl->n_build = 0; /* consistent: the next step rebuilds */
        return floe_error_set(err, errlen, FLOE_EINVAL, "section NLST is short");
    }
    for (int a = 0; a < np; a++) {
        if (nl->pi[a] < 0 || nl->pi[a] >= w->p.n || nl->pj[a] < 0 || nl->pj[a] >= w->p.n) {
            nl->npairs = nl->n_build = 0;
            return floe_error_set(err, errlen, FLOE_EINVAL, "section NLST: pair %d (%d, %d) out of range", a, nl->pi[a], nl->pj[a]);
        }
        /* a bounded particle and a wall: the bounded one is i (neighbor.c push_pair) */
        if (!isfinite(w->p.radius[nl->pi[a]]) && isfinite(w->p.radius[nl->pj[a]])) {
            nl->npairs = nl->n_build = 0;
            return floe_error_set(err, errlen, FLOE_EINVAL, "section NLST: pair %d (%d, %d) has the wall first "
                                  "(a damaged file: format 6 lists the bounded particle first)", a, nl->pi[a], nl->pj[a]);
        }
    }
    w->err[0] = 0;
    if (floe_world_hist_layout(w)) /* this world's stride (the same for the scene that wrote it) */
        return floe_error_set(err, errlen, FLOE_ENOMEM, "%s", w->err);
    return FLOE_OK;
}

/* the force providers' state (floe_provider.h), each by name and size */
static void save_providers(const floe_world *w, obuf *b) {
    PUT(b, w->nprov);
    for (int k = 0; k < w->nprov; k++) {
        const floe_provider *pv = w->prov[k];
        uint64_t m = pv->klass->state_size ? pv->klass->state_size(pv, w) : 0;
        put_str(b, pv->klass->name);
        PUT(b, m);
        unsigned char *dst = m ? room(b, m) : NULL;
        if (dst) pv->klass->save(pv, w, dst);
    }
}
static int restore_providers(floe_world *w, ibuf *r, char *err, size_t errlen) {
    int np = -1;
    GET(r, np);
    if (np != w->nprov)
        return floe_error_set(err, errlen, FLOE_EINVAL, "the checkpoint holds %d force providers, this world %d: another scene",
                    np, w->nprov);
    for (int k = 0; k < np; k++) {
        floe_provider *pv = w->prov[k];
        char name[128];
        uint64_t m = 0;
        get_str(r, name, sizeof name);
        GET(r, m);
        uint64_t want = pv->klass->state_size ? pv->klass->state_size(pv, w) : 0;
        if (r->bad || strcmp(name, pv->klass->name) || m != want || m > r->len - r->pos)
            return floe_error_set(err, errlen, FLOE_EINVAL, "force provider %d: the checkpoint's is %s with %llu bytes of state, "
                        "this world's %s with %llu: another scene", k, name, (unsigned long long)m, pv->klass->name,
                        (unsigned long long)want);
        if (m) pv->klass->restore(pv, w, r->p + r->pos);
        r->pos += m;
    }
    return FLOE_OK;
}

/* beam bonds (their provider has no save hooks yet: contact/bonds/beam_set.h) */
static void save_beams(const floe_world *w, obuf *b) {
    uint64_t m = floe_beam_set_state_size(w->beams);
    PUT(b, m);
    unsigned char *dst = m ? room(b, m) : NULL;
    if (dst) floe_beam_set_state_save(w->beams, dst);
}
static int restore_beams(floe_world *w, ibuf *r, char *err, size_t errlen) {
    uint64_t m = 0;
    GET(r, m);
    if (r->bad || m > r->len - r->pos || floe_beam_set_state_restore(w->beams, r->p + r->pos, m) != FLOE_OK)
        return floe_error_set(err, errlen, FLOE_EINVAL, "section BEAM does not match this world's %d beam bonds: another scene",
                    floe_beam_set_count(w->beams));
    r->pos += m;
    return FLOE_OK;
}

/* the staggered PD-DEM scheme's forces kept between steps and the start of its PD cycle
 * (core/integrators/step.c: the rows w->stag): written as the 5 blocks of 3n doubles of
 * format 4 (F_C, its torques, F_PD, the cycle's start positions, the true velocities) */
static int staggered(const floe_world *w) { return w->def.pd_dem == FLOE_PD_DEM_STAGGERED && w->npd > 0; }
static const int stag_part[5] = {STAG_FS, STAG_TS, STAG_FPD, STAG_XS, STAG_VT};
static void save_stag(const floe_world *w, obuf *b) {
    const int n = w->p.n, have = w->stag && w->stag_n >= n;
    uint64_t m = have ? 15 * (size_t)n : 0;
    PUT(b, m);
    for (int k = 0; have && k < 5; k++)
        for (int i = 0; i < n; i++) put(b, w->stag + (size_t)i * STAG_W + stag_part[k], 3 * sizeof(double));
}
static int restore_stag(floe_world *w, ibuf *r, char *err, size_t errlen) {
    uint64_t m = 0;
    GET(r, m);
    const int n = w->p.n;
    if (r->bad || m != 15 * (uint64_t)n || m * sizeof(double) > r->len - r->pos)
        return floe_error_set(err, errlen, FLOE_EINVAL, "section STAG does not match this world");
    if (!stag_rows(w)) return floe_error_set(err, errlen, FLOE_ENOMEM, "section STAG: out of memory");
    for (int k = 0; k < 5; k++)
        for (int i = 0; i < n; i++) get(r, w->stag + (size_t)i * STAG_W + stag_part[k], 3 * sizeof(double));
    return FLOE_OK;
}

/* ---- the state: sections in order (the observers' are the file's, below) ----
 * To add a part of the world: a save and a restore function and one line here (a new tag;
 * `want` says when the world has that part: the section is then required in a checkpoint
 * and refused in one of a world without it; an `optional` part is written when wanted and
 * read when present, a cache the world can rebuild). */
typedef struct section {
    uint32_t tag;
    int (*want)(const floe_world *w);
    void (*save)(const floe_world *w, obuf *b);
    int (*restore)(floe_world *w, ibuf *r, char *err, size_t errlen);
    int optional;
} section;

/* the periodic cell (floe_cell.h): its whole state, and the list's images and its cell at
 * the build (the list's other arrays are NLST's) */
static int has_cell(const floe_world *w) { return w->cell != NULL; }
static void save_cell(const floe_world *w, obuf *b) {
    put(b, w->cell, sizeof *w->cell);
    const int np = w->nl.npairs, has = w->nl.img != NULL;
    PUT(b, np); PUT(b, has);
    if (has) put(b, w->nl.img, (size_t)np * sizeof(int));
    put(b, w->nl.Hb, sizeof w->nl.Hb);
    PUT(b, w->nl.rmax_b);
}
static int restore_cell(floe_world *w, ibuf *r, char *err, size_t errlen) {
    get(r, w->cell, sizeof *w->cell);
    int np = -1, has = 0;
    GET(r, np); GET(r, has);
    if (r->bad || np != w->nl.npairs)
        return floe_error_set(err, errlen, FLOE_EINVAL, "section CELL does not match this world's neighbour list");
    if (has) {
        void *q = realloc(w->nl.img, (size_t)(np > w->nl.cap ? np : w->nl.cap ? w->nl.cap : 1) * sizeof(int));
        if (!q) return floe_error_set(err, errlen, FLOE_ENOMEM, "out of memory");
        w->nl.img = q;
        get(r, w->nl.img, (size_t)np * sizeof(int));
    }
    get(r, w->nl.Hb, sizeof w->nl.Hb);
    GET(r, w->nl.rmax_b);
    w->nl.cell = w->cell;
    if (r->bad) return floe_error_set(err, errlen, FLOE_EINVAL, "section CELL is short");
    return FLOE_OK;
}

/* the separation cache (forces.c sep_update), when the world keeps one: each particle's
 * motion bound and pose, each list entry's gap, so that a restored run skips the same pairs
 * as the run that saved it (the same bits). Optional: without it the cache starts again
 * empty, which changes no answer, only which apart pairs are tested again */
static void save_sep(const floe_world *w, obuf *b) {
    const int k[2] = {w->sep_n, w->sep_np};
    PUT(b, k);
    put(b, w->sep_d, (size_t)w->sep_n * sizeof(double));
    put(b, w->sep_pose, 8 * (size_t)w->sep_n * sizeof(double));
    put(b, w->sep_geom, (size_t)w->sep_n * sizeof(int));
    put(b, w->sep_pair, 2 * (size_t)w->sep_np * sizeof(double));
}
static int restore_sep(floe_world *w, ibuf *r, char *err, size_t errlen) {
    int k[2] = {-1, -1};
    GET(r, k);
    if (r->bad || k[0] != w->p.n || k[1] != w->nl.npairs)
        return floe_error_set(err, errlen, FLOE_EINVAL, "section SEPC does not match this world (%d particles, %d list "
                              "entries; here %d, %d)", k[0], k[1], w->p.n, w->nl.npairs);
    const size_t n = (size_t)k[0], np = (size_t)k[1];
    int rc = resize((void **)&w->sep_d, n * sizeof(double));
    if (!rc) rc = resize((void **)&w->sep_pose, 8 * n * sizeof(double));
    if (!rc) rc = resize((void **)&w->sep_geom, n * sizeof(int));
    if (!rc) rc = resize((void **)&w->sep_pair, 2 * np * sizeof(double));
    if (rc) return floe_error_set(err, errlen, FLOE_ENOMEM, "out of memory");
    get(r, w->sep_d, n * sizeof(double));
    get(r, w->sep_pose, 8 * n * sizeof(double));
    get(r, w->sep_geom, n * sizeof(int));
    get(r, w->sep_pair, 2 * np * sizeof(double));
    if (r->bad) return floe_error_set(err, errlen, FLOE_EINVAL, "section SEPC is short");
    /* the restored list's entries (NLST, restored before): the cache goes on from here */
    w->sep_n = k[0];
    w->sep_np = k[1];
    w->sep_gen = w->nl.gen;
    w->sep_on = 1;
    return FLOE_OK;
}
static int has_sep(const floe_world *w) {
    return w->sep_on && floe_world_sep_current(w);
}

static int always(const floe_world *w) { (void)w; return 1; }
static int has_beams(const floe_world *w) { return w->beams != NULL; }

/* restore order: state objects first (set() may rescale mass and momentum, put back after) */
static const section sections[] = {
    {TAG('S', 'O', 'B', 'J'), always, save_states, restore_states, 0},
    {TAG('P', 'A', 'R', 'T'), always, save_particles, restore_particles, 0},
    {TAG('N', 'L', 'S', 'T'), always, save_neighbors, restore_neighbors, 0},
    {TAG('C', 'E', 'L', 'L'), has_cell, save_cell, restore_cell, 0},
    {TAG('P', 'R', 'O', 'V'), always, save_providers, restore_providers, 0},
    {TAG('B', 'E', 'A', 'M'), has_beams, save_beams, restore_beams, 0},
    {TAG('S', 'T', 'A', 'G'), staggered, save_stag, restore_stag, 0},
    {TAG('C', 'L', 'O', 'K'), always, save_clock, restore_clock, 0},
    {TAG('E', 'N', 'R', 'G'), always, save_energy, restore_energy, 0},
    {TAG('S', 'T', 'A', 'T'), always, save_stats, restore_stats, 0},
    {TAG('S', 'E', 'P', 'C'), has_sep, save_sep, restore_sep, 1}, /* after NLST: its entries */
};
#define NSECTIONS (sizeof sections / sizeof *sections)
#define TAG_OBSV TAG('O', 'B', 'S', 'V')

static void save_sections(const floe_world *w, obuf *b) {
    for (size_t k = 0; k < NSECTIONS; k++) {
        if (!sections[k].want(w)) continue;
        size_t at = sec_begin(b, sections[k].tag);
        sections[k].save(w, b);
        sec_end(b, at);
    }
}

/* the sections of a checkpoint: tag, start, length */
typedef struct sec_index {
    uint32_t tag[64];
    size_t at[64], len[64];
    int n;
} sec_index;

static int index_sections(const unsigned char *p, size_t len, size_t pos, sec_index *ix, char *err, size_t errlen) {
    ix->n = 0;
    while (pos < len) {
        uint32_t tag;
        uint64_t n;
        if (len - pos < sizeof tag + sizeof n)
            return floe_error_set(err, errlen, FLOE_EINVAL, "truncated (a section header cut at byte %zu)", pos);
        memcpy(&tag, p + pos, sizeof tag);
        memcpy(&n, p + pos + sizeof tag, sizeof n);
        pos += sizeof tag + sizeof n;
        if (n > len - pos) {
            char nm[5];
            return floe_error_set(err, errlen, FLOE_EINVAL, "truncated (section %s of %llu bytes, %zu left)", tag_name(tag, nm),
                        (unsigned long long)n, len - pos);
        }
        if (tag == TAG_END) return FLOE_OK;
        if (ix->n == 64) return floe_error_set(err, errlen, FLOE_EINVAL, "too many sections");
        ix->tag[ix->n] = tag;
        ix->at[ix->n] = pos;
        ix->len[ix->n] = (size_t)n;
        ix->n++;
        pos += n;
    }
    return FLOE_OK;
}

static int find_section(const sec_index *ix, uint32_t tag) {
    for (int k = 0; k < ix->n; k++)
        if (ix->tag[k] == tag) return k;
    return -1;
}

/* prepares w (if needed) without its observers' start, then every section back */
static int restore_sections(floe_world *w, const unsigned char *p, const sec_index *ix, char *err, size_t errlen) {
    for (size_t k = 0; k < NSECTIONS; k++) {
        const int want = sections[k].want(w), at = find_section(ix, sections[k].tag);
        char nm[5];
        if (!sections[k].optional && want != (at >= 0))
            return floe_error_set(err, errlen, FLOE_EINVAL, "section %s is %s the checkpoint but this world %s it: another scene",
                        tag_name(sections[k].tag, nm), at >= 0 ? "in" : "missing from", at >= 0 ? "does not need" : "needs");
        if (at < 0) continue;
        ibuf r = {p + ix->at[at], ix->len[at], 0, 0};
        FLOE_TRY(sections[k].restore(w, &r, err, errlen));
    }
    /* the contact records are those of the prepare's evaluation: none until the next step */
    w->ncontacts = 0;
    w->contacts_valid = 0;
    return FLOE_OK;
}

static int prepare_quietly(floe_world *w, char *err, size_t errlen) {
    if (w->prepared) return FLOE_OK;
    const int nobs = w->nobs;
    w->nobs = 0; /* no begin, no first observation: the restored observers go on instead */
    int rc = floe_world_prepare(w);
    w->nobs = nobs;
    if (rc) return floe_error_set(err, errlen, rc, "preparing the world failed: %s", w->err);
    orientation_refresh(w); /* the prepare did not see the observers: those that read orientations */
    return FLOE_OK;
}

/* ---- in memory ---- */

static int save_mem(const floe_world *w, obuf *b) {
    put(b, MAGIC_MEM, 8);
    uint32_t fmt = FLOE_CHECKPOINT_FORMAT;
    PUT(b, fmt);
    save_sections(w, b);
    size_t at = sec_begin(b, TAG_END);
    sec_end(b, at);
    return b->nomem ? FLOE_ENOMEM : FLOE_OK;
}

size_t floe_world_state_size(const floe_world *w) {
    if (!w || !w->prepared) return 0;
    obuf b = {0};
    size_t n = save_mem(w, &b) ? 0 : b.len;
    free(b.p);
    return n;
}

int floe_world_state_save(const floe_world *w, void *buf, size_t len, char *err, size_t errlen) {
    if (!w || !w->prepared) return floe_error_set(err, errlen, FLOE_EINVAL, "state save: the world has not been prepared");
    obuf b = {0};
    int rc = save_mem(w, &b);
    if (!rc && b.len > len) rc = floe_error_set(err, errlen, FLOE_EINVAL, "state save: %zu bytes needed, %zu given", b.len, len);
    else if (rc) floe_error_set(err, errlen, rc, "state save: out of memory");
    else memcpy(buf, b.p, b.len);
    free(b.p);
    return rc;
}

int floe_world_state_restore(floe_world *w, const void *buf, size_t len, char *err, size_t errlen) {
    const unsigned char *p = buf;
    uint32_t fmt = 0;
    if (!w || !buf || len < 12 || memcmp(p, MAGIC_MEM, 8))
        return floe_error_set(err, errlen, FLOE_EINVAL, "state restore: not a floe state buffer");
    memcpy(&fmt, p + 8, sizeof fmt);
    if (fmt != FLOE_CHECKPOINT_FORMAT)
        return floe_error_set(err, errlen, FLOE_EINVAL, "state restore: format %u, this is floe %s format %d", fmt,
                    FLOE_VERSION_STRING, FLOE_CHECKPOINT_FORMAT);
    sec_index ix;
    char why[512];
    int rc = index_sections(p, len, 12, &ix, why, sizeof why);
    if (!rc) rc = prepare_quietly(w, why, sizeof why);
    if (!rc) rc = restore_sections(w, p, &ix, why, sizeof why);
    if (rc) return floe_error_set(err, errlen, rc, "state restore: %s", why);
    return FLOE_OK;
}

/* ---- the observers (files only) ---- */

static int has_hooks(const floe_observer *o) {
    return o->klass->version >= 2 && o->klass->state_size && o->klass->save && o->klass->restore;
}

/* the observers of w, then (extra: a split world's own outputs under MPI, the vtk pieces of
 * rank 0, floe_world_parallel_add_output) nextra more, marked begun = 2: a world's restore
 * skips them, floe_world_checkpoint_restore_split_outputs reads them */
static void save_observers(const floe_world *w, floe_observer *const *extra, int nextra, obuf *b) {
    const int n = w->nobs + nextra;
    PUT(b, n);
    for (int k = 0; k < n; k++) {
        const floe_observer *o = k < w->nobs ? w->obs[k] : extra[k - w->nobs];
        const int hooks = has_hooks(o);
        uint64_t m = hooks ? o->klass->state_size(o) : 0;
        const int flags[3] = {k < w->nobs ? o->begun : 2, o->ended, hooks};
        put_str(b, o->klass->name);
        PUT(b, o->period_steps); PUT(b, o->period_time); PUT(b, o->next_time); PUT(b, flags); PUT(b, m);
        unsigned char *dst = m ? room(b, m) : NULL;
        if (dst) o->klass->save(o, dst);
    }
}

/* one entry of the observers' section: its header into the arguments, r after it (its state
 * of *m bytes at r->p + r->pos, not consumed) */
static void get_observer(ibuf *r, char *name, size_t cap, double *nt, int flags[3], uint64_t *m) {
    long ps;
    double pt;
    get_str(r, name, cap);
    GET(r, ps); GET(r, pt); GET(r, *nt); GET(r, flags[0]); GET(r, flags[1]); GET(r, flags[2]); GET(r, *m);
    if (*m > r->len - r->pos) r->bad = 1;
}

/* the number of entries of the section r that are a split world's own outputs (-1: malformed) */
static int count_split(ibuf r, int n) {
    int split = 0;
    for (int k = 0; k < n; k++) {
        char name[128];
        double nt;
        int flags[3] = {0, 0, 0};
        uint64_t m = 0;
        get_observer(&r, name, sizeof name, &nt, flags, &m);
        if (r.bad) return -1;
        r.pos += m;
        split += flags[0] == 2;
    }
    return split;
}

/* before anything is changed: every observer of w can be continued */
static int check_observers(const floe_world *w, char *err, size_t errlen) {
    for (int k = 0; k < w->nobs; k++)
        if (!has_hooks(w->obs[k]))
            return floe_error_set(err, errlen, FLOE_ENOTSUP, "output %d (%s) cannot be continued from a checkpoint (its observer "
                        "class has no checkpoint hooks, docs/checkpoints.md); remove it from the scene to restart", k,
                        w->obs[k]->klass->name);
    return FLOE_OK;
}

static int restore_observers(floe_world *w, ibuf *r, char *err, size_t errlen) {
    int n = -1;
    GET(r, n);
    const int split = r->bad || n < 0 ? -1 : count_split(*r, n);
    if (split < 0) return floe_error_set(err, errlen, FLOE_EINVAL, "the observers' section is malformed");
    if (n - split != w->nobs) {
        if (split > 0)
            return floe_error_set(err, errlen, FLOE_EINVAL, "the checkpoint was written under MPI with %d output(s) written "
                        "in pieces per rank (the vtk output: a .pvtu series), which a run in one process cannot continue "
                        "(it writes a .vtu series): restart it under mpirun with more than one rank", split);
        return floe_error_set(err, errlen, FLOE_EINVAL, "the checkpoint holds %d outputs, this world %d: another scene", n, w->nobs);
    }
    for (int k = 0, i = 0; k < n; k++) {
        char name[128];
        double nt;
        int flags[3];
        uint64_t m = 0;
        get_observer(r, name, sizeof name, &nt, flags, &m);
        if (r->bad) return floe_error_set(err, errlen, FLOE_EINVAL, "the observers' section is malformed");
        if (flags[0] == 2) { /* a split world's own output: not this world's */
            r->pos += m;
            continue;
        }
        floe_observer *o = w->obs[i++];
        if (strcmp(name, o->klass->name))
            return floe_error_set(err, errlen, FLOE_EINVAL, "output %d: the checkpoint's is %s, this world's %s: another scene",
                        i - 1, name, o->klass->name);
        if (!flags[2])
            return floe_error_set(err, errlen, FLOE_ENOTSUP, "output %d (%s) had no checkpoint hooks when the checkpoint was "
                        "written: it cannot be continued", i - 1, name);
        w->err[0] = 0;
        int rc = o->klass->begin && !o->begun ? o->klass->begin(o, w) : FLOE_OK;
        if (!rc) rc = o->klass->restore(o, w, r->p + r->pos, (size_t)m);
        if (rc) return floe_error_set(err, errlen, rc, "output %d (%s) could not be continued: %s", i - 1, name, w->err);
        r->pos += m;
        o->next_time = nt;
        o->begun = 1;
        o->ended = 0;
    }
    return FLOE_OK;
}

/* ---- the file ---- */

static int save_file(const floe_world *w, floe_observer *const *extra, int nextra, const char *path,
                     uint64_t scene_hash, const char *scene_name, char *err, size_t errlen) {
    if (!w || !path || !*path) return floe_error_set(err, errlen, FLOE_EINVAL, "checkpoint: no world or no path");
    if (!w->prepared) return floe_error_set(err, errlen, FLOE_EINVAL, "checkpoint: the world has not started (not prepared)");
    obuf b = {0};
    put(&b, MAGIC, 8);
    const uint32_t head[2] = {FLOE_CHECKPOINT_FORMAT, BOM};
    PUT(&b, head);
    put_str(&b, FLOE_VERSION_STRING);
    PUT(&b, scene_hash);
    put_str(&b, scene_name ? scene_name : "");
    save_sections(w, &b);
    size_t at = sec_begin(&b, TAG_OBSV);
    save_observers(w, extra, nextra, &b);
    sec_end(&b, at);
    at = sec_begin(&b, TAG_END);
    uint64_t h = 0;
    PUT(&b, h);
    sec_end(&b, at);
    if (b.nomem) {
        free(b.p);
        return floe_error_set(err, errlen, FLOE_ENOMEM, "checkpoint: out of memory");
    }
    /* the hash covers everything before it, its own section header included */
    h = floe_checkpoint_hash(FLOE_CHECKPOINT_HASH0, b.p, b.len - sizeof h);
    memcpy(b.p + b.len - sizeof h, &h, sizeof h);
    size_t tl = strlen(path) + 5;
    char *tmp = malloc(tl);
    if (!tmp) {
        free(b.p);
        return floe_error_set(err, errlen, FLOE_ENOMEM, "checkpoint: out of memory");
    }
    snprintf(tmp, tl, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    int bad = !f || fwrite(b.p, 1, b.len, f) != b.len;
    int e = errno;
    if (f && fclose(f) != 0 && !bad) { bad = 1; e = errno; }
    if (!bad && rename(tmp, path) != 0) { bad = 1; e = errno; }
    if (bad) remove(tmp);
    free(tmp);
    free(b.p);
    if (bad) return floe_error_set(err, errlen, FLOE_EIO, "checkpoint: cannot write %s: %s", path, strerror(e));
    return FLOE_OK;
}

int floe_world_checkpoint_save(const floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name,
                               char *err, size_t errlen) {
    return save_file(w, NULL, 0, path, scene_hash, scene_name, err, errlen);
}

static int read_file(const char *path, unsigned char **out, size_t *len, char *err, size_t errlen) {
    FILE *f = fopen(path, "rb");
    if (!f) return floe_error_set(err, errlen, FLOE_EIO, "cannot open %s: %s", path, strerror(errno));
    size_t cap = 1 << 16, n = 0;
    unsigned char *p = malloc(cap);
    while (p) {
        n += fread(p + n, 1, cap - n, f);
        if (n < cap) break;
        unsigned char *q = realloc(p, 2 * cap);
        if (!q) { free(p); p = NULL; break; }
        p = q;
        cap *= 2;
    }
    int bad = ferror(f);
    fclose(f);
    if (!p) return floe_error_set(err, errlen, FLOE_ENOMEM, "out of memory reading %s", path);
    if (bad) {
        free(p);
        return floe_error_set(err, errlen, FLOE_EIO, "cannot read %s", path);
    }
    *out = p;
    *len = n;
    return FLOE_OK;
}

/* the header: magic, format, byte order, version, scene; *pos after it */
static int check_header(const unsigned char *p, size_t len, const char *path, uint64_t scene_hash,
                        const char *scene_name, size_t *pos, char *err, size_t errlen) {
    if (len < 16 || memcmp(p, MAGIC, 8))
        return floe_error_set(err, errlen, FLOE_EINVAL, "%s is not a floe checkpoint (%s)", path,
                    len < 16 ? "too short" : "no FLOECKPT magic at its start");
    ibuf r = {p, len, 8, 0};
    uint32_t head[2];
    char version[64], scene[512];
    uint64_t hash = 0;
    GET(&r, head);
    get_str(&r, version, sizeof version);
    if (r.bad) return floe_error_set(err, errlen, FLOE_EINVAL, "%s: truncated header", path);
    if (head[1] != BOM)
        return floe_error_set(err, errlen, FLOE_EINVAL, "%s was written on a machine of another byte order", path);
    if (head[0] != FLOE_CHECKPOINT_FORMAT || strcmp(version, FLOE_VERSION_STRING))
        return floe_error_set(err, errlen, FLOE_EINVAL, "%s was written by floe %s, checkpoint format %u; this is floe %s, "
                    "format %d: continue it with the floe that wrote it", path, version, head[0], FLOE_VERSION_STRING,
                    FLOE_CHECKPOINT_FORMAT);
    GET(&r, hash);
    get_str(&r, scene, sizeof scene);
    if (r.bad) return floe_error_set(err, errlen, FLOE_EINVAL, "%s: truncated header", path);
    /* truncated or corrupted: the closing hash over everything before it */
    if (len < r.pos + 12 + sizeof(uint64_t))
        return floe_error_set(err, errlen, FLOE_EINVAL, "%s is truncated (%zu bytes)", path, len);
    uint32_t tag;
    memcpy(&tag, p + len - sizeof(uint64_t) - 12, sizeof tag);
    uint64_t hs;
    memcpy(&hs, p + len - sizeof hs, sizeof hs);
    if (tag != TAG_END)
        return floe_error_set(err, errlen, FLOE_EINVAL, "%s is truncated (%zu bytes, no closing section): the run that wrote it "
                    "was stopped while writing, or the file was cut", path, len);
    if (hs != floe_checkpoint_hash(FLOE_CHECKPOINT_HASH0, p, len - sizeof hs))
        return floe_error_set(err, errlen, FLOE_EINVAL, "%s is corrupted (its checksum does not match its content)", path);
    if (hash != scene_hash)
        return floe_error_set(err, errlen, FLOE_EINVAL, "%s was written for another scene (%s) than this one (%s): the scene "
                    "text differs", path, scene[0] ? scene : "unnamed", scene_name ? scene_name : "unnamed");
    *pos = r.pos;
    return FLOE_OK;
}

/* read the file at path, check its header against the scene and index its sections; on a
 * failure the reason is in why, and *p stays NULL when the file could not be read (else the
 * caller frees it) */
static int open_indexed(const char *path, uint64_t scene_hash, const char *scene_name, unsigned char **p, size_t *len,
                        sec_index *ix, char *why, size_t wlen) {
    size_t pos = 0;
    int rc = read_file(path, p, len, why, wlen);
    if (rc) return rc;
    rc = check_header(*p, *len, path, scene_hash, scene_name, &pos, why, wlen);
    return rc ? rc : index_sections(*p, *len, pos, ix, why, wlen);
}

/* the file into w; with_obs: the observers' section too (else it is skipped: an MPI rank's
 * share of a world whose outputs are rank 0's mirror's) */
static int load_file(floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name, int with_obs,
                     char *err, size_t errlen) {
    if (!w || !path) return floe_error_set(err, errlen, FLOE_EINVAL, "checkpoint: no world or no path");
    /* a world freshly built: prepared by the scene loader (its outputs began and wrote the
     * start, which the observers' restore cuts off again) or not, but no step taken */
    if (w->step != 0 || w->finished)
        return floe_error_set(err, errlen, FLOE_EINVAL, "checkpoint %s: load it into a world freshly built from its scene, "
                    "before its first step", path);
    unsigned char *p = NULL;
    size_t len = 0;
    char why[1024];
    sec_index ix;
    int rc = open_indexed(path, scene_hash, scene_name, &p, &len, &ix, why, sizeof why);
    if (rc && !p) return floe_error_set(err, errlen, rc, "checkpoint: %s", why);
    if (!rc && with_obs) rc = check_observers(w, why, sizeof why);
    if (!rc) rc = prepare_quietly(w, why, sizeof why);
    if (!rc) rc = restore_sections(w, p, &ix, why, sizeof why);
    if (!rc && with_obs) {
        int at = find_section(&ix, TAG_OBSV);
        if (at < 0) rc = floe_error_set(why, sizeof why, FLOE_EINVAL, "section OBSV is missing");
        else {
            ibuf r = {p + ix.at[at], ix.len[at], 0, 0};
            rc = restore_observers(w, &r, why, sizeof why);
        }
    }
    free(p);
    if (rc) return floe_error_set(err, errlen, rc, "checkpoint %s: %s", path, why);
    return FLOE_OK;
}

int floe_world_checkpoint_load(floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name,
                               char *err, size_t errlen) {
    return load_file(w, path, scene_hash, scene_name, 1, err, errlen);
}

int floe_world_checkpoint_load_state(floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name,
                                     char *err, size_t errlen) {
    return load_file(w, path, scene_hash, scene_name, 0, err, errlen);
}

/* ---- under MPI (core/parallel, docs/parallel.md): the same file, written by rank 0 ---- */

int floe_world_parallel_checkpoint_save(const floe_world *w, floe_world *full, const char *path, uint64_t scene_hash,
                                        const char *scene_name, char *err, size_t errlen) {
    if (!w || !w->par) return floe_world_checkpoint_save(w, path, scene_hash, scene_name, err, errlen);
    int rank = 0, size = 1;
    floe_world_parallel_rank(w, &rank, &size);
    int rc = floe_world_parallel_collect(w, full); /* collective; its error is every rank's */
    if (rc) return floe_error_set(err, errlen, rc, "checkpoint: %s", floe_world_last_error(w));
    /* rank 0's own outputs (the vtk pieces) after the mirror's: their series state (frames and
     * times) is every rank's */
    floe_observer *const *own = NULL;
    const int nown = floe_world_parallel_own_outputs(w, &own);
    if (rank == 0) rc = save_file(full, own, nown, path, scene_hash, scene_name, err, errlen);
    double bad = rc != FLOE_OK;
    floe_world_parallel_sum(w, &bad, 1);
    if (bad > 0 && rank != 0)
        return floe_error_set(err, errlen, FLOE_EIO, "checkpoint: rank 0 could not write %s", path);
    return rc;
}

int floe_world_checkpoint_restore_split_outputs(floe_world *w, floe_observer **obs, int nobs, const char *path,
                                                uint64_t scene_hash, const char *scene_name, char *err, size_t errlen) {
    if (!w || !path || (nobs > 0 && !obs)) return floe_error_set(err, errlen, FLOE_EINVAL, "checkpoint: no world or no path");
    unsigned char *p = NULL;
    size_t len = 0;
    char why[1024];
    sec_index ix;
    int rc = open_indexed(path, scene_hash, scene_name, &p, &len, &ix, why, sizeof why);
    if (rc && !p) return floe_error_set(err, errlen, rc, "checkpoint: %s", why);
    int at = rc ? -1 : find_section(&ix, TAG_OBSV);
    if (!rc && at < 0) rc = floe_error_set(why, sizeof why, FLOE_EINVAL, "section OBSV is missing");
    if (!rc) {
        ibuf r = {p + ix.at[at], ix.len[at], 0, 0};
        int n = -1;
        GET(&r, n);
        const int split = r.bad || n < 0 ? -1 : count_split(r, n);
        if (split < 0) rc = floe_error_set(why, sizeof why, FLOE_EINVAL, "the observers' section is malformed");
        else if (split != nobs)
            rc = floe_error_set(why, sizeof why, FLOE_EINVAL, "the checkpoint holds %d output(s) written in pieces per rank, "
                        "this run writes %d (the vtk output): %s", split, nobs, split == 0 ? "a checkpoint written by one "
                        "process (a .vtu series) continues in one process only" : "another scene");
        for (int k = 0, i = 0; !rc && k < n; k++) {
            char name[128];
            double nt;
            int flags[3];
            uint64_t m = 0;
            get_observer(&r, name, sizeof name, &nt, flags, &m);
            if (r.bad) {
                rc = floe_error_set(why, sizeof why, FLOE_EINVAL, "the observers' section is malformed");
                break;
            }
            if (flags[0] != 2) {
                r.pos += m;
                continue;
            }
            floe_observer *o = obs[i++];
            if (strcmp(name, o->klass->name) || !flags[2] || !has_hooks(o)) {
                rc = floe_error_set(why, sizeof why, FLOE_EINVAL, "output %s in pieces: the checkpoint's is %s: another "
                            "scene, or no checkpoint hooks", o->klass->name, name);
                break;
            }
            w->err[0] = 0;
            rc = o->klass->restore(o, w, r.p + r.pos, (size_t)m);
            if (rc) rc = floe_error_set(why, sizeof why, rc, "output %s could not be continued: %s", name, w->err);
            r.pos += m;
            o->next_time = nt;
            o->begun = 1;
            o->ended = 0;
        }
    }
    free(p);
    if (rc) return floe_error_set(err, errlen, rc, "checkpoint %s: %s", path, why);
    return FLOE_OK;
}
