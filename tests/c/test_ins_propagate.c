/* test_ins_propagate.c — the INS/GNSS filter's error model F (gf_ins_error_model,
 * csrc/est/gf_ins_propagate.c: navigation blocks from gf_ins_model, sensor columns and
 * Gauss-Markov decays of the filter) against a numerical linearisation of the
 * mechanization over one step.
 *
 * Truth: gf_ins_propagate_error moves a hypothesis "nominal corrected by dx0" and the
 * nominal itself one step T with the same increments through the strapdown mechanization
 * (gf_sins) and returns the hypothesis' error about the moved nominal, the UKF's time
 * update of one point; its central differences in dx0, column by column, are the
 * transition matrix Phi of the nonlinear step. The model: F0 at the nominal at the start
 * of the step and F1 at the nominal moved by the step (the same mechanization, written
 * here), Phi_F = I + T (F0 + F1) / 2 + T^2 F0^2 / 2 (the trapezoid on F's variation over
 * the step and the second-order term of the series). Random (seeded) states with every
 * optional state (25), random sensor-error estimates and rates, forward and after
 * gf_ins_reverse.
 *
 * Tolerance per entry: |Phi - Phi_F| <= 1e-3 |Phi_F - I| + R_ij + E_ij T
 *   - 1e-3 |Phi_F - I|: what the trapezoid leaves, T^3 |F|^3 and T^2 |F| |F'| over a step
 *     of T = 5 ms at rates below 0.3 rad/s (|F'| / |F| <= |w| ~ 0.3 /s: ~1e-4 relative);
 *     a sign or an index slip in an entry of F changes it by 2 |F_ij| T, 2000 times this;
 *   - R_ij = 1e3 eps (1 + |x_i|) / h_j: rounding of two error states x (units of state i;
 *     positions differenced in radians of ~1, velocities ~20 m/s) over the step 2 h_j;
 *   - E_ij: what F leaves out on purpose (gf_ins_gnss.h): the derivatives of the radii of
 *     curvature (1.5 e^2 ~ 1% of the latitude column's terms that carry them) and of
 *     gravity with latitude (|dg/dL| = g_e (k + e^2 / 2) |sin 2L| <= 0.052 m/s^2 per rad,
 *     up velocity row), and the vertical gravity gradient's latitude terms (F takes
 *     2 g / (sqrt(R_M R_N) + h): within 0.5% of the normal gravity's).
 * The largest |Phi - Phi_F| / tolerance is printed (measured 0.79: the dg/dL entry at a
 * latitude near 45 deg; every other entry below 0.04). */
#include <float.h>
#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "est/gf_ins_gnss.h"
#include "gf_test.h"
#include "nav/gf_sins.h"

#define PI 3.14159265358979323846
#define N_TRIALS 10
#define T_S 0.005
#define NS (GF_INS_BASE_STATES + 10) /* every optional sensor state (the transfer-alignment
                                          * blocks, off here, have their own test) */
#define IV GF_INS_IDX_VEL
#define IP GF_INS_IDX_POS
#define IA GF_INS_IDX_ATT

static gf_ins_filter g_f, g_moved;

/* a random filter with every optional state, random nominal and sensor estimates */
static void random_filter(test_rng *rng, gf_ins_filter *f)
{
    gf_ins_config c;
    gf_ins_config_default(&c);
    c.scale_factors = c.baro_bias = c.odometer_scale = c.odometer_mount = 1;
    c.noise.gyro_bias_tau_s = test_rng_uniform(rng, 100.0, 3600.0);
    c.noise.accel_bias_tau_s = test_rng_uniform(rng, 100.0, 3600.0);
    c.noise.gyro_scale_tau_s = test_rng_uniform(rng, 100.0, 3600.0);
    c.noise.accel_scale_tau_s = 0.0;           /* a random constant: no decay */
    c.noise.baro_bias_tau_s = test_rng_uniform(rng, 100.0, 3600.0);
    c.noise.odometer_scale_tau_s = test_rng_uniform(rng, 100.0, 3600.0);
    c.noise.odometer_mount_tau_s = test_rng_uniform(rng, 100.0, 3600.0);
    const double e[3] = {test_rng_uniform(rng, -PI, PI), test_rng_uniform(rng, -0.5, 0.5),
                         test_rng_uniform(rng, -0.5, 0.5)};
    double q[4];
    gf_euler_to_quat(e, q);
    const double v[3] = {test_rng_uniform(rng, -25, 25), test_rng_uniform(rng, -25, 25),
                         test_rng_uniform(rng, -2, 2)};
    double s[GF_INS_N_SENSORS];
    for (int i = 0; i < 3; ++i) {
        s[i] = test_rng_uniform(rng, -1e-4, 1e-4);
        s[3 + i] = test_rng_uniform(rng, -0.05, 0.05);
        s[6 + i] = test_rng_uniform(rng, -1e-3, 1e-3);
        s[9 + i] = test_rng_uniform(rng, -1e-3, 1e-3);
    }
    s[12] = test_rng_uniform(rng, -5.0, 5.0);
    s[13] = test_rng_uniform(rng, -0.02, 0.02);
    s[14] = test_rng_uniform(rng, -0.02, 0.02);
    s[15] = test_rng_uniform(rng, -0.02, 0.02);
    static double P[NS * NS];
    memset(P, 0, sizeof P);
    for (int i = 0; i < NS; ++i)
        P[i * NS + i] = 1e-4;
    int32_t bad = 0;
    CHECK(gf_ins_init(f, &c, 10.0, q, v, test_rng_uniform(rng, -1.2, 1.2),
                      test_rng_uniform(rng, -PI, PI), test_rng_uniform(rng, -50.0, 3000.0), s, P,
                      &bad) == GF_OK, "init (bad %d)", bad);
}

/* central-difference step of state j (its unit) */
static double step_of(const gf_ins_filter *f, int j)
{
    if (j < IP)
        return 1e-3;                                       /* m/s */
    if (j < IA)
        return j == IP + 2 ? 1e-1 : 1e-7;                  /* m; rad of latitude, longitude */
    if (j < GF_INS_IDX_BG)
        return 1e-5;                                       /* rad */
    if (j < GF_INS_IDX_BA)
        return 1e-5;                                       /* rad/s */
    if (j < GF_INS_BASE_STATES)
        return 1e-3;                                       /* m/s^2 */
    if (j == f->idx_baro)
        return 1e-1;                                       /* m */
    return 1e-4;                                           /* scales, boresight rad */
}

/* magnitude of state i's values (its unit), for the rounding term */
static double size_of(const gf_ins_filter *f, int i)
{
    if (i < IP)
        return 30.0;
    if (i < IA)
        return i == IP + 2 ? 3000.0 : PI;
    return i == f->idx_baro ? 5.0 : 1.0;
}

static void test_transition(int reversed, test_rng *rng, double *worst)
{
    random_filter(rng, &g_f);
    if (reversed)
        CHECK(gf_ins_reverse(&g_f) == GF_OK, "reverse");
    const int n = g_f.n_states;
    CHECK(n == NS, "25 states: %d", n);
    /* one step's increments: rates up to 0.3 rad/s, specific force about gravity */
    double w[3], fb[3], dth[3], dv[3];
    for (int i = 0; i < 3; ++i) {
        w[i] = test_rng_uniform(rng, -0.3, 0.3);
        fb[i] = test_rng_uniform(rng, -3.0, 3.0);
    }
    double up[3];
    const double g_n[3] = {0.0, 0.0, 9.8};
    double qc[4] = {g_f.nav.q_bn[0], -g_f.nav.q_bn[1], -g_f.nav.q_bn[2], -g_f.nav.q_bn[3]};
    gf_q_rotate(qc, g_n, up);                  /* gravity's reaction in body axes */
    for (int i = 0; i < 3; ++i) {
        fb[i] += up[i];
        dth[i] = w[i] * T_S;
        dv[i] = fb[i] * T_S;
    }
    /* Phi by central differences of the nonlinear step */
    static double Phi[NS * NS];
    double dx0[NS], xp[NS], xm[NS], x0[NS];
    memset(dx0, 0, sizeof dx0);
    CHECK(gf_ins_propagate_error(&g_f, dx0, dth, dv, T_S, x0) == GF_OK, "step");
    for (int i = 0; i < n; ++i)
        CHECK(fabs(x0[i]) <= 1e-12 * size_of(&g_f, i), "the nominal's own error %d: %g", i, x0[i]);
    for (int j = 0; j < n; ++j) {
        const double h = step_of(&g_f, j);
        memset(dx0, 0, sizeof dx0);
        dx0[j] = h;
        gf_status st = gf_ins_propagate_error(&g_f, dx0, dth, dv, T_S, xp);
        dx0[j] = -h;
        st |= gf_ins_propagate_error(&g_f, dx0, dth, dv, T_S, xm);
        CHECK(st == GF_OK, "state %d: %d", j, st);
        for (int i = 0; i < n; ++i)
            Phi[i * n + j] = (xp[i] - xm[i]) / (2.0 * h);
    }
    /* F at the start and at the moved nominal (the UKF's coarse step: increments, no
     * coning, its own first sample) */
    static double F0[NS * NS], F1[NS * NS];
    CHECK(gf_ins_error_model(&g_f, fb, w, F0, NULL, NULL) == GF_OK, "F0");
    g_moved = g_f;
    g_moved.nav.cfg.input = GF_SINS_INPUT_INCREMENTS;
    g_moved.nav.cfg.coning = 0;
    g_moved.nav.have_prev = 0;
    /* the trusted step takes the increments in the state's direction, as the filter holds them */
    CHECK(gf_sins_step_trusted(&g_moved.nav, dth, dv, T_S) == GF_OK, "moved nominal");
    CHECK(gf_ins_error_model(&g_moved, fb, w, F1, NULL, NULL) == GF_OK, "F1");
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            double f2 = 0.0;
            for (int k = 0; k < n; ++k)
                f2 += F0[i * n + k] * F0[k * n + j];
            const double a = 0.5 * T_S * (F0[i * n + j] + F1[i * n + j]) + 0.5 * T_S * T_S * f2;
            const double model = (i == j ? 1.0 : 0.0) + a;
            /* the terms F leaves out: radii and gravity derivatives in the latitude column */
            double allow = 0.0;
            if (j == IP) {
                allow = 0.015 * fabs(F0[i * n + j]) * T_S;
                if (i == IV + 2)
                    allow += 0.052 * T_S;
            }
            if (i == IV + 2 && j == IP + 2)   /* F: 2 g / (sqrt(R_M R_N) + h), the normal */
                allow = 0.005 * fabs(F0[i * n + j]) * T_S;   /* gradient differs by < 0.5% */
            const double tol = 1e-3 * fabs(a) + 1e3 * DBL_EPSILON * (1.0 + size_of(&g_f, i)) /
                                                    step_of(&g_f, j) + allow;
            const double d = fabs(Phi[i * n + j] - model);
            CHECK(d <= tol, "%s: Phi[%d][%d] = %.12g by differences, %.12g from F (|diff| %.3g, "
                  "tol %.3g)", reversed ? "reversed" : "forward", i, j, Phi[i * n + j], model, d,
                  tol);
            *worst = fmax(*worst, d / tol);
        }
}

static void test_errors(void)
{
    test_rng rng = {99};
    random_filter(&rng, &g_f);
    double dx0[NS] = {0}, dx1[NS], g[3] = {0, 0, 0}, a[3] = {0, 0, 0.098};
    CHECK(gf_ins_propagate_error(NULL, dx0, g, a, T_S, dx1) == GF_ERR_NULL_POINTER, "NULL");
    CHECK(gf_ins_propagate_error(&g_f, dx0, g, a, 0.0, dx1) == GF_ERR_BAD_PARAMETER, "T = 0");
    CHECK(gf_ins_propagate_error(&g_f, dx0, g, a, NAN, dx1) == GF_ERR_BAD_PARAMETER, "T NaN");
    dx0[4] = NAN;
    CHECK(gf_ins_propagate_error(&g_f, dx0, g, a, T_S, dx1) == GF_ERR_NONFINITE_INPUT, "NaN dx0");
    dx0[4] = 0.0;
    g[1] = INFINITY;
    CHECK(gf_ins_propagate_error(&g_f, dx0, g, a, T_S, dx1) == GF_ERR_NONFINITE_INPUT, "inf dtheta");
    g[1] = 0.0;
    gf_ins_filter *bad = &g_moved;
    *bad = g_f;
    bad->n_states = 99;
    CHECK(gf_ins_propagate_error(bad, dx0, g, a, T_S, dx1) == GF_ERR_BAD_PARAMETER, "layout");
}

int main(void)
{
    test_rng rng = {0x2545f4914f6cdd1dULL};
    double worst = 0.0;
    for (int t = 0; t < N_TRIALS; ++t)
        test_transition(t % 2, &rng, &worst);
    printf("max |Phi - Phi_F| / tol = %.3f over %d trials of %d x %d entries\n", worst, N_TRIALS,
           NS, NS);
    test_errors();
    TEST_MAIN_END();
}
