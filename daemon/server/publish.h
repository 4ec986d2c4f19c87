/* publish.h: what readers of a job see (publish.c): the status snapshot,
 * the event ring that server-sent events read, the chunk meshes with their
 * versions and history, and the finished job's deviation files. Writers
 * (the worker that owns the job's stock, the table) publish into the job's
 * record; readers (HTTP, the table's listings) copy out under the job's
 * lock and never touch a grid being cut. A leaf over job_record.h. */
#ifndef FM_DAEMON_PUBLISH_H
#define FM_DAEMON_PUBLISH_H

#include <jansson.h>
#include <stdint.h>

#include "job_record.h"
#include "runner/job.h"

struct fm_http_event;

/* ------------------------------------------------------------ writers -- */

/* Emit an event (caller holds j->lock); data is stolen. */
void fm_publish_event(job *j, const char *type, json_t *data);
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
/* Wait for the encoder of the last publication (a live job's chunks are
 * announced before their Draco bytes exist); by the publishing thread,
 * before the job's stock goes away. */
void fm_publish_chunks_settle(job *j);
/* Make sure the chunks of a finished job are published (loads its stock
 * snapshot once after a restart). */
fm_status fm_publish_ensure_meshes(job *j, fm_error *err);
/* Free the chunks' remeshing caches (the job's stock will not change again). */
void fm_publish_chunks_drop_caches(job *j);
/* The adaptivity of the finished stock's whole mesh (docs/daemon.md: the
 * triangles and the deviation it was chosen by). */
#define FM_PUBLISH_VIEW_ADAPTIVITY 0.2
/* A done job: the path of stock.drc, its whole stock meshed once with that
 * adaptivity (made on the first call, then kept). */
fm_status fm_publish_stock_mesh(job *j, char *path, size_t size, fm_error *err);
/* A finished job with a design: write deviation.drc (the stock's mesh in
 * deviation colours) and deviation.json (its key in mm and the figures) to
 * the job's folder, for GET /v1/jobs/{id}/deviation (the caller owns the
 * stock exclusively). */
fm_status fm_publish_deviation(job *j, fm_stock *stock, const fm_design *design,
                               const fm_deviation *dev, fm_error *err);

/* ------------------------------------------------------------ readers -- */

/* Status of a job as JSON (takes j->lock). */
json_t *fm_publish_status_json(job *j);
/* The report of a done job (with its id and state), the error of a failed
 * one; reason "not_finished" otherwise. */
fm_status fm_publish_report_json(job *j, json_t **out, fm_error *err);
/* The chunk list (docs/api.md, GET .../chunks): the chunks changed after
 * version `since`, or (at_s >= 0) the versions that showed the stock at
 * program time at_s; reasons "no_mesh", "history_dropped". */
fm_status fm_publish_chunk_list(job *j, uint64_t since, double at_s, json_t **out,
                                fm_error *err);
/* A copy of chunk `name`'s Draco bytes at version (0: the current one);
 * reasons "not_found", "history_dropped". */
fm_status fm_publish_chunk_bytes(job *j, const char *name, uint64_t version, uint8_t **data,
                                 size_t *size, fm_error *err);
/* The current chunk meshes appended into one mesh (not welded). */
fm_mesh *fm_publish_mesh_copy(job *j, fm_error *err);
/* Wait up to timeout_ms for events after `after`; copy up to cap of them
 * (their data malloc'd) and return how many; *finished once the "end"
 * event has been given. */
int fm_publish_events_wait(job *j, uint64_t after, int timeout_ms, struct fm_http_event *out,
                           int cap, int *finished);

#endif
