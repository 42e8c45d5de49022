/* gf_kalman.c — the Kalman engine: checks, predict (dense and structured), the gated
 * Joseph-form update and the Rauch-Tung-Striebel step; see gf_kalman.h. The unscented
 * transform is gf_ukf.c. */
#include "est/gf_kalman.h"

#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "est/gf_kalman_internal.h"

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
    const size_t n = kf->n;
    for (size_t i = 0; i < n * n; ++i)
        if (!isfinite(kf->P[i]))
            return GF_ERR_NONFINITE_INPUT;
    double C[NMAX * NMAX], s[NMAX];
    for (size_t i = 0; i < n; ++i) {
        const double v = kf->P[i * n + i];
        if (!(v >= 0.0))
            return GF_ERR_BAD_PARAMETER;
        s[i] = v > 0.0 ? 1.0 / sqrt(v) : 0.0;
        /* a state known exactly (variance 0, e.g. a bias held constant) is uncorrelated */
        for (size_t j = 0; v == 0.0 && j < n; ++j)
            if (j != i && (kf->P[i * n + j] != 0.0 || kf->P[j * n + i] != 0.0))
                return GF_ERR_BAD_PARAMETER;
    }
    if (!symmetrised(n, kf->P, C))
        return GF_ERR_BAD_PARAMETER;
    /* the correlation matrix (unit diagonal: the test does not depend on the units of the
     * states), nudged by 1e-10 so that round-off-level indefiniteness passes */
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j)
            C[i * n + j] *= s[i] * s[j];
    for (size_t i = 0; i < n; ++i)
        C[i * n + i] = 1.0 + 1e-10;
    return gf_cholesky(n, C) == GF_OK ? GF_OK : GF_ERR_BAD_PARAMETER;
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

static gf_status joseph_update(gf_kalman *kf, size_t m, const double *residual, const double *H,
                               const double *R, double nis_max, double *nis, int *accepted);

/* Row i of X + D K^T over NB blocks of 4 from column c0, accumulated in registers (x: row
 * i of X, d: row i of D, Kt: K^T in rows of stride S) */
static GF_ALWAYS_INLINE void xdk_row(const size_t NB, const size_t S, size_t m, const double *x,
                                     const double *d, const double *Kt, size_t c0, double *out)
{
    gf_v4 acc[SMAX / 4];
    for (size_t b = 0; b < NB; ++b)
        acc[b] = GF_V4_LOAD(x + c0 + 4 * b);
    for (size_t k = 0; k < m; ++k)
        for (size_t b = 0; b < NB; ++b)
            GF_V4_AXPY(acc[b], d[k], Kt + k * S + c0 + 4 * b);
    for (size_t b = 0; b < NB; ++b)
        GF_V4_STORE(out + c0 + 4 * b, acc[b]);
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
    return joseph_update(kf, m, residual, H, R, nis_max, nis, accepted);
}

/* Joseph-form update in rows padded to the stride S (vector blocks of 4), see
 * joseph_update. P's rows are read S entries at a time from their stride n (the entries
 * past the row are the next row's, or beyond n x n within the array: they only reach the
 * padding lanes, which are never stored into P except past its last row, where they are
 * written back unchanged). */
static GF_ALWAYS_INLINE gf_status joseph_rows(const size_t S, gf_kalman *kf, size_t m,
                                              const double *residual, const double *H,
                                              const double *R, double nis_max, double *nis,
                                              int *accepted)
{
    const size_t n = kf->n;
    const double *P = kf->P;
    /* the non-zeros of each row of H: hnz[k][0 .. hcount[k]) */
    unsigned char hnz[MMAX][NMAX];
    size_t hcount[MMAX];
    for (size_t k = 0; k < m; ++k) {
        hcount[k] = 0;
        for (size_t l = 0; l < n; ++l)
            if (H[k * n + l] != 0.0)
                hnz[k][hcount[k]++] = (unsigned char)l;
    }
    /* HP = H P, padding zero */
    double HP[MMAX * SMAX], S_[MMAX * MMAX], L[MMAX * MMAX], Kt[MMAX * SMAX];
    for (size_t k = 0; k < m; ++k) {
        gf_v4 acc[SMAX / 4];
        for (size_t b = 0; b < S / 4; ++b)
            acc[b] = GF_V4_SET(0.0, 0.0, 0.0, 0.0);
        for (size_t q = 0; q < hcount[k]; ++q) {
            const size_t l = hnz[k][q];
            const double h = H[k * n + l];
            for (size_t b = 0; b < S / 4; ++b)
                GF_V4_AXPY(acc[b], h, P + l * n + 4 * b);
        }
        for (size_t b = 0; b < S / 4; ++b)
            GF_V4_STORE(HP + k * S + 4 * b, acc[b]);
        for (size_t j = n; j < S; ++j)
            HP[k * S + j] = 0.0;
    }
    /* S = H (HP)^T + R */
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < m; ++j) {
            double acc = R[i * m + j];
            for (size_t q = 0; q < hcount[i]; ++q) {
                const size_t k = hnz[i][q];
                acc += H[i * n + k] * HP[j * S + k];
            }
            S_[i * m + j] = acc;
        }
    for (size_t i = 0; i < m; ++i) /* symmetrise against round-off */
        for (size_t j = i + 1; j < m; ++j)
            S_[i * m + j] = S_[j * m + i] = 0.5 * (S_[i * m + j] + S_[j * m + i]);
    memcpy(L, S_, m * m * sizeof *S_);
    const gf_status st = gf_cholesky(m, L);
    if (st != GF_OK)
        return st;
    /* K^T = S^-1 HP (m x S; the padding stays zero) */
    memcpy(Kt, HP, m * S * sizeof *Kt);
    gf_cholesky_solve(m, L, S, Kt);
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
            acc += Kt[j * S + i] * residual[j];
        kf->x[i] += acc;
    }
    /* X = P - K HP */
    double X[NMAX * SMAX], D[NMAX * MMAX];
    for (size_t i = 0; i < n; ++i) {
        gf_v4 acc[SMAX / 4];
        for (size_t b = 0; b < S / 4; ++b)
            acc[b] = GF_V4_LOAD(P + i * n + 4 * b);
        for (size_t k = 0; k < m; ++k)
            for (size_t b = 0; b < S / 4; ++b)
                GF_V4_AXPY(acc[b], -Kt[k * S + i], HP + k * S + 4 * b);
        for (size_t b = 0; b < S / 4; ++b)
            GF_V4_STORE(X + i * S + 4 * b, acc[b]);
    }
    /* D = K R - X H^T, as its columns D_.k = sum_l R_lk K_.l - sum_l H_kl X_.l over the
     * rows' lanes; column l of X is P_l - sum_k HP_kl K_.k (P symmetric), the same
     * operations as its entries in X's rows */
    double Dt[MMAX * SMAX];
    for (size_t k = 0; k < m; ++k) {
        gf_v4 kr[SMAX / 4], xh[SMAX / 4];
        for (size_t b = 0; b < S / 4; ++b)
            kr[b] = xh[b] = GF_V4_SET(0.0, 0.0, 0.0, 0.0);
        for (size_t l = 0; l < m; ++l)
            for (size_t b = 0; b < S / 4; ++b)
                GF_V4_AXPY(kr[b], R[l * m + k], Kt + l * S + 4 * b);
        for (size_t q = 0; q < hcount[k]; ++q) {
            const size_t l = hnz[k][q];
            gf_v4 xl[SMAX / 4];          /* column l of X */
            for (size_t b = 0; b < S / 4; ++b)
                xl[b] = GF_V4_LOAD(P + l * n + 4 * b);
            for (size_t j = 0; j < m; ++j)
                for (size_t b = 0; b < S / 4; ++b)
                    GF_V4_AXPY(xl[b], -HP[j * S + l], Kt + j * S + 4 * b);
            for (size_t b = 0; b < S / 4; ++b)
                GF_V4_AXPYV(xh[b], H[k * n + l], xl[b]);
        }
        for (size_t b = 0; b < S / 4; ++b)
            GF_V4_STORE(Dt + k * S + 4 * b, GF_V4_SUB(kr[b], xh[b]));
    }
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < m; ++k)
            D[i * m + k] = Dt[k * S + i];
    /* P = X + D K^T: the upper triangle (row i from the block holding the diagonal),
     * then mirrored (the rows' padding and left-of-diagonal lanes are overwritten) */
    double U[NMAX * SMAX];
    for (size_t i = 0; i < n; ++i) {
        const size_t c0 = i / 4 * 4;
        switch ((S - c0) / 4) {  /* blocks from the diagonal's: a compile-time count */
        case 1: xdk_row(1, S, m, X + i * S, D + i * m, Kt, c0, U + i * S); break;
        case 2: xdk_row(2, S, m, X + i * S, D + i * m, Kt, c0, U + i * S); break;
        case 3: xdk_row(3, S, m, X + i * S, D + i * m, Kt, c0, U + i * S); break;
        case 4: xdk_row(4, S, m, X + i * S, D + i * m, Kt, c0, U + i * S); break;
        case 5: xdk_row(5, S, m, X + i * S, D + i * m, Kt, c0, U + i * S); break;
        case 6: xdk_row(6, S, m, X + i * S, D + i * m, Kt, c0, U + i * S); break;
        default: xdk_row((S - c0) / 4, S, m, X + i * S, D + i * m, Kt, c0, U + i * S); break;
        }
    }
    for (size_t i = 0; i < n; ++i) {
        double *p = kf->P + i * n;
        const size_t c0 = i / 4 * 4;
        for (size_t k = c0; k < S; k += 4)
            GF_V4_STORE(p + k, GF_V4_LOAD(U + i * S + k));
        for (size_t j = 0; j < i; ++j)
            p[j] = U[j * S + i];
    }
    return GF_OK;
}

/* The update after the checks (R symmetric positive definite). Every product is formed
 * over rows padded to a multiple of 4 (vectorised), skipping the zeros of H
 * (measurement models are mostly zeros); each entry sees the same operations in the
 * same order as the plain products:
 *   HP = H P (m x n; = (P H^T)^T, P symmetric),  S = H (HP)^T + R,
 *   K^T = S^-1 HP,  x += K r,
 *   Joseph form (I - K H) P (I - K H)^T + K R K^T multiplied out in factors, O(n^2 m):
 *   X = (I - K H) P = P - K HP,  P <- X + (K R - X H^T) K^T  (upper triangle, mirrored) */
GF_VECTOR_CLONES
static gf_status joseph_update(gf_kalman *kf, size_t m, const double *residual, const double *H,
                               const double *R, double nis_max, double *nis, int *accepted)
{
    const size_t s = PADDED(kf->n);
    if (s == 8)
        return joseph_rows(8, kf, m, residual, H, R, nis_max, nis, accepted);
    if (s == 16)
        return joseph_rows(16, kf, m, residual, H, R, nis_max, nis, accepted);
    if (s == 20)
        return joseph_rows(20, kf, m, residual, H, R, nis_max, nis, accepted);
    if (s == 24)
        return joseph_rows(24, kf, m, residual, H, R, nis_max, nis, accepted);
    return joseph_rows(s, kf, m, residual, H, R, nis_max, nis, accepted);
}

/* ---- structured predict ------------------------------------------------------------ */


/* One row of (I + A) X over its first NB blocks of 4, accumulated in registers:
 * out = in + sum over the set bits l of mask of a_row[l] X_l (X in rows of stride S). */
static GF_ALWAYS_INLINE void phi_row(const size_t NB, const size_t S, const double *in,
                                     const double *X, const double *a_row, uint64_t mask,
                                     double *out)
{
    gf_v4 acc[SMAX / 4];
    for (size_t k = 0; k < NB; ++k)
        acc[k] = GF_V4_LOAD(in + 4 * k);
    for (; mask; mask &= mask - 1) {
        const size_t l = gf_lowest_bit(mask);
        const double a = a_row[l], *x = X + l * S;
        for (size_t k = 0; k < NB; ++k)
            GF_V4_AXPY(acc[k], a, x + 4 * k);
    }
    for (size_t k = 0; k < NB; ++k)
        GF_V4_STORE(out + 4 * k, acc[k]);
}

/* P <- Phi M Phi^T + D2 with Phi = I + A, M = P + D1, in two passes of row updates over
 * rows padded to the stride S (a multiple of 4):
 *   B = Phi M:    B_i = M_i + sum_l A_il M_l     (M symmetric: its row l is its column l)
 *   P' = Phi B^T: P'_i = Bt_i + sum_l A_il Bt_l  (Bt = B^T, stored transposed as B is made)
 * the sums over the non-zeros of row i of A (row_mask[i]). Only the lower triangle of P'
 * is formed (row i up to column i, rounded up to a block of 4), then mirrored:
 * navigation error models have their dense rows first (velocity, attitude) and their
 * diagonal ones last (sensor errors), so the lower triangle costs about half of the
 * full rows. Leaves the lower rows in L (n x S); returns 0 if a diagonal entry is not
 * finite (a non-finite A or q reaches the diagonal: Inf * 0 = NaN). */
static GF_ALWAYS_INLINE int predict_rows(const size_t S, size_t n, const double *P,
                                         const double *A, size_t stride,
                                         const uint64_t *row_mask, const double *q1,
                                         const double *q2, double *L)
{
    double M[NMAX * SMAX], Bt[SMAX * SMAX], row[SMAX];
    /* S entries from each row of P (stride n): the last ones are the next row's, or for
     * the last row entries of the array beyond n x n ((n - 1) n + S <= NMAX^2); they fall
     * in the padding, which is then zeroed */
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < S; k += 4)
            GF_V4_STORE(M + i * S + k, GF_V4_LOAD(P + i * n + k));
    for (size_t j = n; j < S; ++j)
        for (size_t i = 0; i < n; ++i)
            M[i * S + j] = 0.0;
    if (q1)
        for (size_t i = 0; i < n; ++i)
            M[i * S + i] += q1[i];
    for (size_t i = 0; i < n; ++i) {
        phi_row(S / 4, S, M + i * S, M, A + i * stride, row_mask[i], row);
        for (size_t j = 0; j < S; ++j)
            Bt[j * S + i] = row[j];
    }
    for (size_t i = n; i < S; ++i)       /* the padding rows of B are zero */
        for (size_t j = 0; j < n; ++j)
            Bt[j * S + i] = 0.0;
    int finite = 1;
    for (size_t i = 0; i < n; ++i) {
        const double *in = Bt + i * S, *a = A + i * stride;
        const uint64_t mask = row_mask[i];
        double *out = L + i * S;
        /* blocks of row i up to the diagonal: a compile-time count up to 6 (S = 24) */
        switch (i / 4) {
        case 0: phi_row(1, S, in, Bt, a, mask, out); break;
        case 1: phi_row(2, S, in, Bt, a, mask, out); break;
        case 2: phi_row(3, S, in, Bt, a, mask, out); break;
        case 3: phi_row(4, S, in, Bt, a, mask, out); break;
        case 4: phi_row(5, S, in, Bt, a, mask, out); break;
        case 5: phi_row(6, S, in, Bt, a, mask, out); break;
        default: phi_row(i / 4 + 1, S, in, Bt, a, mask, out); break;
        }
        if (q2)
            out[i] += q2[i];
        finite &= isfinite(out[i]) != 0;
    }
    return finite;
}

/* P (n x n, stride n) from the lower rows L (stride S): row i is a copy of the whole row
 * i of L, whose entries past column i (up to S - n of them beyond the end of the row:
 * into the next row, which is written next, or for the last row beyond n x n, within the
 * array) are then overwritten from column i of L, four at a time. A whole row is a
 * fixed-size copy. */
static GF_ALWAYS_INLINE void write_symmetric(const size_t S, size_t n, const double *L, double *P)
{
    for (size_t i = 0; i < n; ++i) {
        double *p = P + i * n;
        const double *c = L + i;         /* column i of L */
        for (size_t k = 0; k < S; k += 4)
            GF_V4_STORE(p + k, GF_V4_LOAD(L + i * S + k));
        size_t j = i + 1;
        for (; j + 4 <= n; j += 4)
            GF_V4_STORE(p + j, GF_V4_SET(c[j * S], c[(j + 1) * S], c[(j + 2) * S], c[(j + 3) * S]));
        for (; j < n; ++j)
            p[j] = c[j * S];
    }
}

GF_VECTOR_CLONES
gf_status gf_kalman_predict_masked(gf_kalman *kf, const double *A, size_t stride,
                                   const uint64_t *row_mask, const double *q1, const double *q2)
{
    if (!kf || !A || !row_mask)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (n == 0 || n > NMAX || stride < n)
        return GF_ERR_BAD_SIZE;
    uint64_t outside = 0;          /* mask bits at or above n */
    for (size_t i = 0; i < n; ++i)
        outside |= row_mask[i] >> n;
    if (outside)
        return GF_ERR_BAD_SIZE;
    /* the stride as a compile-time constant for the navigation filter's sizes: 16 (its
     * 15 states), 20 and 24 (16 .. 23 states); else the padded n */
    const size_t s = PADDED(n);
    double L[NMAX * SMAX];
    int finite;
    if (s == 16)
        finite = predict_rows(16, n, kf->P, A, stride, row_mask, q1, q2, L);
    else if (s == 20)
        finite = predict_rows(20, n, kf->P, A, stride, row_mask, q1, q2, L);
    else if (s == 24)
        finite = predict_rows(24, n, kf->P, A, stride, row_mask, q1, q2, L);
    else
        finite = predict_rows(s, n, kf->P, A, stride, row_mask, q1, q2, L);
    if (!finite)
        return GF_ERR_NONFINITE_INPUT;     /* P unchanged */
    if (s == 16)
        write_symmetric(16, n, L, kf->P);
    else if (s == 20)
        write_symmetric(20, n, L, kf->P);
    else if (s == 24)
        write_symmetric(24, n, L, kf->P);
    else
        write_symmetric(s, n, L, kf->P);
    return GF_OK;
}

gf_status gf_kalman_predict_sparse(gf_kalman *kf, const double *A, const double *q1,
                                   const double *q2)
{
    if (!kf || !A)
        return GF_ERR_NULL_POINTER;
    const size_t n = kf->n;
    if (n == 0 || n > NMAX)
        return GF_ERR_BAD_SIZE;
    uint64_t mask[NMAX];
    for (size_t i = 0; i < n; ++i) {
        mask[i] = 0;
        for (size_t j = 0; j < n; ++j)
            if (A[i * n + j] != 0.0)
                mask[i] |= (uint64_t)1 << j;
    }
    return gf_kalman_predict_masked(kf, A, n, mask, q1, q2);
}

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
    /* A in rows of stride n (a repeated column adds up) and its structure */
    double A[NMAX * NMAX] = {0};
    uint64_t mask[NMAX];
    for (size_t i = 0; i < n; ++i) {
        mask[i] = 0;
        for (size_t p = start[i]; p < start[i + 1]; ++p) {
            if (col[p] >= n)
                return GF_ERR_BAD_SIZE;
            A[i * n + col[p]] += val[p];
            mask[i] |= (uint64_t)1 << col[p];
        }
    }
    return gf_kalman_predict_masked(kf, A, n, mask, q1, q2);
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
