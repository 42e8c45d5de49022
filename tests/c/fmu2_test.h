/* fmu2_test.h — helpers for the C tests that drive one FMU model through the FMI 2.0
 * glue (test_fmu_vehicle.c, test_fmu_navigator.c): a logger collecting the messages in
 * g_log, the callbacks, value references by name from the generated table, setters by
 * name, and the checks of damaged and crafted FMU states (check_damaged_states).
 * Include after fmu_instance.h (which brings the model's kFmi2Variables, ModelData and
 * the FmuSnapshot / FmuState layouts). */
#ifndef FMU2_TEST_H
#define FMU2_TEST_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_state_ref.h"
#include "gf_test.h"

static char g_log[4096]; /* every message since the test last cleared it */

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env; (void)name; (void)status; (void)category;
    va_list ap;
    va_start(ap, message);
    const size_t used = strlen(g_log);
    vsnprintf(g_log + used, sizeof g_log - used, message, ap);
    va_end(ap);
}

static const fmi2CallbackFunctions kCallbacks = {logger, calloc, free, NULL, NULL};

static fmi2Component instantiate(const char *name)
{
    g_log[0] = '\0';
    fmi2Component c = fmi2Instantiate(name, fmi2CoSimulation, INSTANTIATION_TOKEN, "",
                                      &kCallbacks, fmi2False, fmi2False);
    CHECK(c != NULL, "instantiate %s", name);
    return c;
}

static fmi2ValueReference vr(const char *name)
{
    for (size_t i = 0; i < sizeof kFmi2Variables / sizeof kFmi2Variables[0]; ++i)
        if (strcmp(kFmi2Variables[i].name, name) == 0)
            return kFmi2Variables[i].value_reference;
    CHECK(0, "no variable %s", name);
    return 0;
}

/* Value references of base[1] .. base[n]. */
static void vrs(const char *base, int n, fmi2ValueReference *out)
{
    char name[48];
    for (int i = 0; i < n; ++i) {
        snprintf(name, sizeof name, "%s[%d]", base, i + 1);
        out[i] = vr(name);
    }
}

static void set_real(fmi2Component c, const char *name, double v)
{
    const fmi2ValueReference r = vr(name);
    fmi2SetReal(c, &r, 1, &v);
}

static void set_vec(fmi2Component c, const char *base, const double *v, int n)
{
    fmi2ValueReference r[64];
    vrs(base, n, r);
    fmi2SetReal(c, r, (size_t)n, v);
}

static void set_int(fmi2Component c, const char *name, int v)
{
    const fmi2ValueReference r = vr(name);
    const fmi2Integer x = v;
    fmi2SetInteger(c, &r, 1, &x);
}

/* ---- damaged and crafted FMU states --------------------------------------------------- */

/* One field of ModelData set to a value that no step of the model can produce. */
typedef struct StatePatch {
    const char *what;     /* "field = value" */
    const char *mention;  /* expected in the logged reason */
    size_t offset;        /* offsetof(ModelData, field) */
    char type;            /* 'i' int32_t, 'z' size_t, 'd' double */
    double value;
} StatePatch;
#define PATCH(type, field, v, mention) {#field " = " #v, mention, offsetof(ModelData, field), type, (double)(v)}

static void apply_patch(uint8_t *model_data, const StatePatch *p)
{
    if (p->type == 'i') {
        const int32_t x = (int32_t)p->value;
        memcpy(model_data + p->offset, &x, sizeof x);
    } else if (p->type == 'z') {
        const size_t x = (size_t)p->value;
        memcpy(model_data + p->offset, &x, sizeof x);
    } else {
        memcpy(model_data + p->offset, &p->value, sizeof p->value);
    }
}

/* A region of ModelData to fill with random bytes in the fuzzing (offset, size). */
typedef struct StateRegion {
    size_t offset, size;
} StateRegion;
#define REGION(field) {offsetof(ModelData, field), sizeof(((ModelData *)0)->field)}
#define REGION_HEAD(field, n) {offsetof(ModelData, field), (n)}

/* Steps the model once at t_s with its inputs for that time; returns the doStep status. */
typedef fmi2Status (*StateStepFn)(fmi2Component c, double t_s);

static uint8_t *snapshot_model_data(uint8_t *bytes, size_t size)
{
    return bytes + size - sizeof(FmuSnapshot) + offsetof(FmuSnapshot, data);
}

static void expect_bytes_refused(fmi2Component c, const uint8_t *bytes, size_t size,
                                 const char *what, const char *mention)
{
    g_log[0] = '\0';
    fmi2FMUstate st = NULL;
    const fmi2Status status = fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, size, &st);
    CHECK(status == fmi2Error && st == NULL, "%s: deserialize returned %d (a state: %s)", what,
          (int)status, st ? "yes" : "no");
    CHECK(strstr(g_log, "deserializeFMUState") && strstr(g_log, mention),
          "%s: the logged reason does not mention \"%s\": \"%s\"", what, mention, g_log);
    if (st)
        fmi2FreeFMUstate(c, &st);
}

/* With c initialized and stepped to time t_s (its state 'good' there; steps of h_s):
 *   0. the continuation, n_continue steps reading the outputs out_vr, is recorded;
 *   1. the header's CRC-32 is the CRC of the snapshot bytes (ref_crc32);
 *   2. one flipped bit anywhere in the snapshot: refused, the reason names the CRC-32;
 *   3. every patch, crafted with the CRC-32 recomputed: refused by deserialize with the
 *      patch's reason; the same patch in a state object handed to setFMUState: refused
 *      with that reason;
 *   4. n_fuzz crafted states (CRC recomputed), each with 1..8 random bytes in one of the
 *      regions or anywhere in ModelData: refused, or accepted and then stepped three
 *      times (OK or an error; under ASan/UBSan no report);
 *   5. c is restored to 'good' and continues exactly as in 0 (every refusal left it as
 *      it was). */
static void check_damaged_states(fmi2Component c, double t_s, double h_s, StateStepFn step,
                                 int n_continue, const fmi2ValueReference *out_vr, size_t n_out,
                                 const StatePatch *patches, size_t n_patches,
                                 const StateRegion *regions, size_t n_regions, int n_fuzz)
{
    fmi2FMUstate good = NULL;
    size_t size = 0;
    CHECK(fmi2GetFMUstate(c, &good) == fmi2OK, "get state");
    double *cont[2] = {calloc((size_t)n_continue * n_out, sizeof(double)),
                       calloc((size_t)n_continue * n_out, sizeof(double))};
    for (int j = 0; j < n_continue && cont[0]; ++j) {
        CHECK(step(c, t_s + j * h_s) == fmi2OK, "continuation step %d: %s", j, g_log);
        fmi2GetReal(c, out_vr, n_out, cont[0] + (size_t)j * n_out);
    }
    CHECK(fmi2SetFMUstate(c, good) == fmi2OK, "back to the good state");
    CHECK(fmi2SerializedFMUstateSize(c, good, &size) == fmi2OK && size > REF_STATE_HEADER_SIZE,
          "serialized size");
    uint8_t *ok_bytes = malloc(size), *bytes = malloc(size);
    CHECK(ok_bytes && bytes && fmi2SerializeFMUstate(c, good, (fmi2Byte *)ok_bytes, size) == fmi2OK,
          "serialize");
    if (!ok_bytes || !bytes) {
        free(ok_bytes);
        free(bytes);
        return;
    }
    uint32_t format;
    memcpy(&format, ok_bytes + REF_STATE_FORMAT_AT, sizeof format);
    CHECK(format == 2, "serialized format %u, expected 2", (unsigned)format);
    CHECK(ref_crc32_check(), "the reference CRC-32 misses the check value");
    CHECK(ref_state_crc(ok_bytes) == ref_crc32(ok_bytes + REF_STATE_HEADER_SIZE, size - REF_STATE_HEADER_SIZE),
          "the header's CRC-32 0x%08x is not the CRC-32 of the snapshot", (unsigned)ref_state_crc(ok_bytes));

    test_rng rng = {0x243F6A8885A308D3ULL};
    for (int i = 0; i < 8; ++i) { /* one flipped bit, the header kept */
        memcpy(bytes, ok_bytes, size);
        const size_t at = REF_STATE_HEADER_SIZE +
                          (size_t)test_rng_uniform(&rng, 0, (double)(size - REF_STATE_HEADER_SIZE));
        bytes[at] ^= (uint8_t)(1u << (int)test_rng_uniform(&rng, 0, 8));
        char what[64];
        snprintf(what, sizeof what, "bit flipped at byte %zu", at);
        expect_bytes_refused(c, bytes, size, what, "CRC-32");
    }

    for (size_t i = 0; i < n_patches; ++i) {
        const StatePatch *p = &patches[i];
        memcpy(bytes, ok_bytes, size);
        apply_patch(snapshot_model_data(bytes, size), p);
        ref_state_fix_crc(bytes, size);
        expect_bytes_refused(c, bytes, size, p->what, p->mention);
        fmi2FMUstate st = NULL;
        CHECK(fmi2GetFMUstate(c, &st) == fmi2OK, "get state");
        apply_patch((uint8_t *)&((FmuState *)st)->s.data, p);
        g_log[0] = '\0';
        CHECK(fmi2SetFMUstate(c, st) == fmi2Error, "%s: setFMUState accepted it", p->what);
        CHECK(strstr(g_log, "setFMUState") && strstr(g_log, p->mention),
              "%s: setFMUState's logged reason does not mention \"%s\": \"%s\"", p->what,
              p->mention, g_log);
        fmi2FreeFMUstate(c, &st);
    }

    int refused = 0, accepted_ok = 0, accepted_error = 0;
    for (int it = 0; it < n_fuzz; ++it) {
        memcpy(bytes, ok_bytes, size);
        uint8_t *data = snapshot_model_data(bytes, size);
        const size_t r = (size_t)it % (n_regions + 1);
        const size_t off = r < n_regions ? regions[r].offset : 0;
        const size_t len = r < n_regions ? regions[r].size : sizeof(ModelData);
        const int k = 1 + (int)test_rng_uniform(&rng, 0, 8);
        for (int j = 0; j < k; ++j)
            data[off + (size_t)test_rng_uniform(&rng, 0, (double)len)] =
                (uint8_t)test_rng_uniform(&rng, 0, 256);
        ref_state_fix_crc(bytes, size);
        g_log[0] = '\0';
        fmi2FMUstate st = NULL;
        if (fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, size, &st) != fmi2OK) {
            ++refused;
            CHECK(st == NULL && strstr(g_log, "refused"), "fuzz %d: refused without a reason: %s", it, g_log);
            continue;
        }
        CHECK(fmi2SetFMUstate(c, st) == fmi2OK, "fuzz %d: deserialized but not set: %s", it, g_log);
        fmi2FreeFMUstate(c, &st);
        int all_ok = 1;
        for (int j = 0; j < 3; ++j)
            all_ok &= step(c, t_s + j * h_s) == fmi2OK;
        accepted_ok += all_ok;
        accepted_error += !all_ok;
        CHECK(fmi2SetFMUstate(c, good) == fmi2OK, "restore the good state");
    }
    if (n_fuzz)
        printf("fuzzed states: %d refused, %d accepted and stepped OK, %d accepted and then "
               "refused by a step\n", refused, accepted_ok, accepted_error);
    CHECK(fmi2SetFMUstate(c, good) == fmi2OK, "restore the good state");
    for (int j = 0; j < n_continue && cont[1]; ++j) {
        CHECK(step(c, t_s + j * h_s) == fmi2OK, "continuation step %d after the checks: %s", j, g_log);
        fmi2GetReal(c, out_vr, n_out, cont[1] + (size_t)j * n_out);
    }
    CHECK(cont[0] && cont[1] &&
              memcmp(cont[0], cont[1], (size_t)n_continue * n_out * sizeof(double)) == 0,
          "after the damaged states the instance continues exactly as before");
    free(cont[0]);
    free(cont[1]);
    fmi2FreeFMUstate(c, &good);
    free(ok_bytes);
    free(bytes);
}

#endif /* FMU2_TEST_H */
