/* contact_law.c - generic contact-law helpers. */
#include <math.h>
#include <stdlib.h>

#include "floe_contact.h"

floe_law_info floe_contact_law_info(const floe_contact_law *law)
{
    floe_law_info info = {0};
    info.restitution = NAN;
    if (law && law->klass && law->klass->info) law->klass->info(law, &info);
    return info;
}

void floe_contact_law_destroy(floe_contact_law *law)
{
    if (!law) return;
    if (law->klass && law->klass->destroy)
        law->klass->destroy(law);
    else
        free(law);
}

/* Coulomb friction with a shear spring (ParticLS eqs 17-18): see floe_contact.h and the
 * linear law's header comment (linear_law.c) for the steps and the energy bookkeeping. */
void floe_contact_coulomb(const floe_contact *c, double ks, double gs, double mu, double Fn, double *s,
                          double Ft[3], double *diss)
{
    const double dt = c->dt;
    floe_contact_rotate_history(s, c->n);
    floe_v3_axpy(s, dt, c->vt);
    floe_v3_set(Ft, 0.0, 0.0, 0.0);
    floe_v3_axpy(Ft, -ks, s);
    floe_v3_axpy(Ft, -gs, c->vt);
    const double vt2 = floe_v3_dot(c->vt, c->vt), limit = mu * fabs(Fn), ft2 = floe_v3_dot(Ft, Ft);
    if (ft2 > limit * limit) {
        const double ratio = limit / sqrt(ft2);
        floe_v3_scale(Ft, ratio);
        if (ks > 0.0) {
            const double e_before = 0.5 * ks * floe_v3_dot(s, s), minus_inv_ks = -1.0 / ks;
            for (int k = 0; k < 3; ++k) s[k] = (Ft[k] + gs * c->vt[k]) * minus_inv_ks;
            *diss += gs * vt2 * dt + (e_before - 0.5 * ks * floe_v3_dot(s, s));
        } else {
            floe_v3_set(s, 0.0, 0.0, 0.0);
            *diss += ratio * gs * vt2 * dt;
        }
    } else {
        *diss += gs * vt2 * dt;
    }
}
