/* sheared_cell.h - the periodic cell of test_sphere_path (part 3) and tests/mpi/test_mpi_cell:
 * a cubic lattice of n^3 sites at spacing sp in a cell that tiles it, tilted by 0.1 of its
 * side in xy, sheared at 2 /s (xy) while the stress servo holds the diagonal at -5 Pa (at most
 * 10 /s: unclamped once contacts form, so the servo's stiffness sums steer it). */
#ifndef SHEARED_CELL_H
#define SHEARED_CELL_H
#include "floe.h"

/* the cell and its control on w (before its particles) */
static inline void sheared_cell_set(floe_world *w, int n, double sp) {
    const double L = n * sp, H[9] = {L, 0.1 * L, 0, 0, L, 0, 0, 0, L}, o[3] = {0, 0, 0};
    floe_world_set_cell(w, o, H);
    floe_cell_control c = floe_default_cell_control();
    for (int a = 0; a < 3; a++) {
        c.mode[4 * a] = FLOE_CELL_STRESS;
        c.stress[4 * a] = -5.0;
    }
    c.rate[1] = 2.0;
    c.max_rate = 10.0;
    floe_world_cell_set_control(w, &c);
}

/* lattice site k of n^3, sheared with the cell */
static inline void sheared_cell_site(int k, int n, double sp, double x[3]) {
    const int a = k % n, b = (k / n) % n, c = k / (n * n);
    floe_v3_set(x, (a + 0.5) * sp + 0.1 * (b + 0.5) * sp, (b + 0.5) * sp, (c + 0.5) * sp);
}
#endif
