/* skip_steps.h — the navigators' skip_steps parameter (common/nav_params.py): the first
 * skip_steps doSteps ignore their inputs, for masters that pass no connected outputs
 * before the first step (fmpy's SSP simulator and container FMU start them at 0). */
#ifndef FMU_SKIP_STEPS_H
#define FMU_SKIP_STEPS_H

#include <math.h>
#include <stdint.h>

#include "fmu_model.h"

/* In exitInitializationMode: checks the parameter and resets the count. */
static inline int fmu_skip_steps_reset(FmuInstance *instance, int32_t skip_steps, int32_t *skipped)
{
    *skipped = 0;
    if (skip_steps < 0) {
        fmu_log_error(instance, "parameter skip_steps = %d must be >= 0", (int)skip_steps);
        return 0;
    }
    return 1;
}

/* In doStep: 1 if this step's inputs are to be ignored; then *restart is 1 when it was
 * the last ignored one, so navigation starts at the next communication point. */
static inline int fmu_skip_this_step(int32_t skip_steps, int32_t *skipped, int *restart)
{
    if (*skipped >= skip_steps)
        return 0;
    ++*skipped;
    *restart = *skipped == skip_steps;
    return 1;
}

/* For the navigators' model_validate_state: NULL if the stepping counters a doStep
 * branches on are consistent (0 <= skipped <= skip_steps, started 0 or 1, the previous
 * step finite and >= 0), else why not. */
static inline const char *fmu_nav_counters_invalid(int32_t skip_steps, int32_t skipped,
                                                   int32_t started, double previous_step_s)
{
    if (skip_steps < 0 || skipped < 0 || skipped > skip_steps)
        return "skip_steps / skipped are not 0 <= skipped <= skip_steps";
    if (started != 0 && started != 1)
        return "started is not 0 or 1";
    if (!(previous_step_s >= 0.0) || !isfinite(previous_step_s))
        return "previous_step_s is not finite and >= 0";
    return NULL;
}

#endif /* FMU_SKIP_STEPS_H */
