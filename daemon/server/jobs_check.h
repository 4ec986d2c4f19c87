/* jobs_check.h: the collision check (lib/check) of a canonical job
 * (fm_http_job_parse): set up for a job's own pass (the runner checks as it
 * cuts, job.h), or run alone for POST /v1/check (check_pass.c, as
 * `frepmill check`). Both give the CLI's findings for the same inputs. */
#ifndef FM_DAEMON_JOBS_CHECK_H
#define FM_DAEMON_JOBS_CHECK_H

#include <jansson.h>

#include "http/http_server.h"
#include "runner/job.h"

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

/* The check of a canonical job as the runner takes it (job.h): options,
 * the check's voxel and the fixtures, which are written to files in dir
 * (the job's folder, or a private temporary folder) because lib/check
 * reads models from files; *rapid_rate gets the machine's rapid rate (0
 * when none). Free with fm_jobs_check_setup_free. */
typedef struct fm_jobs_check_setup fm_jobs_check_setup;
fm_status fm_jobs_check_prepare(json_t *spec, const char *dir, fm_jobs_check_setup **out,
                                fm_error *err);
const fm_job_check *fm_jobs_check_of(const fm_jobs_check_setup *setup);
void fm_jobs_check_setup_free(fm_jobs_check_setup *setup);

typedef struct fm_jobs_check_result {
    json_t *findings;  /* array, as `frepmill check` prints it (new reference) */
    int count, errors, warnings;
    int first_line;    /* source line of the first finding, 0 if none */
} fm_jobs_check_result;

/* The check alone (check_pass.h), for POST /v1/check. memory_budget bounds
 * the grid; dialect and subroutine_path are the server's G-code settings
 * (NULL: the defaults), as for jobs. On failure err has the fm_status code
 * and where. */
fm_status fm_jobs_check_run(json_t *spec, const char *dir, size_t memory_budget,
                            const char *dialect, const char *subroutine_path,
                            fm_jobs_check_result *out, fm_error *err);

/* POST /v1/check: the same inputs as a job; {"findings": [...], "errors",
 * "warnings"} or an error status. state_dir holds the private temporary
 * folder. */
int fm_jobs_check_request(const char *state_dir, size_t memory_budget, const char *dialect,
                          const char *subroutine_path, json_t *request,
                          json_t **out, fm_http_error *err);

#endif
