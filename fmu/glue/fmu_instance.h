/* fmu_instance.h — FMI-version-independent part of an FMU instance (shared glue).
 *
 * fmi2_glue.c and fmi3_glue.c translate the FMI 2.0 / 3.0 calls into the functions
 * below; everything that both versions need — call-sequence checks, typed access to
 * the model's variables through the generated table, communication steps with their
 * time checks, FMU state snapshots and their serialization — lives here once.
 */
#ifndef FMU_INSTANCE_H
#define FMU_INSTANCE_H

#include <stdint.h>

#include "fmu_model.h"
#include "model_vars.h"

/* Modes of the call-sequence state machine (bit masks, so a function lists the modes
 * it is allowed in as one mask). */
enum {
    FMU_MODE_INSTANTIATED = 1u << 0,
    FMU_MODE_INITIALIZATION = 1u << 1,
    FMU_MODE_STEP = 1u << 2,
    FMU_MODE_TERMINATED = 1u << 3,
    FMU_MODE_ERROR = 1u << 4
};
#define FMU_MODE_ANY 0x1Fu

/* Everything that an FMU state captures. Pointer-free, so a state is a copy. */
typedef struct FmuSnapshot {
    uint32_t mode;
    int32_t stop_time_defined;
    double start_time_s;
    double stop_time_s;
    double time_s;
    ModelData data;
} FmuSnapshot;

/* An FMU state object (what getFMUState hands out): a tag naming the FMU that made it,
 * then the snapshot. setFMUState, serializeFMUState and freeFMUState refuse an object
 * whose tag is not this FMU's (a state of another FMU, or not a state at all). */
#define FMU_STATE_TAG "GFINSST"
typedef struct FmuState {
    char tag[8];              /* FMU_STATE_TAG */
    char token[48];           /* INSTANTIATION_TOKEN of the FMU that made it */
    FmuSnapshot s;
} FmuState;

/* Sends one formatted message to the importer (implemented per FMI version). */
typedef void (*FmuSendLog)(FmuInstance *instance, FmuStatus status, const char *category,
                           const char *message);

struct FmuInstance {
    char *instance_name;
    int logging_on;
    FmuSendLog send_log;
    void (*log_function)(void); /* the importer's logger (copied), cast back by send_log */
    void *environment;          /* the importer's environment pointer */
    FmuSnapshot s;
};

FmuInstance *fmu_instance_new(const char *instance_name, const char *token,
                              FmuSendLog send_log, void (*log_function)(void),
                              void *environment, int logging_on);
void fmu_instance_free(FmuInstance *instance);

/* 1 if the instance is in one of the modes of `allowed`; otherwise logs which call
 * was made in which mode and returns 0. */
int fmu_check_mode(FmuInstance *instance, uint32_t allowed, const char *function);

FmuStatus fmu_reset(FmuInstance *instance);
FmuStatus fmu_enter_initialization(FmuInstance *instance, int stop_time_defined,
                                   double start_time_s, double stop_time_s);
FmuStatus fmu_exit_initialization(FmuInstance *instance);
FmuStatus fmu_terminate(FmuInstance *instance);
FmuStatus fmu_do_step(FmuInstance *instance, double t_s, double h_s, const char *function);

/* Typed get/set through a generated table. For FMI 2.0 every table row is a scalar and
 * n_values == n_vr; for FMI 3.0 rows may be arrays and n_values counts elements.
 * Value reference 0 is the independent variable (time) where has_time is set. */
FmuStatus fmu_get(FmuInstance *instance, const FmuVariable *table, size_t n_table,
                  int has_time, FmuType type, const unsigned int *vr, size_t n_vr,
                  void *values, size_t n_values, const char *function);
FmuStatus fmu_set(FmuInstance *instance, const FmuVariable *table, size_t n_table,
                  FmuType type, const unsigned int *vr, size_t n_vr, const void *values,
                  size_t n_values, const char *function);

/* FMU states (FmuState objects, opaque to the importer) and their serialization.
 * Serialized form (docs/fmu.md): a 72-byte header — magic "GFINSFMU", format 2, the
 * snapshot size, the CRC-32 (IEEE 802.3, as zlib.crc32) of the snapshot bytes, 4 zero
 * bytes, the instantiation token (48 bytes, zero padded) — then the FmuSnapshot bytes.
 * A state is used only after every check passes: on deserialize the header, the CRC-32
 * and the contents (mode, times, and for an initialized model model_validate_state); on
 * setFMUState the tag and the contents again. A refused state changes nothing and the
 * reason is logged. */
FmuStatus fmu_state_get(FmuInstance *instance, void **state);
FmuStatus fmu_state_set(FmuInstance *instance, const void *state);
FmuStatus fmu_state_free(FmuInstance *instance, void **state);
size_t fmu_state_serialized_size(void);
FmuStatus fmu_state_serialize(FmuInstance *instance, const void *state, uint8_t *buffer,
                              size_t size);
FmuStatus fmu_state_deserialize(FmuInstance *instance, const uint8_t *buffer, size_t size,
                                void **state);

void fmu_log(FmuInstance *instance, FmuStatus status, const char *category,
             const char *format, ...) __attribute__((format(printf, 4, 5)));

#endif /* FMU_INSTANCE_H */
