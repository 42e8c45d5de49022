/* fuzz_rotation.c — libFuzzer target: the rotating IMU of seed 001 (gf_rot.h:
 * schedules, poses, exact IMU increments on a static base, vehicle attitude from the
 * gimbal angles) and the system-level calibration filter (gf_syscal.h), with any
 * schedule, site, prior, parameters and samples, and damaged structs.
 * Oracles (fuzz_data.h): valid statuses; finite outputs on GF_OK and in the rows before
 * *n_done; unit quaternions out of a schedule gf_rot_init accepted; a state gf_rot_init
 * made passes gf_rot_state_check; gf_syscal_run's refusals of a sample (non-finite,
 * time, range) leave the filter as after the last good sample (here: unchanged when the
 * first sample is refused); a filter gf_syscal_init made passes gf_syscal_check. */
#include "fuzz_data.h"
#include "est/gf_syscal.h"
#include "sim/gf_rot.h"

#define MAX_RUN 8

static double fz_angle(fz *d)
{
    /* multiples of 90 degrees (the calibration paths) or anything */
    const uint8_t sel = fz_u8(d);
    if (sel < 160)
        return (double)((int)(fz_u8(d) % 9) - 4) * 1.5707963267948966;
    return fz_num(d, 7.0);
}

static void make_schedule(fz *d, gf_rot_schedule *s)
{
    memset(s, 0, sizeof *s);
    s->q_mb0[0] = 1.0;
    if (fz_u8(d) % 8 == 0)
        fz_nums(d, s->q_mb0, 4, 1.0);
    const uint8_t ns = fz_u8(d);
    s->n_segments = ns < 250 ? ns % 7 : GF_ROT_MAX_SEGMENTS + (ns & 3);
    s->repeat = fz_u8(d) % 4 == 0;
    for (size_t k = 0; k < s->n_segments && k < GF_ROT_MAX_SEGMENTS; ++k) {
        gf_rot_segment *g = s->segment + k;
        g->base_axis = (int32_t)(fz_u8(d) % 6) - 2;
        g->imu_axis = (int32_t)(fz_u8(d) % 6) - 2;
        g->base_angle_rad = g->base_axis >= 0 ? fz_angle(d) : 0.0;
        g->imu_angle_rad = g->imu_axis >= 0 ? fz_angle(d) : 0.0;
        g->move_s = fz_pos(d, 20.0);
        g->ramp_s = fz_u8(d) & 1 ? 0.25 * g->move_s : fz_pos(d, 2.0);
        g->dwell_s = fz_pos(d, 10.0);
    }
}

static void fuzz_rot(fz *d)
{
    static gf_rot_schedule sched;
    static gf_rot_state st;
    make_schedule(d, &sched);
    int bad = -1;
    const double t0 = fz_num(d, 100.0);
    gf_status s = gf_rot_init(&st, &sched, t0, &bad);
    FZ_STATUS(s, "gf_rot_init");
    if (s != GF_OK)
        return;
    FZ_REQUIRE(gf_rot_state_check(&st) == GF_OK, "gf_rot_init made a state gf_rot_state_check refuses");
    /* poses at a few times */
    const size_t n = 1 + fz_index(d, MAX_RUN);
    double t[MAX_RUN], q[4 * MAX_RUN], w[3 * MAX_RUN], gim[2 * MAX_RUN];
    for (size_t k = 0; k < n; ++k)
        t[k] = t0 + fz_num(d, 200.0);
    size_t done = 999;
    s = gf_rot_poses(&st, n, t, q, w, gim, &done);
    FZ_STATUS(s, "gf_rot_poses");
    FZ_REQUIRE(done <= n && (s != GF_OK || done == n), "gf_rot_poses n_done");
    FZ_REQUIRE(fz_all_finite(q, 4 * done) && fz_all_finite(w, 3 * done) && fz_all_finite(gim, 2 * done),
               "gf_rot_poses: non-finite rows done");
    for (size_t k = 0; k < done; ++k) {
        const double *p = q + 4 * k;
        const double nq = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3];
        FZ_REQUIRE(fabs(nq - 1.0) < 1e-9, "gf_rot_poses: |q|^2 = %.17g", nq);
    }
    /* the IMU on a static base */
    double qb[4] = {1, 0, 0, 0};
    if (fz_u8(d) % 8 == 0)
        fz_nums(d, qb, 4, 1.0);
    const double lat = fz_num(d, 1.6), h = fz_num(d, 1000.0), dt = fz_pos(d, 0.01);
    const double delay = fz_u8(d) & 1 ? 0.0 : fz_num(d, 0.01);
    double dth[3 * MAX_RUN], dv[3 * MAX_RUN], qmn[4 * MAX_RUN], g2[2 * MAX_RUN];
    s = gf_rot_imu_static(&st, qb, lat, h, t0 + fz_num(d, 100.0), n, dt, delay, dth, dv, qmn, g2, &done);
    FZ_STATUS(s, "gf_rot_imu_static");
    FZ_REQUIRE(done <= n && (s != GF_OK || done == n), "gf_rot_imu_static n_done");
    FZ_REQUIRE(fz_all_finite(dth, 3 * done) && fz_all_finite(dv, 3 * done) && fz_all_finite(qmn, 4 * done) &&
                   fz_all_finite(g2, 2 * done),
               "gf_rot_imu_static: non-finite rows done");
    /* vehicle attitude from navigated attitudes and gimbal angles */
    double qn[4 * MAX_RUN], gg[2 * MAX_RUN], qv[4 * MAX_RUN];
    fz_nums(d, qn, 4 * n, 1.0);
    fz_nums(d, gg, 2 * n, 4.0);
    s = gf_rot_vehicle_attitude(n, qn, gg, qv, &done);
    FZ_STATUS(s, "gf_rot_vehicle_attitude");
    FZ_REQUIRE(done <= n && (s != GF_OK || done == n), "gf_rot_vehicle_attitude n_done");
    FZ_REQUIRE(fz_all_finite(qv, 4 * done), "gf_rot_vehicle_attitude: non-finite rows done");
    /* a damaged state: checked, then evaluated only if the check passes */
    for (int j = 0, k = 1 + fz_u8(d) % 4; j < k; ++j)
        ((uint8_t *)&st)[fz_index(d, sizeof st)] = fz_u8(d);
    s = gf_rot_state_check(&st);
    FZ_STATUS(s, "gf_rot_state_check");
    gf_rot_pose pose;
    const gf_status e = gf_rot_eval(&st, t0 + fz_num(d, 100.0), &pose);
    FZ_STATUS(e, "gf_rot_eval on a damaged state");
}

static void fuzz_syscal(fz *d)
{
    static gf_syscal f, before;
    static gf_syscal_epoch ep[MAX_RUN];
    gf_syscal_config c;
    gf_syscal_config_default(&c);
    static const int32_t models[4] = {36, 37, 39, 40};   /* seed and full, +delay */
    c.n_states = fz_u8(d) % 8 == 0 ? (int32_t)fz_u8(d) : models[fz_u8(d) & 3];
    c.lat_rad = fz_u8(d) & 3 ? 0.7 : fz_num(d, 1.6);
    c.lon_rad = fz_num(d, 3.0);
    c.h_m = fz_u8(d) & 3 ? 50.0 : fz_num(d, 1e4);
    c.prop_interval_s = fz_pos(d, 0.02);
    c.update_interval_s = fz_pos(d, 0.05);
    c.vel_std_m_s = fz_pos(d, 1e-3);
    c.gyro_arw_rad_sqrt_s = fz_u8(d) & 1 ? 0.0 : fz_pos(d, 1e-6);
    c.accel_vrw_m_s_sqrt_s = fz_u8(d) & 1 ? 0.0 : fz_pos(d, 1e-4);
    for (int i = 0; i < GF_SYSCAL_MAX_STATES; ++i)
        c.p0_std[i] = fz_pos(d, i < 9 ? 1e-3 : 1e-5);
    if (fz_u8(d) % 8 == 0)
        c.max_gap_s = fz_num(d, 1.0);
    double q0[4] = {1, 0, 0, 0}, param[GF_SYSCAL_N_PARAMS] = {0};
    if (fz_u8(d) % 4 == 0)
        fz_nums(d, q0, 4, 1.0);
    if (fz_u8(d) & 1)
        fz_nums(d, param, GF_SYSCAL_N_PARAMS, 1e-4);
    int bad = -1;
    gf_status s = gf_syscal_init(&f, &c, q0, param, 0.0, &bad);
    FZ_STATUS(s, "gf_syscal_init");
    if (s != GF_OK)
        return;
    FZ_REQUIRE(gf_syscal_check(&f) == GF_OK, "gf_syscal_init made a filter gf_syscal_check refuses");
    /* samples near rest (gravity along m's z for the identity attitude) or anything */
    const size_t n = 1 + fz_index(d, MAX_RUN);
    double t[MAX_RUN], dth[3 * MAX_RUN], dv[3 * MAX_RUN], tk = 0.0;
    for (size_t k = 0; k < n; ++k) {
        const double dt = fz_pos(d, 0.01);
        tk += dt;
        t[k] = fz_u8(d) % 16 ? tk : fz_num(d, 1.0);
        for (int i = 0; i < 3; ++i) {
            dth[3 * k + i] = fz_u8(d) % 8 ? 1e-7 * dt * (double)(i + 1) : fz_num(d, 0.1);
            dv[3 * k + i] = fz_u8(d) % 8 ? (i == 2 ? 9.8 * dt : 1e-4 * dt) : fz_num(d, 1.0);
        }
    }
    before = f;
    size_t ne = 0, done = 999;
    s = gf_syscal_run(&f, n, t, dth, dv, ep, MAX_RUN, &ne, &done);
    FZ_STATUS(s, "gf_syscal_run");
    FZ_REQUIRE(done <= n && (s != GF_OK || done == n) && ne <= MAX_RUN, "gf_syscal_run counts");
    if (s == GF_ERR_NONFINITE_INPUT || s == GF_ERR_BAD_TIME || s == GF_ERR_OUT_OF_RANGE) {
        if (done == 0)
            FZ_REQUIRE(memcmp(&f, &before, sizeof f) == 0, "gf_syscal_run: a refused first sample changed the filter");
    }
    for (size_t k = 0; k < ne; ++k)
        FZ_REQUIRE(fz_all_finite(ep[k].param, GF_SYSCAL_N_PARAMS) && fz_all_finite(ep[k].std, (size_t)c.n_states) &&
                       isfinite(ep[k].nis),
                   "gf_syscal_run: non-finite epoch %zu", k);
    double P[GF_SYSCAL_MAX_STATES * GF_SYSCAL_MAX_STATES], sd[GF_SYSCAL_MAX_STATES];
    if (s == GF_OK) {
        s = gf_syscal_covariance(&f, P, sd);
        FZ_STATUS(s, "gf_syscal_covariance");
        FZ_FINITE_ON_OK(s, sd, (size_t)c.n_states, "gf_syscal_covariance");
    }
    /* a damaged filter: refused by the entry points or run to a valid status */
    for (int j = 0, k = 1 + fz_u8(d) % 4; j < k; ++j)
        ((uint8_t *)&f)[fz_index(d, sizeof f)] = fz_u8(d);
    FZ_STATUS(gf_syscal_check(&f), "gf_syscal_check");
    s = gf_syscal_run(&f, 1, t + n - 1, dth, dv, ep, MAX_RUN, &ne, &done);
    FZ_STATUS(s, "gf_syscal_run on a damaged filter");
    FZ_STATUS(gf_syscal_covariance(&f, P, sd), "gf_syscal_covariance on a damaged filter");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz d = {data, size};
    if (fz_u8(&d) & 1)
        fuzz_rot(&d);
    else
        fuzz_syscal(&d);
    return 0;
}
