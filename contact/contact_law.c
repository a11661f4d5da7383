/* contact_law.c - generic contact-law helpers. */
#include <stdlib.h>

#include "floe_contact.h"

void floe_contact_law_destroy(floe_contact_law *law)
{
    if (!law) return;
    if (law->klass && law->klass->destroy)
        law->klass->destroy(law);
    else
        free(law);
}
