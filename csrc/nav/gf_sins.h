/* gf_sins.h — strapdown inertial navigation: ENU quaternion mechanization on WGS-84.
 *
 * Frames and angles (seed 002): body b = right-front-up, navigation n = East-North-Up.
 * Attitude is the quaternion q_b^n (scalar first). Euler angles: heading psi clockwise
 * from north in [0, 2 pi), pitch theta in [-pi/2, pi/2] (nose up +), roll gamma in
 * (-pi, pi] (right wing down +), with C_b^n = Rz(-psi) Rx(theta) Ry(gamma).
 *
 * One update from t_(k-1) to t_k = t_(k-1) + T. Seed 002 (section 1.2) gives the steps:
 * initial quaternion from the Euler angles (its eq. 12-20), attitude update through
 * w_in^n = w_ie^n + w_en^n (eq. 5-11, here as rotation vectors instead of its Picard
 * approximation), specific-force equation with Coriolis and gravity (eq. 21-25), then
 * the position update; the two-sample corrections and the mid-point evaluation follow
 * Savage (Strapdown Analytics ch. 7) and Titterton & Weston (ch. 11):
 *   rotation vector  phi  = dtheta_k + C (coning)         C = dtheta_(k-1) x dtheta_k / 12
 *   velocity (body)  dv_b = dv_k + dtheta_k x dv_k / 2 + S  S = (dtheta_(k-1) x dv_k
 *                                                              + dv_(k-1) x dtheta_k) / 12
 *   mid-interval     v_m = v + a_(k-1) T / 2, position extrapolated with v_m: Earth rate,
 *                    transport rate and gravity are evaluated there
 *   velocity         v_k = v + (I - [zeta x]/2) C_b^n dv_b + (g - (2 w_ie + w_en) x v_m) T,
 *                    zeta = (w_ie + w_en) T
 *   position         trapezoid of v over T with radii at the mid point
 *   attitude         q_k = q(-zeta) (x) q (x) q(phi), normalised
 * Inputs are increments (dtheta rad, dv m/s over the interval) or rates (rad/s, m/s^2
 * at the sample times). Rates are taken as linear between samples, for which
 * dtheta = T (w0 + w1)/2, C = T^2 w0 x w1 / 12, S = T^2 (w0 x f1 + f0 x w1) / 12 are
 * exact. With coning off ("one-sample") C = S = 0.
 *
 * Subsamples (cfg.subsamples = N, 1..4; increments only). gf_sins_run can make one
 * navigation update of T = N h from N consecutive increments (dtheta_i, dv_i),
 * i = 1..N, of equal sub-intervals h (the usual processing of a high-rate IMU: the
 * navigation update, Earth and transport rates, gravity and the position run at 1/N of
 * the sample rate). With the sums Theta = sum dtheta_i, V = sum dv_i:
 *   rotation vector  phi  = Theta + C,           C = (sum_(i<N) k_i dtheta_i) x dtheta_N
 *   velocity (body)  dv_b = V + Theta x V / 2 + S,
 *                    S = (sum_(i<N) k_i dtheta_i) x dv_N + (sum_(i<N) k_i dv_i) x dtheta_N
 *   k (N = 2) = 2/3;  k (N = 3) = 9/20, 27/20;  k (N = 4) = 54/105, 92/105, 214/105
 * These are the coning algorithms, optimised for pure coning, of the class in which the
 * last subsample is crossed with a weighted sum of the earlier ones (the class of
 * Ignagni, "Efficient class of optimized coning compensation algorithms", J. Guidance
 * 19(2), 1996; Savage, Strapdown Analytics, sec. 7.1.1.1; N = 2: Savage's
 * (2/3) dtheta_1 x dtheta_2; the numbers are PSINS' conefactors); the sculling terms take
 * the same coefficients by Ignagni's duality ("Duality of optimal strapdown sculling
 * and coning compensation algorithms", Navigation 45(2), 1998). Derived here (sympy,
 * docs/sins.md, and checked by tests/test_sins_subsamples.py): under classic coning
 * (half-angle a, rate W, lambda = W h) the cone-axis component of
 * dtheta_i x dtheta_j is 4 sin^2 a sin^2(lambda/2) sin((j-i) lambda), the exact (Bortz)
 * rotation per update is 1/2 sin^2 a (N lambda - sin N lambda), and the k_i cancel
 * the Taylor terms lambda^3 .. lambda^(2N-1) of the difference. Truncation: the
 * residual per update is sin^2 a lambda^(2N+1) / {30, 280/3, 315} for N = 2, 3, 4
 * (leading terms lambda^5/30, 3 lambda^7/280, lambda^9/315), i.e. a coning drift of
 * W sin^2 a lambda^(2N) / {60, 280, 1260}; the N = 1 update with the previous sample's
 * terms (above) leaves lambda^5/60 per update, the same drift W sin^2 a lambda^4/60 as
 * N = 2. Sculling (a rotation a sin(W t) about one axis with a specific force
 * A sin(W t) along another) leaves the same function of lambda times a A / W in
 * velocity per update (docs/sins.md). cfg.subsamples = 1 is the update above, sample by
 * sample (bit for bit the same as before the option existed). A record whose length
 * is not a multiple of N ends with one update of the M < N samples left, with the
 * M-sample set (M = 1: the one-sample update with the previous sample's terms, as
 * N = 1). The rows of gf_sins_run are then one per update (see there).
 *
 * Latitude limit. The ENU frame's north reference turns at w_en,z = v_E tan(L) / (R + h)
 * and the longitude rate v_E / ((R + h) cos L) grows without bound at the poles: the
 * mechanization holds for |L| < GF_SINS_LAT_LIMIT_MDEG (89.9 deg, 11 km from a pole).
 * Measured on eastward circles around the pole at constant latitude (300 m/s, 60 s,
 * 100 Hz, exact increments): horizontal error 2.4e-4 m and attitude error 1.8e-11 rad
 * at 89.9 deg, but 3.3e-2 m and 2.3e-5 rad at 89.99 deg and 2.1 m and 1.9e-2 rad at
 * 89.999 deg. gf_sins_init refuses a start at or beyond the limit (GF_ERR_BAD_PARAMETER)
 * and a step that would reach it returns GF_ERR_DIVERGED, state unchanged. (A
 * wander-azimuth mechanization would be needed to navigate across the poles.)
 *
 * Reverse navigation (seed 003): time reversal of the mechanization equations maps
 * (w_ib, f, v, w_ie) to (-w_ib, f, -v, -w_ie): gf_sins_reverse() negates v and the Earth
 * rate, and gf_sins_run(backward = 1) feeds the samples last to first with dtheta
 * negated and dv unchanged.
 */
#ifndef GF_SINS_H
#define GF_SINS_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "nav/gf_earth.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_SINS_LAT_LIMIT_MDEG 89900 /* |latitude| limit of the ENU mechanization, millidegrees */

#define GF_SINS_MAX_SUBSAMPLES 4     /* increments per navigation update, at most */

#define GF_SINS_INPUT_INCREMENTS 0   /* dtheta (rad), dv (m/s) per interval */
#define GF_SINS_INPUT_RATES 1        /* rate (rad/s), specific force (m/s^2) at sample times */

#define GF_SINS_VERTICAL_FREE 0      /* integrate the vertical channel (unstable, ~ e^(t/570 s)) */
#define GF_SINS_VERTICAL_HOLD 1      /* height held at hold_height_m, vertical velocity 0 */
#define GF_SINS_VERTICAL_BARO 2      /* third-order loop on an external height, see below */

#define GF_SINS_EARTH_WGS84 0        /* the Earth of gf_earth: rotation, curvature, gravity */
#define GF_SINS_EARTH_FLAT 1         /* a fixed (non-rotating) frame with constant gravity
                                        flat_gravity_m_s2 along -z (0: none): q_b^i, v^i,
                                        position in metres (east, north, up axes); the
                                        idealised setting of seed 000's simulation.
                                        Vertical modes do not apply. */

/* Configuration (set once, before gf_sins_init). The baro loop (a standard
 * third-order baro-inertial loop; seed 004 feeds the barometric altimeter to its filter
 * instead), with e = h - h_ext:
 *   h' = v_U - k1 e,  v_U' = a_U - k2 e - b,  b' = k3 e,
 *   k1 = 3/tau, k2 = 3/tau^2 + 2 g/R, k3 = 1/tau^3: the height error then has a
 *   triple pole at s = -1/tau (2 g/R cancels the free channel's instability). */
typedef struct gf_sins_config {
    int input;                       /* GF_SINS_INPUT_* */
    int coning;                      /* 1: coning + sculling corrections; 0: none */
    int vertical;                    /* GF_SINS_VERTICAL_* */
    int earth;                       /* GF_SINS_EARTH_* */
    double flat_gravity_m_s2;        /* EARTH_FLAT: gravity magnitude, >= 0 (default 0) */
    double hold_height_m;            /* height held in HOLD mode */
    double baro_tau_s;               /* BARO loop time constant, > 0 */
    double max_rate_rad_s;           /* |w| above this is an absurd sample (default 50) */
    double max_specific_force_m_s2;  /* |f| above this is an absurd sample (default 1000) */
    int subsamples;                  /* increments per navigation update in gf_sins_run,
                                        1..4 (default 1; > 1 needs INPUT_INCREMENTS) */
} gf_sins_config;

/* Navigation state. Pointer-free: copying it copies the navigator. */
typedef struct gf_sins_state {
    gf_sins_config cfg;
    double q_bn[4];                  /* attitude q_b^n */
    double v_n_m_s[3];               /* velocity, ENU */
    double lat_rad, lon_rad, h_m;    /* geodetic position; lon in (-pi, pi] */
    double time_s;                   /* time of the state */
    double earth_rate_sign;          /* +1 forward, -1 reverse navigation */
    double a_n_m_s2[3];              /* last (v_k - v_(k-1)) / T, for the mid-point */
    double prev_gyro[3];             /* previous sample (increment or rate) */
    double prev_accel[3];
    int32_t have_prev;               /* 1 when prev_* hold a sample */
    double baro_accel_m_s2;          /* BARO loop integral state b */
    double sin_lat, cos_lat;         /* of lat_rad (kept to save trigonometry) */
    double R_M_m;                    /* meridian radius at lat_rad */
    double flat_pos_m[3];            /* EARTH_FLAT: position, m */
    uint64_t n_samples;
} gf_sins_state;

/* Defaults: increments, coning on, free vertical channel, WGS-84, tau 10 s, limits
 * 50 rad/s and 1000 m/s^2, one sample per update. */
gf_status gf_sins_config_default(gf_sins_config *cfg);

/* Euler angles (heading, pitch, roll; rad) <-> quaternion q_b^n, conventions above.
 * Errors: non-finite input; a quaternion whose norm differs from 1 by more than 1e-6
 * (GF_ERR_BAD_PARAMETER: normalise it first). A quaternion within that tolerance is
 * normalised before the angles are taken, so they are those of the rotation it
 * stands for. */
gf_status gf_euler_to_quat(const double *euler_rad, double *q_bn);
gf_status gf_quat_to_euler(const double *q_bn, double *euler_rad);
/* n quaternions (n x 4) to Euler angles (n x 3); *n_done = rows converted. */
gf_status gf_quat_to_euler_batch(size_t n, const double *q_bn, double *euler_rad,
                                 size_t *n_done);

/* Initialises *state at time t0_s with attitude q_bn (normalised here; error if it
 * cannot be), ENU velocity v_n_m_s, latitude/longitude (rad) and height (m).
 * Errors: GF_ERR_BAD_PARAMETER (bad configuration, |lat| at or beyond the latitude
 * limit with EARTH_WGS84 (90 deg with EARTH_FLAT), quaternion not normalisable),
 * GF_ERR_NONFINITE_INPUT. */
gf_status gf_sins_init(gf_sins_state *state, const gf_sins_config *cfg, const double *q_bn,
                       const double *v_n_m_s, double lat_rad, double lon_rad, double h_m,
                       double t0_s);

/* One sample. Increments: gyro = dtheta (rad), accel = dv (m/s) over the dt_s that ends
 * at the new state time. Rates: gyro = w_ib^b (rad/s), accel = f^b (m/s^2) sampled
 * dt_s after the previous sample (the first sample only starts the record; its dt_s
 * is not used; gf_sins_run with t_s sets the state time to that sample's time). h_ext_m is
 * the external height at the new state time for the BARO mode (NaN: none this
 * sample). The state is
 * changed only on GF_OK. Errors: GF_ERR_NONFINITE_INPUT, GF_ERR_OUT_OF_RANGE (|w| or
 * |f| beyond the limits), GF_ERR_BAD_TIME (dt_s <= 0), GF_ERR_DIVERGED (the step would
 * leave the state's domain: the latitude limit, a mid-point or new height outside the
 * Earth model's range (-a/2, a/3), a result not finite),
 * GF_ERR_BAD_PARAMETER (cfg.subsamples > 1: one sample is not an update then; use
 * gf_sins_step_group or gf_sins_run). */
gf_status gf_sins_step(gf_sins_state *state, const double *gyro, const double *accel,
                       double dt_s, double h_ext_m);

/* One navigation update from m (1..4) consecutive increments (gyro, accel: m x 3, in
 * time order; dtheta rad, dv m/s) over sub-intervals of dt_s / m each, with the m-sample
 * coning and sculling set above (m = 1: gf_sins_step's update); h_ext_m as there, at the
 * end of the update. Needs INPUT_INCREMENTS; any cfg.subsamples (the update is m
 * samples whatever the configuration says for gf_sins_run). Reverse navigation: the
 * samples in reverse time order, as gf_sins_step takes them (gyro negated here).
 * Errors as gf_sins_step (each sample checked against the limits over dt_s / m),
 * GF_ERR_BAD_PARAMETER (m outside 1..4, rates input); the state is changed only on
 * GF_OK. */
gf_status gf_sins_step_group(gf_sins_state *state, size_t m, const double *gyro,
                             const double *accel, double dt_s, double h_ext_m);

/* One interval of a rate record from increments the caller computed with its own,
 * higher-order model of the motion over the interval (the gyro-free navigator's cubic
 * Hermite rate model, gf_gfins.h): phi_rad, the rotation vector from the body frame at
 * the start of the interval to the body frame at its end (coning included), and
 * dv_b_m_s, the specific force integrated over the interval and expressed in the body
 * frame at its start (rotation and sculling included). rate_rad_s and f_m_s2 are the
 * sample at the end of the interval: checked against the limits and kept as the
 * previous sample, as gf_sins_step keeps them. Needs a forward rate record that has
 * started (input RATES, a first sample given to gf_sins_step): GF_ERR_BAD_PARAMETER
 * otherwise. Other errors and the state on error as gf_sins_step; |phi| and |dv_b| are
 * checked against the limits times dt_s (the trusted variant below checks the samples
 * only). */
gf_status gf_sins_step_compensated(gf_sins_state *state, const double *phi_rad,
                                   const double *dv_b_m_s, const double *rate_rad_s,
                                   const double *f_m_s2, double dt_s, double h_ext_m);

/* The state's position as the batch calls report it: (lat rad, lon rad, h m), or
 * (x, y, z) m with EARTH_FLAT. */
gf_status gf_sins_position(const gf_sins_state *state, double *pos);

/* EARTH_FLAT: sets the position (m); the geodetic fields are then unused. */
gf_status gf_sins_set_flat_position(gf_sins_state *state, const double *pos_m);

/* Replaces the navigation quantities (attitude q_bn, normalised here; ENU velocity;
 * latitude, longitude, height) and refreshes what the state keeps from them (sin and cos
 * of the latitude, the meridian radius); configuration, time, the previous-sample
 * memory and the mid-point acceleration are kept. For filters that correct the
 * mechanization (closed-loop feedback). Errors: GF_ERR_NONFINITE_INPUT;
 * GF_ERR_BAD_PARAMETER (|lat| at or beyond the latitude limit with EARTH_WGS84,
 * quaternion not normalisable, height outside gf_earth's range); the state is unchanged
 * on error. */
gf_status gf_sins_set_navigation(gf_sins_state *state, const double *q_bn,
                                 const double *v_n_m_s, double lat_rad, double lon_rad,
                                 double h_m);

/* Turns the navigator around in time (see above). Calling it twice restores the
 * navigation state and the direction; the previous-sample memory (coning terms, the
 * start of a rate record) is cleared each time, as the next sample is not adjacent. */
gf_status gf_sins_reverse(gf_sins_state *state);

/* Batch: n samples (gyro, accel: n x 3) in one call. Sample spacing: t_s (n sample
 * times, strictly increasing in recorded order; a backward increment run takes interval
 * 0 as dt_s) if not NULL, else dt_s.
 * h_ext_m (n, may be NULL). backward = 1 processes samples n-1 .. 0 (after
 * gf_sins_reverse). Row k of the outputs is the state after sample k: q_bn (n x 4),
 * v_n_m_s (n x 3), pos (n x 3: lat rad, lon rad, h m; EARTH_FLAT: position in m),
 * time_s (n, may be NULL).
 * On an error the run stops: *n_done = samples processed (in processing order),
 * their rows are valid and *state is the state after the last good one.
 * Subsamples (cfg.subsamples = N > 1): samples are grouped in recorded order, group
 * j = samples jN .. min(n, jN + N) - 1 (the last one shorter when N does not divide n),
 * one update per group (gf_sins_step_group); the outputs have one row per group,
 * ceil(n / N) rows: row j is the state after group j (backward: the state at the start
 * of group j, processed last group first). h_ext_m is read once per update, at the
 * group's last sample in processing order (as gf_sins_step reads a sample's); values
 * at the other samples are not used. With t_s the sub-intervals
 * are taken from the times (each must be > 0) and the update's interval is their sum;
 * the coefficients assume equal sub-intervals. *n_done counts the samples of the
 * completed updates (a multiple of N except after the short group); on an error the
 * group that failed (samples from *n_done on, in processing order) is not applied. A
 * record cut into pieces at multiples of N gives the same result as one call. */
gf_status gf_sins_run(gf_sins_state *state, size_t n, const double *gyro, const double *accel,
                      double dt_s, const double *t_s, const double *h_ext_m, int backward,
                      double *q_bn, double *v_n_m_s, double *pos, double *time_s,
                      size_t *n_done);
/* CDEF END */

/* The latitude limit in radians (GF_SINS_LAT_LIMIT_MDEG; cffi takes integer constants). */
#define GF_SINS_LAT_LIMIT_RAD (GF_SINS_LAT_LIMIT_MDEG * (3.14159265358979323846 / 180000.0))

/* Checks a state handed in by a caller (e.g. restored from saved bytes): a valid
 * configuration (enumerations, limits), direction, a unit attitude quaternion (within
 * 1e-6), finite velocity, acceleration, previous sample, baro state and time, the
 * latitude within the limit with the kept sine and cosine of it (1e-12) and meridian
 * radius (1e-6 relative), a finite longitude and a height within the Earth model's
 * range (-a/2, a/3); a finite fixed-frame position in either model (a navigator may
 * publish it). Error: GF_ERR_BAD_PARAMETER. gf_sins_step and gf_sins_run check before every
 * call, with compares only, what selects a branch or divides (configuration, direction,
 * attitude norm, latitude range, cos L > 0, R_M > 0); other non-finite numbers make the
 * step's results non-finite: GF_ERR_DIVERGED. */
gf_status gf_sins_state_check(const gf_sins_state *state);

/* Internal to the core: the compare-only validity check that gf_sins_step runs before
 * every sample (configuration, direction, attitude norm, latitude range, cos L > 0,
 * R_M > 0), for batch callers that check once per call and keep the state valid
 * themselves between samples; and gf_sins_step_compensated without it. */
int gf_sins_state_valid(const gf_sins_state *state);
/* q_phi: gf_q_from_rotvec_fast(phi_rad), computed by the caller already; the inputs
 * must be finite (checked by the caller; h_ext_m may be NaN: no external height) */
gf_status gf_sins_step_compensated_trusted(gf_sins_state *state, const double *phi_rad,
                                           const double *q_phi, const double *dv_b_m_s,
                                           const double *rate_rad_s, const double *f_m_s2,
                                           double dt_s, double h_ext_m);

/* Internal to the core: gf_sins_step without the check of *state and without its gyro
 * negation in reverse (the caller hands the increments in the state's direction of
 * time), for callers that keep the state valid themselves (the integrated-navigation
 * filter sets it only through gf_sins_init, gf_sins_set_navigation and gf_sins_reverse,
 * which check). */
gf_status gf_sins_step_trusted(gf_sins_state *state, const double *gyro, const double *accel,
                               double dt_s);
/* ... and gf_sins_step_group the same way, over sub-intervals dt_s[m] of their own
 * (m = 1..GF_SINS_MAX_SUBSAMPLES; the integrated filter's grouped mechanization). */
gf_status gf_sins_step_group_trusted(gf_sins_state *state, int m, const double *gyro,
                                     const double *accel, const double *dt_s);

#ifdef __cplusplus
}
#endif

#endif /* GF_SINS_H */
