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
 * Also here, so that every filter shares them:
 *   - a structured predict, P <- (I + A)(P + D1)(I + A)^T + D2 (D diagonal), that skips
 *     the zeros of A = Phi - I (navigation error models are ~70% zeros): the trapezoidal
 *     rule for a diagonal continuous noise qc is D1 = D2 = qc T / 2. Its rows are padded
 *     to a multiple of 4 and accumulated in vector registers; each entry is the same
 *     sequence of IEEE operations in every compiled form (AVX2, SSE2, plain C), so the
 *     results are equal bit for bit wherever the engine runs (tests/c/test_kalman.c);
 *   - the unscented transform of the sigma-point (unscented) Kalman filter with the
 *     scaled sigma points of seed 004 (section 2, eq. 25-38; implemented in gf_ukf.c):
 *         lambda = alpha^2 (N + kappa) - N,  gamma = sqrt(N + lambda),
 *         W0m = lambda / (N + lambda),  W0c = W0m + 1 - alpha^2 + beta,
 *         Wi = 1 / (2 (N + lambda)),  i = 1..2N;
 *     points x, x + gamma L_j, x - gamma L_j with L L^T = P (Cholesky columns);
 *   - one backward step of the Rauch-Tung-Striebel smoother:
 *         A = P_k|k Phi^T P_k+1|k^-1,  x_k|N = x_k|k + A (x_k+1|N - x_k+1|k),
 *         P_k|N = P_k|k + A (P_k+1|N - P_k+1|k) A^T.
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
#include <stdint.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_KF_MAX_N 40   /* states: the 36-state rotating-INS calibration of seed 001
                            and its optional accelerometer-delay state (gf_syscal.h), 37,
                            rounded up to a multiple of 4 (see the assertion below) */
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

/* The same with an innovation gate: when nis_max > 0 and r^T S^-1 r > nis_max the filter
 * is left unchanged and *accepted (may be NULL) is 0; otherwise it is updated and
 * *accepted = 1. *nis (may be NULL) always receives r^T S^-1 r. */
gf_status gf_kalman_update_gated(gf_kalman *kf, size_t m, const double *residual,
                                 const double *H, const double *R, double nis_max,
                                 double *nis, int *accepted);

/* P <- (I + A)(P + diag(q1))(I + A)^T + diag(q2) with A = Phi - I (n x n, dense storage;
 * its zero entries are skipped, so the cost is ~1.5 nnz(A) n multiply-adds instead of
 * 2 n^3). q1, q2 (n) are diagonal process noises and may be NULL (zero); the trapezoidal
 * rule is q1 = q2 = qc T / 2. x is not changed (error-state filters keep it 0 between
 * updates). Errors: GF_ERR_NULL_POINTER, GF_ERR_BAD_SIZE; GF_ERR_NONFINITE_INPUT (A or q
 * not finite: P unchanged). */
gf_status gf_kalman_predict_sparse(gf_kalman *kf, const double *A, const double *q1,
                                   const double *q2);

/* The same with A given by its non-zeros, row by row (compressed sparse rows):
 * row_start (n + 1), col and val (row_start[n] entries; columns < n). Errors as above,
 * and GF_ERR_BAD_SIZE for a bad row_start or column. */
gf_status gf_kalman_predict_csr(gf_kalman *kf, const size_t *row_start, const unsigned char *col,
                                const double *val, const double *q1, const double *q2);

/* The same with A in rows of stride `stride` (>= n) and its structure as bit masks: bit
 * j of row_mask[i] set = entry (i, j) is used; the others are taken as zero and not read
 * (the form a filter with a fixed error-model structure builds directly). Errors as
 * above; GF_ERR_BAD_SIZE for a stride below n or a mask bit at or above n. */
gf_status gf_kalman_predict_masked(gf_kalman *kf, const double *A, size_t stride,
                                   const uint64_t *row_mask, const double *q1, const double *q2);

/* Scaled unscented transform (seed 004 eq. 25-28): sigma-point spread and weights. */
typedef struct gf_ukf_weights {
    size_t n;          /* state dimension N */
    double lambda;     /* alpha^2 (N + kappa) - N */
    double gamma;      /* sqrt(N + lambda): spread of the points in units of sqrt(P) */
    double wm0, wc0;   /* weights of the centre point (mean, covariance) */
    double wi;         /* weight of each of the 2N other points (mean and covariance) */
} gf_ukf_weights;

/* Errors: GF_ERR_BAD_SIZE (n), GF_ERR_BAD_PARAMETER (alpha <= 0 or not finite,
 * N + kappa <= 0, beta not finite). */
gf_status gf_ukf_weights_init(gf_ukf_weights *w, size_t n, double alpha, double beta,
                              double kappa);

/* The 2n+1 sigma points of (kf->x, kf->P) as rows of X ((2n+1) x n): row 0 = x,
 * row 1+j = x + gamma L_j, row 1+n+j = x - gamma L_j. Errors: GF_ERR_BAD_SIZE (w->n !=
 * kf->n), GF_ERR_SINGULAR_GEOMETRY (P not positive definite). */
gf_status gf_ukf_sigma_points(const gf_kalman *kf, const gf_ukf_weights *w, double *X);

/* Time update from propagated points Y ((2n+1) x n, same order as X): x = sum Wm Y_i,
 * P = sum Wc (Y_i - x)(Y_i - x)^T + Q (Q n x n, may be NULL) (seed 004 eq. 30-31). */
gf_status gf_ukf_predict(gf_kalman *kf, const gf_ukf_weights *w, const double *Y,
                         const double *Q);

/* Measurement update (seed 004 eq. 33-38) with the points X the measurement points were
 * made from and their images Zp ((2n+1) x m), measurement z (m), noise R (m x m,
 * positive definite): y = sum Wm Zp_i, Pyy = sum Wc (Zp_i - y)(..)^T + R,
 * Pxy = sum Wc (X_i - x)(Zp_i - y)^T, K = Pxy Pyy^-1, x += K (z - y), P -= K Pyy K^T.
 * nis (may be NULL) = (z - y)^T Pyy^-1 (z - y); gate nis_max and *accepted as in
 * gf_kalman_update_gated. Errors as gf_kalman_update; P not
 * positive semi-definite afterwards is GF_ERR_DIVERGED (filter unchanged). */
gf_status gf_ukf_update(gf_kalman *kf, const gf_ukf_weights *w, const double *X, size_t m,
                        const double *Zp, const double *z, const double *R, double nis_max,
                        double *nis, int *accepted);

/* One backward Rauch-Tung-Striebel step (see the top of this file), n states, all
 * matrices n x n row-major: P_post = P_k|k, Phi = transition k -> k+1, P_prior_next =
 * P_k+1|k, P_s_next = P_k+1|N; x_post (x_k|k), x_prior_next (x_k+1|k) may be NULL
 * (zero); x_s_next = x_k+1|N. Outputs x_s = x_k|N (n), P_s = P_k|N (n x n; may alias
 * P_post). Errors: GF_ERR_BAD_SIZE, GF_ERR_NULL_POINTER, GF_ERR_SINGULAR_GEOMETRY
 * (P_k+1|k not positive definite). */
gf_status gf_kalman_rts_step(size_t n, const double *P_post, const double *x_post,
                             const double *Phi, const double *P_prior_next,
                             const double *x_prior_next, const double *P_s_next,
                             const double *x_s_next, double *x_s, double *P_s);
/* CDEF END */

/* The structured predict works in rows padded to a multiple of 4 inside arrays of
 * GF_KF_MAX_N^2 doubles: n rows of stride GF_PADDED(n) fit only if the maximum is itself a
 * multiple of 4 (37 would overflow them by 111 doubles at n = 37). */
_Static_assert(GF_KF_MAX_N % 4 == 0, "GF_KF_MAX_N must be a multiple of 4 (the engine's padded work arrays)");

/* Checks a filter struct handed in by a caller (e.g. restored from saved bytes): n in
 * 1..GF_KF_MAX_N (GF_ERR_BAD_SIZE), x and the used n x n block of P finite
 * (GF_ERR_NONFINITE_INPUT), and P a covariance as the engine keeps it
 * (GF_ERR_BAD_PARAMETER): symmetric within the engine's tolerance (|P_ij - P_ji| <=
 * 1e-9 sqrt(P_ii P_jj), the test of gf_kalman_init and the updates), a diagonal >= 0 (a
 * zero variance with a zero row and column: a state known exactly) and positive
 * (semi-)definite within round-off (the Cholesky factor of its correlation matrix with
 * 1e-10 added to the diagonal exists: eigenvalues of the correlation matrix above -1e-10).
 * A matrix that fails would make the next predict or update produce NaN or a negative
 * variance (found by a crafted FMU state). */
gf_status gf_kalman_check(const gf_kalman *kf);

#ifdef __cplusplus
}
#endif

#endif /* GF_KALMAN_H */
