/* job_cut.c: the cut loop: the survey pass that measures the program, and
 * the cutting pass that batches consecutive motions of one tool, subtracts
 * their swept volume from the stock, relates each motion to the check and
 * reports progress. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_internal.h"
#include "probe.h"
#include "sweep/sweep.h"

static void grow_box(job_survey *s, const double lo[3], const double hi[3])
{
    for (int a = 0; a < 3; a++) {
        if (!s->any_tip || lo[a] < s->tip_lo[a]) s->tip_lo[a] = lo[a];
        if (!s->any_tip || hi[a] > s->tip_hi[a]) s->tip_hi[a] = hi[a];
    }
    s->any_tip = 1;
}

int job_survey_sink(void *user, const fm_motion *m)
{
    job_survey *s = user;
    /* past a stop the program is still checked, but not counted */
    int past = s->stop.line > 0 && (s->stopped || (s->stopped = job_stop_before(&s->stop, m)));
    if (past && m->index < s->stop_index) s->stop_index = m->index;
    /* all of them into the log (the cut stops itself), through the planner
     * when the machine has dynamics */
    if (s->planner && !s->plan_failed) {
        fm_error perr;
        if (fm_planner_push(s->planner, m, &perr) != FM_OK) {
            /* the motions it still holds cannot reach the log */
            s->plan_failed = 1;
            job_motions_spoil(s->log);
        }
    } else {
        job_motions_add(s->log, m);
        if (!s->planner && !past) {
            /* no dynamics: the breakdown of the feed-only times */
            fm_plan_motion pm = {.motion = *m, .feed_t0 = m->t0, .feed_t1 = m->t1};
            fm_cycle_times_add(&s->times, &pm);
        }
    }
    if (past) return 0;
    s->motions++;
    if (m->t1 > s->time_total) s->time_total = m->t1;
    if (m->line > s->max_line) s->max_line = m->line;
    /* where the tip goes: both ends, an arc's whole circle, a path's bounds */
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = fmin(m->start[a], m->end[a]) + m->tip_offset[a];
        hi[a] = fmax(m->start[a], m->end[a]) + m->tip_offset[a];
    }
    if (m->kind == FM_MOTION_ARC) {
        double r2 = 0;
        for (int a = 0; a < 3; a++)
            if (a != m->plane_axis) r2 += (m->start[a] - m->center[a]) * (m->start[a] - m->center[a]);
        double r = sqrt(r2);
        double e2 = 0;
        for (int a = 0; a < 3; a++)
            if (a != m->plane_axis) e2 += (m->end[a] - m->center[a]) * (m->end[a] - m->center[a]);
        r = fmax(r, sqrt(e2));
        for (int a = 0; a < 3; a++)
            if (a != m->plane_axis) {
                lo[a] = fmin(lo[a], m->center[a] + m->tip_offset[a] - r);
                hi[a] = fmax(hi[a], m->center[a] + m->tip_offset[a] + r);
            }
    } else if (m->kind == FM_MOTION_PARAM && m->path && m->path->pose_bounds) {
        double plo[3], phi[3], alo[3], ahi[3];
        m->path->pose_bounds(m->path->ctx, m->t0, m->t1, plo, phi, alo, ahi);
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], plo[a] + m->tip_offset[a]);
            hi[a] = fmax(hi[a], phi[a] + m->tip_offset[a]);
        }
    }
    grow_box(s, lo, hi);
    return 0;
}

int job_survey_planned(void *user, const fm_plan_motion *pm)
{
    job_survey *s = user;
    job_motions_add(s->log, &pm->motion);
    if (pm->motion.index < s->stop_index) {
        fm_cycle_times_add(&s->times, pm);
        s->plan_end = pm->motion.t1;
    }
    return 0;
}

fm_status job_survey_probe(void *user, const fm_motion *move, int toward, int *tripped,
                           double *fraction, int *at_start, fm_error *err)
{
    (void)move, (void)toward, (void)err;
    ((job_survey *)user)->probing = 1;
    *tripped = 1;
    *fraction = 1;
    *at_start = 0;
    return FM_OK;
}

double fm_job_motion_length(const fm_motion *m)
{
    double d2 = 0;
    for (int a = 0; a < 3; a++) d2 += (m->end[a] - m->start[a]) * (m->end[a] - m->start[a]);
    double chord = sqrt(d2);
    if (m->kind == FM_MOTION_ARC) {
        /* An arc is at most its circle's circumference per turn plus the
         * axial travel; an upper bound suffices for batching. */
        double r2 = 0;
        for (int a = 0; a < 3; a++)
            if (a != m->plane_axis) r2 += (m->start[a] - m->center[a]) * (m->start[a] - m->center[a]);
        int turns = m->turns < 0 ? -m->turns : m->turns;
        return chord + 2 * FM_PI * sqrt(r2) * (turns > 0 ? turns : 1);
    }
    return chord;
}

static void mark_line(job_cutter *c, int line)
{
    if (line <= 0) return;
    size_t byte = (size_t)line / 8;
    if (byte >= c->lines_cap) {
        size_t cap = c->lines_cap ? c->lines_cap : 1024;
        while (cap <= byte) cap *= 2;
        unsigned char *p = realloc(c->lines_cut, cap);
        if (!p) return; /* the count is a report figure; losing it is not worth failing */
        memset(p + c->lines_cap, 0, cap - c->lines_cap);
        c->lines_cut = p;
        c->lines_cap = cap;
    }
    unsigned char bit = (unsigned char)(1u << (line % 8));
    if (!(c->lines_cut[byte] & bit)) {
        c->lines_cut[byte] |= bit;
        c->blocks++;
    }
}

fm_status job_flush_batch(job_cutter *c)
{
    if (c->batch_count == 0) return FM_OK;
    const fm_motion *first = &c->batch[0], *last = &c->batch[c->batch_count - 1];
    fm_field field;
    fm_sweep_options sweep_opt = {.max_evaluations = c->spec->sweep_evaluations};
    fm_status st = fm_sweep_field_many_ex(&field, c->batch, c->batch_count, &c->batch_tool->flutes,
                                          &sweep_opt, c->err);
    if (st == FM_OK) {
        fm_stock_cut cut = {.tool = c->batch_tool->spec.number,
                            .block = first->line,
                            .t0 = first->t0,
                            .t1 = last->t1};
        fm_stock_cut_stats cs;
        st = fm_stock_subtract(c->stock, &field, &cut, &cs, c->err);
        if (st == FM_OK && c->check_twin) st = fm_stock_subtract(c->check_grid, &field, &cut, NULL, c->err);
        fm_field_release(&field);
        if (st == FM_OK && c->check) fm_check_stock_cut(c->check);
        if (st == FM_OK) {
            c->stats.removed_mm3 += cs.removed_mm3;
            c->stats.intervals += cs.intervals;
            c->stats.leaves_evaluated += cs.leaves_evaluated;
            c->stats.voxels_evaluated += cs.voxels_evaluated;
            c->stats.interior_boxes += cs.interior_boxes;
            c->stats.leaves_changed += cs.leaves_changed;
            c->stats.voxels_changed += cs.voxels_changed;
            c->stats.time_classify_s += cs.time_classify_s;
            c->stats.time_voxels_s += cs.time_voxels_s;
            c->stats.time_apply_s += cs.time_apply_s;
            c->stats.time_leaves_cpu_s += cs.time_leaves_cpu_s;
            c->stats.time_field_cpu_s += cs.time_field_cpu_s;
            if (cs.voxels_uncertain > 0 && c->stats.voxels_uncertain == 0)
                c->progress.uncertain_line = first->line;
            c->stats.voxels_uncertain += cs.voxels_uncertain;
            if (cs.uncertain_max_mm > c->stats.uncertain_max_mm)
                c->stats.uncertain_max_mm = cs.uncertain_max_mm;
            c->progress.voxels_uncertain = c->stats.voxels_uncertain;
            c->cuts++;
            /* not in live mode: a move's latency is the figure there, and
             * its cuts free little */
            const double now = fm_clock_monotonic_s();
            if (c->spec->program_kind != FM_PROGRAM_LIVE && now - c->trimmed_at >= JOB_TRIM_INTERVAL_S) {
                job_release_free_memory();
                c->trimmed_at = now;
            }
        }
    }
    if (st != FM_OK) {
        if (c->err && c->err->line == 0) {
            c->err->line = first->line;
            const char *name = c->spec->program_path ? c->spec->program_path : c->spec->program_name;
            if (name && !c->err->file[0]) snprintf(c->err->file, sizeof c->err->file, "%s", name);
        }
        return st;
    }
    for (size_t i = 0; i < c->batch_count; i++) mark_line(c, c->batch[i].line);
    c->batch_count = 0;
    c->batch_length = 0;
    c->batch_tool = NULL;
    job_report(c, last);
    return FM_OK;
}

/* Tell the progress hook where the job is after motion last (nothing is
 * pending in the batch). */
void job_report(job_cutter *c, const fm_motion *last)
{
    fm_job_progress *p = &c->progress;
    /* A live job's count says what is cut (a program's counts what the
     * front end has given, for its progress bar). */
    if (c->spec->program_kind == FM_PROGRAM_LIVE) p->motions_done = last->index + 1;
    p->program_time = last->t1;
    p->line = last->line;
    p->block = last->block;
    p->tool = last->tool;
    for (int a = 0; a < 3; a++) p->position[a] = last->end[a] + last->tip_offset[a];
    /* The joints of the machine's rotary axes where the motion ends. */
    double joints[3];
    fm_motion_joints_at(last, last->t1, joints);
    for (int a = 0; a < 3; a++) p->rotary[a] = NAN;
    for (int i = 0; last->machine && i < last->machine->rotary_count; i++) {
        int letter = last->machine->rotary[i].letter;
        if (letter >= 0 && letter < 3) p->rotary[letter] = joints[letter];
    }
    /* A live move's speed is a nominal one (the cut takes it as cutting). */
    p->spindle_rpm = c->spec->program_kind == FM_PROGRAM_LIVE ? NAN
                     : last->spindle_rpm * (last->spindle_dir ? 1 : 0);
    p->removed_mm3 = fm_stock_removed_volume(c->stock);
    /* a motion whose blend arc is not cut yet is cut again on resume */
    p->resume_from = last->index + (c->batch_last_continues ? 0 : 1);
    p->elapsed_s = fm_clock_monotonic_s() - c->started;
    p->stock = c->stock;
    if (c->hooks && c->hooks->progress && c->hooks->progress(c->hooks->user, p)) c->stopped = 1;
}

/* Relate the motion to the check's grid (all earlier motions cut from it
 * or still pending in the check) and report the findings it opened. */
static fm_status check_motion(job_cutter *c, const fm_motion *m, const fm_tool *tool)
{
    double t0 = fm_clock_monotonic_s();
    fm_status st = fm_check_motion(c->check, m, tool, c->check_grid, c->err);
    c->check_time += fm_clock_monotonic_s() - t0;
    if (st != FM_OK) {
        if (c->err && c->err->line == 0) c->err->line = m->line;
        return st;
    }
    size_t n = fm_check_count(c->check);
    for (; c->findings_seen < n; c->findings_seen++)
        if (c->hooks && c->hooks->on_finding)
            c->hooks->on_finding(c->hooks->user, c->check, c->findings_seen);
    return FM_OK;
}

/* Resuming: a motion cut before the snapshot is still checked, and cut
 * from the check's own grid alone. */
static fm_status check_skipped(job_cutter *c, const fm_motion *m)
{
    const fm_tool *tool = job_tool_for(c->tools, m->tool);
    fm_status st = check_motion(c, m, tool);
    if (st != FM_OK || !tool || m->kind == FM_MOTION_DWELL) return st;
    fm_field field;
    st = fm_sweep_field(&field, m, &tool->flutes, c->err);
    if (st != FM_OK) return st;
    fm_stock_cut cut = {.tool = tool->spec.number, .block = m->line, .t0 = m->t0, .t1 = m->t1};
    st = fm_stock_subtract(c->check_grid, &field, &cut, NULL, c->err);
    fm_field_release(&field);
    if (st == FM_OK) fm_check_stock_cut(c->check);
    return st;
}

/* A feed motion with no tool in the spindle cuts nothing; where its tip
 * goes into the stock (as cut so far: the pending batch first) the job
 * warns (fm_job_result.no_tool_line), at the check's depth threshold. */
static fm_status no_tool_feed(job_cutter *c, const fm_motion *m)
{
    fm_status st = job_flush_batch(c);
    if (st != FM_OK || c->stopped) return st;
    fm_check_options defaults;
    fm_check_options_default(&defaults);
    double tol = c->spec->check ? c->spec->check->options.tolerance_mm : defaults.tolerance_mm;
    double u, depth;
    if (!fm_check_tip_in_stock(m, c->stock, 0.5 * tol, &u, &depth)) return FM_OK;
    if (!c->no_tool_motions) c->no_tool_line = m->line;
    c->no_tool_motions++;
    return FM_OK;
}

int job_cut_sink(void *user, const fm_motion *m)
{
    job_cutter *c = user;
    if (job_stop_before(&c->stop, m)) {
        /* what the lines before cut is in the stock, then the job ends */
        if ((c->status = job_flush_batch(c)) != FM_OK) return 1;
        c->stopped_at_line = 1;
        return 1;
    }
    if (!c->piece_blend) c->progress.motions_done++;
    if (c->hooks && c->hooks->on_motion) c->hooks->on_motion(c->hooks->user, m);
    if (m->index < c->spec->skip_motions) {
        /* cut before the snapshot we resume from */
        if (c->check && (c->status = check_skipped(c, m)) != FM_OK) return 1;
        return 0;
    }
    const fm_tool *tool = job_tool_for(c->tools, m->tool);
    if (m->kind == FM_MOTION_DWELL || !tool) {
        /* nothing cuts; the check still sees where the machine goes */
        if (!tool && m->kind != FM_MOTION_DWELL && m->kind != FM_MOTION_RAPID) {
            if ((c->status = no_tool_feed(c, m)) != FM_OK) return 1;
            if (c->stopped) return 1;
        }
        if (c->check && (c->status = check_motion(c, m, tool)) != FM_OK) return 1;
        return 0;
    }
    double length = fm_job_motion_length(m);
    double limit = c->spec->batch_diameters * tool->spec.diameter;
    int fits = c->spec->batch_diameters >= 0 && c->batch_count > 0 && c->batch_tool == tool &&
               c->batch_count < JOB_MAX_BATCH && c->batch_length + length <= limit;
    if (!fits && (c->status = job_flush_batch(c)) != FM_OK) return 1;
    if (c->stopped) return 1;
    /* The check sees the grid with every batch before this one cut; the
     * batch's earlier motions are still pending in it. */
    if (c->check && (c->status = check_motion(c, m, tool)) != FM_OK) return 1;
    c->batch[c->batch_count++] = *m;
    c->batch_last_continues = c->piece_continues;
    c->batch_tool = tool;
    c->batch_length += length;
    /* A PARAM motion's path is valid only while the front end runs this
     * callback, so such motions are cut at once. */
    if (m->kind == FM_MOTION_PARAM || c->spec->batch_diameters < 0) {
        if ((c->status = job_flush_batch(c)) != FM_OK) return 1;
        if (c->stopped) return 1;
    }
    return 0;
}

/* G38.x: the stock as cut so far stops the probe (probe.c), so pending
 * cuts go in first; so do the check's fixtures when the job has a check. */
fm_status job_cut_probe(void *user, const fm_motion *move, int toward, int *tripped,
                           double *fraction, int *at_start, fm_error *err)
{
    job_cutter *c = user;
    fm_status st = job_flush_batch(c);
    if (st != FM_OK) return st;
    double a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = move->start[k] + move->tip_offset[k];
        b[k] = move->end[k] + move->tip_offset[k];
    }
    return fm_runner_probe(c->stock, c->check, job_tool_for(c->tools, move->tool), a, b, toward,
                           tripped, fraction, at_start, err);
}
