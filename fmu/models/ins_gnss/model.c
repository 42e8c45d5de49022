/* model.c — the integrated navigator (error-state INS/GNSS filter, gf_ins_gnss) as an FMU
 * model: FMI-agnostic; gf_ins_init when leaving initialization, gf_ins_step per doStep.
 *
 * Sampling (as the other navigators): doStep(t, h) consumes the IMU sample set for t —
 * increments over (t_prev, t], t_prev the previous sample's time (at the start time there
 * is none: the first doStep only starts the run), or rates at t (the first one starts the
 * record) — and leaves the outputs at t.
 *
 * Measurements: each kind (GNSS position and, with gnss_vel_valid, velocity; barometer;
 * odometer) whose *_valid input is > 0 in this doStep is handed to gf_ins_step with its
 * time of validity t_m (*_time_s), sorted by time (at equal times GNSS position, GNSS
 * velocity, barometer, odometer, as the batch API sorts them):
 *   t_prev < t_m <= t        the IMU interval is split at t_m and the update made there;
 *   t_m <= t_prev            logged by the core as stale (status 3);
 *   t < t_m <= t + 1e-9 max(1, |t|) (the glue's tolerance on communication points):
 *                            taken at t (a master's clock rounding, not a later time);
 *   later                    refused with an error: a measurement cannot arrive before
 *                            it is valid, so the master's timing is wrong.
 * With the same samples, times and measurements the FMU makes the gf_ins_step calls that
 * gf_ins_run makes, so it computes bit for bit what IntegratedNavigator.run computes. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmu_model.h"
#include "base/gf_math.h"
#include "nav/gf_earth.h"
#include "model.h"
#include "model_extra.h"   /* kInsSettings: generated from the settings table */
#include "ins_settings.h"  /* log_bad_config, all_positive, ins_fmu_step */
#include "skip_steps.h"

#define N_MEAS_MAX 4   /* GNSS position, GNSS velocity, barometer, odometer */
#define LOG_MAX 16     /* updates one sample can make: N_MEAS_MAX + NHC + ZUPT + ZARU */

static int32_t saturate(uint64_t x)
{
    return x > (uint64_t)INT32_MAX ? INT32_MAX : (int32_t)x;
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
    d->n_imu = saturate(f->n_imu);
    d->n_updates = saturate(f->n_updates);
    d->n_rejected = saturate(f->n_rejected + d->n_unused);
    d->standstill = f->standstill;
}

/* one update of a kind, for the monitoring outputs */
static void record_update(ModelData *d, int32_t type, int32_t status, double nis, double t_s)
{
    const int k = type - 1;
    if (k < 0 || k >= INS_FMU_KINDS)
        return;
    d->nis[k] = nis;
    d->update_status[k] = status;
    d->update_time_s[k] = t_s;
    if (d->update_count[k] < INT32_MAX)
        d->update_count[k]++;
}

/* Where the filter starts: attitude, velocity, position, sensor-error estimates and the
 * heading 1-sigma (NaN: std0_att[2]). */
typedef struct {
    double q_bn[4], v_n_m_s[3], lat_rad, lon_rad, h_m, sensors[GF_INS_N_SENSORS], heading_std_rad;
} StartPoint;

/* The initial state and its uncertainty; 0 when a parameter was refused (logged). P0 is
 * diagonal, position converted from metres east, north, up to (dlat, dlon, dh) with the
 * radii of gf_earth at the start position s, as gfins_fmi.estimation.InitialState.covariance;
 * the heading std is s->heading_std_rad unless NaN. */
static int initial_covariance(FmuInstance *instance, const ModelData *d, const StartPoint *s,
                              double *P0)
{
    if (!isfinite(d->lon0_rad) || !isfinite(d->h0_m) || !gf_all_finite(d->v0_m_s, 3) ||
        !gf_all_finite(d->q0, 4)) {
        fmu_log_error(instance, "parameters q0, v0, lon0 and h0 must be finite");
        return 0;
    }
    if (!gf_all_finite(d->sensors0, GF_INS_N_SENSORS)) {
        fmu_log_error(instance, "parameter sensors0 must be finite");
        return 0;
    }
    /* the parameters of gf_ins_initial_std's blocks, in its order */
    const struct {
        const char *name, *unit;
        const double *x;
        int n;
    } blocks[] = {
        {"std0_vel", "m/s", d->std0_vel_m_s, 3},
        {"std0_pos", "m", d->std0_pos_m, 3},
        {"std0_att", "rad", d->std0_att_rad, 3},
        {"std0_gyro_bias", "rad/s", d->std0_gyro_bias_rad_s, 3},
        {"std0_accel_bias", "m/s2", d->std0_accel_bias_m_s2, 3},
        {"std0_gyro_scale", "", d->std0_gyro_scale, 3},
        {"std0_accel_scale", "", d->std0_accel_scale, 3},
        {"std0_baro_bias", "m", &d->std0_baro_bias_m, 1},
        {"std0_odo_scale", "", &d->std0_odo_scale, 1},
        {"std0_odo_mount", "rad", d->std0_odo_mount_rad, 2},
    };
    gf_ins_initial_std sd;
    memcpy(sd.velocity_std_m_s, d->std0_vel_m_s, sizeof sd.velocity_std_m_s);
    memcpy(sd.position_std_m, d->std0_pos_m, sizeof sd.position_std_m);
    memcpy(sd.attitude_std_rad, d->std0_att_rad, sizeof sd.attitude_std_rad);
    memcpy(sd.gyro_bias_std_rad_s, d->std0_gyro_bias_rad_s, sizeof sd.gyro_bias_std_rad_s);
    memcpy(sd.accel_bias_std_m_s2, d->std0_accel_bias_m_s2, sizeof sd.accel_bias_std_m_s2);
    memcpy(sd.gyro_scale_std, d->std0_gyro_scale, sizeof sd.gyro_scale_std);
    memcpy(sd.accel_scale_std, d->std0_accel_scale, sizeof sd.accel_scale_std);
    sd.baro_bias_std_m = d->std0_baro_bias_m;
    sd.odometer_scale_std = d->std0_odo_scale;
    memcpy(sd.odometer_mount_std_rad, d->std0_odo_mount_rad, sizeof sd.odometer_mount_std_rad);
    if (!isnan(s->heading_std_rad))   /* an alignment's heading sigma */
        sd.attitude_std_rad[2] = s->heading_std_rad;
    int32_t bad = 0;
    const gf_status st = gf_ins_initial_covariance(&d->cfg, s->lat_rad, s->h_m, &sd, P0, &bad);
    if (st == GF_OK)
        return 1;
    if (bad >= 1 && bad <= (int32_t)(sizeof blocks / sizeof blocks[0])) {
        const double *x = blocks[bad - 1].x;
        if (blocks[bad - 1].n == 3)
            fmu_log_error(instance, "parameter %s = [%g, %g, %g] %s: every element must be "
                          "finite and > 0", blocks[bad - 1].name, x[0], x[1], x[2],
                          blocks[bad - 1].unit);
        else if (blocks[bad - 1].n == 2)
            fmu_log_error(instance, "parameter %s = [%g, %g] %s: every element must be "
                          "finite and > 0", blocks[bad - 1].name, x[0], x[1], blocks[bad - 1].unit);
        else
            fmu_log_error(instance, "parameter %s = %g %s must be finite and > 0",
                          blocks[bad - 1].name, x[0], blocks[bad - 1].unit);
    } else if (st == GF_ERR_OUT_OF_RANGE) {
        fmu_log_error(instance, "parameter lat0 = %g rad (start latitude %g rad): it must be "
                      "within +-89 deg (the ENU error model is singular near the poles)",
                      d->lat0_rad, s->lat_rad);
    } else {
        fmu_log_error(instance, "start height %g m is absurd (parameter h0 or the GNSS height)",
                      s->h_m);
    }
    return 0;
}

static void reset_monitor(ModelData *d)
{
    for (int k = 0; k < INS_FMU_KINDS; ++k) {
        d->nis[k] = NAN;
        d->update_time_s[k] = NAN;
        d->update_status[k] = -1;
        d->update_count[k] = 0;
    }
    d->n_unused = 0;
}

/* The start point of the parameters with attitude q and velocity v. */
static StartPoint start_point(const ModelData *d, const double *q, const double *v)
{
    StartPoint s;
    memcpy(s.q_bn, q, sizeof s.q_bn);
    memcpy(s.v_n_m_s, v, sizeof s.v_n_m_s);
    s.lat_rad = d->lat0_rad;
    s.lon_rad = d->lon0_rad;
    s.h_m = d->h0_m;
    memcpy(s.sensors, d->sensors0, sizeof s.sensors);
    s.heading_std_rad = NAN;
    return s;
}

/* Validates the parameters and starts the filter at t0_s from s. */
static FmuStatus start_filter_at(FmuInstance *instance, ModelData *d, double t0_s,
                                 const StartPoint *s)
{
    double P0[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    int32_t bad = 0;
    if (gf_ins_config_check(&d->cfg, &bad) != GF_OK) {   /* names the field */
        log_bad_config(instance, d, bad);
        return FMU_ERROR;
    }
    if (!initial_covariance(instance, d, s, P0))
        return FMU_ERROR;
    const gf_status st = gf_ins_init(&d->filter, &d->cfg, t0_s, s->q_bn, s->v_n_m_s, s->lat_rad,
                                     s->lon_rad, s->h_m, s->sensors, P0, &bad);
    if (st != GF_OK) {
        if (bad)
            log_bad_config(instance, d, bad);
        else
            fmu_log_error(instance, "initial state refused (%s): q0 must be a finite, non-zero "
                          "quaternion", gf_status_string(st));
        return FMU_ERROR;
    }
    d->started = 0;
    reset_monitor(d);
    publish(d);
    return FMU_OK;
}

/* Validates the parameters and starts the filter at t0_s with attitude q and velocity v. */
static FmuStatus start_filter_with(FmuInstance *instance, ModelData *d, double t0_s,
                                   const double *q, const double *v)
{
    const StartPoint s = start_point(d, q, v);
    return start_filter_at(instance, d, t0_s, &s);
}

/* The alignment phase's limits (those of gfins_fmi.estimation.alignment.coarse_align) */
#define ALIGN_MAX_ACCEL_STD_M_S2 0.2
#define ALIGN_MAX_RATE_RAD_S 0.05
#define ALIGN_MAX_LAT_RAD (85.0 * GF_PI / 180.0)

/* Starts the filter at t0_s from q0, v0; with align_time > 0 the alignment phase starts
 * there instead (the filter holds the initial state until it ends). */
static FmuStatus start_filter(FmuInstance *instance, ModelData *d, double t0_s)
{
    if (!(isfinite(d->align_time_s) && d->align_time_s >= 0.0)) {
        fmu_log_error(instance, "parameter align_time = %g s must be finite and >= 0",
                      d->align_time_s);
        return FMU_ERROR;
    }
    if (d->align_heading != 0 && d->align_heading != 1) {
        fmu_log_error(instance, "parameter align_heading = %d must be 0 (gyrocompassing) or 1 "
                      "(from the GNSS direction of travel)", (int)d->align_heading);
        return FMU_ERROR;
    }
    if (d->align_heading == 1 &&
        !(isfinite(d->align_min_speed_m_s) && d->align_min_speed_m_s > 0.0 &&
          isfinite(d->align_travel_std_rad) && d->align_travel_std_rad > 0.0)) {
        fmu_log_error(instance, "parameters align_min_speed = %g m/s and align_travel_std = %g rad "
                      "must be finite and > 0", d->align_min_speed_m_s, d->align_travel_std_rad);
        return FMU_ERROR;
    }
    if (d->align_time_s > 0.0 && d->align_heading == 0 && !(fabs(d->lat0_rad) <= ALIGN_MAX_LAT_RAD)) {
        fmu_log_error(instance, "align_time = %g s: an alignment at rest finds the heading from "
                      "the Earth rate, which is nearly vertical beyond 85 deg latitude (lat0 = "
                      "%g rad); give q0 and set align_time = 0", d->align_time_s, d->lat0_rad);
        return FMU_ERROR;
    }
    const FmuStatus st = start_filter_with(instance, d, t0_s, d->q0, d->v0_m_s);
    d->aligning = d->align_time_s > 0.0;
    d->align_travel = 0;
    d->align_n = d->align_have_t = 0;
    d->align_t0_s = d->align_t_prev_s = t0_s;
    memset(d->align_f_sum, 0, sizeof d->align_f_sum);
    memset(d->align_w_sum, 0, sizeof d->align_w_sum);
    d->align_fn_sum = d->align_fn2_sum = d->align_wn_sum = 0.0;
    return st;
}

/* After a start at t_s inside a run: with rates this doStep's sample starts the filter's
 * record; with increments the next one covers (t, t_next]. */
static FmuStatus begin_record(FmuInstance *instance, ModelData *d, double t_s)
{
    if (d->cfg.input != GF_SINS_INPUT_INCREMENTS) {
        const gf_status st = gf_ins_step(&d->filter, t_s, d->gyro_rad_s, d->accel_m_s2, 0, NULL,
                                         NULL, NULL);
        if (st != GF_OK) {
            fmu_log_error(instance, "t = %.9g s: the first sample after the alignment was refused (%s)",
                          t_s, gf_status_string(st));
            return FMU_ERROR;
        }
    }
    d->started = 1;
    publish(d);
    return FMU_OK;
}

/* One doStep of the alignment phase: the sample (increments over (t_prev, t], or rates
 * at t) joins the sums; at the end of the phase the attitude from their means starts the
 * filter at t (rates: with this sample as the record's first). */
static FmuStatus align_step(FmuInstance *instance, ModelData *d, double t_s, size_t n_meas,
                            const gf_ins_meas *meas)
{
    const int increments = d->cfg.input == GF_SINS_INPUT_INCREMENTS;
    const double *gyro = increments ? d->dtheta_rad : d->gyro_rad_s;
    const double *accel = increments ? d->dv_m_s : d->accel_m_s2;
    /* the sample's checks first: a refused step changes no model data */
    if (!gf_all_finite(gyro, 3) || !gf_all_finite(accel, 3)) {
        fmu_log_error(instance, "t = %.9g s: IMU input holds NaN or Inf (alignment phase)", t_s);
        return FMU_ERROR;
    }
    if (increments && d->align_have_t && !(t_s - d->align_t_prev_s > 0.0)) {
        fmu_log_error(instance, "t = %.9g s: the time did not advance (alignment phase)", t_s);
        return FMU_ERROR;
    }
    for (size_t j = 0; j < n_meas; ++j)   /* not used while aligning: reported as stale */
        record_update(d, meas[j].type, GF_INS_REJECTED_STALE, NAN, meas[j].t_s);
    d->n_unused += n_meas;
    if (!increments || d->align_have_t) {
        const double dt = t_s - d->align_t_prev_s;
        const double k = increments ? 1.0 / dt : 1.0;
        double f[3], w[3];
        gf_v3_scale(accel, k, f);
        gf_v3_scale(gyro, k, w);
        const double fn = gf_v3_norm(f);
        gf_v3_add(d->align_f_sum, f, d->align_f_sum);
        gf_v3_add(d->align_w_sum, w, d->align_w_sum);
        d->align_fn_sum += fn;
        d->align_fn2_sum += fn * fn;
        d->align_wn_sum += gf_v3_norm(w);
        d->align_n++;
    }
    d->align_have_t = 1;
    d->align_t_prev_s = t_s;
    publish(d);
    if (d->align_n < 1 || t_s - d->align_t0_s < d->align_time_s - 1e-9 * fmax(1.0, fabs(t_s)))
        return FMU_OK;
    const double n = (double)d->align_n;
    const double fm = d->align_fn_sum / n;
    const double sd = sqrt(fmax(0.0, d->align_fn2_sum / n - fm * fm)), wm = d->align_wn_sum / n;
    if (sd > ALIGN_MAX_ACCEL_STD_M_S2 || wm > ALIGN_MAX_RATE_RAD_S) {
        fmu_log_error(instance, "t = %.9g s: motion during the alignment phase (std of |f| %g m/s2, "
                      "limit %g; mean |w| %g rad/s, limit %g): the vehicle must be at rest for "
                      "align_time = %g s, or give q0 and set align_time = 0", t_s, sd,
                      ALIGN_MAX_ACCEL_STD_M_S2, wm, ALIGN_MAX_RATE_RAD_S, d->align_time_s);
        return FMU_ERROR;
    }
    double f_mean[3], w_mean[3], q[4];
    gf_v3_scale(d->align_f_sum, 1.0 / n, f_mean);
    gf_v3_scale(d->align_w_sum, 1.0 / n, w_mean);
    const double zero[3] = {0.0, 0.0, 0.0};
    if (d->align_heading == 1) {
        /* levelling only; the heading comes from the travel (travel_step) */
        if (gf_ins_level_align(f_mean, q) != GF_OK) {
            fmu_log_error(instance, "t = %.9g s: no levelling from the alignment phase (mean |f| "
                          "%g m/s2 must be near g, and the body's forward axis y must not be "
                          "vertical)", t_s, gf_v3_norm(f_mean));
            return FMU_ERROR;
        }
        /* the rate at rest is the gyro bias (the Earth rate, below the bias of gyros that
         * cannot gyrocompass, is left in), as alignment.align_static_then_gnss does */
        StartPoint s = start_point(d, q, zero);
        memcpy(s.sensors, w_mean, sizeof w_mean);
        if (start_filter_at(instance, d, t_s, &s) != FMU_OK || begin_record(instance, d, t_s) != FMU_OK)
            return FMU_ERROR;
        d->align_travel = 1;   /* aligning stays 1 */
        fmu_log_info(instance, "t = %.9g s: levelled (roll %.3f deg, pitch %.3f deg); heading "
                     "from the first GNSS velocity above %g m/s", t_s,
                     d->euler_rad[2] * 180.0 / GF_PI, d->euler_rad[1] * 180.0 / GF_PI,
                     d->align_min_speed_m_s);
        publish(d);
        return FMU_OK;
    }
    if (gf_ins_coarse_align(f_mean, w_mean, q) != GF_OK) {
        fmu_log_error(instance, "t = %.9g s: no attitude from the alignment phase (mean |f| %g "
                      "m/s2; the rate must not be parallel to the specific force: the gyros must "
                      "see the Earth rate)", t_s, gf_v3_norm(f_mean));
        return FMU_ERROR;
    }
    if (start_filter_with(instance, d, t_s, q, zero) != FMU_OK)
        return FMU_ERROR;
    d->aligning = 0;
    if (begin_record(instance, d, t_s) != FMU_OK)
        return FMU_ERROR;
    publish(d);
    return FMU_OK;
}

/* align_heading = 1 after the phase at rest: the filter (levelled, heading 0, no
 * measurement updates: they are reported stale) mechanizes until a GNSS epoch with a
 * velocity faster than align_min_speed. At that epoch (valid at t_m, delivered with the
 * sample at t) the mechanized attitude at t is turned about the vertical so that the
 * body's forward axis y points along the GNSS velocity (heading atan2(vE, vN)), the
 * velocity is the GNSS velocity, the position the antenna's less the lever arm (C_b^n
 * gnss_lever_arm) moved on by v (t - t_m), and the filter restarts there with std0_* and
 * the heading 1-sigma sqrt(align_travel_std^2 + s^2), s = the direction 1-sigma of the
 * GNSS velocity, sqrt(vN^2 sE^2 + vE^2 sN^2) / (vE^2 + vN^2). The epoch is used up by the
 * start (not applied as an update). A failure there restores d (one copy per run). */

/* The filter's step without measurements (NHC / ZUPT, if configured, are heading-free). */
static FmuStatus mechanize(FmuInstance *instance, ModelData *d, double t_s)
{
    gf_ins_innovation entries[LOG_MAX];
    gf_ins_log log = {LOG_MAX, 0, 0, entries};
    if (ins_fmu_step(instance, &d->filter, t_s, d->dtheta_rad, d->dv_m_s, d->gyro_rad_s, d->accel_m_s2, 0, NULL,
                     &log) != GF_OK)
        return FMU_ERROR;
    for (size_t i = 0; i < log.count; ++i)
        record_update(d, entries[i].type, entries[i].status, entries[i].nis, entries[i].t_s);
    return FMU_OK;
}

static FmuStatus travel_end(FmuInstance *instance, ModelData *d, double t_s,
                            const gf_ins_meas *pos, const gf_ins_meas *vel);

static FmuStatus travel_step(FmuInstance *instance, ModelData *d, double t_s, size_t n_meas,
                             const gf_ins_meas *meas)
{
    const gf_ins_meas *pos = NULL, *vel = NULL;
    for (size_t j = 0; j < n_meas; ++j) {
        if (meas[j].type == GF_INS_MEAS_GNSS_POS)
            pos = &meas[j];
        else if (meas[j].type == GF_INS_MEAS_GNSS_VEL)
            vel = &meas[j];
    }
    if (pos && vel && hypot(vel->z[0], vel->z[1]) > d->align_min_speed_m_s)
        return travel_end(instance, d, t_s, pos, vel);
    if (mechanize(instance, d, t_s) != FMU_OK)
        return FMU_ERROR;
    for (size_t j = 0; j < n_meas; ++j)
        record_update(d, meas[j].type, GF_INS_REJECTED_STALE, NAN, meas[j].t_s);
    d->n_unused += n_meas;
    publish(d);
    return FMU_OK;
}

static FmuStatus travel_end(FmuInstance *instance, ModelData *d, double t_s,
                            const gf_ins_meas *pos, const gf_ins_meas *vel)
{
    if (!(fabs(pos->z[0]) < GF_HALF_PI * (89.0 / 90.0))) {
        fmu_log_error(instance, "t = %.9g s: the GNSS epoch that would give the heading is at "
                      "latitude %g rad: the filter needs |lat| below 89 deg", t_s, pos->z[0]);
        return FMU_ERROR;
    }
    const ModelData saved = *d;
    if (mechanize(instance, d, t_s) != FMU_OK) {
        *d = saved;
        return FMU_ERROR;
    }
    const gf_ins_filter *f = &d->filter;
    StartPoint s;
    double euler[3], lever_n[3];
    memcpy(s.q_bn, f->nav.q_bn, sizeof s.q_bn);
    gf_quat_to_euler(s.q_bn, euler);
    const double ve = vel->z[0], vn = vel->z[1], sp2 = ve * ve + vn * vn;
    const double psi_rad = atan2(ve, vn);
    gf_ins_rotate_heading(s.q_bn, NULL, psi_rad - euler[0]);
    const double s_dir = sqrt(vn * vn * vel->std[0] * vel->std[0] +
                              ve * ve * vel->std[1] * vel->std[1]) / sp2;
    s.heading_std_rad = hypot(d->align_travel_std_rad, s_dir);
    memcpy(s.v_n_m_s, vel->z, sizeof s.v_n_m_s);
    memcpy(s.sensors, f->sensors, sizeof s.sensors);
    gf_q_rotate(s.q_bn, d->cfg.gnss_lever_arm_m, lever_n);
    const double dt = t_s - pos->t_s;
    double dp[3];   /* IMU position - antenna position at t_m, then moved on to t (m, ENU) */
    for (int i = 0; i < 3; ++i)
        dp[i] = s.v_n_m_s[i] * dt - lever_n[i];
    gf_earth e;
    if (gf_earth_update(&e, pos->z[0], pos->z[2], NULL, 1.0) != GF_OK) {
        *d = saved;
        fmu_log_error(instance, "t = %.9g s: GNSS height %g m is absurd", t_s, pos->z[2]);
        return FMU_ERROR;
    }
    s.lat_rad = pos->z[0] + dp[1] / (e.R_M_m + pos->z[2]);
    s.lon_rad = pos->z[1] + dp[0] / ((e.R_N_m + pos->z[2]) * e.cos_lat);
    s.h_m = pos->z[2] + dp[2];
    if (start_filter_at(instance, d, t_s, &s) != FMU_OK || begin_record(instance, d, t_s) != FMU_OK) {
        *d = saved;
        return FMU_ERROR;
    }
    d->aligning = 0;
    d->align_travel = 0;
    fmu_log_info(instance, "t = %.9g s: heading from the GNSS direction of travel at %.9g s "
                 "(%.3g m/s): %.2f deg, 1-sigma %.2f deg (turned by %.2f deg); alignment done",
                 t_s, pos->t_s, sqrt(sp2), d->euler_rad[0] * 180.0 / GF_PI,
                 s.heading_std_rad * 180.0 / GF_PI, (psi_rad - euler[0]) * 180.0 / GF_PI);
    publish(d);
    return FMU_OK;
}

FmuStatus model_exit_initialization(FmuInstance *instance, ModelData *d, double start_time_s)
{
    return fmu_nav_exit_initialization(instance, d, start_time_s, start_filter);
}

/* One measurement input group: valid flag, time, and where the values sit. */
static int take_time(FmuInstance *instance, const char *what, int32_t valid, double t_m,
                     double t_s, double *t_use)
{
    if (valid < 0) {
        fmu_log_error(instance, "t = %.9g s: input %s_valid = %d must be >= 0", t_s, what,
                      (int)valid);
        return 0;
    }
    if (!isfinite(t_m)) {
        fmu_log_error(instance, "t = %.9g s: %s_valid = %d but %s_time_s = %g is not finite",
                      t_s, what, (int)valid, what, t_m);
        return 0;
    }
    *t_use = t_m;
    if (t_m > t_s + 1e-9) {
        if (t_m - t_s <= 1e-9 * fmax(1.0, fabs(t_s))) {
            *t_use = t_s; /* the master's clock rounding (glue tolerance) */
        } else {
            fmu_log_error(instance, "t = %.9g s: %s measurement valid at %s_time_s = %.9g s, "
                          "after the IMU sample it was delivered with: deliver a measurement in "
                          "the step whose sample time reaches its time of validity", t_s, what,
                          what, t_m);
            return 0;
        }
    }
    return 1;
}

static int values_ok(FmuInstance *instance, double t_s, const char *names, const double *z,
                     const double *std, int m)
{
    if (!gf_all_finite(z, (size_t)m) || !all_positive(std, m)) {
        if (m == 3)
            fmu_log_error(instance, "t = %.9g s: inputs %s: values must be finite and std > 0 "
                          "(got [%g, %g, %g], std [%g, %g, %g])", t_s, names, z[0], z[1], z[2],
                          std[0], std[1], std[2]);
        else
            fmu_log_error(instance, "t = %.9g s: inputs %s: the value must be finite and the "
                          "std > 0 (got %g, std %g)", t_s, names, z[0], std[0]);
        return 0;
    }
    return 1;
}

/* The measurements delivered with this step, validated and sorted by time; 0 on a
 * refused input (logged). */
static int gather(FmuInstance *instance, const ModelData *d, double t_s, gf_ins_meas *meas,
                  size_t *n_meas)
{
    size_t n = 0;
    double t_m = 0.0;
    if (d->gnss_valid) {
        if (!take_time(instance, "gnss", d->gnss_valid, d->gnss_time_s, t_s, &t_m))
            return 0;
        const double pos[3] = {d->gnss_lat_rad, d->gnss_lon_rad, d->gnss_h_m};
        if (!values_ok(instance, t_s, "GNSS gnss_lat_rad, gnss_lon_rad, gnss_h_m, gnss_pos_std_m",
                       pos, d->gnss_pos_std_m, 3))
            return 0;
        if (!(fabs(d->gnss_lat_rad) < GF_HALF_PI)) {
            fmu_log_error(instance, "t = %.9g s: input gnss_lat_rad = %g is outside (-pi/2, pi/2)",
                          t_s, d->gnss_lat_rad);
            return 0;
        }
        meas[n] = (gf_ins_meas){GF_INS_MEAS_GNSS_POS, t_m, {pos[0], pos[1], pos[2]},
                                {d->gnss_pos_std_m[0], d->gnss_pos_std_m[1], d->gnss_pos_std_m[2]},
                                {0.0, 0.0, 0.0}};
        ++n;
        if (d->gnss_vel_valid != 0 && d->gnss_vel_valid != 1) {
            fmu_log_error(instance, "t = %.9g s: input gnss_vel_valid = %d must be 0 or 1", t_s,
                          (int)d->gnss_vel_valid);
            return 0;
        }
        if (d->gnss_vel_valid) {
            if (!values_ok(instance, t_s, "GNSS gnss_vel_enu_m_s, gnss_vel_std_m_s",
                           d->gnss_vel_enu_m_s, d->gnss_vel_std_m_s, 3))
                return 0;
            const double *v = d->gnss_vel_enu_m_s, *s = d->gnss_vel_std_m_s;
            meas[n++] = (gf_ins_meas){GF_INS_MEAS_GNSS_VEL, t_m, {v[0], v[1], v[2]},
                                      {s[0], s[1], s[2]}, {0.0, 0.0, 0.0}};
        }
    }
    if (d->baro_valid) {
        if (!take_time(instance, "baro", d->baro_valid, d->baro_time_s, t_s, &t_m) ||
            !values_ok(instance, t_s, "barometer baro_h_m, baro_std_m", &d->baro_h_m,
                       &d->baro_std_m, 1))
            return 0;
        meas[n++] = (gf_ins_meas){GF_INS_MEAS_BARO, t_m, {d->baro_h_m, 0.0, 0.0},
                                  {d->baro_std_m, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    }
    if (d->odo_valid) {
        if (!take_time(instance, "odo", d->odo_valid, d->odo_time_s, t_s, &t_m) ||
            !values_ok(instance, t_s, "odometer odo_speed_m_s, odo_std_m_s", &d->odo_speed_m_s,
                       &d->odo_std_m_s, 1))
            return 0;
        meas[n++] = (gf_ins_meas){GF_INS_MEAS_ODO, t_m, {d->odo_speed_m_s, 0.0, 0.0},
                                  {d->odo_std_m_s, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    }
    /* stable insertion sort by time: kinds in the order above at equal times */
    for (size_t i = 1; i < n; ++i) {
        const gf_ins_meas x = meas[i];
        size_t j = i;
        while (j > 0 && meas[j - 1].t_s > x.t_s) {
            meas[j] = meas[j - 1];
            --j;
        }
        meas[j] = x;
    }
    *n_meas = n;
    return 1;
}

FmuStatus model_do_step(FmuInstance *instance, ModelData *d, double t_s, double h_s)
{
    FmuStatus skipped;
    if (fmu_nav_skip_step(instance, d, t_s + h_s, start_filter, &skipped))
        return skipped; /* inputs ignored; navigation (re)started for the next sample */
    gf_ins_meas meas[N_MEAS_MAX];
    size_t n_meas = 0;
    if (!gather(instance, d, t_s, meas, &n_meas))
        return FMU_ERROR;
    if (d->aligning)
        return d->align_travel ? travel_step(instance, d, t_s, n_meas, meas)
                               : align_step(instance, d, t_s, n_meas, meas);
    gf_ins_filter *f = &d->filter;
    const int increments = f->cfg.input == GF_SINS_INPUT_INCREMENTS;
    if (increments && !d->started) {
        /* no increment ends at the filter's start: what arrives now is valid at or before
         * it, stale as the core would call it */
        for (size_t j = 0; j < n_meas; ++j)
            record_update(d, meas[j].type, GF_INS_REJECTED_STALE, NAN, meas[j].t_s);
        d->n_unused += n_meas;
        d->started = 1;
        publish(d);
        return FMU_OK;
    }
    gf_ins_innovation entries[LOG_MAX];
    gf_ins_log log = {LOG_MAX, 0, 0, entries};
    if (ins_fmu_step(instance, f, t_s, d->dtheta_rad, d->dv_m_s, d->gyro_rad_s, d->accel_m_s2, n_meas,
                     meas, &log) != GF_OK)
        return FMU_ERROR;
    for (size_t i = 0; i < log.count; ++i)
        record_update(d, entries[i].type, entries[i].status, entries[i].nis, entries[i].t_s);
    d->started = 1;
    publish(d);
    return FMU_OK;
}

const char *ins_gnss_state_problem(const ModelData *d)
{
    const gf_ins_filter *f = &d->filter;
    if (d->skip_steps < 0 || d->skipped < 0 || d->skipped > d->skip_steps)
        return "skip_steps / skipped out of range";
    if (d->started != 0 && d->started != 1)
        return "started is not 0 or 1";
    if ((d->aligning & ~1) || (d->align_have_t & ~1) || d->align_n < 0 || (d->align_travel & ~1))
        return "alignment phase flags or count out of range";
    if (d->align_heading != 0 && d->align_heading != 1)
        return "align_heading is not 0 or 1";
    if (d->align_travel && !(d->aligning && d->align_heading == 1 && d->started == 1))
        return "align_travel is set outside the alignment from the travel";
    if (f->n_states == 0 && f->kf.n == 0 && f->ukf_w.n == 0)
        return NULL; /* not started yet (before exitInitializationMode) */
    int32_t n = 0;
    if (gf_ins_state_count(&f->cfg, &n) != GF_OK)
        return "filter configuration out of range (an enumeration, flag or limit)";
    if (f->n_states != n)
        return "filter n_states does not match its configuration";
    int32_t next = GF_INS_BASE_STATES, idx_sg = -1, idx_sa = -1, idx_baro = -1, idx_odo = -1;
    if (f->cfg.scale_factors) {
        idx_sg = next;
        idx_sa = next + 3;
        next += 6;
    }
    if (f->cfg.baro_bias)
        idx_baro = next++;
    if (f->cfg.odometer_scale)
        idx_odo = next++;
    const int32_t idx_mount = f->cfg.odometer_mount ? next : -1;
    if (f->idx_sg != idx_sg || f->idx_sa != idx_sa || f->idx_baro != idx_baro ||
        f->idx_odo != idx_odo || f->idx_mount != idx_mount)
        return "filter idx_* do not match its configuration";
    if (f->kf.n != (size_t)n || f->ukf_w.n != (size_t)n)
        return "filter kf.n or ukf_w.n differs from n_states";
    const gf_sins_config *sc = &f->nav.cfg;
    if (sc->input != f->cfg.input || sc->coning != f->cfg.coning ||
        sc->vertical != GF_SINS_VERTICAL_FREE || sc->earth != GF_SINS_EARTH_WGS84)
        return "mechanization configuration differs from the filter's";
    if ((f->have_sample & ~1) || (f->standstill & ~1) || (f->nav.have_prev & ~1) ||
        (f->nav0.have_prev & ~1))
        return "a flag of the filter is not 0 or 1";
    return NULL;
}

/* The model's own floats: NULL when the parameters, the outputs and the alignment sums a
 * restored state carries are finite (the monitoring outputs nis and update_time may be
 * NaN: "no update of this kind yet"; never infinite), else what is wrong. The inputs are
 * the master's to set before the next doStep (which checks them). */
static const char *model_floats_problem(const ModelData *d)
{
    const double *params[] = {d->q0, d->v0_m_s, &d->lat0_rad, &d->lon0_rad, &d->h0_m, d->sensors0,
                              d->std0_vel_m_s, d->std0_pos_m, d->std0_att_rad, d->std0_gyro_bias_rad_s,
                              d->std0_accel_bias_m_s2, d->std0_gyro_scale, d->std0_accel_scale,
                              &d->std0_baro_bias_m, &d->std0_odo_scale, d->std0_odo_mount_rad,
                              &d->align_time_s, &d->align_min_speed_m_s, &d->align_travel_std_rad};
    const size_t n_params[] = {4, 3, 1, 1, 1, GF_INS_N_SENSORS, 3, 3, 3, 3, 3, 3, 3, 1, 1, 2, 1, 1, 1};
    for (size_t i = 0; i < sizeof n_params / sizeof n_params[0]; ++i)
        if (!gf_all_finite(params[i], n_params[i]))
            return "a parameter (initial state, its 1-sigma or the alignment settings) is not finite";
    const double *outs[] = {d->q_bn, d->euler_rad, d->v_n_m_s, &d->lat_rad, &d->lon_rad, &d->h_m,
                            &d->nav_time_s, d->std9, d->sensors};
    const size_t n_outs[] = {4, 3, 3, 1, 1, 1, 1, 9, GF_INS_N_SENSORS};
    for (size_t i = 0; i < sizeof n_outs / sizeof n_outs[0]; ++i)
        if (!gf_all_finite(outs[i], n_outs[i]))
            return "an output (attitude, velocity, position, time, 1-sigma, sensor estimates) is not finite";
    for (int k = 0; k < INS_FMU_KINDS; ++k)
        if (isinf(d->nis[k]) || isinf(d->update_time_s[k]))
            return "a monitoring output (nis, update_time) is infinite";
    const double *sums[] = {&d->align_t0_s, &d->align_t_prev_s, d->align_f_sum, d->align_w_sum,
                            &d->align_fn_sum, &d->align_fn2_sum, &d->align_wn_sum};
    const size_t n_sums[] = {1, 1, 3, 3, 1, 1, 1};
    for (size_t i = 0; i < sizeof n_sums / sizeof n_sums[0]; ++i)
        if (!gf_all_finite(sums[i], n_sums[i]))
            return "the alignment phase's sums are not finite";
    return NULL;
}

const char *model_validate_state(const ModelData *d)
{
    const char *why = ins_gnss_state_problem(d);
    if (!why)
        why = model_floats_problem(d);
    if (why)
        return why;
    /* the whole filter as soon as it exists (exit initialization), not only once it has
     * a sample: a doStep may take it from there */
    const gf_ins_filter *f = &d->filter;
    const int exists = !(f->n_states == 0 && f->kf.n == 0 && f->ukf_w.n == 0);
    if (exists && gf_ins_filter_check(f) != GF_OK)
        return "the filter state (layout, indices, nominal state, covariance, floats) is invalid";
    return NULL;
}
