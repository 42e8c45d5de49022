/* model.h — data of the transfer-alignment FMU (variables: model_spec.py). Pointer-free:
 * an FMU state is a copy of it (the filter gf_ins_filter included). */
#ifndef TRANSFER_ALIGN_MODEL_H
#define TRANSFER_ALIGN_MODEL_H

#include <stdint.h>

#include "est/gf_ins_gnss.h"

/* the master kinds of the monitoring outputs: velocity, attitude, position */
#define TA_FMU_KINDS 3

typedef struct ModelData {
    /* parameters */
    gf_ins_config cfg;                   /* the filter configuration, field by field */
    double q0[4], v0_m_s[3], lat0_rad, lon0_rad, h0_m;
    double sensors0[GF_INS_N_SENSORS];
    double std0_vel_m_s[3], std0_pos_m[3], std0_att_rad[3];
    double std0_gyro_bias_rad_s[3], std0_accel_bias_m_s2[3];
    double std0_gyro_scale[3], std0_accel_scale[3];
    double std0_mount_rad[3], std0_lever_m[3], std0_time_offset_s;
    int32_t skip_steps;
    int32_t start_from_master;           /* 1: q0 = the master's attitude turned by the mounting */
    int32_t match_attitude, match_position;
    double master_interval_s;            /* epochs closer than this to the last used: left out */
    double master_vel_std_m_s[3], master_att_std_rad[3], master_pos_std_m[3];
    /* inputs */
    double dtheta_rad[3], dv_m_s[3], gyro_rad_s[3], accel_m_s2[3];
    int32_t master_valid;
    double master_time_s, master_euler_rad[3], master_vel_m_s[3];
    double master_lat_rad, master_lon_rad, master_h_m, master_rate_rad_s[3];
    /* outputs */
    double q_bn[4], euler_rad[3], v_n_m_s[3], lat_rad, lon_rad, h_m, nav_time_s;
    double std9[9], sensors[GF_INS_N_SENSORS];
    double mount_rad[3], mount_std_rad[3], lever_m[3], lever_std_m[3];
    double time_offset_s, time_offset_std_s, flexure_rad[3];
    int32_t n_imu, n_updates, n_rejected;
    double nis[TA_FMU_KINDS];
    int32_t update_status[TA_FMU_KINDS], update_count[TA_FMU_KINDS];
    /* internal */
    int32_t started;      /* 1 once the filter has a sample (increments: none at its start) */
    int32_t skipped;      /* doSteps ignored so far (skip_steps) */
    uint64_t n_unused;    /* master epochs delivered before the first increment: stale */
    double last_master_t_s; /* the last master epoch used (-inf before the first) */
    gf_ins_filter filter;
} ModelData;

#endif /* TRANSFER_ALIGN_MODEL_H */
