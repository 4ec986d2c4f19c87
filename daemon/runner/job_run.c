/* job_run.c: a job from spec to result (DESIGN.md sec. 3): tools, a survey of
 * the program, the stock and design, the cutting pass (with the check in
 * it, or a live source), the design comparison, and the result's figures.
 * The concerns live in the files job_internal.h lists. */
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "job_internal.h"
#include "stock_spec.h"

void fm_job_check_default(fm_job_check *check)
{
    memset(check, 0, sizeof *check);
    fm_check_options_default(&check->options);
    check->voxel_mm = FM_JOB_CHECK_VOXEL;
}

void fm_job_spec_default(fm_job_spec *spec)
{
    memset(spec, 0, sizeof *spec);
    fm_stock_options_default(&spec->stock);
    spec->rapid_rate = 5000.0;
    spec->batch_diameters = 1.0;
}

void fm_job_result_release(fm_job_result *r)
{
    fm_stock_free(r->stock);
    r->stock = NULL;
    fm_design_free(r->design);
    r->design = NULL;
    fm_deviation_free(&r->deviation);
    r->has_deviation = 0;
    fm_check_free(r->check);
    r->check = NULL;
}

/* The stock's bounds before the first cut (mm, within a voxel). */
static void initial_bounds(fm_stock *stock, double lo[3], double hi[3])
{
    int32_t ilo[3], ihi[3];
    fm_error bounds_err;
    memset(lo, 0, 3 * sizeof *lo);
    memset(hi, 0, 3 * sizeof *hi);
    if (fm_stock_active_bounds(stock, ilo, ihi, &bounds_err) != FM_OK) return;
    double a[3] = {ilo[0], ilo[1], ilo[2]}, b[3] = {ihi[0], ihi[1], ihi[2]};
    fm_stock_index_to_world(stock, a, lo);
    fm_stock_index_to_world(stock, b, hi);
    /* Active voxels reach a band beyond the surface on either side. */
    double band = fm_stock_band_voxels(stock) * fm_stock_voxel_size(stock);
    for (int k = 0; k < 3; k++) {
        lo[k] += band;
        hi[k] -= band;
    }
}

static int dynamics_given(const fm_job_spec *spec)
{
    return spec->dynamics && spec->dynamics->given;
}

/* The survey: the whole program is checked before anything is cut, its
 * length gives the progress its denominator, and its motions are kept for
 * the cut and the blame (the one interpretation). */
static fm_status survey(const fm_job_spec *spec, const job_tools *tools, job_survey *sv,
                        fm_job_result *result, fm_error *err)
{
    sv->stop.line = spec->stop_at_line;
    if (spec->program_kind == FM_PROGRAM_LIVE) return FM_OK;
    sv->log = spec->motion_log ? job_motions_open_log(spec->motion_log, err)
                               : job_motions_new(JOB_MOTIONS_MEMORY, NULL);
    if (!sv->log && spec->motion_log) return err && err->code ? err->code : FM_ERR_LIMIT;
    /* job_motions_new says nothing of its failure */
    if (!sv->log) return fm_error_set(err, FM_ERR_LIMIT, "out of memory keeping the program's motions");
    result->interpretations++;
    sv->stop_index = LONG_MAX;
    fm_cycle_times_init(&sv->times, FM_CYCLE_SUMMARY_BLOCKS);
    fm_error perr;
    if (dynamics_given(spec)) {
        sv->planner = fm_planner_new(spec->dynamics, job_survey_planned, sv, &perr);
        sv->plan_failed = !sv->planner;
    }
    fm_status st = job_run_program(spec, tools->use, job_survey_sink, sv, job_survey_probe, err);
    if (sv->planner) {
        if (fm_planner_finish(sv->planner, &sv->plan, &perr) != FM_OK) {
            sv->plan_failed = 1;
            job_motions_spoil(sv->log);
        }
        fm_planner_free(sv->planner);
        sv->planner = NULL;
    }
    fm_cycle_times_finish(&sv->times);
    /* a log that cannot serve the toolpath leaves no file to be read */
    if (spec->motion_log) job_motions_keep(sv->log, spec->motion_log, st == FM_OK);
    return st;
}

/* The cutting pass: the survey's motions replayed, or the program again
 * when they could not be kept or its probe reads the stock. */
static fm_status cut(job_cutter *c, const job_survey *sv, fm_job_result *result, fm_error *err)
{
    const fm_job_spec *spec = c->spec;
    if (spec->program_kind == FM_PROGRAM_LIVE) return job_run_live(c);
    if (job_follow_wanted(spec, sv)) return job_follow_replay(c, sv->log, err);
    if (job_motions_usable(sv->log) && !sv->probing)
        return fm_job_motions_replay(sv->log, spec->machine, job_cut_sink, c, err);
    result->interpretations++;
    return job_run_program(spec, c->tools->use, job_cut_sink, c, job_cut_probe, err);
}

/* Compare the stock with the design and blame its gouges. */
static fm_status compare(job_cutter *c, fm_design *design, fm_job_motions *log,
                         fm_job_result *result, fm_error *err)
{
    const double w0 = fm_clock_monotonic_s(), c0 = fm_clock_cpu_s();
    fm_status st = fm_stock_compare_design(c->stock, design, FM_JOB_MAX_REGIONS,
                                           &result->deviation, err);
    result->has_deviation = st == FM_OK;
    const double w1 = fm_clock_monotonic_s(), c1 = fm_clock_cpu_s();
    result->design_compare_wall_s = w1 - w0;
    result->design_compare_cpu_s = c1 - c0;
    if (st == FM_OK)
        st = job_blame_gouges(c->spec, c->tools, fm_stock_voxel_size(c->stock), log, result, err);
    result->design_blame_wall_s = fm_clock_monotonic_s() - w1;
    result->design_blame_cpu_s = fm_clock_cpu_s() - c1;
    return st;
}

/* The motions the cut replays carry the planned times (the survey's
 * planner gave them to the log): the progress, the stock's cut times and
 * the toolpath are in controller time. Not when the cut interprets the
 * program again (a parametric path, a G38 probe). */
static int timeline_planned(const fm_job_spec *spec, const job_survey *sv)
{
    return dynamics_given(spec) && !sv->plan_failed && !sv->probing && job_motions_usable(sv->log);
}

/* The figures of a finished job. */
static void fill_result(const job_cutter *c, const job_survey *sv, fm_job_result *result)
{
    fm_stock *stock = c->stock;
    const int live = c->spec->program_kind == FM_PROGRAM_LIVE;
    result->stock = stock;
    result->stopped = c->stopped;
    result->initial_volume_mm3 = fm_stock_initial_volume(stock);
    result->final_volume_mm3 = fm_stock_volume(stock);
    result->removed_volume_mm3 = fm_stock_removed_volume(stock);
    double area = 0;
    fm_error area_err;
    if (fm_stock_surface_area(stock, &area, &area_err) == FM_OK) result->surface_area_mm2 = area;
    result->has_thin = fm_stock_thin_material(stock, &result->thin, &area_err) == FM_OK;
    result->motions = live ? c->progress.motions_total : sv->motions;
    result->blocks = c->blocks;
    result->program_time_s = live ? c->progress.program_time_total : sv->time_total;
    result->cycle_time_planned = !live && dynamics_given(c->spec) && !sv->plan_failed && !sv->probing;
    result->times_planned = !live && c->progress.time_planned;
    result->cycle_time_s = result->cycle_time_planned ? sv->plan_end : result->program_time_s;
    /* the breakdown (planned, or feed-only without dynamics) */
    if (!live && !sv->plan_failed && !sv->times.failed &&
        (result->cycle_time_planned || !dynamics_given(c->spec))) {
        fm_cycle_times_summarize(&sv->times, &result->cycle_times);
        result->has_cycle_times = 1;
    }
    result->voxel_mm = fm_stock_voxel_size(stock);
    size_t n = fm_stock_tool_volumes(stock, result->tools,
                                     sizeof result->tools / sizeof result->tools[0]);
    result->tool_count = n < 64 ? n : 64;
    for (size_t i = 0; i < result->tool_count; i++) {
        const fm_tool_spec *ts = fm_tool_table_find(c->tools->use, result->tools[i].tool);
        if (!ts) continue;
        snprintf(result->tool_info[i].description, sizeof result->tool_info[i].description, "%s",
                 ts->comment);
        result->tool_info[i].flute_count = ts->flute_count;
        result->tool_info[i].preset_count = ts->preset_count;
        memcpy(result->tool_info[i].presets, ts->presets, sizeof ts->presets);
    }
    result->top_block_count = fm_stock_blocks(stock, result->top_blocks, FM_JOB_TOP_BLOCKS);
    if (result->top_block_count > FM_JOB_TOP_BLOCKS) result->top_block_count = FM_JOB_TOP_BLOCKS;
    result->cut_stats = c->stats;
    result->cuts = c->cuts;
    result->voxels_uncertain = c->stats.voxels_uncertain;
    result->uncertain_max_mm = c->stats.uncertain_max_mm;
    result->uncertain_line = c->progress.uncertain_line;
    result->stopped_at_line = c->stopped_at_line ? c->spec->stop_at_line : 0;
    result->no_tool_line = c->no_tool_line;
    result->no_tool_motions = c->no_tool_motions;
    result->design_wall_s =
        result->design_build_wall_s + result->design_compare_wall_s + result->design_blame_wall_s;
    result->design_cpu_s =
        result->design_build_cpu_s + result->design_compare_cpu_s + result->design_blame_cpu_s;
    result->peak_memory_bytes = fm_job_peak_rss();
}

fm_status fm_job_run(const fm_job_spec *spec, const fm_job_hooks *hooks, fm_job_result *result,
                     fm_error *err)
{
    memset(result, 0, sizeof *result);
    const double started = fm_clock_monotonic_s();
    job_tools tools;
    job_survey sv = {0};
    fm_stock *stock = spec->resume_stock; /* owned from here on, also on error */
    fm_design *design = NULL;
    job_cutter *c = NULL;
    fm_status st = job_tools_load(spec, &tools, err);
    if (st == FM_OK) st = survey(spec, &tools, &sv, result, err);
    if (st == FM_OK && !stock && !(stock = fm_job_make_stock(spec->stock_spec, &spec->stock, err)))
        st = err && err->code ? err->code : FM_ERR_INPUT;
    /* The design before any cut: its errors come at once, and progress
     * hooks can colour by deviation while the job runs. */
    if (st == FM_OK && spec->design_path) {
        const double w0 = fm_clock_monotonic_s(), c0 = fm_clock_cpu_s();
        if (!(design = job_make_design(spec, stock, err)))
            st = err && err->code ? err->code : FM_ERR_INPUT;
        result->design_build_wall_s = fm_clock_monotonic_s() - w0;
        result->design_build_cpu_s = fm_clock_cpu_s() - c0;
    }
    if (st == FM_OK && !(c = calloc(1, sizeof *c)))
        st = fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    if (st == FM_OK) {
        initial_bounds(stock, result->initial_lo, result->initial_hi);
        c->spec = spec;
        c->hooks = hooks;
        c->tools = &tools;
        c->stock = stock;
        c->err = err;
        c->started = fm_clock_monotonic_s();
        c->trimmed_at = c->started;
        c->progress.motions_total = sv.motions;
        c->progress.time_planned = timeline_planned(spec, &sv);
        c->progress.program_time_total = c->progress.time_planned ? sv.plan_end : sv.time_total;
        c->progress.feed_only_time_total = sv.time_total;
        c->progress.block = -1;
        c->progress.design = design;
        c->stop.line = spec->stop_at_line;
        if (hooks && hooks->on_stock) hooks->on_stock(hooks->user, stock);
        if (spec->check) st = job_check_setup(c, &sv, err);
        if (st == FM_OK) st = cut(c, &sv, result, err);
        if (st == FM_OK) st = c->status;
        if (st == FM_OK && !c->stopped && !c->stopped_at_line) st = job_flush_batch(c);
        /* the cuts' freed pages go back before the design and the final
         * measures allocate */
        job_release_free_memory();
        if (st == FM_OK && design && !c->stopped) st = compare(c, design, sv.log, result, err);
    }
    if (st == FM_OK) {
        if (c->check) {
            fm_check_finish(c->check);
            result->check = c->check;
            result->check_time_s = c->check_time;
            c->check = NULL;
        }
        fill_result(c, &sv, result);
        result->design = design;
        result->wall_time_s = fm_clock_monotonic_s() - started;
    } else {
        fm_deviation_free(&result->deviation);
        result->has_deviation = 0;
        fm_design_free(design);
        fm_stock_free(stock);
    }
    if (c) {
        job_check_free(c);
        free(c->lines_cut);
        free(c);
    }
    fm_job_motions_free(sv.log);
    fm_cycle_times_free(&sv.times);
    job_tools_free(&tools);
    return st;
}
