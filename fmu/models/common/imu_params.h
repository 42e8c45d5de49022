/* imu_params.h — the IMU error model as FMU parameters (shared by the SINS FMU, which
 * compensates it, and the vehicle FMU, which applies it). The variables are listed once
 * in common/nav_params.py (imu_error_parameters); FMI-agnostic, like every model file. */
#ifndef FMU_IMU_PARAMS_H
#define FMU_IMU_PARAMS_H

#include <string.h>

#include "nav/gf_imu_error.h"

typedef struct FmuImuParams {
    double gyro_bias_rad_s[3], gyro_scale[3], gyro_misalign_rad[9];
    double accel_bias_m_s2[3], accel_scale[3], accel_misalign_rad[9], accel_k2_s2_m[3];
    double lever_arm_m[3];            /* positions along the own axes (the diagonal) */
    double lever_arm_transverse_m[6]; /* r_xy, r_xz, r_yx, r_yz, r_zx, r_zy */
    double accel_delay_s;
} FmuImuParams;

/* Builds the error model (reference temperature only) and checks it; returns NULL or
 * the name and range of the offending parameter. */
static inline const char *fmu_imu_errors_build(const FmuImuParams *p, gf_imu_errors *e)
{
    static const char *const field_names[] = {"a non-finite value", "gyro_scale (|s| < 0.5)",
        "gyro_misalign (|N| < 0.1 rad, zero diagonal)", "accel_scale (|s| < 0.5)",
        "accel_misalign (|N| < 0.1 rad, zero diagonal)", "accel_k2 (|K2| * 1000 m/s2 < 0.1)",
        "lever_arm, lever_arm_transverse (|r| < 1 m)", "temperature order",
        "gyro_bias (|b| < 50 rad/s)", "accel_bias (|b| < 1000 m/s2)", "accel_delay (|d| < 1 s)"};
    memset(e, 0, sizeof *e);
    memcpy(e->g_bias_rad_s, p->gyro_bias_rad_s, sizeof e->g_bias_rad_s);
    memcpy(e->g_scale, p->gyro_scale, sizeof e->g_scale);
    memcpy(e->g_misalign_rad, p->gyro_misalign_rad, sizeof e->g_misalign_rad);
    memcpy(e->a_bias_m_s2, p->accel_bias_m_s2, sizeof e->a_bias_m_s2);
    memcpy(e->a_scale, p->accel_scale, sizeof e->a_scale);
    memcpy(e->a_misalign_rad, p->accel_misalign_rad, sizeof e->a_misalign_rad);
    memcpy(e->a_k2_s2_m, p->accel_k2_s2_m, sizeof e->a_k2_s2_m);
    static const int off_diagonal[6] = {1, 2, 3, 5, 6, 7};
    for (int i = 0; i < 3; ++i)
        e->a_lever_pos_m[4 * i] = p->lever_arm_m[i];
    for (int k = 0; k < 6; ++k)
        e->a_lever_pos_m[off_diagonal[k]] = p->lever_arm_transverse_m[k];
    e->a_delay_s = p->accel_delay_s;
    int bad = 0;
    if (gf_imu_errors_check(e, &bad) != GF_OK)
        return field_names[bad >= 0 && bad <= 10 ? bad : 0];
    return NULL;
}

#endif /* FMU_IMU_PARAMS_H */
