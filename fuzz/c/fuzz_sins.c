/* fuzz_sins.c — libFuzzer target: the strapdown navigator and the Earth model
 * (gf_sins.h, gf_earth.h) with any configuration, attitude, position, samples and
 * times, and with damaged state structs (as an FMU state restored from bytes).
 * Oracles (fuzz_data.h): valid statuses; finite outputs on GF_OK; a state that
 * gf_sins_init or a GF_OK step produced passes gf_sins_state_check; a failed
 * gf_sins_step or gf_sins_set_navigation leaves the state unchanged; gf_sins_run's rows
 * before *n_done are finite. */
#include "fuzz_data.h"
#include "nav/gf_earth.h"
#include "nav/gf_sins.h"

#define MAX_RUN 16

static void fuzz_earth(fz *d)
{
    const double lat = fz_num(d, 1.6), h = fz_num(d, 1e4);
    double v[3];
    fz_nums(d, v, 3, 300.0);
    gf_earth e;
    gf_status st = gf_earth_update(&e, lat, h, (fz_u8(d) & 1) ? v : NULL, fz_num(d, 1.0));
    FZ_STATUS(st, "gf_earth_update");
    FZ_FINITE_ON_OK(st, &e.sin_lat, sizeof e / sizeof(double), "gf_earth_update");
    double g = 0.0;
    st = gf_earth_gravity(lat, h, &g);
    FZ_STATUS(st, "gf_earth_gravity");
    FZ_FINITE_ON_OK(st, &g, 1, "gf_earth_gravity");
    double lats[4], hs[4], rm[4], rn[4], gr[4];
    fz_nums(d, lats, 4, 1.6);
    fz_nums(d, hs, 4, 1e4);
    size_t done = 99;
    st = gf_earth_batch(4, lats, hs, rm, rn, gr, &done);
    FZ_STATUS(st, "gf_earth_batch");
    FZ_REQUIRE(done <= 4 && (st != GF_OK || done == 4), "gf_earth_batch n_done %zu", done);
    FZ_REQUIRE(fz_all_finite(rm, done) && fz_all_finite(rn, done) && fz_all_finite(gr, done),
               "gf_earth_batch: non-finite rows before n_done");
}

static void fuzz_euler(fz *d)
{
    double euler[3], q[4], back[3];
    fz_nums(d, euler, 3, 4.0);
    gf_status st = gf_euler_to_quat(euler, q);
    FZ_STATUS(st, "gf_euler_to_quat");
    FZ_FINITE_ON_OK(st, q, 4, "gf_euler_to_quat");
    if (fz_u8(d) & 1)
        fz_nums(d, q, 4, 1.0);
    st = gf_quat_to_euler(q, back);
    FZ_STATUS(st, "gf_quat_to_euler");
    FZ_FINITE_ON_OK(st, back, 3, "gf_quat_to_euler");
    double qs[3 * 4], es[3 * 3];
    fz_nums(d, qs, 12, 1.0);
    size_t done = 99;
    st = gf_quat_to_euler_batch(3, qs, es, &done);
    FZ_STATUS(st, "gf_quat_to_euler_batch");
    FZ_REQUIRE(done <= 3 && fz_all_finite(es, 3 * done), "gf_quat_to_euler_batch rows");
}

static void step_sample(fz *d, const gf_sins_state *s, double *gyro, double *accel)
{
    const int rates = s->cfg.input == GF_SINS_INPUT_RATES;
    fz_nums(d, gyro, 3, rates ? 2.0 : 0.02);
    fz_nums(d, accel, 3, rates ? 20.0 : 0.2);
}

static void check_state_ok(const gf_sins_state *s, const char *after)
{
    const gf_status st = gf_sins_state_check(s);
    FZ_REQUIRE(st == GF_OK,
               "gf_sins_state_check refuses the state after %s: %d (input %d earth %d vertical %d; "
               "|q| - 1 = %.3g, lat %.17g, sin %.17g - %.17g, cos %.17g - %.17g, R_M %.17g, h %.17g, "
               "v %g %g %g, a %g %g %g, prev %g %g %g / %g %g %g, baro %g, flat %g %g %g)",
               after, (int)st, s->cfg.input, s->cfg.earth, s->cfg.vertical,
               sqrt(s->q_bn[0] * s->q_bn[0] + s->q_bn[1] * s->q_bn[1] + s->q_bn[2] * s->q_bn[2] +
                    s->q_bn[3] * s->q_bn[3]) - 1.0,
               s->lat_rad, s->sin_lat, sin(s->lat_rad), s->cos_lat, cos(s->lat_rad), s->R_M_m,
               s->h_m, s->v_n_m_s[0], s->v_n_m_s[1], s->v_n_m_s[2], s->a_n_m_s2[0], s->a_n_m_s2[1],
               s->a_n_m_s2[2], s->prev_gyro[0], s->prev_gyro[1], s->prev_gyro[2], s->prev_accel[0],
               s->prev_accel[1], s->prev_accel[2], s->baro_accel_m_s2, s->flat_pos_m[0],
               s->flat_pos_m[1], s->flat_pos_m[2]);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz d = {data, size};
    fuzz_earth(&d);
    fuzz_euler(&d);

    gf_sins_config cfg;
    gf_sins_config_default(&cfg);
    const uint8_t pick = fz_u8(&d);
    cfg.input = pick % 3 == 2 ? (int)fz_u32(&d) : pick % 3;
    cfg.coning = (pick >> 2) % 3 == 2 ? (int)fz_u32(&d) : (pick >> 2) % 3;
    cfg.vertical = (pick >> 4) & 3;
    cfg.earth = (pick >> 6) == 3 ? (int)fz_u32(&d) : (pick >> 6) & 1;
    const uint8_t more = fz_u8(&d);
    /* subsamples 1..5 (5, and rates with > 1, refused) from bits the older inputs of the
     * corpus left unused, so that they decode as before unless bits 1 and 2 are set */
    if ((more & 6) == 6)
        cfg.subsamples = 1 + (more >> 3) % 5;
    if (more & 1) {
        cfg.flat_gravity_m_s2 = fz_num(&d, 10.0);
        cfg.hold_height_m = fz_num(&d, 1e3);
        cfg.baro_tau_s = fz_pos(&d, 10.0);
        cfg.max_rate_rad_s = fz_pos(&d, 50.0);
        cfg.max_specific_force_m_s2 = fz_pos(&d, 1000.0);
    }
    double euler[3], q[4], v[3];
    fz_nums(&d, euler, 3, 3.2);
    if (gf_euler_to_quat(euler, q) != GF_OK || (fz_u8(&d) & 7) == 0)
        fz_nums(&d, q, 4, 1.0);
    fz_nums(&d, v, 3, 100.0);
    const double lat = fz_num(&d, 1.6), lon = fz_num(&d, 3.2), h = fz_num(&d, 1e4);
    const double t0 = fz_num(&d, 1e3);

    gf_sins_state s, before;
    gf_status st = gf_sins_init(&s, &cfg, q, v, lat, lon, h, t0);
    FZ_STATUS(st, "gf_sins_init");
    if (st != GF_OK)
        return 0;
    check_state_ok(&s, "gf_sins_init");

    for (int op = 0; op < 48 && d.n > 0; ++op) {
        double gyro[3 * MAX_RUN], accel[3 * MAX_RUN];
        switch (fz_u8(&d) % 8) {
        case 0: case 1: case 2: { /* one sample */
            step_sample(&d, &s, gyro, accel);
            const double dt = fz_pos(&d, 0.01), h_ext = fz_num(&d, 1e3);
            before = s;
            st = gf_sins_step(&s, gyro, accel, dt, h_ext);
            FZ_STATUS(st, "gf_sins_step");
            if (st == GF_OK)
                check_state_ok(&s, "gf_sins_step");
            else
                FZ_REQUIRE(memcmp(&s, &before, sizeof s) == 0, "gf_sins_step error %d changed the state", (int)st);
            break;
        }
        case 3: { /* a batch, forward or backward */
            const size_t n = 1 + fz_index(&d, MAX_RUN);
            for (size_t k = 0; k < n; ++k)
                step_sample(&d, &s, gyro + 3 * k, accel + 3 * k);
            double t[MAX_RUN], h_ext[MAX_RUN], qo[4 * MAX_RUN], vo[3 * MAX_RUN], po[3 * MAX_RUN],
                to[MAX_RUN];
            for (size_t k = 0; k < MAX_RUN; ++k) /* rows not written stay NaN */
                to[k] = qo[4 * k] = vo[3 * k] = po[3 * k] = NAN;
            const uint8_t opt = fz_u8(&d);
            double tk = s.time_s;
            for (size_t k = 0; k < n; ++k)
                t[k] = (opt & 8) ? fz_num(&d, 1e3) : (tk += fz_pos(&d, 0.01));
            fz_nums(&d, h_ext, n, 1e3);
            size_t done = 999;
            st = gf_sins_run(&s, n, gyro, accel, fz_pos(&d, 0.01), (opt & 1) ? t : NULL,
                             (opt & 2) ? h_ext : NULL, (opt >> 2) & 1, qo, vo, po,
                             (opt & 16) ? to : NULL, &done);
            FZ_STATUS(st, "gf_sins_run");
            FZ_REQUIRE(done <= n && (st != GF_OK || done == n), "gf_sins_run n_done %zu of %zu", done, n);
            /* rows done: the first done, or the last done of a backward run; with
             * subsamples N one row per group of N samples (the last group shorter) */
            const size_t N = (size_t)s.cfg.subsamples, rows = (n + N - 1) / N;
            const size_t rd = (done + N - 1) / N;
            const size_t r0 = ((opt >> 2) & 1) ? rows - rd : 0;
            FZ_REQUIRE(fz_all_finite(qo + 4 * r0, 4 * rd) && fz_all_finite(vo + 3 * r0, 3 * rd) &&
                           fz_all_finite(po + 3 * r0, 3 * rd) &&
                           (!(opt & 16) || fz_all_finite(to + r0, rd)),
                       "gf_sins_run: a non-finite row among those done (status %d, %zu of %zu, "
                       "options %d, earth %d)", (int)st, done, n, opt, s.cfg.earth);
            if (st == GF_OK)
                check_state_ok(&s, "gf_sins_run");
            break;
        }
        case 4:
            st = gf_sins_reverse(&s);
            FZ_STATUS(st, "gf_sins_reverse");
            if (st == GF_OK)
                check_state_ok(&s, "gf_sins_reverse");
            break;
        case 5: {
            double qn[4], vn[3];
            fz_nums(&d, qn, 4, 1.0);
            fz_nums(&d, vn, 3, 100.0);
            const double la = fz_num(&d, 1.6), lo = fz_num(&d, 3.2), hh = fz_num(&d, 1e4);
            before = s;
            st = gf_sins_set_navigation(&s, qn, vn, la, lo, hh);
            FZ_STATUS(st, "gf_sins_set_navigation");
            if (st == GF_OK)
                check_state_ok(&s, "gf_sins_set_navigation");
            else
                FZ_REQUIRE(memcmp(&s, &before, sizeof s) == 0, "gf_sins_set_navigation error changed the state");
            break;
        }
        case 6: {
            double pos[3];
            st = gf_sins_position(&s, pos);
            FZ_STATUS(st, "gf_sins_position");
            FZ_FINITE_ON_OK(st, pos, 3, "gf_sins_position");
            fz_nums(&d, pos, 3, 1e4);
            st = gf_sins_set_flat_position(&s, pos);
            FZ_STATUS(st, "gf_sins_set_flat_position");
            if (st == GF_OK)
                check_state_ok(&s, "gf_sins_set_flat_position");
            break;
        }
        default: { /* damaged struct: a few bytes overwritten, as in a crafted FMU state */
            gf_sins_state bad = s;
            const int k = 1 + fz_u8(&d) % 8;
            for (int j = 0; j < k; ++j)
                ((uint8_t *)&bad)[fz_index(&d, sizeof bad)] = fz_u8(&d);
            st = gf_sins_state_check(&bad);
            FZ_STATUS(st, "gf_sins_state_check");
            step_sample(&d, &bad, gyro, accel);
            st = gf_sins_step(&bad, gyro, accel, fz_pos(&d, 0.01), fz_num(&d, 1e3));
            FZ_STATUS(st, "gf_sins_step on a damaged state");
            break;
        }
        }
    }
    return 0;
}
