/* fuzz_traj.c: libFuzzer target for the trajectory front end: any input
 * must end in FM_OK or a clean error, never a crash, a hang or a leak; and
 * for accepted documents, poses must lie inside pose_bounds. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "toolpaths/traj/traj.h"

static int check_sink(void *user, const fm_motion *m)
{
    long *n = user;
    (*n)++;
    if (m->t1 < m->t0) __builtin_trap();
    if (m->kind != FM_MOTION_PARAM) return 0;
    const fm_path *p = m->path;
    for (int k = 0; k < 4; k++) {
        double ta = m->t0 + (m->t1 - m->t0) * k / 4, tb = m->t0 + (m->t1 - m->t0) * (k + 1) / 4;
        double lo[3], hi[3], alo[3], ahi[3];
        p->pose_bounds(p->ctx, ta, tb, lo, hi, alo, ahi);
        for (int j = 0; j <= 4; j++) {
            double pos[3], ax[3];
            p->pose(p->ctx, ta + (tb - ta) * j / 4, pos, ax);
            for (int i = 0; i < 3; i++) {
                /* NaN may hide between samples (only infinities are proven
                 * absent); a value outside the bounds is a soundness bug. */
                if (!isnan(pos[i]) && (pos[i] < lo[i] || pos[i] > hi[i])) __builtin_trap();
                if (!isnan(ax[i]) && (ax[i] < alo[i] || ax[i] > ahi[i])) __builtin_trap();
            }
        }
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fm_traj_options opt;
    fm_traj_options_default(&opt);
    /* keep each run short; the limits themselves are what we test */
    opt.max_document_bytes = 1 << 16;
    opt.max_segments = 64;
    opt.max_expression_bytes = 512;
    opt.max_expression_nodes = 2000;
    opt.max_total_nodes = 20000;
    opt.samples = 100;
    long n = 0;
    fm_error err;
    fm_traj_run_string((const char *)data, size, "fuzz", &opt, check_sink, &n, NULL, &err);
    return 0;
}
