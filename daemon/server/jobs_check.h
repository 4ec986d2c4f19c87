/* jobs_check.h: the collision check (lib/check) over a canonical job
 * (fm_http_job_parse): for every job before it is simulated, and for POST
 * /v1/check. Both run check_pass.c, the pass `frepmill check` runs, so the
 * findings are the CLI's for the same inputs. */
#ifndef FM_DAEMON_JOBS_CHECK_H
#define FM_DAEMON_JOBS_CHECK_H

#include <jansson.h>

#include "http/http_server.h"

/* The largest program (bytes of G-code or trajectory JSON) POST /v1/check
 * answers synchronously; larger programs go through POST /v1/jobs. */
#define FM_JOBS_CHECK_SYNC_MAX_PROGRAM ((size_t)256 << 10)
/* Synchronous checks running at once (each holds an HTTP thread and a
 * coarse grid). */
#define FM_JOBS_CHECK_SYNC_MAX_RUNNING 2

/* Validate options.check of a canonical job (absent, false or an object of
 * clearance, rapid_clearance, tolerance, max_ramp, voxel, machine): 0, or
 * the HTTP status with err filled. */
int fm_jobs_check_validate(json_t *spec, fm_http_error *err);
/* 1 unless options.check is false. */
int fm_jobs_check_enabled(json_t *spec);

typedef struct fm_jobs_check_result {
    json_t *findings;  /* array, as `frepmill check` prints it (new reference) */
    int count, errors, warnings;
    int first_line;    /* source line of the first finding, 0 if none */
} fm_jobs_check_result;

/* Run the check of spec. Inline stock and fixture models are written to
 * files in dir (the job's folder, or a private temporary folder) because
 * lib/check and the runner read models from files. memory_budget bounds the
 * coarse grid. On failure err has the fm_status code and where. */
fm_status fm_jobs_check_run(json_t *spec, const char *dir, size_t memory_budget,
                            fm_jobs_check_result *out, fm_error *err);
/* The same, stopped early (*stopped = 1, FM_OK, no findings) when
 * keep_going(user) returns 0 before a motion. */
fm_status fm_jobs_check_run_until(json_t *spec, const char *dir, size_t memory_budget,
                                  int (*keep_going)(void *user), void *user,
                                  fm_jobs_check_result *out, int *stopped, fm_error *err);

/* POST /v1/check: the same inputs as a job; {"findings": [...], "errors",
 * "warnings"} or an error status. state_dir holds the private temporary
 * folder. */
int fm_jobs_check_request(const char *state_dir, size_t memory_budget, json_t *request,
                          json_t **out, fm_http_error *err);

#endif
