/* model.h — data of the integrated-navigator FMU (variables: model_spec.py). Pointer-free:
 * an FMU state is a copy of it (the filter gf_ins_filter included). */
#ifndef INS_GNSS_MODEL_H
#define INS_GNSS_MODEL_H

#include <stdint.h>

#include "est/gf_ins_gnss.h"

/* kinds of the per-kind monitoring outputs: GF_INS_MEAS_GNSS_POS .. GF_INS_MEAS_ZARU */
#define INS_FMU_KINDS 7

typedef struct ModelData {
    /* parameters */
    gf_ins_config cfg;                   /* the filter configuration, field by field */
    double q0[4], v0_m_s[3], lat0_rad, lon0_rad, h0_m;
    double sensors0[GF_INS_N_SENSORS];
    double std0_vel_m_s[3], std0_pos_m[3], std0_att_rad[3];
    double std0_gyro_bias_rad_s[3], std0_accel_bias_m_s2[3];
    double std0_gyro_scale[3], std0_accel_scale[3], std0_baro_bias_m, std0_odo_scale;
    double std0_odo_mount_rad[2];
    int32_t skip_steps;
    double align_time_s;                 /* > 0: an alignment phase at rest first (s) */
    int32_t align_heading;               /* 0: gyrocompassing; 1: heading from GNSS travel */
    double align_min_speed_m_s, align_travel_std_rad;
    /* inputs */
    double dtheta_rad[3], dv_m_s[3], gyro_rad_s[3], accel_m_s2[3];
    int32_t gnss_valid, gnss_vel_valid;
    double gnss_time_s, gnss_lat_rad, gnss_lon_rad, gnss_h_m, gnss_vel_enu_m_s[3];
    double gnss_pos_std_m[3], gnss_vel_std_m_s[3];
    int32_t baro_valid;
    double baro_time_s, baro_h_m, baro_std_m;
    int32_t odo_valid;
    double odo_time_s, odo_speed_m_s, odo_std_m_s;
    /* outputs */
    double q_bn[4], euler_rad[3], v_n_m_s[3], lat_rad, lon_rad, h_m, nav_time_s;
    double std9[9], sensors[GF_INS_N_SENSORS];
    int32_t n_imu, n_updates, n_rejected, standstill;
    double nis[INS_FMU_KINDS], update_time_s[INS_FMU_KINDS];
    int32_t update_status[INS_FMU_KINDS], update_count[INS_FMU_KINDS];
    int32_t aligning;                    /* 1 during the alignment phase */
    /* internal */
    int32_t started;      /* 1 once the filter has a sample (increments: none at its start) */
    int32_t skipped;      /* doSteps ignored so far (skip_steps) */
    uint64_t n_unused;    /* measurements delivered before the first increment: stale */
    /* alignment phase: sums over the samples at rest since align_t0_s */
    int32_t align_n, align_have_t;
    double align_t0_s, align_t_prev_s, align_f_sum[3], align_w_sum[3];
    double align_fn_sum, align_fn2_sum, align_wn_sum;
    /* align_heading = 1: 1 after the phase at rest (levelled, heading 0) until a GNSS
     * epoch faster than align_min_speed gives the heading; the filter mechanizes meanwhile */
    int32_t align_travel;
    gf_ins_filter filter;
} ModelData;

/* The checks of a restored state: NULL when the fields that size or index arrays (the
 * filter's n_states, idx_*, kf.n, ukf_w.n, its configuration's enumerations and the
 * model's counters) are consistent, else what is wrong. For the glue's state-validation
 * hook (model_validate_state). */
const char *ins_gnss_state_problem(const ModelData *d);

#endif /* INS_GNSS_MODEL_H */
