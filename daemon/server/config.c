/* config.c: frepmilld's settings. The file format is deliberately small:
 * one "key = value" per line, '#' starts a comment, values may be quoted;
 * every key is also a flag (--key value), and flags win over the file. An
 * unknown key or a bad value stops the start with file:line and the reason,
 * rather than running with a setting the operator did not intend. */
#include "config.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "log.h"
#include "toolpaths/gcode/gcode.h"
#include "queue_redis.h"

void fm_daemon_config_default(fm_daemon_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    snprintf(cfg->listen, sizeof cfg->listen, "127.0.0.1:8470");
    snprintf(cfg->state_dir, sizeof cfg->state_dir, "frepmilld-state");
    cfg->workers = 2;
    snprintf(cfg->modbus_listen, sizeof cfg->modbus_listen, "127.0.0.1:1502");
    cfg->log_level = FM_LOG_INFO;
    cfg->snapshot_interval_s = 10;
    cfg->publish_interval_s = 0.5;
    cfg->mesh_history_mb = 64;
    cfg->max_request_mb = 64;
    cfg->max_jobs = 1000;
    cfg->job_memory_mb = 4096;
    cfg->max_connections = 256;
    cfg->max_connections_per_ip = 64;
    cfg->request_deadline_ms = 30000;
    cfg->idle_timeout_s = 60;
    cfg->demo_voxel = 0.1;
    cfg->live_voxel = 0.25;
    cfg->live_feed = 1000;
    snprintf(cfg->dialect, sizeof cfg->dialect, "linuxcnc");
    snprintf(cfg->queue_stream, sizeof cfg->queue_stream, "frepmill:jobs");
    snprintf(cfg->queue_group, sizeof cfg->queue_group, "frepmilld");
    cfg->queue_claim_s = 30;
    cfg->mtconnect = 1;
    snprintf(cfg->mtconnect_device, sizeof cfg->mtconnect_device, "frepmill");
    char host[48] = "localhost";
    gethostname(host, sizeof host - 1);
    host[sizeof host - 1] = '\0';
    snprintf(cfg->mtconnect_uuid, sizeof cfg->mtconnect_uuid, "frepmill-%s", host);
    cfg->mtconnect_buffer = 16384;
    cfg->mtconnect_sample_ms = 50;
    snprintf(cfg->live_units, sizeof cfg->live_units, "mm");
    cfg->live_reconnect_max_s = 30;
}

int fm_daemon_split_addr(const char *spec, char *addr, size_t addr_size, unsigned *port)
{
    const char *colon = strrchr(spec, ':');
    if (!colon || colon == spec || (size_t)(colon - spec) >= addr_size) return -1;
    char *end;
    errno = 0;
    long p = strtol(colon + 1, &end, 10);
    if (errno || end == colon + 1 || *end || p < 0 || p > 65535) return -1;
    memcpy(addr, spec, (size_t)(colon - spec));
    addr[colon - spec] = '\0';
    *port = (unsigned)p;
    return 0;
}

static int parse_number(const char *v, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double d = strtod(v, &end);
    if (errno || end == v || *end || !isfinite(d) || d < lo || d > hi) return 0;
    *out = d;
    return 1;
}

static int parse_bool(const char *v, int *out)
{
    if (!strcmp(v, "1") || !strcmp(v, "yes") || !strcmp(v, "true") || !strcmp(v, "on")) {
        *out = 1;
        return 1;
    }
    if (!strcmp(v, "0") || !strcmp(v, "no") || !strcmp(v, "false") || !strcmp(v, "off")) {
        *out = 0;
        return 1;
    }
    return 0;
}

typedef enum { K_TEXT, K_INT, K_REAL, K_BOOL, K_ADDR, K_LEVEL, K_QUEUE, K_DIALECT } key_kind;

typedef struct key_def {
    const char *name;
    key_kind kind;
    size_t offset;
    size_t size; /* text: buffer size */
    double lo, hi;
} key_def;

#define TEXT(name, field) {name, K_TEXT, offsetof(fm_daemon_config, field), sizeof(((fm_daemon_config *)0)->field), 0, 0}
#define INT(name, field, lo, hi) {name, K_INT, offsetof(fm_daemon_config, field), 0, lo, hi}
#define REAL(name, field, lo, hi) {name, K_REAL, offsetof(fm_daemon_config, field), 0, lo, hi}
#define BOOL(name, field) {name, K_BOOL, offsetof(fm_daemon_config, field), 0, 0, 1}

static const key_def keys[] = {
    {"listen", K_ADDR, offsetof(fm_daemon_config, listen), sizeof(((fm_daemon_config *)0)->listen), 0, 0},
    TEXT("state_dir", state_dir),
    INT("workers", workers, 1, 256),
    INT("threads_per_job", threads_per_job, 0, 1024),
    {"modbus_listen", K_ADDR, offsetof(fm_daemon_config, modbus_listen), sizeof(((fm_daemon_config *)0)->modbus_listen), 0, 0},
    BOOL("modbus_commands", modbus_commands),
    BOOL("modbus_live", modbus_live),
    INT("modbus_watchdog_ms", modbus_watchdog_ms, 0, 3600000),
    TEXT("token", token),
    TEXT("log_file", log_file),
    {"log_level", K_LEVEL, offsetof(fm_daemon_config, log_level), 0, 0, 0},
    REAL("snapshot_interval_s", snapshot_interval_s, 0.1, 86400),
    REAL("publish_interval_s", publish_interval_s, 0.05, 3600),
    REAL("mesh_history_mb", mesh_history_mb, 0, 1e6),
    REAL("max_request_mb", max_request_mb, 0.001, 4096),
    INT("max_jobs", max_jobs, 1, 1000000),
    REAL("job_memory_mb", job_memory_mb, 1, 1e7),
    INT("max_connections", max_connections, 1, 100000),
    INT("max_connections_per_ip", max_connections_per_ip, 1, 100000),
    INT("request_deadline_ms", request_deadline_ms, 100, 3600000),
    INT("idle_timeout_s", idle_timeout_s, 1, 86400),
    TEXT("viewer_dir", viewer_dir),
    BOOL("demo", demo),
    TEXT("demo_dir", demo_dir),
    REAL("demo_voxel", demo_voxel, 0.01, 10),
    TEXT("live_stock", live_stock),
    TEXT("live_tools", live_tools),
    TEXT("live_machine", live_machine),
    REAL("live_voxel", live_voxel, 0.01, 10),
    REAL("live_feed", live_feed, 0.001, 1e7),
    {"dialect", K_DIALECT, offsetof(fm_daemon_config, dialect), sizeof(((fm_daemon_config *)0)->dialect), 0, 0},
    TEXT("subroutine_path", subroutine_path),
    {"queue", K_QUEUE, offsetof(fm_daemon_config, queue), sizeof(((fm_daemon_config *)0)->queue), 0, 0},
    TEXT("queue_stream", queue_stream),
    TEXT("queue_group", queue_group),
    TEXT("queue_consumer", queue_consumer),
    REAL("queue_claim_s", queue_claim_s, 0.1, 86400),
    BOOL("mtconnect", mtconnect),
    TEXT("mtconnect_device", mtconnect_device),
    TEXT("mtconnect_uuid", mtconnect_uuid),
    TEXT("mtconnect_machine", mtconnect_machine),
    INT("mtconnect_buffer", mtconnect_buffer, 4, 1048576),
    INT("mtconnect_sample_ms", mtconnect_sample_ms, 1, 60000),
    TEXT("live_source", live_source),
    TEXT("live_map", live_map),
    TEXT("live_units", live_units),
    REAL("live_reconnect_max_s", live_reconnect_max_s, 1, 3600),
};

int fm_daemon_config_set(fm_daemon_config *cfg, const char *key, const char *value, char *msg,
                         size_t msg_size)
{
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        const key_def *k = &keys[i];
        if (strcmp(k->name, key) != 0) continue;
        char *field = (char *)cfg + k->offset;
        double d;
        int b;
        switch (k->kind) {
        case K_ADDR: {
            char addr[64];
            unsigned port;
            if (strcmp(value, "off") != 0 &&
                fm_daemon_split_addr(value, addr, sizeof addr, &port) != 0) {
                snprintf(msg, msg_size, "%s = %s: expected ADDR:PORT%s", key, value,
                         strcmp(key, "listen") ? " or off" : "");
                return -1;
            }
            if (!strcmp(key, "listen") && !strcmp(value, "off")) {
                snprintf(msg, msg_size, "listen cannot be off");
                return -1;
            }
        } /* fall through: stored as text */
        /* FALLTHROUGH */
        case K_DIALECT:
            if (k->kind == K_DIALECT) {
                fm_gcode_dialect dialect;
                if (!fm_gcode_dialect_parse(value, &dialect)) {
                    snprintf(msg, msg_size, "%s = %.32s: expected linuxcnc or fanuc", key, value);
                    return -1;
                }
                value = fm_gcode_dialect_name(dialect);
            }
            /* FALLTHROUGH */
        case K_QUEUE:
            if (k->kind == K_QUEUE && value[0] && strcmp(value, "off") != 0) {
                fm_redis_url url;
                fm_error uerr;
                if (fm_redis_url_parse(value, &url, &uerr) != FM_OK) {
                    snprintf(msg, msg_size, "%s: %s", key, uerr.message);
                    return -1;
                }
            }
            /* FALLTHROUGH */
        case K_TEXT:
            if (strlen(value) >= k->size) {
                snprintf(msg, msg_size, "%s: the value is longer than %zu characters", key,
                         k->size - 1);
                return -1;
            }
            snprintf(field, k->size, "%s", value);
            return 0;
        case K_INT:
            if (!parse_number(value, k->lo, k->hi, &d) || d != floor(d)) {
                snprintf(msg, msg_size, "%s = %s: expected an integer in [%g, %g]", key, value,
                         k->lo, k->hi);
                return -1;
            }
            *(int *)field = (int)d;
            return 0;
        case K_REAL:
            if (!parse_number(value, k->lo, k->hi, &d)) {
                snprintf(msg, msg_size, "%s = %s: expected a number in [%g, %g]", key, value,
                         k->lo, k->hi);
                return -1;
            }
            *(double *)field = d;
            return 0;
        case K_BOOL:
            if (!parse_bool(value, &b)) {
                snprintf(msg, msg_size, "%s = %s: expected yes or no", key, value);
                return -1;
            }
            *(int *)field = b;
            return 0;
        case K_LEVEL:
            if ((b = fm_log_level_parse(value)) < 0) {
                snprintf(msg, msg_size, "%s = %s: expected error, warn, info or debug", key,
                         value);
                return -1;
            }
            *(int *)field = b;
            return 0;
        }
    }
    snprintf(msg, msg_size, "unknown setting '%s'", key);
    return -1;
}

static char *trim(char *s)
{
    while (isspace((unsigned char)*s)) s++;
    size_t n = strlen(s);
    while (n && isspace((unsigned char)s[n - 1])) s[--n] = '\0';
    return s;
}

int fm_daemon_config_load(fm_daemon_config *cfg, const char *path, char *msg, size_t msg_size)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(msg, msg_size, "%s: %s", path, strerror(errno));
        return -1;
    }
    char line[4096];
    int number = 0;
    while (fgets(line, sizeof line, f)) {
        number++;
        if (!strchr(line, '\n') && !feof(f)) {
            snprintf(msg, msg_size, "%s:%d: line longer than %zu characters", path, number,
                     sizeof line - 2);
            fclose(f);
            return -1;
        }
        char *s = trim(line);
        if (!*s || *s == '#') continue;
        char *eq = strchr(s, '=');
        if (!eq) {
            snprintf(msg, msg_size, "%s:%d: expected key = value", path, number);
            fclose(f);
            return -1;
        }
        *eq = '\0';
        char *key = trim(s), *value = trim(eq + 1);
        size_t n = strlen(value);
        if (n >= 2 && value[0] == '"' && value[n - 1] == '"') {
            value[n - 1] = '\0';
            value++;
        } else {
            /* An unquoted value ends at a comment. */
            char *hash = strstr(value, " #");
            if (hash) {
                *hash = '\0';
                value = trim(value);
            }
        }
        char inner[512];
        if (fm_daemon_config_set(cfg, key, value, inner, sizeof inner) != 0) {
            snprintf(msg, msg_size, "%s:%d: %s", path, number, inner);
            fclose(f);
            return -1;
        }
    }
    fclose(f);
    return 0;
}
