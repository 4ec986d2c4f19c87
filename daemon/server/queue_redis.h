/* queue_redis.h: frepmilld as one consumer of a Redis Streams job queue
 * (docs/fleet.md). Several daemons join one consumer group; each takes a
 * job when it has a free worker, runs it like an HTTP job, and writes the
 * final status once (HSETNX results, XADD done, XACK, in one script). A
 * daemon that dies leaves its entry pending; the others claim it once it is
 * idle longer than claim_s. */
#ifndef FM_DAEMON_QUEUE_REDIS_H
#define FM_DAEMON_QUEUE_REDIS_H

#include <stddef.h>

#include "core/core.h"
#include "jobs.h"

/* redis://[user[:password]@]host[:port][/db] */
typedef struct fm_redis_url {
    char host[256];
    unsigned port;          /* default 6379 */
    char user[128];         /* "" : none (AUTH password alone, or no AUTH) */
    char password[256];     /* "" : no AUTH */
    int db;                 /* SELECT; default 0 */
} fm_redis_url;

/* Parse a queue URL. FM_OK, or FM_ERR_INPUT with what is wrong (rediss://
 * is refused: Debian 12's hiredis 0.14 has no TLS). */
fm_status fm_redis_url_parse(const char *url, fm_redis_url *out, fm_error *err);

typedef struct fm_redis_queue_config {
    const char *url;
    const char *stream;     /* jobs in: "frepmill:jobs" */
    const char *group;      /* "frepmilld" */
    const char *consumer;   /* this daemon's name in the group: host-pid */
    const char *results;    /* hash of final statuses: "frepmill:results" */
    const char *done;       /* stream of finished entry ids: "frepmill:done" */
    double claim_s;         /* claim entries idle longer than this (s): 30 */
    size_t max_job_bytes;   /* the `job` field's budget (the HTTP request limit) */
    int capacity;           /* take a job only while fewer than this many run or wait here */
} fm_redis_queue_config;

typedef struct fm_redis_queue fm_redis_queue;

/* Start the consumer thread. It connects (and reconnects, with backoff) by
 * itself: an unreachable Redis is logged, never fatal. NULL only for a bad
 * configuration or no memory. */
fm_redis_queue *fm_redis_queue_start(const fm_redis_queue_config *cfg, fm_jobs *jobs,
                                     fm_error *err);
/* Stop taking jobs and join the thread. Results not yet written stay
 * pending in Redis (their entries are not acknowledged) and are written by
 * whoever runs the entry next. */
void fm_redis_queue_stop(fm_redis_queue *q);

#endif
