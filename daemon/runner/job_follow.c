/* job_follow.c: the cut along the path the machine really takes
 * (docs/plan.md, "Where the tool goes"): with the machine's dynamics the
 * survey's motions go through the planner again, and its blend arcs
 * (toolpaths/plan's fm_plan_path) are cut instead of the programmed
 * corners. */
#include "job_internal.h"

typedef struct job_follow {
    job_cutter *c;
    fm_planner *planner;
    fm_plan_path *path;
    int halted; /* a push failed: the cut stopped it, or the planner did */
    fm_error perr;
} job_follow;

int job_follow_wanted(const fm_job_spec *spec, const job_survey *sv)
{
    return spec->program_kind != FM_PROGRAM_LIVE && spec->dynamics && spec->dynamics->given &&
           !spec->dynamics->programmed_path && !sv->plan_failed && !sv->probing &&
           job_motions_usable(sv->log);
}

/* A piece of the path into the cut: a blend arc is no motion of its own
 * for the progress, and a motion whose arc is still to come is not done
 * for a resume. */
static int follow_piece(void *user, const fm_motion *m, int blend, int continues)
{
    job_cutter *c = user;
    c->piece_blend = blend;
    c->piece_continues = continues;
    int stop = job_cut_sink(c, m);
    c->piece_blend = c->piece_continues = 0;
    return stop;
}

static int follow_motion(void *user, const fm_motion *m)
{
    job_follow *f = user;
    if (fm_planner_push(f->planner, m, &f->perr) != FM_OK) f->halted = 1;
    return f->halted;
}

fm_status job_follow_replay(job_cutter *c, fm_job_motions *log, fm_error *err)
{
    job_follow f = {.c = c};
    fm_error_clear(&f.perr);
    fm_plan_path_options opt;
    fm_plan_path_options_default(&opt);
    f.path = fm_plan_path_new(&opt, follow_piece, c, err);
    if (f.path) f.planner = fm_planner_new(c->spec->dynamics, fm_plan_path_push, f.path, err);
    fm_status st = f.planner ? FM_OK : err && err->code ? err->code : FM_ERR_LIMIT;
    if (st == FM_OK) st = fm_job_motions_replay(log, c->spec->machine, follow_motion, &f, err);
    if (st == FM_OK && !f.halted) {
        if (fm_planner_finish(f.planner, NULL, &f.perr) != FM_OK)
            f.halted = 1;
        else if (fm_plan_path_finish(f.path))
            f.halted = 1;
    }
    /* a halt the cut did not ask for is the planner's: the survey planned
     * the same motions, so it is not expected */
    if (st == FM_OK && f.halted && !c->stopped && !c->stopped_at_line && c->status == FM_OK)
        st = fm_error_set(err, FM_ERR_INTERNAL, "the planner stopped the cut along the blends: %s",
                          f.perr.message);
    fm_planner_free(f.planner);
    fm_plan_path_free(f.path);
    return st;
}
