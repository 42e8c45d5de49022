/* fuzz_fmu_state.c — crafted FMU states that pass the CRC (issue 21): libFuzzer target
 * for one navigator model (compiled once per model, fuzz/CMakeLists.txt) through the FMI
 * 2.0 and 3.0 glue.
 *
 * The held-out attack that this target reproduces at scale overwrote three words of a
 * saved integrated-navigator state, recomputed the CRC-32, and got the state accepted
 * and stepped to a NaN standard deviation (1 in 1,400 per FMI version). fuzz_fmu.c's
 * mode 0 crafts such states too, but asks only that the sanitizers stay quiet; here every
 * input is one crafted state and the oracle is the contract of a restored state:
 *
 *   every crafted state is either refused (deserialize or set returns Error and no
 *   state) or, once set, has finite Float64 outputs, and keeps them finite through three
 *   doSteps with plausible inputs, whether each doStep succeeds or is refused.
 *
 * NaN is allowed only in the outputs a model documents as "none yet"
 * (FUZZ_NAN_OUTPUTS, comma-separated name prefixes: the integrated navigator's nis and
 * update_time); infinities nowhere.
 *
 * The good state: the model initialized with its defaults and stepped 60 times with a
 * level IMU at rest (increments and rates) and, where the model takes them, a GNSS epoch
 * every 10 samples (so that the covariance is correlated, not diagonal). A crafted state:
 * 1..4 patches of that state's snapshot, most of them a double of the model data (a
 * special value, a scaled or negated copy of what was there, another double of the state,
 * any bit pattern), some an int32 or a byte; the CRC-32 recomputed (tests/c/fmu_state_ref.h).
 * One input in two is restored through FMI 3.0.
 *
 * Counts of accepted and refused states are printed at exit (FUZZ_STATE_STATS=1). */
#include <math.h>
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
#define H_S 0.01
#define GOOD_STEPS 60

#ifndef FUZZ_NAN_OUTPUTS
#define FUZZ_NAN_OUTPUTS ""
#endif

static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                    fmi2String category, fmi2String message, ...)
{
    (void)env; (void)name; (void)status; (void)category;
    if (getenv("FUZZ_FMU_LOG"))
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

static uint8_t *g_good;        /* the good serialized state */
static size_t g_size;
static size_t g_data_at;       /* where ModelData starts in it */
static double g_lat0, g_lon0, g_h0;
static unsigned long g_accepted, g_refused, g_steps_ok, g_steps_refused;

static void print_stats(void)
{
    fprintf(stderr, "fuzz_fmu_state: %lu states accepted, %lu refused; after them %lu doSteps "
            "ok, %lu refused\n", g_accepted, g_refused, g_steps_ok, g_steps_refused);
}

static const FmuVariable *variable(const char *name)
{
    for (size_t i = 0; i < N2; ++i)
        if (strcmp(kFmi2Variables[i].name, name) == 0)
            return &kFmi2Variables[i];
    return NULL;
}

static double *real_at(ModelData *d, const char *name)
{
    const FmuVariable *v = variable(name);
    return v && v->type == FMU_TYPE_FLOAT64 ? (double *)((char *)d + v->offset) : NULL;
}

static int32_t *int_at(ModelData *d, const char *name)
{
    const FmuVariable *v = variable(name);
    return v && v->type == FMU_TYPE_INT32 ? (int32_t *)((char *)d + v->offset) : NULL;
}

static void put(ModelData *d, const char *name, double x)
{
    double *p = real_at(d, name);
    if (p)
        *p = x;
}

/* The inputs of sample k (the doStep at time t consumes them): a level IMU at rest (specific force up,
 * a small rate), the array outputs of a body at rest (gravity on the axes that see it:
 * zero here, which the gyro-free navigators take as free fall: still a plausible
 * sample), and a GNSS fix at the start position every 10 samples. Written into the
 * model data directly (the inputs of a restored state are the master's to set). */
static void drive(ModelData *d, int k, double t)
{
    static const char *ax[3] = {"[1]", "[2]", "[3]"};
    char name[64];
    for (int i = 0; i < 3; ++i) {
        const double w = (i == 2 ? 1e-3 : 2e-4), f = (i == 2 ? 9.79 : 0.0);
        snprintf(name, sizeof name, "dtheta%s", ax[i]);
        put(d, name, w * H_S);
        snprintf(name, sizeof name, "dv%s", ax[i]);
        put(d, name, f * H_S);
        snprintf(name, sizeof name, "gyro_rate%s", ax[i]);
        put(d, name, w);
        snprintf(name, sizeof name, "gyro%s", ax[i]);
        put(d, name, w);
        snprintf(name, sizeof name, "accel%s", ax[i]);
        put(d, name, f);
        snprintf(name, sizeof name, "gnss_vel_enu_m_s%s", ax[i]);
        put(d, name, 0.0);
        snprintf(name, sizeof name, "gnss_pos_std_m%s", ax[i]);
        put(d, name, 1.0);
        snprintf(name, sizeof name, "gnss_vel_std_m_s%s", ax[i]);
        put(d, name, 0.1);
    }
    int32_t *valid = int_at(d, "gnss_valid");
    if (valid) {
        *valid = (k % 10 == 9);
        put(d, "gnss_time_s", t);
        put(d, "gnss_lat_rad", g_lat0 + 1e-8 * (k % 3));
        put(d, "gnss_lon_rad", g_lon0);
        put(d, "gnss_h_m", g_h0 + 0.1);
    }
}

static void make_good_state(void)
{
    atexit(print_stats);
    fmi2Component c = fmi2Instantiate("fuzz", fmi2CoSimulation, INSTANTIATION_TOKEN, "", &kCallbacks,
                                      fmi2False, fmi2False);
    FZ_REQUIRE(c, "instantiate");
    ModelData *d = &((FmuInstance *)c)->s.data;
    const double *p;
    g_lat0 = (p = real_at(d, "lat0")) ? *p : 0.0;
    g_lon0 = (p = real_at(d, "lon0")) ? *p : 0.0;
    g_h0 = (p = real_at(d, "h0")) ? *p : 0.0;
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    FZ_REQUIRE(fmi2ExitInitializationMode(c) == fmi2OK, "the model's defaults are refused");
    double t = 0.0;
    for (int k = 0; k < GOOD_STEPS; ++k, t += H_S) {
        drive(d, k, t);
        FZ_REQUIRE(fmi2DoStep(c, t, H_S, fmi2True) == fmi2OK, "the good run failed at step %d", k);
    }
    fmi2FMUstate st = NULL;
    FZ_REQUIRE(fmi2GetFMUstate(c, &st) == fmi2OK && fmi2SerializedFMUstateSize(c, st, &g_size) == fmi2OK,
               "state size");
    g_good = malloc(g_size);
    FZ_REQUIRE(g_good && fmi2SerializeFMUstate(c, st, (fmi2Byte *)g_good, g_size) == fmi2OK, "serialize");
    fmi2FreeFMUstate(c, &st);
    fmi2FreeInstance(c);
    g_data_at = REF_STATE_HEADER_SIZE + offsetof(FmuSnapshot, data);
    FZ_REQUIRE(g_data_at + sizeof(ModelData) <= g_size, "layout");
    if (!getenv("FUZZ_STATE_STATS"))
        return;
    fprintf(stderr, "fuzz_fmu_state: good state of %zu bytes (model data %zu)\n", g_size, sizeof(ModelData));
}

static int nan_allowed(const char *name)
{
    const char *list = FUZZ_NAN_OUTPUTS;
    while (*list) {
        const char *end = strchr(list, ',');
        const size_t len = end ? (size_t)(end - list) : strlen(list);
        if (len && strncmp(name, list, len) == 0 && (name[len] == '\0' || name[len] == '['))
            return 1;
        list += len + (end ? 1 : 0);
    }
    return 0;
}

/* The oracle: every Float64 output finite (NaN where allowed), read from the model data
 * the getters read. */
static void check_outputs(const ModelData *d, const char *when)
{
    for (size_t i = 0; i < N2; ++i) {
        const FmuVariable *v = &kFmi2Variables[i];
        if (v->type != FMU_TYPE_FLOAT64 || v->causality != FMU_CAUSALITY_OUTPUT)
            continue;
        double x;
        memcpy(&x, (const char *)d + v->offset, sizeof x);
        FZ_REQUIRE(isfinite(x) || (isnan(x) && nan_allowed(v->name)),
                   "%s: output %s = %g (a crafted state with a valid CRC)", when, v->name, x);
    }
}

static void patch(fz *d, uint8_t *bytes)
{
    uint8_t *snap = bytes + REF_STATE_HEADER_SIZE;
    const size_t n_snap = g_size - REF_STATE_HEADER_SIZE;
    const size_t data_at = g_data_at - REF_STATE_HEADER_SIZE;
    const size_t n_doubles = sizeof(ModelData) / 8;
    const uint8_t kind = fz_u8(d);
    if (kind < 200) {             /* a double of the model data */
        const size_t at = data_at + 8 * fz_index(d, n_doubles);
        double old, x;
        memcpy(&old, snap + at, sizeof old);
        const uint8_t how = fz_u8(d) % 8;
        if (how < 2) {
            x = kFzSpecial[fz_u8(d) % (sizeof kFzSpecial / sizeof kFzSpecial[0])];
        } else if (how < 4) {
            static const double scale[] = {-1.0, 2.0, 0.5, 1e3, 1e-3, 1e10, 1e-10, 1e100, 1.0 + 1e-6, 0.0};
            x = old * scale[fz_u8(d) % (sizeof scale / sizeof scale[0])];
        } else if (how == 4) {
            x = old + fz_num(d, 1.0);
        } else if (how == 5) {
            memcpy(&x, snap + data_at + 8 * fz_index(d, n_doubles), sizeof x);
        } else if (how == 6) {
            x = fz_num(d, 1e3);
        } else {
            x = fz_raw(d);
        }
        memcpy(snap + at, &x, sizeof x);
    } else if (kind < 240) {      /* an int32 anywhere in the snapshot */
        const size_t at = (fz_index(d, n_snap / 4)) * 4;
        const int32_t v = (kind & 1) ? (int32_t)fz_u32(d) : (int32_t)(fz_u8(d) % 8) - 2;
        memcpy(snap + at, &v, sizeof v);
    } else {                      /* a byte */
        snap[fz_index(d, n_snap)] = fz_u8(d);
    }
}

static void run2(const uint8_t *bytes)
{
    fmi2Component c = fmi2Instantiate("fuzz", fmi2CoSimulation, INSTANTIATION_TOKEN, "", &kCallbacks,
                                      fmi2False, fmi2False);
    FZ_REQUIRE(c, "instantiate");
    fmi2FMUstate st = NULL;
    const fmi2Status ds = fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, g_size, &st);
    if (ds != fmi2OK) {
        FZ_REQUIRE(ds == fmi2Error && st == NULL, "a refused state: status %d, state %p", (int)ds, (void *)st);
        ++g_refused;
    } else if (fmi2SetFMUstate(c, st) != fmi2OK) {
        ++g_refused;
    } else {
        ++g_accepted;
        FmuInstance *inst = (FmuInstance *)c;
        check_outputs(&inst->s.data, "FMI 2.0, restored");
        double t = inst->s.time_s;
        for (int k = 0; k < 3; ++k, t += H_S) {
            drive(&inst->s.data, GOOD_STEPS + k, t);
            const fmi2Status s = fmi2DoStep(c, t, H_S, fmi2True);
            check_outputs(&inst->s.data, s == fmi2OK ? "FMI 2.0, after a doStep" : "FMI 2.0, after a refused doStep");
            if (s != fmi2OK) {
                ++g_steps_refused;
                break;
            }
            ++g_steps_ok;
        }
    }
    if (st)
        fmi2FreeFMUstate(c, &st);
    fmi2FreeInstance(c);
}

static void run3(const uint8_t *bytes)
{
    fmi3Instance c = fmi3InstantiateCoSimulation("fuzz3", INSTANTIATION_TOKEN, "", fmi3False,
                                                 fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                                 logger3, NULL);
    FZ_REQUIRE(c, "fmi3 instantiate");
    fmi3FMUState st = NULL;
    const fmi3Status ds = fmi3DeserializeFMUState(c, (const fmi3Byte *)bytes, g_size, &st);
    if (ds != fmi3OK) {
        FZ_REQUIRE(ds == fmi3Error && st == NULL, "a refused state: status %d, state %p", (int)ds, (void *)st);
        ++g_refused;
    } else if (fmi3SetFMUState(c, st) != fmi3OK) {
        ++g_refused;
    } else {
        ++g_accepted;
        FmuInstance *inst = (FmuInstance *)c;
        check_outputs(&inst->s.data, "FMI 3.0, restored");
        double t = inst->s.time_s;
        for (int k = 0; k < 3; ++k, t += H_S) {
            drive(&inst->s.data, GOOD_STEPS + k, t);
            fmi3Boolean ev = 0, term = 0, early = 0;
            double last = 0.0;
            const fmi3Status s = fmi3DoStep(c, t, H_S, fmi3True, &ev, &term, &early, &last);
            check_outputs(&inst->s.data, s == fmi3OK ? "FMI 3.0, after a doStep" : "FMI 3.0, after a refused doStep");
            if (s != fmi3OK) {
                ++g_steps_refused;
                break;
            }
            ++g_steps_ok;
        }
    }
    if (st)
        fmi3FreeFMUState(c, &st);
    fmi3FreeInstance(c);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!g_good)
        make_good_state();
    fz d = {data, size};
    uint8_t *bytes = malloc(g_size);
    memcpy(bytes, g_good, g_size);
    const uint8_t head = fz_u8(&d);
    const int k = 1 + (head >> 1) % 4;
    for (int j = 0; j < k; ++j)
        patch(&d, bytes);
    ref_state_fix_crc(bytes, g_size);
    if (head & 1)
        run3(bytes);
    else
        run2(bytes);
    free(bytes);
    return 0;
}
