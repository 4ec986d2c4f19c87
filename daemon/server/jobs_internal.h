/* jobs_internal.h: the job record and the job manager's parts, shared by the
 * files of the manager and its service implementations; nothing outside
 * daemon/server includes it. The parts:
 *   jobs.c       the table of jobs: records, references, submit, cancel,
 *                pause, remove, views for Modbus, open and close
 *   job_store.c  the durable side: job folders, specs, results, snapshots
 *   queue.c      the queue and the worker threads that run the job runner
 *   publish.c    what readers see: status snapshots, events, chunk meshes
 * Locking: fm_jobs.lock guards the table, the queue and each job's refs;
 * job.lock guards everything a worker publishes. */
#ifndef FM_DAEMON_JOBS_INTERNAL_H
#define FM_DAEMON_JOBS_INTERNAL_H

#include <limits.h>
#include <pthread.h>
#include <stdatomic.h>

#include "jobs.h"
#include "mesh/mesh.h"
#include "runner/job.h"
#include "stock/stock.h"

#define JOB_EVENT_RING 256
/* Folder name buffers: small enough that a file name appended still fits
 * PATH_MAX, which lets the compiler prove no path is truncated. */
#define JOB_STATE_DIR_MAX 1100
#define JOB_DIR_MAX 1300

/* One published mesh of a chunk: the stock version it was made from and the
 * program time from which it shows the chunk (until the next version's). */
typedef struct chunk_version {
    uint64_t version;
    double time_s;
    size_t triangles;
    uint8_t *drc;      /* Draco encoding; NULL when it has no triangles */
    size_t drc_size;
} chunk_version;

/* A chunk's published meshes, oldest first; the last is the current one.
 * The versions before it are the history that GET .../chunks?at=T reads;
 * together they stay under the job's history bound (publish.c). */
typedef struct job_chunk {
    int32_t index[3];
    double lo[3], hi[3];
    fm_mesh *mesh;     /* the current version's mesh (immutable once published) */
    fm_mesh_chunk_cache *cache; /* its faces per leaf, for the next remeshing
                                   (publishing thread only; NULL once the job ended) */
    chunk_version *versions;
    size_t version_count, version_cap;
} job_chunk;

static inline const chunk_version *job_chunk_current(const job_chunk *c)
{
    return &c->versions[c->version_count - 1];
}

typedef struct job_event {
    uint64_t id;
    char type[24];
    char *data;
} job_event;

typedef struct job_live job_live; /* live.c */

typedef struct job {
    struct fm_jobs *jobs; /* the manager it belongs to */
    char id[32];
    char dir[JOB_DIR_MAX];
    fm_job_doc *doc;   /* the job document, immutable once stored (its models in dir) */
    double created;    /* unix time */
    int refs;          /* guarded by fm_jobs.lock */
    int deleted;       /* guarded by fm_jobs.lock */
    struct job *next_queued;

    atomic_int cancel_requested;
    /* A job from a shared queue (queue_redis.c) whose entry went to another
     * daemon: stop it like a shutdown does (snapshot, no result). */
    atomic_int released;
    /* Loaded from its folder but not queued: a queue job waits until its
     * queue hands it to this daemon (guarded by fm_jobs.lock). */
    int held;

    pthread_mutex_t lock;
    pthread_cond_t cond;   /* events and pause */
    fm_job_state state;
    int paused;
    fm_job_view view;
    long motions_done, motions_total;
    double initial_mm3;
    json_t *error;     /* {"code","message","line","column","file"} or NULL */
    json_t *report;    /* the result of a finished job, or NULL */
    json_t *findings;  /* the collision check's findings (array), NULL until checked */
    job_chunk *chunks;
    size_t chunk_count, chunk_cap;
    uint64_t mesh_version; /* stock version of the published chunks */
    double mesh_time_s;    /* program time of the last publication */
    /* The mesh history: bytes of the versions before each chunk's current
     * one (Draco bytes and their records), at most history_limit (the
     * daemon's mesh_history_mb); the oldest are dropped first, and
     * history_from_s is the earliest program time it still answers
     * (-1: nothing published yet). */
    size_t history_bytes;
    double history_from_s;
    int meshes_loaded;     /* chunks reflect the final stock (or a worker publishes) */
    job_event ring[JOB_EVENT_RING];
    uint64_t next_event;   /* id of the next event; ids start at 1 */
    int ended;             /* the "end" event was emitted */
    pthread_mutex_t load_lock; /* one lazy mesh load at a time */
    job_live *live;        /* a live job's positions and journal (live.c), else NULL */
} job;

struct fm_jobs {
    fm_jobs_config cfg;
    char state_dir[JOB_STATE_DIR_MAX];
    char jobs_dir[JOB_STATE_DIR_MAX + 8];
    pthread_mutex_t lock;
    pthread_cond_t queue_cond;
    job **table;
    size_t count, cap;
    job *queue_head, *queue_tail;
    atomic_int stopping;
    pthread_t *workers;
    int worker_count;
    atomic_uint id_counter;
    /* Live mode (live.c): the live job taking positions (a reference), or
     * NULL; live jobs run on threads of their own (queue.c), not waiting
     * behind the queue. live_lock is taken before jobs->lock and j->lock. */
    job *live_job;
    pthread_mutex_t live_lock;
    struct own_thread *own_threads; /* queue.c */
    /* Told of every job that ends (queue_redis.c); guarded by lock. */
    fm_jobs_end_hook end_hook;
    void *end_hook_user;
};

/* ------------------------------------------------------------ jobs.c -- */

double fm_jobs_mono_s(void);
double fm_jobs_wall_s(void);
/* A new record with one reference (the table's); it owns doc (NULL: the
 * record could not be made and doc is freed). */
job *fm_jobs_record_new(const char *id, const char *jobs_dir, fm_job_doc *doc, double created);
/* Insert in creation order (caller holds jobs->lock). */
void fm_jobs_table_add(fm_jobs *jobs, job *j);
/* Find a job and take a reference (NULL if unknown or deleted). */
job *fm_jobs_get(fm_jobs *jobs, const char *id);
void fm_jobs_put(fm_jobs *jobs, job *j);
/* 1 once fm_jobs_begin_shutdown was called. */
int fm_jobs_stopping(fm_jobs *jobs);
/* A live job's document stored like any job's, then run at once on a
 * thread of its own and attached as the live session. */
fm_status fm_jobs_submit_live(fm_jobs *jobs, fm_job_doc *doc, char *id, size_t id_size,
                              fm_error *err);

/* The end hook, if any, with the job's final status (queue.c calls it when
 * a job ends). */
void fm_jobs_notify_end(fm_jobs *jobs, job *j);

/* ------------------------------------------------------- job_store.c -- */

/* Make the job's folder and write its spec durably (temp file, fsync,
 * rename, fsync of the folder and of jobs/), with the document's inline
 * models beside it: after this the job survives a crash. On failure
 * nothing is left behind. */
fm_status fm_job_store_create(fm_jobs *jobs, const char *id, double created, fm_job_doc *doc,
                              fm_error *err);
/* Write a document's inline models (stock, fixtures) into dir and point
 * its run spec at the files (also for POST /v1/check's private folder). */
fm_status fm_job_store_write_models(fm_job_doc *doc, const char *dir, fm_error *err);
/* The terminal record: state, last status, error and report (result.json). */
void fm_job_store_write_result(job *j);
/* Read every job folder back at start (finished jobs with their results,
 * unfinished ones to be queued by the caller); drops unacknowledged and
 * half-deleted folders. */
void fm_job_store_load_all(fm_jobs *jobs);
/* Read one job folder (a queue job that another daemon sharing the state
 * folder started): 1 if it is now in the table. */
int fm_job_store_load_one(fm_jobs *jobs, const char *id);
/* stock.vdb with "resume_from=N": every motion before N is in it. */
void fm_job_store_save_snapshot(job *j, fm_stock *stock, long resume_from);
/* The snapshot to resume from, with its N; NULL if none or unusable. */
fm_stock *fm_job_store_load_snapshot(job *j, const fm_stock_options *opt, long *resume_from);
/* Delete: the folder is renamed to ID.deleted first (one atomic step that
 * a restart honours), then removed by fm_job_store_remove_deleted. */
fm_status fm_job_store_mark_deleted(fm_jobs *jobs, job *j, fm_error *err);
void fm_job_store_remove_deleted(job *j);

/* ----------------------------------------------------------- queue.c -- */

/* Queue a job for the workers (caller holds jobs->lock). */
void fm_queue_push(fm_jobs *jobs, job *j);
/* Start and join the worker threads. */
fm_status fm_queue_start_workers(fm_jobs *jobs, int count, fm_error *err);
void fm_queue_join_workers(fm_jobs *jobs);
/* Drop the queue's references of jobs that never ran (at close). */
void fm_queue_drain(fm_jobs *jobs);
/* Run a job now on a thread of its own (live jobs); joined at close. */
fm_status fm_queue_run_now(fm_jobs *jobs, job *j, fm_error *err);
void fm_queue_join_own(fm_jobs *jobs, int all);
/* End a job: state, result.json, the "end" event, a log line. */
void fm_queue_finish(fm_jobs *jobs, job *j, fm_job_state state, const char *what);

/* ------------------------------------------------------------ live.c -- */

/* The live job's motion source for the runner; reads the journal back
 * first after a restart, and opens it for the positions to come. */
fm_status fm_live_prepare(job *j, fm_job_motion_source *src, fm_error *err);
/* Make j the live session (it takes positions) / stop that if it is. */
fm_status fm_live_attach(fm_jobs *jobs, job *j, fm_error *err);
void fm_live_detach(fm_jobs *jobs, job *j);
void fm_live_free(job_live *live);

/* --------------------------------------------------------- publish.c -- */

/* Emit an event (caller holds j->lock); data is stolen. */
void fm_publish_event(job *j, const char *type, json_t *data);
/* Status of a job as JSON (takes j->lock). */
json_t *fm_publish_status_json(job *j);
/* The check's findings into the status and the Modbus view (caller holds
 * j->lock, or owns j alone). */
void fm_publish_findings(job *j, json_t *findings);
/* The view of a finished job from its stored status (at start). */
void fm_publish_view_from_status(job *j, json_t *status);
/* A worker's progress into the view, and (at most every
 * FM_PUBLISH_EVENT_INTERVAL_S) progress and block events; takes j->lock. */
typedef struct publish_pace {
    double last_event;
    int last_line;
} publish_pace;
void fm_publish_progress(job *j, const fm_job_progress *p, publish_pace *pace);
/* Remesh and publish the chunks of stock that changed (the caller owns the
 * stock exclusively), as the stock at program time program_time_s; the
 * chunks' earlier meshes stay in the history within its bound. */
void fm_publish_chunks(job *j, fm_stock *stock, double program_time_s);
/* Make sure the chunks of a finished job are published (loads its stock
 * snapshot once after a restart). */
fm_status fm_publish_ensure_meshes(job *j, fm_error *err);
void fm_publish_chunks_free(job *j);
/* Free the chunks' remeshing caches (the job's stock will not change again). */
void fm_publish_chunks_drop_caches(job *j);
/* A finished job with a design: write deviation.drc (the stock's mesh in
 * deviation colours) and deviation.json (its key in mm and the figures) to
 * the job's folder, for GET /v1/jobs/{id}/deviation (the caller owns the
 * stock exclusively). */
fm_status fm_publish_deviation(job *j, fm_stock *stock, const fm_design *design,
                               const fm_deviation *dev, fm_error *err);

#endif
