/* model.c — the strapdown navigator as an FMU model: FMI-agnostic, calls gf_sins.
 *
 * Sampling: doStep(t, h) consumes the inputs set for t and leaves the outputs at t.
 * Increments cover the step that ends at t (so at the start time there is none: the
 * first doStep only starts the run); rates are samples at t (the first one starts the
 * record, as in gf_sins). The interval since the previous sample is the previous
 * communication step, so with a fixed step the FMU computes exactly what
 * gf_sins_run computes with dt = h. */
#include <math.h>
#include <string.h>

#include "fmu_model.h"
#include "base/gf_math.h"
#include "model.h"
#include "skip_steps.h"

/* returns 0 when the gimbal angles cannot make a vehicle attitude (non-finite) */
static int publish(ModelData *d)
{
    memcpy(d->q_bn, d->nav.q_bn, sizeof d->q_bn);
    gf_quat_to_euler(d->nav.q_bn, d->euler_rad);
    int ok = 1;
    if (d->rotating) {
        size_t done = 0;
        double q[4];
        ok = gf_rot_vehicle_attitude(1, d->nav.q_bn, d->gimbal_rad, q, &done) == GF_OK;
        if (ok) {
            memcpy(d->q_vehicle, q, sizeof q);
            gf_quat_to_euler(q, d->euler_vehicle_rad);
        }
    } else {
        memcpy(d->q_vehicle, d->q_bn, sizeof d->q_vehicle);
        memcpy(d->euler_vehicle_rad, d->euler_rad, sizeof d->euler_vehicle_rad);
    }
    memcpy(d->v_n_m_s, d->nav.v_n_m_s, sizeof d->v_n_m_s);
    d->lat_rad = d->nav.lat_rad;
    d->lon_rad = d->nav.lon_rad;
    d->h_m = d->nav.h_m;
    d->nav_time_s = d->nav.time_s;
    return ok;
}

/* Validates the parameters and starts the navigation at start_time_s (also used to
 * restart it after skip_steps ignored doSteps). */
static FmuStatus start_navigation(FmuInstance *instance, ModelData *d, double start_time_s)
{
    gf_sins_config cfg;
    gf_sins_config_default(&cfg);
    cfg.input = d->input_mode;
    cfg.coning = d->coning;
    cfg.vertical = d->vertical_mode;
    cfg.hold_height_m = d->hold_height_m;
    cfg.baro_tau_s = d->baro_tau_s;
    cfg.max_rate_rad_s = d->max_rate_rad_s;
    cfg.max_specific_force_m_s2 = d->max_specific_force_m_s2;
    const gf_status st = gf_sins_init(&d->nav, &cfg, d->q0, d->v0_m_s, d->lat0_rad,
                                      d->lon0_rad, d->h0_m, start_time_s);
    if (st != GF_OK) {
        if (d->input_mode != 0 && d->input_mode != 1)
            fmu_log_error(instance, "parameter input_mode = %d must be 0 (increments) or 1 (rates)",
                          (int)d->input_mode);
        else if (d->coning != 0 && d->coning != 1)
            fmu_log_error(instance, "parameter coning = %d must be 0 or 1", (int)d->coning);
        else if (d->vertical_mode < 0 || d->vertical_mode > 2)
            fmu_log_error(instance, "parameter vertical_mode = %d must be 0, 1 or 2",
                          (int)d->vertical_mode);
        else if (!(d->baro_tau_s > 0.0) || !(d->max_rate_rad_s > 0.0) ||
                 !(d->max_specific_force_m_s2 > 0.0))
            fmu_log_error(instance, "parameters baro_tau, max_rate and max_specific_force must "
                          "be > 0 (got %g s, %g rad/s, %g m/s2)", d->baro_tau_s,
                          d->max_rate_rad_s, d->max_specific_force_m_s2);
        else if (!(fabs(d->lat0_rad) < GF_SINS_LAT_LIMIT_RAD))
            fmu_log_error(instance, "parameter lat0 = %g rad is outside (-%g, %g) deg, the latitude "
                          "limit of the ENU mechanization", d->lat0_rad,
                          GF_SINS_LAT_LIMIT_MDEG / 1000.0, GF_SINS_LAT_LIMIT_MDEG / 1000.0);
        else
            fmu_log_error(instance, "initial state rejected (%s): q0 must be a finite, non-zero "
                          "quaternion and v0, lat0, lon0, h0 finite", gf_status_string(st));
        return FMU_ERROR;
    }
    memset(&d->imu, 0, sizeof d->imu);
    if (d->imu_comp != 0 && d->imu_comp != 1) {
        fmu_log_error(instance, "parameter imu_comp = %d must be 0 or 1", (int)d->imu_comp);
        return FMU_ERROR;
    }
    if (d->imu_comp) {
        const char *why = fmu_imu_errors_build(&d->imu_params, &d->imu);
        if (why) {
            fmu_log_error(instance, "IMU error parameter out of range: %s", why);
            return FMU_ERROR;
        }
    }
    if (d->lowpass_sections < 0 || d->lowpass_sections > 8) {
        fmu_log_error(instance, "parameter lowpass_sections = %d must be 0..8",
                      (int)d->lowpass_sections);
        return FMU_ERROR;
    }
    if (d->lowpass_sections > 0) {
        size_t bad = 0;
        const gf_status fs = gf_biquad_init(&d->lowpass, (size_t)d->lowpass_sections,
                                            d->lowpass_sos, 6, &bad);
        if (fs != GF_OK) {
            fmu_log_error(instance, "lowpass_sos section %d: %s", (int)bad,
                          fs == GF_ERR_SINGULAR_GEOMETRY ? "unstable (a pole on or outside the unit circle)"
                          : fs == GF_ERR_BAD_PARAMETER ? "a0 must be 1" : "non-finite coefficient");
            return FMU_ERROR;
        }
    }
    if (d->rotating != 0 && d->rotating != 1) {
        fmu_log_error(instance, "parameter rotating = %d must be 0 or 1", (int)d->rotating);
        return FMU_ERROR;
    }
    d->previous_step_s = 0.0;
    d->started = 0;
    d->imu_have_prev = 0;
    memset(d->imu_w_prev_rad_s, 0, sizeof d->imu_w_prev_rad_s);
    if (!publish(d)) {
        fmu_log_error(instance, "input gimbal = [%g, %g] rad is not finite", d->gimbal_rad[0],
                      d->gimbal_rad[1]);
        return FMU_ERROR;
    }
    return FMU_OK;
}

/* Compensation (exact inverse of the error model) and low-pass of one sample. Increments
 * are compensated as mean rates over the step (exact for the linear terms; K2 and the
 * lever arms then act on the mean); the angular acceleration of lever arms across the
 * axes is the backward difference of the compensated rates (gf_imu_compensate_step), the
 * rate written to w_comp. On error the filter state is left unchanged. */
static gf_status condition(ModelData *d, int increments, double dt, const double *gyro_in,
                           const double *accel_in, double gyro[3], double accel[3],
                           double w_comp[3])
{
    double x[6];
    memcpy(x, gyro_in, 3 * sizeof *x);
    memcpy(x + 3, accel_in, 3 * sizeof *x);
    if (d->imu_comp) {
        const double k = increments ? 1.0 / dt : 1.0;
        double w_in[3] = {x[0] * k, x[1] * k, x[2] * k}, f_in[3] = {x[3] * k, x[4] * k, x[5] * k};
        double w[3], f[3];
        const gf_status st = gf_imu_compensate_step(&d->imu, w_in, f_in, NULL,
                                                    d->imu_have_prev ? d->imu_w_prev_rad_s : NULL,
                                                    dt, w, f);
        if (st != GF_OK)
            return st;
        memcpy(w_comp, w, sizeof w);
        for (int i = 0; i < 3; ++i) {
            x[i] = w[i] / k;
            x[3 + i] = f[i] / k;
        }
    }
    if (d->lowpass_sections > 0) {
        size_t done = 0;
        const gf_status st = gf_biquad_run(&d->lowpass, 1, x, x, &done);
        if (st != GF_OK)
            return st;
    }
    memcpy(gyro, x, 3 * sizeof *x);
    memcpy(accel, x + 3, 3 * sizeof *x);
    return GF_OK;
}

FmuStatus model_exit_initialization(FmuInstance *instance, ModelData *d, double start_time_s)
{
    return fmu_nav_exit_initialization(instance, d, start_time_s, start_navigation);
}

FmuStatus model_do_step(FmuInstance *instance, ModelData *d, double t_s, double h_s)
{
    FmuStatus skipped;
    if (fmu_nav_skip_step(instance, d, t_s + h_s, start_navigation, &skipped))
        return skipped; /* inputs ignored; navigation (re)started for the next sample */
    const int increments = d->nav.cfg.input == GF_SINS_INPUT_INCREMENTS;
    if (increments && !d->started) { /* no increment ends at the start time */
        d->previous_step_s = h_s;
        d->started = 1;
        return FMU_OK;
    }
    if (d->rotating && !gf_all_finite(d->gimbal_rad, 2)) {
        fmu_log_error(instance, "t = %.9g s: input gimbal = [%g, %g] rad is not finite; the "
                      "outputs keep the last good sample", t_s, d->gimbal_rad[0], d->gimbal_rad[1]);
        return FMU_ERROR;
    }
    gf_sins_state next = d->nav;
    const double *gyro = increments ? d->dtheta_rad : d->gyro_rad_s;
    const double *accel = increments ? d->dv_m_s : d->accel_m_s2;
    double g_c[3], a_c[3], w_comp[3], z_backup[8 * 6 * 2]; /* filter: sections x 6 channels x 2 */
    const size_t z_used = (size_t)d->lowpass_sections * 6 * 2;
    if (z_used)
        memcpy(z_backup, d->lowpass.z, z_used * sizeof *z_backup);
    const double dt = d->previous_step_s > 0.0 ? d->previous_step_s : h_s;
    gf_status st = GF_OK;
    if (d->imu_comp || d->lowpass_sections > 0) {
        st = condition(d, increments, dt, gyro, accel, g_c, a_c, w_comp);
        if (st == GF_OK) {
            gyro = g_c;
            accel = a_c;
        }
    }
    if (st == GF_OK)
        st = gf_sins_step(&next, gyro, accel, d->previous_step_s, d->h_ext_m);
    if (st != GF_OK && z_used) /* a failed sample leaves the filter as it was */
        memcpy(d->lowpass.z, z_backup, z_used * sizeof *z_backup);
    if (st != GF_OK) {
        const char *g = increments ? "dtheta" : "gyro_rate", *a = increments ? "dv" : "specific_force";
        if (st == GF_ERR_NONFINITE_INPUT)
            fmu_log_error(instance, "t = %.9g s: input %s = [%g, %g, %g] or %s = [%g, %g, %g] is "
                          "not finite (or h_ext is infinite); the outputs keep the last good sample",
                          t_s, g, gyro[0], gyro[1], gyro[2], a, accel[0], accel[1], accel[2]);
        else if (st == GF_ERR_OUT_OF_RANGE)
            fmu_log_error(instance, "t = %.9g s: input %s = [%g, %g, %g] / %s = [%g, %g, %g] exceeds "
                          "max_rate = %g rad/s or max_specific_force = %g m/s2", t_s, g, gyro[0],
                          gyro[1], gyro[2], a, accel[0], accel[1], accel[2],
                          d->nav.cfg.max_rate_rad_s, d->nav.cfg.max_specific_force_m_s2);
        else
            fmu_log_error(instance, "t = %.9g s: navigation step failed: %s", t_s,
                          gf_status_string(st));
        return FMU_ERROR;
    }
    d->nav = next;
    if (d->imu_comp) {
        memcpy(d->imu_w_prev_rad_s, w_comp, sizeof w_comp);
        d->imu_have_prev = 1;
    }
    d->previous_step_s = h_s;
    d->started = 1;
    publish(d); /* the gimbal angles are finite: it cannot fail */
    return FMU_OK;
}

const char *model_validate_state(const ModelData *d)
{
    const char *why = fmu_nav_counters_invalid(d->skip_steps, d->skipped, d->started,
                                               d->previous_step_s);
    if (why)
        return why;
    if (gf_sins_state_check(&d->nav) != GF_OK)
        return "the navigation state (configuration, attitude, position) is invalid";
    /* the outputs a restored state carries (returned by a get before any step) */
    if (!gf_all_finite(d->q_bn, 4) || !gf_all_finite(d->euler_rad, 3) || !gf_all_finite(d->v_n_m_s, 3) ||
        !isfinite(d->lat_rad) || !isfinite(d->lon_rad) || !isfinite(d->h_m) || !isfinite(d->nav_time_s) ||
        !gf_all_finite(d->q_vehicle, 4) || !gf_all_finite(d->euler_vehicle_rad, 3))
        return "an output (attitude, velocity, position, time) is not finite";
    if (!gf_all_finite(d->q0, 4) || !gf_all_finite(d->v0_m_s, 3) || !isfinite(d->lat0_rad) ||
        !isfinite(d->lon0_rad) || !isfinite(d->h0_m) || !isfinite(d->hold_height_m) ||
        !isfinite(d->baro_tau_s) || !isfinite(d->max_rate_rad_s) || !isfinite(d->max_specific_force_m_s2))
        return "a parameter (initial state, vertical channel, limits) is not finite";
    if (d->nav.cfg.subsamples != 1) /* the FMU steps one sample per update */
        return "the navigation state's subsamples is not 1";
    if (d->imu_comp != 0 && d->imu_comp != 1)
        return "imu_comp is not 0 or 1";
    if (d->rotating != 0 && d->rotating != 1)
        return "rotating is not 0 or 1";
    if (d->imu_comp && gf_imu_errors_check(&d->imu, NULL) != GF_OK)
        return "the IMU error model is invalid";
    if ((d->imu_have_prev != 0 && d->imu_have_prev != 1) || !gf_all_finite(d->imu_w_prev_rad_s, 3))
        return "the last compensated rate is invalid";
    /* the low-pass: its section count sizes the filter-state copies of model_do_step */
    if (d->lowpass_sections < 0 || d->lowpass_sections > 8)
        return "lowpass_sections is not in 0..8";
    if (d->lowpass_sections > 0 &&
        (gf_biquad_check(&d->lowpass) != GF_OK ||
         d->lowpass.n_sections != (size_t)d->lowpass_sections || d->lowpass.n_channels != 6))
        return "the low-pass filter (sizes, coefficients, state) is invalid";
    return NULL;
}
