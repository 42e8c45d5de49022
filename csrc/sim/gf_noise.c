/* gf_noise.c — seeded generator and IMU noise model; see gf_noise.h. */
#include "sim/gf_noise.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "base/gf_math.h"

static uint64_t splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

static uint64_t next_u64(gf_rng *r) /* xoshiro256** */
{
    uint64_t *s = r->s;
    const uint64_t result = rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

/* uniform in (0, 1): 53 random bits, never 0 (log below) */
static double uniform_open(gf_rng *r) { return ((double)(next_u64(r) >> 11) + 0.5) * 0x1.0p-53; }

static double normal(gf_rng *r)
{
    if (r->has_spare) {
        r->has_spare = 0;
        return r->spare;
    }
    const double u = uniform_open(r), v = uniform_open(r);
    const double rad = sqrt(-2.0 * log(u)), ang = 2.0 * GF_PI * v;
    r->spare = rad * sin(ang);
    r->has_spare = 1;
    return rad * cos(ang);
}

gf_status gf_rng_seed(gf_rng *rng, uint64_t seed)
{
    if (!rng)
        return GF_ERR_NULL_POINTER;
    uint64_t x = seed;
    for (int i = 0; i < 4; ++i)
        rng->s[i] = splitmix64(&x);
    rng->spare = 0.0;
    rng->has_spare = 0;
    return GF_OK;
}

gf_status gf_rng_normal(gf_rng *rng, size_t n, double *out)
{
    if (!rng || (n && !out))
        return GF_ERR_NULL_POINTER;
    for (size_t i = 0; i < n; ++i)
        out[i] = normal(rng);
    return GF_OK;
}

/* The parameter checks of gf_imu_noise_init: -1 if valid, else the offending field. */
static int params_bad_field(const gf_imu_noise *params)
{
    enum { N_FIELDS = sizeof(gf_imu_noise) / sizeof(double) };
    _Static_assert(sizeof(gf_imu_noise) == N_FIELDS * sizeof(double), "gf_imu_noise: doubles only");
    double f[N_FIELDS];
    memcpy(f, params, sizeof f);
    for (size_t i = 0; i < N_FIELDS; ++i)
        if (!isfinite(f[i]) || f[i] < 0.0)
            return (int)i;
    /* a correlation time or band must be > 0 where its std is used */
    const struct { double std, scale; int field; } need[] = {
        {params->gyro_gm_std_rad_s, params->gyro_gm_tau_s, 2},
        {params->accel_gm_std_m_s2, params->accel_gm_tau_s, 6},
        {params->gyro_band_std_rad_s + params->accel_band_std_m_s2, params->band_hz, 10}};
    for (size_t i = 0; i < sizeof need / sizeof need[0]; ++i)
        if (need[i].std > 0.0 && !(need[i].scale > 0.0))
            return need[i].field;
    return -1;
}

gf_status gf_imu_noise_init(gf_imu_noise_state *state, const gf_imu_noise *params,
                            uint64_t seed, int *bad)
{
    if (bad)
        *bad = -1;
    if (!state || !params)
        return GF_ERR_NULL_POINTER;
    const int field = params_bad_field(params);
    if (field >= 0) {
        if (bad)
            *bad = field;
        return GF_ERR_BAD_PARAMETER;
    }
    memset(state, 0, sizeof *state);
    state->p = *params;
    return gf_rng_seed(&state->rng, seed);
}

gf_status gf_gauss_markov_step(gf_rng *rng, size_t n, const double *std, double a, int first,
                               double *y)
{
    if (!rng || (n && (!std || !y)))
        return GF_ERR_NULL_POINTER;
    if (!(a >= 0.0 && a <= 1.0))
        return GF_ERR_BAD_PARAMETER;
    for (size_t i = 0; i < n; ++i) {
        if (!(std[i] > 0.0))
            continue;
        /* a = 1 (tau >> dt): no innovation, the process is a constant */
        const double sx = a < 1.0 ? std[i] / sqrt((1.0 - a) / (1.0 + a)) : 0.0;
        if (first)
            y[i] = std[i] * normal(rng);
        y[i] = a * y[i] + (1.0 - a) * sx * normal(rng);
    }
    return GF_OK;
}

/* The three axes of one IMU process (one std for the three). */
static void lowpass(gf_rng *r, double y[3], double std, double a, int first)
{
    const double s3[3] = {std, std, std};
    gf_gauss_markov_step(r, 3, s3, a, first, y);
}

gf_status gf_imu_noise_run(gf_imu_noise_state *state, size_t n, double dt_s, double *gyro_rad_s,
                           double *accel_m_s2)
{
    gf_imu_noise_state *const out_state = state;
    if (!state || (n && (!gyro_rad_s || !accel_m_s2)))
        return GF_ERR_NULL_POINTER;
    if (!(dt_s > 0.0) || !isfinite(dt_s))
        return GF_ERR_BAD_TIME;
    if (params_bad_field(&state->p) >= 0) /* a state handed in corrupted */
        return GF_ERR_BAD_PARAMETER;
    /* on a copy, committed when every sample is finite: absurd but finite parameters
     * (stds near 1e300, dt near 1e-300) overflow, found by fuzzing */
    gf_imu_noise_state work = *state;
    state = &work;
    const gf_imu_noise *p = &state->p;
    gf_rng *r = &state->rng;
    const double g_white = p->gyro_arw_rad_sqrt_s / sqrt(dt_s);
    const double a_white = p->accel_asd_m_s2_sqrt_hz * sqrt(0.5 / dt_s);
    const double a_ggm = p->gyro_gm_tau_s > 0.0 ? exp(-dt_s / p->gyro_gm_tau_s) : 0.0;
    const double a_agm = p->accel_gm_tau_s > 0.0 ? exp(-dt_s / p->accel_gm_tau_s) : 0.0;
    const double a_band = exp(-2.0 * GF_PI * p->band_hz * dt_s);
    const double g_rw = p->gyro_rrw_rad_s_sqrt_s * sqrt(dt_s), a_rw = p->accel_rw_m_s2_sqrt_s * sqrt(dt_s);
    for (size_t k = 0; k < n; ++k) {
        const int first = !state->started;
        state->started = 1;
        lowpass(r, state->gyro_gm, p->gyro_gm_std_rad_s, a_ggm, first);
        lowpass(r, state->accel_gm, p->accel_gm_std_m_s2, a_agm, first);
        lowpass(r, state->gyro_band, p->gyro_band_std_rad_s, a_band, first);
        lowpass(r, state->accel_band, p->accel_band_std_m_s2, a_band, first);
        for (int i = 0; i < 3; ++i) {
            if (g_rw > 0.0)
                state->gyro_rw[i] += g_rw * normal(r);
            if (a_rw > 0.0)
                state->accel_rw[i] += a_rw * normal(r);
            const double gw = g_white > 0.0 ? g_white * normal(r) : 0.0;
            const double aw = a_white > 0.0 ? a_white * normal(r) : 0.0;
            gyro_rad_s[3 * k + i] = gw + state->gyro_gm[i] + state->gyro_rw[i] + state->gyro_band[i];
            accel_m_s2[3 * k + i] = aw + state->accel_gm[i] + state->accel_rw[i] + state->accel_band[i];
            if (!isfinite(gyro_rad_s[3 * k + i]) || !isfinite(accel_m_s2[3 * k + i]))
                return GF_ERR_OUT_OF_RANGE;
        }
    }
    *out_state = work;
    return GF_OK;
}

gf_status gf_imu_noise_state_check(const gf_imu_noise_state *state)
{
    if (!state)
        return GF_ERR_NULL_POINTER;
    if (params_bad_field(&state->p) >= 0)
        return GF_ERR_BAD_PARAMETER;
    const double *x[] = {state->gyro_gm, state->gyro_rw, state->gyro_band, state->accel_gm,
                         state->accel_rw, state->accel_band};
    for (size_t i = 0; i < sizeof x / sizeof x[0]; ++i)
        if (!gf_all_finite(x[i], 3))
            return GF_ERR_NONFINITE_INPUT;
    if (!isfinite(state->rng.spare))
        return GF_ERR_NONFINITE_INPUT;
    return GF_OK;
}
