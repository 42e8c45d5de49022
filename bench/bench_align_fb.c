/* bench_align_fb.c — CPU time of one forward-backward pass of the alignment filter
 * (gf_ins_forward_backward, issue 13 / seed 003) on one core, without Python: 300 s of
 * 200 Hz increments of a manoeuvring vehicle (turns, speed changes) with tachometer speed
 * at 10 Hz and depth (a height measurement) at 1 Hz; EKF, 15 states, covariance
 * propagated every 0.1 s (the defaults).
 *
 *   gcc -O3 -ffp-contract=off -I csrc bench/bench_align_fb.c \
 *       $(find csrc -name 'gf*.c' | sort) -lm -o bench_align_fb
 *   ./bench_align_fb [seconds 300] [rate Hz 200] [fb passes 1] [repeats 7]
 *
 * Prints the best of the repeats (process CPU time) for: one forward pass alone, and the
 * forward pass followed by the requested forward-backward passes; the time of one
 * forward-backward pass (backward + forward) is their difference / passes. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "est/gf_ins_gnss.h"
#include "nav/gf_sins.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double run(size_t n, const double *t, const double *g, const double *a, size_t nm,
                  const gf_ins_meas *m, int n_fb, const gf_ins_config *cfg, const double *P0)
{
    gf_ins_filter f;
    int32_t bad, np;
    const double e[3] = {0.5, 0.0, 0.0};
    double q[4];
    gf_euler_to_quat(e, q);
    const double v0[3] = {4.5 * sin(0.5), 4.5 * cos(0.5), 0.0};
    if (gf_ins_init(&f, cfg, 0.0, q, v0, 0.5, 2.0, -50.0, NULL, P0, &bad) != GF_OK)
        exit(2);
    const double t0 = now_s();
    const gf_status st = gf_ins_forward_backward(&f, n, t, g, a, nm, m, n_fb, NULL, NULL, &np);
    const double el = now_s() - t0;
    if (st != GF_OK) {
        fprintf(stderr, "status %d after %d passes\n", (int)st, (int)np);
        exit(3);
    }
    return el;
}

int main(int argc, char **argv)
{
    const double dur = argc > 1 ? atof(argv[1]) : 300.0;
    const double rate = argc > 2 ? atof(argv[2]) : 200.0;
    const int n_fb = argc > 3 ? atoi(argv[3]) : 1;
    const int repeats = argc > 4 ? atoi(argv[4]) : 7;
    const double dt = 1.0 / rate;
    const size_t n = (size_t)(dur * rate);
    double *t = malloc(n * sizeof *t), *g = malloc(3 * n * sizeof *g), *a = malloc(3 * n * sizeof *a);
    const size_t nm = (size_t)(dur * 10.0) + (size_t)dur + 2;
    gf_ins_meas *m = calloc(nm, sizeof *m);
    if (!t || !g || !a || !m)
        return 1;
    for (size_t k = 0; k < n; ++k) {
        const double tk = dt * (double)(k + 1);
        t[k] = tk;
        g[3 * k] = 1e-3 * sin(0.3 * tk) * dt;
        g[3 * k + 1] = 0.0;
        g[3 * k + 2] = 0.05 * sin(2.0 * 3.14159265358979 * tk / 120.0) * dt;  /* turns */
        a[3 * k] = 0.2 * sin(2.0 * 3.14159265358979 * tk / 120.0) * dt;    /* centripetal */
        a[3 * k + 1] = 0.1 * cos(0.05 * tk) * dt;                           /* speed changes */
        a[3 * k + 2] = 9.7936 * dt;
    }
    size_t j = 0;
    for (size_t s = 1; s < (size_t)(dur * 10.0); ++s) {
        m[j].type = GF_INS_MEAS_SPEED;
        m[j].t_s = 0.1 * (double)s + 0.0013;
        m[j].z[0] = 4.5;
        m[j].std[0] = 0.05;
        ++j;
        if (s % 10 == 0) {
            m[j].type = GF_INS_MEAS_BARO;
            m[j].t_s = 0.1 * (double)s + 0.0013;
            m[j].z[0] = -50.0;
            m[j].std[0] = 0.1;
            ++j;
        }
    }
    gf_ins_config cfg;
    gf_ins_config_default(&cfg);
    cfg.noise.gyro_arw_rad_sqrt_s = 1e-6;
    cfg.noise.accel_vrw_m_s_sqrt_s = 1e-4;
    cfg.gate_probability = 0.9999;
    double P0[15 * 15] = {0};
    const double d[15] = {0.1, 0.1, 0.1, 1e-6, 1e-6, 1, 1e-3, 1e-3, 0.1, 1e-7, 1e-7, 1e-7, 1e-4, 1e-4, 1e-4};
    for (int i = 0; i < 15; ++i)
        P0[i * 15 + i] = d[i] * d[i];
    double best_f = 1e300, best_fb = 1e300;
    for (int r = 0; r < repeats; ++r) {
        const double ef = run(n, t, g, a, j, m, 0, &cfg, P0);
        const double efb = run(n, t, g, a, j, m, n_fb, &cfg, P0);
        best_f = ef < best_f ? ef : best_f;
        best_fb = efb < best_fb ? efb : best_fb;
    }
    printf("%.0f s at %.0f Hz (%zu samples, %zu measurements), EKF 15 states, propagation 0.1 s:\n"
           "  forward pass %.1f ms; forward + %d forward-backward pass(es) %.1f ms; "
           "one forward-backward pass (backward + forward) %.1f ms (%.0f ns per sample and direction)\n",
           dur, rate, n, j, best_f * 1e3, n_fb, best_fb * 1e3, (best_fb - best_f) / n_fb * 1e3,
           (best_fb - best_f) / n_fb / (2.0 * (double)n) * 1e9);
    free(t); free(g); free(a); free(m);
    return 0;
}
