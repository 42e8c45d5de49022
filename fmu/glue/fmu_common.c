/* fmu_common.c — FMI-version-independent glue: see fmu_instance.h. */
#include "fmu_instance.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FMU_MESSAGE_MAX 1024

/* Serialized FMU state: this header, then the FmuSnapshot bytes (fmu_instance.h). The
 * token ties a state to the exact interface (and so ModelData layout) that wrote it;
 * the CRC-32 finds damaged bytes (format 1 had no CRC and is refused). */
#define FMU_STATE_MAGIC "GFINSFMU"
#define FMU_STATE_FORMAT 2u
typedef struct FmuStateHeader {
    char magic[8];
    uint32_t format;
    uint32_t snapshot_size;
    uint32_t crc32;           /* CRC-32 of the snapshot bytes */
    uint32_t reserved;        /* 0 */
    char token[48];
} FmuStateHeader;
_Static_assert(sizeof(FmuStateHeader) == 72, "serialized header layout (docs/fmu.md)");

/* CRC-32 of IEEE 802.3 (reflected polynomial 0xEDB88320, initial value and final xor
 * 0xFFFFFFFF; zlib's crc32, check value 0xCBF43926 for "123456789"), a byte at a time.
 * The table is made by the compiler from the polynomial: entry v is the CRC register
 * after shifting v through it 8 times (CRC_SHIFT is one shift: the polynomial is xored
 * in when the bit leaving is 1). */
#define CRC_SHIFT(c) (((c) >> 1) ^ (0xEDB88320u & (0u - ((c) & 1u))))
#define CRC_ENTRY(v)                                                                          \
    CRC_SHIFT(CRC_SHIFT(CRC_SHIFT(CRC_SHIFT(CRC_SHIFT(CRC_SHIFT(CRC_SHIFT(CRC_SHIFT((uint32_t)(v)))))))))
#define CRC_ROW4(v) CRC_ENTRY(v), CRC_ENTRY((v) + 1), CRC_ENTRY((v) + 2), CRC_ENTRY((v) + 3)
#define CRC_ROW16(v) CRC_ROW4(v), CRC_ROW4((v) + 4), CRC_ROW4((v) + 8), CRC_ROW4((v) + 12)
#define CRC_ROW64(v) CRC_ROW16(v), CRC_ROW16((v) + 16), CRC_ROW16((v) + 32), CRC_ROW16((v) + 48)
static const uint32_t kCrcTable[256] = {CRC_ROW64(0), CRC_ROW64(64), CRC_ROW64(128), CRC_ROW64(192)};

static uint32_t crc32_ieee(const uint8_t *p, size_t n)
{
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i)
        crc = (crc >> 8) ^ kCrcTable[(crc ^ p[i]) & 0xFFu];
    return crc ^ 0xFFFFFFFFu;
}

static const char *mode_name(uint32_t mode)
{
    switch (mode) {
    case FMU_MODE_INSTANTIATED: return "Instantiated";
    case FMU_MODE_INITIALIZATION: return "InitializationMode";
    case FMU_MODE_STEP: return "StepMode";
    case FMU_MODE_TERMINATED: return "Terminated";
    case FMU_MODE_ERROR: return "Error";
    }
    return "unknown";
}

static void vlog(FmuInstance *instance, FmuStatus status, const char *category,
                 const char *format, va_list args)
{
    if (!instance || !instance->send_log)
        return;
    if (status < FMU_ERROR && !instance->logging_on)
        return;
    char message[FMU_MESSAGE_MAX];
    vsnprintf(message, sizeof message, format, args);
    instance->send_log(instance, status, category, message);
}

void fmu_log(FmuInstance *instance, FmuStatus status, const char *category,
             const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog(instance, status, category, format, args);
    va_end(args);
}

void fmu_log_error(FmuInstance *instance, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog(instance, FMU_ERROR, "logStatusError", format, args);
    va_end(args);
}

void fmu_log_info(FmuInstance *instance, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog(instance, FMU_OK, "logEvents", format, args);
    va_end(args);
}

static void set_start(FmuInstance *instance)
{
    memset(&instance->s, 0, sizeof instance->s);
    instance->s.mode = FMU_MODE_INSTANTIATED;
    model_set_start_values(&instance->s.data);
}

FmuInstance *fmu_instance_new(const char *instance_name, const char *token,
                              FmuSendLog send_log, void (*log_function)(void),
                              void *environment, int logging_on)
{
    FmuInstance probe = {0};
    probe.instance_name = (char *)(instance_name ? instance_name : "?");
    probe.send_log = send_log;
    probe.log_function = log_function;
    probe.environment = environment;
    if (!instance_name || !instance_name[0]) {
        fmu_log_error(&probe, "instantiate: the instance name must not be empty");
        return NULL;
    }
    if (!token || strcmp(token, INSTANTIATION_TOKEN) != 0) {
        fmu_log_error(&probe,
                      "instantiate: token %s does not match this FMU's %s; the "
                      "modelDescription.xml and the binary come from different builds",
                      token ? token : "(null)", INSTANTIATION_TOKEN);
        return NULL;
    }
    FmuInstance *instance = calloc(1, sizeof *instance);
    char *name = malloc(strlen(instance_name) + 1);
    if (!instance || !name) {
        free(instance);
        free(name);
        fmu_log_error(&probe, "instantiate: out of memory");
        return NULL;
    }
    strcpy(name, instance_name);
    instance->instance_name = name;
    instance->send_log = send_log;
    instance->log_function = log_function;
    instance->environment = environment;
    instance->logging_on = logging_on;
    set_start(instance);
    return instance;
}

void fmu_instance_free(FmuInstance *instance)
{
    if (!instance)
        return;
    free(instance->instance_name);
    free(instance);
}

int fmu_check_mode(FmuInstance *instance, uint32_t allowed, const char *function)
{
    if (!instance)
        return 0;
    if (instance->s.mode & allowed)
        return 1;
    fmu_log_error(instance, "%s must not be called in mode %s", function,
                  mode_name(instance->s.mode));
    return 0;
}

FmuStatus fmu_reset(FmuInstance *instance)
{
    set_start(instance);
    return FMU_OK;
}

FmuStatus fmu_enter_initialization(FmuInstance *instance, int stop_time_defined,
                                   double start_time_s, double stop_time_s)
{
    if (!isfinite(start_time_s) || (stop_time_defined && !isfinite(stop_time_s))) {
        fmu_log_error(instance, "enterInitializationMode: start and stop time must be finite");
        return FMU_ERROR;
    }
    if (stop_time_defined && stop_time_s < start_time_s) {
        fmu_log_error(instance, "enterInitializationMode: stop time %g s is before start time %g s",
                      stop_time_s, start_time_s);
        return FMU_ERROR;
    }
    instance->s.start_time_s = start_time_s;
    instance->s.time_s = start_time_s;
    instance->s.stop_time_defined = stop_time_defined ? 1 : 0;
    instance->s.stop_time_s = stop_time_s;
    instance->s.mode = FMU_MODE_INITIALIZATION;
    return FMU_OK;
}

FmuStatus fmu_exit_initialization(FmuInstance *instance)
{
    FmuStatus status = model_exit_initialization(instance, &instance->s.data,
                                                 instance->s.start_time_s);
    if (status >= FMU_ERROR) {
        instance->s.mode = FMU_MODE_ERROR;
        return status;
    }
    instance->s.mode = FMU_MODE_STEP;
    fmu_log_info(instance, "initialized at t = %g s", instance->s.time_s);
    return status;
}

FmuStatus fmu_terminate(FmuInstance *instance)
{
    instance->s.mode = FMU_MODE_TERMINATED;
    fmu_log_info(instance, "terminated at t = %g s", instance->s.time_s);
    return FMU_OK;
}

/* Tolerance on communication points: masters compute t as start + k*h or as a
 * running sum; both agree with the FMU's own sum to far better than 1e-9 relative. */
static double time_tolerance(double t_s)
{
    return 1e-9 * fmax(1.0, fabs(t_s));
}

FmuStatus fmu_do_step(FmuInstance *instance, double t_s, double h_s, const char *function)
{
    if (!fmu_check_mode(instance, FMU_MODE_STEP, function))
        return FMU_ERROR;
    if (!isfinite(t_s) || !(h_s > 0.0) || !isfinite(h_s)) {
        fmu_log_error(instance, "%s: communication point %g s and step size %g s must be "
                      "finite and the step size > 0", function, t_s, h_s);
        return FMU_ERROR;
    }
    /* comparisons are written so that a NaN anywhere fails them */
    if (!(fabs(t_s - instance->s.time_s) <= time_tolerance(t_s))) {
        fmu_log_error(instance, "%s: communication point %.17g s differs from the FMU's time "
                      "%.17g s; to go back, restore an FMU state first", function, t_s,
                      instance->s.time_s);
        return FMU_ERROR;
    }
    if (instance->s.stop_time_defined &&
        !(t_s + h_s <= instance->s.stop_time_s + time_tolerance(instance->s.stop_time_s))) {
        fmu_log_error(instance, "%s: a step from %.9g s by %g s would pass the stop time "
                      "%.9g s", function, t_s, h_s, instance->s.stop_time_s);
        return FMU_ERROR;
    }
    FmuStatus status = model_do_step(instance, &instance->s.data, t_s, h_s);
    if (status >= FMU_ERROR) {
        instance->s.mode = FMU_MODE_ERROR;
        return status;
    }
    instance->s.time_s = t_s + h_s;
    return status;
}

static const FmuVariable *find_variable(FmuInstance *instance, const FmuVariable *table,
                                        size_t n_table, unsigned int vr, FmuType type,
                                        const char *function)
{
    /* value references are dense: row i has VR i + 1 (VR 0 is time) */
    if (vr >= 1 && vr <= n_table && table[vr - 1].value_reference == vr) {
        const FmuVariable *v = &table[vr - 1];
        if (v->type == type)
            return v;
        fmu_log_error(instance, "%s: variable %s (value reference %u) has another type",
                      function, v->name, vr);
        return NULL;
    }
    fmu_log_error(instance, "%s: unknown value reference %u", function, vr);
    return NULL;
}

static size_t type_size(FmuType type)
{
    return type == FMU_TYPE_FLOAT64 ? sizeof(double) : sizeof(int32_t);
}

FmuStatus fmu_get(FmuInstance *instance, const FmuVariable *table, size_t n_table,
                  int has_time, FmuType type, const unsigned int *vr, size_t n_vr,
                  void *values, size_t n_values, const char *function)
{
    if (!fmu_check_mode(instance, FMU_MODE_INITIALIZATION | FMU_MODE_STEP |
                        FMU_MODE_TERMINATED | FMU_MODE_ERROR, function))
        return FMU_ERROR;
    if (n_vr > 0 && (!vr || !values)) {
        fmu_log_error(instance, "%s: NULL value reference or value array", function);
        return FMU_ERROR;
    }
    const size_t size = type_size(type);
    size_t index = 0;
    for (size_t i = 0; i < n_vr; ++i) {
        if (has_time && vr[i] == 0 && type == FMU_TYPE_FLOAT64) {
            if (index + 1 > n_values)
                goto too_few;
            ((double *)values)[index++] = instance->s.time_s;
            continue;
        }
        const FmuVariable *v = find_variable(instance, table, n_table, vr[i], type, function);
        if (!v)
            return FMU_ERROR;
        if (index + v->count > n_values)
            goto too_few;
        memcpy((char *)values + index * size, (const char *)&instance->s.data + v->offset,
               v->count * size);
        index += v->count;
    }
    if (index != n_values) {
        fmu_log_error(instance, "%s: nValues = %zu but the variables have %zu values", function,
                      n_values, index);
        return FMU_ERROR;
    }
    return FMU_OK;
too_few:
    fmu_log_error(instance, "%s: nValues = %zu is too small for the variables requested",
                  function, n_values);
    return FMU_ERROR;
}

FmuStatus fmu_set(FmuInstance *instance, const FmuVariable *table, size_t n_table,
                  FmuType type, const unsigned int *vr, size_t n_vr, const void *values,
                  size_t n_values, const char *function)
{
    if (!fmu_check_mode(instance, FMU_MODE_INSTANTIATED | FMU_MODE_INITIALIZATION |
                        FMU_MODE_STEP, function))
        return FMU_ERROR;
    if (n_vr > 0 && (!vr || !values)) {
        fmu_log_error(instance, "%s: NULL value reference or value array", function);
        return FMU_ERROR;
    }
    const size_t size = type_size(type);
    /* validate the whole call first so that an error changes nothing */
    size_t index = 0;
    for (size_t i = 0; i < n_vr; ++i) {
        const FmuVariable *v = find_variable(instance, table, n_table, vr[i], type, function);
        if (!v)
            return FMU_ERROR;
        uint32_t allowed = 0;
        if (v->causality == FMU_CAUSALITY_INPUT)
            allowed = FMU_MODE_INSTANTIATED | FMU_MODE_INITIALIZATION | FMU_MODE_STEP;
        else if (v->causality == FMU_CAUSALITY_PARAMETER)
            allowed = v->variability == FMU_VARIABILITY_TUNABLE
                          ? (FMU_MODE_INSTANTIATED | FMU_MODE_INITIALIZATION | FMU_MODE_STEP)
                          : (FMU_MODE_INSTANTIATED | FMU_MODE_INITIALIZATION);
        if (!(instance->s.mode & allowed)) {
            if (allowed == 0)
                fmu_log_error(instance, "%s: variable %s is an output and cannot be set",
                              function, v->name);
            else
                fmu_log_error(instance, "%s: variable %s (a fixed parameter) cannot be set in "
                              "mode %s", function, v->name, mode_name(instance->s.mode));
            return FMU_ERROR;
        }
        index += v->count;
    }
    if (index != n_values) {
        fmu_log_error(instance, "%s: nValues = %zu but the variables have %zu values", function,
                      n_values, index);
        return FMU_ERROR;
    }
    index = 0;
    for (size_t i = 0; i < n_vr; ++i) {
        const FmuVariable *v = &table[vr[i] - 1];
        memcpy((char *)&instance->s.data + v->offset, (const char *)values + index * size,
               v->count * size);
        index += v->count;
    }
    return FMU_OK;
}

/* NULL if a snapshot may be used by this instance, else why not. The model data are
 * checked when the model has been initialized (step mode, terminated): before that they
 * are parameters, which exitInitializationMode checks and from which it rebuilds every
 * internal, and only the variable table reads them. */
/* A state saved before initialization holds what the master set (parameters, inputs) and
 * start values: its outputs must be their start values. A crafted state could carry any
 * bytes there (an infinite output), and the getters would return them (found by
 * fuzz_fmu_state: the model's own checks only apply once it is initialized). */
static const char *outputs_not_at_start(const ModelData *d)
{
    ModelData *start = malloc(sizeof *start);
    if (!start)
        return "it cannot be checked (out of memory)";
    memset(start, 0, sizeof *start);
    model_set_start_values(start);
    const char *why = NULL;
    for (size_t i = 0; i < sizeof kFmi2Variables / sizeof kFmi2Variables[0] && !why; ++i) {
        const FmuVariable *v = &kFmi2Variables[i];
        if (v->causality != FMU_CAUSALITY_OUTPUT)
            continue;
        const size_t bytes = v->count * (v->type == FMU_TYPE_FLOAT64 ? sizeof(double) : sizeof(int32_t));
        if (memcmp((const char *)d + v->offset, (const char *)start + v->offset, bytes) != 0)
            why = "an output differs from its start value before initialization";
    }
    free(start);
    return why;
}

static const char *snapshot_invalid(const FmuSnapshot *s)
{
    if (s->mode == 0 || (s->mode & ~FMU_MODE_ANY) || (s->mode & (s->mode - 1)))
        return "its mode is invalid";
    if (s->stop_time_defined != 0 && s->stop_time_defined != 1)
        return "its stop-time flag is not 0 or 1";
    if (!isfinite(s->time_s) || !isfinite(s->start_time_s) ||
        (s->stop_time_defined && !isfinite(s->stop_time_s)))
        return "it holds a non-finite time";
    if (s->mode & (FMU_MODE_STEP | FMU_MODE_TERMINATED))
        return model_validate_state(&s->data);
    return outputs_not_at_start(&s->data);
}

/* 1 if p is a state object made by this FMU (tag and token). */
static int is_own_state(const FmuState *p)
{
    return memcmp(p->tag, FMU_STATE_TAG, sizeof p->tag) == 0 &&
           strncmp(p->token, INSTANTIATION_TOKEN, sizeof p->token) == 0;
}

static void tag_state(FmuState *p)
{
    memset(p->tag, 0, sizeof p->tag);
    memcpy(p->tag, FMU_STATE_TAG, sizeof FMU_STATE_TAG);
    memset(p->token, 0, sizeof p->token);
    strncpy(p->token, INSTANTIATION_TOKEN, sizeof p->token - 1);
}

FmuStatus fmu_state_get(FmuInstance *instance, void **state)
{
    if (!state) {
        fmu_log_error(instance, "getFMUState: NULL state pointer");
        return FMU_ERROR;
    }
    if (*state && !is_own_state((const FmuState *)*state)) {
        fmu_log_error(instance, "getFMUState: the state to overwrite was not made by this FMU");
        return FMU_ERROR;
    }
    FmuState *p = *state ? (FmuState *)*state : malloc(sizeof *p);
    if (!p) {
        fmu_log_error(instance, "getFMUState: out of memory");
        return FMU_ERROR;
    }
    tag_state(p);
    p->s = instance->s;
    *state = p;
    return FMU_OK;
}

FmuStatus fmu_state_set(FmuInstance *instance, const void *state)
{
    if (!state) {
        fmu_log_error(instance, "setFMUState: NULL state");
        return FMU_ERROR;
    }
    const FmuState *p = (const FmuState *)state;
    if (!is_own_state(p)) {
        fmu_log_error(instance, "setFMUState: the state is refused: it was not made by this FMU "
                      "(another FMU's state, a freed state, or not a state)");
        return FMU_ERROR;
    }
    const char *why = snapshot_invalid(&p->s);
    if (why) {
        fmu_log_error(instance, "setFMUState: the state is refused: %s; the instance is "
                      "unchanged", why);
        return FMU_ERROR;
    }
    instance->s = p->s;
    return FMU_OK;
}

FmuStatus fmu_state_free(FmuInstance *instance, void **state)
{
    if (state && *state) {
        FmuState *p = (FmuState *)*state;
        if (!is_own_state(p)) {
            fmu_log_error(instance, "freeFMUState: the state was not made by this FMU; not freed");
            return FMU_ERROR;
        }
        memset(p->tag, 0, sizeof p->tag);
        free(p);
        *state = NULL;
    }
    return FMU_OK;
}

size_t fmu_state_serialized_size(void)
{
    return sizeof(FmuStateHeader) + sizeof(FmuSnapshot);
}

FmuStatus fmu_state_serialize(FmuInstance *instance, const void *state, uint8_t *buffer,
                              size_t size)
{
    if (!state || !buffer) {
        fmu_log_error(instance, "serializeFMUState: NULL state or buffer");
        return FMU_ERROR;
    }
    if (!is_own_state((const FmuState *)state)) {
        fmu_log_error(instance, "serializeFMUState: the state was not made by this FMU");
        return FMU_ERROR;
    }
    if (size != fmu_state_serialized_size()) {
        fmu_log_error(instance, "serializeFMUState: buffer of %zu bytes, expected %zu", size,
                      fmu_state_serialized_size());
        return FMU_ERROR;
    }
    const FmuSnapshot *snapshot = &((const FmuState *)state)->s;
    FmuStateHeader header;
    memset(&header, 0, sizeof header);
    memcpy(header.magic, FMU_STATE_MAGIC, sizeof header.magic);
    header.format = FMU_STATE_FORMAT;
    header.snapshot_size = (uint32_t)sizeof(FmuSnapshot);
    strncpy(header.token, INSTANTIATION_TOKEN, sizeof header.token - 1);
    memcpy(buffer + sizeof header, snapshot, sizeof *snapshot);
    /* over the bytes as written, padding included: the reader checks those same bytes */
    header.crc32 = crc32_ieee(buffer + sizeof header, sizeof *snapshot);
    memcpy(buffer, &header, sizeof header);
    return FMU_OK;
}

FmuStatus fmu_state_deserialize(FmuInstance *instance, const uint8_t *buffer, size_t size,
                                void **state)
{
    if (!buffer || !state) {
        fmu_log_error(instance, "deserializeFMUState: NULL buffer or state");
        return FMU_ERROR;
    }
    FmuStateHeader header;
    if (size != fmu_state_serialized_size()) {
        fmu_log_error(instance, "deserializeFMUState: %zu bytes, expected %zu", size,
                      fmu_state_serialized_size());
        return FMU_ERROR;
    }
    memcpy(&header, buffer, sizeof header);
    header.token[sizeof header.token - 1] = '\0';
    if (memcmp(header.magic, FMU_STATE_MAGIC, sizeof header.magic) != 0 ||
        header.format != FMU_STATE_FORMAT || header.snapshot_size != sizeof(FmuSnapshot) ||
        strcmp(header.token, INSTANTIATION_TOKEN) != 0) {
        fmu_log_error(instance, "deserializeFMUState: the bytes are not a state of this FMU "
                      "(wrong header, format or instantiation token)");
        return FMU_ERROR;
    }
    const uint32_t crc = crc32_ieee(buffer + sizeof header, sizeof(FmuSnapshot));
    if (crc != header.crc32) {
        fmu_log_error(instance, "deserializeFMUState: the state is damaged (CRC-32 of its %zu "
                      "bytes is 0x%08x, the header says 0x%08x); refused",
                      sizeof(FmuSnapshot), (unsigned)crc, (unsigned)header.crc32);
        return FMU_ERROR;
    }
    FmuState *copy = malloc(sizeof *copy);
    if (!copy) {
        fmu_log_error(instance, "deserializeFMUState: out of memory");
        return FMU_ERROR;
    }
    memcpy(&copy->s, buffer + sizeof header, sizeof copy->s);
    const char *why = snapshot_invalid(&copy->s);
    if (why) {
        free(copy);
        fmu_log_error(instance, "deserializeFMUState: the state is refused: %s", why);
        return FMU_ERROR;
    }
    /* always a new state: *state may hold anything (or a state the importer keeps) */
    tag_state(copy);
    *state = copy;
    return FMU_OK;
}
