/* gf_imu_error.h — the one IMU error model of gfins_fmi (seeds 001 and 004): applied by
 * the simulation, inverted by the compensation, estimated by the calibrations.
 *
 * Gyro (seed 004 eq. 4-7 in matrix form):
 *     w_out = (I + diag(s_g)) (I + N_g) w + b_g
 * Accelerometer (seed 004 eq. 8-9; seed 001's inner lever arms): along sensing axis i
 *     u   = (I + N_a) f - r o [w_y^2 + w_z^2, w_x^2 + w_z^2, w_x^2 + w_y^2]
 *     a_i = (1 + s_a,i) u_i + K2_i u_i^2 + b_a,i
 * (accelerometer i sits r_i from the IMU centre along its own axis, so it also feels the
 * centripetal -r_i (w_j^2 + w_k^2); seed 001 compensates a_xb = a_xc + (w_y^2 + w_z^2) r_x.)
 * N has a zero diagonal: the general cross-coupling of seed 004; seed 001's
 * orthogonalisation angles are the special case of a triangular N.
 * Temperature (seed 004 eq. 10-15): bias and scale of every axis are polynomials in
 * dT = T - T0:  b(T) = b + sum_k c_k dT^(k+1)  (k < order), the same for s.
 * Range of validity: the model holds where every scale factor at the sample's
 * temperature stays in (-0.5, 0.5) (the limit gf_imu_errors_check puts on s at T0) and
 * the biases within their limits (GF_IMU_MAX_*_BIAS), and where the specific force u_i
 * along each axis is within GF_IMU_K2_RANGE_M_S2 (where gf_imu_errors_check bounds
 * |K2 u| < 0.1, so that a_i(u_i) is monotonic and the compensation's root unique;
 * beyond it the quadratic folds back and apply has no inverse: found by fuzzing).
 * Beyond it 1 + s(T) may reach 0 and the compensation would divide by it: both
 * gf_imu_apply and gf_imu_compensate stop with GF_ERR_OUT_OF_RANGE at such a sample, as
 * they do when a result would overflow.
 * Units: SI (rad/s, m/s^2, m, K or degC differences); the Python layer converts from
 * datasheet units.
 */
#ifndef GF_IMU_ERROR_H
#define GF_IMU_ERROR_H

#include <stddef.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_IMU_TEMP_ORDER_MAX 4
/* Bias limits (at every temperature): the navigators' absurd-sample limits
 * (GF9_MAX_RATE_RAD_S, GF9_MAX_SPECIFIC_FORCE_M_S2); a larger bias swamps the signal, and
 * one near 1e308 left compensate(apply(w)) far from w (found by fuzzing). */
#define GF_IMU_MAX_GYRO_BIAS_RAD_S 50
#define GF_IMU_MAX_ACCEL_BIAS_M_S2 1000
#define GF_IMU_K2_RANGE_M_S2 1000

typedef struct gf_imu_errors {
    double g_scale[3];                          /* s_g (1 = 100%) */
    double g_misalign_rad[9];                   /* N_g, row-major, zero diagonal */
    double g_bias_rad_s[3];
    double a_scale[3];
    double a_misalign_rad[9];
    double a_bias_m_s2[3];
    double a_k2_s2_m[3];                        /* K2, (m/s^2)^-1 */
    double a_lever_m[3];                        /* inner lever arm r_i along axis i */
    double t0;                                  /* reference temperature */
    int temp_order;                             /* 0..GF_IMU_TEMP_ORDER_MAX */
    double g_bias_tc[GF_IMU_TEMP_ORDER_MAX * 3];   /* [k][axis], per dT^(k+1) */
    double g_scale_tc[GF_IMU_TEMP_ORDER_MAX * 3];
    double a_bias_tc[GF_IMU_TEMP_ORDER_MAX * 3];
    double a_scale_tc[GF_IMU_TEMP_ORDER_MAX * 3];
} gf_imu_errors;

/* Checks a parameter set. Errors: GF_ERR_NONFINITE_INPUT; GF_ERR_BAD_PARAMETER with
 * *bad_field (may be NULL): 1 gyro scale (|s| >= 0.5), 2 gyro misalignment (|N| >= 0.1
 * rad or non-zero diagonal), 3 accel scale, 4 accel misalignment, 5 K2 (|K2 f| >= 0.1
 * at GF_IMU_K2_RANGE_M_S2), 6 lever arm (|r| >= 1 m), 7 temperature order, 8 gyro bias (|b| >=
 * GF_IMU_MAX_GYRO_BIAS_RAD_S), 9 accel bias (|b| >= GF_IMU_MAX_ACCEL_BIAS_M_S2). */
gf_status gf_imu_errors_check(const gf_imu_errors *e, int *bad_field);

/* Simulation: true rates w (n x 3, rad/s) and specific force f (n x 3, m/s^2) -> sensor
 * outputs. temp (n, may be NULL = T0). *n_done: rows done; the run stops at a
 * non-finite input (GF_ERR_NONFINITE_INPUT) or at a sample beyond the range of validity
 * above or whose outputs overflow (GF_ERR_OUT_OF_RANGE). */
gf_status gf_imu_apply(const gf_imu_errors *e, size_t n, const double *w, const double *f,
                       const double *temp, double *w_out, double *f_out, size_t *n_done);

/* Compensation: sensor outputs -> rates and specific force, the exact inverse of
 * gf_imu_apply (the K2 quadratic by its numerically stable root). Stops as gf_imu_apply
 * does, and with GF_ERR_OUT_OF_RANGE where the K2 quadratic has no real root. */
gf_status gf_imu_compensate(const gf_imu_errors *e, size_t n, const double *w_out,
                            const double *f_out, const double *temp, double *w, double *f,
                            size_t *n_done);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_IMU_ERROR_H */
