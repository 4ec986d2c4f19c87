/* jobs_internal.h: the job record shared by the job manager (jobs.c) and
 * the HTTP service over it (jobs_http.c). Nothing outside those two files
 * includes it. Locking: fm_jobs.lock guards the table, the queue and each
 * job's refs; job.lock guards everything a worker publishes. */
#ifndef FM_DAEMON_JOBS_INTERNAL_H
#define FM_DAEMON_JOBS_INTERNAL_H

#include <limits.h>
#include <pthread.h>
#include <stdatomic.h>

#include "jobs.h"
#include "mesh/mesh.h"
#include "stock/stock.h"

#define JOB_EVENT_RING 256
/* Folder name buffers: small enough that a file name appended still fits
 * PATH_MAX, which lets the compiler prove no path is truncated. */
#define JOB_STATE_DIR_MAX 1100
#define JOB_DIR_MAX 1300

typedef struct job_chunk {
    int32_t index[3];
    uint64_t version;
    double lo[3], hi[3];
    fm_mesh *mesh;     /* immutable once published */
    uint8_t *drc;      /* Draco encoding of mesh; NULL when it has no triangles */
    size_t drc_size;
} job_chunk;

typedef struct job_event {
    uint64_t id;
    char type[24];
    char *data;
} job_event;

typedef struct job {
    char id[32];
    char dir[JOB_DIR_MAX];
    json_t *spec;      /* canonical job, immutable */
    double created;    /* unix time */
    int refs;          /* guarded by fm_jobs.lock */
    int deleted;       /* guarded by fm_jobs.lock */
    struct job *next_queued;

    atomic_int cancel_requested;

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
    int meshes_loaded;     /* chunks reflect the final stock (or a worker publishes) */
    job_event ring[JOB_EVENT_RING];
    uint64_t next_event;   /* id of the next event; ids start at 1 */
    int ended;             /* the "end" event was emitted */
    pthread_mutex_t load_lock; /* one lazy mesh load at a time */
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
    int stopping;
    pthread_t *workers;
    int worker_count;
    atomic_uint id_counter;
    struct jobs_live *live; /* jobs_live.c: the session taking positions, or NULL */
    struct jobs_live *live_ending; /* a stopped session whose thread is still to be joined */
    pthread_mutex_t live_lock; /* guards live and live_ending */
};

/* Find a job and take a reference (NULL if unknown or deleted). */
job *fm_jobs_get(fm_jobs *jobs, const char *id);
void fm_jobs_put(fm_jobs *jobs, job *j);
/* Status of a job as JSON (under its lock). */
json_t *fm_jobs_status_json(job *j);
/* Make sure the chunks of a finished job are published (loads its stock
 * snapshot once after a restart). */
int fm_jobs_ensure_meshes(fm_jobs *jobs, job *j, fm_http_error *err);
int fm_jobs_remove(fm_jobs *jobs, const char *id, fm_http_error *err);

/* For jobs_live.c: a job record in the table that no worker runs and that is
 * not stored (its folder has no spec.json, so a restart drops it); returned
 * with a reference for the caller. */
job *fm_jobs_add_unstored(fm_jobs *jobs, json_t *spec);
/* Emit an event (caller holds j->lock); data is stolen. */
void fm_jobs_emit(job *j, const char *type, json_t *data);
/* Remesh and publish the chunks of stock that changed (the caller owns the
 * stock exclusively). */
void fm_jobs_publish_chunks(job *j, fm_stock *stock);
/* Stop the live job's thread and free the session (fm_jobs_close). */
void fm_jobs_live_close(fm_jobs *jobs);

#endif
