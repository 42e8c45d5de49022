/* test_fmu_transfer_align.c — the transfer-alignment FMU model (fmu/models/transfer_align,
 * issue 24) through the FMI 2.0 glue, linked into this executable so that it runs under
 * ASan/UBSan/LeakSanitizer (tests/fmi/test_fmu_transfer.py covers the shipped FMUs
 * through fmpy, FMI 2.0 and 3.0, against the Python batch API). Data: the vehicle truth
 * of turn_drive.h (15 s: rest, start, a 180 deg turn) as the slave IMU's increments; a
 * master INS whose axes are the slave's turned by (20', -15', 25') back, its epochs every
 * 10 samples valid 3 ms before the sample they come with (the interval is split there),
 * its attitude the truth's turned by the mounting, its velocity and position the truth's
 * (a master at the slave's point, no stream offset: the filter, started from nominal 0s,
 * sees innovations), its rate the truth's in its axes. Every transfer state on (mounting, lever arm, time offset: 22 states).
 *   1. EKF and UKF, velocity + attitude + position matching: the FMU equals the core
 *      started with the same P0 (gf_ins_initial_covariance + gf_ins_master_start_covariance,
 *      the start from the master) and stepped with gf_ins_step and the same master
 *      measurements, bit for bit (navigation, std, sensor errors, mounting, lever arm,
 *      offset and their std, per-kind NIS and status);
 *   2. FMU state mid-run: set back and replay, and serialize into a fresh instance: the
 *      same outputs; damaged and crafted states refused (fmu2_test.h);
 *   3. refused: bad parameters (logged naming them), an epoch valid after the sample it
 *      came with, a non-finite master input. */
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_instance.h"
#include "fmu2_test.h"
#include "base/gf_math.h"
#include "est/gf_ins_gnss.h"
#include "gf_test.h"
#include "nav/gf_sins.h"
#include "sim/gf_vehicle.h"
#include "turn_drive.h"

#define H_S 0.01
enum { N = 1500 };

static gf_vehicle_sample g_truth[N];
/* the master's mounting: heading, pitch, roll of the slave in the master's axes */
static const double kMount[3] = {0.0058, -0.0044, 0.0073};
static const double kVelStd[3] = {0.02, 0.02, 0.02}, kAttStd[3] = {1e-4, 1e-4, 3e-4};
static const double kPosStd[3] = {1.0, 1.0, 1.0};

/* ---- the master epoch delivered with sample k (the same for the FMU and the core) ----- */

typedef struct Master {
    double t_s, euler[3], v[3], lat, lon, h, rate[3];
} Master;

static int master_at(int k, Master *m)
{
    if (k < 10 || k % 10 != 0)
        return 0;
    const gf_vehicle_sample *x = &g_truth[k];
    double qM[4], qMc[4], qm[4];
    gf_euler_to_quat(kMount, qM);
    gf_q_conj(qM, qMc);
    gf_q_mul(x->q_bn, qMc, qm);                 /* C_m^n = C_s^n M^T */
    gf_quat_to_euler(qm, m->euler);
    m->t_s = k * H_S - 0.003;
    memcpy(m->v, x->v_n_m_s, sizeof m->v);
    m->lat = x->lat_rad;
    m->lon = x->lon_rad;
    m->h = x->h_m;
    gf_mat3 M;
    gf_q_to_dcm(qM, &M);                        /* w^m = M w^s */
    double w[3] = {x->dtheta_rad[0] / H_S, x->dtheta_rad[1] / H_S, x->dtheta_rad[2] / H_S};
    gf_m3_mul_v3(&M, w, m->rate);
    return 1;
}

static size_t core_meas(int k, gf_ins_meas *ms)
{
    Master m;
    if (!master_at(k, &m))
        return 0;
    ms[0] = (gf_ins_meas){GF_INS_MEAS_MASTER_VEL, m.t_s, {m.v[0], m.v[1], m.v[2]},
                          {kVelStd[0], kVelStd[1], kVelStd[2]}, {m.rate[0], m.rate[1], m.rate[2]}};
    ms[1] = (gf_ins_meas){GF_INS_MEAS_MASTER_ATT, m.t_s, {m.euler[0], m.euler[1], m.euler[2]},
                          {kAttStd[0], kAttStd[1], kAttStd[2]}, {m.rate[0], m.rate[1], m.rate[2]}};
    ms[2] = (gf_ins_meas){GF_INS_MEAS_MASTER_POS, m.t_s, {m.lat, m.lon, m.h},
                          {kPosStd[0], kPosStd[1], kPosStd[2]}, {m.rate[0], m.rate[1], m.rate[2]}};
    return 3;
}

static void fmu_inputs(fmi2Component c, int k)
{
    Master m;
    const int valid = master_at(k, &m);
    set_vec(c, "dtheta", g_truth[k].dtheta_rad, 3);
    set_vec(c, "dv", g_truth[k].dv_m_s, 3);
    set_int(c, "master_valid", valid);
    if (valid) {
        set_real(c, "master_time_s", m.t_s);
        set_vec(c, "master_euler", m.euler, 3);
        set_vec(c, "master_vel", m.v, 3);
        set_real(c, "master_lat", m.lat);
        set_real(c, "master_lon", m.lon);
        set_real(c, "master_h", m.h);
        set_vec(c, "master_rate", m.rate, 3);
    }
}

/* ---- configuration: the same numbers to the FMU and to the core ----------------------- */

static const double kStd0Vel = 0.1, kStd0Pos = 1.0, kStd0Att = 1e-3, kStd0Bg = 1e-3, kStd0Ba = 0.03;
static const double kStd0Mount = 0.02, kStd0Lever = 0.1, kStd0Offset = 0.02;

static void core_config(gf_ins_config *c, int filter)
{
    gf_ins_config_default(c);
    c->filter = filter;
    c->gate_probability = 0.0;
    c->noise.gyro_arw_rad_sqrt_s = 1e-4;
    c->noise.accel_vrw_m_s_sqrt_s = 1e-3;
    c->master_mount = c->master_lever = c->master_time_offset = 1;
    /* nominal mounting, lever arm and offset 0 (the defaults): the filter finds them */
}

static void set_vec3(fmi2Component c, const char *name, double v)
{
    const double x[3] = {v, v, v};
    set_vec(c, name, x, 3);
}

static fmi2Component open_ready(int filter)
{
    const gf_vehicle_sample *x0 = &g_truth[0];
    fmi2Component c = instantiate("transfer");
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    gf_ins_config cfg;
    core_config(&cfg, filter);
    set_int(c, "filter", filter);
    set_real(c, "gate_probability", cfg.gate_probability);
    set_int(c, "gate_reset_count", (int)cfg.gate_reset_count);
    set_real(c, "gyro_arw_rad_sqrt_s", cfg.noise.gyro_arw_rad_sqrt_s);
    set_real(c, "accel_vrw_m_s_sqrt_s", cfg.noise.accel_vrw_m_s_sqrt_s);
    set_real(c, "gyro_bias_std_rad_s", cfg.noise.gyro_bias_std_rad_s);
    set_real(c, "gyro_bias_tau_s", cfg.noise.gyro_bias_tau_s);
    set_real(c, "accel_bias_std_m_s2", cfg.noise.accel_bias_std_m_s2);
    set_real(c, "accel_bias_tau_s", cfg.noise.accel_bias_tau_s);
    set_int(c, "nhc", cfg.nhc);
    set_int(c, "zupt", cfg.zupt);
    set_real(c, "propagation_interval_s", cfg.propagation_interval_s);
    set_int(c, "master_mount", 1);
    set_int(c, "master_lever", 1);
    set_int(c, "master_time_offset", 1);
    set_vec(c, "q0", x0->q_bn, 4);
    set_vec(c, "v0", x0->v_n_m_s, 3);
    set_real(c, "lat0", x0->lat_rad);
    set_real(c, "lon0", x0->lon_rad);
    set_real(c, "h0", x0->h_m);
    set_vec3(c, "std0_vel", kStd0Vel);
    set_vec3(c, "std0_pos", kStd0Pos);
    set_vec3(c, "std0_att", kStd0Att);
    set_vec3(c, "std0_gyro_bias", kStd0Bg);
    set_vec3(c, "std0_accel_bias", kStd0Ba);
    set_vec3(c, "std0_mount", kStd0Mount);
    set_vec3(c, "std0_lever", kStd0Lever);
    set_real(c, "std0_time_offset", kStd0Offset);
    set_int(c, "match_attitude", 1);
    set_int(c, "match_position", 1);
    set_vec(c, "master_vel_std", kVelStd, 3);
    set_vec(c, "master_att_std", kAttStd, 3);
    set_vec(c, "master_pos_std", kPosStd, 3);
    return c;
}

/* ---- outputs ---------------------------------------------------------------------------- */

enum { O_MOUNT = 4 + 3 + 3 + 9 + GF_INS_N_SENSORS, O_NIS = O_MOUNT + 14 };
enum { N_OUT = O_NIS + 3, N_IOUT = 3 };
static double g_fmu[N][N_OUT], g_fmu2[N][N_OUT], g_core[N][N_OUT];
static int g_ist[N][N_IOUT], g_ist2[N][N_IOUT], g_icore[N][N_IOUT];

static void fmu_steps(fmi2Component c, int k0, int k1, double out[][N_OUT], int iout[][N_IOUT])
{
    fmi2ValueReference r[N_OUT], ri[N_IOUT];
    fmi2ValueReference *p = r;
    vrs("q", 4, p); p += 4;
    vrs("v", 3, p); p += 3;
    *p++ = vr("lat");
    *p++ = vr("lon");
    *p++ = vr("h");
    vrs("std", 9, p); p += 9;
    vrs("sensors", GF_INS_N_SENSORS, p); p += GF_INS_N_SENSORS;
    vrs("mount", 3, p); p += 3;
    vrs("mount_std", 3, p); p += 3;
    vrs("lever", 3, p); p += 3;
    vrs("lever_std", 3, p); p += 3;
    *p++ = vr("time_offset");
    *p++ = vr("time_offset_std");
    vrs("nis", 3, p);
    vrs("update_status", 3, ri);
    for (int k = k0; k < k1; ++k) {
        fmu_inputs(c, k);
        CHECK(fmi2DoStep(c, k * H_S, H_S, fmi2True) == fmi2OK, "doStep %d: %s", k, g_log);
        fmi2GetReal(c, r, N_OUT, out[k]);
        fmi2Integer st[N_IOUT];
        fmi2GetInteger(c, ri, N_IOUT, st);
        for (int i = 0; i < N_IOUT; ++i)
            iout[k][i] = st[i];
    }
}

static void core_run(int filter)
{
    const gf_vehicle_sample *x0 = &g_truth[0];
    gf_ins_config cfg;
    core_config(&cfg, filter);
    int32_t n = 0;
    CHECK(gf_ins_state_count(&cfg, &n) == GF_OK && n == 22, "22 states: %d", (int)n);
    gf_ins_initial_std sd;
    memset(&sd, 0, sizeof sd);
    for (int i = 0; i < 3; ++i) {
        sd.velocity_std_m_s[i] = kStd0Vel;
        sd.position_std_m[i] = kStd0Pos;
        sd.attitude_std_rad[i] = kStd0Att;
        sd.gyro_bias_std_rad_s[i] = kStd0Bg;
        sd.accel_bias_std_m_s2[i] = kStd0Ba;
        sd.master_mount_std_rad[i] = kStd0Mount;
        sd.master_lever_std_m[i] = kStd0Lever;
    }
    sd.master_time_offset_std_s = kStd0Offset;
    static double P0[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    int32_t bad = -1;
    CHECK(gf_ins_initial_covariance(&cfg, x0->lat_rad, x0->h_m, &sd, P0, &bad) == GF_OK, "P0");
    CHECK(gf_ins_master_start_covariance(&cfg, x0->q_bn, P0) == GF_OK, "start from the master");
    static gf_ins_filter f;
    CHECK(gf_ins_init(&f, &cfg, 0.0, x0->q_bn, x0->v_n_m_s, x0->lat_rad, x0->lon_rad, x0->h_m,
                      NULL, P0, &bad) == GF_OK && bad == 0, "core init");
    double nis[3] = {NAN, NAN, NAN};
    int status[3] = {-1, -1, -1};
    for (int k = 0; k < N; ++k) {
        if (k > 0) { /* the sample at the start carries no increment */
            gf_ins_meas m[3];
            const size_t nm = core_meas(k, m);
            gf_ins_innovation entries[16];
            gf_ins_log log = {16, 0, 0, entries};
            CHECK(gf_ins_step(&f, k * H_S, g_truth[k].dtheta_rad, g_truth[k].dv_m_s, nm, m, NULL,
                              &log) == GF_OK, "core step %d", k);
            for (size_t i = 0; i < log.count; ++i) {
                const int j = entries[i].type - GF_INS_MEAS_MASTER_VEL;
                if (j >= 0 && j < 3) {
                    nis[j] = entries[i].nis;
                    status[j] = entries[i].status;
                }
            }
        }
        double *o = g_core[k];
        memcpy(o, f.nav.q_bn, 4 * sizeof *o);
        memcpy(o + 4, f.nav.v_n_m_s, 3 * sizeof *o);
        o[7] = f.nav.lat_rad;
        o[8] = f.nav.lon_rad;
        o[9] = f.nav.h_m;
        memcpy(o + 10, f.std9, 9 * sizeof *o);
        memcpy(o + 19, f.sensors, GF_INS_N_SENSORS * sizeof *o);
        const int nn = f.n_states;
        for (int i = 0; i < 3; ++i) {
            const int a = f.idx_tmount + i, l = f.idx_tlever + i;
            o[O_MOUNT + i] = cfg.master_mount_rad[i] + f.transfer[i];
            o[O_MOUNT + 3 + i] = sqrt(f.kf.P[a * nn + a]);
            o[O_MOUNT + 6 + i] = cfg.master_lever_arm_m[i] + f.transfer[3 + i];
            o[O_MOUNT + 9 + i] = sqrt(f.kf.P[l * nn + l]);
        }
        o[O_MOUNT + 12] = cfg.master_time_offset_s + f.transfer[6];
        o[O_MOUNT + 13] = sqrt(f.kf.P[f.idx_toffset * nn + f.idx_toffset]);
        memcpy(o + O_NIS, nis, sizeof nis);
        memcpy(g_icore[k], status, sizeof status);
    }
}

static void test_equals_core(int filter)
{
    fmi2Component c = open_ready(filter);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", g_log);
    fmu_steps(c, 0, N, g_fmu, g_ist);
    fmi2FreeInstance(c);
    core_run(filter);
    int first_bad = -1;
    for (int k = 0; k < N && first_bad < 0; ++k)
        if (memcmp(g_fmu[k], g_core[k], sizeof g_fmu[k]) != 0 ||
            memcmp(g_ist[k], g_icore[k], sizeof g_ist[k]) != 0)
            first_bad = k;
    CHECK(first_bad < 0, "filter %d: FMU differs from the core at step %d", filter, first_bad);
    /* every kind was used, and the filter moved its mounting towards the master's */
    for (int j = 0; j < 3; ++j)
        CHECK(g_ist[N - 1][j] == GF_INS_ACCEPTED && g_fmu[N - 1][O_NIS + j] > 0.0, "kind %d used", j);
    CHECK(g_fmu[N - 1][O_MOUNT + 3] < 0.5 * kStd0Mount, "the mounting's heading std fell: %g",
          g_fmu[N - 1][O_MOUNT + 3]);
}

static void test_states(void)
{
    fmi2Component c = open_ready(GF_INS_EKF);
    fmi2ExitInitializationMode(c);
    fmu_steps(c, 0, N / 2, g_fmu, g_ist);
    fmi2FMUstate st = NULL;
    CHECK(fmi2GetFMUstate(c, &st) == fmi2OK, "get state");
    const ModelData *live = &((FmuInstance *)c)->s.data;
    CHECK(model_validate_state(live) == NULL, "live state valid: %s", model_validate_state(live));
    fmu_steps(c, N / 2, N, g_fmu, g_ist);
    CHECK(fmi2SetFMUstate(c, st) == fmi2OK, "set state");
    fmu_steps(c, N / 2, N, g_fmu2, g_ist2);
    CHECK(memcmp(g_fmu[N / 2], g_fmu2[N / 2], sizeof g_fmu[0] * (N - N / 2)) == 0 &&
          memcmp(g_ist[N / 2], g_ist2[N / 2], sizeof g_ist[0] * (N - N / 2)) == 0, "replay");
    size_t size = 0;
    fmi2SerializedFMUstateSize(c, st, &size);
    fmi2Byte *bytes = malloc(size);
    CHECK(bytes && fmi2SerializeFMUstate(c, st, bytes, size) == fmi2OK, "serialize");
    fmi2FreeFMUstate(c, &st);
    fmi2FreeInstance(c);
    fmi2Component d = open_ready(GF_INS_UKF); /* another filter: the state carries its own */
    fmi2ExitInitializationMode(d);
    fmi2FMUstate st2 = NULL;
    CHECK(fmi2DeSerializeFMUstate(d, bytes, size, &st2) == fmi2OK, "deserialize");
    CHECK(fmi2SetFMUstate(d, st2) == fmi2OK, "set deserialized");
    memset(g_fmu2, 0, sizeof g_fmu2);
    fmu_steps(d, N / 2, N, g_fmu2, g_ist2);
    CHECK(memcmp(g_fmu[N / 2], g_fmu2[N / 2], sizeof g_fmu[0] * (N - N / 2)) == 0,
          "replay in a fresh instance");
    fmi2FreeFMUstate(d, &st2);
    fmi2FreeInstance(d);
    free(bytes);
}

static fmi2Status ta_step(fmi2Component c, double t_s)
{
    const int k = (int)(t_s / H_S + 0.5);
    fmu_inputs(c, k);
    return fmi2DoStep(c, t_s, H_S, fmi2True);
}

static void test_damaged_states(void)
{
    fmi2Component c = open_ready(GF_INS_EKF);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", g_log);
    const int mid = N / 2;
    fmu_steps(c, 0, mid, g_fmu, g_ist);
    fmi2ValueReference r[4 + 3 + 3];
    vrs("q", 4, r);
    vrs("mount", 3, r + 4);
    vrs("lever", 3, r + 7);
    const StatePatch patches[] = {
        PATCH('i', filter.n_states, 36, "filter"),
        PATCH('i', filter.idx_tmount, 40, "filter"),
        PATCH('i', filter.idx_toffset, 3, "filter"),
        PATCH('z', filter.kf.n, 36, "filter"),
        PATCH('i', filter.cfg.master_mount, 3, "filter"),
        PATCH('d', filter.kf.P[0], -1.0, "filter"),
        PATCH('i', skipped, -2, "skip"),
        PATCH('i', started, 4, "flag"),
        PATCH('i', match_attitude, 2, "flag"),
    };
    const StateRegion regions[] = {
        REGION(filter.cfg), REGION_HEAD(filter, offsetof(gf_ins_filter, kf) + 64),
        REGION(filter.nav), REGION(filter.transfer), REGION(filter.idx_tmount), REGION(skipped),
        REGION(started), REGION(last_master_t_s)};
    check_damaged_states(c, mid * H_S, H_S, ta_step, N - mid, r, 10, patches,
                         sizeof patches / sizeof patches[0], regions,
                         sizeof regions / sizeof regions[0], 300);
    fmi2FreeInstance(c);
}

static void expect_refused(const char *what, const char *param, const double *value, int n,
                           const char *logged)
{
    fmi2Component c = open_ready(GF_INS_EKF);
    set_vec(c, param, value, n);
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error, "%s accepted", what);
    CHECK(strstr(g_log, logged) != NULL, "%s: log: %s", what, g_log);
    fmi2FreeInstance(c);
}

static void test_refusals(void)
{
    const double pitch[3] = {0.0, 2.0, 0.0}, vel_std[3] = {0.01, 0.0, 0.01};
    expect_refused("mounting pitch", "master_mount_rad", pitch, 3,
                   "parameter master_mount_rad = [0, 2, 0] rad refused: must be finite");
    expect_refused("master std", "master_vel_std", vel_std, 3,
                   "master_vel_std, master_att_std and master_pos_std must be finite and > 0");
    fmi2Component c = open_ready(GF_INS_EKF);
    set_int(c, "match_attitude", 2);
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error && strstr(g_log, "match_attitude = 2"),
          "match_attitude = 2: %s", g_log);
    fmi2FreeInstance(c);

    /* an epoch valid after the sample it came with; then a non-finite master input:
     * errors, the outputs keep the last good sample */
    c = open_ready(GF_INS_EKF);
    fmi2ExitInitializationMode(c);
    fmu_steps(c, 0, 41, g_fmu, g_ist);
    fmu_inputs(c, 50);
    set_real(c, "master_time_s", 41 * H_S + 0.003);
    g_log[0] = '\0';
    CHECK(fmi2DoStep(c, 41 * H_S, H_S, fmi2True) == fmi2Error, "future epoch accepted");
    CHECK(strstr(g_log, "after the IMU sample it was delivered with") != NULL, "log: %s", g_log);
    const fmi2ValueReference r = vr("lat");
    double lat = 0.0;
    fmi2GetReal(c, &r, 1, &lat);
    CHECK(lat == g_fmu[40][7], "outputs kept");
    fmi2FreeInstance(c);

    c = open_ready(GF_INS_EKF);
    fmi2ExitInitializationMode(c);
    fmu_steps(c, 0, 50, g_fmu, g_ist);
    fmu_inputs(c, 50);
    set_real(c, "master_lat", NAN);
    g_log[0] = '\0';
    CHECK(fmi2DoStep(c, 50 * H_S, H_S, fmi2True) == fmi2Error, "NaN master accepted");
    CHECK(strstr(g_log, "must be finite") != NULL, "log: %s", g_log);
    fmi2FreeInstance(c);
}

int main(void)
{
    turn_drive(g_truth, N, H_S);
    test_equals_core(GF_INS_EKF);
    test_equals_core(GF_INS_UKF);
    test_states();
    test_damaged_states();
    test_refusals();
    TEST_MAIN_END();
}
