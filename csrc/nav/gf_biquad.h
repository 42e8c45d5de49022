/* gf_biquad.h — streaming IIR filtering as a cascade of second-order sections, for the
 * signal conditioning of seed 004 (Chebyshev type-II low-pass designed with
 * scipy.signal; any stable SOS design works).
 *
 * Section s has coefficients [b0 b1 b2 a0 a1 a2] (a0 = 1) and runs in transposed direct
 * form II, exactly as scipy.signal.sosfilt does (same operations, same order):
 *     y = b0 x + z0;   z0 = b1 x - a1 y + z1;   z1 = b2 x - a2 y
 * The state z lives in the struct, so a record can be filtered in chunks of any size.
 *
 * A struct handed in by a caller (e.g. restored from a saved FMU state) is not trusted:
 * gf_biquad_run and gf_biquad_set_state check its sizes against the fixed maxima before
 * touching its arrays, and gf_biquad_check checks all of it (sizes, coefficients,
 * state).
 */
#ifndef GF_BIQUAD_H
#define GF_BIQUAD_H

#include <stddef.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_BIQUAD_MAX_SECTIONS 16
#define GF_BIQUAD_MAX_CHANNELS 64

typedef struct gf_biquad {
    size_t n_sections;
    size_t n_channels;
    double sos[GF_BIQUAD_MAX_SECTIONS * 6];
    double z[GF_BIQUAD_MAX_SECTIONS * GF_BIQUAD_MAX_CHANNELS * 2];  /* [section][channel][2] */
} gf_biquad;

/* sos: n_sections x 6. Errors: GF_ERR_BAD_SIZE; GF_ERR_NONFINITE_INPUT;
 * GF_ERR_BAD_PARAMETER when a0 != 1; GF_ERR_SINGULAR_GEOMETRY when a section is unstable
 * (a pole on or outside the unit circle: not |a2| < 1 and |a1| < 1 + a2). *bad_section
 * (may be NULL) names the section. State zero. */
gf_status gf_biquad_init(gf_biquad *filter, size_t n_sections, const double *sos,
                         size_t n_channels, size_t *bad_section);

/* Sets the state z (n_z = n_sections x n_channels x 2 values, in that order), e.g.
 * scipy's sosfilt_zi scaled by the first sample to start at steady state.
 * Errors: GF_ERR_BAD_SIZE (n_z is not that product, or the filter's sizes are out of
 * range), GF_ERR_NONFINITE_INPUT; the state is unchanged on error. */
gf_status gf_biquad_set_state(gf_biquad *filter, const double *z, size_t n_z);

/* Filters n samples of n_channels (x, y: n x n_channels, may be the same array).
 * A non-finite sample stops the run: *n_done = its row, earlier rows are filtered and
 * the state is the state after them. GF_ERR_OUT_OF_RANGE: finite samples so large that
 * the output or the state overflowed at row *n_done (earlier rows are filtered; the
 * state is unusable: set it again, gf_biquad_set_state). GF_ERR_BAD_SIZE when the
 * filter's sizes are out of range (a corrupted struct): nothing is read or written then. */
gf_status gf_biquad_run(gf_biquad *filter, size_t n, const double *x, double *y, size_t *n_done);

/* Checks a whole filter struct, e.g. one restored from saved bytes: sizes
 * (GF_ERR_BAD_SIZE), coefficients as gf_biquad_init checks them (GF_ERR_NONFINITE_INPUT,
 * GF_ERR_BAD_PARAMETER, GF_ERR_SINGULAR_GEOMETRY) and a finite state
 * (GF_ERR_NONFINITE_INPUT). */
gf_status gf_biquad_check(const gf_biquad *filter);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_BIQUAD_H */
