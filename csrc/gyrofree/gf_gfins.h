/* gf_gfins.h — gyro-free inertial navigation for any accelerometer array (seed 000).
 *
 * Every output is linear in x = [f (3), w_dot (3), W11, W22, W33, W12, W13, W23], the
 * specific force, the angular acceleration and the six products W = w w^T:
 *
 *   A_i = theta_i . f + (u_i x theta_i) . w_dot + sum_jk M_i,jk W_jk,
 *   M_i = sym(theta_i u_i^T) - (theta_i . u_i) I                (from seed 000 eq. 1-2)
 *
 * so an array is the N x 12 matrix H of these rows. The solver (gf_array_solver) splits
 * the six products into the combinations the outputs separate from f and w_dot
 * (observed), those that enter them only as f and w_dot do (confounded: taken from a
 * predicted rate) and those that do not enter them (absent), in coordinates a rotation
 * of the array acts on orthogonally, so that the same physical array gives the same
 * (rotated) solution in any mounting; it solves each sample by least squares with the
 * pseudo-inverse (SVD). Examples: the 12-accelerometer layout observes all of w w^T;
 * Qin's 9-accelerometer layout the squared rates along its axes (the cross products are
 * absent); the 6-accelerometer cube of Tan & Park none (its cross products are
 * confounded: it must integrate w_dot); a coplanar array three combinations.
 *
 * The rate w follows from a strategy (GF_RATE_*); whether a strategy's error loop is
 * stable on an array is analysed in gfins_fmi/gyrofree.py (rate_loop_stability). The
 * navigator integrates (w, w_dot, f) over each interval with a cubic Hermite rate model
 * (gf_hermite_increments) and hands the increments to the strapdown mechanization
 * (gf_sins_step_compensated), or feeds it the rates (GF_GFNAV_LINEAR).
 */
#ifndef GF_GFINS_H
#define GF_GFINS_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "est/gf_kalman.h"
#include "gyrofree/gf_accel_array.h"
#include "nav/gf_sins.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_X_N 12                /* unknowns per sample */
#define GF_GROUP_F 1             /* f */
#define GF_GROUP_OMEGA_DOT 2     /* w_dot */
#define GF_GROUP_W_DIAG 4        /* W11, W22, W33 */
#define GF_GROUP_W_OFFDIAG 8     /* W12, W13, W23 */

/* What an array observes does not depend on how it is mounted in the body, so the
 * solver works in the space of products rather than on the body-axis groups. With
 * H = [H_l | H_p] (H_l: the 6 columns of f and w_dot; H_p: the products in the
 * orthonormal coordinates p = [W11, W22, W33, sqrt2 W12, sqrt2 W13, sqrt2 W23], in
 * which a rotation of the array acts orthogonally), and Q the projector on the
 * complement of the range of H_l:
 *   - H_l must have rank 6 (else the array is refused: f or w_dot unobservable even
 *     with the rate known);
 *   - the right singular vectors of Q H_p with singular values above the rank tolerance
 *     span the OBSERVED product combinations (n_obs, 0..6): the outputs separate them
 *     from f and w_dot;
 *   - of the rest, those with H_p v != 0 are CONFOUNDED (n_conf): they enter the
 *     outputs exactly as some f, w_dot do and must come from a predicted rate; the
 *     others are ABSENT (no effect on the outputs);
 *   - each sample is solved by least squares for f, w_dot and the observed
 *     combinations z (pinv of [H_l, H_p B_o], B_o the observed basis), after removing
 *     the confounded products of the predicted rate: x = pinv A - K_pred p(w_pred),
 *     K_pred = pinv H_p B_c B_c^T.
 * Everything here rotates with the array (a rotated array gives the rotated estimates,
 * the same condition number and the same principal noise gains). The body-axis group
 * masks are kept as a description: a group is "estimated" when every one of its
 * components lies in the observed subspace, "from_rate" when it is present, not
 * estimated, and touches the confounded subspace. */
typedef struct gf_array_solver {
    size_t n_sensors;
    uint32_t present;            /* groups whose columns are not zero (affect outputs) */
    uint32_t estimated;          /* groups solved from the outputs, every component */
    uint32_t from_rate;          /* present groups with components from the predicted rate */
    size_t n_obs;                /* observed product combinations, 0..6 */
    size_t n_conf;               /* confounded product combinations, 0..6 - n_obs */
    size_t n_est;                /* rows of pinv: f (3), w_dot (3), observed (n_obs) */
    size_t rank;                 /* rank of [H_l, H_p B_o] (= n_est when solvable) */
    double cond;                 /* its condition number s_max / s_min */
    double basis[36];            /* 6x6 orthonormal, row-major, column j = basis vector j
                                    in the orthonormal product coordinates: observed
                                    (0..n_obs-1), confounded, then absent */
    double noise_gain[GF_X_N];   /* std per unit output noise of f, w_dot and of every
                                    product W_jk wholly observed (0 otherwise), body axes */
    double pinv[GF_X_N * GF_ARRAY_MAX_SENSORS];   /* n_est rows, stride GF_ARRAY_MAX_SENSORS */
    double pinv_t[GF_ARRAY_MAX_SENSORS * GF_X_N]; /* its transpose, rows of 12 (zero beyond
                                                     n_est): the per-sample product as
                                                     axpys that vectorise */
    double K_pred[GF_X_N * 6];   /* n_est x 6: rows of x per orthonormal product of w_pred */
    double W_obs[36];            /* 6 x 6 (n_obs columns used): products W (as in x) per
                                    observed coordinate */
    double W_rate[36];           /* 6 x 6: products W (as in x) per orthonormal product of the
                                    rate, for the unobserved directions (B_n B_n^T) */
    double H[GF_ARRAY_MAX_SENSORS * GF_X_N];      /* n_sensors x 12 (products W_jk as in x) */
} gf_array_solver;

/* Builds the solver of an array. On GF_ERR_SINGULAR_GEOMETRY *unobservable (may be
 * NULL) has bit i set for every unknown i of x that the outputs cannot separate even
 * when the products come from a predicted rate (e.g. zero lever arms: w_dot). */
gf_status gf_array_solver_init(gf_array_solver *solver, const gf_array_geometry *geometry,
                               uint32_t *unobservable);

/* One sample: outputs A (n_sensors, m/s^2), predicted rate w_pred (3, rad/s; used for
 * the confounded products, may be NULL when there are none) -> x (12): f, w_dot and
 * the products W (observed combinations from the outputs, the rest from w_pred, or 0
 * without it). GF_ERR_BAD_SIZE for a solver whose sizes are out of range. */
gf_status gf_array_solve(const gf_array_solver *solver, const double *A_m_s2,
                         const double *w_pred_rad_s, double *x);

/* The layouts of the literature (positions in m, unit directions):
 * cube6: Tan & Park's 6-accelerometer cube as tabled in the mission digest (face
 * centres, face diagonals); layout12: Qin's nine plus three tangential sensors
 * (l e_x along e_y, l e_y along e_z, l e_z along e_x), which makes all of w w^T linear. */
gf_status gf_layout_cube6(double lever_arm_m, gf_array_geometry *geometry);
gf_status gf_layout_12(double lever_arm_m, gf_array_geometry *geometry);

/* ---- angular-rate strategies ------------------------------------------------------ */
/* The w_dot integral over an interval (INTEGRATE's rate, FUSED's prediction, the
 * reference of SQRT and EIGEN) is the third-order Adams-Moulton rule
 * T (5 w_dot_k + 8 w_dot_(k-1) - w_dot_(k-2)) / 12 (the trapezoid for the first interval
 * and after a change of dt), and the rate predicted for the confounded products is
 * the second-order Adams-Bashforth extrapolation w_(k-1) + T (3 w_dot_(k-1) - w_dot_(k-2)) / 2:
 * both exact for a quadratic rate, so the rate of a smooth motion errs by O(T^3). */
#define GF_RATE_INTEGRATE 0   /* w_k = w_(k-1) + integral of w_dot (6-accelerometer style) */
#define GF_RATE_SQRT 1        /* w from the observed products, sample by sample; the signs
                                 (mirror images) by continuity with the w_dot integral (Qin) */
#define GF_RATE_EIGEN 2       /* dominant eigenpair of W (all of w w^T observed), sign from
                                 the w_dot integral                                      */
#define GF_RATE_FUSED 3       /* EKF on [w, w_dot bias]: predicted with w_dot (including the
                                 loop through the confounded products), corrected with the
                                 observed product combinations (their information about w
                                 vanishes as w -> 0, so zero crossings ride on w_dot)      */

/* How SQRT and EIGEN read the rate from the observed combinations (gf_gfins_init):
 * FRAME (SQRT): the observed products are the squared rates along three orthogonal axes
 *   a_k of the array (Qin's nine in any mounting): w.a_k = +-sqrt((a_k^T W a_k)), seed
 *   000 eq. 4 in the array's own frame; 8 mirror images (one sign per axis).
 * FULL (EIGEN): all of w w^T is observed: dominant eigenpair (the unweighted rank-one
 *   fit); 2 mirror images (+-w).
 * FIT (SQRT otherwise, >= 3 combinations): Gauss-Newton fit of w to the observed
 *   combinations weighted by their noise covariance (R_W^-1), started from the w_dot
 *   integral; the other roots are the mirror images (+-w always, more for partial
 *   products). */
#define GF_RATE_MODEL_NONE 0
#define GF_RATE_MODEL_FRAME 1
#define GF_RATE_MODEL_FULL 2
#define GF_RATE_MODEL_FIT 3

/* flags per sample */
#define GF_RATE_FLAG_NEG_X 1          /* (a_k^T W a_k) < 0 on axis k of the frame (SQRT) /
                                         lambda_max < 0 (EIGEN, bit 0) / fit failed (FIT) */
#define GF_RATE_FLAG_NEG_Y 2
#define GF_RATE_FLAG_NEG_Z 4
#define GF_RATE_FLAG_SIGN_UNKNOWN 8   /* a sign reference was exactly zero */
#define GF_RATE_FLAG_UPDATE_SKIPPED 16 /* FUSED: innovation covariance not positive definite */
#define GF_RATE_FLAG_AMBIGUOUS 32     /* SQRT, EIGEN: the outputs admit a mirror-image rate
                                         closer than the resolution (a component, the rate or
                                         the fit's weakest direction within 2.5 sqrt(noise
                                         std of the products) of zero): the branch is that of
                                         the w_dot integral, which is not re-anchored here */

typedef struct gf_rate_config {
    int32_t strategy;               /* GF_RATE_* */
    double accel_noise_m_s2;        /* white noise std of each accelerometer (FUSED; the
                                       ambiguity resolution of SQRT, EIGEN), > 0 */
    double bias_walk_rad_s2_sqrt_s; /* FUSED: random walk of the w_dot bias state */
    double init_std_rad_s;          /* FUSED: initial std of w about omega_init */
    double init_bias_std_rad_s2;    /* FUSED: initial std of the w_dot bias */
} gf_rate_config;

typedef struct gf_gfins_state {
    gf_array_solver solver;
    gf_rate_config cfg;
    int32_t rate_model;             /* GF_RATE_MODEL_* (SQRT, EIGEN) */
    double frame[9];                /* FRAME: the array's axes a_k, columns (row-major 3x3) */
    double diag_map[18];            /* FRAME: a_k^T W a_k per observed coordinate (3 x n_obs) */
    double amb_rad_s[3];            /* ambiguity resolution (rad/s): per axis (FRAME), [0] for
                                       FULL and FIT */
    double whiten[36];              /* FIT: L^-1 (n_obs x n_obs, lower), R_W = L L^T, scaled by
                                       the largest product std: whitened residuals */
    double omega_rad_s[3];          /* rate at the last sample */
    double omega_ref_rad_s[3];      /* w_dot integral from omega_init, re-anchored to the
                                       rate wherever the rate is unambiguous */
    double omega_dot_rad_s2[3];     /* w_dot at the last sample */
    double omega_dot_prev_rad_s2[3]; /* w_dot at the sample before it */
    double dt_prev_s;               /* the last interval (0 before the second sample) */
    double R_W[36];                 /* covariance of the observed combinations (n_obs^2) */
    double var_omega_dot[9];        /* covariance of w_dot (3 x 3) */
    int32_t n_w_meas;               /* FUSED: n_obs, 1..6 */
    gf_kalman kf;                   /* FUSED: x = [w (3), b (3)], w_dot_true = w_dot - b */
    uint64_t n_samples;
} gf_gfins_state;

gf_status gf_rate_config_default(gf_rate_config *cfg);

/* Initialises the rate solver. Errors: the geometry's (see gf_array_solver_init);
 * GF_ERR_BAD_PARAMETER when the strategy needs what the array does not measure (SQRT:
 * >= 3 observed product combinations; EIGEN: all of W; FUSED: >= 1) or a bad config.
 * Whether the strategy's error loop is stable on this array is analysed in Python
 * (gfins_fmi.gyrofree.rate_loop_stability), which refuses unstable combinations. */
gf_status gf_gfins_init(gf_gfins_state *state, const gf_array_geometry *geometry,
                        const gf_rate_config *cfg, const double *omega_init_rad_s,
                        uint32_t *unobservable);

/* One sample of outputs A (n_sensors) dt_s after the previous one (ignored for the
 * first): f (3), w (3), w_dot (3), W (6: measured or predicted products), flags.
 * The state changes only on GF_OK. */
gf_status gf_gfins_step(gf_gfins_state *state, const double *A_m_s2, double dt_s,
                        double *f_m_s2, double *omega_rad_s, double *omega_dot_rad_s2,
                        double *W, uint8_t *flags);

/* Batch: n samples (A: n x n_sensors) at a fixed dt_s; outputs n x 3 (W: n x 6, may be
 * NULL) and n flags. *n_done = samples solved; rows before an error are valid. */
gf_status gf_gfins_run(gf_gfins_state *state, size_t n, const double *A_m_s2, double dt_s,
                       double *f_m_s2, double *omega_rad_s, double *omega_dot_rad_s2,
                       double *W, uint8_t *flags, size_t *n_done);

/* ---- navigator: array -> (w, f) -> strapdown ------------------------------------- */
/* Attitude and velocity over one sampling interval [0, T]. The array measures w and
 * w_dot at both ends, so the navigator models the rate as the cubic Hermite polynomial
 * through (w0, w_dot0) and (w1, w_dot1), tau = t / T:
 *   w(t) = (2tau^3 - 3tau^2 + 1) w0 + (tau^3 - 2tau^2 + tau) T w_dot0
 *        + (-2tau^3 + 3tau^2) w1 + (tau^3 - tau^2) T w_dot1,
 * whose increment and (second-order Magnus, "coning") term are, exactly,
 *   dtheta = T (w0 + w1) / 2 + T^2 (w_dot0 - w_dot1) / 12,
 *   cone   = 1/2 int_0^T theta(t) x w(t) dt
 *          = T^2 [ w0 x w1 / 10 + (w0 x T w_dot0 + w1 x T w_dot1) / 168
 *                  - (w0 x T w_dot1 + w1 x T w_dot0) / 70 - T w_dot0 x T w_dot1 / 560 ]
 * (for a linear rate, w_dot0 = w_dot1 = (w1 - w0) / T, this is T^2 w0 x w1 / 12, the
 * mechanization's own two-sample term). The rotation vector of the interval is the
 * sixth-order Magnus series of that polynomial, evaluated at the three Gauss-Legendre
 * nodes c = 1/2 -+ sqrt(15)/10, 1/2 (Blanes, Casas & Ros, BIT 40 (2000) 434, the
 * sixth-order method; commutators [a, b] = b x a for the body rate, q' = q (x) w / 2):
 *   a_i = w(c_i T),  B1 = T a_2,  B2 = sqrt(15) T (a_3 - a_1) / 3,
 *   B3 = 10 T (a_3 - 2 a_2 + a_1) / 3,  C1 = [B1, B2],  C2 = -[B1, 2 B3 + C1] / 60,
 *   phi = B1 + B3 / 12 + [-20 B1 - B3 + C1, B2 + C2] / 240,
 * which holds dtheta exactly and the coning term and all higher commutator terms to
 * O(T^7) (local error of the rotation vector against the attitude ODE under the cubic
 * rate; tests/c/test_gfins.c and tests/test_gyrofree.py check both).
 * The specific force is not differentiated by the array, but expressed in the body
 * frame at the start of the interval, h(t) = R(t) f(t) (R(T) = exp([phi x])), it is the
 * specific force in a non-rotating frame, free of the body rate: its trapezoid
 *   dv_b = T (f0 + R(T) f1) / 2
 * has the error T^3 h''/12 of the vehicle's own acceleration changes only, whatever the
 * body rate (the mechanization's linear model errs by ~T^3 |w|^2 |f| / 12 a step).
 * Inputs w (rad/s), w_dot (rad/s^2), f (m/s^2) at both ends; outputs phi_rad (body at
 * 0 -> body at T) and dv_b_m_s (body frame at 0). Errors: GF_ERR_NULL_POINTER,
 * GF_ERR_BAD_TIME (T not > 0), GF_ERR_NONFINITE_INPUT. */
gf_status gf_hermite_increments(const double *w0_rad_s, const double *w_dot0_rad_s2,
                                const double *f0_m_s2, const double *w1_rad_s,
                                const double *w_dot1_rad_s2, const double *f1_m_s2, double T_s,
                                double *phi_rad, double *dv_b_m_s);

#define GF_GFNAV_LINEAR 0     /* rates linear between samples: the mechanization's own rate
                                 input with its two-sample coning and sculling (second order) */
#define GF_GFNAV_HERMITE 1    /* cubic Hermite rate model from w and w_dot (default) */

typedef struct gf_gfnav_state {
    gf_gfins_state rate;
    gf_sins_state nav;              /* rate input */
    int32_t integration;            /* GF_GFNAV_* */
} gf_gfnav_state;

/* sins_cfg->input must be GF_SINS_INPUT_RATES. The integration is GF_GFNAV_HERMITE. */
gf_status gf_gfnav_init(gf_gfnav_state *state, const gf_array_geometry *geometry,
                        const gf_rate_config *rate_cfg, const double *omega_init_rad_s,
                        const gf_sins_config *sins_cfg, const double *q_bn,
                        const double *v_n_m_s, double lat_rad, double lon_rad, double h_m,
                        double t0_s, uint32_t *unobservable);

/* Chooses the attitude and velocity integration (GF_GFNAV_*; GF_ERR_BAD_PARAMETER
 * otherwise); may be changed between runs. */
gf_status gf_gfnav_set_integration(gf_gfnav_state *state, int32_t integration);

/* Batch navigation of n array samples (the first one at t0): rows of q_bn (n x 4),
 * v_n_m_s (n x 3), pos (n x 3), and optionally omega_rad_s, f_m_s2 (n x 3, may be NULL)
 * and flags (n, may be NULL). Errors as gf_gfins_run and gf_sins_run. */
gf_status gf_gfnav_run(gf_gfnav_state *state, size_t n, const double *A_m_s2, double dt_s,
                       const double *h_ext_m, double *q_bn, double *v_n_m_s, double *pos,
                       double *omega_rad_s, double *f_m_s2, uint8_t *flags, size_t *n_done);
/* CDEF END */

/* Checks a rate-solver state handed in by a caller (e.g. restored from saved bytes).
 * gf_gfins_step, gf_gfins_run, gf_gfnav_run (and gf_array_solve for its solver) check
 * before every call, with integer compares only, what sizes a loop, indexes an array or
 * selects a branch: n_sensors in 6..GF_ARRAY_MAX_SENSORS, n_obs <= 6, n_conf <= 6 - n_obs,
 * n_est = 6 + n_obs, the strategy, for SQRT and EIGEN a rate model the observed
 * combinations allow, and for FUSED n_w_meas = n_obs >= 1 and a 6-state filter
 * (GF_ERR_BAD_SIZE). This function also checks the rest: configuration values as
 * gf_gfins_init does and the group masks (GF_ERR_BAD_PARAMETER), and every number of
 * the solver, the rates, the covariances and the filter finite
 * (GF_ERR_NONFINITE_INPUT). */
gf_status gf_gfins_state_check(const gf_gfins_state *state);

#ifdef __cplusplus
}
#endif

#endif /* GF_GFINS_H */
