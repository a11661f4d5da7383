/* floe_contact.h - contact summary (ParticLS eq 15), materials and the contact-law vtable.
 *
 * Convention: particle i is "p", particle j is "p'". n is the unit normal pointing from i
 * towards j; depth > 0 when they penetrate. The law returns the force on i; j receives
 * the opposite force. The world adds the lever-arm torques (point - x) x F to both. */
#ifndef FLOE_CONTACT_H
#define FLOE_CONTACT_H

#include "floe_base.h"
#include "floe_registry.h"

/* A list entry's history (the world's, core/world/neighbor.c): the world's ledger first,
 * then the law's state, then the manifold's twist:
 *   [0..2] the previous force on i, [3] the stored energy, [4] the energy dissipated since
 *   the contact began (the energy ledger and watchdog);
 *   [5..8] the law's history[0 .. history_size - 1] (a law sees a pointer to slot 5);
 *   [9] the relative twist angle of a contact manifold (3D polytopes).
 * A world whose laws keep at most 3 doubles and whose shapes are only spheres and planes
 * (no manifold) keeps entries of FLOE_HIST_COMPACT doubles (one 64-byte cache line), any
 * other FLOE_MAX_HISTORY: the slots' places are the same in both. */
#define FLOE_MAX_HISTORY 10  /* doubles of per-contact state kept per pair (at most) */
#define FLOE_HIST_COMPACT 8  /* ... in a world without manifolds whose laws keep <= 3 */
#define FLOE_LAW_HISTORY 4   /* doubles a law may keep (floe_contact_law_class.history_size) */
#define FLOE_FORCE_SLOT 0
#define FLOE_ENERGY_SLOT 3
#define FLOE_DISS_SLOT 4
#define FLOE_LAW_SLOT 5
#define FLOE_TWIST_SLOT 9

typedef struct floe_material {
    char name[64];
    double density;          /* kg/m^3 */
    double young;            /* E, Pa (used by Hertz-Mindlin and time-step estimates) */
    double poisson;          /* nu, in (-1, 0.5) */
} floe_material;

/* Contact summary, ParticLS eq 15. */
typedef struct floe_contact {
    int i, j;                /* particle indices */
    double x1[3];            /* point of i's boundary deepest inside j */
    double x2[3];            /* point of j's boundary deepest inside i */
    double n[3];             /* unit normal from i to j */
    double depth;            /* penetration distance |x2 - x1| (>0 overlapping) */
    double point[3];         /* contact point (x1 + x2)/2, the moment arm of eq 16-20 */
    double vr[3];            /* relative velocity of i with respect to j at the point (eq 15b) */
    double vn;               /* vr . n  (> 0 approaching) */
    double vt[3];            /* tangential relative velocity vr - vn n (eq 15c) */
    double r_eff;            /* effective radius R* = (1/Ri + 1/Rj)^-1 (walls: infinite) */
    double m_eff;            /* effective mass m* (fixed/kinematic partners: infinite) */
    double dt;               /* time step the history is advanced by */
    double an_ext;           /* m/s^2: the rate of change of vn that forces other than this
                                contact's own give the pair, (a_i - a_j) . n at the last force
                                evaluation less this contact's last force times 1/m_i + 1/m_j
                                (0 for two bodies alone; set by the world when a law has a linear
                                dashpot, 0 otherwise): the linear dashpot's end-of-step velocity
                                (contact/laws/linear_law.c) */
    double gscale;           /* |grad depth| (<= 1): where the deepest point is equidistant from
                                two faces the depth grows at this rate along n only, and the
                                world scales the law's force by it so that the force stays the
                                gradient of the stored energy (1 otherwise; set by detection) */
    /* set only for the overlap-area law (polytope pairs, floe_overlap_law_class): */
    double area;             /* overlap area (2D, m^2) or volume (3D, m^3) */
    double area_force[3];    /* the elastic force on i per unit stiffness, -dI/dx_i: its length
                                equals the overlap area (volume) where one face of each body
                                bounds it */
    double area_couple[3];   /* 3D: the part of -dI/dθ_i not carried by area_force at point (a
                                couple on i, minus it on j) */
    double area_energy;      /* I = (int_{A∩B} -phi_B + int_{A∩B} -phi_A) / 2, m^3 (2D) or m^4
                                (3D): the stored energy per unit stiffness */
    double area_l2;          /* squared size of the touching patch (rocking dashpot), m^2 */
    double wr[3];            /* relative angular velocity w_i - w_j (set by the world) */
    /* polytope pairs under a point law (not overlap_area): the contact manifold. Besides the
     * deepest point (depth, point, n above) the 2nd .. K-th deepest vertices of either body
     * inside the other (K = 2 in 2D, 4 in 3D) carry elastic springs of the same law, each
     * at its own depth -phi (docs/models.md, "Contact manifold"): */
    int nextra;                          /* 0 .. FLOE_MANIFOLD_EXTRA */
    double extra_point[3][3];            /* the vertex */
    double extra_n[3][3];                /* unit normal from i to j (the nearest face's) */
    double extra_depth[3];               /* -phi of the other body at the vertex, m */
    double fn_extra;                     /* their elastic normal load, N (set by the world before
                                            the law is called): laws add it to the Coulomb
                                            limit, so the patch's friction is mu x the total */
    /* set for laws whose info has needs_floe (sea ice, docs/sea-ice.md): the two bodies'
     * thickness (m; 1 for a particle without one, floe_particle_def.thickness) and bounding
     * radii (m; INFINITY for a wall) */
    double thick_i, thick_j, rad_i, rad_j;
} floe_contact;
#define FLOE_MANIFOLD_EXTRA 3

typedef struct floe_contact_result {
    double force[3];         /* force on i, N */
    double torque_i[3];      /* extra torque on i beyond (point - x_i) x force (rolling), N m */
    double torque_j[3];      /* extra torque on j */
    double energy;           /* elastic energy stored in the contact, J */
    double dissipation;      /* energy dissipated during this step (damping + slip), J, as the
                                law sees it; the world's energy ledger uses work minus the
                                change of stored energy instead (docs/models.md) */
    double fn;               /* magnitude of the normal force (for stress/outputs), N */
} floe_contact_result;

typedef struct floe_contact_law floe_contact_law;

/* What the world's time-step estimates may know of a law beyond its stiffness (the
 * optional info method of the class; a composed law forwards its normal part's). */
typedef struct floe_law_info {
    double hertz_e_star;     /* > 0: the normal force is 4/3 E* sqrt(R*) d^(3/2) with this E*
                                (Pa): the Hertz contact duration and Rayleigh step apply */
    double restitution;      /* head-on restitution the law is calibrated to (NAN: unknown) */
    double linear_kn, linear_gn; /* > 0: a linear spring (N/m) and dashpot (N s/m) normal force */
    int needs_overlap;       /* 1: the law reads the overlap area/volume (floe_contact.area):
                                detection must fill it (polytope pairs only) */
    int spreads_load;        /* 1: the law's stiffness already counts the contact length (the
                                critical step does not add the contact manifold's factor) */
    int needs_floe;          /* 1: the law reads thick_i/j and rad_i/j of the contact summary
                                (the world then takes its general contact path) */
    int single_point;        /* 1: the law models the whole contact at its deepest point (a
                                contact length of its own, plastic history): polytope pairs
                                get no manifold springs */
    int prefers_overlap;     /* 1: polytope pairs get the overlap fields (area*, as
                                needs_overlap), other pairs the deepest point (area = 0) */
    double thickness_max;    /* > 0: the critical step (stiffness()) assumes no floe of the
                                law's materials is thicker (m); the world refuses a thicker one */
} floe_law_info;

typedef struct floe_contact_law_class {
    int version;             /* 1 */
    const char *name;
    int history_size;        /* doubles of per-contact state (<= FLOE_LAW_HISTORY) */
    /* Force for a contact with depth > 0; history is updated in place by c->dt. */
    int (*force)(const floe_contact_law *law, const floe_contact *c, double *history,
                 floe_contact_result *out);
    /* Linearised normal stiffness (N/m) and normal damping coefficient (N s/m) for a
     * representative contact of effective radius r_eff, mass m_eff and overlap depth;
     * used for the critical time step. */
    void (*stiffness)(const floe_contact_law *law, double r_eff, double m_eff, double depth,
                      double *kn, double *cn);
    void (*destroy)(floe_contact_law *law);
    /* optional: tangential stiffness (N/m) and damping (N s/m) at the same representative
     * contact, for the rotational modes in the critical time step (NULL = none) */
    void (*tangential_stiffness)(const floe_contact_law *law, double r_eff, double m_eff, double depth,
                                 double *kt, double *ct);
    /* optional: what the time-step estimates may know (NULL: nothing beyond stiffness) */
    void (*info)(const floe_contact_law *law, floe_law_info *info);
} floe_contact_law_class;

/* The law's info (zeros, restitution NAN, when the class has no info method). */
floe_law_info floe_contact_law_info(const floe_contact_law *law);

struct floe_contact_law {
    const floe_contact_law_class *klass;
    double friction;         /* its Coulomb coefficient (0: none); the world uses it for the
                                twist friction of a contact manifold (core/world/forces.c) */
};

/* Linear elastic with Coulomb friction, ParticLS eqs 16-18 (gn = gs = 0), and linear
 * viscoelastic, eqs 19-20. */
typedef struct floe_linear_law {
    floe_contact_law base;
    double kn, ks;           /* N/m */
    double gn, gs;           /* N s/m (absolute dashpots) */
    double mu;               /* Coulomb friction coefficient */
    int tension;             /* 1: allow the total normal force to become attractive (paper
                                form); 0 (default): clamp it at zero */
} floe_linear_law;

/* Hertz-Mindlin with damping from a coefficient of restitution
 * (003 eqs 15-21, 000 eq 36): kn = 4/3 E* sqrt(R* d), kt = 8 G* sqrt(R* d). */
typedef struct floe_hertz_mindlin_law {
    floe_contact_law base;
    double e_star;           /* effective Young's modulus, Pa */
    double g_star;           /* effective shear modulus, Pa */
    double restitution;      /* e in (0, 1] */
    double mu;               /* friction */
    double damping_ratio;    /* dimensionless damping calibrated so that the collision
                                restitutes exactly e (see docs/models.md) */
    double tangent_damping_ratio; /* sqrt(kt / Sn) = sqrt(4 G* / E*), cached */
} floe_hertz_mindlin_law;

extern const floe_contact_law_class floe_linear_law_class;
extern const floe_contact_law_class floe_hertz_mindlin_law_class;

/* Rotate a stored tangential history vector (shear spring) onto the plane normal to n,
 * keeping its length, so that it follows the rigid rotation of the contact frame
 * (LIGGGHTS/LAMMPS). For the usual small turn, 1/sqrt(1 - q) is expanded to second order
 * in q = (s.n)^2/|s|^2 (relative error < 1e-12 for q < 1e-4); a spring parallel to n has
 * no direction left and is zeroed; a zero spring stays zero. For use inside contact laws.
 * Without a branch (each case computed, the one that applies selected) and without calls,
 * so that a loop over contacts runs it in vector lanes (the world's sphere batches). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void floe_contact_rotate_history(double s[3], const double n[3]) {
    const double mag2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2], sn = s[0] * n[0] + s[1] * n[1] + s[2] * n[2];
    double t[3];
    for (int k = 0; k < 3; k++) t[k] = s[k] + -sn * n[k];
    const double p2 = mag2 - sn * sn, q = sn * sn / mag2;
    const double small = 1.0 + q * (0.5 + 0.375 * q), big = sqrt(mag2 / (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]));
    const int keep = mag2 == 0.0, is_small = q < 1e-4, is_big = p2 > 1e-24 * mag2;
    for (int k = 0; k < 3; k++) {
        const double ts = t[k] * small, tb = t[k] * big;
        s[k] = keep ? s[k] : is_small ? ts : is_big ? tb : 0.0;
    }
}

/* Constructors (caller owns the result, or the world after floe_world_set_law). */
floe_contact_law *floe_linear_law_create(double kn, double ks, double gn, double gs, double mu);
floe_contact_law *floe_hertz_mindlin_law_create(const floe_material *a, const floe_material *b,
                                                double restitution, double mu);
void floe_contact_law_destroy(floe_contact_law *law);
/* Set the law's Coulomb friction coefficient mu (>= 0, finite) in place: the built-in
 * laws (linear/viscoelastic, hertz_mindlin, overlap_area, hopkins, a composed law with a
 * tangential part). FLOE_EINVAL for NULL or mu out of range, FLOE_ENOTSUP for a law that
 * cannot (a frictionless composition, a user law). A law with a zero tangential stiffness
 * (linear ks = 0) stays frictionless whatever mu: give it ks > 0. */
int floe_contact_law_set_friction(floe_contact_law *law, double mu);

/* Hertz-Mindlin damping ratio for a restitution coefficient e (monotone map, computed by
 * integrating the dimensionless collision ODE and bisection; cached). */
double floe_hertz_damping_for_restitution(double e);
/* Restitution of a linear spring-dashpot with stiffness k, damping c and mass m
 * (force allowed to become attractive: e = exp(-pi zeta / sqrt(1 - zeta^2))). */
double floe_linear_restitution(double k, double c, double m);

/* ---- short-range PD contact force and the "none" law (contact/laws/short_range.c) ---- */

/* Silling's short-range repulsive force between PD nodes (Silling & Askari 2005 eq 20,
 * c_s = factor c with factor 15 as in EMU and LAMMPS pair peri/pmb), with the short-range
 * distance d_s = R_i + R_j (the contact radii): F_n = k d, k = c_s V_a V_b / delta, d the
 * contact depth; no damping, friction or tension. See docs/models.md. */
typedef struct floe_short_range_law {
    floe_contact_law base;
    double k;                /* N/m */
    double c_s, delta;       /* c_s = factor c (N/m^6) and the horizon (m), 0 when k was given */
    double v_a, v_b;         /* node volumes (m^3), 0 when k was given */
} floe_short_range_law;

extern const floe_contact_law_class floe_short_range_law_class;
extern const floe_contact_law_class floe_no_contact_law_class;

/* Short-range law with the spring constant k (N/m, > 0); NULL on bad input. */
floe_contact_law *floe_short_range_law_create(double k);
/* The same from the PD parameters: k = factor c v_a v_b / delta (factor <= 0: 15). */
floe_contact_law *floe_short_range_law_create_pd(double c, double delta, double v_a, double v_b, double factor);
/* "none": the pair of materials never interacts by contact: the world skips its pairs before
 * detection (no force, no history, no interpenetration guard). */
floe_contact_law *floe_no_contact_law_create(void);

/* ---- overlap law for polytopes (contact/laws/overlap_law.c, contact/detect/overlap.c) ----
 * Elastic force = ka x the conservative overlap resultant (length: the overlap area A in
 * 2D, volume V in 3D, where one edge/face of each body bounds the overlap: F = ka A as
 * SubZero's floe contact), stored energy ka I (floe_contact.area_energy): a Winkler
 * foundation of modulus ka (N/m^3), so flat faces carry a linear pressure and rest without
 * rocking. Dashpot gn (N s/m) on the normal velocity at the resultant's point and as a
 * couple gn l^2/12 against rocking, Coulomb friction with a shear spring ks (N/m) and
 * dashpot gs as the linear law. 2D forces are per metre of thickness with masses per area. */
typedef struct floe_overlap_law {
    floe_contact_law base;
    double ka, ks, gn, gs, mu;
} floe_overlap_law;
extern const floe_contact_law_class floe_overlap_law_class;
floe_contact_law *floe_overlap_law_create(double ka, double ks, double gn, double gs, double mu);
/* Coulomb friction with a shear spring, shared by the linear and overlap laws: updates the
 * spring s (history[0..2]) by c->vt dt, returns the tangential force in Ft and adds the
 * dissipated energy to *diss (ParticLS eqs 17-18, LAMMPS gran/hooke/history reset) */
void floe_contact_coulomb(const floe_contact *c, double ks, double gs, double mu, double Fn, double *s,
                          double Ft[3], double *diss);
/* 1 when the world must keep the pair out of contact (the "none" law), else 0 (NULL: 0). */
static inline int floe_contact_law_no_contact(const floe_contact_law *law) {
    return law && law->klass == &floe_no_contact_law_class;
}

/* ---- laws composed of a normal part and a tangential part (contact/laws/composed_law.c) ----
 * As MercuryDPM composes a contact law of a normal force and a friction force: the normal
 * part gives the normal force (and its elastic part, stiffness and dashpot, which some
 * tangential parts scale with), the tangential part the friction force limited by
 * mu (Fn + the manifold's other springs). History: the normal part owns history[3], the
 * tangential part history[0..2]. A scene composes them with
 *   laws: [{materials: [a, b], normal: {model: hertz, ...}, tangential: {model: mindlin, ...}}]
 * (kinds "normal" and "tangential" in the registry); hertz + mindlin is the hertz_mindlin
 * law and hooke + coulomb the viscoelastic one, to rounding (tests/test_composed_law.c). */
#define FLOE_KIND_NORMAL "normal"
#define FLOE_KIND_TANGENTIAL "tangential"

typedef struct floe_normal_force {
    double fn;               /* normal force magnitude on the pair, N (repulsive > 0) */
    double fel;              /* its elastic part, N */
    double energy;           /* stored elastic energy, J */
    double kn;               /* elastic stiffness dFel/d(depth) at this depth, N/m */
    double gn;               /* dashpot coefficient in use, N s/m */
    double diss;             /* dissipated over the step by the dashpot, J */
} floe_normal_force;

typedef struct floe_normal_part floe_normal_part;
typedef struct floe_tangential_part floe_tangential_part;

typedef struct floe_normal_part_class {
    int version;             /* 1 */
    const char *name;
    /* normal force for a contact with depth > 0; history[3] is the part's own */
    int (*force)(const floe_normal_part *np, const floe_contact *c, double *history, floe_normal_force *out);
    /* linearised stiffness and damping at a representative contact (critical step) */
    void (*stiffness)(const floe_normal_part *np, double r_eff, double m_eff, double depth, double *kn, double *cn);
    void (*info)(const floe_normal_part *np, floe_law_info *info); /* optional */
    void (*destroy)(floe_normal_part *np);                          /* optional (NULL: free) */
} floe_normal_part_class;
struct floe_normal_part {
    const floe_normal_part_class *klass;
};

typedef struct floe_tangential_part_class {
    int version;             /* 1 */
    const char *name;
    /* tangential force ft on i for a contact with depth > 0, given the normal force nf;
     * history[0..2] are the part's own; adds the stored energy to *energy and the
     * dissipation of the step to *diss */
    int (*force)(const floe_tangential_part *tp, const floe_contact *c, const floe_normal_force *nf,
                 double *history, double ft[3], double *energy, double *diss);
    /* tangential stiffness and damping at a representative contact whose normal part has
     * stiffness kn and damping cn (critical step); optional */
    void (*stiffness)(const floe_tangential_part *tp, double r_eff, double m_eff, double depth, double kn,
                      double cn, double *kt, double *ct);
    void (*destroy)(floe_tangential_part *tp); /* optional (NULL: free) */
} floe_tangential_part_class;
struct floe_tangential_part {
    const floe_tangential_part_class *klass;
    double friction;         /* its Coulomb coefficient (0: none) */
};

/* Constructors of registered parts (the params struct of the entry's schema). */
typedef floe_normal_part *(*floe_normal_create_fn)(const void *params, const floe_material *a,
                                                   const floe_material *b, char *err, size_t errlen);
typedef floe_tangential_part *(*floe_tangential_create_fn)(const void *params, const floe_material *a,
                                                           const floe_material *b, char *err, size_t errlen);
/* The law of a normal part and a tangential part (NULL: frictionless); it owns both after
 * success (on failure it destroys them and returns NULL). */
floe_contact_law *floe_composed_law_create(floe_normal_part *np, floe_tangential_part *tp);
extern const floe_contact_law_class floe_composed_law_class;
/* The built-in parts (NULL on bad input): hooke kn (N/m) > 0, gn (N s/m) >= 0, tension
 * 0/1; hertz from two materials (young, poisson) and a restitution in (0, 1]; coulomb mu,
 * ks > 0, gs >= 0; mindlin from two materials and mu. */
floe_normal_part *floe_hooke_part_create(double kn, double gn, int tension);
floe_normal_part *floe_hertz_part_create(const floe_material *a, const floe_material *b, double restitution);
floe_tangential_part *floe_coulomb_part_create(double mu, double ks, double gs);
floe_tangential_part *floe_mindlin_part_create(const floe_material *a, const floe_material *b, double mu);
/* Destroy a part (its class's destroy, or free). */
void floe_normal_part_destroy(floe_normal_part *np);
void floe_tangential_part_destroy(floe_tangential_part *tp);

/* ---- contact laws as registered components (floe_registry.h, kind FLOE_KIND_LAW) ----
 * A registered law gives a parameter schema and this constructor: params is its parameter
 * struct (filled from the scene by the schema), a and b the materials of the pair. It
 * returns the law (calloc'd, the world owns it after floe_world_set_law), or NULL with a
 * message in err (the loader prefixes the scene position). A scene names it with
 * `laws: [{materials: [a, b], model: <name>, <its parameters>}]`. */
typedef floe_contact_law *(*floe_law_create_fn)(const void *params, const floe_material *a,
                                                const floe_material *b, char *err, size_t errlen);
/* Hopkins' elastic-plastic ridging law for 2D sea-ice floes (contact/laws/hopkins_law.c,
 * docs/sea-ice.md "Ridging law"): reads each floe's thickness (floe_contact.thick_i/j). */
typedef struct floe_hopkins_def {
    double young;             /* E, Pa (2e9, DEMSI) */
    double poisson;           /* nu (0.3) */
    double damping;           /* eta: normal damping, fraction of critical (0.1) */
    double plastic_friction;  /* C_f, Pa: ridging yield per length k_r = C_f h_r (26126) */
    double plastic_hardening; /* C_h, Pa/m^2: hardening k_p = C_h h_r^2 (928) */
    double friction;          /* Coulomb mu (0.3) */
    double gs;                /* tangential dashpot, N s/m (0) */
    double thickness_max;     /* m: the thickest floe, for the critical time step (5) */
} floe_hopkins_def;
floe_hopkins_def floe_hopkins_default(void);
/* NULL with the message in err for an invalid definition */
floe_contact_law *floe_hopkins_law_create(const floe_hopkins_def *d, char *err, size_t errlen);
extern const floe_contact_law_class floe_hopkins_law_class;

/* entry flag: the law needs the materials' young and poisson (Hertz-type stiffness) */
#define FLOE_LAW_NEEDS_YOUNG 256
/* Registers the built-in laws (idempotent); FLOE_OK or the registry's error. */
int floe_register_builtin_laws(char *err, size_t errlen);

#endif
