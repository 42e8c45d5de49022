/* test_imu_error.c — the IMU error model (gf_imu_error): apply, compensate, checks.
 *
 * Truth never comes from the code under test:
 *   - apply against the model of gf_imu_error.h written out here element by element
 *     (explicit (I + diag s)(I + N) products, the centripetal term of each inner lever
 *     arm, the K2 square, the temperature polynomials with pow());
 *   - compensate against the identity compensate(apply(x)) = x for random parameter sets
 *     across the model's range and temperatures inside its range of validity, and
 *     against closed forms of the linear special cases (bias and scale only:
 *     w = (w_out - b) / (1 + s); a pure K2: the root of K2 u^2 + u - a = 0);
 *   - the range of validity: a temperature at which a scale factor reaches -1 (the
 *     compensation would divide by 1 + s(T) = 0) or leaves (-0.5, 0.5), and outputs that
 *     overflow, stop both directions with GF_ERR_OUT_OF_RANGE at that row.
 * Tolerances: apply vs the written-out model, 8 eps relative to the largest term (the
 * two evaluate the same products in different orders); the round trip, 1e-13 relative
 * (the inverse solves with Cramer's rule and the stable quadratic root; measured below
 * 1e-15 relative, printed). */
#include <float.h>
#include <stdint.h>
#include <string.h>

#include "nav/gf_imu_error.h"
#include "gf_test.h"

#define EPS DBL_EPSILON

/* The model of gf_imu_error.h, written out (reference). */
static void ref_apply(const gf_imu_errors *e, const double w[3], const double f[3], double T,
                      double wo[3], double fo[3])
{
    const double dT = T - e->t0;
    double gb[3], gs[3], ab[3], as[3];
    for (int i = 0; i < 3; ++i) {
        gb[i] = e->g_bias_rad_s[i];
        gs[i] = e->g_scale[i];
        ab[i] = e->a_bias_m_s2[i];
        as[i] = e->a_scale[i];
        for (int k = 0; k < e->temp_order; ++k) {
            const double p = pow(dT, k + 1);
            gb[i] += e->g_bias_tc[3 * k + i] * p;
            gs[i] += e->g_scale_tc[3 * k + i] * p;
            ab[i] += e->a_bias_tc[3 * k + i] * p;
            as[i] += e->a_scale_tc[3 * k + i] * p;
        }
    }
    for (int i = 0; i < 3; ++i) {
        double t = w[i];
        for (int j = 0; j < 3; ++j)
            t += e->g_misalign_rad[3 * i + j] * w[j];
        wo[i] = (1.0 + gs[i]) * t + gb[i];
    }
    const double cen[3] = {w[1] * w[1] + w[2] * w[2], w[0] * w[0] + w[2] * w[2],
                           w[0] * w[0] + w[1] * w[1]};
    for (int i = 0; i < 3; ++i) {
        double u = f[i];
        for (int j = 0; j < 3; ++j)
            u += e->a_misalign_rad[3 * i + j] * f[j];
        u -= e->a_lever_pos_m[4 * i] * cen[i];
        fo[i] = (1.0 + as[i]) * u + e->a_k2_s2_m[i] * u * u + ab[i];
    }
}

static void random_errors(test_rng *r, gf_imu_errors *e, int temp_order)
{
    memset(e, 0, sizeof *e);
    for (int i = 0; i < 3; ++i) {
        e->g_scale[i] = test_rng_uniform(r, -0.01, 0.01);
        e->a_scale[i] = test_rng_uniform(r, -0.01, 0.01);
        e->g_bias_rad_s[i] = test_rng_uniform(r, -1e-3, 1e-3);
        e->a_bias_m_s2[i] = test_rng_uniform(r, -0.05, 0.05);
        e->a_k2_s2_m[i] = test_rng_uniform(r, -5e-5, 5e-5);
        e->a_lever_pos_m[4 * i] = test_rng_uniform(r, -0.05, 0.05);
    }
    for (int k = 0; k < 9; ++k)
        if (k % 4) {
            e->g_misalign_rad[k] = test_rng_uniform(r, -0.02, 0.02);
            e->a_misalign_rad[k] = test_rng_uniform(r, -0.02, 0.02);
        }
    e->t0 = 25.0;
    e->temp_order = temp_order;
    for (int k = 0; k < temp_order * 3; ++k) {
        const double scale = pow(30.0, -(k / 3 + 1)); /* a term of ~1e-3 at dT = 30 K */
        e->g_bias_tc[k] = test_rng_uniform(r, -1e-4, 1e-4) * scale;
        e->a_bias_tc[k] = test_rng_uniform(r, -1e-3, 1e-3) * scale;
        e->g_scale_tc[k] = test_rng_uniform(r, -1e-3, 1e-3) * scale;
        e->a_scale_tc[k] = test_rng_uniform(r, -1e-3, 1e-3) * scale;
    }
}

static double rel(double got, double want, double scale) { return fabs(got - want) / scale; }

static void test_apply_and_round_trip(void)
{
    test_rng r = {0x5EED0001ULL};
    enum { N = 200 };
    static double w[N][3], f[N][3], T[N], wo[N][3], fo[N][3], wc[N][3], fc[N][3];
    double worst_apply = 0.0, worst_trip = 0.0;
    for (int set = 0; set < 40; ++set) {
        gf_imu_errors e;
        random_errors(&r, &e, set % (GF_IMU_TEMP_ORDER_MAX + 1));
        CHECK(gf_imu_errors_check(&e, NULL) == GF_OK, "random set %d valid", set);
        for (int k = 0; k < N; ++k) {
            for (int i = 0; i < 3; ++i) {
                w[k][i] = test_rng_uniform(&r, -5, 5);
                f[k][i] = test_rng_uniform(&r, -50, 50);
            }
            T[k] = test_rng_uniform(&r, -15, 65);
        }
        size_t done = 0;
        CHECK(gf_imu_apply(&e, N, w[0], f[0], T, wo[0], fo[0], &done) == GF_OK && done == N,
              "apply set %d", set);
        CHECK(gf_imu_compensate(&e, N, wo[0], fo[0], T, wc[0], fc[0], &done) == GF_OK && done == N,
              "compensate set %d", set);
        for (int k = 0; k < N; ++k) {
            double rw[3], rf[3];
            ref_apply(&e, w[k], f[k], T[k], rw, rf);
            for (int i = 0; i < 3; ++i) {
                worst_apply = fmax(worst_apply, rel(wo[k][i], rw[i], fmax(1.0, fabs(rw[i]))));
                worst_apply = fmax(worst_apply, rel(fo[k][i], rf[i], fmax(1.0, fabs(rf[i]))));
                worst_trip = fmax(worst_trip, rel(wc[k][i], w[k][i], fmax(1.0, fabs(w[k][i]))));
                worst_trip = fmax(worst_trip, rel(fc[k][i], f[k][i], fmax(1.0, fabs(f[k][i]))));
            }
        }
    }
    printf("apply vs the written-out model: %.3g relative; compensate(apply(x)) - x: %.3g relative\n",
           worst_apply, worst_trip);
    CHECK(worst_apply <= 8 * EPS, "apply differs from the model by %.3g relative", worst_apply);
    CHECK(worst_trip <= 1e-13, "compensate(apply(x)) differs from x by %.3g relative", worst_trip);

    /* NULL temperature = T0 */
    gf_imu_errors e;
    random_errors(&r, &e, 2);
    double a[3], b[3], T0 = e.t0;
    CHECK(gf_imu_apply(&e, 1, w[0], f[0], NULL, a, b, NULL) == GF_OK &&
              gf_imu_apply(&e, 1, w[0], f[0], &T0, wo[0], fo[0], NULL) == GF_OK &&
              memcmp(a, wo[0], sizeof a) == 0 && memcmp(b, fo[0], sizeof b) == 0,
          "temp NULL = T0");
    /* outputs may be the inputs' arrays */
    double wi[3] = {1, -2, 0.5}, fi[3] = {0.1, 0.2, 9.8}, wref[3], fref[3];
    CHECK(gf_imu_apply(&e, 1, wi, fi, NULL, wref, fref, NULL) == GF_OK &&
              gf_imu_apply(&e, 1, wi, fi, NULL, wi, fi, NULL) == GF_OK &&
              memcmp(wi, wref, sizeof wi) == 0 && memcmp(fi, fref, sizeof fi) == 0,
          "apply in place = apply into other arrays");
}

static void test_closed_forms(void)
{
    gf_imu_errors e;
    memset(&e, 0, sizeof e);
    e.g_bias_rad_s[1] = 0.01;
    e.g_scale[1] = 0.25;       /* exact in binary: (w_out - b) / 1.25 */
    e.a_k2_s2_m[2] = 1e-5;
    const double wo[3] = {0.5, 1.26, -0.25}, fo[3] = {1.0, -2.0, 9.81};
    double w[3], f[3];
    CHECK(gf_imu_compensate(&e, 1, wo, fo, NULL, w, f, NULL) == GF_OK, "compensate closed form");
    CHECK(w[0] == 0.5 && w[2] == -0.25, "untouched axes exact");
    CHECK_CLOSE(w[1], (1.26 - 0.01) / 1.25, 2 * EPS, "w = (w_out - b) / (1 + s)");
    /* K2 u^2 + u - a = 0, the root near a, as the series u = sum (-1)^n C_n K^n a^(n+1)
     * (C_n the Catalan numbers; the terms fall by 4 K a ~ 4e-4, so 8 terms are exact) */
    const double K = 1e-5, a = 9.81, catalan[8] = {1, 1, 2, 5, 14, 42, 132, 429};
    double u = 0.0;
    for (int n = 7; n >= 0; --n)
        u += (n % 2 ? -1.0 : 1.0) * catalan[n] * pow(K, n) * pow(a, n + 1);
    CHECK_CLOSE(f[2], u, 4 * EPS * a, "K2 root");
    CHECK(f[0] == 1.0 && f[1] == -2.0, "accel axes without errors exact");
}

/* The range of validity (gf_imu_error.h): a temperature at which a scale factor leaves
 * (-0.5, 0.5). Before the check the compensation divided by 1 + s(T) and returned
 * 9e14-sized rates or Inf with GF_OK. */
static void test_temperature_range(void)
{
    gf_imu_errors e;
    memset(&e, 0, sizeof e);
    e.t0 = 20.0;
    e.temp_order = 1;
    e.g_scale_tc[0] = -0.01; /* s_gx(T) = -0.01 (T - 20): -1 at 120 degC */
    CHECK(gf_imu_errors_check(&e, NULL) == GF_OK, "the coefficients alone are valid");
    const double wo[3 * 4] = {0.1, 0.2, 0.3, 0.1, 0.2, 0.3, 0.1, 0.2, 0.3, 0.1, 0.2, 0.3};
    const double fo[3 * 4] = {0, 0, 9.8, 0, 0, 9.8, 0, 0, 9.8, 0, 0, 9.8};
    double w[12], f[12];
    const double temps[3] = {120.0 - 1e-13, 120.0, 80.0}; /* s = -1 + 1e-15, -1, -0.6 */
    for (int i = 0; i < 3; ++i) {
        const double T[4] = {25.0, 60.0, temps[i], 30.0};
        size_t done = 99;
        memset(w, 0, sizeof w);
        const gf_status st = gf_imu_compensate(&e, 4, wo, fo, T, w, f, &done);
        CHECK(st == GF_ERR_OUT_OF_RANGE && done == 2,
              "compensate at T = %.17g (s = %.3g): status %d, rows done %zu, w_x = %.3g "
              "(expected OUT_OF_RANGE at row 2)", temps[i], -0.01 * (temps[i] - 20.0), (int)st,
              done, w[6]);
        CHECK(isfinite(w[0]) && isfinite(w[3]), "rows before it computed");
        CHECK(gf_imu_apply(&e, 4, wo, fo, T, w, f, &done) == GF_ERR_OUT_OF_RANGE && done == 2,
              "apply at T = %.17g: OUT_OF_RANGE at row 2", temps[i]);
    }
    /* near the edge: s = -0.49 accepted and inverted, s = -0.51 refused */
    double T = 69.0, wr[3], fr[3], back[3], fb[3];
    const double win[3] = {0.3, -0.2, 0.1}, fin[3] = {0.5, 0.1, 9.8};
    CHECK(gf_imu_apply(&e, 1, win, fin, &T, wr, fr, NULL) == GF_OK &&
              gf_imu_compensate(&e, 1, wr, fr, &T, back, fb, NULL) == GF_OK,
          "s(T) = -0.49 inside the range");
    CHECK_CLOSE(back[0], win[0], 4 * EPS, "round trip at s = -0.49");
    T = 71.0;
    CHECK(gf_imu_compensate(&e, 1, wr, fr, &T, back, fb, NULL) == GF_ERR_OUT_OF_RANGE, "s(T) = -0.51 refused");
    /* accelerometer scale and an overflowing bias polynomial */
    memset(&e, 0, sizeof e);
    e.temp_order = 2;
    e.a_scale_tc[3 + 2] = 1e-4;   /* s_az = 1e-4 dT^2: 0.5 at dT = 70.7 K */
    T = 75.0;
    CHECK(gf_imu_compensate(&e, 1, wr, fr, &T, back, fb, NULL) == GF_ERR_OUT_OF_RANGE, "accel scale at T refused");
    memset(&e, 0, sizeof e);
    e.temp_order = 4;
    e.g_bias_tc[3 * 3] = 1.0;     /* dT^4 overflows at dT = 1e80 */
    T = 1e80;
    CHECK(gf_imu_compensate(&e, 1, wr, fr, &T, back, fb, NULL) == GF_ERR_OUT_OF_RANGE, "bias overflowing");
}

static void test_overflow_and_errors(void)
{
    gf_imu_errors e;
    memset(&e, 0, sizeof e);
    e.g_scale[0] = 0.4;
    const double big[3] = {1.5e308, 0, 0}, f0[3] = {0, 0, 9.8};
    double wo[3], fo[3];
    size_t done = 99;
    CHECK(gf_imu_apply(&e, 1, big, f0, NULL, wo, fo, &done) == GF_ERR_OUT_OF_RANGE && done == 0,
          "finite input whose output overflows: OUT_OF_RANGE");
    /* K2 without a real root: K2 u^2 + u + (b - a) = 0 has none for a < b - 1/(4 K2) */
    memset(&e, 0, sizeof e);
    e.a_k2_s2_m[0] = -9e-5;
    const double w0[3] = {0, 0, 0}, fneg[3] = {5000.0, 0, 0};
    CHECK(gf_imu_compensate(&e, 1, w0, fneg, NULL, wo, fo, &done) == GF_ERR_OUT_OF_RANGE && done == 0,
          "no real K2 root: OUT_OF_RANGE");
    /* non-finite sample: rows before it */
    const double w2[6] = {0.1, 0, 0, NAN, 0, 0}, f2[6] = {0, 0, 9.8, 0, 0, 9.8};
    double wo2[6], fo2[6];
    CHECK(gf_imu_apply(&e, 2, w2, f2, NULL, wo2, fo2, &done) == GF_ERR_NONFINITE_INPUT && done == 1,
          "NaN at row 1");
    /* every field of the check */
    struct { int field; double *where; double value; } bad[] = {
        {1, &e.g_scale[1], 0.5}, {2, &e.g_misalign_rad[1], 0.1}, {2, &e.g_misalign_rad[4], 1e-9},
        {3, &e.a_scale[2], -0.5}, {4, &e.a_misalign_rad[8], 1e-3}, {5, &e.a_k2_s2_m[0], 1e-4},
        {6, &e.a_lever_pos_m[8], 1.0}, {6, &e.a_lever_pos_m[1], -1.0}, {10, &e.a_delay_s, 1.0}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        memset(&e, 0, sizeof e);
        *bad[i].where = bad[i].value;
        int field = -1;
        CHECK(gf_imu_errors_check(&e, &field) == GF_ERR_BAD_PARAMETER && field == bad[i].field,
              "bad field %d reported as %d", bad[i].field, field);
        CHECK(gf_imu_apply(&e, 1, w0, f0, NULL, wo, fo, NULL) == GF_ERR_BAD_PARAMETER, "apply refuses it");
    }
    memset(&e, 0, sizeof e);
    int field = -1;
    e.temp_order = GF_IMU_TEMP_ORDER_MAX + 1;
    CHECK(gf_imu_errors_check(&e, &field) == GF_ERR_BAD_PARAMETER && field == 7, "temperature order");
    e.temp_order = -1;
    CHECK(gf_imu_errors_check(&e, &field) == GF_ERR_BAD_PARAMETER && field == 7, "negative order");
    e.temp_order = 0;
    e.a_scale_tc[4] = NAN;
    CHECK(gf_imu_errors_check(&e, &field) == GF_ERR_NONFINITE_INPUT, "NaN coefficient");
    CHECK(gf_imu_apply(NULL, 1, w0, f0, NULL, wo, fo, NULL) == GF_ERR_NULL_POINTER, "NULL errors");
}

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* General inner lever arms and the accelerometer delay, against a rigid body written out
 * here: accelerometer i at r_i senses, along e_i, the specific force of its own point,
 * f + w_dot x r_i + w x (w x r_i) (explicit cross products, not the model's expanded
 * W = [w_dot x] + w w^T - |w|^2 I), of the force sampled d late, f + d (w x f) (first
 * order, gf_imu_error.h); then scale, K2, bias. The model puts the lever term after the
 * misalignment (first order: N_a W r is 1e-3 x 1e-1 x 1e-2 here, so the reference leaves
 * N_a out and the test uses N_a = 0 for the comparison; the round trip has every term).
 * Tolerance: 16 eps of the largest term (the two sum the same products differently).
 * The round trip compensate_dw(apply_dw(x, w_dot), w_dot) = x: 1e-13 relative. */
static void test_general_lever_arms_and_delay(void)
{
    test_rng r = {0x5EED0022ULL};
    double worst = 0.0, worst_trip = 0.0;
    for (int set = 0; set < 40; ++set) {
        gf_imu_errors e;
        random_errors(&r, &e, 0);
        memset(e.a_misalign_rad, 0, sizeof e.a_misalign_rad);
        for (int k = 0; k < 9; ++k)
            e.a_lever_pos_m[k] = test_rng_uniform(&r, -0.06, 0.06);
        e.a_delay_s = test_rng_uniform(&r, -2e-3, 2e-3);
        CHECK(gf_imu_errors_check(&e, NULL) == GF_OK, "set %d valid", set);
        for (int k = 0; k < 50; ++k) {
            double w[3], wd[3], f[3], wo[3], fo[3];
            for (int i = 0; i < 3; ++i) {
                w[i] = test_rng_uniform(&r, -3, 3);
                wd[i] = test_rng_uniform(&r, -10, 10);
                f[i] = test_rng_uniform(&r, -30, 30);
            }
            CHECK(gf_imu_apply_dw(&e, 1, w, wd, f, NULL, wo, fo, NULL) == GF_OK, "apply_dw");
            double wf[3], fd[3];
            cross(w, f, wf);
            for (int i = 0; i < 3; ++i)
                fd[i] = f[i] + e.a_delay_s * wf[i];
            for (int i = 0; i < 3; ++i) {
                const double *ri = e.a_lever_pos_m + 3 * i;
                double a1[3], wr[3], a2[3];
                cross(wd, ri, a1);
                cross(w, ri, wr);
                cross(w, wr, a2);
                const double u = fd[i] + a1[i] + a2[i];
                const double want = (1.0 + e.a_scale[i]) * u + e.a_k2_s2_m[i] * u * u + e.a_bias_m_s2[i];
                worst = fmax(worst, rel(fo[i], want, fmax(1.0, fabs(want))));
            }
            /* the round trip, with a misalignment too */
            gf_imu_errors e2 = e;
            for (int q = 0; q < 9; ++q)
                e2.a_misalign_rad[q] = q % 4 ? test_rng_uniform(&r, -0.01, 0.01) : 0.0;
            double wc[3], fc[3];
            CHECK(gf_imu_apply_dw(&e2, 1, w, wd, f, NULL, wo, fo, NULL) == GF_OK &&
                      gf_imu_compensate_dw(&e2, 1, wo, wd, fo, NULL, wc, fc, NULL) == GF_OK,
                  "round trip");
            for (int i = 0; i < 3; ++i) {
                worst_trip = fmax(worst_trip, rel(wc[i], w[i], fmax(1.0, fabs(w[i]))));
                worst_trip = fmax(worst_trip, rel(fc[i], f[i], fmax(1.0, fabs(f[i]))));
            }
        }
    }
    printf("general lever arms + delay vs the rigid body: %.3g relative; round trip %.3g\n", worst,
           worst_trip);
    CHECK(worst <= 16 * EPS, "lever arms / delay differ from the rigid body by %.3g", worst);
    CHECK(worst_trip <= 1e-13, "compensate_dw(apply_dw(x)) differs from x by %.3g", worst_trip);

    /* along-axis lever arms only: w_dot does not enter (bit for bit the seed's model) */
    gf_imu_errors e;
    memset(&e, 0, sizeof e);
    e.a_lever_pos_m[0] = 0.03;
    e.a_lever_pos_m[4] = -0.02;
    e.a_lever_pos_m[8] = 0.01;
    const double w[3] = {0.3, -0.2, 0.5}, wd[3] = {4.0, -1.0, 2.0}, f[3] = {0.1, 0.2, 9.8};
    double a[3], b[3], c[3], d[3];
    CHECK(gf_imu_apply(&e, 1, w, f, NULL, a, b, NULL) == GF_OK &&
              gf_imu_apply_dw(&e, 1, w, wd, f, NULL, c, d, NULL) == GF_OK &&
              memcmp(b, d, sizeof b) == 0, "along-axis arms: w_dot does not enter");
    /* a transverse arm: x accelerometer at y = 5 cm feels -r w_dot_z (tangential) */
    memset(&e, 0, sizeof e);
    e.a_lever_pos_m[1] = 0.05;
    const double w0[3] = {0, 0, 0}, wz[3] = {0, 0, 2.0};
    CHECK(gf_imu_apply_dw(&e, 1, w0, wz, f, NULL, a, b, NULL) == GF_OK, "tangential");
    CHECK_CLOSE(b[0], f[0] - 0.05 * 2.0, 4 * EPS, "x accelerometer at y = 5 cm: f_x - r w_dot_z");
    /* the stream: w_dot from the backward difference of the compensated rates */
    e.a_lever_pos_m[1] = 0.05;
    const double wprev[3] = {0.0, 0.0, 0.1}, wnow[3] = {0.0, 0.0, 0.12};
    double fo[3], wc[3], fc[3];
    const double wdz[3] = {0.0, 0.0, 2.0}; /* (0.12 - 0.1) / 0.01 */
    CHECK(gf_imu_apply_dw(&e, 1, wnow, wdz, f, NULL, a, fo, NULL) == GF_OK &&
              gf_imu_compensate_step(&e, a, fo, NULL, wprev, 0.01, wc, fc) == GF_OK, "step");
    CHECK_CLOSE(fc[0], f[0], 1e-13, "compensate_step uses (w - w_prev) / dt");
    CHECK(gf_imu_compensate_step(&e, a, fo, NULL, wprev, 0.0, wc, fc) == GF_ERR_BAD_TIME, "dt 0");
}

int main(void)
{
    test_general_lever_arms_and_delay();
    test_apply_and_round_trip();
    test_closed_forms();
    test_temperature_range();
    test_overflow_and_errors();
    TEST_MAIN_END();
}
