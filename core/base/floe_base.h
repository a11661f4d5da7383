/* floe_base.h - error codes, status propagation and small vector/quaternion helpers.
 * Every fallible floe function returns an int status (FLOE_OK = 0); the world keeps the
 * message of the last error (floe_world_last_error). Library code never calls exit(). */
#ifndef FLOE_BASE_H
#define FLOE_BASE_H

#include <math.h>
#include <stddef.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define FLOE_VERSION_STRING "0.1.0"

enum {
    FLOE_OK = 0,
    FLOE_EINVAL = 1,      /* invalid argument or definition field */
    FLOE_ENOMEM = 2,      /* allocation failed */
    FLOE_EIO = 3,         /* file could not be read or written */
    FLOE_EPARSE = 4,      /* scene file malformed */
    FLOE_EUNSTABLE = 5,   /* NaN, blow-up or time step above the critical one */
    FLOE_ENOTSUP = 6,     /* feature not built or no detector for a pair */
    FLOE_ESTOP = 7        /* a callback or observer asked to stop */
};

/* Short name of an error code ("FLOE_EINVAL"). */
const char *floe_strerror(int code);

#define FLOE_TRY(expr)              \
    do {                            \
        int floe_try_rc_ = (expr);  \
        if (floe_try_rc_ != FLOE_OK) return floe_try_rc_; \
    } while (0)

/* ---- 3-vectors (double[3]) ---- */
static inline void floe_v3_set(double a[3], double x, double y, double z) { a[0] = x; a[1] = y; a[2] = z; }
static inline void floe_v3_copy(double a[3], const double b[3]) { a[0] = b[0]; a[1] = b[1]; a[2] = b[2]; }
static inline double floe_v3_dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline double floe_v3_norm(const double a[3]) { return sqrt(floe_v3_dot(a, a)); }
static inline void floe_v3_sub(double r[3], const double a[3], const double b[3]) { r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2]; }
static inline void floe_v3_add(double r[3], const double a[3], const double b[3]) { r[0] = a[0] + b[0]; r[1] = a[1] + b[1]; r[2] = a[2] + b[2]; }
static inline void floe_v3_axpy(double r[3], double s, const double a[3]) { r[0] += s * a[0]; r[1] += s * a[1]; r[2] += s * a[2]; }
static inline void floe_v3_scale(double r[3], double s) { r[0] *= s; r[1] *= s; r[2] *= s; }
static inline void floe_v3_cross(double r[3], const double a[3], const double b[3]) {
    double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
    r[0] = x; r[1] = y; r[2] = z;
}

/* ---- unit quaternions q = (w, x, y, z), rotating body frame -> world frame ---- */
static inline void floe_q_identity(double q[4]) { q[0] = 1; q[1] = q[2] = q[3] = 0; }
static inline void floe_q_mul(double r[4], const double a[4], const double b[4]) {
    double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    double y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    double z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    r[0] = w; r[1] = x; r[2] = y; r[3] = z;
}
static inline void floe_q_normalize(double q[4]) {
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    q[0] /= n; q[1] /= n; q[2] /= n; q[3] /= n;
}
/* r = q v q*  (body -> world) */
static inline void floe_q_rotate(double r[3], const double q[4], const double v[3]) {
    double t[3], u[3];
    const double *qv = q + 1;
    floe_v3_cross(t, qv, v);
    floe_v3_scale(t, 2.0);
    floe_v3_cross(u, qv, t);
    r[0] = v[0] + q[0] * t[0] + u[0];
    r[1] = v[1] + q[0] * t[1] + u[1];
    r[2] = v[2] + q[0] * t[2] + u[2];
}
/* r = q* v q  (world -> body), ParticLS eq 3 */
static inline void floe_q_rotate_inv(double r[3], const double q[4], const double v[3]) {
    double qc[4] = {q[0], -q[1], -q[2], -q[3]};
    floe_q_rotate(r, qc, v);
}
/* quaternion of the rotation by vector theta (axis * angle) */
static inline void floe_q_from_rotvec(double q[4], const double th[3]) {
    double a = floe_v3_norm(th);
    if (a < 1e-300) { floe_q_identity(q); return; }
    double s = sin(0.5 * a) / a;
    q[0] = cos(0.5 * a); q[1] = th[0] * s; q[2] = th[1] * s; q[3] = th[2] * s;
}

/* How a particle moves (floe_world_add_particle and the particle store). */
typedef enum floe_motion {
    FLOE_FREE = 0,        /* integrated from forces */
    FLOE_FIXED = 1,       /* never moves */
    FLOE_KINEMATIC = 2    /* prescribed velocity / angular velocity */
} floe_motion;

#endif
