/* test_fmu_vehicle.c — the vehicle FMU model (fmu/models/vehicle) through the FMI 2.0
 * glue, linked into this executable so that it runs under ASan/UBSan/LeakSanitizer
 * (tests/test_cosim.py covers the shipped FMUs through fmpy, FMI 2.0 and 3.0).
 *   1. a run of seed 001's default profile equals gf_vehicle called directly at the
 *      same communication points, bit for bit (truth, IMU, increments);
 *   2. IMU errors and the accelerometer array: outputs = gf_imu_apply / the array's
 *      forward model on the direct truth, bit for bit;
 *   3. FMU state: get mid-run, run on, set back, run again: identical; serialize,
 *      deserialize into a fresh instance: identical;
 *   4. bad parameters are refused by exitInitializationMode with a logged reason;
 *   5. commands (drive = 1): a held command is reached after command_time;
 *   6. GNSS, barometer, odometer: every epoch delivered by the FMU equals the epoch of
 *      gf_aiding_run called directly with the same parameters and seed, bit for bit, in
 *      the first step that reaches its delivery time; the FMU state (3.) holds them;
 *   7. damaged and crafted states (check_damaged_states in fmu2_test.h), with IMU errors
 *      and noise on: refused with a reason (CRC-32, or the field), random bytes in the
 *      live structs never make a step read or write out of bounds, and the instance
 *      continues exactly as before;
 *   8. rotation = 1 (the IMU on the two-axis mechanism, default 16-position scheme):
 *      IMU outputs = gf_rot_vehicle_step (+ gf_imu_apply) called directly, bit for bit;
 *      the gimbal angles = gf_rot_eval; the array stays on the body; a bad turn and a
 *      bad switch refused with a reason. */
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_instance.h"
#include "fmu2_test.h"
#include "base/gf_math.h"
#include "gyrofree/gf9.h"
#include "gyrofree/gf_array.h"
#include "sim/gf_aiding.h"
#include "sim/gf_rot.h"
#include "gf_test.h"
#include "sim/gf_vehicle.h"

#define H_S 0.01
enum { N = 3000 };   /* 30 s: rest, start, into the straight run */

/* Outputs compared: q, v, lat, lon, gyro_rate, specific_force, dtheta, dv, A (first 9). */
enum { N_OUT = 4 + 3 + 2 + 3 + 3 + 3 + 3 + 9 };
static fmi2ValueReference g_out[N_OUT];

static void init_outputs(void)
{
    fmi2ValueReference *p = g_out;
    vrs("q", 4, p); p += 4;
    vrs("v", 3, p); p += 3;
    *p++ = vr("lat");
    *p++ = vr("lon");
    vrs("gyro_rate", 3, p); p += 3;
    vrs("specific_force", 3, p); p += 3;
    vrs("dtheta", 3, p); p += 3;
    vrs("dv", 3, p); p += 3;
    vrs("A", 9, p);
}

/* The aiding sensors of test 6, as FMU parameters and as gf_aiding_params. */
static const double kGnssLever[3] = {0.3, 1.1, 1.6}, kGnssPosStd[3] = {1.0, 1.2, 2.5};
static const double kGnssGm[3] = {0.4, 0.4, 0.9}, kOdoLever[3] = {0.75, -1.2, -0.35};

static void set_aiding(fmi2Component c)
{
    set_int(c, "gnss", 1);
    set_real(c, "gnss_rate", 5.0);
    set_real(c, "gnss_offset", 0.0137);
    set_real(c, "gnss_latency", 0.12);
    set_vec(c, "gnss_lever_arm", kGnssLever, 3);
    set_vec(c, "gnss_pos_std", kGnssPosStd, 3);
    set_vec(c, "gnss_pos_gm_std", kGnssGm, 3);
    set_real(c, "gnss_pos_gm_tau", 20.0);
    set_int(c, "gnss_n_outages", 1);
    set_real(c, "gnss_outage_start[1]", 10.0);
    set_real(c, "gnss_outage_end[1]", 14.0);
    set_real(c, "gnss_outage_first", 20.0);
    set_real(c, "gnss_outage_period", 6.0);
    set_real(c, "gnss_outage_duration", 2.0);
    set_int(c, "baro", 1);
    set_real(c, "baro_rate", 25.0);
    set_real(c, "baro_offset", 0.004);
    set_real(c, "baro_bias0", 3.0);
    set_real(c, "baro_bias_rw", 0.02);
    set_int(c, "odo", 1);
    set_real(c, "odo_rate", 50.0);
    set_real(c, "odo_offset", 0.0051);
    set_vec(c, "odo_lever_arm", kOdoLever, 3);
    set_real(c, "odo_scale_error", 0.004);
    set_int(c, "noise_seed", 11);
}

static gf_aiding_params aiding_params(void)
{
    gf_aiding_params a;
    memset(&a, 0, sizeof a);
    a.gnss.enabled = 1;
    a.gnss.quality = 5;
    a.gnss.rate_hz = 5.0;
    a.gnss.offset_s = 0.0137;
    a.gnss.latency_s = 0.12;
    memcpy(a.gnss.lever_arm_m, kGnssLever, sizeof kGnssLever);
    memcpy(a.gnss.pos_std_m, kGnssPosStd, sizeof kGnssPosStd);
    const double vel_std[3] = {0.05, 0.05, 0.1}; /* the FMU's default */
    memcpy(a.gnss.vel_std_m_s, vel_std, sizeof vel_std);
    memcpy(a.gnss.pos_gm_std_m, kGnssGm, sizeof kGnssGm);
    a.gnss.pos_gm_tau_s = 20.0;
    a.gnss.n_outages = 1;
    a.gnss.outage_start_s[0] = 10.0;
    a.gnss.outage_end_s[0] = 14.0;
    a.gnss.outage_first_s = 20.0;
    a.gnss.outage_period_s = 6.0;
    a.gnss.outage_duration_s = 2.0;
    a.baro.enabled = 1;
    a.baro.rate_hz = 25.0;
    a.baro.offset_s = 0.004;
    a.baro.std_m = 0.5;
    a.baro.bias0_m = 3.0;
    a.baro.bias_rw_m_sqrt_s = 0.02;
    a.baro.bias_gm_tau_s = 100.0;
    a.odo.enabled = 1;
    a.odo.rate_hz = 50.0;
    a.odo.offset_s = 0.0051;
    memcpy(a.odo.lever_arm_m, kOdoLever, sizeof kOdoLever);
    a.odo.scale_error = 0.004;
    a.odo.std_m_s = 0.05;
    return a;
}

/* imu_errors: 0 none, 1 the IMU errors below, 2 the same and the aiding sensors */

static fmi2Component open_ready_noise(const char *name, int imu_errors, int noise, double stop_s);
static fmi2Component open_ready(const char *name, int imu_errors, double stop_s)
{
    return open_ready_noise(name, imu_errors, 0, stop_s);
}

static fmi2Component open_ready_noise(const char *name, int imu_errors, int noise, double stop_s)
{
    fmi2Component c = instantiate(name);
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, stop_s) == fmi2OK, "setup");
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    if (imu_errors == 2)
        set_aiding(c);
    if (imu_errors) {
        const double bias[3] = {1e-6, -2e-6, 3e-6}, scale[3] = {1e-4, -2e-4, 5e-5};
        const double k2[3] = {2e-5, -1e-5, 1.5e-5}, lever[3] = {0.03, -0.02, 0.025};
        const double mis[9] = {0, 5e-5, -4e-5, 6e-5, 0, 3e-5, -5e-5, 4e-5, 0};
        set_int(c, "imu_errors", 1);
        set_vec(c, "gyro_bias", bias, 3);
        set_vec(c, "accel_scale", scale, 3);
        set_vec(c, "accel_k2", k2, 3);
        set_vec(c, "lever_arm", lever, 3);
        set_vec(c, "gyro_misalign", mis, 9);
    }
    if (noise) {
        set_int(c, "noise", 1);
        set_real(c, "gyro_arw", 1e-4);
        set_real(c, "accel_vrw", 1e-4);
        set_real(c, "gyro_bias_instability", 1e-5);
        set_real(c, "array_noise", 1e-4);
    }
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", g_log);
    return c;
}

static double g_a[N][N_OUT], g_b[N][N_OUT];

/* Aiding outputs read after each step (reals, then the three counts). */
enum { N_AID = 1 + 3 + 3 + 3 + 3 + 3 + 3 + 3, N_AID_INT = 3 };
static fmi2ValueReference g_aid[N_AID], g_aid_int[N_AID_INT];

static void init_aiding_outputs(void)
{
    static const char *const scalars[] = {"gnss_time_s", "gnss_lat_rad", "gnss_lon_rad",
        "gnss_h_m", "baro_time_s", "baro_h_m", "baro_std_m", "odo_time_s", "odo_speed_m_s",
        "odo_std_m_s"};
    fmi2ValueReference *p = g_aid;
    for (int i = 0; i < 10; ++i)
        *p++ = vr(scalars[i]);
    vrs("gnss_vel_enu_m_s", 3, p); p += 3;
    vrs("gnss_pos_std_m", 3, p); p += 3;
    vrs("gnss_vel_std_m_s", 3, p);
    g_aid_int[0] = vr("gnss_valid");
    g_aid_int[1] = vr("baro_valid");
    g_aid_int[2] = vr("odo_valid");
}

static double g_aid_a[3001][N_AID], g_aid_b[3001][N_AID];
static fmi2Integer g_cnt_a[3001][N_AID_INT], g_cnt_b[3001][N_AID_INT];

static void run(fmi2Component c, int k0, int k1, double out[][N_OUT])
{
    for (int k = k0; k < k1; ++k) {
        CHECK(fmi2DoStep(c, k * H_S, H_S, fmi2True) == fmi2OK, "doStep %d", k);
        fmi2GetReal(c, g_out, N_OUT, out[k]);
        double (*aid)[N_AID] = out == g_a ? g_aid_a : g_aid_b;
        fmi2Integer (*cnt)[N_AID_INT] = out == g_a ? g_cnt_a : g_cnt_b;
        fmi2GetReal(c, g_aid, N_AID, aid[k + 1]);
        fmi2GetInteger(c, g_aid_int, N_AID_INT, cnt[k + 1]);
    }
}

/* The FMU's default profile (seed 001, 60 s alignment), for direct calls. */
static gf_vehicle_profile default_profile(void)
{
    gf_vehicle_profile p;
    memset(&p, 0, sizeof p);
    p.lat0_rad = 0.5235987755982988;
    p.lon0_rad = 1.9896753472735356;
    p.h0_m = 100.0;
    p.n_segments = 6;
    const double seg[6][4] = {{60, 0, 0, 0}, {20, 15, 0, 0}, {220, 0, 0, 0}, {30, 0, 0, GF_PI},
                              {210, 0, 0, 0}, {30, 0, 0, GF_PI}};
    for (int i = 0; i < 6; ++i) {
        p.segment[i].duration_s = seg[i][0];
        p.segment[i].dspeed_m_s = seg[i][1];
        p.segment[i].dheading_rate_rad_s = seg[i][2];
        p.segment[i].dheading_rad = seg[i][3];
    }
    return p;
}

static void test_equals_core(int imu_errors)
{
    fmi2Component c = open_ready("vehicle", imu_errors, N * H_S);
    run(c, 0, N, g_a);
    fmi2FreeInstance(c);
    /* the same motion directly */
    const gf_vehicle_profile p = default_profile();
    gf_vehicle_state s;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "direct init");
    gf_array_geometry g;
    gf9_geometry(0.1, &g);
    gf_imu_errors e;
    memset(&e, 0, sizeof e);
    if (imu_errors) {
        const double bias[3] = {1e-6, -2e-6, 3e-6}, scale[3] = {1e-4, -2e-4, 5e-5};
        const double k2[3] = {2e-5, -1e-5, 1.5e-5}, lever[3] = {0.03, -0.02, 0.025};
        const double mis[9] = {0, 5e-5, -4e-5, 6e-5, 0, 3e-5, -5e-5, 4e-5, 0};
        memcpy(e.g_bias_rad_s, bias, sizeof bias);
        memcpy(e.a_scale, scale, sizeof scale);
        memcpy(e.a_k2_s2_m, k2, sizeof k2);
        for (int i = 0; i < 3; ++i)
            e.a_lever_pos_m[4 * i] = lever[i];
        memcpy(e.g_misalign_rad, mis, sizeof mis);
    }
    int worst = -1;
    for (int k = 0; k < N && worst < 0; ++k) {
        s.time_s = k * H_S;       /* the FMU steps from the master's t to t + h */
        CHECK(gf_vehicle_step(&s, k * H_S + H_S, &x) == GF_OK, "direct step");
        double w[3], f[3], mw[3], mf[3], ew[3], ef[3], A[GF_ARRAY_MAX_SENSORS];
        size_t done;
        gf_imu_apply(&e, 1, x.gyro_rad_s, x.accel_m_s2, NULL, w, f, &done);
        for (int i = 0; i < 3; ++i) {
            mw[i] = x.dtheta_rad[i] / H_S;
            mf[i] = x.dv_m_s[i] / H_S;
        }
        gf_imu_apply(&e, 1, mw, mf, NULL, ew, ef, &done);
        gf_array_forward(&g, 1, x.accel_m_s2, x.gyro_rad_s, x.gyro_dot_rad_s2, A, &done);
        double want[N_OUT], *q = want;
        memcpy(q, x.q_bn, 4 * sizeof *q); q += 4;
        memcpy(q, x.v_n_m_s, 3 * sizeof *q); q += 3;
        *q++ = x.lat_rad;
        *q++ = x.lon_rad;
        memcpy(q, w, 3 * sizeof *q); q += 3;
        memcpy(q, f, 3 * sizeof *q); q += 3;
        for (int i = 0; i < 3; ++i) q[i] = imu_errors ? ew[i] * H_S : x.dtheta_rad[i];
        q += 3;
        for (int i = 0; i < 3; ++i) q[i] = imu_errors ? ef[i] * H_S : x.dv_m_s[i];
        q += 3;
        memcpy(q, A, 9 * sizeof *q);
        if (memcmp(want, g_a[k], sizeof want) != 0)
            worst = k;
    }
    CHECK(worst < 0, "imu_errors = %d: FMU differs from the core at step %d", imu_errors, worst);
}

/* 8. the rotating IMU: the FMU's default schedule (16 positions: 180 deg turns of 19 s
 * with 1 s ramps, 10 s stops; repeated) against gf_rot_vehicle_step */
static void test_rotation_equals_core(void)
{
    fmi2Component c = instantiate("rotating");
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, N * H_S) == fmi2OK, "setup");
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    set_int(c, "rotation", 1);
    set_int(c, "imu_errors", 1);
    const double k2[3] = {2e-5, -1e-5, 1.5e-5}, lever[3] = {0.03, -0.02, 0.025};
    /* issue 22: accelerometers offset across their axes and a delay (the IMU turns, so
     * the angular acceleration and w x f matter) */
    const double transverse[6] = {0.01, 0.02, 0.04, -0.05, 0.0, 0.0}, delay = 1e-3;
    set_vec(c, "accel_k2", k2, 3);
    set_vec(c, "lever_arm", lever, 3);
    set_vec(c, "lever_arm_transverse", transverse, 6);
    set_real(c, "accel_delay", delay);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", g_log);
    fmi2ValueReference gim[2];
    vrs("gimbal", 2, gim);
    static double got_gimbal[N][2];
    for (int k = 0; k < N; ++k) {
        CHECK(fmi2DoStep(c, k * H_S, H_S, fmi2True) == fmi2OK, "doStep %d", k);
        fmi2GetReal(c, g_out, N_OUT, g_a[k]);
        fmi2GetReal(c, gim, 2, got_gimbal[k]);
    }
    fmi2FreeInstance(c);
    gf_rot_schedule sch;
    memset(&sch, 0, sizeof sch);
    sch.q_mb0[0] = 1.0;
    sch.repeat = 1;
    sch.n_segments = 16;
    const int axis8[8] = {1, 0, 1, 0, 0, 1, 0, 1}; /* 1 inner, 0 middle */
    const double sgn8[8] = {1, 1, -1, -1, -1, -1, 1, 1};
    for (int k = 0; k < 16; ++k) {
        const int inner = k < 8 ? axis8[k] : !axis8[k - 8];
        const double a = sgn8[k % 8] * GF_PI;
        sch.segment[k] = inner ? (gf_rot_segment){-1, 2, 0.0, a, 19.0, 1.0, 10.0}
                               : (gf_rot_segment){0, -1, a, 0.0, 19.0, 1.0, 10.0};
    }
    gf_rot_state rs;
    CHECK(gf_rot_init(&rs, &sch, 0.0, NULL) == GF_OK, "direct schedule");
    const gf_vehicle_profile p = default_profile();
    gf_vehicle_state s;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "direct init");
    gf_array_geometry g;
    gf9_geometry(0.1, &g);
    gf_imu_errors e;
    memset(&e, 0, sizeof e);
    memcpy(e.a_k2_s2_m, k2, sizeof k2);
    for (int i = 0; i < 3; ++i)
        e.a_lever_pos_m[4 * i] = lever[i];
    const int off[6] = {1, 2, 3, 5, 6, 7};
    for (int i = 0; i < 6; ++i)
        e.a_lever_pos_m[off[i]] = transverse[i];
    e.a_delay_s = delay;
    /* the model's angular acceleration (model.c sense): the mean over the step from the
     * IMU's true rates at its ends; the first "previous" rate is the IMU's at the start */
    double w_prev[3], f0[3];
    gf_rot_pose pose0;
    gf_rot_imu_outputs(&rs, 0.0, x.gyro_rad_s, x.accel_m_s2, w_prev, f0, &pose0);
    int worst = -1;
    for (int k = 0; k < N && worst < 0; ++k) {
        s.time_s = k * H_S;
        double imu[12];
        CHECK(gf_rot_vehicle_step(&rs, &s, k * H_S + H_S, &x, imu) == GF_OK, "direct step");
        double w[3], f[3], mw[3], mf[3], ew[3], ef[3], wd[3], A[GF_ARRAY_MAX_SENSORS];
        size_t done;
        for (int i = 0; i < 3; ++i)
            wd[i] = (imu[i] - w_prev[i]) / H_S;
        memcpy(w_prev, imu, sizeof w_prev);
        gf_imu_apply_dw(&e, 1, imu, wd, imu + 3, NULL, w, f, &done);
        for (int i = 0; i < 3; ++i) {
            mw[i] = imu[6 + i] / H_S;
            mf[i] = imu[9 + i] / H_S;
        }
        gf_imu_apply_dw(&e, 1, mw, wd, mf, NULL, ew, ef, &done);
        gf_array_forward(&g, 1, x.accel_m_s2, x.gyro_rad_s, x.gyro_dot_rad_s2, A, &done);
        double want[N_OUT], *q = want;
        memcpy(q, x.q_bn, 4 * sizeof *q); q += 4;
        memcpy(q, x.v_n_m_s, 3 * sizeof *q); q += 3;
        *q++ = x.lat_rad;
        *q++ = x.lon_rad;
        memcpy(q, w, 3 * sizeof *q); q += 3;
        memcpy(q, f, 3 * sizeof *q); q += 3;
        for (int i = 0; i < 3; ++i) q[i] = ew[i] * H_S;
        q += 3;
        for (int i = 0; i < 3; ++i) q[i] = ef[i] * H_S;
        q += 3;
        memcpy(q, A, 9 * sizeof *q);
        gf_rot_pose pose;
        gf_rot_eval(&rs, k * H_S + H_S, &pose);
        if (memcmp(want, g_a[k], sizeof want) != 0 || pose.gimbal_rad[0] != got_gimbal[k][0] ||
            pose.gimbal_rad[1] != got_gimbal[k][1])
            worst = k;
    }
    CHECK(worst < 0, "rotation = 1: FMU differs from the core at step %d", worst);
    CHECK(fabs(got_gimbal[N - 1][1]) > 0.1, "the inner axis has turned by 30 s");
}

/* 6. the aiding sensors against gf_aiding_run on the same vehicle and seed */
enum { CAP = 4000 };
static gf_gnss_epoch g_gnss[CAP];
static gf_baro_epoch g_baro[CAP];
static gf_odo_epoch g_odo[CAP];

static void test_aiding_equals_core(void)
{
    fmi2Component c = open_ready("aiding", 2, N * H_S);
    fmi2GetReal(c, g_aid, N_AID, g_aid_a[0]);
    fmi2GetInteger(c, g_aid_int, N_AID_INT, g_cnt_a[0]);
    run(c, 0, N, g_a);
    fmi2FreeInstance(c);
    const gf_vehicle_profile p = default_profile();
    gf_vehicle_state s;
    CHECK(gf_vehicle_init(&s, &p, 0.0, NULL, NULL) == GF_OK, "direct init");
    const gf_aiding_params a = aiding_params();
    gf_aiding_sim sim;
    CHECK(gf_aiding_init(&sim, &a, &s, 11, NULL, NULL) == GF_OK, "direct aiding init");
    size_t n[3];
    CHECK(gf_aiding_run(&sim, N * H_S, g_gnss, CAP, &n[0], g_baro, CAP, &n[1], g_odo, CAP, &n[2]) ==
              GF_OK, "direct aiding run");
    /* 5 Hz over 30 s less the outages [10, 14), [20, 22), [26, 28): 150 - 20 - 10 - 10 */
    CHECK(n[0] == 110 && n[1] == 750 && n[2] == 1500, "epochs %zu %zu %zu", n[0], n[1], n[2]);
    size_t seen[3] = {0, 0, 0};
    int bad_step = -1;
    for (int k = 0; k <= N; ++k) {
        const double *y = g_aid_a[k];
        const fmi2Integer *cnt = g_cnt_a[k];
        const double t_end = k * H_S, t_prev = (k - 1) * H_S;
        if (cnt[0] == 1) {
            const gf_gnss_epoch *e = &g_gnss[seen[0]++];
            const double want[13] = {e->t_s, e->lat_rad, e->lon_rad, e->h_m,
                e->vel_enu_m_s[0], e->vel_enu_m_s[1], e->vel_enu_m_s[2],
                e->pos_std_m[0], e->pos_std_m[1], e->pos_std_m[2],
                e->vel_std_m_s[0], e->vel_std_m_s[1], e->vel_std_m_s[2]};
            const double got[13] = {y[0], y[1], y[2], y[3], y[10], y[11], y[12], y[13], y[14],
                                    y[15], y[16], y[17], y[18]};
            if (memcmp(want, got, sizeof want) != 0 || !(e->t_delivered_s <= t_end) ||
                !(e->t_delivered_s > t_prev))
                bad_step = k;
        }
        if (cnt[1] == 1) {
            const gf_baro_epoch *e = &g_baro[seen[1]++];
            const double want[3] = {e->t_s, e->h_m, e->std_m};
            if (memcmp(want, y + 4, sizeof want) != 0 || !(e->t_s <= t_end && e->t_s > t_prev))
                bad_step = k;
        }
        if (cnt[2] == 1) {
            const gf_odo_epoch *e = &g_odo[seen[2]++];
            const double want[3] = {e->t_s, e->speed_m_s, e->std_m_s};
            if (memcmp(want, y + 7, sizeof want) != 0 || !(e->t_s <= t_end && e->t_s > t_prev))
                bad_step = k;
        }
        if (cnt[0] > 1 || cnt[1] > 1 || cnt[2] > 1)
            bad_step = k;
    }
    CHECK(bad_step < 0, "aiding outputs differ from the core at step %d", bad_step);
    CHECK(seen[0] == n[0] && seen[1] == n[1] && seen[2] == n[2], "epochs delivered %zu %zu %zu",
          seen[0], seen[1], seen[2]);
    CHECK(isnan(g_aid_a[0][0]) && g_cnt_a[0][0] == 0, "no GNSS epoch at the start (offset)");
}

static void test_states(void)
{
    fmi2Component c = open_ready("vehicle", 2, N * H_S);
    run(c, 0, N / 2, g_a);
    fmi2FMUstate st = NULL;
    CHECK(fmi2GetFMUstate(c, &st) == fmi2OK, "get state");
    run(c, N / 2, N, g_a);
    CHECK(fmi2SetFMUstate(c, st) == fmi2OK, "set state");
    run(c, N / 2, N, g_b);
    CHECK(memcmp(g_a[N / 2], g_b[N / 2], sizeof g_a[0] * (N - N / 2)) == 0, "replay after set");
    CHECK(memcmp(g_aid_a[N / 2 + 1], g_aid_b[N / 2 + 1], sizeof g_aid_a[0] * (N - N / 2)) == 0 &&
          memcmp(g_cnt_a[N / 2 + 1], g_cnt_b[N / 2 + 1], sizeof g_cnt_a[0] * (N - N / 2)) == 0,
          "aiding replay after set");
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, st, &size) == fmi2OK, "size");
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, st, bytes, size) == fmi2OK, "serialize");
    fmi2FreeFMUstate(c, &st);
    fmi2FreeInstance(c);
    fmi2Component d = open_ready("fresh", 2, N * H_S);
    fmi2FMUstate st2 = NULL;
    CHECK(fmi2DeSerializeFMUstate(d, bytes, size, &st2) == fmi2OK, "deserialize");
    CHECK(fmi2SetFMUstate(d, st2) == fmi2OK, "set deserialized");
    run(d, N / 2, N, g_b);
    CHECK(memcmp(g_a[N / 2], g_b[N / 2], sizeof g_a[0] * (N - N / 2)) == 0, "replay after deserialize");
    CHECK(memcmp(g_aid_a[N / 2 + 1], g_aid_b[N / 2 + 1], sizeof g_aid_a[0] * (N - N / 2)) == 0,
          "aiding replay after deserialize");
    fmi2FreeFMUstate(d, &st2);
    fmi2FreeInstance(d);
    free(bytes);
}

static void expect_refused(const char *param, double value, const char *mention)
{
    fmi2Component c = instantiate("bad");
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    /* an aiding sensor's parameters are checked when it is enabled */
    static const char *const sensors[] = {"gnss", "baro", "odo"};
    for (int i = 0; i < 3; ++i)
        if (strncmp(param, sensors[i], strlen(sensors[i])) == 0 && param[strlen(sensors[i])] == '_')
            set_int(c, sensors[i], 1);
    const fmi2ValueReference r = vr(param);
    if (kFmi2Variables[r - 1].type == FMU_TYPE_INT32) {
        const fmi2Integer v = (fmi2Integer)value;
        fmi2SetInteger(c, &r, 1, &v);
    } else {
        fmi2SetReal(c, &r, 1, &value);
    }
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error, "%s = %g accepted", param, value);
    CHECK(strstr(g_log, mention) != NULL, "%s: log does not mention %s: %s", param, mention, g_log);
    fmi2FreeInstance(c);
}

static void expect_refused_rotation(void)
{
    fmi2Component c = instantiate("bad turn");
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    set_int(c, "rotation", 1);
    set_real(c, "rot_ramp[3]", 12.0);
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error, "a ramp longer than half the turn accepted");
    CHECK(strstr(g_log, "turn 3 (rot_*[3])") != NULL, "log does not name turn 3: %s", g_log);
    fmi2FreeInstance(c);
}

static void test_commands(void)
{
    fmi2Component c = instantiate("cmd");
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    set_int(c, "drive", 1);
    set_int(c, "n_segments", 0);
    set_real(c, "command_time", 2.0);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit (commands)");
    set_real(c, "speed_cmd", 8.0);
    set_real(c, "heading_rate_cmd", 0.1);
    for (int k = 0; k < 400; ++k)
        fmi2DoStep(c, k * H_S, H_S, fmi2True);
    const fmi2ValueReference heading = vr("euler[1]");
    double psi = 0.0;
    fmi2GetReal(c, &heading, 1, &psi);
    /* 0.1 rad/s reached over 2 s (smooth step integrates to 1/2), then 2 s more */
    CHECK_CLOSE(psi, 0.3, 1e-12, "heading after a held command");
    fmi2FreeInstance(c);
}

static fmi2Status vehicle_step(fmi2Component c, double t_s)
{
    return fmi2DoStep(c, t_s, H_S, fmi2True);
}

static void test_damaged_states(void)
{
    fmi2Component c = open_ready_noise("damaged", 1, 1, N * H_S);
    const StatePatch patches[] = {
        PATCH('z', vehicle.next_segment, 1000, "vehicle state"),
        PATCH('z', vehicle.profile.n_segments, 1000, "vehicle state"),
        PATCH('d', vehicle.time_s, NAN, "vehicle state"),
        PATCH('z', array.n_sensors, 64, "array"),
        PATCH('i', array_layout, 3, "array"),
        PATCH('i', drive, 2, "drive"),
        PATCH('i', noise, 5, "noise"),
        PATCH('i', imu_errors, -1, "imu_errors"),
        PATCH('i', imu.temp_order, 99, "IMU error"),
        PATCH('d', imu_noise.p.gyro_arw_rad_sqrt_s, -1.0, "noise state"),
        PATCH('d', array_noise_m_s2, NAN, "array_noise"),
        PATCH('d', command_time_s, 0.0, "command_time"),
    };
    const StateRegion regions[] = {
        REGION_HEAD(vehicle.profile, 64), REGION_HEAD(vehicle.time_s, sizeof(gf_vehicle_state) -
                                                     offsetof(gf_vehicle_state, time_s)),
        REGION_HEAD(array, 16), REGION(imu_noise.p), REGION(imu), REGION(n_segments),
        REGION(drive), REGION(imu_errors), REGION(array_layout), REGION(noise),
        REGION(array_noise_m_s2), REGION(command_time_s)};
    const int mid = N / 2;
    run(c, 0, mid, g_a);
    check_damaged_states(c, mid * H_S, H_S, vehicle_step, N - mid, g_out, N_OUT, patches,
                         sizeof patches / sizeof patches[0], regions,
                         sizeof regions / sizeof regions[0], 600);
    fmi2FreeInstance(c);
}

int main(void)
{
    init_outputs();
    init_aiding_outputs();
    test_equals_core(0);
    test_equals_core(1);
    test_states();
    expect_refused("n_segments", 40, "n_segments");
    expect_refused("lat0", 1.56, "lat0");
    expect_refused("array_layout", 7, "array_layout");
    expect_refused("command_time", -1.0, "command_time");
    expect_refused("speed0", -2.0, "speed0");
    expect_refused("gnss", 2, "gnss must be 0 or 1");
    expect_refused("gnss_rate", 0.0, "gnss_rate");
    expect_refused("gnss_latency", 20.0, "gnss_latency");
    expect_refused("gnss_n_outages", 9, "gnss_n_outages");
    expect_refused("gnss_outage_duration", 1.0, "gnss_outage_first/_period/_duration");
    expect_refused("baro_bias_gm_std", -0.1, "baro_bias_gm_std");
    expect_refused("odo_scale_error", 0.6, "odo_scale_error");
    test_aiding_equals_core();
    test_rotation_equals_core();
    expect_refused("rotation", 2, "rotation = 2 must be 0 or 1");
    expect_refused_rotation();
    test_commands();
    test_damaged_states();
    TEST_MAIN_END();
}
