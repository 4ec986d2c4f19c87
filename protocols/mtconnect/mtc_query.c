/* mtc_query.c: the REST protocol's request parameters (from, count, at,
 * interval, heartbeat, path, type) from a raw, percent-encoded query
 * string, and the XPath subset of the path parameter (mtconnect.h says
 * which). Bounded: a query of at most 2048 bytes, a path of 511, eight
 * alternatives. Errors carry the MTConnect error code as their reason. */
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mtc_internal.h"
#include "mtconnect.h"

#define QUERY_MAX 2048

static int hex_value(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* Decode s[0..len) into out (cap bytes); -1 on a bad escape, a NUL or when
 * it does not fit. */
static int percent_decode(const char *s, size_t len, char *out, size_t cap)
{
    size_t o = 0;
    for (size_t i = 0; i < len; i++) {
        char c = s[i];
        if (c == '+') {
            c = ' ';
        } else if (c == '%') {
            if (i + 2 >= len) return -1;
            int hi = hex_value(s[i + 1]), lo = hex_value(s[i + 2]);
            if (hi < 0 || lo < 0) return -1;
            c = (char)(hi * 16 + lo);
            i += 2;
        }
        if (c == '\0' || o + 1 >= cap) return -1;
        out[o++] = c;
    }
    out[o] = '\0';
    return 0;
}

static fm_status query_error(fm_error *err, const char *code, const char *fmt, const char *a)
{
    return fm_error_set_reason(err, FM_ERR_INPUT, code, fmt, a);
}

int mtc_parse_sequence(const char *text, uint64_t *out)
{
    uint64_t v = 0;
    if (!*text) return -1;
    for (const char *c = text; *c; c++) {
        if (*c < '0' || *c > '9') return -1;
        unsigned d = (unsigned)(*c - '0');
        if (v > (UINT64_MAX - d) / 10) return -1;
        v = v * 10 + d;
    }
    *out = v;
    return 0;
}

/* from and at: a sequence number the buffer can hold (at most 2^63). */
static int parse_unsigned(const char *v, uint64_t *out)
{
    uint64_t n;
    if (mtc_parse_sequence(v, &n) != 0 || n > (1ULL << 63)) return -1;
    *out = n;
    return 0;
}

static int parse_signed(const char *v, long *out)
{
    if (!isdigit((unsigned char)v[0]) && !(v[0] == '-' && isdigit((unsigned char)v[1]))) return -1;
    errno = 0;
    char *end;
    long n = strtol(v, &end, 10);
    if (errno || *end) return -1;
    *out = n;
    return 0;
}

fm_status fm_mtc_query_parse(const char *query, size_t len, fm_mtc_query *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    out->count = 100;
    out->heartbeat_ms = 10000;
    if (!query) return FM_OK;
    if (len > QUERY_MAX)
        return fm_error_set_reason(err, FM_ERR_INPUT, "QUERY_ERROR",
                                   "the query is %zu bytes; at most %d", len, QUERY_MAX);
    size_t at = 0;
    while (at < len) {
        const char *amp = memchr(query + at, '&', len - at);
        size_t end = amp ? (size_t)(amp - query) : len;
        if (end > at) {
            const char *eq = memchr(query + at, '=', end - at);
            size_t key_end = eq ? (size_t)(eq - query) : end;
            char key[32], value[512];
            if (percent_decode(query + at, key_end - at, key, sizeof key) != 0)
                return fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_REQUEST",
                                           "a query parameter's name is not one the agent takes");
            const char *vs = eq ? eq + 1 : query + end;
            if (percent_decode(vs, (size_t)(query + end - vs), value, sizeof value) != 0)
                return query_error(err, "QUERY_ERROR",
                                   "the value of %s is too long or badly percent-encoded", key);
            int *has = NULL;
            if (!strcmp(key, "from")) {
                has = &out->has_from;
                if (!*has && parse_unsigned(value, &out->from) != 0)
                    return query_error(err, "QUERY_ERROR", "from must be a sequence number, not \"%s\"",
                                       value);
            } else if (!strcmp(key, "at")) {
                has = &out->has_at;
                if (!*has && parse_unsigned(value, &out->at) != 0)
                    return query_error(err, "QUERY_ERROR", "at must be a sequence number, not \"%s\"",
                                       value);
            } else if (!strcmp(key, "count")) {
                has = &out->has_count;
                if (!*has && (parse_signed(value, &out->count) != 0 || out->count == 0))
                    return query_error(err, "QUERY_ERROR",
                                       "count must be a non-zero whole number, not \"%s\"", value);
            } else if (!strcmp(key, "interval")) {
                has = &out->has_interval;
                if (!*has && (parse_signed(value, &out->interval_ms) != 0 || out->interval_ms < 0 ||
                              out->interval_ms > 2147483646L))
                    return query_error(err, "QUERY_ERROR",
                                       "interval must be 0..2147483646 milliseconds, not \"%s\"", value);
            } else if (!strcmp(key, "heartbeat")) {
                has = &out->has_heartbeat;
                if (!*has && (parse_signed(value, &out->heartbeat_ms) != 0 || out->heartbeat_ms < 10 ||
                              out->heartbeat_ms > 600000))
                    return query_error(err, "QUERY_ERROR",
                                       "heartbeat must be 10..600000 milliseconds, not \"%s\"", value);
            } else if (!strcmp(key, "path")) {
                has = &out->has_path;
                snprintf(out->path, sizeof out->path, "%s", value);
            } else if (!strcmp(key, "type")) {
                if (strlen(value) >= sizeof out->type)
                    return query_error(err, "QUERY_ERROR", "the asset type %s is too long", value);
                snprintf(out->type, sizeof out->type, "%s", value);
            } else {
                return query_error(err, "INVALID_REQUEST",
                                   "the agent takes from, count, at, interval, heartbeat, path and type; "
                                   "not %s",
                                   key);
            }
            if (has) {
                if (*has) return query_error(err, "QUERY_ERROR", "%s is given twice", key);
                *has = 1;
            }
        }
        at = end + 1;
    }
    if (out->has_at && (out->has_from || out->has_interval))
        return fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_REQUEST",
                                   "at cannot be given with from or interval");
    return FM_OK;
}

/* ------------------------------------------------------------- path -- */

typedef struct cursor {
    const char *s;
    size_t at;
} cursor;

static void skip_space(cursor *c)
{
    while (c->s[c->at] == ' ') c->at++;
}

static int parse_step(cursor *c, fm_mtc_path_step *step, fm_error *err)
{
    size_t n = 0;
    if (c->s[c->at] == '*') {
        step->element[n++] = '*';
        c->at++;
    } else {
        while (isalpha((unsigned char)c->s[c->at])) {
            if (n + 1 >= sizeof step->element) {
                fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                                    "an element name at column %zu is too long", c->at + 1);
                return -1;
            }
            step->element[n++] = c->s[c->at++];
        }
    }
    step->element[n] = '\0';
    if (!n) {
        fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                            "an element name (Linear, DataItem, *...) is expected at column %zu",
                            c->at + 1);
        return -1;
    }
    if (c->s[c->at] != '[') return 0;
    c->at++;
    if (c->s[c->at] != '@') {
        fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                            "a predicate is [@attribute=\"value\"]; column %zu", c->at + 1);
        return -1;
    }
    c->at++;
    n = 0;
    while (isalpha((unsigned char)c->s[c->at])) {
        if (n + 1 >= sizeof step->attr) break;
        step->attr[n++] = c->s[c->at++];
    }
    step->attr[n] = '\0';
    static const char *const attrs[] = {"id", "name", "type", "subType", "category"};
    int known = 0;
    for (size_t i = 0; i < sizeof attrs / sizeof attrs[0]; i++)
        if (!strcmp(step->attr, attrs[i])) known = 1;
    if (!known) {
        fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                            "the attribute at column %zu is not id, name, type, subType or category",
                            c->at + 1);
        return -1;
    }
    if (c->s[c->at] != '=' || (c->s[c->at + 1] != '"' && c->s[c->at + 1] != '\'')) {
        fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                            "a quoted value is expected after @%s= at column %zu", step->attr,
                            c->at + 1);
        return -1;
    }
    char quote = c->s[c->at + 1];
    c->at += 2;
    n = 0;
    while (c->s[c->at] && c->s[c->at] != quote) {
        if (n + 1 >= sizeof step->value) {
            fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH", "a value at column %zu is too long",
                                c->at + 1);
            return -1;
        }
        step->value[n++] = c->s[c->at++];
    }
    step->value[n] = '\0';
    if (c->s[c->at] != quote || c->s[c->at + 1] != ']') {
        fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                            "the predicate is not closed (\"value\"]) at column %zu", c->at + 1);
        return -1;
    }
    c->at += 2;
    return 0;
}

fm_status fm_mtc_path_parse(const char *text, fm_mtc_path *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    cursor c = {text, 0};
    for (;;) {
        skip_space(&c);
        if (out->count == FM_MTC_PATH_MAX_ALTS)
            return fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                                       "at most %d alternatives joined by |", FM_MTC_PATH_MAX_ALTS);
        int steps = 0;
        fm_mtc_path_step *component = &out->alt[out->count].component;
        fm_mtc_path_step *item = &out->alt[out->count].item;
        while (c.s[c.at] == '/' && c.s[c.at + 1] == '/') {
            c.at += 2;
            fm_mtc_path_step step;
            memset(&step, 0, sizeof step);
            if (parse_step(&c, &step, err) != 0) return err->code;
            if (item->element[0])
                return fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                                           "nothing may follow //DataItem (column %zu)", c.at + 1);
            if (!strcmp(step.element, "DataItem")) {
                *item = step;
            } else if (component->element[0]) {
                return fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                                           "one component step per alternative (column %zu)", c.at + 1);
            } else {
                if (!strcmp(step.attr, "type") || !strcmp(step.attr, "subType") ||
                    !strcmp(step.attr, "category"))
                    return fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                                               "a component is selected by @id or @name (column %zu)",
                                               c.at + 1);
                *component = step;
            }
            steps++;
        }
        if (!steps)
            return fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                                       "each alternative starts with // (column %zu)", c.at + 1);
        out->count++;
        skip_space(&c);
        if (c.s[c.at] == '\0') return FM_OK;
        if (c.s[c.at] != '|')
            return fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH",
                                       "unexpected '%c' at column %zu (the subset is //Component[@a=\"v\"]"
                                       "//DataItem[@a=\"v\"] | ...)",
                                       c.s[c.at], c.at + 1);
        c.at++;
    }
}
