/* line.c: what every dialect reads a line with: a source line normalized
 * (lower case, no spaces or tabs, comments removed, each character's source
 * column kept for errors; (debug,...) and (msg,...) comments noted, every
 * comment handed to fm_gcode_options.comment), the
 * error helper that names file:line:column, G-code names for messages, and
 * questions about a block's words. */
#include "machine.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

fm_status gc_fail(gc_interp *g, fm_status code, int column, const char *fmt, ...)
{
    char msg[sizeof g->err->message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return fm_error_at(g->err, code, g->line_name ? g->line_name : g->name, g->lineno, column,
                       "%s", msg);
}

int gc_col(const gc_line *ln, size_t p)
{
    if (p > ln->n) p = ln->n;
    return ln->col[p];
}

static int line_reserve(gc_line *ln, size_t n)
{
    if (n + 1 <= ln->cap) return 1;
    size_t cap = ln->cap ? ln->cap : 128;
    while (cap < n + 1) cap *= 2;
    char *s = realloc(ln->s, cap);
    if (!s) return 0;
    ln->s = s;
    int *c = realloc(ln->col, cap * sizeof *c);
    if (!c) return 0;
    ln->col = c;
    ln->cap = cap;
    return 1;
}

/* A (debug,...) or (msg,...) comment: 1 or 2, and where its text starts. */
static int message_kind(const char *c, size_t n, size_t *skip)
{
    static const char *const kinds[2] = {"debug,", "msg,"};
    for (int k = 0; k < 2; k++) {
        size_t m = strlen(kinds[k]);
        if (n < m) continue;
        size_t i = 0;
        while (i < m && (c[i] | 0x20) == kinds[k][i]) i++;
        if (i == m) {
            *skip = m;
            return k + 1;
        }
    }
    return 0;
}

fm_status gc_normalize(gc_interp *g, size_t idx, gc_line *out, int report)
{
    const char *t;
    size_t len;
    gc_line_text(g, idx, &t, &len);
    if (!line_reserve(out, len + 1))
        return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory normalizing line %zu", idx + 1);
    size_t n = 0, comment_at = 0;
    int in_comment = 0, comment_col = 0;
    out->msg_kind = 0;
    for (size_t i = 0; i < len; i++) {
        unsigned char c = (unsigned char)t[i];
        int column = (int)i + 1;
        if (c == '\n' || c == '\r') continue;
        if (c == '\0') {
            if (!report) return FM_ERR_INPUT;
            return gc_fail(g, FM_ERR_INPUT, column, "NUL byte in the program; expected text");
        }
        if (in_comment) {
            if (c == ')') {
                in_comment = 0;
                size_t skip, clen = i - comment_at;
                if (report && g->opt.comment)
                    g->opt.comment(g->opt.comment_user, g->lineno, t + comment_at, clen);
                int kind = message_kind(t + comment_at, clen, &skip);
                if (kind) {
                    out->msg_kind = kind;
                    out->msg = t + comment_at + skip;
                    out->msg_len = clen - skip;
                }
            } else if (c == '(' && report)
                return gc_fail(g, FM_ERR_INPUT, column,
                               "nested comment: '(' inside the comment opened at column %d; "
                               "expected ')' first", comment_col);
            else if (c == '(') return FM_ERR_INPUT;
            continue;
        }
        if (c == '(') {
            in_comment = 1;
            comment_col = column;
            comment_at = i + 1;
            continue;
        }
        if (c == ';') {
            if (report && g->opt.comment) {
                size_t e = len;
                while (e > i + 1 && (t[e - 1] == '\n' || t[e - 1] == '\r')) e--;
                g->opt.comment(g->opt.comment_user, g->lineno, t + i + 1, e - i - 1);
            }
            break;
        }
        if (c == ' ' || c == '\t') continue;
        if (c >= 'A' && c <= 'Z') c = (unsigned char)(c - 'A' + 'a');
        out->s[n] = (char)c;
        out->col[n] = column;
        n++;
    }
    if (in_comment) {
        if (!report) return FM_ERR_INPUT;
        return gc_fail(g, FM_ERR_INPUT, comment_col,
                       "unclosed comment: '(' without ')'; expected ')' before the end of the line");
    }
    out->s[n] = '\0';
    out->col[n] = (int)len + 1;
    out->n = n;
    return FM_OK;
}

void gc_g_name(int code, char *buf, size_t n)
{
    if (code % 10) snprintf(buf, n, "G%d.%d", code / 10, code % 10);
    else snprintf(buf, n, "G%d", code / 10);
}

int gc_block_has_m(const gc_block *b, int m, int *col)
{
    for (int i = 0; i < b->nm; i++)
        if (b->m[i] == m) {
            if (col) *col = b->mcol[i];
            return 1;
        }
    return 0;
}

int gc_block_has_axis(const gc_block *b)
{
    return HAS(b, 'x') || HAS(b, 'y') || HAS(b, 'z') || HAS(b, 'a') || HAS(b, 'b') ||
           HAS(b, 'c') || HAS(b, 'u') || HAS(b, 'v') || HAS(b, 'w');
}

int gc_first_axis_col(const gc_block *b)
{
    const char *ax = "xyzabcuvw";
    int best = 0;
    for (const char *a = ax; *a; a++)
        if (HAS(b, *a) && (!best || COL(b, *a) < best)) best = COL(b, *a);
    return best;
}
