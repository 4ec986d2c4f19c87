/* check_pass.h: one collision-check pass (lib/check) over a program, shared
 * by `frepmill check`, `frepmill simulate --check` and the daemon (jobs and
 * POST /v1/check), so that every front end reports the same findings for
 * the same inputs. The pass runs the job runner at the check's own coarse
 * voxel and relates each motion to the stock in the before_motion hook. */
#ifndef FM_CHECK_PASS_H
#define FM_CHECK_PASS_H

#include "check/check.h"
#include "job.h"

/* The check's voxel and band: coarse, because the relations bound the
 * stock's distance from above instead of trusting the grid (docs/check.md). */
#define FM_CHECK_PASS_VOXEL 0.5
#define FM_CHECK_PASS_BAND 4
#define FM_CHECK_PASS_MAX_FIXTURES 64

typedef struct fm_check_pass_input {
    /* Program, stock and tools as for a simulation. The stock options'
     * voxel and band are replaced by check_voxel_mm and FM_CHECK_PASS_BAND;
     * resume_stock and skip_motions must be unset. */
    fm_job_spec spec;
    double check_voxel_mm;            /* 0: FM_CHECK_PASS_VOXEL */
    fm_check_options options;
    /* Fixture files: a HyperFun model (.hf) or a closed STL mesh (.stl). */
    const char *fixtures[FM_CHECK_PASS_MAX_FIXTURES];
    int fixture_count;
    /* Optional: asked before each motion; 0 stops the pass early (the
     * daemon's cancel and shutdown): fm_check_pass_run then fails with
     * FM_ERR_INTERNAL "the check was stopped" and no findings. */
    int (*keep_going)(void *user);
    void *keep_going_user;
} fm_check_pass_input;

void fm_check_pass_input_default(fm_check_pass_input *in);

/* Run the pass; on success *out holds the finished check (fm_check_free)
 * and, when result is not NULL, the coarse run's figures (its stock is
 * freed here). On error nothing is left allocated. */
fm_status fm_check_pass_run(const fm_check_pass_input *in, fm_check **out, fm_job_result *result,
                            fm_error *err);


#endif
