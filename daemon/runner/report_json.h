/* report_json.h: a job's result as the JSON report that `frepmill simulate
 * --report` writes and the daemon serves at /v1/jobs/{id}/report
 * (docs/simulate.md describes every field). */
#ifndef FM_REPORT_JSON_H
#define FM_REPORT_JSON_H

#include <jansson.h>

#include "job.h"

/* A new JSON object (the caller owns the reference); with the check's
 * "findings" when the job ran one. */
json_t *fm_job_report_json(const fm_job_result *result);

#endif
