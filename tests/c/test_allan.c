/* test_allan.c — the overlapping Allan sums (gf_allan) against their definition:
 * a closed form (x_k = k^2: every second difference is 2 m^2), the definition summed in
 * long double on random phases, the same sums when the record is streamed in chunks of
 * any size with 2 m_max rows of history, and the refusals. Tolerances: the block
 * summation's round-off, (256 + n / 256) eps of the sum, bounded here by 1e-13. */
#include <math.h>
#include <string.h>

#include "base/gf_allan.h"
#include "gf_test.h"

enum { N = 5000, COLS = 3, NM = 5 };
static double g_x[N * COLS];
static double g_buf[N * COLS];

static void test_closed_form(void)
{
    for (size_t k = 0; k < N; ++k)
        for (size_t c = 0; c < COLS; ++c)
            g_x[c * N + k] = (double)(k * k) * (double)(c + 1);
    const int64_t m[NM] = {1, 2, 7, 100, 2499};
    double sums[NM * COLS] = {0};
    uint64_t counts[NM] = {0};
    CHECK(gf_allan_sums(N, COLS, g_x, N, 0, NM, m, sums, counts, NULL) == GF_OK, "status");
    for (int j = 0; j < NM; ++j) {
        CHECK(counts[j] == (uint64_t)(N - 2 * m[j]), "count m=%lld: %llu", (long long)m[j],
              (unsigned long long)counts[j]);
        for (size_t c = 0; c < COLS; ++c) {
            const double d = 2.0 * (double)(m[j] * m[j]) * (double)(c + 1);
            const double want = (double)(N - 2 * m[j]) * d * d;
            CHECK(fabs(sums[j * COLS + c] - want) <= 1e-13 * want, "m=%lld col %zu: %.17g vs %.17g",
                  (long long)m[j], c, sums[j * COLS + c], want);
        }
    }
}

static void test_random_and_streamed(void)
{
    test_rng r = {0x9E3779B97F4A7C15ULL};
    double acc[COLS] = {0};
    for (size_t k = 0; k < N; ++k)
        for (size_t c = 0; c < COLS; ++c) {
            acc[c] += test_rng_uniform(&r, -1.0, 1.0) + 0.01 * (double)c;
            g_x[c * N + k] = acc[c];
        }
    const int64_t m[NM] = {1, 3, 10, 333, 1200};
    double ref[NM * COLS];
    for (int j = 0; j < NM; ++j)
        for (size_t c = 0; c < COLS; ++c) {
            long double s = 0.0L;
            for (size_t k = 0; k + 2 * (size_t)m[j] < N; ++k) {
                const double *col = g_x + c * N;
                const long double d = (long double)col[k + 2 * m[j]] - 2.0L * col[k + m[j]] + col[k];
                s += d * d;
            }
            ref[j * COLS + c] = (double)s;
        }
    double whole[NM * COLS] = {0};
    uint64_t cw[NM] = {0};
    CHECK(gf_allan_sums(N, COLS, g_x, N, 0, NM, m, whole, cw, NULL) == GF_OK, "whole");
    for (int j = 0; j < NM * COLS; ++j)
        CHECK(fabs(whole[j] - ref[j]) <= 1e-13 * ref[j], "definition [%d]: %.17g vs %.17g", j,
              whole[j], ref[j]);
    /* streamed: chunks of 1, 7, 333 and 1999 rows, keeping the last 2 m_max rows */
    const size_t chunks[] = {1, 7, 333, 1999};
    const size_t hist = 2 * 1200;
    for (size_t ci = 0; ci < sizeof chunks / sizeof *chunks; ++ci) {
        double s[NM * COLS] = {0};
        uint64_t cnt[NM] = {0};
        size_t kept = 0;                 /* rows of history at the buffer's start */
        for (size_t start = 0; start < N; start += chunks[ci]) {
            const size_t n_new = (N - start < chunks[ci]) ? N - start : chunks[ci];
            const size_t rows = kept + n_new;
            for (size_t c = 0; c < COLS; ++c)   /* column after column */
                memcpy(g_buf + c * rows, g_x + c * N + (start - kept), rows * sizeof(double));
            CHECK(gf_allan_sums(rows, COLS, g_buf, rows, kept, NM, m, s, cnt, NULL) == GF_OK, "chunk");
            kept = rows < hist ? rows : hist;
        }
        for (int j = 0; j < NM; ++j)
            CHECK(cnt[j] == cw[j], "chunks of %zu: count %d", chunks[ci], j);
        for (int j = 0; j < NM * COLS; ++j)
            CHECK(fabs(s[j] - ref[j]) <= 1e-13 * ref[j], "chunks of %zu [%d]: %.17g vs %.17g",
                  chunks[ci], j, s[j], ref[j]);
    }
}

static void test_refusals(void)
{
    double x[12] = {0}, sums[3] = {0};
    uint64_t counts[1] = {0};
    const int64_t m1[1] = {1}, m0[1] = {0};
    size_t bad = 99;
    CHECK(gf_allan_sums(4, 3, NULL, 4, 0, 1, m1, sums, counts, NULL) == GF_ERR_NULL_POINTER, "null x");
    CHECK(gf_allan_sums(4, 3, x, 4, 0, 1, m1, NULL, counts, NULL) == GF_ERR_NULL_POINTER, "null sums");
    CHECK(gf_allan_sums(4, 0, x, 4, 0, 1, m1, sums, counts, NULL) == GF_ERR_BAD_SIZE, "no column");
    CHECK(gf_allan_sums(4, GF_ALLAN_MAX_COLS + 1, x, 4, 0, 1, m1, sums, counts, NULL) == GF_ERR_BAD_SIZE,
          "too many columns");
    CHECK(gf_allan_sums(4, 3, x, 4, 5, 1, m1, sums, counts, NULL) == GF_ERR_BAD_SIZE, "first_new > n");
    CHECK(gf_allan_sums(4, 3, x, 3, 0, 1, m1, sums, counts, NULL) == GF_ERR_BAD_SIZE, "stride < n");
    CHECK(gf_allan_sums(4, 3, x, 4, 0, 1, m0, sums, counts, NULL) == GF_ERR_BAD_PARAMETER, "m = 0");
    x[4 + 2] = NAN;   /* column 1, row 2 */
    CHECK(gf_allan_sums(4, 3, x, 4, 0, 1, m1, sums, counts, &bad) == GF_ERR_NONFINITE_INPUT && bad == 2,
          "NaN in row 2 (bad %zu)", bad);
    CHECK(sums[0] == 0.0 && counts[0] == 0, "unchanged on error");
    x[4 + 2] = INFINITY;
    x[4 + 1] = 0.0;
    CHECK(gf_allan_sums(4, 3, x, 4, 3, 1, m1, sums, counts, &bad) == GF_OK, "history rows not rechecked");
    x[4 + 2] = 0.0;
    const int64_t big[1] = {INT64_MAX};
    counts[0] = 0;
    CHECK(gf_allan_sums(4, 3, x, 4, 0, 1, big, sums, counts, NULL) == GF_OK && counts[0] == 0,
          "m beyond the buffer: no term");
}

int main(void)
{
    test_closed_form();
    test_random_and_streamed();
    test_refusals();
    TEST_MAIN_END();
}
