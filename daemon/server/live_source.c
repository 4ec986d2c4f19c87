/* live_source.c: live mode from MTConnect. A thread connects to the
 * configured source and turns its observations into live positions:
 * - shdr://HOST:PORT, an adapter: the SHDR stream read by
 *   protocols/mtconnect's reader, with the "* PING" / "* PONG ms" heartbeat
 *   (the connection is taken for dead after two heartbeats of silence);
 * - mtconnect://HOST:PORT/DEVICE, an agent: its current document, then its
 *   sample documents from nextSequence on (polled every 50 ms while there
 *   is nothing new), read by protocols/mtconnect's Streams reader.
 * Observations of one timestamp make one position (an adapter writes X
 * and Z of one instant on one line or several); a position is the mapped
 * X/Y/Z times the scale, the mapped A/B/C in degrees (the joints of the
 * live job's machine), the tool, the program line and the spindle speed.
 * When the live job's queue is full (the cut falls behind, "busy") the
 * newest position waits and replaces the one before it:
 * positions are coalesced, never queued without bound. A lost connection
 * is tried again after 1, 2, 4... s up to reconnect_max_s, which the live
 * job's status says (live_source). */
#include "live_source.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <netdb.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "log.h"
#include "mtconnect/mtconnect.h"
#include "runner/machine.h"

#define HEARTBEAT_DEFAULT_MS 10000
#define SILENCE_WITHOUT_HEARTBEAT_S 600.0
#define AGENT_POLL_MS 50
#define AGENT_REPLY_MAX FM_MTC_STREAMS_MAX
#define CONNECT_TIMEOUT_MS 5000
#define STREAM_HEARTBEAT_MS 1000

static const char *const map_keys[FM_LIVE_MAP_KEYS] = {"X", "Y", "Z", "A", "B", "C", "tool", "line", "S"};

struct fm_live_source {
    fm_live_source_config cfg;
    char source[512];
    fm_live_map map;
    int is_shdr;
    char host[256], port[16], device[128];
    fm_jobs *jobs;
    pthread_t thread;
    atomic_int stopping;

    /* The machine's state (the thread's own). */
    double value[6];
    int known[6];
    long tool;
    long line;             /* 0 until the mapped line has a value */
    double spindle_rpm;    /* NAN until the mapped speed has a value */
    int pending;           /* a mapped value changed since the last position given */
    double pending_time;   /* the timestamp of the observations pending */
    int started;           /* the live job was started */
    long positions;        /* given to the live job */
    long coalesced;        /* replaced while the queue was full */
};

static void sleep_ms(long ms)
{
    struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

static double mono_s(void)
{
    return fm_clock_monotonic_s();
}

int fm_live_map_parse(const char *text, fm_live_map *out, char *msg, size_t msg_size)
{
    memset(out, 0, sizeof *out);
    const char *p = text;
    while (*p) {
        while (*p == ' ' || *p == ',') p++;
        if (!*p) break;
        const char *eq = strchr(p, '=');
        const char *end = strchr(p, ',');
        if (!end) end = p + strlen(p);
        if (!eq || eq > end) {
            snprintf(msg, msg_size, "live_map: \"%.*s\" is not AXIS=NAME", (int)(end - p), p);
            return -1;
        }
        int key = -1;
        for (int k = 0; k < FM_LIVE_MAP_KEYS; k++)
            if ((size_t)(eq - p) == strlen(map_keys[k]) && !strncasecmp(p, map_keys[k], (size_t)(eq - p)))
                key = k;
        if (key < 0) {
            snprintf(msg, msg_size,
                     "live_map: %.*s cannot be mapped (the keys are X, Y, Z, A, B, C, tool, line, S)",
                     (int)(eq - p), p);
            return -1;
        }
        if (out->name[key][0]) {
            snprintf(msg, msg_size, "live_map: %s is mapped twice", map_keys[key]);
            return -1;
        }
        size_t n = (size_t)(end - eq - 1);
        while (n && eq[n] == ' ') n--;
        if (!n || n >= sizeof out->name[0]) {
            snprintf(msg, msg_size, "live_map: the data item of %s is empty or too long", map_keys[key]);
            return -1;
        }
        memcpy(out->name[key], eq + 1, n);
        out->name[key][n] = '\0';
        p = end;
    }
    if (!out->name[0][0] && !out->name[1][0] && !out->name[2][0]) {
        snprintf(msg, msg_size, "live_map must map at least one of X, Y, Z (e.g. X=Xact,Z=Zact)");
        return -1;
    }
    return 0;
}

int fm_live_map_check_rotary(const fm_live_map *map, int rotary_letters, const char *machine, char *msg,
                             size_t msg_size)
{
    for (int a = 0; a < 3; a++) {
        if (!map->name[3 + a][0] || (rotary_letters & (1 << a))) continue;
        if (machine && machine[0])
            snprintf(msg, msg_size, "live_map maps %c, which the machine file %s has no rotary axis for",
                     'A' + a, machine);
        else
            snprintf(msg, msg_size,
                     "live_map maps %c: rotary axes need live_machine, a machine file with them "
                     "(docs/check.md)",
                     'A' + a);
        return -1;
    }
    return 0;
}

/* Split SCHEME://HOST:PORT[/DEVICE]. */
static int split_source(const char *source, int *is_shdr, char *host, size_t host_size, char *port,
                        size_t port_size, char *device, size_t device_size, char *msg, size_t msg_size)
{
    const char *rest;
    if (!strncmp(source, "shdr://", 7)) {
        *is_shdr = 1;
        rest = source + 7;
    } else if (!strncmp(source, "mtconnect://", 12)) {
        *is_shdr = 0;
        rest = source + 12;
    } else {
        snprintf(msg, msg_size, "live_source must be shdr://HOST:PORT or mtconnect://HOST:PORT/DEVICE");
        return -1;
    }
    const char *slash = strchr(rest, '/');
    const char *colon = strrchr(rest, ':');
    if (slash && colon > slash) colon = NULL;
    size_t host_len = (size_t)((colon ? colon : slash ? slash : rest + strlen(rest)) - rest);
    if (!colon || !host_len || host_len >= host_size) {
        snprintf(msg, msg_size, "live_source %s: a host and a port are needed", source);
        return -1;
    }
    memcpy(host, rest, host_len);
    host[host_len] = '\0';
    size_t port_len = (size_t)((slash ? slash : rest + strlen(rest)) - colon - 1);
    if (!port_len || port_len >= port_size || strspn(colon + 1, "0123456789") < port_len) {
        snprintf(msg, msg_size, "live_source %s: the port must be a number", source);
        return -1;
    }
    memcpy(port, colon + 1, port_len);
    port[port_len] = '\0';
    device[0] = '\0';
    if (slash && slash[1]) snprintf(device, device_size, "%s", slash + 1);
    if (*is_shdr && slash && slash[1]) {
        snprintf(msg, msg_size, "live_source %s: an SHDR adapter has no device path", source);
        return -1;
    }
    return 0;
}

int fm_live_source_check(const char *source, char *msg, size_t msg_size)
{
    int is_shdr;
    char host[256], port[16], device[128];
    return split_source(source, &is_shdr, host, sizeof host, port, sizeof port, device, sizeof device,
                        msg, msg_size);
}

static void note(fm_live_source *s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void note(fm_live_source *s, const char *fmt, ...)
{
    char text[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    fm_jobs_live_note(s->jobs, text);
}

/* ---------------------------------------------------------- positions -- */


static void start_live_job(fm_live_source *s)
{
    if (fm_jobs_live_active(s->jobs)) {
        s->started = 1;
        return;
    }
    fm_error err;
    fm_error_clear(&err);
    if (fm_jobs_live_start(s->jobs, 0, &err) == FM_OK) {
        s->started = 1;
        fm_log(FM_LOG_INFO, "live: following %s", s->source);
        note(s, "following %s", s->source);
    } else {
        fm_log(FM_LOG_WARN, "live: cannot start the live job for %s: %s", s->source, err.message);
    }
}

/* Give the pending position to the live job; when its queue is full the
 * position stays pending, to be replaced by the next (coalesced). */
static void flush(fm_live_source *s)
{
    if (!s->pending) return;
    fm_live_pose pose;
    double xyz[3] = {0, 0, 0};
    fm_live_pose_init(&pose, xyz, s->map.name[FM_LIVE_MAP_TOOL][0] ? (int)s->tool : 1);
    for (int a = 0; a < 6; a++) {
        if (s->map.name[a][0] && !s->known[a]) return; /* not all axes seen yet */
        /* lengths in the source's units, angles in degrees */
        if (a < 3) pose.xyz[a] = s->map.name[a][0] ? s->value[a] * s->cfg.scale : 0.0;
        else if (s->map.name[a][0]) pose.abc[a - 3] = s->value[a];
    }
    pose.line = s->line > 0 && s->line <= INT_MAX ? (int)s->line : 0;
    pose.spindle_rpm = s->spindle_rpm;
    if (!s->started) start_live_job(s);
    fm_error err;
    fm_error_clear(&err);
    fm_status st = fm_jobs_live_position(s->jobs, &pose, &err);
    if (st != FM_OK && strcmp(err.reason, "busy") != 0) {
        /* The live job ended (cancelled, or switched off): a new one. */
        s->started = 0;
        start_live_job(s);
        fm_error_clear(&err);
        st = fm_jobs_live_position(s->jobs, &pose, &err);
    }
    if (st == FM_OK) {
        s->pending = 0;
        s->positions++;
    } else if (!strcmp(err.reason, "busy")) {
        s->coalesced++;
    } else {
        s->pending = 0;
        fm_log(FM_LOG_WARN, "live: position refused: %s", err.message);
    }
}

/* One observation by the data item's name (or id). */
static void observe(fm_live_source *s, const char *name, const char *id, const char *value, double time)
{
    for (int k = 0; k < FM_LIVE_MAP_KEYS; k++) {
        const char *want = s->map.name[k];
        if (!want[0] || (strcmp(want, name ? name : "") && strcmp(want, id ? id : ""))) continue;
        if (!strcmp(value, "UNAVAILABLE")) continue;
        char *end;
        double v = strtod(value, &end);
        if (end == value || !isfinite(v)) continue;
        /* a tool or line number out of an int's range is not one */
        if ((k == FM_LIVE_MAP_TOOL || k == FM_LIVE_MAP_LINE) && !(fabs(v) < 1e9)) continue;
        /* A new instant: the position of the one before is complete. */
        if (s->pending && !(time == s->pending_time || (isnan(time) && isnan(s->pending_time)))) flush(s);
        if (k < 6) {
            if (s->known[k] && s->value[k] == v) continue;
            s->value[k] = v;
            s->known[k] = 1;
        } else if (k == FM_LIVE_MAP_TOOL) {
            if (s->tool == (long)v) continue;
            s->tool = (long)v;
        } else if (k == FM_LIVE_MAP_LINE) {
            if (s->line == (long)v) continue;
            s->line = (long)v;
        } else {
            if (s->spindle_rpm == v) continue;
            s->spindle_rpm = v;
        }
        if (!s->pending) s->pending_time = time;
        s->pending = 1;
    }
}

/* ------------------------------------------------------------- network -- */

static int connect_to(fm_live_source *s, char *why, size_t why_size)
{
    struct addrinfo hints, *res = NULL;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    int rc = getaddrinfo(s->host, s->port, &hints, &res);
    if (rc != 0) {
        snprintf(why, why_size, "%.100s: %.100s", s->host, gai_strerror(rc));
        return -1;
    }
    int fd = -1;
    for (struct addrinfo *a = res; a && fd < 0; a = a->ai_next) {
        fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
        if (fd < 0) continue;
        /* Non-blocking, so that an unreachable host costs CONNECT_TIMEOUT_MS
         * and a stopping daemon no more than a poll. */
        int flags = fcntl(fd, F_GETFL);
        fcntl(fd, F_SETFL, flags | O_NONBLOCK);
        int rc2 = connect(fd, a->ai_addr, a->ai_addrlen);
        int e = rc2 == 0 ? 0 : errno;
        if (e == EINPROGRESS) {
            e = ETIMEDOUT;
            for (int waited = 0; waited < CONNECT_TIMEOUT_MS && !atomic_load(&s->stopping); waited += 100) {
                struct pollfd p = {fd, POLLOUT, 0};
                if (poll(&p, 1, 100) > 0) {
                    socklen_t len = sizeof e;
                    if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &e, &len) != 0) e = errno;
                    break;
                }
            }
        }
        if (e != 0) {
            snprintf(why, why_size, "%.100s:%.15s: %.100s", s->host, s->port, strerror(e));
            close(fd);
            fd = -1;
        } else {
            fcntl(fd, F_SETFL, flags);
        }
    }
    freeaddrinfo(res);
    return fd;
}

static int send_all(int fd, const char *text, size_t n)
{
    while (n) {
        ssize_t w = send(fd, text, n, MSG_NOSIGNAL);
        if (w <= 0) {
            if (w < 0 && errno == EINTR) continue;
            return -1;
        }
        text += w;
        n -= (size_t)w;
    }
    return 0;
}

typedef struct shdr_ctx {
    fm_live_source *s;
    long pong_ms;
} shdr_ctx;

static void shdr_observation(void *ctx, const fm_shdr_observation *o)
{
    shdr_ctx *c = ctx;
    if (o->kind == FM_SHDR_VALUE) observe(c->s, o->key, NULL, o->value, o->timestamp);
}

static void shdr_command(void *ctx, const char *text, long pong_ms)
{
    (void)text;
    shdr_ctx *c = ctx;
    if (pong_ms > 0) c->pong_ms = pong_ms;
}

static void shdr_malformed(void *ctx, uint64_t line, size_t column, const char *why)
{
    shdr_ctx *c = ctx;
    fm_log(FM_LOG_WARN, "live: %s line %llu column %zu: %s (skipped)", c->s->source,
           (unsigned long long)line, column, why);
}

/* Follow an adapter until the connection ends; the reason in why. Returns
 * 1 when the adapter sent anything (the wait before the next attempt
 * starts again from 1 s only then: an adapter that accepts and closes at
 * once is tried less and less often). */
static int run_shdr(fm_live_source *s, int fd, char *why, size_t why_size)
{
    shdr_ctx c = {s, -1};
    fm_shdr_handlers h = {&c, NULL, shdr_observation, NULL, shdr_command, shdr_malformed};
    fm_shdr_reader *r = fm_shdr_reader_new(NULL, &h);
    if (!r) {
        snprintf(why, why_size, "out of memory");
        return 0;
    }
    int received = 0;
    double last_data = mono_s(), last_ping = -1e9;
    char buf[65536];
    while (!atomic_load(&s->stopping)) {
        double now = mono_s();
        long hb = c.pong_ms > 0 ? c.pong_ms : HEARTBEAT_DEFAULT_MS;
        if ((now - last_ping) * 1000.0 >= (double)hb) {
            if (send_all(fd, "* PING\n", 7) != 0) {
                snprintf(why, why_size, "cannot send the heartbeat: %s", strerror(errno));
                break;
            }
            last_ping = now;
        }
        double silence = c.pong_ms > 0 ? 2.0 * c.pong_ms / 1000.0 : SILENCE_WITHOUT_HEARTBEAT_S;
        if (now - last_data > silence) {
            snprintf(why, why_size, "silent for %.1f s (heartbeat %ld ms)", now - last_data, c.pong_ms);
            break;
        }
        struct pollfd p = {fd, POLLIN, 0};
        int n = poll(&p, 1, 50);
        if (n < 0 && errno != EINTR) {
            snprintf(why, why_size, "poll: %s", strerror(errno));
            break;
        }
        if (n <= 0) {
            flush(s); /* quiet: the last instant is complete (or retried when busy) */
            continue;
        }
        ssize_t got = recv(fd, buf, sizeof buf, 0);
        if (got == 0) {
            snprintf(why, why_size, "the adapter closed the connection");
            break;
        }
        if (got < 0) {
            if (errno == EINTR || errno == EAGAIN) continue;
            snprintf(why, why_size, "recv: %s", strerror(errno));
            break;
        }
        last_data = mono_s();
        received = 1;
        fm_shdr_reader_feed(r, buf, (size_t)got);
    }
    fm_shdr_reader_finish(r);
    fm_shdr_reader_free(r);
    flush(s);
    return received;
}

/* GET path from the agent (HTTP/1.0, the connection closed after): the
 * body, malloc'd, or NULL with why. */
static char *http_get(fm_live_source *s, const char *path, size_t *size, int *status, char *why,
                      size_t why_size)
{
    int fd = connect_to(s, why, why_size);
    if (fd < 0) return NULL;
    char req[1024];
    int n = snprintf(req, sizeof req, "GET %s HTTP/1.0\r\nHost: %s\r\nAccept: text/xml\r\n\r\n", path, s->host);
    if (send_all(fd, req, (size_t)n) != 0) {
        snprintf(why, why_size, "send: %s", strerror(errno));
        close(fd);
        return NULL;
    }
    size_t cap = 65536, len = 0;
    char *buf = malloc(cap + 1);
    while (buf) {
        int ready = 0;
        for (int waited = 0; waited < 10000 && !ready && !atomic_load(&s->stopping); waited += 100) {
            struct pollfd p = {fd, POLLIN, 0};
            ready = poll(&p, 1, 100) > 0;
        }
        if (!ready) {
            snprintf(why, why_size, "the agent did not answer within 10 s");
            free(buf);
            buf = NULL;
            break;
        }
        if (len == cap) {
            if (cap >= AGENT_REPLY_MAX) {
                snprintf(why, why_size, "the agent's answer is over %zu bytes", AGENT_REPLY_MAX);
                free(buf);
                buf = NULL;
                break;
            }
            char *b = realloc(buf, cap * 2 + 1);
            if (!b) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = b;
            cap *= 2;
        }
        ssize_t got = recv(fd, buf + len, cap - len, 0);
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) break;
        len += (size_t)got;
    }
    close(fd);
    if (!buf) return NULL;
    buf[len] = '\0';
    char *body = strstr(buf, "\r\n\r\n");
    if (!body || sscanf(buf, "HTTP/%*s %d", status) != 1) {
        snprintf(why, why_size, "the agent's answer is not HTTP");
        free(buf);
        return NULL;
    }
    body += 4;
    *size = len - (size_t)(body - buf);
    memmove(buf, body, *size + 1);
    return buf;
}

static void agent_observation(void *ctx, const fm_mtc_observation *o)
{
    observe(ctx, o->name, o->data_item_id, o->value, o->time);
}

/* Apply a Streams document in sequence order (protocols/mtconnect's
 * reader); its nextSequence in *next. -1 with why when it is not one. */
static int apply_streams(fm_live_source *s, const char *body, size_t size, uint64_t *next, char *why,
                         size_t why_size)
{
    return fm_mtc_streams_read(body, size, agent_observation, s, next, why, why_size);
}

/* The sample stream (interval=0, heartbeat 1 s): each multipart part a
 * Streams document applied as it arrives. Returns 0 when the agent does
 * not stream (the caller polls instead), else 1 when the stream ended
 * (why says how). */
static int stream_samples(fm_live_source *s, uint64_t next, char *why, size_t why_size)
{
    int fd = connect_to(s, why, why_size);
    if (fd < 0) return 1;
    char req[1024];
    int n = snprintf(req, sizeof req,
                     "GET /%s%ssample?from=%llu&count=1000&interval=0&heartbeat=%d HTTP/1.0\r\nHost: "
                     "%s\r\n\r\n",
                     s->device, s->device[0] ? "/" : "", (unsigned long long)next, STREAM_HEARTBEAT_MS,
                     s->host);
    if (n <= 0 || (size_t)n >= sizeof req || send_all(fd, req, (size_t)n) != 0) {
        snprintf(why, why_size, "cannot ask the agent for its sample stream");
        close(fd);
        return 1;
    }
    size_t cap = 65536, len = 0;
    char *buf = malloc(cap + 1);
    char boundary[128] = "";
    int streamed = 1;
    double last_data = mono_s();
    while (buf && !atomic_load(&s->stopping)) {
        struct pollfd p = {fd, POLLIN, 0};
        int ready = poll(&p, 1, 100);
        if (ready < 0 && errno != EINTR) {
            snprintf(why, why_size, "poll: %s", strerror(errno));
            break;
        }
        if (ready > 0) {
            if (len == cap) {
                if (cap >= AGENT_REPLY_MAX) {
                    snprintf(why, why_size, "a part of the agent's stream is over %zu bytes", AGENT_REPLY_MAX);
                    break;
                }
                char *b = realloc(buf, cap * 2 + 1);
                if (!b) break;
                buf = b;
                cap *= 2;
            }
            ssize_t got = recv(fd, buf + len, cap - len, 0);
            if (got < 0 && errno == EINTR) continue;
            if (got <= 0) {
                snprintf(why, why_size, "the agent closed its sample stream");
                break;
            }
            len += (size_t)got;
            buf[len] = '\0';
            last_data = mono_s();
        } else if (mono_s() - last_data > 3.0 * STREAM_HEARTBEAT_MS / 1000.0) {
            snprintf(why, why_size, "the agent's sample stream was silent for %.1f s", mono_s() - last_data);
            break;
        }
        if (!boundary[0]) {
            char *end = strstr(buf, "\r\n\r\n");
            if (!end) continue;
            int status = 0;
            const char *b = strstr(buf, "boundary=");
            if (sscanf(buf, "HTTP/%*s %d", &status) != 1 || status != 200 || !b || b > end) {
                streamed = 0; /* no stream: poll */
                break;
            }
            b += 9;
            size_t bl = strcspn(b, "\r\n;\" ");
            if (bl == 0 || bl + 3 >= sizeof boundary) {
                streamed = 0;
                break;
            }
            boundary[0] = boundary[1] = '-';
            memcpy(boundary + 2, b, bl);
            boundary[bl + 2] = '\0';
            end += 4;
            len -= (size_t)(end - buf);
            memmove(buf, end, len + 1);
        }
        /* Whole parts: "--BOUNDARY\r\n", headers with Content-length, a blank
         * line, the document. */
        int failed = 0;
        for (;;) {
            char *start = strstr(buf, boundary);
            if (!start) break;
            char *head_end = strstr(start, "\r\n\r\n");
            if (!head_end) break;
            const char *cl = NULL;
            for (const char *c = start; c < head_end && !cl; c++)
                if (!strncasecmp(c, "content-length:", 15)) cl = c;
            if (!cl) {
                snprintf(why, why_size, "a part of the agent's stream has no Content-length");
                failed = 1;
                break;
            }
            size_t size = strtoul(cl + 15, NULL, 10);
            char *body = head_end + 4;
            if ((size_t)(buf + len - body) < size) break;
            uint64_t after = next;
            if (apply_streams(s, body, size, &after, why, why_size) != 0) {
                failed = 1;
                break;
            }
            next = after;
            flush(s);
            size_t used = (size_t)(body + size - buf);
            len -= used;
            memmove(buf, buf + used, len + 1);
        }
        if (failed) break;
    }
    free(buf);
    close(fd);
    if (streamed && !why[0]) snprintf(why, why_size, "the sample stream ended");
    return streamed;
}

/* Follow an agent: current, then samples from its nextSequence. */
static void run_agent(fm_live_source *s, char *why, size_t why_size)
{
    char path[512];
    snprintf(path, sizeof path, "/%s%scurrent", s->device, s->device[0] ? "/" : "");
    size_t size = 0;
    int status = 0;
    char *body = http_get(s, path, &size, &status, why, why_size);
    if (!body) return;
    uint64_t next = 0;
    int ok = status == 200 && apply_streams(s, body, size, &next, why, why_size) == 0;
    if (status != 200) snprintf(why, why_size, "GET %.200s answered %d", path, status);
    free(body);
    if (!ok) return;
    if (!s->started) start_live_job(s);
    note(s, "following %s", s->source);
    flush(s);
    if (stream_samples(s, next, why, why_size)) return;
    fm_log(FM_LOG_INFO, "live: %s does not stream its samples; polling", s->source);
    why[0] = '\0';
    while (!atomic_load(&s->stopping)) {
        snprintf(path, sizeof path, "/%s%ssample?from=%llu&count=1000", s->device, s->device[0] ? "/" : "",
                 (unsigned long long)next);
        body = http_get(s, path, &size, &status, why, why_size);
        if (!body) return;
        uint64_t before = next;
        if (status != 200) {
            /* OUT_OF_RANGE: the agent's buffer moved on (or it restarted):
             * start again from its current state. */
            snprintf(why, why_size, "GET %.200s answered %d", path, status);
            free(body);
            return;
        }
        ok = apply_streams(s, body, size, &next, why, why_size) == 0;
        free(body);
        if (!ok) return;
        flush(s);
        if (next == before) sleep_ms(AGENT_POLL_MS);
    }
}

static void *source_main(void *arg)
{
    fm_live_source *s = arg;
    double wait = 1.0;
    while (!atomic_load(&s->stopping)) {
        char why[256] = "";
        if (s->is_shdr) {
            int fd = connect_to(s, why, sizeof why);
            if (fd >= 0) {
                fm_log(FM_LOG_INFO, "live: connected to %s", s->source);
                note(s, "following %s", s->source);
                if (run_shdr(s, fd, why, sizeof why)) wait = 1.0;
                close(fd);
            }
        } else {
            run_agent(s, why, sizeof why);
            if (s->started) wait = 1.0;
        }
        if (atomic_load(&s->stopping)) break;
        fm_log(FM_LOG_WARN, "live: %s: %s; trying again in %.0f s", s->source, why, wait);
        note(s, "reconnecting to %s in %.0f s: %s", s->source, wait, why);
        for (double until = mono_s() + wait; mono_s() < until && !atomic_load(&s->stopping);)
            sleep_ms(50);
        wait = wait * 2 > s->cfg.reconnect_max_s ? s->cfg.reconnect_max_s : wait * 2;
    }
    return NULL;
}

fm_status fm_live_source_start(const fm_live_source_config *cfg, fm_jobs *jobs, fm_live_source **out,
                               fm_error *err)
{
    *out = NULL;
    fm_live_source *s = calloc(1, sizeof *s);
    if (!s) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    char msg[300];
    snprintf(s->source, sizeof s->source, "%s", cfg->source);
    if (split_source(cfg->source, &s->is_shdr, s->host, sizeof s->host, s->port, sizeof s->port, s->device,
                     sizeof s->device, msg, sizeof msg) != 0 ||
        fm_live_map_parse(cfg->map ? cfg->map : "", &s->map, msg, sizeof msg) != 0) {
        free(s);
        return fm_error_set(err, FM_ERR_INPUT, "%s", msg);
    }
    /* Rotary axes move the tool through the live job's machine: each one
     * mapped must be one of its axes. */
    int rotary_letters = 0;
    if (cfg->machine && cfg->machine[0]) {
        fm_check_machine machine;
        if (fm_check_machine_load(cfg->machine, &machine, err) != FM_OK) {
            free(s);
            return err->code;
        }
        for (int i = 0; i < machine.chain.rotary_count; i++)
            rotary_letters |= 1 << machine.chain.rotary[i].letter;
    }
    if (fm_live_map_check_rotary(&s->map, rotary_letters, cfg->machine, msg, sizeof msg) != 0) {
        free(s);
        return fm_error_set(err, FM_ERR_INPUT, "%s", msg);
    }
    s->cfg = *cfg;
    if (!(s->cfg.scale > 0)) s->cfg.scale = 1.0;
    if (!(s->cfg.reconnect_max_s >= 1)) s->cfg.reconnect_max_s = 30;
    s->jobs = jobs;
    s->tool = 1;
    s->spindle_rpm = NAN;
    if (pthread_create(&s->thread, NULL, source_main, s) != 0) {
        free(s);
        return fm_error_set(err, FM_ERR_INTERNAL, "cannot start the live source's thread");
    }
    *out = s;
    return FM_OK;
}

void fm_live_source_stop(fm_live_source *s)
{
    if (!s) return;
    atomic_store(&s->stopping, 1);
    pthread_join(s->thread, NULL);
    fm_log(FM_LOG_INFO, "live: %s: %ld positions given, %ld coalesced", s->source, s->positions,
           s->coalesced);
    free(s);
}
