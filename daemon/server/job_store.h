/* job_store.h: the durable side of jobs (job_store.c): one folder per job
 * under jobs_dir with its spec, models, snapshot and result. A leaf under
 * the job table: it makes records from folders and hands them to the
 * table's adopt callback, and knows nothing of the table itself. */
#ifndef FM_DAEMON_JOB_STORE_H
#define FM_DAEMON_JOB_STORE_H

#include "job_record.h"

/* Make the job's folder jobs_dir/id and write its spec durably (temp file,
 * fsync, rename, fsync of the folder and of jobs_dir), with the document's
 * inline models beside it: after this the job survives a crash. On failure
 * nothing is left behind. */
fm_status fm_job_store_create(const char *jobs_dir, const char *id, double created,
                              fm_job_doc *doc, fm_error *err);
/* Write a document's inline models (stock, fixtures) into dir and point
 * its run spec at the files (also for POST /v1/check's private folder). */
fm_status fm_job_store_write_models(fm_job_doc *doc, const char *dir, fm_error *err);
/* The terminal record: state, last status, error and report (result.json). */
void fm_job_store_write_result(job *j);

/* How stored jobs are read back: from jobs_dir, with the rules of the
 * daemon's own documents, into records (fm_job_record_new's history_limit
 * and stopping) handed to adopt with their one reference. */
typedef struct fm_job_store_loader {
    const char *jobs_dir;
    fm_job_doc_rules rules;
    size_t history_limit;
    const atomic_int *stopping;
    void (*adopt)(void *user, job *j);
    void *user;
} fm_job_store_loader;
/* Read every job folder back at start (finished jobs with their results,
 * unfinished ones to be queued by the caller); drops unacknowledged and
 * half-deleted folders. */
void fm_job_store_load_all(const fm_job_store_loader *loader);
/* Read one job folder (a queue job that another daemon sharing the state
 * folder started): 1 if a record was handed to adopt. */
int fm_job_store_load_one(const fm_job_store_loader *loader, const char *id);

/* stock.vdb with "resume_from=N": every motion before N is in it. */
void fm_job_store_save_snapshot(job *j, fm_stock *stock, long resume_from);
/* The snapshot to resume from, with its N; NULL if none or unusable. */
fm_stock *fm_job_store_load_snapshot(job *j, const fm_stock_options *opt, long *resume_from);
/* Delete: the folder is renamed to ID.deleted first (one atomic step that
 * a restart honours; jobs_dir is synced), then removed by
 * fm_job_store_remove_deleted. */
fm_status fm_job_store_mark_deleted(const char *jobs_dir, job *j, fm_error *err);
void fm_job_store_remove_deleted(job *j);

#endif
