/* fuzz_fmu.c — libFuzzer target for one FMU model (compiled once per model, see
 * fuzz/CMakeLists.txt) through the FMI 2.0 and 3.0 glue:
 *   mode 0  the state deserializer with crafted contents: a good serialized state (the
 *           model initialized with its defaults and stepped) with 1..16 fuzzed patches
 *           in the snapshot (bytes, int32 or doubles at any offset) and the CRC-32
 *           recomputed (tests/c/fmu_state_ref.h), so that the contents checks are
 *           reached; an accepted state is set and stepped three times with fuzzed inputs;
 *   mode 1  the deserializer with a damaged header and size (no CRC fix);
 *   mode 2  FMI 2.0 call sequences: setReal/setInteger of any value reference and value,
 *           get, setup, enter/exit initialization, doStep at any time and step, reset,
 *           terminate, get/set/serialize/deserialize states;
 *   mode 3  FMI 3.0 array setters and getters (nValues of any size), initialization
 *           and doStep.
 * Oracles: sanitizers (ASan, UBSan); a refused deserialize returns Error with no state;
 * a failed doStep leaves the model data unchanged (fmu_model.h's contract, compared
 * byte for byte). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "fmu_instance.h"
#include "fmu_state_ref.h"
#include "fuzz_data.h"

#define N2 (sizeof kFmi2Variables / sizeof kFmi2Variables[0])
#define N3 (sizeof kFmi3Variables / sizeof kFmi3Variables[0])
#define H_S 0.01

/* FUZZ_STEP_CAP_S (set for the vehicle model, fuzz/CMakeLists.txt): a model whose doStep
 * works in proportion to the step asked for (the vehicle integrates up to 4e5 quadrature
 * pieces for its longest accepted step, 1e5 s: 50 s of CPU under the sanitizers) would
 * spend the run on a few long steps. Steps between the cap and 1e6 s are shortened to
 * the cap; longer ones (refused by the model) and every other value pass unchanged, so
 * the refusal paths stay reachable (tests/c/test_vehicle.c: the step limit). */
static double capped_step(double h)
{
#ifdef FUZZ_STEP_CAP_S
    if (h > FUZZ_STEP_CAP_S && h < 1e6)
        return FUZZ_STEP_CAP_S;
#endif
    return h;
}

static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                    fmi2String category, fmi2String message, ...)
{
    (void)env; (void)name; (void)status; (void)category;
    if (getenv("FUZZ_FMU_LOG")) /* FUZZ_FMU_LOG=1: print the FMU's log (replaying a finding) */
        fprintf(stderr, "fmu log: %s\n", message);
}

static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                    fmi3String message)
{
    (void)env; (void)status; (void)category;
    if (getenv("FUZZ_FMU_LOG"))
        fprintf(stderr, "fmu log: %s\n", message);
}

static const fmi2CallbackFunctions kCallbacks = {logger2, calloc, free, NULL, NULL};

static uint8_t *g_good;      /* serialized state of an initialized, stepped instance */
static size_t g_size;

static fmi2Component instantiate2(void)
{
    return fmi2Instantiate("fuzz", fmi2CoSimulation, INSTANTIATION_TOKEN, "", &kCallbacks,
                           fmi2False, fmi2False);
}

/* Sets every real input (FMI 2 scalars) to fuzzed values. */
static void set_inputs(fz *d, fmi2Component c)
{
    for (size_t i = 0; i < N2; ++i)
        if (kFmi2Variables[i].causality == FMU_CAUSALITY_INPUT) {
            const fmi2ValueReference r = kFmi2Variables[i].value_reference;
            if (kFmi2Variables[i].type == FMU_TYPE_FLOAT64) {
                const fmi2Real v = fz_num(d, 1.0);
                fmi2SetReal(c, &r, 1, &v);
            } else {
                const fmi2Integer v = (fmi2Integer)(fz_u8(d) % 4);
                fmi2SetInteger(c, &r, 1, &v);
            }
        }
}

/* doStep, with the model-data contract checked: a failed step changes no model data.
 * A model built with FUZZ_FMU_PARTIAL_AFTER_DIVERGENCE (the integrated navigator, which
 * saves no copy of its filter before a step: docs/fmu.md) may leave partial data after an
 * error, and then the instance must refuse to step on them. */
static fmi2Status checked_step(fmi2Component c, double t, double h)
{
    static ModelData before;
    memcpy(&before, &((FmuInstance *)c)->s.data, sizeof before);
    h = capped_step(h);
    const fmi2Status st = fmi2DoStep(c, t, h, fmi2True);
    if (st >= fmi2Error && memcmp(&before, &((FmuInstance *)c)->s.data, sizeof before) != 0) {
#ifdef FUZZ_FMU_PARTIAL_AFTER_DIVERGENCE
        FZ_REQUIRE(fmi2DoStep(c, t + h, h, fmi2True) >= fmi2Error,
                   "an instance with partial data after a failed doStep stepped on");
#else
        FZ_REQUIRE(0, "a failed doStep changed the model data");
#endif
    }
    return st;
}

static void make_good_state(void)
{
    fmi2Component c = instantiate2();
    FZ_REQUIRE(c, "instantiate");
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    const int initialized = fmi2ExitInitializationMode(c) == fmi2OK;
    double t = 0.0;
    for (int k = 0; initialized && k < 20; ++k, t += H_S)
        if (fmi2DoStep(c, t, H_S, fmi2True) != fmi2OK)
            break;
    fmi2FMUstate st = NULL;
    FZ_REQUIRE(fmi2GetFMUstate(c, &st) == fmi2OK && fmi2SerializedFMUstateSize(c, st, &g_size) == fmi2OK,
               "state size");
    g_good = malloc(g_size);
    FZ_REQUIRE(g_good && fmi2SerializeFMUstate(c, st, (fmi2Byte *)g_good, g_size) == fmi2OK, "serialize");
    fmi2FreeFMUstate(c, &st);
    fmi2FreeInstance(c);
    fprintf(stderr, "fuzz_fmu: good state of %zu bytes (%s)\n", g_size,
            initialized ? "initialized, stepped" : "not initialized: default parameters refused");
}

static void mode_state(fz *d, int fix_crc)
{
    uint8_t *bytes = malloc(g_size + 8);
    memcpy(bytes, g_good, g_size);
    size_t size = g_size;
    if (fix_crc) {
        uint8_t *snap = bytes + REF_STATE_HEADER_SIZE;
        const size_t n_snap = g_size - REF_STATE_HEADER_SIZE;
        const int k = 1 + fz_u8(d) % 16;
        for (int j = 0; j < k; ++j) {
            const uint8_t kind = fz_u8(d);
            size_t at = fz_u16(d) | ((size_t)fz_u8(d) << 16);
            at %= n_snap;
            if ((kind & 3) == 0) {
                snap[at] = fz_u8(d);
            } else if ((kind & 3) == 1 && at + 4 <= n_snap) {
                const int32_t v = (kind & 4) ? (int32_t)fz_u32(d) : (int32_t)(fz_u8(d)) - 8;
                memcpy(snap + (at & ~(size_t)3), &v, sizeof v);
            } else if (at + 8 <= n_snap) {
                const double v = fz_num(d, 1e3);
                memcpy(snap + (at & ~(size_t)7), &v, sizeof v);
            }
        }
        ref_state_fix_crc(bytes, size);
    } else {
        const int k = 1 + fz_u8(d) % 8;
        for (int j = 0; j < k; ++j)
            bytes[fz_index(d, REF_STATE_HEADER_SIZE)] = fz_u8(d);
        const uint8_t s = fz_u8(d);
        if (s < 16)
            size = g_size - s;
        else if (s < 24)
            size = g_size + (s - 16);
    }
    fmi2Component c = instantiate2();
    fmi2FMUstate st = (fmi2FMUstate)0x1; /* deserialize must write it (or leave refusals NULL) */
    st = NULL;
    const fmi2Status ds = fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, size, &st);
    if (ds != fmi2OK) {
        FZ_REQUIRE(ds == fmi2Error && st == NULL, "a refused state: status %d, state %p", (int)ds, (void *)st);
    } else if (fmi2SetFMUstate(c, st) == fmi2OK) {
        double t = ((FmuInstance *)c)->s.time_s;
        for (int j = 0; j < 3; ++j, t += H_S) {
            set_inputs(d, c);
            checked_step(c, t, (fz_u8(d) & 7) ? H_S : fz_pos(d, 1.0));
            double out[64];
            fmi2ValueReference vr[64];
            size_t m = 0;
            for (size_t i = 0; i < N2 && m < 64; ++i)
                if (kFmi2Variables[i].type == FMU_TYPE_FLOAT64)
                    vr[m++] = kFmi2Variables[i].value_reference;
            fmi2GetReal(c, vr, m, out);
        }
        /* the state taken now serializes and deserializes again */
        fmi2FMUstate st2 = NULL;
        if (fmi2GetFMUstate(c, &st2) == fmi2OK) {
            FZ_REQUIRE(fmi2SerializeFMUstate(c, st2, (fmi2Byte *)bytes, g_size) == fmi2OK, "reserialize");
            fmi2FreeFMUstate(c, &st2);
        }
    }
    if (st)
        fmi2FreeFMUstate(c, &st);
    fmi2FreeInstance(c);
    free(bytes);
}

static fmi2ValueReference any_vr(fz *d)
{
    const uint8_t k = fz_u8(d);
    return k < 240 ? (fmi2ValueReference)(k % (N2 + 2)) : (fmi2ValueReference)fz_u32(d);
}

static void mode_calls2(fz *d)
{
    fmi2Component c = instantiate2();
    double t = 0.0;
    fmi2FMUstate saved = NULL;
    for (int op = 0; op < 40 && d->n > 0; ++op) {
        switch (fz_u8(d) % 12) {
        case 0: case 1: case 2: {
            const fmi2ValueReference r = any_vr(d);
            const fmi2Real v = fz_num(d, 10.0);
            fmi2SetReal(c, &r, 1, &v);
            break;
        }
        case 3: {
            const fmi2ValueReference r = any_vr(d);
            const fmi2Integer v = (fz_u8(d) & 1) ? (fmi2Integer)fz_u32(d) : (fmi2Integer)(fz_u8(d) % 8) - 2;
            fmi2SetInteger(c, &r, 1, &v);
            break;
        }
        case 4: {
            const fmi2ValueReference r = any_vr(d);
            fmi2Real v;
            fmi2Integer iv;
            fmi2GetReal(c, &r, 1, &v);
            fmi2GetInteger(c, &r, 1, &iv);
            break;
        }
        case 5:
            fmi2SetupExperiment(c, fmi2False, 0.0, t = fz_num(d, 10.0), fz_u8(d) & 1, fz_num(d, 100.0));
            fmi2EnterInitializationMode(c);
            break;
        case 6:
            fmi2ExitInitializationMode(c);
            break;
        case 7: case 8: {
            const double h = capped_step((fz_u8(d) & 3) ? H_S : fz_num(d, 1.0));
            const double tt = (fz_u8(d) & 7) ? t : fz_num(d, 10.0);
            if (checked_step(c, tt, h) == fmi2OK)
                t = tt + h;
            break;
        }
        case 9:
            if (fz_u8(d) & 1)
                fmi2Reset(c);
            else
                fmi2Terminate(c);
            t = 0.0;
            break;
        case 10:
            if (saved)
                fmi2FreeFMUstate(c, &saved);
            fmi2GetFMUstate(c, &saved);
            break;
        default:
            if (saved && fmi2SetFMUstate(c, saved) == fmi2OK)
                t = ((FmuInstance *)c)->s.time_s;
            break;
        }
    }
    if (saved)
        fmi2FreeFMUstate(c, &saved);
    fmi2FreeInstance(c);
}

static void mode_calls3(fz *d)
{
    fmi3Instance c = fmi3InstantiateCoSimulation("fuzz3", INSTANTIATION_TOKEN, "", fmi3False,
                                                 fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                                 logger3, NULL);
    FZ_REQUIRE(c, "fmi3 instantiate");
    double t = 0.0;
    for (int op = 0; op < 24 && d->n > 0; ++op) {
        fmi3ValueReference vr[8];
        double v[96];
        int32_t iv[96];
        const size_t nvr = 1 + fz_u8(d) % 4;
        for (size_t i = 0; i < nvr; ++i) {
            const uint8_t k = fz_u8(d);
            vr[i] = k < 240 ? (fmi3ValueReference)(k % (N3 + 2)) : (fmi3ValueReference)fz_u32(d);
        }
        size_t nv = 0;
        for (size_t i = 0; i < nvr; ++i) /* mostly the right count, sometimes not */
            nv += (vr[i] >= 1 && vr[i] <= N3) ? kFmi3Variables[vr[i] - 1].count : 1;
        if ((fz_u8(d) & 7) == 0)
            nv = fz_u8(d) % 96;
        if (nv > 96)
            nv = 96;
        for (size_t i = 0; i < nv; ++i) {
            v[i] = fz_num(d, 10.0);
            iv[i] = (int32_t)(fz_u8(d) % 8) - 2;
        }
        switch (fz_u8(d) % 6) {
        case 0: fmi3SetFloat64(c, vr, nvr, v, nv); break;
        case 1: fmi3SetInt32(c, vr, nvr, iv, nv); break;
        case 2: fmi3GetFloat64(c, vr, nvr, v, nv); fmi3GetInt32(c, vr, nvr, iv, nv); break;
        case 3:
            fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
            fmi3ExitInitializationMode(c);
            t = 0.0;
            break;
        default: {
            fmi3Boolean ev = 0, term = 0, early = 0;
            double last = 0.0;
            const double h = capped_step((fz_u8(d) & 3) ? H_S : fz_num(d, 1.0));
            if (fmi3DoStep(c, t, h, fmi3True, &ev, &term, &early, &last) == fmi3OK)
                t += h;
        }
        }
    }
    fmi3FreeInstance(c);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!g_good)
        make_good_state();
    fz d = {data, size};
    switch (fz_u8(&d) % 4) {
    case 0: mode_state(&d, 1); break;
    case 1: mode_state(&d, 0); break;
    case 2: mode_calls2(&d); break;
    default: mode_calls3(&d); break;
    }
    return 0;
}
