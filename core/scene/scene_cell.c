/* scene_cell.c - the scene's `cell` block: a periodic cell (floe_cell.h, docs/periodic.md)
 * and how it deforms.
 *
 *   cell:
 *     origin: [x, y, z]              # the cell's corner (default 0)
 *     size: [lx, ly, lz]             # edge lengths along the axes (2D: [lx, ly])
 *     tilt: {xy: .., xz: .., yz: ..} # triclinic as LAMMPS: a = (lx, 0, 0), b = (xy, ly, 0),
 *                                    # c = (xz, yz, lz)
 *     strain_rate: {xx: .., xy: ..}  # velocity gradient L_ab = dv_a/dx_b, 1/s (default 0)
 *     stress: {xx: .., yy: ..}       # components held at this stress (Pa, tension positive)
 *     max_strain_rate: ..            # the servo's largest |L_ab| (required with stress)
 *     servo_time: ..                 # the servo's relaxation time, s (default 50 steps)
 * A component may be given a strain rate or a stress, not both. */
#include "scene_read.h"
#include "floe_cell.h"
#include "floe_view.h"

#include <math.h>
#include <string.h>

static const char *const comp_names[] = {"xx", "xy", "xz", "yx", "yy", "yz", "zx", "zy", "zz", NULL};

/* a map of components -> values; set[k] = 1 where given */
static int read_components(sc *s, const sc_map *cm, const char *key, double out[9], int set[9]) {
    memset(set, 0, 9 * sizeof(int));
    struct fy_node *k, *v = sc_get(cm, key, &k);
    if (!v) return FLOE_OK;
    sc_map m;
    char what[64];
    snprintf(what, sizeof what, "cell.%s", key);
    FLOE_TRY(sc_map_open(s, v == k ? NULL : v, k, what, comp_names, &m));
    for (int c = 0; c < 9; c++) {
        if (!sc_has(&m, comp_names[c])) continue;
        if (s->dim == 2 && (c / 3 == 2 || c % 3 == 2))
            return sc_fail(s, FLOE_EINVAL, sc_get(&m, comp_names[c], NULL),
                           "cell.%s.%s: a 2D cell has no z component", key, comp_names[c]);
        FLOE_TRY(sc_num(s, &m, comp_names[c], 1, 0, &out[c]));
        set[c] = 1;
    }
    return FLOE_OK;
}

int sc_parse_cell(sc *s, struct fy_node *v, struct fy_node *key) {
    if (!v && !key) return FLOE_OK;
    static const char *const keys[] = {"origin", "size", "tilt", "strain_rate", "stress", "max_strain_rate",
                                       "servo_time", NULL};
    static const char *const tilt_keys[] = {"xy", "xz", "yz", NULL};
    sc_map cm;
    FLOE_TRY(sc_map_open(s, v, key, "cell", keys, &cm));
    double o[3], size[3];
    FLOE_TRY(sc_vec(s, &cm, "origin", 0, NULL, o));
    FLOE_TRY(sc_vec(s, &cm, "size", 1, NULL, size));
    for (int a = 0; a < s->dim; a++)
        if (!(size[a] > 0)) return sc_range(s, &cm, "size", "> 0 along every axis (m)", size[a]);
    double H[9] = {size[0], 0, 0, 0, size[1], 0, 0, 0, s->dim == 3 ? size[2] : 1};
    struct fy_node *tk, *tv = sc_get(&cm, "tilt", &tk);
    if (tv) {
        sc_map tm;
        FLOE_TRY(sc_map_open(s, tv == tk ? NULL : tv, tk, "cell.tilt", tilt_keys, &tm));
        FLOE_TRY(sc_num(s, &tm, "xy", 0, 0, &H[1]));
        FLOE_TRY(sc_num(s, &tm, "xz", 0, 0, &H[2]));
        FLOE_TRY(sc_num(s, &tm, "yz", 0, 0, &H[5]));
        if (s->dim == 2 && (H[2] != 0 || H[5] != 0))
            return sc_fail(s, FLOE_EINVAL, tk, "cell.tilt: a 2D cell has only xy");
    }
    if (floe_world_set_cell(s->w, o, H) != FLOE_OK)
        return sc_fail(s, FLOE_EINVAL, key, "cell: %s", floe_world_last_error(s->w));
    {
        /* the width check of prepare, here with the line */
        floe_particles_view pv;
        double wd[3], rmax = 0;
        floe_world_particles(s->w, &pv);
        for (int i = 0; i < pv.n; i++)
            if (pv.radius[i] > rmax && pv.radius[i] < INFINITY) rmax = pv.radius[i];
        floe_world_cell_widths(s->w, wd);
        for (int a = 0; a < s->dim; a++)
            if (wd[a] < 4 * rmax)
                return sc_fail(s, FLOE_EINVAL, sc_get(&cm, "size", NULL),
                               "cell: %g m wide across the faces of cell vector %d, less than two particle "
                               "diameters (the largest bounding diameter is %g m): make the cell larger", wd[a], a,
                               2 * rmax);
    }
    floe_cell_control c = floe_default_cell_control();
    int rset[9], sset[9];
    FLOE_TRY(read_components(s, &cm, "strain_rate", c.rate, rset));
    FLOE_TRY(read_components(s, &cm, "stress", c.stress, sset));
    int any = 0;
    for (int k = 0; k < 9; k++) {
        if (rset[k] && sset[k])
            return sc_fail(s, FLOE_EINVAL, sc_get(&cm, "stress", NULL),
                           "cell: component %s has both a strain rate and a stress; give one", comp_names[k]);
        if (sset[k]) { c.mode[k] = FLOE_CELL_STRESS; any = 1; }
    }
    FLOE_TRY(sc_num(s, &cm, "max_strain_rate", any, 0, &c.max_rate));
    if (any && !(c.max_rate > 0)) return sc_range(s, &cm, "max_strain_rate", "> 0 (1/s)", c.max_rate);
    FLOE_TRY(sc_num(s, &cm, "servo_time", 0, 0, &c.servo_time));
    if (!(c.servo_time >= 0)) return sc_range(s, &cm, "servo_time", ">= 0 (s; 0 = 50 steps)", c.servo_time);
    if (floe_world_cell_set_control(s->w, &c) != FLOE_OK)
        return sc_fail(s, FLOE_EINVAL, key, "cell: %s", floe_world_last_error(s->w));
    return FLOE_OK;
}
