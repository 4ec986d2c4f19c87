/* http_server.c: the HTTP server on libmicrohttpd: routing of the job API
 * (docs/api.md), request bodies read into bounded buffers, bearer-token
 * checks on write endpoints, connection limits with JSON answers, a total
 * deadline per request, server-sent events and static viewer files.
 *
 * Threads: libmicrohttpd runs one thread per connection, so a slow client,
 * a large download or a long-lived event stream holds only its own thread;
 * a sweeper thread enforces the request deadline. Why the deadline needs
 * our own code: libmicrohttpd's connection timeout counts idle time only,
 * so a client sending a header line every few seconds would hold its slot
 * forever. Every connection is tracked (MHD_OPTION_NOTIFY_CONNECTION) with
 * the time its current request started; the request callbacks check it
 * while a body arrives, and the sweeper acts on connections that send
 * nothing more: past the deadline a body still arriving is answered 408 (in
 * JSON, written to the socket: answer_timeout_locked says why) and the
 * socket shut down; one still receiving headers is only shut down. Either
 * way libmicrohttpd's connection thread sees end-of-stream and closes it. */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "http_server.h"

#define SSE_WAIT_MS 1000
#define SSE_KEEPALIVE_S 15.0
#define SSE_EVENTS_PER_WAIT 32

/* One accepted connection, kept from MHD's "started" to its "closed"
 * notification. Guarded by the server's conn_lock. */
typedef struct conn_track {
    struct conn_track *prev, *next;
    int fd;
    struct sockaddr_storage peer;
    socklen_t peer_len;
    char ip[INET6_ADDRSTRLEN];
    double request_start; /* monotonic s when the current request began */
    int receiving;        /* 1 until the request is complete */
    int in_body;          /* 1: its headers are in, its body is arriving */
    int timed_out;        /* 1: answered 408 on the socket and shut down */
    int over_limit;       /* 1: answer with a connection-limit error */
} conn_track;

struct fm_http_server {
    struct MHD_Daemon *mhd;
    fm_http_config cfg;
    fm_http_service svc;
    uint16_t port;

    pthread_mutex_t conn_lock;
    conn_track *conns;
    int conn_count;

    pthread_t sweeper;
    int sweeper_started;
    pthread_mutex_t stop_lock;
    pthread_cond_t stop_cond;
    volatile int stopping;
};

/* The state of one request, from its first callback to its completion. */
typedef struct request {
    char *body;
    size_t size, cap;
    int rejected;          /* a response was queued before the body ended */
    fm_http_error refused; /* status 0, or the answer once the body has ended */
} request;

static void logf_(fm_http_server *s, int level, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static void logf_(fm_http_server *s, int level, const char *fmt, ...)
{
    if (!s->cfg.log) return;
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    s->cfg.log(s->cfg.log_ctx, level, buf);
}

void fm_http_config_default(fm_http_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    snprintf(cfg->listen_addr, sizeof cfg->listen_addr, "127.0.0.1");
    cfg->port = 8470;
    cfg->max_request_bytes = (size_t)64 << 20;
    cfg->max_connections = 256;
    cfg->max_connections_per_ip = 64;
    cfg->request_deadline_ms = 30000;
    cfg->idle_timeout_s = 60;
}

int fm_http_is_loopback(const char *addr)
{
    return !strcmp(addr, "localhost") || !strcmp(addr, "::1") || !strncmp(addr, "127.", 4);
}

/* ----------------------------------------------------------- responses -- */

static enum MHD_Result queue(struct MHD_Connection *con, int status, struct MHD_Response *r)
{
    if (!r) return MHD_NO;
    MHD_add_response_header(r, "X-Content-Type-Options", "nosniff");
    enum MHD_Result ret = MHD_queue_response(con, (unsigned)status, r);
    MHD_destroy_response(r);
    return ret;
}

static enum MHD_Result respond_bytes(struct MHD_Connection *con, int status, const char *type,
                                     void *data, size_t size, int close_after)
{
    struct MHD_Response *r = MHD_create_response_from_buffer(size, data, MHD_RESPMEM_MUST_FREE);
    if (!r) {
        free(data);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", type);
    MHD_add_response_header(r, "Cache-Control", "no-store");
    if (close_after) MHD_add_response_header(r, "Connection", "close");
    return queue(con, status, r);
}

/* Takes the reference. */
static enum MHD_Result respond_json(struct MHD_Connection *con, int status, json_t *body)
{
    char *text = json_dumps(body, JSON_COMPACT | JSON_REAL_PRECISION(12));
    json_decref(body);
    if (!text) return MHD_NO;
    size_t n = strlen(text);
    /* A final newline keeps curl output readable. */
    char *with_nl = realloc(text, n + 2);
    if (with_nl) {
        with_nl[n] = '\n';
        with_nl[n + 1] = '\0';
        text = with_nl;
        n++;
    }
    return respond_bytes(con, status, "application/json", text, n, 0);
}

static json_t *error_json(const fm_http_error *err)
{
    return json_pack("{s:{s:s, s:s, s:o, s:o}}", "error", "code", err->code, "message",
                     err->message, "line", err->line > 0 ? json_integer(err->line) : json_null(),
                     "column", err->column > 0 ? json_integer(err->column) : json_null());
}

static enum MHD_Result respond_error(struct MHD_Connection *con, const fm_http_error *err,
                                     int close_after)
{
    json_t *body = error_json(err);
    char *text = body ? json_dumps(body, JSON_COMPACT) : NULL;
    json_decref(body); /* every error answer leaked it (LeakSanitizer, daemon_check) */
    /* json_dumps of a fresh json_pack never fails short of memory. */
    if (!text) return MHD_NO;
    size_t n = strlen(text);
    char *with_nl = realloc(text, n + 2);
    if (with_nl) {
        with_nl[n] = '\n';
        with_nl[n + 1] = '\0';
        text = with_nl;
        n++;
    }
    return respond_bytes(con, err->status ? err->status : 500, "application/json", text, n,
                         close_after);
}

static enum MHD_Result respond_service_error(struct MHD_Connection *con, const fm_error *e)
{
    fm_http_error err;
    fm_http_error_from(e, &err);
    return respond_error(con, &err, err.status == 413 || err.status == 429 || err.status == 503);
}

static enum MHD_Result fail(struct MHD_Connection *con, int status, const char *code,
                            const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static enum MHD_Result fail(struct MHD_Connection *con, int status, const char *code,
                            const char *fmt, ...)
{
    fm_http_error err;
    memset(&err, 0, sizeof err);
    err.status = status;
    snprintf(err.code, sizeof err.code, "%s", code);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err.message, sizeof err.message, fmt, ap);
    va_end(ap);
    return respond_error(con, &err, status == 408 || status == 413 || status == 429 ||
                                        status == 503);
}

/* ------------------------------------------------------- static files -- */

static const char *content_type_of(const char *path)
{
    static const struct {
        const char *ext, *type;
    } types[] = {{".html", "text/html; charset=utf-8"},
                 {".js", "text/javascript; charset=utf-8"},
                 {".mjs", "text/javascript; charset=utf-8"},
                 {".css", "text/css; charset=utf-8"},
                 {".json", "application/json"},
                 {".wasm", "application/wasm"},
                 {".png", "image/png"},
                 {".svg", "image/svg+xml"},
                 {".ico", "image/x-icon"},
                 {".txt", "text/plain; charset=utf-8"},
                 {".map", "application/json"}};
    const char *dot = strrchr(path, '.');
    if (dot)
        for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
            if (!strcasecmp(dot, types[i].ext)) return types[i].type;
    return "application/octet-stream";
}

/* A URL path is served only if no segment is empty-dot or hidden: no
 * "..", no ".git", no NUL, no backslash. */
static int safe_static_path(const char *url)
{
    if (url[0] != '/' || strlen(url) > 512) return 0;
    for (const char *p = url; *p; p++) {
        if (*p == '\\') return 0;
        if (*p == '/' && p[1] == '.') return 0;
    }
    return 1;
}

static enum MHD_Result respond_file(struct MHD_Connection *con, const char *path, const char *type)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) return MHD_NO;
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return MHD_NO;
    }
    struct MHD_Response *r = MHD_create_response_from_fd((uint64_t)st.st_size, fd);
    if (!r) {
        close(fd);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", type);
    return queue(con, 200, r);
}

/* GET / when no viewer is installed: the jobs as links. */
static enum MHD_Result respond_job_index(fm_http_server *s, struct MHD_Connection *con)
{
    json_t *list = NULL;
    fm_error err;
    size_t cap = 4096, n = 0;
    char *html = malloc(cap);
    if (!html) return MHD_NO;
    n += (size_t)snprintf(html, cap,
                          "<!doctype html><html><head><meta charset=\"utf-8\"><title>frepmilld</title>"
                          "</head><body><h1>frepmilld</h1><p>The viewer is not installed; "
                          "jobs:</p><ul>\n");
    if (s->svc.list && s->svc.list(s->svc.ctx, &list, &err) == FM_OK) {
        json_t *jobs = json_object_get(list, "jobs");
        size_t i;
        json_t *job;
        json_array_foreach(jobs, i, job) {
            const char *id = json_string_value(json_object_get(job, "id"));
            const char *state = json_string_value(json_object_get(job, "state"));
            if (!id || !state) continue;
            char line[512];
            /* Ids are [0-9a-z-] (the daemon makes them), safe in HTML. */
            int m = snprintf(line, sizeof line,
                             "<li><a href=\"/v1/jobs/%s\">%s</a> %s (<a href=\"/v1/jobs/%s/"
                             "mesh?format=stl\">mesh</a>)</li>\n",
                             id, id, state, id);
            if (m < 0 || (size_t)m >= sizeof line) continue;
            if (n + (size_t)m + 64 > cap) {
                char *bigger = realloc(html, cap * 2 + (size_t)m);
                if (!bigger) break;
                html = bigger;
                cap = cap * 2 + (size_t)m;
            }
            memcpy(html + n, line, (size_t)m);
            n += (size_t)m;
        }
        json_decref(list);
    }
    const char *tail = "</ul></body></html>\n";
    if (n + strlen(tail) + 1 > cap) {
        char *bigger = realloc(html, n + strlen(tail) + 1);
        if (!bigger) {
            free(html);
            return MHD_NO;
        }
        html = bigger;
    }
    memcpy(html + n, tail, strlen(tail) + 1);
    n += strlen(tail);
    return respond_bytes(con, 200, "text/html; charset=utf-8", html, n, 0);
}

static enum MHD_Result serve_static(fm_http_server *s, struct MHD_Connection *con, const char *url)
{
    if (!strcmp(url, "/") || !strcmp(url, "/index.html")) {
        char path[PATH_MAX];
        if (s->cfg.viewer_dir[0] &&
            snprintf(path, sizeof path, "%s/index.html", s->cfg.viewer_dir) < (int)sizeof path &&
            access(path, R_OK) == 0)
            return respond_file(con, path, "text/html; charset=utf-8");
        return respond_job_index(s, con);
    }
    if (s->cfg.viewer_dir[0] && safe_static_path(url)) {
        char path[PATH_MAX];
        if (snprintf(path, sizeof path, "%s%s", s->cfg.viewer_dir, url) < (int)sizeof path) {
            int fd = open(path, O_RDONLY | O_CLOEXEC);
            if (fd >= 0) {
                struct stat st;
                int regular = fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
                close(fd);
                if (regular) {
                    enum MHD_Result r = respond_file(con, path, content_type_of(path));
                    if (r == MHD_YES) return r;
                }
            }
        }
    }
    return fail(con, 404, "not_found", "no such resource: %s", url);
}

/* ---------------------------------------------------------------- SSE -- */

typedef struct sse_stream {
    fm_http_server *server;
    char id[64];
    uint64_t after;
    int finished;
    char *pending;
    size_t pending_size, pending_off;
    double last_write;
} sse_stream;

static void sse_append(sse_stream *st, const char *text, size_t n)
{
    size_t live = st->pending_size - st->pending_off;
    char *buf = malloc(live + n);
    if (!buf) return;
    /* The first append finds no pending buffer: memcpy from NULL, even of
     * 0 bytes, is undefined (UBSan, daemon_e2e). */
    if (live) memcpy(buf, st->pending + st->pending_off, live);
    memcpy(buf + live, text, n);
    free(st->pending);
    st->pending = buf;
    st->pending_size = live + n;
    st->pending_off = 0;
}

static ssize_t sse_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos;
    sse_stream *st = cls;
    if (st->pending_off == st->pending_size) {
        if (st->finished || st->server->stopping) return MHD_CONTENT_READER_END_OF_STREAM;
        fm_http_event events[SSE_EVENTS_PER_WAIT];
        int finished = 0;
        int n = st->server->svc.events(st->server->svc.ctx, st->id, st->after, SSE_WAIT_MS,
                                       events, SSE_EVENTS_PER_WAIT, &finished);
        if (n < 0) return MHD_CONTENT_READER_END_OF_STREAM; /* the job was deleted */
        for (int i = 0; i < n; i++) {
            size_t need = strlen(events[i].data) + strlen(events[i].type) + 64;
            char *text = malloc(need);
            if (text) {
                int m = snprintf(text, need, "id: %llu\nevent: %s\ndata: %s\n\n",
                                 (unsigned long long)events[i].id, events[i].type, events[i].data);
                if (m > 0) sse_append(st, text, (size_t)m);
                free(text);
            }
            st->after = events[i].id;
            free(events[i].data);
        }
        if (finished) st->finished = 1;
        if (st->pending_off == st->pending_size) {
            /* A comment now and then keeps proxies and the idle timeout from
             * closing a quiet stream. */
            if (fm_clock_monotonic_s() - st->last_write < SSE_KEEPALIVE_S) return 0;
            sse_append(st, ": keepalive\n\n", 13);
        }
    }
    size_t n = st->pending_size - st->pending_off;
    if (n > max) n = max;
    memcpy(buf, st->pending + st->pending_off, n);
    st->pending_off += n;
    st->last_write = fm_clock_monotonic_s();
    return (ssize_t)n;
}

static void sse_free(void *cls)
{
    sse_stream *st = cls;
    free(st->pending);
    free(st);
}

static enum MHD_Result serve_events(fm_http_server *s, struct MHD_Connection *con, const char *id)
{
    json_t *status = NULL;
    fm_error err;
    if (s->svc.status(s->svc.ctx, id, &status, &err) != FM_OK)
        return respond_service_error(con, &err);
    json_decref(status);
    sse_stream *st = calloc(1, sizeof *st);
    if (!st) return MHD_NO;
    st->server = s;
    snprintf(st->id, sizeof st->id, "%s", id);
    st->last_write = fm_clock_monotonic_s();
    /* A reconnecting EventSource sends the last id it saw. */
    const char *last = MHD_lookup_connection_value(con, MHD_HEADER_KIND, "Last-Event-ID");
    if (last) st->after = strtoull(last, NULL, 10);
    /* An initial comment opens the stream at once for the client. */
    sse_append(st, ": frepmilld events\n\n", 20);
    struct MHD_Response *r =
        MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 4096, sse_read, st, sse_free);
    if (!r) {
        sse_free(st);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", "text/event-stream");
    MHD_add_response_header(r, "Cache-Control", "no-store");
    return queue(con, 200, r);
}

/* ----------------------------------------------------------- mounted -- */

/* The query string of a mounted request, its arguments percent-encoded
 * again (libmicrohttpd hands them decoded). */
typedef struct query_text {
    char text[4096];
    size_t len;
    int overflow;
} query_text;

static void query_put(query_text *q, const char *s)
{
    static const char hex[] = "0123456789ABCDEF";
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        int plain = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.' || c == '~' || c == '/' || c == '@' || c == '*';
        if (q->len + 4 >= sizeof q->text) {
            q->overflow = 1;
            return;
        }
        if (plain) {
            q->text[q->len++] = (char)c;
        } else {
            q->text[q->len++] = '%';
            q->text[q->len++] = hex[c >> 4];
            q->text[q->len++] = hex[c & 15];
        }
    }
    q->text[q->len] = '\0';
}

static enum MHD_Result query_arg(void *cls, enum MHD_ValueKind kind, const char *key,
                                 const char *value)
{
    (void)kind;
    query_text *q = cls;
    if (q->len && q->len + 1 < sizeof q->text) q->text[q->len++] = '&';
    query_put(q, key);
    if (value) {
        if (q->len + 1 < sizeof q->text) q->text[q->len++] = '=';
        query_put(q, value);
    }
    q->text[q->len] = '\0';
    return MHD_YES;
}

typedef struct mounted_stream {
    fm_http_server *server;
    fm_http_reply reply;
} mounted_stream;

static ssize_t mounted_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos;
    mounted_stream *ms = cls;
    if (ms->server->stopping) return MHD_CONTENT_READER_END_OF_STREAM;
    long n = ms->reply.read(ms->reply.stream, buf, max, SSE_WAIT_MS);
    if (n < 0) return MHD_CONTENT_READER_END_OF_STREAM;
    return (ssize_t)n;
}

static void mounted_free(void *cls)
{
    mounted_stream *ms = cls;
    if (ms->reply.free) ms->reply.free(ms->reply.stream);
    free(ms);
}

static enum MHD_Result serve_mounted(fm_http_server *s, struct MHD_Connection *con, const char *path)
{
    query_text q;
    memset(&q, 0, sizeof q);
    MHD_get_connection_values(con, MHD_GET_ARGUMENT_KIND, query_arg, &q);
    if (q.overflow) return fail(con, 414, "uri_too_long", "the query is over 4 KiB");
    fm_http_reply reply;
    memset(&reply, 0, sizeof reply);
    fm_error err;
    fm_error_clear(&err);
    if (s->svc.mounted(s->svc.mount_ctx, path, q.text, &reply, &err) != FM_OK)
        return respond_service_error(con, &err);
    if (reply.stream) {
        mounted_stream *ms = calloc(1, sizeof *ms);
        if (!ms) {
            if (reply.free) reply.free(reply.stream);
            return MHD_NO;
        }
        ms->server = s;
        ms->reply = reply;
        struct MHD_Response *r =
            MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, mounted_read, ms, mounted_free);
        if (!r) {
            mounted_free(ms);
            return MHD_NO;
        }
        MHD_add_response_header(r, "Content-Type", reply.content_type);
        MHD_add_response_header(r, "Cache-Control", "no-store");
        return queue(con, reply.status, r);
    }
    struct MHD_Response *r =
        MHD_create_response_from_buffer(reply.size, reply.body, MHD_RESPMEM_MUST_FREE);
    if (!r) {
        free(reply.body);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", reply.content_type);
    return queue(con, reply.status, r);
}

/* ------------------------------------------------------------ routing -- */

static int token_ok(fm_http_server *s, struct MHD_Connection *con)
{
    if (!s->cfg.require_token && !s->cfg.token[0]) return 1;
    if (!s->cfg.token[0]) return 0; /* required but none configured: no writes */
    const char *auth = MHD_lookup_connection_value(con, MHD_HEADER_KIND, "Authorization");
    if (!auth || strncasecmp(auth, "Bearer ", 7) != 0) return 0;
    const char *given = auth + 7;
    size_t a = strlen(given), b = strlen(s->cfg.token);
    /* Compare every byte, so the time taken does not reveal the prefix
     * that matched. */
    unsigned diff = (unsigned)(a ^ b);
    for (size_t i = 0; i < b; i++) diff |= (unsigned)(given[i < a ? i : 0] ^ s->cfg.token[i]);
    return diff == 0 && a == b;
}

/* Split "/v1/jobs/ID/rest" into id and rest ("" when absent). 0 if the id
 * is not made of [0-9A-Za-z_-] or too long. */
static int split_job_path(const char *path, char *id, size_t id_size, const char **rest)
{
    const char *slash = strchr(path, '/');
    size_t n = slash ? (size_t)(slash - path) : strlen(path);
    if (n == 0 || n >= id_size) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = path[i];
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
              c == '-' || c == '_'))
            return 0;
    }
    memcpy(id, path, n);
    id[n] = '\0';
    *rest = slash ? slash : "";
    return 1;
}

static enum MHD_Result method_not_allowed(struct MHD_Connection *con, const char *method,
                                          const char *url, const char *allow)
{
    fm_http_error err;
    fm_http_error_set(&err, 405, "method_not_allowed", "%s %s: allowed methods are %s", method,
                      url, allow);
    json_t *body = error_json(&err);
    char *text = body ? json_dumps(body, JSON_COMPACT) : NULL;
    json_decref(body);
    if (!text) return MHD_NO;
    struct MHD_Response *r =
        MHD_create_response_from_buffer(strlen(text), text, MHD_RESPMEM_MUST_FREE);
    if (!r) {
        free(text);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", "application/json");
    MHD_add_response_header(r, "Allow", allow);
    return queue(con, 405, r);
}

/* A request body as JSON: syntax errors answered here with their line and
 * column (what the document means is the service's to validate). */
static json_t *parse_body_json(const request *req, const char *what, fm_http_error *err)
{
    json_error_t jerr;
    /* JSON_REJECT_DUPLICATES: two "program" keys are a mistake, not a choice. */
    json_t *v = json_loadb(req->body ? req->body : "", req->size, JSON_REJECT_DUPLICATES, &jerr);
    if (!v) {
        fm_http_error_set(err, 400, "bad_json", "%s is not valid JSON: %s", what, jerr.text);
        err->line = jerr.line > 0 ? jerr.line : 0;
        err->column = jerr.column > 0 ? jerr.column : 0;
    }
    return v;
}

static enum MHD_Result submit_job(fm_http_server *s, struct MHD_Connection *con, request *req)
{
    fm_http_error err;
    memset(&err, 0, sizeof err);
    const char *type = MHD_lookup_connection_value(con, MHD_HEADER_KIND, "Content-Type");
    json_t *job;
    if (type && !strncasecmp(type, "multipart/form-data", 19)) {
        fm_http_part parts[FM_HTTP_MAX_PARTS];
        int n = fm_http_multipart_parse(type, req->body ? req->body : "", req->size, parts,
                                        FM_HTTP_MAX_PARTS, &err);
        job = n < 0 ? NULL : fm_http_job_from_multipart(parts, n, &err);
    } else {
        job = parse_body_json(req, "the job", &err);
    }
    if (!job) return respond_error(con, &err, 0);
    char id[64];
    fm_error serr;
    fm_error_clear(&serr);
    fm_status st = s->svc.submit(s->svc.ctx, job, id, sizeof id, &serr);
    json_decref(job);
    if (st != FM_OK) return respond_service_error(con, &serr);
    char location[128];
    snprintf(location, sizeof location, "/v1/jobs/%s", id);
    json_t *body = json_pack("{s:s, s:s}", "id", id, "status_url", location);
    char *text = json_dumps(body, JSON_COMPACT);
    json_decref(body);
    if (!text) return MHD_NO;
    struct MHD_Response *r =
        MHD_create_response_from_buffer(strlen(text), text, MHD_RESPMEM_MUST_FREE);
    if (!r) {
        free(text);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", "application/json");
    MHD_add_response_header(r, "Location", location);
    return queue(con, 202, r);
}

static enum MHD_Result reply_json_call(struct MHD_Connection *con, fm_status st, json_t *out,
                                       const fm_error *err, int ok_status)
{
    if (st != FM_OK) return respond_service_error(con, err);
    return respond_json(con, ok_status, out);
}

static enum MHD_Result reply_blob(struct MHD_Connection *con, fm_status st, fm_http_blob *blob,
                                  const fm_error *err)
{
    if (st != FM_OK) return respond_service_error(con, err);
    return respond_bytes(con, 200, blob->content_type ? blob->content_type
                                                      : "application/octet-stream",
                         blob->data, blob->size, 0);
}

/* A query argument as a number: 0 and *out, or 1 (absent: *out untouched),
 * or -1 when it is not a number. */
static int query_number(struct MHD_Connection *con, const char *key, int integer, double *out)
{
    const char *v = MHD_lookup_connection_value(con, MHD_GET_ARGUMENT_KIND, key);
    if (!v) return 1;
    char *end;
    errno = 0;
    double d = strtod(v, &end);
    if (end == v || *end || errno || !isfinite(d) || d < 0 || (integer && (d != floor(d) || v[0] == '-')))
        return -1;
    *out = d;
    return 0;
}

static enum MHD_Result route_job(fm_http_server *s, struct MHD_Connection *con, const char *method,
                                 const char *url, const char *id, const char *rest,
                                 int is_get, int is_post, int is_delete)
{
    fm_error err;
    fm_error_clear(&err);
    json_t *out = NULL;
    fm_status st;
    if (!rest[0]) {
        if (is_get) {
            st = s->svc.status(s->svc.ctx, id, &out, &err);
            return reply_json_call(con, st, out, &err, 200);
        }
        if (is_delete) {
            if (!token_ok(s, con)) goto unauthorized;
            st = s->svc.remove(s->svc.ctx, id, &err);
            return reply_json_call(con, st,
                                   st ? NULL : json_pack("{s:s, s:b}", "id", id, "deleted", 1),
                                   &err, 200);
        }
        return method_not_allowed(con, method, url, "GET, DELETE");
    }
    if (!strcmp(rest, "/cancel")) {
        if (!is_post) return method_not_allowed(con, method, url, "POST");
        if (!token_ok(s, con)) goto unauthorized;
        if ((st = s->svc.cancel(s->svc.ctx, id, &err)) != FM_OK)
            return respond_service_error(con, &err);
        st = s->svc.status(s->svc.ctx, id, &out, &err);
        return reply_json_call(con, st, out, &err, 200);
    }
    if (!is_get) return method_not_allowed(con, method, url, "GET");
    if (!strcmp(rest, "/report")) {
        st = s->svc.report(s->svc.ctx, id, &out, &err);
        return reply_json_call(con, st, out, &err, 200);
    }
    if (!strcmp(rest, "/events")) return serve_events(s, con, id);
    if (!strcmp(rest, "/mesh")) {
        const char *format = MHD_lookup_connection_value(con, MHD_GET_ARGUMENT_KIND, "format");
        fm_http_blob blob = {0};
        st = s->svc.mesh(s->svc.ctx, id, format ? format : "drc", &blob, &err);
        return reply_blob(con, st, &blob, &err);
    }
    if (!strcmp(rest, "/chunks")) {
        double since = 0, at = -1;
        if (query_number(con, "since", 1, &since) < 0)
            return fail(con, 400, "bad_parameter", "since: not a version number");
        if (query_number(con, "at", 0, &at) < 0)
            return fail(con, 400, "bad_parameter", "at: not a program time in seconds (>= 0)");
        st = s->svc.chunks(s->svc.ctx, id, (uint64_t)since, at, &out, &err);
        return reply_json_call(con, st, out, &err, 200);
    }
    if (!strncmp(rest, "/chunks/", 8)) {
        const char *name = rest + 8;
        size_t n = strlen(name);
        if (n < 5 || n > 64 || strcmp(name + n - 4, ".drc") != 0)
            return fail(con, 404, "not_found", "chunks are named I_J_K.drc");
        char chunk[64];
        memcpy(chunk, name, n - 4);
        chunk[n - 4] = '\0';
        double version = 0;
        if (query_number(con, "v", 1, &version) < 0)
            return fail(con, 400, "bad_parameter", "v: not a version number");
        fm_http_blob blob = {0};
        st = s->svc.chunk(s->svc.ctx, id, chunk, (uint64_t)version, &blob, &err);
        return reply_blob(con, st, &blob, &err);
    }
    if (!strcmp(rest, "/toolpath") && s->svc.toolpath) {
        fm_http_blob blob = {0};
        st = s->svc.toolpath(s->svc.ctx, id, &blob, &err);
        return reply_blob(con, st, &blob, &err);
    }
    if ((!strcmp(rest, "/deviation") || !strcmp(rest, "/deviation.drc")) && s->svc.deviation_path) {
        int mesh = rest[10] != '\0';
        char path[PATH_MAX];
        if ((st = s->svc.deviation_path(s->svc.ctx, id, mesh, path, sizeof path, &err)) != FM_OK)
            return respond_service_error(con, &err);
        if (respond_file(con, path, mesh ? "application/octet-stream" : "application/json") == MHD_YES)
            return MHD_YES;
        return fail(con, 404, "no_deviation", "job %s has no deviation", id);
    }
    if (!strcmp(rest, "/stock.drc") && s->svc.stock_mesh_path) {
        char path[PATH_MAX];
        if ((st = s->svc.stock_mesh_path(s->svc.ctx, id, path, sizeof path, &err)) != FM_OK)
            return respond_service_error(con, &err);
        if (respond_file(con, path, "application/octet-stream") == MHD_YES) return MHD_YES;
        return fail(con, 404, "no_mesh", "job %s has no stock mesh", id);
    }
    if (!strcmp(rest, "/stock.vdb")) {
        char path[PATH_MAX];
        if ((st = s->svc.stock_path(s->svc.ctx, id, path, sizeof path, &err)) != FM_OK)
            return respond_service_error(con, &err);
        if (respond_file(con, path, "application/octet-stream") == MHD_YES) return MHD_YES;
        return fail(con, 404, "no_snapshot", "job %s has no stock snapshot yet", id);
    }
    return fail(con, 404, "not_found", "no such resource: %s", url);
unauthorized:
    return fail(con, 401, "unauthorized",
                "this endpoint needs the header Authorization: Bearer <token> (the daemon's "
                "token setting)");
}

static enum MHD_Result route(fm_http_server *s, struct MHD_Connection *con, const char *url,
                             const char *method, request *req)
{
    int is_get = !strcmp(method, "GET") || !strcmp(method, "HEAD");
    int is_post = !strcmp(method, "POST");
    int is_delete = !strcmp(method, "DELETE");
    if (!strcmp(url, "/healthz")) {
        if (!is_get) return method_not_allowed(con, method, url, "GET");
        int ready = s->svc.ready ? s->svc.ready(s->svc.ctx) : 1;
        return respond_json(con, ready ? 200 : 503,
                            json_pack("{s:s}", "status", ready ? "ok" : "starting"));
    }
    if (!strcmp(url, "/v1/jobs") || !strcmp(url, "/v1/jobs/")) {
        if (is_get) {
            json_t *out = NULL;
            fm_error err;
            fm_error_clear(&err);
            fm_status st = s->svc.list(s->svc.ctx, &out, &err);
            return reply_json_call(con, st, out, &err, 200);
        }
        if (is_post) {
            if (!token_ok(s, con))
                return fail(con, 401, "unauthorized",
                            "this endpoint needs the header Authorization: Bearer <token>");
            return submit_job(s, con, req);
        }
        return method_not_allowed(con, method, url, "GET, POST");
    }
    if (!strncmp(url, "/v1/jobs/", 9)) {
        char id[64];
        const char *rest;
        if (!split_job_path(url + 9, id, sizeof id, &rest))
            return fail(con, 404, "not_found", "no such job");
        return route_job(s, con, method, url, id, rest, is_get, is_post, is_delete);
    }
    if (!strcmp(url, "/v1/check")) {
        if (!is_post) return method_not_allowed(con, method, url, "POST");
        if (!token_ok(s, con))
            return fail(con, 401, "unauthorized",
                        "this endpoint needs the header Authorization: Bearer <token>");
        if (!s->svc.check)
            return fail(con, 501, "not_built", "the collision check (lib/check) is not built");
        fm_http_error herr;
        json_t *in = parse_body_json(req, "the request", &herr);
        if (!in) return respond_error(con, &herr, 0);
        json_t *out = NULL;
        fm_error err;
        fm_error_clear(&err);
        fm_status st = s->svc.check(s->svc.ctx, in, &out, &err);
        json_decref(in);
        return reply_json_call(con, st, out, &err, 200);
    }
    if (s->svc.mounted && s->svc.mount_prefix && s->svc.mount_prefix[0]) {
        size_t n = strlen(s->svc.mount_prefix);
        if (!strncmp(url, s->svc.mount_prefix, n) && (url[n] == '\0' || url[n] == '/')) {
            if (!is_get) return method_not_allowed(con, method, url, "GET");
            return serve_mounted(s, con, url[n] == '/' ? url + n + 1 : "");
        }
    }
    if (!strncmp(url, "/v1/", 4) || !strcmp(url, "/v1"))
        return fail(con, 404, "not_found", "no such endpoint: %s", url);
    if (!is_get) return method_not_allowed(con, method, url, "GET");
    return serve_static(s, con, url);
}

static conn_track *track_of(struct MHD_Connection *con)
{
    const union MHD_ConnectionInfo *info =
        MHD_get_connection_info(con, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return info ? info->socket_context : NULL;
}

/* Answer 408 on a connection whose body is still arriving, then shut it
 * down. libmicrohttpd takes a response only before the body or after its
 * end (MHD_queue_response refuses one in between), and a client that
 * trickles its body never reaches the end; so the answer is written to the
 * socket directly. That is safe here: while a body arrives libmicrohttpd
 * has nothing to write on this connection (at most a "100 Continue" it
 * sent before), and the caller holds conn_lock, which on_request takes
 * before it routes a completed request, so no answer of its own can start
 * meanwhile; timed_out makes it route nothing afterwards. */
static void answer_timeout_locked(fm_http_server *s, conn_track *t)
{
    fm_http_error err;
    memset(&err, 0, sizeof err);
    err.status = 408;
    snprintf(err.code, sizeof err.code, "request_timeout");
    snprintf(err.message, sizeof err.message,
             "the request took over %d ms to arrive (request_deadline_ms)",
             s->cfg.request_deadline_ms);
    json_t *body = error_json(&err);
    char *text = body ? json_dumps(body, JSON_COMPACT) : NULL;
    json_decref(body);
    char head[256];
    size_t n = text ? strlen(text) : 0;
    int h = snprintf(head, sizeof head,
                     "HTTP/1.1 408 Request Timeout\r\nContent-Type: application/json\r\n"
                     "Cache-Control: no-store\r\nConnection: close\r\nContent-Length: %zu\r\n\r\n",
                     n + 1);
    /* Best effort: a few hundred bytes fit in any socket buffer, and a peer
     * that cannot take them loses only the explanation. */
    if (text && t->fd >= 0 && h > 0 && (size_t)h < sizeof head &&
        send(t->fd, head, (size_t)h, MSG_NOSIGNAL | MSG_DONTWAIT) == h &&
        send(t->fd, text, n, MSG_NOSIGNAL | MSG_DONTWAIT) == (ssize_t)n)
        (void)send(t->fd, "\n", 1, MSG_NOSIGNAL | MSG_DONTWAIT);
    free(text);
    if (t->fd >= 0) shutdown(t->fd, SHUT_RDWR);
    t->timed_out = 1;
    t->receiving = 0;
    t->in_body = 0;
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *con, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    (void)version;
    fm_http_server *s = cls;
    request *req = *con_cls;
    conn_track *track = track_of(con);
    if (!req) {
        req = calloc(1, sizeof *req);
        if (!req) return MHD_NO;
        *con_cls = req;
        if (track && track->over_limit) {
            req->rejected = 1;
            return fail(con, 503, "connection_limit",
                        "too many connections (at most %d in all and %d per address); retry "
                        "later",
                        s->cfg.max_connections, s->cfg.max_connections_per_ip);
        }
        const char *length = MHD_lookup_connection_value(con, MHD_HEADER_KIND, "Content-Length");
        if (length) {
            char *end;
            errno = 0;
            unsigned long long n = strtoull(length, &end, 10);
            if (errno || end == length || n > s->cfg.max_request_bytes) {
                req->rejected = 1;
                return fail(con, 413, "request_too_large",
                            "the request body is %s bytes; at most %zu (max_request_mb)", length,
                            s->cfg.max_request_bytes);
            }
        }
        if (track) {
            pthread_mutex_lock(&s->conn_lock);
            track->in_body = 1;
            pthread_mutex_unlock(&s->conn_lock);
        }
        return MHD_YES;
    }
    if (*upload_data_size) {
        size_t n = *upload_data_size;
        *upload_data_size = 0;
        double deadline = s->cfg.request_deadline_ms / 1000.0;
        int gone = 0;
        if (track) {
            pthread_mutex_lock(&s->conn_lock);
            if (!track->timed_out && fm_clock_monotonic_s() - track->request_start > deadline)
                answer_timeout_locked(s, track);
            gone = track->timed_out;
            pthread_mutex_unlock(&s->conn_lock);
        }
        if (gone) return MHD_NO;
        /* A response is queued, or will be once the body ends: drop the rest. */
        if (req->rejected || req->refused.status) return MHD_YES;
        if (req->size + n > s->cfg.max_request_bytes) {
            /* Mid-body, libmicrohttpd takes no response (a body without a
             * Content-Length, chunked): answer once it has ended. */
            req->refused.status = 413;
            snprintf(req->refused.code, sizeof req->refused.code, "request_too_large");
            snprintf(req->refused.message, sizeof req->refused.message,
                     "the request body is over %zu bytes (max_request_mb)",
                     s->cfg.max_request_bytes);
            free(req->body);
            req->body = NULL;
            req->size = req->cap = 0;
            return MHD_YES;
        }
        if (req->size + n + 1 > req->cap) {
            size_t cap = req->cap ? req->cap : 16384;
            while (cap < req->size + n + 1) cap *= 2;
            char *body = realloc(req->body, cap);
            if (!body) {
                req->rejected = 1;
                return fail(con, 503, "out_of_memory", "cannot buffer the request body");
            }
            req->body = body;
            req->cap = cap;
        }
        memcpy(req->body + req->size, upload_data, n);
        req->size += n;
        req->body[req->size] = '\0';
        return MHD_YES;
    }
    if (req->rejected) return MHD_YES;
    if (track) {
        pthread_mutex_lock(&s->conn_lock);
        int gone = track->timed_out;
        track->receiving = 0;
        track->in_body = 0;
        pthread_mutex_unlock(&s->conn_lock);
        if (gone) return MHD_NO;
    }
    if (req->refused.status) {
        req->rejected = 1;
        return respond_error(con, &req->refused, 1);
    }
    return route(s, con, url, method, req);
}

static void on_completed(void *cls, struct MHD_Connection *con, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    (void)toe;
    fm_http_server *s = cls;
    request *req = *con_cls;
    if (req) {
        free(req->body);
        free(req);
        *con_cls = NULL;
    }
    /* On a kept-alive connection the next request's clock starts now. */
    conn_track *track = track_of(con);
    if (track) {
        pthread_mutex_lock(&s->conn_lock);
        track->request_start = fm_clock_monotonic_s();
        track->receiving = 1;
        track->in_body = 0;
        pthread_mutex_unlock(&s->conn_lock);
    }
}

static void on_connection(void *cls, struct MHD_Connection *con, void **socket_context,
                          enum MHD_ConnectionNotificationCode code)
{
    fm_http_server *s = cls;
    if (code == MHD_CONNECTION_NOTIFY_STARTED) {
        conn_track *t = calloc(1, sizeof *t);
        if (!t) return;
        const union MHD_ConnectionInfo *fdinfo =
            MHD_get_connection_info(con, MHD_CONNECTION_INFO_CONNECTION_FD);
        t->fd = fdinfo ? fdinfo->connect_fd : -1;
        t->peer_len = sizeof t->peer;
        if (t->fd < 0 || getpeername(t->fd, (struct sockaddr *)&t->peer, &t->peer_len) != 0)
            t->peer_len = 0;
        const union MHD_ConnectionInfo *addr =
            MHD_get_connection_info(con, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
        if (addr && addr->client_addr) {
            const struct sockaddr *sa = addr->client_addr;
            if (sa->sa_family == AF_INET)
                inet_ntop(AF_INET, &((const struct sockaddr_in *)sa)->sin_addr, t->ip,
                          sizeof t->ip);
            else if (sa->sa_family == AF_INET6)
                inet_ntop(AF_INET6, &((const struct sockaddr_in6 *)sa)->sin6_addr, t->ip,
                          sizeof t->ip);
        }
        t->request_start = fm_clock_monotonic_s();
        t->receiving = 1;
        pthread_mutex_lock(&s->conn_lock);
        int same_ip = 0;
        for (conn_track *o = s->conns; o; o = o->next)
            if (!strcmp(o->ip, t->ip)) same_ip++;
        t->over_limit = s->conn_count >= s->cfg.max_connections ||
                        same_ip >= s->cfg.max_connections_per_ip;
        t->next = s->conns;
        if (s->conns) s->conns->prev = t;
        s->conns = t;
        s->conn_count++;
        pthread_mutex_unlock(&s->conn_lock);
        *socket_context = t;
    } else if (code == MHD_CONNECTION_NOTIFY_CLOSED) {
        conn_track *t = *socket_context;
        if (!t) return;
        pthread_mutex_lock(&s->conn_lock);
        if (t->prev) t->prev->next = t->next;
        else s->conns = t->next;
        if (t->next) t->next->prev = t->prev;
        s->conn_count--;
        pthread_mutex_unlock(&s->conn_lock);
        free(t);
        *socket_context = NULL;
    }
}

/* Close connections whose request has been arriving for longer than the
 * deadline. The socket is shut down, not closed: libmicrohttpd still owns
 * the descriptor and closes it itself once its thread sees end-of-stream.
 * The peer address is compared first, so a descriptor number reused by a
 * newer connection (possible only if libmicrohttpd closed the old socket
 * before notifying us) is never touched. */
static void *sweeper_main(void *arg)
{
    fm_http_server *s = arg;
    pthread_mutex_lock(&s->stop_lock);
    while (!s->stopping) {
        struct timespec until;
        fm_clock_deadline(&until, 0.25);
        pthread_cond_timedwait(&s->stop_cond, &s->stop_lock, &until);
        if (s->stopping) break;
        pthread_mutex_unlock(&s->stop_lock);
        double deadline = s->cfg.request_deadline_ms / 1000.0, now = fm_clock_monotonic_s();
        pthread_mutex_lock(&s->conn_lock);
        for (conn_track *t = s->conns; t; t = t->next) {
            if (!t->receiving || now - t->request_start <= deadline || t->fd < 0) continue;
            struct sockaddr_storage peer;
            socklen_t len = sizeof peer;
            if (t->peer_len && getpeername(t->fd, (struct sockaddr *)&peer, &len) == 0 &&
                len == t->peer_len && !memcmp(&peer, &t->peer, len)) {
                /* A body that trickles gets its 408; headers that trickle,
                 * or an idle kept-alive connection, are only closed. */
                if (t->in_body) answer_timeout_locked(s, t);
                else shutdown(t->fd, SHUT_RDWR);
                logf_(s, FM_HTTP_LOG_WARN,
                      "http: closed a connection from %s: its request took over %d ms",
                      t->ip, s->cfg.request_deadline_ms);
            }
            t->receiving = 0; /* once */
        }
        pthread_mutex_unlock(&s->conn_lock);
        pthread_mutex_lock(&s->stop_lock);
    }
    pthread_mutex_unlock(&s->stop_lock);
    return NULL;
}

static void mhd_log(void *cls, const char *fmt, va_list ap)
{
    fm_http_server *s = cls;
    if (!s->cfg.log) return;
    char buf[512];
    vsnprintf(buf, sizeof buf, fmt, ap);
    size_t n = strlen(buf);
    while (n && (buf[n - 1] == '\n' || buf[n - 1] == '\r')) buf[--n] = '\0';
    s->cfg.log(s->cfg.log_ctx, FM_HTTP_LOG_DEBUG, buf);
}

fm_status fm_http_server_start(const fm_http_config *cfg, const fm_http_service *svc,
                               fm_http_server **out, fm_error *err)
{
    *out = NULL;
    fm_http_server *s = calloc(1, sizeof *s);
    if (!s) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    s->cfg = *cfg;
    s->svc = *svc;
    pthread_mutex_init(&s->conn_lock, NULL);
    pthread_mutex_init(&s->stop_lock, NULL);
    pthread_cond_init(&s->stop_cond, NULL);

    struct sockaddr_in addr;
    memset(&addr, 0, sizeof addr);
    addr.sin_family = AF_INET;
    addr.sin_port = htons(cfg->port);
    const char *host = !strcmp(cfg->listen_addr, "localhost") ? "127.0.0.1" : cfg->listen_addr;
    if (inet_pton(AF_INET, host, &addr.sin_addr) != 1) {
        free(s);
        return fm_error_set(err, FM_ERR_INPUT, "listen address '%s' is not a numeric IPv4 address",
                            cfg->listen_addr);
    }
    /* libmicrohttpd's own limits sit above ours, so that our connection
     * tracking answers the first excess connections with a JSON error and
     * libmicrohttpd refuses only a flood beyond that. */
    unsigned hard_total = (unsigned)cfg->max_connections + 16;
    unsigned hard_per_ip = (unsigned)cfg->max_connections_per_ip + 8;
    s->mhd = MHD_start_daemon(
        MHD_USE_THREAD_PER_CONNECTION | MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_POLL |
            MHD_USE_ERROR_LOG,
        0, NULL, NULL, on_request, s, MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&addr,
        MHD_OPTION_CONNECTION_LIMIT, hard_total, MHD_OPTION_PER_IP_CONNECTION_LIMIT, hard_per_ip,
        MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)cfg->idle_timeout_s,
        MHD_OPTION_NOTIFY_COMPLETED, on_completed, s, MHD_OPTION_NOTIFY_CONNECTION, on_connection,
        s, MHD_OPTION_THREAD_STACK_SIZE, (size_t)(512 * 1024), MHD_OPTION_EXTERNAL_LOGGER, mhd_log,
        s, MHD_OPTION_END);
    if (!s->mhd) {
        int e = errno;
        free(s);
        return fm_error_set(err, FM_ERR_IO, "cannot listen on %s:%u: %s", cfg->listen_addr,
                            (unsigned)cfg->port, e ? strerror(e) : "libmicrohttpd refused");
    }
    const union MHD_DaemonInfo *info = MHD_get_daemon_info(s->mhd, MHD_DAEMON_INFO_BIND_PORT);
    s->port = info ? info->port : cfg->port;
    if (pthread_create(&s->sweeper, NULL, sweeper_main, s) == 0) s->sweeper_started = 1;
    *out = s;
    return FM_OK;
}

uint16_t fm_http_server_port(const fm_http_server *server)
{
    return server->port;
}

void fm_http_server_stop(fm_http_server *s)
{
    if (!s) return;
    pthread_mutex_lock(&s->stop_lock);
    s->stopping = 1;
    pthread_cond_broadcast(&s->stop_cond);
    pthread_mutex_unlock(&s->stop_lock);
    if (s->sweeper_started) pthread_join(s->sweeper, NULL);
    /* Event streams notice `stopping` within one wait and end. */
    MHD_stop_daemon(s->mhd);
    pthread_mutex_destroy(&s->conn_lock);
    pthread_mutex_destroy(&s->stop_lock);
    pthread_cond_destroy(&s->stop_cond);
    free(s);
}
