/* cell.c - the periodic cell (floe_cell.h, docs/periodic.md): its definition and control,
 * the affine map of every step, the servo on stress components, the homogenised stress
 * with image branch vectors, ParticLS eq 29's tangent and strain increments. The pairs'
 * images are the neighbour list's (neighbor.c), the contact stage reads them (forces.c). */
#include "world_internal.h"
#include "floe_contact.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double det3(const double A[9]) {
    return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) + A[2] * (A[3] * A[7] - A[4] * A[6]);
}
static int inv3(const double A[9], double B[9]) {
    double d = det3(A);
    if (!(fabs(d) > 0) || !isfinite(d)) return FLOE_EINVAL;
    double id = 1.0 / d;
    B[0] = (A[4] * A[8] - A[5] * A[7]) * id;
    B[1] = (A[2] * A[7] - A[1] * A[8]) * id;
    B[2] = (A[1] * A[5] - A[2] * A[4]) * id;
    B[3] = (A[5] * A[6] - A[3] * A[8]) * id;
    B[4] = (A[0] * A[8] - A[2] * A[6]) * id;
    B[5] = (A[2] * A[3] - A[0] * A[5]) * id;
    B[6] = (A[3] * A[7] - A[4] * A[6]) * id;
    B[7] = (A[1] * A[6] - A[0] * A[7]) * id;
    B[8] = (A[0] * A[4] - A[1] * A[3]) * id;
    return FLOE_OK;
}
static void mul3(const double A[9], const double B[9], double C[9]) {
    double T[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) T[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
    memcpy(C, T, sizeof T);
}
static void mv3(const double A[9], const double x[3], double y[3]) {
    for (int r = 0; r < 3; r++) y[r] = A[3 * r] * x[0] + A[3 * r + 1] * x[1] + A[3 * r + 2] * x[2];
}

/* distance between opposite faces: 1 / |row k of H^-1| */
static void widths_of(const double Hinv[9], int dim, double wd[3]) {
    for (int k = 0; k < 3; k++) {
        const double *r = Hinv + 3 * k;
        double n = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        wd[k] = k < dim && n > 0 ? 1.0 / n : INFINITY;
    }
}
static double min_width(const floe_cell_state *c, int dim) {
    double wd[3];
    widths_of(c->Hinv, dim, wd);
    return fmin(wd[0], fmin(wd[1], wd[2]));
}

static int check_planar(floe_world *w, const double H[9], const char *what) {
    if (w->def.dim != 2) return FLOE_OK;
    if (H[2] != 0 || H[5] != 0 || H[6] != 0 || H[7] != 0)
        return floe_world_error(w, FLOE_EINVAL, "%s: a 2D cell has no z component (H[0][2], H[1][2], H[2][0], "
                                "H[2][1] must be 0)", what);
    return FLOE_OK;
}

int floe_world_set_cell(floe_world *w, const double origin[3], const double H[9]) {
    FLOE_TRY(floe_world_refuse_split(w, "set_cell"));
    double Hc[9];
    memcpy(Hc, H, sizeof Hc);
    if (w->def.dim == 2) Hc[8] = 1.0;
    for (int k = 0; k < 9; k++)
        if (!isfinite(Hc[k])) return floe_world_error(w, FLOE_EINVAL, "cell: H[%d][%d] is not finite", k / 3, k % 3);
    for (int k = 0; k < 3; k++)
        if (!isfinite(origin[k])) return floe_world_error(w, FLOE_EINVAL, "cell: the origin is not finite");
    FLOE_TRY(check_planar(w, Hc, "cell"));
    double d = det3(Hc);
    if (!(d > 0))
        return floe_world_error(w, FLOE_EINVAL, "cell: det H = %g; the cell vectors (the columns of H) must be a "
                                "right-handed set spanning a volume", d);
    floe_cell_state *c = w->cell;
    if (!c) {
        c = calloc(1, sizeof *c);
        if (!c) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        c->ctl = floe_default_cell_control();
        w->cell = c;
    }
    memcpy(c->o, origin, sizeof c->o);
    if (w->def.dim == 2) c->o[2] = origin[2];
    memcpy(c->H, Hc, sizeof c->H);
    inv3(c->H, c->Hinv);
    memset(c->L, 0, sizeof c->L);
    c->valid = 0;
    c->path = 0;
    w->prepared = 0; /* the list is built again with the images */
    for (int k = 0; k < w->npd; k++) FLOE_TRY(floe_world_pd_periodic(w, w->pd[k], k)); /* PD families */
    return FLOE_OK;
}

int floe_world_cell(const floe_world *w, double origin[3], double H[9]) {
    if (!w->cell) return 0;
    if (origin) memcpy(origin, w->cell->o, 3 * sizeof(double));
    if (H) memcpy(H, w->cell->H, 9 * sizeof(double));
    return 1;
}

double floe_world_cell_volume(const floe_world *w) { return w->cell ? det3(w->cell->H) : 0.0; }

int floe_world_cell_widths(const floe_world *w, double width[3]) {
    if (!w->cell) return FLOE_EINVAL;
    widths_of(w->cell->Hinv, w->def.dim, width);
    return FLOE_OK;
}

int floe_world_cell_wrap(const floe_world *w, const double x[3], double out[3]) {
    return floe_world_cell_wrap_image(w, x, out, NULL);
}

int floe_world_cell_wrap_image(const floe_world *w, const double x[3], double out[3], int image[3]) {
    const floe_cell_state *c = w->cell;
    if (image) image[0] = image[1] = image[2] = 0;
    if (!c) {
        memcpy(out, x, 3 * sizeof(double));
        return FLOE_EINVAL;
    }
    double d[3], s[3];
    floe_v3_sub(d, x, c->o);
    mv3(c->Hinv, d, s);
    for (int k = 0; k < w->def.dim; k++) {
        double f = floor(s[k]);
        s[k] -= f;
        if (image) image[k] = (int)f;
    }
    if (w->def.dim == 2) s[2] = 0;
    mv3(c->H, s, out);
    floe_v3_add(out, out, c->o);
    if (w->def.dim == 2) out[2] = x[2];
    return FLOE_OK;
}

floe_cell_control floe_default_cell_control(void) {
    floe_cell_control c;
    memset(&c, 0, sizeof c);
    return c;
}

int floe_world_cell_set_control(floe_world *w, const floe_cell_control *ctl) {
    floe_cell_state *c = w->cell;
    if (!c) return floe_world_error(w, FLOE_EINVAL, "cell control: the world has no periodic cell (floe_world_set_cell)");
    int any_stress = 0;
    for (int k = 0; k < 9; k++) {
        int a = k / 3, b = k % 3;
        if (ctl->mode[k] != FLOE_CELL_RATE && ctl->mode[k] != FLOE_CELL_STRESS)
            return floe_world_error(w, FLOE_EINVAL, "cell control: mode of component (%d, %d) is %d (rate 0 or stress 1)",
                                    a, b, ctl->mode[k]);
        if (!isfinite(ctl->rate[k]) || !isfinite(ctl->stress[k]))
            return floe_world_error(w, FLOE_EINVAL, "cell control: component (%d, %d) is not finite", a, b);
        if (w->def.dim == 2 && (a == 2 || b == 2) && (ctl->mode[k] != FLOE_CELL_RATE || ctl->rate[k] != 0))
            return floe_world_error(w, FLOE_EINVAL, "cell control: a 2D cell has no component (%d, %d)", a, b);
        any_stress |= ctl->mode[k] == FLOE_CELL_STRESS;
    }
    if (any_stress && !(ctl->max_rate > 0 && isfinite(ctl->max_rate)))
        return floe_world_error(w, FLOE_EINVAL, "cell control: max_rate must be > 0 (1/s) with a stress-controlled "
                                "component (got %g)", ctl->max_rate);
    if (!(ctl->servo_time >= 0) || !isfinite(ctl->servo_time))
        return floe_world_error(w, FLOE_EINVAL, "cell control: servo_time must be >= 0 (s; 0 = 50 steps)");
    c->ctl = *ctl;
    c->want_kdiag = any_stress;
    return FLOE_OK;
}

int floe_world_cell_get_control(const floe_world *w, floe_cell_control *ctl) {
    if (!w->cell) return FLOE_EINVAL;
    *ctl = w->cell->ctl;
    return FLOE_OK;
}

int floe_world_cell_velocity_gradient(const floe_world *w, double L[9]) {
    if (!w->cell) return FLOE_EINVAL;
    memcpy(L, w->cell->L, 9 * sizeof(double));
    return FLOE_OK;
}

/* the sums in nine locals, not through mvv (which may alias the store: every term was a
 * load and a store, and this pass cost as much as a drift: 11 % of a periodic compaction's
 * step, bench/RESULTS.md issue 14 session 31); the same additions in the same order */
void floe_cell_mvv(const floe_particles *p, int lo, int hi, double mvv[9]) {
    double s[9];
    memcpy(s, mvv, sizeof s);
    const double *restrict vv = p->v, *restrict mass = p->mass;
    const unsigned char *restrict motion = p->motion;
    for (int i = lo; i < hi; i++) {
        if (motion[i] != FLOE_FREE) continue;
        const double *v = vv + 3 * i, m = mass[i];
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) s[3 * a + b] += m * v[a] * v[b];
    }
    memcpy(mvv, s, sizeof s);
}

void floe_cell_stress_of(const double vir[9], const double pvir[9], const double mvv[9], double V, double sigma[9]) {
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            sigma[3 * a + b] =
                0.5 * (vir[3 * a + b] + vir[3 * b + a] + pvir[3 * a + b] + pvir[3 * b + a]) / V - mvv[3 * a + b] / V;
}

int floe_world_cell_stress(const floe_world *w, double sigma[9], double kinetic[9]) {
    const floe_cell_state *c = w->cell;
    if (!c) return FLOE_EINVAL;
    if (w->par) return FLOE_ENOTSUP; /* MPI: this rank's contacts only (the step's servo sums them) */
    if (!c->valid) return FLOE_EINVAL;
    const double V = det3(c->H);
    double mvv[9] = {0};
    floe_cell_mvv(&w->p, 0, w->p.n, mvv);
    floe_cell_stress_of(c->virial, c->pd_virial, mvv, V, sigma);
    if (kinetic)
        for (int k = 0; k < 9; k++) kinetic[k] = -mvv[k] / V; /* the kinetic part -(1/V) sum m v (x) v */
    return FLOE_OK;
}

int floe_world_tangent_contact(const floe_world *w, double volume, double D[81]) {
    if (w->par) return FLOE_ENOTSUP; /* MPI: this rank's contacts only */
    const floe_contact_info *cs;
    int nc = floe_world_contacts(w, &cs);
    if (nc < 0) return FLOE_EINVAL;
    double V = w->cell ? det3(w->cell->H) : volume;
    if (!(V > 0)) return FLOE_EINVAL;
    memset(D, 0, 81 * sizeof(double));
    const floe_particles *p = &w->p;
    for (int q = 0; q < nc; q++) {
        const floe_contact_info *ci = &cs[q];
        const floe_contact_law *law = w->laws[p->material[ci->i] * w->nmats + p->material[ci->j]];
        if (!law || !law->klass->stiffness) continue;
        double kn = 0, cn = 0, kt = 0, ct = 0;
        law->klass->stiffness(law, ci->r_eff, ci->m_eff, ci->depth, &kn, &cn);
        if (law->klass->tangential_stiffness) law->klass->tangential_stiffness(law, ci->r_eff, ci->m_eff, ci->depth, &kt, &ct);
        const double *n = ci->n, *l = ci->branch;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++)
                    for (int m = 0; m < 3; m++)
                        D[27 * i + 9 * j + 3 * k + m] +=
                            (kn * n[i] * n[k] + kt * ((i == k) - n[i] * n[k])) * l[j] * l[m];
    }
    for (int k = 0; k < 81; k++) D[k] /= V;
    return FLOE_OK;
}

void floe_tangent_to_voigt(const double D[81], double Vo[36]) {
    static const int vi[6] = {0, 1, 2, 1, 0, 0}, vj[6] = {0, 1, 2, 2, 2, 1};
    for (int I = 0; I < 6; I++)
        for (int J = 0; J < 6; J++) {
            int i = vi[I], j = vj[I], k = vi[J], l = vj[J];
#define DD(a, b, c, d) D[27 * (a) + 9 * (b) + 3 * (c) + (d)]
            Vo[6 * I + J] = 0.25 * (DD(i, j, k, l) + DD(j, i, k, l) + DD(i, j, l, k) + DD(j, i, l, k));
#undef DD
        }
}

/* ---- the step ---------------------------------------------------------------------- */

int floe_cell_prepare(floe_world *w) {
    floe_cell_state *c = w->cell;
    w->nl.cell = c;
    if (!c) return FLOE_OK;
    const floe_particles *p = &w->p;
    const floe_world_def *d = &w->def;
    if (d->adaptive || (d->integrator != FLOE_VELOCITY_VERLET && d->integrator != FLOE_LEAPFROG))
        return floe_world_error(w, FLOE_ENOTSUP, "a periodic cell needs velocity Verlet or leapfrog steps of a fixed "
                                "size (not %s)", d->adaptive ? "adaptive steps" : "this integrator");
    if (w->npd && d->pd_dem == FLOE_PD_DEM_STAGGERED)
        return floe_world_error(w, FLOE_ENOTSUP, "a periodic cell does not support the staggered PD-DEM scheme yet");
    double rmax = 0, rmin = INFINITY;
    for (int i = 0; i < p->n; i++) {
        if (!isfinite(p->radius[i]))
            return floe_world_error(w, FLOE_ENOTSUP, "particle %d is a wall: a periodic cell has no walls (its "
                                    "boundaries are periodic in every direction)", i);
        if (p->motion[i] != FLOE_FREE)
            return floe_world_error(w, FLOE_ENOTSUP, "particle %d is %s: every particle of a periodic cell is free "
                                    "(the cell's deformation drives them)", i,
                                    p->motion[i] == FLOE_FIXED ? "fixed" : "kinematic");
        if (p->radius[i] > rmax) rmax = p->radius[i];
        if (p->radius[i] < rmin) rmin = p->radius[i];
    }
    c->rmax = rmax;
    double wmin = min_width(c, d->dim);
    if (wmin < 4 * rmax)
        return floe_world_error(w, FLOE_EINVAL, "the periodic cell is %g m wide, less than two particle diameters "
                                "(the largest particle's bounding diameter is %g m): make the cell larger", wmin,
                                2 * rmax);
    double skin = d->skin > 0 ? d->skin : (isfinite(rmin) ? 0.1 * rmin : 0);
    if (2 * rmax + skin > wmin)
        return floe_world_error(w, FLOE_EINVAL, "the neighbour skin %g m is too large for the periodic cell (%g m "
                                "wide): a particle's reach 2 r_max + skin must stay inside one cell width", skin, wmin);
    return FLOE_OK;
}

/* the servo's rate for component k */
static double servo_rate(const floe_world *w, const floe_cell_state *c, const double sig[9], int k) {
    double V = det3(c->H);
    double K = c->kdiag[k] / V;
    double tau = c->ctl.servo_time > 0 ? c->ctl.servo_time : 50 * w->dt;
    double err = c->ctl.stress[k] - sig[k], mr = c->ctl.max_rate;
    double r = K > 0 ? err / (K * tau) : (err > 0 ? mr : err < 0 ? -mr : 0);
    return r > mr ? mr : r < -mr ? -mr : r;
}

int floe_cell_begin_step(floe_world *w, const double *sigma) {
    floe_cell_state *c = w->cell;
    const double dt = w->dt;
    double L[9];
    int masked = 0;
    for (int k = 0; k < 9; k++) masked |= c->path && c->path_mask[k];
    if (c->path && masked) {
        /* mixed: the strained components at a constant rate, the others by the servo */
        for (int k = 0; k < 9; k++) L[k] = c->path_de[k] / ((double)c->path_n * dt);
    } else if (c->path) {
        /* step k + 1 of the increment: (I + dt L) H = H0 + ((k + 1) / n) dH */
        double T[9];
        double f = (double)(c->path_k + 1) / (double)c->path_n;
        for (int k = 0; k < 9; k++) T[k] = c->path_H0[k] + f * c->path_dH[k];
        mul3(T, c->Hinv, L);
        for (int k = 0; k < 9; k++) L[k] = (L[k] - (k % 4 == 0)) / dt;
    } else {
        memcpy(L, c->ctl.rate, sizeof L);
    }
    int any = 0;
    for (int k = 0; k < 9; k++) any |= c->ctl.mode[k] == FLOE_CELL_STRESS && (!c->path || c->path_mask[k]);
    if (any) {
        double sig[9];
        if (sigma) memcpy(sig, sigma, sizeof sig); /* MPI: the whole cell's, summed over the ranks */
        else if (floe_world_cell_stress(w, sig, NULL) != FLOE_OK) memset(sig, 0, sizeof sig);
        for (int k = 0; k < 9; k++)
            if (c->ctl.mode[k] == FLOE_CELL_STRESS && (!c->path || c->path_mask[k])) L[k] = servo_rate(w, c, sig, k);
    }
    if (w->def.dim == 2) L[2] = L[5] = L[6] = L[7] = L[8] = 0;
    memcpy(c->L, L, sizeof L);
    return FLOE_OK;
}

int floe_cell_after_drift(floe_world *w, double dt) {
    floe_cell_state *c = w->cell;
    double M[9], Hn[9];
    for (int k = 0; k < 9; k++) M[k] = (k % 4 == 0) + dt * c->L[k];
    int masked = 0;
    for (int k = 0; k < 9; k++) masked |= c->path && c->path_mask[k];
    if (c->path && !masked) {
        double f = (double)(c->path_k + 1) / (double)c->path_n;
        for (int k = 0; k < 9; k++) Hn[k] = c->path_H0[k] + f * c->path_dH[k];
        c->path_k++;
    } else {
        mul3(M, c->H, Hn);
        if (c->path) c->path_k++;
    }
    int moved = 0;
    for (int k = 0; k < 9; k++) moved |= c->L[k] != 0;
    if (!moved) return FLOE_OK;
    floe_particles *p = &w->p;
    for (int i = 0; i < p->n; i++) {
        double *x = p->x + 3 * i, d[3], y[3];
        floe_v3_sub(d, x, c->o);
        mv3(M, d, y);
        floe_v3_add(x, c->o, y);
    }
    memcpy(c->H, Hn, sizeof Hn);
    if (inv3(c->H, c->Hinv) != FLOE_OK || !(det3(c->H) > 0))
        return floe_world_error(w, FLOE_EUNSTABLE, "the periodic cell inverted at step %ld (det H = %g)", w->step,
                                det3(c->H));
    double wmin = min_width(c, w->def.dim);
    if (wmin < 4 * c->rmax)
        return floe_world_error(w, FLOE_EUNSTABLE, "the periodic cell became %g m wide at step %ld, t = %g s: less "
                                "than two particle diameters (%g m); stop compressing it (the servo's target, the "
                                "strain rate)", wmin, w->step, w->time, 4 * c->rmax);
    return FLOE_OK;
}

/* the neighbour list is stale when some particle moved, apart from the cell's affine map
 * since the build (A = H Hb^-1 - I), by more than half the skin less what the map can do to
 * a pair within reach (|A| (2 r_max + skin) / 2) */
int floe_nl_needs_rebuild_cell(const floe_neighbor_list *nl, const floe_particles *p) {
    const floe_cell_state *c = nl->cell;
    if (!nl->x_build || nl->n_build != p->n) return 1;
    double Hbi[9], A[9];
    if (inv3(nl->Hb, Hbi) != FLOE_OK) return 1;
    mul3(c->H, Hbi, A);
    double an = 0;
    for (int k = 0; k < 9; k++) {
        A[k] -= (k % 4 == 0);
        an += A[k] * A[k];
    }
    double lim = 0.5 * nl->skin - 0.5 * sqrt(an) * (2 * nl->rmax_b + nl->skin);
    if (lim <= 0) return 1;
    const double lim2 = lim * lim;
    /* blocks of particles without an exit inside (the compiler vectorises them: a rebuild
     * is rare, the pass is every step), the block's verdict after it; the same test for
     * each particle (a NaN displacement fails neither) */
    const double *restrict xs = p->x, *restrict xb = nl->x_build, *restrict rad = p->radius,
                           *restrict rb = nl->r_build;
    const double o0 = c->o[0], o1 = c->o[1], o2 = c->o[2];
    /* MPI: the walls and owned particles (floe_nl_needs_rebuild) */
    const int n = nl->gid ? nl->own_hi : p->n;
    for (int i0 = 0; i0 < n; i0 += 256) {
        const int i1 = i0 + 256 < n ? i0 + 256 : n;
        int out = 0;
        for (int i = i0; i < i1; i++) {
            const double *x = xs + 3 * i, *b = xb + 3 * i;
            const double d0 = b[0] - o0, d1 = b[1] - o1, d2 = b[2] - o2;
            const double e0 = x[0] - b[0] - (A[0] * d0 + A[1] * d1 + A[2] * d2);
            const double e1 = x[1] - b[1] - (A[3] * d0 + A[4] * d1 + A[5] * d2);
            const double e2 = x[2] - b[2] - (A[6] * d0 + A[7] * d1 + A[8] * d2);
            out |= (rad[i] > rb[i]) | (e0 * e0 + e1 * e1 + e2 * e2 > lim2);
        }
        if (out) return 1;
    }
    return 0;
}

/* the path of a strain increment (floe_world_cell_strain, core/integrators/rve.c): checks,
 * then step k of n goes to H0 + (k / n) dF H0 (mask: components left to the servo) */
int floe_cell_path_begin(floe_world *w, const double de[9], double max_rate, const int *stress_mask, long *nsteps) {
    floe_cell_state *c = w->cell;
    if (!c) return floe_world_error(w, FLOE_EINVAL, "strain increment: the world has no periodic cell");
    if (!(max_rate > 0) || !isfinite(max_rate))
        return floe_world_error(w, FLOE_EINVAL, "strain increment: max_rate must be > 0 (1/s), got %g", max_rate);
    double F[9], dmax = 0;
    for (int k = 0; k < 9; k++) {
        int masked = stress_mask && stress_mask[k];
        double e = masked ? 0.0 : de[k];
        if (!isfinite(e)) return floe_world_error(w, FLOE_EINVAL, "strain increment: component (%d, %d) is not finite", k / 3, k % 3);
        if (w->def.dim == 2 && (k / 3 == 2 || k % 3 == 2) && e != 0)
            return floe_world_error(w, FLOE_EINVAL, "strain increment: a 2D cell has no component (%d, %d)", k / 3, k % 3);
        F[k] = (k % 4 == 0) + e;
        if (fabs(e) > dmax) dmax = fabs(e);
    }
    if (!(det3(F) > 0))
        return floe_world_error(w, FLOE_EINVAL, "strain increment: det(I + de) = %g <= 0: the cell would invert", det3(F));
    double Hend[9], Hendi[9];
    mul3(F, c->H, Hend);
    if (inv3(Hend, Hendi) == FLOE_OK) {
        double wd[3];
        widths_of(Hendi, w->def.dim, wd);
        double wm = fmin(wd[0], fmin(wd[1], wd[2]));
        if (wm < 4 * c->rmax)
            return floe_world_error(w, FLOE_EINVAL, "strain increment: the cell would be %g m wide, less than two "
                                    "particle diameters (%g m)", wm, 4 * c->rmax);
    }
    long n = (long)ceil(dmax / (max_rate * w->dt) - 1e-9);
    if (n < 1) n = 1;
    c->path = 1;
    c->path_k = 0;
    c->path_n = n;
    memcpy(c->path_H0, c->H, sizeof c->H);
    for (int k = 0; k < 9; k++) c->path_mask[k] = stress_mask ? stress_mask[k] != 0 : 0;
    double dF[9];
    for (int k = 0; k < 9; k++) c->path_de[k] = dF[k] = F[k] - (k % 4 == 0);
    mul3(dF, c->H, c->path_dH);
    *nsteps = n;
    return FLOE_OK;
}
void floe_cell_path_end(floe_world *w) {
    if (!w->cell) return;
    w->cell->path = 0;
    memset(w->cell->L, 0, sizeof w->cell->L);
}

int floe_world_cell_measures(const floe_world *w, floe_rve_measures *out) {
    memset(out, 0, sizeof *out);
    if (!w->cell) return FLOE_EINVAL;
    FLOE_TRY(floe_world_cell_stress(w, out->sigma, NULL));
    const floe_contact_info *cs;
    int nc = floe_world_contacts(w, &cs);
    if (nc < 0) return FLOE_EINVAL;
    for (int q = 0; q < nc; q++)
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) out->fabric[3 * a + b] += cs[q].n[a] * cs[q].n[b];
    if (nc > 0)
        for (int k = 0; k < 9; k++) out->fabric[k] /= nc;
    const floe_particles *p = &w->p;
    double vs = floe_world_solid_volume(w); /* every particle of a cell is free */
    out->contacts = nc;
    out->particles = p->n;
    out->coordination = p->n ? 2.0 * nc / p->n : 0.0;
    out->volume = det3(w->cell->H);
    out->solid_volume = vs;
    out->porosity = 1.0 - vs / out->volume;
    out->void_ratio = vs > 0 ? (out->volume - vs) / vs : INFINITY;
    return FLOE_OK;
}
