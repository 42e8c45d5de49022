/* gf_linalg.h — small dense linear algebra on flat row-major arrays with run-time sizes
 * bounded by the callers' fixed maxima (no heap): the SVD behind the array-geometry
 * report and pseudo-inverse, the Cholesky factorisation behind the Kalman engine, and a
 * symmetric 3x3 eigen-solver for the rate strategies.
 */
#ifndef GF_LINALG_H
#define GF_LINALG_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest dimension any routine here accepts (rows of an SVD may go to 64). */
#define GF_LINALG_MAX_COLS 36
#define GF_LINALG_MAX_ROWS 64

/* Four doubles handled as one value, for kernels over rows padded to a multiple of 4:
 * with GCC and Clang a vector type (one AVX register, two SSE2 or NEON registers; no
 * alignment required), elsewhere a plain struct. Only lane-wise IEEE additions and
 * multiplications are used, so every form gives the same results bit for bit. Loads and
 * stores are macros: functions passing 32-byte vectors by value would have a different
 * ABI with and without AVX. */
#if defined(__GNUC__) && !defined(GF_NO_VECTOR_EXT)
typedef double gf_v4 __attribute__((vector_size(4 * sizeof(double)), aligned(sizeof(double)),
                                    may_alias));
#define GF_V4_LOAD(p) (*(const gf_v4 *)(p))
#define GF_V4_STORE(p, v) (*(gf_v4 *)(p) = (v))
#define GF_V4_SCALE(a, p) ((a) * GF_V4_LOAD(p))                 /* a * p[0..4) */
#define GF_V4_SET(a, b, c, d) ((gf_v4){(a), (b), (c), (d)})
#define GF_V4_AXPY(acc, a, p) ((acc) += (a) * GF_V4_LOAD(p))   /* acc += a * p[0..4) */
#define GF_V4_AXPYV(acc, a, v) ((acc) += (a) * (v))             /* acc += a * v */
#define GF_V4_SUB(u, v) ((u) - (v))
#else
typedef struct gf_v4 {
    double x[4];
} gf_v4;
static inline gf_v4 gf_v4_load(const double *p)
{
    const gf_v4 v = {{p[0], p[1], p[2], p[3]}};
    return v;
}
static inline void gf_v4_store(double *p, gf_v4 v)
{
    for (int k = 0; k < 4; ++k)
        p[k] = v.x[k];
}
static inline gf_v4 gf_v4_set(double a, double b, double c, double d)
{
    const gf_v4 v = {{a, b, c, d}};
    return v;
}
static inline gf_v4 gf_v4_scale(double a, const double *p)
{
    const gf_v4 v = {{a * p[0], a * p[1], a * p[2], a * p[3]}};
    return v;
}
static inline void gf_v4_axpy(gf_v4 *acc, double a, const double *p)
{
    for (int k = 0; k < 4; ++k)
        acc->x[k] += a * p[k];
}
static inline void gf_v4_axpyv(gf_v4 *acc, double a, gf_v4 v)
{
    for (int k = 0; k < 4; ++k)
        acc->x[k] += a * v.x[k];
}
static inline gf_v4 gf_v4_sub(gf_v4 u, gf_v4 v)
{
    for (int k = 0; k < 4; ++k)
        u.x[k] -= v.x[k];
    return u;
}
#define GF_V4_LOAD(p) gf_v4_load(p)
#define GF_V4_STORE(p, v) gf_v4_store((p), (v))
#define GF_V4_AXPYV(acc, a, v) gf_v4_axpyv(&(acc), (a), (v))
#define GF_V4_SUB(u, v) gf_v4_sub((u), (v))
#define GF_V4_SCALE(a, p) gf_v4_scale((a), (p))
#define GF_V4_SET(a, b, c, d) gf_v4_set((a), (b), (c), (d))
#define GF_V4_AXPY(acc, a, p) gf_v4_axpy(&(acc), (a), (p))
#endif

/* n rounded up to a multiple of 4 (the padded row stride of the kernels on gf_v4) */
#define GF_PADDED(n) (((n) + 3) & ~(size_t)3)

/* out[0..m) += a in[0..m) for m a multiple of 4 (rows padded by GF_PADDED) */
static inline void gf_axpy4(size_t m, double a, const double *restrict in, double *restrict out)
{
    for (size_t j = 0; j < m; j += 4) {
        out[j] += a * in[j];
        out[j + 1] += a * in[j + 1];
        out[j + 2] += a * in[j + 2];
        out[j + 3] += a * in[j + 3];
    }
}

/* Hot kernels on gf_v4 are compiled twice on x86-64 Linux with GCC, for the baseline
 * (SSE2) and for AVX2, and the loader picks the one the processor runs (function
 * multi-versioning). Both do the same IEEE operations in the same order (no FMA:
 * -ffp-contract=off), so their results are equal bit for bit. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) && \
    !defined(GF_NO_MULTIVERSION)
#define GF_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GF_VECTOR_CLONES
#endif

/* Kernels written once for sizes that their callers make compile-time constants (row
 * strides, block counts): always inlined, so that their loops unroll completely and the
 * rows being accumulated stay in vector registers. */
#if defined(__GNUC__)
#define GF_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define GF_ALWAYS_INLINE inline
#endif

/* Index of the lowest set bit of m != 0 (iterating over the set bits of a row's
 * structure mask: for (; m; m &= m - 1) j = gf_lowest_bit(m)). */
static inline size_t gf_lowest_bit(uint64_t m)
{
#if defined(__GNUC__)
    return (size_t)__builtin_ctzll(m);
#else
    size_t k = 0;
    while (!(m & 1u)) {
        m >>= 1;
        ++k;
    }
    return k;
#endif
}

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
