/* check_pass.c: the collision-check pass shared by the CLI and the daemon
 * (check_pass.h). */
#include "check_pass.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>

typedef struct check_run {
    fm_check *check;
    fm_status status;
    fm_error err;
    const fm_check_pass_input *in;
    int stopped;
} check_run;

static int before_motion(void *user, const fm_motion *m, const fm_tool *tool, fm_stock *stock)
{
    check_run *r = user;
    if (r->in->keep_going && !r->in->keep_going(r->in->keep_going_user)) {
        r->stopped = 1;
        return 1;
    }
    r->status = fm_check_motion(r->check, m, tool, stock, &r->err);
    return r->status != FM_OK;
}

/* "box:X0,Y0,Z0,X1,Y1,Z1" gives the check the exact initial stock. */
static int parse_box(const char *spec, double lo[3], double hi[3])
{
    double v[6];
    if (!spec || strncmp(spec, "box:", 4)) return 0;
    if (sscanf(spec + 4, "%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5]) != 6)
        return 0;
    for (int a = 0; a < 3; a++) {
        lo[a] = v[a];
        hi[a] = v[a + 3];
    }
    return 1;
}

void fm_check_pass_input_default(fm_check_pass_input *in)
{
    memset(in, 0, sizeof *in);
    fm_job_spec_default(&in->spec);
    in->check_voxel_mm = FM_CHECK_PASS_VOXEL;
    fm_check_options_default(&in->options);
}

fm_status fm_check_pass_run(const fm_check_pass_input *in, fm_check **out, fm_job_result *result,
                            fm_error *err)
{
    *out = NULL;
    if (in->fixture_count < 0 || in->fixture_count > FM_CHECK_PASS_MAX_FIXTURES)
        return fm_error_set(err, FM_ERR_INPUT, "at most %d fixtures", FM_CHECK_PASS_MAX_FIXTURES);
    fm_job_spec spec = in->spec;
    spec.stock.voxel_mm = in->check_voxel_mm > 0 ? in->check_voxel_mm : FM_CHECK_PASS_VOXEL;
    spec.stock.band_voxels = FM_CHECK_PASS_BAND;
    spec.resume_stock = NULL;
    spec.skip_motions = 0;

    check_run run = {0};
    run.in = in;
    run.check = fm_check_new(&in->options, err);
    if (!run.check) return err ? err->code : FM_ERR_INPUT;
    double lo[3], hi[3];
    if (parse_box(spec.stock_spec, lo, hi)) fm_check_set_initial_box(run.check, lo, hi);
    for (int i = 0; i < in->fixture_count; i++) {
        const char *f = in->fixtures[i];
        fm_status st = fm_path_has_extension(f, ".hf")    ? fm_check_add_fixture_hf(run.check, f, NULL, err)
                       : fm_path_has_extension(f, ".stl") ? fm_check_add_fixture_stl(run.check, f,
                                                                             spec.stock.voxel_mm, err)
                                                  : fm_error_set(err, FM_ERR_INPUT,
                                                                 "fixture %s: give a .hf model or "
                                                                 "an .stl mesh",
                                                                 f);
        if (st != FM_OK) {
            fm_check_free(run.check);
            return st;
        }
    }

    fm_job_hooks hooks = {.user = &run, .before_motion = before_motion};
    fm_job_result res;
    fm_status st = fm_job_run(&spec, &hooks, &res, err);
    if (st == FM_OK) {
        fm_stock_free(res.stock);
        res.stock = NULL;
        if (run.status != FM_OK) {
            st = run.status;
            if (err) *err = run.err;
        }
    }
    if (st != FM_OK) {
        fm_check_free(run.check);
        return st;
    }
    fm_check_finish(run.check);
    if (run.stopped) {
        /* Partial findings are not a check's answer. */
        fm_check_free(run.check);
        return fm_error_set(err, FM_ERR_INTERNAL, "the check was stopped");
    }
    if (result) *result = res;
    *out = run.check;
    return FM_OK;
}
