/* log.c: one line per event: "2024-05-01T12:00:00.123Z LEVEL message",
 * written with a single write() under a lock, so lines from the worker,
 * HTTP and Modbus threads never interleave. Newlines inside a message are
 * replaced, so every event stays one line for grep and journald. */
#include "log.h"

#include "core/core.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static pthread_mutex_t log_lock = PTHREAD_MUTEX_INITIALIZER;
static int log_fd = 2;
static char log_path[1024];
static fm_log_level log_level = FM_LOG_INFO;

static int open_file(const char *path)
{
    return open(path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0640);
}

int fm_log_open(const char *path, fm_log_level level)
{
    pthread_mutex_lock(&log_lock);
    log_level = level;
    int rc = 0;
    if (path && path[0] && strcmp(path, "-") != 0) {
        int fd = open_file(path);
        if (fd >= 0) {
            if (log_fd > 2) close(log_fd);
            log_fd = fd;
            snprintf(log_path, sizeof log_path, "%s", path);
        } else {
            rc = -1;
        }
    }
    pthread_mutex_unlock(&log_lock);
    return rc;
}

int fm_log_reopen(void)
{
    pthread_mutex_lock(&log_lock);
    int rc = 0;
    if (log_path[0]) {
        int fd = open_file(log_path);
        if (fd >= 0) {
            if (log_fd > 2) close(log_fd);
            log_fd = fd;
        } else {
            rc = -1; /* keep writing to the old file rather than lose lines */
        }
    }
    pthread_mutex_unlock(&log_lock);
    return rc;
}

void fm_log_close(void)
{
    pthread_mutex_lock(&log_lock);
    if (log_fd > 2) close(log_fd);
    log_fd = 2;
    log_path[0] = '\0';
    pthread_mutex_unlock(&log_lock);
}

int fm_log_level_parse(const char *name)
{
    static const char *const names[] = {"error", "warn", "info", "debug"};
    for (int i = 0; i < 4; i++)
        if (!strcmp(name, names[i])) return i;
    return -1;
}

void fm_log(fm_log_level level, const char *fmt, ...)
{
    if (level > log_level) return;
    static const char *const names[] = {"ERROR", "WARN", "INFO", "DEBUG"};
    char line[2048];
    /* microseconds apart from the seconds, so that rounding never shows
     * 1000 ms */
    const long long us = (long long)(fm_clock_wall_s() * 1e6);
    const time_t sec = (time_t)(us / 1000000);
    struct tm tm;
    gmtime_r(&sec, &tm);
    int n = snprintf(line, sizeof line, "%04d-%02d-%02dT%02d:%02d:%02d.%03ldZ %-5s ",
                     tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min,
                     tm.tm_sec, (long)(us % 1000000 / 1000), names[level]);
    va_list ap;
    va_start(ap, fmt);
    int m = vsnprintf(line + n, sizeof line - (size_t)n - 1, fmt, ap);
    va_end(ap);
    size_t len = (size_t)n + (m < 0 ? 0 : (size_t)m);
    if (len > sizeof line - 2) len = sizeof line - 2;
    for (size_t i = (size_t)n; i < len; i++)
        if (line[i] == '\n' || line[i] == '\r') line[i] = ' ';
    line[len++] = '\n';
    pthread_mutex_lock(&log_lock);
    ssize_t w;
    do {
        w = write(log_fd, line, len);
    } while (w < 0 && errno == EINTR);
    pthread_mutex_unlock(&log_lock);
}
