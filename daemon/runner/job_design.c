/* job_design.c: the design comparison's two ends: the design built on the
 * stock's grid before the first cut, and the blame of each gouge on the
 * motion that cut it deepest once the comparison is made. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "job_internal.h"
#include "stock_spec.h"
#include "sweep/sweep.h"

fm_design *job_make_design(const fm_job_spec *spec, const fm_stock *stock, fm_error *err)
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
        const double h = fm_stock_voxel_size(stock);
        fm_field field;
        if (fm_stock_hf_field(path, h, h * fm_design_band_voxels(stock, spec->tolerance_mm),
                              "design", &field, err) != FM_OK)
            return NULL;
        return fm_design_from_field(stock, &field, &opt, err);
    }
    fm_error_set(err, FM_ERR_INPUT, "design '%s' is not a .stl mesh, a .hf model or a .vdb snapshot",
                 path);
    return NULL;
}

/* Each listed gouge is blamed on the motion whose swept volume reaches
 * deepest at the gouge's deepest point (on the final surface, so the motion
 * that cut it has its sweep's boundary there and every other a value at or
 * below it). The program's motions are replayed (interpreted once more
 * when they could not be kept); only motions whose box
 * can reach a point build their sweep. A gouge no motion reaches within a
 * voxel (cut before this program, in an earlier job's stock) stays
 * unblamed. */
typedef struct blamer {
    const job_tools *tools;
    const fm_deviation *dev;
    fm_job_blame *blame;
    double best[FM_JOB_MAX_REGIONS];
    double voxel;
    job_stop_rule stop;
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
    if (job_stop_before(&b->stop, m)) return 1;
    if (m->kind == FM_MOTION_DWELL) return 0;
    const fm_tool *tool = job_tool_for(b->tools, m->tool);
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

fm_status job_blame_gouges(const fm_job_spec *spec, const job_tools *tools, double voxel,
                           fm_job_motions *log, fm_job_result *result, fm_error *err)
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
    fm_status st;
    if (job_motions_usable(log)) {
        st = fm_job_motions_replay(log, spec->machine, blame_sink, b, err);
    } else {
        st = job_run_program(spec, tools->use, blame_sink, b, NULL, err);
        result->interpretations++;
    }
    if (st == FM_OK) st = b->status;
    /* a sweep that ends more than a voxel from the point did not cut it */
    for (size_t i = 0; i < dev->gouge_count; i++)
        if (b->best[i] < -b->voxel) b->blame[i].line = b->blame[i].tool = 0;
    free(b);
    return st;
}
