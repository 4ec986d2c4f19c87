/* queue.h: the queue of jobs and the threads that run them (queue.c): a
 * worker runs the job runner on a job's record and publishes what it does
 * (publish.h), snapshots it (job_store.h) and feeds a live job its
 * positions (live.h). A leaf under the job table: what the table wants to
 * know of a run (a job ended, a run is over) it hears through hooks. */
#ifndef FM_DAEMON_QUEUE_H
#define FM_DAEMON_QUEUE_H

#include "job_record.h"

typedef struct fm_queue fm_queue;

typedef struct fm_queue_config {
    int threads_per_job;
    double snapshot_interval_s;
    double publish_interval_s;
    size_t job_memory_bytes;
} fm_queue_config;

typedef struct fm_queue_hooks {
    void *user;
    /* A job ended (done, failed, cancelled), on the thread that ended it. */
    void (*ended)(void *user, job *j);
    /* A run is over; unfinished: stopped for a shutdown or a release, to
     * resume later. */
    void (*run_over)(void *user, job *j, int unfinished);
} fm_queue_hooks;

fm_queue *fm_queue_new(const fm_queue_config *cfg, const fm_queue_hooks *hooks, fm_error *err);
/* After fm_queue_stop, the joins and fm_queue_drain. */
void fm_queue_free(fm_queue *q);
/* Queue a job for the workers (takes a reference of its own). */
void fm_queue_push(fm_queue *q, job *j);
/* The daemon is stopping: workers end after their run, runs stop between
 * cuts, live sources stop waiting (the flag records point at). */
void fm_queue_stop(fm_queue *q);
const atomic_int *fm_queue_stopping(const fm_queue *q);
/* Start and join the worker threads. */
fm_status fm_queue_start_workers(fm_queue *q, int count, fm_error *err);
void fm_queue_join_workers(fm_queue *q);
/* Drop the queue's references of jobs that never ran (at close). */
void fm_queue_drain(fm_queue *q);
/* Run a job now on a thread of its own (live jobs); joined at close. */
fm_status fm_queue_run_now(fm_queue *q, job *j, fm_error *err);
void fm_queue_join_own(fm_queue *q, int all);
/* End a job: state, result.json, the "end" event, a log line, the ended
 * hook. */
void fm_queue_finish(fm_queue *q, job *j, fm_job_state state, const char *what);

#endif
