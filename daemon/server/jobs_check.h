/* jobs_check.h: POST /v1/check, the collision check (lib/check) of a job
 * document's run spec (spec->check: options, machine, voxel, fixtures) run
 * alone: check_pass.c, the pass `frepmill check` runs. Jobs run the same
 * check in their own pass (queue.c, job.h), so both give the CLI's
 * findings for the same inputs. */
#ifndef FM_DAEMON_JOBS_CHECK_H
#define FM_DAEMON_JOBS_CHECK_H

#include <jansson.h>

#include "runner/job.h"
#include "runner/job_doc.h"

/* The largest program (bytes of G-code or trajectory JSON) POST /v1/check
 * answers synchronously; larger programs go through POST /v1/jobs. */
#define FM_JOBS_CHECK_SYNC_MAX_PROGRAM ((size_t)256 << 10)
/* Synchronous checks running at once (each holds an HTTP thread and a
 * coarse grid). */
#define FM_JOBS_CHECK_SYNC_MAX_RUNNING 2

typedef struct fm_jobs_check_result {
    json_t *findings;  /* array, as `frepmill check` prints it (new reference) */
    int count, errors, warnings;
    int first_line;    /* source line of the first finding, 0 if none */
} fm_jobs_check_result;

/* Run the check of spec (spec->check set; its stock and fixture files
 * already written).
 * memory_budget bounds the check's grid. Stopped early (*stopped = 1, FM_OK,
 * no findings) when keep_going(user) returns 0 between cuts; keep_going
 * may be NULL. */
fm_status fm_jobs_check_run(const fm_job_spec *spec, size_t memory_budget,
                            int (*keep_going)(void *user), void *user,
                            fm_jobs_check_result *out, int *stopped, fm_error *err);

/* POST /v1/check: a job document (read with rules: the server's G-code
 * settings, as for jobs) checked at once; {"findings": [...], "errors",
 * "warnings"}. Its inline models go to a private temporary folder under
 * state_dir. Refusals: the document's own, "check_too_large" (the program
 * is over FM_JOBS_CHECK_SYNC_MAX_PROGRAM), "busy", and options.check false
 * (nothing to do). */
fm_status fm_jobs_check_request(const char *state_dir, size_t job_memory_bytes,
                                const fm_job_doc_rules *rules, json_t *request, json_t **out,
                                fm_error *err);

#endif
