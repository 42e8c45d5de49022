/* gf_imu_error.h — the one IMU error model of gfins_fmi (seeds 001 and 004): applied by
 * the simulation, inverted by the compensation, estimated by the calibrations.
 *
 * Gyro (seed 004 eq. 4-7 in matrix form):
 *     w_out = (I + diag(s_g)) (I + N_g) w + b_g
 * Accelerometer (seed 004 eq. 8-9; inner lever arms and delay: below): along sensing axis i
 *     f_d = (I + d [w x]) f                                  (sample delay d, first order)
 *     u_i = [(I + N_a) f_d]_i + e_i^T W r_i,   W = [w_dot x] + [w x]^2
 *     a_i = (1 + s_a,i) u_i + K2_i u_i^2 + b_a,i
 * Inner lever arms (size effect): accelerometer i sits at r_i (row i of a_lever_pos_m,
 * IMU axes) from the reference point whose specific force f is; a rigid body's specific
 * force there is f + w_dot x r_i + w x (w x r_i), so the sensor along e_i adds
 *     e_i^T W r_i = -r_ii (w_j^2 + w_k^2) + sum_{j != i} r_ij (w_i w_j + [w_dot x]_ij)
 * (the first term alone is seed 001's lever arm along the own axis, S603:
 * a_xb = a_xc + (w_y^2 + w_z^2) r_x; it needs no angular acceleration). A translation of
 * all three positions by the same vector moves the reference point only: it is not
 * observable by a calibration at rest (choose a convention, e.g. the z accelerometer at
 * the origin, r_z = 0; docs/rotating_ins.md). w_dot: the angular acceleration, an input
 * of the _dw entry points (0 in gf_imu_apply and gf_imu_compensate).
 * Sample delay: the accelerometers sample the specific force d seconds after the gyros'
 * time tag, f(t - d) = f(t) + d (w x f) to first order for a force fixed outside the
 * IMU (its IMU-axis derivative is -w x f); the compensation inverts (I + d [w x]) exactly.
 * (A static calibration uses the rate relative to the navigation frame instead of w:
 * gf_syscal.h; the two differ by d |w_ie| g = 0.07 ug per ms.)
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
#define GF_IMU_MAX_LEVER_M 1          /* |r_ij| below this (m) */
#define GF_IMU_MAX_DELAY_MS 1000      /* |accelerometer delay| below this (ms) */

typedef struct gf_imu_errors {
    double g_scale[3];                          /* s_g (1 = 100%) */
    double g_misalign_rad[9];                   /* N_g, row-major, zero diagonal */
    double g_bias_rad_s[3];
    double a_scale[3];
    double a_misalign_rad[9];
    double a_bias_m_s2[3];
    double a_k2_s2_m[3];                        /* K2, (m/s^2)^-1 */
    double a_lever_pos_m[9];                    /* inner lever arms: row i = position r_i of
                                                   accelerometer i from the reference point,
                                                   IMU axes, row-major (diagonal: along axis i) */
    double a_delay_s;                           /* accelerometer samples late by d (s) */
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
 * at GF_IMU_K2_RANGE_M_S2), 6 lever arm (a |r_ij| >= 1 m), 7 temperature order, 8 gyro bias (|b| >=
 * GF_IMU_MAX_GYRO_BIAS_RAD_S), 9 accel bias (|b| >= GF_IMU_MAX_ACCEL_BIAS_M_S2), 10 accelerometer
 * delay (|d| >= GF_IMU_MAX_DELAY_MS). */
gf_status gf_imu_errors_check(const gf_imu_errors *e, int *bad_field);

/* Simulation: true rates w (n x 3, rad/s) and specific force f (n x 3, m/s^2) -> sensor
 * outputs, with the angular acceleration taken as 0 (exact when the lever arms lie along
 * the sensing axes: then the model does not depend on it). temp (n, may be NULL = T0).
 * *n_done: rows done; the run stops at a non-finite input (GF_ERR_NONFINITE_INPUT) or at
 * a sample beyond the range of validity above or whose outputs overflow
 * (GF_ERR_OUT_OF_RANGE). */
gf_status gf_imu_apply(const gf_imu_errors *e, size_t n, const double *w, const double *f,
                       const double *temp, double *w_out, double *f_out, size_t *n_done);

/* Compensation: sensor outputs -> rates and specific force, the exact inverse of
 * gf_imu_apply (the K2 quadratic by its numerically stable root). Stops as gf_imu_apply
 * does, and with GF_ERR_OUT_OF_RANGE where the K2 quadratic has no real root. */
gf_status gf_imu_compensate(const gf_imu_errors *e, size_t n, const double *w_out,
                            const double *f_out, const double *temp, double *w, double *f,
                            size_t *n_done);

/* The same with the angular acceleration w_dot (n x 3, rad/s^2; NULL = 0), which the
 * lever arms across the sensing axes need: in a simulation the true one (e.g. the mean
 * over each sample interval, (w(t_k) - w(t_(k-1))) / dt), in a compensation the same
 * estimate the caller can make from the compensated rates (gf_imu_compensate_step).
 * gf_imu_compensate_dw(apply_dw(x, w_dot), w_dot) = x to round-off. */
gf_status gf_imu_apply_dw(const gf_imu_errors *e, size_t n, const double *w, const double *w_dot,
                          const double *f, const double *temp, double *w_out, double *f_out,
                          size_t *n_done);
gf_status gf_imu_compensate_dw(const gf_imu_errors *e, size_t n, const double *w_out,
                               const double *w_dot, const double *f_out, const double *temp,
                               double *w, double *f, size_t *n_done);
/* CDEF END */

/* One sample of a stream (outside the cffi block; for the filters and FMUs that
 * compensate sample by sample): the rates w, then w_dot = (w - w_prev) / dt_s (the
 * backward difference of the compensated rates; 0 when w_prev is NULL), then the
 * specific force f. temp may be NULL (T0). Errors as gf_imu_compensate_dw and
 * GF_ERR_BAD_TIME (dt_s <= 0 with w_prev given). */
gf_status gf_imu_compensate_step(const gf_imu_errors *e, const double w_out[3],
                                 const double f_out[3], const double *temp, const double *w_prev,
                                 double dt_s, double w[3], double f[3]);

#ifdef __cplusplus
}
#endif

#endif /* GF_IMU_ERROR_H */
