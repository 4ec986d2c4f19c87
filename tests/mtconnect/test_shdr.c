/* test_shdr.c: the SHDR reader. Lines written here by hand from the
 * protocol's rules (timestamps, key|value pairs, conditions, messages,
 * single and multiline assets, heartbeats, malformed and oversized lines),
 * fed whole and byte by byte; then the recording of a real Okuma MULTUS
 * (../shared/mtconnect) fed in random pieces, its counts checked against a
 * plain scan of the file's lines. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "protocols/mtconnect/mtconnect.h"
#include "test.h"

typedef struct seen {
    int observations, conditions, messages, assets, commands, malformed;
    long pong;
    char last_key[64], last_value[256], last_code[64], last_message[256];
    double last_time;
    uint64_t last_line;
    char asset_id[64], asset_type[64], asset_command[32];
    char asset_body[4096];
    size_t asset_size;
    uint64_t malformed_line[16];
    size_t malformed_column[16];
    char malformed_why[16][256];
    /* The recording's figures. */
    long x1actw, x1actw_unavailable;
    double x1actw_first;
} seen;

static void on_obs(void *ctx, const fm_shdr_observation *o)
{
    seen *s = ctx;
    s->observations++;
    if (o->kind == FM_SHDR_CONDITION) s->conditions++;
    if (o->kind == FM_SHDR_MESSAGE) s->messages++;
    snprintf(s->last_key, sizeof s->last_key, "%s", o->key);
    snprintf(s->last_value, sizeof s->last_value, "%s", o->value);
    snprintf(s->last_code, sizeof s->last_code, "%s", o->native_code);
    snprintf(s->last_message, sizeof s->last_message, "%s", o->message);
    s->last_time = o->timestamp;
    s->last_line = o->line;
    if (!strcmp(o->key, "X1actw")) {
        if (!strcmp(o->value, "UNAVAILABLE")) {
            s->x1actw_unavailable++;
        } else {
            if (!s->x1actw) s->x1actw_first = atof(o->value);
            s->x1actw++;
        }
    }
}

static void on_asset(void *ctx, const fm_shdr_asset *a)
{
    seen *s = ctx;
    s->assets++;
    snprintf(s->asset_id, sizeof s->asset_id, "%s", a->id);
    snprintf(s->asset_type, sizeof s->asset_type, "%s", a->type);
    snprintf(s->asset_command, sizeof s->asset_command, "%s", a->command);
    snprintf(s->asset_body, sizeof s->asset_body, "%.*s", (int)a->size, a->body);
    s->asset_size = a->size;
}

static void on_command(void *ctx, const char *text, long pong_ms)
{
    seen *s = ctx;
    (void)text;
    s->commands++;
    if (pong_ms > 0) s->pong = pong_ms;
}

static void on_malformed(void *ctx, uint64_t line, size_t column, const char *why)
{
    seen *s = ctx;
    if (s->malformed < 16) {
        s->malformed_line[s->malformed] = line;
        s->malformed_column[s->malformed] = column;
        snprintf(s->malformed_why[s->malformed], sizeof s->malformed_why[0], "%s", why);
    }
    s->malformed++;
}

static fm_shdr_reader *reader_for(seen *s, const fm_shdr_limits *limits)
{
    memset(s, 0, sizeof *s);
    fm_shdr_handlers h = {s, NULL, on_obs, on_asset, on_command, on_malformed};
    return fm_shdr_reader_new(limits, &h);
}

/* Feed text one byte at a time (every split point) and whole; both must
 * see the same. */
static void feed_both(const char *text, seen *whole, seen *bytes, const fm_shdr_limits *limits)
{
    fm_shdr_reader *r = reader_for(whole, limits);
    fm_shdr_reader_feed(r, text, strlen(text));
    fm_shdr_reader_finish(r);
    fm_shdr_reader_free(r);
    r = reader_for(bytes, limits);
    for (size_t i = 0; text[i]; i++) fm_shdr_reader_feed(r, text + i, 1);
    fm_shdr_reader_finish(r);
    fm_shdr_reader_free(r);
}

static void test_time(void)
{
    double t = -1;
    CHECK(fm_mtc_parse_time("1970-01-01T00:00:00Z", 20, &t) == 0);
    CHECK_NEAR(t, 0.0, 0.0);
    /* 2000-03-01: 30 years of 365 days, 7 leap days (1972..1996), then
     * January's 31 and the leap February's 29: 11017 days. */
    CHECK(fm_mtc_parse_time("2000-03-01T00:00:00Z", 20, &t) == 0);
    CHECK_NEAR(t, 11017.0 * 86400.0, 0.0);
    CHECK(fm_mtc_parse_time("2000-03-01T01:00:00+01:00", 25, &t) == 0);
    CHECK_NEAR(t, 11017.0 * 86400.0, 0.0);
    CHECK(fm_mtc_parse_time("2000-03-01T00:00:01.2500000Z", 28, &t) == 0);
    CHECK_NEAR(t, 11017.0 * 86400.0 + 1.25, 1e-6);
    CHECK(fm_mtc_parse_time("2000-02-30T00:00:00Z", 20, &t) != 0);
    CHECK(fm_mtc_parse_time("2000-13-01T00:00:00Z", 20, &t) != 0);
    CHECK(fm_mtc_parse_time("2000-03-01T00:00Z", 17, &t) != 0);
    CHECK(fm_mtc_parse_time("2000-03-01T00:00:00.Z", 21, &t) != 0);
    CHECK(fm_mtc_parse_time("2000-03-01T00:00:00Zx", 21, &t) != 0);
}

static void test_lines(void)
{
    seen a, b;
    const char *text =
        "2000-03-01T00:00:01Z|Xact|12.5|Zact|-3.25\n"
        "2000-03-01T00:00:02Z|system|FAULT|E42|2|HIGH|overtravel on Z\r\n"
        "2000-03-01T00:00:03Z|Xact|UNAVAILABLE\n"
        "* PONG 10000\n"
        "* shdrVersion: 2\n"
        "\n"
        "2000-03-01T00:00:04Z|@ASSET@|T1|CuttingTool|<CuttingTool assetId=\"T1\">a|b</CuttingTool>\n"
        "2000-03-01T00:00:05Z|@ASSET@|T2|CuttingTool|--multiline--XYZ\n"
        "<CuttingTool assetId=\"T2\">\n"
        "<Description>two lines</Description></CuttingTool>\n"
        "--multiline--XYZ\n"
        "2000-03-01T00:00:06Z|@REMOVE_ASSET@|T1\n"
        "not a time|Xact|1\n"
        "2000-03-01T00:00:07Z|Xact\n"
        "|Yact|7\n";
    feed_both(text, &a, &b, NULL);
    seen *all[2] = {&a, &b};
    for (int k = 0; k < 2; k++) {
        seen *s = all[k];
        /* Xact, Zact; the condition; Xact UNAVAILABLE; Yact. */
        CHECK(s->observations == 5);
        CHECK(s->conditions == 1);
        CHECK(s->pong == 10000);
        CHECK(s->commands == 2);
        CHECK(s->assets == 3);
        CHECK(!strcmp(s->asset_command, "@REMOVE_ASSET@"));
        CHECK(!strcmp(s->asset_id, "T1"));
        CHECK(s->malformed == 2);
        CHECK(s->malformed_line[0] == 13 && s->malformed_column[0] == 1);
        CHECK_STR_CONTAINS(s->malformed_why[0], "timestamp");
        CHECK(s->malformed_line[1] == 14);
        CHECK_STR_CONTAINS(s->malformed_why[1], "Xact");
        CHECK(!strcmp(s->last_key, "Yact") && !strcmp(s->last_value, "7"));
        CHECK(isnan(s->last_time));
        CHECK(s->last_line == 15);
    }
    /* The condition's fields, and the multiline asset's body. */
    seen c;
    fm_shdr_reader *r = reader_for(&c, NULL);
    const char *cond = "2000-03-01T00:00:02Z|system|FAULT|E42|2|HIGH|overtravel on Z\n";
    fm_shdr_reader_feed(r, cond, strlen(cond));
    CHECK(c.conditions == 1 && !strcmp(c.last_value, "FAULT") && !strcmp(c.last_code, "E42"));
    CHECK(!strcmp(c.last_message, "overtravel on Z"));
    CHECK_NEAR(c.last_time, 11017.0 * 86400.0 + 2.0, 1e-9);
    const char *single = "2000-03-01T00:00:04Z|@ASSET@|T1|CuttingTool|<a>x|y</a>\n";
    fm_shdr_reader_feed(r, single, strlen(single));
    CHECK(!strcmp(c.asset_body, "<a>x|y</a>") && c.asset_size == 10);
    CHECK(!strcmp(c.asset_type, "CuttingTool"));
    const char *multi = "2000-03-01T00:00:05Z|@ASSET@|T2|CuttingTool|--multiline--Q\n<a>\n</a>\n--multiline--Q\n";
    fm_shdr_reader_feed(r, multi, strlen(multi));
    CHECK(!strcmp(c.asset_body, "<a>\n</a>") && !strcmp(c.asset_id, "T2"));
    /* An open asset at the end is reported, never given. */
    const char *open = "2000-03-01T00:00:05Z|@ASSET@|T3|CuttingTool|--multiline--R\n<a>\n";
    fm_shdr_reader_feed(r, open, strlen(open));
    int assets = c.assets;
    fm_shdr_reader_finish(r);
    CHECK(c.assets == assets && c.malformed == 1);
    CHECK_STR_CONTAINS(c.malformed_why[0], "never ended");
    fm_shdr_reader_free(r);
}

static void test_bounds(void)
{
    fm_shdr_limits limits = {128, 256, 8};
    seen s;
    fm_shdr_reader *r = reader_for(&s, &limits);
    char line[400];
    memset(line, 'x', sizeof line);
    memcpy(line, "2000-03-01T00:00:01Z|k|", 23);
    line[sizeof line - 1] = '\n';
    fm_shdr_reader_feed(r, line, sizeof line);
    CHECK(s.malformed == 1 && s.observations == 0);
    CHECK_STR_CONTAINS(s.malformed_why[0], "over 128 bytes");
    /* Nine fields: over max_fields (8). */
    const char *wide = "2000-03-01T00:00:01Z|a|1|b|2|c|3|d|4\n";
    fm_shdr_reader_feed(r, wide, strlen(wide));
    CHECK(s.malformed == 2 && s.observations == 0);
    /* A multiline asset over 256 bytes is skipped to its end; the next line
     * is read again. */
    const char *head = "2000-03-01T00:00:05Z|@ASSET@|T9|CuttingTool|--multiline--Z\n";
    fm_shdr_reader_feed(r, head, strlen(head));
    for (int i = 0; i < 10; i++) fm_shdr_reader_feed(r, "<a>0123456789012345678901234567890123456789</a>\n", 48);
    fm_shdr_reader_feed(r, "--multiline--Z\n2000-03-01T00:00:06Z|k|v\n", 40);
    CHECK(s.assets == 0 && s.malformed == 3 && s.observations == 1);
    CHECK_STR_CONTAINS(s.malformed_why[2], "over 256 bytes");
    /* A NUL byte inside a line. */
    fm_shdr_reader_feed(r, "2000-03-01T00:00:06Z|k|v\0w\n", 27);
    CHECK(s.malformed == 4 && s.observations == 1);
    fm_shdr_reader_finish(r);
    fm_shdr_reader_free(r);
}

/* The recording: every line parses, and the reader sees as many X1actw
 * values and assets as a plain scan of the lines finds. */
static int test_recording(const char *data_dir)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/recordings/okuma_multus_imts2022.shdr", data_dir);
    char *text = NULL;
    size_t text_size = 0;
    fm_error err;
    if (fm_file_read(path, "SHDR recording", (size_t)64 << 20, &text, &text_size, &err) != FM_OK) return 0;
    long size = (long)text_size;
    /* The scan: the fields of each line, "|X1actw|" followed by a value,
     * and lines whose second field is @ASSET@. */
    long x_values = 0, x_unavailable = 0, assets = 0, lines = 0;
    double x_first = NAN;
    for (char *p = text; *p;) {
        char *nl = strchr(p, '\n');
        size_t n = nl ? (size_t)(nl - p) : strlen(p);
        lines++;
        const char *bar = memchr(p, '|', n);
        if (bar && !strncmp(bar, "|@ASSET@|", 9)) assets++;
        for (const char *q = p; q < p + n; q++) {
            if (!strncmp(q, "|X1actw|", 8) && q + 8 <= p + n) {
                if (!strncmp(q + 8, "UNAVAILABLE", 11)) {
                    x_unavailable++;
                } else {
                    if (!x_values) x_first = atof(q + 8);
                    x_values++;
                }
            }
        }
        p += n + (nl ? 1 : 0);
    }
    seen s;
    fm_shdr_reader *r = reader_for(&s, NULL);
    for (long at = 0; at < size;) {
        long piece = 1 + (long)(test_rand01() * 3000);
        if (at + piece > size) piece = size - at;
        fm_shdr_reader_feed(r, text + at, (size_t)piece);
        at += piece;
    }
    fm_shdr_reader_finish(r);
    fm_shdr_reader_free(r);
    printf("recording: %ld lines, %d observations, %d conditions, %d assets, X1actw %ld (+%ld "
           "UNAVAILABLE), %d malformed\n",
           lines, s.observations, s.conditions, s.assets, s.x1actw, s.x1actw_unavailable, s.malformed);
    for (int i = 0; i < s.malformed && i < 16; i++)
        printf("  line %llu column %zu: %s\n", (unsigned long long)s.malformed_line[i], s.malformed_column[i],
               s.malformed_why[i]);
    CHECK(s.malformed == 0);
    CHECK(x_values > 100);
    CHECK(s.x1actw == x_values && s.x1actw_unavailable == x_unavailable);
    CHECK_NEAR(s.x1actw_first, x_first, 0.0);
    CHECK(s.assets >= assets && assets > 0);
    free(text);
    return 1;
}

int main(int argc, char **argv)
{
    test_time();
    test_lines();
    test_bounds();
    const char *data = argc > 1 ? argv[1] : "../../shared/mtconnect";
    if (!test_recording(data)) {
        if (test_summary("mtconnect_shdr")) return 1;
        return test_skip("the MTConnect recording is missing (../shared/mtconnect/recordings; "
                         "cmake -DFM_MTCONNECT_DATA=...)");
    }
    return test_summary("mtconnect_shdr");
}
