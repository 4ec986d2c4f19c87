/* job.c: the simulation pipeline behind `frepmill simulate` and the
 * daemon's jobs. It loads the tools, makes the stock, interprets the
 * program twice (a first pass that validates it and measures its length
 * for progress, a second that cuts), turns each motion (or a short run of
 * consecutive motions of one tool) into a swept-volume field and subtracts
 * it from the stock. */
#include "job.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "frep/frep.h"
#include "probe.h"
#include "stock_spec.h"
#include "toolpaths/gcode/gcode.h"
#include "hf/hf.h"
#include "sweep/sweep.h"
#include "toolpaths/tooltable/tooltable.h"
#include "toolpaths/traj/traj.h"

#define JOB_MAX_BATCH 256

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

size_t fm_job_peak_rss(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return (size_t)ru.ru_maxrss * 1024u; /* Linux reports kilobytes */
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ------------------------------------------------------------- paths -- */

int fm_path_has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    if (n <= e) return 0;
    for (size_t i = 0; i < e; i++)
        if (tolower((unsigned char)path[n - e + i]) != tolower((unsigned char)ext[i])) return 0;
    return 1;
}

/* ------------------------------------------------------------ design -- */

static void release_design_model(void *ctx)
{
    fm_model_field_close(ctx);
    free(ctx);
}

static fm_design *make_design(const fm_job_spec *spec, const fm_stock *stock, fm_error *err)
{
    const char *path = spec->design_path;
    fm_design_options opt;
    fm_design_options_default(&opt);
    opt.tolerance_mm = spec->tolerance_mm;
    opt.threads = spec->stock.threads;
    /* the design shares the job's budget with the stock */
    const size_t budget = spec->stock.memory_budget, used = fm_stock_memory_bytes(stock);
    opt.memory_budget = budget > used + ((size_t)1 << 20) ? budget - used : (size_t)1 << 20;
    if (fm_path_has_extension(path, ".stl")) return fm_design_from_stl(stock, path, &opt, err);
    if (fm_path_has_extension(path, ".vdb")) return fm_design_load_vdb(stock, path, &opt, err);
    if (fm_path_has_extension(path, ".hf")) {
        /* the design evaluates the model when it compares: it owns it */
        fm_model_field *mf = malloc(sizeof *mf);
        if (!mf) {
            fm_error_set(err, FM_ERR_LIMIT, "out of memory for the design's model");
            return NULL;
        }
        const double h = fm_stock_voxel_size(stock);
        if (fm_model_field_open(path, h, h * fm_design_band_voxels(stock, spec->tolerance_mm),
                                "design", mf, err) != FM_OK) {
            free(mf);
            return NULL;
        }
        mf->field.release = release_design_model;
        return fm_design_from_field(stock, &mf->field, &opt, err);
    }
    fm_error_set(err, FM_ERR_INPUT, "design '%s' is not a .stl mesh, a .hf model or a .vdb snapshot",
                 path);
    return NULL;
}

static double process_cpu_s(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
           (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
}

/* ------------------------------------------------------------- tools -- */

/* A built tool, with the HyperFun model behind a custom cutter. */
typedef struct job_tool {
    fm_tool tool;
    fm_graph *graph;
    fm_tape *tape;
} job_tool;

typedef struct job_tools {
    fm_tool_table table; /* when loaded here */
    const fm_tool_table *use;
    job_tool *built;
    size_t count;
} job_tools;

static void free_tools(job_tools *t)
{
    for (size_t i = 0; i < t->count; i++) {
        if (t->built[i].tool.flutes.kind == FM_TOOL_PART_CUSTOM)
            fm_tool_custom_release(&t->built[i].tool.flutes.custom);
        fm_tape_free(t->built[i].tape);
        fm_graph_free(t->built[i].graph);
    }
    free(t->built);
    fm_tool_table_free(&t->table);
    memset(t, 0, sizeof *t);
}

/* The folder part of path (with its slash), or "" for a bare name. */
static void folder_of(const char *path, char *out, size_t size)
{
    const char *slash = path ? strrchr(path, '/') : NULL;
    size_t n = slash ? (size_t)(slash - path + 1) : 0;
    if (n >= size) n = 0;
    if (n) memcpy(out, path, n); /* path may be NULL: memcpy's arguments never may */
    out[n] = '\0';
}

static fm_status build_custom_tool(const fm_tool_spec *spec, const char *tools_path, job_tool *jt,
                                   fm_error *err)
{
    char file[1024];
    if (spec->hyperfun_file[0] == '/') {
        snprintf(file, sizeof file, "%s", spec->hyperfun_file);
    } else {
        char folder[512];
        folder_of(tools_path, folder, sizeof folder);
        snprintf(file, sizeof file, "%s%s", folder, spec->hyperfun_file);
    }
    jt->graph = fm_graph_new(0);
    if (!jt->graph) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    fm_hf_model model;
    fm_status st = fm_hf_compile_file(jt->graph, file, NULL, &model, err);
    if (st != FM_OK) return st;
    jt->tape = fm_tape_compile(jt->graph, model.root, err);
    if (!jt->tape) return err ? err->code : FM_ERR_INPUT;
    fm_tool_custom custom;
    st = fm_tool_custom_from_tape(jt->tape, spec->bound_radius, spec->flute_length, &custom, err);
    if (st != FM_OK) return st;
    st = fm_tool_build_custom(spec, &custom, &jt->tool, err);
    /* once in the tool, free_tools releases the table */
    if (st != FM_OK && jt->tool.flutes.custom.ctx != custom.ctx) fm_tool_custom_release(&custom);
    return st;
}

static fm_status load_tools(const fm_job_spec *spec, job_tools *t, fm_error *err)
{
    memset(t, 0, sizeof *t);
    if (spec->tools) {
        t->use = spec->tools;
    } else if (spec->tools_path) {
        fm_status st = fm_tooltable_load(spec->tools_path, &t->table, err);
        if (st != FM_OK) return st;
        t->use = &t->table;
    } else {
        return fm_error_set(err, FM_ERR_INPUT, "no tool table given (--tools TOOLS.json or .tbl)");
    }
    if (t->use->count == 0)
        return fm_error_set(err, FM_ERR_INPUT, "the tool table %s has no tools",
                            spec->tools_path ? spec->tools_path : "");
    t->built = calloc(t->use->count, sizeof *t->built);
    if (!t->built) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    t->count = t->use->count;
    for (size_t i = 0; i < t->count; i++) {
        const fm_tool_spec *ts = &t->use->tools[i];
        fm_status st = ts->shape == FM_TOOL_HYPERFUN
                           ? build_custom_tool(ts, spec->tools_path, &t->built[i], err)
                           : fm_tool_build(ts, &t->built[i].tool, err);
        if (st != FM_OK) {
            if (err && spec->tools_path && !err->file[0])
                snprintf(err->file, sizeof err->file, "%s", spec->tools_path);
            return st;
        }
    }
    return FM_OK;
}

/* The tool that cuts for a motion: the spindle's, or the table's only tool
 * when the program never loaded one (T0: many single-tool programs have no
 * M6). NULL: nothing cuts. */
static const fm_tool *tool_for(const job_tools *t, int number)
{
    for (size_t i = 0; i < t->count; i++)
        if (t->built[i].tool.spec.number == number) return &t->built[i].tool;
    if (number == 0 && t->count == 1) return &t->built[0].tool;
    return NULL;
}

/* ----------------------------------------------------------- program -- */

static fm_program_kind program_kind(const fm_job_spec *spec)
{
    if (spec->program_kind != FM_PROGRAM_AUTO) return spec->program_kind;
    const char *name = spec->program_path ? spec->program_path : spec->program_name;
    if (name && fm_path_has_extension(name, ".json")) return FM_PROGRAM_TRAJECTORY;
    return FM_PROGRAM_GCODE;
}

typedef fm_status (*job_probe_fn)(void *user, const fm_motion *move, int toward, int *tripped,
                                  double *fraction, int *at_start, fm_error *err);

static fm_status run_program(const fm_job_spec *spec, const fm_tool_table *tools,
                             fm_motion_sink sink, void *user, job_probe_fn probe, fm_error *err)
{
    if (!spec->program_path && !spec->program_text)
        return fm_error_set(err, FM_ERR_INPUT, "no program given");
    if (program_kind(spec) == FM_PROGRAM_TRAJECTORY) {
        fm_traj_options topt;
        fm_traj_options_default(&topt);
        topt.rapid_rate = spec->rapid_rate > 0 ? spec->rapid_rate : topt.rapid_rate;
        if (spec->program_path) return fm_traj_run_file(spec->program_path, &topt, sink, user, NULL, err);
        return fm_traj_run_string(spec->program_text, spec->program_length,
                                  spec->program_name ? spec->program_name : "trajectory", &topt,
                                  sink, user, NULL, err);
    }
    fm_gcode_options gopt;
    fm_gcode_options_default(&gopt);
    if (spec->rapid_rate > 0) gopt.rapid_rate = spec->rapid_rate;
    gopt.tools = tools;
    gopt.probe = probe;
    gopt.probe_user = user;
    if (spec->dialect && !fm_gcode_dialect_parse(spec->dialect, &gopt.dialect))
        return fm_error_set(err, FM_ERR_INPUT, "dialect '%s': expected linuxcnc or fanuc",
                            spec->dialect);
    gopt.subroutine_path = spec->subroutine_path;
    memcpy(gopt.reference_points, spec->reference_points, sizeof gopt.reference_points);
    gopt.calculator_input = spec->calculator_input;
    gopt.machine = spec->machine;
    if (spec->program_path)
        return fm_gcode_run_file(spec->program_path, &gopt, sink, user, NULL, err);
    return fm_gcode_run_string(spec->program_text, spec->program_length,
                               spec->program_name ? spec->program_name : "program", &gopt, sink,
                               user, NULL, err);
}

fm_status fm_job_interpret(const fm_job_spec *spec, fm_motion_sink sink, void *user,
                           fm_error *err)
{
    if (spec->tools) return run_program(spec, spec->tools, sink, user, NULL, err);
    fm_tool_table table;
    memset(&table, 0, sizeof table);
    fm_status st = spec->tools_path ? fm_tooltable_load(spec->tools_path, &table, err)
                                    : fm_error_set(err, FM_ERR_INPUT, "no tool table given");
    if (st == FM_OK) st = run_program(spec, &table, sink, user, NULL, err);
    fm_tool_table_free(&table);
    return st;
}

/* ---------------------------------------------------------- stop at -- */

/* spec.stop_at_line: has the program gone past LINE with this motion? */
typedef struct stop_rule {
    int line;  /* 0: never stop */
    int seen;  /* a motion of LINE went by */
} stop_rule;

static int stop_before(stop_rule *r, const fm_motion *m)
{
    if (r->line <= 0) return 0;
    if (m->line == r->line) {
        r->seen = 1;
        return 0;
    }
    return r->seen || m->line > r->line;
}

/* -------------------------------------------------------- first pass -- */

typedef struct survey {
    long motions;
    double time_total;
    int max_line;
    int any_tip;
    double tip_lo[3], tip_hi[3]; /* box of the tool tip over the program */
    stop_rule stop;
    int stopped;
} survey;

static void grow_box(survey *s, const double lo[3], const double hi[3])
{
    for (int a = 0; a < 3; a++) {
        if (!s->any_tip || lo[a] < s->tip_lo[a]) s->tip_lo[a] = lo[a];
        if (!s->any_tip || hi[a] > s->tip_hi[a]) s->tip_hi[a] = hi[a];
    }
    s->any_tip = 1;
}

static int survey_sink(void *user, const fm_motion *m)
{
    survey *s = user;
    /* past a stop the program is still checked, but not counted */
    if (s->stop.line > 0 && (s->stopped || (s->stopped = stop_before(&s->stop, m)))) return 0;
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

/* --------------------------------------------------------------- cut -- */

typedef struct cutter {
    const fm_job_spec *spec;
    const fm_job_hooks *hooks;
    job_tools *tools;
    fm_stock *stock;
    fm_error *err;
    fm_status status;
    int stopped;

    fm_motion batch[JOB_MAX_BATCH];
    size_t batch_count;
    double batch_length;
    const fm_tool *batch_tool;

    fm_job_progress progress;
    double started;
    stop_rule stop;
    int stopped_at_line;
    unsigned char *lines_cut; /* bitmap of source lines that cut */
    size_t lines_cap;
    long blocks;
    fm_stock_cut_stats stats; /* summed over cuts */
    long cuts;

    /* the collision check and its grid (c->stock itself, or a grid of its
     * own cut alongside) */
    fm_check *check;
    fm_stock *check_grid;
    int check_twin;
    size_t findings_seen;
    double check_time;
} cutter;

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
        return chord + 2 * 3.14159265358979323846 * sqrt(r2) * (turns > 0 ? turns : 1);
    }
    return chord;
}

static void mark_line(cutter *c, int line)
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

static void report(cutter *c, const fm_motion *last);

static fm_status flush_batch(cutter *c)
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
    report(c, last);
    return FM_OK;
}

/* Tell the progress hook where the job is after motion last (nothing is
 * pending in the batch). */
static void report(cutter *c, const fm_motion *last)
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
    p->removed_mm3 = fm_stock_removed_volume(c->stock);
    p->resume_from = last->index + 1;
    p->elapsed_s = now_s() - c->started;
    p->stock = c->stock;
    if (c->hooks && c->hooks->progress && c->hooks->progress(c->hooks->user, p)) c->stopped = 1;
}

/* Relate the motion to the check's grid (all earlier motions cut from it
 * or still pending in the check) and report the findings it opened. */
static fm_status check_motion(cutter *c, const fm_motion *m, const fm_tool *tool)
{
    double t0 = now_s();
    fm_status st = fm_check_motion(c->check, m, tool, c->check_grid, c->err);
    c->check_time += now_s() - t0;
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
static fm_status check_skipped(cutter *c, const fm_motion *m)
{
    const fm_tool *tool = tool_for(c->tools, m->tool);
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

static int cut_sink(void *user, const fm_motion *m)
{
    cutter *c = user;
    if (stop_before(&c->stop, m)) {
        /* what the lines before cut is in the stock, then the job ends */
        if ((c->status = flush_batch(c)) != FM_OK) return 1;
        c->stopped_at_line = 1;
        return 1;
    }
    c->progress.motions_done++;
    if (c->hooks && c->hooks->on_motion) c->hooks->on_motion(c->hooks->user, m);
    if (m->index < c->spec->skip_motions) {
        /* cut before the snapshot we resume from */
        if (c->check && (c->status = check_skipped(c, m)) != FM_OK) return 1;
        return 0;
    }
    const fm_tool *tool = tool_for(c->tools, m->tool);
    if (m->kind == FM_MOTION_DWELL || !tool) {
        /* nothing cuts; the check still sees where the machine goes */
        if (c->check && (c->status = check_motion(c, m, tool)) != FM_OK) return 1;
        return 0;
    }
    double length = fm_job_motion_length(m);
    double limit = c->spec->batch_diameters * tool->spec.diameter;
    int fits = c->spec->batch_diameters >= 0 && c->batch_count > 0 && c->batch_tool == tool &&
               c->batch_count < JOB_MAX_BATCH && c->batch_length + length <= limit;
    if (!fits && (c->status = flush_batch(c)) != FM_OK) return 1;
    if (c->stopped) return 1;
    /* The check sees the grid with every batch before this one cut; the
     * batch's earlier motions are still pending in it. */
    if (c->check && (c->status = check_motion(c, m, tool)) != FM_OK) return 1;
    c->batch[c->batch_count++] = *m;
    c->batch_tool = tool;
    c->batch_length += length;
    /* A PARAM motion's path is valid only while the front end runs this
     * callback, so such motions are cut at once. */
    if (m->kind == FM_MOTION_PARAM || c->spec->batch_diameters < 0) {
        if ((c->status = flush_batch(c)) != FM_OK) return 1;
        if (c->stopped) return 1;
    }
    return 0;
}

/* G38.x: the stock as cut so far stops the probe (probe.c), so pending
 * cuts go in first; so do the check's fixtures when the job has a check. */
static fm_status cut_probe(void *user, const fm_motion *move, int toward, int *tripped,
                           double *fraction, int *at_start, fm_error *err)
{
    cutter *c = user;
    fm_status st = flush_batch(c);
    if (st != FM_OK) return st;
    double a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = move->start[k] + move->tip_offset[k];
        b[k] = move->end[k] + move->tip_offset[k];
    }
    return fm_runner_probe(c->stock, c->check, tool_for(c->tools, move->tool), a, b, toward,
                           tripped, fraction, at_start, err);
}

/* ------------------------------------------------------------- check -- */

/* "box:X0,Y0,Z0,X1,Y1,Z1": the check gets the exact initial stock. */
static int box_of_spec(const char *spec, double lo[3], double hi[3])
{
    fm_stock_spec shape;
    if (!spec || fm_stock_spec_parse(spec, &shape, NULL) != FM_OK ||
        shape.shape != FM_STOCK_SHAPE_BOX)
        return 0;
    memcpy(lo, shape.lo, sizeof shape.lo);
    memcpy(hi, shape.hi, sizeof shape.hi);
    return 1;
}

/* The check, its grid and fixtures, for a job whose stock is made. */
static fm_status setup_check(cutter *c, const survey *sv, fm_error *err)
{
    const fm_job_check *jc = c->spec->check;
    double voxel = jc->voxel_mm > 0 ? jc->voxel_mm : FM_JOB_CHECK_VOXEL;
    int band = fm_check_band_voxels(&jc->options, voxel);
    if (band > 32)
        return fm_error_set(err, FM_ERR_INPUT,
                            "the check's clearances need a band of %d voxels of %g mm (at most "
                            "32): use a larger check voxel or smaller clearances",
                            band, voxel);
    c->check = fm_check_new(&jc->options, err);
    if (!c->check) return err ? err->code : FM_ERR_INPUT;
    double lo[3], hi[3];
    if (box_of_spec(c->spec->stock_spec, lo, hi)) fm_check_set_initial_box(c->check, lo, hi);
    if (sv->any_tip) {
        /* where any part of any tool can go: the tip's box grown by the
         * largest tool */
        double up = 0, out = 0;
        for (size_t i = 0; i < c->tools->count; i++) {
            const fm_tool *t = &c->tools->built[i].tool;
            const fm_tool_part *parts[3] = {&t->flutes, t->has_shank ? &t->shank : NULL,
                                            t->has_holder ? &t->holder : NULL};
            for (int k = 0; k < 3; k++)
                if (parts[k]) {
                    up = fmax(up, fmax(fabs(parts[k]->z_lo), fabs(parts[k]->z_hi)));
                    out = fmax(out, parts[k]->r_max);
                }
        }
        double reach = sqrt(up * up + out * out);
        for (int a = 0; a < 3; a++) {
            lo[a] = sv->tip_lo[a] - reach;
            hi[a] = sv->tip_hi[a] + reach;
        }
        fm_check_set_region(c->check, lo, hi);
    }
    for (int i = 0; i < jc->fixture_count; i++) {
        const char *f = jc->fixtures[i];
        fm_status st = fm_path_has_extension(f, ".hf")
                           ? fm_check_add_fixture_hf(c->check, f, NULL, voxel, err)
                       : fm_path_has_extension(f, ".stl")
                           ? fm_check_add_fixture_stl(c->check, f, voxel, err)
                           : fm_error_set(err, FM_ERR_INPUT,
                                          "fixture %s: give a .hf model or an .stl mesh", f);
        if (st != FM_OK) return st;
    }
    /* the machine's components: fixtures whose contacts are
     * machine_contact, on their link */
    for (int i = 0; i < jc->options.machine.component_count; i++) {
        fm_status st = fm_check_add_component(c->check, i, voxel, err);
        if (st != FM_OK) return st;
    }
    fm_stock_options own = c->spec->stock, defaults;
    fm_stock_options_default(&defaults);
    if (own.voxel_mm <= 0) own.voxel_mm = defaults.voxel_mm;
    if (own.band_voxels <= 0) own.band_voxels = defaults.band_voxels;
    if (!c->spec->resume_stock && fabs(own.voxel_mm - voxel) <= 1e-12 * voxel &&
        own.band_voxels == band) {
        c->check_grid = c->stock;
        return FM_OK;
    }
    own.voxel_mm = voxel;
    own.band_voxels = band;
    c->check_grid = fm_job_make_stock(c->spec->stock_spec, &own, err);
    if (!c->check_grid) return err ? err->code : FM_ERR_INPUT;
    c->check_twin = 1;
    return FM_OK;
}

static void free_check(cutter *c)
{
    if (c->check_twin) fm_stock_free(c->check_grid);
    c->check_grid = NULL;
    c->check_twin = 0;
    fm_check_free(c->check);
    c->check = NULL;
}

/* Live jobs: motions from the source until it ends, through the same cut
 * as a program's. Whenever no motion is waiting, what is held is cut and
 * reported (idle), so the stock follows the machine; a position that cuts
 * nothing is reported too, so the status follows it. */
static fm_status run_source(cutter *c)
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
        if (cut_sink(c, &m)) return c->status;
        if (more) continue;
        c->progress.idle = 1;
        fm_status st = flush_batch(c);
        if (st == FM_OK && !c->stopped && m.index >= c->spec->skip_motions &&
            c->progress.resume_from <= m.index)
            report(c, &m);
        c->progress.idle = 0;
        if (st != FM_OK) return st;
        if (c->stopped) return FM_OK;
    }
}

/* ------------------------------------------------------------- blame -- */

/* Each listed gouge is blamed on the motion whose swept volume reaches
 * deepest at the gouge's deepest point (on the final surface, so the motion
 * that cut it has its sweep's boundary there and every other a value at or
 * below it). The program is interpreted once more; only motions whose box
 * can reach a point build their sweep. A gouge no motion reaches within a
 * voxel (cut before this program, in an earlier job's stock) stays
 * unblamed. */
typedef struct blamer {
    const job_tools *tools;
    const fm_deviation *dev;
    fm_job_blame *blame;
    double best[FM_JOB_MAX_REGIONS];
    double voxel;
    stop_rule stop;
    fm_error *err;
    fm_status status;
} blamer;

/* A box that holds the motion's swept volume (a quick test before building
 * the sweep): the box of its tool tip in the workpiece frame (lib/sweep's
 * pose bounds: lines, arcs and rotary motions, whose start and end may be
 * joint values rather than workpiece positions) widened by the tool's size
 * in any direction. */
static void motion_reach(const fm_motion *m, const fm_tool *tool, double lo[3], double hi[3])
{
    const double r = 0.5 * tool->spec.diameter + tool->spec.flute_length + tool->spec.length;
    double axis_lo[3], axis_hi[3];
    fm_motion_pose_bounds(m, 0, 1, lo, hi, axis_lo, axis_hi);
    for (int k = 0; k < 3; k++) {
        lo[k] -= r;
        hi[k] += r;
    }
}

static int blame_sink(void *user, const fm_motion *m)
{
    blamer *b = user;
    if (stop_before(&b->stop, m)) return 1;
    if (m->kind == FM_MOTION_DWELL) return 0;
    const fm_tool *tool = tool_for(b->tools, m->tool);
    if (!tool) return 0;
    const size_t n = b->dev->gouge_count;
    int any = m->kind == FM_MOTION_PARAM; /* its box is not known before the sweep */
    if (!any) {
        double lo[3], hi[3];
        motion_reach(m, tool, lo, hi);
        for (size_t i = 0; i < n && !any; i++) {
            const double *p = b->dev->gouges[i].position;
            any = p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] &&
                  p[2] >= lo[2] && p[2] <= hi[2];
        }
    }
    if (!any) return 0;
    fm_sweep *sweep = NULL;
    if ((b->status = fm_sweep_new(m, &tool->flutes, NULL, &sweep, b->err)) != FM_OK) return 1;
    fm_sweep_worker *w = fm_sweep_worker_new(sweep);
    if (!w) {
        fm_sweep_free(sweep);
        b->status = fm_error_set(b->err, FM_ERR_LIMIT, "out of memory");
        return 1;
    }
    double lo[3], hi[3];
    fm_sweep_bounds(sweep, lo, hi);
    for (size_t i = 0; i < n; i++) {
        const double *p = b->dev->gouges[i].position;
        int inside = 1;
        for (int k = 0; k < 3; k++) inside &= p[k] >= lo[k] - b->voxel && p[k] <= hi[k] + b->voxel;
        if (!inside) continue;
        const double v = fm_sweep_eval(sweep, w, p);
        /* the first of equal depths: the motion that cut it first */
        if (v > b->best[i] + 1e-9) {
            b->best[i] = v;
            b->blame[i].line = m->line;
            b->blame[i].tool = m->tool;
        }
    }
    fm_sweep_worker_free(w);
    fm_sweep_free(sweep);
    return 0;
}

static fm_status blame_gouges(const fm_job_spec *spec, const job_tools *tools, double voxel,
                              fm_job_result *result, fm_error *err)
{
    const fm_deviation *dev = &result->deviation;
    if (dev->gouge_count == 0) return FM_OK;
    blamer *b = calloc(1, sizeof *b);
    if (!b) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    b->tools = tools;
    b->dev = dev;
    b->blame = result->gouge_blame;
    b->voxel = voxel;
    b->stop.line = spec->stop_at_line;
    b->err = err;
    for (size_t i = 0; i < FM_JOB_MAX_REGIONS; i++) b->best[i] = -INFINITY;
    /* no probe: a G38 move does not trip here (docs/simulate.md) */
    fm_status st = run_program(spec, tools->use, blame_sink, b, NULL, err);
    if (st == FM_OK) st = b->status;
    /* a sweep that ends more than a voxel from the point did not cut it */
    for (size_t i = 0; i < dev->gouge_count; i++)
        if (b->best[i] < -b->voxel) b->blame[i].line = b->blame[i].tool = 0;
    free(b);
    return st;
}

/* ---------------------------------------------------------------- run -- */

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

fm_status fm_job_run(const fm_job_spec *spec, const fm_job_hooks *hooks, fm_job_result *result,
                     fm_error *err)
{
    memset(result, 0, sizeof *result);
    double started = now_s();
    job_tools tools;
    fm_status st = load_tools(spec, &tools, err);
    if (st != FM_OK) {
        free_tools(&tools);
        fm_stock_free(spec->resume_stock);
        return st;
    }

    /* First pass: the whole program is checked before anything is cut, and
     * its length gives the progress its denominator. */
    survey sv = {0};
    int live = spec->program_kind == FM_PROGRAM_LIVE;
    sv.stop.line = spec->stop_at_line;
    st = live ? FM_OK : run_program(spec, tools.use, survey_sink, &sv, NULL, err);
    if (st != FM_OK) {
        free_tools(&tools);
        fm_stock_free(spec->resume_stock);
        return st;
    }

    fm_stock *stock = spec->resume_stock ? spec->resume_stock
                                         : fm_job_make_stock(spec->stock_spec, &spec->stock, err);
    if (!stock) {
        free_tools(&tools);
        return err ? err->code : FM_ERR_INPUT;
    }
    /* The design before any cut: its errors come at once, and progress
     * hooks can colour by deviation while the job runs. */
    fm_design *design = NULL;
    if (spec->design_path) {
        const double w0 = now_s(), c0 = process_cpu_s();
        design = make_design(spec, stock, err);
        if (!design) {
            fm_stock_free(stock);
            free_tools(&tools);
            return err && err->code ? err->code : FM_ERR_INPUT;
        }
        result->design_build_wall_s = now_s() - w0;
        result->design_build_cpu_s = process_cpu_s() - c0;
    }

    double initial_lo[3] = {0, 0, 0}, initial_hi[3] = {0, 0, 0};
    int32_t ilo[3], ihi[3];
    fm_error bounds_err;
    if (fm_stock_active_bounds(stock, ilo, ihi, &bounds_err) == FM_OK) {
        double a[3] = {ilo[0], ilo[1], ilo[2]}, b[3] = {ihi[0], ihi[1], ihi[2]};
        fm_stock_index_to_world(stock, a, initial_lo);
        fm_stock_index_to_world(stock, b, initial_hi);
        /* Active voxels reach a band beyond the surface on either side. */
        double band = fm_stock_band_voxels(stock) * fm_stock_voxel_size(stock);
        for (int k = 0; k < 3; k++) {
            initial_lo[k] += band;
            initial_hi[k] -= band;
        }
    }

    cutter *c = calloc(1, sizeof *c);
    if (!c) {
        fm_design_free(design);
        fm_stock_free(stock);
        free_tools(&tools);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    }
    c->spec = spec;
    c->hooks = hooks;
    c->tools = &tools;
    c->stock = stock;
    c->err = err;
    c->started = now_s();
    c->progress.motions_total = sv.motions;
    c->progress.program_time_total = sv.time_total;
    c->progress.block = -1;
    c->progress.design = design;
    c->stop.line = spec->stop_at_line;

    if (hooks && hooks->on_stock) hooks->on_stock(hooks->user, stock);
    if (spec->check) st = setup_check(c, &sv, err);
    if (st == FM_OK)
        st = live ? run_source(c) : run_program(spec, tools.use, cut_sink, c, cut_probe, err);
    if (st == FM_OK) st = c->status;
    if (st == FM_OK && !c->stopped && !c->stopped_at_line) st = flush_batch(c);
    if (st == FM_OK && design && !c->stopped) {
        const double w0 = now_s(), c0 = process_cpu_s();
        st = fm_stock_compare_design(stock, design, FM_JOB_MAX_REGIONS, &result->deviation, err);
        result->has_deviation = st == FM_OK;
        const double w1 = now_s(), c1 = process_cpu_s();
        result->design_compare_wall_s = w1 - w0;
        result->design_compare_cpu_s = c1 - c0;
        if (st == FM_OK)
            st = blame_gouges(spec, &tools, fm_stock_voxel_size(stock), result, err);
        result->design_blame_wall_s = now_s() - w1;
        result->design_blame_cpu_s = process_cpu_s() - c1;
    }
    if (st != FM_OK) {
        free_check(c);
        free(c->lines_cut);
        free(c);
        fm_deviation_free(&result->deviation);
        result->has_deviation = 0;
        fm_design_free(design);
        fm_stock_free(stock);
        free_tools(&tools);
        return st;
    }
    if (c->check) {
        fm_check_finish(c->check);
        result->check = c->check;
        result->check_time_s = c->check_time;
        c->check = NULL;
        free_check(c);
    }

    result->stock = stock;
    result->stopped = c->stopped;
    result->initial_volume_mm3 = fm_stock_initial_volume(stock);
    result->final_volume_mm3 = fm_stock_volume(stock);
    result->removed_volume_mm3 = fm_stock_removed_volume(stock);
    double area = 0;
    fm_error area_err;
    if (fm_stock_surface_area(stock, &area, &area_err) == FM_OK) result->surface_area_mm2 = area;
    result->has_thin = fm_stock_thin_material(stock, &result->thin, &area_err) == FM_OK;
    result->motions = live ? c->progress.motions_total : sv.motions;
    result->blocks = c->blocks;
    result->program_time_s = live ? c->progress.program_time_total : sv.time_total;
    result->voxel_mm = fm_stock_voxel_size(stock);
    memcpy(result->initial_lo, initial_lo, sizeof initial_lo);
    memcpy(result->initial_hi, initial_hi, sizeof initial_hi);
    size_t n = fm_stock_tool_volumes(stock, result->tools,
                                     sizeof result->tools / sizeof result->tools[0]);
    result->tool_count = n < 64 ? n : 64;
    result->top_block_count = fm_stock_blocks(stock, result->top_blocks, FM_JOB_TOP_BLOCKS);
    if (result->top_block_count > FM_JOB_TOP_BLOCKS) result->top_block_count = FM_JOB_TOP_BLOCKS;
    result->cut_stats = c->stats;
    result->cuts = c->cuts;
    result->voxels_uncertain = c->stats.voxels_uncertain;
    result->uncertain_max_mm = c->stats.uncertain_max_mm;
    result->uncertain_line = c->progress.uncertain_line;
    result->stopped_at_line = c->stopped_at_line ? spec->stop_at_line : 0;
    result->design = design;
    result->design_wall_s =
        result->design_build_wall_s + result->design_compare_wall_s + result->design_blame_wall_s;
    result->design_cpu_s =
        result->design_build_cpu_s + result->design_compare_cpu_s + result->design_blame_cpu_s;
    result->wall_time_s = now_s() - started;
    result->peak_memory_bytes = fm_job_peak_rss();

    free(c->lines_cut);
    free(c);
    free_tools(&tools);
    return FM_OK;
}
