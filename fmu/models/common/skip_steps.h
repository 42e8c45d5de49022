/* skip_steps.h — the navigators' skip_steps parameter (common/nav_params.py): the first
 * skip_steps doSteps ignore their inputs, for masters that pass no connected outputs
 * before the first step (fmpy's SSP simulator and container FMU start them at 0).
 * Included by a navigator's model.c: its ModelData (model.h) has the int32_t fields
 * skip_steps and skipped. */
#ifndef FMU_SKIP_STEPS_H
#define FMU_SKIP_STEPS_H

#include <math.h>
#include <stdint.h>

#include "fmu_model.h"
#include "model.h"

/* In exitInitializationMode (fmu_nav_exit_initialization): checks the parameter and
 * resets the count. */
static inline int fmu_skip_steps_reset(FmuInstance *instance, int32_t skip_steps, int32_t *skipped)
{
    *skipped = 0;
    if (skip_steps < 0) {
        fmu_log_error(instance, "parameter skip_steps = %d must be >= 0", (int)skip_steps);
        return 0;
    }
    return 1;
}

/* In doStep (fmu_nav_skip_step): 1 if this step's inputs are to be ignored; then *restart is 1 when it was
 * the last ignored one, so navigation starts at the next communication point. */
static inline int fmu_skip_this_step(int32_t skip_steps, int32_t *skipped, int *restart)
{
    if (*skipped >= skip_steps)
        return 0;
    ++*skipped;
    *restart = *skipped == skip_steps;
    return 1;
}

/* A navigator's start: (re)initialises the navigation in d at start_time_s, logging
 * why not on an error (it may have written d in part). */
typedef FmuStatus (*FmuNavStart)(FmuInstance *instance, ModelData *d, double start_time_s);

/* A navigator's exitInitializationMode: checks skip_steps, resets the count and starts
 * the navigation at start_time_s (used at once unless skip_steps > 0). */
static inline FmuStatus fmu_nav_exit_initialization(FmuInstance *instance, ModelData *d,
                                                    double start_time_s, FmuNavStart start)
{
    if (!fmu_skip_steps_reset(instance, d->skip_steps, &d->skipped))
        return FMU_ERROR;
    return start(instance, d, start_time_s);
}

/* First thing in a navigator's doStep from t_s to t_next_s = t_s + h_s: 1 if this step's
 * inputs are ignored (one of the first skip_steps), and then *status is the step's
 * status: FMU_OK, or after the last ignored step that of start(instance, d, t_next_s),
 * navigation starting at the next communication point. A failed start changes no model
 * data: the start writes the navigator in place (found by fuzzing: a refused start left
 * a half-initialised solver), so d is restored from a copy (once per run). 0 if the step
 * navigates. */
static inline int fmu_nav_skip_step(FmuInstance *instance, ModelData *d, double t_next_s,
                                    FmuNavStart start, FmuStatus *status)
{
    int restart = 0;
    if (!fmu_skip_this_step(d->skip_steps, &d->skipped, &restart))
        return 0;
    *status = FMU_OK;
    if (restart) {
        const ModelData saved = *d;
        *status = start(instance, d, t_next_s);
        if (*status != FMU_OK)
            *d = saved;
    }
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
