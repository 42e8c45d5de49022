/* model.h — data of the gyro-free navigator FMUs (variables: spec.py). The layout is a
 * compile-time choice: GFNAV_LAYOUT 0 cube6, 1 qin9, 2 twelve. */
#ifndef GFNAV_MODEL_H
#define GFNAV_MODEL_H

#include <stdint.h>

#include "gyrofree/gf_gfnav.h"

typedef struct ModelData {
    /* parameters */
    double lever_arm_m;
    int32_t strategy, earth, vertical_mode;
    double accel_noise_m_s2, omega_init_rad_s[3], flat_gravity_m_s2, hold_height_m, baro_tau_s;
    double q0[4], v0_m_s[3], lat0_rad, lon0_rad, h0_m, pos0_m[3];
    int32_t skip_steps;
    /* inputs (A holds up to 12 outputs; the layout uses the first n) */
    double A_m_s2[12], h_ext_m;
    /* outputs */
    double q_bn[4], euler_rad[3], v_n_m_s[3], lat_rad, lon_rad, h_m, pos_m[3];
    double omega_rad_s[3], f_m_s2[3], nav_time_s;
    int32_t flags;
    /* internal */
    double previous_step_s;
    int32_t started;
    int32_t skipped;          /* doSteps ignored so far (skip_steps) */
    gf_gfnav_state nav;
} ModelData;

#endif /* GFNAV_MODEL_H */
