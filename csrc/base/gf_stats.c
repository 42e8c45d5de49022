/* gf_stats.c — the chi-square quantile and its normal-quantile and distribution-function
 * helpers; see gf_stats.h. */
#include "base/gf_stats.h"

#include <math.h>

#include "base/gf_math.h"

/* inverse of the standard normal distribution (Acklam's rational approximation with one
 * Newton step on erfc: relative error ~1e-15) */
static double normal_quantile(double p)
{
    static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                               -2.759285104469687e+02, 1.383577518672690e+02,
                               -3.066479806614716e+01, 2.506628277459239e+00};
    static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                               -1.556989798598866e+02, 6.680131188771972e+01,
                               -1.328068155288572e+01};
    static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                               -2.400758277161838e+00, -2.549732539343734e+00,
                               4.374664141464968e+00, 2.938163982698783e+00};
    static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                               2.445134137142996e+00, 3.754408661907416e+00};
    double x;
    if (p < 0.02425) {
        const double q = sqrt(-2.0 * log(p));
        x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    } else if (p <= 1.0 - 0.02425) {
        const double q = p - 0.5, r = q * q;
        x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
            (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
    } else {
        const double q = sqrt(-2.0 * log(1.0 - p));
        x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    }
    const double e = 0.5 * erfc(-x / sqrt(2.0)) - p;
    const double u = e * sqrt(2.0 * GF_PI) * exp(0.5 * x * x);
    return x - u / (1.0 + 0.5 * x * u);
}

/* chi-square distribution function for integer m by its closed forms:
 *   m = 2k:     1 - e^(-x/2) sum_{i<k} (x/2)^i / i!
 *   m = 2k + 1: erf(sqrt(x/2)) - e^(-x/2) sum_{i<k} (x/2)^(i+1/2) / Gamma(i + 3/2) */
static double chi2_cdf(int m, double x)
{
    const double y = 0.5 * x;
    double sum = 0.0, term;
    if (m % 2 == 0) {
        term = 1.0;
        for (int i = 0; i < m / 2; ++i) {
            sum += term;
            term *= y / (i + 1);
        }
        return 1.0 - exp(-y) * sum;
    }
    term = sqrt(y) / (0.5 * sqrt(GF_PI));            /* y^(1/2) / Gamma(3/2) */
    for (int i = 0; i < m / 2; ++i) {
        sum += term;
        term *= y / (i + 1.5);
    }
    return erf(sqrt(y)) - exp(-y) * sum;
}

gf_status gf_chi2_quantile(int32_t m, double p, double *q)
{
    if (!q)
        return GF_ERR_NULL_POINTER;
    if (m < 1 || m > GF_CHI2_MAX_DOF || !(p > 0.0 && p < 1.0))
        return GF_ERR_BAD_PARAMETER;
    /* Wilson-Hilferty start, then Newton steps on the closed-form distribution */
    const double z = normal_quantile(p), k = 2.0 / (9.0 * m);
    const double t = 1.0 - k + z * sqrt(k);
    double x = fmax(m * t * t * t, 1e-3);
    const double log_norm = -0.5 * m * log(2.0) - log(tgamma(0.5 * m));
    for (int it = 0; it < 50; ++it) {
        const double pdf = exp(log_norm + (0.5 * m - 1.0) * log(x) - 0.5 * x);
        double step = (chi2_cdf(m, x) - p) / pdf;
        if (step > 0.5 * x)           /* keep x > 0 */
            step = 0.5 * x;
        x -= step;
        if (fabs(step) < 1e-13 * x)
            break;
    }
    *q = x;
    return GF_OK;
}
