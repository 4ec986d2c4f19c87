/* job_record.h: the record of one job of the daemon, at the bottom of
 * daemon/server: the job table (jobs.c) holds records, the queue's workers
 * (queue.c) run them, job_store.c makes them durable, publish.c shows them
 * to readers and live.c feeds a live one. It knows none of them: a record
 * is made, referenced and freed here, and each of those writes its own
 * part under the job's lock. Readers outside these modules (HTTP, Modbus)
 * go through jobs.h and publish.h. Locking: job.lock guards everything a
 * worker publishes; the table's lock guards the table and `held`; refs are
 * atomic. */
#ifndef FM_DAEMON_JOB_RECORD_H
#define FM_DAEMON_JOB_RECORD_H

#include <limits.h>
#include <pthread.h>
#include <stdatomic.h>

#include "job_view.h"
#include "mesh/mesh.h"
#include "runner/job_doc.h"
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
    int encoding;      /* announced, its Draco bytes still being made (a live
                          job's publication encodes after its event, publish.c) */
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
    char id[32];
    char dir[JOB_DIR_MAX];
    fm_job_doc *doc;   /* the job document, immutable once stored (its models in dir) */
    double created;    /* unix time */
    atomic_int refs;   /* fm_job_ref / fm_job_unref */
    atomic_int deleted; /* removed from the table (jobs.c) */
    struct job *next_queued; /* guarded by the queue's lock (queue.c) */
    /* The daemon is stopping (the queue's flag, queue.c): a live job's
     * source stops waiting for positions. */
    const atomic_int *stopping;

    atomic_int cancel_requested;
    /* A job from a shared queue (queue_redis.c) whose entry went to another
     * daemon: stop it like a shutdown does (snapshot, no result). */
    atomic_int released;
    /* Loaded from its folder but not queued: a queue job waits until its
     * queue hands it to this daemon (guarded by fm_jobs.lock). */
    int held;
    size_t history_limit;  /* bytes of mesh history kept (mesh_history_mb) */

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
    /* A live job's last publication is announced before its Draco bytes
     * exist: the encoder thread makes them (publish.c); readers of the bytes
     * wait on cond while encoding_pending. The encoder is started and
     * joined by the publishing thread only. */
    size_t encoding_pending;
    pthread_t encoder;
    int encoder_started;
    job_event ring[JOB_EVENT_RING];
    uint64_t next_event;   /* id of the next event; ids start at 1 */
    int ended;             /* the "end" event was emitted */
    pthread_mutex_t load_lock; /* one lazy mesh load at a time */
    job_live *live;        /* a live job's positions and journal (live.c), else NULL */
    char live_note[200];   /* its source's connection (live_source.c); "" when none */
    void (*live_free)(job_live *live); /* set with live */
} job;

/* A new record with one reference (the caller's, usually the table's); it
 * owns doc (NULL: the record could not be made and doc is freed). Its
 * folder is jobs_dir/id; history_limit bounds its mesh history; stopping
 * is the daemon's stop flag (read by a live job's motion source). */
job *fm_job_record_new(const char *id, const char *jobs_dir, fm_job_doc *doc, double created,
                       size_t history_limit, const atomic_int *stopping);
/* Take and drop a reference; the last one frees the record. */
void fm_job_ref(job *j);
void fm_job_unref(job *j);
/* The job's document (immutable while the record lives) and the path of
 * a file in its folder. */
const fm_job_doc *fm_job_document(const job *j);
void fm_job_file_path(const job *j, const char *name, char *path, size_t size);
/* The chunks' meshes and history freed (the record keeps none after). */
void fm_job_record_free_chunks(job *j);

/* The byte budget of a job's grid: the daemon's job_memory_bytes, or the
 * document's options.memory_budget_mb when lower. */
size_t fm_job_memory_budget(size_t job_memory_bytes, const fm_job_doc *doc);

#endif
