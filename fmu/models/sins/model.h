/* model.h — data of the strapdown navigator FMU (variables: model_spec.py). */
#ifndef SINS_MODEL_H
#define SINS_MODEL_H

#include <stdint.h>

#include "nav/gf_biquad.h"
#include "nav/gf_imu_error.h"
#include "nav/gf_sins.h"
#include "sim/gf_rot.h"
#include "imu_params.h"

typedef struct ModelData {
    /* parameters */
    int32_t input_mode, coning, vertical_mode;
    double hold_height_m, baro_tau_s, max_rate_rad_s, max_specific_force_m_s2;
    double q0[4], v0_m_s[3], lat0_rad, lon0_rad, h0_m;
    int32_t imu_comp, lowpass_sections;
    FmuImuParams imu_params;
    double lowpass_sos[48];
    int32_t skip_steps, rotating;
    /* inputs */
    double dtheta_rad[3], dv_m_s[3], gyro_rad_s[3], accel_m_s2[3], h_ext_m, gimbal_rad[2];
    /* outputs */
    double q_bn[4], euler_rad[3], v_n_m_s[3], lat_rad, lon_rad, h_m, nav_time_s;
    double q_vehicle[4], euler_vehicle_rad[3];
    /* internal */
    double previous_step_s;   /* communication step that ended at this sample: its dt */
    int32_t started;          /* 1 once a doStep has been taken */
    int32_t skipped;          /* doSteps ignored so far (skip_steps) */
    gf_sins_state nav;
    gf_imu_errors imu;        /* built from the parameters when imu_comp = 1 */
    double imu_w_prev_rad_s[3]; /* the last compensated rate (angular acceleration of the */
    int32_t imu_have_prev;      /* lever arms across the axes: gf_imu_compensate_step) */
    gf_biquad lowpass;        /* 6 channels: gyro x y z, accel x y z */
} ModelData;

#endif /* SINS_MODEL_H */
