/* fuzz_data.h — reading a libFuzzer input as a stream of typed values, and the checks
 * (oracles) that the targets apply besides the sanitizers.
 *
 * A target consumes its input from the front: fz_u8 / fz_u32 / fz_index for choices and
 * sizes, fz_num for physical numbers. When the input runs out every reader returns 0, so
 * any input is a complete test case. fz_num(data, scale) draws mostly values a caller
 * could plausibly pass (|x| <= scale, or much smaller), and sometimes the values that
 * break numerical code (0, -0, NaN, +-Inf, the largest and the smallest doubles,
 * denormals, 1e+-300) or any 64-bit pattern: the entry points must refuse or handle all
 * of them.
 *
 * Oracles (FZ_REQUIRE aborts, which libFuzzer reports as a crash with the input saved):
 *  - every entry point returns a gf_status of the enumeration (0..8);
 *  - an output reported with GF_OK is finite (the standard: non-finite values are
 *    detected and reported, never propagated silently);
 *  - where a header documents "the state is unchanged on error", it is (bytes compared).
 */
#ifndef FUZZ_DATA_H
#define FUZZ_DATA_H

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct fz {
    const uint8_t *p;
    size_t n;
} fz;

static inline uint8_t fz_u8(fz *d)
{
    if (d->n == 0)
        return 0;
    --d->n;
    return *d->p++;
}

static inline uint16_t fz_u16(fz *d)
{
    return (uint16_t)(fz_u8(d) | (fz_u8(d) << 8));
}

static inline uint32_t fz_u32(fz *d)
{
    return (uint32_t)fz_u16(d) | ((uint32_t)fz_u16(d) << 16);
}

static inline uint64_t fz_u64(fz *d)
{
    return (uint64_t)fz_u32(d) | ((uint64_t)fz_u32(d) << 32);
}

/* A value in 0 .. n-1 (n > 0). */
static inline size_t fz_index(fz *d, size_t n)
{
    return n ? fz_u16(d) % n : 0;
}

/* Any 64-bit pattern as a double. */
static inline double fz_raw(fz *d)
{
    const uint64_t bits = fz_u64(d);
    double x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

static const double kFzSpecial[] = {0.0, -0.0, 1.0, -1.0, NAN, INFINITY, -INFINITY, DBL_MAX,
                                    -DBL_MAX, DBL_MIN, 4.9406564584124654e-324, 1e300,
                                    -1e300, 1e-300, 0.5, 2.0, 1e-6, 1e6, 1e-9};

/* A number of typical magnitude `scale` (see the top of the file). */
static inline double fz_num(fz *d, double scale)
{
    const uint8_t sel = fz_u8(d);
    const double u = fz_u16(d) / 32767.5 - 1.0;   /* [-1, 1] */
    switch (sel & 7u) {
    case 0: case 1: case 2: case 3:
        return scale * u;
    case 4:
        return scale * 1e-4 * u;
    case 5:
        return kFzSpecial[fz_u8(d) % (sizeof kFzSpecial / sizeof kFzSpecial[0])];
    case 6:
        return fz_raw(d);
    default:
        return scale * 1e3 * u;
    }
}

/* n numbers of magnitude scale into out. */
static inline void fz_nums(fz *d, double *out, size_t n, double scale)
{
    for (size_t i = 0; i < n; ++i)
        out[i] = fz_num(d, scale);
}

/* A positive number near `typical` (a time step, a std, a lever arm), or occasionally
 * anything fz_num gives. */
static inline double fz_pos(fz *d, double typical)
{
    const uint8_t sel = fz_u8(d);
    if (sel < 200)
        return typical * (0.001 + 2.0 * fz_u16(d) / 65535.0);
    return fz_num(d, typical);
}

#define FZ_REQUIRE(cond, ...)                                                                \
    do {                                                                                     \
        if (!(cond)) {                                                                       \
            fprintf(stderr, "fuzz oracle failed at %s:%d: ", __FILE__, __LINE__);           \
            fprintf(stderr, __VA_ARGS__);                                                    \
            fprintf(stderr, "\n");                                                           \
            abort();                                                                         \
        }                                                                                    \
    } while (0)

static inline int fz_all_finite(const double *x, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

/* A status of the enumeration (gf_status.h: GF_OK .. GF_ERR_DIVERGED). */
#define FZ_STATUS(st, what) FZ_REQUIRE((int)(st) >= 0 && (int)(st) <= 8, "%s returned %d", what, (int)(st))

/* On GF_OK the n outputs at x are finite. */
#define FZ_FINITE_ON_OK(st, x, n, what)                                                      \
    FZ_REQUIRE((st) != 0 || fz_all_finite((x), (n)), "%s: GF_OK with a non-finite output", what)

#endif /* FUZZ_DATA_H */
