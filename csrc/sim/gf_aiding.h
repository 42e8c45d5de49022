/* gf_aiding.h — the aiding sensors riding the vehicle of gf_vehicle: a GNSS receiver,
 * a barometer and an odometer, their truth and their simulated outputs (the vehicle FMU
 * and gfins_fmi.vehicle.simulate_vehicle both call this module, so a run of either with
 * the same parameters and seed gives the same bits).
 *
 * Geometry (the conventions of the integrated-navigation wave, which its filters share;
 * docs/cosim.md). x is the vehicle truth at the epoch (gf_vehicle_sample):
 * C = C_b^n of q_b^n, w_ib^b the true rate, v^n the ENU velocity, (L, lambda, h) the IMU.
 *   GNSS antenna at lever arm l_gnss (m, body RFU, IMU -> phase centre):
 *     l^n = C l_gnss
 *     L_a = L + l^n_N / (R_M + h),  lambda_a = lambda + l^n_E / ((R_N + h) cos L),
 *     h_a = h + l^n_U                                     (R_M, R_N at L: gf_earth)
 *     v_a^n = v^n + C (w_eb^b x l_gnss),  w_eb^b = w_ib^b - C^T w_ie^n
 *   Odometer, wheel point at lever arm l_odo (m, body RFU), forward axis y:
 *     u_true = [C^T v^n + w_eb^b x l_odo]_y,  u = (1 + k_odo) u_true + n_u
 *   Barometer at the IMU: h_baro = h + b + n_h, b = b_0 + b_rw + b_gm.
 *
 * Errors. GNSS position error e (m, ENU) = white (std pos_std_m per axis) + first-order
 * Gauss-Markov (stationary std pos_gm_std_m, correlation time pos_gm_tau_s), mapped to
 * geodetic coordinates like the lever arm (e_N / (R_M + h), e_E / ((R_N + h) cos L),
 * e_U); velocity error white (vel_std_m_s, ENU). The receiver reports per epoch
 * pos_std = sqrt(pos_std^2 + pos_gm_std^2) per axis, vel_std, and a fixed quality
 * (RTKLIB Q: 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP; 0 unknown). Barometer bias:
 * constant b_0, random walk b_rw (steps K sqrt(1 / rate) between epochs, 0 at the first
 * epoch) and Gauss-Markov b_gm (stationary std, correlation time); white noise std_m
 * (the reported std). Odometer: scale-factor error k_odo, white noise std_m_s (reported).
 * Gauss-Markov recursions: gf_gauss_markov_step (gf_noise.h), started in steady state at
 * the first epoch, a = exp(-(1 / rate) / tau).
 *
 * Randomness. One generator per sensor (gf_rng, xoshiro256**), seeded from the one seed
 * given (seed XOR a per-sensor constant), kept in the caller's struct: no global state.
 * Each epoch draws its numbers in epoch order whether or not it is delivered (outages
 * mask epochs without changing the noise of the others), in the order Gauss-Markov,
 * random walk, white; a component of zero std draws nothing.
 *
 * Timing. Epoch k of a sensor is valid at t_k = (t0 + offset_s) + k / rate_hz, k >= 0,
 * t0 the vehicle's start time: epochs need not coincide with the IMU samples. The truth
 * at t_k comes from a copy of the vehicle that this module steps from epoch to epoch
 * (gf_vehicle_step; gf_vehicle_truth at the copy's time): the values of an epoch depend
 * on the parameters and the seed only, never on the step sizes of the caller. A GNSS
 * epoch is valid at t_k and delivered at t_k + latency_s; barometer and odometer epochs
 * are delivered at their time of validity. An epoch counts as reached by time t when
 * its time is <= t + tol, tol = 1e-9 max(1, |t|) s (the FMU glue's time tolerance:
 * a master's accumulated clock then delivers an epoch at a communication point in the
 * step ending there). GNSS epochs valid in an outage are never delivered: explicit
 * intervals [start, end) (absolute times) and a periodic rule (first outage at
 * outage_first_s, one every outage_period_s, each outage_duration_s long; duration 0:
 * none; t in an outage when t >= first and fmod(t - first, period) < duration).
 * Drive mode (gf_vehicle_command): gf_aiding_sync hands the module the commanded
 * vehicle, since its copy cannot foresee commands.
 */
#ifndef GF_AIDING_H
#define GF_AIDING_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "sim/gf_noise.h"
#include "sim/gf_vehicle.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GF_AIDING_MAX_RATE_HZ 1000.0 /* any sensor */
#define GF_AIDING_MAX_LEVER_M 100.0  /* |lever arm| */

/* CDEF BEGIN */
#define GF_AIDING_MAX_OUTAGES 8      /* explicit GNSS outage intervals */
#define GF_GNSS_QUEUE 16             /* epochs measured, awaiting delivery (latency) */

typedef struct gf_gnss_params {
    int32_t enabled;                          /* 0: no GNSS epochs */
    int32_t quality;                          /* reported RTKLIB Q, 0..6 */
    double rate_hz;                           /* 0 < rate <= GF_AIDING_MAX_RATE_HZ */
    double offset_s;                          /* first epoch at t0 + offset, >= 0 */
    double latency_s;                         /* >= 0; latency * rate <= GF_GNSS_QUEUE - 2 */
    double lever_arm_m[3];                    /* IMU -> antenna, body RFU */
    double pos_std_m[3];                      /* white position error, ENU */
    double vel_std_m_s[3];                    /* white velocity error, ENU */
    double pos_gm_std_m[3];                   /* Gauss-Markov position error, ENU */
    double pos_gm_tau_s;                      /* > 0 where pos_gm_std > 0 */
    int32_t n_outages;                        /* 0 .. GF_AIDING_MAX_OUTAGES */
    int32_t reserved;
    double outage_start_s[GF_AIDING_MAX_OUTAGES]; /* [start, end), start < end */
    double outage_end_s[GF_AIDING_MAX_OUTAGES];
    double outage_first_s, outage_period_s, outage_duration_s; /* periodic rule */
} gf_gnss_params;

typedef struct gf_baro_params {
    int32_t enabled;
    int32_t reserved;
    double rate_hz, offset_s;
    double std_m;                             /* white noise (reported std) */
    double bias0_m;                           /* constant part of the bias */
    double bias_rw_m_sqrt_s;                  /* random walk K, m/sqrt(s) */
    double bias_gm_std_m, bias_gm_tau_s;      /* Gauss-Markov part */
} gf_baro_params;

typedef struct gf_odo_params {
    int32_t enabled;
    int32_t reserved;
    double rate_hz, offset_s;
    double lever_arm_m[3];                    /* IMU -> wheel contact point, body RFU */
    double scale_error;                       /* k_odo, |k| < 0.5 */
    double std_m_s;                           /* white noise (reported std) */
} gf_odo_params;

typedef struct gf_aiding_params {
    gf_gnss_params gnss;
    gf_baro_params baro;
    gf_odo_params odo;
} gf_aiding_params;

/* One GNSS epoch: measured values, what the receiver reports, and the truth. */
typedef struct gf_gnss_epoch {
    double t_s;                               /* time of validity */
    double t_delivered_s;                     /* t_s + latency */
    double lat_rad, lon_rad, h_m;             /* antenna, with errors */
    double vel_enu_m_s[3];
    double pos_std_m[3];                      /* reported, ENU */
    double vel_std_m_s[3];
    double true_lat_rad, true_lon_rad, true_h_m;
    double true_vel_enu_m_s[3];
    double quality;                           /* RTKLIB Q (an integer) */
} gf_gnss_epoch;

typedef struct gf_baro_epoch {
    double t_s;
    double h_m;                               /* h + bias + noise */
    double std_m;
    double true_h_m;
    double bias_m;                            /* true bias b */
} gf_baro_epoch;

typedef struct gf_odo_epoch {
    double t_s;
    double speed_m_s;                         /* (1 + k) u_true + noise */
    double std_m_s;
    double true_speed_m_s;                    /* u_true */
} gf_odo_epoch;

/* The newest epoch of each sensor delivered by gf_aiding_step, and how many were. */
typedef struct gf_aiding_output {
    int32_t gnss_new, baro_new, odo_new;      /* epochs delivered by the last call */
    int32_t gnss_quality;
    gf_gnss_epoch gnss;                       /* newest; held when none is new; NaN before */
    gf_baro_epoch baro;
    gf_odo_epoch odo;
} gf_aiding_output;

typedef struct gf_aiding_sim {
    gf_aiding_params p;
    double t0_s;                              /* start time: epoch origin */
    double t_s;                               /* time reached by the last call */
    gf_vehicle_state vehicle;                 /* the copy, at the last epoch measured */
    gf_rng gnss_rng, baro_rng, odo_rng;
    uint64_t gnss_k, baro_k, odo_k;           /* next epoch to measure */
    double gnss_gm_m[3];                      /* Gauss-Markov position error, ENU */
    double baro_rw_m, baro_gm_m;
    int32_t queue_head, queue_n;              /* GNSS epochs awaiting delivery */
    gf_gnss_epoch queue[GF_GNSS_QUEUE];
} gf_aiding_sim;

/* Which parameter gf_aiding_init refused (*bad). */
enum {
    GF_AIDING_BAD_NONE = 0,
    GF_AIDING_BAD_GNSS_ENABLED = 1, GF_AIDING_BAD_GNSS_RATE, GF_AIDING_BAD_GNSS_OFFSET,
    GF_AIDING_BAD_GNSS_LATENCY, GF_AIDING_BAD_GNSS_LEVER_ARM, GF_AIDING_BAD_GNSS_POS_STD,
    GF_AIDING_BAD_GNSS_VEL_STD, GF_AIDING_BAD_GNSS_GM_STD, GF_AIDING_BAD_GNSS_GM_TAU,
    GF_AIDING_BAD_GNSS_QUALITY, GF_AIDING_BAD_GNSS_N_OUTAGES, GF_AIDING_BAD_GNSS_PERIODIC,
    GF_AIDING_BAD_BARO_ENABLED = 20, GF_AIDING_BAD_BARO_RATE, GF_AIDING_BAD_BARO_OFFSET,
    GF_AIDING_BAD_BARO_STD, GF_AIDING_BAD_BARO_BIAS0, GF_AIDING_BAD_BARO_RW,
    GF_AIDING_BAD_BARO_GM_STD, GF_AIDING_BAD_BARO_GM_TAU,
    GF_AIDING_BAD_ODO_ENABLED = 40, GF_AIDING_BAD_ODO_RATE, GF_AIDING_BAD_ODO_OFFSET,
    GF_AIDING_BAD_ODO_LEVER_ARM, GF_AIDING_BAD_ODO_SCALE, GF_AIDING_BAD_ODO_STD,
    GF_AIDING_BAD_GNSS_OUTAGE = 100           /* + k: outage interval k (0-based) */
};

/* Checks the parameters of the enabled sensors, copies the vehicle (just initialised or
 * stepped to the start time: its time is t0) and seeds the generators from seed. *out
 * (may be NULL) is cleared: counts 0, epochs NaN.
 * Errors: GF_ERR_BAD_PARAMETER with *bad (may be NULL) = GF_AIDING_BAD_* (enabled must
 * be 0 or 1; finite values; rates in (0, GF_AIDING_MAX_RATE_HZ]; offsets, latency, stds,
 * random walk >= 0; a correlation time > 0 where its std is > 0; |lever arm| <=
 * GF_AIDING_MAX_LEVER_M; quality 0..6; outages start < end; periodic duration <= period,
 * period > 0 when duration > 0; |k_odo| < 0.5). */
gf_status gf_aiding_init(gf_aiding_sim *sim, const gf_aiding_params *params,
                         const gf_vehicle_state *vehicle, uint64_t seed, gf_aiding_output *out,
                         int *bad);

/* Checks a whole simulator struct handed in by a caller (an FMU state): queue indices,
 * outage count, parameters, finite state, the vehicle copy (gf_vehicle_state_check).
 * Errors: GF_ERR_BAD_SIZE, GF_ERR_BAD_PARAMETER, GF_ERR_NONFINITE_INPUT. */
gf_status gf_aiding_sim_check(const gf_aiding_sim *sim);

/* What a refused parameter (bad: GF_AIDING_BAD_*) must satisfy, as a static phrase
 * without the parameter's name ("must be finite and >= 0"): callers prefix their own
 * name of it (FMU parameter, Python attribute). Never NULL. */
const char *gf_aiding_bad_string(int bad);

/* Advances to t_end_s (>= the time of the last call, less tol): measures every epoch
 * reached and delivers those due. out->*_new = number delivered by this call; out's
 * epochs are the newest delivered (unchanged when none: the caller holds them). A step
 * that spans several epochs of a sensor delivers them all; out shows the newest
 * (gf_aiding_run keeps every one). Errors: GF_ERR_BAD_TIME (t_end non-finite or before
 * the last call by more than tol), GF_ERR_DIVERGED (the vehicle passed +-89 deg
 * latitude); sim and out unchanged. */
gf_status gf_aiding_step(gf_aiding_sim *sim, double t_end_s, gf_aiding_output *out);

/* Drive mode: the vehicle has been commanded at its time t_c (gf_vehicle_command):
 * the copy becomes this vehicle. Every epoch up to t_c must have been measured already
 * (gf_aiding_step to t_c before), else GF_ERR_BAD_TIME. */
gf_status gf_aiding_sync(gf_aiding_sim *sim, const gf_vehicle_state *vehicle);

/* Batch: advances to t_end_s and writes every epoch delivered, in time order, into the
 * arrays (capacities *_cap; an array may be NULL when its sensor is disabled).
 * *n_* = epochs written. GF_ERR_BAD_SIZE when an array is too small (sim unchanged, the
 * arrays hold the first *_cap epochs); other errors as gf_aiding_step. */
gf_status gf_aiding_run(gf_aiding_sim *sim, double t_end_s, gf_gnss_epoch *gnss,
                        size_t gnss_cap, size_t *n_gnss, gf_baro_epoch *baro, size_t baro_cap,
                        size_t *n_baro, gf_odo_epoch *odo, size_t odo_cap, size_t *n_odo);

/* The noise-free measurement geometry at one truth sample (the formulas above), for
 * checks and filters' tests: antenna position and ENU velocity for lever arm l_gnss_m
 * (may be NULL: zero), forward wheel speed for l_odo_m (may be NULL). Any output may be
 * NULL. Errors: GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_PARAMETER (|L| >= 90 deg). */
gf_status gf_aiding_truth(const gf_vehicle_sample *x, const double *l_gnss_m,
                          const double *l_odo_m, double *lat_rad, double *lon_rad, double *h_m,
                          double *vel_enu_m_s, double *speed_m_s);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_AIDING_H */
