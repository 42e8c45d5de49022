/* gf_allan.h — the sums of the overlapping Allan variance of a phase record, streamed.
 *
 * IEEE Std 952-1997 Annex C / NIST SP 1065 eq. (11): for N phase points x_0 .. x_(N-1)
 * spaced tau0 (x = the running integral of the rate y: x_0 = 0, x_k = x_(k-1) + y_k tau0),
 *
 *   sigma^2(tau = m tau0) = 1 / (2 tau^2 (N - 2m)) * sum_{k=0}^{N-2m-1} (x_(k+2m) - 2 x_(k+m) + x_k)^2
 *
 * gf_allan_sums adds the squared second differences to running sums, so a record of any
 * length flows through a buffer of rows: rows [0, first_new) are the last rows carried
 * from the previous call (history; at least 2 m_max of them once the record is that
 * long), rows [first_new, n_rows) are new. The terms added are those whose last point
 * x_(k+2m) is a new row and whose first point x_k is in the buffer; a term is added
 * exactly once over a record streamed this way. Columns are independent records (the
 * axes of an IMU), stored column after column (x[c * stride + r], stride >= n_rows: each
 * column's phase contiguous, in a buffer of any capacity). The second difference is formed as (x2 - 2 x1) + x0, the order of
 * allantools and of numpy; squares are summed in blocks of 256 rows, then the blocks
 * (round-off ~ (256 + n/256) eps relative). Stateless: the caller keeps the
 * buffer and the sums (no heap, nothing static). */
#ifndef GF_ALLAN_H
#define GF_ALLAN_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
/* the most columns of one buffer (6 axes of an IMU, with room) */
#define GF_ALLAN_MAX_COLS 64

/* Adds, for every averaging factor m[j] (>= 1) and column c, the squares of the terms
 * described above to sums[j * n_cols + c] and their number to counts[j].
 * x: n_cols columns of n_rows phase values, column c at x + c * stride; first_new <= n_rows.
 * Errors (sums and counts unchanged): GF_ERR_NULL_POINTER; GF_ERR_BAD_SIZE (n_cols 0 or
 * above GF_ALLAN_MAX_COLS, first_new > n_rows, stride < n_rows); GF_ERR_BAD_PARAMETER (an m[j] < 1);
 * GF_ERR_NONFINITE_INPUT (a new row holds NaN or an infinity: *bad_row, may be NULL, is
 * its row; history rows were checked when they were new). */
gf_status gf_allan_sums(size_t n_rows, size_t n_cols, const double *x, size_t stride, size_t first_new,
                        size_t n_m, const int64_t *m, double *sums, uint64_t *counts,
                        size_t *bad_row);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_ALLAN_H */
