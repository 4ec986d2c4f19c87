/* jobs.h: the daemon's job manager: a durable table of jobs (one folder per
 * job under state_dir/jobs), a queue, worker threads that run the shared job
 * runner (job.h), and what the workers publish for readers: immutable status
 * snapshots, chunk meshes with versions, and events. Readers (HTTP, Modbus)
 * never touch a grid being cut. */
#ifndef FM_DAEMON_JOBS_H
#define FM_DAEMON_JOBS_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>

#include "core/core.h"
#include "http/http_server.h"

typedef struct fm_jobs fm_jobs;

typedef struct fm_jobs_config {
    const char *state_dir;
    int workers;
    int threads_per_job;
    double snapshot_interval_s;
    double publish_interval_s;
    int max_jobs;
    size_t job_memory_bytes;
    /* Live mode: stock SPEC string and tool table file (NULL or "": the
     * selected job's), voxel (mm) and the feed that times each move. */
    const char *live_stock;
    const char *live_tools;
    double live_voxel;
    double live_feed;
    /* G-code: the dialect of every job ("linuxcnc" or "fanuc"; NULL: the
     * default) and the folders of subprogram files (NULL or "": none). */
    const char *dialect;
    const char *subroutine_path;
} fm_jobs_config;

typedef enum fm_job_state {
    FM_JOB_QUEUED = 0,
    FM_JOB_RUNNING,
    FM_JOB_DONE,
    FM_JOB_FAILED,
    FM_JOB_CANCELLED
} fm_job_state;

const char *fm_job_state_name(fm_job_state state);

/* A plain copy of a job's published status. */
typedef struct fm_job_view {
    char id[32];
    fm_job_state state;
    int paused;
    double progress;
    int line;
    long block;
    int tool;
    double position[3];
    double program_time_s;
    double removed_mm3;
    double stock_mm3;
    double removal_rate_mm3_s;
    int finding_count;
    int error_finding_count; /* findings of severity "error": the collision alarm */
    int first_finding_line;
    int error_code; /* fm_status of a failed job, 0 if none */
    /* The budget warning (fm_job_progress.voxels_uncertain, uncertain_line):
     * counted since the job last started (a resumed job counts anew). */
    size_t voxels_uncertain;
    int uncertain_line;
} fm_job_view;

/* Open the state folder (created if missing), load every stored job (done
 * ones with their results; unfinished ones queued, to resume from their
 * last snapshot) and start the workers. */
fm_jobs *fm_jobs_open(const fm_jobs_config *cfg, fm_error *err);
/* Stop the workers: running jobs are snapshotted and resume at the next
 * start. Frees everything. */
void fm_jobs_close(fm_jobs *jobs);
/* Wake everything that waits, so that the manager can be closed soon. */
void fm_jobs_begin_shutdown(fm_jobs *jobs);

/* Store a canonical job (fm_http_job_parse) durably and queue it: 0 and
 * its id, or the HTTP status of the refusal with err filled. */
int fm_jobs_submit(fm_jobs *jobs, json_t *spec, char *id, size_t id_size, fm_http_error *err);

/* --------------------------------------------------- shared queues -- */
/* Jobs taken from a shared queue (queue_redis.c, docs/fleet.md) carry the
 * id the queue gives them ("q-" + entry id), are stored like any job, and
 * at start are held, not resumed: the entry may have gone to another
 * daemon meanwhile. The queue resumes them by taking them again. */
typedef enum fm_jobs_take_result {
    FM_JOBS_TAKEN = 0,     /* stored and queued here, or resumed from its folder */
    FM_JOBS_TAKEN_ALREADY, /* already queued or running here */
    FM_JOBS_TAKEN_FINAL    /* it ended before (here or in a shared folder): *final is its status */
} fm_jobs_take_result;
/* Take a canonical job under the queue's id. 0, or the HTTP status of the
 * refusal (the same checks and budgets as fm_jobs_submit) with err filled.
 * *final (FM_JOBS_TAKEN_FINAL) is the caller's to json_decref. */
int fm_jobs_take(fm_jobs *jobs, const char *id, json_t *spec, fm_jobs_take_result *result,
                 json_t **final, fm_http_error *err);
/* Called on a worker thread as each job ends (done, failed, cancelled),
 * with its final status (the GET /v1/jobs/{id} object, borrowed). */
typedef void (*fm_jobs_end_hook)(void *user, const char *id, json_t *status);
void fm_jobs_set_end_hook(fm_jobs *jobs, fm_jobs_end_hook hook, void *user);
/* Jobs queued or running here now. */
int fm_jobs_busy(fm_jobs *jobs);
/* Stop a job without ending it (its queue entry went to another daemon):
 * like a shutdown, it keeps its snapshot, writes no result and is held. */
void fm_jobs_release(fm_jobs *jobs, const char *id);

/* The fm_http_service over this manager. */
void fm_jobs_http_service(fm_jobs *jobs, fm_http_service *out);

/* For Modbus: jobs in creation order (slot 1 = the oldest kept job). */
int fm_jobs_view_slot(fm_jobs *jobs, int slot, fm_job_view *out);
int fm_jobs_count(fm_jobs *jobs);
/* Pause (1) or resume (0) a running or queued job; cancel. 0 on success,
 * -1 unknown job, -2 wrong state. */
int fm_jobs_pause(fm_jobs *jobs, const char *id, int pause);
int fm_jobs_cancel(fm_jobs *jobs, const char *id);
void fm_jobs_pause_all(fm_jobs *jobs);

/* Live mode (Modbus registers 110-117): a live job whose stock is cut along
 * the positions the controller writes, each a straight feed move from the
 * previous one (the first position only places the tool). Its stock and
 * tools come from the config (live_stock, live_tools) or from the job in
 * from_slot. The job is in the table (HTTP, viewer, Modbus read it) while
 * it lives; it is not stored (the machine's part is the record). All calls
 * return at once: a live thread cuts. Codes: 0 accepted, -1 refused (no
 * live session, no stock or tools, the session failed), -2 busy (the queue
 * is full or out of resources). */
int fm_jobs_live_start(fm_jobs *jobs, int from_slot);
int fm_jobs_live_position(fm_jobs *jobs, const double xyz[3], int tool);
int fm_jobs_live_stop(fm_jobs *jobs);
int fm_jobs_live_active(fm_jobs *jobs);

#endif
