/* test_biquad.c — the streaming biquad cascade (gf_biquad).
 *
 * Truth never comes from the code under test:
 *   - one section's impulse response against the closed form of a resonator: for
 *     H(z) = 1 / (1 - 2 r cos(t) z^-1 + r^2 z^-2) (poles r e^(+-i t)),
 *     h[n] = r^n sin((n + 1) t) / sin(t);
 *   - general sections and cascades against the difference equation written out here in
 *     direct form I, y[n] = b0 x[n] + b1 x[n-1] + b2 x[n-2] - a1 y[n-1] - a2 y[n-2]
 *     (another realisation: equal to round-off, not bitwise);
 *   - steady state: with z0 = (G - b0) x0, z1 = b2 x0 - a2 G x0 (G = B(1) / A(1), the DC
 *     gain; from y = G x0 in the section's equations) a constant input gives G x0 from
 *     the first sample;
 *   - exact properties: channels scaled by powers of two scale the outputs exactly;
 *     chunks of any size equal one call bitwise; in-place filtering;
 *   - errors: sizes, a0 != 1, poles on or outside the unit circle (both edges of the
 *     stability triangle), non-finite coefficients / samples / states, and a filter
 *     struct with out-of-range sizes (as a corrupted saved state would hold): refused
 *     with a status, nothing read or written out of bounds (ASan).
 * Tolerances: the direct-form-I reference and the transposed-direct-form-II filter
 * round differently; for the stable sections used (|pole| <= 0.95) the difference stays
 * below 100 eps times the largest |y| (measured below 2e-15 relative). */
#include <float.h>
#include <stdint.h>
#include <string.h>

#include "nav/gf_biquad.h"
#include "gf_test.h"

#define PI 3.14159265358979323846
#define EPS DBL_EPSILON

/* Direct form I of one section (reference). */
static void ref_section(const double c[6], size_t n, const double *x, double *y)
{
    double x1 = 0, x2 = 0, y1 = 0, y2 = 0;
    for (size_t k = 0; k < n; ++k) {
        const double v = c[0] * x[k] + c[1] * x1 + c[2] * x2 - c[4] * y1 - c[5] * y2;
        x2 = x1;
        x1 = x[k];
        y2 = y1;
        y1 = v;
        y[k] = v;
    }
}

static double max_abs(const double *x, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; ++i)
        m = fmax(m, fabs(x[i]));
    return m;
}

enum { NS = 400 };

static void test_resonator_closed_form(void)
{
    const double r_list[3] = {0.5, 0.9, 0.95}, t_list[3] = {0.3, 1.2, 2.9};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const double r = r_list[i], t = t_list[j];
            const double sos[6] = {1.0, 0.0, 0.0, 1.0, -2.0 * r * cos(t), r * r};
            gf_biquad f;
            CHECK(gf_biquad_init(&f, 1, sos, 1, NULL) == GF_OK, "init resonator");
            double x[NS] = {1.0}, y[NS];
            size_t done = 0;
            CHECK(gf_biquad_run(&f, NS, x, y, &done) == GF_OK && done == NS, "run resonator");
            double worst = 0.0;
            for (int n = 0; n < NS; ++n) {
                const double h = pow(r, n) * sin((n + 1) * t) / sin(t);
                worst = fmax(worst, fabs(y[n] - h));
            }
            /* |h| <= 1/sin(t) <= 4.2; the recursion and the closed form round independently */
            CHECK(worst <= 200 * EPS / sin(t), "resonator r %g t %g: max |y - h| %.3g", r, t, worst);
        }
}

static void test_against_direct_form(void)
{
    test_rng rng = {0x1234567ULL};
    /* random stable sections: poles inside radius 0.95 (complex pairs or two reals) */
    for (int trial = 0; trial < 50; ++trial) {
        const size_t ns = 1 + (size_t)(trial % 4);
        double sos[6 * 4];
        for (size_t s = 0; s < ns; ++s) {
            double *c = sos + 6 * s;
            c[0] = test_rng_uniform(&rng, -2, 2);
            c[1] = test_rng_uniform(&rng, -2, 2);
            c[2] = test_rng_uniform(&rng, -2, 2);
            c[3] = 1.0;
            if (test_rng_uniform(&rng, 0, 1) < 0.5) {
                const double r = test_rng_uniform(&rng, 0.0, 0.95), t = test_rng_uniform(&rng, 0, PI);
                c[4] = -2 * r * cos(t);
                c[5] = r * r;
            } else {
                const double p1 = test_rng_uniform(&rng, -0.95, 0.95), p2 = test_rng_uniform(&rng, -0.95, 0.95);
                c[4] = -(p1 + p2);
                c[5] = p1 * p2;
            }
        }
        double x[NS], y[NS], ref[NS], tmp[NS];
        for (int k = 0; k < NS; ++k)
            x[k] = test_rng_uniform(&rng, -1, 1);
        memcpy(ref, x, sizeof x);
        for (size_t s = 0; s < ns; ++s) { /* the cascade: section 0 first */
            ref_section(sos + 6 * s, NS, ref, tmp);
            memcpy(ref, tmp, sizeof tmp);
        }
        gf_biquad f;
        CHECK(gf_biquad_init(&f, ns, sos, 1, NULL) == GF_OK, "init random %d", trial);
        CHECK(gf_biquad_run(&f, NS, x, y, NULL) == GF_OK, "run random %d", trial);
        double d = 0.0;
        for (int k = 0; k < NS; ++k)
            d = fmax(d, fabs(y[k] - ref[k]));
        CHECK(d <= 100 * EPS * fmax(1.0, max_abs(ref, NS)), "cascade of %zu: max |y - ref| %.3g (max |y| %.3g)",
              ns, d, max_abs(ref, NS));
    }
}

static void test_exact_properties(void)
{
    const double sos[12] = {0.2, 0.4, 0.2, 1.0, -0.5, 0.3, 1.0, -1.0, 0.5, 1.0, 0.1, 0.2};
    enum { NC = 5, NK = 300 };
    static double x[NK][NC], y[NK][NC], y2[NK][NC];
    test_rng rng = {0xBADC0FFEEULL};
    for (int k = 0; k < NK; ++k) { /* channel c = 2^c channel 0 */
        x[k][0] = test_rng_uniform(&rng, -1, 1);
        for (int c = 1; c < NC; ++c)
            x[k][c] = x[k][0] * ldexp(1.0, c);
    }
    gf_biquad f, g;
    CHECK(gf_biquad_init(&f, 2, sos, NC, NULL) == GF_OK, "init 5 channels");
    g = f;
    CHECK(gf_biquad_run(&f, NK, x[0], y[0], NULL) == GF_OK, "run 5 channels");
    int scaled = 1;
    for (int k = 0; k < NK; ++k)
        for (int c = 1; c < NC; ++c)
            scaled &= y[k][c] == y[k][0] * ldexp(1.0, c);
    CHECK(scaled, "channels are independent and linear (power-of-two scaling exact)");
    /* chunks of sizes 1, 2, 3, ... equal one call, bitwise */
    int k = 0;
    for (size_t chunk = 1; k < NK; ++chunk) {
        const size_t n = (size_t)(NK - k) < chunk ? (size_t)(NK - k) : chunk;
        CHECK(gf_biquad_run(&g, n, x[k], y2[k], NULL) == GF_OK, "chunk");
        k += (int)n;
    }
    CHECK(memcmp(y, y2, sizeof y) == 0, "chunked run = one run, bitwise");
    /* in place */
    static double z[NK][NC];
    memcpy(z, x, sizeof x);
    CHECK(gf_biquad_init(&g, 2, sos, NC, NULL) == GF_OK && gf_biquad_run(&g, NK, z[0], z[0], NULL) == GF_OK,
          "in place");
    CHECK(memcmp(y, z, sizeof y) == 0, "in-place filtering = separate output, bitwise");
}

static void test_steady_state(void)
{
    const double c[6] = {0.1, 0.3, 0.2, 1.0, -0.6, 0.25};
    const double G = (c[0] + c[1] + c[2]) / (1.0 + c[4] + c[5]);
    const double x0[2] = {3.0, -0.5};
    gf_biquad f;
    CHECK(gf_biquad_init(&f, 1, c, 2, NULL) == GF_OK, "init");
    double z[4]; /* [section 0][channel][2] */
    for (int ch = 0; ch < 2; ++ch) {
        z[2 * ch] = (G - c[0]) * x0[ch];
        z[2 * ch + 1] = c[2] * x0[ch] - c[5] * G * x0[ch];
    }
    CHECK(gf_biquad_set_state(&f, z, 3) == GF_ERR_BAD_SIZE, "set_state with 3 values for 4: BAD_SIZE");
    CHECK(gf_biquad_set_state(&f, z, 5) == GF_ERR_BAD_SIZE, "set_state with 5 values for 4: BAD_SIZE");
    CHECK(gf_biquad_set_state(&f, z, 4) == GF_OK, "set_state");
    double x[50][2], y[50][2];
    for (int k = 0; k < 50; ++k) {
        x[k][0] = x0[0];
        x[k][1] = x0[1];
    }
    CHECK(gf_biquad_run(&f, 50, x[0], y[0], NULL) == GF_OK, "run steady");
    double d = 0.0;
    for (int k = 0; k < 50; ++k)
        for (int ch = 0; ch < 2; ++ch)
            d = fmax(d, fabs(y[k][ch] - G * x0[ch]));
    CHECK(d <= 20 * EPS * fabs(G * x0[0]), "steady state from the first sample: max dev %.3g", d);
    const double znan[4] = {0, NAN, 0, 0};
    gf_biquad before = f;
    CHECK(gf_biquad_set_state(&f, znan, 4) == GF_ERR_NONFINITE_INPUT &&
              memcmp(&f, &before, sizeof f) == 0, "NaN state refused, filter unchanged");
}

static void test_errors(void)
{
    const double good[6] = {1, 0, 0, 1, 0.5, 0.2};
    gf_biquad f;
    size_t bad = 99;
    CHECK(gf_biquad_init(NULL, 1, good, 1, NULL) == GF_ERR_NULL_POINTER, "NULL filter");
    CHECK(gf_biquad_init(&f, 0, good, 1, NULL) == GF_ERR_BAD_SIZE, "0 sections");
    CHECK(gf_biquad_init(&f, GF_BIQUAD_MAX_SECTIONS + 1, good, 1, NULL) == GF_ERR_BAD_SIZE, "17 sections");
    CHECK(gf_biquad_init(&f, 1, good, 0, NULL) == GF_ERR_BAD_SIZE, "0 channels");
    CHECK(gf_biquad_init(&f, 1, good, GF_BIQUAD_MAX_CHANNELS + 1, NULL) == GF_ERR_BAD_SIZE, "65 channels");
    double two[12] = {1, 0, 0, 1, 0.5, 0.2, 1, 0, 0, 2, 0, 0};
    CHECK(gf_biquad_init(&f, 2, two, 1, &bad) == GF_ERR_BAD_PARAMETER && bad == 1, "a0 = 2 in section 1");
    two[9] = 1.0;
    two[11] = 1.0; /* |a2| = 1: pole on the unit circle */
    CHECK(gf_biquad_init(&f, 2, two, 1, &bad) == GF_ERR_SINGULAR_GEOMETRY && bad == 1, "a2 = 1");
    two[11] = 0.5;
    two[10] = 1.5; /* |a1| = 1 + a2: a real pole at -1 */
    CHECK(gf_biquad_init(&f, 2, two, 1, &bad) == GF_ERR_SINGULAR_GEOMETRY && bad == 1, "a1 = 1 + a2");
    two[10] = 1.4999;
    CHECK(gf_biquad_init(&f, 2, two, 1, &bad) == GF_OK, "just inside the triangle");
    two[1] = INFINITY;
    CHECK(gf_biquad_init(&f, 2, two, 1, &bad) == GF_ERR_NONFINITE_INPUT && bad == 0, "Inf b1");

    /* a NaN sample stops the run: rows before it filtered, state after them */
    CHECK(gf_biquad_init(&f, 1, good, 1, NULL) == GF_OK, "init");
    gf_biquad g = f;
    const double x[6] = {1, 2, 3, NAN, 5, 6};
    double y[6] = {0}, yr[3];
    size_t done = 99;
    CHECK(gf_biquad_run(&f, 6, x, y, &done) == GF_ERR_NONFINITE_INPUT && done == 3, "NaN at row 3");
    CHECK(gf_biquad_run(&g, 3, x, yr, NULL) == GF_OK && memcmp(y, yr, sizeof yr) == 0 &&
              memcmp(&f, &g, sizeof f) == 0, "rows before the NaN and the state are those of the prefix");
    CHECK(gf_biquad_check(&f) == GF_OK, "check of a good filter");
}

/* A struct whose sizes were corrupted (a damaged FMU state): a status, no access beyond
 * the fixed arrays. Before the sizes were checked, run read n_sections x n_channels x 2
 * state values from wherever they pointed. */
static void test_corrupted_struct(void)
{
    const double good[6] = {1, 0, 0, 1, 0.5, 0.2};
    static double x[4 * 100000], y[4 * 100000];
    const size_t bad_sizes[4][2] = {{1, 100000}, {1000, 1}, {0, 1}, {1, 0}};
    for (int i = 0; i < 4; ++i) {
        gf_biquad f;
        CHECK(gf_biquad_init(&f, 1, good, 1, NULL) == GF_OK, "init");
        f.n_sections = bad_sizes[i][0];
        f.n_channels = bad_sizes[i][1];
        size_t done = 99;
        y[0] = 42.0;
        CHECK(gf_biquad_run(&f, 4, x, y, &done) == GF_ERR_BAD_SIZE && done == 0 && y[0] == 42.0,
              "run with %zu sections x %zu channels: BAD_SIZE, nothing written", f.n_sections, f.n_channels);
        double z[2] = {0, 0};
        CHECK(gf_biquad_set_state(&f, z, 2) == GF_ERR_BAD_SIZE, "set_state on a corrupted struct");
        CHECK(gf_biquad_check(&f) == GF_ERR_BAD_SIZE, "check: BAD_SIZE");
    }
    gf_biquad f;
    CHECK(gf_biquad_init(&f, 1, good, 1, NULL) == GF_OK, "init");
    f.sos[5] = 1.5;
    CHECK(gf_biquad_check(&f) == GF_ERR_SINGULAR_GEOMETRY, "check: unstable coefficients");
    f.sos[5] = 0.2;
    f.sos[3] = 0.5;
    CHECK(gf_biquad_check(&f) == GF_ERR_BAD_PARAMETER, "check: a0 != 1");
    f.sos[3] = 1.0;
    f.z[1] = NAN;
    CHECK(gf_biquad_check(&f) == GF_ERR_NONFINITE_INPUT, "check: NaN state");
}

int main(void)
{
    test_resonator_closed_form();
    test_against_direct_form();
    test_exact_properties();
    test_steady_state();
    test_errors();
    test_corrupted_struct();
    TEST_MAIN_END();
}
