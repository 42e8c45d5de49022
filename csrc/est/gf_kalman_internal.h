/* gf_kalman_internal.h — what the Kalman engine's two files (gf_kalman.c, gf_ukf.c) share
 * and callers never see (not read by cffi). */
#ifndef GF_KALMAN_INTERNAL_H
#define GF_KALMAN_INTERNAL_H

#include <stddef.h>

#include "base/gf_linalg.h"
#include "est/gf_kalman.h"

#define NMAX GF_KF_MAX_N
#define MMAX GF_KF_MAX_M
#define PADDED GF_PADDED
#define SMAX GF_PADDED(NMAX)   /* largest row stride of the padded work matrices */

/* 1 if all n values are finite: x - x is 0 for finite x and NaN for NaN and +-Inf; a
 * select of any NaN vectorises (also with SSE2 alone), unlike an early exit */
static inline int gf_all_finite_n(const double *a, size_t n)
{
    double nan_seen = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double d = a[i] - a[i];
        nan_seen = d != d ? d : nan_seen;
    }
    return nan_seen == 0.0;
}


#endif /* GF_KALMAN_INTERNAL_H */
