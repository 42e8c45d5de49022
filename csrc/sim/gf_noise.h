/* gf_noise.h — random sensor errors for simulation inside the C core (the vehicle FMU):
 * a seeded generator kept in the caller's struct (no global state: an FMU state holds
 * it, so a restored state replays the same noise) and the IMU noise model of
 * gfins_fmi.ImuNoise, in SI units, with the same per-sample conventions:
 *   gyro white:   std per sample N / sqrt(dt)        (N, angle random walk, rad/sqrt(s))
 *   accel white:  std per sample S sqrt(1 / (2 dt))  (S, one-sided ASD, m/s^2/sqrt(Hz))
 *   Gauss-Markov: y_k = a y_(k-1) + (1 - a) x_k, a = exp(-dt / tau), scaled to the
 *                 stationary std and started in steady state
 *   band-limited: the same recursion with a = exp(-2 pi f_c dt)
 *   random walk:  b_k = b_(k-1) + K sqrt(dt) w_k        (K in unit/sqrt(s))
 * Generator: xoshiro256** (Blackman & Vigna) seeded by splitmix64; normal deviates by
 * Box-Muller. The numpy generator of ImuNoise.sample and this one draw different
 * numbers from the same distributions (tests compare the statistics). */
#ifndef GF_NOISE_H
#define GF_NOISE_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
typedef struct gf_rng {
    uint64_t s[4];
    double spare;          /* second Box-Muller deviate */
    int has_spare;
} gf_rng;

typedef struct gf_imu_noise {
    double gyro_arw_rad_sqrt_s;
    double gyro_gm_std_rad_s, gyro_gm_tau_s;          /* bias instability */
    double gyro_rrw_rad_s_sqrt_s;                     /* rate random walk */
    double accel_asd_m_s2_sqrt_hz;                    /* white, one-sided ASD */
    double accel_gm_std_m_s2, accel_gm_tau_s;
    double accel_rw_m_s2_sqrt_s;
    double gyro_band_std_rad_s, accel_band_std_m_s2, band_hz;
} gf_imu_noise;

typedef struct gf_imu_noise_state {
    gf_imu_noise p;
    gf_rng rng;
    double gyro_gm[3], gyro_rw[3], gyro_band[3];
    double accel_gm[3], accel_rw[3], accel_band[3];
    int started;           /* 0 until the first sample (steady-state start drawn then) */
} gf_imu_noise_state;

/* Seeds a generator (any seed, 0 included). */
gf_status gf_rng_seed(gf_rng *rng, uint64_t seed);
/* n standard normal deviates. */
gf_status gf_rng_normal(gf_rng *rng, size_t n, double *out);

/* One step of n first-order Gauss-Markov processes sharing a = exp(-dt / tau) (the
 * recursion above), component i of stationary std std[i]: y_i = a y_i + (1 - a) x_i,
 * x_i ~ N(0, std_i^2 (1 + a) / (1 - a)); first != 0 draws y_i from the stationary
 * distribution before the step. Components with std[i] <= 0 draw nothing and are left
 * unchanged. The IMU noise model and the aiding-sensor simulation (gf_aiding_sim) use it. */
gf_status gf_gauss_markov_step(gf_rng *rng, size_t n, const double *std, double a, int first,
                               double *y);

/* Checks the parameters (finite, >= 0; correlation times and band > 0 where the
 * corresponding std is > 0) and seeds the state. Error: GF_ERR_BAD_PARAMETER with
 * *bad (may be NULL) = index of the offending field in the struct order, 0-based. */
gf_status gf_imu_noise_init(gf_imu_noise_state *state, const gf_imu_noise *params,
                            uint64_t seed, int *bad);

/* n samples of noise for sampling interval dt_s: gyro (n x 3, rad/s) and accel (n x 3,
 * m/s^2) to add to the sensor rates. Errors: GF_ERR_BAD_TIME (dt <= 0),
 * GF_ERR_BAD_PARAMETER (the state's parameters fail gf_imu_noise_init's checks: a
 * corrupted state), GF_ERR_OUT_OF_RANGE (parameters so large for this dt that the noise
 * overflows); the state is unchanged on error. */
gf_status gf_imu_noise_run(gf_imu_noise_state *state, size_t n, double dt_s, double *gyro_rad_s,
                           double *accel_m_s2);
/* CDEF END */

/* Checks a state handed in by a caller (e.g. restored from saved bytes): parameters as
 * gf_imu_noise_init checks them (GF_ERR_BAD_PARAMETER), the coloured-noise states and
 * the generator's spare deviate finite (GF_ERR_NONFINITE_INPUT). Any generator bits
 * are a valid xoshiro256** state (all zero only repeats zero). */
gf_status gf_imu_noise_state_check(const gf_imu_noise_state *state);

#ifdef __cplusplus
}
#endif

#endif /* GF_NOISE_H */
