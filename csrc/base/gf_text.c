/* gf_text.c — see gf_text.h. */
#include "base/gf_text.h"
#include "base/gf_text_pow10.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the bytes a value may take: sign, 309 digits are handled by snprintf below; the fast
 * path writes at most 1 + 16 + 1 + 9 bytes */
#define VALUE_BYTES 40

static const double kPow10[GF_TEXT_MAX_DECIMALS + 1] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
static const uint32_t kPow10u[GF_TEXT_MAX_DECIMALS + 1] = {1u,      10u,      100u,      1000u,      10000u,
                                                          100000u, 1000000u, 10000000u, 100000000u, 1000000000u};

/* "00" .. "99": two digits a division */
static const char kDigitPairs[201] = "0001020304050607080910111213141516171819202122232425262728293031323334353637383940414243444546474849"
                                     "5051525354555657585960616263646566676869707172737475767778798081828384858687888990919293949596979899";

/* v < 10^n written as exactly n digits (leading zeros) */
static void put_fixed_digits(char *p, uint32_t v, int n) {
    char *q = p + n;
    for (; n >= 2; n -= 2) {
        q -= 2;
        memcpy(q, kDigitPairs + 2u * (v % 100u), 2);
        v /= 100u;
    }
    if (n) *--q = (char)('0' + v);
}

/* v in decimal, no leading zeros (at least one digit), written backwards from its last
 * digit; returns the bytes written */
static size_t put_digits(char *p, uint64_t v) {
    size_t n = 1;
    for (uint64_t t = v; t >= 10u; t /= 10u) ++n;
    char *q = p + n;
    while (v >= 100u) {
        q -= 2;
        memcpy(q, kDigitPairs + 2u * (v % 100u), 2);
        v /= 100u;
    }
    if (v >= 10u) {
        q -= 2;
        memcpy(q, kDigitPairs + 2u * v, 2);
    } else {
        *--q = (char)('0' + v);
    }
    return n;
}

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
    /* printf's digits exactly: the exact binary value rounded to `decimals` places, an
     * exact tie to even. The integer part and the fraction f are exact (ax < 2^53); the
     * fraction scaled, fs = f 10^d, is rounded once, and err = f 10^d - fs (fma: exact,
     * the error of a product is a double) holds what the rounding took, so the sign of
     * (fs - floor(fs) - 1/2) + err (a rounded sum of two doubles is zero, positive or
     * negative as the exact sum is) says whether the exact remainder is below, at or
     * above the half. */
    const int64_t ip = (int64_t)ax;  /* truncation = floor: 0 <= ax < 2^53 */
    uint64_t whole = (uint64_t)ip;
    const double f = ax - (double)ip;
    const double fs = f * kPow10[decimals];
    const double err = fma(f, kPow10[decimals], -fs);
    uint32_t frac = (uint32_t)(int64_t)fs;    /* fs < 10^9 < 2^32 */
    const double half = ((fs - (double)frac) - 0.5) + err;
    const uint32_t odd = (uint32_t)((decimals > 0) ? frac : (uint32_t)whole) & 1u;
    /* without branches: the rounding direction is data, not a pattern to predict */
    frac += (uint32_t)(half > 0.0) | ((uint32_t)(half == 0.0) & odd);
    if (frac >= kPow10u[decimals]) {
        frac -= kPow10u[decimals];
        whole += 1u;
    }
    size_t n = 0;
    if (signbit(x)) p[n++] = '-';
    n += put_digits(p + n, whole);
    if (decimals > 0) {
        p[n++] = '.';
        put_fixed_digits(p + n, frac, decimals);
        n += (size_t)decimals;
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

/* ---- parsing ------------------------------------------------------------------------- */

/* the powers of ten a double holds exactly: 10^k = 2^k 5^k and 5^22 < 2^53 */
static const double kExact10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                    1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                    1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* significant digits kept for strtod: every halfway point between two doubles has at most
 * 767 significant digits, so 779 digits and a sticky '1' for any nonzero digit dropped
 * round as all the digits do */
#define PARSE_KEEP_DIGITS 779
/* decimal exponents beyond this (after the digits are counted) are 0 or infinity */
#define PARSE_EXP_CLAMP 100000
/* the explicit exponent stops growing here (no overflow of int64_t) */
#define PARSE_EXP_CAP 1000000000

static int is_digit(uint8_t c) { return c >= '0' && c <= '9'; }
static int is_blank(uint8_t c) { return c == ' ' || c == '\t'; }
static uint8_t lower(uint8_t c) { return (c >= 'A' && c <= 'Z') ? (uint8_t)(c + 32) : c; }

/* does [p, end) start with the lowercase word w (any case)? */
static int has_word(const uint8_t *p, const uint8_t *end, const char *w) {
    size_t n = strlen(w);
    if ((size_t)(end - p) < n) return 0;
    for (size_t i = 0; i < n; ++i)
        if (lower(p[i]) != (uint8_t)w[i]) return 0;
    return 1;
}

/* the slow path: the significant digits of [p, end) (a checked number without its sign:
 * digits, '.', digits, exponent) written as an integer and a power of ten, by strtod */
static double parse_slow(const uint8_t *p, const uint8_t *end) {
    char buf[PARSE_KEEP_DIGITS + 32];
    int nd = 0, sticky = 0, seen = 0, point = 0;
    int64_t scale = 0;
    for (; p < end && (is_digit(*p) || *p == '.'); ++p) {
        if (*p == '.') {
            point = 1;
            continue;
        }
        if (!seen && *p == '0') {               /* a leading zero */
            if (point) --scale;
            continue;
        }
        seen = 1;
        if (nd < PARSE_KEEP_DIGITS) {
            buf[nd++] = (char)*p;
            if (point) --scale;
        } else {
            if (*p != '0') sticky = 1;
            if (!point) ++scale;
        }
    }
    if (nd == 0) return 0.0;
    int64_t e = 0;
    if (p < end && (*p == 'e' || *p == 'E')) {
        ++p;
        int neg = 0;
        if (*p == '+' || *p == '-') neg = (*p++ == '-');
        for (; p < end && is_digit(*p); ++p)
            if (e < PARSE_EXP_CAP) e = e * 10 + (*p - '0');
        if (neg) e = -e;
    }
    if (sticky) {
        buf[nd++] = '1';
        --scale;
    }
    e += scale;
    if (e > PARSE_EXP_CLAMP) e = PARSE_EXP_CLAMP;
    if (e < -PARSE_EXP_CLAMP) e = -PARSE_EXP_CLAMP;
    /* "DIGITSe-EXP": no decimal point, so LC_NUMERIC cannot change the reading */
    buf[nd++] = 'e';
    if (e < 0) {
        buf[nd++] = '-';
        e = -e;
    }
    char rev[12];
    int nr = 0;
    do {
        rev[nr++] = (char)('0' + (int)(e % 10));
        e /= 10;
    } while (e != 0);
    while (nr > 0) buf[nd++] = rev[--nr];
    buf[nd] = '\0';
    return strtod(buf, NULL);   /* ERANGE (0 or inf) is the value wanted */
}

/* the 128-bit product of two 64-bit numbers (portable: four 32-bit products) */
static void mul64(uint64_t a, uint64_t b, uint64_t *hi, uint64_t *lo) {
    const uint64_t a0 = a & 0xFFFFFFFFu, a1 = a >> 32, b0 = b & 0xFFFFFFFFu, b1 = b >> 32;
    const uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    const uint64_t mid = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
    *lo = (mid << 32) | (p00 & 0xFFFFFFFFu);
    *hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}

static int leading_zeros64(uint64_t x) {   /* x != 0 */
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_clzll(x);
#else
    int n = 0;
    while (!(x & ((uint64_t)1 << 63))) {
        x <<= 1;
        ++n;
    }
    return n;
#endif
}

/* m * 10^e10 (m != 0, exact) correctly rounded by Eisel–Lemire (gf_text_pow10.h's
 * reference; Go's strconv.eiselLemire64 step by step): 1 with the value in *x, 0 when
 * the product is too close to a halfway point to decide, or the result is subnormal or
 * beyond the range (then the slow path decides). */
static int eisel_lemire(uint64_t m, int64_t e10, double *x) {
    if (e10 < GF_TEXT_POW10_MIN || e10 > GF_TEXT_POW10_MAX) return 0;
    const uint64_t *pw = kPow10Mantissa[e10 - GF_TEXT_POW10_MIN];
    const int clz = leading_zeros64(m);
    m <<= clz;
    /* floor(e10 log2(10)) as 217706 e10 / 2^16, rounded toward minus infinity */
    const int64_t t = 217706 * e10;
    const int64_t log2_10e = (t >= 0) ? t / 65536 : -((-t + 65535) / 65536);
    uint64_t exp2 = (uint64_t)(log2_10e + 64 + 1023) - (uint64_t)clz;
    uint64_t hi, lo;
    mul64(m, pw[1], &hi, &lo);
    if ((hi & 0x1FF) == 0x1FF && lo + m < m) {        /* the wider approximation */
        uint64_t yhi, ylo;
        mul64(m, pw[0], &yhi, &ylo);
        uint64_t mhi = hi, mlo = lo + yhi;
        if (mlo < lo) ++mhi;
        if ((mhi & 0x1FF) == 0x1FF && mlo + 1 == 0 && ylo + m < m) return 0;
        hi = mhi;
        lo = mlo;
    }
    const uint64_t msb = hi >> 63;
    uint64_t mant = hi >> (msb + 9);
    exp2 -= 1 ^ msb;
    if (lo == 0 && (hi & 0x1FF) == 0 && (mant & 3) == 1) return 0;   /* halfway: undecided */
    mant += mant & 1;
    mant >>= 1;
    if (mant >> 53) {
        mant >>= 1;
        ++exp2;
    }
    if (exp2 - 1 >= 0x7FF - 1) return 0;                 /* subnormal, zero or beyond */
    const uint64_t bits = (exp2 << 52) | (mant & 0x000FFFFFFFFFFFFFu);
    memcpy(x, &bits, sizeof *x);
    return 1;
}

/* eight digits at once where the byte order allows (SWAR: Lemire's "fast_float"); the
 * plain loop elsewhere */
#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define GF_TEXT_SWAR 1
/* the value of the eight ASCII digits at p */
static uint64_t eight_digits(const uint8_t *p) {
    uint64_t v;
    memcpy(&v, p, 8);
    v -= 0x3030303030303030u;
    v = (v * 10u) + (v >> 8);
    v = (((v & 0x000000FF000000FFu) * 0x000F424000000064u) +
         (((v >> 16) & 0x000000FF000000FFu) * 0x0000271000000001u)) >> 32;
    return v;
}
#else
#define GF_TEXT_SWAR 0
#endif

/* the end of the run of digits that starts at p (SWAR: eight bytes checked at once) */
static const uint8_t *skip_digits(const uint8_t *p, const uint8_t *end) {
#if GF_TEXT_SWAR
    for (; end - p >= 8; p += 8) {
        uint64_t v;
        memcpy(&v, p, 8);
        if (((v & 0xF0F0F0F0F0F0F0F0u) | (((v + 0x0606060606060606u) & 0xF0F0F0F0F0F0F0F0u) >> 4)) !=
            0x3333333333333333u)
            break;
    }
#endif
    while (p < end && (uint8_t)(*p - '0') < 10u) ++p;
    return p;
}

/* m * 10^(q1 - q0) + the digits [q0, q1) (all digits; the product may wrap beyond 19) */
static uint64_t add_digits(uint64_t m, const uint8_t *q0, const uint8_t *q1) {
#if GF_TEXT_SWAR
    for (; q1 - q0 >= 8; q0 += 8) m = m * 100000000u + eight_digits(q0);
#endif
    for (; q0 < q1; ++q0) m = m * 10u + (uint64_t)(*q0 - '0');
    return m;
}

/* One number at p (a field's first character) in [p, end): its value in *v and the
 * pointer after it, or NULL when no number starts there. The digits are accumulated
 * into a uint64 without a check per digit (it wraps beyond 19 digits, when the slow path
 * is taken anyway). */
static const uint8_t *parse_number(const uint8_t *p, const uint8_t *end, double *v) {
    int neg = 0;
    if (p < end && (*p == '+' || *p == '-')) neg = (*p++ == '-');
    if (p == end) return NULL;
    const uint8_t c0 = lower(*p);
    if (c0 == 'n' || c0 == 'i') {
        double x;
        if (has_word(p, end, "nan")) {
            x = NAN;
            p += 3;
        } else if (has_word(p, end, "infinity")) {
            x = INFINITY;
            p += 8;
        } else if (has_word(p, end, "inf")) {
            x = INFINITY;
            p += 3;
        } else {
            return NULL;
        }
        *v = neg ? -x : x;   /* -NaN: the sign bit set, as polars and strtod read it */
        return p;
    }
    const uint8_t *start = p;
    uint64_t m = 0;
    while (p < end && *p == '0') ++p;                   /* leading zeros */
    const uint8_t *sig = p;
    p = skip_digits(p, end);
    m = add_digits(m, sig, p);
    size_t nsig = (size_t)(p - sig), ndig = (size_t)(p - start);
    int64_t e10 = 0;
    if (p < end && *p == '.') {
        const uint8_t *f0 = ++p;
        if (nsig == 0)
            while (p < end && *p == '0') ++p;           /* zeros before the first significant digit */
        const uint8_t *f1 = p;
        p = skip_digits(p, end);
        /* trailing zeros add nothing ("36000.005000000000000": 8 digits, not 20) */
        const uint8_t *f2 = p;
        while (f2 > f1 && f2[-1] == '0') --f2;
        m = add_digits(m, f1, f2);
        nsig += (size_t)(f2 - f1);
        ndig += (size_t)(p - f0);
        e10 = -(int64_t)(f2 - f0);
    }
    if (ndig == 0) return NULL;
    if (p < end && (*p == 'e' || *p == 'E')) {
        ++p;
        int eneg = 0;
        if (p < end && (*p == '+' || *p == '-')) eneg = (*p++ == '-');
        if (p == end || !is_digit(*p)) return NULL;
        int64_t e = 0;
        for (; p < end && is_digit(*p); ++p)
            if (e < PARSE_EXP_CAP) e = e * 10 + (*p - '0');
        e10 += eneg ? -e : e;
    }
    double x;
    if (nsig == 0) {
        x = 0.0;
    } else if (nsig <= 19 && m <= ((uint64_t)1 << 53) && e10 >= -22 && e10 <= 22) {
        /* Clinger's fast path: m and 10^|e10| are exact doubles, one rounding */
        x = (e10 < 0) ? (double)m / kExact10[-e10] : (double)m * kExact10[e10];
    } else if (!(nsig <= 19 && eisel_lemire(m, e10, &x))) {
        x = parse_slow(start, p);
    }
    *v = neg ? -x : x;
    return p;
}

/* One data line [p, end) (no '\n', no trailing '\r') into row; 0 when it is not a row of
 * n_cols numbers. */
static int parse_row(const uint8_t *p, const uint8_t *end, size_t n_cols, int sep, double *row) {
    for (size_t c = 0; c < n_cols; ++c) {
        while (p < end && is_blank(*p)) ++p;
        p = parse_number(p, end, &row[c]);
        if (p == NULL) return 0;
        if (p == end) return c + 1 == n_cols;
        if (sep == GF_TEXT_SEP_COMMA) {
            while (p < end && is_blank(*p)) ++p;
            if (p == end) return c + 1 == n_cols;
            if (*p != ',' || c + 1 == n_cols) return 0;
            ++p;
        } else {
            if (!is_blank(*p)) return 0;
            while (p < end && is_blank(*p)) ++p;
            if (p == end) return c + 1 == n_cols;
            if (c + 1 == n_cols) return 0;
        }
    }
    return 0;   /* not reached: n_cols >= 1 */
}

gf_status gf_text_parse(const uint8_t *text, size_t n_bytes, int final, size_t n_cols, int sep,
                        double *out, size_t max_rows, size_t *n_rows, size_t *n_used,
                        size_t *n_lines) {
    if (n_rows == NULL || n_used == NULL || n_lines == NULL) return GF_ERR_NULL_POINTER;
    *n_rows = *n_used = *n_lines = 0;
    if ((text == NULL && n_bytes > 0) || (out == NULL && max_rows > 0)) return GF_ERR_NULL_POINTER;
    if (n_cols == 0) return GF_ERR_BAD_SIZE;
    if ((sep != GF_TEXT_SEP_COMMA && sep != GF_TEXT_SEP_WHITESPACE) || (final != 0 && final != 1))
        return GF_ERR_BAD_PARAMETER;
    size_t pos = 0, rows = 0, lines = 0;
    gf_status status = GF_OK;
    while (pos < n_bytes) {
        const uint8_t *line = text + pos;
        const uint8_t *nl = memchr(line, '\n', n_bytes - pos);
        if (nl == NULL && !final) break;                 /* an incomplete line: the caller's */
        const uint8_t *end = (nl != NULL) ? nl : text + n_bytes;
        size_t next = (size_t)(end - text) + (nl != NULL);
        if (end > line && end[-1] == '\r') --end;
        const uint8_t *q = line;
        while (q < end && is_blank(*q)) ++q;
        if (q < end && *q != '#') {                      /* a data line */
            if (rows == max_rows) break;
            if (!parse_row(q, end, n_cols, sep, out + rows * n_cols)) {
                status = GF_ERR_BAD_TEXT;
                break;
            }
            ++rows;
        }
        pos = next;
        ++lines;
    }
    *n_rows = rows;
    *n_used = pos;
    *n_lines = lines;
    return status;
}
