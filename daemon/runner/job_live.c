/* job_live.c: live jobs: motions from a controller's positions (the
 * daemon's live mode) through the same cut as a program's. */
#include <string.h>

#include "job_internal.h"

/* Live jobs: motions from the source until it ends, through the same cut
 * as a program's. Whenever no motion is waiting, what is held is cut and
 * reported (idle), so the stock follows the machine; a position that cuts
 * nothing is reported too, so the status follows it. */
fm_status job_run_live(job_cutter *c)
{
    const fm_job_motion_source *src = c->spec->source;
    if (!src || !src->next) return fm_error_set(c->err, FM_ERR_INPUT, "a live job has no source");
    for (;;) {
        fm_motion m;
        int more = 0;
        memset(&m, 0, sizeof m);
        int r = src->next(src->user, &m, &more);
        if (r < 0) c->stopped = 1;
        if (r <= 0) return FM_OK;
        c->progress.motions_total = m.index + 1;
        if (m.t1 > c->progress.program_time_total) c->progress.program_time_total = m.t1;
        if (job_cut_sink(c, &m)) return c->status;
        if (more) continue;
        c->progress.idle = 1;
        fm_status st = job_flush_batch(c);
        if (st == FM_OK && !c->stopped && m.index >= c->spec->skip_motions &&
            c->progress.resume_from <= m.index)
            job_report(c, &m);
        c->progress.idle = 0;
        if (st != FM_OK) return st;
        if (c->stopped) return FM_OK;
    }
}
