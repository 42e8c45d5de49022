/* test_sins.c — strapdown mechanization (gf_sins) and WGS-84 Earth model (gf_earth)
 * against closed forms.
 *
 * Truth never comes from the code under test: the WGS-84 constants, radii, normal
 * gravity (Somigliana, NIMA TR8350.2 eq. 4-1 and 4-3, and the original a/b form),
 * Euler angle matrices and quaternions, and the exact sensor increments of the motions
 * below are written here from their closed forms. The motions:
 *   - stationary on the Earth at (L, lambda, h) with a fixed attitude: f^n = [0, 0, g],
 *     w_ib^b = C_n^b w_ie^n, both constant: dtheta = T C_n^b w_ie^n, dv = T C_n^b f^n
 *     are exact; nothing may move (1 h at 100 Hz);
 *   - constant velocity along a parallel, fixed attitude: f^n = (2 w_ie + w_en) x v - g^n
 *     and w_in are constant, the longitude grows at vE / ((R_N + h) cos L) (1 h);
 *   - stationary and level, spinning about the body up axis: heading psi0 - omega t;
 *   - stationary, spinning about a tilted body axis: the specific force turns in the
 *     body, and the velocity error follows the algorithm's predicted truncation;
 *   - stationary with a height error and the BARO loop: the error follows the triple
 *     pole closed form e0 (1 - 2 t/tau + t^2/(2 tau^2)) exp(-t/tau);
 *   - a moving record navigated forward, reversed and navigated backward: it must come
 *     back to where it started;
 *   - a huge northward velocity next to the latitude limit (89.9 deg): GF_ERR_DIVERGED;
 *     a start at or beyond the limit (the 90 deg - 2e-9 rad where the unlimited
 *     mechanization returned a 74.8 rad longitude) is refused; a step covering more than
 *     a turn of longitude still reports it in (-pi, pi];
 *   - a quaternion off unit norm within the accepted 1e-6 gives the Euler angles of the
 *     rotation it stands for (near pitch 90 deg an unnormalised one moved the pitch by
 *     0.1 deg).
 * Plus bitwise properties (batch = steps, forward and backward; chunks; no hidden
 * state), the rate-input start of record, and every error path (status, state
 * unchanged, n_done). Tolerances are justified where they are set; figures are printed.
 * Runs in ~0.3 s plain, ~2 s under AddressSanitizer + UBSan. */
#include <float.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "nav/gf_earth.h"
#include "nav/gf_sins.h"
#include "gf_ref.h"
#include "gf_test.h"

/* gf_earth_gravity through its status-returning API (NaN on error) */
static double grav(double lat_rad, double h_m)
{
    double g = NAN;
    if (gf_earth_gravity(lat_rad, h_m, &g) != GF_OK)
        return NAN;
    return g;
}

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define EPS DBL_EPSILON

static double wrap_pi(double a) { return remainder(a, 2.0 * PI); }

static double ulp(double x) { return nextafter(fabs(x), INFINITY) - fabs(x); }

/* field-by-field bitwise equality of two states (struct padding is indeterminate) */
#define SAME_FIELD(a, b, f) (memcmp(&(a)->f, &(b)->f, sizeof (a)->f) == 0)
static int state_same(const gf_sins_state *a, const gf_sins_state *b)
{
    return SAME_FIELD(a, b, cfg.input) && SAME_FIELD(a, b, cfg.coning) &&
           SAME_FIELD(a, b, cfg.vertical) && SAME_FIELD(a, b, cfg.hold_height_m) &&
           SAME_FIELD(a, b, cfg.baro_tau_s) && SAME_FIELD(a, b, cfg.max_rate_rad_s) &&
           SAME_FIELD(a, b, cfg.max_specific_force_m_s2) && SAME_FIELD(a, b, cfg.subsamples) &&
           SAME_FIELD(a, b, q_bn) &&
           SAME_FIELD(a, b, v_n_m_s) && SAME_FIELD(a, b, lat_rad) && SAME_FIELD(a, b, lon_rad) &&
           SAME_FIELD(a, b, h_m) && SAME_FIELD(a, b, time_s) && SAME_FIELD(a, b, earth_rate_sign) &&
           SAME_FIELD(a, b, a_n_m_s2) && SAME_FIELD(a, b, prev_gyro) &&
           SAME_FIELD(a, b, prev_accel) && SAME_FIELD(a, b, have_prev) &&
           SAME_FIELD(a, b, baro_accel_m_s2) && SAME_FIELD(a, b, sin_lat) && SAME_FIELD(a, b, cos_lat) &&
           SAME_FIELD(a, b, R_M_m) && SAME_FIELD(a, b, n_samples);
}

/* The state keeps sin and cos of its latitude and R_M there (gf_sins.h). The core
 * updates them by an angle-sum series and recomputes them with libm every 64th
 * sample: at most 63 series steps of a few roundings each, 64 x 4 eps. R_M is taken at
 * the last mid-point, half a step of latitude away: relative 3 e^2 |d| < 1e-9. */
static void check_kept_trig(const gf_sins_state *s, const char *what)
{
    double RM, RN;
    ref_radii(s->lat_rad, &RM, &RN);
    CHECK(fabs(s->sin_lat - sin(s->lat_rad)) <= 256 * EPS && fabs(s->cos_lat - cos(s->lat_rad)) <= 256 * EPS,
          "%s: kept sin/cos of the latitude (%.3g, %.3g)", what, s->sin_lat - sin(s->lat_rad),
          s->cos_lat - cos(s->lat_rad));
    CHECK(fabs(s->R_M_m - RM) <= 1e-9 * RM, "%s: kept R_M (%.3g m)", what, s->R_M_m - RM);
}

static gf_sins_config make_cfg(int input, int coning, int vertical, double hold_h)
{
    gf_sins_config c;
    gf_sins_config_default(&c);
    c.input = input;
    c.coning = coning;
    c.vertical = vertical;
    c.hold_height_m = hold_h;
    return c;
}

/* ======================================================================================
 * Earth model
 * ==================================================================================== */

static void test_earth_published_values(void)
{
    /* the core's constants are the published WGS-84 ones */
    CHECK(GF_WGS84_A_M == REF_A && GF_WGS84_INV_F == REF_INV_F &&
              GF_WGS84_OMEGA_IE_RAD_S == REF_W_IE && GF_WGS84_GM_M3_S2 == REF_GM &&
              GF_WGS84_GAMMA_E_M_S2 == REF_GAMMA_E && GF_WGS84_K_SOMIGLIANA == REF_K,
          "WGS-84 constants of gf_earth.h are the published ones");

    /* equator: sin L = 0 and h = 0 make every factor exactly 1 -> exactly gamma_e */
    CHECK(grav(0.0, 0.0) == 9.7803253359, "gravity at the equator = 9.7803253359 (got %.17g)",
          grav(0.0, 0.0));
    /* pole (sin(pi/2) rounds to exactly 1): published 9.8321849378. TR8350.2 gives k and
     * gamma_p to 11-12 digits; k-form and gamma_p disagree by 5.9e-11 (computed in 40
     * digits), so 1e-10 is the resolution of the published values. */
    CHECK_CLOSE(grav(0.5 * PI, 0.0), 9.8321849378, 1e-10, "gravity at the pole");

    gf_earth e;
    CHECK(gf_earth_update(&e, 0.0, 0.0, NULL, 1.0) == GF_OK, "earth at the equator");
    /* sin 0 = 0 -> the radius expressions are exact except a (1 - e^2) (two roundings) */
    CHECK(e.R_N_m == 6378137.0, "R_N(0) = a exactly (got %.17g)", e.R_N_m);
    CHECK_CLOSE(e.R_M_m, REF_A * (1.0 - ref_e2()), 4 * EPS * REF_A, "R_M(0) = a (1 - e^2)");
    CHECK(e.gravity_m_s2 == 9.7803253359, "gf_earth_update gravity at the equator");
    /* pi/2 - 1e-9: sin^2 = 1 - 1e-18 rounds to 1, so the polar radii are exact values;
     * both are a / sqrt(1 - e^2) within a few roundings (4 eps relative) */
    const double lat_p = 0.5 * PI - 1e-9, Rp = REF_A / sqrt(1.0 - ref_e2());
    CHECK(gf_earth_update(&e, lat_p, 0.0, NULL, 1.0) == GF_OK, "earth next to the pole");
    CHECK_CLOSE(e.R_N_m, Rp, 4 * EPS * Rp, "R_N(90 deg) = a / sqrt(1 - e^2)");
    CHECK_CLOSE(e.R_M_m, Rp, 4 * EPS * Rp, "R_M(90 deg) = a / sqrt(1 - e^2)");
    CHECK_CLOSE(e.R_M_m, 6399593.6258, 1e-4, "polar radius of curvature (TR8350.2 table 3.3: c = 6399593.6258 m)");

    /* free-air gradient at the equator over the first metre: -2 gamma_e (1 + f + m) / a
     * + 3 gamma_e / a^2 = -3.0876899161e-6 s^-2 (40-digit arithmetic); the difference of
     * two values near 9.78 carries ~2 ulp = 4e-15 of round-off */
    const double grad = grav(0.0, 1.0) - grav(0.0, 0.0);
    CHECK_CLOSE(grad, -3.0876899161e-6, 1e-14, "free-air gradient at the equator");
}

static void test_earth_against_reference(void)
{
    test_rng rng = {0x5EED0001ULL};
    double max_rel_g = 0.0, max_rel_R = 0.0, max_ab = 0.0;
    for (int n = 0; n < 2000; ++n) {
        const double lat = test_rng_uniform(&rng, -0.5 * PI + 1e-6, 0.5 * PI - 1e-6);
        const double h = test_rng_uniform(&rng, -500.0, 20000.0);
        double v[3];
        for (int k = 0; k < 3; ++k)
            v[k] = test_rng_uniform(&rng, -300.0, 300.0);
        const double sign = (n & 1) ? -1.0 : 1.0;
        gf_earth e;
        CHECK(gf_earth_update(&e, lat, h, v, sign) == GF_OK, "gf_earth_update at lat %g h %g", lat, h);
        double RM, RN;
        ref_radii(lat, &RM, &RN);
        const double g = ref_gravity(lat, h);
        /* a handful of roundings each (sqrt, divisions, sin): 8 eps relative */
        CHECK(fabs(e.R_M_m - RM) <= 8 * EPS * RM, "R_M %.17g vs %.17g", e.R_M_m, RM);
        CHECK(fabs(e.R_N_m - RN) <= 8 * EPS * RN, "R_N %.17g vs %.17g", e.R_N_m, RN);
        CHECK(fabs(e.gravity_m_s2 - g) <= 8 * EPS * g, "gravity %.17g vs %.17g", e.gravity_m_s2, g);
        max_rel_R = fmax(max_rel_R, fmax(fabs(e.R_M_m - RM) / RM, fabs(e.R_N_m - RN) / RN));
        max_rel_g = fmax(max_rel_g, fabs(e.gravity_m_s2 - g) / g);
        /* the original a/b form of Somigliana with gamma_p (no k): the published k and
         * gamma_p agree to 6e-11 m/s^2 (see the pole check) */
        const double g0 = grav(lat, 0.0);
        CHECK_CLOSE(g0, ref_gravity_ab(lat), 1e-10, "gravity on the ellipsoid = a/b Somigliana");
        max_ab = fmax(max_ab, fabs(g0 - ref_gravity_ab(lat)));
        /* one gravity expression for every entry (gf_earth.c): equal to the bit */
        CHECK(grav(lat, h) == e.gravity_m_s2, "gf_earth_gravity = gf_earth_update gravity (%.17g vs %.17g)",
              grav(lat, h), e.gravity_m_s2);
        /* trigonometric fields */
        CHECK(fabs(e.sin_lat - sin(lat)) <= EPS && fabs(e.cos_lat - cos(lat)) <= EPS, "sin, cos of the latitude");
        CHECK(fabs(e.tan_lat - tan(lat)) <= 4 * EPS * fabs(tan(lat)) + 1e-300, "tan of the latitude");
        /* Earth rate [0, W cos L, W sin L] times the sign: one product each */
        CHECK(e.w_ie_n_rad_s[0] == 0.0, "w_ie East = 0");
        CHECK_CLOSE(e.w_ie_n_rad_s[1], sign * REF_W_IE * cos(lat), EPS * REF_W_IE, "w_ie North");
        CHECK_CLOSE(e.w_ie_n_rad_s[2], sign * REF_W_IE * sin(lat), EPS * REF_W_IE, "w_ie Up");
        /* transport rate [-vN/(R_M+h), vE/(R_N+h), vE tan L/(R_N+h)]; independent of the
         * Earth-rate sign; relative error of a few roundings (8 eps) */
        const double wen[3] = {-v[1] / (RM + h), v[0] / (RN + h), v[0] * tan(lat) / (RN + h)};
        for (int k = 0; k < 3; ++k)
            CHECK(fabs(e.w_en_n_rad_s[k] - wen[k]) <= 8 * EPS * fabs(wen[k]) + 1e-300,
                  "transport rate [%d]: %.17g vs %.17g", k, e.w_en_n_rad_s[k], wen[k]);
        /* gf_earth_from_sincos (the mechanization's entry) = gf_earth_update, bitwise */
        gf_earth ef;
        gf_earth_from_sincos(&ef, sin(lat), cos(lat), h, v, sign);
        CHECK(memcmp(&ef, &e, sizeof e) == 0, "gf_earth_from_sincos = gf_earth_update");
        /* v = NULL: no transport rate */
        gf_earth e0;
        CHECK(gf_earth_update(&e0, lat, h, NULL, sign) == GF_OK &&
                  e0.w_en_n_rad_s[0] == 0.0 && e0.w_en_n_rad_s[1] == 0.0 && e0.w_en_n_rad_s[2] == 0.0,
              "v NULL: zero transport rate");
    }
    printf("earth model: max relative error radii %.3g, gravity %.3g; |k form - a/b form| max %.3g m/s^2\n",
           max_rel_R, max_rel_g, max_ab);

    /* batch = single calls, bitwise */
    enum { NB = 7 };
    const double lat[NB] = {0.0, 0.3, -0.7, 1.2, -1.5, 0.5 * PI - 1e-9, 45 * DEG};
    const double h[NB] = {0.0, 100.0, -50.0, 1000.0, 5000.0, 0.0, 20000.0};
    double RM[NB], RN[NB], g[NB];
    size_t done = 99;
    CHECK(gf_earth_batch(NB, lat, h, RM, RN, g, &done) == GF_OK && done == NB, "earth batch");
    for (int k = 0; k < NB; ++k) {
        gf_earth e;
        gf_earth_update(&e, lat[k], h[k], NULL, 1.0);
        CHECK(RM[k] == e.R_M_m && RN[k] == e.R_N_m && g[k] == e.gravity_m_s2, "batch row %d = single", k);
    }
}

static void test_earth_errors(void)
{
    gf_earth e;
    const double v[3] = {1, 2, 3}, vnan[3] = {1, NAN, 3};
    CHECK(gf_earth_update(NULL, 0.1, 0.0, v, 1.0) == GF_ERR_NULL_POINTER, "NULL earth");
    CHECK(gf_earth_update(&e, NAN, 0.0, v, 1.0) == GF_ERR_NONFINITE_INPUT, "NaN latitude");
    CHECK(gf_earth_update(&e, 0.1, INFINITY, v, 1.0) == GF_ERR_NONFINITE_INPUT, "Inf height");
    CHECK(gf_earth_update(&e, 0.1, 0.0, vnan, 1.0) == GF_ERR_NONFINITE_INPUT, "NaN velocity");
    CHECK(gf_earth_update(&e, 0.1, 0.0, v, NAN) == GF_ERR_NONFINITE_INPUT, "NaN Earth-rate sign");
    CHECK(gf_earth_update(&e, 0.5 * PI, 0.0, v, 1.0) == GF_ERR_BAD_PARAMETER, "latitude 90 deg");
    CHECK(gf_earth_update(&e, -0.5 * PI, 0.0, v, 1.0) == GF_ERR_BAD_PARAMETER, "latitude -90 deg");
    CHECK(gf_earth_update(&e, 100 * DEG, 0.0, v, 1.0) == GF_ERR_BAD_PARAMETER, "latitude 100 deg");
    CHECK(gf_earth_update(&e, nextafter(0.5 * PI, 0.0), 0.0, v, 1.0) == GF_OK,
          "largest latitude below 90 deg accepted");
    CHECK(gf_earth_update(&e, 0.1, -0.6 * REF_A, v, 1.0) == GF_ERR_BAD_PARAMETER, "height below -a/2");
    CHECK(gf_earth_update(&e, 0.1, -0.4 * REF_A, v, 1.0) == GF_OK, "height above -a/2");
    /* on an error the output is left untouched (gf_status.h) */
    gf_earth before, after;
    memset(&before, 0x5A, sizeof before);
    after = before;
    const int unchanged = gf_earth_update(&after, NAN, 0.0, v, 1.0) != GF_OK &&
                          gf_earth_update(&after, 0.5 * PI, 0.0, v, 1.0) != GF_OK &&
                          gf_earth_update(&after, 0.1, -0.6 * REF_A, v, 1.0) != GF_OK &&
                          gf_earth_update(&after, 0.1, 0.0, vnan, 1.0) != GF_OK;
    CHECK(unchanged && memcmp(&before, &after, sizeof before) == 0, "gf_earth_update: output untouched on errors");

    const double lat[3] = {0.1, 0.2, 0.5 * PI}, h[3] = {0, 0, 0};
    double RM[3], RN[3], g[3];
    size_t done = 99;
    CHECK(gf_earth_batch(3, lat, h, RM, RN, g, &done) == GF_ERR_BAD_PARAMETER && done == 2,
          "batch stops at the pole (row 2, done %zu)", done);
    CHECK(gf_earth_batch(3, lat, h, RM, NULL, g, &done) == GF_ERR_NULL_POINTER && done == 0,
          "batch NULL output");
    CHECK(gf_earth_batch(0, lat, h, RM, RN, g, &done) == GF_OK && done == 0, "empty batch");
}

/* ======================================================================================
 * Euler angles
 * ==================================================================================== */

static void test_euler_conventions(void)
{
    double q[4], C[3][3], r[3];
    const double front[3] = {0, 1, 0}, right[3] = {1, 0, 0};
    /* C entries are sums of two products of rounded trig values: 1e-15 (~4 eps) */
    const double e_h90[3] = {90 * DEG, 0, 0};
    gf_euler_to_quat(e_h90, q);
    ref_quat_to_dcm(q, C);
    mat_vec(C, front, r);
    CHECK(fabs(r[0] - 1) <= 1e-15 && fabs(r[1]) <= 1e-15 && fabs(r[2]) <= 1e-15,
          "heading 90 deg: front axis points East (got %g %g %g)", r[0], r[1], r[2]);
    mat_vec(C, right, r);
    CHECK(fabs(r[0]) <= 1e-15 && fabs(r[1] + 1) <= 1e-15 && fabs(r[2]) <= 1e-15,
          "heading 90 deg: right axis points South (got %g %g %g)", r[0], r[1], r[2]);
    const double e_p10[3] = {0, 10 * DEG, 0};
    gf_euler_to_quat(e_p10, q);
    ref_quat_to_dcm(q, C);
    mat_vec(C, front, r);
    CHECK_CLOSE(r[2], sin(10 * DEG), 1e-15, "pitch +10 deg: nose up");
    CHECK_CLOSE(r[1], cos(10 * DEG), 1e-15, "pitch +10 deg: nose still North");
    const double e_r10[3] = {0, 0, 10 * DEG};
    gf_euler_to_quat(e_r10, q);
    ref_quat_to_dcm(q, C);
    mat_vec(C, right, r);
    CHECK_CLOSE(r[2], -sin(10 * DEG), 1e-15, "roll +10 deg: right wing down");
    CHECK_CLOSE(r[0], cos(10 * DEG), 1e-15, "roll +10 deg: right wing still East");

    /* random angles: the quaternion equals the closed form and rotates like the
     * matrix product; the round trip returns the angles. Quaternion: sums of products
     * of rounded half-angle trig values, 4 eps. Round trip: asin and atan2 of DCM
     * entries with ~2 eps absolute error, amplified by 1/cos(theta) -> 32 eps / cos. */
    test_rng rng = {0xE0E0E0E0ULL};
    double max_rt = 0.0;
    enum { NE = 2000 };
    static double qs[NE * 4], es[NE * 3], eb[NE * 3];
    for (int n = 0; n < NE; ++n) {
        double e[3] = {test_rng_uniform(&rng, 0.0, 2 * PI), test_rng_uniform(&rng, -0.5 * PI + 1e-3, 0.5 * PI - 1e-3),
                       test_rng_uniform(&rng, -PI, PI)};
        if (e[2] == -PI)
            e[2] = PI; /* roll range (-pi, pi] */
        double qr[4], Cq[3][3], Ce[3][3];
        gf_euler_to_quat(e, q);
        ref_quat_euler(e, qr);
        for (int k = 0; k < 4; ++k)
            CHECK_CLOSE(q[k], qr[k], 4 * EPS, "gf_euler_to_quat = closed form");
        ref_quat_to_dcm(q, Cq);
        ref_dcm_euler(e, Ce);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                CHECK_CLOSE(Cq[i][j], Ce[i][j], 8 * EPS, "C(q) = Rz(-psi) Rx(theta) Ry(gamma)");
        double back[3];
        gf_quat_to_euler(q, back);
        const double tol = 32 * EPS / cos(e[1]);
        CHECK(fabs(wrap_pi(back[0] - e[0])) <= tol && fabs(back[1] - e[1]) <= tol &&
                  fabs(wrap_pi(back[2] - e[2])) <= tol,
              "round trip (%.17g %.17g %.17g) -> (%.17g %.17g %.17g)", e[0], e[1], e[2], back[0],
              back[1], back[2]);
        CHECK(back[0] >= 0.0 && back[0] < 2 * PI && back[2] > -PI && back[2] <= PI,
              "heading in [0, 2 pi), roll in (-pi, pi]");
        max_rt = fmax(max_rt, fmax(fabs(wrap_pi(back[0] - e[0])),
                                   fmax(fabs(back[1] - e[1]), fabs(wrap_pi(back[2] - e[2])))));
        memcpy(qs + 4 * n, q, sizeof q);
        memcpy(es + 3 * n, back, sizeof back);
    }
    printf("euler round trip over %d random attitudes: max error %.3g rad\n", NE, max_rt);
    CHECK(gf_quat_to_euler_batch(NE, qs, eb, NULL) == GF_OK && memcmp(es, eb, sizeof eb) == 0,
          "gf_quat_to_euler_batch = single calls, bitwise");
    CHECK(gf_quat_to_euler_batch(NE, NULL, eb, NULL) == GF_ERR_NULL_POINTER &&
              gf_quat_to_euler_batch(NE, qs, NULL, NULL) == GF_ERR_NULL_POINTER,
          "gf_quat_to_euler_batch NULL");

    /* heading wrap: -10 deg comes back as 350 deg */
    const double e_m10[3] = {-10 * DEG, 0.2, 0.1};
    double back[3];
    gf_euler_to_quat(e_m10, q);
    gf_quat_to_euler(q, back);
    CHECK_CLOSE(back[0], 350 * DEG, 64 * EPS, "heading -10 deg -> 350 deg");

    /* pitch +-90 deg: heading and roll are one angle, roll is reported 0 and the heading
     * absorbs it: psi - gamma at +90, psi + gamma at -90 (from the matrix product).
     * The pitch comes from asin of an entry 1 - O(eps): error up to sqrt(8 eps) = 4.2e-8. */
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        const double e[3] = {0.7, sgn * 0.5 * PI, 0.3};
        gf_euler_to_quat(e, q);
        gf_quat_to_euler(q, back);
        CHECK(back[2] == 0.0, "gimbal lock: roll reported 0 (got %g)", back[2]);
        CHECK_CLOSE(back[1], sgn * 0.5 * PI, 5e-8, "gimbal lock: pitch +-90");
        CHECK_CLOSE(wrap_pi(back[0] - (sgn > 0 ? 0.4 : 1.0)), 0.0, 1e-14, "gimbal lock: heading psi -+ gamma");
    }
}

/* ======================================================================================
 * Configuration and initialisation
 * ==================================================================================== */

static void test_config_and_init(void)
{
    gf_sins_config c;
    memset(&c, 0x5A, sizeof c);
    gf_sins_config_default(&c);
    CHECK(c.input == GF_SINS_INPUT_INCREMENTS && c.coning == 1 && c.vertical == GF_SINS_VERTICAL_FREE &&
              c.baro_tau_s == 10.0 && c.max_rate_rad_s == 50.0 && c.max_specific_force_m_s2 == 1000.0 &&
              c.hold_height_m == 0.0,
          "documented defaults");
    gf_sins_config_default(NULL); /* must not crash */

    const double e[3] = {200 * DEG, -5 * DEG, 12 * DEG};
    double q[4], q2[4];
    ref_quat_euler(e, q);
    for (int k = 0; k < 4; ++k)
        q2[k] = 2.5 * q[k];
    const double v[3] = {3, -4, 0.5};
    gf_sins_state s;
    CHECK(gf_sins_init(&s, &c, q2, v, 0.6, -2.0, 150.0, 12.5) == GF_OK, "init");
    /* normalised: 2.5 q / |2.5 q| rounds within 2 eps of q */
    for (int k = 0; k < 4; ++k)
        CHECK_CLOSE(s.q_bn[k], q[k], 2 * EPS, "init normalises the quaternion");
    CHECK(memcmp(s.v_n_m_s, v, sizeof v) == 0 && s.lat_rad == 0.6 && s.lon_rad == -2.0 && s.h_m == 150.0 &&
              s.time_s == 12.5 && s.earth_rate_sign == 1.0 && s.have_prev == 0 && s.n_samples == 0 &&
              s.baro_accel_m_s2 == 0.0 && s.a_n_m_s2[0] == 0.0 && s.a_n_m_s2[1] == 0.0 &&
              s.a_n_m_s2[2] == 0.0,
          "init stores the state");
    check_kept_trig(&s, "init");
    CHECK(s.cfg.input == c.input && s.cfg.coning == c.coning && s.cfg.vertical == c.vertical,
          "init copies the configuration");

    /* HOLD: the height is the hold height and the vertical velocity 0 from the start */
    gf_sins_config ch = make_cfg(GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_HOLD, 250.0);
    CHECK(gf_sins_init(&s, &ch, q, v, 0.6, -2.0, 150.0, 0.0) == GF_OK && s.h_m == 250.0 &&
              s.v_n_m_s[2] == 0.0 && s.v_n_m_s[0] == 3.0 && s.v_n_m_s[1] == -4.0,
          "HOLD init: h = hold height, v_U = 0");

    /* errors leave the state untouched, byte for byte */
    gf_sins_state ref;
    memset(&s, 0xA5, sizeof s);
    memcpy(&ref, &s, sizeof s);
    const double qzero[4] = {0, 0, 0, 0}, qnan[4] = {NAN, 0, 0, 1}, vnan[3] = {0, NAN, 0};
#define INIT_FAILS(expr, code, what)                                                            \
    do {                                                                                       \
        const gf_status st_ = (expr);                                                          \
        CHECK(st_ == (code), "%s: status %d, expected %d", (what), (int)st_, (int)(code));     \
        CHECK(memcmp(&s, &ref, sizeof s) == 0, "%s: state unchanged", (what));                 \
    } while (0)
    INIT_FAILS(gf_sins_init(NULL, &c, q, v, 0.6, 0, 0, 0), GF_ERR_NULL_POINTER, "init NULL state");
    INIT_FAILS(gf_sins_init(&s, NULL, q, v, 0.6, 0, 0, 0), GF_ERR_NULL_POINTER, "init NULL cfg");
    INIT_FAILS(gf_sins_init(&s, &c, NULL, v, 0.6, 0, 0, 0), GF_ERR_NULL_POINTER, "init NULL q");
    INIT_FAILS(gf_sins_init(&s, &c, q, NULL, 0.6, 0, 0, 0), GF_ERR_NULL_POINTER, "init NULL v");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, 0.5 * PI, 0, 0, 0), GF_ERR_BAD_PARAMETER, "init lat 90 deg");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, -0.5 * PI, 0, 0, 0), GF_ERR_BAD_PARAMETER, "init lat -90 deg");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, 91 * DEG, 0, 0, 0), GF_ERR_BAD_PARAMETER, "init lat 91 deg");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, -3.0, 0, 0, 0), GF_ERR_BAD_PARAMETER, "init lat -172 deg");
    INIT_FAILS(gf_sins_init(&s, &c, qzero, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "init zero quaternion");
    INIT_FAILS(gf_sins_init(&s, &c, qnan, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "init NaN quaternion");
    INIT_FAILS(gf_sins_init(&s, &c, q, vnan, 0.6, 0, 0, 0), GF_ERR_NONFINITE_INPUT, "init NaN velocity");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, NAN, 0, 0, 0), GF_ERR_NONFINITE_INPUT, "init NaN latitude");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, 0.6, INFINITY, 0, 0), GF_ERR_NONFINITE_INPUT, "init Inf longitude");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, 0.6, 0, NAN, 0), GF_ERR_NONFINITE_INPUT, "init NaN height");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, 0.6, 0, 0, NAN), GF_ERR_NONFINITE_INPUT, "init NaN time");
    INIT_FAILS(gf_sins_init(&s, &c, q, v, 0.6, 0, -0.6 * REF_A, 0), GF_ERR_BAD_PARAMETER, "init height below -a/2");
    gf_sins_config bad = c;
    bad.input = 5;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config input 5");
    bad = c;
    bad.coning = 2;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config coning 2");
    bad = c;
    bad.vertical = 7;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config vertical 7");
    bad.vertical = -1;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config vertical -1");
    bad = c;
    bad.baro_tau_s = 0.0;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config baro_tau 0");
    bad.baro_tau_s = NAN;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config baro_tau NaN");
    bad = c;
    bad.max_rate_rad_s = 0.0;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config max rate 0");
    bad = c;
    bad.max_specific_force_m_s2 = -1.0;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config max force < 0");
    bad = c;
    bad.hold_height_m = NAN;
    INIT_FAILS(gf_sins_init(&s, &bad, q, v, 0.6, 0, 0, 0), GF_ERR_BAD_PARAMETER, "config hold height NaN");
#undef INIT_FAILS
}

/* ======================================================================================
 * Stationary on the Earth: nothing may move
 * ==================================================================================== */

typedef struct {
    const char *name;
    int input, coning, vertical;
    double lat_deg, lon_deg, h_m;
    double euler_deg[3];
    double seconds;
} stationary_case;

static void run_stationary(const stationary_case *c)
{
    enum { CHUNK = 6000 };
    static double gy[CHUNK * 3], ac[CHUNK * 3], qo[CHUNK * 4], vo[CHUNK * 3], po[CHUNK * 3], to[CHUNK];
    const double T = 0.01, t0 = 1000.0;
    const double L = c->lat_deg * DEG, lon = c->lon_deg * DEG, h = c->h_m;
    const double e[3] = {c->euler_deg[0] * DEG, c->euler_deg[1] * DEG, c->euler_deg[2] * DEG};
    double C[3][3], q_true[4];
    ref_dcm_euler(e, C);
    ref_quat_euler(e, q_true);
    const double w_n[3] = {0.0, REF_W_IE * cos(L), REF_W_IE * sin(L)};
    const double f_n[3] = {0.0, 0.0, ref_gravity(L, h)};
    double w_b[3], f_b[3];
    mat_t_vec(C, w_n, w_b); /* C_n^b = (C_b^n)^T */
    mat_t_vec(C, f_n, f_b);
    const int rates = c->input == GF_SINS_INPUT_RATES;
    for (int k = 0; k < CHUNK; ++k)
        for (int i = 0; i < 3; ++i) {
            gy[3 * k + i] = rates ? w_b[i] : T * w_b[i];
            ac[3 * k + i] = rates ? f_b[i] : T * f_b[i];
        }
    const gf_sins_config cfg = make_cfg(c->input, c->coning, c->vertical, h);
    gf_sins_state s;
    const double v0[3] = {0, 0, 0};
    CHECK(gf_sins_init(&s, &cfg, q_true, v0, L, lon, h, t0) == GF_OK, "%s: init", c->name);

    /* n intervals; a rate record needs one more sample to start it */
    const size_t n_int = (size_t)(c->seconds / T + 0.5), n_samp = n_int + (rates ? 1 : 0);
    double max_lat = 0, max_lon = 0, max_vh = 0, max_vu = 0, max_h = 0, max_att = 0, max_t = 0;
    int hold_exact = 1, all_ok = 1;
    for (size_t k0 = 0; k0 < n_samp; k0 += CHUNK) {
        const size_t m = n_samp - k0 < CHUNK ? n_samp - k0 : CHUNK;
        size_t done = 0;
        const gf_status st = gf_sins_run(&s, m, gy, ac, T, NULL, NULL, 0, qo, vo, po, to, &done);
        if (st != GF_OK || done != m) {
            all_ok = 0;
            break;
        }
        for (size_t j = 0; j < m; ++j) {
            const size_t k = k0 + j;
            const double n_k = (double)(rates ? k : k + 1); /* intervals done after sample k */
            max_lat = fmax(max_lat, fabs(po[3 * j] - L));
            max_lon = fmax(max_lon, fabs(po[3 * j + 1] - lon));
            max_h = fmax(max_h, fabs(po[3 * j + 2] - h));
            max_vh = fmax(max_vh, hypot(vo[3 * j], vo[3 * j + 1]));
            max_vu = fmax(max_vu, fabs(vo[3 * j + 2]));
            max_att = fmax(max_att, quat_angle(qo + 4 * j, q_true));
            max_t = fmax(max_t, fabs(to[j] - (t0 + n_k * T)));
            if (c->vertical == GF_SINS_VERTICAL_HOLD)
                hold_exact &= po[3 * j + 2] == h && vo[3 * j + 2] == 0.0;
        }
    }
    CHECK(all_ok, "%s: run without error", c->name);
    CHECK(s.n_samples == n_samp, "%s: %zu samples counted (got %llu)", c->name, n_samp,
          (unsigned long long)s.n_samples);
    printf("stationary %-34s %6.0f s: |dlat| %.2g rad, |dlon| %.2g rad, |v_h| %.2g m/s, attitude %.2g rad, "
           "|dh| %.2g m, |v_U| %.2g m/s, time %.2g s\n",
           c->name, c->seconds, max_lat, max_lon, max_vh, max_att, max_h, max_vu, max_t);
    /* Exact arithmetic would leave everything fixed up to the truncation of the
     * (I - [zeta x]/2) rotation compensation, (W T)^2 g T / 4 ~ 8e-15 m/s per step, an
     * 8e-13 m/s^2 bias whose horizontal effect the Schuler loop bounds (1e-9 m/s).
     * What remains is double round-off, and with constant inputs every step rounds
     * (almost) the same way, so it accumulates coherently, not as a random walk:
     * measured ~0.36 eps per step in attitude (the same runs with the quaternion
     * products in long double stay below 1e-16 rad: it is round-off, not truncation).
     * Attitude bound 1e-10 rad = 1.25 eps per step over 360000 steps. A coherent
     * attitude drift eps_r acts like a gyro drift: the tilt stays Schuler-bounded, the
     * velocity reaches R eps_r (1 - cos w_s t) <= 2 R eps_r = 3.6e-7 m/s, the position
     * grows like eps_r t (rad), as large as the unbounded attitude accumulation: bounds
     * 1e-6 m/s and 2e-10 rad (1.3 mm; 1e-12 rad, 6 um, is below what double-precision
     * round-off allows for a general attitude). */
    CHECK(max_lat <= 2e-10, "%s: latitude fixed (|dlat| %.3g rad)", c->name, max_lat);
    CHECK(max_lon <= 2e-10, "%s: longitude fixed (|dlon| %.3g rad)", c->name, max_lon);
    CHECK(max_vh <= 1e-6, "%s: horizontal velocity 0 (%.3g m/s)", c->name, max_vh);
    CHECK(max_att <= 1e-10, "%s: attitude fixed (%.3g rad)", c->name, max_att);
    /* time: n additions of T, each rounding by at most ulp(t)/2 */
    CHECK(max_t <= (double)n_int * 0.5 * ulp(t0 + c->seconds) + 1e-12, "%s: time (%.3g s)", c->name, max_t);
    if (c->vertical == GF_SINS_VERTICAL_HOLD) {
        CHECK(hold_exact, "%s: HOLD keeps h = hold height and v_U = 0 exactly", c->name);
    } else {
        /* the free channel amplifies a bias b as b tau^2 (cosh(t/tau) - 1), tau = 570 s:
         * 3e5 s^2 x 275 at 1 h. The 8e-13 m/s^2 truncation bias and gravity round-off
         * (~1e-15 m/s^2) give ~1e-4 m; 1e-3 m leaves a factor 10. */
        CHECK(max_h <= 1e-3, "%s: free vertical channel drift %.3g m", c->name, max_h);
        CHECK(max_vu <= 1e-5, "%s: free vertical channel velocity %.3g m/s", c->name, max_vu);
    }
}

static void test_stationary(void)
{
    /* 1 h at 100 Hz: ~0.1 s per case plain, ~0.5 s under the sanitizers */
    const double sec = 3600.0;
    const stationary_case cases[] = {
        {"increments, coning, free", GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_FREE, 37.5, -122.1, 250.0,
         {123.0, 4.0, -7.0}, sec},
        {"increments, coning, hold", GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_HOLD, -62.0, 170.0, 1800.0,
         {300.0, -60.0, 150.0}, sec},
        {"rates, coning, free", GF_SINS_INPUT_RATES, 1, GF_SINS_VERTICAL_FREE, 12.0, 45.0, -30.0,
         {10.0, 30.0, -100.0}, sec},
        {"rates, one-sample, hold", GF_SINS_INPUT_RATES, 0, GF_SINS_VERTICAL_HOLD, 80.0, -179.9, 0.0,
         {0.0, 0.0, 0.0}, sec},
        {"increments, one-sample, free", GF_SINS_INPUT_INCREMENTS, 0, GF_SINS_VERTICAL_FREE, 0.0, 0.0, 10.0,
         {45.0, 89.0, 45.0}, 600.0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i)
        run_stationary(&cases[i]);
}

/* ======================================================================================
 * Constant velocity along a parallel: Coriolis, transport rate, radii
 * ==================================================================================== */

/* v^n = [vE, 0, 0] constant at latitude L and height h: vN = 0 keeps L, the longitude
 * grows at vE / ((R_N + h) cos L). With w_in = w_ie + w_en, w_en = [0, vE/(R_N+h),
 * vE tan L/(R_N+h)] and v' = 0 in ENU, the specific force is
 *   f^n = (2 w_ie + w_en) x v - g^n = [0, r vE, g - p vE],
 *   p = 2 W cos L + vE/(R_N+h),  r = 2 W sin L + vE tan L/(R_N+h);
 * with a fixed attitude relative to ENU the body rate is C_n^b w_in. Both constant:
 * exact constant increments, as in the stationary case. */
typedef struct {
    const char *name;
    int input, vertical;
    double lat_deg, lon_deg, h_m, vE;
    double euler_deg[3];
} parallel_case;

static void run_parallel(const parallel_case *c)
{
    enum { CHUNK = 6000 };
    static double gy[CHUNK * 3], ac[CHUNK * 3], qo[CHUNK * 4], vo[CHUNK * 3], po[CHUNK * 3];
    const double T = 0.01, seconds = 3600.0, L = c->lat_deg * DEG, lon0 = c->lon_deg * DEG, h = c->h_m;
    const double vE = c->vE;
    const double e[3] = {c->euler_deg[0] * DEG, c->euler_deg[1] * DEG, c->euler_deg[2] * DEG};
    double C[3][3], q_true[4], RM, RN;
    ref_dcm_euler(e, C);
    ref_quat_euler(e, q_true);
    ref_radii(L, &RM, &RN);
    const double w_in[3] = {0.0, REF_W_IE * cos(L) + vE / (RN + h), REF_W_IE * sin(L) + vE * tan(L) / (RN + h)};
    const double p = 2 * REF_W_IE * cos(L) + vE / (RN + h), r = 2 * REF_W_IE * sin(L) + vE * tan(L) / (RN + h);
    const double f_n[3] = {0.0, r * vE, ref_gravity(L, h) - p * vE};
    double w_b[3], f_b[3];
    mat_t_vec(C, w_in, w_b);
    mat_t_vec(C, f_n, f_b);
    const int rates = c->input == GF_SINS_INPUT_RATES;
    for (int k = 0; k < CHUNK; ++k)
        for (int i = 0; i < 3; ++i) {
            gy[3 * k + i] = rates ? w_b[i] : T * w_b[i];
            ac[3 * k + i] = rates ? f_b[i] : T * f_b[i];
        }
    const gf_sins_config cfg = make_cfg(c->input, 1, c->vertical, h);
    const double v0[3] = {vE, 0.0, 0.0};
    gf_sins_state s;
    CHECK(gf_sins_init(&s, &cfg, q_true, v0, L, lon0, h, 0.0) == GF_OK, "%s: init", c->name);
    const size_t n_int = (size_t)(seconds / T + 0.5), n_samp = n_int + (rates ? 1 : 0);
    const double lon_rate = vE / ((RN + h) * cos(L));
    double max_lat = 0, max_lon = 0, max_v = 0, max_h = 0, max_att = 0;
    int all_ok = 1, lon_in_range = 1;
    for (size_t k0 = 0; k0 < n_samp; k0 += CHUNK) {
        const size_t m = n_samp - k0 < CHUNK ? n_samp - k0 : CHUNK;
        size_t done = 0;
        if (gf_sins_run(&s, m, gy, ac, T, NULL, NULL, 0, qo, vo, po, NULL, &done) != GF_OK || done != m) {
            all_ok = 0;
            break;
        }
        for (size_t j = 0; j < m; ++j) {
            const double t = (double)(rates ? k0 + j : k0 + j + 1) * T;
            max_lat = fmax(max_lat, fabs(po[3 * j] - L));
            max_lon = fmax(max_lon, fabs(wrap_pi(po[3 * j + 1] - (lon0 + lon_rate * t))));
            lon_in_range &= po[3 * j + 1] > -PI && po[3 * j + 1] <= PI;
            max_h = fmax(max_h, fabs(po[3 * j + 2] - h));
            max_v = fmax(max_v, sqrt((vo[3 * j] - vE) * (vo[3 * j] - vE) + vo[3 * j + 1] * vo[3 * j + 1] +
                                     vo[3 * j + 2] * vo[3 * j + 2]));
            max_att = fmax(max_att, quat_angle(qo + 4 * j, q_true));
        }
    }
    CHECK(all_ok, "%s: run without error", c->name);
    printf("parallel %-30s 3600 s (%.0f km): |dlat| %.2g rad, |dlon| %.2g rad, |dv| %.2g m/s, attitude %.2g rad, "
           "|dh| %.2g m\n",
           c->name, fabs(vE) * seconds / 1000.0, max_lat, max_lon, max_v, max_att, max_h);
    /* As the stationary case (exact constant increments; the rotation compensation
     * truncation (|w_in| T)^2 |f| T / 4 is ~1e-15 m/s per step): double round-off
     * accumulating coherently, bounded as there (1e-10 rad attitude, 2e-10 rad
     * position, 1e-6 m/s). The longitude also gathers the rounding of lon += dlon
     * (<= ulp(pi)/2 per step, 8e-11 rad over 360000 steps): 3e-10 rad. A wrong Coriolis
     * (2 W sin L vE ~ 1e-2 m/s^2 North), transport rate or radius would be off by
     * orders of magnitude. */
    CHECK(lon_in_range, "%s: longitude wrapped into (-pi, pi]", c->name);
    check_kept_trig(&s, c->name);
    CHECK(max_lat <= 2e-10, "%s: latitude kept (%.3g rad)", c->name, max_lat);
    CHECK(max_lon <= 3e-10, "%s: longitude = lon0 + vE t / ((R_N + h) cos L) (%.3g rad)", c->name, max_lon);
    CHECK(max_v <= 1e-6, "%s: velocity kept (%.3g m/s)", c->name, max_v);
    CHECK(max_att <= 1e-10, "%s: attitude kept (%.3g rad)", c->name, max_att);
    if (c->vertical == GF_SINS_VERTICAL_FREE)
        CHECK(max_h <= 1e-3, "%s: free vertical channel (%.3g m; bound as stationary)", c->name, max_h);
    else
        CHECK(max_h == 0.0, "%s: HOLD height exact", c->name);
}

static void test_parallel(void)
{
    /* the second and third cases cross the 180 deg meridian (longitude wraps) */
    const parallel_case cases[] = {
        {"east 200 m/s, increments, free", GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_FREE, 50.0, 10.0, 3000.0, 200.0,
         {90.0, 3.0, -2.0}},
        {"west 150 m/s, rates, hold", GF_SINS_INPUT_RATES, GF_SINS_VERTICAL_HOLD, -35.0, -177.0, 500.0, -150.0,
         {270.0, -1.0, 5.0}},
        {"east 250 m/s at 80 deg, increments", GF_SINS_INPUT_INCREMENTS, GF_SINS_VERTICAL_HOLD, 80.0, 170.0, 10000.0,
         250.0, {75.0, 0.0, 0.0}},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i)
        run_parallel(&cases[i]);
}

/* ======================================================================================
 * Stationary, level, spinning about the body up axis at omega
 * ==================================================================================== */

static void test_spin_about_up(int input)
{
    enum { N = 60000 }; /* 10 min at 100 Hz */
    static double gy[(N + 1) * 3], ac[(N + 1) * 3], qo[(N + 1) * 4], vo[(N + 1) * 3], po[(N + 1) * 3];
    const double T = 0.01, L = 50 * DEG, lon = 0.3, h = 400.0, psi0 = 30 * DEG, om = 0.2;
    const double a = REF_W_IE * cos(L), b = REF_W_IE * sin(L) + om, g = ref_gravity(L, h);
    const int rates = input == GF_SINS_INPUT_RATES;
    /* C_b^n = Rz(-psi), psi(t) = psi0 - om t (a positive rate about body up turns the
     * nose left), so w_ib^b = Rz(psi) w_ie^n + [0, 0, om] = [-a sin psi, a cos psi, b],
     * f^b = [0, 0, g]. Increments: integrals of sin(psi0 - om t) and cos(psi0 - om t). */
    const size_t n = rates ? N + 1 : N;
    for (size_t k = 0; k < n; ++k) {
        if (rates) {
            const double p = psi0 - om * (double)k * T;
            gy[3 * k] = -a * sin(p);
            gy[3 * k + 1] = a * cos(p);
            gy[3 * k + 2] = b;
            ac[3 * k] = ac[3 * k + 1] = 0.0;
            ac[3 * k + 2] = g;
        } else {
            const double p0 = psi0 - om * (double)k * T, p1 = psi0 - om * (double)(k + 1) * T;
            gy[3 * k] = -a * (cos(p1) - cos(p0)) / om;
            gy[3 * k + 1] = -a * (sin(p1) - sin(p0)) / om;
            gy[3 * k + 2] = b * T;
            ac[3 * k] = ac[3 * k + 1] = 0.0;
            ac[3 * k + 2] = g * T;
        }
    }
    const gf_sins_config cfg = make_cfg(input, 1, GF_SINS_VERTICAL_HOLD, h);
    const double e0[3] = {psi0, 0, 0}, v0[3] = {0, 0, 0};
    double q0[4];
    ref_quat_euler(e0, q0);
    gf_sins_state s;
    gf_sins_init(&s, &cfg, q0, v0, L, lon, h, 0.0);
    size_t done = 0;
    CHECK(gf_sins_run(&s, n, gy, ac, T, NULL, NULL, 0, qo, vo, po, NULL, &done) == GF_OK && done == n,
          "spin: run");
    double max_att = 0, max_pos = 0, max_v = 0;
    for (size_t k = 0; k < n; ++k) {
        const double t = (double)(rates ? k : k + 1) * T;
        const double e[3] = {psi0 - om * t, 0, 0};
        double qt[4];
        ref_quat_euler(e, qt);
        max_att = fmax(max_att, quat_angle(qo + 4 * k, qt));
        max_pos = fmax(max_pos, fmax(fabs(po[3 * k] - L), fabs(po[3 * k + 1] - lon)));
        max_v = fmax(max_v, hypot(vo[3 * k], vo[3 * k + 1]));
    }
    printf("spin about up at %.1f rad/s, %s, 600 s: attitude %.2g rad, position %.2g rad, |v_h| %.2g m/s\n", om,
           rates ? "rates" : "increments", max_att, max_pos, max_v);
    /* Expected truncation (second-order algorithm; checked in 40-digit arithmetic and
     * by the T^2 scaling of the measured errors):
     *  - velocity: dv + dtheta x dv / 2 + sculling drops the second-order rotation
     *    term (1/2) int alpha x (alpha x f): with f = g up and alpha = horizontal (a)
     *    plus vertical (b) parts it leaves a North bias a_v = a b g T^2 / 6
     *    (1.5e-9 m/s^2 here); through the transport rate it tilts the platform by
     *    ~ a_v t^2 / (2 R) and moves it by as much (rad); the velocity error is a_v t;
     *  - attitude, increments: the two-sample coning residual, 1.6e-14 rad/s here
     *    (O(T^3)), below 1e-11 rad over the record;
     *  - attitude, rates: the trapezoid of the rotating horizontal Earth-rate
     *    component is short by a (om T)^2 / 12 rad/s (r = 1.6e-11 rad/s), fixed in the
     *    navigation frame: a gyro-drift-like error, tilt (r / w_s) sin(w_s t) <= r t,
     *    position <= r (t - sin(w_s t) / w_s), velocity R r (1 - cos w_s t).
     * Bounds: twice the predicted values plus 1e-11 rad / 1e-8 m/s of round-off. */
    const double t_end = 600.0, R = 6.371e6, ws = sqrt(g / R);
    const double a_v = a * b * g * T * T / 6.0, r = rates ? a * om * om * T * T / 12.0 : 0.0;
    const double att_pred = a_v * t_end * t_end / (2 * R) + r * t_end;
    const double pos_pred = a_v * t_end * t_end / (2 * R) + r * (t_end - sin(ws * t_end) / ws);
    const double v_pred = a_v * t_end + R * r * (1.0 - cos(ws * t_end));
    CHECK(max_att <= 2 * att_pred + 1e-11, "spin: heading psi0 - omega t (%.3g rad, predicted %.3g)", max_att,
          att_pred);
    CHECK(max_pos <= 2 * pos_pred + 1e-11, "spin: position fixed (%.3g rad, predicted %.3g)", max_pos, pos_pred);
    CHECK(max_v <= 2 * v_pred + 1e-8, "spin: velocity 0 (%.3g m/s, predicted %.3g)", max_v, v_pred);
}

/* ======================================================================================
 * Stationary, spinning about a tilted body axis: the sculling terms at work
 * ==================================================================================== */

static void qmul(const double p[4], const double q[4], double o[4])
{
    const double w = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3];
    const double x = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2];
    const double y = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1];
    const double z = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0];
    o[0] = w, o[1] = x, o[2] = y, o[3] = z;
}

static void cross3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

/* integral over [t0, t1] of R_u(-om t) y, R_u = rotation about the unit axis u:
 * R_u(-th) y = y_par + cos(th) y_perp - sin(th) (u x y); differences of sin and cos in
 * product form (no cancellation) */
static void rot_integral(const double u[3], const double y[3], double om, double t0, double t1, double out[3])
{
    const double uy = u[0] * y[0] + u[1] * y[1] + u[2] * y[2];
    double uxy[3];
    cross3(u, y, uxy);
    const double m = 0.5 * om * (t0 + t1), hh = 0.5 * om * (t1 - t0);
    const double dsin = 2.0 * cos(m) * sin(hh), dcos = -2.0 * sin(m) * sin(hh);
    for (int i = 0; i < 3; ++i) {
        const double par = uy * u[i], perp = y[i] - par;
        out[i] = par * (t1 - t0) + perp * dsin / om + uxy[i] * dcos / om;
    }
}

static void rot_apply(const double u[3], const double y[3], double th, double out[3])
{
    const double uy = u[0] * y[0] + u[1] * y[1] + u[2] * y[2];
    double uxy[3];
    cross3(u, y, uxy);
    for (int i = 0; i < 3; ++i) {
        const double par = uy * u[i];
        out[i] = par + cos(th) * (y[i] - par) - sin(th) * uxy[i];
    }
}

/* C_b^n(t) = A R_u(om t): the body turns at om about its own axis u, which stays fixed
 * in ENU (u^n = A u). f^b(t) = R_u(-om t) A^T [0, 0, g] and w_ib^b = om u + R_u(-om t)
 * A^T w_ie^n: both rotate in the body about u, so dv changes from sample to sample and
 * the sculling term matters. Truth: q(t) = q_A (x) [cos(om t/2), u sin(om t/2)],
 * position and velocity fixed. */
static void test_spin_tilted(int input)
{
    enum { N = 60000 }; /* 10 min at 100 Hz */
    static double gy[(N + 1) * 3], ac[(N + 1) * 3], qo[(N + 1) * 4], vo[(N + 1) * 3], po[(N + 1) * 3];
    const double T = 0.01, L = -25 * DEG, lon = 2.0, h = 50.0, om = 0.2;
    const double eA[3] = {30 * DEG, 20 * DEG, -10 * DEG};
    const double un = sqrt(0.4 * 0.4 + 0.3 * 0.3 + 1.0), u[3] = {0.4 / un, -0.3 / un, 1.0 / un};
    const int rates = input == GF_SINS_INPUT_RATES;
    double A[3][3], qA[4];
    ref_dcm_euler(eA, A);
    ref_quat_euler(eA, qA);
    const double g = ref_gravity(L, h);
    const double w_n[3] = {0.0, REF_W_IE * cos(L), REF_W_IE * sin(L)}, f_n[3] = {0.0, 0.0, g};
    double w0[3], f0[3];
    mat_t_vec(A, w_n, w0);
    mat_t_vec(A, f_n, f0);
    const size_t n = rates ? N + 1 : N;
    for (size_t k = 0; k < n; ++k) {
        double wr[3], fr[3];
        if (rates) {
            rot_apply(u, w0, om * (double)k * T, wr);
            rot_apply(u, f0, om * (double)k * T, fr);
            for (int i = 0; i < 3; ++i) {
                gy[3 * k + i] = om * u[i] + wr[i];
                ac[3 * k + i] = fr[i];
            }
        } else {
            rot_integral(u, w0, om, (double)k * T, (double)(k + 1) * T, wr);
            rot_integral(u, f0, om, (double)k * T, (double)(k + 1) * T, fr);
            for (int i = 0; i < 3; ++i) {
                gy[3 * k + i] = om * u[i] * T + wr[i];
                ac[3 * k + i] = fr[i];
            }
        }
    }
    const gf_sins_config cfg = make_cfg(input, 1, GF_SINS_VERTICAL_HOLD, h);
    const double v0[3] = {0, 0, 0};
    gf_sins_state s;
    gf_sins_init(&s, &cfg, qA, v0, L, lon, h, 0.0);
    size_t done = 0;
    CHECK(gf_sins_run(&s, n, gy, ac, T, NULL, NULL, 0, qo, vo, po, NULL, &done) == GF_OK && done == n,
          "tilted spin: run");

    /* Expected truncation. With x = om T, in the plane normal to u (f_perp = the part of
     * f normal to u): dv + dtheta x dv / 2 = f0 T (1 + x^2/12), the sculling term adds
     * x^2/12 (it makes the first-order rotation term exact), and the neglected
     * second-order term (1/2) int alpha x (alpha x f) is -x^2/6: the algorithm's dv is
     * long by x^2/6 (increments). With rates sampled on the circle the trapezoid is
     * short by x^2/12, the rate sculling term adds x^2/12, the result is long by
     * x^2/12. In ENU this is a constant bias b = k (om T)^2 f_perp^n, k = 1/6 or 1/12
     * (f_perp^n = f^n - (u^n . f^n) u^n is fixed), 4e-6 m/s^2 here; its horizontal part
     * drives the Schuler loop: dv_h(t) = b_h sin(w_s t) / w_s, tilt (|b_h|/g)
     * (1 - cos w_s t), position |b_h| / w_s^2 (1 - cos w_s t). The Earth-rate terms
     * of the spin test are ~1e-3 of this; the vertical Earth rate turns the Schuler
     * plane by W |sin L| t = 1.8e-2 rad over 600 s, the radii make w_s uncertain by
     * 0.3 %: the velocity error follows the prediction within 10 % of its amplitude.
     * Without the sculling term it would be half, with its sign flipped zero. */
    const double k_sc = rates ? 1.0 / 12.0 : 1.0 / 6.0;
    double u_n[3], RM, RN;
    mat_vec(A, u, u_n);
    ref_radii(L, &RM, &RN);
    const double uf = u_n[2] * g;
    const double kb = k_sc * om * om * T * T;
    const double b_h[2] = {kb * (f_n[0] - uf * u_n[0]), kb * (f_n[1] - uf * u_n[1])};
    const double bh = hypot(b_h[0], b_h[1]), R = sqrt(RM * RN) + h, ws = sqrt(g / R);
    double max_dev = 0, max_vel = 0, max_att = 0, max_pos = 0;
    for (size_t k = 0; k < n; ++k) {
        const double t = (double)(rates ? k : k + 1) * T;
        const double sn = sin(ws * t) / ws;
        max_dev = fmax(max_dev, hypot(vo[3 * k] - b_h[0] * sn, vo[3 * k + 1] - b_h[1] * sn));
        max_vel = fmax(max_vel, hypot(vo[3 * k], vo[3 * k + 1]));
        const double qu[4] = {cos(0.5 * om * t), u[0] * sin(0.5 * om * t), u[1] * sin(0.5 * om * t),
                              u[2] * sin(0.5 * om * t)};
        double qt[4];
        qmul(qA, qu, qt);
        max_att = fmax(max_att, quat_angle(qo + 4 * k, qt));
        max_pos = fmax(max_pos, hypot((po[3 * k] - L) * (RM + h), wrap_pi(po[3 * k + 1] - lon) * (RN + h) * cos(L)));
    }
    const double t_end = 600.0, amp = bh / ws;
    const double att_pred = bh / g * (1.0 - cos(ws * t_end)), pos_pred = bh / (ws * ws) * (1.0 - cos(ws * t_end));
    printf("tilted spin at %.1f rad/s, %s, 600 s: |v_h| max %.3g m/s (Schuler prediction amplitude %.3g, max "
           "deviation %.2g), attitude %.3g rad (predicted tilt %.3g), position %.3g m (predicted %.3g)\n",
           om, rates ? "rates" : "increments", max_vel, amp * sin(ws * t_end), max_dev, max_att, att_pred, max_pos,
           pos_pred);
    CHECK(max_dev <= 0.1 * amp, "tilted spin (%s): velocity error follows the predicted truncation (dev %.3g, amp %.3g)",
          rates ? "rates" : "increments", max_dev, amp);
    /* attitude: the tilt above plus the rate-mode trapezoid drift of the rotating Earth
     * rate (< W (om T)^2 / 12 t = 1.5e-8 rad) and round-off: 1.5 x + 2e-8 rad */
    CHECK(max_att <= 1.5 * att_pred + 2e-8, "tilted spin (%s): attitude (%.3g rad)", rates ? "rates" : "increments",
          max_att);
    CHECK(max_pos <= 1.5 * pos_pred + 1e-3, "tilted spin (%s): position (%.3g m)", rates ? "rates" : "increments",
          max_pos);
}

/* ======================================================================================
 * BARO loop: triple pole at -1/tau
 * ==================================================================================== */

static void test_baro_loop(double tau, double seconds)
{
    enum { NMAX = 100000 };
    static double gy[NMAX * 3], ac[NMAX * 3], he[NMAX], qo[NMAX * 4], vo[NMAX * 3], po[NMAX * 3];
    const double T = 0.01, L = 40 * DEG, h = 300.0, e0 = 10.0;
    const int N = (int)(seconds / T + 0.5);
    const double g = ref_gravity(L, h), wN = REF_W_IE * cos(L), wU = REF_W_IE * sin(L);
    /* level, heading 0: body = ENU */
    for (int k = 0; k < N; ++k) {
        gy[3 * k] = 0.0;
        gy[3 * k + 1] = T * wN;
        gy[3 * k + 2] = T * wU;
        ac[3 * k] = ac[3 * k + 1] = 0.0;
        ac[3 * k + 2] = T * g;
        he[k] = h;
    }
    gf_sins_config cfg = make_cfg(GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_BARO, 0.0);
    cfg.baro_tau_s = tau;
    const double q0[4] = {1, 0, 0, 0}, v0[3] = {0, 0, 0};
    gf_sins_state s;
    gf_sins_init(&s, &cfg, q0, v0, L, 0.0, h + e0, 0.0);
    size_t done = 0;
    CHECK(gf_sins_run(&s, (size_t)N, gy, ac, T, NULL, he, 0, qo, vo, po, NULL, &done) == GF_OK && done == (size_t)N,
          "baro run");
    /* Error dynamics e' = dv - k1 e, dv' = (2g/R - k2) e - b, b' = k3 e: characteristic
     * polynomial (s + 1/tau)^3; with e(0) = e0, dv(0) = b(0) = 0:
     *   e(t) = e0 (1 - 2 t/tau + t^2 / (2 tau^2)) exp(-t/tau).
     * The core integrates it with explicit steps of T: the local error O((T/tau)^2) e0
     * sums to ~e0 T/tau over the transient (1e-2 m at tau = 10 s, 1e-3 m at 100 s). The
     * true gravity gradient differs from 2 g/R by ~(f + m) = 0.7 %, 2e-8 s^-2 against
     * 3/tau^2 (3e-4 at tau = 100 s): below 1e-4 e0. Bound: 2 e0 T/tau + 1e-3 m. (Without
     * the 2 g/R term the loop would miss 1 % of its stiffness at tau = 100 s.) */
    double max_dev = 0.0;
    for (int k = 0; k < N; ++k) {
        const double t = (k + 1) * T, x = t / tau;
        const double e_cf = e0 * (1.0 - 2.0 * x + 0.5 * x * x) * exp(-x);
        max_dev = fmax(max_dev, fabs((po[3 * k + 2] - h) - e_cf));
    }
    const double tol = 2.0 * e0 * T / tau + 1e-3;
    printf("baro loop (tau %.0f s, e0 %.0f m, %.0f s): max |h error - closed form| %.3g m (bound %.3g), h error at "
           "the end %.3g m\n",
           tau, e0, seconds, max_dev, tol, po[3 * (N - 1) + 2] - h);
    CHECK(max_dev <= tol, "baro tau %g: height error follows the triple-pole closed form (%.3g m)", tau, max_dev);
    if (tau > 20.0)
        return;

    /* BARO with no external height (NaN) integrates like FREE, bitwise */
    for (int k = 0; k < N; ++k)
        he[k] = NAN;
    static double qf[1000 * 4], vf[1000 * 3], pf[1000 * 3];
    gf_sins_state sb, sf;
    gf_sins_init(&sb, &cfg, q0, v0, L, 0.0, h, 0.0);
    gf_sins_config cf = cfg;
    cf.vertical = GF_SINS_VERTICAL_FREE;
    gf_sins_init(&sf, &cf, q0, v0, L, 0.0, h, 0.0);
    CHECK(gf_sins_run(&sb, 1000, gy, ac, T, NULL, he, 0, qo, vo, po, NULL, &done) == GF_OK &&
              gf_sins_run(&sf, 1000, gy, ac, T, NULL, NULL, 0, qf, vf, pf, NULL, &done) == GF_OK,
          "baro without height, free");
    CHECK(memcmp(qo, qf, 1000 * 4 * sizeof(double)) == 0 && memcmp(vo, vf, 1000 * 3 * sizeof(double)) == 0 &&
              memcmp(po, pf, 1000 * 3 * sizeof(double)) == 0,
          "BARO with h_ext = NaN equals FREE bitwise");
}

/* ======================================================================================
 * Bitwise properties: batch = steps; no hidden state
 * ==================================================================================== */

enum { NR = 3000 };
static double r_gy[NR * 3], r_ac[NR * 3], r_t[NR];

/* a smooth, busy motion with noise: increments or rates, and irregular sample times */
static void make_record(int rates, uint64_t seed)
{
    test_rng rng = {seed};
    double t = 0.0;
    for (int k = 0; k < NR; ++k) {
        /* intervals on a 2^-10 s grid: every time sum and difference is exact, so the
         * rows' times do not depend on how the core forms them */
        const double T = floor((0.01 + test_rng_uniform(&rng, -0.002, 0.002)) * 1024.0 + 0.5) / 1024.0;
        t += T;
        r_t[k] = 50.0 + t;
        const double w[3] = {0.3 * sin(0.7 * t) + test_rng_uniform(&rng, -0.01, 0.01),
                             0.2 * cos(1.1 * t) + test_rng_uniform(&rng, -0.01, 0.01),
                             0.5 * sin(0.3 * t) + test_rng_uniform(&rng, -0.01, 0.01)};
        const double f[3] = {1.0 + sin(0.5 * t) + test_rng_uniform(&rng, -0.1, 0.1),
                             -0.5 + cos(0.2 * t) + test_rng_uniform(&rng, -0.1, 0.1),
                             9.8 + 0.3 * sin(0.9 * t) + test_rng_uniform(&rng, -0.1, 0.1)};
        for (int i = 0; i < 3; ++i) {
            r_gy[3 * k + i] = rates ? w[i] : 0.01 * w[i];
            r_ac[3 * k + i] = rates ? f[i] : 0.01 * f[i];
        }
    }
}

static void init_moving(gf_sins_state *s, int input, int coning, int vertical, double t0)
{
    const gf_sins_config c = make_cfg(input, coning, vertical, 100.0);
    const double e[3] = {1.0, 0.05, -0.1}, v[3] = {15.0, -7.0, 0.3};
    double q[4];
    ref_quat_euler(e, q);
    CHECK(gf_sins_init(s, &c, q, v, 0.8, 0.2, 120.0, t0) == GF_OK, "init moving");
}

static void test_batch_equals_steps(void)
{
    static double qo[NR * 4], vo[NR * 3], po[NR * 3], to[NR];
    for (int rates = 0; rates <= 1; ++rates)
        for (int use_t = 0; use_t <= 1; ++use_t) {
            make_record(rates, 77 + (uint64_t)rates);
            const int input = rates ? GF_SINS_INPUT_RATES : GF_SINS_INPUT_INCREMENTS;
            /* increments: the state time precedes t_s[0] (the first interval ends at
             * t_s[0]); rates: the record starts at the state time */
            const double t0 = rates && use_t ? r_t[0] : 50.0;
            gf_sins_state a, b;
            init_moving(&a, input, 1, GF_SINS_VERTICAL_FREE, t0);
            init_moving(&b, input, 1, GF_SINS_VERTICAL_FREE, t0);
            size_t done = 0;
            CHECK(gf_sins_run(&a, NR, r_gy, r_ac, 0.01, use_t ? r_t : NULL, NULL, 0, qo, vo, po, to, &done) ==
                          GF_OK && done == NR,
                  "batch run (rates %d, t_s %d)", rates, use_t);
            int same = 1;
            for (int k = 0; k < NR; ++k) {
                const double dt = !use_t ? 0.01 : (k == 0 ? r_t[0] - t0 : r_t[k] - r_t[k - 1]);
                same &= gf_sins_step(&b, r_gy + 3 * k, r_ac + 3 * k, dt, NAN) == GF_OK;
                same &= memcmp(qo + 4 * k, b.q_bn, sizeof b.q_bn) == 0;
                same &= memcmp(vo + 3 * k, b.v_n_m_s, sizeof b.v_n_m_s) == 0;
                same &= po[3 * k] == b.lat_rad && po[3 * k + 1] == b.lon_rad && po[3 * k + 2] == b.h_m;
                same &= to[k] == b.time_s;
            }
            CHECK(same, "rows of gf_sins_run = gf_sins_step loop, bitwise (rates %d, t_s %d)", rates, use_t);
            CHECK(state_same(&a, &b), "final states equal bitwise (rates %d, t_s %d)", rates, use_t);
            check_kept_trig(&a, "moving record");
            if (use_t) /* n additions of the intervals, each rounding by <= ulp/2 */
                CHECK(fabs(a.time_s - r_t[NR - 1]) <= NR * ulp(r_t[NR - 1]), "time follows t_s (%.17g vs %.17g)",
                      a.time_s, r_t[NR - 1]);

            /* backward: gf_sins_run(backward) = gf_sins_step loop on the samples last
             * to first (gf_sins_step negates dtheta itself on a reversed state) */
            CHECK(gf_sins_reverse(&a) == GF_OK && gf_sins_reverse(&b) == GF_OK, "reverse");
            CHECK(gf_sins_run(&a, NR, r_gy, r_ac, 0.01, use_t ? r_t : NULL, NULL, 1, qo, vo, po, to, &done) ==
                          GF_OK && done == NR,
                  "backward batch run");
            same = 1;
            for (int k = NR - 1; k >= 0; --k) {
                double dt = 0.01;
                if (use_t) {
                    if (rates)
                        dt = k == NR - 1 ? 0.01 /* unused: starts the record */ : r_t[k + 1] - r_t[k];
                    else
                        dt = k >= 1 ? r_t[k] - r_t[k - 1] : 0.01;
                }
                same &= gf_sins_step(&b, r_gy + 3 * k, r_ac + 3 * k, dt, NAN) == GF_OK;
                same &= memcmp(qo + 4 * k, b.q_bn, sizeof b.q_bn) == 0;
                for (int i = 0; i < 3; ++i)
                    same &= vo[3 * k + i] == -b.v_n_m_s[i]; /* rows carry true-time velocity */
                same &= po[3 * k] == b.lat_rad && po[3 * k + 1] == b.lon_rad && po[3 * k + 2] == b.h_m;
                same &= to[k] == b.time_s;
            }
            CHECK(same, "backward rows = reversed gf_sins_step loop, bitwise (rates %d, t_s %d)", rates, use_t);
            CHECK(state_same(&a, &b), "backward final states equal bitwise (rates %d, t_s %d)", rates, use_t);
        }

    /* chunked runs = one run */
    make_record(0, 5);
    gf_sins_state a, b;
    init_moving(&a, GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_BARO, 0.0);
    init_moving(&b, GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_BARO, 0.0);
    static double hx[NR];
    for (int k = 0; k < NR; ++k)
        hx[k] = (k % 7 == 3) ? NAN : 120.0 + 0.001 * k;
    static double q2[NR * 4], v2[NR * 3], p2[NR * 3];
    size_t d1 = 0, d2 = 0, d3 = 0;
    gf_sins_run(&a, NR, r_gy, r_ac, 0.01, NULL, hx, 0, qo, vo, po, NULL, &d1);
    gf_sins_run(&b, 1234, r_gy, r_ac, 0.01, NULL, hx, 0, q2, v2, p2, NULL, &d2);
    gf_sins_run(&b, NR - 1234, r_gy + 3 * 1234, r_ac + 3 * 1234, 0.01, NULL, hx + 1234, 0, q2 + 4 * 1234,
                v2 + 3 * 1234, p2 + 3 * 1234, NULL, &d3);
    CHECK(d1 == NR && d2 + d3 == NR && memcmp(qo, q2, sizeof q2) == 0 && memcmp(vo, v2, sizeof v2) == 0 &&
              memcmp(po, p2, sizeof p2) == 0 && state_same(&a, &b),
          "a run in two chunks = one run, bitwise (BARO with gaps)");
}

/* A rate run with sample times must not depend on how it is split into calls. Here the
 * record starts 100 s after the state time (t_s[0] = t0 + 100): one call and two calls
 * over the same samples must give the same rows (or the same refusal). */
static void test_rate_run_chunking_with_times(void)
{
    enum { M = 200 };
    static double gy[M * 3], ac[M * 3], ts[M], q1[M * 4], v1[M * 3], p1[M * 3], t1[M];
    static double q2[M * 4], v2[M * 3], p2[M * 3], t2[M];
    make_record(1, 51);
    memcpy(gy, r_gy, sizeof gy);
    memcpy(ac, r_ac, sizeof ac);
    for (int k = 0; k < M; ++k)
        ts[k] = 100.0 + 0.01 * k;
    gf_sins_state a, b;
    init_moving(&a, GF_SINS_INPUT_RATES, 1, GF_SINS_VERTICAL_FREE, 0.0);
    b = a;
    size_t d1 = 0, d2 = 0, d3 = 0;
    const gf_status s1 = gf_sins_run(&a, M, gy, ac, 0.0, ts, NULL, 0, q1, v1, p1, t1, &d1);
    const gf_status s2 = gf_sins_run(&b, M / 2, gy, ac, 0.0, ts, NULL, 0, q2, v2, p2, t2, &d2);
    const gf_status s3 = s2 != GF_OK ? s2
                                     : gf_sins_run(&b, M / 2, gy + 3 * (M / 2), ac + 3 * (M / 2), 0.0, ts + M / 2,
                                                   NULL, 0, q2 + 4 * (M / 2), v2 + 3 * (M / 2), p2 + 3 * (M / 2),
                                                   t2 + M / 2, &d3);
    CHECK((s1 == GF_OK) == (s3 == GF_OK), "rates, t_s[0] = t0 + 100 s: one call %d, two calls %d", (int)s1, (int)s3);
    if (s1 == GF_OK && s3 == GF_OK) {
        const size_t j = M / 2; /* first row of the second call */
        CHECK(t2[j] == t1[j] && memcmp(v2, v1, sizeof v1) == 0 && state_same(&a, &b),
              "rates, t_s[0] = t0 + 100 s: two calls = one call (row %zu: time %.6f vs %.6f, |dv| %.3g m/s)", j, t2[j],
              t1[j], fabs(v2[3 * j] - v1[3 * j]) + fabs(v2[3 * j + 1] - v1[3 * j + 1]));
    }
}

static void test_interleaved_states(void)
{
    enum { M = 1500 };
    static double ga[M * 3], aa[M * 3], gb[M * 3], ab[M * 3];
    make_record(0, 11);
    memcpy(ga, r_gy, sizeof ga);
    memcpy(aa, r_ac, sizeof aa);
    make_record(1, 12);
    memcpy(gb, r_gy, sizeof gb);
    memcpy(ab, r_ac, sizeof ab);
    gf_sins_state a, b, a1, b1;
    init_moving(&a, GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_FREE, 0.0);
    init_moving(&a1, GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_FREE, 0.0);
    init_moving(&b, GF_SINS_INPUT_RATES, 0, GF_SINS_VERTICAL_HOLD, 3.0);
    init_moving(&b1, GF_SINS_INPUT_RATES, 0, GF_SINS_VERTICAL_HOLD, 3.0);
    int ok = 1;
    for (int k = 0; k < M; ++k) {
        ok &= gf_sins_step(&a, ga + 3 * k, aa + 3 * k, 0.01, NAN) == GF_OK;
        ok &= gf_sins_step(&b, gb + 3 * k, ab + 3 * k, 0.012, NAN) == GF_OK;
        if (k == M / 2) { /* a batch call in between must not disturb the other state */
            double qx[4], vx[3], px[3];
            size_t d;
            gf_sins_state tmp = b;
            ok &= gf_sins_run(&tmp, 1, gb, ab, 0.012, NULL, NULL, 0, qx, vx, px, NULL, &d) == GF_OK;
        }
    }
    for (int k = 0; k < M; ++k)
        ok &= gf_sins_step(&a1, ga + 3 * k, aa + 3 * k, 0.01, NAN) == GF_OK;
    for (int k = 0; k < M; ++k)
        ok &= gf_sins_step(&b1, gb + 3 * k, ab + 3 * k, 0.012, NAN) == GF_OK;
    CHECK(ok, "interleaved steps succeed");
    CHECK(state_same(&a, &a1) && state_same(&b, &b1), "two interleaved states = separate runs, bitwise");
    /* copying the struct copies the navigator */
    gf_sins_state c = a;
    gf_sins_step(&a, ga, aa, 0.01, NAN);
    gf_sins_step(&c, ga, aa, 0.01, NAN);
    CHECK(state_same(&a, &c), "a copy of the state navigates identically");
}

/* ======================================================================================
 * Reverse navigation: forward, reverse, backward returns to the start
 * ==================================================================================== */

static void test_reverse_roundtrip(int input)
{
    enum { N = 6000 }; /* 60 s at 100 Hz */
    static double gy[(N + 1) * 3], ac[(N + 1) * 3];
    static double qf[(N + 1) * 4], vf[(N + 1) * 3], pf[(N + 1) * 3], tf[N + 1];
    static double qb[(N + 1) * 4], vb[(N + 1) * 3], pb[(N + 1) * 3], tb[N + 1];
    const int rates = input == GF_SINS_INPUT_RATES;
    const double T = 0.01, t0 = 100.0;
    const double w_b[3] = {0.002, -0.003, 0.02}, f_b[3] = {0.3, 0.8, 9.9};
    /* rates: the body rate also ramps linearly (exact for the rate algorithm), so that
     * the coning and sculling terms work in both directions */
    const double w_ramp[3] = {0.001 / 60.0, 0.002 / 60.0, -0.01 / 60.0};
    const size_t n = rates ? N + 1 : N;
    for (size_t k = 0; k < n; ++k)
        for (int i = 0; i < 3; ++i) {
            gy[3 * k + i] = rates ? w_b[i] + w_ramp[i] * (double)k * T : T * w_b[i];
            ac[3 * k + i] = rates ? f_b[i] : T * f_b[i];
        }
    const gf_sins_config cfg = make_cfg(input, 1, GF_SINS_VERTICAL_FREE, 0.0);
    const double e0[3] = {30 * DEG, 2 * DEG, -3 * DEG}, v0[3] = {10.0, 20.0, 0.5};
    const double L0 = 45 * DEG, lon0 = 10 * DEG, h0 = 500.0;
    double q0[4];
    ref_quat_euler(e0, q0);
    gf_sins_state s, s0;
    gf_sins_init(&s, &cfg, q0, v0, L0, lon0, h0, t0);
    s0 = s;

    /* backward = 1 on a state that was not reversed: refused, nothing touched */
    size_t done = 99;
    gf_sins_state before = s;
    CHECK(gf_sins_run(&s, n, gy, ac, T, NULL, NULL, 1, qb, vb, pb, tb, &done) == GF_ERR_BAD_PARAMETER &&
              done == 0 && state_same(&s, &before),
          "backward run on a forward state: BAD_PARAMETER, state unchanged");

    CHECK(gf_sins_run(&s, n, gy, ac, T, NULL, NULL, 0, qf, vf, pf, tf, &done) == GF_OK && done == n,
          "forward run");
    const gf_sins_state s_end = s;
    CHECK(gf_sins_reverse(&s) == GF_OK, "reverse");
    CHECK(s.earth_rate_sign == -1.0 && s.v_n_m_s[0] == -s_end.v_n_m_s[0] && s.v_n_m_s[1] == -s_end.v_n_m_s[1] &&
              s.v_n_m_s[2] == -s_end.v_n_m_s[2] && s.time_s == s_end.time_s && s.lat_rad == s_end.lat_rad &&
              memcmp(s.q_bn, s_end.q_bn, sizeof s.q_bn) == 0,
          "reverse negates v and the Earth rate, keeps time, position, attitude");
    before = s;
    CHECK(gf_sins_run(&s, n, gy, ac, T, NULL, NULL, 0, qb, vb, pb, tb, &done) == GF_ERR_BAD_PARAMETER &&
              done == 0 && state_same(&s, &before),
          "forward run on a reversed state: BAD_PARAMETER, state unchanged");
    CHECK(gf_sins_run(&s, n, gy, ac, T, NULL, NULL, 1, qb, vb, pb, tb, &done) == GF_OK && done == n,
          "backward run");
    CHECK(gf_sins_reverse(&s) == GF_OK && s.earth_rate_sign == 1.0, "reverse again");
    check_kept_trig(&s_end, "reverse: after the forward run");
    check_kept_trig(&s, "reverse: after the backward run");

    double RM, RN;
    ref_radii(L0, &RM, &RN);
    const double att = quat_angle(s.q_bn, s0.q_bn);
    const double dN = (s.lat_rad - L0) * (RM + h0), dE = wrap_pi(s.lon_rad - lon0) * (RN + h0) * cos(L0);
    const double dh = s.h_m - h0;
    const double dv = sqrt((s.v_n_m_s[0] - v0[0]) * (s.v_n_m_s[0] - v0[0]) +
                           (s.v_n_m_s[1] - v0[1]) * (s.v_n_m_s[1] - v0[1]) +
                           (s.v_n_m_s[2] - v0[2]) * (s.v_n_m_s[2] - v0[2]));
    /* rows of the backward run against the forward run at the same times */
    double row_att = 0, row_pos = 0, row_t = 0;
    for (size_t k = 0; k < n; ++k) {
        /* backward row k = state at the start of interval k (increments: t_(k-1); rates:
         * sample k). Forward rows hold the states at the ends of the intervals. */
        const double *qr, *pr;
        double tr;
        if (!rates && k == 0) {
            qr = s0.q_bn;
            pr = NULL;
            tr = t0;
        } else {
            const size_t j = rates ? k : k - 1;
            qr = qf + 4 * j;
            pr = pf + 3 * j;
            tr = tf[j];
        }
        row_att = fmax(row_att, quat_angle(qb + 4 * k, qr));
        const double lat_r = pr ? pr[0] : L0, lon_r = pr ? pr[1] : lon0, h_r = pr ? pr[2] : h0;
        row_pos = fmax(row_pos, fmax(fabs(pb[3 * k] - lat_r) * (RM + h0),
                                     fmax(fabs(wrap_pi(pb[3 * k + 1] - lon_r)) * (RN + h0) * cos(L0),
                                          fabs(pb[3 * k + 2] - h_r))));
        row_t = fmax(row_t, fabs(tb[k] - tr));
    }
    printf("reverse round trip (%s, 60 s, %.0f m travelled): attitude %.2g rad, north %.2g m, east %.2g m, "
           "height %.2g m, velocity %.2g m/s, time %.2g s; worst row: attitude %.2g rad, position %.2g m\n",
           rates ? "rates" : "increments",
           hypot((s_end.lat_rad - L0) * (RM + h0), (s_end.lon_rad - lon0) * (RN + h0) * cos(L0)), att, dN, dE,
           dh, dv, s.time_s - t0, row_att, row_pos);
    /* Forward and backward differ only where the update is not time-symmetric: the
     * mid-point velocity is extrapolated with the acceleration of the neighbouring
     * interval (the previous one forward, the next one backward), an O(T^2 jerk)
     * difference in v_mid that enters through Coriolis and transport rates (~1e-4
     * rad/s): ~1e-12 m/s per step for this record (jerk < 0.1 m/s^3), 1e-8 m/s and
     * 1e-7 m over 6000 steps; and round-off (~eps per step, 1e-12 rad). Bounds with a
     * factor >= 100 over these: 1e-9 rad, 1e-5 m, 1e-6 m/s (the brief's 1e-6 rad and
     * 1e-3 m would let a real asymmetry through). Time: 2n additions of T. */
    CHECK(att <= 1e-9, "round trip: attitude back (%.3g rad)", att);
    CHECK(fabs(dN) <= 1e-5 && fabs(dE) <= 1e-5 && fabs(dh) <= 1e-5, "round trip: position back (%.3g %.3g %.3g m)",
          dN, dE, dh);
    CHECK(dv <= 1e-6, "round trip: velocity back (%.3g m/s)", dv);
    CHECK(fabs(s.time_s - t0) <= 2.0 * (double)n * ulp(t0 + 60.0), "round trip: time back (%.3g s)", s.time_s - t0);
    CHECK(row_att <= 1e-9 && row_pos <= 1e-5, "backward rows retrace the forward rows (%.3g rad, %.3g m)", row_att,
          row_pos);
    CHECK(row_t <= 2.0 * (double)n * ulp(t0 + 60.0), "backward row times (%.3g s)", row_t);
}

/* gf_sins.h: "Calling it twice restores the navigation state and the direction; the
 * previous-sample memory (coning terms, the start of a rate record) is cleared each
 * time". So after two reversals the state equals the original except have_prev = 0,
 * and the next sample behaves as on a state whose memory was cleared. */
static void test_double_reverse(void)
{
    for (int rates = 0; rates <= 1; ++rates) {
        const char *mode = rates ? "rates" : "increments";
        make_record(rates, 21);
        gf_sins_state a, b;
        init_moving(&a, rates ? GF_SINS_INPUT_RATES : GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_FREE, 0.0);
        for (int k = 0; k < 100; ++k)
            gf_sins_step(&a, r_gy + 3 * k, r_ac + 3 * k, 0.01, NAN);
        b = a;
        CHECK(gf_sins_reverse(&b) == GF_OK && gf_sins_reverse(&b) == GF_OK, "reverse twice");
        CHECK(b.have_prev == 0, "%s: two reversals clear the sample memory", mode);
        gf_sins_state cleared = a;
        cleared.have_prev = 0;
        CHECK(state_same(&cleared, &b), "%s: two reversals restore everything else bitwise", mode);
        const double t_b = b.time_s;
        gf_sins_step(&b, r_gy + 300, r_ac + 300, 0.01, NAN);
        gf_sins_step(&cleared, r_gy + 300, r_ac + 300, 0.01, NAN);
        CHECK(state_same(&cleared, &b), "%s: the next sample acts as on a cleared memory", mode);
        if (rates)
            CHECK(b.time_s == t_b, "rates: after two reversals the next sample restarts the record (time kept)");
        else
            CHECK(b.time_s > t_b, "increments: after two reversals the next sample is integrated");
    }
}

/* ======================================================================================
 * Error paths
 * ==================================================================================== */

static void test_step_errors(void)
{
    for (int rates = 0; rates <= 1; ++rates) {
        const int input = rates ? GF_SINS_INPUT_RATES : GF_SINS_INPUT_INCREMENTS;
        const char *mode = rates ? "rates" : "increments";
        make_record(rates, 31);
        gf_sins_state s;
        init_moving(&s, input, 1, GF_SINS_VERTICAL_BARO, 0.0);
        for (int k = 0; k < 50; ++k) /* a state in mid-record: prev sample, acceleration */
            gf_sins_step(&s, r_gy + 3 * k, r_ac + 3 * k, 0.01, 120.0);
        const double T = 0.01, sc = rates ? 1.0 : T; /* increments = rate x T */
        const double okg[3] = {0.1 * sc, -0.2 * sc, 0.3 * sc}, oka[3] = {0.5 * sc, 1.0 * sc, 9.8 * sc};
        gf_sins_state ref;
        memcpy(&ref, &s, sizeof s);
#define STEP_FAILS(g, a, dt, hx, code, what)                                                      \
    do {                                                                                         \
        const gf_status st_ = gf_sins_step(&s, (g), (a), (dt), (hx));                            \
        CHECK(st_ == (code), "%s, %s: status %d, expected %d", mode, (what), (int)st_, (int)(code)); \
        CHECK(memcmp(&s, &ref, sizeof s) == 0, "%s, %s: state unchanged", mode, (what));         \
    } while (0)
        const double bads[4] = {NAN, INFINITY, -INFINITY, -NAN};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 4; ++j) {
                double g[3] = {okg[0], okg[1], okg[2]}, a[3] = {oka[0], oka[1], oka[2]};
                g[i] = bads[j];
                STEP_FAILS(g, oka, T, NAN, GF_ERR_NONFINITE_INPUT, "non-finite gyro");
                a[i] = bads[j];
                STEP_FAILS(okg, a, T, NAN, GF_ERR_NONFINITE_INPUT, "non-finite accel");
            }
        STEP_FAILS(okg, oka, T, INFINITY, GF_ERR_NONFINITE_INPUT, "infinite external height");
        /* |w| limit 50 rad/s: 1 % over is refused, 1 % under accepted (increments: |dtheta|/dt) */
        const double u = 1.0 / sqrt(3.0);
        const double g_hi[3] = {50.5 * u * sc, -50.5 * u * sc, 50.5 * u * sc};
        const double g_lo[3] = {49.5 * u * sc, -49.5 * u * sc, 49.5 * u * sc};
        const double a_hi[3] = {0.0, 1010.0 * sc, 0.0}, a_lo[3] = {0.0, 990.0 * sc, 0.0};
        STEP_FAILS(g_hi, oka, T, NAN, GF_ERR_OUT_OF_RANGE, "|w| above max_rate");
        STEP_FAILS(okg, a_hi, T, NAN, GF_ERR_OUT_OF_RANGE, "|f| above max_specific_force");
        if (!rates) {
            /* same increments over a 1.1x longer interval are a legal rate */
            gf_sins_state t = s;
            CHECK(gf_sins_step(&t, g_hi, oka, 1.1 * T, NAN) == GF_OK, "increments: limit is |dtheta|/dt");
            t = s;
            CHECK(gf_sins_step(&t, okg, a_hi, 1.1 * T, NAN) == GF_OK, "increments: limit is |dv|/dt");
        }
        gf_sins_state t = s;
        CHECK(gf_sins_step(&t, g_lo, oka, T, NAN) == GF_OK, "%s: |w| below max_rate accepted", mode);
        t = s;
        CHECK(gf_sins_step(&t, okg, a_lo, T, NAN) == GF_OK, "%s: |f| below the limit accepted", mode);
        /* a tighter configured limit is honoured */
        t = s;
        t.cfg.max_rate_rad_s = 0.2;
        CHECK(gf_sins_step(&t, okg, oka, T, NAN) == GF_ERR_OUT_OF_RANGE, "%s: configured max_rate", mode);
        STEP_FAILS(okg, oka, 0.0, NAN, GF_ERR_BAD_TIME, "dt = 0");
        STEP_FAILS(okg, oka, -0.01, NAN, GF_ERR_BAD_TIME, "dt < 0");
        STEP_FAILS(okg, oka, NAN, NAN, GF_ERR_BAD_TIME, "dt NaN");
        STEP_FAILS(okg, oka, INFINITY, NAN, GF_ERR_BAD_TIME, "dt Inf");
        STEP_FAILS(NULL, oka, T, NAN, GF_ERR_NULL_POINTER, "NULL gyro");
        STEP_FAILS(okg, NULL, T, NAN, GF_ERR_NULL_POINTER, "NULL accel");
        CHECK(gf_sins_step(NULL, okg, oka, T, NAN) == GF_ERR_NULL_POINTER, "%s: NULL state", mode);
#undef STEP_FAILS
        /* a corrupted state is refused, not propagated */
        gf_sins_state bad = s;
        bad.q_bn[0] *= 2.0;
        CHECK(gf_sins_step(&bad, okg, oka, T, NAN) == GF_ERR_BAD_PARAMETER, "%s: corrupt quaternion refused", mode);
        bad = s;
        bad.earth_rate_sign = 0.5;
        CHECK(gf_sins_step(&bad, okg, oka, T, NAN) == GF_ERR_BAD_PARAMETER, "%s: corrupt sign refused", mode);
        bad = s;
        bad.lat_rad = 2.0;
        CHECK(gf_sins_step(&bad, okg, oka, T, NAN) == GF_ERR_BAD_PARAMETER, "%s: corrupt latitude refused", mode);
        bad = s;
        bad.cfg.vertical = 9;
        CHECK(gf_sins_step(&bad, okg, oka, T, NAN) == GF_ERR_BAD_PARAMETER, "%s: corrupt config refused", mode);
        /* after all that the state still steps normally */
        CHECK(gf_sins_step(&s, okg, oka, T, 120.0) == GF_OK && s.n_samples == 51, "%s: state usable", mode);
    }
    CHECK(gf_sins_reverse(NULL) == GF_ERR_NULL_POINTER, "reverse NULL");
}

/* One error in sample J of a batch: n_done = J, rows before valid (= the step loop),
 * state = state after sample J-1, rows from J on untouched. */
enum { NE_RUN = 60, J_BAD = 17 };
static void check_run_error(const char *what, int rates, int backward, const double *gy, const double *ac,
                            const double *ts, double dt, gf_status expect, size_t expect_done)
{
    const double SENT = 1234.5;
    static double qo[NE_RUN * 4], vo[NE_RUN * 3], po[NE_RUN * 3], to[NE_RUN];
    for (int i = 0; i < NE_RUN * 4; ++i)
        qo[i] = SENT;
    for (int i = 0; i < NE_RUN * 3; ++i)
        vo[i] = po[i] = SENT;
    for (int i = 0; i < NE_RUN; ++i)
        to[i] = SENT;
    gf_sins_state s, r;
    init_moving(&s, rates ? GF_SINS_INPUT_RATES : GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_FREE, 0.0);
    if (backward)
        gf_sins_reverse(&s);
    r = s;
    size_t done = 999;
    const gf_status st = gf_sins_run(&s, NE_RUN, gy, ac, dt, ts, NULL, backward, qo, vo, po, to, &done);
    CHECK(st == expect && done == expect_done, "%s: status %d (expected %d), n_done %zu (expected %zu)", what,
          (int)st, (int)expect, done, expect_done);
    /* reference: step loop over the good samples, in processing order */
    int rows_ok = 1;
    for (size_t d = 0; d < expect_done; ++d) {
        const size_t k = backward ? NE_RUN - 1 - d : d;
        double dtk = dt;
        if (ts)
            dtk = d == 0 ? ts[k] : ts[k] - ts[k - 1]; /* forward only below */
        rows_ok &= gf_sins_step(&r, gy + 3 * k, ac + 3 * k, dtk, NAN) == GF_OK;
        rows_ok &= memcmp(qo + 4 * k, r.q_bn, sizeof r.q_bn) == 0 && po[3 * k] == r.lat_rad &&
                   po[3 * k + 1] == r.lon_rad && po[3 * k + 2] == r.h_m && to[k] == r.time_s;
        for (int i = 0; i < 3; ++i)
            rows_ok &= vo[3 * k + i] == (backward ? -r.v_n_m_s[i] : r.v_n_m_s[i]);
    }
    CHECK(rows_ok, "%s: rows before the bad sample = step loop", what);
    CHECK(state_same(&s, &r), "%s: state = state after the last good sample", what);
    int untouched = 1;
    for (size_t d = expect_done; d < NE_RUN; ++d) {
        const size_t k = backward ? NE_RUN - 1 - d : d;
        untouched &= qo[4 * k] == SENT && vo[3 * k] == SENT && po[3 * k] == SENT && to[k] == SENT;
    }
    CHECK(untouched, "%s: rows from the bad sample on untouched", what);
}

static void test_run_errors(void)
{
    static double gy[NE_RUN * 3], ac[NE_RUN * 3], ts[NE_RUN];
    for (int rates = 0; rates <= 1; ++rates) {
        make_record(rates, 41);
        const double sc = rates ? 1.0 : 0.01;
        for (int backward = 0; backward <= 1; ++backward) {
            const size_t jd = backward ? NE_RUN - 1 - J_BAD : J_BAD; /* processing index */
            char what[96];
#define RESET() (memcpy(gy, r_gy, sizeof gy), memcpy(ac, r_ac, sizeof ac))
            RESET();
            gy[3 * J_BAD + 1] = NAN;
            snprintf(what, sizeof what, "run rates %d backward %d: NaN gyro", rates, backward);
            check_run_error(what, rates, backward, gy, ac, NULL, 0.01, GF_ERR_NONFINITE_INPUT, jd);
            RESET();
            ac[3 * J_BAD + 2] = -INFINITY;
            snprintf(what, sizeof what, "run rates %d backward %d: Inf accel", rates, backward);
            check_run_error(what, rates, backward, gy, ac, NULL, 0.01, GF_ERR_NONFINITE_INPUT, jd);
            RESET();
            gy[3 * J_BAD] = 60.0 * sc;
            snprintf(what, sizeof what, "run rates %d backward %d: |w| too large", rates, backward);
            check_run_error(what, rates, backward, gy, ac, NULL, 0.01, GF_ERR_OUT_OF_RANGE, jd);
            RESET();
            ac[3 * J_BAD] = 2000.0 * sc;
            snprintf(what, sizeof what, "run rates %d backward %d: |f| too large", rates, backward);
            check_run_error(what, rates, backward, gy, ac, NULL, 0.01, GF_ERR_OUT_OF_RANGE, jd);
            RESET();
            snprintf(what, sizeof what, "run rates %d backward %d: dt = 0", rates, backward);
            check_run_error(what, rates, backward, gy, ac, NULL, 0.0, GF_ERR_BAD_TIME, 0);
            snprintf(what, sizeof what, "run rates %d backward %d: dt < 0", rates, backward);
            check_run_error(what, rates, backward, gy, ac, NULL, -0.01, GF_ERR_BAD_TIME, 0);
            snprintf(what, sizeof what, "run rates %d backward %d: dt NaN", rates, backward);
            check_run_error(what, rates, backward, gy, ac, NULL, NAN, GF_ERR_BAD_TIME, 0);
#undef RESET
        }
        /* sample times (forward): a repeated or decreasing time at J, a NaN time at J */
        memcpy(gy, r_gy, sizeof gy);
        memcpy(ac, r_ac, sizeof ac);
        for (int k = 0; k < NE_RUN; ++k) /* from the state time 0 (rates) or one interval after */
            ts[k] = 0.01 * (k + (rates ? 0 : 1));
        ts[J_BAD] = ts[J_BAD - 1];
        char what[96];
        snprintf(what, sizeof what, "run rates %d: repeated sample time", rates);
        check_run_error(what, rates, 0, gy, ac, ts, 0.0, GF_ERR_BAD_TIME, J_BAD);
        ts[J_BAD] = ts[J_BAD - 1] - 0.005;
        snprintf(what, sizeof what, "run rates %d: decreasing sample time", rates);
        check_run_error(what, rates, 0, gy, ac, ts, 0.0, GF_ERR_BAD_TIME, J_BAD);
        ts[J_BAD] = NAN;
        snprintf(what, sizeof what, "run rates %d: NaN sample time", rates);
        check_run_error(what, rates, 0, gy, ac, ts, 0.0, GF_ERR_NONFINITE_INPUT, J_BAD);
    }

    /* NULL pointers: nothing done */
    gf_sins_state s, r;
    init_moving(&s, GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_FREE, 0.0);
    r = s;
    double q[4], v[3], p[3], t[1];
    size_t done = 9;
    CHECK(gf_sins_run(NULL, 1, r_gy, r_ac, 0.01, NULL, NULL, 0, q, v, p, t, &done) == GF_ERR_NULL_POINTER &&
              done == 0,
          "run NULL state");
    CHECK(gf_sins_run(&s, 1, NULL, r_ac, 0.01, NULL, NULL, 0, q, v, p, t, &done) == GF_ERR_NULL_POINTER,
          "run NULL gyro");
    CHECK(gf_sins_run(&s, 1, r_gy, NULL, 0.01, NULL, NULL, 0, q, v, p, t, &done) == GF_ERR_NULL_POINTER,
          "run NULL accel");
    CHECK(gf_sins_run(&s, 1, r_gy, r_ac, 0.01, NULL, NULL, 0, NULL, v, p, t, &done) == GF_ERR_NULL_POINTER,
          "run NULL q");
    CHECK(gf_sins_run(&s, 1, r_gy, r_ac, 0.01, NULL, NULL, 0, q, NULL, p, t, &done) == GF_ERR_NULL_POINTER,
          "run NULL v");
    CHECK(gf_sins_run(&s, 1, r_gy, r_ac, 0.01, NULL, NULL, 0, q, v, NULL, t, &done) == GF_ERR_NULL_POINTER,
          "run NULL pos");
    CHECK(state_same(&s, &r), "NULL pointers: state unchanged");
    CHECK(gf_sins_run(&s, 1, r_gy, r_ac, 0.01, NULL, NULL, 0, q, v, p, NULL, NULL) == GF_OK,
          "run with time_s and n_done NULL");
    s = r;
    s.q_bn[1] = NAN;
    CHECK(gf_sins_run(&s, 1, r_gy, r_ac, 0.01, NULL, NULL, 0, q, v, p, t, &done) == GF_ERR_BAD_PARAMETER &&
              done == 0,
          "run on a corrupt state refused");
    s = r;
    CHECK(gf_sins_run(&s, 0, r_gy, r_ac, 0.01, NULL, NULL, 0, q, v, p, t, &done) == GF_OK && done == 0 &&
              state_same(&s, &r),
          "empty run");
}

/* Towards the pole: a huge northward velocity 0.01 deg below the latitude limit must stop
 * with DIVERGED and leave the state as it was before the failing sample. */
static void test_pole_divergence(void)
{
    enum { NP = 1000 };
    static double gy[NP * 3], ac[NP * 3], qo[NP * 4], vo[NP * 3], po[NP * 3];
    const double T = 0.01, L = 89.89 * DEG, h = 0.0;
    const double g = ref_gravity(L, h);
    for (int k = 0; k < NP; ++k) {
        gy[3 * k] = gy[3 * k + 1] = gy[3 * k + 2] = 0.0;
        ac[3 * k] = ac[3 * k + 1] = 0.0;
        ac[3 * k + 2] = T * g;
    }
    const gf_sins_config cfg = make_cfg(GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_HOLD, h);
    const double q0[4] = {1, 0, 0, 0}, v0[3] = {0.0, 1000.0, 0.0};
    gf_sins_state s, r;
    CHECK(gf_sins_init(&s, &cfg, q0, v0, L, 1.0, h, 0.0) == GF_OK, "pole: init at 89.89 deg");
    r = s;
    /* 0.01 deg = 1.1 km from the limit at 10 m per step: ~110 steps */
    int k_fail = -1;
    gf_sins_state last;
    for (int k = 0; k < NP; ++k) {
        memcpy(&last, &s, sizeof s);
        const gf_status st = gf_sins_step(&s, gy + 3 * k, ac + 3 * k, T, NAN);
        if (st != GF_OK) {
            CHECK(st == GF_ERR_DIVERGED, "pole: DIVERGED (got %d)", (int)st);
            CHECK(memcmp(&last, &s, sizeof s) == 0, "pole: state unchanged by the failing step");
            k_fail = k;
            break;
        }
        CHECK(fabs(s.lat_rad) < 89.9 * DEG, "pole: latitude stays below the limit while OK");
    }
    printf("pole: DIVERGED at sample %d, last latitude %.12f deg\n", k_fail, s.lat_rad / DEG);
    CHECK(k_fail > 50 && k_fail < 200, "pole: fails after ~110 samples (at %d)", k_fail);
    size_t done = 0;
    CHECK(gf_sins_run(&r, NP, gy, ac, T, NULL, NULL, 0, qo, vo, po, NULL, &done) == GF_ERR_DIVERGED &&
              (int)done == k_fail,
          "pole: batch stops with DIVERGED at the same sample (n_done %zu)", done);
    CHECK(state_same(&r, &s), "pole: batch state = state before the failing sample");
}

/* The latitude limit of the ENU mechanization (gf_sins.h). Before it, a start at
 * 90 deg - 2e-9 rad was accepted and one step east returned a longitude of tens of
 * radians and a meaningless attitude with GF_OK. */
static void test_latitude_limit(void)
{
    const gf_sins_config cfg = make_cfg(GF_SINS_INPUT_INCREMENTS, 1, GF_SINS_VERTICAL_HOLD, 0.0);
    const double q0[4] = {1, 0, 0, 0}, v0[3] = {10.0, 0.0, 0.0};
    const double dth[3] = {0, 0, 0}, dv[3] = {0, 0, 0.01 * 9.832};
    gf_sins_state s;
    const double lat_tester = 0.5 * PI - 2e-9;
    const gf_status st = gf_sins_init(&s, &cfg, q0, v0, lat_tester, 1.0, 0.0, 0.0);
    if (st == GF_OK) { /* what the unlimited mechanization did */
        const gf_status st2 = gf_sins_step(&s, dth, dv, 0.01, NAN);
        CHECK(0, "start at 90 deg - 2e-9 rad accepted; one step east returned status %d, "
                 "longitude %.6g rad", (int)st2, s.lon_rad);
    } else {
        CHECK(st == GF_ERR_BAD_PARAMETER, "start at 90 deg - 2e-9 rad: BAD_PARAMETER (got %d)", (int)st);
    }
    /* the limit is 89.9 deg (89900 millidegrees), both hemispheres */
    const double limit = GF_SINS_LAT_LIMIT_MDEG / 1000.0 * DEG;
    CHECK(GF_SINS_LAT_LIMIT_MDEG == 89900, "limit 89.9 deg as documented");
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        CHECK(gf_sins_init(&s, &cfg, q0, v0, sgn * limit, 1.0, 0.0, 0.0) == GF_ERR_BAD_PARAMETER,
              "start at %+g x the limit refused", (double)sgn);
        CHECK(gf_sins_init(&s, &cfg, q0, v0, sgn * nextafter(limit, 0.0), 1.0, 0.0, 0.0) == GF_OK,
              "start just inside the limit accepted");
    }
    /* EARTH_FLAT does not use the latitude: only |lat| < 90 deg as before */
    gf_sins_config flat = cfg;
    flat.earth = GF_SINS_EARTH_FLAT;
    CHECK(gf_sins_init(&s, &flat, q0, v0, 89.95 * DEG, 1.0, 0.0, 0.0) == GF_OK, "flat frame at 89.95 deg");
    /* a state beyond the limit handed to a step (e.g. restored from saved bytes) */
    CHECK(gf_sins_init(&s, &cfg, q0, v0, 89.0 * DEG, 1.0, 0.0, 0.0) == GF_OK, "init 89 deg");
    CHECK(gf_sins_step(&s, dth, dv, 0.01, NAN) == GF_OK && s.have_prev, "a first step");
    CHECK(gf_sins_state_check(&s) == GF_OK, "state check of a good state");
    gf_sins_state bad = s, before;
    bad.lat_rad = lat_tester;
    before = bad;
    CHECK(gf_sins_step(&bad, dth, dv, 0.01, NAN) == GF_ERR_BAD_PARAMETER && state_same(&bad, &before),
          "a state beyond the limit: BAD_PARAMETER, unchanged");
    CHECK(gf_sins_state_check(&bad) == GF_ERR_BAD_PARAMETER, "state check: latitude beyond the limit");
    const struct { const char *what; size_t off; int ivalue; double dvalue; } scrambles[] = {
        {"input 7", offsetof(gf_sins_state, cfg.input), 7, 0},
        {"vertical -1", offsetof(gf_sins_state, cfg.vertical), -1, 0},
        {"earth 2", offsetof(gf_sins_state, cfg.earth), 2, 0},
        {"coning 3", offsetof(gf_sins_state, cfg.coning), 3, 0},
        {"cos_lat 0", offsetof(gf_sins_state, cos_lat), 0, 0.0},
        {"R_M NaN", offsetof(gf_sins_state, R_M_m), 0, NAN},
        {"prev_gyro Inf", offsetof(gf_sins_state, prev_gyro), 0, INFINITY},
        {"earth-rate sign 0.5", offsetof(gf_sins_state, earth_rate_sign), 0, 0.5},
    };
    for (size_t i = 0; i < sizeof scrambles / sizeof scrambles[0]; ++i) {
        bad = s;
        if (i < 4)
            memcpy((char *)&bad + scrambles[i].off, &scrambles[i].ivalue, sizeof(int));
        else
            memcpy((char *)&bad + scrambles[i].off, &scrambles[i].dvalue, sizeof(double));
        CHECK(gf_sins_state_check(&bad) == GF_ERR_BAD_PARAMETER, "state check: %s", scrambles[i].what);
        before = bad;
        const gf_status sst = gf_sins_step(&bad, dth, dv, 0.01, NAN);
        CHECK(sst != GF_OK && memcmp(&bad, &before, sizeof bad) == 0,
              "step with %s: status %d (not OK), state unchanged", scrambles[i].what, (int)sst);
    }
    /* More than a turn of longitude in one step (an absurd 6e9 m/s east on the equator,
     * where nothing else diverges: w_in x v is vertical, the height is held): the
     * longitude is still reported in (-pi, pi]; before, one subtraction of 2 pi left
     * lon0 + 9.4 rad at 6.1 rad. */
    const double vfast[3] = {6e9, 0.0, 0.0};
    CHECK(gf_sins_init(&s, &cfg, q0, vfast, 0.0, 3.0, 0.0, 0.0) == GF_OK, "init on the equator");
    const gf_status sf = gf_sins_step(&s, dth, dv, 0.01, NAN);
    double RM, RN;
    ref_radii(0.0, &RM, &RN);
    const double want = remainder(3.0 + 0.01 * 6e9 / RN, 2 * PI);
    CHECK(sf == GF_OK && s.lon_rad > -PI && s.lon_rad <= PI,
          "a step of %.3g rad of longitude: status %d, longitude %.6g rad in (-pi, pi]", 0.01 * 6e9 / RN,
          (int)sf, s.lon_rad);
    /* the east velocity changes by ~0.5 m/s of 6e9 through the rotation compensation */
    CHECK_CLOSE(s.lon_rad, want, 1e-8, "the longitude is the wrapped one");
}

/* A quaternion within the accepted 1e-6 of unit norm: Euler angles of the rotation it
 * stands for. Unnormalised, C[2][1] = |q|^2 sin(theta) exceeded 1 near pitch 90 deg and
 * was clipped: pitch 90 deg instead of 89.9 and the roll folded into the heading. */
static void test_euler_of_unnormalised_quaternion(void)
{
    const double e[3] = {0.3, 89.9 * DEG, 0.2};
    double qr[4];
    ref_quat_euler(e, qr);
    const double scales[4] = {1.0 + 9e-7, 1.0 - 9e-7, 1.0 + 1e-7, 1.0 - 3e-7};
    for (int i = 0; i < 4; ++i) {
        double q[4], back[3];
        for (int k = 0; k < 4; ++k)
            q[k] = qr[k] * scales[i];
        CHECK(gf_quat_to_euler(q, back) == GF_OK, "|q| = %.9g accepted", scales[i]);
        /* as the random round trip: 32 eps / cos(theta) */
        const double tol = 32 * EPS / cos(e[1]);
        CHECK(fabs(back[0] - e[0]) <= tol && fabs(back[1] - e[1]) <= tol && fabs(back[2] - e[2]) <= tol,
              "|q| = %.9g: angles (%.12g %.12g %.12g), expected (%.12g %.12g %.12g)", scales[i], back[0],
              back[1], back[2], e[0], e[1], e[2]);
    }
    double q[4];
    for (int k = 0; k < 4; ++k)
        q[k] = qr[k] * (1.0 + 2e-6);
    double back[3];
    CHECK(gf_quat_to_euler(q, back) == GF_ERR_BAD_PARAMETER, "|q| = 1 + 2e-6 refused");
}

/* Rate input: the first sample only starts the record. */
static void test_rate_first_sample(void)
{
    gf_sins_state s, r;
    init_moving(&s, GF_SINS_INPUT_RATES, 1, GF_SINS_VERTICAL_FREE, 7.0);
    r = s;
    const double w[3] = {0.1, -0.2, 0.3}, f[3] = {0.5, 0.2, 9.7};
    CHECK(gf_sins_step(&s, w, f, 0.01, NAN) == GF_OK, "first rate sample");
    CHECK(memcmp(s.q_bn, r.q_bn, sizeof s.q_bn) == 0 && memcmp(s.v_n_m_s, r.v_n_m_s, sizeof s.v_n_m_s) == 0 &&
              s.lat_rad == r.lat_rad && s.lon_rad == r.lon_rad && s.h_m == r.h_m && s.time_s == 7.0 &&
              memcmp(s.a_n_m_s2, r.a_n_m_s2, sizeof s.a_n_m_s2) == 0 && s.baro_accel_m_s2 == r.baro_accel_m_s2,
          "first rate sample: navigation state and time unchanged");
    CHECK(s.have_prev == 1 && s.n_samples == 1 && memcmp(s.prev_gyro, w, sizeof w) == 0 &&
              memcmp(s.prev_accel, f, sizeof f) == 0,
          "first rate sample: kept as the start of the record");
    /* the second sample integrates the interval: time advances by dt, and the attitude
     * turns by the body rotation |w| dt */
    CHECK(gf_sins_step(&s, w, f, 0.01, NAN) == GF_OK && s.time_s == 7.0 + 0.01, "second rate sample: time + dt");
    const double ang = quat_angle(s.q_bn, r.q_bn), wdt = 0.01 * sqrt(0.14);
    /* body rotation |w| dt = 3.7e-3 rad, give or take the navigation-frame rotation
     * (Earth and transport rates, 7.6e-5 rad/s x 0.01 s = 7.6e-7 rad) */
    CHECK(fabs(ang - wdt) <= 1e-6, "second rate sample: attitude turned by |w| dt (%.6g vs %.6g rad)", ang, wdt);
    /* in a run, the first row is the unchanged state */
    gf_sins_state u = r;
    double qo[8], vo[6], po[6], to[2];
    const double ws[6] = {0.1, -0.2, 0.3, 0.1, -0.2, 0.3}, fs[6] = {0.5, 0.2, 9.7, 0.5, 0.2, 9.7};
    size_t done = 0;
    CHECK(gf_sins_run(&u, 2, ws, fs, 0.01, NULL, NULL, 0, qo, vo, po, to, &done) == GF_OK && done == 2 &&
              memcmp(qo, r.q_bn, sizeof r.q_bn) == 0 && to[0] == 7.0 && to[1] == 7.0 + 0.01 && state_same(&u, &s),
          "rate run: row 0 = initial state, row 1 = one interval later");
}

/* ======================================================================================
 * Subsamples (cfg.subsamples = N: one navigation update per N increments)
 * ==================================================================================== */

/* A sample of a tumbling, accelerating body (any non-degenerate increments will do:
 * coning and sculling terms are all non-zero). */
static void sub_sample(size_t k, double g[3], double a[3])
{
    const double t = 0.01 * (double)k;
    g[0] = 1e-3 * sin(3.0 * t) + 2e-4; g[1] = 2e-3 * cos(2.0 * t); g[2] = 5e-4 * sin(5.0 * t + 1.0);
    a[0] = 0.02 * cos(4.0 * t); a[1] = 0.01 * sin(t) + 0.003; a[2] = 0.098 + 0.001 * sin(7.0 * t);
}

/* The published m-subsample formulas (gf_sins.h; Savage's 2/3 for two samples, the
 * optimised 3- and 4-sample sets), typed here independently of the core: phi and dv_b. */
static void sub_formula(int m, const double *g, const double *a, double phi[3], double dvb[3])
{
    static const double k2[1] = {2.0 / 3.0}, k3[2] = {0.45, 1.35},
                        k4[3] = {18.0 / 35.0, 92.0 / 105.0, 214.0 / 105.0};
    const double *k = m == 2 ? k2 : m == 3 ? k3 : k4;
    double th[3] = {0, 0, 0}, V[3] = {0, 0, 0}, cg[3] = {0, 0, 0}, ca[3] = {0, 0, 0};
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < 3; ++j) {
            th[j] += g[3 * i + j];
            V[j] += a[3 * i + j];
            if (i < m - 1) {
                cg[j] += k[i] * g[3 * i + j];
                ca[j] += k[i] * a[3 * i + j];
            }
        }
    const double *gl = g + 3 * (m - 1), *al = a + 3 * (m - 1);
#define CROSS(u, v, i) ((u)[((i) + 1) % 3] * (v)[((i) + 2) % 3] - (u)[((i) + 2) % 3] * (v)[((i) + 1) % 3])
    for (int i = 0; i < 3; ++i) {
        phi[i] = th[i] + CROSS(cg, gl, i);
        dvb[i] = V[i] + 0.5 * CROSS(th, V, i) + CROSS(cg, al, i) + CROSS(ca, gl, i);
    }
#undef CROSS
}

static void test_subsample_formulas(void)
{
    /* Fixed frame without gravity, identity attitude, at rest: one update gives
     * q = q(phi) and v = dv_b exactly as the formulas say. q(phi) is taken with libm's
     * sin/cos here; the core's series agrees to 1e-19 below 0.1 rad, so the check is
     * round-off: a few ulp (bound 8 eps). Dropping or mistyping any coefficient moves
     * phi or dv_b by >= 1e-9 (the cross terms here are ~1e-6). */
    for (int m = 2; m <= GF_SINS_MAX_SUBSAMPLES; ++m) {
        gf_sins_config c;
        gf_sins_config_default(&c);
        c.earth = GF_SINS_EARTH_FLAT;
        c.subsamples = m;
        const double q0[4] = {1, 0, 0, 0}, v0[3] = {0, 0, 0};
        double g[12], a[12];
        for (int i = 0; i < m; ++i)
            sub_sample((size_t)(40 + 7 * i), g + 3 * i, a + 3 * i);
        double phi[3], dvb[3];
        sub_formula(m, g, a, phi, dvb);
        const double ang = sqrt(phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]);
        const double qe[4] = {cos(0.5 * ang), sin(0.5 * ang) / ang * phi[0],
                              sin(0.5 * ang) / ang * phi[1], sin(0.5 * ang) / ang * phi[2]};
        for (int api = 0; api < 2; ++api) { /* gf_sins_step_group and gf_sins_run */
            gf_sins_state s;
            CHECK(gf_sins_init(&s, &c, q0, v0, 0.0, 0.0, 0.0, 0.0) == GF_OK, "subsample init");
            double q[4], v[3], pos[3], t;
            size_t done = 0;
            if (api == 0) {
                CHECK(gf_sins_step_group(&s, (size_t)m, g, a, 0.01 * m, NAN) == GF_OK, "step_group");
                memcpy(q, s.q_bn, sizeof q);
                memcpy(v, s.v_n_m_s, sizeof v);
                t = s.time_s;
            } else {
                CHECK(gf_sins_run(&s, (size_t)m, g, a, 0.01, NULL, NULL, 0, q, v, pos, &t, &done) == GF_OK &&
                      done == (size_t)m, "run of one group");
            }
            double dq = 0.0, dv = 0.0;
            for (int i = 0; i < 4; ++i)
                dq = fmax(dq, fabs(q[i] - qe[i]));
            for (int i = 0; i < 3; ++i)
                dv = fmax(dv, fabs(v[i] - dvb[i]));
            CHECK(dq <= 8 * EPS && dv <= 8 * EPS * 0.3, "m = %d (%s): q off %.3g, v off %.3g", m,
                  api ? "run" : "step_group", dq, dv);
            CHECK(fabs(t - 0.01 * m) <= 4 * EPS, "m = %d: time %.17g", m, t);
            CHECK(s.n_samples == (uint64_t)m && s.have_prev == 1 &&
                  memcmp(s.prev_gyro, g + 3 * (m - 1), sizeof s.prev_gyro) == 0,
                  "m = %d: the last sample is kept as the previous one", m);
        }
    }
}

static void test_subsample_config_and_errors(void)
{
    gf_sins_config c;
    gf_sins_config_default(&c);
    CHECK(c.subsamples == 1, "default subsamples %d", c.subsamples);
    const double q0[4] = {1, 0, 0, 0}, v0[3] = {0, 0, 0};
    gf_sins_state s;
    for (int bad = -1; bad <= 6; ++bad) {
        if (bad >= 1 && bad <= 4)
            continue;
        c.subsamples = bad;
        CHECK(gf_sins_init(&s, &c, q0, v0, 0.5, 0.1, 0.0, 0.0) == GF_ERR_BAD_PARAMETER,
              "subsamples = %d refused", bad);
    }
    c.subsamples = 2;
    c.input = GF_SINS_INPUT_RATES;
    CHECK(gf_sins_init(&s, &c, q0, v0, 0.5, 0.1, 0.0, 0.0) == GF_ERR_BAD_PARAMETER,
          "rates with subsamples 2 refused");
    c.input = GF_SINS_INPUT_INCREMENTS;
    CHECK(gf_sins_init(&s, &c, q0, v0, 0.5, 0.1, 0.0, 0.0) == GF_OK, "subsamples 2 init");
    CHECK(gf_sins_state_check(&s) == GF_OK, "state check with subsamples 2");
    const gf_sins_state s0 = s;
    double g[3 * 8], a[3 * 8];
    for (size_t k = 0; k < 8; ++k)
        sub_sample(k, g + 3 * k, a + 3 * k);
    /* gf_sins_step: one sample is not an update with N = 2 */
    CHECK(gf_sins_step(&s, g, a, 0.01, NAN) == GF_ERR_BAD_PARAMETER && state_same(&s, &s0),
          "gf_sins_step refuses subsamples 2, state unchanged");
    CHECK(gf_sins_step_group(&s, 0, g, a, 0.01, NAN) == GF_ERR_BAD_PARAMETER &&
          gf_sins_step_group(&s, 5, g, a, 0.01, NAN) == GF_ERR_BAD_PARAMETER &&
          gf_sins_step_group(NULL, 2, g, a, 0.01, NAN) == GF_ERR_NULL_POINTER &&
          gf_sins_step_group(&s, 2, g, a, 0.0, NAN) == GF_ERR_BAD_TIME && state_same(&s, &s0),
          "step_group argument errors, state unchanged");
    /* a state whose subsamples was damaged is refused */
    gf_sins_state dam = s0;
    dam.cfg.subsamples = 9;
    CHECK(gf_sins_state_check(&dam) == GF_ERR_BAD_PARAMETER, "damaged subsamples refused");
    double q[4 * 8], v[3 * 8], pos[3 * 8], t[8];
    size_t done = 99;
    CHECK(gf_sins_run(&dam, 8, g, a, 0.01, NULL, NULL, 0, q, v, pos, t, &done) ==
              GF_ERR_BAD_PARAMETER && done == 0, "run refuses the damaged state");
    /* a bad sample inside the third group: two updates done (4 samples), their rows
     * valid, the state after them (bitwise that of a 4-sample run), the group not applied */
    const double keep = a[3 * 5 + 1];
    a[3 * 5 + 1] = NAN;
    s = s0;
    CHECK(gf_sins_run(&s, 8, g, a, 0.01, NULL, NULL, 0, q, v, pos, t, &done) ==
              GF_ERR_NONFINITE_INPUT && done == 4, "NaN in sample 5: done %zu", done);
    gf_sins_state r = s0;
    double q2[4 * 2], v2[3 * 2], pos2[3 * 2], t2[2];
    CHECK(gf_sins_run(&r, 4, g, a, 0.01, NULL, NULL, 0, q2, v2, pos2, t2, &done) == GF_OK &&
          done == 4 && state_same(&s, &r) && memcmp(q, q2, sizeof q2) == 0 && memcmp(t, t2, sizeof t2) == 0,
          "state and rows after the failure equal a run of the good groups");
    a[3 * 5 + 1] = keep;
    /* out of range: one sample beyond max_rate * dt */
    g[3 * 6] = 0.6; /* 60 rad/s over 0.01 s */
    s = s0;
    CHECK(gf_sins_run(&s, 8, g, a, 0.01, NULL, NULL, 0, q, v, pos, t, &done) == GF_ERR_OUT_OF_RANGE &&
          done == 6, "out-of-range sample 6: done %zu", done);
    sub_sample(6, g + 18, a + 18);
    /* times: a non-increasing sub-interval inside a group is refused */
    double ts[8];
    for (int k = 0; k < 8; ++k)
        ts[k] = 0.01 * (k + 1);
    ts[3] = ts[2];
    s = s0;
    CHECK(gf_sins_run(&s, 8, g, a, 0.0, ts, NULL, 0, q, v, pos, t, &done) == GF_ERR_BAD_TIME &&
          done == 2, "repeated time in group 1: done %zu", done);
}

/* Batch = groups stepped by hand (bitwise), the short last group, rows and times, pieces
 * cut at multiples of N, and the forward -> backward round trip. */
static void test_subsample_run(void)
{
    enum { n = 403 };
    static double g[3 * n], a[3 * n], q[4 * n], v[3 * n], pos[3 * n], t[n], ts[n];
    for (size_t k = 0; k < n; ++k) {
        sub_sample(k, g + 3 * k, a + 3 * k);
        a[3 * k + 2] += 9.79 * 0.01; /* on the Earth: about 1 g up */
        ts[k] = 0.01 * (double)(k + 1);
    }
    const double q0[4] = {0.9, 0.1, -0.2, 0.3}, v0[3] = {3.0, -2.0, 0.1};
    for (int N = 2; N <= GF_SINS_MAX_SUBSAMPLES; ++N) {
        gf_sins_config c;
        gf_sins_config_default(&c);
        c.subsamples = N;
        gf_sins_state s, h;
        CHECK(gf_sins_init(&s, &c, q0, v0, 0.6, 2.0, 50.0, 0.0) == GF_OK, "init N=%d", N);
        h = s;
        const gf_sins_state s0 = s;
        size_t done = 0;
        CHECK(gf_sins_run(&s, n, g, a, 0.01, NULL, NULL, 0, q, v, pos, t, &done) == GF_OK && done == n,
              "N = %d run", N);
        const size_t rows = (n + (size_t)N - 1) / (size_t)N;
        int same = 1;
        for (size_t j = 0; j < rows; ++j) {
            const size_t m = n - j * (size_t)N < (size_t)N ? n - j * (size_t)N : (size_t)N;
            if (gf_sins_step_group(&h, m, g + 3 * j * (size_t)N, a + 3 * j * (size_t)N, 0.01 * (double)m,
                                   NAN) != GF_OK)
                same = 0;
            same = same && memcmp(q + 4 * j, h.q_bn, sizeof h.q_bn) == 0 &&
                   memcmp(v + 3 * j, h.v_n_m_s, sizeof h.v_n_m_s) == 0 && pos[3 * j] == h.lat_rad &&
                   fabs(t[j] - h.time_s) <= 1e-12;
        }
        CHECK(same && state_same(&s, &h), "N = %d: batch = groups stepped (%zu rows)", N, rows);
        CHECK(fabs(t[rows - 1] - 0.01 * n) <= 1e-11 && s.n_samples == n,
              "N = %d: last row at the last sample's time (%.15g)", N, t[rows - 1]);
        /* pieces cut at multiples of N (and the times) give the same result as one call */
        gf_sins_state p = s0, w = s0;
        static double qp[4 * n], vp[3 * n], pp[3 * n], tp[n];
        CHECK(gf_sins_run(&w, n, g, a, 0.0, ts, NULL, 0, q, v, pos, t, &done) == GF_OK, "times run");
        const size_t cut = 10 * (size_t)N;
        CHECK(gf_sins_run(&p, cut, g, a, 0.0, ts, NULL, 0, qp, vp, pp, tp, &done) == GF_OK &&
              gf_sins_run(&p, n - cut, g + 3 * cut, a + 3 * cut, 0.0, ts + cut, NULL, 0, qp + 40,
                          vp + 30, pp + 30, tp + 10, &done) == GF_OK,
              "two pieces");
        CHECK(state_same(&p, &w) && memcmp(qp, q, 4 * rows * sizeof *q) == 0,
              "N = %d: pieces at a multiple of N = one call", N);
        /* round trip: reverse, same record backward; the groups are the same samples.
         * The residual is the difference of two truncation errors: the reversed group
         * (-dtheta_N .. -dtheta_1) is not the forward one backwards, and the sets,
         * exact for linearly varying rates (sum k_i (N - i) = N^3/12), leave
         * O(|w| |w''| T^4) per update for this tumbling record (|w| ~ 0.2 rad/s,
         * |w''| ~ 1 rad/s^3), growing with T = N h; with coning off the same round trip
         * closes to 4e-10 rad for every N. Measured (attitude rad, position m, height m,
         * velocity m/s): N = 2: 2.4e-9, 2.6e-6, 1.8e-6, 6.1e-7; N = 3: 3.4e-8, 1.6e-5,
         * 1.0e-5, 3.0e-6; N = 4: 1.05e-7, 4.4e-5, 2.8e-5, 7.9e-6. Bounds: 2x those;
         * time to round-off. */
        static const double lim[5][4] = {{0}, {0}, {4.8e-9, 5.2e-6, 3.6e-6, 1.2e-6},
                                         {6.8e-8, 3.2e-5, 2.1e-5, 6.1e-6},
                                         {2.1e-7, 8.8e-5, 5.6e-5, 1.6e-5}};
        CHECK(gf_sins_reverse(&s) == GF_OK, "reverse");
        CHECK(gf_sins_run(&s, n, g, a, 0.01, NULL, NULL, 1, q, v, pos, t, &done) == GF_OK && done == n,
              "N = %d backward", N);
        const double dq = quat_angle(s.q_bn, s0.q_bn);
        const double dp = fabs(s.lat_rad - s0.lat_rad) * 6.4e6 + fabs(s.lon_rad - s0.lon_rad) * 6.4e6;
        double dv = 0.0;
        for (int i = 0; i < 3; ++i)
            dv = fmax(dv, fabs(-s.v_n_m_s[i] - v0[i]));
        printf("  subsamples N = %d, %d samples forward and back: attitude %.3g rad, position %.3g m, "
               "height %.3g m, velocity %.3g m/s, time %.3g s\n", N, n, dq, dp, fabs(s.h_m - 50.0), dv,
               s.time_s);
        CHECK(dq < lim[N][0] && dp < lim[N][1] && fabs(s.h_m - 50.0) < lim[N][2] && dv < lim[N][3] &&
              fabs(s.time_s) < 1e-12,
              "N = %d round trip", N);
        /* backward rows: row j = the state at the start of group j: row 0 at t = 0 */
        CHECK(fabs(t[0]) < 1e-12 && fabs(t[1] - 0.01 * N) < 1e-12 && pos[0] == s.lat_rad,
              "N = %d backward rows at the groups' starts", N);
    }
}

int main(void)
{
    test_earth_published_values();
    test_earth_against_reference();
    test_earth_errors();
    test_euler_conventions();
    test_config_and_init();
    test_stationary();
    test_parallel();
    test_spin_about_up(GF_SINS_INPUT_INCREMENTS);
    test_spin_about_up(GF_SINS_INPUT_RATES);
    test_spin_tilted(GF_SINS_INPUT_INCREMENTS);
    test_spin_tilted(GF_SINS_INPUT_RATES);
    test_baro_loop(10.0, 120.0);
    test_baro_loop(100.0, 1000.0);
    test_batch_equals_steps();
    test_rate_run_chunking_with_times();
    test_interleaved_states();
    test_reverse_roundtrip(GF_SINS_INPUT_INCREMENTS);
    test_reverse_roundtrip(GF_SINS_INPUT_RATES);
    test_double_reverse();
    test_step_errors();
    test_run_errors();
    test_pole_divergence();
    test_latitude_limit();
    test_euler_of_unnormalised_quaternion();
    test_rate_first_sample();
    test_subsample_formulas();
    test_subsample_config_and_errors();
    test_subsample_run();
    TEST_MAIN_END();
}
