/* jobs.c: the job manager (jobs.h) and its table. Every job the daemon
 * knows is a record (job_record.h) here, in creation order (Modbus slots
 * and listings rely on it), shared by reference with the queue, the
 * workers and readers. Submit, take, cancel, pause, remove and live mode
 * act on it; the parts below it never call back into it: job_store.c makes
 * a job durable and reads folders back into records it hands to adopt(),
 * queue.c runs jobs and reports their ends through hooks, publish.c shows
 * them, live.c feeds a live one. */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "jobs.h"
#include "job_record.h"
#include "job_store.h"
#include "live.h"
#include "log.h"
#include "publish.h"
#include "queue.h"
#include "store.h"

/* Folder name buffers: small enough that a file name appended still fits
 * PATH_MAX, which lets the compiler prove no path is truncated. */
#define JOB_STATE_DIR_MAX 1100

struct fm_jobs {
    fm_jobs_config cfg;
    char state_dir[JOB_STATE_DIR_MAX];
    char jobs_dir[JOB_STATE_DIR_MAX + 8];
    /* lock guards the table, each record's `held` and the end hook; it is
     * taken before a job's lock, after the live session's. */
    pthread_mutex_t lock;
    job **table;
    size_t count, cap;
    atomic_uint id_counter;
    fm_queue *queue;
    /* Live mode: the live job taking positions (live.c); live jobs run on
     * threads of their own (fm_queue_run_now), not behind the queue. */
    fm_live_session live;
    /* Told of every job that ends (queue_redis.c). */
    fm_jobs_end_hook end_hook;
    void *end_hook_user;
};

job *fm_jobs_get(fm_jobs *jobs, const char *id)
{
    job *found = NULL;
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++)
        if (!strcmp(jobs->table[i]->id, id) && !jobs->table[i]->deleted) {
            found = jobs->table[i];
            fm_job_ref(found);
            break;
        }
    pthread_mutex_unlock(&jobs->lock);
    return found;
}

void fm_jobs_put(fm_jobs *jobs, job *j)
{
    (void)jobs;
    fm_job_unref(j);
}

/* Insert in creation order (caller holds jobs->lock); the table takes the
 * caller's reference. */
static void table_add(fm_jobs *jobs, job *j)
{
    if (jobs->count == jobs->cap) {
        size_t cap = jobs->cap ? jobs->cap * 2 : 64;
        job **t = realloc(jobs->table, cap * sizeof *t);
        if (!t) {
            fm_job_unref(j);
            return;
        }
        jobs->table = t;
        jobs->cap = cap;
    }
    /* Keep creation order: slots (Modbus) and listings rely on it. */
    size_t i = jobs->count;
    while (i > 0 && jobs->table[i - 1]->created > j->created) {
        jobs->table[i] = jobs->table[i - 1];
        i--;
    }
    jobs->table[i] = j;
    jobs->count++;
}

/* ------------------------------------------------------------ submit -- */

static void make_id(fm_jobs *jobs, char *id, size_t size)
{
    unsigned char r[3] = {0};
    int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
        if (read(fd, r, sizeof r) != (ssize_t)sizeof r) memset(r, 0, sizeof r);
        close(fd);
    }
    unsigned counter = atomic_fetch_add(&jobs->id_counter, 1u);
    /* Time first, so ids sort by creation; the counter and random bytes
     * keep two ids of one second (or of two daemons) apart. */
    snprintf(id, size, "%08llx-%04x%02x%02x", (unsigned long long)time(NULL), counter & 0xffffu,
             r[0], r[1]);
}

fm_job_doc_rules fm_jobs_doc_rules(const fm_jobs *jobs, int own)
{
    fm_job_doc_rules rules = {.allow_files = own, .allow_live = own};
    rules.dialect = jobs->cfg.dialect;
    rules.subroutine_path = jobs->cfg.subroutine_path;
    return rules;
}

size_t fm_jobs_memory_budget(const fm_jobs *jobs, const fm_job_doc *doc)
{
    return fm_job_memory_budget(jobs->cfg.job_memory_bytes, doc);
}

const fm_jobs_config *fm_jobs_config_of(const fm_jobs *jobs)
{
    return &jobs->cfg;
}

/* Store a document durably and make its record (in the table, with a
 * reference for the caller) under given_id, or a new id when NULL. Takes
 * doc. */
static fm_status admit(fm_jobs *jobs, fm_job_doc *doc, const char *given_id, job **out,
                       fm_error *err)
{
    *out = NULL;
    /* A cheap check before acknowledging: a box or cylinder stock whose
     * grid estimate is over the per-job budget is refused now, not after
     * queueing. */
    fm_status st = fm_job_doc_check_memory(doc, fm_jobs_memory_budget(jobs, doc), err);
    if (st != FM_OK) {
        fm_job_doc_free(doc);
        return st;
    }
    pthread_mutex_lock(&jobs->lock);
    size_t kept = 0;
    for (size_t i = 0; i < jobs->count; i++) kept += !atomic_load(&jobs->table[i]->deleted);
    int stopping = atomic_load(fm_queue_stopping(jobs->queue));
    pthread_mutex_unlock(&jobs->lock);
    if (stopping || (int)kept >= jobs->cfg.max_jobs) {
        fm_job_doc_free(doc);
        if (stopping)
            return fm_error_set_reason(err, FM_ERR_LIMIT, "shutting_down", "the daemon is stopping");
        return fm_error_set_reason(err, FM_ERR_LIMIT, "job_limit",
                                   "%zu jobs are stored, the most allowed (max_jobs); delete "
                                   "finished jobs first",
                                   kept);
    }
    char new_id[32];
    if (given_id) snprintf(new_id, sizeof new_id, "%s", given_id);
    else make_id(jobs, new_id, sizeof new_id);
    double created = fm_clock_wall_s();
    fm_error ferr;
    fm_error_clear(&ferr);
    if (fm_job_store_create(jobs->jobs_dir, new_id, created, doc, &ferr) != FM_OK) {
        fm_log(FM_LOG_ERROR, "cannot store a new job: %s", ferr.message);
        fm_job_doc_free(doc);
        return fm_error_set_reason(err, FM_ERR_IO, "storage", "the job could not be stored: %s",
                                   ferr.message);
    }
    job *j = fm_job_record_new(new_id, jobs->jobs_dir, doc, created, jobs->cfg.mesh_history_bytes,
                               fm_queue_stopping(jobs->queue));
    if (!j)
        return fm_error_set_reason(err, FM_ERR_LIMIT, "out_of_memory", "out of memory");
    pthread_mutex_lock(&j->lock);
    fm_publish_event(j, "state", json_pack("{s:s}", "state", "queued"));
    pthread_mutex_unlock(&j->lock);
    fm_job_ref(j); /* the caller's */
    pthread_mutex_lock(&jobs->lock);
    table_add(jobs, j);
    pthread_mutex_unlock(&jobs->lock);
    fm_log(FM_LOG_INFO, "job %s: accepted%s%s", new_id, j->doc->name[0] ? " as " : "",
           j->doc->name);
    *out = j;
    return FM_OK;
}

fm_status fm_jobs_submit(fm_jobs *jobs, fm_job_doc *doc, char *id, size_t id_size,
                         fm_error *err)
{
    job *j;
    fm_status st = admit(jobs, doc, NULL, &j, err);
    if (st != FM_OK) return st;
    fm_queue_push(jobs->queue, j);
    snprintf(id, id_size, "%s", j->id);
    fm_jobs_put(jobs, j);
    return FM_OK;
}

/* A live job's document stored like any job's, then run at once on a
 * thread of its own and attached as the live session. */
static fm_status submit_live(fm_jobs *jobs, fm_job_doc *doc, char *id, size_t id_size,
                             fm_error *err)
{
    job *j;
    fm_status st = admit(jobs, doc, NULL, &j, err);
    if (st != FM_OK) return st;
    st = fm_live_attach(&jobs->live, j, err);
    if (st != FM_OK) {
        fm_jobs_put(jobs, j);
        return st;
    }
    snprintf(id, id_size, "%s", j->id);
    st = fm_queue_run_now(jobs->queue, j, err);
    if (st != FM_OK) fm_live_detach(&jobs->live, j);
    fm_jobs_put(jobs, j);
    return st;
}

/* ------------------------------------------------------ shared queues -- */

/* Stored jobs come back into the table in creation order. */
static void adopt(void *user, job *j)
{
    fm_jobs *jobs = user;
    pthread_mutex_lock(&jobs->lock);
    table_add(jobs, j);
    pthread_mutex_unlock(&jobs->lock);
}

static fm_job_store_loader store_loader(fm_jobs *jobs)
{
    fm_job_store_loader loader = {
        .jobs_dir = jobs->jobs_dir,
        /* What the daemon stored it validated; read back with the rules
         * of its own documents (a live job's stock may be a configured
         * file). */
        .rules = fm_jobs_doc_rules(jobs, 1),
        .history_limit = jobs->cfg.mesh_history_bytes,
        .stopping = fm_queue_stopping(jobs->queue),
        .adopt = adopt,
        .user = jobs,
    };
    return loader;
}

fm_status fm_jobs_take(fm_jobs *jobs, const char *id, fm_job_doc *doc,
                       fm_jobs_take_result *result, json_t **final, fm_error *err)
{
    *final = NULL;
    if (strlen(id) >= 32) {
        fm_job_doc_free(doc);
        return fm_error_set_reason(err, FM_ERR_INPUT, "bad_id",
                                   "the queue's job id '%.64s' is too long", id);
    }
    job *j = fm_jobs_get(jobs, id);
    /* Not known here: a folder that a daemon sharing the state folder left. */
    if (!j) {
        const fm_job_store_loader loader = store_loader(jobs);
        if (fm_job_store_load_one(&loader, id)) j = fm_jobs_get(jobs, id);
    }
    if (!j) {
        *result = FM_JOBS_TAKEN;
        fm_status st = admit(jobs, doc, id, &j, err);
        if (st != FM_OK) return st;
        fm_queue_push(jobs->queue, j);
        fm_jobs_put(jobs, j);
        return FM_OK;
    }
    fm_job_doc_free(doc); /* the stored one stands */
    pthread_mutex_lock(&j->lock);
    int ended = j->state >= FM_JOB_DONE;
    pthread_mutex_unlock(&j->lock);
    if (ended) {
        *final = fm_publish_status_json(j);
        *result = FM_JOBS_TAKEN_FINAL;
        fm_jobs_put(jobs, j);
        return FM_OK;
    }
    pthread_mutex_lock(&jobs->lock);
    if (j->held) {
        j->held = 0;
        atomic_store(&j->released, 0);
        fm_queue_push(jobs->queue, j);
        *result = FM_JOBS_TAKEN;
        fm_log(FM_LOG_INFO, "job %s: taken from the queue again; resuming", id);
    } else {
        *result = FM_JOBS_TAKEN_ALREADY;
    }
    pthread_mutex_unlock(&jobs->lock);
    fm_jobs_put(jobs, j);
    return FM_OK;
}

void fm_jobs_set_end_hook(fm_jobs *jobs, fm_jobs_end_hook hook, void *user)
{
    pthread_mutex_lock(&jobs->lock);
    jobs->end_hook = hook;
    jobs->end_hook_user = user;
    pthread_mutex_unlock(&jobs->lock);
}

/* The queue's hooks: a job ended (the end hook, with its final status), a
 * run is over (a live job's session ends with it). */
static void on_job_ended(void *user, job *j)
{
    fm_jobs *jobs = user;
    pthread_mutex_lock(&jobs->lock);
    fm_jobs_end_hook hook = jobs->end_hook;
    void *hook_user = jobs->end_hook_user;
    pthread_mutex_unlock(&jobs->lock);
    if (!hook) return;
    json_t *status = fm_publish_status_json(j);
    if (status) hook(hook_user, j->id, status);
    json_decref(status);
}

static void on_run_over(void *user, job *j, int unfinished)
{
    fm_jobs *jobs = user;
    if (!unfinished && j->doc->spec.program_kind == FM_PROGRAM_LIVE) fm_live_detach(&jobs->live, j);
}

int fm_jobs_busy(fm_jobs *jobs)
{
    int n = 0;
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        if (atomic_load(&j->deleted) || j->held) continue;
        pthread_mutex_lock(&j->lock);
        n += j->state == FM_JOB_QUEUED || j->state == FM_JOB_RUNNING;
        pthread_mutex_unlock(&j->lock);
    }
    pthread_mutex_unlock(&jobs->lock);
    return n;
}

void fm_jobs_release(fm_jobs *jobs, const char *id)
{
    job *j = fm_jobs_get(jobs, id);
    if (!j) return;
    pthread_mutex_lock(&jobs->lock);
    atomic_store(&j->released, 1);
    j->held = 1;
    pthread_mutex_unlock(&jobs->lock);
    pthread_mutex_lock(&j->lock);
    pthread_cond_broadcast(&j->cond); /* out of a pause */
    pthread_mutex_unlock(&j->lock);
    fm_jobs_put(jobs, j);
}

static fm_status not_found(const char *id, fm_error *err)
{
    return fm_error_set_reason(err, FM_ERR_INPUT, "not_found", "no job %.40s", id);
}

fm_status fm_jobs_remove(fm_jobs *jobs, const char *id, fm_error *err)
{
    job *j = fm_jobs_get(jobs, id);
    if (!j) return not_found(id, err);
    atomic_store(&j->cancel_requested, 1);
    pthread_mutex_lock(&j->lock);
    j->paused = 0;
    pthread_cond_broadcast(&j->cond);
    pthread_mutex_unlock(&j->lock);
    /* Renamed first: one atomic step makes the job gone for a restart even
     * if the files are not all unlinked yet. */
    fm_error ferr;
    fm_error_clear(&ferr);
    if (fm_job_store_mark_deleted(jobs->jobs_dir, j, &ferr) != FM_OK) {
        fm_jobs_put(jobs, j);
        return fm_error_set_reason(err, FM_ERR_IO, "storage", "%s", ferr.message);
    }
    pthread_mutex_lock(&jobs->lock);
    atomic_store(&j->deleted, 1);
    int running = 0, dropped = 0;
    for (size_t i = 0; i < jobs->count; i++)
        if (jobs->table[i] == j) {
            memmove(&jobs->table[i], &jobs->table[i + 1],
                    (jobs->count - i - 1) * sizeof *jobs->table);
            jobs->count--;
            dropped = 1; /* the table's reference, dropped below */
            break;
        }
    pthread_mutex_lock(&j->lock);
    running = j->state == FM_JOB_RUNNING;
    fm_publish_event(j, "end", json_pack("{s:s}", "state", "deleted"));
    pthread_mutex_unlock(&j->lock);
    pthread_mutex_unlock(&jobs->lock);
    /* A running job's worker may still write its snapshot into the renamed
     * folder; it removes the folder when it ends. */
    if (!running) fm_job_store_remove_deleted(j);
    fm_log(FM_LOG_INFO, "job %s: deleted", id);
    if (dropped) fm_job_unref(j);
    fm_jobs_put(jobs, j);
    return FM_OK;
}

/* ---------------------------------------------------------- lifecycle -- */

fm_jobs *fm_jobs_open(const fm_jobs_config *cfg, fm_error *err)
{
    fm_jobs *jobs = calloc(1, sizeof *jobs);
    if (!jobs) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    jobs->cfg = *cfg;
    snprintf(jobs->state_dir, sizeof jobs->state_dir, "%s", cfg->state_dir);
    snprintf(jobs->jobs_dir, sizeof jobs->jobs_dir, "%s/jobs", cfg->state_dir);
    jobs->cfg.state_dir = jobs->state_dir;
    if (fm_store_mkdirs(jobs->jobs_dir, err) != FM_OK) {
        free(jobs);
        return NULL;
    }
    const fm_queue_config qcfg = {.threads_per_job = cfg->threads_per_job,
                                  .snapshot_interval_s = cfg->snapshot_interval_s,
                                  .publish_interval_s = cfg->publish_interval_s,
                                  .job_memory_bytes = cfg->job_memory_bytes};
    const fm_queue_hooks hooks = {.user = jobs, .ended = on_job_ended, .run_over = on_run_over};
    if (!(jobs->queue = fm_queue_new(&qcfg, &hooks, err))) {
        free(jobs);
        return NULL;
    }
    pthread_mutex_init(&jobs->lock, NULL);
    fm_live_session_init(&jobs->live);
    const fm_job_store_loader loader = store_loader(jobs);
    fm_job_store_load_all(&loader);
    /* Resume in creation order (the folders were read in any order); an
     * unfinished live job runs at once and takes positions again. */
    job *live = NULL;
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        if (j->state >= FM_JOB_DONE) continue;
        /* A queue job waits for its queue (fm_jobs_take). */
        if (!strncmp(j->id, "q-", 2)) j->held = 1;
        else if (j->doc->spec.program_kind == FM_PROGRAM_LIVE) live = j;
        else fm_queue_push(jobs->queue, j);
    }
    pthread_mutex_unlock(&jobs->lock);
    if (live) {
        fm_error lerr;
        fm_error_clear(&lerr);
        if (fm_live_attach(&jobs->live, live, &lerr) != FM_OK ||
            fm_queue_run_now(jobs->queue, live, &lerr) != FM_OK)
            fm_log(FM_LOG_ERROR, "job %s: cannot resume the live job: %s", live->id, lerr.message);
    }
    if (fm_queue_start_workers(jobs->queue, cfg->workers, err) != FM_OK) {
        fm_jobs_close(jobs);
        return NULL;
    }
    return jobs;
}

void fm_jobs_begin_shutdown(fm_jobs *jobs)
{
    fm_queue_stop(jobs->queue);
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        pthread_mutex_lock(&j->lock);
        pthread_cond_broadcast(&j->cond);
        pthread_mutex_unlock(&j->lock);
    }
    pthread_mutex_unlock(&jobs->lock);
}

void fm_jobs_close(fm_jobs *jobs)
{
    if (!jobs) return;
    fm_jobs_begin_shutdown(jobs);
    pthread_mutex_lock(&jobs->live.lock);
    job *live = jobs->live.job;
    jobs->live.job = NULL;
    pthread_mutex_unlock(&jobs->live.lock);
    fm_job_unref(live);
    fm_queue_join_workers(jobs->queue);
    fm_queue_join_own(jobs->queue, 1);
    fm_queue_drain(jobs->queue);
    for (size_t i = 0; i < jobs->count; i++) fm_job_unref(jobs->table[i]);
    free(jobs->table);
    fm_queue_free(jobs->queue);
    fm_live_session_destroy(&jobs->live);
    pthread_mutex_destroy(&jobs->lock);
    free(jobs);
}

/* ---------------------------------------------------------- live mode -- */

fm_status fm_jobs_live_start(fm_jobs *jobs, int from_slot, fm_error *err)
{
    if (fm_live_active(&jobs->live)) return FM_OK; /* already on (also after a restart resumed it) */
    /* The selected job's stock and tools, unless configured. */
    job *src = NULL;
    pthread_mutex_lock(&jobs->lock);
    if (from_slot >= 1 && (size_t)from_slot <= jobs->count) {
        src = jobs->table[from_slot - 1];
        fm_job_ref(src);
    }
    pthread_mutex_unlock(&jobs->lock);
    const fm_live_config lcfg = {.stock = jobs->cfg.live_stock,
                                 .tools = jobs->cfg.live_tools,
                                 .machine = jobs->cfg.live_machine,
                                 .voxel = jobs->cfg.live_voxel,
                                 .feed = jobs->cfg.live_feed};
    const fm_job_doc_rules own = fm_jobs_doc_rules(jobs, 1);
    fm_job_doc *doc = NULL;
    fm_status st = fm_live_document(&lcfg, src, &own, &doc, err);
    fm_job_unref(src);
    if (st != FM_OK) {
        fm_log(FM_LOG_WARN, "live mode refused: %s", err->message);
        return st;
    }
    char id[32];
    st = submit_live(jobs, doc, id, sizeof id, err);
    if (st != FM_OK) {
        fm_log(FM_LOG_WARN, "live mode refused: %s", err->message);
        return st;
    }
    fm_log(FM_LOG_INFO, "job %s: live job created", id);
    return FM_OK;
}

fm_status fm_jobs_live_position(fm_jobs *jobs, const fm_live_pose *pose, fm_error *err)
{
    return fm_live_position(&jobs->live, pose, err);
}

fm_status fm_jobs_live_stop(fm_jobs *jobs, fm_error *err)
{
    (void)err;
    fm_live_stop(&jobs->live);
    return FM_OK;
}

int fm_jobs_live_active(fm_jobs *jobs)
{
    return fm_live_active(&jobs->live);
}

void fm_jobs_live_note(fm_jobs *jobs, const char *note)
{
    fm_live_note(&jobs->live, note);
}

int fm_jobs_live_machine(fm_jobs *jobs, fm_live_pose *out)
{
    return fm_live_machine(&jobs->live, out);
}

void fm_jobs_live_on_position(fm_jobs *jobs, void (*fn)(void *user), void *user)
{
    fm_live_on_position(&jobs->live, fn, user);
}

json_t *fm_jobs_status_list(fm_jobs *jobs)
{
    /* References first, statuses after: never hold the table lock while
     * taking a job's lock for long. */
    pthread_mutex_lock(&jobs->lock);
    size_t n = jobs->count;
    job **copy = malloc((n ? n : 1) * sizeof *copy);
    if (copy)
        for (size_t i = 0; i < n; i++) {
            copy[i] = jobs->table[i];
            fm_job_ref(copy[i]);
        }
    pthread_mutex_unlock(&jobs->lock);
    if (!copy) return NULL;
    json_t *list = json_array();
    for (size_t i = 0; i < n; i++) {
        json_array_append_new(list, fm_publish_status_json(copy[i]));
        fm_job_unref(copy[i]);
    }
    free(copy);
    return json_pack("{s:o}", "jobs", list);
}

/* ------------------------------------------------------------- Modbus -- */

int fm_jobs_count(fm_jobs *jobs)
{
    pthread_mutex_lock(&jobs->lock);
    int n = (int)jobs->count;
    pthread_mutex_unlock(&jobs->lock);
    return n;
}

int fm_jobs_view_slot(fm_jobs *jobs, int slot, fm_job_view *out)
{
    job *j = NULL;
    pthread_mutex_lock(&jobs->lock);
    if (slot >= 1 && (size_t)slot <= jobs->count) {
        j = jobs->table[slot - 1];
        fm_job_ref(j);
    }
    pthread_mutex_unlock(&jobs->lock);
    if (!j) return -1;
    pthread_mutex_lock(&j->lock);
    *out = j->view;
    out->state = j->state;
    out->paused = j->paused;
    pthread_mutex_unlock(&j->lock);
    fm_jobs_put(jobs, j);
    return 0;
}

static fm_status ended(const char *id, fm_error *err)
{
    return fm_error_set_reason(err, FM_ERR_INPUT, "bad_state", "job %.40s has already ended", id);
}

fm_status fm_jobs_pause(fm_jobs *jobs, const char *id, int pause, fm_error *err)
{
    job *j = fm_jobs_get(jobs, id);
    if (!j) return not_found(id, err);
    pthread_mutex_lock(&j->lock);
    int ok = j->state <= FM_JOB_RUNNING;
    if (ok) {
        j->paused = pause;
        pthread_cond_broadcast(&j->cond);
        fm_publish_event(j, "state", json_pack("{s:s, s:b}", "state", fm_job_state_name(j->state),
                                               "paused", pause));
    }
    pthread_mutex_unlock(&j->lock);
    fm_jobs_put(jobs, j);
    return ok ? FM_OK : ended(id, err);
}

void fm_jobs_pause_all(fm_jobs *jobs)
{
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        pthread_mutex_lock(&j->lock);
        if (j->state == FM_JOB_RUNNING) j->paused = 1;
        pthread_mutex_unlock(&j->lock);
    }
    pthread_mutex_unlock(&jobs->lock);
}

fm_status fm_jobs_cancel(fm_jobs *jobs, const char *id, fm_error *err)
{
    job *j = fm_jobs_get(jobs, id);
    if (!j) return not_found(id, err);
    pthread_mutex_lock(&j->lock);
    int ok = j->state <= FM_JOB_RUNNING;
    int queued = j->state == FM_JOB_QUEUED;
    if (ok) {
        atomic_store(&j->cancel_requested, 1);
        j->paused = 0;
        pthread_cond_broadcast(&j->cond);
        /* A queued job ends now; its worker will skip it. */
        if (queued) j->state = FM_JOB_CANCELLED;
    }
    pthread_mutex_unlock(&j->lock);
    if (queued) fm_queue_finish(jobs->queue, j, FM_JOB_CANCELLED, "cancelled before it started");
    fm_jobs_put(jobs, j);
    return ok ? FM_OK : ended(id, err);
}
