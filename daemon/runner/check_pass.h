/* check_pass.h: a run of the collision check alone, for `frepmill check`
 * and the daemon's POST /v1/check: the job runner with spec.check, its
 * stock made at the check's own voxel and band so that the one grid serves
 * both (nothing finer is cut). Jobs and `frepmill simulate --check` run the
 * same check in their own pass (job.h), with the same findings. */
#ifndef FM_CHECK_PASS_H
#define FM_CHECK_PASS_H

#include "check/check.h"
#include "job.h"

#define FM_CHECK_PASS_VOXEL FM_JOB_CHECK_VOXEL
#define FM_CHECK_PASS_MAX_FIXTURES FM_JOB_MAX_FIXTURES

typedef struct fm_check_pass_input {
    /* Program, stock and tools as for a simulation; the stock options'
     * voxel and band are the check's. resume_stock and skip_motions must
     * be unset. */
    fm_job_spec spec;
    fm_job_check check;
    /* Optional: asked before each cut; 0 stops the pass early (the
     * daemon's cancel and shutdown): fm_check_pass_run then fails with
     * FM_ERR_INTERNAL "the check was stopped" and no findings. */
    int (*keep_going)(void *user);
    void *keep_going_user;
} fm_check_pass_input;

void fm_check_pass_input_default(fm_check_pass_input *in);

/* Run the pass; on success *out holds the finished check (fm_check_free)
 * and, when result is not NULL, the run's figures (its stock is freed
 * here). On error nothing is left allocated. */
fm_status fm_check_pass_run(const fm_check_pass_input *in, fm_check **out, fm_job_result *result,
                            fm_error *err);

#endif
