/* gf_text.h — numbers as text with fixed decimals, a table at a time.
 *
 * gf_text_fixed writes an (n_rows, n_cols) row-major table of doubles as lines of text:
 * each value with `decimals` digits after the point (0..9), the values separated by `sep`
 * and each line ended by '\n'; NaN as "NaN", +-infinity as "inf"/"-inf". It is the
 * fixed-decimal formats of the navigation programs (KF-GINS's "%-15.9lf", without the
 * padding) at ~20 ns a value, where printf-style formatting takes ~150. The digits are
 * printf's ("%.*f", which rounds the exact binary value, an exact tie to even) except
 * within ~1e-7 of a unit of the last place of a tie without being one, and then by one
 * unit in the last place; |x| >= 2^53 is written by snprintf itself. A negative value
 * that rounds to zero is written "-0.000..." as printf does.
 * Stateless; the caller owns the buffer (no heap, nothing static). */
#ifndef GF_TEXT_H
#define GF_TEXT_H

#include <stddef.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* the largest magnitude it writes (a finite value at or above it: GF_ERR_OUT_OF_RANGE) */
#define GF_TEXT_MAX_ABS 1e25

/* CDEF BEGIN */
/* the most decimals of gf_text_fixed */
#define GF_TEXT_MAX_DECIMALS 9

/* Writes the table into out (capacity bytes) and the bytes written to *n_written (no
 * terminating NUL). Errors (*n_written = 0, nothing written): GF_ERR_NULL_POINTER;
 * GF_ERR_BAD_PARAMETER (decimals above GF_TEXT_MAX_DECIMALS); GF_ERR_BAD_SIZE (n_cols 0,
 * or the text might not fit: a value needs at most 40 bytes with its separator; give
 * capacity >= n_rows * n_cols * 40); GF_ERR_OUT_OF_RANGE (a finite value of magnitude
 * GF_TEXT_MAX_ABS or more: format it another way). */
gf_status gf_text_fixed(size_t n_rows, size_t n_cols, const double *table, int decimals, char sep,
                        char *out, size_t capacity, size_t *n_written);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_TEXT_H */
