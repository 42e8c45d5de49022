/* gf_linalg.c — see gf_linalg.h. */
#include "base/gf_linalg.h"

#include <math.h>
#include <string.h>

gf_status gf_svd(size_t m, size_t n, double *a, double *s, double *v)
{
    if (!a || !s || !v)
        return GF_ERR_NULL_POINTER;
    if (n == 0 || n > GF_LINALG_MAX_COLS || m < n || m > GF_LINALG_MAX_ROWS)
        return GF_ERR_BAD_SIZE;
    for (size_t i = 0; i < m * n; ++i)
        if (!isfinite(a[i]))
            return GF_ERR_NONFINITE_INPUT;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j)
            v[i * n + j] = (i == j) ? 1.0 : 0.0;
    /* rotate column pairs until all are orthogonal to working precision */
    for (int sweep = 0; sweep < 60; ++sweep) {
        double off = 0.0;
        for (size_t p = 0; p + 1 < n; ++p) {
            for (size_t q = p + 1; q < n; ++q) {
                double alpha = 0.0, beta = 0.0, gamma = 0.0;
                for (size_t i = 0; i < m; ++i) {
                    const double ap = a[i * n + p], aq = a[i * n + q];
                    alpha += ap * ap;
                    beta += aq * aq;
                    gamma += ap * aq;
                }
                if (gamma == 0.0)
                    continue;
                /* sqrt of each: alpha * beta overflows for entries ~1e77 */
                const double rel = fabs(gamma) / (sqrt(alpha) * sqrt(beta));
                if (rel > off)
                    off = rel;
                if (rel < 1e-15)
                    continue;
                const double zeta = (beta - alpha) / (2.0 * gamma);
                const double t = (zeta >= 0 ? 1.0 : -1.0) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                const double c = 1.0 / sqrt(1.0 + t * t), sn = c * t;
                for (size_t i = 0; i < m; ++i) {
                    const double ap = a[i * n + p], aq = a[i * n + q];
                    a[i * n + p] = c * ap - sn * aq;
                    a[i * n + q] = sn * ap + c * aq;
                }
                for (size_t i = 0; i < n; ++i) {
                    const double vp = v[i * n + p], vq = v[i * n + q];
                    v[i * n + p] = c * vp - sn * vq;
                    v[i * n + q] = sn * vp + c * vq;
                }
            }
        }
        if (off < 1e-15)
            break;
    }
    for (size_t j = 0; j < n; ++j) {
        double norm = 0.0;
        for (size_t i = 0; i < m; ++i)
            norm += a[i * n + j] * a[i * n + j];
        norm = sqrt(norm);
        s[j] = norm;
        if (norm > 0.0)
            for (size_t i = 0; i < m; ++i)
                a[i * n + j] /= norm;
    }
    /* sort descending (selection sort on columns: n <= 36) */
    for (size_t j = 0; j + 1 < n; ++j) {
        size_t best = j;
        for (size_t k = j + 1; k < n; ++k)
            if (s[k] > s[best])
                best = k;
        if (best != j) {
            const double ts = s[j];
            s[j] = s[best];
            s[best] = ts;
            for (size_t i = 0; i < m; ++i) {
                const double t = a[i * n + j];
                a[i * n + j] = a[i * n + best];
                a[i * n + best] = t;
            }
            for (size_t i = 0; i < n; ++i) {
                const double t = v[i * n + j];
                v[i * n + j] = v[i * n + best];
                v[i * n + best] = t;
            }
        }
    }
    return GF_OK;
}

gf_status gf_cholesky(size_t n, double *a)
{
    for (size_t j = 0; j < n; ++j) {
        double d = a[j * n + j];
        for (size_t k = 0; k < j; ++k)
            d -= a[j * n + k] * a[j * n + k];
        if (!(d > 0.0) || !isfinite(d))
            return GF_ERR_SINGULAR_GEOMETRY;
        d = sqrt(d);
        a[j * n + j] = d;
        for (size_t i = j + 1; i < n; ++i) {
            double x = a[i * n + j];
            for (size_t k = 0; k < j; ++k)
                x -= a[i * n + k] * a[j * n + k];
            a[i * n + j] = x / d;
        }
        for (size_t k = j + 1; k < n; ++k)
            a[j * n + k] = 0.0;
    }
    return GF_OK;
}

/* Substitution on whole rows of b (all k right-hand sides at once: contiguous, so the
 * inner loops vectorise); each entry sees the same operations in the same order as a
 * column-by-column substitution. */
void gf_cholesky_solve(size_t n, const double *l, size_t k, double *b)
{
    for (size_t i = 0; i < n; ++i) { /* L y = b */
        double *bi = b + i * k;
        for (size_t j = 0; j < i; ++j) {
            const double lij = l[i * n + j], *bj = b + j * k;
            for (size_t c = 0; c < k; ++c)
                bi[c] -= lij * bj[c];
        }
        const double d = l[i * n + i];
        for (size_t c = 0; c < k; ++c)
            bi[c] /= d;
    }
    for (size_t i = n; i-- > 0;) { /* L^T x = y */
        double *bi = b + i * k;
        for (size_t j = i + 1; j < n; ++j) {
            const double lji = l[j * n + i], *bj = b + j * k;
            for (size_t c = 0; c < k; ++c)
                bi[c] -= lji * bj[c];
        }
        const double d = l[i * n + i];
        for (size_t c = 0; c < k; ++c)
            bi[c] /= d;
    }
}

void gf_sym3_eig(const double a_in[9], double w[3], double v[9])
{
    double a[9];
    memcpy(a, a_in, sizeof a);
    for (int i = 0; i < 9; ++i)
        v[i] = (i % 4 == 0) ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double off = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
        const double diag = a[0] * a[0] + a[4] * a[4] + a[8] * a[8];
        if (off <= 1e-34 * diag || off == 0.0)
            break;
        for (int p = 0; p < 2; ++p) {
            for (int q = p + 1; q < 3; ++q) {
                const double apq = a[3 * p + q];
                if (apq == 0.0)
                    continue;
                const double theta = (a[3 * q + q] - a[3 * p + p]) / (2.0 * apq);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; ++k) { /* A <- J^T A J */
                    const double akp = a[3 * k + p], akq = a[3 * k + q];
                    a[3 * k + p] = c * akp - s * akq;
                    a[3 * k + q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double apk = a[3 * p + k], aqk = a[3 * q + k];
                    a[3 * p + k] = c * apk - s * aqk;
                    a[3 * q + k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[3 * k + p], vkq = v[3 * k + q];
                    v[3 * k + p] = c * vkp - s * vkq;
                    v[3 * k + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    w[0] = a[0];
    w[1] = a[4];
    w[2] = a[8];
    for (int j = 0; j < 2; ++j) { /* sort descending */
        int best = j;
        for (int k = j + 1; k < 3; ++k)
            if (w[k] > w[best])
                best = k;
        if (best != j) {
            const double t = w[j];
            w[j] = w[best];
            w[best] = t;
            for (int k = 0; k < 3; ++k) {
                const double tv = v[3 * k + j];
                v[3 * k + j] = v[3 * k + best];
                v[3 * k + best] = tv;
            }
        }
    }
}
