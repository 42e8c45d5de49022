/* fmu2_test.h — helpers for the C tests that drive one FMU model through the FMI 2.0
 * glue (test_fmu_vehicle.c, test_fmu_navigator.c): a logger collecting the messages in
 * g_log, the callbacks, value references by name from the generated table, and setters
 * by name. Include after fmu_instance.h (which brings the model's kFmi2Variables). */
#ifndef FMU2_TEST_H
#define FMU2_TEST_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
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

#endif /* FMU2_TEST_H */
