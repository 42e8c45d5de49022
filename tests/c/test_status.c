/* test_status.c — the status codes (gf_status): the values gf_status.h promises (GF_OK is
 * 0, the errors 1..9 in the documented order, which the Python layer and the FMUs rely
 * on), a distinct non-empty message for each, and a message for a value that is no
 * status (a corrupted or future code) instead of NULL. */
#include <string.h>

#include "base/gf_status.h"
#include "gf_test.h"

int main(void)
{
    const gf_status codes[] = {GF_OK, GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT,
                               GF_ERR_BAD_PARAMETER, GF_ERR_SINGULAR_GEOMETRY, GF_ERR_BAD_SIZE,
                               GF_ERR_OUT_OF_RANGE, GF_ERR_BAD_TIME, GF_ERR_DIVERGED,
                               GF_ERR_BAD_TEXT};
    enum { N = sizeof codes / sizeof codes[0] };
    for (int i = 0; i < N; ++i)
        CHECK((int)codes[i] == i, "status %d has value %d (gf_status.h documents %d)", i, (int)codes[i], i);
    const char *unknown = gf_status_string((gf_status)99);
    CHECK(unknown != NULL && strstr(unknown, "unknown") != NULL, "an unknown code has a message");
    CHECK(strcmp(gf_status_string((gf_status)-1), unknown) == 0, "a negative code: the same message");
    for (int i = 0; i < N; ++i) {
        const char *m = gf_status_string(codes[i]);
        CHECK(m != NULL && m[0] != '\0' && strcmp(m, unknown) != 0, "status %d has its own message", i);
        for (int j = 0; j < i; ++j)
            CHECK(strcmp(m, gf_status_string(codes[j])) != 0, "statuses %d and %d share a message", i, j);
    }
    /* the messages name what the header says each code means */
    CHECK(strstr(gf_status_string(GF_ERR_DIVERGED), "pole") != NULL, "DIVERGED names the pole");
    CHECK(strstr(gf_status_string(GF_ERR_NONFINITE_INPUT), "NaN") != NULL, "NONFINITE names NaN");
    TEST_MAIN_END();
}
