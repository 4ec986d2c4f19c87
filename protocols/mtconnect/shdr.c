/* shdr.c: the SHDR reader (the adapter protocol, docs/mtconnect.md). Bytes
 * arrive in any pieces; each complete line is split at '|' into a
 * timestamp and key/value fields, asset commands (single or multiline
 * blocks between two "--multiline--TAG" lines), or a "* ..." protocol line
 * (the heartbeat's PONG). Every size is bounded: a line over max_line, an
 * asset over max_asset or a line of more than max_fields fields is reported
 * with its line number and skipped, as is any line that does not parse. */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mtconnect.h"

#define MULTILINE_PREFIX "--multiline--"

struct fm_shdr_reader {
    fm_shdr_limits limits;
    fm_shdr_handlers h;
    char *line;             /* the line being gathered: max_line + 1 bytes */
    size_t line_len;
    int line_too_long;      /* skipping to the end of an overlong line */
    uint64_t line_no;       /* of the line being gathered */
    char **fields;          /* max_fields pointers into line */
    size_t *columns;        /* where each field starts (0-based) */

    /* An open multiline asset. */
    int in_asset;
    int asset_too_large;
    char asset_command[24];
    char asset_id[256];
    char asset_type[64];
    char asset_tag[96];     /* the whole terminator line "--multiline--TAG" */
    double asset_time;
    uint64_t asset_line;
    char *asset_body;
    size_t asset_len, asset_cap;
};

/* ------------------------------------------------------------- time -- */

static int digits(const char *s, size_t len, size_t at, int n, int *out)
{
    int v = 0;
    if (at + (size_t)n > len) return 0;
    for (int i = 0; i < n; i++) {
        if (!isdigit((unsigned char)s[at + (size_t)i])) return 0;
        v = v * 10 + (s[at + (size_t)i] - '0');
    }
    *out = v;
    return 1;
}

/* Days from 1970-01-01 of a proleptic Gregorian date (Howard Hinnant's
 * days_from_civil), so that no time zone or locale is involved. */
static long days_from_civil(long y, int m, int d)
{
    y -= m <= 2;
    long era = (y >= 0 ? y : y - 399) / 400;
    long yoe = y - era * 400;
    long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return era * 146097 + doe - 719468;
}

int fm_mtc_parse_time(const char *s, size_t len, double *out)
{
    int y, mo, d, h, mi, sec;
    if (!digits(s, len, 0, 4, &y) || len < 19 || s[4] != '-' || !digits(s, len, 5, 2, &mo) ||
        s[7] != '-' || !digits(s, len, 8, 2, &d) || (s[10] != 'T' && s[10] != ' ') ||
        !digits(s, len, 11, 2, &h) || s[13] != ':' || !digits(s, len, 14, 2, &mi) || s[16] != ':' ||
        !digits(s, len, 17, 2, &sec))
        return -1;
    static const int month_days[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (mo < 1 || mo > 12 || d < 1 || d > month_days[mo - 1] || h > 23 || mi > 59 || sec > 60)
        return -1;
    size_t at = 19;
    double frac = 0.0, scale = 0.1;
    if (at < len && s[at] == '.') {
        at++;
        size_t start = at;
        while (at < len && isdigit((unsigned char)s[at])) {
            if (scale > 1e-12) frac += (s[at] - '0') * scale;
            scale *= 0.1;
            at++;
        }
        if (at == start) return -1;
    }
    long offset_s = 0;
    if (at < len && s[at] == 'Z') {
        at++;
    } else if (at < len && (s[at] == '+' || s[at] == '-')) {
        int oh, om;
        int sign = s[at] == '-' ? -1 : 1;
        if (!digits(s, len, at + 1, 2, &oh) || at + 3 >= len || s[at + 3] != ':' ||
            !digits(s, len, at + 4, 2, &om) || oh > 23 || om > 59)
            return -1;
        offset_s = sign * (oh * 3600L + om * 60L);
        at += 6;
    }
    if (at != len) return -1;
    double days = (double)days_from_civil(y, mo, d);
    *out = days * 86400.0 + h * 3600.0 + mi * 60.0 + sec + frac - (double)offset_s;
    return 0;
}

/* ----------------------------------------------------------- reader -- */

fm_shdr_reader *fm_shdr_reader_new(const fm_shdr_limits *limits, const fm_shdr_handlers *handlers)
{
    fm_shdr_reader *r = calloc(1, sizeof *r);
    if (!r) return NULL;
    r->limits.max_line = 65536;
    r->limits.max_asset = 1u << 20;
    r->limits.max_fields = 4096;
    if (limits) {
        if (limits->max_line >= 64) r->limits.max_line = limits->max_line;
        if (limits->max_asset >= 64) r->limits.max_asset = limits->max_asset;
        if (limits->max_fields >= 8) r->limits.max_fields = limits->max_fields;
    }
    if (handlers) r->h = *handlers;
    r->line = malloc(r->limits.max_line + 1);
    r->fields = malloc(sizeof *r->fields * (size_t)r->limits.max_fields);
    r->columns = malloc(sizeof *r->columns * (size_t)r->limits.max_fields);
    if (!r->line || !r->fields || !r->columns) {
        fm_shdr_reader_free(r);
        return NULL;
    }
    r->line_no = 1;
    return r;
}

void fm_shdr_reader_free(fm_shdr_reader *r)
{
    if (!r) return;
    free(r->line);
    free(r->fields);
    free(r->columns);
    free(r->asset_body);
    free(r);
}

static void malformed(fm_shdr_reader *r, uint64_t line, size_t column, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static void malformed(fm_shdr_reader *r, uint64_t line, size_t column, const char *fmt, ...)
{
    if (!r->h.malformed) return;
    char why[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    r->h.malformed(r->h.ctx, line, column, why);
}

static void emit_asset(fm_shdr_reader *r, double ts, const char *command, const char *id,
                       const char *type, const char *body, size_t size, uint64_t line)
{
    if (!r->h.asset) return;
    fm_shdr_asset a = {ts, command, id, type, body, size, line};
    r->h.asset(r->h.ctx, &a);
}

static int asset_append(fm_shdr_reader *r, const char *text, size_t n)
{
    size_t need = r->asset_len + n + 2;
    if (need > r->limits.max_asset + 2) return -1;
    if (need > r->asset_cap) {
        size_t cap = r->asset_cap ? r->asset_cap : 4096;
        while (cap < need) cap *= 2;
        char *b = realloc(r->asset_body, cap);
        if (!b) return -1;
        r->asset_body = b;
        r->asset_cap = cap;
    }
    if (r->asset_len) r->asset_body[r->asset_len++] = '\n';
    memcpy(r->asset_body + r->asset_len, text, n);
    r->asset_len += n;
    r->asset_body[r->asset_len] = '\0';
    return 0;
}

static void asset_line(fm_shdr_reader *r, char *line, size_t len)
{
    if (!strcmp(line, r->asset_tag)) {
        r->in_asset = 0;
        if (r->asset_too_large) return; /* reported when it overflowed */
        emit_asset(r, r->asset_time, r->asset_command, r->asset_id, r->asset_type,
                   r->asset_body ? r->asset_body : "", r->asset_len, r->asset_line);
        return;
    }
    if (r->asset_too_large) return;
    if (asset_append(r, line, len) != 0) {
        r->asset_too_large = 1;
        malformed(r, r->asset_line, 1,
                  "the multiline asset %s is over %zu bytes (or memory ran out); skipped to its end",
                  r->asset_id, r->limits.max_asset);
    }
}

static int is_level(const char *v)
{
    return !strcmp(v, "NORMAL") || !strcmp(v, "WARNING") || !strcmp(v, "FAULT");
}

static void copy_field(char *dst, size_t cap, const char *src)
{
    snprintf(dst, cap, "%s", src);
}

static void asset_command(fm_shdr_reader *r, char *raw, size_t raw_len, int n, double ts)
{
    char **f = r->fields;
    const char *cmd = f[1];
    uint64_t ln = r->line_no;
    if (!strcmp(cmd, "@REMOVE_ALL_ASSETS@")) {
        emit_asset(r, ts, cmd, n > 2 ? f[2] : "", "", "", 0, ln);
        return;
    }
    if (!strcmp(cmd, "@REMOVE_ASSET@")) {
        if (n < 3 || !f[2][0]) {
            malformed(r, ln, r->columns[1] + 1, "@REMOVE_ASSET@ needs an asset id");
            return;
        }
        emit_asset(r, ts, cmd, f[2], "", "", 0, ln);
        return;
    }
    int update = !strcmp(cmd, "@UPDATE_ASSET@");
    if (!update && strcmp(cmd, "@ASSET@")) {
        malformed(r, ln, r->columns[1] + 1, "unknown asset command %.40s", cmd);
        return;
    }
    /* @ASSET@|id|type|document and @UPDATE_ASSET@|id|document: the document
     * is the rest of the line, '|' included. */
    int body_field = update ? 3 : 4;
    if (n < body_field + 1 || !f[2][0]) {
        malformed(r, ln, r->columns[1] + 1, "%s needs an id%s and a document", cmd,
                  update ? "" : ", a type");
        return;
    }
    char *body = raw + r->columns[body_field];
    const char *type = update ? "" : f[3];
    if (!strncmp(body, MULTILINE_PREFIX, strlen(MULTILINE_PREFIX)) && !strchr(body, '<')) {
        if (strlen(body) >= sizeof r->asset_tag || strlen(f[2]) >= sizeof r->asset_id ||
            strlen(type) >= sizeof r->asset_type) {
            malformed(r, ln, r->columns[body_field] + 1, "the multiline asset's id, type or tag is too long");
            return;
        }
        r->in_asset = 1;
        r->asset_too_large = 0;
        r->asset_len = 0;
        if (r->asset_body) r->asset_body[0] = '\0';
        copy_field(r->asset_command, sizeof r->asset_command, cmd);
        copy_field(r->asset_id, sizeof r->asset_id, f[2]);
        copy_field(r->asset_type, sizeof r->asset_type, type);
        copy_field(r->asset_tag, sizeof r->asset_tag, body);
        r->asset_time = ts;
        r->asset_line = ln;
        return;
    }
    /* The rest of the line, with its '|' put back. */
    for (int i = body_field + 1; i < n; i++) f[i][-1] = '|';
    emit_asset(r, ts, cmd, f[2], type, body, raw_len - r->columns[body_field], ln);
}

static void data_line(fm_shdr_reader *r, char *line, size_t len)
{
    uint64_t ln = r->line_no;
    /* "* PONG 10000", "* shdrVersion: 2"; some adapters write no space
     * ("*adapterVersion:UNAVAILABLE"). */
    if (line[0] == '*') {
        if (!r->h.command) return;
        const char *text = line + 1;
        while (*text == ' ') text++;
        long pong = -1;
        if (!strncmp(text, "PONG", 4) && (text[4] == ' ' || text[4] == '\0')) {
            char *end;
            long v = strtol(text + 4, &end, 10);
            while (*end == ' ') end++;
            if (*end != '\0' || v <= 0 || v > 86400000L) {
                malformed(r, ln, (size_t)(text - line) + 5, "a PONG must give its heartbeat in ms (1..86400000)");
                return;
            }
            pong = v;
        }
        r->h.command(r->h.ctx, text, pong);
        return;
    }
    /* Split at '|' in place, remembering where each field started. */
    int n = 0;
    char *p = line;
    for (;;) {
        if (n == r->limits.max_fields) {
            malformed(r, ln, (size_t)(p - line) + 1, "more than %d fields on one line", r->limits.max_fields);
            return;
        }
        r->fields[n] = p;
        r->columns[n] = (size_t)(p - line);
        n++;
        char *bar = memchr(p, '|', len - (size_t)(p - line));
        if (!bar) break;
        *bar = '\0';
        p = bar + 1;
    }
    double ts = NAN;
    const char *tsf = r->fields[0];
    if (tsf[0]) {
        size_t tlen = strlen(tsf);
        const char *at = strchr(tsf, '@'); /* a duration suffix, "time@seconds" */
        if (at) tlen = (size_t)(at - tsf);
        if (fm_mtc_parse_time(tsf, tlen, &ts) != 0) {
            malformed(r, ln, 1, "the timestamp \"%.40s\" is not YYYY-MM-DDTHH:MM:SS[.f][Z|+hh:mm]", tsf);
            return;
        }
    }
    if (n < 2) {
        malformed(r, ln, len + 1, "a line needs a timestamp and at least one key");
        return;
    }
    if (r->fields[1][0] == '@') {
        asset_command(r, line, len, n, ts);
        return;
    }
    int i = 1;
    while (i < n) {
        const char *key = r->fields[i];
        if (!key[0]) {
            /* A trailing '|' leaves an empty last field: nothing more. */
            if (i == n - 1) break;
            malformed(r, ln, r->columns[i] + 1, "an empty key");
            return;
        }
        fm_shdr_kind kind;
        if (r->h.kind) {
            kind = r->h.kind(r->h.ctx, key);
        } else {
            kind = FM_SHDR_VALUE;
            if (i == 1 && n == 7 &&
                (is_level(r->fields[2]) ||
                 (!strcmp(r->fields[2], "UNAVAILABLE") && !r->fields[3][0] && !r->fields[4][0] &&
                  !r->fields[5][0] && !r->fields[6][0])))
                kind = FM_SHDR_CONDITION;
        }
        int need = kind == FM_SHDR_CONDITION ? 5 : kind == FM_SHDR_MESSAGE ? 2 : 1;
        if (i + need > n - 1) {
            malformed(r, ln, r->columns[i] + 1, "the key %.64s has %d of its %d fields", key, n - 1 - i,
                      need);
            return;
        }
        fm_shdr_observation o;
        memset(&o, 0, sizeof o);
        o.timestamp = ts;
        o.key = key;
        o.kind = kind;
        o.line = ln;
        o.native_code = o.native_severity = o.qualifier = o.message = "";
        if (kind == FM_SHDR_CONDITION) {
            o.value = r->fields[i + 1];
            if (!is_level(o.value) && strcmp(o.value, "UNAVAILABLE")) {
                malformed(r, ln, r->columns[i + 1] + 1,
                          "the condition %.64s has the level \"%.20s\" (NORMAL, WARNING, FAULT or "
                          "UNAVAILABLE)",
                          key, o.value);
                return;
            }
            o.native_code = r->fields[i + 2];
            o.native_severity = r->fields[i + 3];
            o.qualifier = r->fields[i + 4];
            o.message = r->fields[i + 5];
        } else if (kind == FM_SHDR_MESSAGE) {
            o.native_code = r->fields[i + 1];
            o.value = r->fields[i + 2];
        } else {
            o.value = r->fields[i + 1];
        }
        if (r->h.observation) r->h.observation(r->h.ctx, &o);
        i += need + 1;
    }
}

static void end_line(fm_shdr_reader *r)
{
    if (r->line_too_long) {
        malformed(r, r->line_no, r->limits.max_line + 1, "the line is over %zu bytes; skipped",
                  r->limits.max_line);
    } else {
        size_t len = r->line_len;
        if (len && r->line[len - 1] == '\r') len--;
        r->line[len] = '\0';
        if (memchr(r->line, '\0', len)) {
            malformed(r, r->line_no, (size_t)(strlen(r->line)) + 1, "a NUL byte in the line; skipped");
        } else if (r->in_asset) {
            asset_line(r, r->line, len);
        } else if (len) {
            data_line(r, r->line, len);
        }
    }
    r->line_len = 0;
    r->line_too_long = 0;
    r->line_no++;
}

void fm_shdr_reader_feed(fm_shdr_reader *r, const char *data, size_t size)
{
    if (!r) return;
    while (size) {
        const char *nl = memchr(data, '\n', size);
        size_t n = nl ? (size_t)(nl - data) : size;
        if (!r->line_too_long) {
            if (r->line_len + n > r->limits.max_line) {
                r->line_too_long = 1;
            } else {
                memcpy(r->line + r->line_len, data, n);
                r->line_len += n;
            }
        }
        if (!nl) return;
        end_line(r);
        data = nl + 1;
        size -= n + 1;
    }
}

void fm_shdr_reader_finish(fm_shdr_reader *r)
{
    if (!r) return;
    if (r->line_len || r->line_too_long) end_line(r);
    if (r->in_asset) {
        if (!r->asset_too_large)
            malformed(r, r->asset_line, 1, "the multiline asset %s never ended (%s)", r->asset_id,
                      r->asset_tag);
        r->in_asset = 0;
    }
}
