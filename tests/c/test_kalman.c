/* test_kalman.c — the Kalman engine's structured predict, Joseph update, unscented
 * covariance and multi-right-hand-side Cholesky substitution, for every state count
 * 1 .. GF_KF_MAX_N (the kernels have compile-time forms for some row strides and a
 * run-time form for the others):
 *   1. the structured predict (masked, CSR and dense-sparse entries) equals
 *      (I + A)(P + D1)(I + A)^T + D2 formed by plain products, within the round-off
 *      bound of two n-term products; its result is exactly symmetric, the entries outside
 *      the mask are not read, bad input is refused with P unchanged;
 *   2. it is bit for bit the documented sequence of IEEE operations (B = M + sum_l A_il
 *      M_l, then the lower triangle of Phi B^T, each sum in ascending l): the property
 *      that makes its AVX2, SSE2 and portable (no vector extension) forms agree — this
 *      file is also built against a portable core (test_kalman_portable);
 *   3. the Joseph update equals the textbook (I - KH) P (I - KH)^T + K R K^T within
 *      round-off, and bit for bit the plain factored products it is documented to
 *      reproduce (H P over all of H, X = P - K HP, D = K R - X H^T, X + D K^T);
 *   4. the unscented covariance equals sum W (Y - y)(Y - y)^T within round-off, exactly
 *      symmetric;
 *   5. the row-wise Cholesky substitution equals the column-by-column one bit for bit. */
#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "est/gf_kalman.h"
#include "gf_ref.h"
#include "gf_test.h"

#define NMAX GF_KF_MAX_N
_Static_assert(REF_KF_MAX >= GF_KF_MAX_N, "gf_ref.h: the reference update must hold the largest filter");
#define MMAX GF_KF_MAX_M
#define EPS 2.220446049250313e-16

static test_rng g_rng = {0x2545F4914F6CDD1DULL};

static double urand(double lo, double hi)
{
    return test_rng_uniform(&g_rng, lo, hi);
}

/* symmetric positive definite: B B^T / n + I, entries O(1) */
static void random_spd(size_t n, double *P)
{
    double B[NMAX * NMAX];
    for (size_t i = 0; i < n * n; ++i)
        B[i] = urand(-1, 1);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j <= i; ++j) {
            double acc = i == j ? 1.0 : 0.0;
            for (size_t k = 0; k < n; ++k)
                acc += B[i * n + k] * B[j * n + k] / (double)n;
            P[i * n + j] = P[j * n + i] = acc;
        }
}

static int bits_equal(const double *a, const double *b, size_t count)
{
    return memcmp(a, b, count * sizeof *a) == 0;
}

/* ---- 1, 2: structured predict ------------------------------------------------------- */

/* (I + A)(P + D1)(I + A)^T + D2 by plain products, and the bound of its round-off:
 * two products of n + 1 terms, |err| <= 2 (n + 2) eps (|Phi| |M| |Phi|^T)_ij */
static void predict_reference(size_t n, const double *P, const double *A, const double *q1,
                              const double *q2, double *ref, double *bound)
{
    double Phi[NMAX * NMAX], M[NMAX * NMAX], T[NMAX * NMAX], aT[NMAX * NMAX];
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            Phi[i * n + j] = A[i * n + j] + (i == j ? 1.0 : 0.0);
            M[i * n + j] = P[i * n + j] + (i == j ? q1[i] : 0.0);
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = 0.0, aacc = 0.0;
            for (size_t k = 0; k < n; ++k) {
                acc += Phi[i * n + k] * M[k * n + j];
                aacc += fabs(Phi[i * n + k]) * fabs(M[k * n + j]);
            }
            T[i * n + j] = acc;
            aT[i * n + j] = aacc;
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = 0.0, aacc = 0.0;
            for (size_t k = 0; k < n; ++k) {
                acc += T[i * n + k] * Phi[j * n + k];
                aacc += aT[i * n + k] * fabs(Phi[j * n + k]);
            }
            ref[i * n + j] = acc + (i == j ? q2[i] : 0.0);
            bound[i * n + j] = 2.0 * (double)(n + 2) * EPS * (aacc + (i == j ? q2[i] : 0.0));
        }
}

/* The documented operation sequence of the structured predict, scalar. */
static void predict_ordered(size_t n, const double *P, const double *A, const uint64_t *mask,
                            const double *q1, const double *q2, double *out)
{
    double M[NMAX * NMAX], B[NMAX * NMAX];
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j)
            M[i * n + j] = P[i * n + j];
    for (size_t i = 0; i < n; ++i)
        M[i * n + i] += q1[i];
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double b = M[i * n + j];
            for (size_t l = 0; l < n; ++l)
                if (mask[i] >> l & 1u)
                    b += A[i * n + l] * M[l * n + j];
            B[i * n + j] = b;
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j <= i; ++j) {
            double p = B[j * n + i];
            for (size_t l = 0; l < n; ++l)
                if (mask[i] >> l & 1u)
                    p += A[i * n + l] * B[j * n + l];
            if (i == j)
                p += q2[i];
            out[i * n + j] = out[j * n + i] = p;
        }
}

static void test_predict(size_t n, double density)
{
    double P[NMAX * NMAX], A[NMAX * NMAX], Aw[NMAX * (NMAX + 3)], q1[NMAX], q2[NMAX];
    double ref[NMAX * NMAX], bound[NMAX * NMAX], ord[NMAX * NMAX];
    uint64_t mask[NMAX];
    random_spd(n, P);
    const size_t stride = n + 3;  /* A handed over in rows wider than n */
    for (size_t i = 0; i < n; ++i) {
        mask[i] = 0;
        q1[i] = urand(0, 0.1);
        q2[i] = urand(0, 0.1);
        for (size_t j = 0; j < stride; ++j)
            Aw[i * stride + j] = NAN;   /* entries outside the mask are not read */
        for (size_t j = 0; j < n; ++j) {
            const int on = urand(0, 1) < density;
            A[i * n + j] = on ? urand(-0.5, 0.5) : 0.0;
            if (on) {
                mask[i] |= (uint64_t)1 << j;
                Aw[i * stride + j] = A[i * n + j];
            }
        }
    }
    predict_reference(n, P, A, q1, q2, ref, bound);
    predict_ordered(n, P, A, mask, q1, q2, ord);

    gf_kalman kf;
    const double x0[NMAX] = {0};
    CHECK(gf_kalman_init(&kf, n, x0, P) == GF_OK, "init n = %zu", n);
    CHECK(gf_kalman_predict_masked(&kf, Aw, stride, mask, q1, q2) == GF_OK, "masked n = %zu", n);
    int close = 1, symmetric = 1;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            close &= fabs(kf.P[i * n + j] - ref[i * n + j]) <= bound[i * n + j];
            symmetric &= kf.P[i * n + j] == kf.P[j * n + i];
        }
    CHECK(close, "masked predict n = %zu, density %.2f: within the round-off bound of the "
                 "plain products", n, density);
    CHECK(symmetric, "masked predict n = %zu: P exactly symmetric", n);
    CHECK(bits_equal(kf.P, ord, n * n), "masked predict n = %zu, density %.2f: bit for bit the "
                                        "documented operation sequence", n, density);

    /* the dense entry finds the same mask: the same bits */
    gf_kalman kf2;
    gf_kalman_init(&kf2, n, x0, P);
    CHECK(gf_kalman_predict_sparse(&kf2, A, q1, q2) == GF_OK, "sparse n = %zu", n);
    CHECK(bits_equal(kf2.P, ord, n * n), "dense-sparse entry n = %zu: same bits", n);

    /* CSR with the non-zeros, in order */
    size_t start[NMAX + 1], nnz = 0;
    unsigned char col[NMAX * NMAX];
    double val[NMAX * NMAX];
    for (size_t i = 0; i < n; ++i) {
        start[i] = nnz;
        for (size_t j = 0; j < n; ++j)
            if (mask[i] >> j & 1u) {
                col[nnz] = (unsigned char)j;
                val[nnz++] = A[i * n + j];
            }
    }
    start[n] = nnz;
    gf_kalman kf3;
    gf_kalman_init(&kf3, n, x0, P);
    CHECK(gf_kalman_predict_csr(&kf3, start, col, val, q1, q2) == GF_OK, "csr n = %zu", n);
    CHECK(bits_equal(kf3.P, ord, n * n), "CSR entry n = %zu: same bits", n);

    /* refused with P unchanged: a non-finite entry in the mask, a mask bit at n, a
     * stride below n, a CSR column at n */
    double before[NMAX * NMAX];
    memcpy(before, kf.P, sizeof before);
    const size_t r = n / 2;
    const uint64_t keep = mask[r];
    mask[r] |= 1;
    const double a0 = Aw[r * stride];
    Aw[r * stride] = INFINITY;
    CHECK(gf_kalman_predict_masked(&kf, Aw, stride, mask, q1, q2) == GF_ERR_NONFINITE_INPUT,
          "n = %zu: Inf in A refused", n);
    CHECK(bits_equal(kf.P, before, NMAX * NMAX), "n = %zu: P unchanged after a refusal", n);
    Aw[r * stride] = a0;
    mask[r] = keep;
    if (n < 64) {
        mask[r] |= (uint64_t)1 << n;
        CHECK(gf_kalman_predict_masked(&kf, Aw, stride, mask, q1, q2) == GF_ERR_BAD_SIZE,
              "n = %zu: mask bit at n refused", n);
        mask[r] = keep;
    }
    CHECK(gf_kalman_predict_masked(&kf, Aw, n - 1, mask, q1, q2) == GF_ERR_BAD_SIZE,
          "n = %zu: stride below n refused", n);
    if (nnz > 0) {
        const unsigned char c0 = col[0];
        col[0] = (unsigned char)n;
        CHECK(gf_kalman_predict_csr(&kf, start, col, val, q1, q2) == GF_ERR_BAD_SIZE,
              "n = %zu: CSR column n refused", n);
        col[0] = c0;
    }
    CHECK(bits_equal(kf.P, before, NMAX * NMAX), "n = %zu: P unchanged after the refusals", n);
}

/* ---- 3: Joseph update --------------------------------------------------------------- */

/* The plain factored products the update reproduces, entry by entry (the engine's
 * earlier form): PHt = P H^T, S = H PHt + R (symmetrised), K^T = S^-1 PHt^T, x = K r,
 * X = P - K PHt^T, D = K R - X H^T, P' = X + D K^T (upper triangle, mirrored). */
static void joseph_plain(size_t n, size_t m, const double *P, const double *H, const double *R,
                         const double *r, double *x, double *Pn)
{
    double PHt[NMAX * MMAX], S[MMAX * MMAX], Kt[MMAX * NMAX], X[NMAX * NMAX], D[NMAX * MMAX];
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < m; ++j) {
            double acc = 0.0;
            for (size_t l = 0; l < n; ++l)
                acc += P[i * n + l] * H[j * n + l];
            PHt[i * m + j] = acc;
        }
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < m; ++j) {
            double acc = R[i * m + j];
            for (size_t k = 0; k < n; ++k)
                acc += H[i * n + k] * PHt[k * m + j];
            S[i * m + j] = acc;
        }
    for (size_t i = 0; i < m; ++i)
        for (size_t j = i + 1; j < m; ++j)
            S[i * m + j] = S[j * m + i] = 0.5 * (S[i * m + j] + S[j * m + i]);
    gf_cholesky(m, S);
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < n; ++j)
            Kt[i * n + j] = PHt[j * m + i];
    gf_cholesky_solve(m, S, n, Kt);
    for (size_t i = 0; i < n; ++i) {
        double acc = 0.0;
        for (size_t j = 0; j < m; ++j)
            acc += Kt[j * n + i] * r[j];
        x[i] = acc;
    }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = P[i * n + j];
            for (size_t k = 0; k < m; ++k)
                acc -= Kt[k * n + i] * PHt[j * m + k];
            X[i * n + j] = acc;
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < m; ++k) {
            double kr = 0.0, xh = 0.0;
            for (size_t l = 0; l < m; ++l)
                kr += Kt[l * n + i] * R[l * m + k];
            for (size_t l = 0; l < n; ++l)
                xh += X[i * n + l] * H[k * n + l];
            D[i * m + k] = kr - xh;
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j) {
            double acc = X[i * n + j];
            for (size_t k = 0; k < m; ++k)
                acc += D[i * m + k] * Kt[k * n + j];
            Pn[i * n + j] = Pn[j * n + i] = acc;
        }
}

static void test_joseph(size_t n, size_t m)
{
    double P[NMAX * NMAX], H[MMAX * NMAX], R[MMAX * MMAX], r[MMAX], x[NMAX], Pp[NMAX * NMAX];
    random_spd(n, P);
    for (size_t i = 0; i < m * n; ++i)   /* measurement models are mostly zeros */
        H[i] = urand(0, 1) < 0.35 ? urand(-1, 1) : 0.0;
    for (size_t k = 0; k < m; ++k)
        H[k * n + (k % n)] = 1.0;
    random_spd(m, R);
    for (size_t k = 0; k < m; ++k)
        r[k] = urand(-1, 1);
    joseph_plain(n, m, P, H, R, r, x, Pp);

    gf_kalman kf;
    const double x0[NMAX] = {0};
    gf_kalman_init(&kf, n, x0, P);
    double nis = 0.0;
    int accepted = 0;
    CHECK(gf_kalman_update_gated(&kf, m, r, H, R, 0.0, &nis, &accepted) == GF_OK && accepted,
          "update n = %zu m = %zu", n, m);
    CHECK(bits_equal(kf.P, Pp, n * n) && bits_equal(kf.x, x, n),
          "update n = %zu m = %zu: bit for bit the plain factored products", n, m);

    /* the textbook form (gf_ref.h), within round-off: the terms are O(1) and the products
     * have ~3 n terms: 1e3 n eps */
    double xr[NMAX] = {0}, Pr[NMAX * NMAX];
    memcpy(Pr, P, n * n * sizeof *P);
    ref_kalman_update(n, m, xr, Pr, r, H, R);
    double worst = 0.0;
    for (size_t i = 0; i < n; ++i) {
        worst = fmax(worst, fabs(xr[i] - kf.x[i]));
        for (size_t j = 0; j < n; ++j)
            worst = fmax(worst, fabs(Pr[i * n + j] - kf.P[i * n + j]));
    }
    CHECK(worst <= 1e3 * (double)n * EPS, "update n = %zu m = %zu: textbook Joseph form, "
                                           "max |diff| %.3g", n, m, worst);

    /* gated: unchanged */
    double before[NMAX * NMAX];
    memcpy(before, kf.P, sizeof before);
    CHECK(gf_kalman_update_gated(&kf, m, r, H, R, 1e-300, &nis, &accepted) == GF_OK && !accepted,
          "n = %zu m = %zu: gated", n, m);
    CHECK(bits_equal(kf.P, before, NMAX * NMAX), "n = %zu m = %zu: P unchanged when gated", n, m);
}

/* ---- 4: unscented covariance ---------------------------------------------------------- */

static void test_ukf_predict(size_t n)
{
    gf_ukf_weights w;
    CHECK(gf_ukf_weights_init(&w, n, 0.5, 2.0, 0.0) == GF_OK, "weights n = %zu", n);
    const size_t np = 2 * n + 1;
    double Y[(2 * NMAX + 1) * NMAX], y[NMAX] = {0}, Q[NMAX * NMAX];
    for (size_t i = 0; i < np * n; ++i)
        Y[i] = urand(-1, 1);
    random_spd(n, Q);
    for (size_t p = 0; p < np; ++p)
        for (size_t i = 0; i < n; ++i)
            y[i] += (p == 0 ? w.wm0 : w.wi) * Y[p * n + i];
    gf_kalman kf;
    double P0[NMAX * NMAX], x0[NMAX] = {0};
    random_spd(n, P0);
    gf_kalman_init(&kf, n, x0, P0);
    CHECK(gf_ukf_predict(&kf, &w, Y, Q) == GF_OK, "ukf predict n = %zu", n);
    /* the weights' magnitudes sum to sum |W| ~ 1 + 2|wc0|: n-term sums of O(1) products */
    double worst = 0.0, scale = 0.0;
    int symmetric = 1;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = Q[i * n + j];
            for (size_t p = 0; p < np; ++p)
                acc += (p == 0 ? w.wc0 : w.wi) * (Y[p * n + i] - y[i]) * (Y[p * n + j] - y[j]);
            worst = fmax(worst, fabs(acc - kf.P[i * n + j]));
            scale = fmax(scale, fabs(acc));
            symmetric &= kf.P[i * n + j] == kf.P[j * n + i];
        }
    CHECK(worst <= 1e2 * (double)np * EPS * (1.0 + fabs(w.wc0)) * fmax(scale, 1.0),
          "ukf covariance n = %zu: max |diff| %.3g", n, worst);
    CHECK(symmetric, "ukf covariance n = %zu exactly symmetric", n);
}

/* ---- 5: multi-column substitution ---------------------------------------------------- */

static void test_cholesky_solve(size_t n, size_t k)
{
    double A[NMAX * NMAX], B[NMAX * NMAX], Bc[NMAX * NMAX];
    random_spd(n, A);
    CHECK(gf_cholesky(n, A) == GF_OK, "cholesky n = %zu", n);
    for (size_t i = 0; i < n * k; ++i)
        B[i] = urand(-1, 1);
    memcpy(Bc, B, n * k * sizeof *B);
    gf_cholesky_solve(n, A, k, B);
    /* column c alone (k = 1) */
    int same = 1;
    for (size_t c = 0; c < k; ++c) {
        double col[NMAX];
        for (size_t i = 0; i < n; ++i)
            col[i] = Bc[i * k + c];
        gf_cholesky_solve(n, A, 1, col);
        for (size_t i = 0; i < n; ++i)
            same &= col[i] == B[i * k + c];
    }
    CHECK(same, "cholesky solve n = %zu k = %zu: all columns at once = one by one, bit for bit",
          n, k);
}

int main(void)
{
    for (size_t n = 1; n <= NMAX; ++n) {
        test_predict(n, 0.3);
        test_predict(n, 1.0);
        test_predict(n, 0.0);
        test_ukf_predict(n);
        test_cholesky_solve(n, n);
    }
    const size_t ns[] = {1, 2, 5, 6, 8, 9, 15, 16, 17, 21, 23, 24, 25, 36, 37, GF_KF_MAX_N};
    const size_t ms[] = {1, 2, 3, 6, 12};
    for (size_t a = 0; a < sizeof ns / sizeof ns[0]; ++a)
        for (size_t b = 0; b < sizeof ms / sizeof ms[0]; ++b)
            if (ms[b] <= ns[a])
                test_joseph(ns[a], ms[b]);
    TEST_MAIN_END();
}
