/* job_record.c: a job's record made, referenced and freed (job_record.h),
 * and the grid budget that every part of the job manager uses. */
#include "job_record.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *fm_job_state_name(fm_job_state state)
{
    static const char *const names[] = {"queued", "running", "done", "failed", "cancelled"};
    return (unsigned)state < 5 ? names[state] : "unknown";
}

size_t fm_job_memory_budget(size_t job_memory_bytes, const fm_job_doc *doc)
{
    size_t budget = job_memory_bytes;
    double mb = doc->memory_budget_mb;
    if (mb > 0 && mb * 1048576.0 < (double)budget) budget = (size_t)(mb * 1048576.0);
    return budget;
}

job *fm_job_record_new(const char *id, const char *jobs_dir, fm_job_doc *doc, double created,
                       size_t history_limit, const atomic_int *stopping)
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
    atomic_init(&j->refs, 1);
    atomic_init(&j->deleted, 0);
    j->history_limit = history_limit;
    j->stopping = stopping;
    pthread_mutex_init(&j->lock, NULL);
    pthread_mutex_init(&j->load_lock, NULL);
    pthread_cond_init(&j->cond, NULL);
    j->next_event = 1;
    j->history_from_s = -1;
    j->view.block = -1;
    snprintf(j->view.id, sizeof j->view.id, "%s", id);
    return j;
}

void fm_job_record_free_chunks(job *j)
{
    /* the worker settles its encoder when the run ends (queue.c); never
     * free meshes it may still be reading */
    if (j->encoder_started) {
        pthread_join(j->encoder, NULL);
        j->encoder_started = 0;
    }
    for (size_t i = 0; i < j->chunk_count; i++) {
        fm_mesh_free(j->chunks[i].mesh);
        fm_mesh_chunk_cache_free(j->chunks[i].cache);
        for (size_t v = 0; v < j->chunks[i].version_count; v++) free(j->chunks[i].versions[v].drc);
        free(j->chunks[i].versions);
    }
    free(j->chunks);
    j->chunks = NULL;
    j->chunk_count = j->chunk_cap = 0;
    j->history_bytes = 0;
}

const fm_job_doc *fm_job_document(const job *j)
{
    return j->doc;
}

void fm_job_file_path(const job *j, const char *name, char *path, size_t size)
{
    snprintf(path, size, "%s/%s", j->dir, name);
}

void fm_job_ref(job *j)
{
    atomic_fetch_add(&j->refs, 1);
}

void fm_job_unref(job *j)
{
    if (!j || atomic_fetch_sub(&j->refs, 1) != 1) return;
    fm_job_record_free_chunks(j);
    for (int i = 0; i < JOB_EVENT_RING; i++) free(j->ring[i].data);
    fm_job_doc_free(j->doc);
    if (j->live && j->live_free) j->live_free(j->live);
    json_decref(j->error);
    json_decref(j->report);
    json_decref(j->findings);
    pthread_mutex_destroy(&j->lock);
    pthread_mutex_destroy(&j->load_lock);
    pthread_cond_destroy(&j->cond);
    free(j);
}
