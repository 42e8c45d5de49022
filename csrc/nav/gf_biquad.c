/* gf_biquad.c — see gf_biquad.h. */
#include "nav/gf_biquad.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"

/* Sizes within the fixed arrays: the only thing the hot loop needs to trust. */
static inline int sizes_valid(size_t n_sections, size_t n_channels)
{
    return n_sections >= 1 && n_sections <= GF_BIQUAD_MAX_SECTIONS && n_channels >= 1 &&
           n_channels <= GF_BIQUAD_MAX_CHANNELS;
}

/* Coefficients of n_sections sections: finite, a0 = 1, poles inside the unit circle. */
static gf_status check_sections(size_t n_sections, const double *sos, size_t *bad_section)
{
    for (size_t s = 0; s < n_sections; ++s) {
        const double *c = sos + 6 * s;
        gf_status st = GF_OK;
        if (!gf_all_finite(c, 6))
            st = GF_ERR_NONFINITE_INPUT;
        else if (c[3] != 1.0)
            st = GF_ERR_BAD_PARAMETER;
        else if (!(fabs(c[5]) < 1.0 && fabs(c[4]) < 1.0 + c[5])) /* stability triangle */
            st = GF_ERR_SINGULAR_GEOMETRY;
        if (st != GF_OK) {
            if (bad_section)
                *bad_section = s;
            return st;
        }
    }
    return GF_OK;
}

gf_status gf_biquad_init(gf_biquad *f, size_t n_sections, const double *sos, size_t n_channels,
                         size_t *bad_section)
{
    if (bad_section)
        *bad_section = 0;
    if (!f || !sos)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(n_sections, n_channels))
        return GF_ERR_BAD_SIZE;
    const gf_status st = check_sections(n_sections, sos, bad_section);
    if (st != GF_OK)
        return st;
    memset(f, 0, sizeof *f);
    f->n_sections = n_sections;
    f->n_channels = n_channels;
    memcpy(f->sos, sos, 6 * n_sections * sizeof *sos);
    return GF_OK;
}

gf_status gf_biquad_check(const gf_biquad *f)
{
    if (!f)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(f->n_sections, f->n_channels))
        return GF_ERR_BAD_SIZE;
    const gf_status st = check_sections(f->n_sections, f->sos, NULL);
    if (st != GF_OK)
        return st;
    return gf_all_finite(f->z, f->n_sections * f->n_channels * 2) ? GF_OK : GF_ERR_NONFINITE_INPUT;
}

gf_status gf_biquad_set_state(gf_biquad *f, const double *z, size_t n_z)
{
    if (!f || !z)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(f->n_sections, f->n_channels))
        return GF_ERR_BAD_SIZE;
    const size_t n = f->n_sections * f->n_channels * 2;
    if (n_z != n)
        return GF_ERR_BAD_SIZE;
    if (!gf_all_finite(z, n))
        return GF_ERR_NONFINITE_INPUT;
    memcpy(f->z, z, n * sizeof *z);
    return GF_OK;
}

gf_status gf_biquad_run(gf_biquad *f, size_t n, const double *x, double *y, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!f || !x || !y)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(f->n_sections, f->n_channels))
        return GF_ERR_BAD_SIZE;
    const size_t nc = f->n_channels, ns = f->n_sections;
    for (size_t k = 0; k < n; ++k) {
        const double *xk = x + nc * k;
        if (!gf_all_finite(xk, nc)) {
            if (n_done)
                *n_done = k;
            return GF_ERR_NONFINITE_INPUT;
        }
        double *yk = y + nc * k;
        int finite = 1;
        for (size_t c = 0; c < nc; ++c) {
            double v = xk[c];
            for (size_t s = 0; s < ns; ++s) {
                const double *q = f->sos + 6 * s;
                double *z = f->z + 2 * (s * nc + c);
                /* transposed direct form II, as scipy.signal.sosfilt */
                const double out = q[0] * v + z[0];
                z[0] = q[1] * v - q[4] * out + z[1];
                z[1] = q[2] * v - q[5] * out;
                finite &= isfinite(z[0]) & isfinite(z[1]);
                v = out;
            }
            yk[c] = v;
            finite &= isfinite(v);
        }
        if (!finite) { /* finite samples so large that the filter overflows (found by fuzzing) */
            if (n_done)
                *n_done = k;
            return GF_ERR_OUT_OF_RANGE;
        }
    }
    if (n_done)
        *n_done = n;
    return GF_OK;
}
