/* gf_gfins.h — gyro-free inertial navigation for any accelerometer array (seed 000): the
 * angular-rate strategies on the array solver (gf_array_solver.h).
 *
 * The rate w follows from a strategy (GF_RATE_*); whether a strategy's error loop is
 * stable on an array is analysed in gfins_fmi/gyrofree.py (rate_loop_stability). The
 * navigator (gf_gfnav.h) integrates the rate, its derivative and the specific force into
 * the strapdown mechanization.
 */
#ifndef GF_GFINS_H
#define GF_GFINS_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "est/gf_kalman.h"
#include "gyrofree/gf_array.h"
#include "gyrofree/gf_array_solver.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
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
