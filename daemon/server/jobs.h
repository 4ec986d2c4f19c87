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
#include "job_view.h"
#include "runner/job_doc.h"

typedef struct fm_jobs fm_jobs;

typedef struct fm_jobs_config {
    const char *state_dir;
    int workers;
    int threads_per_job;
    double snapshot_interval_s;
    double publish_interval_s;
    /* Bytes of earlier chunk meshes each job keeps for GET .../chunks?at=T
     * (0: none); the oldest go first. */
    size_t mesh_history_bytes;
    int max_jobs;
    size_t job_memory_bytes;
    /* Live mode: stock SPEC string and tool table file (NULL or "": the
     * selected job's), voxel (mm) and the feed that times each move. */
    const char *live_stock;
    const char *live_tools;
    const char *live_machine; /* a machine file: the live job's rotary axes, limits */
    double live_voxel;
    double live_feed;
    /* G-code: the dialect of every job ("linuxcnc" or "fanuc"; NULL: the
     * default) and the folders of subprogram files (NULL or "": none). */
    const char *dialect;
    const char *subroutine_path;
} fm_jobs_config;


/* Open the state folder (created if missing), load every stored job (done
 * ones with their results; unfinished ones queued, to resume from their
 * last snapshot) and start the workers. */
fm_jobs *fm_jobs_open(const fm_jobs_config *cfg, fm_error *err);
/* Stop the workers: running jobs are snapshotted and resume at the next
 * start. Frees everything. */
void fm_jobs_close(fm_jobs *jobs);
/* Wake everything that waits, so that the manager can be closed soon. */
void fm_jobs_begin_shutdown(fm_jobs *jobs);

/* Store a job document (fm_job_doc_parse) durably and queue it: FM_OK and
 * its id once its spec is on disk. Takes doc, also on error. Refusals have
 * their reason: "shutting_down", "job_limit", "memory_budget" (the stock's
 * grid estimate over the budget), "storage" (not written: not accepted).
 * This is the one way in for every source of jobs (HTTP, the demo, the
 * queue of a fleet). */
fm_status fm_jobs_submit(fm_jobs *jobs, fm_job_doc *doc, char *id, size_t id_size,
                         fm_error *err);
/* The byte budget of a job's grid: job_memory_mb, or the document's
 * options.memory_budget_mb when lower. */
size_t fm_jobs_memory_budget(const fm_jobs *jobs, const fm_job_doc *doc);
/* The rules every job document is read with here: the daemon's G-code
 * settings (dialect, subroutine_path) as the defaults; own = 0 for
 * documents from clients (HTTP, a fleet's queue: no files, no live
 * programs), 1 for the daemon's own (its store, live mode, the demo). */
fm_job_doc_rules fm_jobs_doc_rules(const fm_jobs *jobs, int own);

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
/* Take a job document under the queue's id (takes doc, also on error).
 * FM_OK, or the refusal with its reason (the same checks and budgets as
 * fm_jobs_submit). *final (FM_JOBS_TAKEN_FINAL) is the caller's to
 * json_decref. */
fm_status fm_jobs_take(fm_jobs *jobs, const char *id, fm_job_doc *doc,
                       fm_jobs_take_result *result, json_t **final, fm_error *err);
/* Called on a worker thread as each job ends (done, failed, cancelled),
 * with its final status (the GET /v1/jobs/{id} object, borrowed). */
typedef void (*fm_jobs_end_hook)(void *user, const char *id, json_t *status);
void fm_jobs_set_end_hook(fm_jobs *jobs, fm_jobs_end_hook hook, void *user);
/* Jobs queued or running here now. */
int fm_jobs_busy(fm_jobs *jobs);
/* Stop a job without ending it (its queue entry went to another daemon):
 * like a shutdown, it keeps its snapshot, writes no result and is held. */
void fm_jobs_release(fm_jobs *jobs, const char *id);


/* A job by id, with a reference for the caller (NULL if unknown or
 * deleted): its record (job_record.h) is read through publish.h. Every
 * fm_jobs_get is paired with one fm_jobs_put. */
struct job;
struct job *fm_jobs_get(fm_jobs *jobs, const char *id);
void fm_jobs_put(fm_jobs *jobs, struct job *j);
/* Every job's status (publish.h) in creation order: {"jobs": [...]}. */
json_t *fm_jobs_status_list(fm_jobs *jobs);
/* The configuration the manager was opened with (state_dir its copy). */
const fm_jobs_config *fm_jobs_config_of(const fm_jobs *jobs);

/* For Modbus: jobs in creation order (slot 1 = the oldest kept job). */
int fm_jobs_view_slot(fm_jobs *jobs, int slot, fm_job_view *out);
int fm_jobs_count(fm_jobs *jobs);
/* Pause (1) or resume (0) a running or queued job; cancel; remove (its
 * folder goes). Refusals: reason "not_found" or "bad_state" (the job has
 * ended). */
fm_status fm_jobs_pause(fm_jobs *jobs, const char *id, int pause, fm_error *err);
fm_status fm_jobs_cancel(fm_jobs *jobs, const char *id, fm_error *err);
fm_status fm_jobs_remove(fm_jobs *jobs, const char *id, fm_error *err);
void fm_jobs_pause_all(fm_jobs *jobs);

/* Live mode (Modbus registers 110-117): a live job is a job whose motions
 * are the positions the controller writes, each a straight feed move from
 * the previous one (the first position only places the tool), through the
 * same runner as a program: the same cut, check, tool marks and
 * publishing. Its stock and tools come from the config (live_stock,
 * live_tools) or from the job in from_slot. It is stored like any job and
 * its positions are journaled, so a restarted daemon resumes it (and takes
 * positions for it again). All calls return at once: the job's own thread
 * cuts. Refusals: FM_ERR_INPUT (live mode off, no stock or tools, the job
 * ended), reason "busy" (the queue of positions is full, no thread). */
fm_status fm_jobs_live_start(fm_jobs *jobs, int from_slot, fm_error *err);
fm_status fm_jobs_live_position(fm_jobs *jobs, const fm_live_pose *pose, fm_error *err);
fm_status fm_jobs_live_stop(fm_jobs *jobs, fm_error *err);
int fm_jobs_live_active(fm_jobs *jobs);
/* What live mode's source says of its connection (live_source.c), shown
 * as "live_source" in the live job's status. */
void fm_jobs_live_note(fm_jobs *jobs, const char *note);
/* The live machine's latest position (1), or 0 (live.h's fm_live_machine);
 * who is told of each position (fm_live_on_position). */
int fm_jobs_live_machine(fm_jobs *jobs, fm_live_pose *out);
void fm_jobs_live_on_position(fm_jobs *jobs, void (*fn)(void *user), void *user);

#endif
