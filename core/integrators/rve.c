/* rve.c - driving a periodic cell as a representative volume element (floe_cell.h,
 * docs/periodic.md): strain increments and the perturbation tangent. They step the world, so
 * they sit in the driver's layer above the cell (core/world/cell.c). */
#include "world_internal.h"
#include "floe_checkpoint.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int floe_world_cell_strain(floe_world *w, const double de[9], double max_rate, const int *stress_mask, long *steps) {
    if (steps) *steps = 0;
    if (!w->cell) return floe_world_error(w, FLOE_EINVAL, "strain increment: the world has no periodic cell");
    if (!w->prepared) FLOE_TRY(floe_world_prepare(w));
    long n = 0;
    FLOE_TRY(floe_cell_path_begin(w, de, max_rate, stress_mask, &n));
    int rc = FLOE_OK;
    for (long s = 0; s < n && rc == FLOE_OK; s++) {
        rc = floe_world_step(w);
        if (rc == FLOE_OK && steps) (*steps)++;
    }
    floe_cell_path_end(w);
    return rc;
}

/* Voigt index of (i, j): 11 22 33 23 13 12 */
static int voigt_of(int i, int j) {
    static const int v[3][3] = {{0, 5, 4}, {5, 1, 3}, {4, 3, 2}};
    return v[i][j];
}

int floe_world_tangent_perturb(floe_world *w, double strain, double max_rate, long relax_steps, double D[81],
                               double Dv[36], long *steps) {
    if (steps) *steps = 0;
    if (!w->cell) return floe_world_error(w, FLOE_EINVAL, "perturbation tangent: the world has no periodic cell");
    if (!(strain > 0) || !(strain < 0.1) || !(max_rate > 0) || relax_steps < 0)
        return floe_world_error(w, FLOE_EINVAL, "perturbation tangent: strain in (0, 0.1), max_rate > 0 and relax_steps "
                                ">= 0 (got %g, %g, %ld)", strain, max_rate, relax_steps);
    if (!w->prepared) FLOE_TRY(floe_world_prepare(w));
    char err[512] = "";
    const size_t size = floe_world_state_size(w);
    unsigned char *buf = malloc(size ? size : 1);
    if (!buf) return floe_world_error(w, FLOE_ENOMEM, "out of memory");
    int rc = floe_world_state_save(w, buf, size, err, sizeof err);
    if (rc) {
        free(buf);
        return floe_world_error(w, rc, "perturbation tangent: saving the state: %s", err);
    }
    /* the contact records of the present state, put back with it */
    const int nrec = w->ncontacts, valid_rec = w->contacts_valid;
    floe_contact_rec *recs = NULL;
    if (valid_rec && nrec > 0) {
        recs = malloc((size_t)nrec * sizeof *recs);
        if (!recs) {
            free(buf);
            return floe_world_error(w, FLOE_ENOMEM, "out of memory");
        }
        memcpy(recs, w->contacts, (size_t)nrec * sizeof *recs);
    }
    floe_cell_control keep, fixed = floe_default_cell_control();
    floe_world_cell_get_control(w, &keep);
    const int keep_rec = w->record_contacts;
    w->obs_muted = 1;
    const int dim = w->def.dim, nv = dim == 3 ? 6 : 3;
    static const int comp3[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
    static const int comp2[3][2] = {{0, 0}, {1, 1}, {0, 1}};
    double s[9], V[36] = {0};
    double s0[2][9];
    long n0[2] = {-1, -1}; /* the reference (unstrained) stress after n + relax steps, per n */
    long taken = 0;
    /* each probe from the saved state, against the unstrained state run for as many steps */
    for (int J = 0; J < nv && rc == FLOE_OK; J++) {
        const int a = dim == 3 ? comp3[J][0] : comp2[J][0], b = dim == 3 ? comp3[J][1] : comp2[J][1];
        double de[9] = {0};
        /* engineering shear: gamma = 2 eps_ab = strain */
        if (a == b) de[4 * a] = strain;
        else de[3 * a + b] = de[3 * b + a] = 0.5 * strain;
        const double dmax = a == b ? strain : 0.5 * strain;
        long n = (long)ceil(dmax / (max_rate * w->dt) - 1e-9);
        if (n < 1) n = 1;
        int slot = n0[0] == n ? 0 : n0[1] == n ? 1 : -1;
        if (slot < 0) {
            slot = n0[0] < 0 ? 0 : 1;
            rc = floe_world_state_restore(w, buf, size, err, sizeof err);
            if (rc) break;
            floe_world_cell_set_control(w, &fixed);
            for (long k = 0; k < n + relax_steps && rc == FLOE_OK; k++, taken++) rc = floe_world_step(w);
            if (rc == FLOE_OK) rc = floe_world_cell_stress(w, s0[slot], NULL);
            n0[slot] = n;
        }
        if (rc == FLOE_OK) rc = floe_world_state_restore(w, buf, size, err, sizeof err);
        if (rc) break;
        floe_world_cell_set_control(w, &fixed);
        long nn = 0;
        rc = floe_world_cell_strain(w, de, max_rate, NULL, &nn);
        taken += nn;
        for (long k = 0; k < relax_steps && rc == FLOE_OK; k++, taken++) rc = floe_world_step(w);
        if (rc == FLOE_OK) rc = floe_world_cell_stress(w, s, NULL);
        if (rc == FLOE_OK) {
            const int Jv = voigt_of(a, b);
            for (int i = 0; i < 3; i++)
                for (int j = i; j < 3; j++) V[6 * voigt_of(i, j) + Jv] = (s[3 * i + j] - s0[slot][3 * i + j]) / strain;
        }
    }
    /* the saved state back, whatever happened */
    int rr = floe_world_state_restore(w, buf, size, err, sizeof err);
    free(buf);
    if (rr == FLOE_OK && recs && w->contacts_cap >= nrec) memcpy(w->contacts, recs, (size_t)nrec * sizeof *recs);
    if (rr == FLOE_OK) {
        w->ncontacts = nrec;
        w->contacts_valid = valid_rec && (!recs || w->contacts_cap >= nrec);
    }
    free(recs);
    w->obs_muted = 0;
    w->record_contacts = keep_rec;
    floe_world_cell_set_control(w, &keep);
    if (steps) *steps = taken;
    if (rc) return rc;
    if (rr) return floe_world_error(w, rr, "perturbation tangent: restoring the state: %s", err);
    if (Dv) memcpy(Dv, V, sizeof V);
    if (D)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++)
                    for (int l = 0; l < 3; l++) D[27 * i + 9 * j + 3 * k + l] = V[6 * voigt_of(i, j) + voigt_of(k, l)];
    return FLOE_OK;
}
