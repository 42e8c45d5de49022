/* fuzz_text.c — libFuzzer target: gf_text_parse (csrc/base/gf_text.h) on any bytes.
 * The first byte chooses the columns (1..8), the separator, final and max_rows; the rest
 * is the text. Oracles: a valid status; the counts within the text and max_rows; n_used
 * at a line boundary; on GF_ERR_BAD_TEXT the line at n_used is a data line; every value
 * of every row written equals strtod of its field (this process stays in the "C" locale;
 * NaN as NaN with its sign); parsing again from n_used continues the same table (the
 * text in two calls, split where the first stopped, gives the rows of one call). */
#include <stdlib.h>
#include <string.h>

#include "base/gf_text.h"
#include "fuzz_data.h"

#define MAX_COLS 8
#define MAX_ROWS 600   /* 2048 bytes hold at most 1024 rows of one column; fewer: max_rows */

static int is_blank(uint8_t c) { return c == ' ' || c == '\t'; }

/* the fields of the data line [p, end) checked against the row strtod reads */
static void check_row(const uint8_t *p, const uint8_t *end, size_t k, int sep, const double *row) {
    char tok[2100];
    for (size_t c = 0; c < k; ++c) {
        while (p < end && is_blank(*p)) ++p;
        size_t n = 0;
        while (p < end && !is_blank(*p) && *p != ',') tok[n++] = (char)*p++;
        tok[n] = '\0';
        while (p < end && (is_blank(*p) || (sep == GF_TEXT_SEP_COMMA && *p == ','))) {
            int comma = *p == ',';
            ++p;
            if (comma) break;
        }
        char *stop = NULL;
        double want = strtod(tok, &stop);
        FZ_REQUIRE(stop == tok + n, "field %zu (%s) accepted by gf_text_parse, not read whole by strtod", c, tok);
        uint64_t a, b;
        memcpy(&a, &row[c], 8);
        memcpy(&b, &want, 8);
        FZ_REQUIRE(a == b || (isnan(want) && isnan(row[c]) && signbit(want) == signbit(row[c])),
                   "field %zu (%s): %.17g where strtod reads %.17g", c, tok, row[c], want);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 2) return 0;
    const uint8_t ctl = data[0], ctl2 = data[1];
    const uint8_t *text = data + 2;
    const size_t n = size - 2;
    const size_t k = 1 + (ctl & 7u);
    const int sep = (ctl >> 3) & 1;
    const int final = (ctl >> 4) & 1;
    const size_t max_rows = (ctl2 < 200) ? MAX_ROWS : ctl2 - 200u; /* mostly room for all */
    static double out[MAX_ROWS * MAX_COLS], again[MAX_ROWS * MAX_COLS];
    size_t rows = 0, used = 0, lines = 0;
    gf_status st = gf_text_parse(text, n, final, k, sep, out, max_rows, &rows, &used, &lines);
    FZ_REQUIRE(st == GF_OK || st == GF_ERR_BAD_TEXT, "status %d on a valid call", (int)st);
    FZ_REQUIRE(used <= n && rows <= max_rows && rows <= lines, "counts: %zu used of %zu, %zu rows, %zu lines",
               used, n, rows, lines);
    size_t nl = 0;
    for (size_t i = 0; i < used; ++i) nl += text[i] == '\n';
    FZ_REQUIRE(used == 0 || text[used - 1] == '\n' || (final && used == n), "n_used %zu not at a line's end", used);
    FZ_REQUIRE(lines == nl + (used > 0 && text[used - 1] != '\n'), "%zu lines counted, %zu consumed", lines, nl);
    /* the data lines consumed, against strtod */
    size_t r = 0;
    for (size_t pos = 0; pos < used;) {
        const uint8_t *line = text + pos, *nlp = memchr(line, '\n', used - pos);
        const uint8_t *end = nlp ? nlp : text + used;
        pos = (size_t)(end - text) + (nlp != NULL);
        if (end > line && end[-1] == '\r') --end;
        const uint8_t *q = line;
        while (q < end && is_blank(*q)) ++q;
        if (q == end || *q == '#') continue;
        FZ_REQUIRE(r < rows, "more data lines consumed than rows written");
        check_row(q, end, k, sep, out + r * k);
        ++r;
    }
    FZ_REQUIRE(r == rows, "%zu rows written, %zu data lines consumed", rows, r);
    if (st == GF_ERR_BAD_TEXT) {
        const uint8_t *q = text + used, *nlp = memchr(q, '\n', n - used);
        const uint8_t *end = nlp ? nlp : text + n;
        if (end > q && end[-1] == '\r') --end;
        while (q < end && is_blank(*q)) ++q;
        FZ_REQUIRE(q < end && *q != '#', "a refused line that is blank or a comment");
    }
    /* resuming where it stopped: the same table as one call with room for everything */
    if (st == GF_OK && used < n) {
        size_t rows2 = 0, used2 = 0, lines2 = 0, rows1 = 0, used1 = 0, lines1 = 0;
        gf_status st2 = gf_text_parse(text + used, n - used, final, k, sep, again, MAX_ROWS - rows, &rows2,
                                      &used2, &lines2);
        gf_status st1 = gf_text_parse(text, n, final, k, sep, out, MAX_ROWS, &rows1, &used1, &lines1);
        FZ_REQUIRE(st1 == st2 && used1 == used + used2 && lines1 == lines + lines2 && rows1 == rows + rows2,
                   "two calls (%d, %zu bytes) differ from one (%d, %zu bytes)", (int)st2, used + used2, (int)st1, used1);
        FZ_REQUIRE(memcmp(out + rows * k, again, rows2 * k * sizeof(double)) == 0, "resumed rows differ");
    }
    return 0;
}
