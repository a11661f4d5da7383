/* floe_cell.h - periodic cells (issue #13; docs/periodic.md): a deformable parallelepiped
 * (2D: parallelogram) repeated in every direction of the world, as Yade's Cell or LAMMPS'
 * triclinic box with fix deform.
 *
 * The cell is x = o + H s, s in [0, 1)^d: H's COLUMNS are the cell vectors (row-major storage,
 * H[3 r + c]). Particles are never wrapped back into the cell: positions stay continuous (so
 * bonds and PD families need no minimum image) and every contact pair carries the image of
 * its second particle, x_j + H n with n integer. Outputs may show positions wrapped
 * (floe_world_cell_wrap).
 *
 * Homogeneous deformation: the cell follows dH/dt = L H with the velocity gradient L; every
 * step the particles are carried by the same affine map as the cell, x <- o + M (x - o) with
 * M = I + dt L (so a lattice stays exactly affine), and their velocities are the FLUCTUATION
 * about the mean field L (x - o): the contact laws see the full relative velocity (fluctuation
 * + L times the branch vector), the integrators and the kinetic energy only the fluctuation
 * (m dv/dt = F: the SLLOD term -L v is left out, as in Yade's periodic cell; quasi-static
 * deformation, |L v| << |F|/m). The work the cell does on the contacts, sum over contacts of
 * F . (L l) dt, is booked in energy.work_boundary, so the energy balance closes.
 *
 * Control, per component (a, b) of L: the strain rate L_ab given, or the stress sigma_ab held
 * at a target by a servo, L_ab = (sigma*_ab - sigma_ab) / (D_abab tau), clamped to
 * max_rate, with D the contact-stiffness tangent (ParticLS eq 29) and tau the servo's time.
 *
 * Homogenised stress (Love-Weber with the image branch vectors, tension positive):
 *   sigma = (1/V) [ sum_c l_c (x) F_c  -  sum_i m_i v_i (x) v_i ],  V = det H (2D: area x 1 m)
 * with l_c = x_j + H n - x_i and F_c the force on i. Not allowed with a cell (refused at
 * prepare): walls, fixed or kinematic particles, the adaptive, RK2 and Newmark integrators,
 * the staggered PD scheme. */
#ifndef FLOE_CELL_H
#define FLOE_CELL_H

#include "floe_world.h"

/* Make the world periodic with the cell origin + H s (H: cell vectors as columns; in 2D the
 * third row and column are ignored and H[8] is 1). Before the first prepare, or later to
 * replace the cell (the neighbour list is rebuilt). FLOE_EINVAL for det H <= 0 or not
 * finite. The cell must stay wider than two of its largest particle diameters in every
 * direction: checked at prepare and at every step (a step that makes it narrower fails with
 * FLOE_EUNSTABLE and says so). PD bodies already in the world get their families through
 * the images (floe_pd_make_periodic); when one cannot (a narrow cell, pre-cracks, a user
 * material: FLOE_EINVAL / FLOE_ENOTSUP with a message), the bodies before it have been
 * converted and the world keeps the new cell: destroy it rather than step it. */
int floe_world_set_cell(floe_world *w, const double origin[3], const double H[9]);
/* 1 when the world is periodic, filling origin and H (either may be NULL); 0 otherwise */
int floe_world_cell(const floe_world *w, double origin[3], double H[9]);
/* The cell's volume det H (2D: area x 1 m); 0 without a cell. */
double floe_world_cell_volume(const floe_world *w);
/* The width of the cell across each pair of faces (the distance between opposite faces) */
int floe_world_cell_widths(const floe_world *w, double width[3]);
/* Wrap a point into the cell (s in [0, 1)^d); with image (may be NULL), the integer image n
 * of the point as well: x = out + H n (the `vtk` output writes both in a cell). */
int floe_world_cell_wrap(const floe_world *w, const double x[3], double out[3]);
int floe_world_cell_wrap_image(const floe_world *w, const double x[3], double out[3], int image[3]);

/* How the cell deforms (floe_world_cell_control): per component (a, b) of the velocity
 * gradient, mode[3 a + b] = FLOE_CELL_RATE (L_ab = rate[3 a + b], 1/s) or FLOE_CELL_STRESS
 * (sigma_ab held at stress[3 a + b], Pa, tension positive, by the servo). A stress-controlled
 * off-diagonal component moves L_ab alone (L_ba keeps its rate). */
enum { FLOE_CELL_RATE = 0, FLOE_CELL_STRESS = 1 };
typedef struct floe_cell_control {
    int mode[9];
    double rate[9];          /* 1/s */
    double stress[9];        /* Pa */
    double max_rate;         /* the servo's |L_ab| at most, 1/s (> 0 when any component is
                                stress-controlled) */
    double servo_time;       /* tau, s; 0 = 50 time steps */
} floe_cell_control;
floe_cell_control floe_default_cell_control(void); /* every rate 0: a fixed cell */
/* Set the control (FLOE_EINVAL without a cell, for a mode out of range, non-finite values,
 * max_rate <= 0 with a stress-controlled component, or a 2D world with a z component not a
 * zero rate). Takes effect at the next step. */
int floe_world_cell_set_control(floe_world *w, const floe_cell_control *c);
int floe_world_cell_get_control(const floe_world *w, floe_cell_control *c);
/* The velocity gradient L of the last step (1/s) */
int floe_world_cell_velocity_gradient(const floe_world *w, double L[9]);

/* Homogenised stress of the cell at the last force evaluation (the formula above, Pa;
 * sigma[3 a + b], symmetric part); kinetic: the kinetic part alone (may be NULL). FLOE_EINVAL
 * without a cell or before prepare. FLOE_ENOTSUP on a world split over MPI ranks (each holds
 * its own contacts: the step's servo sums them over the ranks; the `stress` output, through
 * rank 0's mirror, has the whole cell's); so do floe_world_refresh_forces,
 * floe_world_tangent_contact and floe_world_cell_measures. */
int floe_world_cell_stress(const floe_world *w, double sigma[9], double kinetic[9]);

/* Evaluate the forces again at the present state, advancing nothing (no history, no
 * ledger), with the contacts recorded: the stress, measures and eq 29 tangent below then
 * describe the present state (e.g. right after loading a scene, before any step).
 * FLOE_EINVAL before prepare. Works with or without a cell. */
int floe_world_refresh_forces(floe_world *w);

/* The contact-stiffness tangent of ParticLS eq 29 over the contacts of the last force
 * evaluation (recorded: floe_world_record_contacts), as a 4th-order tensor D[27 i + 9 j +
 * 3 k + l] (Pa):
 *   D_ijkl = (1/V) sum_c [ k_n n_i l_j n_k l_l + k_t (delta_ik - n_i n_k) l_j l_l ]
 * k_n, k_t the laws' linearised normal and tangential stiffness at the contact's overlap
 * (floe_contact_law_class.stiffness, tangential_stiffness; 0 when the law has none), n the
 * normal, l the branch vector from i to j's image. Works with or without a cell (V: the
 * cell's volume, else `volume`, which must then be > 0). FLOE_EINVAL when contacts were not
 * recorded at the last evaluation. */
int floe_world_tangent_contact(const floe_world *w, double volume, double D[81]);
/* 4th-order (ijkl) to Voigt 6x6 (11, 22, 33, 23, 13, 12), minor symmetries averaged:
 * V[6 I + J] = (D_ijkl + D_jikl + D_ijlk + D_jilk) / 4 */
void floe_tangent_to_voigt(const double D[81], double V[36]);

/* What an RVE reports (floe_world_cell_measures), at the last force evaluation:
 *   sigma         the cell's stress (floe_world_cell_stress, Pa)
 *   fabric        F = (1/Nc) sum_c n_c (x) n_c over the contacts (trace 1)
 *   coordination  Z = 2 Nc / N (N: the particles)
 *   solid_volume  sum of the particles' shape volumes (2D: areas x 1 m)
 *   porosity      1 - solid_volume / volume; void_ratio (volume - solid) / solid */
typedef struct floe_rve_measures {
    double sigma[9], fabric[9];
    double coordination, porosity, void_ratio;
    double volume, solid_volume;
    int contacts, particles;
} floe_rve_measures;
/* FLOE_EINVAL without a cell, before prepare, or when contacts were not recorded
 * (floe_world_record_contacts) */
int floe_world_cell_measures(const floe_world *w, floe_rve_measures *out);

/* Apply the strain increment de (de[3 a + b]: the displacement gradient, so the cell goes
 * from H to (I + de) H, exactly, through linear steps of H) over the number of steps that
 * keeps every |L_ab| <= max_rate (1/s), at least one; components marked in stress_mask
 * (may be NULL) stay under the stress servo of the control instead (their de ignored). The
 * steps taken go to *steps (may be NULL). Refused with FLOE_EINVAL before anything moves when
 * det(I + de) <= 0 (the cell would invert) or the end cell would be narrower than two of the
 * largest particle diameters. The control in place before the call is restored after it. */
int floe_world_cell_strain(floe_world *w, const double de[9], double max_rate, const int *stress_mask,
                           long *steps);

/* The perturbation tangent (finite strain probes from a saved state, the state restored
 * after): from the present state (saved in memory, floe_world_state_save), for each
 * independent component (3D: xx yy zz yz xz xy; 2D: xx yy xy) apply the strain `strain`
 * (shear: engineering, gamma = strain) by floe_world_cell_strain at max_rate with the cell
 * otherwise fixed, then relax_steps steps with the cell fixed; the column is (sigma - sigma0) /
 * strain with sigma0 the unstrained state after as many relaxation steps. Fills D (ijkl, may be
 * NULL) and Dv (Voigt 6x6, may be NULL) in Pa; *steps (may be NULL) the steps taken in all.
 * Observers are not called during the probes. The world's state and control are put back,
 * also on failure. relax_steps = 0 and one step per probe give the instantaneous
 * (affine + contact history) response; relaxation lets the packing rearrange (a softer
 * tangent). FLOE_EINVAL without a cell, for strain not in (0, 0.1), max_rate <= 0. */
int floe_world_tangent_perturb(floe_world *w, double strain, double max_rate, long relax_steps, double D[81],
                               double Dv[36], long *steps);

#endif
