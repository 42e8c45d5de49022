/* test_aiding_sim.c — the aiding sensors (gf_aiding_sim) under ASan/UBSan:
 *   1. the measurement geometry against the level-vehicle closed forms written here in
 *      the navigation frame (w_eb^n = w_en^n + [0, 0, -dpsi/dt], tests/c/gf_ref.h radii);
 *   2. epoch values do not depend on the caller's steps: one batch call, steps of 0.01 s
 *      and random steps give the same bits; every epoch is delivered once, in the first
 *      step whose end reaches t_valid + latency;
 *   3. outages (intervals and the periodic rule) and epochs on the step grid;
 *   4. seeds: reproducible, per-sensor streams independent;
 *   5. bad parameters, bad times, errors leave the state unchanged. */
#include <math.h>
#include <string.h>

#include "sim/gf_aiding.h"
#include "gf_ref.h"
#include "gf_test.h"
#include "sim/gf_vehicle.h"

static gf_vehicle_profile turning_profile(void)
{
    gf_vehicle_profile p;
    memset(&p, 0, sizeof p);
    p.lat0_rad = 30.0 * REF_PI / 180.0;
    p.lon0_rad = 114.0 * REF_PI / 180.0;
    p.h0_m = 100.0;
    p.heading0_rad = 0.3;
    p.speed0_m_s = 12.0;
    p.heading_rate0_rad_s = 0.05;
    p.n_segments = 2;
    p.segment[0].duration_s = 5.0;
    p.segment[0].dheading_rad = 1.5; /* a turn to the right */
    p.segment[1].duration_s = 4.0;
    p.segment[1].dspeed_m_s = -4.0;
    return p;
}

static gf_aiding_params all_sensors(void)
{
    gf_aiding_params a;
    memset(&a, 0, sizeof a);
    gf_gnss_params *g = &a.gnss;
    g->enabled = 1;
    g->quality = 5;
    g->rate_hz = 5.0;
    g->offset_s = 0.0137;
    g->latency_s = 0.15;
    const double lg[3] = {0.4, 1.2, 1.5}, ps[3] = {1.0, 1.2, 2.0}, vs[3] = {0.05, 0.05, 0.1};
    const double gm[3] = {0.5, 0.5, 1.0};
    memcpy(g->lever_arm_m, lg, sizeof lg);
    memcpy(g->pos_std_m, ps, sizeof ps);
    memcpy(g->vel_std_m_s, vs, sizeof vs);
    memcpy(g->pos_gm_std_m, gm, sizeof gm);
    g->pos_gm_tau_s = 30.0;
    gf_baro_params *b = &a.baro;
    b->enabled = 1;
    b->rate_hz = 25.0;
    b->offset_s = 0.003;
    b->std_m = 0.3;
    b->bias0_m = 2.0;
    b->bias_rw_m_sqrt_s = 0.01;
    b->bias_gm_std_m = 0.5;
    b->bias_gm_tau_s = 60.0;
    gf_odo_params *o = &a.odo;
    o->enabled = 1;
    o->rate_hz = 50.0;
    o->offset_s = 0.005;
    const double lo[3] = {0.8, -1.3, -0.4};
    memcpy(o->lever_arm_m, lo, sizeof lo);
    o->scale_error = 0.01;
    o->std_m_s = 0.02;
    return a;
}

/* 1. geometry ------------------------------------------------------------------------- */
static void test_geometry(void)
{
    gf_vehicle_profile p = turning_profile();
    gf_vehicle_state s;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "init");
    const double lg[3] = {0.4, 1.2, 1.5}, lo[3] = {0.8, -1.3, -0.4};
    for (int k = 1; k <= 8; ++k) {
        CHECK(gf_vehicle_step(&s, 1.1 * k, &x) == GF_OK, "step");
        double lat, lon, h, v[3], u;
        CHECK(gf_aiding_truth(&x, lg, lo, &lat, &lon, &h, v, &u) == GF_OK, "truth");
        /* level, heading psi: body x -> [c, -s, 0], body y -> [s, c, 0], z -> up */
        const double psi = x.euler_rad[0], c = cos(psi), sn = sin(psi);
        double RM, RN;
        ref_radii(x.lat_rad, &RM, &RN);
        const double L = x.lat_rad, hh = x.h_m;
        const double lgn[3] = {lg[0] * c + lg[1] * sn, -lg[0] * sn + lg[1] * c, lg[2]};
        const double lon_n[3] = {lo[0] * c + lo[1] * sn, -lo[0] * sn + lo[1] * c, lo[2]};
        CHECK_CLOSE(lat, L + lgn[1] / (RM + hh), 2e-16, "antenna latitude");
        CHECK_CLOSE(lon, x.lon_rad + lgn[0] / ((RN + hh) * cos(L)), 4e-16, "antenna longitude");
        CHECK_CLOSE(h, hh + lgn[2], 1e-13, "antenna height");
        /* w_eb^n = w_en^n + [0, 0, -dpsi/dt] (level vehicle) */
        const double vE = x.v_n_m_s[0], vN = x.v_n_m_s[1];
        const double w[3] = {-vN / (RM + hh), vE / (RN + hh),
                             vE * tan(L) / (RN + hh) - x.heading_rate_rad_s};
        const double wxl[3] = {w[1] * lgn[2] - w[2] * lgn[1], w[2] * lgn[0] - w[0] * lgn[2],
                               w[0] * lgn[1] - w[1] * lgn[0]};
        for (int i = 0; i < 3; ++i)
            CHECK_CLOSE(v[i], x.v_n_m_s[i] + wxl[i], 1e-13, "antenna velocity");
        const double wxo[3] = {w[1] * lon_n[2] - w[2] * lon_n[1], w[2] * lon_n[0] - w[0] * lon_n[2],
                               w[0] * lon_n[1] - w[1] * lon_n[0]};
        const double fwd[3] = {sn, c, 0.0};
        double want = 0.0;
        for (int i = 0; i < 3; ++i)
            want += (x.v_n_m_s[i] + wxo[i]) * fwd[i];
        CHECK_CLOSE(u, want, 1e-13, "wheel forward speed");
    }
    /* no lever arms: the IMU's own position and velocity, forward speed = |v| */
    double lat, lon, h, v[3], u;
    CHECK(gf_aiding_truth(&x, NULL, NULL, &lat, &lon, &h, v, &u) == GF_OK, "truth, no arms");
    CHECK(lat == x.lat_rad && lon == x.lon_rad && h == x.h_m, "zero lever arm: IMU position");
    CHECK_CLOSE(u, hypot(x.v_n_m_s[0], x.v_n_m_s[1]), 1e-13, "zero lever arm: speed");
    x.q_bn[0] = NAN;
    CHECK(gf_aiding_truth(&x, NULL, NULL, &lat, NULL, NULL, NULL, NULL) == GF_ERR_NONFINITE_INPUT,
          "NaN in the truth");
}

/* 2. steps ---------------------------------------------------------------------------- */
enum { CAP = 2000 };
static gf_gnss_epoch g_gnss[CAP];
static gf_baro_epoch g_baro[CAP];
static gf_odo_epoch g_odo[CAP];

static void start(gf_aiding_sim *sim, const gf_aiding_params *a, uint64_t seed,
                  gf_aiding_output *out)
{
    gf_vehicle_profile p = turning_profile();
    gf_vehicle_state s;
    CHECK(gf_vehicle_init(&s, &p, 0.0, NULL, NULL) == GF_OK, "vehicle init");
    int bad = -1;
    CHECK(gf_aiding_init(sim, a, &s, seed, out, &bad) == GF_OK && bad == 0, "init, bad %d", bad);
}

static void batch(const gf_aiding_params *a, double t_end, size_t n[3])
{
    gf_aiding_sim sim;
    start(&sim, a, 42, NULL);
    CHECK(gf_aiding_run(&sim, t_end, g_gnss, CAP, &n[0], g_baro, CAP, &n[1], g_odo, CAP, &n[2]) ==
              GF_OK, "batch run");
}

/* steps of the given sizes: every newest output must equal the batch's epoch of the same
 * count, and every epoch is delivered */
static void stepped(const gf_aiding_params *a, const double *h, int n_steps, const size_t n[3],
                    int grid_checks)
{
    gf_aiding_sim sim;
    gf_aiding_output out;
    start(&sim, a, 42, &out);
    CHECK(isnan(out.gnss.lat_rad) && out.gnss_new == 0, "cleared output");
    size_t seen[3] = {0, 0, 0};
    double t = 0.0;
    CHECK(gf_aiding_step(&sim, t, &out) == GF_OK, "step to the start");
    for (int k = 0; k <= n_steps; ++k) {
        if (k > 0) {
            const double t0 = t;
            t += h[k - 1];
            CHECK(gf_aiding_step(&sim, t, &out) == GF_OK, "step %d", k);
            if (grid_checks && out.gnss_new)
                CHECK(out.gnss.t_delivered_s <= t && out.gnss.t_delivered_s > t0,
                      "delivered in the first step reaching t + latency: %.17g in (%.17g, %.17g]",
                      out.gnss.t_delivered_s, t0, t);
            if (grid_checks && out.baro_new)
                CHECK(out.baro.t_s <= t && out.baro.t_s > t0, "baro in its step");
        }
        seen[0] += (size_t)out.gnss_new;
        seen[1] += (size_t)out.baro_new;
        seen[2] += (size_t)out.odo_new;
        if (out.gnss_new)
            CHECK(memcmp(&out.gnss, &g_gnss[seen[0] - 1], sizeof out.gnss) == 0,
                  "GNSS epoch %zu: same bits as the batch", seen[0] - 1);
        if (out.baro_new)
            CHECK(memcmp(&out.baro, &g_baro[seen[1] - 1], sizeof out.baro) == 0,
                  "baro epoch %zu", seen[1] - 1);
        if (out.odo_new)
            CHECK(memcmp(&out.odo, &g_odo[seen[2] - 1], sizeof out.odo) == 0,
                  "odometer epoch %zu", seen[2] - 1);
        if (grid_checks)
            CHECK(out.gnss_new <= 1 && out.baro_new <= 1 && out.odo_new <= 1, "one a step");
    }
    CHECK(seen[0] == n[0] && seen[1] == n[1] && seen[2] == n[2],
          "all delivered once: %zu %zu %zu vs %zu %zu %zu", seen[0], seen[1], seen[2], n[0],
          n[1], n[2]);
}

static double g_h[2000];

static void test_steps(void)
{
    const gf_aiding_params a = all_sensors();
    size_t n[3];
    batch(&a, 10.0, n);
    /* 5 Hz from 0.0137 s, delivered 0.15 s later, by 10 s: t_k + 0.15 <= 10 -> k <= 49 */
    CHECK(n[0] == 50 && n[1] == 250 && n[2] == 500, "epoch counts %zu %zu %zu", n[0], n[1], n[2]);
    for (size_t k = 0; k < n[0]; ++k) {
        CHECK(g_gnss[k].t_s == 0.0137 + (double)k / 5.0, "GNSS time of validity");
        CHECK(g_gnss[k].t_delivered_s == g_gnss[k].t_s + 0.15, "delivery time");
        CHECK(g_gnss[k].quality == 5.0, "quality");
        CHECK_CLOSE(g_gnss[k].pos_std_m[2], sqrt(4.0 + 1.0), 1e-15, "reported std");
    }
    for (int k = 0; k < 1000; ++k)
        g_h[k] = 0.01;
    stepped(&a, g_h, 1000, n, 1);
    /* random steps, 1 ms .. 0.7 s: several epochs per step are delivered together */
    test_rng r = {12345};
    double t = 0.0;
    int m = 0;
    while (t < 9.3) {
        g_h[m] = test_rng_uniform(&r, 0.001, 0.7);
        t += g_h[m++];
    }
    g_h[m++] = 10.0 - t;
    gf_aiding_sim sim;
    gf_aiding_output out;
    start(&sim, &a, 42, &out);
    size_t seen = 0;
    t = 0.0;
    for (int k = 0; k < m; ++k) {
        t += g_h[k];
        CHECK(gf_aiding_step(&sim, t, &out) == GF_OK, "random step");
        seen += (size_t)out.gnss_new;
        if (out.gnss_new)
            CHECK(memcmp(&out.gnss, &g_gnss[seen - 1], sizeof out.gnss) == 0,
                  "newest of a long step = batch epoch %zu", seen - 1);
    }
    CHECK(seen == n[0], "random steps deliver every GNSS epoch once: %zu", seen);
}

/* 3. outages, epochs on the grid ------------------------------------------------------- */
static void test_outages(void)
{
    gf_aiding_params a;
    memset(&a, 0, sizeof a);
    gf_gnss_params *g = &a.gnss;
    g->enabled = 1;
    g->rate_hz = 10.0;
    g->n_outages = 2;
    g->outage_start_s[0] = 2.0;
    g->outage_end_s[0] = 3.5;
    g->outage_start_s[1] = 7.25;
    g->outage_end_s[1] = 7.55;
    g->outage_first_s = 10.0;
    g->outage_period_s = 4.0;
    g->outage_duration_s = 1.0;
    size_t n[3];
    batch(&a, 20.0, n);
    /* epochs t_k = k / 10 (offset 0, latency 0) up to 20 s, minus [2, 3.5), [7.25, 7.55),
     * [10, 11), [14, 15), [18, 19): 201 - 15 - 3 - 3 x 10 */
    CHECK(n[0] == 201 - 15 - 3 - 30, "outage count %zu", n[0]);
    size_t j = 0;
    for (int k = 0; k <= 200; ++k) {
        const double tk = k / 10.0;
        const int out = (tk >= 2.0 && tk < 3.5) || (tk >= 7.25 && tk < 7.55) ||
                        (tk >= 10.0 && fmod(tk - 10.0, 4.0) < 1.0);
        if (!out && j < n[0])
            CHECK(g_gnss[j++].t_s == tk, "epoch %d delivered", k);
    }
    CHECK(j == n[0], "every delivered epoch expected");
    /* on the grid: steps of 0.1 s accumulated by a master (rounding), each epoch in the
     * step ending at it: the tolerance of the FMU glue */
    gf_aiding_sim sim;
    gf_aiding_output o;
    start(&sim, &a, 42, &o);
    CHECK(gf_aiding_step(&sim, 0.0, &o) == GF_OK && o.gnss_new == 1 && o.gnss.t_s == 0.0,
          "epoch at the start time delivered at the start");
    double t = 0.0;
    size_t seen = 1;
    for (int k = 1; k <= 200; ++k) {
        t += 0.1;
        CHECK(gf_aiding_step(&sim, t, &o) == GF_OK, "grid step");
        CHECK(o.gnss_new <= 1, "one epoch a step");
        if (o.gnss_new)
            CHECK(fabs(o.gnss.t_s - t) < 1e-12 && o.gnss.t_s == g_gnss[seen].t_s,
                  "grid epoch %zu at %.17g in the step to %.17g", seen, o.gnss.t_s, t);
        seen += (size_t)o.gnss_new;
    }
    CHECK(seen == n[0], "grid steps deliver %zu of %zu", seen, n[0]);
}

/* 4. seeds ---------------------------------------------------------------------------- */
static void test_seeds(void)
{
    gf_aiding_params a = all_sensors();
    size_t n[3], n2[3];
    static gf_gnss_epoch first[CAP];
    batch(&a, 5.0, n);
    memcpy(first, g_gnss, n[0] * sizeof *first);
    batch(&a, 5.0, n2);
    CHECK(n2[0] == n[0] && memcmp(first, g_gnss, n[0] * sizeof *first) == 0, "same seed");
    a.baro.enabled = 0;
    a.odo.enabled = 0;
    batch(&a, 5.0, n2);
    CHECK(memcmp(first, g_gnss, n[0] * sizeof *first) == 0, "GNSS stream independent of others");
    gf_aiding_sim sim;
    gf_vehicle_profile p = turning_profile();
    gf_vehicle_state s;
    gf_vehicle_init(&s, &p, 0.0, NULL, NULL);
    gf_aiding_init(&sim, &a, &s, 43, NULL, NULL);
    gf_aiding_run(&sim, 5.0, g_gnss, CAP, &n2[0], NULL, 0, NULL, NULL, 0, NULL);
    CHECK(first[3].lat_rad != g_gnss[3].lat_rad && first[3].true_lat_rad == g_gnss[3].true_lat_rad,
          "another seed: other noise, same truth");
}

/* 5. bad input ------------------------------------------------------------------------ */
static void expect_bad(gf_aiding_params a, int code, const char *what)
{
    gf_vehicle_profile p = turning_profile();
    gf_vehicle_state s;
    gf_vehicle_init(&s, &p, 0.0, NULL, NULL);
    gf_aiding_sim sim;
    int bad = -1;
    CHECK(gf_aiding_init(&sim, &a, &s, 1, NULL, &bad) == GF_ERR_BAD_PARAMETER && bad == code,
          "%s: bad = %d, expected %d", what, bad, code);
}

static void test_bad_input(void)
{
    gf_aiding_params a = all_sensors();
    a.gnss.rate_hz = 0.0;
    expect_bad(a, GF_AIDING_BAD_GNSS_RATE, "rate 0");
    a = all_sensors();
    a.gnss.latency_s = 3.0; /* 3 s x 5 Hz = 15 > 14 */
    expect_bad(a, GF_AIDING_BAD_GNSS_LATENCY, "latency beyond the queue");
    a = all_sensors();
    a.gnss.lever_arm_m[1] = NAN;
    expect_bad(a, GF_AIDING_BAD_GNSS_LEVER_ARM, "NaN lever arm");
    a = all_sensors();
    a.gnss.pos_gm_tau_s = 0.0;
    expect_bad(a, GF_AIDING_BAD_GNSS_GM_TAU, "tau 0 with a GM std");
    a = all_sensors();
    a.gnss.n_outages = 3;
    a.gnss.outage_end_s[0] = a.gnss.outage_end_s[1] = 1.0;
    a.gnss.outage_start_s[2] = 5.0;
    a.gnss.outage_end_s[2] = 4.0;
    expect_bad(a, GF_AIDING_BAD_GNSS_OUTAGE + 2, "outage 2 reversed");
    a = all_sensors();
    a.gnss.outage_duration_s = 5.0;
    a.gnss.outage_period_s = 4.0;
    expect_bad(a, GF_AIDING_BAD_GNSS_PERIODIC, "outage longer than its period");
    a = all_sensors();
    a.gnss.quality = 9;
    expect_bad(a, GF_AIDING_BAD_GNSS_QUALITY, "quality 9");
    a = all_sensors();
    a.baro.std_m = -1.0;
    expect_bad(a, GF_AIDING_BAD_BARO_STD, "negative baro std");
    a = all_sensors();
    a.baro.enabled = 2;
    expect_bad(a, GF_AIDING_BAD_BARO_ENABLED, "baro enabled = 2");
    a = all_sensors();
    a.odo.scale_error = 0.7;
    expect_bad(a, GF_AIDING_BAD_ODO_SCALE, "odometer scale error 0.7");
    a = all_sensors();
    a.odo.rate_hz = 5000.0;
    expect_bad(a, GF_AIDING_BAD_ODO_RATE, "odometer at 5 kHz");
    /* times and atomicity */
    gf_aiding_sim sim, copy;
    gf_aiding_output out, out_copy;
    a = all_sensors();
    a.odo.enabled = 0;
    a.odo.rate_hz = NAN; /* a disabled sensor's parameters are not checked */
    start(&sim, &a, 1, &out);
    a = all_sensors();
    start(&sim, &a, 1, &out);
    CHECK(gf_aiding_step(&sim, 1.0, &out) == GF_OK, "step");
    CHECK(gf_aiding_step(&sim, 0.5, &out) == GF_ERR_BAD_TIME, "backwards");
    CHECK(gf_aiding_step(&sim, 1.0 - 1e-12, &out) == GF_OK && out.gnss_new == 0,
          "a master's clock an ulp short: accepted, nothing new");
    CHECK(gf_aiding_step(&sim, NAN, &out) == GF_ERR_BAD_TIME, "NaN time");
    size_t n = 0, nb = 0, no = 0;
    CHECK(gf_aiding_run(&sim, 3.0, g_gnss, 2, &n, g_baro, CAP, &nb, g_odo, CAP, &no) ==
              GF_ERR_BAD_SIZE && n == 2, "too small an array: %zu", n);
    CHECK(gf_aiding_run(&sim, 3.0, NULL, 0, NULL, g_baro, CAP, &nb, g_odo, CAP, &no) ==
              GF_ERR_NULL_POINTER, "no GNSS array for an enabled GNSS");
    /* sync: the commanded vehicle must not be ahead of unmeasured epochs */
    gf_vehicle_profile p = turning_profile();
    gf_vehicle_state s;
    gf_vehicle_sample x;
    gf_vehicle_init(&s, &p, 0.0, NULL, NULL);
    gf_vehicle_step(&s, 2.0, &x);
    CHECK(gf_aiding_sync(&sim, &s) == GF_ERR_BAD_TIME, "sync ahead of the epochs");
    gf_vehicle_init(&s, &p, 0.0, NULL, NULL);
    gf_vehicle_step(&s, 1.0, &x);
    CHECK(gf_aiding_sync(&sim, &s) == GF_OK, "sync at the time reached");
    /* a vehicle running into 89 deg: the step fails and changes nothing */
    memset(&p, 0, sizeof p);
    p.lat0_rad = 88.99 * REF_PI / 180.0; /* 1.1 km to go */
    p.speed0_m_s = 300.0;
    gf_vehicle_init(&s, &p, 0.0, NULL, NULL);
    CHECK(gf_aiding_init(&sim, &a, &s, 1, &out, NULL) == GF_OK, "init near the pole");
    copy = sim;
    out_copy = out;
    CHECK(gf_aiding_step(&sim, 1.0, &out) == GF_OK, "one second north");
    copy = sim;
    out_copy = out;
    CHECK(gf_aiding_step(&sim, 10.0, &out) == GF_ERR_DIVERGED, "the pole");
    CHECK(memcmp(&copy, &sim, sizeof sim) == 0 && memcmp(&out_copy, &out, sizeof out) == 0,
          "unchanged after the error");
}

int main(void)
{
    test_geometry();
    test_steps();
    test_outages();
    test_seeds();
    test_bad_input();
    TEST_MAIN_END();
}
