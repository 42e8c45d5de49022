/* bench_gfnav.c — CPU time per sample of the gyro-free navigator (gf_gfnav_run) on one
 * core, without Python: the data of bench/bench_gfnav.py (Qin et al.'s constant body
 * rate [2, 2, 2] rad/s, gravity turning in the body, fixed frame, 1.4e-5 m/s^2 of
 * pseudo-noise) for cube6/integrate, qin9/sqrt, qin9/fused and 12/eigen.
 *
 *   cc -O3 -std=c11 -ffp-contract=off -I csrc bench/bench_gfnav.c build/libgfins_core.a -lm \
 *      -o bench_gfnav
 *   ./bench_gfnav [repeats] [case 0..3, -1 = all] [1 = linear rate model, else Hermite]
 *
 * Prints, per case, the smallest CPU time of the repeats (ns per sample): CPU time and
 * the minimum keep other processes' load out of the figure as far as they can; on a
 * shared machine alternate runs of the versions compared and compare minima and
 * medians. Instruction counts, which no load changes: valgrind --tool=callgrind
 * --toggle-collect=gf_gfnav_run ./bench_gfnav 1 <case>. */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base/gf_math.h"
#include "gyrofree/gf9.h"
#include "gyrofree/gf_array.h"
#include "gyrofree/gf_gfins.h"
#include "gyrofree/gf_gfnav.h"
#include "gyrofree/gf_layout.h"

enum { N = 200000 };
static double A[N * 12], q[N * 4], v[N * 3], p[N * 3];
static gf_gfnav_state st;

static double cpu_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    const int reps = argc > 1 ? atoi(argv[1]) : 15;
    const int which = argc > 2 ? atoi(argv[2]) : -1;
    const int linear = argc > 3 && atoi(argv[3]) == 1; /* 1: the linear rate model (GF_GFNAV_LINEAR) */
    const double dt = 0.01, w[3] = {2, 2, 2};
    const char *names[4] = {"cube6/integrate", "qin9/sqrt", "qin9/fused", "12/eigen"};
    const int strat[4] = {GF_RATE_INTEGRATE, GF_RATE_SQRT, GF_RATE_FUSED, GF_RATE_EIGEN};
    for (int c = 0; c < 4; ++c) {
        if (which >= 0 && c != which)
            continue;
        gf_array_geometry g;
        if (c == 0)
            gf_layout_cube6(0.1, &g);
        else if (c == 3)
            gf_layout_12(0.1, &g);
        else
            gf9_geometry(0.1, &g);
        const size_t ns = g.n_sensors;
        unsigned long long s = 12345;
        for (size_t k = 0; k < N; ++k) {
            const double ang = sqrt(12.0) * (double)k * dt, r3 = sin(ang / 2) / sqrt(3.0);
            const double qc[4] = {cos(ang / 2), -r3, -r3, -r3}, gn[3] = {0, 0, 9.8}, zero[3] = {0, 0, 0};
            double f[3];
            gf_q_rotate(qc, gn, f); /* f = C^T g */
            gf_array_forward(&g, 1, f, w, zero, A + ns * k, NULL);
            for (size_t i = 0; i < ns; ++i) { /* uniform pseudo-noise of std 1.4e-5 */
                s = s * 6364136223846793005ULL + 1442695040888963407ULL;
                A[ns * k + i] += 1.4e-5 * sqrt(12.0) * ((double)(s >> 11) / 9007199254740992.0 - 0.5);
            }
        }
        double best = 1e300;
        for (int r = 0; r < reps; ++r) {
            gf_rate_config rc;
            gf_rate_config_default(&rc);
            rc.strategy = strat[c];
            rc.accel_noise_m_s2 = 1.4e-5;
            gf_sins_config sc;
            gf_sins_config_default(&sc);
            sc.input = GF_SINS_INPUT_RATES;
            sc.earth = GF_SINS_EARTH_FLAT;
            sc.flat_gravity_m_s2 = 9.8;
            const double q0[4] = {1, 0, 0, 0}, v0[3] = {0, 0, 0};
            if (gf_gfnav_init(&st, &g, &rc, w, &sc, q0, v0, 0, 0, 0, 0, NULL) != GF_OK) {
                printf("%s: init failed\n", names[c]);
                return 1;
            }
            if (linear && gf_gfnav_set_integration(&st, GF_GFNAV_LINEAR) != GF_OK)
                return 1;
            size_t done = 0;
            const double t0 = cpu_s();
            const gf_status e = gf_gfnav_run(&st, N, A, dt, NULL, q, v, p, NULL, NULL, NULL, &done);
            const double el = cpu_s() - t0;
            if (e != GF_OK) {
                printf("%s: run failed (%s) at sample %zu\n", names[c], gf_status_string(e), done);
                return 1;
            }
            best = el < best ? el : best;
        }
        printf("%-16s %7.1f ns/sample  %5.2f M samples/s\n", names[c], best / N * 1e9, N / best / 1e6);
    }
    return 0;
}
