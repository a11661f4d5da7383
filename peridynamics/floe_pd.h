/* floe_pd.h - peridynamic (PD) bodies on plain arrays: lattice discretisation of a box or an
 * SDF region, bond families in CSR arrays built once with floe_kdtree, PMB (bond-based) and
 * LPS (state-based) materials behind a small vtable, critical-stretch bond breakage, local
 * damage and stable time-step estimates. Self-contained: no dependence on floe_world; the
 * world integration (hybrid contact particles, self-contact exclusion, scene format) comes
 * later and reads the arrays documented here.
 *
 * Sources (../shared/papers):
 *   000_*  PD-DEM coupling: bond-based eqs 9-12 (c = 18K/(pi delta^4) in 3D), LPS eqs 15-25,
 *          correspondence eqs 26-30, CFL time step eqs 41-42.
 *   003_*  PMB eqs 2-7 (critical stretch s_c = sqrt(10 G_c/(pi c delta^5)), damage eq 7).
 *   001_*  ParticLS section 2.2 / 5.4, linear peridynamic solid eqs 30-35 (Gaussian influence
 *          exp(-|xi|^2/delta^2), eq 33).
 *
 * Units are whatever the caller uses consistently (SI in the tests). Forces returned are
 * forces (N), not force densities: the point force is L_I V_I (000 eq 12 / eq 14).
 *
 * Bond storage: each bond is stored ONCE, in the row of its lower point index (i < j), and
 * visited once per force evaluation; its force is applied to both ends. This halves the
 * memory and the work of the LAMMPS both-ends layout and makes breakage symmetric by
 * construction (one flag per bond, never two copies that could disagree). LPS per-point
 * sums (m_i, theta_i) and the damage are accumulated into both ends in the same pass.
 * Partners in a row are sorted ascending, so floe_pd_bonded() is a binary search.
 *
 * Nothing is allocated unless a body is created; all functions return FLOE_OK or an error
 * code from floe_base.h and never call exit(). */
#ifndef FLOE_PD_H
#define FLOE_PD_H

#include <stddef.h>
#include <stdint.h>

#include "floe_base.h"
#include "floe_image.h"

/* ---- region and lattice ---- */

/* Signed distance of the region (negative inside). */
typedef double (*floe_pd_sdf_fn)(const double X[3], void *user);

/* Lattices (floe_pd_region.lattice). CUBIC (0, the default of a zeroed region): square in
 * 2D, simple cubic in 3D, points at lo + (k + 1/2) dx, V = dx^2 h (2D) or dx^3.
 * HEXAGONAL: 2D triangular (hexagonal close packed in the plane): rows along x of pitch
 * dx, row pitch sqrt(3)/2 dx, x = lo + (i + 1/4 + (j odd)/2) dx, y = lo + (j + 1/2) sqrt(3)/2
 * dx, V = sqrt(3)/2 dx^2 h (6 nearest neighbours at dx). 3D hexagonal close packing (HCP,
 * ABAB stacking of those layers along z, layer pitch sqrt(2/3) dx, B layers shifted by
 * (dx/2, dx/(2 sqrt 3)); A rows at y = lo + (j + 1/3) sqrt(3)/2 dx, B rows at (j + 2/3)),
 * V = dx^3/sqrt(2) (12 nearest neighbours at dx). Both keep the lattice points inside the
 * box [lo, hi] (and with sdf <= 0 when sdf is given); dx is the nearest distance. The
 * hexagonal pitches do not divide a box: those positions are then shifted so that the
 * in-box points are centred in the box (the same points, a symmetric body). */
enum { FLOE_PD_LATTICE_CUBIC = 0, FLOE_PD_LATTICE_HEXAGONAL = 1 };

typedef struct floe_pd_region {
    int dim;                 /* 2 (points in x-y, z = (lo[2] + hi[2])/2) or 3              */
    double dx;               /* lattice spacing (nearest-neighbour distance)               */
    double horizon_factor;   /* m: delta = m dx; <= 0 selects 3                            */
    double thickness;        /* 2D only: V = dx^2 * thickness (cubic); <= 0 selects dx     */
    double lo[3], hi[3];     /* bounding box; cubic lattice points at lo + (k + 1/2) dx     */
    floe_pd_sdf_fn sdf;      /* NULL: the whole box; else keep points with sdf(X) <= 0      */
    void *sdf_user;
    int lattice;             /* FLOE_PD_LATTICE_CUBIC (0, default) or _HEXAGONAL (above)    */
} floe_pd_region;

/* ---- materials ---- */

/* FLOE_PD_USER: a material of its own (a plugin's), its vtable in floe_pd_material.ops */
enum { FLOE_PD_PMB = 1, FLOE_PD_LPS = 2, FLOE_PD_USER = 3 };
enum { FLOE_PD_W_ONE = 0, FLOE_PD_W_GAUSS = 1 };              /* LPS influence function  */
enum { FLOE_PD_PLANE_STRESS = 0, FLOE_PD_PLANE_STRAIN = 1 };  /* 2D PMB and LPS           */

typedef struct floe_pd_material {
    int model;          /* FLOE_PD_PMB, FLOE_PD_LPS or FLOE_PD_USER (ops)                   */
    double rho;         /* mass density                                                     */
    /* Elastic constants. PMB: give K (3D) or E (2D), or c directly; nu is fixed by the
     * model (3D and 2D plane strain: 1/4, 2D plane stress: 1/3). LPS: K and G (the 3D
                         * moduli, also in 2D: plane strain or plane stress of that solid). */
    double K, G, E;
    double c;           /* PMB micromodulus; 0: 3D c = 18K/(pi delta^4) (000 eq 10,
                         * 003 eq 3), 2D plane stress c = 9E/(pi h delta^3),
                         * plane strain c = 48E/(5 pi h delta^3)                             */
    double s_c;         /* critical stretch; 0: from G_c; both 0: bonds never break        */
    double G_c;         /* fracture energy: 3D s_c = sqrt(10 G_c/(pi c delta^5)) (003 eq 5);
                         * 2D s_c = sqrt(4 G_c/(c h delta^4)) (same integral in 2D);
                         * for LPS the PMB c of the same K is used in this formula          */
    int influence;      /* LPS: FLOE_PD_W_ONE or FLOE_PD_W_GAUSS                            */
    int plane;          /* 2D PMB and LPS: FLOE_PD_PLANE_STRESS or FLOE_PD_PLANE_STRAIN     */
    int broken_tension_only; /* PMB: 1 (default via floe_pd_material_pmb): a broken bond
                         * still resists compression (003 eq 2: mu = 1 when s <= 0);
                         * 0: a broken bond carries nothing                                 */
    double alpha;       /* PMB: per-point critical stretch of LAMMPS pair peri/pmb (Parks et
                         * al. 2008): s0_i = s00 - alpha min_j s_ij over i's intact bonds at
                         * the previous evaluation, s00 = s_c; a bond breaks when
                         * s > min(s0_i, s0_j), after its force of that evaluation is applied
                         * (LAMMPS' order). 0 (default): the constant s_c. >= 0             */
    double yield_compression; /* PMB elastic-perfectly-plastic bond (003 eq 6, Fig 2): > 0: a
                         * bond yields when its elastic stretch s - s_p falls below -this
                         * (f = c s_yc, s_yc = -yield_compression) and keeps the plastic
                         * stretch s_p (unloads elastically). 0 (default): elastic          */
    double yield_tension; /* the same in tension (> 0: yield at s - s_p > this); 0: none.
                         * Breakage by s_c is on the total stretch s.                       */
    /* FLOE_PD_USER (docs/extending.md, "A PD material"): the material's vtable, and its own
     * parameters (the others above still count: rho for the masses, K (and G) for the CFL
     * estimate, s_c / G_c for breakage). NULL / unused for PMB and LPS.                    */
    const struct floe_pd_material_ops *ops;
    double param[8];
} floe_pd_material;

/* Convenience constructors (fill a floe_pd_material with defaults). */
floe_pd_material floe_pd_material_pmb(double rho, double K, double s_c);
floe_pd_material floe_pd_material_lps(double rho, double K, double G, double s_c, int influence);

typedef struct floe_pd_body floe_pd_body;

/* Material vtable: forces() adds point forces for current positions x (3n) into f (3n),
 * breaks bonds whose stretch exceeds s_c and returns the elastic energy. */
typedef struct floe_pd_material_ops {
    const char *name;
    int (*init)(floe_pd_body *b);                     /* derived constants, scratch        */
    double (*forces)(floe_pd_body *b, const double *x, double *f);
    double (*bond_micromodulus)(const floe_pd_body *b); /* equivalent PMB c for dt / s_c   */
    /* optional (a user material, FLOE_PD_USER): */
    int (*surface_correction)(floe_pd_body *b);       /* NULL: none (FLOE_ENOTSUP)          */
    /* the bytes of b->mstate (or other state) that a step changes, saved and restored by
     * the world around a rejected adaptive step (floe_provider.h "pd_bonds"); a material
     * whose forces change state must declare it here (NULL: no state) */
    size_t (*state_size)(const floe_pd_body *b);
    void (*save)(const floe_pd_body *b, unsigned char *buf);
    void (*restore)(floe_pd_body *b, const unsigned char *buf);
    void (*release)(floe_pd_body *b);                 /* frees b->mstate (init allocates it) */
} floe_pd_material_ops;

/* The constructor of a registered PD material (floe_registry.h, kind FLOE_KIND_PD_MATERIAL,
 * named by `material: {model: NAME, ...}` of a scene's peridynamics): its parameter struct
 * read by the schema and the scene's dimension; it fills *out (floe_pd_material_pmb, or
 * model FLOE_PD_USER with ops) and returns FLOE_OK, or an error code with a message. */
typedef int (*floe_pd_material_create_fn)(const void *params, int dim, floe_pd_material *out, char *err,
                                          size_t errlen);
/* Registers the built-in PD materials (pmb, lps); floe_register_builtins calls it. */
int floe_register_builtin_pd_materials(char *err, size_t errlen);

/* ---- the body ---- */

struct floe_pd_body {
    int dim, n;                /* dimension, number of points                               */
    double dx, delta, thickness;
    double *X;                 /* 3n reference positions                                    */
    double *V;                 /* n volumes                                                  */
    /* bonds, CSR over the lower index: bonds of i are k in [off[i], off[i+1]) with
     * partner[k] > i, sorted ascending                                                      */
    int64_t *off;              /* n + 1                                                      */
    int64_t nbond;
    int32_t *partner;          /* nbond                                                      */
    double *len;               /* nbond: reference length |xi|                              */
    float *vfac;               /* nbond: partial-volume factor in (0, 1]                    */
    uint8_t *broken;           /* nbond: 1 once broken (never heals)                        */
    float *scorr;              /* nbond: PMB surface-correction factor, NULL when off       */
    /* material */
    floe_pd_material mat;
    const floe_pd_material_ops *ops;
    double c, s_c;             /* derived PMB micromodulus and critical stretch (0: none)   */
    /* LPS per-point state (allocated by init of LPS): weighted volume, dilatation          */
    double *m, *theta;
    double *wbond;             /* LPS Gaussian influence per bond (NULL for w = 1)          */
    double *acorr;             /* LPS per-point factor on alpha_i = 15G/m_i, NULL when off
                                * (the surface correction now keeps alpha in dten: NULL)   */
    double *dten;              /* LPS surface correction, NULL when off (pd_materials.c):
                                * 11n doubles, per point the dilatation tensor A_i in
                                * [0, 6n) (xx yy zz xy xz yz), the diagonal B_i of
                                * alpha_ij = n^T B_i n in [6n, 9n), 2n scratch              */
    int64_t nbroken;           /* bonds broken so far                                       */
    /* PMB with mat.alpha > 0 (pd_materials.c): 2n doubles, s0_i of the previous evaluation
     * in [0, n) (DBL_MAX until the first evaluation) and the one being built in [n, 2n);
     * NULL otherwise                                                                        */
    double *s0;
    /* PMB plastic bonds (yield_compression / yield_tension > 0): nbond plastic stretches
     * s_p (pd_materials.c); NULL otherwise                                                  */
    float *splast;
    /* pre-cracks (pd_crack.c): bonds removed from the families by floe_pd_add_crack, and
     * the bonds found by floe_pd_bonds_across for the holes the scene loader left out
     * (region.remove), with the midpoint of one of them (for its warning)                   */
    int64_t ncut;
    int64_t nbridge;
    double bridge_at[3];
    /* a user material's own state (FLOE_PD_USER: its ops->init allocates, ->release frees) */
    void *mstate;
    /* periodic cell (floe_pd_make_periodic; NULL / unused without one): the image of j per
     * bond (floe_image.h code), so that the reference bond is xi = X_j + H0 n - X_i and the
     * deformed one x_j + H n - x_i with H the present cell (*cellH, the caller's array, read
     * at every evaluation). img stays NULL when no bond crosses the cell's faces.           */
    int32_t *img;
    double cellH0[9];
    const double *cellH;
    /* threads (docs/parallel.md): the PMB and LPS bond loops run on this many threads when
     * it is above one (0, the default of a created body: one); the world sets it before each
     * evaluation from its thread count and loop grain. The results are the same bits for any
     * count. par: their buffers (pd_materials.c), NULL until a threaded evaluation.         */
    int nthreads;
    struct floe_pd_par *par;
    /* a body split over MPI ranks (core/parallel/par_pd.c; NULL: the whole body is here):
     * per point FLOE_PD_OWNED, FLOE_PD_GHOST (here, another rank's) or 0 (not here). The
     * PMB and LPS bond loops (serial then) evaluate the bonds with an owned end whose two ends are
     * here, counts a bond's energy and breakage on the rank that owns its row's point (the
     * end of lower index: each once over the ranks) and keeps s0 of the owned points; the
     * caller keeps the forces of its owned points. Set and owned by the world's split. */
    const uint8_t *split;
    /* LPS on a split body: called between the dilatation pass and the force pass, it gives
     * the ghosts their owners' theta (and q, with the surface correction): a ghost's own
     * sums lack the bonds its rank does not hold. Set with split (NULL otherwise). */
    void (*split_sync)(struct floe_pd_body *b, void *ctx);
    void *split_ctx;
};
enum { FLOE_PD_OWNED = 1, FLOE_PD_GHOST = 2 };

/* The bond vector of bond k = (i, j): d = x_j - x_i, plus the shift H n of j's image when
 * the bond crosses a periodic cell's faces (H = cellH0 for the reference X, *cellH for the
 * present positions). Without images exactly the plain difference. */
static inline void floe_pd_bond_vec(const floe_pd_body *b, const double *x, const double H[9], int i, int j,
                                    int64_t k, double d[3])
{
    const double *xi = x + 3 * (size_t)i, *xj = x + 3 * (size_t)j;
    d[0] = xj[0] - xi[0];
    d[1] = xj[1] - xi[1];
    d[2] = xj[2] - xi[2];
    if (b->img && b->img[k]) {
        double s[3];
        floe_img_shift(H, b->img[k], s);
        d[0] += s[0];
        d[1] += s[1];
        d[2] += s[2];
    }
}
/* the reference bond vector xi of bond k (X_j + H0 n - X_i) */
static inline void floe_pd_ref_vec(const floe_pd_body *b, int i, int j, int64_t k, double d[3])
{
    floe_pd_bond_vec(b, b->X, b->cellH0, i, j, k, d);
}

/* Families through the images of a periodic cell x = o + H s (H row-major, its columns the
 * cell vectors; 2D: H[8] = 1 and no z components): the families are found again in the
 * reference configuration with the images (a point near a face bonds to the points near the
 * opposite face, docs/periodic.md), each bond storing j's image; H becomes cellH0, and Hlive
 * (the caller's present cell, read at every evaluation; may be H itself while it lives)
 * cellH. The material is set again (floe_pd_set_material) and a surface correction in place
 * recomputed. Call before any step (no bond broken yet). FLOE_EINVAL when the cell is not
 * wider than two horizons across every pair of faces (a pair would bond through two images)
 * or when a point lies on itself; FLOE_ENOTSUP for a body with pre-cracks (the crack is not
 * kept: cut it after) or a user material (its forces know no images); FLOE_ENOMEM. */
int floe_pd_make_periodic(floe_pd_body *b, const double o[3], const double H[9], const double *Hlive);

/* Create the lattice points of the region, build the families (|xi| <= delta + 1e-9 dx)
 * with the k-d tree and the partial-volume factors:
 *   beta = 1 for |xi| <= delta - dx/2, (delta + dx/2 - |xi|)/dx above (linear, LAMMPS PERI).
 * Returns FLOE_EINVAL for bad fields, FLOE_ENOMEM, or FLOE_OK with *out set. */
int floe_pd_body_create(floe_pd_body **out, const floe_pd_region *r);

/* Same from explicit points (n points X[3n], volumes V[n], horizon delta, spacing dx used
 * by the partial-volume factor; dx <= 0: no partial-volume correction). */
int floe_pd_body_create_points(floe_pd_body **out, int dim, int n, const double *X,
                               const double *V, double delta, double dx, double thickness);

void floe_pd_body_destroy(floe_pd_body *b);

/* Set the material (computes c, s_c, LPS weighted volumes). FLOE_EINVAL for bad values.
 * Drops a surface correction. */
int floe_pd_set_material(floe_pd_body *b, const floe_pd_material *m);

/* PMB surface correction, energy method (Madenci & Oterkus 2014, ch. 4.2): for each
 * direction d the strain energy density of point i under the uniform uniaxial strain
 * u = eps X_d e_d, W_i^d = 1/4 c sum_j (eps n_d^2)^2 |xi| beta V_j, is compared with the
 * continuum value W_inf = c pi delta^4 eps^2/20 (3D; 2D c pi h delta^3 eps^2/16), giving
 * g_i^d = W_inf/W_i^d; a bond gets G^d = (g_i^d + g_j^d)/2 and the factor
 * [sum_d (n_d/G^d)^2]^(-1/2) (ellipsoidal interpolation). Interior points of a lattice get
 * about 1 (the discretisation error of the lattice sum is corrected too).
 * LPS (3D and 2D): see floe_pd_lps_surface_correction below.
 * Call after set_material (which drops the correction). */
int floe_pd_surface_correction(floe_pd_body *b);

/* The LPS branch of floe_pd_surface_correction (pd_materials.c), 3D and 2D (docs/models.md,
 * "LPS surface correction"):
 * 1. Dilatation, position-aware (after Mitchell, Silling & Littlewood 2015): theta_i =
 *    sum_j omega_ij |xi| e beta V_j with omega_ij = w n^T A_i n, where the symmetric tensor
 *    A_i solves C_i : A_i = I, C_i = sum_j w |xi|^2 beta V_j n n n n (the family's fourth
 *    moment). Then theta_i = tr(H) exactly for EVERY uniform small strain H at every point
 *    (the plain 3/m_i sum is exact only for an isotropic expansion: at a free surface it
 *    turns the lateral contraction of a bar into spurious dilatation, and K theta^2/2 makes
 *    the bar 7-9 % too stiff at nu = 0.3-0.45). In a full cubic-lattice family
 *    A_i = dim/m_i I, the plain form. A point whose family does not span the space keeps it.
 * 2. Deviatoric: alpha_ij = n^T B_i n, B_i diagonal, fitted per point (a dim x dim solve)
 *    so that the uniform uniaxial strain along EACH axis gives the continuum deviatoric
 *    energy G (1 - 1/dim) eps^2 (with the new dilatation); a scalar alpha_i (the mean over
 *    the axes, the previous calibration) where that has no positive solution. In a full
 *    cubic-lattice family B_i is a multiple of I (C11, C12 exact; C44 keeps the lattice
 *    error). Averaging one scalar alpha over the axes instead leaves a bar 5-6 % too stiff.
 * The force state follows from W_i = k theta_i^2/2 + 1/2 sum_j alpha_ij w (e^d)^2 beta V_j
 * (forces = -grad E exactly, broken bonds included):
 *    t_ij = (k theta_i - q_i/dim) omega_ij |xi| + alpha_ij w e^d_ij,
 *    q_i = sum_j alpha_ij w |xi| e^d_ij beta V_j (0 for the plain form with an intact family);
 * k = K in 3D, K + G/3 (plane strain), 9KG/(3K + 4G) (plane stress). */
int floe_pd_lps_surface_correction(floe_pd_body *b);

/* Internal forces (000 eq 12 for PMB, eq 14 for LPS) for current positions x (3n), ADDED
 * to f (3n); breaks bonds whose stretch exceeds s_c (irreversibly); returns the elastic
 * energy (PMB: sum over bonds of 1/2 c s^2 |xi| beta V_i V_j; LPS: sum_i W_i V_i with
 * W_i = K theta_i^2/2 + alpha_i/2 sum_j w (e^d)^2 beta V_j, 000 eq 24). */
double floe_pd_forces(floe_pd_body *b, const double *x, double *f);

/* Same without breaking bonds (for line searches, finite differences, solvers). */
double floe_pd_forces_nobreak(floe_pd_body *b, const double *x, double *f);

/* Visit every intact bond k = (i, j), i < j, with the force on i exerted through the bond
 * (fij, N; the force on j is -fij) for current positions x, without breaking bonds: PMB
 * c s beta V_i V_j M, LPS (t_ij + t_ji) beta V_i V_j M (a fresh dilatation pass). For
 * stress fluxes and observers. FLOE_ENOMEM never (LPS uses the body's theta array). */
typedef void (*floe_pd_bond_visit_fn)(int i, int j, int64_t k, const double fij[3], void *user);
/* (FLOE_ENOTSUP for a user material. A body split over MPI ranks: the bonds whose row point,
 * the end of lower index, this rank owns: each bond once over the ranks; LPS's dilatation pass
 * exchanges with the other ranks, so every rank calls it for the body) */
int floe_pd_bond_forces(floe_pd_body *b, const double *x, floe_pd_bond_visit_fn fn, void *user);

/* Local damage phi_i = 1 - sum_j mu beta V_j / sum_j beta V_j (003 eq 7) into phi[n].
 * FLOE_ENOMEM when its n-double scratch cannot be allocated. */
int floe_pd_damage(const floe_pd_body *b, double *phi);

/* Number of bonds of each point (both ends counted) into cnt[n]. */
void floe_pd_family_sizes(const floe_pd_body *b, int *cnt);

/* 1 when i and j are bonded in the reference configuration (broken or not), else 0. */
int floe_pd_bonded(const floe_pd_body *b, int i, int j);
/* Index k of the bond (i, j) in the CSR arrays (broken or not), or -1 when the two points
 * are not bonded in the reference configuration. */
int64_t floe_pd_bond_index(const floe_pd_body *b, int i, int j);

/* Correspondence output (000 eqs 26-30, peridynamics/pd_correspondence.c) for current
 * positions x (3n): per point the non-local deformation gradient F (9, row-major), the
 * Green-Lagrange strain E (9), the Cauchy stress sigma (9) of the compressible Neo-Hookean
 * material with shear modulus G and Lame lambda (eq 29), and the von Mises stress (1). Any
 * output may be NULL. Points whose intact bonds do not span the space get F = 1 and zero
 * stress; their number goes to *singular (may be NULL). */
int floe_pd_correspondence(const floe_pd_body *b, const double *x, double G, double lambda, double *F, double *E,
                           double *sigma, double *von_mises, int *singular);

/* ---- pre-cracks (pd_crack.c) ----
 * A crack is a line (2D) or a planar patch (3D) in the reference configuration that cuts
 * every bond crossing it at set-up: bond (i, j) is cut when the segment X_i X_j meets the
 * crack. A point exactly on the crack counts as lying on its positive side (2D: the left
 * of each segment a -> b, cross(b - a, X - a) >= 0; 3D: the side the polygon's normal
 * points to, counter-clockwise vertices seen from there), so a crack through a row of
 * points cuts the bonds of that row with the other side only. A cut bond is REMOVED from
 * the family (the bond filters of Peridigm): it carries no force (not even in compression),
 * does not count in the LPS weighted volume m_i nor in the damage phi_i (a point next to
 * the crack starts with phi = 0; the faces are free surfaces for the surface correction),
 * and its two points meet by contact like any unbonded pair of the body (floe_world_add_pd_body:
 * except a pair whose contact spheres overlap in the reference configuration). */
#define FLOE_PD_CRACK_MAX_POINTS 16
typedef struct floe_pd_crack {
    int n;                 /* 2D: 2.. points of a polyline (z ignored); 3D: 3.. vertices of a
                            * planar convex polygon, in order around it                      */
    double p[FLOE_PD_CRACK_MAX_POINTS][3];
} floe_pd_crack;

/* A segment a-b; a rectangle corner, corner + e1, corner + e1 + e2, corner + e2 (3D). */
floe_pd_crack floe_pd_crack_segment(const double a[3], const double b[3]);
floe_pd_crack floe_pd_crack_rectangle(const double corner[3], const double e1[3], const double e2[3]);

/* FLOE_OK when c is a valid crack in dimension dim (2D: 2..MAX finite points, consecutive
 * ones distinct; 3D: 3..MAX finite points of a convex planar polygon of non-zero area, the
 * vertices within 1e-9 of its size from its plane), else FLOE_EINVAL. */
int floe_pd_crack_check(const floe_pd_crack *c, int dim);

/* 1 when the crack cuts the bond between the reference points xi and xj, else 0 (c must
 * have passed floe_pd_crack_check). */
int floe_pd_crack_cuts(const floe_pd_crack *c, int dim, const double xi[3], const double xj[3]);

/* Remove every bond of b that the crack cuts from the families (see above). Call it before
 * the body goes into a world; it may come before or after floe_pd_set_material (the
 * material state is rebuilt, a surface correction in place is recomputed, bonds broken so
 * far stay broken). Returns the number of bonds removed (>= 0, also added to b->ncut), or
 * -FLOE_EINVAL for an invalid crack, -FLOE_ENOMEM. */
int64_t floe_pd_add_crack(floe_pd_body *b, const floe_pd_crack *c);

/* Bonds of b that bridge a hole left out of its lattice (sdf < 0 inside the hole, e.g.
 * region.remove of a scene): bonds whose segment enters the hole and leaves it through a
 * facing side (the hole's outward normals at entry and exit more than 120 degrees apart,
 * so chords that clip a hole wider than the horizon do not count). Such bonds mean the
 * hole is narrower than the horizon there and does not separate the material on its two
 * sides: a one-row notch is no notch. Cut them with floe_pd_add_crack. Returns the number
 * (>= 0) and the midpoint of one of them in at (may be NULL), or -FLOE_EINVAL,
 * -FLOE_ENOMEM. */
int64_t floe_pd_bonds_across(const floe_pd_body *b, floe_pd_sdf_fn sdf, void *user, double at[3]);

/* Stable time step estimates:
 *   nodal (Silling & Askari 2005): min_i sqrt(2 rho / sum_j beta V_j c/|xi|);
 *   CFL (000 eqs 41-42): dx / sqrt(K/rho) (LPS: sqrt((K + 4G/3)/rho), the P-wave speed). */
double floe_pd_dt_nodal(const floe_pd_body *b);
double floe_pd_dt_cfl(const floe_pd_body *b);

/* Bytes of bond storage per bond (partner + length + factor + flag). */
size_t floe_pd_bytes_per_bond(void);
/* Total bytes held by the body. */
size_t floe_pd_body_bytes(const floe_pd_body *b);

extern const floe_pd_material_ops floe_pd_pmb_ops;
extern const floe_pd_material_ops floe_pd_lps_ops;

#endif
