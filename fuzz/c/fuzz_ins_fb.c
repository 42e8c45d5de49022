/* fuzz_ins_fb.c — libFuzzer target: the integrated filter's reversal and forward-backward
 * driver (gf_ins_gnss.h: gf_ins_reverse, gf_ins_run_backward, gf_ins_forward_backward),
 * which no FMU reaches, with any configuration flags, initial state, record (times,
 * increments or rates) and measurements (GNSS, barometer, odometer, tachometer speed).
 * Oracles (fuzz_data.h): valid statuses; pass states finite and unit attitudes for the
 * passes done; reversing twice restores the filter byte for byte; a filter after a
 * GF_OK driver call passes gf_ins_filter_check. */
#include "fuzz_data.h"
#include "est/gf_ins_gnss.h"

#define MAX_N 24
#define MAX_M 8

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static gf_ins_filter f, copy;
    static gf_ins_innovation entries[64];
    fz dd = {data, size}, *d = &dd;
    gf_ins_config c;
    gf_ins_config_default(&c);
    c.input = fz_u8(d) & 1 ? GF_SINS_INPUT_RATES : GF_SINS_INPUT_INCREMENTS;
    c.filter = fz_u8(d) % 4 == 0;                 /* mostly the EKF */
    c.propagation_interval_s = fz_u8(d) & 1 ? 0.0 : fz_pos(d, 0.05);
    c.odometer_scale = fz_u8(d) & 1;
    c.baro_bias = fz_u8(d) & 1;
    c.scale_factors = fz_u8(d) % 4 == 0;
    c.zupt = fz_u8(d) & 1;
    c.nhc = fz_u8(d) % 4 == 0;
    c.subsamples = c.input == GF_SINS_INPUT_INCREMENTS ? 1 + fz_u8(d) % 4 : 1;
    c.odometer_mount = fz_u8(d) % 4 == 0;        /* odometer boresight states (25 at most) */
    int32_t n_states = 0;
    if (gf_ins_state_count(&c, &n_states) != GF_OK)
        return 0;
    double P0[GF_KF_MAX_N * GF_KF_MAX_N] = {0};
    for (int i = 0; i < n_states; ++i)
        P0[i * n_states + i] = fz_u8(d) % 16 ? 1e-4 : fz_num(d, 1.0);
    double q[4] = {1, 0, 0, 0}, v[3] = {0, 0, 0};
    if (fz_u8(d) % 4 == 0)
        fz_nums(d, q, 4, 1.0);
    if (fz_u8(d) % 4 == 0)
        fz_nums(d, v, 3, 5.0);
    const double lat = fz_u8(d) % 8 ? 0.5 : fz_num(d, 1.6), lon = 0.1, h = fz_u8(d) % 8 ? 10.0 : fz_num(d, 1e4);
    int32_t bad = 0;
    gf_status s = gf_ins_init(&f, &c, 0.0, q, v, lat, lon, h, NULL, P0, &bad);
    FZ_STATUS(s, "gf_ins_init");
    if (s != GF_OK)
        return 0;
    /* a record: times increasing (mostly), samples near rest or anything */
    const size_t n = 2 + fz_index(d, MAX_N - 1);
    double t[MAX_N], g[3 * MAX_N], a[3 * MAX_N], tk = 0.0;
    const int rates = c.input == GF_SINS_INPUT_RATES;
    for (size_t k = 0; k < n; ++k) {
        const double dt = fz_pos(d, 0.01);
        tk += dt;
        t[k] = fz_u8(d) % 32 ? tk : fz_num(d, 1.0);
        const double s_k = rates ? 1.0 : dt;
        for (int i = 0; i < 3; ++i) {
            g[3 * k + i] = fz_u8(d) % 8 ? 7e-5 * s_k * (i == 1) : fz_num(d, 0.1 * s_k);
            a[3 * k + i] = fz_u8(d) % 8 ? (i == 2 ? 9.8 * s_k : 0.0) : fz_num(d, s_k);
        }
    }
    if (rates)
        t[0] = fz_u8(d) & 1 ? 0.0 : t[0];    /* a rate record may start at the filter's time */
    gf_ins_meas m[MAX_M];
    const size_t nm = fz_index(d, MAX_M + 1);
    double tm = 0.0;
    for (size_t j = 0; j < nm; ++j) {
        static const int32_t types[] = {GF_INS_MEAS_GNSS_POS, GF_INS_MEAS_GNSS_VEL, GF_INS_MEAS_BARO,
                                        GF_INS_MEAS_ODO, GF_INS_MEAS_SPEED};
        m[j].type = fz_u8(d) % 16 ? types[fz_u8(d) % 5] : (int32_t)fz_u8(d);
        tm += fz_pos(d, 0.02);
        m[j].t_s = tm;
        m[j].z[0] = m[j].type == GF_INS_MEAS_GNSS_POS ? lat + fz_num(d, 1e-6) : fz_num(d, 2.0);
        m[j].z[1] = m[j].type == GF_INS_MEAS_GNSS_POS ? lon + fz_num(d, 1e-6) : fz_num(d, 2.0);
        m[j].z[2] = m[j].type == GF_INS_MEAS_GNSS_POS ? h + fz_num(d, 1.0) : fz_num(d, 2.0);
        for (int i = 0; i < 3; ++i)
            m[j].std[i] = fz_pos(d, 0.5);
    }
    gf_ins_log log = {64, 0, 0, entries};
    switch (fz_u8(d) % 3) {
    case 0: { /* reversing twice is the identity */
        memcpy(&copy, &f, sizeof f);
        s = gf_ins_reverse(&f);
        FZ_STATUS(s, "gf_ins_reverse");
        if (s == GF_OK) {
            s = gf_ins_reverse(&f);
            FZ_REQUIRE(s == GF_OK, "the second reversal failed (%d)", (int)s);
            FZ_REQUIRE(memcmp(&copy, &f, sizeof f) == 0, "reversing twice changed the filter");
        }
        break;
    }
    case 1: { /* forward over the record, then backward */
        size_t done = 0, mdone = 0;
        s = gf_ins_forward_backward(&f, n, t, g, a, nm, m, 0, NULL, &log, NULL);
        FZ_STATUS(s, "gf_ins_forward_backward(0)");
        if (s != GF_OK)
            break;
        FZ_REQUIRE(gf_ins_filter_check(&f) == GF_OK, "a filter after a GF_OK forward pass fails gf_ins_filter_check");
        s = gf_ins_reverse(&f);
        FZ_STATUS(s, "gf_ins_reverse");
        if (s != GF_OK)
            break;
        s = gf_ins_run_backward(&f, n, t, g, a, rates ? t[0] : 0.0, nm, m, NULL, &log, &done, &mdone);
        FZ_STATUS(s, "gf_ins_run_backward");
        FZ_REQUIRE(done <= n && mdone <= nm, "gf_ins_run_backward counts");
        if (s == GF_OK)
            FZ_REQUIRE(gf_ins_filter_check(&f) == GF_OK, "a filter after a GF_OK backward walk fails gf_ins_filter_check");
        break;
    }
    default: { /* the driver with passes */
        gf_ins_pass passes[1 + 2 * 3];
        const int32_t n_fb = (int32_t)(fz_u8(d) % 4);
        int32_t np = -1;
        /* out-of-range counts too (below 0, above 10000); not the large accepted ones: 10^4
         * passes over the record are work in proportion to the count asked for (a 13 s
         * input under the sanitizers), not a hang */
        const uint32_t u = fz_u32(d);
        const int32_t any = fz_u8(d) % 32 ? n_fb
                            : (u & 1) ? -1 - (int32_t)(u >> 2) : 10001 + (int32_t)(u >> 2);
        s = gf_ins_forward_backward(&f, n, t, g, a, nm, m, any, any >= 0 && any <= 3 ? passes : NULL, &log,
                                    &np);
        FZ_STATUS(s, "gf_ins_forward_backward");
        FZ_REQUIRE(np >= 0, "passes done %d", (int)np);
        for (int32_t k = 0; k < np && k < 1 + 2 * 3 && any >= 0 && any <= 3; ++k) {
            const double *qq = passes[k].q_bn;
            FZ_REQUIRE(fz_all_finite(passes[k].q_bn, 4) && fz_all_finite(passes[k].v_n_m_s, 3) &&
                           fz_all_finite(passes[k].std9, 9),
                       "pass %d not finite", (int)k);
            FZ_REQUIRE(fabs(qq[0] * qq[0] + qq[1] * qq[1] + qq[2] * qq[2] + qq[3] * qq[3] - 1.0) < 1e-9,
                       "pass %d attitude not unit", (int)k);
        }
        if (s == GF_OK)
            FZ_REQUIRE(gf_ins_filter_check(&f) == GF_OK, "a filter after a GF_OK driver call fails gf_ins_filter_check");
        break;
    }
    }
    FZ_REQUIRE(log.count <= log.capacity, "log overrun");
    return 0;
}
