/* gf_ins_gnss.h — integrated navigation: an error-state Kalman filter (EKF or UKF) that
 * corrects the strapdown mechanization (gf_sins) with GNSS position and velocity,
 * barometric height, odometer speed, non-holonomic constraints and zero-velocity /
 * zero-angular-rate updates at standstill, on the one Kalman engine (gf_kalman).
 *
 * States (seed 004 eq. 17, its order; ENU navigation frame, body right-front-up):
 *   0-2   dv     velocity error v_computed - v_true (E, N, U), m/s
 *   3-5   dp     position error (dL rad, dlambda rad, dh m), computed - true
 *   6-8   phi    attitude error, C_b^n(computed) = (I - [phi x]) C_b^n(true), rad (E, N, U)
 *   9-11  dbg    gyro bias not yet compensated, b_true - b_estimated, rad/s (body)
 *   12-14 dba    accelerometer bias not yet compensated, m/s^2 (body)
 * optional blocks, appended in this order when enabled (indices in gf_ins_filter.idx_*):
 *   dsg (3) gyro scale-factor error, dsa (3) accelerometer scale-factor error
 *           (dimensionless: measured = (1 + s) true + b), 15 + 6 = 21 states (issue 11);
 *   dbb (1) barometer bias b_true - b_estimated, m;  dko (1) odometer scale error;
 *   dmo (2) odometer boresight error (pitch, heading of the odometer axes in the body
 *           frame, true - estimated, rad; the nominal angles are cfg.odometer_mount_rad +
 *           the sensors[] correction, fed back like the other sensor estimates);
 *   transfer alignment against a master INS (issue 24; equations under "Transfer
 *   alignment" below; their estimates are the filter's transfer[] array, not sensors[]):
 *   dma (3) mounting error: heading, pitch, roll of the slave's (this IMU's) axes in the
 *           master's body axes, true - estimated, rad (a random constant);
 *   dla (3) lever-arm error: the slave IMU's position from the master IMU, master body
 *           axes, true - estimated, m (a random constant);
 *   dto (1) time-offset error: slave stamp - master stamp of one instant, true -
 *           estimated, s (a random constant);
 *   dfl (6) structural flexure: three angles added to the mounting's heading, pitch and
 *           roll (rad), then their rates (rad/s), a second-order Gauss-Markov process per
 *           axis (Kain & Cloutier, "Rapid transfer alignment for tactical weapon
 *           applications", AIAA 1989; the wing-flexure model of the transfer-alignment
 *           literature): f'' + 2 b f' + b^2 f = w, b = 2.146 / flexure_tau_s, E[w w] =
 *           4 b^3 sigma^2, stationary var(f) = sigma^2, var(f') = b^2 sigma^2.
 * Up to 15 + 6 + 4 + 13 = 38 states.
 * Sensor errors are first-order Gauss-Markov processes (seed 004: "first-order Markov
 * drifts"), x' = -x / tau + w, E[w w] = 2 sigma^2 / tau; tau = 0 makes a random constant.
 *
 * Continuous error model x' = F x + G w (Titterton & Weston, Strapdown Inertial
 * Navigation Technology, 2nd ed., ch. 12.3, with the transport-rate and gravity
 * couplings of the moving vehicle; gfins_fmi.error_models.ins_error_matrices is the
 * definition, tests/test_estimation.py compares this C code with it):
 *   phi' = -w_in x phi + d(w_in) - C_b^n dw_ib          dw_ib = dbg + diag(w_ib) dsg
 *   dv'  = f^n x phi + C_b^n df + v x (2 d(w_ie) + d(w_en)) - (2 w_ie + w_en) x dv + dg
 *                                                        df = dba + diag(f^b) dsa
 *   dL'  = dv_N / (R_M + h) - v_N dh / (R_M + h)^2
 *   dlambda' = dv_E / ((R_N + h) cos L) + v_E tan L dL / ((R_N + h) cos L)
 *              - v_E dh / ((R_N + h)^2 cos L)
 *   dh'  = dv_U,      dg = [0, 0, 2 g dh / (sqrt(R_M R_N) + h)]
 * (derivatives of the radii and of gravity with latitude are neglected: relative size
 * e^2 ~ 0.7% of terms that are themselves small). The navigation blocks (phi, dv, dp)
 * come from gf_ins_model (gf_ins_nav_blocks_sparse), shared with the calibration
 * filter; the sensor-error columns are this filter's. Noise w: accelerometer white noise
 * (velocity random walk) into dv through C_b^n, gyro white noise (angle random walk)
 * into phi through -C_b^n, one driving noise per sensor-error state.
 *
 * Discretisation over the propagation interval T (a number of IMU samples, or every
 * sample): Phi = I + F T + (F T)^2 / 2 (second-order series, F at the end of the
 * interval with the mean specific force and rate of the interval), process noise by the
 * trapezoidal rule P <- Phi (P + Qc T/2) Phi^T + Qc T/2, Qc = G diag(q) G^T; the
 * propagation skips the zeros of Phi - I: the model code marks the entries of F it fills
 * (F's structure, fixed by the configuration), A = Phi - I is formed over them and handed
 * with its structure to gf_kalman_predict_masked.
 *
 * UKF: the same states; sigma points of the error state (seed 004 eq. 25-28) are turned
 * into full navigation hypotheses (v = v_nom - dv, p = p_nom - dp, q = q(phi) q_nom,
 * sensor errors = estimate + state), each is moved over the propagation interval by the
 * mechanization (gf_sins_step) with the interval's summed, compensated increments, and
 * differenced against the nominal moved the same way (errors of this coarse step cancel
 * to first order); measurements are predicted from each hypothesis with the full
 * nonlinear models below. Additive process and measurement noise (seed 004 augments
 * the state with them, eq. 18 and 24; for additive noise this is the same transform with
 * alpha scaled by sqrt(N_augmented / N) up to the centre point's covariance weight).
 *
 * Closed loop: after every update (and, for the UKF, after every time update) the
 * estimated errors are fed back into the mechanization and the sensor-error estimates,
 * and the error state is reset to zero.
 *
 * Measurements (docs/estimation.md; z_err = prediction from the nominal - measurement):
 *   GNSS position: antenna at lever arm l_gnss (body), p_ant = p + C_b^n l (ENU metres).
 *   GNSS velocity: v_ant = v + C_b^n (w_eb^b x l),  w_eb^b = w_ib^b - C_n^b w_ie^n.
 *   barometer: h + b_baro.  odometer: (1 + k) [C_b^m (C_n^b v + w_eb^b x l_odo)]_y
 *   (forward), C_m^b = Rz(-heading_m) Rx(pitch_m) the odometer's mounting (boresight,
 *   odometer_mount_rad + the estimated correction; identity by default).  non-holonomic:
 *   [C_b^m (C_n^b v + w_eb^b x l_odo)]_x,z = 0.  With odometer_mount the rows of both
 *   take d/dpitch_m and d/dheading_m of C_b^m (exact derivatives of its entries, see
 *   gf_ins_meas.c).  ZUPT: v = 0.
 *   ZARU: w_ib^b - C_n^b w_ie^n = 0 (mean over the standstill detector's window).
 *   speed (tachometer, seed 003 section 1.2.2, its eq. 7-8 linearised; the scan lost the
 *   equations, so derived here): y = (1 + k) sqrt(v_E^2 + v_N^2), k the odometer scale
 *   state (one speed-scale state: a vehicle has an odometer or a tachometer), so
 *   dy = (1 + k) (v_E dv_E + v_N dv_N) / |v_h| - |v_h| dk. The seed's 2-D model: the
 *   AUV's depth comes from its depth sensor (a height measurement: GF_INS_MEAS_BARO with
 *   z = -depth + datum), the tachometer gives the horizontal speed through the water
 *   (no current, no lever-arm term: w x l is ~1e-3 of the speed on an AUV). At or below
 *   speed_min_m_s of INS horizontal speed the direction v_h / |v_h| is undefined or
 *   poorly known and the update is refused (logged GF_INS_REJECTED_LOW_SPEED).
 * Transfer alignment (issue 24; gf_ins_master.c). This filter runs the slave IMU (frame
 * s = the body b above); a master INS on the same host reports its attitude C_m^n,
 * velocity and position at its IMU, and its angular rate w_im^m (master axes: the
 * measurement's aux). The slave's axes in the master's: C_s^m = M(a) = Rz(-psi) Rx(theta)
 * Ry(gamma) (gf_sins.h's Euler convention), a = master_mount_rad + the transfer[]
 * mounting estimate + the flexure angles; r = master_lever_arm_m + the transfer[]
 * lever-arm estimate: the slave IMU from the master IMU in master axes; tau =
 * master_time_offset_s + the transfer[] estimate. A master value stamped t_m describes
 * the instant the slave stamps t_m + tau, so the prediction from the filter's state at
 * t_m is carried forward by tau (in the filter's direction of time, dir tau after
 * gf_ins_reverse) with the nominal's rates (their errors times tau are second order):
 *   R_tau = exp([wbar dir tau x]), wbar = (w_ib^s + C_s^m^T w_im^m) / 2 - C_n^s w_in^n
 *     (slave axes, both compensated/measured, the mean over tau to second order: the
 *     slave's rate at t_m, the master's at t_m + tau; less the navigation frame's turn
 *     w_in^n = w_ie^n + w_en^n of the nominal: the attitude's rate w_ns^s, so that the
 *     offset's column vanishes where the attitude stands still), D = C_s^n R_tau C_s^m^T
 *     the master attitude predicted at t_m + tau;
 *   master attitude: the small angle of D C_meas^T (n frame), y = log(D C_meas^T), z = 0
 *     (z carries the master's heading, pitch, roll; std: east, north, up rad);
 *   master velocity: v_m = v + dir tau a - D (w_im^m x r) + w_ie^n x (D r), a = C_s^n f^s
 *     + g^n the nominal's acceleration (Coriolis (2 w_ie + w_en) x v, 2e-5 m/s at 10 m/s
 *     over 15 ms, left out): the slave's velocity less the lever arm's rotation with the
 *     master's rate w_em^m = w_im^m - C_n^m w_ie^n (C (a x r) = (C a) x (C r));
 *   master position: p_m = p + dir tau v - D r (the nominal's local ENU metres).
 * Their H is exact at the nominal (tests/c/test_ins_meas.c: no allowance); the attitude's
 * columns go through J_l^-1 of the residual (log's derivative away from 0: the first
 * updates of an alignment see degrees). Without a measurement
 * (gf_ins_meas_model) the master's rate is taken as the slave's turned into master axes
 * and the attitude's reference is the nominal's own D. The master's own errors enter
 * as the measurement noise (std); the velocity's time-offset term uses the nominal's
 * specific force and rate, so H has no bias columns from it.
 * The models are one table of the kinds (gf_ins_meas.c: per kind its rows, prediction
 * and Jacobian, one section each); gf_ins_meas_kind_info enumerates it and
 * gf_ins_meas_model evaluates one kind at the filter's state. The linearised models H
 * leave out one small term: the Earth rate in w_eb^b turns with the attitude and the
 * latitude, which moves the GNSS velocity, odometer and NHC predictions by at most
 * |w_ie| |l| (7.3e-5 m/s per rad for l = 1 m) and ZARU's by |w_ie| per rad of latitude;
 * their H has no such entries (tests/c/test_ins_meas.c bounds the difference).
 * Measurements carry their time of validity; the IMU interval that contains it is
 * split there (increments in proportion to time, rates interpolated linearly), the
 * covariance is propagated to that instant and the update is made there. A measurement
 * that arrives late (valid before the current sample, by up to max_latency_s, within the
 * last GF_INS_HISTORY samples) is predicted from the nominal state of its time of
 * validity (kept, interpolated between samples) and corrects the current state, the
 * error state being taken as constant over the delay (its change over a delay of
 * 0.1-0.5 s is second order for the slowly varying INS errors).
 * Innovation gating: NIS r^T S^-1 r above the chi-square quantile of the configured
 * probability for m degrees of freedom rejects the measurement (logged).
 *
 * Reverse-time filtering (seed 003 section 2, its eq. 20-36: the reverse navigation
 * algorithm; the scan lost the equations, so derived here). With tau = -t the
 * mechanization is the forward one with (w_ib, f, v, w_ie) -> (-w_ib, f, -v, -w_ie)
 * (gf_sins.h). gf_ins_reverse() turns the filter around: the nominal through
 * gf_sins_reverse (v and the Earth-rate sign negated; error model and measurement
 * models take the Earth rate with that sign), and the error state x_r = D x,
 * P_r = D P D with D = diag(-1 on dv, dbg and the flexure rates, +1 elsewhere). Why: dv_r = v_r,computed -
 * v_r,true = -dv; the gyro increments are negated, so the bias the reverse filter sees
 * is -b (dbg_r = -dbg, its estimate negated too); attitude, position, accelerometer
 * bias (f unchanged), scale factors ((1 + s)(-w) - b keeps s) and barometer/odometer
 * errors (scale and boresight angles: the odometer axes do not turn with time) are
 * unchanged; so are the mounting, lever arm and time offset (an offset between two
 * clocks; the predictions carry it forward by dir tau), while a flexure rate, a time
 * derivative, changes sign with its estimate (the flexure's damping -2 b keeps its sign
 * like the Gauss-Markov decays below). Check on F: with x_r = D x, dx_r/dtau = -D F D x_r, and the
 * forward formula of F evaluated on the reversed nominal (-v, -w_ie, -w_en, -w_ib, same
 * f, C, position) gives exactly -D F D block by block (e.g. phi-phi: -[w_in x] changes
 * sign, phi-dv: dw_en/dv keeps it, dv-phi: [f^n x] keeps it, dv-dv: -(2 w_ie + w_en) x
 * changes it), except the Gauss-Markov decays -1/tau, which keep their sign: a
 * stationary first-order Markov process has the same statistics in reversed time, so
 * that is the right backward model (random constants, tau = 0: exact). Reversing twice
 * is the identity on x, P and the nominal. Measurements in reverse are handed in as
 * recorded (true time): GNSS and master velocity, the master's rate and odometer speed
 * are negated inside, the
 * tachometer speed magnitude and positions/heights are unchanged. Delayed measurements
 * (max_latency_s) are used forward only; in reverse they are stale.
 */
#ifndef GF_INS_GNSS_H
#define GF_INS_GNSS_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "est/gf_kalman.h"
#include "nav/gf_sins.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_INS_EKF 0
#define GF_INS_UKF 1

#define GF_INS_IDX_VEL 0
#define GF_INS_IDX_POS 3
#define GF_INS_IDX_ATT 6
#define GF_INS_IDX_BG 9
#define GF_INS_IDX_BA 12
#define GF_INS_BASE_STATES 15
#define GF_INS_MAX_STATES 38

/* Sensor-error estimates, in this order in every array of them ("sensors"):
 * gyro bias (3, rad/s), accelerometer bias (3, m/s^2), gyro scale (3), accelerometer
 * scale (3), barometer bias (m), odometer scale, odometer boresight correction (pitch,
 * heading, rad: added to cfg.odometer_mount_rad). */
#define GF_INS_N_SENSORS 16

/* Transfer-alignment estimates (the filter's transfer[] array, in this order): mounting
 * correction heading, pitch, roll (rad, added to cfg.master_mount_rad), lever-arm
 * correction x, y, z (m, master axes, added to cfg.master_lever_arm_m), time-offset
 * correction (s, added to cfg.master_time_offset_s), flexure angles heading, pitch, roll
 * (rad), flexure rates (rad/s). */
#define GF_INS_N_TRANSFER 13

/* Measurement types */
#define GF_INS_MEAS_GNSS_POS 1     /* z: antenna lat rad, lon rad, h m; std: E, N, U m */
#define GF_INS_MEAS_GNSS_VEL 2     /* z: antenna v_E, v_N, v_U m/s; std: m/s */
#define GF_INS_MEAS_BARO 3         /* z[0]: barometric height m; std[0] m */
#define GF_INS_MEAS_ODO 4          /* z[0]: forward speed m/s; std[0] m/s */
#define GF_INS_MEAS_NHC 5          /* internal: lateral and vertical body velocity 0 */
#define GF_INS_MEAS_ZUPT 6         /* internal: velocity 0 at standstill */
#define GF_INS_MEAS_ZARU 7         /* internal: angular rate w.r.t. the Earth 0 at standstill */
#define GF_INS_MEAS_SPEED 8        /* z[0]: horizontal speed magnitude m/s (tachometer, seed
                                      003); std[0] m/s */
#define GF_INS_MEAS_MASTER_VEL 9   /* z: master IMU velocity E, N, U m/s; std m/s; aux: the
                                      master's angular rate w_im^m rad/s (master axes) */
#define GF_INS_MEAS_MASTER_ATT 10  /* z: master heading, pitch, roll rad; std: E, N, U rad
                                      (small angles); aux: w_im^m rad/s */
#define GF_INS_MEAS_MASTER_POS 11  /* z: master IMU lat rad, lon rad, h m; std: E, N, U m;
                                      aux: w_im^m rad/s (unused) */
#define GF_INS_N_MEAS_KINDS 12     /* measurement type codes are 1 .. GF_INS_N_MEAS_KINDS - 1 */

/* Outcome of one update */
#define GF_INS_ACCEPTED 0
#define GF_INS_REJECTED_GATE 1     /* NIS above the gate */
#define GF_INS_REJECTED_SINGULAR 2 /* innovation covariance not positive definite */
#define GF_INS_REJECTED_STALE 3    /* time of validity at or before the filter's time */
#define GF_INS_FORCED 4            /* applied above the gate: the previous gate_reset_count
                                      of its kind were all rejected (a gate that rejects
                                      everything after a divergence would never recover) */
#define GF_INS_REJECTED_LOW_SPEED 5 /* speed update refused: INS horizontal speed below
                                      speed_min_m_s (direction of v_h undefined) */

/* The filter's settings. Every field is one row of the settings table
 * (gfins_fmi/estimation/settings.py): the same name in C, in Python's FilterConfig and as
 * the gfins_ins_gnss FMU parameter, with its unit, bounds and meaning; gf_ins_init checks
 * them and names a refused one (gf_ins_config_field). Process noise in SI. */
typedef struct gf_ins_noise {
    double gyro_arw_rad_sqrt_s;        /* gyro white noise (angle random walk), rad/sqrt(s) */
    double accel_vrw_m_s_sqrt_s;       /* accelerometer white noise (velocity r.w.), m/s/sqrt(s) */
    double gyro_bias_std_rad_s;        /* Gauss-Markov steady-state std */
    double gyro_bias_tau_s;            /* correlation time, s; 0 = random constant */
    double accel_bias_std_m_s2;
    double accel_bias_tau_s;
    double gyro_scale_std;             /* dimensionless */
    double gyro_scale_tau_s;
    double accel_scale_std;
    double accel_scale_tau_s;
    double baro_bias_std_m;
    double baro_bias_tau_s;
    double odometer_scale_std;
    double odometer_scale_tau_s;
    double odometer_mount_std_rad;     /* odometer boresight (pitch and heading) */
    double odometer_mount_tau_s;
    double flexure_std_rad;            /* structural flexure: stationary std of each angle */
    double flexure_tau_s;              /* its correlation time, s (> 0): b = 2.146 / tau */
} gf_ins_noise;

typedef struct gf_ins_config {
    int32_t input;                     /* GF_SINS_INPUT_INCREMENTS or GF_SINS_INPUT_RATES */
    int32_t coning;                    /* 1: coning/sculling corrections in the mechanization */
    int32_t filter;                    /* GF_INS_EKF or GF_INS_UKF */
    int32_t scale_factors;             /* 1: gyro and accelerometer scale-factor states (21) */
    int32_t baro_bias;                 /* 1: barometer bias state */
    int32_t odometer_scale;            /* 1: odometer scale-factor state */
    int32_t odometer_mount;            /* 1: odometer boresight states (pitch, heading) */
    double propagation_interval_s;     /* covariance propagation interval, s; 0: every sample */
    double max_imu_gap_s;              /* a longer IMU interval is an error (GF_ERR_BAD_TIME) */
    double max_rate_rad_s;             /* absurd-sample limits of the mechanization */
    double max_specific_force_m_s2;
    double ukf_alpha, ukf_beta, ukf_kappa;   /* seed 004: alpha small, beta 2, kappa 0 */
    gf_ins_noise noise;
    double gnss_lever_arm_m[3];        /* IMU -> GNSS antenna, body axes, m */
    double odometer_lever_arm_m[3];    /* IMU -> odometer wheel contact point, body axes, m */
    double gnss_position_std_floor_m[3];  /* GNSS position stds E, N, U below this are
                                             raised to it (m, >= 0; 0: as reported) */
    double gate_probability;           /* NIS gate probability in (0, 1); 0: no gate */
    int32_t gate_reset_count;          /* > 0: after this many consecutive gate rejections of
                                          one kind the next is applied (GF_INS_FORCED); 0: never */
    int32_t nhc;                       /* 1: non-holonomic constraint updates */
    double nhc_std_m_s;
    double nhc_interval_s;             /* at most one NHC update per interval */
    int32_t zupt;                      /* 1: zero-velocity updates at detected standstill */
    double zupt_std_m_s;
    double zaru_std_rad_s;             /* > 0: also zero-angular-rate updates */
    double zupt_interval_s;
    double standstill_window_s;        /* standstill detector averaging time, s */
    double standstill_accel_std_m_s2;  /* standstill: std of |f| over the window below this */
    double standstill_gyro_rad_s;      /* ... and mean |w| over the window below this */
    double max_latency_s;              /* > 0: measurements valid up to this long before the
                                          current sample are used (delayed update, see above);
                                          older ones, and all past ones with 0, are stale */
    double speed_min_m_s;              /* GF_INS_MEAS_SPEED refused at or below this INS
                                          horizontal speed, m/s (>= 0; default 0.5) */
    double odometer_mount_rad[2];      /* odometer boresight: pitch (nose-up +) and heading
                                          (clockwise +) of its measuring axes in the body
                                          frame, rad, |.| < pi/2; 0, 0: body axes. The angles
                                          used are these + the sensors[] boresight correction
                                          (estimated with odometer_mount) */
    int32_t subsamples;                /* 1..4 IMU samples per navigation update in gf_ins_run
                                          (increments only; see gf_ins_run); 0 or 1: one */
    /* transfer alignment against a master INS (see "Transfer alignment" above) */
    int32_t master_mount;              /* 1: mounting-error states (heading, pitch, roll) */
    int32_t master_lever;              /* 1: lever-arm error states (x, y, z) */
    int32_t master_time_offset;        /* 1: time-offset error state */
    int32_t flexure;                   /* 1: flexure states (3 angles, 3 rates) */
    double master_mount_rad[3];        /* nominal heading, pitch, roll of the slave's axes in
                                          the master's, rad (|pitch| < pi/2) */
    double master_lever_arm_m[3];      /* nominal slave IMU position from the master IMU,
                                          master axes right, front, up, m */
    double master_time_offset_s;       /* nominal slave stamp - master stamp, s */
} gf_ins_config;

typedef struct gf_ins_meas {
    int32_t type;                   /* GF_INS_MEAS_GNSS_POS .. GF_INS_MEAS_ODO, GF_INS_MEAS_SPEED */
    double t_s;                     /* time of validity */
    double z[3];
    double std[3];                  /* > 0 */
    double aux[3];                  /* what a kind reads besides z (the master kinds: the
                                       master's angular rate w_im^m, rad/s, master axes);
                                       0 for the others */
} gf_ins_meas;

/* One update, as logged. */
typedef struct gf_ins_innovation {
    double t_s;
    int32_t type;                   /* GF_INS_MEAS_* */
    int32_t status;                 /* GF_INS_ACCEPTED or GF_INS_REJECTED_* */
    int32_t m;                      /* rows used */
    double nis;                     /* r^T S^-1 r (NaN when not computed) */
    double r[3];                    /* z_err = predicted - measured (m, m/s, rad/s) */
    double s_std[3];                /* sqrt of the diagonal of S */
} gf_ins_innovation;

typedef struct gf_ins_log {
    size_t capacity, count;
    uint64_t n_dropped;             /* updates not logged because the log was full */
    gf_ins_innovation *entries;
} gf_ins_log;

/* What the smoother needs, one row per covariance epoch (propagation or measurement
 * instant). n = number of states; P as packed upper triangles (row by row, n(n+1)/2). */
typedef struct gf_ins_epochs {
    size_t capacity, count;
    double *t_s;                    /* capacity */
    double *nav;                    /* capacity x 10: q_bn (4), v ENU (3), lat, lon, h */
    double *sensors;                /* capacity x GF_INS_N_SENSORS */
    double *dx;                     /* capacity x n: correction fed back at this epoch */
    double *P_prior;                /* capacity x n(n+1)/2: before this epoch's updates */
    double *P_post;                 /* capacity x n(n+1)/2: after them */
    double *Phi;                    /* capacity x n*n: transition from the previous epoch */
} gf_ins_epochs;

/* Per-IMU-sample outputs (rows = samples; any pointer may be NULL except t_s, q_bn,
 * v_n_m_s, pos), or one row per navigation update when gf_ins_run groups samples
 * (cfg.subsamples > 1); n_rows says how many rows a call wrote. */
typedef struct gf_ins_output {
    double *t_s;                    /* n */
    double *q_bn;                   /* n x 4 */
    double *v_n_m_s;                /* n x 3 */
    double *pos;                    /* n x 3: lat rad, lon rad, h m */
    double *std;                    /* n x 9: velocity E N U m/s, position E N U m, attitude E N U rad */
    double *sensors;                /* n x GF_INS_N_SENSORS */
    int8_t *standstill;             /* n: detector output */
    size_t n_rows;                  /* written by gf_ins_run / gf_ins_run_backward */
    double *transfer;               /* n x GF_INS_N_TRANSFER (may be NULL): transfer-alignment
                                       estimates (true-time flexure rates) */
    double *state_std;              /* n x n_states (may be NULL): 1-sigma of every error
                                       state, sqrt of P's diagonal, in the layout's order */
} gf_ins_output;

/* The nominal state after one IMU sample, kept for delayed measurements. */
#define GF_INS_HISTORY 128
typedef struct gf_ins_history {
    double t_s;
    double q_bn[4];
    double v_n_m_s[3];
    double lat_rad, lon_rad, h_m;
    double w_ib_b_rad_s[3];
} gf_ins_history;

typedef struct gf_ins_filter {
    gf_ins_config cfg;
    int32_t n_states;
    int32_t idx_sg, idx_sa, idx_baro, idx_odo;   /* first index of each optional block; -1 absent */
    int32_t idx_mount;              /* odometer boresight block (2); -1 absent */
    int32_t idx_tmount, idx_tlever; /* transfer alignment: mounting (3), lever arm (3) */
    int32_t idx_toffset, idx_flex;  /* time offset (1), flexure (6: angles, rates) */
    gf_sins_state nav;              /* nominal navigation state (the corrected mechanization) */
    double sensors[GF_INS_N_SENSORS];/* estimated sensor errors, fed back */
    double transfer[GF_INS_N_TRANSFER]; /* transfer-alignment estimates, fed back */
    gf_kalman kf;                   /* error state (0 between updates) and covariance */
    gf_ukf_weights ukf_w;
    double t_s;                     /* time of the nominal state */
    int32_t have_sample;            /* 1 after the first IMU sample */
    double prev_gyro_raw[3], prev_accel_raw[3];  /* last raw sample (rates: for splitting) */
    double w_ib_b_rad_s[3];         /* latest compensated angular rate */
    double f_b_m_s2[3];             /* latest compensated specific force */
    double rate_lag_s;              /* how long before t_s the two above describe the body:
                                       half the last (part of a) sample for increments
                                       (their means), 0 for rates */
    double acc_T_s;                 /* accumulation since the last propagation */
    double acc_dtheta_rad[3], acc_dv_m_s[3];
    gf_sins_state nav0;             /* UKF: nominal at the start of the accumulation */
    double sensors0[GF_INS_N_SENSORS];
    double std9[9];                 /* output standard deviations (see gf_ins_output), kept
                                       current after every propagation and update */
    double inv_scale[6];            /* 1 / (1 + scale estimate): gyro x, y, z, accel x, y, z */
    double still_f[3], still_fn, still_fn2, still_w[3], still_wn, still_time_s;
    int32_t standstill;
    double last_nhc_t_s, last_zupt_t_s;
    double last_regular_t_s;        /* time of the last propagation on the regular grid */
    gf_ins_history hist[GF_INS_HISTORY];  /* ring of the last samples (max_latency_s > 0) */
    int32_t hist_head, hist_count;
    uint64_t n_imu, n_updates, n_rejected;
    int32_t gate_run[GF_INS_N_MEAS_KINDS]; /* consecutive gate rejections per measurement type */
} gf_ins_filter;

/* Defaults: increments with coning, EKF, 15 states, propagation every 0.1 s, IMU gap
 * limit 0.5 s, UKF alpha 0.5, beta 2, kappa 0... see gf_ins_config.c (= the settings
 * table's defaults); the IMU's noise zero (set it). */
gf_status gf_ins_config_default(gf_ins_config *cfg);

/* Checks every field; *bad (may be NULL) = 0 when valid, else the code of the first bad
 * field, which gf_ins_config_field names. Errors: GF_ERR_BAD_PARAMETER. */
gf_status gf_ins_config_check(const gf_ins_config *cfg, int32_t *bad);

/* The member name of gf_ins_config behind a field code of gf_ins_config_check or
 * gf_ins_init ("propagation_interval_s", "noise.gyro_arw_rad_sqrt_s", ...); NULL for a
 * code that names no field. The codes run 1 .. the number of fields. */
const char *gf_ins_config_field(int32_t code);

/* Where each error-state block starts (gf_ins_gnss.h's order; -1: not in this
 * configuration) and the number of states. */
typedef struct gf_ins_layout {
    int32_t n_states;
    int32_t idx_vel, idx_pos, idx_att, idx_bg, idx_ba;   /* 3 states each */
    int32_t idx_sg, idx_sa;                              /* 3 each (scale_factors) */
    int32_t idx_baro, idx_odo;                           /* 1 each */
    int32_t idx_mount;                                   /* 2 (odometer_mount) */
    int32_t idx_tmount, idx_tlever;                      /* 3 each (master_mount, _lever) */
    int32_t idx_toffset, idx_flex;                       /* 1 (master_time_offset), 6 */
} gf_ins_layout;

/* The state layout of a configuration. Errors: GF_ERR_BAD_PARAMETER (configuration). */
gf_status gf_ins_state_layout(const gf_ins_config *cfg, gf_ins_layout *layout);

/* Number of states of a configuration (15 .. 38). Errors: GF_ERR_BAD_PARAMETER. */
gf_status gf_ins_state_count(const gf_ins_config *cfg, int32_t *n_states);

/* The initial 1-sigma of each error block; the blocks a configuration has no states for
 * are not read. */
typedef struct gf_ins_initial_std {
    double velocity_std_m_s[3];        /* east, north, up */
    double position_std_m[3];          /* east, north, up */
    double attitude_std_rad[3];        /* east, north tilt; up: heading */
    double gyro_bias_std_rad_s[3];
    double accel_bias_std_m_s2[3];
    double gyro_scale_std[3];          /* dimensionless */
    double accel_scale_std[3];
    double baro_bias_std_m;
    double odometer_scale_std;
    double odometer_mount_std_rad[2];  /* pitch, heading */
    double master_mount_std_rad[3];    /* heading, pitch, roll */
    double master_lever_std_m[3];      /* x, y, z (master axes) */
    double master_time_offset_std_s;
} gf_ins_initial_std;

/* P0 (n x n, diagonal) of a configuration starting at lat_rad, h_m: the squares of the
 * stds in the filter's states (position east, north, up in m -> dlat, dlon in rad with the
 * WGS-84 radii at the start, dh in m; the flexure's stationary variances sigma^2 and
 * b^2 sigma^2 from cfg.noise) — the one P0 of the batch API, the smoother and the
 * FMU. Errors: GF_ERR_BAD_PARAMETER (configuration, or a std of a used block not finite
 * and > 0: *bad, if given, its 1-based block in gf_ins_initial_std's order, named by
 * gf_ins_initial_std_field), GF_ERR_OUT_OF_RANGE (|lat| at or beyond the limit, h not
 * finite; the limit is 89 deg: near a pole the ENU error
 * model, with dlon and a transport rate ~ tan L, is singular), or gf_earth_update's error for an absurd height. */
gf_status gf_ins_initial_covariance(const gf_ins_config *cfg, double lat_rad, double h_m,
                                    const gf_ins_initial_std *std, double *P0, int32_t *bad);

/* Transfer alignment's prior (gf_ins_master.c): a slave started from the master's
 * attitude turned by the nominal mounting, C_s^n = C_m^n M(a_nominal), has the mounting's
 * error as its attitude error, phi = G da with G = C_s^n [vee(M^T dM/da_k)]_k (a small
 * change of the mounting angles turns the slave's axes), so P0 of gf_ins_initial_covariance
 * (its attitude block then the master's own attitude uncertainty) becomes, in place,
 * P_phi,phi += G P_aa G^T, P_phi,a = G P_aa (and its transpose): the prior that the
 * slave's attitude and mounting errors cancel in the master's attitude. q_bn: the start
 * attitude. Errors: GF_ERR_NULL_POINTER, GF_ERR_BAD_PARAMETER (configuration, or no
 * mounting states), GF_ERR_NONFINITE_INPUT. */
gf_status gf_ins_master_start_covariance(const gf_ins_config *cfg, const double *q_bn, double *P0);

/* The gf_ins_initial_std member behind a block code of gf_ins_initial_covariance. */
const char *gf_ins_initial_std_field(int32_t code);

/* Starts the filter at t0_s with the nominal attitude q_bn, ENU velocity, position, the
 * sensor-error estimates sensors0 (GF_INS_N_SENSORS; NULL = 0) and the error covariance
 * P0 (n x n, symmetric positive definite). Errors: GF_ERR_BAD_PARAMETER (configuration,
 * with *bad naming the field: see gf_ins_config.c), GF_ERR_NONFINITE_INPUT,
 * GF_ERR_SINGULAR_GEOMETRY (P0 not positive definite). */
gf_status gf_ins_init(gf_ins_filter *f, const gf_ins_config *cfg, double t0_s,
                      const double *q_bn, const double *v_n_m_s, double lat_rad,
                      double lon_rad, double h_m, const double *sensors0, const double *P0,
                      int32_t *bad);

/* Checks a whole filter handed in by a caller (an FMU state restored from bytes): the
 * configuration, the state layout and every index (idx_*, kf.n, history ring), flags,
 * the nominal states (gf_sins_state_check: unit attitude quaternion, latitude inside the
 * poles, height in the Earth model's range), finite estimates, the covariance
 * (gf_kalman_check: finite, symmetric, positive definite within round-off, a positive
 * diagonal), the UKF weights of the configuration, and every other float of the struct
 * (finite; stds >= 0, scale corrections > 0; the stored nominal states of the delayed
 * updates). gf_ins_step checks the sizes and indices (integer compares) itself every
 * step. Errors: GF_ERR_BAD_SIZE, GF_ERR_BAD_PARAMETER, GF_ERR_NONFINITE_INPUT. */
gf_status gf_ins_filter_check(const gf_ins_filter *f);

/* Records the current state as the first epoch of *epochs (call once before a run
 * whose epochs feed the smoother). */
gf_status gf_ins_epochs_begin(gf_ins_filter *f, gf_ins_epochs *epochs);

/* One IMU sample whose interval ends at t_s (increments over (t_prev, t_s], or rates at
 * t_s), with the measurements valid inside that interval (sorted by time; t_prev <
 * t_m <= t_s; one at t_prev itself, the filter's time, is applied before the sample;
 * earlier ones are delayed or stale). epochs and log may be NULL. Errors: GF_ERR_BAD_TIME (t_s not after the
 * filter's time, interval above max_imu_gap_s, measurement outside the interval or not
 * sorted), GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_PARAMETER (bad measurement type or std),
 * GF_ERR_OUT_OF_RANGE (absurd sample), GF_ERR_DIVERGED (navigation or covariance left
 * its domain), GF_ERR_BAD_SIZE (epochs full). On error the filter is unchanged except
 * after GF_ERR_DIVERGED and GF_ERR_BAD_SIZE raised after the mechanization, where it holds
 * the state reached (see gf_ins_run). */
gf_status gf_ins_step(gf_ins_filter *f, double t_s, const double *gyro, const double *accel,
                      size_t n_meas, const gf_ins_meas *meas, gf_ins_epochs *epochs,
                      gf_ins_log *log);

/* n IMU samples (t_s n, gyro and accel n x 3) with n_meas measurements sorted by time
 * (processing order: time decreasing after gf_ins_reverse). A measurement valid at the
 * filter's time is applied there, before the first sample; earlier ones are delayed
 * updates (max_latency_s) or logged as stale; those after t_s[n-1] are
 * left for the next call). Row k of *out is the state after sample k.
 * *n_done = samples processed, *meas_done = measurements consumed; on an error the rows
 * before *n_done are valid and the filter holds the state after the last good sample.
 * Grouped samples (cfg.subsamples = m > 1, increments, forward in time, no ZUPT, no
 * max_latency_s): samples k .. k+m-1 make one navigation update (gf_sins_step_group's
 * m-sample coning and sculling) when the filter's sample count is a multiple of m at k,
 * no measurement is valid before the end of sample k+m-1, no propagation instant of the
 * regular grid falls on samples k .. k+m-2 (so choose propagation_interval_s a multiple of m
 * samples), the intervals are equal within 1 % and every sample passes the checks;
 * otherwise the samples are processed one by one as above. The outputs then have one row
 * per navigation update (a group's end or a single sample), out->n_rows of them; a
 * record cut into calls at multiples of m gives the same bits as one call. */
gf_status gf_ins_run(gf_ins_filter *f, size_t n, const double *t_s, const double *gyro,
                     const double *accel, size_t n_meas, const gf_ins_meas *meas,
                     gf_ins_output *out, gf_ins_epochs *epochs, gf_ins_log *log,
                     size_t *n_done, size_t *meas_done);

/* Turns the filter around in time (see "Reverse-time filtering" above): the covariance
 * is first propagated to the filter's time, then the nominal is reversed
 * (gf_sins_reverse), x and P flipped (D x, D P D), the gyro-bias estimate negated; the
 * NHC/ZUPT timers and the delayed-measurement history restart. Afterwards gf_ins_step
 * and gf_ins_run take samples with time decreasing (the processing order), the gyro as
 * recorded (negated inside), measurements as recorded and sorted by decreasing time;
 * outputs report true-time velocity and gyro bias. Calling it twice is the identity on
 * the nominal, x and P. Errors: GF_ERR_BAD_PARAMETER (layout), GF_ERR_DIVERGED. */
gf_status gf_ins_reverse(gf_ins_filter *f);

/* A reversed filter (gf_ins_reverse) walked backward over a record stored in recorded
 * order: t_s (n, increasing), gyro, accel (n x 3) as gf_ins_run takes them, the
 * filter's time = t_s[n-1]. Increments: sample k takes the state from t_s[k] to t_s[k-1]
 * (t_start_s for k = 0, the time at which the record's first interval starts); rates:
 * the samples at t_s[n-1] .. t_s[0] (t_start_s unused). Measurements sorted by increasing
 * time, as recorded; those after the filter's time are left (not consumed), those
 * before the end of the walk are left for a later call. Row k of *out (may be NULL) is
 * the state after processing sample k (true-time velocity and gyro bias).
 * *n_done = samples processed (from the last), *meas_done = measurements consumed.
 * Errors: GF_ERR_BAD_PARAMETER (filter not reversed), GF_ERR_BAD_TIME (filter's time not
 * t_s[n-1], times not increasing), the errors of gf_ins_step. */
gf_status gf_ins_run_backward(gf_ins_filter *f, size_t n, const double *t_s, const double *gyro,
                              const double *accel, double t_start_s, size_t n_meas,
                              const gf_ins_meas *meas, gf_ins_output *out, gf_ins_log *log,
                              size_t *n_done, size_t *meas_done);

/* The state at the end of one pass of gf_ins_forward_backward. */
typedef struct gf_ins_pass {
    int32_t direction;              /* +1 forward, -1 backward */
    double t_s;                     /* time reached (end of the record, or its start) */
    double q_bn[4];
    double v_n_m_s[3];              /* true-time velocity, ENU */
    double std9[9];                 /* as gf_ins_output.std */
    double sensors[GF_INS_N_SENSORS];  /* true-time convention */
    uint64_t n_updates, n_rejected; /* in this pass */
} gf_ins_pass;

/* Forward-backward processing of a stored alignment period (seed 003 section 2): the
 * filter (forward; its time t_start is where the record's first interval starts: before
 * t_s[0] for increments, at or before t_s[0] for rates) runs forward over the record,
 * then n_fb times: reversed, backward to the start, reversed, forward to the end,
 * carrying x and P across each reversal. The record (recorded order, as
 * gf_ins_run_backward) and its measurements (increasing time, inside the record's span)
 * are read in place, one call for all the passes (memory: the caller's arrays only).
 * passes (1 + 2 n_fb, may be NULL) receive the state at the end of each pass; log (may
 * be NULL) every update of every pass. On return the filter is forward at t_s[n-1],
 * ready to navigate on. *n_passes_done = passes completed. Errors: GF_ERR_BAD_PARAMETER
 * (n_fb outside 0 .. 10000, filter reversed), GF_ERR_BAD_SIZE (n < 2), the errors of
 * gf_ins_run. */
gf_status gf_ins_forward_backward(gf_ins_filter *f, size_t n, const double *t_s,
                                  const double *gyro, const double *accel, size_t n_meas,
                                  const gf_ins_meas *meas, int32_t n_fb, gf_ins_pass *passes,
                                  gf_ins_log *log, int32_t *n_passes_done);

/* Coarse alignment at rest for any orientation (TRIAD on gravity and the Earth rate; the
 * same as gfins_fmi.estimation.alignment.attitude_from_gravity_and_earth_rate): from the
 * mean specific force f_b (m/s^2) and the mean angular rate w_b (rad/s) over a window at
 * rest, in body axes, up = f / |f|, east = (w x f) / |w x f|, north = up x east, and
 * C_b^n has the rows east, north, up (in body axes); q_bn its quaternion. The heading
 * error is ~ east gyro bias / (Omega cos L): the gyros must see the Earth rate. Errors:
 * GF_ERR_NONFINITE_INPUT, GF_ERR_SINGULAR_GEOMETRY (|f| not in (5, 15) m/s^2 — not at
 * rest on the Earth —, or w x f below 1e-3 |w| |f|: a pole, or no Earth rate seen). */
gf_status gf_ins_coarse_align(const double *f_b_m_s2, const double *w_b_rad_s, double *q_bn);

/* Levelling at rest without a heading (for gyros that cannot see the Earth rate): the
 * attitude whose roll and pitch put the mean specific force f_b (m/s^2, body axes) on
 * the local vertical and whose heading is 0: up = f / |f|, north = the body's forward
 * axis y projected on the horizontal plane, east = north x up; C_b^n has the rows east,
 * north, up (in body axes), q_bn its quaternion. The heading is then found otherwise
 * (gf_ins_rotate_heading). Errors: GF_ERR_NONFINITE_INPUT, GF_ERR_SINGULAR_GEOMETRY (|f|
 * not in (5, 15) m/s^2 — not at rest on the Earth —, or the forward axis within 0.06 deg
 * of the vertical: no heading to define). */
gf_status gf_ins_level_align(const double *f_b_m_s2, double *q_bn);

/* Rotates a navigation attitude q_bn and velocity v_n (ENU, m/s; NULL: none) about the
 * local vertical so that the heading (clockwise from north) grows by dpsi_rad and roll
 * and pitch stay: C_b^n <- R_up(-dpsi) C_b^n, v_n <- R_up(-dpsi) v_n (R_up(a): rotation
 * by a counterclockwise seen from above). In place. Errors: GF_ERR_NULL_POINTER,
 * GF_ERR_NONFINITE_INPUT (nothing written). */
gf_status gf_ins_rotate_heading(double *q_bn, double *v_n_m_s, double dpsi_rad);

/* The continuous error model at the filter's nominal state with specific force f_b and
 * rate w_ib_b (body): F (n x n), G (n x (n - 3)) and the noise intensities q (n - 3):
 * noise inputs = accelerometer white noise (3), gyro white noise (3), one per sensor
 * state. */
gf_status gf_ins_error_model(const gf_ins_filter *f, const double *f_b_m_s2,
                             const double *w_ib_b_rad_s, double *F, double *G, double *q);

/* The error state dx1 (n_states), one propagation interval T_s later, of the hypothesis
 * "the filter's nominal corrected by dx0" (as gf_ins_apply_error corrects it): both the
 * hypothesis and the nominal are moved by one step of the mechanization with the
 * interval's compensated increments dtheta_rad, dv_m_s (the hypothesis' with its own
 * sensor errors), and dx1 is the hypothesis' error about the moved nominal; the sensor
 * states decay by exp(-T / tau). This is the UKF's time update of one sigma point; its
 * derivative in dx0 is the transition matrix that the EKF's Phi = I + F T + (F T)^2 / 2
 * approximates (tests/c/test_ins_propagate.c differentiates it). The filter is not
 * changed. Errors: GF_ERR_NULL_POINTER, GF_ERR_BAD_PARAMETER (a layout out of range,
 * T_s not finite and > 0), GF_ERR_NONFINITE_INPUT (dx0, increments), GF_ERR_DIVERGED
 * (the mechanization refused a state). */
gf_status gf_ins_propagate_error(const gf_ins_filter *f, const double *dx0,
                                 const double *dtheta_rad, const double *dv_m_s, double T_s,
                                 double *dx1);

/* Rauch-Tung-Striebel smoothing of a forward run's epochs (backward pass, all epochs
 * in one call): xs (count x n) receives the smoothed error of each epoch's posterior
 * nominal (subtract it, gf_ins_apply_error), Ps (count x n(n+1)/2, may alias
 * epochs->P_post) the smoothed covariance. */
gf_status gf_ins_smooth(size_t n_states, const gf_ins_epochs *epochs, double *xs, double *Ps);

/* The same backward pass over one block of epochs, for a record whose epochs do not fit
 * in memory (smoothed from its end, a block at a time): epochs holds the block's epochs
 * and, as its last row (count - 1), the first epoch after the block, whose smoothed error
 * xs[count-1] (n) and covariance Ps[count-1] (n(n+1)/2, packed) the caller gives — from
 * the previous block's call, or 0 and the epoch's P_post for the record's last epoch —
 * and fills rows 0..count-2 of xs and Ps. Blocks that overlap by that one epoch give
 * gf_ins_smooth's result bit for bit (one recursion). Errors: GF_ERR_NULL_POINTER,
 * GF_ERR_BAD_SIZE (n out of 1..40, count 0 or > capacity), GF_ERR_NONFINITE_INPUT (the
 * given row), GF_ERR_BAD_PARAMETER (a negative variance in it), and gf_kalman_rts_step's
 * (a prior covariance not positive definite). */
gf_status gf_ins_smooth_block(size_t n_states, const gf_ins_epochs *epochs, double *xs, double *Ps);

/* Applies smoothed errors to the forward solution's rows (t_s n; q_bn n x 4, v n x 3,
 * pos n x 3 and sensors n x GF_INS_N_SENSORS (may be NULL), all in place): a row at an
 * epoch's time takes that epoch's xs; a row between epochs j and j+1 the linear
 * interpolation between xs_j (about the posterior nominal of j) and xs_j+1 + dx_j+1
 * (about the prior nominal of j+1, which the rows in between continue). */
gf_status gf_ins_smooth_apply(const gf_ins_filter *f, size_t n_epochs, const double *epoch_t,
                              const double *xs, const double *dx, size_t n, const double *t_s,
                              double *q_bn, double *v_n_m_s, double *pos, double *sensors);

/* Applies an error-state vector to a navigation state (10: q_bn, v, lat, lon, h) and
 * sensor estimates (may be NULL), the same correction as the filter's feedback. */
gf_status gf_ins_apply_error(const gf_ins_filter *f, const double *dx, double *nav,
                             double *sensors);

/* Chi-square quantile for m degrees of freedom (1..12) at probability p in (0, 1): Newton
 * iterations on the closed-form distribution function from the Wilson-Hilferty start
 * (converged to ~1e-13 relative). */
gf_status gf_chi2_quantile(int32_t m, double p, double *q);

/* The measurement kinds (the table of gf_ins_meas.c): for a code GF_INS_MEAS_*, its rows
 * (m: rows of z, H and R) and its name (as in the innovation logs: "gnss_pos", ...);
 * rows and name may be NULL. Error: GF_ERR_BAD_PARAMETER for a code that is no kind
 * (kinds are 1 .. GF_INS_N_MEAS_KINDS - 1 today; enumerate with this call). */
gf_status gf_ins_meas_kind_info(int32_t kind, int32_t *rows, const char **name);

/* The model of one measurement kind at the filter's current state, as its updates use it
 * (the nominal's local frame for positions, the latest compensated rate w_ib_b_rad_s,
 * ZARU the standstill detector's mean rate; after gf_ins_reverse the reversed nominal):
 *   z_pred (rows, may be NULL): the kind's prediction from the nominal state corrected by
 *     the error-state vector dx (n_states; NULL = 0) as the feedback corrects it
 *     (gf_ins_apply_error), in the units the update compares with the measurement (GNSS
 *     position: east, north, up metres about the nominal's position; the others as
 *     measured, in the filter's direction of time);
 *   H (rows x n_states, may be NULL): the Jacobian at the nominal that the EKF uses,
 *     z_pred(0) - z_pred(dx) = H dx to first order (z_err = predicted - measured, the
 *     states' signs as in the table above), with the small terms H leaves out (see
 *     "Measurements");
 *   *rows (may be NULL): the kind's rows.
 * ms (may be NULL): a measurement of that kind, checked as gf_ins_step checks it and
 * handed to the model (no kind's model reads it today). Errors: GF_ERR_NULL_POINTER,
 * GF_ERR_BAD_PARAMETER (no such kind, a filter whose layout is out of range, ms of
 * another kind or invalid), GF_ERR_NONFINITE_INPUT (dx), GF_ERR_SINGULAR_GEOMETRY (the
 * kind refuses this nominal: a speed at or below speed_min_m_s). */
gf_status gf_ins_meas_model(const gf_ins_filter *f, int32_t kind, const gf_ins_meas *ms,
                            const double *dx, double *z_pred, double *H, int32_t *rows);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_INS_GNSS_H */
