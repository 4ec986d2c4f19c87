/* traj_json.c: finds where values sit in the JSON text. jansson gives
 * positions only for syntax errors, so validation errors (a bad interval, an
 * expression that does not parse) locate their value again by walking the
 * raw text, which jansson has already accepted as valid JSON. */
#include "toolpaths/traj/traj_internal.h"

#include <string.h>

static size_t skip_ws(const char *s, size_t n, size_t i)
{
    while (i < n && (s[i] == ' ' || s[i] == '\t' || s[i] == '\n' || s[i] == '\r')) i++;
    return i;
}

/* i at the opening quote; returns the offset after the closing quote. */
static size_t skip_string(const char *s, size_t n, size_t i)
{
    for (i++; i < n && s[i] != '"'; i++)
        if (s[i] == '\\') i++;
    return i < n ? i + 1 : n;
}

static size_t skip_value(const char *s, size_t n, size_t i)
{
    i = skip_ws(s, n, i);
    if (i >= n) return n;
    if (s[i] == '"') return skip_string(s, n, i);
    if (s[i] == '{' || s[i] == '[') {
        /* Valid JSON: brackets balance outside strings. */
        long depth = 0;
        while (i < n) {
            if (s[i] == '"') {
                i = skip_string(s, n, i);
                continue;
            }
            if (s[i] == '{' || s[i] == '[') depth++;
            if (s[i] == '}' || s[i] == ']') {
                if (--depth == 0) return i + 1;
            }
            i++;
        }
        return n;
    }
    while (i < n && !strchr(",]} \t\r\n", s[i])) i++;
    return i;
}

long traj_json_member(const char *s, size_t n, long obj, const char *key)
{
    if (obj < 0) return -1;
    size_t i = skip_ws(s, n, (size_t)obj);
    if (i >= n || s[i] != '{') return -1;
    size_t klen = strlen(key);
    i = skip_ws(s, n, i + 1);
    while (i < n && s[i] == '"') {
        size_t kend = skip_string(s, n, i);
        int match = kend - i == klen + 2 && !memcmp(s + i + 1, key, klen);
        i = skip_ws(s, n, kend);
        if (i >= n || s[i] != ':') return -1;
        i = skip_ws(s, n, i + 1);
        if (match) return (long)i;
        i = skip_ws(s, n, skip_value(s, n, i));
        if (i < n && s[i] == ',') i = skip_ws(s, n, i + 1);
    }
    return -1;
}

long traj_json_element(const char *s, size_t n, long arr, size_t index)
{
    if (arr < 0) return -1;
    size_t i = skip_ws(s, n, (size_t)arr);
    if (i >= n || s[i] != '[') return -1;
    i = skip_ws(s, n, i + 1);
    for (size_t k = 0; i < n && s[i] != ']'; k++) {
        if (k == index) return (long)i;
        i = skip_ws(s, n, skip_value(s, n, i));
        if (i < n && s[i] == ',') i = skip_ws(s, n, i + 1);
    }
    return -1;
}

size_t traj_json_elements(const char *s, size_t n, long arr, long *offsets, size_t max)
{
    if (arr < 0) return 0;
    size_t i = skip_ws(s, n, (size_t)arr);
    if (i >= n || s[i] != '[') return 0;
    i = skip_ws(s, n, i + 1);
    size_t k = 0;
    while (i < n && s[i] != ']' && k < max) {
        offsets[k++] = (long)i;
        i = skip_ws(s, n, skip_value(s, n, i));
        if (i < n && s[i] == ',') i = skip_ws(s, n, i + 1);
    }
    return k;
}

/* Columns count characters (UTF-8 continuation bytes do not start one). */
void traj_json_position(const char *s, size_t n, long off, int *line, int *column)
{
    int l = 1, c = 1;
    for (long i = 0; i < off && (size_t)i < n; i++) {
        if (s[i] == '\n') {
            l++;
            c = 1;
        } else if (((unsigned char)s[i] & 0xC0) != 0x80) {
            c++;
        }
    }
    *line = l;
    *column = c;
}

void traj_json_lines(const char *s, size_t n, const long *offsets, size_t count, int *lines)
{
    int l = 1;
    size_t i = 0;
    for (size_t k = 0; k < count; k++) {
        for (; (long)i < offsets[k] && i < n; i++)
            if (s[i] == '\n') l++;
        lines[k] = l;
    }
}

static int utf8_length(unsigned long cp)
{
    return cp < 0x80 ? 1 : cp < 0x800 ? 2 : cp < 0x10000 ? 3 : 4;
}

long traj_json_string_char(const char *s, size_t n, long str, int column)
{
    if (str < 0 || (size_t)str >= n || s[str] != '"') return str;
    /* Walk the raw string, counting decoded bytes, until column - 1 of them
     * have passed: escapes make raw and decoded offsets differ. */
    long target = column > 1 ? column - 1 : 0, decoded = 0;
    size_t i = (size_t)str + 1;
    while (i < n && s[i] != '"' && decoded < target) {
        if (s[i] != '\\') {
            i++;
            decoded++;
            continue;
        }
        if (i + 1 < n && s[i + 1] == 'u' && i + 6 <= n) {
            unsigned long cp = 0;
            for (int k = 2; k < 6; k++) {
                char h = s[i + k];
                cp = cp * 16 + (unsigned long)(h <= '9' ? h - '0' : (h | 0x20) - 'a' + 10);
            }
            i += 6;
            if (cp >= 0xD800 && cp < 0xDC00 && i + 6 <= n && s[i] == '\\' && s[i + 1] == 'u') {
                i += 6; /* the low surrogate: one 4-byte character in all */
                decoded += 4;
            } else {
                decoded += utf8_length(cp);
            }
        } else {
            i += 2;
            decoded++;
        }
    }
    return (long)i;
}
