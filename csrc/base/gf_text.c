/* gf_text.c — see gf_text.h. */
#include "base/gf_text.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* the bytes a value may take: sign, 309 digits are handled by snprintf below; the fast
 * path writes at most 1 + 16 + 1 + 9 bytes */
#define VALUE_BYTES 40

static const double kPow10[GF_TEXT_MAX_DECIMALS + 1] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};

/* one value at p (at most VALUE_BYTES bytes); returns the bytes written */
static size_t put_value(char *p, double x, int decimals) {
    if (isnan(x)) {
        memcpy(p, "NaN", 3);
        return 3;
    }
    if (isinf(x)) {
        if (x < 0) {
            memcpy(p, "-inf", 4);
            return 4;
        }
        memcpy(p, "inf", 3);
        return 3;
    }
    double ax = fabs(x);
    if (!(ax < 9007199254740992.0)) { /* 2^53: the integer part not exact in uint64 below */
        int k = snprintf(p, VALUE_BYTES, "%.*f", decimals, x);  /* |x| < GF_TEXT_MAX_ABS: fits */
        return (size_t)k;
    }
    /* the integer part and the fraction exactly (ax - floor(ax) is exact in binary), then
     * the fraction scaled and rounded to nearest, an exact tie to even, as printf: off from
     * printf's exact decimal rounding only when the fraction lies within ~1e-7 of a unit of
     * the last place of a tie without being one (the scaling's one rounding), by one unit */
    double ip = floor(ax);
    uint64_t whole = (uint64_t)ip;
    double fs = (ax - ip) * kPow10[decimals];
    double fl = floor(fs);
    double rem = fs - fl;
    uint64_t frac = (uint64_t)fl;
    if (rem > 0.5 || (rem == 0.5 && (((decimals > 0) ? frac : whole) & 1u))) frac += 1u;
    if (frac >= (uint64_t)kPow10[decimals]) {
        frac -= (uint64_t)kPow10[decimals];
        whole += 1u;
    }
    char digits[32];
    int nd = 0;
    for (int i = 0; i < decimals; ++i) {
        digits[nd++] = (char)('0' + (int)(frac % 10u));
        frac /= 10u;
    }
    do {
        digits[nd++] = (char)('0' + (int)(whole % 10u));
        whole /= 10u;
    } while (whole != 0u);
    size_t n = 0;
    if (signbit(x)) p[n++] = '-';
    for (int i = nd - 1; i >= decimals; --i) p[n++] = digits[i];
    if (decimals > 0) {
        p[n++] = '.';
        for (int i = decimals - 1; i >= 0; --i) p[n++] = digits[i];
    }
    return n;
}

gf_status gf_text_fixed(size_t n_rows, size_t n_cols, const double *table, int decimals, char sep,
                        char *out, size_t capacity, size_t *n_written) {
    if (n_written == NULL) return GF_ERR_NULL_POINTER;
    *n_written = 0;
    if ((table == NULL && n_rows > 0) || out == NULL) return GF_ERR_NULL_POINTER;
    if (decimals < 0 || decimals > GF_TEXT_MAX_DECIMALS) return GF_ERR_BAD_PARAMETER;
    if (n_cols == 0 || (n_rows > 0 && capacity / n_rows / n_cols < VALUE_BYTES)) return GF_ERR_BAD_SIZE;
    for (size_t i = 0; i < n_rows * n_cols; ++i) {
        if (fabs(table[i]) >= GF_TEXT_MAX_ABS && !isinf(table[i])) return GF_ERR_OUT_OF_RANGE;
    }
    size_t n = 0;
    for (size_t r = 0; r < n_rows; ++r) {
        const double *row = table + r * n_cols;
        for (size_t c = 0; c < n_cols; ++c) {
            n += put_value(out + n, row[c], decimals);
            out[n++] = (c + 1 < n_cols) ? sep : '\n';
        }
    }
    *n_written = n;
    return GF_OK;
}
