/* floe_beam.h - beam bonds between particles (ParticLS §5.5; 004 §2, eqs 5-11).
 *
 * A bond joins two particles with an elastic beam (Euler-Bernoulli, or Timoshenko with the
 * shear parameter phi of 004 eq 7) that resists stretching, bending and twisting: it puts
 * a force AND a torque on both particles, from their relative displacement and rotation in
 * the bond's own frame. The world integrates the rotation of bonded particles (it already
 * integrates torques). Bonds are made once, at set-up, between particles within a radius;
 * a bond breaks for good when the largest normal or shear stress in the beam (004 eq 11)
 * exceeds its strength, drawn per bond from a seeded normal distribution. While bonded, a
 * pair never gets a contact force; once broken, it meets by the world's contact law.
 *
 * Formulation in the world (explicit, velocity Verlet): co-rotational. The chord e joins
 * the two centres; the end rotations relative to the chord are theta_i = e x t_i, with t_i
 * the bond direction at creation carried by particle i's orientation; the twist is the
 * angle between the two ends' reference normals about e. Local generalised forces
 *
 *     N = (E A / l0)(L - l0),        T = (G J / l0) twist,
 *     M_i = E I / (l0 (1 + phi)) [(4 + phi) theta_i + (2 - phi) theta_j]   (and i <-> j),
 *
 * are the rows of 004 eq 7 written relative to the chord, so that a rigid motion gives no
 * force at any size of rotation; the shear force is (M_i + M_j) / L. The linearisation of
 * this law is exactly the matrix of eq 7 (tests/test_beam.c checks it by finite
 * differences). Stresses for breakage (eq 11): sigma = N/A + max(|M_i|, |M_j|)/W,
 * tau = 3 |M_i + M_j| / (2 A L) + |T| / (2 W).
 *
 * Damping: stiffness-proportional, the same matrix applied to the rates of the local
 * deformation scaled by 2 xi / omega_a (omega_a = sqrt(E A / (l0 m_r))): it damps no rigid
 * motion. (004 eq 8 damps the absolute end velocities instead; the Newmark solver,
 * core/integrators/floe_newmark.h, follows eq 8.)
 *
 * Units are SI. */
#ifndef FLOE_BEAM_H
#define FLOE_BEAM_H

#include <limits.h>

#include "floe_base.h"

/* Cross-section and stiffness of one bond (one beam). */
typedef struct floe_beam_section {
    double l;                /* reference length l0, m */
    double E, G;             /* Young's and shear modulus, Pa */
    double A;                /* area, m^2 */
    double I;                /* second moment of area about either bending axis, m^4 */
    double J;                /* torsion constant, m^4 (3D) */
    double W;                /* section modulus for bending, m^3 (eq 11) */
    double phi;              /* Timoshenko shear parameter 12 E I / (kappa G A l^2); 0 = Euler-Bernoulli */
} floe_beam_section;

/* Local stiffness matrix of a bond, 004 eq 7 (with its (4,4) entry read as A E / l),
 * row-major into K: dim 2: 6 x 6 on (u, v, theta_z) of end i then end j; dim 3: 12 x 12 on
 * (u, v, w, theta_x, theta_y, theta_z) of end i then end j, u along the bond. */
void floe_beam_local_stiffness(const floe_beam_section *s, int dim, double *K);

/* f = K u with the matrix of floe_beam_local_stiffness, from its structure (about a third
 * of the work of the dense product). */
void floe_beam_local_apply(const floe_beam_section *s, int dim, const double *u, double *f);

/* Spectral norms of the 3 x 3 blocks of the local stiffness, the same in every frame:
 * out[0] translation-translation max(EA/l, 12EI/(l^3(1+phi))), out[1] translation-rotation
 * 6EI/(l^2(1+phi)), out[2] rotation-rotation of one end, out[3] between the two ends
 * (torsion GJ/l included in 3D). For block Gershgorin bounds on the highest frequency. */
void floe_beam_block_norms(const floe_beam_section *s, int dim, double out[4]);

/* Stresses of 004 eq 11 from the local end forces f (the layout of
 * floe_beam_local_stiffness): largest normal stress (tension positive) and shear stress. */
void floe_beam_stress(const floe_beam_section *s, int dim, const double *f, double *sigma, double *tau);

/* Standard normal deviates from a seeded generator (splitmix64 + Box-Muller): state is
 * advanced; the same seed gives the same sequence on every platform. */
double floe_beam_normal(unsigned long long *state);

#define FLOE_BEAM_ALL_GROUPS INT_MIN

typedef struct floe_beam_params {
    double young;            /* E, Pa (> 0) */
    double poisson;          /* nu in (-1, 0.5): G = E / (2 (1 + nu)) */
    int timoshenko;          /* 1: phi = 12 E I / (kappa G A l^2) (004 eq 7); 0: Euler-Bernoulli */
    double shear_coefficient; /* kappa of the Timoshenko shear area (0: 5/6) */
    /* cross-section, either given (area > 0) or from the particle radii (area = 0) */
    double area, inertia;    /* A (m^2) and I (m^4), both > 0 when given */
    double polar;            /* J (m^4); 0: 2 I (a circle) */
    double section_modulus;  /* W (m^3); 0: that of a circle of area A, I / sqrt(A / pi) */
    double radius_ratio;     /* lambda (area = 0): 3D a circle of radius lambda min(R_i, R_j);
                                2D a rectangle of height 2 lambda min(R_i, R_j) and width
                                `thickness` (default 1) */
    double thickness;        /* 2D rectangle width (out of plane), m; 0: 1 m */
    double damping_ratio;    /* xi >= 0 of the stiffness-proportional damping (0 = none) */
    /* strengths (004 §5): per bond N(mean, sd), drawn in bond order from `seed`; a mean of 0
     * means no breakage by that stress; draws below 0 are clamped to 0 */
    double tensile_strength, tensile_sd;   /* sigma_lim, Pa */
    double shear_strength, shear_sd;       /* tau_lim, Pa */
    unsigned long long seed;
    double max_distance;     /* > 0: bond pairs whose centres are within this distance (m)
                                instead of radius_factor (ParticLS Fig. 11, fixed radius) */
    int group;               /* bond only particles of this group (FLOE_BEAM_ALL_GROUPS: any) */
    /* compression and the Mohr-Coulomb envelope (sea-ice floes of bonded cells, DEMSI's
     * bonds; docs/sea-ice.md "Bonded floes"): a bond also breaks when its largest
     * compressive fibre stress -N/A + max|M|/W exceeds sigma_c (drawn after the other two,
     * only when its mean is > 0), and its shear limit grows with the axial compression:
     * tau_lim + tan(friction_angle) max(0, -N/A) */
    double compressive_strength, compressive_sd; /* sigma_c, Pa (0: no compressive breakage) */
    double friction_angle;   /* degrees in [0, 90) (0: a shear limit independent of compression) */
    /* FLOE_BEAM_YIELD_ELLIPSE instead of the three limits above: an elliptical envelope in
     * the (normal, shear) stress plane through the tensile strength sigma_t and the
     * compressive strength -sigma_c on the normal axis, with semi-axis tau_s (the shear
     * strength) at its centre, as Hibler's (1979) elliptical yield curve; all three strengths
     * must be > 0 and friction_angle 0. A fibre of normal stress s (either extreme fibre,
     * N/A +- max|M|/W) with the shear stress tau breaks the bond when
     *     ((s - s0) / a)^2 + (tau / tau_s)^2 >= 1,   s0 = (sigma_t - sigma_c)/2,
     *     a = (sigma_t + sigma_c)/2,
     * in the mode whose term is larger (tension or compression by the sign of s - s0; shear). */
    int yield;               /* FLOE_BEAM_YIELD_LIMITS (0, the default) or FLOE_BEAM_YIELD_ELLIPSE */
} floe_beam_params;
#define FLOE_BEAM_YIELD_LIMITS 0
#define FLOE_BEAM_YIELD_ELLIPSE 1

/* E = 0 (must be set), nu = 0.25, Euler-Bernoulli, radius_ratio 1, thickness 1, no damping,
 * unbreakable, seed 1, all groups. */
floe_beam_params floe_default_beam_params(void);

/* One bond as the world reports it (floe_world_beam_bond). */
typedef struct floe_beam_bond_info {
    int i, j;
    int broken;              /* 1 once broken */
    double t_broken;         /* world time of the break, s (-1 if intact) */
    double sigma, tau;       /* stresses of eq 11 at the last force evaluation (0 once broken), Pa */
    double sigma_lim, tau_lim; /* strengths (INFINITY: unbreakable by that stress), Pa */
    floe_beam_section section;
    double sigma_c, sigma_c_lim; /* compressive fibre stress (last evaluation) and its strength, Pa */
    int mode;                /* how it broke: 0 intact, 1 tension, 2 shear (Mohr-Coulomb), 3 compression */
    /* the break (0 while intact): the stress of its mode that passed the strength (sigma,
     * tau or sigma_c) and that strength (in shear with the Mohr-Coulomb term; under the
     * elliptical yield the envelope's value at the other stress), Pa, at the evaluation that
     * broke it (time t_broken); the midpoint of the two centres then, m */
    double stress_broken, strength_broken;
    double x_broken[3];
} floe_beam_bond_info;

#endif
