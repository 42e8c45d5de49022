/* bench_sins.c — CPU time per input sample of the strapdown record driver (gf_sins_run)
 * on one core, without Python, for N = 1..4 increments per navigation update
 * (gf_sins_config.subsamples): the whole record in one C call, outputs preallocated
 * (one row per update). The record: exact increments of a horizontal sine-velocity
 * motion with a slow heading swing at 100 Hz, as bench/bench_sins.py (the increments are
 * built here from closed-form rates by 2-point Gauss-Legendre per interval; exactness
 * does not matter for timing), height held.
 *
 *   cc -O3 -std=c11 -ffp-contract=off -I csrc bench/bench_sins.c \
 *      $(find csrc -name 'gf*.c' | sort) -lm -o bench_sins
 *   ./bench_sins [samples (default 10^6)] [repeats (default 7)] [N, all of 1..4 if absent]
 *
 * Prints, per N, the smallest and the median CPU time of the repeats
 * (CLOCK_PROCESS_CPUTIME_ID: robust to a busy machine) in ns per input sample and
 * M samples/s, and the throughput relative to N = 1. Instruction counts, which no load
 * changes: valgrind --tool=callgrind --toggle-collect=gf_sins_run ./bench_sins 200000 1 N
 * Built on a core from before the subsample option (-I and sources of that tree) it times
 * that core's one-sample update: the baseline of the "today's throughput". */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nav/gf_sins.h"

#ifndef GF_SINS_MAX_SUBSAMPLES /* a core from before the option: N = 1 only (the baseline) */
#define GF_SINS_MAX_SUBSAMPLES 1
#define BASELINE_CORE 1
#endif

static double cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* body rate (rad/s) and specific force (m/s^2) of a vehicle swinging its heading by
 * 0.1 rad at 0.05 Hz while accelerating sinusoidally (a plausible level motion) */
static void motion(double t, double w[3], double f[3])
{
    const double W = 2.0 * 3.14159265358979323846 * 0.05;
    w[0] = 1e-4 * sin(0.3 * t);
    w[1] = 2e-4 * cos(0.2 * t);
    w[2] = 0.1 * W * cos(W * t);
    f[0] = 0.3 * sin(W * t);
    f[1] = 0.2 * cos(0.5 * W * t);
    f[2] = 9.7940;
}

int main(int argc, char **argv)
{
    const size_t n = argc > 1 ? (size_t)atol(argv[1]) : 1000000;
    int repeats = argc > 2 ? atoi(argv[2]) : 7;
    const int only = argc > 3 ? atoi(argv[3]) : 0;
    if (repeats < 1 || repeats > 99 || n < 4)
        return 2;
    const double dt = 0.01;
    double *g = malloc(3 * n * sizeof *g), *a = malloc(3 * n * sizeof *a);
    double *q = malloc(4 * n * sizeof *q), *v = malloc(3 * n * sizeof *v);
    double *p = malloc(3 * n * sizeof *p), *tt = malloc(n * sizeof *tt);
    if (!g || !a || !q || !v || !p || !tt)
        return 1;
    const double gl = 0.5 / sqrt(3.0);
    for (size_t k = 0; k < n; ++k) {
        const double t0 = dt * (double)k;
        double w1[3], f1[3], w2[3], f2[3];
        motion(t0 + (0.5 - gl) * dt, w1, f1);
        motion(t0 + (0.5 + gl) * dt, w2, f2);
        for (int i = 0; i < 3; ++i) {
            g[3 * k + i] = 0.5 * dt * (w1[i] + w2[i]);
            a[3 * k + i] = 0.5 * dt * (f1[i] + f2[i]);
        }
    }
    memset(q, 0, 4 * n * sizeof *q); memset(v, 0, 3 * n * sizeof *v);
    memset(p, 0, 3 * n * sizeof *p); memset(tt, 0, n * sizeof *tt);
    const double q0[4] = {1, 0, 0, 0}, v0[3] = {0, 0, 0};
    double best1 = 0.0;
    printf("gf_sins_run, %zu increments at 100 Hz, height held, one C call; CPU time, "
           "%d repeats\n", n, repeats);
    for (int N = 1; N <= GF_SINS_MAX_SUBSAMPLES; ++N) {
        if (only && N != only)
            continue;
        gf_sins_config cfg;
        gf_sins_config_default(&cfg);
        cfg.vertical = GF_SINS_VERTICAL_HOLD;
        cfg.hold_height_m = 100.0;
#ifndef BASELINE_CORE
        cfg.subsamples = N;
#endif
        double times[99];
        double checksum = 0.0;
        for (int r = 0; r < repeats; ++r) {
            gf_sins_state s;
            size_t done;
            if (gf_sins_init(&s, &cfg, q0, v0, 0.5, 2.0, 100.0, 0.0) != GF_OK)
                return 3;
            const double c0 = cpu_s();
            const gf_status st = gf_sins_run(&s, n, g, a, dt, NULL, NULL, 0, q, v, p, tt, &done);
            times[r] = cpu_s() - c0;
            if (st != GF_OK || done != n) {
                fprintf(stderr, "N = %d: status %d after %zu samples\n", N, (int)st, done);
                return 4;
            }
            checksum = p[3 * ((n + (size_t)N - 1) / (size_t)N - 1)];
        }
        qsort(times, (size_t)repeats, sizeof times[0], cmp_double);
        const double best = times[0], med = times[repeats / 2];
        if (N == 1)
            best1 = best;
        printf("N = %d: best %6.1f ns/sample (%6.2f M samples/s), median %6.1f ns/sample; "
               "throughput / N=1: %s%.2f; final lat %.12f rad\n",
               N, best / (double)n * 1e9, (double)n / best * 1e-6, med / (double)n * 1e9,
               best1 > 0.0 ? "" : "(N=1 not run) ", best1 > 0.0 ? best1 / best : 0.0, checksum);
    }
    free(g); free(a); free(q); free(v); free(p); free(tt);
    return 0;
}
