/* model.c — the vehicle as an FMU model: FMI-agnostic, calls gf_vehicle (truth),
 * gf_rot (rotation = 1: the IMU on the two-axis mechanism), gf_imu_error (IMU
 * errors), gf_array_forward (accelerometer array) and gf_aiding_sim (GNSS receiver,
 * barometer, odometer).
 *
 * Sampling: after exitInitializationMode the outputs describe the start time (zero
 * increments); doStep(t, h) moves the vehicle to t + h (an absolute time, so a long run
 * keeps no time drift beyond the master's own) and the outputs describe t + h, the
 * increments covering (t, t + h]. Any step size is handled. An aiding epoch (valid at
 * t_v, due at t_v + latency) is delivered in the first step whose end reaches the due
 * time; its values depend on the parameters and the seed only (gf_aiding.h). */
#include <math.h>
#include <string.h>

#include "fmu_model.h"
#include "base/gf_math.h"
#include "gyrofree/gf9.h"
#include "gyrofree/gf_array.h"
#include "gyrofree/gf_layout.h"
#include "model.h"

/* Sensor outputs of a truth sample (IMU with errors and noise if asked; array), computed
 * into *o from d's parameters and generator states; nothing in d changes, so a failed
 * step leaves the model as it was (the caller commits *o). */
typedef struct Sensed {
    double gyro_rad_s[3], accel_m_s2[3], dtheta_rad[3], dv_m_s[3], A_m_s2[VEHICLE_ARRAY_MAX];
    double true_w[3];
    gf_imu_noise_state imu_noise;
    gf_rng array_rng;
} Sensed;

/* imu (12, may be NULL: the body's): the IMU's true w, f at the sample and dtheta, dv over
 * the step (the rotating IMU's, from gf_rot_vehicle_step). The angular acceleration of
 * lever arms across the sensing axes (gf_imu_error.h): over the step, exactly its mean
 * (w(t + h) - w(t)) / h from the true rates at the step's ends; at the sample, the body's
 * (fixed IMU) or that mean (rotating IMU). */
static gf_status sense(const ModelData *d, const gf_vehicle_sample *x, const double *imu,
                       double dt_s, Sensed *o)
{
    double *w = o->gyro_rad_s, *f = o->accel_m_s2;
    double true_w[3], true_f[3];
    memcpy(true_w, imu ? imu : x->gyro_rad_s, sizeof true_w);
    memcpy(true_f, imu ? imu + 3 : x->accel_m_s2, sizeof true_f);
    memcpy(w, true_w, sizeof o->gyro_rad_s);
    memcpy(f, true_f, sizeof o->accel_m_s2);
    memcpy(o->dtheta_rad, imu ? imu + 6 : x->dtheta_rad, sizeof o->dtheta_rad);
    memcpy(o->dv_m_s, imu ? imu + 9 : x->dv_m_s, sizeof o->dv_m_s);
    o->imu_noise = d->imu_noise;
    o->array_rng = d->array_rng;
    memcpy(o->true_w, true_w, sizeof true_w);
    size_t done = 0;
    if (d->imu_errors) {
        double mean_dw[3] = {0.0, 0.0, 0.0};
        if (dt_s > 0.0)
            for (int i = 0; i < 3; ++i)
                mean_dw[i] = (true_w[i] - d->imu_w_true_prev[i]) / dt_s;
        const double *dw_now = imu ? mean_dw : x->gyro_dot_rad_s2;
        gf_status st = gf_imu_apply_dw(&d->imu, 1, true_w, dw_now, true_f, NULL, w, f, &done);
        if (st != GF_OK)
            return st;
        if (dt_s > 0.0) { /* increments as mean rates over the step, as the SINS FMU compensates */
            double mw[3], mf[3], ew[3], ef[3]; /* gf_imu_apply's outputs must not alias its inputs */
            for (int i = 0; i < 3; ++i) {
                mw[i] = o->dtheta_rad[i] / dt_s;
                mf[i] = o->dv_m_s[i] / dt_s;
            }
            st = gf_imu_apply_dw(&d->imu, 1, mw, mean_dw, mf, NULL, ew, ef, &done);
            if (st != GF_OK)
                return st;
            for (int i = 0; i < 3; ++i) {
                o->dtheta_rad[i] = ew[i] * dt_s;
                o->dv_m_s[i] = ef[i] * dt_s;
            }
        }
    }
    if (d->noise && dt_s > 0.0) { /* one noise sample a step, on rates and increments */
        double gn[3], an[3];
        const gf_status st = gf_imu_noise_run(&o->imu_noise, 1, dt_s, gn, an);
        if (st != GF_OK)
            return st;
        for (int i = 0; i < 3; ++i) {
            w[i] += gn[i];
            f[i] += an[i];
            o->dtheta_rad[i] += gn[i] * dt_s;
            o->dv_m_s[i] += an[i] * dt_s;
        }
    }
    double A[GF_ARRAY_MAX_SENSORS];
    const gf_status st = gf_array_forward(&d->array, 1, x->accel_m_s2, x->gyro_rad_s,
                                          x->gyro_dot_rad_s2, A, &done);
    if (st != GF_OK)
        return st;
    const size_t n = d->array.n_sensors;
    double e[VEHICLE_ARRAY_MAX] = {0.0};
    if (d->noise && dt_s > 0.0 && d->array_noise_m_s2 > 0.0) {
        gf_rng_normal(&o->array_rng, n, e);
        for (size_t i = 0; i < n; ++i)
            e[i] *= d->array_noise_m_s2;
    }
    for (size_t i = 0; i < VEHICLE_ARRAY_MAX; ++i)
        o->A_m_s2[i] = i < n ? A[i] + d->array_bias_m_s2[i] + e[i] : 0.0;
    return GF_OK;
}

static void commit(ModelData *d, const Sensed *o)
{
    memcpy(d->gyro_rad_s, o->gyro_rad_s, sizeof d->gyro_rad_s);
    memcpy(d->accel_m_s2, o->accel_m_s2, sizeof d->accel_m_s2);
    memcpy(d->dtheta_rad, o->dtheta_rad, sizeof d->dtheta_rad);
    memcpy(d->dv_m_s, o->dv_m_s, sizeof d->dv_m_s);
    memcpy(d->A_m_s2, o->A_m_s2, sizeof d->A_m_s2);
    memcpy(d->imu_w_true_prev, o->true_w, sizeof d->imu_w_true_prev);
    d->imu_noise = o->imu_noise;
    d->array_rng = o->array_rng;
}

/* Why gf_aiding_init refused the parameters (bad: GF_AIDING_BAD_*), by FMU name. */
static void log_bad_aiding(FmuInstance *instance, int bad)
{
    static const struct { int code; const char *name; } k[] = {
        {GF_AIDING_BAD_GNSS_ENABLED, "gnss"}, {GF_AIDING_BAD_GNSS_RATE, "gnss_rate"},
        {GF_AIDING_BAD_GNSS_OFFSET, "gnss_offset"}, {GF_AIDING_BAD_GNSS_LATENCY, "gnss_latency"},
        {GF_AIDING_BAD_GNSS_LEVER_ARM, "gnss_lever_arm"},
        {GF_AIDING_BAD_GNSS_POS_STD, "gnss_pos_std"}, {GF_AIDING_BAD_GNSS_VEL_STD, "gnss_vel_std"},
        {GF_AIDING_BAD_GNSS_GM_STD, "gnss_pos_gm_std"},
        {GF_AIDING_BAD_GNSS_GM_TAU, "gnss_pos_gm_tau"}, {GF_AIDING_BAD_GNSS_QUALITY, "gnss_q"},
        {GF_AIDING_BAD_GNSS_N_OUTAGES, "gnss_n_outages"},
        {GF_AIDING_BAD_GNSS_PERIODIC, "gnss_outage_first/_period/_duration"},
        {GF_AIDING_BAD_BARO_ENABLED, "baro"}, {GF_AIDING_BAD_BARO_RATE, "baro_rate"},
        {GF_AIDING_BAD_BARO_OFFSET, "baro_offset"}, {GF_AIDING_BAD_BARO_STD, "baro_std"},
        {GF_AIDING_BAD_BARO_BIAS0, "baro_bias0"}, {GF_AIDING_BAD_BARO_RW, "baro_bias_rw"},
        {GF_AIDING_BAD_BARO_GM_STD, "baro_bias_gm_std"},
        {GF_AIDING_BAD_BARO_GM_TAU, "baro_bias_gm_tau"},
        {GF_AIDING_BAD_ODO_ENABLED, "odo"}, {GF_AIDING_BAD_ODO_RATE, "odo_rate"},
        {GF_AIDING_BAD_ODO_OFFSET, "odo_offset"}, {GF_AIDING_BAD_ODO_LEVER_ARM, "odo_lever_arm"},
        {GF_AIDING_BAD_ODO_SCALE, "odo_scale_error"}, {GF_AIDING_BAD_ODO_STD, "odo_std"}};
    const char *why = gf_aiding_bad_string(bad);
    if (bad >= GF_AIDING_BAD_GNSS_OUTAGE) {
        const int i = bad - GF_AIDING_BAD_GNSS_OUTAGE + 1;
        fmu_log_error(instance, "GNSS outage %d (gnss_outage_start[%d], gnss_outage_end[%d]) %s",
                      i, i, i, why);
        return;
    }
    for (size_t i = 0; i < sizeof k / sizeof k[0]; ++i)
        if (k[i].code == bad) {
            fmu_log_error(instance, "parameter %s %s", k[i].name, why);
            return;
        }
    fmu_log_error(instance, "aiding sensor parameters refused (code %d)", bad);
}

/* rotation = 1: the schedule from the rot_* parameters, the IMU's rates at the start
 * (imu0) and the mechanism's outputs; 0 if refused (logged). */
static int rotation_start(FmuInstance *instance, ModelData *d, double start_time_s, double *imu0)
{
    d->gimbal_rad[0] = d->gimbal_rad[1] = 0.0;
    d->q_mb[0] = 1.0;
    d->q_mb[1] = d->q_mb[2] = d->q_mb[3] = 0.0;
    memset(&d->rot, 0, sizeof d->rot);
    if (d->rotation != 0 && d->rotation != 1) {
        fmu_log_error(instance, "parameter rotation = %d must be 0 or 1", (int)d->rotation);
        return 0;
    }
    if (!d->rotation)
        return 1;
    if (d->rot_n < 0 || d->rot_n > GF_ROT_MAX_SEGMENTS) {
        fmu_log_error(instance, "parameter rot_n = %d must be 0..%d", (int)d->rot_n, GF_ROT_MAX_SEGMENTS);
        return 0;
    }
    gf_rot_schedule s;
    memset(&s, 0, sizeof s);
    s.q_mb0[0] = 1.0;
    s.n_segments = (size_t)d->rot_n;
    s.repeat = d->rot_repeat;
    for (int32_t k = 0; k < d->rot_n; ++k) {
        gf_rot_segment *g = &s.segment[k];
        g->base_axis = d->rot_base_axis[k];
        g->imu_axis = d->rot_imu_axis[k];
        g->base_angle_rad = d->rot_base_angle_rad[k];
        g->imu_angle_rad = d->rot_imu_angle_rad[k];
        g->move_s = d->rot_move_s[k];
        g->ramp_s = d->rot_ramp_s[k];
        g->dwell_s = d->rot_dwell_s[k];
    }
    int bad = 0;
    const gf_status st = gf_rot_init(&d->rot, &s, start_time_s, &bad);
    if (st != GF_OK) {
        if (bad >= GF_ROT_BAD_SEGMENT)
            fmu_log_error(instance, "turn %d (rot_*[%d]): an axis not in -1..2, an angle about no "
                          "axis, rot_move <= 0 with an angle, 2 rot_ramp > rot_move, rot_dwell < 0, "
                          "a turn of no duration or faster than 600 deg/s",
                          bad - GF_ROT_BAD_SEGMENT + 1, bad - GF_ROT_BAD_SEGMENT + 1);
        else if (bad == GF_ROT_BAD_REPEAT)
            fmu_log_error(instance, "rot_repeat = 1 but one cycle of the turns does not bring the "
                          "IMU back to its start attitude");
        else if (bad == GF_ROT_BAD_EMPTY_CYCLE)
            fmu_log_error(instance, "rot_repeat = 1 with a cycle of zero duration");
        else
            fmu_log_error(instance, "rotation schedule refused: %s (a non-finite value?)",
                          gf_status_string(st));
        return 0;
    }
    gf_rot_pose pose;
    gf_rot_imu_outputs(&d->rot, start_time_s, d->out.gyro_rad_s, d->out.accel_m_s2, imu0, imu0 + 3, &pose);
    memcpy(d->gimbal_rad, pose.gimbal_rad, sizeof d->gimbal_rad);
    memcpy(d->q_mb, pose.q_mb, sizeof d->q_mb);
    return 1;
}

FmuStatus model_exit_initialization(FmuInstance *instance, ModelData *d, double start_time_s)
{
    if (d->n_segments < 0 || d->n_segments > GF_VEHICLE_MAX_SEGMENTS) {
        fmu_log_error(instance, "parameter n_segments = %d must be 0..%d", (int)d->n_segments,
                      GF_VEHICLE_MAX_SEGMENTS);
        return FMU_ERROR;
    }
    if (d->drive != 0 && d->drive != 1) {
        fmu_log_error(instance, "parameter drive = %d must be 0 (profile) or 1 (inputs)",
                      (int)d->drive);
        return FMU_ERROR;
    }
    if (!(d->command_time_s > 0.0) || !isfinite(d->command_time_s)) {
        fmu_log_error(instance, "parameter command_time = %g s must be finite and > 0",
                      d->command_time_s);
        return FMU_ERROR;
    }
    if (d->imu_errors != 0 && d->imu_errors != 1) {
        fmu_log_error(instance, "parameter imu_errors = %d must be 0 or 1", (int)d->imu_errors);
        return FMU_ERROR;
    }
    memset(&d->imu, 0, sizeof d->imu);
    if (d->imu_errors) {
        const char *why = fmu_imu_errors_build(&d->imu_params, &d->imu);
        if (why) {
            fmu_log_error(instance, "IMU error parameter out of range: %s", why);
            return FMU_ERROR;
        }
    }
    gf_status st = d->array_layout == 0 ? gf_layout_cube6(d->lever_arm_m, &d->array)
                 : d->array_layout == 1 ? gf9_geometry(d->lever_arm_m, &d->array)
                 : d->array_layout == 2 ? gf_layout_12(d->lever_arm_m, &d->array)
                                        : GF_ERR_BAD_PARAMETER;
    if (st != GF_OK) {
        fmu_log_error(instance, "array_layout = %d must be 0, 1 or 2 and l = %g m finite and "
                      ">= 1e-6 m", (int)d->array_layout, d->lever_arm_m);
        return FMU_ERROR;
    }
    if (d->noise != 0 && d->noise != 1) {
        fmu_log_error(instance, "parameter noise = %d must be 0 or 1", (int)d->noise);
        return FMU_ERROR;
    }
    {
        static const char *const names[] = {"gyro_arw", "gyro_bias_instability",
            "gyro_correlation_time", "gyro_rrw", "accel_vrw", "accel_bias_instability",
            "accel_correlation_time", "accel_rrw", "gyro_band", "accel_band", "band_hz"};
        int bad = -1;
        if (gf_imu_noise_init(&d->imu_noise, &d->noise_params, (uint64_t)(uint32_t)d->noise_seed,
                              &bad) != GF_OK) {
            fmu_log_error(instance, "noise parameter %s must be finite and >= 0 (a correlation "
                          "time or band_hz > 0 where its std is > 0)",
                          bad >= 0 && bad < 11 ? names[bad] : "?");
            return FMU_ERROR;
        }
        /* the array's generator: another stream of the same seed */
        gf_rng_seed(&d->array_rng, ((uint64_t)(uint32_t)d->noise_seed) ^ 0xA5A5A5A5A5A5A5A5ULL);
        if (!(d->array_noise_m_s2 >= 0.0) || !isfinite(d->array_noise_m_s2)) {
            fmu_log_error(instance, "parameter array_noise = %g m/s2 must be finite and >= 0",
                          d->array_noise_m_s2);
            return FMU_ERROR;
        }
    }
    if (!gf_all_finite(d->array_bias_m_s2, VEHICLE_ARRAY_MAX)) {
        fmu_log_error(instance, "parameter array_bias must be finite");
        return FMU_ERROR;
    }
    d->profile.n_segments = (size_t)d->n_segments;
    for (int32_t k = 0; k < d->n_segments; ++k) {
        d->profile.segment[k].duration_s = d->seg_duration_s[k];
        d->profile.segment[k].dspeed_m_s = d->seg_dspeed_m_s[k];
        d->profile.segment[k].dheading_rate_rad_s = d->seg_dheading_rate_rad_s[k];
        d->profile.segment[k].dheading_rad = d->seg_dheading_rad[k];
    }
    int bad = 0;
    st = gf_vehicle_init(&d->vehicle, &d->profile, start_time_s, &d->out, &bad);
    if (st != GF_OK) {
        if (bad == 1)
            fmu_log_error(instance, "parameter lat0 = %g rad: |lat0| must be < 89 deg",
                          d->profile.lat0_rad);
        else if (bad == 2)
            fmu_log_error(instance, "parameter h0 = %g m must be in [-1000, 1e5] m", d->profile.h0_m);
        else if (bad == 3)
            fmu_log_error(instance, "parameter speed0 = %g m/s must be >= 0", d->profile.speed0_m_s);
        else if (bad >= 100)
            fmu_log_error(instance, "segment %d (seg_*[%d]): seg_duration must be > 0 and the "
                          "speed must stay >= 0 (the seg_dspeed so far sum below -speed0)",
                          bad - 100 + 1, bad - 100 + 1);
        else
            fmu_log_error(instance, "vehicle parameters refused: %s (a non-finite start value "
                          "or segment?)", gf_status_string(st));
        return FMU_ERROR;
    }
    d->active_cmd[0] = d->active_cmd[1] = NAN;
    double imu0[12] = {0.0};
    if (!rotation_start(instance, d, start_time_s, imu0))
        return FMU_ERROR;
    Sensed sensed;
    st = sense(d, &d->out, d->rotation ? imu0 : NULL, 0.0, &sensed);
    if (st != GF_OK) {
        fmu_log_error(instance, "sensor outputs at the start failed: %s", gf_status_string(st));
        return FMU_ERROR;
    }
    /* aiding sensors: their own streams of noise_seed; epochs due at the start delivered */
    bad = 0;
    st = gf_aiding_init(&d->aiding_sim, &d->aiding, &d->vehicle, (uint64_t)(uint32_t)d->noise_seed,
                        &d->aiding_out, &bad);
    if (st == GF_ERR_BAD_PARAMETER) {
        log_bad_aiding(instance, bad);
        return FMU_ERROR;
    }
    if (st == GF_OK)
        st = gf_aiding_step(&d->aiding_sim, start_time_s, &d->aiding_out);
    if (st != GF_OK) {
        fmu_log_error(instance, "aiding sensors at the start failed: %s", gf_status_string(st));
        return FMU_ERROR;
    }
    commit(d, &sensed);
    return FMU_OK;
}

FmuStatus model_do_step(FmuInstance *instance, ModelData *d, double t_s, double h_s)
{
    gf_vehicle_state next = d->vehicle;
    /* a command starts a smooth step when it changes; a held command is reached after
     * command_time (re-anchoring every step would restart the smooth step each time) */
    const int changed = !(d->speed_cmd_m_s == d->active_cmd[0]) ||
                        !(d->heading_rate_cmd_rad_s == d->active_cmd[1]);
    if (d->drive == 1 && changed) {
        const gf_status st = gf_vehicle_command(&next, d->speed_cmd_m_s, d->heading_rate_cmd_rad_s,
                                                d->command_time_s);
        if (st != GF_OK) {
            fmu_log_error(instance, "t = %.9g s: input speed_cmd = %g m/s must be finite and "
                          ">= 0, heading_rate_cmd = %g rad/s finite", t_s, d->speed_cmd_m_s,
                          d->heading_rate_cmd_rad_s);
            return FMU_ERROR;
        }
    }
    /* the vehicle's clock is the master's: step to t + h, starting from t */
    next.time_s = t_s;
    /* a command changes the motion from t: the aiding sensors' copy of the vehicle takes
     * it (their epochs up to t were measured by the previous steps) */
    const int sync = d->drive == 1 && changed &&
                     (d->aiding.gnss.enabled || d->aiding.baro.enabled || d->aiding.odo.enabled);
    gf_aiding_sim synced;
    if (sync) {
        synced = d->aiding_sim;
        const gf_status st = gf_aiding_sync(&synced, &next);
        if (st != GF_OK) {
            fmu_log_error(instance, "t = %.9g s: aiding sensors cannot take the command: %s",
                          t_s, gf_status_string(st));
            return FMU_ERROR;
        }
    }
    gf_vehicle_sample out;
    double imu[12];
    gf_status st = d->rotation ? gf_rot_vehicle_step(&d->rot, &next, t_s + h_s, &out, imu)
                               : gf_vehicle_step(&next, t_s + h_s, &out);
    if (st != GF_OK) {
        fmu_log_error(instance, "t = %.9g s: vehicle step failed: %s", t_s,
                      st == GF_ERR_DIVERGED ? "the vehicle reached |latitude| = 89 deg"
                                            : gf_status_string(st));
        return FMU_ERROR;
    }
    Sensed sensed;
    st = sense(d, &out, d->rotation ? imu : NULL, h_s, &sensed);
    if (st != GF_OK) {
        fmu_log_error(instance, "t = %.9g s: sensor outputs failed: %s", t_s, gf_status_string(st));
        return FMU_ERROR;
    }
    gf_rot_pose pose;
    if (d->rotation && gf_rot_eval(&d->rot, t_s + h_s, &pose) != GF_OK) {
        fmu_log_error(instance, "t = %.9g s: rotation schedule failed", t_s);
        return FMU_ERROR;
    }
    /* last: it changes its state only on success, and nothing after it can fail */
    gf_aiding_sim *aid = sync ? &synced : &d->aiding_sim;
    st = gf_aiding_step(aid, t_s + h_s, &d->aiding_out);
    if (st != GF_OK) {
        fmu_log_error(instance, "t = %.9g s: aiding sensors failed: %s", t_s,
                      st == GF_ERR_DIVERGED ? "the vehicle reached |latitude| = 89 deg"
                                            : gf_status_string(st));
        return FMU_ERROR;
    }
    if (sync)
        d->aiding_sim = synced;
    if (d->drive == 1) {
        d->active_cmd[0] = d->speed_cmd_m_s;
        d->active_cmd[1] = d->heading_rate_cmd_rad_s;
    }
    d->out = out;
    commit(d, &sensed);
    d->vehicle = next;
    if (d->rotation) {
        memcpy(d->gimbal_rad, pose.gimbal_rad, sizeof d->gimbal_rad);
        memcpy(d->q_mb, pose.q_mb, sizeof d->q_mb);
    }
    return FMU_OK;
}

const char *model_validate_state(const ModelData *d)
{
    static const size_t layout_sensors[3] = {6, 9, 12};
    if (d->drive != 0 && d->drive != 1)
        return "drive is not 0 or 1";
    if (!(d->command_time_s > 0.0) || !isfinite(d->command_time_s))
        return "command_time is not finite and > 0";
    if (d->imu_errors != 0 && d->imu_errors != 1)
        return "imu_errors is not 0 or 1";
    if (!gf_all_finite(d->imu_w_true_prev, 3))
        return "the previous true IMU rate is not finite";
    if (d->imu_errors && gf_imu_errors_check(&d->imu, NULL) != GF_OK)
        return "the IMU error model is invalid";
    if (d->noise != 0 && d->noise != 1)
        return "noise is not 0 or 1";
    if (gf_imu_noise_state_check(&d->imu_noise) != GF_OK)
        return "the IMU noise state is invalid";
    if (!(d->array_noise_m_s2 >= 0.0) || !isfinite(d->array_noise_m_s2) ||
        !isfinite(d->array_rng.spare))
        return "array_noise or the array noise generator is invalid";
    if (!gf_all_finite(d->array_bias_m_s2, VEHICLE_ARRAY_MAX))
        return "array_bias is not finite";
    /* the array's sensor count sizes the noise and output loops (VEHICLE_ARRAY_MAX) */
    if (d->array_layout < 0 || d->array_layout > 2 ||
        d->array.n_sensors != layout_sensors[d->array_layout])
        return "array_layout or the array's sensor count is invalid";
    for (size_t i = 0; i < d->array.n_sensors; ++i)
        if (!gf_v3_isfinite(d->array.u_m[i]) || !gf_v3_isfinite(d->array.theta[i]))
            return "the array geometry is not finite";
    if (gf_vehicle_state_check(&d->vehicle) != GF_OK)
        return "the vehicle state (profile indices, motion) is invalid";
    if (d->rotation != 0 && d->rotation != 1)
        return "rotation is not 0 or 1";
    if (d->rotation && gf_rot_state_check(&d->rot) != GF_OK)
        return "the rotation schedule's state is invalid";
    if ((d->aiding.gnss.enabled || d->aiding.baro.enabled || d->aiding.odo.enabled) &&
        gf_aiding_sim_check(&d->aiding_sim) != GF_OK)
        return "the aiding sensors' state (GNSS queue, outages, parameters) is invalid";
    return NULL;
}
