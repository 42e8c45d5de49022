/* test_accel_array.c — forward model and 9-accelerometer solver (seed 000).
 *
 * Truth: the sensor outputs are computed here independently of the code under test,
 * with the identity omega x (omega x u) = omega (omega . u) - |omega|^2 u, from
 * randomly drawn f, omega, omega_dot. Round-off tolerances: every solved quantity is a
 * sum of at most 6 outputs of magnitude <= S, divided by at most 2 l, so its error is
 * below ~16 eps S / l; we allow 64 eps S / l. A rate from omega^2 divides that by 2|omega|. */
#include <float.h>
#include <string.h>

#include "base/gf_math.h"
#include "gyrofree/gf9.h"
#include "gyrofree/gf_array.h"
#include "gf_test.h"

static void independent_output(const double u[3], const double th[3], const double f[3],
                               const double w[3], const double wd[3], double *A)
{
    double wdxu[3];
    gf_v3_cross(wd, u, wdxu);
    const double wu = gf_v3_dot(w, u), ww = gf_v3_dot(w, w);
    double a[3];
    for (int k = 0; k < 3; ++k)
        a[k] = f[k] + wdxu[k] + w[k] * wu - ww * u[k];
    *A = th[0] * a[0] + th[1] * a[1] + th[2] * a[2];
}

static void random_v3(test_rng *r, double lo, double hi, double v[3])
{
    for (int k = 0; k < 3; ++k)
        v[k] = test_rng_uniform(r, lo, hi);
}

static void test_geometry_table(void)
{
    gf_array_geometry g;
    CHECK(gf9_geometry(0.1, &g) == GF_OK, "gf9_geometry(0.1)");
    const double s = 1.0 / sqrt(2.0);
    /* seed 000, section 1 (with u_7..u_9 = l[...]) */
    const double u[9][3] = {{.1, 0, 0}, {0, .1, 0}, {0, 0, .1}, {-.1, 0, 0}, {0, -.1, 0},
                            {0, 0, -.1}, {.1, -.1, 0}, {.1, 0, -.1}, {0, .1, -.1}};
    const double t[9][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0},
                            {0, 0, -1}, {s, s, 0}, {s, 0, s}, {0, s, s}};
    CHECK(g.n_sensors == 9, "nine sensors");
    for (int i = 0; i < 9; ++i)
        for (int k = 0; k < 3; ++k) {
            CHECK_CLOSE(g.u_m[i][k], u[i][k], 1e-17, "u_i");
            CHECK_CLOSE(g.theta[i][k], t[i][k], 1e-16, "theta_i");
        }
    CHECK(gf9_geometry(0.0, &g) == GF_ERR_BAD_PARAMETER, "l = 0 rejected");
    CHECK(gf9_geometry(-1.0, &g) == GF_ERR_BAD_PARAMETER, "l < 0 rejected");
    CHECK(gf9_geometry(NAN, &g) == GF_ERR_BAD_PARAMETER, "l = NaN rejected");
    CHECK(gf9_geometry(INFINITY, &g) == GF_ERR_BAD_PARAMETER, "l = Inf rejected");
    CHECK(gf9_geometry(0.1, NULL) == GF_ERR_NULL_POINTER, "NULL geometry rejected");
}

static void test_forward_random_geometry(void)
{
    test_rng rng = {12345};
    enum { N = 17, SAMPLES = 50 };
    double u[N * 3], th[N * 3];
    for (int i = 0; i < N; ++i) {
        random_v3(&rng, -0.3, 0.3, u + 3 * i);
        random_v3(&rng, -1, 1, th + 3 * i);
        const double n = gf_v3_norm(th + 3 * i);
        gf_v3_scale(th + 3 * i, 1.0 / n, th + 3 * i);
    }
    gf_array_geometry g;
    CHECK(gf_array_geometry_set(&g, N, u, th, NULL) == GF_OK, "random geometry accepted");
    double f[SAMPLES * 3], w[SAMPLES * 3], wd[SAMPLES * 3], A[SAMPLES * N];
    for (int k = 0; k < SAMPLES; ++k) {
        random_v3(&rng, -20, 20, f + 3 * k);
        random_v3(&rng, -5, 5, w + 3 * k);
        random_v3(&rng, -10, 10, wd + 3 * k);
    }
    size_t done = 99;
    CHECK(gf_array_forward(&g, SAMPLES, f, w, wd, A, &done) == GF_OK && done == SAMPLES,
          "forward batch");
    for (int k = 0; k < SAMPLES; ++k)
        for (int i = 0; i < N; ++i) {
            double ref;
            independent_output(u + 3 * i, th + 3 * i, f + 3 * k, w + 3 * k, wd + 3 * k, &ref);
            /* |terms| <= 20 + 10*0.5 + 25*0.5*2: a few ulp of ~60 */
            CHECK_CLOSE(A[k * N + i], ref, 64 * DBL_EPSILON * 60, "forward model = independent");
        }
    /* a NaN in sample 7 stops the run there */
    w[7 * 3 + 1] = NAN;
    CHECK(gf_array_forward(&g, SAMPLES, f, w, wd, A, &done) == GF_ERR_NONFINITE_INPUT && done == 7,
          "forward: NaN in sample 7 reported at 7 (got %zu)", done);
}

static void test_geometry_errors(void)
{
    gf_array_geometry g;
    double u[6] = {0.1, 0, 0, 0, 0.1, 0};
    double th[6] = {1, 0, 0, 0, 0, 0};
    size_t bad = 99;
    CHECK(gf_array_geometry_set(&g, 2, u, th, &bad) == GF_ERR_SINGULAR_GEOMETRY && bad == 1,
          "zero direction of sensor 1 reported");
    th[4] = 1.1;
    CHECK(gf_array_geometry_set(&g, 2, u, th, &bad) == GF_ERR_BAD_PARAMETER && bad == 1,
          "non-unit direction reported");
    th[4] = 1.0;
    u[0] = INFINITY;
    CHECK(gf_array_geometry_set(&g, 2, u, th, &bad) == GF_ERR_NONFINITE_INPUT && bad == 0,
          "infinite position reported");
    u[0] = 0.1;
    CHECK(gf_array_geometry_set(&g, 0, u, th, &bad) == GF_ERR_BAD_SIZE, "zero sensors");
    CHECK(gf_array_geometry_set(&g, GF_ARRAY_MAX_SENSORS + 1, u, th, &bad) == GF_ERR_BAD_SIZE,
          "too many sensors");
    CHECK(gf_array_geometry_set(&g, 2, u, th, &bad) == GF_OK, "valid geometry");
}

/* A smooth motion whose rate components stay away from zero except through crossings
 * slow enough for the trapezoid sign propagation. */
static void motion(double t, double f[3], double w[3], double wd[3])
{
    f[0] = 1.0 + sin(0.7 * t);
    f[1] = -2.0 + 0.5 * cos(1.3 * t);
    f[2] = 9.8 + 0.2 * sin(0.3 * t);
    w[0] = 0.8 * sin(0.5 * t);          /* crosses zero at t = 2 pi k */
    w[1] = 1.5 + 0.3 * cos(0.9 * t);
    w[2] = -2.0 + 0.1 * t;
    wd[0] = 0.4 * cos(0.5 * t);
    wd[1] = -0.27 * sin(0.9 * t);
    wd[2] = 0.1;
}

static void test_solver_recovers_truth(void)
{
    const double l = 0.1, dt = 0.01;
    gf_array_geometry g;
    gf9_geometry(l, &g);
    enum { SAMPLES = 2000 };
    static double A[SAMPLES * 9], F[SAMPLES * 3], W[SAMPLES * 3], WD[SAMPLES * 3];
    static double f[SAMPLES * 3], w[SAMPLES * 3], wd[SAMPLES * 3], wsq[SAMPLES * 3];
    static uint8_t flags[SAMPLES];
    for (int k = 0; k < SAMPLES; ++k) {
        motion(k * dt, F + 3 * k, W + 3 * k, WD + 3 * k);
        for (int i = 0; i < 9; ++i)
            independent_output(g.u_m[i], g.theta[i], F + 3 * k, W + 3 * k, WD + 3 * k, &A[9 * k + i]);
    }
    gf9_state st;
    /* omega_init = the true rate at t = 0 (w_x = 0 there: its sign is irrelevant) */
    double w0[3], f0[3], wd0[3];
    motion(0.0, f0, w0, wd0);
    CHECK(gf9_init(&st, l, w0) == GF_OK, "init");
    size_t done = 0;
    CHECK(gf9_solve(&st, SAMPLES, A, dt, f, w, wd, wsq, flags, &done) == GF_OK && done == SAMPLES,
          "batch solve");
    double max_err_w = 0.0;
    int n_flagged = 0;
    for (int k = 0; k < SAMPLES; ++k) {
        double S = 0.0;
        for (int i = 0; i < 9; ++i)
            S = fmax(S, fabs(A[9 * k + i]));
        const double tol_lin = 64 * DBL_EPSILON * S / l;
        for (int j = 0; j < 3; ++j) {
            CHECK_CLOSE(f[3 * k + j], F[3 * k + j], 64 * DBL_EPSILON * S, "f (eq. 3)");
            CHECK_CLOSE(wsq[3 * k + j], W[3 * k + j] * W[3 * k + j], tol_lin, "omega^2 (eq. 4)");
            CHECK_CLOSE(wd[3 * k + j], WD[3 * k + j], tol_lin, "omega_dot (eq. 6)");
            const double true_w = W[3 * k + j];
            if (fabs(true_w) > 1e-3) {
                CHECK_CLOSE(w[3 * k + j], true_w, tol_lin / (2 * fabs(true_w)) + 1e-15,
                            "omega (eq. 4 magnitude, eq. 6 sign)");
                max_err_w = fmax(max_err_w, fabs(w[3 * k + j] - true_w));
            }
        }
        n_flagged += flags[k] != 0;
    }
    /* near the zero crossings of w_x, w_x^2 may round to a tiny negative number; the
     * policy then keeps the propagated rate and flags it: allow a handful */
    CHECK(n_flagged <= 10, "at most a few flagged samples on noise-free data (got %d)", n_flagged);
    printf("noise-free 9-accelerometer solve: max |omega error| = %.3g rad/s (|w| > 1e-3)\n",
           max_err_w);

    /* the state after the batch equals the state after stepping sample by sample */
    gf9_state st2;
    gf9_init(&st2, l, w0);
    gf9_output o;
    int same = 1;
    for (int k = 0; k < SAMPLES; ++k) {
        CHECK(gf9_step(&st2, A + 9 * k, dt, &o) == GF_OK, "step %d", k);
        same &= memcmp(o.omega_rad_s, w + 3 * k, sizeof o.omega_rad_s) == 0;
        same &= memcmp(o.f_m_s2, f + 3 * k, sizeof o.f_m_s2) == 0;
        same &= (uint8_t)o.flags == flags[k];
    }
    CHECK(same, "step-by-step results are bitwise equal to the batch");
    CHECK(memcmp(&st, &st2, sizeof st) == 0, "states equal after batch and steps");
}

static void test_negative_omega_sq_policy(void)
{
    const double l = 0.1;
    gf_array_geometry g;
    gf9_geometry(l, &g);
    const double F[3] = {0, 0, 9.8}, W[3] = {0.0, 1.0, 2.0}, WD[3] = {0.5, 0, 0};
    double A[9];
    for (int i = 0; i < 9; ++i)
        independent_output(g.u_m[i], g.theta[i], F, W, WD, &A[i]);
    /* noise on A1 and A4 of +1e-4 m/s^2 each: omega_x^2 += 2e-4/(4l) = 5e-4 -> positive;
     * -1e-4 each: omega_x^2 = -5e-4 -> negative -> propagated, flagged. */
    gf9_state st;
    const double w0[3] = {0.01, 1.0, 2.0};
    gf9_init(&st, l, w0);
    gf9_output o;
    A[0] -= 1e-4;
    A[3] -= 1e-4;
    CHECK(gf9_step(&st, A, 0.01, &o) == GF_OK, "step");
    CHECK(o.omega_sq_rad2_s2[0] < 0, "omega_x^2 driven negative (%g)", o.omega_sq_rad2_s2[0]);
    CHECK(o.flags == GF9_FLAG_NEG_OMEGA_SQ_X, "flag NEG_OMEGA_SQ_X only (flags %u)", o.flags);
    CHECK(o.omega_rad_s[0] == w0[0], "first sample: propagated rate is omega_init (%g)",
          o.omega_rad_s[0]);
    CHECK(isfinite(o.omega_rad_s[0]), "never NaN");
    /* next sample: propagated by the trapezoid of omega_dot */
    gf9_output o2;
    CHECK(gf9_step(&st, A, 0.01, &o2) == GF_OK, "step 2");
    const double expect = w0[0] + 0.5 * 0.01 * (o.omega_dot_rad_s2[0] + o2.omega_dot_rad_s2[0]);
    CHECK_CLOSE(o2.omega_rad_s[0], expect, 1e-15, "propagated with trapezoidal omega_dot");

    /* unknown sign: predicted exactly zero and omega^2 > 0 -> positive, flagged */
    gf9_state s0;
    const double zero[3] = {0, 1, 2};
    gf9_init(&s0, l, zero);
    A[0] += 2e-4;
    A[3] += 2e-4;  /* omega_x^2 = +5e-4 */
    CHECK(gf9_step(&s0, A, 0.01, &o) == GF_OK, "step");
    CHECK(o.flags == GF9_FLAG_SIGN_UNKNOWN_X && o.omega_rad_s[0] > 0,
          "sign unknown flagged, positive taken (flags %u, w %g)", o.flags, o.omega_rad_s[0]);
}

static void test_solver_errors(void)
{
    gf9_state st;
    const double w0[3] = {0, 0, 0};
    CHECK(gf9_init(&st, 0.0, w0) == GF_ERR_BAD_PARAMETER, "l = 0");
    CHECK(gf9_init(&st, -0.1, w0) == GF_ERR_BAD_PARAMETER, "l < 0");
    CHECK(gf9_init(&st, NAN, w0) == GF_ERR_BAD_PARAMETER, "l NaN");
    const double wnan[3] = {0, NAN, 0};
    CHECK(gf9_init(&st, 0.1, wnan) == GF_ERR_BAD_PARAMETER, "omega_init NaN");
    CHECK(gf9_init(NULL, 0.1, w0) == GF_ERR_NULL_POINTER, "NULL state");
    CHECK(gf9_init(&st, 0.1, NULL) == GF_OK, "omega_init NULL = zero");

    double A[3 * 9];
    for (int i = 0; i < 27; ++i)
        A[i] = 0.01 * i;
    double f[9], w[9], wd[9], wsq[9];
    uint8_t fl[3];
    size_t done = 99;
    CHECK(gf9_solve(&st, 3, A, 0.0, f, w, wd, wsq, fl, &done) == GF_ERR_BAD_PARAMETER && done == 0,
          "dt = 0 rejected");
    CHECK(gf9_solve(&st, 3, A, -0.01, f, w, wd, wsq, fl, &done) == GF_ERR_BAD_PARAMETER, "dt < 0");
    CHECK(gf9_solve(&st, 3, A, NAN, f, w, wd, wsq, fl, &done) == GF_ERR_BAD_PARAMETER, "dt NaN");
    CHECK(gf9_solve(&st, 3, A, 0.01, f, NULL, wd, wsq, fl, &done) == GF_ERR_NULL_POINTER, "NULL out");

    /* non-finite sample 2: samples 0, 1 solved, state is the state after sample 1 */
    A[2 * 9 + 4] = NAN;
    gf9_state ref = st;
    CHECK(gf9_solve(&st, 3, A, 0.01, f, w, wd, wsq, fl, &done) == GF_ERR_NONFINITE_INPUT && done == 2,
          "NaN in sample 2 reported at 2 (done %zu)", done);
    CHECK(st.n_samples == 2, "state counts the 2 good samples");
    gf9_output o;
    CHECK(gf9_step(&ref, A, 0.01, &o) == GF_OK && gf9_step(&ref, A + 9, 0.01, &o) == GF_OK,
          "reference steps");
    CHECK(memcmp(&ref, &st, sizeof st) == 0, "state after the error = state after sample 1");
    gf9_state before = st;
    CHECK(gf9_step(&st, A + 18, 0.01, &o) == GF_ERR_NONFINITE_INPUT, "step: NaN rejected");
    CHECK(memcmp(&before, &st, sizeof st) == 0, "step: state unchanged on error");
    A[2 * 9 + 4] = INFINITY;
    CHECK(gf9_step(&st, A + 18, 0.01, &o) == GF_ERR_NONFINITE_INPUT, "step: Inf rejected");
    CHECK(gf9_step(&st, A, 0.0, &o) == GF_ERR_BAD_PARAMETER, "step: dt = 0 after first sample");

    /* a corrupted state is refused rather than propagated */
    gf9_state bad = before;
    bad.omega_ref_rad_s[1] = NAN;
    CHECK(gf9_step(&bad, A, 0.01, &o) == GF_ERR_BAD_PARAMETER, "corrupt state refused");
}

/* Physical limits (gf9.h): |f| <= 1000 m/s^2 and |omega| <= 50 rad/s, as the
 * navigators' defaults; outputs built with independent_output for one sensor set. */
static void outputs_of(const double f[3], const double w[3], const double wd[3], double A[9])
{
    gf_array_geometry g;
    gf9_geometry(0.1, &g);
    for (int i = 0; i < 9; ++i)
        independent_output(g.u_m[i], g.theta[i], f, w, wd, &A[i]);
}

static void test_physical_limits(void)
{
    const double zero[3] = {0, 0, 0};
    double A[9], A2[18], f[6], w[6], wd[6], wsq[6];
    uint8_t fl[2];
    size_t done = 99;
    gf9_state st;
    gf9_output o;
    const double f_in[3] = {999.0, 0, 0}, f_out[3] = {0, 0, -1001.0};
    const double w_in[3] = {0, 49.9, 0}, w_out[3] = {30.0, 0, -40.1}; /* |w_out| = 50.08 */
    outputs_of(f_in, zero, zero, A);
    CHECK(gf9_init(&st, 0.1, NULL) == GF_OK && gf9_step(&st, A, 0.01, &o) == GF_OK, "|f| 999 accepted");
    outputs_of(f_out, zero, zero, A);
    gf9_state before = st;
    CHECK(gf9_step(&st, A, 0.01, &o) == GF_ERR_OUT_OF_RANGE, "|f| 1001 refused");
    CHECK(memcmp(&before, &st, sizeof st) == 0, "state kept on a refused sample");
    outputs_of(zero, w_in, zero, A);
    CHECK(gf9_init(&st, 0.1, w_in) == GF_OK && gf9_step(&st, A, 0.01, &o) == GF_OK, "|w| 49.9 accepted");
    outputs_of(zero, w_out, zero, A);
    CHECK(gf9_step(&st, A, 0.01, &o) == GF_ERR_OUT_OF_RANGE, "|w| 50.08 refused");
    const double w_big[3] = {0, 0, 50.5};
    CHECK(gf9_init(&st, 0.1, w_big) == GF_ERR_BAD_PARAMETER, "|omega_init| 50.5 refused");
    /* 1e300 outputs: |omega^2| ~ 1e301 */
    for (int i = 0; i < 9; ++i)
        A[i] = 1e300;
    gf9_init(&st, 0.1, NULL);
    CHECK(gf9_solve(&st, 1, A, 0.01, f, w, wd, wsq, fl, &done) == GF_ERR_OUT_OF_RANGE && done == 0,
          "1e300 samples refused");
    /* dt = 1e300 with omega_dot = 0.1 rad/s^2 and omega_x^2 < 0 (noise near omega_x = 0):
     * the rate output is the integrated reference, 1e299 rad/s at the second sample,
     * which is refused; the first is solved */
    const double wd1[3] = {0.1, 0, 0};
    outputs_of(zero, zero, wd1, A2);
    outputs_of(zero, zero, wd1, A2 + 9);
    for (int k = 0; k < 2; ++k) {   /* omega_x^2 = (A1 + A4 - ...) / (4 l) = -5e-3 rad^2/s^2 */
        A2[9 * k + 0] -= 1e-3;
        A2[9 * k + 3] -= 1e-3;
    }
    gf9_init(&st, 0.1, NULL);
    CHECK(gf9_solve(&st, 2, A2, 1e300, f, w, wd, wsq, fl, &done) == GF_ERR_OUT_OF_RANGE && done == 1,
          "dt = 1e300: second sample refused (done %zu)", done);
    CHECK(st.n_samples == 1 && st.omega_ref_rad_s[0] == 0.0, "state after the first sample");
    /* the same with omega_x^2 > 0: the reference only gives the sign, the output stays
     * the measured magnitude, so the sample is solved */
    const double w1[3] = {1.0, 0, 0};
    outputs_of(zero, w1, wd1, A2);
    outputs_of(zero, w1, wd1, A2 + 9);
    gf9_init(&st, 0.1, w1);
    CHECK(gf9_solve(&st, 2, A2, 1e300, f, w, wd, wsq, fl, &done) == GF_OK && fabs(w[3] - 1.0) < 1e-12,
          "dt = 1e300, omega_x^2 > 0: solved, omega_x = %g", w[3]);
}

static void test_two_instances_independent(void)
{
    const double l1 = 0.1, l2 = 0.05, dt = 0.01;
    gf_array_geometry g1, g2;
    gf9_geometry(l1, &g1);
    gf9_geometry(l2, &g2);
    enum { SAMPLES = 200 };
    static double A1[SAMPLES * 9], A2[SAMPLES * 9];
    for (int k = 0; k < SAMPLES; ++k) {
        double F[3], W[3], WD[3];
        motion(k * dt, F, W, WD);
        for (int i = 0; i < 9; ++i) {
            independent_output(g1.u_m[i], g1.theta[i], F, W, WD, &A1[9 * k + i]);
            independent_output(g2.u_m[i], g2.theta[i], F, WD, W, &A2[9 * k + i]);
        }
    }
    double w0[3], f0[3], wd0[3];
    motion(0.0, f0, w0, wd0);
    gf9_state a, b, a_alone, b_alone;
    gf9_init(&a, l1, w0); gf9_init(&b, l2, w0);
    gf9_init(&a_alone, l1, w0); gf9_init(&b_alone, l2, w0);
    gf9_output oa, ob, oa1, ob1;
    int same = 1;
    for (int k = 0; k < SAMPLES; ++k) {
        gf9_step(&a, A1 + 9 * k, dt, &oa);
        gf9_step(&b, A2 + 9 * k, dt, &ob);
    }
    for (int k = 0; k < SAMPLES; ++k)
        gf9_step(&a_alone, A1 + 9 * k, dt, &oa1);
    for (int k = 0; k < SAMPLES; ++k)
        gf9_step(&b_alone, A2 + 9 * k, dt, &ob1);
    /* compare fields, not structs: padding bytes are indeterminate */
    for (int j = 0; j < 3; ++j)
        same &= oa.omega_rad_s[j] == oa1.omega_rad_s[j] && ob.omega_rad_s[j] == ob1.omega_rad_s[j] &&
                oa.f_m_s2[j] == oa1.f_m_s2[j] && ob.f_m_s2[j] == ob1.f_m_s2[j];
    same &= memcmp(&a, &a_alone, sizeof a) == 0 && memcmp(&b, &b_alone, sizeof b) == 0;
    CHECK(same, "interleaved instances equal separate runs");
}

int main(void)
{
    test_geometry_table();
    test_forward_random_geometry();
    test_geometry_errors();
    test_solver_recovers_truth();
    test_negative_omega_sq_policy();
    test_solver_errors();
    test_physical_limits();
    test_two_instances_independent();
    TEST_MAIN_END();
}
