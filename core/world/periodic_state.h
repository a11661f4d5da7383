/* periodic_state.h - the periodic cell's state (floe_cell.h, core/world/cell.c) and the image
 * codes of the neighbour list's pairs (neighbor.c, forces.c). Internal, as world_internal.h. */
#ifndef FLOE_PERIODIC_STATE_H
#define FLOE_PERIODIC_STATE_H

#include "floe_cell.h"

/* A periodic cell (floe_cell.h, core/world/cell.c); NULL in a world without one. */
typedef struct floe_cell_state {
    double o[3], H[9], Hinv[9];
    double L[9];             /* velocity gradient of the present step, 1/s */
    floe_cell_control ctl;
    double virial[9];        /* sum over contacts of l (x) F (branch from i to j's image, force
                                on i) at the last force evaluation, N m */
    double kdiag[9];         /* servo: sum over contacts of k_n (n_a l_b)^2 (eq 29's D_abab x V) */
    int want_kdiag;          /* a component is stress-controlled: the stage sums kdiag */
    int valid;               /* virial is that of the last evaluation */
    /* a strain increment in progress (floe_world_cell_strain): step k of n goes to
     * H = H0 + (k / n) dH exactly */
    int path; long path_k, path_n; double path_H0[9], path_dH[9], path_de[9]; int path_mask[9];
    double rmax;             /* largest bounding radius (prepare) */
} floe_cell_state;

/* image code of a pair: j's image is x_j + H n, n packed 10 bits per component (0 = none) */
static inline int floe_img_encode(int a, int b, int c) { return (a & 1023) | (b & 1023) << 10 | (c & 1023) << 20; }
static inline void floe_img_decode(int code, int n[3]) {
    n[0] = ((code & 1023) ^ 512) - 512;
    n[1] = (((code >> 10) & 1023) ^ 512) - 512;
    n[2] = (((code >> 20) & 1023) ^ 512) - 512;
}
/* the shift H n of image code `code` */
static inline void floe_img_shift(const double H[9], int code, double s[3]) {
    int n[3];
    floe_img_decode(code, n);
    for (int r = 0; r < 3; r++) s[r] = H[3 * r] * n[0] + H[3 * r + 1] * n[1] + H[3 * r + 2] * n[2];
}

#endif
