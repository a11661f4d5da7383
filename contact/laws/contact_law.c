/* contact_law.c - generic contact-law helpers. */
#include <math.h>
#include <stdlib.h>

#include "floe_contact.h"
#include "law_parts.h"

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

/* Coulomb friction with a shear spring (ParticLS eqs 17-18): law_parts.h floe_coulomb_k */
void floe_contact_coulomb(const floe_contact *c, double ks, double gs, double mu, double Fn, double *s,
                          double Ft[3], double *diss)
{
    floe_coulomb_k(c, ks, gs, mu, Fn, s, Ft, diss);
}
