/* queue_redis.c: the Redis Streams consumer of queue_redis.h.
 *
 * One thread owns the hiredis connection. Each turn it
 *  1. writes the results of jobs that ended here (the outbox, filled by the
 *     job manager's end hook on worker threads): one Lua script does
 *     HSETNX results <entry> <status>, XADD done (only when HSETNX set it)
 *     and XACK, atomically, so a job yields one result even when two
 *     daemons ran it;
 *  2. renews its claim on the entries it runs (XCLAIM ... JUSTID resets
 *     their idle time) every claim_s / 3, from a script that first checks
 *     that this consumer still owns the entry; an entry lost to another
 *     daemon is released here (no result from us);
 *  3. when a worker is free, takes one entry: an entry idle longer than
 *     claim_s (XAUTOCLAIM: its daemon died), else a new one (XREADGROUP >).
 *     The taking script returns the `job` field only when it fits the job
 *     budget, so an oversized entry is refused before any memory is taken.
 * Entries this consumer already owned (a restart under the same name) are
 * read back with XREADGROUP 0 at every connect.
 *
 * The job id is "q-" + the entry id, so a daemon that shares the state
 * folder of a dead one finds the job's folder and resumes from its
 * snapshot. Redis down: log, back off (0.1 s doubling to 5 s), keep the
 * outbox; nothing is acknowledged before its result is written. */
#include "queue_redis.h"

#include <ctype.h>
#include <errno.h>
#include <hiredis/hiredis.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "log.h"

#define QR_POLL_S 0.1
#define QR_BACKOFF_MIN_S 0.1
#define QR_BACKOFF_MAX_S 5.0
#define QR_IO_TIMEOUT_S 5
#define QR_MAX_RUNNING 256

/* Take one entry: an idle one first (its consumer died), else a new one.
 * KEYS[1] stream; ARGV group, consumer, min idle ms, max job bytes, and
 * "0" to re-read this consumer's own pending entries after ARGV[6] (or ""
 * for the normal path). Returns false, or {id, kind, value}: kind "job"
 * (value: the job JSON), "large" (value: its size), "nojob". */
static const char take_script[] =
    "local function pick(e)\n"
    "  local id, f = e[1], e[2]\n"
    "  if not f then return {id, 'gone', ''} end\n"
    "  for i = 1, #f, 2 do\n"
    "    if f[i] == 'job' then\n"
    "      if #f[i + 1] > tonumber(ARGV[4]) then return {id, 'large', tostring(#f[i + 1])} end\n"
    "      return {id, 'job', f[i + 1]}\n"
    "    end\n"
    "  end\n"
    "  return {id, 'nojob', ''}\n"
    "end\n"
    "if ARGV[5] == '0' then\n"
    "  local r = redis.call('XREADGROUP', 'GROUP', ARGV[1], ARGV[2], 'COUNT', 1,\n"
    "                       'STREAMS', KEYS[1], ARGV[6])\n"
    "  if r and r[1] and r[1][2][1] then return pick(r[1][2][1]) end\n"
    "  return false\n"
    "end\n"
    "local c = redis.call('XAUTOCLAIM', KEYS[1], ARGV[1], ARGV[2], ARGV[3], '0-0', 'COUNT', 1)\n"
    "if c[2][1] then return pick(c[2][1]) end\n"
    "local r = redis.call('XREADGROUP', 'GROUP', ARGV[1], ARGV[2], 'COUNT', 1,\n"
    "                     'STREAMS', KEYS[1], '>')\n"
    "if r and r[1] and r[1][2][1] then return pick(r[1][2][1]) end\n"
    "return false\n";

/* KEYS results, done, stream; ARGV entry id, status JSON, group. 1 when
 * this call wrote the result, 0 when another had. */
static const char finish_script[] =
    "local first = redis.call('HSETNX', KEYS[1], ARGV[1], ARGV[2])\n"
    "if first == 1 then redis.call('XADD', KEYS[2], '*', 'entry', ARGV[1]) end\n"
    "redis.call('XACK', KEYS[3], ARGV[3], ARGV[1])\n"
    "return first\n";

/* KEYS stream; ARGV group, consumer, entry id. 1: still ours (idle time
 * reset), 0: another consumer has it, or it is no longer pending. */
static const char renew_script[] =
    "local p = redis.call('XPENDING', KEYS[1], ARGV[1], ARGV[3], ARGV[3], 1)\n"
    "if p[1] and p[1][2] == ARGV[2] then\n"
    "  redis.call('XCLAIM', KEYS[1], ARGV[1], ARGV[2], 0, ARGV[3], 'JUSTID')\n"
    "  return 1\n"
    "end\n"
    "return 0\n";

typedef struct qr_result {
    char entry[64];
    char *json;
    struct qr_result *next;
} qr_result;

typedef struct qr_running {
    char entry[64];
    int ended;      /* its result is in the outbox (or written) */
} qr_running;

struct fm_redis_queue {
    fm_redis_queue_config cfg;
    char url_text[1024], stream[256], group[256], consumer[256], results[256], done[256];
    fm_redis_url url;
    fm_jobs *jobs;
    pthread_t thread;
    pthread_mutex_t lock;   /* guards stop, outbox, running */
    pthread_cond_t cond;
    int stop;
    qr_result *outbox, *outbox_tail;
    qr_running running[QR_MAX_RUNNING];
    int running_count;
    redisContext *redis;    /* the thread's own */
    double next_renew;
};

/* ------------------------------------------------------------ the URL -- */

static int url_take(const char **p, const char *stop, char *out, size_t size)
{
    size_t n = strcspn(*p, stop);
    if (n >= size) return -1;
    memcpy(out, *p, n);
    out[n] = '\0';
    *p += n;
    return 0;
}

fm_status fm_redis_url_parse(const char *url, fm_redis_url *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    out->port = 6379;
    if (!url) return fm_error_set(err, FM_ERR_INPUT, "no queue URL");
    if (!strncmp(url, "rediss://", 9))
        return fm_error_set(err, FM_ERR_INPUT,
                            "queue '%s': TLS (rediss://) is not supported: Debian 12's hiredis "
                            "0.14 has no TLS; use redis:// on a trusted network or a TLS tunnel",
                            url);
    if (strncmp(url, "redis://", 8) != 0)
        return fm_error_set(err, FM_ERR_INPUT,
                            "queue '%s': expected redis://[user[:password]@]host[:port][/db]", url);
    const char *p = url + 8;
    const char *at = strchr(p, '@');
    if (at) {
        char cred[512];
        if ((size_t)(at - p) >= sizeof cred)
            return fm_error_set(err, FM_ERR_INPUT, "queue URL: the credentials are too long");
        memcpy(cred, p, (size_t)(at - p));
        cred[at - p] = '\0';
        char *colon = strchr(cred, ':');
        if (colon) {
            *colon = '\0';
            if (strlen(colon + 1) >= sizeof out->password || strlen(cred) >= sizeof out->user)
                return fm_error_set(err, FM_ERR_INPUT, "queue URL: the credentials are too long");
            /* lengths checked just above; memcpy keeps GCC's -O2 truncation analysis quiet */
            memcpy(out->user, cred, strlen(cred) + 1);
            memcpy(out->password, colon + 1, strlen(colon + 1) + 1);
        } else {
            /* redis://password@host, as redis-cli -u takes it */
            if (strlen(cred) >= sizeof out->password)
                return fm_error_set(err, FM_ERR_INPUT, "queue URL: the password is too long");
            memcpy(out->password, cred, strlen(cred) + 1);
        }
        p = at + 1;
    }
    if (*p == '[') {
        /* [IPv6]:port */
        p++;
        if (url_take(&p, "]", out->host, sizeof out->host) != 0 || *p != ']')
            return fm_error_set(err, FM_ERR_INPUT, "queue URL: unterminated [address]");
        p++;
    } else if (url_take(&p, ":/", out->host, sizeof out->host) != 0) {
        return fm_error_set(err, FM_ERR_INPUT, "queue URL: the host name is too long");
    }
    if (!out->host[0]) return fm_error_set(err, FM_ERR_INPUT, "queue URL '%s': no host", url);
    for (const char *h = out->host; *h; h++)
        if (!isalnum((unsigned char)*h) && !strchr(".-_:", *h))
            return fm_error_set(err, FM_ERR_INPUT, "queue URL '%s': unexpected '%c' in the host",
                                url, *h);
    if (*p == ':') {
        p++;
        char *end;
        errno = 0;
        long port = strtol(p, &end, 10);
        if (errno || end == p || port < 1 || port > 65535 || (*end && *end != '/'))
            return fm_error_set(err, FM_ERR_INPUT, "queue URL '%s': the port must be 1..65535", url);
        out->port = (unsigned)port;
        p = end;
    }
    if (*p == '/') {
        p++;
        if (*p) {
            char *end;
            errno = 0;
            long db = strtol(p, &end, 10);
            if (errno || end == p || *end || db < 0 || db > 1000000)
                return fm_error_set(err, FM_ERR_INPUT,
                                    "queue URL '%s': the database must be a number 0 or above", url);
            out->db = (int)db;
        }
    } else if (*p) {
        return fm_error_set(err, FM_ERR_INPUT, "queue URL '%s': unexpected '%s' after the host",
                            url, p);
    }
    return FM_OK;
}

/* ------------------------------------------------------ connection -- */

static void qr_disconnect(fm_redis_queue *q, const char *why)
{
    if (!q->redis) return;
    fm_log(FM_LOG_WARN, "queue: lost %s:%u (%s); reconnecting", q->url.host, q->url.port, why);
    redisFree(q->redis);
    q->redis = NULL;
}

/* A reply that is an error, or no reply (the connection broke). */
static int qr_failed(fm_redis_queue *q, redisReply *r, const char *what)
{
    if (!r) {
        qr_disconnect(q, q->redis && q->redis->errstr[0] ? q->redis->errstr : what);
        return 1;
    }
    if (r->type == REDIS_REPLY_ERROR) {
        fm_log(FM_LOG_ERROR, "queue: %s: %s", what, r->str);
        freeReplyObject(r);
        /* A script or command error (not a dropped connection): start over
         * on a fresh connection rather than act on a half-known state. */
        qr_disconnect(q, what);
        return 1;
    }
    return 0;
}

static int qr_connect(fm_redis_queue *q)
{
    struct timeval tv = {QR_IO_TIMEOUT_S, 0};
    redisContext *c = redisConnectWithTimeout(q->url.host, (int)q->url.port, tv);
    if (!c || c->err) {
        fm_log(FM_LOG_WARN, "queue: cannot connect to %s:%u: %s", q->url.host, q->url.port,
               c ? c->errstr : "out of memory");
        if (c) redisFree(c);
        return -1;
    }
    redisSetTimeout(c, tv);
    q->redis = c;
    redisReply *r;
    if (q->url.password[0]) {
        r = q->url.user[0] ? redisCommand(c, "AUTH %s %s", q->url.user, q->url.password)
                           : redisCommand(c, "AUTH %s", q->url.password);
        if (qr_failed(q, r, "AUTH")) return -1;
        freeReplyObject(r);
    }
    if (q->url.db) {
        r = redisCommand(c, "SELECT %d", q->url.db);
        if (qr_failed(q, r, "SELECT")) return -1;
        freeReplyObject(r);
    }
    /* From the stream's start: jobs queued before any daemon ran are taken. */
    r = redisCommand(c, "XGROUP CREATE %s %s 0 MKSTREAM", q->stream, q->group);
    if (!r) {
        qr_disconnect(q, c->errstr);
        return -1;
    }
    int exists = r->type == REDIS_REPLY_ERROR && r->str && !strncmp(r->str, "BUSYGROUP", 9);
    if (r->type == REDIS_REPLY_ERROR && !exists) {
        fm_log(FM_LOG_ERROR, "queue: XGROUP CREATE %s %s: %s", q->stream, q->group, r->str);
        freeReplyObject(r);
        qr_disconnect(q, "XGROUP CREATE");
        return -1;
    }
    freeReplyObject(r);
    fm_log(FM_LOG_INFO, "queue: connected to %s:%u, stream %s, group %s, consumer %s", q->url.host,
           q->url.port, q->stream, q->group, q->consumer);
    return 0;
}

/* ---------------------------------------------------------- results -- */

static void qr_on_job_end(void *user, const char *id, json_t *status)
{
    fm_redis_queue *q = user;
    if (strncmp(id, "q-", 2) != 0) return; /* an HTTP job */
    qr_result *res = calloc(1, sizeof *res);
    if (res) {
        snprintf(res->entry, sizeof res->entry, "%s", id + 2);
        json_t *out = json_deep_copy(status);
        if (out) json_object_set_new(out, "entry", json_string(res->entry));
        res->json = out ? json_dumps(out, JSON_COMPACT) : NULL;
        json_decref(out);
    }
    pthread_mutex_lock(&q->lock);
    int ours = 0;
    for (int i = 0; i < q->running_count; i++)
        if (!strcmp(q->running[i].entry, id + 2)) {
            ours = 1;
            q->running[i].ended = 1;
        }
    if (res && res->json && ours) {
        if (q->outbox_tail) q->outbox_tail->next = res;
        else q->outbox = res;
        q->outbox_tail = res;
        res = NULL;
        pthread_cond_signal(&q->cond);
    } else if (ours) {
        /* No memory for the result: the entry stays pending and is run again
         * by whoever claims it; the job's folder keeps the result for it. */
        fm_log(FM_LOG_ERROR, "queue: entry %s: out of memory for its result", id + 2);
    }
    pthread_mutex_unlock(&q->lock);
    if (res) free(res->json);
    free(res);
}

static void qr_forget_running(fm_redis_queue *q, const char *entry)
{
    for (int i = 0; i < q->running_count; i++)
        if (!strcmp(q->running[i].entry, entry)) {
            q->running[i] = q->running[--q->running_count];
            return;
        }
}

/* Write the outbox. 0 when everything was written. */
static int qr_flush_results(fm_redis_queue *q)
{
    for (;;) {
        pthread_mutex_lock(&q->lock);
        qr_result *res = q->outbox;
        pthread_mutex_unlock(&q->lock);
        if (!res) return 0;
        redisReply *r = redisCommand(q->redis, "EVAL %s 3 %s %s %s %s %s %s", finish_script,
                                     q->results, q->done, q->stream, res->entry, res->json,
                                     q->group);
        if (qr_failed(q, r, "writing a result")) return -1;
        fm_log(FM_LOG_INFO, "queue: entry %s: result %s", res->entry,
               r->type == REDIS_REPLY_INTEGER && r->integer == 1 ? "written"
                                                                   : "already written by another");
        freeReplyObject(r);
        pthread_mutex_lock(&q->lock);
        q->outbox = res->next;
        if (!q->outbox) q->outbox_tail = NULL;
        qr_forget_running(q, res->entry);
        pthread_mutex_unlock(&q->lock);
        free(res->json);
        free(res);
    }
}

/* A result for an entry no job ran (malformed, refused): straight into
 * the outbox. */
static void qr_fail_entry(fm_redis_queue *q, const char *entry, const char *code,
                          const char *message)
{
    fm_log(FM_LOG_WARN, "queue: entry %s: refused: %s", entry, message);
    json_t *status = json_pack("{s:s, s:s, s:{s:s, s:s}, s:s}", "state", "failed", "id", "",
                               "error", "code", code, "message", message, "entry", entry);
    qr_result *res = calloc(1, sizeof *res);
    if (!status || !res) {
        json_decref(status);
        free(res);
        return; /* stays pending: retried when claimed again */
    }
    snprintf(res->entry, sizeof res->entry, "%s", entry);
    res->json = json_dumps(status, JSON_COMPACT);
    json_decref(status);
    if (!res->json) {
        free(res);
        return;
    }
    pthread_mutex_lock(&q->lock);
    if (q->running_count < QR_MAX_RUNNING) {
        snprintf(q->running[q->running_count].entry, sizeof q->running[0].entry, "%s", entry);
        q->running[q->running_count++].ended = 1;
    }
    if (q->outbox_tail) q->outbox_tail->next = res;
    else q->outbox = res;
    q->outbox_tail = res;
    pthread_mutex_unlock(&q->lock);
}

/* ------------------------------------------------------------ taking -- */

static int entry_id_valid(const char *s, size_t n)
{
    if (n == 0 || n > 40) return 0;
    for (size_t i = 0; i < n; i++)
        if (!((s[i] >= '0' && s[i] <= '9') || s[i] == '-')) return 0;
    return 1;
}

/* Hand one taken entry to the job manager. */
static void qr_start_entry(fm_redis_queue *q, const char *entry, const char *kind,
                           const char *value, size_t value_len)
{
    pthread_mutex_lock(&q->lock);
    for (int i = 0; i < q->running_count; i++)
        if (!strcmp(q->running[i].entry, entry)) {
            pthread_mutex_unlock(&q->lock);
            return; /* already ours and in hand (a re-read of our own pending entries) */
        }
    int full = q->running_count >= QR_MAX_RUNNING;
    pthread_mutex_unlock(&q->lock);
    if (full) return; /* stays pending; taken again later */

    char msg[512];
    if (!strcmp(kind, "nojob")) {
        qr_fail_entry(q, entry, "bad_entry", "the entry has no field 'job'");
        return;
    }
    if (!strcmp(kind, "large")) {
        snprintf(msg, sizeof msg, "the job is %s bytes, over the %zu-byte request limit", value,
                 q->cfg.max_job_bytes);
        qr_fail_entry(q, entry, "too_large", msg);
        return;
    }
    /* The same job document as POST /v1/jobs, by the same parser. */
    fm_error derr;
    fm_error_clear(&derr);
    fm_job_doc *doc = NULL;
    const fm_job_doc_rules rules = fm_jobs_doc_rules(q->jobs, 0);
    if (fm_job_doc_parse(value, value_len, &rules, &doc, &derr) != FM_OK) {
        snprintf(msg, sizeof msg, "%s", derr.message);
        qr_fail_entry(q, entry, derr.reason[0] ? derr.reason : "bad_job", msg);
        return;
    }
    char id[64];
    snprintf(id, sizeof id, "q-%.40s", entry);
    pthread_mutex_lock(&q->lock);
    snprintf(q->running[q->running_count].entry, sizeof q->running[0].entry, "%s", entry);
    q->running[q->running_count++].ended = 0;
    pthread_mutex_unlock(&q->lock);
    fm_jobs_take_result taken;
    json_t *final = NULL;
    fm_error_clear(&derr);
    if (fm_jobs_take(q->jobs, id, doc, &taken, &final, &derr) != FM_OK) {
        pthread_mutex_lock(&q->lock);
        qr_forget_running(q, entry);
        pthread_mutex_unlock(&q->lock);
        if (!strcmp(derr.reason, "shutting_down") || !strcmp(derr.reason, "storage") ||
            !strcmp(derr.reason, "out_of_memory") || !strcmp(derr.reason, "busy")) {
            /* Ours to retry (stopping, storage): left pending. */
            fm_log(FM_LOG_WARN, "queue: entry %s: not taken now: %s", entry, derr.message);
            return;
        }
        qr_fail_entry(q, entry, derr.reason[0] ? derr.reason : "bad_job", derr.message);
        return;
    }
    if (taken == FM_JOBS_TAKEN_FINAL) {
        /* It ended before (this daemon or one sharing the folder) and its
         * result may not have been written: write it now. */
        qr_on_job_end(q, id, final);
        json_decref(final);
        return;
    }
    fm_log(FM_LOG_INFO, "queue: entry %s: %s as job %s", entry,
           taken == FM_JOBS_TAKEN ? "taken" : "already running", id);
}

/* One taking script call. 1 when an entry came, 0 when none, -1 on a lost
 * connection. mine: re-read this consumer's own pending entries after
 * *cursor. */
static int qr_take(fm_redis_queue *q, int mine, char *cursor, size_t cursor_size)
{
    char min_idle[32], max_bytes[32];
    snprintf(min_idle, sizeof min_idle, "%lld", (long long)(q->cfg.claim_s * 1000.0));
    snprintf(max_bytes, sizeof max_bytes, "%zu", q->cfg.max_job_bytes);
    redisReply *r = redisCommand(q->redis, "EVAL %s 1 %s %s %s %s %s %s %s", take_script, q->stream,
                                 q->group, q->consumer, min_idle, max_bytes, mine ? "0" : "",
                                 mine ? cursor : "");
    if (qr_failed(q, r, "taking an entry")) return -1;
    if (r->type != REDIS_REPLY_ARRAY || r->elements != 3) {
        freeReplyObject(r);
        return 0;
    }
    redisReply *id = r->element[0], *kind = r->element[1], *value = r->element[2];
    if (id->type != REDIS_REPLY_STRING || kind->type != REDIS_REPLY_STRING ||
        value->type != REDIS_REPLY_STRING || !entry_id_valid(id->str, id->len)) {
        freeReplyObject(r);
        return 0;
    }
    char entry[64];
    snprintf(entry, sizeof entry, "%s", id->str);
    if (mine) snprintf(cursor, cursor_size, "%s", entry);
    if (!strcmp(kind->str, "gone")) {
        /* Deleted from the stream while pending: acknowledge, nothing to run. */
        redisReply *a = redisCommand(q->redis, "XACK %s %s %s", q->stream, q->group, entry);
        if (!qr_failed(q, a, "XACK")) freeReplyObject(a);
    } else {
        qr_start_entry(q, entry, kind->str, value->str, value->len);
    }
    freeReplyObject(r);
    return q->redis ? 1 : -1;
}

/* Renew the claims on the entries running here. */
static int qr_renew(fm_redis_queue *q)
{
    char entries[QR_MAX_RUNNING][64];
    int n = 0;
    pthread_mutex_lock(&q->lock);
    for (int i = 0; i < q->running_count; i++)
        if (!q->running[i].ended) snprintf(entries[n++], sizeof entries[0], "%s", q->running[i].entry);
    pthread_mutex_unlock(&q->lock);
    for (int i = 0; i < n; i++) {
        redisReply *r = redisCommand(q->redis, "EVAL %s 1 %s %s %s %s", renew_script, q->stream,
                                     q->group, q->consumer, entries[i]);
        if (qr_failed(q, r, "renewing a claim")) return -1;
        int ours = r->type == REDIS_REPLY_INTEGER && r->integer == 1;
        freeReplyObject(r);
        if (!ours) {
            char id[80];
            snprintf(id, sizeof id, "q-%.40s", entries[i]);
            fm_log(FM_LOG_WARN, "queue: entry %s went to another consumer; releasing job %s",
                   entries[i], id);
            pthread_mutex_lock(&q->lock);
            qr_forget_running(q, entries[i]);
            pthread_mutex_unlock(&q->lock);
            fm_jobs_release(q->jobs, id);
        }
    }
    return 0;
}

static int qr_has_capacity(fm_redis_queue *q)
{
    return fm_jobs_busy(q->jobs) < q->cfg.capacity;
}

static void qr_wait(fm_redis_queue *q, double seconds)
{
    struct timespec ts;
    fm_clock_deadline(&ts, seconds);
    pthread_mutex_lock(&q->lock);
    if (!q->stop && !q->outbox) pthread_cond_timedwait(&q->cond, &q->lock, &ts);
    pthread_mutex_unlock(&q->lock);
}

static int qr_stopping(fm_redis_queue *q)
{
    pthread_mutex_lock(&q->lock);
    int stop = q->stop;
    pthread_mutex_unlock(&q->lock);
    return stop;
}

static void *qr_main(void *arg)
{
    fm_redis_queue *q = arg;
    double backoff = QR_BACKOFF_MIN_S;
    while (!qr_stopping(q)) {
        if (!q->redis) {
            if (qr_connect(q) != 0) {
                qr_wait(q, backoff);
                backoff = fmin(2 * backoff, QR_BACKOFF_MAX_S);
                continue;
            }
            backoff = QR_BACKOFF_MIN_S;
            /* Entries this consumer owned before (a restart under the same
             * name): run them again or write their results. */
            char cursor[64] = "0";
            while (!qr_stopping(q) && qr_take(q, 1, cursor, sizeof cursor) == 1) {
            }
            q->next_renew = 0;
            continue;
        }
        if (qr_flush_results(q) != 0) continue;
        double now = fm_clock_monotonic_s();
        if (now >= q->next_renew) {
            if (qr_renew(q) != 0) continue;
            q->next_renew = now + q->cfg.claim_s / 3.0;
        }
        int took = 0;
        if (qr_has_capacity(q)) {
            took = qr_take(q, 0, NULL, 0);
            if (took < 0) continue;
        }
        if (!took) qr_wait(q, QR_POLL_S);
    }
    if (q->redis) {
        qr_flush_results(q);
        redisFree(q->redis);
        q->redis = NULL;
    }
    return NULL;
}

fm_redis_queue *fm_redis_queue_start(const fm_redis_queue_config *cfg, fm_jobs *jobs,
                                     fm_error *err)
{
    fm_redis_queue *q = calloc(1, sizeof *q);
    if (!q) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    if (fm_redis_url_parse(cfg->url, &q->url, err) != FM_OK) {
        free(q);
        return NULL;
    }
    q->cfg = *cfg;
#define QR_COPY(field, def)                                                                        \
    snprintf(q->field, sizeof q->field, "%s", cfg->field && cfg->field[0] ? cfg->field : def);     \
    q->cfg.field = q->field;
    QR_COPY(stream, "frepmill:jobs")
    QR_COPY(group, "frepmilld")
    QR_COPY(consumer, "frepmilld")
    QR_COPY(results, "frepmill:results")
    QR_COPY(done, "frepmill:done")
#undef QR_COPY
    snprintf(q->url_text, sizeof q->url_text, "%s", cfg->url);
    q->cfg.url = q->url_text;
    if (!(q->cfg.claim_s > 0)) q->cfg.claim_s = 30;
    if (q->cfg.capacity < 1) q->cfg.capacity = 1;
    if (q->cfg.max_job_bytes == 0) q->cfg.max_job_bytes = (size_t)64 << 20;
    q->jobs = jobs;
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->cond, NULL);
    fm_jobs_set_end_hook(jobs, qr_on_job_end, q);
    if (pthread_create(&q->thread, NULL, qr_main, q) != 0) {
        fm_jobs_set_end_hook(jobs, NULL, NULL);
        pthread_mutex_destroy(&q->lock);
        pthread_cond_destroy(&q->cond);
        free(q);
        fm_error_set(err, FM_ERR_LIMIT, "cannot start the queue thread");
        return NULL;
    }
    return q;
}

void fm_redis_queue_stop(fm_redis_queue *q)
{
    if (!q) return;
    pthread_mutex_lock(&q->lock);
    q->stop = 1;
    pthread_cond_signal(&q->cond);
    pthread_mutex_unlock(&q->lock);
    pthread_join(q->thread, NULL);
    fm_jobs_set_end_hook(q->jobs, NULL, NULL);
    while (q->outbox) {
        qr_result *next = q->outbox->next;
        free(q->outbox->json);
        free(q->outbox);
        q->outbox = next;
    }
    pthread_mutex_destroy(&q->lock);
    pthread_cond_destroy(&q->cond);
    free(q);
}
