/* gf_text.h — numbers as text and back, a table at a time.
 *
 * gf_text_parse reads lines of numbers (CSV or whitespace-separated) into an
 * (n_rows, n_cols) row-major table of doubles, correctly rounded (below).
 *
 * gf_text_fixed writes an (n_rows, n_cols) row-major table of doubles as lines of text:
 * each value with `decimals` digits after the point (0..9), the values separated by `sep`
 * and each line ended by '\n'; NaN as "NaN", +-infinity as "inf"/"-inf". It is the
 * fixed-decimal formats of the navigation programs (KF-GINS's "%-15.9lf", without the
 * padding) at ~10 ns a value, where printf-style formatting takes ~150. The digits are
 * printf's ("%.*f", which rounds the exact binary value, an exact tie to even), exactly
 * (the scaled fraction's rounding error kept by an fma); |x| >= 2^53 is written by
 * snprintf itself. A negative value that rounds to zero is written "-0.000..." as printf
 * does.
 * Stateless; the caller owns the buffer (no heap, nothing static). */
#ifndef GF_TEXT_H
#define GF_TEXT_H

#include <stddef.h>
#include <stdint.h>

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

/* gf_text_parse's separators: commas (spaces and tabs around a field ignored), or runs of
 * spaces and tabs (KF-GINS's text files; leading and trailing ones ignored) */
#define GF_TEXT_SEP_COMMA 0
#define GF_TEXT_SEP_WHITESPACE 1

/* Parses lines of text[0 .. n_bytes) into out, row-major, n_cols values a row, at most
 * max_rows rows. A line ends at '\n' (a '\r' before it is dropped: CRLF); a line that
 * is blank (spaces, tabs) or whose first other character is '#' (a comment) is skipped.
 * Every other line is a row: exactly n_cols numbers separated as `sep` says. A number:
 * an optional sign, then digits with an optional '.' (at least one digit: "5.", ".5"),
 * an optional exponent ([eE][+-]digits); or nan, inf, infinity (any case, with a sign;
 * "-nan" is a NaN with its sign bit set). Values are correctly rounded (round to
 * nearest, ties to even) whatever the number of digits: Clinger's exact path (a
 * mantissa of at most 19 digits and <= 2^53, a power of ten of at most 22: one exact
 * multiply or divide) and otherwise strtod on the digits written without a decimal
 * point (so no locale can change it); beyond the double range: +-inf, or +-0.
 *
 * final = 0: text after the last '\n' is an incomplete line and is left unparsed;
 * final = 1: it is the last line of the file. The call stops before a data line when
 * max_rows rows are written. Outputs (set on every return): *n_rows rows written,
 * *n_used bytes consumed (whole lines: the data lines written and the comment and blank
 * lines among and after them; the caller resumes there), *n_lines lines consumed.
 * Errors: GF_ERR_NULL_POINTER; GF_ERR_BAD_SIZE (n_cols 0); GF_ERR_BAD_PARAMETER (sep
 * not one of GF_TEXT_SEP_*, final not 0 or 1); GF_ERR_BAD_TEXT: the line that starts at
 * text[*n_used] (line *n_lines + 1 of the text, counted from 1) is not a row of n_cols
 * numbers (text or an empty field where a number belongs, another number of fields);
 * the rows before it are written. Stateless, no heap. */
gf_status gf_text_parse(const uint8_t *text, size_t n_bytes, int final, size_t n_cols, int sep,
                        double *out, size_t max_rows, size_t *n_rows, size_t *n_used,
                        size_t *n_lines);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_TEXT_H */
