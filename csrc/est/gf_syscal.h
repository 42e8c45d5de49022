/* gf_syscal.h — system-level calibration of a rotating INS (seed 001, steps S2-S5): the
 * Kalman filter on the Kalman engine in two models: seed 001's 36 states (its inner lever
 * arms along the accelerometers' own axes) and the full model, 39 states, whose lever
 * arms are the x and y accelerometers' positions in all three directions relative to
 * the z accelerometer; each optionally with one more state for the time offset of the
 * accelerometer samples behind the gyro samples (37 and 40 states).
 *
 * States (seed 001 S301, its order; SI units):
 *   0-2   phi    attitude error of the IMU frame m, C_m^n(computed) = (I - [phi x]) C_m^n(true)
 *   3-5   dv     velocity error, computed - true (E, N, U), m/s
 *   6-8   dp     latitude, longitude (rad) and height (m) errors, computed - true
 *   9-17  x_g    gyro: scale factors dKgx, dKgy, dKgz; misalignment angles dgamma_yz,
 *                dgamma_zy, dgamma_zx (rad); biases eps_x, eps_y, eps_z (rad/s)
 *   18-29 x_a    accelerometer: scale factors dKax, dKay, dKaz; misalignment angles
 *                dalpha_xz, dalpha_xy, dalpha_yz, dalpha_yx, dalpha_zy, dalpha_zx (rad);
 *                biases nabla_x, nabla_y, nabla_z (m/s^2)
 *   30-32 x_Ka2  second-order coefficients dKax2, dKay2, dKaz2 ((m/s^2)^-1)
 *   seed model (36):  33-35 x_r  inner lever arms along the own axes dr_xx, dr_yy, dr_zz (m)
 *   full model (39):  33-35 dr_x = the x accelerometer's position (x, y, z components, m),
 *                     36-38 dr_y = the y accelerometer's, both relative to the z
 *                     accelerometer (the reference point; see "lever arms" below)
 *   last  dt_a   (optional: 37 or 40 states) delay of the accelerometer samples behind
 *                the gyro samples (s)
 * The parameter states are the error left in the compensation, true - estimated; the
 * estimates themselves (param[], the layout below) are fed back after every update.
 *
 * param[] (GF_SYSCAL_N_PARAMS, SI, the same layout for both models): 0-2 gyro scale,
 * 3-5 gamma_yz, gamma_zy, gamma_zx, 6-8 gyro bias, 9-11 accelerometer scale, 12-17 the
 * six alphas, 18-20 accelerometer bias, 21-23 K_a2, 24-32 the accelerometers' positions
 * (row-major 3 x 3, row i = accelerometer i, gf_imu_errors.a_lever_pos_m), 33 the delay.
 * The seed model's lever states move the diagonal (24, 28, 32); the full model's move
 * rows x and y (24-29) and leave row z where param0 put it (0: the z accelerometer is the
 * reference point).
 *
 * Lever arms: a translation of all three accelerometers by the same vector is a change of
 * the reference point whose specific force the IMU reports: at rest it changes nothing,
 * so a calibration at rest cannot observe it (3 of the 9 position components). The full
 * model fixes it by taking the z accelerometer as the reference point (r_z = 0) and
 * estimates the 6 components of r_x and r_y; seed 001's model has the three along the
 * own axes (r_ii, reference point = the gyro triad's centre, S101), the special case
 * r_x = r_xx e_x - r_zz e_z, r_y = r_yy e_y - r_zz e_z of the full model's convention.
 *
 * Sensor model: gf_imu_error.h, with seed 001's angles (S107-S108; the seed's matrix
 * images are lost, the convention is stated in gfins_fmi.imu_errors and tested there):
 *   gyro:  w_out = (I + diag K_g)(I + N_g) w + eps,
 *          N_g = [[0, 0, 0], [-gamma_yz, 0, 0], [gamma_zy, -gamma_zx, 0]]
 *   accel: u_i = [(I + N_a) f]_i + e_i^T W r_i,  a_i = (1 + K_a,i) u_i + K_a2,i u_i^2 + nabla_i,
 *          N_a = [[0, alpha_xz, -alpha_xy], [-alpha_yz, 0, alpha_yx], [alpha_zy, -alpha_zx, 0]],
 *          W = [w_dot x] + [w x]^2, whose diagonal is -c(w),
 *          c(w) = [w_y^2 + w_z^2, w_x^2 + w_z^2, w_x^2 + w_y^2] (seed S603,
 *          a_xb = a_xc + (w_y^2 + w_z^2) r_x); w_dot: the backward difference of the
 *          compensated rates (gf_imu_compensate_step)
 *   delay: the accelerometers sample f^m(t - dt_a); compensated with the rotation part
 *          of the specific force's change, f(t) = f(t - dt_a) - dt_a (w_nm^m x f^m),
 *          w_nm^m = w_im^m - C_n^m w_ie^n (exact to first order on a static base).
 *   gravity: the site's gravity is WGS-84 normal gravity g(L, h) + dg (gravity_anomaly_m_s2);
 *          the filter removes dg from the specific force, f -= dg C_n^m e_U (gf_sins
 *          navigates with normal gravity).
 * Errors of the compensated outputs (seed 001 S2, first order in the states):
 *   dw^m = dK_g w^m + eps,                       dK_g = diag(dKg) + dN_g
 *   df^m = dK_a f^m + dK_a2 (f^m)^2 + nabla + [W_i . dr_i]_i + dt_a (w_nm^m x f^m),
 *                                                dK_a = diag(dKa) + dN_a
 * Error equations: the navigation blocks of gf_ins_model (phi, dv, dp) with
 *   phi' += -C_m^n dw^m,  dv' += C_m^n df^m,  parameters constant (x' = 0);
 * white noise: gyro angle random walk into phi, accelerometer velocity random walk into
 * dv (C diag(q) C^T = q I for equal axes).
 * Discretisation over each propagation interval T (prop_interval_s of samples): F with
 * the interval's mean w, w_dot, f, f o f, c(w), w_i w_j and rotation part of df/dt,
 * C_m^n at the interval's mid-point (normalised mean of the end quaternions); the
 * specific force in F is that of a body at rest on the base, f^m = g C_n^m e_U (g: normal
 * gravity at the navigated position plus the anomaly), not the measured one, whose white
 * noise would correlate with the velocity it drives and make unobserved parameters look
 * observed (e.g. a horizontal axis's scale factor);
 * Phi = I + F T + (F T)^2/2; P <- Phi (P + Qc T/2) Phi^T + Qc T/2 on the engine's
 * structured predict. gf_syscal_error_model evaluates F and H at one sample (for checks).
 * Measurement (S303): the system rests on its base (the turntable turns the IMU about its
 * centre), z = v^n - 0 = dv, H = [0 I3 0], R = vel_std^2 I3, every update_interval_s.
 * Feedback (S304) after every update: q_m^n <- q(phi) (x) q_m^n, v <- v - dv, position
 * <- position - dp, param += x(9..), x <- 0; the compensation is rebuilt from param.
 * With feedback_params = 0 only the navigation states are fed back: param stays the
 * linearisation point of the whole run and the parameter states carry the corrections
 * (x <- Phi x between updates; the estimate is param + x, gf_syscal_estimate). A caller
 * that runs the record again from that estimate iterates the linearisation (Gauss-Newton):
 * with wide priors, seed 001's feedback moves weakly observed parameters by thousands of
 * ppm in the first static interval (a combination of them is observed, not each), and the
 * model's second-order terms in those excursions (scale times bias, ...) stay in the
 * result (several sigma on noisy records, docs/rotating_ins.md); a fixed linearisation
 * point keeps them out.
 */
#ifndef GF_SYSCAL_H
#define GF_SYSCAL_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "est/gf_kalman.h"
#include "nav/gf_imu_error.h"
#include "nav/gf_sins.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_SYSCAL_N_BASE 36          /* the seed's filter */
#define GF_SYSCAL_N_FULL 39          /* the full lever-arm model */
#define GF_SYSCAL_MAX_STATES 40      /* the full model with the accelerometer delay */
#define GF_SYSCAL_N_PARAMS 34        /* param[]: the layout above */
#define GF_SYSCAL_P_LEVER 24         /* param[]: the positions, row-major 3 x 3 */
#define GF_SYSCAL_P_DELAY 33         /* param[]: the delay */
#define GF_SYSCAL_IDX_PHI 0
#define GF_SYSCAL_IDX_DV 3
#define GF_SYSCAL_IDX_DP 6
#define GF_SYSCAL_IDX_KG 9
#define GF_SYSCAL_IDX_GAMMA 12
#define GF_SYSCAL_IDX_EPS 15
#define GF_SYSCAL_IDX_KA 18
#define GF_SYSCAL_IDX_ALPHA 21
#define GF_SYSCAL_IDX_NABLA 27
#define GF_SYSCAL_IDX_KA2 30
#define GF_SYSCAL_IDX_R 33           /* the lever-arm states (3 seed, 6 full) */
#define GF_SYSCAL_IDX_DELAY 36       /* the delay state of the seed model (37 states) */
#define GF_SYSCAL_IDX_DELAY_FULL 39  /* the delay state of the full model (40 states) */

/* Why gf_syscal_init refused a configuration (*bad). */
#define GF_SYSCAL_BAD_N_STATES 1
#define GF_SYSCAL_BAD_SITE 2         /* |lat| >= 89 deg, height outside [-1000, 1e5] m or
                                        |gravity anomaly| >= 0.1 m/s^2 */
#define GF_SYSCAL_BAD_INTERVALS 3    /* prop_interval_s or update_interval_s <= 0 */
#define GF_SYSCAL_BAD_VEL_STD 4
#define GF_SYSCAL_BAD_NOISE 5
#define GF_SYSCAL_BAD_P0 6           /* a prior std outside [1e-150, 1e150], or an attitude one above 1 rad */
#define GF_SYSCAL_BAD_PARAM0 7       /* initial parameters outside gf_imu_errors_check's range */
#define GF_SYSCAL_BAD_LIMITS 8
#define GF_SYSCAL_BAD_FEEDBACK 9     /* feedback_params not 0 or 1 */

typedef struct gf_syscal_config {
    int32_t n_states;                /* 36 (seed), 39 (full); 37, 40 with the delay */
    double lat_rad, lon_rad, h_m;    /* the site (known; seed 001 S501) */
    double prop_interval_s;          /* covariance propagation interval (default 0.1 s) */
    double update_interval_s;        /* zero-velocity updates (default 1 s) */
    double vel_std_m_s;              /* std of the zero-velocity measurement (default 1 mm/s) */
    double gyro_arw_rad_sqrt_s;      /* angle random walk (white rate noise density) */
    double accel_vrw_m_s_sqrt_s;     /* velocity random walk */
    double p0_std[GF_SYSCAL_MAX_STATES]; /* prior 1-sigma per state (state order, SI) */
    double max_rate_rad_s;           /* |w| above this: an absurd sample (default 50) */
    double max_specific_force_m_s2;  /* |f| above this: an absurd sample (default 1000) */
    double max_gap_s;                /* a sample interval above this is a gap (default 0.5 s) */
    double gravity_anomaly_m_s2;     /* the site's gravity minus WGS-84 normal gravity (default 0) */
    int32_t feedback_params;         /* 1: parameters fed back after every update (seed 001 S304,
                                        the default); 0: only the navigation states are, the
                                        parameter corrections stay states (gf_syscal_estimate) */
} gf_syscal_config;

typedef struct gf_syscal {
    gf_syscal_config cfg;
    gf_kalman kf;
    gf_sins_state nav;                    /* the IMU frame's navigation (body = m) */
    double param[GF_SYSCAL_N_PARAMS];     /* estimates, state order 9.. (SI) */
    gf_imu_errors comp;                   /* the compensation built from param */
    double t_s;                           /* time of the last sample */
    double acc_T_s;                       /* propagation interval so far */
    double acc_w[3], acc_f[3], acc_f2[3], acc_c[3], acc_fdot[3]; /* integrals over it */
    double acc_wxy[3], acc_wdot[3];       /* of w_x w_y, w_x w_z, w_y w_z and of w_dot */
    double acc_q0[4];                     /* C_m^n at its start */
    double w_prev[3];                     /* the last compensated rate (w_dot) */
    int32_t have_prev;
    double since_update_s;
    uint64_t n_samples, n_updates;
    uint64_t n_refused;                   /* updates refused: estimates beyond the model */
} gf_syscal;

/* One zero-velocity update (the history of a run). */
typedef struct gf_syscal_epoch {
    double t_s;
    double param[GF_SYSCAL_N_PARAMS];     /* estimates after the feedback (SI) */
    double std[GF_SYSCAL_MAX_STATES];     /* 1-sigma of each state after the update */
    double residual_m_s[3];               /* v^n before the update (the innovation) */
    double nis;                           /* r^T S^-1 r */
    double refused;                       /* 1: the update was refused (gf_syscal_run) */
} gf_syscal_epoch;

/* Defaults: 36 states, propagation every 0.1 s, updates every 1 s, vel_std 1 mm/s, no
 * white noise, limits 50 rad/s, 1000 m/s^2, gap 0.5 s; site and p0_std zero (set them). */
gf_status gf_syscal_config_default(gf_syscal_config *cfg);

/* The sensor-error model (gf_imu_errors, at its reference temperature) of the
 * parameters param (GF_SYSCAL_N_PARAMS, the layout above; the delay as a_delay_s).
 * Errors: GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_PARAMETER (outside
 * gf_imu_errors_check's range). */
gf_status gf_syscal_errors(const double *param, gf_imu_errors *errors);

/* Starts the filter at t0_s at the site, at rest, with the IMU attitude q_mn0 (from the
 * coarse alignment), the parameter estimates param0 (GF_SYSCAL_N_PARAMS; NULL = 0) and
 * the prior cfg->p0_std. Errors: GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT,
 * GF_ERR_BAD_PARAMETER with *bad (may be NULL) = GF_SYSCAL_BAD_*. */
gf_status gf_syscal_init(gf_syscal *s, const gf_syscal_config *cfg, const double *q_mn0,
                         const double *param0, double t0_s, int *bad);

/* n raw IMU samples: increments dtheta (rad), dv (m/s) (n x 3) over the intervals that
 * end at t_s (n, strictly increasing, after the filter's time). Each is compensated,
 * navigated, accumulated; the covariance is propagated every prop_interval_s and the
 * zero-velocity update made every update_interval_s (then written to epochs[*n_epochs]
 * while *n_epochs < capacity; epochs may be NULL). An update whose estimates would leave
 * the error model's range (gf_imu_errors_check; |delay| < 1 s) is refused: the filter
 * stays as before it, the epoch says so and n_refused counts it (the model lacks a term
 * the data hold, or the prior or the noise is far off). *n_done: samples processed. A
 * refused sample (non-finite, time, range) stops the run with *s as after the last good
 * one; a divergence leaves *s where it failed (restart from a saved copy).
 * Errors: GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_TIME (times not increasing or a gap above
 * max_gap_s), GF_ERR_OUT_OF_RANGE (|w| or |f| beyond the limits), GF_ERR_DIVERGED (the
 * covariance lost positivity or the navigation its domain), GF_ERR_BAD_SIZE (a damaged
 * struct). */
gf_status gf_syscal_run(gf_syscal *s, size_t n, const double *t_s, const double *dtheta_rad,
                        const double *dv_m_s, gf_syscal_epoch *epochs, size_t capacity,
                        size_t *n_epochs, size_t *n_done);

/* The covariance (n x n, n = cfg.n_states) and the 1-sigma of each state. */
gf_status gf_syscal_covariance(const gf_syscal *s, double *P, double *std);

/* The current estimates (GF_SYSCAL_N_PARAMS, the layout above): param plus the parameter
 * states not yet fed back (feedback_params = 0), or param. */
gf_status gf_syscal_estimate(const gf_syscal *s, double *param);

/* Which param[] entry state k (9 <= k < n_states) moves (-1: a navigation state or none). */
int32_t gf_syscal_param_index(int32_t n_states, int32_t k);

/* The filter's compensation of one raw sample with the parameters param (SI, the layout
 * above; the filter's own estimates when NULL), at the filter's navigation state: rates
 * dtheta / dt_s and dv / dt_s through the error model (w_dot from w_prev, NULL: 0), the
 * delay and the gravity anomaly; w_m, f_m (IMU axes). With gf_syscal_error_model this
 * makes the filter's F checkable: its parameter columns are the derivatives of
 * -C_m^n w_m and C_m^n f_m with respect to param (sign: states are true - estimated).
 * Errors: GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_TIME (dt_s <= 0),
 * GF_ERR_BAD_PARAMETER (param outside the error model), GF_ERR_OUT_OF_RANGE. */
gf_status gf_syscal_compensate(const gf_syscal *s, const double *param, const double *dtheta_rad,
                               const double *dv_m_s, double dt_s, const double *w_prev,
                               double *w_m, double *f_m);

/* The error model at one sample: F (n x n, continuous time, row-major, n = n_states) with
 * the compensated rate w_m, angular acceleration w_dot_m and specific force f_m (IMU axes)
 * as the interval's means and C_m^n, v, position of the filter's navigation state; H
 * (3 x n) of the zero-velocity update. Either output may be NULL. Errors:
 * GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_SIZE (a damaged struct). */
gf_status gf_syscal_error_model(const gf_syscal *s, const double *w_m, const double *w_dot_m,
                                const double *f_m, double *F, double *H);
/* CDEF END */

/* Checks a filter struct handed in by a caller: n_states, the engine's size, the
 * navigation state (gf_sins_state_check), the compensation model, finite numbers. */
gf_status gf_syscal_check(const gf_syscal *s);

#ifdef __cplusplus
}
#endif

#endif /* GF_SYSCAL_H */
