"""_cdef.py - the C declarations that the Python package binds (cffi ABI mode).

A curated subset of floe's public headers, copied as they are there without comments or
macros (cffi parses no preprocessor: the enum values the package needs are in _api.py).
Structs are complete, field for field: ABI mode has no compiler to check their layout, so
python/tests/test_cdef.py checks that every declaration here still reads the same in the
headers.

To bind a new function: paste its declaration (and any struct it takes) into the section
of its header below, then write a thin wrapper in world.py (docs/python.md, "Adding a
function").
"""

CDEF = r"""
/* ---- core/base/floe_base.h ---- */
const char *floe_strerror(int code);

/* ---- core/world/floe_world.h ---- */
typedef struct floe_world floe_world;

void floe_world_destroy(floe_world *w);
const char *floe_world_last_error(const floe_world *w);
int floe_world_prepare(floe_world *w);
double floe_world_critical_dt(floe_world *w);

double floe_world_dt(const floe_world *w);
double floe_world_time(const floe_world *w);
long floe_world_step_count(const floe_world *w);
int floe_world_particle_count(const floe_world *w);

int floe_world_step(floe_world *w);
typedef int (*floe_progress_fn)(const floe_world *w, long step, long nsteps, void *user);
int floe_world_run(floe_world *w, double t_end, floe_progress_fn progress, void *user);
int floe_world_finish(floe_world *w);

int floe_world_set_velocity(floe_world *w, int i, const double v[3], const double omega[3]);
int floe_world_set_pose(floe_world *w, int i, const double x[3], const double q[4]);
int floe_world_set_dt(floe_world *w, double dt, int allow_unstable);

int floe_world_record_contacts(floe_world *w, int on);
int floe_world_set_orientation(floe_world *w, int mode);
int floe_world_contact_count(const floe_world *w);

typedef struct floe_energy {
    double kinetic_trans, kinetic_rot, elastic;
    double work_body;
    double work_boundary;
    double dissipated;
    double initial;
} floe_energy;
floe_energy floe_world_energy(const floe_world *w);
double floe_world_energy_balance_error(const floe_world *w);

/* ---- core/world/floe_view.h ---- */
typedef struct floe_particles_view {
    int n;
    int dim;
    const double *x, *v;
    const double *q;
    const double *w;
    const double *L;
    const double *f, *t;
    const double *mass;
    const double *inertia;
    const double *radius;
    const int *geometry;
    const int *material, *group;
    const unsigned char *motion;
    const int *pieces;
    const double *thickness;
} floe_particles_view;
int floe_world_particles(const floe_world *w, floe_particles_view *out);

typedef struct floe_contact_info {
    int i, j;
    double point[3], n[3], depth;
    double force[3];
    double fn;
    double energy;
    double branch[3];
    double r_eff, m_eff;
} floe_contact_info;
int floe_world_contacts(const floe_world *w, const floe_contact_info **out);

int floe_world_dim(const floe_world *w);
int floe_world_is_prepared(const floe_world *w);

/* ---- core/world/floe_cell.h ---- */
int floe_world_set_cell(floe_world *w, const double origin[3], const double H[9]);
int floe_world_cell(const floe_world *w, double origin[3], double H[9]);
double floe_world_cell_volume(const floe_world *w);
int floe_world_cell_widths(const floe_world *w, double width[3]);
int floe_world_cell_wrap(const floe_world *w, const double x[3], double out[3]);
typedef struct floe_cell_control {
    int mode[9];
    double rate[9];
    double stress[9];
    double max_rate;
    double servo_time;
} floe_cell_control;
floe_cell_control floe_default_cell_control(void);
int floe_world_cell_set_control(floe_world *w, const floe_cell_control *c);
int floe_world_cell_get_control(const floe_world *w, floe_cell_control *c);
int floe_world_cell_velocity_gradient(const floe_world *w, double L[9]);
int floe_world_cell_stress(const floe_world *w, double sigma[9], double kinetic[9]);
int floe_world_refresh_forces(floe_world *w);
int floe_world_tangent_contact(const floe_world *w, double volume, double D[81]);
void floe_tangent_to_voigt(const double D[81], double V[36]);
typedef struct floe_rve_measures {
    double sigma[9], fabric[9];
    double coordination, porosity, void_ratio;
    double volume, solid_volume;
    int contacts, particles;
} floe_rve_measures;
int floe_world_cell_measures(const floe_world *w, floe_rve_measures *out);
int floe_world_cell_strain(floe_world *w, const double de[9], double max_rate, const int *stress_mask,
                           long *steps);

int floe_world_tangent_perturb(floe_world *w, double strain, double max_rate, long relax_steps, double D[81],
                               double Dv[36], long *steps);

/* ---- core/world/floe_servo.h ---- */
int floe_world_servo_set_pressure(floe_world *w, int wall, double pressure);
int floe_world_servo_set_speed(floe_world *w, int wall, double speed);
int floe_world_servo_reset(floe_world *w, int wall);
double floe_world_wall_pressure(const floe_world *w, int wall);
double floe_world_servo_area(const floe_world *w, int wall);
int floe_world_is_servo_wall(const floe_world *w, int wall);

/* ---- core/integrators/floe_checkpoint.h ---- */
int floe_world_checkpoint_save(const floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name,
                               char *err, size_t errlen);
int floe_world_checkpoint_load(floe_world *w, const char *path, uint64_t scene_hash, const char *scene_name,
                               char *err, size_t errlen);
size_t floe_world_state_size(const floe_world *w);
int floe_world_state_save(const floe_world *w, void *buf, size_t len, char *err, size_t errlen);
int floe_world_state_restore(floe_world *w, const void *buf, size_t len, char *err, size_t errlen);

/* ---- core/scene/floe_scene.h ---- */
typedef struct floe_scene_info {
    char name[128];
    double duration;
    int nparticles, nwalls, nmaterials, nlaws, nobservers, nstates;
    char summary[4096];
} floe_scene_info;
int floe_scene_load_ex(const char *path, const char *text, const char *outdir, int with_outputs,
                       floe_world **out_world, floe_scene_info *info, char *err, size_t errlen);
int floe_plugin_load(const char *path, char *err, size_t errlen);
const char *floe_scene_default_demo(void);

/* ---- observers/floe_observer.h ---- */
typedef struct floe_collection_stats {
    double time;
    double sigma[6];
    double coordination;
    int particles;
    int contacts;
    int wall_contacts;
    double volume;
} floe_collection_stats;
int floe_collection_stress(const floe_world *w, int group, double volume,
                           floe_collection_stats *out);
"""
