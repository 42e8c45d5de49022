/* model.c — the 9-accelerometer solver as an FMU model: FMI-agnostic, calls the C core.
 *
 * Sampling: doStep(t, h) solves the input sample set for time t; the outputs read
 * after the step describe time t (the usual one-step lag of a sampled block in
 * co-simulation). The interval since the previous sample, over which omega_dot is
 * integrated, is the previous communication step size: variable steps are handled, and
 * with a fixed step h the FMU computes exactly what gf9_solve does with dt = h. */
#include <math.h>
#include <string.h>

#include "fmu_model.h"
#include "base/gf_math.h"
#include "model.h"

FmuStatus model_exit_initialization(FmuInstance *instance, ModelData *d, double start_time_s)
{
    (void)start_time_s;
    const gf_status status = gf9_init(&d->solver, d->lever_arm_m, d->omega_init_rad_s);
    if (status != GF_OK) {
        /* which parameter: the lever arm alone (no omega_init) decides */
        if (gf9_init(&d->solver, d->lever_arm_m, NULL) != GF_OK)
            fmu_log_error(instance, "parameter l = %g m: the lever arm must be finite and "
                          ">= 1e-6 m", d->lever_arm_m);
        else
            fmu_log_error(instance, "parameter omega_init = [%g, %g, %g] rad/s must be finite "
                          "with |omega_init| <= %d rad/s", d->omega_init_rad_s[0],
                          d->omega_init_rad_s[1], d->omega_init_rad_s[2], GF9_MAX_RATE_RAD_S);
        return FMU_ERROR;
    }
    memset(d->f_m_s2, 0, sizeof d->f_m_s2);
    memcpy(d->omega_rad_s, d->omega_init_rad_s, sizeof d->omega_rad_s);
    memset(d->omega_dot_rad_s2, 0, sizeof d->omega_dot_rad_s2);
    for (int k = 0; k < 3; ++k)
        d->omega_sq_rad2_s2[k] = d->omega_init_rad_s[k] * d->omega_init_rad_s[k];
    d->flags = 0;
    d->previous_step_s = 0.0;
    return FMU_OK;
}

FmuStatus model_do_step(FmuInstance *instance, ModelData *d, double t_s, double h_s)
{
    gf9_output out;
    gf9_state next = d->solver;
    const gf_status status = gf9_step(&next, d->A_m_s2, d->previous_step_s, &out);
    if (status != GF_OK) {
        if (status == GF_ERR_NONFINITE_INPUT) {
            for (int i = 0; i < 9; ++i)
                if (!isfinite(d->A_m_s2[i])) {
                    fmu_log_error(instance, "input A[%d] = %g at t = %.9g s is not finite; "
                                  "the outputs keep the last good sample", i + 1, d->A_m_s2[i],
                                  t_s);
                    break;
                }
        } else {
            fmu_log_error(instance, "solver step at t = %.9g s failed: %s", t_s,
                          gf_status_string(status));
        }
        return FMU_ERROR;
    }
    d->solver = next;
    memcpy(d->f_m_s2, out.f_m_s2, sizeof d->f_m_s2);
    memcpy(d->omega_rad_s, out.omega_rad_s, sizeof d->omega_rad_s);
    memcpy(d->omega_dot_rad_s2, out.omega_dot_rad_s2, sizeof d->omega_dot_rad_s2);
    memcpy(d->omega_sq_rad2_s2, out.omega_sq_rad2_s2, sizeof d->omega_sq_rad2_s2);
    d->flags = (int32_t)out.flags;
    d->previous_step_s = h_s;
    return FMU_OK;
}

const char *model_validate_state(const ModelData *d)
{
    if (gf9_state_check(&d->solver) != GF_OK)
        return "the solver state (lever arm, reference rate, angular acceleration) is invalid";
    if (!(d->previous_step_s >= 0.0) || !isfinite(d->previous_step_s))
        return "previous_step_s is not finite and >= 0";
    if (!gf_all_finite(d->f_m_s2, 3) || !gf_all_finite(d->omega_rad_s, 3) ||
        !gf_all_finite(d->omega_dot_rad_s2, 3) || !gf_all_finite(d->omega_sq_rad2_s2, 3))
        return "an output (specific force, rate, angular acceleration, squared rates) is not finite";
    if (!isfinite(d->lever_arm_m) || !gf_all_finite(d->omega_init_rad_s, 3))
        return "a parameter (lever arm, initial rate) is not finite";
    return NULL;
}
