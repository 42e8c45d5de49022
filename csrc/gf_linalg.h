/* gf_linalg.h — small dense linear algebra on flat row-major arrays with run-time sizes
 * bounded by the callers' fixed maxima (no heap): the SVD behind the array-geometry
 * report and pseudo-inverse, the Cholesky factorisation behind the Kalman engine, and a
 * symmetric 3x3 eigen-solver for the rate strategies.
 */
#ifndef GF_LINALG_H
#define GF_LINALG_H

#include <stddef.h>

#include "gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest dimension any routine here accepts (rows of an SVD may go to 64). */
#define GF_LINALG_MAX_COLS 36
#define GF_LINALG_MAX_ROWS 64

/* out[0..m) += a * in[0..m), m a multiple of 4: rows padded to 4 doubles, so that the
 * loop vectorises without a remainder (the structured Kalman predict and the filters'
 * transition matrices use it). */
static inline void gf_axpy4(size_t m, double a, const double *restrict in, double *restrict out)
{
    for (size_t j = 0; j < m; j += 4) {
        out[j] += a * in[j];
        out[j + 1] += a * in[j + 1];
        out[j + 2] += a * in[j + 2];
        out[j + 3] += a * in[j + 3];
    }
}

/* n rounded up to a multiple of 4 (the padded row stride of gf_axpy4's callers) */
#define GF_PADDED(n) (((n) + 3) & ~(size_t)3)

/* Thin SVD A = U diag(s) V^T of an m x n matrix (m >= n, n <= GF_LINALG_MAX_COLS,
 * m <= GF_LINALG_MAX_ROWS) by one-sided Jacobi rotations (Hestenes), accurate to a few
 * ulp relative to s_max. a (m x n) is overwritten by U (orthonormal columns where
 * s > 0); s (n) is sorted descending; v (n x n) receives V.
 * Errors: GF_ERR_BAD_SIZE, GF_ERR_NONFINITE_INPUT, GF_ERR_NULL_POINTER. */
gf_status gf_svd(size_t m, size_t n, double *a, double *s, double *v);

/* Cholesky factor L (lower) of a symmetric positive-definite n x n matrix, in place
 * (upper triangle zeroed). GF_ERR_SINGULAR_GEOMETRY if not positive definite. */
gf_status gf_cholesky(size_t n, double *a);

/* Solves L L^T X = B for X (n x k) in place in b, with L from gf_cholesky. */
void gf_cholesky_solve(size_t n, const double *l, size_t k, double *b);

/* Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi: values descending in
 * w, vectors as the columns of v (row-major 3x3). */
void gf_sym3_eig(const double a[9], double w[3], double v[9]);

#ifdef __cplusplus
}
#endif

#endif /* GF_LINALG_H */
