/* gf_kalman.h — the one Kalman engine of gfins_fmi: a fixed maximum dimension, dense,
 * no heap. Filters (the fused rate estimator now; the INS/GNSS, calibration and
 * alignment filters later) own the model — state layout with named indices, the
 * transition F, noise Q, measurement H, R — and hand it to these two calls. Extended
 * (linearised) filters propagate their state themselves and give the residual z - h(x).
 *
 *   predict:  x <- F x (unless the caller propagated x),  P <- F P F^T + Q
 *   update:   S = H P H^T + R,  K = P H^T S^-1,  x <- x + K r,
 *             P <- (I - K H) P (I - K H)^T + K R K^T      (Joseph form: stays symmetric
 *                                                           positive semi-definite)
 *
 * Symmetric inputs. P0, Q and R are covariances: the engine reads all of each, so each
 * must be symmetric. An entry pair that differs by more than 1e-9 sqrt(|A_ii A_jj|)
 * (far above the round-off of any symmetric construction, far below a real asymmetry)
 * is refused with GF_ERR_BAD_PARAMETER; within that, the matrix is symmetrised
 * explicitly, (A + A^T) / 2, and only the symmetrised matrix is used (so the
 * positive-definiteness check of R, which reads its lower triangle, and the update,
 * which uses all of it, see the same matrix).
 */
#ifndef GF_KALMAN_H
#define GF_KALMAN_H

#include <stddef.h>

#include "gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_KF_MAX_N 36   /* states: the 36-state rotating-INS calibration of seed 001 */
#define GF_KF_MAX_M 12   /* measurements per update */

typedef struct gf_kalman {
    size_t n;                                /* number of states, 1..GF_KF_MAX_N */
    double x[GF_KF_MAX_N];                   /* state estimate */
    double P[GF_KF_MAX_N * GF_KF_MAX_N];     /* covariance, row-major n x n (stride n) */
} gf_kalman;

/* x0 (n) and P0 (n x n, symmetric positive semi-definite; see "Symmetric inputs").
 * Errors: GF_ERR_BAD_SIZE, GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_PARAMETER (P0 not
 * symmetric). */
gf_status gf_kalman_init(gf_kalman *kf, size_t n, const double *x0, const double *P0);

/* F (n x n; NULL = identity) and Q (n x n, symmetric; NULL = zero). propagate_x = 0
 * leaves x to the caller (extended filters). Errors: GF_ERR_BAD_SIZE (n of the struct
 * out of range), GF_ERR_BAD_PARAMETER (Q not symmetric); the filter is unchanged on
 * error. */
gf_status gf_kalman_predict(gf_kalman *kf, const double *F, const double *Q, int propagate_x);

/* Update with m measurements: residual r = z - h(x) (m), H (m x n), R (m x m, symmetric
 * positive definite). nis (may be NULL) receives r^T S^-1 r. Errors: GF_ERR_BAD_SIZE,
 * GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_PARAMETER (R not symmetric),
 * GF_ERR_SINGULAR_GEOMETRY (R or S not positive definite); the filter is unchanged on
 * error. */
gf_status gf_kalman_update(gf_kalman *kf, size_t m, const double *residual, const double *H,
                           const double *R, double *nis);
/* CDEF END */

/* Checks a filter struct handed in by a caller (e.g. restored from saved bytes): n in
 * 1..GF_KF_MAX_N (GF_ERR_BAD_SIZE), x and the used n x n block of P finite
 * (GF_ERR_NONFINITE_INPUT). */
gf_status gf_kalman_check(const gf_kalman *kf);

#ifdef __cplusplus
}
#endif

#endif /* GF_KALMAN_H */
