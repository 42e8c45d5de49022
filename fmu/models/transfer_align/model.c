/* model.c — transfer alignment (issue 24) as an FMU model: the slave IMU's filter
 * (gf_ins_gnss with the transfer-alignment states) fed per doStep by the slave's IMU
 * sample and the master INS's epoch delivered with it; FMI-agnostic (fmu/glue serves it).
 *
 * Sampling (as the other navigators): doStep(t, h) consumes the IMU sample set for t —
 * increments over (t_prev, t], or rates at t — and leaves the outputs at t. A master
 * epoch (master_valid > 0) carries its time t_m on the master's clock; it becomes the
 * filter's master measurements in the order of the batch API
 * (gfins_fmi.estimation.transfer.master_measurements: velocity, then with match_attitude
 * the attitude, with match_position the position, each with the master's rate):
 *   t_prev < t_m <= t        the sample's interval is split at t_m, the updates made there;
 *   t_m = t_prev             applied at the filter's time, before the sample (a Jacobi
 *                            master delivers a master INS FMU's outputs one step late);
 *   t_m < t_prev             logged by the core as stale (status 3);
 *   t < t_m <= t + 1e-9 max(1, |t|): taken at t (a master's clock rounding);
 *   later                    refused: an epoch cannot be delivered before it is valid.
 * With the same samples and epochs the FMU makes the gf_ins_step calls gf_ins_run makes,
 * so it computes bit for bit what gfins_fmi.estimation.transfer.transfer_align computes
 * (tests/fmi/test_fmu_transfer.py). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmu_model.h"
#include "base/gf_math.h"
#include "model.h"
#include "model_extra.h"   /* kInsSettings: generated from the settings table */
#include "ins_settings.h"  /* log_bad_config, all_positive, ins_fmu_step */
#include "skip_steps.h"

#define N_MEAS_MAX 3   /* master velocity, attitude, position */
#define LOG_MAX 16     /* updates one sample can make: the master's + NHC + ZUPT + ZARU */

static int32_t saturate(uint64_t x)
{
    return x > (uint64_t)INT32_MAX ? INT32_MAX : (int32_t)x;
}

/* sqrt(P_ii) of a state, NaN for a block the configuration has not (idx < 0) */
static double state_std(const gf_ins_filter *f, int32_t idx, int k)
{
    if (idx < 0)
        return NAN;
    const int n = f->n_states, i = idx + k;
    return sqrt(f->kf.P[i * n + i]);
}

static void publish(ModelData *d)
{
    const gf_ins_filter *f = &d->filter;
    memcpy(d->q_bn, f->nav.q_bn, sizeof d->q_bn);
    gf_quat_to_euler(f->nav.q_bn, d->euler_rad);
    memcpy(d->v_n_m_s, f->nav.v_n_m_s, sizeof d->v_n_m_s);
    d->lat_rad = f->nav.lat_rad;
    d->lon_rad = f->nav.lon_rad;
    d->h_m = f->nav.h_m;
    d->nav_time_s = f->t_s;
    memcpy(d->std9, f->std9, sizeof d->std9);
    memcpy(d->sensors, f->sensors, sizeof d->sensors);
    for (int i = 0; i < 3; ++i) {   /* transfer[]: mounting, lever arm, offset, flexure */
        d->mount_rad[i] = f->cfg.master_mount_rad[i] + f->transfer[i];
        d->mount_std_rad[i] = state_std(f, f->idx_tmount, i);
        d->lever_m[i] = f->cfg.master_lever_arm_m[i] + f->transfer[3 + i];
        d->lever_std_m[i] = state_std(f, f->idx_tlever, i);
        d->flexure_rad[i] = f->transfer[7 + i];
    }
    d->time_offset_s = f->cfg.master_time_offset_s + f->transfer[6];
    d->time_offset_std_s = state_std(f, f->idx_toffset, 0);
    d->n_imu = saturate(f->n_imu);
    d->n_updates = saturate(f->n_updates);
    d->n_rejected = saturate(f->n_rejected + d->n_unused);
}

static void record_update(ModelData *d, int32_t type, int32_t status, double nis)
{
    const int k = type - GF_INS_MEAS_MASTER_VEL;
    if (k < 0 || k >= TA_FMU_KINDS)
        return;
    d->nis[k] = nis;
    d->update_status[k] = status;
    if (d->update_count[k] < INT32_MAX)
        d->update_count[k]++;
}

/* Validates the parameters and starts the filter at t0_s from q0, v0, lat0, lon0, h0. */
static FmuStatus start_filter(FmuInstance *instance, ModelData *d, double t0_s)
{
    int32_t bad = 0;
    if (gf_ins_config_check(&d->cfg, &bad) != GF_OK) {
        log_bad_config(instance, d, bad);
        return FMU_ERROR;
    }
    if ((d->match_attitude & ~1) || (d->match_position & ~1) || (d->start_from_master & ~1)) {
        fmu_log_error(instance, "parameters match_attitude = %d, match_position = %d and "
                      "start_from_master = %d must be 0 or 1", (int)d->match_attitude,
                      (int)d->match_position, (int)d->start_from_master);
        return FMU_ERROR;
    }
    if (!(isfinite(d->master_interval_s) && d->master_interval_s >= 0.0)) {
        fmu_log_error(instance, "parameter master_interval = %g s must be finite and >= 0",
                      d->master_interval_s);
        return FMU_ERROR;
    }
    if (!all_positive(d->master_vel_std_m_s, 3) || !all_positive(d->master_att_std_rad, 3) ||
        !all_positive(d->master_pos_std_m, 3)) {
        fmu_log_error(instance, "parameters master_vel_std, master_att_std and master_pos_std must be "
                      "finite and > 0 (each element)");
        return FMU_ERROR;
    }
    if (!gf_all_finite(d->q0, 4) || !gf_all_finite(d->v0_m_s, 3) || !isfinite(d->lon0_rad) ||
        !isfinite(d->h0_m) || !gf_all_finite(d->sensors0, GF_INS_N_SENSORS)) {
        fmu_log_error(instance, "parameters q0, v0, lon0, h0 and sensors0 must be finite");
        return FMU_ERROR;
    }
    /* gf_ins_initial_std's blocks; barometer and odometer from the process-noise rows, as
     * gfins_fmi.estimation.InitialState's defaults */
    gf_ins_initial_std sd;
    memset(&sd, 0, sizeof sd);
    memcpy(sd.velocity_std_m_s, d->std0_vel_m_s, sizeof sd.velocity_std_m_s);
    memcpy(sd.position_std_m, d->std0_pos_m, sizeof sd.position_std_m);
    memcpy(sd.attitude_std_rad, d->std0_att_rad, sizeof sd.attitude_std_rad);
    memcpy(sd.gyro_bias_std_rad_s, d->std0_gyro_bias_rad_s, sizeof sd.gyro_bias_std_rad_s);
    memcpy(sd.accel_bias_std_m_s2, d->std0_accel_bias_m_s2, sizeof sd.accel_bias_std_m_s2);
    memcpy(sd.gyro_scale_std, d->std0_gyro_scale, sizeof sd.gyro_scale_std);
    memcpy(sd.accel_scale_std, d->std0_accel_scale, sizeof sd.accel_scale_std);
    sd.baro_bias_std_m = d->cfg.noise.baro_bias_std_m;
    sd.odometer_scale_std = d->cfg.noise.odometer_scale_std;
    sd.odometer_mount_std_rad[0] = sd.odometer_mount_std_rad[1] = d->cfg.noise.odometer_mount_std_rad;
    memcpy(sd.master_mount_std_rad, d->std0_mount_rad, sizeof sd.master_mount_std_rad);
    memcpy(sd.master_lever_std_m, d->std0_lever_m, sizeof sd.master_lever_std_m);
    sd.master_time_offset_std_s = d->std0_time_offset_s;
    double P0[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    gf_status st = gf_ins_initial_covariance(&d->cfg, d->lat0_rad, d->h0_m, &sd, P0, &bad);
    if (st != GF_OK) {
        const char *name = bad ? gf_ins_initial_std_field(bad) : NULL;
        if (name)
            fmu_log_error(instance, "the initial 1-sigma %s (parameter std0_*) must be finite and > 0 "
                          "(each element)", name);
        else
            fmu_log_error(instance, "parameters lat0 = %g rad, h0 = %g m: the start must be within "
                          "+-89 deg of latitude at a sensible height", d->lat0_rad, d->h0_m);
        return FMU_ERROR;
    }
    if (d->start_from_master && d->cfg.master_mount &&
        gf_ins_master_start_covariance(&d->cfg, d->q0, P0) != GF_OK) {
        fmu_log_error(instance, "parameter q0 must be a finite, non-zero quaternion");
        return FMU_ERROR;
    }
    st = gf_ins_init(&d->filter, &d->cfg, t0_s, d->q0, d->v0_m_s, d->lat0_rad, d->lon0_rad,
                     d->h0_m, d->sensors0, P0, &bad);
    if (st != GF_OK) {
        if (bad)
            log_bad_config(instance, d, bad);
        else
            fmu_log_error(instance, "initial state refused (%s): q0 must be a finite, non-zero "
                          "quaternion", gf_status_string(st));
        return FMU_ERROR;
    }
    for (int k = 0; k < TA_FMU_KINDS; ++k) {
        d->nis[k] = NAN;
        d->update_status[k] = -1;
        d->update_count[k] = 0;
    }
    d->n_unused = 0;
    d->started = 0;
    d->last_master_t_s = -INFINITY;
    publish(d);
    return FMU_OK;
}

FmuStatus model_exit_initialization(FmuInstance *instance, ModelData *d, double start_time_s)
{
    return fmu_nav_exit_initialization(instance, d, start_time_s, start_filter);
}

/* The master epoch delivered with this step as the filter's measurements; 0 on a
 * refused input (logged). */
static int gather(FmuInstance *instance, ModelData *d, double t_s, gf_ins_meas *meas,
                  size_t *n_meas)
{
    *n_meas = 0;
    if (d->master_valid < 0) {
        fmu_log_error(instance, "t = %.9g s: input master_valid = %d must be >= 0", t_s,
                      (int)d->master_valid);
        return 0;
    }
    if (!d->master_valid)
        return 1;
    double t_m = d->master_time_s;
    if (!isfinite(t_m)) {
        fmu_log_error(instance, "t = %.9g s: master_valid = %d but master_time_s = %g is not finite",
                      t_s, (int)d->master_valid, t_m);
        return 0;
    }
    if (t_m > t_s + 1e-9) {
        if (t_m - t_s > 1e-9 * fmax(1.0, fabs(t_s))) {
            fmu_log_error(instance, "t = %.9g s: master epoch at master_time_s = %.9g s, after the IMU "
                          "sample it was delivered with: deliver an epoch in the step whose sample "
                          "time reaches it", t_s, t_m);
            return 0;
        }
        t_m = t_s;   /* the master's clock rounding (glue tolerance) */
    }
    if (t_m - d->last_master_t_s < d->master_interval_s - 1e-9)
        return 1;   /* too soon after the last epoch used (master_interval) */
    const double pos[3] = {d->master_lat_rad, d->master_lon_rad, d->master_h_m};
    if (!gf_all_finite(d->master_euler_rad, 3) || !gf_all_finite(d->master_vel_m_s, 3) ||
        !gf_all_finite(pos, 3) || !gf_all_finite(d->master_rate_rad_s, 3) ||
        !(fabs(d->master_lat_rad) < GF_HALF_PI)) {
        fmu_log_error(instance, "t = %.9g s: the master inputs (master_euler, master_vel, master_lat, "
                      "master_lon, master_h, master_rate) must be finite and |master_lat| < pi/2", t_s);
        return 0;
    }
    size_t n = 0;
    gf_ins_meas *m = meas + n++;   /* velocity, then attitude, then position: the batch order */
    *m = (gf_ins_meas){GF_INS_MEAS_MASTER_VEL, t_m, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    memcpy(m->z, d->master_vel_m_s, sizeof m->z);
    memcpy(m->std, d->master_vel_std_m_s, sizeof m->std);
    if (d->match_attitude) {
        m = meas + n++;
        *m = (gf_ins_meas){GF_INS_MEAS_MASTER_ATT, t_m, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
        memcpy(m->z, d->master_euler_rad, sizeof m->z);
        memcpy(m->std, d->master_att_std_rad, sizeof m->std);
    }
    if (d->match_position) {
        m = meas + n++;
        *m = (gf_ins_meas){GF_INS_MEAS_MASTER_POS, t_m, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
        memcpy(m->z, pos, sizeof m->z);
        memcpy(m->std, d->master_pos_std_m, sizeof m->std);
    }
    for (size_t j = 0; j < n; ++j)
        memcpy(meas[j].aux, d->master_rate_rad_s, sizeof meas[j].aux);
    *n_meas = n;
    d->last_master_t_s = t_m;
    return 1;
}

FmuStatus model_do_step(FmuInstance *instance, ModelData *d, double t_s, double h_s)
{
    FmuStatus skipped;
    if (fmu_nav_skip_step(instance, d, t_s + h_s, start_filter, &skipped))
        return skipped;
    gf_ins_meas meas[N_MEAS_MAX];
    size_t n_meas = 0;
    if (!gather(instance, d, t_s, meas, &n_meas))
        return FMU_ERROR;
    gf_ins_filter *f = &d->filter;
    const int increments = f->cfg.input == GF_SINS_INPUT_INCREMENTS;
    if (increments && !d->started) {
        /* no increment ends at the filter's start: an epoch now is stale, as the core says */
        for (size_t j = 0; j < n_meas; ++j)
            record_update(d, meas[j].type, GF_INS_REJECTED_STALE, NAN);
        d->n_unused += n_meas;
        d->started = 1;
        publish(d);
        return FMU_OK;
    }
    gf_ins_innovation entries[LOG_MAX];
    gf_ins_log log = {LOG_MAX, 0, 0, entries};
    /* a failed step: the FMI error state, the outputs keep the last good sample (ins_fmu_step) */
    if (ins_fmu_step(instance, f, t_s, d->dtheta_rad, d->dv_m_s, d->gyro_rad_s, d->accel_m_s2, n_meas,
                     meas, &log) != GF_OK)
        return FMU_ERROR;
    for (size_t i = 0; i < log.count; ++i)
        record_update(d, entries[i].type, entries[i].status, entries[i].nis);
    d->started = 1;
    publish(d);
    return FMU_OK;
}

/* A 1-sigma output: finite and >= 0 for an estimated block, NaN for one the filter has
 * not (idx < 0) */
static int std_output_ok(const double *s, int n, int32_t idx)
{
    for (int i = 0; i < n; ++i)
        if (idx >= 0 ? !(s[i] >= 0.0 && isfinite(s[i])) : !isnan(s[i]))
            return 0;
    return 1;
}

/* The model's own floats (as fmu/models/ins_gnss/model.c's, issue 21): NULL when the
 * parameters, the outputs and the internals a restored state carries are finite (the
 * monitoring nis may be NaN: "no update of this kind yet", never infinite; the 1-sigma
 * of a block not estimated is NaN), else what is wrong. The inputs are the master's to
 * set before the next doStep (which checks them). */
static const char *model_floats_problem(const ModelData *d)
{
    const double *params[] = {d->q0, d->v0_m_s, &d->lat0_rad, &d->lon0_rad, &d->h0_m, d->sensors0,
                              d->std0_vel_m_s, d->std0_pos_m, d->std0_att_rad, d->std0_gyro_bias_rad_s,
                              d->std0_accel_bias_m_s2, d->std0_gyro_scale, d->std0_accel_scale,
                              d->std0_mount_rad, d->std0_lever_m, &d->std0_time_offset_s,
                              &d->master_interval_s, d->master_vel_std_m_s, d->master_att_std_rad,
                              d->master_pos_std_m};
    const size_t n_params[] = {4, 3, 1, 1, 1, GF_INS_N_SENSORS, 3, 3, 3, 3, 3, 3, 3, 3, 3, 1, 1, 3, 3, 3};
    for (size_t i = 0; i < sizeof n_params / sizeof n_params[0]; ++i)
        if (!gf_all_finite(params[i], n_params[i]))
            return "a parameter (initial state, its 1-sigma, the master's noise) is not finite";
    const double *outs[] = {d->q_bn, d->euler_rad, d->v_n_m_s, &d->lat_rad, &d->lon_rad, &d->h_m,
                            &d->nav_time_s, d->std9, d->sensors, d->mount_rad, d->lever_m,
                            &d->time_offset_s, d->flexure_rad};
    const size_t n_outs[] = {4, 3, 3, 1, 1, 1, 1, 9, GF_INS_N_SENSORS, 3, 3, 1, 3};
    for (size_t i = 0; i < sizeof n_outs / sizeof n_outs[0]; ++i)
        if (!gf_all_finite(outs[i], n_outs[i]))
            return "an output (attitude, velocity, position, time, 1-sigma, sensor and transfer "
                   "estimates) is not finite";
    const gf_ins_filter *f = &d->filter;
    if (!std_output_ok(d->mount_std_rad, 3, f->idx_tmount) || !std_output_ok(d->lever_std_m, 3, f->idx_tlever) ||
        !std_output_ok(&d->time_offset_std_s, 1, f->idx_toffset))
        return "a transfer 1-sigma output (mount_std, lever_std, time_offset_std) is not finite and >= 0 "
               "for an estimated block, or not NaN for one that is not";
    for (int k = 0; k < TA_FMU_KINDS; ++k)
        if (isinf(d->nis[k]))
            return "a monitoring output (nis) is infinite";
    if (!(isfinite(d->last_master_t_s) || d->last_master_t_s == -INFINITY))
        return "last_master_t_s is neither finite nor -Inf (no epoch used yet)";
    return NULL;
}

const char *model_validate_state(const ModelData *d)
{
    const gf_ins_filter *f = &d->filter;
    if (d->skip_steps < 0 || d->skipped < 0 || d->skipped > d->skip_steps)
        return "skip_steps / skipped out of range";
    if ((d->started & ~1) || (d->match_attitude & ~1) || (d->match_position & ~1) ||
        (d->start_from_master & ~1))
        return "a flag of the model is not 0 or 1";
    if (f->n_states == 0 && f->kf.n == 0 && f->ukf_w.n == 0)
        return NULL;   /* not started yet (before exitInitializationMode) */
    const char *why = model_floats_problem(d);
    if (why)
        return why;
    if (gf_ins_filter_check(f) != GF_OK)
        return "the filter state (layout, indices, nominal state, covariance, floats) is invalid";
    return NULL;
}
