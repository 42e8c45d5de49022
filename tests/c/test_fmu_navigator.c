/* test_fmu_navigator.c — a navigator FMU model through the FMI 2.0 glue, linked into
 * this executable so that it runs under ASan/UBSan/LeakSanitizer; compiled twice:
 * NAV_SINS (fmu/models/sins, increments) and otherwise the gyro-free navigator
 * (fmu/models/gfnav, GFNAV_LAYOUT 1 = qin9, sqrt strategy). Sensor data: the vehicle
 * truth source (gf_vehicle) on a short run with a turn.
 *   1. the FMU equals the core called directly (gf_sins_step / gf_gfnav_run with dt = h)
 *      on the same samples, bit for bit;
 *   2. skip_steps = 2: the first two doSteps are ignored and the navigation started at
 *      t_2 from the state given equals the core started there;
 *   3. FMU state mid-run: set back and replay, and serialize into a fresh instance: the
 *      same outputs;
 *   4. skip_steps < 0 is refused with a logged reason;
 *   5. damaged and crafted states (check_damaged_states in fmu2_test.h): one flipped bit
 *      is refused by the CRC-32; every field that sizes a copy, indexes an array or
 *      selects a branch, set out of range in a crafted state (CRC recomputed) or in a
 *      state object handed to setFMUState, is refused with a reason naming it; random
 *      bytes in the live structs never make a step read or write out of bounds (ASan);
 *      afterwards the instance continues exactly as before. The SINS model runs with
 *      IMU compensation and a (pass-through) low-pass on, the gyro-free one with the
 *      fused strategy, so that those structs are live. */
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_instance.h"
#include "fmu2_test.h"
#include "base/gf_math.h"
#include "gyrofree/gf9.h"
#include "gyrofree/gf_array.h"
#include "gyrofree/gf_array_solver.h"
#include "gyrofree/gf_gfins.h"
#include "gyrofree/gf_gfnav.h"
#include "gf_test.h"
#include "sim/gf_vehicle.h"
#include "turn_drive.h"

#define H_S 0.01
enum { N = 1500 };   /* 15 s: 2 s rest, start to 15 m/s, a 180 deg turn in 6 s */

static gf_vehicle_sample g_truth[N];
static double g_A[N][9];
static void make_data(void)
{
    turn_drive(g_truth, N, H_S);
    gf_array_geometry g;
    gf9_geometry(0.1, &g);
    for (int k = 0; k < N; ++k)
        gf_array_forward(&g, 1, g_truth[k].accel_m_s2, g_truth[k].gyro_rad_s,
                         g_truth[k].gyro_dot_rad_s2, g_A[k], NULL);
}

/* Outputs read after each step: q, v, lat, lon. */
enum { N_OUT = 9 };
static double g_fmu[N][N_OUT], g_fmu2[N][N_OUT], g_core[N][N_OUT];

static fmi2Component open_ready(int skip)
{
    const gf_vehicle_sample *x0 = &g_truth[skip];
    fmi2Component c = instantiate("nav");
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    set_vec(c, "q0", x0->q_bn, 4);
    set_vec(c, "v0", x0->v_n_m_s, 3);
    set_real(c, "lat0", x0->lat_rad);
    set_real(c, "lon0", x0->lon_rad);
    set_real(c, "h0", x0->h_m);
    set_int(c, "vertical_mode", 1);
    set_real(c, "hold_height", 100.0);
    set_int(c, "skip_steps", skip);
#ifndef NAV_SINS
    set_vec(c, "omega_init", x0->gyro_rad_s, 3);
#endif
    return c;
}

static void output_vrs(fmi2ValueReference r[N_OUT])
{
    vrs("q", 4, r);
    vrs("v", 3, r + 4);
    r[7] = vr("lat");
    r[8] = vr("lon");
}

/* Sets the inputs of sample k and steps from its time. */
static fmi2Status nav_step_k(fmi2Component c, int k)
{
#ifdef NAV_SINS
    set_vec(c, "dtheta", g_truth[k].dtheta_rad, 3);
    set_vec(c, "dv", g_truth[k].dv_m_s, 3);
#else
    set_vec(c, "A", g_A[k], 9);
#endif
    return fmi2DoStep(c, k * H_S, H_S, fmi2True);
}

/* The same at time t_s (a StateStepFn of fmu2_test.h). */
static fmi2Status nav_step(fmi2Component c, double t_s)
{
    const int k = (int)lround(t_s / H_S);
    return k >= 0 && k < N ? nav_step_k(c, k) : fmi2Error;
}

static void fmu_steps(fmi2Component c, int k0, int k1, double out[][N_OUT])
{
    fmi2ValueReference r[N_OUT];
    output_vrs(r);
    for (int k = k0; k < k1; ++k) {
        CHECK(nav_step_k(c, k) == fmi2OK, "doStep %d: %s", k, g_log);
        fmi2GetReal(c, r, N_OUT, out[k]);
    }
}

/* The core directly from sample k0 (its initial state): rows k0.. of g_core. */
static void core_run(int k0)
{
    const gf_vehicle_sample *x0 = &g_truth[k0];
#ifdef NAV_SINS
    gf_sins_config cfg;
    gf_sins_config_default(&cfg);
    cfg.vertical = GF_SINS_VERTICAL_HOLD;
    cfg.hold_height_m = 100.0;
    gf_sins_state s;
    CHECK(gf_sins_init(&s, &cfg, x0->q_bn, x0->v_n_m_s, x0->lat_rad, x0->lon_rad, x0->h_m,
                       k0 * H_S) == GF_OK, "sins init");
    for (int k = k0; k < N; ++k) {
        if (k > k0) /* the sample at the start carries no increment */
            CHECK(gf_sins_step(&s, g_truth[k].dtheta_rad, g_truth[k].dv_m_s, H_S, NAN) == GF_OK,
                  "sins step");
        memcpy(g_core[k], s.q_bn, 4 * sizeof(double));
        memcpy(g_core[k] + 4, s.v_n_m_s, 3 * sizeof(double));
        g_core[k][7] = s.lat_rad;
        g_core[k][8] = s.lon_rad;
    }
#else
    gf_array_geometry g;
    gf9_geometry(0.1, &g);
    gf_rate_config rc;
    gf_rate_config_default(&rc);
    rc.strategy = GF_RATE_SQRT;
    gf_sins_config sc;
    gf_sins_config_default(&sc);
    sc.input = GF_SINS_INPUT_RATES;
    sc.vertical = GF_SINS_VERTICAL_HOLD;
    sc.hold_height_m = 100.0;
    gf_gfnav_state s;
    CHECK(gf_gfnav_init(&s, &g, &rc, x0->gyro_rad_s, &sc, x0->q_bn, x0->v_n_m_s, x0->lat_rad,
                        x0->lon_rad, x0->h_m, k0 * H_S, NULL) == GF_OK, "gfnav init");
    static double q[N][4], v[N][3], pos[N][3];
    CHECK(gf_gfnav_run(&s, (size_t)(N - k0), g_A[k0], H_S, NULL, q[0], v[0], pos[0], NULL, NULL,
                       NULL, NULL) == GF_OK, "gfnav run");
    for (int k = k0; k < N; ++k) {
        memcpy(g_core[k], q[k - k0], 4 * sizeof(double));
        memcpy(g_core[k] + 4, v[k - k0], 3 * sizeof(double));
        g_core[k][7] = pos[k - k0][0];
        g_core[k][8] = pos[k - k0][1];
    }
#endif
}

static void test_equals_core(int skip)
{
    fmi2Component c = open_ready(skip);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", g_log);
    fmu_steps(c, 0, N, g_fmu);
    fmi2FreeInstance(c);
    core_run(skip);
    int first_bad = -1;
    for (int k = skip; k < N && first_bad < 0; ++k)
        if (memcmp(g_fmu[k], g_core[k], sizeof g_fmu[k]) != 0)
            first_bad = k;
    CHECK(first_bad < 0, "skip_steps = %d: FMU differs from the core at step %d", skip, first_bad);
    /* and it navigates: the exact data keep it on the truth */
    CHECK(fabs(g_fmu[N - 1][7] - g_truth[N - 1].lat_rad) * 6.4e6 < 0.05, "navigates");
}

static void test_states(void)
{
    fmi2Component c = open_ready(0);
    fmi2ExitInitializationMode(c);
    fmu_steps(c, 0, N / 2, g_fmu);
    fmi2FMUstate st = NULL;
    CHECK(fmi2GetFMUstate(c, &st) == fmi2OK, "get state");
    fmu_steps(c, N / 2, N, g_fmu);
    CHECK(fmi2SetFMUstate(c, st) == fmi2OK, "set state");
    fmu_steps(c, N / 2, N, g_fmu2);
    CHECK(memcmp(g_fmu[N / 2], g_fmu2[N / 2], sizeof g_fmu[0] * (N - N / 2)) == 0, "replay");
    size_t size = 0;
    fmi2SerializedFMUstateSize(c, st, &size);
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, st, bytes, size) == fmi2OK, "serialize");
    fmi2FreeFMUstate(c, &st);
    fmi2FreeInstance(c);
    fmi2Component d = open_ready(0);
    fmi2ExitInitializationMode(d);
    fmi2FMUstate st2 = NULL;
    CHECK(fmi2DeSerializeFMUstate(d, bytes, size, &st2) == fmi2OK, "deserialize");
    CHECK(fmi2SetFMUstate(d, st2) == fmi2OK, "set deserialized");
    memset(g_fmu2, 0, sizeof g_fmu2);
    fmu_steps(d, N / 2, N, g_fmu2);
    CHECK(memcmp(g_fmu[N / 2], g_fmu2[N / 2], sizeof g_fmu[0] * (N - N / 2)) == 0,
          "replay in a fresh instance");
    fmi2FreeFMUstate(d, &st2);
    fmi2FreeInstance(d);
    free(bytes);
}

static void test_bad_skip(void)
{
    fmi2Component c = open_ready(0);
    set_int(c, "skip_steps", -1);
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error, "skip_steps = -1 accepted");
    CHECK(strstr(g_log, "skip_steps") != NULL, "log: %s", g_log);
    fmi2FreeInstance(c);
}

static void test_damaged_states(void)
{
    fmi2Component c = open_ready(0);
#ifdef NAV_SINS
    const double pass_through[6] = {1, 0, 0, 1, 0, 0};
    set_int(c, "imu_comp", 1);
    set_int(c, "lowpass_sections", 1);
    set_vec(c, "lowpass_sos", pass_through, 6);
    const StatePatch patches[] = {
        PATCH('i', lowpass_sections, 1000, "lowpass_sections"),
        PATCH('i', lowpass_sections, -1, "lowpass_sections"),
        PATCH('z', lowpass.n_channels, 1e6, "low-pass"),
        PATCH('z', lowpass.n_sections, 0, "low-pass"),
        PATCH('d', lowpass.sos[5], 1.5, "low-pass"),
        PATCH('i', imu_comp, 2, "imu_comp"),
        PATCH('i', imu.temp_order, 99, "IMU error"),
        PATCH('i', nav.cfg.input, 7, "navigation state"),
        PATCH('i', nav.cfg.vertical, -1, "navigation state"),
        PATCH('d', nav.q_bn[0], 5.0, "navigation state"),
        PATCH('d', nav.lat_rad, 1.5707963, "navigation state"),
        PATCH('i', skipped, -3, "skip"),
        PATCH('i', started, 7, "started"),
        PATCH('d', previous_step_s, NAN, "previous_step"),
        /* issue 21: the outputs a restored state carries, a height outside the Earth model */
        PATCH('d', lat_rad, NAN, "output"),
        PATCH('d', euler_rad[2], INFINITY, "output"),
        PATCH('d', nav.h_m, 1e300, "navigation state"),
        PATCH('d', q0[0], NAN, "parameter"),
    };
    const StateRegion regions[] = {
        REGION(nav.cfg), REGION(nav), REGION(imu), REGION_HEAD(lowpass, 16 + 6 * 8),
        REGION(lowpass_sections), REGION(imu_comp), REGION(skip_steps), REGION(skipped),
        REGION(started), REGION(previous_step_s)};
#else
    set_int(c, "strategy", 3);
    const StatePatch patches[] = {
        PATCH('z', nav.rate.solver.n_sensors, 1000, "rate solver"),
        PATCH('z', nav.rate.solver.n_sensors, 12, "sensor count"),
        PATCH('z', nav.rate.solver.n_est, 13, "rate solver"),
        PATCH('z', nav.rate.solver.n_obs, 7, "rate solver"),
        PATCH('z', nav.rate.solver.n_conf, 5, "rate solver"),
        PATCH('i', nav.rate.cfg.strategy, 4, "rate solver"),
        PATCH('i', nav.rate.n_w_meas, 12, "rate solver"),
        PATCH('z', nav.rate.kf.n, 36, "rate solver"),
        PATCH('d', nav.rate.kf.P[7], NAN, "rate solver"),
        /* issue 21: the fused rate filter's covariance must be one (symmetric, positive
         * definite), and the fixed-frame position is published as `pos` whatever the
         * Earth model (fuzz_fmu_state_gfnav_cube6: a NaN there reached the output) */
        PATCH('d', nav.rate.kf.P[1], 1.0, "rate solver"),
        PATCH('d', nav.nav.flat_pos_m[1], NAN, "navigation state"),
        PATCH('d', nav.nav.h_m, 1e300, "navigation state"),
        PATCH('d', pos_m[1], NAN, "output"),
        PATCH('d', omega_rad_s[0], INFINITY, "output"),
        PATCH('d', lever_arm_m, NAN, "parameter"),
        PATCH('i', nav.nav.cfg.input, 0, "navigation state"),
        PATCH('i', nav.nav.cfg.earth, 2, "navigation state"),
        PATCH('i', skipped, 5, "skip"),
        PATCH('i', started, -1, "started"),
    };
    const StateRegion regions[] = {
        REGION_HEAD(nav.rate.solver, offsetof(gf_array_solver, noise_gain)),
        REGION(nav.rate.cfg), REGION(nav.rate.n_w_meas), REGION_HEAD(nav.rate.kf, 64),
        REGION(nav.nav.cfg), REGION(nav.nav), REGION(skip_steps), REGION(skipped),
        REGION(started), REGION(previous_step_s)};
#endif
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", g_log);
    const int mid = N / 2;
    fmu_steps(c, 0, mid, g_fmu);
    fmi2ValueReference r[N_OUT];
    output_vrs(r);
    check_damaged_states(c, mid * H_S, H_S, nav_step, N - mid, r, N_OUT, patches,
                         sizeof patches / sizeof patches[0], regions,
                         sizeof regions / sizeof regions[0], 1000);
    fmi2FreeInstance(c);
}

int main(void)
{
    make_data();
    test_equals_core(0);
    test_equals_core(2);
    test_states();
    test_bad_skip();
    test_damaged_states();
    TEST_MAIN_END();
}
