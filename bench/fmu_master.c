/* fmu_master.c — a minimal FMI 2.0 co-simulation master for timing one FMU's doStep.
 *
 *   fmu_master LIBRARY.so GUID RESOURCE_URI N_STEPS STEP_S IN_VRS OUT_VRS [INPUT.bin]
 *
 * Loads the FMU's shared library with dlopen, instantiates it, and times N_STEPS
 * iterations of { fmi2SetReal(inputs); fmi2DoStep; fmi2GetReal(outputs) } with the
 * inputs of row k of INPUT.bin (N_STEPS x n_in doubles; zeros without it). IN_VRS and
 * OUT_VRS are comma-separated value references ("-" for none). Prints the CPU time of
 * the process per iteration (CLOCK_PROCESS_CPUTIME_ID: robust to other jobs on a shared
 * machine), best and median of RUNS runs (default 5; each on a fresh instance), and a
 * checksum of the outputs. Built and run by bench/bench_cosim.py. */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    fprintf(stderr, "[%s %d %s] %s\n", name, (int)status, category, message);
}

static size_t parse_vrs(const char *text, fmi2ValueReference *out, size_t max)
{
    size_t n = 0;
    if (strcmp(text, "-") == 0)
        return 0;
    char *copy = strdup(text), *save = NULL;
    for (char *tok = strtok_r(copy, ",", &save); tok && n < max; tok = strtok_r(NULL, ",", &save))
        out[n++] = (fmi2ValueReference)strtoul(tok, NULL, 10);
    free(copy);
    return n;
}

#define LOAD(name)                                                                           \
    name##TYPE *name = (name##TYPE *)dlsym(lib, #name);                                      \
    if (!name) {                                                                             \
        fprintf(stderr, "missing %s\n", #name);                                              \
        return 1;                                                                            \
    }

int main(int argc, char **argv)
{
    if (argc < 8) {
        fprintf(stderr, "usage: %s LIB GUID RESOURCE_URI N_STEPS STEP_S IN_VRS OUT_VRS [INPUT.bin]\n", argv[0]);
        return 2;
    }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 1;
    }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2SetReal) LOAD(fmi2GetReal) LOAD(fmi2DoStep)
    LOAD(fmi2FreeInstance) LOAD(fmi2Terminate)
    const long n = atol(argv[4]);
    const double h = atof(argv[5]);
    fmi2ValueReference in_vr[64], out_vr[64];
    const size_t n_in = parse_vrs(argv[6], in_vr, 64), n_out = parse_vrs(argv[7], out_vr, 64);
    double *input = calloc((size_t)n * (n_in ? n_in : 1), sizeof *input);
    if (argc > 8) {
        FILE *f = fopen(argv[8], "rb");
        if (!f || fread(input, sizeof *input, (size_t)n * n_in, f) != (size_t)n * n_in) {
            fprintf(stderr, "cannot read %ld x %zu doubles from %s\n", n, n_in, argv[8]);
            return 1;
        }
        fclose(f);
    }
    const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    double best = 1e300, checksum = 0.0, times[99];
    const char *runs_env = getenv("FMU_MASTER_RUNS");
    int runs = runs_env ? atoi(runs_env) : 5;
    if (runs < 1 || runs > 99)
        runs = 5;
    for (int run = 0; run < runs; ++run) {
        fmi2Component c = fmi2Instantiate("bench", fmi2CoSimulation, argv[2], argv[3], &cb,
                                          fmi2False, fmi2False);
        if (!c || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
            fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK) {
            fprintf(stderr, "initialisation failed\n");
            return 1;
        }
        double out[64];
        checksum = 0.0;
        struct timespec t0, t1;
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
        for (long k = 0; k < n; ++k) {
            if (n_in && fmi2SetReal(c, in_vr, n_in, input + k * (long)n_in) != fmi2OK)
                return 1;
            if (fmi2DoStep(c, (double)k * h, h, fmi2True) != fmi2OK) {
                fprintf(stderr, "doStep failed at step %ld\n", k);
                return 1;
            }
            if (n_out && fmi2GetReal(c, out_vr, n_out, out) != fmi2OK)
                return 1;
            checksum += out[0];
        }
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
        const double dt = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        times[run] = dt;
        if (dt < best)
            best = dt;
        fmi2Terminate(c);
        fmi2FreeInstance(c);
    }
    for (int i = 1; i < runs; ++i) /* median: insertion sort of the few runs */
        for (int j = i; j > 0 && times[j] < times[j - 1]; --j) {
            const double t = times[j];
            times[j] = times[j - 1];
            times[j - 1] = t;
        }
    printf("%.1f ns per step CPU (median %.1f; set %zu + doStep + get %zu), best of %d x %ld "
           "steps; checksum %.17g\n", best / (double)n * 1e9, times[runs / 2] / (double)n * 1e9,
           n_in, n_out, runs, n, checksum);
    free(input);
    dlclose(lib);
    return 0;
}
