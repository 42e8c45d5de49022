/* test_fmu_glue.c — the FMI 2.0 / 3.0 glue (fmu/glue) with the accel9 model, linked
 * straight into this executable (no dlopen), so that it runs under AddressSanitizer,
 * UBSan and LeakSanitizer.
 *
 * Every scenario runs for FMI 2.0 and FMI 3.0: it is written once against `Api`, a
 * table of thin wrappers around the fmi2* or fmi3* entry points. Value references are
 * looked up by name in the generated tables (kFmi2Variables, kFmi3Variables), never
 * hard-coded.
 *   1. happy path: instantiate, set l and omega_init, initialize with a stop time,
 *      500 x (set A, doStep(t_k, h), get outputs); outputs vs the truth, and bitwise
 *      vs the core run directly on the same samples (gf9_step with dt = the previous
 *      communication step, and gf9_solve with dt = h, as docs/fmu.md promises);
 *   2. two instances (different l and motion) interleaved call by call = each alone;
 *   3. FMU states: get at mid-run / replay / set back / replay bitwise; serialize ->
 *      free -> deserialize -> set, into the same and into a fresh instance; corrupted
 *      serialized states are rejected without allocating anything (a flipped bit by the
 *      CRC-32, checked against an independent CRC; crafted contents with the CRC-32
 *      recomputed by the field checks); a corrupted state object, or one not made by
 *      this FMU, is refused by setFMUState (and not freed by freeFMUState);
 *   4. call-sequence errors return fmiXError and log a message naming the function;
 *   5. bad inputs: NaN in A (error naming A[i], outputs keep the last good sample),
 *      l <= 0 or not finite, wrong token, model exchange / scheduled execution;
 *   6. recovery: reset after an error, setFMUState after an error, then fresh runs;
 *   7. logging: per-instance environment pointers, debug logging on/off, FMI 2 '%'
 *      escaping (the FMI 2 logger formats, the FMI 3 one must get the text verbatim),
 *      the FMI 2 callback struct is not needed after fmi2Instantiate.
 * Every instance and FMU state is freed, so LeakSanitizer checks the glue for leaks.
 *
 * Truth: a closed-form motion (f, omega, omega_dot as functions of t, below); the nine
 * sensor outputs are computed here from the layout of seed 000, independently of the
 * core's forward model, as
 *     A_i = theta_i . (f + omega_dot x u_i + omega (omega . u_i) - |omega|^2 u_i).
 *
 * Tolerances (only the truth comparison has any; everything else is bitwise): each
 * solved quantity is a sum of at most 6 outputs of magnitude <= S = max_i |A_i|,
 * scaled by at most 1/(2 l); with the few-ulp round-off of the A_i computed here its
 * error is far below 64 eps S / l (~1.6e-12 for S ~ 11 m/s^2, l = 0.1 m), which we
 * allow for omega_dot and omega_sq, and 64 eps S for f. A rate comes from
 * sqrt(omega_sq): |sqrt(a) - sqrt(b)| <= |a - b| / |omega|, so it gets
 * 64 eps S / l / |omega|, checked only where |omega| > 1e-3 rad/s (near a zero
 * crossing the magnitude is lost in round-off; the sign there is the omega_dot
 * integral's). */
#include <float.h>
#include <stdarg.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "fmu_instance.h" /* FmuSnapshot (to corrupt states), model_vars.h */
#include "fmu_state_ref.h"  /* the serialized format and an independent CRC-32 */
#include "gyrofree/gf9.h"
#include "gf_test.h"

/* ---- samples and truth ------------------------------------------------------------ */

enum { N = 500 };             /* samples per run */
#define H_S 0.01              /* communication step, s; sample k at t_k = k h */
#define RATE_MIN_RAD_S 1e-3   /* rates are compared with the truth above this magnitude */

typedef struct SampleSet {
    double l;                 /* lever arm, m */
    double omega_init[3];     /* the true rate at t_0 (gives the first signs) */
    double stop_s;            /* stop time of the experiment: t_N */
    double t[N];
    double A[N][9];           /* sensor outputs, the FMU's input */
    double f[N][3], w[N][3], wd[N][3];  /* truth */
} SampleSet;

static SampleSet g_set[2];    /* [0]: l = 0.1 m, motion 0; [1]: l = 0.05 m, motion 1 */

/* Smooth motion; omega_x crosses zero once (at t = 2 s for variant 0, 1.2 s for 1), so
 * the sign propagation is exercised, the other rates stay away from zero. */
static void motion(int variant, double t, double f[3], double w[3], double wd[3])
{
    const double a = variant == 0 ? 1.0 : 0.6;   /* amplitude scale of the rate wiggles */
    const double u = variant == 0 ? t : t + 0.8; /* time shift */
    f[0] = 1.0 + sin(0.7 * u);
    f[1] = -2.0 + 0.5 * cos(1.3 * u);
    f[2] = 9.8 + 0.2 * sin(0.3 * u);
    w[0] = 0.8 * a * sin(0.9 * (u - 2.0));
    wd[0] = 0.72 * a * cos(0.9 * (u - 2.0));
    w[1] = 1.5 + 0.3 * a * cos(0.9 * u);
    wd[1] = -0.27 * a * sin(0.9 * u);
    w[2] = -2.0 + 0.3 * a * u;
    wd[2] = 0.3 * a;
}

static void make_samples(SampleSet *s, int variant, double l)
{
    /* seed 000's layout: u_1..6 = +-l e_x,y,z along theta = +-e_x,y,z; u_7..9 = l[1,-1,0],
     * l[1,0,-1], l[0,1,-1] along [1,1,0]/sqrt2, [1,0,1]/sqrt2, [0,1,1]/sqrt2 */
    const double r = 1.0 / sqrt(2.0);
    const double u[9][3] = {{l, 0, 0}, {0, l, 0}, {0, 0, l}, {-l, 0, 0}, {0, -l, 0},
                            {0, 0, -l}, {l, -l, 0}, {l, 0, -l}, {0, l, -l}};
    const double th[9][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0},
                             {0, 0, -1}, {r, r, 0}, {r, 0, r}, {0, r, r}};
    s->l = l;
    s->stop_s = N * H_S;
    for (int k = 0; k < N; ++k) {
        s->t[k] = k * H_S;
        double *f = s->f[k], *w = s->w[k], *wd = s->wd[k];
        motion(variant, s->t[k], f, w, wd);
        const double ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        for (int i = 0; i < 9; ++i) {
            const double *p = u[i];
            const double wu = w[0] * p[0] + w[1] * p[1] + w[2] * p[2];
            const double wdxu[3] = {wd[1] * p[2] - wd[2] * p[1], wd[2] * p[0] - wd[0] * p[2],
                                    wd[0] * p[1] - wd[1] * p[0]};
            double acc = 0.0;
            for (int j = 0; j < 3; ++j)
                acc += th[i][j] * (f[j] + wdxu[j] + w[j] * wu - ww * p[j]);
            s->A[k][i] = acc;
        }
    }
    memcpy(s->omega_init, s->w[0], sizeof s->omega_init);
}

/* What is read back after one doStep. */
typedef struct Outputs {
    double f[3], omega[3], omega_dot[3], omega_sq[3];
    int32_t flags;
    double time_s;            /* FMU time after the step: fmi2LastSuccessfulTime / fmi3 VR 0 */
} Outputs;

/* 1 if a and b differ in any bit; describes the first difference in why. */
static int outputs_differ(const Outputs *a, const Outputs *b, char *why, size_t n_why)
{
    static const char *const names[4] = {"f", "omega", "omega_dot", "omega_sq"};
    const double *pa[4] = {a->f, a->omega, a->omega_dot, a->omega_sq};
    const double *pb[4] = {b->f, b->omega, b->omega_dot, b->omega_sq};
    for (int q = 0; q < 4; ++q)
        for (int j = 0; j < 3; ++j)
            if (memcmp(&pa[q][j], &pb[q][j], sizeof(double)) != 0) {
                snprintf(why, n_why, "%s[%d]: %.17g vs %.17g", names[q], j + 1, pa[q][j],
                         pb[q][j]);
                return 1;
            }
    if (a->flags != b->flags) {
        snprintf(why, n_why, "flags: %d vs %d", (int)a->flags, (int)b->flags);
        return 1;
    }
    if (memcmp(&a->time_s, &b->time_s, sizeof(double)) != 0) {
        snprintf(why, n_why, "time: %.17g vs %.17g", a->time_s, b->time_s);
        return 1;
    }
    return 0;
}

static void check_same_outputs(const char *what, const Outputs *a, const Outputs *b, int k0,
                               int k1)
{
    char why[256] = "";
    int first = -1;
    for (int k = k0; k < k1 && first < 0; ++k)
        if (outputs_differ(&a[k], &b[k], why, sizeof why))
            first = k;
    CHECK(first < 0, "%s: outputs differ first at sample %d: %s", what, first, why);
}

/* The reference: the core's gf9_step on the same samples, with the interval the model
 * integrates over: the previous communication step (none before the first sample,
 * whose dt the solver ignores). The time is the one the FMU must report. */
static void core_run(const SampleSet *s, Outputs out[N], gf9_state *final)
{
    gf9_state st;
    CHECK(gf9_init(&st, s->l, s->omega_init) == GF_OK, "core reference: gf9_init");
    double previous_step_s = 0.0;
    for (int k = 0; k < N; ++k) {
        gf9_output o;
        const gf_status rc = gf9_step(&st, s->A[k], previous_step_s, &o);
        if (rc != GF_OK) {
            CHECK(0, "core reference: gf9_step failed at sample %d: %s", k, gf_status_string(rc));
            return;
        }
        previous_step_s = H_S;
        memcpy(out[k].f, o.f_m_s2, sizeof out[k].f);
        memcpy(out[k].omega, o.omega_rad_s, sizeof out[k].omega);
        memcpy(out[k].omega_dot, o.omega_dot_rad_s2, sizeof out[k].omega_dot);
        memcpy(out[k].omega_sq, o.omega_sq_rad2_s2, sizeof out[k].omega_sq);
        out[k].flags = (int32_t)o.flags;
        out[k].time_s = s->t[k] + H_S;
    }
    if (final)
        *final = st;
}

/* Largest error relative to its tolerance over a run, and where it occurred. */
typedef struct Worst {
    double ratio, got, want, tol;
    int k, j;
} Worst;

static void worst_add(Worst *w, int k, int j, double got, double want, double tol)
{
    double ratio = fabs(got - want) / tol;
    if (isnan(ratio))
        ratio = INFINITY;
    if (ratio > w->ratio) {
        w->ratio = ratio;
        w->got = got;
        w->want = want;
        w->tol = tol;
        w->k = k;
        w->j = j;
    }
}

static void worst_check(const char *what, const char *quantity, const Worst *w)
{
    CHECK(w->ratio <= 1.0, "%s: %s[%d] at sample %d: %.17g vs truth %.17g (|diff| %.3g > tol %.3g)",
          what, quantity, w->j + 1, w->k, w->got, w->want, fabs(w->got - w->want), w->tol);
}

static void check_truth(const char *what, const SampleSet *s, const Outputs out[N])
{
    Worst wf = {-1.0, 0, 0, 0, -1, 0}, wwd = wf, wsq = wf, ww = wf; /* ratio -1: none yet */
    int n_rates = 0, n_flagged = 0, first_flagged = -1;
    for (int k = 0; k < N; ++k) {
        double S = 0.0;
        for (int i = 0; i < 9; ++i)
            S = fmax(S, fabs(s->A[k][i]));
        const double tol_lin = 64 * DBL_EPSILON * S / s->l;
        int all_rates_large = 1;
        for (int j = 0; j < 3; ++j) {
            const double w = s->w[k][j];
            worst_add(&wf, k, j, out[k].f[j], s->f[k][j], 64 * DBL_EPSILON * S);
            worst_add(&wwd, k, j, out[k].omega_dot[j], s->wd[k][j], tol_lin);
            worst_add(&wsq, k, j, out[k].omega_sq[j], w * w, tol_lin);
            if (fabs(w) > RATE_MIN_RAD_S) {
                worst_add(&ww, k, j, out[k].omega[j], w, tol_lin / fabs(w));
                ++n_rates;
            } else {
                all_rates_large = 0;
            }
        }
        /* no omega^2 < 0 and no unknown sign is possible when every |omega_k| > 1e-3 */
        if (all_rates_large && out[k].flags != 0 && n_flagged++ == 0)
            first_flagged = k;
    }
    worst_check(what, "f", &wf);
    worst_check(what, "omega_dot", &wwd);
    worst_check(what, "omega_sq", &wsq);
    worst_check(what, "omega", &ww);
    CHECK(n_rates > 3 * N * 9 / 10, "%s: only %d of %d rates away from zero: truth check vacuous",
          what, n_rates, 3 * N);
    CHECK(n_flagged == 0, "%s: %d samples flagged although every rate is > %g rad/s (first: "
          "sample %d, flags %d)", what, n_flagged, RATE_MIN_RAD_S, first_flagged,
          first_flagged >= 0 ? (int)out[first_flagged].flags : 0);
}

/* ---- logger capture ----------------------------------------------------------------- */

#define LOG_MESSAGE_MAX 4096
#define LOG_TEXT_MAX 8192

/* The importer's environment of one instance: its FMI 2 callbacks and the messages it
 * received. (The glue copies the logger and environment out of the callbacks; that the
 * struct is not needed after fmi2Instantiate is checked in test_fmi2_only.) */
typedef struct Env {
    fmi2CallbackFunctions callbacks2;
    int n_messages, n_errors;
    int last_status;
    char last_instance[64], last_category[64], last_message[LOG_MESSAGE_MAX];
    char text[LOG_TEXT_MAX]; /* every message since env_clear, one per line */
} Env;

static int g_stray_messages; /* messages that arrived without an environment pointer */

static void env_clear(Env *env)
{
    env->n_messages = env->n_errors = 0;
    env->last_status = -1;
    env->last_instance[0] = env->last_category[0] = env->last_message[0] = '\0';
    env->text[0] = '\0';
}

static void env_record(void *environment, const char *instance_name, int status,
                       int error_status, const char *category, const char *message)
{
    Env *env = (Env *)environment;
    if (!env) {
        ++g_stray_messages;
        return;
    }
    ++env->n_messages;
    if (status == error_status)
        ++env->n_errors;
    env->last_status = status;
    snprintf(env->last_instance, sizeof env->last_instance, "%s",
             instance_name ? instance_name : "(null)");
    snprintf(env->last_category, sizeof env->last_category, "%s", category ? category : "(null)");
    snprintf(env->last_message, sizeof env->last_message, "%s", message ? message : "(null)");
    const size_t used = strlen(env->text);
    snprintf(env->text + used, sizeof env->text - used, "%s\n", env->last_message);
}

/* The FMI 2.0 logger is printf-like: format the message with its arguments, as an
 * importer does. */
static void logger2(fmi2ComponentEnvironment environment, fmi2String instance_name,
                    fmi2Status status, fmi2String category, fmi2String message, ...)
{
    char text[LOG_MESSAGE_MAX];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message, args);
    va_end(args);
    env_record(environment, instance_name, (int)status, (int)fmi2Error, category, text);
}

static void logger3(fmi3InstanceEnvironment environment, fmi3Status status,
                    fmi3String category, fmi3String message)
{
    env_record(environment, NULL, (int)status, (int)fmi3Error, category, message);
}

static void env_init2(Env *env)
{
    env_clear(env);
    env->callbacks2.logger = logger2;
    env->callbacks2.allocateMemory = NULL;
    env->callbacks2.freeMemory = NULL;
    env->callbacks2.stepFinished = NULL;
    env->callbacks2.componentEnvironment = env;
}

static int mentions(const Env *env, const char *needle)
{
    return !needle || strstr(env->text, needle) != NULL;
}

/* ---- value references, looked up by name --------------------------------------------- */

static struct {
    fmi2ValueReference l, omega_init[3], A[9], out[12], flags;
} V2;
static struct {
    fmi3ValueReference l, omega_init, A, f, omega, omega_dot, omega_sq, flags;
} V3;
static unsigned int g_unknown_vr; /* a value reference that neither table has */

static unsigned int lookup(const char *version, const FmuVariable *table, size_t n,
                           const char *name, FmuType type, FmuCausality causality, size_t count)
{
    for (size_t i = 0; i < n; ++i)
        if (strcmp(table[i].name, name) == 0) {
            CHECK(table[i].type == type && table[i].causality == causality &&
                      table[i].count == count,
                  "%s table: variable %s has type %d causality %d count %zu, expected %d %d %zu",
                  version, name, (int)table[i].type, (int)table[i].causality, table[i].count,
                  (int)type, (int)causality, count);
            if (table[i].value_reference >= g_unknown_vr)
                g_unknown_vr = table[i].value_reference + 1000;
            return table[i].value_reference;
        }
    CHECK(0, "%s table: no variable named %s", version, name);
    return 0xFFFFFFFFu;
}

static void init_value_references(void)
{
    static const char *const out_names[4] = {"f", "omega", "omega_dot", "omega_sq"};
    const size_t n2 = sizeof kFmi2Variables / sizeof kFmi2Variables[0];
    const size_t n3 = sizeof kFmi3Variables / sizeof kFmi3Variables[0];
    char name[32];
    g_unknown_vr = 1000;
    V2.l = lookup("FMI 2", kFmi2Variables, n2, "l", FMU_TYPE_FLOAT64, FMU_CAUSALITY_PARAMETER, 1);
    for (int i = 0; i < 3; ++i) {
        snprintf(name, sizeof name, "omega_init[%d]", i + 1);
        V2.omega_init[i] = lookup("FMI 2", kFmi2Variables, n2, name, FMU_TYPE_FLOAT64,
                                  FMU_CAUSALITY_PARAMETER, 1);
    }
    for (int i = 0; i < 9; ++i) {
        snprintf(name, sizeof name, "A[%d]", i + 1);
        V2.A[i] = lookup("FMI 2", kFmi2Variables, n2, name, FMU_TYPE_FLOAT64,
                         FMU_CAUSALITY_INPUT, 1);
    }
    for (int q = 0; q < 4; ++q)
        for (int j = 0; j < 3; ++j) {
            snprintf(name, sizeof name, "%s[%d]", out_names[q], j + 1);
            V2.out[3 * q + j] = lookup("FMI 2", kFmi2Variables, n2, name, FMU_TYPE_FLOAT64,
                                       FMU_CAUSALITY_OUTPUT, 1);
        }
    V2.flags = lookup("FMI 2", kFmi2Variables, n2, "flags", FMU_TYPE_INT32,
                      FMU_CAUSALITY_OUTPUT, 1);

    V3.l = lookup("FMI 3", kFmi3Variables, n3, "l", FMU_TYPE_FLOAT64, FMU_CAUSALITY_PARAMETER, 1);
    V3.omega_init = lookup("FMI 3", kFmi3Variables, n3, "omega_init", FMU_TYPE_FLOAT64,
                           FMU_CAUSALITY_PARAMETER, 3);
    V3.A = lookup("FMI 3", kFmi3Variables, n3, "A", FMU_TYPE_FLOAT64, FMU_CAUSALITY_INPUT, 9);
    fmi3ValueReference *outs[4] = {&V3.f, &V3.omega, &V3.omega_dot, &V3.omega_sq};
    for (int q = 0; q < 4; ++q)
        *outs[q] = lookup("FMI 3", kFmi3Variables, n3, out_names[q], FMU_TYPE_FLOAT64,
                          FMU_CAUSALITY_OUTPUT, 3);
    V3.flags = lookup("FMI 3", kFmi3Variables, n3, "flags", FMU_TYPE_INT32,
                      FMU_CAUSALITY_OUTPUT, 1);
}

/* ---- the two APIs behind one interface ----------------------------------------------- */

typedef struct Api {
    const char *label;                          /* "FMI 2.0" / "FMI 3.0" */
    /* function names the glue must put into its messages */
    const char *get_fn, *set_fn, *step_fn, *enter_fn, *exit_fn;
    int ok, error;                              /* fmiXOK, fmiXError */
    const unsigned int *vr_l, *vr_f, *vr_flags;
    size_t n_f;                                 /* values behind vr_f: 1 (FMI 2), 3 (FMI 3) */
    void *(*instantiate)(Env *env, const char *name, const char *token, int logging_on);
    void (*free_instance)(void *c);
    int (*set_debug_logging)(void *c, int on);
    int (*enter_init)(void *c, double start_s, double stop_s);
    int (*exit_init)(void *c);
    int (*terminate)(void *c);
    int (*reset)(void *c);
    int (*set_parameters)(void *c, double l, const double omega_init[3]);
    int (*set_inputs)(void *c, const double A[9]);
    int (*get_outputs)(void *c, Outputs *o);
    /* one value reference; FMI 2 needs n_values == 1 */
    int (*set_float)(void *c, const unsigned int *vr, const double *v, size_t n_values);
    int (*get_float)(void *c, const unsigned int *vr, double *v, size_t n_values);
    int (*do_step)(void *c, double t_s, double h_s);
    int (*get_state)(void *c, void **state);
    int (*set_state)(void *c, void *state);
    int (*free_state)(void *c, void **state);
    int (*serialized_size)(void *c, void *state, size_t *size);
    int (*serialize)(void *c, void *state, uint8_t *buffer, size_t size);
    int (*deserialize)(void *c, const uint8_t *buffer, size_t size, void **state);
} Api;

/* FMI 2.0 */
static void *instantiate2(Env *env, const char *name, const char *token, int logging_on)
{
    env_init2(env);
    return fmi2Instantiate(name, fmi2CoSimulation, token, "file:///nonexistent/resources",
                           &env->callbacks2, fmi2False, logging_on ? fmi2True : fmi2False);
}
static void free2(void *c) { fmi2FreeInstance(c); }
static int debug2(void *c, int on)
{
    return fmi2SetDebugLogging(c, on ? fmi2True : fmi2False, 0, NULL);
}
static int enter2(void *c, double start_s, double stop_s)
{
    const fmi2Status st = fmi2SetupExperiment(c, fmi2False, 0.0, start_s, fmi2True, stop_s);
    return st != fmi2OK ? (int)st : (int)fmi2EnterInitializationMode(c);
}
static int exit2(void *c) { return fmi2ExitInitializationMode(c); }
static int terminate2(void *c) { return fmi2Terminate(c); }
static int reset2(void *c) { return fmi2Reset(c); }
static int parameters2(void *c, double l, const double omega_init[3])
{
    const fmi2ValueReference vr[4] = {V2.l, V2.omega_init[0], V2.omega_init[1], V2.omega_init[2]};
    const fmi2Real v[4] = {l, omega_init[0], omega_init[1], omega_init[2]};
    return fmi2SetReal(c, vr, 4, v);
}
static int inputs2(void *c, const double A[9]) { return fmi2SetReal(c, V2.A, 9, A); }
static int outputs2(void *c, Outputs *o)
{
    fmi2Real v[12], t_s;
    fmi2Integer flags;
    fmi2Status st = fmi2GetReal(c, V2.out, 12, v);
    if (st == fmi2OK)
        st = fmi2GetInteger(c, &V2.flags, 1, &flags);
    if (st == fmi2OK)
        st = fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t_s);
    if (st != fmi2OK)
        return st;
    memcpy(o->f, v, sizeof o->f);
    memcpy(o->omega, v + 3, sizeof o->omega);
    memcpy(o->omega_dot, v + 6, sizeof o->omega_dot);
    memcpy(o->omega_sq, v + 9, sizeof o->omega_sq);
    o->flags = flags;
    o->time_s = t_s;
    return fmi2OK;
}
static int set_float2(void *c, const unsigned int *vr, const double *v, size_t n_values)
{
    return fmi2SetReal(c, vr, n_values, v);
}
static int get_float2(void *c, const unsigned int *vr, double *v, size_t n_values)
{
    return fmi2GetReal(c, vr, n_values, v);
}
static int step2(void *c, double t_s, double h_s) { return fmi2DoStep(c, t_s, h_s, fmi2True); }
static int get_state2(void *c, void **s) { return fmi2GetFMUstate(c, s); }
static int set_state2(void *c, void *s) { return fmi2SetFMUstate(c, s); }
static int free_state2(void *c, void **s) { return fmi2FreeFMUstate(c, s); }
static int size2(void *c, void *s, size_t *n) { return fmi2SerializedFMUstateSize(c, s, n); }
static int serialize2(void *c, void *s, uint8_t *b, size_t n)
{
    return fmi2SerializeFMUstate(c, s, (fmi2Byte *)b, n);
}
static int deserialize2(void *c, const uint8_t *b, size_t n, void **s)
{
    return fmi2DeSerializeFMUstate(c, (const fmi2Byte *)b, n, s);
}

static const Api kApi2 = {
    "FMI 2.0", "fmi2GetReal", "fmi2SetReal", "fmi2DoStep", "fmi2SetupExperiment",
    "fmi2ExitInitializationMode", (int)fmi2OK, (int)fmi2Error, &V2.l, &V2.out[0], &V2.flags, 1,
    instantiate2, free2, debug2, enter2, exit2, terminate2, reset2, parameters2, inputs2,
    outputs2, set_float2, get_float2, step2, get_state2, set_state2, free_state2, size2,
    serialize2, deserialize2};

/* FMI 3.0 */
static void *instantiate3(Env *env, const char *name, const char *token, int logging_on)
{
    env_clear(env);
    return fmi3InstantiateCoSimulation(name, token, "/nonexistent/resources/", fmi3False,
                                       logging_on ? fmi3True : fmi3False, fmi3False, fmi3False,
                                       NULL, 0, env, logger3, NULL);
}
static void free3(void *c) { fmi3FreeInstance(c); }
static int debug3(void *c, int on)
{
    return fmi3SetDebugLogging(c, on ? fmi3True : fmi3False, 0, NULL);
}
static int enter3(void *c, double start_s, double stop_s)
{
    return fmi3EnterInitializationMode(c, fmi3False, 0.0, start_s, fmi3True, stop_s);
}
static int exit3(void *c) { return fmi3ExitInitializationMode(c); }
static int terminate3(void *c) { return fmi3Terminate(c); }
static int reset3(void *c) { return fmi3Reset(c); }
static int parameters3(void *c, double l, const double omega_init[3])
{
    const fmi3ValueReference vr[2] = {V3.l, V3.omega_init};
    const fmi3Float64 v[4] = {l, omega_init[0], omega_init[1], omega_init[2]};
    return fmi3SetFloat64(c, vr, 2, v, 4);
}
static int inputs3(void *c, const double A[9]) { return fmi3SetFloat64(c, &V3.A, 1, A, 9); }
static int outputs3(void *c, Outputs *o)
{
    const fmi3ValueReference vr[5] = {0 /* time */, V3.f, V3.omega, V3.omega_dot, V3.omega_sq};
    fmi3Float64 v[13];
    fmi3Int32 flags;
    fmi3Status st = fmi3GetFloat64(c, vr, 5, v, 13);
    if (st == fmi3OK)
        st = fmi3GetInt32(c, &V3.flags, 1, &flags, 1);
    if (st != fmi3OK)
        return st;
    o->time_s = v[0];
    memcpy(o->f, v + 1, sizeof o->f);
    memcpy(o->omega, v + 4, sizeof o->omega);
    memcpy(o->omega_dot, v + 7, sizeof o->omega_dot);
    memcpy(o->omega_sq, v + 10, sizeof o->omega_sq);
    o->flags = flags;
    return fmi3OK;
}
static int set_float3(void *c, const unsigned int *vr, const double *v, size_t n_values)
{
    return fmi3SetFloat64(c, vr, 1, v, n_values);
}
static int get_float3(void *c, const unsigned int *vr, double *v, size_t n_values)
{
    return fmi3GetFloat64(c, vr, 1, v, n_values);
}
static int step3(void *c, double t_s, double h_s)
{
    fmi3Boolean event_needed = fmi3True, terminate = fmi3True, early = fmi3True;
    fmi3Float64 last_s = -1.0;
    return fmi3DoStep(c, t_s, h_s, fmi3True, &event_needed, &terminate, &early, &last_s);
}
static int get_state3(void *c, void **s) { return fmi3GetFMUState(c, s); }
static int set_state3(void *c, void *s) { return fmi3SetFMUState(c, s); }
static int free_state3(void *c, void **s) { return fmi3FreeFMUState(c, s); }
static int size3(void *c, void *s, size_t *n) { return fmi3SerializedFMUStateSize(c, s, n); }
static int serialize3(void *c, void *s, uint8_t *b, size_t n)
{
    return fmi3SerializeFMUState(c, s, b, n);
}
static int deserialize3(void *c, const uint8_t *b, size_t n, void **s)
{
    return fmi3DeserializeFMUState(c, b, n, s);
}

static const Api kApi3 = {
    "FMI 3.0", "fmi3GetFloat64", "fmi3SetFloat64", "fmi3DoStep", "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode", (int)fmi3OK, (int)fmi3Error, &V3.l, &V3.f, &V3.flags, 3,
    instantiate3, free3, debug3, enter3, exit3, terminate3, reset3, parameters3, inputs3,
    outputs3, set_float3, get_float3, step3, get_state3, set_state3, free_state3, size3,
    serialize3, deserialize3};

/* ---- driving one instance -------------------------------------------------------------- */

#define STATE_BUF 4096 /* room for one serialized FMU state */

typedef struct Fmu {
    const Api *api;
    void *c;
    Env env; /* must not move while c lives: the glue keeps pointers into it */
} Fmu;

static int fmu_open(Fmu *m, const Api *api, const char *name, int logging_on)
{
    m->api = api;
    m->c = api->instantiate(&m->env, name, INSTANTIATION_TOKEN, logging_on);
    CHECK(m->c != NULL, "%s: instantiating \"%s\" with the right token returned NULL; log: %s",
          api->label, name, m->env.text);
    return m->c != NULL;
}

static void fmu_close(Fmu *m)
{
    if (m->c)
        m->api->free_instance(m->c);
    m->c = NULL;
}

/* Parameters of s, initialization mode with s's stop time, step mode. */
static int fmu_initialize(Fmu *m, const SampleSet *s, const char *scenario)
{
    const Api *api = m->api;
    int st = api->set_parameters(m->c, s->l, s->omega_init);
    if (st == api->ok)
        st = api->enter_init(m->c, 0.0, s->stop_s);
    if (st == api->ok)
        st = api->exit_init(m->c);
    CHECK(st == api->ok, "%s %s: initialization returned status %d; log: %s", api->label,
          scenario, st, m->env.text);
    return st == api->ok;
}

static int fmu_open_ready(Fmu *m, const Api *api, const char *name, const SampleSet *s)
{
    if (!fmu_open(m, api, name, 0))
        return 0;
    if (fmu_initialize(m, s, name))
        return 1;
    fmu_close(m);
    return 0;
}

/* One sample: set A, doStep(t_k, h), read the outputs. */
static int fmu_sample(Fmu *m, const SampleSet *s, int k, Outputs *o)
{
    const Api *api = m->api;
    int st = api->set_inputs(m->c, s->A[k]);
    if (st == api->ok)
        st = api->do_step(m->c, s->t[k], H_S);
    if (st == api->ok)
        st = api->get_outputs(m->c, o);
    return st;
}

/* Samples [k0, k1) into out[k]; returns the number of the first failed sample, or k1. */
static int fmu_run(Fmu *m, const SampleSet *s, int k0, int k1, Outputs *out, const char *scenario)
{
    for (int k = k0; k < k1; ++k) {
        const int st = fmu_sample(m, s, k, &out[k]);
        if (st != m->api->ok) {
            CHECK(0, "%s %s: sample %d (t = %g s) returned status %d; log: %s", m->api->label,
                  scenario, k, s->t[k], st, m->env.text);
            return k;
        }
    }
    return k1;
}

/* White box: the core's solver state inside the FMU, read from a serialized FMU state
 * (header, then the FmuSnapshot of fmu_instance.h). */
static int fmu_solver_state(Fmu *m, gf9_state *solver)
{
    static uint8_t buffer[STATE_BUF];
    const Api *api = m->api;
    void *state = NULL;
    size_t size = 0;
    const int ok = api->get_state(m->c, &state) == api->ok &&
                   api->serialized_size(m->c, state, &size) == api->ok &&
                   size > sizeof(FmuSnapshot) && size <= STATE_BUF &&
                   api->serialize(m->c, state, buffer, size) == api->ok;
    if (state)
        api->free_state(m->c, &state);
    CHECK(ok, "%s: getting and serializing an FMU state failed (size %zu); log: %s", api->label,
          size, m->env.text);
    if (ok)
        memcpy(solver, buffer + size - sizeof(FmuSnapshot) + offsetof(FmuSnapshot, data) +
                           offsetof(ModelData, solver), sizeof *solver);
    return ok;
}

/* The call returned fmiXError and logged an error naming mention1 and mention2. */
static void expect_error(Fmu *m, int status, const char *scenario, const char *mention1,
                         const char *mention2)
{
    const Api *api = m->api;
    CHECK(status == api->error, "%s %s: returned status %d, expected %d (Error)", api->label,
          scenario, status, api->error);
    CHECK(m->env.n_errors > 0, "%s %s: no error message was logged", api->label, scenario);
    CHECK(mentions(&m->env, mention1) && mentions(&m->env, mention2),
          "%s %s: the logged message does not mention \"%s\" and \"%s\": \"%s\"", api->label,
          scenario, mention1, mention2 ? mention2 : "", m->env.text);
    env_clear(&m->env);
}

/* ---- 1. happy path ---------------------------------------------------------------------- */

static void test_happy_path(const Api *api)
{
    static Outputs fmu_out[N], core_out[N];
    const SampleSet *s = &g_set[0];
    char what[64];
    snprintf(what, sizeof what, "%s happy path", api->label);
    Fmu m;
    if (!fmu_open(&m, api, "happy", 0))
        return;
    const int done =
        fmu_initialize(&m, s, "happy path") ? fmu_run(&m, s, 0, N, fmu_out, "happy path") : 0;
    gf9_state fmu_solver, core_solver;
    const int have_solver = done == N && fmu_solver_state(&m, &fmu_solver);
    CHECK(m.env.n_messages == 0, "%s: %d messages logged with logging off; first ones: %s", what,
          m.env.n_messages, m.env.text);
    const int st = api->terminate(m.c);
    CHECK(st == api->ok, "%s: terminate returned %d; log: %s", what, st, m.env.text);
    fmu_close(&m);
    if (done != N)
        return;
    check_truth(what, s, fmu_out);
    core_run(s, core_out, &core_solver);
    snprintf(what, sizeof what, "%s happy path vs gf9_step", api->label);
    check_same_outputs(what, fmu_out, core_out, 0, N);
    /* the omega_dot integral reaches the outputs only through signs: compare it too
     * (gf9_state has no padding, so memcmp compares exactly its fields) */
    CHECK(!have_solver || memcmp(&fmu_solver, &core_solver, sizeof fmu_solver) == 0,
          "%s: the FMU's solver state after %d samples differs from gf9_step's: omega_ref "
          "[%.17g %.17g %.17g] vs [%.17g %.17g %.17g], n_samples %llu vs %llu", what, N,
          fmu_solver.omega_ref_rad_s[0], fmu_solver.omega_ref_rad_s[1],
          fmu_solver.omega_ref_rad_s[2], core_solver.omega_ref_rad_s[0],
          core_solver.omega_ref_rad_s[1], core_solver.omega_ref_rad_s[2],
          (unsigned long long)fmu_solver.n_samples, (unsigned long long)core_solver.n_samples);

    /* the batch solver with dt = h (docs/fmu.md: the FMU computes it bit for bit) */
    static double f[N][3], w[N][3], wd[N][3], wsq[N][3];
    static uint8_t flags[N];
    gf9_state solver;
    size_t n_done = 0;
    const int solved = gf9_init(&solver, s->l, s->omega_init) == GF_OK &&
                       gf9_solve(&solver, N, &s->A[0][0], H_S, &f[0][0], &w[0][0], &wd[0][0],
                                 &wsq[0][0], flags, &n_done) == GF_OK && n_done == N;
    CHECK(solved, "%s: gf9_solve reference failed after %zu samples", what, n_done);
    for (int k = 0; k < N && solved; ++k) {
        Outputs o = fmu_out[k]; /* time: gf9_solve has none, keep the FMU's */
        memcpy(o.f, f[k], sizeof o.f);
        memcpy(o.omega, w[k], sizeof o.omega);
        memcpy(o.omega_dot, wd[k], sizeof o.omega_dot);
        memcpy(o.omega_sq, wsq[k], sizeof o.omega_sq);
        o.flags = flags[k];
        core_out[k] = o;
    }
    snprintf(what, sizeof what, "%s happy path vs gf9_solve(dt = h)", api->label);
    if (solved)
        check_same_outputs(what, fmu_out, core_out, 0, N);
}

/* ---- 2. two instances ------------------------------------------------------------------- */

static void test_two_instances(const Api *api)
{
    static Outputs alone[2][N], together[2][N];
    char what[96];
    for (int i = 0; i < 2; ++i) {
        Fmu m;
        if (!fmu_open_ready(&m, api, i ? "alone_b" : "alone_a", &g_set[i]))
            return;
        const int done = fmu_run(&m, &g_set[i], 0, N, alone[i], "two instances: alone");
        fmu_close(&m);
        if (done != N)
            return;
    }
    /* sanity: the two runs really differ, or the comparison below proves nothing */
    char why[256];
    CHECK(outputs_differ(&alone[0][N - 1], &alone[1][N - 1], why, sizeof why),
          "%s two instances: the two sample sets give identical outputs", api->label);

    Fmu m[2];
    const int open_a = fmu_open_ready(&m[0], api, "inst_a", &g_set[0]);
    const int open_b = open_a && fmu_open_ready(&m[1], api, "inst_b", &g_set[1]);
    if (!open_b) {
        if (open_a)
            fmu_close(&m[0]);
        return;
    }
    /* interleaved call by call: set A (a, b), doStep (a, b), get (a, b) */
    int failed_at = -1, st = api->ok;
    for (int k = 0; k < N && failed_at < 0; ++k) {
        for (int i = 0; i < 2 && st == api->ok; ++i)
            st = api->set_inputs(m[i].c, g_set[i].A[k]);
        for (int i = 0; i < 2 && st == api->ok; ++i)
            st = api->do_step(m[i].c, g_set[i].t[k], H_S);
        for (int i = 0; i < 2 && st == api->ok; ++i)
            st = api->get_outputs(m[i].c, &together[i][k]);
        if (st != api->ok)
            failed_at = k;
    }
    CHECK(failed_at < 0,
          "%s two instances: interleaved sample %d returned status %d; logs: %s | %s",
          api->label, failed_at, st, m[0].env.text, m[1].env.text);
    if (failed_at < 0)
        for (int i = 0; i < 2; ++i) {
            snprintf(what, sizeof what, "%s two instances: instance %c interleaved vs alone",
                     api->label, i ? 'b' : 'a');
            check_same_outputs(what, together[i], alone[i], 0, N);
        }

    /* an error in b is reported to b's environment only */
    const double v = 1.0;
    st = api->set_float(m[1].c, &g_unknown_vr, &v, 1);
    CHECK(m[0].env.n_messages == 0 && m[1].env.n_errors == 1,
          "%s two instances: an error of b reached a's logger %d times and b's %d times (1 "
          "expected)", api->label, m[0].env.n_messages, m[1].env.n_errors);
    expect_error(&m[1], st, "two instances: unknown value reference in b", api->set_fn, NULL);
    fmu_close(&m[0]);
    fmu_close(&m[1]);
}

/* ---- 3. FMU states -------------------------------------------------------------------- */

static size_t find_bytes(const uint8_t *hay, size_t n_hay, const char *needle)
{
    const size_t n = strlen(needle);
    for (size_t i = 0; i + n <= n_hay; ++i)
        if (memcmp(hay + i, needle, n) == 0)
            return i;
    return (size_t)-1;
}

/* A corrupted buffer must be rejected with an error, a log line, and no state. */
static void expect_rejected_state(Fmu *m, const uint8_t *bytes, size_t size, const char *scenario)
{
    void *state = NULL;
    const int st = m->api->deserialize(m->c, bytes, size, &state);
    CHECK(state == NULL, "%s %s: a state was returned for a corrupted buffer", m->api->label,
          scenario);
    if (state)
        m->api->free_state(m->c, &state);
    expect_error(m, st, scenario, "deserializ", NULL);
}

static void test_corrupted_states(Fmu *m, const SampleSet *s, const uint8_t *good, size_t size)
{
    static uint8_t bad[STATE_BUF + 1];
    const Api *api = m->api;
    CHECK(size > sizeof(FmuSnapshot), "%s: serialized size %zu <= snapshot size %zu", api->label,
          size, sizeof(FmuSnapshot));
    if (size <= sizeof(FmuSnapshot))
        return;
    const size_t snap = size - sizeof(FmuSnapshot); /* the snapshot follows the header */
    env_clear(&m->env);

    memcpy(bad, good, size);
    expect_rejected_state(m, bad, size - 1, "deserialize: one byte short");
    bad[size] = 0;
    expect_rejected_state(m, bad, size + 1, "deserialize: one byte too many");
    expect_rejected_state(m, bad, 0, "deserialize: zero bytes");
    bad[0] ^= 0x20;
    expect_rejected_state(m, bad, size, "deserialize: first (magic) byte flipped");

    memcpy(bad, good, size);
    const size_t at = find_bytes(good, size, INSTANTIATION_TOKEN);
    CHECK(at != (size_t)-1, "%s: the serialized state does not carry the instantiation token",
          api->label);
    if (at != (size_t)-1) {
        bad[at + 1] = bad[at + 1] == '0' ? '1' : '0';
        expect_rejected_state(m, bad, size, "deserialize: state of another build (token)");
    }

    /* the header's CRC-32 is that of the snapshot bytes (an independent bitwise CRC);
     * a flipped bit anywhere after the header is refused by it */
    CHECK(snap == REF_STATE_HEADER_SIZE, "%s: header of %zu bytes, docs/fmu.md says %d",
          api->label, snap, REF_STATE_HEADER_SIZE);
    CHECK(ref_crc32_check(), "the reference CRC-32 misses the check value");
    CHECK(ref_state_crc(good) == ref_crc32(good + snap, size - snap),
          "%s: the header's CRC-32 is not the CRC-32 of the snapshot", api->label);
    const size_t flips[4] = {snap, snap + offsetof(FmuSnapshot, data), size / 2, size - 1};
    for (int i = 0; i < 4; ++i) {
        memcpy(bad, good, size);
        bad[flips[i]] ^= 0x10;
        void *state = NULL;
        const int st = api->deserialize(m->c, bad, size, &state);
        CHECK(st == api->error && state == NULL && mentions(&m->env, "CRC-32"),
              "%s: a bit flipped at byte %zu was not refused by the CRC-32: %s", api->label,
              flips[i], m->env.text);
        env_clear(&m->env);
    }

    /* crafted states (the CRC-32 recomputed) are checked field by field */
    const uint32_t bad_modes[3] = {0u, FMU_MODE_STEP | FMU_MODE_ERROR, 1u << 7};
    for (int i = 0; i < 3; ++i) {
        memcpy(bad, good, size);
        memcpy(bad + snap + offsetof(FmuSnapshot, mode), &bad_modes[i], sizeof(uint32_t));
        ref_state_fix_crc(bad, size);
        expect_rejected_state(m, bad, size, "deserialize: invalid mode");
    }

    /* Bytes that pass the header checks but hold non-finite values must not make the
     * FMU compute: either deserialization or the next doStep is rejected. */
    const double nan_value = NAN;
    const double t_s = s->t[N / 2];
    const struct {
        const char *what;
        size_t offset;
    } poison[2] = {
        {"lever arm of the solver NaN",
         offsetof(FmuSnapshot, data) + offsetof(ModelData, solver) +
             offsetof(gf9_state, lever_arm_m)},
        {"FMU time NaN", offsetof(FmuSnapshot, time_s)},
    };
    for (int i = 0; i < 2; ++i) {
        memcpy(bad, good, size);
        memcpy(bad + snap + poison[i].offset, &nan_value, sizeof nan_value);
        ref_state_fix_crc(bad, size);
        void *state = NULL;
        int st = api->deserialize(m->c, bad, size, &state);
        int step_st = api->error;
        if (st == api->ok) {
            st = api->set_state(m->c, state);
            step_st = api->do_step(m->c, t_s, H_S);
            api->free_state(m->c, &state);
        }
        CHECK(step_st == api->error,
              "%s deserialize: state with the %s accepted, and doStep(%g, %g) then returned %d "
              "instead of an error", api->label, poison[i].what, t_s, H_S, step_st);
        env_clear(&m->env);
    }

    /* A state object handed back to setFMUState is checked again: its contents, and its
     * tag (a state of another FMU, or not a state, is neither used nor freed). */
    void *obj = NULL;
    CHECK(api->get_state(m->c, &obj) == api->ok && obj != NULL, "%s: getFMUState", api->label);
    if (obj) {
        FmuState *p = (FmuState *)obj;
        const double saved = p->s.data.solver.lever_arm_m;
        p->s.data.solver.lever_arm_m = nan_value;
        expect_error(m, api->set_state(m->c, obj), "setFMUState: lever arm NaN in the object",
                     "setFMUState", "refused");
        p->s.data.solver.lever_arm_m = saved;
        p->tag[0] ^= 0x20;
        expect_error(m, api->set_state(m->c, obj), "setFMUState: not this FMU's state",
                     "setFMUState", "not made by this FMU");
        expect_error(m, api->free_state(m->c, &obj), "freeFMUState: not this FMU's state",
                     "freeFMUState", "not freed");
        CHECK(obj != NULL, "%s: a foreign state object was freed", api->label);
        p->tag[0] ^= 0x20;
        CHECK(api->set_state(m->c, obj) == api->ok, "%s: the repaired state object is refused: %s",
              api->label, m->env.text);
        api->free_state(m->c, &obj);
    }
}

static void test_states(const Api *api)
{
    static Outputs ref[N], again[N], restored[N], other[N];
    static uint8_t buffer[STATE_BUF];
    const SampleSet *s = &g_set[0];
    const int mid = N / 2;
    char what[96];
    Fmu m;
    if (!fmu_open_ready(&m, api, "states", s))
        return;
    void *state = NULL;
    /* the first get allocates, the second reuses the state it is handed */
    int ok = fmu_run(&m, s, 0, mid / 2, ref, "states") == mid / 2 &&
             api->get_state(m.c, &state) == api->ok && state != NULL &&
             fmu_run(&m, s, mid / 2, mid, ref, "states") == mid &&
             api->get_state(m.c, &state) == api->ok &&
             fmu_run(&m, s, mid, N, ref, "states") == N;
    CHECK(ok, "%s states: run with getFMUState at %d and %d failed; log: %s", api->label, mid / 2,
          mid, m.env.text);
    if (ok) {
        ok = api->set_state(m.c, state) == api->ok && fmu_run(&m, s, mid, N, again, "states") == N;
        CHECK(ok, "%s states: setFMUState + replay failed; log: %s", api->label, m.env.text);
        snprintf(what, sizeof what, "%s states: replay after setFMUState", api->label);
        if (ok)
            check_same_outputs(what, again, ref, mid, N);
    }

    size_t size = 0;
    ok = ok && api->serialized_size(m.c, state, &size) == api->ok && size > 0 &&
         size <= STATE_BUF && api->serialize(m.c, state, buffer, size) == api->ok;
    CHECK(ok, "%s states: serializing failed (size %zu); log: %s", api->label, size, m.env.text);
    const int freed = api->free_state(m.c, &state);
    CHECK(freed == api->ok && state == NULL, "%s states: freeFMUState returned %d, state %p",
          api->label, freed, state);
    if (!ok) {
        fmu_close(&m);
        return;
    }

    /* deserialize into the same instance (which is at the end of the run now) */
    void *state2 = NULL;
    ok = api->deserialize(m.c, buffer, size, &state2) == api->ok && state2 != NULL &&
         api->set_state(m.c, state2) == api->ok && fmu_run(&m, s, mid, N, restored, "states") == N;
    CHECK(ok, "%s states: deserialize + set + replay failed; log: %s", api->label, m.env.text);
    snprintf(what, sizeof what, "%s states: replay after deserialize", api->label);
    if (ok)
        check_same_outputs(what, restored, ref, mid, N);
    if (state2)
        api->free_state(m.c, &state2);

    /* ... and into a fresh instance, which has not been initialized */
    Fmu o;
    if (fmu_open(&o, api, "states_other", 0)) {
        void *state3 = NULL;
        ok = api->deserialize(o.c, buffer, size, &state3) == api->ok &&
             api->set_state(o.c, state3) == api->ok &&
             fmu_run(&o, s, mid, N, other, "states: other instance") == N;
        CHECK(ok, "%s states: deserialize into another instance failed; log: %s", api->label,
              o.env.text);
        snprintf(what, sizeof what, "%s states: replay in another instance", api->label);
        if (ok)
            check_same_outputs(what, other, ref, mid, N);
        if (state3)
            api->free_state(o.c, &state3);
        fmu_close(&o);
    }

    test_corrupted_states(&m, s, buffer, size);
    fmu_close(&m);
}

/* ---- 4. call-sequence errors ------------------------------------------------------------- */

static void test_call_sequence(const Api *api)
{
    const SampleSet *s = &g_set[0];
    const double one = 1.0, three[3] = {1.0, 2.0, 3.0};
    double l = 0.0, v[3];
    Outputs o;
    Fmu m;

    /* Instantiated mode */
    if (!fmu_open(&m, api, "sequence", 0))
        return;
    expect_error(&m, api->get_outputs(m.c, &o), "get in Instantiated mode", api->get_fn,
                 "Instantiated");
    expect_error(&m, api->do_step(m.c, 0.0, H_S), "doStep in Instantiated mode", api->step_fn,
                 "Instantiated");
    expect_error(&m, api->exit_init(m.c), "exitInitializationMode in Instantiated mode",
                 api->exit_fn, "Instantiated");

    /* Initialization mode */
    int st = api->set_parameters(m.c, s->l, s->omega_init);
    if (st == api->ok)
        st = api->enter_init(m.c, 0.0, s->stop_s);
    CHECK(st == api->ok, "%s sequence: entering initialization returned %d; log: %s", api->label,
          st, m.env.text);
    expect_error(&m, api->do_step(m.c, 0.0, H_S), "doStep before exitInitializationMode",
                 api->step_fn, "InitializationMode");
    expect_error(&m, api->enter_init(m.c, 0.0, s->stop_s), "enter initialization again",
                 api->enter_fn, "InitializationMode");
    st = api->exit_init(m.c);
    CHECK(st == api->ok, "%s sequence: exitInitializationMode returned %d; log: %s", api->label,
          st, m.env.text);

    /* Step mode */
    expect_error(&m, api->exit_init(m.c), "exitInitializationMode twice", api->exit_fn, "StepMode");
    expect_error(&m, api->set_parameters(m.c, 0.2, s->omega_init), "setting the fixed parameter "
                 "l in step mode", api->set_fn, "variable l ");
    st = api->get_float(m.c, api->vr_l, &l, 1);
    CHECK(st == api->ok && l == s->l, "%s sequence: l = %g after the rejected set (status %d), "
          "expected %g", api->label, l, st, s->l);
    expect_error(&m, api->set_float(m.c, api->vr_f, three, api->n_f), "setting an output",
                 api->set_fn, "output");
    expect_error(&m, api->set_float(m.c, &g_unknown_vr, &one, 1), "set with an unknown value "
                 "reference", api->set_fn, "unknown value reference");
    expect_error(&m, api->get_float(m.c, &g_unknown_vr, v, 1), "get with an unknown value "
                 "reference", api->get_fn, "unknown value reference");
    expect_error(&m, api->get_float(m.c, api->vr_flags, v, 1), "Float64 get of the Int32 flags",
                 api->get_fn, "flags");
    st = api->terminate(m.c);
    CHECK(st == api->ok, "%s sequence: terminate returned %d; log: %s", api->label, st, m.env.text);
    expect_error(&m, api->do_step(m.c, 0.0, H_S), "doStep after terminate", api->step_fn,
                 "Terminated");
    expect_error(&m, api->set_inputs(m.c, s->A[0]), "set after terminate", api->set_fn,
                 "Terminated");
    fmu_close(&m);

    /* doStep arguments, each on a fresh instance in step mode at t = 0 */
    const struct {
        const char *scenario, *mention;
        double t_s, h_s;
    } steps[] = {
        {"doStep at a communication point other than the FMU time", "communication point",
         0.5, H_S},
        {"doStep past the stop time", "stop time", 0.0, 2.0 * s->stop_s},
        {"doStep with h = 0", "step size", 0.0, 0.0},
        {"doStep with h < 0", "step size", 0.0, -H_S},
        {"doStep with h = NaN", "step size", 0.0, NAN},
        {"doStep at t = NaN", "communication point", NAN, H_S},
    };
    for (size_t i = 0; i < sizeof steps / sizeof steps[0]; ++i) {
        if (!fmu_open_ready(&m, api, "sequence_step", s))
            return;
        expect_error(&m, api->do_step(m.c, steps[i].t_s, steps[i].h_s), steps[i].scenario,
                     api->step_fn, steps[i].mention);
        fmu_close(&m);
    }
}

/* ---- 5. bad inputs and failed instantiation ------------------------------------------------ */

static void test_bad_inputs(const Api *api)
{
    static Outputs out[N];
    const SampleSet *s = &g_set[0];
    enum { K_BAD = 10 };
    Fmu m;

    /* NaN in A[5]: error naming the input; the outputs keep the last good sample */
    if (fmu_open_ready(&m, api, "nan_input", s)) {
        if (fmu_run(&m, s, 0, K_BAD, out, "NaN input") == K_BAD) {
            double A[9];
            memcpy(A, s->A[K_BAD], sizeof A);
            A[4] = NAN;
            int st = api->set_inputs(m.c, A);
            CHECK(st == api->ok, "%s NaN input: setting A returned %d", api->label, st);
            expect_error(&m, api->do_step(m.c, s->t[K_BAD], H_S), "doStep with A[5] = NaN",
                         "A[5]", "not finite");
            Outputs o;
            char why[256];
            st = api->get_outputs(m.c, &o);
            CHECK(st == api->ok, "%s NaN input: reading outputs after the error returned %d; "
                  "log: %s", api->label, st, m.env.text);
            CHECK(st != api->ok || !outputs_differ(&o, &out[K_BAD - 1], why, sizeof why),
                  "%s NaN input: outputs changed by the failed step (now vs last good: %s)",
                  api->label, why);
            st = api->terminate(m.c);
            CHECK(st == api->ok, "%s NaN input: terminate after the error returned %d; log: %s",
                  api->label, st, m.env.text);
        }
        fmu_close(&m);
    }

    /* invalid parameters: exitInitializationMode fails naming the parameter */
    const double bad_l[4] = {0.0, -0.1, NAN, INFINITY};
    for (int i = 0; i < 4; ++i) {
        if (!fmu_open(&m, api, "bad_l", 0))
            return;
        int st = api->set_parameters(m.c, bad_l[i], s->omega_init);
        if (st == api->ok)
            st = api->enter_init(m.c, 0.0, s->stop_s);
        CHECK(st == api->ok, "%s l = %g: setting it / entering initialization returned %d",
              api->label, bad_l[i], st);
        char scenario[64];
        snprintf(scenario, sizeof scenario, "exitInitializationMode with l = %g", bad_l[i]);
        expect_error(&m, api->exit_init(m.c), scenario, "parameter l =", NULL);
        fmu_close(&m);
    }
    if (fmu_open(&m, api, "bad_omega_init", 0)) {
        const double w0[3] = {0.0, NAN, 0.0};
        int st = api->set_parameters(m.c, s->l, w0);
        if (st == api->ok)
            st = api->enter_init(m.c, 0.0, s->stop_s);
        CHECK(st == api->ok, "%s omega_init = NaN: setup returned %d", api->label, st);
        expect_error(&m, api->exit_init(m.c), "exitInitializationMode with omega_init[2] = NaN",
                     "omega_init", NULL);
        fmu_close(&m);
    }

    /* failed instantiation: NULL, and a message through the logger */
    const struct {
        const char *scenario, *name, *token, *mention;
    } inst[] = {
        {"instantiate with a wrong token", "wrong_token", "{00000000-0000-0000-0000-000000000000}",
         "token"},
        {"instantiate with a NULL token", "null_token", NULL, "token"},
        {"instantiate with an empty instance name", "", INSTANTIATION_TOKEN, "instance name"},
    };
    for (size_t i = 0; i < sizeof inst / sizeof inst[0]; ++i) {
        m.api = api;
        m.c = api->instantiate(&m.env, inst[i].name, inst[i].token, 0);
        CHECK(m.c == NULL, "%s %s: returned an instance", api->label, inst[i].scenario);
        fmu_close(&m);
        CHECK(m.env.n_errors == 1 && mentions(&m.env, inst[i].mention),
              "%s %s: expected one error message mentioning \"%s\", got %d: %s", api->label,
              inst[i].scenario, inst[i].mention, m.env.n_errors, m.env.text);
    }
}

/* ---- 6. recovery after errors ------------------------------------------------------------ */

static void test_recovery(const Api *api)
{
    static Outputs core_out[N], out[N];
    const SampleSet *s = &g_set[0];
    enum { K_BAD = 10 };
    char what[96];
    Fmu m;
    core_run(s, core_out, NULL);

    /* doStep error (NaN input) -> reset -> Instantiated -> a fresh run */
    if (!fmu_open_ready(&m, api, "recovery", s))
        return;
    double A[9];
    memcpy(A, s->A[K_BAD], sizeof A);
    A[0] = NAN;
    int st = fmu_run(&m, s, 0, K_BAD, out, "recovery") == K_BAD ? api->set_inputs(m.c, A) : -1;
    if (st == api->ok)
        st = api->do_step(m.c, s->t[K_BAD], H_S);
    CHECK(st == api->error, "%s recovery: doStep with a NaN input returned %d", api->label, st);
    env_clear(&m.env);
    st = api->reset(m.c);
    CHECK(st == api->ok, "%s recovery: reset after a doStep error returned %d; log: %s",
          api->label, st, m.env.text);
    Outputs o;
    expect_error(&m, api->get_outputs(m.c, &o), "get right after reset (Instantiated)",
                 api->get_fn, "Instantiated");
    if (fmu_initialize(&m, s, "recovery after reset") &&
        fmu_run(&m, s, 0, N, out, "recovery after reset") == N) {
        snprintf(what, sizeof what, "%s fresh run after reset vs gf9_step", api->label);
        check_same_outputs(what, out, core_out, 0, N);
    }

    /* exitInitializationMode error (l = 0) -> reset -> a fresh run */
    st = api->reset(m.c);
    if (st == api->ok)
        st = api->set_parameters(m.c, 0.0, s->omega_init);
    if (st == api->ok)
        st = api->enter_init(m.c, 0.0, s->stop_s);
    CHECK(st == api->ok, "%s recovery: reset / l = 0 / enter returned %d", api->label, st);
    st = api->exit_init(m.c);
    CHECK(st == api->error, "%s recovery: exitInitializationMode with l = 0 returned %d",
          api->label, st);
    st = api->reset(m.c);
    CHECK(st == api->ok, "%s recovery: reset after an initialization error returned %d",
          api->label, st);
    env_clear(&m.env);
    if (fmu_initialize(&m, s, "recovery after a failed initialization") &&
        fmu_run(&m, s, 0, N, out, "recovery after a failed initialization") == N) {
        snprintf(what, sizeof what, "%s fresh run after a failed initialization vs gf9_step",
                 api->label);
        check_same_outputs(what, out, core_out, 0, N);
    }
    fmu_close(&m);

    /* doStep error -> setFMUState to a state taken before it -> continue */
    if (!fmu_open_ready(&m, api, "recovery_state", s))
        return;
    void *state = NULL;
    st = fmu_run(&m, s, 0, K_BAD, out, "recovery by state") == K_BAD
             ? api->get_state(m.c, &state)
             : -1;
    if (st == api->ok)
        st = api->set_inputs(m.c, A);
    if (st == api->ok)
        st = api->do_step(m.c, s->t[K_BAD], H_S);
    CHECK(st == api->error, "%s recovery by state: doStep with a NaN input returned %d",
          api->label, st);
    env_clear(&m.env);
    if (state) {
        st = api->set_state(m.c, state);
        CHECK(st == api->ok,
              "%s recovery by state: setFMUState after the error returned %d; log: %s",
              api->label, st, m.env.text);
        if (st == api->ok && fmu_run(&m, s, K_BAD, N, out, "recovery by state") == N) {
            snprintf(what, sizeof what, "%s run continued from a state after an error vs gf9_step",
                     api->label);
            check_same_outputs(what, out, core_out, K_BAD, N);
        }
        st = api->free_state(m.c, &state);
        CHECK(st == api->ok && state == NULL, "%s recovery by state: freeFMUState returned %d",
              api->label, st);
    }
    fmu_close(&m);
}

/* ---- 7. logging ------------------------------------------------------------------------ */

static void test_logging(const Api *api)
{
    const SampleSet *s = &g_set[0];
    Fmu m;
    if (!fmu_open(&m, api, "verbose", 1))
        return;
    if (fmu_initialize(&m, s, "logging")) {
        CHECK(m.env.n_messages > 0 && m.env.n_errors == 0 && m.env.last_status == api->ok &&
                  mentions(&m.env, "initialized"),
              "%s logging on: expected an OK message about the initialization, got %d messages "
              "(%d errors, last status %d): %s", api->label, m.env.n_messages, m.env.n_errors,
              m.env.last_status, m.env.text);
        int st = api->set_debug_logging(m.c, 0);
        CHECK(st == api->ok, "%s logging: setDebugLogging(false) returned %d", api->label, st);
        env_clear(&m.env);
        st = api->terminate(m.c);
        CHECK(st == api->ok && m.env.n_messages == 0,
              "%s logging off: terminate returned %d and logged %d messages: %s", api->label, st,
              m.env.n_messages, m.env.text);
        /* errors are reported whatever the debug logging */
        expect_error(&m, api->do_step(m.c, 0.0, H_S), "doStep after terminate, logging off",
                     api->step_fn, NULL);
    }
    fmu_close(&m);
}

/* A token full of printf conversions comes back verbatim in the error message: the
 * FMI 2 glue doubles '%' because its logger formats, the FMI 3 one must not. Only
 * integer conversions: if the escaping broke, the formatting logger would read garbage
 * integers (a wrong message, which fails cleanly) rather than garbage pointers. */
static void test_percent_round_trip(const Api *api)
{
    static char token[1100], expected[1200];
    Env env;
    const char *tokens[2] = {"tok-%d-%%-%x-50%", NULL};
    /* 1000 '%': the 1024-byte message still holds them all; doubled they fill 2000 bytes */
    memset(token, '%', 1000);
    token[1000] = '\0';
    tokens[1] = token;
    for (int i = 0; i < 2; ++i) {
        void *c = api->instantiate(&env, "percent", tokens[i], 0);
        CHECK(c == NULL, "%s '%%' token: instantiate returned an instance", api->label);
        if (c)
            api->free_instance(c);
        snprintf(expected, sizeof expected, "token %s", tokens[i]);
        CHECK(env.n_errors == 1 && strstr(env.last_message, expected) != NULL,
              "%s: a token with '%%' (%zu characters) does not come back verbatim; expected "
              "\"%.60s...\" in: \"%.300s\"", api->label, strlen(tokens[i]), expected,
              env.last_message);
    }
}

/* ---- version-specific -------------------------------------------------------------------- */

static void test_fmi2_only(void)
{
    const SampleSet *s = &g_set[0];
    Env env;
    env_init2(&env);
    void *c = fmi2Instantiate("me", fmi2ModelExchange, INSTANTIATION_TOKEN, NULL,
                              &env.callbacks2, fmi2False, fmi2False);
    CHECK(c == NULL && env.n_errors == 1 && mentions(&env, "co-simulation"),
          "FMI 2.0 fmi2Instantiate(fmi2ModelExchange): instance %p, %d errors logged: %s", c,
          env.n_errors, env.text);
    if (c)
        fmi2FreeInstance(c);
    c = fmi2Instantiate("no_callbacks", fmi2CoSimulation, INSTANTIATION_TOKEN, NULL, NULL,
                        fmi2False, fmi2False);
    CHECK(c == NULL, "FMI 2.0 fmi2Instantiate without callbacks returned an instance");
    if (c)
        fmi2FreeInstance(c);

    /* the callback struct need not outlive fmi2Instantiate: wiping it afterwards must not
     * change where messages go */
    fmi2CallbackFunctions callbacks = {logger2, NULL, NULL, NULL, &env};
    env_clear(&env);
    c = fmi2Instantiate("wiped_callbacks", fmi2CoSimulation, INSTANTIATION_TOKEN, NULL,
                        &callbacks, fmi2False, fmi2False);
    CHECK(c != NULL, "FMI 2.0 fmi2Instantiate(\"wiped_callbacks\") returned NULL: %s", env.text);
    if (c) {
        memset(&callbacks, 0, sizeof callbacks);
        const fmi2Status st2 = fmi2DoStep(c, 0.0, H_S, fmi2True);
        CHECK(st2 == fmi2Error && env.n_errors == 1 && mentions(&env, "fmi2DoStep"),
              "FMI 2.0 with the callback struct wiped after instantiation: doStep returned %d, "
              "%d errors reached the original logger: %s", st2, env.n_errors, env.text);
        fmi2FreeInstance(c);
    }

    Fmu m;
    if (!fmu_open(&m, &kApi2, "fmi2_only", 0))
        return;
    fmi2Status st = fmi2SetupExperiment(m.c, fmi2False, 0.0, 0.0, fmi2True, s->stop_s);
    if (st == fmi2OK)
        st = fmi2EnterInitializationMode(m.c);
    CHECK(st == fmi2OK, "FMI 2.0 setupExperiment + enterInitializationMode returned %d", st);
    expect_error(&m, fmi2SetupExperiment(m.c, fmi2False, 0.0, 0.0, fmi2True, s->stop_s),
                 "fmi2SetupExperiment after fmi2EnterInitializationMode", "fmi2SetupExperiment",
                 "InitializationMode");
    /* the error carries the instance name and the category of errors */
    const double l = 0.5;
    st = fmi2SetReal(m.c, &g_unknown_vr, 1, &l);
    CHECK(m.env.last_status == (int)fmi2Error && strcmp(m.env.last_instance, "fmi2_only") == 0 &&
              strcmp(m.env.last_category, "logStatusError") == 0,
          "FMI 2.0 logger: status %d, instance \"%s\", category \"%s\"; expected %d, "
          "\"fmi2_only\", \"logStatusError\"", m.env.last_status, m.env.last_instance,
          m.env.last_category, (int)fmi2Error);
    expect_error(&m, st, "unknown value reference", "fmi2SetReal", NULL);
    expect_error(&m, fmi2EnterInitializationMode(m.c), "fmi2EnterInitializationMode twice",
                 "fmi2EnterInitializationMode", NULL);
    fmu_close(&m);
}

static void test_fmi3_only(void)
{
    const SampleSet *s = &g_set[0];
    Env env;
    env_clear(&env);
    void *c = fmi3InstantiateModelExchange("me", INSTANTIATION_TOKEN, NULL, fmi3False, fmi3False,
                                           &env, logger3);
    CHECK(c == NULL && env.n_errors == 1, "FMI 3.0 fmi3InstantiateModelExchange: instance %p, "
          "%d errors logged: %s", c, env.n_errors, env.text);
    if (c)
        fmi3FreeInstance(c);
    env_clear(&env);
    c = fmi3InstantiateScheduledExecution("se", INSTANTIATION_TOKEN, NULL, fmi3False, fmi3False,
                                          &env, logger3, NULL, NULL, NULL);
    CHECK(c == NULL && env.n_errors == 1, "FMI 3.0 fmi3InstantiateScheduledExecution: instance "
          "%p, %d errors logged: %s", c, env.n_errors, env.text);
    if (c)
        fmi3FreeInstance(c);
    env_clear(&env);
    c = fmi3InstantiateCoSimulation("events", INSTANTIATION_TOKEN, NULL, fmi3False, fmi3False,
                                    fmi3True, fmi3False, NULL, 0, &env, logger3, NULL);
    CHECK(c == NULL && env.n_errors == 1 && mentions(&env, "event mode"),
          "FMI 3.0 co-simulation with eventModeUsed: instance %p, %d errors logged: %s", c,
          env.n_errors, env.text);
    if (c)
        fmi3FreeInstance(c);

    /* array access: nValues must match the elements exactly; nothing written past them */
    Fmu m;
    if (!fmu_open_ready(&m, &kApi3, "fmi3_only", s))
        return;
    const double A8[8] = {0};
    expect_error(&m, fmi3SetFloat64(m.c, &V3.A, 1, A8, 8), "set A with nValues = 8",
                 "fmi3SetFloat64", "nValues");
    double f2[2];
    expect_error(&m, fmi3GetFloat64(m.c, &V3.f, 1, f2, 2), "get f with nValues = 2",
                 "fmi3GetFloat64", "nValues");
    double t_s = -1.0;
    const fmi3ValueReference time_vr = 0;
    fmi3Status st = fmi3GetFloat64(m.c, &time_vr, 1, &t_s, 1);
    CHECK(st == fmi3OK && t_s == 0.0, "FMI 3.0 time (VR 0) after initialization: status %d, %g",
          st, t_s);
    expect_error(&m, fmi3SetFloat64(m.c, &time_vr, 1, &t_s, 1), "setting time (VR 0)",
                 "fmi3SetFloat64", NULL);
    st = fmi3EnterStepMode(m.c);
    CHECK(st == fmi3OK, "FMI 3.0 fmi3EnterStepMode in step mode returned %d", st);
    fmi3Boolean event_needed = fmi3True, terminate = fmi3True, early = fmi3True;
    fmi3Float64 last_s = -1.0;
    st = fmi3DoStep(m.c, 0.0, H_S, fmi3True, &event_needed, &terminate, &early, &last_s);
    CHECK(st == fmi3OK && !event_needed && !terminate && !early && last_s == H_S,
          "FMI 3.0 fmi3DoStep: status %d, eventHandlingNeeded %d, terminateSimulation %d, "
          "earlyReturn %d, lastSuccessfulTime %g (expected %g)", st, event_needed, terminate,
          early, last_s, H_S);
    st = fmi3DoStep(m.c, 0.5, H_S, fmi3True, &event_needed, &terminate, &early, &last_s);
    CHECK(st == fmi3Error && last_s == H_S, "FMI 3.0 rejected fmi3DoStep: status %d, "
          "lastSuccessfulTime %g (expected %g)", st, last_s, H_S);
    fmu_close(&m);
}

int main(void)
{
    make_samples(&g_set[0], 0, 0.1);
    make_samples(&g_set[1], 1, 0.05);
    init_value_references();
    const Api *const apis[2] = {&kApi2, &kApi3};
    for (int i = 0; i < 2; ++i) {
        test_happy_path(apis[i]);
        test_two_instances(apis[i]);
        test_states(apis[i]);
        test_call_sequence(apis[i]);
        test_bad_inputs(apis[i]);
        test_recovery(apis[i]);
        test_logging(apis[i]);
        test_percent_round_trip(apis[i]);
    }
    test_fmi2_only();
    test_fmi3_only();
    CHECK(g_stray_messages == 0, "%d messages reached a logger without the environment pointer",
          g_stray_messages);
    TEST_MAIN_END();
}
