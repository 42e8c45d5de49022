/* gf_kalman.c — see gf_kalman.h. */
#include "gf_kalman.h"

#include <math.h>
#include <string.h>

#include "gf_linalg.h"

#define NMAX GF_KF_MAX_N
#define MMAX GF_KF_MAX_M

/* C (r x c) = A (r x k) B (k x c), row-major */
static void mat_mul(size_t r, size_t k, size_t c, const double *A, const double *B, double *C)
{
    for (size_t i = 0; i < r; ++i)
        for (size_t j = 0; j < c; ++j) {
            double acc = 0.0;
            for (size_t l = 0; l < k; ++l)
                acc += A[i * k + l] * B[l * c + j];
            C[i * c + j] = acc;
        }
}

/* C (r x c) = A (r x k) B^T, B (c x k), row-major */
static void mat_mul_bt(size_t r, size_t k, size_t c, const double *A, const double *B, double *C)
{
    for (size_t i = 0; i < r; ++i)
        for (size_t j = 0; j < c; ++j) {
            double acc = 0.0;
            for (size_t l = 0; l < k; ++l)
                acc += A[i * k + l] * B[j * k + l];
            C[i * c + j] = acc;
        }
}

/* Symmetric within round-off (see gf_kalman.h): 1 and the symmetrised matrix in out
 * (n x n, may be A itself), or 0. Non-finite entries fail. */
#define GF_KF_SYM_TOL 1e-9
static int symmetrised(size_t n, const double *A, double *out)
{
    for (size_t i = 0; i < n; ++i) {
        if (!isfinite(A[i * n + i]))
            return 0;
        for (size_t j = 0; j < i; ++j) {
            const double a = A[i * n + j], b = A[j * n + i], d = a - b;
            /* squared form (no sqrt on the filter's path); a NaN fails the comparison */
            if (a != b && !(d * d <= GF_KF_SYM_TOL * GF_KF_SYM_TOL *
                                         fabs(A[i * n + i] * A[j * n + j])))
                return 0;
        }
    }
    for (size_t i = 0; i < n; ++i) {
        out[i * n + i] = A[i * n + i];
        for (size_t j = 0; j < i; ++j) {
            const double a = A[i * n + j], b = A[j * n + i];
            out[i * n + j] = out[j * n + i] = a == b ? a : 0.5 * a + 0.5 * b;
        }
    }
    return 1;
}

gf_status gf_kalman_check(const gf_kalman *kf)
{
    if (!kf)
        return GF_ERR_NULL_POINTER;
    if (kf->n == 0 || kf->n > NMAX)
        return GF_ERR_BAD_SIZE;
    for (size_t i = 0; i < kf->n; ++i)
        if (!isfinite(kf->x[i]))
            return GF_ERR_NONFINITE_INPUT;
    for (size_t i = 0; i < kf->n * kf->n; ++i)
        if (!isfinite(kf->P[i]))
            return GF_ERR_NONFINITE_INPUT;
    return GF_OK;
}

gf_status gf_kalman_init(gf_kalman *kf, size_t n, const double *x0, const double *P0)
{
    if (!kf || !x0 || !P0)
        return GF_ERR_NULL_POINTER;
    if (n == 0 || n > NMAX)
        return GF_ERR_BAD_SIZE;
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(x0[i]))
            return GF_ERR_NONFINITE_INPUT;
    for (size_t i = 0; i < n * n; ++i)
        if (!isfinite(P0[i]))
            return GF_ERR_NONFINITE_INPUT;
    double P[NMAX * NMAX];
    if (!symmetrised(n, P0, P))
        return GF_ERR_BAD_PARAMETER;
    memset(kf, 0, sizeof *kf);
    kf->n = n;
    memcpy(kf->x, x0, n * sizeof *x0);
    memcpy(kf->P, P, n * n * sizeof *P);
    return GF_OK;
}

gf_status gf_kalman_predict(gf_kalman *kf, const double *F, const double *Q, int propagate_x)
{
    if (!kf)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (n == 0 || n > NMAX)
        return GF_ERR_BAD_SIZE;
    double Qs[NMAX * NMAX];
    if (Q && !symmetrised(n, Q, Qs))
        return GF_ERR_BAD_PARAMETER;
    if (F) {
        double FP[NMAX * NMAX];
        mat_mul(n, n, n, F, kf->P, FP);
        for (size_t i = 0; i < n; ++i)
            for (size_t j = i; j < n; ++j) {
                double acc = 0.0;
                for (size_t k = 0; k < n; ++k)
                    acc += FP[i * n + k] * F[j * n + k];
                kf->P[i * n + j] = kf->P[j * n + i] = acc;
            }
        if (propagate_x) {
            double x[NMAX];
            mat_mul(n, n, 1, F, kf->x, x);
            memcpy(kf->x, x, n * sizeof *x);
        }
    }
    if (Q)
        for (size_t i = 0; i < n * n; ++i)
            kf->P[i] += Qs[i];
    return GF_OK;
}

gf_status gf_kalman_update(gf_kalman *kf, size_t m, const double *residual, const double *H,
                           const double *R, double *nis)
{
    if (!kf || !residual || !H || !R)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (m == 0 || m > MMAX || n == 0 || n > NMAX)
        return GF_ERR_BAD_SIZE;
    for (size_t i = 0; i < m; ++i)
        if (!isfinite(residual[i]))
            return GF_ERR_NONFINITE_INPUT;
    /* R symmetric (then symmetrised: the one matrix used below) and positive definite
     * itself, not only S = H P H^T + R */
    double R_s[MMAX * MMAX];
    {
        for (size_t i = 0; i < m * m; ++i)
            if (!isfinite(R[i]))
                return GF_ERR_NONFINITE_INPUT;
        if (!symmetrised(m, R, R_s))
            return GF_ERR_BAD_PARAMETER;
        double LR[MMAX * MMAX];
        memcpy(LR, R_s, m * m * sizeof *R_s);
        const gf_status st_r = gf_cholesky(m, LR);
        if (st_r != GF_OK)
            return st_r;
    }
    R = R_s;
    /* PHt = P H^T (n x m), S = H P H^T + R (m x m) */
    double PHt[NMAX * MMAX], S[MMAX * MMAX], L[MMAX * MMAX];
    mat_mul_bt(n, n, m, kf->P, H, PHt);
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < m; ++j) {
            double acc = R[i * m + j];
            for (size_t k = 0; k < n; ++k)
                acc += H[i * n + k] * PHt[k * m + j];
            S[i * m + j] = acc;
        }
    for (size_t i = 0; i < m; ++i) /* symmetrise against round-off */
        for (size_t j = i + 1; j < m; ++j)
            S[i * m + j] = S[j * m + i] = 0.5 * (S[i * m + j] + S[j * m + i]);
    memcpy(L, S, m * m * sizeof *S);
    const gf_status st = gf_cholesky(m, L);
    if (st != GF_OK)
        return st;
    /* K^T = S^-1 (P H^T)^T  (m x n) */
    double Kt[MMAX * NMAX];
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < n; ++j)
            Kt[i * n + j] = PHt[j * m + i];
    gf_cholesky_solve(m, L, n, Kt);
    if (nis) {
        double y[MMAX];
        memcpy(y, residual, m * sizeof *y);
        gf_cholesky_solve(m, L, 1, y);
        double acc = 0.0;
        for (size_t i = 0; i < m; ++i)
            acc += residual[i] * y[i];
        *nis = acc;
    }
    for (size_t i = 0; i < n; ++i) {
        double acc = 0.0;
        for (size_t j = 0; j < m; ++j)
            acc += Kt[j * n + i] * residual[j];
        kf->x[i] += acc;
    }
    /* Joseph form: A = I - K H;  P <- A P A^T + K R K^T */
    double A[NMAX * NMAX], AP[NMAX * NMAX], KR[NMAX * MMAX];
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = (i == j) ? 1.0 : 0.0;
            for (size_t k = 0; k < m; ++k)
                acc -= Kt[k * n + i] * H[k * n + j];
            A[i * n + j] = acc;
        }
    mat_mul(n, n, n, A, kf->P, AP);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < m; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < m; ++k)
                acc += Kt[k * n + i] * R[k * m + j];
            KR[i * m + j] = acc;
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < n; ++k)
                acc += AP[i * n + k] * A[j * n + k];
            for (size_t k = 0; k < m; ++k)
                acc += KR[i * m + k] * Kt[k * n + j];
            kf->P[i * n + j] = kf->P[j * n + i] = acc;
        }
    return GF_OK;
}
