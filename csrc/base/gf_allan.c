/* gf_allan.c — overlapping Allan variance sums; see gf_allan.h (IEEE Std 952-1997
 * Annex C, NIST SP 1065 eq. 11).
 *
 * Speed: the sums are memory-bound (three streams x_r, x_(r-m), x_(r-2m) per factor m).
 * Rows are processed in blocks of BLOCK_ROWS; within a block every factor is summed
 * before the next block, so the block's own rows and, for neighbouring factors, most of
 * the far rows are still in cache (a record of 7.2e6 rows and 64 factors reads ~4x less
 * from memory than one pass per factor). The inner loop keeps LANES independent
 * accumulators (lane k takes the rows r = k mod LANES of a sub-block), which the
 * compiler turns into vector operations without reassociating any addition; the
 * function is compiled for the baseline and for AVX2 on x86-64 Linux with GCC
 * (GF_VECTOR_CLONES), with the same results. */
#include "base/gf_allan.h"

#include <math.h>

#include "base/gf_linalg.h"

enum { LANES = 8, SUB_ROWS = 256, BLOCK_ROWS = 1 << 16 };

/* sum over r in [r0, r1) of ((x_r - 2 x_(r-m)) + x_(r-2m))^2, r0 >= 2m: sub-blocks of
 * SUB_ROWS rows summed in LANES lanes, then added to the total (round-off ~ (SUB_ROWS +
 * n / SUB_ROWS) eps relative) */
static GF_VECTOR_CLONES double sum_sq_d2(const double *x, size_t r0, size_t r1, size_t m)
{
    const double *x2 = x + r0, *x1 = x + r0 - m, *x0 = x + r0 - 2 * m;
    const size_t n = r1 - r0;
    double total = 0.0;
    size_t i = 0;
    while (i < n) {
        const size_t end = (n - i > SUB_ROWS) ? i + SUB_ROWS : n;
        double acc[LANES] = {0.0};
#if defined(__GNUC__) && !defined(GF_NO_VECTOR_EXT)
        /* lanes 0..3 and 4..7 in two vectors: the same additions as the loop below */
        gf_v4 a0 = GF_V4_SET(0.0, 0.0, 0.0, 0.0), a1 = a0;
        const gf_v4 two = GF_V4_SET(2.0, 2.0, 2.0, 2.0);
        for (; i + LANES <= end; i += LANES) {
            const gf_v4 d0 = (GF_V4_LOAD(x2 + i) - two * GF_V4_LOAD(x1 + i)) + GF_V4_LOAD(x0 + i);
            const gf_v4 d1 = (GF_V4_LOAD(x2 + i + 4) - two * GF_V4_LOAD(x1 + i + 4)) +
                             GF_V4_LOAD(x0 + i + 4);
            a0 += d0 * d0;
            a1 += d1 * d1;
        }
        GF_V4_STORE(acc, a0);
        GF_V4_STORE(acc + 4, a1);
#else
        for (; i + LANES <= end; i += LANES)
            for (size_t k = 0; k < LANES; ++k) {
                const double d = (x2[i + k] - 2.0 * x1[i + k]) + x0[i + k];
                acc[k] += d * d;
            }
#endif
        for (size_t k = 0; i < end; ++i, ++k) {
            const double d = (x2[i] - 2.0 * x1[i]) + x0[i];
            acc[k] += d * d;
        }
        double s = 0.0;
        for (size_t k = 0; k < LANES; ++k)
            s += acc[k];
        total += s;
    }
    return total;
}

gf_status gf_allan_sums(size_t n_rows, size_t n_cols, const double *x, size_t stride, size_t first_new,
                        size_t n_m, const int64_t *m, double *sums, uint64_t *counts,
                        size_t *bad_row)
{
    if ((n_rows && !x) || (n_m && (!m || !sums || !counts)))
        return GF_ERR_NULL_POINTER;
    if (n_cols == 0 || n_cols > GF_ALLAN_MAX_COLS || first_new > n_rows || stride < n_rows)
        return GF_ERR_BAD_SIZE;
    for (size_t j = 0; j < n_m; ++j)
        if (m[j] < 1)
            return GF_ERR_BAD_PARAMETER;
    for (size_t c = 0; c < n_cols; ++c)   /* history rows were checked when they were new */
        for (size_t r = first_new; r < n_rows; ++r)
            if (!isfinite(x[c * stride + r])) {
                if (bad_row)
                    *bad_row = r;
                return GF_ERR_NONFINITE_INPUT;
            }
    for (size_t b0 = first_new; b0 < n_rows; b0 += BLOCK_ROWS) {
        const size_t b1 = (n_rows - b0 > BLOCK_ROWS) ? b0 + BLOCK_ROWS : n_rows;
        for (size_t c = 0; c < n_cols; ++c)
            for (size_t j = 0; j < n_m; ++j) {
                const size_t mj = (size_t)m[j];
                if (mj > (n_rows - 1) / 2)          /* no term fits in the buffer */
                    continue;
                const size_t r0 = (b0 > 2 * mj) ? b0 : 2 * mj;
                if (r0 >= b1)
                    continue;
                sums[j * n_cols + c] += sum_sq_d2(x + c * stride, r0, b1, mj);
                if (c == 0)
                    counts[j] += (uint64_t)(b1 - r0);
            }
    }
    return GF_OK;
}
