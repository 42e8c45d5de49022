/* gf_stats.h — distributions the filters need: the chi-square quantile of the NIS gates
 * and its helpers.
 *
 * gf_chi2_quantile is part of the filter's cffi interface: its declaration for cffi
 * stays in the CDEF block of est/gf_ins_gnss.h (this header has none); the two
 * declarations are the same. */
#ifndef GF_STATS_H
#define GF_STATS_H

#include <stdint.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* the most degrees of freedom: the most rows of one Kalman update (GF_KF_MAX_M, checked
 * where both are used: est/gf_ins_update.c) */
#define GF_CHI2_MAX_DOF 12

/* Chi-square quantile for m degrees of freedom (1..12) at probability p in (0, 1): Newton
 * iterations on the closed-form distribution function from the Wilson-Hilferty start
 * (converged to ~1e-13 relative). Errors: GF_ERR_NULL_POINTER, GF_ERR_BAD_PARAMETER. */
gf_status gf_chi2_quantile(int32_t m, double p, double *q);

#ifdef __cplusplus
}
#endif

#endif /* GF_STATS_H */
