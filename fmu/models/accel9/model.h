/* model.h — data of the 9-accelerometer solver FMU (variables: model_spec.py). */
#ifndef ACCEL9_MODEL_H
#define ACCEL9_MODEL_H

#include <stdint.h>

#include "gyrofree/gf9.h"

typedef struct ModelData {
    /* parameters */
    double lever_arm_m;
    double omega_init_rad_s[3];
    /* input */
    double A_m_s2[9];
    /* outputs: the solution of the sample set at the last doStep's start time */
    double f_m_s2[3];
    double omega_rad_s[3];
    double omega_dot_rad_s2[3];
    double omega_sq_rad2_s2[3];
    int32_t flags;
    /* internal */
    double previous_step_s;   /* communication step that led to this sample = its dt */
    gf9_state solver;
} ModelData;

#endif /* ACCEL9_MODEL_H */
