/* core.h: what every frepmill module shares: status codes, the error record
 * that carries a person-readable message and a source position, checked
 * size arithmetic for budgets, pi, the clocks, reading a whole file within
 * a byte budget and writing one durably. Nothing here prints; only the file
 * reader allocates (the buffer it returns). */
#ifndef FM_CORE_H
#define FM_CORE_H

#include <stddef.h>
#include <stdint.h>

typedef enum fm_status {
    FM_OK = 0,
    FM_ERR_INPUT = 2,   /* the user's input is wrong (exit status 2) */
    FM_ERR_LIMIT = 3,   /* a budget would be exceeded (exit status 3) */
    FM_ERR_IO = 4,      /* a file or device failed */
    FM_ERR_INTERNAL = 5 /* a bug or an unexpected library failure */
} fm_status;

/* Where an error happened in the user's input. line and column are 1-based;
 * 0 means unknown. file may be empty. reason is a stable machine-readable
 * word for APIs ("not_found", "unknown_key", ...; empty when none): the
 * daemon's protocols map it to their own codes (an HTTP status, a Modbus
 * error register value). */
typedef struct fm_error {
    fm_status code;
    int line;
    int column;
    char file[256];
    char message[512];
    char reason[32];
} fm_error;

/* Fill err (if not NULL) and return code. The message is printf-formatted. */
fm_status fm_error_set(fm_error *err, fm_status code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Same, with a position in a named input. */
fm_status fm_error_at(fm_error *err, fm_status code, const char *file, int line,
                      int column, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 6, 7)))
#endif
    ;

void fm_error_clear(fm_error *err);

/* fm_error_set with a reason (see fm_error). */
fm_status fm_error_set_reason(fm_error *err, fm_status code, const char *reason, const char *fmt,
                              ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* "file:line:column: message" (the parts that are known) into buf. */
const char *fm_error_format(const fm_error *err, char *buf, size_t size);

/* Checked arithmetic for sizes computed from user input: return 0 and leave
 * *out unchanged on overflow. */
int fm_size_mul(size_t a, size_t b, size_t *out);
int fm_size_add(size_t a, size_t b, size_t *out);

/* ------------------------------------------------------------- numbers -- */

#define FM_PI 3.14159265358979323846
#define FM_DEG (FM_PI / 180.0) /* radians per degree */

/* -------------------------------------------------------------- clocks -- */

/* Seconds on the monotonic clock (never steps back): durations, deadlines. */
double fm_clock_monotonic_s(void);
/* Seconds since the Unix epoch (the real-time clock): timestamps. */
double fm_clock_wall_s(void);
/* CPU seconds of the process (user + system, every thread). */
double fm_clock_cpu_s(void);
/* The real-time instant seconds from now, for pthread_cond_timedwait. */
struct timespec;
void fm_clock_deadline(struct timespec *out, double seconds);

/* --------------------------------------------------------------- files -- */

/* Read the whole regular file at path into a NUL-terminated malloc'd buffer
 * (*data; *size counts the bytes without the NUL; free(*data)). A file of
 * more than max_bytes is refused (FM_ERR_LIMIT with the reason "too_large",
 * which tells it from running out of memory) before any memory is taken,
 * and so is one that grows past it while being read. A folder, FIFO, socket
 * or device is refused (FM_ERR_IO) without reading or blocking. what names
 * the file in messages ("STL", "snapshot"; NULL for none); each message
 * holds the path. On failure *data is NULL and *size 0. */
fm_status fm_file_read(const char *path, const char *what, size_t max_bytes, char **data,
                       size_t *size, fm_error *err);

/* Write all size bytes to fd (again after a short write or EINTR): 0, or
 * an errno value. */
int fm_file_write_all(int fd, const void *data, size_t size);

/* Writes a durable file's bytes to fd: 0, or an errno value on failure. */
typedef int (*fm_file_writer)(int fd, void *ctx);

/* Replace path whole and durably: the bytes go to a temporary file in the
 * same folder (".<name>.fmtmp.<pid>.<n>", created exclusively), which is
 * fsynced, renamed over path, and the folder is fsynced. A crash at any
 * point leaves either the old file or the new one (and perhaps a temporary,
 * see fm_file_remove_stale_temporaries); a failure returns FM_ERR_IO and
 * removes the temporary. what names the file in messages ("<what> not
 * saved: ..."; NULL: the path). */
fm_status fm_file_write_durable(const char *path, const char *what, const void *data,
                                size_t size, fm_error *err);
/* The same with the bytes from writer(fd, ctx). previous, when not NULL, is
 * where the file being replaced is kept: it is hard-linked there (or, where
 * the file system has no hard links, renamed) before the new file takes its
 * name, so that path never disappears. */
fm_status fm_file_write_durable_with(const char *path, const char *what, fm_file_writer writer,
                                     void *ctx, const char *previous, fm_error *err);
/* fsync a folder, so that a rename or a new entry in it survives a power
 * cut. */
fm_status fm_file_sync_dir(const char *path, fm_error *err);
/* Remove the temporary files in dir that durable writers left when their
 * process died (those of living processes stay); *removed counts them. */
fm_status fm_file_remove_stale_temporaries(const char *dir, size_t *removed, fm_error *err);

#endif
