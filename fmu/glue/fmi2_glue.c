/* fmi2_glue.c — FMI 2.0 co-simulation entry points, translated to fmu_instance.h.
 * Model-independent: compiled once per model with that model's model_vars.h. */
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_instance.h"

#define N_VARS2 (sizeof kFmi2Variables / sizeof kFmi2Variables[0])

/* The FMI 2.0 logger takes a printf format. The message goes in as that format with
 * every '%' doubled: a logger that formats prints it verbatim, and so does one that
 * does not (fmpy's plain Python logger), up to the doubled '%'. */
static void send_log2(FmuInstance *instance, FmuStatus status, const char *category,
                      const char *message)
{
    const fmi2CallbackLogger logger = (fmi2CallbackLogger)instance->log_function;
    if (!logger)
        return;
    char escaped[2048];
    size_t j = 0;
    for (size_t i = 0; message[i] && j + 2 < sizeof escaped; ++i) {
        if (message[i] == '%')
            escaped[j++] = '%';
        escaped[j++] = message[i];
    }
    escaped[j] = '\0';
    logger(instance->environment, instance->instance_name, (fmi2Status)status, category,
           escaped);
}

#define INSTANCE ((FmuInstance *)c)
#define CHECK(mask, name)                                                                    \
    do {                                                                                     \
        if (!c)                                                                              \
            return fmi2Error;                                                                \
        if (!fmu_check_mode(INSTANCE, (mask), name))                                          \
            return fmi2Error;                                                                \
    } while (0)

static fmi2Status unsupported(fmi2Component c, const char *name)
{
    if (c)
        fmu_log_error(INSTANCE, "%s is not supported by this co-simulation FMU", name);
    return fmi2Error;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    CHECK(FMU_MODE_ANY, "fmi2SetDebugLogging");
    (void)nCategories;
    (void)categories;
    INSTANCE->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->logger)
        return NULL; /* the standard requires a logger; without one nothing can be reported */
    if (fmuType != fmi2CoSimulation) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                          "logStatusError", "this FMU supports co-simulation only");
        return NULL;
    }
    /* the logger and environment are copied: the importer's struct need not outlive
     * this call */
    return fmu_instance_new(instanceName, fmuGUID, send_log2, (void (*)(void))functions->logger,
                            functions->componentEnvironment, loggingOn ? 1 : 0);
}

void fmi2FreeInstance(fmi2Component c) { fmu_instance_free(INSTANCE); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    CHECK(FMU_MODE_INSTANTIATED, "fmi2SetupExperiment");
    (void)toleranceDefined;
    (void)tolerance;
    /* kept until fmi2EnterInitializationMode, which FMI 2.0 requires next */
    INSTANCE->s.start_time_s = startTime;
    INSTANCE->s.stop_time_defined = stopTimeDefined ? 1 : 0;
    INSTANCE->s.stop_time_s = stopTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    CHECK(FMU_MODE_INSTANTIATED, "fmi2EnterInitializationMode");
    return (fmi2Status)fmu_enter_initialization(INSTANCE, INSTANCE->s.stop_time_defined,
                                                INSTANCE->s.start_time_s,
                                                INSTANCE->s.stop_time_s);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    CHECK(FMU_MODE_INITIALIZATION, "fmi2ExitInitializationMode");
    return (fmi2Status)fmu_exit_initialization(INSTANCE);
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    CHECK(FMU_MODE_STEP | FMU_MODE_ERROR, "fmi2Terminate");
    return (fmi2Status)fmu_terminate(INSTANCE);
}

fmi2Status fmi2Reset(fmi2Component c)
{
    CHECK(FMU_MODE_ANY, "fmi2Reset");
    return (fmi2Status)fmu_reset(INSTANCE);
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    if (!c)
        return fmi2Error;
    return (fmi2Status)fmu_get(INSTANCE, kFmi2Variables, N_VARS2, 0, FMU_TYPE_FLOAT64, vr, nvr,
                               value, nvr, "fmi2GetReal");
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    if (!c)
        return fmi2Error;
    _Static_assert(sizeof(fmi2Integer) == sizeof(int32_t), "fmi2Integer is 32 bits");
    return (fmi2Status)fmu_get(INSTANCE, kFmi2Variables, N_VARS2, 0, FMU_TYPE_INT32, vr, nvr,
                               value, nvr, "fmi2GetInteger");
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetBoolean (no Boolean variables)");
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetString (no String variables)");
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    if (!c)
        return fmi2Error;
    return (fmi2Status)fmu_set(INSTANCE, kFmi2Variables, N_VARS2, FMU_TYPE_FLOAT64, vr, nvr,
                               value, nvr, "fmi2SetReal");
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    if (!c)
        return fmi2Error;
    return (fmi2Status)fmu_set(INSTANCE, kFmi2Variables, N_VARS2, FMU_TYPE_INT32, vr, nvr,
                               value, nvr, "fmi2SetInteger");
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetBoolean (no Boolean variables)");
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetString (no String variables)");
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    CHECK(FMU_MODE_ANY, "fmi2GetFMUstate");
    return (fmi2Status)fmu_state_get(INSTANCE, FMUstate);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    CHECK(FMU_MODE_ANY, "fmi2SetFMUstate");
    return (fmi2Status)fmu_state_set(INSTANCE, FMUstate);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    CHECK(FMU_MODE_ANY, "fmi2FreeFMUstate");
    return (fmi2Status)fmu_state_free(INSTANCE, FMUstate);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    CHECK(FMU_MODE_ANY, "fmi2SerializedFMUstateSize");
    (void)FMUstate;
    if (!size)
        return fmi2Error;
    *size = fmu_state_serialized_size();
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    CHECK(FMU_MODE_ANY, "fmi2SerializeFMUstate");
    return (fmi2Status)fmu_state_serialize(INSTANCE, FMUstate, (uint8_t *)serializedState, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    CHECK(FMU_MODE_ANY, "fmi2DeSerializeFMUstate");
    return (fmi2Status)fmu_state_deserialize(INSTANCE, (const uint8_t *)serializedState, size,
                                             FMUstate);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown;
    (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!c)
        return fmi2Error;
    return (fmi2Status)fmu_do_step(INSTANCE, currentCommunicationPoint, communicationStepSize,
                                   "fmi2DoStep");
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    return unsupported(c, "fmi2CancelStep (doStep always completes synchronously)");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s; (void)value;
    return unsupported(c, "fmi2GetStatus (doStep always completes synchronously)");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    if (!c || !value)
        return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = INSTANCE->s.time_s;
        return fmi2OK;
    }
    return unsupported(c, "fmi2GetRealStatus for this status kind");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s; (void)value;
    return unsupported(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    (void)s; (void)value;
    return unsupported(c, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s; (void)value;
    return unsupported(c, "fmi2GetStringStatus");
}
