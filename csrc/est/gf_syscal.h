/* gf_syscal.h — system-level calibration of a rotating INS (seed 001, steps S2-S5): the
 * 36-state Kalman filter on the Kalman engine, with an optional 37th state for the time
 * offset of the accelerometer samples relative to the gyro samples.
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
 *   33-35 x_r    inner lever arms drx, dry, drz (m)
 *   36    dt_a   (optional) delay of the accelerometer samples behind the gyro samples (s)
 * The parameter states are the error left in the compensation, true - estimated; the
 * estimates themselves (param[], state order from 9) are fed back after every update.
 *
 * Sensor model: gf_imu_error.h, with seed 001's angles (S107-S108; the seed's matrix
 * images are lost, the convention is stated in gfins_fmi.imu_errors and tested there):
 *   gyro:  w_out = (I + diag K_g)(I + N_g) w + eps,
 *          N_g = [[0, 0, 0], [-gamma_yz, 0, 0], [gamma_zy, -gamma_zx, 0]]
 *   accel: u = (I + N_a) f - r o c(w),  a_i = (1 + K_a,i) u_i + K_a2,i u_i^2 + nabla_i,
 *          N_a = [[0, alpha_xz, -alpha_xy], [-alpha_yz, 0, alpha_yx], [alpha_zy, -alpha_zx, 0]],
 *          c(w) = [w_y^2 + w_z^2, w_x^2 + w_z^2, w_x^2 + w_y^2] (the inner lever arms: seed
 *          S603, a_xb = a_xc + (w_y^2 + w_z^2) r_x)
 *   delay: the accelerometers sample f^m(t - dt_a); compensated with the rotation part
 *          of the specific force's change, f(t) = f(t - dt_a) - dt_a (w_nm^m x f^m),
 *          w_nm^m = w_im^m - C_n^m w_ie^n (exact to first order on a static base).
 * Errors of the compensated outputs (seed 001 S2, first order in the states):
 *   dw^m = dK_g w^m + eps,                       dK_g = diag(dKg) + dN_g
 *   df^m = dK_a f^m + dK_a2 (f^m)^2 + nabla - dr o c(w^m) + dt_a (w_nm^m x f^m),
 *                                                dK_a = diag(dKa) + dN_a
 * Error equations: the navigation blocks of gf_ins_model (phi, dv, dp) with
 *   phi' += -C_m^n dw^m,  dv' += C_m^n df^m,  parameters constant (x' = 0);
 * white noise: gyro angle random walk into phi, accelerometer velocity random walk into
 * dv (C diag(q) C^T = q I for equal axes).
 * Discretisation over each propagation interval T (prop_interval_s of samples): F with
 * the interval's mean w, f, f o f, c(w) and rotation part of df/dt, C_m^n at the
 * interval's mid-point (normalised mean of the end quaternions); Phi = I + F T + (F T)^2/2;
 * P <- Phi (P + Qc T/2) Phi^T + Qc T/2 on the engine's structured predict.
 * Measurement (S303): the system rests on its base (the turntable turns the IMU about its
 * centre), z = v^n - 0 = dv, H = [0 I3 0], R = vel_std^2 I3, every update_interval_s.
 * Feedback (S304) after every update: q_m^n <- q(phi) (x) q_m^n, v <- v - dv, position
 * <- position - dp, param += x(9..), x <- 0; the compensation is rebuilt from param.
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
#define GF_SYSCAL_MAX_STATES 37      /* with the accelerometer delay */
#define GF_SYSCAL_N_PARAMS 28        /* param[]: states 9..36 */
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
#define GF_SYSCAL_IDX_R 33
#define GF_SYSCAL_IDX_DELAY 36

/* Why gf_syscal_init refused a configuration (*bad). */
#define GF_SYSCAL_BAD_N_STATES 1
#define GF_SYSCAL_BAD_SITE 2         /* |lat| >= 89 deg or height outside [-1000, 1e5] m */
#define GF_SYSCAL_BAD_INTERVALS 3    /* prop_interval_s or update_interval_s <= 0 */
#define GF_SYSCAL_BAD_VEL_STD 4
#define GF_SYSCAL_BAD_NOISE 5
#define GF_SYSCAL_BAD_P0 6           /* a prior std outside [1e-150, 1e150], or an attitude one above 1 rad */
#define GF_SYSCAL_BAD_PARAM0 7       /* initial parameters outside gf_imu_errors_check's range */
#define GF_SYSCAL_BAD_LIMITS 8

typedef struct gf_syscal_config {
    int32_t n_states;                /* 36, or 37 with the accelerometer delay */
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
    double acc_q0[4];                     /* C_m^n at its start */
    double since_update_s;
    uint64_t n_samples, n_updates;
} gf_syscal;

/* One zero-velocity update (the history of a run). */
typedef struct gf_syscal_epoch {
    double t_s;
    double param[GF_SYSCAL_N_PARAMS];     /* estimates after the feedback (SI) */
    double std[GF_SYSCAL_MAX_STATES];     /* 1-sigma of each state after the update */
    double residual_m_s[3];               /* v^n before the update (the innovation) */
    double nis;                           /* r^T S^-1 r */
} gf_syscal_epoch;

/* Defaults: 36 states, propagation every 0.1 s, updates every 1 s, vel_std 1 mm/s, no
 * white noise, limits 50 rad/s, 1000 m/s^2, gap 0.5 s; site and p0_std zero (set them). */
gf_status gf_syscal_config_default(gf_syscal_config *cfg);

/* The sensor-error model (gf_imu_errors, at its reference temperature) of the
 * parameters param (GF_SYSCAL_N_PARAMS, state order from 9; the delay is not part of it).
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
 * while *n_epochs < capacity; epochs may be NULL). *n_done: samples processed. A refused
 * sample (non-finite, time, range) stops the run with *s as after the last good one; a
 * divergence leaves *s where it failed (restart from a saved copy).
 * Errors: GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_TIME (times not increasing or a gap above
 * max_gap_s), GF_ERR_OUT_OF_RANGE (|w| or |f| beyond the limits), GF_ERR_DIVERGED (the
 * covariance lost positivity, the estimates left the model's range or the navigation its
 * domain), GF_ERR_BAD_SIZE (a damaged struct). */
gf_status gf_syscal_run(gf_syscal *s, size_t n, const double *t_s, const double *dtheta_rad,
                        const double *dv_m_s, gf_syscal_epoch *epochs, size_t capacity,
                        size_t *n_epochs, size_t *n_done);

/* The covariance (n x n, n = cfg.n_states) and the 1-sigma of each state. */
gf_status gf_syscal_covariance(const gf_syscal *s, double *P, double *std);
/* CDEF END */

/* Checks a filter struct handed in by a caller: n_states, the engine's size, the
 * navigation state (gf_sins_state_check), the compensation model, finite numbers. */
gf_status gf_syscal_check(const gf_syscal *s);

#ifdef __cplusplus
}
#endif

#endif /* GF_SYSCAL_H */
