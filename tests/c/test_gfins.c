/* test_gfins.c — dense linear algebra (gf_linalg), the Kalman engine (gf_kalman) and
 * the general gyro-free solver, rate strategies and navigator (gf_gfins).
 *
 * Truth never comes from the code under test:
 *   - SVD: reconstruction U diag(s) V^T = A and orthonormality are checked directly;
 *     singular values against matrices built here as Q1 diag(sigma) Q2^T from
 *     Householder reflections; a duplicated column must give the null vector
 *     (e_p - e_q)/sqrt2.
 *   - Cholesky: L L^T = A and the residual of the solve, with Higham's bounds.
 *   - 3x3 eigen: residuals A v = w v, orthonormality, and the eigenvalues of the
 *     trigonometric closed form (Smith 1961), a different algorithm.
 *   - Kalman: scalar and constant-velocity filters written out by hand, and a
 *     reference update with an explicit inverse for random models.
 *   - Array solver: the outputs are computed here from the physics (as in
 *     test_accel_array.c), the model matrix H is obtained from the same independent
 *     output function (unit f, w_dot, and w = e_j, e_j + e_k for the products), the
 *     noise gains and condition numbers from an eigen-decomposition of H^T H written
 *     here, the closed forms of seed 000 (eq. 3, 4, 6) and of the 6-accelerometer cube
 *     are written out by hand.
 *   - Rate strategies: exact outputs of motions with known rates (constant rate,
 *     linearly varying w_dot, a zero crossing of w_x), FUSED against an EKF on [w, b]
 *     written here; bitwise properties (steps = run, interleaved instances, state
 *     unchanged on error).
 *   - Navigator: a stationary array on the WGS-84 Earth with the constants and
 *     Somigliana gravity written here; the cubic Hermite increments against an RK4
 *     integration of the attitude ODE written here (order, size), a linear rate against
 *     the two-sample formula, a force fixed in space seen by a spinning body.
 *   - Any array: the observed/confounded/absent product subspaces of the solver checked
 *     against a projector built here from the physics; a coplanar array's subspaces
 *     against the ones derived by hand; a rotated array against the unrotated one.
 * Tolerances are justified where they are set; measured figures are printed.
 * Runs in ~0.15 s plain, ~0.8 s under AddressSanitizer + UBSan. */
#include <float.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "est/gf_kalman.h"
#include "gyrofree/gf9.h"
#include "gyrofree/gf_array.h"
#include "gyrofree/gf_array_solver.h"
#include "gyrofree/gf_gfins.h"
#include "gyrofree/gf_gfnav.h"
#include "gyrofree/gf_layout.h"
#include "nav/gf_sins.h"
#include "gf_ref.h"
#include "gf_test.h"

#define EPS DBL_EPSILON
#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define SQ(x) ((x) * (x))

/* ======================================================================================
 * Independent helpers
 * ==================================================================================== */

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static double norm3(const double a[3]) { return sqrt(dot3(a, a)); }

static void cross3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

/* A = theta . (f + wd x u + w (w . u) - |w|^2 u), i.e. theta . (f + wd x u + w x (w x u)) */
static double independent_output(const double u[3], const double th[3], const double f[3],
                                  const double w[3], const double wd[3])
{
    double wdxu[3], a[3];
    cross3(wd, u, wdxu);
    const double wu = dot3(w, u), ww = dot3(w, w);
    for (int k = 0; k < 3; ++k)
        a[k] = f[k] + wdxu[k] + w[k] * wu - ww * u[k];
    return dot3(th, a);
}

static void random_v3(test_rng *r, double lo, double hi, double v[3])
{
    for (int k = 0; k < 3; ++k)
        v[k] = test_rng_uniform(r, lo, hi);
}

static void random_unit(test_rng *r, double v[3])
{
    double n;
    do {
        random_v3(r, -1, 1, v);
        n = norm3(v);
    } while (n < 0.2 || n > 1.0);
    for (int k = 0; k < 3; ++k)
        v[k] /= n;
}

/* Cyclic Jacobi eigen-decomposition of a symmetric n x n matrix (n <= REF_MAX), for
 * the references: eigenvalues in w (unsorted), eigenvectors as the columns of V. */
#define REF_MAX 16
static void ref_sym_eig(size_t n, const double *A, double *w, double *V)
{
    double a[REF_MAX * REF_MAX];
    memcpy(a, A, n * n * sizeof *a);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j)
            V[i * n + j] = i == j ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 100; ++sweep) {
        double off = 0.0, tot = 0.0;
        for (size_t i = 0; i < n; ++i)
            for (size_t j = 0; j < n; ++j) {
                tot += SQ(a[i * n + j]);
                if (i != j)
                    off += SQ(a[i * n + j]);
            }
        if (off <= 1e-34 * tot)
            break;
        for (size_t p = 0; p + 1 < n; ++p)
            for (size_t q = p + 1; q < n; ++q) {
                const double apq = a[p * n + q];
                if (apq == 0.0)
                    continue;
                const double th = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                const double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1.0));
                const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (size_t k = 0; k < n; ++k) {
                    const double x = a[k * n + p], y = a[k * n + q];
                    a[k * n + p] = c * x - s * y;
                    a[k * n + q] = s * x + c * y;
                }
                for (size_t k = 0; k < n; ++k) {
                    const double x = a[p * n + k], y = a[q * n + k];
                    a[p * n + k] = c * x - s * y;
                    a[q * n + k] = s * x + c * y;
                }
                for (size_t k = 0; k < n; ++k) {
                    const double x = V[k * n + p], y = V[k * n + q];
                    V[k * n + p] = c * x - s * y;
                    V[k * n + q] = s * x + c * y;
                }
            }
    }
    for (size_t i = 0; i < n; ++i)
        w[i] = a[i * n + i];
}

/* M <- (I - 2 v v^T / v^T v) M for an m x k matrix M (row-major, stride k) */
static void householder_apply(size_t m, size_t k, const double *v, double *M)
{
    double vv = 0.0;
    for (size_t i = 0; i < m; ++i)
        vv += v[i] * v[i];
    for (size_t c = 0; c < k; ++c) {
        double d = 0.0;
        for (size_t i = 0; i < m; ++i)
            d += v[i] * M[i * k + c];
        d *= 2.0 / vv;
        for (size_t i = 0; i < m; ++i)
            M[i * k + c] -= d * v[i];
    }
}

/* an m x m orthogonal matrix: the product of three random reflections */
static void random_orthogonal(test_rng *r, size_t m, double *Q)
{
    double v[64];
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < m; ++j)
            Q[i * m + j] = i == j ? 1.0 : 0.0;
    for (int h = 0; h < 3; ++h) {
        for (size_t i = 0; i < m; ++i)
            v[i] = test_rng_uniform(r, -1, 1);
        householder_apply(m, m, v, Q);
    }
}

/* ======================================================================================
 * gf_svd
 * ==================================================================================== */

/* Measures (in units of eps) the reconstruction error relative to s_max and the
 * departure of U (columns with s > 0) and V from orthonormality; checks the order. */
static void svd_measure(size_t m, size_t n, const double *A, const double *U, const double *s,
                        const double *V, double *rec, double *orth_u, double *orth_v, int *sorted)
{
    *rec = *orth_u = *orth_v = 0.0;
    *sorted = 1;
    for (size_t j = 0; j < n; ++j)
        *sorted &= s[j] >= 0.0 && (j == 0 || s[j] <= s[j - 1]);
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < n; ++k)
                acc += U[i * n + k] * s[k] * V[j * n + k];
            *rec = fmax(*rec, fabs(acc - A[i * n + j]) / (EPS * s[0]));
        }
    for (size_t p = 0; p < n; ++p)
        for (size_t q = p; q < n; ++q) {
            double du = 0.0, dv = 0.0;
            for (size_t i = 0; i < m; ++i)
                du += U[i * n + p] * U[i * n + q];
            for (size_t i = 0; i < n; ++i)
                dv += V[i * n + p] * V[i * n + q];
            const double id = p == q ? 1.0 : 0.0;
            if (s[p] > 0.0 && s[q] > 0.0)
                *orth_u = fmax(*orth_u, fabs(du - id) / EPS);
            *orth_v = fmax(*orth_v, fabs(dv - id) / EPS);
        }
}

static double g_svd_rec = 0, g_svd_u = 0, g_svd_v = 0;

/* Tolerances. One-sided Jacobi stops when every column pair is orthogonal to 1e-15
 * relative (4.5 eps), so U^T U = I to 1e-15 plus the normalisation and the m-term dot
 * product of the check: 4.5 + 2 sqrt(m) eps with margin -> 8 + 4 sqrt(m) eps (measured
 * <= 4.5 eps). V is a product of rotations, each orthogonal to ~2 eps; a column goes
 * through (n - 1) rotations in each of ~10-15 sweeps, the errors adding like a random
 * walk: ~2 sqrt(15 n) = 8 sqrt(n) eps; allowed 16 sqrt(n) eps (measured <= 8.2 sqrt(n)
 * eps, on the 64 x 36 matrix with singular values over 8 decades). Reconstruction:
 * each rotation rounds the two columns it touches by ~2 eps of their norm (<= s_max),
 * the same walk: allowed 16 sqrt(n) eps s_max (measured <= 2.8 sqrt(n)). */
static void svd_check(const char *what, size_t m, size_t n, const double *A, const double *U,
                      const double *s, const double *V)
{
    double rec, ou, ov;
    int sorted;
    svd_measure(m, n, A, U, s, V, &rec, &ou, &ov, &sorted);
    const double sn = sqrt((double)n), sm = sqrt((double)m);
    CHECK(sorted, "%s %zux%zu: s descending and >= 0", what, m, n);
    CHECK(rec <= 16.0 * sn, "%s %zux%zu: U diag(s) V^T = A (%.3g eps s_max > %.3g)", what, m, n, rec, 16.0 * sn);
    CHECK(ou <= 8.0 + 4.0 * sm, "%s %zux%zu: U^T U = I (%.3g eps)", what, m, n, ou);
    CHECK(ov <= 16.0 * sn, "%s %zux%zu: V^T V = I (%.3g eps)", what, m, n, ov);
    g_svd_rec = fmax(g_svd_rec, rec / sn);
    g_svd_u = fmax(g_svd_u, ou);
    g_svd_v = fmax(g_svd_v, ov / sn);
}

static double svd_A[64 * 36], svd_U[64 * 36], svd_s[36], svd_V[36 * 36];

static void test_svd_random(void)
{
    static const size_t sizes[][2] = {{1, 1}, {2, 2}, {3, 1}, {3, 3}, {6, 6}, {9, 9}, {12, 12},
                                      {20, 12}, {40, 7}, {36, 36}, {50, 30}, {64, 36}, {64, 1}};
    test_rng rng = {0x5eedULL};
    for (size_t c = 0; c < sizeof sizes / sizeof sizes[0]; ++c)
        for (int graded = 0; graded <= 1; ++graded) {
            const size_t m = sizes[c][0], n = sizes[c][1];
            /* graded: column j scaled by 10^(-6 j / n): singular values over 6 decades */
            for (size_t i = 0; i < m; ++i)
                for (size_t j = 0; j < n; ++j)
                    svd_A[i * n + j] = test_rng_uniform(&rng, -1, 1) *
                                       (graded ? pow(10.0, -6.0 * (double)j / (double)n) : 1.0);
            memcpy(svd_U, svd_A, m * n * sizeof *svd_A);
            CHECK(gf_svd(m, n, svd_U, svd_s, svd_V) == GF_OK, "svd %zux%zu", m, n);
            svd_check(graded ? "graded" : "random", m, n, svd_A, svd_U, svd_s, svd_V);
        }
    printf("svd random: max reconstruction %.3g sqrt(n) eps s_max, U^T U %.3g eps, V^T V %.3g sqrt(n) eps\n",
           g_svd_rec, g_svd_u, g_svd_v);
}

/* A = Q1[:, :n] diag(sigma) Q2^T with known sigma. Weyl: |s_k - sigma_k| <= ||dA||_2,
 * where dA is the SVD's backward error (as the reconstruction, <= 16 sqrt(n) eps
 * s_max) plus the rounding of the construction here (Q1, Q2 orthogonal to a few eps):
 * allowed 16 sqrt(n) eps s_max (measured <= 2.8 sqrt(n)). */
static void test_svd_known_values(void)
{
    static double Q1[64 * 64], Q2[36 * 36];
    test_rng rng = {4242};
    static const size_t sizes[][2] = {{5, 3}, {12, 12}, {64, 36}, {30, 20}};
    double worst = 0.0;
    for (size_t c = 0; c < sizeof sizes / sizeof sizes[0]; ++c) {
        const size_t m = sizes[c][0], n = sizes[c][1];
        random_orthogonal(&rng, m, Q1);
        random_orthogonal(&rng, n, Q2);
        double sigma[36];
        for (size_t k = 0; k < n; ++k) /* 3.0 down to 3e-8, given in scrambled order */
            sigma[k] = 3.0 * pow(1e-8, (double)((k * 7) % n) / (double)(n > 1 ? n - 1 : 1));
        for (size_t i = 0; i < m; ++i)
            for (size_t j = 0; j < n; ++j) {
                double acc = 0.0;
                for (size_t k = 0; k < n; ++k)
                    acc += Q1[i * m + k] * sigma[k] * Q2[j * n + k];
                svd_A[i * n + j] = acc;
            }
        memcpy(svd_U, svd_A, m * n * sizeof *svd_A);
        CHECK(gf_svd(m, n, svd_U, svd_s, svd_V) == GF_OK, "svd known %zux%zu", m, n);
        svd_check("known", m, n, svd_A, svd_U, svd_s, svd_V);
        /* sorted sigma */
        double sorted_sigma[36];
        memcpy(sorted_sigma, sigma, n * sizeof *sigma);
        for (size_t a = 0; a < n; ++a)
            for (size_t b = a + 1; b < n; ++b)
                if (sorted_sigma[b] > sorted_sigma[a]) {
                    const double t = sorted_sigma[a];
                    sorted_sigma[a] = sorted_sigma[b];
                    sorted_sigma[b] = t;
                }
        for (size_t k = 0; k < n; ++k) {
            const double err = fabs(svd_s[k] - sorted_sigma[k]) / (EPS * 3.0);
            worst = fmax(worst, err / sqrt((double)n));
            CHECK(err <= 16.0 * sqrt((double)n), "known %zux%zu: s_%zu = %.17g vs %.17g (%.3g eps s_max)", m, n,
                  k, svd_s[k], sorted_sigma[k], err);
        }
    }
    printf("svd known singular values: max |s - sigma| %.3g sqrt(n) eps s_max\n", worst);
}

static void test_svd_rank_deficient(void)
{
    test_rng rng = {99};
    const size_t m = 20, n = 8;
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < n; ++j)
            svd_A[i * n + j] = test_rng_uniform(&rng, -1, 1);
    for (size_t i = 0; i < m; ++i) /* column 5 duplicates column 2 */
        svd_A[i * n + 5] = svd_A[i * n + 2];
    memcpy(svd_U, svd_A, m * n * sizeof *svd_A);
    CHECK(gf_svd(m, n, svd_U, svd_s, svd_V) == GF_OK, "svd rank-deficient");
    /* rank 7: the smallest singular value is the size of the backward error, a few eps
     * s_max; s_(n-2) is O(1), the gap that fixes the null vector to ~eps/gap */
    printf("svd duplicate column: s_min = %.3g s_max (s_6 = %.3g s_max)\n", svd_s[7] / svd_s[0], svd_s[6] / svd_s[0]);
    CHECK(svd_s[7] <= 1e-15 * svd_s[0], "duplicate column: s_min %.3g s_max <= 1e-15 s_max", svd_s[7] / svd_s[0]);
    CHECK(svd_s[6] >= 1e-2 * svd_s[0], "duplicate column: the other values stay O(1)");
    const double r = sqrt(0.5);
    double dev = 0.0;
    const double sgn = svd_V[2 * n + 7] >= 0 ? 1.0 : -1.0;
    for (size_t j = 0; j < n; ++j) {
        const double expect = j == 2 ? r : j == 5 ? -r : 0.0;
        dev = fmax(dev, fabs(sgn * svd_V[j * n + 7] - expect));
    }
    CHECK(dev <= 1e-13, "duplicate column: null vector (e_2 - e_5)/sqrt2 (dev %.3g)", dev);
    /* the range is still reconstructed (U columns with s > 0 orthonormal) */
    double rec, ou, ov;
    int sorted;
    svd_measure(m, n, svd_A, svd_U, svd_s, svd_V, &rec, &ou, &ov, &sorted);
    CHECK(sorted && rec <= 16.0 * sqrt((double)n) && ov <= 16.0 * sqrt((double)n),
          "duplicate column: reconstruction %.3g eps s_max, V^T V %.3g eps", rec, ov);

    /* a zero column: its singular value is zero and V's last column is that axis */
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < n; ++j)
            svd_A[i * n + j] = j == 3 ? 0.0 : test_rng_uniform(&rng, -1, 1);
    memcpy(svd_U, svd_A, m * n * sizeof *svd_A);
    CHECK(gf_svd(m, n, svd_U, svd_s, svd_V) == GF_OK, "svd zero column");
    CHECK(svd_s[7] <= 1e-15 * svd_s[0], "zero column: s_min = %.3g", svd_s[7]);
    CHECK(fabs(fabs(svd_V[3 * n + 7]) - 1.0) <= 1e-14, "zero column: null vector e_3 (%.17g)", svd_V[3 * n + 7]);
    svd_measure(m, n, svd_A, svd_U, svd_s, svd_V, &rec, &ou, &ov, &sorted);
    CHECK(sorted && rec <= 16.0 * sqrt((double)n) && ou <= 8.0 + 4.0 * sqrt((double)m),
          "zero column: reconstruction %.3g eps s_max, U^T U %.3g eps", rec, ou);

    /* all zero: s = 0 */
    memset(svd_U, 0, m * n * sizeof *svd_U);
    CHECK(gf_svd(m, n, svd_U, svd_s, svd_V) == GF_OK, "svd zero matrix");
    int all_zero = 1;
    for (size_t j = 0; j < n; ++j)
        all_zero &= svd_s[j] == 0.0;
    CHECK(all_zero, "zero matrix: all singular values 0");
}

/* Scaling A by a power of two scales s exactly and leaves U, V alone in exact
 * arithmetic, and in floating point as long as nothing over/underflows. Checked at
 * 2^+-200 (to round-off), and at 2^+-330 (|a| ~ 1e99 and 1e-99: squares and sums of
 * squares ~1e200 and 1e-200 stay in range, so a correct Jacobi SVD must still work). */
static void test_svd_scaling(void)
{
    static double B[64 * 36], Ub[64 * 36], sb[36], Vb[36 * 36];
    test_rng rng = {777};
    const size_t m = 30, n = 12;
    for (size_t i = 0; i < m * n; ++i)
        svd_A[i] = test_rng_uniform(&rng, -1, 1);
    memcpy(svd_U, svd_A, m * n * sizeof *svd_A);
    CHECK(gf_svd(m, n, svd_U, svd_s, svd_V) == GF_OK, "svd base");
    const int exps[4] = {200, -200, 330, -330};
    for (int e = 0; e < 4; ++e) {
        const double sc = ldexp(1.0, exps[e]);
        for (size_t i = 0; i < m * n; ++i)
            B[i] = svd_A[i] * sc;
        memcpy(Ub, B, m * n * sizeof *B);
        CHECK(gf_svd(m, n, Ub, sb, Vb) == GF_OK, "svd scaled 2^%d", exps[e]);
        double ds = 0.0;
        for (size_t k = 0; k < n; ++k)
            ds = fmax(ds, fabs(sb[k] / sc - svd_s[k]) / svd_s[0]);
        CHECK(ds <= 16 * EPS, "scaled 2^%d: s scales with A (%.3g s_max)", exps[e], ds);
        char what[32];
        snprintf(what, sizeof what, "scaled 2^%d", exps[e]);
        svd_check(what, m, n, B, Ub, sb, Vb);
    }
}

static void test_svd_errors(void)
{
    double a[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}, s[4], v[16];
    CHECK(gf_svd(4, 3, NULL, s, v) == GF_ERR_NULL_POINTER, "svd NULL a");
    CHECK(gf_svd(4, 3, a, NULL, v) == GF_ERR_NULL_POINTER, "svd NULL s");
    CHECK(gf_svd(4, 3, a, s, NULL) == GF_ERR_NULL_POINTER, "svd NULL v");
    CHECK(gf_svd(4, 0, a, s, v) == GF_ERR_BAD_SIZE, "svd n = 0");
    CHECK(gf_svd(3, 4, a, s, v) == GF_ERR_BAD_SIZE, "svd m < n");
    CHECK(gf_svd(0, 0, a, s, v) == GF_ERR_BAD_SIZE, "svd 0 x 0");
    CHECK(gf_svd(64, GF_LINALG_MAX_COLS + 1, svd_U, svd_s, svd_V) == GF_ERR_BAD_SIZE, "svd n > 36");
    CHECK(gf_svd(GF_LINALG_MAX_ROWS + 1, 3, svd_U, svd_s, svd_V) == GF_ERR_BAD_SIZE, "svd m > 64");
    a[7] = NAN;
    CHECK(gf_svd(4, 3, a, s, v) == GF_ERR_NONFINITE_INPUT, "svd NaN");
    a[7] = -INFINITY;
    CHECK(gf_svd(4, 3, a, s, v) == GF_ERR_NONFINITE_INPUT, "svd -Inf");
    a[7] = 8.0;
    a[11] = INFINITY;
    CHECK(gf_svd(4, 3, a, s, v) == GF_ERR_NONFINITE_INPUT, "svd Inf in the last entry");
}

/* ======================================================================================
 * gf_cholesky, gf_cholesky_solve
 * ==================================================================================== */

static void test_cholesky(void)
{
    static double A[36 * 36], L[36 * 36], B[36 * 36], X[36 * 4], Y[36 * 4];
    test_rng rng = {31337};
    const size_t sizes[] = {1, 2, 3, 6, 12, 36};
    double worst_f = 0.0, worst_s = 0.0;
    for (size_t c = 0; c < sizeof sizes / sizeof sizes[0]; ++c) {
        const size_t n = sizes[c], k = 4;
        for (size_t i = 0; i < n * n; ++i)
            B[i] = test_rng_uniform(&rng, -1, 1);
        for (size_t i = 0; i < n; ++i) /* A = B B^T + 1e-3 n I: SPD, cond up to ~1e5 */
            for (size_t j = 0; j < n; ++j) {
                double acc = i == j ? 1e-3 * (double)n : 0.0;
                for (size_t q = 0; q < n; ++q)
                    acc += B[i * n + q] * B[j * n + q];
                A[i * n + j] = acc;
            }
        memcpy(L, A, n * n * sizeof *A);
        CHECK(gf_cholesky(n, L) == GF_OK, "cholesky n = %zu", n);
        int lower = 1;
        for (size_t i = 0; i < n; ++i) {
            lower &= L[i * n + i] > 0.0;
            for (size_t j = i + 1; j < n; ++j)
                lower &= L[i * n + j] == 0.0;
        }
        CHECK(lower, "cholesky n = %zu: lower triangular, positive diagonal, upper zeroed", n);
        /* Higham, Thm 10.3: L L^T = A + dA, |dA| <= g_(n+1) |L||L^T|, and
         * (|L||L^T|)_ij <= |L_i| |L_j| = sqrt(A_ii A_jj) (1 + O(eps)): allowed twice that */
        const double g = (double)(n + 1) * EPS / (1.0 - (double)(n + 1) * EPS);
        double fe = 0.0;
        for (size_t i = 0; i < n; ++i)
            for (size_t j = 0; j < n; ++j) {
                double acc = 0.0;
                for (size_t q = 0; q < n; ++q)
                    acc += L[i * n + q] * L[j * n + q];
                const double scale = sqrt(A[i * n + i] * A[j * n + j]);
                fe = fmax(fe, fabs(acc - A[i * n + j]) / (g * scale));
            }
        CHECK(fe <= 2.0, "cholesky n = %zu: L L^T = A (%.3g x the bound)", n, fe);
        worst_f = fmax(worst_f, fe);
        /* solve: B = A X_true, solve in place; residual |A X - B|_i <= g_(3n+1) (|L||L^T||X|)_i
         * plus the rounding of A X here (g_n |A||X|): both below
         * 2 g_(3n+1) sum_j sqrt(A_ii A_jj)|X_j| + g_n sum_j |A_ij||X_j| */
        for (size_t i = 0; i < n * k; ++i)
            X[i] = test_rng_uniform(&rng, -2, 2);
        for (size_t i = 0; i < n; ++i)
            for (size_t cc = 0; cc < k; ++cc) {
                double acc = 0.0;
                for (size_t q = 0; q < n; ++q)
                    acc += A[i * n + q] * X[q * k + cc];
                Y[i * k + cc] = acc;
            }
        memcpy(B, Y, n * k * sizeof *Y);
        gf_cholesky_solve(n, L, k, B);
        const double g3 = (double)(3 * n + 1) * EPS / (1.0 - (double)(3 * n + 1) * EPS);
        double se = 0.0;
        for (size_t i = 0; i < n; ++i)
            for (size_t cc = 0; cc < k; ++cc) {
                double acc = 0.0, bound = 0.0;
                for (size_t q = 0; q < n; ++q) {
                    acc += A[i * n + q] * B[q * k + cc];
                    bound += 2.0 * g3 * sqrt(A[i * n + i] * A[q * n + q]) * fabs(B[q * k + cc]) +
                             (double)n * EPS * fabs(A[i * n + q]) * fabs(B[q * k + cc]);
                }
                se = fmax(se, fabs(acc - Y[i * k + cc]) / bound);
            }
        CHECK(se <= 1.0, "cholesky_solve n = %zu: residual %.3g x the bound", n, se);
        worst_s = fmax(worst_s, se);
    }
    printf("cholesky: max |L L^T - A| %.3g x Higham bound, solve residual %.3g x bound\n", worst_f, worst_s);

    /* known 3x3: A = L0 L0^T with L0 = [[2,0,0],[1,3,0],[-1,2,1]] (small integers: exact) */
    const double a3[9] = {4, 2, -2, 2, 10, 5, -2, 5, 6};
    const double l3[9] = {2, 0, 0, 1, 3, 0, -1, 2, 1};
    double t3[9];
    memcpy(t3, a3, sizeof t3);
    CHECK(gf_cholesky(3, t3) == GF_OK && memcmp(t3, l3, sizeof t3) == 0, "cholesky of integer 3x3 exact");
    double b3[3] = {4 * 0.5 + 2 - 2, 2 * 0.5 + 10 + 5, -2 * 0.5 + 5 + 6}; /* A [0.5, 1, 1]^T */
    gf_cholesky_solve(3, t3, 1, b3);
    CHECK(b3[0] == 0.5 && b3[1] == 1.0 && b3[2] == 1.0, "cholesky_solve integer 3x3 exact (%g %g %g)", b3[0],
          b3[1], b3[2]);

    /* not positive definite */
    double d1[4] = {1, 0, 0, -1}, d2[4] = {1, 2, 2, 1}, d3[4] = {1, 1, 1, 1}, d4[4] = {0, 0, 0, 0};
    double d5[4] = {NAN, 0, 0, 1}, d6[9] = {4, 2, -2, 2, 10, 5, -2, 5, 5}, d7[4] = {INFINITY, 0, 0, 1};
    double d8[1] = {-0.0};
    CHECK(gf_cholesky(2, d1) == GF_ERR_SINGULAR_GEOMETRY, "cholesky indefinite diagonal");
    CHECK(gf_cholesky(2, d2) == GF_ERR_SINGULAR_GEOMETRY, "cholesky indefinite");
    CHECK(gf_cholesky(2, d3) == GF_ERR_SINGULAR_GEOMETRY, "cholesky exactly singular (PSD)");
    CHECK(gf_cholesky(2, d4) == GF_ERR_SINGULAR_GEOMETRY, "cholesky zero matrix");
    CHECK(gf_cholesky(2, d5) == GF_ERR_SINGULAR_GEOMETRY, "cholesky NaN");
    CHECK(gf_cholesky(3, d6) == GF_ERR_SINGULAR_GEOMETRY, "cholesky 3x3 singular in the last pivot (0)");
    CHECK(gf_cholesky(2, d7) == GF_ERR_SINGULAR_GEOMETRY, "cholesky Inf");
    CHECK(gf_cholesky(1, d8) == GF_ERR_SINGULAR_GEOMETRY, "cholesky -0");
}

/* ======================================================================================
 * gf_sym3_eig
 * ==================================================================================== */

/* eigenvalues of a symmetric 3x3 matrix by the trigonometric closed form, descending */
static void ref_sym3_values(const double a[9], double e[3])
{
    const double p1 = SQ(a[1]) + SQ(a[2]) + SQ(a[5]);
    const double q = (a[0] + a[4] + a[8]) / 3.0;
    const double p2 = SQ(a[0] - q) + SQ(a[4] - q) + SQ(a[8] - q) + 2.0 * p1;
    if (p2 == 0.0) {
        e[0] = e[1] = e[2] = q;
        return;
    }
    const double p = sqrt(p2 / 6.0);
    double b[9];
    for (int i = 0; i < 9; ++i)
        b[i] = (a[i] - (i % 4 == 0 ? q : 0.0)) / p;
    const double det = b[0] * (b[4] * b[8] - b[5] * b[7]) - b[1] * (b[3] * b[8] - b[5] * b[6]) +
                       b[2] * (b[3] * b[7] - b[4] * b[6]);
    const double r = fmin(1.0, fmax(-1.0, det / 2.0));
    const double phi = acos(r) / 3.0;
    e[0] = q + 2.0 * p * cos(phi);
    e[2] = q + 2.0 * p * cos(phi + 2.0 * PI / 3.0);
    e[1] = 3.0 * q - e[0] - e[2];
}

/* residual max_j |A v_j - w_j v_j| / ||A||_F and |V^T V - I| (eps units); sortedness */
static void eig3_measure(const double a[9], const double w[3], const double v[9], double *res, double *orth,
                         int *sorted)
{
    double fn = 0.0;
    for (int i = 0; i < 9; ++i)
        fn += SQ(a[i]);
    fn = sqrt(fn);
    *res = *orth = 0.0;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
            const double av = a[3 * i] * v[j] + a[3 * i + 1] * v[3 + j] + a[3 * i + 2] * v[6 + j];
            *res = fmax(*res, fabs(av - w[j] * v[3 * i + j]) / (EPS * (fn > 0 ? fn : 1.0)));
        }
    for (int p = 0; p < 3; ++p)
        for (int q = 0; q < 3; ++q) {
            const double d = v[p] * v[q] + v[3 + p] * v[3 + q] + v[6 + p] * v[6 + q];
            *orth = fmax(*orth, fabs(d - (p == q ? 1.0 : 0.0)) / EPS);
        }
    *sorted = w[0] >= w[1] && w[1] >= w[2];
}

static void test_sym3_eig(void)
{
    test_rng rng = {2024};
    double worst_res = 0, worst_orth = 0, worst_val = 0, worst_tr = 0;
    for (int rep = 0; rep < 500; ++rep) {
        double a[9];
        const double sc = pow(10.0, test_rng_uniform(&rng, -3, 3));
        for (int i = 0; i < 3; ++i)
            for (int j = i; j < 3; ++j)
                a[3 * i + j] = a[3 * j + i] = sc * test_rng_uniform(&rng, -1, 1);
        double w[3], v[9], e[3], res, orth;
        int sorted;
        gf_sym3_eig(a, w, v);
        eig3_measure(a, w, v, &res, &orth, &sorted);
        ref_sym3_values(a, e);
        double fn = 0.0;
        for (int i = 0; i < 9; ++i)
            fn += SQ(a[i]);
        fn = sqrt(fn);
        double dv = 0.0;
        for (int k = 0; k < 3; ++k)
            dv = fmax(dv, fabs(w[k] - e[k]) / (EPS * fn));
        const double dtr = fabs(w[0] + w[1] + w[2] - (a[0] + a[4] + a[8])) / (EPS * fn);
        /* Jacobi: ~4 sweeps of 3 rotations, each a few eps of ||A||: residual and
         * orthonormality within 32 eps (measured <= 6 eps); the closed form loses
         * accuracy as eigenvalues approach each other (acos near +-1): measured 15 eps
         * over these 500 matrices, allowed 128 eps ||A||; the trace is a sum of three
         * rounded values: 16 eps */
        CHECK(sorted, "sym3 random %d: descending", rep);
        CHECK(res <= 32.0, "sym3 random %d: A v = w v (%.3g eps ||A||)", rep, res);
        CHECK(orth <= 32.0, "sym3 random %d: V orthonormal (%.3g eps)", rep, orth);
        CHECK(dv <= 128.0, "sym3 random %d: eigenvalues = closed form (%.3g eps ||A||)", rep, dv);
        CHECK(dtr <= 16.0, "sym3 random %d: sum of eigenvalues = trace (%.3g eps ||A||)", rep, dtr);
        worst_res = fmax(worst_res, res);
        worst_orth = fmax(worst_orth, orth);
        worst_val = fmax(worst_val, dv);
        worst_tr = fmax(worst_tr, dtr);
    }
    printf("sym3 eig random: residual %.3g eps ||A||, V^T V %.3g eps, vs closed form %.3g eps ||A||, trace %.3g\n",
           worst_res, worst_orth, worst_val, worst_tr);

    /* repeated eigenvalues: Q diag(d) Q^T */
    const double diags[4][3] = {{2, 2, -1}, {1, -3, -3}, {5, 5, 5}, {0, 0, 1e-3}};
    for (int c = 0; c < 4; ++c) {
        double Q[9], a[9];
        random_orthogonal(&rng, 3, Q);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                a[3 * i + j] = Q[3 * i] * diags[c][0] * Q[3 * j] + Q[3 * i + 1] * diags[c][1] * Q[3 * j + 1] +
                               Q[3 * i + 2] * diags[c][2] * Q[3 * j + 2];
        for (int i = 0; i < 3; ++i) /* symmetric to the bit */
            for (int j = i + 1; j < 3; ++j)
                a[3 * j + i] = a[3 * i + j];
        double w[3], v[9], res, orth;
        int sorted;
        gf_sym3_eig(a, w, v);
        eig3_measure(a, w, v, &res, &orth, &sorted);
        double dsorted[3] = {diags[c][0], diags[c][1], diags[c][2]};
        for (int i = 0; i < 3; ++i)
            for (int j = i + 1; j < 3; ++j)
                if (dsorted[j] > dsorted[i]) {
                    const double t = dsorted[i];
                    dsorted[i] = dsorted[j];
                    dsorted[j] = t;
                }
        const double sc = fmax(fabs(dsorted[0]), fabs(dsorted[2]));
        double dv = 0.0;
        for (int k = 0; k < 3; ++k)
            dv = fmax(dv, fabs(w[k] - dsorted[k]) / (EPS * sc));
        /* the construction rounds A by a few eps |d|: eigenvalues within 16 eps */
        CHECK(sorted && dv <= 16.0, "sym3 repeated %d: eigenvalues (%g %g %g) (%.3g eps)", c, w[0], w[1], w[2], dv);
        CHECK(res <= 32.0 && orth <= 32.0, "sym3 repeated %d: residual %.3g eps, orthonormal %.3g eps", c, res,
              orth);
    }

    /* diagonal input: exact values, the axes as vectors (a permutation) */
    const double dg[9] = {1, 0, 0, 0, 5, 0, 0, 0, -2};
    double w[3], v[9];
    gf_sym3_eig(dg, w, v);
    const double vexp[9] = {0, 1, 0, 1, 0, 0, 0, 0, 1};
    CHECK(w[0] == 5 && w[1] == 1 && w[2] == -2, "sym3 diagonal: values 5, 1, -2 exactly (%g %g %g)", w[0], w[1],
          w[2]);
    CHECK(memcmp(v, vexp, sizeof v) == 0, "sym3 diagonal: vectors e_y, e_x, e_z exactly");
    const double z[9] = {0};
    gf_sym3_eig(z, w, v);
    const double eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    CHECK(w[0] == 0 && w[1] == 0 && w[2] == 0 && memcmp(v, eye, sizeof v) == 0, "sym3 zero matrix: 0, identity");
    /* off-diagonal only: values 1, 0, -1 */
    const double od[9] = {0, 1, 0, 1, 0, 0, 0, 0, 0};
    double res, orth;
    int sorted;
    gf_sym3_eig(od, w, v);
    eig3_measure(od, w, v, &res, &orth, &sorted);
    CHECK(fabs(w[0] - 1) <= 4 * EPS && fabs(w[1]) <= 4 * EPS && fabs(w[2] + 1) <= 4 * EPS && res <= 32 &&
              orth <= 32,
          "sym3 zero diagonal: 1, 0, -1 (%g %g %g)", w[0], w[1], w[2]);
}

/* ======================================================================================
 * gf_kalman
 * ==================================================================================== */

static int kf_same(const gf_kalman *a, const gf_kalman *b)
{
    return a->n == b->n && memcmp(a->x, b->x, sizeof a->x) == 0 && memcmp(a->P, b->P, sizeof a->P) == 0;
}

static void test_kalman_scalar(void)
{
    gf_kalman kf;
    const double x0 = 1.0, P0 = 4.0;
    CHECK(gf_kalman_init(&kf, 1, &x0, &P0) == GF_OK, "scalar init");
    const double F = 0.9, Q = 0.5, H = 1.0, R = 1.26;
    CHECK(gf_kalman_predict(&kf, &F, &Q, 1) == GF_OK, "scalar predict");
    /* x = 0.9, P = 0.81 * 4 + 0.5 = 3.74 */
    CHECK_CLOSE(kf.x[0], 0.9, 0.0, "scalar predict x = F x");
    CHECK_CLOSE(kf.P[0], 3.74, 2 * EPS * 3.74, "scalar predict P = F P F + Q");
    const double z = 2.0, r = z - kf.x[0];
    double nis = -1;
    CHECK(gf_kalman_update(&kf, 1, &r, &H, &R, &nis) == GF_OK, "scalar update");
    /* S = 5, K = 0.748, x = 0.9 + 0.748 * 1.1, P = (1 - K) P = 0.94248, nis = r^2 / S */
    CHECK_CLOSE(kf.x[0], 0.9 + 0.748 * 1.1, 4 * EPS * 2, "scalar update x");
    CHECK_CLOSE(kf.P[0], 0.252 * 3.74, 16 * EPS, "scalar update P (Joseph = (1 - K) P)");
    CHECK_CLOSE(nis, 1.1 * 1.1 / 5.0, 4 * EPS, "scalar NIS r^2/S");

    /* no propagation of x, F = NULL (identity), Q = NULL (zero) */
    const double xb = kf.x[0], Pb = kf.P[0];
    const double F2 = 2.0;
    CHECK(gf_kalman_predict(&kf, &F2, NULL, 0) == GF_OK && kf.x[0] == xb && kf.P[0] == 4 * Pb,
          "predict propagate_x = 0: x kept, P = F P F");
    CHECK(gf_kalman_predict(&kf, NULL, &Q, 1) == GF_OK && kf.x[0] == xb && kf.P[0] == 4 * Pb + Q,
          "predict F = NULL: identity, P += Q");
    CHECK(gf_kalman_predict(&kf, NULL, NULL, 1) == GF_OK && kf.x[0] == xb && kf.P[0] == 4 * Pb + Q,
          "predict F = Q = NULL: nothing changes");
}

/* Constant velocity: x = [p, v], F = [[1, T], [0, 1]], Q = q [[T^3/3, T^2/2], [T^2/2, T]],
 * position measured with variance R; the filter written out by hand:
 *   predict  p' = p + T v,  P00' = P00 + 2 T P01 + T^2 P11 + q T^3/3,
 *            P01' = P01 + T P11 + q T^2/2,  P11' = P11 + q T
 *   update   S = P00 + R, K = [P00, P01]/S, x += K r,
 *            P00 = P00 R/S, P01 = P01 R/S, P11 = P11 - P01^2/S  */
static void test_kalman_cv(void)
{
    const double T = 0.1, q = 0.3, R = 0.04;
    const double x0[2] = {1.0, -0.5}, P0[4] = {2.0, 0.3, 0.3, 1.0};
    const double F[4] = {1, T, 0, 1};
    const double Q[4] = {q * T * T * T / 3, q * T * T / 2, q * T * T / 2, q * T};
    const double H[2] = {1, 0};
    gf_kalman kf;
    CHECK(gf_kalman_init(&kf, 2, x0, P0) == GF_OK, "cv init");
    double p = x0[0], v = x0[1], P00 = P0[0], P01 = P0[1], P11 = P0[3];
    double worst = 0.0, worst_nis = 0.0;
    int sym = 1;
    for (int k = 0; k < 200; ++k) {
        CHECK(gf_kalman_predict(&kf, F, Q, 1) == GF_OK, "cv predict %d", k);
        p += T * v;
        const double a00 = P00 + 2 * T * P01 + T * T * P11 + q * T * T * T / 3;
        const double a01 = P01 + T * P11 + q * T * T / 2;
        const double a11 = P11 + q * T;
        P00 = a00, P01 = a01, P11 = a11;
        if (k == 0) {
            CHECK(fabs(kf.P[0] - P00) <= 8 * EPS * P00 && fabs(kf.P[1] - P01) <= 8 * EPS * P00 &&
                      fabs(kf.P[3] - P11) <= 8 * EPS * P11 && kf.x[0] == 1.0 + T * -0.5,
                  "cv first predict = F P F^T + Q");
        }
        const double z = 0.3 * k * T + sin(0.7 * k); /* any measurement sequence */
        const double r = z - kf.x[0];
        double nis;
        CHECK(gf_kalman_update(&kf, 1, &r, H, &R, &nis) == GF_OK, "cv update %d", k);
        const double S = P00 + R, K0 = P00 / S, K1 = P01 / S, rr = z - p;
        p += K0 * rr;
        v += K1 * rr;
        const double n00 = P00 * R / S, n01 = P01 * R / S, n11 = P11 - P01 * P01 / S;
        P00 = n00, P01 = n01, P11 = n11;
        const double sc = fmax(1.0, fabs(p) + fabs(v));
        const double e = fmax(fmax(fabs(kf.x[0] - p), fabs(kf.x[1] - v)) / sc,
                              fmax(fabs(kf.P[0] - P00) / P00, fmax(fabs(kf.P[1] - P01), fabs(kf.P[3] - P11)) / P11));
        worst = fmax(worst, e);
        worst_nis = fmax(worst_nis, fabs(nis - rr * rr / S) / fmax(1.0, rr * rr / S));
        sym &= kf.P[1] == kf.P[2];
    }
    /* Joseph and the short form agree in exact arithmetic; in floating point both are
     * stable here (P well conditioned), differences a few hundred eps at most */
    printf("kalman constant velocity vs hand formulas (200 steps): max rel. difference %.3g, NIS %.3g\n", worst,
           worst_nis);
    CHECK(worst <= 1e-12, "cv filter = hand formulas over 200 steps (%.3g)", worst);
    CHECK(worst_nis <= 1e-12, "cv NIS = r^2/S (%.3g)", worst_nis);
    CHECK(sym, "cv: P stays exactly symmetric");
}

/* Random models: the engine equals the reference update; over many updates with very
 * precise measurements (R down to 1e-10 of P) P stays exactly symmetric and positive
 * semi-definite (smallest eigenvalue >= -64 eps max|P|). */
static void test_kalman_random(void)
{
    test_rng rng = {8080};
    enum { N = 6, M = 3 };
    double x[N], P[N * N], xr[N], Pr[N * N];
    for (int i = 0; i < N; ++i)
        x[i] = test_rng_uniform(&rng, -1, 1);
    for (int i = 0; i < N * N; ++i)
        P[i] = (i % (N + 1) == 0) ? 1.0 : 0.0;
    gf_kalman kf;
    CHECK(gf_kalman_init(&kf, N, x, P) == GF_OK, "random init");
    memcpy(xr, x, sizeof x);
    memcpy(Pr, P, sizeof P);
    double worst_ref = 0.0, worst_neg = 0.0;
    int sym = 1, ok = 1;
    for (int k = 0; k < 1500; ++k) {
        double F[N * N], Q[N * N], H[M * N], R[M * M], r[M];
        for (int i = 0; i < N * N; ++i) {
            F[i] = (i % (N + 1) == 0 ? 1.0 : 0.0) + 0.05 * test_rng_uniform(&rng, -1, 1);
            Q[i] = (i % (N + 1) == 0) ? 1e-6 : 0.0;
        }
        const size_t m = (size_t)(1 + k % M);
        for (size_t i = 0; i < m * N; ++i)
            H[i] = test_rng_uniform(&rng, -1, 1);
        /* R = diag * 10^(-10 .. 0) plus a correlation */
        const double lev = k < 750 ? pow(10.0, test_rng_uniform(&rng, -2, 0)) : pow(10.0, test_rng_uniform(&rng, -10, 0));
        for (size_t i = 0; i < m; ++i)
            for (size_t j = 0; j < m; ++j)
                R[i * m + j] = i == j ? lev : 0.3 * lev;
        for (size_t i = 0; i < m; ++i)
            r[i] = test_rng_uniform(&rng, -1, 1);
        ok &= gf_kalman_predict(&kf, F, (k % 3) ? Q : NULL, 1) == GF_OK;
        /* reference predict */
        double FP[N * N], xp[N];
        for (int i = 0; i < N; ++i) {
            double acc = 0.0;
            for (int j = 0; j < N; ++j)
                acc += F[i * N + j] * xr[j];
            xp[i] = acc;
            for (int j = 0; j < N; ++j) {
                double a2 = 0.0;
                for (int q = 0; q < N; ++q)
                    a2 += F[i * N + q] * Pr[q * N + j];
                FP[i * N + j] = a2;
            }
        }
        memcpy(xr, xp, sizeof xp);
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) {
                double acc = (k % 3) ? Q[i * N + j] : 0.0;
                for (int q = 0; q < N; ++q)
                    acc += FP[i * N + q] * F[j * N + q];
                Pr[i * N + j] = acc;
            }
        ok &= gf_kalman_update(&kf, m, r, H, R, NULL) == GF_OK;
        if (k < 750) { /* compare while the reference's explicit inverse is accurate */
            ref_kalman_update(N, m, xr, Pr, r, H, R);
            double pmax = 0.0, xmax = 0.0, dp = 0.0, dx = 0.0;
            for (int i = 0; i < N * N; ++i) {
                pmax = fmax(pmax, fabs(Pr[i]));
                dp = fmax(dp, fabs(Pr[i] - kf.P[i]));
            }
            for (int i = 0; i < N; ++i) {
                xmax = fmax(xmax, fabs(xr[i]));
                dx = fmax(dx, fabs(xr[i] - kf.x[i]));
            }
            worst_ref = fmax(worst_ref, fmax(dp / pmax, dx / fmax(1.0, xmax)));
            /* keep the reference on the engine's state: differences do not accumulate */
            memcpy(xr, kf.x, sizeof xr);
            memcpy(Pr, kf.P, sizeof Pr);
        } else {
            memcpy(xr, kf.x, sizeof xr);
            memcpy(Pr, kf.P, sizeof Pr);
        }
        double pmax = 0.0, ev[N], V[N * N];
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) {
                sym &= kf.P[i * N + j] == kf.P[j * N + i];
                pmax = fmax(pmax, fabs(kf.P[i * N + j]));
            }
        ref_sym_eig(N, kf.P, ev, V);
        for (int i = 0; i < N; ++i)
            worst_neg = fmax(worst_neg, -ev[i] / (EPS * pmax));
    }
    printf("kalman random (1500 updates): vs reference %.3g (relative), "
           "most negative eigenvalue of P %.3g eps max|P|\n",
           worst_ref, worst_neg);
    CHECK(ok, "random predicts and updates succeed");
    /* R >= 1e-2 in the compared part: S well conditioned, both forms accurate to a few
     * hundred eps (measured ~1e-15) */
    CHECK(worst_ref <= 1e-12, "engine = explicit-inverse reference update (%.3g)", worst_ref);
    CHECK(sym, "Joseph form: P exactly symmetric after every update");
    CHECK(worst_neg <= 64.0, "Joseph form: P positive semi-definite (%.3g eps max|P|)", worst_neg);
}

static void test_kalman_errors(void)
{
    gf_kalman kf, before;
    const double x0[2] = {0.5, -1.0}, P0[4] = {1.0, 0.2, 0.2, 2.0};
    CHECK(gf_kalman_init(&kf, 2, x0, P0) == GF_OK, "init");
    const double H[4] = {1, 0, 0, 1};
    double R[4] = {-2.0, 0, 0, 1}, r[2] = {0.1, 0.2}, nis = 42.0;
    before = kf;
    /* R not positive definite, S = H P H^T + R = [[-1, .2], [.2, 3]] not either */
    CHECK(gf_kalman_update(&kf, 2, r, H, R, &nis) == GF_ERR_SINGULAR_GEOMETRY, "R not PD -> singular");
    CHECK(kf_same(&kf, &before) && nis == 42.0, "R not PD: x, P (and nis) unchanged bitwise");
    R[0] = 1.0;
    R[3] = -5.0;
    CHECK(gf_kalman_update(&kf, 2, r, H, R, NULL) == GF_ERR_SINGULAR_GEOMETRY && kf_same(&kf, &before),
          "second pivot of S negative -> singular, unchanged");
    R[3] = NAN;
    CHECK(gf_kalman_update(&kf, 2, r, H, R, NULL) != GF_OK && kf_same(&kf, &before), "R NaN -> error, unchanged");
    R[3] = 1.0;
    R[1] = R[2] = INFINITY;
    CHECK(gf_kalman_update(&kf, 2, r, H, R, NULL) != GF_OK && kf_same(&kf, &before), "R Inf -> error, unchanged");
    R[1] = R[2] = 0.0;
    r[1] = NAN;
    CHECK(gf_kalman_update(&kf, 2, r, H, R, NULL) == GF_ERR_NONFINITE_INPUT && kf_same(&kf, &before),
          "residual NaN -> nonfinite, unchanged");
    r[1] = -INFINITY;
    CHECK(gf_kalman_update(&kf, 2, r, H, R, NULL) == GF_ERR_NONFINITE_INPUT && kf_same(&kf, &before),
          "residual -Inf -> nonfinite, unchanged");
    r[1] = 0.2;
    const double Hn[4] = {1, NAN, 0, 1};
    CHECK(gf_kalman_update(&kf, 2, r, Hn, R, NULL) != GF_OK && kf_same(&kf, &before), "H NaN -> error, unchanged");
    CHECK(gf_kalman_update(&kf, 0, r, H, R, NULL) == GF_ERR_BAD_SIZE, "m = 0");
    CHECK(gf_kalman_update(&kf, GF_KF_MAX_M + 1, r, H, R, NULL) == GF_ERR_BAD_SIZE, "m > max");
    CHECK(gf_kalman_update(NULL, 2, r, H, R, NULL) == GF_ERR_NULL_POINTER, "update NULL kf");
    CHECK(gf_kalman_update(&kf, 2, NULL, H, R, NULL) == GF_ERR_NULL_POINTER, "update NULL residual");
    CHECK(gf_kalman_update(&kf, 2, r, NULL, R, NULL) == GF_ERR_NULL_POINTER, "update NULL H");
    CHECK(gf_kalman_update(&kf, 2, r, H, NULL, NULL) == GF_ERR_NULL_POINTER, "update NULL R");
    CHECK(gf_kalman_predict(NULL, NULL, NULL, 1) == GF_ERR_NULL_POINTER, "predict NULL kf");
    CHECK(kf_same(&kf, &before), "state unchanged by every rejected call");
    CHECK(gf_kalman_update(&kf, 2, r, H, R, NULL) == GF_OK, "then a good update works");
    gf_kalman bad;
    bad = kf;
    bad.n = 0;
    CHECK(gf_kalman_predict(&bad, NULL, NULL, 1) == GF_ERR_BAD_SIZE, "predict n = 0");
    CHECK(gf_kalman_update(&bad, 1, r, H, R, NULL) == GF_ERR_BAD_SIZE, "update n = 0");
    bad.n = GF_KF_MAX_N + 1;
    CHECK(gf_kalman_predict(&bad, NULL, NULL, 1) == GF_ERR_BAD_SIZE, "predict n > max");
    CHECK(gf_kalman_update(&bad, 1, r, H, R, NULL) == GF_ERR_BAD_SIZE, "update n > max");
    static double bigx[GF_KF_MAX_N + 1], bigP[(GF_KF_MAX_N + 1) * (GF_KF_MAX_N + 1)];
    CHECK(gf_kalman_init(&kf, 0, bigx, bigP) == GF_ERR_BAD_SIZE, "init n = 0");
    CHECK(gf_kalman_init(&kf, GF_KF_MAX_N + 1, bigx, bigP) == GF_ERR_BAD_SIZE, "init n > max");
    CHECK(gf_kalman_init(&kf, GF_KF_MAX_N, bigx, bigP) == GF_OK, "init n = max");
    CHECK(gf_kalman_init(NULL, 2, x0, P0) == GF_ERR_NULL_POINTER &&
              gf_kalman_init(&kf, 2, NULL, P0) == GF_ERR_NULL_POINTER &&
              gf_kalman_init(&kf, 2, x0, NULL) == GF_ERR_NULL_POINTER,
          "init NULLs");
    const double xn[2] = {0, NAN}, Pn[4] = {1, 0, 0, INFINITY};
    CHECK(gf_kalman_init(&kf, 2, xn, P0) == GF_ERR_NONFINITE_INPUT, "init x0 NaN");
    CHECK(gf_kalman_init(&kf, 2, x0, Pn) == GF_ERR_NONFINITE_INPUT, "init P0 Inf");
    CHECK(gf_kalman_init(&kf, 2, x0, P0) == GF_OK && gf_kalman_check(&kf) == GF_OK, "check good");
    bad = kf;
    bad.n = GF_KF_MAX_N + 1;
    CHECK(gf_kalman_check(&bad) == GF_ERR_BAD_SIZE, "check n > max");
    bad = kf;
    bad.P[3] = NAN;
    CHECK(gf_kalman_check(&bad) == GF_ERR_NONFINITE_INPUT, "check NaN in P");
}

/* R, Q and P0 are covariances and the engine reads all of each (gf_kalman.h). Before,
 * the positive-definiteness check of R read its lower triangle only while S and the
 * Joseph form used all of it: R = [[1, 5], [0, 1]] passed as the identity and was used
 * as itself. Now a real asymmetry is refused, and a round-off one is symmetrised: the
 * result equals the call with (A + A^T) / 2 formed here, bitwise. */
static void test_kalman_symmetric_inputs(void)
{
    const double x0[2] = {0.5, -1.0}, P0[4] = {1.0, 0.2, 0.2, 2.0};
    const double H[4] = {1.0, 0.5, 0.0, 1.0}, r[2] = {0.1, -0.3};
    gf_kalman kf, ref, before;
    CHECK(gf_kalman_init(&kf, 2, x0, P0) == GF_OK, "init");
    before = kf;
    const double R_asym[4] = {1.0, 5.0, 0.0, 1.0};
    CHECK(gf_kalman_update(&kf, 2, r, H, R_asym, NULL) == GF_ERR_BAD_PARAMETER && kf_same(&kf, &before),
          "R with R_12 = 5, R_21 = 0: BAD_PARAMETER, filter unchanged");
    const double R_lower[4] = {1.0, 0.0, 5.0, 1.0};
    CHECK(gf_kalman_update(&kf, 2, r, H, R_lower, NULL) == GF_ERR_BAD_PARAMETER && kf_same(&kf, &before),
          "R with R_21 = 5, R_12 = 0: BAD_PARAMETER");
    /* a round-off asymmetry (4 ulp of R_12) */
    const double R_ro[4] = {2.0, 0.3, 0.3 * (1.0 + 4 * EPS), 1.5};
    const double R_sym[4] = {2.0, 0.5 * R_ro[1] + 0.5 * R_ro[2], 0.5 * R_ro[1] + 0.5 * R_ro[2], 1.5};
    ref = kf;
    double nis1 = 0, nis2 = 0;
    CHECK(gf_kalman_update(&kf, 2, r, H, R_ro, &nis1) == GF_OK, "round-off asymmetric R accepted");
    CHECK(gf_kalman_update(&ref, 2, r, H, R_sym, &nis2) == GF_OK, "symmetrised R");
    CHECK(kf_same(&kf, &ref) && nis1 == nis2, "update with R = update with (R + R^T) / 2, bitwise");
    /* Q and P0 the same way */
    const double F[4] = {1.0, 0.1, 0.0, 1.0};
    const double Q_asym[4] = {0.01, 0.0, 0.02, 0.01};
    before = kf;
    CHECK(gf_kalman_predict(&kf, F, Q_asym, 1) == GF_ERR_BAD_PARAMETER && kf_same(&kf, &before),
          "asymmetric Q: BAD_PARAMETER, filter unchanged");
    const double Q_ro[4] = {0.01, 1e-3, 1e-3 * (1.0 - 2 * EPS), 0.02};
    const double Q_sym[4] = {0.01, 0.5 * Q_ro[1] + 0.5 * Q_ro[2], 0.5 * Q_ro[1] + 0.5 * Q_ro[2], 0.02};
    ref = kf;
    CHECK(gf_kalman_predict(&kf, F, Q_ro, 1) == GF_OK && gf_kalman_predict(&ref, F, Q_sym, 1) == GF_OK &&
              kf_same(&kf, &ref),
          "predict with Q = predict with (Q + Q^T) / 2, bitwise");
    const double P_asym[4] = {1.0, 0.2, -0.2, 2.0};
    CHECK(gf_kalman_init(&kf, 2, x0, P_asym) == GF_ERR_BAD_PARAMETER, "asymmetric P0 refused");
    const double P_ro[4] = {1.0, 0.2, 0.2 * (1.0 + 2 * EPS), 2.0};
    CHECK(gf_kalman_init(&kf, 2, x0, P_ro) == GF_OK && kf.P[1] == kf.P[2], "round-off P0 symmetrised");
}

/* ======================================================================================
 * Array solver
 * ==================================================================================== */

/* Layout tables written here. Qin's nine (seed 000, section 1, with u_7..u_9 = l[...]);
 * the 6-accelerometer cube of Tan & Park as tabled in the mission digest (face centres
 * +-l e_k, face-diagonal directions perpendicular to the lever arm; its closed form
 * below confirms it); layout 12: the nine plus l e_x along e_y, l e_y along e_z, l e_z
 * along e_x (gf_gfins.h). Rows: u / l and theta. */
#define R2 0.70710678118654752440
static const double kQin9U[9][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0},
                                    {0, 0, -1}, {1, -1, 0}, {1, 0, -1}, {0, 1, -1}};
static const double kQin9T[9][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0},
                                    {0, 0, -1}, {R2, R2, 0}, {R2, 0, R2}, {0, R2, R2}};
static const double kCube6U[6][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
static const double kCube6T[6][3] = {{0, R2, R2}, {R2, 0, R2}, {R2, R2, 0}, {0, R2, -R2}, {-R2, 0, R2}, {R2, -R2, 0}};
static const double kExtra12U[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
static const double kExtra12T[3][3] = {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}};

typedef struct layout {
    const char *name;
    size_t n;
    double u[GF_ARRAY_MAX_SENSORS][3], th[GF_ARRAY_MAX_SENSORS][3];
} layout;

static void layout_qin9(double l, layout *L)
{
    L->name = "qin9";
    L->n = 9;
    for (int i = 0; i < 9; ++i)
        for (int k = 0; k < 3; ++k) {
            L->u[i][k] = l * kQin9U[i][k];
            L->th[i][k] = kQin9T[i][k];
        }
}

static void layout_cube6(double l, layout *L)
{
    L->name = "cube6";
    L->n = 6;
    for (int i = 0; i < 6; ++i)
        for (int k = 0; k < 3; ++k) {
            L->u[i][k] = l * kCube6U[i][k];
            L->th[i][k] = kCube6T[i][k];
        }
}

static void layout_twelve(double l, layout *L)
{
    layout_qin9(l, L);
    L->name = "layout12";
    L->n = 12;
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) {
            L->u[9 + i][k] = l * kExtra12U[i][k];
            L->th[9 + i][k] = kExtra12T[i][k];
        }
}

static void layout_random(test_rng *r, size_t n, layout *L)
{
    L->name = "random";
    L->n = n;
    for (size_t i = 0; i < n; ++i) {
        random_v3(r, -0.3, 0.3, L->u[i]);
        random_unit(r, L->th[i]);
    }
}

static gf_status to_geometry(const layout *L, gf_array_geometry *g)
{
    return gf_array_geometry_set(g, L->n, &L->u[0][0], &L->th[0][0], NULL);
}

/* Model matrix from the independent output function: columns of f and w_dot from unit
 * vectors; W_jj from w = e_j; W_jk (j != k) from w = e_j + e_k minus the two squares
 * (w w^T then has W_jk = W_kj = 1, the header's convention). */
static void ref_model(const layout *L, double H[][GF_X_N])
{
    const double zero[3] = {0, 0, 0};
    for (size_t i = 0; i < L->n; ++i) {
        for (int j = 0; j < 3; ++j) {
            double e[3] = {0, 0, 0};
            e[j] = 1.0;
            H[i][j] = independent_output(L->u[i], L->th[i], e, zero, zero);
            H[i][3 + j] = independent_output(L->u[i], L->th[i], zero, zero, e);
            H[i][6 + j] = independent_output(L->u[i], L->th[i], zero, e, zero);
        }
        const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        for (int p = 0; p < 3; ++p) {
            double e[3] = {0, 0, 0};
            e[pairs[p][0]] = e[pairs[p][1]] = 1.0;
            H[i][9 + p] = independent_output(L->u[i], L->th[i], zero, e, zero) - H[i][6 + pairs[p][0]] -
                          H[i][6 + pairs[p][1]];
        }
    }
}

static const uint32_t kGroup[GF_X_N] = {1, 1, 1, 2, 2, 2, 4, 4, 4, 8, 8, 8};

/* Eigen-decomposition of H_c^T H_c for the columns in mask: condition number, noise
 * gains sqrt(diag((H^T H)^-1)) and the unknowns touched by the null space. */
typedef struct ref_report {
    size_t k, rank;
    int cols[GF_X_N];
    double cond, gain[GF_X_N];
    uint32_t null_bits;
} ref_report;

static void ref_analyse(const layout *L, double H[][GF_X_N], uint32_t groups, ref_report *rep)
{
    memset(rep, 0, sizeof *rep);
    for (int j = 0; j < GF_X_N; ++j)
        if (kGroup[j] & groups)
            rep->cols[rep->k++] = j;
    const size_t k = rep->k;
    /* in the solver's orthonormal product coordinates: an off-diagonal product W_jk
     * enters as (H_jk / sqrt2)(sqrt2 W_jk), so its column is scaled by 1/sqrt2 (the
     * condition number is that of these columns) and its gain divided by sqrt2 below */
    double sc[GF_X_N];
    for (size_t a = 0; a < k; ++a)
        sc[a] = rep->cols[a] >= 9 ? 1.0 / sqrt(2.0) : 1.0;
    double G[GF_X_N * GF_X_N] = {0}, ev[GF_X_N] = {0}, V[GF_X_N * GF_X_N] = {0};
    for (size_t a = 0; a < k; ++a)
        for (size_t b = 0; b < k; ++b) {
            double acc = 0.0;
            for (size_t i = 0; i < L->n; ++i)
                acc += H[i][rep->cols[a]] * sc[a] * H[i][rep->cols[b]] * sc[b];
            G[a * k + b] = acc;
        }
    ref_sym_eig(k, G, ev, V);
    double emax = 0.0;
    for (size_t c = 0; c < k; ++c)
        emax = fmax(emax, ev[c]);
    double emin = emax;
    double nullw[GF_X_N] = {0};
    for (size_t c = 0; c < k; ++c) {
        /* H^T H squares the singular values, and an exact zero comes out at ~eps emax:
         * rank counts singular values above 1e-6 s_max (the layouts here have
         * cond < 1e3, dependent columns give ~1e-8 s_max through H^T H) */
        if (ev[c] > 1e-12 * emax) {
            ++rep->rank;
            emin = fmin(emin, ev[c]);
            for (size_t a = 0; a < k; ++a)
                rep->gain[rep->cols[a]] += SQ(V[a * k + c]) / ev[c];
        } else {
            for (size_t a = 0; a < k; ++a)
                nullw[a] += SQ(V[a * k + c]);
        }
    }
    for (size_t a = 0; a < k; ++a) {
        rep->gain[rep->cols[a]] = sqrt(rep->gain[rep->cols[a]]) * sc[a];
        if (nullw[a] > 1e-6)
            rep->null_bits |= 1u << rep->cols[a];
    }
    rep->cond = sqrt(emax / emin);
}

/* Per-unknown round-off bound of a least-squares estimate from outputs whose terms are
 * at most S in size (|A| <= sqrt(N) S). x_j = P_j . A with the row P_j of norm g_j (the
 * noise gain): the outputs computed here carry <= 8 eps S of round-off (five terms, a
 * dot product), giving g_j sqrt(N) 8 eps S; the computed pseudo-inverse differs from
 * the exact one by ~eps cond |P|_2 (perturbation of a full-rank pseudo-inverse after
 * a backward-stable SVD), |P|_2 ~ g_max, giving 2 eps cond g_max sqrt(N) S. Measured
 * errors stay below 1.5 eps g_j sqrt(N) S, i.e. 1/10 of this bound or less. */
static void ls_tolerance(const gf_array_solver *s, double S, double tol[GF_X_N])
{
    double gmax = 0.0;
    for (int j = 0; j < GF_X_N; ++j)
        gmax = fmax(gmax, s->noise_gain[j]);
    const double sn = sqrt((double)s->n_sensors);
    for (int j = 0; j < GF_X_N; ++j)
        tol[j] = (8.0 * s->noise_gain[j] + 2.0 * s->cond * gmax) * EPS * sn * S;
}

static double term_bound(const layout *L, const double f[3], const double w[3], const double wd[3])
{
    double umax = 0.0;
    for (size_t i = 0; i < L->n; ++i)
        umax = fmax(umax, norm3(L->u[i]));
    return norm3(f) + norm3(wd) * umax + 2.0 * dot3(w, w) * umax;
}

static void outputs(const layout *L, const double f[3], const double w[3], const double wd[3], double *A)
{
    for (size_t i = 0; i < L->n; ++i)
        A[i] = independent_output(L->u[i], L->th[i], f, w, wd);
}

static void products(const double w[3], double p[6])
{
    p[0] = w[0] * w[0], p[1] = w[1] * w[1], p[2] = w[2] * w[2];
    p[3] = w[0] * w[1], p[4] = w[0] * w[2], p[5] = w[1] * w[2];
}

static double g_ls_ratio = 0.0;

typedef struct expected_groups {
    uint32_t present, estimated, from_rate;
    size_t n_obs, n_conf;
} expected_groups;

/* Q v for the projector Q on the complement of range(H_l) (normal equations of the six
 * f, w_dot columns, solved with the reference eigen-decomposition): |Q v| */
static double ref_residual_norm(const layout *L, double H[][GF_X_N], const double *v)
{
    double G[36], ev[6], V[36], b[6] = {0};
    for (int a = 0; a < 6; ++a) {
        for (int c = 0; c < 6; ++c) {
            double acc = 0.0;
            for (size_t i = 0; i < L->n; ++i)
                acc += H[i][a] * H[i][c];
            G[a * 6 + c] = acc;
        }
        for (size_t i = 0; i < L->n; ++i)
            b[a] += H[i][a] * v[i];
    }
    ref_sym_eig(6, G, ev, V);
    double coef[6] = {0};
    for (int c = 0; c < 6; ++c) {
        double proj = 0.0;
        for (int a = 0; a < 6; ++a)
            proj += V[a * 6 + c] * b[a];
        for (int a = 0; a < 6; ++a)
            coef[a] += V[a * 6 + c] * proj / ev[c];
    }
    double r2 = 0.0;
    for (size_t i = 0; i < L->n; ++i) {
        double acc = v[i];
        for (int a = 0; a < 6; ++a)
            acc -= H[i][a] * coef[a];
        r2 += acc * acc;
    }
    return sqrt(r2);
}

static void check_solver(const layout *L, const gf_array_solver *s, const expected_groups *eg, double l)
{
    static double H[GF_ARRAY_MAX_SENSORS][GF_X_N];
    ref_model(L, H);
    CHECK(s->n_sensors == L->n, "%s: n_sensors", L->name);
    CHECK(s->present == eg->present, "%s: present 0x%x (expected 0x%x)", L->name, s->present, eg->present);
    CHECK(s->estimated == eg->estimated, "%s: estimated 0x%x (expected 0x%x)", L->name, s->estimated,
          eg->estimated);
    CHECK(s->from_rate == eg->from_rate, "%s: from_rate 0x%x (expected 0x%x)", L->name, s->from_rate,
          eg->from_rate);
    CHECK(s->n_obs == eg->n_obs && s->n_conf == eg->n_conf, "%s: %zu observed, %zu confounded (expected %zu, %zu)",
          L->name, s->n_obs, s->n_conf, eg->n_obs, eg->n_conf);
    ref_report rep;
    ref_analyse(L, H, eg->estimated, &rep);
    CHECK(s->n_est == rep.k && s->rank == rep.k && rep.rank == rep.k, "%s: n_est = rank = %zu (got %zu, %zu)",
          L->name, rep.k, s->n_est, s->rank);
    /* H^T H is formed here: its eigenvalues carry ~eps cond^2 relative error, cond <= 1e3 */
    CHECK(fabs(s->cond - rep.cond) <= 1e-9 * rep.cond, "%s: cond %.17g (reference %.17g)", L->name, s->cond,
          rep.cond);
    for (int j = 0; j < GF_X_N; ++j)
        CHECK(fabs(s->noise_gain[j] - rep.gain[j]) <= 1e-9 * rep.gain[j], "%s: noise gain %d %.17g (reference %.17g)",
              L->name, j, s->noise_gain[j], rep.gain[j]);
    /* the model matrix is the one of the physics (to round-off of the forms) */
    double dH = 0.0, hmax = 0.0;
    for (size_t i = 0; i < L->n; ++i)
        for (int j = 0; j < GF_X_N; ++j) {
            dH = fmax(dH, fabs(s->H[i * GF_X_N + j] - H[i][j]));
            hmax = fmax(hmax, fabs(H[i][j]));
        }
    CHECK(dH <= 8 * EPS, "%s: model matrix = physics (%.3g)", L->name, dH);
    /* the product basis: orthonormal; the observed vectors leave a residual outside the
     * range of the f, w_dot columns, the others none; the confounded ones affect the
     * outputs, the absent ones do not (reference projector of the normal equations) */
    double dB = 0.0, obs_min = 1e300, null_max = 0.0, conf_min = 1e300, absent_max = 0.0;
    double Xc[GF_X_N][GF_ARRAY_MAX_SENSORS];
    for (int c = 0; c < 6; ++c) {
        for (int d = 0; d < 6; ++d) {
            double acc = 0.0;
            for (int j = 0; j < 6; ++j)
                acc += s->basis[j * 6 + c] * s->basis[j * 6 + d];
            dB = fmax(dB, fabs(acc - (c == d ? 1.0 : 0.0)));
        }
        double v[GF_ARRAY_MAX_SENSORS], hv = 0.0;
        for (size_t i = 0; i < L->n; ++i) {
            double acc = 0.0;
            for (int j = 0; j < 6; ++j)
                acc += H[i][6 + j] * (j < 3 ? 1.0 : 1.0 / sqrt(2.0)) * s->basis[j * 6 + c];
            v[i] = acc;
            hv += acc * acc;
            if ((size_t)c < s->n_obs)
                Xc[6 + c][i] = acc;
        }
        hv = sqrt(hv);
        const double res = ref_residual_norm(L, H, v);
        if ((size_t)c < s->n_obs) {
            obs_min = fmin(obs_min, res);
        } else {
            null_max = fmax(null_max, res);
            if ((size_t)c < s->n_obs + s->n_conf)
                conf_min = fmin(conf_min, hv);
            else
                absent_max = fmax(absent_max, hv);
        }
    }
    CHECK(dB <= 16 * EPS, "%s: product basis orthonormal (%.3g)", L->name, dB);
    /* separations: observed/confounded vectors act at the size of H (>= 1e-3 |H| for
     * these layouts); the others are round-off (<= 1e-12 |H|) */
    CHECK(s->n_obs == 0 || obs_min >= 1e-3 * hmax, "%s: observed combinations leave the f, w_dot range (%.3g)",
          L->name, obs_min);
    CHECK(null_max <= 1e-12 * hmax, "%s: the others do not (%.3g)", L->name, null_max);
    CHECK(s->n_conf == 0 || conf_min >= 1e-3 * hmax, "%s: confounded combinations affect the outputs (%.3g)",
          L->name, conf_min);
    CHECK(absent_max <= 1e-12 * hmax, "%s: absent combinations do not (%.3g)", L->name, absent_max);
    /* pinv X = I, X = [H_l, H_p B_o] from the physics and the solver's basis (to eps cond) */
    for (size_t i = 0; i < L->n; ++i)
        for (int j = 0; j < 6; ++j)
            Xc[j][i] = H[i][j];
    double dI = 0.0;
    for (size_t r = 0; r < s->n_est; ++r)
        for (size_t c = 0; c < s->n_est; ++c) {
            double acc = 0.0;
            for (size_t i = 0; i < L->n; ++i)
                acc += s->pinv[r * GF_ARRAY_MAX_SENSORS + i] * Xc[c][i];
            dI = fmax(dI, fabs(acc - (r == c ? 1.0 : 0.0)));
        }
    CHECK(dI <= 64 * EPS * s->cond, "%s: pinv X = I (%.3g)", L->name, dI);

    /* exact outputs of random motions, w_pred = true w */
    test_rng rng = {(uint64_t)(1000 + L->n)};
    double worst = 0.0, worst_tol = 0.0;
    for (int rep_i = 0; rep_i < 100; ++rep_i) {
        double f[3], w[3], wd[3], A[GF_ARRAY_MAX_SENSORS], x[GF_X_N], p[6], tol[GF_X_N];
        random_v3(&rng, -20, 20, f);
        random_v3(&rng, -3, 3, w);
        random_v3(&rng, -10, 10, wd);
        outputs(L, f, w, wd, A);
        products(w, p);
        CHECK(gf_array_solve(s, A, w, x) == GF_OK, "%s: solve", L->name);
        const double S = term_bound(L, f, w, wd);
        ls_tolerance(s, S, tol);
        const double truth[GF_X_N] = {f[0], f[1], f[2], wd[0], wd[1], wd[2], p[0], p[1], p[2], p[3], p[4], p[5]};
        for (int j = 0; j < GF_X_N; ++j) {
            if (kGroup[j] & s->estimated) {
                CHECK(fabs(x[j] - truth[j]) <= tol[j], "%s: x_%d = %.17g vs %.17g (tol %.3g)", L->name, j, x[j],
                      truth[j], tol[j]);
                worst = fmax(worst, fabs(x[j] - truth[j]) /
                                        (EPS * s->noise_gain[j] * sqrt((double)L->n) * S));
                worst_tol = fmax(worst_tol, fabs(x[j] - truth[j]) / tol[j]);
            } else {
                /* not observed: the products of w_pred through the orthonormal basis
                 * (B_n B_n^T p: 12 terms, each rounded: <= 16 eps |w|^2) */
                CHECK(fabs(x[j] - truth[j]) <= 16 * EPS * dot3(w, w), "%s: x_%d from w_pred (%.17g vs %.17g)",
                      L->name, j, x[j], truth[j]);
            }
        }
    }
    g_ls_ratio = fmax(g_ls_ratio, worst);
    printf("solver %-8s l = %.2f: cond %.4g, rank %zu, max error %.3g eps g_j sqrt(N) S = %.3g of the tolerance\n",
           L->name, l, s->cond, s->rank, worst, worst_tol);
}

static void test_solver_layouts(void)
{
    const double l = 0.1;
    layout L;
    gf_array_geometry g, gc;
    gf_array_solver s;
    uint32_t unobs = 77;

    /* qin9 */
    layout_qin9(l, &L);
    CHECK(gf9_geometry(l, &gc) == GF_OK, "gf9_geometry");
    CHECK(to_geometry(&L, &g) == GF_OK, "qin9 table");
    double dg = 0.0;
    for (int i = 0; i < 9; ++i)
        for (int k = 0; k < 3; ++k)
            dg = fmax(dg, fmax(fabs(g.u_m[i][k] - gc.u_m[i][k]), fabs(g.theta[i][k] - gc.theta[i][k])));
    /* 1/sqrt2 written as a decimal here, as 1/GF_SQRT2 in the core: one ulp apart */
    CHECK(gc.n_sensors == 9 && dg <= 2 * EPS, "gf9_geometry = seed 000 table (%.3g)", dg);
    CHECK(gf_array_solver_init(&s, &gc, &unobs) == GF_OK && unobs == 0, "qin9 solver");
    const expected_groups eq = {GF_GROUP_F | GF_GROUP_OMEGA_DOT | GF_GROUP_W_DIAG,
                                GF_GROUP_F | GF_GROUP_OMEGA_DOT | GF_GROUP_W_DIAG, 0, 3, 0};
    check_solver(&L, &s, &eq, l);
    /* closed-form noise gains of eq. 3, 4, 6: row norms 1/sqrt2, sqrt6/(4l), 1/l */
    for (int k = 0; k < 3; ++k) {
        CHECK_CLOSE(s.noise_gain[k], 1.0 / sqrt(2.0), 1e-14, "qin9 gain f = 1/sqrt2");
        CHECK_CLOSE(s.noise_gain[3 + k], 1.0 / l, 1e-13, "qin9 gain w_dot = 1/l");
        CHECK_CLOSE(s.noise_gain[6 + k], sqrt(6.0) / (4.0 * l), 1e-13, "qin9 gain W_kk = sqrt6/(4l)");
        CHECK(s.noise_gain[9 + k] == 0.0, "qin9: no gain for the absent products");
    }
    /* seed 000 closed forms on exact outputs */
    {
        test_rng rng = {55};
        double worst = 0.0;
        for (int rep = 0; rep < 200; ++rep) {
            double f[3], w[3], wd[3], A[9], x[GF_X_N];
            random_v3(&rng, -20, 20, f);
            random_v3(&rng, -3, 3, w);
            random_v3(&rng, -10, 10, wd);
            outputs(&L, f, w, wd, A);
            CHECK(gf_array_solve(&s, A, NULL, x) == GF_OK, "qin9 solve without w_pred");
            const double sq2 = sqrt(2.0);
            const double cf[9] = {
                0.5 * (A[0] - A[3]), 0.5 * (A[1] - A[4]), 0.5 * (A[2] - A[5]),                 /* eq. 3 */
                -(A[1] - A[5] - sq2 * A[8]) / (2 * l), -(-A[0] + A[5] + sq2 * A[7]) / (2 * l), /* eq. 6 */
                -(A[0] - A[4] - sq2 * A[6]) / (2 * l),
                (A[0] - A[1] - A[2] + A[3] - A[4] - A[5]) / (4 * l), /* eq. 4, cyclic */
                (A[1] - A[2] - A[0] + A[4] - A[5] - A[3]) / (4 * l),
                (A[2] - A[0] - A[1] + A[5] - A[3] - A[4]) / (4 * l)};
            double tol[GF_X_N];
            ls_tolerance(&s, term_bound(&L, f, w, wd), tol);
            for (int j = 0; j < 9; ++j) {
                CHECK(fabs(x[j] - cf[j]) <= tol[j], "qin9: x_%d = closed form (%.17g vs %.17g)", j, x[j], cf[j]);
                worst = fmax(worst, fabs(x[j] - cf[j]) / tol[j]);
            }
            CHECK(x[9] == 0 && x[10] == 0 && x[11] == 0, "qin9 without w_pred: absent products 0");
        }
        printf("qin9 general solver vs seed 000 closed forms: max %.3g of the tolerance\n", worst);
    }

    /* cube6 */
    layout_cube6(l, &L);
    CHECK(gf_layout_cube6(l, &gc) == GF_OK, "gf_layout_cube6");
    CHECK(to_geometry(&L, &g) == GF_OK, "cube6 table");
    dg = 0.0;
    int tangential = 1;
    for (int i = 0; i < 6; ++i) {
        tangential &= fabs(dot3(gc.u_m[i], gc.theta[i])) <= 1e-17 && fabs(norm3(gc.theta[i]) - 1) <= 2 * EPS;
        for (int k = 0; k < 3; ++k)
            dg = fmax(dg, fmax(fabs(g.u_m[i][k] - gc.u_m[i][k]), fabs(g.theta[i][k] - gc.theta[i][k])));
    }
    CHECK(gc.n_sensors == 6 && dg <= 2 * EPS, "gf_layout_cube6 = the table (%.3g)", dg);
    CHECK(tangential, "cube6: unit directions perpendicular to the lever arms");
    CHECK(gf_array_solver_init(&s, &gc, &unobs) == GF_OK && unobs == 0, "cube6 solver");
    const expected_groups ec = {GF_GROUP_F | GF_GROUP_OMEGA_DOT | GF_GROUP_W_OFFDIAG, GF_GROUP_F | GF_GROUP_OMEGA_DOT,
                                GF_GROUP_W_OFFDIAG, 0, 3};
    check_solver(&L, &s, &ec, l);
    for (int k = 0; k < 3; ++k)
        CHECK_CLOSE(s.noise_gain[3 + k], 1.0 / (sqrt(2.0) * l), 1e-13, "cube6 gain w_dot = 1/(sqrt2 l)");
    {
        test_rng rng = {56};
        double worst = 0.0;
        for (int rep = 0; rep < 200; ++rep) {
            double f[3], w[3], wd[3], A[6], x[GF_X_N], tol[GF_X_N];
            random_v3(&rng, -20, 20, f);
            random_v3(&rng, -3, 3, w);
            random_v3(&rng, -10, 10, wd);
            outputs(&L, f, w, wd, A);
            CHECK(gf_array_solve(&s, A, NULL, x) == GF_ERR_NULL_POINTER, "cube6 needs w_pred");
            /* w_dot does not depend on the products: any w_pred gives the closed form */
            const double wz[3] = {0.3, -0.2, 0.1};
            CHECK(gf_array_solve(&s, A, wz, x) == GF_OK, "cube6 solve");
            const double c = 2.0 * sqrt(2.0) * l;
            const double cf[3] = {(A[1] - A[2] - A[4] - A[5]) / c, (A[2] - A[0] - A[3] - A[5]) / c,
                                  (A[0] - A[1] - A[3] - A[4]) / c};
            ls_tolerance(&s, term_bound(&L, f, w, wd), tol);
            for (int k = 0; k < 3; ++k) {
                CHECK(fabs(x[3 + k] - cf[k]) <= tol[3 + k], "cube6 w_dot_%d = closed form (%.17g vs %.17g)", k,
                      x[3 + k], cf[k]);
                CHECK(fabs(cf[k] - wd[k]) <= tol[3 + k], "cube6 closed form = truth");
                worst = fmax(worst, fabs(x[3 + k] - cf[k]) / tol[3 + k]);
            }
        }
        printf("cube6 general solver vs closed form: max %.3g of the tolerance\n", worst);
    }

    /* layout 12 */
    layout_twelve(l, &L);
    CHECK(gf_layout_12(l, &gc) == GF_OK, "gf_layout_12");
    CHECK(to_geometry(&L, &g) == GF_OK, "layout12 table");
    dg = 0.0;
    for (int i = 0; i < 12; ++i)
        for (int k = 0; k < 3; ++k)
            dg = fmax(dg, fmax(fabs(g.u_m[i][k] - gc.u_m[i][k]), fabs(g.theta[i][k] - gc.theta[i][k])));
    CHECK(gc.n_sensors == 12 && dg <= 2 * EPS, "gf_layout_12 = the table (%.3g)", dg);
    CHECK(gf_array_solver_init(&s, &gc, &unobs) == GF_OK && unobs == 0, "layout12 solver");
    const expected_groups all = {15, 15, 0, 6, 0};
    check_solver(&L, &s, &all, l);

    /* a random array of 20 sensors, and a larger lever arm for layout 12 */
    test_rng rng = {20};
    layout_random(&rng, 20, &L);
    CHECK(to_geometry(&L, &g) == GF_OK, "random20 geometry");
    CHECK(gf_array_solver_init(&s, &g, &unobs) == GF_OK && unobs == 0, "random20 solver");
    CHECK(s.cond < 1e3, "random20 well conditioned (%g)", s.cond);
    check_solver(&L, &s, &all, 0.3);
    layout_twelve(2.0, &L);
    CHECK(to_geometry(&L, &g) == GF_OK && gf_array_solver_init(&s, &g, NULL) == GF_OK, "layout12 l = 2");
    check_solver(&L, &s, &all, 2.0);
    printf("solver on exact outputs: max error %.3g eps g_j sqrt(N) S over all layouts\n", g_ls_ratio);

    /* layouts: parameter errors */
    CHECK(gf_layout_cube6(0.0, &g) == GF_ERR_BAD_PARAMETER && gf_layout_cube6(-1, &g) == GF_ERR_BAD_PARAMETER &&
              gf_layout_cube6(NAN, &g) == GF_ERR_BAD_PARAMETER &&
              gf_layout_cube6(INFINITY, &g) == GF_ERR_BAD_PARAMETER &&
              gf_layout_cube6(0.1, NULL) == GF_ERR_NULL_POINTER,
          "cube6 layout errors");
    CHECK(gf_layout_12(0.0, &g) == GF_ERR_BAD_PARAMETER && gf_layout_12(NAN, &g) == GF_ERR_BAD_PARAMETER &&
              gf_layout_12(0.1, NULL) == GF_ERR_NULL_POINTER,
          "layout12 errors");
}

/* Sensor `to` becomes a copy of sensor `from` (same place, same axis). */
static void copy_sensor(layout *L, size_t from, size_t to)
{
    for (int k = 0; k < 3; ++k) {
        L->u[to][k] = L->u[from][k];
        L->th[to][k] = L->th[from][k];
    }
}

/* Unsolvable geometries: GF_ERR_SINGULAR_GEOMETRY, and the unobservable bits are the
 * unknowns touched by the null space of [f, w_dot] (products from the rate), computed
 * here from H^T H. */
static void check_unsolvable(const char *what, const layout *L, uint32_t expect_bits)
{
    static double H[GF_ARRAY_MAX_SENSORS][GF_X_N];
    ref_model(L, H);
    ref_report rep;
    ref_analyse(L, H, GF_GROUP_F | GF_GROUP_OMEGA_DOT, &rep);
    CHECK(rep.null_bits == expect_bits, "%s: reference null space 0x%x (expected 0x%x)", what, rep.null_bits,
          expect_bits);
    gf_array_geometry g;
    gf_array_solver s;
    uint32_t unobs = 0;
    CHECK(to_geometry(L, &g) == GF_OK, "%s: geometry", what);
    const gf_status st = gf_array_solver_init(&s, &g, &unobs);
    CHECK(st == GF_ERR_SINGULAR_GEOMETRY, "%s: singular (status %d)", what, (int)st);
    CHECK(unobs == rep.null_bits, "%s: unobservable 0x%x (expected 0x%x)", what, unobs, rep.null_bits);
}

static void test_solver_unsolvable(void)
{
    layout L;
    /* zero lever arms: w_dot (bits 3, 4, 5) */
    layout_qin9(0.1, &L);
    L.name = "zero lever arm";
    for (size_t i = 0; i < L.n; ++i)
        L.u[i][0] = L.u[i][1] = L.u[i][2] = 0.0;
    check_unsolvable("zero lever arms", &L, 0x38);
    /* cube6 with sensor 2 a copy of sensor 1: null vector in f_x, f_z, wd_x, wd_z */
    layout_cube6(0.1, &L);
    copy_sensor(&L, 0, 1);
    check_unsolvable("cube6, sensors 1 = 2", &L, 0x2D);
    /* a random minimal array (6 sensors: f and w_dot, products from the rate) with
     * sensor 2 = sensor 1 moved along its sensing axis by 37 mm: the f and w_dot
     * coefficients are unchanged in exact arithmetic (theta . (w_dot x (u + c theta)) =
     * (u x theta) . w_dot) but computed from other numbers, so the dependency shows as
     * a round-off singular value (~1e-16 s_max), not an exact zero */
    {
        test_rng r6 = {66};
        layout_random(&r6, 6, &L);
        gf_array_geometry g6;
        gf_array_solver s6;
        CHECK(to_geometry(&L, &g6) == GF_OK && gf_array_solver_init(&s6, &g6, NULL) == GF_OK &&
                  s6.estimated == (GF_GROUP_F | GF_GROUP_OMEGA_DOT) &&
                  s6.from_rate == (GF_GROUP_W_DIAG | GF_GROUP_W_OFFDIAG),
              "random 6 sensors: f and w_dot, all products from the rate");
        for (int k = 0; k < 3; ++k) {
            L.u[1][k] = L.u[0][k] + 0.037 * L.th[0][k];
            L.th[1][k] = L.th[0][k];
        }
        static double H6[GF_ARRAY_MAX_SENSORS][GF_X_N];
        ref_model(&L, H6);
        ref_report rep6;
        ref_analyse(&L, H6, GF_GROUP_F | GF_GROUP_OMEGA_DOT, &rep6);
        check_unsolvable("random 6, sensor 2 = sensor 1 moved along theta", &L, rep6.null_bits);
        CHECK(rep6.rank == 5, "random 6 moved: reference rank 5 (%zu)", rep6.rank);
    }
    /* qin9 with sensor 8 a copy of sensor 7: w_dot_y alone (even from the rate) */
    layout_qin9(0.1, &L);
    copy_sensor(&L, 6, 7);
    check_unsolvable("qin9, sensors 7 = 8", &L, 0x10);
    /* five random sensors: one null vector touching all six */
    test_rng rng = {5};
    layout_random(&rng, 5, &L);
    check_unsolvable("5 random sensors", &L, 0x3F);
    /* five of Qin's sensors (the radial ones 1..5): f is still determined, w_dot not at all */
    layout_qin9(0.1, &L);
    L.n = 5;
    check_unsolvable("qin9 sensors 1-5", &L, 0x38);
    /* a single radial sensor (u = l e_x, theta = e_x): f_x alone is determined */
    layout_qin9(0.1, &L);
    L.n = 1;
    check_unsolvable("one sensor", &L, 0x3E);

    /* errors */
    gf_array_geometry g;
    gf_array_solver s;
    uint32_t unobs = 99;
    gf9_geometry(0.1, &g);
    CHECK(gf_array_solver_init(NULL, &g, &unobs) == GF_ERR_NULL_POINTER && unobs == 0, "solver NULL");
    CHECK(gf_array_solver_init(&s, NULL, NULL) == GF_ERR_NULL_POINTER, "solver NULL geometry");
    g.n_sensors = 0;
    CHECK(gf_array_solver_init(&s, &g, NULL) == GF_ERR_BAD_SIZE, "solver 0 sensors");
    g.n_sensors = GF_ARRAY_MAX_SENSORS + 1;
    CHECK(gf_array_solver_init(&s, &g, NULL) == GF_ERR_BAD_SIZE, "solver 65 sensors");
    gf9_geometry(0.1, &g);
    g.u_m[4][1] = NAN;
    CHECK(gf_array_solver_init(&s, &g, NULL) == GF_ERR_NONFINITE_INPUT, "solver NaN lever arm");
    gf9_geometry(0.1, &g);
    g.theta[8][2] = INFINITY;
    CHECK(gf_array_solver_init(&s, &g, NULL) == GF_ERR_NONFINITE_INPUT, "solver Inf direction");
    gf9_geometry(0.1, &g);
    CHECK(gf_array_solver_init(&s, &g, NULL) == GF_OK, "solver");
    double A[9] = {0}, x[GF_X_N];
    CHECK(gf_array_solve(NULL, A, NULL, x) == GF_ERR_NULL_POINTER &&
              gf_array_solve(&s, NULL, NULL, x) == GF_ERR_NULL_POINTER &&
              gf_array_solve(&s, A, NULL, NULL) == GF_ERR_NULL_POINTER,
          "solve NULLs");
}

/* ======================================================================================
 * Rate strategies
 * ==================================================================================== */

/* field-by-field bitwise equality (struct padding is indeterminate) */
#define SAME_FIELD(a, b, f) (memcmp(&(a)->f, &(b)->f, sizeof (a)->f) == 0)
static int rate_same(const gf_gfins_state *a, const gf_gfins_state *b)
{
    return SAME_FIELD(a, b, solver.n_sensors) && SAME_FIELD(a, b, solver.present) &&
           SAME_FIELD(a, b, solver.estimated) && SAME_FIELD(a, b, solver.from_rate) &&
           SAME_FIELD(a, b, solver.n_est) && SAME_FIELD(a, b, solver.n_obs) && SAME_FIELD(a, b, solver.n_conf) &&
           SAME_FIELD(a, b, solver.basis) && SAME_FIELD(a, b, solver.K_pred) && SAME_FIELD(a, b, solver.pinv) &&
           SAME_FIELD(a, b, rate_model) && SAME_FIELD(a, b, frame) && SAME_FIELD(a, b, diag_map) &&
           SAME_FIELD(a, b, amb_rad_s) &&
           SAME_FIELD(a, b, solver.H) && SAME_FIELD(a, b, cfg.strategy) && SAME_FIELD(a, b, cfg.accel_noise_m_s2) &&
           SAME_FIELD(a, b, omega_rad_s) && SAME_FIELD(a, b, omega_ref_rad_s) &&
           SAME_FIELD(a, b, omega_dot_rad_s2) && SAME_FIELD(a, b, R_W) && SAME_FIELD(a, b, var_omega_dot) &&
           SAME_FIELD(a, b, n_w_meas) && SAME_FIELD(a, b, kf.n) && SAME_FIELD(a, b, kf.x) &&
           SAME_FIELD(a, b, kf.P) && SAME_FIELD(a, b, n_samples);
}

static gf_rate_config rate_cfg(int strategy)
{
    gf_rate_config c;
    gf_rate_config_default(&c);
    c.strategy = strategy;
    return c;
}

static void test_rate_init(void)
{
    gf_array_geometry q9, c6, l12, bad;
    gf9_geometry(0.1, &q9);
    gf_layout_cube6(0.1, &c6);
    gf_layout_12(0.1, &l12);
    gf_gfins_state st;
    uint32_t unobs = 0;
    const gf_rate_config ci = rate_cfg(GF_RATE_INTEGRATE), cs = rate_cfg(GF_RATE_SQRT), ce = rate_cfg(GF_RATE_EIGEN),
                         cf = rate_cfg(GF_RATE_FUSED);
    CHECK(gf_gfins_init(&st, &c6, &cs, NULL, NULL) == GF_ERR_BAD_PARAMETER, "SQRT on cube6 refused");
    CHECK(gf_gfins_init(&st, &c6, &ce, NULL, NULL) == GF_ERR_BAD_PARAMETER, "EIGEN on cube6 refused");
    CHECK(gf_gfins_init(&st, &c6, &cf, NULL, NULL) == GF_ERR_BAD_PARAMETER, "FUSED on cube6 refused");
    CHECK(gf_gfins_init(&st, &q9, &ce, NULL, NULL) == GF_ERR_BAD_PARAMETER, "EIGEN on qin9 refused");
    CHECK(gf_gfins_init(&st, &c6, &ci, NULL, NULL) == GF_OK, "INTEGRATE on cube6");
    CHECK(gf_gfins_init(&st, &q9, &ci, NULL, NULL) == GF_OK && gf_gfins_init(&st, &q9, &cs, NULL, NULL) == GF_OK,
          "INTEGRATE, SQRT on qin9");
    CHECK(gf_gfins_init(&st, &q9, &cf, NULL, NULL) == GF_OK && st.n_w_meas == 3, "FUSED on qin9: 3 products");
    CHECK(gf_gfins_init(&st, &l12, &cf, NULL, NULL) == GF_OK && st.n_w_meas == 6, "FUSED on layout12: 6 products");
    CHECK(gf_gfins_init(&st, &l12, &ce, NULL, NULL) == GF_OK && gf_gfins_init(&st, &l12, &cs, NULL, NULL) == GF_OK,
          "EIGEN, SQRT on layout12");
    /* the noise covariances sigma^2 P P^T, from the closed forms of seed 000 (qin9's
     * pseudo-inverse is its inverse) */
    {
        gf_rate_config c = cf;
        c.accel_noise_m_s2 = 2e-3;
        CHECK(gf_gfins_init(&st, &q9, &c, NULL, NULL) == GF_OK, "FUSED qin9 sigma 2e-3");
        const double s2 = 4e-6, l = 0.1;
        /* wd_x = -(A2 - A6 - r2 A9)/2l, wd_y = -(-A1 + A6 + r2 A8)/2l: common A6 with
         * coefficients (+1, -1)/2l -> covariance -s2/(4 l^2); variance s2 (1+1+2)/(4l^2) */
        CHECK_CLOSE(st.var_omega_dot[0], s2 / (l * l), 1e-12 * s2 / (l * l), "qin9 var w_dot_x = s^2/l^2");
        CHECK_CLOSE(st.var_omega_dot[1], -s2 / (4 * l * l), 1e-12 * s2 / (l * l), "qin9 cov w_dot_x,y");
        /* W11 = (1, -1, -1, 1, -1, -1) . A1..6 / 4l, W22 = (-1, 1, -1, -1, 1, -1) . A1..6 / 4l:
         * variance 6 s2 / (16 l^2), covariance (-1 - 1 + 1 - 1 - 1 + 1) s2 / (16 l^2).
         * R_W is the covariance of the observed coordinates z; W_kk = W_obs z */
        double RW[9];
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                double acc = 0.0;
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        acc += st.solver.W_obs[a * 6 + i] * st.R_W[3 * i + j] * st.solver.W_obs[b * 6 + j];
                RW[3 * a + b] = acc;
            }
        CHECK_CLOSE(RW[0], 6 * s2 / (16 * l * l), 1e-12 * s2 / (l * l), "qin9 var W11");
        CHECK_CLOSE(RW[1], -2 * s2 / (16 * l * l), 1e-12 * s2 / (l * l), "qin9 cov W11,W22");
    }
    /* configuration errors */
    CHECK(gf_rate_config_default(NULL) == GF_ERR_NULL_POINTER, "config default NULL");
    gf_rate_config c = ci;
    c.strategy = 4;
    CHECK(gf_gfins_init(&st, &q9, &c, NULL, NULL) == GF_ERR_BAD_PARAMETER, "unknown strategy");
    c.strategy = -1;
    CHECK(gf_gfins_init(&st, &q9, &c, NULL, NULL) == GF_ERR_BAD_PARAMETER, "negative strategy");
    c = cf;
    c.accel_noise_m_s2 = 0.0;
    CHECK(gf_gfins_init(&st, &q9, &c, NULL, NULL) == GF_ERR_BAD_PARAMETER, "noise 0");
    c.accel_noise_m_s2 = NAN;
    CHECK(gf_gfins_init(&st, &q9, &c, NULL, NULL) == GF_ERR_BAD_PARAMETER, "noise NaN");
    c = cf;
    c.bias_walk_rad_s2_sqrt_s = -1.0;
    CHECK(gf_gfins_init(&st, &q9, &c, NULL, NULL) == GF_ERR_BAD_PARAMETER, "bias walk < 0");
    c = cf;
    c.init_std_rad_s = 0.0;
    CHECK(gf_gfins_init(&st, &q9, &c, NULL, NULL) == GF_ERR_BAD_PARAMETER, "init std 0");
    c = cf;
    c.init_bias_std_rad_s2 = INFINITY;
    CHECK(gf_gfins_init(&st, &q9, &c, NULL, NULL) == GF_ERR_BAD_PARAMETER, "init bias std Inf");
    const double wnan[3] = {0, NAN, 0};
    CHECK(gf_gfins_init(&st, &q9, &ci, wnan, NULL) == GF_ERR_BAD_PARAMETER, "omega_init NaN");
    CHECK(gf_gfins_init(NULL, &q9, &ci, NULL, NULL) == GF_ERR_NULL_POINTER &&
              gf_gfins_init(&st, NULL, &ci, NULL, NULL) == GF_ERR_NULL_POINTER &&
              gf_gfins_init(&st, &q9, NULL, NULL, NULL) == GF_ERR_NULL_POINTER,
          "init NULLs");
    /* unsolvable geometry: its status and bits */
    bad = q9;
    for (int i = 0; i < 9; ++i)
        bad.u_m[i][0] = bad.u_m[i][1] = bad.u_m[i][2] = 0.0;
    CHECK(gf_gfins_init(&st, &bad, &ci, NULL, &unobs) == GF_ERR_SINGULAR_GEOMETRY && unobs == 0x38,
          "init: zero lever arms -> singular, w_dot unobservable (0x%x)", unobs);
}

/* Constant rate, no angular acceleration, varying specific force. */
static const double kW[3] = {0.7, -0.5, 0.9};
static void cr_force(double t, double f[3])
{
    f[0] = 1.0 + sin(0.7 * t);
    f[1] = -2.0 + 0.5 * cos(1.3 * t);
    f[2] = 9.8 + 0.2 * sin(0.3 * t);
}

enum { NCR = 1000 };
static double cr_A[NCR * GF_ARRAY_MAX_SENSORS];
static double o_f[NCR * 3], o_w[NCR * 3], o_wd[NCR * 3], o_W[NCR * 6];
static uint8_t o_fl[NCR];

typedef struct run_case {
    const char *name;
    int layout_id; /* 0 cube6, 1 qin9, 2 layout12, 3 random20 */
    int strategy;
} run_case;

static void make_layout(int id, layout *L)
{
    test_rng rng = {20};
    switch (id) {
    case 0: layout_cube6(0.1, L); break;
    case 1: layout_qin9(0.1, L); break;
    case 2: layout_twelve(0.1, L); break;
    default: layout_random(&rng, 20, L); break;
    }
}

static void test_rate_constant(void)
{
    const double dt = 0.01;
    const run_case cases[] = {
        {"cube6 INTEGRATE", 0, GF_RATE_INTEGRATE}, {"qin9 INTEGRATE", 1, GF_RATE_INTEGRATE},
        {"qin9 SQRT", 1, GF_RATE_SQRT},           {"qin9 FUSED", 1, GF_RATE_FUSED},
        {"12 INTEGRATE", 2, GF_RATE_INTEGRATE},   {"12 SQRT", 2, GF_RATE_SQRT},
        {"12 EIGEN", 2, GF_RATE_EIGEN},           {"12 FUSED", 2, GF_RATE_FUSED},
        {"random20 SQRT", 3, GF_RATE_SQRT},       {"random20 EIGEN", 3, GF_RATE_EIGEN},
        {"random20 FUSED", 3, GF_RATE_FUSED},     {"random20 INTEGRATE", 3, GF_RATE_INTEGRATE},
    };
    const double zero[3] = {0, 0, 0};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        layout L;
        make_layout(cases[c].layout_id, &L);
        gf_array_geometry g;
        to_geometry(&L, &g);
        double Smax = 0.0;
        for (int k = 0; k < NCR; ++k) {
            double f[3];
            cr_force(k * dt, f);
            outputs(&L, f, kW, zero, cr_A + L.n * (size_t)k);
            Smax = fmax(Smax, term_bound(&L, f, kW, zero));
        }
        const gf_rate_config cfg = rate_cfg(cases[c].strategy);
        gf_gfins_state st, st2;
        CHECK(gf_gfins_init(&st, &g, &cfg, kW, NULL) == GF_OK, "%s: init", cases[c].name);
        st2 = st;
        size_t done = 0;
        CHECK(gf_gfins_run(&st, NCR, cr_A, dt, o_f, o_w, o_wd, o_W, o_fl, &done) == GF_OK && done == NCR,
              "%s: run", cases[c].name);
        double tol[GF_X_N];
        ls_tolerance(&st.solver, Smax, tol);
        /* rate tolerance by strategy (t = 10 s of samples):
         *   INTEGRATE: w = w0 + trapezoid of w_dot: each w_dot within tol_wd, summed over
         *     t: t tol_wd, plus 2 eps |w| per addition;
         *   SQRT: |sqrt(W + d) - |w|| <= d / |w| (d < W/2), plus the sqrt's rounding;
         *   EIGEN: W = w w^T + E, the dominant pair moves by <= 2 |E|_F / |w| (gap |w|^2);
         *   FUSED: Gauss-Newton steps of the EKF on W: as SQRT from the measured
         *     products, plus the prediction's integration as INTEGRATE. */
        const double T = NCR * dt, wn = norm3(kW);
        double tol_w[3];
        const double EF = sqrt(SQ(tol[6]) + SQ(tol[7]) + SQ(tol[8]) + 2 * (SQ(tol[9]) + SQ(tol[10]) + SQ(tol[11])));
        for (int k = 0; k < 3; ++k) {
            const double integ = T * tol[3 + k] + 2.0 * NCR * EPS * fabs(kW[k]);
            switch (cases[c].strategy) {
            case GF_RATE_INTEGRATE: tol_w[k] = integ; break;
            case GF_RATE_SQRT: tol_w[k] = tol[6 + k] / fabs(kW[k]) + 4 * EPS * fabs(kW[k]); break;
            case GF_RATE_EIGEN: tol_w[k] = 2.0 * EF / wn + 64 * EPS * wn; break;
            default: tol_w[k] = tol[6 + k] / fabs(kW[k]) + 2.0 * EF / wn + integ; break;
            }
        }
        /* with products from the rate (cube6), f and w_dot also carry the rate's error:
         * |d(w_j w_k)| <= 2 |w|_inf dw, at most 6 of them in an output with coefficients
         * <= 2 umax: add g_j sqrt(N) 24 umax |w|_inf dw */
        if (st.solver.from_rate) {
            double umax = 0.0, twmax = 0.0, winf = 0.0;
            for (size_t i = 0; i < L.n; ++i)
                umax = fmax(umax, norm3(L.u[i]));
            for (int k = 0; k < 3; ++k) {
                twmax = fmax(twmax, tol_w[k]);
                winf = fmax(winf, fabs(kW[k]));
            }
            for (int j = 0; j < 6; ++j)
                tol[j] += st.solver.noise_gain[j] * sqrt((double)L.n) * 24.0 * umax * winf * twmax;
        }
        double ew = 0, ef = 0, ewd = 0, eW = 0, ew_abs = 0;
        int flags = 0, ok = 1;
        for (int k = 0; k < NCR; ++k) {
            double f[3], p[6];
            cr_force(k * dt, f);
            products(kW, p);
            for (int j = 0; j < 3; ++j) {
                ok &= fabs(o_w[3 * k + j] - kW[j]) <= tol_w[j];
                ok &= fabs(o_f[3 * k + j] - f[j]) <= tol[j];
                ok &= fabs(o_wd[3 * k + j]) <= tol[3 + j];
                ew = fmax(ew, fabs(o_w[3 * k + j] - kW[j]) / tol_w[j]);
                ew_abs = fmax(ew_abs, fabs(o_w[3 * k + j] - kW[j]));
                ef = fmax(ef, fabs(o_f[3 * k + j] - f[j]) / tol[j]);
                ewd = fmax(ewd, fabs(o_wd[3 * k + j]) / tol[3 + j]);
            }
            for (int j = 0; j < 6; ++j)
                if (kGroup[6 + j] & st.solver.estimated)
                    eW = fmax(eW, fabs(o_W[6 * k + j] - p[j]) / tol[6 + j]);
            flags |= o_fl[k];
        }
        printf("constant rate %-18s: |w err| %.3g, |f err| %.3g, |w_dot| %.3g, |W err| %.3g of the tolerances "
               "(max |w err| %.2g rad/s)\n",
               cases[c].name, ew, ef, ewd, eW, ew_abs);
        CHECK(ok, "%s: w, f, w_dot within round-off (w %.3g, f %.3g, w_dot %.3g of tol)", cases[c].name, ew, ef, ewd);
        CHECK(eW <= 1.0, "%s: estimated products within round-off (%.3g of tol)", cases[c].name, eW);
        CHECK(flags == 0, "%s: no flags (0x%x)", cases[c].name, flags);
        CHECK(st.n_samples == NCR, "%s: %d samples counted", cases[c].name, NCR);

        /* step by step = run, bitwise */
        int same = 1;
        for (int k = 0; k < NCR; ++k) {
            double f[3], w[3], wd[3], W[6];
            uint8_t fl = 0xff;
            same &= gf_gfins_step(&st2, cr_A + L.n * (size_t)k, dt, f, w, wd, W, &fl) == GF_OK;
            same &= memcmp(f, o_f + 3 * k, sizeof f) == 0 && memcmp(w, o_w + 3 * k, sizeof w) == 0 &&
                    memcmp(wd, o_wd + 3 * k, sizeof wd) == 0 && memcmp(W, o_W + 6 * k, sizeof W) == 0 &&
                    fl == o_fl[k];
        }
        CHECK(same, "%s: steps = run, bitwise", cases[c].name);
        CHECK(rate_same(&st, &st2), "%s: states after steps and run equal", cases[c].name);
    }
}

/* w = w0 + a t + b t^2 / 2: w_dot = a + b t is linear in time, so the trapezoid of
 * w_dot (INTEGRATE, the sign references, FUSED's prediction) is exact and every
 * strategy must follow w to round-off (a rectangle rule would be off by b dt t / 2,
 * ~1e-3 rad/s here). */
static void lin_motion(double t, double f[3], double w[3], double wd[3])
{
    static const double w0[3] = {0.6, -0.7, 0.8}, a[3] = {0.2, 0.1, -0.3}, b[3] = {-0.1, 0.1, 0.05};
    cr_force(t, f);
    for (int k = 0; k < 3; ++k) {
        w[k] = w0[k] + a[k] * t + 0.5 * b[k] * t * t;
        wd[k] = a[k] + b[k] * t;
    }
}

static void test_rate_linear_acceleration(void)
{
    enum { NL = 200 };
    const double dt = 0.01;
    const run_case cases[] = {
        {"cube6 INTEGRATE", 0, GF_RATE_INTEGRATE}, {"qin9 INTEGRATE", 1, GF_RATE_INTEGRATE},
        {"qin9 SQRT", 1, GF_RATE_SQRT},           {"qin9 FUSED", 1, GF_RATE_FUSED},
        {"12 EIGEN", 2, GF_RATE_EIGEN},           {"random20 INTEGRATE", 3, GF_RATE_INTEGRATE},
        {"random20 FUSED", 3, GF_RATE_FUSED},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        layout L;
        make_layout(cases[c].layout_id, &L);
        gf_array_geometry g;
        to_geometry(&L, &g);
        double Smax = 0.0, wmin = 1e9, wmax = 0.0;
        for (int k = 0; k < NL; ++k) {
            double f[3], w[3], wd[3];
            lin_motion(k * dt, f, w, wd);
            outputs(&L, f, w, wd, cr_A + L.n * (size_t)k);
            Smax = fmax(Smax, term_bound(&L, f, w, wd));
            for (int j = 0; j < 3; ++j) {
                wmin = fmin(wmin, fabs(w[j]));
                wmax = fmax(wmax, fabs(w[j]));
            }
        }
        const gf_rate_config cfg = rate_cfg(cases[c].strategy);
        double f0[3], w0[3], wd0[3];
        lin_motion(0.0, f0, w0, wd0);
        gf_gfins_state st;
        size_t done = 0;
        CHECK(gf_gfins_init(&st, &g, &cfg, w0, NULL) == GF_OK &&
                  gf_gfins_run(&st, NL, cr_A, dt, o_f, o_w, o_wd, o_W, o_fl, &done) == GF_OK && done == NL,
              "%s: linear w_dot run", cases[c].name);
        double tol[GF_X_N];
        ls_tolerance(&st.solver, Smax, tol);
        /* as in the constant-rate test; with products from the rate (cube6) w_dot does
         * not depend on them (its closed form), f does, through the rate error */
        double tw = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double integ = NL * dt * tol[3 + k] + 4.0 * NL * EPS * wmax;
            const double sq = tol[6 + k] / wmin + 4 * EPS * wmax;
            tw = fmax(tw, cases[c].strategy == GF_RATE_INTEGRATE ? integ
                          : cases[c].strategy == GF_RATE_SQRT    ? sq
                          : cases[c].strategy == GF_RATE_EIGEN   ? 4.0 * sqrt(3.0) * tol[6] / wmin + 64 * EPS * wmax
                                                                 : sq + integ);
        }
        double ew = 0.0, ewd = 0.0, ef = 0.0;
        int flags = 0;
        for (int k = 0; k < NL; ++k) {
            double f[3], w[3], wd[3];
            lin_motion(k * dt, f, w, wd);
            for (int j = 0; j < 3; ++j) {
                ew = fmax(ew, fabs(o_w[3 * k + j] - w[j]));
                ewd = fmax(ewd, fabs(o_wd[3 * k + j] - wd[j]) / tol[3 + j]);
                ef = fmax(ef, fabs(o_f[3 * k + j] - f[j]));
            }
            flags |= o_fl[k];
        }
        double umax = 0.0;
        for (size_t i = 0; i < L.n; ++i)
            umax = fmax(umax, norm3(L.u[i]));
        const double tf =
            tol[0] + (st.solver.from_rate ? st.solver.noise_gain[0] * sqrt((double)L.n) * 24.0 * umax * wmax * tw : 0.0);
        printf("linear w_dot %-18s: |w err| %.3g rad/s (tol %.3g), |w_dot err| %.3g of tol, |f err| %.3g (tol %.3g)\n",
               cases[c].name, ew, tw, ewd, ef, tf);
        CHECK(ew <= tw, "%s: w follows w0 + a t + b t^2/2 to round-off (%.3g > %.3g)", cases[c].name, ew, tw);
        CHECK(ewd <= 1.0, "%s: w_dot (%.3g of tol)", cases[c].name, ewd);
        CHECK(ef <= tf, "%s: f (%.3g > %.3g)", cases[c].name, ef, tf);
        CHECK(flags == 0, "%s: no flags (0x%x)", cases[c].name, flags);
    }
}

/* A smooth motion whose w_x crosses zero (t = 2 pi): SQRT must take the sign from the
 * integrated w_dot reference, EIGEN from the reference's direction. */
static void zc_motion(double t, double f[3], double w[3], double wd[3])
{
    cr_force(t, f);
    w[0] = 0.8 * sin(0.5 * t);
    w[1] = 1.5 + 0.3 * cos(0.9 * t);
    w[2] = -2.0 + 0.1 * t;
    wd[0] = 0.4 * cos(0.5 * t);
    wd[1] = -0.27 * sin(0.9 * t);
    wd[2] = 0.1;
}

static void test_rate_zero_crossing(void)
{
    const double dt = 0.01;
    const run_case cases[] = {
        {"qin9 SQRT", 1, GF_RATE_SQRT}, {"12 SQRT", 2, GF_RATE_SQRT}, {"12 EIGEN", 2, GF_RATE_EIGEN}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        layout L;
        make_layout(cases[c].layout_id, &L);
        gf_array_geometry g;
        to_geometry(&L, &g);
        double Smax = 0.0;
        for (int k = 0; k < NCR; ++k) {
            double f[3], w[3], wd[3];
            zc_motion(k * dt + 1.0, f, w, wd);
            outputs(&L, f, w, wd, cr_A + L.n * (size_t)k);
            Smax = fmax(Smax, term_bound(&L, f, w, wd));
        }
        const gf_rate_config cfg = rate_cfg(cases[c].strategy);
        double f0[3], w0[3], wd0[3];
        zc_motion(1.0, f0, w0, wd0);
        gf_gfins_state st;
        size_t done = 0;
        CHECK(gf_gfins_init(&st, &g, &cfg, w0, NULL) == GF_OK &&
                  gf_gfins_run(&st, NCR, cr_A, dt, o_f, o_w, o_wd, o_W, o_fl, &done) == GF_OK,
              "%s: zero-crossing run", cases[c].name);
        double tol[GF_X_N];
        ls_tolerance(&st.solver, Smax, tol);
        /* away from the crossing (|w_k| > 1e-3): SQRT within tol_W / |w_k|; EIGEN within
         * 2 |E|_F / |w| (gap |w|^2 >= 2.5) */
        const double EF = sqrt(SQ(tol[6]) + SQ(tol[7]) + SQ(tol[8]) + 2 * (SQ(tol[9]) + SQ(tol[10]) + SQ(tol[11])));
        double worst = 0.0;
        int bad = 0, flagged = 0, n_sign_flips = 0, n_amb = 0, amb_ok = 1;
        for (int k = 0; k < NCR; ++k) {
            double f[3], w[3], wd[3];
            zc_motion(k * dt + 1.0, f, w, wd);
            for (int j = 0; j < 3; ++j) {
                const double e = fabs(o_w[3 * k + j] - w[j]);
                if (st.rate_model == GF_RATE_MODEL_FRAME) {
                    if (fabs(w[j]) > 1e-3) {
                        bad += e > tol[6 + j] / fabs(w[j]) + 4 * EPS * fabs(w[j]);
                        worst = fmax(worst, e / (tol[6 + j] / fabs(w[j])));
                    }
                } else {
                    bad += e > 2.0 * EF / norm3(w) + 64 * EPS * norm3(w);
                    worst = fmax(worst, e / (2.0 * EF / norm3(w)));
                }
            }
            flagged += (o_fl[k] & ~GF_RATE_FLAG_AMBIGUOUS) != 0;
            /* ambiguous (a mirror image within the resolution): only where a component is
             * within 2.5 sqrt(sigma_W) of zero, sigma_W = sigma sqrt6 / (4 l) (seed 000 eq. 4,
             * sigma the configured 1e-4 m/s^2), plus the noise-free round-off */
            const double amb = 2.5 * sqrt(cfg.accel_noise_m_s2 * sqrt(6.0) / (4.0 * 0.1)) * (1 + 1e-9);
            if (o_fl[k] & GF_RATE_FLAG_AMBIGUOUS) {
                ++n_amb;
                amb_ok &= st.rate_model == GF_RATE_MODEL_FRAME &&
                          (fabs(w[0]) < amb || fabs(w[1]) < amb || fabs(w[2]) < amb);
            }
            n_sign_flips += k > 0 && (o_w[3 * k] > 0) != (o_w[3 * k - 3] > 0);
        }
        printf("zero crossing %-9s: max error %.3g of the tolerance, %d flagged samples, %d ambiguous, "
               "%d sign change(s) of w_x\n", cases[c].name, worst, flagged, n_amb, n_sign_flips);
        CHECK(amb_ok, "%s: ambiguous samples only where a component is within the resolution of 0", cases[c].name);
        /* qin9: |w_x| < 0.0619 rad/s for ~0.31 s around the crossing at 0.4 rad/s^2: ~31 samples */
        CHECK(st.rate_model != GF_RATE_MODEL_FRAME || (n_amb >= 25 && n_amb <= 35), "%s: %d ambiguous samples",
              cases[c].name, n_amb);
        CHECK(bad == 0, "%s: rate through the zero crossing of w_x (%d components off, %.3g of tol)", cases[c].name,
              bad, worst);
        CHECK(n_sign_flips == 1, "%s: w_x changes sign once (%d)", cases[c].name, n_sign_flips);
        /* w_x^2 ~ 0 near the crossing may round below zero: a handful of flags */
        CHECK(flagged <= 10, "%s: at most a few flagged samples (%d)", cases[c].name, flagged);
    }
}

/* FUSED against an EKF written here: state [w, b], w_dot_true = w_dot - b;
 *   predict  w += dt (w_dot_(k-1) + w_dot_k)/2 - dt b,  F = [[I, -dt I], [0, I]],
 *            Q = diag(dt^2 Cov(w_dot), q_b^2 dt I)
 *   update   z = measured products (3 or 6), h = products of w, H = dh/dw,
 *            R = sigma^2 (H_a^T H_a)^-1 on the product block,
 * with the measured w_dot and products the least-squares solution (H_a^T H_a)^-1 H_a^T A
 * computed here, on outputs perturbed by a deterministic "noise" of 1e-3 m/s^2. */
static void test_rate_fused_model(void)
{
    const double dt = 0.01, zero3[3] = {0, 0, 0};
    for (int id = 1; id <= 2; ++id) {
        layout L;
        make_layout(id, &L);
        gf_array_geometry g;
        to_geometry(&L, &g);
        static double H[GF_ARRAY_MAX_SENSORS][GF_X_N];
        ref_model(&L, H);
        const int m = id == 1 ? 3 : 6, k_est = 6 + m;
        /* inverse of H_a^T H_a over the estimated columns 0 .. k_est-1 */
        double G[GF_X_N * GF_X_N] = {0}, ev[GF_X_N] = {0}, V[GF_X_N * GF_X_N] = {0}, Gi[GF_X_N * GF_X_N] = {0};
        for (int a = 0; a < k_est; ++a)
            for (int b = 0; b < k_est; ++b) {
                double acc = 0.0;
                for (size_t i = 0; i < L.n; ++i)
                    acc += H[i][a] * H[i][b];
                G[a * k_est + b] = acc;
            }
        ref_sym_eig((size_t)k_est, G, ev, V);
        for (int a = 0; a < k_est; ++a)
            for (int b = 0; b < k_est; ++b) {
                double acc = 0.0;
                for (int c2 = 0; c2 < k_est; ++c2)
                    acc += V[a * k_est + c2] * V[b * k_est + c2] / ev[c2];
                Gi[a * k_est + b] = acc;
            }
        gf_rate_config cfg = rate_cfg(GF_RATE_FUSED);
        cfg.accel_noise_m_s2 = 1e-3;
        cfg.bias_walk_rad_s2_sqrt_s = 1e-3;
        const double s2 = SQ(cfg.accel_noise_m_s2);
        const double w_init[3] = {0.61, -0.48, 0.93};
        gf_gfins_state st;
        CHECK(gf_gfins_init(&st, &g, &cfg, w_init, NULL) == GF_OK, "fused model init");
        double x[6] = {w_init[0], w_init[1], w_init[2], 0, 0, 0}, P[36] = {0};
        for (int i = 0; i < 3; ++i) {
            P[7 * i] = SQ(cfg.init_std_rad_s);
            P[7 * (i + 3)] = SQ(cfg.init_bias_std_rad_s2);
        }
        double R[36];
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b)
                R[a * m + b] = s2 * Gi[(6 + a) * k_est + 6 + b];
        double wd_prev[3] = {0, 0, 0}, wd_prev2[3] = {0, 0, 0}, worst = 0.0, worst_out = 0.0;
        test_rng rng = {(uint64_t)(900 + id)};
        for (int k = 0; k < 50; ++k) {
            double f[3], A[GF_ARRAY_MAX_SENSORS];
            cr_force(k * dt, f);
            outputs(&L, f, kW, zero3, A);
            for (size_t i = 0; i < L.n; ++i)
                A[i] += test_rng_uniform(&rng, -1e-3, 1e-3);
            double xo[3], wo[3], wdo[3], Wo[6];
            uint8_t fl;
            CHECK(gf_gfins_step(&st, A, dt, xo, wo, wdo, Wo, &fl) == GF_OK, "fused model step %d", k);
            /* reference: least-squares solution */
            double xl[GF_X_N] = {0};
            for (int a = 0; a < k_est; ++a) {
                double acc = 0.0;
                for (int b = 0; b < k_est; ++b) {
                    double hty = 0.0;
                    for (size_t i = 0; i < L.n; ++i)
                        hty += H[i][b] * A[i];
                    acc += Gi[a * k_est + b] * hty;
                }
                xl[a] = acc;
            }
            if (k > 0) {
                double F[36] = {0}, Q[36] = {0};
                for (int i = 0; i < 6; ++i)
                    F[7 * i] = 1.0;
                for (int i = 0; i < 3; ++i) {
                    F[6 * i + 3 + i] = -dt;
                    for (int j = 0; j < 3; ++j)
                        Q[6 * i + j] = dt * dt * s2 * Gi[(3 + i) * k_est + 3 + j];
                    Q[7 * (i + 3)] = SQ(cfg.bias_walk_rad_s2_sqrt_s) * dt;
                }
                /* w_dot integral: trapezoid on the first interval, then third-order
                 * Adams-Moulton T (5 w_dot_k + 8 w_dot_(k-1) - w_dot_(k-2)) / 12 */
                for (int i = 0; i < 3; ++i)
                    x[i] += (k == 1 ? 0.5 * dt * (wd_prev[i] + xl[3 + i])
                                    : dt / 12.0 * (5.0 * xl[3 + i] + 8.0 * wd_prev[i] - wd_prev2[i])) -
                            dt * x[3 + i];
                double FP[36], Pn[36];
                for (int i = 0; i < 6; ++i)
                    for (int j = 0; j < 6; ++j) {
                        double acc = 0.0;
                        for (int q = 0; q < 6; ++q)
                            acc += F[6 * i + q] * P[6 * q + j];
                        FP[6 * i + j] = acc;
                    }
                for (int i = 0; i < 6; ++i)
                    for (int j = 0; j < 6; ++j) {
                        double acc = Q[6 * i + j];
                        for (int q = 0; q < 6; ++q)
                            acc += FP[6 * i + q] * F[6 * j + q];
                        Pn[6 * i + j] = acc;
                    }
                memcpy(P, Pn, sizeof P);
            }
            for (int i = 0; i < 3; ++i) {
                wd_prev2[i] = wd_prev[i];
                wd_prev[i] = xl[3 + i];
            }
            double h[6], Hm[36] = {0}, r[6];
            products(x, h);
            Hm[0] = 2 * x[0], Hm[6 + 1] = 2 * x[1], Hm[12 + 2] = 2 * x[2];
            if (m == 6) {
                Hm[18 + 0] = x[1], Hm[18 + 1] = x[0];
                Hm[24 + 0] = x[2], Hm[24 + 2] = x[0];
                Hm[30 + 1] = x[2], Hm[30 + 2] = x[1];
            }
            for (int i = 0; i < m; ++i)
                r[i] = xl[6 + i] - h[i];
            ref_kalman_update(6, (size_t)m, x, P, r, Hm, R);
            double pmax = 0.0, dp = 0.0, dx = 0.0;
            for (int i = 0; i < 36; ++i) {
                pmax = fmax(pmax, fabs(P[i]));
                dp = fmax(dp, fabs(P[i] - st.kf.P[i]));
            }
            for (int i = 0; i < 6; ++i)
                dx = fmax(dx, fabs(x[i] - st.kf.x[i]));
            worst = fmax(worst, fmax(dp / pmax, dx));
            for (int i = 0; i < 3; ++i)
                worst_out = fmax(worst_out, fabs(wo[i] - st.kf.x[i]));
            /* keep the reference on the engine's state: differences do not accumulate */
            memcpy(x, st.kf.x, sizeof x);
            memcpy(P, st.kf.P, sizeof P);
        }
        /* two solutions of the same least-squares problem (cond <= 45), P's of size
         * 1e-7: agreement to ~1e-12 relative; allowed 1e-9 */
        printf("FUSED %-8s vs the EKF written here (50 noisy samples): max difference %.3g (x abs, P rel)\n", L.name,
               worst);
        CHECK(worst <= 1e-9, "FUSED %s = reference EKF (%.3g)", L.name, worst);
        CHECK(worst_out == 0.0, "FUSED %s: output w = the filter's w", L.name);
    }
}

/* FUSED from a wrong initial rate: the EKF on the measured products pulls it in. */
static void test_rate_fused_convergence(void)
{
    const double dt = 0.01, zero[3] = {0, 0, 0};
    for (int id = 1; id <= 2; ++id) {
        layout L;
        make_layout(id, &L);
        gf_array_geometry g;
        to_geometry(&L, &g);
        for (int k = 0; k < NCR; ++k) {
            double f[3];
            cr_force(k * dt, f);
            outputs(&L, f, kW, zero, cr_A + L.n * (size_t)k);
        }
        const gf_rate_config cfg = rate_cfg(GF_RATE_FUSED);
        const double w0[3] = {kW[0] + 0.02, kW[1] - 0.015, kW[2] + 0.01}; /* 2-3 sigma of init_std */
        gf_gfins_state st;
        CHECK(gf_gfins_init(&st, &g, &cfg, w0, NULL) == GF_OK, "fused init");
        size_t done = 0;
        CHECK(gf_gfins_run(&st, NCR, cr_A, dt, o_f, o_w, o_wd, o_W, o_fl, &done) == GF_OK, "fused run");
        /* The first update is a Gauss-Newton step on W_kk = w_k^2: it leaves
         * e1 = max_k e0_k^2 / (2 |w_k|) (2.9e-4 rad/s here). The filter then weighs that
         * estimate as one more measurement and averages it down like 1/N (its
         * measurement noise is 1e-4 m/s^2 while the products here are exact); the
         * w_dot bias state lets it overshoot once: measured N e(N) <= 1.75 e1.
         * Allowed: e(N) <= 4 e1 / N at every sample. */
        double e1 = 0.0;
        for (int j = 0; j < 3; ++j)
            e1 = fmax(e1, SQ(w0[j] - kW[j]) / (2.0 * fabs(kW[j])));
        double worst = 0.0, e10 = 0.0, elast = 0.0;
        for (int k = 1; k < NCR; ++k) {
            double e = 0.0;
            for (int j = 0; j < 3; ++j)
                e = fmax(e, fabs(o_w[3 * k + j] - kW[j]));
            worst = fmax(worst, e * k / e1);
            if (k == 10)
                e10 = e;
            elast = e;
        }
        printf("FUSED %-8s from a 0.02 rad/s error: %.3g rad/s after 10 samples, %.3g after %d; max N e(N) = %.3g e1\n",
               L.name, e10, elast, NCR, worst);
        CHECK(worst <= 4.0, "FUSED %s: error <= 4 e1 / N (max N e(N) = %.3g e1)", L.name, worst);
        CHECK(elast <= 1e-6, "FUSED %s: error after %d samples %.3g rad/s", L.name, NCR, elast);
    }
}

/* NaN sample, dt errors, state unchanged on error; interleaved instances. */
static void test_rate_errors_and_instances(void)
{
    const double dt = 0.01, zero[3] = {0, 0, 0};
    layout L9, L12;
    make_layout(1, &L9);
    make_layout(2, &L12);
    gf_array_geometry g9, g12;
    to_geometry(&L9, &g9);
    to_geometry(&L12, &g12);
    enum { M = 60, BAD = 23 };
    static double A9[M * 9], A12[M * 12];
    for (int k = 0; k < M; ++k) {
        double f[3], w[3] = {0.3 + 0.01 * k, -0.6, 0.4 - 0.005 * k}, wd[3] = {1.0, 0.0, -0.5};
        cr_force(k * dt, f);
        outputs(&L9, f, w, wd, A9 + 9 * k);
        outputs(&L12, f, w, zero, A12 + 12 * k);
    }
    const double a_bad = A9[9 * BAD + 4];
    for (int strategy = 0; strategy <= 3; ++strategy) {
        if (strategy == GF_RATE_EIGEN)
            continue;
        const gf_rate_config cfg = rate_cfg(strategy);
        const double w0[3] = {0.3, -0.6, 0.4};
        gf_gfins_state a, ref;
        gf_gfins_init(&a, &g9, &cfg, w0, NULL);
        ref = a;
        A9[9 * BAD + 4] = NAN;
        size_t done = 99;
        CHECK(gf_gfins_run(&a, M, A9, dt, o_f, o_w, o_wd, NULL, o_fl, &done) == GF_ERR_NONFINITE_INPUT && done == BAD,
              "strategy %d: NaN in sample %d reported (n_done %zu)", strategy, BAD, done);
        size_t done2 = 0;
        static double rf[M * 3], rw[M * 3], rwd[M * 3];
        static uint8_t rfl[M];
        CHECK(gf_gfins_run(&ref, BAD, A9, dt, rf, rw, rwd, NULL, rfl, &done2) == GF_OK && done2 == BAD,
              "strategy %d: reference run of the good samples", strategy);
        CHECK(rate_same(&a, &ref), "strategy %d: state after the error = state after sample %d", strategy, BAD - 1);
        CHECK(memcmp(rw, o_w, BAD * 3 * sizeof(double)) == 0 && memcmp(rf, o_f, BAD * 3 * sizeof(double)) == 0,
              "strategy %d: rows before the error valid", strategy);
        gf_gfins_state before = a;
        double f[3] = {7, 7, 7}, w[3] = {7, 7, 7};
        CHECK(gf_gfins_step(&a, A9 + 9 * BAD, dt, f, w, NULL, NULL, NULL) == GF_ERR_NONFINITE_INPUT,
              "strategy %d: step NaN", strategy);
        CHECK(rate_same(&a, &before) && f[0] == 7 && w[0] == 7, "strategy %d: step error leaves state, outputs",
              strategy);
        A9[9 * BAD + 4] = INFINITY;
        CHECK(gf_gfins_step(&a, A9 + 9 * BAD, dt, f, w, NULL, NULL, NULL) == GF_ERR_NONFINITE_INPUT &&
                  rate_same(&a, &before),
              "strategy %d: step Inf, unchanged", strategy);
        A9[9 * BAD + 4] = a_bad;
        CHECK(gf_gfins_step(&a, A9, 0.0, f, w, NULL, NULL, NULL) == GF_ERR_BAD_TIME && rate_same(&a, &before),
              "strategy %d: dt = 0 after the first sample -> bad time, unchanged", strategy);
        CHECK(gf_gfins_step(&a, A9, NAN, f, w, NULL, NULL, NULL) == GF_ERR_BAD_TIME && rate_same(&a, &before),
              "strategy %d: dt NaN -> bad time", strategy);
        CHECK(gf_gfins_run(&a, 3, A9, -dt, o_f, o_w, o_wd, NULL, o_fl, &done) == GF_ERR_BAD_TIME && done == 0 &&
                  rate_same(&a, &before),
              "strategy %d: run dt < 0", strategy);
        CHECK(gf_gfins_run(&a, 3, A9, dt, o_f, NULL, o_wd, NULL, o_fl, &done) == GF_ERR_NULL_POINTER && done == 0,
              "strategy %d: run NULL output", strategy);
    }
    /* the first sample's dt is ignored */
    {
        const gf_rate_config cfg = rate_cfg(GF_RATE_SQRT);
        gf_gfins_state a;
        gf_gfins_init(&a, &g9, &cfg, NULL, NULL);
        CHECK(gf_gfins_step(&a, A9, 0.0, NULL, NULL, NULL, NULL, NULL) == GF_OK && a.n_samples == 1,
              "first sample: dt ignored");
        CHECK(gf_gfins_step(NULL, A9, dt, NULL, NULL, NULL, NULL, NULL) == GF_ERR_NULL_POINTER &&
                  gf_gfins_step(&a, NULL, dt, NULL, NULL, NULL, NULL, NULL) == GF_ERR_NULL_POINTER,
              "step NULLs");
    }
    /* two interleaved instances (qin9 SQRT, layout12 FUSED) = separate runs */
    {
        const gf_rate_config c1 = rate_cfg(GF_RATE_SQRT), c2 = rate_cfg(GF_RATE_FUSED);
        const double w0[3] = {0.3, -0.6, 0.4};
        gf_gfins_state a, b, a1, b1;
        gf_gfins_init(&a, &g9, &c1, w0, NULL);
        gf_gfins_init(&b, &g12, &c2, w0, NULL);
        a1 = a;
        b1 = b;
        int ok = 1;
        for (int k = 0; k < M; ++k) {
            ok &= gf_gfins_step(&a, A9 + 9 * k, dt, NULL, NULL, NULL, NULL, NULL) == GF_OK;
            ok &= gf_gfins_step(&b, A12 + 12 * k, dt, NULL, NULL, NULL, NULL, NULL) == GF_OK;
        }
        size_t d;
        ok &= gf_gfins_run(&a1, M, A9, dt, o_f, o_w, o_wd, NULL, o_fl, &d) == GF_OK;
        ok &= gf_gfins_run(&b1, M, A12, dt, o_f, o_w, o_wd, o_W, o_fl, &d) == GF_OK;
        CHECK(ok, "interleaved: all steps succeed");
        CHECK(rate_same(&a, &a1) && rate_same(&b, &b1), "two interleaved states = separate runs");
    }
}

/* Negative products under a perturbation: flagged, rate from the integrated reference. */
static void test_rate_flags(void)
{
    const double l = 0.1;
    layout L;
    layout_qin9(l, &L);
    gf_array_geometry g;
    to_geometry(&L, &g);
    const double F[3] = {0.2, -0.1, 9.8}, W[3] = {0.0, 0.8, -1.1}, WD[3] = {0, 0, 0};
    double A[GF_ARRAY_MAX_SENSORS];
    outputs(&L, F, W, WD, A);
    /* -1e-4 on A1 and A4: W11 = (A1 - A2 - A3 + A4 - A5 - A6)/(4l) = -5e-4 */
    A[0] -= 1e-4;
    A[3] -= 1e-4;
    const gf_rate_config cs = rate_cfg(GF_RATE_SQRT);
    const double w0[3] = {0.01, 0.8, -1.1};
    gf_gfins_state st;
    gf_gfins_init(&st, &g, &cs, w0, NULL);
    double f[3], w[3], wd[3], Wp[6];
    uint8_t fl = 0;
    CHECK(gf_gfins_step(&st, A, 0.01, f, w, wd, Wp, &fl) == GF_OK, "sqrt perturbed step");
    CHECK(Wp[0] < 0 && fabs(Wp[0] + 5e-4) <= 1e-12, "W11 driven to -5e-4 (%.6g)", Wp[0]);
    CHECK(fl == GF_RATE_FLAG_NEG_X, "SQRT: NEG_X flag only (0x%x)", fl);
    CHECK(w[0] == w0[0] && isfinite(w[1]) && isfinite(w[2]), "SQRT: w_x = the reference (%g), finite", w[0]);
    uint8_t fl2 = 0;
    double w2[3], wd2[3];
    CHECK(gf_gfins_step(&st, A, 0.01, NULL, w2, wd2, NULL, &fl2) == GF_OK && fl2 == GF_RATE_FLAG_NEG_X,
          "second sample flagged too");
    CHECK_CLOSE(w2[0], w0[0] + 0.5 * 0.01 * (wd[0] + wd2[0]), 1e-17, "SQRT: reference = trapezoid of w_dot");
    /* sign unknown: reference exactly zero, W_kk > 0 */
    const double w0z[3] = {0.0, 0.8, -1.1};
    const double W2[3] = {0.3, 0.8, -1.1};
    outputs(&L, F, W2, WD, A);
    gf_gfins_init(&st, &g, &cs, w0z, NULL);
    CHECK(gf_gfins_step(&st, A, 0.01, f, w, wd, Wp, &fl) == GF_OK && fl == GF_RATE_FLAG_SIGN_UNKNOWN && w[0] > 0,
          "SQRT: zero reference -> SIGN_UNKNOWN, positive (0x%x, %g)", fl, w[0]);

    /* EIGEN: layout 12 at rest with W perturbed to diag(-1, -2, -3) 1e-4: lambda_max < 0 */
    layout_twelve(l, &L);
    to_geometry(&L, &g);
    static double H[GF_ARRAY_MAX_SENSORS][GF_X_N];
    ref_model(&L, H);
    const double zero[3] = {0, 0, 0};
    outputs(&L, F, zero, zero, A);
    for (size_t i = 0; i < L.n; ++i)
        A[i] += -1e-4 * H[i][6] - 2e-4 * H[i][7] - 3e-4 * H[i][8];
    const gf_rate_config ce = rate_cfg(GF_RATE_EIGEN);
    const double wi[3] = {0.001, -0.002, 0.003};
    gf_gfins_init(&st, &g, &ce, wi, NULL);
    CHECK(gf_gfins_step(&st, A, 0.01, f, w, wd, Wp, &fl) == GF_OK, "eigen perturbed step");
    CHECK(fl == GF_RATE_FLAG_NEG_X, "EIGEN: lambda_max < 0 flagged (0x%x; W %g %g %g)", fl, Wp[0], Wp[1], Wp[2]);
    CHECK(w[0] == wi[0] && w[1] == wi[1] && w[2] == wi[2], "EIGEN: rate = the reference");
    CHECK(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]), "EIGEN: finite f");
    /* SQRT on qin9: w_z = 0 and W33 perturbed by -2e-4: NEG_Z, and ambiguous (w_z at 0) */
    layout_qin9(l, &L);
    to_geometry(&L, &g);
    ref_model(&L, H);
    const double W3[3] = {0.5, 0.8, 0.0};
    outputs(&L, F, W3, WD, A);
    for (size_t i = 0; i < L.n; ++i)
        A[i] += -2e-4 * H[i][8];
    const double w0b[3] = {0.5, 0.8, 0.01};
    gf_gfins_init(&st, &g, &cs, w0b, NULL);
    CHECK(gf_gfins_step(&st, A, 0.01, f, w, wd, Wp, &fl) == GF_OK, "sqrt qin9 step");
    CHECK(fabs(Wp[2] + 2e-4) <= 1e-12, "qin9: W33 = -2e-4 (%.6g)", Wp[2]);
    CHECK(fl == GF_RATE_FLAG_NEG_Z && w[2] == w0b[2] && isfinite(w[0]) && isfinite(w[1]),
          "SQRT qin9: NEG_Z flagged only, w_z = reference (0x%x)", fl);
}

/* ======================================================================================
 * Navigator
 * ==================================================================================== */

static int nav_same(const gf_sins_state *a, const gf_sins_state *b)
{
    return SAME_FIELD(a, b, cfg.input) && SAME_FIELD(a, b, cfg.coning) && SAME_FIELD(a, b, cfg.vertical) &&
           SAME_FIELD(a, b, cfg.earth) && SAME_FIELD(a, b, cfg.flat_gravity_m_s2) &&
           SAME_FIELD(a, b, cfg.hold_height_m) && SAME_FIELD(a, b, cfg.baro_tau_s) &&
           SAME_FIELD(a, b, cfg.max_rate_rad_s) && SAME_FIELD(a, b, cfg.max_specific_force_m_s2) &&
           SAME_FIELD(a, b, flat_pos_m) && SAME_FIELD(a, b, q_bn) && SAME_FIELD(a, b, v_n_m_s) && SAME_FIELD(a, b, lat_rad) &&
           SAME_FIELD(a, b, lon_rad) && SAME_FIELD(a, b, h_m) && SAME_FIELD(a, b, time_s) &&
           SAME_FIELD(a, b, earth_rate_sign) && SAME_FIELD(a, b, a_n_m_s2) && SAME_FIELD(a, b, prev_gyro) &&
           SAME_FIELD(a, b, prev_accel) && SAME_FIELD(a, b, have_prev) && SAME_FIELD(a, b, baro_accel_m_s2) &&
           SAME_FIELD(a, b, sin_lat) && SAME_FIELD(a, b, cos_lat) && SAME_FIELD(a, b, R_M_m) &&
           SAME_FIELD(a, b, n_samples);
}

static int gfnav_same(const gf_gfnav_state *a, const gf_gfnav_state *b)
{
    return rate_same(&a->rate, &b->rate) && nav_same(&a->nav, &b->nav);
}

enum { NAV_CHUNK = 6000 };
static double nv_A[NAV_CHUNK * 9], nv_q[NAV_CHUNK * 4], nv_v[NAV_CHUNK * 3], nv_p[NAV_CHUNK * 3];
static double nv_w[NAV_CHUNK * 3], nv_f[NAV_CHUNK * 3];
static uint8_t nv_fl[NAV_CHUNK];

static void test_gfnav(void)
{
    const double l = 0.1, T = 0.01, t0 = 100.0;
    const double L = 45.0 * DEG, lon = 10.0 * DEG, h = 100.0;
    /* an attitude that spreads the Earth rate over the three body axes (|w_k| >= 4.1e-5
     * rad/s): SQRT's error dW / (2 |w_k|) grows as a component approaches zero */
    const double e[3] = {70.0 * DEG, 30.0 * DEG, -10.0 * DEG};
    double C[3][3], q_true[4];
    ref_dcm_euler(e, C);
    ref_quat_euler(e, q_true);
    const double w_n[3] = {0.0, REF_W_IE * cos(L), REF_W_IE * sin(L)};
    const double f_n[3] = {0.0, 0.0, ref_gravity(L, h)};
    double w_b[3], f_b[3];
    for (int i = 0; i < 3; ++i) { /* C_n^b = (C_b^n)^T */
        w_b[i] = C[0][i] * w_n[0] + C[1][i] * w_n[1] + C[2][i] * w_n[2];
        f_b[i] = C[0][i] * f_n[0] + C[1][i] * f_n[1] + C[2][i] * f_n[2];
    }
    layout Lq;
    layout_qin9(l, &Lq);
    gf_array_geometry g;
    to_geometry(&Lq, &g);
    const double zero[3] = {0, 0, 0};
    double A1[9];
    outputs(&Lq, f_b, w_b, zero, A1);
    for (int k = 0; k < NAV_CHUNK; ++k)
        memcpy(nv_A + 9 * k, A1, sizeof A1);

    gf_sins_config sc;
    gf_sins_config_default(&sc);
    gf_rate_config rc = rate_cfg(GF_RATE_SQRT);
    gf_gfnav_state nav;
    const double v0[3] = {0, 0, 0};
    sc.input = GF_SINS_INPUT_INCREMENTS;
    CHECK(gf_gfnav_init(&nav, &g, &rc, w_b, &sc, q_true, v0, L, lon, h, t0, NULL) == GF_ERR_BAD_PARAMETER,
          "gfnav: increments input refused");
    CHECK(gf_gfnav_init(NULL, &g, &rc, w_b, &sc, q_true, v0, L, lon, h, t0, NULL) == GF_ERR_NULL_POINTER &&
              gf_gfnav_init(&nav, &g, &rc, w_b, NULL, q_true, v0, L, lon, h, t0, NULL) == GF_ERR_NULL_POINTER,
          "gfnav init NULLs");
    sc.input = GF_SINS_INPUT_RATES;
    sc.vertical = GF_SINS_VERTICAL_HOLD;
    sc.hold_height_m = h;
    gf_array_geometry c6;
    gf_layout_cube6(l, &c6);
    CHECK(gf_gfnav_init(&nav, &c6, &rc, w_b, &sc, q_true, v0, L, lon, h, t0, NULL) == GF_ERR_BAD_PARAMETER,
          "gfnav: SQRT on cube6 refused");
    CHECK(gf_gfnav_init(&nav, &g, &rc, w_b, &sc, q_true, v0, 2.0, lon, h, t0, NULL) == GF_ERR_BAD_PARAMETER,
          "gfnav: sins errors passed on (|lat| > 90 deg)");
    CHECK(gf_gfnav_init(&nav, &g, &rc, w_b, &sc, q_true, v0, L, lon, h, t0, NULL) == GF_OK, "gfnav init");
    const gf_gfnav_state nav0 = nav;
    {   /* found by fuzzing: a refused strapdown start left a new rate solver beside the old
         * navigation state; now an error changes nothing */
        static gf_gfnav_state c;
        memcpy(&c, &nav, sizeof c);
        gf_rate_config rc2 = rate_cfg(GF_RATE_FUSED);
        CHECK(gf_gfnav_init(&c, &g, &rc2, w_b, &sc, q_true, v0, 2.0, lon, h, t0, NULL) == GF_ERR_BAD_PARAMETER &&
                  memcmp(&c, &nav, sizeof c) == 0,
              "gfnav: a refused start leaves the state as it was");
    }

    /* 600 s at 100 Hz (the first sample starts the rate record) */
    const size_t n_total = 60001;
    double max_att = 0, max_v = 0, max_lat = 0, max_lon = 0, max_w = 0, max_f = 0;
    int ok = 1, flagged = 0;
    for (size_t k0 = 0; k0 < n_total; k0 += NAV_CHUNK) {
        const size_t m = n_total - k0 < NAV_CHUNK ? n_total - k0 : NAV_CHUNK;
        size_t done = 0;
        ok &= gf_gfnav_run(&nav, m, nv_A, T, NULL, nv_q, nv_v, nv_p, nv_w, nv_f, nv_fl, &done) == GF_OK && done == m;
        for (size_t j = 0; j < m; ++j) {
            max_att = fmax(max_att, quat_angle(nv_q + 4 * j, q_true));
            max_v = fmax(max_v, norm3(nv_v + 3 * j));
            max_lat = fmax(max_lat, fabs(nv_p[3 * j] - L));
            max_lon = fmax(max_lon, fabs(nv_p[3 * j + 1] - lon));
            for (int i = 0; i < 3; ++i) {
                max_w = fmax(max_w, fabs(nv_w[3 * j + i] - w_b[i]));
                max_f = fmax(max_f, fabs(nv_f[3 * j + i] - f_b[i]));
            }
            flagged |= nv_fl[j];
        }
    }
    printf("gfnav stationary qin9 + SQRT, 600 s: rate error %.3g rad/s, f error %.3g m/s^2, attitude %.3g rad, "
           "|v| %.3g m/s, |dlat| %.3g rad, |dlon| %.3g rad\n",
           max_w, max_f, max_att, max_v, max_lat, max_lon);
    CHECK(ok, "gfnav: 600 s run");
    CHECK(nav.rate.n_samples == n_total && nav.nav.n_samples == n_total, "gfnav: samples counted");
    /* the Earth rate's components (<= 7.3e-5 rad/s) lie far inside the resolution of the
     * squared rates (0.06 rad/s at the default 1e-4 m/s^2): every sample is ambiguous and
     * takes its signs from the w_dot integral from omega_init; nothing else is flagged */
    CHECK(flagged == GF_RATE_FLAG_AMBIGUOUS, "gfnav: ambiguous flags only (0x%x)", flagged);
    /* The outputs are constant, so every solved quantity carries one fixed round-off
     * error. f: within 8 eps g_f sqrt(N) g (g_f = 1/sqrt2, ls_tolerance's first term).
     * W_kk ~ 1e-9 rad^2/s^2 sits on outputs of size g: its error is round-off of g
     * times the gain sqrt6/(4l); with the measured constant of the solver tests
     * (<= 1.5 eps g_j sqrt(N) S, 4 allowed), dW <= 4 eps sqrt6/(4l) 3 g = 1.6e-13 and
     * |dw_k| <= dW / (2 |w_k|), |w_k| >= 4.1e-5 rad/s here (printed): 2e-9 rad/s. */
    double wmin = 1.0;
    for (int i = 0; i < 3; ++i)
        wmin = fmin(wmin, fabs(w_b[i]));
    const double dW = 4.0 * EPS * sqrt(6.0) / (4.0 * l) * 3.0 * f_n[2];
    const double tol_w = dW / (2.0 * wmin);
    printf("gfnav: body rate |w_k| >= %.3g rad/s, rate bound %.3g rad/s\n", wmin, tol_w);
    CHECK(max_w <= tol_w, "gfnav: rate error %.3g rad/s (bound %.3g)", max_w, tol_w);
    CHECK(max_f <= 8.0 * EPS * sqrt(0.5) * 3.0 * f_n[2], "gfnav: specific force error %.3g m/s^2", max_f);
    /* A constant rate error b (|b| <= sqrt3 max_w, the error actually fed to the
     * strapdown) acts as a gyro bias over t = 600 s: attitude b t (Earth-rate coupling
     * W t = 0.04 changes it by a few %), Schuler-bounded velocity R b (1 - cos w_s t)
     * and position R b (t - sin(w_s t)/w_s), w_s = sqrt(g/R); longitude in radians
     * divided by cos L. Allowed: 1.25 x the attitude, 2 x the velocity and position
     * (the tilt's projection and the azimuth coupling are not in the single-axis
     * closed forms). The rate path itself is bounded above; this checks that the
     * navigator adds no error of its own. */
    {
        const double t = (double)(n_total - 1) * T, b = sqrt(3.0) * max_w;
        const double ws = sqrt(f_n[2] / REF_A);
        const double att_b = 1.25 * b * t;
        const double v_b = 2.0 * REF_A * b * (1.0 - cos(ws * t));
        const double p_b = 2.0 * b * (t - sin(ws * t) / ws);
        printf("gfnav bounds from the rate error: attitude %.3g rad, |v| %.3g m/s, lat %.3g rad, lon %.3g rad\n",
               att_b, v_b, p_b, p_b / cos(L));
        CHECK(max_att <= att_b, "gfnav: attitude error %.3g rad (bound %.3g)", max_att, att_b);
        CHECK(max_v <= v_b, "gfnav: velocity error %.3g m/s (bound %.3g)", max_v, v_b);
        CHECK(max_lat <= p_b && max_lon <= p_b / cos(L), "gfnav: position error %.3g, %.3g rad (bounds %.3g, %.3g)",
              max_lat, max_lon, p_b, p_b / cos(L));
    }

    /* error in sample 17 of 40: stops there, state = after 17 good samples */
    gf_gfnav_state a = nav0, ref = nav0;
    nv_A[9 * 17 + 2] = NAN;
    size_t done = 99;
    CHECK(gf_gfnav_run(&a, 40, nv_A, T, NULL, nv_q, nv_v, nv_p, NULL, NULL, NULL, &done) == GF_ERR_NONFINITE_INPUT &&
              done == 17,
          "gfnav: NaN in sample 17 (n_done %zu)", done);
    CHECK(gf_gfnav_run(&ref, 17, nv_A, T, NULL, nv_q, nv_v, nv_p, NULL, NULL, NULL, &done) == GF_OK && done == 17,
          "gfnav: reference run");
    CHECK(gfnav_same(&a, &ref), "gfnav: state after the error = state after sample 16");
    /* an absurd sample the rate solver accepts but the strapdown refuses (|f| > 1000) */
    for (int i = 0; i < 9; ++i)
        nv_A[9 * 17 + i] = A1[i] * 1e3;
    CHECK(gf_gfnav_run(&a, 23, nv_A + 9 * 17, T, NULL, nv_q, nv_v, nv_p, NULL, NULL, NULL, &done) ==
                  GF_ERR_OUT_OF_RANGE &&
              done == 0,
          "gfnav: out-of-range specific force stops at once (n_done %zu)", done);
    CHECK(gfnav_same(&a, &ref), "gfnav: strapdown error leaves the rate solver untouched too");
    memcpy(nv_A + 9 * 17, A1, sizeof A1);
    CHECK(gf_gfnav_run(&a, 5, nv_A, 0.0, NULL, nv_q, nv_v, nv_p, NULL, NULL, NULL, &done) == GF_ERR_BAD_TIME &&
              done == 0 && gfnav_same(&a, &ref),
          "gfnav: dt = 0");
    CHECK(gf_gfnav_run(&a, 5, nv_A, T, NULL, NULL, nv_v, nv_p, NULL, NULL, NULL, &done) == GF_ERR_NULL_POINTER,
          "gfnav: NULL output");
}

/* gf_gfnav_run works in blocks of samples (rates, then Hermite increments, then the
 * mechanization); one sample per call is the plain sequence. Both must agree bit for bit
 * on a varying motion, for the per-sample strategies and the fused one (whose w_dot
 * carries the filter's bias), and a mechanization refusal inside a block must leave
 * both states after the last good sample. */
static void test_gfnav_blocks(void)
{
    enum { NB = 100, BAD = 45 };   /* 45: inside the run's second block of 32 */
    const double l = 0.1, T = 0.01, L = 30.0 * DEG, h = 50.0;
    layout Lq;
    layout_qin9(l, &Lq);
    gf_array_geometry g;
    to_geometry(&Lq, &g);
    static double A[NB * 9], q1[NB * 4], v1[NB * 3], p1[NB * 3], w1[NB * 3], f1[NB * 3];
    static double q2[NB * 4], v2[NB * 3], p2[NB * 3], w2[NB * 3], f2[NB * 3];
    uint8_t fl1[NB], fl2[NB];
    for (int k = 0; k < NB; ++k) {   /* w = w0 + a sin(c t) per axis: w_dot = a c cos(c t) */
        const double t = k * T;
        const double w[3] = {0.8 + 0.3 * sin(2.0 * t), -0.5 + 0.2 * sin(3.0 * t), 1.1 + 0.4 * sin(1.5 * t)};
        const double wd[3] = {0.6 * cos(2.0 * t), 0.6 * cos(3.0 * t), 0.6 * cos(1.5 * t)};
        const double f[3] = {0.3 * sin(t), 0.1, 9.8};
        outputs(&Lq, f, w, wd, A + 9 * k);
    }
    const int strategies[2] = {GF_RATE_SQRT, GF_RATE_FUSED};
    for (int s = 0; s < 2; ++s) {
        gf_sins_config sc;
        gf_sins_config_default(&sc);
        sc.input = GF_SINS_INPUT_RATES;
        gf_rate_config rc = rate_cfg(strategies[s]);
        const double w0[3] = {0.8, -0.5, 1.1}, q0[4] = {1, 0, 0, 0}, v0[3] = {0, 0, 0};
        gf_gfnav_state one, many;
        CHECK(gf_gfnav_init(&one, &g, &rc, w0, &sc, q0, v0, L, 0.1, h, 0.0, NULL) == GF_OK,
              "blocks %d: init", s);
        many = one;
        size_t done = 0;
        CHECK(gf_gfnav_run(&many, NB, A, T, NULL, q1, v1, p1, w1, f1, fl1, &done) == GF_OK && done == NB,
              "blocks %d: one call", s);
        int ok = 1;
        for (int k = 0; k < NB; ++k)
            ok &= gf_gfnav_run(&one, 1, A + 9 * k, T, NULL, q2 + 4 * k, v2 + 3 * k, p2 + 3 * k,
                               w2 + 3 * k, f2 + 3 * k, fl2 + k, &done) == GF_OK;
        CHECK(ok && gfnav_same(&one, &many), "blocks %d: states equal bit for bit", s);
        CHECK(!memcmp(q1, q2, sizeof q1) && !memcmp(v1, v2, sizeof v1) && !memcmp(p1, p2, sizeof p1) &&
                  !memcmp(w1, w2, sizeof w1) && !memcmp(f1, f2, sizeof f1) && !memcmp(fl1, fl2, sizeof fl1),
              "blocks %d: outputs equal bit for bit", s);
        /* sample BAD: a specific force the rate solver takes but the mechanization refuses */
        gf_gfnav_state a, ref;
        CHECK(gf_gfnav_init(&a, &g, &rc, w0, &sc, q0, v0, L, 0.1, h, 0.0, NULL) == GF_OK, "init");
        ref = a;
        double keep[9];
        memcpy(keep, A + 9 * BAD, sizeof keep);
        for (int i = 0; i < 9; ++i)
            A[9 * BAD + i] *= 1e3;
        CHECK(gf_gfnav_run(&a, NB, A, T, NULL, q1, v1, p1, NULL, NULL, NULL, &done) == GF_ERR_OUT_OF_RANGE &&
                  done == BAD,
              "blocks %d: refusal at sample %d (n_done %zu)", s, BAD, done);
        CHECK(gf_gfnav_run(&ref, BAD, A, T, NULL, q2, v2, p2, NULL, NULL, NULL, &done) == GF_OK && done == BAD,
              "blocks %d: reference run", s);
        CHECK(gfnav_same(&a, &ref), "blocks %d: both states after the last good sample", s);
        memcpy(A + 9 * BAD, keep, sizeof keep);
    }
}

/* ---- the navigator's cubic Hermite increments ---------------------------------------- */

static void ref_qmul(const double a[4], const double b[4], double o[4])
{
    o[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    o[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    o[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    o[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/* w(t) = c0 + c1 t + c2 t^2 + c3 t^3 (rad/s) and its derivative */
static void cubic_rate(double c[4][3], double t, double w[3], double wd[3])
{
    for (int i = 0; i < 3; ++i) {
        w[i] = c[0][i] + t * (c[1][i] + t * (c[2][i] + t * c[3][i]));
        wd[i] = c[1][i] + t * (2.0 * c[2][i] + 3.0 * t * c[3][i]);
    }
}

/* dq/dt = q (x) [0, w] / 2 */
static void ref_qdot(const double q[4], const double w[3], double o[4])
{
    const double wq[4] = {0.0, w[0], w[1], w[2]};
    ref_qmul(q, wq, o);
    for (int i = 0; i < 4; ++i)
        o[i] *= 0.5;
}

/* Attitude ODE over [0, T] under the cubic rate from q(0) = 1, classic RK4 with m
 * steps: q(T). (Arrays are not const: ISO C11 cannot pass double[4][3] as const.) */
static void ref_attitude_ode(double c[4][3], double T, int m, double q[4])
{
    double dummy[3];
    q[0] = 1.0, q[1] = q[2] = q[3] = 0.0;
    const double h = T / m;
    for (int k = 0; k < m; ++k) {
        const double t = k * h;
        double w1[3], w2[3], w3[3], k1[4], k2[4], k3[4], k4[4], y[4];
        cubic_rate(c, t, w1, dummy);
        cubic_rate(c, t + 0.5 * h, w2, dummy);
        cubic_rate(c, t + h, w3, dummy);
        ref_qdot(q, w1, k1);
        for (int i = 0; i < 4; ++i) y[i] = q[i] + 0.5 * h * k1[i];
        ref_qdot(y, w2, k2);
        for (int i = 0; i < 4; ++i) y[i] = q[i] + 0.5 * h * k2[i];
        ref_qdot(y, w2, k3);
        for (int i = 0; i < 4; ++i) y[i] = q[i] + h * k3[i];
        ref_qdot(y, w3, k4);
        for (int i = 0; i < 4; ++i)
            q[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

/* rotation vector of a unit quaternion (shortest rotation) */
static void ref_rotvec(const double q[4], double v[3])
{
    const double sgn = q[0] < 0 ? -1.0 : 1.0, s = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    const double k = s > 0 ? 2.0 * atan2(s, sgn * q[0]) / s : 2.0;
    for (int i = 0; i < 3; ++i)
        v[i] = sgn * k * q[1 + i];
}

static void test_hermite_increments(void)
{
    /* 1. Rotation vector against the attitude ODE under cubic rates (|w| up to ~6 rad/s,
     * |w_dot| up to ~20 rad/s^2): the method's local error is O(T^7). RK4 with 4000
     * steps errs by ~(T/4000)^4 |w|^5 T < 1e-20 rad at T = 0.04; the comparison is then
     * limited by round-off of the ~1e3 RK4 steps (~1e-16 rad). Measured and printed: the
     * error and its ratio when T halves (expected ~2^7 = 128 until round-off). */
    test_rng r = {77};
    double worst_ratio = 1e300, worst_err_10ms = 0.0;
    for (int trial = 0; trial < 20; ++trial) {
        double c[4][3];
        random_v3(&r, -3.5, 3.5, c[0]);
        random_v3(&r, -8.0, 8.0, c[1]);
        random_v3(&r, -40.0, 40.0, c[2]);
        random_v3(&r, -150.0, 150.0, c[3]);
        double prev = 0.0;
        for (int j = 0; j < 3; ++j) {
            const double T = 0.04 / (1 << j);
            double w0[3], wd0[3], w1[3], wd1[3], phi[3], dv[3], q[4], ref[3];
            const double f0[3] = {0, 0, 0};
            cubic_rate(c, 0.0, w0, wd0);
            cubic_rate(c, T, w1, wd1);
            CHECK(gf_hermite_increments(w0, wd0, f0, w1, wd1, f0, T, phi, dv) == GF_OK, "hermite: call");
            ref_attitude_ode(c, T, 4000, q);
            ref_rotvec(q, ref);
            double e[3];
            for (int i = 0; i < 3; ++i)
                e[i] = phi[i] - ref[i];
            const double err = norm3(e);
            if (j > 0 && err > 1e-14)
                worst_ratio = fmin(worst_ratio, prev / err);
            if (j == 2)
                worst_err_10ms = fmax(worst_err_10ms, err);
            prev = err;
        }
    }
    printf("hermite increments: rotation vector vs attitude ODE at T = 10 ms: max error %.3g rad, "
           "smallest error ratio per halving of T %.1f\n", worst_err_10ms, worst_ratio);
    /* O(T^7): the ratio tends to 128; 80 leaves room for the T^8 terms at T = 40 ms */
    CHECK(worst_ratio > 80.0, "hermite: local error O(T^7) (ratio %.1f)", worst_ratio);
    CHECK(worst_err_10ms < 1e-12, "hermite: error %.3g rad at 10 ms", worst_err_10ms);

    /* 2. A rate linear in time: dtheta = T (w0 + w1)/2 and the coning T^2 w0 x w1 / 12 are
     * its exact first- and second-order Magnus terms; what remains is the third-order
     * term, a double commutator bounded by T^3 max|w|^2 |w1 - w0| / 12 (|[a,[b,c]]| <=
     * |a||b||c| over the ordered triple integral of volume T^3/6, twice, halved) */
    {
        const double w0[3] = {1.0, -2.0, 0.5}, w1[3] = {1.3, -1.6, 0.9}, T = 0.01, f[3] = {0, 0, 0};
        double wd[3], phi[3], dv[3], lin[3], cx[3], dw[3];
        for (int i = 0; i < 3; ++i) {
            wd[i] = (w1[i] - w0[i]) / T;
            dw[i] = w1[i] - w0[i];
        }
        CHECK(gf_hermite_increments(w0, wd, f, w1, wd, f, T, phi, dv) == GF_OK, "hermite: linear rate");
        cross3(w0, w1, cx);
        for (int i = 0; i < 3; ++i)
            lin[i] = phi[i] - (0.5 * T * (w0[i] + w1[i]) + T * T / 12.0 * cx[i]);
        const double bound = T * T * T * fmax(dot3(w0, w0), dot3(w1, w1)) * norm3(dw) / 12.0;
        printf("hermite: linear rate, difference from the two-sample formula %.3g rad (third-order bound %.3g)\n",
               norm3(lin), bound);
        CHECK(norm3(lin) <= bound, "hermite: linear rate = two-sample coning to third order (%.3g)", norm3(lin));
    }

    /* 3. Velocity increment: a specific force constant in a non-rotating frame, h, seen by
     * a body turning at a constant rate w: f(t) = exp(-[w x] t) h. The increment in the
     * start frame is exactly T h whatever w (the trapezoid of a constant) */
    {
        const double w[3] = {2.0, 2.0, 2.0}, zero[3] = {0, 0, 0}, h[3] = {1.0, -2.0, 9.8}, T = 0.01;
        double phi[3], dv[3], f1[3], q[4], qc[4], tmp[4], hq[4] = {0, h[0], h[1], h[2]};
        const double phi_T[3] = {w[0] * T, w[1] * T, w[2] * T};
        const double a = norm3(phi_T);
        q[0] = cos(0.5 * a);
        for (int i = 0; i < 3; ++i)
            q[1 + i] = sin(0.5 * a) * phi_T[i] / a;
        qc[0] = q[0], qc[1] = -q[1], qc[2] = -q[2], qc[3] = -q[3];
        ref_qmul(qc, hq, tmp);           /* f1 = R(T)^T h = q* h q */
        ref_qmul(tmp, q, hq);
        f1[0] = hq[1], f1[1] = hq[2], f1[2] = hq[3];
        CHECK(gf_hermite_increments(w, zero, h, w, zero, f1, T, phi, dv) == GF_OK, "hermite: spinning body");
        double e[3] = {dv[0] - T * h[0], dv[1] - T * h[1], dv[2] - T * h[2]};
        double ep[3] = {phi[0] - phi_T[0], phi[1] - phi_T[1], phi[2] - phi_T[2]};
        printf("hermite: constant force, spinning body: dv error %.3g m/s, phi error %.3g rad\n", norm3(e),
               norm3(ep));
        CHECK(norm3(e) <= 16 * EPS * T * norm3(h), "hermite: dv of a force fixed in space (%.3g)", norm3(e));
        CHECK(norm3(ep) <= 8 * EPS * a, "hermite: constant rate: phi = w T (%.3g)", norm3(ep));
    }

    /* 4. gf_sins_step_compensated is the mechanization's own update fed with its own
     * increments: with the two-sample terms of gf_sins.h computed here, it gives the
     * state of gf_sins_step bit for bit; it refuses a record that has not started */
    {
        gf_sins_config sc;
        gf_sins_config_default(&sc);
        sc.input = GF_SINS_INPUT_RATES;
        const double q0[4] = {1, 0, 0, 0}, v0[3] = {1.0, 2.0, 0.1}, T = 0.01;
        const double w0[3] = {0.3, -0.2, 0.5}, f0[3] = {0.1, 0.2, 9.8};
        const double w1[3] = {0.35, -0.1, 0.45}, f1[3] = {0.2, 0.1, 9.7};
        gf_sins_state a, b;
        CHECK(gf_sins_init(&a, &sc, q0, v0, 0.5, 1.0, 10.0, 0.0) == GF_OK, "compensated: init");
        double phi[3], dvb[3], c1[3], c2[3], dth[3], dv[3];
        for (int i = 0; i < 3; ++i) {
            dth[i] = 0.5 * T * (w0[i] + w1[i]);
            dv[i] = 0.5 * T * (f0[i] + f1[i]);
        }
        CHECK(gf_sins_step_compensated(&a, dth, dv, w1, f1, T, NAN) == GF_ERR_BAD_PARAMETER,
              "compensated: a record that has not started is refused");
        CHECK(gf_sins_step(&a, w0, f0, T, NAN) == GF_OK, "compensated: first sample");
        b = a;
        cross3(w0, w1, c1);
        for (int i = 0; i < 3; ++i)
            phi[i] = dth[i] + T * T / 12.0 * c1[i];
        cross3(dth, dv, c1);
        double s1[3], s2[3];
        cross3(w0, f1, s1);
        cross3(f0, w1, s2);
        for (int i = 0; i < 3; ++i) {
            /* the same operation order as gf_sins.c: (a x b + c x d) scaled, then summed */
            c2[i] = (s1[i] + s2[i]) * (T * T / 12.0);
            dvb[i] = dv[i] + 0.5 * c1[i] + c2[i];
        }
        CHECK(gf_sins_step_compensated(&a, phi, dvb, w1, f1, T, NAN) == GF_OK &&
                  gf_sins_step(&b, w1, f1, T, NAN) == GF_OK,
              "compensated: step");
        CHECK(memcmp(&a, &b, sizeof a) == 0, "compensated: same state as gf_sins_step, bitwise");
        const double fast[3] = {60.0, 0.0, 0.0};
        gf_sins_state c = a;
        CHECK(gf_sins_step_compensated(&c, phi, dvb, fast, f1, T, NAN) == GF_ERR_OUT_OF_RANGE &&
                  memcmp(&c, &a, sizeof a) == 0,
              "compensated: a rate over the limit is refused, state unchanged");
        CHECK(gf_sins_step_compensated(&c, phi, dvb, w1, f1, 0.0, NAN) == GF_ERR_BAD_TIME,
              "compensated: dt = 0");
        gf_gfnav_state nav;
        CHECK(gf_gfnav_set_integration(&nav, 2) == GF_ERR_BAD_PARAMETER &&
                  gf_gfnav_set_integration(NULL, GF_GFNAV_LINEAR) == GF_ERR_NULL_POINTER,
              "gfnav: integration must be LINEAR or HERMITE");
    }

    /* 5. errors */
    {
        const double v[3] = {0, 0, 0}, bad[3] = {0, NAN, 0};
        double phi[3], dv[3];
        CHECK(gf_hermite_increments(NULL, v, v, v, v, v, 0.01, phi, dv) == GF_ERR_NULL_POINTER, "hermite: NULL");
        CHECK(gf_hermite_increments(v, v, v, v, v, v, 0.0, phi, dv) == GF_ERR_BAD_TIME, "hermite: T = 0");
        CHECK(gf_hermite_increments(v, v, v, v, bad, v, 0.01, phi, dv) == GF_ERR_NONFINITE_INPUT, "hermite: NaN");
    }
}

/* ---- any array: coplanar, rotated ------------------------------------------------------- */

/* A coplanar array (12 sensors in z = 0, random directions): by hand from the output
 * equation with u_z = 0, the outputs separate f, w_dot and three product combinations
 * (w_x^2 + w_z^2, w_y^2 + w_z^2, w_x w_y), take w_x w_z and w_y w_z exactly as w_dot_x,
 * w_dot_y (confounded), and never see w_x^2 + w_y^2 - w_z^2. Every strategy that runs on
 * it (INTEGRATE, SQRT by the Gauss-Newton fit, FUSED with the loop in F) follows a
 * smooth rate through 10 s of exact outputs; and the same array rotated gives the same
 * condition number and rotated estimates. */
static void test_coplanar_and_rotated(void)
{
    const double dt = 0.01;
    test_rng rng = {321};
    layout L;
    L.name = "coplanar12";
    L.n = 12;
    for (size_t i = 0; i < L.n; ++i) {
        random_v3(&rng, -0.2, 0.2, L.u[i]);
        L.u[i][2] = 0.0;
        random_unit(&rng, L.th[i]);
    }
    gf_array_geometry g;
    gf_array_solver s;
    CHECK(to_geometry(&L, &g) == GF_OK && gf_array_solver_init(&s, &g, NULL) == GF_OK, "coplanar solver");
    CHECK(s.n_obs == 3 && s.n_conf == 2, "coplanar: 3 observed, 2 confounded (%zu, %zu)", s.n_obs, s.n_conf);
    /* the observed subspace holds e11 + e33, e22 + e33 and e12 (orthonormal coordinates:
     * (1,0,1,0,0,0)/sqrt2, (0,1,1,0,0,0)/sqrt2, (0,0,0,1,0,0)), the confounded e13, e23 */
    const double obs[3][6] = {{R2, 0, R2, 0, 0, 0}, {0, R2, R2, 0, 0, 0}, {0, 0, 0, 1, 0, 0}};
    const double conf[2][6] = {{0, 0, 0, 0, 1, 0}, {0, 0, 0, 0, 0, 1}};
    double worst_in = 0.0;
    for (int v = 0; v < 5; ++v) {
        const double *e = v < 3 ? obs[v] : conf[v - 3];
        const size_t c0 = v < 3 ? 0 : 3, c1 = v < 3 ? 3 : 5; /* the basis columns it must lie in */
        double in = 0.0;
        for (size_t c = c0; c < c1; ++c) {
            double d = 0.0;
            for (int j = 0; j < 6; ++j)
                d += s.basis[j * 6 + c] * e[j];
            in += d * d;
        }
        worst_in = fmax(worst_in, fabs(in - 1.0));
    }
    CHECK(worst_in <= 1e-12, "coplanar: observed and confounded subspaces as derived (%.3g)", worst_in);

    /* 10 s of a smooth rate with w_z crossing zero at t = 5 s */
    enum { NC = 1001 };
    static double A[NC * 12], fo[NC * 3], wo[NC * 3], wdo[NC * 3], Wo[NC * 6];
    static uint8_t fl[NC];
    double wt[NC][3];
    for (int k = 0; k < NC; ++k) {
        const double t = k * dt;
        double f[3], w[3] = {1.2 * cos(0.4 * t), -0.8 + 0.5 * sin(0.3 * t), 0.6 * sin(0.2 * (t - 5.0))};
        const double wd[3] = {-0.48 * sin(0.4 * t), 0.15 * cos(0.3 * t), 0.12 * cos(0.2 * (t - 5.0))};
        cr_force(t, f);
        outputs(&L, f, w, wd, A + 12 * k);
        memcpy(wt[k], w, sizeof w);
    }
    const int strategies[3] = {GF_RATE_INTEGRATE, GF_RATE_SQRT, GF_RATE_FUSED};
    const char *names[3] = {"INTEGRATE", "SQRT (fit)", "FUSED"};
    /* INTEGRATE: third-order integral, error ~1e-8 over 10 s at these rates; SQRT: the
     * fit to round-off away from w_z = 0 (there it rides on the integral); FUSED: the
     * filter's lag to the integration error. Allowed 1e-6 rad/s. */
    for (int c = 0; c < 3; ++c) {
        gf_rate_config cfg = rate_cfg(strategies[c]);
        cfg.accel_noise_m_s2 = 1e-6;
        gf_gfins_state st;
        size_t done = 0;
        CHECK(gf_gfins_init(&st, &g, &cfg, wt[0], NULL) == GF_OK &&
                  gf_gfins_run(&st, NC, A, dt, fo, wo, wdo, Wo, fl, &done) == GF_OK && done == NC,
              "coplanar %s run", names[c]);
        CHECK(st.solver.n_conf == 2 && (strategies[c] != GF_RATE_SQRT || st.rate_model == GF_RATE_MODEL_FIT),
              "coplanar %s: model", names[c]);
        double ew = 0.0;
        int amb = 0;
        for (int k = 0; k < NC; ++k) {
            for (int i = 0; i < 3; ++i)
                ew = fmax(ew, fabs(wo[3 * k + i] - wt[k][i]));
            amb += (fl[k] & GF_RATE_FLAG_AMBIGUOUS) != 0;
        }
        printf("coplanar12 %-10s: max rate error %.3g rad/s over 10 s, %d ambiguous samples\n", names[c], ew, amb);
        CHECK(ew <= 1e-6, "coplanar %s: rate error %.3g", names[c], ew);
        CHECK(strategies[c] != GF_RATE_SQRT || amb > 0, "coplanar SQRT: the crossing of w_z is flagged");
    }

    /* rotated: u' = R u, theta' = R theta (R about (1, 2, 2)/3 by 0.7 rad); the outputs of
     * the body motion R m are those of m */
    double R[3][3];
    {
        const double ax[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, a = 0.7, c = cos(a), sn = sin(a);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                const double skew = (i == j) ? 0.0 : ((i + 1) % 3 == j ? -ax[3 - i - j] : ax[3 - i - j]);
                R[i][j] = c * (i == j) + (1 - c) * ax[i] * ax[j] + sn * skew;
            }
    }
    layout Lr = L;
    Lr.name = "coplanar12 rotated";
    for (size_t i = 0; i < L.n; ++i) {
        mat_vec(R, L.u[i], Lr.u[i]);
        mat_vec(R, L.th[i], Lr.th[i]);
    }
    gf_array_geometry gr;
    gf_array_solver sr;
    CHECK(to_geometry(&Lr, &gr) == GF_OK && gf_array_solver_init(&sr, &gr, NULL) == GF_OK, "rotated solver");
    CHECK(sr.n_obs == 3 && sr.n_conf == 2 && fabs(sr.cond - s.cond) <= 1e-12 * s.cond,
          "rotated: same subspaces and condition number (%.17g vs %.17g)", sr.cond, s.cond);
    double dmax = 0.0;
    for (int k = 0; k < NC; k += 50) {
        double x[GF_X_N], xr[GF_X_N], wr[3], fr_[3], wdr[3];
        CHECK(gf_array_solve(&s, A + 12 * k, wt[k], x) == GF_OK, "solve");
        mat_vec(R, wt[k], wr);
        CHECK(gf_array_solve(&sr, A + 12 * k, wr, xr) == GF_OK, "solve rotated");
        mat_vec(R, x, fr_);
        mat_vec(R, x + 3, wdr);
        for (int i = 0; i < 3; ++i)
            dmax = fmax(dmax, fmax(fabs(xr[i] - fr_[i]), fabs(xr[3 + i] - wdr[i])));
    }
    /* round-off of two pseudo-inverses: 64 eps cond |A| g, |A| <= 12 m/s^2, g <= 12 */
    printf("coplanar12 rotated: f, w_dot differ from the rotated unrotated ones by %.3g\n", dmax);
    CHECK(dmax <= 64 * EPS * s.cond * 12.0 * 12.0, "rotated: estimates rotate with the array (%.3g)", dmax);
}

/* A rate-solver state whose sizes, indices or strategy were corrupted (as a damaged FMU
 * state would hold): every entry refuses it with GF_ERR_BAD_SIZE and changes nothing,
 * instead of reading the outputs, pinv rows or x beyond their arrays. */
static void test_rate_state_corrupted(void)
{
    layout L9;
    make_layout(1, &L9);
    gf_array_geometry g9;
    to_geometry(&L9, &g9);
    gf_rate_config rc;
    gf_rate_config_default(&rc);
    rc.strategy = GF_RATE_FUSED;
    const double w0[3] = {0.3, -0.6, 0.4}, wd0[3] = {0, 0, 0};
    gf_gfins_state good;
    CHECK(gf_gfins_init(&good, &g9, &rc, w0, NULL) == GF_OK, "init fused qin9");
    static double A[2 * GF_ARRAY_MAX_SENSORS];
    double f[3];
    cr_force(0.0, f);
    outputs(&L9, f, w0, wd0, A);
    outputs(&L9, f, w0, wd0, A + 9);
    double fo[6], wo[6], wdo[6], W[12], x[GF_X_N];
    uint8_t fl[2];
    CHECK(gf_gfins_step(&good, A, 0.01, fo, wo, wdo, W, fl) == GF_OK, "a good step");
    CHECK(gf_gfins_state_check(&good) == GF_OK, "check of a good state");
    gf_sins_config sc;
    gf_sins_config_default(&sc);
    sc.input = GF_SINS_INPUT_RATES;
    const double q0[4] = {1, 0, 0, 0}, v0[3] = {0, 0, 0};
    gf_gfnav_state nav;
    CHECK(gf_gfnav_init(&nav, &g9, &rc, w0, &sc, q0, v0, 0.5, 1.0, 0.0, 0.0, NULL) == GF_OK, "gfnav init");
    const struct { const char *what; size_t off; int is_size; double value; } bad[] = {
        {"n_sensors 0", offsetof(gf_gfins_state, solver.n_sensors), 1, 0},
        {"n_sensors 65", offsetof(gf_gfins_state, solver.n_sensors), 1, GF_ARRAY_MAX_SENSORS + 1},
        {"n_sensors 1e9", offsetof(gf_gfins_state, solver.n_sensors), 1, 1e9},
        {"n_est 13", offsetof(gf_gfins_state, solver.n_est), 1, 13},
        {"n_obs 7", offsetof(gf_gfins_state, solver.n_obs), 1, 7},
        {"n_conf 4 with 3 observed", offsetof(gf_gfins_state, solver.n_conf), 1, 4},
        {"rate model FULL for 3 observed", offsetof(gf_gfins_state, rate_model), 0, GF_RATE_MODEL_FULL},
        {"strategy 4", offsetof(gf_gfins_state, cfg.strategy), 0, 4},
        {"strategy -1", offsetof(gf_gfins_state, cfg.strategy), 0, -1},
        {"n_w_meas 12", offsetof(gf_gfins_state, n_w_meas), 0, 12},
        {"kf.n 36", offsetof(gf_gfins_state, kf.n), 1, 36},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        gf_gfins_state st = good, before;
        if (bad[i].is_size) {
            const size_t v = (size_t)bad[i].value;
            memcpy((char *)&st + bad[i].off, &v, sizeof v);
        } else {
            const int32_t v = (int32_t)bad[i].value;
            memcpy((char *)&st + bad[i].off, &v, sizeof v);
        }
        before = st;
        size_t done = 99;
        CHECK(gf_gfins_step(&st, A, 0.01, fo, wo, wdo, W, fl) == GF_ERR_BAD_SIZE &&
                  memcmp(&st, &before, sizeof st) == 0,
              "%s: gf_gfins_step BAD_SIZE, state unchanged", bad[i].what);
        CHECK(gf_gfins_run(&st, 2, A, 0.01, fo, wo, wdo, W, fl, &done) == GF_ERR_BAD_SIZE && done == 0 &&
                  memcmp(&st, &before, sizeof st) == 0,
              "%s: gf_gfins_run BAD_SIZE", bad[i].what);
        CHECK(gf_gfins_state_check(&st) == GF_ERR_BAD_SIZE, "%s: gf_gfins_state_check", bad[i].what);
        gf_gfnav_state n2 = nav;
        n2.rate = st;
        double q[8], v[6], p[6];
        CHECK(gf_gfnav_run(&n2, 2, A, 0.01, NULL, q, v, p, NULL, NULL, NULL, &done) == GF_ERR_BAD_SIZE &&
                  done == 0,
              "%s: gf_gfnav_run BAD_SIZE", bad[i].what);
        if (i < 6)
            CHECK(gf_array_solve(&st.solver, A, w0, x) == GF_ERR_BAD_SIZE, "%s: gf_array_solve", bad[i].what);
    }
    /* numbers: the full check finds them (a step would report them as DIVERGED or a
     * skipped update) */
    gf_gfins_state st = good;
    st.R_W[4] = NAN;
    CHECK(gf_gfins_state_check(&st) == GF_ERR_NONFINITE_INPUT, "check: NaN in R_W");
    st = good;
    st.solver.pinv[3] = INFINITY;
    CHECK(gf_gfins_state_check(&st) == GF_ERR_NONFINITE_INPUT, "check: Inf in pinv");
    st = good;
    st.cfg.accel_noise_m_s2 = -1.0;
    CHECK(gf_gfins_state_check(&st) == GF_ERR_BAD_PARAMETER, "check: negative accel noise");
    st = good;
    st.solver.estimated = 0;
    CHECK(gf_gfins_state_check(&st) == GF_ERR_BAD_PARAMETER, "check: f and w_dot not estimated");
}

int main(void)
{
    test_svd_random();
    test_svd_known_values();
    test_svd_rank_deficient();
    test_svd_scaling();
    test_svd_errors();
    test_cholesky();
    test_sym3_eig();
    test_kalman_scalar();
    test_kalman_cv();
    test_kalman_random();
    test_kalman_errors();
    test_kalman_symmetric_inputs();
    test_solver_layouts();
    test_solver_unsolvable();
    test_rate_init();
    test_rate_constant();
    test_rate_linear_acceleration();
    test_rate_fused_convergence();
    test_rate_zero_crossing();
    test_rate_fused_model();
    test_rate_errors_and_instances();
    test_rate_flags();
    test_rate_state_corrupted();
    test_gfnav();
    test_gfnav_blocks();
    test_hermite_increments();
    test_coplanar_and_rotated();
    TEST_MAIN_END();
}
