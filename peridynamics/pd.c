/* pd.c - peridynamic bodies: lattice discretisation, families (k-d tree, CSR, one entry per
 * bond), partial-volume factors, damage, time-step estimates. Materials in pd_pmb.c and
 * pd_lps.c. See floe_pd.h for the sources of the equations. */
#include <stdlib.h>
#include <string.h>

#include "floe_pd.h"
#include "floe_kdtree.h"
#include "pd_par.h"

floe_pd_material floe_pd_material_pmb(double rho, double K, double s_c)
{
    floe_pd_material m;
    memset(&m, 0, sizeof m);
    m.model = FLOE_PD_PMB;
    m.rho = rho;
    m.K = K;
    m.E = 1.5 * K; /* nu = 1/4: E = 3K(1 - 2 nu) */
    m.G = 0.6 * K; /* G = E / (2 (1 + nu)) */
    m.s_c = s_c;
    m.broken_tension_only = 1;
    return m;
}

floe_pd_material floe_pd_material_lps(double rho, double K, double G, double s_c, int influence)
{
    floe_pd_material m;
    memset(&m, 0, sizeof m);
    m.model = FLOE_PD_LPS;
    m.rho = rho;
    m.K = K;
    m.G = G;
    m.E = 9.0 * K * G / (3.0 * K + G);
    m.s_c = s_c;
    m.influence = influence;
    m.broken_tension_only = 1;
    return m;
}

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

void floe_pd_body_destroy(floe_pd_body *b)
{
    if (!b) return;
    free(b->X);
    free(b->V);
    free(b->off);
    free(b->partner);
    free(b->len);
    free(b->vfac);
    free(b->broken);
    free(b->scorr);
    free(b->acorr);
    free(b->m);
    free(b->theta);
    free(b->wbond);
    free(b->s0); /* PMB alpha state (pd_materials.c) */
    free(b->splast); /* PMB plastic stretches */
    free(b->dten); /* LPS surface correction (pd_materials.c) */
    free(b->img); /* periodic images (floe_pd_make_periodic) */
    if (b->ops && b->ops->release) b->ops->release(b); /* a user material's state */
    floe_pd_par_free(b); /* threads' buffers (pd_materials.c) */
    free(b);
}

/* Families in the reference configuration: |xi| <= delta + 1e-9 dx (the LAMMPS PERI
 * "3.0001 dx" tolerance for lattice neighbours), each bond once in the row of its lower
 * index, partners sorted. Partial-volume factor (linear): 1 for |xi| <= delta - dx/2,
 * (delta + dx/2 - |xi|)/dx above, clamped to [0, 1]. */
static int build_families(floe_pd_body *b)
{
    int n = b->n;
    b->off = malloc(((size_t)n + 1) * sizeof *b->off);
    if (!b->off) return FLOE_ENOMEM;
    b->off[0] = 0;
    b->nbond = 0;
    if (n == 0) return FLOE_OK;
    floe_kdtree *t = floe_kdtree_build(b->X, n, b->dim, 0);
    if (!t) return FLOE_ENOMEM;
    double tol = b->dx > 0 ? 1e-9 * b->dx : 1e-9 * b->delta;
    double r = b->delta + tol;
    int cap = 256, *buf = malloc((size_t)cap * sizeof *buf);
    int64_t bcap = 1024;
    int32_t *part = malloc((size_t)bcap * sizeof *part);
    int rc = FLOE_OK;
    if (!buf || !part) { rc = FLOE_ENOMEM; goto done; }
    for (int i = 0; i < n; i++) {
        const double *q = b->X + 3 * (size_t)i;
        int cnt = floe_kdtree_radius(t, q, r, buf, cap);
        if (cnt > cap) {
            int *nb = realloc(buf, (size_t)cnt * sizeof *nb);
            if (!nb) { rc = FLOE_ENOMEM; goto done; }
            buf = nb;
            cap = cnt;
            cnt = floe_kdtree_radius(t, q, r, buf, cap);
        }
        int64_t start = b->nbond;
        for (int k = 0; k < cnt; k++) {
            if (buf[k] <= i) continue;
            if (b->nbond == bcap) {
                int32_t *np = realloc(part, (size_t)(2 * bcap) * sizeof *np);
                if (!np) { rc = FLOE_ENOMEM; goto done; }
                part = np;
                bcap *= 2;
            }
            part[b->nbond++] = buf[k];
        }
        qsort(part + start, (size_t)(b->nbond - start), sizeof *part, cmp_i32);
        b->off[i + 1] = b->nbond;
    }
    {
        size_t nb = (size_t)(b->nbond > 0 ? b->nbond : 1);
        int32_t *np = realloc(part, nb * sizeof *np);
        if (np) part = np;
        b->partner = part;
        part = NULL;
        b->len = malloc(nb * sizeof *b->len);
        b->vfac = malloc(nb * sizeof *b->vfac);
        b->broken = calloc(nb, 1);
        if (!b->len || !b->vfac || !b->broken) { rc = FLOE_ENOMEM; goto done; }
        for (int i = 0; i < n; i++) {
            const double *xi = b->X + 3 * (size_t)i;
            for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
                const double *xj = b->X + 3 * (size_t)b->partner[k];
                double d[3];
                floe_v3_sub(d, xj, xi);
                double L = floe_v3_norm(d);
                b->len[k] = L;
                double beta = 1.0;
                if (b->dx > 0 && L > b->delta - 0.5 * b->dx)
                    beta = (b->delta + 0.5 * b->dx - L) / b->dx;
                if (beta > 1.0) beta = 1.0;
                if (beta < 0.0) beta = 0.0;
                b->vfac[k] = (float)beta;
            }
        }
    }
done:
    free(buf);
    free(part);
    floe_kdtree_destroy(t);
    return rc;
}

int floe_pd_body_create_points(floe_pd_body **out, int dim, int n, const double *X,
                               const double *V, double delta, double dx, double thickness)
{
    if (!out) return FLOE_EINVAL;
    *out = NULL;
    if ((dim != 2 && dim != 3) || n < 0 || (n > 0 && (!X || !V)) || !(delta > 0))
        return FLOE_EINVAL;
    for (int i = 0; i < n; i++)
        if (!(V[i] > 0)) return FLOE_EINVAL;
    floe_pd_body *b = calloc(1, sizeof *b);
    if (!b) return FLOE_ENOMEM;
    b->dim = dim;
    b->n = n;
    b->dx = dx > 0 ? dx : 0;
    b->delta = delta;
    b->thickness = dim == 2 ? (thickness > 0 ? thickness : (dx > 0 ? dx : delta)) : 0;
    size_t nn = (size_t)(n > 0 ? n : 1);
    b->X = malloc(3 * nn * sizeof *b->X);
    b->V = malloc(nn * sizeof *b->V);
    if (!b->X || !b->V) { floe_pd_body_destroy(b); return FLOE_ENOMEM; }
    if (n > 0) {
        memcpy(b->X, X, 3 * (size_t)n * sizeof *X);
        memcpy(b->V, V, (size_t)n * sizeof *V);
    }
    int rc = build_families(b);
    if (rc != FLOE_OK) { floe_pd_body_destroy(b); return rc; }
    *out = b;
    return FLOE_OK;
}

/* Hexagonal lattice (floe_pd.h, FLOE_PD_LATTICE_HEXAGONAL): 2D triangular, 3D HCP, nearest
 * distance dx; the points inside the box [lo, hi] (1e-9 dx tolerance) with sdf <= 0. The
 * row and layer pitches (sqrt(3)/2 dx, sqrt(2/3) dx) do not divide a box, so the lattice is
 * centred in the box (pass -1 finds the extent of the in-box points; the shift keeps the
 * same points in the box) and a symmetric box gives a symmetric body. */
static int body_create_hex(floe_pd_body **out, const floe_pd_region *r, double m)
{
    const double dx = r->dx, dy = 0.5 * sqrt(3.0) * dx, dz = sqrt(2.0 / 3.0) * dx;
    const double tol = 1e-9 * dx;
    const double pitch[3] = {dx, dy, dz};
    long nk[3] = {1, 1, 1};
    for (int d = 0; d < r->dim; d++) {
        double ext = (r->hi[d] - r->lo[d]) / pitch[d];
        if (!(ext >= 1.0 - 1e-9) || ext > 1e7) return FLOE_EINVAL;
        nk[d] = (long)floor(ext + 1e-9) + 1; /* candidates; the box test keeps the inside */
    }
    double total = (double)nk[0] * (double)nk[1] * (double)nk[2];
    if (total > 2e9) return FLOE_EINVAL;
    double h = r->dim == 2 ? (r->thickness > 0 ? r->thickness : dx) : 0;
    double vol = r->dim == 3 ? dx * dx * dx / sqrt(2.0) : dy * dx * h;
    size_t cap = 0, n = 0;
    double *X = NULL, *V = NULL;
    double shift[3] = {0, 0, 0}, pmin[3] = {INFINITY, INFINITY, INFINITY}, pmax[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int pass = -1; pass < 2; pass++) {
        n = 0;
        for (long k = 0; k < nk[2]; k++) {
            int layer_b = r->dim == 3 && (k & 1); /* 3D: B layers of the ABAB stacking */
            double yoff = r->dim == 3 ? (layer_b ? 2.0 / 3.0 : 1.0 / 3.0) : 0.5;
            for (long j = 0; j < nk[1]; j++) {
                double xoff = ((j + layer_b) & 1) ? 0.75 : 0.25;
                for (long i = 0; i < nk[0]; i++) {
                    double p[3] = {r->lo[0] + (i + xoff) * dx + shift[0], r->lo[1] + (j + yoff) * dy + shift[1],
                                   r->dim == 3 ? r->lo[2] + (k + 0.5) * dz + shift[2] : 0.5 * (r->lo[2] + r->hi[2])};
                    int in = 1;
                    for (int d = 0; d < r->dim; d++)
                        if (p[d] < r->lo[d] - tol || p[d] > r->hi[d] + tol) in = 0;
                    if (!in) continue;
                    if (pass < 0) {
                        for (int d = 0; d < r->dim; d++) {
                            pmin[d] = fmin(pmin[d], p[d]);
                            pmax[d] = fmax(pmax[d], p[d]);
                        }
                        continue;
                    }
                    if (r->sdf && !(r->sdf(p, r->sdf_user) <= 0)) continue;
                    if (pass == 1) {
                        floe_v3_copy(X + 3 * n, p);
                        V[n] = vol;
                    }
                    n++;
                }
            }
        }
        if (pass < 0) {
            for (int d = 0; d < r->dim; d++)
                if (pmax[d] >= pmin[d]) shift[d] = 0.5 * ((r->lo[d] + r->hi[d]) - (pmin[d] + pmax[d]));
        } else if (pass == 0) {
            if (n > (size_t)INT32_MAX) return FLOE_EINVAL;
            cap = n > 0 ? n : 1;
            X = malloc(3 * cap * sizeof *X);
            V = malloc(cap * sizeof *V);
            if (!X || !V) { free(X); free(V); return FLOE_ENOMEM; }
        }
    }
    int rc = floe_pd_body_create_points(out, r->dim, (int)n, X, V, m * dx, dx, h);
    free(X);
    free(V);
    return rc;
}

int floe_pd_body_create(floe_pd_body **out, const floe_pd_region *r)
{
    if (!out) return FLOE_EINVAL;
    *out = NULL;
    if (!r || (r->dim != 2 && r->dim != 3) || !(r->dx > 0)) return FLOE_EINVAL;
    double m = r->horizon_factor > 0 ? r->horizon_factor : 3.0;
    if (r->lattice == FLOE_PD_LATTICE_HEXAGONAL) return body_create_hex(out, r, m);
    if (r->lattice != FLOE_PD_LATTICE_CUBIC) return FLOE_EINVAL;
    long nk[3] = {1, 1, 1};
    for (int d = 0; d < r->dim; d++) {
        double ext = (r->hi[d] - r->lo[d]) / r->dx;
        if (!(ext >= 1.0 - 1e-9) || ext > 1e7) return FLOE_EINVAL;
        nk[d] = (long)floor(ext + 1e-9);
    }
    double total = (double)nk[0] * (double)nk[1] * (double)nk[2];
    if (total > 2e9) return FLOE_EINVAL;
    double h = r->dim == 2 ? (r->thickness > 0 ? r->thickness : r->dx) : 0;
    double vol = r->dim == 3 ? r->dx * r->dx * r->dx : r->dx * r->dx * h;
    /* count, then fill */
    size_t cap = 0, n = 0;
    double *X = NULL, *V = NULL;
    for (int pass = 0; pass < 2; pass++) {
        n = 0;
        for (long k = 0; k < nk[2]; k++)
            for (long j = 0; j < nk[1]; j++)
                for (long i = 0; i < nk[0]; i++) {
                    double p[3] = {r->lo[0] + (i + 0.5) * r->dx, r->lo[1] + (j + 0.5) * r->dx,
                                   r->dim == 3 ? r->lo[2] + (k + 0.5) * r->dx
                                               : 0.5 * (r->lo[2] + r->hi[2])};
                    if (r->sdf && !(r->sdf(p, r->sdf_user) <= 0)) continue;
                    if (pass == 1) {
                        floe_v3_copy(X + 3 * n, p);
                        V[n] = vol;
                    }
                    n++;
                }
        if (pass == 0) {
            cap = n > 0 ? n : 1;
            X = malloc(3 * cap * sizeof *X);
            V = malloc(cap * sizeof *V);
            if (!X || !V) { free(X); free(V); return FLOE_ENOMEM; }
        }
    }
    int rc = floe_pd_body_create_points(out, r->dim, (int)n, X, V, m * r->dx, r->dx, h);
    free(X);
    free(V);
    return rc;
}

void floe_pd_family_sizes(const floe_pd_body *b, int *cnt)
{
    for (int i = 0; i < b->n; i++) cnt[i] = 0;
    for (int i = 0; i < b->n; i++) {
        cnt[i] += (int)(b->off[i + 1] - b->off[i]);
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) cnt[b->partner[k]]++;
    }
}

int64_t floe_pd_bond_index(const floe_pd_body *b, int i, int j)
{
    if (!b || i == j || i < 0 || j < 0 || i >= b->n || j >= b->n) return -1;
    if (i > j) { int t = i; i = j; j = t; }
    int64_t lo = b->off[i], hi = b->off[i + 1];
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (b->partner[mid] < j) lo = mid + 1;
        else hi = mid;
    }
    return lo < b->off[i + 1] && b->partner[lo] == j ? lo : -1;
}

int floe_pd_bonded(const floe_pd_body *b, int i, int j)
{
    return floe_pd_bond_index(b, i, j) >= 0;
}

int floe_pd_damage(const floe_pd_body *b, double *phi)
{
    /* 003 eq 7: phi_i = 1 - sum_j mu beta V_j / sum_j beta V_j */
    if (!b || (!phi && b->n > 0)) return FLOE_EINVAL;
    int n = b->n;
    double *tot = calloc((size_t)(n > 0 ? n : 1), sizeof *tot);
    if (!tot) return FLOE_ENOMEM;
    for (int i = 0; i < n; i++) phi[i] = 0;
    for (int i = 0; i < n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            double wi = b->vfac[k] * b->V[j], wj = b->vfac[k] * b->V[i];
            tot[i] += wi;
            tot[j] += wj;
            if (!b->broken[k]) { phi[i] += wi; phi[j] += wj; }
        }
    for (int i = 0; i < n; i++) phi[i] = tot[i] > 0 ? 1.0 - phi[i] / tot[i] : 0.0;
    free(tot);
    return FLOE_OK;
}

int floe_pd_set_material(floe_pd_body *b, const floe_pd_material *m)
{
    if (!b || !m || !(m->rho > 0) || !(m->s_c >= 0) || !(m->G_c >= 0)) return FLOE_EINVAL;
    const floe_pd_material_ops *ops;
    if (m->model == FLOE_PD_PMB) ops = &floe_pd_pmb_ops;
    else if (m->model == FLOE_PD_LPS) ops = &floe_pd_lps_ops;
    else if (m->model == FLOE_PD_USER && m->ops && m->ops->init && m->ops->forces && m->ops->bond_micromodulus &&
             (!m->ops->state_size || (m->ops->save && m->ops->restore)))
        ops = m->ops;
    else return FLOE_EINVAL;
    floe_pd_material save = b->mat;
    const floe_pd_material_ops *save_ops = b->ops;
    /* a user material's state goes with it (its init allocates it anew) */
    if (save_ops && save_ops->release) save_ops->release(b);
    b->mat = *m;
    b->ops = ops;
    int rc = ops->init(b);
    if (rc != FLOE_OK) {
        if (ops->release) ops->release(b);
        b->mat = save;
        b->ops = save_ops;
        if (save_ops && save_ops->release) save_ops->init(b); /* its state back (fresh) */
        return rc;
    }
    free(b->scorr);
    b->scorr = NULL;
    free(b->acorr);
    b->acorr = NULL;
    /* critical stretch: given, or from G_c by 003 eq 5 (3D) / its 2D analogue with the
     * (equivalent) PMB micromodulus */
    double c = ops->bond_micromodulus(b);
    b->s_c = m->s_c;
    if (b->s_c == 0 && m->G_c > 0) {
        if (b->dim == 3) b->s_c = sqrt(10.0 * m->G_c / (M_PI * c * pow(b->delta, 5)));
        else b->s_c = sqrt(4.0 * m->G_c / (c * b->thickness * pow(b->delta, 4)));
    }
    return FLOE_OK;
}

static double forces_impl(floe_pd_body *b, const double *x, double *f, int allow_break)
{
    if (!b || !b->ops) return 0.0;
    double s_c = b->s_c;
    if (!allow_break) b->s_c = 0;
    double e = b->ops->forces(b, x, f);
    b->s_c = s_c;
    return e;
}

double floe_pd_forces(floe_pd_body *b, const double *x, double *f)
{
    return forces_impl(b, x, f, 1);
}

double floe_pd_forces_nobreak(floe_pd_body *b, const double *x, double *f)
{
    return forces_impl(b, x, f, 0);
}

int floe_pd_surface_correction(floe_pd_body *b)
{
    if (!b || !b->ops) return FLOE_EINVAL;
    if (b->mat.model == FLOE_PD_LPS) return floe_pd_lps_surface_correction(b); /* pd_materials.c */
    if (b->mat.model == FLOE_PD_USER) return b->ops->surface_correction ? b->ops->surface_correction(b) : FLOE_ENOTSUP;
    if (b->mat.model != FLOE_PD_PMB) return FLOE_ENOTSUP;
    size_t n = (size_t)(b->n > 0 ? b->n : 1), nb = (size_t)(b->nbond > 0 ? b->nbond : 1);
    double *sum = calloc(3 * n, sizeof *sum);
    float *sc = malloc(nb * sizeof *sc);
    if (!sum || !sc) { free(sum); free(sc); return FLOE_ENOMEM; }
    const int nd = b->dim;
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            double L = b->len[k], d[3];
            floe_pd_ref_vec(b, i, j, k, d);
            for (int a = 0; a < nd; a++) {
                double na = d[a] / L, q = na * na * na * na * L * b->vfac[k];
                sum[3 * (size_t)i + a] += q * b->V[j];
                sum[3 * (size_t)j + a] += q * b->V[i];
            }
        }
    double dl = b->delta;
    double ref = nd == 3 ? M_PI * dl * dl * dl * dl / 5.0 : M_PI * b->thickness * dl * dl * dl / 4.0;
    for (size_t i = 0; i < 3 * (size_t)b->n; i++) sum[i] = sum[i] > 0 ? ref / sum[i] : 1.0;
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            double L = b->len[k], d[3], q = 0;
            floe_pd_ref_vec(b, i, j, k, d);
            for (int a = 0; a < nd; a++) {
                double G = 0.5 * (sum[3 * (size_t)i + a] + sum[3 * (size_t)j + a]);
                double t = d[a] / L / G;
                q += t * t;
            }
            sc[k] = q > 0 ? (float)(1.0 / sqrt(q)) : 1.0f;
        }
    free(sum);
    free(b->scorr);
    b->scorr = sc;
    return FLOE_OK;
}

double floe_pd_dt_nodal(const floe_pd_body *b)
{
    if (!b || !b->ops || b->n == 0) return 0.0;
    double c = b->ops->bond_micromodulus(b);
    double *sum = calloc((size_t)b->n, sizeof *sum);
    if (!sum) return 0.0;
    for (int i = 0; i < b->n; i++)
        for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
            int j = b->partner[k];
            double s = b->vfac[k] * (b->scorr ? b->scorr[k] : 1.0f) * c / b->len[k];
            sum[i] += s * b->V[j];
            sum[j] += s * b->V[i];
        }
    double dt = INFINITY;
    for (int i = 0; i < b->n; i++)
        if (sum[i] > 0) {
            double d = sqrt(2.0 * b->mat.rho / sum[i]);
            if (d < dt) dt = d;
        }
    free(sum);
    return dt;
}

double floe_pd_dt_cfl(const floe_pd_body *b)
{
    if (!b || !b->ops) return 0.0;
    double M = b->mat.model == FLOE_PD_LPS ? b->mat.K + 4.0 / 3.0 * b->mat.G : b->mat.K;
    if (b->mat.model == FLOE_PD_PMB && b->dim == 2) M = b->mat.E;
    double h = b->dx > 0 ? b->dx : b->delta / 3.0;
    return h / sqrt(M / b->mat.rho);
}

size_t floe_pd_bytes_per_bond(void)
{
    return sizeof(int32_t) + sizeof(double) + sizeof(float) + sizeof(uint8_t);
}

size_t floe_pd_body_bytes(const floe_pd_body *b)
{
    if (!b) return 0;
    size_t n = (size_t)b->n, nb = (size_t)b->nbond;
    size_t s = sizeof *b + n * (3 * sizeof(double) + sizeof(double)) + (n + 1) * sizeof(int64_t) +
               nb * floe_pd_bytes_per_bond();
    if (b->m) s += n * sizeof(double);
    if (b->theta) s += n * sizeof(double);
    if (b->wbond) s += nb * sizeof(double);
    if (b->scorr) s += nb * sizeof(float);
    if (b->acorr) s += n * sizeof(double);
    if (b->s0) s += 2 * n * sizeof(double); /* PMB alpha state */
    if (b->splast) s += (size_t)b->nbond * sizeof(float); /* PMB plastic stretches */
    if (b->dten) s += 11 * n * sizeof(double); /* LPS surface correction */
    if (b->img) s += nb * sizeof(int32_t); /* periodic images */
    return s;
}

/* ---- periodic families (floe_pd_make_periodic) ---- */

typedef struct pd_imgbond {
    int32_t j, code;
} pd_imgbond;

static int cmp_imgbond(const void *a, const void *b)
{
    int32_t x = ((const pd_imgbond *)a)->j, y = ((const pd_imgbond *)b)->j;
    return (x > y) - (x < y);
}

static double pd_det3(const double A[9])
{
    return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) + A[2] * (A[3] * A[7] - A[4] * A[6]);
}

int floe_pd_make_periodic(floe_pd_body *b, const double o[3], const double H[9], const double *Hlive)
{
    if (!b || !o || !H || !Hlive || !b->ops) return FLOE_EINVAL;
    if (b->mat.model == FLOE_PD_USER || b->ncut > 0) return FLOE_ENOTSUP;
    if (b->nbroken > 0) return FLOE_EINVAL;
    const int n = b->n, dim = b->dim;
    double Hc[9];
    memcpy(Hc, H, sizeof Hc);
    if (dim == 2) Hc[2] = Hc[5] = Hc[6] = Hc[7] = 0, Hc[8] = 1.0;
    double det = pd_det3(Hc);
    if (!(det > 0) || !isfinite(det)) return FLOE_EINVAL;
    double Hi[9] = {(Hc[4] * Hc[8] - Hc[5] * Hc[7]) / det, (Hc[2] * Hc[7] - Hc[1] * Hc[8]) / det,
                    (Hc[1] * Hc[5] - Hc[2] * Hc[4]) / det, (Hc[5] * Hc[6] - Hc[3] * Hc[8]) / det,
                    (Hc[0] * Hc[8] - Hc[2] * Hc[6]) / det, (Hc[2] * Hc[3] - Hc[0] * Hc[5]) / det,
                    (Hc[3] * Hc[7] - Hc[4] * Hc[6]) / det, (Hc[1] * Hc[6] - Hc[0] * Hc[7]) / det,
                    (Hc[0] * Hc[4] - Hc[1] * Hc[3]) / det};
    double tol = b->dx > 0 ? 1e-9 * b->dx : 1e-9 * b->delta;
    double r = b->delta + tol;
    /* every width (1/|row k of H^-1|) more than two horizons: one image per pair at most */
    for (int a = 0; a < dim; a++) {
        double q = sqrt(Hi[3 * a] * Hi[3 * a] + Hi[3 * a + 1] * Hi[3 * a + 1] + Hi[3 * a + 2] * Hi[3 * a + 2]);
        if (!(q > 0) || !(1.0 / q > 2.0 * r)) return FLOE_EINVAL;
    }
    size_t nn = (size_t)(n > 0 ? n : 1);
    double *Y = calloc(3 * nn, sizeof *Y);
    int *sh = malloc(3 * nn * sizeof *sh);
    int64_t *off = malloc((nn + 1) * sizeof *off);
    int cap = 256, *buf = malloc((size_t)cap * sizeof *buf);
    int64_t bcap = 1024, nb = 0;
    pd_imgbond *bond = malloc((size_t)bcap * sizeof *bond);
    floe_kdtree *t = NULL;
    int rc = FLOE_OK;
    if (!Y || !sh || !off || !buf || !bond) { rc = FLOE_ENOMEM; goto done; }
    /* the points wrapped into the cell: Y = X - H sh, sh = floor(H^-1 (X - o)) */
    for (int i = 0; i < n; i++) {
        const double *X = b->X + 3 * (size_t)i;
        double d[3] = {X[0] - o[0], X[1] - o[1], X[2] - o[2]}, y[3];
        for (int a = 0; a < 3; a++) {
            double s = Hi[3 * a] * d[0] + Hi[3 * a + 1] * d[1] + Hi[3 * a + 2] * d[2];
            double f = a < dim ? floor(s) : 0.0;
            if (!(fabs(f) < 400)) { rc = FLOE_EINVAL; goto done; } /* image codes hold +-511 */
            sh[3 * (size_t)i + a] = (int)f;
        }
        for (int a = 0; a < 3; a++)
            y[a] = X[a] - (Hc[3 * a] * sh[3 * (size_t)i] + Hc[3 * a + 1] * sh[3 * (size_t)i + 1] +
                           Hc[3 * a + 2] * sh[3 * (size_t)i + 2]);
        floe_v3_copy(Y + 3 * (size_t)i, y);
    }
    t = floe_kdtree_build(Y, n, dim, 0);
    if (n > 0 && !t) { rc = FLOE_ENOMEM; goto done; }
    off[0] = 0;
    const int mz = dim == 3 ? 1 : 0;
    for (int i = 0; i < n; i++) {
        int64_t start = nb;
        const double *yi = Y + 3 * (size_t)i;
        for (int m0 = -1; m0 <= 1; m0++)
            for (int m1 = -1; m1 <= 1; m1++)
                for (int m2 = -mz; m2 <= mz; m2++) {
                    /* j found near y_i + H m: X_j + H n - X_i = y_j - y_i - H m, n = sh_i - sh_j - m */
                    double q[3];
                    for (int a = 0; a < 3; a++) q[a] = yi[a] + Hc[3 * a] * m0 + Hc[3 * a + 1] * m1 + Hc[3 * a + 2] * m2;
                    int cnt = floe_kdtree_radius(t, q, r, buf, cap);
                    if (cnt > cap) {
                        int *nbuf = realloc(buf, (size_t)cnt * sizeof *nbuf);
                        if (!nbuf) { rc = FLOE_ENOMEM; goto done; }
                        buf = nbuf;
                        cap = cnt;
                        cnt = floe_kdtree_radius(t, q, r, buf, cap);
                    }
                    for (int c = 0; c < cnt; c++) {
                        int j = buf[c];
                        if (j == i && (m0 || m1 || m2)) { rc = FLOE_EINVAL; goto done; } /* its own image */
                        if (j <= i) continue;
                        double dd = 0;
                        for (int a = 0; a < 3; a++) dd += (Y[3 * (size_t)j + a] - q[a]) * (Y[3 * (size_t)j + a] - q[a]);
                        if (dd <= 1e-18 * r * r) { rc = FLOE_EINVAL; goto done; } /* two points on one spot */
                        const int *si = sh + 3 * (size_t)i, *sj = sh + 3 * (size_t)j;
                        int code = floe_img_encode(si[0] - sj[0] - m0, si[1] - sj[1] - m1, dim == 3 ? si[2] - sj[2] - m2 : 0);
                        if (nb == bcap) {
                            pd_imgbond *nbd = realloc(bond, (size_t)(2 * bcap) * sizeof *nbd);
                            if (!nbd) { rc = FLOE_ENOMEM; goto done; }
                            bond = nbd;
                            bcap *= 2;
                        }
                        bond[nb].j = j;
                        bond[nb].code = code;
                        nb++;
                    }
                }
        qsort(bond + start, (size_t)(nb - start), sizeof *bond, cmp_imgbond);
        for (int64_t k = start + 1; k < nb; k++)
            if (bond[k].j == bond[k - 1].j) { rc = FLOE_EINVAL; goto done; } /* two images (cannot be) */
        off[i + 1] = nb;
    }
    {
        size_t nbb = (size_t)(nb > 0 ? nb : 1);
        int32_t *part = malloc(nbb * sizeof *part), *img = malloc(nbb * sizeof *img);
        double *len = malloc(nbb * sizeof *len);
        float *vfac = malloc(nbb * sizeof *vfac);
        uint8_t *brk = calloc(nbb, 1);
        if (!part || !img || !len || !vfac || !brk) {
            free(part); free(img); free(len); free(vfac); free(brk);
            rc = FLOE_ENOMEM;
            goto done;
        }
        int any = 0;
        for (int64_t k = 0; k < nb; k++) {
            part[k] = bond[k].j;
            img[k] = bond[k].code;
            any |= img[k] != 0;
        }
        free(b->off); free(b->partner); free(b->len); free(b->vfac); free(b->broken); free(b->img);
        floe_pd_par_free(b); /* the threads' index of the old bonds */
        b->off = off;
        off = NULL;
        b->partner = part;
        b->len = len;
        b->vfac = vfac;
        b->broken = brk;
        b->nbond = nb;
        b->img = any ? img : NULL; /* no bond across the faces: the plain path */
        if (!any) free(img);
        memcpy(b->cellH0, Hc, sizeof Hc);
        b->cellH = Hlive;
        for (int i = 0; i < n; i++)
            for (int64_t k = b->off[i]; k < b->off[i + 1]; k++) {
                double d[3];
                floe_pd_ref_vec(b, i, b->partner[k], k, d);
                double L = floe_v3_norm(d);
                len[k] = L;
                double beta = 1.0;
                if (b->dx > 0 && L > b->delta - 0.5 * b->dx) beta = (b->delta + 0.5 * b->dx - L) / b->dx;
                if (beta > 1.0) beta = 1.0;
                if (beta < 0.0) beta = 0.0;
                vfac[k] = (float)beta;
            }
        /* per-bond material state sized by the new families */
        int corr = b->scorr != NULL || b->dten != NULL;
        free(b->splast);
        b->splast = NULL;
        floe_pd_material m = b->mat;
        rc = floe_pd_set_material(b, &m);
        if (rc == FLOE_OK && corr) rc = floe_pd_surface_correction(b);
    }
done:
    floe_kdtree_destroy(t);
    free(Y);
    free(sh);
    free(off);
    free(buf);
    free(bond);
    return rc;
}
