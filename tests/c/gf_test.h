/* gf_test.h — a minimal test harness for the C tests (one header, no dependencies).
 *
 * CHECK(cond, fmt, ...) records a failure with its location and a message;
 * CHECK_CLOSE(a, b, tol, what) compares two doubles within an absolute tolerance.
 * TEST_MAIN_END prints "N passed, N failed" and returns non-zero on any failure. */
#ifndef GF_TEST_H
#define GF_TEST_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>

static int gf_test_passed = 0, gf_test_failed = 0;

#define CHECK(cond, ...)                                                                     \
    do {                                                                                     \
        if (cond) {                                                                          \
            ++gf_test_passed;                                                                \
        } else {                                                                             \
            ++gf_test_failed;                                                                \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                             \
            fprintf(stderr, __VA_ARGS__);                                                    \
            fprintf(stderr, "\n");                                                           \
        }                                                                                    \
    } while (0)

#define CHECK_CLOSE(a, b, tol, what)                                                         \
    do {                                                                                     \
        const double gf_a_ = (a), gf_b_ = (b);                                               \
        CHECK(fabs(gf_a_ - gf_b_) <= (tol), "%s: %.17g vs %.17g (|diff| %.3g > tol %.3g)",  \
              (what), gf_a_, gf_b_, fabs(gf_a_ - gf_b_), (double)(tol));                    \
    } while (0)

#define TEST_MAIN_END()                                                                      \
    do {                                                                                     \
        printf("%d passed, %d failed\n", gf_test_passed, gf_test_failed);                   \
        return gf_test_failed ? 1 : 0;                                                       \
    } while (0)

/* Deterministic uniform random numbers in [lo, hi) (xorshift64*), fixed seed per test. */
typedef struct { uint64_t s; } test_rng;
static inline double test_rng_uniform(test_rng *r, double lo, double hi)
{
    r->s ^= r->s >> 12;
    r->s ^= r->s << 25;
    r->s ^= r->s >> 27;
    const uint64_t x = r->s * 2685821657736338717ULL;
    return lo + (hi - lo) * (double)(x >> 11) * (1.0 / 9007199254740992.0);
}

#endif /* GF_TEST_H */
