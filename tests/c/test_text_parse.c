/* test_text_parse.c — gf_text_parse (csrc/base/gf_text.c): lines of numbers into a table.
 *
 * Truth: the C library's strtod on the same digits (glibc's is correctly rounded; this
 * process never leaves the "C" locale except in the locale case, which compares with
 * bits written here), and bit patterns written by hand for the exact cases. Values are
 * compared bit for bit (no tolerance: the parser claims correct rounding). */
#include <locale.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/gf_text.h"
#include "gf_test.h"

static uint64_t bits(double x) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static double from_bits(uint64_t u) {
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

typedef struct {
    gf_status st;
    size_t rows, used, lines;
} parse_result;

static parse_result parse(const char *text, int final, size_t n_cols, int sep, double *out, size_t max_rows) {
    parse_result r;
    r.st = gf_text_parse((const uint8_t *)text, strlen(text), final, n_cols, sep, out, max_rows, &r.rows,
                         &r.used, &r.lines);
    return r;
}

/* one value through the parser and through strtod: the same bits */
static int same_as_strtod(const char *s) {
    double v = -1.0;
    parse_result r = parse(s, 1, 1, GF_TEXT_SEP_COMMA, &v, 1);
    double want = strtod(s, NULL);
    int ok = r.st == GF_OK && r.rows == 1 && bits(v) == bits(want);
    if (!ok) fprintf(stderr, "  %s: parsed %.17g (status %d), strtod %.17g\n", s, v, (int)r.st, want);
    return ok;
}

static void test_values_against_strtod(void) {
    test_rng rng = {0x9E3779B97F4A7C15ULL};
    const char *formats[] = {"%.17g", "%.15e", "%.16e", "%.20g", "%.9f", "%.15f", "%.3g", "%.25e"};
    char s[512];
    int bad = 0, n = 0;
    for (int i = 0; i < 20000; ++i) {
        /* any bit pattern (finite), and magnitudes spread over the decades */
        uint64_t u = (uint64_t)(test_rng_uniform(&rng, 0.0, 1.0) * 18446744073709551615.0);
        double x = from_bits(u);
        if (!isfinite(x)) continue;
        double y = test_rng_uniform(&rng, -1.0, 1.0) * pow(10.0, floor(test_rng_uniform(&rng, -30.0, 30.0)));
        for (int f = 0; f < 8; ++f) {
            snprintf(s, sizeof s, formats[f], (f % 2) ? x : y);
            bad += !same_as_strtod(s);
            snprintf(s, sizeof s, formats[f], (f % 2) ? y : x);
            if (strlen(s) < 400) bad += !same_as_strtod(s);
            n += 2;
        }
    }
    CHECK(bad == 0, "%d of %d values differ from strtod", bad, n);
    /* hard cases: the fast path's limits, halfway points, subnormals, the range's ends */
    const char *hard[] = {"9007199254740992", "9007199254740993", "9007199254740993.0000000001",
                          "9007199254740994", "9007199254740995", "1e22", "1e23", "8.5e-22", "123456789e22",
                          "0.1", "0.3", "2.2250738585072011e-308", "2.2250738585072014e-308",
                          "4.9406564584124654e-324", "2.4703282292062327e-324", "2.4703282292062328e-324",
                          "1.7976931348623157e308", "1.7976931348623158e308", "1.7976931348623159e308",
                          "1e-400", "1e400", "1e999999999999", "1e-999999999999", "0e999999", "00000.000001",
                          "1234567890123456789", "12345678901234567890", "0.000000266273294",
                          "-0.048922431910081", "7.2057594037927933e16", "5e-324", "3e-324"};
    for (size_t i = 0; i < sizeof hard / sizeof hard[0]; ++i)
        CHECK(same_as_strtod(hard[i]), "%s as strtod reads it", hard[i]);
    /* many digits: the value of 1 followed by 800 digits and e-800 (kept digits + sticky) */
    static char big[2000];
    big[0] = '1';
    for (int i = 1; i < 800; ++i) big[i] = '0';
    strcpy(big + 800, "1e-800");   /* 1.000...0001 (801 digits) * 10^-800 * 10^800 / ... */
    CHECK(same_as_strtod(big), "801 digits");
    /* a halfway point between 1 and 1 + 2^-52 with its 53rd bit: 1 + 2^-53 exactly is a tie
     * (to even: 1); the same plus 10^-700 rounds up */
    static char tie[1200];
    strcpy(tie, "1.00000000000000011102230246251565404236316680908203125");
    double v;
    parse_result r = parse(tie, 1, 1, GF_TEXT_SEP_COMMA, &v, 1);
    CHECK(r.st == GF_OK && v == 1.0, "1 + 2^-53 (a tie) reads as 1: %.17g", v);
    size_t n0 = strlen(tie);
    for (size_t i = n0; i < 700; ++i) tie[i] = '0';
    strcpy(tie + 700, "1");
    r = parse(tie, 1, 1, GF_TEXT_SEP_COMMA, &v, 1);
    CHECK(r.st == GF_OK && v == 1.0 + 0x1p-52, "1 + 2^-53 + 10^-700 reads as 1 + 2^-52: %.17g", v);
}

static void test_special_values(void) {
    double out[12];
    parse_result r = parse("nan,NaN,-nan,inf,-Inf,+INFINITY,-0,+0.,.5,5.,-.5e1,1E+2", 1, 12, GF_TEXT_SEP_COMMA, out, 1);
    CHECK(r.st == GF_OK && r.rows == 1, "special forms read (status %d)", (int)r.st);
    CHECK(isnan(out[0]) && !signbit(out[0]) && isnan(out[1]) && isnan(out[2]) && signbit(out[2]),
          "nan, NaN, -nan (sign bit set)");
    CHECK(out[3] == INFINITY && out[4] == -INFINITY && out[5] == INFINITY, "inf, -Inf, +INFINITY");
    CHECK(out[6] == 0.0 && signbit(out[6]) && out[7] == 0.0 && !signbit(out[7]), "-0 keeps its sign");
    CHECK(out[8] == 0.5 && out[9] == 5.0 && out[10] == -5.0 && out[11] == 100.0, ".5, 5., -.5e1, 1E+2");
    const char *refused[] = {"1e", "1e+", "e5", ".", "-", "+-1", "--1", "1_0", "0x10", "1d5", "nan(1)",
                             "infx", "1.5.3", "1 2", "- 1", "\x01", "1\r2", "１"};
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; ++i) {
        r = parse(refused[i], 1, 1, GF_TEXT_SEP_COMMA, out, 1);
        CHECK(r.st == GF_ERR_BAD_TEXT && r.rows == 0 && r.used == 0 && r.lines == 0, "%s refused (status %d)",
              refused[i], (int)r.st);
    }
}

static void test_lines(void) {
    double out[12];
    /* comments, blank lines, CRLF, spaces around fields (CSV), runs of blanks */
    parse_result r = parse("# head\r\n\r\n 1 , 2,3 \r\n  # 4,5,6\n\t\n-4,+5,6e0", 1, 3, GF_TEXT_SEP_COMMA, out, 4);
    CHECK(r.st == GF_OK && r.rows == 2 && r.lines == 6 && r.used == 42, "CSV: 2 rows of 6 lines (%d %zu %zu %zu)",
          (int)r.st, r.rows, r.lines, r.used);
    CHECK(out[0] == 1 && out[1] == 2 && out[2] == 3 && out[3] == -4 && out[4] == 5 && out[5] == 6, "CSV values");
    r = parse("  1\t2   3  \r\n#x\n4 5 6\n7 8", 0, 3, GF_TEXT_SEP_WHITESPACE, out, 4);
    CHECK(r.st == GF_OK && r.rows == 2 && r.lines == 3 && r.used == 22,
          "whitespace, final = 0: the incomplete last line left (%zu rows, %zu used)", r.rows, r.used);
    r = parse("7 8 9", 1, 3, GF_TEXT_SEP_WHITESPACE, out, 4);
    CHECK(r.st == GF_OK && r.rows == 1 && r.used == 5 && out[2] == 9, "final = 1: the last line without '\\n'");
    /* max_rows: stops before the next data line, after the comment lines in between */
    r = parse("1\n2\n#c\n\n3\n", 1, 1, GF_TEXT_SEP_COMMA, out, 2);
    CHECK(r.st == GF_OK && r.rows == 2 && r.used == 8 && r.lines == 4, "stops at max_rows (%zu used)", r.used);
    r = parse("3\n", 1, 1, GF_TEXT_SEP_COMMA, out, 0);
    CHECK(r.st == GF_OK && r.rows == 0 && r.used == 0, "max_rows 0: nothing");
    /* a bad line: the rows before it written, *n_used at its start, *n_lines before it */
    const struct { const char *text; int sep; size_t rows, used, lines; } bad[] = {
        {"1,2,3\n#c\n4,5\n", GF_TEXT_SEP_COMMA, 1, 9, 2},            /* too few fields */
        {"1,2,3\n4,5,6,7\n", GF_TEXT_SEP_COMMA, 1, 6, 1},            /* too many */
        {"1,2,3\n4,5,6,\n", GF_TEXT_SEP_COMMA, 1, 6, 1},             /* a trailing comma */
        {"1,,3\n", GF_TEXT_SEP_COMMA, 0, 0, 0},                       /* an empty field */
        {"1,2,3 # c\n", GF_TEXT_SEP_COMMA, 0, 0, 0},                  /* a trailing comment */
        {"1 2 3\n\n4 5 x\n", GF_TEXT_SEP_WHITESPACE, 1, 7, 2},       /* text */
        {"1,2,3\n", GF_TEXT_SEP_WHITESPACE, 0, 0, 0},                 /* commas in whitespace mode */
        {"1 2 3 4\n", GF_TEXT_SEP_WHITESPACE, 0, 0, 0},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        r = parse(bad[i].text, 1, 3, bad[i].sep, out, 4);
        CHECK(r.st == GF_ERR_BAD_TEXT && r.rows == bad[i].rows && r.used == bad[i].used && r.lines == bad[i].lines,
              "bad case %zu: status %d, %zu rows, %zu used, %zu lines", i, (int)r.st, r.rows, r.used, r.lines);
    }
}

static void test_arguments(void) {
    double out[3];
    size_t a, b, c;
    const uint8_t *t = (const uint8_t *)"1";
    CHECK(gf_text_parse(t, 1, 1, 1, 0, out, 1, NULL, &b, &c) == GF_ERR_NULL_POINTER, "NULL n_rows");
    CHECK(gf_text_parse(NULL, 1, 1, 1, 0, out, 1, &a, &b, &c) == GF_ERR_NULL_POINTER, "NULL text");
    CHECK(gf_text_parse(t, 1, 1, 1, 0, NULL, 1, &a, &b, &c) == GF_ERR_NULL_POINTER, "NULL out");
    CHECK(gf_text_parse(t, 1, 1, 0, 0, out, 1, &a, &b, &c) == GF_ERR_BAD_SIZE, "0 columns");
    CHECK(gf_text_parse(t, 1, 1, 1, 2, out, 1, &a, &b, &c) == GF_ERR_BAD_PARAMETER, "sep 2");
    CHECK(gf_text_parse(t, 1, 2, 1, 0, out, 1, &a, &b, &c) == GF_ERR_BAD_PARAMETER, "final 2");
    CHECK(gf_text_parse(NULL, 0, 1, 1, 0, NULL, 0, &a, &b, &c) == GF_OK && a == 0 && b == 0 && c == 0,
          "no text, no rows: OK");
}

/* a locale whose decimal point is ',' changes nothing (the slow path writes no point) */
static void test_locale(void) {
    const char *names[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "fr_FR.utf8"};
    const char *set = NULL;
    for (size_t i = 0; i < sizeof names / sizeof names[0] && set == NULL; ++i)
        set = setlocale(LC_NUMERIC, names[i]);
    if (set == NULL) {
        printf("no locale with a decimal comma installed: the locale case skipped\n");
        return;
    }
    double out[3];
    parse_result r = parse("0.1 12345678901234567890.5 1.7976931348623157e308\n", 1, 3, GF_TEXT_SEP_WHITESPACE, out, 1);
    CHECK(r.st == GF_OK && bits(out[0]) == 0x3FB999999999999AULL && out[1] == 12345678901234567168.0 &&
              bits(out[2]) == 0x7FEFFFFFFFFFFFFFULL, "in locale %s: %.17g %.17g %.17g", set, out[0], out[1], out[2]);
    setlocale(LC_NUMERIC, "C");
}

int main(void) {
    test_values_against_strtod();
    test_special_values();
    test_lines();
    test_arguments();
    test_locale();
    TEST_MAIN_END();
}
