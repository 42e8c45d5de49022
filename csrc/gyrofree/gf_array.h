/* gf_array.h — accelerometer arrays for gyro-free inertial navigation: the geometry of
 * an array of single-axis accelerometers and its forward model.
 *
 * Source: seed 000 (Qin, Xu, Li, "A new 9-accelerometer gyro-free INS solution").
 *
 * Output model of single-axis accelerometer i at body position u_i (m) with unit
 * sensing direction theta_i (seed 000, eq. 1-2 in vector form):
 *
 *     A_i = theta_i . [ f + omega_dot x u_i + omega x (omega x u_i) ]      (m/s^2)
 *
 * f is the specific force at the array centre (gravity enters through f), omega the
 * body angular rate (rad/s) and omega_dot its derivative (rad/s^2), all in body axes.
 * The solvers: gf9.h (seed 000's nine accelerometers), gf_array_solver.h (any array).
 */
#ifndef GF_ARRAY_H
#define GF_ARRAY_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_ARRAY_MAX_SENSORS 64

/* Geometry of an array of single-axis accelerometers. */
typedef struct gf_array_geometry {
    size_t n_sensors;                          /* 1 .. GF_ARRAY_MAX_SENSORS */
    double u_m[GF_ARRAY_MAX_SENSORS][3];       /* positions, body frame, m */
    double theta[GF_ARRAY_MAX_SENSORS][3];     /* unit sensing directions */
} gf_array_geometry;

/* Fills *geometry from n_sensors rows of u_m (n x 3, m) and theta (n x 3, unit).
 * Errors: GF_ERR_BAD_SIZE (n = 0 or > max), GF_ERR_NONFINITE_INPUT,
 * GF_ERR_SINGULAR_GEOMETRY (a zero sensing direction), GF_ERR_BAD_PARAMETER (a
 * direction whose norm differs from 1 by more than 1e-9). *bad_sensor (may be NULL)
 * receives the index of the offending sensor. */
gf_status gf_array_geometry_set(gf_array_geometry *geometry, size_t n_sensors,
                                const double *u_m, const double *theta,
                                size_t *bad_sensor);

/* Forward model for n_samples samples: rows of f_m_s2, omega_rad_s, omega_dot_rad_s2
 * (each n x 3) -> A_m_s2 (n x n_sensors). On a non-finite input the run stops,
 * *n_done (may be NULL) = index of the bad sample, and GF_ERR_NONFINITE_INPUT is
 * returned (GF_ERR_OUT_OF_RANGE when finite inputs overflow the outputs); rows before
 * it are valid. */
gf_status gf_array_forward(const gf_array_geometry *geometry, size_t n_samples,
                           const double *f_m_s2, const double *omega_rad_s,
                           const double *omega_dot_rad_s2, double *A_m_s2,
                           size_t *n_done);

/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_ARRAY_H */
