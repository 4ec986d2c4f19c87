/* core.h: what every frepmill module shares: status codes, the error record
 * that carries a person-readable message and a source position, and checked
 * size arithmetic for budgets. Nothing here allocates or prints. */
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

#endif
