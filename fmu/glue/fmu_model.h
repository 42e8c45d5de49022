/* fmu_model.h — the contract between the generic FMI glue and a model.
 *
 * A model (fmu/models/<name>/) provides:
 *   model.h        typedef struct ModelData {...} ModelData;  pointer-free, fixed arrays
 *   model_spec.py  its variables (fmugen.py makes model_vars.h and modelDescription.xml)
 *   model.c        model_exit_initialization() and model_do_step() below
 * and knows nothing about FMI: no FMI header, type or status appears in it.
 * The glue (fmu_common.c, fmi2_glue.c, fmi3_glue.c) knows nothing about navigation.
 */
#ifndef FMU_MODEL_H
#define FMU_MODEL_H

#include <stddef.h>
#include <stdint.h>

typedef enum FmuStatus {
    FMU_OK = 0,
    FMU_WARNING = 1,
    FMU_DISCARD = 2,
    FMU_ERROR = 3,
    FMU_FATAL = 4
} FmuStatus;

typedef enum FmuType { FMU_TYPE_FLOAT64, FMU_TYPE_INT32 } FmuType;
typedef enum FmuCausality {
    FMU_CAUSALITY_INDEPENDENT,
    FMU_CAUSALITY_PARAMETER,
    FMU_CAUSALITY_INPUT,
    FMU_CAUSALITY_OUTPUT
} FmuCausality;
typedef enum FmuVariability {
    FMU_VARIABILITY_FIXED,
    FMU_VARIABILITY_TUNABLE,
    FMU_VARIABILITY_DISCRETE,
    FMU_VARIABILITY_CONTINUOUS
} FmuVariability;

/* One row of a generated variable table: where a value reference lives in ModelData. */
typedef struct FmuVariable {
    unsigned int value_reference;
    FmuType type;
    FmuCausality causality;
    FmuVariability variability;
    size_t offset;       /* byte offset of the first element in ModelData */
    size_t count;        /* number of elements (1 for scalars) */
    const char *name;
} FmuVariable;

typedef struct FmuInstance FmuInstance;

/* Logging for models: printf-style, delivered through the importer's logger callback.
 * Errors are always delivered; information only while debug logging is on. */
void fmu_log_error(FmuInstance *instance, const char *format, ...)
    __attribute__((format(printf, 2, 3)));
void fmu_log_info(FmuInstance *instance, const char *format, ...)
    __attribute__((format(printf, 2, 3)));

struct ModelData;

/* Called when leaving initialization mode, after parameters and start values are set:
 * validates the parameters and initialises the model. Log the reason of an error. */
FmuStatus model_exit_initialization(FmuInstance *instance, struct ModelData *data,
                                    double start_time_s);

/* One communication step from t_s to t_s + h_s. data holds the inputs set for t_s.
 * On an error the model must leave data unchanged (the glue keeps the last good
 * outputs readable). */
FmuStatus model_do_step(FmuInstance *instance, struct ModelData *data, double t_s, double h_s);

/* Checks model data that did not come from this instance's own steps: a deserialized
 * FMU state, or a state object handed back to setFMUState. The glue calls it for states
 * of an initialized model (step mode or terminated; before initialization the data are
 * parameters that exitInitializationMode checks, and the internals are rebuilt there).
 * It must check every field that sizes a copy, indexes an array or selects a branch in
 * model_do_step (and the core structs it hands to the core, with their gf_*_check), so
 * that no content of data can make a step read or write out of bounds. Returns NULL if
 * the data may be used, else a static text naming the first bad field. */
const char *model_validate_state(const struct ModelData *data);

#endif /* FMU_MODEL_H */
