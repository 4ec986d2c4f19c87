/* jobs.c: the job manager's table. Every job the daemon knows is a record
 * here, in creation order (Modbus slots and listings rely on it), shared by
 * reference between the table, the queue, the workers and readers. Submit,
 * cancel, pause and remove act on it; job_store.c makes it durable,
 * queue.c runs it, publish.c shows it. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "jobs_internal.h"
#include "log.h"
#include "store.h"

double fm_jobs_mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double fm_jobs_wall_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

const char *fm_job_state_name(fm_job_state state)
{
    static const char *const names[] = {"queued", "running", "done", "failed", "cancelled"};
    return (unsigned)state < 5 ? names[state] : "unknown";
}

/* ------------------------------------------------------------ records -- */

job *fm_jobs_record_new(const char *id, const char *jobs_dir, fm_job_doc *doc, double created)
{
    job *j = calloc(1, sizeof *j);
    if (!j) {
        fm_job_doc_free(doc);
        return NULL;
    }
    snprintf(j->id, sizeof j->id, "%s", id);
    snprintf(j->dir, sizeof j->dir, "%.1200s/%.40s", jobs_dir, id);
    j->doc = doc;
    j->created = created;
    j->refs = 1; /* the table's */
    pthread_mutex_init(&j->lock, NULL);
    pthread_mutex_init(&j->load_lock, NULL);
    pthread_cond_init(&j->cond, NULL);
    j->next_event = 1;
    j->history_from_s = -1;
    j->view.block = -1;
    snprintf(j->view.id, sizeof j->view.id, "%s", id);
    return j;
}

static void job_free(job *j)
{
    fm_publish_chunks_free(j);
    for (int i = 0; i < JOB_EVENT_RING; i++) free(j->ring[i].data);
    fm_job_doc_free(j->doc);
    fm_live_free(j->live);
    json_decref(j->error);
    json_decref(j->report);
    json_decref(j->findings);
    pthread_mutex_destroy(&j->lock);
    pthread_mutex_destroy(&j->load_lock);
    pthread_cond_destroy(&j->cond);
    free(j);
}

job *fm_jobs_get(fm_jobs *jobs, const char *id)
{
    job *found = NULL;
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++)
        if (!strcmp(jobs->table[i]->id, id) && !jobs->table[i]->deleted) {
            found = jobs->table[i];
            found->refs++;
            break;
        }
    pthread_mutex_unlock(&jobs->lock);
    return found;
}

void fm_jobs_put(fm_jobs *jobs, job *j)
{
    if (!j) return;
    pthread_mutex_lock(&jobs->lock);
    int last = --j->refs == 0;
    pthread_mutex_unlock(&jobs->lock);
    if (last) job_free(j);
}

void fm_jobs_table_add(fm_jobs *jobs, job *j)
{
    j->jobs = jobs;
    if (jobs->count == jobs->cap) {
        size_t cap = jobs->cap ? jobs->cap * 2 : 64;
        job **t = realloc(jobs->table, cap * sizeof *t);
        if (!t) return;
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

int fm_jobs_stopping(fm_jobs *jobs)
{
    pthread_mutex_lock(&jobs->lock);
    int stopping = jobs->stopping;
    pthread_mutex_unlock(&jobs->lock);
    return stopping;
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
    size_t budget = jobs->cfg.job_memory_bytes;
    double mb = doc->memory_budget_mb;
    if (mb > 0 && mb * 1048576.0 < (double)budget) budget = (size_t)(mb * 1048576.0);
    return budget;
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
    for (size_t i = 0; i < jobs->count; i++) kept += !jobs->table[i]->deleted;
    int stopping = jobs->stopping;
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
    double created = fm_jobs_wall_s();
    fm_error ferr;
    fm_error_clear(&ferr);
    if (fm_job_store_create(jobs, new_id, created, doc, &ferr) != FM_OK) {
        fm_log(FM_LOG_ERROR, "cannot store a new job: %s", ferr.message);
        fm_job_doc_free(doc);
        return fm_error_set_reason(err, FM_ERR_IO, "storage", "the job could not be stored: %s",
                                   ferr.message);
    }
    job *j = fm_jobs_record_new(new_id, jobs->jobs_dir, doc, created);
    if (!j)
        return fm_error_set_reason(err, FM_ERR_LIMIT, "out_of_memory", "out of memory");
    pthread_mutex_lock(&j->lock);
    fm_publish_event(j, "state", json_pack("{s:s}", "state", "queued"));
    pthread_mutex_unlock(&j->lock);
    pthread_mutex_lock(&jobs->lock);
    fm_jobs_table_add(jobs, j);
    j->refs++; /* the caller's */
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
    pthread_mutex_lock(&jobs->lock);
    fm_queue_push(jobs, j);
    pthread_mutex_unlock(&jobs->lock);
    snprintf(id, id_size, "%s", j->id);
    fm_jobs_put(jobs, j);
    return FM_OK;
}

fm_status fm_jobs_submit_live(fm_jobs *jobs, fm_job_doc *doc, char *id, size_t id_size,
                              fm_error *err)
{
    job *j;
    fm_status st = admit(jobs, doc, NULL, &j, err);
    if (st != FM_OK) return st;
    st = fm_live_attach(jobs, j, err);
    if (st != FM_OK) {
        fm_jobs_put(jobs, j);
        return st;
    }
    snprintf(id, id_size, "%s", j->id);
    st = fm_queue_run_now(jobs, j, err);
    if (st != FM_OK) fm_live_detach(jobs, j);
    fm_jobs_put(jobs, j);
    return st;
}

/* ------------------------------------------------------ shared queues -- */

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
    if (!j && fm_job_store_load_one(jobs, id)) j = fm_jobs_get(jobs, id);
    if (!j) {
        *result = FM_JOBS_TAKEN;
        fm_status st = admit(jobs, doc, id, &j, err);
        if (st != FM_OK) return st;
        pthread_mutex_lock(&jobs->lock);
        fm_queue_push(jobs, j);
        pthread_mutex_unlock(&jobs->lock);
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
        fm_queue_push(jobs, j);
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

void fm_jobs_notify_end(fm_jobs *jobs, job *j)
{
    pthread_mutex_lock(&jobs->lock);
    fm_jobs_end_hook hook = jobs->end_hook;
    void *user = jobs->end_hook_user;
    pthread_mutex_unlock(&jobs->lock);
    if (!hook) return;
    json_t *status = fm_publish_status_json(j);
    if (status) hook(user, j->id, status);
    json_decref(status);
}

int fm_jobs_busy(fm_jobs *jobs)
{
    int n = 0;
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        if (j->deleted || j->held) continue;
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
    if (fm_job_store_mark_deleted(jobs, j, &ferr) != FM_OK) {
        fm_jobs_put(jobs, j);
        return fm_error_set_reason(err, FM_ERR_IO, "storage", "%s", ferr.message);
    }
    pthread_mutex_lock(&jobs->lock);
    j->deleted = 1;
    int running = 0;
    for (size_t i = 0; i < jobs->count; i++)
        if (jobs->table[i] == j) {
            memmove(&jobs->table[i], &jobs->table[i + 1],
                    (jobs->count - i - 1) * sizeof *jobs->table);
            jobs->count--;
            j->refs--; /* the table's */
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
    pthread_mutex_init(&jobs->lock, NULL);
    pthread_mutex_init(&jobs->live_lock, NULL);
    pthread_cond_init(&jobs->queue_cond, NULL);
    fm_job_store_load_all(jobs);
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
        else fm_queue_push(jobs, j);
    }
    pthread_mutex_unlock(&jobs->lock);
    if (live) {
        fm_error lerr;
        fm_error_clear(&lerr);
        if (fm_live_attach(jobs, live, &lerr) != FM_OK || fm_queue_run_now(jobs, live, &lerr) != FM_OK)
            fm_log(FM_LOG_ERROR, "job %s: cannot resume the live job: %s", live->id, lerr.message);
    }
    if (fm_queue_start_workers(jobs, cfg->workers, err) != FM_OK) {
        fm_jobs_close(jobs);
        return NULL;
    }
    return jobs;
}

void fm_jobs_begin_shutdown(fm_jobs *jobs)
{
    pthread_mutex_lock(&jobs->lock);
    jobs->stopping = 1;
    pthread_cond_broadcast(&jobs->queue_cond);
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
    pthread_mutex_lock(&jobs->live_lock);
    job *live = jobs->live_job;
    jobs->live_job = NULL;
    pthread_mutex_unlock(&jobs->live_lock);
    if (live) fm_jobs_put(jobs, live);
    fm_queue_join_workers(jobs);
    fm_queue_join_own(jobs, 1);
    fm_queue_drain(jobs);
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        if (--j->refs == 0) job_free(j);
    }
    free(jobs->table);
    pthread_mutex_destroy(&jobs->lock);
    pthread_mutex_destroy(&jobs->live_lock);
    pthread_cond_destroy(&jobs->queue_cond);
    free(jobs);
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
        j->refs++;
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
    if (queued) fm_queue_finish(jobs, j, FM_JOB_CANCELLED, "cancelled before it started");
    fm_jobs_put(jobs, j);
    return ok ? FM_OK : ended(id, err);
}
