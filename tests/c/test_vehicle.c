/* test_vehicle.c — the vehicle truth source (gf_vehicle) against closed forms written
 * here independently: rest, straight run, circle; bad input and error atomicity.
 * (The comparison with the Python trajectory generator is in tests/test_vehicle.py.) */
#include <math.h>
#include <string.h>

#include "gf_ref.h"
#include "gf_test.h"
#include "sim/gf_vehicle.h"

static gf_vehicle_profile base_profile(void)
{
    gf_vehicle_profile p;
    memset(&p, 0, sizeof p);
    p.lat0_rad = 30.0 * REF_PI / 180.0;
    p.lon0_rad = 114.0 * REF_PI / 180.0;
    p.h0_m = 100.0;
    return p;
}

static void test_rest(void)
{
    gf_vehicle_profile p = base_profile();
    p.heading0_rad = 0.7;
    gf_vehicle_state s;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "init at rest");
    for (int k = 1; k <= 100; ++k)
        CHECK(gf_vehicle_step(&s, 0.01 * k, &x) == GF_OK, "step %d", k);
    /* at rest: f^b = C_n^b [0, 0, g], w_ib^b = C_n^b w_ie^n; heading 0.7 clockwise */
    const double g = ref_gravity(p.lat0_rad, p.h0_m), W = 7.292115e-5;
    const double c = cos(0.7), sn = sin(0.7), wN = W * cos(p.lat0_rad);
    CHECK_CLOSE(x.accel_m_s2[2], g, 1e-12, "rest f_z = gamma (NIMA TR8350.2)");
    CHECK_CLOSE(x.accel_m_s2[0], 0.0, 1e-15, "rest f_x");
    /* body x = c E - s N, body y = s E + c N */
    CHECK_CLOSE(x.gyro_rad_s[0], -sn * wN, 1e-19, "rest w_x");
    CHECK_CLOSE(x.gyro_rad_s[1], c * wN, 1e-19, "rest w_y");
    CHECK_CLOSE(x.gyro_rad_s[2], W * sin(p.lat0_rad), 1e-19, "rest w_z");
    CHECK_CLOSE(x.dv_m_s[2], 0.01 * g, 1e-14, "rest dv_z = g dt");
    CHECK_CLOSE(x.euler_rad[0], 0.7, 1e-15, "heading");
    CHECK_CLOSE(x.lat_rad, p.lat0_rad, 0.0, "no motion");
}

static void test_straight(void)
{
    /* from rest to 10 m/s over 20 s (smooth step), heading north: distance after the
     * segment = 10 * 20 / 2 (S integrates to 1/2), then 10 m/s */
    gf_vehicle_profile p = base_profile();
    p.n_segments = 1;
    p.segment[0].duration_s = 20.0;
    p.segment[0].dspeed_m_s = 10.0;
    gf_vehicle_state s;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "init straight");
    CHECK(gf_vehicle_step(&s, 20.0, &x) == GF_OK, "to 20 s in one step (80 pieces)");
    CHECK_CLOSE(x.north_m, 100.0, 1e-11, "displacement after the smooth start");
    CHECK_CLOSE(x.speed_m_s, 10.0, 1e-14, "speed");
    CHECK(gf_vehicle_step(&s, 30.0, &x) == GF_OK, "cruise");
    CHECK_CLOSE(x.north_m, 200.0, 1e-11, "cruise displacement");
    double RM, RN;
    ref_radii(p.lat0_rad, &RM, &RN);
    CHECK_CLOSE(x.lat_rad, p.lat0_rad + 200.0 / (RM + p.h0_m), 1e-16, "latitude mapping");
    CHECK_CLOSE(x.east_m, 0.0, 0.0, "no east motion");
}

static void test_circle(void)
{
    /* constant speed v, heading rate -v/r: horizontal acceleration v^2/r toward the
     * centre = body -x (counter-clockwise circle: centre on the left) */
    gf_vehicle_profile p = base_profile();
    const double v = 10.0, r = 100.0;
    p.speed0_m_s = v;
    p.heading_rate0_rad_s = -v / r;
    gf_vehicle_state s;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "init circle");
    const double T = 2.0 * REF_PI * r / v;
    CHECK(gf_vehicle_run(&s, 1, T, &x, NULL) == GF_OK, "one lap in one step");
    CHECK_CLOSE(x.east_m, 0.0, 1e-9, "back at the start (east)");
    CHECK_CLOSE(x.north_m, 0.0, 1e-9, "back at the start (north)");
    /* Coriolis and transport terms are below 1.5e-3 m/s^2 here */
    CHECK_CLOSE(x.accel_m_s2[0], -v * v / r, 2e-3, "centripetal (body -x)");
    CHECK_CLOSE(x.gyro_rad_s[2], v / r + 7.292115e-5 * sin(p.lat0_rad), 2e-6, "yaw rate");
    /* one turn plus the Earth rate about the vertical; transport terms < 1e-5 rad */
    CHECK_CLOSE(x.dtheta_rad[2], 2.0 * REF_PI + 7.292115e-5 * sin(p.lat0_rad) * T, 1e-5,
                "one turn of increments");
}

static void test_bad_input(void)
{
    gf_vehicle_profile p = base_profile();
    gf_vehicle_state s;
    gf_vehicle_sample x;
    int bad = 0;
    p.lat0_rad = 1.56;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, &bad) == GF_ERR_BAD_PARAMETER && bad == 1, "pole");
    p = base_profile();
    p.n_segments = 2;
    p.segment[0].duration_s = 1.0;
    p.segment[0].dspeed_m_s = 5.0;
    p.segment[1].duration_s = 1.0;
    p.segment[1].dspeed_m_s = -6.0;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, &bad) == GF_ERR_BAD_PARAMETER && bad == 101,
          "negative speed in segment 1 (bad = %d)", bad);
    p.segment[1].dspeed_m_s = NAN;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, &bad) == GF_ERR_NONFINITE_INPUT, "NaN segment");
    p.n_segments = GF_VEHICLE_MAX_SEGMENTS + 1;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, &bad) == GF_ERR_BAD_SIZE, "too many segments");
    p = base_profile();
    CHECK(gf_vehicle_init(&s, &p, 5.0, &x, &bad) == GF_OK, "init at 5 s");
    gf_vehicle_state before = s;
    CHECK(gf_vehicle_step(&s, 5.0, &x) == GF_ERR_BAD_TIME, "step to the same time");
    CHECK(gf_vehicle_step(&s, NAN, &x) == GF_ERR_BAD_TIME, "step to NaN");
    CHECK(memcmp(&before, &s, sizeof s) == 0, "state unchanged after errors");
    CHECK(gf_vehicle_command(&s, -1.0, 0.0, 1.0) == GF_ERR_BAD_PARAMETER, "negative speed command");
    CHECK(gf_vehicle_command(&s, 1.0, 0.0, 0.0) == GF_ERR_BAD_PARAMETER, "zero command time");
    /* a northward run toward the pole stops with GF_ERR_DIVERGED */
    p.speed0_m_s = 3e5;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, &bad) == GF_OK, "fast run");
    CHECK(gf_vehicle_step(&s, 100.0, &x) == GF_ERR_DIVERGED, "past 89 deg");
}

/* A state whose profile indices were corrupted (a damaged FMU state), and a step so long
 * that its quadrature piece count overflowed an int: refused with a status, nothing read
 * beyond the segment array. Before, a 1e12 s step computed (int) of 4e12 pieces
 * (undefined; in practice negative, so nothing was integrated) and returned GF_OK. */
static void test_corrupted_state_and_huge_step(void)
{
    gf_vehicle_profile p = base_profile();
    gf_vehicle_state s, before;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "init");
    CHECK(gf_vehicle_state_check(&s) == GF_OK, "check of a good state");
    before = s;
    x.time_s = -1.0;
    const gf_status st = gf_vehicle_step(&s, 1e12, &x);
    CHECK(st == GF_ERR_BAD_TIME && memcmp(&s, &before, sizeof s) == 0,
          "a step of 1e12 s: BAD_TIME (got %d, sample time %g), state unchanged", (int)st, x.time_s);
    CHECK(gf_vehicle_step(&s, 1e5 + 1.0, &x) == GF_ERR_BAD_TIME, "a step just over 1e5 s refused");
    CHECK(gf_vehicle_step(&s, 1.0, &x) == GF_OK, "a normal step");
    const struct { const char *what; size_t n_segments, next_segment; } bad[] = {
        {"n_segments 33", GF_VEHICLE_MAX_SEGMENTS + 1, 0},
        {"n_segments 1e9, next 5", 1000000000u, 5},
        {"next_segment beyond n_segments", 2, 3},
        {"next_segment 1e9", 2, 1000000000u},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        gf_vehicle_state b = s;
        b.profile.n_segments = bad[i].n_segments;
        b.next_segment = bad[i].next_segment;
        before = b;
        CHECK(gf_vehicle_step(&b, 2.0, &x) == GF_ERR_BAD_SIZE && memcmp(&b, &before, sizeof b) == 0,
              "%s: step BAD_SIZE, state unchanged", bad[i].what);
        CHECK(gf_vehicle_command(&b, 5.0, 0.0, 1.0) == GF_ERR_BAD_SIZE, "%s: command BAD_SIZE", bad[i].what);
        CHECK(gf_vehicle_state_check(&b) == GF_ERR_BAD_SIZE, "%s: check BAD_SIZE", bad[i].what);
    }
    gf_vehicle_state b = s;
    b.east_m = NAN;
    CHECK(gf_vehicle_state_check(&b) == GF_ERR_NONFINITE_INPUT, "check: NaN displacement");
    b = s;
    b.R_M0_m = -1.0;
    CHECK(gf_vehicle_state_check(&b) == GF_ERR_BAD_PARAMETER, "check: negative radius");
    b = s;
    b.profile.lat0_rad = 1.56;
    CHECK(gf_vehicle_state_check(&b) == GF_ERR_BAD_PARAMETER, "check: start latitude beyond 89 deg");
    {
        /* a time far beyond the active segment (a restored state whose time was changed;
         * fuzz_fmu_vehicle): the step used to integrate from the segment's end, 10^6 s of
         * pieces in one "0.01 s" step; refused now, by the check and by the step */
        gf_vehicle_profile pp = base_profile();
        pp.n_segments = 1;
        pp.segment[0].duration_s = 60.0;
        pp.segment[0].dspeed_m_s = 5.0;
        gf_vehicle_state v;
        CHECK(gf_vehicle_init(&v, &pp, 0.0, &x, NULL) == GF_OK, "init, one 60 s segment");
        CHECK(gf_vehicle_step(&v, 60.0, &x) == GF_OK, "to the segment's end");
        CHECK(gf_vehicle_state_check(&v) == GF_OK, "check at the segment's end (cruise next)");
        gf_vehicle_state w = v;
        w.time_s = 30.0;           /* before the cruise segment began: inconsistent too */
        w.active_t0_s = 60.0;
        CHECK(gf_vehicle_state_check(&w) == GF_ERR_BAD_PARAMETER, "check: time before its segment");
        v = s;                     /* the base vehicle: its first segment is the cruise */
        v.active.duration_s = 60.0;
        v.time_s = 1e6;
        before = v;
        CHECK(gf_vehicle_state_check(&v) == GF_ERR_BAD_PARAMETER, "check: time beyond its segment");
        CHECK(gf_vehicle_step(&v, 1e6 + 0.01, &x) == GF_ERR_BAD_PARAMETER &&
                  memcmp(&v, &before, sizeof v) == 0, "step: refused, state unchanged");
    }
}

static void test_command(void)
{
    /* a command reached over 2 s: speed and heading rate arrive, with zero acceleration
     * at both ends (smooth step) */
    gf_vehicle_profile p = base_profile();
    gf_vehicle_state s;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "init");
    CHECK(gf_vehicle_command(&s, 8.0, 0.1, 2.0) == GF_OK, "command");
    CHECK(gf_vehicle_run(&s, 300, 0.01, (gf_vehicle_sample[300]){0}, NULL) == GF_OK, "3 s");
    CHECK(gf_vehicle_step(&s, 3.01, &x) == GF_OK, "step");
    CHECK_CLOSE(x.speed_m_s, 8.0, 1e-14, "commanded speed");
    CHECK_CLOSE(x.heading_rate_rad_s, 0.1, 1e-15, "commanded heading rate");
    /* heading: 0.1 * (2 * 1/2 + 1.01) = 0.201 rad */
    CHECK_CLOSE(x.euler_rad[0], 0.201, 1e-13, "heading from the integral of S");
}

static void test_east_cruise_coriolis(void)
{
    /* constant speed v due east (heading pi/2, level): v^n = [v, 0, 0] is constant, so
     * f^n = (2 w_ie + w_en) x v^n - g^n with w_ie = W [0, cos L, sin L], w_en = v / (R_N + h)
     * [0, 1, tan L]: f^n = [0, (2 W sin L + v tan L / (R_N + h)) v, g - (2 W cos L +
     * v / (R_N + h)) v]; the body (x right = south, y forward = east, z up) sees
     * f^b = [-f^n_N, f^n_E, f^n_U]. The Coriolis terms are 1.5e-3 and 2.5e-3 m/s^2 here. */
    gf_vehicle_profile p = base_profile();
    const double v = 20.0, L = p.lat0_rad, h = p.h0_m, W = REF_W_IE;
    p.speed0_m_s = v;
    p.heading0_rad = 0.5 * REF_PI;
    gf_vehicle_state s;
    gf_vehicle_sample x;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &x, NULL) == GF_OK, "init east cruise");
    CHECK(gf_vehicle_step(&s, 10.0, &x) == GF_OK, "cruise 10 s");
    double RM, RN;
    ref_radii(L, &RM, &RN);
    const double fN = (2.0 * W * sin(L) + v * tan(L) / (RN + h)) * v;
    const double fU = ref_gravity(L, h) - (2.0 * W * cos(L) + v / (RN + h)) * v;
    /* measured: 0 in x and z, 2.4e-19 m/s^2 in y (gcc 12, x86-64); tolerance 1e-10 m/s^2,
     * the reference gravity's 1e-12 relative agreement with gf_earth (test_earth) on
     * g = 9.8 m/s^2, should another compiler round the Somigliana terms otherwise; the
     * Coriolis mistakes this guards against are 7e-4 m/s^2 and more */
    CHECK_CLOSE(x.lat_rad, L, 1e-15, "a due-east rhumb line keeps the latitude");
    CHECK_CLOSE(x.accel_m_s2[0], -fN, 1e-10, "f^b x = -f^n_N (Coriolis + transport)");
    CHECK_CLOSE(x.accel_m_s2[1], 0.0, 1e-10, "f^b y = f^n_E = 0");
    CHECK_CLOSE(x.accel_m_s2[2], fU, 1e-10, "f^b z = g - vertical Coriolis/transport");
}

int main(void)
{
    test_rest();
    test_straight();
    test_circle();
    test_east_cruise_coriolis();
    test_bad_input();
    test_corrupted_state_and_huge_step();
    test_command();
    TEST_MAIN_END();
}
