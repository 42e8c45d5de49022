/* test_sins_domain.c — a step that would take the navigation state out of its domain
 * (gf_sins_state_check: a height in the Earth model's range (-a/2, a/3), finite numbers)
 * returns GF_ERR_DIVERGED and leaves the state as it was, in every stepper that shares
 * the mechanization (gf_sins_step, gf_sins_run forward and backward, gf_sins_step_group,
 * gf_sins_step_compensated, gf_ins_step).
 *
 * Found by fuzz_sins (corpus crash-03894d44...): a GF_OK step of the BARO loop with an
 * absurd but finite external height took the height from within the range to 4.7e172 m;
 * the step checked the new height against the lower bound and finiteness only, and the
 * state was then refused by gf_sins_state_check. Any way of reaching it is refused now:
 * the external height, a vertical velocity, the baro loop's own overflow.
 *
 * Closed form, from nothing the code computes: level attitude, a purely vertical velocity
 * v_U and zero increments over T. The transport rate is zero (v_E = v_N = 0) and the
 * Coriolis term (2 w_ie) x v is horizontal, so the vertical channel is
 *   v_U' = v_U - g(L, h_mid) T,   h' = h + T (v_U + v_U') / 2 = h + T v_U - g T^2 / 2
 * (trapezoid, gf_sins.h), with g from NIMA TR8350.2 eq. 4-1 and 4-3 (gf_ref.h) and
 * h_mid = h + T v_U / 2. With T = 0.01 s and v_U = 1e5 m/s the height moves by 1000 m
 * less g T^2 / 2 < 5e-4 m: starting 1500 m below a/3 the step ends 500 m below it (GF_OK,
 * the state passes the check), starting 600 m below it ends 400 m above (GF_ERR_DIVERGED).
 * Runs in a few ms. */
#include <float.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "est/gf_ins_gnss.h"
#include "nav/gf_earth.h"
#include "nav/gf_sins.h"
#include "gf_ref.h"
#include "gf_test.h"

#define T_S 0.01             /* sample interval, s */
#define VU_M_S 1e5           /* vertical velocity, m/s: T v_U = 1000 m */
#define LAT_RAD 0.5
#define H_TOP_M (REF_A / 3.0) /* the Earth model's upper height bound, a/3 (gf_earth.h) */

static gf_sins_config cfg_of(int input, int vertical)
{
    gf_sins_config c;
    gf_sins_config_default(&c);
    c.input = input;
    c.vertical = vertical;
    /* the absurd-sample limits out of the way: the samples here are zero */
    return c;
}

static int start(gf_sins_state *s, int input, int vertical, double h_m, double vU_m_s)
{
    const gf_sins_config c = cfg_of(input, vertical);
    const double q[4] = {1, 0, 0, 0}, v[3] = {0.0, 0.0, vU_m_s};
    memset(s, 0, sizeof *s); /* padding zero, so that whole-struct compares hold */
    return gf_sins_init(s, &c, q, v, LAT_RAD, 0.1, h_m, 0.0) == GF_OK;
}

/* one gf_sins_step: its status; *s unchanged (bytes) unless GF_OK */
static gf_status step_once(gf_sins_state *s, const char *what)
{
    const double z[3] = {0, 0, 0};
    gf_sins_state before;
    memcpy(&before, s, sizeof before);
    const gf_status st = gf_sins_step(s, z, z, T_S, NAN);
    if (st != GF_OK)
        CHECK(memcmp(&before, s, sizeof before) == 0, "%s: refused step changed the state", what);
    return st;
}

/* the closed form above: accepted below a/3, refused beyond it, state untouched */
static void test_height_top(void)
{
    gf_sins_state s;
    /* accepted: h' = a/3 - 500 m */
    const double h_ok = H_TOP_M - 1500.0;
    CHECK(start(&s, GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, h_ok, VU_M_S), "init below a/3");
    CHECK(step_once(&s, "below a/3") == GF_OK, "a step ending 500 m below a/3 is GF_OK");
    const double g_mid = ref_gravity(LAT_RAD, h_ok + 0.5 * T_S * VU_M_S);
    const double h_ref = h_ok + T_S * VU_M_S - 0.5 * g_mid * T_S * T_S;
    /* the mid point's gravity differs from the one at h_mid by the velocity
     * extrapolation only (a = 0): the difference is round-off of 2e6 m, 1e-9 m */
    CHECK_CLOSE(s.h_m, h_ref, 1e-6, "h' = h + T v_U - g T^2/2");
    CHECK_CLOSE(s.v_n_m_s[2], VU_M_S - g_mid * T_S, 1e-9, "v_U' = v_U - g T");
    CHECK(gf_sins_state_check(&s) == GF_OK, "the accepted state passes gf_sins_state_check");

    /* refused at the new height: h_mid = a/3 - 100 m, h' = a/3 + 400 m */
    CHECK(start(&s, GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, H_TOP_M - 600.0, VU_M_S),
          "init 600 m below a/3");
    gf_status st = step_once(&s, "new height beyond a/3");
    CHECK(st == GF_ERR_DIVERGED, "new height beyond a/3: GF_ERR_DIVERGED (got %d)", (int)st);
    CHECK(gf_sins_state_check(&s) == GF_OK, "the untouched state still passes the check");

    /* refused at the mid point: h_mid = a/3 + 100 m (h' = a/3 + 600 m) */
    CHECK(start(&s, GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, H_TOP_M - 400.0, VU_M_S),
          "init 400 m below a/3");
    st = step_once(&s, "mid-point height beyond a/3");
    CHECK(st == GF_ERR_DIVERGED, "mid-point height beyond a/3: GF_ERR_DIVERGED (got %d)", (int)st);

    /* the fuzzer's case: the BARO loop (tau = 10 s) with an absurd but finite external
     * height h_ext = 1.6e175 m at 10 km. The corrector (gf_sins.h) makes
     * h' = h_pred - k1 (h_pred - h_ext) T ~ (3 / tau) T h_ext = 4.8e172 m, finite (the
     * gravity is taken at h_mid = 1e4 m): before the fix GF_OK with h' = 4.8e172 m,
     * v_U' = -k2 err T ~ 4.8e171 m/s, which gf_sins_state_check refused */
    {
        const gf_sins_config c = cfg_of(GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_BARO);
        const double q[4] = {1, 0, 0, 0}, v[3] = {0, 0, 0}, z[3] = {0, 0, 0};
        gf_sins_state before;
        memset(&s, 0, sizeof s);
        CHECK(gf_sins_init(&s, &c, q, v, LAT_RAD, 0.1, 1e4, 0.0) == GF_OK, "init BARO at 10 km");
        memcpy(&before, &s, sizeof s);
        st = gf_sins_step(&s, z, z, T_S, 1.6e175);
        CHECK(st == GF_ERR_DIVERGED, "BARO, h_ext = 1.6e175 m: GF_ERR_DIVERGED (got %d)", (int)st);
        CHECK(memcmp(&before, &s, sizeof s) == 0, "BARO, h_ext = 1.6e175 m: state unchanged");
    }

    /* a finite vertical velocity so absurd that the height term of the gravity overflows
     * (h_mid = 5e175 m): refused before the fix too, by the non-finite velocity */
    CHECK(start(&s, GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, 1e4, 1e178), "init at 1e178 m/s");
    st = step_once(&s, "v_U = 1e178 m/s");
    CHECK(st == GF_ERR_DIVERGED, "v_U = 1e178 m/s: GF_ERR_DIVERGED (got %d)", (int)st);

    /* the lower bound, -a/2, as before the fix: from -a/2 + 600 m downwards at 1e5 m/s */
    CHECK(start(&s, GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, -0.5 * REF_A + 600.0, -VU_M_S),
          "init 600 m above -a/2");
    st = step_once(&s, "below -a/2");
    CHECK(st == GF_ERR_DIVERGED, "new height below -a/2: GF_ERR_DIVERGED (got %d)", (int)st);
}

/* BARO loop with tau = 1e-104 s: k3 = 1/tau^3 overflows (tau^3 is below the smallest
 * double), so b' = b + k3 err T is Inf, or Inf * 0 = NaN when the external height equals
 * the inertial prediction (err = 0). Before the fix: GF_OK with b' = NaN, refused by the
 * check. The prediction h_pred is the free channel's h' (the same expression, gf_sins.c). */
static void test_baro_overflow(void)
{
    gf_sins_config c = cfg_of(GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_BARO);
    c.baro_tau_s = 1e-104;
    const double q[4] = {1, 0, 0, 0}, v[3] = {0, 0, 0}, z[3] = {0, 0, 0};
    gf_sins_state s, free_s, before;
    memset(&s, 0, sizeof s);
    CHECK(gf_sins_init(&s, &c, q, v, LAT_RAD, 0.1, 100.0, 0.0) == GF_OK, "baro: init");
    memcpy(&free_s, &s, sizeof s);
    free_s.cfg.vertical = GF_SINS_VERTICAL_FREE;
    CHECK(gf_sins_step(&free_s, z, z, T_S, NAN) == GF_OK, "baro: the free channel's step");
    memcpy(&before, &s, sizeof s);
    const gf_status st = gf_sins_step(&s, z, z, T_S, free_s.h_m); /* err = 0 */
    CHECK(st == GF_ERR_DIVERGED, "baro, k3 overflow: GF_ERR_DIVERGED (got %d)", (int)st);
    CHECK(memcmp(&before, &s, sizeof s) == 0, "baro: refused step changed the state");
}

/* The other entry points over the same mechanization, on the refused case (new height
 * a/3 + 400 m): each reports GF_ERR_DIVERGED and leaves its state as it was. */
static void test_other_steppers(void)
{
    const double z[3 * 4] = {0};
    gf_sins_state s, before;
    double qo[4 * 4], vo[3 * 4], po[3 * 4];

    /* gf_sins_run forward: n_done 0, state unchanged */
    start(&s, GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, H_TOP_M - 600.0, VU_M_S);
    memcpy(&before, &s, sizeof s);
    size_t done = 99;
    gf_status st = gf_sins_run(&s, 2, z, z, T_S, NULL, NULL, 0, qo, vo, po, NULL, &done);
    CHECK(st == GF_ERR_DIVERGED && done == 0, "run forward: DIVERGED, n_done 0 (got %d, %zu)",
          (int)st, done);
    CHECK(memcmp(&before, &s, sizeof s) == 0, "run forward: state unchanged");

    /* gf_sins_run backward: reversed navigation of a body falling at v_U (true time), i.e.
     * rising at v_U in processing order */
    start(&s, GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, H_TOP_M - 600.0, -VU_M_S);
    CHECK(gf_sins_reverse(&s) == GF_OK && s.v_n_m_s[2] == VU_M_S, "reverse");
    memcpy(&before, &s, sizeof s);
    done = 99;
    st = gf_sins_run(&s, 2, z, z, T_S, NULL, NULL, 1, qo, vo, po, NULL, &done);
    CHECK(st == GF_ERR_DIVERGED && done == 0, "run backward: DIVERGED, n_done 0 (got %d, %zu)",
          (int)st, done);
    CHECK(memcmp(&before, &s, sizeof s) == 0, "run backward: state unchanged");
    /* and gf_sins_step on the reversed state */
    st = step_once(&s, "reversed step");
    CHECK(st == GF_ERR_DIVERGED, "reversed step: DIVERGED (got %d)", (int)st);

    /* gf_sins_step_group, two subsamples of T/2 */
    start(&s, GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, H_TOP_M - 600.0, VU_M_S);
    memcpy(&before, &s, sizeof s);
    st = gf_sins_step_group(&s, 2, z, z, T_S, NAN);
    CHECK(st == GF_ERR_DIVERGED, "step_group: DIVERGED (got %d)", (int)st);
    CHECK(memcmp(&before, &s, sizeof s) == 0, "step_group: state unchanged");

    /* gf_sins_step_compensated (rates; the first sample starts the record) */
    start(&s, GF_SINS_INPUT_RATES, GF_SINS_VERTICAL_FREE, H_TOP_M - 600.0, VU_M_S);
    CHECK(gf_sins_step(&s, z, z, T_S, NAN) == GF_OK, "rates: first sample");
    memcpy(&before, &s, sizeof s);
    st = gf_sins_step_compensated(&s, z, z, z, z, T_S, NAN);
    CHECK(st == GF_ERR_DIVERGED, "step_compensated: DIVERGED (got %d)", (int)st);
    CHECK(memcmp(&before, &s, sizeof s) == 0, "step_compensated: state unchanged");
}

/* The integrated filter's sample (gf_ins_step -> gf_sins_step_trusted): DIVERGED, the
 * navigation state untouched (the mechanization refuses before any write). */
static void test_ins_gnss(void)
{
    gf_ins_config c;
    gf_ins_config_default(&c);
    int32_t n = 0, bad = 0;
    CHECK(gf_ins_state_count(&c, &n) == GF_OK && n > 0 && n <= GF_INS_MAX_STATES, "ins: states");
    static double P[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    memset(P, 0, sizeof P);
    for (int i = 0; i < n; ++i)
        P[i * n + i] = 1e-4;
    static gf_ins_filter f, before;
    memset(&f, 0, sizeof f);
    const double q[4] = {1, 0, 0, 0}, v[3] = {0, 0, VU_M_S}, z[3] = {0, 0, 0};
    gf_status st = gf_ins_init(&f, &c, 0.0, q, v, LAT_RAD, 0.1, H_TOP_M - 600.0, NULL, P, &bad);
    CHECK(st == GF_OK, "ins: init 600 m below a/3 (got %d, bad %d)", (int)st, (int)bad);
    if (st != GF_OK)
        return;
    memcpy(&before, &f, sizeof f);
    st = gf_ins_step(&f, T_S, z, z, 0, NULL, NULL, NULL);
    CHECK(st == GF_ERR_DIVERGED, "ins: step beyond a/3: DIVERGED (got %d)", (int)st);
    CHECK(memcmp(&before.nav, &f.nav, sizeof f.nav) == 0, "ins: navigation state unchanged");
    CHECK(gf_sins_state_check(&f.nav) == GF_OK, "ins: navigation state still valid");
}

int main(void)
{
    test_height_top();
    test_baro_overflow();
    test_other_steppers();
    test_ins_gnss();
    TEST_MAIN_END();
}
