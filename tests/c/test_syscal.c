/* test_syscal.c — the system-level calibration filter (gf_syscal) against independent
 * truth:
 *   - the parameter -> error-model mapping against the seed's angle definitions written
 *     here as rotations of the m axes (first order: the difference is the angle squared);
 *   - records from the rotating-IMU simulator (gf_rot, the forward model) with
 *     known errors (gf_imu_apply): exact data with no errors leave the estimates at zero;
 *     biases, a lever arm and the accelerometer delay (37 states) are recovered within
 *     3 sigma, the sigmas well below the prior (the path observes them);
 *   - the full lever-arm model (39/40 states): accelerometers offset across their axes
 *     (simulated with the exact mean angular acceleration over each sample from the
 *     mechanism's rates at the sample ends) and the delay recovered within 3 sigma;
 *   - the error model F against central differences of the filter's own compensation
 *     (gf_syscal_error_model vs gf_syscal_compensate): every parameter column;
 *   - bad configurations and samples refused, the filter unchanged; a damaged struct
 *     found by the check.
 * The filter runs at 100 Hz on a short path (rest, six turns of the mechanism at 5 deg/s)
 * to keep the sanitizer run short; tolerances are the filter's own sigmas (3 sigma) or,
 * for exact data, 0.3 sigma: the two-sample velocity algorithm of gf_sins leaves
 * g (w T)^2 / 6 along the specific force while turning (w T = 8.7e-4 rad a sample here),
 * measured at 0.04 sigma at 100 Hz on the seed's path, 0.35 sigma at 50 Hz on this one. */
#include <math.h>
#include <string.h>

#include "est/gf_syscal.h"
#include "gf_ref.h"
#include "nav/gf_imu_error.h"
#include "sim/gf_rot.h"
#include "gf_test.h"

#define DEG (REF_PI / 180.0)
#define LAT (40.0 * DEG)
#define HGT 50.0
#define DT 0.01
#define NMAXS 60000

static double dth[3 * NMAXS], dv[3 * NMAXS], qmn[4 * NMAXS], tt[NMAXS];
static gf_syscal filt;
static gf_syscal_epoch epochs[3000];

static void rot_small(int axis, double a, double R[3][3])
{
    const double c = cos(a), s = sin(a);
    memset(R, 0, 9 * sizeof(double));
    R[axis][axis] = 1.0;
    const int i = (axis + 1) % 3, j = (axis + 2) % 3;
    R[i][i] = c;
    R[i][j] = -s;
    R[j][i] = s;
    R[j][j] = c;
}

static void test_mapping(void)
{
    /* gyro: y_g = R_z(gamma_yz) e_y; z_g = R_y(gamma_zy) R_x(gamma_zx) e_z (seed S103,
     * S107); accelerometer axis i turned about m axis j by alpha_ij (S108) */
    const double a = 2e-4; /* rad: first-order agreement to a^2 = 4e-8 */
    double p[GF_SYSCAL_N_PARAMS] = {0};
    const double ang[9] = {1.0 * a, -1.3 * a, 0.7 * a, 0.9 * a, -0.4 * a, 1.1 * a, -0.8 * a, 0.5 * a, 1.2 * a};
    p[3] = ang[0]; p[4] = ang[1]; p[5] = ang[2];
    for (int k = 0; k < 6; ++k)
        p[12 + k] = ang[3 + k];
    gf_imu_errors e;
    CHECK(gf_syscal_errors(p, &e) == GF_OK, "mapping");
    double R1[3][3], R2[3][3], R3[3][3], ax[3];
    const double ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1}, ex[3] = {1, 0, 0};
    rot_small(2, ang[0], R1);
    mat_vec(R1, ey, ax);
    for (int j = 0; j < 3; ++j)
        CHECK_CLOSE((j == 1) + e.g_misalign_rad[3 + j], ax[j], 2 * a * a, "gyro y axis");
    rot_small(1, ang[1], R1);
    rot_small(0, ang[2], R2);
    mat_mul(R1, R2, R3);
    mat_vec(R3, ez, ax);
    for (int j = 0; j < 3; ++j)
        CHECK_CLOSE((j == 2) + e.g_misalign_rad[6 + j], ax[j], 2 * a * a, "gyro z axis");
    /* accelerometer: alpha_xz, xy, yz, yx, zy, zx turn axis i about m axis j; one angle
     * at a time, row i of I + N_a is the turned axis */
    const int ai[6] = {0, 0, 1, 1, 2, 2}, aj[6] = {2, 1, 2, 0, 1, 0};
    const double *base[3] = {ex, ey, ez};
    for (int k = 0; k < 6; ++k) {
        double q[GF_SYSCAL_N_PARAMS] = {0};
        q[12 + k] = ang[3 + k];
        gf_imu_errors ek;
        CHECK(gf_syscal_errors(q, &ek) == GF_OK, "one angle");
        rot_small(aj[k], ang[3 + k], R1);
        mat_vec(R1, base[ai[k]], ax);
        for (int j = 0; j < 3; ++j)
            CHECK_CLOSE((j == ai[k]) + ek.a_misalign_rad[3 * ai[k] + j], ax[j], 2 * a * a,
                        "accelerometer axis turned about an m axis");
    }
    CHECK(e.g_misalign_rad[1] == 0.0 && e.g_misalign_rad[2] == 0.0 && e.g_misalign_rad[5] == 0.0,
          "x_m = x_g, y_m in the x_g-y_g plane: N_g lower triangular");
    p[0] = 0.7;
    CHECK(gf_syscal_errors(p, &e) == GF_ERR_BAD_PARAMETER, "scale 0.7 outside the model's range");
}

/* rest 120 s, then middle +90, inner +90, middle +180, inner +180, middle +90, inner +90,
 * each followed by 40 s at rest (every axis turned and up/down: biases, lever arms and
 * the delay are observed; scale and misalignment only partly) */
static gf_rot_state short_path(void)
{
    gf_rot_schedule s;
    memset(&s, 0, sizeof s);
    s.q_mb0[0] = 1.0;
    s.segment[0] = (gf_rot_segment){-1, -1, 0.0, 0.0, 0.0, 0.0, 120.0};
    const int mid[6] = {1, 0, 1, 0, 1, 0};
    const double deg[6] = {90, 90, 180, 180, 90, 90};
    for (int k = 0; k < 6; ++k) {
        const double a = deg[k] * DEG;
        s.segment[1 + k] = mid[k] ? (gf_rot_segment){0, -1, a, 0.0, a / (5 * DEG) + 1.0, 1.0, 40.0}
                                  : (gf_rot_segment){-1, 2, 0.0, a, a / (5 * DEG) + 1.0, 1.0, 40.0};
    }
    s.n_segments = 7;
    gf_rot_state st;
    CHECK(gf_rot_init(&st, &s, 0.0, NULL) == GF_OK, "short path");
    return st;
}

/* w_im^m at t on the static base of simulate() (identity base attitude at LAT, HGT) */
static void rate_at(const gf_rot_state *st, double t, double w[3])
{
    const double W = 7.2921151467e-5, g = 9.8;   /* g: does not enter the rate */
    const double wb[3] = {0.0, W * cos(LAT), W * sin(LAT)}, fb[3] = {0.0, 0.0, g};
    double f[3];
    gf_rot_pose pose;
    gf_rot_imu_outputs(st, t, wb, fb, w, f, &pose);
}

static size_t simulate(const gf_rot_state *st, const gf_imu_errors *e, double delay_s)
{
    const size_t n = (size_t)(st->cycle_s / DT);
    const double qb[4] = {1, 0, 0, 0};
    size_t done = 0;
    CHECK(gf_rot_imu_static(st, qb, LAT, HGT, 0.0, n, DT, delay_s, dth, dv, qmn, NULL, &done) == GF_OK,
          "simulation");
    for (size_t k = 0; k < n; ++k) {
        tt[k] = (k + 1) * DT;
        if (e) {
            double w[3], f[3], wo[3], fo[3];
            for (int i = 0; i < 3; ++i) {
                w[i] = dth[3 * k + i] / DT;
                f[i] = dv[3 * k + i] / DT;
            }
            double w0[3], w1[3], wd[3];   /* the mean angular acceleration over the sample */
            rate_at(st, k * DT, w0);
            rate_at(st, (k + 1) * DT, w1);
            for (int i = 0; i < 3; ++i)
                wd[i] = (w1[i] - w0[i]) / DT;
            gf_imu_apply_dw(e, 1, w, wd, f, NULL, wo, fo, &done);
            for (int i = 0; i < 3; ++i) {
                dth[3 * k + i] = wo[i] * DT;
                dv[3 * k + i] = fo[i] * DT;
            }
        }
    }
    return n;
}

static gf_syscal_config config(int n_states)
{
    gf_syscal_config c;
    gf_syscal_config_default(&c);
    c.n_states = n_states;
    c.lat_rad = LAT;
    c.h_m = HGT;
    c.vel_std_m_s = 1e-5;
    c.gyro_arw_rad_sqrt_s = 0.002 * DEG / 60.0;
    c.accel_vrw_m_s_sqrt_s = 10e-6 * 9.80665 / sqrt(2.0);
    const double prior[37] = {
        0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 1.6e-7, 2e-7, 1.0,
        50e-6, 50e-6, 50e-6, 4.85e-5, 4.85e-5, 4.85e-5, 4.85e-8, 4.85e-8, 4.85e-8,
        100e-6, 100e-6, 100e-6, 4.85e-5, 4.85e-5, 4.85e-5, 4.85e-5, 4.85e-5, 4.85e-5,
        9.8e-3, 9.8e-3, 9.8e-3, 2.04e-6, 2.04e-6, 2.04e-6, 0.03, 0.03, 0.03, 5e-3};
    memcpy(c.p0_std, prior, sizeof prior);
    if (n_states >= GF_SYSCAL_N_FULL) {   /* six lever-arm states of 3 cm, then the delay */
        for (int k = 33; k < 39; ++k)
            c.p0_std[k] = 0.03;
        c.p0_std[39] = 5e-3;
    }
    return c;
}

static void run_filter(const gf_syscal_config *c, size_t n, size_t *ne)
{
    int bad = -1;
    CHECK(gf_syscal_init(&filt, c, qmn, NULL, 0.0, &bad) == GF_OK && bad == 0, "init (bad %d)", bad);
    size_t done = 0;
    const gf_status st = gf_syscal_run(&filt, n, tt, dth, dv, epochs, 3000, ne, &done);
    CHECK(st == GF_OK && done == n, "run: status %d, %zu of %zu samples", (int)st, done, n);
    CHECK(gf_syscal_check(&filt) == GF_OK, "the filter passes its check after the run");
}

static void test_exact_data(void)
{
    const gf_rot_state st = short_path();
    const size_t n = simulate(&st, NULL, 0.0);
    gf_syscal_config c = config(36);
    size_t ne = 0;
    run_filter(&c, n, &ne);
    CHECK(ne + 1 >= (size_t)(n * DT) && ne <= (size_t)(n * DT), "one update a second: %zu", ne);
    double worst = 0.0, std[GF_SYSCAL_MAX_STATES];
    gf_syscal_covariance(&filt, NULL, std);
    for (int k = 9; k < 36; ++k)
        worst = fmax(worst, fabs(filt.param[gf_syscal_param_index(36, k)]) / std[k]);
    CHECK(worst < 0.3, "exact data, no errors: every estimate within 0.3 sigma of 0 (%.3g)", worst);
    CHECK(fabs(epochs[ne - 1].residual_m_s[0]) < 1e-4, "velocity residual at the end");
}

static void test_recovery(int n_states)
{
    const gf_rot_state st = short_path();
    gf_imu_errors e;
    double p[GF_SYSCAL_N_PARAMS] = {0};
    p[6] = 0.01 * DEG / 3600.0;   /* gyro bias x 0.01 deg/h */
    p[8] = -0.008 * DEG / 3600.0;
    /* accelerometer biases of 200-300 ug: a first pass from a coarse alignment tilted by
     * 1000 ug (the seed's prior) would carry second-order errors of the tilt (phi^2 g) into
     * the lever arms; calibrate() runs two passes for that (docs/rotating_ins.md) */
    p[18] = 200e-6 * 9.80665;
    p[20] = -300e-6 * 9.80665;
    p[24] = 0.02;                 /* lever arm x 2 cm (r_xx) */
    p[32] = -0.03;                /* r_zz */
    CHECK(gf_syscal_errors(p, &e) == GF_OK, "truth model");
    const double delay = n_states == 37 ? 2e-3 : 0.0;
    const size_t n = simulate(&st, &e, delay);
    gf_syscal_config c = config(n_states);
    size_t ne = 0;
    run_filter(&c, n, &ne);
    double std[GF_SYSCAL_MAX_STATES];
    gf_syscal_covariance(&filt, NULL, std);
    const int states[6] = {15, 17, 27, 29, 33, 35};   /* eps_x, eps_z, nabla_x, nabla_z, r_xx, r_zz */
    for (int j = 0; j < 6; ++j) {
        const int k = states[j], q = gf_syscal_param_index(n_states, k);
        CHECK(fabs(filt.param[q] - p[q]) < 3.0 * std[k], "%d states: state %d: %.6g vs true %.6g "
              "(sigma %.3g)", n_states, k, filt.param[q], p[q], std[k]);
        if (k >= 27) /* six 40 s positions do not pin the gyro biases against the noise */
            CHECK(std[k] < 0.2 * c.p0_std[k], "state %d observed: sigma %.3g, prior %.3g",
                  k, std[k], c.p0_std[k]);
    }
    if (n_states == 37) {
        CHECK(fabs(filt.param[GF_SYSCAL_P_DELAY] - delay) < 3.0 * std[36] && std[36] < 2e-4,
              "delay %.6g s vs 2 ms (sigma %.3g)", filt.param[GF_SYSCAL_P_DELAY], std[36]);
    }
}

/* The full model on accelerometers offset across their axes (the x accelerometer at
 * [1, 2, 3] cm and the y accelerometer at [4, 5, 6] cm from the z accelerometer, issue 22's
 * case), with biases and a 1 ms delay: noise-free data, every lever-arm component and the
 * delay within 3 sigma, and observed (sigma below a fifth of the 3 cm / 5 ms prior). The
 * seed model on the same data cannot represent them: its worst accelerometer or
 * lever-arm error is checked to be beyond 3 of its sigmas. */
static void test_full_model(int n_states)
{
    const gf_rot_state st = short_path();
    gf_imu_errors e;
    double p[GF_SYSCAL_N_PARAMS] = {0};
    p[18] = 20e-6 * 9.80665;
    p[20] = -30e-6 * 9.80665;
    const double rx[3] = {0.01, 0.02, 0.03}, ry[3] = {0.04, 0.05, 0.06};
    memcpy(p + GF_SYSCAL_P_LEVER, rx, sizeof rx);
    memcpy(p + GF_SYSCAL_P_LEVER + 3, ry, sizeof ry);
    CHECK(gf_syscal_errors(p, &e) == GF_OK, "truth model");
    const double delay = n_states == GF_SYSCAL_MAX_STATES ? 1e-3 : 0.0;
    const size_t n = simulate(&st, &e, delay);
    gf_syscal_config c = config(n_states);
    size_t ne = 0;
    run_filter(&c, n, &ne);
    double std[GF_SYSCAL_MAX_STATES];
    gf_syscal_covariance(&filt, NULL, std);
    for (int k = 33; k < 39; ++k) {
        const int q = gf_syscal_param_index(n_states, k);
        CHECK(fabs(filt.param[q] - p[q]) < 3.0 * std[k] && std[k] < 0.2 * c.p0_std[k],
              "%d states: lever state %d: %.6g vs true %.6g (sigma %.3g)", n_states, k,
              filt.param[q], p[q], std[k]);
    }
    if (n_states == GF_SYSCAL_MAX_STATES)
        CHECK(fabs(filt.param[GF_SYSCAL_P_DELAY] - delay) < 3.0 * std[39] && std[39] < 1e-3,
              "full model: delay %.6g s vs 1 ms (sigma %.3g)", filt.param[GF_SYSCAL_P_DELAY], std[39]);
    gf_syscal_config cs = config(36);
    run_filter(&cs, n, &ne);
    gf_syscal_covariance(&filt, NULL, std);
    double worst = 0.0;
    for (int k = 27; k < 36; ++k) {
        const int q = gf_syscal_param_index(36, k);
        const double truth = k >= 33 ? 0.0 : p[q];   /* the seed's r_ii: 0 in this truth */
        worst = fmax(worst, fabs(filt.param[q] - truth) / std[k]);
    }
    CHECK(worst > 3.0, "the seed model cannot fit transverse lever arms: worst accelerometer/"
          "lever error only %.3g sigma", worst);
}

/* F against central differences of the filter's compensation (gf_syscal.h): the column of
 * parameter state k is C_m^n d(w_m)/dp in the attitude rows and -C_m^n d(f_m)/dp in the
 * velocity rows (states are true - estimated), p = param[gf_syscal_param_index(k)].
 * Evaluated at zero parameters (where the compensation's derivatives are exactly the
 * first-order model's) for both models with the delay, on a sample turning about all
 * three axes while accelerating. Steps h = 1e-3 of a typical parameter scale: central
 * differences err by h^2 times the third derivative (~1e-9 relative here); the model is
 * linear in the lever arms and the delay. Tolerance 1e-7 of the column's largest entry
 * plus 1e-12 absolute (round-off of the differences: ~1e-12 relative). */
static void test_error_model_jacobian(void)
{
    const int models[2] = {37, GF_SYSCAL_MAX_STATES};
    for (int mi = 0; mi < 2; ++mi) {
        const int n = models[mi];
        gf_syscal_config c = config(n);
        const double q[4] = {0.9, 0.2, -0.3, 0.25};
        double qn[4];
        const double nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        for (int i = 0; i < 4; ++i)
            qn[i] = q[i] / nq;
        CHECK(gf_syscal_init(&filt, &c, qn, NULL, 0.0, NULL) == GF_OK, "init %d", n);
        const double T = 0.01;
        const double dth1[3] = {0.3 * T, -0.2 * T, 0.5 * T}, dvv[3] = {1.5 * T, -2.0 * T, 9.5 * T};
        const double wp[3] = {0.28, -0.21, 0.47};
        double w[3], f[3], wd[3];
        CHECK(gf_syscal_compensate(&filt, NULL, dth1, dvv, T, wp, w, f) == GF_OK, "compensate");
        for (int i = 0; i < 3; ++i)
            wd[i] = (w[i] - wp[i]) / T;
        static double F[GF_SYSCAL_MAX_STATES * GF_SYSCAL_MAX_STATES];
        double H[3 * GF_SYSCAL_MAX_STATES];
        CHECK(gf_syscal_error_model(&filt, w, wd, f, F, H) == GF_OK, "error model");
        double C[3][3];
        ref_quat_to_dcm(qn, C);
        double worst = 0.0;
        for (int k = 9; k < n; ++k) {
            const int pi = gf_syscal_param_index(n, k);
            const double scale = pi == GF_SYSCAL_P_DELAY ? 1e-3 : pi >= GF_SYSCAL_P_LEVER ? 0.03
                                 : (pi >= 6 && pi < 9) ? 1e-5 : (pi >= 18 && pi < 21) ? 1e-3
                                 : (pi >= 21 && pi < 24) ? 1e-5 : 1e-4;
            const double h = 1e-3 * scale;
            double pp[GF_SYSCAL_N_PARAMS] = {0}, pm[GF_SYSCAL_N_PARAMS] = {0};
            pp[pi] = h;
            pm[pi] = -h;
            double wpl[3], fpl[3], wmi[3], fmi[3];
            CHECK(gf_syscal_compensate(&filt, pp, dth1, dvv, T, wp, wpl, fpl) == GF_OK &&
                      gf_syscal_compensate(&filt, pm, dth1, dvv, T, wp, wmi, fmi) == GF_OK, "perturbed");
            double dw[3], df[3], want[6], big = 0.0;
            for (int i = 0; i < 3; ++i) {
                dw[i] = (wpl[i] - wmi[i]) / (2 * h);
                df[i] = (fpl[i] - fmi[i]) / (2 * h);
            }
            for (int i = 0; i < 3; ++i) {
                want[i] = C[i][0] * dw[0] + C[i][1] * dw[1] + C[i][2] * dw[2];
                want[3 + i] = -(C[i][0] * df[0] + C[i][1] * df[1] + C[i][2] * df[2]);
            }
            for (int r = 0; r < 6; ++r)
                big = fmax(big, fabs(want[r]));
            for (int r = 0; r < 6; ++r) {
                const double err = fabs(F[r * n + k] - want[r]);
                worst = fmax(worst, err / (big + 1e-300));
                CHECK(err <= 1e-7 * big + 1e-12, "%d states: F[%d][%d] = %.9g, central difference %.9g",
                      n, r, k, F[r * n + k], want[r]);
            }
        }
        printf("F vs central differences of the compensation (%d states): %.3g relative\n", n, worst);
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < n; ++k)
                CHECK(H[r * n + k] == (k == 3 + r ? 1.0 : 0.0), "H = [0 I 0]");
    }
}

static void test_bad(void)
{
    gf_syscal_config c = config(36);
    const double q[4] = {1, 0, 0, 0};
    int bad = 0;
    gf_syscal_config b = c;
    b.n_states = 30;
    CHECK(gf_syscal_init(&filt, &b, q, NULL, 0.0, &bad) == GF_ERR_BAD_PARAMETER && bad == GF_SYSCAL_BAD_N_STATES, "n");
    b = c;
    b.lat_rad = 89.5 * DEG;
    CHECK(gf_syscal_init(&filt, &b, q, NULL, 0.0, &bad) == GF_ERR_BAD_PARAMETER && bad == GF_SYSCAL_BAD_SITE, "lat");
    b = c;
    b.p0_std[20] = 0.0;
    CHECK(gf_syscal_init(&filt, &b, q, NULL, 0.0, &bad) == GF_ERR_BAD_PARAMETER && bad == GF_SYSCAL_BAD_P0, "p0");
    /* found by fuzzing: a 1e6 rad attitude prior (and a 5e-324 one) lost positivity */
    b = c;
    b.p0_std[1] = 2.0;
    CHECK(gf_syscal_init(&filt, &b, q, NULL, 0.0, &bad) == GF_ERR_BAD_PARAMETER && bad == GF_SYSCAL_BAD_P0,
          "an attitude prior beyond the small-angle model");
    b = c;
    b.p0_std[2] = 5e-324;
    CHECK(gf_syscal_init(&filt, &b, q, NULL, 0.0, &bad) == GF_ERR_BAD_PARAMETER && bad == GF_SYSCAL_BAD_P0,
          "a subnormal prior std");
    b = c;
    b.vel_std_m_s = -1.0;
    CHECK(gf_syscal_init(&filt, &b, q, NULL, 0.0, &bad) == GF_ERR_BAD_PARAMETER && bad == GF_SYSCAL_BAD_VEL_STD, "R");
    double p0[GF_SYSCAL_N_PARAMS] = {0};
    p0[26] = 2.0;
    CHECK(gf_syscal_init(&filt, &c, q, p0, 0.0, &bad) == GF_ERR_BAD_PARAMETER && bad == GF_SYSCAL_BAD_PARAM0, "lever 2 m");
    CHECK(gf_syscal_init(&filt, &c, q, NULL, 0.0, &bad) == GF_OK, "valid");
    const double t[2] = {0.01, 0.02}, w[6] = {0, 0, 0, NAN, 0, 0}, f[6] = {0, 0, 0.098, 0, 0, 0.098};
    size_t done = 9, ne = 9;
    gf_syscal before = filt;
    CHECK(gf_syscal_run(&filt, 2, t, w, f, NULL, 0, &ne, &done) == GF_ERR_NONFINITE_INPUT && done == 1,
          "NaN in sample 1 (done %zu)", done);
    CHECK(filt.t_s == 0.01 && filt.n_samples == 1, "the good sample was taken");
    filt = before;
    const double t_back[2] = {0.01, 0.005};
    const double w0[6] = {0};
    CHECK(gf_syscal_run(&filt, 2, t_back, w0, f, NULL, 0, &ne, &done) == GF_ERR_BAD_TIME && done == 1,
          "time going back");
    const double t_gap[1] = {5.0};
    CHECK(gf_syscal_run(&filt, 1, t_gap, w0, f, NULL, 0, &ne, &done) == GF_ERR_BAD_TIME, "gap of 5 s");
    const double f_big[3] = {0, 0, 50.0};
    const double t_ok[1] = {0.02};
    CHECK(gf_syscal_run(&filt, 1, t_ok, w0, f_big, NULL, 0, &ne, &done) == GF_ERR_OUT_OF_RANGE,
          "5000 m/s^2 specific force");
    gf_syscal damaged = filt;
    damaged.kf.n = 12;
    CHECK(gf_syscal_run(&damaged, 1, t_ok, w0, f, NULL, 0, &ne, &done) == GF_ERR_BAD_SIZE, "damaged size");
    damaged = filt;
    damaged.param[3] = 1e-3;
    CHECK(gf_syscal_check(&damaged) == GF_ERR_BAD_PARAMETER, "estimates and compensation disagree");
}

/* The measurement noise of the zero-velocity update: the velocity-error states are
 * observed directly (H = I, R = vel_std^2 I), so after an update from a prior P >= R I
 * the eigenvalues of their posterior block P (P + R)^-1 R lie in [R/2, R): each std in
 * [vel_std / sqrt 2, vel_std] (a 1e-9 relative slack for round-off). The prior here is
 * 0.01 m/s, 1000 vel_std. */
static void test_update_variance(void)
{
    const gf_rot_state st = short_path();
    simulate(&st, NULL, 0.0);
    gf_syscal_config c = config(36);
    size_t ne = 0;
    run_filter(&c, 150, &ne);
    CHECK(ne == 1, "one update in 1.5 s: %zu", ne);
    for (int i = 0; i < 3; ++i) {
        const double s = epochs[0].std[GF_SYSCAL_IDX_DV + i];
        CHECK(s >= c.vel_std_m_s / sqrt(2.0) * (1.0 - 1e-9) && s <= c.vel_std_m_s * (1.0 + 1e-9),
              "velocity-error std after the update %.6g, in [%.6g, %.6g]", s,
              c.vel_std_m_s / sqrt(2.0), c.vel_std_m_s);
    }
}

int main(void)
{
    test_mapping();
    test_exact_data();
    test_update_variance();
    test_recovery(36);
    test_recovery(37);
    test_full_model(GF_SYSCAL_N_FULL);
    test_full_model(GF_SYSCAL_MAX_STATES);
    test_error_model_jacobian();
    test_bad();
    TEST_MAIN_END();
}
