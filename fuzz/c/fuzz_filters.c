/* fuzz_filters.c — libFuzzer target: the signal-conditioning and sensor-error models
 * (gf_biquad.h, gf_imu_error.h, gf_noise.h) with any coefficients, parameters, samples
 * and damaged structs.
 * Oracles (fuzz_data.h): valid statuses; finite outputs on GF_OK and in the rows before
 * *n_done; gf_biquad_set_state leaves the filter unchanged on error; a filter made by
 * gf_biquad_init passes gf_biquad_check; apply then compensate returns the input (1e-6
 * relative) where both succeed. */
#include "fuzz_data.h"
#include "nav/gf_biquad.h"
#include "nav/gf_imu_error.h"
#include "sim/gf_noise.h"

#define MAX_RUN 8

static void fuzz_biquad(fz *d)
{
    static gf_biquad f, before; /* 16 kB */
    const size_t ns = fz_u8(d) % (GF_BIQUAD_MAX_SECTIONS + 2);
    const size_t nc = fz_u8(d) % 6;
    double sos[6 * (GF_BIQUAD_MAX_SECTIONS + 1)];
    for (size_t i = 0; i < ns; ++i) {
        fz_nums(d, sos + 6 * i, 6, 1.0);
        if (fz_u8(d) & 3)
            sos[6 * i + 3] = 1.0; /* a0 */
    }
    size_t bad = 0;
    gf_status st = gf_biquad_init(&f, ns, sos, nc, &bad);
    FZ_STATUS(st, "gf_biquad_init");
    if (st != GF_OK)
        return;
    FZ_REQUIRE(gf_biquad_check(&f) == GF_OK, "gf_biquad_init made a filter gf_biquad_check refuses");
    double z[GF_BIQUAD_MAX_SECTIONS * 5 * 2 + 1];
    const size_t nz = ns * nc * 2 + (fz_u8(d) % 8 == 0);
    fz_nums(d, z, nz, 10.0);
    before = f;
    st = gf_biquad_set_state(&f, z, nz);
    FZ_STATUS(st, "gf_biquad_set_state");
    if (st != GF_OK)
        FZ_REQUIRE(memcmp(&f, &before, sizeof f) == 0, "gf_biquad_set_state error changed the filter");
    const size_t n = 1 + fz_index(d, MAX_RUN);
    double x[MAX_RUN * 5], y[MAX_RUN * 5];
    fz_nums(d, x, n * nc, 10.0);
    size_t done = 999;
    st = gf_biquad_run(&f, n, x, y, &done);
    FZ_STATUS(st, "gf_biquad_run");
    FZ_REQUIRE(done <= n && (st != GF_OK || done == n), "gf_biquad_run n_done");
    FZ_REQUIRE(fz_all_finite(y, done * nc), "gf_biquad_run: non-finite rows done");
    for (int j = 0, k = 1 + fz_u8(d) % 4; j < k; ++j)
        ((uint8_t *)&f)[fz_index(d, sizeof f)] = fz_u8(d);
    FZ_STATUS(gf_biquad_check(&f), "gf_biquad_check");
    /* buffers for any channel count the damaged struct may claim (the caller's part) */
    double xd[GF_BIQUAD_MAX_CHANNELS], yd[GF_BIQUAD_MAX_CHANNELS];
    fz_nums(d, xd, GF_BIQUAD_MAX_CHANNELS, 10.0);
    FZ_STATUS(gf_biquad_run(&f, f.n_channels <= GF_BIQUAD_MAX_CHANNELS ? 1 : 0, xd, yd, &done),
              "gf_biquad_run on a damaged filter");
}

static void fuzz_imu_error(fz *d)
{
    gf_imu_errors e;
    memset(&e, 0, sizeof e);
    const double small = fz_u8(d) & 1 ? 0.01 : 1.0;
    for (int i = 0; i < 3; ++i) {
        e.g_scale[i] = fz_num(d, small);
        e.a_scale[i] = fz_num(d, small);
        e.g_bias_rad_s[i] = fz_num(d, 0.01);
        e.a_bias_m_s2[i] = fz_num(d, 0.1);
        e.a_k2_s2_m[i] = fz_num(d, 1e-5);
        e.a_lever_pos_m[4 * i] = fz_num(d, 0.05);
    }
    for (int i = 0; i < 9; ++i) {
        e.g_misalign_rad[i] = i % 4 ? fz_num(d, 0.01) : 0.0;
        e.a_misalign_rad[i] = i % 4 ? fz_num(d, 0.01) : 0.0;
    }
    e.t0 = fz_num(d, 30.0);
    e.temp_order = (int)(fz_u8(d) % (GF_IMU_TEMP_ORDER_MAX + 2));
    fz_nums(d, e.g_bias_tc, 3 * GF_IMU_TEMP_ORDER_MAX, 1e-4);
    fz_nums(d, e.g_scale_tc, 3 * GF_IMU_TEMP_ORDER_MAX, 1e-4);
    fz_nums(d, e.a_bias_tc, 3 * GF_IMU_TEMP_ORDER_MAX, 1e-4);
    fz_nums(d, e.a_scale_tc, 3 * GF_IMU_TEMP_ORDER_MAX, 1e-4);
    int bad = 0;
    gf_status st = gf_imu_errors_check(&e, &bad);
    FZ_STATUS(st, "gf_imu_errors_check");
    const size_t n = 1 + fz_index(d, MAX_RUN);
    double w[3 * MAX_RUN], f[3 * MAX_RUN], T[MAX_RUN], wo[3 * MAX_RUN], fo[3 * MAX_RUN],
        wb[3 * MAX_RUN], fb[3 * MAX_RUN];
    fz_nums(d, w, 3 * n, 3.0);
    fz_nums(d, f, 3 * n, 30.0);
    fz_nums(d, T, n, 40.0);
    const int with_t = fz_u8(d) & 1;
    size_t done = 999, done2 = 999;
    st = gf_imu_apply(&e, n, w, f, with_t ? T : NULL, wo, fo, &done);
    FZ_STATUS(st, "gf_imu_apply");
    FZ_REQUIRE(done <= n && fz_all_finite(wo, 3 * done) && fz_all_finite(fo, 3 * done),
               "gf_imu_apply: rows done");
    const gf_status st2 = gf_imu_compensate(&e, done, wo, fo, with_t ? T : NULL, wb, fb, &done2);
    FZ_STATUS(st2, "gf_imu_compensate");
    FZ_REQUIRE(done2 <= done && fz_all_finite(wb, 3 * done2) && fz_all_finite(fb, 3 * done2),
               "gf_imu_compensate: rows done");
    /* the compensation inverts the model: back to the inputs to a few ulp of the largest
     * term (scale errors < 0.5, misalignment < 0.1: condition number below ~10) */
    for (size_t k = 0; k < done2; ++k)
        for (int i = 0; i < 3; ++i) {
            const double sw = 1e-9 * (1.0 + fabs(w[3 * k]) + fabs(w[3 * k + 1]) + fabs(w[3 * k + 2]) +
                                      fabs(wo[3 * k + i]));
            const double sf = 1e-9 * (1.0 + fabs(f[3 * k]) + fabs(f[3 * k + 1]) + fabs(f[3 * k + 2]) +
                                      fabs(fo[3 * k + i]));
            FZ_REQUIRE(fabs(wb[3 * k + i] - w[3 * k + i]) <= sw * 1e3 &&
                           fabs(fb[3 * k + i] - f[3 * k + i]) <= sf * 1e3,
                       "apply -> compensate (check %d field %d, temp %d order %d): row %zu axis %d: w %.17g -> %.17g, f %.17g -> %.17g", (int)gf_imu_errors_check(&e, &bad), bad, with_t, e.temp_order, k, i,
                       w[3 * k + i], wb[3 * k + i], f[3 * k + i], fb[3 * k + i]);
        }
}

static void fuzz_noise(fz *d)
{
    gf_imu_noise p;
    double *x = &p.gyro_arw_rad_sqrt_s;
    for (size_t i = 0; i < sizeof p / sizeof(double); ++i)
        x[i] = fz_pos(d, i == 10 ? 10.0 : 0.01);
    gf_imu_noise_state s;
    int bad = 0;
    gf_status st = gf_imu_noise_init(&s, &p, fz_u64(d), &bad);
    FZ_STATUS(st, "gf_imu_noise_init");
    if (st != GF_OK)
        return;
    FZ_REQUIRE(gf_imu_noise_state_check(&s) == GF_OK, "gf_imu_noise_init made a state its check refuses");
    const size_t n = 1 + fz_index(d, MAX_RUN);
    double g[3 * MAX_RUN], a[3 * MAX_RUN];
    st = gf_imu_noise_run(&s, n, fz_pos(d, 0.01), g, a);
    FZ_STATUS(st, "gf_imu_noise_run");
    FZ_FINITE_ON_OK(st, g, 3 * n, "gf_imu_noise_run gyro");
    FZ_FINITE_ON_OK(st, a, 3 * n, "gf_imu_noise_run accel");
    if (st == GF_OK)
        FZ_REQUIRE(gf_imu_noise_state_check(&s) == GF_OK, "gf_imu_noise_run left a state its check refuses");
    for (int j = 0, k = 1 + fz_u8(d) % 4; j < k; ++j)
        ((uint8_t *)&s)[fz_index(d, sizeof s)] = fz_u8(d);
    FZ_STATUS(gf_imu_noise_state_check(&s), "gf_imu_noise_state_check");
    FZ_STATUS(gf_imu_noise_run(&s, 1, 0.01, g, a), "gf_imu_noise_run on a damaged state");
    gf_rng rng;
    gf_rng_seed(&rng, fz_u64(d));
    double y[3], std[3];
    fz_nums(d, std, 3, 1.0);
    fz_nums(d, y, 3, 1.0);
    st = gf_gauss_markov_step(&rng, 3, std, fz_num(d, 1.0), fz_u8(d) & 1, y);
    FZ_STATUS(st, "gf_gauss_markov_step");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz d = {data, size};
    switch (fz_u8(&d) % 3) {
    case 0: fuzz_biquad(&d); break;
    case 1: fuzz_imu_error(&d); break;
    default: fuzz_noise(&d); break;
    }
    return 0;
}
