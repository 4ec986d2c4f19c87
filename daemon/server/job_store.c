/* job_store.c: the durable side of jobs. Each job is a folder
 * state_dir/jobs/<id>/: spec.json (written before the job is acknowledged),
 * stock.vdb (the crash-safe stock snapshot whose resume string
 * "resume_from=N" says every motion before N is in it) and result.json
 * (written when the job ends). At start every folder is read back: a result
 * means the job is finished; no result means it is to be queued again and
 * resumes from its snapshot, if any, at motion N. */
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "job_store.h"
#include "log.h"
#include "publish.h"
#include "store.h"

#define JOB_SPEC_MAX_BYTES ((size_t)1 << 30)

static int state_from_name(const char *name)
{
    for (int i = 0; i < 5; i++)
        if (name && !strcmp(name, fm_job_state_name((fm_job_state)i))) return i;
    return -1;
}

static fm_status write_json(const char *dir, const char *name, json_t *value, fm_error *err)
{
    char *text = json_dumps(value, JSON_COMPACT | JSON_REAL_PRECISION(17));
    if (!text) return fm_error_set(err, FM_ERR_LIMIT, "cannot serialize %s", name);
    fm_status st = fm_store_write_atomic(dir, name, text, strlen(text), err);
    free(text);
    return st;
}

void fm_job_store_write_result(job *j)
{
    json_t *status = fm_publish_status_json(j);
    pthread_mutex_lock(&j->lock);
    json_t *result = json_pack("{s:O, s:O?}", "status", status, "report", j->report);
    pthread_mutex_unlock(&j->lock);
    json_decref(status);
    fm_error err;
    if (write_json(j->dir, "result.json", result, &err) != FM_OK)
        fm_log(FM_LOG_ERROR, "job %s: cannot store its result: %s", j->id, err.message);
    json_decref(result);
}

/* The models beside spec.json (the runner's one writer of inline models,
 * crash-safe here). */
fm_status fm_job_store_write_models(fm_job_doc *doc, const char *dir, fm_error *err)
{
    return fm_job_doc_materialize(doc, dir, fm_store_write_atomic, err);
}

fm_status fm_job_store_create(const char *jobs_dir, const char *id, double created,
                              fm_job_doc *doc, fm_error *err)
{
    char dir[JOB_DIR_MAX];
    snprintf(dir, sizeof dir, "%.1200s/%.40s", jobs_dir, id);
    json_t *stored = json_pack("{s:s, s:f, s:O}", "id", id, "created", created, "job", doc->json);
    /* Durable before acknowledged: the folder, the models, the spec (temp,
     * fsync, rename, fsync folder; last, so that a folder without it was
     * never acknowledged) and the new folder's entry in jobs/. */
    fm_status st = mkdir(dir, 0750) == 0 ? FM_OK
                                         : fm_error_set(err, FM_ERR_IO, "cannot create %s: %s",
                                                        dir, strerror(errno));
    if (st == FM_OK) st = fm_job_store_write_models(doc, dir, err);
    if (st == FM_OK) st = write_json(dir, "spec.json", stored, err);
    if (st == FM_OK) st = fm_file_sync_dir(jobs_dir, err);
    json_decref(stored);
    if (st != FM_OK) fm_store_remove_dir(dir, NULL);
    return st;
}

void fm_job_store_save_snapshot(job *j, fm_stock *stock, long resume_from)
{
    char path[PATH_MAX], resume[64];
    snprintf(path, sizeof path, "%s/stock.vdb", j->dir);
    snprintf(resume, sizeof resume, "resume_from=%ld", resume_from);
    fm_error err;
    double t0 = fm_clock_monotonic_s();
    if (fm_stock_save(stock, path, resume, &err) != FM_OK)
        fm_log(FM_LOG_ERROR, "job %s: snapshot failed: %s", j->id, err.message);
    else
        fm_log(FM_LOG_DEBUG, "job %s: snapshot at motion %ld in %.2f s", j->id, resume_from,
               fm_clock_monotonic_s() - t0);
}

fm_stock *fm_job_store_load_snapshot(job *j, const fm_stock_options *opt, long *resume_from)
{
    char snap[PATH_MAX];
    snprintf(snap, sizeof snap, "%s/stock.vdb", j->dir);
    if (access(snap, R_OK) != 0) return NULL;
    fm_error err;
    fm_stock *stock = fm_stock_load_vdb(snap, opt, &err);
    long from = -1;
    if (stock && sscanf(fm_stock_resume_string(stock), "resume_from=%ld", &from) == 1 &&
        from >= 0) {
        *resume_from = from;
        return stock;
    }
    fm_stock_free(stock);
    fm_log(FM_LOG_WARN, "job %s: its snapshot cannot be resumed; starting over", j->id);
    return NULL;
}

fm_status fm_job_store_mark_deleted(const char *jobs_dir, job *j, fm_error *err)
{
    char gone[PATH_MAX];
    snprintf(gone, sizeof gone, "%s.deleted", j->dir);
    if (rename(j->dir, gone) != 0)
        return fm_error_set(err, FM_ERR_IO, "cannot delete job %s: %s", j->id, strerror(errno));
    fm_error ferr;
    fm_file_sync_dir(jobs_dir, &ferr);
    return FM_OK;
}

void fm_job_store_remove_deleted(job *j)
{
    char gone[PATH_MAX];
    snprintf(gone, sizeof gone, "%s.deleted", j->dir);
    fm_error err;
    fm_store_remove_dir(gone, &err);
}

/* 1 if a record was handed to the loader's adopt. */
static int load_job(const fm_job_store_loader *loader, const char *id)
{
    char dir[JOB_DIR_MAX], path[PATH_MAX];
    snprintf(dir, sizeof dir, "%.1200s/%.40s", loader->jobs_dir, id);
    snprintf(path, sizeof path, "%s/spec.json", dir);
    char *text;
    size_t size;
    fm_error err;
    if (fm_file_read(path, NULL, JOB_SPEC_MAX_BYTES, &text, &size, &err) != FM_OK) {
        /* A folder without its spec was never acknowledged: the daemon
         * died between mkdir and the rename of spec.json. */
        fm_log(FM_LOG_WARN, "job %s: no stored spec (%s); removing the unacknowledged folder", id,
               err.message);
        fm_store_remove_dir(dir, &err);
        return 0;
    }
    json_error_t jerr;
    json_t *stored = json_loadb(text, size, 0, &jerr);
    free(text);
    /* What the daemon stored it validated; read back with the rules of its
     * own documents (a live job's stock may be a configured file). */
    fm_job_doc *doc = NULL;
    fm_error derr;
    fm_error_clear(&derr);
    if (fm_job_doc_from_json(json_object_get(stored, "job"), &loader->rules, &doc, &derr) != FM_OK ||
        fm_job_store_write_models(doc, dir, &derr) != FM_OK) {
        fm_log(FM_LOG_ERROR, "job %s: its stored spec is unreadable (%s); left in place", id,
               derr.message);
        fm_job_doc_free(doc);
        json_decref(stored);
        return 0;
    }
    job *j = fm_job_record_new(id, loader->jobs_dir, doc,
                               json_number_value(json_object_get(stored, "created")),
                               loader->history_limit, loader->stopping);
    json_decref(stored);
    if (!j) return 0;
    snprintf(path, sizeof path, "%s/result.json", dir);
    if (fm_file_read(path, NULL, JOB_SPEC_MAX_BYTES, &text, &size, &err) == FM_OK) {
        json_t *result = json_loadb(text, size, 0, &jerr);
        free(text);
        json_t *status = json_object_get(result, "status");
        int state = state_from_name(json_string_value(json_object_get(status, "state")));
        if (state >= FM_JOB_DONE) {
            j->state = (fm_job_state)state;
            fm_publish_view_from_status(j, status);
            j->report = json_incref(json_object_get(result, "report"));
            if (json_is_null(j->report)) {
                json_decref(j->report);
                j->report = NULL;
            }
            fm_publish_event(j, "end", json_pack("{s:s}", "state", fm_job_state_name(j->state)));
            json_decref(result);
            loader->adopt(loader->user, j);
            return 1;
        }
        json_decref(result);
    }
    fm_log(FM_LOG_INFO, "job %s: unfinished; queued to resume", id);
    loader->adopt(loader->user, j);
    return 1;
}

void fm_job_store_load_all(const fm_job_store_loader *loader)
{
    DIR *d = opendir(loader->jobs_dir);
    if (!d) return;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        size_t n = strlen(e->d_name);
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/%s", loader->jobs_dir, e->d_name);
        if (n > 8 && !strcmp(e->d_name + n - 8, ".deleted")) {
            fm_error err;
            fm_store_remove_dir(path, &err); /* a delete the daemon did not finish */
            continue;
        }
        if (n >= 32) continue;
        fm_error err;
        size_t removed = 0;
        fm_stock_snapshot_cleanup(path, &removed, &err);
        load_job(loader, e->d_name);
    }
    closedir(d);
}

int fm_job_store_load_one(const fm_job_store_loader *loader, const char *id)
{
    char path[PATH_MAX];
    struct stat st;
    snprintf(path, sizeof path, "%s/%.40s", loader->jobs_dir, id);
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) return 0;
    fm_error err;
    size_t removed = 0;
    fm_stock_snapshot_cleanup(path, &removed, &err);
    return load_job(loader, id);
}
