/* fmi3_glue.c — FMI 3.0 co-simulation entry points, translated to fmu_instance.h.
 * Model-independent: compiled once per model with that model's model_vars.h.
 * Model exchange, scheduled execution, clocks and event mode are not offered; their
 * entry points exist (importers resolve every symbol) and return fmi3Error. */
#include <string.h>

#include "fmi3Functions.h"
#include "fmu_instance.h"

#define N_VARS3 (sizeof kFmi3Variables / sizeof kFmi3Variables[0])
#define INSTANCE ((FmuInstance *)instance)
#define CHECK(mask, name)                                                                    \
    do {                                                                                     \
        if (!instance)                                                                       \
            return fmi3Error;                                                                \
        if (!fmu_check_mode(INSTANCE, (mask), name))                                          \
            return fmi3Error;                                                                \
    } while (0)

static void send_log3(FmuInstance *instance, FmuStatus status, const char *category,
                      const char *message)
{
    fmi3LogMessageCallback log = (fmi3LogMessageCallback)instance->log_function;
    if (log)
        log(instance->environment, (fmi3Status)status, category, message);
}

static fmi3Status unsupported(fmi3Instance instance, const char *name)
{
    if (instance)
        fmu_log_error(INSTANCE, "%s is not supported by this co-simulation FMU", name);
    return fmi3Error;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    CHECK(FMU_MODE_ANY, "fmi3SetDebugLogging");
    (void)nCategories;
    (void)categories;
    INSTANCE->logging_on = loggingOn ? 1 : 0;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible;
    (void)loggingOn;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "this FMU supports co-simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)resourcePath; (void)visible; (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    if (eventModeUsed) {
        if (logMessage)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "event mode is not supported (hasEventMode=\"false\")");
        return NULL;
    }
    return fmu_instance_new(instanceName, instantiationToken, send_log3,
                            (void (*)(void))logMessage, instanceEnvironment, loggingOn ? 1 : 0);
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible;
    (void)loggingOn; (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "this FMU supports co-simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { fmu_instance_free(INSTANCE); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    CHECK(FMU_MODE_INSTANTIATED, "fmi3EnterInitializationMode");
    (void)toleranceDefined;
    (void)tolerance;
    return (fmi3Status)fmu_enter_initialization(INSTANCE, stopTimeDefined, startTime, stopTime);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    CHECK(FMU_MODE_INITIALIZATION, "fmi3ExitInitializationMode");
    return (fmi3Status)fmu_exit_initialization(INSTANCE);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterEventMode");
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    CHECK(FMU_MODE_STEP | FMU_MODE_ERROR, "fmi3Terminate");
    return (fmi3Status)fmu_terminate(INSTANCE);
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    CHECK(FMU_MODE_ANY, "fmi3Reset");
    return (fmi3Status)fmu_reset(INSTANCE);
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues)
{
    if (!instance)
        return fmi3Error;
    return (fmi3Status)fmu_get(INSTANCE, kFmi3Variables, N_VARS3, 1, FMU_TYPE_FLOAT64,
                               valueReferences, nValueReferences, values, nValues,
                               "fmi3GetFloat64");
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int32 values[], size_t nValues)
{
    if (!instance)
        return fmi3Error;
    return (fmi3Status)fmu_get(INSTANCE, kFmi3Variables, N_VARS3, 1, FMU_TYPE_INT32,
                               valueReferences, nValueReferences, values, nValues,
                               "fmi3GetInt32");
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    if (!instance)
        return fmi3Error;
    return (fmi3Status)fmu_set(INSTANCE, kFmi3Variables, N_VARS3, FMU_TYPE_FLOAT64,
                               valueReferences, nValueReferences, values, nValues,
                               "fmi3SetFloat64");
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int32 values[], size_t nValues)
{
    if (!instance)
        return fmi3Error;
    return (fmi3Status)fmu_set(INSTANCE, kFmi3Variables, N_VARS3, FMU_TYPE_INT32,
                               valueReferences, nValueReferences, values, nValues,
                               "fmi3SetInt32");
}

/* Types this FMU has no variables of: an empty request succeeds, any other fails. */
#define NO_VARIABLES_GET(Name, T)                                                            \
    fmi3Status fmi3Get##Name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                             T values[], size_t nValues)                                     \
    {                                                                                        \
        (void)vr; (void)values; (void)nValues;                                               \
        return nvr == 0 ? fmi3OK : unsupported(instance, "fmi3Get" #Name " (no such variables)"); \
    }
#define NO_VARIABLES_SET(Name, T)                                                            \
    fmi3Status fmi3Set##Name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                             const T values[], size_t nValues)                               \
    {                                                                                        \
        (void)vr; (void)values; (void)nValues;                                               \
        return nvr == 0 ? fmi3OK : unsupported(instance, "fmi3Set" #Name " (no such variables)"); \
    }
NO_VARIABLES_GET(Float32, fmi3Float32)
NO_VARIABLES_GET(Int8, fmi3Int8)
NO_VARIABLES_GET(UInt8, fmi3UInt8)
NO_VARIABLES_GET(Int16, fmi3Int16)
NO_VARIABLES_GET(UInt16, fmi3UInt16)
NO_VARIABLES_GET(UInt32, fmi3UInt32)
NO_VARIABLES_GET(Int64, fmi3Int64)
NO_VARIABLES_GET(UInt64, fmi3UInt64)
NO_VARIABLES_GET(Boolean, fmi3Boolean)
NO_VARIABLES_GET(String, fmi3String)
NO_VARIABLES_SET(Float32, fmi3Float32)
NO_VARIABLES_SET(Int8, fmi3Int8)
NO_VARIABLES_SET(UInt8, fmi3UInt8)
NO_VARIABLES_SET(Int16, fmi3Int16)
NO_VARIABLES_SET(UInt16, fmi3UInt16)
NO_VARIABLES_SET(UInt32, fmi3UInt32)
NO_VARIABLES_SET(Int64, fmi3Int64)
NO_VARIABLES_SET(UInt64, fmi3UInt64)
NO_VARIABLES_SET(Boolean, fmi3Boolean)
NO_VARIABLES_SET(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    (void)vr; (void)valueSizes; (void)values; (void)nValues;
    return nvr == 0 ? fmi3OK : unsupported(instance, "fmi3GetBinary (no such variables)");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    (void)vr; (void)valueSizes; (void)values; (void)nValues;
    return nvr == 0 ? fmi3OK : unsupported(instance, "fmi3SetBinary (no such variables)");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[])
{
    (void)vr; (void)values;
    return nvr == 0 ? fmi3OK : unsupported(instance, "fmi3GetClock (no clocks)");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[])
{
    (void)vr; (void)values;
    return nvr == 0 ? fmi3OK : unsupported(instance, "fmi3SetClock (no clocks)");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference; (void)nDependencies;
    return unsupported(instance, "fmi3GetNumberOfVariableDependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    (void)dependent; (void)elementIndicesOfDependent; (void)independents;
    (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)nDependencies;
    return unsupported(instance, "fmi3GetVariableDependencies");
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    CHECK(FMU_MODE_ANY, "fmi3GetFMUState");
    return (fmi3Status)fmu_state_get(INSTANCE, FMUState);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    CHECK(FMU_MODE_ANY, "fmi3SetFMUState");
    return (fmi3Status)fmu_state_set(INSTANCE, FMUState);
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    CHECK(FMU_MODE_ANY, "fmi3FreeFMUState");
    return (fmi3Status)fmu_state_free(INSTANCE, FMUState);
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    CHECK(FMU_MODE_ANY, "fmi3SerializedFMUStateSize");
    (void)FMUState;
    if (!size)
        return fmi3Error;
    *size = fmu_state_serialized_size();
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size)
{
    CHECK(FMU_MODE_ANY, "fmi3SerializeFMUState");
    return (fmi3Status)fmu_state_serialize(INSTANCE, FMUState, serializedState, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState)
{
    CHECK(FMU_MODE_ANY, "fmi3DeserializeFMUState");
    return (fmi3Status)fmu_state_deserialize(INSTANCE, serializedState, size, FMUState);
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
    (void)sensitivity; (void)nSensitivity;
    return unsupported(instance, "fmi3GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
    (void)sensitivity; (void)nSensitivity;
    return unsupported(instance, "fmi3GetAdjointDerivative");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterConfigurationMode (no structural parameters)");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3ExitConfigurationMode (no structural parameters)");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{
    (void)vr; (void)nvr; (void)intervals; (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalDecimal (no clocks)");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions; (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalFraction (no clocks)");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[])
{
    (void)vr; (void)nvr; (void)shifts;
    return unsupported(instance, "fmi3GetShiftDecimal (no clocks)");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3GetShiftFraction (no clocks)");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[])
{
    (void)vr; (void)nvr; (void)intervals;
    return unsupported(instance, "fmi3SetIntervalDecimal (no clocks)");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3SetIntervalFraction (no clocks)");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[])
{
    (void)vr; (void)nvr; (void)shifts;
    return unsupported(instance, "fmi3SetShiftDecimal (no clocks)");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3SetShiftFraction (no clocks)");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EvaluateDiscreteStates");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    (void)discreteStatesNeedUpdate; (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged; (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined; (void)nextEventTime;
    return unsupported(instance, "fmi3UpdateDiscreteStates (no event mode)");
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterContinuousTimeMode (model exchange)");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return unsupported(instance, "fmi3CompletedIntegratorStep (model exchange)");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return unsupported(instance, "fmi3SetTime (model exchange)");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates; (void)nContinuousStates;
    return unsupported(instance, "fmi3SetContinuousStates (model exchange)");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives; (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStateDerivatives (model exchange)");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators)
{
    (void)eventIndicators; (void)nEventIndicators;
    return unsupported(instance, "fmi3GetEventIndicators (model exchange)");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates; (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStates (model exchange)");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    (void)nominals; (void)nContinuousStates;
    return unsupported(instance, "fmi3GetNominalsOfContinuousStates (model exchange)");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    CHECK(FMU_MODE_ANY, "fmi3GetNumberOfEventIndicators");
    if (!nEventIndicators)
        return fmi3Error;
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    CHECK(FMU_MODE_ANY, "fmi3GetNumberOfContinuousStates");
    if (!nContinuousStates)
        return fmi3Error;
    *nContinuousStates = 0;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    /* without event mode the FMU is in step mode after initialization already */
    CHECK(FMU_MODE_STEP, "fmi3EnterStepMode");
    return fmi3OK;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)vr; (void)nvr; (void)orders; (void)values; (void)nValues;
    return unsupported(instance, "fmi3GetOutputDerivatives");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!instance)
        return fmi3Error;
    fmi3Status status = (fmi3Status)fmu_do_step(INSTANCE, currentCommunicationPoint,
                                                 communicationStepSize, "fmi3DoStep");
    if (eventHandlingNeeded)
        *eventHandlingNeeded = fmi3False;
    if (terminateSimulation)
        *terminateSimulation = fmi3False;
    if (earlyReturn)
        *earlyReturn = fmi3False;
    if (lastSuccessfulTime)
        *lastSuccessfulTime = INSTANCE->s.time_s;
    return status;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference; (void)activationTime;
    return unsupported(instance, "fmi3ActivateModelPartition (scheduled execution)");
}
