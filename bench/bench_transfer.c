/* bench_transfer.c — throughput of the transfer-alignment filter (issue 24: gf_ins_run with
 * the master kinds) on one core, without Python: a slave IMU at 100 Hz on a host whose
 * platform rolls (a sinusoidal roll rate of +-30 deg/s amplitude about the forward axis,
 * a forward acceleration: every block of F and H filled) with a master epoch every 10
 * slave samples (10 Hz: master velocity with its rate, and master attitude — velocity +
 * attitude matching — at times between slave samples). The filter: EKF, 22 states (15 +
 * mounting 3 + lever arm 3 + time offset 1), covariance propagated every 0.1 s (the
 * master's interval), or every sample with a propagation interval of 0.
 *
 *   gcc -O3 -ffp-contract=off -I csrc bench/bench_transfer.c \
 *       $(find csrc -name 'gf*.c' | sort) -lm -o bench_transfer
 *   ./bench_transfer [filter 0=EKF 1=UKF] [propagation interval s] [samples] [repeats]
 *                    [flexure 0/1: 28 states] [position 0/1: master position too]
 *
 * Prints the best of the repeats (process CPU time) in ns per slave sample, amortised
 * over the master updates (issue 24's goal: <= 1 us), and the number of updates made
 * (every master epoch must be used: no gate, a consistent record). The record's master
 * values are the filter's own prediction of them at the epoch (gf_ins_meas_model of a
 * filter run once without updates): innovations ~ 0, as in a converged alignment, so the
 * covariance stays positive over the long record. */
#define _POSIX_C_SOURCE 199309L   /* clock_gettime */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base/gf_math.h"
#include "est/gf_ins_gnss.h"
#include "nav/gf_sins.h"

#define DEG (3.14159265358979323846 / 180.0)

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts); /* CPU time: robust to a busy machine */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static gf_status start(gf_ins_filter *f, const gf_ins_config *cfg)
{
    gf_ins_initial_std sd;
    memset(&sd, 0, sizeof sd);
    for (int i = 0; i < 3; ++i) {
        sd.velocity_std_m_s[i] = 0.1;
        sd.position_std_m[i] = 1.0;
        sd.attitude_std_rad[i] = 1e-3;
        sd.gyro_bias_std_rad_s[i] = 200.0 * DEG / 3600.0;
        sd.accel_bias_std_m_s2[i] = 0.03;
        sd.gyro_scale_std[i] = sd.accel_scale_std[i] = 1e-3;
        sd.master_mount_std_rad[i] = 0.02;
        sd.master_lever_std_m[i] = 0.1;
    }
    sd.baro_bias_std_m = 1.0;
    sd.odometer_scale_std = 0.01;
    sd.odometer_mount_std_rad[0] = sd.odometer_mount_std_rad[1] = 0.01;
    sd.master_time_offset_std_s = 0.03;
    static double P0[GF_INS_MAX_STATES * GF_INS_MAX_STATES];   /* the harness only */
    int32_t bad = 0;
    gf_status st = gf_ins_initial_covariance(cfg, 0.5, 100.0, &sd, P0, &bad);
    if (st != GF_OK)
        return st;
    const double q[4] = {1, 0, 0, 0}, v0[3] = {0, 10, 0};
    return gf_ins_init(f, cfg, 0.0, q, v0, 0.5, 1.0, 100.0, NULL, P0, &bad);
}

int main(int argc, char **argv)
{
    const int filter = argc > 1 ? atoi(argv[1]) : 0;
    const double prop = argc > 2 ? atof(argv[2]) : 0.1;
    const size_t n = argc > 3 ? (size_t)atol(argv[3]) : 200000;
    const int repeats = argc > 4 ? atoi(argv[4]) : 5;
    const int flexure = argc > 5 ? atoi(argv[5]) : 0;
    const int position = argc > 6 ? atoi(argv[6]) : 0;
    const double dt = 0.01;
    const size_t every = 10;                       /* a master epoch every 10 samples */
    const size_t kinds = position ? 3 : 2;
    double *t = malloc(n * sizeof *t), *g = malloc(3 * n * sizeof *g), *a = malloc(3 * n * sizeof *a);
    const size_t m = kinds * (n / every + 1);
    gf_ins_meas *meas = calloc(m, sizeof *meas);
    double *out_buf = malloc(n * (1 + 4 + 3 + 3 + 9 + GF_INS_N_SENSORS) * sizeof(double));
    if (!t || !g || !a || !meas || !out_buf)
        return 1;
    for (size_t k = 0; k < n; ++k) {
        const double tk = dt * (double)(k + 1), w = 30.0 * DEG * sin(2.0 * 3.14159265358979 * tk / 4.0);
        t[k] = tk;
        g[3 * k] = 1e-4 * dt; g[3 * k + 1] = w * dt; g[3 * k + 2] = 2e-3 * dt;
        a[3 * k] = 0.02 * dt; a[3 * k + 1] = 0.05 * dt; a[3 * k + 2] = 9.79 * dt;
    }
    gf_ins_config cfg;
    gf_ins_config_default(&cfg);
    cfg.filter = filter;
    cfg.propagation_interval_s = prop;
    cfg.noise.gyro_arw_rad_sqrt_s = 0.3 * DEG / 60.0;
    cfg.noise.accel_vrw_m_s_sqrt_s = 1e-3;
    cfg.gate_probability = 0.0;   /* no gate, as in the figures of docs/benchmarks.md */
    cfg.gate_reset_count = 0;
    cfg.master_mount = cfg.master_lever = cfg.master_time_offset = 1;
    cfg.flexure = flexure;
    cfg.noise.flexure_std_rad = 2e-4;
    cfg.noise.flexure_tau_s = 0.5;
    cfg.master_mount_rad[0] = 0.006; cfg.master_mount_rad[1] = -0.004; cfg.master_mount_rad[2] = 0.007;
    cfg.master_lever_arm_m[0] = 0.1; cfg.master_lever_arm_m[2] = -0.05;
    cfg.master_time_offset_s = 0.015;
    /* the master record: a free run of the filter, its predictions at each epoch
     * (3 ms after a slave sample: the interval is split there) */
    gf_ins_filter f;
    if (start(&f, &cfg) != GF_OK)
        return 2;
    size_t nm = 0;
    for (size_t k = 0; k < n; ++k) {
        if (gf_ins_step(&f, t[k], g + 3 * k, a + 3 * k, 0, NULL, NULL, NULL) != GF_OK)
            return 3;
        if ((k + 1) % every == 0 && k + 1 < n) {
            const int types[3] = {GF_INS_MEAS_MASTER_VEL, GF_INS_MEAS_MASTER_ATT, GF_INS_MEAS_MASTER_POS};
            const double w_m[3] = {g[3 * k] / dt, g[3 * k + 1] / dt, g[3 * k + 2] / dt};
            for (size_t j = 0; j < kinds; ++j) {
                gf_ins_meas *ms = meas + nm++;
                ms->type = types[j];
                ms->t_s = t[k];
                memcpy(ms->aux, w_m, sizeof w_m);
                ms->std[0] = ms->std[1] = ms->std[2] = 1.0;
                double z[3];
                if (types[j] != GF_INS_MEAS_MASTER_ATT &&
                    gf_ins_meas_model(&f, types[j], ms, NULL, z, NULL, NULL) != GF_OK)
                    return 4;
                if (types[j] == GF_INS_MEAS_MASTER_VEL) {
                    memcpy(ms->z, z, sizeof z);
                    ms->std[0] = ms->std[1] = 0.015; ms->std[2] = 0.005;
                } else if (types[j] == GF_INS_MEAS_MASTER_ATT) {
                    /* z: the master's Euler angles with C_meas = D, the attitude the
                     * filter predicts: from C_m^n = C_s^n M^T, then D = exp([y x]) C_meas
                     * (y = log(D C_meas^T), the model's residual) */
                    double qM[4], qMc[4], qm[4], qy[4], qd[4], y[3];
                    gf_euler_to_quat(cfg.master_mount_rad, qM);
                    gf_q_conj(qM, qMc);
                    gf_q_mul(f.nav.q_bn, qMc, qm);
                    gf_quat_to_euler(qm, ms->z);
                    if (gf_ins_meas_model(&f, types[j], ms, NULL, y, NULL, NULL) != GF_OK)
                        return 4;
                    gf_q_from_rotvec(y, qy);
                    gf_q_mul(qy, qm, qd);
                    gf_quat_to_euler(qd, ms->z);
                    ms->std[0] = ms->std[1] = 2e-5; ms->std[2] = 3e-4;
                } else {   /* the predicted local ENU metres as latitude, longitude, height */
                    const double e2 = 6.69437999014e-3, a_m = 6378137.0, sl = sin(f.nav.lat_rad);
                    const double w = sqrt(1.0 - e2 * sl * sl), rn = a_m / w, rm = a_m * (1.0 - e2) / (w * w * w);
                    ms->z[0] = f.nav.lat_rad + z[1] / (rm + f.nav.h_m);
                    ms->z[1] = f.nav.lon_rad + z[0] / ((rn + f.nav.h_m) * cos(f.nav.lat_rad));
                    ms->z[2] = f.nav.h_m + z[2];
                }
                ms->t_s = t[k] + 0.003;
            }
        }
    }
    double best = 1e300;
    uint64_t updates = 0;
    for (int r = 0; r < repeats; ++r) {
        if (start(&f, &cfg) != GF_OK)
            return 2;
        gf_ins_output out = {out_buf, out_buf + n, out_buf + 5 * n, out_buf + 8 * n,
                             out_buf + 11 * n, out_buf + 20 * n, NULL, 0, NULL, NULL};
        size_t done, mdone;
        const double t0 = now_s();
        const gf_status st = gf_ins_run(&f, n, t, g, a, nm, meas, &out, NULL, NULL, &done, &mdone);
        const double el = now_s() - t0;
        if (st != GF_OK) {
            fprintf(stderr, "status %d at %zu\n", (int)st, done);
            return 5;
        }
        updates = f.n_updates;
        if (el < best)
            best = el;
    }
    printf("%s, %d states, propagation %g s, %zu slave samples at 100 Hz, %zu master measurements "
           "(%s at 10 Hz), %llu updates made: %.1f ns per slave sample (%.3f M samples/s)\n",
           filter ? "UKF" : "EKF", f.n_states, prop, n, nm,
           position ? "velocity + attitude + position" : "velocity + attitude",
           (unsigned long long)updates, best / (double)n * 1e9, (double)n / best * 1e-6);
    free(t); free(g); free(a); free(meas); free(out_buf);
    return 0;
}
