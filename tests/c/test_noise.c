/* test_noise.c — the seeded generator and the IMU noise model (gf_noise) against their
 * definitions: normal moments, reproducibility, each process's per-sample law, bad
 * input. Sample sizes and bounds: a moment estimated from n deviates has a standard
 * error of 1/sqrt(n) (mean) or sqrt(2/n) (variance); bounds are 5 standard errors. */
#include <math.h>
#include <string.h>

#include "sim/gf_noise.h"
#include "gf_test.h"

enum { N = 200000 };
static double g_buf[3 * N], g_buf2[3 * N];

static void moments(const double *x, size_t n, size_t stride, double *mean, double *var)
{
    double m = 0.0, v = 0.0;
    for (size_t i = 0; i < n; ++i)
        m += x[i * stride];
    m /= (double)n;
    for (size_t i = 0; i < n; ++i)
        v += (x[i * stride] - m) * (x[i * stride] - m);
    *mean = m;
    *var = v / (double)(n - 1);
}

static void test_normal(void)
{
    gf_rng r, r2;
    CHECK(gf_rng_seed(&r, 12345) == GF_OK && gf_rng_seed(&r2, 12345) == GF_OK, "seed");
    CHECK(gf_rng_normal(&r, N, g_buf) == GF_OK, "draw");
    gf_rng_normal(&r2, N, g_buf2);
    CHECK(memcmp(g_buf, g_buf2, N * sizeof *g_buf) == 0, "same seed, same stream");
    double m, v;
    moments(g_buf, N, 1, &m, &v);
    CHECK(fabs(m) < 5.0 / sqrt(N), "mean %g", m);
    CHECK(fabs(v - 1.0) < 5.0 * sqrt(2.0 / N), "variance %g", v);
    double m4 = 0.0, lag1 = 0.0; /* Gaussian kurtosis 3; no correlation between draws */
    for (size_t i = 0; i < N; ++i)
        m4 += pow(g_buf[i], 4);
    for (size_t i = 1; i < N; ++i)
        lag1 += g_buf[i] * g_buf[i - 1];
    CHECK(fabs(m4 / N - 3.0) < 5.0 * sqrt(96.0 / N), "fourth moment %g", m4 / N);
    CHECK(fabs(lag1 / N) < 5.0 / sqrt(N), "lag-1 correlation %g", lag1 / N);
    gf_rng_seed(&r2, 12346);
    gf_rng_normal(&r2, 16, g_buf2);
    CHECK(memcmp(g_buf, g_buf2, 16 * sizeof *g_buf) != 0, "another seed, another stream");
}

static void test_processes(void)
{
    const double dt = 0.01, N_arw = 2e-4, asd = 3e-4, sigma = 1e-5, tau = 0.5, K = 1e-6;
    gf_imu_noise p;
    memset(&p, 0, sizeof p);
    p.gyro_arw_rad_sqrt_s = N_arw;
    p.accel_asd_m_s2_sqrt_hz = asd;
    gf_imu_noise_state s;
    CHECK(gf_imu_noise_init(&s, &p, 1, NULL) == GF_OK, "init white");
    CHECK(gf_imu_noise_run(&s, N, dt, g_buf, g_buf2) == GF_OK, "run white");
    double m, v;
    moments(g_buf, 3 * N, 1, &m, &v);
    CHECK(fabs(sqrt(v) / (N_arw / sqrt(dt)) - 1.0) < 5.0 * sqrt(0.5 / (3 * N)), "gyro white std");
    moments(g_buf2, 3 * N, 1, &m, &v);
    CHECK(fabs(sqrt(v) / (asd * sqrt(0.5 / dt)) - 1.0) < 5.0 * sqrt(0.5 / (3 * N)), "accel white std");
    memset(&p, 0, sizeof p);
    p.gyro_gm_std_rad_s = sigma;
    p.gyro_gm_tau_s = tau;
    p.accel_rw_m_s2_sqrt_s = K;
    CHECK(gf_imu_noise_init(&s, &p, 2, NULL) == GF_OK, "init GM + RW");
    CHECK(gf_imu_noise_run(&s, N, dt, g_buf, g_buf2) == GF_OK, "run GM + RW");
    /* Gauss-Markov: y_k - a y_(k-1) is white with std sigma sqrt(1 - a^2) */
    const double a = exp(-dt / tau);
    double r_var = 0.0, d_var = 0.0;
    for (size_t k = 1; k < N; ++k)
        for (int i = 0; i < 3; ++i) {
            const double r = g_buf[3 * k + i] - a * g_buf[3 * (k - 1) + i];
            const double d = g_buf2[3 * k + i] - g_buf2[3 * (k - 1) + i];
            r_var += r * r;
            d_var += d * d;
        }
    r_var /= 3.0 * (N - 1);
    d_var /= 3.0 * (N - 1);
    CHECK(fabs(sqrt(r_var) / (sigma * sqrt(1.0 - a * a)) - 1.0) < 5.0 * sqrt(0.5 / (3 * N)),
          "GM innovation std");
    CHECK(fabs(sqrt(d_var) / (K * sqrt(dt)) - 1.0) < 5.0 * sqrt(0.5 / (3 * N)), "RW step std");
    /* the GM process is stationary from the first sample: its std over many short
     * independent starts equals sigma (1000 starts x 3 axes) */
    double first_var = 0.0;
    for (int run = 0; run < 1000; ++run) {
        double gy[3], ac[3];
        gf_imu_noise_init(&s, &p, 1000 + (uint64_t)run, NULL);
        gf_imu_noise_run(&s, 1, dt, gy, ac);
        for (int i = 0; i < 3; ++i)
            first_var += gy[i] * gy[i];
    }
    CHECK(fabs(sqrt(first_var / 3000.0) / sigma - 1.0) < 5.0 * sqrt(0.5 / 3000.0),
          "GM steady-state start: std %g vs %g", sqrt(first_var / 3000.0), sigma);

    /* band-limited noise (gf_noise.h: the Gauss-Markov recursion with a = exp(-2 pi f_c
     * dt), a first-order low-pass of corner f_c): stationary std sigma_b, and
     * y_k - a y_(k-1) white with std sigma_b sqrt(1 - a^2), a from the corner. At f_c =
     * 5 Hz, dt = 0.01 s: a = 0.730; a corner off by 2 (a = 0.855) moves that std by 37 %,
     * the bound is 5 standard errors (0.6 %) */
    const double sb_g = 2e-5, sb_a = 3e-3, fc = 5.0;
    memset(&p, 0, sizeof p);
    p.gyro_band_std_rad_s = sb_g;
    p.accel_band_std_m_s2 = sb_a;
    p.band_hz = fc;
    CHECK(gf_imu_noise_init(&s, &p, 3, NULL) == GF_OK, "init band-limited");
    CHECK(gf_imu_noise_run(&s, N, dt, g_buf, g_buf2) == GF_OK, "run band-limited");
    const double ab = exp(-2.0 * 3.14159265358979323846 * fc * dt);
    double rg = 0.0, ra = 0.0;
    for (size_t k = 1; k < N; ++k)
        for (int i = 0; i < 3; ++i) {
            const double eg = g_buf[3 * k + i] - ab * g_buf[3 * (k - 1) + i];
            const double ea = g_buf2[3 * k + i] - ab * g_buf2[3 * (k - 1) + i];
            rg += eg * eg;
            ra += ea * ea;
        }
    rg /= 3.0 * (N - 1);
    ra /= 3.0 * (N - 1);
    CHECK(fabs(sqrt(rg) / (sb_g * sqrt(1.0 - ab * ab)) - 1.0) < 5.0 * sqrt(0.5 / (3 * N)),
          "band-limited gyro innovation std %g vs %g", sqrt(rg), sb_g * sqrt(1.0 - ab * ab));
    CHECK(fabs(sqrt(ra) / (sb_a * sqrt(1.0 - ab * ab)) - 1.0) < 5.0 * sqrt(0.5 / (3 * N)),
          "band-limited accel innovation std");
    /* the stationary std: samples are correlated (a = 0.73), the effective sample count
     * is 3N (1 - a^2) / (1 + a^2) = 1.8e5, the standard error of the std 0.17 %; bound 1 %
     * (6 standard errors) */
    moments(g_buf, 3 * N, 1, &m, &v);
    CHECK(fabs(sqrt(v) / sb_g - 1.0) < 0.01, "band-limited gyro std %g vs %g", sqrt(v), sb_g);
}

static void test_bad_input(void)
{
    gf_imu_noise p;
    gf_imu_noise_state s;
    int bad = -1;
    memset(&p, 0, sizeof p);
    p.accel_rw_m_s2_sqrt_s = -1.0;
    CHECK(gf_imu_noise_init(&s, &p, 0, &bad) == GF_ERR_BAD_PARAMETER && bad == 7, "negative (bad %d)", bad);
    memset(&p, 0, sizeof p);
    p.gyro_band_std_rad_s = 1e-5;
    p.band_hz = 0.0;
    CHECK(gf_imu_noise_init(&s, &p, 0, &bad) == GF_ERR_BAD_PARAMETER && bad == 10, "band 0 (bad %d)", bad);
    p.band_hz = NAN;
    CHECK(gf_imu_noise_init(&s, &p, 0, &bad) == GF_ERR_BAD_PARAMETER && bad == 10, "band NaN");
    memset(&p, 0, sizeof p);
    CHECK(gf_imu_noise_init(&s, &p, 0, &bad) == GF_OK, "all zero");
    double g[3], a[3];
    CHECK(gf_imu_noise_run(&s, 1, 0.0, g, a) == GF_ERR_BAD_TIME, "dt 0");
    CHECK(gf_imu_noise_run(&s, 1, 0.01, g, a) == GF_OK && g[0] == 0.0 && a[2] == 0.0, "zero noise");
    CHECK(gf_imu_noise_state_check(&s) == GF_OK, "check of a good state");
    /* a state whose parameters were corrupted (a damaged FMU state): refused by the run
     * and by the check, nothing drawn */
    gf_imu_noise_state bad_state = s, before;
    bad_state.p.gyro_arw_rad_sqrt_s = -1.0;
    before = bad_state;
    CHECK(gf_imu_noise_run(&bad_state, 1, 0.01, g, a) == GF_ERR_BAD_PARAMETER &&
              memcmp(&bad_state, &before, sizeof before) == 0,
          "run with a negative ARW in the state: BAD_PARAMETER, unchanged");
    CHECK(gf_imu_noise_state_check(&bad_state) == GF_ERR_BAD_PARAMETER, "check: negative ARW");
    bad_state = s;
    bad_state.p.gyro_gm_std_rad_s = 1e-5;
    bad_state.p.gyro_gm_tau_s = 0.0;
    CHECK(gf_imu_noise_run(&bad_state, 1, 0.01, g, a) == GF_ERR_BAD_PARAMETER, "GM std without tau");
    bad_state = s;
    bad_state.gyro_rw[1] = NAN;
    CHECK(gf_imu_noise_state_check(&bad_state) == GF_ERR_NONFINITE_INPUT, "check: NaN random walk");
}

int main(void)
{
    test_normal();
    test_processes();
    test_bad_input();
    TEST_MAIN_END();
}
