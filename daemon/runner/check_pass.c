/* check_pass.c: the collision check alone (check_pass.h). */
#include "check_pass.h"

#include <string.h>

typedef struct pass_run {
    const fm_check_pass_input *in;
    int stopped;
} pass_run;

static int keep_going(void *user, const fm_job_progress *progress)
{
    (void)progress;
    pass_run *r = user;
    if (r->in->keep_going && !r->in->keep_going(r->in->keep_going_user)) {
        r->stopped = 1;
        return 1;
    }
    return 0;
}

void fm_check_pass_input_default(fm_check_pass_input *in)
{
    memset(in, 0, sizeof *in);
    fm_job_spec_default(&in->spec);
    fm_job_check_default(&in->check);
}

fm_status fm_check_pass_run(const fm_check_pass_input *in, fm_check **out, fm_job_result *result,
                            fm_error *err)
{
    *out = NULL;
    if (in->check.fixture_count < 0 || in->check.fixture_count > FM_JOB_MAX_FIXTURES)
        return fm_error_set(err, FM_ERR_INPUT, "at most %d fixtures", FM_JOB_MAX_FIXTURES);
    fm_job_spec spec = in->spec;
    double voxel = in->check.voxel_mm > 0 ? in->check.voxel_mm : FM_JOB_CHECK_VOXEL;
    spec.stock.voxel_mm = voxel;
    /* beyond the stock's limit the runner explains what is too large */
    int band = fm_check_band_voxels(&in->check.options, voxel);
    spec.stock.band_voxels = band < 32 ? band : 32;
    spec.resume_stock = NULL;
    spec.skip_motions = 0;
    spec.check = &in->check;
    spec.design_path = NULL; /* the simulation compares, not the check */

    pass_run run = {in, 0};
    fm_job_hooks hooks = {.user = &run, .progress = keep_going};
    fm_job_result res;
    fm_status st = fm_job_run(&spec, &hooks, &res, err);
    if (st != FM_OK) return st;
    fm_stock_free(res.stock);
    res.stock = NULL;
    if (run.stopped) {
        /* Partial findings are not a check's answer. */
        fm_check_free(res.check);
        return fm_error_set(err, FM_ERR_INTERNAL, "the check was stopped");
    }
    *out = res.check;
    res.check = NULL;
    if (result) *result = res;
    return FM_OK;
}
