/* jobs_check.c: the collision check of a job's run spec, for jobs and for
 * POST /v1/check (jobs_check.h). */
#include "jobs_check.h"

#include <errno.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_store.h"
#include "runner/check_pass.h"
#include "runner/findings_json.h"
#include "runner/job_doc.h"
#include "store.h"

fm_status fm_jobs_check_run(const fm_job_spec *spec, size_t memory_budget,
                            int (*keep_going)(void *user), void *user,
                            fm_jobs_check_result *out, int *stopped, fm_error *err)
{
    memset(out, 0, sizeof *out);
    *stopped = 0;
    fm_check_pass_input *in = calloc(1, sizeof *in);
    if (!in) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    /* The pass's input from the run spec: options, machine, voxel and
     * fixtures as the document gave them. */
    fm_check_pass_input_default(in);
    in->spec = *spec;
    in->spec.check = NULL;
    in->check = *spec->check;
    in->keep_going = keep_going;
    in->keep_going_user = user;
    in->spec.stock.memory_budget = memory_budget;
    in->spec.stock.threads = 1; /* a request's thread; leave the cores to the jobs */
    fm_check *check = NULL;
    fm_status st = fm_check_pass_run(in, &check, NULL, err);
    free(in);
    if (st != FM_OK && keep_going && !keep_going(user)) {
        *stopped = 1;
        return FM_OK;
    }
    if (st != FM_OK) return st;
    out->findings = fm_findings_json_array(check);
    out->count = (int)fm_check_count(check);
    out->errors = (int)fm_check_count_severity(check, FM_CHECK_ERROR);
    out->warnings = (int)fm_check_count_severity(check, FM_CHECK_WARNING);
    out->first_line = out->count ? fm_check_get(check, 0)->line : 0;
    fm_check_free(check);
    return FM_OK;
}

static atomic_int sync_running;

fm_status fm_jobs_check_request(const char *state_dir, size_t job_memory_bytes,
                                const fm_job_doc_rules *rules, json_t *request, json_t **out,
                                fm_error *err)
{
    fm_job_doc *doc = NULL;
    fm_status st = fm_job_doc_from_json(request, rules, &doc, err);
    if (st != FM_OK) return st;
    size_t bytes = fm_job_doc_program_bytes(doc);
    if (bytes > FM_JOBS_CHECK_SYNC_MAX_PROGRAM) {
        st = fm_error_set_reason(err, FM_ERR_LIMIT, "check_too_large",
                                 "the program is %zu bytes; POST /v1/check answers programs up to "
                                 "%zu bytes at once. Submit it with POST /v1/jobs: the job's "
                                 "status carries the findings",
                                 bytes, FM_JOBS_CHECK_SYNC_MAX_PROGRAM);
        goto done;
    }
    if (!doc->spec.check) {
        st = fm_error_set_reason(err, FM_ERR_INPUT, "bad_value",
                                 "options.check is false: nothing to do");
        goto done;
    }
    if (atomic_fetch_add(&sync_running, 1) >= FM_JOBS_CHECK_SYNC_MAX_RUNNING) {
        atomic_fetch_sub(&sync_running, 1);
        st = fm_error_set_reason(err, FM_ERR_LIMIT, "busy",
                                 "%d checks are running; retry, or submit a job",
                                 FM_JOBS_CHECK_SYNC_MAX_RUNNING);
        goto done;
    }
    /* A private folder for the inline models (mkdtemp: mode 0700, a name
     * no other request can guess or share). */
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%.3000s/check-XXXXXX", state_dir);
    if (!mkdtemp(dir)) {
        atomic_fetch_sub(&sync_running, 1);
        st = fm_error_set_reason(err, FM_ERR_IO, "storage", "cannot create a temporary folder: %s",
                                 strerror(errno));
        goto done;
    }
    fm_jobs_check_result res;
    int stopped;
    size_t budget = job_memory_bytes;
    if (doc->memory_budget_mb > 0 && doc->memory_budget_mb * 1048576.0 < (double)budget)
        budget = (size_t)(doc->memory_budget_mb * 1048576.0);
    st = fm_job_store_write_models(doc, dir, err);
    if (st == FM_OK) st = fm_jobs_check_run(&doc->spec, budget, NULL, NULL, &res, &stopped, err);
    fm_store_remove_dir(dir, NULL);
    atomic_fetch_sub(&sync_running, 1);
    if (st == FM_OK)
        *out = json_pack("{s:o, s:i, s:i}", "findings", res.findings, "errors", res.errors,
                         "warnings", res.warnings);
done:
    fm_job_doc_free(doc);
    return st;
}
