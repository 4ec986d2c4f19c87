/* log.h: the daemon's log: one line per event with a time stamp and a
 * level, to standard error or a file that SIGHUP reopens (for logrotate). */
#ifndef FM_DAEMON_LOG_H
#define FM_DAEMON_LOG_H

typedef enum fm_log_level {
    FM_LOG_ERROR = 0,
    FM_LOG_WARN = 1,
    FM_LOG_INFO = 2,
    FM_LOG_DEBUG = 3
} fm_log_level;

/* path NULL or "" or "-": standard error. 0 on success, -1 if the file
 * cannot be opened (the log then stays on standard error). */
int fm_log_open(const char *path, fm_log_level level);
/* Reopen the file (after logrotate moved it). Safe to call at any time
 * from a normal thread (not from a signal handler). */
int fm_log_reopen(void);
void fm_log_close(void);
/* "error", "warn", "info", "debug" -> level; -1 if unknown. */
int fm_log_level_parse(const char *name);

void fm_log(fm_log_level level, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif
