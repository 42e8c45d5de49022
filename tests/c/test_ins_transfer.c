/* test_ins_transfer.c — the transfer-alignment states of the INS/GNSS filter (issue 24;
 * gf_ins_gnss.h, "Transfer alignment"): their layout, the flexure's second-order Markov
 * model against its closed-form stationary variances, and reverse-time filtering with
 * every state (38). The measurement models' Jacobians are checked by test_ins_meas.c
 * (central differences, every kind), the predictions against the simulator's kinematics
 * by tests/estimation/test_transfer.py.
 *
 * Truth: the stationary variances of f'' + 2 b f' + b^2 f = w with E[w w] = 4 b^3 sigma^2
 * are var(f) = q / (4 b^3) = sigma^2 and var(f') = q / (4 b) = b^2 sigma^2 (the integrals
 * of |1 / (j w + b)^2|^2 and of w^2 times it), independent of the filter's code; the
 * reversal's D is the header's derivation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "est/gf_ins_gnss.h"
#include "gf_test.h"
#include "base/gf_math.h"
#include "nav/gf_sins.h"

#define DEG (3.14159265358979323846 / 180.0)

static gf_ins_config transfer_config(void)
{
    gf_ins_config c;
    gf_ins_config_default(&c);
    c.noise.gyro_arw_rad_sqrt_s = 1e-5;
    c.noise.accel_vrw_m_s_sqrt_s = 1e-4;
    c.master_mount = c.master_lever = c.master_time_offset = c.flexure = 1;
    c.master_mount_rad[0] = 0.3;
    c.master_mount_rad[1] = -0.1;
    c.master_mount_rad[2] = 0.05;
    c.master_lever_arm_m[0] = 0.1;
    c.master_lever_arm_m[1] = -0.4;
    c.master_time_offset_s = 0.015;
    c.noise.flexure_std_rad = 2e-3;
    c.noise.flexure_tau_s = 2.0;
    return c;
}

static gf_status start(gf_ins_filter *f, const gf_ins_config *c)
{
    gf_ins_initial_std sd;
    memset(&sd, 0, sizeof sd);
    for (int i = 0; i < 3; ++i) {
        sd.velocity_std_m_s[i] = 0.1;
        sd.position_std_m[i] = 1.0;
        sd.attitude_std_rad[i] = 0.01;
        sd.gyro_bias_std_rad_s[i] = 1e-4;
        sd.accel_bias_std_m_s2[i] = 0.01;
        sd.gyro_scale_std[i] = sd.accel_scale_std[i] = 1e-3;
        sd.master_mount_std_rad[i] = 0.02;
        sd.master_lever_std_m[i] = 0.1;
    }
    sd.baro_bias_std_m = 1.0;
    sd.odometer_scale_std = 0.01;
    sd.odometer_mount_std_rad[0] = sd.odometer_mount_std_rad[1] = 0.01;
    sd.master_time_offset_std_s = 0.02;
    double P0[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    int32_t bad = 0;
    gf_status st = gf_ins_initial_covariance(c, 30 * DEG, 10.0, &sd, P0, &bad);
    if (st != GF_OK)
        return st;
    const double e[3] = {30 * DEG, 1 * DEG, -2 * DEG}, v[3] = {5.0, -3.0, 0.2};
    double q[4];
    gf_euler_to_quat(e, q);
    return gf_ins_init(f, c, 0.0, q, v, 30 * DEG, 114 * DEG, 10.0, NULL, P0, &bad);
}

static void test_layout(void)
{
    gf_ins_config c = transfer_config();
    gf_ins_layout l;
    CHECK(gf_ins_state_layout(&c, &l) == GF_OK, "layout");
    CHECK(l.n_states == 15 + 13 && l.idx_tmount == 15 && l.idx_tlever == 18 &&
              l.idx_toffset == 21 && l.idx_flex == 22,
          "blocks after the base states: %d %d %d %d (n %d)", l.idx_tmount, l.idx_tlever,
          l.idx_toffset, l.idx_flex, l.n_states);
    c.scale_factors = c.baro_bias = c.odometer_scale = c.odometer_mount = 1;
    CHECK(gf_ins_state_layout(&c, &l) == GF_OK && l.n_states == GF_INS_MAX_STATES &&
              l.idx_tmount == 25 && l.idx_flex == 32,
          "every state: %d (mounting at %d, flexure at %d)", l.n_states, l.idx_tmount, l.idx_flex);
    /* the initial covariance of the flexure: its stationary variances */
    gf_ins_filter f;
    c = transfer_config();
    CHECK(start(&f, &c) == GF_OK, "start");
    const int n = f.n_states, k = f.idx_flex;
    const double b = 2.146 / c.noise.flexure_tau_s, s2 = c.noise.flexure_std_rad * c.noise.flexure_std_rad;
    CHECK(fabs(f.kf.P[k * n + k] - s2) <= 1e-15 * s2 &&
              fabs(f.kf.P[(k + 3) * n + k + 3] - b * b * s2) <= 1e-15 * b * b * s2,
          "P0 of the flexure: %.6g, %.6g (sigma^2 %.6g, b^2 sigma^2 %.6g)", f.kf.P[k * n + k],
          f.kf.P[(k + 3) * n + k + 3], s2, b * b * s2);
    /* refused: the mounting's pitch at 90 deg, a flexure without a correlation time */
    c.master_mount_rad[1] = 1.5707963267948966;
    int32_t bad = 0;
    CHECK(gf_ins_config_check(&c, &bad) == GF_ERR_BAD_PARAMETER &&
              strcmp(gf_ins_config_field(bad), "master_mount_rad") == 0, "pitch 90 deg refused");
    c = transfer_config();
    c.noise.flexure_tau_s = 0.0;
    CHECK(gf_ins_config_check(&c, &bad) == GF_ERR_BAD_PARAMETER &&
              strcmp(gf_ins_config_field(bad), "noise.flexure_tau_s") == 0, "tau 0 refused");
    c.flexure = 0;
    CHECK(gf_ins_config_check(&c, &bad) == GF_OK, "tau 0 is not read without the flexure");
}

/* Free propagation (no measurement) over 120 s from the stationary P0: the flexure block
 * stays at its stationary variances. The filter discretises over T = 0.1 s with Phi = I +
 * F T + (F T)^2 / 2 and the trapezoidal noise, whose stationary point differs from the
 * continuous one at second order in b T (solving that discrete Lyapunov equation: -0.66%
 * on the angle, +1.74% on the rate at b T = 0.107, i.e. 0.6 and 1.5 (b T)^2): the bound is
 * 2 (b T)^2 = 2.3%. A 1e-3 rad flexure estimate decays as the closed-form critically
 * damped response e^(-b t) (1 + b t); the series' error over one step is (b T)^3 / 6 of
 * it, so the same bound holds with a wide margin. */
static void test_flexure_stationary(void)
{
    gf_ins_config c = transfer_config();
    c.master_mount = c.master_lever = c.master_time_offset = 0;
    gf_ins_filter f;
    CHECK(start(&f, &c) == GF_OK, "start");
    const int n = f.n_states, k = f.idx_flex;
    f.transfer[7] = 1e-3;                    /* flexure heading angle estimate */
    const double dt = 0.01, g[3] = {0.0, 0.0, 0.0}, a[3] = {0.0, 0.0, 9.79 * dt};
    const double b = 2.146 / c.noise.flexure_tau_s, s2 = 4e-6;
    double worst_a = 0.0, worst_r = 0.0, worst_mean = 0.0;
    for (int i = 1; i <= 12000; ++i) {
        const gf_status st = gf_ins_step(&f, dt * i, g, a, 0, NULL, NULL, NULL);
        if (st != GF_OK) {
            CHECK(0, "step %d: %d", i, st);
            return;
        }
        if (i % 10 == 0) {
            const double t = dt * i;
            for (int j = 0; j < 3; ++j) {
                worst_a = fmax(worst_a, fabs(f.kf.P[(k + j) * n + k + j] / s2 - 1.0));
                worst_r = fmax(worst_r, fabs(f.kf.P[(k + 3 + j) * n + k + 3 + j] / (b * b * s2) - 1.0));
            }
            const double mean = 1e-3 * exp(-b * t) * (1.0 + b * t);
            worst_mean = fmax(worst_mean, fabs(f.transfer[7] - mean) / 1e-3);
        }
    }
    printf("flexure over 120 s: angle variance within %.2e, rate variance within %.2e of "
           "stationary; mean within %.2e of e^-bt (1 + bt)\n", worst_a, worst_r, worst_mean);
    const double bound = 2.0 * (b * 0.1) * (b * 0.1);
    CHECK(worst_a < bound && worst_r < bound, "stationary variances: %.3g, %.3g (bound %.3g)",
          worst_a, worst_r, bound);
    CHECK(worst_mean < bound, "mean decay: %.3g", worst_mean);
}

/* gf_ins_reverse with every state: x_r = D x, P_r = D P D with D = -1 on dv, dbg and the
 * flexure rates; the flexure-rate estimate negated; F of the reversed nominal = -D F D
 * except the decays (the flexure's damping, the barometer bias' Gauss-Markov), which keep
 * their sign; twice = identity. */
static void test_reverse_signs(void)
{
    gf_ins_config c = transfer_config();
    c.scale_factors = c.baro_bias = c.odometer_scale = c.odometer_mount = 1;
    gf_ins_filter f;
    CHECK(start(&f, &c) == GF_OK, "init");
    const int n = f.n_states;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            if (i != j)
                f.kf.P[i * n + j] = 0.3 * sqrt(f.kf.P[i * n + i] * f.kf.P[j * n + j]) / (1.0 + abs(i - j));
    for (int i = 0; i < n; ++i)
        f.kf.x[i] = 0.01 * (i + 1);
    for (int i = 0; i < GF_INS_N_TRANSFER; ++i)
        f.transfer[i] = 1e-3 * (i + 1);
    const gf_ins_filter f0 = f;
    const double fb[3] = {0.3, -0.2, 9.8}, wb[3] = {0.01, -0.02, 0.05};
    double F[GF_INS_MAX_STATES * GF_INS_MAX_STATES], Fr[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    CHECK(gf_ins_error_model(&f, fb, wb, F, NULL, NULL) == GF_OK, "F forward");
    CHECK(gf_ins_reverse(&f) == GF_OK, "reverse");
    double d[GF_INS_MAX_STATES];
    for (int i = 0; i < n; ++i)
        d[i] = (i < 3 || (i >= 9 && i < 12) || (i >= f.idx_flex + 3 && i < f.idx_flex + 6)) ? -1.0
                                                                                            : 1.0;
    int ok_x = 1, ok_P = 1;
    for (int i = 0; i < n; ++i) {
        ok_x &= f.kf.x[i] == d[i] * f0.kf.x[i];
        for (int j = 0; j < n; ++j)
            ok_P &= f.kf.P[i * n + j] == d[i] * d[j] * f0.kf.P[i * n + j];
    }
    CHECK(ok_x && ok_P, "x_r = D x, P_r = D P D");
    int ok_t = 1;
    for (int i = 0; i < GF_INS_N_TRANSFER; ++i)
        ok_t &= f.transfer[i] == (i >= 10 ? -1.0 : 1.0) * f0.transfer[i];
    CHECK(ok_t, "flexure-rate estimates negated, the other transfer estimates kept");
    const double wr[3] = {-wb[0], -wb[1], -wb[2]};
    CHECK(gf_ins_error_model(&f, fb, wr, Fr, NULL, NULL) == GF_OK, "F reversed");
    double worst = 0.0, scale = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            /* the decays of the sensor states (the barometer bias' Gauss-Markov, the
             * flexure's damping) keep their sign */
            const int decay = i == j && i >= 9;
            const double want = decay ? F[i * n + j] : -d[i] * d[j] * F[i * n + j];
            worst = fmax(worst, fabs(Fr[i * n + j] - want));
            scale = fmax(scale, fabs(F[i * n + j]));
        }
    CHECK(worst <= 1e-15 * scale, "F_reversed = -D F D (damping kept): worst %.3g", worst);
    CHECK(gf_ins_reverse(&f) == GF_OK, "reverse again");
    CHECK(memcmp(f.kf.x, f0.kf.x, sizeof f.kf.x) == 0 && memcmp(f.kf.P, f0.kf.P, sizeof f.kf.P) == 0 &&
              memcmp(f.transfer, f0.transfer, sizeof f.transfer) == 0,
          "reversing twice is the identity (bits)");
}

/* A caller's master measurement: NaN in aux refused, a latitude at the pole refused. */
static void test_measurement_checks(void)
{
    gf_ins_config c = transfer_config();
    gf_ins_filter f;
    CHECK(start(&f, &c) == GF_OK, "start");
    const double g[3] = {0.0, 0.0, 0.0}, a[3] = {0.0, 0.0, 0.0979};
    gf_ins_meas m = {GF_INS_MEAS_MASTER_VEL, 0.005, {5.0, -3.0, 0.2}, {0.02, 0.02, 0.02},
                     {0.0, NAN, 0.0}};
    gf_ins_filter before = f;
    CHECK(gf_ins_step(&f, 0.01, g, a, 1, &m, NULL, NULL) == GF_ERR_NONFINITE_INPUT &&
              memcmp(&f, &before, sizeof f) == 0, "NaN master rate refused, filter unchanged");
    m = (gf_ins_meas){GF_INS_MEAS_MASTER_POS, 0.005, {1.6, 2.0, 10.0}, {1, 1, 1}, {0, 0, 0}};
    CHECK(gf_ins_step(&f, 0.01, g, a, 1, &m, NULL, NULL) == GF_ERR_BAD_PARAMETER,
          "master latitude beyond pi/2 refused");
    m = (gf_ins_meas){GF_INS_MEAS_MASTER_ATT, 0.005, {0.3, 0.01, -0.02}, {1e-3, 1e-3, 1e-3},
                      {0.0, 0.0, 0.0}};
    gf_ins_innovation e[4];
    gf_ins_log log = {4, 0, 0, e};
    CHECK(gf_ins_step(&f, 0.01, g, a, 1, &m, NULL, &log) == GF_OK && log.count == 1 &&
              e[0].type == GF_INS_MEAS_MASTER_ATT && e[0].m == 3, "an attitude update is logged");
}

/* The attitude kind's H with a measurement 0.1 rad away from the prediction (an
 * alignment's first epochs): central differences of its prediction with that
 * measurement, the tolerance of test_ins_meas.c (1e-6 |H| + 1e3 eps / h). */
static void test_attitude_jacobian_away_from_the_measurement(void)
{
    gf_ins_config c = transfer_config();
    gf_ins_filter f;
    CHECK(start(&f, &c) == GF_OK, "start");
    for (int i = 0; i < 3; ++i)
        f.w_ib_b_rad_s[i] = 0.2 * (i + 1);
    const int n = f.n_states;
    double e[3];
    gf_quat_to_euler(f.nav.q_bn, e);
    gf_ins_meas ms = {GF_INS_MEAS_MASTER_ATT, f.t_s, {e[0] + 0.3 + 0.07, e[1] - 0.06, e[2] + 0.08},
                      {1e-4, 1e-4, 1e-4}, {0.1, -0.3, 0.2}};
    double z0[3], H[3 * GF_INS_MAX_STATES], zp[3], zm[3], dx[GF_INS_MAX_STATES];
    CHECK(gf_ins_meas_model(&f, GF_INS_MEAS_MASTER_ATT, &ms, NULL, z0, H, NULL) == GF_OK, "model");
    CHECK(gf_v3_norm(z0) > 0.05, "the residual is large: %g", gf_v3_norm(z0));
    double worst = 0.0;
    for (int j = 0; j < n; ++j) {
        const double h = j >= f.idx_tlever && j < f.idx_tlever + 3 ? 1e-4 : (j < 3 ? 1e-3 : 1e-5);
        memset(dx, 0, sizeof dx);
        dx[j] = h;
        gf_ins_meas_model(&f, GF_INS_MEAS_MASTER_ATT, &ms, dx, zp, NULL, NULL);
        dx[j] = -h;
        gf_ins_meas_model(&f, GF_INS_MEAS_MASTER_ATT, &ms, dx, zm, NULL, NULL);
        for (int i = 0; i < 3; ++i) {
            const double cd = -(zp[i] - zm[i]) / (2.0 * h), hij = H[i * n + j];
            const double tol = 1e-6 * fabs(hij) + 1e3 * 2.2e-16 * 2.0 / h;
            CHECK(fabs(hij - cd) <= tol, "H[%d][%d] = %.12g, central difference %.12g", i, j, hij, cd);
            worst = fmax(worst, fabs(hij - cd) / tol);
        }
    }
    printf("master attitude 0.1 rad from its measurement: max |H - CD| / tol = %.3f\n", worst);
}

int main(void)
{
    test_attitude_jacobian_away_from_the_measurement();
    test_layout();
    test_flexure_stationary();
    test_reverse_signs();
    test_measurement_checks();
    TEST_MAIN_END();
}
