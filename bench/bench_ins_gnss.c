/* bench_ins_gnss.c — throughput of the integrated-navigation filter (gf_ins_run) on one
 * core, without Python: a 200 Hz IMU record of a vehicle-like motion (constant turn
 * rate and acceleration, enough to make every block of F non-zero) with 1 Hz GNSS
 * position + velocity at times between IMU samples, from an antenna 1.3 m from the IMU
 * (a lever arm fills the attitude and gyro-bias columns of H, as on a vehicle).
 *
 *   gcc -O3 -ffp-contract=off -I csrc bench/bench_ins_gnss.c \
 *       $(find csrc -name 'gf*.c' | sort) -lm -o bench_ins_gnss
 *   ./bench_ins_gnss [filter 0=EKF 1=UKF] [propagation interval s, 0 = every sample]
 *                    [samples] [repeats] [subsamples per navigation update, 1..4]
 *
 * Prints the best of the repeats (process CPU time) in IMU samples per second, and beside
 * it the strapdown mechanization alone (gf_sins_run, the filter's own settings, same
 * record, timed in alternation with the filter): on a shared machine both slow down
 * together, so their ratio says what the filter adds to the mechanization. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "est/gf_ins_gnss.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts); /* CPU time: robust to a busy machine */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    const int filter = argc > 1 ? atoi(argv[1]) : 0;
    const double prop = argc > 2 ? atof(argv[2]) : 0.1;
    const size_t n = argc > 3 ? (size_t)atol(argv[3]) : 1000000;
    const int repeats = argc > 4 ? atoi(argv[4]) : 3;
    const int subsamples = argc > 5 ? atoi(argv[5]) : 1;
    const double dt = 0.005;
    double *t = malloc(n * sizeof *t), *g = malloc(3 * n * sizeof *g), *a = malloc(3 * n * sizeof *a);
    const size_t m = (size_t)(n * dt) * 2;
    gf_ins_meas *meas = calloc(m + 1, sizeof *meas);
    double *out_buf = malloc(n * (1 + 4 + 3 + 3 + 9 + GF_INS_N_SENSORS) * sizeof(double));
    if (!t || !g || !a || !meas || !out_buf)
        return 1;
    for (size_t k = 0; k < n; ++k) {
        t[k] = dt * (double)(k + 1);
        g[3 * k] = 1e-4 * dt; g[3 * k + 1] = -2e-4 * dt; g[3 * k + 2] = 0.02 * dt;
        a[3 * k] = 0.2 * dt; a[3 * k + 1] = 0.3 * dt; a[3 * k + 2] = 9.79 * dt;
    }
    size_t nm = 0;
    for (size_t s = 1; nm + 1 < m && s < (size_t)(n * dt); ++s) {
        gf_ins_meas *p = meas + nm++, *v = meas + nm++;
        p->type = GF_INS_MEAS_GNSS_POS; p->t_s = (double)s + 0.0013;
        p->z[0] = 0.5; p->z[1] = 1.0; p->z[2] = 100.0;
        p->std[0] = p->std[1] = 1.0; p->std[2] = 2.0;
        v->type = GF_INS_MEAS_GNSS_VEL; v->t_s = p->t_s;
        v->std[0] = v->std[1] = v->std[2] = 0.1;
    }
    gf_ins_config cfg;
    gf_ins_config_default(&cfg);
    cfg.filter = filter;
    cfg.propagation_interval_s = prop;
    cfg.subsamples = subsamples;
    cfg.noise.gyro_arw_rad_sqrt_s = 1e-4; cfg.noise.accel_vrw_m_s_sqrt_s = 1e-3;
    cfg.noise.gyro_bias_std_rad_s = 5e-6; cfg.noise.gyro_bias_tau_s = 3600;
    cfg.noise.accel_bias_std_m_s2 = 1e-3; cfg.noise.accel_bias_tau_s = 3600;
    cfg.gnss_lever_arm_m[0] = 0.2; cfg.gnss_lever_arm_m[1] = -0.6; cfg.gnss_lever_arm_m[2] = 1.1;
    cfg.gate_probability = 0.0;   /* no gate, as in the figures of docs/benchmarks.md */
    cfg.gate_reset_count = 0;
    double P0[15 * 15] = {0};
    const double d[15] = {0.01, 0.01, 0.01, 1e-14, 1e-14, 1, 1e-4, 1e-4, 1e-3, 1e-11, 1e-11, 1e-11, 1e-6, 1e-6, 1e-6};
    for (int i = 0; i < 15; ++i)
        P0[i * 15 + i] = d[i];
    const double q[4] = {1, 0, 0, 0}, v0[3] = {0, 0, 0};
    gf_sins_config sc;
    gf_sins_config_default(&sc);
    sc.vertical = GF_SINS_VERTICAL_FREE;   /* as the filter's mechanization */
    sc.subsamples = subsamples;
    double best = 1e300, best_sins = 1e300;
    for (int r = 0; r < repeats; ++r) {
        /* in chunks of 100 s from the initial state: free inertial, the record's constant
         * horizontal acceleration would leave the Earth model's range in an hour */
        double el_sins = 0.0;
        for (size_t k0 = 0; k0 < n; k0 += 20000) {
            const size_t nk = n - k0 < 20000 ? n - k0 : 20000;
            gf_sins_state s0;
            if (gf_sins_init(&s0, &sc, (const double[4]){1, 0, 0, 0}, (const double[3]){0, 0, 0},
                             0.5, 1.0, 100.0, 0.0) != GF_OK)
                return 2;
            const double ts0 = now_s();
            if (gf_sins_run(&s0, nk, g + 3 * k0, a + 3 * k0, dt, NULL, NULL, 0, out_buf + n,
                            out_buf + 5 * n, out_buf + 8 * n, out_buf, NULL) != GF_OK)
                return 4;
            el_sins += now_s() - ts0;
        }
        if (el_sins < best_sins)
            best_sins = el_sins;
        gf_ins_filter f;
        int32_t bad;
        if (gf_ins_init(&f, &cfg, 0.0, q, v0, 0.5, 1.0, 100.0, NULL, P0, &bad) != GF_OK)
            return 2;
        gf_ins_output out = {out_buf, out_buf + n, out_buf + 5 * n, out_buf + 8 * n,
                             out_buf + 11 * n, out_buf + 20 * n, NULL, 0, NULL, NULL};
        size_t done, mdone;
        const double t0 = now_s();
        const gf_status st = gf_ins_run(&f, n, t, g, a, nm, meas, &out, NULL, NULL, &done, &mdone);
        const double el = now_s() - t0;
        if (st != GF_OK) {
            fprintf(stderr, "status %d at %zu\n", (int)st, done);
            return 3;
        }
        if (el < best)
            best = el;
    }
    printf("%s, propagation %s%g s, %d sample(s) per update, %zu samples at 200 Hz, %zu GNSS updates: %.3f M samples/s "
           "(%.1f ns/sample); mechanization alone %.3f M samples/s (%.1f ns/sample), "
           "filter / mechanization %.2f\n", filter ? "UKF" : "EKF",
           prop == 0 ? "every sample, " : "", prop, subsamples, n, nm, n / best * 1e-6, best / n * 1e9,
           n / best_sins * 1e-6, best_sins / n * 1e9, best / best_sins);
    free(t); free(g); free(a); free(meas); free(out_buf);
    return 0;
}
