/* model.h — data of the vehicle FMU (variables: model_spec.py). */
#ifndef VEHICLE_MODEL_H
#define VEHICLE_MODEL_H

#include <stdint.h>

#include "gyrofree/gf_array.h"
#include "nav/gf_imu_error.h"
#include "sim/gf_aiding.h"
#include "sim/gf_noise.h"
#include "sim/gf_rot.h"
#include "sim/gf_vehicle.h"
#include "imu_params.h"

#define VEHICLE_ARRAY_MAX 12

typedef struct ModelData {
    /* parameters */
    gf_vehicle_profile profile;           /* start values; segments from the seg_* arrays */
    int32_t n_segments, drive, imu_errors, array_layout;
    double seg_duration_s[GF_VEHICLE_MAX_SEGMENTS], seg_dspeed_m_s[GF_VEHICLE_MAX_SEGMENTS];
    double seg_dheading_rate_rad_s[GF_VEHICLE_MAX_SEGMENTS];
    double seg_dheading_rad[GF_VEHICLE_MAX_SEGMENTS];
    double command_time_s, lever_arm_m, array_bias_m_s2[VEHICLE_ARRAY_MAX];
    FmuImuParams imu_params;
    int32_t noise, noise_seed;
    gf_imu_noise noise_params;            /* SI, the conventions of gfins_fmi.ImuNoise */
    double array_noise_m_s2;
    gf_aiding_params aiding;              /* GNSS, barometer, odometer (gf_aiding.h) */
    int32_t rotation, rot_n, rot_repeat;  /* the rotating IMU (gf_rot.h) */
    int32_t rot_base_axis[GF_ROT_MAX_SEGMENTS], rot_imu_axis[GF_ROT_MAX_SEGMENTS];
    double rot_base_angle_rad[GF_ROT_MAX_SEGMENTS], rot_imu_angle_rad[GF_ROT_MAX_SEGMENTS];
    double rot_move_s[GF_ROT_MAX_SEGMENTS], rot_ramp_s[GF_ROT_MAX_SEGMENTS];
    double rot_dwell_s[GF_ROT_MAX_SEGMENTS];
    /* inputs */
    double speed_cmd_m_s, heading_rate_cmd_rad_s;
    /* outputs */
    gf_vehicle_sample out;                /* truth (and ideal sensors) */
    double gyro_rad_s[3], accel_m_s2[3], dtheta_rad[3], dv_m_s[3];
    double A_m_s2[VEHICLE_ARRAY_MAX];
    gf_aiding_output aiding_out;          /* newest epochs and how many the last step delivered */
    double gimbal_rad[2], q_mb[4];        /* the mechanism at the outputs' time */
    /* internal */
    gf_vehicle_state vehicle;
    double active_cmd[2];                 /* command being followed (drive = 1); NaN: none */
    gf_imu_errors imu;
    double imu_w_true_prev[3];            /* the IMU's true rate at the previous sample: the
                                             mean angular acceleration over a step */
    gf_imu_noise_state imu_noise;         /* the generators are state: restored with it */
    gf_rng array_rng;
    gf_array_geometry array;
    gf_aiding_sim aiding_sim;             /* its generators and vehicle copy: restored with it */
    gf_rot_state rot;                     /* rotation = 1: the schedule, derived at start */
} ModelData;

#endif /* VEHICLE_MODEL_H */
