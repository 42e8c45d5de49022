/* gf_kalman.c — see gf_kalman.h. */
#include "gf_kalman.h"

#include <math.h>
#include <string.h>

#include "gf_linalg.h"

#define NMAX GF_KF_MAX_N
#define MMAX GF_KF_MAX_M

static int gf_all_finite_n(const double *a, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(a[i]))
            return 0;
    return 1;
}

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
    return gf_kalman_update_gated(kf, m, residual, H, R, 0.0, nis, NULL);
}

gf_status gf_kalman_update_gated(gf_kalman *kf, size_t m, const double *residual,
                                 const double *H, const double *R, double nis_max,
                                 double *nis, int *accepted)
{
    if (accepted)
        *accepted = 0;
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
    if (nis || nis_max > 0.0) {
        double y[MMAX];
        memcpy(y, residual, m * sizeof *y);
        gf_cholesky_solve(m, L, 1, y);
        double acc = 0.0;
        for (size_t i = 0; i < m; ++i)
            acc += residual[i] * y[i];
        if (nis)
            *nis = acc;
        if (nis_max > 0.0 && !(acc <= nis_max))
            return GF_OK; /* gated: unchanged, *accepted = 0 */
    }
    if (accepted)
        *accepted = 1;
    for (size_t i = 0; i < n; ++i) {
        double acc = 0.0;
        for (size_t j = 0; j < m; ++j)
            acc += Kt[j * n + i] * residual[j];
        kf->x[i] += acc;
    }
    /* Joseph form (I - K H) P (I - K H)^T + K R K^T, multiplied out in factors so that it
     * costs O(n^2 m) instead of O(n^3):
     *   X = (I - K H) P = P - K (H P),      H P = (P H^T)^T (P symmetric)
     *   P <- X (I - K H)^T + K R K^T = X + (K R - X H^T) K^T */
    double X[NMAX * NMAX], D[NMAX * MMAX];
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = kf->P[i * n + j];
            for (size_t k = 0; k < m; ++k)
                acc -= Kt[k * n + i] * PHt[j * m + k];
            X[i * n + j] = acc;
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < m; ++k) {
            double kr = 0.0, xh = 0.0;
            for (size_t l = 0; l < m; ++l)
                kr += Kt[l * n + i] * R[l * m + k];
            const double *hrow = H + k * n, *xrow = X + i * n;
            for (size_t l = 0; l < n; ++l)
                xh += xrow[l] * hrow[l];
            D[i * m + k] = kr - xh;
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j) {
            double acc = X[i * n + j];
            for (size_t k = 0; k < m; ++k)
                acc += D[i * m + k] * Kt[k * n + j];
            kf->P[i * n + j] = kf->P[j * n + i] = acc;
        }
    return GF_OK;
}

/* ---- structured predict ------------------------------------------------------------ */

#define axpy4 gf_axpy4
#define PADDED GF_PADDED

/* The structured predict is a few thousand vectorisable multiply-adds: on x86-64 with
 * GCC it is compiled twice, for the baseline (SSE2) and for AVX2, and the loader picks
 * the one the processor runs (function multi-versioning). Both do the same IEEE
 * operations in the same order (no FMA: -ffp-contract=off), so their results are equal
 * bit for bit. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) && \
    !defined(GF_NO_MULTIVERSION)
#define GF_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GF_VECTOR_CLONES
#endif

gf_status gf_kalman_predict_sparse(gf_kalman *kf, const double *A, const double *q1,
                                   const double *q2)
{
    if (!kf || !A)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (n == 0 || n > NMAX)
        return GF_ERR_BAD_SIZE;
    /* the non-zeros of A, row by row (compressed sparse rows) */
    unsigned char col[NMAX * NMAX];
    double val[NMAX * NMAX];
    size_t start[NMAX + 1], nnz = 0;
    for (size_t i = 0; i < n; ++i) {
        start[i] = nnz;
        for (size_t j = 0; j < n; ++j) {
            const double a = A[i * n + j];
            if (a != 0.0) {
                col[nnz] = (unsigned char)j;
                val[nnz++] = a;
            }
        }
    }
    start[n] = nnz;
    return gf_kalman_predict_csr(kf, start, col, val, q1, q2);
}

GF_VECTOR_CLONES
gf_status gf_kalman_predict_csr(gf_kalman *kf, const size_t *start, const unsigned char *col,
                                const double *val, const double *q1, const double *q2)
{
    if (!kf || !start || !col || !val)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (n == 0 || n > NMAX || start[0] != 0)
        return GF_ERR_BAD_SIZE;
    for (size_t i = 0; i < n; ++i)
        if (start[i + 1] < start[i] || start[i + 1] > NMAX * NMAX)
            return GF_ERR_BAD_SIZE;
    for (size_t p = 0; p < start[n]; ++p)
        if (col[p] >= n)
            return GF_ERR_BAD_SIZE;
    const size_t s = PADDED(n);   /* row stride of the work matrices */
    /* (I + A) M (I + A)^T = M + G + G^T + G A^T with M = P + D1 (symmetric), G = A M:
     * G row by row (vectorised axpys over rows padded to the stride), then the upper
     * triangle, (G A^T)_ij = sum over the non-zeros A_jl of A_jl G_il */
    double M[NMAX * NMAX], G[NMAX * NMAX];
    for (size_t i = 0; i < n; ++i) {
        memcpy(M + i * s, kf->P + i * n, n * sizeof *M);
        for (size_t j = n; j < s; ++j)
            M[i * s + j] = 0.0;
        if (q1)
            M[i * s + i] += q1[i];
    }
    memset(G, 0, n * s * sizeof *G);
    for (size_t i = 0; i < n; ++i)
        for (size_t p = start[i]; p < start[i + 1]; ++p)
            axpy4(s, val[p], M + (size_t)col[p] * s, G + i * s);
    /* the transpose of G, so that column j of P, (G A^T)_.j = sum_p A_jl G_.l, is a sum of
     * rows of G^T: axpys again, over i = 0..j (rounded up to the padding) */
    double Gt[NMAX * NMAX], Pc[NMAX * NMAX];
    for (size_t i = 0; i < n; ++i)
        for (size_t l = 0; l < n; ++l)
            Gt[l * s + i] = G[i * s + l];
    for (size_t l = 0; l < n; ++l)
        for (size_t i = n; i < s; ++i)
            Gt[l * s + i] = 0.0;
    /* Pc row j = column j of the new P (entries 0..j used) */
    for (size_t j = 0; j < n; ++j) {
        double *pc = Pc + j * s;
        const size_t len = PADDED(j + 1);
        for (size_t i = 0; i < len; ++i)
            pc[i] = M[j * s + i] + Gt[j * s + i] + G[j * s + i];   /* M_ij + G_ij + G_ji (M sym) */
        for (size_t p = start[j]; p < start[j + 1]; ++p)
            axpy4(len, val[p], Gt + (size_t)col[p] * s, pc);
    }
    /* a non-finite A or q reaches the diagonal (Inf * 0 = NaN): refuse, P unchanged */
    int finite = 1;
    for (size_t j = 0; j < n; ++j) {
        if (q2)
            Pc[j * s + j] += q2[j];
        finite &= isfinite(Pc[j * s + j]) != 0;
    }
    if (!finite)
        return GF_ERR_NONFINITE_INPUT;
    for (size_t j = 0; j < n; ++j)
        for (size_t i = 0; i <= j; ++i)
            kf->P[i * n + j] = kf->P[j * n + i] = Pc[j * s + i];
    return GF_OK;
}

/* ---- unscented transform ------------------------------------------------------------ */

gf_status gf_ukf_weights_init(gf_ukf_weights *w, size_t n, double alpha, double beta,
                              double kappa)
{
    if (!w)
        return GF_ERR_NULL_POINTER;
    if (n == 0 || n > NMAX)
        return GF_ERR_BAD_SIZE;
    if (!(alpha > 0.0) || !isfinite(alpha) || !isfinite(beta) || !isfinite(kappa) ||
        !((double)n + kappa > 0.0))
        return GF_ERR_BAD_PARAMETER;
    const double N = (double)n;
    const double lambda = alpha * alpha * (N + kappa) - N;   /* seed 004, below eq. 28 */
    w->n = n;
    w->lambda = lambda;
    w->gamma = sqrt(N + lambda);                             /* eq. 25 */
    w->wm0 = lambda / (N + lambda);                          /* eq. 26 */
    w->wc0 = w->wm0 + 1.0 - alpha * alpha + beta;            /* eq. 27 */
    w->wi = 0.5 / (N + lambda);                              /* eq. 28 */
    return GF_OK;
}

gf_status gf_ukf_sigma_points(const gf_kalman *kf, const gf_ukf_weights *w, double *X)
{
    if (!kf || !w || !X)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (n == 0 || n > NMAX || w->n != n)
        return GF_ERR_BAD_SIZE;
    double L[NMAX * NMAX];
    memcpy(L, kf->P, n * n * sizeof *L);
    const gf_status st = gf_cholesky(n, L);
    if (st != GF_OK)
        return st;
    memcpy(X, kf->x, n * sizeof *X);
    for (size_t j = 0; j < n; ++j) {
        double *plus = X + (1 + j) * n, *minus = X + (1 + n + j) * n;
        for (size_t i = 0; i < n; ++i) {
            const double d = w->gamma * L[i * n + j];   /* column j of L */
            plus[i] = kf->x[i] + d;
            minus[i] = kf->x[i] - d;
        }
    }
    return GF_OK;
}

/* mean (m values) of the 2n+1 points Y ((2n+1) x m) */
static void ukf_mean(const gf_ukf_weights *w, size_t m, const double *Y, double *mean)
{
    const size_t np = 2 * w->n + 1;
    for (size_t i = 0; i < m; ++i) {
        double acc = 0.0;
        for (size_t p = 1; p < np; ++p)
            acc += Y[p * m + i];
        mean[i] = w->wm0 * Y[i] + w->wi * acc;
    }
}

/* C (ma x mb) = sum_p Wc_p (Ya_p - ma)(Yb_p - mb)^T */
static void ukf_cross(const gf_ukf_weights *w, size_t ma, const double *Ya, const double *mean_a,
                      size_t mb, const double *Yb, const double *mean_b, double *C)
{
    const size_t np = 2 * w->n + 1;
    for (size_t i = 0; i < ma * mb; ++i)
        C[i] = 0.0;
    for (size_t p = 0; p < np; ++p) {
        const double wc = p == 0 ? w->wc0 : w->wi;
        double da[NMAX], db[NMAX];
        for (size_t i = 0; i < ma; ++i)
            da[i] = Ya[p * ma + i] - mean_a[i];
        for (size_t j = 0; j < mb; ++j)
            db[j] = Yb[p * mb + j] - mean_b[j];
        for (size_t i = 0; i < ma; ++i) {
            const double s = wc * da[i];
            for (size_t j = 0; j < mb; ++j)
                C[i * mb + j] += s * db[j];
        }
    }
}

gf_status gf_ukf_predict(gf_kalman *kf, const gf_ukf_weights *w, const double *Y,
                         const double *Q)
{
    if (!kf || !w || !Y)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (n == 0 || n > NMAX || w->n != n)
        return GF_ERR_BAD_SIZE;
    if (!gf_all_finite_n(Y, (2 * n + 1) * n) || (Q && !gf_all_finite_n(Q, n * n)))
        return GF_ERR_NONFINITE_INPUT;
    double x[NMAX], P[NMAX * NMAX];
    ukf_mean(w, n, Y, x);
    ukf_cross(w, n, Y, x, n, Y, x, P);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j) {
            double p = 0.5 * (P[i * n + j] + P[j * n + i]);
            if (Q)
                p += 0.5 * (Q[i * n + j] + Q[j * n + i]);
            P[i * n + j] = P[j * n + i] = p;
        }
    memcpy(kf->x, x, n * sizeof *x);
    memcpy(kf->P, P, n * n * sizeof *P);
    return GF_OK;
}

gf_status gf_ukf_update(gf_kalman *kf, const gf_ukf_weights *w, const double *X, size_t m,
                        const double *Zp, const double *z, const double *R, double nis_max,
                        double *nis, int *accepted)
{
    if (accepted)
        *accepted = 0;
    if (!kf || !w || !X || !Zp || !z || !R)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (n == 0 || n > NMAX || w->n != n || m == 0 || m > MMAX)
        return GF_ERR_BAD_SIZE;
    const size_t np = 2 * n + 1;
    if (!gf_all_finite_n(Zp, np * m) || !gf_all_finite_n(z, m) || !gf_all_finite_n(R, m * m))
        return GF_ERR_NONFINITE_INPUT;
    {
        double LR[MMAX * MMAX];
        memcpy(LR, R, m * m * sizeof *R);
        const gf_status st_r = gf_cholesky(m, LR);
        if (st_r != GF_OK)
            return st_r;
    }
    double xm[NMAX], ym[MMAX], Pyy[MMAX * MMAX], Pxy[NMAX * MMAX], L[MMAX * MMAX];
    ukf_mean(w, n, X, xm);
    ukf_mean(w, m, Zp, ym);
    ukf_cross(w, m, Zp, ym, m, Zp, ym, Pyy);                  /* eq. 34 */
    ukf_cross(w, n, X, xm, m, Zp, ym, Pxy);                   /* eq. 35 */
    for (size_t i = 0; i < m; ++i)
        for (size_t j = i; j < m; ++j)
            Pyy[i * m + j] = Pyy[j * m + i] =
                0.5 * (Pyy[i * m + j] + Pyy[j * m + i] + R[i * m + j] + R[j * m + i]);
    memcpy(L, Pyy, m * m * sizeof *L);
    const gf_status st = gf_cholesky(m, L);
    if (st != GF_OK)
        return st;
    /* K^T = Pyy^-1 Pxy^T (m x n), eq. 36 */
    double Kt[MMAX * NMAX], r[MMAX];
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < n; ++j)
            Kt[i * n + j] = Pxy[j * m + i];
    gf_cholesky_solve(m, L, n, Kt);
    for (size_t i = 0; i < m; ++i)
        r[i] = z[i] - ym[i];
    double nis_value;
    {
        double y[MMAX];
        memcpy(y, r, m * sizeof *y);
        gf_cholesky_solve(m, L, 1, y);
        nis_value = 0.0;
        for (size_t i = 0; i < m; ++i)
            nis_value += r[i] * y[i];
    }
    if (nis)
        *nis = nis_value;
    if (nis_max > 0.0 && !(nis_value <= nis_max))
        return GF_OK; /* gated */
    double x_new[NMAX], P_new[NMAX * NMAX];
    for (size_t i = 0; i < n; ++i) {                          /* eq. 37 */
        double acc = 0.0;
        for (size_t j = 0; j < m; ++j)
            acc += Kt[j * n + i] * r[j];
        x_new[i] = kf->x[i] + acc;
    }
    /* eq. 38: P - K Pyy K^T = P - Pxy K^T */
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < m; ++k)
                acc += Pxy[i * m + k] * Kt[k * n + j] + Pxy[j * m + k] * Kt[k * n + i];
            P_new[i * n + j] = P_new[j * n + i] = kf->P[i * n + j] - 0.5 * acc;
        }
    for (size_t i = 0; i < n; ++i)
        if (!(P_new[i * n + i] >= 0.0) || !isfinite(P_new[i * n + i]))
            return GF_ERR_DIVERGED;
    if (accepted)
        *accepted = 1;
    memcpy(kf->x, x_new, n * sizeof *x_new);
    memcpy(kf->P, P_new, n * n * sizeof *P_new);
    return GF_OK;
}

/* ---- Rauch-Tung-Striebel ------------------------------------------------------------ */

gf_status gf_kalman_rts_step(size_t n, const double *P_post, const double *x_post,
                             const double *Phi, const double *P_prior_next,
                             const double *x_prior_next, const double *P_s_next,
                             const double *x_s_next, double *x_s, double *P_s)
{
    if (!P_post || !Phi || !P_prior_next || !P_s_next || !x_s_next || !x_s || !P_s)
        return GF_ERR_NULL_POINTER;
    if (n == 0 || n > NMAX)
        return GF_ERR_BAD_SIZE;
    /* A^T = P_k+1|k^-1 Phi P_k|k  (P symmetric), so A = (P_k+1|k^-1 Phi P_k|k)^T */
    double L[NMAX * NMAX], At[NMAX * NMAX];
    memcpy(L, P_prior_next, n * n * sizeof *L);
    const gf_status st = gf_cholesky(n, L);
    if (st != GF_OK)
        return st;
    mat_mul(n, n, n, Phi, P_post, At);
    gf_cholesky_solve(n, L, n, At);
    double dx[NMAX], dP[NMAX * NMAX], T[NMAX * NMAX], xs[NMAX];
    for (size_t i = 0; i < n; ++i)
        dx[i] = x_s_next[i] - (x_prior_next ? x_prior_next[i] : 0.0);
    for (size_t i = 0; i < n * n; ++i)
        dP[i] = P_s_next[i] - P_prior_next[i];
    for (size_t i = 0; i < n; ++i) {
        double acc = x_post ? x_post[i] : 0.0;
        for (size_t k = 0; k < n; ++k)
            acc += At[k * n + i] * dx[k];
        xs[i] = acc;
    }
    /* T = dP A^T (n x n), then P_s = P_post + A T, upper triangle mirrored */
    mat_mul(n, n, n, dP, At, T);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < n; ++k)
                acc += At[k * n + i] * T[k * n + j];
            const double p = 0.5 * (P_post[i * n + j] + P_post[j * n + i]) + acc;
            P_s[i * n + j] = p;
            if (j != i)
                P_s[j * n + i] = p;
        }
    memcpy(x_s, xs, n * sizeof *xs);
    return GF_OK;
}
