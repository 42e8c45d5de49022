/* test_fmu_ins_gnss.c — the integrated-navigator FMU model (fmu/models/ins_gnss) through
 * the FMI 2.0 glue, linked into this executable so that it runs under
 * ASan/UBSan/LeakSanitizer (tests/test_fmu_ins_gnss.py covers the shipped FMUs through
 * fmpy, FMI 2.0 and 3.0, against the Python batch API). Sensor data: the vehicle truth
 * of turn_drive.h (15 s: rest, start, a 180 deg turn) with GNSS at 1 Hz on samples, a GNSS
 * epoch delivered 0.2 s late every 100 samples (stale), barometer and odometer at 10 Hz
 * valid inside the sample intervals (and a barometer sample delivered with each GNSS epoch,
 * valid before it: the FMU must sort what one step brings); all 25 states (scale factors, barometer bias,
 * odometer scale and boresight) and NHC on, every parameter a value of its own.
 *   1. EKF and UKF: the FMU equals gf_ins_init + gf_ins_step called directly with the
 *      same P0 and the same measurements, bit for bit (navigation, std, sensor errors,
 *      per-kind NIS and status);
 *   2. skip_steps = 2: the filter started at t_2 from the state given equals the core
 *      started there;
 *   3. FMU state mid-run: set back and replay, and serialize into a fresh instance: the
 *      same outputs; the state-validation function accepts the live state and refuses
 *      corrupted n_states, idx_*, kf.n and configuration enumerations;
 *   4. refused: bad parameters (logged naming them), a measurement valid after the sample
 *      it came with, a non-finite GNSS input (outputs kept). */
#include <math.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_instance.h"
#include "fmu2_test.h"
#include "base/gf_math.h"
#include "est/gf_ins_gnss.h"
#include "nav/gf_earth.h"
#include "gf_test.h"
#include "sim/gf_vehicle.h"
#include "turn_drive.h"

#define H_S 0.01
enum { N = 1500 };

static gf_vehicle_sample g_truth[N];

/* ---- the measurements delivered with sample k (the same for the FMU and the core) ---- */

typedef struct Delivery {
    int gnss, baro, odo;            /* 1: delivered with this sample */
    int gnss_from;                  /* truth row of the GNSS epoch */
    double gnss_t, baro_t, odo_t;   /* times of validity */
} Delivery;

static Delivery delivery(int k)
{
    Delivery d = {0, 0, 0, k, 0.0, 0.0, 0.0};
    if (k > 0 && k % 100 == 0) {            /* on the sample */
        d.gnss = 1;
        d.gnss_t = k * H_S;
    } else if (k > 100 && k % 100 == 50) {  /* 0.2 s late: stale */
        d.gnss = 1;
        d.gnss_from = k - 20;
        d.gnss_t = (k - 20) * H_S;
    }
    if (k > 0 && k % 10 == 3) {
        d.baro = 1;
        d.baro_t = k * H_S - 0.004;
    }
    if (k > 0 && k % 100 == 0) {            /* with the GNSS epoch, valid before it */
        d.baro = 1;
        d.baro_t = k * H_S - 0.006;
    }
    if (k > 0 && k % 10 == 7) {
        d.odo = 1;
        d.odo_t = k * H_S - 0.006;
    }
    return d;
}

/* every axis its own std: an east/north swap of an input cannot hide */
static const double kPosStd[3] = {0.5, 0.6, 1.0}, kVelStd[3] = {0.05, 0.06, 0.1};
#define BARO_BIAS_M 0.3
#define BARO_STD_M 0.5
#define ODO_STD_M_S 0.05

static const double kGnssLever[3] = {0.31, 1.27, 1.61};

/* the antenna at kGnssLever of truth row x: position (lat, lon, h) p + C l and velocity
 * v + C (w_eb x l), w_eb = w_ib - C^T w_ie (the measurement model of gf_ins_gnss.h, the
 * truth's own rates) */
static void antenna(const gf_vehicle_sample *x, double pos[3], double vel[3])
{
    double cl[3], w_ie_b[3], w_eb[3], wl[3], cwl[3];
    gf_q_rotate(x->q_bn, kGnssLever, cl);
    gf_earth e;
    CHECK(gf_earth_update(&e, x->lat_rad, x->h_m, NULL, 1.0) == GF_OK, "earth");
    pos[0] = x->lat_rad + cl[1] / (e.R_M_m + x->h_m);
    pos[1] = x->lon_rad + cl[0] / ((e.R_N_m + x->h_m) * e.cos_lat);
    pos[2] = x->h_m + cl[2];
    const double w_ie[3] = {0.0, GF_WGS84_OMEGA_IE_RAD_S * cos(x->lat_rad),
                            GF_WGS84_OMEGA_IE_RAD_S * sin(x->lat_rad)};
    const double qc[4] = {x->q_bn[0], -x->q_bn[1], -x->q_bn[2], -x->q_bn[3]};
    gf_q_rotate(qc, w_ie, w_ie_b);
    gf_v3_sub(x->gyro_rad_s, w_ie_b, w_eb);
    gf_v3_cross(w_eb, kGnssLever, wl);
    gf_q_rotate(x->q_bn, wl, cwl);
    gf_v3_add(x->v_n_m_s, cwl, vel);
}

static size_t core_meas(int k, gf_ins_meas *m)
{
    const Delivery d = delivery(k);
    size_t n = 0;
    if (d.gnss) {
        double pos[3], vel[3];
        antenna(&g_truth[d.gnss_from], pos, vel);
        m[n++] = (gf_ins_meas){GF_INS_MEAS_GNSS_POS, d.gnss_t, {pos[0], pos[1], pos[2]},
                               {kPosStd[0], kPosStd[1], kPosStd[2]}, {0, 0, 0}};
        m[n++] = (gf_ins_meas){GF_INS_MEAS_GNSS_VEL, d.gnss_t, {vel[0], vel[1], vel[2]},
                               {kVelStd[0], kVelStd[1], kVelStd[2]}, {0, 0, 0}};
    }
    if (d.baro)
        m[n++] = (gf_ins_meas){GF_INS_MEAS_BARO, d.baro_t, {g_truth[k].h_m + BARO_BIAS_M, 0, 0},
                               {BARO_STD_M, 0, 0}, {0, 0, 0}};
    if (d.odo)
        m[n++] = (gf_ins_meas){GF_INS_MEAS_ODO, d.odo_t, {g_truth[k].speed_m_s, 0, 0},
                               {ODO_STD_M_S, 0, 0}, {0, 0, 0}};
    /* gf_ins_step takes them sorted by time (stable: kinds in the order above at equal
     * times), as the FMU must hand them over */
    for (size_t i = 1; i < n; ++i)
        for (size_t j = i; j > 0 && m[j - 1].t_s > m[j].t_s; --j) {
            const gf_ins_meas x = m[j];
            m[j] = m[j - 1];
            m[j - 1] = x;
        }
    return n;
}

static void fmu_inputs(fmi2Component c, int k)
{
    const Delivery d = delivery(k);
    set_vec(c, "dtheta", g_truth[k].dtheta_rad, 3);
    set_vec(c, "dv", g_truth[k].dv_m_s, 3);
    set_int(c, "gnss_valid", d.gnss);
    set_int(c, "baro_valid", d.baro);
    set_int(c, "odo_valid", d.odo);
    if (d.gnss) {
        double pos[3], vel[3];
        antenna(&g_truth[d.gnss_from], pos, vel);
        set_real(c, "gnss_time_s", d.gnss_t);
        set_real(c, "gnss_lat_rad", pos[0]);
        set_real(c, "gnss_lon_rad", pos[1]);
        set_real(c, "gnss_h_m", pos[2]);
        set_vec(c, "gnss_vel_enu_m_s", vel, 3);
        set_vec(c, "gnss_pos_std_m", kPosStd, 3);
        set_vec(c, "gnss_vel_std_m_s", kVelStd, 3);
    }
    if (d.baro) {
        set_real(c, "baro_time_s", d.baro_t);
        set_real(c, "baro_h_m", g_truth[k].h_m + BARO_BIAS_M);
        set_real(c, "baro_std_m", BARO_STD_M);
    }
    if (d.odo) {
        set_real(c, "odo_time_s", d.odo_t);
        set_real(c, "odo_speed_m_s", g_truth[k].speed_m_s);
        set_real(c, "odo_std_m_s", ODO_STD_M_S);
    }
}

/* ---- configuration: the same numbers to the FMU and to the core ----------------------- */

/* Every parameter below has a value different from every other (every axis of a vector
 * too), so that the FMU reading one parameter into another's place (issue 25: the gyro
 * scale-factor P0 taken from the accelerometer's) changes the run; all 25 states on. */
static const double kStd0Vel[3] = {0.1, 0.11, 0.12}, kStd0Pos[3] = {1.0, 2.0, 3.0};
static const double kStd0Att[3] = {0.01, 0.011, 0.05}, kStd0Bg[3] = {1e-4, 1.1e-4, 1.2e-4};
static const double kStd0Ba[3] = {1e-2, 1.1e-2, 1.2e-2}, kStd0Sg[3] = {3e-4, 3.1e-4, 3.2e-4};
static const double kStd0Sa[3] = {4e-4, 4.1e-4, 4.2e-4}, kStd0Mount[2] = {0.021, 0.023};
static const double kStd0Baro = 1.3, kStd0Odo = 0.014;
static const double kSensors0[GF_INS_N_SENSORS] = {
    1.1e-6, -1.3e-6, 1.7e-6, 2.3e-3, -2.9e-3, 3.1e-3, 1.9e-5, -2.1e-5, 2.7e-5,
    -3.3e-5, 3.4e-5, -4.1e-5, 0.27, 0.0047, 0.0013, -0.0019};
/* the odometer point below the IMU, nearly on its forward axis, and a boresight of less
 * than a milliradian: the truth's forward speed is the odometer's to 1e-3 m/s in the turn
 * and the NHC hold to that (their stds: 0.05 and 0.1 m/s) */
static const double kOdoLever[3] = {1e-3, 2e-3, -0.4};
static const double kOdoMount[2] = {6.1e-4, -8.3e-4};

static void core_config(gf_ins_config *c, int filter)
{
    gf_ins_config_default(c);
    c->filter = filter;
    c->scale_factors = 1;
    c->baro_bias = 1;
    c->odometer_scale = 1;
    c->odometer_mount = 1;
    c->nhc = 1;
    c->gate_probability = 0.9999;
    c->gate_reset_count = 5;          /* the FMU's default (FilterConfig's) */
    c->noise.gyro_arw_rad_sqrt_s = 1e-4;
    c->noise.accel_vrw_m_s_sqrt_s = 1e-3;
    c->noise.gyro_bias_std_rad_s = 1e-5;
    c->noise.gyro_bias_tau_s = 3600.0;
    c->noise.accel_bias_std_m_s2 = 1.1e-3;
    c->noise.accel_bias_tau_s = 3100.0;
    c->noise.gyro_scale_std = 1.3e-3;
    c->noise.gyro_scale_tau_s = 5100.0;
    c->noise.accel_scale_std = 1.7e-3;
    c->noise.accel_scale_tau_s = 4700.0;
    c->noise.baro_bias_std_m = 1.0;
    c->noise.baro_bias_tau_s = 2900.0;
    c->noise.odometer_scale_std = 0.01;
    c->noise.odometer_mount_std_rad = 0.031;
    c->noise.odometer_mount_tau_s = 6100.0;
    memcpy(c->gnss_lever_arm_m, kGnssLever, sizeof kGnssLever);
    memcpy(c->odometer_lever_arm_m, kOdoLever, sizeof kOdoLever);
    memcpy(c->odometer_mount_rad, kOdoMount, sizeof kOdoMount);
}

static fmi2Component open_ready(int filter, int skip)
{
    const gf_vehicle_sample *x0 = &g_truth[skip];
    fmi2Component c = instantiate("ins");
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    set_int(c, "filter", filter);
    set_int(c, "scale_factors", 1);
    set_int(c, "baro_bias", 1);
    set_int(c, "odometer_scale", 1);
    set_int(c, "odometer_mount", 1);
    set_int(c, "nhc", 1);
    set_real(c, "gate_probability", 0.9999);
    set_real(c, "gyro_arw_rad_sqrt_s", 1e-4);
    set_real(c, "accel_vrw_m_s_sqrt_s", 1e-3);
    set_real(c, "gyro_bias_std_rad_s", 1e-5);
    set_real(c, "gyro_bias_tau_s", 3600.0);
    set_real(c, "accel_bias_std_m_s2", 1.1e-3);
    set_real(c, "accel_bias_tau_s", 3100.0);
    set_real(c, "gyro_scale_std", 1.3e-3);
    set_real(c, "gyro_scale_tau_s", 5100.0);
    set_real(c, "accel_scale_std", 1.7e-3);
    set_real(c, "accel_scale_tau_s", 4700.0);
    set_real(c, "baro_bias_std_m", 1.0);
    set_real(c, "baro_bias_tau_s", 2900.0);
    set_real(c, "odometer_scale_std", 0.01);
    set_real(c, "odometer_scale_tau_s", 0.0);
    set_real(c, "odometer_mount_std_rad", 0.031);
    set_real(c, "odometer_mount_tau_s", 6100.0);
    set_vec(c, "gnss_lever_arm_m", kGnssLever, 3);
    set_vec(c, "odometer_lever_arm_m", kOdoLever, 3);
    set_vec(c, "odometer_mount_rad", kOdoMount, 2);
    set_vec(c, "sensors0", kSensors0, GF_INS_N_SENSORS);
    set_vec(c, "q0", x0->q_bn, 4);
    set_vec(c, "v0", x0->v_n_m_s, 3);
    set_real(c, "lat0", x0->lat_rad);
    set_real(c, "lon0", x0->lon_rad);
    set_real(c, "h0", x0->h_m);
    set_vec(c, "std0_vel", kStd0Vel, 3);
    set_vec(c, "std0_pos", kStd0Pos, 3);
    set_vec(c, "std0_att", kStd0Att, 3);
    set_vec(c, "std0_gyro_bias", kStd0Bg, 3);
    set_vec(c, "std0_accel_bias", kStd0Ba, 3);
    set_vec(c, "std0_gyro_scale", kStd0Sg, 3);
    set_vec(c, "std0_accel_scale", kStd0Sa, 3);
    set_vec(c, "std0_odo_mount", kStd0Mount, 2);
    set_real(c, "std0_baro_bias", kStd0Baro);
    set_real(c, "std0_odo_scale", kStd0Odo);
    set_int(c, "skip_steps", skip);
    return c;
}

/* ---- outputs: navigation, std, sensors, time, per-kind NIS (doubles) and status ------- */

enum { O_TIME = 19 + GF_INS_N_SENSORS, O_NIS = O_TIME + 1 };
enum { N_OUT = 4 + 3 + 3 + 9 + GF_INS_N_SENSORS + 1 + 7, N_IOUT = 7 };
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
    *p++ = vr("time_s");
    vrs("nis", 7, p);
    vrs("update_status", 7, ri);
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

/* The core directly from sample k0 (its start): rows k0.. of g_core. */
static void core_run(int filter, int k0)
{
    const gf_vehicle_sample *x0 = &g_truth[k0];
    gf_ins_config cfg;
    core_config(&cfg, filter);
    int32_t n = 0;
    CHECK(gf_ins_state_count(&cfg, &n) == GF_OK && n == 25, "25 states");
    /* P0: the initial std per block, position metres -> (dlat, dlon) with gf_earth */
    static double P0[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    memset(P0, 0, sizeof P0);
    gf_earth e;
    CHECK(gf_earth_update(&e, x0->lat_rad, x0->h_m, NULL, 1.0) == GF_OK, "earth");
    const double dlat = kStd0Pos[1] / (e.R_M_m + x0->h_m);
    const double dlon = kStd0Pos[0] / ((e.R_N_m + x0->h_m) * e.cos_lat);
    /* the state order of gf_ins_gnss.h: dv, dp, phi, dbg, dba, dsg, dsa, baro, odo, mount */
    const double sd[25] = {kStd0Vel[0], kStd0Vel[1], kStd0Vel[2], dlat, dlon, kStd0Pos[2],
                           kStd0Att[0], kStd0Att[1], kStd0Att[2], kStd0Bg[0], kStd0Bg[1],
                           kStd0Bg[2], kStd0Ba[0], kStd0Ba[1], kStd0Ba[2], kStd0Sg[0],
                           kStd0Sg[1], kStd0Sg[2], kStd0Sa[0], kStd0Sa[1], kStd0Sa[2],
                           kStd0Baro, kStd0Odo, kStd0Mount[0], kStd0Mount[1]};
    for (int i = 0; i < n; ++i)
        P0[i * n + i] = sd[i] * sd[i];
    static gf_ins_filter f;
    int32_t bad = -1;
    CHECK(gf_ins_init(&f, &cfg, k0 * H_S, x0->q_bn, x0->v_n_m_s, x0->lat_rad, x0->lon_rad,
                      x0->h_m, kSensors0, P0, &bad) == GF_OK && bad == 0, "core init");
    double nis[7];
    int status[7];
    for (int i = 0; i < 7; ++i) {
        nis[i] = NAN;
        status[i] = -1;
    }
    for (int k = k0; k < N; ++k) {
        if (k > k0) { /* the sample at the start carries no increment */
            gf_ins_meas m[4];
            const size_t nm = core_meas(k, m);
            gf_ins_innovation entries[16];
            gf_ins_log log = {16, 0, 0, entries};
            CHECK(gf_ins_step(&f, k * H_S, g_truth[k].dtheta_rad, g_truth[k].dv_m_s, nm, m, NULL,
                              &log) == GF_OK, "core step %d", k);
            for (size_t i = 0; i < log.count; ++i) {
                nis[entries[i].type - 1] = entries[i].nis;
                status[entries[i].type - 1] = entries[i].status;
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
        o[O_TIME] = f.t_s;
        memcpy(o + O_NIS, nis, 7 * sizeof *o);
        memcpy(g_icore[k], status, sizeof status);
    }
}

static void test_equals_core(int filter, int skip)
{
    fmi2Component c = open_ready(filter, skip);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", g_log);
    fmu_steps(c, 0, N, g_fmu, g_ist);
    fmi2FreeInstance(c);
    core_run(filter, skip);
    int first_bad = -1;
    for (int k = skip; k < N && first_bad < 0; ++k)
        if (memcmp(g_fmu[k], g_core[k], sizeof g_fmu[k]) != 0 ||
            memcmp(g_ist[k], g_icore[k], sizeof g_ist[k]) != 0)
            first_bad = k;
    CHECK(first_bad < 0, "filter %d, skip_steps = %d: FMU differs from the core at step %d",
          filter, skip, first_bad);
    /* every kind was used: GNSS accepted, the late epoch stale, baro, odometer, NHC */
    CHECK(g_ist[N - 1][0] >= 0 && g_ist[N - 1][2] == GF_INS_ACCEPTED &&
          g_ist[N - 1][3] == GF_INS_ACCEPTED && g_ist[N - 1][4] >= 0, "kinds used");
    CHECK(g_ist[1450][0] == GF_INS_REJECTED_STALE && isnan(g_fmu[1450][O_NIS]), "stale epoch");
    CHECK(g_ist[1400][0] == GF_INS_ACCEPTED && g_fmu[1400][O_NIS] > 0.0, "GNSS epoch");
    /* and it navigates: exact data keep it within centimetres of the truth */
    CHECK(fabs(g_fmu[N - 1][7] - g_truth[N - 1].lat_rad) * 6.4e6 < 0.05, "navigates");
}

static void test_states(void)
{
    fmi2Component c = open_ready(GF_INS_UKF, 0);
    fmi2ExitInitializationMode(c);
    fmu_steps(c, 0, N / 2, g_fmu, g_ist);
    fmi2FMUstate st = NULL;
    CHECK(fmi2GetFMUstate(c, &st) == fmi2OK, "get state");
    const ModelData *live = &((FmuInstance *)c)->s.data;
    CHECK(ins_gnss_state_problem(live) == NULL, "live state valid: %s", ins_gnss_state_problem(live));
    /* corrupted copies are refused */
    static ModelData bad;
    const char *why;
    bad = *live;
    bad.filter.n_states = 40;
    CHECK((why = ins_gnss_state_problem(&bad)) != NULL && strstr(why, "n_states"), "n_states");
    bad = *live;
    bad.filter.idx_baro = 22;
    CHECK((why = ins_gnss_state_problem(&bad)) != NULL && strstr(why, "idx_"), "idx_baro");
    bad = *live;
    bad.filter.kf.n = 36;
    CHECK((why = ins_gnss_state_problem(&bad)) != NULL && strstr(why, "kf.n"), "kf.n");
    bad = *live;
    bad.filter.cfg.filter = 7;
    CHECK(ins_gnss_state_problem(&bad) != NULL, "cfg.filter");
    bad = *live;
    bad.filter.nav.cfg.input = 1;
    CHECK(ins_gnss_state_problem(&bad) != NULL, "nav.cfg.input");
    bad = *live;
    bad.skipped = 3;
    CHECK(ins_gnss_state_problem(&bad) != NULL, "skipped");
    bad = *live;
    bad.align_travel = 2;
    CHECK(ins_gnss_state_problem(&bad) != NULL, "align_travel not a flag");
    bad = *live;
    bad.align_heading = 5;
    CHECK((why = ins_gnss_state_problem(&bad)) != NULL && strstr(why, "align_heading"), "align_heading");
    bad = *live;   /* the travel phase flag without the alignment from the travel */
    bad.align_travel = 1;
    CHECK((why = ins_gnss_state_problem(&bad)) != NULL && strstr(why, "align_travel"), "align_travel");
    bad.aligning = 1;
    bad.align_heading = 1;
    CHECK(ins_gnss_state_problem(&bad) == NULL, "travel phase state valid: %s", ins_gnss_state_problem(&bad));

    fmu_steps(c, N / 2, N, g_fmu, g_ist);
    CHECK(fmi2SetFMUstate(c, st) == fmi2OK, "set state");
    fmu_steps(c, N / 2, N, g_fmu2, g_ist2);
    CHECK(memcmp(g_fmu[N / 2], g_fmu2[N / 2], sizeof g_fmu[0] * (N - N / 2)) == 0 &&
          memcmp(g_ist[N / 2], g_ist2[N / 2], sizeof g_ist[0] * (N - N / 2)) == 0, "replay");
    size_t size = 0;
    fmi2SerializedFMUstateSize(c, st, &size);
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, st, bytes, size) == fmi2OK, "serialize");
    fmi2FreeFMUstate(c, &st);
    fmi2FreeInstance(c);
    fmi2Component d = open_ready(GF_INS_EKF, 0); /* another filter: the state carries its own */
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

static void expect_refused(const char *what, const char *param, double value, int is_int,
                           const char *logged)
{
    fmi2Component c = open_ready(GF_INS_EKF, 0);
    if (is_int)
        set_int(c, param, (int)value);
    else
        set_real(c, param, value);
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error, "%s accepted", what);
    CHECK(strstr(g_log, logged) != NULL, "%s: log: %s", what, g_log);
    fmi2FreeInstance(c);
}

static void test_refusals(void)
{
    expect_refused("filter", "filter", 5, 1, "parameter filter = 5 refused: must be 0 (ekf) or 1 (ukf)");
    expect_refused("gate", "gate_probability", 1.0, 0,
                   "parameter gate_probability = 1 refused: must be 0 (no gate) or in (0, 1)");
    expect_refused("gate_reset_count", "gate_reset_count", -1, 1,
                   "parameter gate_reset_count = -1 refused: must be an integer >= 0");
    expect_refused("max_latency_s", "max_latency_s", -0.1, 0,
                   "parameter max_latency_s = -0.1 s refused: must be finite and >= 0");
    expect_refused("noise", "accel_bias_tau_s", -2.0, 0,
                   "parameter accel_bias_tau_s = -2 s refused: must be finite and >= 0");
    expect_refused("std0_pos", "std0_pos[2]", 0.0, 0, "parameter std0_pos = [1, 0, 3] m");
    expect_refused("std0_odo_scale", "std0_odo_scale", NAN, 0, "std0_odo_scale = nan");
    expect_refused("lat0", "lat0", 1.56, 0, "parameter lat0 = 1.56 rad");
    expect_refused("skip_steps", "skip_steps", -1, 1, "skip_steps = -1 must be >= 0");
    expect_refused("odometer_mount_rad", "odometer_mount_rad[2]", 2.0, 0,
                   "parameter odometer_mount_rad = [0.00061, 2] rad refused: must be finite and inside");

    /* a measurement valid after the sample it came with; then a non-finite GNSS input:
     * errors, the outputs keep the last good sample */
    fmi2Component c = open_ready(GF_INS_EKF, 0);
    fmi2ExitInitializationMode(c);
    fmu_steps(c, 0, 40, g_fmu, g_ist);
    set_int(c, "baro_valid", 1);
    set_real(c, "baro_time_s", 40 * H_S + 0.003);
    set_real(c, "baro_h_m", 100.0);
    set_real(c, "baro_std_m", 1.0);
    g_log[0] = '\0';
    CHECK(fmi2DoStep(c, 40 * H_S, H_S, fmi2True) == fmi2Error, "future measurement accepted");
    CHECK(strstr(g_log, "baro measurement valid at baro_time_s = 0.403 s, after the IMU sample"),
          "log: %s", g_log);
    const fmi2ValueReference r = vr("lat");
    double lat = 0.0;
    fmi2GetReal(c, &r, 1, &lat);
    CHECK(lat == g_fmu[39][7], "outputs kept");
    fmi2FreeInstance(c);

    c = open_ready(GF_INS_EKF, 0);
    fmi2ExitInitializationMode(c);
    fmu_steps(c, 0, 40, g_fmu, g_ist);
    set_int(c, "gnss_valid", 1);
    set_real(c, "gnss_time_s", 40 * H_S);
    set_real(c, "gnss_lat_rad", NAN);
    g_log[0] = '\0';
    CHECK(fmi2DoStep(c, 40 * H_S, H_S, fmi2True) == fmi2Error, "NaN GNSS accepted");
    CHECK(strstr(g_log, "gnss_lat_rad") != NULL, "log: %s", g_log);
    fmi2FreeInstance(c);
}

/* A refused step of the alignment phase at rest changes no model data: a NaN IMU sample
 * with a GNSS epoch delivered beside it (the epoch used to be recorded as stale first). */
static void test_alignment_refusal(void)
{
    fmi2Component c = open_ready(GF_INS_EKF, 0);
    set_real(c, "align_time", 1.0);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "alignment phase of 1 s accepted");
    for (int k = 0; k < 20; ++k) {
        set_vec(c, "dtheta", g_truth[k].dtheta_rad, 3);
        set_vec(c, "dv", g_truth[k].dv_m_s, 3);
        CHECK(fmi2DoStep(c, k * H_S, H_S, fmi2True) == fmi2OK, "aligning step %d", k);
    }
    static ModelData before;
    const ModelData *live = &((FmuInstance *)c)->s.data;
    const double nan3[3] = {NAN, NAN, NAN}, std3[3] = {1.0, 1.0, 2.0};
    set_vec(c, "dtheta", nan3, 3);
    set_int(c, "gnss_valid", 1);
    set_real(c, "gnss_time_s", 20 * H_S);
    set_real(c, "gnss_lat_rad", g_truth[20].lat_rad);
    set_real(c, "gnss_lon_rad", g_truth[20].lon_rad);
    set_real(c, "gnss_h_m", g_truth[20].h_m);
    set_vec(c, "gnss_vel_enu_m_s", g_truth[20].v_n_m_s, 3);
    set_vec(c, "gnss_pos_std_m", std3, 3);
    set_vec(c, "gnss_vel_std_m_s", std3, 3);
    memcpy(&before, live, sizeof before);
    g_log[0] = '\0';
    CHECK(fmi2DoStep(c, 20 * H_S, H_S, fmi2True) == fmi2Error, "NaN IMU sample while aligning accepted");
    CHECK(strstr(g_log, "NaN or Inf (alignment phase)") != NULL, "log: %s", g_log);
    CHECK(memcmp(&before, live, sizeof before) == 0, "the refused step changed no model data");
    fmi2FreeInstance(c);
}

/* ---- damaged and crafted states (fmu2_test.h) ------------------------------------------ */

static fmi2Status ins_step(fmi2Component c, double t_s)
{
    const int k = (int)(t_s / H_S + 0.5);
    fmu_inputs(c, k);
    return fmi2DoStep(c, t_s, H_S, fmi2True);
}

/* Covariances that are finite and symmetric, word for word, yet not covariances: two
 * (three with a diagonal) words overwritten consistently and the CRC recomputed, as a
 * crafted file would be. Each is refused; an untouched state goes back in. */
static void test_crafted_covariances(fmi2Component c)
{
    fmi2FMUstate good = NULL;
    size_t size = 0;
    CHECK(fmi2GetFMUstate(c, &good) == fmi2OK && fmi2SerializedFMUstateSize(c, good, &size) == fmi2OK,
          "state");
    uint8_t *ok = malloc(size), *bytes = malloc(size);
    CHECK(ok && bytes && fmi2SerializeFMUstate(c, good, (fmi2Byte *)ok, size) == fmi2OK, "serialize");
    const size_t at = offsetof(ModelData, filter.kf.P);
    const ModelData *d = (const ModelData *)snapshot_model_data(ok, size);
    const int n = d->filter.n_states;
    CHECK(n >= 15, "n_states %d", n);
    double P[GF_KF_MAX_N * GF_KF_MAX_N];
    for (int kase = 0; kase < 3; ++kase) {
        memcpy(bytes, ok, size);
        memcpy(P, d->filter.kf.P, sizeof P);
        const char *what = "";
        if (kase == 0) {        /* correlation 2 between two states: indefinite */
            P[1] = P[n] = 2.0 * sqrt(P[0] * P[n + 1]);
            what = "P[0][1] = P[1][0] = 2 sqrt(P00 P11)";
        } else if (kase == 1) { /* three words: a variance made 1e-12 of itself, its correlations kept */
            P[1] = P[n] = 0.9 * sqrt(P[0] * P[n + 1]);
            P[0] *= 1e-12;
            what = "P[0][0] *= 1e-12 with P[0][1] = P[1][0] at correlation 0.9";
        } else {                /* a pair off by more than the engine's symmetry tolerance */
            P[2 * n + 5] = P[5 * n + 2] + 1e-6 * sqrt(P[2 * n + 2] * P[5 * n + 5]);
            what = "P[2][5] != P[5][2] by 1e-6 of sqrt(P22 P55)";
        }
        memcpy(snapshot_model_data(bytes, size) + at, P, sizeof P);
        ref_state_fix_crc(bytes, size);
        expect_bytes_refused(c, bytes, size, what, "covariance");
    }
    CHECK(fmi2SetFMUstate(c, good) == fmi2OK, "the good state goes back in");
    fmi2FreeFMUstate(c, &good);
    free(ok);
    free(bytes);
}

/* A state saved in initialization mode (before any output is computed) with an output
 * overwritten and the CRC recomputed: before, the model's checks ran only for an
 * initialized model, so it was accepted and the getters returned update_time = Inf
 * (fuzz_fmu_state, issue 21). Now its outputs must be their start values. */
static void test_crafted_state_before_initialization(void)
{
    fmi2Component c = open_ready(GF_INS_EKF, 0);     /* in initialization mode */
    fmi2FMUstate st = NULL;
    size_t size = 0;
    CHECK(fmi2GetFMUstate(c, &st) == fmi2OK && fmi2SerializedFMUstateSize(c, st, &size) == fmi2OK,
          "state in initialization mode");
    uint8_t *ok = malloc(size), *bytes = malloc(size);
    CHECK(ok && bytes && fmi2SerializeFMUstate(c, st, (fmi2Byte *)ok, size) == fmi2OK, "serialize");
    g_log[0] = '\0';
    fmi2FMUstate back = NULL;
    CHECK(fmi2DeSerializeFMUstate(c, (const fmi2Byte *)ok, size, &back) == fmi2OK,
          "the untouched state is taken: %s", g_log);
    fmi2FreeFMUstate(c, &back);
    const double inf = INFINITY, nan = NAN;
    const struct { size_t at; double v; const char *what; } cases[] = {
        {offsetof(ModelData, update_time_s) + 3 * sizeof(double), inf, "update_time[4] = Inf"},
        {offsetof(ModelData, lat_rad), nan, "lat = NaN"},
        {offsetof(ModelData, std9) + 4 * sizeof(double), 1.0, "std[5] = 1 (finite, not its start value)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        memcpy(bytes, ok, size);
        memcpy(snapshot_model_data(bytes, size) + cases[i].at, &cases[i].v, sizeof(double));
        ref_state_fix_crc(bytes, size);
        expect_bytes_refused(c, bytes, size, cases[i].what, "start value");
    }
    fmi2FreeFMUstate(c, &st);
    free(ok);
    free(bytes);
    fmi2FreeInstance(c);
}

static void test_damaged_states(int filter)
{
    fmi2Component c = open_ready(filter, 0);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", g_log);
    const int mid = N / 2;
    fmu_steps(c, 0, mid, g_fmu, g_ist);
    fmi2ValueReference r[4 + 3 + 3];
    vrs("q", 4, r);
    vrs("v", 3, r + 4);
    r[7] = vr("lat");
    r[8] = vr("lon");
    r[9] = vr("h");
    const StatePatch patches[] = {
        PATCH('i', filter.n_states, 36, "filter"),
        PATCH('i', filter.idx_baro, 40, "filter"),
        PATCH('i', filter.idx_sg, 16, "filter"),
        PATCH('z', filter.kf.n, 36, "filter"),
        PATCH('z', filter.ukf_w.n, 14, "filter"),
        PATCH('i', filter.hist_head, 500, "filter"),
        PATCH('i', filter.hist_count, -1, "filter"),
        PATCH('i', filter.cfg.filter, 3, "filter"),
        PATCH('i', filter.cfg.input, 5, "filter"),
        PATCH('i', filter.nav.cfg.vertical, 1, "filter"),
        PATCH('d', filter.nav.q_bn[0], 3.0, "filter"),
        PATCH('d', filter.kf.P[0], -1.0, "filter"),
        /* issue 21: the floats of a crafted state with a valid CRC (before: accepted, and
         * a NaN covariance entry stepped to a NaN standard deviation) */
        PATCH('d', filter.kf.P[1], NAN, "filter"),            /* off the diagonal */
        PATCH('d', filter.kf.P[1], 1e3, "filter"),            /* asymmetric (and indefinite) */
        PATCH('d', filter.nav.h_m, 1e300, "filter"),          /* outside the Earth model */
        PATCH('d', filter.ukf_w.gamma, 2.0, "filter"),        /* not the configuration's */
        PATCH('d', filter.std9[4], NAN, "filter"),
        PATCH('d', filter.inv_scale[0], 0.0, "filter"),
        PATCH('d', filter.still_fn, INFINITY, "filter"),
        PATCH('d', filter.acc_T_s, -1.0, "filter"),
        PATCH('d', filter.last_nhc_t_s, NAN, "filter"),
        PATCH('d', std9[4], NAN, "output"),                   /* what a get returns at once */
        PATCH('d', lat_rad, INFINITY, "output"),
        PATCH('d', nis[0], INFINITY, "monitoring"),
        PATCH('d', q0[0], NAN, "parameter"),
        PATCH('d', align_f_sum[0], NAN, "alignment"),
        PATCH('i', skipped, -2, "skip"),
        PATCH('i', started, 4, "started"),
    };
    const StateRegion regions[] = {
        REGION(filter.cfg), REGION_HEAD(filter, offsetof(gf_ins_filter, kf) + 64),
        REGION(filter.nav), REGION(filter.idx_sg), REGION(filter.hist_head),
        REGION(filter.hist_count), REGION(filter.gate_run), REGION(skipped), REGION(started)};
    check_damaged_states(c, mid * H_S, H_S, ins_step, N - mid, r, 10, patches,
                         sizeof patches / sizeof patches[0], regions,
                         sizeof regions / sizeof regions[0], 300);
    test_crafted_covariances(c);
    fmi2FreeInstance(c);
}

int main(void)
{
    turn_drive(g_truth, N, H_S);
    test_damaged_states(GF_INS_EKF);
    test_crafted_state_before_initialization();
    test_equals_core(GF_INS_EKF, 0);
    test_equals_core(GF_INS_UKF, 0);
    test_equals_core(GF_INS_EKF, 2);
    test_states();
    test_refusals();
    test_alignment_refusal();
    TEST_MAIN_END();
}
