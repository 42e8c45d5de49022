/* test_ins_gnss.c — the integrated-navigation filter (est/gf_ins_gnss.h) end to end: the
 * tachometer speed measurement (issue 13, seed 003), the odometer boresight, the coarse
 * alignment, levelling and heading rotation, reverse-time filtering (gf_ins_reverse,
 * gf_ins_run_backward), the forward-backward driver (gf_ins_forward_backward) and grouped
 * samples (subsamples). Its measurement models kind by kind: test_ins_meas.c.
 *
 * Truth never comes from the code under test:
 *   - odometer boresight: the speed and non-holonomic components of a body moving straight
 *     ahead seen along rotated axes, and the innovation variance, written out here;
 *   - speed update: the scalar Kalman update written out here (H = [vE, vN]/|v| on dv,
 *     -|v| on the scale state, K = P H^T / (H P H^T + R)), on a filter whose covariance is
 *     the P0 given (a measurement at the filter's initial time, applied before any
 *     propagation: also the check of that fix);
 *   - reversal: the sign pattern D = diag(-1 on dv and dbg) derived in gf_ins_gnss.h,
 *     checked on x, P and on the error model (F_reversed = -D F D for random-constant
 *     sensor errors), and reversing twice = identity, bit for bit;
 *   - round trip: free-inertial forward then backward over the same record returns the
 *     nominal to its start within the truncation level documented for gf_sins
 *     (docs/sins.md: 1e-5 m horizontal, 2.3e-8 m/s, 1.3e-11 rad over 10 min);
 *   - forward-backward driver: the same bits as the passes made one by one through the
 *     public calls.
 * Runs in well under a second plain. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "est/gf_ins_gnss.h"
#include "nav/gf_sins.h"
#include "gf_test.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

static gf_ins_config base_config(void)
{
    gf_ins_config c;
    gf_ins_config_default(&c);
    c.noise.gyro_arw_rad_sqrt_s = 1e-6;
    c.noise.accel_vrw_m_s_sqrt_s = 1e-5;
    c.gate_probability = 0.9999;
    c.gate_reset_count = 0;
    return c;
}

static void diag_P(int n, const double *d, double *P)
{
    memset(P, 0, sizeof(double) * (size_t)(n * n));
    for (int i = 0; i < n; ++i)
        P[i * n + i] = d[i] * d[i];
}

static const double kStd[17] = {0.3, 0.2, 0.1, 1e-6, 1e-6, 1.0, 1e-3, 2e-3, 0.05,
                                1e-6, 2e-6, 3e-6, 1e-3, 2e-3, 3e-3, 1.0, 0.01};

static gf_status start(gf_ins_filter *f, const gf_ins_config *c, const double v[3], double t0)
{
    int32_t n, bad;
    gf_ins_state_count(c, &n);
    double P[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    double d[GF_INS_MAX_STATES];
    for (int i = 0; i < n; ++i)
        d[i] = kStd[i < 15 ? i : 16];       /* the odometer scale (and boresight) states last */
    diag_P(n, d, P);
    const double e[3] = {30 * DEG, 1 * DEG, -2 * DEG};
    double q[4];
    gf_euler_to_quat(e, q);
    return gf_ins_init(f, c, t0, q, v, 30 * DEG, 114 * DEG, 10.0, NULL, P, &bad);
}

/* increments of a manoeuvring body: turn rate, pitch/roll wobble, speed changes */
static void make_record(size_t n, double dt, double *t, double *g, double *a)
{
    for (size_t k = 0; k < n; ++k) {
        const double tk = dt * (double)(k + 1);
        t[k] = tk;
        g[3 * k] = 2e-3 * sin(0.3 * tk) * dt;
        g[3 * k + 1] = -1e-3 * cos(0.2 * tk) * dt;
        g[3 * k + 2] = 0.03 * sin(0.05 * tk) * dt;
        a[3 * k] = 0.05 * cos(0.1 * tk) * dt;
        a[3 * k + 1] = 0.2 * sin(0.07 * tk) * dt;
        a[3 * k + 2] = 9.7936 * dt;
    }
}

static void test_speed_update(void)
{
    for (int with_scale = 0; with_scale <= 1; ++with_scale) {
        gf_ins_config c = base_config();
        c.odometer_scale = with_scale;
        gf_ins_filter f;
        const double v[3] = {3.0, 4.0, 0.1};
        CHECK(start(&f, &c, v, 0.0) == GF_OK, "init");
        gf_ins_filter free_run = f;          /* the same sample without the update */
        const int n = f.n_states;
        const double z = 5.2, sd = 0.1;
        gf_ins_meas m = {GF_INS_MEAS_SPEED, 0.0, {z, 0, 0}, {sd, 0, 0}, {0, 0, 0}};
        gf_ins_innovation entries[8];
        gf_ins_log log = {8, 0, 0, entries};
        const double g[3] = {0, 0, 0}, acc[3] = {0, 0, 9.79 * 0.01};
        /* the measurement at the filter's time t0 = 0 comes with the first sample */
        CHECK(gf_ins_step(&f, 0.01, g, acc, 1, &m, NULL, &log) == GF_OK, "step");
        CHECK(log.count == 1 && entries[0].status == GF_INS_ACCEPTED && entries[0].type == GF_INS_MEAS_SPEED,
              "speed at the initial time applied (count %zu, status %d)", log.count,
              log.count ? entries[0].status : -1);
        /* reference: scalar update with P = P0 at the initial nominal */
        const double sp = 5.0, h[2] = {3.0 / 5.0, 4.0 / 5.0};
        const double pE = kStd[0] * kStd[0], pN = kStd[1] * kStd[1], pk = kStd[16] * kStd[16];
        const double S = h[0] * h[0] * pE + h[1] * h[1] * pN + (with_scale ? sp * sp * pk : 0.0) + sd * sd;
        const double r = sp - z;
        CHECK_CLOSE(entries[0].r[0], r, 1e-12, "innovation");
        CHECK_CLOSE(entries[0].nis, r * r / S, 1e-9, "NIS");
        const double dvE = pE * h[0] / S * r, dvN = pN * h[1] / S * r;
        /* the sample after the update moves both runs alike (the velocity enters the
         * step only through Coriolis and transport rate: 2 x 7.3e-5/s x 0.01 s x 0.12 m/s
         * = 1.7e-7 m/s; tolerance 5e-7) */
        CHECK(gf_ins_step(&free_run, 0.01, g, acc, 0, NULL, NULL, NULL) == GF_OK, "free step");
        CHECK_CLOSE(f.nav.v_n_m_s[0] - free_run.nav.v_n_m_s[0], -dvE, 5e-7, "v_E after the speed update");
        CHECK_CLOSE(f.nav.v_n_m_s[1] - free_run.nav.v_n_m_s[1], -dvN, 5e-7, "v_N after the speed update");
        CHECK(fabs(dvE) > 1e-2, "the update moved v_E (%g)", dvE);
        if (with_scale) {
            const double dk = pk * (-sp) / S * r;
            CHECK_CLOSE(f.sensors[13], dk, 1e-12, "speed scale estimate");
            (void)n;
        }
    }
    /* below the minimum speed: refused and logged; a grossly wrong speed: gated */
    {
        gf_ins_config c = base_config();
        gf_ins_filter f;
        const double v[3] = {0.1, 0.2, 0.0};
        CHECK(start(&f, &c, v, 0.0) == GF_OK, "init");
        gf_ins_meas m = {GF_INS_MEAS_SPEED, 0.005, {0.2, 0, 0}, {0.1, 0, 0}, {0, 0, 0}};
        gf_ins_innovation entries[8];
        gf_ins_log log = {8, 0, 0, entries};
        const double g[3] = {0, 0, 0}, acc[3] = {0, 0, 9.79 * 0.01};
        CHECK(gf_ins_step(&f, 0.01, g, acc, 1, &m, NULL, &log) == GF_OK, "step");
        CHECK(log.count == 1 && entries[0].status == GF_INS_REJECTED_LOW_SPEED && f.n_rejected == 1,
              "low speed refused");
        const double v2[3] = {4.0, 0.0, 0.0};
        CHECK(start(&f, &c, v2, 0.0) == GF_OK, "init");
        m.z[0] = 40.0;
        log.count = 0;
        CHECK(gf_ins_step(&f, 0.01, g, acc, 1, &m, NULL, &log) == GF_OK, "step");
        CHECK(log.count == 1 && entries[0].status == GF_INS_REJECTED_GATE, "gross speed gated");
        c.speed_min_m_s = -1.0;
        int32_t bad = 0;
        double P[15 * 15];
        diag_P(15, kStd, P);
        const double q[4] = {1, 0, 0, 0};
        CHECK(gf_ins_init(&f, &c, 0.0, q, v, 0.5, 1.0, 0.0, NULL, P, &bad) == GF_ERR_BAD_PARAMETER &&
                  strcmp(gf_ins_config_field(bad), "speed_min_m_s") == 0,
              "speed_min_m_s < 0 refused (bad %d)", bad);
    }
}

/* Odometer boresight: a body moving straight ahead at 5 m/s (heading 0, level: C = I) seen
 * by an odometer pitched by tm and turned by hm. Its axes in body (C_m^b = Rz(-hm) Rx(tm)):
 * forward (sin hm cos tm, cos hm cos tm, sin tm), x (cos hm, -sin hm, 0),
 * z (-sin tm sin hm, -sin tm cos hm, cos tm); so the predicted speed is 5 cos hm cos tm and
 * the non-holonomic components -5 sin hm and -5 sin tm cos hm. The innovation's variance:
 * H on dv is the forward axis, on phi the forward axis times -[v x] (C = I):
 * (-5 sin tm, 0, 5 sin hm cos tm); no lever arm, no bias terms. */
static void test_odometer_mounting(void)
{
    const double tm = 1.5 * DEG, hm = -2.0 * DEG, V = 5.0;
    gf_ins_config c = base_config();
    c.odometer_mount_rad[0] = tm;
    c.odometer_mount_rad[1] = hm;
    c.nhc = 1;
    c.nhc_std_m_s = 0.05;
    c.gate_probability = 0.0;
    gf_ins_filter f;
    int32_t bad;
    double P[15 * 15];
    diag_P(15, kStd, P);
    const double q[4] = {1, 0, 0, 0}, v[3] = {0.0, V, 0.0};
    CHECK(gf_ins_init(&f, &c, 0.0, q, v, 30 * DEG, 114 * DEG, 0.0, NULL, P, &bad) == GF_OK, "init");
    gf_ins_meas m = {GF_INS_MEAS_ODO, 0.0, {0.0, 0, 0}, {0.02, 0, 0}, {0, 0, 0}};
    gf_ins_innovation e[4];
    gf_ins_log log = {4, 0, 0, e};
    const double g[3] = {0, 0, 0}, a[3] = {0, 0, 0};
    /* the odometer at the initial time (P = P0, nominal = initial) with the first sample */
    CHECK(gf_ins_step(&f, 0.01, g, a, 1, &m, NULL, &log) == GF_OK && log.count == 1, "odometer update");
    const double fwd[3] = {sin(hm) * cos(tm), cos(hm) * cos(tm), sin(tm)};
    const double hphi[3] = {-V * sin(tm), 0.0, V * sin(hm) * cos(tm)};
    double S = 0.02 * 0.02;
    for (int j = 0; j < 3; ++j)
        S += fwd[j] * fwd[j] * kStd[j] * kStd[j] + hphi[j] * hphi[j] * kStd[6 + j] * kStd[6 + j];
    CHECK_CLOSE(e[0].r[0], V * cos(hm) * cos(tm), 1e-12, "predicted odometer speed with boresight");
    CHECK_CLOSE(e[0].s_std[0], sqrt(S), 1e-12, "innovation std with boresight");
    /* NHC on the regular grid (0.1 s): a fresh filter, ten samples of straight motion */
    CHECK(gf_ins_init(&f, &c, 0.0, q, v, 30 * DEG, 114 * DEG, 0.0, NULL, P, &bad) == GF_OK, "init");
    log.count = 0;
    for (int k = 1; k <= 10; ++k) {
        const double dv[3] = {0.0, 0.0, 9.7936 * 0.01};
        CHECK(gf_ins_step(&f, 0.01 * k, g, dv, 0, NULL, NULL, &log) == GF_OK, "step");
    }
    CHECK(log.count == 1 && e[0].type == GF_INS_MEAS_NHC, "one NHC update (%zu)", log.count);
    /* the nominal moved over 0.1 s by gravity mismatch and Earth terms: ~1e-3 m/s */
    CHECK_CLOSE(e[0].r[0], -V * sin(hm), 2e-3, "NHC lateral with boresight");
    CHECK_CLOSE(e[0].r[1], -V * sin(tm) * cos(hm), 2e-3, "NHC vertical with boresight");
    CHECK(fabs(e[0].r[0]) > 0.1 && fabs(e[0].r[1]) > 0.1, "boresight seen by the NHC");
    c.odometer_mount_rad[1] = 1.6;
    CHECK(gf_ins_init(&f, &c, 0.0, q, v, 0.5, 1.0, 0.0, NULL, P, &bad) == GF_ERR_BAD_PARAMETER &&
              strcmp(gf_ins_config_field(bad), "odometer_mount_rad") == 0,
          "mounting angle beyond 90 deg refused");
}

/* The boresight states' columns of H (odometer_mount): the update they make equals the
 * one computed here from central differences of the filter's own measurement prediction
 * with respect to the mounting angles (r = prediction - measurement, so dr/dtheta = dy/
 * dtheta), with only the two boresight states uncertain (the others at 1e-9: their part
 * of S is ~1e-17 of it): dx = P H^T S^-1 r, H = -dy/dtheta (states true - estimated).
 * A tilted, turned attitude, a velocity with all body components and a lever arm make
 * every term of dM/dtheta ub count. Central differences with eps = 1e-6 rad: truncation
 * ~eps^2 |y| ~ 1e-11, round-off ~1e-16 |y| / eps ~ 1e-9: tolerance 1e-7 relative. */
static void mount_run(double dp, double dh, int type, int with_state, double r[2],
                      double sens[2], double s_std[2])
{
    gf_ins_config c = base_config();
    c.odometer_mount_rad[0] = 0.02 + dp;
    c.odometer_mount_rad[1] = -0.03 + dh;
    c.odometer_lever_arm_m[0] = -0.7;
    c.odometer_lever_arm_m[1] = 1.1;
    c.odometer_lever_arm_m[2] = -0.4;
    c.odometer_mount = with_state;
    c.nhc = type == GF_INS_MEAS_NHC;
    c.nhc_std_m_s = 0.05;
    c.gate_probability = 0.0;
    const int n = 15 + 2 * with_state;
    double sd[17], P[17 * 17];
    for (int i = 0; i < n; ++i)
        sd[i] = i >= 15 ? 0.02 : 1e-9;
    diag_P(n, sd, P);
    const double e[3] = {40 * DEG, 3 * DEG, -4 * DEG};
    double q[4];
    CHECK(gf_euler_to_quat(e, q) == GF_OK, "attitude");
    const double v[3] = {3.0, 4.0, 0.5};
    gf_ins_filter f;
    int32_t bad;
    CHECK(gf_ins_init(&f, &c, 0.0, q, v, 30 * DEG, 114 * DEG, 0.0, NULL, P, &bad) == GF_OK, "init");
    gf_ins_innovation lg[4];
    gf_ins_log log = {4, 0, 0, lg};
    const double g[3] = {0.001, -0.002, 0.003}, a[3] = {0.01, 0.02, 0.098};
    if (type == GF_INS_MEAS_ODO) {
        gf_ins_meas m = {GF_INS_MEAS_ODO, 0.0, {4.5, 0, 0}, {0.02, 0, 0}, {0, 0, 0}};
        CHECK(gf_ins_step(&f, 0.01, g, a, 1, &m, NULL, &log) == GF_OK, "odometer update");
    } else {
        for (int k = 1; k <= 10; ++k)
            CHECK(gf_ins_step(&f, 0.01 * k, g, a, 0, NULL, NULL, &log) == GF_OK, "step");
    }
    CHECK(log.count == 1 && lg[0].type == type && lg[0].status == GF_INS_ACCEPTED, "one update");
    for (int i = 0; i < 2; ++i) {
        r[i] = lg[0].r[i];
        s_std[i] = lg[0].s_std[i];
        sens[i] = f.sensors[14 + i];
    }
}

static void test_odometer_mount_jacobian(void)
{
    const double eps = 1e-6;
    const int types[2] = {GF_INS_MEAS_ODO, GF_INS_MEAS_NHC};
    for (int t = 0; t < 2; ++t) {
        const int m = types[t] == GF_INS_MEAS_ODO ? 1 : 2;
        const double R = types[t] == GF_INS_MEAS_ODO ? 0.02 * 0.02 : 0.05 * 0.05;
        double r0[2], s0[2], sd[2], rp[2], rm[2], dum[2], H[2][2];
        for (int j = 0; j < 2; ++j) {
            mount_run(j == 0 ? eps : 0.0, j == 1 ? eps : 0.0, types[t], 0, rp, dum, dum);
            mount_run(j == 0 ? -eps : 0.0, j == 1 ? -eps : 0.0, types[t], 0, rm, dum, dum);
            for (int i = 0; i < m; ++i)
                H[i][j] = -(rp[i] - rm[i]) / (2.0 * eps);
        }
        mount_run(0.0, 0.0, types[t], 1, r0, s0, sd);
        /* S = R + H P H^T (P = 0.02^2 I on the boresight), dx = P H^T S^-1 r */
        const double p = 0.02 * 0.02;
        double S[2][2] = {{R, 0}, {0, R}};
        for (int i = 0; i < m; ++i)
            for (int k = 0; k < m; ++k)
                S[i][k] += p * (H[i][0] * H[k][0] + H[i][1] * H[k][1]);
        double y[2];
        if (m == 1)
            y[0] = r0[0] / S[0][0];
        else {
            const double det = S[0][0] * S[1][1] - S[0][1] * S[1][0];
            y[0] = (S[1][1] * r0[0] - S[0][1] * r0[1]) / det;
            y[1] = (-S[1][0] * r0[0] + S[0][0] * r0[1]) / det;
        }
        for (int j = 0; j < 2; ++j) {
            double dx = 0.0;
            for (int i = 0; i < m; ++i)
                dx += p * H[i][j] * y[i];
            CHECK(fabs(s0[j] - dx) <= 1e-7 * fabs(dx) && fabs(dx) > 1e-4,
                  "boresight update %d of type %d: %.12g, from differences %.12g", j, types[t],
                  s0[j], dx);
        }
        for (int i = 0; i < m; ++i)
            CHECK(fabs(sd[i] - sqrt(S[i][i])) <= 1e-7 * sqrt(S[i][i]), "innovation std row %d: %.12g vs %.12g", i, sd[i], sqrt(S[i][i]));
    }
}

/* Coarse alignment: the specific force and Earth rate of a known attitude at rest,
 * written here from their definitions (f^n = (0, 0, g), w_ie^n = (0, W cos L, W sin L),
 * body = C^T navigation), give the attitude back to round-off; gravity parallel to the
 * rate (a pole) and an absurd |f| are refused. */
static void test_coarse_align(void)
{
    const double W = 7.292115e-5, g = 9.79, L = 30 * DEG;
    double worst = 0.0;
    for (int c = 0; c < 8; ++c) {
        const double e[3] = {(37.0 + 45.0 * c) * DEG, (c % 3 - 1) * 20.0 * DEG, (c % 5 - 2) * 40.0 * DEG};
        double q[4], q2[4];
        gf_euler_to_quat(e, q);
        const double q0 = q[0], q1 = q[1], q2_ = q[2], q3 = q[3];
        double C[3][3] = {{q0 * q0 + q1 * q1 - q2_ * q2_ - q3 * q3, 2 * (q1 * q2_ - q0 * q3), 2 * (q1 * q3 + q0 * q2_)},
                          {2 * (q1 * q2_ + q0 * q3), q0 * q0 - q1 * q1 + q2_ * q2_ - q3 * q3, 2 * (q2_ * q3 - q0 * q1)},
                          {2 * (q1 * q3 - q0 * q2_), 2 * (q2_ * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2_ * q2_ + q3 * q3}};
        const double fn[3] = {0, 0, g}, wn[3] = {0, W * cos(L), W * sin(L)};
        double fb[3], wb[3];
        for (int i = 0; i < 3; ++i) {
            fb[i] = C[0][i] * fn[0] + C[1][i] * fn[1] + C[2][i] * fn[2];
            wb[i] = C[0][i] * wn[0] + C[1][i] * wn[1] + C[2][i] * wn[2];
        }
        CHECK(gf_ins_coarse_align(fb, wb, q2) == GF_OK, "coarse align %d", c);
        /* angle between them: 2 |vector part of q^* q2| */
        const double *a = q, *b = q2;
        const double x = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
        const double y = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
        const double z = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
        worst = fmax(worst, 2.0 * sqrt(x * x + y * y + z * z));
    }
    printf("coarse alignment from exact gravity and Earth rate: worst angle %.3g rad\n", worst);
    /* round-off: the east axis is w x f with |w| ~ 7e-5 of |f| scale, normalised: a few
     * 1e-16 relative on every axis; bound 1e-13 */
    CHECK(worst < 1e-13, "coarse alignment angle error %.3g rad", worst);
    const double f_up[3] = {0, 0, 9.8}, w_up[3] = {0, 0, 7e-5}, f_bad[3] = {0, 0, 30.0}, w[3] = {0, 7e-5, 0};
    double q[4];
    CHECK(gf_ins_coarse_align(f_up, w_up, q) == GF_ERR_SINGULAR_GEOMETRY, "rate parallel to gravity");
    CHECK(gf_ins_coarse_align(f_bad, w, q) == GF_ERR_SINGULAR_GEOMETRY, "absurd specific force");
}

/* Levelling without a heading and the rotation about the vertical: the specific force of
 * a known attitude at rest (f^n = (0, 0, g), body = C^T navigation, C written here from
 * the quaternion's definition) gives back its roll and pitch with heading 0; rotating that
 * attitude by the true heading gives the attitude back, and a velocity along heading 0
 * (north) turns to (sin psi, cos psi); a forward axis on the vertical and NaN are refused. */
static void test_level_align_and_rotate(void)
{
    const double g = 9.79;
    double worst = 0.0, worst_v = 0.0;
    for (int c = 0; c < 8; ++c) {
        const double e[3] = {(37.0 + 45.0 * c) * DEG, (c % 3 - 1) * 20.0 * DEG, (c % 5 - 2) * 40.0 * DEG};
        double q[4], q2[4], e2[3];
        gf_euler_to_quat(e, q);
        const double q0 = q[0], q1 = q[1], q2_ = q[2], q3 = q[3];
        const double C[3][3] = {{q0 * q0 + q1 * q1 - q2_ * q2_ - q3 * q3, 2 * (q1 * q2_ - q0 * q3), 2 * (q1 * q3 + q0 * q2_)},
                                {2 * (q1 * q2_ + q0 * q3), q0 * q0 - q1 * q1 + q2_ * q2_ - q3 * q3, 2 * (q2_ * q3 - q0 * q1)},
                                {2 * (q1 * q3 - q0 * q2_), 2 * (q2_ * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2_ * q2_ + q3 * q3}};
        const double fb[3] = {C[2][0] * g, C[2][1] * g, C[2][2] * g};
        CHECK(gf_ins_level_align(fb, q2) == GF_OK, "level align %d", c);
        gf_quat_to_euler(q2, e2);
        /* heading 0 (or 2 pi by round-off), pitch and roll as given */
        worst = fmax(worst, fmin(fabs(e2[0]), fabs(e2[0] - 2 * PI)));
        worst = fmax(worst, fmax(fabs(e2[1] - e[1]), fabs(e2[2] - e[2])));
        double v[3] = {0.0, 3.0, 0.5};
        CHECK(gf_ins_rotate_heading(q2, v, e[0]) == GF_OK, "rotate %d", c);
        const double *a = q, *b = q2;
        const double x = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
        const double y = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
        const double z = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
        worst = fmax(worst, 2.0 * sqrt(x * x + y * y + z * z));
        worst_v = fmax(worst_v, fmax(fabs(v[0] - 3.0 * sin(e[0])), fabs(v[1] - 3.0 * cos(e[0]))));
        worst_v = fmax(worst_v, fabs(v[2] - 0.5));
    }
    printf("levelling + rotation about the vertical: worst angle %.3g rad, velocity %.3g m/s\n",
           worst, worst_v);
    /* round-off: a unit vector normalised, a DCM to quaternion, one product: a few 1e-16 */
    CHECK(worst < 1e-13 && worst_v < 1e-13, "level/rotate error %.3g rad, %.3g m/s", worst, worst_v);
    const double f_fwd_up[3] = {0, 9.8, 0}, f_nan[3] = {0, NAN, 9.8}, f_bad[3] = {0, 0, 30.0};
    double q[4] = {1, 0, 0, 0}, v[3] = {1, 2, 3};
    CHECK(gf_ins_level_align(f_fwd_up, q) == GF_ERR_SINGULAR_GEOMETRY, "forward axis vertical");
    CHECK(gf_ins_level_align(f_bad, q) == GF_ERR_SINGULAR_GEOMETRY, "absurd specific force");
    CHECK(gf_ins_level_align(f_nan, q) == GF_ERR_NONFINITE_INPUT, "NaN specific force");
    CHECK(gf_ins_rotate_heading(q, v, NAN) == GF_ERR_NONFINITE_INPUT && q[0] == 1 && v[0] == 1,
          "NaN angle refused, nothing written");
    CHECK(gf_ins_rotate_heading(NULL, v, 0.1) == GF_ERR_NULL_POINTER, "NULL attitude");
}

static void test_reverse_signs(void)
{
    gf_ins_config c = base_config();
    c.scale_factors = 1;
    c.odometer_scale = 1;
    c.odometer_mount = 1;         /* 25 states: the boresight angles keep their sign */
    gf_ins_filter f;
    const double v[3] = {5.0, -3.0, 0.2};
    CHECK(start(&f, &c, v, 0.0) == GF_OK, "init");
    const int n = f.n_states;
    /* a full covariance: correlate everything a little */
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            if (i != j)
                f.kf.P[i * n + j] = 0.3 * sqrt(f.kf.P[i * n + i] * f.kf.P[j * n + j]) / (1.0 + abs(i - j));
    for (int i = 0; i < n; ++i)
        f.kf.x[i] = 0.01 * (i + 1);
    f.sensors[0] = 1e-6;
    f.sensors[3] = 2e-4;
    const gf_ins_filter f0 = f;
    const double fb[3] = {0.3, -0.2, 9.8}, wb[3] = {0.01, -0.02, 0.05};
    double F[GF_INS_MAX_STATES * GF_INS_MAX_STATES], Fr[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    CHECK(gf_ins_error_model(&f, fb, wb, F, NULL, NULL) == GF_OK, "F forward");
    CHECK(gf_ins_reverse(&f) == GF_OK, "reverse");
    double d[GF_INS_MAX_STATES];
    for (int i = 0; i < n; ++i)
        d[i] = (i < 3 || (i >= 9 && i < 12)) ? -1.0 : 1.0;
    int ok_x = 1, ok_P = 1;
    for (int i = 0; i < n; ++i) {
        ok_x &= f.kf.x[i] == d[i] * f0.kf.x[i];
        for (int j = 0; j < n; ++j)
            ok_P &= f.kf.P[i * n + j] == d[i] * d[j] * f0.kf.P[i * n + j];
    }
    CHECK(ok_x && ok_P, "x_r = D x, P_r = D P D");
    CHECK(f.nav.v_n_m_s[0] == -v[0] && f.nav.earth_rate_sign == -1.0 && f.sensors[0] == -1e-6 &&
              f.sensors[3] == 2e-4, "nominal and sensor estimates reversed");
    /* the error model of the reversed nominal, with the body rate negated: -D F D for
     * every entry except the Gauss-Markov decays (none here: random constants) */
    const double wr[3] = {-wb[0], -wb[1], -wb[2]};
    CHECK(gf_ins_error_model(&f, fb, wr, Fr, NULL, NULL) == GF_OK, "F reversed");
    double worst = 0.0, scale = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            worst = fmax(worst, fabs(Fr[i * n + j] + d[i] * d[j] * F[i * n + j]));
            scale = fmax(scale, fabs(F[i * n + j]));
        }
    /* exact up to the rounding of the products that build each entry */
    CHECK(worst <= 1e-15 * scale, "F_reversed = -D F D: worst %.3g (scale %.3g)", worst, scale);
    printf("reversed error model: max |F_r + D F D| = %.3g (max |F| %.3g)\n", worst, scale);
    CHECK(gf_ins_reverse(&f) == GF_OK, "reverse again");
    CHECK(memcmp(f.kf.x, f0.kf.x, sizeof f.kf.x) == 0 && memcmp(f.kf.P, f0.kf.P, sizeof f.kf.P) == 0 &&
              memcmp(f.sensors, f0.sensors, sizeof f.sensors) == 0 &&
              memcmp(f.nav.q_bn, f0.nav.q_bn, sizeof f.nav.q_bn) == 0 &&
              memcmp(f.nav.v_n_m_s, f0.nav.v_n_m_s, sizeof f.nav.v_n_m_s) == 0 &&
              f.nav.lat_rad == f0.nav.lat_rad && f.nav.earth_rate_sign == 1.0,
          "reversing twice is the identity (bits)");
}

#define NREC 30000   /* 300 s at 100 Hz */
static double g_t[NREC], g_g[3 * NREC], g_a[3 * NREC];
static double o_t[NREC], o_q[4 * NREC], o_v[3 * NREC], o_p[3 * NREC];
static double b_t[NREC], b_q[4 * NREC], b_v[3 * NREC], b_p[3 * NREC];

static void test_round_trip(void)
{
    const double dt = 0.01;
    make_record(NREC, dt, g_t, g_g, g_a);
    gf_ins_config c = base_config();
    gf_ins_filter f;
    const double v[3] = {4.0, 1.0, 0.0};
    CHECK(start(&f, &c, v, 0.0) == GF_OK, "init");
    const gf_ins_filter f0 = f;
    gf_ins_output out = {o_t, o_q, o_v, o_p, NULL, NULL, NULL, 0, NULL, NULL};
    size_t done, mdone;
    CHECK(gf_ins_run(&f, NREC, g_t, g_g, g_a, 0, NULL, &out, NULL, NULL, &done, &mdone) == GF_OK, "forward");
    CHECK(gf_ins_run_backward(&f, NREC, g_t, g_g, g_a, 0.0, 0, NULL, NULL, NULL, &done, &mdone) ==
              GF_ERR_BAD_PARAMETER, "backward run needs gf_ins_reverse first");
    CHECK(gf_ins_reverse(&f) == GF_OK, "reverse");
    gf_ins_output bout = {b_t, b_q, b_v, b_p, NULL, NULL, NULL, 0, NULL, NULL};
    CHECK(gf_ins_run_backward(&f, NREC, g_t, g_g, g_a, 0.0, 0, NULL, &bout, NULL, &done, &mdone) == GF_OK &&
              done == NREC, "backward");
    /* back at the start: the nominal against the initial one */
    const double R = 6.37e6;
    double dpos = hypot((f.nav.lat_rad - f0.nav.lat_rad) * R,
                        (f.nav.lon_rad - f0.nav.lon_rad) * R * cos(f0.nav.lat_rad));
    double dvel = 0.0, datt = 0.0;
    for (int i = 0; i < 3; ++i)
        dvel = fmax(dvel, fabs(-f.nav.v_n_m_s[i] - f0.nav.v_n_m_s[i]));
    {
        /* rotation angle between the quaternions: 2 |vector part of q0^* q| */
        const double *a = f0.nav.q_bn, *b = f.nav.q_bn;
        const double x = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
        const double y = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
        const double z = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
        datt = 2.0 * sqrt(x * x + y * y + z * z);
    }
    printf("filter round trip over %g s (free inertial): %.3g m horizontal, %.3g m height, "
           "%.3g m/s, %.3g rad, time %.3g s\n", NREC * dt, dpos, fabs(f.nav.h_m - f0.nav.h_m), dvel, datt,
           fabs(f.t_s - f0.t_s));
    /* gf_sins' documented round trip over 10 min (docs/sins.md): 1.0e-5 m, 6e-8 m height,
     * 2.3e-8 m/s, 1.3e-11 rad — the truncation asymmetry of the mid-point extrapolation;
     * the filter's nominal is the same mechanization: the same bounds over 5 min */
    CHECK(dpos < 1e-5 && fabs(f.nav.h_m - f0.nav.h_m) < 6e-8 && dvel < 2.3e-8 && datt < 1.3e-11 &&
              fabs(f.t_s - f0.t_s) < 1e-9,
          "round trip: %.3g m, %.3g m, %.3g m/s, %.3g rad", dpos, fabs(f.nav.h_m - f0.nav.h_m), dvel, datt);
    /* every backward row k (the state at t_(k-1)) against the forward row k-1 */
    double worst_p = 0.0;
    for (size_t k = 1; k < NREC; ++k) {
        worst_p = fmax(worst_p, fabs(b_p[3 * k] - o_p[3 * (k - 1)]) * R);
        CHECK(b_t[k] == o_t[k - 1] || fabs(b_t[k] - o_t[k - 1]) < 1e-9, "row time %zu", k);
    }
    CHECK(worst_p < 1e-5, "backward rows vs forward rows: %.3g m", worst_p);
    CHECK(fabs(b_v[3] - o_v[0]) < 1e-7, "backward rows report true-time velocity");
    /* the covariance: no process noise in this check. The backward pass undoes the
     * forward transition up to the discretisation: both directions evaluate F at the end
     * of each propagation interval (the forward pass at t_k, the backward one at t_(k-1)),
     * so Phi_b Phi_f = I + (F(t_k) - F(t_(k-1))) T + ...: an error of first order in T.
     * Checked: below 1e-2 (relative to sqrt(P_ii P_jj)) at T = 0.1 s, and halving with T. */
    double worstP[2];
    for (int r = 0; r < 2; ++r) {
        gf_ins_config c0 = c;
        c0.noise.gyro_arw_rad_sqrt_s = c0.noise.accel_vrw_m_s_sqrt_s = 0.0;
        c0.propagation_interval_s = r == 0 ? 0.1 : 0.05;
        CHECK(start(&f, &c0, v, 0.0) == GF_OK, "init");
        const gf_ins_filter fs = f;
        const int n = f.n_states;
        CHECK(gf_ins_run(&f, 6000, g_t, g_g, g_a, 0, NULL, &out, NULL, NULL, &done, &mdone) == GF_OK, "fwd 60 s");
        CHECK(gf_ins_reverse(&f) == GF_OK, "reverse");
        CHECK(gf_ins_run_backward(&f, 6000, g_t, g_g, g_a, 0.0, 0, NULL, NULL, NULL, &done, &mdone) == GF_OK,
              "bwd 60 s");
        CHECK(gf_ins_reverse(&f) == GF_OK, "reverse");
        worstP[r] = 0.0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                worstP[r] = fmax(worstP[r], fabs(f.kf.P[i * n + j] - fs.kf.P[i * n + j]) /
                                                sqrt(fs.kf.P[i * n + i] * fs.kf.P[j * n + j]));
    }
    printf("covariance round trip over 60 s without process noise: max |dP_ij| / sqrt(P_ii P_jj) = "
           "%.3g (T = 0.1 s), %.3g (T = 0.05 s)\n", worstP[0], worstP[1]);
    /* measured 4.8e-3 and 2.4e-3 (ratio 2.00, gcc 12 x86-64) */
    CHECK(worstP[0] < 1e-2 && worstP[0] / worstP[1] > 1.8 && worstP[0] / worstP[1] < 2.2,
          "covariance round trip %.3g, %.3g: not first order in T", worstP[0], worstP[1]);
}

static void test_forward_backward_driver(void)
{
    const size_t n = 6000;
    const double dt = 0.01;
    make_record(n, dt, g_t, g_g, g_a);
    /* tachometer speeds from the nominal of a free run (the value does not matter for a
     * bit comparison) and one at the record's start and end (turning points) */
    gf_ins_meas m[62];
    size_t nm = 0;
    for (int s = 0; s <= 60; ++s) {
        m[nm].type = GF_INS_MEAS_SPEED;
        m[nm].t_s = s * 1.0 + (s > 0 && s < 60 ? 0.0037 : 0.0);
        m[nm].z[0] = 4.1 + 0.01 * s;
        m[nm].std[0] = 0.1;
        ++nm;
    }
    gf_ins_config c = base_config();
    gf_ins_filter f1, f2;
    const double v[3] = {4.0, 1.0, 0.0};
    CHECK(start(&f1, &c, v, 0.0) == GF_OK && start(&f2, &c, v, 0.0) == GF_OK, "init");
    gf_ins_pass passes[5];
    int32_t np = 0;
    gf_ins_innovation entries[1024];
    gf_ins_log log = {1024, 0, 0, entries};
    CHECK(gf_ins_forward_backward(&f1, n, g_t, g_g, g_a, nm, m, 2, passes, &log, &np) == GF_OK && np == 5,
          "driver (%d passes)", np);
    /* the same passes by hand */
    gf_ins_output out = {o_t, o_q, o_v, o_p, NULL, NULL, NULL, 0, NULL, NULL};
    size_t done, md;
    CHECK(gf_ins_run(&f2, n, g_t, g_g, g_a, nm, m, &out, NULL, NULL, &done, &md) == GF_OK && md == nm, "fwd");
    for (int p = 0; p < 2; ++p) {
        CHECK(gf_ins_reverse(&f2) == GF_OK, "rev");
        CHECK(gf_ins_run_backward(&f2, n, g_t, g_g, g_a, 0.0, nm - 1, m, NULL, NULL, &done, &md) == GF_OK &&
                  md == nm - 1, "bwd");
        CHECK(gf_ins_reverse(&f2) == GF_OK, "rev");
        CHECK(gf_ins_run(&f2, n, g_t, g_g, g_a, nm - 1, m + 1, &out, NULL, NULL, &done, &md) == GF_OK, "fwd");
    }
    CHECK(memcmp(f1.nav.q_bn, f2.nav.q_bn, sizeof f1.nav.q_bn) == 0 &&
              memcmp(f1.kf.P, f2.kf.P, sizeof f1.kf.P) == 0 && memcmp(f1.sensors, f2.sensors, sizeof f1.sensors) == 0,
          "driver = passes by hand (bits)");
    CHECK(passes[0].direction == 1 && passes[1].direction == -1 && passes[4].direction == 1 &&
              fabs(passes[1].t_s) < 1e-9 && fabs(passes[4].t_s - g_t[n - 1]) < 1e-9 && f1.nav.earth_rate_sign == 1.0,
          "pass directions and times");
    /* every speed epoch used once per pass, the turning-point ones not twice in a row */
    CHECK(log.count == nm + 4 * (nm - 1), "updates logged: %zu (expected %zu)", log.count, nm + 4 * (nm - 1));
    CHECK(passes[0].n_updates + passes[0].n_rejected == nm, "pass 0 counts");
    CHECK(memcmp(passes[4].q_bn, f1.nav.q_bn, sizeof passes[4].q_bn) == 0, "last pass = filter state");
    /* bad input */
    CHECK(gf_ins_forward_backward(&f1, n, g_t, g_g, g_a, nm, m, -1, NULL, NULL, &np) == GF_ERR_BAD_PARAMETER,
          "n_fb < 0");
    CHECK(gf_ins_forward_backward(&f1, 1, g_t, g_g, g_a, 0, NULL, 1, NULL, NULL, &np) == GF_ERR_BAD_SIZE,
          "record of one sample");
    CHECK(gf_ins_reverse(&f1) == GF_OK, "rev");
    CHECK(gf_ins_forward_backward(&f1, n, g_t, g_g, g_a, nm, m, 1, NULL, NULL, &np) == GF_ERR_BAD_PARAMETER,
          "driver on a reversed filter");
    CHECK(gf_ins_run_backward(&f1, n - 1, g_t, g_g, g_a, 0.0, 0, NULL, NULL, NULL, &done, &md) == GF_ERR_BAD_TIME,
          "backward walk that does not start at the filter's time");
}

/* cfg.subsamples = 2 (gf_ins_run groups two increments per navigation update between
 * measurement and propagation instants): one row per group, at the group's end; a record
 * cut into calls at an even sample count gives the same bits as one call; a faulty
 * sample inside a group is reported at its own index, the rows before it kept. */
static void test_subsample_groups(void)
{
    enum { N = 6000 };           /* 60 s at 100 Hz; propagation every 10 samples */
    const double dt = 0.01;
    make_record(N, dt, g_t, g_g, g_a);
    gf_ins_config c = base_config();
    c.subsamples = 2;
    const double v[3] = {4.0, 1.0, 0.0};
    gf_ins_meas ms[2] = {{0}};
    for (int j = 0; j < 2; ++j) {          /* GNSS velocity inside groups: 10.003 s, 30.013 s */
        ms[j].type = GF_INS_MEAS_GNSS_VEL;
        ms[j].t_s = j ? 30.013 : 10.003;
        ms[j].z[0] = 4.0;
        ms[j].z[1] = 1.0;
        ms[j].std[0] = ms[j].std[1] = ms[j].std[2] = 0.1;
    }
    gf_ins_filter f1, f2;
    CHECK(start(&f1, &c, v, 0.0) == GF_OK && start(&f2, &c, v, 0.0) == GF_OK, "init");
    gf_ins_output out = {o_t, o_q, o_v, o_p, NULL, NULL, NULL, 0, NULL, NULL};
    size_t done, mdone;
    CHECK(gf_ins_run(&f1, N, g_t, g_g, g_a, 2, ms, &out, NULL, NULL, &done, &mdone) == GF_OK &&
              done == N && mdone == 2, "whole record");
    /* a measurement breaks its group into two single samples: one row more each */
    CHECK(out.n_rows == N / 2 + 2, "one row per group");
    int on_grid = 1;
    for (size_t r = 0; r < out.n_rows; ++r)
        on_grid &= fabs(o_t[r] / dt - rint(o_t[r] / dt)) < 1e-9 && (r == 0 || o_t[r] > o_t[r - 1]);
    CHECK(on_grid && o_t[out.n_rows - 1] == g_t[N - 1], "rows at sample times, increasing, to the end");
    /* in two calls cut at sample 2000 (even) */
    gf_ins_output out2 = {b_t, b_q, b_v, b_p, NULL, NULL, NULL, 0, NULL, NULL};
    CHECK(gf_ins_run(&f2, 2000, g_t, g_g, g_a, 1, ms, &out2, NULL, NULL, &done, &mdone) == GF_OK &&
              mdone == 1, "first part");
    const size_t r1 = out2.n_rows;
    gf_ins_output out3 = {b_t + r1, b_q + 4 * r1, b_v + 3 * r1, b_p + 3 * r1, NULL, NULL, NULL, 0, NULL, NULL};
    CHECK(gf_ins_run(&f2, N - 2000, g_t + 2000, g_g + 6000, g_a + 6000, 1, ms + 1, &out3, NULL, NULL,
                     &done, &mdone) == GF_OK, "second part");
    CHECK(r1 + out3.n_rows == out.n_rows && memcmp(b_q, o_q, 4 * out.n_rows * sizeof(double)) == 0 &&
              memcmp(b_p, o_p, 3 * out.n_rows * sizeof(double)) == 0 &&
              memcmp(b_v, o_v, 3 * out.n_rows * sizeof(double)) == 0, "two calls = one call (bits)");
    /* NaN in the second sample of a group: stopped there, the rows before kept */
    g_a[3 * 1001 + 2] = NAN;
    CHECK(start(&f2, &c, v, 0.0) == GF_OK, "init");
    CHECK(gf_ins_run(&f2, N, g_t, g_g, g_a, 0, NULL, &out2, NULL, NULL, &done, &mdone) ==
              GF_ERR_NONFINITE_INPUT && done == 1001 && out2.n_rows == 501 && f2.t_s == g_t[1000],
          "a faulty sample inside a group is reported at its index");
    g_a[3 * 1001 + 2] = 9.7936 * dt;
}

int main(void)
{
    test_speed_update();
    test_odometer_mounting();
    test_odometer_mount_jacobian();
    test_coarse_align();
    test_level_align_and_rotate();
    test_reverse_signs();
    test_round_trip();
    test_forward_backward_driver();
    test_subsample_groups();
    TEST_MAIN_END();
}
