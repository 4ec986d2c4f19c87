/* http_server.h: the HTTP face of frepmill (docs/api.md). A JSON job API,
 * server-sent events and static files for the browser viewer, on
 * libmicrohttpd. The server owns its sockets and threads and knows nothing
 * of the daemon: the daemon hands it an fm_http_service, the small set of
 * calls the API needs (submit a job, read a status snapshot, fetch a mesh or
 * a chunk, wait for events, cancel). Request bodies are read and parsed here
 * (JSON with jansson, multipart/form-data by our own bounded parser), never
 * by libmicrohttpd's PostProcessor. */
#ifndef FM_HTTP_SERVER_H
#define FM_HTTP_SERVER_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>

#include "core/core.h"

/* An API error: the HTTP status, a stable machine code ("bad_json",
 * "not_found", ...), a message a person can act on, and where known the
 * line and column in the request body (1-based; 0 = unknown). */
typedef struct fm_http_error {
    int status;
    char code[40];
    char message[512];
    int line;
    int column;
} fm_http_error;

/* Fill err and return status. */
int fm_http_error_set(fm_http_error *err, int status, const char *code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* The API error of a service call (fm_error with its reason) in HTTP terms:
 * the reason is the machine code when it has one of its own status
 * ("not_found" 404, "not_finished" and "bad_state" 409, "job_limit" 429,
 * "shutting_down", "busy" and "out_of_memory" 503, "storage" 507,
 * "memory_budget", "too_large", "check_too_large" and "limit" 413); any other
 * reason keeps its name with the status of the fm_status: FM_ERR_INPUT 400
 * (code "bad_job" without a reason), FM_ERR_LIMIT 413 ("limit"), FM_ERR_IO 507
 * ("storage"), otherwise 500 ("internal"). Line and column are kept. */
void fm_http_error_from(const fm_error *err, fm_http_error *out);

/* ------------------------------------------------------------ multipart -- */

typedef struct fm_http_part {
    char name[64];        /* the form field name */
    char filename[256];   /* "" when the part is not a file */
    char content_type[128];
    const char *data;     /* points into the body given to the parser */
    size_t size;
} fm_http_part;

#define FM_HTTP_MAX_PARTS 16

/* Split a multipart/form-data body (RFC 7578) whose Content-Type header is
 * content_type into at most max_parts parts (data points into body). Returns
 * the number of parts, or -1 with err filled (400). Bounded: the header
 * block of a part is at most 8 KiB, a boundary at most 70 characters. */
int fm_http_multipart_parse(const char *content_type, const char *body, size_t len,
                            fm_http_part *parts, int max_parts, fm_http_error *err);

/* Turn a multipart job upload into the JSON job document: a "job" (or
 * "spec") part with the JSON job (its program may be absent), and optional
 * "program" (G-code, or a trajectory when its file name ends in .json) and
 * "tools" (JSON tool table) parts that replace the corresponding keys.
 * Returns a new reference (the service validates it), or NULL with err
 * filled. */
json_t *fm_http_job_from_multipart(const fm_http_part *parts, int count, fm_http_error *err);

/* ------------------------------------------------------------- service -- */

/* A byte buffer handed to the server, which frees it with free(). */
typedef struct fm_http_blob {
    uint8_t *data;
    size_t size;
    const char *content_type; /* static string */
} fm_http_blob;

/* One server-sent event. */
typedef struct fm_http_event {
    uint64_t id;       /* increasing per job; the SSE "id:" line */
    char type[24];     /* progress | block | chunks | finding | end */
    char *data;        /* one line of JSON, malloc'd (freed by the server) */
} fm_http_event;

/* The answer of a mounted protocol (fm_http_service.mounted): a whole body,
 * or a stream whose bytes read() gives (0: nothing yet, -1: the end) until
 * the server frees it. */
typedef struct fm_http_reply {
    int status;
    char content_type[128];
    char *body;           /* malloc'd (freed by the server); NULL with a stream */
    size_t size;
    void *stream;
    long (*read)(void *stream, char *buf, size_t max, int timeout_ms);
    void (*free)(void *stream);
} fm_http_reply;

/* What the daemon implements. Calls come from the server's connection
 * threads, many at once: each must be thread-safe and must never wait for a
 * job's simulation (read the published snapshots). Calls return FM_OK, or
 * an fm_status with err filled: its reason picks the HTTP status
 * (fm_http_error_from). JSON bodies reach the service parsed (the server
 * answers syntax errors with their line and column); what a job document
 * means is the service's to validate. */
typedef struct fm_http_service {
    void *ctx;
    /* 1 when ready to take jobs (GET /healthz). */
    int (*ready)(void *ctx);
    /* Validate the job document, store it durably, then give its id (202).
     * The service takes a new reference if it keeps the value. */
    fm_status (*submit)(void *ctx, json_t *job, char *id, size_t id_size, fm_error *err);
    /* New references. */
    fm_status (*status)(void *ctx, const char *id, json_t **out, fm_error *err);
    fm_status (*list)(void *ctx, json_t **out, fm_error *err);
    fm_status (*report)(void *ctx, const char *id, json_t **out, fm_error *err);
    /* The chunk list: with at_s < 0 the current chunks changed after version
     * since; with at_s >= 0 the chunks as they were at program time at_s
     * (the viewer's timeline). */
    fm_status (*chunks)(void *ctx, const char *id, uint64_t since, double at_s, json_t **out,
                        fm_error *err);
    fm_status (*cancel)(void *ctx, const char *id, fm_error *err);
    fm_status (*remove)(void *ctx, const char *id, fm_error *err);
    /* format: drc | stl | ply | obj. */
    fm_status (*mesh)(void *ctx, const char *id, const char *format, fm_http_blob *out,
                      fm_error *err);
    /* chunk: "I_J_K" (chunk indices); version 0: the current mesh, else the
     * mesh of that version (one the chunk list named). */
    fm_status (*chunk)(void *ctx, const char *id, const char *chunk, uint64_t version,
                       fm_http_blob *out, fm_error *err);
    /* The path of the job's stock snapshot (a file the daemon wrote). */
    fm_status (*stock_path)(void *ctx, const char *id, char *path, size_t size, fm_error *err);
    /* Wait up to timeout_ms for events after *after; fill up to cap events
     * and return how many (0 on timeout), or -1 when the job is unknown.
     * *finished is set once the job's last event ("end") has been given. */
    int (*events)(void *ctx, const char *id, uint64_t after, int timeout_ms, fm_http_event *out,
                  int cap, int *finished);
    /* POST /v1/check: the synchronous collision check of a job document.
     * NULL: 501. */
    fm_status (*check)(void *ctx, json_t *job, json_t **out, fm_error *err);
    /* GET /v1/jobs/{id}/toolpath: the job's program and its motions as a
     * compact JSON polyline for the viewer (docs/api.md). NULL: 404. */
    fm_status (*toolpath)(void *ctx, const char *id, fm_http_blob *out, fm_error *err);
    /* GET /v1/jobs/{id}/deviation (mesh 0: the key, JSON) and
     * /v1/jobs/{id}/deviation.drc (mesh 1: the stock in deviation colours):
     * the path of the file the daemon wrote. NULL: 404. */
    fm_status (*deviation_path)(void *ctx, const char *id, int mesh, char *path, size_t size,
                                fm_error *err);
    /* GET /v1/jobs/{id}/stock.drc: a done job's whole stock as one Draco
     * mesh for the viewer, the path of the file the daemon keeps. NULL: 404. */
    fm_status (*stock_mesh_path)(void *ctx, const char *id, char *path, size_t size,
                                 fm_error *err);
    /* Another protocol served on this server (the MTConnect agent): GET
     * and HEAD of mount_prefix ("/mtconnect") and below, with path what
     * follows the prefix and its '/', query the request's arguments
     * percent-encoded again (at most 4 KiB). Reads only: no token. NULL:
     * nothing is mounted. */
    const char *mount_prefix;
    void *mount_ctx;
    fm_status (*mounted)(void *mount_ctx, const char *path, const char *query, fm_http_reply *out,
                         fm_error *err);
} fm_http_service;

enum { FM_HTTP_LOG_ERROR = 0, FM_HTTP_LOG_WARN = 1, FM_HTTP_LOG_INFO = 2, FM_HTTP_LOG_DEBUG = 3 };

typedef struct fm_http_config {
    char listen_addr[64];        /* numeric IPv4 address; "127.0.0.1" by default */
    uint16_t port;               /* 0 = ephemeral; see fm_http_server_port() */
    char token[128];             /* bearer token for write endpoints; "" = none */
    int require_token;           /* refuse writes without the token (set when not loopback) */
    size_t max_request_bytes;    /* headers + body; default 64 MiB */
    int max_connections;         /* in all; default 256 */
    int max_connections_per_ip;  /* default 64 */
    int request_deadline_ms;     /* whole request (headers and body); default 30000 */
    int idle_timeout_s;          /* a connection silent this long is closed; default 60 */
    int threads;                 /* unused: one thread per connection */
    char viewer_dir[1024];       /* static files for GET /; "" = none */
    /* Optional: where the server's messages go (never printed otherwise). */
    void (*log)(void *log_ctx, int level, const char *message);
    void *log_ctx;
} fm_http_config;

void fm_http_config_default(fm_http_config *cfg);

typedef struct fm_http_server fm_http_server;

/* Bind, listen and start serving. The service is copied; its ctx must
 * outlive the server. On failure *out is NULL and err says why. */
fm_status fm_http_server_start(const fm_http_config *cfg, const fm_http_service *svc,
                               fm_http_server **out, fm_error *err);
uint16_t fm_http_server_port(const fm_http_server *server);
/* Stop accepting, close every connection, join the threads and free. NULL
 * is fine. No service call is made after this returns. */
void fm_http_server_stop(fm_http_server *server);

/* "127.0.0.1", "localhost", "::1" and 127.x.y.z are loopback. */
int fm_http_is_loopback(const char *addr);

#endif
