/* error.c: filling and formatting fm_error records. */
#include "core/core.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static void copy_string(char *dst, size_t size, const char *src)
{
    if (!src) src = "";
    size_t n = strlen(src);
    if (n >= size) n = size - 1;
    memcpy(dst, src, n);
    dst[n] = '\0';
}

fm_status fm_error_set(fm_error *err, fm_status code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->code = code;
        err->line = 0;
        err->column = 0;
        err->file[0] = '\0';
        err->reason[0] = '\0';
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

fm_status fm_error_at(fm_error *err, fm_status code, const char *file, int line,
                      int column, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->code = code;
        err->line = line;
        err->column = column;
        copy_string(err->file, sizeof err->file, file);
        err->reason[0] = '\0';
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

void fm_error_clear(fm_error *err)
{
    if (err) memset(err, 0, sizeof *err);
}

fm_status fm_error_set_reason(fm_error *err, fm_status code, const char *reason, const char *fmt,
                              ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->code = code;
        err->line = 0;
        err->column = 0;
        err->file[0] = '\0';
        copy_string(err->reason, sizeof err->reason, reason);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

const char *fm_error_format(const fm_error *err, char *buf, size_t size)
{
    if (!buf || size == 0) return "";
    if (!err) {
        buf[0] = '\0';
        return buf;
    }
    if (err->file[0] && err->line > 0 && err->column > 0)
        snprintf(buf, size, "%s:%d:%d: %s", err->file, err->line, err->column, err->message);
    else if (err->file[0] && err->line > 0)
        snprintf(buf, size, "%s:%d: %s", err->file, err->line, err->message);
    else if (err->line > 0 && err->column > 0)
        snprintf(buf, size, "%d:%d: %s", err->line, err->column, err->message);
    else if (err->line > 0)
        snprintf(buf, size, "line %d: %s", err->line, err->message);
    else if (err->file[0])
        snprintf(buf, size, "%s: %s", err->file, err->message);
    else
        snprintf(buf, size, "%s", err->message);
    return buf;
}

int fm_size_mul(size_t a, size_t b, size_t *out)
{
    if (a != 0 && b > SIZE_MAX / a) return 0;
    *out = a * b;
    return 1;
}

int fm_size_add(size_t a, size_t b, size_t *out)
{
    if (b > SIZE_MAX - a) return 0;
    *out = a + b;
    return 1;
}
