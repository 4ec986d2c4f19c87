/* http_error.c: API errors: filling the server's own, and turning a service
 * call's fm_error (its reason) into the HTTP status and machine code of
 * docs/api.md. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "http_server.h"

int fm_http_error_set(fm_http_error *err, int status, const char *code, const char *fmt, ...)
{
    if (!err) return status;
    memset(err, 0, sizeof *err);
    err->status = status;
    snprintf(err->code, sizeof err->code, "%s", code);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return status;
}

/* Reasons with a status of their own; every other reason takes the status
 * of its fm_status. */
static const struct {
    const char *reason;
    int status;
} reason_status[] = {
    {"not_found", 404},     {"no_snapshot", 404},    {"no_mesh", 404},       {"no_deviation", 404},
    {"not_finished", 409},  {"bad_state", 409},      {"job_limit", 429},
    {"shutting_down", 503}, {"busy", 503},           {"out_of_memory", 503},
    {"storage", 507},       {"memory_budget", 413},  {"too_large", 413},
    {"check_too_large", 413}, {"limit", 413},   {"history_dropped", 410},
};

void fm_http_error_from(const fm_error *err, fm_http_error *out)
{
    memset(out, 0, sizeof *out);
    const char *reason = err->reason[0] ? err->reason : NULL;
    int status = 0;
    for (size_t i = 0; reason && i < sizeof reason_status / sizeof reason_status[0]; i++)
        if (!strcmp(reason, reason_status[i].reason)) status = reason_status[i].status;
    if (!status) {
        switch (err->code) {
        case FM_ERR_INPUT: status = 400; if (!reason) reason = "bad_job"; break;
        case FM_ERR_LIMIT: status = 413; if (!reason) reason = "limit"; break;
        case FM_ERR_IO: status = 507; if (!reason) reason = "storage"; break;
        default: status = 500; if (!reason) reason = "internal"; break;
        }
    }
    out->status = status;
    snprintf(out->code, sizeof out->code, "%s", reason);
    snprintf(out->message, sizeof out->message, "%s", err->message);
    out->line = err->line > 0 ? err->line : 0;
    out->column = err->column > 0 ? err->column : 0;
}
