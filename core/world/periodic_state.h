/* periodic_state.h - the periodic cell's state (floe_cell.h, core/world/cell.c) and the image
 * codes of the neighbour list's pairs (neighbor.c, forces.c). Internal, as world_internal.h. */
#ifndef FLOE_PERIODIC_STATE_H
#define FLOE_PERIODIC_STATE_H

#include "floe_cell.h"
#include "floe_image.h"

/* A periodic cell (floe_cell.h, core/world/cell.c); NULL in a world without one. */
typedef struct floe_cell_state {
    double o[3], H[9], Hinv[9];
    double L[9];             /* velocity gradient of the present step, 1/s */
    floe_cell_control ctl;
    double virial[9];        /* sum over contacts of l (x) F (branch from i to j's image, force
                                on i) at the last force evaluation, N m */
    double pd_virial[9];     /* the same over the PD bonds (bond vector to j's image, force on
                                i), forces.c's pd stage; enters the stress with virial */
    double kdiag[9];         /* servo: sum over contacts of k_n (n_a l_b)^2 (eq 29's D_abab x V) */
    int want_kdiag;          /* a component is stress-controlled: the stage sums kdiag */
    int valid;               /* virial is that of the last evaluation */
    /* a strain increment in progress (floe_world_cell_strain): step k of n goes to
     * H = H0 + (k / n) dH exactly */
    int path; long path_k, path_n; double path_H0[9], path_dH[9], path_de[9]; int path_mask[9];
    double rmax;             /* largest bounding radius (prepare) */
} floe_cell_state;

/* image codes of the pairs (floe_img_encode, floe_img_decode, floe_img_shift): floe_image.h
 * (peridynamics/, whose bonds across the faces carry them too) */

#endif
