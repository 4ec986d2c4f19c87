/* queue.c: the queue of jobs and the worker threads that take them. A
 * worker runs fm_job_run (daemon/runner, shared with the CLI) with a
 * progress hook that, between cuts and on the worker's own thread,
 * publishes the status (publish.c), snapshots the stock every
 * snapshot_interval_s of work (job_store.c), remeshes the chunks that
 * changed every publish_interval_s (and at once when a live job has
 * caught up with the machine), and holds the job while it is paused. Live
 * jobs take the same path on a thread of their own (fm_queue_run_now), so
 * that a controller never waits behind the queue. */
#include "queue.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_store.h"
#include "live.h"
#include "log.h"
#include "publish.h"
#include "runner/findings_json.h"
#include "runner/report_json.h"

/* A thread running one job outside the queue (live jobs). */
typedef struct own_thread {
    pthread_t thread;
    fm_queue *q;
    job *j;              /* a reference, dropped when the run ends */
    atomic_int done;
    struct own_thread *next;
} own_thread;

struct fm_queue {
    fm_queue_config cfg;
    fm_queue_hooks hooks;
    /* lock guards the list, the workers and the own threads; cond wakes
     * the workers. */
    pthread_mutex_t lock;
    pthread_cond_t cond;
    job *head, *tail;
    atomic_int stopping;
    pthread_t *workers;
    int worker_count;
    own_thread *own_threads;
};

fm_queue *fm_queue_new(const fm_queue_config *cfg, const fm_queue_hooks *hooks, fm_error *err)
{
    fm_queue *q = calloc(1, sizeof *q);
    if (!q) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    q->cfg = *cfg;
    q->hooks = *hooks;
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->cond, NULL);
    atomic_init(&q->stopping, 0);
    return q;
}

void fm_queue_free(fm_queue *q)
{
    if (!q) return;
    pthread_mutex_destroy(&q->lock);
    pthread_cond_destroy(&q->cond);
    free(q);
}

void fm_queue_push(fm_queue *q, job *j)
{
    fm_job_ref(j); /* the queue's */
    pthread_mutex_lock(&q->lock);
    j->next_queued = NULL;
    if (q->tail) q->tail->next_queued = j;
    else q->head = j;
    q->tail = j;
    pthread_cond_signal(&q->cond);
    pthread_mutex_unlock(&q->lock);
}

void fm_queue_stop(fm_queue *q)
{
    pthread_mutex_lock(&q->lock);
    atomic_store(&q->stopping, 1);
    pthread_cond_broadcast(&q->cond);
    pthread_mutex_unlock(&q->lock);
}

const atomic_int *fm_queue_stopping(const fm_queue *q)
{
    return &q->stopping;
}

typedef struct run_ctx {
    fm_queue *q;
    job *j;
    double last_snapshot, last_publish;
    publish_pace pace;
    long resume_from;
    int stopped_for_shutdown;
} run_ctx;

static int on_progress(void *user, const fm_job_progress *p)
{
    run_ctx *rc = user;
    job *j = rc->j;
    double now = fm_clock_monotonic_s();
    rc->resume_from = p->resume_from;
    fm_publish_progress(j, p, &rc->pace);
    pthread_mutex_lock(&j->lock);
    /* Paused (Modbus): wait here, between cuts, until resumed. */
    while (j->paused && !atomic_load(&j->cancel_requested) && !atomic_load(&rc->q->stopping) &&
           !atomic_load(&j->released))
        pthread_cond_wait(&j->cond, &j->lock);
    pthread_mutex_unlock(&j->lock);

    if (atomic_load(&j->cancel_requested)) return 1;
    if (atomic_load(&rc->q->stopping) || atomic_load(&j->released)) {
        rc->stopped_for_shutdown = 1;
        return 1;
    }
    if (now - rc->last_snapshot >= rc->q->cfg.snapshot_interval_s) {
        fm_job_store_save_snapshot(j, p->stock, p->resume_from);
        rc->last_snapshot = fm_clock_monotonic_s();
    }
    /* A live job publishes as soon as it has caught up with the machine. */
    if (p->idle || now - rc->last_publish >= rc->q->cfg.publish_interval_s) {
        fm_publish_chunks(j, p->stock, p->program_time);
        rc->last_publish = fm_clock_monotonic_s();
    }
    return 0;
}

/* Meshing the uncut stock before the first cut holds the job's first
 * progress back for as long as that takes (a 100 x 100 x 50 mm block at
 * 0.1 mm is about 8 M triangles, 12 s on the 2-core machine): above this
 * many triangles, estimated as two per voxel face of the stock's bounding
 * box, the history starts at the first publication after cuts instead, and
 * history_from_s says so. */
#define HISTORY_START_TRIANGLES 1e6

/* The stock before the first cut: published as the stock at program time 0,
 * the start of the mesh history (a resumed job's history starts at its
 * first publication: the meshes before the restart are gone). */
static void on_stock(void *user, fm_stock *stock)
{
    run_ctx *rc = user;
    if (rc->resume_from > 0) return;
    int32_t lo[3], hi[3];
    if (fm_stock_active_bounds(stock, lo, hi, NULL) != FM_OK) return;
    double n[3];
    for (int a = 0; a < 3; a++) n[a] = (double)hi[a] - lo[a] - 2.0 * fm_stock_band_voxels(stock);
    for (int a = 0; a < 3; a++) n[a] = n[a] > 1 ? n[a] : 1;
    double triangles = 4 * (n[0] * n[1] + n[1] * n[2] + n[2] * n[0]);
    if (!(triangles <= HISTORY_START_TRIANGLES)) return;
    fm_publish_chunks(rc->j, stock, 0);
    rc->last_publish = fm_clock_monotonic_s();
}

static json_t *error_json(const fm_error *err)
{
    static const char *const codes[] = {"ok", "", "input", "limit", "io", "internal"};
    const char *code = (unsigned)err->code < 6 ? codes[err->code] : "internal";
    return json_pack("{s:s, s:i, s:s, s:o, s:o, s:s}", "code", code, "status", (int)err->code,
                     "message", err->message, "line",
                     err->line > 0 ? json_integer(err->line) : json_null(), "column",
                     err->column > 0 ? json_integer(err->column) : json_null(), "file", err->file);
}

void fm_queue_finish(fm_queue *q, job *j, fm_job_state state, const char *what)
{
    pthread_mutex_lock(&j->lock);
    j->state = state;
    if (state == FM_JOB_DONE) j->view.progress = 1;
    j->meshes_loaded = state != FM_JOB_FAILED;
    pthread_mutex_unlock(&j->lock);
    fm_job_store_write_result(j);
    pthread_mutex_lock(&j->lock);
    fm_publish_event(j, "end", json_pack("{s:s, s:O?}", "state", fm_job_state_name(state), "error", j->error));
    pthread_mutex_unlock(&j->lock);
    fm_log(state == FM_JOB_FAILED ? FM_LOG_WARN : FM_LOG_INFO, "job %s: %s", j->id, what);
    if (q->hooks.ended) q->hooks.ended(q->hooks.user, j);
}

/* The check opened a finding: published at once (status, `finding` event,
 * Modbus registers 23-25) while the job goes on cutting. */
static void on_finding(void *user, const fm_check *check, size_t index)
{
    run_ctx *rc = user;
    job *j = rc->j;
    json_t *all = fm_findings_json_array(check);
    pthread_mutex_lock(&j->lock);
    fm_publish_findings(j, all);
    fm_publish_event(j, "finding", fm_finding_json(fm_check_get(check, index)));
    pthread_mutex_unlock(&j->lock);
    json_decref(all);
}

static void run_job(fm_queue *q, job *j)
{
    /* The run spec as the document made it; the daemon adds its budget and
     * threads. j->doc is immutable while the job is known. */
    fm_job_spec spec = j->doc->spec;
    fm_error err;
    fm_error_clear(&err);
    run_ctx rc = {.q = q, .j = j, .pace = {.last_line = -1}};
    int unfinished = 0; /* stopped by shutdown: resumes at the next start */
    rc.last_snapshot = rc.last_publish = fm_clock_monotonic_s();

    pthread_mutex_lock(&j->lock);
    j->state = FM_JOB_RUNNING;
    fm_publish_event(j, "state", json_pack("{s:s}", "state", "running"));
    pthread_mutex_unlock(&j->lock);

    spec.stock.memory_budget = fm_job_memory_budget(q->cfg.job_memory_bytes, j->doc);
    if (!j->doc->threads_given) spec.stock.threads = q->cfg.threads_per_job;
    /* the motions the job makes, kept for GET /v1/jobs/ID/toolpath */
    char motion_log[JOB_DIR_MAX + 16];
    fm_job_file_path(j, "motions.log", motion_log, sizeof motion_log);
    spec.motion_log = motion_log;
    fm_status st = FM_OK;
    int live = spec.program_kind == FM_PROGRAM_LIVE;
    fm_job_motion_source source;
    if (live) {
        st = fm_live_prepare(j, &source, &err);
        spec.source = &source;
    }

    /* Resume from the last snapshot, if any. */
    long from = 0;
    if (st == FM_OK && (spec.resume_stock = fm_job_store_load_snapshot(j, &spec.stock, &from))) {
        spec.skip_motions = rc.resume_from = from;
        fm_log(FM_LOG_INFO, "job %s: resuming from its snapshot at motion %ld", j->id, from);
    }
    /* The collision check (spec.check, from the document) runs in the
     * same pass as the cut, on a grid of its own voxel (job.h): findings
     * are published as they are found (on_finding) and are the ones
     * `frepmill check` gives. */
    if (st == FM_OK) fm_log(FM_LOG_INFO, "job %s: running", j->id);

    fm_job_result result;
    memset(&result, 0, sizeof result);
    fm_job_hooks hooks = {
        .user = &rc, .progress = on_progress, .on_finding = on_finding, .on_stock = on_stock};
    if (st == FM_OK) {
        st = fm_job_run(&spec, &hooks, &result, &err);
        spec.resume_stock = NULL; /* the runner took it */
        /* the encoder of a live job's last publication ends here, on the
         * thread that started it, before any path below can free chunks */
        fm_publish_chunks_settle(j);
    } else {
        fm_stock_free(spec.resume_stock);
        spec.resume_stock = NULL;
    }
    if (st == FM_OK && result.check) {
        /* the findings as the check closed them (final depths and extents) */
        json_t *findings = fm_findings_json_array(result.check);
        pthread_mutex_lock(&j->lock);
        fm_publish_findings(j, findings);
        pthread_mutex_unlock(&j->lock);
        fm_log(fm_check_count_severity(result.check, FM_CHECK_ERROR) ? FM_LOG_WARN : FM_LOG_INFO,
               "job %s: check: %zu errors, %zu warnings in %.2f s of the pass", j->id,
               fm_check_count_severity(result.check, FM_CHECK_ERROR),
               fm_check_count_severity(result.check, FM_CHECK_WARNING), result.check_time_s);
        json_decref(findings);
    }
    if (st != FM_OK) {
        pthread_mutex_lock(&j->lock);
        json_decref(j->error);
        j->error = error_json(&err);
        j->view.error_code = (int)err.code;
        pthread_mutex_unlock(&j->lock);
        char buf[1024];
        char what[1200];
        snprintf(what, sizeof what, "failed: %s", fm_error_format(&err, buf, sizeof buf));
        fm_queue_finish(q, j, FM_JOB_FAILED, what);
        goto done;
    }
    pthread_mutex_lock(&j->lock);
    j->initial_mm3 = result.initial_volume_mm3;
    pthread_mutex_unlock(&j->lock);
    if (result.stopped && (rc.stopped_for_shutdown || atomic_load(&q->stopping)) &&
        !atomic_load(&j->cancel_requested)) {
        /* Stopping: keep the work done, resume at the next start. */
        fm_job_store_save_snapshot(j, result.stock, rc.resume_from);
        fm_stock_free(result.stock);
        result.stock = NULL;
        pthread_mutex_lock(&j->lock);
        j->state = FM_JOB_QUEUED;
        pthread_mutex_unlock(&j->lock);
        fm_log(FM_LOG_INFO, "job %s: stopped by %s at motion %ld; will resume", j->id,
               atomic_load(&j->released) ? "its queue (another daemon has it)" : "shutdown",
               rc.resume_from);
        unfinished = 1;
        goto done;
    }
    int deleted = atomic_load(&j->deleted);
    if (deleted) {
        fm_stock_free(result.stock);
        result.stock = NULL;
        fm_job_store_remove_deleted(j);
        fm_log(FM_LOG_INFO, "job %s: stopped (deleted)", j->id);
        goto done;
    }
    pthread_mutex_lock(&j->lock);
    double end_time = j->view.program_time_s;
    pthread_mutex_unlock(&j->lock);
    fm_publish_chunks(j, result.stock, end_time);
    fm_publish_chunks_drop_caches(j);
    if (result.design && result.has_deviation) {
        double w0 = fm_clock_monotonic_s();
        fm_error derr;
        if (fm_publish_deviation(j, result.stock, result.design, &result.deviation, &derr) == FM_OK)
            fm_log(FM_LOG_INFO, "job %s: deviation mesh written in %.2f s", j->id,
                   fm_clock_monotonic_s() - w0);
        else
            fm_log(FM_LOG_WARN, "job %s: no deviation mesh for the viewer: %s", j->id, derr.message);
    }
    pthread_mutex_lock(&j->lock);
    j->view.removed_mm3 = result.initial_volume_mm3 - result.final_volume_mm3;
    j->view.stock_mm3 = result.final_volume_mm3;
    j->report = fm_job_report_json(&result);
    pthread_mutex_unlock(&j->lock);
    fm_job_store_save_snapshot(j, result.stock, result.stopped ? rc.resume_from : result.motions);
    fm_stock_free(result.stock);
    result.stock = NULL;
    if (result.stopped) {
        fm_queue_finish(q, j, FM_JOB_CANCELLED, "cancelled");
    } else {
        char what[256];
        snprintf(what, sizeof what, "done: %ld motions, removed %.1f mm3 in %.2f s",
                 result.motions, result.removed_volume_mm3, result.wall_time_s);
        fm_queue_finish(q, j, FM_JOB_DONE, what);
    }
done:
    fm_job_result_release(&result);
    if (q->hooks.run_over) q->hooks.run_over(q->hooks.user, j, unfinished);
}

static void *worker_main(void *arg)
{
    fm_queue *q = arg;
    pthread_mutex_lock(&q->lock);
    for (;;) {
        while (!atomic_load(&q->stopping) && !q->head) pthread_cond_wait(&q->cond, &q->lock);
        if (atomic_load(&q->stopping)) break;
        job *j = q->head;
        q->head = j->next_queued;
        if (!q->head) q->tail = NULL;
        pthread_mutex_unlock(&q->lock);
        int skip = atomic_load(&j->deleted);
        pthread_mutex_lock(&j->lock);
        skip = skip || j->state >= FM_JOB_DONE; /* cancelled while queued */
        pthread_mutex_unlock(&j->lock);
        skip = skip || atomic_load(&j->released); /* its queue gave it to another daemon */
        if (!skip && atomic_load(&j->cancel_requested)) {
            fm_queue_finish(q, j, FM_JOB_CANCELLED, "cancelled before it started");
        } else if (!skip) {
            run_job(q, j);
        }
        fm_job_unref(j); /* the queue's reference */
        pthread_mutex_lock(&q->lock);
    }
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

fm_status fm_queue_start_workers(fm_queue *q, int count, fm_error *err)
{
    q->workers = calloc((size_t)(count > 0 ? count : 1), sizeof *q->workers);
    for (int i = 0; q->workers && i < count; i++)
        if (pthread_create(&q->workers[i], NULL, worker_main, q) == 0) q->worker_count++;
    if (q->worker_count == 0)
        return fm_error_set(err, FM_ERR_INTERNAL, "cannot start worker threads");
    return FM_OK;
}

void fm_queue_join_workers(fm_queue *q)
{
    for (int i = 0; i < q->worker_count; i++) pthread_join(q->workers[i], NULL);
    q->worker_count = 0;
    free(q->workers);
    q->workers = NULL;
}

void fm_queue_drain(fm_queue *q)
{
    pthread_mutex_lock(&q->lock);
    job *j = q->head;
    q->head = q->tail = NULL;
    pthread_mutex_unlock(&q->lock);
    while (j) {
        job *next = j->next_queued;
        fm_job_unref(j);
        j = next;
    }
}

static void *own_main(void *arg)
{
    own_thread *t = arg;
    run_job(t->q, t->j);
    fm_job_unref(t->j);
    atomic_store(&t->done, 1);
    return NULL;
}

fm_status fm_queue_run_now(fm_queue *q, job *j, fm_error *err)
{
    fm_queue_join_own(q, 0); /* threads of live jobs that have ended */
    own_thread *t = calloc(1, sizeof *t);
    if (!t) return fm_error_set_reason(err, FM_ERR_LIMIT, "busy", "out of memory");
    t->q = q;
    t->j = j;
    fm_job_ref(j); /* the thread's */
    if (pthread_create(&t->thread, NULL, own_main, t) != 0) {
        fm_job_unref(j);
        free(t);
        return fm_error_set_reason(err, FM_ERR_LIMIT, "busy", "cannot start a thread");
    }
    pthread_mutex_lock(&q->lock);
    t->next = q->own_threads;
    q->own_threads = t;
    pthread_mutex_unlock(&q->lock);
    return FM_OK;
}

void fm_queue_join_own(fm_queue *q, int all)
{
    pthread_mutex_lock(&q->lock);
    own_thread **link = &q->own_threads, *gone = NULL;
    while (*link) {
        own_thread *t = *link;
        if (all || atomic_load(&t->done)) {
            *link = t->next;
            t->next = gone;
            gone = t;
        } else {
            link = &t->next;
        }
    }
    pthread_mutex_unlock(&q->lock);
    while (gone) {
        own_thread *next = gone->next;
        pthread_join(gone->thread, NULL);
        free(gone);
        gone = next;
    }
}
