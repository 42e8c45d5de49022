/* gf_ukf.c — the unscented transform of the Kalman engine (seed 004 section 2, eq.
 * 25-38): weights, sigma points, time and measurement updates; see gf_kalman.h. */
#include "est/gf_kalman.h"

#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "est/gf_kalman_internal.h"

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

/* mean (m values) of the 2n+1 points Y ((2n+1) x m): the points' rows summed in order */
static void ukf_mean(const gf_ukf_weights *w, size_t m, const double *Y, double *mean)
{
    const size_t np = 2 * w->n + 1;
    double acc[NMAX];
    for (size_t i = 0; i < m; ++i)
        acc[i] = 0.0;
    for (size_t p = 1; p < np; ++p)
        for (size_t i = 0; i < m; ++i)
            acc[i] += Y[p * m + i];
    for (size_t i = 0; i < m; ++i)
        mean[i] = w->wm0 * Y[i] + w->wi * acc[i];
}

/* C (ma x mb) = sum_p Wc_p (Ya_p - ma)(Yb_p - mb)^T */
static void ukf_cross(const gf_ukf_weights *w, size_t ma, const double *Ya, const double *mean_a,
                      size_t mb, const double *Yb, const double *mean_b, double *restrict C)
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

/* Row i of the upper triangle of sum_p Wc_p d_p d_p^T over NB blocks of 4 from column
 * c0 (the block holding the diagonal), accumulated in registers over the points: the
 * deviations d_p are the rows of D (stride S, padded with zeros). */
static GF_ALWAYS_INLINE void cov_row(const size_t NB, const size_t S, const gf_ukf_weights *w,
                                     size_t np, const double *D, size_t i, size_t c0, double *out)
{
    gf_v4 acc[SMAX / 4];
    const double s0 = w->wc0 * D[i];
    for (size_t k = 0; k < NB; ++k)
        acc[k] = GF_V4_SCALE(s0, D + c0 + 4 * k);
    for (size_t p = 1; p < np; ++p) {
        const double *d = D + p * S;
        const double s = w->wi * d[i];
        for (size_t k = 0; k < NB; ++k)
            GF_V4_AXPY(acc[k], s, d + c0 + 4 * k);
    }
    for (size_t k = 0; k < NB; ++k)
        GF_V4_STORE(out + c0 + 4 * k, acc[k]);
}

static GF_ALWAYS_INLINE void cov_upper_rows(const size_t S, const gf_ukf_weights *w, size_t n,
                                            const double *Y, const double *mean, double *C)
{
    const size_t np = 2 * n + 1;
    double D[(2 * NMAX + 1) * SMAX];
    for (size_t p = 0; p < np; ++p) {
        for (size_t j = 0; j < n; ++j)
            D[p * S + j] = Y[p * n + j] - mean[j];
        for (size_t j = n; j < S; ++j)
            D[p * S + j] = 0.0;
    }
    for (size_t i = 0; i < n; ++i) {
        const size_t c0 = i / 4 * 4;
        switch ((S - c0) / 4) {  /* blocks from the diagonal's: a compile-time count */
        case 1: cov_row(1, S, w, np, D, i, c0, C + i * S); break;
        case 2: cov_row(2, S, w, np, D, i, c0, C + i * S); break;
        case 3: cov_row(3, S, w, np, D, i, c0, C + i * S); break;
        case 4: cov_row(4, S, w, np, D, i, c0, C + i * S); break;
        case 5: cov_row(5, S, w, np, D, i, c0, C + i * S); break;
        case 6: cov_row(6, S, w, np, D, i, c0, C + i * S); break;
        default: cov_row((S - c0) / 4, S, w, np, D, i, c0, C + i * S); break;
        }
    }
}

/* The upper triangle (j >= i) of C = sum_p Wc_p (Y_p - m)(Y_p - m)^T (n x n) in rows of
 * stride PADDED(n) (entries left of the diagonal's block of 4 are not written); each
 * entry is summed over the points in their order. */
GF_VECTOR_CLONES
static void ukf_cov_upper(const gf_ukf_weights *w, size_t n, const double *Y, const double *mean,
                          double *C)
{
    const size_t s = PADDED(n);
    if (s == 16)
        cov_upper_rows(16, w, n, Y, mean, C);
    else if (s == 20)
        cov_upper_rows(20, w, n, Y, mean, C);
    else if (s == 24)
        cov_upper_rows(24, w, n, Y, mean, C);
    else
        cov_upper_rows(s, w, n, Y, mean, C);
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
    double x[NMAX], C[NMAX * SMAX];
    ukf_mean(w, n, Y, x);
    ukf_cov_upper(w, n, Y, x, C);
    const size_t s = PADDED(n);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j) {
            double p = C[i * s + j];
            if (Q)
                p += 0.5 * (Q[i * n + j] + Q[j * n + i]);
            kf->P[i * n + j] = kf->P[j * n + i] = p;
        }
    memcpy(kf->x, x, n * sizeof *x);
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

